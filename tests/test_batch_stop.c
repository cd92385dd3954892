/* Clean stops of the batch work behind synth, calibrate and map: a stop
 * (what SIGINT/SIGTERM set, mr_stop_request here) ends a photo set before
 * its next image, the calibration set before its next image with what it
 * wrote whole, and the marker map's bundle adjustment inside Ceres (its
 * iteration callback), each with MR_ERR_INTERRUPTED. */
#include "mr_bench.h"
#include "mr_test.h"

#include <signal.h>
#include <string.h>

/* The map's progress hook: asks for the stop as the adjustment starts. */
static void stop_at_adjust(void *user, const char *stage, double f) {
    (void)user;
    (void)f;
    if (strcmp(stage, "adjust") == 0) mr_stop_request(SIGINT);
}

static void test_map_stop(void) {
    mr_synth_map_params sp = {MR_SYNTH_MAP_DEFAULTS};
    sp.tags = 8;
    sp.photos = 20;
    mr_synth_map s;
    mr_error err = {0};
    CHECK_MSG(mr_synth_map_make(&sp, &s, &err), "%s", err.msg);
    mr_map_photo ph[32];
    for (int j = 0; j < s.photo_count; j++) ph[j] = (mr_map_photo){s.dets[j], s.counts[j], NULL};
    mr_map_params mp = MR_MAP_DEFAULTS;
    mp.tag_size = sp.tag_size;
    mp.fix_id = s.truth.tags[0].id;
    mr_map_result r;
    CHECK_MSG(mr_map_build(&s.camera, ph, s.photo_count, &mp, &r, &err), "unstopped map: %s", err.msg);
    mr_map_result_free(&r);
    mp.progress = stop_at_adjust;
    CHECK(!mr_map_build(&s.camera, ph, s.photo_count, &mp, &r, &err) && err.code == MR_ERR_INTERRUPTED);
    /* Ceres itself stopped (its iteration callback), not a check after it. */
    CHECK_MSG(strstr(err.msg, "bundle adjustment interrupted at iteration"), "%s", err.msg);
    CHECK(r.tags == NULL && r.tag_count == 0);
    mr_stop_request(0);
    mr_synth_map_free(&s);
}

static void test_sets_stop(void) {
    char dir[4096], sub[4200];
    if (!mr_test_fresh_dir("batch_stop", dir, sizeof dir)) {
        CHECK(false);
        return;
    }
    mr_error err = {0};
    CHECK_MSG(mr_synth_calibration(dir, 3, &err), "%s", err.msg);
    /* A photo set stops before its next image. */
    mr_marker_map board;
    snprintf(sub, sizeof sub, "%s/board.json", dir);
    CHECK(mr_marker_map_load(sub, &board, &err));
    snprintf(sub, sizeof sub, "%s/images", dir);
    mr_stop_request(SIGTERM);
    mr_board_calib_params bp = {.images = sub, .board = &board};
    mr_board_calib c;
    CHECK(!mr_calibrate_board(&bp, &c, &err) && err.code == MR_ERR_INTERRUPTED &&
          strstr(err.msg, "interrupted after 0 images; nothing written"));
    mr_stop_request(0);
    CHECK_MSG(mr_calibrate_board(&bp, &c, &err) && c.views == 3, "%s", err.msg);
    mr_board_calib_free(&c);
    mr_marker_map_free(&board);
    /* The calibration set: board.json and no image. */
    snprintf(sub, sizeof sub, "%s/second", dir);
    mr_stop_request(SIGINT);
    CHECK(!mr_synth_calibration(sub, 3, &err) && err.code == MR_ERR_INTERRUPTED && strstr(err.msg, "0 of 3 images"));
    mr_stop_request(0);
    snprintf(sub, sizeof sub, "%s/second/board.json", dir);
    CHECK(mr_file_exists(sub));
    snprintf(sub, sizeof sub, "%s/second/images/board_00.png", dir);
    CHECK(!mr_file_exists(sub));
}

int main(void) {
    test_map_stop();
    test_sets_stop();
    return mr_test_finish("test_batch_stop");
}
