/* mr_test_lod.h — brute-force distances between triangle sets, the
 * reference the LOD tests hold the certified error bound against (include
 * after mr_test.h). */
#ifndef MR_TEST_LOD_H
#define MR_TEST_LOD_H

#include <math.h>
#include <stdint.h>
#include <stddef.h>

static inline double mr_test_tri_dist2(const double p[3], const float *a, const float *b, const float *c) {
    /* Brute force: dense barycentric sampling is not exact, so compute the
     * exact distance by projecting onto the plane and the edges. */
    double ab[3], ac[3], ap[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
    double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    double best = INFINITY;
    if (nn > 0) {
        double t = (ap[0] * n[0] + ap[1] * n[1] + ap[2] * n[2]) / nn;
        double q[3] = {p[0] - t * n[0], p[1] - t * n[1], p[2] - t * n[2]};
        /* inside test by barycentric signs */
        const float *v[3] = {a, b, c};
        bool inside = true;
        for (int e = 0; e < 3; e++) {
            const float *p0 = v[e], *p1 = v[(e + 1) % 3];
            double ed[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, qp[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
            double cr[3] = {ed[1] * qp[2] - ed[2] * qp[1], ed[2] * qp[0] - ed[0] * qp[2], ed[0] * qp[1] - ed[1] * qp[0]};
            if (cr[0] * n[0] + cr[1] * n[1] + cr[2] * n[2] < 0) inside = false;
        }
        if (inside) best = t * t * nn;
    }
    const float *v[3] = {a, b, c};
    for (int e = 0; e < 3; e++) {
        const float *p0 = v[e], *p1 = v[(e + 1) % 3];
        double ed[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double ee = ed[0] * ed[0] + ed[1] * ed[1] + ed[2] * ed[2];
        double t = ee > 0 ? ((p[0] - p0[0]) * ed[0] + (p[1] - p0[1]) * ed[1] + (p[2] - p0[2]) * ed[2]) / ee : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double d[3] = {p[0] - p0[0] - t * ed[0], p[1] - p0[1] - t * ed[1], p[2] - p0[2] - t * ed[2]};
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (d2 < best) best = d2;
    }
    return best;
}

/* Max over dense samples of `from` of the distance to `to` (brute force). */
static inline double mr_test_sampled_distance(const float *pos, const uint32_t *from, uint32_t nf, const uint32_t *to, uint32_t nt, int k) {
    double worst = 0;
    for (uint32_t t = 0; t < nf; t += 3) {
        const float *a = pos + 3 * (size_t)from[t], *b = pos + 3 * (size_t)from[t + 1], *c = pos + 3 * (size_t)from[t + 2];
        for (int i = 0; i <= k; i++)
            for (int j = 0; i + j <= k; j++) {
                double u = (double)i / k, v = (double)j / k, w = 1 - u - v;
                double p[3] = {w * a[0] + u * b[0] + v * c[0], w * a[1] + u * b[1] + v * c[1], w * a[2] + u * b[2] + v * c[2]};
                double best = INFINITY;
                for (uint32_t s = 0; s < nt; s += 3) {
                    double d2 = mr_test_tri_dist2(p, pos + 3 * (size_t)to[s], pos + 3 * (size_t)to[s + 1], pos + 3 * (size_t)to[s + 2]);
                    if (d2 < best) best = d2;
                }
                if (sqrt(best) > worst) worst = sqrt(best);
            }
    }
    return worst;
}

#endif
