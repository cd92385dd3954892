/* Pose accuracy on the shipped synthetic recording (recordings/demo: the
 * demo hall rendered along a walking path, lens distortion, noise, motion
 * blur, exposure changes, JPEG), against its ground truth. Bounds are loose
 * enough for the single-tag frames (small tags at 3-7 m) and tight for the
 * multi-tag ones; see `mrcheck bench tracking` for the measured numbers. */
#include "mr_session.h"
#include "mr_test.h"

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
#define MAXD 16

/* Detections of every frame, found once: the pose runs below (and the
 * mutation checks in the report) change only the solver and the filter. */
typedef struct frame_dets { int n; mr_detection d[MAXD]; } frame_dets;

typedef struct run {
    int frames, poses, multi;
    bool valid[MAXF];
    int tags_used[MAXF];
    mr_dmat4 pose[MAXF], filt[MAXF];
} run;

static void detect_all(const mr_recording *rec, frame_dets *fd) {
    mr_error err = {0};
    mr_detector *det = mr_detector_create(NULL, &err);
    for (int i = 0; i < rec->frame_count && i < MAXF; i++) {
        fd[i].n = 0;
        mr_image img;
        CHECK_MSG(mr_recording_load_image(rec, i, true, &img, &err), "frame %d: %s", i, err.msg);
        int n = 0;
        const mr_detection *d = mr_detector_detect(det, &img, &n, &err);
        CHECK_MSG(d != NULL, "frame %d: %s", i, err.msg);
        for (int k = 0; d && k < n && k < MAXD; k++) fd[i].d[fd[i].n++] = d[k];
        mr_image_free(&img);
    }
    mr_detector_destroy(&det);
}

/* The tracker as `mrcheck track` runs it (app/track_util.c): the previous
 * pose helps only if it is under 0.5 s old; valid poses feed the One Euro
 * filter with default parameters. */
static void track_all(const mr_recording *rec, const frame_dets *fd, run *out) {
    memset(out, 0, sizeof *out);
    mr_error err = {0};
    mr_pose_filter *filt = mr_pose_filter_create(NULL, &err);
    mr_pose prev = {0};
    double prev_t = 0;
    out->frames = rec->frame_count < MAXF ? rec->frame_count : MAXF;
    for (int i = 0; i < out->frames; i++) {
        double t = rec->frames[i].t;
        const mr_pose *pp = prev.valid && t - prev_t < 0.5 && t >= prev_t ? &prev : NULL;
        mr_pose p;
        CHECK(mr_pose_solve(&rec->camera, &rec->markers, fd[i].d, fd[i].n, pp, NULL, &p, &err));
        out->valid[i] = p.valid;
        out->pose[i] = p.world_from_camera;
        out->tags_used[i] = p.tags_used;
        if (!p.valid) continue;
        prev = p;
        prev_t = t;
        mr_pose_filter_update(filt, t, &p.world_from_camera, &out->filt[i]);
        out->poses++;
        out->multi += p.tags_used >= 2;
    }
    mr_pose_filter_destroy(&filt);
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
    int n;
    double pos_med, pos_p90, pos_p95, pos_max;    /* mm */
    double rot_med, rot_p90, rot_p95, rot_max;    /* degrees */
    int flips;                                    /* rotation error > FLIP_DEG */
    int jn;                                       /* triples of consecutive tracked frames */
    double jit_pos, jit_rot;                      /* RMS second difference of the error, mm, deg */
    double gt_jit_pos, gt_jit_rot;                /* ground truth's own, mm, deg */
} err_stats;

/* A pose flip: a single tag's mirror solution is tilted by twice the
 * viewing angle off the tag's normal (>= ~20 degrees for the tags in this
 * hall), while correct poses here stay under 5 degrees (measured max of the
 * multi-tag and unflipped single-tag frames); 10 degrees separates them. */
#define FLIP_DEG 10.0

static void error_stats(const mr_recording *rec, const run *r, bool filtered, err_stats *s) {
    static double pe[MAXF], re[MAXF];
    static double erv[MAXF][3], edt[MAXF][3];
    memset(s, 0, sizeof *s);
    for (int i = 0; i < r->frames; i++) {
        if (!r->valid[i]) continue;
        const mr_dmat4 *est = filtered ? &r->filt[i] : &r->pose[i];
        pose_error(est, &rec->frames[i].gt, erv[i], edt[i]);
        pe[s->n] = 1e3 * mr_pose_dist(est, &rec->frames[i].gt);
        re[s->n] = mr_pose_angle_deg(est, &rec->frames[i].gt);
        s->flips += re[s->n] > FLIP_DEG;
        s->n++;
    }
    /* Jitter: second differences over three consecutive tracked frames of
     * the error (estimate minus truth), so the camera's own motion cancels;
     * ground truth's own second differences give the scale of that motion. */
    double jp = 0, jr = 0, gp = 0, gr = 0;
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
        double ga = mr_pose_angle_deg(&rec->frames[i - 1].gt, &rec->frames[i].gt) -
                    mr_pose_angle_deg(&rec->frames[i].gt, &rec->frames[i + 1].gt);
        gr += ga * ga;
        s->jn++;
    }
    if (s->jn) {
        s->jit_pos = 1e3 * sqrt(jp / s->jn);
        s->jit_rot = 180 / M_PI * sqrt(jr / s->jn);
        s->gt_jit_pos = 1e3 * sqrt(gp / s->jn);
        s->gt_jit_rot = sqrt(gr / s->jn);
    }
    s->pos_med = percentile(pe, s->n, 0.5);
    s->pos_p90 = percentile(pe, s->n, 0.9);
    s->pos_p95 = percentile(pe, s->n, 0.95);
    s->pos_max = percentile(pe, s->n, 1.0);
    s->rot_med = percentile(re, s->n, 0.5);
    s->rot_p90 = percentile(re, s->n, 0.9);
    s->rot_p95 = percentile(re, s->n, 0.95);
    s->rot_max = percentile(re, s->n, 1.0);
}

static void print_stats(const char *what, const err_stats *s, int frames) {
    printf("%s: %d/%d tracked (%.1f%%); position mm median %.1f p90 %.1f p95 %.1f max %.1f; rotation deg median "
           "%.3f p90 %.3f p95 %.3f max %.3f; flips %d (%.1f%%); jitter over %d triples: %.2f mm, %.4f deg "
           "(ground truth's own %.2f mm, %.4f deg)\n",
           what, s->n, frames, 100.0 * s->n / frames, s->pos_med, s->pos_p90, s->pos_p95, s->pos_max, s->rot_med,
           s->rot_p90, s->rot_p95, s->rot_max, s->flips, 100.0 * s->flips / frames, s->jn, s->jit_pos, s->jit_rot,
           s->gt_jit_pos, s->gt_jit_rot);
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
    static frame_dets fd[MAXF];
    static run a, b;
    detect_all(rec, fd);
    track_all(rec, fd, &a);
    err_stats raw, filt;
    error_stats(rec, &a, false, &raw);
    error_stats(rec, &a, true, &filt);
    print_stats("raw", &raw, a.frames);
    print_stats("filtered", &filt, a.frames);
    for (int i = 0; i < a.frames; i++) {
        if (!a.valid[i]) { printf("%3d -\n", i); continue; }
        printf("%3d tags %d pos %.1f rot %.2f  filt pos %.1f rot %.2f\n", i, a.tags_used[i],
               1e3 * mr_pose_dist(&a.pose[i], &rec->frames[i].gt), mr_pose_angle_deg(&a.pose[i], &rec->frames[i].gt),
               1e3 * mr_pose_dist(&a.filt[i], &rec->frames[i].gt), mr_pose_angle_deg(&a.filt[i], &rec->frames[i].gt));
    }
    /* The same frames give the same poses, bit for bit. */
    track_all(rec, fd, &b);
    bool same = true;
    for (int i = 0; i < a.frames; i++)
        same = same && a.valid[i] == b.valid[i] && (!a.valid[i] || memcmp(&a.pose[i], &b.pose[i], sizeof a.pose[i]) == 0);
    CHECK_MSG(same, "two runs over the same detections gave different poses");
    mr_recording_close(&rec);
    return mr_test_finish("test_track_recording");
}
