/* Ambient occlusion: sample kernels and outline directions (CPU), the
 * Embree ground truth against the closed form beside a wall (CPU), and
 * through EGL: scheer on a flat plane and in a concave corner, every method
 * darker in the corner, the pixel path of the ground truth against the
 * closed form, scale invariance (1e-3 .. 1e4 and a 1e7 offset), finite
 * output on extreme inputs (c in [0,1e7], depth near 0, sky, zero normals),
 * the pass list (no AO pass when off, reuse while the camera is frozen,
 * half resolution, corner masking); every method (and the paper-pure
 * scheer) pinned against the Embree reference on a plane, the corner and
 * two demo-hall views, and against stored goldens (tests/data/golden/ao_*,
 * MR_TEST_DATA must point at tests/data); the corner mask against the
 * unmasked frame and the analytic outline count; the stand-alone mask's own
 * strength; 5 radii. GPU parts skip only where there is no EGL device. */
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"
#include "mr_test_ao.h"

#include <stdlib.h>
#include <string.h>

/* --------------------------------------------------------- scene helpers */

/* The corner, its view and the AO measures are mr_test_ao.h's. */

/* ------------------------------------------------------------ CPU tests */

static void test_kernels(void) {
    for (int kind = 0; kind < 4; kind++) {
        for (int n = 8; n <= 64; n *= 2) {
            float k3[64 * 3], k2[64 * 2];
            mr_ao_kernel_generate((mr_ao_kernel)kind, n, 0.8f, 1.0f, 42, k3, k2);
            int bad = 0;
            double mind = 1e9;
            int strata[64] = {0};
            for (int i = 0; i < n; i++) {
                double r = sqrt(k3[3 * i] * k3[3 * i] + k3[3 * i + 1] * k3[3 * i + 1] + k3[3 * i + 2] * k3[3 * i + 2]);
                double r2 = sqrt(k2[2 * i] * k2[2 * i] + k2[2 * i + 1] * k2[2 * i + 1]);
                if (!(r >= 0.8 - 1e-5 && r <= 1.0 + 1e-5) || !(r2 <= 1 + 1e-5)) bad++;
                double u3 = (r * r * r - 0.512) / (1 - 0.512);
                int st = (int)(u3 * n);
                if (st >= 0 && st < n) strata[st]++;
                for (int j = 0; j < i; j++) {
                    double dx = k3[3 * i] - k3[3 * j], dy = k3[3 * i + 1] - k3[3 * j + 1], dz = k3[3 * i + 2] - k3[3 * j + 2];
                    double d = sqrt(dx * dx + dy * dy + dz * dz);
                    if (d < mind) mind = d;
                }
            }
            CHECK_MSG(bad == 0, "kernel %s n=%d: %d samples outside the shell", mr_ao_kernel_name((mr_ao_kernel)kind), n, bad);
            if (kind == MR_AO_KERNEL_LATIN || kind == MR_AO_KERNEL_STRATIFIED) {
                /* One sample per radius stratum: the Latin property. */
                int empty = 0;
                for (int i = 0; i < n; i++) empty += strata[i] != 1;
                CHECK_MSG(empty == 0, "kernel %s n=%d: radius strata not filled once each", mr_ao_kernel_name((mr_ao_kernel)kind), n);
            }
            if (kind == MR_AO_KERNEL_POISSON) {
                /* Dart throwing keeps points apart: far more than random
                 * points of the same count would be. */
                double expect = 0.85 * 0.5 * cbrt(4.0 / 3.0 * 3.14159 * (1 - 0.512) / n);
                CHECK_MSG(mind > expect, "poisson n=%d: min distance %g <= %g", n, mind, expect);
            }
        }
    }
    float a[48], b[48];
    mr_ao_kernel_generate(MR_AO_KERNEL_LATIN, 16, 0.5f, 1.0f, 7, a, NULL);
    mr_ao_kernel_generate(MR_AO_KERNEL_LATIN, 16, 0.5f, 1.0f, 7, b, NULL);
    CHECK(memcmp(a, b, sizeof a) == 0); /* deterministic */
    mr_ao_method m;
    CHECK(mr_ao_method_parse("scheer", &m) && m == MR_AO_SCHEER);
    CHECK(!mr_ao_method_parse("ssao", &m));
}

/* A closed cylinder (radius rad, height h, n segments round the y axis):
 * split vertices along the side seams and the rims, fans for the caps. */
static mr_mesh outline_cylinder(double rad, double h, int n) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "cylinder");
    m.vertex_count = (uint32_t)(4 * n + 2 * (n + 1));
    m.index_count = (uint32_t)(6 * n + 6 * n);
    m.positions = malloc(m.vertex_count * 3 * sizeof(float));
    m.indices = malloc(m.index_count * sizeof(uint32_t));
    uint32_t v = 0, t = 0;
    for (int i = 0; i < n; i++) { /* side quads, 4 vertices each */
        double a0 = 2 * M_PI * i / n, a1 = 2 * M_PI * ((i + 1) % n) / n;
        const double q[4][3] = {{rad * cos(a0), -h / 2, rad * sin(a0)}, {rad * cos(a1), -h / 2, rad * sin(a1)},
                                {rad * cos(a1), h / 2, rad * sin(a1)}, {rad * cos(a0), h / 2, rad * sin(a0)}};
        for (int k = 0; k < 4; k++)
            for (int c = 0; c < 3; c++) m.positions[3 * (v + k) + c] = (float)q[k][c];
        const uint32_t tri[6] = {0, 2, 1, 0, 3, 2};
        for (int k = 0; k < 6; k++) m.indices[t++] = v + tri[k];
        v += 4;
    }
    for (int cap = 0; cap < 2; cap++) { /* centre + rim, its own copies */
        double y = cap ? h / 2 : -h / 2;
        uint32_t c0 = v;
        m.positions[3 * v] = 0, m.positions[3 * v + 1] = (float)y, m.positions[3 * v + 2] = 0;
        v++;
        for (int i = 0; i < n; i++, v++) {
            double a = 2 * M_PI * i / n;
            m.positions[3 * v] = (float)(rad * cos(a)), m.positions[3 * v + 1] = (float)y,
                        m.positions[3 * v + 2] = (float)(rad * sin(a));
        }
        for (int i = 0; i < n; i++) {
            m.indices[t++] = c0;
            m.indices[t++] = c0 + 1 + (uint32_t)(cap ? (i + 1) % n : i);
            m.indices[t++] = c0 + 1 + (uint32_t)(cap ? i : (i + 1) % n);
        }
    }
    return m;
}

/* An open sheet: a gx x gy grid of quads in the z = 0 plane, w x h, one-sided. */
static mr_mesh outline_sheet(double w, double h, int gx, int gy) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "sheet");
    m.vertex_count = (uint32_t)((gx + 1) * (gy + 1));
    m.index_count = (uint32_t)(6 * gx * gy);
    m.positions = malloc(m.vertex_count * 3 * sizeof(float));
    m.indices = malloc(m.index_count * sizeof(uint32_t));
    for (int y = 0; y <= gy; y++)
        for (int x = 0; x <= gx; x++) {
            size_t k = (size_t)y * (gx + 1) + x;
            m.positions[3 * k] = (float)(w * ((double)x / gx - 0.5));
            m.positions[3 * k + 1] = (float)(h * ((double)y / gy - 0.5));
            m.positions[3 * k + 2] = 0;
        }
    uint32_t t = 0;
    for (int y = 0; y < gy; y++)
        for (int x = 0; x < gx; x++) {
            uint32_t a = (uint32_t)(y * (gx + 1) + x), b = a + 1, c = a + (uint32_t)gx + 1, d = c + 1;
            const uint32_t tri[6] = {a, b, d, a, d, c};
            for (int k = 0; k < 6; k++) m.indices[t++] = tri[k];
        }
    return m;
}

/* Ray (o, dir) against triangle (a, b, c): hit at t > 0 (Moller-Trumbore). */
static bool ray_hits(const double o[3], const double d[3], const double a[3], const double b[3], const double c[3]) {
    double e1[3], e2[3], pv[3], tv[3], qv[3];
    for (int k = 0; k < 3; k++) e1[k] = b[k] - a[k], e2[k] = c[k] - a[k], tv[k] = o[k] - a[k];
    pv[0] = d[1] * e2[2] - d[2] * e2[1], pv[1] = d[2] * e2[0] - d[0] * e2[2], pv[2] = d[0] * e2[1] - d[1] * e2[0];
    double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
    if (fabs(det) < 1e-14) return false;
    double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
    if (u < 0 || u > 1) return false;
    qv[0] = tv[1] * e1[2] - tv[2] * e1[1], qv[1] = tv[2] * e1[0] - tv[0] * e1[2], qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
    double vv = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
    if (vv < 0 || u + vv > 1) return false;
    return (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det > 0;
}

/* Whether p is inside the outline volume at radius r: crossings of three
 * random rays, odd for the majority. `unit` normalises the offsets first:
 * the paper's integrated normal taken as the extrusion, the r/sqrt 3 bug. */
static bool outline_contains(const mr_outline *o, double r, bool unit, const double p[3], unsigned *seed) {
    int inside = 0;
    for (int ray = 0; ray < 3; ray++) {
        double d[3];
        for (int k = 0; k < 3; k++) d[k] = 2.0 * rand_r(seed) / RAND_MAX - 1.0 + (k == ray ? 0.1 : 0);
        int hits = 0;
        for (uint32_t t = 0; t + 2 < o->index_count; t += 3) {
            double v[3][3];
            for (int c = 0; c < 3; c++) {
                const float *dir = o->dirs + 3 * (size_t)o->indices[t + c];
                double l = unit ? sqrt((double)dir[0] * dir[0] + (double)dir[1] * dir[1] + (double)dir[2] * dir[2]) : 1.0;
                for (int k = 0; k < 3; k++) v[c][k] = o->positions[3 * (size_t)o->indices[t + c] + k] + r * dir[k] / (l > 0 ? l : 1);
            }
            hits += ray_hits(p, d, v[0], v[1], v[2]);
        }
        inside += hits & 1;
    }
    return inside >= 2;
}

/* Points within r of mesh m's surface (a random point of a random triangle
 * plus a random offset in the ball of 0.995 r; a third of them pushed out to
 * 0.995 r exactly, where a short extrusion shows) that the outline volume
 * does not hold. */
static int outline_misses(const mr_mesh *m, const mr_outline *o, double r, bool unit, int samples, double worst[3]) {
    unsigned seed = 12345;
    int miss = 0;
    for (int i = 0; i < samples; i++) {
        uint32_t t = (uint32_t)(rand_r(&seed) % (m->index_count / 3)) * 3;
        double u = (double)rand_r(&seed) / RAND_MAX, w = (double)rand_r(&seed) / RAND_MAX;
        if (u + w > 1) u = 1 - u, w = 1 - w;
        double e[3], l2;
        do {
            for (int k = 0; k < 3; k++) e[k] = 2.0 * rand_r(&seed) / RAND_MAX - 1.0;
            l2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        } while (l2 > 1 || l2 < 1e-6);
        double scale = (i % 3 == 0 ? 1.0 / sqrt(l2) : 1.0) * 0.995 * r;
        double p[3];
        for (int k = 0; k < 3; k++) {
            const float *a = m->positions + 3 * (size_t)m->indices[t], *b = m->positions + 3 * (size_t)m->indices[t + 1],
                        *c = m->positions + 3 * (size_t)m->indices[t + 2];
            p[k] = a[k] + u * (b[k] - a[k]) + w * (c[k] - a[k]) + scale * e[k];
        }
        if (!outline_contains(o, r, unit, p, &seed)) {
            if (!miss && worst) memcpy(worst, p, sizeof p);
            miss++;
        }
    }
    return miss;
}

/* Park & Baek's outline must hold every point the AO radius reaches from the
 * surface: a box (edges and corners), a faceted cylinder (uneven corners at
 * the rims) and an open sheet (both sides and past the rim). The paper's
 * unit integrated normal (r/sqrt 3 at a box corner) must fail the same check. */
static void test_outline_volume(void) {
    mr_scene *s = mr_scene_create();
    int32_t b = mr_test_add_box(s, 2, 1, 4, -1);
    mr_mesh cyl = outline_cylinder(0.7, 2.0, 24), sheet = outline_sheet(3.0, 2.0, 3, 2);
    const mr_mesh *meshes[3] = {&s->meshes[b], &cyl, &sheet};
    const char *names[3] = {"box", "cylinder", "open sheet"};
    for (int i = 0; i < 3; i++) {
        mr_outline o;
        mr_error err = {0};
        CHECK_MSG(mr_mesh_outline(meshes[i], &o, &err), "%s: %s", names[i], err.msg);
        CHECK_MSG(o.open == (i == 2), "%s: open %d", names[i], o.open);
        for (int ri = 0; ri < 2; ri++) {
            double r = ri ? 0.6 : 0.25, at[3] = {0, 0, 0};
            int miss = outline_misses(meshes[i], &o, r, false, 1500, at);
            CHECK_MSG(miss == 0, "%s, r %.2f: %d of 1500 points within r of the surface outside the outline (first at %.3f %.3f %.3f)",
                      names[i], r, miss, at[0], at[1], at[2]);
            if (i != 1) {
                /* The planted r/sqrt 3 extrusion must be caught (the cylinder's
                 * rims are its only corners, too few samples land there). */
                int planted = outline_misses(meshes[i], &o, r, true, 1500, NULL);
                CHECK_MSG(planted > 20, "%s, r %.2f: the unit-normal extrusion misses only %d points: the check is blind", names[i],
                          r, planted);
            }
        }
        if (i == 0) {
            /* A box corner moves by r along (+-1, +-1, +-1): each face by r. */
            int bad = 0;
            for (uint32_t v = 0; v < o.vertex_count; v++)
                for (int k = 0; k < 3; k++) bad += fabs(fabs(o.dirs[3 * v + k]) - 1.0) > 1e-5;
            CHECK_MSG(bad == 0, "box: %d outline offset components are not +-1", bad);
        }
        mr_outline_free(&o);
    }
    free(cyl.positions), free(cyl.indices), free(sheet.positions), free(sheet.indices);
    mr_scene_destroy(&s);
}

/* Floor y = 0 (normal up) and a wall face x = 0 standing on it; a point on
 * the floor at distance d from the wall, rays of length R. */
static void test_groundtruth_wall(void) {
    for (int far = 0; far < 2; far++) {
        double off = far ? 1e7 : 0;
        mr_scene *s = mr_scene_create();
        mr_test_ao_place(s, mr_test_add_box(s, 400, 1, 400, -1), 1, mr_v3(off, -0.5, off), 0, 0, 0);
        mr_test_ao_place(s, mr_test_add_box(s, 1, 400, 400, -1), 1, mr_v3(off + 0.5, 0, off), 0, 0, 0);
        mr_scene_update_bounds(s);
        mr_error err = {0};
        mr_eval_gt *gt = mr_eval_gt_create(s, false, &err);
        CHECK_MSG(gt != NULL, "%s", err.msg);
        if (gt) {
            const double as[] = {0.01, 0.1, 0.3, 0.5, 0.8, 0.99, 1.3};
            for (size_t i = 0; i < sizeof as / sizeof as[0]; i++) {
                double R = 1.0, d = as[i] * R;
                double v = mr_eval_ao_point(gt, mr_v3(off - d, 1e-5, off), mr_v3(0, 1, 0), R, 16384, 3 + i);
                double want = mr_eval_ao_wall_analytic(d, R);
                /* 16384 stratified rays: the error is well below 0.01. */
                CHECK_MSG(fabs(v - want) < 0.01, "offset %g a=%g: traced %.4f, analytic %.4f", off, as[i], v, want);
            }
            /* Same with R = 40 (scale does not matter to the closed form). */
            double v = mr_eval_ao_point(gt, mr_v3(off - 20, 1e-4, off), mr_v3(0, 1, 0), 40, 16384, 9);
            CHECK_NEAR(v, mr_eval_ao_wall_analytic(20, 40), 0.01);
        }
        mr_eval_gt_destroy(&gt);
        mr_scene_destroy(&s);
    }
    CHECK_NEAR(mr_eval_ao_wall_analytic(0, 1), 0.5, 1e-12); /* a point at the wall sees half the sky */
    CHECK_NEAR(mr_eval_ao_wall_analytic(2, 1), 1.0, 1e-12);
}

static void test_metrics(void) {
    mr_image a = {0}, b = {0};
    mr_image_alloc(&a, 32, 24, 1, MR_PIX_F32, NULL);
    mr_image_alloc(&b, 32, 24, 1, MR_PIX_F32, NULL);
    float *pa = a.data, *pb = b.data;
    for (int i = 0; i < 32 * 24; i++) {
        pb[i] = (float)((i % 32) / 31.0);
        pa[i] = pb[i] + 0.1f;
    }
    mr_image_metrics m;
    CHECK(mr_image_compare(&a, &b, NULL, &m, NULL));
    CHECK_NEAR(m.rmse, 0.1, 1e-6);
    CHECK_NEAR(m.bias, 0.1, 1e-6);
    CHECK(m.ssim < 1.0 && m.ssim > 0.5);
    CHECK(mr_image_compare(&b, &b, NULL, &m, NULL));
    CHECK_NEAR(m.ssim, 1.0, 1e-9);
    CHECK_NEAR(m.rmse, 0.0, 1e-12);
    pa[5] = NAN;
    CHECK(mr_image_compare(&a, &b, NULL, &m, NULL));
    CHECK_NEAR(m.max_abs, 1.0, 1e-12); /* NaN counts as the worst error */
    mr_image_free(&a);
    mr_image_free(&b);
}

/* ------------------------------------------------------------ GPU tests */

static mr_gpu *g_gpu;
static mr_renderer *g_r;

static void test_flat_plane(void) {
    mr_scene *s = mr_test_ao_corner_scene(1, mr_v3(0, 0, 0), false);
    mr_view v = mr_test_ao_corner_view(1, mr_v3(0, 0, 0), 128, 96);
    for (int mode = 0; mode < 2; mode++) {
        mr_ao_params ao = MR_AO_DEFAULTS;
        ao.method = MR_AO_SCHEER;
        ao.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
        ao.radius = 0.5;
        mr_frame_result res;
        if (!mr_test_render_ao(g_r, s, &v, &ao, &res)) continue;
        const float *a = res.ao.data, *d = res.depth.data;
        double sum = 0;
        int n = 0;
        for (int i = 0; i < 128 * 96; i++)
            if (d[i] > 0) { sum += a[i]; n++; }
        CHECK(n > 1000);
        CHECK_MSG(n && sum / n >= 0.98, "flat plane, %s radius: mean AO %.4f < 0.98", mode ? "view" : "screen", n ? sum / n : 0);
        CHECK(mr_test_ao_count_bad(&res.ao) == 0);
        mr_frame_result_free(&res);
    }
    mr_scene_destroy(&s);
}

/* Mean AO over floor pixels at distance [d0, d1) in front of the wall. */
static double floor_band(const mr_view *v, const mr_frame_result *res, const mr_image *ao, double d0, double d1, double k,
                         mr_dvec3 off, int *count) {
    double sum = 0;
    int n = 0;
    const float *d = res->depth.data, *a = ao->data;
    for (int y = 0; y < res->depth.height; y++)
        for (int x = 0; x < res->depth.width; x++) {
            size_t i = (size_t)y * res->depth.width + x;
            if (!(d[i] > 0)) continue;
            mr_dvec3 p = mr_test_pixel_world(v, &res->depth, x, y);
            double py = (p.y - off.y) / k, dist = 2.9 - (p.z - off.z) / k, px = (p.x - off.x) / k;
            if (fabs(py) > 0.01 || dist < d0 || dist >= d1 || px < -0.5 || px > 5) continue;
            sum += a[i];
            n++;
        }
    if (count) *count = n;
    return n ? sum / n : NAN;
}

static void test_corner_all_methods(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 128, 96);
    for (int m = MR_AO_SCHEER; m < MR_AO_METHOD_COUNT; m++) {
        for (int mode = 0; mode < 2; mode++) {
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = (mr_ao_method)m;
            ao.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
            ao.radius = 0.5;
            mr_frame_result res;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &res)) continue;
            int nc = 0, no = 0;
            double corner = floor_band(&v, &res, &res.ao, 0.0, 0.12, 1, o, &nc);
            double open = floor_band(&v, &res, &res.ao, 1.5, 2.5, 1, o, &no);
            CHECK_MSG(nc > 5 && no > 20, "%s: too few pixels (%d corner, %d open)", mr_ao_method_name(ao.method), nc, no);
            /* scheer must show the corner clearly; the baselines at least darker. */
            double margin = m == MR_AO_SCHEER ? 0.1 : 0.02;
            if (getenv("MR_TEST_VERBOSE"))
                printf("%s %s: corner %.3f open %.3f\n", mr_ao_method_name(ao.method), mode ? "view" : "screen", corner, open);
            CHECK_MSG(corner < open - margin, "%s %s: corner %.3f not darker than open floor %.3f", mr_ao_method_name(ao.method),
                      mode ? "view" : "screen", corner, open);
            CHECK(mr_test_ao_count_bad(&res.ao) == 0);
            mr_frame_result_free(&res);
        }
    }
    mr_scene_destroy(&s);
}

/* The ground truth through the renderer's depth and normals, against the
 * closed form for floor pixels in front of the wall (away from its ends). */
static void test_groundtruth_pixels(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
    mr_ao_params none = MR_AO_DEFAULTS;
    mr_frame_result res;
    if (mr_test_render_ao(g_r, s, &v, &none, &res)) {
        mr_error err = {0};
        mr_eval_gt *gt = mr_eval_gt_create(s, false, &err);
        mr_gt_params gp = MR_GT_DEFAULTS;
        gp.radius = 0.6;
        gp.rays = 1024;
        mr_image ao = {0};
        CHECK_MSG(gt && mr_eval_ao_groundtruth(gt, &v, &res.depth, &res.normal, &gp, &ao, &err), "%s", err.msg);
        if (ao.data) {
            CHECK(mr_test_ao_count_bad(&ao) == 0);
            double se = 0;
            int n = 0;
            const float *a = ao.data, *d = res.depth.data;
            for (int y = 0; y < 72; y++)
                for (int x = 0; x < 96; x++) {
                    size_t i = (size_t)y * 96 + x;
                    if (!(d[i] > 0)) continue;
                    mr_dvec3 p = mr_test_pixel_world(&v, &res.depth, x, y);
                    double dist = 2.9 - p.z;
                    /* Floor, in front of the wall, away from the cube (x < -0.9). */
                    if (fabs(p.y) > 0.01 || dist < 0 || dist > 1.0 || p.x < -0.5 || p.x > 5) continue;
                    double e = a[i] - mr_eval_ao_wall_analytic(dist, gp.radius);
                    se += e * e;
                    n++;
                }
            CHECK_MSG(n > 30, "only %d floor pixels in front of the wall", n);
            CHECK_MSG(n && sqrt(se / n) < 0.03, "pixel ground truth vs closed form: RMSE %.4f over %d pixels",
                      n ? sqrt(se / n) : 0, n);
            int nc = 0, no = 0;
            double corner = floor_band(&v, &res, &ao, 0, 0.12, 1, o, &nc), open = floor_band(&v, &res, &ao, 1.5, 2.5, 1, o, &no);
            CHECK(corner < 0.7 && open > 0.97);
        }
        /* Screen mode: R = F z height / fy per pixel, the same closed form. */
        mr_image aos = {0};
        gp.radius_mode = MR_AO_RADIUS_SCREEN;
        gp.screen_radius = 0.1;
        CHECK_MSG(gt && mr_eval_ao_groundtruth(gt, &v, &res.depth, &res.normal, &gp, &aos, &err), "%s", err.msg);
        if (aos.data) {
            mr_camera c = mr_camera_resized(&v.camera, 96, 72);
            double se = 0;
            int n = 0;
            const float *a = aos.data, *d = res.depth.data;
            for (int y = 0; y < 72; y++)
                for (int x = 0; x < 96; x++) {
                    size_t i = (size_t)y * 96 + x;
                    if (!(d[i] > 0)) continue;
                    mr_dvec3 p = mr_test_pixel_world(&v, &res.depth, x, y);
                    double dist = 2.9 - p.z, R = gp.screen_radius * d[i] * c.height / c.fy;
                    if (fabs(p.y) > 0.01 || dist < 0 || dist > 1.0 || p.x < -0.5 || p.x > 5) continue;
                    double e = a[i] - mr_eval_ao_wall_analytic(dist, R);
                    se += e * e;
                    n++;
                }
            CHECK_MSG(n > 30 && sqrt(se / n) < 0.03, "screen-mode ground truth vs closed form: RMSE %.4f over %d pixels",
                      n ? sqrt(se / n) : 0, n);
        }
        /* scheer is closer to the reference of its radius mode than no AO. */
        for (int mode = 0; mode < 2 && ao.data && aos.data; mode++) {
            mr_ao_params sp = MR_AO_DEFAULTS;
            sp.method = MR_AO_SCHEER;
            sp.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
            sp.radius = 0.6;
            sp.screen_radius = 0.1;
            mr_frame_result rs;
            if (!mr_test_render_ao(g_r, s, &v, &sp, &rs)) continue;
            mr_image ones = {0};
            mr_image_alloc(&ones, 96, 72, 1, MR_PIX_F32, NULL);
            for (int i = 0; i < 96 * 72; i++) ((float *)ones.data)[i] = 1.0f;
            mr_image_metrics ms, m1;
            const mr_image *ref = mode ? &ao : &aos;
            CHECK(mr_image_compare(&rs.ao, ref, &res.depth, &ms, NULL) && mr_image_compare(&ones, ref, &res.depth, &m1, NULL));
            CHECK_MSG(ms.rmse < 0.8 * m1.rmse && ms.ssim > m1.ssim, "scheer %s: RMSE %.4f SSIM %.3f vs no AO %.4f %.3f",
                      mode ? "view" : "screen", ms.rmse, ms.ssim, m1.rmse, m1.ssim);
            mr_image_free(&ones);
            mr_frame_result_free(&rs);
        }
        mr_image_free(&aos);
        mr_image_free(&ao);
        mr_eval_gt_destroy(&gt);
        mr_frame_result_free(&res);
    }
    mr_scene_destroy(&s);
}

static double rmse(const mr_image *a, const mr_image *b);

/* Half resolution with the joint bilateral upsample stays close to full
 * resolution, and does not smear AO across the cube's silhouette. */
static void test_half_res(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 128, 96);
    mr_ao_params ao = MR_AO_DEFAULTS;
    ao.method = MR_AO_SCHEER;
    mr_frame_result full, half;
    if (mr_test_render_ao(g_r, s, &v, &ao, &full)) {
        ao.half_res = true;
        if (mr_test_render_ao(g_r, s, &v, &ao, &half)) {
            double e = rmse(&half.ao, &full.ao);
            if (getenv("MR_TEST_VERBOSE")) printf("half vs full resolution: RMSE %.4f\n", e);
            CHECK_MSG(e < 0.05, "half vs full resolution: RMSE %.4f", e);
            /* Sky stays 1 next to geometry (no bleeding from the upsample). */
            const float *d = full.depth.data, *a = half.ao.data;
            int bad = 0;
            for (int i = 0; i < 128 * 96; i++) bad += d[i] == 0 && a[i] != 1.0f;
            CHECK(bad == 0);
            mr_frame_result_free(&half);
        }
        mr_frame_result_free(&full);
    }
    mr_scene_destroy(&s);
}

static double rmse(const mr_image *a, const mr_image *b) {
    mr_image_metrics m;
    if (!mr_image_compare(a, b, NULL, &m, NULL)) return 1e9;
    return m.rmse;
}

static void test_scale_invariance(void) {
    const double scales[] = {1, 1e-3, 1e4, 1};
    const mr_dvec3 offs[] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {1e7, 0, -1e7}};
    /* Every depth-scaled method: scheer, and (issue 18) the slice integrators. */
    /* issue 18 (lane ao): scheer-bm, and the slice methods with the depth mip chain */
    const mr_ao_method methods[] = {MR_AO_SCHEER, MR_AO_GTAO, MR_AO_BITMASK, MR_AO_SCHEER_GT, MR_AO_SCHEER_BM};
    for (size_t mi = 0; mi < sizeof methods / sizeof methods[0]; mi++)
    for (int mips = 0; mips < (methods[mi] == MR_AO_SCHEER ? 1 : 2); mips++)
    for (int half = 0; half < 2; half++) {
        mr_image ref = {0};
        for (int i = 0; i < 4; i++) {
            mr_scene *s = mr_test_ao_corner_scene(scales[i], offs[i], true);
            mr_view v = mr_test_ao_corner_view(scales[i], offs[i], 128, 96);
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = methods[mi];
            ao.half_res = half;
            ao.mips = mips;
            ao.screen_radius = mips ? 0.15 : ao.screen_radius; /* 19 px at 128x96: levels 1 and 2 are read */
            mr_frame_result res;
            if (mr_test_render_ao(g_r, s, &v, &ao, &res)) {
                CHECK(mr_test_ao_count_bad(&res.ao) == 0);
                if (i == 0) {
                    ref = res.ao;
                    res.ao.data = NULL;
                } else {
                    double e = rmse(&res.ao, &ref);
                    if (getenv("MR_TEST_VERBOSE"))
                        printf("%s%s scale %g offset %g: RMSE %.5f\n", mr_ao_method_name(methods[mi]), half ? " half-res" : "",
                               scales[i], offs[i].x, e);
                    CHECK_MSG(e < 0.01, "%s%s%s at scale %g offset %g: RMSE %.5f vs scale 1", mr_ao_method_name(methods[mi]),
                              half ? " half-res" : "", mips ? " mips" : "", scales[i], offs[i].x, e);
                }
                mr_frame_result_free(&res);
            }
            mr_scene_destroy(&s);
        }
        mr_image_free(&ref);
    }
}

/* Extreme inputs: every method and option stays finite and in [0,1]. */
static void test_finite(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    /* Zero-length normals on the cube (the G-buffer must cope). */
    memset(s->meshes[2].normals, 0, s->meshes[2].vertex_count * 3 * sizeof(float));
    mr_view views[3];
    views[0] = mr_test_ao_corner_view(1, o, 96, 72);
    /* Half the image is sky. */
    views[1] = views[0];
    views[1].world_from_camera = mr_m4_look_at_cv(mr_v3(0, 0.5, -2), mr_v3(0, 0.6, -30), mr_v3(0, 1, 0));
    /* The camera a hair in front of the wall: depth close to the near plane. */
    views[2] = views[0];
    views[2].world_from_camera = mr_m4_look_at_cv(mr_v3(0.3, 1.0, 2.9 - 1e-5), mr_v3(0.3, 1.0, 3.5), mr_v3(0, 1, 0));
    const float cs[] = {0.0f, 1.0f, 1e7f};
    int bad_total = 0, frames = 0;
    for (int vi = 0; vi < 3; vi++)
        for (int m = MR_AO_SCHEER; m < MR_AO_METHOD_COUNT; m++)
            for (int variant = 0; variant < 4; variant++) {
                mr_ao_params ao = MR_AO_DEFAULTS;
                ao.method = (mr_ao_method)m;
                ao.c = cs[variant % 3];
                ao.half_res = variant == 1;
                ao.mask = variant == 2 ? MR_AO_MASK_ON : variant == 3 ? MR_AO_MASK_STANDALONE : MR_AO_MASK_OFF;
                ao.positions = variant == 3;
                ao.radii = variant == 1 ? 3 : 1;
                ao.radius_mode = variant == 2 ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
                ao.samples = 8;
                mr_frame_result res;
                if (!mr_test_render_ao(g_r, s, &views[vi], &ao, &res)) continue;
                int bad = mr_test_ao_count_bad(&res.ao);
                const unsigned char *c = res.color.data;
                (void)c;
                CHECK_MSG(bad == 0, "view %d %s variant %d: %d non-finite or out-of-range AO values", vi,
                          mr_ao_method_name(ao.method), variant, bad);
                bad_total += bad;
                /* Sky pixels are unoccluded. */
                const float *d = res.depth.data, *a = res.ao.data;
                int sky_bad = 0;
                for (int i = 0; i < res.ao.width * res.ao.height; i++) sky_bad += d[i] == 0 && a[i] != 1.0f;
                CHECK_MSG(sky_bad == 0, "view %d %s: %d sky pixels with AO != 1", vi, mr_ao_method_name(ao.method), sky_bad);
                frames++;
                mr_frame_result_free(&res);
            }
    CHECK(frames == 3 * (MR_AO_METHOD_COUNT - 1) * 4 && bad_total == 0);
    mr_scene_destroy(&s);
}

static void passes_of(const mr_frame_result *r, char *buf, size_t n) { mr_frame_result_passes(r, buf, n); }

static void test_pass_list(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
    mr_error err = {0};
    CHECK(mr_renderer_set_scene(g_r, s, &err));
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.ao.want_ao = true;
    mr_frame_result r1, r2, r3;
    char buf[256];
    /* Off: no AO pass, AO image is all ones. */
    CHECK(mr_render_frame(g_r, &v, &p, &r1, &err));
    passes_of(&r1, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "gbuffer shade") == 0, "passes with AO off: %s", buf);
    CHECK(((float *)r1.ao.data)[0] == 1.0f && r1.ao_masked_fraction == -1);
    mr_frame_result_free(&r1);
    /* On, then the same frame again: reused, identical, no AO pass. */
    p.ao.method = MR_AO_SCHEER;
    CHECK(mr_render_frame(g_r, &v, &p, &r1, &err));
    passes_of(&r1, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "gbuffer ao ao_blur shade") == 0, "passes with scheer: %s", buf);
    CHECK(mr_render_frame(g_r, &v, &p, &r2, &err));
    passes_of(&r2, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "gbuffer shade") == 0 && r2.ao_reused, "frozen camera: %s", buf);
    CHECK(memcmp(r1.ao.data, r2.ao.data, mr_image_bytes(&r1.ao)) == 0);
    CHECK(memcmp(r1.color.data, r2.color.data, mr_image_bytes(&r1.color)) == 0);
    /* AO darkens the shading somewhere, never brightens. */
    mr_frame_params p0 = p;
    p0.ao.method = MR_AO_NONE;
    CHECK(mr_render_frame(g_r, &v, &p0, &r3, &err));
    int darker = 0, brighter = 0;
    for (size_t i = 0; i < mr_image_bytes(&r3.color); i++) {
        int a = ((unsigned char *)r1.color.data)[i], b = ((unsigned char *)r3.color.data)[i];
        darker += a < b - 2;
        brighter += a > b + 1;
    }
    CHECK(darker > 50 && brighter == 0);
    mr_frame_result_free(&r3);
    mr_frame_result_free(&r2);
    /* The camera moves: computed again. */
    mr_view v2 = v;
    v2.world_from_camera.m[3] += 0.01;
    CHECK(mr_render_frame(g_r, &v2, &p, &r2, &err));
    passes_of(&r2, buf, sizeof buf);
    CHECK(strstr(buf, "ao ") != NULL && !r2.ao_reused);
    mr_frame_result_free(&r2);
    mr_frame_result_free(&r1);
    /* The rasterised positions texture gives the AO of the un-projected
     * depth (both are the same surface points), and it holds real points. */
    {
        mr_frame_params pd = p, pp = p;
        pd.ao.no_reuse = pp.ao.no_reuse = true;
        pp.ao.positions = true;
        mr_frame_result rd, rp;
        if (mr_render_frame(g_r, &v, &pd, &rd, &err)) {
            if (mr_render_frame(g_r, &v, &pp, &rp, &err)) {
                double e = rmse(&rd.ao, &rp.ao);
                CHECK_MSG(e < 0.01, "positions path vs depth path: RMSE %g", e);
                mr_frame_result_free(&rp);
            }
            mr_frame_result_free(&rd);
        }
    }
    /* Half resolution, positions, masking. */
    p.ao.half_res = true;
    p.ao.positions = true;
    p.ao.mask = MR_AO_MASK_ON;
    CHECK_MSG(mr_render_frame(g_r, &v, &p, &r1, &err), "%s", err.msg);
    passes_of(&r1, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "gbuffer ao_mask ao ao_blur ao_upsample shade") == 0, "passes: %s", buf);
    CHECK_MSG(r1.ao_masked_fraction > 0.02 && r1.ao_masked_fraction < 0.9, "masked fraction %g", r1.ao_masked_fraction);
    mr_frame_result_free(&r1);
    /* An external AO image (ground truth) is shaded with, no AO pass runs;
     * one of the wrong size is refused. */
    mr_image ext = {0};
    mr_image_alloc(&ext, 96, 72, 1, MR_PIX_F32, NULL);
    for (int i = 0; i < 96 * 72; i++) ((float *)ext.data)[i] = 0.25f;
    p.ao.external = &ext;
    CHECK(mr_render_frame(g_r, &v, &p, &r1, &err));
    passes_of(&r1, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "gbuffer shade") == 0, "external AO: %s", buf);
    CHECK(r1.ao.data && ((float *)r1.ao.data)[100] == 0.25f);
    mr_frame_result_free(&r1);
    ext.width = 95;
    CHECK(!mr_render_frame(g_r, &v, &p, &r1, &err));
    p.ao.external = NULL;
    ext.width = 96;
    mr_image_free(&ext);
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* Corner masking keeps the corner and skips the open floor, whose AO is
 * then exactly 1; the standalone mask darkens the corner by itself. */
static void test_mask(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 128, 96);
    for (int mm = MR_AO_MASK_ON; mm <= MR_AO_MASK_STANDALONE; mm++) {
        mr_ao_params ao = MR_AO_DEFAULTS;
        ao.method = MR_AO_SCHEER;
        ao.mask = (mr_ao_mask)mm;
        ao.blur_radius = 0;
        mr_frame_result res;
        if (!mr_test_render_ao(g_r, s, &v, &ao, &res)) continue;
        int nc = 0, no = 0;
        double corner = floor_band(&v, &res, &res.ao, 0.0, 0.1, 1, o, &nc);
        double open = floor_band(&v, &res, &res.ao, 2.0, 2.5, 1, o, &no);
        CHECK_MSG(corner < 0.9, "mask %d: corner %.3f", mm, corner);
        if (mm == MR_AO_MASK_ON) CHECK_MSG(open == 1.0, "mask on: open floor AO %.4f, not skipped", open);
        CHECK(res.ao_masked_fraction > 0 && res.ao_masked_fraction < 0.8);
        mr_frame_result_free(&res);
    }
    mr_scene_destroy(&s);
}

/* ------------------------------------------- pinned against the reference */

/* Per-pixel error of an AO image against a reference over the geometry
 * pixels: mean |e|, RMSE, signed mean (> 0 brighter) and the 95th
 * percentile of |e|. */
typedef struct ao_err {
    double mae, rmse, bias, p95;
    int n;
} ao_err;

static int cmp_float(const void *a, const void *b) {
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static ao_err ao_error(const mr_image *a, const mr_image *ref, const mr_image *depth) {
    ao_err e = {0, 0, 0, 0, 0};
    size_t n = (size_t)a->width * a->height;
    float *abs_e = malloc(n * sizeof *abs_e);
    if (!abs_e) return e;
    const float *pa = a->data, *pr = ref->data, *d = depth->data;
    for (size_t i = 0; i < n; i++) {
        if (!(d[i] > 0)) continue;
        double v = isfinite(pa[i]) ? pa[i] - pr[i] : 1.0; /* NaN counts as the worst error */
        e.mae += fabs(v);
        e.rmse += v * v;
        e.bias += v;
        abs_e[e.n++] = (float)fabs(v);
    }
    if (e.n) {
        e.mae /= e.n;
        e.rmse = sqrt(e.rmse / e.n);
        e.bias /= e.n;
        qsort(abs_e, (size_t)e.n, sizeof *abs_e, cmp_float);
        e.p95 = abs_e[(int)(0.95 * (e.n - 1))];
    }
    free(abs_e);
    return e;
}

/* The views the AO is pinned on, 96x72: a plain floor, the floor/wall/cube
 * corner, and two views of the procedural demo hall. */
enum { PIN_PLANE, PIN_CORNER, PIN_HALL_NEAR, PIN_HALL_FAR, PIN_VIEWS };
static const char *const k_pin_names[PIN_VIEWS] = {"plane", "corner", "hall-partition", "hall-down"};

static mr_view hall_view(int i) {
    /* The demo tablet's field of view (fx 500 at 640 px) at 96x72, looking
     * at the partition and down the hall (two of `mrcheck demo`'s views). */
    static const double k[2][6] = {{-4.0, 1.6, -2.0, -14.0, 2.0, 8.0}, {12.0, 1.7, 9.0, -4.0, 1.6, -9.0}};
    mr_view v;
    mr_camera c = {96, 72, 75.0, 75.0, 47.5, 35.5, {0, 0, 0, 0, 0}};
    v.camera = c;
    v.world_from_camera = mr_m4_look_at_cv(mr_v3(k[i][0], k[i][1], k[i][2]), mr_v3(k[i][3], k[i][4], k[i][5]), mr_v3(0, 1, 0));
    return v;
}

typedef struct pin_view {
    mr_scene *scene;
    mr_view view;
    mr_demo_hall hall;
} pin_view;

static bool pin_view_make(int which, pin_view *pv) {
    memset(pv, 0, sizeof *pv);
    mr_dvec3 o = mr_v3(0, 0, 0);
    if (which == PIN_PLANE || which == PIN_CORNER) {
        pv->scene = mr_test_ao_corner_scene(1, o, which == PIN_CORNER);
        pv->view = mr_test_ao_corner_view(1, o, 96, 72);
        return pv->scene != NULL;
    }
    mr_error err = {0};
    bool ok = mr_demo_build(NULL, &pv->hall, &err);
    CHECK_MSG(ok, "demo hall: %s", err.msg);
    pv->scene = ok ? pv->hall.planned : NULL;
    pv->view = hall_view(which == PIN_HALL_NEAR ? 0 : 1);
    return ok;
}

static void pin_view_free(pin_view *pv) {
    if (pv->hall.planned) mr_demo_free(&pv->hall);
    else mr_scene_destroy(&pv->scene);
    memset(pv, 0, sizeof *pv);
}

/* Today's error of every method at its defaults (screen radius 0.05 of the
 * image against the depth-scaled reference; view radius 0.5 against the
 * fixed-R reference, 256 rays), measured once with MR_TEST_VERBOSE=1 and
 * pinned: mean |e| and RMSE may grow by 10% + 0.002, the 95th percentile by
 * 10% + 0.005, and the signed mean may move by 10% + 0.003 either way (a
 * change that brightens or darkens the AO must update this table on
 * purpose). Columns: mae, rmse, bias, p95. Slot 0 (MR_AO_NONE) holds the
 * paper-pure scheer instead: no cosine bias, the whole unit ball as kernel
 * (`--ao scheer --ao-bias 0 --ao-rmin 0`). */
static const double k_pinned[PIN_VIEWS][MR_AO_METHOD_COUNT][2][4] = {
#include "ao_pinned.inc"
};

static void test_pinned_reference(void) {
    bool verbose = getenv("MR_TEST_VERBOSE") != NULL;
    for (int vi = 0; vi < PIN_VIEWS; vi++) {
        pin_view pv;
        if (!pin_view_make(vi, &pv)) continue;
        mr_ao_params none = MR_AO_DEFAULTS;
        mr_frame_result g;
        if (!mr_test_render_ao(g_r, pv.scene, &pv.view, &none, &g)) {
            pin_view_free(&pv);
            continue;
        }
        mr_error err = {0};
        mr_eval_gt *gt = mr_eval_gt_create(pv.scene, false, &err);
        CHECK_MSG(gt != NULL, "%s", err.msg);
        mr_image ref[2] = {{0}, {0}};
        for (int mode = 0; mode < 2 && gt; mode++) {
            mr_gt_params gp = MR_GT_DEFAULTS;
            gp.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
            gp.radius = 0.5;
            gp.screen_radius = 0.05;
            gp.rays = 256;
            gp.seed = 11;
            CHECK_MSG(mr_eval_ao_groundtruth(gt, &pv.view, &g.depth, &g.normal, &gp, &ref[mode], &err), "%s", err.msg);
        }
        for (int m = 0; m < MR_AO_METHOD_COUNT && ref[0].data && ref[1].data; m++)
            for (int mode = 0; mode < 2; mode++) {
                mr_ao_params ao = MR_AO_DEFAULTS;
                ao.method = m == 0 ? MR_AO_SCHEER : (mr_ao_method)m;
                if (m == 0) {
                    ao.bias = 0;
                    ao.r_min = 0;
                }
                const char *mname = m == 0 ? "scheer-paper" : mr_ao_method_name(ao.method);
                ao.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
                ao.radius = 0.5;
                mr_frame_result res;
                if (!mr_test_render_ao(g_r, pv.scene, &pv.view, &ao, &res)) continue;
                ao_err e = ao_error(&res.ao, &ref[mode], &g.depth);
                const double *k = k_pinned[vi][m][mode];
                const char *what = mode ? "view" : "screen";
                if (verbose)
                    printf("    /* %s %s %s */ {%.4f, %.4f, %.4f, %.4f},\n", k_pin_names[vi], mname, what,
                           e.mae, e.rmse, e.bias, e.p95);
                CHECK_MSG(e.n > 1000, "%s: only %d geometry pixels", k_pin_names[vi], e.n);
                CHECK_MSG(e.mae <= 1.1 * k[0] + 0.002, "%s %s %s: mean |AO - reference| %.4f > pinned %.4f",
                          k_pin_names[vi], mname, what, e.mae, k[0]);
                CHECK_MSG(e.rmse <= 1.1 * k[1] + 0.002, "%s %s %s: RMSE against the reference %.4f > pinned %.4f",
                          k_pin_names[vi], mname, what, e.rmse, k[1]);
                CHECK_MSG(fabs(e.bias - k[2]) <= 0.1 * fabs(k[2]) + 0.003,
                          "%s %s %s: mean signed error (AO - reference) %.4f, pinned %.4f: the AO got %s",
                          k_pin_names[vi], mname, what, e.bias, k[2], e.bias > k[2] ? "brighter" : "darker");
                CHECK_MSG(e.p95 <= 1.1 * k[3] + 0.005, "%s %s %s: 95th percentile of |AO - reference| %.4f > pinned %.4f",
                          k_pin_names[vi], mname, what, e.p95, k[3]);
                mr_frame_result_free(&res);
            }
        mr_image_free(&ref[0]);
        mr_image_free(&ref[1]);
        mr_eval_gt_destroy(&gt);
        mr_frame_result_free(&g);
        pin_view_free(&pv);
    }
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* ------------------------------------------------------------ AO goldens */

/* Each method's AO image on the corner scene (96x72), unblurred so that
 * every change to a shader shows per pixel, plus scheer blurred, at half
 * resolution, with 5 radii, the standalone mask and the paper-pure scheer
 * (bias 0, kernel r_min 0: `--ao-bias 0 --ao-rmin 0`), stored as 8-bit grey
 * PNGs in tests/data/golden/ao_*.png (MR_UPDATE_GOLDEN=1 rewrites them).
 * A pixel mismatches when it is off by more than 0.006 (the PNG's rounding
 * is 0.002); at most 1% may, and the mean |difference| stays below 0.002. */
typedef struct golden_case {
    const char *name;
    mr_ao_method method;
    mr_ao_radius_mode mode;
    int blur;
    bool half;
    int radii;
    mr_ao_mask mask;
    bool paper; /* scheer as the paper has it: no cosine bias, the whole unit ball as kernel */
} golden_case;

static void test_golden(void) {
    const char *data = getenv("MR_TEST_DATA");
    CHECK_MSG(data != NULL, "MR_TEST_DATA not set: run through ctest, or set it to tests/data");
    if (!data) return;
    static const golden_case cases[] = {
        {"scheer_screen", MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"scheer_view", MR_AO_SCHEER, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        {"crytek_screen", MR_AO_CRYTEK, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"crytek_view", MR_AO_CRYTEK, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        {"filion_screen", MR_AO_FILION, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"filion_view", MR_AO_FILION, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        {"hbao_screen", MR_AO_HBAO, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"hbao_view", MR_AO_HBAO, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        {"alchemy_screen", MR_AO_ALCHEMY, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"alchemy_view", MR_AO_ALCHEMY, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        {"scheer_blur", MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, 4, false, 1, MR_AO_MASK_OFF, false},
        {"scheer_half", MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, 4, true, 1, MR_AO_MASK_OFF, false},
        {"scheer_radii5", MR_AO_SCHEER, MR_AO_RADIUS_VIEW, 0, false, 5, MR_AO_MASK_OFF, false},
        {"mask_standalone", MR_AO_SCHEER, MR_AO_RADIUS_VIEW, 4, false, 1, MR_AO_MASK_STANDALONE, false},
        {"scheer_paper", MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, true},
        /* issue 18 */
        {"gtao_screen", MR_AO_GTAO, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"gtao_view", MR_AO_GTAO, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        {"bitmask_screen", MR_AO_BITMASK, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"bitmask_view", MR_AO_BITMASK, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        {"scheer_gt_screen", MR_AO_SCHEER_GT, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
        {"scheer_gt_view", MR_AO_SCHEER_GT, MR_AO_RADIUS_VIEW, 0, false, 1, MR_AO_MASK_OFF, false},
        /* issue 18 (lane ao) */
        {"scheer_bm_screen", MR_AO_SCHEER_BM, MR_AO_RADIUS_SCREEN, 0, false, 1, MR_AO_MASK_OFF, false},
    };
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
    bool update = getenv("MR_UPDATE_GOLDEN") != NULL;
    for (size_t ci = 0; ci < sizeof cases / sizeof cases[0]; ci++) {
        const golden_case *gc = &cases[ci];
        mr_ao_params ao = MR_AO_DEFAULTS;
        ao.method = gc->method;
        ao.radius_mode = gc->mode;
        ao.radius = 0.5;
        ao.blur_radius = gc->blur;
        ao.half_res = gc->half;
        ao.radii = gc->radii;
        ao.mask = gc->mask;
        if (gc->paper) {
            ao.bias = 0;
            ao.r_min = 0;
        }
        mr_frame_result res;
        if (!mr_test_render_ao(g_r, s, &v, &ao, &res)) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/golden/ao_%s.png", data, gc->name);
        mr_error err = {0};
        size_t n = (size_t)res.ao.width * res.ao.height;
        const float *a = res.ao.data;
        if (update) {
            mr_image png = {0};
            CHECK(mr_image_alloc(&png, res.ao.width, res.ao.height, 1, MR_PIX_U8, &err));
            for (size_t i = 0; i < n && png.data; i++) {
                float x = isfinite(a[i]) ? a[i] : 0.0f;
                ((unsigned char *)png.data)[i] = (unsigned char)lrintf(255.0f * fminf(fmaxf(x, 0.0f), 1.0f));
            }
            CHECK_MSG(png.data && mr_image_save_png(path, &png, &err), "%s", err.msg);
            fprintf(stderr, "test_ao: wrote %s\n", path);
            mr_image_free(&png);
        } else {
            mr_image gold = {0};
            if (!mr_image_load(path, 1, &gold, &err)) {
                CHECK_MSG(false, "%s", err.msg);
            } else if (gold.width != res.ao.width || gold.height != res.ao.height) {
                CHECK_MSG(false, "%s: golden is %dx%d, AO %dx%d", path, gold.width, gold.height, res.ao.width, res.ao.height);
            } else {
                const unsigned char *gp = gold.data;
                size_t bad = 0;
                double sum = 0, worst = 0;
                for (size_t i = 0; i < n; i++) {
                    double d = isfinite(a[i]) ? fabs(a[i] - gp[i] / 255.0) : 1.0;
                    bad += d > 0.006;
                    sum += d;
                    if (d > worst) worst = d;
                }
                double frac = (double)bad / (double)n;
                CHECK_MSG(frac <= 0.01 && sum / n < 0.002,
                          "AO golden %s: %.2f%% of pixels off by > 0.006 (max %.3f, mean %.4f): the AO of this case changed",
                          gc->name, 100 * frac, worst, sum / n);
            }
            mr_image_free(&gold);
        }
        mr_frame_result_free(&res);
    }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* ------------------------------------------------- corner mask, analytic */

/* The corner scene's boxes (corner_scene with k = 1 at the origin):
 * centre and half extents. An axis-aligned box's outline volume is the box
 * grown by r on every side (each corner moves by r (+-1,+-1,+-1), the
 * miter of its three faces). */
static const double k_boxes[3][6] = {
    {0, -0.1, 0, 10, 0.1, 10},   /* floor */
    {0, 3, 3.0, 10, 3, 0.1},     /* wall, face at z = 2.9 */
    {-1.5, 0.5, 1.0, 0.5, 0.5, 0.5}, /* cube */
};

/* How many outline volumes contain p (the camera is outside all of them, so
 * this is what +1 entering / -1 leaving sums to), and how far p is from the
 * nearest volume boundary (pixels closer than a rasterisation step are
 * ambiguous). */
static int analytic_count(mr_dvec3 p, double a, double *margin) {
    const double q[3] = {p.x, p.y, p.z};
    int count = 0;
    *margin = 1e9;
    for (int b = 0; b < 3; b++) {
        double dmax = -1e9;
        for (int k = 0; k < 3; k++) {
            double d = fabs(q[k] - k_boxes[b][k]) - (k_boxes[b][3 + k] + a);
            if (d > dmax) dmax = d;
        }
        count += dmax < 0;
        if (fabs(dmax) < *margin) *margin = fabs(dmax);
    }
    return count;
}

/* Whether every geometry pixel within `rad` of (x, y) (a square: the
 * separable blur's footprint) is in (want_in) or out of the mask. */
static bool window_is(const mr_image *cnt, const mr_image *depth, int x, int y, int rad, bool want_in) {
    const float *c = cnt->data, *d = depth->data;
    for (int j = -rad; j <= rad; j++)
        for (int i = -rad; i <= rad; i++) {
            int u = x + i, v = y + j;
            if (u < 0 || v < 0 || u >= cnt->width || v >= cnt->height) continue;
            size_t k = (size_t)v * cnt->width + u;
            if (d[k] > 0 && (c[k] >= 1.5f) != want_in) return false;
        }
    return true;
}

/* Park & Baek: the mask changes AO only where the outline count is >= 2.
 * The same frame with and without the mask: where the count is >= 2 the
 * masked AO is the unmasked AO, elsewhere it is exactly 1 (with the blur:
 * where the whole blur footprint is on one side). The counts themselves are
 * checked against the analytic count of grown boxes (view radius). */
static void test_mask_count(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    for (int inside = 0; inside < 2; inside++)
    for (int mode = 0; mode < 2; mode++)
        for (int blur = 0; blur <= 2; blur += 2) {
            /* The second view stands in the floor's and the wall's outline
             * volumes (0.6 above the floor, 0.7 from the wall, r = 1): the
             * count must not lose the volumes around the eye. */
            mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
            if (inside)
                v.world_from_camera = mr_m4_look_at_cv(mr_v3(1.5, 0.6, 2.2), mr_v3(-0.5, 0.0, 2.9), mr_v3(0, 1, 0));
            const char *what = inside ? (mode ? "view, camera inside" : "screen, camera inside") : mode ? "view" : "screen";
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = MR_AO_SCHEER;
            ao.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
            ao.radius = 1.0;
            ao.screen_radius = 0.1;
            ao.blur_radius = blur;
            mr_frame_result off, on;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &off)) continue;
            ao.mask = MR_AO_MASK_ON;
            ao.want_mask = true;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &on)) {
                mr_frame_result_free(&off);
                continue;
            }
            CHECK_MSG(on.ao_mask.data && on.ao_mask.width == 96 && on.ao_mask.height == 72,
                      "mask on: no outline count image returned");
            CHECK_MSG(!off.ao_mask.data, "mask off: an outline count image was returned");
            if (!on.ao_mask.data) {
                mr_frame_result_free(&on);
                mr_frame_result_free(&off);
                continue;
            }
            const float *cnt = on.ao_mask.data, *am = on.ao.data, *au = off.ao.data, *d = off.depth.data;
            int in = 0, out = 0, in_occ = 0, out_occ = 0, bad_in = 0, bad_out = 0;
            double worst_in = 0, worst_out = 0;
            for (int y = 0; y < 72; y++)
                for (int x = 0; x < 96; x++) {
                    size_t i = (size_t)y * 96 + x;
                    if (!(d[i] > 0)) continue;
                    bool is_in = cnt[i] >= 1.5f;
                    if (!window_is(&on.ao_mask, &off.depth, x, y, blur, is_in)) continue;
                    if (is_in) {
                        in++;
                        in_occ += au[i] < 0.99f;
                        double e = fabs(am[i] - au[i]);
                        if (e > 1e-6) bad_in++;
                        if (e > worst_in) worst_in = e;
                    } else {
                        out++;
                        out_occ += au[i] < 0.99f;
                        double e = fabs(am[i] - 1.0);
                        if (e > (blur ? 1e-6 : 0)) bad_out++;
                        if (e > worst_out) worst_out = e;
                    }
                }
            CHECK_MSG(bad_in == 0, "mask on, %s, blur %d: %d of %d pixels with outline count >= 2 differ from the unmasked AO "
                      "(max %.4f): the mask threshold skips corners", what, blur, bad_in, in, worst_in);
            CHECK_MSG(bad_out == 0, "mask on, %s, blur %d: %d of %d pixels with outline count < 2 have AO != 1 (max %.4f): "
                      "the mask threshold lets non-corners through", what, blur, bad_out, out, worst_out);
            /* Both sides must have occluded pixels, or the checks above prove nothing. */
            if (getenv("MR_TEST_VERBOSE")) printf("mask %s blur %d: occluded %d in, %d out\n", what, blur, in_occ, out_occ);
            CHECK_MSG(in_occ > (blur ? 5 : 20) && (inside || out > 300), "mask %s blur %d: too few pixels to compare (%d occluded in, %d out)",
                      what, blur, in_occ, out);
            if (mode == 1 && blur == 0) {
                double a = ao.radius;
                int checked = 0, wrong = 0, floor_open = 0, floor_corner = 0;
                char first[160] = "";
                for (int y = 0; y < 72; y++)
                    for (int x = 0; x < 96; x++) {
                        size_t i = (size_t)y * 96 + x;
                        if (!(d[i] > 0)) continue;
                        double margin;
                        mr_dvec3 p = mr_test_pixel_world(&v, &off.depth, x, y);
                        int want = analytic_count(p, a, &margin);
                        if (margin < 0.03) continue;
                        checked++;
                        if (fabs(cnt[i] - want) > 1e-3) {
                            if (!wrong++)
                                snprintf(first, sizeof first, "pixel (%d,%d) at (%.2f,%.2f,%.2f): count %g, expected %d", x, y, p.x,
                                         p.y, p.z, cnt[i], want);
                        }
                        if (fabs(p.y) < 0.01 && p.x > -0.5) {
                            double dist = 2.9 - p.z;
                            floor_open += dist > 0.7 && want == 1;
                            floor_corner += dist < 0.5 && want == 2;
                        }
                    }
                CHECK_MSG(checked > 3000 && (inside || floor_open > 300) && floor_corner > 20,
                          "outline count check covers too little (%d pixels, %d open floor, %d corner)", checked, floor_open,
                          floor_corner);
                CHECK_MSG(wrong == 0, "outline count wrong at %d of %d pixels (open floor must count 1, the floor-wall corner 2): %s",
                          wrong, checked, first);
            }
            mr_frame_result_free(&on);
            mr_frame_result_free(&off);
        }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* Park & Baek promise the image of the unmasked AO: with the outline grown
 * by the whole radius, every method keeps 99 % of its darkening (sum of
 * 1 - AO) on the floor within the radius of the wall, where the closed form
 * puts all the wall's occlusion, in both radius modes. (Beyond the radius
 * the closed form is 1 and the masked AO is exactly 1, test_mask; crytek,
 * filion and scheer grey the open floor there unmasked, which the mask
 * removes: the whole-image ratio is printed, not asserted.) */
static void test_mask_retains(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
    bool verbose = getenv("MR_TEST_VERBOSE") != NULL;
    for (int m = MR_AO_SCHEER; m < MR_AO_METHOD_COUNT; m++)
        for (int mode = 0; mode < 2; mode++) {
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = (mr_ao_method)m;
            ao.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
            ao.radius = 0.8;
            ao.screen_radius = 0.1;
            ao.blur_radius = 0; /* the blur would mix in the open floor's greying, which the mask removes */
            mr_frame_result off, on;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &off)) continue;
            ao.mask = MR_AO_MASK_ON;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &on)) {
                mr_frame_result_free(&off);
                continue;
            }
            double d_off = 0, d_on = 0, all_off = 0, all_on = 0;
            int n = 0;
            const float *am = on.ao.data, *au = off.ao.data, *d = off.depth.data;
            for (int y = 0; y < 72; y++)
                for (int x = 0; x < 96; x++) {
                    size_t i = (size_t)y * 96 + x;
                    if (!(d[i] > 0)) continue;
                    all_off += 1 - au[i];
                    all_on += 1 - am[i];
                    mr_dvec3 p = mr_test_pixel_world(&v, &off.depth, x, y);
                    double dist = 2.9 - p.z, R = mode ? ao.radius : ao.screen_radius * d[i] * v.camera.height / v.camera.fy;
                    if (fabs(p.y) > 0.01 || dist < 0 || dist > R || p.x < -0.5 || p.x > 5) continue;
                    d_off += 1 - au[i];
                    d_on += 1 - am[i];
                    n++;
                }
            const char *name = mr_ao_method_name(ao.method);
            if (verbose)
                printf("mask retains %s %s: floor %.4f (%.3f / %.3f over %d px), whole image %.4f\n", name, mode ? "view" : "screen",
                       d_off > 0 ? d_on / d_off : 1, d_on, d_off, n, all_off > 0 ? all_on / all_off : 1);
            CHECK_MSG(n > 150 && d_off > 5, "%s: too little floor darkening to compare (%d px, %.2f)", name, n, d_off);
            CHECK_MSG(fabs(d_on - d_off) <= 0.01 * d_off, "%s %s: the mask keeps %.2f%% of the floor's darkening within the radius of the wall",
                      name, mode ? "view" : "screen", d_off > 0 ? 100 * d_on / d_off : 0);
            mr_frame_result_free(&on);
            mr_frame_result_free(&off);
        }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* The stand-alone mask is AO of its own: 1 - mask_strength inside the mask
 * and 1 outside before the blur (so in [0,1] whatever --ao names and
 * whatever its strength), and the blur is linear, so AO(s) = 1 - s * B with
 * B = 1 - AO(1) the blurred mask. The stand-alone mask is always blurred
 * (blur 0 means the default 4 there): where the whole blur footprint is
 * inside the mask the AO is exactly 1 - s, where it is outside exactly 1. */
static void test_mask_standalone(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
    const mr_ao_method methods[3] = {MR_AO_SCHEER, MR_AO_CRYTEK, MR_AO_HBAO};
    const float strengths[3] = {0.0f, 1.0f, 7.0f}; /* the method's strength plays no part */
    for (int blur = 0; blur <= 2; blur += 2) {
        int rad = blur ? blur : 4;
        mr_image first = {0}, unit = {0};
        for (int mi = 0; mi < 3; mi++) {
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = methods[mi];
            ao.strength = strengths[mi];
            ao.radius_mode = MR_AO_RADIUS_VIEW;
            ao.radius = 1.0;
            ao.blur_radius = blur;
            ao.mask = MR_AO_MASK_STANDALONE;
            ao.mask_strength = 0.6f;
            ao.want_mask = true;
            mr_frame_result res;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &res)) continue;
            const float *a = res.ao.data, *cnt = res.ao_mask.data, *d = res.depth.data;
            CHECK_MSG(cnt != NULL, "standalone mask: no outline counts returned");
            int out_of_range = 0, wrong = 0, inside = 0;
            for (int i = 0; i < 96 * 72 && cnt; i++) {
                out_of_range += !(a[i] >= 0 && a[i] <= 1);
                if (!(d[i] > 0)) continue;
                bool in = cnt[i] >= 1.5f;
                if (!window_is(&res.ao_mask, &res.depth, i % 96, i / 96, rad, in)) continue;
                inside += in;
                wrong += fabsf(a[i] - (in ? 0.4f : 1.0f)) > 1e-5f;
            }
            CHECK_MSG(out_of_range == 0, "standalone %s blur %d: %d AO values outside [0,1]", mr_ao_method_name(ao.method), blur,
                      out_of_range);
            CHECK_MSG(wrong == 0 && inside > 10,
                      "standalone %s (strength %g), blur %d: %d pixels are not 1 - 0.6 deep in the mask (%d pixels) and 1 outside",
                      mr_ao_method_name(ao.method), strengths[mi], rad, wrong, inside);
            if (mi == 0) {
                first = res.ao;
                res.ao.data = NULL;
            } else if (first.data) {
                double e = 0;
                for (int i = 0; i < 96 * 72; i++) e = fmax(e, fabs(a[i] - ((float *)first.data)[i]));
                CHECK_MSG(e <= 1e-6, "standalone mask with --ao %s differs from --ao scheer by %.4f: it must not depend on the method",
                          mr_ao_method_name(ao.method), e);
            }
            mr_frame_result_free(&res);
        }
        /* Strength 1 gives the blurred mask B itself; 1.7 is clamped to 1
         * before the blur; 0 means the default 0.5. */
        const float ms[3] = {1.0f, 1.7f, 0.0f};
        for (int k = 0; k < 3 && first.data; k++) {
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = MR_AO_SCHEER;
            ao.radius_mode = MR_AO_RADIUS_VIEW;
            ao.radius = 1.0;
            ao.blur_radius = blur;
            ao.mask = MR_AO_MASK_STANDALONE;
            ao.mask_strength = ms[k];
            mr_frame_result res;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &res)) continue;
            const float *a = res.ao.data, *f6 = first.data;
            if (k == 0) {
                unit = res.ao;
                res.ao.data = NULL;
                double e = 0;
                int dark = 0;
                for (int i = 0; i < 96 * 72; i++) {
                    e = fmax(e, fabs(f6[i] - (1.0 - 0.6 * (1.0 - ((float *)unit.data)[i]))));
                    dark += ((float *)unit.data)[i] < 0.5f;
                }
                CHECK_MSG(e <= 1e-5 && dark > 50, "standalone blur %d: AO(0.6) != 1 - 0.6 * blurred mask (max error %.5f, %d dark pixels)",
                          blur, e, dark);
            } else {
                double want_s = k == 1 ? 1.0 : 0.5, e = 0;
                for (int i = 0; i < 96 * 72 && unit.data; i++)
                    e = fmax(e, fabs(a[i] - (1.0 - want_s * (1.0 - ((float *)unit.data)[i]))));
                CHECK_MSG(e <= 1e-5, "standalone blur %d, mask_strength %g: AO is not 1 - %g * blurred mask (max error %.5f)", blur,
                          ms[k], want_s, e);
            }
            mr_frame_result_free(&res);
        }
        mr_image_free(&first);
        mr_image_free(&unit);
    }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* Up to 5 radii (Doronin et al.): the darkest radius wins, so a fifth
 * radius can only darken (per pixel, no blur) and does somewhere; 6 and
 * more are clamped to 5. */
static void test_radii(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
    for (int mode = 0; mode < 2; mode++) {
        mr_image img[3] = {{0}, {0}, {0}};
        const int ks[3] = {4, 5, 6};
        for (int k = 0; k < 3; k++) {
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = MR_AO_SCHEER;
            ao.radius_mode = mode ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
            ao.radius = 2.0;
            ao.screen_radius = 0.4;
            ao.blur_radius = 0;
            ao.radii = ks[k];
            mr_frame_result res;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &res)) continue;
            img[k] = res.ao;
            res.ao.data = NULL;
            mr_frame_result_free(&res);
        }
        if (img[0].data && img[1].data && img[2].data) {
            const float *a4 = img[0].data, *a5 = img[1].data, *a6 = img[2].data;
            int brighter = 0, darker = 0, bad = 0, differ6 = 0;
            for (int i = 0; i < 96 * 72; i++) {
                brighter += a5[i] > a4[i] + 1e-6f;
                darker += a5[i] < a4[i] - 1e-3f;
                bad += !(a5[i] >= 0 && a5[i] <= 1);
                differ6 += a6[i] != a5[i];
            }
            const char *what = mode ? "view" : "screen";
            CHECK_MSG(brighter == 0 && bad == 0, "%s: 5 radii brighter than 4 at %d pixels, %d values outside [0,1]", what, brighter, bad);
            CHECK_MSG(darker > 10, "%s: a fifth radius darkens only %d pixels: is it used?", what, darker);
            CHECK_MSG(differ6 == 0, "%s: 6 radii are not clamped to 5 (%d pixels differ)", what, differ6);
        }
        for (int k = 0; k < 3; k++) mr_image_free(&img[k]);
    }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* ------------------------------------------------ issue 18: slice methods */

/* GTAO, the bitmask and scheer-gt (c = 0, bias 0: its horizon is GTAO's
 * without the falloff, so the same closed form) beside a wall: V = 1 -
 * (acos a - a sqrt(1 - a^2)) / pi, a = d / R, within 0.025 RMSE with 64
 * samples (4 slices x 8 steps per side), unblurred, for a fixed and for
 * the depth-scaled radius. */
static void test_slice_wall(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 160, 120);
    /* issue 18 (lane ao): scheer-bm with c = 0 (the bitmask's closed form),
     * and every method again with the depth mip chain (12 px of radius:
     * the samples beyond 8 px read level 1) */
    const mr_ao_method ms[4] = {MR_AO_GTAO, MR_AO_BITMASK, MR_AO_SCHEER_GT, MR_AO_SCHEER_BM};
    for (int mi = 0; mi < 4; mi++)
        for (int mode = 0; mode < 4; mode++) {
            bool mips = mode >= 2;
            mr_ao_params ao = mr_test_ao_wall_params(ms[mi], mode % 2);
            ao.mips = mips;
            char what[96];
            snprintf(what, sizeof what, "%s %s radius", mr_ao_method_name(ao.method),
                     mode % 2 ? (mips ? "view mips" : "view") : (mips ? "screen mips" : "screen"));
            mr_test_ao_wall_check(g_r, s, &v, &ao, what);
        }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* issue 18 (lane ao): scheer-bm with c = 0 is the bitmask (the same
 * sectors, each counted once with weight 1); with c > 0 a sector counts
 * with its nearest sample's 1/(1 + c l^2) <= 1, so the AO is nowhere
 * darker than the bitmask's and lighter on average, more so as c grows. */
static double mean_geo(const mr_image *ao, const mr_image *depth) {
    const float *a = ao->data, *d = depth->data;
    double s = 0;
    int n = 0;
    for (int i = 0; i < ao->width * ao->height; i++)
        if (d[i] > 0) s += a[i], n++;
    return n ? s / n : 0;
}

static void test_scheer_bm(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 128, 96);
    const float cs[3] = {0.0f, 1.0f, 4.0f};
    mr_frame_result bm, r[3];
    memset(&bm, 0, sizeof bm);
    mr_ao_params ao = MR_AO_DEFAULTS;
    ao.method = MR_AO_BITMASK;
    ao.blur_radius = 0; /* per pixel */
    ao.screen_radius = 0.15;
    bool ok = mr_test_render_ao(g_r, s, &v, &ao, &bm);
    for (int k = 0; k < 3 && ok; k++) {
        ao.method = MR_AO_SCHEER_BM;
        ao.c = cs[k];
        ok = mr_test_render_ao(g_r, s, &v, &ao, &r[k]);
        if (!ok) {
            for (int j = 0; j < k; j++) mr_frame_result_free(&r[j]);
        }
    }
    if (ok) {
        const float *a = bm.ao.data, *b0 = r[0].ao.data, *b1 = r[1].ao.data;
        double maxd = 0;
        int darker = 0;
        for (int i = 0; i < 128 * 96; i++) {
            maxd = fmax(maxd, fabs((double)a[i] - b0[i]));
            darker += b1[i] < a[i] - 1e-5f;
        }
        double m0 = mean_geo(&r[0].ao, &bm.depth), m1 = mean_geo(&r[1].ao, &bm.depth), m4 = mean_geo(&r[2].ao, &bm.depth);
        if (getenv("MR_TEST_VERBOSE"))
            printf("scheer-bm: c=0 vs bitmask max |d| %.2g; mean AO c=0 %.4f, c=1 %.4f, c=4 %.4f; %d pixels darker\n", maxd, m0,
                   m1, m4, darker);
        CHECK_MSG(maxd < 1e-5, "scheer-bm with c = 0 differs from the bitmask by up to %.3g", maxd);
        CHECK_MSG(darker == 0, "scheer-bm with c = 1: %d pixels darker than the bitmask", darker);
        CHECK_MSG(m1 > m0 + 0.002 && m4 > m1 + 0.002, "scheer-bm mean AO c=0 %.4f, c=1 %.4f, c=4 %.4f: not lighter with c", m0,
                  m1, m4);
        for (int k = 0; k < 3; k++) {
            CHECK(mr_test_ao_count_bad(&r[k].ao) == 0);
            mr_frame_result_free(&r[k]);
        }
    }
    if (bm.ao.data || bm.depth.data) mr_frame_result_free(&bm);
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* issue 18 (lane ao): the depth mip chain changes far samples only. With
 * a projected radius below MR_AO_MIP_NEAR_PX (0.05 of 96 px = 4.8 px)
 * every sample reads level 0 and the AO is the same bit for bit; with 29
 * px the far samples read levels 1..2: the AO moves (the chain is read)
 * but by little: its box filter of reversed-Z depth is exact on planes
 * (the wall test holds with mips), and only the averages across the
 * cube's depth edges differ (RMSE 0.030 gtao, 0.024 bitmask measured;
 * bound 0.04). */
static void test_mips(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 128, 96);
    const mr_ao_method ms[4] = {MR_AO_GTAO, MR_AO_BITMASK, MR_AO_SCHEER_GT, MR_AO_SCHEER_BM};
    for (int mi = 0; mi < 4; mi++)
        for (int far = 0; far < 2; far++) {
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = ms[mi];
            ao.blur_radius = 0;
            ao.screen_radius = far ? 0.3 : 0.05;
            mr_frame_result a, b;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &a)) continue;
            ao.mips = true;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &b)) {
                mr_frame_result_free(&a);
                continue;
            }
            const float *x = a.ao.data, *y = b.ao.data;
            double maxd = 0;
            for (int i = 0; i < 128 * 96; i++) maxd = fmax(maxd, fabs((double)x[i] - y[i]));
            double e = rmse(&a.ao, &b.ao);
            if (getenv("MR_TEST_VERBOSE"))
                printf("mips %s %s: max |d| %.3g, RMSE %.4f\n", mr_ao_method_name(ao.method), far ? "far" : "near", maxd, e);
            if (!far) CHECK_MSG(maxd == 0, "%s: the mip chain changed near samples (max |d| %.3g)", mr_ao_method_name(ao.method), maxd);
            else {
                CHECK_MSG(maxd > 1e-4, "%s: far samples do not read the mip chain (max |d| %.3g)", mr_ao_method_name(ao.method), maxd);
                CHECK_MSG(e < 0.04, "%s: the mip chain moved the AO by RMSE %.4f", mr_ao_method_name(ao.method), e);
            }
            CHECK(mr_test_ao_count_bad(&b.ao) == 0);
            mr_frame_result_free(&a);
            mr_frame_result_free(&b);
        }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* issue 18: temporal accumulation. A static camera converges towards the
 * many-sample AO; a slowly moving one too (the reprojection carries the
 * history: a wrong transform would smear it); after a jump with a
 * tracking reset, or a jump to a view with nothing in common, the frame
 * equals a fresh single frame (no ghost of the previous view). */
/* Without mr_renderer_set_scene per frame: a new scene starts a new history. */
static void render_ao_fp(const mr_scene *s, const mr_view *v, const mr_ao_params *ao, mr_image *out) {
    (void)s;
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.ao = *ao;
    p.ao.want_ao = true;
    mr_frame_result res;
    mr_error err = {0};
    bool ok = mr_render_frame(g_r, v, &p, &res, &err);
    CHECK_MSG(ok, "%s", err.msg);
    if (!ok) return;
    mr_image_free(out);
    *out = res.ao;
    res.ao.data = NULL;
    mr_frame_result_free(&res);
}

static mr_view moved_view(double t, int w, int h) {
    mr_view v = mr_test_ao_corner_view(1, mr_v3(0, 0, 0), w, h);
    v.world_from_camera = mr_m4_look_at_cv(mr_v3(0.7 + 0.3 * t, 2.2, -2.5 + 0.2 * t), mr_v3(0.2 + 0.2 * t, 0.2, 2.5),
                                           mr_v3(0, 1, 0));
    return v;
}

static void test_temporal(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    const int w = 128, h = 96;
    const mr_ao_method ms[2] = {MR_AO_SCHEER, MR_AO_GTAO};
    mr_error serr = {0};
    CHECK_MSG(mr_renderer_set_scene(g_r, s, &serr), "%s", serr.msg);
    for (int mi = 0; mi < 2; mi++) {
        mr_ao_params ao = MR_AO_DEFAULTS;
        ao.method = ms[mi];
        ao.radius_mode = MR_AO_RADIUS_VIEW;
        ao.radius = 0.5;
        ao.blur_radius = 0;
        mr_image ref = {0}, single = {0}, acc = {0}, fresh = {0};
        const char *name = mr_ao_method_name(ao.method);
        for (int moving = 0; moving < 2; moving++) {
            const int frames = 16;
            mr_view last = moved_view(moving ? 1.0 : 0.0, w, h);
            ao.samples = 64;
            ao.temporal = false;
            render_ao_fp(s, &last, &ao, &ref);
            ao.samples = 4;
            render_ao_fp(s, &last, &ao, &single);
            ao.temporal = true;
            for (int k = 0; k < frames; k++) {
                mr_view v = moved_view(moving ? (double)k / (frames - 1) : 0.0, w, h);
                ao.temporal_reset = k == 0;
                render_ao_fp(s, &v, &ao, &acc);
            }
            ao.temporal_reset = false;
            double e1 = rmse(&single, &ref), ea = rmse(&acc, &ref);
            if (getenv("MR_TEST_VERBOSE"))
                printf("temporal %s %s: 4 samples RMSE %.4f, accumulated %d frames %.4f (against 64 samples)\n", name,
                       moving ? "moving" : "static", e1, frames, ea);
            /* moving: history is lost at the image's edges and resampled at
             * the nearest previous pixel every frame */
            double bound = moving ? 0.75 : 0.6;
            CHECK_MSG(ea < bound * e1, "temporal %s %s camera: accumulated RMSE %.4f not below %.2f x one frame's %.4f", name,
                      moving ? "moving" : "static", ea, bound, e1);
            CHECK(mr_test_ao_count_bad(&acc) == 0);
        }
        /* A step of 0.4 units towards the wall after 16 still frames: every
         * pixel's depth changes, so only a correct reprojection finds the
         * history (at the same pixel the depth test rejects it: the frame
         * would be a single frame's). */
        {
            mr_view a = mr_test_ao_corner_view(1, o, w, h), a2 = a;
            a2.world_from_camera = mr_m4_look_at_cv(mr_v3(0.7, 2.1, -2.1), mr_v3(0.2, 0.2, 2.5), mr_v3(0, 1, 0));
            ao.temporal = false;
            ao.samples = 64;
            render_ao_fp(s, &a2, &ao, &ref);
            ao.samples = 4;
            render_ao_fp(s, &a2, &ao, &single);
            ao.temporal = true;
            for (int k = 0; k < 16; k++) {
                ao.temporal_reset = k == 0;
                render_ao_fp(s, &a, &ao, &acc);
            }
            ao.temporal_reset = false;
            render_ao_fp(s, &a2, &ao, &acc);
            double e1 = rmse(&single, &ref), ea = rmse(&acc, &ref);
            if (getenv("MR_TEST_VERBOSE")) printf("temporal %s step: one frame %.4f, with history %.4f\n", name, e1, ea);
            CHECK_MSG(ea < 0.8 * e1, "temporal %s: after a step the history was lost (RMSE %.4f, one frame %.4f)", name, ea, e1);
        }
        /* Jumps, after a history at the corner view: with a tracking reset
         * the frame is the fresh one exactly (frame 0's noise); without a
         * reset, to a view of the other side of the wall (nothing in
         * common), every pixel's history is rejected: the frame is as far
         * from the 64-sample AO as a fresh single frame (another frame's
         * noise, so not equal to it), where a kept history would be the
         * other view's AO. */
        for (int reset = 1; reset >= 0; reset--) {
            mr_view a = mr_test_ao_corner_view(1, o, w, h), b = a;
            b.world_from_camera = reset ? mr_m4_look_at_cv(mr_v3(-3, 1.5, 0.5), mr_v3(2, 0.2, 2.8), mr_v3(0, 1, 0))
                                        : mr_m4_look_at_cv(mr_v3(1, 2, 8), mr_v3(0.5, 0.5, 3.2), mr_v3(0, 1, 0));
            ao.temporal = true;
            for (int k = 0; k < 5; k++) {
                ao.temporal_reset = k == 0;
                render_ao_fp(s, &a, &ao, &acc);
            }
            ao.temporal_reset = reset;
            render_ao_fp(s, &b, &ao, &acc);
            ao.temporal = false;
            ao.temporal_reset = false;
            render_ao_fp(s, &b, &ao, &fresh);
            double e = rmse(&acc, &fresh);
            if (getenv("MR_TEST_VERBOSE")) printf("temporal %s jump %s: RMSE against a fresh frame %.6f\n", name, reset ? "with reset" : "no reset", e);
            if (reset) {
                CHECK_MSG(e < 1e-6, "temporal %s: after a tracking reset the frame differs from a fresh one: RMSE %.6f (a ghost)",
                          name, e);
            } else {
                ao.samples = 64;
                render_ao_fp(s, &b, &ao, &ref);
                ao.samples = 4;
                double ej = rmse(&acc, &ref), ef = rmse(&fresh, &ref);
                if (getenv("MR_TEST_VERBOSE")) printf("temporal %s jump no reset: %.4f, fresh %.4f against 64 samples\n", name, ej, ef);
                CHECK_MSG(ej < 1.15 * ef + 0.003, "temporal %s: after a jump to a view with nothing in common RMSE %.4f, a fresh "
                          "frame %.4f (a ghost of the previous view)", name, ej, ef);
            }
        }
        mr_image_free(&ref);
        mr_image_free(&single);
        mr_image_free(&acc);
        mr_image_free(&fresh);
    }
    /* Off, single frames do not accumulate: the pass list has no ao_temporal. */
    mr_ao_params off = MR_AO_DEFAULTS;
    off.method = MR_AO_SCHEER;
    mr_view v = mr_test_ao_corner_view(1, o, w, h);
    mr_frame_result res;
    if (mr_test_render_ao(g_r, s, &v, &off, &res)) {
        char buf[512];
        mr_frame_result_passes(&res, buf, sizeof buf);
        CHECK_MSG(strstr(buf, "ao_temporal") == NULL, "temporal accumulation ran while off: %s", buf);
        mr_frame_result_free(&res);
    }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

int main(void) {
    test_kernels();
    test_outline_volume();
    test_groundtruth_wall();
    test_metrics();
    mr_error err = {0};
    g_gpu = mr_gpu_create_headless(NULL, &err);
    if (!g_gpu) {
        /* Only a missing device is a skip; any other failure is a failure. */
        CHECK_MSG(err.code == MR_ERR_NODEVICE, "no headless GL context: %s", err.msg);
        if (err.code == MR_ERR_NODEVICE) fprintf(stderr, "test_ao: GPU tests SKIPPED: %s\n", err.msg);
        int rc = mr_test_finish("test_ao (CPU part)");
        return rc ? rc : MR_TEST_SKIP;
    }
    g_r = mr_renderer_create(g_gpu, &err);
    CHECK_MSG(g_r != NULL, "%s", err.msg);
    if (g_r) {
        test_flat_plane();
        test_corner_all_methods();
        test_groundtruth_pixels();
        test_scale_invariance();
        test_half_res();
        test_finite();
        test_pass_list();
        test_mask();
        test_pinned_reference();
        test_golden();
        test_mask_count();
        test_mask_retains();
        test_mask_standalone();
        test_radii();
        test_slice_wall();
        test_temporal();
        test_scheer_bm(); /* issue 18 (lane ao) */
        test_mips();
    }
    mr_renderer_destroy(&g_r);
    mr_gpu_destroy(&g_gpu);
    return mr_test_finish("test_ao");
}
