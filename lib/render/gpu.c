/* GL contexts: EGL surfaceless (headless) or one made current by the caller
 * (a GLFW window). Everything GL-specific stays inside lib/render. */
#include "gpu_internal.h"

#include <stdlib.h>
#include <string.h>

#include <EGL/egl.h>
#include <EGL/eglext.h>

#ifndef EGL_PLATFORM_SURFACELESS_MESA
#define EGL_PLATFORM_SURFACELESS_MESA 0x31DD
#endif

struct mr_gpu {
    EGLDisplay dpy;
    EGLContext ctx;
    bool owns_context;
    char desc[512];
};

static void APIENTRY gl_debug_cb(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                                 const GLchar *message, const void *user) {
    (void)source; (void)id; (void)length; (void)user;
    if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
    mr_log(type == GL_DEBUG_TYPE_ERROR ? MR_LOG_ERROR : MR_LOG_DEBUG, "GL: %s", message);
}

/* Checks that the current context can do what the renderer needs. */
static bool check_gl(mr_gpu *g, const mr_gpu_params *p, mr_error *err) {
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    const char *ven = (const char *)glGetString(GL_VENDOR);
    const char *ren = (const char *)glGetString(GL_RENDERER);
    const char *ver = (const char *)glGetString(GL_VERSION);
    snprintf(g->desc, sizeof g->desc, "%s / %s / %s", ven ? ven : "?", ren ? ren : "?", ver ? ver : "?");
    if (major * 10 + minor < 45)
        return mr_fail(err, MR_ERR_NODEVICE, "OpenGL 4.5 core is required, the context offers %d.%d (%s)", major, minor,
                       g->desc);
    if (p && p->debug) {
        glEnable(GL_DEBUG_OUTPUT);
        glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
        glDebugMessageCallback(gl_debug_cb, NULL);
    }
    return true;
}

static bool has_ext(const char *list, const char *name) {
    if (!list) return false;
    size_t n = strlen(name);
    for (const char *s = list; (s = strstr(s, name)); s += n)
        if ((s == list || s[-1] == ' ') && (s[n] == ' ' || s[n] == 0)) return true;
    return false;
}

/* Tries the surfaceless platform (Mesa: llvmpipe or a GPU without a
 * display), then the first EGL device. */
static EGLDisplay open_display(char *why, size_t n) {
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    if (!client || !get_platform_display) {
        snprintf(why, n, "EGL has no platform-display support");
        return EGL_NO_DISPLAY;
    }
    if (has_ext(client, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
        if (d != EGL_NO_DISPLAY && eglInitialize(d, NULL, NULL)) return d;
    }
    if (has_ext(client, "EGL_EXT_platform_device")) {
        PFNEGLQUERYDEVICESEXTPROC query_devices = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
        EGLDeviceEXT devs[8];
        EGLint count = 0;
        if (query_devices && query_devices(8, devs, &count))
            for (EGLint i = 0; i < count; i++) {
                EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devs[i], NULL);
                if (d != EGL_NO_DISPLAY && eglInitialize(d, NULL, NULL)) return d;
            }
    }
    snprintf(why, n, "no EGL device found (tried the surfaceless platform and EGL devices; is Mesa's libegl-mesa0 installed?)");
    return EGL_NO_DISPLAY;
}

mr_gpu *mr_gpu_create_headless(const mr_gpu_params *params, mr_error *err) {
    char why[256] = "";
    EGLDisplay dpy = open_display(why, sizeof why);
    if (dpy == EGL_NO_DISPLAY) {
        mr_fail(err, MR_ERR_NODEVICE, "%s", why);
        return NULL;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        eglTerminate(dpy);
        mr_fail(err, MR_ERR_NODEVICE, "EGL cannot bind the desktop OpenGL API");
        return NULL;
    }
    /* No surface at all: we render into framebuffer objects. */
    EGLConfig cfg = (EGLConfig)0;
    const char *dext = eglQueryString(dpy, EGL_EXTENSIONS);
    if (!has_ext(dext, "EGL_KHR_no_config_context") && !has_ext(dext, "EGL_MESA_configless_context")) {
        EGLint attrs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint n = 0;
        if (!eglChooseConfig(dpy, attrs, &cfg, 1, &n) || n < 1) {
            eglTerminate(dpy);
            mr_fail(err, MR_ERR_NODEVICE, "EGL has no OpenGL config");
            return NULL;
        }
    }
    EGLint ctx_attrs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                          EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attrs);
    if (ctx == EGL_NO_CONTEXT) {
        eglTerminate(dpy);
        mr_fail(err, MR_ERR_NODEVICE, "EGL cannot create an OpenGL 4.5 core context (error 0x%x)", eglGetError());
        return NULL;
    }
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        mr_fail(err, MR_ERR_NODEVICE, "EGL cannot make a surfaceless context current (error 0x%x)", eglGetError());
        return NULL;
    }
    mr_gpu *g = calloc(1, sizeof *g);
    if (!g) {
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    g->dpy = dpy;
    g->ctx = ctx;
    g->owns_context = true;
    if (!check_gl(g, params, err)) {
        mr_gpu_destroy(&g);
        return NULL;
    }
    mr_log(MR_LOG_INFO, "GL context: %s", g->desc);
    return g;
}

mr_gpu *mr_gpu_create_current(const mr_gpu_params *params, mr_error *err) {
    mr_gpu *g = calloc(1, sizeof *g);
    if (!g) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    if (!check_gl(g, params, err)) {
        free(g);
        return NULL;
    }
    return g;
}

void mr_gpu_destroy(mr_gpu **gp) {
    if (!gp || !*gp) return;
    mr_gpu *g = *gp;
    if (g->owns_context) {
        eglMakeCurrent(g->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(g->dpy, g->ctx);
        eglTerminate(g->dpy);
    }
    free(g);
    *gp = NULL;
}

const char *mr_gpu_description(const mr_gpu *g) { return g ? g->desc : ""; }
