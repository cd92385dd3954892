/* The synthetic data of `mrcheck synth` / `mrcheck demo` (lib/scene's
 * calibration board, lib/bench's recording and calibration set): the board
 * is rendered where the camera model says it is, and a short synthetic
 * recording holds its frames, ground truth on the walking path and the
 * tracker's real detections, which land where the ground truth projects
 * the hall's tags. */
#include "mr_bench.h"
#include "mr_scene.h"
#include "mr_session.h"
#include "mr_test.h"
#include "mr_track.h"

#include <string.h>

static char g_tmp[1024];

/* Largest distance of a detection's corners from where the camera model
 * projects the marker's corners (apriltag order, both); *matched counts the
 * detections whose id is in the map. */
static double corner_error(const mr_camera *cam, const mr_dmat4 *world_from_camera, const mr_marker_map *map,
                           const mr_detection *dets, int n, int *matched) {
    double worst = 0;
    *matched = 0;
    for (int d = 0; d < n; d++) {
        const mr_marker *m = NULL;
        for (int k = 0; k < map->count; k++)
            if (map->tags[k].id == dets[d].id) m = &map->tags[k];
        if (!m) continue;
        ++*matched;
        mr_dvec3 w[4];
        mr_marker_corners_world(map, m, w);
        for (int c = 0; c < 4; c++) {
            double u, v;
            if (!mr_project_point(cam, world_from_camera, w[c], &u, &v)) return INFINITY;
            double e = hypot(u - dets[d].corners[c][0], v - dets[d].corners[c][1]);
            if (e > worst) worst = e;
        }
    }
    return worst;
}

/* The board seen obliquely and off centre (the lens distortion matters
 * there): every tag is found with its id, its corners within 0.5 px of the
 * camera model's projection of mr_demo_board_tag's pose. */
static void test_board(void) {
    enum { n_tags = MR_DEMO_BOARD_COLS * MR_DEMO_BOARD_ROWS };
    mr_error err = {0};
    mr_image *all = NULL;
    int border = 0;
    CHECK_MSG(mr_demo_tag_images(MR_DEMO_BOARD_FIRST_ID + n_tags, &all, &border, &err), "tag images: %s", err.msg);
    if (!all) return;
    mr_marker tags[n_tags];
    mr_marker_map map = {.family = "tag36h11", .tag_size = MR_DEMO_BOARD_TAG, .tags = tags, .count = n_tags};
    for (int i = 0; i < n_tags; i++) {
        tags[i].id = mr_demo_board_tag(i, &tags[i].world_from_tag);
        tags[i].size = 0; /* the map's tag_size */
    }
    CHECK_MSG(tags[0].id == MR_DEMO_BOARD_FIRST_ID && tags[n_tags - 1].id == MR_DEMO_BOARD_FIRST_ID + n_tags - 1,
              "board ids run %d..%d, want %d..%d", tags[0].id, tags[n_tags - 1].id, MR_DEMO_BOARD_FIRST_ID,
              MR_DEMO_BOARD_FIRST_ID + n_tags - 1);
    mr_dvec3 t7 = mr_m4_point(&tags[7].world_from_tag, mr_v3(0, 0, 0));
    CHECK_MSG(fabs(t7.x - MR_DEMO_BOARD_PITCH) < 1e-12 && fabs(t7.y - MR_DEMO_BOARD_PITCH) < 1e-12 && t7.z == 0,
              "tag 7 (row 1, column 1) is at (%g, %g, %g), want one pitch right and down", t7.x, t7.y, t7.z);
    mr_camera cam = mr_demo_camera();
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    dp.decimate = 1;
    mr_detector *det = mr_detector_create(&dp, &err);
    CHECK_MSG(det, "detector: %s", err.msg);
    /* Two views: the board in the image's left half, tilted, and in the
     * lower right; each covers a corner region where distortion is pixels. */
    const double views[2][6] = {{0.30, 0.05, -0.32, 0.20, 0.07, 0.0}, {0.0, 0.20, -0.35, 0.12, 0.03, 0.0}};
    mr_rng rng;
    mr_rng_seed(&rng, 5);
    for (int vi = 0; det && vi < 2; vi++) {
        mr_dmat4 bfc = mr_m4_look_at_cv(mr_v3(views[vi][0], views[vi][1], views[vi][2]),
                                        mr_v3(views[vi][3], views[vi][4], views[vi][5]), mr_v3(0, -1, 0));
        mr_image img = {0};
        bool ok = mr_demo_board_render(&cam, &bfc, all + MR_DEMO_BOARD_FIRST_ID, &rng, &img, &err);
        CHECK_MSG(ok, "board render: %s", err.msg);
        if (!ok) continue;
        CHECK_MSG(img.width == cam.width && img.height == cam.height && img.channels == 1,
                  "board image is %dx%dx%d, want the camera's %dx%d gray", img.width, img.height, img.channels, cam.width,
                  cam.height);
        int n = 0, matched = 0;
        const mr_detection *d = mr_detector_detect(det, &img, &n, &err);
        double worst = d ? corner_error(&cam, &bfc, &map, d, n, &matched) : INFINITY;
        CHECK_MSG(n == n_tags && matched == n_tags, "view %d: %d tags detected, %d of them board ids, want all %d", vi,
                  n, matched, n_tags);
        CHECK_MSG(worst <= 0.5, "view %d: a detected board corner is %.3f px from the camera model's projection (max 0.5)",
                  vi, worst);
        mr_image_free(&img);
    }
    mr_detector_destroy(&det);
    mr_demo_tag_images_free(all, MR_DEMO_BOARD_FIRST_ID + n_tags);
}

/* The calibration set: board.json is the board as a marker map, and the
 * images are there at the demo camera's size. */
static void test_calibration_set(void) {
    mr_error err = {0};
    char dir[1200], path[1400];
    snprintf(dir, sizeof dir, "%s/calib", g_tmp);
    CHECK_MSG(mr_synth_calibration(dir, 2, &err), "calibration set: %s", err.msg);
    mr_marker_map map = {0};
    snprintf(path, sizeof path, "%s/board.json", dir);
    bool ok = mr_marker_map_load(path, &map, &err);
    CHECK_MSG(ok, "board.json does not load as a marker map: %s", err.msg);
    if (ok) {
        CHECK_MSG(map.count == MR_DEMO_BOARD_COLS * MR_DEMO_BOARD_ROWS && fabs(map.tag_size - MR_DEMO_BOARD_TAG) < 1e-12,
                  "board.json: %d tags of %g m, want %d of %g m", map.count, map.tag_size,
                  MR_DEMO_BOARD_COLS * MR_DEMO_BOARD_ROWS, MR_DEMO_BOARD_TAG);
        int bad = 0;
        for (int i = 0; i < map.count; i++) {
            mr_dmat4 want;
            int id = mr_demo_board_tag(i, &want);
            for (int k = 0; k < 16; k++) bad += map.tags[i].id != id || fabs(map.tags[i].world_from_tag.m[k] - want.m[k]) > 1e-9;
        }
        CHECK_MSG(bad == 0, "board.json differs from mr_demo_board_tag's ids and poses (%d entries)", bad);
    }
    mr_marker_map_free(&map);
    for (int i = 0; i < 3; i++) {
        mr_image img = {0};
        snprintf(path, sizeof path, "%s/images/board_%02d.png", dir, i);
        bool exists = mr_file_exists(path);
        CHECK_MSG(exists == (i < 2), "%s %s, want %s", path, exists ? "exists" : "is missing", i < 2 ? "it" : "none");
        if (i < 2 && exists) {
            CHECK_MSG(mr_image_load(path, 1, &img, &err) && img.width == 640 && img.height == 480,
                      "%s: %dx%d, want the demo camera's 640x480 (%s)", path, img.width, img.height, err.msg);
            mr_image_free(&img);
        }
    }
    CHECK_MSG(!mr_synth_calibration(dir, 0, &err) && err.code == MR_ERR_INVALID, "zero calibration images accepted");
}

/* Three frames over the whole walking path at 5 path steps per second:
 * the timestamps on the path's clock, (total - 1) / 2 steps apart. */
static int test_recording(void) {
    mr_error err = {0};
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) return mr_test_no_gpu("test_synth", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r, "renderer: %s", err.msg);
    mr_bench_gpu gfx = {gpu, r};
    char dir[1200];
    snprintf(dir, sizeof dir, "%s/rec", g_tmp);
    mr_synth_recording_params p = {MR_SYNTH_RECORDING_DEFAULTS};
    p.frames = 3;
    p.motion_blur = 1;
    p.fps = 5;
    mr_bench_gpu none = {gpu, NULL};
    CHECK_MSG(!mr_synth_recording(dir, &p, &none, &err) && err.code == MR_ERR_INVALID, "no renderer accepted");
    mr_synth_recording_params bad = p;
    bad.frames = -1;
    CHECK_MSG(!mr_synth_recording(dir, &bad, &gfx, &err) && err.code == MR_ERR_INVALID, "-1 frames accepted");
    bad = p;
    bad.shutter = 0;
    CHECK_MSG(!mr_synth_recording(dir, &bad, &gfx, &err) && err.code == MR_ERR_INVALID, "shutter 0 (an endless exposure) accepted");
    CHECK_MSG(!mr_is_recording(dir), "a refused call left a recording behind");
    bool ok = r && mr_synth_recording(dir, &p, &gfx, &err);
    CHECK_MSG(ok, "synthetic recording: %s", err.msg);
    mr_recording *rec = ok ? mr_recording_open(dir, &err) : NULL;
    CHECK_MSG(!ok || rec, "the synthetic recording does not open: %s", err.msg);
    if (rec) {
        CHECK_MSG(rec->frame_count == 3, "%d frames recorded, want 3", rec->frame_count);
        CHECK_MSG(rec->has_markers && rec->markers.count == MR_DEMO_TAGS, "recording's marker map: %d tags, want the hall's %d",
                  rec->has_markers ? rec->markers.count : 0, MR_DEMO_TAGS);
        mr_camera demo = mr_demo_camera();
        CHECK_MSG(rec->camera.width == 640 && rec->camera.height == 480 && rec->camera.fx == demo.fx &&
                      rec->camera.cx == demo.cx,
                  "the recording's camera is not the demo camera at its own size");
        /* The path runs from its first keyframe to its last. */
        const double ends[2][3] = {{11.5, 1.60, 4.0}, {-6.5, 1.60, 3.0}};
        for (int i = 0; i < rec->frame_count && i < 3; i++) {
            const mr_rec_frame *f = &rec->frames[i];
            CHECK_MSG(f->has_gt, "frame %d has no ground-truth line", i);
            const double want_t = i * (mr_synth_path_frames() - 1) / 2.0 / 5.0;
            CHECK_MSG(fabs(f->t - want_t) < 1e-9, "frame %d at t = %g, want %g (the path's clock at 5 steps/s)", i, f->t,
                      want_t);
            if (i != 1) {
                const double *e = ends[i / 2];
                mr_dvec3 o = mr_m4_point(&f->gt, mr_v3(0, 0, 0));
                CHECK_MSG(fabs(o.x - e[0]) < 1e-9 && fabs(o.y - e[1]) < 1e-9 && fabs(o.z - e[2]) < 1e-9,
                          "frame %d's ground-truth eye is (%g, %g, %g), want the path's %s (%g, %g, %g)", i, o.x, o.y,
                          o.z, i ? "end" : "start", e[0], e[1], e[2]);
                CHECK_MSG(f->still, "frame %d stands at a keyframe pause but is not marked still", i);
            }
            mr_image img = {0};
            CHECK_MSG(mr_recording_load_image(rec, i, true, &img, &err) && img.width == 640 && img.height == 480,
                      "frame %d's image: %dx%d (%s)", i, img.width, img.height, err.msg);
            mr_image_free(&img);
        }
        /* The first frame faces tag post 0 (tags 16-19, two on each face):
         * all four detected where the ground truth projects them, and a
         * pose near the truth. */
        const mr_rec_frame *f = &rec->frames[0];
        int post0 = 0;
        for (int d = 0; d < f->detection_count; d++) post0 += f->detections[d].id >= 16 && f->detections[d].id <= 19;
        CHECK_MSG(post0 == 4, "frame 0: the four tags of post 0 are in view but %d of them detected (%d detections)",
                  post0, f->detection_count);
        int matched = 0;
        double worst = corner_error(&rec->camera, &f->gt, &rec->markers, f->detections, f->detection_count, &matched);
        CHECK_MSG(worst <= 0.75, "frame 0: a detected corner is %.3f px from the ground truth's projection (max 0.75)", worst);
        double dt = f->pose.valid ? mr_pose_dist(&f->pose.world_from_camera, &f->gt) : INFINITY;
        CHECK_MSG(f->pose.valid && dt < 0.12, "frame 0: the tracker's pose is %s %.3f m from the truth (max 0.12)",
                  f->pose.valid ? "" : "missing,", dt);
        mr_recording_close(&rec);
    }
    /* Another size: the demo lens scaled with the width (square pixels,
     * the principal point's offset from the centre scaled too), rendered
     * and recorded with that same camera. */
    snprintf(dir, sizeof dir, "%s/rec800", g_tmp);
    p.frames = 1;
    p.width = 800;
    p.height = 600;
    ok = r && mr_synth_recording(dir, &p, &gfx, &err);
    CHECK_MSG(ok, "synthetic recording at 800x600: %s", err.msg);
    rec = ok ? mr_recording_open(dir, &err) : NULL;
    if (rec && rec->frame_count == 1) {
        mr_camera d = mr_demo_camera(), c = rec->camera;
        double sc = 800.0 / d.width;
        CHECK_MSG(c.width == 800 && c.height == 600 && fabs(c.fx - d.fx * sc) < 1e-9 && fabs(c.fy - d.fy * sc) < 1e-9 &&
                      fabs(c.cx - (399.5 + (d.cx - 0.5 * (d.width - 1)) * sc)) < 1e-9 &&
                      fabs(c.cy - (299.5 + (d.cy - 0.5 * (d.height - 1)) * sc)) < 1e-9,
                  "800x600 camera fx %g fy %g cx %g cy %g is not the demo camera scaled by %g", c.fx, c.fy, c.cx, c.cy,
                  sc);
        const mr_rec_frame *f = &rec->frames[0];
        int matched = 0;
        double worst = corner_error(&c, &f->gt, &rec->markers, f->detections, f->detection_count, &matched);
        CHECK_MSG(matched >= 2 && worst <= 0.75,
                  "800x600 frame 0: %d hall tags detected (want 2), worst corner %.3f px from the ground truth's "
                  "projection (max 0.75)",
                  matched, worst);
    } else
        CHECK_MSG(false, "the 800x600 recording does not open with one frame: %s", err.msg);
    mr_recording_close(&rec);
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return -1;
}

int main(void) {
    if (!mr_test_fresh_dir("test_synth", g_tmp, sizeof g_tmp)) return 1;
    test_board();
    test_calibration_set();
    int rc = test_recording();
    return rc >= 0 ? rc : mr_test_finish("test_synth");
}
