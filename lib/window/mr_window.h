/* mr_window.h — the on-screen window: a GLFW window with an OpenGL 4.5 core
 * context that lib/render draws with, its input events (pointer, touch as an
 * emulated pointer, keys, text) as plain structs, and the 2D layer that
 * shows the renderer's frame and a UI draw list (lib/ui) in it.
 *
 * Depends on: lib/core, lib/render (mr_gpu, mr_renderer: the window wraps
 * its context with mr_gpu_create_current), lib/ui (the draw list's vertex
 * layout). No GLFW or GL type leaves this module; without GLFW in the build
 * mr_window_create fails with one line and the rest are no-ops.
 */
#ifndef MR_WINDOW_H
#define MR_WINDOW_H

#include "mr_core.h"
#include "mr_render.h"
#include "mr_ui.h"

#ifdef __cplusplus
extern "C" {
#endif

/* --------------------------------------------------------------- window */

/* An on-screen window (GLFW, OpenGL 4.5 core) whose context the renderer
 * draws with. Events are queued as plain structs in framebuffer pixels,
 * so the UI never sees a GLFW type, and tests can push their own. */
typedef struct mr_window mr_window;

typedef struct mr_window_params {
    int width, height;        /* window size in screen units; 0 = 960x720 */
    bool fullscreen;          /* the primary monitor at its current mode */
    bool no_vsync;            /* swap without waiting for the display */
    bool debug;               /* GL debug output to the log */
    const char *title;        /* NULL = "mrcheck" */
} mr_window_params;
#define MR_WINDOW_DEFAULT_WIDTH 960
#define MR_WINDOW_DEFAULT_HEIGHT 720
#define MR_WINDOW_DEFAULTS {.width = 0, .height = 0, .title = NULL} /* 0 = the default size */

typedef enum mr_event_type {
    MR_EVENT_NONE = 0,
    MR_EVENT_POINTER_MOVE,    /* x, y */
    MR_EVENT_POINTER_DOWN,    /* x, y: left button or a touch */
    MR_EVENT_POINTER_UP,      /* x, y */
    MR_EVENT_POINTER_LEAVE,
    MR_EVENT_KEY,             /* key: a printable character or MR_KEY_* */
    MR_EVENT_RESIZE,          /* x, y: new framebuffer size */
    MR_EVENT_CLOSE,
} mr_event_type;

enum {
    MR_KEY_ESCAPE = 256, MR_KEY_ENTER, MR_KEY_TAB, MR_KEY_BACKSPACE, MR_KEY_LEFT, MR_KEY_RIGHT, MR_KEY_UP,
    MR_KEY_DOWN, MR_KEY_HOME, MR_KEY_END, MR_KEY_PAGE_UP, MR_KEY_PAGE_DOWN, MR_KEY_F1, MR_KEY_F11,
};

typedef struct mr_event {
    mr_event_type type;
    double x, y;              /* framebuffer pixels, origin top-left */
    int key;
} mr_event;

/* NULL + MR_ERR_NODEVICE if there is no display (no $DISPLAY / Wayland). */
mr_window *mr_window_create(const mr_window_params *params, mr_error *err);
void mr_window_destroy(mr_window **win);
mr_gpu *mr_window_gpu(mr_window *win);
/* Processes window-system events, waiting up to timeout_s (0 = just poll). */
void mr_window_wait(mr_window *win, double timeout_s);
/* Wakes a mr_window_wait from another thread (a new camera frame). */
void mr_window_wake(mr_window *win);
bool mr_window_next_event(mr_window *win, mr_event *ev);
bool mr_window_push_event(mr_window *win, const mr_event *ev);
/* Events queued and not yet taken. */
int mr_window_pending(const mr_window *win);
void mr_window_framebuffer_size(const mr_window *win, int *w, int *h);
/* Framebuffer pixels per millimetre on the window's monitor: the monitor's
 * physical size where it is plausible, else the content scale x 96 dpi. */
double mr_window_px_per_mm(const mr_window *win);
void mr_window_set_fullscreen(mr_window *win, bool on);
bool mr_window_fullscreen(const mr_window *win);
void mr_window_set_size(mr_window *win, int width, int height);
void mr_window_set_title(mr_window *win, const char *title);
void mr_window_swap(mr_window *win);

/* ------------------------------------------------------------ 2D layer */

/* Draws into the window's framebuffer: the renderer's last frame in a
 * rectangle, then a 2D draw list (the touch UI) on top. */
typedef struct mr_draw2d mr_draw2d;

/* Same layout as the UI's vertex (lib/ui), so the app can hand it over. */
typedef struct mr_draw2d_vertex {
    float x, y, u, v;          /* framebuffer pixels; atlas coordinates */
    uint32_t rgba;             /* sRGB, straight alpha, R in the low byte */
} mr_draw2d_vertex;

typedef struct mr_draw2d_list {
    const mr_draw2d_vertex *vertices;
    int vertex_count;
    const uint32_t *indices;   /* triangles */
    int index_count;
    const uint8_t *atlas;      /* 8-bit coverage, atlas_w x atlas_h */
    int atlas_w, atlas_h;
    uint32_t atlas_version;    /* re-uploaded when it changes */
} mr_draw2d_list;

mr_draw2d *mr_draw2d_create(mr_gpu *gpu, mr_error *err);
void mr_draw2d_destroy(mr_draw2d **d);
/* Binds the window framebuffer (fb_w x fb_h) and clears it to an sRGB colour. */
void mr_draw2d_begin(mr_draw2d *d, int fb_w, int fb_h, const float clear_srgb[3]);
/* The renderer's last frame scaled into (x, y, w, h) (pixels, top-left). */
bool mr_draw2d_frame(mr_draw2d *d, mr_renderer *r, float x, float y, float w, float h, mr_error *err);
bool mr_draw2d_list_draw(mr_draw2d *d, const mr_draw2d_list *list, mr_error *err);
/* What is in the framebuffer now (before the swap), RGB8, top row first. */
bool mr_draw2d_read(mr_draw2d *d, mr_image *out, mr_error *err);
/* An 8-bit sRGB image (1, 3 or 4 channels) as a texture of the 2D layer,
 * drawn scaled into a rectangle (the study window's stimuli). */
typedef struct mr_draw2d_image mr_draw2d_image;
mr_draw2d_image *mr_draw2d_image_create(mr_draw2d *d, const mr_image *img, mr_error *err);
void mr_draw2d_image_destroy(mr_draw2d_image **im);
bool mr_draw2d_image_draw(mr_draw2d *d, const mr_draw2d_image *im, float x, float y, float w, float h, mr_error *err);

/* A UI draw list (lib/ui's vertices have the 2D layer's layout) drawn with
 * the 2D layer; an error is logged with `cmd`'s name, not returned. */
void mr_draw2d_ui(mr_draw2d *d, const mr_ui_draw_list *dl, const char *cmd);

#ifdef __cplusplus
}
#endif

#endif
