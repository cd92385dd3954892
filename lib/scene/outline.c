/* Outline directions for corner masking (Park & Baek, OdSSAO): integrated
 * normal extrusion. A mesh's vertices are welded by position (CAD exports
 * split vertices at hard edges, and an outline built from split vertices
 * tears open at every edge); each welded vertex gets the average of the
 * distinct face normals around it (near-duplicates, e.g. the two triangles
 * of a quad, count once), so a box's outline is a closed, evenly thick
 * shell with continuous corners. */
#include "mr_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define OUTLINE_MAX_NORMALS 12 /* distinct face normals kept per welded vertex */

typedef struct weld_key {
    float p[3];
    uint32_t index;
} weld_key;

static int cmp_weld(const void *a, const void *b) {
    const weld_key *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x->p[i] != y->p[i]) return x->p[i] < y->p[i] ? -1 : 1;
    return 0;
}

bool mr_mesh_outline_dirs(const mr_mesh *m, float *out, mr_error *err) {
    uint32_t nv = m->vertex_count;
    memset(out, 0, (size_t)nv * 3 * sizeof *out);
    if (nv == 0) return true;
    weld_key *keys = malloc((size_t)nv * sizeof *keys);
    uint32_t *weld = malloc((size_t)nv * sizeof *weld);
    float *normals = calloc((size_t)nv * OUTLINE_MAX_NORMALS * 3, sizeof *normals);
    uint8_t *count = calloc(nv, 1);
    if (!keys || !weld || !normals || !count) {
        free(keys); free(weld); free(normals); free(count);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory building the outline of mesh %s", m->name);
    }
    for (uint32_t i = 0; i < nv; i++) {
        memcpy(keys[i].p, m->positions + 3 * (size_t)i, sizeof keys[i].p);
        keys[i].index = i;
    }
    qsort(keys, nv, sizeof *keys, cmp_weld);
    /* weld[i]: the representative (first in sorted order) of vertex i. */
    for (uint32_t i = 0; i < nv; i++) {
        uint32_t rep = (i > 0 && cmp_weld(&keys[i], &keys[i - 1]) == 0) ? weld[keys[i - 1].index] : keys[i].index;
        weld[keys[i].index] = rep;
    }
    for (uint32_t t = 0; t + 2 < m->index_count; t += 3) {
        const float *a = m->positions + 3 * (size_t)m->indices[t], *b = m->positions + 3 * (size_t)m->indices[t + 1],
                    *c = m->positions + 3 * (size_t)m->indices[t + 2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0) || !isfinite(l)) continue; /* degenerate triangle: no direction */
        float fn[3] = {(float)(n[0] / l), (float)(n[1] / l), (float)(n[2] / l)};
        for (int k = 0; k < 3; k++) {
            uint32_t w = weld[m->indices[t + k]];
            float *list = normals + (size_t)w * OUTLINE_MAX_NORMALS * 3;
            bool dup = false;
            for (int j = 0; j < count[w] && !dup; j++)
                dup = list[3 * j] * fn[0] + list[3 * j + 1] * fn[1] + list[3 * j + 2] * fn[2] > 0.999f;
            if (dup || count[w] >= OUTLINE_MAX_NORMALS) continue;
            memcpy(list + 3 * count[w], fn, sizeof fn);
            count[w]++;
        }
    }
    for (uint32_t i = 0; i < nv; i++) {
        uint32_t w = weld[i];
        const float *list = normals + (size_t)w * OUTLINE_MAX_NORMALS * 3;
        double s[3] = {0, 0, 0};
        for (int j = 0; j < count[w]; j++)
            for (int k = 0; k < 3; k++) s[k] += list[3 * j + k];
        double l = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        /* Opposite faces cancel (a zero-thickness sheet): fall back to the
         * vertex normal so the outline still has a thickness. */
        if (!(l > 1e-6) && m->normals) {
            for (int k = 0; k < 3; k++) s[k] = m->normals[3 * (size_t)i + k];
            l = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        }
        if (l > 1e-6 && isfinite(l))
            for (int k = 0; k < 3; k++) out[3 * (size_t)i + k] = (float)(s[k] / l);
    }
    free(keys); free(weld); free(normals); free(count);
    return true;
}
