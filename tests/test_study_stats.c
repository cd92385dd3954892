/* lib/study's inferential statistics against published worked examples:
 * each dataset is printed in a textbook (or R's documentation of it) with
 * its result, and the numbers below are those printed results (more
 * digits where the source gives them); scipy 1.10 agrees with each. */
#include "mr_test.h"
#include "mr_study.h"

/* Student's sleep data (Cushny & Peebles 1905; R's `sleep`): extra hours of
 * sleep of 10 patients under two drugs. R's t.test(paired = TRUE):
 * t = -4.0621, df = 9, p-value = 0.002833, mean difference -1.58. */
static void test_paired_t(void) {
    const double d1[10] = {0.7, -1.6, -0.2, -1.2, -0.1, 3.4, 3.7, 0.8, 0.0, 2.0};
    const double d2[10] = {1.9, 0.8, 1.1, 0.1, -0.1, 4.4, 5.5, 1.6, 4.6, 3.4};
    mr_study_ttest t;
    CHECK(mr_study_paired_t(d1, d2, 10, &t));
    CHECK_NEAR(t.t, -4.0621, 5e-5);
    CHECK_NEAR(t.df, 9, 0);
    CHECK_NEAR(t.p, 0.002833, 5e-7);
    CHECK_NEAR(t.mean_diff, -1.58, 1e-12);
    CHECK(!mr_study_paired_t(d1, d2, 1, &t));
    /* Identical samples: no difference at all, p = 1. */
    CHECK(mr_study_paired_t(d1, d1, 10, &t));
    CHECK_NEAR(t.p, 1, 0);
}

/* Field (2009), Discovering Statistics Using SPSS, 3rd ed., ch. 13: the
 * "bushtucker" data, 8 celebrities x 4 animals, seconds to retch. Printed:
 * Mauchly's W = .136, chi^2(5) = 11.41, p = .047; epsilon GG = .533,
 * HF = .666; F(3, 21) = 3.79, p = .026; with GG p = .063. */
static void test_rm_anova(void) {
    const double y[8 * 4] = {8, 7, 1, 6, 9, 5, 2, 5, 6, 2, 3, 8, 5, 3, 1, 9,
                             8, 4, 5, 8, 7, 5, 6, 7, 10, 2, 7, 2, 12, 6, 8, 1};
    mr_study_rm_anova_result r;
    mr_error err = {0};
    CHECK(mr_study_rm_anova(y, 8, 4, &r, &err));
    CHECK_NEAR(r.df1, 3, 0);
    CHECK_NEAR(r.df2, 21, 0);
    CHECK_NEAR(r.F, 3.79, 0.005);
    CHECK_NEAR(r.p, 0.026, 0.0005);
    CHECK_NEAR(r.mauchly_w, 0.136, 0.0005);
    CHECK_NEAR(r.mauchly_chi2, 11.41, 0.005);
    CHECK_NEAR(r.mauchly_df, 5, 0);
    CHECK_NEAR(r.mauchly_p, 0.047, 0.0005);
    CHECK_NEAR(r.eps_gg, 0.533, 0.0005);
    CHECK_NEAR(r.eps_hf, 0.666, 0.0005);
    CHECK_NEAR(r.p_gg, 0.063, 0.0005);
    CHECK_NEAR(r.mean[0], 8.125, 1e-12);
    /* Two conditions: the F of the RM-ANOVA is the paired t squared, and
     * sphericity holds trivially (epsilon 1, W 1). */
    double two[8 * 2];
    for (int i = 0; i < 8; i++) two[i * 2] = y[i * 4], two[i * 2 + 1] = y[i * 4 + 1];
    CHECK(mr_study_rm_anova(two, 8, 2, &r, &err));
    double a[8], b[8];
    for (int i = 0; i < 8; i++) a[i] = two[i * 2], b[i] = two[i * 2 + 1];
    mr_study_ttest t;
    CHECK(mr_study_paired_t(a, b, 8, &t));
    CHECK_NEAR(r.F, t.t * t.t, 1e-9);
    CHECK_NEAR(r.p, t.p, 1e-9);
    CHECK_NEAR(r.eps_gg, 1, 1e-12);
    CHECK_NEAR(r.mauchly_w, 1, 0);
    CHECK(!mr_study_rm_anova(y, 1, 4, &r, &err));
}

/* Hollander & Wolfe (1973), p. 29 (R's ?wilcox.test): Hamilton depression
 * scale before (x) and after (y) a tranquilizer, 9 patients. Printed:
 * V = 40, exact one-sided p = 0.01953, so two-sided 0.0390625 = 20/512. */
static void test_wilcoxon(void) {
    const double x[9] = {1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30};
    const double y[9] = {0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29};
    mr_study_wilcoxon_result w;
    CHECK(mr_study_wilcoxon(x, y, 9, &w));
    CHECK(w.exact);
    CHECK_NEAR(w.w_plus, 40, 0);
    CHECK_NEAR(w.w_minus, 5, 0);
    CHECK_NEAR(w.p, 20.0 / 512.0, 1e-15);
    /* The other way round: W+ = 5, the same two-sided p. */
    CHECK(mr_study_wilcoxon(y, x, 9, &w));
    CHECK(w.exact && w.w_plus == 5);
    CHECK_NEAR(w.p, 20.0 / 512.0, 1e-15);
    /* The smallest exact two-sided p of n = 5 all one way: 2/32. */
    const double up[5] = {1, 2, 3, 4, 5}, zero[5] = {0};
    CHECK(mr_study_wilcoxon(up, zero, 5, &w));
    CHECK(w.exact && w.w_plus == 15);
    CHECK_NEAR(w.p, 2.0 / 32.0, 1e-15);
    /* Ties or zeros: the normal approximation; a zero is dropped. With
     * d = (1, 1, 2, 0): ranks 1.5, 1.5, 3 of n = 3, W+ = 6, mean 3,
     * variance 3*4*7/24 - (8-2)/48 = 3.375, z = (3 - 0.5)/sqrt(3.375). */
    const double dd[4] = {1, 1, 2, 0}, z4[4] = {0};
    CHECK(mr_study_wilcoxon(dd, z4, 4, &w));
    CHECK(!w.exact && w.n == 3 && w.zeros == 1);
    CHECK_NEAR(w.z, 2.5 / sqrt(3.375), 1e-12);
    CHECK_NEAR(w.p, 2 * mr_stat_normal_cdf(-2.5 / sqrt(3.375)), 1e-12);
}

/* Hollander & Wolfe (1973), p. 140 (R's ?friedman.test): times of 22
 * players rounding first base by three methods. Printed: Friedman
 * chi-squared = 11.143, df = 2, p-value = 0.003805 (ties corrected). */
static void test_friedman(void) {
    const double y[22 * 3] = {5.40, 5.50, 5.55, 5.85, 5.70, 5.75, 5.20, 5.60, 5.50, 5.55, 5.50, 5.40, 5.90, 5.85,
                              5.70, 5.45, 5.55, 5.60, 5.40, 5.40, 5.35, 5.45, 5.50, 5.35, 5.25, 5.15, 5.00, 5.85,
                              5.80, 5.70, 5.25, 5.20, 5.10, 5.65, 5.55, 5.45, 5.60, 5.35, 5.45, 5.05, 5.00, 4.95,
                              5.50, 5.50, 5.40, 5.45, 5.55, 5.50, 5.55, 5.55, 5.35, 5.45, 5.50, 5.55, 5.50, 5.45,
                              5.25, 5.65, 5.60, 5.40, 5.70, 5.65, 5.55, 6.30, 6.30, 6.25};
    mr_study_friedman_result f;
    mr_error err = {0};
    CHECK(mr_study_friedman(y, 22, 3, &f, &err));
    CHECK_NEAR(f.chi2, 11.143, 5e-4);
    CHECK_NEAR(f.df, 2, 0);
    CHECK_NEAR(f.p, 0.003805, 5e-7);
    /* Perfect agreement of the ranks: Kendall's W = 1. */
    const double mono[4 * 3] = {1, 2, 3, 2, 3, 4, 0, 5, 9, 1, 1.5, 2};
    CHECK(mr_study_friedman(mono, 4, 3, &f, &err));
    CHECK_NEAR(f.kendall_w, 1, 1e-12);
    CHECK_NEAR(f.mean_rank[2], 3, 0);
}

/* Bonferroni and Holm (Holm 1979) on p = (0.01, 0.04, 0.03, 0.005), by
 * hand: Bonferroni 4p clipped to 1; Holm sorted 0.005*4 = 0.02, 0.01*3 =
 * 0.03, 0.03*2 = 0.06, 0.04*1 = 0.04 -> kept monotone at 0.06. */
static void test_adjust(void) {
    const double p[4] = {0.01, 0.04, 0.03, 0.005};
    double b[4], h[4];
    mr_study_p_adjust(p, 4, MR_STUDY_ADJUST_BONFERRONI, b);
    mr_study_p_adjust(p, 4, MR_STUDY_ADJUST_HOLM, h);
    CHECK_NEAR(b[0], 0.04, 1e-15);
    CHECK_NEAR(b[1], 0.16, 1e-15);
    CHECK_NEAR(b[3], 0.02, 1e-15);
    CHECK_NEAR(h[3], 0.02, 1e-15);
    CHECK_NEAR(h[0], 0.03, 1e-15);
    CHECK_NEAR(h[2], 0.06, 1e-15);
    CHECK_NEAR(h[1], 0.06, 1e-15);
    const double big[2] = {0.6, 0.7};
    mr_study_p_adjust(big, 2, MR_STUDY_ADJUST_BONFERRONI, b);
    CHECK_NEAR(b[0], 1, 0);
}

/* Distributions at values in every table: t_{0.975, 10} = 2.228,
 * F_{0.95}(2, 10) = 4.10, chi^2_{0.95}(1) = 3.841. D'Agostino's K^2 on the
 * first column of the Friedman data: scipy.stats.normaltest gives
 * K^2 = 5.6515, p = 0.05926 (skew z 1.7213, kurtosis z 1.6397). */
static void test_distributions(void) {
    CHECK_NEAR(mr_stat_t_p2(2.228, 10), 0.05, 2e-4);
    CHECK_NEAR(mr_stat_f_sf(4.10, 2, 10), 0.05, 2e-4);
    CHECK_NEAR(mr_stat_chi2_sf(3.841, 1), 0.05, 1e-4);
    CHECK_NEAR(mr_stat_chi2_sf(2, 2), exp(-1), 1e-14);
    CHECK_NEAR(mr_stat_normal_cdf(1.959964), 0.975, 1e-6);
    const double x[22] = {5.40, 5.85, 5.20, 5.55, 5.90, 5.45, 5.40, 5.45, 5.25, 5.85, 5.25,
                          5.65, 5.60, 5.05, 5.50, 5.45, 5.55, 5.45, 5.50, 5.65, 5.70, 6.30};
    mr_study_normality_result n;
    CHECK(mr_study_normality(x, 22, &n));
    CHECK_NEAR(n.z_skew, 1.72126, 1e-4);
    CHECK_NEAR(n.z_kurt, 1.63975, 1e-4);
    CHECK_NEAR(n.k2, 5.65149, 1e-4);
    CHECK_NEAR(n.p, 0.059264, 1e-5);
    CHECK(!mr_study_normality(x, 7, &n));
}

int main(void) {
    test_paired_t();
    test_rm_anova();
    test_wilcoxon();
    test_friedman();
    test_adjust();
    test_distributions();
    return mr_test_finish("test_study_stats");
}
