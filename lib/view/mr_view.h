/* mr_view.h — the interactive check (`mrcheck view`) as a controller that
 * runs without a window: state, settings, key map, layout, replay control,
 * the tracking-lost policy and the scripted input of tests.
 *
 * Input events in (pointer in framebuffer pixels, keys), plain data about
 * the newest camera frame and the source in, actions and a draw list (lib/ui)
 * out. The window loop (run.c, mr_view_run) owns the window, the renderer
 * and the capture threads and carries the actions out, through lib/render's
 * and lib/session's public headers; nothing here touches GL, GLFW or app/,
 * and only run.c reads or writes files other than the settings file
 * (inputs, snapshots, marks, script shots and states).
 *
 * Depends on: lib/core, lib/ui, lib/track's mr_pose_point_sigma (pure
 * math: the "± N mm here" of the status line), lib/window's plain events
 * (mr_event, MR_KEY_*), and from lib/render only plain types and
 * names (mr_ao_method, mr_ghost_mode,
 * mr_ao_method_name/parse, the option tables' enum names): no GL or GLFW call. One way only: nothing
 * below lib/view includes this header.
 * mark.c (the marking and render decisions moved out of app/cmd_view.c)
 * adds lib/track's mr_project_point and lib/render's plain mr_pick,
 * mr_frame_params and mr_shadow_method_parse, and lib/session's plain
 * types (mr_capture_frame, mr_annotation: a mark's line and the frame's
 * render setup, DESIGN.md's view -> session). run.c (the window loop,
 * moved out of app/cmd_view.c) adds lib/window's window and 2D layer and
 * lib/render's renderer (opaque handles: no GL type), lib/session's capture, snapshots and
 * marks, lib/track's camera and marker-map files, lib/scene's loader and LOD builder; not
 * lib/eval (Measure's search is the caller's, mr_view_nearest_fns). */
#ifndef MR_VIEW_CTL_H
#define MR_VIEW_CTL_H

#include "mr_core.h"
#include "mr_render.h"
#include "mr_session.h"
#include "mr_ui.h"
#include "mr_window.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------- settings */

/* Replay rates the rate button and [ ] step through. */
#define MR_VIEW_RATE_COUNT 5
extern const double mr_view_rates[MR_VIEW_RATE_COUNT];   /* 0.25 .. 4 */
/* The categories offered when marking (lib/session's mr_mark_categories;
 * a tap is quicker than typing on a tablet, the note field takes the rest). */
#define MR_VIEW_NOTE_COUNT MR_MARK_CATEGORY_COUNT

/* What persists between runs (~/.config/mrcheck/view.json). */
typedef struct mr_view_settings {
    float alpha;          /* video transparency: 0 model only, 1 video only; default 0.5 */
    bool show_video;      /* default true */
    bool hide_hidden;     /* hide the hidden layer; default false */
    int rate_i;           /* index into mr_view_rates; default 2 (1x) */
    /* The depth cues are on/off toggles for the planner (the AO, Ghost and
     * Shadows buttons, keys a g c); which method each uses when on is a
     * setting of its own (the settings panel under ?, the settings file). */
    bool ao_on, ghost_on, shadows_on; /* default false */
    mr_ao_method ao;      /* AO method when on; default MR_AO_SCHEER (never none) */
    mr_ghost_mode ghost;  /* ghosting mode when on; default MR_GHOST_ADAPTIVE (never off) */
    mr_shadow_method shadows; /* hard, pcf, pcss or bp when on; default pcss (never off) */
} mr_view_settings;
#define MR_VIEW_DEFAULT_ALPHA MR_FRAME_DEFAULT_ALPHA /* the renderer's overlay default */
#define MR_VIEW_DEFAULT_RATE_I 2
#define MR_VIEW_SETTINGS_DEFAULTS {.alpha = MR_VIEW_DEFAULT_ALPHA, .show_video = true, .hide_hidden = false, \
                                   .rate_i = MR_VIEW_DEFAULT_RATE_I, .ao = MR_AO_SCHEER, .ghost = MR_GHOST_ADAPTIVE, \
                                   .shadows = MR_SHADOW_PCSS}
/* What the toggles give: the method when on, else none / off. */
mr_ao_method mr_view_ao(const mr_view_settings *s);
mr_ghost_mode mr_view_ghost(const mr_view_settings *s);
mr_shadow_method mr_view_shadows(const mr_view_settings *s);
/* The settings that differ from the defaults, in words ("video 70%, AO on
 * (scheer)"); "" when none. Returns how many. */
int mr_view_settings_describe_changes(const mr_view_settings *s, char *out, size_t n);
/* The option table of the settings file (keys alpha, show_video,
 * hide_hidden_layer, ao_on, ghost_on, shadows_on, ao, ghost, shadows); the
 * settings panel cycles through the ao, ghost and shadows rows' names
 * (shadows: hard, pcf, pcss, bp; the ground truth is for the bench, too
 * slow to look around in). A file from before the toggles ("ao": "none",
 * no "ao_on") reads as off with the default method, and a method other
 * than none as on. The rate is stored as a rate, not as rate_i, so it is
 * read and written beside the table. */
extern const mr_opt mr_view_settings_opts[];

/* "off", "alpha", "g0", "adaptive" (mr_ghost_mode_names); "off" if out of range. */
const char *mr_view_ghost_name(mr_ghost_mode m);
bool mr_view_ghost_parse(const char *name, mr_ghost_mode *out);
/* $XDG_CONFIG_HOME/mrcheck/view.json, else ~/.config/mrcheck/view.json,
 * else ./.mrcheck-view.json. */
void mr_view_default_config_path(char *out, size_t n);
/* Tolerant: starts from the defaults; a missing file is no warning; a file
 * that does not parse, or a key with a wrong type or out of range, keeps the
 * default for what it cannot use and says so in `warn` (empty when all was
 * well). Never fails. */
void mr_view_settings_load(const char *path, mr_view_settings *s, char *warn, size_t warn_n);
/* Creates the folder and writes atomically (temporary file + rename), so a
 * crash never leaves a half-written file. */
bool mr_view_settings_save(const char *path, const mr_view_settings *s, mr_error *err);

/* ---------------------------------------------------------------- layout */

typedef enum mr_view_widget_id {
    MR_VW_ALPHA = 0, MR_VW_PLAY, MR_VW_BACK, MR_VW_FORWARD, MR_VW_RATE, MR_VW_SEEK,
    MR_VW_FREEZE, MR_VW_SNAPSHOT, MR_VW_MARK, MR_VW_VIDEO, MR_VW_HIDDEN, MR_VW_AO, MR_VW_GHOST, MR_VW_HELP,
    MR_VW_NOTE1, MR_VW_NOTE6 = MR_VW_NOTE1 + MR_VIEW_NOTE_COUNT - 1, MR_VW_CANCEL,
    MR_VW_MEASURE,        /* Measure; in the column right after Mark */
    MR_VW_SHADOWS,        /* the shadows toggle, after Ghost */
    MR_VW_QUIT,           /* last in the column: asks first */
    MR_VW_QUIT_YES, MR_VW_QUIT_NO, /* the question */
    MR_VW_NOTE_TEXT,      /* the note chooser's text field */
    MR_VW_CLOSE_MARK,     /* the chooser of a mark being edited: close it */
    MR_VW_SET_AO, MR_VW_SET_GHOST, MR_VW_SET_SHADOWS, MR_VW_RESET, /* the settings panel (under ?) */
    MR_VW_COUNT
} mr_view_widget_id;

/* The name scripts use (`tap @video`): "alpha", "play", ..., "note1", "cancel". */
const char *mr_view_widget_name(mr_view_widget_id id);

typedef struct mr_view_layout_params {
    float fb_w, fb_h;     /* framebuffer pixels */
    bool seekable;        /* replay: the play / step / rate / seek row */
    bool note_open;       /* the note chooser after a tap in mark mode */
    float mark_x;         /* the mark's window x, to put the chooser on the other side */
    bool editing;         /* the chooser edits a saved mark: a Close button */
    bool quit_open;       /* "Quit?" */
    bool help_open;       /* the help and settings panel */
} mr_view_layout_params;

typedef struct mr_viewer mr_viewer;

typedef struct mr_view_layout {
    mr_ui_rect status, bottom, column, notes, quit, help; /* panels (zero size when absent) */
    mr_ui_rect picture;   /* what the panels leave free: the camera picture is fitted into it */
    bool shown[MR_VW_COUNT];
    mr_ui_rect rect[MR_VW_COUNT];
    int dropped;          /* widgets left out because the window is too small */
} mr_view_layout;

/* RectCut in millimetres through the ui's density: a status line on top, the
 * transparency slider (and the replay row) at the bottom, a column of toggles
 * at the right that wraps into more columns when the window is short. Every
 * shown widget is at least the ui's touch target (9 mm) on both sides, inside
 * the window, and overlaps no other. A window too small for all of them
 * leaves out the lowest priorities first (help, then ghost, AO, hidden, ...;
 * in the replay row rate, then seek); the keys still reach them all. */
void mr_view_layout_compute(const mr_ui *ui, const mr_view_layout_params *p, mr_view_layout *out);

/* The area the panels leave free in a window of fb_w x fb_h (the replay
 * row when seekable): where the camera picture is fitted, so that no part
 * of it lies under a control. */
mr_ui_rect mr_viewer_picture_area(mr_viewer *v, float fb_w, float fb_h, bool seekable);

/* --------------------------------------------------- tracking-lost policy */

typedef struct mr_view_render_choice {
    float alpha;          /* the alpha to render with */
    bool use_pose;        /* false: no pose yet, draw from a neutral pose (video only) */
    bool dimmed;          /* tracking lost: model faded at the last good pose */
} mr_view_render_choice;

/* Tracking lost keeps the last good pose but lets the video through, so a
 * stale model never passes for the truth: alpha goes to
 * 1 - (1 - alpha) * 0.35 (only with video shown; frozen pictures stay as
 * they are). No pose yet: video only. */
mr_view_render_choice mr_view_render_policy(const mr_view_settings *s, bool have_pose, bool pose_valid,
                                            bool frozen);

/* ------------------------------------------------------------ controller */

typedef enum mr_view_action_type {
    MR_VA_NONE = 0,
    MR_VA_RENDER,         /* a setting the picture depends on changed: render again */
    MR_VA_FREEZE,         /* on: freeze frame and pose */
    MR_VA_SNAPSHOT,       /* screen + raw frame + pose, from this frame's screen */
    MR_VA_MARK_AT,        /* x, y: window pixel to mark; answer with mr_viewer_note_open */
    MR_VA_MARK_FINISH,    /* i: category index, or -1 cancelled; path: the note as typed */
    MR_VA_PLAY,           /* on: replay plays */
    MR_VA_STEP,           /* i: frames (+1 / -1) */
    MR_VA_SEEK,           /* i: frame index (large: the last) */
    MR_VA_RATE,           /* x: replay rate */
    MR_VA_FULLSCREEN,     /* toggle */
    MR_VA_RESIZE,         /* x, y: window size (scripts) */
    MR_VA_SHOT,           /* path: save this frame's screen as PNG (scripts) */
    MR_VA_STATE,          /* path: write a state snapshot JSON (scripts) */
    MR_VA_QUIT,
    MR_VA_MEASURE_DONE,   /* a measurement is finished (mr_viewer_measurement);
                             measure it against the plan, answer with
                             mr_viewer_measure_distance, and mark it */
    MR_VA_MARK_EDIT,      /* a saved mark edited: x its pin index, i its category,
                             path the note as typed, on: close it; the answer
                             is mr_viewer_pin_put with the new state */
} mr_view_action_type;

typedef struct mr_view_action {
    mr_view_action_type type;
    bool on;
    int64_t i;
    double x, y;
    const char *path;     /* valid until the next call into the controller */
} mr_view_action;

#define MR_VIEW_MAX_ACTIONS 64
typedef struct mr_view_actions {
    mr_view_action a[MR_VIEW_MAX_ACTIONS];
    int count;            /* set to 0 before each call that fills it */
    mr_view_action overflow; /* scratch: what a full list drops */
} mr_view_actions;

typedef struct mr_viewer_params {
    double px_per_mm;          /* screen density (already times any UI scale); 0 = 96 dpi */
    const char *font_path;     /* NULL = a system sans font */
    const char *config_path;   /* settings file; NULL = none (nothing saved) */
    double now;                /* clock at start, seconds (mr_time_now) */
    double save_delay_s;       /* settings are saved this long after a change; 0 = 1 s */
    double script_wait_s;      /* a script starts with the first picture, or after this; 0 = 3 s */
    bool show_stats;           /* the status line adds the render passes and the frame rate (--stats) */
    const mr_tolerances *tolerances; /* Measure's verdicts (borrowed); NULL: DIN 18202 Table 1 */
} mr_viewer_params;
#define MR_VIEWER_DEFAULTS {0.0, NULL, NULL, 0.0, 0.0, 0.0, false, NULL}

/* Plain data about what the window shows, given each frame. */
typedef struct mr_viewer_frame {
    double now;                /* clock, seconds */
    float fb_w, fb_h;          /* framebuffer pixels */
    double px_per_mm;          /* 0 = unchanged */
    /* the newest camera frame */
    bool have_frame, have_pose, pose_valid;
    int64_t index, count;      /* count -1 if unknown (live) */
    int tags_seen;
    double rms_px;
    /* the source */
    bool seekable, playing;    /* replay */
    const char *source_desc;   /* "replay", "live /dev/video0" */
    const char *source_msg;    /* a failure to show ("no camera ..."), or NULL */
    const char *scene_msg;     /* loading / failure of the scene, or NULL */
    /* the rendered picture */
    bool have_image;           /* a picture is on screen */
    mr_ui_rect image_rect;     /* where, in framebuffer pixels */
    bool dimmed;               /* the policy dimmed it */
    const char *passes;        /* the frame's pass list */
    double fps;
    /* Registration uncertainty: the pose shown, its covariance
     * (mr_pose.cov's convention; NULL or corner_sigma_px 0: unknown, as in
     * recordings made before it was written) and the world point to tell it
     * at: the model under the screen centre (mr_renderer_pick) or the point
     * just picked for a mark; have_point false: nothing there. */
    mr_dmat4 world_from_camera;
    const double *pose_cov;    /* 36 */
    double corner_sigma_px;
    bool have_point;
    mr_dvec3 point;            /* world, scene units */
    /* Measure: the picture's camera (intrinsics at the frame's
     * image size; the picture is shown undistorted, so its distortion is
     * not used); NULL: taps cannot be measured */
    const mr_camera *camera;
} mr_viewer_frame;

/* "± N mm here": the registration's 1-σ at f->point (3D, scene units taken
 * as metres) from the pose covariance through mr_pose_point_sigma. false
 * (σ unknown) without a valid pose, a covariance or a point, or with the
 * point behind the camera. */
bool mr_view_sigma_here(const mr_viewer_frame *f, double *sigma_m);
/* The colour state of that σ: below MR_VIEW_SIGMA_OK_MM good enough to
 * judge a discrepancy of a few centimetres, up to MR_VIEW_SIGMA_WARN_MM
 * doubtful, above it not to be trusted. */
typedef enum mr_view_sigma_state { MR_VIEW_SIGMA_UNKNOWN = 0, MR_VIEW_SIGMA_OK, MR_VIEW_SIGMA_WARN, MR_VIEW_SIGMA_BAD } mr_view_sigma_state;
#define MR_VIEW_SIGMA_OK_MM 10.0
#define MR_VIEW_SIGMA_WARN_MM 30.0
mr_view_sigma_state mr_view_sigma_classify(bool known, double sigma_m);

/* NULL + err when the font cannot be found (MR_ERR_IO) or memory runs out.
 * Reads the settings file (warnings go to the log). */
mr_viewer *mr_viewer_create(const mr_viewer_params *p, mr_error *err);
void mr_viewer_destroy(mr_viewer **v);

/* Queues one input event (window events and scripted ones alike). */
void mr_viewer_push_event(mr_viewer *v, const mr_event *e);
/* Events queued and not yet taken. */
int mr_viewer_pending(const mr_viewer *v);

/* First half of a frame: runs the script commands that are due, then takes
 * queued input (at most one press or release per frame, so a quick tap is
 * never lost; moves and keys at once). Key actions go to *out. `busy`: a
 * render is pending, so a script waits for its effect to be drawn. */
void mr_viewer_input(mr_viewer *v, double now, bool busy, mr_view_actions *out);
/* Second half: lays out and draws the UI for this frame; taps on widgets go
 * to *out. Returns the draw list (valid until the next call). Also saves
 * the settings a moment after they changed. */
const mr_ui_draw_list *mr_viewer_ui(mr_viewer *v, const mr_viewer_frame *f, mr_view_actions *out);

/* Answers to actions. */
void mr_viewer_note_open(mr_viewer *v, float mark_x, float mark_y); /* MARK_AT worked: fractions of the picture */

/* Saved marks, shown as pins anchored in the world: projected each frame
 * with the frame's pose into the picture (none without a pose), numbered,
 * grey once closed. A tap on a pin opens its mark for editing
 * (MR_VA_MARK_EDIT). */
typedef struct mr_view_pin {
    mr_dvec3 world;            /* scene units */
    bool has_world;            /* false: listed, not drawn */
    int number;                /* shown on the pin */
    bool closed;
    int category;              /* index into mr_mark_categories, -1 none */
    mr_verdict_kind verdict;   /* a measured mark's verdict: the pin's colour
                                  (within green, undecided amber, out red) */
    char note[512];            /* as the editor shows it (with @ # ! fields) */
    char title[200];
} mr_view_pin;
/* index < count replaces that pin, index == count appends; false when out
 * of memory or out of range. */
bool mr_viewer_pin_put(mr_viewer *v, int index, const mr_view_pin *pin);
int mr_viewer_pin_count(const mr_viewer *v);
/* Where pin i is on screen this frame (window px); false when not drawn. */
bool mr_viewer_pin_at(const mr_viewer *v, int i, float *x, float *y);
void mr_viewer_toast(mr_viewer *v, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* State. */
const mr_view_settings *mr_viewer_settings(const mr_viewer *v);
/* Replaces the settings for this run without marking them changed (flags). */
void mr_viewer_set_settings(mr_viewer *v, const mr_view_settings *s);
bool mr_viewer_frozen(const mr_viewer *v);
bool mr_viewer_note_is_open(const mr_viewer *v);
bool mr_viewer_wants_input(const mr_viewer *v); /* script running, press held or queued */
const mr_ui *mr_viewer_ui_ctx(const mr_viewer *v);
const mr_view_layout *mr_viewer_layout(const mr_viewer *v);
/* Saves now if changed; false + err if it could not. */
bool mr_viewer_save_settings(mr_viewer *v, mr_error *err);
/* The status line as last drawn ("" before the first mr_viewer_ui). */
const char *mr_viewer_status_text(const mr_viewer *v);
/* The controller's part of a `state` snapshot (settings, modes, widgets,
 * "sigma_here_mm" (null: unknown) and "sigma_state"). */
cJSON *mr_viewer_state_json(const mr_viewer *v);

/* ------------------------------------------------ Measure */

/* The Measure button (key d): the planner taps the same real feature in
 * two or more frames (replay or live); each tap keeps its frame's pose and
 * pose covariance, and a second tap in one frame replaces the first. From
 * two taps on, the point is triangulated (mr_triangulate with the default
 * tap noise: refused, with the baseline angle, when the taps came from
 * nearly one pose) and its sigma shown. Measure (or Enter) again finishes a
 * solved measurement with MR_VA_MEASURE_DONE; Esc, or Measure before a
 * solution, cancels. A tap needs a tracked pose and f->camera. */
typedef struct mr_measurement mr_measurement; /* mr_track.h */
bool mr_viewer_measuring(const mr_viewer *v);
/* The measurement being made or the last one finished (taps, point,
 * covariance, and the distance once given); false when there is none. */
bool mr_viewer_measurement(const mr_viewer *v, mr_measurement *out);
/* The answer to MR_VA_MEASURE_DONE: the distance (scene units taken as
 * metres) and its 1-sigma to `planned` (on node `node` of layer `layer`
 * ("visible" / "hidden"), either may be NULL), kept in the measurement and
 * judged (mr_verdict_measure with the params' tolerances: the part's, the
 * layer's, else by the planned point's nominal size); the verdict, the
 * interval and the tolerance stay on screen in the verdict's colour while
 * the mark is filed. */
void mr_viewer_measure_distance(mr_viewer *v, mr_dvec3 planned, double dist_m, double sigma_m, const char *node,
                                const char *layer);
/* The last measurement's verdict; false when it has none (no distance yet). */
bool mr_viewer_measure_verdict(const mr_viewer *v, mr_verdict *out);

/* ----------------------------------------- marking and rendering (mark.c) */

/* A window position (framebuffer px) in the picture shown at image_rect,
 * rendered at rw x rh: the rendered image's pixel (OpenCV convention);
 * false outside the picture. */
bool mr_view_window_to_image(mr_ui_rect image_rect, int rw, int rh, double x, double y, double *u, double *v);
/* The pin of a snapshot: a filled disc of pure magenta (255, 0, 255),
 * radius 4 px, centred on pixel (u, v) (OpenCV convention), in a white
 * ring out to 7 px; RGB 8-bit images only (others are left as they are). */
#define MR_VIEW_PIN_R 4.0
void mr_view_draw_pin(mr_image *img, double u, double v);
/* That pixel in the camera's own resolution (ideal pinhole), as marks store it. */
void mr_view_image_to_camera(const mr_camera *cam, int rw, int rh, double u, double v, double *px, double *py);

/* The planned surface's point nearest to a measurement (lib/eval's
 * mr_nearest_hit, as plain data). */
typedef struct mr_view_planned {
    bool found;
    mr_dvec3 point;            /* world, scene units */
    int node;                  /* -1: none */
    int layer;                 /* that node's layer */
} mr_view_planned;
/* Where the mark of a finished measurement goes. */
typedef struct mr_view_mark_at {
    double px, py;             /* the measured point in the frame (ideal pinhole; the centre if behind) */
    mr_pick pick;              /* the planned point, when found; else no hit, node -1 */
    float note_u, note_v;      /* for mr_viewer_note_open: fractions of the picture */
} mr_view_mark_at;
/* cam: the camera (resized here to the frame's image_w x image_h). */
void mr_view_measure_mark(const mr_camera *cam, int image_w, int image_h, const mr_dmat4 *world_from_camera,
                          mr_dvec3 measured, const mr_view_planned *planned, mr_view_mark_at *out);

/* The shadow method of a frame: the C key's once it changed the saved
 * setting (start), else --shadows (given, flag), else the scene config's
 * ("" none; an unknown name: off), else the saved setting. */
typedef struct mr_view_shadow_choice {
    mr_shadow_method start;    /* the saved setting at start */
    bool keyed;                /* the C key changed it (set by mr_view_shadow_choose) */
    bool given;                /* --shadows */
    mr_shadow_method flag;
} mr_view_shadow_choice;
mr_shadow_method mr_view_shadow_choose(mr_view_shadow_choice *c, mr_shadow_method setting, const char *scene_method);
/* What the settings set in a frame's parameters: the hidden layer, the AO
 * method, the ghosting mode, and the shadow method given. */
void mr_view_frame_params(const mr_view_settings *s, mr_shadow_method shadows, mr_frame_params *fp);

/* What the window renders for capture frame f at rw x rh: the view (the
 * frame's pose, or a neutral one where the render policy says not to use
 * it) and the frame parameters (size, video, the policy's alpha, the
 * settings' passes, temporal AO reset when the pose comes back after a gap:
 * had_pose is whether the last render had one). *c gets the policy. */
void mr_view_render_setup(const mr_view_settings *s, const mr_camera *cam, const mr_capture_frame *f, bool frozen,
                          mr_shadow_method shadows, bool ao_temporal, bool had_pose, int rw, int rh, mr_view *view,
                          mr_frame_params *fp, mr_view_render_choice *c);

/* What the planner said about a mark. */
typedef struct mr_view_mark_words {
    const char *id;            /* the mark's id (mr_mark_new_id) */
    int category;              /* index into mr_mark_categories, -1 none */
    const char *typed;         /* the note as typed (mr_mark_set_note), may be NULL */
} mr_view_mark_words;
/* The annotation line (lib/session's format) of a mark made on frame f:
 * its id, category, note and generated title, the tapped camera pixel, what was picked there (its node's name
 * and layer from scene), the registration's sigma at the picked point, and
 * the measurement of a Measure mark and its verdict (NULL for a plain
 * mark, or a measurement without one). */
cJSON *mr_view_mark_line(const mr_capture_frame *f, const mr_view_mark_words *w, double px, double py,
                         const mr_pick *pick, const mr_scene *scene, const mr_measurement *measured,
                         const mr_verdict *verdict);

/* The capture frame's part of what the controller is told each frame
 * (pose, its covariance, tracking counts, the picture's undistorted camera
 * in *picture_cam, which vf->camera then points to). */
void mr_view_frame_from_capture(mr_viewer_frame *vf, const mr_capture_frame *f, bool have_frame, const mr_camera *cam,
                                mr_camera *picture_cam);

/* What only the window knows, for a `state` snapshot. */
typedef struct mr_view_window_state {
    int marks, snapshots;
    const char *source_state, *source_message, *scene_message;
    const mr_image *screen;    /* the screen as read back, or NULL */
    bool have_render;          /* a rendered picture with a pose: the fields below */
    int render_w, render_h;
    double diff_to_model, diff_to_video; /* mean |difference| of the picture to the
                                            alpha 0 and alpha 1 renderings (-1: failed) */
} mr_view_window_state;
/* Adds it to j (mr_viewer_state_json's object): "marks", "snapshots",
 * "source_state", "source_message", "scene_message", the screen's
 * "screen_mean" and "screen_std" (a blank window has no spread), and with a
 * render "render_width", "render_height", "diff_to_model", "diff_to_video"
 * (which way the slider moved the picture). */
void mr_view_state_add_window(cJSON *j, const mr_view_window_state *w);

/* ---------------------------------------------------------------- script */

/* A script of timed input: one command per line, `T COMMAND ARGS`, T in
 * seconds from the first picture on screen. Widgets are named (`@alpha`),
 * so scripts survive layout changes:
 *   tap X Y | tap @name        down X Y | up X Y | move X Y
 *   tap @picture U V           (U, V: fractions of the camera picture's width
 *                               and height, wherever the layout put it)
 *   drag @slider F0 F1         (fractions of the slider's width)
 *   key K                      (a character, or esc enter left right up down home end f1 f11 space tab backspace)
 *   text WORDS...              (typed, as a keyboard's characters: the rest of the line)
 *   resize W H | shot OUT.png | state OUT.json | quit (at once, without the question)
 *   seek N                     (replay: shows frame N, forwards or back; the
 *                               commands after it wait, up to 60 s, until
 *                               frame N itself is shown)
 *   frame N                    (the commands after it wait, up to 60 s, until
 *                               frame N or a later one is shown: play tests
 *                               that do not depend on the machine's speed)
 * Input enters the controller's queue, the path real input takes. */
typedef struct mr_view_script mr_view_script;
/* NULL + err (MR_ERR_IO, or MR_ERR_PARSE naming the line) on a bad file. */
mr_view_script *mr_view_script_load(const char *path, mr_error *err);
void mr_view_script_destroy(mr_view_script **s);
/* Hands the script to the controller, which owns it from then on (*s is
 * set to NULL); it replaces any earlier one. */
void mr_viewer_set_script(mr_viewer *v, mr_view_script **s);
/* Parses a key name as scripts write it. */
bool mr_view_key_parse(const char *s, int *key);

/* Every key and what it does (what `?` shows). Esc only ever cancels;
 * q (or the Quit button) asks before quitting. */
typedef struct mr_view_key_help {
    const char *keys, *what;
} mr_view_key_help;
extern const mr_view_key_help mr_view_keymap[];
extern const int mr_view_keymap_count;

/* ------------------------------------------------- the window (run.c) */

/* Where the frames come from, and the files they are tracked with. */
typedef struct mr_view_source_params {
    const char *input;         /* live: /dev/videoN, a video file, an image or a folder of images */
    const char *replay_dir;    /* a recording (exactly one of input and replay_dir) */
    const char *camera_path;   /* camera JSON; NULL: the view file's, or the recording's */
    const char *markers_path;  /* marker map JSON; NULL: the recording's, if any */
    const char *view_path;     /* view file: a fixed pose instead of tracking (and its camera) */
} mr_view_source_params;
#define MR_VIEW_SOURCE_DEFAULTS {NULL, NULL, NULL, NULL, NULL}
/* The source loaded: what the capture threads and the window need. */
typedef struct mr_view_source {
    const char *input, *replay_dir; /* borrowed from the params */
    mr_camera camera;
    mr_marker_map markers;
    bool have_markers;
    mr_dmat4 fixed_pose;       /* world_from_camera of the view file */
    bool have_fixed_pose;
    char desc[256];            /* "replay", "live /dev/video0" (the status line) */
} mr_view_source;
/* Loads the camera, the marker map and the fixed pose, a recording's
 * meta.json filling in what the files did not give. Live input needs a
 * camera (or a view file) and a marker map (or a view file). false + err
 * (the message names the file or the missing flag), with nothing left to
 * free; else free *out with mr_view_source_free. */
bool mr_view_source_load(const mr_view_source_params *p, mr_view_source *out, mr_error *err);
void mr_view_source_free(mr_view_source *s); /* accepts NULL and a zeroed source */

/* Measure's planned surface: the nearest point of the model to a measured
 * point. The search lives above lib/view (lib/eval), so the caller hands it
 * in as functions; without `create` nothing is measured against the plan. */
typedef struct mr_view_nearest_hit {
    bool found;
    mr_dvec3 point;            /* nearest point on the model, world, scene units */
    double distance;           /* to it, scene units */
    double sigma;              /* the distance's 1-sigma from the point's covariance, scene units */
    int node;                  /* its scene node, -1 none */
} mr_view_nearest_hit;
typedef struct mr_view_nearest_fns {
    /* A search over scene's triangles (built on the first measurement; the
     * scene outlives it); NULL + err on failure. */
    void *(*create)(void *user, const mr_scene *scene, mr_error *err);
    /* p's nearest point; cov: p's 3x3 covariance (row-major, scene units^2).
     * false: no answer (out->found false). */
    bool (*query)(void *user, void *search, mr_dvec3 p, const double cov[9], mr_view_nearest_hit *out);
    void (*destroy)(void *user, void *search);
    void *user;
} mr_view_nearest_fns;

/* One interactive check, from the window's opening to its closing. */
typedef struct mr_view_run_params {
    const char *scene_path;    /* glTF/GLB or scene config JSON (required) */
    const mr_view_source *source; /* required; borrowed */
    const char *out_dir;       /* annotations.jsonl and snapshots/; NULL: the recording, else ./mrcheck-session */
    const char *config_path;   /* settings file; NULL: mr_view_default_config_path */
    int width, height;         /* window size, px; 0 = 960 x 720 */
    bool fullscreen;           /* default false (F11 toggles) */
    double ui_scale;           /* the UI beyond the screen's density; 0 = 1 */
    bool paused;               /* replay: start paused */
    bool retrack;              /* replay: track the frames again (needs a marker map) */
    bool ao_given, ghost_given, shadows_given; /* the values below replace the saved settings for this run */
    mr_ao_method ao;
    mr_ghost_mode ghost;
    mr_shadow_method shadows;  /* over the scene config's too (mr_view_shadow_choice) */
    bool ao_temporal;          /* accumulate the AO over frames; default false */
    mr_view_script **script;   /* handed to the controller (*script NULLed) once it exists; NULL: none */
    FILE *stats;               /* the frame-time split is printed here on exit; NULL: not */
    mr_view_nearest_fns nearest; /* Measure's planned surface; zero: none */
    const char *tolerances_path; /* Measure's tolerance table (--tolerances, the hall's); NULL: DIN 18202
                                    Table 1. One that does not load ends the run before the window opens */
    double start_time;         /* mr_time_now() when the command started (the stats' wall clock); 0 = now */
} mr_view_run_params;
#define MR_VIEW_RUN_DEFAULT_WIDTH 960
#define MR_VIEW_RUN_DEFAULT_HEIGHT 720
#define MR_VIEW_RUN_DEFAULTS {.width = MR_VIEW_RUN_DEFAULT_WIDTH, .height = MR_VIEW_RUN_DEFAULT_HEIGHT, .ui_scale = 1.0}
/* Loads the scene on a thread (a scene that fails is shown as a message)
 * and, where it draws MR_LOD_AUTO_TRIANGLES or more, its levels of detail
 * (the cache next to it, else built on a thread while the full detail is
 * drawn), opens the window, the renderer and the controller, starts capture, and
 * runs until quit; then saves the settings. false + err when the window,
 * the renderer, the controller or the capture cannot start (MR_ERR_NODEVICE
 * without a display). */
bool mr_view_run(const mr_view_run_params *p, mr_error *err);

#ifdef __cplusplus
}
#endif
#endif
