/* Cluster culling (issue 17, lane meshlet): a big mesh is split into
 * meshlets at upload and each draw keeps only those whose bounding spheres
 * reach the view. It must never remove a visible cluster: over 40 random
 * views (inside and outside the meshes, near and far, also 1e7 units from
 * the origin) the depth image with culling is byte-identical to the one
 * without (both draw the same reordered index buffer, the kept triangles in
 * the same order, so the same fragments win the depth test); a view that
 * sees part of the mesh submits fewer triangles. The back-facing cone test
 * (closed solids only) keeps the image of a closed sphere seen from
 * outside. Skips (77) where no EGL device exists. */
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A closed sphere of nu * nv * 2 triangles, bumps so clusters differ. */
static mr_mesh big_sphere(double r, int nu, int nv) { return mr_test_sphere_mesh("big_sphere", r, nu, nv, 0.03, 7, 5); }

static mr_gpu *g_gpu;
static mr_renderer *g_r;

static uint64_t g_rng = 0x9e3779b97f4a7c15ull;
static double rnd(void) { /* uniform [0, 1) */
    g_rng = g_rng * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(g_rng >> 11) / 9007199254740992.0;
}

/* An open, wavy sheet (both faces visible: the cone test must not run). */
static mr_mesh sheet(double size, int n) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "big_sheet");
    m.vertex_count = (uint32_t)((n + 1) * (n + 1));
    m.index_count = (uint32_t)(n * n * 6);
    m.positions = malloc((size_t)m.vertex_count * 12);
    m.indices = malloc((size_t)m.index_count * 4);
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++) {
            float *p = m.positions + 3 * (size_t)(i * (n + 1) + j);
            double x = size * ((double)i / n - 0.5), z = size * ((double)j / n - 0.5);
            p[0] = (float)x;
            p[1] = (float)(0.2 * sin(2 * x) * cos(3 * z));
            p[2] = (float)z;
        }
    uint32_t ni = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            uint32_t a = (uint32_t)(i * (n + 1) + j), b = a + (uint32_t)(n + 1);
            uint32_t q[6] = {a, a + 1, b, a + 1, b + 1, b};
            for (int k = 0; k < 6; k++) m.indices[ni++] = q[k];
        }
    m.material = -1;
    return m;
}

static mr_scene *big_scene(double ox, bool with_sheet) {
    mr_error err = {0};
    mr_scene *s = mr_scene_create();
    mr_mesh a = big_sphere(2.0, 160, 80); /* 25.6k triangles */
    int32_t ma = mr_scene_add_mesh(s, &a, &err);
    int32_t mb = -1;
    if (with_sheet) {
        mr_mesh b = sheet(12.0, 100); /* 20k triangles */
        mb = mr_scene_add_mesh(s, &b, &err);
    }
    CHECK_MSG(ma >= 0 && (!with_sheet || mb >= 0), "%s", err.msg);
    for (int k = 0; k < (with_sheet ? 2 : 1); k++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, k ? "Sheet" : "Ball");
        n.parent = -1;
        n.world = k ? mr_m4_translate(ox, -2.5, 0) : mr_m4_translate(ox, 0, 0);
        if (!k) { /* a similarity (rotation + uniform scale): radii and cones scale */
            mr_dmat4 R = mr_m4_rotate_axis(mr_v3(0, 1, 0), 0.7), S = mr_m4_scale(1.25, 1.25, 1.25), RS = mr_m4_mul(&R, &S);
            n.world = mr_m4_mul(&n.world, &RS);
        }
        n.mesh_first = k ? mb : ma;
        n.mesh_count = 1;
        mr_scene_add_node(s, &n);
    }
    /* Small balls after the big meshes: their commands follow the
     * meshlets' (a per-node submission must find room for both). */
    mr_mesh c = big_sphere(0.2, 8, 4);
    int32_t mc = mr_scene_add_mesh(s, &c, &err);
    for (int k = 0; k < 40 && mc >= 0; k++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "Small_%d", k);
        n.parent = -1;
        n.world = mr_m4_translate(ox + (k % 8) - 3.5, 3.2, (k / 8) - 2.0);
        n.mesh_first = mc;
        n.mesh_count = 1;
        mr_scene_add_node(s, &n);
    }
    mr_scene_update_bounds(s);
    return s;
}

static bool frame(const mr_view *v, const mr_draw_params *dp, mr_frame_result *res, mr_draw_stats *st) {
    mr_error err = {0};
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = v->camera.width;
    fp.height = v->camera.height;
    fp.want_depth = true;
    bool ok = mr_renderer_set_draw_params(g_r, dp, &err) && mr_render_frame(g_r, v, &fp, res, &err);
    CHECK_MSG(ok, "%s", err.msg);
    if (ok && st) mr_renderer_draw_stats(g_r, st);
    return ok;
}

/* Pixels that see geometry (background depth is 0 or not finite). */
static size_t covered(const mr_frame_result *a) {
    size_t n = (size_t)a->depth.width * a->depth.height, c = 0;
    const float *p = a->depth.data;
    for (size_t i = 0; p && i < n; i++) c += isfinite(p[i]) && p[i] > 0;
    return c;
}

static bool same_depth(const mr_frame_result *a, const mr_frame_result *b) {
    if (a->depth.width != b->depth.width || a->depth.height != b->depth.height || !a->depth.data || !b->depth.data)
        return false;
    size_t n = (size_t)a->depth.width * a->depth.height, bad = 0;
    const float *pa = a->depth.data, *pb = b->depth.data;
    double worst = 0;
    for (size_t i = 0; i < n; i++)
        if (memcmp(pa + i, pb + i, sizeof *pa) != 0) {
            bad++;
            if (fabs((double)pa[i] - pb[i]) > worst) worst = fabs((double)pa[i] - pb[i]);
        }
    if (bad) printf("  %zu of %zu depth pixels differ, by up to %g (%g vs %g)\n", bad, n, worst, pa[n / 2], pb[n / 2]);
    return bad == 0;
}

/* Random views around the meshes at offset ox: eyes inside and outside
 * the sphere and under the sheet, targets near the meshes or off to the
 * side (so the frustum cuts the mesh). With cone, only outside eyes. */
static mr_view random_view(double ox, bool outside) {
    double dist = outside ? 3.2 + 9 * rnd() : 0.5 + 9 * rnd();
    double th = acos(2 * rnd() - 1), ph = 6.283185307179586 * rnd();
    mr_dvec3 eye = mr_v3(ox + dist * sin(th) * cos(ph), dist * cos(th), dist * sin(th) * sin(ph));
    mr_dvec3 at = mr_v3(ox + 4 * (rnd() - 0.5), 4 * (rnd() - 0.5), 4 * (rnd() - 0.5));
    double f = 80 + 200 * rnd();
    mr_view v = {{128, 96, f, f, 63.5, 47.5, {0}}, mr_m4_look_at_cv(eye, at, mr_v3(0.1, 1, 0.05))};
    return v;
}

static void views_same(double ox) {
    mr_error err = {0};
    mr_scene *s = big_scene(ox, true);
    mr_draw_params on = MR_DRAW_DEFAULTS, off = MR_DRAW_DEFAULTS, cone = MR_DRAW_DEFAULTS;
    on.occlusion_auto = off.occlusion_auto = cone.occlusion_auto = false;
    off.no_cluster_cull = true;
    mr_draw_params each = on; /* one command per node and mesh, one GL call per command */
    each.no_batch = each.no_instancing = true;
    cone.cluster_cone = true;
    if (!s || !mr_renderer_set_scene(g_r, s, &err)) {
        CHECK_MSG(false, "%s", err.msg);
        mr_scene_destroy(&s);
        return;
    }
    int fewer = 0, cut = 0, seen = 0;
    for (int i = 0; i < 40; i++) {
        mr_view v = random_view(ox, false);
        mr_frame_result a, b;
        mr_draw_stats sa, sb;
        if (!frame(&v, &on, &a, &sa)) break;
        if (!frame(&v, &off, &b, &sb)) {
            mr_frame_result_free(&a);
            break;
        }
        CHECK_MSG(same_depth(&a, &b), "offset %g view %d: depth differs with cluster culling", ox, i);
        if (i % 8 == 0) {
            mr_frame_result e;
            if (frame(&v, &each, &e, NULL)) {
                CHECK_MSG(same_depth(&e, &b), "offset %g view %d: per-node submission differs", ox, i);
                mr_frame_result_free(&e);
            }
        }
        CHECK(sa.clusters_tested > 0 && sb.clusters_tested == 0);
        CHECK(sa.triangles <= sb.triangles);
        fewer += sa.triangles < sb.triangles;
        seen += covered(&b) > 200;
        cut += sa.clusters_drawn < sa.clusters_tested;
        mr_frame_result_free(&a);
        mr_frame_result_free(&b);
    }
    CHECK_MSG(seen >= 20, "offset %g: only %d of 40 views see the meshes", ox, seen);
    CHECK_MSG(fewer >= 10, "offset %g: only %d of 40 views submitted fewer triangles", ox, fewer);
    printf("offset %g: %d of 40 random views see the meshes, %d submit fewer triangles (%d cut clusters)\n", ox, seen,
           fewer, cut);

    /* A view that sees a corner of the sheet and part of the ball. */
    mr_view part = {{128, 96, 200, 200, 63.5, 47.5, {0}},
                    mr_m4_look_at_cv(mr_v3(ox + 3, 0.5, -6), mr_v3(ox + 2.2, -0.5, 0), mr_v3(0, 1, 0))};
    mr_frame_result a, b;
    mr_draw_stats sa, sb;
    if (frame(&part, &on, &a, &sa) && frame(&part, &off, &b, &sb)) {
        CHECK(same_depth(&a, &b));
        CHECK_MSG(sa.triangles * 2 < sb.triangles, "partial view: %llu of %llu triangles submitted",
                  (unsigned long long)sa.triangles, (unsigned long long)sb.triangles);
        printf("offset %g partial view: %llu of %llu triangles, %llu of %llu clusters\n", ox,
               (unsigned long long)sa.triangles, (unsigned long long)sb.triangles, (unsigned long long)sa.clusters_drawn,
               (unsigned long long)sa.clusters_tested);
        mr_frame_result_free(&a);
        mr_frame_result_free(&b);
    }
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_scene_destroy(&s);

    /* The cone test on the closed ball alone, from outside. */
    s = big_scene(ox, false);
    if (!s || !mr_renderer_set_scene(g_r, s, &err)) {
        CHECK_MSG(false, "%s", err.msg);
        mr_scene_destroy(&s);
        return;
    }
    int backs = 0;
    for (int i = 0; i < 12; i++) {
        mr_view v = random_view(ox, true);
        mr_frame_result c, d;
        mr_draw_stats sc, sd;
        if (!frame(&v, &cone, &c, &sc)) break;
        if (!frame(&v, &on, &d, &sd)) {
            mr_frame_result_free(&c);
            break;
        }
        CHECK_MSG(same_depth(&c, &d), "offset %g cone view %d: depth differs with the cone test", ox, i);
        backs += sc.clusters_drawn < sd.clusters_drawn;
        mr_frame_result_free(&c);
        mr_frame_result_free(&d);
    }
    CHECK_MSG(backs >= 6, "offset %g: the cone test removed clusters in only %d of 12 views", ox, backs);
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_scene_destroy(&s);
}

static void test_views_origin(void) { views_same(0); }
static void test_views_far(void) { views_same(1e7); }

/* A mesh below the threshold is not split (nothing tested). */
static void test_threshold(void) {
    mr_error err = {0};
    mr_scene *s = big_scene(0, false);
    mr_draw_params dp = MR_DRAW_DEFAULTS;
    dp.cluster_triangles = 1 << 20;
    CHECK(mr_renderer_set_draw_params(g_r, &dp, &err));
    if (s && mr_renderer_set_scene(g_r, s, &err)) {
        mr_view v = random_view(0, true);
        mr_frame_result a;
        mr_draw_stats st;
        if (frame(&v, &dp, &a, &st)) {
            CHECK(st.clusters_tested == 0 && st.triangles > 0);
            mr_frame_result_free(&a);
        }
    }
    mr_renderer_set_draw_params(g_r, NULL, &err);
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_scene_destroy(&s);
}

int main(void) {
    mr_error err = {0};
    g_gpu = mr_gpu_create_headless(NULL, &err);
    if (!g_gpu) return mr_test_no_gpu("test_meshlet", &err);
    g_r = mr_renderer_create(g_gpu, &err);
    CHECK_MSG(g_r != NULL, "%s", err.msg);
    if (g_r) {
        mr_renderer_set_draw_params(g_r, NULL, &err);
        test_views_origin();
        test_views_far();
        test_threshold();
    }
    mr_renderer_destroy(&g_r);
    mr_gpu_destroy(&g_gpu);
    return mr_test_finish("test_meshlet");
}
