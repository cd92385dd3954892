/* The inferential statistics of the rating and task designs (Scheer &
 * Keutel's and Kalkofen et al.'s analyses): the t, F, chi-square and
 * normal distributions, the paired t-test, the one-way repeated-measures
 * ANOVA with Mauchly's test and the Greenhouse-Geisser and Huynh-Feldt
 * corrections, D'Agostino's normality test, Friedman's test, Wilcoxon's
 * signed-rank test (exact for small n without ties) and the Bonferroni and
 * Holm adjustments. Plain arrays in, numbers out; nothing reads files. */
#include "mr_study.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------- distributions */

/* Continued fraction of the regularized incomplete beta (modified Lentz). */
static double beta_cf(double a, double b, double x) {
    const double tiny = 1e-300;
    double qab = a + b, qap = a + 1, qam = a - 1;
    double c = 1, d = 1 - qab * x / qap;
    if (fabs(d) < tiny) d = tiny;
    d = 1 / d;
    double h = d;
    for (int m = 1; m <= 500; m++) {
        double m2 = 2.0 * m;
        double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1 + aa * d;
        if (fabs(d) < tiny) d = tiny;
        c = 1 + aa / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1 / d;
        h *= d * c;
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1 + aa * d;
        if (fabs(d) < tiny) d = tiny;
        c = 1 + aa / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1) < 1e-15) break;
    }
    return h;
}

double mr_stat_beta_inc(double a, double b, double x) {
    if (!(x > 0)) return 0;
    if (!(x < 1)) return 1;
    double lbt = lgamma(a + b) - lgamma(a) - lgamma(b) + a * log(x) + b * log1p(-x);
    if (x < (a + 1) / (a + b + 2)) return exp(lbt) * beta_cf(a, b, x) / a;
    return 1 - exp(lbt) * beta_cf(b, a, 1 - x) / b;
}

/* Regularized upper incomplete gamma Q(a, x): the series below a + 1, the
 * continued fraction above. */
static double gamma_q(double a, double x) {
    if (!(x > 0)) return 1;
    double lg = -x + a * log(x) - lgamma(a);
    if (x < a + 1) {
        double ap = a, sum = 1 / a, del = sum;
        for (int n = 0; n < 1000; n++) {
            ap += 1;
            del *= x / ap;
            sum += del;
            if (fabs(del) < fabs(sum) * 1e-16) break;
        }
        return 1 - sum * exp(lg);
    }
    const double tiny = 1e-300;
    double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 1000; i++) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1) < 1e-16) break;
    }
    return exp(lg) * h;
}

double mr_stat_normal_cdf(double z) { return 0.5 * erfc(-z / sqrt(2.0)); }

double mr_stat_t_p2(double t, double df) {
    if (!isfinite(t)) return isnan(t) ? NAN : 0.0;
    if (!(df > 0)) return NAN;
    return mr_stat_beta_inc(df / 2, 0.5, df / (df + t * t));
}

double mr_stat_f_sf(double F, double d1, double d2) {
    if (isnan(F) || !(d1 > 0) || !(d2 > 0)) return NAN;
    if (!(F > 0)) return 1;
    if (!isfinite(F)) return 0;
    return mr_stat_beta_inc(d2 / 2, d1 / 2, d2 / (d2 + d1 * F));
}

double mr_stat_chi2_sf(double x, double k) {
    if (isnan(x) || !(k > 0)) return NAN;
    if (!isfinite(x)) return 0;
    return gamma_q(k / 2, x / 2);
}

/* ----------------------------------------------------------- adjustments */

const char *mr_study_adjust_name(mr_study_adjust a) {
    return a == MR_STUDY_ADJUST_HOLM ? "holm" : a == MR_STUDY_ADJUST_BONFERRONI ? "bonferroni" : "none";
}

void mr_study_p_adjust(const double *p, int m, mr_study_adjust how, double *out) {
    if (how == MR_STUDY_ADJUST_NONE || m <= 0) {
        for (int i = 0; i < m; i++) out[i] = p[i];
        return;
    }
    if (how == MR_STUDY_ADJUST_BONFERRONI) {
        for (int i = 0; i < m; i++) out[i] = fmin(1.0, p[i] * m);
        return;
    }
    /* Holm: the k-th smallest (k from 0) times m - k, made monotone. */
    int *ord = malloc((size_t)m * sizeof *ord);
    if (!ord) {
        for (int i = 0; i < m; i++) out[i] = fmin(1.0, p[i] * m); /* Bonferroni bounds Holm */
        return;
    }
    for (int i = 0; i < m; i++) ord[i] = i;
    for (int i = 1; i < m; i++) /* insertion sort: m is a handful of pairs */
        for (int j = i; j > 0 && p[ord[j]] < p[ord[j - 1]]; j--) {
            int x = ord[j];
            ord[j] = ord[j - 1], ord[j - 1] = x;
        }
    double run = 0;
    for (int k = 0; k < m; k++) {
        run = fmax(run, fmin(1.0, p[ord[k]] * (m - k)));
        out[ord[k]] = run;
    }
    free(ord);
}

/* ---------------------------------------------------------------- t-test */

bool mr_study_paired_t(const double *x, const double *y, int n, mr_study_ttest *out) {
    memset(out, 0, sizeof *out);
    out->n = n;
    out->t = out->p = NAN;
    if (n < 2) return false;
    double mean = 0;
    for (int i = 0; i < n; i++) mean += (x[i] - y[i]) / n;
    double ss = 0;
    for (int i = 0; i < n; i++) ss += (x[i] - y[i] - mean) * (x[i] - y[i] - mean);
    out->mean_diff = mean;
    out->sd_diff = sqrt(ss / (n - 1));
    out->df = n - 1;
    double se = out->sd_diff / sqrt((double)n);
    if (!(se > 0)) {
        out->t = mean == 0 ? 0 : copysign(INFINITY, mean);
        out->p = mean == 0 ? 1 : 0;
        return true;
    }
    out->t = mean / se;
    out->p = mr_stat_t_p2(out->t, out->df);
    return true;
}

/* ------------------------------------------------------ small linear algebra */

/* Determinant of the n x n matrix a (destroyed) by Gaussian elimination. */
static double det(double *a, int n) {
    double d = 1;
    for (int c = 0; c < n; c++) {
        int p = c;
        for (int r = c + 1; r < n; r++)
            if (fabs(a[r * n + c]) > fabs(a[p * n + c])) p = r;
        if (a[p * n + c] == 0) return 0;
        if (p != c) {
            for (int k = 0; k < n; k++) {
                double t = a[c * n + k];
                a[c * n + k] = a[p * n + k], a[p * n + k] = t;
            }
            d = -d;
        }
        d *= a[c * n + c];
        for (int r = c + 1; r < n; r++) {
            double f = a[r * n + c] / a[c * n + c];
            for (int k = c; k < n; k++) a[r * n + k] -= f * a[c * n + k];
        }
    }
    return d;
}

/* Row r of the normalised Helmert contrasts of k conditions (r < k - 1):
 * orthonormal, each orthogonal to the constant vector. */
static void helmert_row(int k, int r, double *row) {
    double norm = sqrt((double)(r + 1) * (r + 2));
    for (int j = 0; j < k; j++) row[j] = j <= r ? 1.0 / norm : j == r + 1 ? -(r + 1) / norm : 0.0;
}

/* -------------------------------------------------------------- RM-ANOVA */

bool mr_study_rm_anova(const double *y, int n, int k, mr_study_rm_anova_result *o, mr_error *err) {
    memset(o, 0, sizeof *o);
    o->n = n, o->k = k;
    if (n < 2 || k < 2 || k > MR_STUDY_MAX_CONDITIONS)
        return mr_fail(err, MR_ERR_INVALID, "rm-anova needs >= 2 participants and 2..%d conditions (got %d x %d)",
                       MR_STUDY_MAX_CONDITIONS, n, k);
    for (int i = 0; i < n * k; i++)
        if (!isfinite(y[i])) return mr_fail(err, MR_ERR_INVALID, "rm-anova: a value is not finite");
    double grand = 0, cm[MR_STUDY_MAX_CONDITIONS] = {0};
    for (int i = 0; i < n; i++)
        for (int j = 0; j < k; j++) {
            grand += y[i * k + j] / (n * k);
            cm[j] += y[i * k + j] / n;
        }
    double ss_total = 0, ss_cond = 0, ss_subj = 0;
    for (int j = 0; j < k; j++) ss_cond += n * (cm[j] - grand) * (cm[j] - grand);
    for (int i = 0; i < n; i++) {
        double sm = 0;
        for (int j = 0; j < k; j++) {
            sm += y[i * k + j] / k;
            ss_total += (y[i * k + j] - grand) * (y[i * k + j] - grand);
        }
        ss_subj += k * (sm - grand) * (sm - grand);
    }
    for (int j = 0; j < k; j++) o->mean[j] = cm[j];
    o->ss_cond = ss_cond;
    o->ss_subj = ss_subj;
    o->ss_error = fmax(0.0, ss_total - ss_cond - ss_subj);
    o->df1 = k - 1;
    o->df2 = (double)(k - 1) * (n - 1);
    double ms_e = o->ss_error / o->df2;
    o->F = ms_e > 0 ? (ss_cond / o->df1) / ms_e : ss_cond > 0 ? INFINITY : NAN;
    o->p = mr_stat_f_sf(o->F, o->df1, o->df2);
    o->eta_p2 = ss_cond + o->ss_error > 0 ? ss_cond / (ss_cond + o->ss_error) : NAN;
    /* The covariance of the conditions, and of the orthonormal contrasts. */
    double S[MR_STUDY_MAX_CONDITIONS * MR_STUDY_MAX_CONDITIONS];
    for (int a = 0; a < k; a++)
        for (int b = 0; b < k; b++) {
            double s = 0;
            for (int i = 0; i < n; i++) s += (y[i * k + a] - cm[a]) * (y[i * k + b] - cm[b]);
            S[a * k + b] = s / (n - 1);
        }
    int q = k - 1;
    double M[MR_STUDY_MAX_CONDITIONS * MR_STUDY_MAX_CONDITIONS], C[MR_STUDY_MAX_CONDITIONS * MR_STUDY_MAX_CONDITIONS];
    for (int r = 0; r < q; r++) helmert_row(k, r, &M[r * k]);
    for (int r = 0; r < q; r++)
        for (int c = 0; c < q; c++) {
            double s = 0;
            for (int a = 0; a < k; a++)
                for (int b = 0; b < k; b++) s += M[r * k + a] * S[a * k + b] * M[c * k + b];
            C[r * q + c] = s;
        }
    /* Greenhouse-Geisser: tr(C)^2 / (q tr(C^2)); Huynh-Feldt from it. */
    double tr = 0, tr2 = 0;
    for (int r = 0; r < q; r++) {
        tr += C[r * q + r];
        for (int c = 0; c < q; c++) tr2 += C[r * q + c] * C[c * q + r];
    }
    o->eps_lb = 1.0 / q;
    o->eps_gg = tr2 > 0 ? tr * tr / (q * tr2) : 1.0;
    double hf = (n * q * o->eps_gg - 2) / (q * (n - 1 - q * o->eps_gg));
    o->eps_hf = fmin(1.0, hf > 0 ? hf : o->eps_gg);
    o->p_gg = mr_stat_f_sf(o->F, o->df1 * o->eps_gg, o->df2 * o->eps_gg);
    o->p_hf = mr_stat_f_sf(o->F, o->df1 * o->eps_hf, o->df2 * o->eps_hf);
    /* Mauchly: W = det(C) / (tr(C)/q)^q, chi^2 with Bartlett's factor. */
    if (q == 1) {
        o->mauchly_w = 1, o->mauchly_chi2 = 0, o->mauchly_df = 0, o->mauchly_p = 1;
    } else {
        double Cd[MR_STUDY_MAX_CONDITIONS * MR_STUDY_MAX_CONDITIONS];
        memcpy(Cd, C, sizeof Cd);
        double d = det(Cd, q), mean_ev = tr / q;
        o->mauchly_w = mean_ev > 0 ? fmax(0.0, d / pow(mean_ev, q)) : NAN;
        double f = (n - 1) - (2.0 * q * q + q + 2) / (6.0 * q);
        o->mauchly_df = q * (q + 1) / 2.0 - 1;
        o->mauchly_chi2 = o->mauchly_w > 0 ? -f * log(o->mauchly_w) : INFINITY;
        /* p with Anderson's second-order term (as SPSS reports it):
         * (1 - w2) P(chi2_f > x) + w2 P(chi2_{f+4} > x). */
        double rho = f / (n - 1);
        double w2 = (q + 2.0) * (q - 1) * (q - 2) * (2.0 * q * q * q + 6.0 * q * q + 3 * q + 2) /
                    (288.0 * q * q * (n - 1.0) * (n - 1.0) * rho * rho);
        double p0 = mr_stat_chi2_sf(o->mauchly_chi2, o->mauchly_df);
        double p4 = mr_stat_chi2_sf(o->mauchly_chi2, o->mauchly_df + 4);
        o->mauchly_p = n - 1 >= q && f > 0 ? fmin(1.0, fmax(0.0, p0 + w2 * (p4 - p0))) : NAN;
    }
    return true;
}

/* ---------------------------------------------------------- normality */

bool mr_study_normality(const double *x, int n, mr_study_normality_result *o) {
    memset(o, 0, sizeof *o);
    o->n = n;
    o->p = NAN;
    if (n < 8) return false;
    double mean = 0;
    for (int i = 0; i < n; i++) mean += x[i] / n;
    double m2 = 0, m3 = 0, m4 = 0;
    for (int i = 0; i < n; i++) {
        double d = x[i] - mean;
        m2 += d * d / n, m3 += d * d * d / n, m4 += d * d * d * d / n;
    }
    if (!(m2 > 0)) return false;
    double N = n;
    /* Skewness (D'Agostino 1970). */
    double b1 = m3 / pow(m2, 1.5);
    double Y = b1 * sqrt((N + 1) * (N + 3) / (6 * (N - 2)));
    double beta2 = 3 * (N * N + 27 * N - 70) * (N + 1) * (N + 3) / ((N - 2) * (N + 5) * (N + 7) * (N + 9));
    double W2 = -1 + sqrt(2 * (beta2 - 1));
    double delta = 1 / sqrt(0.5 * log(W2));
    double alpha = sqrt(2 / (W2 - 1));
    double ya = Y / alpha;
    o->z_skew = delta * log(ya + sqrt(ya * ya + 1));
    /* Kurtosis (Anscombe & Glynn 1983). */
    double b2 = m4 / (m2 * m2);
    double E = 3 * (N - 1) / (N + 1);
    double var = 24 * N * (N - 2) * (N - 3) / ((N + 1) * (N + 1) * (N + 3) * (N + 5));
    double xk = (b2 - E) / sqrt(var);
    double sb1 = 6 * (N * N - 5 * N + 2) / ((N + 7) * (N + 9)) * sqrt(6 * (N + 3) * (N + 5) / (N * (N - 2) * (N - 3)));
    double A = 6 + 8 / sb1 * (2 / sb1 + sqrt(1 + 4 / (sb1 * sb1)));
    double term = (1 - 2 / A) / (1 + xk * sqrt(2 / (A - 4)));
    double cube = term >= 0 ? cbrt(term) : -cbrt(-term);
    o->z_kurt = ((1 - 2 / (9 * A)) - cube) / sqrt(2 / (9 * A));
    o->k2 = o->z_skew * o->z_skew + o->z_kurt * o->z_kurt;
    o->p = mr_stat_chi2_sf(o->k2, 2);
    return true;
}

/* ------------------------------------------------------------- ranks */

/* Mid-ranks (1-based) of v[0..n-1] into r; returns sum over tie groups of
 * (t^3 - t). */
static double midranks(const double *v, int n, double *r, int *idx) {
    for (int i = 0; i < n; i++) idx[i] = i;
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && v[idx[j]] < v[idx[j - 1]]; j--) {
            int x = idx[j];
            idx[j] = idx[j - 1], idx[j - 1] = x;
        }
    double ties = 0;
    for (int a = 0; a < n;) {
        int b = a;
        while (b + 1 < n && v[idx[b + 1]] == v[idx[a]]) b++;
        double rank = (a + b) / 2.0 + 1;
        for (int c = a; c <= b; c++) r[idx[c]] = rank;
        double t = b - a + 1;
        ties += t * t * t - t;
        a = b + 1;
    }
    return ties;
}

bool mr_study_friedman(const double *y, int n, int k, mr_study_friedman_result *o, mr_error *err) {
    memset(o, 0, sizeof *o);
    o->n = n, o->k = k;
    if (n < 2 || k < 2 || k > MR_STUDY_MAX_CONDITIONS)
        return mr_fail(err, MR_ERR_INVALID, "friedman needs >= 2 participants and 2..%d conditions", MR_STUDY_MAX_CONDITIONS);
    double R[MR_STUDY_MAX_CONDITIONS] = {0}, r[MR_STUDY_MAX_CONDITIONS], ties = 0;
    int idx[MR_STUDY_MAX_CONDITIONS];
    for (int i = 0; i < n; i++) {
        ties += midranks(&y[i * k], k, r, idx);
        for (int j = 0; j < k; j++) R[j] += r[j];
    }
    double K = k, N = n, s = 0;
    for (int j = 0; j < k; j++) {
        s += R[j] * R[j];
        o->mean_rank[j] = R[j] / n;
    }
    double chi = 12.0 / (N * K * (K + 1)) * s - 3 * N * (K + 1);
    double corr = 1 - ties / (N * (K * K * K - K));
    o->chi2 = corr > 0 ? chi / corr : NAN;
    o->df = k - 1;
    o->p = mr_stat_chi2_sf(o->chi2, o->df);
    o->kendall_w = o->chi2 / (N * (K - 1));
    return true;
}

/* Number of subsets of {1..n} with each sum s (s = 0..n(n+1)/2) into c. */
static void signrank_counts(int n, double *c) {
    int max = n * (n + 1) / 2;
    for (int s = 0; s <= max; s++) c[s] = 0;
    c[0] = 1;
    for (int i = 1; i <= n; i++)
        for (int s = i * (i + 1) / 2; s >= i; s--) c[s] += c[s - i];
}

bool mr_study_wilcoxon(const double *x, const double *y, int n, mr_study_wilcoxon_result *o) {
    memset(o, 0, sizeof *o);
    o->z = o->p = NAN;
    double *d = malloc((size_t)(n > 0 ? n : 1) * 3 * sizeof *d);
    int *idx = malloc((size_t)(n > 0 ? n : 1) * sizeof *idx);
    if (!d || !idx) {
        free(d), free(idx);
        return false;
    }
    double *ad = d + n, *r = d + 2 * n;
    int m = 0;
    for (int i = 0; i < n; i++) {
        double v = x[i] - y[i];
        if (v == 0) {
            o->zeros++;
            continue;
        }
        d[m] = v, ad[m] = fabs(v), m++;
    }
    o->n = m;
    if (m == 0) {
        free(d), free(idx);
        o->p = 1, o->z = 0;
        return true;
    }
    double ties = midranks(ad, m, r, idx);
    for (int i = 0; i < m; i++) {
        if (d[i] > 0) o->w_plus += r[i];
        else o->w_minus += r[i];
    }
    double M = m, mu = M * (M + 1) / 4, var = M * (M + 1) * (2 * M + 1) / 24 - ties / 48;
    double diff = o->w_plus - mu;
    /* Normal approximation with continuity correction (reported always). */
    double cc = diff > 0 ? 0.5 : diff < 0 ? -0.5 : 0;
    o->z = var > 0 ? (diff - cc) / sqrt(var) : 0;
    if (m <= MR_STUDY_WILCOXON_EXACT_MAX && ties == 0 && o->zeros == 0) {
        int max = m * (m + 1) / 2;
        double *c = malloc((size_t)(max + 1) * sizeof *c);
        if (c) {
            signrank_counts(m, c);
            double total = ldexp(1.0, m), lo = 0, hi = 0;
            int w = (int)lround(o->w_plus);
            for (int s = 0; s <= max; s++) {
                if (s <= w) lo += c[s];
                if (s >= w) hi += c[s];
            }
            o->p = fmin(1.0, 2 * fmin(lo, hi) / total);
            o->exact = true;
            free(c);
        }
    }
    if (!o->exact) o->p = var > 0 ? fmin(1.0, 2 * mr_stat_normal_cdf(-fabs(o->z))) : 1.0;
    free(d), free(idx);
    return true;
}
