/* The GLFW window: an OpenGL 4.5 core window whose context the renderer
 * wraps with mr_gpu_create_current. Input arrives through GLFW callbacks
 * and is queued as plain mr_event structs in framebuffer pixels (HiDPI:
 * window coordinates times the framebuffer/window ratio), so nothing
 * outside this file sees GLFW. Touch screens reach X11/Wayland clients as an
 * emulated pointer, which is what the UI is built for. */
#include "mr_window.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef MR_HAVE_GLFW
#include <GLFW/glfw3.h>

#define QUEUE_CAP 512

struct mr_window {
    GLFWwindow *win;
    mr_gpu *gpu;
    mr_event queue[QUEUE_CAP];
    int head, count;
    double last_x, last_y;     /* last pointer position, framebuffer px */
    bool fullscreen;
    int windowed[4];           /* x y w h before going fullscreen */
};

/* GLFW itself is process-wide; count windows so the last one terminates it. */
static int g_windows = 0;

static void scale(const mr_window *w, double *x, double *y) {
    int ww = 0, wh = 0, fw = 0, fh = 0;
    glfwGetWindowSize(w->win, &ww, &wh);
    glfwGetFramebufferSize(w->win, &fw, &fh);
    if (ww > 0 && wh > 0) {
        *x *= (double)fw / ww;
        *y *= (double)fh / wh;
    }
}

bool mr_window_push_event(mr_window *w, const mr_event *ev) {
    if (w->count >= QUEUE_CAP) return false; /* a flood: drop the newest */
    w->queue[(w->head + w->count) % QUEUE_CAP] = *ev;
    w->count++;
    return true;
}

static void push(mr_window *w, mr_event_type t, double x, double y, int key) {
    mr_event e = {t, x, y, key};
    mr_window_push_event(w, &e);
}

static void on_cursor(GLFWwindow *gw, double x, double y) {
    mr_window *w = glfwGetWindowUserPointer(gw);
    scale(w, &x, &y);
    w->last_x = x;
    w->last_y = y;
    /* Coalesce moves: only the newest position matters. */
    if (w->count > 0) {
        mr_event *tail = &w->queue[(w->head + w->count - 1) % QUEUE_CAP];
        if (tail->type == MR_EVENT_POINTER_MOVE) {
            tail->x = x;
            tail->y = y;
            return;
        }
    }
    push(w, MR_EVENT_POINTER_MOVE, x, y, 0);
}

static void on_button(GLFWwindow *gw, int button, int action, int mods) {
    (void)mods;
    mr_window *w = glfwGetWindowUserPointer(gw);
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    double x, y;
    glfwGetCursorPos(gw, &x, &y);
    scale(w, &x, &y);
    push(w, action == GLFW_PRESS ? MR_EVENT_POINTER_DOWN : MR_EVENT_POINTER_UP, x, y, 0);
}

static void on_enter(GLFWwindow *gw, int entered) {
    mr_window *w = glfwGetWindowUserPointer(gw);
    if (!entered) push(w, MR_EVENT_POINTER_LEAVE, w->last_x, w->last_y, 0);
}

/* Printable keys come through the character callback (so '?' is '?' on any
 * keyboard layout); the rest are mapped here. */
static void on_key(GLFWwindow *gw, int key, int scancode, int action, int mods) {
    (void)scancode; (void)mods;
    mr_window *w = glfwGetWindowUserPointer(gw);
    if (action == GLFW_RELEASE) return;
    int k = 0;
    switch (key) {
    case GLFW_KEY_ESCAPE: k = MR_KEY_ESCAPE; break;
    case GLFW_KEY_ENTER: case GLFW_KEY_KP_ENTER: k = MR_KEY_ENTER; break;
    case GLFW_KEY_TAB: k = MR_KEY_TAB; break;
    case GLFW_KEY_BACKSPACE: k = MR_KEY_BACKSPACE; break;
    case GLFW_KEY_LEFT: k = MR_KEY_LEFT; break;
    case GLFW_KEY_RIGHT: k = MR_KEY_RIGHT; break;
    case GLFW_KEY_UP: k = MR_KEY_UP; break;
    case GLFW_KEY_DOWN: k = MR_KEY_DOWN; break;
    case GLFW_KEY_HOME: k = MR_KEY_HOME; break;
    case GLFW_KEY_END: k = MR_KEY_END; break;
    case GLFW_KEY_PAGE_UP: k = MR_KEY_PAGE_UP; break;
    case GLFW_KEY_PAGE_DOWN: k = MR_KEY_PAGE_DOWN; break;
    case GLFW_KEY_F1: k = MR_KEY_F1; break;
    case GLFW_KEY_F11: k = MR_KEY_F11; break;
    default: return;
    }
    push(w, MR_EVENT_KEY, w->last_x, w->last_y, k);
}

static void on_char(GLFWwindow *gw, unsigned int cp) {
    mr_window *w = glfwGetWindowUserPointer(gw);
    if (cp >= 32 && cp < 127) push(w, MR_EVENT_KEY, w->last_x, w->last_y, (int)cp);
}

static void on_fb_size(GLFWwindow *gw, int fw, int fh) {
    mr_window *w = glfwGetWindowUserPointer(gw);
    push(w, MR_EVENT_RESIZE, fw, fh, 0);
}

static void on_close(GLFWwindow *gw) {
    mr_window *w = glfwGetWindowUserPointer(gw);
    push(w, MR_EVENT_CLOSE, 0, 0, 0);
}

static void on_glfw_error(int code, const char *msg) { mr_log(MR_LOG_DEBUG, "GLFW error 0x%x: %s", code, msg); }

mr_window *mr_window_create(const mr_window_params *params, mr_error *err) {
    mr_window_params p = MR_WINDOW_DEFAULTS;
    if (params) p = *params;
    if (p.width <= 0) p.width = MR_WINDOW_DEFAULT_WIDTH;
    if (p.height <= 0) p.height = MR_WINDOW_DEFAULT_HEIGHT;
    if (g_windows == 0) {
        glfwSetErrorCallback(on_glfw_error);
        if (!glfwInit()) {
            const char *d = getenv("DISPLAY"), *wl = getenv("WAYLAND_DISPLAY");
            mr_fail(err, MR_ERR_NODEVICE, "cannot open a window: no display (%s)",
                    (d && d[0]) || (wl && wl[0]) ? "the display server refused" : "DISPLAY is not set");
            return NULL;
        }
    }
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_TRUE);
    glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, p.debug ? GLFW_TRUE : GLFW_FALSE);
    GLFWmonitor *mon = NULL;
    int w = p.width, h = p.height;
    if (p.fullscreen && (mon = glfwGetPrimaryMonitor())) {
        const GLFWvidmode *m = glfwGetVideoMode(mon);
        if (m) { w = m->width; h = m->height; }
    }
    mr_window *win = calloc(1, sizeof *win);
    if (!win) {
        if (g_windows == 0) glfwTerminate();
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    win->win = glfwCreateWindow(w, h, p.title ? p.title : "mrcheck", mon, NULL);
    if (!win->win) {
        free(win);
        if (g_windows == 0) glfwTerminate();
        mr_fail(err, MR_ERR_NODEVICE, "cannot create an OpenGL 4.5 core window");
        return NULL;
    }
    g_windows++;
    win->fullscreen = mon != NULL;
    glfwSetWindowUserPointer(win->win, win);
    glfwMakeContextCurrent(win->win);
    glfwSwapInterval(p.no_vsync ? 0 : 1);
    glfwSetCursorPosCallback(win->win, on_cursor);
    glfwSetMouseButtonCallback(win->win, on_button);
    glfwSetCursorEnterCallback(win->win, on_enter);
    glfwSetKeyCallback(win->win, on_key);
    glfwSetCharCallback(win->win, on_char);
    glfwSetFramebufferSizeCallback(win->win, on_fb_size);
    glfwSetWindowCloseCallback(win->win, on_close);
    mr_gpu_params gp = MR_GPU_DEFAULTS;
    gp.debug = p.debug;
    win->gpu = mr_gpu_create_current(&gp, err);
    if (!win->gpu) {
        mr_window_destroy(&win);
        return NULL;
    }
    mr_log(MR_LOG_INFO, "window: %s", mr_gpu_description(win->gpu));
    return win;
}

void mr_window_destroy(mr_window **wp) {
    if (!wp || !*wp) return;
    mr_window *w = *wp;
    mr_gpu_destroy(&w->gpu);
    glfwDestroyWindow(w->win);
    if (--g_windows == 0) glfwTerminate();
    free(w);
    *wp = NULL;
}

mr_gpu *mr_window_gpu(mr_window *w) { return w->gpu; }

void mr_window_wait(mr_window *w, double timeout_s) {
    (void)w;
    if (timeout_s > 0) glfwWaitEventsTimeout(timeout_s);
    else glfwPollEvents();
}

void mr_window_wake(mr_window *w) {
    (void)w;
    glfwPostEmptyEvent();
}

bool mr_window_next_event(mr_window *w, mr_event *ev) {
    if (w->count == 0) return false;
    *ev = w->queue[w->head];
    w->head = (w->head + 1) % QUEUE_CAP;
    w->count--;
    return true;
}

void mr_window_framebuffer_size(const mr_window *w, int *fw, int *fh) { glfwGetFramebufferSize(w->win, fw, fh); }

int mr_window_pending(const mr_window *w) { return w->count; }

double mr_window_px_per_mm(const mr_window *w) {
    int ww = 0, wh = 0, fw = 0, fh = 0;
    glfwGetWindowSize(w->win, &ww, &wh);
    glfwGetFramebufferSize(w->win, &fw, &fh);
    double fb_ratio = ww > 0 ? (double)fw / ww : 1.0;
    GLFWmonitor *mon = glfwGetWindowMonitor(w->win);
    if (!mon) mon = glfwGetPrimaryMonitor();
    double from_size = 0;
    if (mon) {
        int mm_w = 0, mm_h = 0;
        glfwGetMonitorPhysicalSize(mon, &mm_w, &mm_h);
        const GLFWvidmode *m = glfwGetVideoMode(mon);
        if (m && mm_w > 0) from_size = (double)m->width / mm_w * fb_ratio;
    }
    /* EDID sizes are missing or wrong often enough (projectors, virtual
     * displays report 0 or nonsense): trust them only between 60 and 600
     * dpi, else fall back to the content scale at 96 dpi. */
    if (from_size >= 60 / 25.4 && from_size <= 600 / 25.4) return from_size;
    float sx = 1, sy = 1;
    glfwGetWindowContentScale(w->win, &sx, &sy);
    if (!(sx > 0) || !isfinite(sx)) sx = 1;
    /* Content scale is relative to window coordinates, which are already
     * scaled by fb_ratio on HiDPI systems that separate the two. */
    double s = fb_ratio > 1.01 ? fb_ratio : (double)sx;
    return 96.0 / 25.4 * s;
}

void mr_window_set_fullscreen(mr_window *w, bool on) {
    if (on == w->fullscreen) return;
    if (on) {
        GLFWmonitor *mon = glfwGetPrimaryMonitor();
        const GLFWvidmode *m = mon ? glfwGetVideoMode(mon) : NULL;
        if (!m) return;
        glfwGetWindowPos(w->win, &w->windowed[0], &w->windowed[1]);
        glfwGetWindowSize(w->win, &w->windowed[2], &w->windowed[3]);
        glfwSetWindowMonitor(w->win, mon, 0, 0, m->width, m->height, m->refreshRate);
    } else {
        glfwSetWindowMonitor(w->win, NULL, w->windowed[0], w->windowed[1], w->windowed[2], w->windowed[3], 0);
    }
    w->fullscreen = on;
}

bool mr_window_fullscreen(const mr_window *w) { return w->fullscreen; }
void mr_window_set_size(mr_window *w, int width, int height) {
    if (width > 0 && height > 0) glfwSetWindowSize(w->win, width, height);
}
void mr_window_set_title(mr_window *w, const char *title) { glfwSetWindowTitle(w->win, title ? title : "mrcheck"); }
void mr_window_swap(mr_window *w) { glfwSwapBuffers(w->win); }

#else /* no GLFW in this build */

mr_window *mr_window_create(const mr_window_params *params, mr_error *err) {
    (void)params;
    mr_fail(err, MR_ERR_UNSUPPORTED, "this build has no window support (install libglfw3-dev and rebuild)");
    return NULL;
}
void mr_window_destroy(mr_window **w) { if (w) *w = NULL; }
mr_gpu *mr_window_gpu(mr_window *w) { (void)w; return NULL; }
void mr_window_wait(mr_window *w, double t) { (void)w; (void)t; }
void mr_window_wake(mr_window *w) { (void)w; }
bool mr_window_next_event(mr_window *w, mr_event *ev) { (void)w; (void)ev; return false; }
bool mr_window_push_event(mr_window *w, const mr_event *ev) { (void)w; (void)ev; return false; }
int mr_window_pending(const mr_window *w) { (void)w; return 0; }
void mr_window_framebuffer_size(const mr_window *w, int *fw, int *fh) { (void)w; *fw = *fh = 0; }
double mr_window_px_per_mm(const mr_window *w) { (void)w; return 96.0 / 25.4; }
void mr_window_set_fullscreen(mr_window *w, bool on) { (void)w; (void)on; }
bool mr_window_fullscreen(const mr_window *w) { (void)w; return false; }
void mr_window_set_size(mr_window *w, int width, int height) { (void)w; (void)width; (void)height; }
void mr_window_set_title(mr_window *w, const char *title) { (void)w; (void)title; }
void mr_window_swap(mr_window *w) { (void)w; }

#endif
