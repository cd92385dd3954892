/* `mrcheck study stimuli`: one image per method and stimulus (a view of
 * the demo hall, for shadows also a view of a shadow-suite case), rendered
 * through mr_render_frame. The families are rows of one table: methods,
 * setup, how the reference is made and which scenes are the stimuli. */
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

static const char *const k_shadow_methods[] = {"bp", "hard", "pcf", "pcss", NULL};
static const mr_shadow_method k_shadow_enum[] = {MR_SHADOW_BP, MR_SHADOW_HARD, MR_SHADOW_PCF, MR_SHADOW_PCSS};
static void shadow_setup(mr_frame_params *fp, int m) { fp->shadow.method = k_shadow_enum[m]; }

const char *const mr_study_shadow_cases[MR_STUDY_SHADOW_CASES] = {"simple_varying_overlap", "furniture_varying",
                                                                  "fence_constant", "plant_varying"};

static bool ao_reference(mr_renderer *r, const mr_scene *scene, const mr_view *view, const mr_frame_params *base,
                         const mr_study_stimuli_params *p, mr_frame_result *res, mr_error *err);

/* The reference of the shadows family: the renderer's ground truth, the
 * average of gt_samples hard shadow maps from points on the light (as
 * `render --shadows groundtruth`), with every other setting the methods'. */
static bool shadow_reference(mr_renderer *r, const mr_scene *scene, const mr_view *view, const mr_frame_params *base,
                             const mr_study_stimuli_params *p, mr_frame_result *res, mr_error *err) {
    (void)scene;
    mr_frame_params fp = *base;
    fp.shadow.method = MR_SHADOW_GROUNDTRUTH;
    fp.shadow.gt_samples = p->gt_samples;
    return mr_render_frame(r, view, &fp, res, err);
}

const mr_study_family mr_study_families[] = {
    {"ao", "screen-space AO methods against ray-traced AO (lib/eval) as the reference", k_ao_methods, true, ao_setup,
     ao_reference, false},
    {"ghost", "ghosted views of the hidden layer (alpha, g0, adaptive); no reference", k_ghost_methods, false,
     ghost_setup, NULL, false},
    {"shadows", "shadow-map soft shadows (hard, pcf, pcss, bp) against the GPU ground truth (many light samples)",
     k_shadow_methods, true, shadow_setup, shadow_reference, true},
};
const int mr_study_family_count = (int)(sizeof mr_study_families / sizeof mr_study_families[0]);
const char *const mr_study_family_names[] = {"ao", "ghost", "shadows", NULL};
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
    {"cases", MR_OPT_INT, offsetof(mr_study_stimuli_params, cases), 0, MR_STUDY_SHADOW_CASES, MR_STUDY_SHADOW_CASES,
     NULL, "shadows: also both views of the first N shadow-suite cases", 0},
    {"gt-samples", MR_OPT_INT, offsetof(mr_study_stimuli_params, gt_samples), 1, 1024, MR_SHADOW_DEFAULT_GT_SAMPLES,
     NULL, "reference shadows: light samples (hard shadow maps averaged)", 0},
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
static bool ao_reference(mr_renderer *r, const mr_scene *scene, const mr_view *view, const mr_frame_params *base,
                         const mr_study_stimuli_params *p, mr_frame_result *res, mr_error *err) {
    mr_gt_params gtp = MR_GT_DEFAULTS;
    gtp.rays = p->gt_rays;
    return mr_eval_render_groundtruth_ao(r, scene, view, base, &gtp, res, err);
}

/* One stimulus: every method of the family and its reference. */
static bool render_stimulus(mr_renderer *r, const mr_study_family *fam, const mr_study_stimuli_params *p,
                            const mr_scene *scene, const mr_view *view, const char *dir, const char *stim, int *count,
                            mr_error *err) {
    mr_frame_params base = MR_FRAME_DEFAULTS;
    base.width = p->width;
    base.height = p->height;
    bool ok = true;
    for (int m = 0; ok && fam->methods[m]; m++) {
        mr_frame_params fp = base;
        fam->setup(&fp, m);
        mr_frame_result res = {0};
        ok = mr_render_frame(r, view, &fp, &res, err) && save(dir, fam->methods[m], stim, &res.color, err);
        mr_frame_result_free(&res);
        if (ok && count) (*count)++;
    }
    if (ok && fam->has_reference && fam->reference) {
        mr_frame_result res = {0};
        ok = fam->reference(r, scene, view, &base, p, &res, err) &&
             save(dir, MR_STUDY_REFERENCE, stim, &res.color, err);
        mr_frame_result_free(&res);
        if (ok && count) (*count)++;
    }
    return ok;
}

/* Index of a suite case by name (-1 when the suite has no such case). */
static int suite_index(const char *name) {
    for (int i = 0; i < MR_SHADOW_SUITE_COUNT; i++)
        if (strcmp(mr_shadow_suite_name(i), name) == 0) return i;
    return -1;
}

bool mr_study_stimuli_render(mr_renderer *r, const mr_study_stimuli_params *pp, const char *dir, int *count,
                             mr_error *err) {
    mr_study_stimuli_params p = pp ? *pp : (mr_study_stimuli_params)MR_STUDY_STIMULI_DEFAULTS;
    if (count) *count = 0;
    if (p.family < 0 || p.family >= mr_study_family_count) return mr_fail(err, MR_ERR_INVALID, "unknown stimulus family");
    if (p.views < 1 || p.views > mr_demo_view_count())
        return mr_fail(err, MR_ERR_INVALID, "views must be in [1, %d]", mr_demo_view_count());
    const mr_study_family *fam = &mr_study_families[p.family];
    if (fam->shadow_suite && (p.cases < 0 || p.cases > MR_STUDY_SHADOW_CASES))
        return mr_fail(err, MR_ERR_INVALID, "cases must be in [0, %d]", MR_STUDY_SHADOW_CASES);
    if (fam->shadow_suite && (p.gt_samples < 1 || p.gt_samples > 1024))
        return mr_fail(err, MR_ERR_INVALID, "gt-samples must be in [1, 1024]");
    mr_demo_hall hall;
    mr_demo_params dp = MR_DEMO_DEFAULTS;
    if (!mr_demo_build(&dp, &hall, err)) return false;
    /* The hall as planned has no lights: the shadows family sees it under
     * the renderer's default sun. */
    bool ok = mr_mkdirs(dir, err) && mr_renderer_set_scene(r, hall.planned, err);
    for (int v = 0; ok && v < p.views; v++) {
        mr_view view = mr_demo_view(v);
        char stim[32];
        snprintf(stim, sizeof stim, "hall_v%d", v);
        ok = render_stimulus(r, fam, &p, hall.planned, &view, dir, stim, count, err);
    }
    mr_renderer_set_scene(r, NULL, NULL);
    mr_demo_free(&hall);
    for (int c = 0; ok && fam->shadow_suite && c < p.cases; c++) {
        int ci = suite_index(mr_study_shadow_cases[c]);
        if (ci < 0) return mr_fail(err, MR_ERR_INVALID, "no shadow suite case %s", mr_study_shadow_cases[c]);
        mr_shadow_suite_case sc;
        ok = mr_shadow_suite_build(ci, &sc, err) && mr_renderer_set_scene(r, sc.scene, err);
        for (int v = 0; ok && v < 2; v++) {
            char stim[MR_STUDY_NAME_MAX];
            snprintf(stim, sizeof stim, "%s_v%d", sc.name, v);
            ok = render_stimulus(r, fam, &p, sc.scene, &sc.views[v], dir, stim, count, err);
        }
        mr_renderer_set_scene(r, NULL, NULL);
        mr_shadow_suite_free(&sc);
    }
    return ok;
}
