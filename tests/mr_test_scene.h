/* mr_test_scene.h — small scene builders shared by the rendering tests:
 * boxes, quads and nodes added to an mr_scene (include after mr_test.h). */
#ifndef MR_TEST_SCENE_H
#define MR_TEST_SCENE_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mr_scene.h"

/* An axis-aligned box sx x sy x sz centred on its node origin, 24 vertices
 * (split at the edges, as CAD exports come); material may be -1. */
static inline int32_t mr_test_add_box(mr_scene *s, double sx, double sy, double sz, int32_t material) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "box");
    m.vertex_count = 24;
    m.index_count = 36;
    m.positions = malloc(72 * sizeof(float));
    m.indices = malloc(36 * sizeof(uint32_t));
    static const int faces[6][4][3] = {
        {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}},     {{-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}, {-1, -1, -1}},
        {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}},     {{-1, -1, 1}, {-1, -1, -1}, {1, -1, -1}, {1, -1, 1}},
        {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}},     {{1, -1, -1}, {-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}},
    };
    for (int f = 0; f < 6; f++) {
        for (int v = 0; v < 4; v++) {
            m.positions[(f * 4 + v) * 3 + 0] = (float)(faces[f][v][0] * sx / 2);
            m.positions[(f * 4 + v) * 3 + 1] = (float)(faces[f][v][1] * sy / 2);
            m.positions[(f * 4 + v) * 3 + 2] = (float)(faces[f][v][2] * sz / 2);
        }
        const uint32_t q[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++) m.indices[f * 6 + k] = (uint32_t)(f * 4) + q[k];
    }
    m.material = material;
    mr_error err = {0};
    int32_t id = mr_scene_add_mesh(s, &m, &err);
    CHECK_MSG(id >= 0, "%s", err.msg);
    return id;
}

/* A quad sx x sy in its node's z = 0 plane, with uvs (0,0)..(1,1) if asked. */
static inline int32_t mr_test_add_quad(mr_scene *s, double sx, double sy, int32_t material, bool uvs) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "quad");
    m.vertex_count = 4;
    m.index_count = 6;
    m.positions = malloc(12 * sizeof(float));
    m.indices = malloc(6 * sizeof(uint32_t));
    const float p[12] = {(float)(-sx / 2), (float)(-sy / 2), 0, (float)(sx / 2), (float)(-sy / 2), 0,
                         (float)(sx / 2),  (float)(sy / 2),  0, (float)(-sx / 2), (float)(sy / 2), 0};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    memcpy(m.positions, p, sizeof p);
    memcpy(m.indices, idx, sizeof idx);
    if (uvs) {
        m.uvs = malloc(8 * sizeof(float));
        const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
        memcpy(m.uvs, uv, sizeof uv);
    }
    m.material = material;
    mr_error err = {0};
    int32_t id = mr_scene_add_mesh(s, &m, &err);
    CHECK_MSG(id >= 0, "%s", err.msg);
    return id;
}

/* A root node drawing one mesh. */
static inline void mr_test_add_node(mr_scene *s, const char *name, mr_dmat4 world, int32_t mesh, uint8_t layer) {
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "%s", name);
    n.parent = -1;
    n.world = world;
    n.mesh_first = mesh;
    n.mesh_count = 1;
    n.layer = layer;
    mr_scene_add_node(s, &n);
}

/* A closed UV sphere of nu * nv * 2 triangles, radius r * (1 + bump *
 * sin(fu * phi) * sin(fv * theta)) (bump 0: a plain sphere; bumps make
 * every cluster and LOD level differ), named name ("" none). */
static inline mr_mesh mr_test_sphere_mesh(const char *name, double r, int nu, int nv, double bump, int fu, int fv) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    m.vertex_count = (uint32_t)((nu + 1) * (nv + 1));
    m.index_count = (uint32_t)(nu * nv * 6);
    m.positions = malloc((size_t)m.vertex_count * 12);
    m.indices = malloc((size_t)m.index_count * 4);
    for (int i = 0; i <= nu; i++)
        for (int j = 0; j <= nv; j++) {
            double th = 3.14159265358979 * j / nv, ph = 2 * 3.14159265358979 * (i % nu) / nu;
            double rr = r * (1 + bump * sin(fu * ph) * sin(fv * th));
            float *p = m.positions + 3 * (size_t)(i * (nv + 1) + j);
            p[0] = (float)(rr * sin(th) * cos(ph));
            p[1] = (float)(rr * cos(th));
            p[2] = (float)(rr * sin(th) * sin(ph));
        }
    uint32_t ni = 0;
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            uint32_t a = (uint32_t)(i * (nv + 1) + j), b = a + (uint32_t)(nv + 1);
            uint32_t q[6] = {a, b, a + 1, a + 1, b, b + 1};
            for (int k = 0; k < 6; k++) m.indices[ni++] = q[k];
        }
    m.material = -1;
    return m;
}

/* count root nodes "part_<i>" on a 400 x 5 x ... grid 0.5 apart, drawing
 * meshes 0 .. meshes-1 in turn, every 50th on the hidden layer: a big
 * assembly's node list. */
static inline void mr_test_add_grid_nodes(mr_scene *s, int count, int meshes) {
    for (int i = 0; i < count; i++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "part_%d", i);
        n.parent = -1;
        n.world = mr_m4_translate((i % 400) * 0.5, (i / 400 % 5) * 0.5, (i / 2000) * 0.5);
        n.mesh_first = i % meshes;
        n.mesh_count = 1;
        n.layer = i % 50 == 0 ? MR_LAYER_HIDDEN : MR_LAYER_VISIBLE;
        mr_scene_add_node(s, &n);
    }
}

#endif
