/* The vote log: one JSON line per vote, appended durably; a tolerant
 * reader; where a participant's run resumes. */
#include "mr_study.h"
#include "mr_session.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *answer_name(mr_study_answer a) {
    return a == MR_STUDY_LEFT ? "left" : a == MR_STUDY_RIGHT ? "right" : "neutral";
}

bool mr_study_vote_append(const char *path, const mr_study_vote *v, mr_error *err) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "plan", v->plan);
    cJSON_AddStringToObject(j, "participant", v->participant);
    if (v->design != MR_STUDY_PAIRWISE) cJSON_AddStringToObject(j, "design", mr_study_design_names[v->design]);
    cJSON_AddStringToObject(j, "block", mr_study_block_name(v->block));
    cJSON_AddNumberToObject(j, "trial", v->trial);
    cJSON_AddStringToObject(j, "stimulus", v->stimulus);
    cJSON_AddStringToObject(j, "left", v->left);
    cJSON_AddStringToObject(j, "right", v->right);
    if (v->design == MR_STUDY_PAIRWISE) {
        if (v->group) cJSON_AddStringToObject(j, "group", mr_study_group_name(v->group));
        cJSON_AddStringToObject(j, "question", mr_study_question_of(v->block, v->group));
        cJSON_AddStringToObject(j, "answer", answer_name(v->answer));
        cJSON_AddNumberToObject(j, "slider", v->slider);
    } else if (v->design == MR_STUDY_RATING && v->choice >= 0) {
        cJSON_AddNumberToObject(j, "choice", v->choice); /* the overall question: the method's index */
    } else if (v->design == MR_STUDY_RATING) {
        cJSON *r = cJSON_AddArrayToObject(j, "ratings");
        for (int k = 0; k < v->rating_count; k++)
            cJSON_AddItemToArray(r, v->ratings[k] == MR_STUDY_RATING_X ? cJSON_CreateString("X")
                                                                       : cJSON_CreateNumber(v->ratings[k]));
    } else {
        if (v->choice >= 0) cJSON_AddNumberToObject(j, "choice", v->choice);
        if (v->has_tap) {
            cJSON *t = cJSON_AddArrayToObject(j, "tap");
            cJSON_AddItemToArray(t, cJSON_CreateNumber(v->tap_x));
            cJSON_AddItemToArray(t, cJSON_CreateNumber(v->tap_y));
        }
    }
    cJSON_AddNumberToObject(j, "ms", v->ms);
    cJSON_AddNumberToObject(j, "time_unix", v->time_unix);
    bool ok = j && mr_annotation_append(path, j, err);
    cJSON_Delete(j);
    return ok;
}

static bool get_name(const cJSON *o, const char *key, char *out, size_t n) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!cJSON_IsString(v) || !v->valuestring[0] || strlen(v->valuestring) >= n) return false;
    snprintf(out, n, "%s", v->valuestring);
    return true;
}

static bool parse_vote(const cJSON *o, mr_study_vote *v) {
    memset(v, 0, sizeof *v);
    v->choice = -1;
    char block[8], answer[16], design[16] = "pairwise", group[4] = "";
    const cJSON *trial = cJSON_GetObjectItemCaseSensitive(o, "trial");
    if (!cJSON_IsObject(o) || !get_name(o, "plan", v->plan, sizeof v->plan) ||
        !get_name(o, "participant", v->participant, sizeof v->participant) || !get_name(o, "block", block, sizeof block) ||
        !get_name(o, "stimulus", v->stimulus, sizeof v->stimulus) || !get_name(o, "left", v->left, sizeof v->left) ||
        !get_name(o, "right", v->right, sizeof v->right) || !cJSON_IsNumber(trial) || trial->valuedouble < 0 ||
        trial->valuedouble > 1e9)
        return false;
    if (cJSON_GetObjectItemCaseSensitive(o, "design") && !get_name(o, "design", design, sizeof design)) return false;
    int d = -1;
    for (int k = 0; mr_study_design_names[k]; k++)
        if (!strcmp(design, mr_study_design_names[k])) d = k;
    if (d < 0) return false;
    v->design = (mr_study_design)d;
    v->trial = (int)trial->valuedouble;
    v->block = 0;
    for (int b = 1; b <= MR_STUDY_MAX_BLOCKS; b++)
        if (strcmp(block, mr_study_block_name(b)) == 0) v->block = b;
    if (!v->block) return false;
    if (v->design == MR_STUDY_PAIRWISE) {
        if (!get_name(o, "answer", answer, sizeof answer)) return false;
        if (!strcmp(answer, "left")) v->answer = MR_STUDY_LEFT;
        else if (!strcmp(answer, "right")) v->answer = MR_STUDY_RIGHT;
        else if (!strcmp(answer, "neutral")) v->answer = MR_STUDY_NEUTRAL;
        else return false;
        if (cJSON_GetObjectItemCaseSensitive(o, "group")) {
            if (!get_name(o, "group", group, sizeof group)) return false;
            v->group = !strcmp(group, "A") ? MR_STUDY_GROUP_A : !strcmp(group, "B") ? MR_STUDY_GROUP_B : -1;
            if ((int)v->group < 0) return false;
        }
    } else if (v->design == MR_STUDY_RATING && cJSON_GetObjectItemCaseSensitive(o, "choice")) {
        const cJSON *c = cJSON_GetObjectItemCaseSensitive(o, "choice");
        if (!cJSON_IsNumber(c) || c->valuedouble < 0 || c->valuedouble >= MR_STUDY_MAX_METHODS ||
            c->valuedouble != (int)c->valuedouble)
            return false;
        v->choice = (int)c->valuedouble;
    } else if (v->design == MR_STUDY_RATING) {
        const cJSON *r = cJSON_GetObjectItemCaseSensitive(o, "ratings");
        int n = cJSON_IsArray(r) ? cJSON_GetArraySize(r) : 0;
        if (n < 1 || n > MR_STUDY_MAX_SCALES) return false;
        for (const cJSON *x = r->child; x; x = x->next) {
            int val;
            if (cJSON_IsString(x) && !strcmp(x->valuestring, "X")) val = MR_STUDY_RATING_X;
            else if (cJSON_IsNumber(x) && x->valuedouble >= 1 && x->valuedouble <= 7 && x->valuedouble == (int)x->valuedouble)
                val = (int)x->valuedouble;
            else return false;
            v->ratings[v->rating_count++] = val;
        }
    } else {
        const cJSON *c = cJSON_GetObjectItemCaseSensitive(o, "choice"), *t = cJSON_GetObjectItemCaseSensitive(o, "tap");
        if (c) {
            if (!cJSON_IsNumber(c) || (c->valuedouble != 0 && c->valuedouble != 1)) return false;
            v->choice = (int)c->valuedouble;
        }
        if (t) {
            if (!cJSON_IsArray(t) || cJSON_GetArraySize(t) != 2 || !cJSON_IsNumber(t->child) ||
                !cJSON_IsNumber(t->child->next) || !isfinite(t->child->valuedouble) || !isfinite(t->child->next->valuedouble))
                return false;
            v->has_tap = true;
            v->tap_x = t->child->valuedouble;
            v->tap_y = t->child->next->valuedouble;
        }
        if (v->choice < 0 && !v->has_tap) return false;
    }
    /* Optional numbers; present ones must be finite (1e999 parses as inf). */
    const char *keys[3] = {"slider", "ms", "time_unix"};
    double *dst[3] = {&v->slider, &v->ms, &v->time_unix};
    for (int k = 0; k < 3; k++) {
        const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, keys[k]);
        if (!x) continue;
        if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble)) return false;
        *dst[k] = x->valuedouble;
    }
    return v->slider >= -1 && v->slider <= 1;
}

static bool push(mr_study_votes *out, const mr_study_vote *v) {
    if (out->count == out->cap) {
        int cap = out->cap ? out->cap * 2 : 256;
        void *p = realloc(out->v, (size_t)cap * sizeof *out->v);
        if (!p) return false;
        out->v = p;
        out->cap = cap;
    }
    out->v[out->count++] = *v;
    return true;
}

/* The same answer twice: plan, participant and trial all equal. */
static bool seen(const mr_study_votes *out, const mr_study_vote *v) {
    for (int i = out->count - 1; i >= 0; i--) {
        const mr_study_vote *w = &out->v[i];
        if (w->trial == v->trial && !strcmp(w->plan, v->plan) && !strcmp(w->participant, v->participant)) return true;
    }
    return false;
}

bool mr_study_votes_read(const char *path, bool missing_ok, mr_study_votes *out, mr_error *err) {
    if (missing_ok && !mr_file_exists(path)) return true;
    size_t size = 0;
    char *text = mr_file_read(path, &size, 0, err);
    if (!text) return false;
    out->torn_tail = size > 0 && text[size - 1] != '\n';
    int line_no = 0;
    bool ok = true;
    for (char *line = text; ok && line && *line;) {
        char *nl = strchr(line, '\n');
        if (nl) *nl = 0;
        line_no++;
        bool last = !nl;
        if (line[0]) {
            cJSON *j = cJSON_Parse(line);
            mr_study_vote v;
            if (!j || !parse_vote(j, &v)) {
                out->bad_lines++;
                mr_log(MR_LOG_WARN, "%s:%d: %s, skipped", path, line_no,
                       last ? "torn last line (the run was killed while writing?)" : "not a vote line");
            } else if (seen(out, &v)) {
                out->duplicates++;
                mr_log(MR_LOG_WARN, "%s:%d: participant %s answered trial %d of plan %s again; the first answer is kept",
                       path, line_no, v.participant, v.trial, v.plan);
            } else if (!push(out, &v)) {
                ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
            }
            cJSON_Delete(j);
        }
        line = nl ? nl + 1 : NULL;
    }
    free(text);
    return ok;
}

void mr_study_votes_free(mr_study_votes *v) {
    if (!v) return;
    free(v->v);
    memset(v, 0, sizeof *v);
}

bool mr_study_votes_seal(const char *path, mr_error *err) {
    int fd = open(path, O_RDWR | O_CLOEXEC);
    if (fd < 0) return errno == ENOENT ? true : mr_fail(err, MR_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    struct stat st;
    char last = '\n';
    bool ok = fstat(fd, &st) == 0;
    if (ok && st.st_size > 0) ok = pread(fd, &last, 1, st.st_size - 1) == 1;
    if (ok && last != '\n') {
        /* Appended, never rewritten: the torn line stays as it was and
         * readers skip it; the next vote starts a line of its own. */
        close(fd);
        fd = open(path, O_WRONLY | O_APPEND | O_CLOEXEC);
        ok = fd >= 0 && write(fd, "\n", 1) == 1 && (fsync(fd) == 0 || errno == EINVAL);
        if (ok) mr_log(MR_LOG_WARN, "%s: its last line was torn; ended it so the next vote starts a new line", path);
    }
    int e = errno;
    if (fd >= 0) close(fd);
    return ok || mr_fail(err, MR_ERR_IO, "cannot seal %s: %s", path, strerror(e));
}

int mr_study_resume(const mr_study_plan *plan, const mr_study_votes *votes, const char *participant, bool *answered,
                    mr_error *err) {
    for (int k = 0; k < plan->trial_count; k++) answered[k] = false;
    for (int i = 0; i < votes->count; i++) {
        const mr_study_vote *v = &votes->v[i];
        if (strcmp(v->participant, participant) != 0) continue;
        if (strcmp(v->plan, plan->id) != 0) {
            mr_fail(err, MR_ERR_INVALID,
                    "participant %s already has votes for another plan (%s, this one is %s) in this log; "
                    "use another --out or --participant",
                    participant, v->plan, plan->id);
            return -1;
        }
        const mr_study_trial *t = v->trial < plan->trial_count ? &plan->trials[v->trial] : NULL;
        char rot[16] = "";
        if (t && t->left < 0) snprintf(rot, sizeof rot, "%d", t->right);
        if (!t || v->design != plan->design || t->block != v->block || strcmp(plan->set.stimuli[t->stimulus], v->stimulus) != 0 ||
            strcmp(t->left < 0 ? "*" : plan->set.methods[t->left], v->left) != 0 ||
            strcmp(t->left < 0 ? rot : plan->set.methods[t->right], v->right) != 0 ||
            (t->left < 0) != (v->choice >= 0 && v->design == MR_STUDY_RATING)) {
            mr_fail(err, MR_ERR_INVALID, "the log's vote for trial %d of participant %s does not match the plan", v->trial,
                    participant);
            return -1;
        }
        answered[v->trial] = true;
    }
    for (int k = 0; k < plan->trial_count; k++)
        if (!answered[k]) return k;
    return plan->trial_count;
}
