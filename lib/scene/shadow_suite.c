/* The soft-shadow test suite (after Hecher's scene categories):
 * simple regular objects and furniture-like assemblies, each with constant
 * penumbra (lifted off the floor, every part about as far from it) or
 * varying penumbra (standing on it: contact hardening), without and with
 * overlapping penumbrae; fences/grids and plant-like random leaves (whose
 * penumbrae always overlap) with constant or varying penumbra; and the demo
 * hall. A 1.2 x 1.2 rect light 5 units above the floor; two views each. */
#include "mr_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const k_names[MR_SHADOW_SUITE_COUNT] = {
    "simple_constant",    "simple_constant_overlap",    "simple_varying",    "simple_varying_overlap",
    "furniture_constant", "furniture_constant_overlap", "furniture_varying", "furniture_varying_overlap",
    "fence_constant",     "fence_varying",              "plant_constant",    "plant_varying",
    "factory",
};

const char *mr_shadow_suite_name(int index) {
    return index >= 0 && index < MR_SHADOW_SUITE_COUNT ? k_names[index] : NULL;
}

/* A unit cube centred at its origin, 24 vertices (flat normals). */
static int32_t unit_box(mr_scene *s, mr_error *err) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "unit_box");
    m.material = -1; /* the default grey */
    m.vertex_count = 24;
    m.index_count = 36;
    m.positions = malloc(72 * sizeof(float));
    m.indices = malloc(36 * sizeof(uint32_t));
    if (!m.positions || !m.indices) {
        free(m.positions);
        free(m.indices);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return -1;
    }
    static const int faces[6][4][3] = {
        {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}},     {{-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}, {-1, -1, -1}},
        {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}},     {{-1, -1, 1}, {-1, -1, -1}, {1, -1, -1}, {1, -1, 1}},
        {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}},     {{1, -1, -1}, {-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}},
    };
    for (int f = 0; f < 6; f++) {
        for (int v = 0; v < 4; v++)
            for (int k = 0; k < 3; k++) m.positions[(f * 4 + v) * 3 + k] = 0.5f * (float)faces[f][v][k];
        const uint32_t q[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++) m.indices[f * 6 + k] = (uint32_t)(f * 4) + q[k];
    }
    return mr_scene_add_mesh(s, &m, err);
}

typedef struct suite_ctx {
    mr_scene *s;
    int32_t box;
    int count;
    bool ok;
} suite_ctx;

/* A box of size (sx, sy, sz) centred at (x, y, z), turned by `yaw` about y
 * and `tilt` about x (radians). */
static void box(suite_ctx *c, double x, double y, double z, double sx, double sy, double sz, double yaw, double tilt) {
    if (!c->ok) return;
    mr_dmat4 t = mr_m4_translate(x, y, z), ry = mr_m4_rotate_axis(mr_v3(0, 1, 0), yaw),
             rx = mr_m4_rotate_axis(mr_v3(1, 0, 0), tilt), sc = mr_m4_scale(sx, sy, sz);
    mr_dmat4 a = mr_m4_mul(&t, &ry), b = mr_m4_mul(&a, &rx);
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "Part_%d", c->count++);
    n.parent = -1;
    n.world = mr_m4_mul(&b, &sc);
    n.mesh_first = c->box;
    n.mesh_count = 1;
    n.layer = MR_LAYER_VISIBLE;
    if (mr_scene_add_node(c->s, &n) < 0) c->ok = false;
}

/* A table: top at height h (its underside), four legs of length `legs`
 * hanging from it (legs = h: standing on the floor). */
static void table(suite_ctx *c, double x, double z, double h, double legs, double yaw) {
    const double w = 1.0, d = 0.6, t = 0.05, l = 0.05;
    double cy = cos(yaw), sy = sin(yaw);
    box(c, x, h + 0.5 * t, z, w, t, d, yaw, 0);
    for (int k = 0; k < 4; k++) {
        double lx = (k & 1 ? 0.5 : -0.5) * (w - l), lz = (k & 2 ? 0.5 : -0.5) * (d - l);
        box(c, x + cy * lx + sy * lz, h - 0.5 * legs, z - sy * lx + cy * lz, l, legs, l, yaw, 0);
    }
    /* a chair-like back on one side */
    box(c, x + sy * 0.5 * d, h + 0.25, z + cy * 0.5 * d, w * 0.6, 0.5, t, yaw, 0);
}

static void build(suite_ctx *c, int index) {
    uint64_t seed = 0x5eed0000u + (uint64_t)index;
    mr_rng rng;
    mr_rng_seed(&rng, seed);
    switch (index) {
    case 0: /* cubes floating at one height, apart */
    case 1: /* the same, close together: overlapping penumbrae */
        for (int i = 0; i < 3; i++) {
            double gap = index == 0 ? 2.0 : 0.65;
            box(c, (i - 1) * gap, 1.0, 0.2 * i, 0.5, 0.5, 0.5, 0.3 * i, 0);
        }
        break;
    case 2: /* standing boxes of different heights */
    case 3:
        for (int i = 0; i < 3; i++) {
            double gap = index == 2 ? 2.0 : 0.7, h = 0.4 + 0.7 * i;
            box(c, (i - 1) * gap, 0.5 * h, 0.2 * i, 0.45, h, 0.45, 0.3 * i, 0);
        }
        break;
    case 4: /* tables lifted off the floor: short legs */
    case 5:
        for (int i = 0; i < 2; i++) table(c, (i - 0.5) * (index == 4 ? 2.6 : 0.9), 0.3 * i, 1.2, 0.15, 0.4 * i);
        break;
    case 6: /* tables standing on the floor */
    case 7:
        for (int i = 0; i < 2; i++) table(c, (i - 0.5) * (index == 6 ? 2.6 : 0.9), 0.3 * i, 0.75, 0.75, 0.4 * i);
        break;
    case 8: /* a horizontal grid at one height */
        for (int i = -4; i <= 4; i++) {
            box(c, i * 0.22, 1.0, 0, 0.05, 0.05, 2.0, 0, 0);
            box(c, 0, 1.05, i * 0.22, 2.0, 0.05, 0.05, 0, 0);
        }
        break;
    case 9: /* a standing fence: pickets and rails */
        for (int i = -6; i <= 6; i++) box(c, i * 0.2, 0.6, 0, 0.06, 1.2, 0.06, 0, 0);
        box(c, 0, 0.3, 0, 2.6, 0.06, 0.06, 0, 0);
        box(c, 0, 1.0, 0, 2.6, 0.06, 0.06, 0, 0);
        break;
    case 10: /* leaves at one height */
    case 11: /* leaves from the floor up: a bush */
        for (int i = 0; i < 70; i++) {
            double r = 0.9 * sqrt(mr_rng_uniform(&rng)), a = 6.2831853 * mr_rng_uniform(&rng);
            double y = index == 10 ? 1.0 + 0.05 * mr_rng_uniform(&rng) : 0.1 + 1.6 * mr_rng_uniform(&rng);
            box(c, r * cos(a), y, r * sin(a), 0.18, 0.01, 0.1, 6.2831853 * mr_rng_uniform(&rng),
                0.6 * (mr_rng_uniform(&rng) - 0.5));
        }
        if (index == 11) box(c, 0, 0.6, 0, 0.05, 1.2, 0.05, 0, 0); /* the stem */
        break;
    default:
        break;
    }
}

static mr_view view_at(mr_dvec3 eye, mr_dvec3 at) {
    mr_view v;
    memset(&v, 0, sizeof v);
    v.camera.width = 320;
    v.camera.height = 240;
    v.camera.fx = v.camera.fy = 280;
    v.camera.cx = 159.5;
    v.camera.cy = 119.5;
    v.world_from_camera = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
    return v;
}

bool mr_shadow_suite_build(int index, mr_shadow_suite_case *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (index < 0 || index >= MR_SHADOW_SUITE_COUNT) return mr_fail(err, MR_ERR_INVALID, "no shadow suite case %d", index);
    snprintf(out->name, sizeof out->name, "%s", k_names[index]);
    out->varying = strstr(k_names[index], "varying") != NULL || index == 12;
    out->overlap = strstr(k_names[index], "overlap") != NULL || (index >= 8 && index <= 12);
    if (index == 12) {
        /* The demo hall as planned, under the default sun with a wider disk. */
        mr_demo_hall hall;
        if (!mr_demo_build(NULL, &hall, err)) return false;
        out->scene = hall.planned;
        hall.planned = NULL;
        mr_demo_free(&hall);
        mr_scene *s = out->scene;
        s->light_count = 2;
        memset(s->lights, 0, 2 * sizeof s->lights[0]);
        const double d0[3] = {0.4, 1.0, 0.25}, d1[3] = {-0.5, 0.3, -0.7};
        double l0 = sqrt(d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]);
        for (int k = 0; k < 3; k++) {
            s->lights[0].direction[k] = d0[k] / l0;
            s->lights[1].direction[k] = d1[k];
            s->lights[0].color[k] = 0.55f;
            s->lights[1].color[k] = 0.2f;
        }
        s->lights[0].kind = MR_LIGHT_SUN;
        s->lights[0].casts = true;
        s->lights[0].angle = 3.0;
        double cx = 0.5 * (s->bounds_min[0] + s->bounds_max[0]), cz = 0.5 * (s->bounds_min[2] + s->bounds_max[2]);
        out->views[0] = view_at(mr_v3(cx + 6, 3.0, cz + 5), mr_v3(cx, 0.5, cz));
        out->views[1] = view_at(mr_v3(cx - 8, 5.0, cz - 2), mr_v3(cx + 1, 0.0, cz + 1));
        return true;
    }
    suite_ctx c = {mr_scene_create(), -1, 0, true};
    if (!c.s) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    c.box = unit_box(c.s, err);
    c.ok = c.box >= 0;
    box(&c, 0, -0.05, 0, 10, 0.1, 10, 0, 0); /* the floor */
    build(&c, index);
    if (!c.ok) {
        mr_scene_destroy(&c.s);
        if (c.box < 0) return false; /* err says why */
        return mr_fail(err, MR_ERR_NOMEM, "cannot build shadow suite case %s", k_names[index]);
    }
    mr_scene_update_bounds(c.s);
    mr_light *L = &c.s->lights[0];
    c.s->light_count = 1;
    L->direction[1] = 1;
    L->color[0] = L->color[1] = L->color[2] = 0.65f;
    L->kind = MR_LIGHT_RECT;
    L->casts = true;
    L->position[0] = 0.4;
    L->position[1] = 5.0;
    L->position[2] = 0.3;
    L->size[0] = L->size[1] = 1.2;
    L->axis_u[0] = 1;
    out->scene = c.s;
    out->views[0] = view_at(mr_v3(3.2, 2.6, 3.0), mr_v3(0, 0.3, 0));
    out->views[1] = view_at(mr_v3(-3.0, 3.8, -1.6), mr_v3(0.2, 0.0, 0.3));
    return true;
}

void mr_shadow_suite_free(mr_shadow_suite_case *c) {
    if (!c) return;
    mr_scene_destroy(&c->scene);
    memset(c, 0, sizeof *c);
}
