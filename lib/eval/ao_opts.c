/* The AO options' checks that involve more than one option, shared by the
 * commands that render (render, replay), and the ground truth's radius,
 * which follows the AO's (its params live here in lib/eval). */
#include "mr_eval.h"

bool mr_eval_ao_opts_check(const mr_cli_table *t, bool *groundtruth, mr_gt_params *gt, mr_error *err) {
    mr_ao_params *ao = t->params;
    bool mode_named = mr_cli_table_given(t, "radius-mode");
    *groundtruth = t->extra_given;
    if (*groundtruth) ao->method = MR_AO_NONE;
    if (mr_cli_table_given(t, "radius")) {
        /* In screen mode the radius is a fraction of the image, not a length:
         * silently ignoring a length would hide a mistake. */
        if (mode_named && ao->radius_mode == MR_AO_RADIUS_SCREEN)
            return mr_fail(err, MR_ERR_INVALID,
                           "--ao-radius is a length for --ao-radius-mode view; screen mode takes --ao-screen-radius");
        /* A radius in scene units asks for the constant one unless the mode is named. */
        if (!mode_named) ao->radius_mode = MR_AO_RADIUS_VIEW;
    }
    if (ao->r_min > ao->r_max) return mr_fail(err, MR_ERR_INVALID, "--ao-rmin must not exceed --ao-rmax");
    /* Only the standalone mask has a strength of its own: silently ignoring
     * it elsewhere would hide a mistake. */
    if (mr_cli_table_given(t, "mask-strength") && ao->mask != MR_AO_MASK_STANDALONE)
        return mr_fail(err, MR_ERR_INVALID, "--ao-mask-strength applies to --ao-mask standalone only");
    gt->radius_mode = ao->radius_mode;
    gt->radius = ao->radius;
    gt->screen_radius = ao->screen_radius;
    /* Ground truth defaults to the fixed radius unless a mode is named. */
    if (*groundtruth && !mode_named) gt->radius_mode = MR_AO_RADIUS_VIEW;
    return true;
}
