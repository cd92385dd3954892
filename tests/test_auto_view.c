/* `render --view auto` (lib/scene/auto_view.c): every vertex of a scene
 * projects inside the image, in front of the camera, at scales 1e-3, 1 and
 * 1e3 and at a 1e7 offset, for a long flat hall, a tall tower and a
 * cube; the frame is tight (a corner of the bounds lies on the margin),
 * seen from above. Then the binary draws one. */
#include "mr_test.h"
#include "mr_test_scene.h"

/* The binary under ASan unloads Mesa's driver at exit, whose globals then
 * look like a leak from an unknown module (tests/mr_test.h); the library
 * code it runs is leak-checked in this process, so the child skips it. */
#define MR_CHILD_ENV "ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\" "

/* Boxes of size (sx, sy, sz) * scale at a few places in a block, offset. */
static mr_scene *block(double sx, double sy, double sz, double scale, double off) {
    mr_scene *s = mr_scene_create();
    for (int i = 0; i < 3; i++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "b%d", i);
        n.parent = -1;
        double q[4] = {0, sin(0.3 * i), 0, cos(0.3 * i)}, t[3] = {off + (i - 1) * sx * scale, (i * 0.3) * sy * scale,
                                                                       off - (i - 1) * sz * scale * 0.5};
        double sc[3] = {1, 1, 1};
        n.world = mr_m4_from_trs(t, q, sc);
        n.mesh_first = mr_test_add_box(s, sx * scale, sy * scale, sz * scale, -1);
        n.mesh_count = 1;
        mr_scene_add_node(s, &n);
    }
    mr_scene_update_bounds(s);
    return s;
}

static void check_scene(const mr_scene *s, int w, int h, const char *what) {
    mr_view v = mr_scene_auto_view(s, w, h);
    CHECK(v.camera.width == (w ? w : MR_AUTO_VIEW_DEFAULT_WIDTH));
    CHECK(mr_m4_is_rigid(&v.world_from_camera, 1e-9));
    CHECK_MSG(v.world_from_camera.m[6] < -0.3, "%s: not looking down (%g)", what, v.world_from_camera.m[6]);
    mr_dmat4 cw = mr_m4_invert_rigid(&v.world_from_camera);
    double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
    int outside = 0;
    for (int32_t n = 0; n < s->node_count; n++) {
        const mr_node *nd = &s->nodes[n];
        for (int32_t k = 0; k < nd->mesh_count; k++) {
            const mr_mesh *m = &s->meshes[nd->mesh_first + k];
            for (uint32_t i = 0; i < m->vertex_count; i++) {
                const float *p = &m->positions[i * 3];
                mr_dvec3 wp = mr_m4_point(&nd->world, mr_v3(m->origin[0] + p[0], m->origin[1] + p[1], m->origin[2] + p[2]));
                mr_dvec3 c = mr_m4_point(&cw, wp);
                double u = v.camera.fx * c.x / c.z + v.camera.cx, vv = v.camera.fy * c.y / c.z + v.camera.cy;
                outside += !(c.z > 0 && u >= 0 && u <= v.camera.width - 1 && vv >= 0 && vv <= v.camera.height - 1);
                umin = fmin(umin, u), umax = fmax(umax, u), vmin = fmin(vmin, vv), vmax = fmax(vmax, vv);
            }
        }
    }
    CHECK_MSG(outside == 0, "%s: %d vertices outside (u %g..%g, v %g..%g)", what, outside, umin, umax, vmin, vmax);
    /* Tight: a corner of the bounds lies on the margin (the nearest
     * distance that frames them all). */
    double reach = 0;
    double mx = v.camera.cx - MR_AUTO_VIEW_MARGIN * v.camera.width, my = v.camera.cy - MR_AUTO_VIEW_MARGIN * v.camera.height;
    for (int c = 0; c < 8; c++) {
        mr_dvec3 p = mr_v3(c & 1 ? s->bounds_max[0] : s->bounds_min[0], c & 2 ? s->bounds_max[1] : s->bounds_min[1],
                           c & 4 ? s->bounds_max[2] : s->bounds_min[2]);
        mr_dvec3 q = mr_m4_point(&cw, p);
        reach = fmax(reach, fmax(fabs(v.camera.fx * q.x / q.z) / mx, fabs(v.camera.fy * q.y / q.z) / my));
    }
    CHECK_MSG(fabs(reach - 1) < 1e-6, "%s: the bounds reach %.9f of the margin", what, reach);
}

static void check_cli(void) {
    const char *mr = getenv("MR_MRCHECK");
    CHECK_MSG(mr && mr[0], "MR_MRCHECK (the mrcheck binary) is not set");
    char dir[1024];
    if (!mr || !mr[0] || !mr_test_fresh_dir("test_auto_view", dir, sizeof dir)) return;
    char glb[1200], out[1200], cmd[4096];
    snprintf(glb, sizeof glb, "%s/block.glb", dir);
    snprintf(out, sizeof out, "%s/auto.png", dir);
    mr_scene *s = block(4, 1, 2, 1, 1e7);
    mr_error err = {0};
    CHECK_MSG(mr_scene_save_glb(s, glb, &err), "%s", err.msg);
    mr_scene_destroy(&s);
    snprintf(cmd, sizeof cmd, MR_CHILD_ENV "'%s' render --scene '%s' --view auto --size 96x72 --out '%s'", mr, glb, out);
    int rc = system(cmd);
    if (WIFEXITED(rc) && WEXITSTATUS(rc) == 69) {
        printf("test_auto_view: SKIPPED (the render): no GL device\n");
        return;
    }
    CHECK_MSG(rc == 0, "%s: exit %d", cmd, rc);
    mr_image im = {0};
    if (!mr_image_load(out, 3, &im, &err)) {
        CHECK_MSG(0, "%s", err.msg);
        return;
    }
    /* Geometry in the image, and none on its border rows and columns. */
    int inside = 0, border = 0;
    const uint8_t *b = im.data; /* a corner: the background */
    for (int y = 0; y < im.height; y++)
        for (int x = 0; x < im.width; x++) {
            const uint8_t *p = (const uint8_t *)im.data + ((size_t)y * im.width + x) * 3;
            bool geo = abs(p[0] - b[0]) + abs(p[1] - b[1]) + abs(p[2] - b[2]) > 12;
            if (x == 0 || y == 0 || x == im.width - 1 || y == im.height - 1) border += geo;
            else inside += geo;
        }
    CHECK_MSG(inside > im.width * im.height / 10 && border == 0, "auto view: %d pixels of geometry, %d on the border",
              inside, border);
    mr_image_free(&im);
}

int main(void) {
    static const double scales[3] = {1e-3, 1, 1e3}, offsets[2] = {0, 1e7};
    static const double shapes[3][3] = {{100, 1, 10}, {2, 40, 2}, {3, 3, 3}}; /* hall, tower, cube */
    char what[128];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 2; j++)
            for (int k = 0; k < 3; k++) {
                mr_scene *s = block(shapes[k][0], shapes[k][1], shapes[k][2], scales[i], offsets[j]);
                snprintf(what, sizeof what, "shape %d scale %g offset %g", k, scales[i], offsets[j]);
                check_scene(s, 0, 0, what);
                check_scene(s, 320, 120, what);
                check_scene(s, 90, 160, what);
                mr_scene_destroy(&s);
            }
    /* An empty scene still gets a finite view. */
    mr_scene *e = mr_scene_create();
    mr_view v = mr_scene_auto_view(e, 0, 0);
    CHECK(mr_m4_is_finite(&v.world_from_camera) && v.camera.height == MR_AUTO_VIEW_DEFAULT_HEIGHT);
    mr_scene_destroy(&e);
    check_cli();
    return mr_test_finish("test_auto_view");
}
