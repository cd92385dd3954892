/* `mrcheck study stimuli`: one image per method and stimulus (a view of
 * the demo hall; for shadows Hecher's categories, two scenes each),
 * rendered through mr_render_frame. The families are rows of one table:
 * methods, setup, how the reference is made, which scenes are the stimuli,
 * the default size, antialiasing and ambient term. */
#include "mr_eval.h"
#include "mr_scene.h"
#include "mr_study.h"
#include "study_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const k_ao_methods[] = {"alchemy", "crytek", "filion", "hbao", "scheer", NULL};
static const mr_ao_method k_ao_enum[] = {MR_AO_ALCHEMY, MR_AO_CRYTEK, MR_AO_FILION, MR_AO_HBAO, MR_AO_SCHEER};
static void ao_setup(mr_frame_params *fp, int m) { fp->ao.method = k_ao_enum[m]; }

/* Scheer & Keutel's D1, D2 and D3, as mr_render defines them
 * (mr_ao_sk_setup). */
static const char *const k_depth_methods[] = {"D1", "D2", "D3", NULL};
static void depth_setup(mr_frame_params *fp, int m) { mr_ao_sk_setup((mr_ao_sk_rendering)m, &fp->ao); }

static const char *const k_ghost_methods[] = {"adaptive", "alpha", "g0", NULL};
static const mr_ghost_mode k_ghost_enum[] = {MR_GHOST_ADAPTIVE, MR_GHOST_ALPHA, MR_GHOST_G0};
static void ghost_setup(mr_frame_params *fp, int m) { fp->ghost.mode = k_ghost_enum[m]; }

/* The thesis's four: PCF, PCSS, backprojection and the ground truth (the
 * reference); hard shadows only when asked (index 3). */
static const char *const k_shadow_methods[] = {"bp", "pcf", "pcss", NULL};
static const mr_shadow_method k_shadow_enum[] = {MR_SHADOW_BP, MR_SHADOW_PCF, MR_SHADOW_PCSS, MR_SHADOW_HARD};
static void shadow_setup(mr_frame_params *fp, int m) { fp->shadow.method = k_shadow_enum[m]; }

const char *const mr_study_shadow_cases[MR_STUDY_SHADOW_CASES] = {
    "simple_constant",    "simple_constant_overlap",    "simple_varying",    "simple_varying_overlap",
    "furniture_constant", "furniture_constant_overlap", "furniture_varying", "furniture_varying_overlap",
    "fence_constant",     "fence_varying",              "plant_constant",    "plant_varying",
    "factory",
};

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
     ao_reference, false, 320, 240, 1, 0.0f, NULL, false, false},
    {"ghost", "ghosted views of the hidden layer (alpha, g0, adaptive); no reference", k_ghost_methods, false,
     ghost_setup, NULL, false, 320, 240, 1, 0.0f, NULL, false, false},
    {"shadows", "Hecher's study: pcf, pcss, bp against the GPU ground truth, 13 categories x 2 scenes, 800x450",
     k_shadow_methods, true, shadow_setup, shadow_reference, true, 800, 450, 2, 0.4f, "hard", false, false},
    {"depth", "Scheer & Keutel's rating study: D1, D2, D3 in virtual/ and in video/ (camera image at alpha 0.5)",
     k_depth_methods, false, depth_setup, NULL, false, 320, 240, 1, 0.0f, NULL, true, false},
    {"xray", "Kalkofen et al.'s task study: hidden boxes and a pipe behind a wall through alpha, g0, adaptive; "
             "conflict/ and no-conflict/ with answers.json",
     k_ghost_methods, false, ghost_setup, NULL, false, 320, 240, 1, 0.0f, NULL, false, true},
};
const int mr_study_family_count = (int)(sizeof mr_study_families / sizeof mr_study_families[0]);
const char *const mr_study_family_names[] = {"ao", "ghost", "shadows", "depth", "xray", NULL};
_Static_assert(sizeof mr_study_family_names / sizeof mr_study_family_names[0] ==
                   sizeof mr_study_families / sizeof mr_study_families[0] + 1,
               "one name per family row");

const mr_opt mr_study_stimuli_opts[] = {
    {"family", MR_OPT_ENUM, offsetof(mr_study_stimuli_params, family), 0, 0, 0, mr_study_family_names,
     "which methods to render", 0},
    {"width", MR_OPT_INT, offsetof(mr_study_stimuli_params, width), 16, 4096, 0, NULL,
     "image width, pixels (0: the family's, shadows 800, else 320)", MR_OPT_ZERO_AUTO},
    {"height", MR_OPT_INT, offsetof(mr_study_stimuli_params, height), 16, 4096, 0, NULL,
     "image height, pixels (0: the family's, shadows 450, else 240)", MR_OPT_ZERO_AUTO},
    {"views", MR_OPT_INT, offsetof(mr_study_stimuli_params, views), 1, MR_DEMO_VIEWS, 3, NULL,
     "stimuli: the first N standing viewpoints of the demo hall", 0},
    {"gt-rays", MR_OPT_INT, offsetof(mr_study_stimuli_params, gt_rays), 1, 4096, 128, NULL,
     "reference AO: ray-traced rays per pixel", 0},
    {"cases", MR_OPT_INT, offsetof(mr_study_stimuli_params, cases), 1, MR_STUDY_SHADOW_CASES, MR_STUDY_SHADOW_CASES,
     NULL, "shadows: the first N of the 13 categories (two scenes each)", 0},
    {"gt-samples", MR_OPT_INT, offsetof(mr_study_stimuli_params, gt_samples), 1, 1024, MR_SHADOW_DEFAULT_GT_SAMPLES,
     NULL, "reference shadows: light samples (hard shadow maps averaged)", 0},
    {"supersample", MR_OPT_INT, offsetof(mr_study_stimuli_params, supersample), 1, 4, 0, NULL,
     "antialiasing: render N times the size and average N x N pixels (0: the family's, shadows 2)", MR_OPT_ZERO_AUTO},
    {"ambient", MR_OPT_FLOAT, offsetof(mr_study_stimuli_params, ambient), 0.01, 1, 0, NULL,
     "the scenes' ambient term (0: the family's, shadows the thesis's 0.4)", MR_OPT_ZERO_AUTO},
    {"targets", MR_OPT_INT, offsetof(mr_study_stimuli_params, targets), 1, 64, 6, NULL,
     "xray: targets (questions) per scene; the scenes are `views`", 0},
    {"hard", MR_OPT_BOOL, offsetof(mr_study_stimuli_params, hard), 0, 1, 0, NULL,
     "shadows: also hard shadows (not one of the thesis's methods)", 0},
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

/* The average of each ss x ss block of src (RGB8) into dst. */
static bool downsample(const mr_image *src, int ss, mr_image *dst, mr_error *err) {
    if (!mr_image_alloc(dst, src->width / ss, src->height / ss, 3, MR_PIX_U8, err)) return false;
    const uint8_t *in = src->data;
    uint8_t *out = dst->data;
    for (int y = 0; y < dst->height; y++)
        for (int x = 0; x < dst->width; x++)
            for (int c = 0; c < 3; c++) {
                int sum = 0;
                for (int j = 0; j < ss; j++)
                    for (int i = 0; i < ss; i++) sum += in[((size_t)(y * ss + j) * src->width + (x * ss + i)) * 3 + c];
                out[((size_t)y * dst->width + x) * 3 + c] = (uint8_t)((sum + ss * ss / 2) / (ss * ss));
            }
    return true;
}

/* img (ss times the size) as the stimulus: averaged down, or copied. */
static bool final_image(const mr_image *img, int ss, mr_image *out, mr_error *err) {
    if (ss > 1) return downsample(img, ss, out, err);
    if (!mr_image_alloc(out, img->width, img->height, 3, MR_PIX_U8, err)) return false;
    memcpy(out->data, img->data, mr_image_bytes(out));
    return true;
}

bool mr_study_save_frame(const char *dir, const char *method, const char *stim, const mr_image *img, int ss,
                         mr_error *err) {
    if (ss <= 1) return save(dir, method, stim, img, err);
    mr_image small = {0};
    bool ok = downsample(img, ss, &small, err) && save(dir, method, stim, &small, err);
    mr_image_free(&small);
    return ok;
}

/* The thesis's check that a category's two scenes are alike (Fig. 4.5):
 * per method the mean absolute difference to the reference (RGB, in
 * [0, 1]) over the whole image and over the pixels the shadows touch --
 * where the image without shadows differs from the reference. */
static void difference_rows(mr_csv *csv, const char *stim, const mr_image *shots, const char *const *names, int n,
                            const mr_image *ref, const mr_image *unlit) {
    size_t px = (size_t)ref->width * ref->height;
    const uint8_t *R = ref->data, *U = unlit->data;
    size_t shadow = 0;
    for (size_t i = 0; i < px; i++)
        shadow += R[i * 3] != U[i * 3] || R[i * 3 + 1] != U[i * 3 + 1] || R[i * 3 + 2] != U[i * 3 + 2];
    char cat[MR_STUDY_NAME_MAX];
    mr_study_category_of(stim, cat, sizeof cat);
    for (int m = 0; m < n; m++) {
        const uint8_t *A = shots[m].data;
        double whole = 0, inside = 0;
        for (size_t i = 0; i < px; i++) {
            double d = (abs(A[i * 3] - R[i * 3]) + abs(A[i * 3 + 1] - R[i * 3 + 1]) + abs(A[i * 3 + 2] - R[i * 3 + 2])) /
                       (3 * 255.0);
            whole += d;
            if (R[i * 3] != U[i * 3] || R[i * 3 + 1] != U[i * 3 + 1] || R[i * 3 + 2] != U[i * 3 + 2]) inside += d;
        }
        mr_csv_text(csv, cat);
        mr_csv_text(csv, stim);
        mr_csv_text(csv, names[m]);
        mr_csv_num(csv, "%.6f", whole / (double)px);
        mr_csv_num(csv, "%.6f", shadow ? inside / (double)shadow : NAN);
        mr_csv_num(csv, "%.6f", (double)shadow / (double)px);
        mr_csv_end_row(csv);
    }
}

/* One stimulus: every method of the family (the optional one when asked)
 * and its reference, at ss times the size, averaged down; with diff, the
 * shadows family's differences to the reference (one more render, without
 * shadows). */
static bool render_stimulus(mr_renderer *r, const mr_study_family *fam, const mr_study_stimuli_params *p, int ss,
                            const mr_scene *scene, const mr_view *view, const mr_image *video, const char *dir,
                            const char *stim, int *count, mr_csv *diff, mr_error *err) {
    mr_frame_params base = MR_FRAME_DEFAULTS;
    base.width = p->width * ss;
    base.height = p->height * ss;
    base.video = video;
    base.alpha = 0.5f; /* Scheer & Keutel's 50 % overlay */
    int n = 0;
    while (fam->methods[n]) n++;
    int total = n + (fam->optional && p->hard);
    mr_image shots[MR_STUDY_MAX_METHODS + 2];
    const char *names[MR_STUDY_MAX_METHODS + 2];
    memset(shots, 0, sizeof shots);
    bool ok = true;
    for (int m = 0; ok && m < total; m++) {
        mr_frame_params fp = base;
        fam->setup(&fp, m);
        mr_frame_result res = {0};
        names[m] = m < n ? fam->methods[m] : fam->optional;
        ok = mr_render_frame(r, view, &fp, &res, err) && final_image(&res.color, ss, &shots[m], err) &&
             save(dir, names[m], stim, &shots[m], err);
        mr_frame_result_free(&res);
        if (ok && count) (*count)++;
    }
    mr_image ref = {0}, unlit = {0};
    if (ok && fam->has_reference && fam->reference) {
        mr_frame_result res = {0};
        ok = fam->reference(r, scene, view, &base, p, &res, err) && final_image(&res.color, ss, &ref, err) &&
             save(dir, MR_STUDY_REFERENCE, stim, &ref, err);
        mr_frame_result_free(&res);
        if (ok && count) (*count)++;
        if (ok && diff) {
            mr_frame_params fp = base;
            fp.shadow.method = MR_SHADOW_OFF;
            mr_frame_result off = {0};
            ok = mr_render_frame(r, view, &fp, &off, err) && final_image(&off.color, ss, &unlit, err);
            mr_frame_result_free(&off);
            if (ok) difference_rows(diff, stim, shots, names, total, &ref, &unlit);
        }
    }
    for (int m = 0; m < total; m++) mr_image_free(&shots[m]);
    mr_image_free(&ref);
    mr_image_free(&unlit);
    return ok;
}

/* Scene b of a category: the objects (the floor too, a square) turned 90
 * degrees about the vertical through the origin, the light kept. */
static void turn_scene(mr_scene *s) {
    mr_dmat4 r = mr_m4_rotate_axis(mr_v3(0, 1, 0), 1.5707963267948966);
    for (int i = 0; i < s->node_count; i++) s->nodes[i].world = mr_m4_mul(&r, &s->nodes[i].world);
    mr_scene_update_bounds(s);
}

/* The rating family's two conditions: DIR/virtual/<method>/hall_vN.png and
 * DIR/video/<method>/hall_vN.png, the latter over a camera image at alpha
 * 0.5. The camera image is the hall as built drawn plainly from the same
 * viewpoint (the repository has no photographs of a factory; any real
 * frame can take its place through `render --video`). */
static bool conditions_render(mr_renderer *r, const mr_study_family *fam, const mr_study_stimuli_params *p, int ss,
                              mr_demo_hall *hall, const char *dir, int *count, mr_error *err) {
    bool ok = true;
    for (int v = 0; ok && v < p->views; v++) {
        mr_view view = mr_demo_view(v);
        char stim[32], sub[4200];
        snprintf(stim, sizeof stim, "hall_v%d", v);
        /* The camera image: the as-built hall, plain shading. */
        mr_frame_params vp = MR_FRAME_DEFAULTS;
        vp.width = p->width * ss;
        vp.height = p->height * ss;
        mr_frame_result cam = {0};
        ok = mr_renderer_set_scene(r, hall->built, err) && mr_render_frame(r, &view, &vp, &cam, err);
        ok = ok && mr_renderer_set_scene(r, hall->planned, err);
        mr_path_join(dir, "virtual", sub, sizeof sub);
        ok = ok && render_stimulus(r, fam, p, ss, hall->planned, &view, NULL, sub, stim, count, NULL, err);
        mr_path_join(dir, "video", sub, sizeof sub);
        ok = ok && render_stimulus(r, fam, p, ss, hall->planned, &view, &cam.color, sub, stim, count, NULL, err);
        mr_frame_result_free(&cam);
        mr_renderer_set_scene(r, NULL, NULL);
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
    const mr_study_family *fam = &mr_study_families[p.family];
    if (!p.width) p.width = fam->width;
    if (!p.height) p.height = fam->height;
    int ss = p.supersample > 0 ? p.supersample : fam->supersample;
    float ambient = p.ambient > 0 ? p.ambient : fam->ambient;
    if (p.width < 16 || p.height < 16 || p.width > 4096 || p.height > 4096 || ss < 1 || ss > 4)
        return mr_fail(err, MR_ERR_INVALID, "size must be 16..4096 and supersample 1..4");
    if (!fam->shadow_suite && (p.views < 1 || p.views > mr_demo_view_count()))
        return mr_fail(err, MR_ERR_INVALID, "views must be in [1, %d]", mr_demo_view_count());
    if (fam->shadow_suite && (p.cases < 1 || p.cases > MR_STUDY_SHADOW_CASES))
        return mr_fail(err, MR_ERR_INVALID, "cases must be in [1, %d]", MR_STUDY_SHADOW_CASES);
    if (fam->shadow_suite && (p.gt_samples < 1 || p.gt_samples > 1024))
        return mr_fail(err, MR_ERR_INVALID, "gt-samples must be in [1, 1024]");
    if (fam->task && (p.targets < 1 || p.targets > 64)) return mr_fail(err, MR_ERR_INVALID, "targets must be in [1, 64]");
    if (!mr_mkdirs(dir, err)) return false;
    if (fam->task) return mr_study_task_stimuli_render(r, fam, &p, ss, dir, count, err);
    bool ok = true;
    if (!fam->shadow_suite) {
        mr_demo_hall hall;
        mr_demo_params dp = MR_DEMO_DEFAULTS;
        if (!mr_demo_build(&dp, &hall, err)) return false;
        if (ambient > 0) hall.planned->ambient = ambient;
        if (fam->conditions) {
            ok = conditions_render(r, fam, &p, ss, &hall, dir, count, err);
            mr_demo_free(&hall);
            return ok;
        }
        ok = mr_renderer_set_scene(r, hall.planned, err);
        for (int v = 0; ok && v < p.views; v++) {
            mr_view view = mr_demo_view(v);
            char stim[32];
            snprintf(stim, sizeof stim, "hall_v%d", v);
            ok = render_stimulus(r, fam, &p, ss, hall.planned, &view, NULL, dir, stim, count, NULL, err);
        }
        mr_renderer_set_scene(r, NULL, NULL);
        mr_demo_free(&hall);
        return ok;
    }
    mr_csv *diff = mr_csv_create(err);
    if (!diff) return false;
    mr_csv_comment(diff, "per stimulus and method: mean |method - reference| (RGB / 255) over the whole image and over the "
                         "pixels the shadows touch (where the image without shadows differs from the reference); "
                         "the thesis's Fig. 4.5 check that a category's two scenes are alike");
    mr_csv_header(diff, "category,stimulus,method,diff_whole,diff_shadow,shadow_fraction");
    for (int c = 0; ok && c < p.cases; c++) {
        int ci = suite_index(mr_study_shadow_cases[c]);
        mr_shadow_suite_case sc;
        if (ci < 0) ok = mr_fail(err, MR_ERR_INVALID, "no shadow suite case %s", mr_study_shadow_cases[c]);
        if (!ok || !mr_shadow_suite_build(ci, &sc, err)) {
            ok = false;
            break;
        }
        for (int scene = 0; ok && scene < 2; scene++) {
            mr_scene *s = sc.scene;
            mr_demo_hall hall = {0};
            if (scene == 1 && !strcmp(sc.name, "factory")) {
                /* The factory's second scene: the hall as built, lit alike. */
                mr_demo_params dp = MR_DEMO_DEFAULTS;
                ok = mr_demo_build(&dp, &hall, err);
                if (!ok) break;
                s = hall.built;
                s->light_count = sc.scene->light_count;
                memcpy(s->lights, sc.scene->lights, sizeof s->lights);
            } else if (scene == 1) {
                turn_scene(s);
            }
            s->ambient = ambient > 0 ? ambient : s->ambient;
            char stim[MR_STUDY_NAME_MAX];
            snprintf(stim, sizeof stim, "%s.%c", sc.name, 'a' + scene);
            /* The suite's views are 320 x 240: the same field of view at the
             * stimulus's size, the aspect kept by the wider side. */
            mr_view view = sc.views[0];
            double k = fmax((double)p.width / view.camera.width, (double)p.height / view.camera.height);
            view.camera.fx *= k, view.camera.fy *= k;
            view.camera.width = p.width * ss, view.camera.height = p.height * ss;
            view.camera.fx *= ss, view.camera.fy *= ss;
            view.camera.cx = 0.5 * view.camera.width - 0.5, view.camera.cy = 0.5 * view.camera.height - 0.5;
            ok = mr_renderer_set_scene(r, s, err) && render_stimulus(r, fam, &p, ss, s, &view, NULL, dir, stim, count, diff, err);
            mr_renderer_set_scene(r, NULL, NULL);
            if (hall.planned || hall.built) mr_demo_free(&hall);
        }
        mr_shadow_suite_free(&sc);
    }
    char path[4200];
    mr_path_join(dir, "differences.csv", path, sizeof path);
    ok = ok && mr_csv_save(diff, path, err);
    mr_csv_destroy(&diff);
    return ok;
}
