/* mrcheck view: the in-situ check. A window shows the camera frame with the
 * planned model over it; big touch controls fade between them, switch the
 * depth cues, freeze the picture, snapshot it and mark discrepancies; a
 * recording replays with play/pause, step, seek and rate.
 *
 * Threads: capture and tracking run in view_capture.c; this file is the
 * render thread (window, UI, renderer) and only swaps in the newest frame.
 * Wiring only: widgets come from lib/ui, drawing from lib/render. */
#include "view.h"

#include "mr_session.h"
#include "mr_ui.h"

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* The UI's vertices are handed to the renderer as they are. */
_Static_assert(sizeof(mr_ui_vertex) == sizeof(mr_draw2d_vertex), "vertex layouts differ");
_Static_assert(offsetof(mr_ui_vertex, u) == offsetof(mr_draw2d_vertex, u), "vertex layouts differ");
_Static_assert(offsetof(mr_ui_vertex, rgba) == offsetof(mr_draw2d_vertex, rgba), "vertex layouts differ");

static const char *const k_cmd = "view";

/* Notes offered when marking (a tap is quicker than typing on a tablet). */
static const char *const k_notes[] = {"missing", "extra", "moved", "wrong size", "clash", "other"};
#define NOTE_COUNT (int)(sizeof k_notes / sizeof k_notes[0])

static const double k_rates[] = {0.25, 0.5, 1.0, 2.0, 4.0};
#define RATE_COUNT (int)(sizeof k_rates / sizeof k_rates[0])

/* Every control has a key; this table is also what `?` shows. */
static const struct {
    const char *keys, *what;
} k_keymap[] = {
    {"Up / +", "more video (slider right)"},
    {"Down / -", "more model (slider left)"},
    {"f", "freeze / unfreeze the frame and pose"},
    {"s", "snapshot (screen, raw frame, pose)"},
    {"m", "mark mode: tap the scene, then pick a note"},
    {"Enter", "in mark mode: mark the image centre"},
    {"1..6", "choose a note / Esc cancels"},
    {"v", "video on/off"},
    {"h", "hidden layer on/off"},
    {"a", "next ambient occlusion method"},
    {"g", "next ghosting mode"},
    {"space", "replay: play / pause"},
    {". / Right", "replay: step forward"},
    {", / Left", "replay: step back"},
    {"Home / End", "replay: first / last frame"},
    {"[ / ]", "replay: slower / faster"},
    {"F11", "fullscreen"},
    {"? / F1", "this help"},
    {"q / Esc", "quit"},
};

typedef struct settings {
    float alpha;         /* video transparency: 0 model only, 1 video only */
    bool show_video;
    bool hide_hidden;
    int rate_i;          /* index into k_rates */
    mr_ao_method ao;     /* ambient occlusion method, default none */
    mr_ghost_mode ghost; /* ghosted views of the hidden layer, default off */
} settings;

static const char *const k_ghost_names[] = {"off", "alpha", "g0", "adaptive"};
#define GHOST_COUNT 4

typedef struct named_rect {
    char name[24];
    mr_ui_rect r;
} named_rect;

typedef enum script_op { S_TAP, S_DOWN, S_UP, S_MOVE, S_DRAG, S_KEY, S_RESIZE, S_SHOT, S_STATE, S_QUIT } script_op;

typedef struct script_cmd {
    double t;
    script_op op;
    char target[24];     /* "@name" widget, or "" for coordinates */
    double a, b, c, d;
    int key;
    char path[1024];
} script_cmd;

typedef struct view_app {
    /* inputs */
    mr_camera camera;
    mr_marker_map markers;
    bool have_markers;
    mr_dmat4 fixed_pose;
    bool have_fixed_pose;
    char source_desc[256];
    /* window and drawing */
    mr_window *win;
    mr_renderer *rend;
    mr_draw2d *d2;
    mr_ui_font *font;
    mr_ui *ui;
    double ui_scale;
    int fb_w, fb_h;
    /* scene */
    mr_scene *scene;
    char scene_msg[600];
    mr_scene_loader *loader; /* the scene loads on a thread; the window stays live meanwhile */
    /* frames */
    vw_capture *cap;
    vw_frame frame;
    bool have_frame;
    /* state */
    settings s;
    char config_path[4096];
    bool settings_dirty;
    bool frozen, mark_mode, help, note_open, quit;
    mr_pick mark_pick;
    double mark_px, mark_py;       /* camera image pixel (ideal pinhole) */
    vw_frame mark_frame;           /* the frame the mark was made on */
    mr_image mark_screen;
    bool mark_grab_screen;
    bool snap_request;
    char session_dir[4096];
    int snap_count, mark_count;
    char toast[300];
    double toast_until;
    /* the rendered frame */
    bool need_render;
    mr_frame_result res;
    bool have_res;
    char passes[256];
    mr_ui_rect image_rect;
    int rw, rh;
    bool dimmed;
    /* pointer */
    mr_ui_input input;
    mr_event held;                 /* a press/release kept for the next frame */
    bool have_held;
    /* widgets by name, for scripts */
    named_rect named[40];
    int named_count;
    /* script */
    script_cmd *script;
    int script_count, script_next;
    double script_t0;
    int64_t script_frame;          /* frames_drawn when the last command ran */
    bool script_started;
    char shot_path[1024], state_path[1024];
    /* stats */
    bool stats;
    double t_start;
    int64_t frames_drawn, renders, frames_skipped;
    double sum_render_ms, sum_present_ms, sum_ui_cpu_ms, sum_ui_draw_ms, sum_loop_ms;
    double fps, fps_t0;
    int64_t fps_frames;
} view_app;

/* ------------------------------------------------------------ settings */

static void settings_default(settings *s) {
    s->alpha = 0.5f;
    s->show_video = true;
    s->hide_hidden = false;
    s->rate_i = 2;
    s->ao = MR_AO_NONE;
    s->ghost = MR_GHOST_OFF;
}

static void settings_load(view_app *a) {
    settings_default(&a->s);
    if (!mr_file_exists(a->config_path)) return;
    mr_error err = {0};
    cJSON *j = mr_json_load(a->config_path, &err);
    if (!j) {
        mr_log(MR_LOG_WARN, "view: ignoring settings: %s", err.msg);
        return;
    }
    double v;
    if (mr_json_number(j, "alpha", &v, false, NULL) && v >= 0 && v <= 1) a->s.alpha = (float)v;
    if (mr_json_number(j, "rate", &v, false, NULL))
        for (int i = 0; i < RATE_COUNT; i++)
            if (fabs(k_rates[i] - v) < 1e-9) a->s.rate_i = i;
    const cJSON *b = cJSON_GetObjectItemCaseSensitive(j, "show_video");
    if (cJSON_IsBool(b)) a->s.show_video = cJSON_IsTrue(b);
    b = cJSON_GetObjectItemCaseSensitive(j, "hide_hidden_layer");
    if (cJSON_IsBool(b)) a->s.hide_hidden = cJSON_IsTrue(b);
    b = cJSON_GetObjectItemCaseSensitive(j, "ao");
    mr_ao_method m;
    if (cJSON_IsString(b) && mr_ao_method_parse(b->valuestring, &m)) a->s.ao = m;
    b = cJSON_GetObjectItemCaseSensitive(j, "ghost");
    for (int i = 0; cJSON_IsString(b) && i < GHOST_COUNT; i++)
        if (strcmp(b->valuestring, k_ghost_names[i]) == 0) a->s.ghost = (mr_ghost_mode)i;
    cJSON_Delete(j);
}

static void settings_save(view_app *a) {
    if (!a->settings_dirty || !a->config_path[0]) return;
    char dir[4096];
    mr_path_dir(a->config_path, dir, sizeof dir);
    mr_error err = {0};
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "alpha", a->s.alpha);
    cJSON_AddBoolToObject(j, "show_video", a->s.show_video);
    cJSON_AddBoolToObject(j, "hide_hidden_layer", a->s.hide_hidden);
    cJSON_AddNumberToObject(j, "rate", k_rates[a->s.rate_i]);
    cJSON_AddStringToObject(j, "ao", mr_ao_method_name(a->s.ao));
    cJSON_AddStringToObject(j, "ghost", k_ghost_names[a->s.ghost]);
    /* mr_json_save writes a temporary file and renames it: a crash never
     * leaves a half-written config. */
    if (!mr_mkdirs(dir, &err) || !mr_json_save(a->config_path, j, &err))
        mr_log(MR_LOG_WARN, "view: cannot save settings: %s", err.msg);
    else a->settings_dirty = false;
    cJSON_Delete(j);
}

static void default_config_path(char *out, size_t n) {
    const char *x = getenv("XDG_CONFIG_HOME"), *home = getenv("HOME");
    if (x && x[0]) snprintf(out, n, "%s/mrcheck/view.json", x);
    else if (home && home[0]) snprintf(out, n, "%s/.config/mrcheck/view.json", home);
    else snprintf(out, n, ".mrcheck-view.json");
}

static void changed(view_app *a) {
    a->settings_dirty = true;
    a->need_render = true;
}

static void toast(view_app *a, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void toast(view_app *a, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(a->toast, sizeof a->toast, fmt, ap);
    va_end(ap);
    a->toast_until = mr_time_now() + 3.0;
}

/* ------------------------------------------------------------- actions */

static void set_alpha(view_app *a, float v) {
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    if (v != a->s.alpha) {
        a->s.alpha = v;
        changed(a);
    }
}

static void set_frozen(view_app *a, bool on) {
    a->frozen = on;
    if (a->cap) vw_capture_freeze(a->cap, on);
}

static void toggle_play(view_app *a) {
    if (!a->cap || !vw_capture_seekable(a->cap)) return;
    /* Playing does not unfreeze: the still stays until Freeze is undone. */
    vw_capture_play(a->cap, !vw_capture_playing(a->cap));
}

static void step(view_app *a, int d) {
    if (!a->cap || !vw_capture_seekable(a->cap)) return;
    if (a->frozen) set_frozen(a, false);
    vw_capture_step(a->cap, d);
}

static void next_ao(view_app *a) {
    a->s.ao = (mr_ao_method)((a->s.ao + 1) % MR_AO_METHOD_COUNT);
    changed(a);
}

static void next_ghost(view_app *a) {
    a->s.ghost = (mr_ghost_mode)((a->s.ghost + 1) % GHOST_COUNT);
    changed(a);
}

static void set_rate(view_app *a, int i) {
    i = i < 0 ? 0 : i >= RATE_COUNT ? RATE_COUNT - 1 : i;
    a->s.rate_i = i;
    a->settings_dirty = true;
    if (a->cap) vw_capture_rate(a->cap, k_rates[i]);
}

static cJSON *pose_json(const vw_frame *f) {
    cJSON *p = cJSON_CreateObject();
    cJSON_AddBoolToObject(p, "valid", f->pose_valid);
    cJSON_AddItemToObject(p, "world_from_camera", mr_json_from_dmat4(&f->pose));
    cJSON_AddNumberToObject(p, "tags_seen", f->tags_seen);
    cJSON_AddNumberToObject(p, "rms_px", f->rms_px);
    return p;
}

/* snapshots/<stem>_screen.png, <stem>_frame.png, <stem>.json, each written
 * atomically; rel gets the three paths relative to the session folder. */
static bool write_snapshot(view_app *a, const char *stem, const mr_image *screen, const vw_frame *f, cJSON *rel,
                           mr_error *err) {
    char dir[4096], path[8192], name[256];
    mr_path_join(a->session_dir, "snapshots", dir, sizeof dir);
    if (!mr_mkdirs(dir, err)) return false;
    snprintf(name, sizeof name, "%s_screen.png", stem);
    mr_path_join(dir, name, path, sizeof path);
    if (!mr_image_save_png(path, screen, err)) return false;
    if (rel) cJSON_AddItemToObject(rel, "screen", cJSON_CreateString(path + strlen(a->session_dir) + 1));
    if (f && f->image.data) {
        snprintf(name, sizeof name, "%s_frame.png", stem);
        mr_path_join(dir, name, path, sizeof path);
        if (!mr_image_save_png(path, &f->image, err)) return false;
        if (rel) cJSON_AddItemToObject(rel, "frame", cJSON_CreateString(path + strlen(a->session_dir) + 1));
    }
    cJSON *j = cJSON_CreateObject();
    cJSON_AddItemToObject(j, "camera", mr_camera_to_json(&a->camera));
    if (f) {
        cJSON_AddNumberToObject(j, "frame_index", (double)f->index);
        cJSON_AddNumberToObject(j, "timestamp", f->timestamp);
        cJSON_AddItemToObject(j, "pose", pose_json(f));
    }
    cJSON_AddNumberToObject(j, "alpha", a->s.alpha);
    cJSON_AddStringToObject(j, "passes", a->passes);
    snprintf(name, sizeof name, "%s.json", stem);
    mr_path_join(dir, name, path, sizeof path);
    bool ok = mr_json_save(path, j, err);
    cJSON_Delete(j);
    if (ok && rel) cJSON_AddItemToObject(rel, "pose", cJSON_CreateString(path + strlen(a->session_dir) + 1));
    return ok;
}

static void do_snapshot(view_app *a, const mr_image *screen) {
    char stem[64];
    snprintf(stem, sizeof stem, "snap_%04d", ++a->snap_count);
    /* Never overwrite an earlier session's files. */
    char probe[8192];
    for (;;) {
        snprintf(probe, sizeof probe, "%s/snapshots/%s.json", a->session_dir, stem);
        if (!mr_file_exists(probe)) break;
        snprintf(stem, sizeof stem, "snap_%04d", ++a->snap_count);
    }
    mr_error err = {0};
    if (write_snapshot(a, stem, screen, a->have_frame ? &a->frame : NULL, NULL, &err))
        toast(a, "snapshot saved: snapshots/%s_*", stem);
    else toast(a, "snapshot failed: %s", err.msg);
}

/* Maps a window position to the rendered image; false outside it. */
static bool window_to_image(const view_app *a, double x, double y, double *u, double *v) {
    mr_ui_rect r = a->image_rect;
    if (!a->have_res || !mr_ui_rect_contains(r, (float)x, (float)y)) return false;
    *u = (x - r.x) * a->rw / r.w - 0.5;
    *v = (y - r.y) * a->rh / r.h - 0.5;
    return true;
}

/* A tap in mark mode: what is under it, and the screen as it is now. */
static void begin_mark(view_app *a, double x, double y) {
    double u, v;
    if (!window_to_image(a, x, y, &u, &v)) {
        toast(a, "tap on the picture to mark");
        return;
    }
    mr_error err = {0};
    if (!mr_renderer_pick(a->rend, u, v, &a->mark_pick, &err)) {
        toast(a, "cannot mark: %s", err.msg);
        return;
    }
    /* Store the pixel in the camera's own resolution (ideal pinhole). */
    a->mark_px = (u + 0.5) * a->camera.width / a->rw - 0.5;
    a->mark_py = (v + 0.5) * a->camera.height / a->rh - 0.5;
    vw_frame_free(&a->mark_frame);
    a->mark_frame = a->frame;
    memset(&a->mark_frame.image, 0, sizeof a->mark_frame.image);
    if (a->frame.image.data && mr_image_alloc(&a->mark_frame.image, a->frame.image.width, a->frame.image.height,
                                              a->frame.image.channels, MR_PIX_U8, &err))
        memcpy(a->mark_frame.image.data, a->frame.image.data, mr_image_bytes(&a->frame.image));
    a->mark_grab_screen = true;
    a->note_open = true;
}

static void finish_mark(view_app *a, int note) {
    a->note_open = false;
    a->mark_mode = false;
    if (note < 0 || note >= NOTE_COUNT) {
        toast(a, "mark cancelled");
        mr_image_free(&a->mark_screen);
        vw_frame_free(&a->mark_frame);
        return;
    }
    mr_error err = {0};
    char stem[64];
    a->mark_count++;
    snprintf(stem, sizeof stem, "mark_%ld_%04d", (long)time(NULL), a->mark_count);
    cJSON *line = cJSON_CreateObject();
    cJSON_AddStringToObject(line, "type", "discrepancy");
    cJSON_AddNumberToObject(line, "time_unix", (double)time(NULL));
    cJSON_AddNumberToObject(line, "frame_index", (double)a->mark_frame.index);
    cJSON_AddNumberToObject(line, "timestamp", a->mark_frame.timestamp);
    cJSON_AddStringToObject(line, "note", k_notes[note]);
    double px[2] = {a->mark_px, a->mark_py};
    cJSON_AddItemToObject(line, "pixel", mr_json_from_doubles(px, 2));
    cJSON_AddBoolToObject(line, "hit", a->mark_pick.hit);
    if (a->mark_pick.hit) {
        double w[3] = {a->mark_pick.world.x, a->mark_pick.world.y, a->mark_pick.world.z};
        cJSON_AddItemToObject(line, "world", mr_json_from_doubles(w, 3));
        cJSON_AddNumberToObject(line, "depth", a->mark_pick.depth);
    } else {
        cJSON_AddNullToObject(line, "world");
    }
    const mr_scene *sc = a->scene;
    if (a->mark_pick.node >= 0 && sc && a->mark_pick.node < sc->node_count) {
        cJSON_AddStringToObject(line, "node", sc->nodes[a->mark_pick.node].name);
        cJSON_AddNumberToObject(line, "node_index", a->mark_pick.node);
        cJSON_AddStringToObject(line, "layer", a->mark_pick.layer == MR_LAYER_HIDDEN ? "hidden" : "visible");
    } else {
        cJSON_AddNullToObject(line, "node");
    }
    cJSON_AddItemToObject(line, "pose", pose_json(&a->mark_frame));
    cJSON *snap = cJSON_CreateObject();
    bool ok = a->mark_screen.data != NULL &&
              write_snapshot(a, stem, &a->mark_screen, &a->mark_frame, snap, &err);
    if (!ok && !err.msg[0]) snprintf(err.msg, sizeof err.msg, "no screen image");
    cJSON_AddItemToObject(line, "snapshot", snap);
    char path[8192];
    mr_path_join(a->session_dir, "annotations.jsonl", path, sizeof path);
    /* The line goes out even if the snapshot failed: the mark matters more. */
    mr_error aerr = {0};
    if (!mr_mkdirs(a->session_dir, &aerr) || !vw_append_line(path, line, &aerr))
        toast(a, "MARK NOT SAVED: %s", aerr.msg);
    else if (!ok) toast(a, "mark %d saved (snapshot failed: %s)", a->mark_count, err.msg);
    else
        toast(a, "mark %d saved: %s%s%s", a->mark_count, k_notes[note], a->mark_pick.node >= 0 && sc ? " on " : "",
              a->mark_pick.node >= 0 && sc ? sc->nodes[a->mark_pick.node].name : "");
    cJSON_Delete(line);
    mr_image_free(&a->mark_screen);
    vw_frame_free(&a->mark_frame);
}

static void on_key(view_app *a, int k) {
    if (a->note_open) {
        if (k >= '1' && k < '1' + NOTE_COUNT) finish_mark(a, k - '1');
        else if (k == MR_KEY_ESCAPE || k == 'q') finish_mark(a, -1);
        return;
    }
    if (a->help && (k == MR_KEY_ESCAPE || k == '?' || k == MR_KEY_F1)) {
        a->help = false;
        return;
    }
    switch (k) {
    case '?': case MR_KEY_F1: a->help = !a->help; break;
    case MR_KEY_UP: case '+': case '=': set_alpha(a, roundf(a->s.alpha * 10 + 1) / 10); break;
    case MR_KEY_DOWN: case '-': set_alpha(a, roundf(a->s.alpha * 10 - 1) / 10); break;
    case 'f': set_frozen(a, !a->frozen); break;
    case 's': a->snap_request = true; break;
    case 'm': a->mark_mode = !a->mark_mode; break;
    case MR_KEY_ENTER:
        if (a->mark_mode)
            begin_mark(a, a->image_rect.x + a->image_rect.w * 0.5, a->image_rect.y + a->image_rect.h * 0.5);
        break;
    case 'v': a->s.show_video = !a->s.show_video; changed(a); break;
    case 'h': a->s.hide_hidden = !a->s.hide_hidden; changed(a); break;
    case 'a': next_ao(a); break;
    case 'g': next_ghost(a); break;
    case ' ': toggle_play(a); break;
    case '.': case MR_KEY_RIGHT: step(a, 1); break;
    case ',': case MR_KEY_LEFT: step(a, -1); break;
    case MR_KEY_HOME: if (a->cap) vw_capture_seek(a->cap, 0); break;
    case MR_KEY_END: if (a->cap) vw_capture_seek(a->cap, INT64_MAX / 2); break;
    case '[': set_rate(a, a->s.rate_i - 1); break;
    case ']': set_rate(a, a->s.rate_i + 1); break;
    case MR_KEY_F11: mr_window_set_fullscreen(a->win, !mr_window_fullscreen(a->win)); break;
    case MR_KEY_ESCAPE:
        if (a->mark_mode) a->mark_mode = false;
        else a->quit = true;
        break;
    case 'q': a->quit = true; break;
    default: break;
    }
}

/* ------------------------------------------------------------- script */

static bool parse_key(const char *s, int *key) {
    static const struct { const char *n; int k; } names[] = {
        {"esc", MR_KEY_ESCAPE}, {"enter", MR_KEY_ENTER}, {"left", MR_KEY_LEFT}, {"right", MR_KEY_RIGHT},
        {"up", MR_KEY_UP}, {"down", MR_KEY_DOWN}, {"home", MR_KEY_HOME}, {"end", MR_KEY_END},
        {"f1", MR_KEY_F1}, {"f11", MR_KEY_F11}, {"space", ' '}, {"tab", MR_KEY_TAB},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strcmp(s, names[i].n) == 0) {
            *key = names[i].k;
            return true;
        }
    if (strlen(s) == 1 && s[0] > 32 && s[0] < 127) {
        *key = s[0];
        return true;
    }
    return false;
}

/* A script of timed input: one command per line, `T COMMAND ARGS`, T in
 * seconds from the first frame on screen. Widgets are named (`@alpha`), so
 * scripts survive layout changes:
 *   tap X Y | tap @name        down X Y | up X Y | move X Y
 *   drag @slider F0 F1         (fractions of the slider's width)
 *   key K                      (a character, or esc enter left right up down home end f1 f11 space)
 *   resize W H | shot OUT.png | state OUT.json | quit */
static bool script_load(view_app *a, const char *path, mr_error *err) {
    size_t size = 0;
    char *text = mr_file_read(path, &size, 1 << 20, err);
    if (!text) return false;
    int cap = 0, line_no = 0;
    bool ok = true;
    for (char *line = text; line && *line && ok; line_no++) {
        char *nl = strchr(line, '\n');
        if (nl) *nl = 0;
        char *hash = strchr(line, '#');
        if (hash) *hash = 0;
        script_cmd c;
        memset(&c, 0, sizeof c);
        char op[32] = "", arg[5][1000];
        memset(arg, 0, sizeof arg);
        int n = sscanf(line, "%lf %31s %999s %999s %999s %999s", &c.t, op, arg[0], arg[1], arg[2], arg[3]);
        line = nl ? nl + 1 : NULL;
        if (n <= 0) continue;
        if (n < 2) {
            ok = mr_fail(err, MR_ERR_PARSE, "%s:%d: expected `TIME COMMAND ...`", path, line_no + 1);
            break;
        }
        int na = n - 2;
        bool target = na >= 1 && arg[0][0] == '@';
        if (target) snprintf(c.target, sizeof c.target, "%.23s", arg[0] + 1);
        int first = target ? 1 : 0;
        double v[4] = {0, 0, 0, 0};
        for (int i = first; i < na && i - first < 4; i++) v[i - first] = atof(arg[i]);
        c.a = v[0]; c.b = v[1]; c.c = v[2]; c.d = v[3];
        if (!strcmp(op, "tap")) c.op = S_TAP, ok = target || na >= 2;
        else if (!strcmp(op, "down")) c.op = S_DOWN, ok = target || na >= 2;
        else if (!strcmp(op, "up")) c.op = S_UP, ok = target || na >= 2;
        else if (!strcmp(op, "move")) c.op = S_MOVE, ok = target || na >= 2;
        else if (!strcmp(op, "drag")) c.op = S_DRAG, ok = target && na >= 3;
        else if (!strcmp(op, "key")) c.op = S_KEY, ok = na >= 1 && parse_key(arg[0], &c.key);
        else if (!strcmp(op, "resize")) c.op = S_RESIZE, ok = na >= 2 && c.a > 0 && c.b > 0;
        else if (!strcmp(op, "shot")) c.op = S_SHOT, ok = na >= 1;
        else if (!strcmp(op, "state")) c.op = S_STATE, ok = na >= 1;
        else if (!strcmp(op, "quit")) c.op = S_QUIT;
        else ok = false;
        if ((c.op == S_SHOT || c.op == S_STATE) && na >= 1) snprintf(c.path, sizeof c.path, "%s", arg[0]);
        if (!ok) {
            mr_fail(err, MR_ERR_PARSE, "%s:%d: bad command '%s'", path, line_no + 1, op);
            break;
        }
        if (a->script_count == cap) {
            cap = cap ? cap * 2 : 32;
            script_cmd *p = realloc(a->script, (size_t)cap * sizeof *p);
            if (!p) {
                ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
                break;
            }
            a->script = p;
        }
        a->script[a->script_count++] = c;
    }
    free(text);
    return ok;
}

static bool find_named(const view_app *a, const char *name, mr_ui_rect *r) {
    for (int i = 0; i < a->named_count; i++)
        if (strcmp(a->named[i].name, name) == 0) {
            *r = a->named[i].r;
            return true;
        }
    return false;
}

static void push(view_app *a, mr_event_type t, double x, double y) {
    mr_event e = {t, x, y, 0};
    mr_window_push_event(a->win, &e);
}

/* Runs the commands that are due; input becomes ordinary window events so
 * it takes exactly the path real input takes. */
static void script_tick(view_app *a) {
    if (!a->script_count || a->script_next >= a->script_count) return;
    if (!a->script_started) {
        /* Time starts with the first camera frame on screen, or after 3 s
         * without one (no camera), so slow starts do not shift the script. */
        if (!a->have_res && mr_time_now() - a->t_start < 3.0) return;
        a->script_started = true;
        a->script_t0 = mr_time_now();
    }
    /* Times are earliest times: a command also waits until the input of
     * the one before has been taken and its effect drawn, so a slow machine
     * shifts the script but never reorders it. */
    if (a->have_held || mr_window_pending(a->win) > 0 || (a->need_render && a->have_frame) ||
        a->frames_drawn < a->script_frame + 2)
        return;
    double t = mr_time_now() - a->script_t0;
    if (a->script_next < a->script_count && a->script[a->script_next].t <= t) {
        a->script_frame = a->frames_drawn;
        const script_cmd *c = &a->script[a->script_next++];
        double x = c->a, y = c->b;
        mr_ui_rect r = mr_ui_rect_make((float)x, (float)y, 0, 0);
        if (c->target[0]) {
            if (!find_named(a, c->target, &r)) {
                mr_log(MR_LOG_WARN, "view: script: no widget named @%s on screen", c->target);
                return;
            }
            x = r.x + r.w * 0.5;
            y = r.y + r.h * 0.5;
        }
        switch (c->op) {
        case S_TAP: push(a, MR_EVENT_POINTER_MOVE, x, y); push(a, MR_EVENT_POINTER_DOWN, x, y);
            push(a, MR_EVENT_POINTER_UP, x, y); break;
        case S_DOWN: push(a, MR_EVENT_POINTER_MOVE, x, y); push(a, MR_EVENT_POINTER_DOWN, x, y); break;
        case S_UP: push(a, MR_EVENT_POINTER_UP, x, y); break;
        case S_MOVE: push(a, MR_EVENT_POINTER_MOVE, x, y); break;
        case S_DRAG: {
            double x0 = r.x + r.w * c->a, x1 = r.x + r.w * c->b;
            push(a, MR_EVENT_POINTER_MOVE, x0, y);
            push(a, MR_EVENT_POINTER_DOWN, x0, y);
            /* Moves are interleaved with a no-op key so they are not coalesced. */
            for (int i = 1; i <= 8; i++) {
                push(a, MR_EVENT_POINTER_MOVE, x0 + (x1 - x0) * i / 8.0, y);
                mr_event nop = {MR_EVENT_NONE, 0, 0, 0};
                mr_window_push_event(a->win, &nop);
            }
            push(a, MR_EVENT_POINTER_UP, x1, y);
            break;
        }
        case S_KEY: {
            mr_event e = {MR_EVENT_KEY, a->input.x, a->input.y, c->key};
            mr_window_push_event(a->win, &e);
            break;
        }
        case S_RESIZE: mr_window_set_size(a->win, (int)c->a, (int)c->b); break;
        case S_SHOT: snprintf(a->shot_path, sizeof a->shot_path, "%s", c->path); break;
        case S_STATE: snprintf(a->state_path, sizeof a->state_path, "%s", c->path); break;
        case S_QUIT: a->quit = true; break;
        }
    }
}

/* --------------------------------------------------------------- events */

/* Drains window events. Presses and releases are handed to the UI one per
 * frame (a quick tap is a press frame then a release frame), so no tap is
 * lost however fast it was; moves and keys are applied at once. */
static void pump_events(view_app *a) {
    bool transition = false;
    mr_event e;
    for (;;) {
        if (a->have_held) {
            e = a->held;
            a->have_held = false;
        } else if (!mr_window_next_event(a->win, &e)) {
            break;
        }
        switch (e.type) {
        case MR_EVENT_POINTER_DOWN:
        case MR_EVENT_POINTER_UP:
            if (transition) {
                a->held = e;
                a->have_held = true;
                return;
            }
            transition = true;
            a->input.x = (float)e.x;
            a->input.y = (float)e.y;
            a->input.down = e.type == MR_EVENT_POINTER_DOWN;
            a->input.inside = true;
            break;
        case MR_EVENT_POINTER_MOVE:
            if (transition) {
                /* A move after a transition belongs to the next frame. */
                a->held = e;
                a->have_held = true;
                return;
            }
            a->input.x = (float)e.x;
            a->input.y = (float)e.y;
            a->input.inside = true;
            break;
        case MR_EVENT_NONE:
            if (transition) return;
            break;
        case MR_EVENT_POINTER_LEAVE: a->input.inside = false; break;
        case MR_EVENT_KEY: on_key(a, e.key); break;
        case MR_EVENT_RESIZE: a->need_render = true; break;
        case MR_EVENT_CLOSE: a->quit = true; break;
        }
    }
}

/* ---------------------------------------------------------------- frame */

static void add_named(view_app *a, const char *name, mr_ui_rect r) {
    if (a->named_count >= (int)(sizeof a->named / sizeof a->named[0])) return;
    snprintf(a->named[a->named_count].name, sizeof a->named[0].name, "%s", name);
    a->named[a->named_count++].r = r;
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
    view.camera = mr_camera_resized(&a->camera, a->frame.image.width, a->frame.image.height);
    view.world_from_camera = a->frame.pose;
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = rw;
    fp.height = rh;
    fp.video = a->s.show_video ? &a->frame.image : NULL;
    fp.alpha = a->s.alpha;
    fp.hide_hidden_layer = a->s.hide_hidden;
    fp.ao.method = a->s.ao;
    fp.ghost.mode = a->s.ghost;
    /* Tracking lost: keep the last good pose but let the video through, so
     * a stale model never passes for the truth. No pose yet: video only. */
    a->dimmed = false;
    if (!a->frame.have_pose) {
        fp.alpha = 1.0f;
        view.world_from_camera = mr_m4_look_at_cv(mr_v3(0, 0, 0), mr_v3(0, 0, 1), mr_v3(0, -1, 0));
    } else if (!a->frame.pose_valid && !a->frozen) {
        fp.alpha = fp.video ? 1.0f - (1.0f - a->s.alpha) * 0.35f : a->s.alpha;
        a->dimmed = true;
    }
    double t0 = mr_time_now();
    mr_frame_result_free(&a->res);
    mr_error err = {0};
    a->have_res = mr_render_frame(a->rend, &view, &fp, &a->res, &err);
    a->sum_render_ms += (mr_time_now() - t0) * 1e3;
    a->renders++;
    if (!a->have_res) {
        toast(a, "render failed: %s", err.msg);
        a->passes[0] = 0;
        return;
    }
    a->rw = rw;
    a->rh = rh;
    a->image_rect = fit;
    mr_frame_result_passes(&a->res, a->passes, sizeof a->passes);
    /* A still camera reuses the last AO: say so, or AO seems to be off. */
    if (a->res.ao_reused) strncat(a->passes, " (ao reused)", sizeof a->passes - strlen(a->passes) - 1);
}

static void build_ui(view_app *a) {
    mr_ui *ui = a->ui;
    a->named_count = 0;
    float T = mr_ui_target_px(ui), g = mr_ui_mm(ui, 1.2f), th = mr_ui_text_px(ui);
    mr_ui_rect full = mr_ui_rect_make(0, 0, (float)a->fb_w, (float)a->fb_h);
    bool seekable = a->cap && vw_capture_seekable(a->cap);

    /* Status line. */
    mr_ui_rect status = mr_ui_cut_top(&full, th * 1.7f);
    mr_ui_panel(ui, status);
    char line[512], track[128], src[160];
    if (!a->have_frame) snprintf(track, sizeof track, "no frame");
    else if (a->frame.pose_valid)
        snprintf(track, sizeof track, "tracking: %d tags, %.2f px", a->frame.tags_seen < 0 ? 0 : a->frame.tags_seen,
                 a->frame.rms_px < 0 ? 0.0 : a->frame.rms_px);
    else snprintf(track, sizeof track, "TRACKING LOST (%d tags)", a->frame.tags_seen < 0 ? 0 : a->frame.tags_seen);
    if (seekable && a->have_frame)
        snprintf(src, sizeof src, "replay %lld/%lld %s %gx", (long long)a->frame.index + 1, (long long)a->frame.count,
                 vw_capture_playing(a->cap) ? "playing" : "paused", k_rates[a->s.rate_i]);
    else snprintf(src, sizeof src, "%.150s", a->source_desc);
    snprintf(line, sizeof line, "%s%s | %s | %.1f fps | %.200s", a->frozen ? "FROZEN | " : "", src, track, a->fps,
             a->passes[0] ? a->passes : "-");
    mr_ui_label(ui, status, line, a->have_frame && !a->frame.pose_valid ? MR_UI_RGBA(255, 150, 120, 255)
                                                                          : MR_UI_RGBA(235, 240, 245, 255), false);

    /* Bottom: the transparency slider, and the replay bar. */
    mr_ui_rect bottom = mr_ui_cut_bottom(&full, (T + g) * (seekable ? 2 : 1) + g);
    mr_ui_panel(ui, bottom);
    mr_ui_rect inner = mr_ui_rect_inset(bottom, g);
    mr_ui_rect srow = mr_ui_cut_top(&inner, T);
    char lab[64];
    snprintf(lab, sizeof lab, "model  <  >  video  %d%%", (int)lroundf(a->s.alpha * 100));
    float alpha = a->s.alpha;
    if (mr_ui_slider(ui, 1, srow, lab, &alpha, 0.0f, 1.0f)) set_alpha(a, alpha);
    add_named(a, "alpha", srow);
    if (seekable) {
        mr_ui_cut_top(&inner, g);
        mr_ui_rect rrow = mr_ui_cut_top(&inner, T);
        float bw = fmaxf(T * 1.6f, mr_ui_text_width(mr_ui_get_font(ui), "Pause", th) + 2 * g);
        mr_ui_rect bplay = mr_ui_cut_left(&rrow, bw);
        mr_ui_cut_left(&rrow, g);
        mr_ui_rect bback = mr_ui_cut_left(&rrow, T);
        mr_ui_cut_left(&rrow, g);
        mr_ui_rect bfwd = mr_ui_cut_left(&rrow, T);
        mr_ui_cut_left(&rrow, g);
        mr_ui_rect brate = mr_ui_cut_right(&rrow, T * 1.4f);
        mr_ui_cut_right(&rrow, g);
        bool playing = vw_capture_playing(a->cap);
        if (mr_ui_button(ui, 20, bplay, playing ? "Pause" : "Play", playing ? MR_UI_ON : MR_UI_NORMAL)) toggle_play(a);
        if (mr_ui_button(ui, 21, bback, "<", MR_UI_NORMAL)) step(a, -1);
        if (mr_ui_button(ui, 22, bfwd, ">", MR_UI_NORMAL)) step(a, 1);
        snprintf(lab, sizeof lab, "%gx", k_rates[a->s.rate_i]);
        if (mr_ui_button(ui, 23, brate, lab, MR_UI_NORMAL)) set_rate(a, (a->s.rate_i + 1) % RATE_COUNT);
        add_named(a, "play", bplay);
        add_named(a, "back", bback);
        add_named(a, "forward", bfwd);
        add_named(a, "rate", brate);
        int64_t count = a->have_frame && a->frame.count > 0 ? a->frame.count : 1;
        float pos = a->have_frame ? (float)a->frame.index : 0;
        snprintf(lab, sizeof lab, "frame %lld", (long long)(a->have_frame ? a->frame.index + 1 : 0));
        if (mr_ui_slider(ui, 24, rrow, lab, &pos, 0.0f, (float)(count > 1 ? count - 1 : 1))) {
            int64_t want = (int64_t)lroundf(pos);
            if (!a->have_frame || want != a->frame.index) {
                if (a->frozen) set_frozen(a, false);
                vw_capture_seek(a->cap, want);
            }
        }
        add_named(a, "seek", rrow);
    }

    /* Right column: the toggles and actions, wrapping into a second column
     * when the screen is too short. */
    float colw = fmaxf(T * 2.4f, mr_ui_text_width(mr_ui_get_font(ui), "AO alchemy", th) + 3 * g);
    char ao_label[32], ghost_label[32];
    snprintf(ao_label, sizeof ao_label, "AO %s", mr_ao_method_name(a->s.ao));
    snprintf(ghost_label, sizeof ghost_label, "Ghost %s", k_ghost_names[a->s.ghost]);
    struct {
        const char *name, *label;
        int kind; /* 0 button, 1 toggle state shown */
        bool on;
    } items[] = {
        {"freeze", a->frozen ? "Frozen" : "Freeze", 1, a->frozen},
        {"snapshot", "Snapshot", 0, false},
        {"mark", "Mark", 1, a->mark_mode},
        {"video", "Video", 1, a->s.show_video},
        {"hidden", "Hidden", 1, !a->s.hide_hidden},
        {"ao", ao_label, 1, a->s.ao != MR_AO_NONE},
        {"ghost", ghost_label, 1, a->s.ghost != MR_GHOST_OFF},
        {"help", "?", 1, a->help},
    };
    int n = (int)(sizeof items / sizeof items[0]);
    float avail = full.h - g;
    int per_col = (int)((avail) / (T + g));
    if (per_col < 1) per_col = 1;
    int cols = (n + per_col - 1) / per_col;
    mr_ui_rect column = mr_ui_cut_right(&full, cols * (colw + g) + g);
    column.h = fminf(column.h, (float)((n < per_col ? n : per_col) * (T + g) + g));
    mr_ui_panel(ui, column);
    for (int i = 0; i < n; i++) {
        int c = i / per_col, r = i % per_col;
        mr_ui_rect b = mr_ui_rect_make(column.x + column.w - (c + 1) * (colw + g), column.y + g + r * (T + g), colw, T);
        add_named(a, items[i].name, b);
        if (!mr_ui_button(ui, (uint32_t)(40 + i), b, items[i].label, items[i].on ? MR_UI_ON : MR_UI_NORMAL)) continue;
        if (!strcmp(items[i].name, "freeze")) set_frozen(a, !a->frozen);
        else if (!strcmp(items[i].name, "snapshot")) a->snap_request = true;
        else if (!strcmp(items[i].name, "mark")) a->mark_mode = !a->mark_mode;
        else if (!strcmp(items[i].name, "video")) { a->s.show_video = !a->s.show_video; changed(a); }
        else if (!strcmp(items[i].name, "hidden")) { a->s.hide_hidden = !a->s.hide_hidden; changed(a); }
        else if (!strcmp(items[i].name, "help")) a->help = !a->help;
        else if (!strcmp(items[i].name, "ao")) next_ao(a);
        else if (!strcmp(items[i].name, "ghost")) next_ghost(a);
    }

    /* Messages over the picture: failures first. */
    mr_ui_rect msg_area = full;
    char state_msg[512] = "";
    vw_state st = a->cap ? vw_capture_state(a->cap, state_msg, sizeof state_msg) : VW_STARTING;
    const char *banners[4];
    uint32_t colors[4];
    int nb = 0;
    if (st == VW_NO_CAMERA) { banners[nb] = state_msg; colors[nb++] = MR_UI_RGBA(200, 40, 40, 230); }
    if (a->scene_msg[0]) { banners[nb] = a->scene_msg; colors[nb++] = MR_UI_RGBA(200, 40, 40, 230); }
    if (a->have_frame && !a->frame.have_pose) {
        banners[nb] = "searching for markers: no pose yet";
        colors[nb++] = MR_UI_RGBA(200, 120, 20, 230);
    } else if (a->dimmed) {
        banners[nb] = "TRACKING LOST: model dimmed at the last good pose";
        colors[nb++] = MR_UI_RGBA(200, 120, 20, 230);
    }
    if (a->mark_mode && !a->note_open) {
        banners[nb] = "MARK: tap the discrepancy in the picture (Esc cancels)";
        colors[nb++] = MR_UI_RGBA(214, 120, 28, 230);
    }
    for (int i = 0; i < nb; i++) {
        mr_ui_rect b = mr_ui_cut_top(&msg_area, th * 2.0f);
        b = mr_ui_rect_inset(b, g * 0.5f);
        mr_ui_draw_rect(mr_ui_list(ui), b, colors[i]);
        mr_ui_label(ui, b, banners[i], MR_UI_RGBA(255, 255, 255, 255), true);
    }
    if (a->toast[0] && mr_time_now() < a->toast_until) {
        mr_ui_rect b = mr_ui_cut_bottom(&msg_area, th * 2.0f);
        b = mr_ui_rect_inset(b, g * 0.5f);
        mr_ui_draw_rect(mr_ui_list(ui), b, MR_UI_RGBA(20, 20, 20, 200));
        mr_ui_label(ui, b, a->toast, MR_UI_RGBA(255, 255, 255, 255), true);
    }
    /* Note chooser. */
    if (a->note_open) {
        float w = fminf(full.w - 2 * g, 2 * colw + 3 * g), h = (T + g) * ((NOTE_COUNT + 1) / 2 + 2) + g;
        /* On the side away from the mark, so the cross stays visible. */
        float mx = a->image_rect.x + (float)((a->mark_px + 0.5) / a->camera.width) * a->image_rect.w;
        float px = mx < full.x + full.w * 0.5f ? full.x + full.w - w - g : full.x + g;
        if (full.w < 2 * w) px = full.x + (full.w - w) / 2;
        mr_ui_rect p = mr_ui_rect_make(px, full.y + (full.h - h) / 2, w, h);
        mr_ui_panel(ui, p);
        mr_ui_panel(ui, p); /* darker */
        mr_ui_rect in = mr_ui_rect_inset(p, g);
        mr_ui_label(ui, mr_ui_cut_top(&in, T), "What differs here?", MR_UI_RGBA(255, 255, 255, 255), true);
        float bw = (in.w - g) / 2;
        for (int i = 0; i < NOTE_COUNT; i++) {
            mr_ui_rect b = mr_ui_rect_make(in.x + (i % 2) * (bw + g), in.y + (i / 2) * (T + g), bw, T);
            char nm[16], lb[48];
            snprintf(nm, sizeof nm, "note%d", i + 1);
            snprintf(lb, sizeof lb, "%d %s", i + 1, k_notes[i]);
            add_named(a, nm, b);
            if (mr_ui_button(ui, (uint32_t)(60 + i), b, lb, MR_UI_NORMAL)) finish_mark(a, i);
        }
        mr_ui_rect bc = mr_ui_rect_make(in.x, in.y + ((NOTE_COUNT + 1) / 2) * (T + g), in.w, T);
        add_named(a, "cancel", bc);
        if (mr_ui_button(ui, 70, bc, "Cancel", MR_UI_NORMAL)) finish_mark(a, -1);
    }

    /* The mark being made: a cross on the picture, over everything. */
    if (a->note_open && a->have_res) {
        float x = a->image_rect.x + (float)((a->mark_px + 0.5) / a->camera.width) * a->image_rect.w;
        float y = a->image_rect.y + (float)((a->mark_py + 0.5) / a->camera.height) * a->image_rect.h;
        float s = mr_ui_mm(ui, 3), t = fmaxf(2, mr_ui_mm(ui, 0.4f));
        mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(x - s, y - t / 2, 2 * s, t), MR_UI_RGBA(255, 60, 60, 255));
        mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(x - t / 2, y - s, t, 2 * s), MR_UI_RGBA(255, 60, 60, 255));
    }

    /* Help. */
    if (a->help) {
        int rows = (int)(sizeof k_keymap / sizeof k_keymap[0]);
        float lh = th * 1.35f;
        float w = fminf(full.w - 2 * g, mr_ui_mm(ui, 120)), h = fminf(full.h, lh * (rows + 1) + 2 * g);
        mr_ui_rect p = mr_ui_rect_make(full.x + (full.w - w) / 2, full.y + (full.h - h) / 2, w, h);
        /* The whole panel is one button: a tap anywhere closes it. */
        if (mr_ui_button(ui, 80, p, "", MR_UI_NORMAL)) a->help = false;
        mr_ui_panel(ui, p);
        mr_ui_rect in = mr_ui_rect_inset(p, g);
        mr_ui_label(ui, mr_ui_cut_top(&in, lh), "Keys (tap or press ? to close)", MR_UI_RGBA(255, 220, 150, 255),
                    false);
        for (int i = 0; i < rows && in.h >= lh; i++) {
            mr_ui_rect row = mr_ui_cut_top(&in, lh);
            mr_ui_rect k = mr_ui_cut_left(&row, fminf(row.w * 0.3f, mr_ui_mm(ui, 30)));
            mr_ui_label(ui, k, k_keymap[i].keys, MR_UI_RGBA(150, 200, 255, 255), false);
            mr_ui_label(ui, row, k_keymap[i].what, MR_UI_RGBA(235, 240, 245, 255), false);
        }
    }
    float tx, ty;
    mr_ui_end(ui);
    if (mr_ui_scene_tap(ui, &tx, &ty)) {
        if (a->help) a->help = false;
        else if (a->mark_mode && !a->note_open) begin_mark(a, tx, ty);
    }
}

/* Mean absolute difference between two RGB8 images of one size (0..255). */
static double mean_abs_diff(const mr_image *x, const mr_image *y) {
    if (!x->data || !y->data || x->width != y->width || x->height != y->height) return -1;
    const uint8_t *p = x->data, *q = y->data;
    size_t n = mr_image_bytes(x);
    double s = 0;
    for (size_t i = 0; i < n; i++) s += abs((int)p[i] - (int)q[i]);
    return n ? s / (double)n : 0;
}

/* `state` in a script: what a test needs to check, as JSON. The distances
 * of the shown picture to the model-only and video-only renderings say
 * which way the slider moved the image. */
static void write_state(view_app *a, const mr_image *screen) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "alpha", a->s.alpha);
    cJSON_AddBoolToObject(j, "show_video", a->s.show_video);
    cJSON_AddBoolToObject(j, "hide_hidden_layer", a->s.hide_hidden);
    cJSON_AddStringToObject(j, "ao", mr_ao_method_name(a->s.ao));
    cJSON_AddStringToObject(j, "ghost", k_ghost_names[a->s.ghost]);
    cJSON_AddBoolToObject(j, "frozen", a->frozen);
    cJSON_AddBoolToObject(j, "mark_mode", a->mark_mode);
    cJSON_AddBoolToObject(j, "help", a->help);
    cJSON_AddStringToObject(j, "passes", a->passes);
    cJSON_AddBoolToObject(j, "have_frame", a->have_frame);
    cJSON_AddNumberToObject(j, "frame_index", a->have_frame ? (double)a->frame.index : -1);
    cJSON_AddBoolToObject(j, "pose_valid", a->have_frame && a->frame.pose_valid);
    cJSON_AddNumberToObject(j, "tags_seen", a->have_frame ? a->frame.tags_seen : -1);
    cJSON_AddBoolToObject(j, "tracking_lost_dimmed", a->dimmed);
    cJSON_AddNumberToObject(j, "marks", a->mark_count);
    cJSON_AddNumberToObject(j, "snapshots", a->snap_count);
    cJSON_AddNumberToObject(j, "fb_width", a->fb_w);
    cJSON_AddNumberToObject(j, "fb_height", a->fb_h);
    cJSON_AddNumberToObject(j, "px_per_mm", mr_ui_px_per_mm(a->ui));
    cJSON_AddNumberToObject(j, "target_px", mr_ui_target_px(a->ui));
    char msg[512] = "";
    vw_state st = a->cap ? vw_capture_state(a->cap, msg, sizeof msg) : VW_STARTING;
    cJSON_AddStringToObject(j, "source_state", st == VW_RUNNING ? "running" : st == VW_NO_CAMERA ? "no_camera"
                                               : st == VW_ENDED ? "ended" : "starting");
    cJSON_AddStringToObject(j, "source_message", msg);
    cJSON_AddStringToObject(j, "scene_message", a->scene_msg);
    /* Where each widget is (framebuffer pixels x y w h), for tests that
     * drive the window with real X input (xdotool). */
    cJSON *wd = cJSON_AddObjectToObject(j, "widgets");
    for (int i = 0; i < a->named_count; i++) {
        double r[4] = {a->named[i].r.x, a->named[i].r.y, a->named[i].r.w, a->named[i].r.h};
        cJSON_AddItemToObject(wd, a->named[i].name, mr_json_from_doubles(r, 4));
    }
    if (screen && screen->data) {
        /* Spread of the screen's pixel values: a blank window has none. */
        const uint8_t *p = screen->data;
        size_t n = mr_image_bytes(screen);
        double s = 0, s2 = 0;
        for (size_t i = 0; i < n; i++) {
            s += p[i];
            s2 += (double)p[i] * p[i];
        }
        double mean = n ? s / n : 0;
        cJSON_AddNumberToObject(j, "screen_mean", mean);
        cJSON_AddNumberToObject(j, "screen_std", n ? sqrt(fmax(0, s2 / n - mean * mean)) : 0);
    }
    if (a->have_res && a->have_frame && a->frame.have_pose) {
        cJSON_AddNumberToObject(j, "render_width", a->rw);
        cJSON_AddNumberToObject(j, "render_height", a->rh);
        mr_view view;
        view.camera = mr_camera_resized(&a->camera, a->frame.image.width, a->frame.image.height);
        view.world_from_camera = a->frame.pose;
        double d[2] = {-1, -1};
        for (int k = 0; k < 2; k++) {
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = a->rw;
            fp.height = a->rh;
            fp.video = &a->frame.image;
            fp.alpha = (float)k;
            fp.hide_hidden_layer = a->s.hide_hidden;
            fp.ao.method = a->s.ao;
            fp.ghost.mode = a->s.ghost;
            mr_frame_result r;
            mr_error err = {0};
            if (mr_render_frame(a->rend, &view, &fp, &r, &err)) {
                d[k] = mean_abs_diff(&a->res.color, &r.color);
                mr_frame_result_free(&r);
            }
        }
        cJSON_AddNumberToObject(j, "diff_to_model", d[0]);
        cJSON_AddNumberToObject(j, "diff_to_video", d[1]);
        a->need_render = true; /* the renderer's last frame is now another one */
    }
    mr_error err = {0};
    if (!mr_json_save(a->state_path, j, &err)) mr_log(MR_LOG_ERROR, "view: %s", err.msg);
    cJSON_Delete(j);
}

static void wake_window(void *ctx) { mr_window_wake(ctx); }

/* One pass of the loop: input, newest frame, 3D render if needed, UI, draw. */
static void frame_tick(view_app *a) {
    double t0 = mr_time_now();
    script_tick(a);
    pump_events(a);
    mr_window_framebuffer_size(a->win, &a->fb_w, &a->fb_h);
    if (a->fb_w <= 0 || a->fb_h <= 0) return; /* minimised */
    double ppmm = mr_window_px_per_mm(a->win) * a->ui_scale;
    if (fabs(ppmm - mr_ui_px_per_mm(a->ui)) > 1e-6) mr_ui_set_density(a->ui, ppmm);

    uint64_t old_seq = a->frame.seq;
    if (a->cap && !a->frozen && !a->note_open && vw_capture_latest(a->cap, &a->frame)) {
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

    mr_ui_input in = a->input;
    mr_ui_begin(a->ui, &in);
    build_ui(a);
    const mr_ui_draw_list *dl = mr_ui_list(a->ui);
    a->sum_ui_cpu_ms += mr_ui_last_cpu_s(a->ui) * 1e3;
    double t3 = mr_time_now();
    mr_draw2d_list l = {(const mr_draw2d_vertex *)dl->vertices, dl->vertex_count, dl->indices, dl->index_count,
                        dl->atlas, dl->atlas_w, dl->atlas_h, dl->atlas_version};
    if (!mr_draw2d_list_draw(a->d2, &l, &err)) mr_log(MR_LOG_ERROR, "view: %s", err.msg);
    a->sum_ui_draw_ms += (mr_time_now() - t3) * 1e3;

    /* Screen reads happen before the swap, while the back buffer holds
     * exactly what is about to be shown. */
    if (a->snap_request || a->mark_grab_screen || a->shot_path[0] || a->state_path[0]) {
        mr_image screen = {0};
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
    (void)t2;
}

/* ------------------------------------------------------------- wiring */

/* A recording's meta.json names its camera and marker map (inline objects
 * or paths relative to the recording); without one, camera.json and
 * markers.json next to the frames are used. */
static bool load_replay_meta(const char *dir, mr_camera *cam, bool have_cam, mr_marker_map *map, bool *have_map,
                             mr_error *err) {
    char path[4096], sub[8192];
    if (mr_is_recording(dir)) {
        mr_recording *rec = mr_recording_open(dir, err);
        if (!rec) return false;
        if (!have_cam) *cam = rec->camera;
        if (!*have_map && rec->has_markers) {
            /* Take the map over; the recording is closed right after. */
            *map = rec->markers;
            memset(&rec->markers, 0, sizeof rec->markers);
            rec->has_markers = false;
            *have_map = true;
        }
        mr_recording_close(&rec);
        return true;
    }
    mr_path_join(dir, "meta.json", path, sizeof path);
    cJSON *meta = mr_file_exists(path) ? mr_json_load(path, err) : NULL;
    if (mr_file_exists(path) && !meta) return false;
    bool ok = true;
    if (!have_cam) {
        const cJSON *c = meta ? cJSON_GetObjectItemCaseSensitive(meta, "camera") : NULL;
        if (cJSON_IsObject(c)) ok = mr_camera_from_json(c, cam, err);
        else {
            mr_path_join(dir, cJSON_IsString(c) ? c->valuestring : "camera.json", sub, sizeof sub);
            ok = mr_camera_load(sub, cam, err);
        }
    }
    if (ok && !*have_map) {
        const cJSON *m = meta ? cJSON_GetObjectItemCaseSensitive(meta, "markers") : NULL;
        if (!m && meta) m = cJSON_GetObjectItemCaseSensitive(meta, "marker_map");
        if (cJSON_IsObject(m)) *have_map = mr_marker_map_from_json(m, map, err);
        else {
            mr_path_join(dir, cJSON_IsString(m) ? m->valuestring : "markers.json", sub, sizeof sub);
            if (mr_file_exists(sub)) *have_map = mr_marker_map_load(sub, map, err);
        }
        /* No marker map is fine when frames.jsonl carries the poses. */
        if (!*have_map) err->msg[0] = 0;
    }
    cJSON_Delete(meta);
    return ok;
}

static void print_stats(view_app *a) {
    double wall = mr_time_now() - a->t_start;
    int64_t nread = 0, ntracked = 0, ndropped = 0;
    double track_sum = 0;
    if (a->cap) vw_capture_counts(a->cap, &nread, &ntracked, &ndropped, &track_sum);
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

int cmd_view(int argc, char **argv) {
    app_opt opts[] = {
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
        {"script", "FILE", "timed input events (tests, demos): see cmd_view.c", NULL},
        {"stats", NULL, "print the frame-time split on exit", NULL},
        {"ao", "METHOD", "start with this AO method (none, scheer, crytek, filion, hbao, alchemy); the A key cycles", NULL},
        {"ghost", "MODE", "start with this ghosting mode (off, alpha, g0, adaptive); the G key cycles", NULL},
        {"verbose", NULL, "more log output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!app_parse(argc, argv, 2, opts, NULL, 0, NULL,
                   "usage: mrcheck view --scene S (--input /dev/videoN|VIDEO --camera C --markers M | --replay DIR) "
                   "[--out DIR] [--fullscreen] [--stats]",
                   &help))
        return 2;
    if (help) return 0;
    app_log_level(opts);
    const char *scene_path = app_get(opts, "scene"), *input = app_get(opts, "input"), *replay = app_get(opts, "replay");
    if (!scene_path) return app_errorf(k_cmd, "--scene is required"), 2;
    if (!input == !replay) return app_errorf(k_cmd, "give either --input or --replay"), 2;

    view_app *a = calloc(1, sizeof *a);
    if (!a) return app_errorf(k_cmd, "out of memory");
    a->t_start = a->fps_t0 = mr_time_now();
    a->stats = app_flag(opts, "stats");
    a->ui_scale = 1.0;
    int rc = 0;
    mr_error err = {0};
    int ww = 960, wh = 720;
    if (app_get(opts, "size") && !app_size("size", app_get(opts, "size"), &ww, &wh)) { rc = 2; goto done; }
    if (app_get(opts, "ui-scale") && !app_double("ui-scale", app_get(opts, "ui-scale"), 0.25, 8, &a->ui_scale)) {
        rc = 2;
        goto done;
    }
    /* Inputs that can be checked without a window are checked first. */
    bool have_cam = false;
    if (app_get(opts, "camera")) {
        if (!mr_camera_load(app_get(opts, "camera"), &a->camera, &err)) { rc = app_error(k_cmd, &err); goto done; }
        have_cam = true;
    }
    if (app_get(opts, "markers")) {
        if (!mr_marker_map_load(app_get(opts, "markers"), &a->markers, &err)) { rc = app_error(k_cmd, &err); goto done; }
        a->have_markers = true;
    }
    if (app_get(opts, "view")) {
        mr_view v;
        if (!mr_view_load(app_get(opts, "view"), &v, &err)) { rc = app_error(k_cmd, &err); goto done; }
        a->fixed_pose = v.world_from_camera;
        a->have_fixed_pose = true;
        if (!have_cam) { a->camera = v.camera; have_cam = true; }
    }
    if (replay) {
        if (!load_replay_meta(replay, &a->camera, have_cam, &a->markers, &a->have_markers, &err)) {
            mr_error_prefix(&err, "%s: ", replay);
            rc = app_error(k_cmd, &err);
            goto done;
        }
        snprintf(a->source_desc, sizeof a->source_desc, "replay");
    } else {
        if (!have_cam) { rc = app_errorf(k_cmd, "--input needs --camera (or --view)"); goto done; }
        if (!a->have_markers && !a->have_fixed_pose) { rc = app_errorf(k_cmd, "--input needs --markers (or --view)"); goto done; }
        snprintf(a->source_desc, sizeof a->source_desc, "live %.200s", input);
    }
    if (app_get(opts, "script") && !script_load(a, app_get(opts, "script"), &err)) { rc = app_error(k_cmd, &err); goto done; }
    if (app_get(opts, "out")) snprintf(a->session_dir, sizeof a->session_dir, "%s", app_get(opts, "out"));
    else if (replay) snprintf(a->session_dir, sizeof a->session_dir, "%s", replay);
    else snprintf(a->session_dir, sizeof a->session_dir, "mrcheck-session");
    if (app_get(opts, "config")) snprintf(a->config_path, sizeof a->config_path, "%s", app_get(opts, "config"));
    else default_config_path(a->config_path, sizeof a->config_path);
    settings_load(a);
    /* Flags win over the saved settings for this run (and are then saved). */
    if (app_get(opts, "ao")) {
        mr_ao_method m;
        if (!mr_ao_method_parse(app_get(opts, "ao"), &m) || m >= MR_AO_METHOD_COUNT) {
            rc = app_errorf(k_cmd, "--ao must be none, scheer, crytek, filion, hbao or alchemy, got '%s'", app_get(opts, "ao"));
            goto done;
        }
        a->s.ao = m;
    }
    if (app_get(opts, "ghost")) {
        int k = -1;
        for (int i = 0; i < GHOST_COUNT; i++)
            if (strcmp(app_get(opts, "ghost"), k_ghost_names[i]) == 0) k = i;
        if (k < 0) {
            rc = app_errorf(k_cmd, "--ghost must be off, alpha, g0 or adaptive, got '%s'", app_get(opts, "ghost"));
            goto done;
        }
        a->s.ghost = (mr_ghost_mode)k;
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

    mr_window_params wp = MR_WINDOW_DEFAULTS;
    wp.width = ww;
    wp.height = wh;
    wp.fullscreen = app_flag(opts, "fullscreen");
    wp.title = "mrcheck view";
    wp.debug = mr_log_get_level() >= MR_LOG_DEBUG;
    a->win = mr_window_create(&wp, &err);
    if (!a->win) { rc = app_error(k_cmd, &err); goto done; }
    a->rend = mr_renderer_create(mr_window_gpu(a->win), &err);
    a->d2 = a->rend ? mr_draw2d_create(mr_window_gpu(a->win), &err) : NULL;
    if (!a->d2) { rc = app_error(k_cmd, &err); goto done; }
    double ppmm = mr_window_px_per_mm(a->win) * a->ui_scale;
    mr_ui_params up = MR_UI_DEFAULTS;
    up.px_per_mm = ppmm;
    mr_ui_font_params fp = MR_UI_FONT_DEFAULTS;
    fp.pixel_height = roundf((float)(3.2 * ppmm)); /* baked at the size it is drawn */
    a->font = mr_ui_font_create(&fp, &err);
    if (!a->font) { rc = app_error(k_cmd, &err); goto done; }
    up.font = a->font;
    a->ui = mr_ui_create(&up, &err);
    if (!a->ui) { rc = app_error(k_cmd, &err); goto done; }

    vw_capture_params cp = {0};
    cp.input = input;
    cp.replay_dir = replay;
    cp.camera = &a->camera;
    cp.markers = a->have_markers ? &a->markers : NULL;
    cp.fixed_pose = a->have_fixed_pose ? &a->fixed_pose : NULL;
    cp.retry_s = 1.0;
    cp.retrack = app_flag(opts, "retrack");
    if (cp.retrack && !a->have_markers) { rc = app_errorf(k_cmd, "--retrack needs a marker map"); goto done; }
    cp.wake = wake_window;
    cp.wake_ctx = a->win;
    a->cap = vw_capture_start(&cp, &err);
    if (!a->cap) { rc = app_error(k_cmd, &err); goto done; }
    vw_capture_rate(a->cap, k_rates[a->s.rate_i]);
    if (app_flag(opts, "paused")) vw_capture_play(a->cap, false);
    a->need_render = true;

    double last_save = mr_time_now();
    while (!a->quit) {
        poll_scene_load(a);
        frame_tick(a);
        /* Settings are saved a moment after they change, not per slider
         * step, and again on exit. */
        if (a->settings_dirty && mr_time_now() - last_save > 1.0) {
            settings_save(a);
            last_save = mr_time_now();
        }
        /* Sleep until input or a new frame arrives; a script or a pending
         * press keeps the loop going. */
        bool busy = a->have_held || (a->script_count && a->script_next < a->script_count) || a->input.down;
        mr_window_wait(a->win, busy ? 0.0 : 0.1);
        if (busy) {
            struct timespec ts = {0, 4000000};
            nanosleep(&ts, NULL);
        }
    }
    settings_save(a);
    if (a->stats) print_stats(a);

done:
    if (a->loader) {
        mr_error ignored = {0};
        a->scene = mr_scene_loader_finish(&a->loader, &ignored); /* waits for the thread */
    }
    vw_capture_stop(&a->cap);
    vw_frame_free(&a->frame);
    vw_frame_free(&a->mark_frame);
    mr_image_free(&a->mark_screen);
    mr_frame_result_free(&a->res);
    mr_ui_destroy(&a->ui);
    mr_ui_font_destroy(&a->font);
    mr_draw2d_destroy(&a->d2);
    mr_renderer_destroy(&a->rend);
    mr_window_destroy(&a->win);
    mr_scene_destroy(&a->scene);
    mr_marker_map_free(&a->markers);
    free(a->script);
    free(a);
    return rc;
}
