/* mrcheck measure: a real feature tapped in several frames of a recording,
 * triangulated (lib/track's mr_triangulate) and compared with the plan. */
#include "app_track.h"
#include "mr_eval.h"
#include "mr_session.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    mr_triangulate_params tp = MR_TRIANGULATE_DEFAULTS;
    mr_cli_table table = {.prefix = "", .table = mr_triangulate_opts, .params = &tp};
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
    const char *dir = mr_cli_get(opts, "recording"), *obsf = mr_cli_get(opts, "observations"), *out = mr_cli_get(opts, "out");
    if (!dir || !obsf) return mr_cli_errorf(cmd, "--recording and --observations are required (see --help)"), 2;
    mr_error err = {0};
    mr_recording *rec = NULL;
    mr_scene *scene = NULL;
    mr_eval_nearest *near = NULL;
    int rc = 1;
    mr_observations o;
    mr_tolerances tols = MR_TOLERANCES_DEFAULTS;
    const mr_tolerances *tol = NULL;
    double nominal = -1;
    if (mr_cli_get(opts, "nominal") && !mr_cli_double("nominal", mr_cli_get(opts, "nominal"), 0, 1e9, &nominal))
        return 2;
    if (mr_cli_get(opts, "tolerances")) {
        if (!mr_tolerances_load(mr_cli_get(opts, "tolerances"), &tols, &err)) goto fail;
        tol = &tols;
    }
    const char *part = mr_cli_get(opts, "part");
    char line[320];
    mr_verdict v = {0}, sv = {0};
    rec = mr_recording_open(dir, &err);
    if (!rec || !mr_observations_load(obsf, rec, &o, &err)) goto fail;
    if (mr_cli_get(opts, "scene")) {
        scene = mr_scene_load(mr_cli_get(opts, "scene"), NULL, &err);
        if (!scene || !(near = mr_eval_nearest_create(scene, false, &err))) goto fail;
    }
    const mr_tap *taps = o.taps;
    int n = o.count, no_cov = o.no_cov;
    bool has_planned = o.has_planned;
    const double *planned = o.planned;
    mr_triangulation tr;
    if (!mr_triangulate(&rec->camera, taps, n, &tp, &tr, &err)) goto fail;
    /* After the solve, so that a refusal stays one line. */
    if (no_cov)
        fprintf(stderr, "mrcheck: measure: warning: %d frame(s) carry no pose covariance (an older recording): "
                        "only the taps' noise is counted there\n", no_cov);
    printf("point %.4f %.4f %.4f  sigma %.1f mm  from %d taps, baseline angle %.1f deg, tap RMS %.2f px\n", tr.point.x,
           tr.point.y, tr.point.z, tr.sigma * 1e3, n, tr.angle_deg, tr.rms_px);
    double dist = NAN, dsig = NAN;
    if (has_planned) {
        mr_triangulation_distance(&tr, mr_v3(planned[0], planned[1], planned[2]), &dist, &dsig);
        printf("distance to the planned point: %.1f mm +- %.1f mm (1 sigma)\n", dist * 1e3, dsig * 1e3);
        if (!mr_verdict_measure(tol, part, NULL, planned, nominal, dist, dsig, &v, &err)) goto fail;
        mr_verdict_format(&v, line, sizeof line);
        printf("verdict: %s\n", line);
    }
    /* The nearest point of the planned surface (exact, lib/eval). */
    mr_nearest_hit nh = {0};
    double nsig = NAN;
    if (near) {
        if (!mr_eval_nearest_point(near, tr.point, &nh)) {
            mr_fail(&err, MR_ERR_INVALID, "the scene has no surface to measure against");
            goto fail;
        }
        nsig = mr_eval_nearest_sigma(&nh, tr.cov);
        printf("distance to the planned surface: %.1f mm +- %.1f mm (1 sigma), nearest point %.4f %.4f %.4f on %s\n",
               nh.distance * 1e3, nsig * 1e3, nh.point.x, nh.point.y, nh.point.z,
               nh.node >= 0 ? scene->nodes[nh.node].name : "?");
        double np[3] = {nh.point.x, nh.point.y, nh.point.z};
        const mr_node *sn = nh.node >= 0 ? &scene->nodes[nh.node] : NULL;
        if (!mr_verdict_measure(tol, sn ? sn->name : part, sn && sn->layer == MR_LAYER_HIDDEN ? "hidden" : "visible", np,
                                nominal, nh.distance, nsig, &sv, &err))
            goto fail;
        mr_verdict_format(&sv, line, sizeof line);
        printf("verdict (surface): %s\n", line);
    }
    if (out) {
        cJSON *r = cJSON_CreateObject();
        double pt[3] = {tr.point.x, tr.point.y, tr.point.z};
        cJSON_AddItemToObject(r, "point", mr_json_from_doubles(pt, 3));
        cJSON_AddItemToObject(r, "covariance", mr_json_from_doubles(tr.cov, 9));
        cJSON_AddNumberToObject(r, "sigma_mm", tr.sigma * 1e3);
        cJSON_AddNumberToObject(r, "angle_deg", tr.angle_deg);
        cJSON_AddNumberToObject(r, "rms_px", tr.rms_px);
        cJSON_AddNumberToObject(r, "taps", n);
        if (has_planned) {
            cJSON_AddItemToObject(r, "planned", mr_json_from_doubles(planned, 3));
            cJSON_AddNumberToObject(r, "distance_mm", dist * 1e3);
            cJSON_AddNumberToObject(r, "distance_sigma_mm", dsig * 1e3);
            cJSON_AddItemToObject(r, "verdict", mr_verdict_to_json(&v));
        }
        if (nh.found) {
            double np[3] = {nh.point.x, nh.point.y, nh.point.z};
            cJSON_AddItemToObject(r, "nearest_planned", mr_json_from_doubles(np, 3));
            cJSON_AddStringToObject(r, "nearest_node", nh.node >= 0 ? scene->nodes[nh.node].name : "");
            cJSON_AddNumberToObject(r, "surface_distance_mm", nh.distance * 1e3);
            cJSON_AddNumberToObject(r, "surface_distance_sigma_mm", nsig * 1e3);
            cJSON_AddItemToObject(r, "surface_verdict", mr_verdict_to_json(&sv));
        }
        bool ok = mr_json_save(out, r, &err);
        cJSON_Delete(r);
        if (!ok) goto fail;
    }
    rc = 0;
    goto done;
fail:
    rc = mr_cli_error(cmd, &err);
done:
    mr_eval_nearest_destroy(&near);
    mr_scene_destroy(&scene);
    mr_recording_close(&rec);
    return rc;
}
