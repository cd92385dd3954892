/* The synthetic calibration board: a grid of tag36h11 tags on a plane and
 * its CPU ray-cast rendering through a distorted camera (the calibration
 * set of `mrcheck synth --calibration` and `mrcheck demo`). Ray casting,
 * not the GL renderer: the board needs exact lens distortion and nothing
 * else, so no GPU is needed for it. */
#include "mr_scene.h"

#include <math.h>

int mr_demo_board_tag(int i, mr_dmat4 *board_from_tag) {
    int r = i / MR_DEMO_BOARD_COLS, c = i % MR_DEMO_BOARD_COLS;
    if (board_from_tag) *board_from_tag = mr_m4_translate(c * MR_DEMO_BOARD_PITCH, r * MR_DEMO_BOARD_PITCH, 0);
    return MR_DEMO_BOARD_FIRST_ID + i;
}

/* The grey level the board shows at board point (px, py): white board,
 * black/white tag cells, or -1 off the board. */
static double board_value(double px, double py, const mr_image *tag_imgs) {
    const double plate = MR_DEMO_BOARD_TAG * 10.0 / 8.0; /* the tag with its white border: 10 cells */
    const double x0 = -MR_DEMO_BOARD_PITCH, x1 = MR_DEMO_BOARD_COLS * MR_DEMO_BOARD_PITCH;
    const double y0 = -MR_DEMO_BOARD_PITCH, y1 = MR_DEMO_BOARD_ROWS * MR_DEMO_BOARD_PITCH;
    if (!(px >= x0 && px <= x1 && py >= y0 && py <= y1)) return -1;
    int c = (int)floor(px / MR_DEMO_BOARD_PITCH + 0.5), r = (int)floor(py / MR_DEMO_BOARD_PITCH + 0.5);
    if (c < 0 || r < 0 || c >= MR_DEMO_BOARD_COLS || r >= MR_DEMO_BOARD_ROWS) return 230;
    double lx = px - c * MR_DEMO_BOARD_PITCH, ly = py - r * MR_DEMO_BOARD_PITCH;
    int cx = (int)floor((lx / plate + 0.5) * 10), cy = (int)floor((ly / plate + 0.5) * 10);
    if (cx < 0 || cy < 0 || cx >= 10 || cy >= 10) return 230;
    const mr_image *ti = &tag_imgs[r * MR_DEMO_BOARD_COLS + c];
    return ((const unsigned char *)ti->data)[cy * ti->width + cx] ? 230 : 25;
}

bool mr_demo_board_render(const mr_camera *cam, const mr_dmat4 *board_from_camera, const mr_image *tag_imgs,
                          mr_rng *rng, mr_image *out, mr_error *err) {
    if (!mr_image_alloc(out, cam->width, cam->height, 1, MR_PIX_U8, err)) return false;
    unsigned char *o = out->data;
    const mr_dvec3 oc = mr_m4_point(board_from_camera, mr_v3(0, 0, 0));
    for (int v = 0; v < cam->height; v++)
        for (int u = 0; u < cam->width; u++) {
            double acc = 0;
            for (int sy = 0; sy < 3; sy++)
                for (int sx = 0; sx < 3; sx++) {
                    double uu = u + (sx - 1) / 3.0, vv = v + (sy - 1) / 3.0, x, y, val = 40; /* background */
                    if (mr_camera_undistort(cam, (uu - cam->cx) / cam->fx, (vv - cam->cy) / cam->fy, &x, &y)) {
                        mr_dvec3 d = mr_m4_dir(board_from_camera, mr_v3(x, y, 1));
                        double t = fabs(d.z) > 1e-12 ? -oc.z / d.z : -1;
                        if (t > 0) {
                            double b = board_value(oc.x + t * d.x, oc.y + t * d.y, tag_imgs);
                            if (b >= 0) val = b;
                        }
                    }
                    acc += val;
                }
            double g = acc / 9 + 1.5 * mr_rng_normal(rng);
            o[(size_t)v * cam->width + u] = (unsigned char)(g < 0 ? 0 : g > 255 ? 255 : lrint(g));
        }
    return true;
}
