/* Immediate-mode widgets: the caller describes the UI every frame; the ui
 * keeps only which widget holds the pointer, so there is no widget tree to
 * keep in sync with the app's state. */
#include "ui_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A tap that moves further than this between press and release is a drag
 * (or a finger that slipped), not a tap on the scene. */
#define TAP_SLOP_MM 4.0f

struct mr_ui {
    mr_ui_params p;
    mr_ui_draw_list dl;
    mr_ui_input in, prev;
    bool pressed, released;    /* edges this frame */
    uint32_t active;           /* widget holding the pointer (pressed on it) */
    bool over_ui;              /* pointer over a widget or panel this frame */
    bool press_on_ui;          /* the current/last press started on the UI */
    bool press_seen;           /* a press happened since the ui was created */
    float press_x, press_y;
    bool scene_tap;
    float tap_x, tap_y;
    double t_begin, cpu_s;
};

mr_ui *mr_ui_create(const mr_ui_params *params, mr_error *err) {
    if (!params || !params->font) {
        mr_fail(err, MR_ERR_INVALID, "the UI needs a font");
        return NULL;
    }
    mr_ui *ui = calloc(1, sizeof *ui);
    if (!ui) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    ui->p = *params;
    if (!(ui->p.px_per_mm > 0)) ui->p.px_per_mm = 96.0 / 25.4;
    if (!(ui->p.min_target_mm > 0)) ui->p.min_target_mm = 9.0f;
    if (!(ui->p.text_mm > 0)) ui->p.text_mm = 3.2f;
    int aw, ah;
    mr_ui_font_internal(ui->p.font, &ui->dl.atlas, &aw, &ah, &ui->dl.white_u, &ui->dl.white_v);
    ui->dl.atlas_w = aw;
    ui->dl.atlas_h = ah;
    ui->dl.atlas_version = 1;
    return ui;
}

void mr_ui_destroy(mr_ui **up) {
    if (!up || !*up) return;
    mr_ui_draw_list_free(&(*up)->dl);
    free(*up);
    *up = NULL;
}

void mr_ui_set_density(mr_ui *ui, double px_per_mm) {
    if (px_per_mm > 0 && isfinite(px_per_mm)) ui->p.px_per_mm = px_per_mm;
}
double mr_ui_px_per_mm(const mr_ui *ui) { return ui->p.px_per_mm; }
float mr_ui_mm(const mr_ui *ui, float mm) { return (float)(mm * ui->p.px_per_mm); }
float mr_ui_target_px(const mr_ui *ui) { return ceilf(mr_ui_mm(ui, ui->p.min_target_mm)); }
float mr_ui_text_px(const mr_ui *ui) { return roundf(mr_ui_mm(ui, ui->p.text_mm)); }
const mr_ui_font *mr_ui_get_font(const mr_ui *ui) { return ui->p.font; }
mr_ui_draw_list *mr_ui_list(mr_ui *ui) { return &ui->dl; }

void mr_ui_begin(mr_ui *ui, const mr_ui_input *in) {
    ui->t_begin = mr_time_now();
    ui->prev = ui->in;
    ui->in = *in;
    ui->pressed = in->down && !ui->prev.down;
    ui->released = !in->down && ui->prev.down;
    ui->over_ui = false;
    ui->scene_tap = false;
    if (ui->pressed) {
        ui->press_x = in->x;
        ui->press_y = in->y;
        ui->press_seen = true;
    }
    mr_ui_draw_list_clear(&ui->dl);
}

const mr_ui_draw_list *mr_ui_end(mr_ui *ui) {
    if (ui->pressed) ui->press_on_ui = ui->over_ui;
    if (ui->released) {
        float dx = ui->in.x - ui->press_x, dy = ui->in.y - ui->press_y;
        float slop = mr_ui_mm(ui, TAP_SLOP_MM);
        if (ui->press_seen && !ui->press_on_ui && !ui->over_ui && ui->active == 0 && dx * dx + dy * dy <= slop * slop) {
            ui->scene_tap = true;
            ui->tap_x = ui->in.x;
            ui->tap_y = ui->in.y;
        }
        ui->active = 0;
    }
    ui->cpu_s = mr_time_now() - ui->t_begin;
    return &ui->dl;
}

bool mr_ui_captured(const mr_ui *ui) { return ui->over_ui || ui->active != 0; }

bool mr_ui_scene_tap(const mr_ui *ui, float *x, float *y) {
    if (!ui->scene_tap) return false;
    if (x) *x = ui->tap_x;
    if (y) *y = ui->tap_y;
    return true;
}

double mr_ui_last_cpu_s(const mr_ui *ui) { return ui->cpu_s; }

/* Registers r as UI for this frame; true if the pointer is over it. */
static bool hover(mr_ui *ui, mr_ui_rect r) {
    bool over = ui->in.inside && mr_ui_rect_contains(r, ui->in.x, ui->in.y);
    /* A release outside the window still counts at its last position. */
    if (!ui->in.inside && ui->released) over = mr_ui_rect_contains(r, ui->in.x, ui->in.y);
    if (over) ui->over_ui = true;
    return over;
}

#define C_TEXT MR_UI_RGBA(245, 247, 250, 255)
#define C_TEXT_DIM MR_UI_RGBA(150, 155, 160, 255)
#define C_PANEL MR_UI_RGBA(18, 22, 26, 165)
#define C_BTN MR_UI_RGBA(48, 54, 62, 225)
#define C_BTN_HOT MR_UI_RGBA(68, 76, 88, 235)
#define C_BTN_DOWN MR_UI_RGBA(96, 112, 136, 245)
#define C_ON MR_UI_RGBA(28, 118, 204, 240)
#define C_ON_HOT MR_UI_RGBA(48, 138, 224, 245)
#define C_ACCENT MR_UI_RGBA(214, 120, 28, 240)
#define C_BORDER MR_UI_RGBA(255, 255, 255, 60)

/* Text that does not fit first shrinks (down to 80 %, still legible at
 * arm's length), then is cut with "..." so it never spills over its
 * neighbours. */
void mr_ui_label(mr_ui *ui, mr_ui_rect r, const char *text, uint32_t rgba, bool center) {
    float th = mr_ui_text_px(ui), pad = mr_ui_mm(ui, 1.0f);
    float avail = r.w - 2 * pad;
    float w = mr_ui_text_width(ui->p.font, text, th);
    char buf[512];
    if (w > avail && avail > 0) {
        float s = avail / w;
        if (s >= 0.8f) {
            th *= s;
        } else {
            th *= 0.8f;
            size_t n = strlen(text);
            if (n > sizeof buf - 4) n = sizeof buf - 4;
            while (n > 0) {
                memcpy(buf, text, n);
                memcpy(buf + n, "...", 4);
                if (mr_ui_text_width(ui->p.font, buf, th) <= avail) break;
                n--;
            }
            if (n == 0) snprintf(buf, sizeof buf, "...");
            text = buf;
        }
        w = mr_ui_text_width(ui->p.font, text, th);
    }
    float x = center ? r.x + (r.w - w) * 0.5f : r.x + pad;
    float y = r.y + (r.h - th) * 0.5f;
    mr_ui_draw_text(&ui->dl, ui->p.font, x, y, th, text, rgba);
}

void mr_ui_panel(mr_ui *ui, mr_ui_rect r) {
    hover(ui, r);
    mr_ui_draw_rect(&ui->dl, r, C_PANEL);
}

bool mr_ui_button(mr_ui *ui, uint32_t id, mr_ui_rect r, const char *label, mr_ui_style style) {
    bool over = hover(ui, r);
    bool enabled = style != MR_UI_DISABLED;
    if (enabled && ui->pressed && over) ui->active = id;
    bool clicked = enabled && ui->released && ui->active == id && over;
    bool held = ui->active == id && ui->in.down;
    uint32_t bg = style == MR_UI_ON ? (over ? C_ON_HOT : C_ON)
                  : style == MR_UI_ACCENT ? C_ACCENT
                  : held ? C_BTN_DOWN
                  : over && enabled ? C_BTN_HOT
                  : C_BTN;
    if (held && style != MR_UI_NORMAL) bg = C_BTN_DOWN;
    mr_ui_draw_rect(&ui->dl, r, bg);
    mr_ui_draw_frame(&ui->dl, r, 1.0f, C_BORDER);
    mr_ui_label(ui, r, label, enabled ? C_TEXT : C_TEXT_DIM, true);
    return clicked;
}

bool mr_ui_toggle(mr_ui *ui, uint32_t id, mr_ui_rect r, const char *label, bool *value) {
    if (!mr_ui_button(ui, id, r, label, *value ? MR_UI_ON : MR_UI_NORMAL)) return false;
    *value = !*value;
    return true;
}

/* Half the knob is kept free at each end, so 0 and 1 are as easy to hit as
 * any value in between. */
static float knob_w(const mr_ui *ui, mr_ui_rect r) {
    float k = mr_ui_mm(ui, 4.0f);
    return k * 2 > r.w ? r.w * 0.5f : k;
}

float mr_ui_slider_value(const mr_ui *ui, mr_ui_rect r, float x, float lo, float hi) {
    float k = knob_w(ui, r);
    float span = r.w - k;
    if (!(span > 0)) return lo;
    float t = (x - (r.x + k * 0.5f)) / span;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return lo + t * (hi - lo);
}

float mr_ui_slider_knob_x(const mr_ui *ui, mr_ui_rect r, float value, float lo, float hi) {
    float k = knob_w(ui, r);
    float t = hi != lo ? (value - lo) / (hi - lo) : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return r.x + k * 0.5f + t * (r.w - k);
}

bool mr_ui_slider(mr_ui *ui, uint32_t id, mr_ui_rect r, const char *label, float *value, float lo, float hi) {
    bool over = hover(ui, r);
    if (ui->pressed && over) ui->active = id;
    bool changed = false;
    if (ui->active == id && (ui->in.down || ui->released)) {
        float v = mr_ui_slider_value(ui, r, ui->in.x, lo, hi);
        changed = v != *value;
        *value = v;
    }
    bool held = ui->active == id && ui->in.down;
    mr_ui_draw_rect(&ui->dl, r, held ? C_BTN_HOT : C_BTN);
    float kx = mr_ui_slider_knob_x(ui, r, *value, lo, hi);
    float bar = mr_ui_mm(ui, 1.2f);
    mr_ui_draw_rect(&ui->dl, mr_ui_rect_make(r.x, r.y + (r.h - bar) * 0.5f, kx - r.x, bar), C_ON);
    float k = knob_w(ui, r);
    mr_ui_rect knob = mr_ui_rect_make(kx - k * 0.5f, r.y + 1, k, r.h - 2);
    mr_ui_draw_rect(&ui->dl, knob, held ? C_TEXT : MR_UI_RGBA(220, 225, 232, 255));
    mr_ui_draw_frame(&ui->dl, r, 1.0f, C_BORDER);
    if (label && label[0]) {
        /* The label sits on the side away from the knob, so it stays legible. */
        float th = mr_ui_text_px(ui), tw = mr_ui_text_width(ui->p.font, label, th);
        float pad = mr_ui_mm(ui, 1.5f);
        float x = kx < r.x + r.w * 0.5f ? r.x + r.w - tw - pad : r.x + pad;
        mr_ui_draw_text(&ui->dl, ui->p.font, x, r.y + (r.h - th) * 0.5f, th, label, C_TEXT);
    }
    return changed;
}
