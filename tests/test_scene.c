/* Scene module: builder, normals, bounds, globs, glTF load/save round trip,
 * content sniffing, scene configs, and bad input that must fail cleanly. */
#include "mr_scene.h"
#include "mr_test.h"
#include "prepare_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char g_tmp[1024];

static void tmp_path(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", g_tmp, name); }

static bool write_file(const char *path, const void *data, size_t n) {
    FILE *f = fopen(path, "wb");
    if (!f) return false;
    bool ok = fwrite(data, 1, n, f) == n;
    return (fclose(f) == 0) && ok;
}

static bool one_line_msg(const mr_error *e) {
    return e->msg[0] != 0 && strchr(e->msg, '\n') == NULL && strchr(e->msg, '\r') == NULL;
}

/* ------------------------------------------------------------ helpers */

static float *fdup(const float *v, size_t n) {
    float *p = malloc(n * sizeof *p);
    memcpy(p, v, n * sizeof *p);
    return p;
}
static uint32_t *udup(const uint32_t *v, size_t n) {
    uint32_t *p = malloc(n * sizeof *p);
    memcpy(p, v, n * sizeof *p);
    return p;
}

/* Axis-aligned box [lo,hi] as 8 shared vertices and 12 triangles (CCW out). */
static mr_mesh make_box(const char *name, double cx, double cy, double cz, double h) {
    static const uint32_t idx[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                     2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    m.positions = malloc(24 * sizeof(float));
    for (int i = 0; i < 8; i++) {
        double x = (i == 1 || i == 2 || i == 5 || i == 6) ? h : -h;
        double y = (i == 2 || i == 3 || i == 6 || i == 7) ? h : -h;
        double z = i >= 4 ? h : -h;
        /* Positions given absolute (far from 0); add_mesh recentres them. */
        m.positions[3 * i] = (float)(cx + x);
        m.positions[3 * i + 1] = (float)(cy + y);
        m.positions[3 * i + 2] = (float)(cz + z);
    }
    m.indices = udup(idx, 36);
    m.vertex_count = 8;
    m.index_count = 36;
    m.material = -1;
    return m;
}

static mr_dmat4 model_of(const mr_scene *s, const mr_node *n, int k) {
    const mr_mesh *m = &s->meshes[n->mesh_first + k];
    mr_dmat4 t = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
    return mr_m4_mul(&n->world, &t);
}

static bool mat_close(const mr_dmat4 *a, const mr_dmat4 *b, double rel) {
    for (int i = 0; i < 16; i++) {
        double tol = rel * fmax(1.0, fabs(b->m[i]));
        if (!(fabs(a->m[i] - b->m[i]) <= tol)) return false;
    }
    return true;
}

static const mr_node *find_node(const mr_scene *s, const char *name) {
    for (int i = 0; i < s->node_count; i++)
        if (strcmp(s->nodes[i].name, name) == 0) return &s->nodes[i];
    return NULL;
}

static mr_node make_node(const char *name, int32_t parent, mr_dmat4 world, int32_t first, int32_t count) {
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "%s", name);
    n.parent = parent;
    n.world = world;
    n.mesh_first = first;
    n.mesh_count = count;
    n.layer = MR_LAYER_VISIBLE;
    return n;
}

/* ------------------------------------------------------------ builder */

static void test_builder(void) {
    mr_scene *s = mr_scene_create();
    CHECK(s != NULL);
    CHECK_NEAR(s->ambient, 0.35, 1e-6);

    /* Cube far from the origin: positions get recentred into origin. */
    mr_mesh box = make_box("box", 1000.0, 2000.0, 3000.0, 1.0);
    mr_error err = {0};
    int32_t bi = mr_scene_add_mesh(s, &box, &err);
    CHECK(bi == 0);
    CHECK(box.positions == NULL && box.indices == NULL); /* ownership moved */
    const mr_mesh *m = &s->meshes[0];
    CHECK_NEAR(m->origin[0], 1000.0, 1e-3);
    CHECK_NEAR(m->origin[1], 2000.0, 1e-3);
    CHECK_NEAR(m->origin[2], 3000.0, 1e-3);
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(m->bounds_min[k], -1.0, 1e-3);
        CHECK_NEAR(m->bounds_max[k], 1.0, 1e-3);
        CHECK_NEAR(m->bounds_min[k] + m->bounds_max[k], 0.0, 1e-6); /* centred */
    }
    CHECK(m->normals != NULL);
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const float *n = m->normals + 3 * v;
        const float *p = m->positions + 3 * v;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        CHECK_NEAR(len, 1.0, 1e-5);
        /* Corner normals point outwards, along the corner's diagonal. */
        double d = (n[0] * p[0] + n[1] * p[1] + n[2] * p[2]) / sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        CHECK(d > 0.8);
    }

    /* A degenerate triangle and a zero normal stay finite. */
    {
        float pos[9] = {1, 1, 1, 2, 2, 2, 3, 3, 3}; /* collinear */
        uint32_t idx[3] = {0, 1, 2};
        mr_mesh d;
        memset(&d, 0, sizeof d);
        snprintf(d.name, sizeof d.name, "degenerate");
        d.positions = fdup(pos, 9);
        d.indices = udup(idx, 3);
        d.vertex_count = 3;
        d.index_count = 3;
        d.material = -1;
        int32_t di = mr_scene_add_mesh(s, &d, &err);
        CHECK(di == 1);
        for (int i = 0; i < 9; i++) CHECK(isfinite(s->meshes[di].normals[i]));
        CHECK_NEAR(s->meshes[di].normals[1], 1.0, 1e-6); /* fallback (0,1,0) */

        float nrm[9] = {0, 0, 0, 0, 0, 5, 1e-30f, 0, 0};
        mr_mesh e;
        memset(&e, 0, sizeof e);
        e.positions = fdup(pos, 9);
        e.normals = fdup(nrm, 9);
        e.indices = udup(idx, 3);
        e.vertex_count = 3;
        e.index_count = 3;
        e.material = -1;
        int32_t ei = mr_scene_add_mesh(s, &e, &err);
        CHECK(ei == 2);
        const float *en = s->meshes[ei].normals;
        CHECK_NEAR(en[1], 1.0, 1e-6);
        CHECK_NEAR(en[5], 1.0, 1e-6);
        CHECK_NEAR(en[6], 1.0, 1e-6); /* tiny but non-zero: still normalised */

        float gen[9];
        mr_mesh_generate_normals(pos, 3, idx, 3, gen);
        for (int i = 0; i < 9; i++) CHECK(isfinite(gen[i]));
    }

    /* Invalid meshes fail; the caller keeps (and frees) its arrays. */
    {
        float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        uint32_t bad_idx[3] = {0, 1, 3};
        mr_mesh b;
        memset(&b, 0, sizeof b);
        snprintf(b.name, sizeof b.name, "badidx");
        b.positions = fdup(pos, 9);
        b.indices = udup(bad_idx, 3);
        b.vertex_count = 3;
        b.index_count = 3;
        b.material = -1;
        CHECK(mr_scene_add_mesh(s, &b, &err) == -1);
        CHECK(err.code == MR_ERR_INVALID && strstr(err.msg, "badidx") != NULL);
        CHECK(b.positions != NULL);
        b.indices[2] = 2;
        b.index_count = 2;
        CHECK(mr_scene_add_mesh(s, &b, &err) == -1);
        b.index_count = 3;
        b.positions[4] = NAN;
        CHECK(mr_scene_add_mesh(s, &b, &err) == -1);
        CHECK(strstr(err.msg, "non-finite position") != NULL);
        b.positions[4] = 0;
        b.material = 5; /* no such material */
        CHECK(mr_scene_add_mesh(s, &b, &err) == -1);
        free(b.positions);
        free(b.indices);
        CHECK(s->mesh_count == 3);
    }

    /* Bounds: box of half-size 1 at mesh origin (5,0,0), node rotated 90
     * degrees about z and moved by (10,0,0): the box lands at (10,5,0). */
    {
        mr_scene *t = mr_scene_create();
        mr_mesh b2 = make_box("b2", 5.0, 0.0, 0.0, 1.0);
        CHECK(mr_scene_add_mesh(t, &b2, &err) == 0);
        mr_dmat4 tr = mr_m4_translate(10, 0, 0);
        mr_dmat4 rz = mr_m4_rotate_axis(mr_v3(0, 0, 1), M_PI / 2);
        mr_node n = make_node("rotated", -1, mr_m4_mul(&tr, &rz), 0, 1);
        CHECK(mr_scene_add_node(t, &n) == 0);
        mr_node n2 = make_node("copy", -1, mr_m4_identity(), 0, 1);
        CHECK(mr_scene_add_node(t, &n2) == 1);
        mr_node bad = make_node("bad", 7, mr_m4_identity(), -1, 0);
        CHECK(mr_scene_add_node(t, &bad) == -1);
        mr_scene_update_bounds(t);
        CHECK_NEAR(t->bounds_min[0], 4.0, 1e-5);
        CHECK_NEAR(t->bounds_max[0], 11.0, 1e-5);
        CHECK_NEAR(t->bounds_min[1], -1.0, 1e-5);
        CHECK_NEAR(t->bounds_max[1], 6.0, 1e-5);
        CHECK_NEAR(t->bounds_min[2], -1.0, 1e-5);
        CHECK_NEAR(t->bounds_max[2], 1.0, 1e-5);
        CHECK(mr_scene_triangle_count(t) == 24); /* instances count each time */
        mr_scene_destroy(&t);
        CHECK(t == NULL);
    }

    /* Textures: gray becomes RGBA, ownership moves. */
    {
        mr_texture tex;
        memset(&tex, 0, sizeof tex);
        CHECK(mr_image_alloc(&tex.image, 2, 2, 1, MR_PIX_U8, &err));
        ((uint8_t *)tex.image.data)[3] = 200;
        CHECK(mr_scene_add_texture(s, &tex) == 0);
        CHECK(tex.image.data == NULL);
        CHECK(s->textures[0].image.channels == 4);
        const uint8_t *px = s->textures[0].image.data;
        CHECK(px[12] == 200 && px[13] == 200 && px[15] == 255);
        mr_material mat = {.name = "m", .base_color = {1, 1, 1, 1}, .base_color_texture = 0};
        CHECK(mr_scene_add_material(s, &mat) == 0);
        mat.base_color_texture = 3;
        CHECK(mr_scene_add_material(s, &mat) == -1);
    }

    mr_scene_destroy(&s);
    CHECK(s == NULL);
    mr_scene_destroy(&s);   /* NULL pointer */
    mr_scene_destroy(NULL); /* NULL handle */
}

/* mr_scene_add_mesh in two steps (mr_mesh_prepare, then
 * mr_scene_add_prepared_mesh, as the loader does on its second core): the
 * same mesh as in one step, bit for bit; a prepare that fails changes
 * nothing; preparing an added mesh's arrays again changes none of its
 * normals (a saved and reloaded mesh keeps them). */
static void test_prepare(void) {
    enum { nv = 5000 };
    mr_mesh a, b;
    memset(&a, 0, sizeof a);
    a.vertex_count = nv;
    a.index_count = 3 * (nv - 2);
    a.material = -1;
    a.origin[0] = 1e7;
    a.positions = malloc(nv * 3 * sizeof(float));
    a.normals = malloc(nv * 3 * sizeof(float));
    a.indices = malloc(a.index_count * sizeof(uint32_t));
    CHECK(a.positions && a.normals && a.indices);
    if (!a.positions || !a.normals || !a.indices) return;
    uint32_t r = 12345;
    for (int i = 0; i < 3 * nv; i++) {
        r = r * 1664525u + 1013904223u;
        a.positions[i] = (float)(r >> 8) * 1e-3f - 5000.0f;
        /* lengths from 1e-3 to 1e3, and some exactly 0 (the fallback) */
        a.normals[i] = i < 30 ? 0.0f : ((float)(r >> 8) / 16777216.0f - 0.5f) * powf(10.0f, (float)(i % 7) - 3.0f);
    }
    for (uint32_t t = 0; t < a.index_count; t++) a.indices[t] = t / 3 + t % 3;
    b = a;
    b.positions = malloc(nv * 3 * sizeof(float));
    b.normals = malloc(nv * 3 * sizeof(float));
    b.indices = malloc(a.index_count * sizeof(uint32_t));
    CHECK(b.positions && b.normals && b.indices);
    if (!b.positions || !b.normals || !b.indices) return;
    memcpy(b.positions, a.positions, nv * 3 * sizeof(float));
    memcpy(b.normals, a.normals, nv * 3 * sizeof(float));
    memcpy(b.indices, a.indices, a.index_count * sizeof(uint32_t));
    mr_scene *s1 = mr_scene_create(), *s2 = mr_scene_create();
    mr_error err = {0};
    /* A non-finite normal at the end: refused, and nothing changed. */
    b.normals[3 * nv - 1] = INFINITY;
    CHECK(!mr_mesh_prepare(&b, &err) && strstr(err.msg, "non-finite normal") != NULL);
    CHECK(memcmp(b.positions, a.positions, nv * 3 * sizeof(float)) == 0 && b.origin[0] == 1e7);
    b.normals[3 * nv - 1] = a.normals[3 * nv - 1];
    CHECK_MSG(mr_scene_add_mesh(s1, &a, &err) == 0, "one step: %s", err.msg);
    CHECK_MSG(mr_mesh_prepare(&b, &err), "prepare: %s", err.msg);
    CHECK_MSG(mr_scene_add_prepared_mesh(s2, &b, &err) == 0, "prepared: %s", err.msg);
    CHECK(a.positions == NULL && b.positions == NULL);
    if (s1->mesh_count == 1 && s2->mesh_count == 1) {
        const mr_mesh *m1 = &s1->meshes[0], *m2 = &s2->meshes[0];
        CHECK(memcmp(m1->positions, m2->positions, nv * 3 * sizeof(float)) == 0);
        CHECK(memcmp(m1->normals, m2->normals, nv * 3 * sizeof(float)) == 0);
        CHECK(memcmp(m1->origin, m2->origin, sizeof m1->origin) == 0);
        CHECK(memcmp(m1->bounds_min, m2->bounds_min, sizeof m1->bounds_min) == 0);
        double worst = 0;
        for (int v = 0; v < nv; v++) {
            const float *n = m1->normals + 3 * v;
            worst = fmax(worst, fabs(sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]) - 1.0));
        }
        CHECK_MSG(worst < 1e-6, "normals off unit length by %g", worst);
        /* Again: the normals stay as they are. */
        mr_mesh c = *m1;
        c.positions = malloc(nv * 3 * sizeof(float));
        c.normals = malloc(nv * 3 * sizeof(float));
        c.indices = malloc(c.index_count * sizeof(uint32_t));
        CHECK(c.positions && c.normals && c.indices);
        if (c.positions && c.normals && c.indices) {
            memcpy(c.positions, m1->positions, nv * 3 * sizeof(float));
            memcpy(c.normals, m1->normals, nv * 3 * sizeof(float));
            memcpy(c.indices, m1->indices, c.index_count * sizeof(uint32_t));
            CHECK(mr_mesh_prepare(&c, &err));
            CHECK_MSG(memcmp(c.normals, m1->normals, nv * 3 * sizeof(float)) == 0, "normals changed when prepared again");
        }
        free(c.positions);
        free(c.normals);
        free(c.indices);
    }
    CHECK(s1->mesh_count == 1 && s2->mesh_count == 1);
    /* A prepared mesh whose material the scene lacks: refused, still the caller's. */
    mr_mesh d;
    memset(&d, 0, sizeof d);
    d.vertex_count = 3;
    d.material = 3;
    d.positions = calloc(9, sizeof(float));
    CHECK(d.positions && mr_mesh_prepare(&d, &err));
    CHECK(mr_scene_add_prepared_mesh(s2, &d, &err) == -1 && strstr(err.msg, "material") != NULL && d.positions != NULL);
    free(d.positions);
    free(d.normals);
    mr_scene_destroy(&s1);
    mr_scene_destroy(&s2);
}

/* ------------------------------------------- the prepare step's passes */

/* The passes as first written, one element at a time: the reference the
 * vector forms (scene.c, SSE2 on x86-64) must match. */
static bool ref_bounds(const float *pos, size_t n, double lo[3], double hi[3]) {
    for (size_t i = 0; i < 3 * n; i++) {
        double p = pos[i];
        if (!isfinite(p)) return false;
        if (p < lo[i % 3]) lo[i % 3] = p;
        if (p > hi[i % 3]) hi[i % 3] = p;
    }
    return true;
}

/* Written apart from scene.c's loop (a test of the same arithmetic, not a
 * copy): |l2 - 1| is exact near 1, so it is the same band test. */
static void ref_unit(float *nrm, size_t n) {
    for (size_t v = 0; v < 3 * n; v += 3) {
        float *p = &nrm[v];
        const float l2 = (p[0] * p[0] + p[1] * p[1]) + p[2] * p[2];
        if (fabsf(l2 - 1.0f) < 0x1p-20f) continue;
        if (l2 > 1e-30f && l2 < 1e30f) {
            const float s = 1.0f / sqrtf(l2);
            for (int k = 0; k < 3; k++) p[k] *= s;
            continue;
        }
        const double len = sqrt((double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2]);
        const bool ok = len > 1e-300 && isfinite(len);
        for (int k = 0; k < 3; k++) p[k] = ok ? (float)(p[k] / len) : (k == 1 ? 1.0f : 0.0f);
    }
}

static uint32_t g_rng = 777;
static float rnd_unit(void) { /* [-1, 1) */
    g_rng = g_rng * 1664525u + 1013904223u;
    return (float)(g_rng >> 8) / 8388608.0f - 1.0f;
}

/* Every length of array (0 to 41 vertices, so each tail), values over
 * many magnitudes, unit and degenerate normals in every lane, non-finite
 * values and out-of-range indices at every place: the same results as the
 * reference, bit for bit (a bound's zero may differ in sign only). */
static void test_prepare_passes(void) {
    enum { max_n = 41 };
    float pos[3 * max_n], q[3 * max_n], nrm[3 * max_n], r[3 * max_n];
    int bad_bounds = 0, bad_recentre = 0, bad_unit = 0, bad_finite = 0, bad_index = 0;
    for (int n = 0; n <= max_n; n++)
        for (int trial = 0; trial < 40; trial++) {
            const float scale = powf(10.0f, (float)(trial % 11) - 3.0f), offset = trial % 3 == 0 ? 1e7f : 0.0f;
            for (int i = 0; i < 3 * n; i++) pos[i] = offset + scale * rnd_unit();
            if (trial == 5 && n > 0) pos[0] = -0.0f; /* signed zeros in play */
            double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            double rlo[3] = {INFINITY, INFINITY, INFINITY}, rhi[3] = {-INFINITY, -INFINITY, -INFINITY};
            if (trial % 4 == 1) /* bounds carried in from an earlier chunk */
                for (int k = 0; k < 3; k++) lo[k] = rlo[k] = offset - 0.5 * scale, hi[k] = rhi[k] = offset + 0.25 * scale;
            bool ok = mr_mesh_bounds_add(pos, (size_t)n, lo, hi), rok = ref_bounds(pos, (size_t)n, rlo, rhi);
            for (int k = 0; k < 3; k++) bad_bounds += ok != rok || lo[k] != rlo[k] || hi[k] != rhi[k];
            /* recentred: the reference's arithmetic per element */
            if (n > 0) {
                double org[3] = {1, 2, 3}, centre[3];
                float bmin[3], bmax[3], rmin[3] = {INFINITY, INFINITY, INFINITY}, rmax[3] = {-INFINITY, -INFINITY, -INFINITY};
                memcpy(q, pos, sizeof(float) * 3 * (size_t)n);
                mr_mesh_recentre_within(q, (uint32_t)n, rlo, rhi, org, bmin, bmax);
                for (int k = 0; k < 3; k++) centre[k] = 0.5 * rlo[k] + 0.5 * rhi[k];
                for (int i = 0; i < 3 * n; i++) {
                    float e = (float)((double)pos[i] - centre[i % 3]);
                    bad_recentre += memcmp(&e, &q[i], sizeof e) != 0 && !(e == 0.0f && q[i] == 0.0f);
                    rmin[i % 3] = fminf(rmin[i % 3], e);
                    rmax[i % 3] = fmaxf(rmax[i % 3], e);
                }
                for (int k = 0; k < 3; k++)
                    bad_recentre += bmin[k] != rmin[k] || bmax[k] != rmax[k] || org[k] != 1.0 + k + centre[k];
            }
            /* normals: random lengths, some already unit, zero, tiny, huge */
            for (int i = 0; i < 3 * n; i++) nrm[i] = rnd_unit() * powf(10.0f, (float)((i / 3 + trial) % 9) - 4.0f);
            for (int v = 0; v < n; v++) {
                int kind = (v * 7 + trial) % 9;
                float *p = nrm + 3 * v;
                if (kind == 0) p[0] = 0.0f, p[1] = 0.0f, p[2] = 1.0f;
                if (kind == 1) p[0] = p[1] = p[2] = 0.0f;
                if (kind == 2) p[0] *= 1e-17f, p[1] *= 1e-17f, p[2] *= 1e-17f;
                if (kind == 3) p[0] = 3e19f, p[1] = -2e19f, p[2] = 1e18f;
                if (kind == 4) p[0] = 0.6f, p[1] = -0.8f, p[2] = 0.0f; /* unit, maybe not exactly */
            }
            memcpy(r, nrm, sizeof(float) * 3 * (size_t)n);
            mr_mesh_unit_normals(nrm, (uint32_t)n);
            ref_unit(r, (size_t)n);
            bad_unit += memcmp(nrm, r, sizeof(float) * 3 * (size_t)n) != 0;
        }
    /* a non-finite value at each place and component: refused */
    for (int n = 1; n <= 13; n++)
        for (int at = 0; at < 3 * n; at++)
            for (int kind = 0; kind < 3; kind++) {
                for (int i = 0; i < 3 * n; i++) pos[i] = rnd_unit();
                pos[at] = kind == 0 ? INFINITY : kind == 1 ? -INFINITY : NAN;
                double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
                bad_finite += mr_mesh_bounds_add(pos, (size_t)n, lo, hi);
            }
    /* mr_floats_finite: every length to 150 (vector blocks and tail), a
     * non-finite value at every place */
    float fv[150];
    for (int n = 0; n <= 150; n++) {
        for (int i = 0; i < n; i++) fv[i] = rnd_unit() * 3e38f;
        bad_finite += !mr_floats_finite(fv, (size_t)n);
        for (int at = 0; at < n; at++)
            for (int kind = 0; kind < 3; kind++) {
                float keep = fv[at];
                fv[at] = kind == 0 ? INFINITY : kind == 1 ? -INFINITY : NAN;
                bad_finite += mr_floats_finite(fv, (size_t)n);
                fv[at] = keep;
            }
    }
    /* the largest index found in every place, also past 2^31 */
    uint32_t idx[23];
    mr_error err = {0};
    for (uint32_t count = 1; count <= 23; count++)
        for (uint32_t at = 0; at < count; at++)
            for (int big = 0; big < 3; big++) {
                for (uint32_t i = 0; i < count; i++) idx[i] = i % 5;
                const uint32_t nv = 10, v = big == 0 ? 10 : big == 1 ? 0x80000000u : 0xffffffffu;
                idx[at] = v;
                bool ok = mr_mesh_check_indices(idx, count, nv, "k", &err);
                bad_index += ok || strstr(err.msg, "out of range") == NULL;
                idx[at] = 9;
                bad_index += !mr_mesh_check_indices(idx, count, nv, "k", &err);
            }
    CHECK_MSG(bad_bounds == 0, "bounds differ from the reference in %d cases", bad_bounds);
    CHECK_MSG(bad_recentre == 0, "recentring differs from the reference in %d cases", bad_recentre);
    CHECK_MSG(bad_unit == 0, "unit normals differ from the reference in %d arrays", bad_unit);
    CHECK_MSG(bad_finite == 0, "%d non-finite values passed (bounds, finite test)", bad_finite);
    CHECK_MSG(bad_index == 0, "index check wrong in %d cases", bad_index);
}

static void test_globs(void) {
    CHECK(mr_glob_match("Pipe*", "Pipe_12"));
    CHECK(mr_glob_match("Pipe*", "Pipe"));
    CHECK(!mr_glob_match("Pipe*", "pipe"));
    CHECK(mr_glob_match("*", ""));
    CHECK(!mr_glob_match("?", ""));
    CHECK(mr_glob_match("a?c", "abc"));
    CHECK(!mr_glob_match("a?c", "ac"));
    CHECK(mr_glob_match("*duct*", "air_duct_3"));
    CHECK(mr_glob_match("*a*b*c", "xxaxxbxxbxc"));
    CHECK(!mr_glob_match("*a*b*c", "xxaxxbxxbx"));
    CHECK(mr_glob_match("[abc]x", "bx"));
    CHECK(!mr_glob_match("[abc]x", "dx"));
    CHECK(mr_glob_match("Tray_[0-9][0-9]", "Tray_42"));
    CHECK(!mr_glob_match("Tray_[0-9][0-9]", "Tray_4a"));
    CHECK(mr_glob_match("[!x]y", "ay"));
    CHECK(!mr_glob_match("[!x]y", "xy"));
    CHECK(mr_glob_match("[]]", "]"));
    CHECK(mr_glob_match("a[", "a["));   /* unterminated bracket is literal */
    CHECK(mr_glob_match("**x", "abx"));
    CHECK(!mr_glob_match("abc", "abcd"));
    CHECK(!mr_glob_match(NULL, "a"));
}

/* --------------------------------------------------------- round trip */

static mr_scene *build_rich_scene(void) {
    mr_error err;
    mr_scene *s = mr_scene_create();
    mr_texture tex;
    memset(&tex, 0, sizeof tex);
    mr_image_alloc(&tex.image, 4, 3, 4, MR_PIX_U8, &err);
    uint8_t *px = tex.image.data;
    for (int i = 0; i < 4 * 3 * 4; i++) px[i] = (uint8_t)(i * 17 + 3);
    tex.nearest = true;
    mr_scene_add_texture(s, &tex);
    mr_material red = {.name = "red", .base_color = {0.8f, 0.2f, 0.1f, 1.0f}, .base_color_texture = 0};
    mr_material blue = {.name = "blue", .base_color = {0.1f, 0.2f, 0.9f, 0.5f}, .base_color_texture = -1};
    blue.single_sided = true; /* issue 17 (lane cluster): doubleSided survives the round trip */
    mr_scene_add_material(s, &red);
    mr_scene_add_material(s, &blue);

    /* Mesh 0: a textured quad far from the origin. */
    float qp[12] = {0, 0, 0, 2, 0, 0, 2, 1, 0, 0, 1, 0};
    float qn[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    float quv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    uint32_t qi[6] = {0, 1, 2, 0, 2, 3};
    mr_mesh q;
    memset(&q, 0, sizeof q);
    snprintf(q.name, sizeof q.name, "quad");
    q.origin[0] = 1.0e6;
    q.origin[1] = 2.0e5;
    q.origin[2] = -3.0e6;
    q.positions = fdup(qp, 12);
    q.normals = fdup(qn, 12);
    q.uvs = fdup(quv, 8);
    q.indices = udup(qi, 6);
    q.vertex_count = 4;
    q.index_count = 6;
    q.material = 0;
    mr_scene_add_mesh(s, &q, &err);
    /* Meshes 1, 2: one node with two primitives of different origins. */
    mr_mesh b1 = make_box("pipe", 1.0e6 + 3.0, 2.0e5, -3.0e6, 0.25);
    b1.material = 1;
    mr_scene_add_mesh(s, &b1, &err);
    mr_mesh b2 = make_box("pipe", 1.0e6 + 7.5, 2.0e5 + 1.0, -3.0e6, 0.5);
    b2.material = -1;
    mr_scene_add_mesh(s, &b2, &err);

    mr_dmat4 t1 = mr_m4_translate(12.5, -3.25, 100.0);
    mr_dmat4 r1 = mr_m4_rotate_axis(mr_v3(1, 2, 3), 0.7);
    mr_node wall = make_node("Wall", -1, mr_m4_mul(&t1, &r1), 0, 1);
    int32_t wi = mr_scene_add_node(s, &wall);
    mr_dmat4 t2 = mr_m4_translate(0, 0, 5.0);
    mr_node copy = make_node("Wall_copy", wi, mr_m4_mul(&wall.world, &t2), 0, 1);
    mr_scene_add_node(s, &copy);
    mr_node pipe = make_node("Pipe_1", -1, mr_m4_rotate_axis(mr_v3(0, 1, 0), -1.1), 1, 2);
    pipe.layer = MR_LAYER_HIDDEN;
    mr_scene_add_node(s, &pipe);
    mr_node empty = make_node("Empty", -1, mr_m4_translate(1, 2, 3), -1, 0);
    mr_scene_add_node(s, &empty);
    mr_scene_update_bounds(s);
    return s;
}

/* World position of vertex v of mesh k drawn by node n. */
static mr_dvec3 world_vertex(const mr_scene *s, const mr_node *n, int k, uint32_t v) {
    const mr_mesh *m = &s->meshes[n->mesh_first + k];
    mr_dmat4 model = model_of(s, n, k);
    const float *p = m->positions + 3 * v;
    return mr_m4_point(&model, mr_v3(p[0], p[1], p[2]));
}

static void compare_scenes(const mr_scene *a, const mr_scene *b) {
    CHECK(b->node_count == a->node_count);
    CHECK(b->mesh_count == a->mesh_count);
    CHECK(mr_scene_triangle_count(b) == mr_scene_triangle_count(a));
    for (int i = 0; i < a->node_count && i < b->node_count; i++) {
        const mr_node *na = &a->nodes[i], *nb = &b->nodes[i];
        CHECK_MSG(strcmp(na->name, nb->name) == 0, "%s vs %s", na->name, nb->name);
        CHECK(na->layer == nb->layer);
        CHECK(na->mesh_count == nb->mesh_count);
        if (na->mesh_first < 0) {
            CHECK(nb->mesh_first < 0);
            CHECK(mat_close(&nb->world, &na->world, 1e-9));
            continue;
        }
        if (nb->mesh_first < 0) continue;
        for (int k = 0; k < na->mesh_count && k < nb->mesh_count; k++) {
            const mr_mesh *ma = &a->meshes[na->mesh_first + k], *mb = &b->meshes[nb->mesh_first + k];
            CHECK(ma->vertex_count == mb->vertex_count && ma->index_count == mb->index_count);
            CHECK(ma->material == mb->material);
            CHECK((ma->uvs != NULL) == (mb->uvs != NULL));
            if (k == 0) {
                mr_dmat4 ma_model = model_of(a, na, 0), mb_model = model_of(b, nb, 0);
                CHECK_MSG(mat_close(&mb_model, &ma_model, 1e-9), "node %s model matrix", na->name);
            }
            if (ma->vertex_count != mb->vertex_count || ma->index_count != mb->index_count) continue;
            for (uint32_t v = 0; v < ma->vertex_count; v++) {
                mr_dvec3 pa = world_vertex(a, na, k, v), pb = world_vertex(b, nb, k, v);
                CHECK_NEAR(mr_v3_len(mr_v3_sub(pa, pb)), 0.0, 1e-5);
                for (int c = 0; c < 3; c++) CHECK_NEAR(mb->normals[3 * v + c], ma->normals[3 * v + c], 1e-6);
                if (ma->uvs && mb->uvs)
                    for (int c = 0; c < 2; c++) CHECK_NEAR(mb->uvs[2 * v + c], ma->uvs[2 * v + c], 0);
            }
            for (uint32_t j = 0; j < ma->index_count; j++) CHECK(ma->indices[j] == mb->indices[j]);
        }
    }
    CHECK(b->material_count == a->material_count);
    for (int i = 0; i < a->material_count && i < b->material_count; i++) {
        CHECK(strcmp(a->materials[i].name, b->materials[i].name) == 0);
        CHECK(a->materials[i].base_color_texture == b->materials[i].base_color_texture);
        CHECK(a->materials[i].single_sided == b->materials[i].single_sided); /* issue 17 (lane cluster) */
        for (int c = 0; c < 4; c++) CHECK_NEAR(b->materials[i].base_color[c], a->materials[i].base_color[c], 1e-7);
    }
    CHECK(b->texture_count == a->texture_count);
    for (int i = 0; i < a->texture_count && i < b->texture_count; i++) {
        const mr_image *ia = &a->textures[i].image, *ib = &b->textures[i].image;
        CHECK(ia->width == ib->width && ia->height == ib->height && ib->channels == 4);
        CHECK(a->textures[i].nearest == b->textures[i].nearest);
        if (ia->width == ib->width && ia->height == ib->height && ib->channels == 4)
            CHECK(memcmp(ia->data, ib->data, mr_image_bytes(ia)) == 0);
    }
    for (int k = 0; k < 3; k++) {
        double tol = 1e-6 * fmax(1.0, fabs(a->bounds_max[k]));
        CHECK_NEAR(b->bounds_min[k], a->bounds_min[k], tol);
        CHECK_NEAR(b->bounds_max[k], a->bounds_max[k], tol);
    }
}

static void *read_all(const char *path, size_t *n) {
    mr_error e;
    return mr_file_read(path, n, 0, &e);
}

static void test_round_trip(void) {
    mr_error err = {0};
    mr_scene *a = build_rich_scene();
    CHECK(a->mesh_count == 3 && a->node_count == 4);
    char path[1200];
    tmp_path(path, sizeof path, "rich.glb");
    CHECK_MSG(mr_scene_save_glb(a, path, &err), "%s", err.msg);
    mr_scene *b = mr_scene_load(path, NULL, &err);
    CHECK_MSG(b != NULL, "%s", err.msg);
    if (b) {
        compare_scenes(a, b);
        CHECK(strcmp(b->source, path) == 0);
        const mr_node *w = find_node(b, "Wall"), *c = find_node(b, "Wall_copy"), *p = find_node(b, "Pipe_1");
        CHECK(w && c && p);
        if (w && c) CHECK(w->mesh_first == c->mesh_first); /* instancing survives */
        if (p) CHECK(p->layer == MR_LAYER_HIDDEN && p->mesh_count == 2);
        /* Saving the loaded scene again gives the same scene. */
        char path2[1200];
        tmp_path(path2, sizeof path2, "rich2.glb");
        CHECK(mr_scene_save_glb(b, path2, &err));
        mr_scene *c2 = mr_scene_load(path2, NULL, &err);
        CHECK(c2 != NULL);
        if (c2) compare_scenes(b, c2);
        mr_scene_destroy(&c2);
    }

    /* A .glb named .gltf loads by content. */
    size_t n = 0;
    void *bytes = read_all(path, &n);
    CHECK(bytes != NULL);
    char gpath[1200];
    tmp_path(gpath, sizeof gpath, "really_glb.gltf");
    CHECK(write_file(gpath, bytes, n));
    mr_scene *d = mr_scene_load(gpath, NULL, &err);
    CHECK_MSG(d != NULL, "%s", err.msg);
    if (d) compare_scenes(a, d);
    mr_scene_destroy(&d);

    /* Truncated .glb: every cut length fails cleanly. */
    char tpath[1200];
    tmp_path(tpath, sizeof tpath, "truncated.glb");
    int failures = 0, bad_msgs = 0;
    for (size_t cut = 0; cut < n; cut += (cut < 64 ? 1 : 97)) {
        write_file(tpath, bytes, cut);
        mr_error e = {0};
        mr_scene *t = mr_scene_load(tpath, NULL, &e);
        if (t) mr_scene_destroy(&t);
        else failures++;
        if (!t && (!one_line_msg(&e) || e.code == MR_OK)) bad_msgs++;
        if (t) CHECK_MSG(0, "truncated to %zu bytes loaded", cut);
    }
    CHECK(failures > 10);
    CHECK(bad_msgs == 0);
    /* Also straight from memory, without a file. */
    for (size_t cut = 0; cut < n; cut += 13) {
        mr_error e = {0};
        mr_scene *t = mr_scene_load_gltf_memory(bytes, cut, NULL, NULL, &e);
        CHECK(t == NULL && one_line_msg(&e));
        mr_scene_destroy(&t);
    }

    /* Mutated bytes: no crash, and a failure always says why. */
    mr_rng rng;
    mr_rng_seed(&rng, 42);
    unsigned char *mut = malloc(n);
    int fuzz_bad = 0;
    for (int it = 0; it < 300; it++) {
        memcpy(mut, bytes, n);
        int flips = 1 + (int)(mr_rng_u64(&rng) % 4);
        for (int f = 0; f < flips; f++) {
            size_t at = (size_t)(mr_rng_u64(&rng) % n);
            mut[at] = (unsigned char)mr_rng_u64(&rng);
        }
        mr_error e = {0};
        mr_scene *t = mr_scene_load_gltf_memory(mut, n, NULL, NULL, &e);
        if (!t && !one_line_msg(&e)) fuzz_bad++;
        mr_scene_destroy(&t);
    }
    CHECK(fuzz_bad == 0);
    free(mut);

    /* Random bytes behind a glTF magic. */
    unsigned char junk[256];
    for (size_t i = 0; i < sizeof junk; i++) junk[i] = (unsigned char)mr_rng_u64(&rng);
    memcpy(junk, "glTF", 4);
    char jpath[1200];
    tmp_path(jpath, sizeof jpath, "junk.glb");
    write_file(jpath, junk, sizeof junk);
    mr_error e = {0};
    CHECK(mr_scene_load(jpath, NULL, &e) == NULL);
    CHECK(e.code == MR_ERR_PARSE && one_line_msg(&e));
    /* A valid GLB header with garbage JSON. */
    uint32_t hdr[5] = {0x46546C67u, 2, 20 + 16, 16, 0x4E4F534Au};
    unsigned char glb[36];
    memcpy(glb, hdr, 20);
    memcpy(glb + 20, "{\"asset\":{\"vers", 16);
    e.code = MR_OK;
    CHECK(mr_scene_load_gltf_memory(glb, sizeof glb, NULL, NULL, &e) == NULL);
    CHECK(e.code == MR_ERR_PARSE && one_line_msg(&e));

    free(bytes);
    mr_scene_destroy(&b);
    mr_scene_destroy(&a);
}

/* ------------------------------------------------- hand-written glTF */

static char *base64(const unsigned char *in, size_t n) {
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * ((n + 2) / 3) + 1), *o = out;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16;
        if (i + 1 < n) v |= (uint32_t)in[i + 1] << 8;
        if (i + 2 < n) v |= in[i + 2];
        *o++ = tab[(v >> 18) & 63];
        *o++ = tab[(v >> 12) & 63];
        *o++ = i + 1 < n ? tab[(v >> 6) & 63] : '=';
        *o++ = i + 2 < n ? tab[v & 63] : '=';
    }
    *o = 0;
    return out;
}

/* One triangle (0,0,0) (1,0,0) (0,1,0) and uint16 indices, in a data: URI
 * buffer. `accessors` and `prim` vary per test. Root is hidden by extras
 * (Child inherits), Duct_7 can be hidden by a glob. */
static char *triangle_gltf(const float pos[9], const uint16_t idx[3], const char *accessors, const char *prim,
                           const char *uri_override) {
    unsigned char bin[44] = {0};
    memcpy(bin, pos, 36);
    memcpy(bin + 36, idx, 6);
    char *b64 = base64(bin, sizeof bin);
    size_t cap = strlen(b64) + 4096;
    char *json = malloc(cap);
    char uri[512];
    if (uri_override) snprintf(uri, sizeof uri, "%s", uri_override);
    snprintf(json, cap,
             "{\"asset\":{\"version\":\"2.0\"},\n"
             " \"buffers\":[{\"byteLength\":44,\"uri\":\"%s%s\"}],\n"
             " \"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
             "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],\n"
             " \"accessors\":[%s],\n"
             " \"meshes\":[{\"name\":\"Tri\",\"primitives\":[%s]}],\n"
             " \"nodes\":[{\"name\":\"Root\",\"extras\":{\"mrcheck_layer\":\"hidden\"},\"children\":[1],"
             "\"rotation\":[0,0,0.7071067811865476,0.7071067811865476]},\n"
             "   {\"name\":\"Child\",\"mesh\":0,\"translation\":[1,2,3]},\n"
             "   {\"name\":\"Duct_7\",\"mesh\":0},\n"
             "   {\"name\":\"Floor\",\"mesh\":0,\"scale\":[2,2,2]}],\n"
             " \"scenes\":[{\"nodes\":[0,2,3]}],\"scene\":0}\n",
             uri_override ? "" : "data:application/octet-stream;base64,", uri_override ? uri : b64, accessors,
             prim);
    free(b64);
    return json;
}

static const float k_tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
static const uint16_t k_tri_idx[3] = {0, 1, 2};
static const char *k_pos_acc = "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}";
static const char *k_pos_idx_acc = "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
                                   "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}";
static const char *k_prim = "{\"attributes\":{\"POSITION\":0}}";
static const char *k_prim_idx = "{\"attributes\":{\"POSITION\":0},\"indices\":1}";

static mr_scene *load_string(const char *json, const char *name, const mr_scene_params *p, mr_error *err) {
    char path[1200];
    tmp_path(path, sizeof path, name);
    write_file(path, json, strlen(json));
    return mr_scene_load(path, p, err);
}

static void test_handwritten(void) {
    mr_error err = {0};
    char *json = triangle_gltf(k_tri, k_tri_idx, k_pos_acc, k_prim, NULL);
    const char *globs[] = {"Duct*"};
    mr_scene_params params = MR_SCENE_DEFAULTS;
    params.hidden_globs = globs;
    params.hidden_glob_count = 1;

    mr_scene *s = mr_scene_load_gltf_memory(json, strlen(json), NULL, &params, &err);
    CHECK_MSG(s != NULL, "%s", err.msg);
    if (s) {
        CHECK(s->node_count == 4);
        CHECK(s->mesh_count == 1); /* one glTF mesh, used three times */
        const mr_node *root = find_node(s, "Root"), *child = find_node(s, "Child"), *duct = find_node(s, "Duct_7"),
                      *floor_ = find_node(s, "Floor");
        CHECK(root && child && duct && floor_);
        if (root && child && duct && floor_) {
            CHECK(root->layer == MR_LAYER_HIDDEN);
            CHECK(child->layer == MR_LAYER_HIDDEN); /* inherited */
            CHECK(duct->layer == MR_LAYER_HIDDEN);  /* glob */
            CHECK(floor_->layer == MR_LAYER_VISIBLE);
            CHECK(child->parent == (int32_t)(root - s->nodes));
            /* Rz(90) * T(1,2,3): the child's origin is at (-2,1,3). */
            CHECK_NEAR(child->world.m[3], -2.0, 1e-12);
            CHECK_NEAR(child->world.m[7], 1.0, 1e-12);
            CHECK_NEAR(child->world.m[11], 3.0, 1e-12);
            CHECK(child->mesh_first == duct->mesh_first && duct->mesh_first == floor_->mesh_first);
            CHECK_NEAR(floor_->world.m[0], 2.0, 1e-12);
        }
        const mr_mesh *m = &s->meshes[0];
        CHECK(m->index_count == 3 && m->vertex_count == 3);
        CHECK_NEAR(m->origin[0], 0.5, 1e-12);
        CHECK_NEAR(m->origin[1], 0.5, 1e-12);
        for (uint32_t v = 0; v < 3; v++) CHECK_NEAR(m->normals[3 * v + 2], 1.0, 1e-6); /* generated */
        CHECK(m->uvs == NULL);
        CHECK(mr_scene_triangle_count(s) == 3);
        /* Bounds over drawn nodes: Floor spans [0,2]x[0,2]. */
        CHECK_NEAR(s->bounds_max[0], 2.0, 1e-6);
        CHECK(s->source[0] == 0);
    }
    mr_scene_destroy(&s);

    /* Without globs Duct_7 is visible. */
    s = mr_scene_load_gltf_memory(json, strlen(json), NULL, NULL, &err);
    CHECK(s != NULL);
    if (s) {
        const mr_node *duct = find_node(s, "Duct_7");
        CHECK(duct && duct->layer == MR_LAYER_VISIBLE);
    }
    mr_scene_destroy(&s);

    /* A .gltf named .glb loads by content, from a file. */
    s = load_string(json, "really_gltf.glb", &params, &err);
    CHECK_MSG(s != NULL, "%s", err.msg);
    if (s) {
        const mr_node *duct = find_node(s, "Duct_7");
        CHECK(duct && duct->layer == MR_LAYER_HIDDEN);
    }
    mr_scene_destroy(&s);

    /* Scene config next to it: relative path, extra globs, lights, ambient. */
    {
        const char *cfg = "{\"gltf\": \"really_gltf.glb\", \"hidden\": [\"Floor\"],"
                          " \"lights\": [{\"direction\": [0, 2, 0], \"color\": [1, 0.5, 0.25]}],"
                          " \"ambient\": 0.2}";
        s = load_string(cfg, "scene.json", &params, &err);
        CHECK_MSG(s != NULL, "%s", err.msg);
        if (s) {
            const mr_node *duct = find_node(s, "Duct_7"), *floor_ = find_node(s, "Floor");
            CHECK(duct && duct->layer == MR_LAYER_HIDDEN);     /* from params */
            CHECK(floor_ && floor_->layer == MR_LAYER_HIDDEN); /* from the config */
            CHECK(s->light_count == 1);
            CHECK_NEAR(s->lights[0].direction[1], 1.0, 1e-12);
            CHECK_NEAR(s->lights[0].color[2], 0.25, 1e-7);
            CHECK_NEAR(s->ambient, 0.2, 1e-7);
            CHECK(strstr(s->source, "scene.json") != NULL);
        }
        mr_scene_destroy(&s);

        const char *missing = "{\"gltf\": \"no_such_file.glb\"}";
        s = load_string(missing, "scene_missing.json", NULL, &err);
        CHECK(s == NULL && err.code == MR_ERR_IO && one_line_msg(&err));
        CHECK(strstr(err.msg, "no_such_file.glb") != NULL);
        mr_scene_destroy(&s);

        const char *badamb = "{\"gltf\": \"really_gltf.glb\", \"ambient\": 3}";
        s = load_string(badamb, "scene_badamb.json", NULL, &err);
        CHECK(s == NULL && err.code == MR_ERR_INVALID && one_line_msg(&err));

        const char *self = "{\"gltf\": \"scene_self.json\"}";
        s = load_string(self, "scene_self.json", NULL, &err);
        CHECK(s == NULL && one_line_msg(&err));
    }
    free(json);

    /* Indexed, and the same as non-indexed. */
    json = triangle_gltf(k_tri, k_tri_idx, k_pos_idx_acc, k_prim_idx, NULL);
    s = mr_scene_load_gltf_memory(json, strlen(json), NULL, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.msg);
    if (s) CHECK(s->meshes[0].index_count == 3 && s->meshes[0].indices[1] == 1);
    mr_scene_destroy(&s);
    free(json);

    /* Triangle strip and points. */
    json = triangle_gltf(k_tri, k_tri_idx, k_pos_acc, "{\"attributes\":{\"POSITION\":0},\"mode\":5}", NULL);
    s = mr_scene_load_gltf_memory(json, strlen(json), NULL, NULL, &err);
    CHECK(s != NULL && s->mesh_count == 1 && s->meshes[0].index_count == 3);
    mr_scene_destroy(&s);
    free(json);
    json = triangle_gltf(k_tri, k_tri_idx, k_pos_acc, "{\"attributes\":{\"POSITION\":0},\"mode\":0}", NULL);
    s = mr_scene_load_gltf_memory(json, strlen(json), NULL, NULL, &err);
    CHECK(s != NULL && s->mesh_count == 0 && s->node_count == 4);
    mr_scene_destroy(&s);
    free(json);

    /* External buffer next to a .gltf file: resolved against its folder. */
    {
        unsigned char bin[44] = {0};
        memcpy(bin, k_tri, 36);
        char bpath[1200];
        tmp_path(bpath, sizeof bpath, "ext_tri.bin");
        CHECK(write_file(bpath, bin, sizeof bin));
        json = triangle_gltf(k_tri, k_tri_idx, k_pos_acc, k_prim, "ext_tri.bin");
        s = load_string(json, "ext.gltf", NULL, &err);
        CHECK_MSG(s != NULL && s->mesh_count == 1, "%s", s ? "" : err.msg);
        mr_scene_destroy(&s);
        free(json);
    }

    /* A gray PNG in a data: URI with a NEAREST sampler, and normalised
     * UNSIGNED_BYTE texture coordinates with a byte stride. */
    {
        mr_image gray;
        CHECK(mr_image_alloc(&gray, 3, 2, 1, MR_PIX_U8, &err));
        for (int i = 0; i < 6; i++) ((uint8_t *)gray.data)[i] = (uint8_t)(40 * i + 5);
        char ppath[1200];
        tmp_path(ppath, sizeof ppath, "gray.png");
        CHECK(mr_image_save_png(ppath, &gray, &err));
        size_t pn = 0;
        unsigned char *png = read_all(ppath, &pn);
        CHECK(png != NULL);
        unsigned char bin[48] = {0};
        memcpy(bin, k_tri, 36);
        const unsigned char uv[12] = {0, 0, 0, 0, 255, 0, 0, 0, 0, 255, 0, 0};
        memcpy(bin + 36, uv, 12);
        char *b64 = base64(bin, sizeof bin), *p64 = base64(png, pn);
        size_t cap = strlen(b64) + strlen(p64) + 2048;
        char *j = malloc(cap);
        snprintf(j, cap,
                 "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":48,"
                 "\"uri\":\"data:application/octet-stream;base64,%s\"}],"
                 "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
                 "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":12,\"byteStride\":4}],"
                 "\"accessors\":[%s,{\"bufferView\":1,\"componentType\":5121,\"normalized\":true,"
                 "\"count\":3,\"type\":\"VEC2\"}],"
                 "\"images\":[{\"uri\":\"data:image/png;base64,%s\"}],\"samplers\":[{\"magFilter\":9728}],"
                 "\"textures\":[{\"source\":0,\"sampler\":0}],"
                 "\"materials\":[{\"name\":\"plate\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,1,1,1],"
                 "\"baseColorTexture\":{\"index\":0}}}],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"material\":0}]}],"
                 "\"nodes\":[{\"mesh\":0}]}",
                 b64, k_pos_acc, p64);
        s = mr_scene_load_gltf_memory(j, strlen(j), NULL, NULL, &err);
        CHECK_MSG(s != NULL, "%s", s ? "" : err.msg);
        if (s) {
            CHECK(s->node_count == 1 && strcmp(s->nodes[0].name, "node_0") == 0); /* no scenes: roots */
            CHECK(s->texture_count == 1 && s->textures[0].nearest);
            CHECK(s->material_count == 1 && s->materials[0].base_color_texture == 0);
            CHECK_NEAR(s->materials[0].base_color[0], 0.5, 1e-7);
            if (s->texture_count == 1) {
                const mr_image *im = &s->textures[0].image;
                CHECK(im->width == 3 && im->height == 2 && im->channels == 4);
                const uint8_t *px = im->data;
                for (int i = 0; i < 6; i++) {
                    CHECK(px[4 * i] == 40 * i + 5 && px[4 * i + 2] == 40 * i + 5);
                    CHECK(px[4 * i + 3] == 255);
                }
            }
            const float *u = s->meshes[0].uvs;
            CHECK(u != NULL);
            if (u) CHECK(u[0] == 0.0f && u[2] == 1.0f && u[3] == 0.0f && u[5] == 1.0f);
        }
        mr_scene_destroy(&s);
        free(j);
        free(b64);
        free(p64);
        free(png);
        mr_image_free(&gray);
    }
}

static void expect_fail(const char *json, mr_err_code code, const char *needle, int line) {
    mr_error err = {0};
    mr_scene *s = mr_scene_load_gltf_memory(json, strlen(json), NULL, NULL, &err);
    CHECK_MSG(s == NULL, "line %d: loaded", line);
    CHECK_MSG(err.code == code, "line %d: code %s, msg %s", line, mr_err_name(err.code), err.msg);
    CHECK_MSG(one_line_msg(&err), "line %d: message '%s'", line, err.msg);
    if (needle) CHECK_MSG(strstr(err.msg, needle) != NULL, "line %d: '%s' lacks '%s'", line, err.msg, needle);
    mr_scene_destroy(&s);
}

static void test_bad_inputs(void) {
    mr_error err = {0};
    char path[1200];

    tmp_path(path, sizeof path, "does_not_exist.glb");
    CHECK(mr_scene_load(path, NULL, &err) == NULL);
    CHECK(err.code == MR_ERR_IO && one_line_msg(&err));

    tmp_path(path, sizeof path, "empty.glb");
    write_file(path, "", 0);
    CHECK(mr_scene_load(path, NULL, &err) == NULL);
    CHECK(err.code == MR_ERR_PARSE && one_line_msg(&err));

    mr_scene *s = load_string("this is not a model\n", "text.gltf", NULL, &err);
    CHECK(s == NULL && err.code == MR_ERR_PARSE && one_line_msg(&err));
    s = load_string("{\"foo\": 1}", "foo.json", NULL, &err);
    CHECK(s == NULL && err.code == MR_ERR_PARSE && strstr(err.msg, "not a glTF file or scene config"));
    s = load_string("[1,2,3]", "array.json", NULL, &err);
    CHECK(s == NULL && err.code == MR_ERR_PARSE);
    CHECK(mr_scene_load_gltf_memory(NULL, 0, NULL, NULL, &err) == NULL && one_line_msg(&err));

    /* Accessor count past the end of its bufferView. */
    char *json = triangle_gltf(k_tri, k_tri_idx,
                               "{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}", k_prim, NULL);
    expect_fail(json, MR_ERR_PARSE, "past the end", __LINE__);
    free(json);
    /* Huge count must not overflow the bounds check. */
    json = triangle_gltf(k_tri, k_tri_idx,
                         "{\"bufferView\":0,\"componentType\":5126,\"count\":1537228672809129301,\"type\":\"VEC3\"}",
                         k_prim, NULL);
    expect_fail(json, MR_ERR_PARSE, NULL, __LINE__);
    free(json);
    /* Accessor offset past the view. */
    json = triangle_gltf(k_tri, k_tri_idx,
                         "{\"bufferView\":0,\"byteOffset\":40,\"componentType\":5126,\"count\":1,\"type\":\"VEC3\"}",
                         k_prim, NULL);
    expect_fail(json, MR_ERR_PARSE, NULL, __LINE__);
    free(json);
    /* Wrong component type for positions. */
    json = triangle_gltf(k_tri, k_tri_idx, "{\"bufferView\":0,\"componentType\":5123,\"count\":3,\"type\":\"VEC3\"}",
                         k_prim, NULL);
    expect_fail(json, MR_ERR_PARSE, "POSITION", __LINE__);
    free(json);
    /* Missing accessor. */
    json = triangle_gltf(k_tri, k_tri_idx, k_pos_acc, "{\"attributes\":{\"POSITION\":5}}", NULL);
    expect_fail(json, MR_ERR_PARSE, NULL, __LINE__);
    free(json);
    /* Index out of range. */
    const uint16_t bad_idx[3] = {0, 1, 7};
    json = triangle_gltf(k_tri, bad_idx, k_pos_idx_acc, k_prim_idx, NULL);
    expect_fail(json, MR_ERR_INVALID, "out of range", __LINE__);
    free(json);
    /* NaN position. */
    float nan_tri[9] = {0, 0, 0, 1, 0, 0, 0, NAN, 0};
    json = triangle_gltf(nan_tri, k_tri_idx, k_pos_acc, k_prim, NULL);
    expect_fail(json, MR_ERR_INVALID, "mesh 'Tri' has a non-finite position", __LINE__);
    free(json);
    float inf_tri[9] = {0, 0, 0, INFINITY, 0, 0, 0, 1, 0};
    json = triangle_gltf(inf_tri, k_tri_idx, k_pos_acc, k_prim, NULL);
    expect_fail(json, MR_ERR_INVALID, "non-finite position", __LINE__);
    free(json);
    /* Sparse accessors (supported since issue 17; test_gltf_ext checks
     * their values): sparse values past their bufferView are refused. */
    json = triangle_gltf(k_tri, k_tri_idx,
                         "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"sparse\":"
                         "{\"count\":1,\"indices\":{\"bufferView\":1,\"componentType\":5123},"
                         "\"values\":{\"bufferView\":0,\"byteOffset\":32}}}",
                         k_prim, NULL);
    expect_fail(json, MR_ERR_PARSE, "sparse", __LINE__);
    free(json);
    /* External buffer with no base folder is refused. */
    json = triangle_gltf(k_tri, k_tri_idx, k_pos_acc, k_prim, "external.bin");
    expect_fail(json, MR_ERR_PARSE, NULL, __LINE__);
    free(json);
    /* Required extensions we cannot honour. */
    const char *inst = "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"EXT_mesh_gpu_instancing\"],"
                       "\"extensionsRequired\":[\"EXT_mesh_gpu_instancing\"]}";
    expect_fail(inst, MR_ERR_UNSUPPORTED, "EXT_mesh_gpu_instancing", __LINE__);
    /* A node cycle. */
    const char *cycle = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"a\",\"children\":[1]},"
                        "{\"name\":\"b\",\"children\":[0]}],\"scenes\":[{\"nodes\":[0]}]}";
    expect_fail(cycle, MR_ERR_INVALID, NULL, __LINE__);
    const char *badchild = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"a\",\"children\":[9]}],"
                           "\"scenes\":[{\"nodes\":[0]}]}";
    expect_fail(badchild, MR_ERR_PARSE, NULL, __LINE__);
    /* Image in a bufferView that lies outside the buffer: the texture is
     * dropped (with a warning), nothing is read out of bounds. */
    {
        char *b64 = base64((const unsigned char *)k_tri, 36);
        char buf[4096];
        snprintf(buf, sizeof buf,
                 "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":36,"
                 "\"uri\":\"data:application/octet-stream;base64,%s\"}],"
                 "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
                 "{\"buffer\":0,\"byteOffset\":100000,\"byteLength\":5000}],"
                 "\"images\":[{\"bufferView\":1,\"mimeType\":\"image/png\"}],\"textures\":[{\"source\":0}],"
                 "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],"
                 "\"accessors\":[%s],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}],"
                 "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}",
                 b64, k_pos_acc);
        free(b64);
        s = mr_scene_load_gltf_memory(buf, strlen(buf), NULL, NULL, &err);
        CHECK_MSG(s != NULL, "%s", err.msg);
        if (s) CHECK(s->texture_count == 0 && s->material_count == 1 && s->materials[0].base_color_texture == -1);
        mr_scene_destroy(&s);
    }
}

int main(void) {
    mr_log_set_level(MR_LOG_ERROR); /* the expected warnings of bad input would only be noise */
    const char *tmp = getenv("MR_TEST_TMP");
    snprintf(g_tmp, sizeof g_tmp, "%s/scene", tmp && tmp[0] ? tmp : "/tmp/mrcheck_test");
    mr_error err;
    if (!mr_mkdirs(g_tmp, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    test_builder();
    test_prepare();
    test_prepare_passes();
    test_globs();
    test_round_trip();
    test_handwritten();
    test_bad_inputs();
    return mr_test_finish("test_scene");
}
