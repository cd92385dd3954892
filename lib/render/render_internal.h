/* Private to lib/render: the renderer's state, the per-frame context, the
 * pass registry's row type and the named resources passes exchange.
 *
 * A pass is a row of k_passes (renderer.c): a name, needed() (pure: says
 * whether this frame runs it), prepare() (allocates and compiles), run(),
 * scene_changed() and destroy() (for the state of its file), and the named
 * resources it reads and writes. Passes hand textures to each other only
 * through the frame's resource table (frame_put / frame_get). Geometry
 * (scene upload and drawing through a view) lives in geometry.c. */
#ifndef MR_RENDER_INTERNAL_H
#define MR_RENDER_INTERNAL_H

#include "gpu_internal.h"
#include "mr_bindings.h" /* uniform locations and texture units, shared with the GLSL */

/* A framebuffer with up to 4 colour textures and an optional depth texture. */
typedef struct target {
    GLuint fbo, color[4], depth;
} target;

/* The named resources of a frame: textures written by one pass and read by
 * later ones. k_resource_names (renderer.c) spells them. */
typedef enum res_id {
    RES_DEPTH = 0,      /* "depth": reversed-Z 32F depth of the G-buffer */
    RES_ALBEDO,         /* "albedo": sRGB8 */
    RES_NORMAL,         /* "normal": RGBA16F view normal, w = 1 where geometry */
    RES_IDS,            /* "ids": RG32UI node index + 1, layer */
    RES_POSITIONS,      /* "positions": RGBA32F view-space position (AO positions path) */
    RES_AO_MASK,        /* "ao.mask": R16F outline count (corner masking) */
    RES_AO,             /* "ao": R32F ambient visibility at the output size */
    RES_HIDDEN_DEPTH,   /* "hidden.depth": the hidden layer D's G-buffer ... */
    RES_HIDDEN_NORMAL,  /* "hidden.normal" */
    RES_HIDDEN_IDS,     /* "hidden.ids" */
    RES_HIDDEN_SHADED,  /* "hidden.shaded": D shaded alone (sRGB8) */
    RES_SHADED,         /* "shaded": the virtual image (sRGB8) */
    RES_IMAGE,          /* "image": the image so far; the frame's output is its last value */
    RES_CURVATURE,      /* "curvature": R32F per-pixel curvature of the occluder's mesh */
    RES_GHOST_MASK,     /* "ghost.mask": IM, region, silhouette (RGBA32F) */
    /* shadows (pass_shadow.c) */
    RES_SHADOW_MAP,     /* "shadow.map": R32F linear light depth of the casting light */
    RES_SHADOW,         /* "shadow.visibility": R32F visibility of the casting light, 1 = lit */
    /* backprojection's depth pyramid (pass_shadow.c) */
    RES_SHADOW_PYRAMID, /* "shadow.pyramid": RG32F min / max light depth mip pyramid */
    RES_COUNT
} res_id;
#define RES(x) (1u << (x))
extern const char *const mr_resource_names[RES_COUNT];

struct mr_renderer {
    mr_gpu *gpu;
    const mr_scene *scene;
    struct mr_geo *geo;    /* geometry.c: buffers, BVH, per-frame scratch */
    struct mr_hlod_gpu *hlod; /* hlod_draw.c: the LOD hierarchy's proxies (NULL: none) */
    /* A multi-view rig's shared culling (geometry.c) and its
     * views' common fitting set (multiview.c); NULL outside a rig frame. */
    struct mr_geo_share *share;
    const struct mr_rig_share *rig;
    mr_draw_params draw;   /* how geometry is submitted */
    mr_draw_stats stats;   /* of the current / last frame */
    GLuint *textures;
    int32_t texture_count;
    GLuint empty_vao;      /* for full-screen triangles */
    int w, h;              /* current output size */
    GLuint queries[MR_MAX_PASSES];
    /* The last finished frame, for showing it in a window and for picking. */
    struct {
        bool valid;
        GLuint tex;            /* texture holding the finished image */
        GLuint depth, ids;     /* its G-buffer depth and ids (picking) */
        mr_camera cam;         /* at the output size */
        mr_dmat4 world_from_camera;
        double near_plane;
        /* Its G-buffer drew proxies of the LOD hierarchy (not through a
         * display mapping), of these layers: a pick redraws the pixel at
         * the part levels (mr_gbuffer_pick_pixel). */
        bool hier;
        uint32_t layers;
    } last;
    /* The state of each pass file, owned by it (created in its prepare,
     * freed by its destroy). */
    struct mr_base_state *base;    /* passes.c: G-buffer, shading, overlay */
    struct mr_ao_state *ao;        /* pass_ao.c: AO targets, programs, kernel, reuse cache */
    struct mr_ao_state *ao_hidden; /* the same for the ghosting's hidden layer D */
    struct mr_ghost_state *ghost;  /* pass_ghost.c: targets, programs, caches */
    struct mr_shadow_state *shadow; /* pass_shadow.c: maps, visibility, the fitted light */
    /* The meshlet cache file ("" = none) and what
     * the last upload took from it (geometry.c, cluster_cache.c). */
    char cluster_cache[4096];
    mr_cluster_info cluster_info;
};

typedef struct frame {
    mr_renderer *r;
    const mr_view *view;
    const mr_frame_params *p;
    mr_camera cam;          /* the view's camera at the output size */
    mr_dmat4 cam_from_world;
    double near_plane;
    mr_frame_result *out;
    GLuint res[RES_COUNT];  /* the resource table: texture per name, 0 = not made this frame */
    uint32_t reading;       /* RES() bits some pass this frame reads (decided before any runs) */
    uint32_t writing;       /* RES() bits some pass this frame writes */
    bool ao_reused;         /* pass_ao.c: the AO of an earlier frame stands in */
    int ao_hidden_plan;     /* pass_ao.c: what the hidden layer's AO does this frame */
} frame;

static inline void frame_put(frame *f, res_id id, GLuint tex) { f->res[id] = tex; }
static inline GLuint frame_get(const frame *f, res_id id) { return f->res[id]; }

typedef struct pass_desc {
    const char *name;                       /* in the frame's pass list (NULL: not listed) */
    bool (*needed)(const frame *f);         /* no side effects; NULL = always */
    bool (*prepare)(frame *f, mr_error *err); /* allocation and compilation; NULL = nothing */
    void (*run)(frame *f);
    void (*scene_changed)(mr_renderer *r);  /* drops what was derived from the scene; NULL */
    void (*destroy)(mr_renderer *r);        /* frees the file's state (idempotent); NULL */
    uint32_t reads;                         /* RES() bits it needs an earlier pass to have written */
    uint32_t uses;                          /* RES() bits it reads when some earlier pass made them */
    uint32_t writes;                        /* RES() bits */
    uint32_t (*reads_now)(const frame *f);  /* the part of `reads` this frame needs; NULL = all */
    /* Checks the frame's settings of this pass file before any row runs
     * (one line in err); NULL = nothing to check. */
    bool (*check)(const mr_frame_params *p, mr_error *err);
    /* After the frame: copies what the caller asked for (mr_frame_params'
     * want_*) into f->out; called whether or not the row ran; NULL. */
    bool (*read_back)(frame *f, mr_error *err);
} pass_desc;

/* A way to draw the scene: from the frame's camera or any other eye. */
typedef struct mr_geo_view {
    mr_camera cam;              /* intrinsics at the target size */
    mr_dmat4 cam_from_world, world_from_camera;
    double near_plane;
    GLuint program;             /* its MR_LOC_PROJECTION receives the projection */
    uint32_t layers;            /* 1 << mr_layer of the nodes drawn */
    bool shared;                /* a rig view: draws the rig frame's shared list */
    /* Cull the back faces of single-sided
     * materials (glTF doubleSided = false), as glTF says they look; only
     * then may back-facing meshlets be skipped. Set by the G-buffer. */
    bool cull_back;
    /* The pixel factor of the LOD choice (mr_geometry_lod_fmax); 0: cam's.
     * A draw of one pixel of a frame passes the frame camera's, so it
     * chooses the frame's levels. */
    double lod_fmax;
} mr_geo_view;
/* The frame's camera with a program and layers. */
mr_geo_view mr_frame_view(const frame *f, GLuint program, uint32_t layers);

/* GL helpers (gl_util.c). */
GLuint mr_gl_make_tex(GLenum fmt, int w, int h, GLenum filter);
bool mr_gl_target_make(target *t, int w, int h, const GLenum *fmts, int n, bool depth, mr_error *err);
void mr_gl_target_free(target *t);
/* Reversed-Z infinite projection for OpenCV intrinsics (column-major). */
void mr_gl_projection(const mr_camera *c, double near_plane, float out[16]);

/* Geometry (geometry.c). */
bool mr_geometry_upload(mr_renderer *r, const mr_scene *s, const mr_lod *lod, mr_error *err);
void mr_geometry_free(mr_renderer *r);
/* Draws the view's layers with its program into the bound framebuffer
 * (culling, LOD, instancing), counting triangles and draw calls into out
 * (may be NULL). */
void mr_geometry_draw(mr_renderer *r, const mr_geo_view *view, mr_frame_result *out);
/* Resets the frame's draw statistics (called by mr_render_frame). */
void mr_geometry_begin_frame(mr_renderer *r);

/* Multi-view rigs. Until share_end, draws with .shared set cull
 * once per layer set against `cull` and choose LOD levels once (with the
 * depth row of cam_from_world, near_plane and fmax_t, the largest
 * mr_geometry_lod_fmax of the views), then each draws that list through
 * its own camera. */
bool mr_geometry_share_begin(mr_renderer *r, const mr_frustum *cull, const mr_dmat4 *cam_from_world, double near_plane,
                             double fmax_t, mr_error *err);
void mr_geometry_share_end(mr_renderer *r);
double mr_geometry_lod_fmax(const mr_camera *c);
/* The layered experiment: the shared list of vw->layers through vw's
 * camera, each instance drawn `replicate` times (attribute divisor); the
 * caller's program and uniforms place the copies. False outside a share. */
bool mr_geometry_draw_replicated(mr_renderer *r, const mr_geo_view *vw, int replicate);
/* What a rig frame's views have in common, for fitting what is made once
 * per frame (the shadow maps): the centre camera, the two outer views
 * (every view's frustum lies in their hull, slice by slice) and the union
 * volume's planes in the centre camera's axes. */
typedef struct mr_rig_share {
    mr_camera centre_cam;        /* at the output size, no shear */
    mr_dmat4 world_from_centre, centre_from_world;
    mr_camera cam[2];            /* views 0 and N-1 */
    mr_dmat4 world_from_camera[2];
    double near_plane;           /* the nearest of the views' */
    double planes[5][4];         /* centre camera: a.xyz . p + a.w >= 0 inside (the last: z >= near) */
    int views;
    unsigned serial;             /* this rig frame's number, from 1 */
} mr_rig_share;
/* The near plane mr_render_frame picks for an eye (renderer.c). */
double mr_render_near_plane(const mr_scene *s, const mr_dmat4 *world_from_camera);

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
/* Draws every node of the view's layers at full detail, no culling, through
 * the aux VAOs with the view's program (uniforms other than the matrices set
 * by the caller); sets MR_LOC_PROJECTION, and per instance MR_LOC_MODELVIEW
 * (camera relative, composed in double) and MR_LOC_NORMAL_MATRIX. */
void mr_geometry_aux_draw(mr_renderer *r, const mr_geo_view *view, const mr_geo_aux *aux);

/* Meshes of a pass's own, one per scene mesh (AO outline volumes): each a
 * position and one 3-float stream (`attrib`) per vertex and its triangles,
 * packed in one vertex and one index buffer; drawn with each scene node's
 * transform like mr_geometry_aux_draw (a mesh with no triangles draws
 * nothing). */
typedef struct mr_geo_own_mesh {
    const float *positions, *attr;  /* 3 floats per vertex each */
    const uint32_t *indices;
    uint32_t vertex_count, index_count;
} mr_geo_own_mesh;
typedef struct mr_geo_own {
    GLuint vao, vbo, ibo;
    uint32_t *first, *count;        /* per scene mesh: first index, index count */
    int32_t *base;                  /* per scene mesh: base vertex */
    int32_t mesh_count;
    bool valid;
} mr_geo_own;
bool mr_geometry_own_create(const mr_geo_own_mesh *meshes, int32_t n, GLuint attrib, mr_geo_own *o);
void mr_geometry_own_free(mr_geo_own *o);
void mr_geometry_own_draw(mr_renderer *r, const mr_geo_view *view, const mr_geo_own *o);

/* The registry's rows: each pass file defines its descriptors, renderer.c
 * lists them in order. */
extern const pass_desc mr_pass_desc_gbuffer, mr_pass_desc_shade, mr_pass_desc_overlay;         /* passes.c */
extern const pass_desc mr_pass_desc_ao_mask, mr_pass_desc_ao, mr_pass_desc_ao_blur, mr_pass_desc_ao_upsample,
    mr_pass_desc_ao_reuse, mr_pass_desc_ao_external;
extern const pass_desc mr_pass_desc_ao_deint_split, mr_pass_desc_ao_deint_merge; /* pass_ao.c */
extern const pass_desc mr_pass_desc_ao_temporal;                                  /* pass_ao.c */
extern const pass_desc mr_pass_desc_ghost_hidden, mr_pass_desc_ghost_curvature, mr_pass_desc_ghost_importance,
    mr_pass_desc_ghost_g0, mr_pass_desc_ghost_analysis, mr_pass_desc_ghost_emphasis;            /* pass_ghost.c */
extern const pass_desc mr_pass_desc_shadow_map, mr_pass_desc_shadow_map_reuse, mr_pass_desc_shadow; /* pass_shadow.c */
extern const pass_desc mr_pass_desc_shadow_pyramid, mr_pass_desc_shadow_pyramid_reuse;                 /* pass_shadow.c */

/* Helpers the pass files share. */

/* passes.c */
void mr_base_free(mr_renderer *r);
/* Binds a G-buffer-layout target, clears it (depth to infinity) and sets
 * the depth state the geometry pass draws with. */
void mr_gbuffer_begin(frame *f, const target *t);
/* The G-buffer program (for drawing another layer into a G-buffer). */
GLuint mr_gbuffer_program(const frame *f);
/* The last frame's G-buffer at pixel (px, py) drawn again without the LOD
 * hierarchy (the part levels the frame would have chosen, same camera and
 * layers) into a 1x1 target: its depth and ids, exactly those of a frame
 * drawn without the hierarchy. */
bool mr_gbuffer_pick_pixel(mr_renderer *r, int px, int py, float *depth, GLuint ids[2], mr_error *err);
/* Shades albedo + normal (+ ao, 0 = none) into dst's first colour target
 * with the scene's lights: the main image and the hidden layer D. */
void mr_shade_draw(frame *f, GLuint albedo, GLuint normal, GLuint ao, const target *dst);
/* The lights of a scene without lights (the first, a sun, casts). */
extern const mr_light mr_default_lights[2];


/* pass_ao.c: ambient occlusion. */
typedef struct mr_ao_state mr_ao_state;
/* AO of the hidden layer D (depth, normal) with the frame's AO settings, in
 * a state of its own (reuse works per target); no corner mask, no
 * positions path. prepare before run; run returns the AO texture or 0. */
bool mr_ao_hidden_prepare(frame *f, mr_error *err);
GLuint mr_ao_hidden_run(frame *f, GLuint depth, GLuint normal);
void mr_pass_ao_free(mr_renderer *r);

/* pass_shadow.c: soft shadows. The index among the shaded lights of the
 * casting one (-1: none). */
int mr_shadow_light_index(const mr_scene *s);
void mr_pass_shadow_free(mr_renderer *r);
/* The overlay's shadow catcher: sets its uniforms and textures on the bound
 * overlay program (catcher off when the scene marks no receivers). */
bool mr_shadow_catcher_setup(frame *f, GLuint program, mr_error *err);

#endif
