/* issue 17 (lane bench): the image difference off depth edges
 * (mr_image_diff_depth), which bench scene --unique reports for each
 * configuration against the full-detail image. Small synthetic images: a
 * floor (a depth ramp) with a box standing in front of it. */
#include "mr_eval.h"
#include "mr_test.h"

enum { W = 40, H = 30 };

typedef struct pic {
    mr_image color, depth;
} pic;

/* The floor as a camera sees a plane at a grazing angle: inverse depth
 * affine in the row, depth from 3 at the bottom to 30 at the horizon (up to
 * 40 % from one row to the next there, no edge for all that); a box of
 * colour `box` at depth 1 covering [x0, x1) x [y0, y1) (empty when x1 <=
 * x0); `sky_rows` rows at the top show nothing. */
static void draw(pic *p, int x0, int x1, int y0, int y1, const unsigned char box[3], int sky_rows) {
    mr_image_alloc(&p->color, W, H, 3, MR_PIX_U8, NULL);
    mr_image_alloc(&p->depth, W, H, 1, MR_PIX_F32, NULL);
    unsigned char *c = p->color.data;
    float *z = p->depth.data;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            size_t i = (size_t)y * W + x;
            bool in_box = x >= x0 && x < x1 && y >= y0 && y < y1;
            bool sky = y < sky_rows;
            double t = (double)(H - 1 - y) / (H - 5); /* 0 at the bottom, 1 at row 4 */
            z[i] = in_box ? 1.0f : sky ? 0.0f : (float)(1.0 / (1.0 / 3 + t * (1.0 / 30 - 1.0 / 3)));
            for (int k = 0; k < 3; k++) c[3 * i + k] = in_box ? box[k] : sky ? 200 : (unsigned char)(60 + y);
        }
}

static void drop(pic *p) {
    mr_image_free(&p->color);
    mr_image_free(&p->depth);
}

static mr_image_diff diff(const pic *a, const pic *b) {
    mr_image_diff d;
    mr_error err = {0};
    bool ok = mr_image_diff_depth(&a->color, &a->depth, &b->color, &b->depth, NULL, &d, &err);
    CHECK_MSG(ok, "%s", err.msg);
    return d;
}

static const unsigned char k_red[3] = {220, 30, 30};

static void test_identical(void) {
    pic a, b;
    draw(&a, 10, 20, 8, 20, k_red, 4);
    draw(&b, 10, 20, 8, 20, k_red, 4);
    mr_image_diff d = diff(&a, &b);
    CHECK(d.pixels == W * H);
    CHECK(d.differ == 0 && d.differ_pct == 0);
    /* The box outline and the horizon are depth edges, the ramp is not. */
    CHECK(d.edge > 0 && d.edge < W * H / 2);
    drop(&a);
    drop(&b);
}

/* A silhouette one pixel off (a 1 px LOD error): nothing counted. */
static void test_one_pixel_silhouette(void) {
    pic a, b;
    draw(&a, 10, 20, 8, 20, k_red, 4);
    draw(&b, 11, 21, 8, 21, k_red, 4);
    mr_image_diff d = diff(&a, &b);
    CHECK_MSG(d.differ == 0, "%lld pixels counted for a 1 px silhouette shift", d.differ);
    drop(&a);
    drop(&b);
}

/* The box moved by 6 px: the strips it left and entered, off the edges of
 * either image, count. Left strip: columns 10..15 are box in a, floor in
 * b; column 10 is a's outline, column 15 lies next to b's box (16), rows 8
 * and 19 are a's outline: columns 11..14 x rows 9..18 count (4 x 10). The
 * same on the right: columns 20..25 less 20 (next to a's box) and 25 (b's
 * outline). 80 in all. */
static void test_moved_object(void) {
    pic a, b;
    draw(&a, 10, 20, 8, 20, k_red, 4);
    draw(&b, 16, 26, 8, 20, k_red, 4);
    mr_image_diff d = diff(&a, &b);
    CHECK_MSG(d.differ == 2 * 4 * 10, "moved box: %lld pixels differ, expected 80", d.differ);
    CHECK_NEAR(d.differ_pct, 100.0 * 80 / (W * H), 1e-9);
    drop(&a);
    drop(&b);
}

/* A box culled away: its inside counts, its outline does not. */
static void test_missing_object(void) {
    pic a, b;
    draw(&a, 10, 20, 8, 20, k_red, 4);
    draw(&b, 0, 0, 0, 0, k_red, 4);
    mr_image_diff d = diff(&a, &b);
    CHECK_MSG(d.differ == 8 * 10, "missing box: %lld pixels differ, expected 80", d.differ);
    drop(&a);
    drop(&b);
}

/* The colour tolerance: 8 levels pass, 9 do not (on one channel). */
static void test_tolerance(void) {
    pic a, b;
    draw(&a, 10, 20, 8, 20, k_red, 4);
    const unsigned char near[3] = {220, 38, 30}, far[3] = {220, 39, 30};
    draw(&b, 10, 20, 8, 20, near, 4);
    CHECK(diff(&a, &b).differ == 0);
    drop(&b);
    draw(&b, 10, 20, 8, 20, far, 4);
    CHECK_MSG(diff(&a, &b).differ == 8 * 10, "one channel 9 levels off: %lld", diff(&a, &b).differ);
    mr_image_diff_params p = MR_IMAGE_DIFF_DEFAULTS;
    mr_image_diff d;
    p.tolerance = 0;
    CHECK(mr_image_diff_depth(&a.color, &a.depth, &a.color, &a.depth, &p, &d, NULL) && d.differ == 0);
    drop(&a);
    drop(&b);
}

/* Which pixels are edges: the horizon (rows 3 and 4: coverage) and the
 * box's outline on both sides (columns 9..20 x rows 7..20 less the inside
 * 11..18 x 9..18); the grazing floor is none. A depth_rel above the box's
 * step (1/z: 1 against 0.33..0.03) leaves the outline uncounted: a missing
 * box then counts whole (10 x 12). */
static void test_edges(void) {
    pic a, b;
    draw(&a, 10, 20, 8, 20, k_red, 4);
    draw(&b, 0, 0, 0, 0, k_red, 4);
    mr_image_diff d = diff(&a, &a);
    CHECK_MSG(d.edge == 2 * W + 12 * 14 - 8 * 10, "%lld edge pixels, expected %d", d.edge, 2 * W + 12 * 14 - 8 * 10);
    d = diff(&b, &b);
    CHECK_MSG(d.edge == 2 * W, "floor alone: %lld edge pixels, expected the horizon's %d", d.edge, 2 * W);
    mr_image_diff_params p = MR_IMAGE_DIFF_DEFAULTS;
    p.depth_rel = 100;
    CHECK(mr_image_diff_depth(&a.color, &a.depth, &b.color, &b.depth, &p, &d, NULL));
    CHECK_MSG(d.differ == 10 * 12 && d.edge == 2 * W, "depth_rel 100: %lld differ, %lld edges", d.differ, d.edge);
    drop(&a);
    drop(&b);
}

/* Non-finite depth reads as nothing; bad input is refused. */
static void test_bad_input(void) {
    pic a, b;
    draw(&a, 10, 20, 8, 20, k_red, 4);
    draw(&b, 10, 20, 8, 20, k_red, 0);
    float *z = b.depth.data;
    for (int i = 0; i < 4 * W; i++) z[i] = (float)NAN; /* the sky as NaN instead of 0 */
    unsigned char *c = b.color.data;
    for (int i = 0; i < 4 * W * 3; i++) c[i] = 200;
    mr_image_diff d = diff(&a, &b);
    CHECK_MSG(d.differ == 0, "NaN sky: %lld", d.differ);
    mr_error err = {0};
    mr_image small;
    mr_image_alloc(&small, W - 1, H, 3, MR_PIX_U8, NULL);
    CHECK(!mr_image_diff_depth(&small, &a.depth, &b.color, &b.depth, NULL, &d, &err) && err.code == MR_ERR_INVALID);
    CHECK(!mr_image_diff_depth(&a.depth, &a.depth, &b.color, &b.depth, NULL, &d, &err));
    mr_image_diff_params p = {.tolerance = NAN, .depth_rel = 0.02};
    CHECK(!mr_image_diff_depth(&a.color, &a.depth, &b.color, &b.depth, &p, &d, &err));
    mr_image_free(&small);
    drop(&a);
    drop(&b);
}

int main(void) {
    test_identical();
    test_one_pixel_silhouette();
    test_moved_object();
    test_missing_object();
    test_tolerance();
    test_edges();
    test_bad_input();
    return mr_test_finish("test_image_diff");
}
