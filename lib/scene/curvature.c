/* Per-vertex principal curvature of a triangle mesh, for the model-based
 * importance map of ghosted views (Kalkofen et al.: "strongly curved
 * portions of the occluder define its shape and should be more opaque"). */
#include "mr_scene.h"

#include <math.h>
#include <string.h>

/* |(n_j - n_i) . e| / |e|^2 for e = p_j - p_i: the normal curvature of the
 * surface along e (for a sphere of radius r it is exactly 1/r). */
static float edge_curvature(const float *p, const float *n, uint32_t i, uint32_t j) {
    double e[3], dn[3], len2 = 0, dot = 0;
    for (int k = 0; k < 3; k++) {
        e[k] = (double)p[j * 3 + k] - (double)p[i * 3 + k];
        dn[k] = (double)n[j * 3 + k] - (double)n[i * 3 + k];
        len2 += e[k] * e[k];
        dot += e[k] * dn[k];
    }
    /* Coincident vertices (a degenerate edge) say nothing about curvature. */
    if (!(len2 > 0) || !isfinite(len2)) return 0.0f;
    double k = fabs(dot) / len2;
    return isfinite(k) ? (float)k : 0.0f;
}

void mr_mesh_curvature(const mr_mesh *m, float *out) {
    if (!out) return;
    memset(out, 0, (size_t)m->vertex_count * sizeof *out);
    if (!m->positions || !m->normals || !m->indices) return;
    /* The maximum over a vertex's edges approximates |kappa_max|: the edges
     * sample the tangent directions around the vertex. */
    for (uint32_t t = 0; t + 2 < m->index_count; t += 3) {
        const uint32_t *v = &m->indices[t];
        for (int a = 0; a < 3; a++) {
            uint32_t i = v[a], j = v[(a + 1) % 3];
            if (i >= m->vertex_count || j >= m->vertex_count) continue;
            float k = edge_curvature(m->positions, m->normals, i, j);
            if (k > out[i]) out[i] = k;
            if (k > out[j]) out[j] = k;
        }
    }
}
