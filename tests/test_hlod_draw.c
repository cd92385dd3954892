/* The LOD hierarchy drawn (lib/render/hlod_draw.c): proxies replace whole
 * groups of parts where their certified error projects under
 * --lod-pixels, yet a tap still names the real part (40 random taps
 * against the frame without the hierarchy: the same part and depth, at
 * edges too, since a pick redraws its pixel at the part levels), the
 * hidden layer stays hidden, each part keeps its own colour through the
 * proxies, and far from the origin it draws like at it. Skips (77) where
 * no EGL device exists. */
#include "mr_render.h"
#include "mr_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static mr_gpu *g_gpu;
static mr_renderer *g_r;

static mr_scene *cad(double unit, double ox) {
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    cp.parts = 24;
    cp.part_triangles = 800;
    cp.unit = unit;
    cp.origin[0] = ox;
    mr_error err = {0};
    mr_scene *s = mr_synth_cad_build(&cp, &err);
    /* every third part in the hidden layer; every mesh a colour of its own */
    for (int32_t i = 0; s && i < s->node_count; i++)
        if (s->nodes[i].mesh_count > 0 && i % 3 == 1) s->nodes[i].layer = MR_LAYER_HIDDEN;
    for (int32_t i = 0; s && i < s->mesh_count; i++) {
        mr_material m = {.base_color = {(float)(i % 3 == 0), (float)(i % 3 == 1), (float)((i / 3) % 3) * 0.5f, 1},
                         .base_color_texture = -1};
        s->meshes[i].material = mr_scene_add_material(s, &m);
    }
    CHECK_MSG(s != NULL, "%s", err.msg);
    return s;
}

static bool frame(const mr_view *v, bool hier, bool hide_hidden, mr_frame_result *res, mr_draw_stats *st) {
    mr_error err = {0};
    mr_draw_params dp = MR_DRAW_DEFAULTS;
    dp.no_hlod = !hier;
    dp.occlusion_auto = false;
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = 320;
    fp.height = 240;
    fp.hide_hidden_layer = hide_hidden;
    bool ok = mr_renderer_set_draw_params(g_r, &dp, &err) && mr_render_frame(g_r, v, &fp, res, &err);
    CHECK_MSG(ok, "%s", err.msg);
    if (ok && st) mr_renderer_draw_stats(g_r, st);
    return ok;
}

static double mismatch(const mr_image *a, const mr_image *b, int tol) {
    if (a->width != b->width || a->height != b->height || a->channels != b->channels) return 1.0;
    size_t bad = 0, n = (size_t)a->width * a->height;
    const unsigned char *pa = a->data, *pb = b->data;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < a->channels; c++)
            if (abs((int)pa[i * a->channels + c] - (int)pb[i * a->channels + c]) > tol) {
                bad++;
                break;
            }
    return (double)bad / (double)n;
}

/* node under (x, y) of the last frame, -1 for none; its depth (0: none) */
static int32_t pick_depth(double x, double y, double *depth) {
    mr_pick pk;
    mr_error err = {0};
    *depth = 0;
    if (!mr_renderer_pick(g_r, x, y, &pk, &err)) return -2;
    *depth = pk.depth;
    return pk.hit ? pk.node : -1;
}

static int32_t pick_node(double x, double y) {
    double d;
    return pick_depth(x, y, &d);
}

/* largest channel difference of pixel (x, y) */
static int pixel_diff(const mr_image *a, const mr_image *b, int x, int y) {
    const unsigned char *pa = a->data, *pb = b->data;
    size_t o = ((size_t)y * a->width + x) * a->channels;
    int m = 0;
    for (int c = 0; c < a->channels; c++) {
        int d = abs((int)pa[o + c] - (int)pb[o + c]);
        if (d > m) m = d;
    }
    return m;
}

static void check_case(double unit, double ox) {
    mr_scene *s = cad(unit, ox);
    if (!s) return;
    mr_error err = {0};
    mr_lod_params lp = MR_LOD_DEFAULTS;
    mr_lod *lod = mr_lod_build(s, &lp, &err);
    mr_hlod_params hp = MR_HLOD_DEFAULTS;
    mr_hlod *h = lod ? mr_hlod_build(s, lod, &hp, &err) : NULL;
    CHECK_MSG(h != NULL, "%s", err.msg);
    CHECK_MSG(mr_renderer_set_scene_lod(g_r, s, lod, &err) && mr_renderer_set_hlod(g_r, h, &err), "%s", err.msg);
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    cp.parts = 24;
    cp.part_triangles = 800;
    cp.unit = unit;
    cp.origin[0] = ox;
    mr_view v = mr_synth_view(NULL, &cp, MR_SYNTH_VIEW_OVERVIEW);
    /* Twice as far from the hall's centre: most of it in proxies */
    for (int k = 0; k < 3; k++) {
        double c = 0.5 * (s->bounds_min[k] + s->bounds_max[k]);
        v.world_from_camera.m[k * 4 + 3] = c + 2 * (v.world_from_camera.m[k * 4 + 3] - c);
    }
    mr_frame_result with, without;
    mr_draw_stats sw, so;
    memset(&with, 0, sizeof with);
    memset(&without, 0, sizeof without);
    /* Taps: without first (and whether the 3x3 around each tap is one
     * part: there the colour is compared), then with. */
    enum { TAPS = 40 };
    double tx[TAPS], ty[TAPS], ref_depth[TAPS];
    int32_t ref[TAPS];
    bool interior[TAPS];
    mr_rng rng;
    mr_rng_seed(&rng, 7);
    bool ok = frame(&v, false, false, &without, &so);
    /* 40 random taps on the model (random pixels, those that hit a part) */
    for (int t = 0, tries = 0; ok && t < TAPS; t++) {
        do {
            tx[t] = 2 + mr_rng_uniform(&rng) * 315;
            ty[t] = 2 + mr_rng_uniform(&rng) * 235;
            ref[t] = pick_depth(tx[t], ty[t], &ref_depth[t]);
        } while (ref[t] < 0 && ++tries < 20000);
        interior[t] = true;
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++)
                if (pick_node(tx[t] + dx, ty[t] + dy) != ref[t]) interior[t] = false;
    }
    ok = ok && frame(&v, true, false, &with, &sw);
    CHECK_MSG(sw.hlod_proxies > 0 && sw.hlod_triangles > 0, "unit %g: no proxy drawn", unit);
    CHECK(sw.triangles < so.triangles); /* the proxies are cheaper than the parts */
    int compared = 0, hits = 0;
    for (int t = 0; ok && t < TAPS; t++) {
        double d;
        int32_t n = pick_depth(tx[t], ty[t], &d);
        CHECK(n >= -1 && n < s->node_count);
        if (n >= 0) CHECK(s->nodes[n].mesh_count > 0); /* a real part, never a proxy */
        hits += ref[t] >= 0;
        /* Every tap, edges included: the part and depth of the frame
         * without the hierarchy */
        CHECK_MSG(n == ref[t] && fabs(d - ref_depth[t]) <= 1e-5 * ref_depth[t],
                  "unit %g tap (%.1f, %.1f): node %d at %.9g with the hierarchy, %d at %.9g without", unit, tx[t], ty[t],
                  (int)n, d, (int)ref[t], ref_depth[t]);
        if (!interior[t]) continue;
        /* The part's own colour through the proxy */
        int tap_x = (int)floor(tx[t] + 0.5), tap_y = (int)floor(ty[t] + 0.5);
        compared++;
        CHECK_MSG(pixel_diff(&with.color, &without.color, tap_x, tap_y) <= 40,
                  "unit %g tap (%d, %d) on node %d: colour off by %d with the hierarchy", unit, tap_x, tap_y, (int)n,
                  pixel_diff(&with.color, &without.color, tap_x, tap_y));
    }
    CHECK_MSG(compared >= 20 && hits >= 30, "only %d taps inside a part's area (%d on parts)", compared, hits);
    /* Colours survive: the same picture up to the proxies' sub-pixel error */
    if (ok) CHECK_MSG(mismatch(&with.color, &without.color, 48) < 0.03, "unit %g: %.4f of pixels differ", unit,
                      mismatch(&with.color, &without.color, 48));
    mr_frame_result_free(&with);
    mr_frame_result_free(&without);
    /* The hidden layer stays hidden: no pixel names a hidden node */
    if (frame(&v, true, true, &with, NULL)) {
        for (int y = 0; y < 240; y += 6)
            for (int x = 0; x < 320; x += 6) {
                int32_t n = pick_node(x, y);
                if (n >= 0) CHECK(s->nodes[n].layer == MR_LAYER_VISIBLE);
            }
        mr_frame_result_free(&with);
    }
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_hlod_destroy(&h);
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
}

int main(void) {
    mr_error err = {0};
    g_gpu = mr_gpu_create_headless(NULL, &err);
    if (!g_gpu) return mr_test_no_gpu("test_hlod_draw", &err);
    g_r = mr_renderer_create(g_gpu, &err);
    CHECK_MSG(g_r != NULL, "%s", err.msg);
    if (g_r) {
        check_case(1, 0);
        check_case(1000, 0);
        check_case(1, 1e7);
    }
    mr_renderer_destroy(&g_r);
    mr_gpu_destroy(&g_gpu);
    return mr_test_finish("test_hlod_draw");
}
