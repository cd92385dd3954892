/* The statistics of a pairwise comparison study (Hecher, thesis ch. 5):
 * consistence, agreement, indifference, exact binomial thresholds and the
 * Bradley-Terry / Davidson scores with standard errors. Plain arrays in,
 * numbers out; nothing here reads files. */
#include "mr_study.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void mr_study_split_ties(const double *w, const double *ties, int t, double *A) {
    for (int i = 0; i < t; i++)
        for (int j = 0; j < t; j++)
            A[i * t + j] = i == j ? 0.0 : w[i * t + j] + (ties ? 0.5 * ties[i * t + j] : 0.0);
}

mr_study_consistence mr_study_consistence_of(const double *A, int t) {
    mr_study_consistence r = {0, 1, 1};
    if (t < 3) return r; /* no triad can be circular */
    double a[MR_STUDY_MAX_METHODS], mean = 0;
    for (int i = 0; i < t; i++) {
        a[i] = 0;
        for (int j = 0; j < t; j++)
            if (j != i) a[i] += A[i * t + j];
        mean += a[i] / t;
    }
    double ss = 0;
    for (int i = 0; i < t; i++) ss += (a[i] - mean) * (a[i] - mean);
    double td = t;
    r.c = td * (td * td - 1) / 24.0 - ss / 2.0;
    r.xi = 1.0 - 24.0 * r.c / (td * (td * td - 1));
    double cmax = (t % 2) ? (td * td * td - td) / 24.0 : (td * td * td - 4 * td) / 24.0;
    r.xi_kendall = fmin(1.0, fmax(0.0, 1.0 - r.c / cmax));
    return r;
}

double mr_study_agreement(const double *A, int t) {
    double tau = 0, max_tau = 0;
    for (int i = 0; i < t; i++)
        for (int j = i + 1; j < t; j++) {
            double x = A[i * t + j], y = A[j * t + i], n = x + y;
            tau += x * (x - 1) / 2 + y * (y - 1) / 2;
            max_tau += n * (n - 1) / 2;
        }
    if (!(max_tau > 0)) return NAN;
    return 2.0 * tau / max_tau - 1.0;
}

double mr_study_indifference(double neutral_distinct, double n_distinct, double neutral_identical,
                             double n_identical, bool *baseline) {
    double num = n_distinct > 0 ? neutral_distinct / n_distinct : 0.0;
    double den = n_identical > 0 ? neutral_identical / n_identical : 0.0;
    bool have = den > 0;
    if (baseline) *baseline = have;
    return fmin(1.0, have ? num / den : num);
}

double mr_study_indifference_eq56(double neutral_distinct, double n_per_pair, double neutral_identical,
                                  double n_identical) {
    if (!(n_per_pair > 0) || !(n_identical > 0) || !(neutral_identical > 0)) return NAN;
    return (neutral_distinct / n_per_pair) / (neutral_identical / n_identical);
}

/* log C(n, k) through lgamma: exact enough for any n a study has. */
static double log_choose(int n, int k) { return lgamma(n + 1.0) - lgamma(k + 1.0) - lgamma(n - k + 1.0); }

double mr_study_binom_upper_tail(int n, int k) {
    if (k <= 0) return 1.0;
    if (k > n) return 0.0;
    double s = 0;
    for (int x = k; x <= n; x++) s += exp(log_choose(n, x) - n * log(2.0));
    return fmin(1.0, s);
}

int mr_study_binom_threshold(int n, double alpha) {
    for (int k = 0; k <= n; k++)
        if (mr_study_binom_upper_tail(n, k) < alpha) return k;
    return n + 1;
}

/* --------------------------------------------------------- graph check */

bool mr_study_graph_connected(const double *w, const double *ties, int t, int *who) {
    if (who) *who = -1;
    if (t <= 1) return true;
    /* Reachability by Floyd-Warshall on booleans: t is at most 16. */
    bool R[MR_STUDY_MAX_METHODS][MR_STUDY_MAX_METHODS];
    for (int i = 0; i < t; i++)
        for (int j = 0; j < t; j++)
            R[i][j] = i == j || w[i * t + j] > 0 || (ties && (ties[i * t + j] > 0 || ties[j * t + i] > 0));
    for (int k = 0; k < t; k++)
        for (int i = 0; i < t; i++)
            for (int j = 0; j < t; j++)
                if (R[i][k] && R[k][j]) R[i][j] = true;
    bool all = true;
    for (int i = 0; i < t && all; i++)
        for (int j = 0; j < t; j++)
            if (!R[i][j]) all = false;
    if (all || !who) return all;
    /* A method no one outside its component beats: one that reaches every
     * method that reaches it, and is reached by fewest. */
    int best = -1, best_in = t + 1;
    for (int i = 0; i < t; i++) {
        int in = 0;
        for (int j = 0; j < t; j++) in += R[j][i];
        if (in < best_in) best_in = in, best = i;
    }
    *who = best;
    return false;
}

/* ------------------------------------------------------ linear algebra */

/* Inverts the n x n matrix a in place (Gauss-Jordan, partial pivoting);
 * false if singular. */
static bool invert(double *a, int n) {
    double inv[(MR_STUDY_MAX_METHODS + 1) * (MR_STUDY_MAX_METHODS + 1)];
    for (int i = 0; i < n * n; i++) inv[i] = 0;
    for (int i = 0; i < n; i++) inv[i * n + i] = 1;
    for (int c = 0; c < n; c++) {
        int p = c;
        for (int r = c + 1; r < n; r++)
            if (fabs(a[r * n + c]) > fabs(a[p * n + c])) p = r;
        if (!(fabs(a[p * n + c]) > 1e-300)) return false;
        if (p != c)
            for (int k = 0; k < n; k++) {
                double x = a[c * n + k];
                a[c * n + k] = a[p * n + k], a[p * n + k] = x;
                x = inv[c * n + k];
                inv[c * n + k] = inv[p * n + k], inv[p * n + k] = x;
            }
        double d = a[c * n + c];
        for (int k = 0; k < n; k++) a[c * n + k] /= d, inv[c * n + k] /= d;
        for (int r = 0; r < n; r++) {
            if (r == c) continue;
            double f = a[r * n + c];
            if (f == 0) continue;
            for (int k = 0; k < n; k++) a[r * n + k] -= f * a[c * n + k], inv[r * n + k] -= f * inv[c * n + k];
        }
    }
    memcpy(a, inv, (size_t)n * n * sizeof *a);
    return true;
}

/* --------------------------------------------------------- likelihood */

/* The Davidson log-likelihood (Bradley-Terry when !ties_on) at theta (t
 * values) and lambda = log nu, with its gradient g and Hessian H over the
 * t + 1 coordinates (theta..., lambda). */
static double loglik(const double *w, const double *ties, int t, bool ties_on, const double *theta, double lambda,
                     double *g, double *H) {
    int n = t + 1;
    if (g) memset(g, 0, (size_t)n * sizeof *g);
    if (H) memset(H, 0, (size_t)n * n * sizeof *H);
    double L = 0;
    for (int i = 0; i < t; i++)
        for (int j = i + 1; j < t; j++) {
            double wij = w[i * t + j], wji = w[j * t + i], tij = ties_on && ties ? ties[i * t + j] : 0;
            double nij = wij + wji + tij;
            if (!(nij > 0)) continue;
            /* Outcome k has linear score s_k = f_k . (theta_i, theta_j, lambda). */
            double s[3] = {theta[i], theta[j], lambda + 0.5 * (theta[i] + theta[j])};
            int K = ties_on ? 3 : 2;
            double m = fmax(s[0], s[1]);
            if (K == 3) m = fmax(m, s[2]);
            double z = 0, e[3];
            for (int k = 0; k < K; k++) z += (e[k] = exp(s[k] - m));
            double lz = m + log(z);
            double cnt[3] = {wij, wji, tij};
            for (int k = 0; k < K; k++) L += cnt[k] * (s[k] - lz);
            double pr[3];
            for (int k = 0; k < K; k++) pr[k] = e[k] / z;
            /* Features over (i, j, lambda) of each outcome. */
            static const double f[3][3] = {{1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
            int idx[3] = {i, j, t};
            double Ef[3] = {0, 0, 0};
            for (int k = 0; k < K; k++)
                for (int d = 0; d < 3; d++) Ef[d] += pr[k] * f[k][d];
            if (g)
                for (int d = 0; d < 3; d++) {
                    double obs = 0;
                    for (int k = 0; k < K; k++) obs += cnt[k] * f[k][d];
                    g[idx[d]] += obs - nij * Ef[d];
                }
            if (H)
                for (int a = 0; a < 3; a++)
                    for (int b = 0; b < 3; b++) {
                        double Eab = 0;
                        for (int k = 0; k < K; k++) Eab += pr[k] * f[k][a] * f[k][b];
                        H[idx[a] * n + idx[b]] -= nij * (Eab - Ef[a] * Ef[b]);
                    }
        }
    return L;
}

/* Standard errors (and the final theta convention) from the Hessian at the
 * fit: the fixed method's row and column left out, the rest inverted; when
 * no reference is given, theta is centred and its covariance carried
 * through the centring map. */
static bool finish_scores(const double *w, const double *ties, int t, bool ties_on, int fixed, int reference,
                          double *theta, double lambda, mr_study_scores *out, mr_error *err) {
    int n = t + 1;
    double H[(MR_STUDY_MAX_METHODS + 1) * (MR_STUDY_MAX_METHODS + 1)];
    loglik(w, ties, t, ties_on, theta, lambda, NULL, H);
    int keep[MR_STUDY_MAX_METHODS + 1], m = 0;
    for (int k = 0; k < t; k++)
        if (k != fixed) keep[m++] = k;
    if (ties_on) keep[m++] = t;
    double C[(MR_STUDY_MAX_METHODS + 1) * (MR_STUDY_MAX_METHODS + 1)];
    for (int a = 0; a < m; a++)
        for (int b = 0; b < m; b++) C[a * m + b] = -H[keep[a] * n + keep[b]];
    if (!invert(C, m)) return mr_fail(err, MR_ERR_INVALID, "scores: the information matrix is singular");
    /* Full covariance over (theta_0..theta_{t-1}) with the fixed one 0. */
    double S[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS];
    memset(S, 0, sizeof S);
    for (int a = 0; a < m; a++)
        for (int b = 0; b < m; b++)
            if (keep[a] < t && keep[b] < t) S[keep[a] * t + keep[b]] = C[a * m + b];
    if (ties_on) {
        out->se_log_nu = sqrt(fmax(0.0, C[(m - 1) * m + (m - 1)]));
        out->log_nu = lambda;
        out->has_nu = true;
    }
    if (reference < 0) {
        double mean = 0;
        for (int k = 0; k < t; k++) mean += theta[k] / t;
        for (int k = 0; k < t; k++) theta[k] -= mean;
        /* Var(theta_i - mean) = S_ii - 2 mean_k S_ik + mean_kl S_kl. */
        double row[MR_STUDY_MAX_METHODS], tot = 0;
        for (int i = 0; i < t; i++) {
            row[i] = 0;
            for (int k = 0; k < t; k++) row[i] += S[i * t + k] / t;
            tot += row[i] / t;
        }
        for (int i = 0; i < t; i++) out->se[i] = sqrt(fmax(0.0, S[i * t + i] - 2 * row[i] + tot));
    } else {
        for (int i = 0; i < t; i++) out->se[i] = sqrt(fmax(0.0, S[i * t + i]));
    }
    double mx = theta[0], sum = 0;
    for (int k = 1; k < t; k++) mx = fmax(mx, theta[k]);
    for (int k = 0; k < t; k++) sum += exp(theta[k] - mx);
    for (int k = 0; k < t; k++) {
        out->theta[k] = theta[k];
        out->p[k] = exp(theta[k] - mx) / sum;
    }
    return true;
}

/* Counts with the documented pseudo-count when the graph needs it. */
static void prepare(const double *w, const double *ties, int t, const mr_study_fit_params *p, double *wp,
                    mr_study_scores *out, const char *model) {
    memcpy(wp, w, (size_t)t * t * sizeof *wp);
    int who = -1;
    out->isolated = -1;
    if (mr_study_graph_connected(w, ties, t, &who)) return;
    out->isolated = who;
    double a = p->pseudo > 0 ? p->pseudo : 0.5;
    for (int i = 0; i < t; i++)
        for (int j = 0; j < t; j++)
            if (i != j) wp[i * t + j] += a;
    out->pseudo = true;
    snprintf(out->note, sizeof out->note,
             "%s: the comparison graph is not strongly connected (method %d is never beaten or tied by "
             "the others); added %g pseudo-wins each way to every pair",
             model, who, a);
}

static bool check_input(const double *w, int t, mr_error *err) {
    if (t < 2 || t > MR_STUDY_MAX_METHODS)
        return mr_fail(err, MR_ERR_INVALID, "scores need 2..%d methods, got %d", MR_STUDY_MAX_METHODS, t);
    for (int i = 0; i < t * t; i++)
        if (!(w[i] >= 0) || !isfinite(w[i])) return mr_fail(err, MR_ERR_INVALID, "scores: counts must be finite and >= 0");
    return true;
}

bool mr_study_bt_fit(const double *w, int t, const mr_study_fit_params *pp, mr_study_scores *out, mr_error *err) {
    mr_study_fit_params p = pp ? *pp : (mr_study_fit_params)MR_STUDY_FIT_DEFAULTS;
    memset(out, 0, sizeof *out);
    out->t = t;
    if (!check_input(w, t, err)) return false;
    double wp[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS];
    prepare(w, NULL, t, &p, wp, out, "bradley-terry");
    int max_iter = p.max_iter > 0 ? p.max_iter : 10000;
    double tol = p.tol > 0 ? p.tol : 1e-10;
    double g[MR_STUDY_MAX_METHODS], W[MR_STUDY_MAX_METHODS];
    for (int i = 0; i < t; i++) {
        g[i] = 1.0 / t;
        W[i] = 0;
        for (int j = 0; j < t; j++) W[i] += wp[i * t + j];
    }
    for (int it = 0; it < max_iter; it++) {
        double delta = 0, sum = 0, ng[MR_STUDY_MAX_METHODS];
        for (int i = 0; i < t; i++) {
            double d = 0;
            for (int j = 0; j < t; j++) {
                double nij = wp[i * t + j] + wp[j * t + i];
                if (j != i && nij > 0) d += nij / (g[i] + g[j]);
            }
            ng[i] = d > 0 ? W[i] / d : g[i];
            sum += ng[i];
        }
        for (int i = 0; i < t; i++) {
            ng[i] /= sum;
            delta = fmax(delta, fabs(log(ng[i]) - log(g[i])));
            g[i] = ng[i];
        }
        out->iterations = it + 1;
        if (delta < tol) {
            out->converged = true;
            break;
        }
    }
    double theta[MR_STUDY_MAX_METHODS];
    int fixed = p.reference >= 0 && p.reference < t ? p.reference : t - 1;
    for (int i = 0; i < t; i++) theta[i] = log(g[i]) - log(g[fixed]);
    return finish_scores(wp, NULL, t, false, fixed, p.reference >= 0 && p.reference < t ? p.reference : -1, theta,
                         0, out, err);
}

bool mr_study_davidson_fit(const double *w, const double *ties, int t, const mr_study_fit_params *pp,
                           mr_study_scores *out, mr_error *err) {
    mr_study_fit_params p = pp ? *pp : (mr_study_fit_params)MR_STUDY_FIT_DEFAULTS;
    double tie_sum = 0;
    for (int i = 0; ties && i < t * t; i++) {
        if (!(ties[i] >= 0) || !isfinite(ties[i])) return mr_fail(err, MR_ERR_INVALID, "scores: tie counts must be finite and >= 0");
        tie_sum += ties[i];
    }
    if (!(tie_sum > 0)) return mr_study_bt_fit(w, t, &p, out, err);
    memset(out, 0, sizeof *out);
    out->t = t;
    if (!check_input(w, t, err)) return false;
    double wp[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS];
    prepare(w, ties, t, &p, wp, out, "davidson");
    int reference = p.reference >= 0 && p.reference < t ? p.reference : -1;
    int fixed = reference >= 0 ? reference : t - 1;
    int max_iter = p.max_iter > 0 ? p.max_iter : 100;
    double tol = p.tol > 0 ? p.tol : 1e-10;
    double theta[MR_STUDY_MAX_METHODS] = {0}, lambda = 0;
    int n = t + 1;
    /* With only ties between some pairs nu has no finite optimum; the
     * bound keeps it finite (documented as nu <= e^20). */
    const double lambda_max = 20.0;
    for (int it = 0; it < max_iter; it++) {
        double g[MR_STUDY_MAX_METHODS + 1], H[(MR_STUDY_MAX_METHODS + 1) * (MR_STUDY_MAX_METHODS + 1)];
        double L = loglik(wp, ties, t, true, theta, lambda, g, H);
        int keep[MR_STUDY_MAX_METHODS + 1], m = 0;
        for (int k = 0; k < n; k++)
            if (k != fixed) keep[m++] = k;
        double A[(MR_STUDY_MAX_METHODS + 1) * (MR_STUDY_MAX_METHODS + 1)], step[MR_STUDY_MAX_METHODS + 1];
        double gnorm = 0;
        for (int a = 0; a < m; a++) {
            gnorm = fmax(gnorm, fabs(g[keep[a]]));
            for (int b = 0; b < m; b++) A[a * m + b] = -H[keep[a] * n + keep[b]];
        }
        out->iterations = it;
        if (gnorm < tol) {
            out->converged = true;
            break;
        }
        if (!invert(A, m)) return mr_fail(err, MR_ERR_INVALID, "davidson: singular information matrix");
        for (int a = 0; a < m; a++) {
            step[a] = 0;
            for (int b = 0; b < m; b++) step[a] += A[a * m + b] * g[keep[b]];
        }
        /* Step halving: the log-likelihood is concave, so some fraction of
         * the Newton step increases it unless we are at the optimum. */
        double f = 1.0;
        bool moved = false;
        for (int h = 0; h < 60; h++, f *= 0.5) {
            double nt[MR_STUDY_MAX_METHODS], nl = lambda;
            memcpy(nt, theta, sizeof nt);
            for (int a = 0; a < m; a++) {
                if (keep[a] < t) nt[keep[a]] += f * step[a];
                else nl += f * step[a];
            }
            nl = fmin(nl, lambda_max);
            double L2 = loglik(wp, ties, t, true, nt, nl, NULL, NULL);
            if (L2 >= L - 1e-12 * fabs(L)) {
                memcpy(theta, nt, sizeof nt);
                lambda = nl;
                moved = true;
                break;
            }
        }
        if (!moved) {
            out->converged = gnorm < 1e-6;
            break;
        }
    }
    return finish_scores(wp, ties, t, true, fixed, reference, theta, lambda, out, err);
}
