/* The pose solver over sequences (lib/track/pose.c): a lone tag seen
 * nearly head-on by a slowly moving camera, fed back its previous pose as
 * the tracker does, flips to the mirror solution no more often than today
 * and far less often than without it; the refined pose of several tags is
 * the reprojection minimum. Corners are projected with
 * the camera model (lens distortion included) plus fixed-seed Gaussian
 * noise, so the numbers are deterministic. */
#include "mr_track.h"
#include "mr_test.h"
#include "mr_test_track.h"

#include <stdlib.h>
#include <string.h>

/* The shipped recording's camera (recordings/demo/meta.json). */
static mr_camera demo_camera(void) {
    mr_camera c = {640, 480, 500, 500, 319.5, 239.5, {-0.1, 0.04, 0.0005, -0.0005, 0}};
    return c;
}

static void project_tag(const mr_camera *cam, const mr_marker_map *map, const mr_marker *m, const mr_dmat4 *wfc,
                        double sigma_px, mr_rng *rng, mr_detection *det) {
    mr_dvec3 w[4];
    mr_marker_corners_world(map, m, w);
    memset(det, 0, sizeof *det);
    det->id = m->id;
    det->decision_margin = 50;
    for (int k = 0; k < 4; k++) {
        CHECK(mr_project_point(cam, wfc, w[k], &det->corners[k][0], &det->corners[k][1]));
        det->corners[k][0] += sigma_px * mr_rng_normal(rng);
        det->corners[k][1] += sigma_px * mr_rng_normal(rng);
    }
}

/* One run of the tracker loop over a lone 0.3 m tag at distance d (+-0.3 m)
 * with corner noise sigma: the camera circles the tag's normal at a view
 * angle of 8-16 degrees (nearly head-on, where IPPE's two solutions fit
 * about equally well), 30 Hz for 20 s. A frame counts as a flip when its
 * rotation is nearer the mirror of the truth than the truth itself: the
 * two are 16-32 degrees apart here, so this is "off by more than half the
 * branch separation (>= 8 degrees)", and correct-branch noise seldom gets
 * there. The previous pose is fed back as the tracker does; `free` counts
 * the same frames solved without it. */
typedef struct flip_run { int frames, valid, ambiguous, flips, free_flips, first_flip; } flip_run;

static flip_run lone_tag_run(double dist, double sigma, uint64_t seed) {
    mr_marker tag = {.id = 7, .world_from_tag = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}}}; /* faces -z, y down */
    mr_marker_map map = {"tag36h11", 0.3, &tag, 1};
    mr_camera cam = demo_camera();
    mr_rng rng;
    mr_rng_seed(&rng, seed);
    flip_run r = {600, 0, 0, 0, 0, -1};
    mr_pose prev = {0};
    for (int k = 0; k < r.frames; k++) {
        double t = k / 30.0;
        double th = (12 + 4 * sin(0.6 * t)) * M_PI / 180, phi = 0.35 * t, d = dist + 0.3 * sin(0.5 * t);
        mr_dvec3 eye = mr_v3(d * sin(th) * cos(phi), d * sin(th) * sin(phi), -d * cos(th));
        /* aimed slightly off the tag centre, as a hand-held camera */
        mr_dmat4 truth = mr_m4_look_at_cv(eye, mr_v3(0.02 * sin(t), 0.015 * cos(1.3 * t), 0), mr_v3(0, -1, 0));
        mr_dmat4 mirror = mr_test_mirror_pose(&tag, &truth);
        mr_detection det;
        project_tag(&cam, &map, &tag, &truth, sigma, &rng, &det);
        mr_pose p, q;
        mr_error err = {0};
        CHECK(mr_pose_solve(&cam, &map, &det, 1, prev.valid ? &prev : NULL, NULL, &p, &err));
        CHECK(mr_pose_solve(&cam, &map, &det, 1, NULL, NULL, &q, &err));
        r.valid += p.valid;
        r.ambiguous += p.ambiguous;
        if (p.valid) {
            bool flip = mr_pose_angle_deg(&p.world_from_camera, &truth) > mr_pose_angle_deg(&p.world_from_camera, &mirror);
            r.flips += flip;
            if (flip && r.first_flip < 0) r.first_flip = k;
            prev = p;
        }
        if (q.valid)
            r.free_flips += mr_pose_angle_deg(&q.world_from_camera, &truth) > mr_pose_angle_deg(&q.world_from_camera, &mirror);
    }
    return r;
}

/* Measured today (seed 2024, 600 frames each):
 *   2.8 m (~54 px tag), 0.3 px: 12 flips with the previous pose, 26 without;
 *   3.5 m (~43 px tag), 0.3 px: 23 flips with the previous pose, 86 without.
 * The guard cannot reach 0 here (a mirror that fits > 2.5x better wins by
 * design, so a wrong start does not stick), so the bounds pin today's
 * counts with ~10% margin. Disabling the tie-break toward the previous pose
 * gives the counts without it (26 and 80); ambiguity_ratio 1.0 gives 15 and 44; 10 gives 33 and
 * 147 (a wrong branch then sticks). */
static void test_lone_tag_flips(void) {
    static const struct { double dist, sigma; int max_flips, min_free; } cases[] = {{2.8, 0.3, 13, 24}, {3.5, 0.3, 25, 72}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        flip_run r = lone_tag_run(cases[i].dist, cases[i].sigma, 2024);
        printf("lone tag at %.1f m, %.2f px noise, %d frames: %d valid, %d ambiguous; flips %d (%.1f%%) with the previous "
               "pose, %d (%.1f%%) without\n", cases[i].dist, cases[i].sigma, r.frames, r.valid, r.ambiguous, r.flips,
               100.0 * r.flips / r.frames, r.free_flips, 100.0 * r.free_flips / r.frames);
        CHECK_MSG(r.valid == r.frames, "lone tag at %.1f m: %d of %d frames without a pose", cases[i].dist,
                  r.frames - r.valid, r.frames);
        CHECK_MSG(r.free_flips >= cases[i].min_free && r.ambiguous >= r.frames / 4,
                  "lone tag at %.1f m: only %d flips without the previous pose, %d ambiguous frames: the case no longer "
                  "tests the flip guard", cases[i].dist, r.free_flips, r.ambiguous);
        CHECK_MSG(r.flips <= cases[i].max_flips,
                  "lone tag at %.1f m: %d of %d frames flipped to the mirror pose (first at frame %d; bound %d, %d "
                  "without the previous pose): the tie-break toward the previous pose (or the ambiguity margin) is "
                  "broken", cases[i].dist, r.flips, r.frames, r.first_flip, cases[i].max_flips, r.free_flips);
        CHECK_MSG(2 * r.flips <= r.free_flips, "lone tag at %.1f m: the previous pose removes too few flips (%d with, %d "
                  "without)", cases[i].dist, r.flips, r.free_flips);
    }
}

/* Sum of squared reprojection residuals of the corners in normalised,
 * undistorted coordinates: what the solver's Levenberg-Marquardt step
 * minimises (the demo camera has fx = fy, so pixels are a constant scale). */
static double reproj_cost(const mr_camera *cam, const mr_marker_map *map, const mr_detection *det, int n,
                          const mr_dmat4 *wfc) {
    mr_dmat4 cfw = mr_m4_invert_rigid(wfc);
    double s = 0;
    for (int i = 0; i < n; i++) {
        mr_dvec3 w[4];
        mr_marker_corners_world(map, mr_marker_map_find(map, det[i].id), w);
        for (int k = 0; k < 4; k++) {
            mr_dvec3 q = mr_m4_point(&cfw, w[k]);
            double x, y;
            CHECK(mr_camera_undistort(cam, (det[i].corners[k][0] - cam->cx) / cam->fx,
                                      (det[i].corners[k][1] - cam->cy) / cam->fy, &x, &y));
            s += (q.x / q.z - x) * (q.x / q.z - x) + (q.y / q.z - y) * (q.y / q.z - y);
        }
    }
    return s;
}

/* Four tags on two walls at 2-7 m, 0.5 px noise, 20 random views: the
 * returned pose must be a stationary point of the reprojection error. From
 * central differences along the six pose directions, the cost a Newton step
 * could still remove (sum g_i^2 / 2 H_i) is measured against the cost
 * itself. Refined poses leave < 1e-8 of it (measured max 2.3e-16); with the
 * LM refinement skipped, the best start (SQPnP or one tag's IPPE) leaves
 * 7e-5 .. 1.8e-2. */
static void test_multi_tag_refined(void) {
    mr_marker tags[4] = {
        {.id = 1, .world_from_tag = {{1, 0, 0, -1.0, 0, 1, 0, 0.3, 0, 0, 1, 0, 0, 0, 0, 1}}},
        {.id = 2, .world_from_tag = {{1, 0, 0, 1.2, 0, 1, 0, -0.2, 0, 0, 1, 0, 0, 0, 0, 1}}},
        {.id = 3, .world_from_tag = {{0, 0, 1, 2.5, 0, 1, 0, 0.1, -1, 0, 0, -1.2, 0, 0, 0, 1}}}, /* side wall, seen from -x */
        {.id = 4, .world_from_tag = {{0, 0, 1, 2.5, 0, 1, 0, -0.4, -1, 0, 0, -2.4, 0, 0, 0, 1}}},
    };
    mr_marker_map map = {"tag36h11", 0.3, tags, 4};
    mr_camera cam = demo_camera();
    mr_rng rng;
    mr_rng_seed(&rng, 77);
    double worst = 0;
    int views = 0;
    for (int v = 0; v < 20; v++) {
        mr_dvec3 eye = mr_v3(-1.5 + 1.5 * mr_rng_uniform(&rng), -0.5 + mr_rng_uniform(&rng), -7.0 + 2.0 * mr_rng_uniform(&rng));
        mr_dmat4 truth = mr_m4_look_at_cv(eye, mr_v3(0.9, 0, -0.8), mr_v3(0, -1, 0));
        mr_detection det[4];
        int n = 0;
        for (int i = 0; i < 4; i++) {
            project_tag(&cam, &map, &tags[i], &truth, 0.5, &rng, &det[n]);
            bool inside = true;
            for (int k = 0; k < 4; k++)
                inside = inside && det[n].corners[k][0] > 0 && det[n].corners[k][0] < cam.width - 1 &&
                         det[n].corners[k][1] > 0 && det[n].corners[k][1] < cam.height - 1;
            n += inside;
        }
        if (n < 3) continue;
        mr_pose p;
        mr_error err = {0};
        CHECK(mr_pose_solve(&cam, &map, det, n, NULL, NULL, &p, &err));
        CHECK_MSG(p.valid && p.tags_used == n, "view %d: valid %d, %d of %d tags used", v, p.valid, p.tags_used, n);
        if (!p.valid) continue;
        double c0 = reproj_cost(&cam, &map, det, n, &p.world_from_camera), gain = 0;
        const double eps = 1e-5;
        for (int a = 0; a < 6; a++) {
            double c[2];
            for (int sgn = 0; sgn < 2; sgn++) {
                mr_dmat4 m = p.world_from_camera;
                double e = sgn ? eps : -eps;
                if (a < 3) {
                    mr_dmat4 r = mr_m4_rotate_axis(mr_v3(a == 0, a == 1, a == 2), e);
                    m = mr_m4_mul(&p.world_from_camera, &r);
                } else {
                    m.m[(a - 3) * 4 + 3] += e;
                }
                c[sgn] = reproj_cost(&cam, &map, det, n, &m);
            }
            double g = (c[1] - c[0]) / (2 * eps), h = (c[1] + c[0] - 2 * c0) / (eps * eps);
            if (h > 0) gain += g * g / (2 * h);
        }
        worst = fmax(worst, gain / c0);
        views++;
        CHECK_MSG(gain <= 1e-8 * c0, "view %d (%d tags): the pose is not at the reprojection minimum; a Newton step "
                  "would still remove %.3g of the cost (LM refinement skipped or not converged?)", v, n, gain / c0);
    }
    printf("multi-tag: %d views; cost left to a Newton step at most %.3g of the cost\n", views, worst);
    CHECK_MSG(views >= 15, "multi-tag: only %d of 20 views see 3 or more tags", views);
}

int main(void) {
    test_lone_tag_flips();
    test_multi_tag_refined();
    return mr_test_finish("test_track_pose");
}
