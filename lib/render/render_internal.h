/* Private to lib/render: the renderer's state, the per-frame context and the
 * pass interface. A pass lives in its own file (passes.c, later pass_ao.c,
 * pass_ghost.c, ...) and is listed in k_passes in renderer.c with a predicate
 * saying when a frame needs it. Geometry (scene upload and drawing) lives in
 * geometry.c. */
#ifndef MR_RENDER_INTERNAL_H
#define MR_RENDER_INTERNAL_H

#include "gpu_internal.h"

/* A framebuffer with up to 4 colour textures and an optional depth texture. */
typedef struct target {
    GLuint fbo, color[4], depth;
} target;

struct mr_renderer {
    mr_gpu *gpu;
    const mr_scene *scene;
    struct mr_geo *geo;    /* geometry.c: buffers, BVH, per-frame scratch */
    mr_draw_params draw;   /* how geometry is submitted */
    mr_draw_stats stats;   /* of the current / last frame */
    GLuint *textures;
    int32_t texture_count;
    GLuint prog_gbuffer, prog_shade, prog_overlay;
    GLuint empty_vao;
    int w, h;              /* current target size */
    target gbuf;           /* albedo (sRGB8), normal (RGBA16F), ids (RG32UI), depth (32F) */
    target shaded;         /* sRGB8: the virtual image */
    target composed;       /* sRGB8: virtual + video */
    GLuint video_tex;
    int video_w, video_h;
    GLuint queries[MR_MAX_PASSES];
    /* The last finished frame, for showing it in a window and for picking. */
    struct {
        bool valid;
        GLuint tex;            /* texture holding the finished image */
        mr_camera cam;         /* at the output size */
        mr_dmat4 world_from_camera;
        double near_plane;
    } last;
    struct mr_ao_state *ao; /* pass_ao.c: AO targets, programs, kernel, reuse cache */
    struct mr_ao_state *ao_hidden; /* the same for the ghosting's hidden layer D */
    struct mr_ghost_state *ghost; /* pass_ghost.c: targets, programs, caches; NULL until first used */
};

typedef struct frame {
    mr_renderer *r;
    const mr_view *view;
    const mr_frame_params *p;
    mr_camera cam;          /* the view's camera at the output size */
    mr_dmat4 cam_from_world;
    double near_plane;
    mr_frame_result *out;
    GLuint final_tex;       /* the texture holding the finished image */
    int ao_plan;            /* pass_ao.c: decided once per frame (off / reuse / run) */
    GLuint hidden_ao;       /* AO of the hidden layer D (pass_ghost.c), 0 if none */
    int ghost;              /* pass_ghost.c: 0 not decided yet, 1 ghosting runs, -1 it does not */
} frame;

typedef struct pass_desc {
    const char *name;
    bool (*needed)(frame *f);
    void (*run)(frame *f);
} pass_desc;

/* Helpers (renderer.c). */
GLuint mr_gl_make_tex(GLenum fmt, int w, int h, GLenum filter);
bool mr_gl_target_make(target *t, int w, int h, const GLenum *fmts, int n, bool depth, mr_error *err);
void mr_gl_target_free(target *t);
/* Reversed-Z infinite projection for OpenCV intrinsics (column-major). */
void mr_gl_projection(const mr_camera *c, double near_plane, float out[16]);

/* Geometry (geometry.c). */
bool mr_geometry_upload(mr_renderer *r, const mr_scene *s, mr_error *err);
void mr_geometry_free(mr_renderer *r);
/* Draws the nodes whose layer bit (1 << layer) is in layer_mask with the
 * G-buffer program into the currently bound framebuffer, counting triangles
 * and draw calls into the frame result. */
void mr_geometry_draw(frame *f, uint32_t layer_mask);
/* Resets the frame's draw statistics (called by mr_render_frame). */
void mr_geometry_begin_frame(mr_renderer *r);

/* Extra per-vertex streams for passes that draw the scene with their own
 * program (AO outline volumes, ghost curvature): one buffer per vertex pool,
 * laid out like the shared geometry, paired with the pools' positions
 * (attribute 0) in VAOs of their own; `attrib` receives the stream. */
typedef struct mr_geo_aux {
    GLuint vao[2], vbo[2];
    bool valid;
} mr_geo_aux;
/* per_mesh[i]: comps floats per vertex of scene mesh i (NULL: zeros). */
bool mr_geometry_aux_create(mr_renderer *r, float *const *per_mesh, int comps, GLuint attrib, mr_geo_aux *aux);
void mr_geometry_aux_free(mr_geo_aux *aux);
/* Draws every node of the layers at full detail, no culling, through the aux
 * VAOs with the bound program; sets uniform location 0 (model-view, camera
 * relative, composed in double) and 1 (its normal matrix) per instance. */
void mr_geometry_aux_draw(frame *f, const mr_geo_aux *aux, uint32_t layer_mask);

/* Passes (passes.c). */
bool mr_pass_need_always(frame *f);
bool mr_pass_need_overlay(frame *f);
/* Binds a G-buffer-layout target, clears it (depth to infinity) and sets
 * the depth state the geometry pass draws with. */
void mr_gbuffer_begin(frame *f, const target *t);
void mr_pass_gbuffer(frame *f);
void mr_pass_shade(frame *f);
void mr_pass_overlay(frame *f);
/* Shades G-buffer `src` (albedo, normal) into `dst`'s first colour target
 * with the scene's lights (used for the main image and for the hidden
 * layer D of ghosted views). */
void mr_shade_draw(frame *f, const target *src, const target *dst);

/* Ghosted views (pass_ghost.c). mr_ghost_active: this frame ghosts (a mode
 * other than off, the hidden layer drawn, and hidden structure in view);
 * then the G-buffer pass leaves the hidden layer to the ghost passes. */
bool mr_ghost_active(frame *f);
bool mr_pass_need_ghost(frame *f);
bool mr_pass_need_ghost_curvature(frame *f);
bool mr_pass_need_ghost_adaptive(frame *f);
void mr_pass_ghost_hidden(frame *f);
void mr_pass_ghost_curvature(frame *f);
void mr_pass_ghost_importance(frame *f);
void mr_pass_ghost_g0(frame *f);
void mr_pass_ghost_analysis(frame *f);
void mr_pass_ghost_emphasis(frame *f);
/* Checks the ghost parameters and builds programs and targets, before the
 * frame's passes run (so a failure fails the frame). */
bool mr_ghost_prepare(mr_renderer *r, const mr_ghost_params *gp, int w, int h, mr_error *err);
/* Drops what was derived from the scene (per-mesh curvature buffers). */
void mr_ghost_scene_changed(mr_renderer *r);
void mr_ghost_free(mr_renderer *r);

/* Ambient occlusion (pass_ao.c). */
typedef struct mr_ao_state mr_ao_state;
bool mr_pass_need_ao_positions(frame *f);
bool mr_pass_need_ao_mask(frame *f);
bool mr_pass_need_ao(frame *f);
bool mr_pass_need_ao_blur(frame *f);
bool mr_pass_need_ao_upsample(frame *f);
void mr_pass_ao_mask(frame *f);
void mr_pass_ao(frame *f);
void mr_pass_ao_blur(frame *f);
void mr_pass_ao_upsample(frame *f);
/* The finished AO texture of this frame (computed or reused), or 0. */
GLuint mr_pass_ao_texture(frame *f);
/* AO of another G-buffer-like target (the ghosting's hidden layer D) with
 * the frame's AO settings, in a state of its own (reuse works per target);
 * no corner mask, no positions path. Returns the AO texture or 0. */
GLuint mr_pass_ao_for_hidden(frame *f, const target *src);
/* Fills out->ao (if asked) and the mask statistics; reports a failed AO shader. */
bool mr_pass_ao_read_back(frame *f, mr_error *err);
void mr_pass_ao_scene_changed(mr_renderer *r);
void mr_pass_ao_free(mr_renderer *r);

#endif
