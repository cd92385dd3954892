/* lib/view without a window: the controller driven by synthetic events and
 * a fake clock. Slider, toggles (act on release, slide off cancels), the
 * key map, AO and ghost cycling, settings (round trip, damaged files,
 * atomic writes), replay controls, the tracking-lost policy, the real
 * layout at several densities and in windows too small for it, scripts. */
#include "mr_session.h"
#include "mr_test.h"
#include "mr_track.h"
#include "mr_view.h"

#include <errno.h>
#include <string.h>
#include <unistd.h>

/* test_view links with -Wl,--wrap=rename (tests/CMakeLists.txt): the test
 * sees that the settings file arrives by rename and can make it fail. */
int __real_rename(const char *from, const char *to);
int __wrap_rename(const char *from, const char *to);
static struct {
    int fail;            /* errno to fail with, 0: pass through */
    int renames;
    char to[1200];
} g_rn;
int __wrap_rename(const char *from, const char *to) {
    g_rn.renames++;
    snprintf(g_rn.to, sizeof g_rn.to, "%s", to);
    if (g_rn.fail) {
        errno = g_rn.fail;
        return -1;
    }
    return __real_rename(from, to);
}

static char g_tmp[1024];

static void tmp_path(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", g_tmp, name); }

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "wb");
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

static char *read_text(const char *path) {
    mr_error err = {0};
    size_t n = 0;
    return mr_file_read(path, &n, 1 << 20, &err);
}

/* ------------------------------------------------------------ the rig */

typedef struct rig {
    mr_viewer *v;
    mr_viewer_frame f;
    mr_view_actions acts;  /* everything the last step asked for */
    double t;
} rig;

static bool rig_open(rig *r, const char *config, double ppmm, mr_error *err) {
    memset(r, 0, sizeof *r);
    mr_viewer_params p = MR_VIEWER_DEFAULTS;
    p.px_per_mm = ppmm;
    p.config_path = config;
    p.now = 0;
    r->v = mr_viewer_create(&p, err);
    r->f.fb_w = 960;
    r->f.fb_h = 720;
    r->f.px_per_mm = ppmm;
    r->f.have_frame = r->f.have_pose = r->f.pose_valid = true;
    r->f.index = 2;
    r->f.count = 100;
    r->f.tags_seen = 3;
    r->f.source_desc = "replay";
    r->f.have_image = true;
    r->f.image_rect = mr_ui_rect_make(100, 60, 640, 480);
    r->f.passes = "gbuffer shade overlay";
    return r->v != NULL;
}

/* One frame: input, then UI; the actions of both halves in r->acts. */
static void step(rig *r) {
    r->t += 1.0 / 60;
    mr_view_actions a = {0}, b = {0};
    mr_viewer_input(r->v, r->t, false, &a);
    r->f.now = r->t;
    mr_viewer_ui(r->v, &r->f, &b);
    r->acts = a;
    for (int i = 0; i < b.count && r->acts.count < MR_VIEW_MAX_ACTIONS; i++) r->acts.a[r->acts.count++] = b.a[i];
}

static void ev(rig *r, mr_event_type t, double x, double y) {
    mr_event e = {t, x, y, 0};
    mr_viewer_push_event(r->v, &e);
}

static void key(rig *r, int k) {
    mr_event e = {MR_EVENT_KEY, 0, 0, k};
    mr_viewer_push_event(r->v, &e);
    step(r);
}

/* How many actions of a type the last step asked for; *first gets the first. */
static int count(const rig *r, mr_view_action_type t, mr_view_action *first) {
    int n = 0;
    for (int i = 0; i < r->acts.count; i++)
        if (r->acts.a[i].type == t) {
            if (!n && first) *first = r->acts.a[i];
            n++;
        }
    return n;
}

static mr_ui_rect wrect(const rig *r, mr_view_widget_id id) { return mr_viewer_layout(r->v)->rect[id]; }
static float cx(mr_ui_rect b) { return b.x + b.w / 2; }
static float cy(mr_ui_rect b) { return b.y + b.h / 2; }

/* A press and a release at (x, y), one frame each (as the window sees a
 * tap); the actions of all three frames are counted together in *acts. */
static void tap_at(rig *r, float x, float y, mr_view_actions *acts) {
    memset(acts, 0, sizeof *acts);
    ev(r, MR_EVENT_POINTER_MOVE, x, y);
    ev(r, MR_EVENT_POINTER_DOWN, x, y);
    ev(r, MR_EVENT_POINTER_UP, x, y);
    for (int k = 0; k < 3; k++) {
        step(r);
        for (int i = 0; i < r->acts.count && acts->count < MR_VIEW_MAX_ACTIONS; i++) acts->a[acts->count++] = r->acts.a[i];
    }
    r->acts = *acts;
}

static void tap(rig *r, mr_view_widget_id id) {
    mr_view_actions all;
    CHECK_MSG(mr_viewer_layout(r->v)->shown[id], "widget %s is not on screen", mr_view_widget_name(id));
    tap_at(r, cx(wrect(r, id)), cy(wrect(r, id)), &all);
}

/* ------------------------------------------------------------- slider */

static void test_slider(rig *r) {
    step(r);
    mr_ui_rect s = wrect(r, MR_VW_ALPHA);
    const mr_ui *ui = mr_viewer_ui_ctx(r->v);
    /* Press at the knob of 0.3, hold: alpha follows the pointer. */
    float x3 = mr_ui_slider_knob_x(ui, s, 0.3f, 0, 1);
    ev(r, MR_EVENT_POINTER_MOVE, x3, cy(s));
    ev(r, MR_EVENT_POINTER_DOWN, x3, cy(s));
    step(r);
    CHECK_MSG(fabs(mr_viewer_settings(r->v)->alpha - 0.3) < 1e-4, "slider pressed at 0.3 gave alpha %.4f",
              mr_viewer_settings(r->v)->alpha);
    CHECK_MSG(count(r, MR_VA_RENDER, NULL) == 1, "moving the slider asked for %d renders, want 1",
              count(r, MR_VA_RENDER, NULL));
    /* Dragged far left, past the end: 0, which is the model only. */
    ev(r, MR_EVENT_POINTER_MOVE, -500, cy(s) + 300);
    step(r);
    float a = mr_viewer_settings(r->v)->alpha;
    CHECK_MSG(a == 0.0f, "slider dragged past the left end gave alpha %g, want 0 (model only)", a);
    mr_view_render_choice c = mr_view_render_policy(mr_viewer_settings(r->v), true, true, false);
    CHECK_MSG(c.alpha == 0.0f && !c.dimmed, "alpha 0 with a good pose renders with alpha %g, want 0 (model only)",
              c.alpha);
    /* Far right: 1 (video only), never beyond. */
    ev(r, MR_EVENT_POINTER_MOVE, 1e5, cy(s));
    step(r);
    a = mr_viewer_settings(r->v)->alpha;
    CHECK_MSG(a == 1.0f, "slider dragged past the right end gave alpha %g, want 1 (video only)", a);
    /* Back to 0.75 and let go: it stays. */
    float x75 = mr_ui_slider_knob_x(ui, s, 0.75f, 0, 1);
    ev(r, MR_EVENT_POINTER_MOVE, x75, cy(s));
    step(r);
    ev(r, MR_EVENT_POINTER_UP, x75, cy(s));
    step(r);
    ev(r, MR_EVENT_POINTER_MOVE, s.x + 2, cy(s));
    step(r);
    a = mr_viewer_settings(r->v)->alpha;
    CHECK_MSG(fabs(a - 0.75) < 1e-4, "after release at 0.75 and a hover, alpha is %g", a);
    for (int i = 0; i < 14; i++) {
        key(r, MR_KEY_UP);
        a = mr_viewer_settings(r->v)->alpha;
        CHECK_MSG(a >= 0 && a <= 1, "Up made alpha %g, outside [0, 1]", a);
    }
    CHECK_MSG(a == 1.0f, "Up 14 times from 0.75 gave alpha %g, want 1", a);
}

/* ------------------------------------------------- toggles on release */

static void test_toggles(rig *r) {
    step(r);
    mr_ui_rect b = wrect(r, MR_VW_VIDEO);
    bool before = mr_viewer_settings(r->v)->show_video;
    ev(r, MR_EVENT_POINTER_MOVE, cx(b), cy(b));
    ev(r, MR_EVENT_POINTER_DOWN, cx(b), cy(b));
    step(r);
    CHECK_MSG(mr_viewer_settings(r->v)->show_video == before && count(r, MR_VA_RENDER, NULL) == 0,
              "the Video toggle acted on press (it must act on release)");
    ev(r, MR_EVENT_POINTER_UP, cx(b), cy(b));
    step(r);
    CHECK_MSG(mr_viewer_settings(r->v)->show_video == !before && count(r, MR_VA_RENDER, NULL) == 1,
              "the Video toggle did not act on release over it");
    /* Freeze: press, nothing; release, FREEZE on. */
    mr_ui_rect fz = wrect(r, MR_VW_FREEZE);
    ev(r, MR_EVENT_POINTER_MOVE, cx(fz), cy(fz));
    ev(r, MR_EVENT_POINTER_DOWN, cx(fz), cy(fz));
    step(r);
    CHECK_MSG(count(r, MR_VA_FREEZE, NULL) == 0 && !mr_viewer_frozen(r->v), "Freeze acted on press");
    ev(r, MR_EVENT_POINTER_UP, cx(fz), cy(fz));
    step(r);
    mr_view_action x;
    CHECK_MSG(count(r, MR_VA_FREEZE, &x) == 1 && x.on && mr_viewer_frozen(r->v), "Freeze did not act on release");
    /* Slide off: press on Video, move onto the picture, release there:
     * nothing, and not a tap on the scene either (no mark in mark mode). */
    key(r, 'm');
    before = mr_viewer_settings(r->v)->show_video;
    ev(r, MR_EVENT_POINTER_MOVE, cx(b), cy(b));
    ev(r, MR_EVENT_POINTER_DOWN, cx(b), cy(b));
    step(r);
    ev(r, MR_EVENT_POINTER_MOVE, 300, 300);
    step(r);
    ev(r, MR_EVENT_POINTER_UP, 300, 300);
    step(r);
    CHECK_MSG(mr_viewer_settings(r->v)->show_video == before && count(r, MR_VA_RENDER, NULL) == 0,
              "a finger that slid off the Video toggle still toggled it");
    CHECK_MSG(count(r, MR_VA_MARK_AT, NULL) == 0, "a slide off a toggle was taken as a tap on the scene");
    /* A real tap on the picture in mark mode asks for a mark there. */
    mr_view_actions all;
    tap_at(r, 300, 300, &all);
    CHECK_MSG(count(r, MR_VA_MARK_AT, &x) == 1 && x.x == 300 && x.y == 300, "a tap on the picture in mark mode "
              "gave %d MARK_AT actions", count(r, MR_VA_MARK_AT, NULL));
    /* The chooser opens; note 2 by tap finishes the mark with note index 1. */
    mr_viewer_note_open(r->v, 0.3f, 0.5f);
    step(r);
    CHECK_MSG(mr_viewer_layout(r->v)->shown[MR_VW_NOTE1 + 1], "no note chooser after the mark");
    tap(r, MR_VW_NOTE1 + 1);
    CHECK_MSG(count(r, MR_VA_MARK_FINISH, &x) == 1 && x.i == 1, "tap on note 2 gave %d MARK_FINISH (i %lld)",
              count(r, MR_VA_MARK_FINISH, NULL), (long long)x.i);
    CHECK_MSG(!mr_viewer_note_is_open(r->v), "the chooser stayed open after a note");
    key(r, 'f'); /* unfreeze for the next tests */
}

/* ------------------------------------------------------------ key map */

static void test_keys(rig *r) {
    r->f.seekable = true;
    r->f.playing = false;
    step(r);
    if (mr_viewer_frozen(r->v)) key(r, 'f');
    mr_view_action x;
    mr_view_settings s0 = *mr_viewer_settings(r->v);
    s0.alpha = 0.5f;
    s0.rate_i = 2;
    mr_viewer_set_settings(r->v, &s0);
    key(r, '+');
    CHECK_MSG(fabs(mr_viewer_settings(r->v)->alpha - 0.6) < 1e-6, "+ gave alpha %g from 0.5, want 0.6",
              mr_viewer_settings(r->v)->alpha);
    key(r, '=');
    key(r, MR_KEY_UP);
    CHECK_MSG(fabs(mr_viewer_settings(r->v)->alpha - 0.8) < 1e-6, "= and Up gave %g, want 0.8", mr_viewer_settings(r->v)->alpha);
    key(r, '-');
    key(r, MR_KEY_DOWN);
    CHECK_MSG(fabs(mr_viewer_settings(r->v)->alpha - 0.6) < 1e-6, "- and Down gave %g, want 0.6", mr_viewer_settings(r->v)->alpha);
    key(r, 'f');
    CHECK_MSG(count(r, MR_VA_FREEZE, &x) == 1 && x.on, "f did not freeze");
    key(r, '.');
    CHECK_MSG(count(r, MR_VA_FREEZE, &x) == 1 && !x.on && r->acts.a[0].type == MR_VA_FREEZE,
              "stepping while frozen did not unfreeze first");
    CHECK_MSG(count(r, MR_VA_STEP, &x) == 1 && x.i == 1, ". did not step +1");
    key(r, MR_KEY_RIGHT);
    CHECK_MSG(count(r, MR_VA_STEP, &x) == 1 && x.i == 1, "Right did not step +1");
    key(r, ',');
    CHECK_MSG(count(r, MR_VA_STEP, &x) == 1 && x.i == -1, ", did not step -1");
    key(r, MR_KEY_LEFT);
    CHECK_MSG(count(r, MR_VA_STEP, &x) == 1 && x.i == -1, "Left did not step -1");
    key(r, 's');
    CHECK_MSG(count(r, MR_VA_SNAPSHOT, NULL) == 1, "s asked for no snapshot");
    bool v0 = mr_viewer_settings(r->v)->show_video;
    key(r, 'v');
    CHECK_MSG(mr_viewer_settings(r->v)->show_video == !v0 && count(r, MR_VA_RENDER, NULL) == 1, "v did not toggle the video");
    bool h0 = mr_viewer_settings(r->v)->hide_hidden;
    key(r, 'h');
    CHECK_MSG(mr_viewer_settings(r->v)->hide_hidden == !h0 && count(r, MR_VA_RENDER, NULL) == 1, "h did not toggle the hidden layer");
    key(r, ' ');
    CHECK_MSG(count(r, MR_VA_PLAY, &x) == 1 && x.on, "space while paused did not ask to play");
    r->f.playing = true;
    step(r);
    key(r, ' ');
    CHECK_MSG(count(r, MR_VA_PLAY, &x) == 1 && !x.on, "space while playing did not ask to pause");
    key(r, MR_KEY_HOME);
    CHECK_MSG(count(r, MR_VA_SEEK, &x) == 1 && x.i == 0, "Home did not seek to 0");
    key(r, MR_KEY_END);
    CHECK_MSG(count(r, MR_VA_SEEK, &x) == 1 && x.i >= 1000000, "End did not seek to the end");
    key(r, '[');
    CHECK_MSG(count(r, MR_VA_RATE, &x) == 1 && x.x == 0.5, "[ from 1x gave rate %g, want 0.5", x.x);
    key(r, ']');
    key(r, ']');
    CHECK_MSG(count(r, MR_VA_RATE, &x) == 1 && x.x == 2.0, "] ] from 0.5x gave rate %g, want 2", x.x);
    for (int i = 0; i < 5; i++) key(r, ']');
    CHECK_MSG(x.x == 2.0 && mr_viewer_settings(r->v)->rate_i == MR_VIEW_RATE_COUNT - 1, "] does not stop at 4x");
    key(r, MR_KEY_F11);
    CHECK_MSG(count(r, MR_VA_FULLSCREEN, NULL) == 1, "F11 did not toggle fullscreen");
    key(r, '?');
    cJSON *j = mr_viewer_state_json(r->v);
    CHECK_MSG(cJSON_IsTrue(cJSON_GetObjectItem(j, "help")), "? did not open the help");
    cJSON_Delete(j);
    key(r, MR_KEY_ESCAPE);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "Esc with the help open quit instead of closing the help");
    key(r, MR_KEY_F1);
    key(r, MR_KEY_F1);
    j = mr_viewer_state_json(r->v);
    CHECK_MSG(!cJSON_IsTrue(cJSON_GetObjectItem(j, "help")), "F1 twice left the help open");
    cJSON_Delete(j);
    /* Mark mode: Enter marks the picture's centre; Esc leaves the mode. */
    key(r, 'm');
    key(r, MR_KEY_ENTER);
    CHECK_MSG(count(r, MR_VA_MARK_AT, &x) == 1 && x.x == cx(r->f.image_rect) && x.y == cy(r->f.image_rect),
              "Enter in mark mode did not mark the picture's centre");
    key(r, MR_KEY_ESCAPE);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "Esc in mark mode quit");
    key(r, MR_KEY_ENTER);
    CHECK_MSG(count(r, MR_VA_MARK_AT, NULL) == 0, "Esc did not leave mark mode");
    /* The chooser: 1..6 choose, Esc cancels, other keys do nothing; Esc
     * again (the chooser gone) never quits. */
    key(r, 'm');
    mr_viewer_note_open(r->v, 0.5f, 0.5f);
    key(r, 'q');
    CHECK_MSG(r->acts.count == 0, "q with the chooser open did something");
    key(r, MR_KEY_ESCAPE);
    CHECK_MSG(count(r, MR_VA_MARK_FINISH, &x) == 1 && x.i == -1 && count(r, MR_VA_QUIT, NULL) == 0,
              "Esc with the chooser open did not cancel the mark (or quit)");
    for (int i = 0; i < 3; i++) {
        key(r, MR_KEY_ESCAPE);
        CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "Esc after cancelling the chooser quit (press %d)", i + 1);
    }
    key(r, 'm');
    mr_viewer_note_open(r->v, 0.5f, 0.5f);
    key(r, 'v');
    CHECK_MSG(r->acts.count == 0, "v with the chooser open did something");
    key(r, '6');
    CHECK_MSG(count(r, MR_VA_MARK_FINISH, &x) == 1 && x.i == 5, "6 did not choose category 6");
    /* The note's text field: Enter gives it the keyboard, what is typed
     * goes in (digits too), Backspace deletes, Enter leaves it; the note
     * goes with the category chosen. */
    key(r, 'm');
    mr_viewer_note_open(r->v, 0.5f, 0.5f);
    key(r, MR_KEY_ENTER);
    const char *typed = "pipe 2 moved @ann #hvac";
    for (const char *c = typed; *c; c++) key(r, *c);
    key(r, 'x');
    key(r, MR_KEY_BACKSPACE);
    CHECK_MSG(r->acts.count == 0, "typing a note did something else");
    key(r, MR_KEY_ENTER);
    key(r, '3');
    CHECK_MSG(count(r, MR_VA_MARK_FINISH, &x) == 1 && x.i == 2 && x.path && strcmp(x.path, typed) == 0,
              "the typed note did not go with the mark: '%s'", x.path ? x.path : "(none)");
    /* Quitting asks first: q opens the question, Esc or n keeps the check
     * going, Enter (or y, or q again) quits. */
    key(r, 'q');
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "q quit without asking");
    key(r, MR_KEY_ESCAPE);
    key(r, MR_KEY_ENTER);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "Esc did not take back the question");
    key(r, 'q');
    key(r, 'n');
    key(r, 'y');
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "n did not take back the question");
    key(r, 'q');
    key(r, MR_KEY_ENTER);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 1, "q then Enter did not quit");
    key(r, 'q');
    tap(r, MR_VW_QUIT_NO);
    key(r, MR_KEY_ENTER);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "Stay did not take back the question");
    tap(r, MR_VW_QUIT);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "the Quit button quit without asking");
    tap(r, MR_VW_QUIT_YES);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 1, "Quit then Quit did not quit");
    key(r, MR_KEY_ESCAPE);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 0, "Esc quit");
    /* q and Esc are in the help. */
    bool q_listed = false, esc_listed = false;
    for (int i = 0; i < mr_view_keymap_count; i++) {
        q_listed |= strcmp(mr_view_keymap[i].keys, "q") == 0 && strstr(mr_view_keymap[i].what, "quit");
        esc_listed |= strcmp(mr_view_keymap[i].keys, "Esc") == 0 && strstr(mr_view_keymap[i].what, "never quits");
    }
    CHECK_MSG(q_listed && esc_listed, "the help does not list q (quit) and Esc (never quits)");
    /* Live input: no replay keys. */
    r->f.seekable = false;
    step(r);
    key(r, ' ');
    key(r, '.');
    CHECK_MSG(r->acts.count == 0, "replay keys act on live input");
    /* A window close is a quit. */
    ev(r, MR_EVENT_CLOSE, 0, 0);
    step(r);
    CHECK_MSG(count(r, MR_VA_QUIT, NULL) == 1, "closing the window did not quit");
}

/* Taps are queued, never lost: eleven taps on AO that arrive at once (as
 * a slow render leaves them in the queue) are eleven toggles, one render
 * asked for each. */
static void test_tap_queue(rig *r) {
    step(r);
    bool on0 = mr_viewer_settings(r->v)->ao_on;
    mr_ui_rect b = wrect(r, MR_VW_AO);
    for (int i = 0; i < 11; i++) {
        ev(r, MR_EVENT_POINTER_MOVE, cx(b), cy(b));
        ev(r, MR_EVENT_POINTER_DOWN, cx(b), cy(b));
        ev(r, MR_EVENT_POINTER_UP, cx(b), cy(b));
    }
    int renders = 0;
    for (int i = 0; i < 100; i++) {
        step(r);
        renders += count(r, MR_VA_RENDER, NULL);
    }
    CHECK_MSG(renders == 11 && mr_viewer_settings(r->v)->ao_on == !on0 && mr_viewer_pending(r->v) == 0,
              "11 queued taps on AO gave %d renders (want 11), AO %s", renders,
              mr_viewer_settings(r->v)->ao_on == !on0 ? "toggled" : "not toggled an odd number of times");
}

/* ------------------------------------------- depth cues: toggles, methods */

/* AO, ghosting and shadows are on/off toggles (keys a g c, the buttons);
 * the method each uses when on is chosen in the settings panel (under ?),
 * which cycles through the methods and never offers "none" / "off". */
static void test_cycling(rig *r) {
    mr_view_settings s = *mr_viewer_settings(r->v);
    s.ao_on = s.ghost_on = s.shadows_on = false;
    mr_viewer_set_settings(r->v, &s);
    step(r);
    for (int i = 1; i <= 4; i++) {
        if (i % 2) key(r, 'a');
        else tap(r, MR_VW_AO);
        bool want = i % 2;
        CHECK_MSG(mr_viewer_settings(r->v)->ao_on == want && (mr_view_ao(mr_viewer_settings(r->v)) != MR_AO_NONE) == want,
                  "AO press %d (%s): on %d, want %d", i, i % 2 ? "key a" : "button", mr_viewer_settings(r->v)->ao_on, want);
        CHECK_MSG(count(r, MR_VA_RENDER, NULL) == 1, "an AO toggle asked for no render");
        if (i % 2) key(r, 'g');
        else tap(r, MR_VW_GHOST);
        CHECK_MSG(mr_viewer_settings(r->v)->ghost_on == want && (mr_view_ghost(mr_viewer_settings(r->v)) != MR_GHOST_OFF) == want,
                  "ghost press %d: on %d", i, mr_viewer_settings(r->v)->ghost_on);
        if (i % 2) key(r, 'c');
        else tap(r, MR_VW_SHADOWS);
        CHECK_MSG(mr_viewer_settings(r->v)->shadows_on == want &&
                      (mr_view_shadows(mr_viewer_settings(r->v)) != MR_SHADOW_OFF) == want,
                  "shadows press %d: on %d", i, mr_viewer_settings(r->v)->shadows_on);
        CHECK_MSG(count(r, MR_VA_RENDER, NULL) == 1, "a shadows toggle asked for no render");
    }
    /* The methods, in the settings panel. */
    key(r, '?');
    mr_ao_method a0 = mr_viewer_settings(r->v)->ao;
    for (int i = 0; i < 2 * (MR_AO_METHOD_COUNT - 1); i++) {
        tap(r, MR_VW_SET_AO);
        CHECK_MSG(mr_viewer_settings(r->v)->ao != MR_AO_NONE, "the AO method cycle offered none");
        CHECK_MSG(!mr_viewer_settings(r->v)->ao_on, "choosing the AO method turned AO on");
    }
    CHECK_MSG(mr_viewer_settings(r->v)->ao == a0, "the AO methods do not cycle back (every method but none, in order)");
    static const mr_ghost_mode order[] = {MR_GHOST_ALPHA, MR_GHOST_G0, MR_GHOST_ADAPTIVE, MR_GHOST_ALPHA};
    for (int i = 0; i < 4; i++) {
        tap(r, MR_VW_SET_GHOST);
        CHECK_MSG(mr_viewer_settings(r->v)->ghost == order[i], "ghost mode press %d gave %s, want %s", i + 1,
                  mr_view_ghost_name(mr_viewer_settings(r->v)->ghost), mr_view_ghost_name(order[i]));
    }
    /* Shadows: hard, pcf, pcss, bp (never off, never the ground truth). */
    static const mr_shadow_method sorder[] = {MR_SHADOW_BP, MR_SHADOW_HARD, MR_SHADOW_PCF, MR_SHADOW_PCSS, MR_SHADOW_BP};
    for (int i = 0; i < 5; i++) {
        tap(r, MR_VW_SET_SHADOWS);
        CHECK_MSG(mr_viewer_settings(r->v)->shadows == sorder[i], "shadows press %d gave %s, want %s", i + 1,
                  mr_shadow_method_names[mr_viewer_settings(r->v)->shadows], mr_shadow_method_names[sorder[i]]);
        CHECK_MSG(count(r, MR_VA_RENDER, NULL) == 1, "a shadow method change asked for no render");
    }
    /* Reset: the defaults again, from the UI. */
    mr_view_settings d = MR_VIEW_SETTINGS_DEFAULTS;
    char changes[300];
    CHECK(mr_view_settings_describe_changes(mr_viewer_settings(r->v), changes, sizeof changes) > 0 && changes[0]);
    tap(r, MR_VW_RESET);
    const mr_view_settings *now = mr_viewer_settings(r->v);
    CHECK_MSG(now->ao == d.ao && now->ghost == d.ghost && now->shadows == d.shadows && now->alpha == d.alpha &&
                  now->ao_on == d.ao_on && mr_view_settings_describe_changes(now, changes, sizeof changes) == 0,
              "Reset did not bring the defaults back (%s)", changes);
    key(r, '?');
}

/* ---------------------------------------------------------- settings */

static bool same(const mr_view_settings *a, const mr_view_settings *b) {
    return a->alpha == b->alpha && a->show_video == b->show_video && a->hide_hidden == b->hide_hidden &&
           a->rate_i == b->rate_i && a->ao == b->ao && a->ghost == b->ghost && a->shadows == b->shadows &&
           a->ao_on == b->ao_on && a->ghost_on == b->ghost_on && a->shadows_on == b->shadows_on;
}

static void test_settings(void) {
    char path[1200], warn[1024];
    tmp_path(path, sizeof path, "cfg/sub/view.json");
    unlink(path);
    mr_view_settings d = MR_VIEW_SETTINGS_DEFAULTS, s;
    mr_view_settings_load(path, &s, warn, sizeof warn);
    CHECK_MSG(same(&s, &d) && !warn[0], "a missing settings file: not the defaults, or a warning '%s'", warn);
    CHECK(d.alpha == 0.5f && d.show_video && !d.hide_hidden && d.rate_i == 2 && !d.ao_on && !d.ghost_on &&
          !d.shadows_on && mr_view_ao(&d) == MR_AO_NONE && mr_view_ghost(&d) == MR_GHOST_OFF &&
          mr_view_shadows(&d) == MR_SHADOW_OFF && d.ao != MR_AO_NONE && d.ghost != MR_GHOST_OFF && d.shadows != MR_SHADOW_OFF);
    /* Round trip of every field, in a folder that does not exist yet. */
    mr_view_settings w = {0.25f, false, true, 4, true, false, true, MR_AO_HBAO, MR_GHOST_G0, MR_SHADOW_PCSS};
    mr_error err = {0};
    g_rn.renames = 0;
    CHECK_MSG(mr_view_settings_save(path, &w, &err), "save: %s", err.msg);
    mr_view_settings_load(path, &s, warn, sizeof warn);
    CHECK_MSG(same(&s, &w) && !warn[0], "settings round trip: read back alpha %g video %d hidden %d rate %d ao %s "
              "ghost %s, warning '%s'", s.alpha, s.show_video, s.hide_hidden, s.rate_i, mr_ao_method_name(s.ao),
              mr_view_ghost_name(s.ghost), warn);
    /* Atomic: the file arrives by rename; a failed rename leaves the old
     * file whole and the save reports it. */
    CHECK_MSG(g_rn.renames >= 1 && strcmp(g_rn.to, path) == 0,
              "the settings file was not written by rename over it (written in place: not atomic)");
    char *old = read_text(path);
    mr_view_settings w2 = w;
    w2.alpha = 0.9f;
    g_rn.fail = EIO;
    memset(&err, 0, sizeof err);
    bool ok = mr_view_settings_save(path, &w2, &err);
    g_rn.fail = 0;
    char *now = read_text(path);
    CHECK_MSG(!ok && err.msg[0], "a save whose rename failed reported success");
    CHECK_MSG(old && now && strcmp(old, now) == 0, "a failed save changed the settings file in place (not atomic)");
    free(old);
    free(now);
    /* A file from before the toggles: a method named is on; none is off
     * with the default method. */
    write_text(path, "{\"ao\": \"hbao\", \"ghost\": \"off\", \"shadows\": \"pcf\"}");
    mr_view_settings_load(path, &s, warn, sizeof warn);
    CHECK_MSG(!warn[0] && s.ao_on && s.ao == MR_AO_HBAO && !s.ghost_on && s.ghost == d.ghost && s.shadows_on &&
                  s.shadows == MR_SHADOW_PCF,
              "an older settings file read as ao %d/%s ghost %d/%s shadows %d (%s)", s.ao_on, mr_ao_method_name(s.ao),
              s.ghost_on, mr_view_ghost_name(s.ghost), s.shadows_on, warn);
    /* Damaged files: a warning, defaults for what cannot be used, the rest
     * kept, never a crash. */
    static const struct {
        const char *text, *what;
        bool keeps_alpha;     /* alpha 0.25 in the text survives */
    } bad[] = {
        {"{\"alpha\": 0.25, \"ao\": \"hbao\"", "truncated JSON", false},
        {"garbage \x01\xff", "not JSON", false},
        {"", "an empty file", false},
        {"[1, 2, 3]", "an array", false},
        {"{\"alpha\": 1.5}", "alpha out of range", false},
        {"{\"alpha\": \"half\"}", "alpha a string", false},
        {"{\"alpha\": 0.25, \"show_video\": 1}", "show_video a number", true},
        {"{\"alpha\": 0.25, \"ao\": \"magic\"}", "an unknown AO method", true},
        {"{\"alpha\": 0.25, \"ghost\": 3}", "ghost a number", true},
        {"{\"alpha\": 0.25, \"shadows\": \"groundtruth\"}", "shadows the ground truth (not offered)", true},
        {"{\"alpha\": 0.25, \"shadows\": \"soft\"}", "an unknown shadow method", true},
        {"{\"alpha\": 0.25, \"rate\": 3}", "a rate not on the list", true},
        {"{\"alpha\": 0.25, \"hide_hidden_layer\": null}", "hide_hidden_layer null", true},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        write_text(path, bad[i].text);
        mr_view_settings_load(path, &s, warn, sizeof warn);
        CHECK_MSG(warn[0], "settings with %s gave no warning", bad[i].what);
        CHECK_MSG(s.alpha == (bad[i].keeps_alpha ? 0.25f : d.alpha), "settings with %s: alpha %g", bad[i].what, s.alpha);
        CHECK_MSG(s.show_video == d.show_video && s.hide_hidden == d.hide_hidden && s.rate_i == d.rate_i &&
                      s.ao == d.ao && s.ghost == d.ghost && s.shadows == d.shadows,
                  "settings with %s: a damaged field did not fall back to its default", bad[i].what);
    }
    /* The controller reads the file at start and saves a moment after a
     * change, not at once (a slider drag would write per step). */
    w.alpha = 0.25f;
    CHECK(mr_view_settings_save(path, &w, &err));
    rig r;
    if (!rig_open(&r, path, 96 / 25.4, &err)) return;
    CHECK_MSG(same(mr_viewer_settings(r.v), &w), "the controller did not start from the settings file");
    step(&r);
    key(&r, 'v');
    mr_view_settings_load(path, &s, warn, sizeof warn);
    CHECK_MSG(s.show_video == w.show_video, "settings saved at once on a change (want a moment later)");
    for (int i = 0; i < 70; i++) step(&r); /* > 1 s of frames */
    mr_view_settings_load(path, &s, warn, sizeof warn);
    CHECK_MSG(s.show_video == !w.show_video, "settings not saved a second after a change");
    mr_viewer_destroy(&r.v);
    CHECK(r.v == NULL);
    mr_viewer_destroy(&r.v);
}

/* ----------------------------------------------------------- replay */

static void test_replay(rig *r) {
    r->f.seekable = true;
    r->f.playing = false;
    r->f.index = 10;
    r->f.count = 101;
    mr_view_settings s = *mr_viewer_settings(r->v);
    s.rate_i = MR_VIEW_RATE_COUNT - 1;
    mr_viewer_set_settings(r->v, &s);
    step(r);
    if (mr_viewer_frozen(r->v)) key(r, 'f');
    mr_view_action x;
    tap(r, MR_VW_PLAY);
    CHECK_MSG(count(r, MR_VA_PLAY, &x) == 1 && x.on, "Play while paused did not ask to play");
    r->f.playing = true;
    tap(r, MR_VW_PLAY);
    CHECK_MSG(count(r, MR_VA_PLAY, &x) == 1 && !x.on, "Pause while playing did not ask to pause");
    tap(r, MR_VW_BACK);
    CHECK_MSG(count(r, MR_VA_STEP, &x) == 1 && x.i == -1, "< did not step back");
    tap(r, MR_VW_FORWARD);
    CHECK_MSG(count(r, MR_VA_STEP, &x) == 1 && x.i == 1, "> did not step forward");
    tap(r, MR_VW_RATE);
    CHECK_MSG(count(r, MR_VA_RATE, &x) == 1 && x.x == 0.25, "the rate button after 4x gave %g, want 0.25", x.x);
    tap(r, MR_VW_RATE);
    CHECK_MSG(count(r, MR_VA_RATE, &x) == 1 && x.x == 0.5, "the rate button after 0.25x gave %g, want 0.5", x.x);
    /* Seek bar pressed at 90%: frame 90 of 0..100. */
    key(r, 'f');
    mr_ui_rect sk = wrect(r, MR_VW_SEEK);
    float x9 = mr_ui_slider_knob_x(mr_viewer_ui_ctx(r->v), sk, 90.0f, 0, 100);
    ev(r, MR_EVENT_POINTER_MOVE, x9, cy(sk));
    ev(r, MR_EVENT_POINTER_DOWN, x9, cy(sk));
    step(r);
    CHECK_MSG(count(r, MR_VA_SEEK, &x) == 1 && x.i == 90, "seek bar at 90%% gave %d seeks to %lld, want frame 90",
              count(r, MR_VA_SEEK, NULL), (long long)x.i);
    CHECK_MSG(count(r, MR_VA_FREEZE, &x) == 1 && !x.on, "seeking while frozen did not unfreeze");
    r->f.index = 90;
    step(r);
    CHECK_MSG(count(r, MR_VA_SEEK, NULL) == 0, "holding the seek bar on the shown frame seeks again");
    ev(r, MR_EVENT_POINTER_UP, x9, cy(sk));
    step(r);
    /* Live input: no replay row. */
    r->f.seekable = false;
    step(r);
    for (int id = MR_VW_PLAY; id <= MR_VW_SEEK; id++)
        CHECK_MSG(!mr_viewer_layout(r->v)->shown[id], "live input shows the replay widget %s",
                  mr_view_widget_name((mr_view_widget_id)id));
}

/* -------------------------------------------------- tracking lost */

static void test_tracking_lost(void) {
    for (int k = 0; k < 3; k++) {
        mr_view_settings s = MR_VIEW_SETTINGS_DEFAULTS;
        s.alpha = k == 0 ? 0.0f : k == 1 ? 0.5f : 0.8f;
        mr_view_render_choice good = mr_view_render_policy(&s, true, true, false);
        CHECK_MSG(good.alpha == s.alpha && good.use_pose && !good.dimmed, "a good pose changed alpha %g to %g",
                  s.alpha, good.alpha);
        /* Lost: towards the video, at the last good pose, model still there. */
        mr_view_render_choice lost = mr_view_render_policy(&s, true, false, false);
        double want = 1.0 - (1.0 - s.alpha) * 0.35;
        CHECK_MSG(lost.dimmed && lost.use_pose && fabs(lost.alpha - want) < 1e-6,
                  "tracking lost at alpha %g: alpha %g (want %g, faded towards the video), dimmed %d, pose %d",
                  s.alpha, lost.alpha, want, lost.dimmed, lost.use_pose);
        CHECK_MSG(lost.alpha > s.alpha && lost.alpha < 1.0f, "tracking lost at alpha %g gave %g: want between the "
                  "setting and video only", s.alpha, lost.alpha);
        /* Frozen: the still is what the user chose to look at. */
        mr_view_render_choice fr = mr_view_render_policy(&s, true, false, true);
        CHECK_MSG(fr.alpha == s.alpha && !fr.dimmed, "a frozen picture was dimmed");
        /* No video: nothing to fade to. */
        s.show_video = false;
        mr_view_render_choice nv = mr_view_render_policy(&s, true, false, false);
        CHECK_MSG(nv.alpha == s.alpha && nv.dimmed, "tracking lost without video changed alpha to %g", nv.alpha);
        /* Never a pose: video only, from a neutral pose. */
        s.show_video = true;
        mr_view_render_choice np = mr_view_render_policy(&s, false, false, false);
        CHECK_MSG(np.alpha == 1.0f && !np.use_pose, "no pose yet: alpha %g, pose %d (want video only)", np.alpha,
                  np.use_pose);
    }
}

/* ------------------------------------------ registration uncertainty */

/* Issue 15: "+/- N mm here" from a given covariance and point. The camera
 * sits at (10, 0, 0) looking down +z (OpenCV axes); the point is on its
 * axis at depth d. A rotation error w about the camera's x and y moves the
 * point by d * w across the ray, a translation error tau moves it by tau:
 * sigma^2 = d^2 (sx^2 + sy^2) + tx^2 + ty^2 + tz^2 (closed form, not the
 * library's code). */
static double closed_form_sigma(double d, const double *cov) {
    return sqrt(d * d * (cov[0] + cov[7]) + cov[21] + cov[28] + cov[35]);
}

static void test_sigma(rig *r) {
    double cov[36] = {0};
    cov[0] = cov[7] = 0.002 * 0.002;                 /* 2 mrad about x and y */
    cov[14] = 0.01 * 0.01;                           /* roll: no effect on the axis */
    cov[21] = cov[28] = cov[35] = 0.001 * 0.001;     /* 1 mm per axis */
    mr_dmat4 wfc = mr_m4_identity();
    wfc.m[3] = 10.0; /* row-major: the translation column */
    const double depths[3] = {1.0, 4.0, 20.0};
    const mr_view_sigma_state want_state[3] = {MR_VIEW_SIGMA_OK, MR_VIEW_SIGMA_WARN, MR_VIEW_SIGMA_BAD};
    for (int k = 0; k < 3; k++) {
        double d = depths[k];
        r->f.world_from_camera = wfc;
        r->f.pose_cov = cov;
        r->f.corner_sigma_px = 0.5;
        r->f.have_point = true;
        r->f.point = mr_v3(10.0, 0.0, d);
        double want = closed_form_sigma(d, cov), got = -1;
        CHECK_MSG(mr_view_sigma_here(&r->f, &got) && fabs(got - want) < 1e-9 * (1 + want),
                  "sigma at depth %g: %g m, want %g m", d, got, want);
        step(r);
        char text[64];
        double mm = want * 1e3;
        snprintf(text, sizeof text, mm < 9.95 ? "registration +/- %.1f mm at the centre" : "registration +/- %.0f mm at the centre", mm);
        CHECK_MSG(strstr(mr_viewer_status_text(r->v), text) != NULL, "status line '%s' lacks '%s'",
                  mr_viewer_status_text(r->v), text);
        CHECK_MSG(mr_view_sigma_classify(true, want) == want_state[k], "sigma %.1f mm: state %d, want %d", mm,
                  (int)mr_view_sigma_classify(true, want), (int)want_state[k]);
        cJSON *st = mr_viewer_state_json(r->v);
        const cJSON *sh = cJSON_GetObjectItemCaseSensitive(st, "sigma_here_mm");
        CHECK_MSG(cJSON_IsNumber(sh) && fabs(sh->valuedouble - mm) < 1e-6, "state sigma_here_mm %g, want %g",
                  cJSON_IsNumber(sh) ? sh->valuedouble : -1.0, mm);
        cJSON_Delete(st);
    }
    CHECK_MSG(mr_view_sigma_classify(false, 0.001) == MR_VIEW_SIGMA_UNKNOWN, "an unknown sigma has a state");
    /* Unknown: no covariance (an older recording), nothing under the centre,
     * the point behind the camera. */
    for (int k = 0; k < 3; k++) {
        r->f.pose_cov = k == 0 ? NULL : cov;
        r->f.corner_sigma_px = k == 0 ? 0 : 0.5;
        r->f.have_point = k != 1;
        r->f.point = mr_v3(10.0, 0.0, k == 2 ? -3.0 : 3.0);
        CHECK_MSG(!mr_view_sigma_here(&r->f, NULL), "case %d: a sigma without covariance, point or depth", k);
        step(r);
        CHECK_MSG(strstr(mr_viewer_status_text(r->v), "+/- ? mm at the centre") != NULL, "case %d: status line '%s' "
                  "does not say the sigma is unknown", k, mr_viewer_status_text(r->v));
        cJSON *st = mr_viewer_state_json(r->v);
        CHECK_MSG(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(st, "sigma_here_mm")), "case %d: state has a sigma", k);
        cJSON_Delete(st);
    }
    /* No pose at all: nothing to tell. */
    r->f.have_pose = r->f.pose_valid = false;
    step(r);
    CHECK_MSG(strstr(mr_viewer_status_text(r->v), "mm at the") == NULL, "no pose, yet '%s'", mr_viewer_status_text(r->v));
    r->f.have_pose = r->f.pose_valid = true;
    r->f.pose_cov = NULL;
    r->f.have_point = false;
}

/* ------------------------------------------------- Measure (issue 15) */

/* The rig's frame as seen from `eye` looking at `at`, frame `index`. */
static void measure_frame(rig *r, int64_t index, mr_dvec3 eye, mr_dvec3 at, const double *cov) {
    r->f.index = index;
    r->f.have_pose = r->f.pose_valid = true;
    r->f.world_from_camera = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
    r->f.pose_cov = cov;
    r->f.corner_sigma_px = cov ? 0.5 : 0;
}

/* Where world point X shows in the rig's picture (window pixels): the
 * picture is undistorted, so a plain pinhole. */
static void window_of(const rig *r, const mr_camera *cam, mr_dvec3 X, float *x, float *y) {
    mr_dmat4 cfw = mr_m4_invert_rigid(&r->f.world_from_camera);
    mr_dvec3 q = mr_m4_point(&cfw, X);
    double u = cam->fx * q.x / q.z + cam->cx, v = cam->fy * q.y / q.z + cam->cy;
    mr_ui_rect ir = r->f.image_rect;
    *x = (float)(ir.x + (u + 0.5) * ir.w / cam->width);
    *y = (float)(ir.y + (v + 0.5) * ir.h / cam->height);
}

/* obj as one line of a .jsonl file (a line without its newline is torn). */
static char *line_of(const cJSON *obj) {
    char *t = cJSON_PrintUnformatted(obj), *l = t ? malloc(strlen(t) + 2) : NULL;
    if (l) snprintf(l, strlen(t) + 2, "%s\n", t);
    free(t);
    return l;
}

static const char *state_str(const rig *r, const char *key, char *buf, size_t n) {
    cJSON *st = mr_viewer_state_json(r->v);
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(st, key);
    snprintf(buf, n, "%s", cJSON_IsString(m) ? m->valuestring : "");
    cJSON_Delete(st);
    return buf;
}

/* Events in, a measurement and its annotation out: taps of one feature in
 * three frames (one from nearly the same place as the first: refused on
 * its own), the button finishes, the distance comes back, the mark's
 * measured_* fields round-trip through lib/session. Also: Esc and d
 * cancel, a tap without a tracked pose or outside the picture is not
 * taken, a second tap in one frame replaces the first. */
static void test_measure(rig *r) {
    /* Distorted camera: the picture is shown undistorted, so the
     * measurement must not undistort the taps again. */
    mr_camera cam = {640, 480, 500, 500, 319.5, 239.5, {-0.2, 0.05, 0, 0, 0}};
    r->f.camera = &cam;
    r->f.image_rect = mr_ui_rect_make(100, 60, 640, 480);
    double cov[36] = {0};
    for (int i = 0; i < 3; i++) cov[7 * i] = 1e-6, cov[7 * (i + 3)] = 1e-6; /* 1 mrad, 1 mm */
    const mr_dvec3 X = mr_v3(0.3, 1.2, 5.0), at = mr_v3(-1.0, 0.4, 5); /* X well off the centre */
    char msg[256];
    mr_measurement m;
    measure_frame(r, 10, mr_v3(-1, 1.5, 0), at, cov);
    step(r);
    CHECK(!mr_viewer_measuring(r->v) && !mr_viewer_measurement(r->v, &m));
    CHECK_MSG(mr_viewer_layout(r->v)->shown[MR_VW_MEASURE], "no Measure button");
    tap(r, MR_VW_MEASURE);
    CHECK(mr_viewer_measuring(r->v));
    float x, y;
    window_of(r, &cam, X, &x, &y);
    mr_view_actions acts;
    tap_at(r, x + 3, y, &acts);
    tap_at(r, x, y, &acts); /* the same frame: replaces the first */
    CHECK(mr_viewer_measurement(r->v, &m) && m.taps == 1 && m.frames[0] == 10);
    CHECK_NEAR(m.px[0][0], (x - 100) - 0.5, 1e-3); /* the picture is 1:1 with the camera */
    /* Nearly the same place (1 mm to the side): refused with the angle. */
    measure_frame(r, 11, mr_v3(-0.999, 1.5, 0), at, cov);
    step(r);
    window_of(r, &cam, X, &x, &y);
    tap_at(r, x, y, &acts);
    CHECK(mr_viewer_measurement(r->v, &m) && m.taps == 2);
    CHECK_MSG(strstr(state_str(r, "measure_message", msg, sizeof msg), "baseline angle") != NULL, "message '%s'", msg);
    cJSON *st = mr_viewer_state_json(r->v);
    CHECK(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(st, "measure"), "solved")));
    cJSON_Delete(st);
    /* A frame from far enough away, but tracking lost: the tap is refused. */
    measure_frame(r, 12, mr_v3(1.5, 1.4, 0.5), at, cov);
    r->f.pose_valid = false;
    step(r);
    window_of(r, &cam, X, &x, &y);
    tap_at(r, x, y, &acts);
    CHECK(mr_viewer_measurement(r->v, &m) && m.taps == 2);
    CHECK_MSG(strstr(state_str(r, "measure_message", msg, sizeof msg), "no tracked pose") != NULL, "message '%s'", msg);
    r->f.pose_valid = true;
    step(r);
    tap_at(r, x, y, &acts);
    CHECK(mr_viewer_measurement(r->v, &m) && m.taps == 3 && m.frames[2] == 12);
    CHECK_MSG(mr_v3_len(mr_v3_sub(m.tri.point, X)) < 2e-3, "measured (%g %g %g), want (0.3 1.2 5)", m.tri.point.x,
              m.tri.point.y, m.tri.point.z);
    CHECK(m.tri.sigma > 0 && m.tri.sigma < 0.05 && m.tri.angle_deg > 10);
    CHECK(count(r, MR_VA_MEASURE_DONE, NULL) == 0);
    /* Finish: one MEASURE_DONE, then the distance comes back. */
    tap(r, MR_VW_MEASURE);
    CHECK(count(r, MR_VA_MEASURE_DONE, NULL) == 1 && !mr_viewer_measuring(r->v));
    /* Judged against DIN 18202 (no table): the planned point is 5.14 m
     * from the origin, so +-16 mm; 12 +- 2*4 mm straddles it. */
    mr_verdict vd;
    mr_viewer_measure_distance(r->v, mr_v3(0.0, 1.2, 5.0), 0.012, 0.004, "Machine_2", "visible");
    CHECK(mr_viewer_measure_verdict(r->v, &vd) && vd.kind == MR_VERDICT_UNDECIDED);
    CHECK_MSG(strstr(state_str(r, "measure_message", msg, sizeof msg), "undecided") != NULL, "'%s'", msg);
    mr_viewer_measure_distance(r->v, mr_v3(0.0, 1.2, 5.0), 0.003, 0.004, "Machine_2", "visible");
    CHECK(mr_viewer_measure_verdict(r->v, &vd) && vd.kind == MR_VERDICT_WITHIN);
    mr_viewer_measure_distance(r->v, mr_v3(0.0, 1.2, 5.0), 0.3, 0.004, "Machine_2", "visible");
    CHECK(mr_viewer_measurement(r->v, &m) && m.has_distance && m.distance_m == 0.3);
    CHECK_MSG(strstr(state_str(r, "measure_message", msg, sizeof msg), "300.0 mm +/- 4.0 mm") != NULL, "'%s'", msg);
    CHECK(mr_viewer_measure_verdict(r->v, &vd) && vd.kind == MR_VERDICT_OUT);
    CHECK_NEAR(vd.tol.limit_m, 0.016, 1e-12);
    CHECK_NEAR(vd.lo_m, 0.292, 1e-9);
    CHECK_NEAR(vd.hi_m, 0.308, 1e-9);
    /* On screen, in words, with the interval and the tolerance; in the state. */
    step(r);
    CHECK_MSG(strstr(state_str(r, "verdict_banner", msg, sizeof msg), "OUT OF TOLERANCE Machine_2: 300 mm, 95 % 292..308 mm, "
                                                                     "limit +/-16 mm (DIN 18202 Table 1, 3-6 m)") != NULL,
              "banner '%s'", msg);
    st = mr_viewer_state_json(r->v);
    const cJSON *sv = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(st, "measure"), "verdict");
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(sv, "verdict")) &&
          strcmp(cJSON_GetObjectItemCaseSensitive(sv, "verdict")->valuestring, "out") == 0);
    CHECK(cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(st, "measure"), "taps_with_pose_covariance")
              ->valueint == 3);
    cJSON_Delete(st);
    /* The mark's fields, as the view appends them, read back. */
    mr_annotation a;
    memset(&a, 0, sizeof a);
    snprintf(a.type, sizeof a.type, "discrepancy");
    a.frame_index = 12;
    a.node_index = -1;
    a.world_from_camera = r->f.world_from_camera;
    a.has_measurement = true;
    a.measurement = m;
    a.has_verdict = true;
    a.verdict = vd;
    snprintf(a.category, sizeof a.category, "moved");
    mr_mark_title(&a, a.title, sizeof a.title);
    CHECK_MSG(strstr(a.title, "Moved: Machine_2, 0.30 m along ") == a.title && strstr(a.title, ", out of tolerance"),
              "title '%s'", a.title);
    cJSON *line = mr_annotation_to_json(&a);
    char *text = line_of(line);
    mr_annotations back;
    mr_error err = {0};
    CHECK(text && mr_annotations_parse(text, strlen(text), &back, &err) && back.count == 1 && back.bad_lines == 0);
    if (back.count == 1) {
        const mr_measurement *b = &back.items[0].measurement;
        CHECK(back.items[0].has_measurement && b->taps == 3 && b->frames[1] == 11 && b->has_distance);
        CHECK_NEAR(b->tri.point.x, m.tri.point.x, 1e-12);
        CHECK_NEAR(b->distance_m, 0.3, 1e-12);
        CHECK_NEAR(b->distance_sigma_m, 0.004, 1e-12);
        CHECK_NEAR(b->tri.cov[4], m.tri.cov[4], 1e-15);
        CHECK(strcmp(b->planned_node, "Machine_2") == 0);
        const mr_verdict *bv = &back.items[0].verdict;
        CHECK(back.items[0].has_verdict && bv->kind == MR_VERDICT_OUT && strcmp(bv->tol.source, vd.tol.source) == 0);
        CHECK_NEAR(bv->tol.limit_m, 0.016, 1e-12);
        CHECK_NEAR(bv->hi_m, vd.hi_m, 1e-12);
    }
    mr_annotations_free(&back);
    free(text);
    /* A damaged measurement makes the line garbage, not a half mark. */
    cJSON_ReplaceItemInObject(line, "measured_sigma_m", cJSON_CreateString("x"));
    text = line_of(line);
    CHECK(text && mr_annotations_parse(text, strlen(text), &back, &err) && back.count == 0 && back.bad_lines == 1);
    mr_annotations_free(&back);
    free(text);
    /* So does a damaged verdict. */
    cJSON_ReplaceItemInObject(line, "measured_sigma_m", cJSON_CreateNumber(0.004));
    cJSON_ReplaceItemInObject(cJSON_GetObjectItem(line, "verdict"), "verdict", cJSON_CreateString("fine"));
    text = line_of(line);
    CHECK(text && mr_annotations_parse(text, strlen(text), &back, &err) && back.count == 0 && back.bad_lines == 1);
    mr_annotations_free(&back);
    free(text);
    cJSON_Delete(line);
    /* Esc cancels; d starts and, unsolved, cancels; a tap off the picture is not taken. */
    key(r, 'd');
    CHECK(mr_viewer_measuring(r->v));
    tap_at(r, 50, 400, &acts); /* left of the picture (it starts at x = 100) */
    CHECK(mr_viewer_measurement(r->v, &m) && m.taps == 0);
    key(r, MR_KEY_ESCAPE);
    CHECK(!mr_viewer_measuring(r->v) && !mr_viewer_measurement(r->v, &m));
    CHECK(count(r, MR_VA_QUIT, NULL) == 0);
    key(r, 'd');
    key(r, 'd');
    CHECK(!mr_viewer_measuring(r->v) && count(r, MR_VA_MEASURE_DONE, NULL) == 0);
    r->f.camera = NULL;
    r->f.pose_cov = NULL;
    r->f.corner_sigma_px = 0;
    r->f.world_from_camera = mr_m4_identity();
}

/* ------------------------------------------------------------ layout */

/* The right column in priority order (Measure, issue 15, after Mark). */
static const mr_view_widget_id k_column[] = {MR_VW_FREEZE, MR_VW_SNAPSHOT, MR_VW_MARK, MR_VW_MEASURE, MR_VW_VIDEO,
                                             MR_VW_HIDDEN, MR_VW_AO, MR_VW_GHOST, MR_VW_SHADOWS, MR_VW_QUIT,
                                             MR_VW_HELP};
#define K_COLUMN_N ((int)(sizeof k_column / sizeof k_column[0]))

/* Clearance between two rects in pixels (negative: they overlap). */
static float gap(mr_ui_rect a, mr_ui_rect b) {
    return fmaxf(fmaxf(b.x - (a.x + a.w), a.x - (b.x + b.w)), fmaxf(b.y - (a.y + a.h), a.y - (b.y + b.h)));
}

/* Every shown widget: >= 9 mm on both sides at the screen's own density,
 * inside the window, and at least 1 mm clear of every other (the layout
 * keeps 1.2 mm), so a finger between two targets hits neither by mistake.
 * Returns how many are shown. */
static int check_layout(const mr_view_layout *L, double ppmm, float w, float h, const char *what) {
    int n = 0;
    float smallest = INFINITY;
    for (int i = 0; i < MR_VW_COUNT; i++) {
        if (!L->shown[i]) continue;
        n++;
        mr_ui_rect r = L->rect[i];
        double wmm = r.w / ppmm, hmm = r.h / ppmm;
        smallest = fminf(smallest, (float)fmin(wmm, hmm));
        CHECK_MSG(wmm >= 9.0 - 1e-3 && hmm >= 9.0 - 1e-3, "%s: widget %s is %.2f x %.2f mm, want >= 9 mm", what,
                  mr_view_widget_name((mr_view_widget_id)i), wmm, hmm);
        CHECK_MSG(r.x >= 0 && r.y >= 0 && r.x + r.w <= w + 1e-3f && r.y + r.h <= h + 1e-3f,
                  "%s: widget %s at (%.1f, %.1f) %.1f x %.1f leaves the %gx%g window", what,
                  mr_view_widget_name((mr_view_widget_id)i), r.x, r.y, r.w, r.h, w, h);
        for (int j = 0; j < i; j++)
            CHECK_MSG(!L->shown[j] || gap(r, L->rect[j]) >= ppmm * 1.0 - 1e-3, "%s: widgets %s and %s %s (%.2f mm "
                      "apart, want >= 1 mm)", what, mr_view_widget_name((mr_view_widget_id)i),
                      mr_view_widget_name((mr_view_widget_id)j), gap(r, L->rect[j]) < 0 ? "overlap" : "touch",
                      gap(r, L->rect[j]) / ppmm);
    }
    if (n) CHECK_MSG(smallest <= 9.6f, "%s: the smallest target is %.2f mm, want 9 (sizes scaled wrongly)", what, smallest);
    return n;
}

/* A ui at a density, for the layout alone (the font's bake size does not
 * matter to it). */
static mr_ui *make_ui(const char *font_path, float font_px, double ppmm, mr_ui_font **font) {
    mr_ui_font_params fp = MR_UI_FONT_DEFAULTS;
    fp.path = font_path;
    fp.pixel_height = font_px;
    mr_error err = {0};
    *font = mr_ui_font_create(&fp, &err);
    mr_ui_params up = MR_UI_DEFAULTS;
    up.font = *font;
    up.px_per_mm = ppmm;
    mr_ui *ui = *font ? mr_ui_create(&up, &err) : NULL;
    CHECK_MSG(ui != NULL, "%s", err.msg);
    return ui;
}

static void test_layout(const char *font_path) {
    static const struct {
        const char *what;
        double dpi;
        float w, h;
        bool all;       /* everything fits */
    } cases[] = {
        {"96 dpi 1280x720", 96, 1280, 720, true},
        {"160 dpi tablet 1280x800", 160, 1280, 800, true},
        {"2x scale 2560x1440", 192, 2560, 1440, true},
        {"96 dpi 480x360 (the CLI test's window)", 96, 480, 360, true},
        {"267 dpi phone 1080x1920", 267, 1080, 1920, true},
        {"96 dpi 480x150, short", 96, 480, 150, false},
        {"96 dpi 160x120, tiny", 96, 160, 120, false},
        {"160 dpi 200x150, tiny", 160, 200, 150, false},
        {"96 dpi 40x30, smaller than a target", 96, 40, 30, false},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double ppmm = cases[c].dpi / 25.4;
        mr_ui_font *font = NULL;
        mr_ui *ui = make_ui(font_path, 20, ppmm, &font);
        for (int mode = 0; ui && mode < 4; mode++) {
            bool seek = mode & 1, notes = mode & 2;
            char what[200];
            snprintf(what, sizeof what, "%s%s%s", cases[c].what, seek ? ", replay" : "", notes ? ", note chooser" : "");
            mr_view_layout_params lp = {cases[c].w, cases[c].h, seek, notes, cases[c].w * 0.25f, false, false, false};
            mr_view_layout L;
            mr_view_layout_compute(ui, &lp, &L);
            int n = check_layout(&L, ppmm, cases[c].w, cases[c].h, what);
            int want = 12 + (seek ? 5 : 0) + (notes ? 8 : 0);
            if (cases[c].all) {
                CHECK_MSG(n == want && L.dropped == 0, "%s: %d widgets shown (%d dropped), want all %d", what, n,
                          L.dropped, want);
            } else {
                CHECK_MSG(n + L.dropped == want && (L.dropped > 0 || !seek), "%s: %d shown + %d dropped, want %d "
                          "in all and some dropped", what, n, L.dropped, want);
                /* Lower priorities go first: the column is a prefix of
                 * freeze, snapshot, mark, measure, video, hidden, ao, ghost, help. */
                for (int i = 1; i < K_COLUMN_N; i++)
                    CHECK_MSG(!L.shown[k_column[i]] || L.shown[k_column[i - 1]], "%s: %s shown but %s (higher "
                              "priority) left out", what, mr_view_widget_name(k_column[i]),
                              mr_view_widget_name(k_column[i - 1]));
                CHECK_MSG(!L.shown[MR_VW_RATE] || L.shown[MR_VW_SEEK], "%s: the rate button kept, the seek bar left out",
                          what);
            }
            if (notes && cases[c].all && L.picture.w >= 2 * L.notes.w) {
                /* The chooser sits over the picture, away from the mark. */
                CHECK_MSG(L.notes.x > lp.mark_x, "%s: the chooser covers the mark", what);
                lp.mark_x = cases[c].w * 0.6f;
                mr_view_layout_compute(ui, &lp, &L);
                CHECK_MSG(L.notes.x + L.notes.w < lp.mark_x, "%s: the chooser covers a mark on the right", what);
            } else if (notes && cases[c].all) {
                CHECK_MSG(fabsf(L.notes.x + L.notes.w / 2 - (L.picture.x + L.picture.w / 2)) < 1,
                          "%s: a chooser with no room beside the mark is not centred", what);
            }
        }
        /* The transparency slider, the main control, survives in tiny windows. */
        mr_view_layout_params lp = {160 * (float)ppmm / 3.78f, 120 * (float)ppmm / 3.78f, true, false, 0, false, false, false};
        mr_view_layout L;
        if (ui) {
            mr_view_layout_compute(ui, &lp, &L);
            CHECK_MSG(L.shown[MR_VW_ALPHA] && L.shown[MR_VW_PLAY] && !L.shown[MR_VW_HELP],
                      "%s: a 42x32 mm window shows alpha %d, play %d, help %d (want the slider and play, no help)",
                      cases[c].what, L.shown[MR_VW_ALPHA], L.shown[MR_VW_PLAY], L.shown[MR_VW_HELP]);
        }
        mr_ui_destroy(&ui);
        mr_ui_font_destroy(&font);
    }
}

/* Every window size from tiny to large, in small steps: the rules hold
 * everywhere (not only at the sizes above), and widgets come back in
 * priority order as the window grows. */
static void test_layout_sweep(const char *font_path) {
    double ppmm = 96 / 25.4;
    mr_ui_font *font = NULL;
    mr_ui *ui = make_ui(font_path, 12, ppmm, &font);
    for (float w = 20; ui && w <= 900; w += 7)
        for (float h = 20; h <= 700; h += 23) {
            char what[64];
            snprintf(what, sizeof what, "replay window %gx%g at 96 dpi", w, h);
            mr_view_layout_params lp = {w, h, true, false, 0, false, false, false};
            mr_view_layout L;
            mr_view_layout_compute(ui, &lp, &L);
            int n = check_layout(&L, ppmm, w, h, what);
            CHECK_MSG(n + L.dropped == 17, "%s: %d shown + %d dropped, want 17", what, n, L.dropped);
            for (int i = 1; i < K_COLUMN_N; i++)
                CHECK_MSG(!L.shown[k_column[i]] || L.shown[k_column[i - 1]], "%s: %s shown but %s left out", what,
                          mr_view_widget_name(k_column[i]), mr_view_widget_name(k_column[i - 1]));
            CHECK_MSG(!L.shown[MR_VW_RATE] || L.shown[MR_VW_SEEK], "%s: the rate button kept, the seek bar left out",
                      what);
            CHECK_MSG(!L.shown[MR_VW_PLAY] || L.shown[MR_VW_ALPHA], "%s: replay buttons without the slider", what);
            if (mr_test_failures > 20) goto out;
        }
out:
    mr_ui_destroy(&ui);
    mr_ui_font_destroy(&font);
}

/* ------------------------------------------------------------ scripts */

static void test_script(void) {
    char sp[1200], st[1200];
    tmp_path(sp, sizeof sp, "s.script");
    tmp_path(st, sizeof st, "s_state.json");
    char text[2600];
    snprintf(text, sizeof text,
             "# comment\n0.1 tap @video\n\n0.2 key f\n0.3 state %s\n0.35 drag @alpha 0.5 0.0\n0.4 resize 300 200\n"
             "0.5 quit\n", st);
    write_text(sp, text);
    mr_error err = {0};
    mr_view_script *s = mr_view_script_load(sp, &err);
    CHECK_MSG(s != NULL, "script: %s", err.msg);
    rig r;
    if (!s || !rig_open(&r, NULL, 96 / 25.4, &err)) {
        mr_view_script_destroy(&s);
        return;
    }
    mr_viewer_set_script(r.v, &s);
    CHECK(s == NULL);
    bool video = mr_viewer_settings(r.v)->show_video, froze = false, state = false, quit = false, resize = false;
    double t_state = -1, t_quit = -1;
    for (int i = 0; i < 200 && !quit; i++) {
        step(&r);
        if (count(&r, MR_VA_FREEZE, NULL)) froze = true;
        mr_view_action x;
        if (count(&r, MR_VA_STATE, &x)) {
            state = x.path && strcmp(x.path, st) == 0;
            t_state = r.t;
        }
        if (count(&r, MR_VA_RESIZE, &x)) resize = x.x == 300 && x.y == 200;
        if (count(&r, MR_VA_QUIT, NULL)) {
            quit = true;
            t_quit = r.t;
        }
    }
    CHECK_MSG(mr_viewer_settings(r.v)->show_video == !video, "script tap @video did not toggle the video");
    CHECK_MSG(froze && state && resize && quit, "script: freeze %d state %d resize %d quit %d", froze, state, resize,
              quit);
    CHECK_MSG(mr_viewer_settings(r.v)->alpha == 0.0f, "script drag @alpha to 0 gave %g", mr_viewer_settings(r.v)->alpha);
    CHECK_MSG(t_state >= 0.3 && t_quit >= 0.5 && t_quit > t_state, "script commands ran early or out of order "
              "(state at %.3f s, quit at %.3f s)", t_state, t_quit);
    mr_viewer_destroy(&r.v);
    /* `frame N`: what follows waits until frame N is shown, however late
     * (a loaded machine plays slowly); a frame already past goes on at once. */
    write_text(sp, "0.1 frame 7\n0.2 quit\n");
    s = mr_view_script_load(sp, &err);
    CHECK_MSG(s != NULL, "script with frame: %s", err.msg);
    if (s && rig_open(&r, NULL, 96 / 25.4, &err)) {
        mr_viewer_set_script(r.v, &s);
        double t_q = -1;
        for (int i = 0; i < 2000 && t_q < 0; i++) {
            if (i == 600) r.f.index = 6;  /* 10 s in: still short of 7 */
            if (i == 1200) r.f.index = 9; /* 20 s in: past 7 */
            step(&r);
            if (count(&r, MR_VA_QUIT, NULL)) t_q = r.t;
        }
        CHECK_MSG(t_q > 20, "script `frame 7` did not wait for frame 7 (quit at %.2f s)", t_q);
        CHECK_MSG(t_q > 0 && t_q < 21, "script `frame 7` went on late or never (quit at %.2f s)", t_q);
        mr_viewer_destroy(&r.v);
    }
    mr_view_script_destroy(&s);
    /* `seek N`: asks for frame N and waits until N itself is shown, also
     * backwards (a later frame on screen does not count). */
    write_text(sp, "0.1 seek 3\n0.2 quit\n");
    s = mr_view_script_load(sp, &err);
    CHECK_MSG(s != NULL, "script with seek: %s", err.msg);
    if (s && rig_open(&r, NULL, 96 / 25.4, &err)) {
        mr_viewer_set_script(r.v, &s);
        r.f.index = 9;
        double t_q = -1;
        bool asked = false;
        for (int i = 0; i < 2000 && t_q < 0; i++) {
            if (i == 600) r.f.index = 3; /* 10 s in: the seek lands */
            step(&r);
            mr_view_action x;
            if (count(&r, MR_VA_SEEK, &x)) asked = x.i == 3;
            if (count(&r, MR_VA_QUIT, NULL)) t_q = r.t;
        }
        CHECK_MSG(asked && t_q > 10 && t_q < 11, "script `seek 3`: asked %d, went on at %.2f s (want just after 10 s)",
                  asked, t_q);
        mr_viewer_destroy(&r.v);
    }
    mr_view_script_destroy(&s);
    write_text(sp, "0.1 frame\n");
    memset(&err, 0, sizeof err);
    s = mr_view_script_load(sp, &err);
    CHECK_MSG(s == NULL && err.code == MR_ERR_PARSE, "`frame` without N was taken");
    mr_view_script_destroy(&s);
    /* A bad line names the file and line. */
    write_text(sp, "0.1 tap @video\n0.2 fly 1 2\n");
    memset(&err, 0, sizeof err);
    s = mr_view_script_load(sp, &err);
    CHECK_MSG(s == NULL && err.code == MR_ERR_PARSE && strstr(err.msg, ":2:"), "bad script line: %s", err.msg);
    mr_view_script_destroy(&s);
    int k = 0;
    CHECK(mr_view_key_parse("esc", &k) && k == MR_KEY_ESCAPE);
    CHECK(mr_view_key_parse("space", &k) && k == ' ');
    CHECK(!mr_view_key_parse("nokey", &k));
}

/* The frame's shadow method (mark.c): the scene config's over the saved
 * setting, --shadows over both, the C key over all once it changed the
 * setting; an unknown scene name is off. And a tap's picture pixel. */
static void test_shadow_choice_and_taps(void) {
    mr_view_shadow_choice c = {.start = MR_SHADOW_OFF};
    CHECK(mr_view_shadow_choose(&c, MR_SHADOW_OFF, NULL) == MR_SHADOW_OFF);
    CHECK(mr_view_shadow_choose(&c, MR_SHADOW_OFF, "pcss") == MR_SHADOW_PCSS);
    CHECK(mr_view_shadow_choose(&c, MR_SHADOW_OFF, "soft") == MR_SHADOW_OFF);
    c.given = true;
    c.flag = MR_SHADOW_HARD;
    CHECK(mr_view_shadow_choose(&c, MR_SHADOW_OFF, "pcss") == MR_SHADOW_HARD);
    CHECK(!c.keyed);
    CHECK(mr_view_shadow_choose(&c, MR_SHADOW_PCF, "pcss") == MR_SHADOW_PCF && c.keyed);
    /* keyed stays: back to the start value is still the key's choice */
    CHECK(mr_view_shadow_choose(&c, MR_SHADOW_OFF, "pcss") == MR_SHADOW_OFF);
    double u = 0, v = 0, px = 0, py = 0;
    mr_ui_rect r = mr_ui_rect_make(100, 50, 320, 240);
    CHECK(!mr_view_window_to_image(r, 160, 120, 99, 60, &u, &v));
    CHECK(mr_view_window_to_image(r, 160, 120, 260, 170, &u, &v));
    CHECK_NEAR(u, 79.5, 1e-12);
    CHECK_NEAR(v, 59.5, 1e-12);
    mr_camera cam = {640, 480, 500, 500, 319.5, 239.5, {0}};
    mr_view_image_to_camera(&cam, 160, 120, u, v, &px, &py);
    CHECK_NEAR(px, 319.5, 1e-12);
    CHECK_NEAR(py, 239.5, 1e-12);
    /* A finished measurement's mark: at the measured point's pixel (the
     * centre when it is behind the camera), its point the planned one. */
    mr_dmat4 pose = mr_m4_identity();
    mr_view_planned planned = {true, mr_v3(0.1, 0, 2), 3, MR_LAYER_HIDDEN};
    mr_view_mark_at at;
    mr_view_measure_mark(&cam, 640, 480, &pose, mr_v3(0.2, -0.1, 2), &planned, &at);
    CHECK_NEAR(at.px, 319.5 + 500 * 0.1, 1e-9);
    CHECK_NEAR(at.py, 239.5 - 500 * 0.05, 1e-9);
    CHECK_NEAR(at.note_u, (at.px + 0.5) / 640, 1e-6);
    CHECK(at.pick.hit && at.pick.node == 3 && at.pick.layer == MR_LAYER_HIDDEN);
    CHECK_NEAR(at.pick.depth, 2, 1e-12);
    planned.found = false;
    mr_view_measure_mark(&cam, 640, 480, &pose, mr_v3(0, 0, -1), &planned, &at);
    CHECK(!at.pick.hit && at.pick.node == -1 && at.px == 319.5 && at.py == 239.5);
}

/* A mark's annotation line and a frame's render setup (lib/view/mark.c,
 * out of app/cmd_view.c): the picked node's name and layer, the pixel,
 * the measurement only on a Measure mark; no pose: the neutral view, and
 * temporal AO reset after a render without one. */
static void test_mark_line_and_setup(void) {
    mr_scene *s = mr_scene_create();
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "Pipe_1");
    n.parent = -1;
    n.mesh_first = -1;
    n.layer = MR_LAYER_HIDDEN;
    n.world = mr_m4_identity();
    CHECK(mr_scene_add_node(s, &n) == 0);
    mr_capture_frame f;
    memset(&f, 0, sizeof f);
    f.have_pose = f.pose_valid = true;
    f.pose = mr_m4_identity();
    f.index = 7;
    f.image.width = 64;
    f.image.height = 48;
    mr_pick pick = {true, mr_v3(1, 2, 3), 3, 0, MR_LAYER_HIDDEN};
    mr_view_mark_words words = {"m1", 0, "pipe 2 @ann #hvac !high"};
    cJSON *line = mr_view_mark_line(&f, &words, 10.5, 20.25, &pick, s, NULL, NULL);
    CHECK(line != NULL);
    if (line) {
        const cJSON *node = cJSON_GetObjectItem(line, "node"), *layer = cJSON_GetObjectItem(line, "layer");
        const cJSON *px = cJSON_GetObjectItem(line, "pixel");
        CHECK(cJSON_IsString(node) && strcmp(node->valuestring, "Pipe_1") == 0);
        CHECK(cJSON_IsString(layer) && strcmp(layer->valuestring, "hidden") == 0);
        CHECK(cJSON_GetArraySize(px) == 2 && cJSON_GetArrayItem(px, 1)->valuedouble == 20.25);
        CHECK(!cJSON_GetObjectItem(line, "measured_point"));
        /* What the planner said: the category, the note without its inline
         * fields, the fields, a title in words. */
        const cJSON *cat = cJSON_GetObjectItem(line, "category"), *note = cJSON_GetObjectItem(line, "note"),
                    *title = cJSON_GetObjectItem(line, "title"), *lab = cJSON_GetObjectItem(line, "labels");
        CHECK(cJSON_IsString(cat) && strcmp(cat->valuestring, "missing") == 0);
        CHECK(cJSON_IsString(note) && strcmp(note->valuestring, "pipe 2") == 0);
        CHECK(cJSON_IsString(title) && strcmp(title->valuestring, "Missing: Pipe_1") == 0);
        CHECK(cJSON_GetArraySize(lab) == 1 && strcmp(cJSON_GetArrayItem(lab, 0)->valuestring, "hvac") == 0);
        CHECK(!strcmp(cJSON_GetObjectItem(line, "assignee")->valuestring, "ann") &&
              !strcmp(cJSON_GetObjectItem(line, "priority")->valuestring, "high") &&
              !strcmp(cJSON_GetObjectItem(line, "id")->valuestring, "m1"));
        cJSON_Delete(line);
    }
    mr_measurement m;
    memset(&m, 0, sizeof m);
    m.tri.point = mr_v3(1, 2, 3);
    m.has_distance = true;
    m.distance_m = 0.3;
    mr_view_mark_words moved = {"m2", 2, NULL};
    mr_verdict vd;
    mr_tolerance tol = {0.02, 5, "test"};
    mr_error verr = {0};
    CHECK(mr_verdict_judge(0.3, 0.01, &tol, &vd, &verr));
    line = mr_view_mark_line(&f, &moved, 1, 2, &pick, s, &m, &vd);
    CHECK(line && cJSON_GetObjectItem(line, "measured_point"));
    const cJSON *lv = line ? cJSON_GetObjectItem(line, "verdict") : NULL;
    CHECK(lv && strcmp(cJSON_GetObjectItem(lv, "verdict")->valuestring, "out") == 0);
    CHECK(line && strstr(cJSON_GetObjectItem(line, "title")->valuestring, "out of tolerance"));
    cJSON_Delete(line);
    /* A plain mark carries no verdict, even if one is given. */
    line = mr_view_mark_line(&f, &moved, 1, 2, &pick, s, NULL, &vd);
    CHECK(line && !cJSON_GetObjectItem(line, "verdict"));
    cJSON_Delete(line);
    mr_view_settings vs = MR_VIEW_SETTINGS_DEFAULTS;
    mr_camera cam = mr_demo_camera();
    mr_view view;
    mr_frame_params fp;
    mr_view_render_choice c;
    f.have_pose = f.pose_valid = false;
    mr_view_render_setup(&vs, &cam, &f, false, MR_SHADOW_OFF, true, false, 32, 24, &view, &fp, &c);
    CHECK(fp.width == 32 && fp.height == 24 && fp.video == &f.image && fp.ao.temporal && fp.ao.temporal_reset);
    CHECK(!c.use_pose && fp.alpha == c.alpha && view.camera.width == 64);
    mr_dmat4 neutral = mr_m4_look_at_cv(mr_v3(0, 0, 0), mr_v3(0, 0, 1), mr_v3(0, -1, 0));
    CHECK(memcmp(&view.world_from_camera, &neutral, sizeof neutral) == 0);
    f.have_pose = f.pose_valid = true;
    f.pose.m[3] = 5;
    mr_view_render_setup(&vs, &cam, &f, false, MR_SHADOW_OFF, true, true, 32, 24, &view, &fp, &c);
    CHECK(c.use_pose && !fp.ao.temporal_reset && view.world_from_camera.m[3] == 5);
    mr_scene_destroy(&s);
}

/* The view's source (lib/view/run.c, out of app/cmd_view.c): live input
 * needs a camera and a marker map, or a view file that gives both a camera
 * and a fixed pose; a recording's failure names its folder; a failure
 * leaves nothing to free. */
static void test_source_load(void) {
    const char *src = getenv("MR_SOURCE_DIR");
    if (!src) {
        printf("test_view: MR_SOURCE_DIR not set, source tests left out\n");
        return;
    }
    char cam[1024], markers[1024], view[1024];
    snprintf(cam, sizeof cam, "%s/configs/cameras/demo_640x480.json", src);
    snprintf(markers, sizeof markers, "%s/configs/markers/demo_hall.json", src);
    snprintf(view, sizeof view, "%s/configs/views/demo_machine.json", src);
    mr_view_source s;
    mr_error err = {0};
    mr_view_source_params p = MR_VIEW_SOURCE_DEFAULTS;
    CHECK(!mr_view_source_load(&p, &s, &err) && err.code == MR_ERR_INVALID); /* neither input nor replay */
    p.input = "/dev/video9";
    memset(&err, 0, sizeof err);
    CHECK(!mr_view_source_load(&p, &s, &err) && strstr(err.msg, "--input needs --camera"));
    p.camera_path = cam;
    memset(&err, 0, sizeof err);
    CHECK(!mr_view_source_load(&p, &s, &err) && strstr(err.msg, "--input needs --markers") && !s.have_markers);
    p.markers_path = markers;
    CHECK_MSG(mr_view_source_load(&p, &s, &err), "%s", err.msg);
    CHECK(s.have_markers && s.markers.count > 0 && !s.have_fixed_pose && s.camera.width == 640);
    CHECK(!strcmp(s.desc, "live /dev/video9") && s.input == p.input && !s.replay_dir);
    mr_view_source_free(&s);
    CHECK(s.markers.count == 0);
    /* A still with a fixed pose: the image must be there now (only a
     * /dev/video device may come later). */
    char still[1200];
    snprintf(still, sizeof still, "%s/tests/data/golden/ao_gtao_view.png", src);
    mr_view_source_params pv = {.input = still, .view_path = view};
    CHECK_MSG(mr_view_source_load(&pv, &s, &err), "%s", err.msg);
    CHECK(s.have_fixed_pose && !s.have_markers && s.camera.width > 0);
    mr_view_source_free(&s);
    pv.input = "no-such-frame.png";
    memset(&err, 0, sizeof err);
    CHECK_MSG(!mr_view_source_load(&pv, &s, &err) && strstr(err.msg, "no-such-frame.png"),
              "a missing still was taken (or not named): %s", err.msg);
    mr_view_source_params pr = {.replay_dir = "/nonexistent-recording"};
    memset(&err, 0, sizeof err);
    CHECK_MSG(!mr_view_source_load(&pr, &s, &err) && strstr(err.msg, "/nonexistent-recording"), "%s", err.msg);
    /* An empty folder is no recording: refused at once. */
    char empty[1200];
    tmp_path(empty, sizeof empty, "empty_recording");
    CHECK(mr_mkdirs(empty, &err));
    mr_view_source_params pe = {.replay_dir = empty};
    memset(&err, 0, sizeof err);
    CHECK_MSG(!mr_view_source_load(&pe, &s, &err) && strstr(err.msg, "empty_recording"), "an empty recording folder: %s",
              err.msg);
    mr_view_source_free(NULL);
}

int main(void) {
    const char *t = getenv("MR_TEST_TMP");
    snprintf(g_tmp, sizeof g_tmp, "%s/test_view", t && t[0] ? t : "/tmp");
    mr_error err = {0};
    CHECK_MSG(mr_mkdirs(g_tmp, &err), "%s", err.msg);
    test_tracking_lost();
    test_settings();
    test_shadow_choice_and_taps();
    test_mark_line_and_setup();
    test_source_load();
    char font[1024];
    if (!mr_ui_font_find(font, sizeof font, &err)) {
        printf("test_view: SKIPPED the controller tests (no font): %s\n", err.msg);
        return mr_test_failures ? mr_test_finish("test_view") : MR_TEST_SKIP;
    }
    rig r;
    CHECK_MSG(rig_open(&r, NULL, 96 / 25.4, &err), "%s", err.msg);
    if (r.v) {
        test_slider(&r);
        test_toggles(&r);
        test_keys(&r);
        test_cycling(&r);
        test_tap_queue(&r);
        test_replay(&r);
        test_sigma(&r);
        test_measure(&r);
        mr_viewer_destroy(&r.v);
    }
    test_layout(font);
    test_layout_sweep(font);
    test_script();
    return mr_test_finish("test_view");
}
