/* Synthetic recordings of the demo hall with ground truth, and a synthetic
 * calibration set (tag-grid board). The camera frames come from
 * mr_demo_camera_frame (lib/scene). */
#include "app_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ------------------------------------------------------------ the path */

/* Keyframes of a walk along the east side of the hall: eye, look-at target
 * and how many frames to pause there (the camera is still: jitter is
 * measured there) before walking `walk` frames to the next keyframe. Chosen
 * so that most frames see one tag at 3-5 m and some see two. */
typedef struct keyframe { double eye[3], at[3]; int pause, walk; } keyframe;
static const keyframe k_path[] = {
    {{12.5, 1.60, -5.5}, {12.5, 2.0, -12.0}, 8, 16},  /* tags 2 and 12, far */
    {{15.0, 1.60, -8.0}, {16.0, 1.9, -12.0}, 8, 16},  /* tag 12 close */
    {{16.0, 1.55, -6.5}, {20.0, 2.0, -6.0}, 8, 14},   /* tag 3 */
    {{16.0, 1.60, -2.0}, {20.0, 2.2, -1.0}, 8, 14},   /* tag 13 */
    {{15.5, 1.65, 2.5}, {20.0, 2.0, 2.5}, 8, 12},     /* tags 13 and 4 */
    {{16.5, 1.60, 5.3}, {20.0, 1.7, 5.0}, 8, 0},      /* tag 4 close */
};
#define PATH_KEYS (int)(sizeof k_path / sizeof k_path[0])

static int path_frames(void) {
    int n = 0;
    for (int i = 0; i < PATH_KEYS; i++) n += k_path[i].pause + k_path[i].walk;
    return n;
}

/* Pose at path position s in [0, path_frames()) (fractional), and whether
 * the camera stands still there. */
static mr_dmat4 path_pose(double s, bool *still) {
    int base = 0;
    for (int i = 0; i < PATH_KEYS; i++) {
        const keyframe *k = &k_path[i];
        if (s < base + k->pause || i == PATH_KEYS - 1 || k->walk == 0) {
            if (still) *still = true;
            return mr_m4_look_at_cv(mr_v3(k->eye[0], k->eye[1], k->eye[2]), mr_v3(k->at[0], k->at[1], k->at[2]),
                                    mr_v3(0, 1, 0));
        }
        if (s < base + k->pause + k->walk) {
            const keyframe *n = &k_path[i + 1];
            /* walk frames end one step before the next pause */
            double u = (s - base - k->pause + 1) / (k->walk + 1);
            u = u * u * (3 - 2 * u); /* ease in and out */
            double e[3], a[3];
            for (int c = 0; c < 3; c++) {
                e[c] = k->eye[c] + u * (n->eye[c] - k->eye[c]);
                a[c] = k->at[c] + u * (n->at[c] - k->at[c]);
            }
            if (still) *still = false;
            return mr_m4_look_at_cv(mr_v3(e[0], e[1], e[2]), mr_v3(a[0], a[1], a[2]), mr_v3(0, 1, 0));
        }
        base += k->pause + k->walk;
    }
    if (still) *still = true;
    return mr_m4_identity();
}

static bool hall_markers(const mr_demo_hall *hall, mr_marker_map *map, mr_error *err) {
    memset(map, 0, sizeof *map);
    snprintf(map->family, sizeof map->family, "tag36h11");
    map->tag_size = hall->tag_size;
    map->tags = calloc((size_t)hall->tag_count, sizeof *map->tags);
    if (!map->tags) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    map->count = hall->tag_count;
    for (int i = 0; i < hall->tag_count; i++) {
        map->tags[i].id = hall->tags[i].id;
        map->tags[i].world_from_tag = hall->tags[i].world_from_tag;
    }
    return true;
}

/* Tracks one synthetic frame as `record` would (lib/track's one tracker),
 * so frames.jsonl holds real results: fills fr's detections, raw pose and
 * filtered pose (fr->t is the time). */
static bool track_frame(mr_tracker *trk, const mr_image *gray, mr_frame_record *fr, mr_error *err) {
    mr_tracker_result r;
    if (!mr_tracker_frame(trk, gray, fr->t, &r, err)) return false;
    fr->detections = r.detections;
    fr->detection_count = r.detection_count;
    fr->pose = r.pose;
    fr->has_filtered = r.has_filtered;
    if (r.has_filtered) fr->filtered = r.filtered;
    return true;
}

bool app_synth_recording(const char *dir, const app_synth_params *params, mr_error *err) {
    app_synth_params p = params ? *params : (app_synth_params)APP_SYNTH_DEFAULTS;
    if (p.frames < 1 || p.width < 64 || p.height < 48 || p.motion_blur < 1 || p.motion_blur > 16 || p.noise < 0 ||
        p.exposure < 0 || p.exposure >= 1 || p.fps <= 0)
        return mr_fail(err, MR_ERR_INVALID, "synth: parameters out of range");
    mr_demo_hall hall;
    if (!mr_demo_build_tagged(NULL, 0, &hall, err)) return false;
    mr_marker_map map;
    /* The demo lens at another resolution: square pixels, the focal length
     * scaled with the width, so 1280x720 is a 16:9 crop of a 1280x960. */
    mr_camera cam = mr_demo_camera();
    double sc = (double)p.width / cam.width;
    cam.fx *= sc;
    cam.fy *= sc;
    cam.cx = 0.5 * (p.width - 1) + (cam.cx - 0.5 * (mr_demo_camera().width - 1)) * sc;
    cam.cy = 0.5 * (p.height - 1) + (cam.cy - 0.5 * (mr_demo_camera().height - 1)) * sc;
    cam.width = p.width;
    cam.height = p.height;
    bool ok = hall_markers(&hall, &map, err);
    app_gfx gfx = {0};
    ok = ok && app_gfx_open(&gfx, err) && mr_renderer_set_scene(gfx.renderer, hall.built, err);
    mr_recorder *rec = NULL;
    if (ok) {
        mr_recorder_params rp = MR_RECORDER_DEFAULTS;
        rp.camera = &cam;
        rp.markers = &map;
        rp.source = "synthetic: mrcheck demo hall (as built) along a walking path";
        rp.jpeg_quality = p.jpeg_quality;
        rp.ground_truth = true;
        rec = mr_recorder_create(dir, &rp, err);
        ok = rec != NULL;
    }
    mr_tracker_params tp = MR_TRACKER_DEFAULTS;
    tp.camera = &cam;
    tp.markers = &map;
    mr_tracker *trk = ok ? mr_tracker_create(&tp, err) : NULL;
    ok = ok && trk;
    const int margin = 48 * p.width / 640 + 8, scale = 2;
    mr_camera wide = cam;
    wide.width += 2 * margin;
    wide.height += 2 * margin;
    wide.cx += margin;
    wide.cy += margin;
    memset(wide.dist, 0, sizeof wide.dist);
    mr_image ideal[16];
    memset(ideal, 0, sizeof ideal);
    mr_rng rng;
    mr_rng_seed(&rng, p.seed);
    int total = path_frames();
    int with_pose = 0;
    for (int i = 0; ok && i < p.frames; i++) {
        /* Spread the requested frames over the whole path. */
        double s = p.frames > 1 ? (double)i * (total - 1) / (p.frames - 1) : 0;
        double step = p.frames > 1 ? (double)(total - 1) / (p.frames - 1) : 1;
        bool still = false;
        mr_dmat4 truth = path_pose(s, &still);
        double t = i / p.fps;
        /* Sub-frames over an open shutter of a quarter of the frame
         * interval (1/40 s at 10 fps, an indoor auto-exposure). */
        for (int k = 0; ok && k < p.motion_blur; k++) {
            double sk = p.motion_blur > 1 ? s - 0.25 * step * (double)k / (p.motion_blur - 1) : s;
            mr_view v = {wide, path_pose(sk < 0 ? 0 : sk, NULL)};
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = wide.width * scale;
            fp.height = wide.height * scale;
            mr_frame_result res;
            ok = mr_render_frame(gfx.renderer, &v, &fp, &res, err);
            if (ok) {
                mr_image_free(&ideal[k]);
                ideal[k] = res.color;
                res.color.data = NULL;
                mr_frame_result_free(&res);
            }
        }
        double gain = 1.0 + p.exposure * sin(2 * M_PI * i / 40.0);
        mr_image frame = {0}, gray = {0};
        ok = ok && mr_demo_camera_frame(&cam, ideal, p.motion_blur, margin, scale, gain, p.noise, &rng, &frame, err) &&
             mr_image_to_gray(&frame, &gray, err);
        mr_frame_record fr = {0};
        fr.t = t;
        ok = ok && track_frame(trk, &gray, &fr, err);
        const int n = fr.detection_count;
        if (ok) {
            with_pose += fr.pose.valid;
            ok = mr_recorder_append(rec, &fr, &gray, err) && mr_recorder_ground_truth(rec, fr.index, t, &truth, still, err);
        }
        mr_image_free(&frame);
        mr_image_free(&gray);
        if (ok && i % 10 == 0) mr_log(MR_LOG_INFO, "synth: frame %d/%d, %d tags", i, p.frames, n);
        if (ok && isatty(2) && mr_log_get_level() < MR_LOG_INFO) fprintf(stderr, "\rsynth: frame %d/%d", i + 1, p.frames);
    }
    if (isatty(2) && mr_log_get_level() < MR_LOG_INFO) fprintf(stderr, "\r\033[K");
    for (int k = 0; k < 16; k++) mr_image_free(&ideal[k]);
    if (ok) mr_log(MR_LOG_INFO, "synth: %d frames, %d with a pose", p.frames, with_pose);
    mr_recorder_close(&rec);
    mr_tracker_destroy(&trk);
    app_gfx_close(&gfx);
    mr_marker_map_free(&map);
    mr_demo_free(&hall);
    return ok;
}

/* ------------------------------------------------------- calibration set */

#define BOARD_COLS 6
#define BOARD_ROWS 4
#define BOARD_FIRST_ID 100
#define BOARD_TAG 0.04   /* m, black square */
#define BOARD_PITCH 0.06 /* m between tag centres */

/* The board: tag36h11 ids 100..123 on a plane, board frame = tag frame
 * convention (x right, y down, z into the board), origin at the top-left
 * tag's centre. Written as a marker map, so calibrate reads the same format. */
static void board_map(mr_marker_map *map, mr_marker *tags) {
    memset(map, 0, sizeof *map);
    snprintf(map->family, sizeof map->family, "tag36h11");
    map->tag_size = BOARD_TAG;
    map->tags = tags;
    map->count = BOARD_COLS * BOARD_ROWS;
    for (int r = 0; r < BOARD_ROWS; r++)
        for (int c = 0; c < BOARD_COLS; c++) {
            mr_marker *m = &tags[r * BOARD_COLS + c];
            m->id = BOARD_FIRST_ID + r * BOARD_COLS + c;
            m->world_from_tag = mr_m4_translate(c * BOARD_PITCH, r * BOARD_PITCH, 0);
        }
}

/* Ray-casts the white board with its tags through the distorted camera,
 * 3x3 supersampled, background dark grey. */
static bool render_board(const mr_camera *cam, const mr_dmat4 *board_from_camera, const mr_image *tag_imgs,
                         mr_rng *rng, mr_image *out, mr_error *err) {
    if (!mr_image_alloc(out, cam->width, cam->height, 1, MR_PIX_U8, err)) return false;
    unsigned char *o = out->data;
    double plate = BOARD_TAG * 10.0 / 8.0;
    double x0 = -BOARD_PITCH, x1 = (BOARD_COLS)*BOARD_PITCH, y0 = -BOARD_PITCH, y1 = BOARD_ROWS * BOARD_PITCH;
    for (int v = 0; v < cam->height; v++)
        for (int u = 0; u < cam->width; u++) {
            double acc = 0;
            for (int sy = 0; sy < 3; sy++)
                for (int sx = 0; sx < 3; sx++) {
                    double uu = u + (sx - 1) / 3.0, vv = v + (sy - 1) / 3.0, x, y, val = 40;
                    if (mr_camera_undistort(cam, (uu - cam->cx) / cam->fx, (vv - cam->cy) / cam->fy, &x, &y)) {
                        mr_dvec3 oc = mr_m4_point(board_from_camera, mr_v3(0, 0, 0));
                        mr_dvec3 d = mr_m4_dir(board_from_camera, mr_v3(x, y, 1));
                        double t = fabs(d.z) > 1e-12 ? -oc.z / d.z : -1;
                        if (t > 0) {
                            double px = oc.x + t * d.x, py = oc.y + t * d.y;
                            if (px >= x0 && px <= x1 && py >= y0 && py <= y1) {
                                val = 230;
                                int c = (int)floor(px / BOARD_PITCH + 0.5), r = (int)floor(py / BOARD_PITCH + 0.5);
                                if (c >= 0 && r >= 0 && c < BOARD_COLS && r < BOARD_ROWS) {
                                    double lx = px - c * BOARD_PITCH, ly = py - r * BOARD_PITCH;
                                    int cx = (int)floor((lx / plate + 0.5) * 10), cy = (int)floor((ly / plate + 0.5) * 10);
                                    if (cx >= 0 && cy >= 0 && cx < 10 && cy < 10) {
                                        const mr_image *ti = &tag_imgs[r * BOARD_COLS + c];
                                        val = ((const unsigned char *)ti->data)[cy * ti->width + cx] ? 230 : 25;
                                    }
                                }
                            }
                        }
                    }
                    acc += val;
                }
            double g = acc / 9 + 1.5 * mr_rng_normal(rng);
            o[(size_t)v * cam->width + u] = (unsigned char)(g < 0 ? 0 : g > 255 ? 255 : lrint(g));
        }
    return true;
}

bool app_synth_calibration(const char *dir, int images, mr_error *err) {
    char path[4096], sub[4096];
    mr_path_join(dir, "images", sub, sizeof sub);
    if (!mr_mkdirs(sub, err)) return false;
    mr_marker tags[BOARD_COLS * BOARD_ROWS];
    mr_marker_map map;
    board_map(&map, tags);
    cJSON *j = mr_marker_map_to_json(&map);
    cJSON_AddStringToObject(j, "description", "calibration board: 6x4 tag36h11 grid, ids 100..123, 40 mm tags at 60 mm pitch");
    mr_path_join(dir, "board.json", path, sizeof path);
    bool ok = mr_json_save(path, j, err);
    cJSON_Delete(j);
    /* The tag images for ids 100..123. */
    mr_image *all = NULL;
    int border = 1;
    ok = ok && mr_demo_tag_images(BOARD_FIRST_ID + BOARD_COLS * BOARD_ROWS, &all, &border, err);
    if (!ok) return false;
    mr_camera cam = mr_demo_camera();
    mr_rng rng;
    mr_rng_seed(&rng, 77);
    double cxb = 0.5 * (BOARD_COLS - 1) * BOARD_PITCH, cyb = 0.5 * (BOARD_ROWS - 1) * BOARD_PITCH;
    for (int i = 0; ok && i < images; i++) {
        /* Views from around the board: tilts up to ~35 degrees, the board
         * filling different parts of the image. */
        double a = 2 * M_PI * i / images;
        double tilt = 0.25 + 0.35 * (i % 3) / 2.0;
        double dist = 0.45 + 0.1 * (i % 2);
        mr_dvec3 eye = mr_v3(cxb + dist * sin(tilt) * cos(a), cyb + dist * sin(tilt) * sin(a), -dist * cos(tilt));
        mr_dvec3 at = mr_v3(cxb + 0.04 * cos(3 * a), cyb + 0.03 * sin(2 * a), 0);
        /* board frame: y down, z into the board; "up" for the camera is -y */
        mr_dmat4 bfc = mr_m4_look_at_cv(eye, at, mr_v3(0, -1, 0));
        mr_image img;
        ok = render_board(&cam, &bfc, all + BOARD_FIRST_ID, &rng, &img, err);
        snprintf(sub, sizeof sub, "images/board_%02d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &img, err);
        mr_image_free(&img);
    }
    mr_demo_tag_images_free(all, BOARD_FIRST_ID + BOARD_COLS * BOARD_ROWS);
    return ok;
}

bool app_demo_track(const char *dir, mr_error *err) {
    char path[4096];
    mr_path_join(dir, "calib", path, sizeof path);
    if (!app_synth_calibration(path, 12, err)) return false;
    mr_path_join(dir, "recording", path, sizeof path);
    char fl[4096];
    mr_path_join(path, "frames.jsonl", fl, sizeof fl);
    if (mr_file_exists(fl)) {
        /* A recording is never overwritten: say where the old one is. */
        printf("  recording exists, kept:        %s/\n", path);
        return true;
    }
    app_synth_params sp = APP_SYNTH_DEFAULTS;
    sp.frames = 40; /* the path subsampled: the demo stays quick */
    sp.motion_blur = 1;
    if (!app_synth_recording(path, &sp, err)) return false;
    printf("  synthetic recording (tracked, with ground truth): %s/\n", path);
    printf("  calibration board and images:  %s/calib/\n", dir);
    return true;
}

int cmd_synth(int argc, char **argv) {
    static const char *cmd = "synth";
    app_opt opts[] = {
        {"out", "DIR", "recording folder to create (required; never overwritten)", NULL},
        {"frames", "N", "frames spread over the walking path (default 120: one per path step)", NULL},
        {"size", "WxH", "frame size (default 640x480, the demo camera scaled)", NULL},
        {"noise", "SIGMA", "sensor noise in grey levels (default 2)", NULL},
        {"motion-blur", "N", "sub-frames averaged per frame, 1 = none (default 3)", NULL},
        {"exposure", "A", "relative exposure swing along the path, 0..0.9 (default 0.25)", NULL},
        {"jpeg", "Q", "JPEG quality of the stored frames (default 90)", NULL},
        {"seed", "N", "noise seed (default 1)", NULL},
        {"fps", "F", "frame rate of the timestamps (default 10)", NULL},
        {"calibration", "DIR", "instead: write a calibration board and 12 images there", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!app_parse(argc, argv, 2, opts, NULL, 0, NULL,
                   "usage: mrcheck synth --out DIR [--frames N] [--size WxH] [--noise S] [--motion-blur N] [--exposure A] [--jpeg Q]\n"
                   "Renders the as-built demo hall along a walking path with pauses and writes a tracked recording\n"
                   "with groundtruth.jsonl (needs EGL).",
                   &help))
        return 2;
    if (help) return 0;
    app_log_level(opts);
    mr_error err = {0};
    if (app_get(opts, "calibration")) {
        if (!app_synth_calibration(app_get(opts, "calibration"), 12, &err)) return app_error(cmd, &err);
        printf("wrote %s/board.json and %s/images/\n", app_get(opts, "calibration"), app_get(opts, "calibration"));
        return 0;
    }
    if (!app_get(opts, "out")) return app_errorf(cmd, "--out is required (see --help)"), 2;
    app_synth_params p = APP_SYNTH_DEFAULTS;
    long l;
    double v;
    if (app_get(opts, "frames")) {
        if (!app_int("frames", app_get(opts, "frames"), 1, 100000, &l)) return 2;
        p.frames = (int)l;
    }
    if (app_get(opts, "size") && !app_size("size", app_get(opts, "size"), &p.width, &p.height)) return 2;
    if (p.width < 64 || p.height < 48) return app_errorf(cmd, "--size must be at least 64x48"), 2;
    if (app_get(opts, "noise")) {
        if (!app_double("noise", app_get(opts, "noise"), 0, 100, &v)) return 2;
        p.noise = v;
    }
    if (app_get(opts, "motion-blur")) {
        if (!app_int("motion-blur", app_get(opts, "motion-blur"), 1, 16, &l)) return 2;
        p.motion_blur = (int)l;
    }
    if (app_get(opts, "exposure")) {
        if (!app_double("exposure", app_get(opts, "exposure"), 0, 0.9, &v)) return 2;
        p.exposure = v;
    }
    if (app_get(opts, "jpeg")) {
        if (!app_int("jpeg", app_get(opts, "jpeg"), 1, 100, &l)) return 2;
        p.jpeg_quality = (int)l;
    }
    if (app_get(opts, "seed")) {
        if (!app_int("seed", app_get(opts, "seed"), 0, 1L << 40, &l)) return 2;
        p.seed = (uint64_t)l;
    }
    if (app_get(opts, "fps")) {
        if (!app_double("fps", app_get(opts, "fps"), 0.1, 1000, &v)) return 2;
        p.fps = v;
    }
    double t0 = mr_time_now();
    if (!app_synth_recording(app_get(opts, "out"), &p, &err)) return app_error(cmd, &err);
    printf("wrote %s/ (%d frames, %dx%d) in %.1f s\n", app_get(opts, "out"), p.frames, p.width, p.height, mr_time_now() - t0);
    return 0;
}
