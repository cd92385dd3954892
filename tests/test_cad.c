/* Unique CAD-like geometry (issue 17): LOD without unit assumptions and
 * across normal seams.
 *  - The CAD factory's parts (split at every normal seam) get simplified
 *    levels down to about 2 % of their size, in millimetres, metres and
 *    kilometres alike, and the same levels in each unit (scaled).
 *  - Every level's certified error holds against brute-force sampling of
 *    the two-sided distance, at scales 1e-3, 1 and 1e3.
 *  - Levels keep the seams' normals: each corner uses a vertex whose normal
 *    agrees with its triangle's face.
 *  - GPU: a factory and its 1000x scaled copy pick the same levels from
 *    corresponding views with the default settings (pixels only). */
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_lod.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>


static mr_scene *cad(double unit, int parts, uint32_t tris) {
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    cp.parts = parts;
    cp.part_triangles = tris;
    cp.unit = unit;
    mr_error err = {0};
    mr_scene *s = mr_synth_cad_build(&cp, &err);
    CHECK_MSG(s != NULL, "%s", err.msg);
    return s;
}

static double mesh_size(const mr_mesh *m) {
    double e = 0;
    for (int k = 0; k < 3; k++) e = fmax(e, (double)m->bounds_max[k] - m->bounds_min[k]);
    return e;
}

/* A cylinder (radius r, length len along y, seg segments) written as CAD
 * exporters write it: the side and the two caps are separate patches, so
 * every rim position appears twice, with the side's and the cap's normal. */
static mr_mesh split_cylinder(double r, double len, int seg) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "split_cylinder");
    m.vertex_count = (uint32_t)(4 * seg + 2);
    m.index_count = (uint32_t)(12 * seg);
    m.positions = malloc((size_t)m.vertex_count * 12);
    m.indices = malloc((size_t)m.index_count * 4);
    for (int i = 0; i < seg; i++) {
        double a = 2 * 3.14159265358979 * i / seg;
        for (int k = 0; k < 4; k++) { /* side bottom, side top, cap bottom, cap top */
            float *p = m.positions + 3 * (size_t)(k * seg + i);
            p[0] = (float)(r * cos(a));
            p[1] = (float)((k & 1) ? len / 2 : -len / 2);
            p[2] = (float)(r * sin(a));
        }
    }
    uint32_t cb = (uint32_t)(4 * seg), ct = cb + 1, ni = 0;
    float *p = m.positions + 3 * (size_t)cb;
    p[0] = 0; p[1] = (float)(-len / 2); p[2] = 0;
    p[3] = 0; p[4] = (float)(len / 2); p[5] = 0;
    for (int i = 0; i < seg; i++) {
        uint32_t a = (uint32_t)i, b = (uint32_t)((i + 1) % seg), S = (uint32_t)seg;
        uint32_t q[12] = {a, a + S, b, b, a + S, b + S, /* side */
                          cb, 2 * S + a, 2 * S + b, ct, 3 * S + b, 3 * S + a}; /* caps */
        for (int k = 0; k < 12; k++) m.indices[ni++] = q[k];
    }
    m.material = -1;
    return m;
}

/* The classic CAD case: a finely tessellated cylinder split at its rims is
 * simplified to a quarter of its triangles or less within 2 % of its size (the default budget), in
 * any unit, and its bound holds against brute force at 1e-3, 1 and 1e3. */
static void test_split_cylinder(void) {
    static const double units[] = {1e-3, 1, 1e3};
    for (int u = 0; u < 3; u++) {
        mr_scene *s = mr_scene_create();
        mr_mesh m = split_cylinder(0.25 * units[u], 1.0 * units[u], 128);
        mr_error err = {0};
        CHECK_MSG(mr_scene_add_mesh(s, &m, &err) == 0, "%s", err.msg);
        mr_lod *lod = mr_lod_build(s, NULL, &err);
        CHECK_MSG(lod != NULL, "%s", err.msg);
        if (lod) {
            const mr_mesh *mm = &s->meshes[0];
            const mr_mesh_lods *ml = &lod->meshes[0];
            double size = mesh_size(mm);
            printf("  cylinder at unit %g: %u triangles:", units[u], mm->index_count / 3);
            for (int k = 0; k < ml->level_count; k++) printf(" %u@%.3g", ml->levels[k].index_count / 3, ml->levels[k].error / size);
            printf("\n");
            /* Levels are certified in a chain (lod.c: the steps' errors add
             * up), so the 2 % budget runs out after two or three levels. */
            CHECK_MSG(ml->level_count >= 2, "unit %g: %d levels", units[u], ml->level_count);
            if (ml->level_count > 0)
                CHECK_MSG(ml->levels[ml->level_count - 1].index_count * 2 <= mm->index_count,
                          "unit %g: coarsest level %u of %u triangles", units[u],
                          ml->levels[ml->level_count - 1].index_count / 3, mm->index_count / 3);
            for (int k = 0; k < ml->level_count; k++) {
                const mr_lod_level *l = &ml->levels[k];
                CHECK(l->error <= MR_LOD_DEFAULT_REL_ERROR * size * (1 + 1e-6));
                double ab = mr_test_sampled_distance(mm->positions, mm->indices, mm->index_count, l->indices, l->index_count, 2);
                double ba = mr_test_sampled_distance(mm->positions, l->indices, l->index_count, mm->indices, mm->index_count, 8);
                double brute = fmax(ab, ba);
                CHECK_MSG(brute <= l->error * (1 + 1e-6) + 1e-7 * size, "cylinder unit %g level %d: sampled %g > bound %g",
                          units[u], k, brute, l->error);
                /* Not vacuous: the chained bound is a sum of steps, each
                 * within a quarter of its truth (+ resolution). */
                CHECK_MSG(l->error <= 2.5 * brute + 0.05 * MR_LOD_DEFAULT_REL_ERROR * size,
                          "cylinder unit %g level %d: bound %g vs sampled %g", units[u], k, l->error, brute);
            }
            /* The portable kernel builds the same levels in every unit (the
             * x86-64-v3 one, where this CPU takes it, is the same code
             * compiled with FMA). */
            mr_lod_params pp = MR_LOD_DEFAULTS;
            pp.portable = true;
            mr_lod *port = mr_lod_build(s, &pp, &err);
            CHECK_MSG(port && port->meshes[0].level_count == ml->level_count, "unit %g: portable kernel: %d levels, %s %d",
                      units[u], port ? port->meshes[0].level_count : -1, mr_lod_kernel(NULL), ml->level_count);
            for (int k = 0; port && k < ml->level_count && k < port->meshes[0].level_count; k++) {
                const mr_lod_level *a = &ml->levels[k], *b = &port->meshes[0].levels[k];
                CHECK_MSG(a->index_count == b->index_count && memcmp(a->indices, b->indices, (size_t)a->index_count * 4) == 0 &&
                              fabs(a->error - b->error) <= 1e-9 * b->error,
                          "unit %g level %d: %s kernel %u triangles, error %.17g; portable %u, %.17g", units[u], k,
                          mr_lod_kernel(NULL), a->index_count / 3, a->error, b->index_count / 3, b->error);
            }
            mr_lod_destroy(&port);
        }
        mr_lod_destroy(&lod);
        mr_scene_destroy(&s);
    }
}

/* Levels engage on seam-split parts, stay within 2 % of the part's size,
 * hold against brute force, and are the same in every unit. */
static void test_cad_levels(void) {
    static const double units[] = {1e-3, 1, 1e3};
    mr_lod *ref = NULL;
    mr_scene *ref_s = NULL;
    for (int u = 0; u < 3; u++) {
        mr_scene *s = cad(units[u], 1, 1500);
        if (!s) continue;
        mr_error err = {0};
        mr_lod *lod = mr_lod_build(s, NULL, &err);
        CHECK_MSG(lod != NULL, "%s", err.msg);
        if (!lod) {
            mr_scene_destroy(&s);
            continue;
        }
        for (int32_t i = 1; i < s->mesh_count; i++) { /* mesh 0: the floor (12 triangles) */
            const mr_mesh *m = &s->meshes[i];
            const mr_mesh_lods *ml = &lod->meshes[i];
            double size = mesh_size(m);
            CHECK_MSG(ml->level_count >= 1, "unit %g, part %d: %d levels", units[u], (int)i, ml->level_count);
            if (ml->level_count < 1) continue;
            const mr_lod_level *last = &ml->levels[ml->level_count - 1];
            /* Engages: the coarsest level keeps at most half of these
             * coarsely tessellated parts' triangles (46 % with the chained
             * bound, 41 % with each level certified against the full mesh;
             * without the weld, meshoptimizer's own seam handling stalls
             * sooner). */
            CHECK_MSG(last->index_count * 100 <= m->index_count * 50, "unit %g, part %d: coarsest %u of %u triangles", units[u],
                      (int)i, last->index_count / 3, m->index_count / 3);
            printf("  unit %g part %d: %u triangles, size %g:", units[u], (int)i, m->index_count / 3, size);
            for (int k = 0; k < ml->level_count; k++) printf(" %u@%.3g", ml->levels[k].index_count / 3, ml->levels[k].error / size);
            printf("\n");
            double prev = 0;
            for (int k = 0; k < ml->level_count; k++) {
                const mr_lod_level *l = &ml->levels[k];
                CHECK(l->error >= prev && l->error <= MR_LOD_DEFAULT_REL_ERROR * size * (1 + 1e-6));
                prev = l->error;
                double ab = mr_test_sampled_distance(m->positions, m->indices, m->index_count, l->indices, l->index_count, 2);
                double ba = mr_test_sampled_distance(m->positions, l->indices, l->index_count, m->indices, m->index_count, 3);
                double brute = fmax(ab, ba);
                CHECK_MSG(brute <= l->error * (1 + 1e-6) + 1e-7 * size, "unit %g part %d level %d: sampled %g > bound %g",
                          units[u], (int)i, k, brute, l->error);
                /* Not vacuous: a sum of chained steps, each within a
                 * quarter of its truth plus the resolution (5 % of the
                 * level's error budget) plus what sampling misses. */
                CHECK_MSG(l->error <= 2.5 * brute + 0.05 * MR_LOD_DEFAULT_REL_ERROR * size,
                          "unit %g part %d level %d: bound %g vs sampled %g", units[u], (int)i, k, l->error, brute);
            }
        }
        if (u == 1) {
            ref = lod;
            ref_s = s;
            continue;
        }
        if (u == 2 && ref) {
            /* The same levels in kilounits as in units (compared with metres). */
            for (int32_t i = 0; i < s->mesh_count; i++) {
                CHECK_MSG(lod->meshes[i].level_count == ref->meshes[i].level_count, "part %d: %d levels at unit 1000, %d at 1",
                          (int)i, lod->meshes[i].level_count, ref->meshes[i].level_count);
                for (int k = 0; k < lod->meshes[i].level_count && k < ref->meshes[i].level_count; k++) {
                    const mr_lod_level *a = &lod->meshes[i].levels[k], *b = &ref->meshes[i].levels[k];
                    /* Built on their own: meshoptimizer breaks ties in its
                     * collapse order by rounding, so a few triangles may differ. */
                    CHECK_MSG(labs((long)a->index_count - (long)b->index_count) * 20 <= (long)b->index_count &&
                                  a->error / units[2] <= 1.1 * b->error + 1e-3 * mesh_size(&ref_s->meshes[i]) &&
                                  b->error <= 1.1 * a->error / units[2] + 1e-3 * mesh_size(&ref_s->meshes[i]),
                              "part %d level %d: %u triangles at %g (x1000) vs %u at %g", (int)i, k, a->index_count / 3,
                              a->error / units[2], b->index_count / 3, b->error);
                }
            }
        }
        mr_lod_destroy(&lod);
        mr_scene_destroy(&s);
    }
    mr_lod_destroy(&ref);
    mr_scene_destroy(&ref_s);
}

/* Each corner of a level keeps a normal of its own side of a crease: its
 * vertex normal agrees with the level triangle's face normal. */
static void test_seam_normals(void) {
    mr_scene *s = cad(1, 2, 1500);
    if (!s) return;
    mr_error err = {0};
    mr_lod *lod = mr_lod_build(s, NULL, &err);
    CHECK_MSG(lod != NULL, "%s", err.msg);
    for (int32_t i = 1; lod && i < s->mesh_count; i++) {
        const mr_mesh *m = &s->meshes[i];
        for (int k = 0; k < lod->meshes[i].level_count; k++) {
            const mr_lod_level *l = &lod->meshes[i].levels[k];
            size_t agree = 0, corners = 0;
            for (uint32_t t = 0; t + 2 < l->index_count; t += 3) {
                const float *a = m->positions + 3 * (size_t)l->indices[t], *b = m->positions + 3 * (size_t)l->indices[t + 1],
                            *c = m->positions + 3 * (size_t)l->indices[t + 2];
                double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
                double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
                double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                if (!(nl > 0)) continue;
                for (int j = 0; j < 3; j++) {
                    const float *vn = m->normals + 3 * (size_t)l->indices[t + (uint32_t)j];
                    corners++;
                    agree += (vn[0] * n[0] + vn[1] * n[1] + vn[2] * n[2]) / nl > 0.5;
                }
            }
            CHECK_MSG(agree >= 0.97 * corners, "part %d level %d: %zu of %zu corners with a normal off their face", (int)i, k,
                      corners - agree, corners);
        }
    }
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
}

/* A factory and its copies 1024x and 1000x larger, each with its own
 * levels, seen from corresponding views with the default draw settings.
 * 1024x scales every float exactly, so everything (welding, meshoptimizer,
 * the bounds, the choice) must come out the same: the same number of
 * instances at each level and the same triangles. 1000x rounds every
 * coordinate differently and meshoptimizer breaks ties in its collapse
 * order by those roundings, so its levels differ by a few triangles: the
 * same instances are simplified and the triangles agree within 10 %. Any
 * tolerance in scene units (the old 5 mm cap) fails both. */
static void test_units_same_choice(mr_renderer *r) {
    enum { PARTS = 6 };
    static const double units[3] = {1, 1024, 1000};
    mr_scene *s[3];
    mr_lod *lod[3] = {NULL, NULL, NULL};
    mr_error err = {0};
    bool ok = true;
    for (int u = 0; u < 3; u++) {
        s[u] = cad(units[u], PARTS, 1200);
        lod[u] = s[u] ? mr_lod_build(s[u], NULL, &err) : NULL;
        ok = ok && lod[u];
    }
    CHECK_MSG(ok, "%s", err.msg);
    uint32_t any_lod = 0;
    for (int v = 0; ok && v < MR_SYNTH_VIEW_COUNT; v++) {
        mr_draw_stats st[3];
        mr_frame_result res[3];
        memset(res, 0, sizeof res);
        for (int u = 0; u < 3 && ok; u++) {
            mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
            cp.parts = PARTS;
            cp.part_triangles = 1200;
            cp.unit = units[u];
            mr_view view;
            memset(&view, 0, sizeof view);
            view.camera = mr_demo_camera();
            memset(view.camera.dist, 0, sizeof view.camera.dist);
            view.camera.width = 160;
            view.camera.height = 120;
            view.camera.fx = view.camera.fy = 150;
            view.camera.cx = 79.5;
            view.camera.cy = 59.5;
            view.world_from_camera = mr_synth_cad_viewpoint(&cp, v);
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = 160;
            fp.height = 120;
            ok = mr_renderer_set_scene(r, s[u], &err) && mr_renderer_set_lod(r, lod[u], &err) &&
                 mr_renderer_set_draw_params(r, NULL, &err) && mr_render_frame(r, &view, &fp, &res[u], &err);
            CHECK_MSG(ok, "%s", err.msg);
            if (ok) mr_renderer_draw_stats(r, &st[u]);
        }
        if (ok) {
            printf("  view %d: %llu triangles of %llu, levels", v, (unsigned long long)st[0].triangles,
                   (unsigned long long)st[0].triangles_full);
            for (int k = 0; k <= MR_LOD_MAX_LEVELS; k++)
                printf(" %u/%u/%u", st[0].level_instances[k], st[1].level_instances[k], st[2].level_instances[k]);
            printf(" (x1, x1024, x1000); x1000 %llu triangles\n", (unsigned long long)st[2].triangles);
            for (int k = 0; k <= MR_LOD_MAX_LEVELS; k++)
                CHECK_MSG(st[0].level_instances[k] == st[1].level_instances[k],
                          "view %d: %u instances at level %d in unit 1, %u in unit 1/1024", v, st[0].level_instances[k], k,
                          st[1].level_instances[k]);
            CHECK_MSG(st[0].triangles == st[1].triangles, "view %d: %llu triangles in unit 1, %llu in unit 1/1024", v,
                      (unsigned long long)st[0].triangles, (unsigned long long)st[1].triangles);
            CHECK_MSG(st[0].lod_instances == st[2].lod_instances &&
                          llabs((long long)st[0].triangles - (long long)st[2].triangles) * 100 <= 15 * (long long)st[0].triangles,
                      "view %d: %u simplified instances, %llu triangles in metres; %u, %llu in millimetres", v,
                      st[0].lod_instances, (unsigned long long)st[0].triangles, st[2].lod_instances,
                      (unsigned long long)st[2].triangles);
            any_lod += st[0].lod_instances;
            /* The same picture (up to rasterisation of differently rounded floats). */
            for (int u = 1; u < 3; u++) {
                size_t bad = 0, n = (size_t)160 * 120;
                const unsigned char *a = res[0].color.data, *b = res[u].color.data;
                int ch = res[0].color.channels;
                for (size_t i = 0; i < n; i++)
                    for (int c = 0; c < ch; c++)
                        if (abs((int)a[i * ch + c] - (int)b[i * ch + c]) > 24) {
                            bad++;
                            break;
                        }
                CHECK_MSG(bad <= n / 100, "view %d: %zu of %zu pixels differ between unit 1 and %g", v, bad, n, units[u]);
            }
        }
        for (int u = 0; u < 3; u++) mr_frame_result_free(&res[u]);
    }
    CHECK_MSG(any_lod > 0, "test set-up: no view drew a simplified level (%u)", any_lod);
    mr_renderer_set_scene(r, NULL, &err);
    for (int u = 0; u < 3; u++) {
        mr_lod_destroy(&lod[u]);
        mr_scene_destroy(&s[u]);
    }
}

/* issue 17 (lane cluster): the CAD factory's materials are single-sided,
 * which is right only if every mesh is a closed surface wound outwards.
 * Positions welded on a fine grid (the seams repeat them, up to rounding):
 * every directed edge of a non-degenerate triangle has its reverse as
 * often (closed, consistently oriented), and the signed volume of each
 * connected piece (plate, body, rim, bolts) is positive (outwards). */
typedef struct wkey {
    int64_t q[3];
    uint32_t v;
} wkey;
static int wkey_cmp(const void *a, const void *b) {
    const wkey *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->q[k] != y->q[k]) return x->q[k] < y->q[k] ? -1 : 1;
    return 0;
}
static int edge_cmp(const void *a, const void *b) {
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}
static uint32_t uf_find(uint32_t *p, uint32_t x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
}
static bool closed_outward(const mr_mesh *m, double cell, double *volume) {
    wkey *k = malloc((size_t)m->vertex_count * sizeof *k);
    uint32_t *weld = malloc((size_t)m->vertex_count * sizeof *weld);
    uint64_t *fw = malloc((size_t)m->index_count * sizeof *fw), *bw = malloc((size_t)m->index_count * sizeof *bw);
    bool ok = k && weld && fw && bw;
    for (uint32_t v = 0; ok && v < m->vertex_count; v++) {
        for (int c = 0; c < 3; c++) k[v].q[c] = (int64_t)llround(m->positions[3 * v + c] / cell);
        k[v].v = v;
    }
    if (ok) qsort(k, m->vertex_count, sizeof *k, wkey_cmp);
    uint32_t id = 0;
    for (uint32_t v = 0; ok && v < m->vertex_count; v++) {
        if (v > 0 && wkey_cmp(&k[v], &k[v - 1]) != 0) id++;
        weld[k[v].v] = id;
    }
    size_t ne = 0;
    double vol = 0;
    uint32_t *uf = ok ? malloc(((size_t)id + 1) * sizeof *uf) : NULL;
    double *pvol = ok ? calloc((size_t)id + 1, sizeof *pvol) : NULL;
    ok = ok && uf && pvol;
    for (uint32_t v = 0; ok && v <= id; v++) uf[v] = v;
    for (uint32_t t = 0; ok && t + 2 < m->index_count; t += 3) {
        uint32_t a = weld[m->indices[t]], b = weld[m->indices[t + 1]], c = weld[m->indices[t + 2]];
        uf[uf_find(uf, a)] = uf_find(uf, b);
        uf[uf_find(uf, b)] = uf_find(uf, c);
    }
    for (uint32_t t = 0; ok && t + 2 < m->index_count; t += 3) {
        uint32_t a = weld[m->indices[t]], b = weld[m->indices[t + 1]], c = weld[m->indices[t + 2]];
        const float *p0 = m->positions + 3 * (size_t)m->indices[t], *p1 = m->positions + 3 * (size_t)m->indices[t + 1],
                    *p2 = m->positions + 3 * (size_t)m->indices[t + 2];
        double tv = (p0[0] * ((double)p1[1] * p2[2] - (double)p1[2] * p2[1]) -
                     p0[1] * ((double)p1[0] * p2[2] - (double)p1[2] * p2[0]) +
                     p0[2] * ((double)p1[0] * p2[1] - (double)p1[1] * p2[0])) / 6;
        vol += tv;
        pvol[uf_find(uf, a)] += tv;
        if (a == b || b == c || c == a) continue;
        const uint32_t e[3][2] = {{a, b}, {b, c}, {c, a}};
        for (int j = 0; j < 3; j++) {
            fw[ne] = (uint64_t)e[j][0] << 32 | e[j][1];
            bw[ne++] = (uint64_t)e[j][1] << 32 | e[j][0];
        }
    }
    if (ok) {
        qsort(fw, ne, sizeof *fw, edge_cmp);
        qsort(bw, ne, sizeof *bw, edge_cmp);
        ok = memcmp(fw, bw, ne * sizeof *fw) == 0;
        for (uint32_t v = 0; ok && v <= id; v++)
            if (uf_find(uf, v) == v && pvol[v] < 0) ok = false; /* a piece wound inwards */
    }
    free(uf);
    free(pvol);
    *volume = vol;
    free(k);
    free(weld);
    free(fw);
    free(bw);
    return ok && vol > 0;
}

static void test_closed_outward(void) {
    const double units[2] = {1, 1000};
    for (int u = 0; u < 2; u++) {
        mr_scene *s = cad(units[u], 12, 3000);
        if (!s) return;
        int good = 0;
        for (int32_t i = 0; i < s->mesh_count; i++) {
            const mr_mesh *m = &s->meshes[i];
            double vol = 0;
            bool ok = closed_outward(m, 1e-5 * units[u], &vol);
            CHECK_MSG(ok, "unit %g mesh %s: not a closed outward surface (signed volume %g)", units[u], m->name, vol);
            good += ok;
            CHECK(m->material >= 0 && s->materials[m->material].single_sided);
        }
        CHECK(good == s->mesh_count && s->mesh_count == 13);
        mr_scene_destroy(&s);
    }
}

/* The part count for a triangle target (mrcheck factory --unique, bench
 * scene --unique, bench load): nearest, at least 1, at most 1e6; and a
 * built factory of that many parts stores about the target. */
static void test_parts_for(void) {
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    CHECK(mr_synth_cad_parts_for(&cp, 2e6) == 100);
    CHECK(mr_synth_cad_parts_for(&cp, 29999) == 1 && mr_synth_cad_parts_for(&cp, 30001) == 2);
    CHECK(mr_synth_cad_parts_for(&cp, 0) == 1 && mr_synth_cad_parts_for(&cp, -5) == 1);
    CHECK(mr_synth_cad_parts_for(&cp, 1e15) == 1000000 && mr_synth_cad_parts_for(&cp, NAN) == 1);
    cp.part_triangles = 0; /* the default */
    CHECK(mr_synth_cad_parts_for(&cp, 2e6) == 100);
    cp.part_triangles = 5000;
    cp.parts = mr_synth_cad_parts_for(&cp, 2e4);
    CHECK(cp.parts == 4);
    mr_error err = {0};
    mr_scene *s = mr_synth_cad_build(&cp, &err);
    CHECK_MSG(s != NULL, "%s", err.msg);
    uint64_t stored = 0;
    for (int32_t i = 0; s && i < s->mesh_count; i++) stored += s->meshes[i].index_count / 3;
    CHECK_MSG(stored > 1e4 && stored < 4e4, "4 parts of ~5000: %llu triangles", (unsigned long long)stored);
    mr_scene_destroy(&s);
    /* The viewpoints as files (mrcheck factory --views): each reads back
     * as the view it was made from; a file where the folder should be
     * fails with one line. */
    char dir[1024], path[1200];
    CHECK(mr_test_fresh_dir("cad_views", dir, sizeof dir));
    CHECK_MSG(mr_synth_save_views(dir, NULL, &cp, &err), "%s", err.msg);
    for (int v = 0; v < MR_SYNTH_VIEW_COUNT; v++) {
        snprintf(path, sizeof path, "%s/view_%s.json", dir, mr_synth_view_name(v));
        mr_view got, want = mr_synth_view(NULL, &cp, v);
        CHECK_MSG(mr_view_load(path, &got, &err), "%s: %s", path, err.msg);
        double worst = 0;
        for (int k = 0; k < 16; k++) worst = fmax(worst, fabs(got.world_from_camera.m[k] - want.world_from_camera.m[k]));
        CHECK_MSG(worst < 1e-9 && got.camera.width == want.camera.width && got.camera.dist[0] == 0, "%s: pose off by %g", path,
                  worst);
    }
    snprintf(path, sizeof path, "%s/view_floor.json", dir);
    CHECK(!mr_synth_save_views(path, NULL, &cp, &err) && err.msg[0] && !strchr(err.msg, '\n'));
}

static bool stop_at_first(void *user, double fraction) {
    (void)fraction;
    ++*(int *)user;
    return false;
}

/* Levels off the caller's thread (the view builds them while it draws):
 * the same levels as a build here; a stop from on_progress or a cancel
 * ends the build with no levels and no cache. */
static void test_async(void) {
    mr_scene *s = cad(1, 4, 1500);
    if (!s) return;
    mr_error err = {0};
    mr_lod *ref = mr_lod_build(s, NULL, &err);
    CHECK_MSG(ref != NULL, "%s", err.msg);
    mr_lod_builder *b = mr_lod_build_async(s, NULL, NULL, &err);
    CHECK_MSG(b != NULL, "%s", err.msg);
    double f = -1;
    while (b && !mr_lod_builder_poll(b, &f)) {
        CHECK(f >= 0 && f <= 1);
        struct timespec ts = {0, 1000000};
        nanosleep(&ts, NULL);
    }
    CHECK(f == 1.0);
    mr_lod_info info;
    mr_lod *l = b ? mr_lod_builder_finish(&b, &info, &err) : NULL;
    CHECK_MSG(l != NULL && b == NULL, "%s", err.msg);
    CHECK(l && !info.from_cache && info.levels > 0);
    for (int32_t i = 0; l && ref && i < s->mesh_count; i++) {
        CHECK(l->meshes[i].level_count == ref->meshes[i].level_count);
        for (int k = 0; k < l->meshes[i].level_count && k < ref->meshes[i].level_count; k++)
            CHECK(l->meshes[i].levels[k].index_count == ref->meshes[i].levels[k].index_count &&
                  l->meshes[i].levels[k].error == ref->meshes[i].levels[k].error &&
                  memcmp(l->meshes[i].levels[k].indices, ref->meshes[i].levels[k].indices,
                         l->meshes[i].levels[k].index_count * sizeof(uint32_t)) == 0);
    }
    mr_lod_destroy(&l);
    /* Stopped by the caller's progress hook: one call, then nothing. */
    char cache[4096];
    snprintf(cache, sizeof cache, "%s/mr_test_cad_async_%d.mrlod", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", (int)getpid());
    remove(cache);
    int calls = 0;
    mr_lod_params lp = MR_LOD_DEFAULTS;
    lp.on_progress = stop_at_first;
    lp.progress_user = &calls;
    b = mr_lod_build_async(s, cache, &lp, &err);
    CHECK_MSG(b != NULL, "%s", err.msg);
    mr_error e2 = {0};
    l = b ? mr_lod_builder_finish(&b, NULL, &e2) : NULL;
    CHECK(l == NULL && strstr(e2.msg, "cancelled") != NULL);
    CHECK_MSG(calls == 1, "%d progress calls, one expected (none after a stop)", calls);
    FILE *fc = fopen(cache, "rb");
    CHECK_MSG(fc == NULL, "a cancelled build wrote %s", cache);
    if (fc) fclose(fc);
    remove(cache);
    /* Cancelled while running (or already done): no leak, no wait for all. */
    b = mr_lod_build_async(s, NULL, NULL, &err);
    CHECK(b != NULL);
    mr_lod_builder_cancel(&b);
    CHECK(b == NULL);
    mr_lod_builder_cancel(&b); /* accepts NULL */
    mr_lod_destroy(&ref);
    mr_scene_destroy(&s);
}

int main(void) {
    double t = mr_time_now();
#define RUN(f) f; printf("%s: %.2f s\n", #f, mr_time_now() - t); t = mr_time_now()
    RUN(test_closed_outward()); /* issue 17 (lane cluster) */
    RUN(test_split_cylinder());
    RUN(test_cad_levels());
    RUN(test_seam_normals());
    RUN(test_parts_for());
    RUN(test_async());
    mr_error err = {0};
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) {
        mr_test_finish("test_cad");
        return mr_test_failures ? 1 : mr_test_no_gpu("test_cad", &err);
    }
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    if (r) {
        RUN(test_units_same_choice(r));
    }
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return mr_test_finish("test_cad");
}
