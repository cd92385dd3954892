/* lib/study: the statistics against answers known exactly (the issue's
 * cases and the thesis's tables), the plan's reproducibility and shape,
 * the vote log's durability, tolerance and resume, and the analysis files. */
#include "mr_test.h"
#include "mr_study.h"

#include <fcntl.h>
#include <unistd.h>

/* ------------------------------------------------------------ families */

/* The family table: one name per row in the option's enum, and the shadows
 * row renders the four shadow-map methods (each set up to its own method,
 * never off or the ground truth) against a reference, from suite cases that
 * exist. Checked without a GPU: the setups and the argument checks. */
static void test_families(void) {
    int sh = -1;
    for (int f = 0; f < mr_study_family_count; f++) {
        CHECK(mr_study_family_names[f] && strcmp(mr_study_family_names[f], mr_study_families[f].name) == 0);
        CHECK(mr_study_families[f].has_reference == (mr_study_families[f].reference != NULL));
        if (strcmp(mr_study_families[f].name, "shadows") == 0) sh = f;
    }
    CHECK(mr_study_family_names[mr_study_family_count] == NULL);
    CHECK_MSG(sh >= 0, "no shadows family");
    if (sh < 0) return;
    const mr_study_family *fam = &mr_study_families[sh];
    CHECK(fam->has_reference && fam->shadow_suite);
    bool seen[MR_SHADOW_METHOD_COUNT] = {false};
    int n = 0;
    for (; fam->methods[n]; n++) {
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fam->setup(&fp, n);
        mr_shadow_method want;
        CHECK_MSG(mr_shadow_method_parse(fam->methods[n], &want) && fp.shadow.method == want,
                  "method %s set up as %d", fam->methods[n], (int)fp.shadow.method);
        CHECK(fp.shadow.method != MR_SHADOW_OFF && fp.shadow.method != MR_SHADOW_GROUNDTRUTH);
        CHECK(!seen[fp.shadow.method]);
        seen[fp.shadow.method] = true;
    }
    /* The thesis's four: pcf, pcss, bp and the reference; hard only when asked. */
    CHECK(n == 3 && seen[MR_SHADOW_PCF] && seen[MR_SHADOW_PCSS] && seen[MR_SHADOW_BP] && !seen[MR_SHADOW_HARD]);
    CHECK(fam->optional && !strcmp(fam->optional, "hard"));
    {
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fam->setup(&fp, n);
        CHECK(fp.shadow.method == MR_SHADOW_HARD);
    }
    /* The thesis's stimuli: 800 x 450, antialiased, ambient 0.4. */
    CHECK(fam->width == 800 && fam->height == 450 && fam->supersample == 2 && fabsf(fam->ambient - 0.4f) < 1e-6f);
    /* Its 13 categories: the suite's 12 systematic ones and the factory. */
    CHECK(MR_STUDY_SHADOW_CASES == 13);
    for (int c = 0; c < MR_STUDY_SHADOW_CASES; c++) {
        bool found = false;
        for (int i = 0; i < MR_SHADOW_SUITE_COUNT; i++)
            found |= strcmp(mr_shadow_suite_name(i), mr_study_shadow_cases[c]) == 0;
        CHECK_MSG(found, "case %s", mr_study_shadow_cases[c]);
        for (int d = 0; d < c; d++) CHECK(strcmp(mr_study_shadow_cases[c], mr_study_shadow_cases[d]) != 0);
    }
    /* Out-of-range arguments fail before anything is rendered or written. */
    mr_study_stimuli_params p = MR_STUDY_STIMULI_DEFAULTS;
    p.family = sh;
    p.cases = MR_STUDY_SHADOW_CASES + 1;
    mr_error err = {0};
    int count = 7;
    CHECK(!mr_study_stimuli_render(NULL, &p, "/nonexistent/study_stimuli", &count, &err) && err.code == MR_ERR_INVALID);
    CHECK(count == 0);
    p.cases = 1;
    p.gt_samples = 0;
    CHECK(!mr_study_stimuli_render(NULL, &p, "/nonexistent/study_stimuli", &count, &err) && err.code == MR_ERR_INVALID);
}

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

/* Consistence at odd and even t >= 5, where Kendall's maximum differs by
 * parity ((t^3-t)/24 odd, (t^3-4t)/24 even) and no clamp hides it: a
 * transitive tournament 0 > 1 > ... > t-1 with one result reversed, the
 * circular triads counted by hand (each j between the reversed pair's
 * ends closes one). */
static void test_consistence_odd_even(void) {
    static const struct { int t, lo, hi; double c, xi, xik; } cases[] = {
        {5, 0, 2, 1, 1 - 24.0 * 1 / 120, 1 - 1.0 / 5},   /* cmax 5 */
        {5, 0, 4, 3, 1 - 24.0 * 3 / 120, 1 - 3.0 / 5},   /* cmax 5 */
        {6, 0, 3, 2, 1 - 24.0 * 2 / 210, 1 - 2.0 / 8},   /* cmax 8 */
        {7, 0, 6, 5, 1 - 24.0 * 5 / 336, 1 - 5.0 / 14},  /* cmax 14 */
        {8, 1, 5, 3, 1 - 24.0 * 3 / 504, 1 - 3.0 / 20}}; /* cmax 20 */
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        int t = cases[k].t;
        double A[64] = {0};
        for (int i = 0; i < t; i++)
            for (int j = i + 1; j < t; j++) A[i * t + j] = 1;
        A[cases[k].lo * t + cases[k].hi] = 0, A[cases[k].hi * t + cases[k].lo] = 1;
        mr_study_consistence c = mr_study_consistence_of(A, t);
        CHECK_MSG(fabs(c.c - cases[k].c) < 1e-12, "t %d: c %g, want %g", t, c.c, cases[k].c);
        CHECK_MSG(fabs(c.xi - cases[k].xi) < 1e-12, "t %d: xi %g, want %g", t, c.xi, cases[k].xi);
        CHECK_MSG(fabs(c.xi_kendall - cases[k].xik) < 1e-12, "t %d: Kendall's xi %g, want %g", t, c.xi_kendall,
                  cases[k].xik);
    }
    /* Agreement at t = 5 and 6, three judges: a pair 3:0 adds 3 agreeing
     * judge pairs, 2:1 adds 1, of 3 possible; u = 2 tau / max_tau - 1. */
    for (int t = 5; t <= 6; t++) {
        double A[36] = {0};
        int pairs = 0, split = 0;
        for (int i = 0; i < t; i++)
            for (int j = i + 1; j < t; j++, pairs++) {
                bool s = (i + j) % 3 == 0;
                split += s;
                A[i * t + j] = s ? 2 : 3, A[j * t + i] = s ? 1 : 0;
            }
        double want = 2.0 * (3 * (pairs - split) + split) / (3.0 * pairs) - 1;
        CHECK_MSG(fabs(mr_study_agreement(A, t) - want) < 1e-12, "t %d: u %g, want %g", t, mr_study_agreement(A, t), want);
    }
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
    /* Centred (no reference): theta = +-d/2, so each se is half of d's. */
    p.reference = -1;
    CHECK(mr_study_bt_fit(two, 2, &p, &s, &err));
    CHECK_NEAR(s.theta[0], log(3.0) / 2, 1e-9);
    CHECK_NEAR(s.se[0], sqrt(1.0 / (4 * 0.75 * 0.25)) / 2, 1e-7);
    CHECK_NEAR(s.se[1], s.se[0], 1e-12);
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
    /* Two methods, 4 : 1 with 1 tie (saturated, so by hand): theta = log 4,
     * nu = 1/sqrt(4 * 1); the information n Cov(f) with p = (2/3, 1/6, 1/6)
     * and f = (1, 0), (0, 0), (1/2, 1) is [[7/8, -1/4], [-1/4, 5/6]]
     * (determinant 2/3), whose inverse gives var theta = 5/4 and
     * var log nu = 21/16. */
    {
        double w2[4] = {0, 4, 1, 0}, t2[4] = {0, 1, 1, 0};
        mr_study_fit_params p = MR_STUDY_FIT_DEFAULTS;
        p.reference = 1;
        mr_study_scores s;
        CHECK(mr_study_davidson_fit(w2, t2, 2, &p, &s, &err));
        CHECK_NEAR(s.theta[0], log(4.0), 1e-8);
        CHECK_NEAR(s.log_nu, log(0.5), 1e-8);
        CHECK_NEAR(s.se[0], sqrt(5.0 / 4.0), 1e-7);
        CHECK_NEAR(s.se_log_nu, sqrt(21.0 / 16.0), 1e-7);
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


/* ------------------------------------------------------- plan and votes */

static bool write_png(const char *dir, const char *method, const char *stim, int grey) {
    char path[8300], d[4200];
    snprintf(d, sizeof d, "%s/%s", dir, method);
    mr_error err = {0};
    if (!mr_mkdirs(d, &err)) return false;
    snprintf(path, sizeof path, "%s/%s.png", d, stim);
    mr_image img = {0};
    if (!mr_image_alloc(&img, 4, 4, 3, MR_PIX_U8, &err)) return false;
    memset(img.data, grey, mr_image_bytes(&img));
    bool ok = mr_image_save_png(path, &img, &err);
    mr_image_free(&img);
    return ok;
}

/* DIR with methods a, b, c, reference and stimuli s1, s2 (c also has s3). */
static bool make_stimuli(char *dir, size_t n, bool reference) {
    if (!mr_test_fresh_dir(reference ? "study_stimuli" : "study_stimuli_noref", dir, n)) return false;
    const char *methods[4] = {"a", "b", "c", "reference"};
    bool ok = true;
    for (int m = 0; m < (reference ? 4 : 3); m++)
        for (int s = 0; s < 2; s++) ok = ok && write_png(dir, methods[m], s ? "s2" : "s1", 40 * m + s);
    return ok && write_png(dir, "c", "s3", 9);
}

static void test_plan(void) {
    char dir[4096];
    CHECK(make_stimuli(dir, sizeof dir, true));
    mr_error err = {0};
    mr_study_set set;
    CHECK(mr_study_scan(dir, &set, &err));
    CHECK(set.method_count == 4 && set.reference == 3 && set.stimulus_count == 2);
    CHECK(strcmp(set.stimuli[0], "s1") == 0 && strcmp(set.stimuli[1], "s2") == 0); /* s3 left out */
    unsigned mask = 0;
    CHECK(mr_study_blocks_parse("I,III", &mask, &err) && mask == 5u);
    CHECK(!mr_study_blocks_parse("I,IV", &mask, &err));
    CHECK(!mr_study_blocks_parse("II,II", &mask, &err));
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.seed = 7;
    mr_study_plan a, b, c;
    CHECK(mr_study_plan_make(dir, &set, &pp, &a, &err));
    CHECK(a.blocks == 7u);
    CHECK(a.trial_count == 3 * 2 * (6 + 1));
    /* Per block and stimulus: every unordered pair once, one identical pair;
     * blocks in order; sides not all the same. */
    int lefts_low = 0;
    for (int blk = 1; blk <= 3; blk++)
        for (int st = 0; st < 2; st++) {
            int seen[16] = {0}, identical = 0;
            for (int k = 0; k < a.trial_count; k++) {
                const mr_study_trial *t = &a.trials[k];
                if (t->block != blk || t->stimulus != st) continue;
                CHECK(k >= (blk - 1) * 14 && k < blk * 14);
                if (t->left == t->right) identical++;
                else {
                    int lo = t->left < t->right ? t->left : t->right, hi = t->left ^ t->right ^ lo;
                    seen[lo * 4 + hi]++;
                    lefts_low += t->left < t->right;
                }
            }
            CHECK(identical == 1);
            for (int i = 0; i < 4; i++)
                for (int j = i + 1; j < 4; j++) CHECK(seen[i * 4 + j] == 1);
        }
    CHECK(lefts_low > 0 && lefts_low < 36);
    /* Shuffled within each block: the stimuli are not in generation order. */
    int changes = 0;
    for (int k = 1; k < 14; k++) changes += a.trials[k].stimulus != a.trials[k - 1].stimulus;
    CHECK(changes > 1);
    /* Reproducible from the seed; another seed gives another order. */
    CHECK(mr_study_plan_make(dir, &set, &pp, &b, &err));
    CHECK(strcmp(a.id, b.id) == 0 && memcmp(a.trials, b.trials, sizeof *a.trials * (size_t)a.trial_count) == 0);
    pp.seed = 8;
    CHECK(mr_study_plan_make(dir, &set, &pp, &c, &err));
    CHECK(strcmp(a.id, c.id) != 0);
    mr_study_plan_free(&b);
    mr_study_plan_free(&c);
    /* Save and load. */
    char path[4200];
    snprintf(path, sizeof path, "%s/plan.json", dir);
    CHECK(mr_study_plan_save(path, &a, &err));
    CHECK(mr_study_plan_load(path, &b, &err));
    CHECK(strcmp(a.id, b.id) == 0 && b.trial_count == a.trial_count && b.fixation_ms == 2000);
    CHECK(memcmp(a.trials, b.trials, sizeof *a.trials * (size_t)a.trial_count) == 0);
    mr_study_plan_free(&b);
    /* An edited plan is refused. */
    size_t size;
    char *text = mr_file_read(path, &size, 0, &err);
    char *hit = text ? strstr(text, "\"left\":\t\"a\"") : NULL;
    if (!hit && text) hit = strstr(text, "\"left\": \"a\"");
    CHECK(hit != NULL);
    if (hit) {
        char *q = strchr(hit + 7, 'a');
        *q = 'b';
        CHECK(mr_file_write_atomic(path, text, size, &err));
        CHECK(!mr_study_plan_load(path, &b, &err));
        CHECK(strstr(err.msg, "edited") != NULL);
    }
    free(text);
    /* Block II needs a reference. */
    char dir2[4096];
    mr_study_set set2;
    CHECK(make_stimuli(dir2, sizeof dir2, false));
    CHECK(mr_study_scan(dir2, &set2, &err));
    pp.blocks = 2u;
    CHECK(!mr_study_plan_make(dir2, &set2, &pp, &b, &err));
    pp.blocks = 0;
    CHECK(mr_study_plan_make(dir2, &set2, &pp, &b, &err) && b.blocks == 1u && b.trial_count == 2 * (3 + 1));
    mr_study_plan_free(&b);
    mr_study_set_free(&set2);
    mr_study_plan_free(&a);
    mr_study_set_free(&set);
}

static mr_study_vote vote_of(const mr_study_plan *p, const char *who, int k, mr_study_answer a) {
    mr_study_vote v;
    memset(&v, 0, sizeof v);
    const mr_study_trial *t = &p->trials[k];
    snprintf(v.plan, sizeof v.plan, "%s", p->id);
    snprintf(v.participant, sizeof v.participant, "%s", who);
    v.block = t->block;
    v.trial = k;
    snprintf(v.stimulus, sizeof v.stimulus, "%s", p->set.stimuli[t->stimulus]);
    snprintf(v.left, sizeof v.left, "%s", p->set.methods[t->left]);
    snprintf(v.right, sizeof v.right, "%s", p->set.methods[t->right]);
    v.answer = a;
    v.slider = a;
    v.ms = 100;
    return v;
}

static void test_votes(void) {
    char dir[4096], path[4200];
    CHECK(make_stimuli(dir, sizeof dir, true));
    mr_error err = {0};
    mr_study_set set;
    mr_study_plan plan;
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    CHECK(mr_study_scan(dir, &set, &err) && mr_study_plan_make(dir, &set, &pp, &plan, &err));
    snprintf(path, sizeof path, "%s/votes.jsonl", dir);
    for (int k = 0; k < 3; k++) {
        mr_study_vote v = vote_of(&plan, "p1", k, MR_STUDY_LEFT);
        CHECK(mr_study_vote_append(path, &v, &err));
    }
    mr_study_votes vs = {0};
    CHECK(mr_study_votes_read(path, false, &vs, &err));
    CHECK(vs.count == 3 && vs.bad_lines == 0 && !vs.torn_tail);
    CHECK(vs.v[2].trial == 2 && vs.v[2].answer == MR_STUDY_LEFT && strcmp(vs.v[1].participant, "p1") == 0);
    bool *answered = calloc((size_t)plan.trial_count, 1);
    CHECK(mr_study_resume(&plan, &vs, "p1", answered, &err) == 3);
    CHECK(answered[0] && answered[2] && !answered[3]);
    CHECK(mr_study_resume(&plan, &vs, "p2", answered, &err) == 0);
    mr_study_votes_free(&vs);
    /* A torn last line (killed mid-write): skipped, sealed, appended after. */
    int fd = open(path, O_WRONLY | O_APPEND);
    CHECK(fd >= 0 && write(fd, "{\"plan\":\"", 9) == 9);
    close(fd);
    CHECK(mr_study_votes_read(path, false, &vs, &err));
    CHECK(vs.count == 3 && vs.bad_lines == 1 && vs.torn_tail);
    mr_study_votes_free(&vs);
    CHECK(mr_study_votes_seal(path, &err));
    CHECK(mr_study_votes_seal(path, &err)); /* sealed once only */
    mr_study_vote v = vote_of(&plan, "p1", 3, MR_STUDY_NEUTRAL);
    CHECK(mr_study_vote_append(path, &v, &err));
    /* The same trial answered twice: the first answer is kept. */
    v.answer = MR_STUDY_RIGHT;
    CHECK(mr_study_vote_append(path, &v, &err));
    CHECK(mr_study_votes_read(path, false, &vs, &err));
    CHECK(vs.count == 4 && vs.bad_lines == 1 && vs.duplicates == 1 && !vs.torn_tail);
    CHECK(vs.v[3].answer == MR_STUDY_NEUTRAL);
    CHECK(mr_study_resume(&plan, &vs, "p1", answered, &err) == 4);
    size_t size;
    char *text = mr_file_read(path, &size, 0, &err);
    CHECK(text && strstr(text, "{\"plan\":\"\n") != NULL); /* what was written stays */
    free(text);
    mr_study_votes_free(&vs);
    /* The same participant's votes of another plan in this log: an error. */
    mr_study_plan other;
    pp.seed = 99;
    CHECK(mr_study_plan_make(dir, &set, &pp, &other, &err));
    CHECK(mr_study_votes_read(path, false, &vs, &err));
    CHECK(mr_study_resume(&other, &vs, "p1", answered, &err) == -1 && strstr(err.msg, "another plan"));
    CHECK(mr_study_resume(&other, &vs, "p9", answered, &err) == 0);
    mr_study_votes_free(&vs);
    /* Numbers that are not finite, or a slider outside [-1, 1]: not a vote. */
    char bad_path[4300];
    snprintf(bad_path, sizeof bad_path, "%s/bad_votes.jsonl", dir);
    const char *bad_text = "{\"plan\":\"x\",\"participant\":\"p\",\"block\":\"I\",\"trial\":0,\"stimulus\":\"s\","
                           "\"left\":\"a\",\"right\":\"b\",\"answer\":\"left\",\"ms\":1e999}\n"
                           "{\"plan\":\"x\",\"participant\":\"p\",\"block\":\"I\",\"trial\":1,\"stimulus\":\"s\","
                           "\"left\":\"a\",\"right\":\"b\",\"answer\":\"left\",\"slider\":3}\n"
                           "{\"plan\":\"x\",\"participant\":\"p\",\"block\":\"I\",\"trial\":2,\"stimulus\":\"s\","
                           "\"left\":\"a\",\"right\":\"b\",\"answer\":\"left\"}\n";
    CHECK(mr_file_write_atomic(bad_path, bad_text, strlen(bad_text), &err));
    CHECK(mr_study_votes_read(bad_path, false, &vs, &err));
    CHECK(vs.count == 1 && vs.bad_lines == 2 && vs.v[0].trial == 2);
    mr_study_votes_free(&vs);
    CHECK(mr_study_votes_read("/nonexistent/votes.jsonl", true, &vs, &err) && vs.count == 0);
    CHECK(!mr_study_votes_read("/nonexistent/votes.jsonl", false, &vs, &err));
    free(answered);
    mr_study_plan_free(&other);
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

/* Five participants who all rank reference > c > b > a, answer every
 * identical pair with "no preference" except p5 once. */
static void test_analyze(void) {
    char dir[4096], out[4200], path[4400];
    CHECK(make_stimuli(dir, sizeof dir, true));
    mr_error err = {0};
    mr_study_set set;
    mr_study_plan plan;
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.blocks = 1u;
    CHECK(mr_study_scan(dir, &set, &err) && mr_study_plan_make(dir, &set, &pp, &plan, &err));
    mr_study_votes vs = {0};
    int rank[4] = {0, 1, 2, 3}; /* a < b < c < reference */
    for (int p = 0; p < 5; p++) {
        char who[8];
        snprintf(who, sizeof who, "p%d", p + 1);
        for (int k = 0; k < plan.trial_count; k++) {
            const mr_study_trial *t = &plan.trials[k];
            mr_study_answer a = t->left == t->right ? (p == 4 && t->stimulus == 0 ? MR_STUDY_LEFT : MR_STUDY_NEUTRAL)
                                : rank[t->left] > rank[t->right] ? MR_STUDY_LEFT : MR_STUDY_RIGHT;
            mr_study_vote v = vote_of(&plan, who, k, a);
            if (vs.count == vs.cap) {
                vs.cap = vs.cap ? 2 * vs.cap : 64;
                vs.v = realloc(vs.v, (size_t)vs.cap * sizeof *vs.v);
            }
            vs.v[vs.count++] = v;
        }
    }
    snprintf(out, sizeof out, "%s/analysis", dir);
    mr_study_analyze_params ap = MR_STUDY_ANALYZE_DEFAULTS;
    CHECK(mr_study_analyze(&vs, &plan, &ap, out, &err));
    const char *files[] = {"pairs.csv", "scores.csv", "consistence.csv", "participants.csv", "agreement.csv",
                           "identical.csv", "chart_I.svg", "summary.md"};
    for (int i = 0; i < 8; i++) {
        snprintf(path, sizeof path, "%s/%s", out, files[i]);
        CHECK_MSG(mr_file_exists(path), "%s", files[i]);
    }
    size_t size;
    snprintf(path, sizeof path, "%s/pairs.csv", out);
    char *text = mr_file_read(path, &size, 0, &err);
    /* Pooled: 10 votes per pair, all for the better method; k(10) = 9. */
    CHECK(text && strstr(text, "\nI,all,a,b,10,0,10,0,0,10,9,1,b,"));
    CHECK(text && strstr(text, "\nI,s1,c,reference,5,0,5,0,0,5,6,-1,,")); /* n = 5 is too few */
    free(text);
    snprintf(path, sizeof path, "%s/agreement.csv", out);
    text = mr_file_read(path, &size, 0, &err);
    CHECK(text && strstr(text, "\nI,s1,1.000000,0.000000,0.000000,1,0,30,4,5\n")); /* total agreement, p5 saw a difference */
    free(text);
    snprintf(path, sizeof path, "%s/participants.csv", out);
    text = mr_file_read(path, &size, 0, &err);
    CHECK(text && strstr(text, "\np5,14,2,1.000000,1.000000,0,2,1\n"));
    free(text);
    /* Everyone agrees: the graph is not strongly connected, the scores are
     * still finite and ordered, and the summary says so. */
    snprintf(path, sizeof path, "%s/summary.md", out);
    text = mr_file_read(path, &size, 0, &err);
    CHECK(text && strstr(text, "not strongly connected") && strstr(text, "reference > a"));
    free(text);
    snprintf(path, sizeof path, "%s/scores.csv", out);
    text = mr_file_read(path, &size, 0, &err);
    CHECK(text && !strstr(text, "nan") && strstr(text, "\nI,all,davidson,reference,0.000000,0.000000,"));
    free(text);
    /* Votes of an unknown plan are left out. */
    for (int i = 0; i < 3; i++) snprintf(vs.v[i].plan, sizeof vs.v[i].plan, "%s", "0123456789abcdef");
    CHECK(mr_study_analyze(&vs, &plan, &ap, out, &err));
    mr_study_votes_free(&vs);
    CHECK(!mr_study_analyze(&vs, &plan, &ap, out, &err)); /* no votes */
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

/* The run controller without a window: fixation, the pair, a key answer,
 * block II's reference, a vote that could not be stored. */
static void test_runner(void) {
    char dir[4096];
    CHECK(make_stimuli(dir, sizeof dir, true));
    mr_error err = {0};
    mr_study_set set;
    mr_study_plan plan;
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.fixation_ms = 500;
    pp.blocks = 2u; /* block II only */
    CHECK(mr_study_scan(dir, &set, &err) && mr_study_plan_make(dir, &set, &pp, &plan, &err));
    bool *answered = calloc((size_t)plan.trial_count, 1);
    answered[0] = answered[1] = true;
    mr_study_run_params rp = MR_STUDY_RUN_DEFAULTS;
    rp.plan = &plan;
    rp.participant = "p7";
    rp.first_trial = 0;
    rp.answered = answered;
    rp.image_w = 4, rp.image_h = 4;
    rp.now = 10.0;
    mr_study_runner *r = mr_study_runner_create(&rp, &err);
    if (!r) {
        printf("test_runner: skipped (%s)\n", err.msg); /* no system font */
        free(answered);
        mr_study_plan_free(&plan);
        mr_study_set_free(&set);
        return;
    }
    mr_study_frame f;
    mr_study_vote v;
    mr_event key = {MR_EVENT_KEY, 0, 0, MR_KEY_RIGHT};
    mr_study_runner_push_event(r, &key);
    mr_study_runner_frame(r, 10.2, 800, 600, &f, &v);
    CHECK(f.fixation && f.image_count == 0 && !f.vote); /* a key during the cross does nothing */
    mr_study_runner_frame(r, 10.6, 800, 600, &f, &v);
    CHECK(!f.fixation && f.trial == 2 && f.image_count == 3); /* answered trials skipped */
    CHECK(f.image_method[0] == plan.set.reference);
    CHECK(f.image_rect[0].y < f.image_rect[1].y && f.image_rect[1].x < f.image_rect[2].x);
    mr_study_runner_push_event(r, &key);
    mr_study_runner_frame(r, 11.1, 800, 600, &f, &v);
    CHECK(f.vote && v.trial == 2 && v.answer == MR_STUDY_RIGHT && v.slider == 1 && v.block == 2);
    CHECK_NEAR(v.ms, 500, 1e-6);
    CHECK(strcmp(v.participant, "p7") == 0 && strcmp(v.plan, plan.id) == 0);
    CHECK(strcmp(v.left, plan.set.methods[plan.trials[2].left]) == 0);
    /* Not stored: the same trial again, at once. */
    mr_study_runner_vote_failed(r, "disk full");
    mr_study_runner_frame(r, 11.2, 800, 600, &f, &v);
    CHECK(!f.fixation && f.trial == 2 && !f.vote);
    CHECK(mr_study_runner_answered(r) == 0);
    mr_study_runner_push_event(r, &key);
    mr_study_runner_frame(r, 11.3, 800, 600, &f, &v);
    CHECK(f.vote && v.trial == 2);
    mr_study_runner_frame(r, 11.4, 800, 600, &f, &v);
    CHECK(f.fixation && mr_study_runner_answered(r) == 1);
    mr_study_runner_destroy(&r);
    CHECK(r == NULL);
    free(answered);
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

int main(void) {
    test_families();
    test_consistence_table51();
    test_consistence_odd_even();
    test_agreement_tables();
    test_split_and_indifference();
    test_binomial();
    test_bt_known();
    test_davidson_known();
    test_disconnected();
    test_plan();
    test_votes();
    test_analyze();
    test_runner();
    return mr_test_finish("test_study");
}
