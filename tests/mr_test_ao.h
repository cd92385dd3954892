/* mr_test_ao.h — the AO tests' shared scene, view and measures (test_ao,
 * test_ao_deint): the concave corner (floor, a wall, a cube), the view of
 * it, one AO frame, the closed form beside the wall (include after
 * mr_test.h and mr_test_scene.h). */
#ifndef MR_TEST_AO_H
#define MR_TEST_AO_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mr_eval.h"
#include "mr_render.h"

/* A root node drawing mesh at (x, y, z) times k, moved by off; named nN. */
static inline void mr_test_ao_place(mr_scene *s, int32_t mesh, double k, mr_dvec3 off, double x, double y, double z) {
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "n%d", (int)s->node_count);
    n.parent = -1;
    n.world = mr_m4_translate(off.x + x * k, off.y + y * k, off.z + z * k);
    n.mesh_first = mesh;
    n.mesh_count = 1;
    mr_scene_add_node(s, &n);
}

/* Floor (top at y = 0), a wall whose face is the plane z = 2.9 standing on
 * it (a concave corner), and a cube; all lengths times k, moved by off. */
static inline mr_scene *mr_test_ao_corner_scene(double k, mr_dvec3 off, bool with_wall) {
    mr_scene *s = mr_scene_create();
    mr_test_ao_place(s, mr_test_add_box(s, 20 * k, 0.2 * k, 20 * k, -1), k, off, 0, -0.1, 0);
    if (with_wall) {
        mr_test_ao_place(s, mr_test_add_box(s, 20 * k, 6 * k, 0.2 * k, -1), k, off, 0, 3, 3.0);
        mr_test_ao_place(s, mr_test_add_box(s, 1 * k, 1 * k, 1 * k, -1), k, off, -1.5, 0.5, 1.0);
    }
    mr_scene_update_bounds(s);
    return s;
}

static inline mr_view mr_test_ao_corner_view(double k, mr_dvec3 off, int w, int h) {
    mr_view v;
    mr_camera c = {w, h, 0.8 * w, 0.8 * w, (w - 1) / 2.0, (h - 1) / 2.0, {0, 0, 0, 0, 0}};
    v.camera = c;
    v.world_from_camera = mr_m4_look_at_cv(mr_v3(off.x + 0.7 * k, off.y + 2.2 * k, off.z - 2.5 * k),
                                           mr_v3(off.x + 0.2 * k, off.y + 0.2 * k, off.z + 2.5 * k), mr_v3(0, 1, 0));
    return v;
}

/* World point of pixel (x, y) of a rendered frame (depth > 0). */
static inline mr_dvec3 mr_test_pixel_world(const mr_view *v, const mr_image *depth, int x, int y) {
    mr_camera c = mr_camera_resized(&v->camera, depth->width, depth->height);
    double z = ((const float *)depth->data)[(size_t)y * depth->width + x];
    return mr_m4_point(&v->world_from_camera, mr_v3((x - c.cx) / c.fx * z, (y - c.cy) / c.fy * z, z));
}

/* One frame of scene s on r with ao (AO, depth and normals kept). */
static inline bool mr_test_render_ao(mr_renderer *r, const mr_scene *s, const mr_view *v, const mr_ao_params *ao,
                                     mr_frame_result *res) {
    mr_frame_params p = MR_FRAME_DEFAULTS;
    p.ao = *ao;
    p.ao.want_ao = true;
    p.want_depth = p.want_normals = true;
    mr_error err = {0};
    bool ok = mr_renderer_set_scene(r, s, &err) && mr_render_frame(r, v, &p, res, &err);
    CHECK_MSG(ok, "%s", err.msg);
    return ok;
}

/* Pixels of an AO image outside [0, 1] (NaN included). */
static inline int mr_test_ao_count_bad(const mr_image *ao) {
    int bad = 0;
    const float *a = ao->data;
    for (int i = 0; i < ao->width * ao->height; i++) bad += !(a[i] >= 0 && a[i] <= 1);
    return bad;
}

/* RMSE of an AO image against the closed form beside the wall, over floor
 * pixels in front of it (dist < 1, away from the cube and the image's
 * ends), for the view radius R or the depth-scaled one (screen > 0). */
static inline double mr_test_ao_wall_rmse(const mr_view *v, const mr_frame_result *g, const mr_image *ao, double R,
                                          double screen, int *count) {
    mr_camera c = mr_camera_resized(&v->camera, g->depth.width, g->depth.height);
    double se = 0;
    int n = 0;
    const float *a = ao->data, *d = g->depth.data;
    for (int y = 0; y < g->depth.height; y++)
        for (int x = 0; x < g->depth.width; x++) {
            size_t i = (size_t)y * g->depth.width + x;
            if (!(d[i] > 0)) continue;
            mr_dvec3 p = mr_test_pixel_world(v, &g->depth, x, y);
            double dist = 2.9 - p.z, r = screen > 0 ? screen * d[i] * c.height / c.fy : R;
            if (fabs(p.y) > 0.01 || dist < 0 || dist > 1.0 || p.x < -0.5 || p.x > 5) continue;
            double e = a[i] - mr_eval_ao_wall_analytic(dist, r);
            se += e * e;
            n++;
        }
    if (count) *count = n;
    return n ? sqrt(se / n) : 1e9;
}

/* The slice methods' wall setting (test_ao's closed-form check, issue 18):
 * radius 0.6 (view) or 0.1 (screen), 64 samples unblurred, a thick wall;
 * scheer-gt and scheer-bm with c = 0 (and scheer-gt bias 0) reduce to the
 * closed form of GTAO and the bitmask. */
static inline mr_ao_params mr_test_ao_wall_params(mr_ao_method m, bool view_radius) {
    mr_ao_params ao = MR_AO_DEFAULTS;
    ao.method = m;
    ao.radius_mode = view_radius ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
    ao.radius = 0.6;
    ao.screen_radius = 0.1;
    ao.samples = 64;
    ao.thickness = 2.0f; /* the wall is thick */
    ao.blur_radius = 0;  /* the bilateral blur mixes the wall's AO into the floor's */
    if (m == MR_AO_SCHEER_GT) ao.c = 0, ao.bias = 0;
    if (m == MR_AO_SCHEER_BM) ao.c = 0;
    return ao;
}

/* One frame with ao beside the wall: > 100 floor pixels in front of it,
 * within 0.025 RMSE of the closed form, no value outside [0, 1]. */
static inline void mr_test_ao_wall_check(mr_renderer *r, const mr_scene *s, const mr_view *v, const mr_ao_params *ao,
                                         const char *what) {
    mr_frame_result res;
    if (!mr_test_render_ao(r, s, v, ao, &res)) return;
    int n = 0;
    bool view = ao->radius_mode == MR_AO_RADIUS_VIEW;
    double e = mr_test_ao_wall_rmse(v, &res, &res.ao, ao->radius, view ? 0 : ao->screen_radius, &n);
    if (getenv("MR_TEST_VERBOSE")) printf("wall %s: RMSE %.4f over %d pixels\n", what, e, n);
    CHECK_MSG(n > 100, "only %d floor pixels in front of the wall", n);
    CHECK_MSG(e < 0.025, "%s beside a wall: RMSE %.4f against the closed form", what, e);
    CHECK(mr_test_ao_count_bad(&res.ao) == 0);
    mr_frame_result_free(&res);
}

#endif
