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
