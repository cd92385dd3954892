/* `mrcheck study analyze` of a pairwise study: votes -> the thesis's
 * tables (ch. 5) per block (I, II, III-A, III-B) and category (a
 * category's two scenes pooled, as the thesis's matrices are) as CSV, a
 * chart per block in the manner of its Fig. 6.4 (SVG), and a Markdown
 * summary; computed without the participants below the consistence
 * threshold and, in all_participants/, with everyone. The numbers come
 * from stats.c; this file only counts and writes. */
#include "mr_eval.h"
#include "mr_study.h"
#include "study_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

static const char *const k_adjust_names[] = {"none", "bonferroni", "holm", NULL};
static const char *const k_test_names[] = {"auto", "anova", "friedman", NULL};

const mr_opt mr_study_analyze_opts[] = {
    {"alpha", MR_OPT_DOUBLE, offsetof(mr_study_analyze_params, alpha), 1e-6, 0.5, 0.025, NULL,
     "binomial test level per tail (the thesis's 0.025)", 0},
    {"min-consistence", MR_OPT_DOUBLE, offsetof(mr_study_analyze_params, min_consistence), 0, 1, 0.3, NULL,
     "flag participants whose mean coefficient of consistence is below this", 0},
    {"pseudo", MR_OPT_DOUBLE, offsetof(mr_study_analyze_params, pseudo), 1e-6, 10, 0.5, NULL,
     "pseudo-wins added each way to every pair when the comparison graph is not strongly connected", 0},
    {"z", MR_OPT_DOUBLE, offsetof(mr_study_analyze_params, z), 0.1, 10, 1.96, NULL,
     "confidence interval of the scores: theta +- z * standard error", 0},
    {"level", MR_OPT_DOUBLE, offsetof(mr_study_analyze_params, level), 1e-6, 0.5, 0.05, NULL,
     "rating, task: significance level of Mauchly's, the normality and the post hoc tests", 0},
    {"adjust", MR_OPT_ENUM, offsetof(mr_study_analyze_params, adjust), 0, 0, 1, k_adjust_names,
     "rating, task: post hoc adjustment", 0},
    {"test", MR_OPT_ENUM, offsetof(mr_study_analyze_params, test), 0, 0, 0, k_test_names,
     "task: auto (RM-ANOVA where the residuals look normal, else Friedman), anova or friedman; "
     "rating: anova (auto) or friedman (with Wilcoxon post hoc)", 0},
    {"tap-tolerance", MR_OPT_DOUBLE, offsetof(mr_study_analyze_params, tap_tolerance), 0, 1e6, 40, NULL,
     "task: a tap this near the answer (image pixels) counts as right", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

/* ------------------------------------------------------------- tallies */

typedef char name_t[MR_STUDY_NAME_MAX];

typedef struct names {
    name_t *v;
    int n, cap;
} names;

static int names_find(const names *ns, const char *s) {
    for (int i = 0; i < ns->n; i++)
        if (strcmp(ns->v[i], s) == 0) return i;
    return -1;
}

static int names_add(names *ns, const char *s) {
    int i = names_find(ns, s);
    if (i >= 0) return i;
    if (ns->n == ns->cap) {
        int cap = ns->cap ? ns->cap * 2 : 16;
        void *p = realloc(ns->v, (size_t)cap * sizeof *ns->v);
        if (!p) return -1;
        ns->v = p;
        ns->cap = cap;
    }
    snprintf(ns->v[ns->n], MR_STUDY_NAME_MAX, "%s", s);
    return ns->n++;
}

static int cmp_name(const void *a, const void *b) { return strcmp((const char *)a, (const char *)b); }

/* Analysis blocks: I, II, and block III split by group (A: "looks
 * better", B: "physically more plausible"); a block III vote without a
 * group was asked block I's question (A). */
#define NB 4
static const char *ablock_name(int b) {
    static const char *const n[NB] = {"I", "II", "III-A", "III-B"};
    return b >= 1 && b <= NB ? n[b - 1] : "?";
}
static int ablock_of(const mr_study_vote *v) { return v->block < 3 ? v->block : v->group == MR_STUDY_GROUP_B ? 4 : 3; }

/* Counts of one (block, category) cell, or of a block pooled ("all"). */
typedef struct cell {
    double w[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS];
    double ties[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS];
    double id_n[MR_STUDY_MAX_METHODS], id_neutral[MR_STUDY_MAX_METHODS], id_left[MR_STUDY_MAX_METHODS],
        id_right[MR_STUDY_MAX_METHODS];
} cell;

/* One participant's answers in one (block, stimulus). */
typedef struct pcell {
    double A[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS];
    unsigned char seen[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS]; /* answers per pair (i < j) */
} pcell;

typedef struct tally {
    int t, S, P;
    names methods, stimuli, people;
    int reference;
    bool block_present[NB + 1];
    cell *cells;      /* (block 1..NB) x (S + 1): index S is "all"; S counts categories */
    pcell *pcells;    /* P x NB x S */
    int *votes_of;    /* per participant */
} tally;

static cell *cell_at(tally *T, int b, int s) { return &T->cells[(size_t)(b - 1) * (T->S + 1) + (s < 0 ? T->S : s)]; }
static pcell *pcell_at(tally *T, int p, int b, int s) { return &T->pcells[((size_t)p * NB + (b - 1)) * T->S + s]; }

static void count_into(cell *c, int t, int L, int R, mr_study_answer a) {
    if (L == R) {
        c->id_n[L] += 1;
        if (a == MR_STUDY_NEUTRAL) c->id_neutral[L] += 1;
        else if (a == MR_STUDY_LEFT) c->id_left[L] += 1;
        else c->id_right[L] += 1;
        return;
    }
    if (a == MR_STUDY_LEFT) c->w[L * t + R] += 1;
    else if (a == MR_STUDY_RIGHT) c->w[R * t + L] += 1;
    else {
        c->ties[L * t + R] += 1;
        c->ties[R * t + L] += 1;
    }
}

static bool tally_build(tally *T, const mr_study_votes *votes, const mr_study_plan *plan, bool *use, mr_error *err) {
    memset(T, 0, sizeof *T);
    if (plan) {
        for (int m = 0; m < plan->set.method_count; m++) names_add(&T->methods, plan->set.methods[m]);
        for (int s = 0; s < plan->set.stimulus_count; s++) {
            char c[MR_STUDY_NAME_MAX];
            mr_study_category_of(plan->set.stimuli[s], c, sizeof c);
            names_add(&T->stimuli, c);
        }
    }
    int other_plan = 0, unknown = 0;
    for (int i = 0; i < votes->count; i++) {
        const mr_study_vote *v = &votes->v[i];
        use[i] = false;
        char cat[MR_STUDY_NAME_MAX];
        mr_study_category_of(v->stimulus, cat, sizeof cat);
        if (v->design != MR_STUDY_PAIRWISE) {
            unknown++;
            continue;
        }
        if (plan && strcmp(v->plan, plan->id) != 0) {
            if (!other_plan++) mr_log(MR_LOG_WARN, "study: votes of plan %s are not of this plan (%s): left out", v->plan, plan->id);
            continue;
        }
        if (plan && (names_find(&T->methods, v->left) < 0 || names_find(&T->methods, v->right) < 0 ||
                     names_find(&T->stimuli, cat) < 0)) {
            unknown++;
            continue;
        }
        if (names_add(&T->methods, v->left) < 0 || names_add(&T->methods, v->right) < 0 ||
            names_add(&T->stimuli, cat) < 0 || names_add(&T->people, v->participant) < 0)
            return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        use[i] = true;
    }
    if (other_plan) mr_log(MR_LOG_WARN, "study: %d votes of other plans left out", other_plan);
    if (unknown) mr_log(MR_LOG_WARN, "study: %d votes name a method or stimulus the plan does not have: left out", unknown);
    if (T->methods.n > MR_STUDY_MAX_METHODS)
        return mr_fail(err, MR_ERR_INVALID, "the votes name %d methods (at most %d)", T->methods.n, MR_STUDY_MAX_METHODS);
    if (T->methods.n < 2 || T->people.n == 0) return mr_fail(err, MR_ERR_INVALID, "no votes to analyse");
    qsort(T->methods.v, (size_t)T->methods.n, sizeof(name_t), cmp_name);
    qsort(T->stimuli.v, (size_t)T->stimuli.n, sizeof(name_t), cmp_name);
    qsort(T->people.v, (size_t)T->people.n, sizeof(name_t), cmp_name);
    T->t = T->methods.n;
    T->S = T->stimuli.n;
    T->P = T->people.n;
    T->reference = names_find(&T->methods, MR_STUDY_REFERENCE);
    T->cells = calloc((size_t)NB * (T->S + 1), sizeof *T->cells);
    T->pcells = calloc((size_t)T->P * NB * T->S, sizeof *T->pcells);
    T->votes_of = calloc((size_t)T->P, sizeof *T->votes_of);
    if (!T->cells || !T->pcells || !T->votes_of) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int t = T->t;
    for (int i = 0; i < votes->count; i++) {
        if (!use[i]) continue;
        const mr_study_vote *v = &votes->v[i];
        int L = names_find(&T->methods, v->left), R = names_find(&T->methods, v->right);
        char cat[MR_STUDY_NAME_MAX];
        mr_study_category_of(v->stimulus, cat, sizeof cat);
        int s = names_find(&T->stimuli, cat), p = names_find(&T->people, v->participant), b = ablock_of(v);
        T->block_present[b] = true;
        T->votes_of[p]++;
        count_into(cell_at(T, b, s), t, L, R, v->answer);
        count_into(cell_at(T, b, -1), t, L, R, v->answer);
        if (L != R) {
            pcell *pc = pcell_at(T, p, b, s);
            double a = v->answer == MR_STUDY_LEFT ? 1 : v->answer == MR_STUDY_RIGHT ? 0 : 0.5;
            pc->A[L * t + R] += a;
            pc->A[R * t + L] += 1 - a;
            int lo = L < R ? L : R, hi = L < R ? R : L;
            if (pc->seen[lo * t + hi] < 255) pc->seen[lo * t + hi]++;
        }
    }
    return true;
}

static void tally_free(tally *T) {
    free(T->methods.v);
    free(T->stimuli.v);
    free(T->people.v);
    free(T->cells);
    free(T->pcells);
    free(T->votes_of);
}

/* ------------------------------------------------------------ per cell */

typedef struct cell_stats {
    double u, iota;   /* iota: eq. 5.6 normalised per pair and clamped (mr_study_indifference) */
    double iota56;    /* eq. 5.6 as printed: (sum_{i<j} A0_ij / N) / (sum_i A0_ii / N0) */
    bool baseline;
    double neutral_distinct, n_distinct, neutral_identical, n_identical;
    int participants;
    mr_study_scores bt, dav;
    bool have_bt, have_dav;
} cell_stats;

static void cell_compute(const tally *T, const cell *c, const mr_study_analyze_params *p, cell_stats *cs) {
    int t = T->t;
    memset(cs, 0, sizeof *cs);
    double A[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS];
    mr_study_split_ties(c->w, c->ties, t, A);
    cs->u = mr_study_agreement(A, t);
    for (int i = 0; i < t; i++) {
        for (int j = i + 1; j < t; j++) {
            cs->neutral_distinct += c->ties[i * t + j];
            cs->n_distinct += c->w[i * t + j] + c->w[j * t + i] + c->ties[i * t + j];
        }
        cs->neutral_identical += c->id_neutral[i];
        cs->n_identical += c->id_n[i];
    }
    cs->iota = mr_study_indifference(cs->neutral_distinct, cs->n_distinct, cs->neutral_identical, cs->n_identical,
                                     &cs->baseline);
    int answered_pairs = 0;
    for (int i = 0; i < t; i++)
        for (int j = i + 1; j < t; j++) answered_pairs += c->w[i * t + j] + c->w[j * t + i] + c->ties[i * t + j] > 0;
    cs->iota56 = mr_study_indifference_eq56(cs->neutral_distinct, answered_pairs ? cs->n_distinct / answered_pairs : 0,
                                            cs->neutral_identical, cs->n_identical);
    if (!(cs->n_distinct > 0)) return;
    mr_study_fit_params fp = MR_STUDY_FIT_DEFAULTS;
    fp.reference = T->reference;
    fp.pseudo = p->pseudo;
    mr_error e = {0};
    cs->have_bt = mr_study_bt_fit(A, t, &fp, &cs->bt, &e);
    cs->have_dav = mr_study_davidson_fit(c->w, c->ties, t, &fp, &cs->dav, &e);
    if (!cs->have_bt || !cs->have_dav) mr_log(MR_LOG_WARN, "study: scores: %s", e.msg);
}

/* ---------------------------------------------------------------- chart */

/* Fig. 6.4 of the thesis, per block: for each pair a bar split at the
 * share of votes (ties split) for the left method, the significance lines
 * at k/n and (n-k)/n, a star on the side that wins significantly; beside
 * it the Davidson scores theta +- z se (the reference at 0). */
static bool write_chart(const char *path, const tally *T, int block, const cell *c, const cell_stats *cs,
                        const mr_study_analyze_params *p, mr_error *err) {
    int t = T->t, pairs = t * (t - 1) / 2;
    const double row_h = 26, top = 60, left = 190, bar_w = 300;
    double h1 = top + pairs * row_h + 50, h2 = top + t * row_h + 80;
    double H = h1 > h2 ? h1 : h2, W = 1000;
    mr_sbuf b = {0};
    mr_sb_printf(&b, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" font-family=\"sans-serif\">\n",
              W, H);
    mr_sb_printf(&b, "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n");
    char title[256];
    snprintf(title, sizeof title, "Block %s: pairwise preferences (ties split) and scores", ablock_name(block));
    mr_svg_text(&b, W / 2, 24, "middle", 16, "#000", title);
    mr_svg_text(&b, left + bar_w / 2, 48, "middle", 11, "#444", "share of votes; red: binomial significance lines");
    int row = 0;
    for (int i = 0; i < t; i++)
        for (int j = i + 1; j < t; j++, row++) {
            double wi = c->w[i * t + j], wj = c->w[j * t + i], ti = c->ties[i * t + j], n = wi + wj + ti;
            double y = top + row * row_h;
            char label[3 * MR_STUDY_NAME_MAX];
            snprintf(label, sizeof label, "%s vs %s", T->methods.v[i], T->methods.v[j]);
            mr_svg_text(&b, left - 8, y + 15, "end", 12, "#000", label);
            if (!(n > 0)) {
                mr_svg_text(&b, left + 4, y + 15, "start", 11, "#888", "no votes");
                continue;
            }
            double share = (wi + ti / 2) / n;
            mr_sb_printf(&b, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"18\" fill=\"#4e79a7\"/>\n", left, y + 2,
                      bar_w * share);
            mr_sb_printf(&b, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"18\" fill=\"#f28e2b\"/>\n",
                      left + bar_w * share, y + 2, bar_w * (1 - share));
            int N = (int)lround(n), k = mr_study_binom_threshold(N, p->alpha);
            if (k <= N) {
                for (int s = 0; s < 2; s++) {
                    double x = left + bar_w * (s ? (double)k / N : (double)(N - k) / N);
                    mr_sb_printf(&b, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#d00\" stroke-width=\"2\"/>\n",
                              x, y, x, y + 22);
                }
                char mark[MR_STUDY_NAME_MAX + 4] = "";
                if (wi + ti / 2 >= k || wj + ti / 2 >= k)
                    snprintf(mark, sizeof mark, "* %s", wi + ti / 2 >= k ? T->methods.v[i] : T->methods.v[j]);
                mr_svg_text(&b, left + bar_w + 6, y + 15, "start", 12, "#d00", mark);
            }
            char pct[32];
            snprintf(pct, sizeof pct, "%.0f%%", 100 * share);
            mr_svg_text(&b, left + 4, y + 15, "start", 11, "#fff", pct);
        }
    mr_svg_text(&b, left, top + pairs * row_h + 18, "start", 11, "#4e79a7", "first method preferred");
    mr_svg_text(&b, left + bar_w, top + pairs * row_h + 18, "end", 11, "#f28e2b", "second method preferred");
    mr_svg_text(&b, left + bar_w + 6, top + pairs * row_h + 18, "start", 11, "#d00", "* significant");
    /* Scores panel. */
    const mr_study_scores *s = cs->have_dav ? &cs->dav : cs->have_bt ? &cs->bt : NULL;
    double px0 = 640, pw = 320;
    mr_svg_text(&b, px0 + pw / 2, 48, "middle", 11, "#444",
             cs->have_dav && cs->dav.has_nu ? "Davidson log-strength theta +- z se (p_i)" : "Bradley-Terry log-strength theta +- z se (p_i)");
    if (s) {
        double lo = 0, hi = 0;
        for (int i = 0; i < t; i++) {
            lo = fmin(lo, s->theta[i] - p->z * s->se[i]);
            hi = fmax(hi, s->theta[i] + p->z * s->se[i]);
        }
        if (!(hi - lo > 1e-9)) lo -= 1, hi += 1;
        double pad = 0.05 * (hi - lo);
        lo -= pad, hi += pad;
#define XS(v) (px0 + pw * ((v) - lo) / (hi - lo))
        double y0 = top, y1 = top + t * row_h;
        mr_sb_printf(&b, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\" stroke-dasharray=\"4 3\"/>\n",
                  XS(0), y0, XS(0), y1);
        for (int i = 0; i < t; i++) {
            double y = top + i * row_h + 11;
            mr_svg_text(&b, px0 - 8, y + 4, "end", 12, "#000", T->methods.v[i]);
            mr_sb_printf(&b, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#333\" stroke-width=\"2\"/>\n",
                      XS(s->theta[i] - p->z * s->se[i]), y, XS(s->theta[i] + p->z * s->se[i]), y);
            mr_sb_printf(&b, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"5\" fill=\"%s\"/>\n", XS(s->theta[i]), y,
                      i == T->reference ? "#59a14f" : "#4e79a7");
            char lab[48];
            snprintf(lab, sizeof lab, "%.2f (%.0f%%)", s->theta[i], 100 * s->p[i]);
            mr_svg_text(&b, XS(s->theta[i]), y - 7, "middle", 10, "#333", lab);
        }
        char ax[64];
        snprintf(ax, sizeof ax, "%.2f", lo);
        mr_svg_text(&b, px0, y1 + 16, "start", 10, "#444", ax);
        snprintf(ax, sizeof ax, "%.2f", hi);
        mr_svg_text(&b, px0 + pw, y1 + 16, "end", 10, "#444", ax);
        if (s->pseudo) mr_svg_text(&b, px0, y1 + 34, "start", 10, "#d00", "graph not strongly connected: pseudo-count added");
#undef XS
    }
    mr_sb_printf(&b, "</svg>\n");
    bool ok = mr_sb_save(&b, path, err);
    free(b.s);
    return ok;
}

/* ---------------------------------------------------------- the writers */

static void scores_rows(mr_csv *csv, const tally *T, const char *block, const char *stim, const char *model,
                        const mr_study_scores *s, double z) {
    for (int i = 0; i < T->t; i++) {
        mr_csv_text(csv, block);
        mr_csv_text(csv, stim);
        mr_csv_text(csv, model);
        mr_csv_text(csv, T->methods.v[i]);
        mr_csv_num(csv, "%.6f", s->theta[i]);
        mr_csv_num(csv, "%.6f", s->se[i]);
        mr_csv_num(csv, "%.6f", s->theta[i] - z * s->se[i]);
        mr_csv_num(csv, "%.6f", s->theta[i] + z * s->se[i]);
        mr_csv_num(csv, "%.6f", s->p[i]);
        mr_csv_int(csv, s->pseudo);
        mr_csv_end_row(csv);
    }
    if (s->has_nu) {
        mr_csv_text(csv, block);
        mr_csv_text(csv, stim);
        mr_csv_text(csv, model);
        mr_csv_text(csv, "log_nu");
        mr_csv_num(csv, "%.6f", s->log_nu);
        mr_csv_num(csv, "%.6f", s->se_log_nu);
        mr_csv_num(csv, "%.6f", s->log_nu - z * s->se_log_nu);
        mr_csv_num(csv, "%.6f", s->log_nu + z * s->se_log_nu);
        mr_csv_num(csv, "%.6f", exp(s->log_nu));
        mr_csv_int(csv, s->pseudo);
        mr_csv_end_row(csv);
    }
}

static void pair_rows(mr_csv *csv, const tally *T, const char *block, const char *stim, const cell *c, double alpha) {
    int t = T->t;
    for (int i = 0; i < t; i++)
        for (int j = i + 1; j < t; j++) {
            double wi = c->w[i * t + j], wj = c->w[j * t + i], ti = c->ties[i * t + j];
            int n = (int)lround(wi + wj + ti);
            if (n == 0) continue;
            int k = mr_study_binom_threshold(n, alpha);
            double ai = wi + ti / 2, aj = wj + ti / 2;
            int m = (int)lround(wi + wj), x = (int)lround(wi > wj ? wi : wj);
            double p_sign = m > 0 ? fmin(1.0, 2 * mr_study_binom_upper_tail(m, x)) : 1.0;
            mr_csv_text(csv, block);
            mr_csv_text(csv, stim);
            mr_csv_text(csv, T->methods.v[i]);
            mr_csv_text(csv, T->methods.v[j]);
            mr_csv_int(csv, n);
            mr_csv_num(csv, "%g", wi);
            mr_csv_num(csv, "%g", wj);
            mr_csv_num(csv, "%g", ti);
            mr_csv_num(csv, "%g", ai);
            mr_csv_num(csv, "%g", aj);
            mr_csv_int(csv, k);
            mr_csv_int(csv, n - k);
            mr_csv_text(csv, ai >= k ? T->methods.v[i] : aj >= k ? T->methods.v[j] : "");
            mr_csv_num(csv, "%.6g", p_sign);
            mr_csv_end_row(csv);
        }
}

static bool save_csv(mr_csv **csv, const char *dir, const char *name, mr_error *err) {
    char path[8192];
    mr_path_join(dir, name, path, sizeof path);
    bool ok = mr_csv_save(*csv, path, err);
    mr_csv_destroy(csv);
    return ok;
}

/* What one pass tells the other: the pooled scores and who is below the
 * consistence threshold. */
#define MAX_FLAGGED 256
typedef struct pass_info {
    int t, P, nflag;
    name_t methods[MR_STUDY_MAX_METHODS];
    name_t flagged[MAX_FLAGGED];
    bool have[NB + 1];
    double theta[NB + 1][MR_STUDY_MAX_METHODS];
} pass_info;

static bool analyze_one(const mr_study_votes *votes, const mr_study_plan *plan, const mr_study_analyze_params *pp,
                        const char *out_dir, const pass_info *other, pass_info *mine, mr_error *err) {
    mr_study_analyze_params p = pp ? *pp : (mr_study_analyze_params)MR_STUDY_ANALYZE_DEFAULTS;
    bool *use = calloc((size_t)(votes->count > 0 ? votes->count : 1), sizeof *use);
    if (!use) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    tally T;
    bool ok = tally_build(&T, votes, plan, use, err);
    free(use);
    if (ok) ok = mr_mkdirs(out_dir, err);
    int t = T.t;
    cell_stats *cs = ok ? calloc((size_t)NB * (T.S + 1), sizeof *cs) : NULL;
    if (ok && !cs) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int b = 1; ok && b <= NB; b++)
        for (int s = -1; T.block_present[b] && s < T.S; s++)
            cell_compute(&T, cell_at(&T, b, s), &p, &cs[(size_t)(b - 1) * (T.S + 1) + (s < 0 ? T.S : s)]);
#define CS(b, s) (&cs[(size_t)((b) - 1) * (T.S + 1) + ((s) < 0 ? T.S : (s))])

    /* pairs.csv and scores.csv */
    mr_csv *pairs = ok ? mr_csv_create(err) : NULL, *scores = ok ? mr_csv_create(err) : NULL;
    char note[512];
    snprintf(note, sizeof note,
             "A_ij = wins + ties/2; i is significantly preferred when A_ij >= k_upper (exact binomial, p = 1/2, "
             "alpha %g per tail, n = all votes of the pair); p_sign: two-sided sign test on the votes that are not ties",
             p.alpha);
    mr_csv_comment(pairs, note);
    mr_csv_header(pairs, "block,category,method_i,method_j,n,i_preferred,j_preferred,no_preference,A_ij,A_ji,k_upper,k_lower,significant,p_sign");
    mr_csv_comment(scores, "theta = log strength; the reference at 0 when present, else centred; se from the inverse Hessian; p = e^theta / sum e^theta");
    mr_csv_header(scores, "block,category,model,method,theta,se,ci_low,ci_high,p,pseudo_count");
    for (int b = 1; ok && b <= NB; b++)
        for (int s = -1; T.block_present[b] && s < T.S; s++) {
            const char *bn = ablock_name(b), *sn = s < 0 ? "all" : T.stimuli.v[s];
            pair_rows(pairs, &T, bn, sn, cell_at(&T, b, s), p.alpha);
            if (CS(b, s)->have_bt) scores_rows(scores, &T, bn, sn, "bradley-terry", &CS(b, s)->bt, p.z);
            if (CS(b, s)->have_dav) scores_rows(scores, &T, bn, sn, "davidson", &CS(b, s)->dav, p.z);
        }
    if (ok) ok = save_csv(&pairs, out_dir, "pairs.csv", err);
    if (ok) ok = save_csv(&scores, out_dir, "scores.csv", err);

    /* consistence.csv and participants.csv */
    mr_csv *cons = ok ? mr_csv_create(err) : NULL, *parts = ok ? mr_csv_create(err) : NULL;
    mr_csv_comment(cons, "per participant x block x stimulus with every pair answered once: c = t(t^2-1)/24 - sum(a_i - mean)^2/2 "
                         "(ties split), xi = 1 - 24c/(t(t^2-1)) as the thesis (eq. 5.2), xi_kendall = 1 - c/c_max with "
                         "Kendall's c_max ((t^3-4t)/24 for even t), clamped to [0,1]");
    mr_csv_header(cons, "participant,block,category,c,xi,xi_kendall");
    mr_csv_header(parts, "participant,votes,matrices,mean_xi,mean_xi_kendall,flagged,identical_trials,identical_seen_different");
    double *pxi = calloc((size_t)T.P + 1, sizeof *pxi);
    int flagged = 0;
    for (int pi = 0; ok && pi < T.P; pi++) {
        double sx = 0, sk = 0;
        int nm = 0;
        for (int b = 1; b <= NB; b++)
            for (int s = 0; T.block_present[b] && s < T.S; s++) {
                pcell *pc = pcell_at(&T, pi, b, s);
                bool complete = true;
                for (int i = 0; i < t && complete; i++)
                    for (int j = i + 1; j < t; j++)
                        if (pc->seen[i * t + j] != 1) complete = false;
                if (!complete) continue;
                mr_study_consistence c = mr_study_consistence_of(pc->A, t);
                mr_csv_text(cons, T.people.v[pi]);
                mr_csv_text(cons, ablock_name(b));
                mr_csv_text(cons, T.stimuli.v[s]);
                mr_csv_num(cons, "%.6f", c.c);
                mr_csv_num(cons, "%.6f", c.xi);
                mr_csv_num(cons, "%.6f", c.xi_kendall);
                mr_csv_end_row(cons);
                sx += c.xi, sk += c.xi_kendall, nm++;
            }
        /* Identical pairs: how often this participant saw a difference. */
        int id_n = 0, id_diff = 0;
        for (int i = 0; i < votes->count; i++) {
            const mr_study_vote *v = &votes->v[i];
            if (strcmp(v->participant, T.people.v[pi]) != 0 || strcmp(v->left, v->right) != 0) continue;
            if (plan && strcmp(v->plan, plan->id) != 0) continue;
            id_n++;
            id_diff += v->answer != MR_STUDY_NEUTRAL;
        }
        bool flag = nm > 0 && sx / nm < p.min_consistence;
        flagged += flag;
        if (pxi) pxi[pi] = nm ? sx / nm : NAN;
        mr_csv_text(parts, T.people.v[pi]);
        mr_csv_int(parts, T.votes_of[pi]);
        mr_csv_int(parts, nm);
        mr_csv_num(parts, "%.6f", nm ? sx / nm : NAN);
        mr_csv_num(parts, "%.6f", nm ? sk / nm : NAN);
        mr_csv_int(parts, flag);
        mr_csv_int(parts, id_n);
        mr_csv_int(parts, id_diff);
        mr_csv_end_row(parts);

    }
    if (ok) ok = save_csv(&cons, out_dir, "consistence.csv", err);
    if (ok) ok = save_csv(&parts, out_dir, "participants.csv", err);

    /* agreement.csv and identical.csv */
    mr_csv *agr = ok ? mr_csv_create(err) : NULL, *ident = ok ? mr_csv_create(err) : NULL;
    mr_csv_comment(agr, "u: Kendall's coefficient of agreement (eq. 5.4, ties split); indifference_eq5_6: eq. 5.6 as printed, "
                        "(sum_{i<j} A0_ij / N) / (sum_i A0_ii / N0), N the answers per pair, not clamped (up to C(t,2)); "
                        "indifference_per_pair: the share of no-preference answers on different pairs over the share on "
                        "identical pairs (eq. 5.6 / C(t,2)), clamped to 1; category 'all' = mean over the categories");
    mr_csv_header(agr, "block,category,u,indifference_eq5_6,indifference_per_pair,baseline,no_pref_distinct,n_distinct,no_pref_identical,n_identical");
    mr_csv_comment(ident, "identical pairs (left out of the fits): how often people saw a difference that was not there");
    mr_csv_header(ident, "block,category,method,n,left,right,no_preference,seen_different");
    for (int b = 1; ok && b <= NB; b++) {
        if (!T.block_present[b]) continue;
        double su = 0, si = 0, s56 = 0;
        int nu = 0, ni = 0, n56 = 0;
        for (int s = 0; s <= T.S; s++) {
            bool all = s == T.S;
            const cell_stats *x = CS(b, all ? -1 : s);
            mr_csv_text(agr, ablock_name(b));
            mr_csv_text(agr, all ? "all" : T.stimuli.v[s]);
            mr_csv_num(agr, "%.6f", all ? (nu ? su / nu : NAN) : x->u);
            mr_csv_num(agr, "%.6f", all ? (n56 ? s56 / n56 : NAN) : x->iota56);
            mr_csv_num(agr, "%.6f", all ? (ni ? si / ni : NAN) : x->iota);
            mr_csv_int(agr, x->baseline);
            mr_csv_num(agr, "%g", x->neutral_distinct);
            mr_csv_num(agr, "%g", x->n_distinct);
            mr_csv_num(agr, "%g", x->neutral_identical);
            mr_csv_num(agr, "%g", x->n_identical);
            mr_csv_end_row(agr);
            if (!all && isfinite(x->u)) su += x->u, nu++;
            if (!all && x->n_distinct > 0) si += x->iota, ni++;
            if (!all && isfinite(x->iota56)) s56 += x->iota56, n56++;
            const cell *c = cell_at(&T, b, all ? -1 : s);
            for (int m = 0; m < t; m++) {
                if (!(c->id_n[m] > 0)) continue;
                mr_csv_text(ident, ablock_name(b));
                mr_csv_text(ident, all ? "all" : T.stimuli.v[s]);
                mr_csv_text(ident, T.methods.v[m]);
                mr_csv_num(ident, "%g", c->id_n[m]);
                mr_csv_num(ident, "%g", c->id_left[m]);
                mr_csv_num(ident, "%g", c->id_right[m]);
                mr_csv_num(ident, "%g", c->id_neutral[m]);
                mr_csv_num(ident, "%.6f", (c->id_left[m] + c->id_right[m]) / c->id_n[m]);
                mr_csv_end_row(ident);
            }
        }
        /* The pooled row's u and iota: the means (kept for the summary). */
        CS(b, -1)->u = nu ? su / nu : NAN;
        CS(b, -1)->iota = ni ? si / ni : NAN;
        CS(b, -1)->iota56 = n56 ? s56 / n56 : NAN;
    }
    if (ok) ok = save_csv(&agr, out_dir, "agreement.csv", err);
    if (ok) ok = save_csv(&ident, out_dir, "identical.csv", err);

    /* Charts and the summary. */
    mr_sbuf md = {0};
    mr_sb_printf(&md, "# Pairwise comparison study\n\n");
    mr_sb_printf(&md, "%d votes of %d participants; %d methods; %d categories%s%s.\n\n", votes->count, T.P, t, T.S,
              plan ? "; plan " : "", plan ? plan->id : "");
    mr_sb_printf(&md, "Method (Hecher, ch. 5): ties split half to each side; consistence xi = 1 - 24c/(t(t^2-1)) "
                   "(the thesis's normalisation; `consistence.csv` also gives Kendall's, with c_max = (t^3-4t)/24 for even t); "
                   "agreement u (Kendall/Babington-Smith); indifference iota by eq. 5.6 as printed (not divided by "
                   "C(t,2), not clamped), beside it the per-pair share ratio (eq. 5.6 / C(t,2), clamped to 1); "
                   "a category's two scenes are pooled (its matrices, as the thesis's); exact binomial test at alpha = %g per tail with the "
                   "thresholds from n = all votes of a pair (ties split before comparing); scores by Davidson's model "
                   "with ties (Newton) and Bradley-Terry on split counts (Hunter's MM), %s; identical pairs are "
                   "left out of the fits.\n\n",
              p.alpha, T.reference >= 0 ? "the reference fixed at theta = 0" : "centred (mean theta = 0, no reference)");
    for (int b = 1; ok && b <= NB; b++) {
        if (!T.block_present[b]) continue;
        const cell_stats *x = CS(b, -1);
        char name[64], path[8192];
        snprintf(name, sizeof name, "chart_%s.svg", ablock_name(b));
        mr_path_join(out_dir, name, path, sizeof path);
        ok = write_chart(path, &T, b, cell_at(&T, b, -1), x, &p, err);
        mr_sb_printf(&md, "## Block %s\n\n![block %s](%s)\n\n", ablock_name(b), ablock_name(b), name);
        const mr_study_scores *s = x->have_dav ? &x->dav : x->have_bt ? &x->bt : NULL;
        if (s) {
            mr_sb_printf(&md, "| method | theta | se | %.0f%% CI | p |\n|---|---|---|---|---|\n",
                      100 * (1 - 2 * (1 - 0.5 * (1 + erf(p.z / sqrt(2.0))))));
            for (int i = 0; i < t; i++)
                mr_sb_printf(&md, "| %s | %.3f | %.3f | [%.3f, %.3f] | %.3f |\n", T.methods.v[i], s->theta[i], s->se[i],
                          s->theta[i] - p.z * s->se[i], s->theta[i] + p.z * s->se[i], s->p[i]);
            if (s->has_nu) mr_sb_printf(&md, "\nDavidson's tie parameter: log nu = %.3f (se %.3f).\n", s->log_nu, s->se_log_nu);
            if (s->pseudo) {
                mr_sb_printf(&md, "\n**The comparison graph is not strongly connected** (%s is never beaten or tied by the "
                               "others): %g pseudo-wins were added each way to every pair.\n",
                          s->isolated >= 0 ? T.methods.v[s->isolated] : "a method", p.pseudo);
                mr_log(MR_LOG_WARN, "study: block %s: the comparison graph is not strongly connected (%s is never beaten "
                       "or tied); added %g pseudo-wins each way to every pair",
                       ablock_name(b), s->isolated >= 0 ? T.methods.v[s->isolated] : "a method", p.pseudo);
            }
        }
        mr_sb_printf(&md, "\nSignificant pairs (pooled over stimuli):");
        const cell *c = cell_at(&T, b, -1);
        int nsig = 0;
        for (int i = 0; i < t; i++)
            for (int j = i + 1; j < t; j++) {
                double ti = c->ties[i * t + j], ai = c->w[i * t + j] + ti / 2, aj = c->w[j * t + i] + ti / 2;
                int n = (int)lround(ai + aj), k = mr_study_binom_threshold(n, p.alpha);
                if (n > 0 && (ai >= k || aj >= k)) {
                    mr_sb_printf(&md, "%s %s > %s (%g of %d, k = %d)", nsig++ ? ";" : "", ai >= k ? T.methods.v[i] : T.methods.v[j],
                              ai >= k ? T.methods.v[j] : T.methods.v[i], ai >= k ? ai : aj, n, k);
                }
            }
        mr_sb_printf(&md, "%s\n\nAgreement u = %.3f (mean over categories); indifference (eq. 5.6 as printed) = %.3f, "
                       "per pair (eq. 5.6 / C(t,2), clamped) = %.3f%s.\n\n",
                  nsig ? "." : " none.", x->u, x->iota56, x->iota,
                  x->baseline ? "" : " (no identical-pair baseline: eq. 5.6 undefined, the per-pair value is the raw share)");
        /* Per-category Davidson scores (the thesis's Fig. 6.7 per category). */
        if (T.S > 1) {
            mr_sb_printf(&md, "Davidson theta per category:\n\n| category |");
            for (int i = 0; i < t; i++) mr_sb_printf(&md, " %s |", T.methods.v[i]);
            mr_sb_printf(&md, "\n|---|");
            for (int i = 0; i < t; i++) mr_sb_printf(&md, "---|");
            mr_sb_printf(&md, "\n");
            for (int sc = 0; sc < T.S; sc++) {
                const cell_stats *y = CS(b, sc);
                const mr_study_scores *z = y->have_dav ? &y->dav : y->have_bt ? &y->bt : NULL;
                mr_sb_printf(&md, "| %s |", T.stimuli.v[sc]);
                for (int i = 0; i < t; i++) {
                    if (z) mr_sb_printf(&md, " %.2f |", z->theta[i]);
                    else mr_sb_printf(&md, " - |");
                }
                mr_sb_printf(&md, "\n");
            }
            mr_sb_printf(&md, "\n");
        }
        if (mine) {
            mine->have[b] = s != NULL;
            for (int i = 0; s && i < t; i++) mine->theta[b][i] = s->theta[i];
        }
    }
    if (ok && mine) {
        mine->t = t;
        mine->P = T.P;
        for (int i = 0; i < t; i++) snprintf(mine->methods[i], MR_STUDY_NAME_MAX, "%s", T.methods.v[i]);
        mine->nflag = 0;
        for (int pi = 0; pi < T.P && mine->nflag < MAX_FLAGGED; pi++)
            if (pxi && isfinite(pxi[pi]) && pxi[pi] < p.min_consistence)
                snprintf(mine->flagged[mine->nflag++], MR_STUDY_NAME_MAX, "%s", T.people.v[pi]);
    }
    if (ok && other) {
        mr_sb_printf(&md, "## With and without the excluded participants\n\n");
        if (!other->nflag) {
            mr_sb_printf(&md, "No participant's mean consistence is below %.3f: none excluded.\n\n", p.min_consistence);
        } else {
            mr_sb_printf(&md, "Excluded (mean consistence below %.3f):", p.min_consistence);
            for (int k = 0; k < other->nflag; k++) mr_sb_printf(&md, "%s %s", k ? "," : "", other->flagged[k]);
            mr_sb_printf(&md, ". The tables above leave them out; `all_participants/` has every file with them. Pooled "
                           "Davidson theta, without / with them:\n\n| block | method | without | with |\n|---|---|---|---|\n");
            for (int b = 1; b <= NB; b++)
                for (int i = 0; i < t && T.block_present[b]; i++) {
                    int j = -1;
                    for (int k = 0; k < other->t; k++)
                        if (!strcmp(other->methods[k], T.methods.v[i])) j = k;
                    const cell_stats *x = CS(b, -1);
                    const mr_study_scores *z = x->have_dav ? &x->dav : x->have_bt ? &x->bt : NULL;
                    mr_sb_printf(&md, "| %s | %s | %.3f | %.3f |\n", ablock_name(b), T.methods.v[i], z ? z->theta[i] : NAN,
                              j >= 0 && other->have[b] ? other->theta[b][j] : NAN);
                }
            mr_sb_printf(&md, "\n");
        }
    }
    if (ok) {
        mr_sb_printf(&md, "## Participants\n\n");
        int nflag = 0;
        for (int pi = 0; pi < T.P; pi++)
            if (pxi && isfinite(pxi[pi]) && pxi[pi] < p.min_consistence) {
                mr_sb_printf(&md, "%s%s (mean xi %.3f)", nflag++ ? ", " : "Flagged (mean consistence below the threshold): ",
                          T.people.v[pi], pxi[pi]);
            }
        mr_sb_printf(&md, "%s\n\n", nflag ? "." : "No participant is below the consistence threshold.");
        double id_n = 0, id_d = 0;
        for (int b = 1; b <= NB; b++)
            for (int m = 0; T.block_present[b] && m < t; m++) {
                id_n += cell_at(&T, b, -1)->id_n[m];
                id_d += cell_at(&T, b, -1)->id_left[m] + cell_at(&T, b, -1)->id_right[m];
            }
        mr_sb_printf(&md, "Identical pairs: %g answers, %g of them saw a difference that was not there (%.0f%%).\n", id_n,
                  id_d, id_n > 0 ? 100 * id_d / id_n : 0.0);
        if (votes->bad_lines || votes->duplicates)
            mr_sb_printf(&md, "\nInput: %d lines skipped (not a vote, or torn), %d repeated answers dropped (first kept).\n",
                      votes->bad_lines, votes->duplicates);
        mr_sb_printf(&md, "\nFiles: pairs.csv, scores.csv, consistence.csv, participants.csv, agreement.csv, identical.csv.\n");
        char path[8192];
        mr_path_join(out_dir, "summary.md", path, sizeof path);
        ok = mr_sb_save(&md, path, err);
    }
    (void)flagged;
#undef CS
    free(md.s);
    free(pxi);
    free(cs);
    mr_csv_destroy(&pairs);
    mr_csv_destroy(&scores);
    mr_csv_destroy(&cons);
    mr_csv_destroy(&parts);
    mr_csv_destroy(&agr);
    mr_csv_destroy(&ident);
    tally_free(&T);
    return ok;
}

bool mr_study_analyze(const mr_study_votes *votes, const mr_study_plan *plan, const mr_study_analyze_params *pp,
                      const char *out_dir, mr_error *err) {
    /* Everyone first (into all_participants/), then without those below
     * the threshold (the thesis removed participant 43 so), the summary
     * comparing both. */
    char all_dir[8192];
    mr_path_join(out_dir, "all_participants", all_dir, sizeof all_dir);
    pass_info *a = calloc(2, sizeof *a);
    if (!a) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    bool ok = analyze_one(votes, plan, pp, all_dir, NULL, &a[0], err);
    mr_study_votes kept = {0};
    if (ok) {
        kept = *votes;
        kept.v = malloc((size_t)(votes->count > 0 ? votes->count : 1) * sizeof *kept.v);
        kept.count = 0;
        if (!kept.v) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
        for (int i = 0; ok && i < votes->count; i++) {
            bool out = false;
            for (int k = 0; k < a[0].nflag && !out; k++) out = !strcmp(votes->v[i].participant, a[0].flagged[k]);
            if (!out) kept.v[kept.count++] = votes->v[i];
        }
        kept.cap = kept.count;
        for (int k = 0; ok && k < a[0].nflag; k++)
            mr_log(MR_LOG_WARN, "study: participant %s is below the consistence threshold: excluded (all_participants/ "
                   "keeps them)", a[0].flagged[k]);
        if (ok && kept.count == 0) ok = mr_fail(err, MR_ERR_INVALID, "every participant is below the consistence threshold");
    }
    if (ok) ok = analyze_one(&kept, plan, pp, out_dir, &a[0], &a[1], err);
    free(kept.v);
    free(a);
    return ok;
}

bool mr_study_analyze_files(const char *const *votes_paths, int n, const char *plan_path,
                            const mr_study_analyze_params *p, const char *out_dir, int *vote_count, mr_error *err) {
    mr_study_plan plan;
    const bool have_plan = plan_path != NULL;
    if (have_plan && !mr_study_plan_load(plan_path, &plan, err)) return false;
    mr_study_votes votes = {0};
    bool ok = true;
    for (int i = 0; ok && i < n; i++) ok = mr_study_votes_read(votes_paths[i], false, &votes, err);
    for (int i = 0; ok && !have_plan && i < votes.count; i++)
        if (votes.v[i].design != MR_STUDY_PAIRWISE)
            ok = mr_fail(err, MR_ERR_INVALID, "%s answers need their plan: give --plan plan.json",
                         mr_study_design_names[votes.v[i].design]);
    if (ok && have_plan && plan.design != MR_STUDY_PAIRWISE)
        ok = plan.design == MR_STUDY_RATING ? mr_study_analyze_rating(&votes, &plan, p, out_dir, err)
                                            : mr_study_analyze_task(&votes, &plan, p, out_dir, err);
    else ok = ok && mr_study_analyze(&votes, have_plan ? &plan : NULL, p, out_dir, err);
    *vote_count = votes.count;
    mr_study_votes_free(&votes);
    if (have_plan) mr_study_plan_free(&plan);
    return ok;
}
