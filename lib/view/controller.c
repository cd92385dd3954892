/* The view controller: modes, key map, input queue, layout and the UI of
 * `mrcheck view`, with no window behind it. */
#include "view_internal.h"
#include "mr_track.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

const mr_view_key_help mr_view_keymap[] = {
    {"Up / +", "more video (slider right)"},
    {"Down / -", "more model (slider left)"},
    {"f", "freeze / unfreeze the frame and pose"},
    {"s", "snapshot (screen, raw frame, pose)"},
    {"m", "mark mode: tap the scene, then type a note and pick what differs"},
    {"Enter", "in mark mode: mark the image centre"},
    {"1..6", "what differs (while not typing a note)"},
    {"tap a pin", "edit or close that mark"},
    {"d", "measure: tap one feature in 2+ frames, d again to finish"},
    {"v", "video on/off"},
    {"h", "hidden layer on/off"},
    {"a", "ambient occlusion on/off (method: in the settings below)"},
    {"g", "ghosting on/off"},
    {"c", "shadows on/off"},
    {"space", "replay: play / pause"},
    {". / Right", "replay: step forward"},
    {", / Left", "replay: step back"},
    {"Home / End", "replay: first / last frame"},
    {"[ / ]", "replay: slower / faster"},
    {"F11", "fullscreen"},
    {"? / F1", "this help and the settings"},
    {"Esc", "cancel what is going on (never quits)"},
    {"q", "quit (asks first; Enter or y confirms)"},
};
const int mr_view_keymap_count = (int)(sizeof mr_view_keymap / sizeof mr_view_keymap[0]);

static const char *const k_widget_names[MR_VW_COUNT] = {
    "alpha", "play", "back", "forward", "rate", "seek", "freeze", "snapshot", "mark", "video", "hidden", "ao",
    "ghost", "help", "note1", "note2", "note3", "note4", "note5", "note6", "cancel",
    "measure",
    "shadows", "quit", "quit_yes", "quit_no", "note_text", "close_mark", "set_ao", "set_ghost", "set_shadows",
    "reset",
};
_Static_assert(sizeof k_widget_names / sizeof k_widget_names[0] == MR_VW_COUNT, "a name for every widget");

const char *mr_view_widget_name(mr_view_widget_id id) {
    return (int)id >= 0 && id < MR_VW_COUNT ? k_widget_names[id] : "";
}

/* ---------------------------------------------------------------- layout */

/* The column's widgets in priority order (what a small window leaves out
 * last comes first); Quit stays last but is never dropped before help. */
static const mr_view_widget_id k_column[] = {MR_VW_FREEZE, MR_VW_SNAPSHOT, MR_VW_MARK, MR_VW_MEASURE,
                                              MR_VW_VIDEO, MR_VW_HIDDEN, MR_VW_AO, MR_VW_GHOST,
                                              MR_VW_SHADOWS, MR_VW_QUIT, MR_VW_HELP};
#define COLUMN_N ((int)(sizeof k_column / sizeof k_column[0]))
static mr_view_widget_id column_widget(int i) { return k_column[i]; }

/* Shows a widget only when it keeps its full touch target inside the
 * window; a smaller one would be a target nobody can hit. */
static void place(mr_view_layout *L, mr_view_widget_id id, mr_ui_rect r, float T, const mr_view_layout_params *p) {
    const float eps = 1e-3f;
    if (r.w + eps < T || r.h + eps < T || r.x < -eps || r.y < -eps || r.x + r.w > p->fb_w + eps ||
        r.y + r.h > p->fb_h + eps) {
        L->dropped++;
        return;
    }
    L->shown[id] = true;
    L->rect[id] = r;
}

void mr_view_layout_compute(const mr_ui *ui, const mr_view_layout_params *p, mr_view_layout *L) {
    memset(L, 0, sizeof *L);
    float T = mr_ui_target_px(ui), g = mr_ui_mm(ui, 1.2f), th = mr_ui_text_px(ui);
    const mr_ui_font *font = mr_ui_get_font(ui);
    mr_ui_rect full = mr_ui_rect_make(0, 0, p->fb_w, p->fb_h);

    L->status = mr_ui_cut_top(&full, th * 1.7f);
    /* Bottom: the transparency slider, and the replay row. */
    L->bottom = mr_ui_cut_bottom(&full, (T + g) * (p->seekable ? 2 : 1) + g);
    mr_ui_rect inner = mr_ui_rect_inset(L->bottom, g);
    place(L, MR_VW_ALPHA, mr_ui_cut_top(&inner, T), T, p);
    if (p->seekable) {
        mr_ui_cut_top(&inner, g);
        mr_ui_rect rrow = mr_ui_cut_top(&inner, T);
        float bw = fmaxf(T * 1.6f, mr_ui_text_width(font, "Pause", th) + 2 * g);
        place(L, MR_VW_PLAY, mr_ui_cut_left(&rrow, bw), T, p);
        mr_ui_cut_left(&rrow, g);
        place(L, MR_VW_BACK, mr_ui_cut_left(&rrow, T), T, p);
        mr_ui_cut_left(&rrow, g);
        place(L, MR_VW_FORWARD, mr_ui_cut_left(&rrow, T), T, p);
        mr_ui_cut_left(&rrow, g);
        /* A seek bar under two targets wide cannot be aimed; the rate
         * button goes first, then the seek bar. */
        if (rrow.w >= T * 1.4f + g + 2 * T) {
            place(L, MR_VW_RATE, mr_ui_cut_right(&rrow, T * 1.4f), T, p);
            mr_ui_cut_right(&rrow, g);
        } else {
            L->dropped++;
        }
        if (rrow.w >= 2 * T) place(L, MR_VW_SEEK, rrow, T, p);
        else L->dropped++;
    }

    /* Right column: toggles and actions in priority order, wrapping into
     * more columns when the window is short; what fits in neither is left
     * out from the end (help first). */
    float colw = fmaxf(T * 2.4f, mr_ui_text_width(font, "AO alchemy", th) + 3 * g);
    const int n = COLUMN_N;
    int per_col = (int)((full.h - g) / (T + g));
    int max_cols = (int)((full.w - g) / (colw + g));
    if (per_col < 0) per_col = 0;
    if (max_cols < 0) max_cols = 0;
    int cols = per_col ? (n + per_col - 1) / per_col : 0;
    if (cols > max_cols) cols = max_cols;
    int shown = cols * per_col < n ? cols * per_col : n;
    if (shown > 0) {
        L->column = mr_ui_cut_right(&full, cols * (colw + g) + g);
        L->column.h = fminf(L->column.h, (float)((shown < per_col ? shown : per_col) * (T + g) + g));
    }
    for (int i = 0; i < n; i++) {
        if (i >= shown) {
            L->dropped++;
            continue;
        }
        int c = i / per_col, r = i % per_col;
        mr_ui_rect b = mr_ui_rect_make(L->column.x + L->column.w - (c + 1) * (colw + g), L->column.y + g + r * (T + g),
                                       colw, T);
        place(L, column_widget(i), b, T, p);
    }

    /* The note chooser, over the picture on the side away from the mark
     * so the cross stays visible. Too little room: the keys 1..6 remain. */
    if (p->note_open) {
        float w = fminf(full.w - 2 * g, 2 * colw + 3 * g), h = (T + g) * ((MR_VIEW_NOTE_COUNT + 1) / 2 + 3) + g;
        float px = p->mark_x < full.x + full.w * 0.5f ? full.x + full.w - w - g : full.x + g;
        if (full.w < 2 * w) px = full.x + (full.w - w) / 2;
        L->notes = mr_ui_rect_make(px, full.y + (full.h - h) / 2, w, h);
        mr_ui_rect in = mr_ui_rect_inset(L->notes, g);
        mr_ui_cut_top(&in, T); /* the question */
        float bw = (in.w - g) / 2;
        bool fits = h <= full.h && w > 0 && bw + 1e-3f >= T;
        /* The note's text field, then the categories, then Cancel (and
         * Close when editing a saved mark). */
        if (fits) place(L, MR_VW_NOTE_TEXT, mr_ui_rect_make(in.x, in.y, in.w, T), T, p);
        else L->dropped++;
        in.y += T + g;
        for (int i = 0; i <= MR_VIEW_NOTE_COUNT; i++) {
            float cy = in.y + ((MR_VIEW_NOTE_COUNT + 1) / 2) * (T + g);
            mr_ui_rect b = i < MR_VIEW_NOTE_COUNT
                               ? mr_ui_rect_make(in.x + (i % 2) * (bw + g), in.y + (i / 2) * (T + g), bw, T)
                           : p->editing ? mr_ui_rect_make(in.x, cy, bw, T)
                                        : mr_ui_rect_make(in.x, cy, in.w, T);
            if (fits) place(L, (mr_view_widget_id)(MR_VW_NOTE1 + i), b, T, p);
            else L->dropped++;
        }
        if (fits && p->editing)
            place(L, MR_VW_CLOSE_MARK,
                  mr_ui_rect_make(in.x + bw + g, in.y + ((MR_VIEW_NOTE_COUNT + 1) / 2) * (T + g), bw, T), T, p);
        if (!fits) L->notes = mr_ui_rect_make(full.x, full.y, full.w, fminf(full.h, T + 2 * g));
    }
    /* "Quit?": a question and two buttons in the middle of the picture. */
    if (p->quit_open) {
        float w = fminf(full.w - 2 * g, 2 * colw + 3 * g), h = 2 * T + 3 * g;
        L->quit = mr_ui_rect_make(full.x + (full.w - w) / 2, full.y + (full.h - h) / 2, w, h);
        mr_ui_rect in = mr_ui_rect_inset(L->quit, g);
        mr_ui_cut_top(&in, T + g);
        float bw = (in.w - g) / 2;
        place(L, MR_VW_QUIT_YES, mr_ui_rect_make(in.x, in.y, bw, T), T, p);
        place(L, MR_VW_QUIT_NO, mr_ui_rect_make(in.x + bw + g, in.y, bw, T), T, p);
    }
    /* The help and settings panel: the keys, then a row of settings
     * (the methods the toggles use, Reset) at its bottom. */
    if (p->help_open) {
        float w = fminf(full.w - 2 * g, mr_ui_mm(ui, 120)), h = full.h;
        L->help = mr_ui_rect_make(full.x + (full.w - w) / 2, full.y, w, h);
        mr_ui_rect in = mr_ui_rect_inset(L->help, g);
        float bw = (in.w - 3 * g) / 4;
        mr_ui_rect row = mr_ui_cut_bottom(&in, T);
        for (int i = 0; i < 4; i++)
            place(L, (mr_view_widget_id)(MR_VW_SET_AO + i), mr_ui_rect_make(row.x + i * (bw + g), row.y, bw, T), T, p);
    }
    L->picture = full;
}

/* --------------------------------------------------- tracking-lost policy */

mr_ui_rect mr_viewer_picture_area(mr_viewer *v, float fb_w, float fb_h, bool seekable) {
    mr_view_layout_params lp = {fb_w, fb_h, seekable, false, 0, false, false, false};
    mr_view_layout L;
    mr_view_layout_compute(v->ui, &lp, &L);
    return L.picture;
}

mr_view_render_choice mr_view_render_policy(const mr_view_settings *s, bool have_pose, bool pose_valid,
                                            bool frozen) {
    mr_view_render_choice c = {s->alpha, true, false};
    if (!have_pose) {
        c.alpha = 1.0f;
        c.use_pose = false;
    } else if (!pose_valid && !frozen) {
        c.alpha = s->show_video ? 1.0f - (1.0f - s->alpha) * 0.35f : s->alpha;
        c.dimmed = true;
    }
    return c;
}

/* ------------------------------------------------------------ controller */

mr_view_action *vw_emit(mr_view_actions *out, mr_view_action_type t) {
    if (out->count >= MR_VIEW_MAX_ACTIONS) {
        /* Never more than a handful per frame; a full list drops the rest. */
        memset(&out->overflow, 0, sizeof out->overflow);
        return &out->overflow;
    }
    mr_view_action *a = &out->a[out->count++];
    memset(a, 0, sizeof *a);
    a->type = t;
    return a;
}

mr_viewer *mr_viewer_create(const mr_viewer_params *params, mr_error *err) {
    mr_viewer *v = calloc(1, sizeof *v);
    if (!v) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    static const mr_viewer_params defaults = MR_VIEWER_DEFAULTS;
    v->p = params ? *params : defaults;
    if (v->p.px_per_mm <= 0) v->p.px_per_mm = 96.0 / 25.4;
    if (v->p.save_delay_s <= 0) v->p.save_delay_s = 1.0;
    if (v->p.script_wait_s <= 0) v->p.script_wait_s = 3.0;
    snprintf(v->config_path, sizeof v->config_path, "%s", v->p.config_path ? v->p.config_path : "");
    v->p.config_path = v->config_path;
    v->now = v->last_save = v->p.now;
    v->edit_pin = -1;
    mr_ui_font_params fp = MR_UI_FONT_DEFAULTS;
    fp.path = v->p.font_path;
    fp.pixel_height = roundf((float)(3.2 * v->p.px_per_mm)); /* baked at the size it is drawn */
    v->p.font_path = NULL;
    v->font = mr_ui_font_create(&fp, err);
    mr_ui_params up = MR_UI_DEFAULTS;
    up.px_per_mm = v->p.px_per_mm;
    up.font = v->font;
    v->ui = v->font ? mr_ui_create(&up, err) : NULL;
    if (!v->ui) {
        mr_viewer_destroy(&v);
        return NULL;
    }
    char warn[1024];
    mr_view_settings_load(v->config_path, &v->s, warn, sizeof warn);
    if (warn[0]) mr_log(MR_LOG_WARN, "view: %s: %s", v->config_path, warn);
    return v;
}

void mr_viewer_destroy(mr_viewer **pv) {
    if (!pv || !*pv) return;
    mr_viewer *v = *pv;
    mr_ui_destroy(&v->ui);
    mr_ui_font_destroy(&v->font);
    free(v->queue);
    free(v->pins);
    mr_view_script_destroy(&v->script);
    free(v);
    *pv = NULL;
}

void mr_viewer_push_event(mr_viewer *v, const mr_event *e) {
    if (v->qhead == v->qcount) v->qhead = v->qcount = 0;
    if (v->qcount == v->qcap) {
        int cap = v->qcap ? v->qcap * 2 : 64;
        mr_event *q = realloc(v->queue, (size_t)cap * sizeof *q);
        if (!q) return; /* out of memory: the event is lost, nothing else */
        v->queue = q;
        v->qcap = cap;
    }
    v->queue[v->qcount++] = *e;
}

int mr_viewer_pending(const mr_viewer *v) { return v->qcount - v->qhead; }

void mr_viewer_toast(mr_viewer *v, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(v->toast, sizeof v->toast, fmt, ap);
    va_end(ap);
    v->toast_until = v->now + 3.0;
}

void mr_viewer_note_open(mr_viewer *v, float u, float vv) {
    v->mark_u = u;
    v->mark_v = vv;
    v->note_open = true;
    v->edit_pin = -1;
    v->note_text[0] = 0;
    v->text_focus = false;
}

bool mr_viewer_pin_put(mr_viewer *v, int index, const mr_view_pin *pin) {
    if (index < 0 || index > v->pin_count) return false;
    if (index == v->pin_count) {
        if (v->pin_count == v->pin_cap) {
            int cap = v->pin_cap ? v->pin_cap * 2 : 16;
            vw_pin *p = realloc(v->pins, (size_t)cap * sizeof *p);
            if (!p) return false;
            v->pins = p;
            v->pin_cap = cap;
        }
        v->pin_count++;
    }
    memset(&v->pins[index], 0, sizeof v->pins[index]);
    v->pins[index].p = *pin;
    return true;
}

int mr_viewer_pin_count(const mr_viewer *v) { return v->pin_count; }

bool mr_viewer_pin_at(const mr_viewer *v, int i, float *x, float *y) {
    if (i < 0 || i >= v->pin_count || !v->pins[i].shown) return false;
    *x = v->pins[i].x;
    *y = v->pins[i].y;
    return true;
}

/* Opens the chooser on saved mark i, its note and category as they are. */
static void edit_pin(mr_viewer *v, int i) {
    const mr_view_pin *p = &v->pins[i].p;
    v->note_open = true;
    v->edit_pin = i;
    v->text_focus = false;
    snprintf(v->note_text, sizeof v->note_text, "%s", p->note);
    const mr_ui_rect ir = v->f.image_rect;
    v->mark_u = ir.w > 0 ? (v->pins[i].x - ir.x) / ir.w : 0.5f;
    v->mark_v = ir.h > 0 ? (v->pins[i].y - ir.y) / ir.h : 0.5f;
}

const mr_view_settings *mr_viewer_settings(const mr_viewer *v) { return &v->s; }
void mr_viewer_set_settings(mr_viewer *v, const mr_view_settings *s) { v->s = *s; }
bool mr_viewer_frozen(const mr_viewer *v) { return v->frozen; }
bool mr_viewer_note_is_open(const mr_viewer *v) { return v->note_open; }
const mr_ui *mr_viewer_ui_ctx(const mr_viewer *v) { return v->ui; }
const mr_view_layout *mr_viewer_layout(const mr_viewer *v) { return &v->lay; }

bool mr_viewer_wants_input(const mr_viewer *v) {
    return mr_viewer_pending(v) > 0 || (v->script && v->script_next < v->script->count) || v->input.down;
}

bool mr_viewer_save_settings(mr_viewer *v, mr_error *err) {
    if (!v->dirty || !v->config_path[0]) return true;
    if (!mr_view_settings_save(v->config_path, &v->s, err)) return false;
    v->dirty = false;
    return true;
}

/* ------------------------------------------------------------- actions */

static void changed(mr_viewer *v, mr_view_actions *out) {
    v->dirty = true;
    vw_emit(out, MR_VA_RENDER);
}

static void set_alpha(mr_viewer *v, float a, mr_view_actions *out) {
    a = a < 0 ? 0 : a > 1 ? 1 : a;
    if (a != v->s.alpha) {
        v->s.alpha = a;
        changed(v, out);
    }
}

static void set_frozen(mr_viewer *v, bool on, mr_view_actions *out) {
    v->frozen = on;
    vw_emit(out, MR_VA_FREEZE)->on = on;
}

static void toggle_play(mr_viewer *v, mr_view_actions *out) {
    if (!v->f.seekable) return;
    /* Playing does not unfreeze: the still stays until Freeze is undone. */
    vw_emit(out, MR_VA_PLAY)->on = !v->f.playing;
}

static void step(mr_viewer *v, int d, mr_view_actions *out) {
    if (!v->f.seekable) return;
    if (v->frozen) set_frozen(v, false, out);
    vw_emit(out, MR_VA_STEP)->i = d;
}

static void seek(mr_viewer *v, int64_t index, mr_view_actions *out) {
    if (v->frozen) set_frozen(v, false, out);
    vw_emit(out, MR_VA_SEEK)->i = index;
}

static void set_rate(mr_viewer *v, int i, mr_view_actions *out) {
    i = i < 0 ? 0 : i >= MR_VIEW_RATE_COUNT ? MR_VIEW_RATE_COUNT - 1 : i;
    v->s.rate_i = i;
    v->dirty = true;
    vw_emit(out, MR_VA_RATE)->x = mr_view_rates[i];
}

/* AO and ghosting cycle through the names of their settings rows, in
 * their order (the enums' order). */
/* The next method of a settings row, skipping its "off" value (the toggle's). */
static int next_method(const char *key, int cur, int off) {
    const mr_opt *o = mr_opt_find(mr_view_settings_opts, key);
    int m = mr_opt_enum_next(o, cur);
    if (m == off) m = mr_opt_enum_next(o, m);
    return m;
}

static void next_ao(mr_viewer *v, mr_view_actions *out) {
    v->s.ao = (mr_ao_method)next_method("ao", (int)v->s.ao, MR_AO_NONE);
    changed(v, out);
}

static void next_ghost(mr_viewer *v, mr_view_actions *out) {
    v->s.ghost = (mr_ghost_mode)next_method("ghost", (int)v->s.ghost, MR_GHOST_OFF);
    changed(v, out);
}

static void next_shadows(mr_viewer *v, mr_view_actions *out) {
    v->s.shadows = (mr_shadow_method)next_method("shadows", (int)v->s.shadows, MR_SHADOW_OFF);
    changed(v, out);
}

static void toggle(mr_viewer *v, bool *on, mr_view_actions *out) {
    *on = !*on;
    changed(v, out);
}

static void reset_settings(mr_viewer *v, mr_view_actions *out) {
    static const mr_view_settings d = MR_VIEW_SETTINGS_DEFAULTS;
    bool rate = v->s.rate_i != d.rate_i;
    v->s = d;
    changed(v, out);
    if (rate) vw_emit(out, MR_VA_RATE)->x = mr_view_rates[d.rate_i];
    v->notice_until = 0;
    mr_viewer_toast(v, "settings reset to the defaults");
}

static void mark_at(mr_viewer *v, double x, double y, mr_view_actions *out) {
    v->verdict_note = false; /* a plain mark: not the measurement's */
    mr_view_action *a = vw_emit(out, MR_VA_MARK_AT);
    a->x = x;
    a->y = y;
}

/* The chooser's answer: a category (-1 cancelled), or closing the mark
 * being edited. The note goes with it, as typed. */
static void finish_mark(mr_viewer *v, int category, bool close, mr_view_actions *out) {
    v->note_open = false;
    if (v->verdict_note) v->verdict_until = v->now + 6.0; /* the verdict stays a moment longer */
    v->verdict_note = false;
    v->mark_mode = false;
    v->text_focus = false;
    mr_view_action *a;
    if (v->edit_pin >= 0) {
        if (category < 0 && !close) {
            mr_viewer_toast(v, "edit cancelled");
        } else {
            a = vw_emit(out, MR_VA_MARK_EDIT);
            a->x = v->edit_pin;
            a->i = category >= 0 ? category : v->pins[v->edit_pin].p.category;
            a->on = close;
            a->path = v->note_text;
        }
    } else {
        a = vw_emit(out, MR_VA_MARK_FINISH);
        a->i = category;
        a->path = v->note_text;
    }
    v->edit_pin = -1;
}

/* Keys while the note field has the keyboard: printable characters are
 * typed, Backspace deletes, Enter and Esc leave the field. */
static void type_key(mr_viewer *v, int k) {
    size_t n = strlen(v->note_text);
    if (k == MR_KEY_ENTER || k == MR_KEY_ESCAPE || k == MR_KEY_TAB) v->text_focus = false;
    else if (k == MR_KEY_BACKSPACE && n > 0) v->note_text[n - 1] = 0;
    else if (k >= 32 && k < 127 && n + 1 < sizeof v->note_text) v->note_text[n] = (char)k, v->note_text[n + 1] = 0;
}

/* Esc: the innermost thing going on ends; nothing else. */
static void cancel(mr_viewer *v) {
    if (v->quit_open) v->quit_open = false;
    else if (v->text_focus) v->text_focus = false;
    else if (v->note_open) return; /* handled by the caller: it emits the cancel */
    else if (v->help) v->help = false;
    else if (v->measure_mode) vw_measure_cancel(v);
    else if (v->mark_mode) v->mark_mode = false;
    else if (v->frozen) mr_viewer_toast(v, "frozen: f unfreezes; q quits");
    else mr_viewer_toast(v, "nothing to cancel; q quits");
}

static void on_key(mr_viewer *v, int k, mr_view_actions *out) {
    if (v->quit_open) {
        if (k == MR_KEY_ENTER || k == 'y' || k == 'q') vw_emit(out, MR_VA_QUIT);
        else if (k == MR_KEY_ESCAPE || k == 'n') v->quit_open = false;
        return;
    }
    if (v->text_focus) {
        type_key(v, k);
        return;
    }
    if (v->note_open) {
        if (k >= '1' && k < '1' + MR_VIEW_NOTE_COUNT) finish_mark(v, k - '1', false, out);
        else if (k == MR_KEY_ESCAPE) finish_mark(v, -1, false, out);
        else if (k == MR_KEY_ENTER || k == 'n') v->text_focus = true;
        return;
    }
    if (v->help && (k == MR_KEY_ESCAPE || k == '?' || k == MR_KEY_F1)) {
        v->help = false;
        return;
    }
    mr_ui_rect ir = v->f.image_rect;
    switch (k) {
    case '?': case MR_KEY_F1: v->help = !v->help; break;
    case MR_KEY_UP: case '+': case '=': set_alpha(v, roundf(v->s.alpha * 10 + 1) / 10, out); break;
    case MR_KEY_DOWN: case '-': set_alpha(v, roundf(v->s.alpha * 10 - 1) / 10, out); break;
    case 'f': set_frozen(v, !v->frozen, out); break;
    case 's': vw_emit(out, MR_VA_SNAPSHOT); break;
    case 'm':
        vw_measure_cancel(v);
        v->mark_mode = !v->mark_mode;
        break;
    case 'd': vw_measure_toggle(v, out); break;
    case MR_KEY_ENTER:
        if (v->measure_mode) vw_measure_toggle(v, out);
        else if (v->mark_mode) mark_at(v, ir.x + ir.w * 0.5, ir.y + ir.h * 0.5, out);
        break;
    case 'v': v->s.show_video = !v->s.show_video; changed(v, out); break;
    case 'h': v->s.hide_hidden = !v->s.hide_hidden; changed(v, out); break;
    case 'a': toggle(v, &v->s.ao_on, out); break;
    case 'g': toggle(v, &v->s.ghost_on, out); break;
    case 'c': toggle(v, &v->s.shadows_on, out); break;
    case ' ': toggle_play(v, out); break;
    case '.': case MR_KEY_RIGHT: step(v, 1, out); break;
    case ',': case MR_KEY_LEFT: step(v, -1, out); break;
    case MR_KEY_HOME: vw_emit(out, MR_VA_SEEK)->i = 0; break;
    case MR_KEY_END: vw_emit(out, MR_VA_SEEK)->i = INT64_MAX / 2; break;
    case '[': set_rate(v, v->s.rate_i - 1, out); break;
    case ']': set_rate(v, v->s.rate_i + 1, out); break;
    case MR_KEY_F11: vw_emit(out, MR_VA_FULLSCREEN); break;
    case MR_KEY_ESCAPE: cancel(v); break;
    case 'q': v->quit_open = true; break;
    default: break;
    }
}

/* Takes queued events. Presses and releases reach the UI one per frame (a
 * quick tap is a press frame then a release frame), so no tap is lost
 * however fast it was; moves and keys are applied at once. */
static void pump(mr_viewer *v, mr_view_actions *out) {
    bool transition = false;
    while (v->qhead < v->qcount) {
        const mr_event e = v->queue[v->qhead];
        switch (e.type) {
        case MR_EVENT_POINTER_DOWN:
        case MR_EVENT_POINTER_UP:
            if (transition) return; /* the next frame's */
            transition = true;
            v->input.x = (float)e.x;
            v->input.y = (float)e.y;
            v->input.down = e.type == MR_EVENT_POINTER_DOWN;
            v->input.inside = true;
            break;
        case MR_EVENT_POINTER_MOVE:
            if (transition) return; /* a move after a transition belongs to the next frame */
            v->input.x = (float)e.x;
            v->input.y = (float)e.y;
            v->input.inside = true;
            break;
        case MR_EVENT_NONE:
            if (transition) {
                v->qhead++;
                return;
            }
            break;
        case MR_EVENT_POINTER_LEAVE: v->input.inside = false; break;
        case MR_EVENT_KEY: on_key(v, e.key, out); break;
        case MR_EVENT_RESIZE: vw_emit(out, MR_VA_RENDER); break;
        case MR_EVENT_CLOSE: vw_emit(out, MR_VA_QUIT); break;
        }
        v->qhead++;
    }
}

void mr_viewer_input(mr_viewer *v, double now, bool busy, mr_view_actions *out) {
    v->now = now;
    vw_script_tick(v, busy, out);
    pump(v, out);
}

/* ------------------------------------------------------------------ UI */

bool mr_view_sigma_here(const mr_viewer_frame *f, double *sigma_m) {
    if (!f || !f->have_pose || !f->pose_cov || !(f->corner_sigma_px > 0) || !f->have_point) return false;
    mr_pose p;
    memset(&p, 0, sizeof p);
    p.valid = true;
    p.world_from_camera = f->world_from_camera;
    memcpy(p.cov, f->pose_cov, sizeof p.cov);
    p.corner_sigma_px = f->corner_sigma_px;
    double s3 = 0;
    if (!mr_pose_point_sigma(&p, f->point, &s3, NULL) || !isfinite(s3)) return false;
    if (sigma_m) *sigma_m = s3;
    return true;
}

mr_view_sigma_state mr_view_sigma_classify(bool known, double sigma_m) {
    if (!known || !isfinite(sigma_m)) return MR_VIEW_SIGMA_UNKNOWN;
    double mm = sigma_m * 1e3;
    return mm < MR_VIEW_SIGMA_OK_MM ? MR_VIEW_SIGMA_OK : mm <= MR_VIEW_SIGMA_WARN_MM ? MR_VIEW_SIGMA_WARN : MR_VIEW_SIGMA_BAD;
}

/* The planner's words: tracking, the registration's sigma at the centre,
 * the frame (its number as in the files), the marks; the frame rate and the
 * render passes only with --stats. */
static void status_line(mr_viewer *v, const mr_viewer_frame *f) {
    char line[600], track[128], frame[160] = "", here[64] = "", marks[64] = "", stats[300] = "";
    int tags = f->tags_seen < 0 ? 0 : f->tags_seen;
    if (!f->have_frame) snprintf(track, sizeof track, "no camera frame yet");
    else if (f->pose_valid) snprintf(track, sizeof track, "tracking OK (%d tag%s)", tags, tags == 1 ? "" : "s");
    else if (f->have_pose) snprintf(track, sizeof track, "TRACKING LOST (%d tag%s)", tags, tags == 1 ? "" : "s");
    else snprintf(track, sizeof track, "searching for markers");
    if (f->have_frame && f->seekable)
        snprintf(frame, sizeof frame, " | frame %lld of 0-%lld, %s %gx", (long long)f->index,
                 (long long)(f->count > 0 ? f->count - 1 : 0), f->playing ? "playing" : "paused", mr_view_rates[v->s.rate_i]);
    else if (f->have_frame) snprintf(frame, sizeof frame, " | frame %lld", (long long)f->index);
    /* The registration's sigma where the planner looks ("+/-": the UI font
     * is printable ASCII only); "?" when the pose has no covariance (an
     * older recording) or nothing is under the centre. */
    v->sigma_known = f->have_frame && f->have_pose && mr_view_sigma_here(f, &v->sigma_m);
    if (!v->sigma_known) v->sigma_m = NAN;
    if (f->have_frame && f->have_pose) {
        double mm = v->sigma_m * 1e3;
        const char *where = v->note_open ? "at the mark" : "at the centre";
        if (!v->sigma_known) snprintf(here, sizeof here, " | registration +/- ? mm %s", where);
        else snprintf(here, sizeof here, mm < 9.95 ? " | registration +/- %.1f mm %s" : " | registration +/- %.0f mm %s", mm,
                      where);
    }
    int open_marks = 0;
    for (int i = 0; i < v->pin_count; i++) open_marks += !v->pins[i].p.closed;
    if (v->pin_count)
        snprintf(marks, sizeof marks, " | %d mark%s (%d open)", v->pin_count, v->pin_count == 1 ? "" : "s", open_marks);
    else snprintf(marks, sizeof marks, " | no marks");
    if (v->p.show_stats) snprintf(stats, sizeof stats, " | %.1f fps | %.200s", f->fps, v->passes[0] ? v->passes : "-");
    snprintf(line, sizeof line, "%s%s%s%s%s%s", v->frozen ? "FROZEN | " : "", track, here, frame, marks, stats);
    snprintf(v->status, sizeof v->status, "%s", line);
    mr_view_sigma_state st = mr_view_sigma_classify(v->sigma_known, v->sigma_m);
    uint32_t col = MR_UI_RGBA(235, 240, 245, 255);
    if (f->have_frame && !f->pose_valid) col = MR_UI_RGBA(255, 150, 120, 255);
    else if (st == MR_VIEW_SIGMA_BAD) col = MR_UI_RGBA(255, 120, 100, 255);
    else if (st == MR_VIEW_SIGMA_WARN) col = MR_UI_RGBA(255, 210, 110, 255);
    /* A line longer than the window loses its end, not its start. */
    float th = mr_ui_text_px(v->ui), room = v->lay.status.w - mr_ui_mm(v->ui, 2);
    const mr_ui_font *font = mr_ui_get_font(v->ui);
    size_t n = strlen(line);
    while (n > 4 && mr_ui_text_width(font, line, th) > room) {
        line[--n] = 0;
        memcpy(line + n - 3, "...", 3);
    }
    mr_ui_label(v->ui, v->lay.status, line, col, false);
}

const char *mr_viewer_status_text(const mr_viewer *v) { return v->status; }

static bool button(mr_viewer *v, mr_view_widget_id id, const char *label, bool on) {
    return v->lay.shown[id] &&
           mr_ui_button(v->ui, 20 + (uint32_t)id, v->lay.rect[id], label, on ? MR_UI_ON : MR_UI_NORMAL);
}

static void bottom_bar(mr_viewer *v, const mr_viewer_frame *f, mr_view_actions *out) {
    const mr_view_layout *L = &v->lay;
    char lab[64];
    mr_ui_panel(v->ui, L->bottom);
    snprintf(lab, sizeof lab, "model  <  >  video  %d%%", (int)lroundf(v->s.alpha * 100));
    float alpha = v->s.alpha;
    if (L->shown[MR_VW_ALPHA] && mr_ui_slider(v->ui, 1, L->rect[MR_VW_ALPHA], lab, &alpha, 0.0f, 1.0f))
        set_alpha(v, alpha, out);
    if (!f->seekable) return;
    if (button(v, MR_VW_PLAY, f->playing ? "Pause" : "Play", f->playing)) toggle_play(v, out);
    if (button(v, MR_VW_BACK, "<", false)) step(v, -1, out);
    if (button(v, MR_VW_FORWARD, ">", false)) step(v, 1, out);
    snprintf(lab, sizeof lab, "%gx", mr_view_rates[v->s.rate_i]);
    if (button(v, MR_VW_RATE, lab, false)) set_rate(v, (v->s.rate_i + 1) % MR_VIEW_RATE_COUNT, out);
    if (!L->shown[MR_VW_SEEK]) return;
    int64_t count = f->have_frame && f->count > 0 ? f->count : 1;
    float pos = f->have_frame ? (float)f->index : 0;
    snprintf(lab, sizeof lab, "frame %lld", (long long)(f->have_frame ? f->index : 0));
    if (mr_ui_slider(v->ui, 2, L->rect[MR_VW_SEEK], lab, &pos, 0.0f, (float)(count > 1 ? count - 1 : 1))) {
        int64_t want = (int64_t)lroundf(pos);
        if (!f->have_frame || want != f->index) seek(v, want, out);
    }
}

static void column(mr_viewer *v, mr_view_actions *out) {
    if (v->lay.column.w > 0) mr_ui_panel(v->ui, v->lay.column);
    if (button(v, MR_VW_FREEZE, v->frozen ? "Frozen" : "Freeze", v->frozen)) set_frozen(v, !v->frozen, out);
    if (button(v, MR_VW_SNAPSHOT, "Snapshot", false)) vw_emit(out, MR_VA_SNAPSHOT);
    if (button(v, MR_VW_MARK, "Mark", v->mark_mode)) {
        vw_measure_cancel(v);
        v->mark_mode = !v->mark_mode;
    }
    /* Measure (measure.c) */
    if (button(v, MR_VW_MEASURE, v->measure_mode ? "Finish" : "Measure", v->measure_mode)) vw_measure_toggle(v, out);
    if (button(v, MR_VW_VIDEO, "Video", v->s.show_video)) {
        v->s.show_video = !v->s.show_video;
        changed(v, out);
    }
    if (button(v, MR_VW_HIDDEN, "Hidden", !v->s.hide_hidden)) {
        v->s.hide_hidden = !v->s.hide_hidden;
        changed(v, out);
    }
    if (button(v, MR_VW_AO, "AO", v->s.ao_on)) toggle(v, &v->s.ao_on, out);
    if (button(v, MR_VW_GHOST, "Ghost", v->s.ghost_on)) toggle(v, &v->s.ghost_on, out);
    if (button(v, MR_VW_SHADOWS, "Shadows", v->s.shadows_on)) toggle(v, &v->s.shadows_on, out);
    if (button(v, MR_VW_QUIT, "Quit", v->quit_open)) v->quit_open = true;
    if (button(v, MR_VW_HELP, "?", v->help)) v->help = !v->help;
}

/* Messages over the picture, failures first; the toast at the bottom. */
static void messages(mr_viewer *v, const mr_viewer_frame *f) {
    mr_ui *ui = v->ui;
    float g = mr_ui_mm(ui, 1.2f), th = mr_ui_text_px(ui);
    mr_ui_rect area = v->lay.picture;
    const char *banners[8];
    uint32_t colors[8];
    char measure_banner[160];
    int nb = 0;
    if (f->source_msg && f->source_msg[0]) { banners[nb] = f->source_msg; colors[nb++] = MR_UI_RGBA(200, 40, 40, 230); }
    if (f->scene_msg && f->scene_msg[0]) { banners[nb] = f->scene_msg; colors[nb++] = MR_UI_RGBA(200, 40, 40, 230); }
    if (f->have_frame && !f->have_pose) {
        banners[nb] = "searching for markers: no pose yet";
        colors[nb++] = MR_UI_RGBA(200, 120, 20, 230);
    } else if (f->dimmed) {
        banners[nb] = "TRACKING LOST: model dimmed at the last good pose";
        colors[nb++] = MR_UI_RGBA(200, 120, 20, 230);
    }
    if (v->mark_mode && !v->note_open) {
        banners[nb] = "MARK: tap the discrepancy in the picture (Esc cancels)";
        colors[nb++] = MR_UI_RGBA(214, 120, 28, 230);
    }
    if (v->notice[0] && v->now < v->notice_until) {
        banners[nb] = v->notice;
        colors[nb++] = MR_UI_RGBA(40, 90, 150, 230);
    }
    if (v->measure_mode) {
        vw_measure_banner(v, measure_banner, sizeof measure_banner);
        banners[nb] = measure_banner;
        colors[nb++] = MR_UI_RGBA(30, 120, 190, 230);
    }
    /* A measurement's verdict: while its mark is filed, and a while after. */
    if (v->verdict_banner[0] && (v->now < v->verdict_until || (v->note_open && v->verdict_note))) {
        banners[nb] = v->verdict_banner;
        colors[nb++] = v->verdict_kind == MR_VERDICT_WITHIN ? MR_UI_RGBA(30, 130, 50, 235)
                       : v->verdict_kind == MR_VERDICT_OUT  ? MR_UI_RGBA(190, 30, 30, 235)
                                                            : MR_UI_RGBA(200, 125, 10, 235);
    }
    for (int i = 0; i < nb; i++) {
        mr_ui_rect b = mr_ui_rect_inset(mr_ui_cut_top(&area, th * 2.0f), g * 0.5f);
        mr_ui_draw_rect(mr_ui_list(ui), b, colors[i]);
        mr_ui_label(ui, b, banners[i], MR_UI_RGBA(255, 255, 255, 255), true);
    }
    if (v->toast[0] && v->now < v->toast_until) {
        mr_ui_rect b = mr_ui_rect_inset(mr_ui_cut_bottom(&area, th * 2.0f), g * 0.5f);
        mr_ui_draw_rect(mr_ui_list(ui), b, MR_UI_RGBA(20, 20, 20, 200));
        mr_ui_label(ui, b, v->toast, MR_UI_RGBA(255, 255, 255, 255), true);
    }
}

/* The note's text field: a tap gives it the keyboard (a tablet shows its
 * on-screen keyboard for it); what is typed shows with a caret, its end
 * kept in view. */
static void note_field(mr_viewer *v, mr_ui_rect r) {
    mr_ui *ui = v->ui;
    if (mr_ui_button(ui, 75, r, "", v->text_focus ? MR_UI_ON : MR_UI_NORMAL)) v->text_focus = !v->text_focus;
    float th = mr_ui_text_px(ui), pad = mr_ui_mm(ui, 1.5f);
    mr_ui_rect in = mr_ui_rect_inset(r, pad);
    char shown[sizeof v->note_text + 2];
    bool empty = !v->note_text[0];
    snprintf(shown, sizeof shown, "%s%s", empty && !v->text_focus ? "tap to type a note (@who #label !priority)" : v->note_text,
             v->text_focus ? "_" : "");
    const char *t = shown;
    while (*t && mr_ui_text_width(mr_ui_get_font(ui), t, th) > in.w) t++;
    mr_ui_label(ui, in, t, empty && !v->text_focus ? MR_UI_RGBA(170, 180, 190, 255) : MR_UI_RGBA(255, 255, 255, 255), false);
}

/* The note chooser and the cross of the mark being made. */
static void notes(mr_viewer *v, const mr_viewer_frame *f, mr_view_actions *out) {
    mr_ui *ui = v->ui;
    const mr_view_layout *L = &v->lay;
    float T = mr_ui_target_px(ui), g = mr_ui_mm(ui, 1.2f);
    mr_ui_panel(ui, L->notes);
    mr_ui_panel(ui, L->notes); /* darker */
    mr_ui_rect in = mr_ui_rect_inset(L->notes, g);
    char q[260];
    if (v->edit_pin >= 0) snprintf(q, sizeof q, "Mark %d: %.200s", v->pins[v->edit_pin].p.number, v->pins[v->edit_pin].p.title);
    else snprintf(q, sizeof q, "%s", L->shown[MR_VW_NOTE1] ? "Note, then what differs here?" : "What differs? keys 1..6");
    mr_ui_label(ui, mr_ui_cut_top(&in, T), q, MR_UI_RGBA(255, 255, 255, 255), true);
    if (L->shown[MR_VW_NOTE_TEXT]) note_field(v, L->rect[MR_VW_NOTE_TEXT]);
    int current = v->edit_pin >= 0 ? v->pins[v->edit_pin].p.category : -1;
    for (int i = 0; i < MR_VIEW_NOTE_COUNT; i++) {
        char lb[48];
        snprintf(lb, sizeof lb, "%d %s", i + 1, mr_mark_categories[i]);
        if (L->shown[MR_VW_NOTE1 + i] &&
            mr_ui_button(ui, (uint32_t)(60 + i), L->rect[MR_VW_NOTE1 + i], lb, i == current ? MR_UI_ON : MR_UI_NORMAL))
            finish_mark(v, i, false, out);
    }
    if (L->shown[MR_VW_CANCEL] && mr_ui_button(ui, 70, L->rect[MR_VW_CANCEL], "Cancel", MR_UI_NORMAL))
        finish_mark(v, -1, false, out);
    if (L->shown[MR_VW_CLOSE_MARK] && v->edit_pin >= 0 &&
        mr_ui_button(ui, 71, L->rect[MR_VW_CLOSE_MARK], v->pins[v->edit_pin].p.closed ? "Keep closed" : "Close mark",
                     MR_UI_NORMAL))
        finish_mark(v, -1, true, out);
    if (!f->have_image) return;
    mr_ui_rect ir = f->image_rect;
    float x = ir.x + v->mark_u * ir.w, y = ir.y + v->mark_v * ir.h;
    float s = mr_ui_mm(ui, 3), t = fmaxf(2, mr_ui_mm(ui, 0.4f));
    mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(x - s, y - t / 2, 2 * s, t), MR_UI_RGBA(255, 60, 60, 255));
    mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(x - t / 2, y - s, t, 2 * s), MR_UI_RGBA(255, 60, 60, 255));
}

/* "Quit?" with its two answers. */
static void quit_panel(mr_viewer *v, mr_view_actions *out) {
    mr_ui *ui = v->ui;
    const mr_view_layout *L = &v->lay;
    float g = mr_ui_mm(ui, 1.2f);
    mr_ui_panel(ui, L->quit);
    mr_ui_panel(ui, L->quit);
    mr_ui_rect in = mr_ui_rect_inset(L->quit, g);
    mr_ui_label(ui, mr_ui_cut_top(&in, mr_ui_target_px(ui)), "Quit the check? (marks are saved)", MR_UI_RGBA(255, 255, 255, 255),
                true);
    if (L->shown[MR_VW_QUIT_YES] && mr_ui_button(ui, 90, L->rect[MR_VW_QUIT_YES], "Quit", MR_UI_ACCENT))
        vw_emit(out, MR_VA_QUIT);
    if (L->shown[MR_VW_QUIT_NO] && mr_ui_button(ui, 91, L->rect[MR_VW_QUIT_NO], "Stay", MR_UI_NORMAL)) v->quit_open = false;
}

static void help_panel(mr_viewer *v, mr_view_actions *out) {
    mr_ui *ui = v->ui;
    const mr_view_layout *L = &v->lay;
    float g = mr_ui_mm(ui, 1.2f), th = mr_ui_text_px(ui), lh = th * 1.35f, T = mr_ui_target_px(ui);
    mr_ui_rect p = L->help;
    mr_ui_panel(ui, p);
    mr_ui_panel(ui, p);
    mr_ui_rect in = mr_ui_rect_inset(p, g);
    mr_ui_cut_bottom(&in, T + g); /* the settings row */
    char changes[300], head[400];
    int nc = mr_view_settings_describe_changes(&v->s, changes, sizeof changes);
    snprintf(head, sizeof head, "Settings: %s", nc ? changes : "the defaults");
    mr_ui_label(ui, mr_ui_cut_bottom(&in, lh), head, MR_UI_RGBA(255, 220, 150, 255), false);
    char lb[4][48];
    snprintf(lb[0], sizeof lb[0], "AO: %s", mr_ao_method_name(v->s.ao));
    snprintf(lb[1], sizeof lb[1], "Ghost: %s", mr_view_ghost_name(v->s.ghost));
    snprintf(lb[2], sizeof lb[2], "Shadows: %s",
             mr_shadow_method_names[(int)v->s.shadows >= 0 && v->s.shadows < MR_SHADOW_METHOD_COUNT ? v->s.shadows : 0]);
    snprintf(lb[3], sizeof lb[3], "Reset");
    for (int i = 0; i < 4; i++) {
        mr_view_widget_id id = (mr_view_widget_id)(MR_VW_SET_AO + i);
        if (!L->shown[id] || !mr_ui_button(ui, 95 + (uint32_t)i, L->rect[id], lb[i], MR_UI_NORMAL)) continue;
        if (i == 0) next_ao(v, out);
        else if (i == 1) next_ghost(v, out);
        else if (i == 2) next_shadows(v, out);
        else reset_settings(v, out);
    }
    mr_ui_label(ui, mr_ui_cut_top(&in, lh), "Keys (? or Esc closes)", MR_UI_RGBA(255, 220, 150, 255), false);
    for (int i = 0; i < mr_view_keymap_count && in.h >= lh; i++) {
        mr_ui_rect row = mr_ui_cut_top(&in, lh);
        mr_ui_rect k = mr_ui_cut_left(&row, fminf(row.w * 0.3f, mr_ui_mm(ui, 30)));
        mr_ui_label(ui, k, mr_view_keymap[i].keys, MR_UI_RGBA(150, 200, 255, 255), false);
        mr_ui_label(ui, row, mr_view_keymap[i].what, MR_UI_RGBA(235, 240, 245, 255), false);
    }
}

/* Saved marks as pins: projected with this frame's pose into the picture. */
static void pins(mr_viewer *v, const mr_viewer_frame *f) {
    mr_ui *ui = v->ui;
    const mr_ui_rect ir = f->image_rect;
    bool can = f->have_image && f->have_pose && f->camera && f->camera->width > 0;
    mr_camera pin_cam;
    if (can) {
        pin_cam = *f->camera;
        memset(pin_cam.dist, 0, sizeof pin_cam.dist); /* the picture is undistorted */
    }
    float s = mr_ui_mm(ui, 2.2f), t = fmaxf(2, mr_ui_mm(ui, 0.5f)), th = mr_ui_text_px(ui);
    for (int i = 0; i < v->pin_count; i++) {
        vw_pin *p = &v->pins[i];
        double u, w;
        p->shown = can && p->p.has_world && mr_project_point(&pin_cam, &f->world_from_camera, p->p.world, &u, &w);
        if (!p->shown) continue;
        p->x = ir.x + (float)((u + 0.5) * ir.w / pin_cam.width);
        p->y = ir.y + (float)((w + 0.5) * ir.h / pin_cam.height);
        p->shown = mr_ui_rect_contains(ir, p->x, p->y);
        if (!p->shown) continue;
        /* Grey once closed; a measured mark in its verdict's colour. */
        uint32_t col = p->p.closed                              ? MR_UI_RGBA(150, 150, 150, 235)
                       : p->p.verdict == MR_VERDICT_WITHIN    ? MR_UI_RGBA(40, 150, 60, 240)
                       : p->p.verdict == MR_VERDICT_UNDECIDED ? MR_UI_RGBA(215, 140, 20, 240)
                                                              : MR_UI_RGBA(220, 40, 40, 240);
        /* A head with the number above a stem whose tip is the point. */
        mr_ui_rect head = mr_ui_rect_make(p->x - s, p->y - 3.2f * s, 2 * s, 2 * s);
        mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(p->x - t / 2, p->y - 1.2f * s, t, 1.2f * s), col);
        mr_ui_draw_rect(mr_ui_list(ui), head, col);
        mr_ui_draw_frame(mr_ui_list(ui), head, 1.0f, MR_UI_RGBA(255, 255, 255, 255));
        mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(p->x - t, p->y - t, 2 * t, 2 * t), MR_UI_RGBA(255, 255, 255, 255));
        char num[16];
        snprintf(num, sizeof num, "%d", p->p.number);
        (void)th;
        mr_ui_label(ui, head, num, MR_UI_RGBA(255, 255, 255, 255), true);
    }
}

/* The saved mark whose pin is nearest a tap, within a touch target; -1 none. */
static int pin_hit(const mr_viewer *v, float x, float y) {
    float T = mr_ui_target_px(v->ui), s = mr_ui_mm(v->ui, 2.2f), best = T * T * 0.36f;
    int hit = -1;
    for (int i = 0; i < v->pin_count; i++) {
        if (!v->pins[i].shown) continue;
        /* the head and the stem count: measure to the middle of the pin */
        float dx = x - v->pins[i].x, dy = y - (v->pins[i].y - 1.6f * s), d = dx * dx + dy * dy;
        if (d < best) best = d, hit = i;
    }
    return hit;
}

const mr_ui_draw_list *mr_viewer_ui(mr_viewer *v, const mr_viewer_frame *f, mr_view_actions *out) {
    v->now = f->now;
    if (f->px_per_mm > 0 && fabs(f->px_per_mm - mr_ui_px_per_mm(v->ui)) > 1e-6) mr_ui_set_density(v->ui, f->px_per_mm);
    v->f = *f;
    snprintf(v->passes, sizeof v->passes, "%s", f->passes ? f->passes : "");
    v->f.source_desc = v->f.source_msg = v->f.scene_msg = v->f.passes = NULL;

    if (!v->notice_done) {
        /* Settings carried over from an earlier session are said at start. */
        char changes[300];
        v->notice_done = true;
        if (mr_view_settings_describe_changes(&v->s, changes, sizeof changes) > 0) {
            snprintf(v->notice, sizeof v->notice, "Settings differ from the defaults: %s (? > Reset)", changes);
            v->notice_until = f->now + 10.0;
        }
    }
    mr_view_layout_params lp = {f->fb_w, f->fb_h, f->seekable, v->note_open,
                                f->image_rect.x + v->mark_u * f->image_rect.w, v->note_open && v->edit_pin >= 0,
                                v->quit_open, v->help};
    mr_view_layout_compute(v->ui, &lp, &v->lay);
    mr_ui_input in = v->input;
    mr_ui_begin(v->ui, &in);
    mr_ui_panel(v->ui, v->lay.status);
    status_line(v, f);
    bottom_bar(v, f, out);
    column(v, out);
    pins(v, f);
    messages(v, f);
    if (v->note_open) notes(v, f, out);
    vw_measure_draw(v, f);
    if (v->help) help_panel(v, out);
    if (v->quit_open) quit_panel(v, out);
    float tx, ty;
    const mr_ui_draw_list *dl = mr_ui_end(v->ui);
    if (mr_ui_scene_tap(v->ui, &tx, &ty)) {
        int pin = -1;
        if (v->help) v->help = false;
        else if (v->quit_open) v->quit_open = false;
        else if (v->note_open) v->text_focus = false;
        else if (v->mark_mode) mark_at(v, tx, ty, out);
        else if (v->measure_mode) vw_measure_tap(v, f, tx, ty);
        else if ((pin = pin_hit(v, tx, ty)) >= 0) edit_pin(v, pin);
    }
    v->frames++;
    /* Settings are saved a moment after they change, not per slider step. */
    if (v->dirty && v->now - v->last_save > v->p.save_delay_s) {
        mr_error err = {0};
        if (!mr_viewer_save_settings(v, &err)) mr_log(MR_LOG_WARN, "view: cannot save settings: %s", err.msg);
        v->last_save = v->now;
    }
    return dl;
}

cJSON *mr_viewer_state_json(const mr_viewer *v) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "alpha", v->s.alpha);
    cJSON_AddBoolToObject(j, "show_video", v->s.show_video);
    cJSON_AddBoolToObject(j, "hide_hidden_layer", v->s.hide_hidden);
    /* What the toggles give (none / off when off), and the methods. */
    mr_shadow_method sh = mr_view_shadows(&v->s);
    cJSON_AddStringToObject(j, "ao", mr_ao_method_name(mr_view_ao(&v->s)));
    cJSON_AddStringToObject(j, "ghost", mr_view_ghost_name(mr_view_ghost(&v->s)));
    cJSON_AddStringToObject(j, "shadows", mr_shadow_method_names[(int)sh >= 0 && sh < MR_SHADOW_METHOD_COUNT ? sh : 0]);
    cJSON_AddStringToObject(j, "ao_method", mr_ao_method_name(v->s.ao));
    cJSON_AddStringToObject(j, "status_line", v->status);
    cJSON_AddBoolToObject(j, "quit_asked", v->quit_open);
    cJSON_AddBoolToObject(j, "note_open", v->note_open);
    cJSON_AddStringToObject(j, "note_text", v->note_text);
    cJSON_AddBoolToObject(j, "note_typing", v->text_focus);
    cJSON_AddStringToObject(j, "notice", v->now < v->notice_until ? v->notice : "");
    bool verdict_shown = v->verdict_banner[0] && (v->now < v->verdict_until || (v->note_open && v->verdict_note));
    cJSON_AddStringToObject(j, "verdict_banner", verdict_shown ? v->verdict_banner : "");
    cJSON *pj = cJSON_AddArrayToObject(j, "pins");
    for (int i = 0; i < v->pin_count; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "number", v->pins[i].p.number);
        cJSON_AddBoolToObject(o, "shown", v->pins[i].shown);
        cJSON_AddBoolToObject(o, "closed", v->pins[i].p.closed);
        cJSON_AddStringToObject(o, "verdict", mr_verdict_key(v->pins[i].p.verdict));
        cJSON_AddStringToObject(o, "title", v->pins[i].p.title);
        if (v->pins[i].shown) {
            double xy[2] = {v->pins[i].x, v->pins[i].y};
            cJSON_AddItemToObject(o, "xy", mr_json_from_doubles(xy, 2));
        }
        cJSON_AddItemToArray(pj, o);
    }
    cJSON_AddBoolToObject(j, "frozen", v->frozen);
    cJSON_AddBoolToObject(j, "mark_mode", v->mark_mode);
    cJSON_AddBoolToObject(j, "help", v->help);
    cJSON_AddStringToObject(j, "passes", v->passes);
    cJSON_AddBoolToObject(j, "have_frame", v->f.have_frame);
    cJSON_AddNumberToObject(j, "frame_index", v->f.have_frame ? (double)v->f.index : -1);
    cJSON_AddBoolToObject(j, "pose_valid", v->f.have_frame && v->f.pose_valid);
    cJSON_AddNumberToObject(j, "tags_seen", v->f.have_frame ? v->f.tags_seen : -1);
    cJSON_AddBoolToObject(j, "tracking_lost_dimmed", v->f.dimmed);
    double ir[4] = {v->f.image_rect.x, v->f.image_rect.y, v->f.image_rect.w, v->f.image_rect.h};
    cJSON_AddItemToObject(j, "image_rect", mr_json_from_doubles(ir, 4));
    cJSON_AddNumberToObject(j, "fb_width", v->f.fb_w);
    cJSON_AddNumberToObject(j, "fb_height", v->f.fb_h);
    if (v->sigma_known) cJSON_AddNumberToObject(j, "sigma_here_mm", v->sigma_m * 1e3);
    else cJSON_AddNullToObject(j, "sigma_here_mm");
    static const char *const k_sigma_states[] = {"unknown", "ok", "warn", "bad"};
    cJSON_AddStringToObject(j, "sigma_state", k_sigma_states[mr_view_sigma_classify(v->sigma_known, v->sigma_m)]);
    vw_measure_state_json(v, j);
    cJSON_AddNumberToObject(j, "px_per_mm", mr_ui_px_per_mm(v->ui));
    cJSON_AddNumberToObject(j, "target_px", mr_ui_target_px(v->ui));
    /* Where each widget is (framebuffer pixels x y w h), for tests that
     * drive the window with real X input (xdotool). */
    cJSON *wd = cJSON_AddObjectToObject(j, "widgets");
    for (int i = 0; i < MR_VW_COUNT; i++) {
        if (!v->lay.shown[i]) continue;
        mr_ui_rect r = v->lay.rect[i];
        double d[4] = {r.x, r.y, r.w, r.h};
        cJSON_AddItemToObject(wd, k_widget_names[i], mr_json_from_doubles(d, 4));
    }
    return j;
}
