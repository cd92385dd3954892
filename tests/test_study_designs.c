/* lib/study's three designs: Hecher's pairwise schedules (two scenes per
 * category alternating between blocks I and II and split in block III,
 * balanced groups), eq. 5.6 as printed, the exclusion of inconsistent
 * participants against counts by hand, and simulated participants with
 * known effects recovered by the rating and the task analyses; the run
 * controller's rating and task trials. */
#include "mr_test.h"
#include "mr_study.h"

static void set_make(mr_study_set *s, const char *const *methods, int t, const char *const *stimuli, int S) {
    memset(s, 0, sizeof *s);
    s->method_count = t;
    s->reference = -1;
    for (int m = 0; m < t; m++) {
        snprintf(s->methods[m], MR_STUDY_NAME_MAX, "%s", methods[m]);
        if (!strcmp(methods[m], MR_STUDY_REFERENCE)) s->reference = m;
    }
    s->stimulus_count = S;
    s->stimuli = calloc((size_t)S, MR_STUDY_NAME_MAX);
    for (int i = 0; i < S; i++) snprintf(s->stimuli[i], MR_STUDY_NAME_MAX, "%s", stimuli[i]);
}

static char *read_text(const char *dir, const char *name) {
    char path[8400];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    size_t n;
    mr_error err = {0};
    return mr_file_read(path, &n, 0, &err);
}

static void push_vote(mr_study_votes *vs, const mr_study_vote *v) {
    if (vs->count == vs->cap) {
        vs->cap = vs->cap ? 2 * vs->cap : 256;
        vs->v = realloc(vs->v, (size_t)vs->cap * sizeof *vs->v);
    }
    vs->v[vs->count++] = *v;
}

static mr_study_vote vote_for(const mr_study_plan *p, const char *who, int k) {
    mr_study_vote v;
    memset(&v, 0, sizeof v);
    const mr_study_trial *t = &p->trials[k];
    snprintf(v.plan, sizeof v.plan, "%s", p->id);
    snprintf(v.participant, sizeof v.participant, "%s", who);
    v.design = p->design;
    v.block = t->block;
    v.trial = k;
    v.group = p->group;
    v.choice = -1;
    snprintf(v.stimulus, sizeof v.stimulus, "%s", p->set.stimuli[t->stimulus]);
    if (t->left < 0) { /* a rating plan's overall question */
        snprintf(v.left, sizeof v.left, "*");
        snprintf(v.right, sizeof v.right, "%d", t->right);
    } else {
        snprintf(v.left, sizeof v.left, "%s", p->set.methods[t->left]);
        snprintf(v.right, sizeof v.right, "%s", p->set.methods[t->right]);
    }
    return v;
}

/* ------------------------------------------------------------ pairwise */

static void test_pairwise_schedules(void) {
    static const char *const methods[4] = {"bp", "pcf", "pcss", "reference"};
    static const char *const stimuli[5] = {"fence.a", "fence.b", "plant.a", "plant.b", "solo"};
    mr_study_set set;
    set_make(&set, methods, 4, stimuli, 5);
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.participants = 8;
    pp.seed = 3;
    mr_study_plan plan;
    mr_error err = {0};
    CHECK(mr_study_plan_make("unused", &set, &pp, &plan, &err));
    CHECK(plan.schedule_count == 8 && plan.blocks == 7u);
    int groups[3] = {0}, first_a = 0;
    for (int q = 0; q < 8; q++) {
        const mr_study_schedule *sc = &plan.schedules[q];
        char id[8];
        snprintf(id, sizeof id, "P%02d", q + 1);
        CHECK(!strcmp(sc->id, id));
        groups[sc->group]++;
        /* 3 categories x (6 pairs + 1 identical) per block, as the thesis's 13 x 7 = 91. */
        CHECK(sc->trial_count == 3 * 3 * 7);
        for (int c = 0; c < 3; c++) {
            int sa = c == 2 ? 4 : 2 * c, sb = c == 2 ? 4 : 2 * c + 1;
            int scene_of[4] = {-1, -1, -1, -1}, pairs[4][16] = {{0}}, ident[4] = {0}, on[4][5] = {{0}};
            for (int k = 0; k < sc->trial_count; k++) {
                const mr_study_trial *t = &sc->trials[k];
                if (t->stimulus != sa && t->stimulus != sb) continue;
                CHECK(k >= (t->block - 1) * 21 && k < t->block * 21); /* blocks in order */
                if (t->left == t->right) {
                    ident[t->block]++;
                    continue;
                }
                int lo = t->left < t->right ? t->left : t->right, hi = t->left ^ t->right ^ lo;
                pairs[t->block][lo * 4 + hi]++;
                on[t->block][t->stimulus]++;
                if (t->block < 3) {
                    if (scene_of[t->block] < 0) scene_of[t->block] = t->stimulus;
                    CHECK(scene_of[t->block] == t->stimulus); /* one scene per block I, II */
                }
            }
            for (int b = 1; b <= 3; b++) {
                CHECK(ident[b] == 1);
                for (int i = 0; i < 4; i++)
                    for (int j = i + 1; j < 4; j++) CHECK(pairs[b][i * 4 + j] == 1);
            }
            if (c < 2) {
                CHECK(scene_of[1] != scene_of[2]); /* I and II alternate the two scenes */
                CHECK(on[3][sa] == 3 && on[3][sb] == 3); /* III: half the pairs on each */
                first_a += scene_of[1] == sa;
            } else {
                CHECK(scene_of[1] == 4 && scene_of[2] == 4 && on[3][4] == 6); /* one scene: every block */
            }
        }
    }
    CHECK(groups[MR_STUDY_GROUP_A] == 4 && groups[MR_STUDY_GROUP_B] == 4);
    CHECK(first_a > 0 && first_a < 16); /* which scene comes first is drawn per participant and category */
    /* Different orders per participant. */
    CHECK(memcmp(plan.schedules[0].trials, plan.schedules[1].trials, 63 * sizeof(mr_study_trial)) != 0);
    /* Save, load, select. */
    char dir[4096], path[4200];
    CHECK(mr_test_fresh_dir("study_designs_plan", dir, sizeof dir));
    snprintf(path, sizeof path, "%s/plan.json", dir);
    CHECK(mr_study_plan_save(path, &plan, &err));
    mr_study_plan b;
    CHECK(mr_study_plan_load(path, &b, &err));
    CHECK(!strcmp(b.id, plan.id) && b.schedule_count == 8);
    CHECK(mr_study_plan_select(&b, "P05", &err));
    CHECK(b.group == plan.schedules[4].group && b.trial_count == 63);
    CHECK(!memcmp(b.trials, plan.schedules[4].trials, 63 * sizeof(mr_study_trial)));
    CHECK(!mr_study_plan_select(&b, "P09", &err));
    mr_study_plan_free(&b);
    /* Block III's question follows the group. */
    CHECK(!strcmp(mr_study_question_of(3, MR_STUDY_GROUP_A), "better"));
    CHECK(!strcmp(mr_study_question_of(3, MR_STUDY_GROUP_B), "plausible"));
    CHECK(!strcmp(mr_study_question_of(2, MR_STUDY_GROUP_A), "plausible"));
    /* Three scenes in one category: refused. */
    static const char *const three[3] = {"x.a", "x.b", "x.c"};
    mr_study_set s3;
    set_make(&s3, methods, 4, three, 3);
    CHECK(!mr_study_plan_make("unused", &s3, &pp, &b, &err) && strstr(err.msg, "more than two"));
    mr_study_set_free(&s3);
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

/* Eq. 5.6 by hand: 3 participants, t = 4 (6 pairs), 6 no-preference
 * answers among the 18 different pairs, 2 of the 3 identical pairs:
 * (6 / 3) / (2 / 3) = 3; per pair (the share ratio) 3 / C(4,2) = 0.5. */
static void test_indifference_eq56(void) {
    CHECK_NEAR(mr_study_indifference_eq56(6, 3, 2, 3), 3.0, 1e-15);
    bool base;
    CHECK_NEAR(mr_study_indifference(6, 18, 2, 3, &base), 0.5, 1e-15);
    /* Every answer "no preference": eq. 5.6 reaches C(t,2), unclamped. */
    CHECK_NEAR(mr_study_indifference_eq56(18, 3, 3, 3), 6.0, 1e-15);
    CHECK(isnan(mr_study_indifference_eq56(6, 3, 0, 3)));
}

/* Exclusion by hand: methods a, b, c; p1 and p2 answer a > b > c; p3 in a
 * circle (a > b, b > c, c > a), so its row sums are 1, 1, 1, c = 1 and
 * xi = 0 < 0.3: excluded. With everyone a vs c is 2 : 1 (n = 3), without
 * p3 it is 2 : 0. */
static void test_exclusion(void) {
    static const char *const methods[3] = {"a", "b", "c"};
    static const char *const stimuli[1] = {"s"};
    mr_study_set set;
    set_make(&set, methods, 3, stimuli, 1);
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    mr_study_plan plan;
    mr_error err = {0};
    CHECK(mr_study_plan_make("unused", &set, &pp, &plan, &err) && plan.trial_count == 4);
    mr_study_votes vs = {0};
    for (int p = 0; p < 3; p++) {
        char who[8];
        snprintf(who, sizeof who, "p%d", p + 1);
        for (int k = 0; k < plan.trial_count; k++) {
            mr_study_vote v = vote_for(&plan, who, k);
            const mr_study_trial *t = &plan.trials[k];
            int L = t->left, R = t->right;
            bool left_wins = L < R; /* a > b > c */
            if (p == 2 && ((L == 0 && R == 2) || (L == 2 && R == 0))) left_wins = L == 2; /* c > a */
            v.answer = L == R ? MR_STUDY_NEUTRAL : left_wins ? MR_STUDY_LEFT : MR_STUDY_RIGHT;
            push_vote(&vs, &v);
        }
    }
    char dir[4096], out[4200], all[4300];
    CHECK(mr_test_fresh_dir("study_exclusion", dir, sizeof dir));
    snprintf(out, sizeof out, "%s/analysis", dir);
    snprintf(all, sizeof all, "%s/all_participants", out);
    mr_study_analyze_params ap = MR_STUDY_ANALYZE_DEFAULTS;
    CHECK(mr_study_analyze(&vs, &plan, &ap, out, &err));
    char *with = read_text(all, "pairs.csv"), *without = read_text(out, "pairs.csv");
    CHECK(with && strstr(with, "\nI,all,a,c,3,2,1,0,2,1,"));
    CHECK(without && strstr(without, "\nI,all,a,c,2,2,0,0,2,0,"));
    free(with), free(without);
    char *parts = read_text(all, "participants.csv");
    CHECK(parts && strstr(parts, "\np3,4,1,0.000000,0.000000,1,1,0\n") && strstr(parts, "\np1,4,1,1.000000,1.000000,0,1,0\n"));
    free(parts);
    parts = read_text(out, "participants.csv");
    CHECK(parts && !strstr(parts, "\np3,"));
    free(parts);
    char *md = read_text(out, "summary.md");
    CHECK(md && strstr(md, "Excluded (mean consistence below 0.300): p3."));
    free(md);
    /* A threshold below everyone's: nobody is left out. */
    ap.min_consistence = 0;
    CHECK(mr_study_analyze(&vs, &plan, &ap, out, &err));
    without = read_text(out, "pairs.csv");
    CHECK(without && strstr(without, "\nI,all,a,c,3,2,1,0,2,1,"));
    free(without);
    mr_study_votes_free(&vs);
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

/* -------------------------------------------------------------- rating */

/* 20 simulated participants rate D1, D2, D3 on two scales, virtual and
 * with video, as Scheer & Keutel's did: on "occlusion" D2 is far above D1
 * and D3 between; with video D1 rises. On "linear_perspective" the methods
 * do not differ. The analysis must find the effect, the post hoc order and
 * the change of D1 between the conditions, and no effect where none is. */
static void test_rating_simulated(void) {
    static const char *const methods[3] = {"D1", "D2", "D3"};
    static const char *const stimuli[2] = {"hall.v0", "hall.v1"};
    mr_study_set set;
    set_make(&set, methods, 3, stimuli, 2);
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.design = MR_STUDY_RATING;
    pp.scales = "occlusion,linear_perspective";
    mr_study_plan plan;
    mr_error err = {0};
    CHECK(mr_study_plan_make("unused", &set, &pp, &plan, &err));
    CHECK(plan.blocks == 3u && plan.scale_count == 2 && plan.trial_count == 2 * 3 * 2);
    const double base[2][3] = {{2.5, 6.0, 4.5}, {4.0, 5.5, 4.8}}; /* [condition][method] on occlusion */
    mr_rng rng;
    mr_rng_seed(&rng, 14);
    mr_study_votes vs = {0};
    for (int p = 0; p < 20; p++) {
        char who[8];
        snprintf(who, sizeof who, "s%02d", p);
        double offset = 0.6 * mr_rng_normal(&rng);
        for (int k = 0; k < plan.trial_count; k++) {
            mr_study_vote v = vote_for(&plan, who, k);
            const mr_study_trial *t = &plan.trials[k];
            v.rating_count = 2;
            double occ = base[t->block - 1][t->left] + offset + 0.7 * mr_rng_normal(&rng);
            double lin = 4.0 + offset + 0.8 * mr_rng_normal(&rng);
            v.ratings[0] = (int)fmin(7, fmax(1, lround(occ)));
            v.ratings[1] = p == 3 && k == 0 ? MR_STUDY_RATING_X : (int)fmin(7, fmax(1, lround(lin)));
            push_vote(&vs, &v);
        }
    }
    char dir[4096];
    CHECK(mr_test_fresh_dir("study_rating", dir, sizeof dir));
    mr_study_analyze_params ap = MR_STUDY_ANALYZE_DEFAULTS;
    CHECK_MSG(mr_study_analyze_rating(&vs, &plan, &ap, dir, &err), "%s", err.msg);
    char *anova = read_text(dir, "anova.csv"), *post = read_text(dir, "posthoc.csv"), *tt = read_text(dir, "ttest.csv");
    CHECK(anova && post && tt);
    /* Parse the reported p of each (condition, scale). */
    double p_occ[2] = {NAN, NAN}, p_lin[2] = {NAN, NAN};
    for (char *line = anova; line && *line;) {
        char *nl = strchr(line, '\n');
        char cond[32], scale[64];
        double v[17];
        if (sscanf(line, "%31[^,],%63[^,],rm-anova,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", cond, scale,
                   &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &v[11], &v[12]) == 15) {
            int c = !strcmp(cond, "video");
            if (!strcmp(scale, "occlusion")) p_occ[c] = v[12];
            else p_lin[c] = v[12];
        }
        line = nl ? nl + 1 : NULL;
    }
    CHECK(p_occ[0] < 1e-6 && p_occ[1] < 1e-3);
    CHECK(p_lin[0] > 0.01 && p_lin[1] > 0.01);
    /* D1 < D2 on occlusion, virtual, Bonferroni-adjusted. */
    char *row = post ? strstr(post, "\nvirtual,occlusion,D1,D2,paired-t,") : NULL;
    CHECK(row != NULL);
    if (row) {
        double d, t, pr, pa;
        CHECK(sscanf(row, "\nvirtual,occlusion,D1,D2,paired-t,%lf,%lf,%lf,bonferroni,%lf", &d, &t, &pr, &pa) == 4);
        CHECK(d < -2.5 && pa < 1e-6);
        CHECK_NEAR(pa, fmin(1.0, 3 * pr), 1e-9 + 1e-6 * pr);
    }
    /* Between the conditions: D1 rises with the video (S1 < S2). */
    row = tt ? strstr(tt, "\nD1,occlusion,20,") : NULL;
    CHECK(row != NULL);
    if (row) {
        double m1, m2, t, df, p;
        CHECK(sscanf(row, "\nD1,occlusion,20,%lf,%lf,%lf,%lf,%lf", &m1, &m2, &t, &df, &p) == 5);
        CHECK(m1 < m2 && t < 0 && df == 19 && p < 1e-3);
    }
    char *md = read_text(dir, "summary.md");
    CHECK(md && strstr(md, "D1<D2, p < .001") && strstr(md, "S1<S2"));
    free(md), free(anova), free(post), free(tt);
    /* Kalkofen's analysis of ratings: Friedman with Wilcoxon post hoc. */
    ap.test = MR_STUDY_TEST_FRIEDMAN;
    CHECK(mr_study_analyze_rating(&vs, &plan, &ap, dir, &err));
    anova = read_text(dir, "anova.csv"), post = read_text(dir, "posthoc.csv");
    CHECK(anova && strstr(anova, "\nvirtual,occlusion,friedman,20,"));
    CHECK(post && strstr(post, "\nvirtual,occlusion,D1,D2,wilcoxon,"));
    free(anova), free(post);
    mr_study_votes_free(&vs);
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

/* ---------------------------------------------------------------- task */

/* Three scenes with six targets each (Kalkofen's design), half "which is
 * nearer", half "tap where the pipe crosses the wall"; the plan rotates
 * the ghosting modes over the scenes per participant. 18 simulated
 * participants: with conflicting colours adaptive ghosting is right 95 %
 * of the time and alpha / g0 50 %, taps 8 px off against 60 px. */
static bool write_keys(const char *dir, const char *cond) {
    char sub[4200], path[4300];
    snprintf(sub, sizeof sub, "%s/%s", dir, cond);
    mr_error err = {0};
    if (!mr_mkdirs(sub, &err)) return false;
    cJSON *j = cJSON_CreateObject();
    for (int s = 0; s < 3; s++)
        for (int q = 0; q < 6; q++) {
            char name[32];
            snprintf(name, sizeof name, "scene%d.t%d", s, q);
            cJSON *o = cJSON_AddObjectToObject(j, name);
            if (q % 2 == 0) {
                cJSON_AddStringToObject(o, "question", "nearer");
                cJSON *l = cJSON_AddArrayToObject(o, "labels");
                cJSON_AddItemToArray(l, cJSON_CreateString("A"));
                cJSON_AddItemToArray(l, cJSON_CreateString("B"));
                cJSON_AddStringToObject(o, "correct", q % 4 ? "B" : "A");
            } else {
                cJSON_AddStringToObject(o, "question", "crossing");
                cJSON_AddNumberToObject(o, "x", 100 + 10 * q);
                cJSON_AddNumberToObject(o, "y", 80);
                cJSON_AddNumberToObject(o, "units_per_px", 0.01);
            }
        }
    snprintf(path, sizeof path, "%s/answers.json", sub);
    bool ok = mr_json_save(path, j, &err);
    cJSON_Delete(j);
    return ok;
}

static void test_task_simulated(void) {
    static const char *const methods[3] = {"adaptive", "alpha", "g0"};
    char names[18][32];
    const char *stimuli[18];
    for (int s = 0; s < 3; s++)
        for (int q = 0; q < 6; q++) {
            snprintf(names[s * 6 + q], 32, "scene%d.t%d", s, q);
            stimuli[s * 6 + q] = names[s * 6 + q];
        }
    mr_study_set set;
    set_make(&set, methods, 3, stimuli, 18);
    char dir[4096];
    CHECK(mr_test_fresh_dir("study_task", dir, sizeof dir));
    CHECK(write_keys(dir, "conflict") && write_keys(dir, "no-conflict"));
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.design = MR_STUDY_TASK;
    pp.participants = 18;
    mr_study_plan plan;
    mr_error err = {0};
    CHECK_MSG(mr_study_plan_make(dir, &set, &pp, &plan, &err), "%s", err.msg);
    CHECK(plan.blocks == 3u && plan.schedule_count == 18 && plan.trial_count == 2 * 18);
    /* The rotation: a scene's targets share one mode, the modes differ between scenes. */
    {
        int mode[3] = {-1, -1, -1};
        bool same = true;
        for (int k = 0; k < plan.trial_count; k++) {
            const mr_study_trial *t = &plan.trials[k];
            int sc = t->stimulus / 6;
            if (t->block != 1) continue;
            if (mode[sc] < 0) mode[sc] = t->left;
            same = same && mode[sc] == t->left;
        }
        CHECK(same && mode[0] != mode[1] && mode[1] != mode[2] && mode[0] != mode[2]);
    }
    const double p_right[2][3] = {{0.95, 0.5, 0.5}, {0.9, 0.6, 0.9}}, px[2][3] = {{8, 60, 60}, {8, 40, 8}};
    mr_rng rng;
    mr_rng_seed(&rng, 5);
    mr_study_votes vs = {0};
    for (int q = 0; q < 18; q++) {
        CHECK(mr_study_plan_select(&plan, plan.schedules[q].id, &err));
        for (int k = 0; k < plan.trial_count; k++) {
            mr_study_vote v = vote_for(&plan, plan.schedules[q].id, k);
            const mr_study_trial *t = &plan.trials[k];
            const mr_study_key *key = mr_study_plan_key(&plan, t->block, t->stimulus);
            if (key->question == MR_STUDY_Q_CHOICE) {
                bool right = mr_rng_uniform(&rng) < p_right[t->block - 1][t->left];
                v.choice = right ? key->correct : 1 - key->correct;
            } else {
                double e = px[t->block - 1][t->left] * fabs(mr_rng_normal(&rng));
                double a = 6.2831853 * mr_rng_uniform(&rng);
                v.has_tap = true;
                v.tap_x = key->x + e * cos(a);
                v.tap_y = key->y + e * sin(a);
            }
            push_vote(&vs, &v);
        }
    }
    char out[4200];
    snprintf(out, sizeof out, "%s/analysis", dir);
    mr_study_analyze_params ap = MR_STUDY_ANALYZE_DEFAULTS;
    ap.adjust = MR_STUDY_ADJUST_HOLM;
    CHECK(mr_study_analyze_task(&vs, &plan, &ap, out, &err));
    char *post = read_text(out, "posthoc.csv"), *tests = read_text(out, "tests.csv"), *trials = read_text(out, "trials.csv");
    CHECK(post && tests && trials);
    /* Conflict: adaptive beats alpha and g0 in the share right. */
    const char *rows[2] = {"\nconflict,share_right,adaptive,alpha,", "\nconflict,share_right,adaptive,g0,"};
    for (int i = 0; i < 2; i++) {
        char *row = post ? strstr(post, rows[i]) : NULL;
        CHECK(row != NULL);
        if (!row) continue;
        char test[16];
        double d, z, pr, pa;
        CHECK(sscanf(row + strlen(rows[i]), "%15[^,],%lf,%lf,%lf,holm,%lf", test, &d, &z, &pr, &pa) == 5);
        CHECK(d > 0.2 && pa < 0.01);
    }
    /* No conflict: alpha vs g0 and adaptive vs g0 differ, adaptive vs g0 not. */
    char *row = post ? strstr(post, "\nno-conflict,share_right,adaptive,g0,") : NULL;
    CHECK(row != NULL);
    if (row) {
        char test[16];
        double d, z, pr, pa;
        CHECK(sscanf(row, "\nno-conflict,share_right,adaptive,g0,%15[^,],%lf,%lf,%lf,holm,%lf", test, &d, &z, &pr, &pa) == 5);
        CHECK(pa > 0.05);
    }
    /* Tap errors: adaptive's far smaller in the conflict condition. */
    row = post ? strstr(post, "\nconflict,tap_error_px,adaptive,alpha,") : NULL;
    CHECK(row != NULL);
    if (row) {
        char test[16];
        double d, z, pr, pa;
        CHECK(sscanf(row, "\nconflict,tap_error_px,adaptive,alpha,%15[^,],%lf,%lf,%lf,holm,%lf", test, &d, &z, &pr, &pa) == 5);
        CHECK(d < -20 && pa < 0.01);
    }
    /* Auto: RM-ANOVA exactly where the residuals' normality p >= 0.05. */
    int decided = 0;
    for (char *line = tests; line && *line;) {
        char *nl = strchr(line, '\n');
        char cond[32], measure[32], test[16];
        int n;
        double np;
        if (sscanf(line, "%31[^,],%31[^,],%15[^,],%d,%lf,", cond, measure, test, &n, &np) == 5) {
            CHECK(isfinite(np) && n == 18);
            CHECK(!strcmp(test, np >= 0.05 ? "rm-anova" : "friedman"));
            decided++;
        }
        line = nl ? nl + 1 : NULL;
    }
    CHECK(decided == 4);
    /* Forced either way. */
    ap.test = MR_STUDY_TEST_ANOVA;
    CHECK(mr_study_analyze_task(&vs, &plan, &ap, out, &err));
    free(tests);
    tests = read_text(out, "tests.csv");
    CHECK(tests && strstr(tests, "\nconflict,share_right,rm-anova,18,nan,2,34,"));
    ap.test = MR_STUDY_TEST_FRIEDMAN;
    CHECK(mr_study_analyze_task(&vs, &plan, &ap, out, &err));
    free(tests);
    tests = read_text(out, "tests.csv");
    CHECK(tests && strstr(tests, "\nconflict,share_right,friedman,18,nan,2,,"));
    free(post);
    post = read_text(out, "posthoc.csv");
    CHECK(post && strstr(post, "\nconflict,share_right,adaptive,alpha,wilcoxon,"));
    /* A tap's error in scene units is its px times units_per_px. */
    {
        mr_study_plan_select(&plan, "P01", &err);
        const char *line = trials ? strstr(trials, "\nP01,") : NULL;
        int hits = 0;
        for (; line; line = strstr(line + 1, "\nP01,")) {
            double epx, eu;
            const char *c = strstr(line, ",crossing,");
            const char *nl = strchr(line + 1, '\n');
            if (!c || (nl && c > nl)) continue;
            c = strchr(c + 10, '"');
            c = c ? strchr(c + 1, '"') : NULL;
            if (c && sscanf(c + 1, ",%*d,%lf,%lf", &epx, &eu) == 2) {
                CHECK_NEAR(eu, epx * 0.01, 1e-5 + 1e-6 * epx);
                hits++;
            }
        }
        CHECK(hits == 18);
    }
    free(post), free(tests), free(trials);
    mr_study_votes_free(&vs);
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

/* ------------------------------------------------------------- runner */

static void test_runner_designs(void) {
    static const char *const methods[3] = {"D1", "D2", "D3"};
    static const char *const stimuli[1] = {"hall"};
    mr_study_set set;
    set_make(&set, methods, 3, stimuli, 1);
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.design = MR_STUDY_RATING;
    pp.scales = "occlusion,contrast";
    pp.fixation_ms = 100;
    mr_study_plan plan;
    mr_error err = {0};
    CHECK(mr_study_plan_make("unused", &set, &pp, &plan, &err));
    mr_study_run_params rp = MR_STUDY_RUN_DEFAULTS;
    rp.plan = &plan;
    rp.participant = "r1";
    rp.image_w = 8, rp.image_h = 6;
    mr_study_runner *r = mr_study_runner_create(&rp, &err);
    if (!r) {
        printf("test_runner_designs: no system font (%s)\n", err.msg);
        mr_study_plan_free(&plan);
        mr_study_set_free(&set);
        mr_test_failures++;
        return;
    }
    mr_study_frame f;
    mr_study_vote v;
    mr_study_runner_frame(r, 0.0, 1000, 700, &f, &v);
    mr_study_runner_frame(r, 0.2, 1000, 700, &f, &v);
    CHECK(!f.fixation && f.trial == 0 && f.image_count == 1 && f.image_method[0] == plan.trials[0].left);
    mr_event k5 = {MR_EVENT_KEY, 0, 0, '5'}, kx = {MR_EVENT_KEY, 0, 0, 'x'};
    mr_study_runner_push_event(r, &k5);
    mr_study_runner_frame(r, 0.3, 1000, 700, &f, &v);
    CHECK(!f.vote); /* one scale of two */
    mr_study_runner_push_event(r, &kx);
    mr_study_runner_frame(r, 0.4, 1000, 700, &f, &v);
    CHECK(f.vote && v.design == MR_STUDY_RATING && v.rating_count == 2 && v.ratings[0] == 5 &&
          v.ratings[1] == MR_STUDY_RATING_X);
    CHECK(!strcmp(v.left, plan.set.methods[plan.trials[0].left]));
    mr_study_runner_destroy(&r);
    /* Resumed where block II begins: its break screen first, the fixation
     * after Continue (Enter), then the trial. */
    {
        bool answered[6] = {true, true, true, false, false, false};
        rp.first_trial = 3;
        rp.answered = answered;
        r = mr_study_runner_create(&rp, &err);
        CHECK(r != NULL);
        if (r) {
            mr_study_runner_frame(r, 0.0, 1000, 700, &f, &v);
            mr_study_runner_frame(r, 5.0, 1000, 700, &f, &v);
            cJSON *st = mr_study_runner_state_json(r);
            CHECK(cJSON_IsTrue(cJSON_GetObjectItem(st, "break")) && !f.fixation && f.image_count == 0 && f.trial == -1);
            cJSON_Delete(st);
            mr_event enter = {MR_EVENT_KEY, 0, 0, MR_KEY_ENTER};
            mr_study_runner_push_event(r, &enter);
            mr_study_runner_frame(r, 5.1, 1000, 700, &f, &v);
            mr_study_runner_frame(r, 5.15, 1000, 700, &f, &v);
            CHECK(f.fixation && !f.vote); /* the cross's full 100 ms after Continue */
            mr_study_runner_frame(r, 5.25, 1000, 700, &f, &v);
            CHECK(!f.fixation && f.trial == 3 && plan.trials[3].block == 2);
            mr_study_runner_destroy(&r);
        }
        rp.first_trial = 0;
        rp.answered = NULL;
    }
    mr_study_plan_free(&plan);
    /* Task: a choice by key, then a tap on the image and Confirm. */
    char dir[4096];
    CHECK(mr_test_fresh_dir("study_runner_task", dir, sizeof dir));
    char sub[4200], path[4300];
    snprintf(sub, sizeof sub, "%s/conflict", dir);
    CHECK(mr_mkdirs(sub, &err));
    snprintf(path, sizeof path, "%s/answers.json", sub);
    const char *keys = "{\"hall\": {\"question\": \"crossing\", \"x\": 4, \"y\": 3, \"units_per_px\": 0.5}}";
    CHECK(mr_file_write_atomic(path, keys, strlen(keys), &err));
    pp.design = MR_STUDY_TASK;
    pp.blocks = 1u;
    CHECK(mr_study_plan_make(dir, &set, &pp, &plan, &err));
    rp.plan = &plan;
    r = mr_study_runner_create(&rp, &err);
    CHECK(r != NULL);
    if (r) {
        mr_study_runner_frame(r, 0.0, 1000, 700, &f, &v);
        mr_study_runner_frame(r, 0.2, 1000, 700, &f, &v);
        CHECK(f.image_count == 1);
        mr_ui_rect ir = f.image_rect[0];
        /* Confirm before a tap does nothing. */
        mr_event enter = {MR_EVENT_KEY, 0, 0, MR_KEY_ENTER};
        mr_study_runner_push_event(r, &enter);
        mr_study_runner_frame(r, 0.3, 1000, 700, &f, &v);
        CHECK(!f.vote);
        double x = ir.x + ir.w * 0.25, y = ir.y + ir.h * 0.5;
        mr_event down = {MR_EVENT_POINTER_DOWN, x, y, 0}, up = {MR_EVENT_POINTER_UP, x, y, 0};
        mr_study_runner_push_event(r, &down);
        mr_study_runner_frame(r, 0.4, 1000, 700, &f, &v);
        mr_study_runner_push_event(r, &up);
        mr_study_runner_frame(r, 0.5, 1000, 700, &f, &v);
        CHECK(!f.vote);
        mr_study_runner_push_event(r, &enter);
        mr_study_runner_frame(r, 0.6, 1000, 700, &f, &v);
        CHECK(f.vote && v.design == MR_STUDY_TASK && v.has_tap && v.choice == -1);
        CHECK_NEAR(v.tap_x, 2.0, 0.05);
        CHECK_NEAR(v.tap_y, 3.0, 0.05);
        mr_study_runner_destroy(&r);
    }
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

/* The vote line of each design round trips through the log. */
static void test_vote_lines(void) {
    char dir[4096], path[4200];
    CHECK(mr_test_fresh_dir("study_vote_lines", dir, sizeof dir));
    snprintf(path, sizeof path, "%s/votes.jsonl", dir);
    mr_error err = {0};
    mr_study_vote a;
    memset(&a, 0, sizeof a);
    snprintf(a.plan, sizeof a.plan, "0123456789abcdef");
    snprintf(a.participant, sizeof a.participant, "P01");
    snprintf(a.stimulus, sizeof a.stimulus, "s");
    snprintf(a.left, sizeof a.left, "D1");
    snprintf(a.right, sizeof a.right, "D1");
    a.block = 2;
    a.design = MR_STUDY_RATING;
    a.rating_count = 3;
    a.ratings[0] = 7, a.ratings[1] = MR_STUDY_RATING_X, a.ratings[2] = 1;
    a.choice = -1;
    mr_study_vote b = a;
    b.trial = 1;
    b.design = MR_STUDY_TASK;
    b.rating_count = 0;
    b.has_tap = true, b.tap_x = 12.5, b.tap_y = -3;
    mr_study_vote c = a;
    c.trial = 2;
    c.design = MR_STUDY_PAIRWISE;
    c.block = 3;
    c.group = MR_STUDY_GROUP_B;
    c.answer = MR_STUDY_LEFT;
    c.slider = -1;
    CHECK(mr_study_vote_append(path, &a, &err) && mr_study_vote_append(path, &b, &err) &&
          mr_study_vote_append(path, &c, &err));
    mr_study_votes vs = {0};
    CHECK(mr_study_votes_read(path, false, &vs, &err) && vs.count == 3 && vs.bad_lines == 0);
    if (vs.count == 3) {
        CHECK(vs.v[0].design == MR_STUDY_RATING && vs.v[0].rating_count == 3 && vs.v[0].ratings[1] == MR_STUDY_RATING_X &&
              vs.v[0].ratings[2] == 1);
        CHECK(vs.v[1].design == MR_STUDY_TASK && vs.v[1].has_tap && vs.v[1].tap_x == 12.5 && vs.v[1].choice == -1);
        CHECK(vs.v[2].design == MR_STUDY_PAIRWISE && vs.v[2].group == MR_STUDY_GROUP_B);
    }
    char *text = read_text(dir, "votes.jsonl");
    CHECK(text && strstr(text, "\"question\":\"plausible\""));
    free(text);
    mr_study_votes_free(&vs);
}

/* Scheer & Keutel's overall question: first in each condition, one per
 * stimulus, every method side by side in a rotation; the runner hands out
 * the method chosen; the log resumes over it; the analysis counts it. */
static void test_rating_overall(void) {
    static const char *const methods[3] = {"D1", "D2", "D3"};
    static const char *const stimuli[2] = {"hall_v0", "hall_v1"};
    mr_study_set set;
    set_make(&set, methods, 3, stimuli, 2);
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    pp.design = MR_STUDY_RATING;
    pp.scales = "occlusion";
    pp.overall = true;
    pp.fixation_ms = 100;
    mr_study_plan plan;
    mr_error err = {0};
    CHECK(mr_study_plan_make("unused", &set, &pp, &plan, &err));
    CHECK(plan.overall && plan.trial_count == 2 * (2 + 6));
    for (int k = 0; k < plan.trial_count; k++) {
        const mr_study_trial *t = &plan.trials[k];
        bool first = k % 8 < 2;
        CHECK(t->block == 1 + k / 8);
        CHECK((t->left < 0) == first);
        if (first) CHECK(t->right >= 0 && t->right < 3);
    }
    char dir[4096], path[4200];
    CHECK(mr_test_fresh_dir("study_overall", dir, sizeof dir));
    snprintf(path, sizeof path, "%s/plan.json", dir);
    mr_study_plan b;
    CHECK(mr_study_plan_save(path, &plan, &err) && mr_study_plan_load(path, &b, &err));
    CHECK(b.overall && !strcmp(b.id, plan.id) && !memcmp(b.trials, plan.trials, 16 * sizeof(mr_study_trial)));
    mr_study_plan_free(&b);
    /* Too many methods to show side by side. */
    static const char *const six[6] = {"a", "b", "c", "d", "e", "f"};
    mr_study_set s6;
    set_make(&s6, six, 6, stimuli, 2);
    CHECK(!mr_study_plan_make("unused", &s6, &pp, &b, &err));
    mr_study_set_free(&s6);
    /* The runner: all three images, key 2 picks the second position. */
    mr_study_run_params rp = MR_STUDY_RUN_DEFAULTS;
    rp.plan = &plan;
    rp.participant = "o1";
    rp.image_w = 8, rp.image_h = 6;
    mr_study_runner *r = mr_study_runner_create(&rp, &err);
    CHECK(r != NULL);
    mr_study_vote v;
    if (r) {
        mr_study_frame f;
        mr_study_runner_frame(r, 0.0, 1200, 700, &f, &v);
        mr_study_runner_frame(r, 0.2, 1200, 700, &f, &v);
        int rot = plan.trials[0].right;
        CHECK(f.image_count == 3 && f.image_method[0] == rot && f.image_method[1] == (rot + 1) % 3);
        CHECK(f.image_rect[0].x < f.image_rect[1].x && f.image_rect[1].x < f.image_rect[2].x);
        mr_event k2 = {MR_EVENT_KEY, 0, 0, '2'};
        mr_study_runner_push_event(r, &k2);
        mr_study_runner_frame(r, 0.3, 1200, 700, &f, &v);
        CHECK(f.vote && v.design == MR_STUDY_RATING && v.choice == (rot + 1) % 3 && !strcmp(v.left, "*"));
        mr_study_runner_destroy(&r);
        /* Through the log and back; the resume takes it as trial 0. */
        snprintf(path, sizeof path, "%s/votes.jsonl", dir);
        mr_study_votes vs = {0};
        CHECK(mr_study_vote_append(path, &v, &err) && mr_study_votes_read(path, false, &vs, &err) && vs.count == 1);
        if (vs.count == 1) CHECK(vs.v[0].choice == v.choice && vs.v[0].rating_count == 0);
        bool answered[16];
        CHECK(mr_study_resume(&plan, &vs, "o1", answered, &err) == 1 && answered[0]);
        mr_study_votes_free(&vs);
    }
    /* The analysis: 10 participants choose D2 seven times, D3 twice, D1
     * once per stimulus and condition; by hand: 20 answers, 2 / 14 / 4,
     * chi2 = ((2-20/3)^2 + (14-20/3)^2 + (4-20/3)^2) / (20/3) = 12.4. */
    mr_study_votes vs = {0};
    for (int q = 0; q < 10; q++) {
        char who[8];
        snprintf(who, sizeof who, "s%d", q);
        int pick = q < 7 ? 1 : q < 9 ? 2 : 0;
        for (int k = 0; k < plan.trial_count; k++) {
            mr_study_vote x = vote_for(&plan, who, k);
            const mr_study_trial *t = &plan.trials[k];
            if (t->left < 0) {
                snprintf(x.left, sizeof x.left, "*");
                snprintf(x.right, sizeof x.right, "%d", t->right);
                x.choice = pick;
            } else {
                x.rating_count = 1;
                x.ratings[0] = 3 + t->left;
            }
            push_vote(&vs, &x);
        }
    }
    snprintf(path, sizeof path, "%s/analysis", dir);
    mr_study_analyze_params ap = MR_STUDY_ANALYZE_DEFAULTS;
    CHECK_MSG(mr_study_analyze_rating(&vs, &plan, &ap, path, &err), "%s", err.msg);
    char *o = read_text(path, "overall.csv");
    CHECK(o && strstr(o, "\nvirtual,D1,2,0.100000,12.400000,2,") && strstr(o, "\nvirtual,D2,14,0.700000,12.400000,2,") &&
          strstr(o, "\nvideo,D3,4,0.200000,12.400000,2,"));
    free(o);
    mr_study_votes_free(&vs);
    mr_study_plan_free(&plan);
    mr_study_set_free(&set);
}

int main(void) {
    test_pairwise_schedules();
    test_indifference_eq56();
    test_exclusion();
    test_rating_simulated();
    test_task_simulated();
    test_runner_designs();
    test_vote_lines();
    test_rating_overall();
    return mr_test_finish("test_study_designs");
}
