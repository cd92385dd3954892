/* One Euro filter (Casiez et al., CHI 2012) on a rigid pose: translation per
 * axis with a shared speed-adaptive cutoff; rotation in the tangent space of
 * the filtered rotation (the step towards the raw rotation is a rotation
 * vector, scaled by the low-pass factor and applied on the right), so it
 * never leaves SO(3) and has no Euler-angle wrap. */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct mr_pose_filter {
    mr_filter_params p;
    bool have;            /* a sample was seen since the last reset */
    bool frozen;
    double t_last;
    mr_dmat4 raw_last;    /* previous raw sample: jump detection */
    mr_dmat4 out;         /* filtered pose */
    double dx_hat[3];     /* filtered translation speed */
    double dr_hat;        /* filtered angular speed, rad/s */
};

static double or_default(double v, double d) { return v > 0 && isfinite(v) ? v : d; }

mr_pose_filter *mr_pose_filter_create(const mr_filter_params *params, mr_error *err) {
    mr_filter_params p = params ? *params : (mr_filter_params)MR_FILTER_DEFAULTS;
    if (!isfinite(p.min_cutoff) || !isfinite(p.beta) || p.min_cutoff < 0 || p.beta < 0 || p.rot_beta < 0 ||
        p.rot_min_cutoff < 0 || p.d_cutoff < 0 || p.jump_dist < 0 || p.jump_deg < 0 || p.max_gap_s < 0) {
        mr_fail(err, MR_ERR_INVALID, "filter parameters must be finite and >= 0");
        return NULL;
    }
    p.min_cutoff = or_default(p.min_cutoff, MR_FILTER_DEFAULT_MIN_CUTOFF);
    p.beta = or_default(p.beta, MR_FILTER_DEFAULT_BETA);
    p.d_cutoff = or_default(p.d_cutoff, MR_FILTER_DEFAULT_D_CUTOFF);
    p.rot_min_cutoff = or_default(p.rot_min_cutoff, MR_FILTER_DEFAULT_ROT_MIN_CUTOFF);
    p.rot_beta = or_default(p.rot_beta, MR_FILTER_DEFAULT_ROT_BETA);
    p.jump_dist = or_default(p.jump_dist, MR_FILTER_DEFAULT_JUMP_DIST);
    p.jump_deg = or_default(p.jump_deg, MR_FILTER_DEFAULT_JUMP_DEG);
    p.max_gap_s = or_default(p.max_gap_s, MR_FILTER_DEFAULT_MAX_GAP_S);
    mr_pose_filter *f = calloc(1, sizeof *f);
    if (!f) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    f->p = p;
    f->out = mr_m4_identity();
    return f;
}

void mr_pose_filter_destroy(mr_pose_filter **f) {
    if (!f) return;
    free(*f);
    *f = NULL;
}

void mr_pose_filter_reset(mr_pose_filter *f) {
    f->have = false;
    memset(f->dx_hat, 0, sizeof f->dx_hat);
    f->dr_hat = 0;
}

void mr_pose_filter_freeze(mr_pose_filter *f, bool frozen) {
    if (f->frozen && !frozen) mr_pose_filter_reset(f);
    f->frozen = frozen;
}

bool mr_pose_filter_frozen(const mr_pose_filter *f) { return f->frozen; }

bool mr_pose_filter_last(const mr_pose_filter *f, mr_dmat4 *out) {
    *out = f->out;
    return f->have || f->frozen;
}

/* Smoothing factor of an exponential low-pass with cutoff fc at step dt. */
static double lp_alpha(double fc, double dt) {
    double tau = 1.0 / (2.0 * M_PI * fc);
    return 1.0 / (1.0 + tau / dt);
}

/* Gram-Schmidt on the rows, so rounding from thousands of small steps does
 * not let the rotation drift away from SO(3). */
static void orthonormalize(double R[9]) {
    double *a = R, *b = R + 3, *c = R + 6;
    double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int i = 0; i < 3; i++) a[i] /= n;
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for (int i = 0; i < 3; i++) b[i] -= d * a[i];
    n = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    for (int i = 0; i < 3; i++) b[i] /= n;
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

bool mr_pose_filter_update(mr_pose_filter *f, double t, const mr_dmat4 *raw, mr_dmat4 *out) {
    if (f->frozen) {
        *out = f->out;
        return false;
    }
    bool reset = !f->have || !mr_m4_is_finite(raw);
    double dt = t - f->t_last;
    if (!reset && (!(dt > 0) || dt > f->p.max_gap_s)) reset = true;
    if (!reset && (mr_pose_dist(raw, &f->raw_last) > f->p.jump_dist ||
                   mr_pose_angle_deg(raw, &f->raw_last) > f->p.jump_deg))
        reset = true;
    f->t_last = t;
    f->raw_last = *raw;
    if (reset || !mr_m4_is_finite(raw)) {
        mr_pose_filter_reset(f);
        f->have = mr_m4_is_finite(raw);
        if (f->have) f->out = *raw;
        *out = f->out;
        return true;
    }
    /* Translation. */
    double dx[3], speed = 0;
    double a_d = lp_alpha(f->p.d_cutoff, dt);
    for (int i = 0; i < 3; i++) {
        dx[i] = (raw->m[i * 4 + 3] - f->out.m[i * 4 + 3]) / dt;
        f->dx_hat[i] += a_d * (dx[i] - f->dx_hat[i]);
        speed += f->dx_hat[i] * f->dx_hat[i];
    }
    double a = lp_alpha(f->p.min_cutoff + f->p.beta * sqrt(speed), dt);
    for (int i = 0; i < 3; i++) f->out.m[i * 4 + 3] += a * (raw->m[i * 4 + 3] - f->out.m[i * 4 + 3]);
    /* Rotation: delta = log(Rf^T Rraw), body frame. */
    double Rf[9], Rr[9], D[9], rv[3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            Rf[r * 3 + c] = f->out.m[r * 4 + c];
            Rr[r * 3 + c] = raw->m[r * 4 + c];
        }
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) D[r * 3 + c] = Rf[0 * 3 + r] * Rr[0 * 3 + c] + Rf[1 * 3 + r] * Rr[1 * 3 + c] + Rf[2 * 3 + r] * Rr[2 * 3 + c];
    mr_mat_to_rotvec(D, rv);
    double w = sqrt(rv[0] * rv[0] + rv[1] * rv[1] + rv[2] * rv[2]) / dt;
    f->dr_hat += a_d * (w - f->dr_hat);
    double ar = lp_alpha(f->p.rot_min_cutoff + f->p.rot_beta * f->dr_hat, dt);
    double step[3] = {ar * rv[0], ar * rv[1], ar * rv[2]}, S[9], Rn[9];
    mr_rotvec_to_mat(step, S);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) Rn[r * 3 + c] = Rf[r * 3] * S[c] + Rf[r * 3 + 1] * S[3 + c] + Rf[r * 3 + 2] * S[6 + c];
    orthonormalize(Rn);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) f->out.m[r * 4 + c] = Rn[r * 3 + c];
    *out = f->out;
    return false;
}
