/* Shading of the G-buffer: Lambert + ambient, and the optional Phong
 * specular term (Scheer & Keutel's D1 is "standard Phong shading"), checked
 * against the closed form on a wall facing the camera: with the light
 * straight behind the camera the mirror direction is the view direction,
 * so the highlight adds exactly specular * light colour; with the light
 * 30 degrees off the normal, r is 30 degrees off the view direction:
 * specular * light colour * cos(30 deg)^shininess (0.010 at 32, 0.866 at 1).
 * Skips (77) without an EGL device. */
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"

#include <math.h>

static double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4); }

/* Linear value of the centre pixel (green channel) of the wall, lit by one
 * light whose direction (towards the light, world = camera axes) is d. */
static double centre(mr_renderer *r, mr_scene *s, const double d[3], float specular, float shininess) {
    s->light_count = 1;
    for (int k = 0; k < 3; k++) s->lights[0].direction[k] = d[k];
    s->lights[0].color[0] = s->lights[0].color[1] = s->lights[0].color[2] = 0.4f;
    mr_view v = {{64, 48, 60, 60, 31.5, 23.5, {0}}, mr_m4_identity()};
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.specular = specular;
    p.shininess = shininess;
    mr_frame_result res;
    mr_error err = {0};
    if (!mr_renderer_set_scene(r, s, &err) || !mr_render_frame(r, &v, &p, &res, &err)) {
        CHECK_MSG(false, "render: %s", err.msg);
        return NAN;
    }
    double g = srgb_decode(((const unsigned char *)res.color.data)[(24 * 64 + 32) * 3 + 1] / 255.0);
    mr_frame_result_free(&res);
    return g;
}

int main(void) {
    mr_error err = {0};
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) return mr_test_no_gpu("test_shade", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    if (r) {
        mr_scene *s = mr_scene_create();
        mr_material m = {"wall", {0.5f, 0.5f, 0.5f, 1}, -1, false};
        int32_t mi = mr_scene_add_material(s, &m);
        /* A wall across the view at z = 5 (camera axes: z forward), its
         * front face towards the camera. */
        mr_test_add_node(s, "Wall", mr_m4_translate(0, 0, 5), mr_test_add_box(s, 20, 20, 0.1, mi), MR_LAYER_VISIBLE);
        s->ambient = 0.2f;
        mr_scene_update_bounds(s);
        const double behind[3] = {0, 0, -1}, off[3] = {0, -0.5, -0.8660254};
        const double albedo = 0.5, lc = 0.4, amb = 0.2;
        double lambert = centre(r, s, behind, 0, 0), mirror = centre(r, s, behind, 0.5f, 32),
               tilted = centre(r, s, off, 0.5f, 32), tilted0 = centre(r, s, off, 0, 0);
        printf("  wall centre (linear): Lambert %.4f, Phong mirror %.4f, Phong 30 deg off %.4f (Lambert %.4f)\n", lambert,
               mirror, tilted, tilted0);
        const double tol = 0.006; /* 8-bit sRGB near 0.3..0.6 linear */
        CHECK_MSG(fabs(lambert - albedo * (amb + lc)) < tol, "Lambert %.4f, want %.4f", lambert, albedo * (amb + lc));
        CHECK_MSG(fabs(mirror - (albedo * (amb + lc) + 0.5 * lc)) < tol,
                  "Phong highlight in the mirror direction %.4f, want %.4f", mirror, albedo * (amb + lc) + 0.5 * lc);
        CHECK_MSG(fabs(tilted0 - albedo * (amb + lc * 0.8660254)) < tol, "Lambert 30 deg off %.4f, want %.4f", tilted0,
                  albedo * (amb + lc * 0.8660254));
        double c30 = 0.8660254, want32 = albedo * (amb + lc * c30) + 0.5 * lc * pow(c30, 32);
        CHECK_MSG(fabs(tilted - want32) < tol, "Phong 30 deg off, shininess 32: %.4f, want %.4f", tilted, want32);
        double wide = centre(r, s, off, 0.5f, 1), want1 = albedo * (amb + lc * c30) + 0.5 * lc * c30;
        CHECK_MSG(fabs(wide - want1) < tol, "Phong 30 deg off, shininess 1: %.4f, want %.4f", wide, want1);
        mr_renderer_set_scene(r, NULL, NULL);
        mr_scene_destroy(&s);
    }
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return mr_test_finish("test_shade");
}
