/* Rendering tests through EGL (llvmpipe here): analytic shading, reversed-Z
 * precision (1e7 offset, 1 mm at 1 km, scale 1e-3..1e7), the video overlay
 * against a CPU reference, aux outputs, the pass list, and golden images.
 * Skips (77) where no EGL device exists. */
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static mr_gpu *g_gpu;
static mr_renderer *g_r;



static int32_t add_material(mr_scene *s, float r, float g, float b, int32_t tex) {
    mr_material mat;
    memset(&mat, 0, sizeof mat);
    mat.base_color[0] = r; mat.base_color[1] = g; mat.base_color[2] = b; mat.base_color[3] = 1;
    mat.base_color_texture = tex;
    return mr_scene_add_material(s, &mat);
}


/* A small still life: floor, three boxes, a hidden pipe-like box behind a
 * wall, a checker-textured plate. `scale` multiplies all lengths, `offset`
 * moves everything. */
static mr_scene *still_life(double scale, mr_dvec3 offset) {
    mr_scene *s = mr_scene_create();
    mr_texture tex;
    memset(&tex, 0, sizeof tex);
    mr_image_alloc(&tex.image, 8, 8, 4, MR_PIX_U8, NULL);
    for (int i = 0; i < 64; i++) {
        unsigned char v = ((i % 8) + (i / 8)) % 2 ? 230 : 20;
        unsigned char *px = (unsigned char *)tex.image.data + i * 4;
        px[0] = px[1] = px[2] = v;
        px[3] = 255;
    }
    tex.nearest = true;
    int32_t t = mr_scene_add_texture(s, &tex);
    int32_t grey = add_material(s, 0.6f, 0.6f, 0.6f, -1), red = add_material(s, 0.8f, 0.1f, 0.1f, -1),
            blue = add_material(s, 0.1f, 0.2f, 0.8f, -1), yel = add_material(s, 0.9f, 0.8f, 0.1f, -1),
            chk = add_material(s, 1, 1, 1, t);
    double k = scale;
    int32_t floor_mesh = mr_test_add_box(s, 20 * k, 0.2 * k, 20 * k, grey);
    int32_t cube = mr_test_add_box(s, 1 * k, 1 * k, 1 * k, red);
    int32_t tall = mr_test_add_box(s, 0.6 * k, 2.5 * k, 0.6 * k, blue);
    int32_t wall = mr_test_add_box(s, 4 * k, 2 * k, 0.1 * k, yel);
    int32_t pipe = mr_test_add_box(s, 3 * k, 0.2 * k, 0.2 * k, red);
    int32_t plate = mr_test_add_quad(s, 1 * k, 1 * k, chk, true);
    mr_dmat4 T;
#define PLACE(name, mesh, px, py, pz, layer)                                                    \
    T = mr_m4_translate(offset.x + (px) * k, offset.y + (py) * k, offset.z + (pz) * k);         \
    mr_test_add_node(s, name, T, mesh, layer)
    PLACE("Floor", floor_mesh, 0, -0.1, 0, MR_LAYER_VISIBLE);
    PLACE("Cube", cube, -1.5, 0.5, 1, MR_LAYER_VISIBLE);
    PLACE("Tall", tall, 1.2, 1.25, 0.5, MR_LAYER_VISIBLE);
    PLACE("Wall", wall, 0, 1, 3, MR_LAYER_VISIBLE);
    PLACE("Pipe", pipe, 0, 1.2, 3.4, MR_LAYER_HIDDEN);
    /* The plate faces the camera: rotate the quad about y by 180 degrees. */
    mr_dmat4 R = mr_m4_rotate_axis(mr_v3(0, 1, 0), 3.14159265358979 * 0.9);
    T = mr_m4_translate(offset.x + 0.2 * k, offset.y + 0.8 * k, offset.z - 0.5 * k);
    T = mr_m4_mul(&T, &R);
    mr_test_add_node(s, "Plate", T, plate, MR_LAYER_VISIBLE);
#undef PLACE
    mr_scene_update_bounds(s);
    return s;
}

static mr_view still_life_view(double scale, mr_dvec3 offset, int w, int h) {
    mr_view v;
    mr_camera c = {w, h, 0.9 * w, 0.9 * w, (w - 1) / 2.0 + 1.3, (h - 1) / 2.0 - 0.7, {0, 0, 0, 0, 0}};
    v.camera = c;
    mr_dvec3 eye = mr_v3(offset.x + 2.5 * scale, offset.y + 2.2 * scale, offset.z - 6.0 * scale);
    mr_dvec3 at = mr_v3(offset.x - 0.2 * scale, offset.y + 0.6 * scale, offset.z + 1.0 * scale);
    v.world_from_camera = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
    return v;
}

/* Per-pixel comparison: fraction of pixels whose channels differ by more
 * than tol; also the largest difference seen. */
static double mismatch(const mr_image *a, const mr_image *b, int tol, int *maxdiff) {
    *maxdiff = 255;
    if (a->width != b->width || a->height != b->height || a->channels != b->channels) return 1.0;
    size_t bad = 0, n = (size_t)a->width * a->height;
    const unsigned char *pa = a->data, *pb = b->data;
    *maxdiff = 0;
    for (size_t i = 0; i < n; i++) {
        int worst = 0;
        for (int c = 0; c < a->channels; c++) {
            int d = abs((int)pa[i * a->channels + c] - (int)pb[i * a->channels + c]);
            if (d > worst) worst = d;
        }
        if (worst > *maxdiff) *maxdiff = worst;
        if (worst > tol) bad++;
    }
    return (double)bad / (double)n;
}

static bool render(const mr_scene *s, const mr_view *v, const mr_frame_params *p, mr_frame_result *res) {
    mr_error err = {0};
    bool ok = mr_renderer_set_scene(g_r, s, &err) && mr_render_frame(g_r, v, p, res, &err);
    CHECK_MSG(ok, "%s", err.msg);
    return ok;
}

static void test_analytic_shading(void) {
    /* A grey quad facing the camera, one light straight from the camera:
     * linear = albedo * (ambient + 1) exactly. */
    mr_scene *s = mr_scene_create();
    int32_t m = add_material(s, 0.25f, 0.5f, 0.125f, -1);
    int32_t q = mr_test_add_quad(s, 10, 10, m, false);
    mr_test_add_node(s, "Q", mr_m4_translate(0, 0, 5), q, MR_LAYER_VISIBLE);
    s->light_count = 1;
    s->lights[0].direction[2] = -1; /* towards the camera at the origin */
    s->lights[0].color[0] = s->lights[0].color[1] = s->lights[0].color[2] = 0.6f;
    s->ambient = 0.4f;
    mr_scene_update_bounds(s);
    mr_view v = {{32, 24, 30, 30, 15.5, 11.5, {0}}, mr_m4_identity()};
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.want_depth = p.want_normals = true;
    mr_frame_result res;
    if (render(s, &v, &p, &res)) {
        const unsigned char *px = (const unsigned char *)res.color.data + (12 * 32 + 16) * 3;
        /* sRGB encodings of 0.25, 0.5, 0.125. */
        CHECK(abs(px[0] - 137) <= 1 && abs(px[1] - 188) <= 1 && abs(px[2] - 99) <= 1);
        float *d = res.depth.data, *n = res.normal.data;
        CHECK_NEAR(d[12 * 32 + 16], 5.0, 5e-5);
        CHECK_NEAR(d[0], 5.0, 5e-5);
        CHECK_NEAR(n[(12 * 32 + 16) * 3 + 2], -1.0, 1e-3);
        char passes[128];
        mr_frame_result_passes(&res, passes, sizeof passes);
        CHECK(strcmp(passes, "gbuffer shade") == 0);
        CHECK(res.draw_calls == 1 && res.triangles == 2);
        mr_frame_result_free(&res);
    }
    mr_scene_destroy(&s);
}

static void test_far_offset(void) {
    /* The same still life at the origin and 1e7 units away (and far below):
     * the images must match. */
    mr_view v0 = still_life_view(1, mr_v3(0, 0, 0), 96, 72);
    mr_scene *s0 = still_life(1, mr_v3(0, 0, 0));
    mr_dvec3 off = mr_v3(1e7, -3e6, 1e7);
    mr_view v1 = still_life_view(1, off, 96, 72);
    mr_scene *s1 = still_life(1, off);
    mr_frame_params p = MR_FRAME_DEFAULTS;
    mr_frame_result a, b;
    if (render(s0, &v0, &p, &a)) {
        if (render(s1, &v1, &p, &b)) {
            int md;
            double frac = mismatch(&a.color, &b.color, 2, &md);
            CHECK_MSG(frac <= 0.002, "1e7 offset: %.4f of pixels differ (max diff %d)", frac, md);
            mr_frame_result_free(&b);
        }
        /* Scale invariance: the same picture at 1e-3 and 1e7 units. */
        static const double scales[] = {1e-3, 1e7};
        for (int i = 0; i < 2; i++) {
            mr_scene *ss = still_life(scales[i], mr_v3(0, 0, 0));
            mr_view vs = still_life_view(scales[i], mr_v3(0, 0, 0), 96, 72);
            if (render(ss, &vs, &p, &b)) {
                int md;
                double frac = mismatch(&a.color, &b.color, 2, &md);
                CHECK_MSG(frac <= 0.002, "scale %g: %.4f of pixels differ (max diff %d)", scales[i], frac, md);
                mr_frame_result_free(&b);
            }
            mr_scene_destroy(&ss);
        }
        mr_frame_result_free(&a);
    }
    mr_scene_destroy(&s0);
    mr_scene_destroy(&s1);
}

/* Two parallel planes 1 mm apart seen from 1 km: the nearer one must win
 * everywhere, whatever the drawing order and tilt. */
static void test_zfight(void) {
    for (int variant = 0; variant < 4; variant++) {
        bool near_first = variant & 1;
        double tilt = (variant & 2) ? 1.0 : 0.0; /* radians about y */
        mr_scene *s = mr_scene_create();
        int32_t red = add_material(s, 1, 0, 0, -1), blue = add_material(s, 0, 0, 1, -1);
        int32_t qn = mr_test_add_quad(s, 40, 40, red, false), qf = mr_test_add_quad(s, 40, 40, blue, false);
        mr_dmat4 R = mr_m4_rotate_axis(mr_v3(0, 1, 0), tilt);
        mr_dmat4 Tn = mr_m4_translate(0, 0, 1000.0), Tf = mr_m4_translate(0, 0, 1000.001);
        mr_dmat4 Wn = mr_m4_mul(&Tn, &R), Wf = mr_m4_mul(&Tf, &R);
        /* Depth offset along the plane normal: move the far plane 1 mm along
         * its own normal so the gap is 1 mm also when tilted. */
        mr_dvec3 nrm = mr_m4_dir(&R, mr_v3(0, 0, 1));
        Wf = mr_m4_translate(nrm.x * 0.001, nrm.y * 0.001, 1000.0 + nrm.z * 0.001);
        Wf = mr_m4_mul(&Wf, &R);
        (void)Tf;
        if (near_first) {
            mr_test_add_node(s, "near", Wn, qn, 0);
            mr_test_add_node(s, "far", Wf, qf, 0);
        } else {
            mr_test_add_node(s, "far", Wf, qf, 0);
            mr_test_add_node(s, "near", Wn, qn, 0);
        }
        mr_scene_update_bounds(s);
        /* 64x48 pixels spanning about 3 m at 1 km. */
        mr_view v = {{64, 48, 20000, 20000, 31.5, 23.5, {0}}, mr_m4_identity()};
        mr_frame_params p = MR_FRAME_DEFAULTS;
        mr_frame_result res;
        if (render(s, &v, &p, &res)) {
            const unsigned char *px = res.color.data;
            int bad = 0;
            for (int i = 0; i < 64 * 48; i++)
                if (!(px[i * 3] > 100 && px[i * 3 + 2] < 50)) bad++;
            CHECK_MSG(bad == 0, "z-fight variant %d: %d of %d pixels show the far plane", variant, bad, 64 * 48);
            mr_frame_result_free(&res);
        }
        mr_scene_destroy(&s);
    }
}

/* Strong tangential distortion (p1, p2 of a tilted lens) with barrel k1:
 * the overlay's GPU undistortion must follow the CPU camera model per
 * pixel. The video encodes its own pixel position (red = 3 u, green = 4 v),
 * so each output pixel says which source position the shader sampled; that
 * must be where mr_camera_distort sends the pixel's ideal ray, and
 * mr_camera_undistort must bring it back to the pixel, within 0.5 px. */
static void test_overlay_tangential(const mr_scene *s, const mr_view *v) {
    const int W = v->camera.width, H = v->camera.height;
    mr_image video;
    CHECK(mr_image_alloc(&video, W, H, 3, MR_PIX_U8, NULL));
    unsigned char *vp = video.data;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            vp[(y * W + x) * 3 + 0] = (unsigned char)(x * 3);
            vp[(y * W + x) * 3 + 1] = (unsigned char)(y * 4);
            vp[(y * W + x) * 3 + 2] = 128;
        }
    mr_view vd = *v;
    const double k1 = -0.15, p1 = 0.05, p2 = -0.04;
    vd.camera.dist[0] = k1;
    vd.camera.dist[2] = p1;
    vd.camera.dist[3] = p2;
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.video = &video;
    p.alpha = 1;
    mr_frame_result res;
    if (render(s, &vd, &p, &res)) {
        const mr_camera *c = &vd.camera;
        const unsigned char *o = res.color.data;
        int inside = 0, bad = 0, bad_back = 0, wx = 0, wy = 0;
        double worst = 0, worst_back = 0, sum = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double xd, yd;
                mr_camera_distort(c, (x - c->cx) / c->fx, (y - c->cy) / c->fy, &xd, &yd);
                double u = xd * c->fx + c->cx, w = yd * c->fy + c->cy;
                /* Away from the border, where clamping and black take over. */
                if (u < 1 || w < 1 || u > W - 2 || w > H - 2) continue;
                inside++;
                double gu = o[(y * W + x) * 3 + 0] / 3.0, gw = o[(y * W + x) * 3 + 1] / 4.0;
                double e = hypot(gu - u, gw - w);
                sum += e;
                if (e > worst) { worst = e; wx = x; wy = y; }
                if (e > 0.5) bad++;
                /* The sampled position, undistorted, is this pixel. */
                double ux, uy;
                bool conv = mr_camera_undistort(c, (gu - c->cx) / c->fx, (gw - c->cy) / c->fy, &ux, &uy);
                double eb = conv ? hypot(ux * c->fx + c->cx - x, uy * c->fy + c->cy - y) : INFINITY;
                if (eb > worst_back) worst_back = eb;
                if (eb > 0.6) bad_back++;
            }
        CHECK_MSG(inside > W * H * 6 / 10, "tangential overlay: only %d of %d pixels sample inside the frame", inside,
                  W * H);
        CHECK_MSG(bad == 0 && worst < 0.5,
                  "tangential overlay (k1 %g, p1 %g, p2 %g): %d of %d pixels sample the video more than 0.5 px from "
                  "where the camera model puts them (worst %.2f px at %d,%d; mean %.3f px): the shader's distortion "
                  "terms differ from mr_camera_distort", k1, p1, p2, bad, inside, worst, wx, wy, sum / inside);
        CHECK_MSG(bad_back == 0, "tangential overlay: %d pixels do not undistort back onto themselves (worst %.2f px)",
                  bad_back, worst_back);
        printf("  tangential overlay: worst %.3f px, mean %.3f px over %d pixels; back %.3f px\n", worst, sum / inside,
               inside, worst_back);
        mr_frame_result_free(&res);
    }
    mr_image_free(&video);
}

static void test_overlay(void) {
    mr_scene *s = still_life(1, mr_v3(0, 0, 0));
    mr_view v = still_life_view(1, mr_v3(0, 0, 0), 80, 60);
    /* A video frame with structure everywhere. */
    mr_image video;
    mr_image_alloc(&video, 80, 60, 3, MR_PIX_U8, NULL);
    unsigned char *vp = video.data;
    for (int y = 0; y < 60; y++)
        for (int x = 0; x < 80; x++) {
            vp[(y * 80 + x) * 3 + 0] = (unsigned char)(x * 3);
            vp[(y * 80 + x) * 3 + 1] = (unsigned char)(y * 4);
            vp[(y * 80 + x) * 3 + 2] = (unsigned char)(((x / 8) + (y / 8)) % 2 ? 200 : 40);
        }
    mr_frame_params p = MR_FRAME_DEFAULTS;
    mr_frame_result virt, res;
    if (render(s, &v, &p, &virt)) {
        /* alpha = 0: the virtual image, unchanged. */
        p.video = &video;
        p.alpha = 0;
        if (render(s, &v, &p, &res)) {
            int md;
            CHECK(mismatch(&virt.color, &res.color, 1, &md) == 0);
            char passes[128];
            mr_frame_result_passes(&res, passes, sizeof passes);
            CHECK(strcmp(passes, "gbuffer shade overlay") == 0);
            mr_frame_result_free(&res);
        }
        /* alpha = 1 without distortion: the video, unchanged. */
        p.alpha = 1;
        if (render(s, &v, &p, &res)) {
            int md;
            double frac = mismatch(&video, &res.color, 1, &md);
            CHECK_MSG(frac == 0, "alpha 1: %.4f differ (max %d)", frac, md);
            mr_frame_result_free(&res);
        }
        /* alpha = 1 with distortion: each pixel shows the raw frame at the
         * distorted position (CPU reference through mr_camera_distort). */
        mr_view vd = v;
        vd.camera.dist[0] = -0.2;
        vd.camera.dist[1] = 0.05;
        vd.camera.dist[2] = 0.002;
        vd.camera.dist[3] = -0.001;
        if (render(s, &vd, &p, &res)) {
            int bad = 0, inside = 0;
            const unsigned char *o = res.color.data;
            for (int y = 0; y < 60; y++)
                for (int x = 0; x < 80; x++) {
                    double xd, yd;
                    mr_camera_distort(&vd.camera, (x - vd.camera.cx) / vd.camera.fx, (y - vd.camera.cy) / vd.camera.fy,
                                      &xd, &yd);
                    double u = xd * vd.camera.fx + vd.camera.cx, w = yd * vd.camera.fy + vd.camera.cy;
                    if (u < 1 || w < 1 || u > 78 || w > 58) continue;
                    float ref[3];
                    mr_image_sample_bilinear(&video, u, w, ref);
                    inside++;
                    /* Texture filtering happens in linear light, the CPU
                     * reference in sRGB bytes: allow for that on edges. */
                    for (int c = 0; c < 2; c++)
                        if (abs((int)o[(y * 80 + x) * 3 + c] - (int)(ref[c] + 0.5f)) > 3) { bad++; break; }
                }
            CHECK(inside > 3000);
            CHECK_MSG(bad <= inside / 100, "distorted overlay: %d of %d pixels off", bad, inside);
            mr_frame_result_free(&res);
        }
        /* alpha = 0.5: halfway in linear light between the two. */
        p.alpha = 0.5f;
        if (render(s, &v, &p, &res)) {
            const unsigned char *o = res.color.data, *a = virt.color.data, *b = video.data;
            int bad = 0;
            for (int i = 0; i < 80 * 60 * 3; i++) {
                float la = powf(a[i] / 255.0f, 2.2f), lb = powf(b[i] / 255.0f, 2.2f);
                float expect = 255.0f * powf(0.5f * (la + lb), 1 / 2.2f);
                if (fabsf(o[i] - expect) > 4) bad++;
            }
            CHECK_MSG(bad < 80 * 60 * 3 / 100, "alpha 0.5: %d channels off", bad);
            mr_frame_result_free(&res);
        }
        mr_frame_result_free(&virt);
    }
    /* Hidden layer: hiding it changes pixels only where the pipe is seen. */
    mr_view top = v;
    top.world_from_camera = mr_m4_look_at_cv(mr_v3(0, 8, 3.2), mr_v3(0, 0, 3.3), mr_v3(0, 0, 1));
    p = (mr_frame_params)MR_FRAME_DEFAULTS;
    if (render(s, &top, &p, &virt)) {
        p.hide_hidden_layer = true;
        if (render(s, &top, &p, &res)) {
            int md;
            double frac = mismatch(&virt.color, &res.color, 2, &md);
            CHECK_MSG(frac > 0.005 && frac < 0.3, "hidden layer covers %.4f of the top view", frac);
            mr_frame_result_free(&res);
        }
        mr_frame_result_free(&virt);
    }
    mr_image_free(&video);
    test_overlay_tangential(s, &v);
    mr_scene_destroy(&s);
}

/* Golden images: the still life with and without overlay. Set
 * MR_UPDATE_GOLDEN=1 to rewrite them after an intended change. */
static void test_golden(void) {
    const char *data = getenv("MR_TEST_DATA");
    if (!data) {
        fprintf(stderr, "test_render: MR_TEST_DATA not set, golden images not checked\n");
        return;
    }
    mr_scene *s = still_life(1, mr_v3(0, 0, 0));
    mr_view v = still_life_view(1, mr_v3(0, 0, 0), 128, 96);
    v.camera.dist[0] = -0.1;
    mr_image video;
    mr_image_alloc(&video, 128, 96, 3, MR_PIX_U8, NULL);
    unsigned char *vp = video.data;
    for (int i = 0; i < 128 * 96; i++) {
        int x = i % 128, y = i / 128;
        vp[i * 3] = (unsigned char)(x * 2);
        vp[i * 3 + 1] = (unsigned char)((x / 16 + y / 16) % 2 ? 180 : 60);
        vp[i * 3 + 2] = (unsigned char)(y * 2);
    }
    for (int k = 0; k < 2; k++) {
        mr_frame_params p = MR_FRAME_DEFAULTS;
        if (k == 1) {
            p.video = &video;
            p.alpha = 0.4f;
        }
        mr_frame_result res;
        if (!render(s, &v, &p, &res)) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/golden/still_life_%s.png", data, k ? "overlay" : "plain");
        mr_error err = {0};
        if (getenv("MR_UPDATE_GOLDEN")) {
            CHECK_MSG(mr_image_save_png(path, &res.color, &err), "%s", err.msg);
            fprintf(stderr, "test_render: wrote %s\n", path);
        } else {
            mr_image gold;
            if (mr_image_load(path, 3, &gold, &err)) {
                int md;
                double frac = mismatch(&gold, &res.color, 3, &md);
                CHECK_MSG(frac <= 0.005, "%s: %.4f of pixels differ by more than 3 (max %d)", path, frac, md);
                mr_image_free(&gold);
            } else {
                CHECK_MSG(false, "%s", err.msg);
            }
        }
        mr_frame_result_free(&res);
    }
    mr_image_free(&video);
    mr_scene_destroy(&s);
}

static void test_bad_views(void) {
    mr_scene *s = still_life(1, mr_v3(0, 0, 0));
    mr_view v = still_life_view(1, mr_v3(0, 0, 0), 32, 24);
    mr_error err = {0};
    CHECK(mr_renderer_set_scene(g_r, s, &err));
    mr_frame_result res;
    mr_view bad = v;
    bad.camera.fx = 0;
    CHECK(!mr_render_frame(g_r, &bad, NULL, &res, &err) && err.code == MR_ERR_INVALID);
    bad = v;
    bad.world_from_camera.m[0] *= 2; /* scaled: not rigid */
    CHECK(!mr_render_frame(g_r, &bad, NULL, &res, &err) && err.code == MR_ERR_INVALID);
    bad = v;
    bad.world_from_camera.m[3] = NAN;
    CHECK(!mr_render_frame(g_r, &bad, NULL, &res, &err));
    /* Grazing view along the floor and a camera inside a box stay finite. */
    mr_view graze = v;
    graze.world_from_camera = mr_m4_look_at_cv(mr_v3(-30, 1e-4, 0), mr_v3(30, 0, 0), mr_v3(0, 1, 0));
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.want_depth = true;
    if (render(s, &graze, &p, &res)) {
        const float *d = res.depth.data;
        bool finite = true;
        for (int i = 0; i < 32 * 24; i++) finite = finite && isfinite(d[i]) && d[i] >= 0;
        CHECK(finite);
        mr_frame_result_free(&res);
    }
    mr_renderer_set_scene(g_r, NULL, &err);
    mr_scene_destroy(&s);
}

int main(void) {
    mr_error err = {0};
    g_gpu = mr_gpu_create_headless(NULL, &err);
    if (!g_gpu) return mr_test_no_gpu("test_render", &err);
    g_r = mr_renderer_create(g_gpu, &err);
    CHECK_MSG(g_r != NULL, "%s", err.msg);
    if (g_r) {
        test_analytic_shading();
        test_far_offset();
        test_zfight();
        test_overlay();
        test_golden();
        test_bad_views();
    }
    mr_renderer_destroy(&g_r);
    mr_gpu_destroy(&g_gpu);
    return mr_test_finish("test_render");
}
