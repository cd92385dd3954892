/* Cluster culling (issue 17, lane meshlet): a big mesh is split into
 * meshlets at upload and each draw keeps only those whose bounding spheres
 * reach the view. It must never remove a visible cluster: over 40 random
 * views (inside and outside the meshes, near and far, also 1e7 units from
 * the origin) the depth image with culling is byte-identical to the one
 * without (both draw the same reordered index buffer, the kept triangles in
 * the same order, so the same fragments win the depth test); a view that
 * sees part of the mesh submits fewer triangles. The back-facing cone test
 * (issue 17, lane cluster: single-sided materials only, where the G-buffer
 * culls back faces) keeps the image byte for byte over random views, also
 * at a 1e7 offset and at scales 1e-3 and 1e3, and skips meshlets.
 * Skips (77) where no EGL device exists. */
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* issue 17 (lane cluster): sc scales the whole scene (1e-3 .. 1e3); mirror
 * gives the ball a mirroring transform (det < 0) and single a single-sided
 * material (glTF doubleSided = false: back faces culled, cones tested). */
static mr_scene *big_scene_ex(double ox, bool with_sheet, double sc, bool single, bool mirror) {
    mr_error err = {0};
    mr_scene *s = mr_scene_create();
    mr_material mat = {"ball", {0.8f, 0.6f, 0.3f, 1}, -1, single};
    int32_t mt = mr_scene_add_material(s, &mat);
    mr_mesh a = big_sphere(2.0 * sc, 160, 80); /* 25.6k triangles */
    a.material = mt;
    int32_t ma = mr_scene_add_mesh(s, &a, &err);
    int32_t mb = -1;
    if (with_sheet) {
        mr_mesh b = sheet(12.0 * sc, 100); /* 20k triangles */
        mb = mr_scene_add_mesh(s, &b, &err);
    }
    CHECK_MSG(ma >= 0 && (!with_sheet || mb >= 0), "%s", err.msg);
    for (int k = 0; k < (with_sheet ? 2 : 1); k++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, k ? "Sheet" : "Ball");
        n.parent = -1;
        n.world = k ? mr_m4_translate(ox, -2.5 * sc, 0) : mr_m4_translate(ox, 0, 0);
        if (!k) { /* a similarity (rotation + uniform scale): radii and cones scale */
            double mx = mirror ? -1.25 : 1.25;
            mr_dmat4 R = mr_m4_rotate_axis(mr_v3(0, 1, 0), 0.7), S = mr_m4_scale(mx, 1.25, 1.25), RS = mr_m4_mul(&R, &S);
            n.world = mr_m4_mul(&n.world, &RS);
        }
        n.mesh_first = k ? mb : ma;
        n.mesh_count = 1;
        mr_scene_add_node(s, &n);
    }
    /* Small balls after the big meshes: their commands follow the
     * meshlets' (a per-node submission must find room for both). */
    mr_mesh c = big_sphere(0.2 * sc, 8, 4);
    int32_t mc = mr_scene_add_mesh(s, &c, &err);
    for (int k = 0; k < 40 && mc >= 0; k++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "Small_%d", k);
        n.parent = -1;
        n.world = mr_m4_translate(ox + sc * ((k % 8) - 3.5), sc * 3.2, sc * ((k / 8) - 2.0));
        n.mesh_first = mc;
        n.mesh_count = 1;
        mr_scene_add_node(s, &n);
    }
    mr_scene_update_bounds(s);
    return s;
}
static mr_scene *big_scene(double ox, bool with_sheet) { return big_scene_ex(ox, with_sheet, 1, false, false); }

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
static mr_view random_view_sc(double ox, bool outside, double sc) {
    double dist = sc * (outside ? 3.2 + 9 * rnd() : 0.5 + 9 * rnd());
    double th = acos(2 * rnd() - 1), ph = 6.283185307179586 * rnd();
    mr_dvec3 eye = mr_v3(ox + dist * sin(th) * cos(ph), dist * cos(th), dist * sin(th) * sin(ph));
    mr_dvec3 at = mr_v3(ox + sc * 4 * (rnd() - 0.5), sc * 4 * (rnd() - 0.5), sc * 4 * (rnd() - 0.5));
    double f = 80 + 200 * rnd();
    mr_view v = {{128, 96, f, f, 63.5, 47.5, {0}}, mr_m4_look_at_cv(eye, at, mr_v3(0.1, 1, 0.05))};
    return v;
}
static mr_view random_view(double ox, bool outside) { return random_view_sc(ox, outside, 1); }

static void views_same(double ox) {
    mr_error err = {0};
    mr_scene *s = big_scene(ox, true);
    mr_draw_params on = MR_DRAW_DEFAULTS, off = MR_DRAW_DEFAULTS;
    on.occlusion_auto = off.occlusion_auto = false;
    off.no_cluster_cull = true;
    mr_draw_params each = on; /* one command per node and mesh, one GL call per command */
    each.no_batch = each.no_instancing = true;
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

}

/* Depth equal within rel (relative) wherever either sees geometry, and
 * coverage the same: where a back face and the front face that shares its
 * silhouette edge interpolate depth a hair apart, a double-sided draw may
 * let the back one win a pixel. */
static bool near_depth(const mr_frame_result *a, const mr_frame_result *b, double rel) {
    size_t n = (size_t)a->depth.width * a->depth.height, bad = 0;
    const float *pa = a->depth.data, *pb = b->depth.data;
    if (!pa || !pb || a->depth.width != b->depth.width || a->depth.height != b->depth.height) return false;
    for (size_t i = 0; i < n; i++) {
        bool ca = isfinite(pa[i]) && pa[i] > 0, cb = isfinite(pb[i]) && pb[i] > 0;
        if (ca != cb || (ca && fabs((double)pa[i] - pb[i]) > rel * pa[i])) bad++;
    }
    if (bad) printf("  %zu of %zu depth pixels differ by more than %g (relative)\n", bad, n, rel);
    return bad == 0;
}

static bool same_color(const mr_frame_result *a, const mr_frame_result *b) {
    size_t n = mr_image_bytes(&a->color);
    if (n != mr_image_bytes(&b->color) || !a->color.data || !b->color.data) return false;
    size_t bad = 0;
    for (size_t i = 0; i < n; i++) bad += ((const uint8_t *)a->color.data)[i] != ((const uint8_t *)b->color.data)[i];
    if (bad) printf("  %zu of %zu colour bytes differ\n", bad, n);
    return bad == 0;
}

/* issue 17 (lane cluster): the cone test on the closed single-sided ball
 * (glTF doubleSided = false: the G-buffer culls its back faces). Over
 * random views from outside and inside, the image (colour and depth) with
 * cone culling is byte-identical to the one without, and from outside it
 * skips meshlets. A double-sided ball never tests cones; a mirrored one
 * (det < 0: clockwise front faces) is drawn, not culled away, and tests
 * no cones either. */
static void cone_views(double ox, double sc, bool mirror) {
    mr_error err = {0};
    mr_scene *s = big_scene_ex(ox, false, sc, true, mirror);
    if (!s || !mr_renderer_set_scene(g_r, s, &err)) {
        CHECK_MSG(false, "%s", err.msg);
        mr_scene_destroy(&s);
        return;
    }
    mr_draw_params cone = MR_DRAW_DEFAULTS, nocone = MR_DRAW_DEFAULTS;
    cone.occlusion_auto = nocone.occlusion_auto = false;
    nocone.no_cluster_cone = true;
    int backs = 0, seen = 0;
    uint64_t skipped = 0;
    mr_frame_result keep[24];
    mr_view views[24];
    memset(keep, 0, sizeof keep);
    for (int i = 0; i < 24; i++) {
        mr_view v = random_view_sc(ox, i % 4 != 3, sc);
        views[i] = v;
        mr_frame_result c, d;
        mr_draw_stats sc_, sd;
        if (!frame(&v, &cone, &c, &sc_)) break;
        if (!frame(&v, &nocone, &d, &sd)) {
            mr_frame_result_free(&c);
            break;
        }
        CHECK_MSG(same_depth(&c, &d) && same_color(&c, &d), "offset %g scale %g%s view %d: image differs with the cone test",
                  ox, sc, mirror ? " mirrored" : "", i);
        CHECK(sc_.clusters_drawn <= sd.clusters_drawn && sd.clusters_tested == sc_.clusters_tested);
        backs += sc_.clusters_drawn < sd.clusters_drawn;
        skipped += sd.clusters_drawn - sc_.clusters_drawn;
        seen += covered(&d) > 200;
        mr_frame_result_free(&c);
        keep[i] = d;
    }
    CHECK_MSG(seen >= 12, "offset %g scale %g: only %d of 24 views see the ball", ox, sc, seen);
    if (mirror) CHECK_MSG(backs == 0, "offset %g scale %g: cones tested under a mirror", ox, sc);
    else CHECK_MSG(backs >= 12, "offset %g scale %g: the cone test removed meshlets in only %d of 24 views", ox, sc, backs);
    printf("offset %g scale %g%s: cone test skipped meshlets in %d of 24 views (%llu in all)\n", ox, sc,
           mirror ? " mirrored" : "", backs, (unsigned long long)skipped);

    /* From the back of the part: a view at the ball's -z side sees only
     * its half; the cone test skips more than a third of the meshlets. */
    mr_view back = {{128, 96, 120, 120, 63.5, 47.5, {0}},
                    mr_m4_look_at_cv(mr_v3(ox, 0.3 * sc, -9 * sc), mr_v3(ox, 0, 0), mr_v3(0, 1, 0))};
    mr_frame_result c, d;
    mr_draw_stats st, sn;
    if (frame(&back, &cone, &c, &st) && frame(&back, &nocone, &d, &sn)) {
        CHECK(same_depth(&c, &d) && same_color(&c, &d));
        CHECK_MSG(covered(&d) > 1000, "the back view sees %zu pixels of the ball", covered(&d));
        if (!mirror)
            CHECK_MSG(st.clusters_drawn * 3 < sn.clusters_drawn * 2, "back view: %llu of %llu meshlets drawn with cones",
                      (unsigned long long)st.clusters_drawn, (unsigned long long)sn.clusters_drawn);
        mr_frame_result_free(&c);
        mr_frame_result_free(&d);
    }
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_scene_destroy(&s);

    /* Seen from outside, the closed ball looks the same (depth) drawn
     * double-sided: the culled faces were all hidden, none in front was
     * culled (a wrong front face, e.g. under the mirror, fails here). */
    s = big_scene_ex(ox, false, sc, false, mirror);
    if (!s || !mr_renderer_set_scene(g_r, s, &err)) CHECK_MSG(false, "%s", err.msg);
    for (int i = 0; s && i < 24; i++) {
        mr_frame_result e;
        if (i % 4 != 3 && keep[i].depth.data && frame(&views[i], &nocone, &e, NULL)) {
            CHECK_MSG(near_depth(&e, &keep[i], 1e-2), "offset %g scale %g%s view %d: single-sided depth differs from double-sided",
                      ox, sc, mirror ? " mirrored" : "", i);
            mr_frame_result_free(&e);
        }
        mr_frame_result_free(&keep[i]);
    }
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_scene_destroy(&s);
}

/* Back faces of single-sided materials are culled in the G-buffer (an
 * open sheet seen from below disappears), of double-sided ones not. */
static void single_sided_culls(void) {
    mr_error err = {0};
    for (int single = 0; single < 2; single++) {
        mr_scene *s = mr_scene_create();
        mr_material mat = {"sheet", {0.5f, 0.5f, 0.5f, 1}, -1, single != 0};
        mr_mesh b = sheet(12.0, 20);
        b.material = mr_scene_add_material(s, &mat);
        int32_t mb = mr_scene_add_mesh(s, &b, &err);
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "Sheet");
        n.parent = -1;
        n.world = mr_m4_identity();
        n.mesh_first = mb;
        n.mesh_count = 1;
        mr_scene_add_node(s, &n);
        mr_scene_update_bounds(s);
        CHECK_MSG(mr_renderer_set_scene(g_r, s, &err), "%s", err.msg);
        mr_draw_params dp = MR_DRAW_DEFAULTS;
        dp.occlusion_auto = false;
        size_t px[2];
        for (int below = 0; below < 2; below++) {
            mr_view v = {{128, 96, 100, 100, 63.5, 47.5, {0}},
                         mr_m4_look_at_cv(mr_v3(0.5, below ? -5 : 5, 0.3), mr_v3(0, 0, 0), mr_v3(0, 0, 1))};
            mr_frame_result a;
            px[below] = 0;
            if (frame(&v, &dp, &a, NULL)) {
                px[below] = covered(&a);
                mr_frame_result_free(&a);
            }
        }
        CHECK_MSG(px[0] > 5000, "%s sheet from above: %zu pixels", single ? "single-sided" : "double-sided", px[0]);
        if (single) CHECK_MSG(px[1] == 0, "single-sided sheet from below: %zu pixels drawn", px[1]);
        else CHECK_MSG(px[1] > 5000, "double-sided sheet from below: %zu pixels", px[1]);
        mr_renderer_set_scene(g_r, NULL, &err);
        mr_scene_destroy(&s);
    }
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

/* issue 17 (lane cluster): the meshlet cache beside the file. A first
 * upload builds and writes it; the next reads every clustered level from
 * it, and both draw byte-identical images with the same meshlet counts.
 * A truncated, damaged (one flipped byte), foreign (garbage) or stale
 * (another threshold, another geometry) file is ignored: the levels are
 * built, the image is the same, the file is rewritten; never a crash. */
typedef struct shot {
    mr_frame_result res[4];
    uint64_t drawn[4];
} shot;

static void take(mr_scene *s, const char *cache, const mr_draw_params *dp, shot *out, mr_cluster_info *ci) {
    mr_error err = {0};
    CHECK(mr_renderer_set_cluster_cache(g_r, cache, &err));
    CHECK(mr_renderer_set_draw_params(g_r, dp, &err));
    CHECK_MSG(mr_renderer_set_scene(g_r, s, &err), "%s", err.msg);
    mr_renderer_cluster_info(g_r, ci);
    g_rng = 0x1234567ull;
    for (int i = 0; i < 4; i++) {
        mr_view v = random_view(0, i != 3);
        mr_draw_stats st;
        memset(&out->res[i], 0, sizeof out->res[i]);
        out->drawn[i] = frame(&v, dp, &out->res[i], &st) ? st.clusters_drawn : 0;
    }
    mr_renderer_set_cluster_cache(g_r, NULL, &err);
}

static void same_shots(shot *a, shot *b, const char *what) {
    for (int i = 0; i < 4; i++) {
        CHECK_MSG(same_depth(&a->res[i], &b->res[i]) && same_color(&a->res[i], &b->res[i]), "%s: view %d differs", what, i);
        CHECK_MSG(a->drawn[i] == b->drawn[i] && a->drawn[i] > 0, "%s: view %d draws %llu vs %llu meshlets", what, i,
                  (unsigned long long)a->drawn[i], (unsigned long long)b->drawn[i]);
        mr_frame_result_free(&b->res[i]);
    }
}

static long file_size(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fclose(f);
    return n;
}

static void test_cache(void) {
    char dir[4096], path[4200];
    if (!mr_test_fresh_dir("test_meshlet", dir, sizeof dir)) {
        CHECK_MSG(false, "no scratch folder");
        return;
    }
    snprintf(path, sizeof path, "%s/scene.glb.mrclu", dir);
    mr_error err = {0};
    mr_scene *s = big_scene_ex(0, true, 1, true, false);
    mr_draw_params dp = MR_DRAW_DEFAULTS;
    dp.occlusion_auto = false;
    shot ref, got;
    mr_cluster_info ci;
    take(s, NULL, &dp, &ref, &ci); /* no cache: the reference */
    CHECK(ci.levels_built == 2 && ci.levels_cached == 0 && !ci.cache_written);
    take(s, path, &dp, &got, &ci);
    CHECK_MSG(ci.levels_built == 2 && ci.levels_cached == 0 && ci.cache_written, "first upload: %llu built, %llu cached",
              (unsigned long long)ci.levels_built, (unsigned long long)ci.levels_cached);
    same_shots(&ref, &got, "built with a cache");
    take(s, path, &dp, &got, &ci);
    CHECK_MSG(ci.levels_cached == 2 && ci.levels_built == 0 && !ci.cache_written, "second upload: %llu built, %llu cached",
              (unsigned long long)ci.levels_built, (unsigned long long)ci.levels_cached);
    same_shots(&ref, &got, "read from the cache");
    long size = file_size(path);
    CHECK(size > 1000);
    /* Damage: truncated, one byte flipped in the middle and near the end,
     * garbage; each is ignored, rebuilt and rewritten. */
    for (int k = 0; k < 4 && size > 1000; k++) {
        FILE *f = fopen(path, "r+b");
        if (!f) break;
        if (k == 0) {
            CHECK(ftruncate(fileno(f), size / 2) == 0);
        } else if (k < 3) {
            long at = k == 1 ? size / 2 : size - 3;
            fseek(f, at, SEEK_SET);
            int ch = fgetc(f);
            fseek(f, at, SEEK_SET);
            fputc(ch ^ 0x10, f);
        } else {
            for (long i = 0; i < size; i++) fputc((int)((i * 7919) & 0xff), f);
        }
        fclose(f);
        take(s, path, &dp, &got, &ci);
        CHECK_MSG(ci.levels_built == 2 && ci.levels_cached == 0 && ci.cache_written, "damage %d: %llu built, %llu cached", k,
                  (unsigned long long)ci.levels_built, (unsigned long long)ci.levels_cached);
        same_shots(&ref, &got, "rebuilt after damage");
        CHECK(file_size(path) == size);
    }
    /* Stale: another threshold (a whole other cache) ... */
    mr_draw_params dt = dp;
    dt.cluster_triangles = 20000; /* the sheet (20k) is still clustered, the ball too */
    take(s, path, &dt, &got, &ci);
    CHECK(ci.levels_built == 2 && ci.levels_cached == 0);
    same_shots(&ref, &got, "another threshold");
    take(s, path, &dp, &got, &ci); /* back: built again (the file was for 20000) */
    CHECK(ci.levels_built == 2 && ci.levels_cached == 0);
    mr_frame_result_free(&got.res[0]), mr_frame_result_free(&got.res[1]), mr_frame_result_free(&got.res[2]),
        mr_frame_result_free(&got.res[3]);
    /* ... and another geometry: the ball's level misses, the sheet's hits. */
    mr_renderer_set_scene(g_r, NULL, &err);
    for (uint32_t v = 0; v < s->meshes[0].vertex_count; v += 97) s->meshes[0].positions[3 * v] *= 1.01f;
    take(s, path, &dp, &got, &ci);
    CHECK_MSG(ci.levels_built == 1 && ci.levels_cached == 1, "changed ball: %llu built, %llu cached",
              (unsigned long long)ci.levels_built, (unsigned long long)ci.levels_cached);
    for (int i = 0; i < 4; i++) mr_frame_result_free(&got.res[i]);
    for (int i = 0; i < 4; i++) mr_frame_result_free(&ref.res[i]);
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_renderer_set_draw_params(g_r, NULL, &err);
    mr_scene_destroy(&s);
    remove(path);
}

/* issue 17 (lane cluster): meshlets of the nodes that pass the occlusion
 * test are tested against the same depth pyramid. A wall hides part of a
 * grid of 96 balls (small on screen, so they are tested, not occluders),
 * some before it;
 * over 12 views the image with meshlet occlusion is byte-identical to the
 * one without and to the one without any occlusion culling, also at a
 * 1e7 offset, and meshlets of partly hidden balls are skipped. */
static void test_cluster_occlusion(double ox) {
    mr_error err = {0};
    mr_scene *s = mr_scene_create();
    mr_material mat = {"ball", {0.8f, 0.6f, 0.3f, 1}, -1, true};
    int32_t mt = mr_scene_add_material(s, &mat);
    mr_mesh ball = big_sphere(0.35, 48, 24); /* 2304 triangles: clustered with the threshold below */
    ball.material = mt;
    int32_t mb = mr_scene_add_mesh(s, &ball, &err);
    mr_mesh wall = sheet(1.0, 4);        /* 32 triangles, a unit square */
    int32_t mw = mr_scene_add_mesh(s, &wall, &err);
    CHECK_MSG(mb >= 0 && mw >= 0, "%s", err.msg);
    for (int k = 0; k < 96; k++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "Ball_%d", k);
        n.parent = -1;
        n.world = mr_m4_translate(ox + (k % 12) - 5.5, (k / 12) * 0.8 - 2.8, 4.4 + 0.6 * (k % 5)); /* before and behind the wall */
        n.mesh_first = mb;
        n.mesh_count = 1;
        mr_scene_add_node(s, &n);
    }
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "Wall");
    n.parent = -1;
    /* the sheet lies in y = 0: stand it up (normal towards -z, the camera) */
    mr_dmat4 T = mr_m4_translate(ox - 3.3, 0, 5.4), R = mr_m4_rotate_axis(mr_v3(1, 0, 0), 1.5707963267948966),
             S = mr_m4_scale(7, 1, 9), TR = mr_m4_mul(&T, &R);
    n.world = mr_m4_mul(&TR, &S);
    n.mesh_first = mw;
    n.mesh_count = 1;
    mr_scene_add_node(s, &n);
    mr_scene_update_bounds(s);
    mr_draw_params on = MR_DRAW_DEFAULTS;
    on.occlusion = true;
    on.cluster_triangles = 2000;
    mr_draw_params off = on, none = on;
    off.no_cluster_occlusion = true;
    none.occlusion = false;
    none.occlusion_auto = false;
    CHECK(mr_renderer_set_draw_params(g_r, &on, &err));
    CHECK_MSG(mr_renderer_set_scene(g_r, s, &err), "%s", err.msg);
    uint64_t occl = 0, fewer = 0;
    g_rng = 0x5eed5eedull; /* the same views whatever ran before */
    for (int i = 0; i < 12; i++) {
        mr_dvec3 eye = mr_v3(ox + 0.6 * (rnd() - 0.5), 0.6 * (rnd() - 0.5), -4 - 2 * rnd());
        mr_dvec3 at = mr_v3(ox + 0.5 * (rnd() - 0.5), 0.5 * (rnd() - 0.5), 6);
        mr_view v = {{320, 240, 220, 220, 159.5, 119.5, {0}}, mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0))};
        mr_frame_result a, b, c;
        mr_draw_stats sa, sb, sc;
        if (!frame(&v, &on, &a, &sa)) break;
        if (!frame(&v, &off, &b, &sb)) {
            mr_frame_result_free(&a);
            break;
        }
        if (frame(&v, &none, &c, &sc)) {
            CHECK_MSG(same_depth(&a, &c) && same_color(&a, &c), "offset %g view %d: occlusion changes the image", ox, i);
            mr_frame_result_free(&c);
        }
        CHECK_MSG(same_depth(&a, &b) && same_color(&a, &b), "offset %g view %d: meshlet occlusion changes the image", ox, i);
        CHECK(sa.occlusion_frames > 0 && sb.clusters_occluded == 0 && sa.triangles <= sb.triangles);
        occl += sa.clusters_occluded;
        fewer += sa.triangles < sb.triangles;
        mr_frame_result_free(&a);
        mr_frame_result_free(&b);
    }
    CHECK_MSG(occl > 0 && fewer >= 5, "offset %g: meshlet occlusion skipped %llu meshlets, fewer triangles in %llu of 12 views",
              ox, (unsigned long long)occl, (unsigned long long)fewer);
    printf("offset %g: meshlet occlusion skipped %llu meshlets over 12 views (fewer triangles in %llu)\n", ox,
           (unsigned long long)occl, (unsigned long long)fewer);
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_renderer_set_draw_params(g_r, NULL, &err);
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
        /* issue 17 (lane cluster) */
        single_sided_culls();
        cone_views(0, 1, false);
        cone_views(1e7, 1, false);
        cone_views(0, 1e-3, false);
        cone_views(0, 1e3, false);
        cone_views(1e7, 1e3, false);
        cone_views(0, 1, true);
        test_cache();
        test_cluster_occlusion(0);
        test_cluster_occlusion(1e7);
    }
    mr_renderer_destroy(&g_r);
    mr_gpu_destroy(&g_gpu);
    return mr_test_finish("test_meshlet");
}
