/* Fuzz target: the study plan loader (lib/study/plan.c). A file that loads
 * has 2..16 methods, trials whose block, stimulus and methods are in range,
 * a 16-digit id that matches its content; saved and loaded again it is the
 * same plan. Anything else is one error line. */
#include "fuzz_file.h"
#include "mr_study.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_log_set_level(MR_LOG_ERROR);
    char path[600], again[600];
    if (!fuzz_put("plan.json", data, size, path, sizeof path)) __builtin_trap();
    mr_study_plan p;
    mr_error err = {0};
    if (!mr_study_plan_load(path, &p, &err)) {
        if (!err.msg[0] || strchr(err.msg, '\n')) __builtin_trap();
        return 0;
    }
    int t = p.set.method_count;
    if (t < 2 || t > MR_STUDY_MAX_METHODS || strlen(p.id) != 16 || p.trial_count < 1) __builtin_trap();
    for (int i = 0; i < p.trial_count; i++) {
        const mr_study_trial *x = &p.trials[i];
        if (x->block < 1 || x->block > 3 || !(p.blocks & (1u << (x->block - 1))) || x->stimulus < 0 ||
            x->stimulus >= p.set.stimulus_count || x->left < 0 || x->left >= t || x->right < 0 || x->right >= t)
            __builtin_trap();
    }
    snprintf(again, sizeof again, "%s/again.json", fuzz_dir());
    mr_study_plan q;
    if (!mr_study_plan_save(again, &p, &err) || !mr_study_plan_load(again, &q, &err)) __builtin_trap();
    if (strcmp(p.id, q.id) != 0 || p.trial_count != q.trial_count ||
        memcmp(p.trials, q.trials, (size_t)p.trial_count * sizeof *p.trials) != 0)
        __builtin_trap();
    mr_study_plan_free(&q);
    mr_study_plan_free(&p);
    return 0;
}
