/* Synthetic recordings of the demo hall with ground truth, and the
 * synthetic calibration set: what `mrcheck synth` and `mrcheck demo` write.
 * Here, not in app/, because it needs render + session + track at once and
 * lib/bench is the lowest library that may (the tracking bench reads these
 * recordings). The camera frames come from mr_demo_camera_frame and the
 * board images from mr_demo_board_render (lib/scene). */
#include "bench_internal.h"
#include "mr_session.h"
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ the path */

/* Keyframes of the check walk: eye, look-at target and how many
 * path steps (0.1 s each at the default 10 fps) to pause there (the camera
 * is still: jitter is measured there) before walking `walk` steps to the
 * next keyframe. From the yellow lathe and the roller conveyor in the east,
 * past the robot cell that was installed 0.30 m off its plan, along the
 * west roller conveyor, to the missing column and the partition with the
 * raised pipe behind it. Each pause faces one of the hall's tag posts (four
 * tags on two faces, 3.5-5 m away), which stay in view while walking on.
 * The walks are paced as a person walks with a tablet: 5.6, 8.9 and 4.0 m
 * in 5.1, 8.1 and 3.7 s, about 1.1 m/s on average and 1.4 m/s at most
 * (walk_u); the first recording covered the same distances in 2.9, 2.9 and
 * 1.6 s, up to 4.5 m/s, a run, whose blur no detector setting could read. */
typedef struct keyframe { double eye[3], at[3]; int pause, walk; } keyframe;
static const keyframe k_path[] = {
    {{11.5, 1.60, 4.0}, {9.0, 1.3, -0.5}, 10, 51},    /* lathe, roller conveyor, post 0 */
    {{6.0, 1.60, 5.0}, {0.8, 1.2, 0.3}, 12, 81},      /* the moved robot cell, post 1 */
    {{-2.5, 1.60, 2.5}, {-8.0, 1.1, 0.5}, 10, 37},    /* west conveyor, post 2 */
    {{-6.5, 1.60, 3.0}, {-12.0, 1.8, 6.0}, 16, 0},    /* missing column, partition, post 3 */
};
#define PATH_KEYS (int)(sizeof k_path / sizeof k_path[0])

int mr_synth_path_frames(void) {
    int n = 0;
    for (int i = 0; i < PATH_KEYS; i++) n += k_path[i].pause + k_path[i].walk;
    return n;
}

/* Walked fraction at x in [0,1] of a walk: speeding up over the first
 * fifth, a steady pace, slowing down over the last fifth (peak speed 1.25x
 * the mean; a smoothstep's 1.5x is a lunge). */
static double walk_u(double x) {
    const double a = 0.2, v = 1.0 / (1.0 - a);
    x = x < 0 ? 0 : x > 1 ? 1 : x;
    if (x < a) return v * x * x / (2 * a);
    if (x > 1 - a) return 1 - v * (1 - x) * (1 - x) / (2 * a);
    return v * (x - a / 2);
}

/* Pose at path position s in [0, mr_synth_path_frames()) (fractional), and
 * whether the camera stands still there. */
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
            double u = walk_u((s - base - k->pause + 1) / (k->walk + 1));
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

bool mr_synth_recording(const char *dir, const mr_synth_recording_params *params, const mr_bench_gpu *gfx, mr_error *err) {
    mr_synth_recording_params p = params ? *params : (mr_synth_recording_params){MR_SYNTH_RECORDING_DEFAULTS};
    if (!bench_gpu_check(gfx, "synth", err)) return false;
    if (p.frames < 0 || p.width < 64 || p.height < 48 || p.motion_blur < 1 || p.motion_blur > 16 || p.noise < 0 ||
        p.exposure < 0 || p.exposure >= 1 || p.fps <= 0 || !(p.shutter >= 1 && p.shutter <= 1e5))
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
    ok = ok && mr_renderer_set_scene(gfx->renderer, hall.built, err);
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
    mr_camera wide = mr_demo_wide_camera(&cam, margin);
    mr_image ideal[16];
    memset(ideal, 0, sizeof ideal);
    mr_rng rng;
    mr_rng_seed(&rng, p.seed);
    const int total = mr_synth_path_frames();
    const int frames = p.frames > 0 ? p.frames : total;
    int with_pose = 0, stopped = -1;
    for (int i = 0; ok && i < frames; i++) {
        if (mr_stop_requested()) {
            stopped = i;
            break;
        }
        /* Spread the frames over the whole path; the timestamps are the
         * path's clock (one step per 1/fps), so fewer frames are further
         * apart in time, never a faster walk. */
        double s = frames > 1 ? (double)i * (total - 1) / (frames - 1) : 0;
        bool still = false;
        mr_dmat4 truth = path_pose(s, &still);
        double t = s / p.fps;
        /* Sub-frames over the open shutter, 1/shutter s before the frame's
         * time (1/60 s: an indoor tablet's auto-exposure at walking pace). */
        for (int k = 0; ok && k < p.motion_blur; k++) {
            double sk = p.motion_blur > 1 ? s - p.fps / p.shutter * (double)k / (p.motion_blur - 1) : s;
            mr_view v = {wide, path_pose(sk < 0 ? 0 : sk, NULL)};
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = wide.width * scale;
            fp.height = wide.height * scale;
            mr_frame_result res;
            ok = mr_render_frame(gfx->renderer, &v, &fp, &res, err);
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
        if (ok && i % 10 == 0) mr_log(MR_LOG_INFO, "synth: frame %d/%d, %d tags", i, frames, n);
        if (ok && p.progress) fprintf(stderr, "\rsynth: frame %d/%d", i + 1, frames);
    }
    if (p.progress) fprintf(stderr, "\r\033[K");
    for (int k = 0; k < 16; k++) mr_image_free(&ideal[k]);
    if (ok) mr_log(MR_LOG_INFO, "synth: %d frames, %d with a pose", frames, with_pose);
    mr_recorder_close(&rec);
    /* Every frame appended so far is whole in the recording (frames.jsonl,
     * groundtruth.jsonl and the images are append-only). */
    if (ok && stopped >= 0)
        ok = mr_fail(err, MR_ERR_INTERRUPTED, "interrupted after frame %d: %d of %d frames in %s", stopped - 1, stopped,
                     frames, dir);
    mr_tracker_destroy(&trk);
    mr_renderer_set_scene(gfx->renderer, NULL, NULL); /* the caller's renderer keeps no scene of ours */
    mr_marker_map_free(&map);
    mr_demo_free(&hall);
    return ok;
}

/* ------------------------------------------------------- calibration set */

bool mr_synth_calibration(const char *dir, int images, mr_error *err) {
    if (images < 1) return mr_fail(err, MR_ERR_INVALID, "synth calibration: need at least one image");
    enum { n_tags = MR_DEMO_BOARD_COLS * MR_DEMO_BOARD_ROWS };
    char path[4096], sub[4096];
    mr_path_join(dir, "images", sub, sizeof sub);
    if (!mr_mkdirs(sub, err)) return false;
    /* Written as a marker map, so calibrate reads the same format. */
    mr_marker tags[n_tags];
    mr_marker_map map;
    memset(&map, 0, sizeof map);
    snprintf(map.family, sizeof map.family, "tag36h11");
    map.tag_size = MR_DEMO_BOARD_TAG;
    map.tags = tags;
    map.count = n_tags;
    for (int i = 0; i < n_tags; i++) {
        memset(&tags[i], 0, sizeof tags[i]);
        tags[i].id = mr_demo_board_tag(i, &tags[i].world_from_tag);
    }
    cJSON *j = mr_marker_map_to_json(&map);
    cJSON_AddStringToObject(j, "description", "calibration board: 6x4 tag36h11 grid, ids 100..123, 40 mm tags at 60 mm pitch");
    mr_path_join(dir, "board.json", path, sizeof path);
    bool ok = mr_json_save(path, j, err);
    cJSON_Delete(j);
    /* The tag images for ids 100..123. */
    mr_image *all = NULL;
    int border = 1;
    ok = ok && mr_demo_tag_images(MR_DEMO_BOARD_FIRST_ID + n_tags, &all, &border, err);
    if (!ok) return false;
    mr_camera cam = mr_demo_camera();
    mr_rng rng;
    mr_rng_seed(&rng, 77);
    double cxb = 0.5 * (MR_DEMO_BOARD_COLS - 1) * MR_DEMO_BOARD_PITCH, cyb = 0.5 * (MR_DEMO_BOARD_ROWS - 1) * MR_DEMO_BOARD_PITCH;
    for (int i = 0; ok && i < images; i++) {
        if (mr_stop_requested()) {
            ok = mr_fail(err, MR_ERR_INTERRUPTED, "interrupted after image %d: board.json and %d of %d images in %s", i - 1,
                         i, images, dir);
            break;
        }
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
        ok = mr_demo_board_render(&cam, &bfc, all + MR_DEMO_BOARD_FIRST_ID, &rng, &img, err);
        snprintf(sub, sizeof sub, "images/board_%02d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &img, err);
        mr_image_free(&img);
    }
    mr_demo_tag_images_free(all, MR_DEMO_BOARD_FIRST_ID + n_tags);
    return ok;
}
