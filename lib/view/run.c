/* The interactive check's window loop (`mrcheck view`): opens the window,
 * starts capture (lib/session/capture.c, threads), feeds the controller its
 * events and carries its actions out: renders with lib/render, writes
 * snapshots and annotations. It lives here rather than in app/ so that the
 * command is only its flags; everything it touches goes through the public
 * headers of lib/window (window, events, 2D layer), lib/render (renderer:
 * no GL type), lib/session and lib/ui. The planned surface that Measure needs comes from
 * the caller (mr_view_nearest_fns): lib/eval is above lib/view. */
#include "mr_view.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Camera, marker map and fixed pose from the flags (or the recording). */
static bool source_load(const mr_view_source_params *p, mr_view_source *out, mr_error *err) {
    if (!p->input == !p->replay_dir) return mr_fail(err, MR_ERR_INVALID, "give either --input or --replay");
    out->input = p->input;
    out->replay_dir = p->replay_dir;
    bool have_cam = false;
    if (p->camera_path) {
        if (!mr_camera_load(p->camera_path, &out->camera, err)) return false;
        have_cam = true;
    }
    if (p->markers_path) {
        if (!mr_marker_map_load(p->markers_path, &out->markers, err)) return false;
        out->have_markers = true;
    }
    if (p->view_path) {
        mr_view v;
        if (!mr_view_load(p->view_path, &v, err)) return false;
        out->fixed_pose = v.world_from_camera;
        out->have_fixed_pose = true;
        if (!have_cam) {
            out->camera = v.camera;
            have_cam = true;
        }
    }
    if (p->replay_dir) {
        /* A folder with no frames (empty, or not a recording) ends here,
         * not in a window that waits for frames forever. */
        mr_replay *r = mr_replay_open(p->replay_dir, err);
        if (!r) return false; /* the message names the folder */
        mr_replay_close(&r);
        if (!mr_replay_meta_load(p->replay_dir, &out->camera, have_cam, &out->markers, &out->have_markers, err)) {
            mr_error_prefix(err, "%s: ", p->replay_dir);
            return false;
        }
        snprintf(out->desc, sizeof out->desc, "replay");
    } else {
        if (!have_cam) return mr_fail(err, MR_ERR_INVALID, "--input needs --camera (or --view)");
        if (!out->have_markers && !out->have_fixed_pose)
            return mr_fail(err, MR_ERR_INVALID, "--input needs --markers (or --view)");
        /* Only a camera device may come later (plugged in, or busy): a file
         * or folder that cannot be opened now never will be. */
        if (strncmp(p->input, "/dev/video", 10) != 0) {
            mr_source_params sp = MR_SOURCE_DEFAULTS;
            mr_source *probe = mr_source_open(p->input, &sp, err);
            if (!probe) return false;
            mr_source_close(&probe);
        }
        snprintf(out->desc, sizeof out->desc, "live %.200s", p->input);
    }
    return true;
}

bool mr_view_source_load(const mr_view_source_params *p, mr_view_source *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (source_load(p, out, err)) return true;
    mr_view_source_free(out);
    return false;
}

void mr_view_source_free(mr_view_source *s) {
    if (!s) return;
    mr_marker_map_free(&s->markers);
    memset(s, 0, sizeof *s);
}

typedef struct view_app {
    /* inputs */
    const mr_view_source *src;
    double ui_scale;
    mr_view_nearest_fns nearest_fns;
    mr_tolerances *tolerances;  /* Measure's verdicts; NULL: DIN 18202 */
    /* window, drawing, the controller */
    mr_window *win;
    mr_renderer *rend;
    mr_draw2d *d2;
    mr_viewer *vc;
    int fb_w, fb_h;
    bool quit;
    bool failed;           /* quit because an input turned out unusable: err says why */
    mr_error fail_err;
    /* scene */
    mr_scene *scene;
    char scene_msg[600];
    mr_scene_loader *loader; /* the scene loads on a thread; the window stays live meanwhile */
    /* Levels of detail of a big scene (MR_LOD_AUTO_TRIANGLES, as render's
     * --lod auto), read from <scene>.mrlod or built on a thread while the
     * full detail is drawn; the renderer holds lod until it is destroyed. */
    mr_lod_builder *lod_builder;
    mr_lod *lod;
    mr_hlod *hlod; /* levels above the part (after lod, same thread; <scene>.mrhlod) where the scene wants them */
    bool upload_pending; /* the scene waits for its levels from the cache: one upload of both */
    double pending_since;
    /* frames */
    mr_capture *cap;
    mr_capture_frame frame;
    bool have_frame;
    /* marks and snapshots */
    mr_pick mark_pick;
    double mark_px, mark_py;       /* camera image pixel (ideal pinhole) */
    mr_capture_frame mark_frame;           /* the frame the mark was made on */
    mr_image mark_screen;                  /* the rendered picture, no UI, with the pin */
    double mark_u, mark_v;                 /* the mark in the rendered picture, px */
    bool snap_request;
    /* the session's marks (the newest line of each), shown as pins */
    mr_annotations marks;
    char session_dir[4096];
    /* --shadows, the scene config's, the saved setting, the C key (mark.c) */
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
    /* The model under the picture's centre, for "+/- N mm here" */
    bool centre_hit;
    mr_dvec3 centre_world;
    /* Measure: the picture's camera, the planned surface's search
     * (built on the first measurement), the measurement the open mark carries */
    mr_camera picture_cam;
    void *nearest;
    bool mark_measured;
    mr_measurement mark_measure;
    bool mark_judged;                      /* the measurement has a verdict */
    mr_verdict mark_verdict;
    /* Temporal AO (--ao-temporal); a frame after one without a valid pose restarts it */
    bool ao_temporal, ao_had_pose;
    /* stats */
    double t_start;
    int64_t frames_drawn, renders, frames_skipped;
    double sum_render_ms, sum_present_ms, sum_ui_cpu_ms, sum_ui_draw_ms, sum_loop_ms;
    double fps, fps_t0;
    int64_t fps_frames;
} view_app;

/* What a snapshot of this frame's screen records. */
static mr_snapshot snapshot_of(const view_app *a, const mr_image *screen, const mr_capture_frame *f) {
    mr_snapshot sn = {screen, f, &a->src->camera, mr_viewer_settings(a->vc)->alpha, a->passes};
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

/* The mark's picture: the rendered frame as the planner saw it, without
 * the UI, and the raw camera frame, each with the pin at the marked point
 * (the raw frame's pin distorted like the frame). */
static void grab_mark_pictures(view_app *a, mr_error *err) {
    mr_image_free(&a->mark_screen);
    if (a->have_res && a->res.color.data &&
        mr_image_alloc(&a->mark_screen, a->res.color.width, a->res.color.height, a->res.color.channels, MR_PIX_U8, err)) {
        memcpy(a->mark_screen.data, a->res.color.data, mr_image_bytes(&a->res.color));
        mr_view_draw_pin(&a->mark_screen, a->mark_u, a->mark_v);
    }
    mr_capture_frame_copy(&a->mark_frame, &a->frame, err);
    const mr_camera *cam = &a->src->camera;
    mr_image *fr = &a->mark_frame.image;
    if (!fr->data || fr->width <= 0) return;
    mr_camera c = mr_camera_resized(cam, fr->width, fr->height);
    double sx = (double)fr->width / cam->width, sy = (double)fr->height / cam->height;
    double px = (a->mark_px + 0.5) * sx - 0.5, py = (a->mark_py + 0.5) * sy - 0.5, xd, yd;
    mr_camera_distort(&c, (px - c.cx) / c.fx, (py - c.cy) / c.fy, &xd, &yd);
    mr_view_draw_pin(fr, c.fx * xd + c.cx, c.fy * yd + c.cy);
}

/* The session's marks read again (the newest line of each) and shown as pins. */
static void reload_marks(view_app *a) {
    char path[4200];
    mr_path_join(a->session_dir, "annotations.jsonl", path, sizeof path);
    mr_annotations_free(&a->marks);
    mr_error err = {0};
    if (!mr_annotations_load(path, &a->marks, &err)) {
        mr_log(MR_LOG_WARN, "view: %s", err.msg);
        return;
    }
    mr_annotations_current(&a->marks);
    for (int i = 0; i < a->marks.count; i++) {
        const mr_annotation *m = &a->marks.items[i];
        mr_view_pin pin;
        memset(&pin, 0, sizeof pin);
        pin.number = i + 1;
        pin.has_world = m->hit || m->has_measurement;
        double *w = m->hit ? (double *)m->world : NULL;
        pin.world = w ? mr_v3(w[0], w[1], w[2]) : m->measurement.tri.point;
        pin.closed = strcmp(m->status, "closed") == 0;
        pin.category = -1;
        pin.verdict = m->has_verdict ? m->verdict.kind : MR_VERDICT_NONE;
        for (int k = 0; k < MR_MARK_CATEGORY_COUNT; k++)
            if (strcmp(m->category, mr_mark_categories[k]) == 0) pin.category = k;
        /* The editor shows the note with its fields written inline. */
        size_t n = (size_t)snprintf(pin.note, sizeof pin.note, "%s", m->note);
        if (m->assignee[0] && n < sizeof pin.note) n += (size_t)snprintf(pin.note + n, sizeof pin.note - n, " @%s", m->assignee);
        for (int l = 0; l < m->label_count && n < sizeof pin.note; l++)
            n += (size_t)snprintf(pin.note + n, sizeof pin.note - n, " #%s", m->labels[l]);
        if (m->priority[0] && n < sizeof pin.note) snprintf(pin.note + n, sizeof pin.note - n, " !%s", m->priority);
        if (m->title[0]) snprintf(pin.title, sizeof pin.title, "%s", m->title);
        else mr_mark_title(m, pin.title, sizeof pin.title);
        mr_viewer_pin_put(a->vc, i, &pin);
    }
}

/* A saved mark edited or closed: a new line that supersedes it. */
static void edit_mark(view_app *a, int i, int category, const char *typed, bool close) {
    if (i < 0 || i >= a->marks.count) return;
    const mr_annotation *m = &a->marks.items[i];
    mr_annotation *e = calloc(1, sizeof *e);
    if (!e) return;
    snprintf(e->category, sizeof e->category, "%s",
             category >= 0 && category < MR_MARK_CATEGORY_COUNT ? mr_mark_categories[category] : m->category);
    mr_mark_set_note(e, typed);
    snprintf(e->status, sizeof e->status, "%s", close ? "closed" : m->status);
    cJSON *line = mr_annotation_edit_line(m, e, (double)time(NULL));
    free(e);
    char path[4200];
    mr_path_join(a->session_dir, "annotations.jsonl", path, sizeof path);
    mr_error err = {0};
    if (!line || !mr_annotation_append(path, line, &err)) mr_viewer_toast(a->vc, "EDIT NOT SAVED: %s", line ? err.msg : "out of memory");
    else mr_viewer_toast(a->vc, "mark %d %s", i + 1, close ? "closed" : "saved");
    cJSON_Delete(line);
    reload_marks(a);
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
    /* What the planner tapped, as the model names it. */
    char what[300];
    mr_scene_element_describe(a->scene, a->mark_pick.node, 3, what, sizeof what);
    if (what[0]) mr_viewer_toast(a->vc, "%s", what);
    const mr_camera *cam = &a->src->camera;
    mr_view_image_to_camera(cam, a->rw, a->rh, u, v, &a->mark_px, &a->mark_py);
    a->mark_u = u;
    a->mark_v = v;
    grab_mark_pictures(a, &err);
    mr_viewer_note_open(a->vc, (float)((a->mark_px + 0.5) / cam->width), (float)((a->mark_py + 0.5) / cam->height));
}

static void finish_mark(view_app *a, int note, const char *typed) {
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
    char id[40];
    mr_mark_new_id((double)time(NULL), a->mark_count, id, sizeof id);
    mr_view_mark_words w = {id, note, typed};
    cJSON *line = mr_view_mark_line(&a->mark_frame, &w, a->mark_px, a->mark_py, &a->mark_pick, a->scene,
                                    a->mark_measured ? &a->mark_measure : NULL,
                                    a->mark_measured && a->mark_judged ? &a->mark_verdict : NULL);
    mr_snapshot sn = snapshot_of(a, &a->mark_screen, &a->mark_frame);
    bool ok;
    mr_error aerr = {0};
    const mr_scene *sc = a->scene;
    if (!mr_mark_save(a->session_dir, stem, line, &sn, &ok, &err, &aerr))
        mr_viewer_toast(a->vc, "MARK NOT SAVED: %s", aerr.msg);
    else if (!ok) mr_viewer_toast(a->vc, "mark %d saved (snapshot failed: %s)", a->mark_count, err.msg);
    else
        mr_viewer_toast(a->vc, "mark saved: %s%s%s", mr_mark_categories[note], a->mark_pick.node >= 0 && sc ? " on " : "",
                        a->mark_pick.node >= 0 && sc ? sc->nodes[a->mark_pick.node].name : "");
    cJSON_Delete(line);
    reload_marks(a);
    mr_image_free(&a->mark_screen);
    mr_capture_frame_free(&a->mark_frame);
    a->mark_measured = false;
}

/* A finished measurement. Its distance to the planned surface
 * (the nearest point of the model, the caller's search), told by the
 * controller; then a mark of it at the current frame, the note chooser
 * open, the line carrying the measured_* fields and the nearest planned
 * point as the mark's point. */
static void measure_done(view_app *a) {
    mr_measurement m;
    if (!mr_viewer_measurement(a->vc, &m)) return;
    mr_error err = {0};
    mr_view_nearest_hit h = {0};
    const mr_view_nearest_fns *nf = &a->nearest_fns;
    if (a->scene && !a->nearest && nf->create) a->nearest = nf->create(nf->user, a->scene, &err);
    if (a->nearest && nf->query(nf->user, a->nearest, m.tri.point, m.tri.cov, &h)) {
        const mr_node *n = h.node >= 0 ? &a->scene->nodes[h.node] : NULL;
        mr_viewer_measure_distance(a->vc, h.point, h.distance, h.sigma, n ? n->name : NULL,
                                   n ? (n->layer == MR_LAYER_HIDDEN ? "hidden" : "visible") : NULL);
    }
    else
        mr_viewer_toast(a->vc, "measured point +/- %.1f mm; no planned surface to measure it against%s%s",
                        m.tri.sigma * 1e3, err.msg[0] ? ": " : "", err.msg);
    if (!a->have_frame) return;
    mr_viewer_measurement(a->vc, &a->mark_measure);
    a->mark_judged = mr_viewer_measure_verdict(a->vc, &a->mark_verdict);
    a->mark_measured = true; /* the mark opened below carries it and its verdict */
    mr_view_planned planned = {h.found, h.point, h.node, 0};
    if (h.found && h.node >= 0) planned.layer = a->scene->nodes[h.node].layer;
    mr_view_mark_at at;
    mr_view_measure_mark(&a->src->camera, a->frame.image.width, a->frame.image.height, &a->frame.pose, m.tri.point,
                         &planned, &at);
    a->mark_pick = at.pick;
    a->mark_px = at.px;
    a->mark_py = at.py;
    a->mark_u = (at.px + 0.5) * a->rw / a->src->camera.width - 0.5;
    a->mark_v = (at.py + 0.5) * a->rh / a->src->camera.height - 0.5;
    grab_mark_pictures(a, &err);
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
        case MR_VA_MARK_FINISH: finish_mark(a, (int)x->i, x->path); break;
        case MR_VA_MARK_EDIT: edit_mark(a, (int)x->x, (int)x->i, x->path, x->on); break;
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
    return mr_view_shadow_choose(&a->shadows, mr_view_shadows(mr_viewer_settings(a->vc)),
                                 a->scene ? a->scene->shadow_method : NULL);
}

/* Where the picture goes: the area the panels leave free, so that no part
 * of it is under a control. */
static mr_ui_rect picture_fit(view_app *a) {
    bool seekable = a->cap && mr_capture_seekable(a->cap);
    mr_ui_rect area = mr_viewer_picture_area(a->vc, (float)a->fb_w, (float)a->fb_h, seekable);
    return mr_ui_fit(area, a->frame.image.width, a->frame.image.height);
}

/* Renders the 3D frame when something it depends on changed. */
static void render_3d(view_app *a) {
    if (!a->have_frame || !a->need_render) return;
    a->need_render = false;
    mr_ui_rect fit = picture_fit(a);
    int rw = (int)lround(fit.w), rh = (int)lround(fit.h);
    if (rw < 16 || rh < 16) return;
    mr_view view;
    mr_frame_params fp;
    mr_view_render_choice c;
    mr_view_render_setup(mr_viewer_settings(a->vc), &a->src->camera, &a->frame, mr_viewer_frozen(a->vc), view_shadows(a),
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
    /* What is under the centre (one pixel read back per render) */
    mr_pick cp = {0};
    a->centre_hit = c.use_pose && mr_renderer_pick(a->rend, rw * 0.5 - 0.5, rh * 0.5 - 0.5, &cp, &err) && cp.hit;
    a->centre_world = cp.world;
    mr_frame_result_passes(&a->res, a->passes, sizeof a->passes);
    /* A still camera reuses the last AO: say so, or AO seems to be off. */
    if (a->res.ao_reused) strncat(a->passes, " (ao reused)", sizeof a->passes - strlen(a->passes) - 1);
}

/* `state` in a script: what a test needs to check, as JSON: the
 * controller's part, and what only the window knows (mark.c). The
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
        view.camera = mr_camera_resized(&a->src->camera, a->frame.image.width, a->frame.image.height);
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
    if (!a->snap_request && !a->shot_path[0] && !a->state_path[0]) return;
    mr_image screen = {0};
    mr_error err = {0};
    /* A snapshot is the picture as rendered, without the UI over it. */
    if (a->snap_request && a->have_res && a->res.color.data) do_snapshot(a, &a->res.color);
    else if (a->snap_request) mr_viewer_toast(a->vc, "nothing to snapshot yet");
    if ((a->shot_path[0] || a->state_path[0]) && mr_draw2d_read(a->d2, &screen, &err)) {
        if (a->shot_path[0] && !mr_image_save_png(a->shot_path, &screen, &err))
            mr_log(MR_LOG_ERROR, "view: %s", err.msg);
        if (a->state_path[0]) write_state(a, &screen);
    }
    mr_image_free(&screen);
    a->snap_request = false;
    a->shot_path[0] = a->state_path[0] = 0;
}

/* What the controller needs to know about this frame, as plain data. */
static mr_viewer_frame frame_info(view_app *a, char *state_msg, size_t n) {
    mr_viewer_frame f = {0};
    f.now = mr_time_now();
    f.fb_w = (float)a->fb_w;
    f.fb_h = (float)a->fb_h;
    f.px_per_mm = mr_window_px_per_mm(a->win) * a->ui_scale;
    mr_view_frame_from_capture(&f, &a->frame, a->have_frame, &a->src->camera, &a->picture_cam);
    f.seekable = a->cap && mr_capture_seekable(a->cap);
    f.playing = f.seekable && mr_capture_playing(a->cap);
    f.source_desc = a->src->desc;
    mr_capture_status st = a->cap ? mr_capture_state(a->cap, state_msg, n) : MR_CAPTURE_STARTING;
    f.source_msg = st == MR_CAPTURE_NO_CAMERA ? state_msg : NULL;
    f.scene_msg = a->scene_msg;
    f.have_image = a->have_res;
    f.image_rect = a->image_rect;
    f.dimmed = a->dimmed;
    f.passes = a->passes;
    f.fps = a->fps;
    /* The pose's covariance is told at the point being marked
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
    if (a->have_res && (a->image_rect.w != picture_fit(a).w || a->image_rect.x != picture_fit(a).x))
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
    mr_draw2d_ui(a->d2, dl, "view");
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

/* ------------------------------------------------------------- start, end */

static void print_stats(view_app *a, FILE *out) {
    double wall = mr_time_now() - a->t_start;
    int64_t nread = 0, ntracked = 0, ndropped = 0;
    double track_sum = 0;
    if (a->cap) mr_capture_counts(a->cap, &nread, &ntracked, &ndropped, &track_sum);
    int64_t nf = a->frames_drawn > 0 ? a->frames_drawn : 1;
    fprintf(out, "mrcheck view --stats: %lld frames drawn in %.1f s (%.1f fps), %lld 3D renders; "
                 "%lld camera frames read, %lld tracked, newest wins: %lld skipped before tracking, %lld before drawing\n",
            (long long)a->frames_drawn, wall, a->frames_drawn / (wall > 0 ? wall : 1), (long long)a->renders,
            (long long)nread, (long long)ntracked, (long long)ndropped, (long long)a->frames_skipped);
    fprintf(out, "  tracking (capture thread)  %8.2f ms per camera frame\n", ntracked ? track_sum / ntracked : 0.0);
    fprintf(out, "  render (3D frame)          %8.2f ms per render, %.2f ms per drawn frame\n",
            a->renders ? a->sum_render_ms / a->renders : 0.0, a->sum_render_ms / nf);
    fprintf(out, "  present (frame to window)  %8.2f ms per drawn frame\n", a->sum_present_ms / nf);
    fprintf(out, "  ui: widgets + draw list    %8.3f ms CPU per drawn frame\n", a->sum_ui_cpu_ms / nf);
    fprintf(out, "  ui: GL draw                %8.3f ms per drawn frame\n", a->sum_ui_draw_ms / nf);
    fprintf(out, "  whole loop                 %8.2f ms per drawn frame\n", a->sum_loop_ms / nf);
}

/* Uploads the scene with lod (NULL: full detail); a failure is shown as
 * the scene's message and drops the scene (after any build reading it). */
static bool upload_scene(view_app *a, const mr_lod *lod) {
    mr_error err = {0};
    if (mr_renderer_set_scene_lod(a->rend, a->scene, lod, &err)) return true;
    snprintf(a->scene_msg, sizeof a->scene_msg, "scene failed to upload: %.500s", err.msg);
    mr_log(MR_LOG_ERROR, "view: %s", a->scene_msg);
    mr_lod_builder_cancel(&a->lod_builder);
    mr_renderer_set_scene(a->rend, NULL, &err);
    mr_hlod_destroy(&a->hlod);
    mr_lod_destroy(&a->lod);
    mr_scene_destroy(&a->scene);
    return false;
}

/* Called once per loop iteration: shows the loader's progress and, when the
 * scene is ready, uploads it (on this thread, which owns the GL context)
 * and starts on its levels of detail if it is big. */
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
    a->need_render = true;
    if (!a->scene) {
        /* A plan that cannot be read ends the check: there is nothing to
         * compare with (the caller says why, in one line). */
        a->failed = a->quit = true;
        a->fail_err = err;
        return;
    }
    char cache[4096], hcache[4096];
    mr_lod_cache_path(a->scene->source, cache, sizeof cache);
    mr_hlod_cache_path(a->scene->source, hcache, sizeof hcache);
    const bool has_file = a->scene->source[0] != 0;
    if (mr_lod_wanted(MR_LOD_MODE_AUTO, a->scene)) {
        mr_lod_params lp = MR_LOD_DEFAULTS;
        a->lod_builder = mr_lod_build_async_hlod(a->scene, has_file ? cache : NULL, &lp, "auto", has_file ? hcache : NULL, &err);
        if (!a->lod_builder) mr_log(MR_LOG_WARN, "view: no levels of detail: %s", err.msg);
    }
    /* With a cache file the levels come in a fraction of the scene's load
     * (0.3 s for 20M triangles, measured in bench scene): the scene waits
     * for them and is uploaded once, not in full detail first and again
     * with the levels (2.3 s each at 20M). A cache that turns out stale
     * is rebuilt: after a second the full detail is uploaded meanwhile. */
    FILE *f = a->lod_builder && has_file ? fopen(cache, "rb") : NULL;
    if (f) {
        fclose(f);
        a->upload_pending = true;
        a->pending_since = mr_time_now();
        snprintf(a->scene_msg, sizeof a->scene_msg, "loading levels of detail ...");
    } else {
        upload_scene(a, NULL);
    }
}

/* Called once per loop iteration: the levels, once read or built, go to
 * the renderer (an upload of the levels, on this, the GL thread); until
 * then, and where they fail, the full detail is drawn. */
static void poll_lod(view_app *a) {
    if (a->upload_pending && mr_time_now() - a->pending_since > 1.0) {
        a->upload_pending = false; /* a rebuild: the full detail until it is done */
        a->scene_msg[0] = 0;
        a->need_render = true;
        if (!upload_scene(a, NULL)) return;
    }
    if (!a->lod_builder || !mr_lod_builder_poll(a->lod_builder, NULL)) return;
    mr_error err = {0};
    mr_lod_info info;
    a->lod = mr_lod_builder_finish_hlod(&a->lod_builder, &info, &a->hlod, &err);
    a->need_render = true;
    if (a->upload_pending) {
        a->upload_pending = false;
        a->scene_msg[0] = 0;
        if (!upload_scene(a, a->lod)) return;
    } else if (a->lod && !mr_renderer_set_lod(a->rend, a->lod, &err)) {
        mr_hlod_destroy(&a->hlod);
        mr_lod_destroy(&a->lod);
    }
    mr_error herr = {0};
    if (a->lod && a->hlod && !mr_renderer_set_hlod(a->rend, a->hlod, &herr)) {
        mr_log(MR_LOG_WARN, "view: no levels above the part: %s", herr.msg);
        mr_hlod_destroy(&a->hlod);
    }
    if (!a->lod) {
        mr_log(MR_LOG_WARN, "view: no levels of detail: %s", err.msg);
        return;
    }
    if (info.from_cache) {
        mr_log(MR_LOG_INFO, "view: %llu levels of detail from the cache", (unsigned long long)info.levels);
    } else {
        mr_log(MR_LOG_INFO, "view: %llu levels of detail built in %.2f s%s", (unsigned long long)info.levels, info.build_s,
               info.cache_written ? " (cached)" : "");
        mr_viewer_toast(a->vc, "levels of detail ready: %llu levels built in %.1f s", (unsigned long long)info.levels,
                        info.build_s);
    }
}

/* The scene loads on a thread while the window opens; one that cannot
 * be loaded ends the program (poll_scene_load). */
static bool start_scene_load(view_app *a, const char *path, mr_error *err) {
    mr_scene_params sp = MR_SCENE_DEFAULTS;
    a->loader = mr_scene_load_async(path, &sp, err);
    if (!a->loader) return false;
    snprintf(a->scene_msg, sizeof a->scene_msg, "loading scene ...");
    return true;
}

/* The window, the renderer and the controller (with the settings file). */
static bool open_window(view_app *a, const mr_view_run_params *p, mr_error *err) {
    mr_window_params wp = MR_WINDOW_DEFAULTS;
    wp.width = p->width > 0 ? p->width : MR_VIEW_RUN_DEFAULT_WIDTH;
    wp.height = p->height > 0 ? p->height : MR_VIEW_RUN_DEFAULT_HEIGHT;
    wp.fullscreen = p->fullscreen;
    wp.title = "mrcheck view";
    wp.debug = mr_log_get_level() >= MR_LOG_DEBUG;
    a->win = mr_window_create(&wp, err);
    if (!a->win) return false;
    a->rend = mr_renderer_create(mr_window_gpu(a->win), err);
    a->d2 = a->rend ? mr_draw2d_create(mr_window_gpu(a->win), err) : NULL;
    if (!a->d2) return false;
    char config[4096];
    if (p->config_path) snprintf(config, sizeof config, "%s", p->config_path);
    else mr_view_default_config_path(config, sizeof config);
    mr_viewer_params vp = MR_VIEWER_DEFAULTS;
    vp.px_per_mm = mr_window_px_per_mm(a->win) * a->ui_scale;
    vp.config_path = config;
    vp.now = a->t_start;
    vp.show_stats = p->stats != NULL;
    vp.tolerances = a->tolerances;
    a->vc = mr_viewer_create(&vp, err);
    if (!a->vc) return false;
    /* Flags win over the saved settings for this run. */
    mr_view_settings s = *mr_viewer_settings(a->vc);
    /* --ao none / --ghost off turn the toggle off, a method turns it on with it. */
    if (p->ao_given) s.ao_on = p->ao != MR_AO_NONE;
    if (p->ao_given && p->ao != MR_AO_NONE) s.ao = p->ao;
    if (p->ghost_given) s.ghost_on = p->ghost != MR_GHOST_OFF;
    if (p->ghost_given && p->ghost != MR_GHOST_OFF) s.ghost = p->ghost;
    mr_viewer_set_settings(a->vc, &s);
    a->shadows.start = mr_view_shadows(&s);
    if (p->script && *p->script) mr_viewer_set_script(a->vc, p->script);
    return true;
}

static bool start_capture(view_app *a, const mr_view_run_params *p, mr_error *err) {
    mr_capture_params cp = {0};
    cp.input = a->src->input;
    cp.replay_dir = a->src->replay_dir;
    cp.camera = &a->src->camera;
    cp.markers = a->src->have_markers ? &a->src->markers : NULL;
    cp.fixed_pose = a->src->have_fixed_pose ? &a->src->fixed_pose : NULL;
    cp.retry_s = 1.0;
    cp.retrack = p->retrack;
    if (cp.retrack && !a->src->have_markers) return mr_fail(err, MR_ERR_INVALID, "--retrack needs a marker map");
    cp.wake = wake_window;
    cp.wake_ctx = a->win;
    a->cap = mr_capture_start(&cp, err);
    if (!a->cap) return false;
    mr_capture_rate(a->cap, mr_view_rates[mr_viewer_settings(a->vc)->rate_i]);
    if (p->paused) mr_capture_play(a->cap, false);
    return true;
}

static void run_loop(view_app *a) {
    while (!a->quit) {
        poll_scene_load(a);
        poll_lod(a);
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
}

bool mr_view_run(const mr_view_run_params *p, mr_error *err) {
    view_app *a = calloc(1, sizeof *a);
    if (!a) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    a->t_start = a->fps_t0 = p->start_time > 0 ? p->start_time : mr_time_now();
    a->src = p->source;
    a->ui_scale = p->ui_scale > 0 ? p->ui_scale : 1.0;
    a->ao_temporal = p->ao_temporal;
    a->nearest_fns = p->nearest;
    a->shadows.given = p->shadows_given;
    a->shadows.flag = p->shadows;
    if (p->out_dir) snprintf(a->session_dir, sizeof a->session_dir, "%s", p->out_dir);
    else if (a->src->replay_dir) snprintf(a->session_dir, sizeof a->session_dir, "%s", a->src->replay_dir);
    else snprintf(a->session_dir, sizeof a->session_dir, "mrcheck-session");

    bool ok = true;
    if (p->tolerances_path) {
        ok = (a->tolerances = malloc(sizeof *a->tolerances)) != NULL;
        if (!ok) mr_fail(err, MR_ERR_NOMEM, "out of memory");
        ok = ok && mr_tolerances_load(p->tolerances_path, a->tolerances, err);
    }
    ok = ok && start_scene_load(a, p->scene_path, err) && open_window(a, p, err) && start_capture(a, p, err);
    if (ok) {
        a->need_render = true;
        reload_marks(a);
        run_loop(a);
        if (a->failed) {
            *err = a->fail_err;
            ok = false;
        }
        mr_error serr = {0};
        if (!mr_viewer_save_settings(a->vc, &serr)) mr_log(MR_LOG_WARN, "view: cannot save settings: %s", serr.msg);
        if (p->stats) print_stats(a, p->stats);
    }

    if (a->loader) {
        mr_error ignored = {0};
        a->scene = mr_scene_loader_finish(&a->loader, &ignored); /* waits for the thread */
    }
    mr_lod_builder_cancel(&a->lod_builder); /* a build still running stops after its meshes in progress */
    mr_capture_stop(&a->cap);
    mr_capture_frame_free(&a->frame);
    mr_capture_frame_free(&a->mark_frame);
    mr_image_free(&a->mark_screen);
    mr_annotations_free(&a->marks);
    mr_frame_result_free(&a->res);
    mr_viewer_destroy(&a->vc);
    free(a->tolerances);
    mr_draw2d_destroy(&a->d2);
    mr_renderer_destroy(&a->rend);
    mr_hlod_destroy(&a->hlod);
    mr_lod_destroy(&a->lod);
    mr_window_destroy(&a->win);
    if (a->nearest && a->nearest_fns.destroy) a->nearest_fns.destroy(a->nearest_fns.user, a->nearest);
    a->nearest = NULL;
    mr_scene_destroy(&a->scene);
    free(a);
    return ok;
}
