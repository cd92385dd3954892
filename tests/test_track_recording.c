/* Pose accuracy on the shipped synthetic recording (recordings/demo: the
 * demo hall rendered along a walking path, lens distortion, noise, motion
 * blur, exposure changes, JPEG), against its ground truth. Bounds are loose
 * enough for the single-tag frames (small tags at 3-7 m) and tight for the
 * multi-tag ones; see `mrcheck bench tracking` for the measured numbers. */
#include "mr_session.h"
#include "mr_test.h"

#include <stdlib.h>
#include <string.h>

static int cmp_d(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n) {
    if (n == 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

typedef struct run { int poses, multi; double te[512], tp[512], re[512], multi_tp[512]; mr_dmat4 pose[512]; bool valid[512]; } run;

static void track_all(mr_recording *rec, run *out) {
    memset(out, 0, sizeof *out);
    mr_error err = {0};
    mr_detector *det = mr_detector_create(NULL, &err);
    mr_pose prev = {0};
    for (int i = 0; i < rec->frame_count && i < 512; i++) {
        mr_image img;
        if (!mr_recording_load_image(rec, i, true, &img, &err)) continue;
        int n = 0;
        const mr_detection *d = mr_detector_detect(det, &img, &n, &err);
        mr_pose p;
        CHECK(d && mr_pose_solve(&rec->camera, &rec->markers, d, n, prev.valid ? &prev : NULL, NULL, &p, &err));
        mr_image_free(&img);
        out->valid[i] = p.valid;
        out->pose[i] = p.world_from_camera;
        if (!p.valid || !rec->frames[i].has_gt) continue;
        prev = p;
        const mr_dmat4 *gt = &rec->frames[i].gt;
        double dist = 0;
        for (int k = 0; k < p.tags_used; k++) {
            const mr_marker *m = mr_marker_map_find(&rec->markers, p.ids_used[k]);
            dist += mr_v3_len(mr_v3(gt->m[3] - m->world_from_tag.m[3], gt->m[7] - m->world_from_tag.m[7],
                                    gt->m[11] - m->world_from_tag.m[11])) / p.tags_used;
        }
        double e = mr_pose_dist(&p.world_from_camera, gt);
        out->te[out->poses] = e;
        out->tp[out->poses] = 100 * e / dist;
        out->re[out->poses] = mr_pose_angle_deg(&p.world_from_camera, gt);
        out->poses++;
        if (p.tags_used >= 2) out->multi_tp[out->multi++] = 100 * e / dist;
    }
    mr_detector_destroy(&det);
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
    double tp = median(a.tp, a.poses), re = median(a.re, a.poses), mp = median(a.multi_tp, a.multi);
    printf("%d frames, %d poses (%d multi-tag): median translation error %.2f%% of distance (multi-tag %.2f%%), "
           "rotation %.2f deg\n", rec->frame_count, a.poses, a.multi, tp, mp, re);
    CHECK(a.poses >= rec->frame_count / 2);
    CHECK(a.multi >= 10);
    CHECK(tp < 2.5);
    CHECK(re < 1.5);
    CHECK(mp < 1.0);
    /* The same frames give the same poses, bit for bit. */
    track_all(rec, &b);
    bool same = true;
    for (int i = 0; i < rec->frame_count && i < 512; i++)
        same = same && a.valid[i] == b.valid[i] && (!a.valid[i] || memcmp(&a.pose[i], &b.pose[i], sizeof a.pose[i]) == 0);
    CHECK(same);
    mr_recording_close(&rec);
    return mr_test_finish("test_track_recording");
}
