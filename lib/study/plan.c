/* The stimulus folder, the study plan of the three designs (pairwise:
 * thesis sec. 4.3, all pairs plus one identical pair per category, random
 * order and sides, three blocks, two scenes per category alternating;
 * rating and task: every method on every stimulus per condition, or the
 * task's methods rotated over the scenes) and its JSON file. */
#include "mr_study.h"

#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

const mr_opt mr_study_plan_opts[] = {
    {"seed", MR_OPT_INT, offsetof(mr_study_plan_params, seed), 0, 2147483647, 1, NULL,
     "random seed of the order and sides: the same seed gives the same plan", 0},
    {"fixation-ms", MR_OPT_INT, offsetof(mr_study_plan_params, fixation_ms), 0, 60000, 2000, NULL,
     "fixation cross before each trial, milliseconds", 0},
    {"design", MR_OPT_ENUM, offsetof(mr_study_plan_params, design), 0, 0, 0, mr_study_design_names,
     "pairwise (Hecher), rating (Scheer & Keutel) or task (Kalkofen et al.)", 0},
    {"participants", MR_OPT_INT, offsetof(mr_study_plan_params, participants), 0, 999, 0, NULL,
     "one schedule per participant P01..PN (own order, scenes and group); 0: one shared schedule", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

const char *const mr_study_design_names[] = {"pairwise", "rating", "task", NULL};

const char *mr_study_condition_name(mr_study_design d, int block) {
    static const char *const rating[] = {"virtual", "video"}, *const task[] = {"conflict", "no-conflict"};
    if (d == MR_STUDY_RATING) return block >= 1 && block <= 2 ? rating[block - 1] : "?";
    if (d == MR_STUDY_TASK) return block >= 1 && block <= 2 ? task[block - 1] : "?";
    return mr_study_block_name(block);
}

void mr_study_category_of(const char *stimulus, char *out, size_t n) {
    const char *dot = strrchr(stimulus, '.');
    size_t len = dot && dot != stimulus ? (size_t)(dot - stimulus) : strlen(stimulus);
    snprintf(out, n, "%.*s", (int)len, stimulus);
}

const char *mr_study_group_name(mr_study_group g) {
    return g == MR_STUDY_GROUP_A ? "A" : g == MR_STUDY_GROUP_B ? "B" : "";
}

const char *mr_study_question_of(int block, mr_study_group g) {
    return block == 2 || (block == 3 && g == MR_STUDY_GROUP_B) ? "plausible" : "better";
}

const char *mr_study_block_name(int block) {
    static const char *const names[] = {"I", "II", "III"};
    return block >= 1 && block <= 3 ? names[block - 1] : "?";
}

static int block_parse(const char *s) {
    for (int b = 1; b <= 3; b++)
        if (strcmp(s, mr_study_block_name(b)) == 0) return b;
    return 0;
}

bool mr_study_blocks_parse(const char *text, unsigned *mask, mr_error *err) {
    *mask = 0;
    char buf[64];
    snprintf(buf, sizeof buf, "%s", text ? text : "");
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        int b = block_parse(tok);
        if (!b) return mr_fail(err, MR_ERR_INVALID, "blocks: '%s' is not one of I, II, III", tok);
        if (*mask & (1u << (b - 1))) return mr_fail(err, MR_ERR_INVALID, "blocks: %s given twice", tok);
        *mask |= 1u << (b - 1);
    }
    if (!*mask) return mr_fail(err, MR_ERR_INVALID, "blocks: none given (use e.g. I,II,III)");
    return true;
}

/* ------------------------------------------------------------- stimuli */

static bool good_name(const char *s) {
    if (!s[0] || strlen(s) >= MR_STUDY_NAME_MAX || s[0] == '.') return false;
    for (const char *p = s; *p; p++)
        if (!((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '_' ||
              *p == '-' || *p == '.'))
            return false;
    return true;
}

static int cmp_name(const void *a, const void *b) { return strcmp((const char *)a, (const char *)b); }

static bool is_dir(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* The stimuli (file stems of *.png) of one method folder, sorted. */
static int list_pngs(const char *dir, char (**out)[MR_STUDY_NAME_MAX]) {
    *out = NULL;
    DIR *d = opendir(dir);
    if (!d) return 0;
    int n = 0, cap = 0;
    for (struct dirent *e; (e = readdir(d));) {
        size_t len = strlen(e->d_name);
        if (len < 5 || strcmp(e->d_name + len - 4, ".png") != 0) continue;
        char stem[MR_STUDY_NAME_MAX + 8];
        snprintf(stem, sizeof stem, "%.*s", (int)(len - 4), e->d_name);
        if (!good_name(stem)) {
            mr_log(MR_LOG_WARN, "study: %s/%s: name not of [A-Za-z0-9_.-] (or too long), skipped", dir, e->d_name);
            continue;
        }
        if (n == cap) {
            cap = cap ? cap * 2 : 16;
            void *p = realloc(*out, (size_t)cap * MR_STUDY_NAME_MAX);
            if (!p) break;
            *out = p;
        }
        snprintf((*out)[n++], MR_STUDY_NAME_MAX, "%.63s", stem); /* good_name: < 64 */
    }
    closedir(d);
    if (n) qsort(*out, (size_t)n, MR_STUDY_NAME_MAX, cmp_name);
    return n;
}

bool mr_study_scan(const char *dir, mr_study_set *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    out->reference = -1;
    DIR *d = opendir(dir);
    if (!d) return mr_fail(err, MR_ERR_IO, "cannot open stimulus folder %s", dir);
    for (struct dirent *e; (e = readdir(d));) {
        char path[8192];
        mr_path_join(dir, e->d_name, path, sizeof path);
        if (e->d_name[0] == '.' || !is_dir(path)) continue;
        if (!good_name(e->d_name)) {
            mr_log(MR_LOG_WARN, "study: %s: method name not of [A-Za-z0-9_.-] (or too long), skipped", path);
            continue;
        }
        if (out->method_count == MR_STUDY_MAX_METHODS) {
            closedir(d);
            return mr_fail(err, MR_ERR_INVALID, "%s: more than %d method folders", dir, MR_STUDY_MAX_METHODS);
        }
        snprintf(out->methods[out->method_count++], MR_STUDY_NAME_MAX, "%.63s", e->d_name);
    }
    closedir(d);
    qsort(out->methods, (size_t)out->method_count, MR_STUDY_NAME_MAX, cmp_name);
    if (out->method_count < 2)
        return mr_fail(err, MR_ERR_INVALID, "%s: needs at least two method folders (DIR/<method>/<stimulus>.png), found %d",
                       dir, out->method_count);
    for (int m = 0; m < out->method_count; m++)
        if (strcmp(out->methods[m], MR_STUDY_REFERENCE) == 0) out->reference = m;
    /* The stimuli all methods have. */
    char(*lists[MR_STUDY_MAX_METHODS])[MR_STUDY_NAME_MAX];
    int counts[MR_STUDY_MAX_METHODS];
    for (int m = 0; m < out->method_count; m++) {
        char path[8192];
        mr_path_join(dir, out->methods[m], path, sizeof path);
        counts[m] = list_pngs(path, &lists[m]);
    }
    out->stimuli = calloc((size_t)(counts[0] > 0 ? counts[0] : 1), MR_STUDY_NAME_MAX);
    bool ok = out->stimuli != NULL || mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int s = 0; ok && s < counts[0]; s++) {
        bool all = true;
        for (int m = 1; m < out->method_count && all; m++)
            all = bsearch(lists[0][s], lists[m], (size_t)counts[m], MR_STUDY_NAME_MAX, cmp_name) != NULL;
        if (all) snprintf(out->stimuli[out->stimulus_count++], MR_STUDY_NAME_MAX, "%s", lists[0][s]);
        else mr_log(MR_LOG_WARN, "study: stimulus %s is missing for some method, left out", lists[0][s]);
    }
    for (int m = 1; ok && m < out->method_count; m++)
        for (int s = 0; s < counts[m]; s++)
            if (!bsearch(lists[m][s], out->stimuli, (size_t)out->stimulus_count, MR_STUDY_NAME_MAX, cmp_name))
                mr_log(MR_LOG_WARN, "study: stimulus %s is missing for some method, left out", lists[m][s]);
    for (int m = 0; m < out->method_count; m++) free(lists[m]);
    if (ok && out->stimulus_count == 0)
        ok = mr_fail(err, MR_ERR_INVALID, "%s: no stimulus <name>.png that every method folder has", dir);
    if (!ok) mr_study_set_free(out);
    return ok;
}

void mr_study_set_free(mr_study_set *s) {
    if (!s) return;
    free(s->stimuli);
    memset(s, 0, sizeof *s);
    s->reference = -1;
}

/* ---------------------------------------------------------------- plan */

static void trial_json(cJSON *arr, const mr_study_plan *p, const mr_study_trial *x, int i) {
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "trial", i);
    cJSON_AddStringToObject(o, "block", mr_study_block_name(x->block));
    cJSON_AddStringToObject(o, "stimulus", p->set.stimuli[x->stimulus]);
    if (x->left < 0) { /* the overall question: every method, from rotation right */
        char r[16];
        snprintf(r, sizeof r, "%d", x->right);
        cJSON_AddStringToObject(o, "left", "*");
        cJSON_AddStringToObject(o, "right", r);
    } else {
        cJSON_AddStringToObject(o, "left", p->set.methods[x->left]);
        cJSON_AddStringToObject(o, "right", p->set.methods[x->right]);
    }
    cJSON_AddItemToArray(arr, o);
}

/* What a plan says, in file order; its id hashes exactly this (not the
 * folder, so a moved stimulus folder keeps the plan's id). A pairwise plan
 * with one shared schedule writes what version 1 wrote, so its id stays. */
static cJSON *content_json(const mr_study_plan *p) {
    cJSON *j = cJSON_CreateObject();
    if (p->design != MR_STUDY_PAIRWISE) cJSON_AddStringToObject(j, "design", mr_study_design_names[p->design]);
    cJSON *m = cJSON_AddArrayToObject(j, "methods");
    for (int i = 0; i < p->set.method_count; i++) cJSON_AddItemToArray(m, cJSON_CreateString(p->set.methods[i]));
    cJSON *s = cJSON_AddArrayToObject(j, "stimuli");
    for (int i = 0; i < p->set.stimulus_count; i++) cJSON_AddItemToArray(s, cJSON_CreateString(p->set.stimuli[i]));
    cJSON_AddNumberToObject(j, "seed", p->seed);
    cJSON_AddNumberToObject(j, "fixation_ms", p->fixation_ms);
    cJSON *b = cJSON_AddArrayToObject(j, "blocks");
    for (int i = 1; i <= MR_STUDY_MAX_BLOCKS; i++)
        if (p->blocks & (1u << (i - 1))) cJSON_AddItemToArray(b, cJSON_CreateString(mr_study_block_name(i)));
    if (p->design == MR_STUDY_RATING) {
        if (p->overall) cJSON_AddBoolToObject(j, "overall", true);
        cJSON *sc = cJSON_AddArrayToObject(j, "scales");
        for (int i = 0; i < p->scale_count; i++) cJSON_AddItemToArray(sc, cJSON_CreateString(p->scales[i]));
    }
    if (p->design == MR_STUDY_TASK && p->keys) {
        cJSON *keys = cJSON_AddObjectToObject(j, "keys");
        for (int b2 = 1; b2 <= 2; b2++) {
            if (!(p->blocks & (1u << (b2 - 1)))) continue;
            cJSON *kb = cJSON_AddObjectToObject(keys, mr_study_block_name(b2));
            for (int st = 0; st < p->set.stimulus_count; st++) {
                const mr_study_key *k = &p->keys[(b2 - 1) * p->set.stimulus_count + st];
                cJSON *o = cJSON_AddObjectToObject(kb, p->set.stimuli[st]);
                cJSON_AddStringToObject(o, "question", k->question == MR_STUDY_Q_CHOICE ? "nearer" : "crossing");
                cJSON_AddStringToObject(o, "text", k->text);
                if (k->question == MR_STUDY_Q_CHOICE) {
                    cJSON *l = cJSON_AddArrayToObject(o, "labels");
                    cJSON_AddItemToArray(l, cJSON_CreateString(k->labels[0]));
                    cJSON_AddItemToArray(l, cJSON_CreateString(k->labels[1]));
                    cJSON_AddStringToObject(o, "correct", k->labels[k->correct]);
                } else {
                    cJSON_AddNumberToObject(o, "x", k->x);
                    cJSON_AddNumberToObject(o, "y", k->y);
                    cJSON_AddNumberToObject(o, "units_per_px", k->units_per_px);
                }
            }
        }
    }
    if (p->schedule_count == 1 && !p->schedules[0].id[0]) {
        cJSON *t = cJSON_AddArrayToObject(j, "trials");
        for (int i = 0; i < p->schedules[0].trial_count; i++) trial_json(t, p, &p->schedules[0].trials[i], i);
    } else {
        cJSON *ps = cJSON_AddArrayToObject(j, "participants");
        for (int q = 0; q < p->schedule_count; q++) {
            const mr_study_schedule *sc = &p->schedules[q];
            cJSON *o = cJSON_CreateObject();
            cJSON_AddStringToObject(o, "id", sc->id);
            if (sc->group) cJSON_AddStringToObject(o, "group", mr_study_group_name(sc->group));
            cJSON *t = cJSON_AddArrayToObject(o, "trials");
            for (int i = 0; i < sc->trial_count; i++) trial_json(t, p, &sc->trials[i], i);
            cJSON_AddItemToArray(ps, o);
        }
    }
    return j;
}

/* FNV-1a 64 of the compact content JSON, as 16 hex digits. */
static bool plan_hash(const mr_study_plan *p, char out[17]) {
    cJSON *j = content_json(p);
    char *text = j ? cJSON_PrintUnformatted(j) : NULL;
    cJSON_Delete(j);
    if (!text) return false;
    uint64_t h = 1469598103934665603ull;
    for (const char *c = text; *c; c++) h = (h ^ (uint8_t)*c) * 1099511628211ull;
    free(text);
    snprintf(out, 17, "%016llx", (unsigned long long)h);
    return true;
}

static uint64_t rng_below(mr_rng *r, uint64_t n) { return n ? mr_rng_u64(r) % n : 0; }

static void shuffle(mr_rng *rng, mr_study_trial *t, int n) {
    for (int i = n - 1; i > 0; i--) {
        int j = (int)rng_below(rng, (uint64_t)(i + 1));
        mr_study_trial x = t[i];
        t[i] = t[j];
        t[j] = x;
    }
}

/* Categories of the stimuli: cat[s] its index, first[c] / second[c] the
 * stimuli of category c (second -1 for a category of one scene). Pairwise
 * categories have one or two scenes; a rating or task category (a scene)
 * any number of stimuli (its targets), second unused. */
typedef struct cats {
    int n;
    int *cat, *first, *second;
} cats;

static bool cats_make(const mr_study_set *set, bool pairs, cats *c, mr_error *err) {
    int S = set->stimulus_count;
    c->n = 0;
    c->cat = calloc((size_t)S, sizeof(int));
    c->first = calloc((size_t)S, sizeof(int));
    c->second = calloc((size_t)S, sizeof(int));
    if (!c->cat || !c->first || !c->second) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int s = 0; s < S; s++) {
        char a[MR_STUDY_NAME_MAX], b[MR_STUDY_NAME_MAX];
        mr_study_category_of(set->stimuli[s], a, sizeof a);
        int found = -1;
        for (int k = 0; k < c->n && found < 0; k++) {
            mr_study_category_of(set->stimuli[c->first[k]], b, sizeof b);
            if (!strcmp(a, b)) found = k;
        }
        if (found < 0) {
            c->cat[s] = c->n;
            c->first[c->n] = s;
            c->second[c->n++] = -1;
        } else if (!pairs) {
            c->cat[s] = found; /* a scene's targets (task, rating): any number */
        } else if (c->second[found] < 0) {
            c->cat[s] = found;
            c->second[found] = s;
        } else {
            return mr_fail(err, MR_ERR_INVALID, "category %s has more than two scenes (%s, %s, %s)", a,
                           set->stimuli[c->first[found]], set->stimuli[c->second[found]], set->stimuli[s]);
        }
    }
    return true;
}

static void cats_free(cats *c) {
    free(c->cat);
    free(c->first);
    free(c->second);
}

/* One pairwise schedule (thesis sec. 4.3, "Avoiding Ordering Effects"). */
static int pairwise_schedule(const mr_study_set *set, const cats *C, unsigned blocks, mr_rng *rng,
                             mr_study_trial *out) {
    int t = set->method_count, k = 0;
    int npairs = t * (t - 1) / 2;
    /* Which scene of a two-scene category is block I's (the other is II's). */
    int *first_scene = malloc((size_t)C->n * sizeof(int));
    int *pi = malloc((size_t)npairs * sizeof(int)), *pj = malloc((size_t)npairs * sizeof(int));
    if (!first_scene || !pi || !pj) {
        free(first_scene), free(pi), free(pj);
        return -1;
    }
    for (int c = 0; c < C->n; c++)
        first_scene[c] = C->second[c] >= 0 && rng_below(rng, 2) ? C->second[c] : C->first[c];
    for (int b = 1; b <= MR_STUDY_MAX_BLOCKS; b++) {
        if (!(blocks & (1u << (b - 1)))) continue;
        int start = k;
        for (int c = 0; c < C->n; c++) {
            int sI = first_scene[c], sII = C->second[c] < 0 ? sI : sI == C->first[c] ? C->second[c] : C->first[c];
            int n = 0;
            for (int i = 0; i < t; i++)
                for (int j = i + 1; j < t; j++) pi[n] = i, pj[n++] = j;
            /* Block III: a random half of the pairs on block I's scene. */
            int half = npairs / 2 + (npairs % 2 ? (int)rng_below(rng, 2) : 0);
            if (b == 3) {
                for (int q = n - 1; q > 0; q--) {
                    int r = (int)rng_below(rng, (uint64_t)(q + 1)), x = pi[q], y = pj[q];
                    pi[q] = pi[r], pj[q] = pj[r], pi[r] = x, pj[r] = y;
                }
            }
            for (int q = 0; q < n; q++) {
                int s = b == 1 ? sI : b == 2 ? sII : q < half ? sI : sII;
                bool swap = rng_below(rng, 2);
                out[k++] = (mr_study_trial){b, s, swap ? pj[q] : pi[q], swap ? pi[q] : pj[q]};
            }
            int m = (int)rng_below(rng, (uint64_t)t);
            int s = b == 1 ? sI : b == 2 ? sII : rng_below(rng, 2) ? sI : sII;
            out[k++] = (mr_study_trial){b, s, m, m};
        }
        shuffle(rng, out + start, k - start);
    }
    free(first_scene), free(pi), free(pj);
    return k;
}

/* One rating or task schedule: per block every (method, stimulus), or
 * (task with participants) the method of category c is (c + rot) mod t. */
static int single_schedule(const mr_study_set *set, const cats *C, unsigned blocks, int rot, bool overall,
                           mr_rng *rng, mr_study_trial *out) {
    int t = set->method_count, k = 0;
    for (int b = 1; b <= 2; b++) {
        if (!(blocks & (1u << (b - 1)))) continue;
        /* The overall question first (Scheer & Keutel asked it before the
         * ratings), one per stimulus, the methods in a random rotation. */
        int first = k;
        for (int s = 0; overall && s < set->stimulus_count; s++)
            out[k++] = (mr_study_trial){b, s, -1, (int)rng_below(rng, (uint64_t)t)};
        shuffle(rng, out + first, k - first);
        int start = k;
        for (int s = 0; s < set->stimulus_count; s++) {
            if (rot >= 0) {
                int m = (C->cat[s] + rot) % t;
                out[k++] = (mr_study_trial){b, s, m, m};
            } else {
                for (int m = 0; m < t; m++) out[k++] = (mr_study_trial){b, s, m, m};
            }
        }
        shuffle(rng, out + start, k - start);
    }
    return k;
}

static bool parse_scales(const char *text, mr_study_plan *out, mr_error *err) {
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", text ? text : MR_STUDY_DEFAULT_SCALES);
    char *save = NULL;
    out->scale_count = 0;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (!good_name(tok)) return mr_fail(err, MR_ERR_INVALID, "scale '%s': names are [A-Za-z0-9_.-]+", tok);
        if (out->scale_count == MR_STUDY_MAX_SCALES)
            return mr_fail(err, MR_ERR_INVALID, "at most %d scales", MR_STUDY_MAX_SCALES);
        snprintf(out->scales[out->scale_count++], MR_STUDY_NAME_MAX, "%s", tok);
    }
    if (!out->scale_count) return mr_fail(err, MR_ERR_INVALID, "rating: no scale given");
    return true;
}

/* The answer keys of a task plan: DIR/<condition>/answers.json per block. */
static bool parse_key(const cJSON *o, const char *where, mr_study_key *k, mr_error *err) {
    memset(k, 0, sizeof *k);
    const cJSON *q = cJSON_GetObjectItemCaseSensitive(o, "question");
    const cJSON *text = cJSON_GetObjectItemCaseSensitive(o, "text");
    if (!cJSON_IsString(q)) return mr_fail(err, MR_ERR_PARSE, "%s: no \"question\"", where);
    if (cJSON_IsString(text)) snprintf(k->text, sizeof k->text, "%s", text->valuestring);
    if (!strcmp(q->valuestring, "nearer")) {
        k->question = MR_STUDY_Q_CHOICE;
        const cJSON *labels = cJSON_GetObjectItemCaseSensitive(o, "labels");
        const cJSON *correct = cJSON_GetObjectItemCaseSensitive(o, "correct");
        if (!cJSON_IsArray(labels) || cJSON_GetArraySize(labels) != 2 || !cJSON_IsString(correct))
            return mr_fail(err, MR_ERR_PARSE, "%s: \"nearer\" needs labels [2] and correct", where);
        for (int i = 0; i < 2; i++) {
            const cJSON *l = cJSON_GetArrayItem(labels, i);
            if (!cJSON_IsString(l) || !l->valuestring[0] || strlen(l->valuestring) >= sizeof k->labels[i])
                return mr_fail(err, MR_ERR_PARSE, "%s: bad label", where);
            snprintf(k->labels[i], sizeof k->labels[i], "%s", l->valuestring);
        }
        k->correct = !strcmp(correct->valuestring, k->labels[0]) ? 0 : !strcmp(correct->valuestring, k->labels[1]) ? 1 : -1;
        if (k->correct < 0) return mr_fail(err, MR_ERR_PARSE, "%s: correct is neither label", where);
        if (!k->text[0]) snprintf(k->text, sizeof k->text, "Which hidden object is nearer to you: %s or %s?", k->labels[0], k->labels[1]);
    } else if (!strcmp(q->valuestring, "crossing")) {
        k->question = MR_STUDY_Q_TAP;
        if (!mr_json_number(o, "x", &k->x, true, err) || !mr_json_number(o, "y", &k->y, true, err) ||
            !mr_json_number(o, "units_per_px", &k->units_per_px, true, err))
            return mr_fail(err, MR_ERR_PARSE, "%s: \"crossing\" needs x, y, units_per_px", where);
        if (!(k->units_per_px > 0) || !isfinite(k->x) || !isfinite(k->y))
            return mr_fail(err, MR_ERR_INVALID, "%s: x, y finite and units_per_px > 0", where);
        if (!k->text[0]) snprintf(k->text, sizeof k->text, "Tap where the hidden pipe crosses the wall.");
    } else {
        return mr_fail(err, MR_ERR_PARSE, "%s: question '%s' is not nearer or crossing", where, q->valuestring);
    }
    return true;
}

static bool keys_from(const cJSON *kb, const char *where, mr_study_plan *out, int b, mr_error *err) {
    for (int s = 0; s < out->set.stimulus_count; s++) {
        const cJSON *o = cJSON_GetObjectItemCaseSensitive(kb, out->set.stimuli[s]);
        char w[600];
        snprintf(w, sizeof w, "%s: %s", where, out->set.stimuli[s]);
        if (!cJSON_IsObject(o)) return mr_fail(err, MR_ERR_INVALID, "%s: no answer", w);
        if (!parse_key(o, w, &out->keys[(b - 1) * out->set.stimulus_count + s], err)) return false;
    }
    return true;
}

static bool load_keys(const char *dir, mr_study_plan *out, mr_error *err) {
    out->keys = calloc((size_t)2 * out->set.stimulus_count, sizeof *out->keys);
    if (!out->keys) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int b = 1; b <= 2; b++) {
        if (!(out->blocks & (1u << (b - 1)))) continue;
        char sub[4200], path[8300];
        mr_path_join(dir, mr_study_condition_name(MR_STUDY_TASK, b), sub, sizeof sub);
        mr_path_join(sub, "answers.json", path, sizeof path);
        cJSON *j = mr_json_load(path, err);
        if (!j) return false;
        bool ok = keys_from(j, path, out, b, err);
        cJSON_Delete(j);
        if (!ok) return false;
    }
    return true;
}

bool mr_study_plan_make(const char *dir, const mr_study_set *set, const mr_study_plan_params *pp, mr_study_plan *out,
                        mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_study_plan_params p = pp ? *pp : (mr_study_plan_params)MR_STUDY_PLAN_DEFAULTS;
    if (p.design < 0 || p.design > MR_STUDY_TASK) return mr_fail(err, MR_ERR_INVALID, "unknown design");
    mr_study_design d = (mr_study_design)p.design;
    unsigned blocks = p.blocks;
    if (d == MR_STUDY_PAIRWISE) {
        if (!blocks) blocks = set->reference >= 0 ? 7u : 1u;
        if ((blocks & 2u) && set->reference < 0)
            return mr_fail(err, MR_ERR_INVALID, "block II shows the reference, but %s has no %s/ folder", dir,
                           MR_STUDY_REFERENCE);
    } else {
        if (!blocks) blocks = 3u;
        if (blocks & 4u) return mr_fail(err, MR_ERR_INVALID, "the %s design has blocks I and II only", mr_study_design_names[d]);
    }
    if (p.fixation_ms < 0) return mr_fail(err, MR_ERR_INVALID, "fixation-ms must be >= 0");
    if (p.overall && d == MR_STUDY_RATING && (set->method_count < 2 || set->method_count > MR_STUDY_OVERALL_MAX))
        return mr_fail(err, MR_ERR_INVALID, "the overall question shows 2..%d methods side by side, not %d",
                       MR_STUDY_OVERALL_MAX, set->method_count);
    if (p.participants < 0 || p.participants > 999) return mr_fail(err, MR_ERR_INVALID, "participants must be in [0, 999]");
    cats C = {0};
    bool ok = cats_make(set, d == MR_STUDY_PAIRWISE, &C, err);
    int t = set->method_count, nblocks = 0;
    for (int b = 0; b < MR_STUDY_MAX_BLOCKS; b++) nblocks += (blocks >> b) & 1u;
    size_t per = d == MR_STUDY_PAIRWISE ? (size_t)nblocks * C.n * (t * (t - 1) / 2 + 1)
                                        : (size_t)nblocks * set->stimulus_count * (t + (p.overall ? 1 : 0));
    int nsched = p.participants > 0 ? p.participants : 1;
    out->design = d;
    out->blocks = blocks;
    out->overall = p.overall && d == MR_STUDY_RATING;
    out->seed = p.seed;
    out->fixation_ms = p.fixation_ms;
    snprintf(out->dir, sizeof out->dir, "%s", dir);
    out->set.method_count = t;
    memcpy(out->set.methods, set->methods, sizeof set->methods);
    out->set.reference = set->reference;
    out->set.stimulus_count = set->stimulus_count;
    out->set.stimuli = calloc((size_t)set->stimulus_count, MR_STUDY_NAME_MAX);
    out->schedules = calloc((size_t)nsched, sizeof *out->schedules);
    out->schedule_count = nsched;
    if (ok && (!out->set.stimuli || !out->schedules)) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    if (ok) memcpy(out->set.stimuli, set->stimuli, (size_t)set->stimulus_count * MR_STUDY_NAME_MAX);
    if (ok && d == MR_STUDY_RATING) ok = parse_scales(p.scales, out, err);
    if (ok && d == MR_STUDY_TASK) ok = load_keys(dir, out, err);
    mr_rng rng;
    mr_rng_seed(&rng, (uint64_t)p.seed);
    /* Balanced groups: A and B alternate over a shuffled list. */
    int *order = ok ? calloc((size_t)nsched, sizeof(int)) : NULL;
    if (ok && !order) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int i = 0; ok && i < nsched; i++) order[i] = i;
    for (int i = nsched - 1; ok && i > 0; i--) {
        int j = (int)rng_below(&rng, (uint64_t)(i + 1)), x = order[i];
        order[i] = order[j], order[j] = x;
    }
    int width = nsched >= 100 ? 3 : 2;
    for (int q = 0; ok && q < nsched; q++) {
        mr_study_schedule *sc = &out->schedules[q];
        if (p.participants > 0) {
            snprintf(sc->id, sizeof sc->id, "P%0*d", width, q + 1);
            if (d == MR_STUDY_PAIRWISE && (blocks & 4u)) sc->group = order[q] % 2 ? MR_STUDY_GROUP_B : MR_STUDY_GROUP_A;
        }
        sc->trials = calloc(per ? per : 1, sizeof *sc->trials);
        if (!sc->trials) {
            ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
            break;
        }
        int rot = d == MR_STUDY_TASK && p.participants > 0 ? q % t : -1;
        sc->trial_count = d == MR_STUDY_PAIRWISE ? pairwise_schedule(set, &C, blocks, &rng, sc->trials)
                                                 : single_schedule(set, &C, blocks, rot, out->overall, &rng, sc->trials);
        if (sc->trial_count < 0) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    free(order);
    cats_free(&C);
    if (ok) {
        out->selected = 0;
        out->trials = out->schedules[0].trials;
        out->trial_count = out->schedules[0].trial_count;
        out->group = out->schedules[0].group;
        if (!plan_hash(out, out->id)) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    if (!ok) mr_study_plan_free(out);
    return ok;
}

bool mr_study_plan_scan_make(const char *dir, const mr_study_plan_params *pp, mr_study_plan *out, mr_error *err) {
    mr_study_plan_params p = pp ? *pp : (mr_study_plan_params)MR_STUDY_PLAN_DEFAULTS;
    mr_study_set set;
    if (p.design == MR_STUDY_PAIRWISE) {
        if (!mr_study_scan(dir, &set, err)) return false;
    } else {
        /* The condition folders present (or those asked for), alike. */
        unsigned have = 0;
        bool got = false;
        for (int b = 1; b <= 2; b++) {
            if (p.blocks && !(p.blocks & (1u << (b - 1)))) continue;
            char sub[4200];
            mr_path_join(dir, mr_study_condition_name((mr_study_design)p.design, b), sub, sizeof sub);
            if (!is_dir(sub)) {
                if (p.blocks) return mr_fail(err, MR_ERR_IO, "no condition folder %s", sub);
                continue;
            }
            mr_study_set s2;
            if (!mr_study_scan(sub, got ? &s2 : &set, err)) {
                if (got) mr_study_set_free(&set);
                return false;
            }
            if (got) {
                bool same = s2.method_count == set.method_count && s2.stimulus_count == set.stimulus_count &&
                            !memcmp(s2.methods, set.methods, sizeof s2.methods) &&
                            !memcmp(s2.stimuli, set.stimuli, (size_t)s2.stimulus_count * MR_STUDY_NAME_MAX);
                mr_study_set_free(&s2);
                if (!same) {
                    mr_study_set_free(&set);
                    return mr_fail(err, MR_ERR_INVALID, "%s: the condition folders must hold the same methods and stimuli", dir);
                }
            }
            got = true;
            have |= 1u << (b - 1);
        }
        if (!got)
            return mr_fail(err, MR_ERR_IO, "%s: no condition folder (%s/ or %s/)", dir,
                           mr_study_condition_name((mr_study_design)p.design, 1),
                           mr_study_condition_name((mr_study_design)p.design, 2));
        p.blocks = have;
    }
    bool ok = mr_study_plan_make(dir, &set, &p, out, err);
    mr_study_set_free(&set);
    return ok;
}

void mr_study_plan_free(mr_study_plan *plan) {
    if (!plan) return;
    for (int q = 0; plan->schedules && q < plan->schedule_count; q++) free(plan->schedules[q].trials);
    free(plan->schedules);
    free(plan->keys);
    mr_study_set_free(&plan->set);
    memset(plan, 0, sizeof *plan);
    plan->set.reference = -1;
}

bool mr_study_plan_select(mr_study_plan *plan, const char *participant, mr_error *err) {
    int q = -1;
    if (plan->schedule_count == 1 && !plan->schedules[0].id[0]) q = 0;
    for (int i = 0; q < 0 && participant && i < plan->schedule_count; i++)
        if (!strcmp(plan->schedules[i].id, participant)) q = i;
    if (q < 0)
        return mr_fail(err, MR_ERR_INVALID, "plan %s has no participant '%s' (its ids: %s .. %s)", plan->id,
                       participant ? participant : "", plan->schedules[0].id,
                       plan->schedules[plan->schedule_count - 1].id);
    plan->selected = q;
    plan->trials = plan->schedules[q].trials;
    plan->trial_count = plan->schedules[q].trial_count;
    plan->group = plan->schedules[q].group;
    return true;
}

void mr_study_plan_image(const mr_study_plan *plan, int block, int stimulus, int method, char *out, size_t n) {
    char rel[4 * MR_STUDY_NAME_MAX];
    if (plan->design == MR_STUDY_PAIRWISE)
        snprintf(rel, sizeof rel, "%s/%s.png", plan->set.methods[method], plan->set.stimuli[stimulus]);
    else
        snprintf(rel, sizeof rel, "%s/%s/%s.png", mr_study_condition_name(plan->design, block),
                 plan->set.methods[method], plan->set.stimuli[stimulus]);
    mr_path_join(plan->dir, rel, out, n);
}

int mr_study_plan_image_count(const mr_study_plan *plan) {
    return (plan->design == MR_STUDY_PAIRWISE ? 1 : MR_STUDY_MAX_BLOCKS) * plan->set.method_count *
           plan->set.stimulus_count;
}

int mr_study_plan_image_index(const mr_study_plan *plan, int block, int method, int stimulus) {
    int b = plan->design == MR_STUDY_PAIRWISE ? 0 : block - 1;
    return (b * plan->set.method_count + method) * plan->set.stimulus_count + stimulus;
}

const mr_study_key *mr_study_plan_key(const mr_study_plan *plan, int block, int stimulus) {
    if (plan->design != MR_STUDY_TASK || !plan->keys || block < 1 || block > 2) return NULL;
    return &plan->keys[(block - 1) * plan->set.stimulus_count + stimulus];
}

static const char *const k_format = "mrcheck-study-plan";

bool mr_study_plan_save(const char *path, const mr_study_plan *plan, mr_error *err) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "format", k_format);
    cJSON_AddNumberToObject(j, "version", plan->design == MR_STUDY_PAIRWISE && plan->schedule_count == 1 &&
                                                  !plan->schedules[0].id[0] ? 1 : 2);
    cJSON_AddStringToObject(j, "id", plan->id);
    cJSON_AddStringToObject(j, "dir", plan->dir);
    cJSON *c = content_json(plan);
    for (cJSON *it = c ? c->child : NULL; it;) {
        cJSON *next = it->next;
        cJSON_AddItemToObject(j, it->string, cJSON_DetachItemViaPointer(c, it));
        it = next;
    }
    cJSON_Delete(c);
    bool ok = mr_json_save(path, j, err);
    cJSON_Delete(j);
    return ok;
}

static int name_index(const char (*names)[MR_STUDY_NAME_MAX], int n, const char *s) {
    for (int i = 0; s && i < n; i++)
        if (strcmp(names[i], s) == 0) return i;
    return -1;
}

static const char *str_item(const cJSON *o, const char *key) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static bool load_trials(const cJSON *trials, const char *path, mr_study_plan *plan, mr_study_schedule *sc,
                        mr_error *err) {
    int nt = cJSON_IsArray(trials) ? cJSON_GetArraySize(trials) : 0;
    if (nt < 1) return mr_fail(err, MR_ERR_INVALID, "%s: a schedule without trials", path);
    sc->trials = calloc((size_t)nt, sizeof *sc->trials);
    if (!sc->trials) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int t = plan->set.method_count, ns = plan->set.stimulus_count, i = 0;
    for (const cJSON *x = trials->child; x; x = x->next, i++) {
        const char *bn = str_item(x, "block");
        mr_study_trial *tr = &sc->trials[i];
        tr->block = bn ? block_parse(bn) : 0;
        tr->stimulus = name_index((const char(*)[MR_STUDY_NAME_MAX])plan->set.stimuli, ns, str_item(x, "stimulus"));
        tr->left = name_index((const char(*)[MR_STUDY_NAME_MAX])plan->set.methods, t, str_item(x, "left"));
        tr->right = name_index((const char(*)[MR_STUDY_NAME_MAX])plan->set.methods, t, str_item(x, "right"));
        const char *l = str_item(x, "left"), *r = str_item(x, "right");
        if (plan->overall && l && r && !strcmp(l, "*")) {
            char *end = NULL;
            long rot = strtol(r, &end, 10);
            tr->left = -1;
            tr->right = end && !*end && end != r && rot >= 0 && rot < t ? (int)rot : -1;
            if (tr->right < 0) return mr_fail(err, MR_ERR_INVALID, "%s: trial %d: bad rotation", path, i);
            tr->left = 0; /* checked like the others below, then marked */
        }
        bool all = plan->overall && l && !strcmp(l, "*");
        if (!tr->block || !(plan->blocks & (1u << (tr->block - 1))) || tr->stimulus < 0 || tr->left < 0 || tr->right < 0)
            return mr_fail(err, MR_ERR_INVALID, "%s: trial %d names an unknown block, stimulus or method", path, i);
        if (all) tr->left = -1;
    }
    sc->trial_count = nt;
    return true;
}

static bool load_json(const cJSON *j, const char *path, mr_study_plan *plan, mr_error *err) {
    const char *fmt = str_item(j, "format"), *id = str_item(j, "id"), *dir = str_item(j, "dir");
    if (!fmt || strcmp(fmt, k_format) != 0) return mr_fail(err, MR_ERR_PARSE, "%s: not a study plan (format)", path);
    if (!id || strlen(id) != 16 || !dir) return mr_fail(err, MR_ERR_PARSE, "%s: plan without id or dir", path);
    const char *design = str_item(j, "design");
    plan->design = MR_STUDY_PAIRWISE;
    if (design) {
        int d = -1;
        for (int k = 0; mr_study_design_names[k]; k++)
            if (!strcmp(design, mr_study_design_names[k])) d = k;
        if (d < 0) return mr_fail(err, MR_ERR_INVALID, "%s: unknown design '%s'", path, design);
        plan->design = (mr_study_design)d;
    }
    const cJSON *methods = cJSON_GetObjectItemCaseSensitive(j, "methods");
    const cJSON *stimuli = cJSON_GetObjectItemCaseSensitive(j, "stimuli");
    const cJSON *trials = cJSON_GetObjectItemCaseSensitive(j, "trials");
    const cJSON *people = cJSON_GetObjectItemCaseSensitive(j, "participants");
    const cJSON *blocks = cJSON_GetObjectItemCaseSensitive(j, "blocks");
    double seed = 0, fix = 0;
    if (!cJSON_IsArray(methods) || !cJSON_IsArray(stimuli) || !(cJSON_IsArray(trials) || cJSON_IsArray(people)) ||
        !cJSON_IsArray(blocks) || !mr_json_number(j, "seed", &seed, true, err) ||
        !mr_json_number(j, "fixation_ms", &fix, true, err))
        return mr_fail(err, MR_ERR_PARSE, "%s: plan needs methods, stimuli, blocks, trials, seed, fixation_ms", path);
    int t = cJSON_GetArraySize(methods), ns = cJSON_GetArraySize(stimuli);
    int nsched = cJSON_IsArray(people) ? cJSON_GetArraySize(people) : 1;
    if (t < 1 || t > MR_STUDY_MAX_METHODS || ns < 1 || nsched < 1 || (plan->design == MR_STUDY_PAIRWISE && t < 2))
        return mr_fail(err, MR_ERR_INVALID, "%s: plan needs 2..%d methods, a stimulus and a schedule", path,
                       MR_STUDY_MAX_METHODS);
    plan->set.method_count = t;
    plan->set.reference = -1;
    int i = 0;
    for (const cJSON *m = methods->child; m; m = m->next, i++) {
        if (!cJSON_IsString(m) || !good_name(m->valuestring)) return mr_fail(err, MR_ERR_INVALID, "%s: bad method name", path);
        snprintf(plan->set.methods[i], MR_STUDY_NAME_MAX, "%s", m->valuestring);
        if (strcmp(m->valuestring, MR_STUDY_REFERENCE) == 0) plan->set.reference = i;
    }
    plan->set.stimuli = calloc((size_t)ns, MR_STUDY_NAME_MAX);
    plan->schedules = calloc((size_t)nsched, sizeof *plan->schedules);
    if (!plan->set.stimuli || !plan->schedules) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    plan->schedule_count = nsched;
    plan->set.stimulus_count = ns;
    i = 0;
    for (const cJSON *s = stimuli->child; s; s = s->next, i++) {
        if (!cJSON_IsString(s) || !good_name(s->valuestring)) return mr_fail(err, MR_ERR_INVALID, "%s: bad stimulus name", path);
        snprintf(plan->set.stimuli[i], MR_STUDY_NAME_MAX, "%s", s->valuestring);
    }
    for (const cJSON *b = blocks->child; b; b = b->next) {
        int k = cJSON_IsString(b) ? block_parse(b->valuestring) : 0;
        if (!k) return mr_fail(err, MR_ERR_INVALID, "%s: bad block name", path);
        plan->blocks |= 1u << (k - 1);
    }
    if (plan->design == MR_STUDY_RATING) {
        plan->overall = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, "overall"));
        const cJSON *sc = cJSON_GetObjectItemCaseSensitive(j, "scales");
        int n = cJSON_IsArray(sc) ? cJSON_GetArraySize(sc) : 0;
        if (n < 1 || n > MR_STUDY_MAX_SCALES) return mr_fail(err, MR_ERR_INVALID, "%s: a rating plan needs 1..%d scales", path, MR_STUDY_MAX_SCALES);
        for (const cJSON *x = sc->child; x; x = x->next) {
            if (!cJSON_IsString(x) || !good_name(x->valuestring)) return mr_fail(err, MR_ERR_INVALID, "%s: bad scale name", path);
            snprintf(plan->scales[plan->scale_count++], MR_STUDY_NAME_MAX, "%s", x->valuestring);
        }
    }
    if (plan->design == MR_STUDY_TASK) {
        const cJSON *keys = cJSON_GetObjectItemCaseSensitive(j, "keys");
        plan->keys = calloc((size_t)2 * ns, sizeof *plan->keys);
        if (!plan->keys) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        for (int b = 1; b <= 2; b++) {
            if (!(plan->blocks & (1u << (b - 1)))) continue;
            const cJSON *kb = cJSON_GetObjectItemCaseSensitive(keys, mr_study_block_name(b));
            if (!cJSON_IsObject(kb)) return mr_fail(err, MR_ERR_INVALID, "%s: a task plan needs keys of block %s", path, mr_study_block_name(b));
            if (!keys_from(kb, path, plan, b, err)) return false;
        }
    }
    if (cJSON_IsArray(people)) {
        int q = 0;
        for (const cJSON *o = people->child; o; o = o->next, q++) {
            mr_study_schedule *sc = &plan->schedules[q];
            const char *pid = str_item(o, "id"), *grp = str_item(o, "group");
            if (!pid || !good_name(pid)) return mr_fail(err, MR_ERR_INVALID, "%s: a participant without a good id", path);
            snprintf(sc->id, sizeof sc->id, "%s", pid);
            sc->group = !grp ? MR_STUDY_GROUP_NONE : !strcmp(grp, "A") ? MR_STUDY_GROUP_A : !strcmp(grp, "B") ? MR_STUDY_GROUP_B : -1;
            if ((int)sc->group < 0) return mr_fail(err, MR_ERR_INVALID, "%s: group is A or B", path);
            if (!load_trials(cJSON_GetObjectItemCaseSensitive(o, "trials"), path, plan, sc, err)) return false;
        }
    } else if (!load_trials(trials, path, plan, &plan->schedules[0], err)) {
        return false;
    }
    plan->trials = plan->schedules[0].trials;
    plan->trial_count = plan->schedules[0].trial_count;
    plan->group = plan->schedules[0].group;
    plan->seed = (int)seed;
    plan->fixation_ms = (int)fix;
    snprintf(plan->id, sizeof plan->id, "%s", id);
    char dirpath[4096];
    if (mr_file_exists(dir) || dir[0] == '/') snprintf(plan->dir, sizeof plan->dir, "%s", dir);
    else {
        mr_path_dir(path, dirpath, sizeof dirpath);
        mr_path_join(dirpath, dir, plan->dir, sizeof plan->dir);
    }
    char check[17];
    if (!plan_hash(plan, check)) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    if (strcmp(check, plan->id) != 0)
        return mr_fail(err, MR_ERR_INVALID, "%s: the plan was edited (its content does not match its id %s)", path, plan->id);
    return true;
}

bool mr_study_plan_load(const char *path, mr_study_plan *plan, mr_error *err) {
    memset(plan, 0, sizeof *plan);
    cJSON *j = mr_json_load(path, err);
    if (!j) return false;
    bool ok = load_json(j, path, plan, err);
    cJSON_Delete(j);
    if (!ok) mr_study_plan_free(plan);
    return ok;
}

void mr_study_plan_describe(const mr_study_plan *plan, const char *path, FILE *f) {
    fprintf(f, "study plan %s (%s): %d trials per participant, %d schedule%s (%d methods%s, %d stimuli, blocks", plan->id,
            mr_study_design_names[plan->design], plan->trial_count, plan->schedule_count,
            plan->schedule_count > 1 ? "s" : "", plan->set.method_count,
            plan->set.reference >= 0 ? " with the reference" : "", plan->set.stimulus_count);
    for (int b = 1; b <= MR_STUDY_MAX_BLOCKS; b++)
        if (plan->blocks & (1u << (b - 1))) fprintf(f, " %s", mr_study_condition_name(plan->design, b));
    fprintf(f, ") -> %s\n", path);
}
