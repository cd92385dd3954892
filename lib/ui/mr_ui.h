/* mr_ui.h — the touch UI: a font (stb_truetype, a system TrueType file),
 * immediate-mode widgets (button, toggle, slider, label), hit-testing and
 * layout in millimetres, and the draw list they produce. No GL here: the
 * draw list is plain data (vertices, indices, one 8-bit atlas) that
 * lib/render draws; app/ hands it over.
 *
 * Coordinates are framebuffer pixels, origin top-left, x right, y down.
 * Sizes are given in millimetres and turned into pixels with the screen's
 * density (px_per_mm), so a 9 mm target is 9 mm under a finger on any
 * screen.
 *
 * Input is one pointer (mouse or a touch point; a touch screen reaches us
 * as an emulated pointer) plus keys handled by the caller. A widget acts on
 * release over itself after a press on itself, as touch users expect (a
 * finger that slides off cancels); a slider follows the pointer while held.
 */
#ifndef MR_UI_H
#define MR_UI_H

#include "mr_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------ font */

typedef struct mr_ui_font mr_ui_font;

typedef struct mr_ui_font_params {
    const char *path;      /* TrueType file; NULL = find a system sans font */
    float pixel_height;    /* baked glyph height in pixels; 0 = default 20 */
} mr_ui_font_params;
#define MR_UI_FONT_DEFAULTS {NULL, 0.0f}

/* Finds a system sans-serif TrueType font: $MR_FONT, a list of well-known
 * paths (DejaVu, Liberation, Noto, FreeFont), then fontconfig's fc-match if
 * it is installed. false + err (MR_ERR_IO) if none exists. */
bool mr_ui_font_find(char *out, size_t n, mr_error *err);
/* Loads the font and bakes printable ASCII (32..126) into an 8-bit atlas
 * whose texel (0,0) is opaque white, so solid shapes and text share one
 * texture and one draw call. */
mr_ui_font *mr_ui_font_create(const mr_ui_font_params *params, mr_error *err);
void mr_ui_font_destroy(mr_ui_font **font);
float mr_ui_font_height(const mr_ui_font *font);   /* baked pixel height */
/* Width in pixels of text drawn at `height` pixels (scaled from the bake). */
float mr_ui_text_width(const mr_ui_font *font, const char *text, float height);

/* ------------------------------------------------------------ draw list */

/* One vertex: position in framebuffer pixels, atlas coordinates in [0,1],
 * colour as 0xAABBGGRR (bytes R,G,B,A in memory), sRGB, straight alpha. */
typedef struct mr_ui_vertex {
    float x, y, u, v;
    uint32_t rgba;
} mr_ui_vertex;

typedef struct mr_ui_draw_list {
    mr_ui_vertex *vertices;
    int vertex_count, vertex_cap;
    uint32_t *indices;          /* triangles */
    int index_count, index_cap;
    const uint8_t *atlas;       /* atlas_w * atlas_h alpha values */
    int atlas_w, atlas_h;
    uint32_t atlas_version;     /* changes when the atlas is rebaked */
    float white_u, white_v;     /* an opaque atlas texel, for solid shapes */
} mr_ui_draw_list;

#define MR_UI_RGBA(r, g, b, a) ((uint32_t)(r) | (uint32_t)(g) << 8 | (uint32_t)(b) << 16 | (uint32_t)(a) << 24)

typedef struct mr_ui_rect { float x, y, w, h; } mr_ui_rect;

static inline mr_ui_rect mr_ui_rect_make(float x, float y, float w, float h) {
    mr_ui_rect r = {x, y, w, h};
    return r;
}
/* Half-open: x <= px < x + w (so adjacent rects never both claim a pixel). */
bool mr_ui_rect_contains(mr_ui_rect r, float px, float py);
/* Grown by d on every side (negative shrinks, never below zero size). */
mr_ui_rect mr_ui_rect_inset(mr_ui_rect r, float d);
/* RectCut layout: takes a strip of size a off one side of *r and returns
 * it; *r keeps the rest (sizes clamp to what is there). */
mr_ui_rect mr_ui_cut_left(mr_ui_rect *r, float a);
mr_ui_rect mr_ui_cut_right(mr_ui_rect *r, float a);
mr_ui_rect mr_ui_cut_top(mr_ui_rect *r, float a);
mr_ui_rect mr_ui_cut_bottom(mr_ui_rect *r, float a);
/* The largest rect of aspect w/h centred in `area` (letterboxing). */
mr_ui_rect mr_ui_fit(mr_ui_rect area, double w, double h);

/* Low-level drawing into a list (used by the widgets; also by the app for
 * markers). Grows the arrays; false only when out of memory. */
bool mr_ui_draw_rect(mr_ui_draw_list *dl, mr_ui_rect r, uint32_t rgba);
bool mr_ui_draw_frame(mr_ui_draw_list *dl, mr_ui_rect r, float thickness, uint32_t rgba);
/* Text with its top-left at (x, y), `height` pixels tall. */
bool mr_ui_draw_text(mr_ui_draw_list *dl, const mr_ui_font *font, float x, float y, float height, const char *text,
                     uint32_t rgba);
void mr_ui_draw_list_clear(mr_ui_draw_list *dl);
void mr_ui_draw_list_free(mr_ui_draw_list *dl);

/* ------------------------------------------------------------- widgets */

typedef struct mr_ui mr_ui;

typedef struct mr_ui_params {
    const mr_ui_font *font;     /* required, outlives the ui */
    double px_per_mm;           /* screen density; 0 = 96 dpi (3.78 px/mm) */
    float min_target_mm;        /* smallest touch target, default 9 mm */
    float text_mm;              /* text cap-to-descender height, default 3.2 mm */
} mr_ui_params;
#define MR_UI_DEFAULTS {NULL, 0.0, 0.0f, 0.0f}

/* The pointer as the frame starts. Feed at most one press or release per
 * frame (queue the rest) so a quick tap is never lost between frames. */
typedef struct mr_ui_input {
    float x, y;                 /* framebuffer pixels */
    bool down;                  /* button or finger down */
    bool inside;                /* pointer over the window */
} mr_ui_input;

mr_ui *mr_ui_create(const mr_ui_params *params, mr_error *err);
void mr_ui_destroy(mr_ui **ui);
void mr_ui_set_density(mr_ui *ui, double px_per_mm);
double mr_ui_px_per_mm(const mr_ui *ui);
float mr_ui_mm(const mr_ui *ui, float mm);        /* millimetres -> pixels */
float mr_ui_target_px(const mr_ui *ui);           /* min_target_mm in pixels */
float mr_ui_text_px(const mr_ui *ui);             /* text height in pixels */
const mr_ui_font *mr_ui_get_font(const mr_ui *ui);

void mr_ui_begin(mr_ui *ui, const mr_ui_input *in);
/* The finished draw list, valid until the next mr_ui_begin. */
const mr_ui_draw_list *mr_ui_end(mr_ui *ui);
mr_ui_draw_list *mr_ui_list(mr_ui *ui);

/* Widget state shown by a button. */
typedef enum mr_ui_style { MR_UI_NORMAL = 0, MR_UI_ON = 1, MR_UI_ACCENT = 2, MR_UI_DISABLED = 3 } mr_ui_style;

/* Ids tell widgets apart across frames: any non-zero number stable for the
 * widget (e.g. its key or an enum). */
bool mr_ui_button(mr_ui *ui, uint32_t id, mr_ui_rect r, const char *label, mr_ui_style style);
/* Flips *value on a tap; returns true when it changed. */
bool mr_ui_toggle(mr_ui *ui, uint32_t id, mr_ui_rect r, const char *label, bool *value);
/* Horizontal slider over [lo, hi]; returns true while the value changes. */
bool mr_ui_slider(mr_ui *ui, uint32_t id, mr_ui_rect r, const char *label, float *value, float lo, float hi);
/* Text vertically centred in r, left-aligned (or centred when `center`). */
void mr_ui_label(mr_ui *ui, mr_ui_rect r, const char *text, uint32_t rgba, bool center);
/* A translucent panel behind a group of widgets; blocks taps from reaching
 * the scene below. */
void mr_ui_panel(mr_ui *ui, mr_ui_rect r);

/* Slider math, exposed for tests: the track is r shrunk by half a knob on
 * each side; x maps linearly onto [lo, hi] and clamps. */
float mr_ui_slider_value(const mr_ui *ui, mr_ui_rect r, float x, float lo, float hi);
float mr_ui_slider_knob_x(const mr_ui *ui, mr_ui_rect r, float value, float lo, float hi);

/* True if the pointer is over a widget or panel drawn this frame, or a
 * widget holds it: the caller must not treat the tap as a tap on the scene. */
bool mr_ui_captured(const mr_ui *ui);
/* The pointer was released this frame over no widget or panel after a
 * press that also hit none: a tap on the scene, at *x, *y. */
bool mr_ui_scene_tap(const mr_ui *ui, float *x, float *y);
/* Per-frame CPU cost of the widgets and draw list in seconds (begin to end). */
double mr_ui_last_cpu_s(const mr_ui *ui);

#ifdef __cplusplus
}
#endif
#endif
