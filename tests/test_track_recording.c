/* Tracking on the shipped synthetic recording (recordings/demo: the demo
 * hall rendered along a walking path with pauses, lens distortion, noise,
 * motion blur over a 1/60 s shutter, exposure changes, JPEG; 217 frames at
 * 10 Hz, 640x480, the walk of issue 16 past the tag posts at walking pace) against its ground truth, run as `mrcheck track` runs it
 * (the one tracker, mr_tracker: detect, solve with the previous pose by
 * its policy, One Euro filter): tracked
 * fraction, error percentiles and maximum, flips and jitter, each pinned
 * just above today's value (see check_today), and golden detections. */
#include "mr_session.h"
#include "mr_test.h"
#include "mr_test_track.h"

#include <stdlib.h>
#include <string.h>

/* Nearest-rank percentile (q in [0,1]) of v[0..n); sorts v. */
static int cmp_d(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double percentile(double *v, int n, double q) {
    if (n == 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    int k = (int)ceil(q * n) - 1;
    return v[k < 0 ? 0 : k >= n ? n - 1 : k];
}

#define MAXF 512

typedef struct run {
    int frames, poses, multi;
    bool valid[MAXF];
    int tags_used[MAXF], tag0[MAXF];  /* tags used, the first of them */
    mr_dmat4 pose[MAXF], filt[MAXF];
} run;

/* The recording through the one tracker (mr_tracker, default parameters)
 * as `mrcheck track` runs it: grey frames, recorded timestamps. */
static void track_all(const mr_recording *rec, run *out) {
    memset(out, 0, sizeof *out);
    mr_error err = {0};
    mr_tracker_params tp = MR_TRACKER_DEFAULTS;
    tp.camera = &rec->camera;
    tp.markers = &rec->markers;
    mr_tracker *t = mr_tracker_create(&tp, &err);
    CHECK_MSG(t != NULL, "tracker: %s", err.msg);
    if (!t) return;
    out->frames = rec->frame_count < MAXF ? rec->frame_count : MAXF;
    for (int i = 0; i < out->frames; i++) {
        mr_image img;
        CHECK_MSG(mr_recording_load_image(rec, i, true, &img, &err), "frame %d: %s", i, err.msg);
        mr_tracker_result r;
        CHECK_MSG(mr_tracker_frame(t, &img, rec->frames[i].t, &r, &err), "frame %d: %s", i, err.msg);
        mr_image_free(&img);
        const mr_pose *p = &r.pose;
        out->valid[i] = p->valid;
        out->pose[i] = p->world_from_camera;
        out->tags_used[i] = p->tags_used;
        out->tag0[i] = p->ids_used[0];
        if (!p->valid) continue;
        out->filt[i] = r.filtered;
        out->poses++;
        out->multi += p->tags_used >= 2;
    }
    mr_tracker_destroy(&t);
}

/* Error of a pose against ground truth as a rotation vector (radians, in
 * the camera frame: log(R_gt^T R)) and a translation (scene units). */
static void pose_error(const mr_dmat4 *est, const mr_dmat4 *gt, double rv[3], double dt[3]) {
    double R[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            R[r * 3 + c] = gt->m[0 * 4 + r] * est->m[0 * 4 + c] + gt->m[1 * 4 + r] * est->m[1 * 4 + c] +
                           gt->m[2 * 4 + r] * est->m[2 * 4 + c];
    mr_mat_to_rotvec(R, rv);
    for (int k = 0; k < 3; k++) dt[k] = est->m[k * 4 + 3] - gt->m[k * 4 + 3];
}

typedef struct err_stats {
    int n;                                        /* frames with a pose */
    double pos_med, pos_p90, pos_p95, pos_max;    /* mm */
    double rot_med, rot_p90, rot_p95, rot_max;    /* degrees */
    double multi_pos_med, multi_pos_max;          /* mm, frames with >= 2 tags */
    int over5, over10;                            /* rotation error > 5 / 10 degrees */
    int flips;                                    /* single tag, nearer its mirror pose */
    int jn, jn_still;                             /* triples of consecutive tracked frames (still) */
    double jit_pos, jit_rot;                      /* RMS second difference of the error, mm, deg */
    double jit_still_pos, jit_still_rot;          /* the same over still triples */
    double gt_jit_pos;                            /* ground truth's own, mm */
} err_stats;

/* A flip is a single-tag pose nearer the tag's mirror pose (what IPPE's
 * second solution approximates, mr_test_track.h) than the truth, where the
 * two are >= 10 degrees apart (closer to head-on the branches merge and
 * the word means nothing). Large errors are not all flips: the frames
 * with 5-9 degrees error here have their mirror 24-50 degrees away. */
#define FLIP_MIN_SEPARATION_DEG 10.0

static void error_stats(const mr_recording *rec, const run *r, bool filtered, err_stats *s) {
    static double pe[MAXF], re[MAXF], mp[MAXF];
    static double erv[MAXF][3], edt[MAXF][3];
    memset(s, 0, sizeof *s);
    int nm = 0;
    for (int i = 0; i < r->frames; i++) {
        if (!r->valid[i]) continue;
        const mr_dmat4 *est = filtered ? &r->filt[i] : &r->pose[i], *gt = &rec->frames[i].gt;
        pose_error(est, gt, erv[i], edt[i]);
        double e = mr_pose_angle_deg(est, gt);
        pe[s->n] = 1e3 * mr_pose_dist(est, gt);
        re[s->n] = e;
        if (r->tags_used[i] >= 2) mp[nm++] = pe[s->n];
        s->n++;
        s->over5 += e > 5;
        s->over10 += e > 10;
        if (r->tags_used[i] == 1) {
            mr_dmat4 mir = mr_test_mirror_pose(mr_marker_map_find(&rec->markers, r->tag0[i]), gt);
            s->flips += mr_pose_angle_deg(&mir, gt) >= FLIP_MIN_SEPARATION_DEG && mr_pose_angle_deg(est, &mir) < e;
        }
    }
    /* Jitter: second differences over three consecutive tracked frames of
     * the error (estimate minus truth), so the camera's own motion cancels
     * (ground truth's own second differences give the scale of that
     * motion); over all such triples and over those inside the
     * recording's pauses, where the filter should calm the pose. */
    double jp = 0, jr = 0, sp = 0, sr = 0, gp = 0;
    for (int i = 1; i + 1 < r->frames; i++) {
        if (!r->valid[i - 1] || !r->valid[i] || !r->valid[i + 1]) continue;
        double a = 0, b = 0, c = 0;
        for (int k = 0; k < 3; k++) {
            double d2p = edt[i + 1][k] - 2 * edt[i][k] + edt[i - 1][k];
            double d2r = erv[i + 1][k] - 2 * erv[i][k] + erv[i - 1][k];
            double g = rec->frames[i + 1].gt.m[k * 4 + 3] - 2 * rec->frames[i].gt.m[k * 4 + 3] +
                       rec->frames[i - 1].gt.m[k * 4 + 3];
            a += d2p * d2p;
            b += d2r * d2r;
            c += g * g;
        }
        jp += a;
        jr += b;
        gp += c;
        s->jn++;
        if (rec->frames[i - 1].still && rec->frames[i].still && rec->frames[i + 1].still) {
            sp += a;
            sr += b;
            s->jn_still++;
        }
    }
    s->jit_pos = s->jn ? 1e3 * sqrt(jp / s->jn) : NAN;
    s->jit_rot = s->jn ? 180 / M_PI * sqrt(jr / s->jn) : NAN;
    s->gt_jit_pos = s->jn ? 1e3 * sqrt(gp / s->jn) : NAN;
    s->jit_still_pos = s->jn_still ? 1e3 * sqrt(sp / s->jn_still) : NAN;
    s->jit_still_rot = s->jn_still ? 180 / M_PI * sqrt(sr / s->jn_still) : NAN;
    s->pos_med = percentile(pe, s->n, 0.5);
    s->pos_p90 = percentile(pe, s->n, 0.9);
    s->pos_p95 = percentile(pe, s->n, 0.95);
    s->pos_max = percentile(pe, s->n, 1.0);
    s->rot_med = percentile(re, s->n, 0.5);
    s->rot_p90 = percentile(re, s->n, 0.9);
    s->rot_p95 = percentile(re, s->n, 0.95);
    s->rot_max = percentile(re, s->n, 1.0);
    s->multi_pos_med = percentile(mp, nm, 0.5);
    s->multi_pos_max = percentile(mp, nm, 1.0);
}

static void print_stats(const char *what, const err_stats *s, int frames) {
    printf("%s: %d/%d tracked (%.1f%%); position mm median %.1f p90 %.1f p95 %.1f max %.1f (multi-tag median %.1f "
           "max %.1f); rotation deg median %.3f p90 %.3f p95 %.3f max %.3f; > 5 deg %d, > 10 deg %d, flips %d "
           "(%.1f%% of poses); jitter over %d triples %.1f mm %.3f deg (ground truth's own motion %.1f mm), over %d "
           "still triples %.2f mm %.4f deg\n",
           what, s->n, frames, 100.0 * s->n / frames, s->pos_med, s->pos_p90, s->pos_p95, s->pos_max, s->multi_pos_med,
           s->multi_pos_max, s->rot_med, s->rot_p90, s->rot_p95, s->rot_max, s->over5, s->over10, s->flips,
           100.0 * s->flips / s->n, s->jn, s->jit_pos, s->jit_rot, s->gt_jit_pos, s->jn_still, s->jit_still_pos,
           s->jit_still_rot);
}

/* Today's numbers on the shipped recording (RelWithDebInfo, x86-64; the
 * test prints them), pinned with 3% slack: the code is deterministic, so a
 * change beyond that is a change in behaviour, to be looked at and the
 * numbers updated on purpose.
 *                   raw pose                    after the One Euro filter
 *   (the recording of issue 16 at walking pace, 1.1 m/s, 1/60 s shutter;
 *   adaptive decimation)
 *   tracked         210 of 217 frames (96.8%), 209 with >= 2 tags; the 7
 *                   without a pose see no tag of >= 20 px
 *   position mm     median 12.7 p90 58.7        median 53.0 p90 73.6
 *                   p95 89.2 max 414.3          p95 108.1 max 271.0
 *   multi-tag mm    median 12.7 max 314.8       median 53.0 max 271.0
 *   rotation deg    median 0.158 p90 0.459      median 0.709 p90 2.141
 *                   p95 0.698 max 4.329         p95 2.388 max 2.461
 *   > 5 / > 10 deg  0 / 0 poses                 0 / 0
 *   flips           0
 *   jitter, all     108.8 mm 0.755 deg          81.4 mm 0.322 deg  (206 triples;
 *                                               the truth moves 6.9 mm RMS per triple)
 *   jitter, still   3.321 mm 0.0400 deg         1.149 mm 0.0174 deg (40 triples)
 * The filtered error is the One Euro filter's lag behind a steady walk
 * (1.33 m/s for seconds on end; the first recording's walks were short
 * lunges between pauses). The largest raw errors are single far frames
 * with one or two small tags (frame 22: one tag, 414 mm).
 * The flip rate is a regression gate, not a target: "8.5% flips" in
 * docs/bench/tracking counts rotation errors > 5 degrees (7 of 82 on the old recording, 0 here),
 * most of which are not flips. The filtered jitter at rest is pinned both
 * ways: lower means more lag (a cutoff or beta term gone), higher less
 * smoothing. */
typedef struct pin { const char *what; double value, today; bool both_ways; } pin;

static void check_today(const err_stats *raw, const err_stats *filt, int frames, int multi) {
    CHECK_MSG(frames == 217, "the recording has %d frames, the numbers below are for 217", frames);
    CHECK_MSG(raw->n >= 210, "tracked fraction fell: %d of %d frames have a pose, today 210", raw->n, frames);
    CHECK_MSG(multi >= 209, "multi-tag poses fell: %d, today 209", multi);
    CHECK_MSG(raw->flips <= 0, "pose flips rose: %d single-tag poses nearer the mirror pose than the truth, today 0 "
              "(flip guard or ambiguity margin broken?)", raw->flips);
    CHECK_MSG(filt->flips <= 0, "filtered pose flips rose: %d, today 0", filt->flips);
    CHECK_MSG(raw->over5 <= 0 && raw->over10 <= 0, "rotation errors > 5 / 10 deg rose: %d / %d poses, today 0 / 0",
              raw->over5, raw->over10);
    CHECK_MSG(filt->over5 <= 0 && filt->over10 <= 0, "filtered rotation errors > 5 / 10 deg rose: %d / %d, today 0 / 0",
              filt->over5, filt->over10);
    const pin pins[] = {
        {"raw position error median (mm)", raw->pos_med, 12.65, false},
        {"raw position error p90 (mm)", raw->pos_p90, 58.72, false},
        {"raw position error p95 (mm)", raw->pos_p95, 89.25, false},
        {"raw position error max (mm)", raw->pos_max, 414.3, false},
        {"raw multi-tag position error median (mm)", raw->multi_pos_med, 12.65, false},
        {"raw multi-tag position error max (mm)", raw->multi_pos_max, 314.8, false},
        {"raw rotation error median (deg)", raw->rot_med, 0.1581, false},
        {"raw rotation error p90 (deg)", raw->rot_p90, 0.4586, false},
        {"raw rotation error p95 (deg)", raw->rot_p95, 0.6977, false},
        {"raw rotation error max (deg)", raw->rot_max, 4.329, false},
        {"raw jitter, position (mm)", raw->jit_pos, 108.8, false},
        {"raw jitter, rotation (deg)", raw->jit_rot, 0.7548, false},
        {"raw jitter at rest, position (mm)", raw->jit_still_pos, 3.321, false},
        {"raw jitter at rest, rotation (deg)", raw->jit_still_rot, 0.03997, false},
        {"filtered position error median (mm)", filt->pos_med, 53.04, false},
        {"filtered position error p90 (mm)", filt->pos_p90, 73.62, false},
        {"filtered position error p95 (mm)", filt->pos_p95, 108.1, false},
        {"filtered position error max (mm)", filt->pos_max, 271.0, false},
        {"filtered multi-tag position error median (mm)", filt->multi_pos_med, 53.04, false},
        {"filtered multi-tag position error max (mm)", filt->multi_pos_max, 271.0, false},
        {"filtered rotation error median (deg)", filt->rot_med, 0.7086, false},
        {"filtered rotation error p90 (deg)", filt->rot_p90, 2.141, false},
        {"filtered rotation error p95 (deg)", filt->rot_p95, 2.388, false},
        {"filtered rotation error max (deg)", filt->rot_max, 2.461, false},
        {"filtered jitter, position (mm)", filt->jit_pos, 81.44, false},
        {"filtered jitter, rotation (deg)", filt->jit_rot, 0.3218, false},
        {"filtered jitter at rest, position (mm)", filt->jit_still_pos, 1.149, true},
        {"filtered jitter at rest, rotation (deg)", filt->jit_still_rot, 0.0174, true},
    };
    /* MR_PRINT_TODAY=1 prints every measured value (to re-pin on purpose). */
    if (getenv("MR_PRINT_TODAY")) {
        printf("today: tracked %d of %d, multi %d, flips %d / %d, >5 deg %d / %d, >10 deg %d / %d\n", raw->n, frames,
               multi, raw->flips, filt->flips, raw->over5, filt->over5, raw->over10, filt->over10);
        for (size_t i = 0; i < sizeof pins / sizeof pins[0]; i++) printf("today: %s = %.4g\n", pins[i].what, pins[i].value);
    }
    for (size_t i = 0; i < sizeof pins / sizeof pins[0]; i++) {
        const pin *p = &pins[i];
        bool high = !(p->value <= 1.03 * p->today), low = p->both_ways && !(p->value >= 0.97 * p->today);
        CHECK_MSG(!high && !low, "%s is %.4g, today %.4g (%s)", p->what, p->value, p->today,
                  high ? "worse by more than 3%" : "lower by more than 3%: the filter smooths more, so it lags more");
    }
}

/* Golden detections (apriltag habit: a .txt per image): frames 0 and 95 of
 * the shipped recording with the default detector, one line per tag:
 * "id hamming x0 y0 x1 y1 x2 y2 x3 y3". MR_UPDATE_GOLDEN=1 rewrites. */
static void check_golden(const mr_recording *rec, int frame, const char *data_dir) {
    char path[2048];
    snprintf(path, sizeof path, "%s/golden/detections_%03d.txt", data_dir, frame);
    mr_error err = {0};
    mr_image img;
    CHECK(mr_recording_load_image(rec, frame, true, &img, &err));
    mr_detector *d = mr_detector_create(NULL, &err);
    int n = 0;
    const mr_detection *det = mr_detector_detect(d, &img, &n, &err);
    char text[4096];
    int len = 0;
    for (int i = 0; det && i < n; i++) {
        len += snprintf(text + len, sizeof text - (size_t)len, "%d %d", det[i].id, det[i].hamming);
        for (int k = 0; k < 4; k++)
            len += snprintf(text + len, sizeof text - (size_t)len, " %.4f %.4f", det[i].corners[k][0], det[i].corners[k][1]);
        len += snprintf(text + len, sizeof text - (size_t)len, "\n");
    }
    if (getenv("MR_UPDATE_GOLDEN")) {
        CHECK(mr_file_write_atomic(path, text, (size_t)len, &err));
    } else {
        size_t size = 0;
        char *want = mr_file_read(path, &size, 0, &err);
        CHECK_MSG(want != NULL, "%s", err.msg);
        /* compare numerically: 0.01 px leaves room for libm differences */
        const char *a = text, *b = want ? want : "";
        int lines = 0;
        while (want && *a && *b) {
            int id1, h1, id2, h2, c1, c2;
            double p[8], q[8];
            c1 = sscanf(a, "%d %d %lf %lf %lf %lf %lf %lf %lf %lf", &id1, &h1, &p[0], &p[1], &p[2], &p[3], &p[4], &p[5], &p[6], &p[7]);
            c2 = sscanf(b, "%d %d %lf %lf %lf %lf %lf %lf %lf %lf", &id2, &h2, &q[0], &q[1], &q[2], &q[3], &q[4], &q[5], &q[6], &q[7]);
            CHECK(c1 == 10 && c2 == 10 && id1 == id2 && h1 == h2);
            for (int k = 0; k < 8; k++) CHECK_NEAR(p[k], q[k], 0.01);
            a = strchr(a, '\n');
            b = strchr(b, '\n');
            if (!a || !b) break;
            a++;
            b++;
            lines++;
        }
        CHECK_MSG(lines == n && (!b || !*b), "frame %d: %d detections, golden has more or fewer", frame, n);
        free(want);
    }
    mr_detector_destroy(&d);
    mr_image_free(&img);
}

int main(void) {
    const char *src = getenv("MR_SOURCE_DIR");
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/recordings/demo", src ? src : ".");
    mr_error err = {0};
    mr_recording *rec = mr_recording_open(dir, &err);
    CHECK_MSG(rec != NULL, "%s", err.msg);
    if (!rec) return mr_test_finish("test_track_recording");
    CHECK(rec->frame_count >= 60 && rec->has_markers && rec->bad_lines == 0);
    int gt = 0;
    for (int i = 0; i < rec->frame_count; i++) gt += rec->frames[i].has_gt;
    CHECK(gt == rec->frame_count);
    const char *data = getenv("MR_TEST_DATA");
    check_golden(rec, 0, data ? data : "tests/data");
    check_golden(rec, 95, data ? data : "tests/data");
    static run a, b;
    track_all(rec, &a);
    err_stats raw, filt;
    error_stats(rec, &a, false, &raw);
    error_stats(rec, &a, true, &filt);
    print_stats("raw", &raw, a.frames);
    print_stats("filtered", &filt, a.frames);
    check_today(&raw, &filt, a.frames, a.multi);
    /* The same frames give the same detections and poses, bit for bit. */
    track_all(rec, &b);
    bool same = true;
    for (int i = 0; i < a.frames; i++)
        same = same && a.valid[i] == b.valid[i] && (!a.valid[i] || memcmp(&a.pose[i], &b.pose[i], sizeof a.pose[i]) == 0);
    CHECK_MSG(same, "two runs over the same frames gave different poses");
    mr_recording_close(&rec);
    return mr_test_finish("test_track_recording");
}
