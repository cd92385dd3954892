/* lib/study: the statistics against answers known exactly (the issue's
 * cases and the thesis's tables), the plan's reproducibility and shape,
 * the vote log's durability, tolerance and resume, and the analysis files. */
#include "mr_test.h"
#include "mr_study.h"

#include <fcntl.h>
#include <unistd.h>

/* ---------------------------------------------------------- statistics */

static void test_consistence_table51(void) {
    /* Thesis Table 5.1 (left): one participant, t = 4, ties already split. */
    const double A[16] = {0, 1, 1, 0.5,  0, 0, 0, 0.5,  0, 1, 0, 0,  0.5, 0.5, 1, 0};
    mr_study_consistence c = mr_study_consistence_of(A, 4);
    CHECK_NEAR(c.c, 1.25, 1e-12);
    CHECK_NEAR(c.xi, 0.5, 1e-12);
    /* Kendall's maximum for even t is (t^3-4t)/24 = 2: 1 - 1.25/2. */
    CHECK_NEAR(c.xi_kendall, 0.375, 1e-12);
    /* A transitive tournament has no circular triad. */
    const double T[9] = {0, 1, 1, 0, 0, 1, 0, 0, 0};
    c = mr_study_consistence_of(T, 3);
    CHECK_NEAR(c.c, 0, 1e-12);
    CHECK_NEAR(c.xi, 1, 1e-12);
    /* One cycle 0>1>2>0: one circular triad, the maximum for t = 3. */
    const double C3[9] = {0, 1, 0, 0, 0, 1, 1, 0, 0};
    c = mr_study_consistence_of(C3, 3);
    CHECK_NEAR(c.c, 1, 1e-12);
    CHECK_NEAR(c.xi, 0, 1e-12);
    CHECK_NEAR(c.xi_kendall, 0, 1e-12);
}

static void test_agreement_tables(void) {
    /* Table 5.2: each pair 48 : 0 one way or the other, N = 48 -> u = 1. */
    const double A2[16] = {0, 0, 48, 0,  48, 0, 0, 48,  0, 48, 0, 0,  48, 0, 48, 0};
    CHECK_NEAR(mr_study_agreement(A2, 4), 1.0, 1e-12);
    /* Table 5.3: every cell 24 -> u = -1/47 (printed -0.0213). */
    double A3[16];
    for (int i = 0; i < 16; i++) A3[i] = i % 5 == 0 ? 0 : 24;
    CHECK_NEAR(mr_study_agreement(A3, 4), -1.0 / 47.0, 1e-12);
    /* Split ties: the two-participant minimum is -1 (each cell 1). */
    const double w[4] = {0, 1, 1, 0};
    CHECK_NEAR(mr_study_agreement(w, 2), -1.0, 1e-12);
    const double none[4] = {0, 0, 0, 0};
    CHECK(isnan(mr_study_agreement(none, 2)));
}

static void test_split_and_indifference(void) {
    const double w[4] = {0, 3, 1, 0}, ties[4] = {0, 2, 2, 0};
    double A[4];
    mr_study_split_ties(w, ties, 2, A);
    CHECK_NEAR(A[1], 4, 1e-12);
    CHECK_NEAR(A[2], 2, 1e-12);
    bool base;
    /* 30% neutral on different pairs, 60% on identical ones: 0.5. */
    CHECK_NEAR(mr_study_indifference(3, 10, 6, 10, &base), 0.5, 1e-12);
    CHECK(base);
    CHECK_NEAR(mr_study_indifference(9, 10, 3, 10, &base), 1.0, 1e-12); /* clamped */
    CHECK_NEAR(mr_study_indifference(2, 10, 0, 10, &base), 0.2, 1e-12);
    CHECK(!base);
}

static void test_binomial(void) {
    CHECK(mr_study_binom_threshold(47, 0.025) == 31);
    CHECK(mr_study_binom_threshold(25, 0.025) == 18);
    CHECK(mr_study_binom_threshold(23, 0.025) == 17);
    CHECK(mr_study_binom_threshold(48, 0.025) == 32); /* the thesis's example */
    CHECK(mr_study_binom_threshold(3, 0.025) == 4);   /* too few votes: never */
    CHECK_NEAR(mr_study_binom_upper_tail(4, 3), 5.0 / 16.0, 1e-15);
    CHECK_NEAR(mr_study_binom_upper_tail(10, 0), 1.0, 1e-15);
}

static void test_bt_known(void) {
    mr_error err = {0};
    mr_study_scores s;
    /* Cycle: 0 beats 1 twice, 1 beats 2 once, 2 beats 0 once. */
    double w[9] = {0};
    w[0 * 3 + 1] = 2, w[1 * 3 + 2] = 1, w[2 * 3 + 0] = 1;
    mr_study_fit_params p = MR_STUDY_FIT_DEFAULTS;
    CHECK(mr_study_bt_fit(w, 3, &p, &s, &err));
    CHECK(s.converged && !s.pseudo);
    CHECK_NEAR(s.theta[0], 0.419618, 1e-6);
    CHECK_NEAR(s.theta[1], -0.419618, 1e-6);
    CHECK_NEAR(s.theta[2], 0.0, 1e-6);
    /* Consistent data: pi = (4, 2, 1) / 7. */
    double v[9] = {0, 2, 4, 1, 0, 2, 1, 1, 0};
    CHECK(mr_study_bt_fit(v, 3, &p, &s, &err));
    CHECK_NEAR(s.p[0], 4.0 / 7, 1e-8);
    CHECK_NEAR(s.p[1], 2.0 / 7, 1e-8);
    CHECK_NEAR(s.p[2], 1.0 / 7, 1e-8);
    /* The reference fixed at 0: theta_2 = 0, theta_0 = log 4. */
    p.reference = 2;
    CHECK(mr_study_bt_fit(v, 3, &p, &s, &err));
    CHECK_NEAR(s.theta[2], 0, 1e-12);
    CHECK_NEAR(s.se[2], 0, 1e-12);
    CHECK_NEAR(s.theta[0], log(4.0), 1e-8);
    CHECK(s.se[0] > 0 && isfinite(s.se[0]));
    /* Standard error of a two-method fit by hand: theta = log(W1/W2), the
     * information is n p (1-p): 3 wins of 4 -> var = 1 / (4 * 3/4 * 1/4). */
    double two[4] = {0, 3, 1, 0};
    p.reference = 1;
    CHECK(mr_study_bt_fit(two, 2, &p, &s, &err));
    CHECK_NEAR(s.theta[0], log(3.0), 1e-9);
    CHECK_NEAR(s.se[0], sqrt(1.0 / (4 * 0.75 * 0.25)), 1e-7);
}

static void test_davidson_known(void) {
    mr_error err = {0};
    const double pi[4] = {1, 4, 9, 16};
    for (int k = 0; k < 2; k++) {
        double nu = k == 0 ? 1.0 : 2.0;
        double w[16] = {0}, ties[16] = {0};
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                if (i != j) {
                    w[i * 4 + j] = pi[i];
                    ties[i * 4 + j] = nu * sqrt(pi[i] * pi[j]);
                }
        mr_study_fit_params p = MR_STUDY_FIT_DEFAULTS;
        p.reference = 3;
        mr_study_scores s;
        CHECK(mr_study_davidson_fit(w, ties, 4, &p, &s, &err));
        CHECK(s.converged && s.has_nu && !s.pseudo);
        CHECK_NEAR(s.theta[0], -2.772589, 1e-6);
        CHECK_NEAR(s.theta[1], -1.386294, 1e-6);
        CHECK_NEAR(s.theta[2], -0.575364, 1e-6);
        CHECK_NEAR(s.theta[3], 0.0, 1e-12);
        CHECK_NEAR(s.log_nu, k == 0 ? 0.0 : 0.693147, 1e-6);
        for (int i = 0; i < 3; i++) CHECK(s.se[i] > 0 && isfinite(s.se[i]));
        CHECK(s.se_log_nu > 0 && isfinite(s.se_log_nu));
    }
    /* No ties at all: the same as Bradley-Terry. */
    double v[9] = {0, 2, 4, 1, 0, 2, 1, 1, 0}, z[9] = {0};
    mr_study_scores s;
    CHECK(mr_study_davidson_fit(v, z, 3, NULL, &s, &err));
    CHECK(!s.has_nu);
    CHECK_NEAR(s.p[0], 4.0 / 7, 1e-8);
}

static void test_disconnected(void) {
    mr_error err = {0};
    /* Method 0 always wins: no finite maximum without the pseudo-count. */
    double w[9] = {0, 5, 5, 0, 0, 2, 0, 1, 0}, ties[9] = {0, 0, 0, 0, 0, 1, 0, 1, 0};
    int who = -2;
    CHECK(!mr_study_graph_connected(w, ties, 3, &who));
    CHECK(who == 0);
    mr_study_scores s;
    CHECK(mr_study_bt_fit(w, 3, NULL, &s, &err));
    CHECK(s.pseudo && s.isolated == 0 && s.note[0]);
    for (int i = 0; i < 3; i++) CHECK(isfinite(s.theta[i]) && isfinite(s.se[i]) && isfinite(s.p[i]));
    CHECK(s.theta[0] > s.theta[1] && s.theta[0] > s.theta[2]);
    CHECK(mr_study_davidson_fit(w, ties, 3, NULL, &s, &err));
    CHECK(s.pseudo);
    for (int i = 0; i < 3; i++) CHECK(isfinite(s.theta[i]) && isfinite(s.se[i]) && isfinite(s.p[i]));
    CHECK(isfinite(s.log_nu) && isfinite(s.se_log_nu));
    /* Ties alone connect a pair. */
    double t2[4] = {0, 1, 1, 0}, w2[4] = {0, 0, 0, 0};
    CHECK(mr_study_graph_connected(w2, t2, 2, NULL));
    /* Only ties: nu is bounded, scores equal and finite. */
    CHECK(mr_study_davidson_fit(w2, t2, 2, NULL, &s, &err));
    CHECK(isfinite(s.log_nu) && isfinite(s.se[0]));
    CHECK_NEAR(s.theta[0], s.theta[1], 1e-9);
}

int main(void) {
    test_consistence_table51();
    test_agreement_tables();
    test_split_and_indifference();
    test_binomial();
    test_bt_known();
    test_davidson_known();
    test_disconnected();
    return mr_test_finish("test_study");
}
