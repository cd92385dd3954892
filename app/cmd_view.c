/* mrcheck view: the in-situ check. A window shows the camera frame with the
 * planned model over it; big touch controls fade between them, switch the
 * depth cues, freeze the picture, snapshot it and mark discrepancies; a
 * recording replays with play/pause, step, seek and rate.
 *
 * Wiring only: the controller (lib/view: modes, settings, key map, layout,
 * scripts) takes the window's events and says what to do; this file opens
 * the window, starts capture (lib/session/capture.c, threads) and carries the
 * actions out: renders with lib/render, writes snapshots and annotations. */
#include "app.h"

#include "mr_eval.h"
#include "mr_session.h"
#include "mr_track.h"
#include "mr_ui.h"
#include "mr_view.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The UI's vertices are handed to the renderer as they are. */
_Static_assert(sizeof(mr_ui_vertex) == sizeof(mr_draw2d_vertex), "vertex layouts differ");
_Static_assert(offsetof(mr_ui_vertex, u) == offsetof(mr_draw2d_vertex, u), "vertex layouts differ");
_Static_assert(offsetof(mr_ui_vertex, rgba) == offsetof(mr_draw2d_vertex, rgba), "vertex layouts differ");

static const char *const k_cmd = "view";

typedef struct view_app {
    /* inputs */
    mr_camera camera;
    mr_marker_map markers;
    bool have_markers;
    mr_dmat4 fixed_pose;
    bool have_fixed_pose;
    char source_desc[256];
    double ui_scale;
    /* window, drawing, the controller */
    mr_window *win;
    mr_renderer *rend;
    mr_draw2d *d2;
    mr_viewer *vc;
    int fb_w, fb_h;
    bool quit;
    /* scene */
    mr_scene *scene;
    char scene_msg[600];
    mr_scene_loader *loader; /* the scene loads on a thread; the window stays live meanwhile */
    /* frames */
    mr_capture *cap;
    mr_capture_frame frame;
    bool have_frame;
    /* marks and snapshots */
    mr_pick mark_pick;
    double mark_px, mark_py;       /* camera image pixel (ideal pinhole) */
    mr_capture_frame mark_frame;           /* the frame the mark was made on */
    mr_image mark_screen;
    bool mark_grab_screen, snap_request;
    char session_dir[4096];
    /* --shadows, the scene config's, the saved setting, the C key (lib/view) */
    mr_view_shadow_choice shadows;
    int snap_count, mark_count;
    char shot_path[1024], state_path[1024];
    /* the rendered frame */
    bool need_render;
    mr_frame_result res;
    bool have_res;
    char passes[256];
    mr_ui_rect image_rect;
    int rw, rh;
    bool dimmed;
    /* issue 15: the model under the picture's centre, for "+/- N mm here" */
    bool centre_hit;
    mr_dvec3 centre_world;
    /* issue 15, Measure: the picture's camera, the planned surface's search
     * (built on the first measurement), the measurement the open mark carries */
    mr_camera picture_cam;
    mr_eval_nearest *nearest;
    bool mark_measured;
    mr_measurement mark_measure;
    /* issue 18: temporal AO (--ao-temporal); a frame after one without a valid pose restarts it */
    bool ao_temporal, ao_had_pose;
    /* stats */
    bool stats;
    double t_start;
    int64_t frames_drawn, renders, frames_skipped;
    double sum_render_ms, sum_present_ms, sum_ui_cpu_ms, sum_ui_draw_ms, sum_loop_ms;
    double fps, fps_t0;
    int64_t fps_frames;
} view_app;

/* What a snapshot of this frame's screen records. */
static mr_snapshot snapshot_of(const view_app *a, const mr_image *screen, const mr_capture_frame *f) {
    mr_snapshot sn = {screen, f, &a->camera, mr_viewer_settings(a->vc)->alpha, a->passes};
    return sn;
}

static void do_snapshot(view_app *a, const mr_image *screen) {
    char stem[64];
    mr_snapshot_next_stem(a->session_dir, "snap", &a->snap_count, stem, sizeof stem);
    mr_error err = {0};
    mr_snapshot sn = snapshot_of(a, screen, a->have_frame ? &a->frame : NULL);
    if (mr_snapshot_write(a->session_dir, stem, &sn, NULL, &err))
        mr_viewer_toast(a->vc, "snapshot saved: snapshots/%s_*", stem);
    else mr_viewer_toast(a->vc, "snapshot failed: %s", err.msg);
}

/* A tap in mark mode: what is under it, and the screen as it is now. */
static void begin_mark(view_app *a, double x, double y) {
    a->mark_measured = false; /* a mark of Mark, not of Measure */
    double u, v;
    if (!a->have_res || !mr_view_window_to_image(a->image_rect, a->rw, a->rh, x, y, &u, &v)) {
        mr_viewer_toast(a->vc, "tap on the picture to mark");
        return;
    }
    mr_error err = {0};
    if (!mr_renderer_pick(a->rend, u, v, &a->mark_pick, &err)) {
        mr_viewer_toast(a->vc, "cannot mark: %s", err.msg);
        return;
    }
    mr_view_image_to_camera(&a->camera, a->rw, a->rh, u, v, &a->mark_px, &a->mark_py);
    mr_capture_frame_copy(&a->mark_frame, &a->frame, &err);
    a->mark_grab_screen = true;
    mr_viewer_note_open(a->vc, (float)((a->mark_px + 0.5) / a->camera.width),
                        (float)((a->mark_py + 0.5) / a->camera.height));
}

static void finish_mark(view_app *a, int note) {
    if (note < 0 || note >= MR_VIEW_NOTE_COUNT) {
        mr_viewer_toast(a->vc, "mark cancelled");
        mr_image_free(&a->mark_screen);
        mr_capture_frame_free(&a->mark_frame);
        a->mark_measured = false;
        return;
    }
    mr_error err = {0};
    char stem[64];
    a->mark_count++;
    snprintf(stem, sizeof stem, "mark_%ld_%04d", (long)time(NULL), a->mark_count);
    cJSON *line = mr_view_mark_line(&a->mark_frame, mr_view_notes[note], a->mark_px, a->mark_py, &a->mark_pick, a->scene,
                                    a->mark_measured ? &a->mark_measure : NULL);
    mr_snapshot sn = snapshot_of(a, &a->mark_screen, &a->mark_frame);
    bool ok;
    mr_error aerr = {0};
    const mr_scene *sc = a->scene;
    if (!mr_mark_save(a->session_dir, stem, line, &sn, &ok, &err, &aerr))
        mr_viewer_toast(a->vc, "MARK NOT SAVED: %s", aerr.msg);
    else if (!ok) mr_viewer_toast(a->vc, "mark %d saved (snapshot failed: %s)", a->mark_count, err.msg);
    else
        mr_viewer_toast(a->vc, "mark %d saved: %s%s%s", a->mark_count, mr_view_notes[note],
                        a->mark_pick.node >= 0 && sc ? " on " : "",
                        a->mark_pick.node >= 0 && sc ? sc->nodes[a->mark_pick.node].name : "");
    cJSON_Delete(line);
    mr_image_free(&a->mark_screen);
    mr_capture_frame_free(&a->mark_frame);
    a->mark_measured = false;
}

/* issue 15: a finished measurement. Its distance to the planned surface
 * (the nearest point of the model, lib/eval), told by the controller; then
 * a mark of it at the current frame, the note chooser open, the line
 * carrying the measured_* fields and the nearest planned point as the
 * mark's point. */
static void measure_done(view_app *a) {
    mr_measurement m;
    if (!mr_viewer_measurement(a->vc, &m)) return;
    mr_error err = {0};
    mr_nearest_hit h = {0};
    if (a->scene && !a->nearest) a->nearest = mr_eval_nearest_create(a->scene, false, &err);
    if (a->nearest && mr_eval_nearest_point(a->nearest, m.tri.point, &h))
        mr_viewer_measure_distance(a->vc, h.point, h.distance, mr_eval_nearest_sigma(&h, m.tri.cov),
                                   h.node >= 0 ? a->scene->nodes[h.node].name : NULL);
    else
        mr_viewer_toast(a->vc, "measured point +/- %.1f mm; no planned surface to measure it against%s%s",
                        m.tri.sigma * 1e3, err.msg[0] ? ": " : "", err.msg);
    if (!a->have_frame) return;
    mr_viewer_measurement(a->vc, &a->mark_measure);
    a->mark_measured = true; /* the mark opened below carries it */
    mr_view_planned planned = {h.found, h.point, h.node, 0};
    if (h.found && h.node >= 0) planned.layer = a->scene->nodes[h.node].layer;
    mr_view_mark_at at;
    mr_view_measure_mark(&a->camera, a->frame.image.width, a->frame.image.height, &a->frame.pose, m.tri.point,
                         &planned, &at);
    a->mark_pick = at.pick;
    a->mark_px = at.px;
    a->mark_py = at.py;
    mr_capture_frame_copy(&a->mark_frame, &a->frame, &err);
    a->mark_grab_screen = true;
    mr_viewer_note_open(a->vc, at.note_u, at.note_v);
}

static void set_frozen(view_app *a, bool on) {
    if (a->cap) mr_capture_freeze(a->cap, on);
}

/* Carries out what the controller asked for. */
static void carry_out(view_app *a, const mr_view_actions *acts) {
    bool seekable = a->cap && mr_capture_seekable(a->cap);
    for (int i = 0; i < acts->count; i++) {
        const mr_view_action *x = &acts->a[i];
        switch (x->type) {
        case MR_VA_NONE: break;
        case MR_VA_RENDER: a->need_render = true; break;
        case MR_VA_FREEZE: set_frozen(a, x->on); break;
        case MR_VA_SNAPSHOT: a->snap_request = true; break;
        case MR_VA_MARK_AT: begin_mark(a, x->x, x->y); break;
        case MR_VA_MARK_FINISH: finish_mark(a, (int)x->i); break;
        case MR_VA_PLAY: if (seekable) mr_capture_play(a->cap, x->on); break;
        case MR_VA_STEP: if (seekable) mr_capture_step(a->cap, (int)x->i); break;
        case MR_VA_SEEK: if (a->cap) mr_capture_seek(a->cap, x->i); break;
        case MR_VA_RATE: if (a->cap) mr_capture_rate(a->cap, x->x); break;
        case MR_VA_FULLSCREEN: mr_window_set_fullscreen(a->win, !mr_window_fullscreen(a->win)); break;
        case MR_VA_RESIZE: mr_window_set_size(a->win, (int)x->x, (int)x->y); break;
        case MR_VA_SHOT: snprintf(a->shot_path, sizeof a->shot_path, "%s", x->path); break;
        case MR_VA_STATE: snprintf(a->state_path, sizeof a->state_path, "%s", x->path); break;
        case MR_VA_QUIT: a->quit = true; break;
        case MR_VA_MEASURE_DONE: measure_done(a); break;
        }
    }
}

static mr_shadow_method view_shadows(view_app *a) {
    return mr_view_shadow_choose(&a->shadows, mr_viewer_settings(a->vc)->shadows, a->scene ? a->scene->shadow_method : NULL);
}

/* Renders the 3D frame when something it depends on changed. */
static void render_3d(view_app *a) {
    if (!a->have_frame || !a->need_render) return;
    a->need_render = false;
    mr_ui_rect area = mr_ui_rect_make(0, 0, (float)a->fb_w, (float)a->fb_h);
    mr_ui_rect fit = mr_ui_fit(area, a->frame.image.width, a->frame.image.height);
    int rw = (int)lround(fit.w), rh = (int)lround(fit.h);
    if (rw < 16 || rh < 16) return;
    mr_view view;
    mr_frame_params fp;
    mr_view_render_choice c;
    mr_view_render_setup(mr_viewer_settings(a->vc), &a->camera, &a->frame, mr_viewer_frozen(a->vc), view_shadows(a),
                         a->ao_temporal, a->ao_had_pose, rw, rh, &view, &fp, &c);
    a->ao_had_pose = a->frame.have_pose && a->frame.pose_valid;
    a->dimmed = c.dimmed;
    double t0 = mr_time_now();
    mr_frame_result_free(&a->res);
    mr_error err = {0};
    a->have_res = mr_render_frame(a->rend, &view, &fp, &a->res, &err);
    a->sum_render_ms += (mr_time_now() - t0) * 1e3;
    a->renders++;
    if (!a->have_res) {
        mr_viewer_toast(a->vc, "render failed: %s", err.msg);
        a->passes[0] = 0;
        return;
    }
    a->rw = rw;
    a->rh = rh;
    a->image_rect = fit;
    /* issue 15: what is under the centre (one pixel read back per render) */
    mr_pick cp = {0};
    a->centre_hit = c.use_pose && mr_renderer_pick(a->rend, rw * 0.5 - 0.5, rh * 0.5 - 0.5, &cp, &err) && cp.hit;
    a->centre_world = cp.world;
    mr_frame_result_passes(&a->res, a->passes, sizeof a->passes);
    /* A still camera reuses the last AO: say so, or AO seems to be off. */
    if (a->res.ao_reused) strncat(a->passes, " (ao reused)", sizeof a->passes - strlen(a->passes) - 1);
}

/* `state` in a script: what a test needs to check, as JSON: the
 * controller's part, and what only the window knows (lib/view). The
 * distances of the shown picture to the model-only and video-only
 * renderings say which way the slider moved the image. */
static void write_state(view_app *a, const mr_image *screen) {
    cJSON *j = mr_viewer_state_json(a->vc);
    const mr_view_settings *s = mr_viewer_settings(a->vc);
    char msg[512] = "";
    mr_capture_status st = a->cap ? mr_capture_state(a->cap, msg, sizeof msg) : MR_CAPTURE_STARTING;
    mr_view_window_state ws = {a->mark_count, a->snap_count, mr_capture_status_name(st), msg, a->scene_msg, screen,
                               false, 0, 0, -1, -1};
    if (a->have_res && a->have_frame && a->frame.have_pose) {
        mr_view view;
        view.camera = mr_camera_resized(&a->camera, a->frame.image.width, a->frame.image.height);
        view.world_from_camera = a->frame.pose;
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.width = a->rw;
        fp.height = a->rh;
        fp.video = &a->frame.image;
        mr_view_frame_params(s, view_shadows(a), &fp);
        double d[2];
        mr_render_alpha_distances(a->rend, &view, &fp, &a->res.color, d);
        ws.have_render = true;
        ws.render_w = a->rw;
        ws.render_h = a->rh;
        ws.diff_to_model = d[0];
        ws.diff_to_video = d[1];
        a->need_render = true; /* the renderer's last frame is now another one */
    }
    mr_view_state_add_window(j, &ws);
    mr_error err = {0};
    if (!mr_json_save(a->state_path, j, &err)) mr_log(MR_LOG_ERROR, "view: %s", err.msg);
    cJSON_Delete(j);
}

static void wake_window(void *ctx) { mr_window_wake(ctx); }

/* Screen reads happen before the swap, while the back buffer holds exactly
 * what is about to be shown. */
static void read_screen(view_app *a) {
    if (!a->snap_request && !a->mark_grab_screen && !a->shot_path[0] && !a->state_path[0]) return;
    mr_image screen = {0};
    mr_error err = {0};
    if (mr_draw2d_read(a->d2, &screen, &err)) {
        if (a->snap_request) do_snapshot(a, &screen);
        if (a->shot_path[0] && !mr_image_save_png(a->shot_path, &screen, &err))
            mr_log(MR_LOG_ERROR, "view: %s", err.msg);
        if (a->state_path[0]) write_state(a, &screen);
        if (a->mark_grab_screen) {
            mr_image_free(&a->mark_screen);
            a->mark_screen = screen;
            memset(&screen, 0, sizeof screen);
        }
    }
    mr_image_free(&screen);
    a->snap_request = a->mark_grab_screen = false;
    a->shot_path[0] = a->state_path[0] = 0;
}

/* What the controller needs to know about this frame, as plain data. */
static mr_viewer_frame frame_info(view_app *a, char *state_msg, size_t n) {
    mr_viewer_frame f = {0};
    f.now = mr_time_now();
    f.fb_w = (float)a->fb_w;
    f.fb_h = (float)a->fb_h;
    f.px_per_mm = mr_window_px_per_mm(a->win) * a->ui_scale;
    mr_view_frame_from_capture(&f, &a->frame, a->have_frame, &a->camera, &a->picture_cam);
    f.seekable = a->cap && mr_capture_seekable(a->cap);
    f.playing = f.seekable && mr_capture_playing(a->cap);
    f.source_desc = a->source_desc;
    mr_capture_status st = a->cap ? mr_capture_state(a->cap, state_msg, n) : MR_CAPTURE_STARTING;
    f.source_msg = st == MR_CAPTURE_NO_CAMERA ? state_msg : NULL;
    f.scene_msg = a->scene_msg;
    f.have_image = a->have_res;
    f.image_rect = a->image_rect;
    f.dimmed = a->dimmed;
    f.passes = a->passes;
    f.fps = a->fps;
    /* issue 15: the pose's covariance is told at the point being marked
     * while the note chooser is open, else at the model under the centre */
    bool marking = mr_viewer_note_is_open(a->vc);
    f.have_point = marking ? a->mark_pick.hit : a->centre_hit;
    f.point = marking ? a->mark_pick.world : a->centre_world;
    return f;
}

/* One pass of the loop: input, newest frame, 3D render if needed, UI, draw. */
static void frame_tick(view_app *a) {
    double t0 = mr_time_now();
    mr_event e;
    while (mr_window_next_event(a->win, &e)) mr_viewer_push_event(a->vc, &e);
    mr_view_actions acts = {0};
    mr_viewer_input(a->vc, t0, a->need_render && a->have_frame, &acts);
    carry_out(a, &acts);
    mr_window_framebuffer_size(a->win, &a->fb_w, &a->fb_h);
    if (a->fb_w <= 0 || a->fb_h <= 0) return; /* minimised */

    uint64_t old_seq = a->frame.seq;
    if (a->cap && !mr_viewer_frozen(a->vc) && !mr_viewer_note_is_open(a->vc) && mr_capture_latest(a->cap, &a->frame)) {
        /* Newest wins: frames that arrived while we were busy are skipped. */
        if (old_seq > 0 && a->frame.seq > old_seq + 1) a->frames_skipped += (int64_t)(a->frame.seq - old_seq - 1);
        a->have_frame = true;
        a->need_render = true;
    }
    if (a->have_res && (a->image_rect.w != mr_ui_fit(mr_ui_rect_make(0, 0, (float)a->fb_w, (float)a->fb_h),
                                                     a->frame.image.width, a->frame.image.height).w))
        a->need_render = true;
    render_3d(a);

    double t1 = mr_time_now();
    static const float bg[3] = {0.08f, 0.09f, 0.10f};
    mr_draw2d_begin(a->d2, a->fb_w, a->fb_h, bg);
    mr_error err = {0};
    if (a->have_res && !mr_draw2d_frame(a->d2, a->rend, a->image_rect.x, a->image_rect.y, a->image_rect.w,
                                        a->image_rect.h, &err))
        mr_log(MR_LOG_ERROR, "view: %s", err.msg);
    double t2 = mr_time_now();
    a->sum_present_ms += (t2 - t1) * 1e3;

    char state_msg[512] = "";
    mr_viewer_frame f = frame_info(a, state_msg, sizeof state_msg);
    acts.count = 0;
    const mr_ui_draw_list *dl = mr_viewer_ui(a->vc, &f, &acts);
    carry_out(a, &acts);
    a->sum_ui_cpu_ms += mr_ui_last_cpu_s(mr_viewer_ui_ctx(a->vc)) * 1e3;
    double t3 = mr_time_now();
    app_draw_ui(a->d2, dl, "view");
    a->sum_ui_draw_ms += (mr_time_now() - t3) * 1e3;
    read_screen(a);
    mr_window_swap(a->win);

    double now = mr_time_now();
    a->frames_drawn++;
    a->fps_frames++;
    if (now - a->fps_t0 >= 0.5) {
        a->fps = a->fps_frames / (now - a->fps_t0);
        a->fps_t0 = now;
        a->fps_frames = 0;
    }
    a->sum_loop_ms += (now - t0) * 1e3;
}

/* ------------------------------------------------------------- wiring */

static void print_stats(view_app *a) {
    double wall = mr_time_now() - a->t_start;
    int64_t nread = 0, ntracked = 0, ndropped = 0;
    double track_sum = 0;
    if (a->cap) mr_capture_counts(a->cap, &nread, &ntracked, &ndropped, &track_sum);
    int64_t nf = a->frames_drawn > 0 ? a->frames_drawn : 1;
    printf("mrcheck view --stats: %lld frames drawn in %.1f s (%.1f fps), %lld 3D renders; "
           "%lld camera frames read, %lld tracked, newest wins: %lld skipped before tracking, %lld before drawing\n",
           (long long)a->frames_drawn, wall, a->frames_drawn / (wall > 0 ? wall : 1), (long long)a->renders,
           (long long)nread, (long long)ntracked, (long long)ndropped, (long long)a->frames_skipped);
    printf("  tracking (capture thread)  %8.2f ms per camera frame\n", ntracked ? track_sum / ntracked : 0.0);
    printf("  render (3D frame)          %8.2f ms per render, %.2f ms per drawn frame\n",
           a->renders ? a->sum_render_ms / a->renders : 0.0, a->sum_render_ms / nf);
    printf("  present (frame to window)  %8.2f ms per drawn frame\n", a->sum_present_ms / nf);
    printf("  ui: widgets + draw list    %8.3f ms CPU per drawn frame\n", a->sum_ui_cpu_ms / nf);
    printf("  ui: GL draw                %8.3f ms per drawn frame\n", a->sum_ui_draw_ms / nf);
    printf("  whole loop                 %8.2f ms per drawn frame\n", a->sum_loop_ms / nf);
}

/* Called once per loop iteration: shows the loader's progress and, when the
 * scene is ready, uploads it (on this thread, which owns the GL context). */
static void poll_scene_load(view_app *a) {
    if (!a->loader) return;
    const char *stage = NULL;
    double frac = 0;
    if (!mr_scene_loader_poll(a->loader, &stage, &frac)) {
        snprintf(a->scene_msg, sizeof a->scene_msg, "loading scene: %s %.0f%%", stage ? stage : "", 100.0 * frac);
        return;
    }
    mr_error err = {0};
    a->scene = mr_scene_loader_finish(&a->loader, &err);
    a->scene_msg[0] = 0;
    if (!a->scene) {
        snprintf(a->scene_msg, sizeof a->scene_msg, "scene failed to load: %.500s", err.msg);
        mr_log(MR_LOG_ERROR, "view: %s", a->scene_msg);
    } else if (!mr_renderer_set_scene(a->rend, a->scene, &err)) {
        snprintf(a->scene_msg, sizeof a->scene_msg, "scene failed to upload: %.500s", err.msg);
        mr_log(MR_LOG_ERROR, "view: %s", a->scene_msg);
        mr_scene_destroy(&a->scene);
    }
    a->need_render = true;
}

/* --ao and --ghost, checked before any window opens through the settings
 * file's rows (so the names are the ones A and G cycle); -1 where not given. */
static int parse_start_modes(const mr_cli_opt *opts, int *ao, int *ghost) {
    int *out[2] = {ao, ghost};
    static const char *const keys[2] = {"ao", "ghost"};
    for (int i = 0; i < 2; i++) {
        const mr_opt *o = mr_opt_find(mr_view_settings_opts, keys[i]);
        mr_view_settings s = MR_VIEW_SETTINGS_DEFAULTS;
        mr_error err = {0};
        *out[i] = -1;
        if (!mr_cli_get(opts, keys[i])) continue;
        if (!mr_opt_set_row(o, &s, mr_cli_get(opts, keys[i]), &err)) return mr_cli_errorf(k_cmd, "--%s", err.msg);
        *out[i] = (int)mr_opt_get(o, &s);
    }
    return 0;
}

/* Camera, marker map and fixed pose from the flags (or the recording). */
static int load_inputs(view_app *a, const mr_cli_opt *opts, const char *input, const char *replay) {
    mr_error err = {0};
    bool have_cam = false;
    if (mr_cli_get(opts, "camera")) {
        if (!mr_camera_load(mr_cli_get(opts, "camera"), &a->camera, &err)) return mr_cli_error(k_cmd, &err);
        have_cam = true;
    }
    if (mr_cli_get(opts, "markers")) {
        if (!mr_marker_map_load(mr_cli_get(opts, "markers"), &a->markers, &err)) return mr_cli_error(k_cmd, &err);
        a->have_markers = true;
    }
    if (mr_cli_get(opts, "view")) {
        mr_view v;
        if (!mr_view_load(mr_cli_get(opts, "view"), &v, &err)) return mr_cli_error(k_cmd, &err);
        a->fixed_pose = v.world_from_camera;
        a->have_fixed_pose = true;
        if (!have_cam) {
            a->camera = v.camera;
            have_cam = true;
        }
    }
    if (replay) {
        if (!mr_replay_meta_load(replay, &a->camera, have_cam, &a->markers, &a->have_markers, &err)) {
            mr_error_prefix(&err, "%s: ", replay);
            return mr_cli_error(k_cmd, &err);
        }
        snprintf(a->source_desc, sizeof a->source_desc, "replay");
    } else {
        if (!have_cam) return mr_cli_errorf(k_cmd, "--input needs --camera (or --view)");
        if (!a->have_markers && !a->have_fixed_pose) return mr_cli_errorf(k_cmd, "--input needs --markers (or --view)");
        snprintf(a->source_desc, sizeof a->source_desc, "live %.200s", input);
    }
    return 0;
}

/* The window, the renderer and the controller (with the settings file). */
static int open_window(view_app *a, const mr_cli_opt *opts, int ww, int wh, int ao, int ghost,
                       mr_view_script **script) {
    mr_error err = {0};
    mr_window_params wp = MR_WINDOW_DEFAULTS;
    wp.width = ww;
    wp.height = wh;
    wp.fullscreen = mr_cli_flag(opts, "fullscreen");
    wp.title = "mrcheck view";
    wp.debug = mr_log_get_level() >= MR_LOG_DEBUG;
    a->win = mr_window_create(&wp, &err);
    if (!a->win) return mr_cli_error(k_cmd, &err);
    a->rend = mr_renderer_create(mr_window_gpu(a->win), &err);
    a->d2 = a->rend ? mr_draw2d_create(mr_window_gpu(a->win), &err) : NULL;
    if (!a->d2) return mr_cli_error(k_cmd, &err);
    char config[4096];
    if (mr_cli_get(opts, "config")) snprintf(config, sizeof config, "%s", mr_cli_get(opts, "config"));
    else mr_view_default_config_path(config, sizeof config);
    mr_viewer_params vp = MR_VIEWER_DEFAULTS;
    vp.px_per_mm = mr_window_px_per_mm(a->win) * a->ui_scale;
    vp.config_path = config;
    vp.now = a->t_start;
    a->vc = mr_viewer_create(&vp, &err);
    if (!a->vc) return mr_cli_error(k_cmd, &err);
    /* Flags win over the saved settings for this run. */
    mr_view_settings s = *mr_viewer_settings(a->vc);
    if (ao >= 0) s.ao = (mr_ao_method)ao;
    if (ghost >= 0) s.ghost = (mr_ghost_mode)ghost;
    mr_viewer_set_settings(a->vc, &s);
    a->shadows.start = s.shadows;
    if (*script) mr_viewer_set_script(a->vc, script);
    return 0;
}

static int start_capture(view_app *a, const mr_cli_opt *opts, const char *input, const char *replay) {
    mr_error err = {0};
    mr_capture_params cp = {0};
    cp.input = input;
    cp.replay_dir = replay;
    cp.camera = &a->camera;
    cp.markers = a->have_markers ? &a->markers : NULL;
    cp.fixed_pose = a->have_fixed_pose ? &a->fixed_pose : NULL;
    cp.retry_s = 1.0;
    cp.retrack = mr_cli_flag(opts, "retrack");
    if (cp.retrack && !a->have_markers) return mr_cli_errorf(k_cmd, "--retrack needs a marker map");
    cp.wake = wake_window;
    cp.wake_ctx = a->win;
    a->cap = mr_capture_start(&cp, &err);
    if (!a->cap) return mr_cli_error(k_cmd, &err);
    mr_capture_rate(a->cap, mr_view_rates[mr_viewer_settings(a->vc)->rate_i]);
    if (mr_cli_flag(opts, "paused")) mr_capture_play(a->cap, false);
    return 0;
}

int cmd_view(int argc, char **argv) {
    /* The names and defaults of --ao and --ghost from the settings table. */
    char ao_help[400], ghost_help[400], desc[256];
    mr_opt_describe(mr_opt_find(mr_view_settings_opts, "ao"), desc, sizeof desc);
    snprintf(ao_help, sizeof ao_help, "start with this AO method instead of the saved one (the A key cycles): %s", desc);
    mr_opt_describe(mr_opt_find(mr_view_settings_opts, "ghost"), desc, sizeof desc);
    snprintf(ghost_help, sizeof ghost_help, "start with this ghosting mode instead of the saved one (the G key cycles): %s",
             desc);
    mr_cli_opt opts[] = {
        {"scene", "FILE", "glTF/GLB or scene config JSON (required)", NULL},
        {"input", "PATH", "live input: /dev/videoN, a video file, an image or a folder of images", NULL},
        {"camera", "C.json", "camera intrinsics of the input (required with --input)", NULL},
        {"markers", "M.json", "marker map (required with --input unless --view is given)", NULL},
        {"replay", "DIR", "replay a recording (frames/ + frames.jsonl + meta.json)", NULL},
        {"view", "V.json", "with --input IMG: a fixed pose instead of tracking", NULL},
        {"out", "DIR", "where annotations.jsonl and snapshots go (default: the recording, or ./mrcheck-session)", NULL},
        {"config", "FILE", "settings file (default ~/.config/mrcheck/view.json)", NULL},
        {"size", "WxH", "window size (default 960x720)", NULL},
        {"fullscreen", NULL, "start fullscreen (F11 toggles)", NULL},
        {"ui-scale", "S", "scale the UI beyond the screen's density (default 1)", NULL},
        {"paused", NULL, "replay: start paused", NULL},
        {"retrack", NULL, "replay: track the frames again instead of using the recorded poses", NULL},
        {"script", "FILE", "timed input events (tests, demos): see lib/view/mr_view.h", NULL},
        {"stats", NULL, "print the frame-time split on exit", NULL},
        {"ao", "METHOD", ao_help, NULL},
        {"ghost", "MODE", ghost_help, NULL},
        {"ao-temporal", NULL, "accumulate the AO over frames (reprojected; restarts when tracking is regained)", NULL},
        {"shadows", "METHOD", "soft shadows: off, hard, pcf, pcss, bp, groundtruth (default: the scene config's, else off)", NULL},
        {"verbose", NULL, "more log output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 2, opts, NULL, 0, NULL,
                   "usage: mrcheck view --scene S (--input /dev/videoN|VIDEO --camera C --markers M | --replay DIR) "
                   "[--out DIR] [--fullscreen] [--stats]",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *scene_path = mr_cli_get(opts, "scene"), *input = mr_cli_get(opts, "input"), *replay = mr_cli_get(opts, "replay");
    if (!scene_path) return mr_cli_errorf(k_cmd, "--scene is required"), 2;
    if (!input == !replay) return mr_cli_errorf(k_cmd, "give either --input or --replay"), 2;

    view_app *a = calloc(1, sizeof *a);
    if (!a) return mr_cli_errorf(k_cmd, "out of memory");
    a->t_start = a->fps_t0 = mr_time_now();
    a->stats = mr_cli_flag(opts, "stats");
    a->ao_temporal = mr_cli_flag(opts, "ao-temporal");
    a->ui_scale = 1.0;
    mr_view_script *script = NULL;
    int rc = 0, ao = -1, ghost = -1;
    mr_error err = {0};
    int ww = 960, wh = 720;
    /* Inputs that can be checked without a window are checked first. */
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &ww, &wh)) { rc = 2; goto done; }
    if (mr_cli_get(opts, "ui-scale") && !mr_cli_double("ui-scale", mr_cli_get(opts, "ui-scale"), 0.25, 8, &a->ui_scale)) {
        rc = 2;
        goto done;
    }
    if ((rc = load_inputs(a, opts, input, replay)) != 0) goto done;
    if (mr_cli_get(opts, "script") && !(script = mr_view_script_load(mr_cli_get(opts, "script"), &err))) {
        rc = mr_cli_error(k_cmd, &err);
        goto done;
    }
    if (mr_cli_get(opts, "out")) snprintf(a->session_dir, sizeof a->session_dir, "%s", mr_cli_get(opts, "out"));
    else if (replay) snprintf(a->session_dir, sizeof a->session_dir, "%s", replay);
    else snprintf(a->session_dir, sizeof a->session_dir, "mrcheck-session");
    if ((rc = parse_start_modes(opts, &ao, &ghost)) != 0) goto done;
    if (mr_cli_get(opts, "shadows")) {
        if (!mr_shadow_method_parse(mr_cli_get(opts, "shadows"), &a->shadows.flag)) {
            mr_cli_errorf(k_cmd, "--shadows must be off, hard, pcf, pcss, bp or groundtruth, not '%s'", mr_cli_get(opts, "shadows"));
            rc = 2;
            goto done;
        }
        a->shadows.given = true;
    }

    /* A scene that fails to load is shown as a message; the window still
     * opens, so the video and the controls stay usable. */
    mr_scene_params sp = MR_SCENE_DEFAULTS;
    a->loader = mr_scene_load_async(scene_path, &sp, &err);
    if (!a->loader) {
        snprintf(a->scene_msg, sizeof a->scene_msg, "scene failed to load: %.500s", err.msg);
        mr_log(MR_LOG_ERROR, "view: %s", a->scene_msg);
        memset(&err, 0, sizeof err);
    } else {
        snprintf(a->scene_msg, sizeof a->scene_msg, "loading scene ...");
    }
    if ((rc = open_window(a, opts, ww, wh, ao, ghost, &script)) != 0) goto done;
    if ((rc = start_capture(a, opts, input, replay)) != 0) goto done;
    a->need_render = true;

    while (!a->quit) {
        poll_scene_load(a);
        frame_tick(a);
        /* Sleep until input or a new frame arrives; a script or a pending
         * press keeps the loop going. */
        bool busy = mr_viewer_wants_input(a->vc);
        mr_window_wait(a->win, busy ? 0.0 : 0.1);
        if (busy) {
            struct timespec ts = {0, 4000000};
            nanosleep(&ts, NULL);
        }
    }
    if (!mr_viewer_save_settings(a->vc, &err)) mr_log(MR_LOG_WARN, "view: cannot save settings: %s", err.msg);
    if (a->stats) print_stats(a);

done:
    if (a->loader) {
        mr_error ignored = {0};
        a->scene = mr_scene_loader_finish(&a->loader, &ignored); /* waits for the thread */
    }
    mr_capture_stop(&a->cap);
    mr_capture_frame_free(&a->frame);
    mr_capture_frame_free(&a->mark_frame);
    mr_image_free(&a->mark_screen);
    mr_frame_result_free(&a->res);
    mr_viewer_destroy(&a->vc);
    mr_view_script_destroy(&script);
    mr_draw2d_destroy(&a->d2);
    mr_renderer_destroy(&a->rend);
    mr_window_destroy(&a->win);
    mr_eval_nearest_destroy(&a->nearest);
    mr_scene_destroy(&a->scene);
    mr_marker_map_free(&a->markers);
    free(a);
    return rc;
}
