/* mrcheck calibrate: camera intrinsics from images of a tag-grid board. */
#include "app_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int cmd_calibrate(int argc, char **argv) {
    static const char *cmd = "calibrate";
    mr_cli_opt opts[] = {
        {"images", "DIR", "folder of board images (png, jpg, ...)", NULL},
        {"board", "BOARD.json", "the board as a marker map: tag poses in the board frame (z = 0 plane)", NULL},
        {"out", "CAMERA.json", "camera file to write", NULL},
        {"min-tags", "N", "images with fewer board tags are skipped (default 4)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 2, opts, NULL, 0, NULL,
                   "usage: mrcheck calibrate --images DIR --board BOARD.json --out CAMERA.json\n"
                   "Detects the board's AprilTags in every image and calibrates fx fy cx cy and k1 k2 p1 p2\n"
                   "(k3 = 0) with OpenCV; prints the RMS reprojection error.",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *dir = mr_cli_get(opts, "images"), *board = mr_cli_get(opts, "board"), *out = mr_cli_get(opts, "out");
    if (!dir || !board || !out) return mr_cli_errorf(cmd, "--images, --board and --out are required (see --help)"), 2;
    long min_tags = 4;
    if (mr_cli_get(opts, "min-tags") && !mr_cli_int("min-tags", mr_cli_get(opts, "min-tags"), 1, 10000, &min_tags)) return 2;

    mr_error err = {0};
    mr_marker_map map;
    if (!mr_marker_map_load(board, &map, &err)) return mr_cli_error(cmd, &err);
    for (int i = 0; i < map.count; i++) {
        mr_dvec3 c[4];
        mr_marker_corners_world(&map, &map.tags[i], c);
        for (int k = 0; k < 4; k++)
            if (fabs(c[k].z) > 1e-9 * (1 + map.tag_size)) {
                mr_marker_map_free(&map);
                return mr_cli_errorf(cmd, "%s: the board must be planar (all tags in the z = 0 plane)", board);
            }
    }
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = true;
    mr_source *src = mr_source_open(dir, &sp, &err);
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    dp.family = map.family;
    dp.decimate = 1; /* full resolution: corner accuracy matters here */
    mr_detector *det = src ? mr_detector_create(&dp, &err) : NULL;
    if (!det) {
        mr_source_close(&src);
        mr_marker_map_free(&map);
        return mr_cli_error(cmd, &err);
    }
    int cap = 0, nv = 0, width = 0, height = 0, skipped = 0;
    mr_calib_view *views = NULL;
    char (*names)[256] = NULL;
    bool ok = true;
    for (;;) {
        mr_frame f;
        mr_read_status st = mr_source_read(src, &f, &err);
        if (st == MR_READ_END) break;
        if (st == MR_READ_ERROR) {
            ok = false;
            break;
        }
        if (width == 0) {
            width = f.image.width;
            height = f.image.height;
        } else if (f.image.width != width || f.image.height != height) {
            fprintf(stderr, "mrcheck: calibrate: warning: %s is %dx%d, not %dx%d; skipped\n", f.name, f.image.width,
                    f.image.height, width, height);
            skipped++;
            continue;
        }
        int n = 0;
        mr_error fe = {0};
        const mr_detection *d = mr_detector_detect(det, &f.image, &n, &fe);
        if (!d) {
            fprintf(stderr, "mrcheck: calibrate: warning: %s: %s\n", f.name, fe.msg);
            skipped++;
            continue;
        }
        int used = 0;
        for (int i = 0; i < n; i++) used += mr_marker_map_find(&map, d[i].id) != NULL;
        if (used < min_tags) {
            mr_log(MR_LOG_INFO, "%s: %d board tags, skipped", f.name, used);
            skipped++;
            continue;
        }
        if (nv == cap) {
            cap = cap ? 2 * cap : 16;
            mr_calib_view *nvw = realloc(views, (size_t)cap * sizeof *nvw);
            char (*nn)[256] = realloc(names, (size_t)cap * sizeof *nn);
            if (nvw) views = nvw;
            if (nn) names = nn;
            if (!nvw || !nn) {
                ok = mr_fail(&err, MR_ERR_NOMEM, "out of memory");
                break;
            }
        }
        double *o = malloc((size_t)used * 4 * 3 * sizeof *o), *p = malloc((size_t)used * 4 * 2 * sizeof *p);
        if (!o || !p) {
            free(o);
            free(p);
            ok = mr_fail(&err, MR_ERR_NOMEM, "out of memory");
            break;
        }
        int m = 0;
        for (int i = 0; i < n; i++) {
            const mr_marker *mk = mr_marker_map_find(&map, d[i].id);
            if (!mk) continue;
            mr_dvec3 c[4];
            mr_marker_corners_world(&map, mk, c);
            for (int k = 0; k < 4; k++, m++) {
                o[3 * m] = c[k].x;
                o[3 * m + 1] = c[k].y;
                o[3 * m + 2] = 0;
                p[2 * m] = d[i].corners[k][0];
                p[2 * m + 1] = d[i].corners[k][1];
            }
        }
        views[nv] = (mr_calib_view){o, p, m};
        snprintf(names[nv], 256, "%s", f.name);
        nv++;
    }
    mr_camera cam;
    double rms = 0, *per = nv ? calloc((size_t)nv, sizeof *per) : NULL;
    ok = ok && mr_calibrate(views, nv, width, height, &cam, &rms, per, &err);
    if (ok) {
        cJSON *j = mr_camera_to_json(&cam);
        cJSON *c = cJSON_AddObjectToObject(j, "calibration");
        cJSON_AddNumberToObject(c, "rms_px", rms);
        cJSON_AddNumberToObject(c, "images", nv);
        cJSON_AddStringToObject(c, "board", board);
        ok = mr_json_save(out, j, &err);
        cJSON_Delete(j);
    }
    if (ok) {
        printf("calibrated from %d images (%d skipped): fx %.2f fy %.2f cx %.2f cy %.2f k1 %.4f k2 %.4f p1 %.5f p2 %.5f\n",
               nv, skipped, cam.fx, cam.fy, cam.cx, cam.cy, cam.dist[0], cam.dist[1], cam.dist[2], cam.dist[3]);
        printf("RMS reprojection error %.3f px; wrote %s\n", rms, out);
        for (int v = 0; v < nv && mr_log_get_level() >= MR_LOG_INFO; v++) printf("  %s: %.3f px\n", names[v], per[v]);
    }
    for (int v = 0; v < nv; v++) {
        free((void *)views[v].object);
        free((void *)views[v].image);
    }
    free(views);
    free(names);
    free(per);
    mr_detector_destroy(&det);
    mr_source_close(&src);
    mr_marker_map_free(&map);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
