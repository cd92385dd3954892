/* Multi-view rigs and quilts (lib/render/multiview.c): the issue's known
 * answers for the off-axis frusta, the views as pinhole cameras, the quilt
 * layout (view 0 bottom-left) and its name, bad input; on the GPU: N views
 * with one renderer, and AO that agrees across views with the world-position
 * noise better than with the pixel noise. */
#include "mr_test.h"
#include "mr_test_scene.h"

#include "mr_bench.h"
#include "mr_eval.h"
#include "mr_render.h"

/* The NDC of a camera-frame point through a pinhole camera as
 * mr_gl_projection makes it: x = 2 (fx X/Z + cx + 0.5) / W - 1. */
static void camera_ndc(const mr_camera *c, mr_dvec3 p, double ndc[2]) {
    ndc[0] = 2 * (c->fx * p.x / p.z + c->cx + 0.5) / c->width - 1;
    ndc[1] = 2 * (c->fy * p.y / p.z + c->cy + 0.5) / c->height - 1;
}

static void test_known_answers(void) {
    mr_rig_params p = MR_RIG_DEFAULTS;
    p.views = 48;
    double D = mr_rig_distance_for_size(p.fov_deg, 1.0);
    CHECK_NEAR(D, 8.14435, 5e-6);
    mr_rig rig;
    mr_error err = {0};
    CHECK(mr_rig_make(&p, 0.75, D, &rig, &err));
    CHECK_NEAR(rig.size, 1.0, 1e-12);
    CHECK_NEAR(mr_rig_shift(&rig, 0), -2.56790, 5e-6);
    CHECK_NEAR(mr_rig_shift(&rig, 47), 2.56790, 5e-6);
    CHECK_NEAR(mr_rig_angle(&rig, 0), -17.5 * 3.14159265358979 / 180, 1e-9);
    /* The focal plane's centre and corners land on the same NDC in every
     * view, through the frustum and through the view's pinhole camera. */
    const double corner[5][2] = {{0, 0}, {-0.75, -1}, {0.75, -1}, {-0.75, 1}, {0.75, 1}};
    mr_view centre;
    memset(&centre, 0, sizeof centre);
    centre.world_from_camera = mr_m4_identity();
    int bad = 0, bad_cam = 0, bad_edge = 0;
    for (int i = 0; i < 48; i++) {
        mr_view v = mr_rig_view(&rig, &centre, i, 64, 48);
        /* the eye sits at s_i on the centre camera's x axis */
        if (fabs(v.world_from_camera.m[3] - mr_rig_shift(&rig, i)) > 1e-12 || v.world_from_camera.m[7] != 0 ||
            v.world_from_camera.m[11] != 0)
            bad_cam++;
        for (int k = 0; k < 5; k++) {
            mr_dvec3 q = mr_v3(corner[k][0], corner[k][1], D);
            double a[2], b[2];
            mr_rig_project(&rig, i, q, a);
            mr_dvec3 qi = mr_m4_point(&(mr_dmat4){{1, 0, 0, -v.world_from_camera.m[3], 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}}, q);
            camera_ndc(&v.camera, qi, b);
            double want_x = corner[k][0] / 0.75, want_y = corner[k][1];
            if (fabs(a[0] - want_x) > 1e-12 || fabs(a[1] - want_y) > 1e-12) bad++;
            if (fabs(b[0] - want_x) > 1e-9 || fabs(b[1] - want_y) > 1e-9) bad_cam++;
        }
        /* The frustum's edges, scaled from the near plane to D and moved to
         * the rig's axes, meet the focal plane at the same rectangle. */
        double l, r, bo, t, n = 0.01;
        mr_rig_frustum(&rig, i, n, &l, &r, &bo, &t);
        double s = mr_rig_shift(&rig, i);
        if (fabs(l * D / n + s + 0.75) > 1e-12 || fabs(r * D / n + s - 0.75) > 1e-12 || fabs(bo * D / n + 1) > 1e-12 ||
            fabs(t * D / n - 1) > 1e-12)
            bad_edge++;
    }
    CHECK_MSG(bad == 0, "%d focal-plane points off their NDC (frustum)", bad);
    CHECK_MSG(bad_cam == 0, "%d focal-plane points off their NDC (pinhole view)", bad_cam);
    CHECK_MSG(bad_edge == 0, "%d frusta meet the focal plane elsewhere", bad_edge);
    /* A point on the axis behind the focal plane: left of centre in view 0. */
    double ndc[2];
    mr_rig_project(&rig, 0, mr_v3(0, 0, 1.1 * D), ndc);
    CHECK_NEAR(ndc[0], -0.311261, 5e-7);
    CHECK_NEAR(ndc[1], 0, 1e-12);
    mr_view v0 = mr_rig_view(&rig, &centre, 0, 64, 48);
    double b[2];
    camera_ndc(&v0.camera, mr_v3(0 - mr_rig_shift(&rig, 0), 0, 1.1 * D), b);
    CHECK_NEAR(b[0], -0.311261, 5e-7);
    /* One view: the plain centre camera, no shear. */
    p.views = 1;
    CHECK(mr_rig_make(&p, 0.75, D, &rig, &err));
    CHECK(mr_rig_shift(&rig, 0) == 0);
    /* Bad input: one line each. */
    p.views = 0;
    CHECK(!mr_rig_make(&p, 0.75, D, &rig, &err) && strstr(err.msg, "views"));
    p.views = 8;
    p.cone_deg = 180;
    CHECK(!mr_rig_make(&p, 0.75, D, &rig, &err) && strstr(err.msg, "cone"));
    p.cone_deg = 35;
    CHECK(!mr_rig_make(&p, 0.75, -1, &rig, &err) && strstr(err.msg, "focal"));
    CHECK(!mr_rig_make(&p, 0.75, NAN, &rig, &err));
}

static void test_quilt(void) {
    mr_error err = {0};
    mr_quilt q;
    mr_quilt_layout l;
    char name[128];
    /* Presets and the file name: the view aspect, not the tile's. */
    CHECK(mr_quilt_parse("portrait", &q, &err) && q.cols == 8 && q.rows == 6 && q.width == 3360);
    CHECK(mr_quilt_layout_make(&q, 48, 1, 1, &l, &err) && l.tile_w == 420 && l.tile_h == 560);
    mr_quilt_file_name("quilt", &l, name, sizeof name);
    CHECK_MSG(strcmp(name, "quilt_qs8x6a0.75.png") == 0, "%s", name);
    CHECK(mr_quilt_parse("go", &q, &err) && mr_quilt_layout_make(&q, 66, 1, 1, &l, &err) && l.tile_w == 372 && l.tile_h == 682);
    mr_quilt_file_name("x", &l, name, sizeof name);
    CHECK_MSG(strcmp(name, "x_qs11x6a0.5625.png") == 0, "%s", name);
    CHECK(mr_quilt_parse("5x3@100x60", &q, &err) && q.cols == 5 && q.rows == 3 && q.width == 100 && q.height == 60);
    /* Round trip: view i filled with i lands in its tile, view 0 bottom-left. */
    const int C = 5, R = 3, w = 8, h = 6;
    CHECK(mr_quilt_parse("5x3", &q, &err));
    CHECK(mr_quilt_layout_make(&q, 13, w, h, &l, &err) && l.width == C * w && l.height == R * h);
    mr_image quilt, view;
    CHECK(mr_image_alloc(&quilt, l.width, l.height, 3, MR_PIX_U8, &err));
    memset(quilt.data, 255, mr_image_bytes(&quilt));
    CHECK(mr_image_alloc(&view, w, h, 3, MR_PIX_U8, &err));
    for (int i = 0; i < 13; i++) {
        memset(view.data, i, mr_image_bytes(&view));
        CHECK(mr_quilt_put(&l, &quilt, i, &view, &err));
    }
    int bad = 0;
    const unsigned char *qd = quilt.data;
    for (int i = 0; i < 13; i++) {
        int x = (i % C) * w + w / 2, y = (R - 1 - i / C) * h + h / 2;
        if (qd[((size_t)y * quilt.width + x) * 3] != i) bad++;
    }
    CHECK_MSG(bad == 0, "%d views not in their tile", bad);
    /* view 0's tile is the bottom-left corner in PNG rows */
    CHECK(qd[((size_t)(quilt.height - 1) * quilt.width + 0) * 3] == 0);
    CHECK(qd[((size_t)(quilt.height - 1) * quilt.width + quilt.width - 1) * 3] == 4);
    CHECK(qd[0] == 10);
    /* the unused tiles stay as they were */
    CHECK(qd[((size_t)0 * quilt.width + quilt.width - 1) * 3] == 255);
    CHECK(!mr_quilt_put(&l, &quilt, 15, &view, &err));
    mr_image_free(&view);
    CHECK(mr_image_alloc(&view, w + 1, h, 3, MR_PIX_U8, &err));
    CHECK(!mr_quilt_put(&l, &quilt, 1, &view, &err)); /* wrong size */
    mr_image_free(&view);
    mr_image_free(&quilt);
    /* No spec: about square, enough tiles. */
    CHECK(mr_quilt_layout_make(NULL, 48, 4, 3, &l, &err) && l.cols == 7 && l.rows == 7);
    CHECK(mr_quilt_layout_make(NULL, 1, 4, 3, &l, &err) && l.cols == 1 && l.rows == 1);
    /* Bad input. */
    CHECK(mr_quilt_parse("8x6", &q, &err));
    CHECK(!mr_quilt_layout_make(&q, 49, 4, 3, &l, &err) && strstr(err.msg, "too few"));
    CHECK(mr_quilt_parse("8x6@4x4", &q, &err));
    CHECK(!mr_quilt_layout_make(&q, 48, 4, 3, &l, &err) && strstr(err.msg, "under one pixel"));
    const char *bad_specs[] = {"", "8", "8x", "0x6", "8x6@", "8x6@0x10", "8x6x", "lookingglass", "8 x 6", "-1x2"};
    for (size_t k = 0; k < sizeof bad_specs / sizeof bad_specs[0]; k++)
        CHECK_MSG(!mr_quilt_parse(bad_specs[k], &q, &err), "'%s' accepted", bad_specs[k]);
}

static void test_focal_from_depth(void) {
    mr_image d;
    mr_error err = {0};
    CHECK(mr_image_alloc(&d, 9, 9, 1, MR_PIX_F32, &err));
    float *z = d.data;
    for (int i = 0; i < 81; i++) z[i] = 100; /* the border is not looked at */
    for (int y = 3; y < 6; y++)
        for (int x = 3; x < 6; x++) z[y * 9 + x] = (float)(y == 4 ? 0 : 2 + (x - 3));
    CHECK_NEAR(mr_rig_focal_from_depth(&d), 3, 1e-6);
    memset(d.data, 0, mr_image_bytes(&d));
    CHECK(mr_rig_focal_from_depth(&d) == 0);
    mr_image_free(&d);
}


/* The display mapping on the CPU: exact round trip, the band error formula,
 * and that it is no pinhole (a straight line does not stay straight). */
static void test_display_cpu(void) {
    mr_camera c = {96, 72, 80, 80, 47.5, 35.5, {0, 0, 0, 0, 0}};
    mr_display_map m = {4.0, 4.0 * tan(17.5 * 3.14159265358979 / 180), 1};
    int bad = 0;
    for (int u = 0; u < 96; u += 5)
        for (double z = 0.5; z < 6; z += 0.37) {
            mr_dvec3 p = mr_display_point(&m, &c, u, 20, z);
            double uu, vv;
            if (!mr_display_project(&m, &c, p, &uu, &vv) || fabs(uu - u) > 1e-9 || fabs(vv - 20) > 1e-9) bad++;
        }
    CHECK_MSG(bad == 0, "%d display round trips off", bad);
    /* Band 1: exact at every pixel centre; band 8: |j| (E/A) |1 - D/z|. */
    double A = (c.width / 2.0) * m.distance / c.fx; /* half-width of the focal plane seen */
    double worst1 = 0, worst8 = 0, worst8_formula = 0;
    for (int u = 0; u < 96; u++)
        for (double z = 1; z < 8; z += 0.5) {
            worst1 = fmax(worst1, fabs(mr_display_column_error(&m, &c, u, z)));
            mr_display_map m8 = m;
            m8.band = 8;
            double e = fabs(mr_display_column_error(&m8, &c, u, z));
            double j = fabs(u % 8 - 3.5);
            double q = (m.eye_half / A) * (1 - m.distance / z);
            double want = j * fabs(q / (1 - q));
            if (fabs(e - want) > 1e-9 * (1 + want)) bad++;
            worst8 = fmax(worst8, e);
            worst8_formula = fmax(worst8_formula, want);
        }
    CHECK_MSG(worst1 < 1e-9, "band 1 off by %g px", worst1);
    CHECK_MSG(bad == 0, "%d band-8 errors off the formula", bad);
    CHECK(worst8 > 1.0);
    printf("display mapping: band 1 column error %.2g px, band 8 up to %.2f px (formula %.2f) for z in [1, 8), D = 4\n",
           worst1, worst8, worst8_formula);
    /* A straight 3D line (not through the eye line) is not straight in the
     * image: the middle point leaves the chord by more than a pixel. */
    mr_dvec3 a = mr_v3(-2, -1, 2), b = mr_v3(2, 1, 7), mid = mr_v3(0, 0, 4.5);
    double ua, va, ub, vb, um, vm;
    CHECK(mr_display_project(&m, &c, a, &ua, &va) && mr_display_project(&m, &c, b, &ub, &vb) &&
          mr_display_project(&m, &c, mid, &um, &vm));
    double cross = ((ub - ua) * (vm - va) - (vb - va) * (um - ua)) / hypot(ub - ua, vb - va);
    CHECK_MSG(fabs(cross) > 1.0, "the line stayed straight (%.3f px off the chord)", cross);
    /* The pinhole keeps it straight. */
    mr_display_map pin = m;
    pin.eye_half = 0;
    CHECK(mr_display_project(&pin, &c, a, &ua, &va) && mr_display_project(&pin, &c, b, &ub, &vb) &&
          mr_display_project(&pin, &c, mid, &um, &vm));
    cross = ((ub - ua) * (vm - va) - (vb - va) * (um - ua)) / hypot(ub - ua, vb - va);
    CHECK_NEAR(cross, 0, 1e-9);
}

/* ------------------------------------------------------------ GPU part */

static void add_node(mr_scene *s, mr_dmat4 m, int32_t mesh) { mr_test_add_node(s, "n", m, mesh, MR_LAYER_VISIBLE); }

/* A floor, a wall on it and two boxes, seen from above the floor. */
static mr_scene *rig_scene(void) {
    mr_scene *s = mr_scene_create();
    add_node(s, mr_m4_translate(0, -0.1, 0), mr_test_add_box(s, 20, 0.2, 20, -1));
    add_node(s, mr_m4_translate(0, 3, 3.0), mr_test_add_box(s, 20, 6, 0.2, -1));
    add_node(s, mr_m4_translate(-1.5, 0.5, 1.0), mr_test_add_box(s, 1, 1, 1, -1));
    add_node(s, mr_m4_translate(1.2, 0.4, 0.2), mr_test_add_box(s, 0.8, 0.8, 0.8, -1));
    mr_scene_update_bounds(s);
    return s;
}

/* Mean RMSE of AO between neighbouring views, AO reprojected through depth. */
static double rig_consistency(mr_renderer *r, const mr_rig *rig, const mr_view *centre, mr_ao_noise noise, int w, int h,
                              double *fraction) {
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = w;
    fp.height = h;
    fp.want_depth = true;
    fp.ao.method = MR_AO_CRYTEK;
    fp.ao.blur_radius = 0; /* the noise itself, not what the blur leaves of it */
    fp.ao.want_ao = true;
    fp.ao.noise = noise;
    fp.ao.noise_anchor = centre->world_from_camera;
    fp.ao.noise_anchor_set = true;
    mr_frame_result prev = {0}, cur;
    mr_view vprev = {0};
    mr_error err = {0};
    double sum = 0, fsum = 0;
    int pairs = 0;
    for (int i = 0; i < rig->views; i++) {
        mr_view v = mr_rig_view(rig, centre, i, w, h);
        if (!mr_render_frame(r, &v, &fp, &cur, &err)) {
            CHECK_MSG(false, "view %d: %s", i, err.msg);
            break;
        }
        if (i > 0) {
            mr_view_consistency c;
            CHECK(mr_eval_view_consistency(&vprev, &prev.depth, &prev.ao, &v, &cur.depth, &cur.ao, 0.01, &c, &err));
            CHECK_MSG(c.fraction > 0.5, "views %d/%d share only %.2f of the pixels", i - 1, i, c.fraction);
            sum += c.rmse;
            fsum += c.fraction;
            pairs++;
        }
        mr_frame_result_free(&prev);
        prev = cur;
        vprev = v;
    }
    mr_frame_result_free(&prev);
    *fraction = pairs ? fsum / pairs : 0;
    return pairs ? sum / pairs : NAN;
}


/* Floor (top at y = 0) and a wall whose face is the plane z = 2.9, a cube
 * on the floor (test_ao's corner). */
static mr_scene *corner_scene(void) {
    mr_scene *s = mr_scene_create();
    add_node(s, mr_m4_translate(0, -0.1, 0), mr_test_add_box(s, 20, 0.2, 20, -1));
    add_node(s, mr_m4_translate(0, 3, 3.0), mr_test_add_box(s, 20, 6, 0.2, -1));
    add_node(s, mr_m4_translate(-1.5, 0.5, 1.0), mr_test_add_box(s, 1, 1, 1, -1));
    mr_scene_update_bounds(s);
    return s;
}

/* RMSE of an AO image against the closed form over floor pixels in front
 * of the wall, away from the cube; points from the display's exact rays
 * (m) or the pinhole (m NULL). */
static double wall_rmse(const mr_view *v, const mr_display_map *m, const mr_image *depth, const mr_image *ao, double R,
                        int *count) {
    mr_camera c = mr_camera_resized(&v->camera, depth->width, depth->height);
    const float *d = depth->data, *a = ao->data;
    double se = 0;
    int n = 0;
    for (int y = 0; y < depth->height; y++)
        for (int x = 0; x < depth->width; x++) {
            size_t i = (size_t)y * depth->width + x;
            if (!(d[i] > 0)) continue;
            mr_dvec3 pc = m ? mr_display_point(m, &c, x, y, d[i])
                            : mr_v3((x - c.cx) / c.fx * d[i], (y - c.cy) / c.fy * d[i], d[i]);
            mr_dvec3 p = mr_m4_point(&v->world_from_camera, pc);
            double dist = 2.9 - p.z;
            if (fabs(p.y) > 0.01 || dist < 0 || dist > 1.0 || p.x < -0.5 || p.x > 5) continue;
            double e = a[i] - mr_eval_ao_wall_analytic(dist, R);
            se += e * e;
            n++;
        }
    *count = n;
    return n ? sqrt(se / n) : NAN;
}

static double image_rmse(const mr_image *a, const mr_image *b, const mr_image *depth) {
    const float *x = a->data, *y = b->data, *d = depth->data;
    double se = 0;
    long n = 0;
    for (size_t i = 0; i < (size_t)a->width * a->height; i++)
        if (d[i] > 0) {
            se += (x[i] - y[i]) * (double)(x[i] - y[i]);
            n++;
        }
    return n ? sqrt(se / n) : NAN;
}

/* The display mapping on the GPU: each column is its own eye's pinhole
 * column; the ray-traced AO through the exact per-column rays matches the
 * closed form beside a wall as the pinhole's does; the SSAO's error against
 * it is measured the same way under both. */
static void test_display_gpu(mr_renderer *r) {
    mr_error err = {0};
    mr_scene *s = corner_scene();
    CHECK(mr_renderer_set_scene(r, s, &err));
    const int W = 96, H = 72;
    mr_view v;
    mr_camera c = {W, H, 0.8 * W, 0.8 * W, (W - 1) / 2.0, (H - 1) / 2.0, {0, 0, 0, 0, 0}};
    v.camera = c;
    /* Looking across the wall, so that depth varies along the rows and a
     * sample projected to the wrong column reads the wrong depth. */
    v.world_from_camera = mr_m4_look_at_cv(mr_v3(0.7, 2.2, -2.5), mr_v3(4, 0.2, 2.5), mr_v3(0, 1, 0));
    mr_display_map m = {4.0, 4.0 * tan(17.5 * 3.14159265358979 / 180), 1};
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.want_depth = fp.want_normals = true;
    fp.display = &m;
    mr_frame_result disp;
    if (!mr_render_frame(r, &v, &fp, &disp, &err)) {
        CHECK_MSG(false, "display frame: %s", err.msg);
        mr_scene_destroy(&s);
        return;
    }
    /* Column u of the display frame is column u of the pinhole view from
     * eye e(u) (the band camera of band u at band width 1). */
    const int cols[] = {0, 17, 48, 70, 95};
    int bad = 0, geom = 0;
    for (int k = 0; k < 5; k++) {
        int x0, x1;
        double e;
        mr_view pv = v;
        pv.camera = mr_display_band_camera(&m, &c, cols[k], &x0, &x1, &e);
        mr_dmat4 sh = mr_m4_translate(e, 0, 0);
        pv.world_from_camera = mr_m4_mul(&v.world_from_camera, &sh);
        mr_frame_params pp = MR_FRAME_DEFAULTS;
        pp.want_depth = true;
        mr_frame_result pr;
        if (!mr_render_frame(r, &pv, &pp, &pr, &err)) {
            CHECK_MSG(false, "%s", err.msg);
            continue;
        }
        for (int y = 0; y < H; y++) {
            float a = ((float *)disp.depth.data)[y * W + cols[k]], b = ((float *)pr.depth.data)[y * W + cols[k]];
            if (fabsf(a - b) > 1e-5f * (b + 1)) bad++;
            geom += b > 0;
        }
        mr_frame_result_free(&pr);
    }
    CHECK_MSG(bad == 0 && geom > 200, "%d of %d column pixels differ from their eye's pinhole view", bad, geom);
    /* It is not the pinhole frame. */
    mr_frame_params pin = MR_FRAME_DEFAULTS;
    pin.want_depth = pin.want_normals = true;
    mr_frame_result pinr;
    CHECK(mr_render_frame(r, &v, &pin, &pinr, &err));
    int differ = 0;
    for (int i = 0; i < W * H && pinr.depth.data; i++)
        differ += fabsf(((float *)disp.depth.data)[i] - ((float *)pinr.depth.data)[i]) > 1e-3f;
    CHECK_MSG(differ > W * H / 10, "display frame barely differs from the pinhole (%d pixels)", differ);

    /* Ground truth through the exact rays vs the closed form (as test_ao's
     * pinhole case, same tolerance), then the SSAO against it. */
    mr_eval_gt *gt = mr_eval_gt_create(s, false, &err);
    CHECK_MSG(gt != NULL, "%s", err.msg);
    mr_gt_params gp = MR_GT_DEFAULTS;
    gp.radius = 0.6;
    gp.rays = 1024;
    mr_image gt_disp = {0}, gt_pin = {0};
    mr_gt_params gpd = gp;
    gpd.display = &m;
    if (gt && mr_eval_ao_groundtruth(gt, &v, &disp.depth, &disp.normal, &gpd, &gt_disp, &err) &&
        mr_eval_ao_groundtruth(gt, &v, &pinr.depth, &pinr.normal, &gp, &gt_pin, &err)) {
        int nd, np;
        double ed = wall_rmse(&v, &m, &disp.depth, &gt_disp, 0.6, &nd), ep = wall_rmse(&v, NULL, &pinr.depth, &gt_pin, 0.6, &np);
        printf("ground truth vs closed form beside the wall: display %.4f (%d px), pinhole %.4f (%d px)\n", ed, nd, ep, np);
        CHECK_MSG(nd > 30 && ed < 0.03, "display ground truth vs closed form: RMSE %.4f over %d pixels", ed, nd);
        CHECK_MSG(np > 30 && ep < 0.03, "pinhole ground truth vs closed form: RMSE %.4f over %d pixels", ep, np);
        /* SSAO against its ground truth, both ways (view radius): filion
         * compares depths at the projected samples, so a sample projected
         * through the pinhole instead of the display mapping shows (0.22
         * against 0.05 when project() ignores the mapping); scheer reads
         * positions there and is less sensitive. */
        const mr_ao_method methods[2] = {MR_AO_FILION, MR_AO_SCHEER};
        for (int mi = 0; mi < 2; mi++) {
            mr_frame_params sp = MR_FRAME_DEFAULTS;
            sp.want_depth = true;
            sp.ao.method = methods[mi];
            sp.ao.radius_mode = MR_AO_RADIUS_VIEW;
            sp.ao.radius = 0.6;
            sp.ao.want_ao = true;
            sp.ao.positions = true;
            mr_frame_result sa_pin, sa_disp;
            CHECK(mr_render_frame(r, &v, &sp, &sa_pin, &err));
            sp.display = &m;
            CHECK(mr_render_frame(r, &v, &sp, &sa_disp, &err));
            if (sa_pin.ao.data && sa_disp.ao.data) {
                double e_pin = image_rmse(&sa_pin.ao, &gt_pin, &pinr.depth), e_disp = image_rmse(&sa_disp.ao, &gt_disp, &disp.depth);
                printf("SSAO (%s) RMSE vs ground truth: pinhole %.4f, display %.4f\n", mr_ao_method_name(methods[mi]), e_pin,
                       e_disp);
                CHECK_MSG(e_disp < e_pin + 0.03, "%s: display SSAO error %.4f far above the pinhole's %.4f",
                          mr_ao_method_name(methods[mi]), e_disp, e_pin);
            }
            mr_frame_result_free(&sa_pin);
            mr_frame_result_free(&sa_disp);
        }
    } else {
        CHECK_MSG(false, "ground truth: %s", err.msg);
    }
    /* What the mapping cannot draw is refused with one line. */
    mr_frame_params refused = MR_FRAME_DEFAULTS;
    refused.display = &m;
    refused.ao.method = MR_AO_CRYTEK;
    refused.ao.mask = MR_AO_MASK_ON;
    mr_frame_result br;
    CHECK(!mr_render_frame(r, &v, &refused, &br, &err) && strstr(err.msg, "display mapping"));
    mr_display_map zero = m;
    zero.band = 0;
    refused.display = &zero;
    refused.ao.mask = MR_AO_MASK_OFF;
    CHECK(!mr_render_frame(r, &v, &refused, &br, &err) && strstr(err.msg, "band"));
    mr_image_free(&gt_disp);
    mr_image_free(&gt_pin);
    mr_eval_gt_destroy(&gt);
    mr_frame_result_free(&pinr);
    mr_frame_result_free(&disp);
    CHECK(mr_renderer_set_scene(r, NULL, &err));
    mr_scene_destroy(&s);
}

/* Lines of a file (0 if unreadable) and whether its first non-comment
 * line is `header`. */
static int csv_lines(const char *path, const char *header) {
    size_t n = 0;
    mr_error err = {0};
    char *t = mr_file_read(path, &n, 0, &err);
    if (!t) return 0;
    int lines = 0;
    bool head_ok = false, seen_head = false;
    for (char *l = t; l && *l; ) {
        char *e = strchr(l, '\n');
        if (e) *e = 0;
        if (l[0] != '#') {
            if (!seen_head) head_ok = strcmp(l, header) == 0, seen_head = true;
            else lines++;
        }
        l = e ? e + 1 : NULL;
    }
    free(t);
    return head_ok ? lines : -1;
}

/* The bench at a tiny size: its files, columns and rows. */
static void test_bench_tiny(mr_gpu *gpu, mr_renderer *r) {
    char dir[4096], path[4200];
    if (!mr_test_fresh_dir("multiview_bench", dir, sizeof dir)) return;
    mr_bench_multiview_params p = {MR_BENCH_MULTIVIEW_DEFAULTS};
    p.gfx.gpu = gpu;
    p.gfx.renderer = r;
    p.out_dir = dir;
    p.quick = true;
    p.budget_w = 64;
    p.budget_h = 48;
    p.view_w = 32;
    p.view_h = 24;
    p.table_w = 32;
    p.table_h = 24;
    p.frames = 1;
    p.rays = 4;
    mr_error err = {0};
    CHECK_MSG(mr_bench_multiview(&p, &err), "bench multiview: %s", err.msg);
    snprintf(path, sizeof path, "%s/bench_multiview.csv", dir);
    CHECK_MSG(csv_lines(path, "mode,views,width,height,ms_frame,ms_per_view,ao_rmse_pinhole,ao_rmse_display,"
                              "consistency_rmse_world,consistency_rmse_pixel,consistency_rmse_world_noblur,"
                              "consistency_rmse_pixel_noblur,shared_fraction") == 4,
              "bench_multiview.csv: header or 4 rows (quick: 2 modes x views 1, 8)");
    snprintf(path, sizeof path, "%s/bench_multiview_display.csv", dir);
    CHECK(csv_lines(path, "band,width,height,ms_frame,column_error_mean_px,column_error_max_px,ao_rmse_display") == 3);
    snprintf(path, sizeof path, "%s/bench_multiview_table1.csv", dir);
    CHECK(csv_lines(path, "scene,triangles,width,height,ms_no_ssao,ms_ssao,ms_difference") == 3);
    snprintf(path, sizeof path, "%s/bench_multiview.svg", dir);
    size_t n = 0;
    char *svg = mr_file_read(path, &n, 0, &err);
    CHECK(svg && strstr(svg, "<svg"));
    free(svg);
    snprintf(path, sizeof path, "%s/bench_multiview.md", dir);
    char *md = mr_file_read(path, &n, 0, &err);
    CHECK(md && strstr(md, "| per_view | 8 | 32x24 |") && strstr(md, "Table 1"));
    free(md);
}

static int test_gpu(void) {
    mr_error err = {0};
    mr_gpu_params gp = MR_GPU_DEFAULTS;
    mr_gpu *gpu = mr_gpu_create_headless(&gp, &err);
    if (!gpu) return mr_test_no_gpu("test_multiview", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    mr_scene *s = rig_scene();
    CHECK(mr_renderer_set_scene(r, s, &err));
    mr_view centre;
    mr_camera c = {64, 48, 50, 50, 31.5, 23.5, {0, 0, 0, 0, 0}};
    centre.camera = c;
    centre.world_from_camera = mr_m4_look_at_cv(mr_v3(0.3, 2.2, -2.5), mr_v3(0, 0.3, 1.5), mr_v3(0, 1, 0));
    mr_rig_params rp = MR_RIG_DEFAULTS;
    rp.views = 8;
    rp.fov_deg = 50;
    rp.cone_deg = 10;
    mr_rig rig;
    CHECK(mr_rig_make(&rp, 64.0 / 48, 4.5, &rig, &err));

    /* 8 views of 64x48 with one renderer into a quilt; neighbouring views
     * differ (parallax), and the quilt's tiles are the views. */
    mr_quilt_layout l;
    mr_quilt q;
    CHECK(mr_quilt_parse("4x2", &q, &err) && mr_quilt_layout_make(&q, 8, 64, 48, &l, &err));
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.ao.method = MR_AO_CRYTEK;
    mr_image quilt = {0};
    mr_rig_result rr;
    char dir[4096];
    CHECK(mr_test_fresh_dir("multiview", dir, sizeof dir));
    CHECK_MSG(mr_render_rig(r, &rig, &centre, &fp, &l, dir, &quilt, &rr, &err), "%s", err.msg);
    CHECK(rr.views == 8 && quilt.width == 256 && quilt.height == 96);
    int differ = 0;
    for (int i = 0; i < 8; i++) {
        char p[4200];
        snprintf(p, sizeof p, "%s/view_%03d.png", dir, i);
        mr_image v;
        if (!mr_image_load(p, 3, &v, &err)) {
            CHECK_MSG(false, "%s", err.msg);
            continue;
        }
        int x0, y0, same = 1;
        mr_quilt_tile_origin(&l, i, &x0, &y0);
        for (int y = 0; y < 48 && same; y++)
            same = memcmp((unsigned char *)quilt.data + ((size_t)(y0 + y) * quilt.width + x0) * 3,
                          (unsigned char *)v.data + (size_t)y * 64 * 3, 64 * 3) == 0;
        CHECK_MSG(same, "tile %d is not view_%03d.png", i, i);
        if (i > 0) {
            int x1, y1;
            mr_quilt_tile_origin(&l, i - 1, &x1, &y1);
            for (int y = 0; y < 48; y++)
                differ += memcmp((unsigned char *)quilt.data + ((size_t)(y0 + y) * quilt.width + x0) * 3,
                                 (unsigned char *)quilt.data + ((size_t)(y1 + y) * quilt.width + x1) * 3, 64 * 3) != 0;
        }
        mr_image_free(&v);
    }
    CHECK_MSG(differ > 7 * 10, "views barely differ: %d differing rows", differ);
    mr_image_free(&quilt);

    /* The middle of the focal plane is seen at the same pixel by all views:
     * render depth at the centre pixel of every view equals the point's. */
    /* AO agrees across views better when its noise is tied to the surface. */
    double f_pix, f_world;
    double e_pix = rig_consistency(r, &rig, &centre, MR_AO_NOISE_PIXEL, 64, 48, &f_pix);
    double e_world = rig_consistency(r, &rig, &centre, MR_AO_NOISE_WORLD, 64, 48, &f_world);
    printf("cross-view AO RMSE: pixel noise %.4f, world noise %.4f (%.2f of the pixels seen by both)\n", e_pix, e_world,
           f_world);
    CHECK_MSG(e_world < 0.75 * e_pix, "world noise %.4f not clearly better than pixel noise %.4f", e_world, e_pix);

    CHECK(mr_renderer_set_scene(r, NULL, &err));
    mr_scene_destroy(&s);
    test_display_gpu(r);
    test_bench_tiny(gpu, r);
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return 0;
}

int main(void) {
    test_known_answers();
    test_quilt();
    test_focal_from_depth();
    test_display_cpu();
    int rc = test_gpu();
    if (rc) return rc;
    return mr_test_finish("test_multiview");
}
