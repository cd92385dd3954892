/* mr_calibrate_board (lib/track) on the synthetic board set of lib/bench
 * (mr_synth_calibration: the demo camera, fx = fy = 500): the intrinsics
 * come back within 1 %, each used image is named with its own RMS, and bad
 * boards and too few usable images fail with one line. */
#include "mr_bench.h"
#include "mr_test.h"
#include "mr_track.h"

#include <math.h>
#include <string.h>

int main(void) {
    char dir[4096], images[4200], board[4200];
    CHECK(mr_test_fresh_dir("track_calib", dir, sizeof dir));
    mr_error err = {0};
    CHECK_MSG(mr_synth_calibration(dir, 6, &err), "%s", err.msg);
    snprintf(images, sizeof images, "%s/images", dir);
    snprintf(board, sizeof board, "%s/board.json", dir);
    mr_marker_map map;
    CHECK_MSG(mr_marker_map_load(board, &map, &err), "%s", err.msg);

    mr_board_calib_params p = {images, &map, "board.json", 0, false};
    mr_board_calib c;
    CHECK_MSG(mr_calibrate_board(&p, &c, &err), "%s", err.msg);
    CHECK_MSG(fabs(c.camera.fx - 500) < 5 && fabs(c.camera.fy - 500) < 5, "fx %g fy %g, expected 500 +- 1%%",
              c.camera.fx, c.camera.fy);
    CHECK_MSG(c.views == 6 && c.skipped == 0, "%d views used, %d skipped", c.views, c.skipped);
    CHECK(c.rms_px > 0 && c.rms_px < 1);
    for (int v = 0; v < c.views; v++) CHECK(c.names[v][0] && c.view_rms_px[v] > 0 && c.view_rms_px[v] < 2);
    mr_board_calib_free(&c);
    CHECK(c.names == NULL && c.views == 0);

    /* Every image short of tags: none is used, and the calibration says why. */
    p.min_tags = 10000;
    memset(&err, 0, sizeof err);
    CHECK(!mr_calibrate_board(&p, &c, &err) && err.msg[0] && !strchr(err.msg, '\n'));
    CHECK(c.names == NULL && c.view_rms_px == NULL);

    /* A tag lifted out of the board's plane: refused before any image is read. */
    p.min_tags = 0;
    map.tags[0].world_from_tag.m[11] += 0.01; /* row-major: z of the translation */
    memset(&err, 0, sizeof err);
    CHECK(!mr_calibrate_board(&p, &c, &err) && err.code == MR_ERR_INVALID && strstr(err.msg, "board.json: ") &&
          strstr(err.msg, "planar"));
    mr_marker_map_free(&map);
    return mr_test_finish("test_track_calib");
}
