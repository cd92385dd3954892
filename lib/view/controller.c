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
    {"m", "mark mode: tap the scene, then pick a note"},
    {"Enter", "in mark mode: mark the image centre"},
    {"1..6", "choose a note / Esc cancels"},
    {"d", "measure: tap one feature in 2+ frames, d again to finish"},
    {"v", "video on/off"},
    {"h", "hidden layer on/off"},
    {"a", "next ambient occlusion method"},
    {"g", "next ghosting mode"},
    {"c", "next shadow method (off, hard, pcf, pcss, bp)"},
    {"space", "replay: play / pause"},
    {". / Right", "replay: step forward"},
    {", / Left", "replay: step back"},
    {"Home / End", "replay: first / last frame"},
    {"[ / ]", "replay: slower / faster"},
    {"F11", "fullscreen"},
    {"? / F1", "this help"},
    {"q / Esc", "quit"},
};
const int mr_view_keymap_count = (int)(sizeof mr_view_keymap / sizeof mr_view_keymap[0]);

static const char *const k_widget_names[MR_VW_COUNT] = {
    "alpha", "play", "back", "forward", "rate", "seek", "freeze", "snapshot", "mark", "video", "hidden", "ao",
    "ghost", "help", "note1", "note2", "note3", "note4", "note5", "note6", "cancel",
    "measure",
};

const char *mr_view_widget_name(mr_view_widget_id id) {
    return (int)id >= 0 && id < MR_VW_COUNT ? k_widget_names[id] : "";
}

/* ---------------------------------------------------------------- layout */

/* The column's i-th widget in priority order: Measure right
 * after Mark, then the rest as they are numbered. */
static mr_view_widget_id column_widget(int i) {
    const int after_mark = MR_VW_MARK - MR_VW_FREEZE + 1;
    return i < after_mark ? (mr_view_widget_id)(MR_VW_FREEZE + i)
           : i == after_mark ? MR_VW_MEASURE : (mr_view_widget_id)(MR_VW_FREEZE + i - 1);
}

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
    const int n = MR_VW_HELP - MR_VW_FREEZE + 1 + 1 /* Measure */;
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
        float w = fminf(full.w - 2 * g, 2 * colw + 3 * g), h = (T + g) * ((MR_VIEW_NOTE_COUNT + 1) / 2 + 2) + g;
        float px = p->mark_x < full.x + full.w * 0.5f ? full.x + full.w - w - g : full.x + g;
        if (full.w < 2 * w) px = full.x + (full.w - w) / 2;
        L->notes = mr_ui_rect_make(px, full.y + (full.h - h) / 2, w, h);
        mr_ui_rect in = mr_ui_rect_inset(L->notes, g);
        mr_ui_cut_top(&in, T); /* the question */
        float bw = (in.w - g) / 2;
        bool fits = h <= full.h && w > 0 && bw + 1e-3f >= T;
        for (int i = 0; i <= MR_VIEW_NOTE_COUNT; i++) {
            mr_ui_rect b = i < MR_VIEW_NOTE_COUNT
                               ? mr_ui_rect_make(in.x + (i % 2) * (bw + g), in.y + (i / 2) * (T + g), bw, T)
                               : mr_ui_rect_make(in.x, in.y + ((MR_VIEW_NOTE_COUNT + 1) / 2) * (T + g), in.w, T);
            if (fits) place(L, (mr_view_widget_id)(MR_VW_NOTE1 + i), b, T, p);
            else L->dropped++;
        }
        if (!fits) L->notes = mr_ui_rect_make(full.x, full.y, full.w, fminf(full.h, T + 2 * g));
    }
    L->picture = full;
}

/* --------------------------------------------------- tracking-lost policy */

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
static void next_ao(mr_viewer *v, mr_view_actions *out) {
    v->s.ao = (mr_ao_method)mr_opt_enum_next(mr_opt_find(mr_view_settings_opts, "ao"), (int)v->s.ao);
    changed(v, out);
}

static void next_ghost(mr_viewer *v, mr_view_actions *out) {
    v->s.ghost = (mr_ghost_mode)mr_opt_enum_next(mr_opt_find(mr_view_settings_opts, "ghost"), (int)v->s.ghost);
    changed(v, out);
}

static void next_shadows(mr_viewer *v, mr_view_actions *out) {
    v->s.shadows = (mr_shadow_method)mr_opt_enum_next(mr_opt_find(mr_view_settings_opts, "shadows"), (int)v->s.shadows);
    changed(v, out);
}

static void mark_at(mr_viewer *v, double x, double y, mr_view_actions *out) {
    mr_view_action *a = vw_emit(out, MR_VA_MARK_AT);
    a->x = x;
    a->y = y;
}

static void finish_mark(mr_viewer *v, int note, mr_view_actions *out) {
    v->note_open = false;
    v->mark_mode = false;
    vw_emit(out, MR_VA_MARK_FINISH)->i = note;
}

static void on_key(mr_viewer *v, int k, mr_view_actions *out) {
    if (v->note_open) {
        if (k >= '1' && k < '1' + MR_VIEW_NOTE_COUNT) finish_mark(v, k - '1', out);
        else if (k == MR_KEY_ESCAPE || k == 'q') finish_mark(v, -1, out);
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
    case 'a': next_ao(v, out); break;
    case 'g': next_ghost(v, out); break;
    case 'c': next_shadows(v, out); break;
    case ' ': toggle_play(v, out); break;
    case '.': case MR_KEY_RIGHT: step(v, 1, out); break;
    case ',': case MR_KEY_LEFT: step(v, -1, out); break;
    case MR_KEY_HOME: vw_emit(out, MR_VA_SEEK)->i = 0; break;
    case MR_KEY_END: vw_emit(out, MR_VA_SEEK)->i = INT64_MAX / 2; break;
    case '[': set_rate(v, v->s.rate_i - 1, out); break;
    case ']': set_rate(v, v->s.rate_i + 1, out); break;
    case MR_KEY_F11: vw_emit(out, MR_VA_FULLSCREEN); break;
    case MR_KEY_ESCAPE:
        if (v->measure_mode) vw_measure_cancel(v);
        else if (v->mark_mode) v->mark_mode = false;
        else vw_emit(out, MR_VA_QUIT);
        break;
    case 'q': vw_emit(out, MR_VA_QUIT); break;
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

static void status_line(mr_viewer *v, const mr_viewer_frame *f) {
    char line[512], track[128], src[160], here[48] = "";
    if (!f->have_frame) snprintf(track, sizeof track, "no frame");
    else if (f->pose_valid)
        snprintf(track, sizeof track, "tracking: %d tags, %.2f px", f->tags_seen < 0 ? 0 : f->tags_seen,
                 f->rms_px < 0 ? 0.0 : f->rms_px);
    else snprintf(track, sizeof track, "TRACKING LOST (%d tags)", f->tags_seen < 0 ? 0 : f->tags_seen);
    if (f->seekable && f->have_frame)
        snprintf(src, sizeof src, "replay %lld/%lld %s %gx", (long long)f->index + 1, (long long)f->count,
                 f->playing ? "playing" : "paused", mr_view_rates[v->s.rate_i]);
    else snprintf(src, sizeof src, "%.150s", f->source_desc ? f->source_desc : "");
    /* The registration's σ where the planner looks ("+/-": the UI font is
     * printable ASCII only); "?" when the pose has
     * no covariance (an older recording) or nothing is under the centre. */
    v->sigma_known = f->have_frame && f->have_pose && mr_view_sigma_here(f, &v->sigma_m);
    if (!v->sigma_known) v->sigma_m = NAN;
    if (f->have_frame && f->have_pose) {
        double mm = v->sigma_m * 1e3;
        if (!v->sigma_known) snprintf(here, sizeof here, " | +/- ? mm here");
        else snprintf(here, sizeof here, mm < 9.95 ? " | +/- %.1f mm here" : " | +/- %.0f mm here", mm);
    }
    snprintf(line, sizeof line, "%s%s | %s%s | %.1f fps | %.200s", v->frozen ? "FROZEN | " : "", src, track, here,
             f->fps, v->passes[0] ? v->passes : "-");
    snprintf(v->status, sizeof v->status, "%s", line);
    mr_view_sigma_state st = mr_view_sigma_classify(v->sigma_known, v->sigma_m);
    uint32_t col = MR_UI_RGBA(235, 240, 245, 255);
    if (f->have_frame && !f->pose_valid) col = MR_UI_RGBA(255, 150, 120, 255);
    else if (st == MR_VIEW_SIGMA_BAD) col = MR_UI_RGBA(255, 120, 100, 255);
    else if (st == MR_VIEW_SIGMA_WARN) col = MR_UI_RGBA(255, 210, 110, 255);
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
    snprintf(lab, sizeof lab, "frame %lld", (long long)(f->have_frame ? f->index + 1 : 0));
    if (mr_ui_slider(v->ui, 2, L->rect[MR_VW_SEEK], lab, &pos, 0.0f, (float)(count > 1 ? count - 1 : 1))) {
        int64_t want = (int64_t)lroundf(pos);
        if (!f->have_frame || want != f->index) seek(v, want, out);
    }
}

static void column(mr_viewer *v, mr_view_actions *out) {
    char ao_label[32], ghost_label[32];
    snprintf(ao_label, sizeof ao_label, "AO %s", mr_ao_method_name(v->s.ao));
    snprintf(ghost_label, sizeof ghost_label, "Ghost %s", mr_view_ghost_name(v->s.ghost));
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
    if (button(v, MR_VW_AO, ao_label, v->s.ao != MR_AO_NONE)) next_ao(v, out);
    if (button(v, MR_VW_GHOST, ghost_label, v->s.ghost != MR_GHOST_OFF)) next_ghost(v, out);
    if (button(v, MR_VW_HELP, "?", v->help)) v->help = !v->help;
}

/* Messages over the picture, failures first; the toast at the bottom. */
static void messages(mr_viewer *v, const mr_viewer_frame *f) {
    mr_ui *ui = v->ui;
    float g = mr_ui_mm(ui, 1.2f), th = mr_ui_text_px(ui);
    mr_ui_rect area = v->lay.picture;
    const char *banners[5];
    uint32_t colors[5];
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
    if (v->measure_mode) {
        vw_measure_banner(v, measure_banner, sizeof measure_banner);
        banners[nb] = measure_banner;
        colors[nb++] = MR_UI_RGBA(30, 120, 190, 230);
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

/* The note chooser and the cross of the mark being made. */
static void notes(mr_viewer *v, const mr_viewer_frame *f, mr_view_actions *out) {
    mr_ui *ui = v->ui;
    const mr_view_layout *L = &v->lay;
    float T = mr_ui_target_px(ui), g = mr_ui_mm(ui, 1.2f);
    mr_ui_panel(ui, L->notes);
    mr_ui_panel(ui, L->notes); /* darker */
    mr_ui_rect in = mr_ui_rect_inset(L->notes, g);
    mr_ui_label(ui, mr_ui_cut_top(&in, T), L->shown[MR_VW_NOTE1] ? "What differs here?" : "What differs? keys 1..6",
                MR_UI_RGBA(255, 255, 255, 255), true);
    for (int i = 0; i < MR_VIEW_NOTE_COUNT; i++) {
        char lb[48];
        snprintf(lb, sizeof lb, "%d %s", i + 1, mr_view_notes[i]);
        if (L->shown[MR_VW_NOTE1 + i] && mr_ui_button(ui, (uint32_t)(60 + i), L->rect[MR_VW_NOTE1 + i], lb, MR_UI_NORMAL))
            finish_mark(v, i, out);
    }
    if (L->shown[MR_VW_CANCEL] && mr_ui_button(ui, 70, L->rect[MR_VW_CANCEL], "Cancel", MR_UI_NORMAL))
        finish_mark(v, -1, out);
    if (!f->have_image) return;
    mr_ui_rect ir = f->image_rect;
    float x = ir.x + v->mark_u * ir.w, y = ir.y + v->mark_v * ir.h;
    float s = mr_ui_mm(ui, 3), t = fmaxf(2, mr_ui_mm(ui, 0.4f));
    mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(x - s, y - t / 2, 2 * s, t), MR_UI_RGBA(255, 60, 60, 255));
    mr_ui_draw_rect(mr_ui_list(ui), mr_ui_rect_make(x - t / 2, y - s, t, 2 * s), MR_UI_RGBA(255, 60, 60, 255));
}

static void help_panel(mr_viewer *v) {
    mr_ui *ui = v->ui;
    float g = mr_ui_mm(ui, 1.2f), th = mr_ui_text_px(ui), lh = th * 1.35f;
    mr_ui_rect full = v->lay.picture;
    float w = fminf(full.w - 2 * g, mr_ui_mm(ui, 120)), h = fminf(full.h, lh * (mr_view_keymap_count + 1) + 2 * g);
    mr_ui_rect p = mr_ui_rect_make(full.x + (full.w - w) / 2, full.y + (full.h - h) / 2, w, h);
    /* The whole panel is one button: a tap anywhere closes it. */
    if (mr_ui_button(ui, 80, p, "", MR_UI_NORMAL)) v->help = false;
    mr_ui_panel(ui, p);
    mr_ui_rect in = mr_ui_rect_inset(p, g);
    mr_ui_label(ui, mr_ui_cut_top(&in, lh), "Keys (tap or press ? to close)", MR_UI_RGBA(255, 220, 150, 255), false);
    for (int i = 0; i < mr_view_keymap_count && in.h >= lh; i++) {
        mr_ui_rect row = mr_ui_cut_top(&in, lh);
        mr_ui_rect k = mr_ui_cut_left(&row, fminf(row.w * 0.3f, mr_ui_mm(ui, 30)));
        mr_ui_label(ui, k, mr_view_keymap[i].keys, MR_UI_RGBA(150, 200, 255, 255), false);
        mr_ui_label(ui, row, mr_view_keymap[i].what, MR_UI_RGBA(235, 240, 245, 255), false);
    }
}

const mr_ui_draw_list *mr_viewer_ui(mr_viewer *v, const mr_viewer_frame *f, mr_view_actions *out) {
    v->now = f->now;
    if (f->px_per_mm > 0 && fabs(f->px_per_mm - mr_ui_px_per_mm(v->ui)) > 1e-6) mr_ui_set_density(v->ui, f->px_per_mm);
    v->f = *f;
    snprintf(v->passes, sizeof v->passes, "%s", f->passes ? f->passes : "");
    v->f.source_desc = v->f.source_msg = v->f.scene_msg = v->f.passes = NULL;

    mr_view_layout_params lp = {f->fb_w, f->fb_h, f->seekable, v->note_open,
                                f->image_rect.x + v->mark_u * f->image_rect.w};
    mr_view_layout_compute(v->ui, &lp, &v->lay);
    mr_ui_input in = v->input;
    mr_ui_begin(v->ui, &in);
    mr_ui_panel(v->ui, v->lay.status);
    status_line(v, f);
    bottom_bar(v, f, out);
    column(v, out);
    messages(v, f);
    if (v->note_open) notes(v, f, out);
    vw_measure_draw(v, f);
    if (v->help) help_panel(v);
    float tx, ty;
    const mr_ui_draw_list *dl = mr_ui_end(v->ui);
    if (mr_ui_scene_tap(v->ui, &tx, &ty)) {
        if (v->help) v->help = false;
        else if (v->mark_mode && !v->note_open) mark_at(v, tx, ty, out);
        else if (v->measure_mode && !v->note_open) vw_measure_tap(v, f, tx, ty);
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
    cJSON_AddStringToObject(j, "ao", mr_ao_method_name(v->s.ao));
    cJSON_AddStringToObject(j, "ghost", mr_view_ghost_name(v->s.ghost));
    cJSON_AddStringToObject(j, "shadows", mr_shadow_method_names[(int)v->s.shadows >= 0 && v->s.shadows < MR_SHADOW_METHOD_COUNT ? v->s.shadows : 0]);
    cJSON_AddBoolToObject(j, "frozen", v->frozen);
    cJSON_AddBoolToObject(j, "mark_mode", v->mark_mode);
    cJSON_AddBoolToObject(j, "help", v->help);
    cJSON_AddStringToObject(j, "passes", v->passes);
    cJSON_AddBoolToObject(j, "have_frame", v->f.have_frame);
    cJSON_AddNumberToObject(j, "frame_index", v->f.have_frame ? (double)v->f.index : -1);
    cJSON_AddBoolToObject(j, "pose_valid", v->f.have_frame && v->f.pose_valid);
    cJSON_AddNumberToObject(j, "tags_seen", v->f.have_frame ? v->f.tags_seen : -1);
    cJSON_AddBoolToObject(j, "tracking_lost_dimmed", v->f.dimmed);
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
