/* Levels of detail with a certified error bound, and their disk cache.
 *
 * meshoptimizer simplifies each mesh once (edge collapses onto existing
 * vertices, so every level indexes the mesh's own vertex arrays). Its
 * result_error is an estimate from quadrics, not a bound, so a level's error
 * here is measured: an upper bound of the two-sided Hausdorff distance
 * between the level and the full mesh, found by branch and bound:
 *
 *  - every vertex of each surface is queried exactly against the other
 *    surface (a uniform grid of triangles, exact point-triangle distance;
 *    a vertex the other surface uses is on it); the largest distance L is a
 *    lower bound of the Hausdorff distance;
 *  - a triangle T is then bounded without sampling: the distance to one
 *    triangle t is a convex function, so over all of T it is at most the
 *    largest distance of T's corners to t; likewise for any convex region
 *    near the other surface, plus how far that region is from it: a
 *    neighbour folded flat about the shared edge (hinge), a planar fan, the
 *    1-ring of a vertex projected onto its plane (curved surfaces). The
 *    smallest of these over a few candidates (the corners' nearest
 *    triangles) bounds T; so does a projected patch (the other surface's
 *    triangles under T, projected onto T's plane, proven to cover T from
 *    their border edges: the distance is at most their height over T),
 *    the bound that handles chords of curved surfaces and re-triangulated
 *    regions in one piece. Only where it exceeds what is enough (the level's
 *    error budget, or L + a quarter) is T split (in four if thin, else
 *    across its longest edge) and the pieces bounded again.
 *
 * Levels are chained: each is certified against the one it was simplified
 * from and the errors add (triangle inequality), so the work per level is
 * the size of its source. The result is a true upper bound, which tests
 * check against dense brute-force sampling; the renderer never uses a level
 * whose bound (times the node's stretch) exceeds the tolerance. */
#include "mr_scene.h"
#include "lod_internal.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <meshoptimizer.h>

/* ------------------------------------------------------- distance math */

typedef struct dv { double x, y, z; } dv;

/* max and min without libm's calls (fmax is a call at -O2: it must treat
 * NaN specially; every value here is finite or +-INFINITY, positions
 * being checked finite on load). */
static inline double dmax(double a, double b) { return a > b ? a : b; }
static inline double dmin(double a, double b) { return a < b ? a : b; }

static dv dv_sub(dv a, dv b) { return (dv){a.x - b.x, a.y - b.y, a.z - b.z}; }
static double dv_dot(dv a, dv b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static dv dv_mad(dv a, dv b, double s) { return (dv){a.x + b.x * s, a.y + b.y * s, a.z + b.z * s}; }

/* Squared distance from p to triangle abc (Ericson, Real-Time Collision
 * Detection 5.1.5), in double; degenerate triangles fall back to edges. */
static double dist2_point_tri(dv p, dv a, dv b, dv c) {
    dv ab = dv_sub(b, a), ac = dv_sub(c, a), ap = dv_sub(p, a);
    double d1 = dv_dot(ab, ap), d2 = dv_dot(ac, ap);
    dv q;
    if (d1 <= 0 && d2 <= 0) q = a;
    else {
        dv bp = dv_sub(p, b);
        double d3 = dv_dot(ab, bp), d4 = dv_dot(ac, bp);
        if (d3 >= 0 && d4 <= d3) q = b;
        else {
            double vc = d1 * d4 - d3 * d2;
            if (vc <= 0 && d1 >= 0 && d3 <= 0) q = dv_mad(a, ab, d1 / (d1 - d3));
            else {
                dv cp = dv_sub(p, c);
                double d5 = dv_dot(ab, cp), d6 = dv_dot(ac, cp);
                if (d6 >= 0 && d5 <= d6) q = c;
                else {
                    double vb = d5 * d2 - d1 * d6;
                    if (vb <= 0 && d2 >= 0 && d6 <= 0) q = dv_mad(a, ac, d2 / (d2 - d6));
                    else {
                        double va = d3 * d6 - d5 * d4;
                        if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
                            dv bc = dv_sub(c, b);
                            q = dv_mad(b, bc, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
                        } else {
                            double den = va + vb + vc;
                            if (!(fabs(den) > 0) || !isfinite(1.0 / den)) {
                                /* Degenerate (collinear): nearest of the edges. */
                                double best = INFINITY;
                                const dv e0[3] = {a, b, c}, e1[3] = {b, c, a};
                                for (int k = 0; k < 3; k++) {
                                    dv d = dv_sub(e1[k], e0[k]);
                                    double dd = dv_dot(d, d), t = dd > 0 ? dv_dot(dv_sub(p, e0[k]), d) / dd : 0;
                                    t = t < 0 ? 0 : t > 1 ? 1 : t;
                                    dv r = dv_sub(p, dv_mad(e0[k], d, t));
                                    double r2 = dv_dot(r, r);
                                    if (r2 < best) best = r2;
                                }
                                return best;
                            }
                            double v = vb / den, w = vc / den;
                            q = dv_mad(dv_mad(a, ab, v), ac, w);
                        }
                    }
                }
            }
        }
    }
    dv d = dv_sub(p, q);
    return dv_dot(d, d);
}

/* A uniform grid over the triangles of one surface. */
typedef struct tri_grid {
    const double *pos; /* positions as doubles: a copy made once per mesh,
                          so no lookup converts (4 % of the build's
                          instructions went to float loads) */
    const uint32_t *idx;
    uint32_t tri_count;
    double lo[3], cell, inv_cell; /* (a product, not a quotient, per cell lookup) */
    int n[3];
    uint32_t *start;   /* n0*n1*n2 + 1 offsets into items */
    uint32_t *items;   /* triangle ids */
    uint32_t *partner; /* 3 per triangle: across each manifold edge the
                          other triangle's far corner, until partner_get
                          finds the pair not convex and flat (then, and for
                          borders, UINT32_MAX) */
    double ptol;       /* coplanarity tolerance used for partner */
    /* Hinges: per triangle edge with a partner, the partner's opposite
     * corner rotated about the shared edge into this triangle's plane
     * (hinge_p) and how far that moved it (hinge_s): see convex_partners. */
    double *hinge_p, *hinge_s;
    /* Curved fans (see ring_bound), prepared on first use per vertex:
     * ring_n the plane's unit normal, ring_s the slack (INFINITY: no claim,
     * NAN: not prepared yet). */
    double *ring_n, *ring_s;
    uint32_t *vt_start, *vt_items; /* triangles around each vertex (CSR) */
    /* Cheap lower bounds that let a bound which cannot hold be skipped
     * before its point-triangle distances are computed: vrad, per vertex,
     * the largest distance from it to a corner of a triangle around it (the
     * fan and 1-ring lie within that ball); tsph, per triangle, a centre
     * and radius of a ball holding it, and the length of its edges' cross
     * product (twice its area). */
    double *vrad, *tsph;
    /* Planar fans (fan_bound), the last one per vertex: fan_ref the
     * triangle whose plane chose it (UINT32_MAX: none yet), fan_mask which
     * of the vertex's triangles (vt_items order) lie in that plane,
     * fan_slack its slack (INFINITY: no claim). */
    uint32_t *fan_ref;
    uint16_t *fan_mask;
    double *fan_slack;
    /* Projected patches (patch_bound): nbr, 3 per triangle, the triangle
     * across each edge where exactly two share it and run it in opposite
     * directions (else UINT32_MAX: the edge is a border); mark, per
     * triangle, 2 * stamp (+1 if in the patch) of the last patch that
     * looked at it. */
    uint32_t *nbr, *mark, stamp;
    /* pmark, per vertex, the stamp of the last patch that projected it,
     * and pxy its projection there (in-plane x, y and height): a patch's
     * triangles share their corners. */
    uint32_t *pmark;
    double *pxy;
    /* Nearest queries (grid_nearest): qmark, per triangle, the last query
     * that computed its distance (a long triangle sits in many cells). */
    uint32_t *qmark, qstamp;
    /* tpl, per triangle, its unit normal and offset (n.a): the distance to
     * the plane is a lower bound of the distance to the triangle, so most
     * of a cell's triangles are passed over without the full distance. */
    double *tpl;
    double mag; /* largest |coordinate| of the grid's box */
} tri_grid;

static dv vtx(const double *pos, uint32_t i) {
    return (dv){pos[3 * (size_t)i], pos[3 * (size_t)i + 1], pos[3 * (size_t)i + 2]};
}
static dv vtxf(const float *pos, uint32_t i) {
    return (dv){pos[3 * (size_t)i], pos[3 * (size_t)i + 1], pos[3 * (size_t)i + 2]};
}

static inline void cell_of(const tri_grid *g, dv p, int c[3]) {
    const double q[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; k++) {
        double f = floor((q[k] - g->lo[k]) * g->inv_cell);
        c[k] = f < 0 ? 0 : f >= g->n[k] ? g->n[k] - 1 : (int)f;
    }
}

static void grid_free(tri_grid *g) {
    free(g->start);
    free(g->items);
    free(g->partner);
    free(g->hinge_p);
    free(g->hinge_s);
    free(g->ring_n);
    free(g->ring_s);
    free(g->vt_start);
    free(g->vt_items);
    free(g->vrad);
    free(g->tsph);
    free(g->fan_ref);
    free(g->fan_mask);
    free(g->fan_slack);
    free(g->nbr);
    free(g->mark);
    free(g->pmark);
    free(g->pxy);
    free(g->qmark);
    free(g->tpl);
    memset(g, 0, sizeof *g);
}

/* bounds: of all vertices (both surfaces share them), so every query point
 * lies inside the grid's box. */
static bool grid_build(tri_grid *g, const double *pos, const uint32_t *idx, uint32_t index_count, const double lo[3],
                       const double hi[3]) {
    memset(g, 0, sizeof *g);
    g->pos = pos;
    g->idx = idx;
    g->tri_count = index_count / 3;
    double ext = dmax(hi[0] - lo[0], dmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (!(ext > 0)) ext = 1;
    /* A few cells per triangle (most are empty: surfaces are thin), at most
     * 128 per axis. */
    double per_axis = cbrt((double)g->tri_count + 1) * 1.6;
    if (per_axis > 128) per_axis = 128;
    if (per_axis < 1) per_axis = 1;
    g->cell = ext / per_axis * 1.0000001;
    g->inv_cell = 1 / g->cell;
    for (int k = 0; k < 3; k++) {
        g->mag = dmax(g->mag, dmax(fabs(lo[k]), fabs(hi[k])));
        g->lo[k] = lo[k];
        g->n[k] = (int)ceil((hi[k] - lo[k]) / g->cell);
        if (g->n[k] < 1) g->n[k] = 1;
    }
    size_t cells = (size_t)g->n[0] * g->n[1] * g->n[2];
    g->start = calloc(cells + 1, sizeof *g->start);
    g->qmark = calloc((size_t)g->tri_count + 1, sizeof *g->qmark);
    if (!g->start || !g->qmark) return false;
    /* Two passes: count, then fill (triangle AABB against cells). The
     * first keeps each triangle's range of cells (at most 128 per axis:
     * bytes), so the second reads no positions. */
    uint8_t *box = malloc((size_t)g->tri_count * 6 + 1);
    if (!box) return false;
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t t = 0; t < g->tri_count; t++) {
            uint8_t *bx = box + 6 * (size_t)t;
            if (pass == 0) {
                dv a = vtx(pos, idx[3 * t]), b = vtx(pos, idx[3 * t + 1]), c = vtx(pos, idx[3 * t + 2]);
                dv mn = {dmin(a.x, dmin(b.x, c.x)), dmin(a.y, dmin(b.y, c.y)), dmin(a.z, dmin(b.z, c.z))};
                dv mx = {dmax(a.x, dmax(b.x, c.x)), dmax(a.y, dmax(b.y, c.y)), dmax(a.z, dmax(b.z, c.z))};
                int c0[3], c1[3];
                cell_of(g, mn, c0);
                cell_of(g, mx, c1);
                for (int k = 0; k < 3; k++) {
                    bx[k] = (uint8_t)c0[k];
                    bx[3 + k] = (uint8_t)c1[k];
                }
            }
            for (int z = bx[2]; z <= bx[5]; z++)
                for (int y = bx[1]; y <= bx[4]; y++)
                    for (int x = bx[0]; x <= bx[3]; x++) {
                        size_t ci = ((size_t)z * g->n[1] + y) * g->n[0] + x;
                        if (pass == 0) g->start[ci + 1]++;
                        else g->items[g->start[ci]++] = t;
                    }
        }
        if (pass == 0) {
            for (size_t i = 0; i < cells; i++) g->start[i + 1] += g->start[i];
            g->items = malloc(((size_t)g->start[cells] + 1) * sizeof *g->items);
            if (!g->items) {
                free(box);
                return false;
            }
        } else {
            /* start[i] now holds the end of cell i: shift back. */
            for (size_t i = cells; i > 0; i--) g->start[i] = g->start[i - 1];
            g->start[0] = 0;
        }
    }
    free(box);
    return true;
}

typedef struct edge_rec { uint32_t a, b, tri, slot; } edge_rec;

static int cmp_edge(const void *x, const void *y) {
    const edge_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    if (p->tri != q->tri) return p->tri < q->tri ? -1 : 1;
    return p->slot < q->slot ? -1 : p->slot > q->slot;
}

/* Two triangles sharing edge ab with opposite corners c and d form a convex
 * planar quad iff they are coplanar and segment cd crosses ab: then the
 * distance to their union is convex too, and a piece straddling their
 * common edge needs no subdivision (planar faces split into triangles are
 * the common case in CAD meshes). */
static bool convex_pair(dv a, dv b, dv c, dv d, double tol) {
    dv ab = dv_sub(b, a), ac = dv_sub(c, a), ad = dv_sub(d, a);
    dv n = {ab.y * ac.z - ab.z * ac.y, ab.z * ac.x - ab.x * ac.z, ab.x * ac.y - ab.y * ac.x};
    double nl = sqrt(dv_dot(n, n));
    if (!(nl > 0)) return false;
    if (fabs(dv_dot(ad, n)) / nl > tol) return false; /* not coplanar */
    /* c and d on opposite sides of ab, a and b on opposite sides of cd. */
    dv x1 = {ab.y * ad.z - ab.z * ad.y, ab.z * ad.x - ab.x * ad.z, ab.x * ad.y - ab.y * ad.x};
    if (dv_dot(x1, n) >= 0) return false;
    dv cd = dv_sub(d, c), ca = dv_sub(a, c), cb = dv_sub(b, c);
    dv y1 = {cd.y * ca.z - cd.z * ca.y, cd.z * ca.x - cd.x * ca.z, cd.x * ca.y - cd.y * ca.x};
    dv y2 = {cd.y * cb.z - cd.z * cb.y, cd.z * cb.x - cd.x * cb.z, cd.x * cb.y - cd.y * cb.x};
    return dv_dot(y1, y2) <= 0;
}

/* Folds `far` (the opposite corner of the triangle across edge ab) about
 * the line ab into the plane of (a, b, own), on the side away from own:
 * *f, and how far it moved (*moved). Every point of the far triangle moves
 * at most that much under the fold (linearly with its distance from ab), so
 * the distance to the real pair is at most the distance to the flat pair
 * (convex if the flat quad is) + moved. A curved surface tessellated finely
 * has small folds: pieces straddling its edges need no subdivision. */
static bool hinge_fold(dv a, dv b, dv own, dv far, dv *f, double *moved) {
    dv ab = dv_sub(b, a);
    double l2 = dv_dot(ab, ab);
    if (!(l2 > 0)) return false;
    dv e = {ab.x / sqrt(l2), ab.y / sqrt(l2), ab.z / sqrt(l2)};
    dv wc = dv_sub(own, a);
    wc = dv_mad(wc, e, -dv_dot(wc, e));
    double wl = sqrt(dv_dot(wc, wc));
    dv wd = dv_sub(far, a);
    double along = dv_dot(wd, e);
    wd = dv_mad(wd, e, -along);
    double h = sqrt(dv_dot(wd, wd));
    if (!(wl > 0) || !(h > 0)) return false;
    *f = dv_mad(dv_mad(a, e, along), wc, -h / wl);
    dv mv = dv_sub(far, *f);
    *moved = sqrt(dv_dot(mv, mv));
    return isfinite(*moved);
}

static bool convex_partners(tri_grid *g, double tol, uint32_t vertex_count) {
    g->ptol = tol;
    /* Triangles around each vertex, for fan bounds. */
    g->vt_start = calloc((size_t)vertex_count + 2, sizeof *g->vt_start);
    g->vt_items = malloc(((size_t)g->tri_count * 3 + 1) * sizeof *g->vt_items);
    g->ring_n = malloc(((size_t)vertex_count * 3 + 1) * sizeof *g->ring_n);
    g->ring_s = malloc(((size_t)vertex_count + 1) * sizeof *g->ring_s);
    g->vrad = calloc((size_t)vertex_count + 1, sizeof *g->vrad);
    g->tsph = malloc(((size_t)g->tri_count * 5 + 1) * sizeof *g->tsph);
    g->tpl = malloc(((size_t)g->tri_count * 4 + 1) * sizeof *g->tpl);
    g->fan_ref = malloc(((size_t)vertex_count + 1) * sizeof *g->fan_ref);
    g->fan_mask = malloc(((size_t)vertex_count + 1) * sizeof *g->fan_mask);
    g->fan_slack = malloc(((size_t)vertex_count + 1) * sizeof *g->fan_slack);
    if (!g->vt_start || !g->vt_items || !g->ring_n || !g->ring_s || !g->vrad || !g->tsph || !g->tpl || !g->fan_ref ||
        !g->fan_mask || !g->fan_slack)
        return false;
    for (uint32_t v = 0; v < vertex_count; v++) {
        g->ring_s[v] = NAN;
        g->fan_ref[v] = UINT32_MAX;
    }
    for (size_t i = 0; i < (size_t)g->tri_count * 3; i++) g->vt_start[g->idx[i] + 2]++;
    for (uint32_t v = 0; v < vertex_count; v++) g->vt_start[v + 2] += g->vt_start[v + 1];
    for (size_t i = 0; i < (size_t)g->tri_count * 3; i++) g->vt_items[g->vt_start[g->idx[i] + 1]++] = (uint32_t)(i / 3);
    for (uint32_t t = 0; t < g->tri_count; t++) {
        dv p[3];
        for (int j = 0; j < 3; j++) p[j] = vtx(g->pos, g->idx[3 * (size_t)t + (size_t)j]);
        /* Centroid ball; 1 + 1e-9 and + ptol so rounding never makes it
         * smaller than the triangle (it only ever skips a bound that would
         * have failed). */
        dv ctr = {(p[0].x + p[1].x + p[2].x) / 3, (p[0].y + p[1].y + p[2].y) / 3, (p[0].z + p[1].z + p[2].z) / 3};
        /* (Squares here, vrad's roots below: a root per vertex, not
         * nine per triangle.) */
        double r2 = 0, e2[3];
        for (int j = 0; j < 3; j++) {
            dv d = dv_sub(p[j], ctr), e = dv_sub(p[(j + 1) % 3], p[j]);
            r2 = dmax(r2, dv_dot(d, d));
            e2[j] = dv_dot(e, e); /* edge j: corners j, j + 1 */
        }
        for (int j = 0; j < 3; j++) {
            uint32_t v = g->idx[3 * (size_t)t + (size_t)j];
            g->vrad[v] = dmax(g->vrad[v], dmax(e2[j], e2[(j + 2) % 3]));
        }
        double r = sqrt(r2);
        double *sp = g->tsph + 5 * (size_t)t;
        sp[0] = ctr.x;
        sp[1] = ctr.y;
        sp[2] = ctr.z;
        sp[3] = r * (1 + 1e-9) + tol;
        dv f1 = dv_sub(p[1], p[0]), f2 = dv_sub(p[2], p[0]);
        dv fn = {f1.y * f2.z - f1.z * f2.y, f1.z * f2.x - f1.x * f2.z, f1.x * f2.y - f1.y * f2.x};
        sp[4] = sqrt(dv_dot(fn, fn));
        double *pl = g->tpl + 4 * (size_t)t;
        if (sp[4] > 0 && isfinite(1 / sp[4])) {
            pl[0] = fn.x / sp[4];
            pl[1] = fn.y / sp[4];
            pl[2] = fn.z / sp[4];
            pl[3] = pl[0] * p[0].x + pl[1] * p[0].y + pl[2] * p[0].z;
        } else {
            pl[0] = pl[1] = pl[2] = pl[3] = 0; /* degenerate: never passed over */
        }
    }
    for (uint32_t v = 0; v < vertex_count; v++) g->vrad[v] = sqrt(g->vrad[v]) * (1 + 1e-9) + tol;
    size_t ne = (size_t)g->tri_count * 3;
    g->partner = malloc((ne + 1) * sizeof *g->partner);
    g->nbr = malloc((ne + 1) * sizeof *g->nbr);
    g->mark = calloc((size_t)g->tri_count + 1, sizeof *g->mark);
    g->pmark = calloc((size_t)vertex_count + 1, sizeof *g->pmark);
    g->pxy = malloc(((size_t)vertex_count * 3 + 1) * sizeof *g->pxy);
    g->stamp = 0;
    g->hinge_p = malloc((ne * 3 + 1) * sizeof *g->hinge_p);
    g->hinge_s = malloc((ne + 1) * sizeof *g->hinge_s);
    edge_rec *e = malloc((ne + 1) * sizeof *e);
    if (!g->partner || !g->hinge_p || !g->hinge_s || !e || !g->nbr || !g->mark || !g->pmark || !g->pxy) {
        free(e);
        return false;
    }
    for (size_t i = 0; i < ne; i++) {
        uint32_t t = (uint32_t)(i / 3), k = (uint32_t)(i % 3);
        uint32_t a = g->idx[3 * t + k], b = g->idx[3 * t + (k + 1) % 3];
        e[i] = (edge_rec){a < b ? a : b, a < b ? b : a, t, k};
        g->partner[i] = UINT32_MAX;
        g->nbr[i] = UINT32_MAX;
    }
    /* Sorted by (a, b): a counting sort on a (edges per vertex are few),
     * then insertion sort within each vertex's run; 3-4x faster than qsort
     * here, and deterministic (ties by triangle and slot). */
    {
        uint32_t *cnt = calloc((size_t)vertex_count + 2, sizeof *cnt);
        edge_rec *tmp = malloc((ne + 1) * sizeof *tmp);
        if (!cnt || !tmp) {
            free(cnt);
            free(tmp);
            free(e);
            return false;
        }
        for (size_t i = 0; i < ne; i++) cnt[e[i].a + 1]++;
        for (uint32_t v = 0; v < vertex_count; v++) cnt[v + 1] += cnt[v];
        for (size_t i = 0; i < ne; i++) tmp[cnt[e[i].a]++] = e[i]; /* cnt[v] ends at run v's end */
        for (size_t lo = 0, v = 0; v < vertex_count; v++) {
            size_t hi = cnt[v];
            if (hi - lo > 32) { /* a hub (a cap's centre): no quadratic sort */
                qsort(tmp + lo, hi - lo, sizeof *tmp, cmp_edge);
                lo = hi;
                continue;
            }
            for (size_t i = lo + 1; i < hi; i++) {
                edge_rec x = tmp[i];
                size_t k = i;
                while (k > lo && (tmp[k - 1].b > x.b || (tmp[k - 1].b == x.b && (tmp[k - 1].tri > x.tri ||
                                                                                   (tmp[k - 1].tri == x.tri && tmp[k - 1].slot > x.slot))))) {
                    tmp[k] = tmp[k - 1];
                    k--;
                }
                tmp[k] = x;
            }
            lo = hi;
        }
        memcpy(e, tmp, ne * sizeof *e);
        free(tmp);
        free(cnt);
    }
    for (size_t i = 0, j; i < ne; i = j) {
        for (j = i + 1; j < ne && e[j].a == e[i].a && e[j].b == e[i].b;) j++;
        if (j - i != 2) continue; /* a border, or non-manifold */
        bool fwd0 = g->idx[3 * (size_t)e[i].tri + e[i].slot] == e[i].a;
        bool fwd1 = g->idx[3 * (size_t)e[i + 1].tri + e[i + 1].slot] == e[i + 1].a;
        if (fwd0 == fwd1 || e[i].tri == e[i + 1].tri) continue; /* inconsistently oriented: a border too */
        g->nbr[3 * (size_t)e[i].tri + e[i].slot] = e[i + 1].tri;
        g->nbr[3 * (size_t)e[i + 1].tri + e[i + 1].slot] = e[i].tri;
    }
    /* Hinges are folded on first use (partner_get): most edges never are
     * asked. Until then partner holds the far corner (the other
     * triangle's opposite vertex) and hinge_s is NAN. */
    for (size_t i = 0, j; i < ne; i = j) {
        for (j = i + 1; j < ne && e[j].a == e[i].a && e[j].b == e[i].b;) j++;
        if (j - i != 2) continue; /* a border, or non-manifold */
        uint32_t t1 = e[i].tri, t2 = e[i + 1].tri;
        uint32_t c = g->idx[3 * (size_t)t1 + (e[i].slot + 2) % 3], d = g->idx[3 * (size_t)t2 + (e[i + 1].slot + 2) % 3];
        g->partner[3 * (size_t)t1 + e[i].slot] = d;
        g->hinge_s[3 * (size_t)t1 + e[i].slot] = NAN;
        g->partner[3 * (size_t)t2 + e[i + 1].slot] = c;
        g->hinge_s[3 * (size_t)t2 + e[i + 1].slot] = NAN;
    }
    free(e);
    return true;
}

/* The hinge of edge h (triangle h / 3, edge h % 3): the other triangle's
 * corner folded flat onto this one's plane, if the flat pair is convex
 * (see hinge_fold, convex_pair); false if there is none. */
static bool partner_get(const tri_grid *og, size_t h) {
    tri_grid *g = (tri_grid *)og; /* folded lazily: scratch */
    if (g->partner[h] == UINT32_MAX) return false;
    if (!isnan(g->hinge_s[h])) return true;
    size_t t = h / 3, slot = h % 3;
    dv pa = vtx(g->pos, g->idx[3 * t + slot]), pb = vtx(g->pos, g->idx[3 * t + (slot + 1) % 3]);
    dv own = vtx(g->pos, g->idx[3 * t + (slot + 2) % 3]), far = vtx(g->pos, g->partner[h]);
    dv f;
    double moved;
    if (!hinge_fold(pa, pb, own, far, &f, &moved) || !convex_pair(pa, pb, own, f, g->ptol)) {
        g->partner[h] = UINT32_MAX;
        return false;
    }
    g->hinge_p[3 * h] = f.x;
    g->hinge_p[3 * h + 1] = f.y;
    g->hinge_p[3 * h + 2] = f.z;
    g->hinge_s[h] = moved;
    return true;
}

/* Distance from p to the surface, searched out to `limit` (beyond it:
 * INFINITY); *tri gets the nearest triangle (or UINT32_MAX). */
static double grid_nearest(const tri_grid *og, dv p, double limit, uint32_t *tri, uint32_t hint0, uint32_t hint1) {
    tri_grid *g = (tri_grid *)og; /* the query marks are scratch */
    int c[3];
    cell_of(g, p, c);
    if (g->qstamp == UINT32_MAX) {
        memset(g->qmark, 0, (size_t)g->tri_count * sizeof *g->qmark);
        g->qstamp = 0;
    }
    uint32_t qs = ++g->qstamp;
    double best2 = INFINITY, best = INFINITY;
    /* Rounding of a plane distance (n.p - n.a, both of the size of the
     * coordinates): far below this, so a triangle passed over is never
     * nearer. */
    const double htol = 1e-3 * g->ptol + 1e-13 * (fabs(p.x) + fabs(p.y) + fabs(p.z) + g->mag);
    uint32_t bt = UINT32_MAX;
    /* Hints (the nearest triangles of nearby points: a bisected edge's
     * ends, the previous vertex) first: their distance lets the plane test
     * and the cell boxes pass over most of the rest. Still the exact
     * nearest: a hint is only a first candidate. */
    const uint32_t hint[2] = {hint0, hint1};
    for (int h = 0; h < 2; h++) {
        uint32_t t = hint[h];
        if (t >= g->tri_count || g->qmark[t] == qs) continue;
        g->qmark[t] = qs;
        double d2 = dist2_point_tri(p, vtx(g->pos, g->idx[3 * t]), vtx(g->pos, g->idx[3 * t + 1]), vtx(g->pos, g->idx[3 * t + 2]));
        if (d2 < best2) {
            best2 = d2;
            best = sqrt(d2);
            bt = t;
        }
    }
    int maxr = g->n[0] + g->n[1] + g->n[2];
    const double q[3] = {p.x, p.y, p.z};
    /* How far p lies inside its cell from each side: ring r (r >= 1) is at
     * least r - 1 cells plus the nearest of these away. */
    double wall = INFINITY;
    for (int k = 0; k < 3; k++) {
        double lo = g->lo[k] + c[k] * g->cell;
        wall = dmin(wall, dmax(0, dmin(q[k] - lo, lo + g->cell - q[k])));
    }
    for (int r = 0; r <= maxr; r++) {
        double ring_min = (r - 1) * g->cell + wall;
        if (r > 0 && ring_min * ring_min > best2) break;
        if (r > 0 && ring_min > limit) break;
        for (int z = c[2] - r; z <= c[2] + r; z++) {
            if (z < 0 || z >= g->n[2]) continue;
            for (int y = c[1] - r; y <= c[1] + r; y++) {
                if (y < 0 || y >= g->n[1]) continue;
                bool shell_yz = z == c[2] - r || z == c[2] + r || y == c[1] - r || y == c[1] + r;
                for (int x = c[0] - r; x <= c[0] + r; x += (shell_yz || r == 0) ? 1 : 2 * r) {
                    if (x < 0 || x >= g->n[0]) continue;
                    size_t ci = ((size_t)z * g->n[1] + y) * g->n[0] + x;
                    if (g->start[ci] == g->start[ci + 1]) continue;
                    /* Skip cells whose box is farther than the best so far. */
                    const int cc[3] = {x, y, z};
                    double box2 = 0;
                    for (int k = 0; k < 3; k++) {
                        double lo = g->lo[k] + cc[k] * g->cell, hi = lo + g->cell;
                        double d = q[k] < lo ? lo - q[k] : q[k] > hi ? q[k] - hi : 0;
                        box2 += d * d;
                    }
                    if (box2 >= best2) continue;
                    for (uint32_t k = g->start[ci]; k < g->start[ci + 1]; k++) {
                        uint32_t t = g->items[k];
                        if (g->qmark[t] == qs) continue;
                        g->qmark[t] = qs;
                        if (g->tpl) {
                            const double *pl = g->tpl + 4 * (size_t)t;
                            if (fabs(pl[0] * p.x + pl[1] * p.y + pl[2] * p.z - pl[3]) - htol > best) continue;
                            /* ... and the ball around it (tsph): a triangle of
                             * the same curved sheet passes the plane test
                             * but lies off to the side. */
                            const double *sp = g->tsph + 5 * (size_t)t;
                            double cx = p.x - sp[0], cy = p.y - sp[1], cz = p.z - sp[2], reach = sp[3] + best + htol;
                            if (cx * cx + cy * cy + cz * cz > reach * reach) continue;
                        }
                        double d2 = dist2_point_tri(p, vtx(g->pos, g->idx[3 * t]), vtx(g->pos, g->idx[3 * t + 1]),
                                                    vtx(g->pos, g->idx[3 * t + 2]));
                        if (d2 < best2) {
                            best2 = d2;
                            best = sqrt(d2);
                            bt = t;
                        }
                    }
                }
            }
        }
    }
    if (tri) *tri = bt;
    double d = sqrt(best2);
    return d <= limit ? d : INFINITY;
}

static double dist_to_tri(const tri_grid *g, dv p, uint32_t t) {
    return sqrt(dist2_point_tri(p, vtx(g->pos, g->idx[3 * t]), vtx(g->pos, g->idx[3 * t + 1]), vtx(g->pos, g->idx[3 * t + 2])));
}

/* Length of a 2D vector. Not hypot: these are differences of coordinates
 * (at most about 1e9 here, squares far from overflow), and hypot's care
 * cost 0.8 % of a first LOD build. */
static inline double len2d(double x, double y) { return sqrt(x * x + y * y); }

/* 2D cross of (b - a) x (c - a). */
static double cross2(const double *a, const double *b, const double *c) {
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Convex hull (monotone chain) of np <= 48 points (sorted in place, by x
 * then y: insertion sort, as the points are few; qsort and its calls
 * through a pointer were 1.4 % of a first LOD build): its area and perimeter. */
static void hull_area2(double (*pts)[2], int np, double *area, double *perim) {
    for (int i = 1; i < np; i++) {
        double x = pts[i][0], y = pts[i][1];
        int k = i;
        while (k > 0 && (pts[k - 1][0] > x || (pts[k - 1][0] == x && pts[k - 1][1] > y))) {
            pts[k][0] = pts[k - 1][0];
            pts[k][1] = pts[k - 1][1];
            k--;
        }
        pts[k][0] = x;
        pts[k][1] = y;
    }
    double hull[97][2];
    int h = 0;
    for (int i = 0; i < np; i++) {
        while (h >= 2 && cross2(hull[h - 2], hull[h - 1], pts[i]) <= 0) h--;
        hull[h][0] = pts[i][0];
        hull[h][1] = pts[i][1];
        h++;
    }
    for (int i = np - 2, lo = h + 1; i >= 0; i--) {
        while (h >= lo && cross2(hull[h - 2], hull[h - 1], pts[i]) <= 0) h--;
        hull[h][0] = pts[i][0];
        hull[h][1] = pts[i][1];
        h++;
    }
    *area = *perim = 0;
    for (int i = 0; i + 1 < h; i++) {
        *area += 0.5 * (hull[i][0] * hull[i + 1][1] - hull[i + 1][0] * hull[i][1]);
        *perim += len2d(hull[i + 1][0] - hull[i][0], hull[i + 1][1] - hull[i][1]);
    }
}

/* Bound over the piece (a, b, c) from the fan of triangles around vertex v
 * that lie in the plane of triangle `ref`: if their union is a convex
 * polygon (it equals its convex hull: same orientation, angles at v within
 * a full turn, and area sum equal to the hull's area), the distance to it
 * is convex, so its largest value over the piece is at a corner. Planar
 * regions split into many triangles (cylinder strips, box faces, caps)
 * then need no subdivision around their vertices. INFINITY if it does not
 * apply. */
/* Largest distance of the corners q from a ball (centre c, radius r): a
 * lower bound of the largest corner distance to anything inside the ball,
 * so a bound from a region there that cannot reach `enough` is skipped. */
static bool ball_misses(const dv q[3], dv c, double r, double enough) {
    double lim = r + enough;
    for (int j = 0; j < 3; j++) {
        dv d = dv_sub(q[j], c);
        if (dv_dot(d, d) > lim * lim) return true;
    }
    return false;
}

/* The planar fan of vertex v in the plane of `ref`: which of v's
 * triangles it holds (*mask) and its slack (INFINITY: no claim). */
static double fan_prepare(const tri_grid *o, uint32_t v, uint32_t ref, uint16_t *mask) {
    *mask = 0;
    dv r0 = vtx(o->pos, o->idx[3 * ref]), r1 = vtx(o->pos, o->idx[3 * ref + 1]), r2 = vtx(o->pos, o->idx[3 * ref + 2]);
    dv e1 = dv_sub(r1, r0), e2 = dv_sub(r2, r0);
    dv n = {e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
    double nl = sqrt(dv_dot(n, n));
    if (!(nl > 0)) return INFINITY;
    n = (dv){n.x / nl, n.y / nl, n.z / nl};
    dv u = dv_mad(e1, n, 0);
    double ul = sqrt(dv_dot(u, u));
    u = (dv){u.x / ul, u.y / ul, u.z / ul};
    dv w = {n.y * u.z - n.z * u.y, n.z * u.x - n.x * u.z, n.x * u.y - n.y * u.x};
    int nf = 0;
    double area = 0, angle = 0;
    double pts[48][2];
    int np = 0;
    uint32_t k0 = o->vt_start[v], k1 = o->vt_start[v + 1];
    if (k1 - k0 > 16) return INFINITY; /* the mask holds 16: a vertex with more makes no claim (looser, not wrong) */
    for (uint32_t k = k0; k < k1; k++) {
        uint32_t t = o->vt_items[k];
        dv p[3];
        bool in_plane = true;
        for (int j = 0; j < 3; j++) {
            p[j] = vtx(o->pos, o->idx[3 * t + (uint32_t)j]);
            if (fabs(dv_dot(dv_sub(p[j], r0), n)) > o->ptol) in_plane = false;
        }
        if (!in_plane) continue;
        dv f1 = dv_sub(p[1], p[0]), f2 = dv_sub(p[2], p[0]);
        dv fn = {f1.y * f2.z - f1.z * f2.y, f1.z * f2.x - f1.x * f2.z, f1.x * f2.y - f1.y * f2.x};
        if (!(dv_dot(fn, n) > 0)) return INFINITY; /* flipped or degenerate: no claim */
        *mask |= (uint16_t)(1u << (k - k0));
        nf++;
        area += 0.5 * sqrt(dv_dot(fn, fn));
        /* angle at v */
        int iv = o->idx[3 * t] == v ? 0 : o->idx[3 * t + 1] == v ? 1 : 2;
        dv x1 = dv_sub(p[(iv + 1) % 3], p[iv]), x2 = dv_sub(p[(iv + 2) % 3], p[iv]);
        double cs = dv_dot(x1, x2) / sqrt(dv_dot(x1, x1) * dv_dot(x2, x2));
        angle += acos(cs < -1 ? -1 : cs > 1 ? 1 : cs);
        for (int j = 0; j < 3; j++) {
            dv d = dv_sub(p[j], r0);
            pts[np][0] = dv_dot(d, u);
            pts[np][1] = dv_dot(d, w);
            np++;
        }
    }
    if (nf < 2 || angle > 2 * 3.14159265358979323846 + 1e-9) return INFINITY;
    double harea, perim; /* the fan's convex hull */
    hull_area2(pts, np, &harea, &perim);
    if (!(harea > 0) || !(fabs(harea - area) <= 1e-6 * harea)) return INFINITY;
    /* What float rounding may leave uncovered: a sliver of the area
     * mismatch is at most 2 * area / perimeter wide; plus the plane slack. */
    return 2 * fabs(harea - area) / perim + 2 * o->ptol;
}

static double fan_bound(const tri_grid *o, uint32_t v, uint32_t ref, dv a, dv b, dv c, double enough) {
    const dv q[3] = {a, b, c};
    /* The fan lies within v's ball. */
    if (ball_misses(q, vtx(o->pos, v), o->vrad[v], enough)) return INFINITY;
    if (o->fan_ref[v] != ref) {
        o->fan_slack[v] = fan_prepare(o, v, ref, &o->fan_mask[v]);
        o->fan_ref[v] = ref;
    }
    double slack = o->fan_slack[v];
    if (!(slack < enough)) return INFINITY;
    uint32_t k0 = o->vt_start[v];
    double m = 0;
    for (int j = 0; j < 3; j++) {
        double best = INFINITY;
        for (uint32_t k = 0; k < 16; k++)
            if (o->fan_mask[v] & (1u << k)) best = dmin(best, dist_to_tri(o, q[j], o->vt_items[k0 + k]));
        m = dmax(m, best);
        if (m + slack > enough) return INFINITY; /* fails: the other corners need not be measured */
    }
    return m + slack;
}

/* A projected patch: the bound that makes big pieces cheap. Project the
 * other surface's triangles near the piece P orthogonally onto P's plane.
 * If P lies inside the projection U of some of them, every point p of P is
 * the projection of a point s of the surface, and |p - s| is s's height
 * above the plane: the distance from P to the surface is at most the
 * largest height H of those triangles' corners (heights are affine over a
 * triangle). No corner distances, no convexity: a chord of a curved
 * surface, a re-triangulated planar region, a fine strip under a coarse
 * one are each bounded in one piece.
 *
 * Coverage is proven, not assumed: the patch is grown from the corners'
 * nearest triangles across edges (each shared by exactly two triangles
 * running it in opposite directions), keeping triangles that face the
 * plane (projected orientation positive, at least 5 % of their area),
 * touch P's projection and are within `enough` of the plane. Across an
 * interior edge the two projected triangles then lie on opposite sides, and
 * around an interior vertex they wind around it, so the boundary of U lies
 * on the projected border edges of the patch. If no border edge meets the
 * open triangle P_d (P shrunk by d = ptol about its incentre) and P_d's
 * centroid lies in U, the connected P_d lies in U; every point of P is
 * within d' (d / inradius times the corners' distance to the incentre) of
 * P_d. Bound: H + d' + 2 ptol (rounding of positions). INFINITY where any
 * step fails: only the cost of trying is lost. */
/* Triangles in one patch at most. 256, not 128: a coarse piece over a big
 * finely split planar region then needs no subdivision (measured with
 * callgrind on a 300k-triangle unique factory: 2.2 % fewer instructions in
 * the LOD build, the same bounds). */
#define PATCH_MAX 256

/* Closed triangles (both counter-clockwise) overlap: no edge of either
 * separates them. */
static bool tri2_overlap(const double x[3][2], const double y[3][2]) {
    for (int i = 0; i < 3; i++) {
        const double *p = x[i], *q = x[(i + 1) % 3];
        if (cross2(p, q, y[0]) < 0 && cross2(p, q, y[1]) < 0 && cross2(p, q, y[2]) < 0) return false;
        p = y[i], q = y[(i + 1) % 3];
        if (cross2(p, q, x[0]) < 0 && cross2(p, q, x[1]) < 0 && cross2(p, q, x[2]) < 0) return false;
    }
    return true;
}

/* The largest |height| over the part of triangle x (counter-clockwise,
 * signed heights h at its corners, affine in between) that projects into
 * the triangle p (counter-clockwise). Affine over a convex polygon, the
 * height is largest at a corner of x inside p, a corner of p inside x, or
 * where an edge of x crosses an edge of p: the side tests (signed areas)
 * of x's corners against p's edges and of p's corners against x's edges
 * decide all three, with no polygon clipped. Each test admits what lies
 * within a margin of the line (1e-12 of the largest coordinate, far above
 * the rounding of a side test), so rounding only ever adds a candidate:
 * the result is never below the true largest height. If nothing is found
 * (they only touch), the corners' largest. */
static double clipped_height(const double x[3][2], const double h[3], const double p[3][2]) {
    double S[3][3]; /* S[i][e]: x's corner i against p's edge e */
    bool xin = true;
    for (int i = 0; i < 3; i++)
        for (int e = 0; e < 3; e++) {
            S[i][e] = cross2(p[e], p[(e + 1) % 3], x[i]);
            xin = xin && S[i][e] >= 0;
        }
    double hc = dmax(fabs(h[0]), dmax(fabs(h[1]), fabs(h[2])));
    /* Common cases first: x inside p (a fine triangle under a coarse
     * piece), then p inside x (a small piece over a big triangle: the
     * heights at p's corners, barycentric). */
    if (xin) return hc;
    double ax = cross2(x[0], x[1], x[2]);
    double W[3][3]; /* W[j][i]: p's corner j against x's edge i */
    bool pin = ax > 0;
    double hm = 0;
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++) {
            W[j][i] = cross2(x[i], x[(i + 1) % 3], p[j]);
            pin = pin && W[j][i] >= 0;
        }
    if (pin) {
        for (int j = 0; j < 3; j++) hm = dmax(hm, fabs((W[j][1] * h[0] + W[j][2] * h[1] + W[j][0] * h[2]) / ax));
        return hm;
    }
    double d = 0;
    for (int k = 0; k < 3; k++)
        d = dmax(d, dmax(dmax(fabs(x[k][0]), fabs(x[k][1])), dmax(fabs(p[k][0]), fabs(p[k][1]))));
    d *= 1e-12;
    double ts[3], tw[3]; /* the margins as side-test values: d times the edges' L1 lengths */
    for (int k = 0; k < 3; k++) {
        ts[k] = d * (fabs(p[(k + 1) % 3][0] - p[k][0]) + fabs(p[(k + 1) % 3][1] - p[k][1]));
        tw[k] = d * (fabs(x[(k + 1) % 3][0] - x[k][0]) + fabs(x[(k + 1) % 3][1] - x[k][1]));
    }
    bool found = false;
    for (int i = 0; i < 3; i++)
        if (S[i][0] >= -ts[0] && S[i][1] >= -ts[1] && S[i][2] >= -ts[2]) {
            hm = dmax(hm, fabs(h[i]));
            found = true;
        }
    for (int j = 0; j < 3 && ax > 0; j++)
        if (W[j][0] >= -tw[0] && W[j][1] >= -tw[1] && W[j][2] >= -tw[2]) {
            /* (weights clamped: admitted by the margin, the corner is taken
             * at the nearest point of x, never extrapolated along a sliver) */
            double w0 = dmax(W[j][1], 0), w1 = dmax(W[j][2], 0), w2 = dmax(W[j][0], 0), ws = w0 + w1 + w2;
            hm = dmax(hm, ws > 0 ? fabs((w0 * h[0] + w1 * h[1] + w2 * h[2]) / ws) : hc);
            found = true;
        }
    for (int i = 0; i < 3; i++) {
        int i1 = (i + 1) % 3;
        for (int e = 0; e < 3; e++) {
            double sa = S[i][e], sb = S[i1][e];
            if ((sa > ts[e] && sb > ts[e]) || (sa < -ts[e] && sb < -ts[e])) continue; /* edge i off p's edge e's line */
            double wa = W[e][i], wb = W[(e + 1) % 3][i];
            if ((wa > tw[i] && wb > tw[i]) || (wa < -tw[i] && wb < -tw[i])) continue; /* p's edge e off x's edge i's line */
            double den = sa - sb, t = fabs(den) > ts[e] ? sa / den : 0.5;
            if (!(fabs(den) > ts[e])) hm = dmax(hm, dmax(fabs(h[i]), fabs(h[i1]))); /* along the line: both ends */
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            hm = dmax(hm, fabs(h[i] + t * (h[i1] - h[i])));
            found = true;
        }
    }
    return found ? hm : hc;
}

/* Segment s0 s1 meets the open counter-clockwise triangle t. */
static bool seg_hits_open_tri(const double *s0, const double *s1, const double t[3][2]) {
    for (int i = 0; i < 3; i++)
        if (cross2(t[i], t[(i + 1) % 3], s0) <= 0 && cross2(t[i], t[(i + 1) % 3], s1) <= 0) return false;
    double c0 = cross2(s0, s1, t[0]), c1 = cross2(s0, s1, t[1]), c2 = cross2(s0, s1, t[2]);
    if ((c0 >= 0 && c1 >= 0 && c2 >= 0) || (c0 <= 0 && c1 <= 0 && c2 <= 0)) return false;
    return true;
}

/* seed: where to start (the corners' nearest triangles); more: further
 * starts (the triangles around corners the surfaces share), taken only if
 * nothing from seed lies under the piece. */
static double patch_bound(const tri_grid *og, dv a, dv b, dv c, const uint32_t *seed, int nseed, const uint32_t *more,
                          int nmore, double enough) {
    tri_grid *o = (tri_grid *)og; /* the patch marks are scratch */
    if (!o->nbr) return INFINITY;
    dv e1 = dv_sub(b, a), e2 = dv_sub(c, a);
    dv n = {e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
    double nl = sqrt(dv_dot(n, n)), l1 = sqrt(dv_dot(e1, e1));
    if (!(nl > 0) || !(l1 > 0)) return INFINITY;
    n = (dv){n.x / nl, n.y / nl, n.z / nl};
    dv u = {e1.x / l1, e1.y / l1, e1.z / l1};
    dv w = {n.y * u.z - n.z * u.y, n.z * u.x - n.x * u.z, n.x * u.y - n.y * u.x};
    const double P[3][2] = {{0, 0}, {l1, 0}, {dv_dot(e2, u), dv_dot(e2, w)}};
    /* The shrunk triangle: a homothety about the incentre. */
    double la = len2d(P[2][0] - P[1][0], P[2][1] - P[1][1]), lb = len2d(P[2][0], P[2][1]), lc = l1;
    double per = la + lb + lc, area2 = cross2(P[0], P[1], P[2]);
    double r = area2 / per, d = o->ptol > 0 ? o->ptol : 1e-300;
    if (!(r > 4 * d)) return INFINITY;
    const double I[2] = {(la * P[0][0] + lb * P[1][0] + lc * P[2][0]) / per, (la * P[0][1] + lb * P[1][1] + lc * P[2][1]) / per};
    double k = (r - d) / r, dgrow = 0, Q[3][2];
    for (int i = 0; i < 3; i++) {
        Q[i][0] = I[0] + k * (P[i][0] - I[0]);
        Q[i][1] = I[1] + k * (P[i][1] - I[1]);
        dgrow = dmax(dgrow, d / r * len2d(P[i][0] - I[0], P[i][1] - I[1]));
    }
    if (o->stamp >= 0x7ffffff0u) {
        memset(o->mark, 0, (size_t)o->tri_count * sizeof *o->mark);
        for (uint32_t i = 0; i < o->tri_count * 3; i++) o->pmark[o->idx[i]] = 0;
        o->stamp = 0;
    }
    uint32_t st = ++o->stamp, in = 2 * st + 1, seen = 2 * st;
    uint32_t list[PATCH_MAX];
    double xy[PATCH_MAX][3][2];
    int np = 0;
    double H = 0;
    /* Breadth first: candidates come from the seeds, then from the border
     * edges of what is in. */
    uint32_t cand[PATCH_MAX * 3 + 96];
    int nc = 0;
    for (int i = 0; i < nseed && nc < 96; i++)
        if (seed[i] != UINT32_MAX) cand[nc++] = seed[i];
    for (int ci = 0;; ci++) {
        if (ci == nc) {
            if (np > 0 || nmore == 0) break;
            for (int i = 0; i < nmore && nc < 96; i++)
                if (more[i] != UINT32_MAX) cand[nc++] = more[i];
            nmore = 0;
            if (ci == nc) break;
        }
        uint32_t t = cand[ci];
        if (o->mark[t] >= seen) continue;
        o->mark[t] = seen;
        double x[3][2], hs[3];
        for (int j = 0; j < 3; j++) {
            uint32_t v = o->idx[3 * (size_t)t + (size_t)j];
            double *pv = o->pxy + 3 * (size_t)v;
            if (o->pmark[v] != st) {
                o->pmark[v] = st;
                dv dp = dv_sub(vtx(o->pos, v), a);
                pv[0] = dv_dot(dp, u);
                pv[1] = dv_dot(dp, w);
                pv[2] = dv_dot(dp, n);
            }
            x[j][0] = pv[0];
            x[j][1] = pv[1];
            hs[j] = pv[2];
        }
        /* Facing the plane, by at least 5 % of its area. */
        double a2 = cross2(x[0], x[1], x[2]);
        if (!(a2 > 0.05 * o->tsph[5 * (size_t)t + 4])) continue;
        if (!tri2_overlap(Q, x)) continue;
        /* Only the part over P matters (the clip also keeps 9 corners at
         * most: a triangle clipped by three half-planes); no clip needed
         * where even the corners do not raise H. */
        double hmax = dmax(fabs(hs[0]), dmax(fabs(hs[1]), fabs(hs[2])));
        if (hmax > H) hmax = clipped_height(x, hs, P);
        if (!(hmax <= enough)) continue;
        if (np == PATCH_MAX) return INFINITY;
        o->mark[t] = in;
        memcpy(xy[np], x, sizeof x);
        list[np++] = t;
        H = dmax(H, hmax);
        if (H + dgrow + 2 * o->ptol > enough) return INFINITY;
        for (int j = 0; j < 3; j++) {
            uint32_t nb = o->nbr[3 * (size_t)t + (size_t)j];
            if (nb == UINT32_MAX || o->mark[nb] >= seen) continue;
            /* Not across an edge with all of Q strictly on this side: the
             * neighbour lies beyond it and cannot touch Q (only a skipped
             * test: coverage is still proven below). */
            const double *s0 = x[j], *s1 = x[(j + 1) % 3];
            if (cross2(s0, s1, Q[0]) > 0 && cross2(s0, s1, Q[1]) > 0 && cross2(s0, s1, Q[2]) > 0) continue;
            cand[nc++] = nb;
        }
    }
    if (np == 0) return INFINITY;
    /* Border edges must stay off the open shrunk triangle. */
    for (int i = 0; i < np; i++) {
        uint32_t t = list[i];
        for (int j = 0; j < 3; j++) {
            uint32_t nb = o->nbr[3 * (size_t)t + (size_t)j];
            if (nb != UINT32_MAX && o->mark[nb] == in) continue;
            if (seg_hits_open_tri(xy[i][j], xy[i][(j + 1) % 3], Q)) return INFINITY;
        }
    }
    /* ... and the shrunk triangle's centroid must be covered. */
    const double g[2] = {(Q[0][0] + Q[1][0] + Q[2][0]) / 3, (Q[0][1] + Q[1][1] + Q[2][1]) / 3};
    for (int i = 0; i < np; i++)
        if (cross2(xy[i][0], xy[i][1], g) > 0 && cross2(xy[i][1], xy[i][2], g) > 0 && cross2(xy[i][2], xy[i][0], g) > 0)
            return H + dgrow + 2 * o->ptol;
    return INFINITY;
}

/* The whole fan of triangles around vertex v, projected orthogonally onto
 * the plane through v normal to their area-weighted normal. If that
 * projection is a convex polygon (consistently oriented, angles at v within
 * a full turn, its area equal to its hull's), the distance to it is convex,
 * and the distance to the real fan is at most that + the largest height of
 * a fan vertex above the plane (each point of a fan triangle moves by its
 * height, affine over the triangle). So a piece lying over the 1-ring of a
 * vertex of a curved surface is bounded from its corners. Prepared once per
 * vertex; returns INFINITY where it does not apply. */
static void ring_prepare(const tri_grid *o, uint32_t v) {
    double *nrm = o->ring_n + 3 * (size_t)v;
    o->ring_s[v] = INFINITY;
    uint32_t k0 = o->vt_start[v], k1 = o->vt_start[v + 1];
    if (k1 - k0 < 3 || k1 - k0 > 16) return;
    dv n = {0, 0, 0}, pv = vtx(o->pos, v);
    for (uint32_t k = k0; k < k1; k++) {
        uint32_t t = o->vt_items[k];
        dv p0 = vtx(o->pos, o->idx[3 * t]), p1 = vtx(o->pos, o->idx[3 * t + 1]), p2 = vtx(o->pos, o->idx[3 * t + 2]);
        dv f1 = dv_sub(p1, p0), f2 = dv_sub(p2, p0);
        n = dv_mad(n, (dv){f1.y * f2.z - f1.z * f2.y, f1.z * f2.x - f1.x * f2.z, f1.x * f2.y - f1.y * f2.x}, 1);
    }
    double nl = sqrt(dv_dot(n, n));
    if (!(nl > 0)) return;
    n = (dv){n.x / nl, n.y / nl, n.z / nl};
    /* In-plane axes. */
    dv u = fabs(n.x) < 0.6 ? (dv){0, -n.z, n.y} : (dv){n.z, 0, -n.x};
    double ul = sqrt(dv_dot(u, u));
    u = (dv){u.x / ul, u.y / ul, u.z / ul};
    dv w = {n.y * u.z - n.z * u.y, n.z * u.x - n.x * u.z, n.x * u.y - n.y * u.x};
    double pts[48][2], area = 0, angle = 0, height = 0;
    int np = 0;
    for (uint32_t k = k0; k < k1; k++) {
        uint32_t t = o->vt_items[k];
        double q[3][2];
        int iv = 0;
        for (int j = 0; j < 3; j++) {
            uint32_t vi = o->idx[3 * t + (uint32_t)j];
            if (vi == v) iv = j;
            dv d = dv_sub(vtx(o->pos, vi), pv);
            height = dmax(height, fabs(dv_dot(d, n)));
            q[j][0] = pts[np][0] = dv_dot(d, u);
            q[j][1] = pts[np][1] = dv_dot(d, w);
            np++;
        }
        double cr = cross2(q[0], q[1], q[2]);
        if (!(cr > 0)) return; /* flipped or degenerate in projection: no claim */
        area += 0.5 * cr;
        const double *x0 = q[iv], *x1 = q[(iv + 1) % 3], *x2 = q[(iv + 2) % 3];
        double ax = x1[0] - x0[0], ay = x1[1] - x0[1], bx = x2[0] - x0[0], by = x2[1] - x0[1];
        angle += atan2(ax * by - ay * bx, ax * bx + ay * by);
    }
    if (angle > 2 * 3.14159265358979323846 + 1e-9) return;
    double harea, perim;
    hull_area2(pts, np, &harea, &perim);
    if (!(harea > 0) || !(fabs(harea - area) <= 1e-6 * harea)) return;
    nrm[0] = n.x;
    nrm[1] = n.y;
    nrm[2] = n.z;
    /* + the sliver float rounding may leave uncovered, + the positions'
     * rounding (as for the planar fans). */
    o->ring_s[v] = height + 2 * fabs(harea - area) / perim + 2 * o->ptol;
}

static double ring_bound(const tri_grid *o, uint32_t v, dv a, dv b, dv c, double enough) {
    if (isnan(o->ring_s[v])) ring_prepare(o, v);
    double slack = o->ring_s[v];
    if (!(slack < enough)) return INFINITY;
    dv n = {o->ring_n[3 * (size_t)v], o->ring_n[3 * (size_t)v + 1], o->ring_n[3 * (size_t)v + 2]}, pv = vtx(o->pos, v);
    const dv q[3] = {a, b, c};
    /* The projected fan lies in the plane: a corner's height is a lower
     * bound of its distance to it. */
    for (int j = 0; j < 3; j++)
        if (fabs(dv_dot(dv_sub(q[j], pv), n)) + slack > enough) return INFINITY;
    /* The projected ring lies within v's ball (projection only shortens
     * distances to v, which is in the plane). */
    if (ball_misses(q, pv, o->vrad[v], enough - slack)) return INFINITY;
    dv p[16][3];
    uint32_t k0 = o->vt_start[v], nk = o->vt_start[v + 1] - k0; /* <= 16 (ring_prepare) */
    for (uint32_t k = 0; k < nk; k++) {
        uint32_t t = o->vt_items[k0 + k];
        for (int i = 0; i < 3; i++) {
            dv x = vtx(o->pos, o->idx[3 * t + (uint32_t)i]);
            p[k][i] = dv_mad(x, n, -dv_dot(dv_sub(x, pv), n));
        }
    }
    double m = 0;
    for (int j = 0; j < 3; j++) {
        double best = INFINITY;
        for (uint32_t k = 0; k < nk; k++) best = dmin(best, dist2_point_tri(q[j], p[k][0], p[k][1], p[k][2]));
        m = dmax(m, sqrt(best));
        if (m + slack > enough) return INFINITY; /* fails (as fan_bound) */
    }
    return m + slack;
}

typedef struct bb_ctx {
    const tri_grid *other;
    double lower;      /* largest exact point distance seen (both directions) */
    double upper;      /* largest accepted bound */
    double resolution, limit;
    double accept;     /* a piece whose bound is at most this needs no more work */
    double rel;        /* ... nor one within this fraction (+ resolution) of lower */
    uint64_t work;
} bb_ctx;

/* Largest corner distance from q to triangle t: by convexity of the
 * distance to one triangle, its largest value over the whole piece; or
 * INFINITY as soon as one corner is past enough (no bound then). */
static double corner_max(const tri_grid *o, const dv q[3], uint32_t t, double enough) {
    double m = 0;
    for (int j = 0; j < 3 && m <= enough; j++) m = dmax(m, dist_to_tri(o, q[j], t));
    return m <= enough ? m : INFINITY;
}

/* Largest distance of the piece's corners from the plane of triangle t: a
 * lower bound of any bound from a region in that plane (a triangle, a flat
 * pair, a planar fan), so where it already exceeds what is enough, those
 * bounds need not be tried. */
static double plane_gap(const tri_grid *o, uint32_t t, dv a, dv b, dv c) {
    /* From the triangle's unit normal and offset (tpl), prepared once;
     * slightly under the exact value and less the rounding of an offset
     * (as in grid_nearest), so rounding never skips a bound that would
     * have held (skipping would only cost time anyway). */
    const double *pl = o->tpl + 4 * (size_t)t;
    double g = dmax(fabs(pl[0] * a.x + pl[1] * a.y + pl[2] * a.z - pl[3]),
                    dmax(fabs(pl[0] * b.x + pl[1] * b.y + pl[2] * b.z - pl[3]),
                         fabs(pl[0] * c.x + pl[1] * c.y + pl[2] * c.z - pl[3])));
    return 0.999 * g - 1e-13 * (fabs(a.x) + fabs(a.y) + fabs(a.z) + o->mag);
}

/* Bound of the distance from triangle (a, b, c) to the other surface.
 * va, vb, vc: the corners' vertex ids where they are vertices of the mesh
 * (UINT32_MAX for midpoints): a vertex the other surface uses lies on it,
 * and every triangle around it there is a candidate. */
static void bound_tri(bb_ctx *x, dv a, dv b, dv c, double da, double db, double dc, uint32_t ta, uint32_t tb,
                      uint32_t tc, uint32_t va, uint32_t vb, uint32_t vc, int depth) {
    for (;;) {
        x->work++;
        if (!isfinite(da) || !isfinite(db) || !isfinite(dc)) {
            x->upper = INFINITY;
            return;
        }
        /* Enough: within what is asked (accept), or within resolution of
         * the largest distance known to be real (lower). */
        double enough = dmax(x->accept, x->lower * (1 + x->rel) + x->resolution);
        double ub = INFINITY, cdd[3][3];
        const uint32_t cand[3] = {ta, tb, tc}, vid[3] = {va, vb, vc};
        const dv q[3] = {a, b, c};
        const tri_grid *o = x->other;
        /* Lipschitz, first because it is free: every point is within the
         * covering radius (at most the longest edge / sqrt 3) of a corner. */
        dv ab = dv_sub(b, a), bc = dv_sub(c, b), ca = dv_sub(a, c);
        double lab = dv_dot(ab, ab), lbc = dv_dot(bc, bc), lca = dv_dot(ca, ca);
        double longest = sqrt(dmax(lab, dmax(lbc, lca)));
        double lip = dmax(da, dmax(db, dc)) + longest / sqrt(3.0);
        if (lip <= enough) {
            if (lip > x->upper) x->upper = lip;
            return;
        }
        /* Convexity: over the triangle, distance to one triangle t is at
         * most the largest corner distance to t. A corner whose nearest
         * triangle is t is at its known distance from it (all three, the
         * common case: no distance computed at all). */
        const double dk[3] = {da, db, dc};
        /* (Each stage stops at the first bound that is enough: a tighter
         * one would not change what is kept, only cost more distances.
         * cdd of candidates not reached is not read: the flat pairs below
         * run only while ub is over enough.) */
        for (int k = 0; k < 3 && ub > enough; k++) {
            uint32_t t = cand[k];
            if (t == UINT32_MAX || (k > 0 && t == cand[0]) || (k > 1 && t == cand[1])) continue;
            /* Corners known to be near t first; past enough the rest are
             * left unknown (-1, computed by the flat pairs if asked): this
             * bound has failed. */
            double m = 0;
            for (int j = 0; j < 3; j++) cdd[k][j] = cand[j] == t ? dk[j] : -1;
            for (int j = 0; j < 3 && m <= enough; j++) m = dmax(m, cdd[k][j]);
            for (int j = 0; j < 3 && m <= enough; j++)
                if (cdd[k][j] < 0) m = dmax(m, cdd[k][j] = dist_to_tri(o, q[j], t));
            if (m <= enough && m < ub) ub = m;
        }
        /* The convex union with a coplanar neighbour. */
        for (int k = 0; k < 3 && ub > enough && o->partner; k++) {
            uint32_t t = cand[k];
            if (t == UINT32_MAX || (k > 0 && t == cand[0]) || (k > 1 && t == cand[1])) continue;
            if (plane_gap(o, t, a, b, c) > enough) continue;
            double *kd = cdd[k];
            for (int j = 0; j < 3 && ub > enough; j++) {
                size_t h = 3 * (size_t)t + (size_t)j;
                if (!partner_get(o, h)) continue;
                /* The flat pair (t and the folded partner) is convex: its
                 * distance is largest at a corner; + what the fold moved,
                 * + 2 ptol: "coplanar" allows float rounding, so the flat
                 * union is convex only up to that distance. */
                double slack = o->hinge_s[h] + 2 * o->ptol;
                if (slack >= ub) continue;
                dv e0 = vtx(o->pos, o->idx[3 * t + (size_t)j]), e1 = vtx(o->pos, o->idx[3 * t + (size_t)(j + 1) % 3]);
                dv f = {o->hinge_p[3 * h], o->hinge_p[3 * h + 1], o->hinge_p[3 * h + 2]};
                /* A corner already within enough of t needs no distance to
                 * the pair; the first corner past it ends this pair (its
                 * partial maximum is no bound). */
                double mq = 0;
                for (int i = 0; i < 3 && mq + slack <= enough; i++) {
                    if (kd[i] < 0) kd[i] = dist_to_tri(o, q[i], t);
                    double v = kd[i];
                    if (v + slack > enough) v = dmin(v, sqrt(dist2_point_tri(q[i], e1, e0, f)));
                    mq = dmax(mq, v);
                }
                mq += slack;
                if (mq <= enough && mq < ub) ub = mq;
            }
        }
        /* A projected patch of the other surface (see patch_bound). */
        if (ub > enough) {
            uint32_t more[3 * 24];
            int ns = 0;
            for (int k = 0; k < 3 && o->vt_start; k++)
                if (vid[k] != UINT32_MAX)
                    for (uint32_t j = o->vt_start[vid[k]], m = 0; j < o->vt_start[vid[k] + 1] && m < 24; j++, m++)
                        more[ns++] = o->vt_items[j];
            double pb = patch_bound(o, a, b, c, cand, 3, more, ns, enough);
            if (pb < ub) ub = pb;
        }
        /* Curved fans around the candidates' vertices and the shared
         * corners. */
        for (int k = 0; k < 3 && ub > enough && o->ring_s; k++) {
            uint32_t t = cand[k];
            if (t == UINT32_MAX || (k > 0 && t == cand[0]) || (k > 1 && t == cand[1])) continue;
            for (int j = 0; j < 3 && ub > enough; j++) {
                double rb = ring_bound(o, o->idx[3 * t + (uint32_t)j], a, b, c, enough);
                if (rb < ub) ub = rb;
            }
        }
        for (int k = 0; k < 3 && ub > enough && o->ring_s; k++)
            if (vid[k] != UINT32_MAX && o->vt_start[vid[k] + 1] > o->vt_start[vid[k]]) {
                double rb = ring_bound(o, vid[k], a, b, c, enough);
                if (rb < ub) ub = rb;
            }
        /* Triangles around corners shared with the other surface. */
        for (int k = 0; k < 3 && ub > enough && o->vt_start; k++) {
            uint32_t v = vid[k];
            if (v == UINT32_MAX) continue;
            for (uint32_t j = o->vt_start[v], n = 0; j < o->vt_start[v + 1] && n < 24 && ub > enough; j++, n++) {
                const double *sp = o->tsph + 5 * (size_t)o->vt_items[j];
                if (ball_misses(q, (dv){sp[0], sp[1], sp[2]}, sp[3], enough)) continue;
                if (plane_gap(o, o->vt_items[j], a, b, c) > enough) continue;
                double m = corner_max(o, q, o->vt_items[j], enough);
                if (m < ub) ub = m;
            }
        }
        /* Planar fans around the candidates' vertices, where still needed. */
        for (int k = 0; k < 3 && ub > enough && o->vt_start; k++) {
            uint32_t t = cand[k];
            if (t == UINT32_MAX || (k > 0 && t == cand[0]) || (k > 1 && t == cand[1])) continue;
            if (plane_gap(o, t, a, b, c) > enough) continue;
            for (int j = 0; j < 3 && ub > enough; j++) {
                double fb = fan_bound(o, o->idx[3 * t + (uint32_t)j], t, a, b, c, enough);
                if (fb < ub) ub = fb;
            }
        }
        if (lip < ub) ub = lip; /* (computed above) */
        /* Past the work cap a piece keeps the bound it has: still a bound,
         * only looser, so a pathological mesh costs seconds, not hours. */
        if (ub <= enough || depth >= 40 || longest <= x->resolution || x->work > 4000000ull) {
            if (ub > x->upper) x->upper = ub;
            return;
        }
        /* Bisect the longest edge: query the midpoint exactly. A thin
         * piece too (no four-way split, which halved its width at once):
         * bisection makes it fat within a few steps and keeps two of its
         * corners' vertices for the shared-corner stages. Measured: 8 to
         * 11 % less CPU on the 2M and 10M unique factories, the same number
         * of levels (0.15 % more level triangles: each level's target
         * follows the bound of the one before), the bounds' sum from
         * 0.4 % tighter (10M) to 0.13 % looser (200k). */
        dv m;
        uint32_t tm;
        if (lab >= lbc && lab >= lca) {
            m = dv_mad(a, ab, 0.5);
            double dm = grid_nearest(x->other, m, x->limit, &tm, ta, tb);
            if (dm > x->lower) x->lower = dm;
            bound_tri(x, a, m, c, da, dm, dc, ta, tm, tc, va, UINT32_MAX, vc, depth + 1);
            a = m; da = dm; ta = tm; va = UINT32_MAX; /* second half: m, b, c */
        } else if (lbc >= lca) {
            m = dv_mad(b, bc, 0.5);
            double dm = grid_nearest(x->other, m, x->limit, &tm, tb, tc);
            if (dm > x->lower) x->lower = dm;
            bound_tri(x, a, b, m, da, db, dm, ta, tb, tm, va, vb, UINT32_MAX, depth + 1);
            b = m; db = dm; tb = tm; vb = UINT32_MAX; /* a, m, c */
        } else {
            m = dv_mad(c, ca, 0.5);
            double dm = grid_nearest(x->other, m, x->limit, &tm, tc, ta);
            if (dm > x->lower) x->lower = dm;
            bound_tri(x, a, b, m, da, db, dm, ta, tb, tm, va, vb, UINT32_MAX, depth + 1);
            a = m; da = dm; ta = tm; va = UINT32_MAX; /* m, b, c */
        }
        depth++;
    }
}

/* Exact distance of every vertex of `from` to the other surface, and its
 * nearest triangle there; a vertex the other surface uses is on it (0, any
 * triangle around it). Raises *lower. false if out of memory. */
static bool vertex_distances(const double *pos, uint32_t nv, const uint32_t *from, uint32_t from_count,
                             const tri_grid *to, double limit, double *d, uint32_t *near, double *lower) {
    for (uint32_t v = 0; v < nv; v++) d[v] = -1;
    for (uint32_t i = 0; i < from_count; i++) {
        uint32_t v = from[i];
        if (d[v] >= 0) continue;
        if (to->vt_start && to->vt_start[v + 1] > to->vt_start[v]) {
            d[v] = 0;
            near[v] = to->vt_items[to->vt_start[v]];
            continue;
        }
        /* hint: the nearest of the triangle's previous corner */
        d[v] = grid_nearest(to, vtx(pos, v), limit, &near[v], i % 3 ? near[from[i - 1]] : UINT32_MAX, UINT32_MAX);
        if (d[v] > *lower) *lower = d[v];
    }
    return true;
}

/* One direction: from surface `from` to the grid's surface, given the
 * vertices' distances. */
static double directed_bound(const double *pos, const uint32_t *from, uint32_t from_count, const tri_grid *to,
                             const double *d, const uint32_t *near, double *lower, double resolution, double accept,
                             double limit) {
    /* Within a quarter of the truth: a level's bound only decides from how
     * far it is drawn, and refining the last quarter costs more than all
     * the rest. Tight mode (accept 0, mr_lod_hausdorff_bound) keeps the
     * old contract: within resolution. */
    bb_ctx x = {to, *lower, *lower, resolution, limit, accept, accept > 0 ? 0.25 : 0, 0};
    for (uint32_t t = 0; t + 2 < from_count && isfinite(x.upper); t += 3) {
        uint32_t i0 = from[t], i1 = from[t + 1], i2 = from[t + 2];
        /* A triangle the other surface has too (the simplifier left it as
         * it was) is at distance 0. */
        bool shared = false;
        if (to->vt_start)
            for (uint32_t k = to->vt_start[i0]; k < to->vt_start[i0 + 1] && !shared; k++) {
                const uint32_t *q = to->idx + 3 * (size_t)to->vt_items[k];
                int hit = 0;
                for (int j = 0; j < 3; j++) hit += q[j] == i0 || q[j] == i1 || q[j] == i2;
                shared = hit == 3 && i0 != i1 && i1 != i2 && i0 != i2;
            }
        if (shared) continue;
        bound_tri(&x, vtx(pos, i0), vtx(pos, i1), vtx(pos, i2), d[i0], d[i1], d[i2], near[i0], near[i1], near[i2], i0,
                  i1, i2, 0);
    }
    *lower = x.lower;
    return x.upper;
}

/* The box of all vertices (both surfaces use the same array) and the
 * coplanarity tolerance: positions are float, a few ulps of the extent. */
static void vertex_box(const float *positions, uint32_t vertex_count, double lo[3], double hi[3], double *ptol) {
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (uint32_t v = 0; v < vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            double p = positions[3 * (size_t)v + (size_t)k];
            if (p < lo[k]) lo[k] = p;
            if (p > hi[k]) hi[k] = p;
        }
    *ptol = 1e-6 * dmax(hi[0] - lo[0], dmax(hi[1] - lo[1], hi[2] - lo[2]));
}

/* One surface ready to be measured against: its grid, neighbours, hinges
 * and fans. All of it (and what the bounds prepare lazily in it) belongs to
 * the surface alone, so a level's grid serves again when it is the next
 * level's source. false if out of memory (g still freeable). */
static bool surface_prepare(tri_grid *g, const double *positions, uint32_t vertex_count, const uint32_t *idx,
                            uint32_t count, const double lo[3], const double hi[3], double ptol) {
    return grid_build(g, positions, idx, count, lo, hi) && convex_partners(g, ptol, vertex_count);
}

/* The doubles the bounds read (NULL if out of memory). */
static double *positions_double(const float *positions, uint32_t vertex_count) {
    double *d = malloc(((size_t)vertex_count * 3 + 1) * sizeof *d);
    if (d)
        for (size_t i = 0; i < (size_t)vertex_count * 3; i++) d[i] = positions[i];
    return d;
}

#ifndef MR_LOD_KERNEL_V3 /* (what the kernel build below does not use) */
static bool indices_ok(const uint32_t *idx, uint32_t count, uint32_t vertex_count) {
    for (uint32_t i = 0; i < count; i++)
        if (idx[i] >= vertex_count) return false;
    return true;
}
#endif

/* The two-sided bound between prepared surfaces ga (of a) and gb (of b). */
static double hausdorff_prepared(const double *positions, uint32_t vertex_count, const uint32_t *a, uint32_t a_count,
                                 const uint32_t *b, uint32_t b_count, const tri_grid *ga, const tri_grid *gb,
                                 double resolution, double accept, double limit) {
    if (!(limit > 0)) limit = INFINITY;
    if (!(accept > 0)) accept = 0;
    double *da = malloc((size_t)vertex_count * sizeof *da), *db = malloc((size_t)vertex_count * sizeof *db);
    uint32_t *na = malloc((size_t)vertex_count * sizeof *na), *nb = malloc((size_t)vertex_count * sizeof *nb);
    double r = INFINITY;
    if (da && db && na && nb) {
        double lower = 0;
        vertex_distances(positions, vertex_count, a, a_count, gb, limit, da, na, &lower);
        vertex_distances(positions, vertex_count, b, b_count, ga, limit, db, nb, &lower);
        if (isfinite(lower)) {
            double ab = directed_bound(positions, a, a_count, gb, da, na, &lower, resolution, accept, limit);
            double ba = isfinite(ab) ? directed_bound(positions, b, b_count, ga, db, nb, &lower, resolution, accept, limit)
                                     : INFINITY;
            r = dmax(ab, ba);
        }
    }
    free(da);
    free(db);
    free(na);
    free(nb);
    return r;
}

#ifndef MR_LOD_KERNEL_V3
/* The two-sided bound. Vertex distances of both directions come first, so
 * that the largest real distance (lower) is known before any triangle is
 * bounded: no piece is refined below what the Hausdorff distance already is
 * (the vertices of a simplified level lie on the full mesh, so that
 * direction alone would know no lower bound but 0). */
static double hausdorff(const float *positions, uint32_t vertex_count, const uint32_t *a, uint32_t a_count,
                        const uint32_t *b, uint32_t b_count, double resolution, double accept, double limit) {
    if (!positions || vertex_count == 0 || !a || !b || a_count < 3 || b_count < 3) return INFINITY;
    if (!indices_ok(a, a_count, vertex_count) || !indices_ok(b, b_count, vertex_count)) return INFINITY;
    double lo[3], hi[3], ptol;
    vertex_box(positions, vertex_count, lo, hi, &ptol);
    if (!(resolution > 0)) resolution = ptol;
    if (!(resolution > 0)) resolution = 1e-12;
    tri_grid ga, gb;
    memset(&ga, 0, sizeof ga);
    memset(&gb, 0, sizeof gb);
    double r = INFINITY, *dpos = positions_double(positions, vertex_count);
    if (dpos && surface_prepare(&ga, dpos, vertex_count, a, a_count, lo, hi, ptol) &&
        surface_prepare(&gb, dpos, vertex_count, b, b_count, lo, hi, ptol))
        r = hausdorff_prepared(dpos, vertex_count, a, a_count, b, b_count, &ga, &gb, resolution, accept, limit);
    grid_free(&ga);
    grid_free(&gb);
    free(dpos);
    return r;
}

double mr_lod_hausdorff_bound(const float *positions, uint32_t vertex_count, const uint32_t *a, uint32_t a_count,
                              const uint32_t *b, uint32_t b_count, double resolution, double limit) {
    return hausdorff(positions, vertex_count, a, a_count, b, b_count, resolution, 0, limit);
}

double mr_lod_hausdorff_bound_within(const float *positions, uint32_t vertex_count, const uint32_t *a,
                                     uint32_t a_count, const uint32_t *b, uint32_t b_count, double accept,
                                     double resolution, double limit) {
    return hausdorff(positions, vertex_count, a, a_count, b, b_count, resolution, accept, limit);
}

/* ---------------------------------------------------------- building */

void mr_lod_destroy(mr_lod **lp) {
    if (!lp || !*lp) return;
    mr_lod *l = *lp;
    for (int32_t i = 0; l->meshes && i < l->mesh_count; i++)
        for (int32_t k = 0; k < l->meshes[i].level_count; k++) free(l->meshes[i].levels[k].indices);
    free(l->meshes);
    free(l);
    *lp = NULL;
}


uint64_t mr_lod_scene_hash(const mr_scene *s) {
    uint64_t h = 0xcbf29ce484222325ull;
    if (!s) return h;
    h = mr_hash64(h, &s->mesh_count, sizeof s->mesh_count);
    for (int32_t i = 0; i < s->mesh_count; i++) {
        const mr_mesh *m = &s->meshes[i];
        h = mr_hash64(h, &m->vertex_count, sizeof m->vertex_count);
        h = mr_hash64(h, &m->index_count, sizeof m->index_count);
        h = mr_hash64(h, m->positions, (size_t)m->vertex_count * 12);
        h = mr_hash64(h, m->indices, (size_t)m->index_count * 4);
        /* a level's corner is, among the vertices at its position, the one
         * whose normal is nearest the face's (unweld): normals shape it too */
        if (m->normals) h = mr_hash64(h, m->normals, (size_t)m->vertex_count * 12);
    }
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return h;
}

static void resolve(const mr_lod_params *in, mr_lod_params *p) {
    mr_lod_params d = MR_LOD_DEFAULTS;
    *p = in ? *in : d;
    if (!(p->max_error > 0)) p->max_error = 0; /* none: relative to each mesh's size */
    if (!(p->rel_error > 0)) p->rel_error = MR_LOD_DEFAULT_REL_ERROR;
    if (p->min_triangles == 0) p->min_triangles = 64;
}
#endif

/* Position welding. A CAD mesh repeats a position along every normal seam
 * (each face of a box, each segment of a lathed profile has its own
 * vertices), and an edge collapse never crosses such a seam: the simplifier
 * sees a mesh of many small open patches and stops almost at once. So it
 * runs on the index list welded by position (meshopt's shadow index
 * buffer), and each level is mapped back onto the mesh's own vertices
 * afterwards: every corner takes, among the vertices at its position, the
 * one whose normal is closest to the level triangle's face normal, so both
 * sides of a crease keep their own (sharp) normals. Positions are
 * unchanged, hence the error bound holds for the mapped level too. */
typedef struct weld {
    uint32_t *idx;            /* welded index list, degenerate triangles left out */
    size_t count;
    double slack;             /* largest distance of a vertex from its canonical one */
    uint32_t *gstart, *gitem; /* vertices per canonical vertex (CSR) */
    /* The welded mesh as meshoptimizer gets it: only the canonical
     * vertices, renumbered (a vertex buffer that still held the unused
     * duplicates would make meshoptimizer see every seam vertex as a seam of
     * wedges with no triangles, and lock it). idx is in these numbers. */
    float *cpos;              /* 3 * ccount */
    uint32_t *corig;          /* compact -> canonical vertex of the mesh */
    uint32_t ccount;
} weld;

static void weld_free(weld *w) {
    free(w->idx);
    free(w->cpos);
    free(w->corig);
    free(w->gstart);
    free(w->gitem);
    memset(w, 0, sizeof *w);
}

static bool weld_build(const mr_mesh *m, weld *w) {
    memset(w, 0, sizeof *w);
    size_t nv = m->vertex_count;
    w->idx = malloc(((size_t)m->index_count + 1) * sizeof *w->idx);
    uint32_t *canon = malloc((nv + 1) * sizeof *canon);
    w->gstart = calloc(nv + 2, sizeof *w->gstart);
    w->gitem = malloc((nv + 1) * sizeof *w->gitem);
    if (!w->idx || !canon || !w->gstart || !w->gitem) {
        free(canon);
        weld_free(w);
        return false;
    }
    /* Exporters round the same point differently on the two sides of a
     * seam (sin(2 pi) is not 0): positions are welded on a grid of about
     * 1e-6 of the mesh's size, and what that moves is measured exactly and
     * added to every bound (slack). */
    float *q = malloc((nv * 3 + 1) * sizeof *q);
    if (!q) {
        free(canon);
        weld_free(w);
        return false;
    }
    float ext = meshopt_simplifyScale(m->positions, nv, 12);
    double step = ldexp(1.0, (int)floor(log2(ext > 0 ? ext : 1.0)) - 20);
    for (size_t i = 0; i < nv * 3; i++) q[i] = (float)(nearbyint(m->positions[i] / step) * step);
    meshopt_generateShadowIndexBuffer(w->idx, m->indices, m->index_count, q, nv, 12, 12);
    free(q);
    for (size_t v = 0; v < nv; v++) canon[v] = (uint32_t)v;
    for (size_t i = 0; i < m->index_count; i++) canon[m->indices[i]] = w->idx[i];
    w->slack = 0;
    for (size_t v = 0; v < nv; v++) {
        dv d = dv_sub(vtxf(m->positions, (uint32_t)v), vtxf(m->positions, canon[v]));
        w->slack = dmax(w->slack, sqrt(dv_dot(d, d)));
    }
    for (size_t v = 0; v < nv; v++) w->gstart[canon[v] + 2]++;
    for (size_t v = 0; v < nv; v++) w->gstart[v + 2] += w->gstart[v + 1];
    for (size_t v = 0; v < nv; v++) w->gitem[w->gstart[canon[v] + 1]++] = (uint32_t)v;
    free(canon);
    /* Triangles that welding makes degenerate (the fan of a lathed cap at
     * its axis, where a ring of vertices shares one position) are segments
     * on the surface: left out, the simplifier sees a clean manifold. */
    size_t kept = 0;
    for (size_t t = 0; t + 2 < m->index_count; t += 3) {
        uint32_t a = w->idx[t], b = w->idx[t + 1], c = w->idx[t + 2];
        if (a == b || b == c || a == c) continue;
        w->idx[kept++] = a;
        w->idx[kept++] = b;
        w->idx[kept++] = c;
    }
    w->count = kept;
    /* Compact numbering of the canonical vertices used. */
    uint32_t *cid = malloc((nv + 1) * sizeof *cid);
    w->corig = malloc((nv + 1) * sizeof *w->corig);
    if (!cid || !w->corig) {
        free(cid);
        return false;
    }
    for (size_t v = 0; v < nv; v++) cid[v] = UINT32_MAX;
    uint32_t nc = 0;
    for (size_t i = 0; i < kept; i++) {
        uint32_t v = w->idx[i];
        if (cid[v] == UINT32_MAX) {
            cid[v] = nc;
            w->corig[nc++] = v;
        }
        w->idx[i] = cid[v];
    }
    free(cid);
    w->ccount = nc;
    w->cpos = malloc(((size_t)nc * 3 + 1) * sizeof *w->cpos);
    if (!w->cpos) return false;
    for (uint32_t c = 0; c < nc; c++) memcpy(w->cpos + 3 * (size_t)c, m->positions + 3 * (size_t)w->corig[c], 12);
    return true;
}

static void unweld(const mr_mesh *m, const weld *w, const uint32_t *src, uint32_t *dst, size_t n) {
    for (size_t t = 0; t + 2 < n; t += 3) {
        dv a = vtxf(w->cpos, src[t]), b = vtxf(w->cpos, src[t + 1]), c = vtxf(w->cpos, src[t + 2]);
        dv ab = dv_sub(b, a), ac = dv_sub(c, a);
        dv fn = {ab.y * ac.z - ab.z * ac.y, ab.z * ac.x - ab.x * ac.z, ab.x * ac.y - ab.y * ac.x};
        for (int k = 0; k < 3; k++) {
            uint32_t cv = w->corig[src[t + (size_t)k]], best = cv;
            uint32_t g0 = w->gstart[cv], g1 = w->gstart[cv + 1];
            if (m->normals && g1 - g0 > 1) {
                double bd = -INFINITY;
                for (uint32_t j = g0; j < g1; j++) {
                    uint32_t v = w->gitem[j];
                    dv nn = vtxf(m->normals, v);
                    double d = dv_dot(nn, fn);
                    if (d > bd) {
                        bd = d;
                        best = v;
                    }
                }
            }
            dst[t + (size_t)k] = best;
        }
    }
}

/* Levels of one mesh, for the errors cap / 32, cap / 16, ..., cap with
 * cap = rel_error * the mesh's size (or max_error): each level simplifies
 * the previous one (welded by position) by what is left of its error budget
 * (the error so far being certified, the budget is what the simplifier may
 * add), and is then certified against the full mesh. A level is kept if it
 * saves at least 15 % of the triangles of the one before. */
static bool build_mesh(const mr_mesh *m, const mr_lod_params *p, mr_mesh_lods *out) {
    memset(out, 0, sizeof *out);
    if (m->index_count / 3 < p->min_triangles || m->vertex_count == 0) return true;
    float scale = meshopt_simplifyScale(m->positions, m->vertex_count, 12);
    if (!(scale > 0) || !isfinite(scale)) return true;
    double cap = p->max_error > 0 ? p->max_error : p->rel_error * scale;
    weld w;
    if (!weld_build(m, &w)) {
        weld_free(&w);
        return false;
    }
    uint32_t *buf[3] = {malloc(((size_t)m->index_count + 1) * sizeof *buf[0]),
                        malloc(((size_t)m->index_count + 1) * sizeof *buf[1]),
                        malloc(((size_t)m->index_count + 1) * sizeof *buf[2])};
    if (!buf[0] || !buf[1] || !buf[2]) {
        free(buf[0]);
        free(buf[1]);
        free(buf[2]);
        weld_free(&w);
        return false;
    }
    /* Three buffers rotate: the source (the welded mesh at first), the
     * result and a second result to compare. */
    int si = -1;
    size_t src_n = w.count;
    double src_err = 0;
    if (src_n < 3) {
        free(buf[0]);
        free(buf[1]);
        free(buf[2]);
        weld_free(&w);
        return true;
    }
    bool ok = true;
    double lo[3], hi[3], ptol;
    vertex_box(w.cpos, w.ccount, lo, hi, &ptol);
    tri_grid gsrc;
    memset(&gsrc, 0, sizeof gsrc);
    double *dpos = NULL; /* (made when the first level is to be certified) */
    bool gsrc_ready = false;
    double ratio = 0; /* least certified step / meshopt's estimate so far (0: none yet) */
    for (int k = MR_LOD_MAX_LEVELS - 1; k >= 0 && out->level_count < MR_LOD_MAX_LEVELS; k--) {
        double target = cap / (double)(1u << k);
        double step = target - src_err;
        /* A step of under a quarter of its level's error: measured, such
         * attempts (the next level right above a chained error) never
         * saved the 15 % a level must, and a simplification costs what
         * its source has. */
        if (!(step > 0.25 * target)) continue;
        /* Not tried either: a level whose bound would exceed the cap at
         * the least ratio of certified error to meshopt's own estimate seen
         * on this mesh's kept levels (meshopt's estimate runs up to the
         * step it is given). Measured on the 2M unique factory: the ratio
         * is 2.3 to 4.2 (median 3), so the last level (its step all the
         * room left) was always dropped after its simplification and bound
         * had been paid for: 3.6 % of the first build, same levels. */
        if (ratio > 1 && src_err + ratio * step > cap) continue;
        const uint32_t *src = si < 0 ? w.idx : buf[si];
        int di = si < 0 ? 0 : (si + 1) % 3, d2 = si < 0 ? 1 : (si + 2) % 3;
        uint32_t *dst = buf[di], *dst2 = buf[d2];
        float est = 0;
        size_t n = meshopt_simplify(dst, src, src_n, w.cpos, w.ccount, 12, 0, (float)(step / scale), 0, &est);
        if (n > src_n / 2) {
            /* Edge collapses stall on some shapes (thin tori, long lathed
             * strips); vertex clustering does not, and its result indexes
             * the same vertices. Its error is certified like any other. */
            float est2 = 0;
            size_t n2 = meshopt_simplifySloppy(dst2, src, src_n, w.cpos, w.ccount, 12, 0, (float)(step / scale), &est2);
            if (n2 >= 3 && n2 < n) {
                dst = dst2;
                di = d2;
                n = n2;
            }
        }
        if (n < 3) break;
        if (n > (size_t)(src_n * 0.85)) continue; /* too little saved: try the next, larger error */
        /* Certified against the source level (welded), chained by the
         * triangle inequality: H(level, full) <= H(level, source) +
         * H(source, full), the latter certified before. Each step then
         * costs what its source has (a geometric series over the levels;
         * measured: 2.4x faster than each level against the full mesh), at
         * the price of a looser bound (the steps' errors add up; up to
         * about twice the sampled truth on the tests' shapes). Pieces are
         * refined only where their bound exceeds the step's budget and is
         * more than a quarter over the largest real distance found.
         * Resolution: a small part of the level's error budget; it only
         * ever adds to the bound. */
        double res = dmax(0.05 * target, 1e-6 * scale);
        /* Searched only out to what the level may add and still be kept
         * (beyond: INFINITY, the level is dropped as it would be anyway),
         * so a level that fails gives up early. */
        double room = cap - src_err - 2 * w.slack;
        if (!(room > 0)) break;
        /* The source's grid is the last kept level's (prepared once). */
        tri_grid gdst;
        memset(&gdst, 0, sizeof gdst);
        if (!dpos) dpos = positions_double(w.cpos, w.ccount);
        if (!dpos || (!gsrc_ready && !surface_prepare(&gsrc, dpos, w.ccount, src, (uint32_t)src_n, lo, hi, ptol)) ||
            !surface_prepare(&gdst, dpos, w.ccount, dst, (uint32_t)n, lo, hi, ptol)) {
            grid_free(&gdst);
            ok = false;
            break;
        }
        gsrc_ready = true;
        double e = src_err + hausdorff_prepared(dpos, w.ccount, src, (uint32_t)src_n, dst, (uint32_t)n, &gsrc, &gdst,
                                                res, res, room * (1 + 1e-9));
        if (!(e + 2 * w.slack <= cap)) {
            grid_free(&gdst);
            break; /* coarser levels only get worse */
        }
        grid_free(&gsrc);
        gsrc = gdst; /* this level is the next one's source (its idx is dst, kept as buf[di]) */
        mr_lod_level *l = &out->levels[out->level_count];
        l->indices = malloc(n * sizeof *l->indices);
        if (!l->indices) {
            ok = false;
            break;
        }
        unweld(m, &w, dst, l->indices, n);
        l->index_count = (uint32_t)n;
        /* The welded surfaces differ from the mesh's own (full, and the
         * level mapped back) by at most the weld's slack each. */
        l->error = dmax(e + 2 * w.slack, src_err + 2 * w.slack); /* kept increasing for the renderer */
        out->level_count++;
        /* This level (welded) is the next one's source. */
        si = di;
        src_n = n;
        if (est > 0 && e > src_err) {
            double r = (e - src_err) / ((double)est * scale);
            if (ratio == 0 || r < ratio) ratio = r;
        }
        src_err = e;
    }
    grid_free(&gsrc);
    free(dpos);
    free(buf[0]);
    free(buf[1]);
    free(buf[2]);
    weld_free(&w);
    return ok;
}

#ifdef MR_LOD_KERNEL_V3
bool mr_lod_build_mesh_v3(const mr_mesh *m, const mr_lod_params *p, mr_mesh_lods *out) { return build_mesh(m, p, out); }
#else

/* The kernel for this CPU: the same code compiled for x86-64-v3 (AVX2,
 * FMA; lod_v3.c) where the CPU has it and the build made it, else the
 * portable one. Measured on the 2M unique factory, 12 alternating pairs:
 * median CPU 3.87 s against 4.22 s (-8 %), identical levels and errors. */
static bool use_v3(const mr_lod_params *p) {
#if defined(MR_LOD_HAVE_V3) && defined(__clang__) /* (no "x86-64-v3" in clang 14: its main parts) */
    return !p->portable && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
           __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
#elif defined(MR_LOD_HAVE_V3)
    return !p->portable && __builtin_cpu_supports("x86-64-v3");
#else
    (void)p;
    return false;
#endif
}

const char *mr_lod_kernel(const mr_lod_params *params) {
    mr_lod_params d = MR_LOD_DEFAULTS;
    return use_v3(params ? params : &d) ? "x86-64-v3" : "portable";
}

static bool build_mesh_for_cpu(const mr_mesh *m, const mr_lod_params *p, mr_mesh_lods *out) {
#ifdef MR_LOD_HAVE_V3
    if (use_v3(p)) return mr_lod_build_mesh_v3(m, p, out);
#endif
    return build_mesh(m, p, out);
}

/* Meshes are independent: workers take the next mesh from a shared
 * counter, largest meshes first so the last one does not run alone. */
typedef struct build_job {
    const mr_scene *s;
    const mr_lod_params *p;
    mr_lod *l;
    const int32_t *order;
    pthread_mutex_t lock;
    int32_t done;
    uint64_t tri_total, tri_done; /* input triangles, for the progress line */
    int32_t failed;          /* mesh that ran out of memory, or -1 */
    bool cancelled;          /* params' on_progress said stop */
    double t0;
    bool shown;
} build_job;

static bool build_one(void *arg, size_t k) {
    build_job *j = arg;
    int32_t i = j->order[k];
    bool ok = build_mesh_for_cpu(&j->s->meshes[i], j->p, &j->l->meshes[i]);
    pthread_mutex_lock(&j->lock);
    if (!ok && j->failed < 0) j->failed = i;
    j->done++;
    j->tri_done += j->s->meshes[i].index_count / 3;
    double dt = mr_time_now() - j->t0;
    if (j->p->progress && dt > 1.0) {
        fprintf(stderr, "\rLOD: mesh %d of %d, %.2f of %.2f M triangles (%.0f triangles/s)   ", (int)j->done,
                (int)j->s->mesh_count, j->tri_done / 1e6, j->tri_total / 1e6, j->tri_done / dt);
        fflush(stderr);
        j->shown = true;
    }
    if (j->p->on_progress && !j->cancelled &&
        !j->p->on_progress(j->p->progress_user, j->tri_total ? (double)j->tri_done / (double)j->tri_total : 1.0))
        j->cancelled = true;
    bool go = ok && !j->cancelled;
    pthread_mutex_unlock(&j->lock);
    return go; /* out of memory or cancelled: no further mesh is started */
}

mr_lod *mr_lod_build(const mr_scene *s, const mr_lod_params *params, mr_error *err) {
    if (!s) {
        mr_fail(err, MR_ERR_INVALID, "no scene");
        return NULL;
    }
    mr_lod_params p;
    resolve(params, &p);
    mr_lod *l = calloc(1, sizeof *l);
    if (l) l->meshes = calloc((size_t)s->mesh_count + 1, sizeof *l->meshes);
    int32_t *order = malloc(((size_t)s->mesh_count + 1) * sizeof *order);
    if (!l || !l->meshes || !order) {
        free(order);
        mr_lod_destroy(&l);
        mr_fail(err, MR_ERR_NOMEM, "out of memory for LOD levels");
        return NULL;
    }
    l->mesh_count = s->mesh_count;
    l->scene_hash = mr_lod_scene_hash(s);
    /* Largest first (insertion sort: mesh counts are small; very large
     * counts keep file order). */
    for (int32_t i = 0; i < s->mesh_count; i++) order[i] = i;
    for (int32_t i = 1; i < s->mesh_count && s->mesh_count <= 4096; i++) {
        int32_t v = order[i], k = i;
        while (k > 0 && s->meshes[order[k - 1]].index_count < s->meshes[v].index_count) {
            order[k] = order[k - 1];
            k--;
        }
        order[k] = v;
    }
    build_job j;
    memset(&j, 0, sizeof j);
    j.s = s;
    j.p = &p;
    j.l = l;
    j.order = order;
    j.failed = -1;
    j.t0 = mr_time_now();
    for (int32_t i = 0; i < s->mesh_count; i++) j.tri_total += s->meshes[i].index_count / 3;
    pthread_mutex_init(&j.lock, NULL); /* the progress line and the failure */
    mr_parallel_for((size_t)s->mesh_count, 0, build_one, &j);
    pthread_mutex_destroy(&j.lock);
    free(order);
    if (j.shown) fprintf(stderr, "\r%80s\r", "");
    if (j.failed >= 0) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory simplifying mesh '%s'", s->meshes[j.failed].name);
        mr_lod_destroy(&l);
        return NULL;
    }
    if (j.cancelled) {
        mr_fail(err, MR_ERR_INVALID, "LOD build cancelled");
        mr_lod_destroy(&l);
        return NULL;
    }
    return l;
}

/* -------------------------------------------------------------- cache */

#define CACHE_MAGIC "MRLOD\r\n\x1a"
#define CACHE_VERSION 7u /* bump whenever simplification or certification changes */

void mr_lod_cache_path(const char *scene_path, char *out, size_t n) {
    snprintf(out, n, "%s.mrlod", scene_path ? scene_path : "scene");
}

typedef struct wbuf {
    unsigned char *p;
    size_t n, cap;
    bool oom;
} wbuf;

static void put(wbuf *b, const void *d, size_t n) {
    if (b->oom) return;
    if (b->n + n > b->cap) {
        size_t c = b->cap ? b->cap : 4096;
        while (c < b->n + n) c *= 2;
        unsigned char *q = realloc(b->p, c);
        if (!q) { b->oom = true; return; }
        b->p = q;
        b->cap = c;
    }
    memcpy(b->p + b->n, d, n);
    b->n += n;
}

static bool cache_write(const mr_lod *l, const mr_lod_params *p, const char *path, mr_error *err) {
    wbuf b = {0};
    uint32_t ver = CACHE_VERSION, mc = (uint32_t)l->mesh_count, mt = p->min_triangles;
    put(&b, CACHE_MAGIC, 8);
    put(&b, &ver, 4);
    put(&b, &mc, 4);
    put(&b, &l->scene_hash, 8);
    put(&b, &p->max_error, 8);
    put(&b, &mt, 4);
    put(&b, &p->rel_error, 8);
    for (int32_t i = 0; i < l->mesh_count; i++) {
        uint32_t lc = (uint32_t)l->meshes[i].level_count;
        put(&b, &lc, 4);
        for (uint32_t k = 0; k < lc; k++) {
            const mr_lod_level *lv = &l->meshes[i].levels[k];
            put(&b, &lv->index_count, 4);
            put(&b, &lv->error, 8);
            put(&b, lv->indices, (size_t)lv->index_count * 4);
        }
    }
    uint64_t sum = b.oom ? 0 : mr_hash64(0x9e3779b97f4a7c15ull, b.p, b.n);
    put(&b, &sum, 8);
    bool ok = !b.oom && mr_file_write_atomic(path, b.p, b.n, err);
    if (b.oom) mr_fail(err, MR_ERR_NOMEM, "out of memory writing %s", path);
    free(b.p);
    return ok;
}

typedef struct rbuf {
    const unsigned char *p;
    size_t n, at;
} rbuf;

static bool get(rbuf *r, void *d, size_t n) {
    if (n > r->n - r->at) return false;
    memcpy(d, r->p + r->at, n);
    r->at += n;
    return true;
}

/* NULL (with the reason in *why) unless the file holds levels for exactly
 * this geometry and these params, intact and in range. */
static mr_lod *cache_read(const mr_scene *s, const mr_lod_params *p, const char *path, const char **why) {
    size_t size = 0;
    mr_error e;
    unsigned char *data = mr_file_read(path, &size, 0, &e);
    if (!data) {
        *why = "no cache";
        return NULL;
    }
    rbuf r = {data, size, 0};
    char magic[8];
    uint32_t ver, mc, mt;
    uint64_t hash, sum;
    double maxe, rele;
    mr_lod *l = NULL;
    *why = "not a LOD cache";
    if (size < 8 + 8 || !get(&r, magic, 8) || memcmp(magic, CACHE_MAGIC, 8) != 0) goto out;
    memcpy(&sum, data + size - 8, 8);
    *why = "checksum mismatch (truncated or damaged)";
    if (mr_hash64(0x9e3779b97f4a7c15ull, data, size - 8) != sum) goto out;
    r.n = size - 8;
    *why = "written for another scene or other settings";
    if (!get(&r, &ver, 4) || ver != CACHE_VERSION || !get(&r, &mc, 4) || mc != (uint32_t)s->mesh_count ||
        !get(&r, &hash, 8) || hash != mr_lod_scene_hash(s) || !get(&r, &maxe, 8) || maxe != p->max_error ||
        !get(&r, &mt, 4) || mt != p->min_triangles || !get(&r, &rele, 8) || rele != p->rel_error)
        goto out;
    l = calloc(1, sizeof *l);
    if (!l || !(l->meshes = calloc((size_t)mc + 1, sizeof *l->meshes))) {
        *why = "out of memory";
        goto fail;
    }
    l->mesh_count = (int32_t)mc;
    l->scene_hash = hash;
    *why = "malformed";
    for (uint32_t i = 0; i < mc; i++) {
        const mr_mesh *m = &s->meshes[i];
        uint32_t lc;
        if (!get(&r, &lc, 4) || lc > MR_LOD_MAX_LEVELS) goto fail;
        double prev = 0;
        for (uint32_t k = 0; k < lc; k++) {
            mr_lod_level *lv = &l->meshes[i].levels[k];
            if (!get(&r, &lv->index_count, 4) || !get(&r, &lv->error, 8)) goto fail;
            if (lv->index_count == 0 || lv->index_count % 3 || lv->index_count > m->index_count ||
                !(lv->error >= prev) || !isfinite(lv->error) || (size_t)lv->index_count * 4 > r.n - r.at)
                goto fail;
            prev = lv->error;
            lv->indices = malloc((size_t)lv->index_count * 4);
            if (!lv->indices) goto fail;
            l->meshes[i].level_count = (int32_t)k + 1;
            get(&r, lv->indices, (size_t)lv->index_count * 4);
            for (uint32_t j = 0; j < lv->index_count; j++)
                if (lv->indices[j] >= m->vertex_count) goto fail;
        }
    }
    if (r.at != r.n) goto fail;
    *why = NULL;
    goto out;
fail:
    mr_lod_destroy(&l);
out:
    free(data);
    return l;
}

mr_lod *mr_lod_load_or_build(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                             mr_lod_info *info, mr_error *err) {
    mr_lod_info li;
    memset(&li, 0, sizeof li);
    if (!s) {
        mr_fail(err, MR_ERR_INVALID, "no scene");
        return NULL;
    }
    mr_lod_params p;
    resolve(params, &p);
    mr_lod *l = NULL;
    if (cache_path) {
        const char *why = NULL;
        l = cache_read(s, &p, cache_path, &why);
        if (l) li.from_cache = true;
        else if (why && strcmp(why, "no cache") != 0)
            mr_log(MR_LOG_WARN, "%s: ignored (%s); rebuilding the LOD levels", cache_path, why);
    }
    if (!l) {
        double t0 = mr_time_now();
        l = mr_lod_build(s, &p, err);
        if (!l) return NULL;
        li.build_s = mr_time_now() - t0;
        for (int32_t i = 0; i < s->mesh_count; i++) li.triangles += s->meshes[i].index_count / 3;
        if (cache_path) {
            mr_error we = {0};
            li.cache_written = cache_write(l, &p, cache_path, &we);
            if (!li.cache_written) mr_log(MR_LOG_WARN, "LOD cache not written: %s", we.msg);
        }
    }
    for (int32_t i = 0; i < l->mesh_count; i++) li.levels += (uint64_t)l->meshes[i].level_count;
    if (info) *info = li;
    return l;
}

#endif /* MR_LOD_KERNEL_V3 */
