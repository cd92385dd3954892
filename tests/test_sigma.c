/* test_sigma.c — reported sigmas against the spread they predict, two-
 * sided: over many noisy draws the RMS of error / sigma lies in [0.6, 1.6]
 * (1 for a right sigma; a sigma too small or too large by sqrt(3) falls
 * out on one side). A one-sided coverage count ("within 2 sigma in >= 85 %
 * of draws") lets a sigma that is too large pass. */
#include "mr_scene.h"
#include "mr_test.h"
#include "mr_track.h"

/* A point tapped from 4 exact poses 3 m away over 60 degrees, each tap
 * with N(0, 1 px) noise per axis (the default tap sigma): the point's 3D
 * sigma (sqrt of the covariance's trace), and mr_triangulation_distance's
 * sigma along the line to a planned point 0.4 m off (the signed error
 * along it) and at the point itself (per axis: sqrt(trace / 3)). */
static void test_triangulated_sigma(void) {
    const mr_camera cam = mr_demo_camera();
    const mr_dvec3 truth = mr_v3(1.0, 0.9, -2.0);
    const mr_dvec3 planned = mr_v3(truth.x + 0.24, truth.y + 0.32, truth.z); /* 0.4 m off */
    mr_rng rng;
    mr_rng_seed(&rng, 7);
    enum { draws = 300 };
    double z3 = 0, zd = 0, z0 = 0;
    int n = 0;
    for (int d = 0; d < draws; d++) {
        mr_tap taps[4];
        int m = 0;
        for (int k = 0; k < 4; k++) {
            double a = (M_PI / 3) * (k - 1.5) / 3 + 0.3 * d / draws;
            mr_dvec3 eye = mr_v3(truth.x - 3 * cos(a), 1.6, truth.z - 3 * sin(a));
            mr_dmat4 wfc = mr_m4_look_at_cv(eye, truth, mr_v3(0, 1, 0));
            double u, v;
            if (!mr_project_point(&cam, &wfc, truth, &u, &v)) continue;
            taps[m++] = (mr_tap){.world_from_camera = wfc, .px = {u + mr_rng_normal(&rng), v + mr_rng_normal(&rng)}};
        }
        mr_triangulation t;
        mr_error err = {0};
        if (m < 4 || !mr_triangulate(&cam, taps, m, NULL, &t, &err)) {
            CHECK_MSG(false, "draw %d: %d taps: %s", d, m, err.msg);
            continue;
        }
        mr_dvec3 e = mr_v3_sub(t.point, truth);
        z3 += mr_v3_dot(e, e) / (t.sigma * t.sigma);
        double dist, sig;
        mr_triangulation_distance(&t, planned, &dist, &sig);
        double along = dist - mr_v3_len(mr_v3_sub(truth, planned));
        zd += along * along / (sig * sig);
        /* at the point itself: the distance is |e|, sigma per axis */
        mr_triangulation_distance(&t, t.point, &dist, &sig);
        CHECK(dist == 0);
        z0 += mr_v3_dot(e, e) / 3 / (sig * sig);
        n++;
    }
    z3 = sqrt(z3 / n), zd = sqrt(zd / n), z0 = sqrt(z0 / n);
    printf("triangulated point, %d draws: RMS of error/sigma %.3f (3D), %.3f (along a line), %.3f (per axis)\n", n, z3,
           zd, z0);
    CHECK_MSG(z3 >= 0.6 && z3 <= 1.6, "3D: RMS of error/sigma %.3f", z3);
    CHECK_MSG(zd >= 0.6 && zd <= 1.6, "along a line: RMS of error/sigma %.3f", zd);
    CHECK_MSG(z0 >= 0.6 && z0 <= 1.6, "per axis: RMS of error/sigma %.3f", z0);
}

int main(void) {
    test_triangulated_sigma();
    return mr_test_finish("test_sigma");
}
