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

/* A headless GPU and a renderer on it: what a command or a bench renders
 * with (headless.c). GL debug output follows the log level (debug). Close
 * also after a failed open. */
typedef struct mr_gfx {
    mr_gpu *gpu;
    struct mr_renderer *renderer;
} mr_gfx;
bool mr_gfx_open(mr_gfx *g, mr_error *err);
void mr_gfx_close(mr_gfx *g);

/* For lib/window's 2D layer, which draws with the same context: a GL
 * program built from embedded shaders/<name> files (NULL-terminated list;
 * 0 + err on failure). GL object names travel as plain integers so that no
 * GL type leaves this module. */
uint32_t mr_gpu_program(const char *const *files, mr_error *err);

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
    MR_AO_SCHEER,      /* occlusion vectors, depth-scaled radius (D2; see mr_ao_sk_setup);
                          as printed with bias 0 and r_min 0 (the whole ball) */
    MR_AO_CRYTEK,      /* Mittring 2007: ratio of sphere samples behind the depth buffer */
    MR_AO_FILION,      /* Filion & McNaughton 2008: hemisphere samples, depth-difference falloff */
    MR_AO_HBAO,        /* Bavoil et al. 2008: horizon search along image-space directions */
    MR_AO_ALCHEMY,     /* McGuire et al. 2011: obscurance estimator on a screen-space disk */
    /* The modern integrators (slices of the hemisphere around the
     * view vector, per slice both horizons within the radius). */
    MR_AO_GTAO,        /* Jimenez et al. 2016: cosine-weighted visibility between the two
                          horizons against the normal projected into the slice */
    MR_AO_BITMASK,     /* Therrien, Levesque & Gilet 2023: 32 sectors per slice marked
                          occluded by samples assumed `thickness` deep */
    MR_AO_SCHEER_GT,   /* scheer-gt: Scheer & Keutel's quasi-normalised attenuation
                          1/(1 + c l^2) on GTAO's slices (see pass_ao.c) */
    MR_AO_SCHEER_BM,   /* scheer-bm: the bitmask's sectors, each counted with the attenuation
                          1/(1 + c l^2) of the nearest sample that marks it (l = |v| / r),
                          depth-scaled radius; c = 0 is the bitmask (shaders/ao_main.frag.glsl) */
    MR_AO_METHOD_COUNT
} mr_ao_method;

typedef enum mr_ao_radius_mode {
    MR_AO_RADIUS_SCREEN = 0, /* r_S = screen_radius * Z_p * height / fy: the projected
                                radius is constant (Scheer & Keutel; their printed
                                r_S = r_B s d / Z_p is a misprint, see pass_ao.c); scale-free */
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

/* The kernel's per-pixel rotation: a hash of the pixel, or of the surface's
 * position (quantised to a grid), so that the noise stays on the surface
 * when the eye moves (multi-view displays). */
typedef enum mr_ao_noise {
    MR_AO_NOISE_PIXEL = 0,
    MR_AO_NOISE_WORLD,
} mr_ao_noise;

/* World noise: the anchor camera's pixels per cell side. A surface point
 * seen at a pixel centre in one view is seen up to half a pixel away in
 * another, so cells of one pixel would split it half the time. */
#define MR_AO_NOISE_CELL_PX 4

#define MR_AO_MAX_SAMPLES 128
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
    float thickness;              /* bitmask: assumed depth of every occluder behind its
                                     visible face, as a fraction of the radius; 0 = 0.5
                                     (gtao, scheer-gt: the same fraction bounds how far
                                     in front of the pixel an occluder may be before the
                                     thickness heuristic fades it) */
    bool temporal;                /* accumulate the AO over frames (reprojected by
                                     the poses, history rejected by depth and normal; a
                                     running mean over up to MR_AO_TEMPORAL_FRAMES frames,
                                     then weight 1/MR_AO_TEMPORAL_FRAMES for the new one);
                                     off by default, and a single frame (render) has no
                                     history to use */
    bool temporal_reset;          /* this frame starts a new history (a tracking reset);
                                     set by the caller per frame, like no_reuse */
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
    /* multi-view: where the kernel's per-pixel rotation comes from */
    mr_ao_noise noise;            /* default pixel (a hash of the pixel) */
    double noise_cell;            /* world noise: > 0, a grid of cells this size in scene
                                     units, in the anchor's frame; 0 = the anchor camera's
                                     pixels (the frame's intrinsics) grouped
                                     MR_AO_NOISE_CELL_PX x MR_AO_NOISE_CELL_PX, so the noise
                                     is as fine as the image at any depth */
    mr_dmat4 noise_anchor;        /* world noise: world_from_anchor, the frame positions are
                                     hashed in (a multi-view rig sets its centre camera, so
                                     all views share it); used when noise_anchor_set */
    bool noise_anchor_set;        /* false: the world frame itself */
    bool mips;                    /* gtao / bitmask / scheer-gt / scheer-bm: samples at least
                                     MR_AO_MIP_NEAR_PX from the pixel read a box-filtered
                                     depth mip chain (built only for these methods); off
                                     by default */
    bool deinterleave;            /* the AO pass over 4x4 quarter-size layers of the depth
                                     (a tiled atlas), one kernel rotation per layer, then
                                     re-interleaved before the blur; all methods, not with
                                     the positions path or the standalone mask (ignored
                                     there); off by default */
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
#define MR_AO_DEFAULT_THICKNESS 0.5f
#define MR_AO_TEMPORAL_FRAMES 16     /* temporal: frames in the running mean */
#define MR_AO_TEMPORAL_DEPTH_TOL 0.02 /* temporal: relative depth difference that rejects history */
#define MR_AO_TEMPORAL_NORMAL_COS 0.9 /* temporal: normals further apart reject history */
#define MR_AO_MAX_SLICES 16 /* gtao / bitmask / scheer-gt: slice directions (a uniform array) */
#define MR_AO_MIP_NEAR_PX 8.0 /* mips: offsets below this (pixels) read level 0;
                                 level L for [8 * 2^(L-1), 8 * 2^L) */
#define MR_AO_MIP_LEVELS 4    /* mips: levels above 0 in the chain (at most) */
#define MR_AO_DEINT_NEAR 2     /* deinterleave: samples nearer than this many
                                 layer spacings (4 AO pixels each) read the G-buffer itself */
#define MR_AO_DEFAULTS {.method = MR_AO_NONE, .radius_mode = MR_AO_RADIUS_SCREEN, \
                        .screen_radius = MR_AO_DEFAULT_SCREEN_RADIUS, .samples = MR_AO_DEFAULT_SAMPLES, \
                        .kernel = MR_AO_KERNEL_UNIFORM, .r_min = MR_AO_DEFAULT_R_MIN, .r_max = MR_AO_DEFAULT_R_MAX, \
                        .radii = MR_AO_DEFAULT_RADII, .c = MR_AO_DEFAULT_C, .bias = MR_AO_DEFAULT_BIAS, \
                        .blur_radius = MR_AO_DEFAULT_BLUR_RADIUS, .mask = MR_AO_MASK_OFF, \
                        .thickness = MR_AO_DEFAULT_THICKNESS, .mask_strength = MR_AO_DEFAULT_MASK_STRENGTH}

/* The one home of the AO defaults that depend on the scene or are written
 * as 0 = default: every zero / out-of-range field replaced by its default,
 * the view-mode radius by MR_AO_DEFAULT_RADIUS_FRACTION of the scene's
 * diagonal (1 scene unit without a scene). What the AO passes run with. */
mr_ao_params mr_ao_params_resolve(const mr_ao_params *in, const mr_scene *scene);
/* The view-mode radius a scene gets by default (scene units). */
double mr_ao_default_radius(const mr_scene *scene);

/* The option table of mr_ao_params (lib/render/options.c): on the command
 * line "--ao" + "-" + key ("" is --ao itself, the method). Its rows cover the
 * user's tunables; want_*, no_reuse and external are for programs. */
extern const mr_opt mr_ao_opts[];
/* "none", "scheer", ..., NULL: the method names by value. */
extern const char *const mr_ao_method_names[MR_AO_METHOD_COUNT + 1];

/* Names used on the command line ("none", "scheer", ...); NULL if out of range. */
const char *mr_ao_method_name(mr_ao_method m);

/* Scheer & Keutel's three renderings, as their Sec. 5 defines them, defined
 * here once (the study stimuli, `bench ao` and the docs take them from
 * here): D1 "standard phong shading" (no AO); D2 "our approach to SSAO"
 * (occlusion vectors, the sampling radius constant on screen, so growing
 * with depth: scheer, radius mode screen); D3 "standard SSAO with a
 * decreasing size of the sample radius in depth": Mittring's SSAO (crytek),
 * the paper's origin of standard SSAO [Mit07a], with a constant view-space
 * radius. scheer with a constant radius isolates the radius rule; it is an
 * extra row, not D3. */
typedef enum mr_ao_sk_rendering { MR_AO_SK_D1, MR_AO_SK_D2, MR_AO_SK_D3, MR_AO_SK_COUNT } mr_ao_sk_rendering;
/* Sets p's method and radius mode to rendering d's; the rest is kept. */
void mr_ao_sk_setup(mr_ao_sk_rendering d, mr_ao_params *p);
/* "D1", "D2" or "D3" when (method, radius mode) is one of them, else "-". */
const char *mr_ao_sk_role(mr_ao_method m, mr_ao_radius_mode mode);
/* Parses a method name; false if unknown. */
bool mr_ao_method_parse(const char *name, mr_ao_method *out);
/* gtao / bitmask / scheer-gt: how `samples` splits into slices and steps
 * per slice side (slices * 2 * steps <= samples where samples >= 2). */
void mr_ao_slice_split(int samples, int *slices, int *steps);
/* The fetch floor of an AO pass (lib/render/probe.c): a full-
 * screen pass over a w x h R32F target doing `fetches` texel fetches per
 * pixel spread over radius_px pixels (the AO disk kernel) and nothing
 * else; each of `frames` draws (after one warm-up) is timed on the CPU
 * between two glFinish, in ms[0 .. frames-1]. */
bool mr_render_fetch_probe(mr_renderer *r, int w, int h, int fetches, double radius_px, int frames, double *ms,
                           mr_error *err);
const char *mr_ao_kernel_name(mr_ao_kernel k);
bool mr_ao_kernel_parse(const char *name, mr_ao_kernel *out);
/* The sampling kernels (kernels.c) of the AO pass, and of the shadow and
 * probe passes, deterministic for given arguments: out3
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
    float opacity;               /* Kalkofen et al.'s t, which they call a transparency: alpha = t * IM
                                    is the occluder's opacity, so t scales it; in [0,1]; default 1 */
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
#define MR_GHOST_DEFAULT_OPACITY 1.0f
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
                           .opacity = MR_GHOST_DEFAULT_OPACITY, .curv_scale = MR_GHOST_DEFAULT_CURV_SCALE, \
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

/* ------------------------------------------------------------ shadows
 * Soft shadows of the scene's casting light (the first light with `casts`;
 * with no lights, the renderer's default sun of MR_LIGHT_DEFAULT_SUN_ANGLE)
 * from a shadow map (pass_shadow.c, shaders/shadow_*.glsl), after Hecher's
 * comparison of shadow-map soft-shadow methods. The result is a visibility
 * buffer in [0,1] (1 = lit) that scales that light's direct term. */
typedef enum mr_shadow_method {
    MR_SHADOW_OFF = 0,     /* no shadow pass runs (default) */
    MR_SHADOW_HARD,        /* one depth comparison at the light's centre */
    MR_SHADOW_PCF,         /* fixed kernel of Poisson taps, rotated per pixel */
    MR_SHADOW_PCSS,        /* Fernando 2005: blocker search, penumbra estimate, PCF */
    MR_SHADOW_BP,          /* backprojection (Guennebaud et al. 2006) */
    MR_SHADOW_GROUNDTRUTH, /* the average of `gt_samples` hard shadow maps from stratified
                              points on the light (the frustum translated, not rotated) */
    MR_SHADOW_METHOD_COUNT
} mr_shadow_method;

typedef struct mr_shadow_params {
    mr_shadow_method method;   /* default off */
    int map_size;              /* shadow-map side in texels, 64..8192; 0 = 1024 */
    int taps;                  /* PCF / PCSS filter taps (and blocker-search taps), 1..64; 0 = 32 */
    float pcf_radius;          /* PCF kernel radius in shadow-map texels; 0 = 3 */
    int gt_samples;            /* groundtruth: light samples, 1..1024; 0 = 256 */
    float light_scale;         /* multiplies the light's size (sun angle, rect, sphere); 0 = 1 */
    bool want_shadow;          /* fill mr_frame_result.shadow */
    bool no_reuse;             /* redraw the maps even when camera and light are unchanged */
    /* Cascaded sun shadows: 1..4 maps over slices of the camera's
     * visible depth; 0 = auto by the ratio of far to near visible depth
     * (1 below 16, one more per factor 16, at most 4). Rect and sphere
     * lights always use one map. */
    int cascades;
    /* Backprojection without its depth pyramid: every texel of the square
     * the light reaches from the nearest caster (tests compare the two). */
    bool bp_no_pyramid;
} mr_shadow_params;
#define MR_SHADOW_MAX_CASCADES 4
#define MR_SHADOW_DEFAULT_MAP_SIZE 1024
#define MR_SHADOW_DEFAULT_TAPS 32
#define MR_SHADOW_DEFAULT_PCF_RADIUS 3.0f
#define MR_SHADOW_DEFAULT_GT_SAMPLES 256
#define MR_SHADOW_MAX_TAPS 64
#define MR_SHADOW_DEFAULTS {.method = MR_SHADOW_OFF, .map_size = MR_SHADOW_DEFAULT_MAP_SIZE, \
                            .taps = MR_SHADOW_DEFAULT_TAPS, .pcf_radius = MR_SHADOW_DEFAULT_PCF_RADIUS, \
                            .gt_samples = MR_SHADOW_DEFAULT_GT_SAMPLES, .light_scale = 1.0f}
/* --shadows, --shadows-KEY (lib/render/options.c). */
extern const mr_opt mr_shadow_opts[];
/* "off", "hard", "pcf", "pcss", "bp", "groundtruth", NULL */
extern const char *const mr_shadow_method_names[MR_SHADOW_METHOD_COUNT + 1];
bool mr_shadow_method_parse(const char *name, mr_shadow_method *out);
/* Without --shadows given in t (the parsed mr_shadow_opts table), the
 * scene config's "shadows" names the method; false + one line if it names
 * none. */
bool mr_shadow_scene_default(const mr_cli_table *t, const mr_scene *s, mr_shadow_params *p, mr_error *err);
/* The light a frame's shadows come from: the scene's first casting light, or
 * the default sun when the scene has no lights; false when none casts. */
bool mr_shadow_light(const mr_scene *s, mr_light *out);
/* The sun cascades of the renderer's last shadow frame (for tests): cascade
 * k's rectangle corner and texel size in the light's frame fixed to the
 * scene (the light's axes, origin at the scene's bounds centre). Returns
 * the cascade count, 0 when the last frame drew a single map. */
int mr_shadow_cascade_grid(const mr_renderer *r, int k, double corner[2], double texel[2]);
/* The sun's cascade count, the rule a shadow frame applies: 1 when one is
 * asked for or the 2 x 2 atlas of map_size tiles exceeds max_tex; else
 * the count asked for, or with 0 one more per factor 16 between the far
 * and the near visible depth (1 without a visible depth range); at most
 * MR_SHADOW_MAX_CASCADES. */
int mr_shadow_cascade_count(int asked, int map_size, int max_tex, double vis_near, double vis_far);

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
    bool timing_sync;          /* with timing: glFinish before and after every pass, so that
                                  cpu_ms is the pass's whole synchronous cost (llvmpipe
                                  defers rasterisation past a lone timer query) */
    mr_ao_params ao;           /* ambient occlusion; default none */
    mr_ghost_params ghost;     /* ghosted views of the hidden layer; default off */
    float specular;            /* Phong specular weight (white highlights); default 0 = Lambert only */
    float shininess;           /* Phong exponent, >= 1; 0 = 32 */
    mr_shadow_params shadow;   /* soft shadows; default off */
    const struct mr_display_map *display; /* light-field display mapping instead of the
                                  pinhole (then the AO reads positions); NULL = pinhole */
} mr_frame_params;
#define MR_FRAME_DEFAULT_ALPHA 0.5f
#define MR_FRAME_DEFAULT_BACKGROUND {0.62f, 0.66f, 0.70f}
#define MR_FRAME_DEFAULT_SHININESS 32.0f /* used where shininess < 1 */
/* Designated initialisers in declaration order (C; g++ accepts them too). */
/* Option table of what a user sets directly (alpha, hide-hidden); the
 * depth cues have their own (mr_ao_opts, mr_ghost_opts, mr_shadow_opts). */
extern const mr_opt mr_frame_opts[];
#define MR_FRAME_DEFAULTS {.alpha = MR_FRAME_DEFAULT_ALPHA, .background = MR_FRAME_DEFAULT_BACKGROUND, \
                           .ao = MR_AO_DEFAULTS, .ghost = MR_GHOST_DEFAULTS, .shadow = MR_SHADOW_DEFAULTS}

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
    mr_image shadow;           /* F32x1 visibility of the casting light in [0,1] (1 = lit,
                                  1 where nothing) when shadow.want_shadow and shadows ran */
    bool shadow_reused;        /* the shadow maps of the previous frame were reused */
    int shadow_cascades;       /* shadow maps of the casting light this frame (sun cascades; 0: none) */
} mr_frame_result;

/* Renders one frame of the current scene seen through `view`. */
bool mr_render_frame(mr_renderer *r, const mr_view *view, const mr_frame_params *params,
                     mr_frame_result *out, mr_error *err);

/* How far `shown` is from the same view drawn as the model only (d[0],
 * alpha 0) and as the video only (d[1], alpha 1): mean absolute 8-bit
 * difference, -1 where a render fails. Says which way a transparency
 * slider moved a picture (the view's `state`). The renderer's last frame
 * is one of these afterwards. */
void mr_render_alpha_distances(mr_renderer *r, const mr_view *view, const mr_frame_params *params, const mr_image *shown,
                               double d[2]);
void mr_frame_result_free(mr_frame_result *res);
/* "gbuffer shade overlay" — the pass list as one line. */
void mr_frame_result_passes(const mr_frame_result *res, char *buf, size_t n);
/* The frame's auxiliary buffers, those it has, into dir (created):
 * depth.pfm (linear view depth), normal.pfm, ao.pfm (1 = unoccluded),
 * shadow.pfm (frame_files.c). */
bool mr_frame_result_save_aux(const char *dir, const mr_frame_result *res, mr_error *err);

/* ------------------------------------------------------- multi-view rigs
 * Views for 3D displays (lib/render/multiview.c; pure functions, no GL).
 * N parallel cameras along the centre camera's x axis, each with an
 * off-axis (sheared) frustum converging on a focal plane at distance D, no
 * toe-in: view i has theta_i = (i/(N-1) - 1/2) cone, its eye at
 * s_i = D tan(theta_i) on the x axis, and at the near plane n the frustum
 * left/right = (-/+ aspect size - s_i) n / D, bottom/top = -/+ size n / D,
 * where size = D tan(fov/2) is the focal plane's half-height. Every view
 * sees the same rectangle of the focal plane. */
typedef struct mr_rig_params {
    int views;              /* N; 0 = off (one ordinary view); 1..1024 */
    double cone_deg;        /* total view cone, degrees; default 35 */
    double fov_deg;         /* vertical field of view at the focal plane, degrees;
                               default 14 (0 in a struct = the default) */
    double focal_distance;  /* D in scene units; 0 = the median depth the centre
                               view sees in its middle third (mr_rig_focal_from_depth),
                               else the scene's centre (mr_rig_auto_focal_distance) */
    bool per_view_work;     /* cull and fit the shadow maps per view, as
                               before the shared work (for comparison) */
} mr_rig_params;
#define MR_RIG_DEFAULT_CONE 35.0
#define MR_RIG_DEFAULT_FOV 14.0
#define MR_RIG_MAX_VIEWS 1024
#define MR_RIG_DEFAULTS {.views = 0, .cone_deg = MR_RIG_DEFAULT_CONE, .fov_deg = MR_RIG_DEFAULT_FOV, \
                         .focal_distance = 0.0}
/* The option table of mr_rig_params (no prefix: --views, --view-cone,
 * --view-fov, --focal-distance). */
extern const mr_opt mr_rig_opts[];

typedef struct mr_rig {
    int views;
    double cone, fov;       /* radians */
    double distance;        /* D, scene units */
    double size;            /* half-height of the focal plane's rectangle, scene units */
    double aspect;          /* view aspect: half-width / half-height of that rectangle */
    bool per_view_work;     /* from mr_rig_params */
} mr_rig;

/* D = size / tan(fov/2): the focal distance at which a focal plane of
 * half-height `size` fills a vertical field of view of fov_deg. */
double mr_rig_distance_for_size(double fov_deg, double size);
/* Fills rig from params, the view aspect (> 0) and D (> 0, finite); false +
 * one line on a value out of range (N < 1, cone outside [0, 180), ...). */
bool mr_rig_make(const mr_rig_params *p, double aspect, double distance, mr_rig *rig, mr_error *err);
/* theta_i (radians) and s_i = D tan(theta_i); a single view sits at 0. */
double mr_rig_angle(const mr_rig *rig, int i);
double mr_rig_shift(const mr_rig *rig, int i);
/* The frustum of view i at near distance n (GL glFrustum's l r b t). */
void mr_rig_frustum(const mr_rig *rig, int i, double n, double *l, double *r, double *b, double *t);
/* A point p in the centre camera's axes (OpenCV: x right, y down, z forward)
 * to view i's NDC (x right, y down), through the frustum above. */
void mr_rig_project(const mr_rig *rig, int i, mr_dvec3 p, double ndc[2]);
/* View i as a pinhole view of width x height pixels: eye moved by s_i along
 * the centre camera's x axis, principal point shifted to shear the frustum
 * (fx = W D / (2 aspect size), fy = H D / (2 size); no lens distortion).
 * Rendering it with mr_render_frame gives exactly the frustum above. */
mr_view mr_rig_view(const mr_rig *rig, const mr_view *centre, int i, int width, int height);
/* The depth of the scene's bounding-box centre along the view's axis; <= 0
 * when the centre is behind the camera (then D must be given). */
double mr_rig_auto_focal_distance(const mr_scene *scene, const mr_view *view);
/* The median depth (F32x1 linear depth, 0 = nothing) over the middle third
 * of the image: the default focal plane, where the centre view looks; 0 if
 * nothing is seen there. */
double mr_rig_focal_from_depth(const mr_image *depth);

/* A quilt in the Looking Glass convention: cols x rows tiles, view 0 at the
 * bottom-left, views going right then up; file name NAME_qs{C}x{R}a{A}.png
 * with A the view aspect (not the tile's pixel aspect). */
typedef struct mr_quilt {
    int cols, rows;
    int width, height;      /* quilt pixels; 0 = cols x tile width, rows x tile height */
    double aspect;          /* the device's view aspect; 0 = the views' */
    const char *preset;     /* the preset's name, or NULL */
} mr_quilt;
/* "portrait" (8x6, 3360x3360, a 0.75), "go" (11x6, 4092x4092, a 0.5625),
 * "4k" (5x9, 4096x4096, a 1.7778), "8k" (5x9, 8192x8192, a 1.7778), or
 * "CxR" (tiles of the view size) or "CxR@WxH" (tiles cut from W x H). */
bool mr_quilt_parse(const char *spec, mr_quilt *q, mr_error *err);
/* The multi-view options of a command that depend on each other: t is
 * the parsed mr_rig_opts table, quilt_spec --quilt (parsed into *quilt,
 * *have_quilt set; zeroed when NULL), lightfield whether --lightfield was
 * given. Rig options without --views, --quilt or --lightfield, and
 * --lightfield with either, are one line in err. */
bool mr_rig_opts_check(const mr_cli_table *t, const char *quilt_spec, bool lightfield, mr_quilt *quilt,
                       bool *have_quilt, mr_error *err);
/* The layout for n views: a tiles grid of the spec (or, with spec NULL,
 * ceil(sqrt(n)) columns and as many rows as needed) and the tile size: the
 * quilt's size / grid, else view_w x view_h. false + one line if the quilt
 * has fewer tiles than views or tiles under 1 pixel. */
typedef struct mr_quilt_layout {
    int cols, rows, tile_w, tile_h, width, height;
    double aspect;          /* view aspect written into the name */
} mr_quilt_layout;
bool mr_quilt_layout_make(const mr_quilt *spec, int views, int view_w, int view_h, mr_quilt_layout *out,
                          mr_error *err);
/* Top-left pixel of view i's tile, image rows top-down (PNG order). */
void mr_quilt_tile_origin(const mr_quilt_layout *q, int i, int *x, int *y);
/* Copies view i (tile_w x tile_h, same channels and type as quilt) into its tile. */
bool mr_quilt_put(const mr_quilt_layout *q, mr_image *quilt, int i, const mr_image *view, mr_error *err);
/* "NAME_qs8x6a0.75.png". */
void mr_quilt_file_name(const char *name, const mr_quilt_layout *q, char *out, size_t n);

/* A horizontal-parallax-only light-field display (HoloVizio-like): each
 * pixel column u is seen from its own eye on the observer line (the centre
 * camera's x axis), e(u) = (2 (u + 0.5) / W - 1) E with E = D tan(cone/2),
 * through its own point of the focal plane; vertically every column is the
 * centre camera. The world-to-image mapping is not affine and not a 4x4
 * projection (x and y have different denominators; all columns' rays cross
 * at one depth when E exceeds the focal plane's half-width), so AO reads
 * positions, never un-projected depth. It is rendered in narrow perspective
 * slices: each band of `band` columns is a pinhole view from the eye of its
 * middle column, scissored to the band, into the one G-buffer. At band 1
 * every pixel centre's ray is the column's exact ray; a column j away from
 * its band's middle is off by |j q / (1 - q)| pixels, q = (E / A)(1 - D/z),
 * for a surface at depth z (A the focal plane's half-width seen by the
 * camera): mr_display_column_error. */
typedef struct mr_display_map {
    double distance;        /* D: the focal plane, scene units */
    double eye_half;        /* E: the observer line spans [-E, E] on the x axis */
    int band;               /* columns per perspective slice, >= 1 */
} mr_display_map;
#define MR_DISPLAY_DEFAULT_BAND 1
/* From a rig: its D and E = D tan(cone/2). */
mr_display_map mr_display_from_rig(const mr_rig *rig, int band);
/* The eye (x on the observer line) of column u of a W-pixel image. */
double mr_display_eye(const mr_display_map *m, int width, double u);
/* The centre-camera point the banded rendering puts at pixel (u, v) at
 * depth z: on the ray of u in its band's camera (at band 1 the exact ray of
 * column u), as the positions texture holds it; `cam` is the frame's
 * (centre) camera. */
mr_dvec3 mr_display_point(const mr_display_map *m, const mr_camera *cam, double u, double v, double z);
/* The exact pixel of a centre-camera point under the per-column mapping
 * (the inverse of the above at band 1); false behind the observer line or
 * where the columns' rays cross (no single column sees the point's depth). */
bool mr_display_project(const mr_display_map *m, const mr_camera *cam, mr_dvec3 p, double *u, double *v);
/* Band b's columns [*x0, *x1) and its pinhole camera (the frame camera
 * with the principal point shifted by fx e_b / D) and eye offset e_b. */
int mr_display_band_count(const mr_display_map *m, int width);
mr_camera mr_display_band_camera(const mr_display_map *m, const mr_camera *cam, int b, int *x0, int *x1, double *eye);
/* Column error (pixels) of the banded rendering for a surface at depth z
 * seen in column u: where the exact mapping puts the point the band's
 * camera drew there, minus u. 0 for band 1 at pixel centres. */
double mr_display_column_error(const mr_display_map *m, const mr_camera *cam, int u, double z);

/* Renders the rig's views with one renderer (scene upload and programs are
 * shared; each view is a mr_render_frame of its own camera). Writes
 * view_NNN.png into views_dir (NULL: none) and fills quilt (RGB8, when not
 * NULL). The video overlay is left out (the camera frame is seen from one
 * eye only). AO noise is anchored to the centre camera when the AO's noise
 * is "world", so it stays on the surface from view to view. */
typedef struct mr_rig_result {
    double ms_total;        /* wall-clock, all views, glFinish'ed */
    int views;
    /* The shared work, summed over the views */
    int frustum_culls;      /* BVH culls (G-buffer and shadow maps) */
    int shadow_maps;        /* shadow_map passes run */
    double cull_ms;         /* CPU: culling, LOD, instance data */
} mr_rig_result;
bool mr_render_rig(mr_renderer *r, const mr_rig *rig, const mr_view *centre, const mr_frame_params *params,
                   const mr_quilt_layout *layout, const char *views_dir, mr_image *quilt, mr_rig_result *res,
                   mr_error *err);

/* The focal distance of a rig around `centre`: rp->focal_distance when
 * set, else *focal when > 0, else the median depth the centre view sees in
 * its middle third at fp's output size (one extra frame), else the scene's
 * centre; stored in *focal. false + err if nothing lies ahead. */
bool mr_rig_focus(mr_renderer *r, const mr_scene *scene, const mr_rig_params *rp, const mr_view *centre,
                  const mr_frame_params *fp, double *focal, mr_error *err);

/* One rig frame written as files (`render --views`, `replay --views`). */
typedef struct mr_rig_files {
    const mr_rig_params *rig;     /* views (0: one per quilt tile), cone, fov, focal distance */
    const mr_quilt *quilt;        /* the quilt's tiles; cols 0 = fitted to the views */
    const char *views_dir;        /* view_NNN.png go here (NULL: none) */
    const char *quilt_dir;        /* NAME_qs{C}x{R}a{A}.png goes here ... */
    const char *quilt_name;       /* ... with this NAME */
    double focal;                 /* in/out: 0 = found by mr_rig_focus on the first call,
                                     then kept (a replay keeps the first frame's) */
    mr_quilt_layout layout;       /* out: the layout used */
} mr_rig_files;
/* Renders the rig around `centre` with mr_render_rig and writes its views
 * and quilt; res (may be NULL) gets what the views shared. */
bool mr_render_rig_files(mr_renderer *r, const mr_scene *scene, mr_rig_files *job, const mr_view *centre,
                         const mr_frame_params *fp, mr_rig_result *res, mr_error *err);

/* --lightfield: for one frame around *view, the display mapping with `band`
 * columns per eye into *map, and *view replaced by the centre camera of the
 * rig's focal-plane rectangle (the focal distance from mr_rig_focus). */
bool mr_display_setup(mr_renderer *r, const mr_scene *scene, const mr_rig_params *rp, int band, mr_view *view,
                      const mr_frame_params *fp, mr_display_map *map, mr_error *err);

/* The work a rig frame shares. The views (width x height pixels,
 * mr_rig_view) are translated along the centre camera's x axis and share
 * its orientation, so every view's frustum lies in one convex volume: the
 * bottom/top planes (the same slopes) and the near plane (the nearest of
 * the views') are shared; left is the plane through the leftmost eye with
 * the smallest left slope of any view, right the one through the rightmost
 * eye with the largest right slope (margin_px widens each view's image as
 * mr_frustum_from_camera does). A point of view i's frustum has x - s_i >=
 * l_i z, so x - s_min >= l_min z for z >= 0; with an infinite far plane
 * this is the convex hull of the views' frusta. */
mr_frustum mr_rig_cull_frustum(const mr_rig *rig, const mr_view *centre, int width, int height, double near_plane,
                               double margin_px);
/* Between begin and end, mr_render_frame of the rig's views shares one
 * cull and LOD choice for the union (every view draws that list through
 * its own camera) and, with shadows, one shadow map per frame (fitted to
 * the union: the outer views' frusta and the union's visible depth; the
 * other views reuse it). Nothing is shared with rig->per_view_work or
 * fewer than 2 views. mr_render_rig calls them. */
bool mr_render_rig_begin(mr_renderer *r, const mr_rig *rig, const mr_view *centre, int width, int height,
                         mr_error *err);
void mr_render_rig_end(mr_renderer *r);
/* The layered-rendering experiment: the G-buffer pass's geometry
 * work (depth only, the rig frame's shared cull) for all views into one
 * quilt depth target, either as the per-view loop does it (one draw per
 * view with that view's instance matrices) or layered: one instanced draw
 * per 16 views whose copies go to their eyes and tiles through
 * gl_ViewportIndex (GL_ARB_shader_viewport_layer_array). ms[0..frames-1]:
 * wall-clock per run, glFinish'ed; depth (NULL: not read): the quilt's
 * reversed-Z depth, rows bottom-up. Not used by mr_render_rig: the frame's
 * other passes still run per view (see docs/bench/multiview). */
bool mr_rig_geometry_time(mr_renderer *r, const mr_rig *rig, const mr_view *centre, int w, int h, bool layered,
                          int frames, double *ms, mr_image *depth, mr_error *err);

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

/* The GL texture holding the last finished frame (top row first),
 * for lib/window's 2D layer to show; 0 if no frame is finished. */
uint32_t mr_renderer_frame_texture(const mr_renderer *r);

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
                              default MR_DRAW_DEFAULT_LOD_PIXELS (a zeroed
                              struct's 0 is read as that default too) */
    bool occlusion;        /* occlusion culling within the frame: big
                              occluders first, then a hierarchical-Z test
                              of the rest on the CPU; exact (same image),
                              costs a depth read-back; default off */
    /* Occlusion culling where it pays, decided per frame from its
     * measured gain (geometry.c, "auto"); ignored where occlusion is on;
     * default on. */
    bool occlusion_auto;
    /* Cluster culling of big meshes. Levels with
     * at least cluster_triangles triangles are split into meshlets at
     * upload (their index ranges reordered, meshlet by meshlet); each drawn
     * instance tests its meshlets' bounding spheres against the view
     * frustum and submits the surviving ranges. 0 = the default below; it
     * takes effect at the next scene upload. */
    bool no_cluster_cull;       /* default off: clusters are culled */
    int32_t cluster_triangles;  /* 0 = MR_DRAW_DEFAULT_CLUSTER_TRIANGLES */
    /* The back-facing cone test of meshopt's meshlet bounds. It runs only
     * where the draw culls back faces: the G-buffer's instances of single-sided materials (glTF doubleSided =
     * false) under a similarity that does not mirror; there it removes
     * only triangles the rasteriser would cull, so the image is the same.
     * Default off: meshlets are cone-tested where valid. */
    bool no_cluster_cone;
    /* Where a frame runs occlusion culling (on,
     * or automatic and paying), the meshlets of the nodes that pass it are
     * tested against the same depth pyramid (exact: the same image).
     * Default off: they are. */
    bool no_cluster_occlusion;
    /* The LOD hierarchy set with mr_renderer_set_hlod is not drawn (the
     * part levels alone). Default off: it is, where one is set. */
    bool no_hlod;
} mr_draw_params;
#define MR_DRAW_DEFAULT_LOD_PIXELS 1.0
#define MR_DRAW_DEFAULT_CLUSTER_TRIANGLES 16384
#define MR_DRAW_DEFAULTS {.no_cull = false, .lod_tolerance = 0.0, .lod_pixels = MR_DRAW_DEFAULT_LOD_PIXELS, .occlusion_auto = true}
/* Option table (lib/render/options.c): --cull --batch --instancing
 * --occlusion (on|off), --lod-tolerance, --lod-pixels. Whether levels are
 * built at all (--lod auto|on|off) is the loading's choice, not a draw
 * parameter: no_lod is set by the caller. */
extern const mr_opt mr_draw_opts[];

/* What the last frame's geometry submission did (summed over the passes
 * that drew geometry). */
typedef struct mr_draw_stats {
    double cull_ms;            /* CPU: culling, LOD choice, instance data */
    uint32_t nodes_drawable;   /* nodes of the drawn layers that draw something */
    uint32_t nodes_visible;    /* of those, not culled */
    uint32_t nodes_occluded;   /* culled by occlusion (when enabled) */
    uint32_t occlusion_frames; /* draws that ran the occlusion test (auto or on) */
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
    uint32_t frustum_culls;    /* BVH frustum culls run (a rig
                                  frame's shared list: once, in its first view) */
    /* Meshlets of big meshes tested and drawn */
    uint64_t clusters_tested;
    uint64_t clusters_drawn;
    /* Meshlets of the nodes that passed the
     * occlusion test, themselves skipped by it (their bounding spheres lie
     * behind the occluders' depth) */
    uint64_t clusters_occluded;
    /* The LOD hierarchy: proxies drawn and their triangles (counted in
     * `triangles` too) */
    uint32_t hlod_proxies;
    uint64_t hlod_triangles;
} mr_draw_stats;

/* Sets how geometry is submitted from the next frame on (NULL: defaults). */
bool mr_renderer_set_draw_params(mr_renderer *r, const mr_draw_params *params, mr_error *err);
void mr_renderer_draw_stats(const mr_renderer *r, mr_draw_stats *out);
/* Forgets what automatic occlusion culling learnt
 * from the frames drawn so far (on or off, the smoothed gain, the next
 * trial), as a scene upload does, so that the next frame measures afresh;
 * the read-back cost of the frame size is kept (a cost of the size, not of
 * the view). For comparable measurements from different views. */
void mr_renderer_reset_occlusion(mr_renderer *r);
/* Draws simplified levels from `lod` (built for the scene that is set; it
 * must stay alive while set; NULL: full detail only). Re-uploads the
 * scene's geometry; setting another scene drops the levels. */
bool mr_renderer_set_lod(mr_renderer *r, const mr_lod *lod, mr_error *err);
/* mr_renderer_set_scene and mr_renderer_set_lod in one upload (a big
 * scene's upload, meshlets included, costs seconds: not twice). */
bool mr_renderer_set_scene_lod(mr_renderer *r, const mr_scene *s, const mr_lod *lod, mr_error *err);

/* Draws the proxies of `h` (built for the scene that is set, from the
 * levels set; it must stay alive while set; NULL: none) where a view's
 * cut reaches them (mr_hlod_cut: projected error under lod_pixels), and
 * the part levels below. Setting a scene or levels drops it. */
bool mr_renderer_set_hlod(mr_renderer *r, const mr_hlod *h, mr_error *err);

/* The meshlets of big meshes cached beside the
 * scene file. From the next upload (set_scene / set_lod) on, each level's
 * meshlets are read from `path` where it holds them for exactly this input
 * (keyed by the level's indices and the mesh's positions, the threshold,
 * the meshlet limits and meshoptimizer's version; checked by a checksum
 * and ranges: a stale or damaged file is ignored with a warning), else
 * built, and the file is rewritten atomically. NULL or "": no cache. */
bool mr_renderer_set_cluster_cache(mr_renderer *r, const char *path, mr_error *err);
typedef struct mr_cluster_info {
    uint64_t levels_cached;  /* clustered levels read from the cache */
    uint64_t levels_built;   /* clustered levels built (meshopt) */
    double build_s;          /* seconds building them */
    bool cache_written;
} mr_cluster_info;
/* What the last upload took from the cache. */
void mr_renderer_cluster_info(const mr_renderer *r, mr_cluster_info *out);
/* `render --verbose`: the frame's passes, draw calls, the geometry's and
 * meshlets' counts (mr_renderer_draw_stats, mr_renderer_cluster_info), the
 * upload time given and the peak RSS, as lines "mrcheck: render: ..." on f. */
void mr_render_report(FILE *f, const mr_renderer *r, const mr_frame_result *res, double upload_s);
/* The default cache path next to a scene file: "<scene>.mrclu". */
void mr_cluster_cache_path(const char *scene_path, char *out, size_t n);

#ifdef __cplusplus
}
#endif
#endif
