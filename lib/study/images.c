/* The stimulus images of a plan, loaded before `mrcheck study run` opens
 * its window (a missing or odd-sized image is an error before anything is
 * shown). */
#include "mr_study.h"

#include <stdlib.h>

bool mr_study_images_load(const mr_study_plan *plan, mr_image **out, mr_error *err) {
    int t = plan->set.method_count, S = plan->set.stimulus_count;
    mr_image *im = calloc((size_t)t * S, sizeof *im);
    *out = NULL;
    if (!im) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    bool ok = true;
    for (int m = 0; ok && m < t; m++)
        for (int s = 0; ok && s < S; s++) {
            char path[8192];
            mr_study_plan_image(plan, s, m, path, sizeof path);
            ok = mr_image_load(path, 3, &im[m * S + s], err);
            if (ok && (im[m * S + s].width != im[0].width || im[m * S + s].height != im[0].height))
                ok = mr_fail(err, MR_ERR_INVALID, "%s: all stimuli must have one size (%dx%d)", path, im[0].width,
                             im[0].height);
        }
    if (!ok) {
        mr_study_images_free(plan, &im);
        return false;
    }
    *out = im;
    return true;
}

void mr_study_images_free(const mr_study_plan *plan, mr_image **images) {
    if (!*images) return;
    for (int i = 0; i < plan->set.method_count * plan->set.stimulus_count; i++) mr_image_free(&(*images)[i]);
    free(*images);
    *images = NULL;
}
