/* mr_renderer_pick: a tap on the screen names the part and the world point
 * under it, read back from the G-buffer. Checked against planes at known
 * depths, at a far offset and at a tiny scale, plus misses and bad input. */
#include "mr_test.h"
#include "mr_test_scene.h"

#include "mr_render.h"

#include <string.h>



/* Two planes facing a camera at `offset` looking down +z: a wall (visible)
 * filling the left half at depth 4*scale, a panel (hidden layer) on the
 * right at depth 2*scale. */
static void check_case(mr_renderer *r, double scale, mr_dvec3 offset) {
    mr_scene *s = mr_scene_create();
    int32_t q = mr_test_add_quad(s, 4 * scale, 6 * scale, -1, false);
    mr_dmat4 w1 = mr_m4_translate(offset.x - 2 * scale, offset.y, offset.z + 4 * scale);
    mr_dmat4 w2 = mr_m4_translate(offset.x + 2 * scale, offset.y, offset.z + 2 * scale);
    mr_test_add_node(s, "wall", w1, q, MR_LAYER_VISIBLE);
    mr_test_add_node(s, "panel", w2, q, MR_LAYER_HIDDEN);
    mr_scene_update_bounds(s);
    mr_error err = {0};
    CHECK_MSG(mr_renderer_set_scene(r, s, &err), "%s", err.msg);
    mr_view v;
    mr_camera cam = {200, 100, 100, 100, 99.5, 49.5, {0, 0, 0, 0, 0}};
    v.camera = cam;
    /* OpenCV axes: x right, y down, z forward; identity rotation. */
    v.world_from_camera = mr_m4_translate(offset.x, offset.y, offset.z);
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    mr_frame_result res;
    CHECK_MSG(mr_render_frame(r, &v, &fp, &res, &err), "%s", err.msg);
    mr_frame_result_free(&res);
    mr_pick pk;
    /* Pixel 50 (left half): the wall at depth 4*scale; x = (50 - 99.5)/100 * z. */
    CHECK_MSG(mr_renderer_pick(r, 50, 49.5, &pk, &err), "%s", err.msg);
    CHECK(pk.hit && pk.node == 0 && pk.layer == MR_LAYER_VISIBLE);
    CHECK_NEAR(pk.depth, 4 * scale, 1e-4 * scale);
    CHECK_NEAR(pk.world.z - offset.z, 4 * scale, 1e-4 * scale);
    CHECK_NEAR(pk.world.x - offset.x, (50 - 99.5) / 100 * 4 * scale, 2e-4 * scale);
    CHECK_NEAR(pk.world.y - offset.y, 0, 2e-4 * scale);
    /* Pixel 150 (right half): the hidden panel, nearer. */
    CHECK(mr_renderer_pick(r, 150, 20, &pk, &err) && pk.hit && pk.node == 1 && pk.layer == MR_LAYER_HIDDEN);
    CHECK_NEAR(pk.depth, 2 * scale, 1e-4 * scale);
    CHECK_NEAR(pk.world.y - offset.y, (20 - 49.5) / 100 * 2 * scale, 2e-4 * scale);
    /* With the hidden layer left out, the right half is background. */
    fp.hide_hidden_layer = true;
    CHECK(mr_render_frame(r, &v, &fp, &res, &err));
    mr_frame_result_free(&res);
    CHECK(mr_renderer_pick(r, 150, 20, &pk, &err) && !pk.hit && pk.node == -1);
    /* Outside the frame, or not a number: refused with a message. */
    memset(&err, 0, sizeof err);
    CHECK(!mr_renderer_pick(r, 200, 20, &pk, &err) && err.code == MR_ERR_INVALID && err.msg[0]);
    CHECK(!mr_renderer_pick(r, -1, 20, &pk, &err));
    CHECK(!mr_renderer_pick(r, 0.0 / 0.0, 20, &pk, &err));
    mr_renderer_set_scene(r, NULL, &err);
    mr_scene_destroy(&s);
}

int main(void) {
    mr_error err = {0};
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) return mr_test_no_gpu("test_pick", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    if (r) {
        mr_pick pk;
        CHECK(!mr_renderer_pick(r, 1, 1, &pk, &err)); /* nothing rendered yet */
        check_case(r, 1.0, mr_v3(0, 0, 0));
        check_case(r, 1e-3, mr_v3(0, 0, 0));
        check_case(r, 1.0, mr_v3(1e7, -3e6, 2e7)); /* far from the origin: picks stay exact */
    }
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return mr_test_finish("test_pick");
}
