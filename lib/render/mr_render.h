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
#define MR_GPU_DEFAULTS {false}

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
} mr_frame_params;
#define MR_FRAME_DEFAULTS {0, 0, NULL, 0.5f, false, {0.62f, 0.66f, 0.70f}, false, false, false}

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
} mr_frame_result;

/* Renders one frame of the current scene seen through `view`. */
bool mr_render_frame(mr_renderer *r, const mr_view *view, const mr_frame_params *params,
                     mr_frame_result *out, mr_error *err);
void mr_frame_result_free(mr_frame_result *res);
/* "gbuffer shade overlay" — the pass list as one line. */
void mr_frame_result_passes(const mr_frame_result *res, char *buf, size_t n);

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
                              may have, whatever its projected size; 0 = 0.005
                              (5 mm in a metre scene); < 0: no LOD at all */
    double lod_pixels;     /* largest projected error of a chosen level, pixels;
                              0 = 1.0 */
    bool occlusion;        /* occlusion culling within the frame: big
                              occluders first, then a hierarchical-Z test
                              of the rest on the CPU; exact (same image),
                              costs a depth read-back; default off */
} mr_draw_params;
#define MR_DRAW_DEFAULTS {false, false, false, false, 0.0, 0.0, false}

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
