/* mrcheck measure: a real feature tapped in several frames of a recording,
 * triangulated and compared with the plan (mr_batch_measure). */
#include "app_track.h"
#include "mr_batch.h"

int cmd_measure(int argc, char **argv) {
    static const char *cmd = "measure";
    mr_cli_opt opts[] = {
        {"recording", "DIR", "recording whose frames were tapped (poses and their covariance)", NULL},
        {"observations", "OBS.json", "{\"taps\": [{\"frame\": N, \"px\": [u, v]}, ...], \"planned\": [x, y, z]}", NULL},
        {"out", "RESULT.json", "also write the result there", NULL},
        {"scene", "S", "the plan (glTF/GLB or scene config): also the distance to its nearest surface point", NULL},
        {"tolerances", "T.json", "the tolerance table (default: DIN 18202 Table 1 by nominal size)", NULL},
        {"nominal", "M", "the nominal size the tolerance is looked up for, metres (default: the planned\n"
                         "point's distance from the table's reference point)", NULL},
        {"part", "NAME", "the part the planned point belongs to (for a part's tolerance)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_batch_measure_params mp = MR_BATCH_MEASURE_DEFAULTS;
    mr_cli_table table = {.prefix = "", .table = mr_triangulate_opts, .params = &mp.triangulate};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck measure --recording DIR --observations OBS.json [--scene S] [--out RESULT.json]\n"
                   "Triangulates the feature tapped in two or more frames (linear, then refined, with the taps'\n"
                   "noise and each frame's pose covariance) and reports its distance to the planned point\n"
                   "(\"planned\" in OBS.json) and, with --scene, to the nearest point of the planned model, in mm\n"
                   "with its 1-sigma uncertainty, and the verdict against the tolerance: within, out of tolerance\n"
                   "or undecided (the 95 % interval, k = 2, straddles the limit).",
                   &help))
        return 2;
    if (help) return 0;
    mp.recording = mr_cli_get(opts, "recording");
    mp.observations = mr_cli_get(opts, "observations");
    if (!mp.recording || !mp.observations)
        return mr_cli_errorf(cmd, "--recording and --observations are required (see --help)"), 2;
    if (mr_cli_get(opts, "nominal") && !mr_cli_double("nominal", mr_cli_get(opts, "nominal"), 0, 1e9, &mp.nominal))
        return 2;
    mp.scene = mr_cli_get(opts, "scene");
    mp.tolerances = mr_cli_get(opts, "tolerances");
    mp.part = mr_cli_get(opts, "part");
    mp.out_json = mr_cli_get(opts, "out");
    mp.out = stdout;
    mr_error err = {0};
    return mr_batch_measure(&mp, &err) ? 0 : mr_cli_error(cmd, &err);
}
