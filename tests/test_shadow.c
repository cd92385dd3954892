/* Soft shadows (issue 12) against known answers:
 *  - a square light of side 1 at height 4 over a square occluder of side 1
 *    at height 1 over a floor: V(x, z) = 1 - bx(x) bz(z), the blocked
 *    fraction per axis being the overlap of [-0.5, 0.5] with
 *    [-2 - 3x, 2 - 3x] (so V(x, 0) = 3|x| - 1.5 on [0.5, 0.8333], 0
 *    inside, 1 outside; V(2/3, 2/3) = 0.75); the GPU ground truth and
 *    Embree's within 0.02 of it and of each other, PCSS within 0.1 over the
 *    penumbra with a penumbra width of 1/3, backprojection within 0.05;
 *  - contact hardening: a pole's shadow under a sun of 8 degrees widens with
 *    the distance from its base for PCSS, BP and the ground truth, not for
 *    PCF;
 *  - no acne under a grazing sun (10 degrees), no light gap at a box's base;
 *  - scale 1e-3 and 1e4 and an offset of 1e7 give the same visibility;
 *  - bad light sizes, a zero direction and a receiver glob that matches
 *    nothing fail the scene config with one line.
 * Skips (77) without an EGL device (after the CPU checks). */
#include "mr_bench.h"
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"

#include <math.h>
#include <stdio.h>

#define W 160
#define H 120

typedef struct world {
    double scale;
    mr_dvec3 offset;
} world;

static mr_dvec3 wpt(const world *w, double x, double y, double z) {
    return mr_v3(w->offset.x + w->scale * x, w->offset.y + w->scale * y, w->offset.z + w->scale * z);
}

static void add_box(mr_scene *s, const world *w, const char *name, double sx, double sy, double sz, double x, double y,
                    double z, int32_t mat) {
    mr_dvec3 p = wpt(w, x, y, z);
    mr_test_add_node(s, name, mr_m4_translate(p.x, p.y, p.z),
                     mr_test_add_box(s, sx * w->scale, sy * w->scale, sz * w->scale, mat), MR_LAYER_VISIBLE);
}

static mr_scene *base_scene(const world *w, double floor_size) {
    mr_scene *s = mr_scene_create();
    mr_material m = {"grey", {0.7f, 0.7f, 0.7f, 1}, -1, false};
    int32_t mi = mr_scene_add_material(s, &m);
    add_box(s, w, "Floor", floor_size, 0.02, floor_size, 0, -0.01, 0, mi);
    return s;
}

/* The analytic scene: floor, a 1 x 1 occluder at height 1, a 1 x 1 rect
 * light at height 4 facing down. */
static mr_scene *square_scene(const world *w) {
    mr_scene *s = base_scene(w, 8);
    add_box(s, w, "Occluder", 1, 1e-3, 1, 0, 1, 0, 0);
    mr_scene_update_bounds(s);
    s->light_count = 1;
    mr_light *L = &s->lights[0];
    memset(L, 0, sizeof *L);
    L->direction[1] = 1;
    L->color[0] = L->color[1] = L->color[2] = 0.6f;
    L->kind = MR_LIGHT_RECT;
    L->casts = true;
    mr_dvec3 p = wpt(w, 0, 4, 0);
    L->position[0] = p.x, L->position[1] = p.y, L->position[2] = p.z;
    L->size[0] = L->size[1] = w->scale;
    L->axis_u[0] = 1;
    return s;
}

static double blocked(double x) {
    double lo = fmax(-0.5, -2 - 3 * x), hi = fmin(0.5, 2 - 3 * x);
    return fmax(0.0, hi - lo);
}
static double v_analytic(double x, double z) { return 1 - blocked(x) * blocked(z); }

static mr_view look(const world *w, mr_dvec3 eye, mr_dvec3 at, mr_dvec3 up) {
    mr_view v = {{W, H, 110, 110, W / 2 - 0.5, H / 2 - 0.5, {0}}, mr_m4_identity()};
    v.world_from_camera = mr_m4_look_at_cv(wpt(w, eye.x, eye.y, eye.z), wpt(w, at.x, at.y, at.z), up);
    return v;
}

typedef struct shot {
    mr_image vis, depth;
    char passes[256];
    bool reused;
} shot;

static bool g_bp_no_pyramid; /* render(): backprojection's full search */

static bool render(mr_renderer *r, const mr_scene *s, const mr_view *v, mr_shadow_method m, int samples, shot *out) {
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.shadow.method = m;
    p.shadow.bp_no_pyramid = g_bp_no_pyramid;
    p.shadow.want_shadow = true;
    p.shadow.gt_samples = samples;
    p.want_depth = true;
    mr_frame_result res;
    mr_error err = {0};
    memset(out, 0, sizeof *out);
    if (!mr_renderer_set_scene(r, s, &err) || !mr_render_frame(r, v, &p, &res, &err)) {
        CHECK_MSG(false, "render (%s): %s", mr_shadow_method_names[m], err.msg);
        return false;
    }
    out->vis = res.shadow;
    out->depth = res.depth;
    memset(&res.shadow, 0, sizeof res.shadow);
    memset(&res.depth, 0, sizeof res.depth);
    mr_frame_result_passes(&res, out->passes, sizeof out->passes);
    out->reused = res.shadow_reused;
    mr_frame_result_free(&res);
    CHECK_MSG(out->vis.data != NULL, "%s: no shadow buffer", mr_shadow_method_names[m]);
    return out->vis.data != NULL;
}

/* As render(), over the scene already set (its maps may be kept). */
static bool render_again(mr_renderer *r, const mr_view *v, mr_shadow_method m, shot *out) {
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.shadow.method = m;
    p.shadow.want_shadow = true;
    p.want_depth = true;
    mr_frame_result res;
    mr_error err = {0};
    memset(out, 0, sizeof *out);
    if (!mr_render_frame(r, v, &p, &res, &err)) {
        CHECK_MSG(false, "render again (%s): %s", mr_shadow_method_names[m], err.msg);
        return false;
    }
    out->vis = res.shadow;
    memset(&res.shadow, 0, sizeof res.shadow);
    mr_frame_result_passes(&res, out->passes, sizeof out->passes);
    out->reused = res.shadow_reused;
    mr_frame_result_free(&res);
    return out->vis.data != NULL;
}

static void shot_free(shot *s) {
    mr_image_free(&s->vis);
    mr_image_free(&s->depth);
}

static float px(const mr_image *im, int x, int y) { return ((const float *)im->data)[(size_t)y * im->width + x]; }

/* The world point (in the unscaled frame) a pixel sees, false if none. */
static bool pixel_world(const world *w, const mr_view *v, const mr_image *depth, int x, int y, mr_dvec3 *out) {
    double z = px(depth, x, y);
    if (!(z > 0)) return false;
    const mr_camera *c = &v->camera;
    mr_dvec3 pc = mr_v3((x - c->cx) / c->fx * z, (y - c->cy) / c->fy * z, z);
    mr_dvec3 p = mr_m4_point(&v->world_from_camera, pc);
    *out = mr_v3((p.x - w->offset.x) / w->scale, (p.y - w->offset.y) / w->scale, (p.z - w->offset.z) / w->scale);
    return true;
}

/* RMSE of the visibility against the closed form over the floor pixels
 * (all, or the penumbra only). */
static double rmse_analytic(const world *w, const mr_view *v, const shot *s, bool penumbra_only, int *count) {
    double se = 0;
    int n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            mr_dvec3 p;
            if (!pixel_world(w, v, &s->depth, x, y, &p) || fabs(p.y) > 0.01 || fabs(p.x) > 3 || fabs(p.z) > 3) continue;
            double ref = v_analytic(p.x, p.z);
            if (penumbra_only && !(ref > 0.02 && ref < 0.98)) continue;
            double e = px(&s->vis, x, y) - ref;
            se += e * e;
            n++;
        }
    if (count) *count = n;
    return n ? sqrt(se / n) : INFINITY;
}

static double rmse_images(const mr_image *a, const mr_image *b) {
    double se = 0;
    size_t n = (size_t)a->width * a->height;
    for (size_t i = 0; i < n; i++) {
        double e = ((const float *)a->data)[i] - ((const float *)b->data)[i];
        se += isfinite(e) ? e * e : 1;
    }
    return sqrt(se / (double)n);
}

/* Bilinear visibility at a world point on the floor (unscaled frame). */
static double vis_at(const world *w, const mr_view *v, const mr_image *vis, double x, double z) {
    mr_dmat4 cfw = mr_m4_invert_rigid(&v->world_from_camera);
    mr_dvec3 pc = mr_m4_point(&cfw, wpt(w, x, 0, z));
    const mr_camera *c = &v->camera;
    double u = c->fx * pc.x / pc.z + c->cx, vv = c->fy * pc.y / pc.z + c->cy;
    int x0 = (int)floor(u), y0 = (int)floor(vv);
    if (x0 < 0 || y0 < 0 || x0 + 1 >= W || y0 + 1 >= H) return NAN;
    double fu = u - x0, fv = vv - y0;
    return (1 - fv) * ((1 - fu) * px(vis, x0, y0) + fu * px(vis, x0 + 1, y0)) +
           fv * ((1 - fu) * px(vis, x0, y0 + 1) + fu * px(vis, x0 + 1, y0 + 1));
}

/* Width between the 25% and 75% crossings of the visibility going out
 * from the shadow's axis (z = 0) at distance x along it. */
static double edge_width(const world *w, const mr_view *v, const mr_image *vis, double x) {
    double z25 = NAN, z75 = NAN, prev = vis_at(w, v, vis, x, 0);
    for (double z = 0.002; z < 0.9; z += 0.002) {
        double c = vis_at(w, v, vis, x, z);
        if (isnan(z25) && prev < 0.25 && c >= 0.25) z25 = z - 0.002 * (c - 0.25) / (c - prev);
        if (isnan(z75) && prev < 0.75 && c >= 0.75) z75 = z - 0.002 * (c - 0.75) / (c - prev);
        prev = c;
    }
    return z75 - z25;
}

static void analytic_checks(mr_renderer *r, mr_image *gpu_gt_out) {
    world w = {1, {0, 0, 0}};
    mr_scene *s = square_scene(&w);
    /* Low and to the side, so the floor under the occluder is in view. */
    mr_view v = look(&w, mr_v3(2.6, 0.7, 0.4), mr_v3(0.2, 0, 0), mr_v3(0, 1, 0));
    shot gt, pcss, bp, hard, pcf;
    if (render(r, s, &v, MR_SHADOW_GROUNDTRUTH, 256, &gt)) {
        int n;
        double e = rmse_analytic(&w, &v, &gt, false, &n), ep = rmse_analytic(&w, &v, &gt, true, NULL);
        printf("  square light: GPU ground truth (256 samples) RMSE %.4f over %d floor pixels, %.4f over the penumbra\n",
               e, n, ep);
        CHECK_MSG(n > 2000, "only %d floor pixels in view", n);
        CHECK_MSG(e < 0.02, "GPU ground truth RMSE %.4f >= 0.02 against the closed form", e);
        /* V(2/3, 2/3) = 0.75 and a point on the ramp V(0.6, 0) = 0.3. */
        double a = vis_at(&w, &v, &gt.vis, 2.0 / 3, 2.0 / 3), b = vis_at(&w, &v, &gt.vis, 0.6, 0);
        printf("  GPU ground truth V(2/3, 2/3) = %.3f (0.75), V(0.6, 0) = %.3f (0.3)\n", a, b);
        CHECK_MSG(fabs(a - 0.75) < 0.05, "V(2/3, 2/3) = %.3f, want 0.75", a);
        CHECK_MSG(fabs(b - 0.3) < 0.05, "V(0.6, 0) = %.3f, want 0.3", b);
        if (gpu_gt_out) {
            *gpu_gt_out = gt.vis;
            memset(&gt.vis, 0, sizeof gt.vis);
        }
        shot_free(&gt);
    }
    if (render(r, s, &v, MR_SHADOW_PCSS, 0, &pcss)) {
        double ep = rmse_analytic(&w, &v, &pcss, true, NULL), e = rmse_analytic(&w, &v, &pcss, false, NULL);
        /* The ramp V(x, 0) from 0 at 0.5 to 1 at 0.8333: 25%..75% is 1/6 wide. */
        double lo = NAN, hi = NAN, prev = vis_at(&w, &v, &pcss.vis, 0.3, 0);
        for (double x = 0.302; x < 1.2; x += 0.002) {
            double c = vis_at(&w, &v, &pcss.vis, x, 0);
            if (isnan(lo) && prev < 0.25 && c >= 0.25) lo = x;
            if (isnan(hi) && prev < 0.75 && c >= 0.75) hi = x;
            prev = c;
        }
        printf("  PCSS: RMSE %.4f over the penumbra, %.4f over the floor; 25-75%% ramp width %.3f (1/6 = 0.167: penumbra 1/3)\n",
               ep, e, hi - lo);
        CHECK_MSG(ep < 0.1, "PCSS RMSE over the penumbra %.4f >= 0.1", ep);
        CHECK_MSG(fabs((hi - lo) - 1.0 / 6) < 0.05, "PCSS ramp width %.3f, want 1/6 (penumbra width 1/3)", hi - lo);
        shot_free(&pcss);
    }
    if (render(r, s, &v, MR_SHADOW_BP, 0, &bp)) {
        double ep = rmse_analytic(&w, &v, &bp, true, NULL), e = rmse_analytic(&w, &v, &bp, false, NULL);
        printf("  backprojection: RMSE %.4f over the penumbra, %.4f over the floor\n", ep, e);
        CHECK_MSG(e < 0.05, "backprojection RMSE %.4f >= 0.05", e);
        shot_free(&bp);
    }
    if (render(r, s, &v, MR_SHADOW_HARD, 0, &hard)) {
        /* A hard shadow from the light's centre: the occluder's projection
         * |x|, |z| < 0.5 * 4 / 3 = 0.667 dark, outside lit. */
        double in = vis_at(&w, &v, &hard.vis, 0.3, 0.2), out = vis_at(&w, &v, &hard.vis, 1.0, 0.2);
        printf("  hard: V(0.3, 0.2) = %.2f (0), V(1.0, 0.2) = %.2f (1); passes: %s\n", in, out, hard.passes);
        CHECK_MSG(in < 0.01 && out > 0.99, "hard shadow: inside %.2f, outside %.2f", in, out);
        CHECK_MSG(strstr(hard.passes, "shadow_map shadow shade") != NULL, "pass list: %s", hard.passes);
        shot_free(&hard);
    }
    /* A frozen camera and a static light: the second frame reuses the map. */
    if (render(r, s, &v, MR_SHADOW_PCF, 0, &pcf)) {
        shot again;
        mr_frame_params p = MR_FRAME_DEFAULTS;
        p.shadow.method = MR_SHADOW_PCF;
        p.shadow.want_shadow = true;
        mr_frame_result res;
        mr_error err = {0};
        CHECK_MSG(mr_render_frame(r, &v, &p, &res, &err), "%s", err.msg);
        mr_frame_result_passes(&res, again.passes, sizeof again.passes);
        printf("  frozen camera: passes %s (reused %d)\n", again.passes, (int)res.shadow_reused);
        CHECK_MSG(res.shadow_reused && !strstr(again.passes, "shadow_map"), "the map was not reused: %s", again.passes);
        CHECK_MSG(res.shadow.data && rmse_images(&res.shadow, &pcf.vis) == 0, "reused map gives another picture");
        mr_frame_result_free(&res);
        shot_free(&pcf);
    }
    /* Shadows off: no shadow pass at all. */
    {
        mr_frame_params p = MR_FRAME_DEFAULTS;
        mr_frame_result res;
        mr_error err = {0};
        char passes[256];
        CHECK_MSG(mr_render_frame(r, &v, &p, &res, &err), "%s", err.msg);
        mr_frame_result_passes(&res, passes, sizeof passes);
        CHECK_MSG(!strstr(passes, "shadow"), "shadows off runs %s", passes);
        mr_frame_result_free(&res);
    }
    /* Embree's ground truth on the same pixels. */
    {
        mr_frame_params p = MR_FRAME_DEFAULTS;
        p.want_depth = p.want_normals = true;
        mr_frame_result res;
        mr_error err = {0};
        mr_eval_gt *g = NULL;
        mr_image ray = {0};
        mr_light L;
        mr_shadow_light(s, &L);
        mr_shadow_gt_params sp = MR_SHADOW_GT_DEFAULTS;
        bool ok = mr_render_frame(r, &v, &p, &res, &err) && (g = mr_eval_gt_create(s, false, &err)) &&
                  mr_eval_shadow_groundtruth(g, &v, &res.depth, &res.normal, &L, &sp, &ray, &err);
        CHECK_MSG(ok, "embree shadow ground truth: %s", err.msg);
        if (ok) {
            shot e = {.vis = ray, .depth = res.depth};
            int n;
            double er = rmse_analytic(&w, &v, &e, false, &n);
            printf("  Embree ground truth (%d rays): RMSE %.4f against the closed form", sp.rays, er);
            CHECK_MSG(er < 0.02, "Embree ground truth RMSE %.4f >= 0.02", er);
            if (gpu_gt_out && gpu_gt_out->data) {
                /* Over the floor, the known answer's receiver, and over
                 * every pixel (the plate's rims too). */
                double se = 0;
                int nf = 0;
                for (int y = 0; y < H; y++)
                    for (int x = 0; x < W; x++) {
                        mr_dvec3 q;
                        if (!pixel_world(&w, &v, &res.depth, x, y, &q) || fabs(q.y) > 0.01) continue;
                        double dd = px(&ray, x, y) - px(gpu_gt_out, x, y);
                        se += dd * dd;
                        nf++;
                    }
                double d = nf ? sqrt(se / nf) : 1;
                printf(", %.4f against the GPU's over %d floor pixels (%.4f over all)", d, nf,
                       rmse_images(&ray, gpu_gt_out));
                CHECK_MSG(d < 0.01, "the two ground truths differ on the floor: RMSE %.4f >= 0.01", d);
                double da = rmse_images(&ray, gpu_gt_out);
                CHECK_MSG(da < 0.01, "the two ground truths differ: RMSE %.4f >= 0.01 over all pixels", da);
            }
            printf("\n");
        }
        mr_image_free(&ray);
        mr_eval_gt_destroy(&g);
        mr_frame_result_free(&res);
    }
    mr_renderer_set_scene(r, NULL, NULL);
    mr_scene_destroy(&s);
}

static mr_scene *sun_scene(const world *w, double elev_deg, double angle_deg, int what) {
    mr_scene *s = base_scene(w, 8);
    if (what == 1) add_box(s, w, "Pole", 0.4, 2, 0.4, 0, 1, 0, 0);
    if (what == 2) add_box(s, w, "Box", 0.6, 0.6, 0.6, 0, 0.3, 0, 0);
    mr_scene_update_bounds(s);
    s->light_count = 1;
    mr_light *L = &s->lights[0];
    memset(L, 0, sizeof *L);
    double e = elev_deg * 3.14159265358979323846 / 180;
    L->direction[0] = cos(e);
    L->direction[1] = sin(e);
    L->color[0] = L->color[1] = L->color[2] = 0.6f;
    L->kind = MR_LIGHT_SUN;
    L->casts = true;
    L->angle = angle_deg;
    return s;
}

static void contact_hardening(mr_renderer *r) {
    world w = {1, {0, 0, 0}};
    mr_scene *s = sun_scene(&w, 45, 8, 1);
    /* From above: the shadow runs along -x from the pole's base. */
    mr_view v = look(&w, mr_v3(-1.2, 5, 0.01), mr_v3(-1.2, 0, 0), mr_v3(1, 0, 0));
    const mr_shadow_method ms[4] = {MR_SHADOW_PCF, MR_SHADOW_PCSS, MR_SHADOW_BP, MR_SHADOW_GROUNDTRUTH};
    for (int i = 0; i < 4; i++) {
        shot sh;
        if (!render(r, s, &v, ms[i], 256, &sh)) continue;
        /* The pole's half-width is 0.2: its shadow's edge at z = 0.2. */
        double near = edge_width(&w, &v, &sh.vis, -0.5), far = edge_width(&w, &v, &sh.vis, -1.8);
        printf("  pole, %s: 25-75%% edge width %.3f at 0.5 from the base, %.3f at 1.8\n", mr_shadow_method_names[ms[i]],
               near, far);
        if (ms[i] == MR_SHADOW_PCF)
            CHECK_MSG(far < 1.5 * near && near < 1.5 * far, "PCF's penumbra changes with distance: %.3f -> %.3f", near, far);
        else
            CHECK_MSG(far > 2 * near, "%s: no contact hardening: %.3f -> %.3f", mr_shadow_method_names[ms[i]], near, far);
        shot_free(&sh);
    }
    mr_renderer_set_scene(r, NULL, NULL);
    mr_scene_destroy(&s);
}

static void acne_and_gaps(mr_renderer *r) {
    world w = {1, {0, 0, 0}};
    const mr_shadow_method ms[4] = {MR_SHADOW_HARD, MR_SHADOW_PCF, MR_SHADOW_PCSS, MR_SHADOW_BP};
    /* A bare floor under a 10 degree sun, seen from a low camera. */
    mr_scene *s = sun_scene(&w, 10, 2, 0);
    mr_view v = look(&w, mr_v3(2.5, 1.2, 1.5), mr_v3(0, 0, 0), mr_v3(0, 1, 0));
    for (int i = 0; i < 4; i++) {
        shot sh;
        if (!render(r, s, &v, ms[i], 0, &sh)) continue;
        float lo = 1;
        int n = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                if (px(&sh.depth, x, y) > 0) lo = fminf(lo, px(&sh.vis, x, y)), n++;
        printf("  grazing sun, %s: darkest floor pixel %.4f over %d\n", mr_shadow_method_names[ms[i]], lo, n);
        CHECK_MSG(n > 1000 && lo >= 0.99f, "%s: acne on a lit floor under a grazing sun: %.4f", mr_shadow_method_names[ms[i]],
                  lo);
        shot_free(&sh);
    }
    mr_scene_destroy(&s);
    /* A box on the floor: right behind its base (away from the sun) the
     * floor is in shadow, no lit gap (peter-panning). */
    s = sun_scene(&w, 30, 1, 2);
    v = look(&w, mr_v3(-0.5, 3, 1.8), mr_v3(-0.6, 0, 0), mr_v3(0, 1, 0));
    for (int i = 0; i < 4; i++) {
        shot sh;
        if (!render(r, s, &v, ms[i], 0, &sh)) continue;
        double worst = 0;
        for (double d = 0.005; d <= 0.1; d += 0.005) worst = fmax(worst, vis_at(&w, &v, &sh.vis, -0.3 - d, 0));
        printf("  box base, %s: brightest floor point within 0.1 behind the base %.3f\n", mr_shadow_method_names[ms[i]],
               worst);
        CHECK_MSG(worst < 0.2, "%s: light gap at the box's base (%.3f)", mr_shadow_method_names[ms[i]], worst);
        shot_free(&sh);
    }
    mr_renderer_set_scene(r, NULL, NULL);
    mr_scene_destroy(&s);
}

/* Backprojection on the sunlit faces of a box under a small high sun (the
 * factory case of the bench): no receiver pixel that the ground truth sees
 * lit may come out dark. The receiver plane of a face the sun grazes,
 * extrapolated over the search area, runs deeper than the receiver; texels
 * between the two depths lie behind the receiver, and their projections
 * through it (flipped, or huge) used to black out the light: dark seams
 * along the box's faces and edges. */
static void bp_steep_receivers(mr_renderer *r) {
    world w = {1, {0, 0, 0}};
    /* The bench's factory sun (3 degrees), and a wider one whose search
     * area reaches further behind the receivers. */
    const double angles[2] = {3, 15};
    for (int ai = 0; ai < 2; ai++) {
        mr_scene *s = sun_scene(&w, 60, angles[ai], 1);
        add_box(s, &w, "Box", 0.8, 0.8, 0.8, 0.9, 0.4, 0.7, 0);
        mr_scene_update_bounds(s);
        const double d[3] = {0.4, 1.0, 0.25};
        double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int k = 0; k < 3; k++) s->lights[0].direction[k] = d[k] / l;
        mr_view v = look(&w, mr_v3(3.5, 2.2, 3.0), mr_v3(0.4, 0.5, 0.3), mr_v3(0, 1, 0));
        shot gt, bp;
        if (render(r, s, &v, MR_SHADOW_GROUNDTRUTH, 64, &gt) && render(r, s, &v, MR_SHADOW_BP, 0, &bp)) {
            int lit = 0, dark = 0;
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    if (!(px(&gt.depth, x, y) > 0) || px(&gt.vis, x, y) < 0.95f) continue;
                    lit++;
                    dark += px(&bp.vis, x, y) < 0.5f;
                }
            double e = rmse_images(&bp.vis, &gt.vis);
            printf("  steep receivers, %.0f degree sun, bp: %d of %d pixels the ground truth sees lit come out below "
                   "0.5; RMSE %.4f against the GPU ground truth\n", angles[ai], dark, lit, e);
            CHECK_MSG(lit > 5000 && dark <= lit / 2000, "bp blacks out lit receivers (%.0f degree sun): %d of %d",
                      angles[ai], dark, lit);
            CHECK_MSG(e < 0.025, "bp against the ground truth (%.0f degree sun): RMSE %.4f", angles[ai], e);
            /* The depth pyramid runs for bp only, after a new map, or over
             * a kept map that has none yet; a kept map keeps it. */
            shot p2 = {0}, b2 = {0}, b3 = {0};
            if (ai == 0 && render(r, s, &v, MR_SHADOW_PCSS, 0, &p2) && render_again(r, &v, MR_SHADOW_BP, &b2) &&
                render_again(r, &v, MR_SHADOW_BP, &b3)) {
                printf("  passes: bp '%s'; pcss '%s'; bp after it '%s'; again '%s'\n", bp.passes, p2.passes, b2.passes,
                       b3.passes);
                CHECK_MSG(strstr(bp.passes, "shadow_pyramid") && !strstr(p2.passes, "shadow_pyramid"),
                          "the pyramid pass must run for bp and only for bp");
                CHECK_MSG(b2.reused && strstr(b2.passes, "shadow_pyramid") && !strstr(b2.passes, "shadow_map"),
                          "bp over a map kept from pcss must build its pyramid: '%s'", b2.passes);
                CHECK_MSG(b3.reused && !strstr(b3.passes, "shadow_pyramid") && !strstr(b3.passes, "shadow_map"),
                          "bp over a kept map and pyramid must redo neither: '%s'", b3.passes);
                CHECK_MSG(rmse_images(&b2.vis, &bp.vis) == 0 && rmse_images(&b3.vis, &bp.vis) == 0,
                          "bp over kept maps differs from bp over new ones");
            }
            if (ai == 0) shot_free(&p2), shot_free(&b2), shot_free(&b3);
            /* The pyramid only prunes: the full search finds the same (at a
             * quarter of the pixels: the full search is slow). */
            shot full = {0}, pyr = {0};
            mr_view vq = v;
            vq.camera = mr_camera_resized(&v.camera, W / 2, H / 2);
            if (render(r, s, &vq, MR_SHADOW_BP, 0, &pyr)) {
                g_bp_no_pyramid = true;
                bool okf = render(r, s, &vq, MR_SHADOW_BP, 0, &full);
                g_bp_no_pyramid = false;
                double worst = 0;
                int differ = 0;
                for (size_t i = 0; okf && i < (size_t)(W / 2) * (H / 2); i++) {
                    double dd = fabs((double)((const float *)full.vis.data)[i] - ((const float *)pyr.vis.data)[i]);
                    worst = fmax(worst, dd);
                    differ += dd > 1e-4;
                }
                printf("  bp with the pyramid against the full search: %d pixels differ, by at most %.2e\n", differ, worst);
                CHECK_MSG(okf && worst < 1e-3, "the pyramid changed bp's result: %d pixels, by up to %.4f", differ, worst);
            }
            shot_free(&pyr);
            g_bp_no_pyramid = false;
            shot_free(&full);
        }
        shot_free(&gt);
        shot_free(&bp);
        mr_renderer_set_scene(r, NULL, NULL);
        mr_scene_destroy(&s);
    }
}

static void scales(mr_renderer *r) {
    const world ws[4] = {{1, {0, 0, 0}}, {1e-3, {0, 0, 0}}, {1e4, {0, 0, 0}}, {1, {1e7, 0, -1e7}}};
    const mr_shadow_method ms[4] = {MR_SHADOW_HARD, MR_SHADOW_PCF, MR_SHADOW_PCSS, MR_SHADOW_BP};
    for (int k = 0; k < 2; k++) {
        shot ref[4];
        for (int i = 0; i < 4; i++) {
            const world *w = &ws[i];
            mr_scene *s = k == 0 ? square_scene(w) : sun_scene(w, 45, 8, 1);
            mr_view v = k == 0 ? look(w, mr_v3(2.6, 0.7, 0.4), mr_v3(0.2, 0, 0), mr_v3(0, 1, 0))
                               : look(w, mr_v3(-1.2, 5, 0.01), mr_v3(-1.2, 0, 0), mr_v3(1, 0, 0));
            for (int m = 0; m < 4; m++) {
                shot sh;
                if (!render(r, s, &v, ms[m], 0, &sh)) continue;
                if (i == 0) {
                    ref[m] = sh;
                    continue;
                }
                double e = ref[m].vis.data ? rmse_images(&sh.vis, &ref[m].vis) : 1;
                printf("  %s, %s at scale %g, offset %g: RMSE %.5f against scale 1\n", k ? "sun" : "rect",
                       mr_shadow_method_names[ms[m]], w->scale, w->offset.x, e);
                CHECK_MSG(e < 0.01, "%s at scale %g offset %g: RMSE %.4f", mr_shadow_method_names[ms[m]], w->scale,
                          w->offset.x, e);
                shot_free(&sh);
            }
            mr_renderer_set_scene(r, NULL, NULL);
            mr_scene_destroy(&s);
        }
        for (int m = 0; m < 4; m++) shot_free(&ref[m]);
    }
}

/* Cascades (sun): a hall-sized floor seen from eye height at a grazing
 * angle, a pole 4 ahead of the camera, the sun behind the pole so its
 * shadow runs towards the camera and its edges along the view. */
#define HALL 60.0
static mr_scene *hall_scene(const world *w, double elev_deg, double angle_deg, bool pole) {
    mr_scene *s = base_scene(w, HALL);
    if (pole) add_box(s, w, "Pole", 0.4, 2, 0.4, 0, 1, -HALL / 2 + 5, 0);
    mr_scene_update_bounds(s);
    s->light_count = 1;
    mr_light *L = &s->lights[0];
    memset(L, 0, sizeof *L);
    double e = elev_deg * 3.14159265358979323846 / 180;
    L->direction[1] = sin(e);
    L->direction[2] = cos(e);
    L->color[0] = L->color[1] = L->color[2] = 0.6f;
    L->kind = MR_LIGHT_SUN;
    L->casts = true;
    L->angle = angle_deg;
    return s;
}

static mr_view hall_view(const world *w) {
    mr_view v = {{W, H, 220, 220, W / 2 - 0.5, H / 2 - 0.5, {0}}, mr_m4_identity()};
    v.world_from_camera = mr_m4_look_at_cv(wpt(w, 0.3, 1.2, -HALL / 2 + 1), wpt(w, 0.3, 0, -HALL / 2 + 1 + 1.2 / tan(0.26)),
                                           mr_v3(0, 1, 0));
    return v;
}

static bool render_c(mr_renderer *r, const mr_scene *s, const mr_view *v, mr_shadow_method m, int cascades, shot *out,
                     int *ncasc) {
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.shadow.method = m;
    p.shadow.want_shadow = true;
    p.shadow.gt_samples = 64;
    p.shadow.cascades = cascades;
    p.want_depth = true;
    mr_frame_result res;
    mr_error err = {0};
    memset(out, 0, sizeof *out);
    if (!mr_renderer_set_scene(r, s, &err) || !mr_render_frame(r, v, &p, &res, &err)) {
        CHECK_MSG(false, "render (%s, %d cascades): %s", mr_shadow_method_names[m], cascades, err.msg);
        return false;
    }
    out->vis = res.shadow;
    out->depth = res.depth;
    memset(&res.shadow, 0, sizeof res.shadow);
    memset(&res.depth, 0, sizeof res.depth);
    if (ncasc) *ncasc = res.shadow_cascades;
    mr_frame_result_free(&res);
    return out->vis.data != NULL;
}

/* The 25-75% width of the pole shadow's edge across x at z (unscaled). */
static double edge_width_x(const world *w, const mr_view *v, const mr_image *vis, double z) {
    double x25 = NAN, x75 = NAN, prev = vis_at(w, v, vis, 0, z);
    for (double x = 0.001; x < 0.7; x += 0.001) {
        double c = vis_at(w, v, vis, x, z);
        if (isnan(x25) && prev < 0.25 && c >= 0.25) x25 = x - 0.001 * (c - 0.25) / (c - prev);
        if (isnan(x75) && prev < 0.75 && c >= 0.75) x75 = x - 0.001 * (c - 0.75) / (c - prev);
        prev = c;
    }
    return x75 - x25;
}

static void cascades(mr_renderer *r) {
    world w = {1, {0, 0, 0}};
    /* A small scene needs one map: the pole under a sun from above. */
    {
        mr_scene *small = sun_scene(&w, 45, 8, 1);
        mr_view sv = look(&w, mr_v3(-1.2, 5, 0.01), mr_v3(-1.2, 0, 0), mr_v3(1, 0, 0));
        shot sh;
        int nc = 0;
        if (render_c(r, small, &sv, MR_SHADOW_PCSS, 0, &sh, &nc)) {
            printf("  small scene: auto picks %d cascade(s)\n", nc);
            CHECK_MSG(nc == 1, "a small scene got %d cascades", nc);
            shot_free(&sh);
        }
        mr_renderer_set_scene(r, NULL, NULL);
        mr_scene_destroy(&small);
    }
    mr_scene *s = hall_scene(&w, 45, 0.5, true);
    mr_view v = hall_view(&w);
    shot gt, one, many, hard1, hardn;
    int n_auto = 0, n1 = 0, ngt = 0;
    /* The pole's shadow near the camera: 0.6 and 1.2 in front of its base. */
    const double zs[2] = {-HALL / 2 + 5 - 0.6, -HALL / 2 + 5 - 1.2};
    if (render_c(r, s, &v, MR_SHADOW_GROUNDTRUTH, 4, &gt, &ngt) && render_c(r, s, &v, MR_SHADOW_PCF, 1, &one, &n1) &&
        render_c(r, s, &v, MR_SHADOW_PCF, 0, &many, &n_auto) && render_c(r, s, &v, MR_SHADOW_HARD, 1, &hard1, NULL) &&
        render_c(r, s, &v, MR_SHADOW_HARD, 0, &hardn, NULL)) {
        printf("  hall view: auto picks %d cascades (1 asked: %d, ground truth with %d)\n", n_auto, n1, ngt);
        CHECK_MSG(n_auto >= 2 && n1 == 1 && ngt == 4, "cascades: auto %d, one %d, four %d", n_auto, n1, ngt);
        for (int i = 0; i < 2; i++) {
            double eg = edge_width_x(&w, &v, &gt.vis, zs[i] - (-HALL / 2 + 5) + (-HALL / 2 + 5));
            double e1 = edge_width_x(&w, &v, &one.vis, zs[i]), en = edge_width_x(&w, &v, &many.vis, zs[i]);
            printf("  pole edge %.1f before its base, PCF 25-75%% width: 1 cascade %.4f, %d cascades %.4f, "
                   "ground truth %.4f\n", -HALL / 2 + 5 - zs[i], e1, n_auto, en, eg);
            CHECK_MSG(en < 0.6 * e1, "cascades do not sharpen the near shadow: %.4f vs %.4f", en, e1);
            CHECK_MSG(fabs(en - eg) < fabs(e1 - eg), "cascades not closer to ground truth: %.4f %.4f (gt %.4f)", en, e1,
                      eg);
        }
        /* Hard shadows against the ground truth near the camera (depth < 8). */
        double se1 = 0, sen = 0;
        int np = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                float d = px(&gt.depth, x, y);
                if (!(d > 0 && d < 8)) continue;
                double g = px(&gt.vis, x, y), a = px(&hard1.vis, x, y) - g, b = px(&hardn.vis, x, y) - g;
                se1 += a * a, sen += b * b, np++;
            }
        double r1 = sqrt(se1 / (np ? np : 1)), rn = sqrt(sen / (np ? np : 1));
        printf("  hard vs ground truth near the camera (%d px): RMSE 1 cascade %.4f, %d cascades %.4f\n", np, r1, n_auto,
               rn);
        CHECK_MSG(np > 1000 && rn < r1, "hard with cascades not closer to the ground truth: %.4f vs %.4f", rn, r1);
    }
    shot_free(&gt), shot_free(&one), shot_free(&many), shot_free(&hard1), shot_free(&hardn);
    mr_renderer_set_scene(r, NULL, NULL);
    mr_scene_destroy(&s);

    /* Stable: wherever the camera walks (sideways and forwards, by odd
     * amounts), each cascade's corner lies on whole texels of the
     * scene-fixed light frame, and a small step keeps its size. */
    {
        s = hall_scene(&w, 45, 0.5, true);
        const double steps[4][2] = {{0, 0}, {0.0137, 0.0071}, {0.31, -0.173}, {-1.7, 2.9}};
        double worst = 0, t0[MR_SHADOW_MAX_CASCADES][2] = {{0}};
        bool same_size = true;
        int ncs = 0;
        for (int i = 0; i < 4; i++) {
            mr_view sv = hall_view(&w);
            sv.world_from_camera.m[3] += steps[i][0];
            sv.world_from_camera.m[11] += steps[i][1];
            shot sh;
            if (!render_c(r, s, &sv, MR_SHADOW_HARD, 0, &sh, NULL)) continue;
            shot_free(&sh);
            double corner[2], texel[2];
            ncs = mr_shadow_cascade_grid(r, 0, corner, texel);
            for (int k = 0; k < ncs; k++) {
                mr_shadow_cascade_grid(r, k, corner, texel);
                for (int a = 0; a < 2; a++) {
                    double q = corner[a] / texel[a];
                    worst = fmax(worst, fabs(q - round(q)));
                    if (i == 0) t0[k][a] = texel[a];
                    if (i == 1 && texel[a] != t0[k][a]) same_size = false;
                }
            }
        }
        printf("  cascades (%d) on a walking camera: corners off whole texels by at most %.2e texel; a 1.4 cm step "
               "keeps the size: %s\n", ncs, worst, same_size ? "yes" : "no");
        CHECK_MSG(ncs >= 2 && worst < 1e-3, "cascade not snapped to texels: %.3g texel off (%d cascades)", worst, ncs);
        CHECK_MSG(same_size, "a 1.4 cm step changed a cascade's size");
        mr_renderer_set_scene(r, NULL, NULL);
        mr_scene_destroy(&s);
    }

    /* No seam: a bare lit floor under a grazing sun (10 degrees), 2..4
     * cascades: every floor pixel lit, across the boundaries too. */
    s = hall_scene(&w, 10, 1, false);
    const mr_shadow_method ms[4] = {MR_SHADOW_HARD, MR_SHADOW_PCF, MR_SHADOW_PCSS, MR_SHADOW_BP};
    for (int c = 2; c <= 4; c++)
        for (int i = 0; i < 4; i++) {
            shot sh;
            int nc = 0;
            if (!render_c(r, s, &v, ms[i], c, &sh, &nc)) continue;
            float lo = 1;
            int n = 0;
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++)
                    if (px(&sh.depth, x, y) > 0) lo = fminf(lo, px(&sh.vis, x, y)), n++;
            printf("  hall floor, grazing sun, %s, %d cascades: darkest floor pixel %.4f over %d\n",
                   mr_shadow_method_names[ms[i]], nc, lo, n);
            CHECK_MSG(nc >= 2 && n > 5000 && lo >= 0.99f, "%s, %d cascades: seam or acne on a lit floor: %.4f",
                      mr_shadow_method_names[ms[i]], nc, lo);
            shot_free(&sh);
        }
    mr_renderer_set_scene(r, NULL, NULL);
    mr_scene_destroy(&s);

    /* The same picture at scale 1e-3 and 1e4 and a 1e7 offset. */
    const world ws[4] = {{1, {0, 0, 0}}, {1e-3, {0, 0, 0}}, {1e4, {0, 0, 0}}, {1, {1e7, 0, -1e7}}};
    shot ref[2];
    const mr_shadow_method m2[2] = {MR_SHADOW_PCF, MR_SHADOW_PCSS};
    for (int i = 0; i < 4; i++) {
        s = hall_scene(&ws[i], 45, 2, true);
        v = hall_view(&ws[i]);
        for (int m = 0; m < 2; m++) {
            shot sh;
            int nc = 0;
            if (!render_c(r, s, &v, m2[m], 0, &sh, &nc)) continue;
            if (i == 0) {
                ref[m] = sh;
                continue;
            }
            double e = ref[m].vis.data ? rmse_images(&sh.vis, &ref[m].vis) : 1;
            printf("  hall, %s, %d cascades at scale %g, offset %g: RMSE %.5f against scale 1\n",
                   mr_shadow_method_names[m2[m]], nc, ws[i].scale, ws[i].offset.x, e);
            CHECK_MSG(nc >= 2 && e < 0.01, "cascades at scale %g offset %g: RMSE %.4f (%d cascades)", ws[i].scale,
                      ws[i].offset.x, e, nc);
            shot_free(&sh);
        }
        mr_renderer_set_scene(r, NULL, NULL);
        mr_scene_destroy(&s);
    }
    shot_free(&ref[0]), shot_free(&ref[1]);
}

/* Scene configs with bad lights fail with one line. */
static void bad_configs(void) {
    char dir[4096];
    if (!mr_test_fresh_dir("test_shadow", dir, sizeof dir)) return;
    static const struct {
        const char *json, *want;
    } cases[] = {
        {"{\"demo\": \"planned\", \"lights\": [{\"direction\": [0,1,0], \"kind\": \"rect\", \"position\": [0,4,0], \"size\": [-1, 1]}]}",
         "light size must be positive"},
        {"{\"demo\": \"planned\", \"lights\": [{\"direction\": [0,1,0], \"kind\": \"sphere\", \"position\": [0,4,0], \"size\": \"nan\"}]}",
         "finite number"},
        {"{\"demo\": \"planned\", \"lights\": [{\"direction\": [0,1,0], \"angle\": -2}]}", "angle"},
        {"{\"demo\": \"planned\", \"lights\": [{\"direction\": [0,0,0]}]}", "direction is zero"},
        {"{\"demo\": \"planned\", \"receivers\": [\"NoSuchNode*\"]}", "matches no node"},
        {"{\"demo\": \"planned\", \"lights\": [{\"direction\": [0,1,0], \"kind\": \"disk\"}]}", "kind"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[4200];
        snprintf(path, sizeof path, "%s/bad%zu.json", dir, i);
        FILE *f = fopen(path, "wb");
        fputs(cases[i].json, f);
        fclose(f);
        mr_error err = {0};
        mr_scene *s = mr_scene_load(path, NULL, &err);
        CHECK_MSG(!s, "case %zu loaded", i);
        CHECK_MSG(strstr(err.msg, cases[i].want) && !strchr(err.msg, '\n'), "case %zu: '%s' (want '%s')", i, err.msg,
                  cases[i].want);
        mr_scene_destroy(&s);
    }
    /* A good one: sizes, kinds and receivers read back. */
    char path[4200];
    snprintf(path, sizeof path, "%s/good.json", dir);
    FILE *f = fopen(path, "wb");
    fputs("{\"demo\": \"planned\", \"shadows\": \"pcss\", \"receivers\": [\"Floor*\"], \"lights\": ["
          "{\"direction\": [0,2,0], \"kind\": \"rect\", \"position\": [1,4,2], \"size\": [1, 0.5], \"axis\": [1,0,0]},"
          "{\"direction\": [1,1,0], \"angle\": 0.5, \"shadows\": false}]}",
          f);
    fclose(f);
    mr_error err = {0};
    mr_scene *s = mr_scene_load(path, NULL, &err);
    CHECK_MSG(s, "good config: %s", err.msg);
    if (s) {
        CHECK(s->light_count == 2 && s->lights[0].kind == MR_LIGHT_RECT && s->lights[0].casts);
        CHECK_NEAR(s->lights[0].size[1], 0.5, 0);
        CHECK_NEAR(s->lights[0].position[2], 2, 0);
        CHECK(s->lights[1].kind == MR_LIGHT_SUN && !s->lights[1].casts);
        CHECK_NEAR(s->lights[1].angle, 0.5, 0);
        CHECK(strcmp(s->shadow_method, "pcss") == 0);
        int catchers = 0;
        for (int32_t i = 0; i < s->node_count; i++) catchers += s->nodes[i].shadow_catcher;
        CHECK_MSG(catchers > 0, "no receiver marked");
        mr_light L;
        CHECK(mr_shadow_light(s, &L) && L.kind == MR_LIGHT_RECT);
        mr_scene_destroy(&s);
    }
}

/* The shadow catcher: over a uniform grey video, the floor (a receiver) is
 * not drawn: lit, it is the video itself; in the box's shadow, darker; the
 * box is blended as ever. */
static void catcher(mr_renderer *r) {
    world w = {1, {0, 0, 0}};
    mr_scene *s = sun_scene(&w, 45, 2, 2);
    s->nodes[0].shadow_catcher = true; /* the floor */
    mr_view v = look(&w, mr_v3(-0.5, 3, 1.8), mr_v3(-0.6, 0, 0), mr_v3(0, 1, 0));
    mr_image video = {0};
    mr_error err = {0};
    CHECK(mr_image_alloc(&video, W, H, 3, MR_PIX_U8, &err));
    memset(video.data, 200, mr_image_bytes(&video));
    for (int on = 0; on < 2; on++) {
        mr_frame_params p = MR_FRAME_DEFAULTS;
        p.video = &video;
        p.alpha = 0.3f;
        p.shadow.method = on ? MR_SHADOW_PCSS : MR_SHADOW_OFF;
        p.want_depth = true;
        mr_frame_result res;
        if (!mr_renderer_set_scene(r, s, &err) || !mr_render_frame(r, &v, &p, &res, &err)) {
            CHECK_MSG(false, "catcher: %s", err.msg);
            continue;
        }
        /* Floor points: lit (in front of the box, towards the sun) and in
         * its shadow (behind it); the box's top. */
        mr_dmat4 cfw = mr_m4_invert_rigid(&v.world_from_camera);
        const double pts[3][3] = {{0.8, 0, 0}, {-0.6, 0, 0}, {0, 0.6, 0}};
        int val[3];
        for (int k = 0; k < 3; k++) {
            mr_dvec3 pc = mr_m4_point(&cfw, mr_v3(pts[k][0], pts[k][1], pts[k][2]));
            int x = (int)lround(v.camera.fx * pc.x / pc.z + v.camera.cx), y = (int)lround(v.camera.fy * pc.y / pc.z + v.camera.cy);
            val[k] = x >= 0 && y >= 0 && x < W && y < H ? ((const unsigned char *)res.color.data)[(y * W + x) * 3 + 1] : -1;
        }
        printf("  catcher, shadows %s: lit floor %d, shadowed floor %d, box top %d (video 200)\n", on ? "pcss" : "off",
               val[0], val[1], val[2]);
        CHECK_MSG(val[0] == 200, "the lit floor must be the video: %d", val[0]);
        if (on) CHECK_MSG(val[1] >= 0 && val[1] < 170, "the box's shadow must darken the video: %d", val[1]);
        else CHECK_MSG(val[1] == 200, "without shadows the floor is the video: %d", val[1]);
        CHECK_MSG(val[2] != 200 && val[2] > 0, "the box must still be drawn over the video: %d", val[2]);
        mr_frame_result_free(&res);
    }
    mr_image_free(&video);
    mr_renderer_set_scene(r, NULL, NULL);
    mr_scene_destroy(&s);
}

/* The map reuse key includes hide_hidden_layer: an occluder on the hidden
 * layer casts while that layer is drawn and not when it is left out, so a
 * frozen camera that toggles it must redraw the map each time (a kept map
 * would show the other setting's shadow). */
static void hidden_layer_key(mr_renderer *r) {
    world w = {1, {0, 0, 0}};
    mr_scene *s = square_scene(&w);
    s->nodes[1].layer = MR_LAYER_HIDDEN; /* the occluder */
    mr_view v = look(&w, mr_v3(2.6, 0.7, 0.4), mr_v3(0.2, 0, 0), mr_v3(0, 1, 0));
    mr_error err = {0};
    CHECK_MSG(mr_renderer_set_scene(r, s, &err), "%s", err.msg);
    static const bool hide[4] = {false, true, false, true};
    for (int i = 0; i < 4; i++) {
        mr_frame_params p = MR_FRAME_DEFAULTS;
        p.shadow.method = MR_SHADOW_HARD;
        p.shadow.want_shadow = true;
        p.hide_hidden_layer = hide[i];
        p.want_depth = true;
        mr_frame_result res;
        if (!mr_render_frame(r, &v, &p, &res, &err)) {
            CHECK_MSG(false, "hidden layer key: %s", err.msg);
            continue;
        }
        char passes[256];
        mr_frame_result_passes(&res, passes, sizeof passes);
        double in = res.shadow.data && res.depth.data ? vis_at(&w, &v, &res.shadow, 0.3, 0.2) : -1;
        printf("  hidden occluder, hide_hidden_layer %d: V(0.3, 0.2) = %.2f, reused %d\n", (int)hide[i], in,
               (int)res.shadow_reused);
        CHECK_MSG(!res.shadow_reused && strstr(passes, "shadow_map"), "frame %d reused the other setting's map: %s", i,
                  passes);
        if (hide[i]) CHECK_MSG(in > 0.99, "hidden layer left out, yet it casts: V = %.2f", in);
        else CHECK_MSG(in >= 0 && in < 0.01, "hidden layer drawn, yet no shadow: V = %.2f", in);
        mr_frame_result_free(&res);
    }
    mr_renderer_set_scene(r, NULL, NULL);
    mr_scene_destroy(&s);
}

/* The bench at a tiny size: its files, its header, one row per setting;
 * and the suite's cases all build with a casting light. */
static void bench_and_suite(mr_gpu *gpu, mr_renderer *r) {
    for (int i = 0; i < MR_SHADOW_SUITE_COUNT; i++) {
        mr_shadow_suite_case c;
        mr_error err = {0};
        mr_light L;
        CHECK_MSG(mr_shadow_suite_build(i, &c, &err), "suite case %d: %s", i, err.msg);
        CHECK_MSG(c.scene && mr_shadow_light(c.scene, &L) && c.scene->node_count > 1, "suite case %d", i);
        mr_shadow_suite_free(&c);
    }
    char dir[4096];
    if (!mr_test_fresh_dir("test_shadow_bench", dir, sizeof dir)) return;
    mr_bench_shadows_params p = {MR_BENCH_SHADOWS_DEFAULTS};
    p.gfx.gpu = gpu;
    p.gfx.renderer = r;
    p.out_dir = dir;
    p.width = 64;
    p.height = 48;
    p.frames = 1;
    p.rays = 16;
    p.first = 2;
    p.count = 1;
    p.views = 1;
    p.gt_samples_max = 4; /* the rows, not the ground truth's quality */
    mr_error err = {0};
    CHECK_MSG(mr_bench_shadows(&p, &err), "bench shadows: %s", err.msg);
    char path[4200];
    snprintf(path, sizeof path, "%s/bench_shadows.csv", dir);
    size_t n = 0;
    char *csv = mr_file_read(path, &n, 1 << 20, &err);
    const char *cols = "case,varying,overlap,view,tuning,method,setting,value,pcf_radius,gpu_ms,S_pixels,rmse_S,"
                       "sqrtD_over_S,ssim_S,rmse_floor_S,rmse_objects_S\n";
    const char *h = csv ? strstr(csv, "\ncase,") : NULL;
    CHECK_MSG(h && strncmp(h + 1, cols, strlen(cols)) == 0, "bench_shadows.csv header");
    int rows = 0;
    for (const char *q = h ? h + 1 : NULL; q && (q = strstr(q, "\nsimple_varying,")); q++) rows++;
    CHECK_MSG(rows == 31, "bench_shadows.csv: %d rows for one case and view, want 31 (one per setting)", rows);
    free(csv);
    static const char *const files[] = {"bench_shadows.svg", "bench_shadows.md", "bench_shadows_simple_varying.png"};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, files[i]);
        FILE *f = fopen(path, "rb");
        CHECK_MSG(f != NULL, "bench wrote no %s", files[i]);
        if (f) fclose(f);
    }
}

int main(void) {
    bad_configs();
    mr_error err = {0};
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) return mr_test_no_gpu("test_shadow", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    if (r) {
        mr_image gt = {0};
        analytic_checks(r, &gt);
        mr_image_free(&gt);
        contact_hardening(r);
        acne_and_gaps(r);
        bp_steep_receivers(r);
        scales(r);
        cascades(r);
        catcher(r);
        hidden_layer_key(r);
        bench_and_suite(gpu, r);
    }
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return mr_test_finish("test_shadow");
}
