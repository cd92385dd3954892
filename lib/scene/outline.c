/* Outline volumes for corner masking (Park & Baek, OdSSAO).
 *
 * The paper extrudes every vertex along its integrated normal (the average
 * of the distinct face normals around it) "with an arbitrary extent". Taken
 * literally with the AO radius r as the extent, a box's faces move out only
 * r/sqrt 3 at a corner (the unit average of three orthogonal normals has a
 * component 1/sqrt 3 along each), so occluders between 0.58 r and r never
 * reach the mask and the masked image loses that occlusion. Here each vertex
 * moves by the shortest vector d with d . n >= 1 for every distinct face
 * normal n around it (a miter: (1,1,1) at a box corner, (1,1,0) on an edge,
 * n on a flat face), times r in the shader, so every face plane moves out by
 * at least r and the volume holds every point within r of a convex part of
 * the surface. d is still along the integrated normal's cone; only its
 * length (and at uneven corners its direction) differs.
 *
 * Vertices are welded by position first (CAD exports split vertices at hard
 * edges; an outline built from split vertices tears open at every edge), so
 * the moved mesh is closed wherever the mesh is.
 *
 * An open mesh (an edge used by one triangle: a sheet, a box without a lid)
 * has no inside to grow, and the paper asks for closed polyhedra. Its
 * outline is built as a shell: the mesh moved out along +d, a copy moved
 * along the miter of the reversed normals, and a wall along each boundary
 * edge; boundary vertices also move out across the edge (the edge's in-plane
 * outward normal joins their constraints), so the shell holds every point
 * within r of the sheet, both sides and past its rim. */
#include "mr_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define OUTLINE_MAX_NORMALS 16 /* distinct constraint normals kept per welded vertex */
#define OUTLINE_MITER_LIMIT 4.0 /* |d| cap: a face pair sharper than ~29 degrees */

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

typedef struct edge_key {
    uint32_t lo, hi; /* welded vertex ids, lo < hi */
    uint32_t tri, k; /* the triangle and its corner k: the edge runs k -> k+1 */
} edge_key;

static int cmp_edge(const void *a, const void *b) {
    const edge_key *x = a, *y = b;
    if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi) return x->hi < y->hi ? -1 : 1;
    return 0;
}

/* Distinct unit normals per welded vertex. */
typedef struct nset {
    float *n; /* OUTLINE_MAX_NORMALS * 3 per vertex */
    uint8_t *count;
} nset;

static void nset_add(nset *s, uint32_t w, const double v[3]) {
    float *list = s->n + (size_t)w * OUTLINE_MAX_NORMALS * 3;
    for (int j = 0; j < s->count[w]; j++)
        if (list[3 * j] * v[0] + list[3 * j + 1] * v[1] + list[3 * j + 2] * v[2] > 0.999) return;
    if (s->count[w] >= OUTLINE_MAX_NORMALS) return; /* the final check below still sees every face */
    for (int k = 0; k < 3; k++) list[3 * s->count[w] + k] = (float)v[k];
    s->count[w]++;
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Shortest d with sign * n . d >= 1 for the set's normals (and b . d >= 1
 * for the extra ones): Hildreth's dual coordinate ascent, then scaled up
 * so the least constraint holds exactly. Infeasible (opposite normals, a
 * zero-thickness fin) or sharper than the miter limit: capped. Returns
 * false when no direction satisfies all constraints. */
static bool miter(const float *list, int cnt, double sign, const float *extra, int ecnt, double d[3]) {
    double n[2 * OUTLINE_MAX_NORMALS][3], lam[2 * OUTLINE_MAX_NORMALS];
    int m = 0;
    for (int j = 0; j < cnt; j++, m++)
        for (int k = 0; k < 3; k++) n[m][k] = sign * list[3 * j + k];
    for (int j = 0; j < ecnt; j++, m++)
        for (int k = 0; k < 3; k++) n[m][k] = extra[3 * j + k];
    d[0] = d[1] = d[2] = 0;
    if (m == 0) return false;
    for (int j = 0; j < m; j++) lam[j] = 0;
    for (int it = 0; it < 500; it++) {
        double moved = 0;
        for (int j = 0; j < m; j++) {
            double nl = lam[j] + (1.0 - dot3(n[j], d));
            if (nl < 0) nl = 0;
            double dl = nl - lam[j];
            lam[j] = nl;
            for (int k = 0; k < 3; k++) d[k] += dl * n[j][k];
            moved += fabs(dl);
        }
        if (moved < 1e-10) break;
    }
    double least = 1e300;
    for (int j = 0; j < m; j++) least = fmin(least, dot3(n[j], d));
    double len = sqrt(dot3(d, d));
    if (!(least > 1e-3) || !isfinite(len)) return false;
    if (least < 1) {
        for (int k = 0; k < 3; k++) d[k] /= least;
        len /= least;
    }
    if (len > OUTLINE_MITER_LIMIT)
        for (int k = 0; k < 3; k++) d[k] *= OUTLINE_MITER_LIMIT / len;
    return true;
}

static bool face_normal(const mr_mesh *m, uint32_t t, double out[3]) {
    const float *a = m->positions + 3 * (size_t)m->indices[t], *b = m->positions + 3 * (size_t)m->indices[t + 1],
                *c = m->positions + 3 * (size_t)m->indices[t + 2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double l = sqrt(dot3(n, n));
    if (!(l > 0) || !isfinite(l)) return false; /* degenerate triangle: no direction */
    for (int k = 0; k < 3; k++) out[k] = n[k] / l;
    return true;
}

void mr_outline_free(mr_outline *o) {
    if (!o) return;
    free(o->positions);
    free(o->dirs);
    free(o->indices);
    memset(o, 0, sizeof *o);
}

bool mr_mesh_outline(const mr_mesh *m, mr_outline *o, mr_error *err) {
    memset(o, 0, sizeof *o);
    uint32_t nv = m->vertex_count, ni = m->index_count - m->index_count % 3;
    if (nv == 0 || ni == 0) return true;
    weld_key *keys = malloc((size_t)nv * sizeof *keys);
    uint32_t *weld = malloc((size_t)nv * sizeof *weld);
    edge_key *edges = malloc((size_t)ni * sizeof *edges);
    nset top = {calloc((size_t)nv * OUTLINE_MAX_NORMALS * 3, sizeof(float)), calloc(nv, 1)};
    nset rim = {calloc((size_t)nv * OUTLINE_MAX_NORMALS * 3, sizeof(float)), calloc(nv, 1)};
    double *dtop = calloc((size_t)nv * 3, sizeof *dtop), *dbot = calloc((size_t)nv * 3, sizeof *dbot);
    bool ok = keys && weld && edges && top.n && top.count && rim.n && rim.count && dtop && dbot;
    uint32_t boundary = 0;
    if (!ok) goto done;
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
    for (uint32_t t = 0; t < ni; t += 3) {
        double fn[3];
        bool good = face_normal(m, t, fn);
        for (int k = 0; k < 3; k++) {
            if (good) nset_add(&top, weld[m->indices[t + k]], fn);
            uint32_t a = weld[m->indices[t + k]], b = weld[m->indices[t + (k + 1) % 3]];
            edges[t + k] = (edge_key){a < b ? a : b, a < b ? b : a, t, (uint32_t)k};
        }
    }
    /* Boundary edges: used by one triangle. Their in-plane outward normal
     * joins the constraints of both ends. */
    qsort(edges, ni, sizeof *edges, cmp_edge);
    for (uint32_t e = 0; e < ni;) {
        uint32_t run = 1;
        while (e + run < ni && cmp_edge(&edges[e], &edges[e + run]) == 0) run++;
        if (run == 1 && edges[e].lo != edges[e].hi) {
            uint32_t t = edges[e].tri, k = edges[e].k;
            double fn[3];
            if (face_normal(m, t, fn)) {
                const float *pa = m->positions + 3 * (size_t)m->indices[t + k],
                            *pb = m->positions + 3 * (size_t)m->indices[t + (k + 1) % 3],
                            *pc = m->positions + 3 * (size_t)m->indices[t + (k + 2) % 3];
                double ed[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
                double b[3] = {ed[1] * fn[2] - ed[2] * fn[1], ed[2] * fn[0] - ed[0] * fn[2], ed[0] * fn[1] - ed[1] * fn[0]};
                double l = sqrt(dot3(b, b)), to_c[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
                if (l > 0 && isfinite(l)) {
                    double s = dot3(b, to_c) > 0 ? -1.0 / l : 1.0 / l;
                    for (int q = 0; q < 3; q++) b[q] *= s;
                    nset_add(&rim, edges[e].lo, b);
                    nset_add(&rim, edges[e].hi, b);
                }
            }
            boundary++;
        }
        e += run;
    }
    for (uint32_t i = 0; i < nv; i++) {
        if (weld[i] != i) continue;
        const float *tl = top.n + (size_t)i * OUTLINE_MAX_NORMALS * 3, *rl = rim.n + (size_t)i * OUTLINE_MAX_NORMALS * 3;
        if (!miter(tl, top.count[i], 1.0, rl, rim.count[i], dtop + 3 * (size_t)i) && m->normals)
            for (int k = 0; k < 3; k++) dtop[3 * (size_t)i + k] = m->normals[3 * (size_t)i + k]; /* a fin: the vertex normal */
        if (boundary && !miter(tl, top.count[i], -1.0, rl, rim.count[i], dbot + 3 * (size_t)i))
            for (int k = 0; k < 3; k++) dbot[3 * (size_t)i + k] = -dtop[3 * (size_t)i + k];
    }
    /* Faces beyond the OUTLINE_MAX_NORMALS kept per vertex: grow d until
     * it clears every face plane around the vertex too. */
    for (uint32_t t = 0; t < ni; t += 3) {
        double fn[3];
        if (!face_normal(m, t, fn)) continue;
        for (int k = 0; k < 3; k++) {
            double *d = dtop + 3 * (size_t)weld[m->indices[t + k]];
            double c = dot3(d, fn), len = sqrt(dot3(d, d));
            if (c > 1e-3 && c < 1 && len / c <= OUTLINE_MITER_LIMIT)
                for (int q = 0; q < 3; q++) d[q] /= c;
        }
    }
    o->open = boundary > 0;
    o->vertex_count = o->open ? 2 * nv : nv;
    o->index_count = o->open ? 2 * ni + 6 * boundary : ni;
    o->positions = malloc((size_t)o->vertex_count * 3 * sizeof *o->positions);
    o->dirs = malloc((size_t)o->vertex_count * 3 * sizeof *o->dirs);
    o->indices = malloc((size_t)o->index_count * sizeof *o->indices);
    if (!o->positions || !o->dirs || !o->indices) {
        ok = false;
        goto done;
    }
    for (uint32_t c = 0; c < (o->open ? 2u : 1u); c++)
        for (uint32_t i = 0; i < nv; i++) {
            const double *d = (c ? dbot : dtop) + 3 * (size_t)weld[i];
            for (int k = 0; k < 3; k++) {
                o->positions[3 * ((size_t)c * nv + i) + k] = m->positions[3 * (size_t)i + k];
                o->dirs[3 * ((size_t)c * nv + i) + k] = (float)d[k];
            }
        }
    memcpy(o->indices, m->indices, (size_t)ni * sizeof *o->indices);
    if (o->open) {
        uint32_t *w = o->indices + ni;
        for (uint32_t t = 0; t < ni; t += 3) { /* the second copy, wound the other way */
            *w++ = nv + m->indices[t];
            *w++ = nv + m->indices[t + 2];
            *w++ = nv + m->indices[t + 1];
        }
        for (uint32_t e = 0; e < ni;) { /* a wall along each boundary edge */
            uint32_t run = 1;
            while (e + run < ni && cmp_edge(&edges[e], &edges[e + run]) == 0) run++;
            if (run == 1 && edges[e].lo != edges[e].hi) {
                uint32_t t = edges[e].tri, k = edges[e].k;
                uint32_t a = m->indices[t + k], b = m->indices[t + (k + 1) % 3];
                uint32_t q[6] = {b, a, nv + a, b, nv + a, nv + b};
                memcpy(w, q, sizeof q);
                w += 6;
            }
            e += run;
        }
        o->index_count = (uint32_t)(w - o->indices);
    }
done:
    free(keys); free(weld); free(edges); free(top.n); free(top.count); free(rim.n); free(rim.count);
    free(dtop); free(dbot);
    if (!ok) {
        mr_outline_free(o);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory building the outline of mesh %s", m->name);
    }
    return true;
}
