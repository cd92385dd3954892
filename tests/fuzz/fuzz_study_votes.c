/* Fuzz target: the study's vote log reader (lib/study/votes.c), tolerant of
 * torn and foreign lines: whatever the file holds, every vote read back has
 * a block in 1..3, an answer in {left, neutral, right}, a finite slider and
 * time, names that are NUL-terminated and non-empty; votes + bad lines +
 * repeats never exceed the lines; resume against a small plan either
 * answers a trial index in range or fails with one line. */
#include "fuzz_file.h"
#include "mr_study.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static bool name_ok(const char *s, size_t n) { return s[0] && memchr(s, 0, n) != NULL; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_log_set_level(MR_LOG_ERROR);
    char path[600];
    if (!fuzz_put("votes.jsonl", data, size, path, sizeof path)) __builtin_trap();
    mr_study_votes v = {0};
    mr_error err = {0};
    if (!mr_study_votes_read(path, false, &v, &err)) return 0;
    size_t lines = 1;
    for (size_t i = 0; i < size; i++) lines += data[i] == '\n';
    if ((size_t)v.count + (size_t)v.bad_lines + (size_t)v.duplicates > lines) __builtin_trap();
    for (int i = 0; i < v.count; i++) {
        const mr_study_vote *x = &v.v[i];
        if (x->block < 1 || x->block > 3 || x->answer < -1 || x->answer > 1 || x->trial < 0) __builtin_trap();
        if (!isfinite(x->slider) || !isfinite(x->ms) || !isfinite(x->time_unix)) __builtin_trap();
        if (!name_ok(x->plan, sizeof x->plan) || !name_ok(x->participant, sizeof x->participant) ||
            !name_ok(x->stimulus, sizeof x->stimulus) || !name_ok(x->left, sizeof x->left) ||
            !name_ok(x->right, sizeof x->right))
            __builtin_trap();
    }
    /* A plan of two methods and one stimulus, block I: 2 trials. */
    static mr_study_plan plan;
    static bool have;
    if (!have) {
        mr_study_set set = {0};
        set.method_count = 2;
        snprintf(set.methods[0], MR_STUDY_NAME_MAX, "a");
        snprintf(set.methods[1], MR_STUDY_NAME_MAX, "b");
        set.reference = -1;
        static char stim[1][MR_STUDY_NAME_MAX] = {"s"};
        set.stimuli = stim;
        set.stimulus_count = 1;
        mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
        have = mr_study_plan_make("dir", &set, &pp, &plan, &err);
    }
    bool answered[2];
    int k = have ? mr_study_resume(&plan, &v, v.count ? v.v[0].participant : "p", answered, &err) : 0;
    if (k < -1 || k > 2 || (k == -1 && (!err.msg[0] || strchr(err.msg, '\n')))) __builtin_trap();
    mr_study_votes_free(&v);
    return 0;
}
