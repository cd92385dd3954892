/* `mrcheck study analyze` of the rating design (Scheer & Keutel: ratings
 * 1..7 per depth cue, repeated-measures ANOVA with Bonferroni post hoc,
 * paired t between the virtual and the video condition; their Tables 3
 * and 4) and of the task design (Kalkofen et al.: answers scored right or
 * wrong, tap errors; RM-ANOVA where its assumptions hold, else Friedman
 * with Wilcoxon signed-rank post hoc). The numbers come from infer.c;
 * this file only gathers, decides and writes. */
#include "mr_eval.h"
#include "mr_study.h"
#include "study_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef char name_t[MR_STUDY_NAME_MAX];

/* The participants of the votes that belong to the plan, in first-seen
 * order; use[i] says which votes count. */
typedef struct people {
    name_t *v;
    int n;
} people;

static bool gather(const mr_study_votes *votes, const mr_study_plan *plan, people *P, bool *use, int *stim,
                   int *meth, mr_error *err) {
    P->v = calloc((size_t)(votes->count > 0 ? votes->count : 1), sizeof *P->v);
    P->n = 0;
    if (!P->v) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int other = 0;
    for (int i = 0; i < votes->count; i++) {
        const mr_study_vote *v = &votes->v[i];
        use[i] = false;
        stim[i] = meth[i] = -1;
        if (plan->overall && v->design == MR_STUDY_RATING && !strcmp(v->left, "*")) continue; /* the overall question */
        if (strcmp(v->plan, plan->id) != 0 || v->design != plan->design || v->block < 1 || v->block > 2 ||
            !(plan->blocks & (1u << (v->block - 1)))) {
            other++;
            continue;
        }
        for (int s = 0; s < plan->set.stimulus_count; s++)
            if (!strcmp(plan->set.stimuli[s], v->stimulus)) stim[i] = s;
        for (int m = 0; m < plan->set.method_count; m++)
            if (!strcmp(plan->set.methods[m], v->left)) meth[i] = m;
        if (stim[i] < 0 || meth[i] < 0 || (plan->design == MR_STUDY_RATING && v->rating_count != plan->scale_count)) {
            other++;
            continue;
        }
        int p = -1;
        for (int k = 0; k < P->n && p < 0; k++)
            if (!strcmp(P->v[k], v->participant)) p = k;
        if (p < 0) snprintf(P->v[p = P->n++], MR_STUDY_NAME_MAX, "%s", v->participant);
        use[i] = true;
    }
    if (other) mr_log(MR_LOG_WARN, "study: %d answers are not of plan %s (or name what it lacks): left out", other, plan->id);
    if (!P->n) return mr_fail(err, MR_ERR_INVALID, "no answers of plan %s to analyse", plan->id);
    return true;
}

static int person(const people *P, const char *name) {
    for (int k = 0; k < P->n; k++)
        if (!strcmp(P->v[k], name)) return k;
    return -1;
}

/* "p < .001", "p < .01", "p < .05", "p < .1" or "NO", as the paper's tables. */
static const char *stars(double p) {
    return !(p < 0.1) ? "NO" : p < 0.001 ? "p < .001" : p < 0.01 ? "p < .01" : p < 0.05 ? "p < .05" : "p < .1";
}

static bool save_csv(mr_csv **csv, const char *dir, const char *name, mr_error *err) {
    char path[8192];
    mr_path_join(dir, name, path, sizeof path);
    bool ok = *csv && mr_csv_save(*csv, path, err);
    mr_csv_destroy(csv);
    return ok;
}

/* Grouped bars with +-sd whiskers: G groups (x) of M bars (one per
 * method), values in [0, ymax]. Not-finite means are left out. */
static bool chart_bars(const char *path, const char *title, const char *ylabel, const name_t *groups, int G,
                       const name_t *series, int M, const double *mean, const double *sd, double ymax, mr_error *err) {
    static const char *const colors[] = {"#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#76b7b2", "#edc948"};
    const double left = 60, top = 50, plot_h = 300, group_w = fmax(60.0, 22.0 * M + 20), legend = 160;
    double W = left + G * group_w + legend + 20, H = top + plot_h + 110;
    mr_sbuf b = {0};
    mr_sb_printf(&b, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" font-family=\"sans-serif\">\n", W, H);
    mr_sb_printf(&b, "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n");
    mr_svg_text(&b, W / 2, 24, "middle", 15, "#000", title);
    double y0 = top + plot_h;
#define YS(v) (y0 - plot_h * fmin(1.0, fmax(0.0, (v) / ymax)))
    for (int k = 0; k <= 7; k++) {
        double v = ymax * k / 7.0;
        mr_sb_printf(&b, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", left, YS(v),
                     left + G * group_w, YS(v));
        char lab[32];
        snprintf(lab, sizeof lab, "%.3g", v);
        mr_svg_text(&b, left - 6, YS(v) + 4, "end", 10, "#444", lab);
    }
    mr_svg_text(&b, 14, top + plot_h / 2, "middle", 11, "#444", ylabel);
    for (int g = 0; g < G; g++) {
        double gx = left + g * group_w + 10;
        for (int m = 0; m < M; m++) {
            double v = mean[g * M + m], e = sd ? sd[g * M + m] : NAN;
            if (!isfinite(v)) continue;
            double x = gx + m * 22;
            mr_sb_printf(&b, "<rect x=\"%.1f\" y=\"%.1f\" width=\"18\" height=\"%.1f\" fill=\"%s\"/>\n", x, YS(v),
                         y0 - YS(v), colors[m % 6]);
            if (isfinite(e))
                mr_sb_printf(&b, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000\"/>\n", x + 9,
                             YS(v - e), x + 9, YS(v + e));
        }
        char lab[MR_STUDY_NAME_MAX];
        snprintf(lab, sizeof lab, "%s", groups[g]);
        for (char *c = lab; *c; c++)
            if (*c == '_') *c = ' ';
        mr_sb_printf(&b, "<g transform=\"translate(%.1f,%.1f) rotate(30)\">", gx + 4, y0 + 14);
        mr_svg_text(&b, 0, 0, "start", 10, "#000", lab);
        mr_sb_printf(&b, "</g>\n");
    }
#undef YS
    double lx = left + G * group_w + 20;
    for (int m = 0; m < M; m++) {
        mr_sb_printf(&b, "<rect x=\"%.1f\" y=\"%.1f\" width=\"12\" height=\"12\" fill=\"%s\"/>\n", lx, top + m * 18,
                     colors[m % 6]);
        mr_svg_text(&b, lx + 18, top + m * 18 + 10, "start", 11, "#000", series[m]);
    }
    mr_svg_text(&b, lx, top + M * 18 + 14, "start", 10, "#444", "whiskers: +-1 SD");
    mr_sb_printf(&b, "</svg>\n");
    bool ok = mr_sb_save(&b, path, err);
    free(b.s);
    return ok;
}

/* Rows of an n x k matrix (participants x methods) with every value
 * finite; returns how many. */
static int complete_rows(const double *y, int n, int k, double *out) {
    int r = 0;
    for (int i = 0; i < n; i++) {
        bool all = true;
        for (int j = 0; j < k; j++) all = all && isfinite(y[i * k + j]);
        if (!all) continue;
        memcpy(&out[r * k], &y[i * k], (size_t)k * sizeof *out);
        r++;
    }
    return r;
}

/* ------------------------------------------------------------ omnibus */

/* The omnibus test of one (condition, measure): RM-ANOVA or Friedman, and
 * the post hoc pairs. */
typedef struct omni {
    bool anova;                  /* else Friedman */
    int n;                       /* complete participants */
    mr_study_rm_anova_result a;
    mr_study_friedman_result f;
    double normal_p;             /* D'Agostino on the residuals (NaN: not computed) */
    bool gg;                     /* Greenhouse-Geisser's p reported (sphericity rejected) */
    double p;                    /* the p reported */
    int pairs;
    int pi[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS / 2], pj[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS / 2];
    double stat[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS / 2];   /* t or z */
    double praw[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS / 2], padj[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS / 2];
    double di[MR_STUDY_MAX_METHODS * MR_STUDY_MAX_METHODS / 2];     /* mean of i - j */
} omni;

/* y: n x k complete rows. use_anova: -1 decide by the residuals, 0
 * Friedman, 1 ANOVA. false when fewer than two rows. */
static bool omnibus(const double *y, int n, int k, int use_anova, const mr_study_analyze_params *p, omni *o) {
    memset(o, 0, sizeof *o);
    o->n = n;
    o->normal_p = NAN;
    o->p = NAN;
    if (n < 2 || k < 2) return false;
    if (use_anova < 0) {
        /* Residuals of the additive model participant + method. */
        double *res = malloc((size_t)n * k * sizeof *res), grand = 0, cm[MR_STUDY_MAX_METHODS] = {0};
        if (!res) return false;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < k; j++) grand += y[i * k + j] / (n * k), cm[j] += y[i * k + j] / n;
        for (int i = 0; i < n; i++) {
            double rm = 0;
            for (int j = 0; j < k; j++) rm += y[i * k + j] / k;
            for (int j = 0; j < k; j++) res[i * k + j] = y[i * k + j] - rm - cm[j] + grand;
        }
        mr_study_normality_result nr;
        bool have = mr_study_normality(res, n * k, &nr);
        free(res);
        o->normal_p = have ? nr.p : NAN;
        use_anova = have && nr.p >= p->level;
    }
    o->anova = use_anova;
    mr_error e = {0};
    if (o->anova) {
        if (!mr_study_rm_anova(y, n, k, &o->a, &e)) return false;
        o->gg = k > 2 && isfinite(o->a.mauchly_p) && o->a.mauchly_p < p->level;
        o->p = o->gg ? o->a.p_gg : o->a.p;
    } else {
        if (!mr_study_friedman(y, n, k, &o->f, &e)) return false;
        o->p = o->f.p;
    }
    double *a = malloc((size_t)n * 2 * sizeof *a);
    if (!a) return false;
    for (int i = 0; i < k; i++)
        for (int j = i + 1; j < k; j++) {
            int q = o->pairs++;
            o->pi[q] = i, o->pj[q] = j;
            double mean = 0;
            for (int r = 0; r < n; r++) a[r] = y[r * k + i], a[n + r] = y[r * k + j], mean += (a[r] - a[n + r]) / n;
            o->di[q] = mean;
            if (o->anova) {
                mr_study_ttest t;
                mr_study_paired_t(a, a + n, n, &t);
                o->stat[q] = t.t, o->praw[q] = t.p;
            } else {
                mr_study_wilcoxon_result w;
                mr_study_wilcoxon(a, a + n, n, &w);
                o->stat[q] = w.z, o->praw[q] = w.p;
            }
        }
    free(a);
    mr_study_p_adjust(o->praw, o->pairs, (mr_study_adjust)p->adjust, o->padj);
    return true;
}

/* "F(2;46) = 87.48" (GG-corrected df when sphericity was rejected) or
 * "chi2(2) = 7.00". */
static void omni_text(const omni *o, char *out, size_t n) {
    if (o->anova) {
        double e = o->gg ? o->a.eps_gg : 1.0;
        if (o->gg) snprintf(out, n, "F(%.2f;%.2f) = %.2f", o->a.df1 * e, o->a.df2 * e, o->a.F);
        else snprintf(out, n, "F(%.0f;%.0f) = %.2f", o->a.df1, o->a.df2, o->a.F);
    } else {
        snprintf(out, n, "chi2(%.0f) = %.2f", o->f.df, o->f.chi2);
    }
}

static void omni_rows(mr_csv *tests, mr_csv *post, const char *cond, const char *measure, const omni *o,
                      const mr_study_plan *plan, mr_study_adjust adjust) {
    mr_csv_text(tests, cond);
    mr_csv_text(tests, measure);
    mr_csv_text(tests, o->anova ? "rm-anova" : "friedman");
    mr_csv_int(tests, o->n);
    mr_csv_num(tests, "%.6g", o->normal_p);
    if (o->anova) {
        mr_csv_num(tests, "%.6g", o->a.df1);
        mr_csv_num(tests, "%.6g", o->a.df2);
        mr_csv_num(tests, "%.6f", o->a.F);
        mr_csv_num(tests, "%.6g", o->a.p);
        mr_csv_num(tests, "%.6f", o->a.mauchly_w);
        mr_csv_num(tests, "%.6g", o->a.mauchly_p);
        mr_csv_num(tests, "%.6f", o->a.eps_gg);
        mr_csv_num(tests, "%.6f", o->a.eps_hf);
        mr_csv_num(tests, "%.6g", o->a.p_gg);
        mr_csv_num(tests, "%.6f", o->a.eta_p2);
    } else {
        mr_csv_num(tests, "%.6g", o->f.df);
        mr_csv_text(tests, "");
        mr_csv_num(tests, "%.6f", o->f.chi2);
        mr_csv_num(tests, "%.6g", o->f.p);
        for (int k = 0; k < 5; k++) mr_csv_text(tests, "");
        mr_csv_num(tests, "%.6f", o->f.kendall_w);
    }
    mr_csv_num(tests, "%.6g", o->p);
    mr_csv_int(tests, o->gg);
    mr_csv_end_row(tests);
    for (int q = 0; q < o->pairs; q++) {
        mr_csv_text(post, cond);
        mr_csv_text(post, measure);
        mr_csv_text(post, plan->set.methods[o->pi[q]]);
        mr_csv_text(post, plan->set.methods[o->pj[q]]);
        mr_csv_text(post, o->anova ? "paired-t" : "wilcoxon");
        mr_csv_num(post, "%.6f", o->di[q]);
        mr_csv_num(post, "%.6f", o->stat[q]);
        mr_csv_num(post, "%.6g", o->praw[q]);
        mr_csv_text(post, mr_study_adjust_name(adjust));
        mr_csv_num(post, "%.6g", o->padj[q]);
        mr_csv_end_row(post);
    }
}

#define OMNI_TESTS_HEADER \
    "condition,measure,test,n,normality_p,df1,df2,statistic,p_uncorrected,mauchly_w,mauchly_p,eps_gg,eps_hf,p_gg," \
    "eta_p2_or_kendall_w,p_reported,gg_reported"
#define OMNI_POST_HEADER "condition,measure,method_i,method_j,test,mean_i_minus_j,t_or_z,p,adjust,p_adjusted"

/* The paper's "D1<D2, p < .001" for a post hoc pair. */
static void pair_text(const omni *o, int q, const mr_study_plan *plan, char *out, size_t n) {
    snprintf(out, n, "%s%s%s, %s", plan->set.methods[o->pi[q]], o->di[q] < 0 ? "<" : ">", plan->set.methods[o->pj[q]],
             stars(o->padj[q]));
}

/* ------------------------------------------------------------- rating */

bool mr_study_analyze_rating(const mr_study_votes *votes, const mr_study_plan *plan, const mr_study_analyze_params *pp,
                             const char *out_dir, mr_error *err) {
    mr_study_analyze_params p = pp ? *pp : (mr_study_analyze_params)MR_STUDY_ANALYZE_DEFAULTS;
    if (!plan || plan->design != MR_STUDY_RATING) return mr_fail(err, MR_ERR_INVALID, "a rating analysis needs its rating plan");
    int N = votes->count > 0 ? votes->count : 1, M = plan->set.method_count, K = plan->scale_count;
    bool *use = calloc((size_t)N, sizeof *use);
    int *stim = calloc((size_t)N, sizeof *stim), *meth = calloc((size_t)N, sizeof *meth);
    people P = {0};
    bool ok = use && stim && meth ? gather(votes, plan, &P, use, stim, meth, err) : mr_fail(err, MR_ERR_NOMEM, "out of memory");
    /* sum and count per (participant, block 0..1, method, scale). */
    size_t cells = (size_t)(ok ? P.n : 1) * 2 * M * K;
    double *sum = ok ? calloc(cells, sizeof *sum) : NULL, *cnt = ok ? calloc(cells, sizeof *cnt) : NULL;
    double *mean = ok ? calloc(cells, sizeof *mean) : NULL;
    if (ok && (!sum || !cnt || !mean)) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
#define AT(pi, b, m, k) ((((size_t)(pi) * 2 + (b)) * M + (m)) * K + (k))
    int x_count = 0;
    for (int i = 0; ok && i < votes->count; i++) {
        if (!use[i]) continue;
        const mr_study_vote *v = &votes->v[i];
        int pi = person(&P, v->participant);
        for (int k = 0; k < K; k++) {
            if (v->ratings[k] == MR_STUDY_RATING_X) {
                x_count++;
                continue;
            }
            sum[AT(pi, v->block - 1, meth[i], k)] += v->ratings[k];
            cnt[AT(pi, v->block - 1, meth[i], k)] += 1;
        }
    }
    for (size_t c = 0; ok && c < cells; c++) mean[c] = cnt[c] > 0 ? sum[c] / cnt[c] : NAN;
    if (ok) ok = mr_mkdirs(out_dir, err);
    mr_csv *means = ok ? mr_csv_create(err) : NULL, *anova = ok ? mr_csv_create(err) : NULL;
    mr_csv *post = ok ? mr_csv_create(err) : NULL, *tt = ok ? mr_csv_create(err) : NULL;
    if (ok && (!means || !anova || !post || !tt)) ok = false;
    mr_sbuf md = {0};
    mr_csv_comment(means, "per condition, method and scale: over participants of their mean rating (1..7, 'X' left out)");
    mr_csv_header(means, "condition,method,scale,n,mean,sd");
    mr_csv_comment(anova, "per condition and scale: RM-ANOVA over the methods (Friedman with --test friedman), participants "
                          "with every method rated; p_reported is Greenhouse-Geisser's where Mauchly's test rejects sphericity");
    mr_csv_header(anova, OMNI_TESTS_HEADER);
    mr_csv_header(post, OMNI_POST_HEADER);
    mr_csv_comment(tt, "per method and scale: paired t-test of the participants' mean ratings, condition 1 (S1) against 2 (S2)");
    mr_csv_header(tt, "method,scale,n,mean_s1,mean_s2,t,df,p");
    mr_sb_printf(&md, "# Rating study\n\n%d answers of %d participants; plan %s; methods:", votes->count, P.n, plan->id);
    for (int m = 0; m < M; m++) mr_sb_printf(&md, " %s", plan->set.methods[m]);
    mr_sb_printf(&md, "; %d stimuli; %d scales rated 1..7 (%d 'X' answers left out).\n\n", plan->set.stimulus_count, K,
                 x_count);
    if (p.test == MR_STUDY_TEST_FRIEDMAN)
        mr_sb_printf(&md, "Method (as Kalkofen et al. analysed their categorical comparisons): per participant the mean "
                          "rating of each method on each scale; per condition and scale Friedman's test over the methods "
                          "(participants who rated every method), Wilcoxon signed-rank tests as post hoc with %s "
                          "adjustment; per method and scale a paired t-test between the conditions.\n\n",
                     mr_study_adjust_name((mr_study_adjust)p.adjust));
    else
        mr_sb_printf(&md, "Method (Scheer & Keutel, sec. 5): per participant the mean rating of each method on each scale; "
                          "per condition and scale a repeated-measures ANOVA over the methods (participants who rated every "
                          "method; Mauchly's test at %g, Greenhouse-Geisser-corrected df and p where it rejects "
                          "sphericity), paired t-tests as post hoc with %s adjustment; per method and scale a paired "
                          "t-test between the conditions.\n\n",
                     p.level, mr_study_adjust_name((mr_study_adjust)p.adjust));
    double *y = ok ? malloc((size_t)P.n * M * sizeof *y) : NULL, *yc = ok ? malloc((size_t)P.n * M * sizeof *yc) : NULL;
    double *bar_m = ok ? calloc((size_t)K * M, sizeof *bar_m) : NULL, *bar_s = ok ? calloc((size_t)K * M, sizeof *bar_s) : NULL;
    if (ok && (!y || !yc || !bar_m || !bar_s)) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int b = 1; ok && b <= 2; b++) {
        if (!(plan->blocks & (1u << (b - 1)))) continue;
        const char *cond = mr_study_condition_name(MR_STUDY_RATING, b);
        mr_sb_printf(&md, "## Condition %s (%s)\n\n", mr_study_block_name(b),
                     b == 1 ? "virtual only" : "with the camera image at alpha 0.5");
        mr_sb_printf(&md, "| scale | %s | post hoc |\n|---|---|---|\n",
                     p.test == MR_STUDY_TEST_FRIEDMAN ? "Friedman" : "ANOVA");
        for (int k = 0; ok && k < K; k++) {
            for (int m = 0; m < M; m++) {
                double s = 0, s2 = 0;
                int n = 0;
                for (int pi = 0; pi < P.n; pi++) {
                    double v = mean[AT(pi, b - 1, m, k)];
                    if (isfinite(v)) s += v, s2 += v * v, n++;
                }
                double mu = n ? s / n : NAN, sd = n > 1 ? sqrt(fmax(0.0, (s2 - n * mu * mu) / (n - 1))) : NAN;
                bar_m[k * M + m] = mu, bar_s[k * M + m] = sd;
                mr_csv_text(means, cond);
                mr_csv_text(means, plan->set.methods[m]);
                mr_csv_text(means, plan->scales[k]);
                mr_csv_int(means, n);
                mr_csv_num(means, "%.6f", mu);
                mr_csv_num(means, "%.6f", sd);
                mr_csv_end_row(means);
            }
            for (int pi = 0; pi < P.n; pi++)
                for (int m = 0; m < M; m++) y[pi * M + m] = mean[AT(pi, b - 1, m, k)];
            int n = complete_rows(y, P.n, M, yc);
            omni o;
            char ftxt[64], pair[160];
            if (M >= 2 && omnibus(yc, n, M, p.test == MR_STUDY_TEST_FRIEDMAN ? 0 : 1, &p, &o)) {
                omni_rows(anova, post, cond, plan->scales[k], &o, plan, (mr_study_adjust)p.adjust);
                omni_text(&o, ftxt, sizeof ftxt);
                mr_sb_printf(&md, "| %s | %s, %s%s |", plan->scales[k], ftxt, stars(o.p), o.gg ? " (GG)" : "");
                for (int q = 0; q < o.pairs; q++) {
                    pair_text(&o, q, plan, pair, sizeof pair);
                    mr_sb_printf(&md, "%s%s", q ? "; " : " ", pair);
                }
                mr_sb_printf(&md, " |\n");
            } else {
                mr_sb_printf(&md, "| %s | too few participants (%d) | |\n", plan->scales[k], n);
            }
        }
        char name[64], path[8192];
        snprintf(name, sizeof name, "chart_%s.svg", cond);
        mr_path_join(out_dir, name, path, sizeof path);
        char title[160];
        snprintf(title, sizeof title, "Ratings, %s: mean and SD over participants", cond);
        ok = chart_bars(path, title, "rating (1..7)", (const name_t *)plan->scales, K, (const name_t *)plan->set.methods,
                        M, bar_m, bar_s, 7.0, err);
        mr_sb_printf(&md, "\n![%s](%s)\n\n", cond, name);
    }
    /* Scheer & Keutel's overall question: how often each method was chosen,
     * against an even split (chi-square goodness of fit, t - 1 df). */
    mr_csv *overall = ok && plan->overall ? mr_csv_create(err) : NULL;
    if (overall) {
        mr_csv_comment(overall, "the overall question: choices per condition and method; chi2 against an even split");
        mr_csv_header(overall, "condition,method,chosen,share,chi2,df,p");
        mr_sb_printf(&md, "## Which representation supports the depth cues best as a whole\n\n");
    }
    for (int b = 1; overall && b <= 2; b++) {
        if (!(plan->blocks & (1u << (b - 1)))) continue;
        double n[MR_STUDY_MAX_METHODS] = {0}, tot = 0;
        for (int i = 0; i < votes->count; i++) {
            const mr_study_vote *v = &votes->v[i];
            if (strcmp(v->plan, plan->id) || v->design != MR_STUDY_RATING || v->block != b || strcmp(v->left, "*") ||
                v->choice < 0 || v->choice >= M)
                continue;
            n[v->choice] += 1, tot += 1;
        }
        double chi = 0;
        for (int m = 0; m < M; m++) chi += tot > 0 ? (n[m] - tot / M) * (n[m] - tot / M) / (tot / M) : 0;
        double pv = tot > 0 ? mr_stat_chi2_sf(chi, M - 1) : NAN;
        mr_sb_printf(&md, "%s: %.0f answers;", mr_study_condition_name(MR_STUDY_RATING, b), tot);
        for (int m = 0; m < M; m++) {
            mr_csv_text(overall, mr_study_condition_name(MR_STUDY_RATING, b));
            mr_csv_text(overall, plan->set.methods[m]);
            mr_csv_num(overall, "%g", n[m]);
            mr_csv_num(overall, "%.6f", tot > 0 ? n[m] / tot : NAN);
            mr_csv_num(overall, "%.6f", chi);
            mr_csv_int(overall, M - 1);
            mr_csv_num(overall, "%.6g", pv);
            mr_csv_end_row(overall);
            mr_sb_printf(&md, "%s %s %.0f (%.1f %%)", m ? "," : "", plan->set.methods[m], n[m],
                         tot > 0 ? 100 * n[m] / tot : NAN);
        }
        mr_sb_printf(&md, "; against an even split chi2(%d) = %.2f, p = %.4g.\n\n", M - 1, chi, pv);
    }
    if (overall) ok = save_csv(&overall, out_dir, "overall.csv", err);
    /* Table 4: the conditions against each other per method and scale. */
    if (ok && (plan->blocks & 3u) == 3u) {
        mr_sb_printf(&md, "## Virtual (S1) against video (S2), paired t\n\n| scale |");
        for (int m = 0; m < M; m++) mr_sb_printf(&md, " %s |", plan->set.methods[m]);
        mr_sb_printf(&md, "\n|---|");
        for (int m = 0; m < M; m++) mr_sb_printf(&md, "---|");
        mr_sb_printf(&md, "\n");
        double *a = y, *c = yc;
        for (int k = 0; k < K; k++) {
            mr_sb_printf(&md, "| %s |", plan->scales[k]);
            for (int m = 0; m < M; m++) {
                int n = 0;
                for (int pi = 0; pi < P.n; pi++) {
                    double s1 = mean[AT(pi, 0, m, k)], s2 = mean[AT(pi, 1, m, k)];
                    if (isfinite(s1) && isfinite(s2)) a[n] = s1, c[n] = s2, n++;
                }
                mr_study_ttest t;
                bool have = mr_study_paired_t(a, c, n, &t);
                mr_csv_text(tt, plan->set.methods[m]);
                mr_csv_text(tt, plan->scales[k]);
                mr_csv_int(tt, n);
                double m1 = 0, m2 = 0;
                for (int r = 0; r < n; r++) m1 += a[r] / n, m2 += c[r] / n;
                mr_csv_num(tt, "%.6f", n ? m1 : NAN);
                mr_csv_num(tt, "%.6f", n ? m2 : NAN);
                mr_csv_num(tt, "%.6f", have ? t.t : NAN);
                mr_csv_num(tt, "%.6g", have ? t.df : NAN);
                mr_csv_num(tt, "%.6g", have ? t.p : NAN);
                mr_csv_end_row(tt);
                if (have) mr_sb_printf(&md, " T=%.2f, S1%sS2, %s |", t.t, t.mean_diff < 0 ? "<" : ">", stars(t.p));
                else mr_sb_printf(&md, " - |");
            }
            mr_sb_printf(&md, "\n");
        }
        mr_sb_printf(&md, "\n");
    }
#undef AT
    mr_sb_printf(&md, "Files: means.csv, anova.csv, posthoc.csv, ttest.csv, chart_<condition>.svg.\n");
    if (ok) ok = save_csv(&means, out_dir, "means.csv", err);
    if (ok) ok = save_csv(&anova, out_dir, "anova.csv", err);
    if (ok) ok = save_csv(&post, out_dir, "posthoc.csv", err);
    if (ok) ok = save_csv(&tt, out_dir, "ttest.csv", err);
    if (ok) {
        char path[8192];
        mr_path_join(out_dir, "summary.md", path, sizeof path);
        ok = mr_sb_save(&md, path, err);
    }
    mr_csv_destroy(&means), mr_csv_destroy(&anova), mr_csv_destroy(&post), mr_csv_destroy(&tt);
    free(md.s), free(y), free(yc), free(bar_m), free(bar_s);
    free(sum), free(cnt), free(mean), free(use), free(stim), free(meth), free(P.v);
    return ok;
}

/* --------------------------------------------------------------- task */

bool mr_study_analyze_task(const mr_study_votes *votes, const mr_study_plan *plan, const mr_study_analyze_params *pp,
                           const char *out_dir, mr_error *err) {
    mr_study_analyze_params p = pp ? *pp : (mr_study_analyze_params)MR_STUDY_ANALYZE_DEFAULTS;
    if (!plan || plan->design != MR_STUDY_TASK) return mr_fail(err, MR_ERR_INVALID, "a task analysis needs its task plan");
    int N = votes->count > 0 ? votes->count : 1, M = plan->set.method_count;
    bool *use = calloc((size_t)N, sizeof *use);
    int *stim = calloc((size_t)N, sizeof *stim), *meth = calloc((size_t)N, sizeof *meth);
    people P = {0};
    bool ok = use && stim && meth ? gather(votes, plan, &P, use, stim, meth, err) : mr_fail(err, MR_ERR_NOMEM, "out of memory");
    /* Per (participant, block, method): answers, right, taps, tap error px and units. */
    enum { F_N, F_RIGHT, F_TAPS, F_PX, F_UNITS, F_COUNT };
    size_t cells = (size_t)(ok ? P.n : 1) * 2 * M;
    double *acc = ok ? calloc(cells * F_COUNT, sizeof *acc) : NULL;
    if (ok && !acc) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
#define AT(pi, b, m, f) ((((size_t)(pi) * 2 + (b)) * M + (m)) * F_COUNT + (f))
    if (ok) ok = mr_mkdirs(out_dir, err);
    mr_csv *trials = ok ? mr_csv_create(err) : NULL, *scores = ok ? mr_csv_create(err) : NULL;
    mr_csv *tests = ok ? mr_csv_create(err) : NULL, *post = ok ? mr_csv_create(err) : NULL;
    if (ok && (!trials || !scores || !tests || !post)) ok = false;
    char note[200];
    snprintf(note, sizeof note, "each answer scored: choice right or wrong; tap error in image px and scene units "
                                "(px x units_per_px of the answer), right within %g px", p.tap_tolerance);
    mr_csv_comment(trials, note);
    mr_csv_header(trials, "participant,condition,trial,stimulus,method,question,answer,right,error_px,error_units,ms");
    for (int i = 0; ok && i < votes->count; i++) {
        if (!use[i]) continue;
        const mr_study_vote *v = &votes->v[i];
        const mr_study_key *k = mr_study_plan_key(plan, v->block, stim[i]);
        int pi = person(&P, v->participant);
        bool right = false;
        double epx = NAN, eu = NAN;
        char ans[64] = "";
        if (k->question == MR_STUDY_Q_CHOICE && v->choice >= 0) {
            right = v->choice == k->correct;
            snprintf(ans, sizeof ans, "%s", k->labels[v->choice]);
        } else if (k->question == MR_STUDY_Q_TAP && v->has_tap) {
            epx = hypot(v->tap_x - k->x, v->tap_y - k->y);
            eu = epx * k->units_per_px;
            right = epx <= p.tap_tolerance;
            snprintf(ans, sizeof ans, "%.1f %.1f", v->tap_x, v->tap_y);
            acc[AT(pi, v->block - 1, meth[i], F_TAPS)] += 1;
            acc[AT(pi, v->block - 1, meth[i], F_PX)] += epx;
            acc[AT(pi, v->block - 1, meth[i], F_UNITS)] += eu;
        } else {
            snprintf(ans, sizeof ans, "(does not answer the question)");
        }
        acc[AT(pi, v->block - 1, meth[i], F_N)] += 1;
        acc[AT(pi, v->block - 1, meth[i], F_RIGHT)] += right;
        mr_csv_text(trials, v->participant);
        mr_csv_text(trials, mr_study_condition_name(MR_STUDY_TASK, v->block));
        mr_csv_int(trials, v->trial);
        mr_csv_text(trials, v->stimulus);
        mr_csv_text(trials, v->left);
        mr_csv_text(trials, k->question == MR_STUDY_Q_CHOICE ? "nearer" : "crossing");
        mr_csv_quoted(trials, ans);
        mr_csv_int(trials, right);
        mr_csv_num(trials, "%.3f", epx);
        mr_csv_num(trials, "%.6g", eu);
        mr_csv_num(trials, "%.0f", v->ms);
        mr_csv_end_row(trials);
    }
    mr_csv_comment(scores, "per participant, condition and method: share of right answers, mean tap error");
    mr_csv_header(scores, "participant,condition,method,answers,right,share_right,taps,mean_error_px,mean_error_units");
    for (int pi = 0; ok && pi < P.n; pi++)
        for (int b = 0; b < 2; b++)
            for (int m = 0; m < M; m++) {
                const double *a = &acc[AT(pi, b, m, 0)];
                if (!(a[F_N] > 0)) continue;
                mr_csv_text(scores, P.v[pi]);
                mr_csv_text(scores, mr_study_condition_name(MR_STUDY_TASK, b + 1));
                mr_csv_text(scores, plan->set.methods[m]);
                mr_csv_num(scores, "%g", a[F_N]);
                mr_csv_num(scores, "%g", a[F_RIGHT]);
                mr_csv_num(scores, "%.6f", a[F_RIGHT] / a[F_N]);
                mr_csv_num(scores, "%g", a[F_TAPS]);
                mr_csv_num(scores, "%.3f", a[F_TAPS] > 0 ? a[F_PX] / a[F_TAPS] : NAN);
                mr_csv_num(scores, "%.6g", a[F_TAPS] > 0 ? a[F_UNITS] / a[F_TAPS] : NAN);
                mr_csv_end_row(scores);
            }
    mr_csv_comment(tests, "per condition and measure: RM-ANOVA where D'Agostino's test passes the residuals (or --test anova), "
                          "else Friedman (or --test friedman)");
    mr_csv_header(tests, OMNI_TESTS_HEADER);
    mr_csv_header(post, OMNI_POST_HEADER);
    mr_sbuf md = {0};
    mr_sb_printf(&md, "# Task study\n\n%d answers of %d participants; plan %s; methods:", votes->count, P.n, plan->id);
    for (int m = 0; m < M; m++) mr_sb_printf(&md, " %s", plan->set.methods[m]);
    mr_sb_printf(&md, ".\n\nMethod (Kalkofen et al., sec. 5): each answer scored against the plan's key (a tap is right "
                      "within %g px; its error also in scene units); per participant and method the share right and the "
                      "mean tap error; per condition and measure %s, post hoc %s with %s adjustment at %g.\n\n",
                 p.tap_tolerance,
                 p.test == MR_STUDY_TEST_ANOVA      ? "a repeated-measures ANOVA (forced)"
                 : p.test == MR_STUDY_TEST_FRIEDMAN ? "Friedman's test (forced)"
                                                    : "a repeated-measures ANOVA where the residuals pass D'Agostino's "
                                                      "normality test (Greenhouse-Geisser where Mauchly rejects "
                                                      "sphericity), else Friedman's test",
                 p.test == MR_STUDY_TEST_FRIEDMAN ? "Wilcoxon signed-rank" : "paired t (ANOVA) or Wilcoxon signed-rank (Friedman)",
                 mr_study_adjust_name((mr_study_adjust)p.adjust), p.level);
    double *y = ok ? malloc((size_t)P.n * M * sizeof *y) : NULL, *yc = ok ? malloc((size_t)P.n * M * sizeof *yc) : NULL;
    double bar_m[2 * MR_STUDY_MAX_METHODS], bar_s[2 * MR_STUDY_MAX_METHODS];
    if (ok && (!y || !yc)) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    static const char *const measures[2] = {"share_right", "tap_error_px"};
    for (int b = 1; ok && b <= 2; b++) {
        if (!(plan->blocks & (1u << (b - 1)))) continue;
        const char *cond = mr_study_condition_name(MR_STUDY_TASK, b);
        mr_sb_printf(&md, "## Condition %s (%s)\n\n| method | share right (mean, SD) | tap error px (mean) | tap error "
                          "units (mean) |\n|---|---|---|---|\n",
                     mr_study_block_name(b), b == 1 ? "conflicting colours, Experiment 1" : "no conflict, Experiment 2");
        for (int m = 0; m < M; m++) {
            double s = 0, s2 = 0, px = 0, un = 0;
            int n = 0, nt = 0;
            for (int pi = 0; pi < P.n; pi++) {
                const double *a = &acc[AT(pi, b - 1, m, 0)];
                if (!(a[F_N] > 0)) continue;
                double r = a[F_RIGHT] / a[F_N];
                s += r, s2 += r * r, n++;
                if (a[F_TAPS] > 0) px += a[F_PX] / a[F_TAPS], un += a[F_UNITS] / a[F_TAPS], nt++;
            }
            double mu = n ? s / n : NAN, sd = n > 1 ? sqrt(fmax(0.0, (s2 - n * mu * mu) / (n - 1))) : NAN;
            bar_m[m] = mu, bar_s[m] = sd;
            mr_sb_printf(&md, "| %s | %.3f (%.3f) | %.1f | %.4g |\n", plan->set.methods[m], mu, sd, nt ? px / nt : NAN,
                         nt ? un / nt : NAN);
        }
        mr_sb_printf(&md, "\n");
        for (int ms = 0; ok && ms < 2; ms++) {
            for (int pi = 0; pi < P.n; pi++)
                for (int m = 0; m < M; m++) {
                    const double *a = &acc[AT(pi, b - 1, m, 0)];
                    y[pi * M + m] = ms == 0 ? (a[F_N] > 0 ? a[F_RIGHT] / a[F_N] : NAN)
                                            : (a[F_TAPS] > 0 ? a[F_PX] / a[F_TAPS] : NAN);
                }
            int n = complete_rows(y, P.n, M, yc);
            if (ms == 1 && n == 0) continue; /* no tap questions */
            omni o;
            int force = p.test == MR_STUDY_TEST_ANOVA ? 1 : p.test == MR_STUDY_TEST_FRIEDMAN ? 0 : -1;
            if (M < 2 || !omnibus(yc, n, M, force, &p, &o)) {
                mr_sb_printf(&md, "%s: too few participants with every method (%d).\n\n", measures[ms], n);
                continue;
            }
            omni_rows(tests, post, cond, measures[ms], &o, plan, (mr_study_adjust)p.adjust);
            char ftxt[64], pair[160];
            omni_text(&o, ftxt, sizeof ftxt);
            mr_sb_printf(&md, "%s, n = %d: %s %s, p = %.4g%s", measures[ms], n, o.anova ? "RM-ANOVA" : "Friedman", ftxt,
                         o.p, o.gg ? " (Greenhouse-Geisser)" : "");
            if (isfinite(o.normal_p)) mr_sb_printf(&md, " (residuals' normality p = %.3g)", o.normal_p);
            mr_sb_printf(&md, ". Post hoc (%s):", o.anova ? "paired t" : "Wilcoxon");
            for (int q = 0; q < o.pairs; q++) {
                pair_text(&o, q, plan, pair, sizeof pair);
                mr_sb_printf(&md, "%s %s (%s = %.2f)", q ? ";" : "", pair, o.anova ? "t" : "Z", o.stat[q]);
            }
            mr_sb_printf(&md, ".\n\n");
        }
        char name[64], path[8192], title[160];
        snprintf(name, sizeof name, "chart_%s.svg", cond);
        mr_path_join(out_dir, name, path, sizeof path);
        snprintf(title, sizeof title, "Share of right answers, %s: mean and SD over participants", cond);
        name_t group = "share_right";
        ok = chart_bars(path, title, "share right", (const name_t *)&group, 1, (const name_t *)plan->set.methods, M,
                        bar_m, bar_s, 1.0, err);
        mr_sb_printf(&md, "![%s](%s)\n\n", cond, name);
    }
#undef AT
    mr_sb_printf(&md, "Files: trials.csv, scores.csv, tests.csv, posthoc.csv, chart_<condition>.svg.\n");
    if (ok) ok = save_csv(&trials, out_dir, "trials.csv", err);
    if (ok) ok = save_csv(&scores, out_dir, "scores.csv", err);
    if (ok) ok = save_csv(&tests, out_dir, "tests.csv", err);
    if (ok) ok = save_csv(&post, out_dir, "posthoc.csv", err);
    if (ok) {
        char path[8192];
        mr_path_join(out_dir, "summary.md", path, sizeof path);
        ok = mr_sb_save(&md, path, err);
    }
    mr_csv_destroy(&trials), mr_csv_destroy(&scores), mr_csv_destroy(&tests), mr_csv_destroy(&post);
    free(md.s), free(y), free(yc), free(acc), free(use), free(stim), free(meth), free(P.v);
    return ok;
}
