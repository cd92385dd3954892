/* test_sigma.c — reported sigmas against the spread they predict, two-
 * sided: over many noisy draws the RMS of error / sigma lies in [0.6, 1.6]
 * (1 for a right sigma; a sigma too small or too large by sqrt(3) falls
 * out on one side). A one-sided coverage count ("within 2 sigma in >= 85 %
 * of draws") lets a sigma that is too large pass. */
#include "mr_bench.h"
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

/* RMS of error / sigma per component: sums of squares over draws. */
typedef struct zacc {
    double ss[8];
    int n;
} zacc;

static void z_add(zacc *a, int k, double e, double var) {
    if (var > 0 && isfinite(var)) a->ss[k] += e * e / var;
}

static void z_check(const zacc *a, int k, const char *what) {
    double z = sqrt(a->ss[k] / a->n);
    printf("  %-28s RMS of error/sigma %.3f (%d samples)\n", what, z, a->n);
    CHECK_MSG(z >= 0.6 && z <= 1.6, "%s: RMS of error/sigma %.3f", what, z);
}

/* The rotation vector (radians) of the 3x3 part of m. */
static mr_dvec3 rotvec_of(const mr_dmat4 *m) {
    double R[9], rv[3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) R[3 * i + j] = m->m[4 * i + j];
    mr_mat_to_rotvec(R, rv);
    return mr_v3(rv[0], rv[1], rv[2]);
}

static mr_dmat4 facing(mr_dvec3 c) { return mr_m4_look_at_cv(c, mr_v3_add(c, mr_v3(0, 0, 1)), mr_v3(0, 1, 0)); }

/* One frame's pose from 4 tags 2 m ahead, 0.5 px corner noise, 300 draws:
 * the pose covariance (a left perturbation in camera axes: rotation w,
 * then translation tau) against the error of each draw, per axis, as the
 * rotation's and the position's 3D sigma (sqrt of each block's trace), and
 * the registration sigma of a model point beyond the tags
 * (mr_pose_point_sigma: 3D and across the line of sight). */
static void test_pose_sigma(void) {
    const mr_camera cam = mr_demo_camera();
    mr_marker tags[4];
    for (int i = 0; i < 4; i++)
        tags[i] = (mr_marker){.id = i, .world_from_tag = facing(mr_v3(-0.6 + 0.4 * i, 0.2 * (i % 2), 2.0 + 0.3 * i))};
    mr_marker_map map = {.family = "tag36h11", .tag_size = 0.2, .tags = tags, .count = 4};
    const mr_dmat4 wfc = mr_m4_look_at_cv(mr_v3(0, 0.1, 0), mr_v3(0, 0.1, 3), mr_v3(0, 1, 0));
    const mr_dvec3 point = mr_v3(0.3, -0.2, 4.0);
    const mr_dmat4 cfw_true = mr_m4_invert_rigid(&wfc);
    const mr_dvec3 qt = mr_m4_point(&cfw_true, point);
    mr_rng rng;
    mr_rng_seed(&rng, 11);
    enum { draws = 300 };
    zacc a = {0};
    /* 0..5: w x y z, tau x y z; 6: rotation 3D; 7: position 3D */
    zacc pt = {0}; /* 0: point 3D, 1: point lateral */
    for (int d = 0; d < draws; d++) {
        mr_detection det[4];
        for (int i = 0; i < 4; i++) {
            mr_dvec3 c[4];
            mr_marker_corners_world(&map, &tags[i], c);
            det[i] = (mr_detection){.id = i};
            for (int k = 0; k < 4; k++) {
                double u, v;
                mr_project_point(&cam, &wfc, c[k], &u, &v);
                det[i].corners[k][0] = u + 0.5 * mr_rng_normal(&rng);
                det[i].corners[k][1] = v + 0.5 * mr_rng_normal(&rng);
            }
        }
        mr_pose pose;
        mr_error err = {0};
        if (!mr_pose_solve(&cam, &map, det, 4, NULL, NULL, &pose, &err) || !pose.valid) {
            CHECK_MSG(false, "draw %d: no pose: %s", d, err.msg);
            continue;
        }
        /* X_est = exp([w]x) X_true + tau in camera axes: delta = cfw_est * wfc_true */
        mr_dmat4 cfw = mr_m4_invert_rigid(&pose.world_from_camera), delta = mr_m4_mul(&cfw, &wfc);
        mr_dvec3 w = rotvec_of(&delta), tau = mr_v3(delta.m[3], delta.m[7], delta.m[11]);
        const double *C = pose.cov;
        double e[6] = {w.x, w.y, w.z, tau.x, tau.y, tau.z};
        for (int k = 0; k < 6; k++) z_add(&a, k, e[k], C[7 * k]);
        z_add(&a, 6, mr_v3_len(w), C[0] + C[7] + C[14]);
        z_add(&a, 7, mr_v3_len(tau), C[21] + C[28] + C[35]);
        a.n++;
        double s3, sl;
        if (!mr_pose_point_sigma(&pose, point, &s3, &sl)) {
            CHECK_MSG(false, "draw %d: no point sigma", d);
            continue;
        }
        mr_dvec3 q = mr_m4_point(&cfw, point), eq = mr_v3_sub(q, qt), dir = mr_v3_normalize(qt);
        double along = mr_v3_dot(eq, dir);
        z_add(&pt, 0, mr_v3_len(eq), s3 * s3);
        z_add(&pt, 1, sqrt(fmax(0, mr_v3_dot(eq, eq) - along * along)), sl * sl);
        pt.n++;
    }
    printf("single-frame pose, 4 tags, 0.5 px corners:\n");
    static const char *names[8] = {"rotation about camera x", "rotation about camera y", "rotation about camera z",
                                   "position along camera x", "position along camera y", "position along camera z",
                                   "rotation (3D)", "position (3D)"};
    for (int k = 0; k < 8; k++) z_check(&a, k, names[k]);
    z_check(&pt, 0, "model point 4 m away (3D)");
    z_check(&pt, 1, "model point, across the view");
}

/* The marker map's per-tag sigma (bundle adjustment with tag 0 fixed):
 * one ring of 8 tags seen in 60 photos (fixed), 60 draws of 0.5 px corner
 * noise, 7 mapped tags each (420 tag poses; MR_SIGMA_DRAWS sets more);
 * each tag's rotation (about world axes) and centre error against its
 * covariance per axis, against sigma_deg and sigma_pos (sqrt of each
 * block's trace) and sigma_xyz. A ring seen in fewer photos (14..40) is
 * not in the linear regime: now and then a tag's yaw converges 8..25
 * sigma off (its centre stays right), which no covariance predicts. */
static void test_map_sigma(void) {
    mr_synth_map_params sp = {MR_SYNTH_MAP_DEFAULTS};
    sp.tags = 8;
    sp.photos = 60;
    sp.tag_size = 0.3;
    sp.radius = 2.0;
    sp.width = 1280;
    sp.height = 960;
    sp.corner_noise_px = 0;
    sp.seed = 3;
    mr_synth_map s;
    mr_error err = {0};
    CHECK_MSG(mr_synth_map_make(&sp, &s, &err), "%s", err.msg);
    mr_map_photo ph[64];
    mr_detection *noisy[64];
    for (int j = 0; j < s.photo_count; j++) noisy[j] = malloc((size_t)(s.counts[j] + 1) * sizeof *noisy[j]);
    mr_rng rng;
    mr_rng_seed(&rng, 13);
    const int draws = getenv("MR_SIGMA_DRAWS") ? atoi(getenv("MR_SIGMA_DRAWS")) : 60;
    zacc a = {0}, pos = {0};
    double deg = 180.0 / M_PI;
    for (int d = 0; d < draws; d++) {
        for (int j = 0; j < s.photo_count; j++) {
            for (int i = 0; i < s.counts[j]; i++) {
                noisy[j][i] = s.dets[j][i];
                for (int k = 0; k < 4; k++) {
                    noisy[j][i].corners[k][0] += 0.5 * mr_rng_normal(&rng);
                    noisy[j][i].corners[k][1] += 0.5 * mr_rng_normal(&rng);
                }
            }
            ph[j] = (mr_map_photo){noisy[j], s.counts[j], NULL};
        }
        mr_map_params mp = MR_MAP_DEFAULTS;
        mp.tag_size = sp.tag_size;
        mp.fix_id = 0;
        mp.fix_pose = &s.truth.tags[0].world_from_tag;
        mr_map_result r;
        if (!mr_map_build(&s.camera, ph, s.photo_count, &mp, &r, &err)) {
            CHECK_MSG(false, "draw %d: %s", d, err.msg);
            continue;
        }
        CHECK_MSG(r.tag_count == sp.tags, "draw %d: %d tags mapped", d, r.tag_count);
        for (int i = 0; i < r.tag_count; i++) {
            const mr_map_tag *t = &r.tags[i];
            const mr_marker *m = mr_marker_map_find(&s.truth, t->id);
            if (!m || t->id == 0) continue;
            /* R_est = exp([w]x) R_true: about world axes */
            mr_dmat4 inv = mr_m4_invert_rigid(&m->world_from_tag), dr = mr_m4_mul(&t->world_from_tag, &inv);
            mr_dvec3 w = rotvec_of(&dr);
            mr_dvec3 e = mr_v3(t->world_from_tag.m[3] - m->world_from_tag.m[3],
                               t->world_from_tag.m[7] - m->world_from_tag.m[7],
                               t->world_from_tag.m[11] - m->world_from_tag.m[11]);
            const double *C = t->cov;
            double ev[6] = {w.x, w.y, w.z, e.x, e.y, e.z};
            for (int k = 0; k < 6; k++) z_add(&a, k, ev[k], C[7 * k]);
            z_add(&a, 6, mr_v3_len(w) * deg, t->sigma_deg * t->sigma_deg);
            z_add(&a, 7, mr_v3_len(e), t->sigma_pos * t->sigma_pos);
            double exyz[3] = {e.x, e.y, e.z};
            for (int k = 0; k < 3; k++) z_add(&pos, k, exyz[k], t->sigma_xyz[k] * t->sigma_xyz[k]);
            a.n++;
            pos.n++;
        }
        mr_map_result_free(&r);
    }
    printf("marker map, %d tags, %d photos, 0.5 px corners, %d draws:\n", sp.tags, s.photo_count, draws);
    static const char *names[8] = {"rotation about world x", "rotation about world y", "rotation about world z",
                                   "centre along world x", "centre along world y", "centre along world z",
                                   "sigma_deg", "sigma_pos"};
    for (int k = 0; k < 8; k++) z_check(&a, k, names[k]);
    z_check(&pos, 0, "sigma_xyz[0]");
    z_check(&pos, 1, "sigma_xyz[1]");
    z_check(&pos, 2, "sigma_xyz[2]");
    for (int j = 0; j < s.photo_count; j++) free(noisy[j]);
    mr_synth_map_free(&s);
}

int main(void) {
    test_triangulated_sigma();
    test_pose_sigma();
    test_map_sigma();
    return mr_test_finish("test_sigma");
}
