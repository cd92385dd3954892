/* The One Euro pose filter (lib/track/filter.c) against its exact discrete
 * behaviour: lag under constant velocity and angular velocity, the
 * transient, the jump and gap resets at their thresholds.
 *
 * A ramp along one direction (translation) or about one fixed body axis
 * (rotation: raw = base * Rot(axis, θ), and the filter steps by
 * exp(α log(Rf^T Rraw)) on the right) keeps the filter one-dimensional, so
 * it must follow the scalar One Euro recursion of Casiez et al. exactly:
 *     d_k  = (x_k - y_{k-1}) / dt            speed from the last output
 *     d̂_k  = d̂_{k-1} + α(f_d, dt) (d_k - d̂_{k-1})
 *     f_k  = f_min + β |d̂_k|
 *     y_k  = y_{k-1} + α(f_k, dt) (x_k - y_{k-1})
 * with α(f, dt) = 1 / (1 + τ/dt), τ = 1/(2π f); a reset sets y = x, d̂ = 0.
 *
 * Steady state of a ramp x_k = v k dt (derived, not simulated): a constant
 * lag L = x_k - y_k needs y_k - y_{k-1} = v dt = α (L + v dt), so
 * L = v dt (1-α)/α = v τ exactly (no discretisation term with this α).
 * The speed estimate settles at d̂ = (L + v dt)/dt = v/α = v (1 + τ/dt)
 * (it sees the lag, so it overestimates v), whatever f_d is; hence
 * f = f_min + β v + β v / (2π f dt), i.e.
 *     f² - (f_min + β v) f - β v / (2π dt) = 0,
 *     L = v / (2π f)   with f the positive root.
 * f_d only shapes the transient, which the scalar recursion pins. */
#include "mr_track.h"
#include "mr_test.h"

#include <string.h>

/* ------------------------------------------------------------ helpers */

static double alpha(double f, double dt) { return 1.0 / (1.0 + 1.0 / (2.0 * M_PI * f * dt)); }

/* The scalar One Euro filter written from the paper (the oracle). */
typedef struct one_euro { double f_min, beta, f_d, y, dh; } one_euro;

static void oe_reset(one_euro *s, double x) {
    s->y = x;
    s->dh = 0;
}

static void oe_step(one_euro *s, double x, double dt) {
    double d = (x - s->y) / dt;
    s->dh += alpha(s->f_d, dt) * (d - s->dh);
    s->y += alpha(s->f_min + s->beta * fabs(s->dh), dt) * (x - s->y);
}

/* Steady-state lag of a ramp at speed v (derivation above). */
static double steady_lag(double f_min, double beta, double v, double dt) {
    double b = f_min + beta * v, f = 0.5 * (b + sqrt(b * b + 4 * beta * v / (2 * M_PI * dt)));
    return v / (2 * M_PI * f);
}

static const mr_dvec3 DIR = {2.0 / 3, -1.0 / 3, 2.0 / 3};   /* unit */
static mr_dvec3 axis_unit(void) { return mr_v3_normalize(mr_v3(1, -2, 0.5)); }

static mr_dmat4 base_pose(void) { return mr_m4_look_at_cv(mr_v3(1, 1.6, 3), mr_v3(0, 1.5, 0), mr_v3(0, 1, 0)); }

/* The raw pose at translation x along DIR and rotation θ about the body axis. */
static mr_dmat4 pose_at(double x, double th) {
    mr_dmat4 b = base_pose(), r = mr_m4_rotate_axis(axis_unit(), th), m = mr_m4_mul(&b, &r);
    m.m[3] += x * DIR.x;
    m.m[7] += x * DIR.y;
    m.m[11] += x * DIR.z;
    return m;
}

/* Signed lag along the motion: translation (scene units) and rotation
 * (radians, about the axis) of raw ahead of out, and how far out strays
 * off the line / off the axis (must be ~0). */
static void lags(const mr_dmat4 *raw, const mr_dmat4 *out, double *lt, double *lr, double *off_t, double *off_r) {
    mr_dvec3 d = mr_v3(raw->m[3] - out->m[3], raw->m[7] - out->m[7], raw->m[11] - out->m[11]);
    *lt = mr_v3_dot(d, DIR);
    *off_t = mr_v3_len(mr_v3_sub(d, mr_v3_scale(DIR, *lt)));
    double D[9], rv[3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            D[r * 3 + c] = out->m[0 * 4 + r] * raw->m[0 * 4 + c] + out->m[1 * 4 + r] * raw->m[1 * 4 + c] +
                           out->m[2 * 4 + r] * raw->m[2 * 4 + c];
    /* log(D) with atan2: acos near 1 would cost ~1e-8 rad here. */
    double v[3] = {D[7] - D[5], D[2] - D[6], D[3] - D[1]}, s2 = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double th = atan2(0.5 * s2, 0.5 * (D[0] + D[4] + D[8] - 1));
    for (int k = 0; k < 3; k++) rv[k] = s2 > 0 ? v[k] / s2 * th : 0;
    mr_dvec3 a = axis_unit(), w = mr_v3(rv[0], rv[1], rv[2]);
    *lr = mr_v3_dot(w, a);
    *off_r = mr_v3_len(mr_v3_sub(w, mr_v3_scale(a, *lr)));
}

static double max_abs_diff(const mr_dmat4 *a, const mr_dmat4 *b) {
    double e = 0;
    for (int k = 0; k < 16; k++) e = fmax(e, fabs(a->m[k] - b->m[k]));
    return e;
}

/* A sample sequence: times, translations, rotations and which samples the
 * filter must reset on. */
#define MAXS 400
typedef struct seq { int n; double t[MAXS], x[MAXS], th[MAXS]; bool reset[MAXS]; } seq;

static void seq_ramp(seq *s, double t0, double hz, int frames, double v, double w) {
    for (int k = 0; k < frames && s->n < MAXS; k++, s->n++) {
        s->t[s->n] = t0 + k / hz;
        s->x[s->n] = v * s->t[s->n];
        s->th[s->n] = w * s->t[s->n];
        s->reset[s->n] = s->n == 0;
    }
}

/* Runs the filter over s and compares every output with the scalar oracles
 * (translation and rotation); returns the largest deviation and leaves the
 * final lags in *lt, *lr. */
static double run_seq(const char *what, const mr_filter_params *fp, const seq *s, double *lt, double *lr) {
    mr_error err = {0};
    mr_pose_filter *f = mr_pose_filter_create(fp, &err);
    CHECK_MSG(f != NULL, "%s: %s", what, err.msg);
    if (!f) return INFINITY;
    /* The documented defaults (mr_track.h). */
    one_euro ot = {fp && fp->min_cutoff > 0 ? fp->min_cutoff : 0.5, fp && fp->beta > 0 ? fp->beta : 2.0,
                   fp && fp->d_cutoff > 0 ? fp->d_cutoff : 1.0, 0, 0};
    one_euro orr = {fp && fp->rot_min_cutoff > 0 ? fp->rot_min_cutoff : 0.5, fp && fp->rot_beta > 0 ? fp->rot_beta : 1.0,
                    ot.f_d, 0, 0};
    double worst = 0, off = 0;
    int bad_reset = -1;
    for (int k = 0; k < s->n; k++) {
        mr_dmat4 raw = pose_at(s->x[k], s->th[k]), out;
        bool reset = mr_pose_filter_update(f, s->t[k], &raw, &out);
        if (reset != s->reset[k] && bad_reset < 0) bad_reset = k;
        if (s->reset[k]) {
            oe_reset(&ot, s->x[k]);
            oe_reset(&orr, s->th[k]);
        } else {
            double dt = s->t[k] - s->t[k - 1];
            oe_step(&ot, s->x[k], dt);
            oe_step(&orr, s->th[k], dt);
        }
        double ot_, or_;
        lags(&raw, &out, lt, lr, &ot_, &or_);
        worst = fmax(worst, fmax(fabs(*lt - (s->x[k] - ot.y)), fabs(*lr - (s->th[k] - orr.y))));
        off = fmax(off, fmax(ot_, or_));
        if (s->reset[k]) {
            CHECK_MSG(max_abs_diff(&out, &raw) < 1e-9, "%s: sample %d must pass through unfiltered (reset), "
                      "output differs from the raw pose by %.3g", what, k, max_abs_diff(&out, &raw));
        }
    }
    CHECK_MSG(bad_reset < 0, "%s: sample %d: filter %s, expected %s", what, bad_reset,
              bad_reset >= 0 && !s->reset[bad_reset] ? "reset" : "did not reset",
              bad_reset >= 0 && s->reset[bad_reset] ? "a reset (jump/gap threshold)" : "smoothing");
    CHECK_MSG(off < 1e-9, "%s: output left the line of motion / the rotation axis by %.3g", what, off);
    mr_pose_filter_destroy(&f);
    return worst;
}

/* ------------------------------------------------------------- tests */

/* Constant velocity and angular velocity, at 30 Hz and at the shipped
 * recording's 10 Hz, default and non-default parameters (all different,
 * so swapping two of them shows). */
static void test_ramp_lag(void) {
    static const struct { double v, w_deg, hz; } cases[] = {
        {0.3, 30, 30}, {2.0, 180, 30}, {1.0, 90, 10}, {0.0, 60, 30}, {0.8, 0, 30},
    };
    mr_filter_params custom = MR_FILTER_DEFAULTS;
    custom.min_cutoff = 0.7;
    custom.beta = 1.3;
    custom.d_cutoff = 2.2;
    custom.rot_min_cutoff = 0.3;
    custom.rot_beta = 0.6;
    const mr_filter_params *params[2] = {NULL, &custom};
    for (int pi = 0; pi < 2; pi++)
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
            const mr_filter_params *fp = params[pi];
            double v = cases[i].v, w = cases[i].w_deg * M_PI / 180, hz = cases[i].hz, dt = 1 / hz;
            char what[160];
            snprintf(what, sizeof what, "%s params, %.1f units/s and %.0f deg/s at %.0f Hz", pi ? "custom" : "default",
                     v, cases[i].w_deg, hz);
            static seq s;
            s.n = 0;
            seq_ramp(&s, 0, hz, (int)(8 * hz), v, w); /* 8 s: the transient is gone to 1e-12 */
            double lt, lr;
            double dev = run_seq(what, fp, &s, &lt, &lr);
            CHECK_MSG(dev < 1e-9, "%s: output departs from the discrete One Euro recursion by %.3g (min cutoff, beta, "
                      "or the speed filter's cutoff d_cutoff wrong?)", what, dev);
            double f_min = fp ? fp->min_cutoff : 0.5, beta = fp ? fp->beta : 2.0;
            double rf_min = fp ? fp->rot_min_cutoff : 0.5, rbeta = fp ? fp->rot_beta : 1.0;
            double want_t = steady_lag(f_min, beta, v, dt), want_r = steady_lag(rf_min, rbeta, w, dt);
            printf("%s: lag %.6f units (analytic %.6f), %.5f deg (analytic %.5f)\n", what, lt, want_t, lr * 180 / M_PI,
                   want_r * 180 / M_PI);
            CHECK_MSG(fabs(lt - want_t) <= 1e-9 + 1e-6 * want_t,
                      "%s: translation lag %.6f, analytic One Euro lag %.6f (beta term or cutoff wrong)", what, lt, want_t);
            CHECK_MSG(fabs(lr - want_r) <= 1e-9 + 1e-6 * fabs(want_r),
                      "%s: rotation lag %.5f deg, analytic One Euro lag %.5f deg (rot_beta term or rot cutoff wrong)",
                      what, lr * 180 / M_PI, want_r * 180 / M_PI);
        }
}

/* Jumps between consecutive raw poses beyond jump_dist (0.5) or jump_deg
 * (20) reset the filter (the new pose passes through unfiltered), below
 * them it smooths; so do gaps beyond max_gap_s (0.5 s). Each case runs
 * while moving, so the reset must also clear the speed estimate (the
 * samples after it follow the oracle restarted from rest). */
static void test_jumps_and_gaps(void) {
    static const struct { const char *what; double dx, dth_deg, gap_s; bool reset; } cases[] = {
        {"translation jump 0.60", 0.60, 0, 0, true},   {"translation jump 0.52", 0.52, 0, 0, true},
        {"translation step 0.48", 0.48, 0, 0, false},  {"translation step 0.40", 0.40, 0, 0, false},
        {"rotation jump 25 deg", 0, 25, 0, true},      {"rotation jump 21 deg", 0, 21, 0, true},
        {"rotation step 19 deg", 0, 19, 0, false},     {"rotation step 15 deg", 0, 15, 0, false},
        {"gap 0.60 s", 0, 0, 0.60, true},              {"gap 0.52 s", 0, 0, 0.52, true},
        {"gap 0.48 s", 0, 0, 0.48, false},             {"gap 0.40 s", 0, 0, 0.40, false},
    };
    const double hz = 30, v = 0.3, w = 20 * M_PI / 180;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        static seq s;
        s.n = 0;
        seq_ramp(&s, 0, hz, 60, v, w);
        /* The step: raw moves by exactly dx / dth from the previous raw
         * sample (on top of the ramp's own motion), or time skips. */
        double t = s.t[s.n - 1] + (cases[i].gap_s > 0 ? cases[i].gap_s : 1 / hz);
        double dt = t - s.t[s.n - 1];
        double x0 = s.x[s.n - 1] + (cases[i].dx > 0 ? cases[i].dx : v * dt);
        double th0 = s.th[s.n - 1] + (cases[i].dth_deg > 0 ? cases[i].dth_deg * M_PI / 180 : w * dt);
        for (int k = 0; k < 30 && s.n < MAXS; k++, s.n++) {
            s.t[s.n] = t + k / hz;
            s.x[s.n] = x0 + v * k / hz;
            s.th[s.n] = th0 + w * k / hz;
            s.reset[s.n] = k == 0 && cases[i].reset;
        }
        double lt, lr;
        double dev = run_seq(cases[i].what, NULL, &s, &lt, &lr);
        CHECK_MSG(dev < 1e-9, "%s: output departs from the One Euro recursion by %.3g (%s)", cases[i].what, dev,
                  cases[i].reset ? "reset did not pass the new pose through or did not clear the speed estimate"
                                 : "a step below the thresholds must be smoothed, not reset");
    }
    /* The thresholds are parameters: jump_deg 10, jump_dist 0.2, max_gap_s
     * 0.2 move the boundaries. */
    static const struct { const char *what; double dx, dth_deg, gap_s; bool reset; } custom[] = {
        {"custom jump_dist 0.2: step 0.25", 0.25, 0, 0, true}, {"custom jump_dist 0.2: step 0.15", 0.15, 0, 0, false},
        {"custom jump_deg 10: step 12 deg", 0, 12, 0, true},   {"custom jump_deg 10: step 8 deg", 0, 8, 0, false},
        {"custom max_gap_s 0.2: gap 0.25", 0, 0, 0.25, true},  {"custom max_gap_s 0.2: gap 0.15", 0, 0, 0.15, false},
    };
    mr_filter_params fp = MR_FILTER_DEFAULTS;
    fp.jump_dist = 0.2;
    fp.jump_deg = 10;
    fp.max_gap_s = 0.2;
    for (size_t i = 0; i < sizeof custom / sizeof custom[0]; i++) {
        static seq s;
        s.n = 0;
        seq_ramp(&s, 0, hz, 30, 0.1, 3 * M_PI / 180);
        double t = s.t[s.n - 1] + (custom[i].gap_s > 0 ? custom[i].gap_s : 1 / hz);
        s.t[s.n] = t;
        s.x[s.n] = s.x[s.n - 1] + (custom[i].dx > 0 ? custom[i].dx : 0.1 * (t - s.t[s.n - 1]));
        s.th[s.n] = s.th[s.n - 1] + (custom[i].dth_deg > 0 ? custom[i].dth_deg : 3 * (t - s.t[s.n - 1])) * M_PI / 180;
        s.reset[s.n] = custom[i].reset;
        s.n++;
        double lt, lr;
        double dev = run_seq(custom[i].what, &fp, &s, &lt, &lr);
        CHECK_MSG(dev < 1e-9, "%s: output departs from the One Euro recursion by %.3g", custom[i].what, dev);
    }
}

int main(void) {
    test_ramp_lag();
    test_jumps_and_gaps();
    return mr_test_finish("test_track_filter");
}
