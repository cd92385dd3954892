/* The ambient-occlusion options shared by the commands that render
 * (render now; replay and view take the same table). */
#include "app.h"

#include <string.h>

bool app_ao_parse(const char *cmd, const app_opt *opts, mr_ao_params *ao, bool *groundtruth, mr_gt_params *gt) {
    const char *m = app_get(opts, "ao");
    *groundtruth = false;
    if (m && strcmp(m, "groundtruth") == 0) {
        *groundtruth = true;
        ao->method = MR_AO_NONE;
    } else if (m && !mr_ao_method_parse(m, &ao->method)) {
        app_errorf(cmd, "--ao %s: unknown method (none, scheer, crytek, filion, hbao, alchemy, groundtruth)", m);
        return false;
    }
    const char *v;
    double d;
    long l;
    if ((v = app_get(opts, "ao-radius-mode"))) {
        if (strcmp(v, "screen") == 0) ao->radius_mode = MR_AO_RADIUS_SCREEN;
        else if (strcmp(v, "view") == 0) ao->radius_mode = MR_AO_RADIUS_VIEW;
        else return app_errorf(cmd, "--ao-radius-mode %s: expected screen or view", v), false;
    }
    if ((v = app_get(opts, "ao-radius"))) {
        /* In screen mode the radius is a fraction of the image, not a length:
         * silently ignoring a length would hide a mistake. */
        if (ao->radius_mode == MR_AO_RADIUS_SCREEN && app_get(opts, "ao-radius-mode"))
            return app_errorf(cmd, "--ao-radius is a length for --ao-radius-mode view; screen mode takes --ao-screen-radius"),
                   false;
        if (!app_double("ao-radius", v, 1e-30, 1e30, &d)) return false;
        ao->radius = d;
        /* A radius in scene units asks for the constant one unless the mode is named. */
        if (!app_get(opts, "ao-radius-mode")) ao->radius_mode = MR_AO_RADIUS_VIEW;
    }
    if ((v = app_get(opts, "ao-screen-radius"))) {
        if (!app_double("ao-screen-radius", v, 1e-6, 10, &d)) return false;
        ao->screen_radius = d;
    }
    if ((v = app_get(opts, "ao-samples"))) {
        if (!app_int("ao-samples", v, 1, MR_AO_MAX_SAMPLES, &l)) return false;
        ao->samples = (int)l;
    }
    if ((v = app_get(opts, "ao-kernel")) && !mr_ao_kernel_parse(v, &ao->kernel))
        return app_errorf(cmd, "--ao-kernel %s: expected uniform, stratified, latin or poisson", v), false;
    if ((v = app_get(opts, "ao-rmin"))) {
        if (!app_double("ao-rmin", v, 0, 1, &d)) return false;
        ao->r_min = (float)d;
    }
    if ((v = app_get(opts, "ao-rmax"))) {
        if (!app_double("ao-rmax", v, 1e-3, 1, &d)) return false;
        ao->r_max = (float)d;
    }
    if (ao->r_min > ao->r_max) return app_errorf(cmd, "--ao-rmin must not exceed --ao-rmax"), false;
    if ((v = app_get(opts, "ao-radii"))) {
        if (!app_int("ao-radii", v, 1, MR_AO_MAX_RADII, &l)) return false;
        ao->radii = (int)l;
    }
    if ((v = app_get(opts, "ao-c"))) {
        if (!app_double("ao-c", v, 0, 1e7, &d)) return false;
        ao->c = (float)d;
    }
    if ((v = app_get(opts, "ao-bias"))) {
        if (!app_double("ao-bias", v, 0, 0.5, &d)) return false;
        ao->bias = (float)d;
    }
    if ((v = app_get(opts, "ao-strength"))) {
        if (!app_double("ao-strength", v, 0.01, 10, &d)) return false;
        ao->strength = (float)d;
    }
    if ((v = app_get(opts, "ao-blur"))) {
        if (!app_int("ao-blur", v, 0, 32, &l)) return false;
        ao->blur_radius = (int)l;
    }
    ao->half_res = app_flag(opts, "ao-half");
    ao->positions = app_flag(opts, "ao-positions");
    if ((v = app_get(opts, "ao-mask"))) {
        if (strcmp(v, "off") == 0) ao->mask = MR_AO_MASK_OFF;
        else if (strcmp(v, "on") == 0) ao->mask = MR_AO_MASK_ON;
        else if (strcmp(v, "standalone") == 0) ao->mask = MR_AO_MASK_STANDALONE;
        else return app_errorf(cmd, "--ao-mask %s: expected off, on or standalone", v), false;
    }
    if ((v = app_get(opts, "ao-mask-strength"))) {
        /* Only the standalone mask has a strength of its own: silently
         * ignoring it elsewhere would hide a mistake. */
        if (ao->mask != MR_AO_MASK_STANDALONE)
            return app_errorf(cmd, "--ao-mask-strength applies to --ao-mask standalone only"), false;
        if (!app_double("ao-mask-strength", v, 1e-3, 1, &d)) return false;
        ao->mask_strength = (float)d;
    }
    gt->radius_mode = ao->radius_mode;
    gt->radius = ao->radius;
    gt->screen_radius = ao->screen_radius;
    if ((v = app_get(opts, "ao-rays"))) {
        if (!app_int("ao-rays", v, 1, 1 << 20, &l)) return false;
        gt->rays = (int)l;
    }
    /* Ground truth defaults to the fixed radius unless a mode is named. */
    if (*groundtruth && !app_get(opts, "ao-radius-mode")) gt->radius_mode = MR_AO_RADIUS_VIEW;
    return true;
}
