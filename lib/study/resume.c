/* Where `mrcheck study run` picks up a participant's run: the votes file
 * read (tolerant), the trials they answered, the first one left, and
 * whether the file ends in a torn line that must be sealed first. */
#include "mr_study.h"

#include <stdlib.h>
#include <string.h>

bool mr_study_resume_open(const mr_study_plan *plan, const char *votes_path, const char *participant,
                          mr_study_resume_point *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_study_votes votes = {0};
    if (!mr_study_votes_read(votes_path, true, &votes, err)) return false;
    out->torn_tail = votes.torn_tail;
    out->answered = calloc((size_t)plan->trial_count, sizeof *out->answered);
    bool ok = out->answered != NULL || mr_fail(err, MR_ERR_NOMEM, "out of memory");
    if (ok) ok = (out->first = mr_study_resume(plan, &votes, participant, out->answered, err)) >= 0;
    mr_study_votes_free(&votes);
    if (!ok) {
        mr_study_resume_point_free(out);
        return false;
    }
    for (int k = 0; k < plan->trial_count; k++) out->answered_count += out->answered[k];
    return true;
}

void mr_study_resume_point_free(mr_study_resume_point *p) {
    free(p->answered);
    memset(p, 0, sizeof *p);
}
