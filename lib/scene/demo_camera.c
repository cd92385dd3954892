/* The demo's camera side: AprilTag images for the tag plates (from the
 * apriltag library, the one place outside lib/track that uses it), the demo
 * tablet camera and its standing viewpoints, the hall built with its tags,
 * and the camera-frame synthesis (lens distortion, optical blur, exposure,
 * sensor noise, motion blur) that turns ideal renders into camera frames
 * for `mrcheck demo`, `mrcheck synth` and the benches. */
#include "mr_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>

bool mr_demo_tag_images(int count, mr_image **out, int *border, mr_error *err) {
    *out = NULL;
    apriltag_family_t *fam = tag36h11_create();
    if (!fam) return mr_fail(err, MR_ERR_NOMEM, "cannot create the tag36h11 family");
    if (count > (int)fam->ncodes) count = (int)fam->ncodes;
    mr_image *imgs = calloc((size_t)count, sizeof *imgs);
    bool ok = imgs != NULL;
    for (int i = 0; ok && i < count; i++) {
        image_u8_t *im = apriltag_to_image(fam, i);
        ok = im && mr_image_alloc(&imgs[i], im->width, im->height, 1, MR_PIX_U8, err);
        for (int y = 0; ok && y < im->height; y++)
            memcpy((unsigned char *)imgs[i].data + (size_t)y * im->width, im->buf + (size_t)y * im->stride,
                   (size_t)im->width);
        if (im) image_u8_destroy(im);
    }
    /* The image spans total_width cells; the black square spans
     * width_at_border; the rest is the white quiet zone around it. */
    *border = (fam->total_width - fam->width_at_border) / 2;
    tag36h11_destroy(fam);
    if (!ok) {
        mr_demo_tag_images_free(imgs, count);
        return err && err->code ? false : mr_fail(err, MR_ERR_NOMEM, "cannot render AprilTag images");
    }
    *out = imgs;
    return true;
}

void mr_demo_tag_images_free(mr_image *imgs, int count) {
    if (!imgs) return;
    for (int i = 0; i < count; i++) mr_image_free(&imgs[i]);
    free(imgs);
}

/* The demo tablet camera: 640x480, ~65 degrees horizontal, mild barrel
 * distortion as a real tablet lens has. */
mr_camera mr_demo_camera(void) {
    mr_camera c = {640, 480, 500.0, 500.0, 319.5, 239.5, {-0.10, 0.04, 0.0005, -0.0005, 0.0}};
    return c;
}

/* Standing viewpoints at eye height, looking at different parts of the
 * hall (tags, machines, the partition with the pipes behind it): eye, then
 * look-at target. */
static const double k_views[][6] = {
    {-4.0, 1.6, -2.0, -14.0, 2.0, 8.0},  /* the partition: pipes hidden behind it */
    {12.0, 1.7, 9.0, -4.0, 1.6, -9.0},   /* down the hall from the south-east */
    {0.0, 1.6, 6.0, 0.0, 2.2, -12.0},    /* the north wall and its tags */
    {16.0, 1.6, -9.0, -8.0, 1.5, 6.0},   /* under the suspended ceiling */
    {-2.0, 7.5, -11.0, -8.0, 0.0, 6.0},  /* overview from high up */
};
#define DEMO_VIEWS (int)(sizeof k_views / sizeof k_views[0])
_Static_assert(DEMO_VIEWS == MR_DEMO_VIEWS, "MR_DEMO_VIEWS names the rows of k_views");

int mr_demo_view_count(void) { return DEMO_VIEWS; }

mr_view mr_demo_view(int i) {
    mr_view v;
    v.camera = mr_demo_camera();
    i = i < 0 ? 0 : i >= DEMO_VIEWS ? DEMO_VIEWS - 1 : i;
    v.world_from_camera = mr_m4_look_at_cv(mr_v3(k_views[i][0], k_views[i][1], k_views[i][2]),
                                           mr_v3(k_views[i][3], k_views[i][4], k_views[i][5]), mr_v3(0, 1, 0));
    return v;
}

bool mr_demo_build_tagged(const mr_demo_params *params, int tag_count, mr_demo_hall *hall, mr_error *err) {
    mr_image *tags = NULL;
    int border = 1;
    memset(hall, 0, sizeof *hall);
    if (tag_count <= 0) tag_count = MR_DEMO_TAGS;
    if (!mr_demo_tag_images(tag_count, &tags, &border, err)) return false;
    mr_demo_params dp = params ? *params : (mr_demo_params)MR_DEMO_DEFAULTS;
    dp.tag_images = tags;
    dp.tag_image_count = tag_count;
    dp.tag_border_px = border;
    bool ok = mr_demo_build(&dp, hall, err);
    mr_demo_tag_images_free(tags, tag_count);
    return ok;
}

bool mr_demo_camera_frame(const mr_camera *cam, const mr_image *ideal, int n, int margin, int scale, double gain,
                          double noise, mr_rng *rng, mr_image *out, mr_error *err) {
    size_t np = (size_t)cam->width * cam->height;
    float *acc = calloc(np * 3, sizeof *acc), *tmp = malloc(np * 3 * sizeof *tmp);
    if (!acc || !tmp || !mr_image_alloc(out, cam->width, cam->height, 3, MR_PIX_U8, err)) {
        free(acc);
        free(tmp);
        return err && err->code ? false : mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    /* Each camera pixel looks up where its undistorted ray lands in the
     * wide, supersampled pinhole renders (bilinear), averaged over the n
     * sub-frames. */
    for (int v = 0; v < cam->height; v++)
        for (int u = 0; u < cam->width; u++) {
            double x, y;
            float sum[3] = {0, 0, 0};
            if (mr_camera_undistort(cam, (u - cam->cx) / cam->fx, (v - cam->cy) / cam->fy, &x, &y)) {
                double iu = (cam->fx * x + cam->cx + margin + 0.5) * scale - 0.5;
                double iv = (cam->fy * y + cam->cy + margin + 0.5) * scale - 0.5;
                for (int k = 0; k < n; k++) {
                    float px[4] = {0, 0, 0, 0};
                    mr_image_sample_bilinear(&ideal[k], iu, iv, px);
                    for (int c = 0; c < 3; c++) sum[c] += px[c] / (float)n;
                }
            }
            memcpy(&acc[((size_t)v * cam->width + u) * 3], sum, sizeof sum);
        }
    /* The lens's optical blur: a separable [1 2 1] / 4, edges clamped. */
    for (int pass = 0; pass < 2; pass++) {
        const float *src = pass ? tmp : acc;
        float *dst = pass ? acc : tmp;
        int du = pass ? 0 : 1, dv = pass ? 1 : 0;
        for (int v = 0; v < cam->height; v++)
            for (int u = 0; u < cam->width; u++) {
                int u0 = u - du < 0 ? u : u - du, u1 = u + du >= cam->width ? u : u + du;
                int v0 = v - dv < 0 ? v : v - dv, v1 = v + dv >= cam->height ? v : v + dv;
                for (int c = 0; c < 3; c++)
                    dst[((size_t)v * cam->width + u) * 3 + c] = 0.25f * src[((size_t)v0 * cam->width + u0) * 3 + c] +
                                                                0.5f * src[((size_t)v * cam->width + u) * 3 + c] +
                                                                0.25f * src[((size_t)v1 * cam->width + u1) * 3 + c];
            }
    }
    unsigned char *o = out->data;
    for (size_t i = 0; i < np * 3; i++) {
        double val = acc[i] * gain + noise * mr_rng_normal(rng);
        o[i] = (unsigned char)(val < 0 ? 0 : val > 255 ? 255 : lrint(val));
    }
    free(acc);
    free(tmp);
    return true;
}

mr_camera mr_demo_wide_camera(const mr_camera *cam, int margin) {
    mr_camera wide = *cam;
    wide.width += 2 * margin;
    wide.height += 2 * margin;
    wide.cx += margin;
    wide.cy += margin;
    memset(wide.dist, 0, sizeof wide.dist);
    return wide;
}
