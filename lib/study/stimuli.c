/* `mrcheck study stimuli`: one image per method and stimulus (a view of
 * the demo hall), rendered through mr_render_frame. The families are rows
 * of one table, so the soft-shadow methods are one more row (with its
 * methods and setup) when they land. */
#include "mr_eval.h"
#include "mr_scene.h"
#include "mr_study.h"

#include <string.h>

static const char *const k_ao_methods[] = {"alchemy", "crytek", "filion", "hbao", "scheer", NULL};
static const mr_ao_method k_ao_enum[] = {MR_AO_ALCHEMY, MR_AO_CRYTEK, MR_AO_FILION, MR_AO_HBAO, MR_AO_SCHEER};
static void ao_setup(mr_frame_params *fp, int m) { fp->ao.method = k_ao_enum[m]; }

static const char *const k_ghost_methods[] = {"adaptive", "alpha", "g0", NULL};
static const mr_ghost_mode k_ghost_enum[] = {MR_GHOST_ADAPTIVE, MR_GHOST_ALPHA, MR_GHOST_G0};
static void ghost_setup(mr_frame_params *fp, int m) { fp->ghost.mode = k_ghost_enum[m]; }

const mr_study_family mr_study_families[] = {
    {"ao", "screen-space AO methods against ray-traced AO (lib/eval) as the reference", k_ao_methods, true, ao_setup},
    {"ghost", "ghosted views of the hidden layer (alpha, g0, adaptive); no reference", k_ghost_methods, false,
     ghost_setup},
    /* shadows: the soft-shadow methods with the ray-traced area light as the reference */
};
const int mr_study_family_count = (int)(sizeof mr_study_families / sizeof mr_study_families[0]);
const char *const mr_study_family_names[] = {"ao", "ghost", NULL};
_Static_assert(sizeof mr_study_family_names / sizeof mr_study_family_names[0] ==
                   sizeof mr_study_families / sizeof mr_study_families[0] + 1,
               "one name per family row");

const mr_opt mr_study_stimuli_opts[] = {
    {"family", MR_OPT_ENUM, offsetof(mr_study_stimuli_params, family), 0, 0, 0, mr_study_family_names,
     "which methods to render", 0},
    {"width", MR_OPT_INT, offsetof(mr_study_stimuli_params, width), 16, 4096, 320, NULL, "image width, pixels", 0},
    {"height", MR_OPT_INT, offsetof(mr_study_stimuli_params, height), 16, 4096, 240, NULL, "image height, pixels", 0},
    {"views", MR_OPT_INT, offsetof(mr_study_stimuli_params, views), 1, MR_DEMO_VIEWS, 3, NULL,
     "stimuli: the first N standing viewpoints of the demo hall", 0},
    {"gt-rays", MR_OPT_INT, offsetof(mr_study_stimuli_params, gt_rays), 1, 4096, 128, NULL,
     "reference AO: ray-traced rays per pixel", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

static bool save(const char *dir, const char *method, const char *stim, const mr_image *img, mr_error *err) {
    char sub[4200], path[8300];
    mr_path_join(dir, method, sub, sizeof sub);
    if (!mr_mkdirs(sub, err)) return false;
    snprintf(path, sizeof path, "%s/%s.png", sub, stim);
    return mr_image_save_png(path, img, err);
}

/* The reference of the AO family: shading with ray-traced AO of the
 * surface the G-buffer saw (as `render --ao groundtruth`). */
static bool render_reference(mr_renderer *r, const mr_scene *scene, const mr_view *view, const mr_frame_params *base,
                             int rays, mr_frame_result *res, mr_error *err) {
    mr_frame_params gp = *base;
    gp.want_depth = gp.want_normals = true;
    mr_frame_result g = {0};
    mr_image ao = {0};
    mr_eval_gt *gt = NULL;
    mr_gt_params gtp = MR_GT_DEFAULTS;
    gtp.rays = rays;
    bool ok = mr_render_frame(r, view, &gp, &g, err) && (gt = mr_eval_gt_create(scene, base->hide_hidden_layer, err)) &&
              mr_eval_ao_groundtruth(gt, view, &g.depth, &g.normal, &gtp, &ao, err);
    mr_frame_result_free(&g);
    mr_eval_gt_destroy(&gt);
    if (ok) {
        mr_frame_params fp = *base;
        fp.ao.external = &ao;
        ok = mr_render_frame(r, view, &fp, res, err);
    }
    mr_image_free(&ao);
    return ok;
}

bool mr_study_stimuli_render(mr_renderer *r, const mr_study_stimuli_params *pp, const char *dir, int *count,
                             mr_error *err) {
    mr_study_stimuli_params p = pp ? *pp : (mr_study_stimuli_params)MR_STUDY_STIMULI_DEFAULTS;
    if (count) *count = 0;
    if (p.family < 0 || p.family >= mr_study_family_count) return mr_fail(err, MR_ERR_INVALID, "unknown stimulus family");
    if (p.views < 1 || p.views > mr_demo_view_count())
        return mr_fail(err, MR_ERR_INVALID, "views must be in [1, %d]", mr_demo_view_count());
    const mr_study_family *fam = &mr_study_families[p.family];
    mr_demo_hall hall;
    mr_demo_params dp = MR_DEMO_DEFAULTS;
    if (!mr_demo_build(&dp, &hall, err)) return false;
    bool ok = mr_mkdirs(dir, err) && mr_renderer_set_scene(r, hall.planned, err);
    for (int v = 0; ok && v < p.views; v++) {
        mr_view view = mr_demo_view(v);
        char stim[32];
        snprintf(stim, sizeof stim, "hall_v%d", v);
        mr_frame_params base = MR_FRAME_DEFAULTS;
        base.width = p.width;
        base.height = p.height;
        for (int m = 0; ok && fam->methods[m]; m++) {
            mr_frame_params fp = base;
            fam->setup(&fp, m);
            mr_frame_result res = {0};
            ok = mr_render_frame(r, &view, &fp, &res, err) && save(dir, fam->methods[m], stim, &res.color, err);
            mr_frame_result_free(&res);
            if (ok && count) (*count)++;
        }
        if (ok && fam->has_reference) {
            mr_frame_result res = {0};
            ok = render_reference(r, hall.planned, &view, &base, p.gt_rays, &res, err) &&
                 save(dir, MR_STUDY_REFERENCE, stim, &res.color, err);
            mr_frame_result_free(&res);
            if (ok && count) (*count)++;
        }
    }
    mr_renderer_set_scene(r, NULL, NULL);
    mr_demo_free(&hall);
    return ok;
}
