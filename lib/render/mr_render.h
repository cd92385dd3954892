/* mr_render.h — the renderer: a GL context (EGL surfaceless, headless), the
 * scene uploaded to the GPU, and a frame assembled from the passes this frame
 * needs (G-buffer, shading, video overlay, ...). No GL type leaves this
 * module.
 *
 * Precision: model-view matrices are composed in double relative to the
 * camera and only then cast to float; depth is reversed-Z 32-bit float with
 * an infinite far plane (glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)).
 * Images come back top row first, in OpenCV pixel convention.
 */
#ifndef MR_RENDER_H
#define MR_RENDER_H

#include "mr_core.h"
#include "mr_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------- context */

typedef struct mr_gpu mr_gpu;

typedef struct mr_gpu_params {
    bool debug;   /* enable GL debug output (messages go to the log), default off */
} mr_gpu_params;
#define MR_GPU_DEFAULTS {.debug = false}

/* Headless OpenGL 4.5 core context through EGL: the surfaceless Mesa
 * platform first, then an EGL device. NULL + MR_ERR_NODEVICE (one line) if
 * no usable EGL device exists. */
mr_gpu *mr_gpu_create_headless(const mr_gpu_params *params, mr_error *err);
/* Wraps a context already current on this thread (e.g. a GLFW window's). */
mr_gpu *mr_gpu_create_current(const mr_gpu_params *params, mr_error *err);
void mr_gpu_destroy(mr_gpu **gpu);
/* "vendor / renderer / version" of the context. */
const char *mr_gpu_description(const mr_gpu *gpu);

/* ------------------------------------------------------------ renderer */

typedef struct mr_renderer mr_renderer;

mr_renderer *mr_renderer_create(mr_gpu *gpu, mr_error *err);
void mr_renderer_destroy(mr_renderer **r);

/* Uploads the scene's meshes and textures. The scene must stay alive and
 * unchanged while it is set (node transforms are read every frame). Passing
 * NULL removes the scene. */
bool mr_renderer_set_scene(mr_renderer *r, const mr_scene *scene, mr_error *err);

/* ------------------------------------------------------ ambient occlusion */

/* Screen-space ambient occlusion methods (pass_ao.c, shaders/ao_*.glsl).
 * AO is a visibility factor in [0,1]: 1 = unoccluded. It multiplies the
 * ambient term of the shading. */
typedef enum mr_ao_method {
    MR_AO_NONE = 0,    /* plain shading (Scheer & Keutel's D1): no AO pass runs */
    MR_AO_SCHEER,      /* occlusion vectors, depth-scaled radius (D2; D3 with radius_mode view);
                          as printed with bias 0 and r_min 0 (the whole ball) */
    MR_AO_CRYTEK,      /* Mittring 2007: ratio of sphere samples behind the depth buffer */
    MR_AO_FILION,      /* Filion & McNaughton 2008: hemisphere samples, depth-difference falloff */
    MR_AO_HBAO,        /* Bavoil et al. 2008: horizon search along image-space directions */
    MR_AO_ALCHEMY,     /* McGuire et al. 2011: obscurance estimator on a screen-space disk */
    MR_AO_METHOD_COUNT
} mr_ao_method;

typedef enum mr_ao_radius_mode {
    MR_AO_RADIUS_SCREEN = 0, /* r_S = screen_radius * Z_p * height / fy: the projected
                                radius is constant (Scheer & Keutel); scale-free */
    MR_AO_RADIUS_VIEW = 1,   /* constant view-space radius `radius` (scene units) */
} mr_ao_radius_mode;

/* How the sample kernel is generated (Doronin et al.). */
typedef enum mr_ao_kernel {
    MR_AO_KERNEL_UNIFORM = 0, /* independent uniform samples */
    MR_AO_KERNEL_STRATIFIED,  /* jittered grid over direction, shuffled radius strata */
    MR_AO_KERNEL_LATIN,       /* Latin hypercube: one sample per stratum in each dimension */
    MR_AO_KERNEL_POISSON,     /* Poisson disk: dart throwing with a shrinking minimum distance */
} mr_ao_kernel;

/* Corner masking (Park & Baek's OdSSAO). */
typedef enum mr_ao_mask {
    MR_AO_MASK_OFF = 0,
    MR_AO_MASK_ON,         /* AO only where >= 2 outline volumes contain the surface */
    MR_AO_MASK_STANDALONE, /* the mask itself is the AO (no sampling): 1 - mask_strength
                              inside, 1 outside, then blurred (Park & Baek sec. 5) */
} mr_ao_mask;

#define MR_AO_MAX_SAMPLES 64
#define MR_AO_MAX_RADII 5 /* Doronin et al. merge 5 radii */

typedef struct mr_ao_params {
    mr_ao_method method;          /* default MR_AO_NONE */
    mr_ao_radius_mode radius_mode;/* default screen (scheer's D2) */
    double radius;                /* view mode: radius in scene units; 0 = 2% of the
                                     scene's bounding-box diagonal */
    double screen_radius;         /* screen mode: projected radius as a fraction of the
                                     image height; 0 = 0.05 */
    int samples;                  /* samples per pixel per radius, 1..64; 0 = 16 */
    mr_ao_kernel kernel;          /* default uniform */
    float r_min, r_max;           /* kernel shell as fractions of the radius;
                                     default 0.8 and 1.0 (Doronin et al.) */
    int radii;                    /* multi-radius: K radii R, R/2, .. R/2^(K-1), the AO is
                                     the darkest of them; 0 = 1 */
    float c;                      /* scheer's attenuation 1/(1 + c |v|'^2); any value in
                                     [0,1e7]; default 1 */
    float bias;                   /* per-method bias (cosine / depth, as a fraction of
                                     the radius); default 0.05 */
    float strength;               /* AO = 1 - strength * occlusion; <= 0: the method's
                                     default (scheer 3, crytek 1, filion 1, hbao 1.5,
                                     alchemy 2: tuned once by `bench ao` on the demo
                                     hall's tuning view at the default radius) */
    int blur_radius;              /* bilateral blur half-width in AO pixels; 0 = off;
                                     default 4 */
    bool half_res;                /* AO at half resolution + joint bilateral upsample */
    bool positions;               /* read view-space positions from a positions texture
                                     instead of un-projecting depth */
    mr_ao_mask mask;              /* corner masking; default off */
    float mask_strength;          /* standalone mask: AO = 1 - mask_strength inside the
                                     mask before the blur, clamped to [0,1] (the method's
                                     strength plays no part); 0 = 0.5, the paper's grey
                                     highlight (Park & Baek give no number) */
    bool want_ao;                 /* fill mr_frame_result.ao */
    bool want_mask;               /* fill mr_frame_result.ao_mask (debug / tests) */
    bool no_reuse;                /* recompute even if camera and settings are unchanged
                                     (benchmarks) */
    const mr_image *external;     /* F32x1 AO at the output size to shade with instead of
                                     computing one (e.g. ray-traced ground truth); NULL */
} mr_ao_params;
/* Each default is written once, here: the initialiser below, the AO pass
 * (which puts them in where a field is zero or out of range) and option
 * tables all name these. Fields not named in MR_AO_DEFAULTS are zero. */
#define MR_AO_DEFAULT_SCREEN_RADIUS 0.05
#define MR_AO_DEFAULT_SAMPLES 16
#define MR_AO_DEFAULT_R_MIN 0.8f
#define MR_AO_DEFAULT_R_MAX 1.0f
#define MR_AO_DEFAULT_RADII 1
#define MR_AO_DEFAULT_C 1.0f
#define MR_AO_DEFAULT_BIAS 0.05f
#define MR_AO_DEFAULT_BLUR_RADIUS 4
#define MR_AO_DEFAULT_MASK_STRENGTH 0.5f
#define MR_AO_DEFAULT_RADIUS_FRACTION 0.02 /* of the scene's bounding-box diagonal */
#define MR_AO_DEFAULTS {.method = MR_AO_NONE, .radius_mode = MR_AO_RADIUS_SCREEN, \
                        .screen_radius = MR_AO_DEFAULT_SCREEN_RADIUS, .samples = MR_AO_DEFAULT_SAMPLES, \
                        .kernel = MR_AO_KERNEL_UNIFORM, .r_min = MR_AO_DEFAULT_R_MIN, .r_max = MR_AO_DEFAULT_R_MAX, \
                        .radii = MR_AO_DEFAULT_RADII, .c = MR_AO_DEFAULT_C, .bias = MR_AO_DEFAULT_BIAS, \
                        .blur_radius = MR_AO_DEFAULT_BLUR_RADIUS, .mask = MR_AO_MASK_OFF, \
                        .mask_strength = MR_AO_DEFAULT_MASK_STRENGTH}

/* The option table of mr_ao_params (lib/render/options.c): on the command
 * line "--ao" + "-" + key ("" is --ao itself, the method). Its rows cover the
 * user's tunables; want_*, no_reuse and external are for programs. */
extern const mr_opt mr_ao_opts[];
/* "none", "scheer", ..., NULL: the method names by value. */
extern const char *const mr_ao_method_names[MR_AO_METHOD_COUNT + 1];

/* Names used on the command line ("none", "scheer", ...); NULL if out of range. */
const char *mr_ao_method_name(mr_ao_method m);
/* Parses a method name; false if unknown. */
bool mr_ao_method_parse(const char *name, mr_ao_method *out);
const char *mr_ao_kernel_name(mr_ao_kernel k);
bool mr_ao_kernel_parse(const char *name, mr_ao_kernel *out);
/* The kernels the AO pass uses, deterministic for given arguments: out3
 * (n x 3 floats) in the unit ball shell [r_min, r_max] for the view-space
 * methods, out2 (n x 2) in the unit disk of radius r_max for the screen-space
 * disk (alchemy: there only surface points within the radius count, so an
 * inner hole would only lose samples). Either may be NULL. */
void mr_ao_kernel_generate(mr_ao_kernel kind, int n, float r_min, float r_max, uint64_t seed, float *out3,
                           float *out2);
/* Adaptive ghosted views of hidden structure (Kalkofen et al., "Adaptive
 * Ghosted Views for Augmented Reality"). The hidden layer D is rendered into
 * its own target; the occluder O is the image in front of it (the shaded
 * visible layer, with the video blended in when there is video). An
 * importance map IM (curvature of the occluder's mesh, or saliency of O)
 * gives the occluder's opacity alpha = t * IM; G0 = O*alpha + D*(1-alpha).
 * The analysis compares the saliency of G0 with the desired contrast and the
 * emphasis changes the occluder's L* where contrast was lost, one sign per
 * occluder object. */
typedef enum mr_ghost_mode {
    MR_GHOST_OFF = 0,      /* hidden layer depth-tested like the rest */
    MR_GHOST_ALPHA,        /* uniform alpha = t * mean(IM) over the occludee */
    MR_GHOST_G0,           /* importance-driven alpha: the initial ghosted view */
    MR_GHOST_ADAPTIVE,     /* G0 + analysis + emphasis: G_A */
} mr_ghost_mode;

typedef enum mr_ghost_importance {
    MR_GHOST_IMP_AUTO = 0,   /* curvature where a registered model occludes, saliency of the video elsewhere */
    MR_GHOST_IMP_CURVATURE,  /* principal curvature of the occluder's mesh */
    MR_GHOST_IMP_SALIENCY,   /* centre-surround saliency of O */
} mr_ghost_importance;

typedef enum mr_saliency_impl {
    MR_SALIENCY_MIPMAP = 0,  /* mip-mapped box pyramid (paper eq. 9-10 with a box f_p) */
    MR_SALIENCY_GAUSS,       /* two separable Gaussians approximating eq. 9 */
} mr_saliency_impl;

/* Which pyramid levels eq. 9's centre-surround differences read. As printed,
 * k_n - k_{n+m} with n = 0..2 and m = n+2..n+4 reaches surround levels
 * 2n+2..2n+4 (2..8, nine levels). The default reads m as the surround level
 * offset, surrounds n+2..n+4 (2..6), as Itti et al. and Veas et al. do; it
 * is also the only reading that fits the paper's own remark that the wide
 * Gaussian of the two-Gaussian version is "approximately 40 samples" (sigma
 * 16 here; the printed levels need sigma 58, about 350 samples), and the
 * printed level 8 is 256 pixels wide: the image mean at test and tablet
 * sizes. */
typedef enum mr_saliency_levels {
    MR_SAL_LEVELS_OFFSET = 0, /* surrounds n+2..n+4 (levels 0..6); default */
    MR_SAL_LEVELS_PRINTED,    /* surrounds n+m, m = n+2..n+4 (levels 0..8), eq. 9 as printed */
} mr_saliency_levels;

typedef struct mr_ghost_params {
    mr_ghost_mode mode;          /* default MR_GHOST_OFF */
    mr_ghost_importance importance; /* default auto */
    mr_saliency_impl saliency;   /* default mip-map pyramid */
    float t;                     /* user transparency: alpha = t * IM, in [0,1]; default 1 */
    float curv_scale;            /* IM = curv_scale * curvature (radians per pixel) + curv_bias; default 2 */
    float curv_bias;             /* default 0.35 (higher: denser occluder, lower: sparser) */
    float saliency_gain;         /* saliency S = gain * |centre-surround| / 100 L* units; default 4 */
    float tc_minimal;            /* minimal desired contrast where 0 < alpha < 1; default 0.1 */
    float gamma;                 /* multiplier of IM in C_desired; default 0.5 (curvature IM
                                    reaches 1 on edges where saliency rarely does) */
    float tc_silhouette;         /* added to C_desired on the hidden structure's silhouette; default 0.15 */
    float emphasis_gain;         /* L* units per unit of GK(C); default 200 (O_A is seen through
                                    alpha, so its change must be larger than the contrast wanted) */
    float sigma_c;               /* Gaussian GK on C, pixels; default 3 */
    float sigma_d;               /* Gaussian GK on D, pixels; default 3 */
    bool stats;                  /* fill mr_frame_result.ghost (extra GPU work and a read-back) */
    mr_saliency_levels saliency_levels; /* eq. 9's levels; default MR_SAL_LEVELS_OFFSET */
} mr_ghost_params;
#define MR_GHOST_DEFAULT_T 1.0f
#define MR_GHOST_DEFAULT_CURV_SCALE 2.0f
#define MR_GHOST_DEFAULT_CURV_BIAS 0.35f
#define MR_GHOST_DEFAULT_SALIENCY_GAIN 4.0f
#define MR_GHOST_DEFAULT_TC_MINIMAL 0.1f
#define MR_GHOST_DEFAULT_GAMMA 0.5f
#define MR_GHOST_DEFAULT_TC_SILHOUETTE 0.15f
#define MR_GHOST_DEFAULT_EMPHASIS_GAIN 200.0f
#define MR_GHOST_DEFAULT_SIGMA_C 3.0f
#define MR_GHOST_DEFAULT_SIGMA_D 3.0f
#define MR_GHOST_DEFAULTS {.mode = MR_GHOST_OFF, .importance = MR_GHOST_IMP_AUTO, .saliency = MR_SALIENCY_MIPMAP, \
                           .t = MR_GHOST_DEFAULT_T, .curv_scale = MR_GHOST_DEFAULT_CURV_SCALE, \
                           .curv_bias = MR_GHOST_DEFAULT_CURV_BIAS, .saliency_gain = MR_GHOST_DEFAULT_SALIENCY_GAIN, \
                           .tc_minimal = MR_GHOST_DEFAULT_TC_MINIMAL, .gamma = MR_GHOST_DEFAULT_GAMMA, \
                           .tc_silhouette = MR_GHOST_DEFAULT_TC_SILHOUETTE, \
                           .emphasis_gain = MR_GHOST_DEFAULT_EMPHASIS_GAIN, .sigma_c = MR_GHOST_DEFAULT_SIGMA_C, \
                           .sigma_d = MR_GHOST_DEFAULT_SIGMA_D, .saliency_levels = MR_SAL_LEVELS_OFFSET}

/* The option table of mr_ghost_params (--ghost, --ghost-KEY): the mode,
 * importance, saliency and the numbers a user tunes; the rest (gains,
 * sigmas, levels, stats) keep their MR_GHOST_DEFAULTS. */
extern const mr_opt mr_ghost_opts[];
/* "off", "alpha", "g0", "adaptive", NULL: the ghosting modes by value. */
extern const char *const mr_ghost_mode_names[];

/* Legibility of a ghosted frame (when mr_ghost_params.stats). */
typedef struct mr_ghost_stats {
    bool valid;
    double region_fraction;    /* fraction of the image where hidden structure lies behind an occluder */
    double mean_importance;    /* mean IM over that region */
    double target_reached;     /* fraction of region pixels with IM > 0.3 whose saliency in the final
                                  image is >= C_desired: the adaptive stage's own target, so a
                                  diagnostic of the optimiser, NOT a legibility measure (that is
                                  mr_eval_ghost_legibility); two-Gaussian saliency; NaN if none */
    double mean_abs_dL;        /* mean |L*(O_A) - L*(O)| over the region (0 unless adaptive) */
    double mean_contrast_missing; /* mean C over the region (adaptive mode only, else 0) */
} mr_ghost_stats;

typedef struct mr_frame_params {
    int width, height;         /* output size in pixels; 0 = the camera's */
    const mr_image *video;     /* camera frame (8-bit, 1/3/4 channels, raw
                                  i.e. distorted), or NULL: no overlay */
    float alpha;               /* video transparency in [0,1]: 0 = virtual only,
                                  1 = video only; default 0.5 */
    bool hide_hidden_layer;    /* leave the hidden layer out; default false */
    float background[3];       /* sRGB colour where no geometry; default grey-blue */
    bool want_depth;           /* fill result.depth (linear view depth) */
    bool want_normals;         /* fill result.normal (view-space normals) */
    bool timing;               /* GPU timer queries per pass (adds a sync) */
    mr_ao_params ao;           /* ambient occlusion; default none */
    mr_ghost_params ghost;     /* ghosted views of the hidden layer; default off */
    float specular;            /* Phong specular weight (white highlights); default 0 = Lambert only */
    float shininess;           /* Phong exponent, >= 1; 0 = 32 */
} mr_frame_params;
#define MR_FRAME_DEFAULT_ALPHA 0.5f
#define MR_FRAME_DEFAULT_BACKGROUND {0.62f, 0.66f, 0.70f}
#define MR_FRAME_DEFAULT_SHININESS 32.0f /* used where shininess < 1 */
/* Designated initialisers in declaration order (C; g++ accepts them too). */
#define MR_FRAME_DEFAULTS {.alpha = MR_FRAME_DEFAULT_ALPHA, .background = MR_FRAME_DEFAULT_BACKGROUND, \
                           .ao = MR_AO_DEFAULTS, .ghost = MR_GHOST_DEFAULTS}

#define MR_MAX_PASSES 32

typedef struct mr_frame_result {
    mr_image color;            /* RGB8, sRGB, top row first */
    mr_image depth;            /* F32x1: linear view depth z (scene units) of
                                  the nearest surface; 0 where nothing */
    mr_image normal;           /* F32x3: unit normal in camera axes (OpenCV),
                                  facing the camera; 0 0 0 where nothing */
    int pass_count;
    const char *passes[MR_MAX_PASSES]; /* names of the passes that ran, in order */
    double gpu_ms[MR_MAX_PASSES];      /* per pass, when params.timing (else 0) */
    double cpu_ms[MR_MAX_PASSES];      /* CPU time spent issuing each pass */
    uint64_t triangles;        /* submitted this frame */
    uint32_t draw_calls;
    double near_plane;         /* the near plane used (scene units) */
    mr_image ao;               /* F32x1 ambient visibility in [0,1] at the output size
                                  (1 = unoccluded, 1 where nothing), when ao.want_ao */
    mr_image ao_mask;          /* F32x1 outline count per pixel at the output size (the
                                  corner mask is count >= 2), when ao.want_mask and
                                  masking ran; empty otherwise */
    double ao_masked_fraction; /* corner masking: fraction of geometry pixels in the
                                  mask (-1 when masking is off) */
    bool ao_reused;            /* AO of the previous frame was reused (frozen camera) */
    mr_ghost_stats ghost;      /* when params.ghost.stats and ghosting ran */
} mr_frame_result;

/* Renders one frame of the current scene seen through `view`. */
bool mr_render_frame(mr_renderer *r, const mr_view *view, const mr_frame_params *params,
                     mr_frame_result *out, mr_error *err);
void mr_frame_result_free(mr_frame_result *res);
/* "gbuffer shade overlay" — the pass list as one line. */
void mr_frame_result_passes(const mr_frame_result *res, char *buf, size_t n);

/* -------------------------------------------------------------- picking */

/* What lies under one pixel of the last rendered frame. */
typedef struct mr_pick {
    bool hit;                  /* false: background at that pixel */
    mr_dvec3 world;            /* world point (scene units) */
    double depth;              /* linear view depth z (scene units) */
    int32_t node;              /* scene node index, or -1 */
    int layer;                 /* mr_layer of that node */
} mr_pick;

/* Reads the G-buffer depth and ids of the last mr_render_frame at pixel
 * (x, y) (OpenCV convention, output size) and turns the depth back into a
 * world point along that pixel's ray. false + err if no frame was rendered
 * or (x, y) is outside it; a miss is out->hit == false. */
bool mr_renderer_pick(mr_renderer *r, double x, double y, mr_pick *out, mr_error *err);

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
/* ------------------------------------------------- ghosting, image level
 * The stages of the ghosting passes on plain images, with the same shaders
 * the frame uses: for tests, benches and tools. Colour images are F32 with 3
 * channels in linear RGB (not sRGB-encoded); maps are F32 x1. */

/* Linear RGB -> CIE L*a*b* (D65, as OpenCV's cvtColor) or back (inverse). */
bool mr_ghost_lab(mr_renderer *r, const mr_image *in, bool inverse, mr_image *out, mr_error *err);
/* Saliency S of a linear RGB image (F32x1, scaled by saliency_gain), with
 * eq. 9's levels read as `levels` says. */
bool mr_ghost_saliency(mr_renderer *r, const mr_image *rgb, mr_saliency_impl impl, mr_saliency_levels levels,
                       float saliency_gain, mr_image *out, mr_error *err);

/* The layers of the last frame that ghosted, as the ghosting saw them, for
 * measuring it (mr_eval_ghost_legibility): the occluder O and the hidden
 * layer D shaded alone (RGB8 sRGB, top row first, like mr_frame_result.color)
 * and the region (F32x1, 1 where D lies behind an occluder). Valid until the
 * next frame; false + err if no frame ghosted since the last resize. */
bool mr_ghost_read_layers(mr_renderer *r, mr_image *occluder, mr_image *hidden, mr_image *region, mr_error *err);

typedef struct mr_ghost_images {
    const mr_image *occluder;   /* O, F32x3 linear RGB */
    const mr_image *occludee;   /* D, F32x3 linear RGB */
    const mr_image *importance; /* IM in [0,1], F32x1 */
    const mr_image *region;     /* F32x1: 1 where hidden structure lies behind the occluder */
    const mr_image *silhouette; /* F32x1: 1 on the hidden structure's silhouette, or NULL */
    const mr_image *objects;    /* F32x1 occluder object id (> 0) per pixel, or NULL: connected regions */
} mr_ghost_images;

typedef struct mr_ghost_output {
    mr_image g0;          /* F32x3 linear: the initial ghosted view (mode alpha or g0 rules) */
    mr_image ga;          /* F32x3 linear: the adaptive ghosted view */
    mr_image occluder_a;  /* F32x3 linear: O_A, the emphasised occluder */
    mr_image contrast;    /* F32x1: C = max(0, C_desired - S(G0)) */
    mr_image alpha;       /* F32x1: the alpha used */
} mr_ghost_output;

/* Runs G0, analysis and emphasis on the images (mode alpha uses the uniform
 * alpha, other modes the importance). */
bool mr_ghost_compose(mr_renderer *r, const mr_ghost_images *in, const mr_ghost_params *params, mr_ghost_output *out,
                      mr_error *err);
void mr_ghost_output_free(mr_ghost_output *out);

/* -------------------------------------------------- drawing the scene */

/* How the scene's geometry is submitted. Zero means default; every switch
 * turns a saving off, so the plain path stays available for comparison
 * (the images are the same either way, up to rasterisation order). */
typedef struct mr_draw_params {
    bool no_cull;          /* draw every node: no BVH frustum culling; default off */
    bool no_batch;         /* one GL draw call per command instead of one
                              glMultiDrawElementsIndirect per group; default off */
    bool no_instancing;    /* one command per node and mesh instead of one per
                              mesh (and LOD level); default off */
    bool no_lod;           /* always full detail; default off */
    double lod_tolerance;  /* largest geometric error (scene units) a LOD level
                              may have, whatever its projected size; 0 = no
                              such cap (the default: only lod_pixels decides,
                              so no unit is assumed); < 0: no LOD at all */
    double lod_pixels;     /* largest projected error of a chosen level, pixels;
                              0 = 1.0 */
    bool occlusion;        /* occlusion culling within the frame: big
                              occluders first, then a hierarchical-Z test
                              of the rest on the CPU; exact (same image),
                              costs a depth read-back; default off */
} mr_draw_params;
#define MR_DRAW_DEFAULT_LOD_PIXELS 1.0
#define MR_DRAW_DEFAULTS {.no_cull = false, .lod_tolerance = 0.0, .lod_pixels = 0.0} /* 0 = the defaults above */

/* What the last frame's geometry submission did (summed over the passes
 * that drew geometry). */
typedef struct mr_draw_stats {
    double cull_ms;            /* CPU: culling, LOD choice, instance data */
    uint32_t nodes_drawable;   /* nodes of the drawn layers that draw something */
    uint32_t nodes_visible;    /* of those, not culled */
    uint32_t nodes_occluded;   /* culled by occlusion (when enabled) */
    uint32_t instances;        /* mesh instances submitted */
    uint32_t commands;         /* indirect draw commands */
    uint32_t gl_draw_calls;    /* GL draw calls issued */
    uint64_t triangles;        /* submitted */
    uint64_t triangles_full;   /* the same instances at full detail */
    uint32_t lod_instances;    /* instances drawn with a simplified level */
    double lod_max_error;      /* largest error bound (scene units, node
                                  stretch included) of a level drawn */
    uint32_t level_instances[MR_LOD_MAX_LEVELS + 1]; /* instances drawn at
                                  each level: 0 full detail, 1 the finest
                                  simplified level, ... */
} mr_draw_stats;

/* Sets how geometry is submitted from the next frame on (NULL: defaults). */
bool mr_renderer_set_draw_params(mr_renderer *r, const mr_draw_params *params, mr_error *err);
void mr_renderer_draw_stats(const mr_renderer *r, mr_draw_stats *out);
/* Draws simplified levels from `lod` (built for the scene that is set; it
 * must stay alive while set; NULL: full detail only). Re-uploads the
 * scene's geometry; setting another scene drops the levels. */
bool mr_renderer_set_lod(mr_renderer *r, const mr_lod *lod, mr_error *err);

#ifdef __cplusplus
}
#endif
#endif
