/* The stimulus images of a plan, loaded before `mrcheck study run` opens
 * its window (a missing or odd-sized image is an error before anything is
 * shown). */
#include "mr_study.h"

#include <stdlib.h>

bool mr_study_images_load(const mr_study_plan *plan, mr_image **out, mr_error *err) {
    int t = plan->set.method_count, S = plan->set.stimulus_count, n = mr_study_plan_image_count(plan);
    mr_image *im = calloc((size_t)n, sizeof *im);
    *out = NULL;
    if (!im) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    bool ok = true;
    const mr_image *first = NULL;
    int nb = plan->design == MR_STUDY_PAIRWISE ? 1 : MR_STUDY_MAX_BLOCKS;
    for (int b = 1; ok && b <= nb; b++) {
        if (nb > 1 && !(plan->blocks & (1u << (b - 1)))) continue;
        for (int m = 0; ok && m < t; m++)
            for (int s = 0; ok && s < S; s++) {
                char path[8192];
                mr_study_plan_image(plan, b, s, m, path, sizeof path);
                mr_image *x = &im[mr_study_plan_image_index(plan, b, m, s)];
                ok = mr_image_load(path, 3, x, err);
                if (ok && !first) first = x;
                if (ok && (x->width != first->width || x->height != first->height))
                    ok = mr_fail(err, MR_ERR_INVALID, "%s: all stimuli must have one size (%dx%d)", path, first->width,
                                 first->height);
            }
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
    int n = mr_study_plan_image_count(plan);
    for (int i = 0; i < n; i++) mr_image_free(&(*images)[i]);
    free(*images);
    *images = NULL;
}
