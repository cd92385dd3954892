/* lib/track: the one tracker (mr_tracker). On frames of the shipped
 * recording: the previous-pose policy at its boundaries (fresh, exactly the
 * age limit, just under it, time going backwards, a longer limit, the
 * filter's gap as the default), that the tracker is detect -> solve(prev)
 * -> filter and nothing else (bit-equal to the parts run by hand), freeze
 * and hold, no filter, detection only, bad frames and bad parameters.
 *
 * Frame 52 of the old recordings/demo (tests/data/tracker) shows one tag whose two IPPE solutions are
 * ambiguous: with frame 0's pose as the previous one it gives another pose
 * than without (checked below), so the policy is visible in the poses. */
#include "mr_session.h"
#include "mr_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static mr_recording *g_rec;
static mr_image g_f0, g_f52;

static mr_tracker *make(const mr_tracker_params *extra) {
    mr_tracker_params tp = MR_TRACKER_DEFAULTS;
    if (extra) tp = *extra;
    tp.camera = &g_rec->camera;
    tp.markers = &g_rec->markers;
    mr_error err = {0};
    mr_tracker *t = mr_tracker_create(&tp, &err);
    CHECK_MSG(t != NULL, "tracker: %s", err.msg);
    return t;
}

/* Frame 0 at t0, then frame 52 at t1: was the previous pose used? */
static bool prev_used_after(const mr_tracker_params *p, double t0, double t1, mr_pose *pose52) {
    mr_tracker *t = make(p);
    if (!t) return false;
    mr_tracker_result r;
    mr_error err = {0};
    CHECK(mr_tracker_frame(t, &g_f0, t0, &r, &err) && r.pose.valid && !r.prev_used);
    CHECK(mr_tracker_frame(t, &g_f52, t1, &r, &err) && r.pose.valid && r.pose.tags_used == 1);
    if (pose52) *pose52 = r.pose;
    mr_tracker_destroy(&t);
    return r.prev_used;
}

static void test_policy(void) {
    mr_tracker_params p = MR_TRACKER_DEFAULTS;
    CHECK_MSG(prev_used_after(NULL, 0, 0.25, NULL), "a 0.25 s old pose must steer the solve");
    CHECK_MSG(prev_used_after(NULL, 0, 0.49, NULL), "a 0.49 s old pose must steer the solve (limit 0.5 s)");
    CHECK_MSG(!prev_used_after(NULL, 0, 0.5, NULL), "a pose exactly 0.5 s old must not steer the solve");
    CHECK_MSG(!prev_used_after(NULL, 0, 0.75, NULL), "a 0.75 s old pose must not steer the solve");
    CHECK_MSG(!prev_used_after(NULL, 1.0, 0.9, NULL), "time going backwards must drop the previous pose");
    CHECK_MSG(prev_used_after(NULL, 1.0, 1.0, NULL), "the same timestamp (age 0) keeps the previous pose");
    p.prev_max_age_s = 2.0;
    CHECK_MSG(prev_used_after(&p, 0, 1.5, NULL), "prev_max_age_s 2: a 1.5 s old pose steers");
    p.prev_max_age_s = 0.2;
    CHECK_MSG(!prev_used_after(&p, 0, 0.25, NULL), "prev_max_age_s 0.2: a 0.25 s old pose does not");
    p = (mr_tracker_params)MR_TRACKER_DEFAULTS;
    p.filter.max_gap_s = 1.0;
    CHECK_MSG(prev_used_after(&p, 0, 0.75, NULL), "the default limit follows the filter's max_gap_s (1 s here)");

    /* The rule shows in the poses: frame 52 solves differently with and
     * without frame 0's pose. */
    mr_pose with, without;
    prev_used_after(NULL, 0, 0.25, &with);
    prev_used_after(NULL, 0, 0.75, &without);
    CHECK_MSG(mr_pose_dist(&with.world_from_camera, &without.world_from_camera) > 1e-4,
              "frame 52 gives the same pose with and without the previous one (%.3g): the test lost its sense",
              mr_pose_dist(&with.world_from_camera, &without.world_from_camera));
    mr_error err = {0};
    CHECK(mr_tracker_create(&(mr_tracker_params){.prev_max_age_s = -1}, &err) == NULL && err.msg[0]);
}

/* The tracker is the parts run by hand, bit for bit. */
static void test_composition(void) {
    mr_error err = {0};
    mr_detector *det = mr_detector_create(NULL, &err);
    mr_pose_filter *filt = mr_pose_filter_create(NULL, &err);
    /* At the detector's fixed default: the adaptive decimation is
     * test_adaptive's. */
    mr_tracker_params fixed = MR_TRACKER_DEFAULTS;
    fixed.detector.decimate = MR_DETECTOR_DEFAULT_DECIMATE;
    mr_tracker *t = make(&fixed), *t2 = make(&fixed);
    if (!det || !filt || !t || !t2) return;
    const mr_image *frames[] = {&g_f0, &g_f52, &g_f0, &g_f52};
    const double ts[] = {0, 0.1, 0.2, 1.5};
    mr_pose prev = {0};
    double prev_t = 0;
    for (int i = 0; i < 4; i++) {
        int n = 0;
        const mr_detection *d = mr_detector_detect(det, frames[i], &n, &err);
        bool fresh = prev.valid && ts[i] - prev_t < 0.5 && ts[i] >= prev_t;
        mr_pose want;
        CHECK(d && mr_pose_solve(&g_rec->camera, &g_rec->markers, d, n, fresh ? &prev : NULL, NULL, &want, &err));
        mr_dmat4 wantf = mr_m4_identity();
        bool reset = mr_pose_filter_update(filt, ts[i], &want.world_from_camera, &wantf);
        prev = want;
        prev_t = ts[i];
        mr_tracker_result r;
        CHECK(mr_tracker_frame(t, frames[i], ts[i], &r, &err));
        CHECK_MSG(r.solved && r.detection_count == n && r.prev_used == fresh, "step %d: detections or policy", i);
        CHECK_MSG(r.pose.valid && memcmp(&r.pose.world_from_camera, &want.world_from_camera, sizeof want.world_from_camera) == 0 &&
                      r.pose.rms_px == want.rms_px && r.pose.tags_seen == want.tags_seen,
                  "step %d: the tracker's raw pose is not mr_pose_solve's", i);
        CHECK_MSG(r.has_filtered && memcmp(&r.filtered, &wantf, sizeof wantf) == 0 && r.filter_reset == reset,
                  "step %d: the tracker's filtered pose is not the One Euro filter's", i);
        /* Detections from elsewhere: the same from there on. */
        mr_tracker_result r2;
        CHECK(mr_tracker_detections(t2, d, n, frames[i]->width, frames[i]->height, ts[i], &r2, &err));
        CHECK_MSG(r2.detections == d && r2.prev_used == r.prev_used &&
                      memcmp(&r2.pose.world_from_camera, &r.pose.world_from_camera, sizeof wantf) == 0 &&
                      memcmp(&r2.filtered, &r.filtered, sizeof wantf) == 0,
                  "step %d: mr_tracker_detections differs from mr_tracker_frame", i);
    }
    mr_tracker_result r3;
    CHECK(!mr_tracker_detections(t2, NULL, 3, 640, 480, 9, &r3, &err));
    mr_tracker_destroy(&t2);
    mr_tracker_destroy(&t);
    CHECK(t == NULL);
    mr_tracker_destroy(&t);
    mr_tracker_destroy(NULL);
    mr_detector_destroy(&det);
    mr_pose_filter_destroy(&filt);
}

static void test_freeze_hold(void) {
    mr_tracker_params p = MR_TRACKER_DEFAULTS;
    p.freeze_first = true;
    mr_tracker *t = make(&p);
    if (!t) return;
    mr_image blank;
    mr_image_alloc(&blank, g_f0.width, g_f0.height, 1, MR_PIX_U8, NULL);
    memset(blank.data, 128, mr_image_bytes(&blank));
    mr_tracker_result r;
    mr_error err = {0};
    CHECK(mr_tracker_frame(t, &g_f0, 0, &r, &err) && r.pose.valid && r.frozen && mr_tracker_frozen(t));
    mr_dmat4 held = r.filtered;
    CHECK(memcmp(&held, &r.pose.world_from_camera, sizeof held) == 0);
    CHECK(mr_tracker_frame(t, &g_f52, 0.1, &r, &err) && r.pose.valid);
    CHECK_MSG(r.has_filtered && memcmp(&r.filtered, &held, sizeof held) == 0, "frozen: the filtered pose must hold");
    CHECK(mr_tracker_frame(t, &blank, 0.2, &r, &err) && !r.pose.valid && r.detection_count == 0);
    CHECK_MSG(r.has_filtered && memcmp(&r.filtered, &held, sizeof held) == 0,
              "frozen: the held pose must stand when the tags are lost");
    mr_tracker_freeze(t, false);
    CHECK(!mr_tracker_frozen(t));
    CHECK(mr_tracker_frame(t, &g_f52, 0.3, &r, &err) && r.pose.valid && r.filter_reset);
    CHECK_MSG(memcmp(&r.filtered, &r.pose.world_from_camera, sizeof held) == 0, "unfrozen: the filter restarts");
    /* The view's freeze: on demand, and a reset lifts it and forgets the
     * previous pose. */
    mr_tracker_freeze(t, true);
    CHECK(mr_tracker_frame(t, &blank, 0.35, &r, &err) && r.frozen && r.has_filtered);
    mr_tracker_reset(t);
    CHECK(!mr_tracker_frozen(t));
    CHECK(mr_tracker_frame(t, &g_f52, 0.4, &r, &err) && !r.prev_used && r.filter_reset);
    mr_tracker_destroy(&t);

    /* Without the filter: raw poses only. */
    p = (mr_tracker_params)MR_TRACKER_DEFAULTS;
    p.no_filter = true;
    t = make(&p);
    CHECK(t && mr_tracker_frame(t, &g_f0, 0, &r, &err) && r.pose.valid && !r.has_filtered);
    mr_tracker_destroy(&t);
    mr_image_free(&blank);
}

/* A frame at half the calibrated size: the intrinsics are rescaled, so the
 * pose stays near where the full frame puts it (frame 0's two tags are
 * about 14 px wide at half size: 0.29 units apart today;
 * unscaled intrinsics put it ~8 units away). */
static void test_resized_frame(void) {
    mr_image half;
    mr_image_alloc(&half, g_f0.width / 2, g_f0.height / 2, 1, MR_PIX_U8, NULL);
    const unsigned char *s = g_f0.data;
    unsigned char *d = half.data;
    for (int y = 0; y < half.height; y++)
        for (int x = 0; x < half.width; x++) {
            const unsigned char *p = s + (size_t)(2 * y) * g_f0.width + 2 * x;
            d[(size_t)y * half.width + x] = (unsigned char)((p[0] + p[1] + p[g_f0.width] + p[g_f0.width + 1] + 2) / 4);
        }
    mr_tracker *t = make(NULL), *tf = make(NULL);
    mr_tracker_result r, rf;
    mr_error err = {0};
    CHECK(t && tf && mr_tracker_frame(tf, &g_f0, 0, &rf, &err) && rf.pose.valid);
    CHECK(t && mr_tracker_frame(t, &half, 0, &r, &err));
    double dist = r.pose.valid ? mr_pose_dist(&r.pose.world_from_camera, &rf.pose.world_from_camera) : 1e9;
    CHECK_MSG(r.pose.valid && dist < 0.5 && r.pose.rms_px < 1.0,
              "half-size frame: pose %s, %.3f units from the full frame's, rms %.2f px (intrinsics not rescaled?)",
              r.pose.valid ? "valid" : "lost", dist, r.pose.rms_px);
    mr_tracker_destroy(&t);
    mr_tracker_destroy(&tf);
    mr_image_free(&half);
}

/* Shortest edge of the second largest detection (the only one's if one). */
static double second_edge(const mr_detection *d, int n) {
    double a = 0, b = 0;
    for (int i = 0; i < n; i++) {
        double e = INFINITY;
        for (int k = 0; k < 4; k++)
            e = fmin(e, hypot(d[i].corners[(k + 1) % 4][0] - d[i].corners[k][0], d[i].corners[(k + 1) % 4][1] - d[i].corners[k][1]));
        if (e > a) b = a, a = e;
        else if (e > b) b = e;
    }
    return n == 1 ? a : b;
}

/* Adaptive decimation (mr_track.h): the rule, the first frame at 2, each
 * next frame at the rule's pick from the frame before, a probe at 2 every
 * MR_TRACKER_PROBE_FRAMES frames, a lost frame detected again at 2, the
 * pose at a coarse decimation as good, and --decimate fixing it. Large
 * tags: frame 0 at three times its size (pixels tripled, the intrinsics
 * scaled). */
static void test_adaptive(void) {
    CHECK(mr_tracker_pick_decimate(70) == 4 && mr_tracker_pick_decimate(64) == 4 && mr_tracker_pick_decimate(50) == 3 &&
          mr_tracker_pick_decimate(30) == 2 && mr_tracker_pick_decimate(16) == 2 && mr_tracker_pick_decimate(10) == 1 &&
          mr_tracker_pick_decimate(NAN) == MR_DETECTOR_DEFAULT_DECIMATE);
    mr_image big;
    mr_image_alloc(&big, g_f0.width * 3, g_f0.height * 3, 1, MR_PIX_U8, NULL);
    for (int y = 0; y < big.height; y++)
        for (int x = 0; x < big.width; x++)
            ((unsigned char *)big.data)[(size_t)y * big.width + x] =
                ((const unsigned char *)g_f0.data)[(size_t)(y / 3) * g_f0.width + x / 3];
    mr_tracker *t = make(NULL);
    mr_tracker_result r;
    mr_error err = {0};
    CHECK(t && mr_tracker_frame(t, &big, 0, &r, &err) && r.decimate == MR_DETECTOR_DEFAULT_DECIMATE && r.pose.valid);
    double want = mr_tracker_pick_decimate(second_edge(r.detections, r.detection_count));
    mr_dmat4 first = r.pose.world_from_camera;
    CHECK_MSG(want > MR_DETECTOR_DEFAULT_DECIMATE, "frame 0 tripled: tags of %.1f px pick %g, want coarser than 2",
              second_edge(r.detections, r.detection_count), want);
    int probes = 0;
    for (int i = 1; t && i <= MR_TRACKER_PROBE_FRAMES; i++) {
        CHECK(mr_tracker_frame(t, &big, 0.1 * i, &r, &err) && r.pose.valid);
        probes += r.decimate == MR_DETECTOR_DEFAULT_DECIMATE;
        CHECK_MSG(r.decimate == want || r.decimate == MR_DETECTOR_DEFAULT_DECIMATE, "frame %d at decimation %g, want %g", i,
                  r.decimate, want);
        double dist = mr_pose_dist(&r.pose.world_from_camera, &first);
        /* the tags are ~10 units away: 1% of that (blocky tripled pixels) */
        CHECK_MSG(r.pose.tags_used >= 2 && dist < 0.1, "frame %d at decimation %g: pose %.3f units from decimation 2's", i,
                  r.decimate, dist);
    }
    CHECK_MSG(probes == 1, "%d probes at decimation 2 in %d frames, want 1", probes, MR_TRACKER_PROBE_FRAMES);
    /* The original size after large tags: decimation 4 loses them (7 px),
     * the frame is detected again at 2. */
    CHECK_MSG(want == 4, "frame 0 tripled picks %g, want 4", want);
    CHECK(t && mr_tracker_frame(t, &g_f0, 1.0, &r, &err));
    CHECK_MSG(r.redetected && r.decimate == MR_DETECTOR_DEFAULT_DECIMATE && r.detection_count >= 2 && r.pose.valid,
              "small tags after large ones: decimation %g, %d tags (redetected %d)", r.decimate, r.detection_count,
              r.redetected);
    mr_tracker_destroy(&t);
    /* A given decimation stays. */
    mr_tracker_params p = MR_TRACKER_DEFAULTS;
    p.detector.decimate = 1.5;
    t = make(&p);
    for (int i = 0; t && i < 3; i++) CHECK(mr_tracker_frame(t, &big, 0.1 * i, &r, &err) && r.decimate == 1.5 && !r.redetected);
    mr_tracker_destroy(&t);
    mr_image_free(&big);
}

static void test_detect_only_and_errors(void) {
    mr_error err = {0};
    mr_tracker *t = mr_tracker_create(NULL, &err);
    CHECK_MSG(t != NULL, "a tracker without camera and markers detects: %s", err.msg);
    mr_tracker_result r;
    CHECK(t && mr_tracker_frame(t, &g_f0, 0, &r, &err) && !r.solved && !r.pose.valid && r.detection_count >= 2 &&
          !r.has_filtered);
    CHECK(t && mr_tracker_camera(t) == NULL && mr_tracker_markers(t) == NULL);
    /* A frame too small for the detector is an error, not a crash. */
    mr_image tiny;
    mr_image_alloc(&tiny, 8, 8, 1, MR_PIX_U8, NULL);
    err.msg[0] = 0;
    CHECK(t && !mr_tracker_frame(t, &tiny, 0, &r, &err) && err.msg[0]);
    mr_image_free(&tiny);
    mr_tracker_destroy(&t);
    /* The tracker keeps copies: the caller's map may go away. */
    mr_marker_map copy = g_rec->markers;
    copy.tags = malloc((size_t)copy.count * sizeof *copy.tags);
    memcpy(copy.tags, g_rec->markers.tags, (size_t)copy.count * sizeof *copy.tags);
    mr_tracker_params p = MR_TRACKER_DEFAULTS;
    p.camera = &g_rec->camera;
    p.markers = &copy;
    t = mr_tracker_create(&p, &err);
    mr_marker_map_free(&copy);
    CHECK(t && mr_tracker_frame(t, &g_f0, 0, &r, &err) && r.pose.valid && r.pose.tags_used >= 2);
    CHECK(t && mr_tracker_markers(t) && mr_tracker_markers(t)->count == g_rec->markers.count);
    mr_tracker_destroy(&t);
    /* Bad parameters. */
    mr_camera bad = g_rec->camera;
    bad.fx = 0;
    p.markers = &g_rec->markers;
    p.camera = &bad;
    CHECK(mr_tracker_create(&p, &err) == NULL);
    p.camera = &g_rec->camera;
    p.detector.family = "tag99h99";
    err.msg[0] = 0;
    CHECK(mr_tracker_create(&p, &err) == NULL && err.msg[0]);
}

int main(void) {
    const char *src = getenv("MR_SOURCE_DIR");
    char dir[2048];
    /* Frames 0 and 52 of the recording shipped before issue 16 (its walk saw
     * lone wall tags; the new one sees tag posts), kept as a two-frame
     * recording: the cases below need a lone ambiguous tag. */
    snprintf(dir, sizeof dir, "%s/tests/data/tracker", src ? src : ".");
    mr_error err = {0};
    g_rec = mr_recording_open(dir, &err);
    CHECK_MSG(g_rec != NULL, "%s", err.msg);
    if (!g_rec) return mr_test_finish("test_track_tracker");
    CHECK(mr_recording_load_image(g_rec, 0, true, &g_f0, &err));
    CHECK(g_rec->frame_count == 2 && mr_recording_load_image(g_rec, 1, true, &g_f52, &err));
    test_policy();
    test_composition();
    test_freeze_hold();
    test_resized_frame();
    test_adaptive();
    test_detect_only_and_errors();
    mr_image_free(&g_f0);
    mr_image_free(&g_f52);
    mr_recording_close(&g_rec);
    return mr_test_finish("test_track_tracker");
}
