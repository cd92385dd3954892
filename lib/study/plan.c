/* The stimulus folder, the study plan (thesis sec. 4.3: all pairs plus one
 * identical pair per stimulus, random order and sides, three blocks) and
 * its JSON file. */
#include "mr_study.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

const mr_opt mr_study_plan_opts[] = {
    {"seed", MR_OPT_INT, offsetof(mr_study_plan_params, seed), 0, 2147483647, 1, NULL,
     "random seed of the order and sides: the same seed gives the same plan", 0},
    {"fixation-ms", MR_OPT_INT, offsetof(mr_study_plan_params, fixation_ms), 0, 60000, 2000, NULL,
     "fixation cross before each trial, milliseconds", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

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

/* What a plan says, in file order; its id hashes exactly this (not the
 * folder, so a moved stimulus folder keeps the plan's id). */
static cJSON *content_json(const mr_study_plan *p) {
    cJSON *j = cJSON_CreateObject();
    cJSON *m = cJSON_AddArrayToObject(j, "methods");
    for (int i = 0; i < p->set.method_count; i++) cJSON_AddItemToArray(m, cJSON_CreateString(p->set.methods[i]));
    cJSON *s = cJSON_AddArrayToObject(j, "stimuli");
    for (int i = 0; i < p->set.stimulus_count; i++) cJSON_AddItemToArray(s, cJSON_CreateString(p->set.stimuli[i]));
    cJSON_AddNumberToObject(j, "seed", p->seed);
    cJSON_AddNumberToObject(j, "fixation_ms", p->fixation_ms);
    cJSON *b = cJSON_AddArrayToObject(j, "blocks");
    for (int i = 1; i <= MR_STUDY_MAX_BLOCKS; i++)
        if (p->blocks & (1u << (i - 1))) cJSON_AddItemToArray(b, cJSON_CreateString(mr_study_block_name(i)));
    cJSON *t = cJSON_AddArrayToObject(j, "trials");
    for (int i = 0; i < p->trial_count; i++) {
        const mr_study_trial *x = &p->trials[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "trial", i);
        cJSON_AddStringToObject(o, "block", mr_study_block_name(x->block));
        cJSON_AddStringToObject(o, "stimulus", p->set.stimuli[x->stimulus]);
        cJSON_AddStringToObject(o, "left", p->set.methods[x->left]);
        cJSON_AddStringToObject(o, "right", p->set.methods[x->right]);
        cJSON_AddItemToArray(t, o);
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

bool mr_study_plan_make(const char *dir, const mr_study_set *set, const mr_study_plan_params *pp, mr_study_plan *out,
                        mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_study_plan_params p = pp ? *pp : (mr_study_plan_params)MR_STUDY_PLAN_DEFAULTS;
    unsigned blocks = p.blocks ? p.blocks : set->reference >= 0 ? 7u : 1u;
    if ((blocks & 2u) && set->reference < 0)
        return mr_fail(err, MR_ERR_INVALID, "block II shows the reference, but %s has no %s/ folder", dir,
                       MR_STUDY_REFERENCE);
    if (p.fixation_ms < 0) return mr_fail(err, MR_ERR_INVALID, "fixation-ms must be >= 0");
    int t = set->method_count, per_stim = t * (t - 1) / 2 + 1;
    int nblocks = 0;
    for (int b = 0; b < MR_STUDY_MAX_BLOCKS; b++) nblocks += (blocks >> b) & 1u;
    size_t n = (size_t)nblocks * (size_t)set->stimulus_count * (size_t)per_stim;
    out->trials = calloc(n ? n : 1, sizeof *out->trials);
    out->set.stimuli = calloc((size_t)set->stimulus_count, MR_STUDY_NAME_MAX);
    if (!out->trials || !out->set.stimuli) {
        mr_study_plan_free(out);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    out->set.method_count = t;
    memcpy(out->set.methods, set->methods, sizeof set->methods);
    out->set.reference = set->reference;
    out->set.stimulus_count = set->stimulus_count;
    memcpy(out->set.stimuli, set->stimuli, (size_t)set->stimulus_count * MR_STUDY_NAME_MAX);
    snprintf(out->dir, sizeof out->dir, "%s", dir);
    out->seed = p.seed;
    out->fixation_ms = p.fixation_ms;
    out->blocks = blocks;
    mr_rng rng;
    mr_rng_seed(&rng, (uint64_t)p.seed);
    int k = 0;
    for (int b = 1; b <= MR_STUDY_MAX_BLOCKS; b++) {
        if (!(blocks & (1u << (b - 1)))) continue;
        int first = k;
        for (int s = 0; s < set->stimulus_count; s++) {
            for (int i = 0; i < t; i++)
                for (int j = i + 1; j < t; j++) {
                    bool swap = rng_below(&rng, 2);
                    out->trials[k++] = (mr_study_trial){b, s, swap ? j : i, swap ? i : j};
                }
            int m = (int)rng_below(&rng, (uint64_t)t);
            out->trials[k++] = (mr_study_trial){b, s, m, m};
        }
        for (int i = k - 1; i > first; i--) {
            int j = first + (int)rng_below(&rng, (uint64_t)(i - first + 1));
            mr_study_trial x = out->trials[i];
            out->trials[i] = out->trials[j];
            out->trials[j] = x;
        }
    }
    out->trial_count = k;
    if (!plan_hash(out, out->id)) {
        mr_study_plan_free(out);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    return true;
}

void mr_study_plan_free(mr_study_plan *plan) {
    if (!plan) return;
    free(plan->trials);
    mr_study_set_free(&plan->set);
    memset(plan, 0, sizeof *plan);
    plan->set.reference = -1;
}

void mr_study_plan_image(const mr_study_plan *plan, int stimulus, int method, char *out, size_t n) {
    char rel[3 * MR_STUDY_NAME_MAX];
    snprintf(rel, sizeof rel, "%s/%s.png", plan->set.methods[method], plan->set.stimuli[stimulus]);
    mr_path_join(plan->dir, rel, out, n);
}

static const char *const k_format = "mrcheck-study-plan";

bool mr_study_plan_save(const char *path, const mr_study_plan *plan, mr_error *err) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "format", k_format);
    cJSON_AddNumberToObject(j, "version", 1);
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

static bool load_json(const cJSON *j, const char *path, mr_study_plan *plan, mr_error *err) {
    const char *fmt = str_item(j, "format"), *id = str_item(j, "id"), *dir = str_item(j, "dir");
    if (!fmt || strcmp(fmt, k_format) != 0) return mr_fail(err, MR_ERR_PARSE, "%s: not a study plan (format)", path);
    if (!id || strlen(id) != 16 || !dir) return mr_fail(err, MR_ERR_PARSE, "%s: plan without id or dir", path);
    const cJSON *methods = cJSON_GetObjectItemCaseSensitive(j, "methods");
    const cJSON *stimuli = cJSON_GetObjectItemCaseSensitive(j, "stimuli");
    const cJSON *trials = cJSON_GetObjectItemCaseSensitive(j, "trials");
    const cJSON *blocks = cJSON_GetObjectItemCaseSensitive(j, "blocks");
    double seed = 0, fix = 0;
    if (!cJSON_IsArray(methods) || !cJSON_IsArray(stimuli) || !cJSON_IsArray(trials) || !cJSON_IsArray(blocks) ||
        !mr_json_number(j, "seed", &seed, true, err) || !mr_json_number(j, "fixation_ms", &fix, true, err))
        return mr_fail(err, MR_ERR_PARSE, "%s: plan needs methods, stimuli, blocks, trials, seed, fixation_ms", path);
    int t = cJSON_GetArraySize(methods), ns = cJSON_GetArraySize(stimuli), nt = cJSON_GetArraySize(trials);
    if (t < 2 || t > MR_STUDY_MAX_METHODS || ns < 1 || nt < 1)
        return mr_fail(err, MR_ERR_INVALID, "%s: plan needs 2..%d methods, a stimulus and a trial", path,
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
    plan->trials = calloc((size_t)nt, sizeof *plan->trials);
    if (!plan->set.stimuli || !plan->trials) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
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
    i = 0;
    for (const cJSON *x = trials->child; x; x = x->next, i++) {
        const char *bn = str_item(x, "block");
        mr_study_trial *tr = &plan->trials[i];
        tr->block = bn ? block_parse(bn) : 0;
        tr->stimulus = name_index((const char(*)[MR_STUDY_NAME_MAX])plan->set.stimuli, ns, str_item(x, "stimulus"));
        tr->left = name_index((const char(*)[MR_STUDY_NAME_MAX])plan->set.methods, t, str_item(x, "left"));
        tr->right = name_index((const char(*)[MR_STUDY_NAME_MAX])plan->set.methods, t, str_item(x, "right"));
        if (!tr->block || !(plan->blocks & (1u << (tr->block - 1))) || tr->stimulus < 0 || tr->left < 0 || tr->right < 0)
            return mr_fail(err, MR_ERR_INVALID, "%s: trial %d names an unknown block, stimulus or method", path, i);
    }
    plan->trial_count = nt;
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
