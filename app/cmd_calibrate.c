/* mrcheck calibrate: camera intrinsics from images of a tag-grid board. */
#include "app_track.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int cmd_calibrate(int argc, char **argv) {
    static const char *cmd = "calibrate";
    mr_cli_opt opts[] = {
        {"images", "DIR", "folder of board images (png, jpg, ...)", NULL},
        {"board", "BOARD.json", "the board as a marker map: tag poses in the board frame (z = 0 plane)", NULL},
        {"out", "CAMERA.json", "camera file to write", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_board_calib_params bp = {.min_tags = 0};
    mr_cli_table table = {.prefix = "", .table = mr_board_calib_opts, .params = &bp};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck calibrate --images DIR --board BOARD.json --out CAMERA.json\n"
                   "Detects the board's AprilTags in every image and calibrates fx fy cx cy and k1 k2 p1 p2\n"
                   "(k3 = 0) with OpenCV; prints the RMS reprojection error.",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *dir = mr_cli_get(opts, "images"), *board = mr_cli_get(opts, "board"), *out = mr_cli_get(opts, "out");
    if (!dir || !board || !out) return mr_cli_errorf(cmd, "--images, --board and --out are required (see --help)"), 2;

    mr_error err = {0};
    mr_marker_map map;
    if (!mr_marker_map_load(board, &map, &err)) return mr_cli_error(cmd, &err);
    bp.images = dir;
    bp.progress = isatty(2) && mr_log_get_level() >= MR_LOG_WARN;
    mr_stop_catch();
    bp.board = &map;
    bp.board_name = board;
    mr_board_calib c;
    bool ok = mr_calibrate_board(&bp, &c, &err);
    mr_marker_map_free(&map);
    if (!ok) return mr_cli_error(cmd, &err);
    cJSON *j = mr_camera_to_json(&c.camera);
    cJSON *cal = cJSON_AddObjectToObject(j, "calibration");
    cJSON_AddNumberToObject(cal, "rms_px", c.rms_px);
    cJSON_AddNumberToObject(cal, "images", c.views);
    cJSON_AddStringToObject(cal, "board", board);
    ok = mr_json_save(out, j, &err);
    cJSON_Delete(j);
    if (ok) {
        const mr_camera *cam = &c.camera;
        printf("calibrated from %d images (%d skipped): fx %.2f fy %.2f cx %.2f cy %.2f k1 %.4f k2 %.4f p1 %.5f p2 %.5f\n",
               c.views, c.skipped, cam->fx, cam->fy, cam->cx, cam->cy, cam->dist[0], cam->dist[1], cam->dist[2],
               cam->dist[3]);
        printf("RMS reprojection error %.3f px; wrote %s\n", c.rms_px, out);
        for (int v = 0; v < c.views && mr_log_get_level() >= MR_LOG_INFO; v++)
            printf("  %s: %.3f px\n", c.names[v], c.view_rms_px[v]);
    }
    mr_board_calib_free(&c);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
