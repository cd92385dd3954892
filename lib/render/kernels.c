/* Sampling kernels shared by the passes that sample a ball or a disk
 * around a point (the AO methods' offsets, the shadow pass's filter taps,
 * the fetch-floor probe): stratified, Latin hypercube, Poisson disk or
 * plain random, from one seed so a frame is reproducible. */
#include "mr_render.h"

#include <math.h>
#include <string.h>

static void shuffle(mr_rng *rng, int *perm, int n) {
    for (int i = 0; i < n; i++) perm[i] = i;
    for (int i = n - 1; i > 0; i--) {
        int j = (int)(mr_rng_uniform(rng) * (i + 1));
        if (j > i) j = i;
        int t = perm[i]; perm[i] = perm[j]; perm[j] = t;
    }
}

/* Unit-cube coordinates (u1,u2,u3) to the ball shell [rmin, rmax] with
 * uniform volume density, and (u1,u2) to the disk annulus with uniform
 * area density. */
static void to_ball(double u1, double u2, double u3, double rmin, double rmax, float *o) {
    double z = 1 - 2 * u1, phi = 2 * 3.14159265358979323846 * u2, s = sqrt(fmax(0, 1 - z * z));
    double r = cbrt(rmin * rmin * rmin + u3 * (rmax * rmax * rmax - rmin * rmin * rmin));
    o[0] = (float)(r * s * cos(phi));
    o[1] = (float)(r * s * sin(phi));
    o[2] = (float)(r * z);
}

static void to_disk(double u1, double u2, double rmin, double rmax, float *o) {
    double r = sqrt(rmin * rmin + u1 * (rmax * rmax - rmin * rmin)), a = 2 * 3.14159265358979323846 * u2;
    o[0] = (float)(r * cos(a));
    o[1] = (float)(r * sin(a));
}

/* Poisson disk by dart throwing in the shell (dim 3) or annulus (dim 2):
 * candidates closer than dmin to an accepted point are rejected; dmin
 * shrinks by 10% whenever 64 candidates in a row fail, so n points are
 * always found. */
static void poisson(mr_rng *rng, int n, int dim, double rmin, double rmax, float *out, int stride) {
    double d;
    if (dim == 3) {
        double vol = 4.0 / 3.0 * 3.14159265358979323846 * (rmax * rmax * rmax - rmin * rmin * rmin);
        double area = 4 * 3.14159265358979323846 * rmax * rmax;
        d = rmax - rmin > 0.05 ? 0.85 * cbrt(vol / n) : 0.85 * sqrt(area / n);
    } else {
        double area = 3.14159265358979323846 * (rmax * rmax - rmin * rmin);
        d = rmax - rmin > 0.05 ? 0.85 * sqrt(area / n) : 0.85 * 2 * 3.14159265358979323846 * rmax / n;
    }
    int have = 0, fails = 0;
    while (have < n) {
        float c[3] = {0, 0, 0};
        if (dim == 3) to_ball(mr_rng_uniform(rng), mr_rng_uniform(rng), mr_rng_uniform(rng), rmin, rmax, c);
        else to_disk(mr_rng_uniform(rng), mr_rng_uniform(rng), rmin, rmax, c);
        bool ok = true;
        for (int j = 0; j < have && ok; j++) {
            double s = 0;
            for (int k = 0; k < dim; k++) s += (c[k] - out[j * stride + k]) * (c[k] - out[j * stride + k]);
            ok = s >= d * d;
        }
        if (ok) {
            for (int k = 0; k < dim; k++) out[have * stride + k] = c[k];
            have++;
            fails = 0;
        } else if (++fails >= 64) {
            d *= 0.9;
            fails = 0;
        }
    }
}

void mr_ao_kernel_generate(mr_ao_kernel kind, int n, float r_min, float r_max, uint64_t seed, float *out3, float *out2) {
    if (n <= 0) return;
    if (n > MR_AO_MAX_SAMPLES) n = MR_AO_MAX_SAMPLES;
    double rmax = r_max > 0 && r_max <= 1 ? r_max : 1.0;
    double rmin = r_min >= 0 ? r_min : 0.0;
    if (rmin > rmax) rmin = rmax;
    mr_rng rng;
    mr_rng_seed(&rng, seed);
    if (kind == MR_AO_KERNEL_POISSON) {
        if (out3) poisson(&rng, n, 3, rmin, rmax, out3, 3);
        if (out2) poisson(&rng, n, 2, 0.0, rmax, out2, 2);
        return;
    }
    int p1[MR_AO_MAX_SAMPLES], p2[MR_AO_MAX_SAMPLES], p3[MR_AO_MAX_SAMPLES];
    shuffle(&rng, p1, n);
    shuffle(&rng, p2, n);
    shuffle(&rng, p3, n);
    int nx = 1; /* stratified: an nx x ny grid over the two direction coordinates */
    for (int k = 1; k * k <= n; k++)
        if (n % k == 0) nx = k;
    int ny = n / nx;
    for (int i = 0; i < n; i++) {
        double u1, u2, u3;
        if (kind == MR_AO_KERNEL_STRATIFIED) {
            u1 = ((i % nx) + mr_rng_uniform(&rng)) / nx;
            u2 = ((i / nx) + mr_rng_uniform(&rng)) / ny;
            u3 = (p3[i] + mr_rng_uniform(&rng)) / n;
        } else if (kind == MR_AO_KERNEL_LATIN) {
            u1 = (p1[i] + mr_rng_uniform(&rng)) / n;
            u2 = (p2[i] + mr_rng_uniform(&rng)) / n;
            u3 = (p3[i] + mr_rng_uniform(&rng)) / n;
        } else {
            u1 = mr_rng_uniform(&rng);
            u2 = mr_rng_uniform(&rng);
            u3 = mr_rng_uniform(&rng);
        }
        if (out3) to_ball(u1, u2, u3, rmin, rmax, out3 + 3 * i);
        if (out2) to_disk(u1, u2, 0.0, rmax, out2 + 2 * i);
    }
}
