/* The procedural demo factory hall, as planned and as built.
 *
 * World frame = glTF: Y up, metres. The hall's inner wall faces are at
 * x = +-20 and z = +-12, the floor top at y = 0. North is -z, east is +x.
 * Both variants are generated from one plan (drawn once from the seed), so
 * they differ only by the three discrepancies listed in `discrepancies`.
 */
#include "mr_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEMO_PI 3.14159265358979323846

/* Hall geometry (metres). */
#define HALL_X 20.0  /* inner faces of Wall_E / Wall_W at +-HALL_X */
#define HALL_Z 12.0  /* inner faces of Wall_S / Wall_N at +-HALL_Z */
#define HALL_H 8.0
#define WALL_T 0.3
#define FLOOR_T 0.2
#define COL_HALF 0.2
#define TAG_GAP 0.005 /* plate in front of its surface: no z-fighting */

/* Column grid, every 8 m: Column_r_c stands at x = k_col_x[c], z = k_col_z[r]. */
static const double k_col_x[4] = {-12.0, -4.0, 4.0, 12.0};
static const double k_col_z[2] = {-4.0, 4.0};

/* The three known discrepancies of the built hall. */
#define MOVED_MACHINE 2
#define MOVED_DX 0.30
#define MISSING_COL_R 1
#define MISSING_COL_C 0
#define RAISED_PIPE 1
#define RAISED_DY 0.25

#define N_MACHINES 5
#define N_PIPES 4
#define N_TRAYS 3
#define N_CONVEYORS 3
#define MAX_TAGS 32 /* 16 on walls and columns, 16 on the four tag posts */
#define WALL_TAGS 16

/* Partition wall and the pipes behind it (on its +z side). */
#define PART_X 12.0  /* length */
#define PART_CX -12.0
#define PART_Z 8.0
#define PART_H 4.0
#define PART_T 0.2

/* Suspended ceiling over x in [2,20], z in [-12,0]; trays just above. */
#define CEIL_X0 2.0
#define CEIL_Z1 0.0
#define CEIL_Y 5.5
#define CEIL_T 0.05

static const char *const k_hidden_globs[] = {"Pipe_*", "CableTray_*"};

/* ------------------------------------------------------------ mesh buffer */

/* Growable vertex/index arrays that become one mr_mesh. */
typedef struct mesh_buf {
    float *pos, *nrm, *uv;
    uint32_t *idx;
    uint32_t nv, ni, cap_v, cap_i;
    bool with_uv;
    bool oom;
} mesh_buf;

static void mb_free(mesh_buf *b) {
    free(b->pos);
    free(b->nrm);
    free(b->uv);
    free(b->idx);
    memset(b, 0, sizeof *b);
}

static bool mb_reserve(mesh_buf *b, uint32_t add_v, uint32_t add_i) {
    if (b->oom) return false;
    if (b->nv + add_v > b->cap_v) {
        uint32_t cap = b->cap_v ? b->cap_v : 64;
        while (cap < b->nv + add_v) cap *= 2;
        float *p = realloc(b->pos, (size_t)cap * 3 * sizeof *p);
        if (!p) goto oom;
        b->pos = p;
        p = realloc(b->nrm, (size_t)cap * 3 * sizeof *p);
        if (!p) goto oom;
        b->nrm = p;
        if (b->with_uv) {
            p = realloc(b->uv, (size_t)cap * 2 * sizeof *p);
            if (!p) goto oom;
            b->uv = p;
        }
        b->cap_v = cap;
    }
    if (b->ni + add_i > b->cap_i) {
        uint32_t cap = b->cap_i ? b->cap_i : 128;
        while (cap < b->ni + add_i) cap *= 2;
        uint32_t *q = realloc(b->idx, (size_t)cap * sizeof *q);
        if (!q) goto oom;
        b->idx = q;
        b->cap_i = cap;
    }
    return true;
oom: /* arrays already grown stay valid; commit_mesh reports and frees */
    b->oom = true;
    return false;
}

/* Appends one vertex (room must be reserved); xf may be NULL. */
static uint32_t mb_vertex(mesh_buf *b, const mr_dmat4 *xf, mr_dvec3 p, mr_dvec3 n, double u, double v) {
    if (xf) {
        p = mr_m4_point(xf, p);
        n = mr_v3_normalize(mr_m4_dir(xf, n));
    }
    float *P = b->pos + 3 * (size_t)b->nv, *N = b->nrm + 3 * (size_t)b->nv;
    P[0] = (float)p.x, P[1] = (float)p.y, P[2] = (float)p.z;
    N[0] = (float)n.x, N[1] = (float)n.y, N[2] = (float)n.z;
    if (b->with_uv) {
        b->uv[2 * (size_t)b->nv] = (float)u;
        b->uv[2 * (size_t)b->nv + 1] = (float)v;
    }
    return b->nv++;
}

static void mb_tri(mesh_buf *b, uint32_t i0, uint32_t i1, uint32_t i2) {
    b->idx[b->ni++] = i0;
    b->idx[b->ni++] = i1;
    b->idx[b->ni++] = i2;
}

static double v3_get(mr_dvec3 v, int k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }

static mr_dvec3 v3_axis(int k, double s) {
    return mr_v3(k == 0 ? s : 0.0, k == 1 ? s : 0.0, k == 2 ? s : 0.0);
}

/* Axis-aligned box lo..hi (then transformed by xf): 24 vertices, flat
 * normals, counter-clockwise seen from outside. */
static void mb_box(mesh_buf *b, const mr_dmat4 *xf, mr_dvec3 lo, mr_dvec3 hi) {
    if (!mb_reserve(b, 24, 36)) return;
    mr_dvec3 c = mr_v3_scale(mr_v3_add(lo, hi), 0.5), h = mr_v3_scale(mr_v3_sub(hi, lo), 0.5);
    for (int a = 0; a < 3; a++) {
        for (int side = 0; side < 2; side++) {
            double s = side ? 1.0 : -1.0;
            int ku = (a + 1) % 3, kv = (a + 2) % 3;
            if (s < 0) { int t = ku; ku = kv; kv = t; } /* keeps cross(u, v) = n */
            mr_dvec3 n = v3_axis(a, s);
            mr_dvec3 fc = mr_v3_add(c, v3_axis(a, s * v3_get(h, a)));
            mr_dvec3 u = v3_axis(ku, v3_get(h, ku)), v = v3_axis(kv, v3_get(h, kv));
            uint32_t i0 = mb_vertex(b, xf, mr_v3_sub(mr_v3_sub(fc, u), v), n, 0, 0);
            uint32_t i1 = mb_vertex(b, xf, mr_v3_sub(mr_v3_add(fc, u), v), n, 1, 0);
            uint32_t i2 = mb_vertex(b, xf, mr_v3_add(mr_v3_add(fc, u), v), n, 1, 1);
            uint32_t i3 = mb_vertex(b, xf, mr_v3_add(mr_v3_sub(fc, u), v), n, 0, 1);
            mb_tri(b, i0, i1, i2);
            mb_tri(b, i0, i2, i3);
        }
    }
}

/* Cylinder along local +y, centred on the origin: `seg` segments with smooth
 * side normals, `rings` bands along the axis (long pipes get many, so that
 * per-vertex effects have vertices to work with), flat caps. */
static void mb_cylinder(mesh_buf *b, const mr_dmat4 *xf, double r, double len, int seg, int rings) {
    uint32_t S = (uint32_t)seg, R = (uint32_t)rings;
    if (!mb_reserve(b, S * (R + 1) + 2 * (S + 1), 6 * S * R + 6 * S)) return;
    uint32_t base = b->nv;
    for (uint32_t j = 0; j <= R; j++) {
        double y = -0.5 * len + len * (double)j / (double)R;
        for (uint32_t i = 0; i < S; i++) {
            double t = 2.0 * DEMO_PI * (double)i / (double)S;
            mr_dvec3 n = mr_v3(cos(t), 0.0, sin(t));
            mb_vertex(b, xf, mr_v3(r * n.x, y, r * n.z), n, 0, 0);
        }
    }
    for (uint32_t j = 0; j < R; j++)
        for (uint32_t i = 0; i < S; i++) {
            uint32_t a = base + j * S + i, bb = base + j * S + (i + 1) % S;
            uint32_t c = bb + S, d = a + S;
            mb_tri(b, a, d, c);
            mb_tri(b, a, c, bb);
        }
    for (int cap = 0; cap < 2; cap++) {
        double y = cap ? 0.5 * len : -0.5 * len;
        mr_dvec3 n = mr_v3(0.0, cap ? 1.0 : -1.0, 0.0);
        uint32_t centre = mb_vertex(b, xf, mr_v3(0.0, y, 0.0), n, 0, 0);
        uint32_t ring = b->nv;
        for (uint32_t i = 0; i < S; i++) {
            double t = 2.0 * DEMO_PI * (double)i / (double)S;
            mb_vertex(b, xf, mr_v3(r * cos(t), y, r * sin(t)), n, 0, 0);
        }
        for (uint32_t i = 0; i < S; i++) {
            uint32_t p0 = ring + i, p1 = ring + (i + 1) % S;
            if (cap) mb_tri(b, centre, p1, p0);
            else mb_tri(b, centre, p0, p1);
        }
    }
}

/* Textured square of edge `plate` in the tag frame (x right, y down, z into
 * the surface), facing -z. uv (0,0) is the image's top-left corner, so pixel
 * (col,row) lands at ((col+0.5)/W - 0.5) * plate, ((row+0.5)/W - 0.5) * plate. */
static void mb_tag_quad(mesh_buf *b, double plate) {
    if (!mb_reserve(b, 4, 6)) return;
    double h = 0.5 * plate;
    mr_dvec3 n = mr_v3(0.0, 0.0, -1.0);
    uint32_t tl = mb_vertex(b, NULL, mr_v3(-h, -h, 0.0), n, 0.0, 0.0);
    uint32_t tr = mb_vertex(b, NULL, mr_v3(h, -h, 0.0), n, 1.0, 0.0);
    uint32_t br = mb_vertex(b, NULL, mr_v3(h, h, 0.0), n, 1.0, 1.0);
    uint32_t bl = mb_vertex(b, NULL, mr_v3(-h, h, 0.0), n, 0.0, 1.0);
    mb_tri(b, tl, bl, br); /* counter-clockwise seen from -z */
    mb_tri(b, tl, br, tr);
}

/* ------------------------------------------------------------------- plan */

typedef struct machine_plan {
    double x, z, yaw;      /* footprint centre on the floor, rotation about y */
    double sx, sy, sz;     /* housing size (local x, y, z) */
    float rgb[3];          /* linear housing colour */
    bool tank;
} machine_plan;

typedef struct conveyor_plan {
    double x, z, yaw, length;
    bool rollers;          /* roller conveyor instead of a belt */
} conveyor_plan;

typedef struct pipe_plan {
    double y, radius;
    int color;             /* index into k_pipe_rgb */
} pipe_plan;

typedef struct demo_plan {
    machine_plan machines[N_MACHINES];
} demo_plan;

static const machine_plan k_machines[N_MACHINES] = {
    {-15.0, -8.0, 0.0, 3.2, 2.2, 2.2, {0.10f, 0.32f, 0.12f}, true},        /* green mill */
    {-8.0, -8.0, 0.0, 2.6, 1.8, 2.4, {0.04f, 0.14f, 0.45f}, false},        /* blue press */
    {0.0, 0.0, 0.0, 3.0, 2.4, 2.0, {0.80f, 0.25f, 0.03f}, false},          /* orange robot cell */
    {8.0, 0.6, 0.5 * DEMO_PI, 2.4, 2.0, 2.0, {0.75f, 0.55f, 0.04f}, false}, /* yellow lathe */
    {15.0, 8.0, 0.0, 3.4, 2.6, 2.4, {0.50f, 0.05f, 0.06f}, true},          /* red furnace */
};

static const conveyor_plan k_conveyors[N_CONVEYORS] = {
    {3.0, 8.0, 0.0, 12.0, false},
    {8.0, -6.75, 0.5 * DEMO_PI, 8.5, true},
    {-12.0, 0.0, 0.0, 10.0, true},
};

static const float k_pipe_rgb[3][3] = {
    {0.05f, 0.20f, 0.60f}, /* water: blue */
    {0.70f, 0.04f, 0.03f}, /* sprinkler: red */
    {0.85f, 0.65f, 0.02f}, /* gas: yellow */
};

/* Pipe_0 and Pipe_3 have the same size and colour, so they share a mesh. */
static const pipe_plan k_pipes[N_PIPES] = {
    {1.0, 0.05, 0}, {1.8, 0.10, 1}, {2.6, 0.075, 2}, {3.3, 0.05, 0},
};

static const double k_tray_z[N_TRAYS] = {-10.0, -7.0, -1.5};
static const double k_tray_w[N_TRAYS] = {0.6, 0.6, 0.4};

/* Tag slots: a point on a surface facing into the hall, outward normal
 * (nx, 0, nz). Walls first, then columns; extra slots only used when more
 * than 12 tag images are given. None sits on the missing column. */
typedef struct tag_slot { double x, y, z, nx, nz; } tag_slot;
static const tag_slot k_tag_slots[WALL_TAGS] = {
    {-11.0, 2.2, -HALL_Z, 0, 1},  {-1.0, 1.8, -HALL_Z, 0, 1}, {9.0, 2.3, -HALL_Z, 0, 1},
    {HALL_X, 2.0, -6.0, -1, 0},   {HALL_X, 1.7, 5.0, -1, 0},
    {12.0, 2.1, HALL_Z, 0, -1},   {1.0, 1.9, HALL_Z, 0, -1},
    {-HALL_X, 2.0, -5.0, 1, 0},   {-HALL_X, 2.4, 3.0, 1, 0},
    {-4.0, 1.6, -4.0 + COL_HALF, 0, 1},   /* Column_0_1, south face */
    {4.0 - COL_HALF, 2.0, 4.0, -1, 0},    /* Column_1_2, west face */
    {12.0 - COL_HALF, 1.7, -4.0, -1, 0},  /* Column_0_3, west face */
    {16.0, 1.9, -HALL_Z, 0, 1},   {HALL_X, 2.3, 0.0, -1, 0},
    {-4.0, 2.1, 4.0 - COL_HALF, 0, -1},   /* Column_1_1, north face */
    {-HALL_X, 1.6, -10.0, 1, 0},
};

static double jitter(mr_rng *rng, double amp) { return amp * (2.0 * mr_rng_uniform(rng) - 1.0); }

static void make_plan(uint64_t seed, demo_plan *plan) {
    mr_rng rng;
    mr_rng_seed(&rng, seed);
    for (int k = 0; k < N_MACHINES; k++) {
        machine_plan *m = &plan->machines[k];
        *m = k_machines[k];
        m->x += jitter(&rng, 0.1);
        m->z += jitter(&rng, 0.1);
        m->sx += jitter(&rng, 0.1);
        m->sy += jitter(&rng, 0.1);
        m->sz += jitter(&rng, 0.1);
        for (int c = 0; c < 3; c++) m->rgb[c] *= (float)(1.0 + jitter(&rng, 0.05));
    }
}

/* Tag posts: square pillars carrying a cluster of four tags, two
 * on each of the two faces turned towards a check point of the walk, so
 * that a camera there sees 2-4 tags within a metre, not coplanar (a pose
 * from them has no mirror ambiguity). In both halls: they are surveyed,
 * part of the marker map. Tags 16.. sit on them, four per post. */
typedef struct tag_post { double x, z, toward_x, toward_z; } tag_post;
static const tag_post k_tag_posts[(MAX_TAGS - WALL_TAGS) / 4] = {
    {10.5, -1.2, 11.5, 4.0},   /* by the yellow lathe and the roller conveyor */
    {3.4, 2.2, 7.5, 4.8},      /* by the robot cell (Machine_2, moved); both faces seen on the way */
    {-6.2, 2.4, -2.5, 2.5},    /* by the west roller conveyor */
    {-9.6, 6.6, -6.5, 3.0},    /* by the missing column and the partition */
};
#define POST_HALF 0.3
#define POST_H 2.3
static const double k_post_tag_y[2] = {1.05, 1.75};

/* The two face normals of post k: towards its check point, turned by
 * -45 and +45 degrees (rotation about +y: (x, z) -> (x c + z s, -x s + z c)). */
static void post_normals(int k, double n[2][2]) {
    const tag_post *p = &k_tag_posts[k];
    double dx = p->toward_x - p->x, dz = p->toward_z - p->z, l = sqrt(dx * dx + dz * dz);
    dx /= l, dz /= l;
    const double c = sqrt(0.5);
    for (int f = 0; f < 2; f++) {
        double s = f == 0 ? c : -c;
        n[f][0] = dx * c + dz * s;
        n[f][1] = -dx * s + dz * c;
    }
}

static tag_slot slot_of(int i) {
    if (i < WALL_TAGS) return k_tag_slots[i];
    int j = i - WALL_TAGS, k = j / 4, f = (j / 2) % 2, level = j % 2;
    double n[2][2];
    post_normals(k, n);
    tag_slot t = {k_tag_posts[k].x + POST_HALF * n[f][0], k_post_tag_y[level], k_tag_posts[k].z + POST_HALF * n[f][1],
                  n[f][0], n[f][1]};
    return t;
}

static mr_dmat4 tag_pose(const tag_slot *t) {
    mr_dvec3 n = mr_v3(t->nx, 0.0, t->nz), up = mr_v3(0.0, 1.0, 0.0);
    mr_dvec3 x = mr_v3_cross(mr_v3_scale(n, -1.0), up), y = mr_v3_scale(up, -1.0), z = mr_v3_scale(n, -1.0);
    mr_dvec3 o = mr_v3_add(mr_v3(t->x, t->y, t->z), mr_v3_scale(n, TAG_GAP));
    mr_dmat4 m = {{x.x, y.x, z.x, o.x, x.y, y.y, z.y, o.y, x.z, y.z, z.z, o.z, 0, 0, 0, 1}};
    return m;
}

/* ---------------------------------------------------------- scene builder */

enum {
    MAT_FLOOR, MAT_WALL, MAT_COLUMN, MAT_PARTITION, MAT_CEILING, MAT_TRAY, MAT_CABLE,
    MAT_CABINET, MAT_TOPUNIT, MAT_LAMP, MAT_TANK, MAT_BELT, MAT_RAIL, MAT_LEG, MAT_STEEL,
    MAT_TAG_BACKING, MAT_TAG_WHITE, MAT_PIPE0, MAT_COUNT = MAT_PIPE0 + 3
};

typedef struct hall_ctx {
    mr_scene *s;
    mr_error *err;
    bool ok;                 /* false after the first failure; later calls do nothing */
    bool built;              /* as built (with the discrepancies) */
    const demo_plan *plan;
    const mr_demo_params *params;
    double tag_size;
    int tag_count;
    int32_t mat[MAT_COUNT];
} hall_ctx;

static int32_t add_material(hall_ctx *h, const char *name, float r, float g, float b, int32_t tex) {
    if (!h->ok) return -1;
    mr_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    m.base_color[0] = r, m.base_color[1] = g, m.base_color[2] = b, m.base_color[3] = 1.0f;
    m.base_color_texture = tex;
    int32_t i = mr_scene_add_material(h->s, &m);
    if (i < 0) h->ok = mr_fail(h->err, MR_ERR_NOMEM, "demo: cannot add material %s", name);
    return i;
}

/* Moves the buffer into the scene as one mesh; the buffer is emptied. */
static int32_t commit_mesh(hall_ctx *h, mesh_buf *b, const char *name, int32_t material) {
    int32_t idx = -1;
    if (h->ok && b->oom) h->ok = mr_fail(h->err, MR_ERR_NOMEM, "demo: out of memory building mesh %s", name);
    if (h->ok) {
        mr_mesh m;
        memset(&m, 0, sizeof m);
        snprintf(m.name, sizeof m.name, "%s", name);
        m.positions = b->pos;
        m.normals = b->nrm;
        m.uvs = b->with_uv ? b->uv : NULL;
        m.indices = b->idx;
        m.vertex_count = b->nv;
        m.index_count = b->ni;
        m.material = material;
        idx = mr_scene_add_mesh(h->s, &m, h->err);
        if (idx < 0) {
            h->ok = false;
        } else {
            memset(b, 0, sizeof *b); /* arrays now belong to the scene */
            return idx;
        }
    }
    mb_free(b);
    return -1;
}

static int32_t box_mesh(hall_ctx *h, const char *name, int32_t material, mr_dvec3 lo, mr_dvec3 hi) {
    mesh_buf b = {0};
    mb_box(&b, NULL, lo, hi);
    return commit_mesh(h, &b, name, material);
}

static int32_t cylinder_mesh(hall_ctx *h, const char *name, int32_t material, const mr_dmat4 *xf, double r,
                             double len, int seg, int rings) {
    mesh_buf b = {0};
    mb_cylinder(&b, xf, r, len, seg, rings);
    return commit_mesh(h, &b, name, material);
}

static int32_t add_node(hall_ctx *h, const char *name, int32_t parent, mr_dmat4 world, int32_t mesh,
                        mr_layer layer) {
    if (!h->ok) return -1;
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "%s", name);
    n.parent = parent;
    n.world = world;
    n.mesh_first = mesh;
    n.mesh_count = mesh >= 0 ? 1 : 0;
    n.layer = (uint8_t)layer;
    int32_t i = mr_scene_add_node(h->s, &n);
    if (i < 0) h->ok = mr_fail(h->err, MR_ERR_NOMEM, "demo: cannot add node %s", name);
    return i;
}

static mr_dmat4 mul(mr_dmat4 a, mr_dmat4 b) { return mr_m4_mul(&a, &b); }

static mr_dmat4 place(double x, double y, double z, double yaw) {
    return mul(mr_m4_translate(x, y, z), mr_m4_rotate_axis(mr_v3(0, 1, 0), yaw));
}

static void build_materials(hall_ctx *h) {
    static const struct { const char *name; float r, g, b; } k[MAT_PIPE0] = {
        {"Concrete", 0.30f, 0.30f, 0.29f},   {"WallPaint", 0.70f, 0.70f, 0.66f},
        {"ColumnSteel", 0.40f, 0.45f, 0.52f}, {"Drywall", 0.62f, 0.58f, 0.50f},
        {"CeilingPanel", 0.80f, 0.80f, 0.78f}, {"Galvanised", 0.55f, 0.57f, 0.58f},
        {"Cable", 0.02f, 0.02f, 0.02f},      {"Cabinet", 0.70f, 0.70f, 0.68f},
        {"TopUnit", 0.10f, 0.10f, 0.11f},    {"Lamp", 0.05f, 0.60f, 0.08f},
        {"Tank", 0.60f, 0.60f, 0.60f},       {"Belt", 0.03f, 0.03f, 0.03f},
        {"Aluminium", 0.60f, 0.62f, 0.64f},  {"LegPaint", 0.20f, 0.20f, 0.22f},
        {"Steel", 0.50f, 0.50f, 0.52f},      {"TagBacking", 1.0f, 1.0f, 1.0f},
        {"TagWhite", 1.0f, 1.0f, 1.0f},
    };
    for (int i = 0; i < MAT_PIPE0; i++) h->mat[i] = add_material(h, k[i].name, k[i].r, k[i].g, k[i].b, -1);
    static const char *const pipe_names[3] = {"PipeWater", "PipeSprinkler", "PipeGas"};
    /* The ghosting conflict case: the hidden pipes take the colour of the
     * partition in front of them, so plain ghosting loses them. */
    const bool conflict = h->params && h->params->pipes_like_partition;
    for (int i = 0; i < 3; i++) {
        float r = k_pipe_rgb[i][0], g = k_pipe_rgb[i][1], b = k_pipe_rgb[i][2];
        if (conflict) r = k[MAT_PARTITION].r, g = k[MAT_PARTITION].g, b = k[MAT_PARTITION].b;
        h->mat[MAT_PIPE0 + i] = add_material(h, pipe_names[i], r, g, b, -1);
    }
}

static void build_shell(hall_ctx *h) {
    const double X = HALL_X + WALL_T, Z = HALL_Z + WALL_T;
    int32_t floor_mesh = box_mesh(h, "Floor", h->mat[MAT_FLOOR], mr_v3(-X, -FLOOR_T, -Z), mr_v3(X, 0, Z));
    add_node(h, "Floor", -1, mr_m4_identity(), floor_mesh, MR_LAYER_VISIBLE);
    /* North/south walls span the corners; east/west fit between them. */
    int32_t ns = box_mesh(h, "WallNS", h->mat[MAT_WALL], mr_v3(-X, 0, -0.5 * WALL_T), mr_v3(X, HALL_H, 0.5 * WALL_T));
    int32_t ew = box_mesh(h, "WallEW", h->mat[MAT_WALL], mr_v3(-0.5 * WALL_T, 0, -HALL_Z), mr_v3(0.5 * WALL_T, HALL_H, HALL_Z));
    const double c = 0.5 * WALL_T;
    add_node(h, "Wall_N", -1, mr_m4_translate(0, 0, -HALL_Z - c), ns, MR_LAYER_VISIBLE);
    add_node(h, "Wall_S", -1, mr_m4_translate(0, 0, HALL_Z + c), ns, MR_LAYER_VISIBLE);
    add_node(h, "Wall_E", -1, mr_m4_translate(HALL_X + c, 0, 0), ew, MR_LAYER_VISIBLE);
    add_node(h, "Wall_W", -1, mr_m4_translate(-HALL_X - c, 0, 0), ew, MR_LAYER_VISIBLE);

    int32_t col = box_mesh(h, "Column", h->mat[MAT_COLUMN], mr_v3(-COL_HALF, 0, -COL_HALF), mr_v3(COL_HALF, HALL_H, COL_HALF));
    for (int r = 0; r < 2; r++)
        for (int ci = 0; ci < 4; ci++) {
            if (h->built && r == MISSING_COL_R && ci == MISSING_COL_C) continue;
            char name[32];
            snprintf(name, sizeof name, "Column_%d_%d", r, ci);
            add_node(h, name, -1, mr_m4_translate(k_col_x[ci], 0, k_col_z[r]), col, MR_LAYER_VISIBLE);
        }
}

static void build_partition_and_pipes(hall_ctx *h) {
    int32_t part = box_mesh(h, "Partition", h->mat[MAT_PARTITION], mr_v3(-0.5 * PART_X, 0, -0.5 * PART_T),
                            mr_v3(0.5 * PART_X, PART_H, 0.5 * PART_T));
    add_node(h, "Wall_Partition", -1, mr_m4_translate(PART_CX, 0, PART_Z), part, MR_LAYER_VISIBLE);

    /* Pipes run along x, 0.12 m behind the partition's back face. */
    const double len = PART_X - 0.4;
    mr_dmat4 along_x = mr_m4_rotate_axis(mr_v3(0, 0, 1), -0.5 * DEMO_PI);
    int32_t meshes[N_PIPES];
    for (int k = 0; k < N_PIPES; k++) {
        meshes[k] = -1;
        for (int j = 0; j < k; j++)
            if (k_pipes[j].radius == k_pipes[k].radius && k_pipes[j].color == k_pipes[k].color) meshes[k] = meshes[j];
        if (meshes[k] < 0) {
            char name[32];
            snprintf(name, sizeof name, "Pipe_d%.0fmm", 2000.0 * k_pipes[k].radius);
            meshes[k] = cylinder_mesh(h, name, h->mat[MAT_PIPE0 + k_pipes[k].color], &along_x, k_pipes[k].radius,
                                      len, 32, (int)ceil(len / 0.2));
        }
        double y = k_pipes[k].y + (h->built && k == RAISED_PIPE ? RAISED_DY : 0.0);
        double z = PART_Z + 0.5 * PART_T + 0.12 + k_pipes[k].radius;
        char name[32];
        snprintf(name, sizeof name, "Pipe_%d", k);
        add_node(h, name, -1, mr_m4_translate(PART_CX, y, z), meshes[k], MR_LAYER_HIDDEN);
    }
}

static void build_ceiling_and_trays(hall_ctx *h) {
    const double cx = 0.5 * (CEIL_X0 + HALL_X), cz = 0.5 * (-HALL_Z + CEIL_Z1);
    const double hx = 0.5 * (HALL_X - CEIL_X0), hz = 0.5 * (CEIL_Z1 + HALL_Z);
    int32_t ceil_mesh = box_mesh(h, "Ceiling", h->mat[MAT_CEILING], mr_v3(-hx, 0, -hz), mr_v3(hx, CEIL_T, hz));
    add_node(h, "Ceiling", -1, mr_m4_translate(cx, CEIL_Y, cz), ceil_mesh, MR_LAYER_VISIBLE);

    /* U-shaped trays along x, 5 cm above the ceiling, with a cable bundle. */
    const double len = HALL_X - CEIL_X0 - 1.0, wall = 0.01, height = 0.1;
    int32_t tray_mesh[N_TRAYS];
    for (int k = 0; k < N_TRAYS; k++) {
        tray_mesh[k] = -1;
        for (int j = 0; j < k; j++)
            if (k_tray_w[j] == k_tray_w[k]) tray_mesh[k] = tray_mesh[j];
        if (tray_mesh[k] >= 0) continue;
        double w = 0.5 * k_tray_w[k], L = 0.5 * len;
        mesh_buf b = {0};
        mb_box(&b, NULL, mr_v3(-L, 0, -w + wall), mr_v3(L, wall, w - wall));
        mb_box(&b, NULL, mr_v3(-L, 0, -w), mr_v3(L, height, -w + wall));
        mb_box(&b, NULL, mr_v3(-L, 0, w - wall), mr_v3(L, height, w));
        char name[32];
        snprintf(name, sizeof name, "CableTray_w%.0fcm", 100.0 * k_tray_w[k]);
        tray_mesh[k] = commit_mesh(h, &b, name, h->mat[MAT_TRAY]);
    }
    static const double k_cable_yz[4][2] = {{0.018, -0.04}, {0.018, 0.0}, {0.018, 0.04}, {0.052, -0.02}};
    mesh_buf cb = {0};
    mr_dmat4 along_x = mr_m4_rotate_axis(mr_v3(0, 0, 1), -0.5 * DEMO_PI);
    for (int i = 0; i < 4; i++) {
        mr_dmat4 xf = mul(mr_m4_translate(0, k_cable_yz[i][0], k_cable_yz[i][1]), along_x);
        mb_cylinder(&cb, &xf, 0.018, len - 0.1, 16, (int)ceil(len / 0.5));
    }
    int32_t cables = commit_mesh(h, &cb, "CableBundle", h->mat[MAT_CABLE]);
    for (int k = 0; k < N_TRAYS; k++) {
        char name[48];
        snprintf(name, sizeof name, "CableTray_%d", k);
        mr_dmat4 w = mr_m4_translate(cx, CEIL_Y + CEIL_T + 0.05, k_tray_z[k]);
        int32_t tray = add_node(h, name, -1, w, tray_mesh[k], MR_LAYER_HIDDEN);
        snprintf(name, sizeof name, "CableTray_%d_Cables", k);
        add_node(h, name, tray, mul(w, mr_m4_translate(0, wall, 0)), cables, MR_LAYER_HIDDEN);
    }
}

static void build_machines(hall_ctx *h) {
    int32_t cabinet = box_mesh(h, "Cabinet", h->mat[MAT_CABINET], mr_v3(-0.3, 0, -0.25), mr_v3(0.3, 1.9, 0.25));
    int32_t top = box_mesh(h, "TopUnit", h->mat[MAT_TOPUNIT], mr_v3(-0.5, 0, -0.4), mr_v3(0.5, 0.5, 0.4));
    mr_dmat4 lamp_xf = mr_m4_translate(0, 0.25, 0);
    int32_t lamp = cylinder_mesh(h, "SignalLamp", h->mat[MAT_LAMP], &lamp_xf, 0.04, 0.5, 16, 1);
    mr_dmat4 tank_xf = mr_m4_translate(0, 0.8, 0);
    int32_t tank = cylinder_mesh(h, "Tank", h->mat[MAT_TANK], &tank_xf, 0.5, 1.6, 48, 8);
    for (int k = 0; k < N_MACHINES; k++) {
        const machine_plan *m = &h->plan->machines[k];
        char name[48];
        /* Housing with a slightly smaller hood on top, in the machine's colour. */
        mesh_buf b = {0};
        mb_box(&b, NULL, mr_v3(-0.5 * m->sx, 0, -0.5 * m->sz), mr_v3(0.5 * m->sx, m->sy - 0.15, 0.5 * m->sz));
        mb_box(&b, NULL, mr_v3(-0.5 * m->sx + 0.1, m->sy - 0.15, -0.5 * m->sz + 0.1),
               mr_v3(0.5 * m->sx - 0.1, m->sy, 0.5 * m->sz - 0.1));
        snprintf(name, sizeof name, "Machine_%d_Housing", k);
        int32_t mat = add_material(h, name, m->rgb[0], m->rgb[1], m->rgb[2], -1);
        int32_t housing = commit_mesh(h, &b, name, mat);

        double dx = h->built && k == MOVED_MACHINE ? MOVED_DX : 0.0;
        mr_dmat4 w = place(m->x + dx, 0, m->z, m->yaw);
        snprintf(name, sizeof name, "Machine_%d", k);
        int32_t node = add_node(h, name, -1, w, housing, MR_LAYER_VISIBLE);
        snprintf(name, sizeof name, "Machine_%d_Cabinet", k);
        add_node(h, name, node, mul(w, mr_m4_translate(0.5 * m->sx + 0.32, 0, -0.5 * m->sz + 0.25)), cabinet,
                 MR_LAYER_VISIBLE);
        snprintf(name, sizeof name, "Machine_%d_Top", k);
        add_node(h, name, node, mul(w, mr_m4_translate(-0.25 * m->sx, m->sy, 0)), top, MR_LAYER_VISIBLE);
        snprintf(name, sizeof name, "Machine_%d_Lamp", k);
        add_node(h, name, node, mul(w, mr_m4_translate(0.5 * m->sx - 0.2, m->sy, 0.5 * m->sz - 0.2)), lamp,
                 MR_LAYER_VISIBLE);
        if (m->tank) {
            snprintf(name, sizeof name, "Machine_%d_Tank", k);
            add_node(h, name, node, mul(w, mr_m4_translate(-0.5 * m->sx - 0.6, 0, 0)), tank, MR_LAYER_VISIBLE);
        }
    }
}

static void build_conveyors(hall_ctx *h) {
    const double half_w = 0.4, bed = 0.8;
    int32_t leg = box_mesh(h, "ConveyorLeg", h->mat[MAT_LEG], mr_v3(-0.03, 0, -0.03), mr_v3(0.03, bed, 0.03));
    mr_dmat4 along_z = mr_m4_rotate_axis(mr_v3(1, 0, 0), 0.5 * DEMO_PI);
    int32_t roller = cylinder_mesh(h, "Roller", h->mat[MAT_STEEL], &along_z, 0.03, 2.0 * half_w, 32, 1);
    int32_t drum = cylinder_mesh(h, "Drum", h->mat[MAT_STEEL], &along_z, 0.05, 2.0 * half_w, 32, 1);
    for (int k = 0; k < N_CONVEYORS; k++) {
        const conveyor_plan *c = &k_conveyors[k];
        const double L = 0.5 * c->length;
        char name[48];
        mr_dmat4 w = place(c->x, 0, c->z, c->yaw);
        /* Belt conveyor: the belt box; roller conveyor: a drip tray below. */
        snprintf(name, sizeof name, "Conveyor_%d_Bed", k);
        int32_t bed_mesh = c->rollers
            ? box_mesh(h, name, h->mat[MAT_LEG], mr_v3(-L, bed - 0.02, -half_w), mr_v3(L, bed, half_w))
            : box_mesh(h, name, h->mat[MAT_BELT], mr_v3(-L, bed + 0.02, -half_w), mr_v3(L, bed + 0.1, half_w));
        snprintf(name, sizeof name, "Conveyor_%d", k);
        int32_t node = add_node(h, name, -1, w, bed_mesh, MR_LAYER_VISIBLE);

        snprintf(name, sizeof name, "Conveyor_%d_RailMesh", k);
        int32_t rail = box_mesh(h, name, h->mat[MAT_RAIL], mr_v3(-L, bed, -0.025), mr_v3(L, bed + 0.2, 0.025));
        for (int s = 0; s < 2; s++) {
            snprintf(name, sizeof name, "Conveyor_%d_Rail_%d", k, s);
            add_node(h, name, node, mul(w, mr_m4_translate(0, 0, (s ? 1 : -1) * (half_w + 0.025))), rail,
                     MR_LAYER_VISIBLE);
        }
        int legs = (int)ceil((c->length - 0.6) / 2.0) + 1;
        for (int j = 0; j < legs; j++) {
            double x = -L + 0.3 + (c->length - 0.6) * (double)j / (double)(legs - 1);
            for (int s = 0; s < 2; s++) {
                snprintf(name, sizeof name, "Conveyor_%d_Leg_%d", k, 2 * j + s);
                add_node(h, name, node, mul(w, mr_m4_translate(x, 0, (s ? 1 : -1) * (half_w - 0.03))), leg,
                         MR_LAYER_VISIBLE);
            }
        }
        if (c->rollers) {
            const double pitch = 0.075;
            int n = (int)floor(c->length / pitch);
            for (int j = 0; j < n; j++) {
                double x = -L + pitch * (j + 0.5);
                snprintf(name, sizeof name, "Conveyor_%d_Roller_%d", k, j);
                add_node(h, name, node, mul(w, mr_m4_translate(x, bed + 0.1, 0)), roller, MR_LAYER_VISIBLE);
            }
        } else {
            for (int s = 0; s < 2; s++) {
                snprintf(name, sizeof name, "Conveyor_%d_Drum_%d", k, s);
                add_node(h, name, node, mul(w, mr_m4_translate((s ? 1 : -1) * L, bed + 0.06, 0)), drum,
                         MR_LAYER_VISIBLE);
            }
        }
    }
}

/* Plate edge for tag i: the black square (W - 2*border px) is tag_size. */
static double plate_size(const hall_ctx *h, int i) {
    const mr_demo_params *p = h->params;
    if (!p->tag_images) return h->tag_size * 10.0 / 8.0; /* tag36h11 geometry */
    int W = p->tag_images[i].width, border = p->tag_border_px > 0 ? p->tag_border_px : 1;
    return h->tag_size * (double)W / (double)(W - 2 * border);
}

/* Gray (or RGB/RGBA) 8-bit tag image -> RGBA8 texture with NEAREST. */
static int32_t tag_texture(hall_ctx *h, const mr_image *img) {
    if (!h->ok) return -1;
    mr_texture tex;
    memset(&tex, 0, sizeof tex);
    tex.nearest = true;
    if (!mr_image_alloc(&tex.image, img->width, img->height, 4, MR_PIX_U8, h->err)) {
        h->ok = false;
        return -1;
    }
    const uint8_t *src = img->data;
    uint8_t *dst = tex.image.data;
    size_t n = (size_t)img->width * (size_t)img->height, ch = (size_t)img->channels;
    for (size_t i = 0; i < n; i++) {
        const uint8_t *s = src + i * ch;
        dst[4 * i + 0] = s[0];
        dst[4 * i + 1] = ch >= 3 ? s[1] : s[0];
        dst[4 * i + 2] = ch >= 3 ? s[2] : s[0];
        dst[4 * i + 3] = 255;
    }
    int32_t idx = mr_scene_add_texture(h->s, &tex);
    if (idx < 0) {
        mr_image_free(&tex.image);
        h->ok = mr_fail(h->err, MR_ERR_NOMEM, "demo: cannot add a tag texture");
    }
    return idx;
}

/* The posts whose tags are placed: local +x onto the first face normal. */
static void build_tag_posts(hall_ctx *h) {
    int32_t post = -1;
    for (int k = 0; k < (MAX_TAGS - WALL_TAGS) / 4 && WALL_TAGS + 4 * k < h->tag_count && h->ok; k++) {
        if (post < 0)
            post = box_mesh(h, "TagPost", h->mat[MAT_COLUMN], mr_v3(-POST_HALF, 0, -POST_HALF),
                            mr_v3(POST_HALF, POST_H, POST_HALF));
        double n[2][2];
        post_normals(k, n);
        double yaw = atan2(-n[0][1], n[0][0]);
        mr_dmat4 r = mr_m4_rotate_axis(mr_v3(0, 1, 0), yaw), t = mr_m4_translate(k_tag_posts[k].x, 0, k_tag_posts[k].z);
        char name[32];
        snprintf(name, sizeof name, "TagPost_%d", k);
        add_node(h, name, -1, mr_m4_mul(&t, &r), post, MR_LAYER_VISIBLE);
    }
}

static void build_tags(hall_ctx *h) {
    build_tag_posts(h);
    const mr_demo_params *p = h->params;
    int32_t shared_quad = -1, backing = -1;
    double backing_plate = -1.0;
    for (int i = 0; i < h->tag_count && h->ok; i++) {
        double plate = plate_size(h, i);
        char name[48];
        int32_t quad;
        if (p->tag_images) {
            int32_t tex = tag_texture(h, &p->tag_images[i]);
            snprintf(name, sizeof name, "Tag_%d", i);
            int32_t mat = add_material(h, name, 1.0f, 1.0f, 1.0f, tex);
            mesh_buf b = {.with_uv = true};
            mb_tag_quad(&b, plate);
            quad = commit_mesh(h, &b, name, mat);
        } else {
            if (shared_quad < 0) {
                mesh_buf b = {.with_uv = true};
                mb_tag_quad(&b, plate);
                shared_quad = commit_mesh(h, &b, "TagQuad", h->mat[MAT_TAG_WHITE]);
            }
            quad = shared_quad;
        }
        /* White backing plate from the surface to 1 mm behind the tag quad,
         * 2 cm wider on each side; shared while the plate size repeats. */
        if (plate != backing_plate) {
            double e = 0.5 * plate + 0.02;
            backing = box_mesh(h, "TagBacking", h->mat[MAT_TAG_BACKING], mr_v3(-e, -e, 0.001), mr_v3(e, e, TAG_GAP));
            backing_plate = plate;
        }
        tag_slot slot = slot_of(i);
        mr_dmat4 w = tag_pose(&slot);
        snprintf(name, sizeof name, "Tag_%d", i);
        int32_t node = add_node(h, name, -1, w, quad, MR_LAYER_VISIBLE);
        snprintf(name, sizeof name, "TagBacking_%d", i);
        add_node(h, name, node, w, backing, MR_LAYER_VISIBLE);
    }
}

static mr_scene *build_scene(const demo_plan *plan, const mr_demo_params *p, double tag_size, int tag_count,
                             bool built, mr_error *err) {
    hall_ctx h;
    memset(&h, 0, sizeof h);
    h.s = mr_scene_create();
    if (!h.s) {
        mr_fail(err, MR_ERR_NOMEM, "demo: cannot create a scene");
        return NULL;
    }
    h.err = err;
    h.ok = true;
    h.built = built;
    h.plan = plan;
    h.params = p;
    h.tag_size = tag_size;
    h.tag_count = tag_count;
    snprintf(h.s->source, sizeof h.s->source, "demo hall (%s)", built ? "as built" : "as planned");
    build_materials(&h);
    build_shell(&h);
    build_partition_and_pipes(&h);
    build_ceiling_and_trays(&h);
    build_machines(&h);
    build_conveyors(&h);
    build_tags(&h);
    if (!h.ok) {
        mr_scene_destroy(&h.s);
        return NULL;
    }
    mr_scene_update_bounds(h.s);
    return h.s;
}

/* ---------------------------------------------------------- discrepancies */

/* built_delta NULL: the part is missing. The delta is stored as given (not
 * re-derived from rounded positions). */
static bool add_discrepancy(cJSON *arr, int id, const char *kind, const char *node, const char *desc,
                            const double planned[3], const double *built_delta) {
    cJSON *o = cJSON_CreateObject();
    if (!o) return false;
    cJSON_AddItemToArray(arr, o);
    bool ok = cJSON_AddNumberToObject(o, "id", id) && cJSON_AddStringToObject(o, "kind", kind) &&
              cJSON_AddStringToObject(o, "node", node) && cJSON_AddStringToObject(o, "description", desc);
    cJSON *pp = mr_json_from_doubles(planned, 3);
    ok = ok && pp && cJSON_AddItemToObject(o, "planned_position", pp);
    if (!ok) return false;
    if (!built_delta) return cJSON_AddNullToObject(o, "built_position") != NULL;
    double b[3] = {planned[0] + built_delta[0], planned[1] + built_delta[1], planned[2] + built_delta[2]};
    cJSON *bp = mr_json_from_doubles(b, 3);
    if (!bp || !cJSON_AddItemToObject(o, "built_position", bp)) return false;
    cJSON *dp = mr_json_from_doubles(built_delta, 3);
    return dp && cJSON_AddItemToObject(o, "delta", dp);
}

static cJSON *make_discrepancies(const demo_plan *plan) {
    cJSON *arr = cJSON_CreateArray();
    if (!arr) return NULL;
    char node[48], desc[160];
    bool ok = true;

    const machine_plan *m = &plan->machines[MOVED_MACHINE];
    double mp[3] = {m->x, 0.0, m->z}, md[3] = {MOVED_DX, 0.0, 0.0};
    snprintf(node, sizeof node, "Machine_%d", MOVED_MACHINE);
    snprintf(desc, sizeof desc, "%s was installed %.2f m further along +x than planned", node, MOVED_DX);
    ok = ok && add_discrepancy(arr, 1, "moved", node, desc, mp, md);

    double cp[3] = {k_col_x[MISSING_COL_C], 0.0, k_col_z[MISSING_COL_R]};
    snprintf(node, sizeof node, "Column_%d_%d", MISSING_COL_R, MISSING_COL_C);
    snprintf(desc, sizeof desc, "%s (at x=%.1f, z=%.1f) was not built", node, cp[0], cp[2]);
    ok = ok && add_discrepancy(arr, 2, "missing", node, desc, cp, NULL);

    const pipe_plan *pp = &k_pipes[RAISED_PIPE];
    double pz = PART_Z + 0.5 * PART_T + 0.12 + pp->radius;
    double ppl[3] = {PART_CX, pp->y, pz}, pd[3] = {0.0, RAISED_DY, 0.0};
    snprintf(node, sizeof node, "Pipe_%d", RAISED_PIPE);
    snprintf(desc, sizeof desc, "%s (behind the partition) runs %.2f m higher than planned", node, RAISED_DY);
    ok = ok && add_discrepancy(arr, 3, "height", node, desc, ppl, pd);

    if (!ok) {
        cJSON_Delete(arr);
        return NULL;
    }
    return arr;
}

/* ------------------------------------------------------------------ API */

static bool check_params(const mr_demo_params *p, int *tag_count, mr_error *err) {
    if (!isfinite(p->tag_size) || p->tag_size < 0.0)
        return mr_fail(err, MR_ERR_INVALID, "demo: tag_size must be positive (got %g)", p->tag_size);
    if (p->tag_border_px < 0)
        return mr_fail(err, MR_ERR_INVALID, "demo: tag_border_px must not be negative (got %d)", p->tag_border_px);
    if (!p->tag_images) {
        *tag_count = 12;
        return true;
    }
    if (p->tag_image_count <= 0)
        return mr_fail(err, MR_ERR_INVALID, "demo: tag_images given but tag_image_count is %d", p->tag_image_count);
    int border = p->tag_border_px > 0 ? p->tag_border_px : 1;
    *tag_count = p->tag_image_count < MAX_TAGS ? p->tag_image_count : MAX_TAGS;
    if (p->tag_image_count > MAX_TAGS)
        mr_log(MR_LOG_WARN, "demo: %d tag images given, only the first %d are placed", p->tag_image_count, MAX_TAGS);
    for (int i = 0; i < *tag_count; i++) {
        const mr_image *im = &p->tag_images[i];
        if (!im->data || im->type != MR_PIX_U8 || im->channels < 1 || im->channels > 4)
            return mr_fail(err, MR_ERR_INVALID, "demo: tag image %d is not an 8-bit image", i);
        if (im->width != im->height || im->width <= 2 * border)
            return mr_fail(err, MR_ERR_INVALID, "demo: tag image %d is %dx%d; needs a square wider than 2*border (%d px)",
                           i, im->width, im->height, border);
    }
    return true;
}

bool mr_demo_build(const mr_demo_params *params, mr_demo_hall *out, mr_error *err) {
    if (!out) return mr_fail(err, MR_ERR_INVALID, "mr_demo_build: NULL output");
    memset(out, 0, sizeof *out);
    mr_demo_params p = MR_DEMO_DEFAULTS;
    if (params) p = *params;
    if (p.seed == 0) p.seed = 1;
    int tag_count = 0;
    if (!check_params(&p, &tag_count, err)) return false;
    double tag_size = p.tag_size > 0.0 ? p.tag_size : 0.4;

    demo_plan plan;
    make_plan(p.seed, &plan);
    out->tag_size = tag_size;
    out->hidden_globs = k_hidden_globs;
    out->hidden_glob_count = (int)(sizeof k_hidden_globs / sizeof k_hidden_globs[0]);
    out->planned = build_scene(&plan, &p, tag_size, tag_count, false, err);
    if (out->planned) out->built = build_scene(&plan, &p, tag_size, tag_count, true, err);
    if (!out->built) goto fail;

    out->tags = calloc((size_t)tag_count, sizeof *out->tags);
    if (!out->tags) {
        mr_fail(err, MR_ERR_NOMEM, "demo: out of memory");
        goto fail;
    }
    out->tag_count = tag_count;
    for (int i = 0; i < tag_count; i++) {
        out->tags[i].id = i;
        tag_slot slot = slot_of(i);
        out->tags[i].world_from_tag = tag_pose(&slot);
    }
    out->discrepancies = make_discrepancies(&plan);
    if (!out->discrepancies) {
        mr_fail(err, MR_ERR_NOMEM, "demo: out of memory building the discrepancy list");
        goto fail;
    }
    return true;
fail:
    mr_demo_free(out);
    return false;
}

void mr_demo_free(mr_demo_hall *hall) {
    if (!hall) return;
    mr_scene_destroy(&hall->planned);
    mr_scene_destroy(&hall->built);
    free(hall->tags);
    cJSON_Delete(hall->discrepancies);
    memset(hall, 0, sizeof *hall);
}
