/* CPU tests of the big-scene machinery: BVH frustum culling never drops a
 * node that shows in the image (random views, checked against projected
 * geometry), the LOD error bound is a true bound (brute-force sampling) and
 * not a loose guess (a known offset), and two-sided (a level that loses a
 * protrusion), the LOD cache is used only when it
 * matches, synthetic factories are deterministic and keep their instancing
 * through .glb, a 100k-node scene loads, and truncated .glb files fail
 * cleanly. */
#include "mr_scene.h"
#include "mr_test.h"
#include "mr_test_lod.h"
#include "mr_test_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *tmp_dir(void) {
    const char *t = getenv("MR_TEST_TMP");
    return t ? t : "/tmp";
}

/* ------------------------------------------------------------ culling */

/* Does any vertex or triangle sample of node n project into the image in
 * front of the near plane? (What the rasteriser could show.) */
static bool node_shows(const mr_scene *s, int32_t ni, const mr_camera *cam, const mr_dmat4 *cfw, double near_plane) {
    const mr_node *n = &s->nodes[ni];
    for (int32_t mi = n->mesh_first; mi >= 0 && mi < n->mesh_first + n->mesh_count; mi++) {
        const mr_mesh *m = &s->meshes[mi];
        mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
        mr_dmat4 cw = mr_m4_mul(cfw, &n->world);
        mr_dmat4 cm = mr_m4_mul(&cw, &T);
        for (uint32_t t = 0; t + 2 < m->index_count; t += 3) {
            mr_dvec3 c[3];
            for (int k = 0; k < 3; k++) {
                const float *p = m->positions + 3 * (size_t)m->indices[t + (uint32_t)k];
                c[k] = mr_m4_point(&cm, mr_v3(p[0], p[1], p[2]));
            }
            /* corners, edge midpoints and the centroid */
            static const double w[7][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {.5, .5, 0}, {0, .5, .5}, {.5, 0, .5}, {1. / 3, 1. / 3, 1. / 3}};
            for (int k = 0; k < 7; k++) {
                double x = w[k][0] * c[0].x + w[k][1] * c[1].x + w[k][2] * c[2].x;
                double y = w[k][0] * c[0].y + w[k][1] * c[1].y + w[k][2] * c[2].y;
                double z = w[k][0] * c[0].z + w[k][1] * c[1].z + w[k][2] * c[2].z;
                if (z <= near_plane) continue;
                double u = cam->fx * x / z + cam->cx, v = cam->fy * y / z + cam->cy;
                if (u >= -0.5 && u <= cam->width - 0.5 && v >= -0.5 && v <= cam->height - 0.5) return true;
            }
        }
    }
    return false;
}

static void test_no_false_cull(void) {
    mr_synth_params sp = MR_SYNTH_DEFAULTS;
    sp.halls = 2;
    sp.hall_width = 24;
    sp.hall_depth = 16;
    mr_error err = {0};
    mr_scene *s = mr_synth_build(&sp, &err);
    CHECK_MSG(s != NULL, "%s", err.msg);
    if (!s) return;
    mr_bvh *bvh = mr_bvh_build(s, &err);
    CHECK_MSG(bvh != NULL, "%s", err.msg);
    int32_t *out = malloc((size_t)s->node_count * sizeof *out);
    char *in = malloc((size_t)s->node_count);
    mr_rng rng;
    mr_rng_seed(&rng, 42);
    int views = 40, culled_total = 0, shown_total = 0, false_culls = 0;
    double lo[3] = {s->bounds_min[0], s->bounds_min[1], s->bounds_min[2]};
    double hi[3] = {s->bounds_max[0], s->bounds_max[1], s->bounds_max[2]};
    for (int v = 0; bvh && v < views; v++) {
        mr_camera cam = {160, 120, 80 + 200 * mr_rng_uniform(&rng), 0, 79.5, 59.5, {0}};
        cam.fy = cam.fx * (0.9 + 0.2 * mr_rng_uniform(&rng));
        cam.cx += 20 * (mr_rng_uniform(&rng) - 0.5);
        mr_dvec3 eye = mr_v3(lo[0] + (hi[0] - lo[0]) * mr_rng_uniform(&rng), 0.5 + 8 * mr_rng_uniform(&rng),
                             lo[2] + (hi[2] - lo[2]) * mr_rng_uniform(&rng));
        mr_dvec3 at = mr_v3(lo[0] + (hi[0] - lo[0]) * mr_rng_uniform(&rng), 3 * mr_rng_uniform(&rng),
                            lo[2] + (hi[2] - lo[2]) * mr_rng_uniform(&rng));
        mr_dmat4 wfc = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
        mr_dmat4 cfw = mr_m4_invert_rigid(&wfc);
        double near_plane = 0.05;
        mr_frustum fr = mr_frustum_from_camera(&cam, &wfc, near_plane, 1.0);
        int32_t n = mr_bvh_cull(bvh, &fr, 3u, out, NULL);
        memset(in, 0, (size_t)s->node_count);
        for (int32_t i = 0; i < n; i++) in[out[i]] = 1;
        for (int32_t i = 0; i < s->node_count; i++) {
            bool shows = node_shows(s, i, &cam, &cfw, near_plane);
            shown_total += shows;
            if (!in[i]) culled_total++;
            if (shows && !in[i]) {
                false_culls++;
                if (false_culls < 5) fprintf(stderr, "view %d: node %s shows but was culled\n", v, s->nodes[i].name);
            }
        }
    }
    CHECK(false_culls == 0);
    /* The test means something only if culling culls and views see things. */
    CHECK_MSG(culled_total > views * s->node_count / 4, "culled %d", culled_total);
    CHECK(shown_total > views * 10);
    /* Layer masks: only hidden nodes come back for the hidden bit. */
    int32_t n = mr_bvh_cull(bvh, NULL, 1u << MR_LAYER_HIDDEN, out, NULL);
    bool only_hidden = n > 0;
    for (int32_t i = 0; i < n; i++) only_hidden = only_hidden && s->nodes[out[i]].layer == MR_LAYER_HIDDEN;
    CHECK(only_hidden);
    free(out);
    free(in);
    mr_bvh_destroy(&bvh);
    mr_scene_destroy(&s);
}

static int cmp_i32(const void *a, const void *b) {
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return x < y ? -1 : x > y;
}

/* The same culling 1e7 units from the origin. */
static void test_far_cull(void) {
    mr_synth_params sp = MR_SYNTH_DEFAULTS;
    sp.hall_width = 20;
    sp.hall_depth = 14;
    mr_error err = {0};
    mr_scene *a = mr_synth_build(&sp, &err);
    sp.origin[0] = 1e7;
    sp.origin[2] = -1e7;
    mr_scene *b = mr_synth_build(&sp, &err);
    mr_bvh *ba = a ? mr_bvh_build(a, &err) : NULL, *bb = b ? mr_bvh_build(b, &err) : NULL;
    CHECK(ba && bb);
    if (ba && bb) {
        mr_camera cam = {200, 150, 150, 150, 99.5, 74.5, {0}};
        int32_t *oa = malloc((size_t)a->node_count * 4), *ob = malloc((size_t)b->node_count * 4);
        int same = 0;
        for (int v = 0; v < MR_SYNTH_VIEW_COUNT; v++) {
            mr_synth_params p0 = MR_SYNTH_DEFAULTS;
            p0.hall_width = 20;
            p0.hall_depth = 14;
            mr_dmat4 w0 = mr_synth_viewpoint(&p0, v), w1 = mr_synth_viewpoint(&sp, v);
            mr_frustum f0 = mr_frustum_from_camera(&cam, &w0, 0.05, 1.0), f1 = mr_frustum_from_camera(&cam, &w1, 0.05, 1.0);
            int32_t na = mr_bvh_cull(ba, &f0, 3u, oa, NULL), nb = mr_bvh_cull(bb, &f1, 3u, ob, NULL);
            /* The same set (the BVH's order may differ with rounding). */
            qsort(oa, (size_t)na, 4, cmp_i32);
            qsort(ob, (size_t)nb, 4, cmp_i32);
            same += na == nb && memcmp(oa, ob, (size_t)na * 4) == 0;
            if (na != nb) fprintf(stderr, "view %d: %d vs %d nodes\n", v, (int)na, (int)nb);
        }
        CHECK(same == MR_SYNTH_VIEW_COUNT);
        free(oa);
        free(ob);
    }
    mr_bvh_destroy(&ba);
    mr_bvh_destroy(&bb);
    mr_scene_destroy(&a);
    mr_scene_destroy(&b);
}

/* ---------------------------------------------------------------- LOD */


/* A bumpy sphere (radius ~r): curved everywhere, so every level has a real
 * error. */
static mr_mesh bumpy_sphere(double r, int nu, int nv) { return mr_test_sphere_mesh("bumpy", r, nu, nv, 0.08, 3, 2); }

/* A capped cylinder along y (planar strips, planar fans at the caps):
 * exercises the convex-pair and planar-fan bounds. */
static mr_mesh capped_cylinder(double r, double len, int seg, int rings) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "cyl");
    m.vertex_count = (uint32_t)(seg * (rings + 1) + 2);
    m.index_count = (uint32_t)(seg * rings * 6 + seg * 6);
    m.positions = malloc((size_t)m.vertex_count * 12);
    m.indices = malloc((size_t)m.index_count * 4);
    for (int j = 0; j <= rings; j++)
        for (int i = 0; i < seg; i++) {
            double t = 2 * 3.14159265358979 * i / seg;
            float *p = m.positions + 3 * (size_t)(j * seg + i);
            p[0] = (float)(r * cos(t));
            p[1] = (float)(-len / 2 + len * j / rings);
            p[2] = (float)(r * sin(t));
        }
    uint32_t c0 = (uint32_t)(seg * (rings + 1)), c1 = c0 + 1;
    float *p = m.positions + 3 * (size_t)c0;
    p[0] = 0; p[1] = (float)(-len / 2); p[2] = 0;
    p[3] = 0; p[4] = (float)(len / 2); p[5] = 0;
    uint32_t ni = 0;
    for (int j = 0; j < rings; j++)
        for (int i = 0; i < seg; i++) {
            uint32_t a = (uint32_t)(j * seg + i), b = (uint32_t)(j * seg + (i + 1) % seg), c = b + (uint32_t)seg, d = a + (uint32_t)seg;
            uint32_t q[6] = {a, d, c, a, c, b};
            for (int k = 0; k < 6; k++) m.indices[ni++] = q[k];
        }
    for (int i = 0; i < seg; i++) {
        uint32_t a = (uint32_t)i, b = (uint32_t)((i + 1) % seg);
        m.indices[ni++] = c0; m.indices[ni++] = a; m.indices[ni++] = b;
        uint32_t ta = (uint32_t)(rings * seg + i), tb = (uint32_t)(rings * seg + (i + 1) % seg);
        m.indices[ni++] = c1; m.indices[ni++] = tb; m.indices[ni++] = ta;
    }
    m.material = -1;
    return m;
}

static void check_levels(const mr_mesh *mm, const mr_mesh_lods *ml, const mr_lod_params *lp, const char *what) {
    double prev = 0;
    for (int k = 0; k < ml->level_count; k++) {
        const mr_lod_level *l = &ml->levels[k];
        CHECK(l->index_count < mm->index_count && l->index_count % 3 == 0);
        CHECK(l->error >= prev && l->error <= lp->max_error);
        prev = l->error;
        /* The bound holds against brute force in both directions... */
        double ab = mr_test_sampled_distance(mm->positions, mm->indices, mm->index_count, l->indices, l->index_count, 3);
        double ba = mr_test_sampled_distance(mm->positions, l->indices, l->index_count, mm->indices, mm->index_count, 5);
        double brute = fmax(ab, ba);
        CHECK_MSG(brute <= l->error + 1e-7, "%s level %d: sampled %g > bound %g", what, k, brute, l->error);
        /* ...and the certificate the builder uses is not vacuous: the
         * level against the full mesh directly is within a quarter of the
         * largest real distance plus the resolution, and this sampling
         * misses up to a fifth of that (the tent): 1.6 (and sound too). The
         * level's own error is a chain of such steps (lod.c), which may add
         * up to more on adversarial shapes (the tent: 2.3x), never less. */
        double res = 0.01 * lp->max_error;
        double direct = mr_lod_hausdorff_bound_within(mm->positions, mm->vertex_count, mm->indices, mm->index_count,
                                                      l->indices, l->index_count, res, res, INFINITY);
        CHECK_MSG(brute <= direct + 1e-7, "%s level %d: sampled %g > direct bound %g", what, k, brute, direct);
        CHECK_MSG(direct <= brute * 1.6 + res + 1e-6, "%s level %d: direct bound %g vs sampled %g", what, k, direct, brute);
    }
}

/* The kernel this CPU gets and the portable one build the same levels
 * (lod_v3.c is lod.c compiled for AVX2 and FMA): the same counts, errors
 * within rounding, and the portable levels hold against brute force too. */
static void check_kernels(mr_scene *s, const mr_lod *fast, const mr_lod_params *lp, const char *what) {
    mr_lod_params pp = *lp;
    pp.portable = true;
    CHECK(strcmp(mr_lod_kernel(&pp), "portable") == 0);
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
    /* (CMakeLists.txt builds the x86-64-v3 kernel on x86-64) */
    if (__builtin_cpu_supports("x86-64-v3"))
        CHECK_MSG(strcmp(mr_lod_kernel(lp), "x86-64-v3") == 0, "%s: kernel %s on an x86-64-v3 CPU", what, mr_lod_kernel(lp));
#endif
    printf("  %s: kernel %s against portable\n", what, mr_lod_kernel(lp));
    mr_error err = {0};
    mr_lod *port = mr_lod_build(s, &pp, &err);
    CHECK_MSG(port != NULL, "%s", err.msg);
    if (!port || !fast) {
        mr_lod_destroy(&port);
        return;
    }
    for (int32_t i = 0; i < s->mesh_count; i++) {
        const mr_mesh_lods *a = &fast->meshes[i], *b = &port->meshes[i];
        CHECK_MSG(a->level_count == b->level_count, "%s: %d levels, portable %d", what, a->level_count, b->level_count);
        for (int k = 0; k < a->level_count && k < b->level_count; k++)
            CHECK_MSG(a->levels[k].index_count == b->levels[k].index_count &&
                          fabs(a->levels[k].error - b->levels[k].error) <= 1e-9 * b->levels[k].error,
                      "%s level %d: %u triangles, error %.17g; portable %u, %.17g", what, k, a->levels[k].index_count / 3,
                      a->levels[k].error, b->levels[k].index_count / 3, b->levels[k].error);
        check_levels(&s->meshes[i], b, lp, what);
    }
    mr_lod_destroy(&port);
}

static void test_lod_bound(void) {
    mr_scene *s = mr_scene_create();
    mr_mesh m = bumpy_sphere(0.5, 32, 16);
    mr_error err = {0};
    int32_t id = mr_scene_add_mesh(s, &m, &err);
    CHECK_MSG(id == 0, "%s", err.msg);
    mr_lod_params lp = MR_LOD_DEFAULTS;
    lp.max_error = 0.1;
    double t0 = mr_time_now();
    mr_lod *lod = mr_lod_build(s, &lp, &err);
    printf("  LOD build %.2f s\n", mr_time_now() - t0);
    CHECK_MSG(lod != NULL, "%s", err.msg);
    if (lod) {
        const mr_mesh *mm = &s->meshes[0];
        const mr_mesh_lods *ml = &lod->meshes[0];
        CHECK_MSG(ml->level_count >= 2, "only %d levels", ml->level_count);
        check_levels(mm, ml, &lp, "bumpy sphere");
        check_kernels(s, lod, &lp, "bumpy sphere");
    }
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
    /* Planar pieces: strips and cap fans of a cylinder. */
    s = mr_scene_create();
    mr_mesh cyl = capped_cylinder(0.1, 2.0, 24, 20);
    CHECK(mr_scene_add_mesh(s, &cyl, &err) == 0);
    lod = mr_lod_build(s, &lp, &err);
    CHECK(lod && lod->meshes[0].level_count >= 2);
    if (lod) check_levels(&s->meshes[0], &lod->meshes[0], &lp, "cylinder");
    check_kernels(s, lod, &lp, "cylinder");
    /* A surface shifted by exactly 1 cm: the bound finds it (a real bound
     * would report at least the shift, a loose guess might not). */
    {
        mr_mesh q = bumpy_sphere(0.5, 24, 12);
        uint32_t nv = q.vertex_count;
        float *pos = malloc((size_t)nv * 2 * 12);
        memcpy(pos, q.positions, (size_t)nv * 12);
        for (uint32_t v = 0; v < nv; v++)
            for (int k = 0; k < 3; k++) pos[3 * (nv + v) + (uint32_t)k] = q.positions[3 * v + (uint32_t)k] + (k == 0 ? 0.01f : 0.0f);
        uint32_t *b = malloc((size_t)q.index_count * 4);
        for (uint32_t i = 0; i < q.index_count; i++) b[i] = q.indices[i] + nv;
        double e = mr_lod_hausdorff_bound(pos, 2 * nv, q.indices, q.index_count, b, q.index_count, 1e-4, 1.0);
        double brute = mr_test_sampled_distance(pos, q.indices, q.index_count, b, q.index_count, 3);
        CHECK_MSG(e >= brute - 1e-9 && e <= 0.01 + 2e-4, "shifted sphere: bound %g, sampled %g", e, brute);
        CHECK(brute > 0.003); /* a sphere shifted sideways is that far at its sides */
        /* Nothing within the limit: infinite. */
        CHECK(isinf(mr_lod_hausdorff_bound(pos, 2 * nv, q.indices, q.index_count, b, q.index_count, 1e-4, 0.001)));
        free(pos);
        free(b);
        free(q.positions);
        free(q.indices);
    }
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
}

/* A flat square plate in y = 0 (n x n vertices over [-0.5, 0.5]^2), with
 * room for `extra` more vertices after the grid. */
static mr_mesh plate(int n, uint32_t extra) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "plate");
    m.vertex_count = (uint32_t)(n * n) + extra;
    m.index_count = (uint32_t)((n - 1) * (n - 1) * 6);
    m.positions = calloc((size_t)m.vertex_count, 12);
    m.indices = malloc((size_t)m.index_count * 4);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            float *p = m.positions + 3 * (size_t)(j * n + i);
            p[0] = (float)(-0.5 + (double)i / (n - 1));
            p[2] = (float)(-0.5 + (double)j / (n - 1));
        }
    uint32_t ni = 0;
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i + 1 < n; i++) {
            uint32_t a = (uint32_t)(j * n + i), b = a + 1, c = a + (uint32_t)n, d = c + 1;
            uint32_t q[6] = {a, c, b, b, c, d};
            for (int k = 0; k < 6; k++) m.indices[ni++] = q[k];
        }
    m.material = -1;
    return m;
}

/* The asymmetric case: a level that loses a protrusion. The full surface is
 * a plate plus a thin spike (a pyramid of height h on a 2w-wide base); the
 * level is the plate alone. d(full -> level) = h (the tip), d(level ->
 * full) = 0 (the plate is in both), so a bound that looks one way only
 * reports 0 for one argument order; a loose one reports much more than h. */
static void test_lod_lost_protrusion(void) {
    const double h = 0.1, w = 0.01;
    mr_mesh m = plate(9, 5);
    uint32_t g = m.vertex_count - 5; /* base corners g..g+3, tip g+4 */
    for (int k = 0; k < 4; k++) {
        float *p = m.positions + 3 * (size_t)(g + (uint32_t)k);
        p[0] = (float)((k == 0 || k == 3) ? -w : w);
        p[1] = 0.0f;
        p[2] = (float)(k < 2 ? -w : w);
    }
    m.positions[3 * (size_t)(g + 4) + 1] = (float)h;
    uint32_t nplate = m.index_count, nfull = nplate + 12;
    uint32_t *full = malloc((size_t)nfull * 4);
    memcpy(full, m.indices, (size_t)nplate * 4);
    for (uint32_t k = 0; k < 4; k++) {
        full[nplate + 3 * k] = g + k;
        full[nplate + 3 * k + 1] = g + (k + 1) % 4;
        full[nplate + 3 * k + 2] = g + 4;
    }
    const double eps = 1e-4;
    double d_fl = mr_test_sampled_distance(m.positions, full, nfull, m.indices, nplate, 8);
    double d_lf = mr_test_sampled_distance(m.positions, m.indices, nplate, full, nfull, 8);
    CHECK_MSG(fabs(d_fl - h) < 1e-6 && d_lf < 1e-6, "test set-up: sampled full->level %g (want %g), level->full %g (want 0)",
              d_fl, h, d_lf);
    double e_fl = mr_lod_hausdorff_bound(m.positions, m.vertex_count, full, nfull, m.indices, nplate, 1e-4, 1.0);
    double e_lf = mr_lod_hausdorff_bound(m.positions, m.vertex_count, m.indices, nplate, full, nfull, 1e-4, 1.0);
    CHECK_MSG(e_fl >= h - eps && e_fl <= h * 1.05 + eps,
              "lost spike, bound(full, level) = %g, want %g (the spike tip is %g from the level: the full->level "
              "direction of the two-sided Hausdorff bound is missing or loose)", e_fl, h, h);
    CHECK_MSG(e_lf >= h - eps && e_lf <= h * 1.05 + eps,
              "lost spike, bound(level, full) = %g, want %g (the bound must be symmetric: the direction from the "
              "second surface to the first is missing or loose)", e_lf, h);
    CHECK_MSG(e_fl >= fmax(d_fl, d_lf) - 1e-9 && e_lf >= fmax(d_fl, d_lf) - 1e-9,
              "lost spike: bounds %g / %g below brute-force sampling %g", e_fl, e_lf, fmax(d_fl, d_lf));
    /* Identical surfaces: 0 both ways (a bound that adds slack fails here). */
    double e0 = mr_lod_hausdorff_bound(m.positions, m.vertex_count, full, nfull, full, nfull, 1e-4, 1.0);
    CHECK_MSG(e0 <= 1e-4 + 1e-9, "identical surfaces: bound %g, want 0 (within the resolution 1e-4)", e0);
    free(full);
    free(m.positions);
    free(m.indices);

    /* The same through the level builder: a fine plate with one grid
     * vertex raised into a tent of height h. A level that collapses the tip
     * lies flat in y = 0, so its certified error must reach h. */
    mr_mesh t = plate(17, 0);
    uint32_t tip = 8 * 17 + 8;
    t.positions[3 * (size_t)tip + 1] = (float)h;
    mr_scene *s = mr_scene_create();
    mr_error err = {0};
    CHECK_MSG(mr_scene_add_mesh(s, &t, &err) == 0, "%s", err.msg);
    mr_lod_params lp = MR_LOD_DEFAULTS;
    lp.max_error = 3 * h; /* room for the chained steps (lod.c) */
    mr_lod *lod = mr_lod_build(s, &lp, &err);
    CHECK_MSG(lod != NULL, "%s", err.msg);
    if (lod) {
        const mr_mesh *mm = &s->meshes[0];
        const mr_mesh_lods *ml = &lod->meshes[0];
        int dropped = 0;
        for (int k = 0; k < ml->level_count; k++) {
            const mr_lod_level *l = &ml->levels[k];
            bool has_tip = false;
            for (uint32_t i = 0; i < l->index_count; i++) has_tip = has_tip || l->indices[i] == tip;
            if (has_tip) continue;
            dropped++;
            /* At least h (the lost tip), and the tight bound finds h. */
            double tight = mr_lod_hausdorff_bound(mm->positions, mm->vertex_count, mm->indices, mm->index_count, l->indices,
                                                  l->index_count, 1e-3 * h, INFINITY);
            CHECK_MSG(tight >= h - eps && tight <= h * 1.05 + eps, "tent level %d: tight bound %g, want %g", k, tight, h);
            CHECK_MSG(l->error >= h - eps && l->error <= lp.max_error,
                      "tent level %d drops the tip: certified error %g, want %g (the lost protrusion)", k, l->error, h);
        }
        CHECK_MSG(dropped > 0, "test set-up: no level of the tent dropped its tip (%d levels)", ml->level_count);
        check_levels(mm, ml, &lp, "tent");
    }
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
}

static bool same_lod(const mr_lod *a, const mr_lod *b) {
    if (!a || !b || a->mesh_count != b->mesh_count) return false;
    for (int32_t i = 0; i < a->mesh_count; i++) {
        if (a->meshes[i].level_count != b->meshes[i].level_count) return false;
        for (int32_t k = 0; k < a->meshes[i].level_count; k++) {
            const mr_lod_level *x = &a->meshes[i].levels[k], *y = &b->meshes[i].levels[k];
            if (x->index_count != y->index_count || x->error != y->error ||
                memcmp(x->indices, y->indices, (size_t)x->index_count * 4) != 0)
                return false;
        }
    }
    return true;
}

static void test_lod_cache(void) {
    mr_scene *s = mr_scene_create();
    mr_mesh m = bumpy_sphere(0.3, 32, 16);
    mr_error err = {0};
    mr_scene_add_mesh(s, &m, &err);
    char path[1024];
    snprintf(path, sizeof path, "%s/cache_test.glb.mrlod", tmp_dir());
    remove(path);
    mr_lod_params lp = MR_LOD_DEFAULTS;
    mr_lod_info info;
    mr_lod *a = mr_lod_load_or_build(s, path, &lp, &info, &err);
    CHECK(a && !info.from_cache && info.cache_written && info.levels > 0);
    mr_lod *b = mr_lod_load_or_build(s, path, &lp, &info, &err);
    CHECK(b && info.from_cache && same_lod(a, b));
    mr_lod_destroy(&b);
    /* Other params: ignored. */
    mr_lod_params lp2 = lp;
    lp2.max_error = 0.03;
    b = mr_lod_load_or_build(s, path, &lp2, &info, &err);
    CHECK(b && !info.from_cache);
    mr_lod_destroy(&b);
    b = mr_lod_load_or_build(s, path, &lp, &info, &err); /* rewrites for lp */
    mr_lod_destroy(&b);
    /* A flipped byte and a truncation: ignored and rebuilt, never trusted. */
    size_t size = 0;
    unsigned char *data = mr_file_read(path, &size, 0, &err);
    CHECK(data && size > 100);
    if (data) {
        data[size / 2] ^= 0x40;
        mr_file_write_atomic(path, data, size, &err);
        b = mr_lod_load_or_build(s, path, &lp, &info, &err);
        CHECK(b && !info.from_cache && same_lod(a, b));
        mr_lod_destroy(&b);
        data[size / 2] ^= 0x40;
        mr_file_write_atomic(path, data, size - 9, &err);
        b = mr_lod_load_or_build(s, path, &lp, &info, &err);
        CHECK(b && !info.from_cache && same_lod(a, b));
        mr_lod_destroy(&b);
        free(data);
    }
    /* Another scene's geometry: the hash differs, the cache is ignored. */
    mr_scene *s2 = mr_scene_create();
    mr_mesh m2 = bumpy_sphere(0.31, 32, 16);
    mr_scene_add_mesh(s2, &m2, &err);
    CHECK(mr_lod_scene_hash(s) != mr_lod_scene_hash(s2));
    b = mr_lod_load_or_build(s2, path, &lp, &info, &err);
    CHECK(b && !info.from_cache);
    mr_lod_destroy(&b);
    mr_scene_destroy(&s2);
    mr_lod_destroy(&a);
    mr_scene_destroy(&s);
}

/* --------------------------------------------------- synth, load, fuzz */

static void test_synth_roundtrip(void) {
    mr_synth_params sp = MR_SYNTH_DEFAULTS;
    sp.halls = 2;
    mr_error err = {0};
    mr_scene *a = mr_synth_build(&sp, &err), *b = mr_synth_build(&sp, &err);
    CHECK(a && b);
    if (!a || !b) return;
    CHECK(a->node_count == b->node_count && mr_lod_scene_hash(a) == mr_lod_scene_hash(b));
    CHECK(memcmp(a->nodes, b->nodes, (size_t)a->node_count * sizeof *a->nodes) == 0);
    uint64_t tri = mr_scene_triangle_count(a), stored = 0;
    for (int32_t i = 0; i < a->mesh_count; i++) stored += a->meshes[i].index_count / 3;
    CHECK(tri > 1000000 && stored * 10 < tri); /* mostly instances */
    int hidden = 0;
    for (int32_t i = 0; i < a->node_count; i++) hidden += a->nodes[i].layer == MR_LAYER_HIDDEN;
    CHECK(hidden > 10 && hidden < a->node_count / 4);
    int h = mr_synth_halls_for(20000000);
    CHECK(h >= 20 && h <= 30);
    char path[1024];
    snprintf(path, sizeof path, "%s/synth2.glb", tmp_dir());
    CHECK_MSG(mr_scene_save_glb(a, path, &err), "%s", err.msg);
    mr_scene *c = mr_scene_load(path, NULL, &err);
    CHECK_MSG(c != NULL, "%s", err.msg);
    if (c) {
        /* Instancing survives: the same meshes, shared by as many nodes. */
        CHECK(c->mesh_count == a->mesh_count && c->node_count == a->node_count);
        CHECK(mr_scene_triangle_count(c) == tri);
        mr_scene_destroy(&c);
    }
    mr_scene_destroy(&a);
    mr_scene_destroy(&b);
}

/* 100k nodes of small shared parts: builds, saves, loads within memory;
 * truncated copies of the file fail with one clean error. */
static void test_100k_and_truncation(void) {
    mr_scene *s = mr_scene_create();
    mr_error err = {0};
    for (int k = 0; k < 4; k++) {
        mr_mesh m = bumpy_sphere(0.05 + 0.01 * k, 6 + 2 * k, 4 + k);
        CHECK(mr_scene_add_mesh(s, &m, &err) == k);
    }
    mr_test_add_grid_nodes(s, 100000, 4);
    mr_scene_update_bounds(s);
    CHECK(s->node_count == 100000);
    char path[1024];
    snprintf(path, sizeof path, "%s/nodes100k.glb", tmp_dir());
    CHECK_MSG(mr_scene_save_glb(s, path, &err), "%s", err.msg);
    double t0 = mr_time_now();
    mr_scene *l = mr_scene_load(path, NULL, &err);
    double dt = mr_time_now() - t0;
    CHECK_MSG(l != NULL, "%s", err.msg);
    if (l) {
        CHECK(l->node_count == 100000 && l->mesh_count == 4);
        mr_bvh *bvh = mr_bvh_build(l, &err);
        CHECK(bvh && mr_bvh_node_count(bvh) == 100000);
        mr_bvh_destroy(&bvh);
        mr_scene_destroy(&l);
    }
    printf("100k nodes: load %.2f s, peak RSS %.0f MB\n", dt, mr_peak_rss_bytes() / 1048576.0);
    /* The same load on a thread: polls return at once while it runs. */
    mr_scene_loader *ld = mr_scene_load_async(path, NULL, &err);
    CHECK(ld != NULL);
    int polls = 0;
    double worst_poll = 0, last_fraction = 0;
    bool monotone = true;
    for (;;) {
        const char *stage;
        double fr, tp = mr_time_now();
        bool done = mr_scene_loader_poll(ld, &stage, &fr);
        worst_poll = fmax(worst_poll, mr_time_now() - tp);
        polls++;
        if (done) break;
        if (strcmp(stage, "nodes") == 0) {
            monotone = monotone && fr >= last_fraction;
            last_fraction = fr;
        }
        struct timespec ts = {0, 2000000};
        nanosleep(&ts, NULL);
    }
    l = mr_scene_loader_finish(&ld, &err);
    /* A poll that waited for the load would end it at the first call:
     * polls > 1 says they return while it runs. How long one took is
     * printed, not asserted: on a loaded machine any call can be
     * descheduled for longer than a frame. */
    printf("async load: %d polls, the longest %.2f ms\n", polls, worst_poll * 1e3);
    CHECK(l && l->node_count == 100000 && ld == NULL && monotone && polls > 1);
    mr_scene_destroy(&l);
    mr_scene_loader *bad = mr_scene_load_async("/nonexistent/x.glb", NULL, &err);
    mr_error e4 = {0};
    CHECK(bad && !mr_scene_loader_finish(&bad, &e4) && e4.code == MR_ERR_IO);
    CHECK(mr_peak_rss_bytes() < (size_t)2 << 30);
    size_t size = 0;
    unsigned char *data = mr_file_read(path, &size, 0, &err);
    CHECK(data != NULL);
    static const double cuts[] = {0.0001, 0.01, 0.3, 0.5, 0.9, 0.999};
    for (size_t i = 0; data && i < sizeof cuts / sizeof cuts[0]; i++) {
        size_t n = (size_t)(size * cuts[i]);
        mr_error e2 = {0};
        mr_scene *t = mr_scene_load_gltf_memory(data, n, NULL, NULL, &e2);
        CHECK_MSG(t == NULL && e2.code != MR_OK && e2.msg[0] && !strchr(e2.msg, '\n'), "cut at %zu: %s", n, e2.msg);
        mr_scene_destroy(&t);
    }
    /* On disk too: the file path names itself in the message. */
    if (data) {
        char tpath[1100];
        snprintf(tpath, sizeof tpath, "%s/truncated.glb", tmp_dir());
        mr_file_write_atomic(tpath, data, size / 2, &err);
        mr_error e3 = {0};
        mr_scene *t = mr_scene_load(tpath, NULL, &e3);
        CHECK(t == NULL && strstr(e3.msg, "truncated.glb") != NULL);
        mr_scene_destroy(&t);
    }
    free(data);
    mr_scene_destroy(&s);
}

/* The projected-patch bound (lod.c, patch_bound) claims a piece lies over
 * the other surface; the claim is proven from the patch's border edges. A
 * coarse plate (two triangles) over a fine one with a hole, a slit, a hole
 * with a separate sheet under it, and cells wound the other way: each bound
 * holds against brute force, at scales 1e-3, 1 and 1e3, and at 1e3 moved
 * 1e7 away. Without the border check the hole would be bounded by the
 * heights alone (0). */
static void test_lod_patch_holes(void) {
    const int n = 21;
    const double scales[4] = {1e-3, 1, 1e3, 1e3};
    for (int cs = 0; cs < 4; cs++)
        for (int si = 0; si < 4; si++) {
            double sc = scales[si], off = si == 3 ? 1e7 : 0;
            mr_mesh m = plate(n, 16);
            /* A small sheet under the hole (case 2): 4 x 4 vertices, 1 cm below. */
            uint32_t base = (uint32_t)(n * n);
            for (int j = 0; j < 4; j++)
                for (int i = 0; i < 4; i++) {
                    float *q = m.positions + 3 * (size_t)(base + (uint32_t)(j * 4 + i));
                    q[0] = (float)(-0.15 - 0.075 + 0.05 * i);
                    q[1] = -0.01f;
                    q[2] = (float)(0.1 - 0.075 + 0.05 * j);
                }
            for (uint32_t v = 0; v < m.vertex_count * 3; v++) m.positions[v] = (float)(m.positions[v] * sc + (v % 3 == 0 ? off : 0));
            uint32_t *fine = malloc(((size_t)m.index_count + 64) * 4), nf = 0;
            for (int j = 0; j + 1 < n; j++)
                for (int i = 0; i + 1 < n; i++) {
                    const uint32_t *c6 = m.indices + 6 * (size_t)(j * (n - 1) + i);
                    /* Centred at (-0.15, 0.1): not a dyadic point, so no
                     * midpoint the bound queries lands on it by luck. */
                    bool hole = (cs == 0 || cs == 2) && i >= 6 && i <= 7 && j >= 11 && j <= 12;
                    bool slit = cs == 1 && i == 10;
                    if (hole || slit) continue;
                    bool flip = cs == 3 && i >= 8 && i <= 11 && j >= 8 && j <= 11;
                    for (int k = 0; k < 6; k++) fine[nf++] = c6[flip ? (k / 3) * 3 + 2 - k % 3 : k];
                }
            if (cs == 2)
                for (int j = 0; j < 3; j++)
                    for (int i = 0; i < 3; i++) {
                        uint32_t a = base + (uint32_t)(j * 4 + i), b = a + 1, c = a + 4, d = c + 1;
                        const uint32_t q6[6] = {a, c, b, b, c, d};
                        for (int k = 0; k < 6; k++) fine[nf++] = q6[k];
                    }
            const uint32_t c00 = 0, c10 = (uint32_t)(n - 1), c01 = (uint32_t)(n * (n - 1)), c11 = (uint32_t)(n * n - 1);
            const uint32_t coarse[6] = {c00, c01, c10, c10, c01, c11};
            double res = 1e-4 * sc;
            double e = mr_lod_hausdorff_bound(m.positions, m.vertex_count, coarse, 6, fine, nf, res, 10 * sc);
            double brute = mr_test_sampled_distance(m.positions, coarse, 6, fine, nf, 40);
            const double truth[4] = {0.05, 0.025, 0.01, 0};
            CHECK_MSG(brute >= 0.9 * truth[cs] * sc, "patch case %d scale %g: sampled %g, expected about %g", cs, sc, brute,
                      truth[cs] * sc);
            CHECK_MSG(e >= brute - 1e-9 * sc, "patch case %d scale %g: bound %g below sampled %g", cs, sc, e, brute);
            CHECK_MSG(e <= 1.2 * brute + 4 * res, "patch case %d scale %g: bound %g, sampled %g", cs, sc, e, brute);
            free(fine);
            free(m.positions);
            free(m.indices);
        }
}

int main(void) {
    mr_error err;
    mr_mkdirs(tmp_dir(), &err);
    double t = mr_time_now();
#define RUN(f) f(); printf("%s: %.2f s\n", #f, mr_time_now() - t); t = mr_time_now()
    RUN(test_no_false_cull);
    RUN(test_far_cull);
    RUN(test_lod_bound);
    RUN(test_lod_lost_protrusion);
    RUN(test_lod_patch_holes);
    RUN(test_lod_cache);
    RUN(test_synth_roundtrip);
    RUN(test_100k_and_truncation);
    return mr_test_finish("test_cull_lod");
}
