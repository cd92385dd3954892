/* issue 18 (lane deint): deinterleaved AO (--ao-deinterleave). With the
 * option on: the frame runs ao_deint_split and ao_deint_merge around the
 * AO pass (and not without it); the slice methods beside the analytic wall
 * stay within test_ao's closed-form tolerance (RMSE 0.025, 64 samples,
 * unblurred); the blurred image differs from the interleaved one only by
 * noise (see test_noise for the bound); scale invariance (1e-3 .. 1e4 and a
 * 1e7 offset) holds, at full and half resolution; sizes not divisible by 4
 * keep the sky at 1. GPU parts skip only where there is no EGL device. */
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"
#include "mr_test_ao.h"

#include <stdlib.h>
#include <string.h>

static mr_gpu *g_gpu;
static mr_renderer *g_r;

/* RMSE over geometry pixels (depth > 0); 1e9 where there are none. */
static double rmse_geo(const mr_image *a, const mr_image *b, const mr_image *depth) {
    mr_image_metrics m;
    mr_error e = {0};
    return mr_image_compare(a, b, depth, &m, &e) && m.count > 0 ? m.rmse : 1e9;
}

static void test_pass_list(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 96, 72);
    mr_ao_params ao = MR_AO_DEFAULTS;
    ao.method = MR_AO_SCHEER;
    mr_frame_result r;
    char buf[256];
    for (int on = 0; on < 2; on++) {
        ao.deinterleave = on;
        if (!mr_test_render_ao(g_r, s, &v, &ao, &r)) continue;
        mr_frame_result_passes(&r, buf, sizeof buf);
        const char *want = on ? "gbuffer ao_deint_split ao ao_deint_merge ao_blur shade" : "gbuffer ao ao_blur shade";
        CHECK_MSG(strcmp(buf, want) == 0, "deinterleave %s: passes %s", on ? "on" : "off", buf);
        mr_frame_result_free(&r);
    }
    /* The positions path is not split: the option is ignored there. */
    ao.positions = true;
    if (mr_test_render_ao(g_r, s, &v, &ao, &r)) {
        mr_frame_result_passes(&r, buf, sizeof buf);
        CHECK_MSG(strstr(buf, "deint") == NULL, "deinterleave with positions: passes %s", buf);
        mr_frame_result_free(&r);
    }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* The slice methods beside the wall with deinterleave on: test_ao's
 * closed form and tolerance (0.025 RMSE, 64 samples, unblurred), for the
 * depth-scaled and the fixed radius, at full and half resolution. */
static void test_wall(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 160, 120);
    const mr_ao_method ms[4] = {MR_AO_GTAO, MR_AO_BITMASK, MR_AO_SCHEER_GT, MR_AO_SCHEER_BM};
    for (int mi = 0; mi < 4; mi++)
        for (int mode = 0; mode < 2; mode++) {
            mr_ao_params ao = mr_test_ao_wall_params(ms[mi], mode);
            ao.deinterleave = true;
            char what[96];
            snprintf(what, sizeof what, "deinterleaved %s %s radius", mr_ao_method_name(ao.method), mode ? "view" : "screen");
            mr_test_ao_wall_check(g_r, s, &v, &ao, what);
        }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* Deinterleaved against interleaved, both blurred (the defaults): the two
 * differ by their noise, nothing else. The bound comes from the
 * interleaved estimator itself: two independent noise draws of it (the
 * pixel hash and a world hash on a grid finer than a pixel) differ by
 * e_ii = sqrt(2) sigma, sigma its per-pixel noise after the blur. The
 * deinterleaved image's noise is no larger (16 stratified rotations, each
 * in every 4x4 block the blur averages), so against the interleaved one it
 * differs by at most sqrt(sigma^2 + sigma^2) = e_ii; the bound allows 50%
 * for the sample snap to the layer's grid (up to 2 AO pixels, for samples
 * at least 8 AO pixels out: MR_AO_DEINT_NEAR). The mean
 * differs by less than 0.01 (no bias). An odd size (not divisible by 4)
 * checks the layers' padding: sky stays exactly 1. */
static void test_noise(void) {
    mr_dvec3 o = mr_v3(0, 0, 0);
    mr_scene *s = mr_test_ao_corner_scene(1, o, true);
    mr_view v = mr_test_ao_corner_view(1, o, 126, 94);
    const mr_ao_method ms[3] = {MR_AO_SCHEER, MR_AO_GTAO, MR_AO_HBAO};
    for (int mi = 0; mi < 3; mi++)
        for (int half = 0; half < 2; half++) {
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = ms[mi];
            ao.half_res = half;
            ao.screen_radius = 0.2; /* 19 px: the samples beyond 8 px (16 at half) read the layers */
            mr_frame_result a, b, c;
            if (!mr_test_render_ao(g_r, s, &v, &ao, &a)) continue;
            ao.noise = MR_AO_NOISE_WORLD;
            ao.noise_cell = 1e-4; /* pixels are ~0.03 apart: a cell per pixel */
            if (!mr_test_render_ao(g_r, s, &v, &ao, &b)) {
                mr_frame_result_free(&a);
                continue;
            }
            ao.noise = MR_AO_NOISE_PIXEL;
            ao.deinterleave = true;
            if (mr_test_render_ao(g_r, s, &v, &ao, &c)) {
                double e_ii = rmse_geo(&a.ao, &b.ao, &a.depth), e_di = rmse_geo(&c.ao, &a.ao, &a.depth);
                double ma = 0, mc = 0;
                int n = 0, sky = 0;
                const float *pa = a.ao.data, *pc = c.ao.data, *d = a.depth.data;
                for (int i = 0; i < 126 * 94; i++) {
                    if (d[i] > 0) ma += pa[i], mc += pc[i], n++;
                    else sky += pc[i] != 1.0f;
                }
                ma /= n > 0 ? n : 1;
                mc /= n > 0 ? n : 1;
                if (getenv("MR_TEST_VERBOSE"))
                    printf("%s%s: deint vs interleaved RMSE %.4f, two interleaved draws %.4f; mean %.4f vs %.4f\n",
                           mr_ao_method_name(ao.method), half ? " half" : "", e_di, e_ii, mc, ma);
                CHECK_MSG(e_di < 1.5 * e_ii, "%s%s: deinterleaved vs interleaved RMSE %.4f, noise bound %.4f",
                          mr_ao_method_name(ao.method), half ? " half" : "", e_di, 1.5 * e_ii);
                CHECK_MSG(fabs(mc - ma) < 0.01, "%s%s: mean AO deinterleaved %.4f vs interleaved %.4f",
                          mr_ao_method_name(ao.method), half ? " half" : "", mc, ma);
                CHECK_MSG(sky == 0, "%s%s: %d sky pixels not 1", mr_ao_method_name(ao.method), half ? " half" : "", sky);
                CHECK(mr_test_ao_count_bad(&c.ao) == 0);
                mr_frame_result_free(&c);
            }
            mr_frame_result_free(&a);
            mr_frame_result_free(&b);
        }
    mr_scene_destroy(&s);
    mr_renderer_set_scene(g_r, NULL, NULL);
}

/* test_ao's scale invariance with deinterleave on: the same image (RMSE <
 * 0.01) at scales 1e-3 and 1e4 and with a 1e7 offset. */
static void test_scale_invariance(void) {
    const double scales[] = {1, 1e-3, 1e4, 1};
    const mr_dvec3 offs[] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {1e7, 0, -1e7}};
    const mr_ao_method methods[] = {MR_AO_SCHEER, MR_AO_GTAO, MR_AO_SCHEER_BM};
    for (size_t mi = 0; mi < sizeof methods / sizeof methods[0]; mi++)
        for (int half = 0; half < 2; half++) {
            mr_image ref = {0};
            for (int i = 0; i < 4; i++) {
                mr_scene *s = mr_test_ao_corner_scene(scales[i], offs[i], true);
                mr_view v = mr_test_ao_corner_view(scales[i], offs[i], 128, 96);
                mr_ao_params ao = MR_AO_DEFAULTS;
                ao.method = methods[mi];
                ao.half_res = half;
                ao.deinterleave = true;
                mr_frame_result res;
                if (mr_test_render_ao(g_r, s, &v, &ao, &res)) {
                    CHECK(mr_test_ao_count_bad(&res.ao) == 0);
                    if (i == 0) {
                        ref = res.ao;
                        res.ao.data = NULL;
                    } else {
                        double e = rmse_geo(&res.ao, &ref, &res.depth);
                        CHECK_MSG(e < 0.01, "deinterleaved %s%s at scale %g offset %g: RMSE %.5f vs scale 1",
                                  mr_ao_method_name(methods[mi]), half ? " half-res" : "", scales[i], offs[i].x, e);
                    }
                    mr_frame_result_free(&res);
                }
                mr_scene_destroy(&s);
            }
            mr_image_free(&ref);
        }
    mr_renderer_set_scene(g_r, NULL, NULL);
}

int main(void) {
    mr_error err = {0};
    g_gpu = mr_gpu_create_headless(NULL, &err);
    if (!g_gpu) return mr_test_no_gpu("test_ao_deint", &err);
    g_r = mr_renderer_create(g_gpu, &err);
    CHECK_MSG(g_r != NULL, "%s", err.msg);
    if (g_r) {
        test_pass_list();
        test_wall();
        test_noise();
        test_scale_invariance();
        mr_renderer_destroy(&g_r);
    }
    mr_gpu_destroy(&g_gpu);
    return mr_test_finish("test_ao_deint");
}
