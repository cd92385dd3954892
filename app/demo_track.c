/* `mrcheck synth`: the options and the wiring; the recording and the
 * calibration set are made by mr_synth_recording / mr_synth_calibration
 * (lib/bench). */
#include "app_track.h"
#include "mr_bench.h"

#include <unistd.h>

int cmd_synth(int argc, char **argv) {
    static const char *cmd = "synth";
    mr_cli_opt opts[] = {
        {"out", "DIR", "recording folder to create (required; never overwritten)", NULL},
        {"size", "WxH", "frame size (default 640x480, the demo camera scaled)", NULL},
        {"seed", "N", "noise seed (default 1)", NULL},
        {"calibration", "DIR", "instead: write a calibration board and 12 images there", NULL},
        {"force", NULL, "write into a folder that already holds files (a recording is still never overwritten)", NULL},
        {"map-photos", "DIR", "instead: write a synthetic photo set for `mrcheck map` there (images/, photos.avi, camera.json, truth.json, control.json)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_synth_recording_params p = {MR_SYNTH_RECORDING_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_synth_recording_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck synth --out DIR [--frames N] [--size WxH] [--noise S] [--motion-blur N] [--exposure A] [--jpeg Q]\n"
                   "Renders the as-built demo hall along a walking path with pauses and writes a tracked recording\n"
                   "with groundtruth.jsonl (needs EGL).",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    mr_error err = {0};
    mr_outdir od;
    const bool force = mr_cli_flag(opts, "force");
    const char *set = mr_cli_get(opts, "map-photos") ? mr_cli_get(opts, "map-photos") : mr_cli_get(opts, "calibration");
    if (set && !mr_outdir_create(&od, set, force, &err)) return mr_cli_error(cmd, &err);
    mr_stop_catch();
    if (mr_cli_get(opts, "map-photos")) {
        if (!mr_synth_map_write(mr_cli_get(opts, "map-photos"), NULL, &err)) return mr_outdir_abandon(&od), mr_cli_error(cmd, &err);
        printf("wrote %s/images/, photos.avi, camera.json, truth.json, control.json\n", mr_cli_get(opts, "map-photos"));
        return 0;
    }
    if (mr_cli_get(opts, "calibration")) {
        if (!mr_synth_calibration(mr_cli_get(opts, "calibration"), 12, &err)) return mr_outdir_abandon(&od), mr_cli_error(cmd, &err);
        printf("wrote %s/board.json and %s/images/\n", mr_cli_get(opts, "calibration"), mr_cli_get(opts, "calibration"));
        return 0;
    }
    if (!mr_cli_get(opts, "out")) return mr_cli_errorf(cmd, "--out is required (see --help)"), 2;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) return 2;
    if (p.width < 64 || p.height < 48) return mr_cli_errorf(cmd, "--size must be at least 64x48"), 2;
    long l;
    if (mr_cli_get(opts, "seed")) {
        if (!mr_cli_int("seed", mr_cli_get(opts, "seed"), 0, 1L << 40, &l)) return 2;
        p.seed = (uint64_t)l;
    }
    if (!mr_outdir_create(&od, mr_cli_get(opts, "out"), force, &err)) return mr_cli_error(cmd, &err);
    double t0 = mr_time_now();
    p.progress = isatty(2) && mr_log_get_level() < MR_LOG_INFO;
    mr_gfx g;
    bool ok = mr_gfx_open(&g, &err) && mr_synth_recording(mr_cli_get(opts, "out"), &p, &g, &err);
    mr_gfx_close(&g);
    if (!ok && err.code != MR_ERR_INTERRUPTED) mr_outdir_abandon(&od);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("wrote %s/ (%d frames, %dx%d) in %.1f s\n", mr_cli_get(opts, "out"), p.frames > 0 ? p.frames : mr_synth_path_frames(),
           p.width, p.height, mr_time_now() - t0);
    return 0;
}
