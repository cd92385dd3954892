/* mr_scene.h — the planned model in memory: meshes, materials, textures and a
 * node tree flattened to double-precision world transforms, split into a
 * visible and a hidden layer. glTF 2.0 import/export (tinygltf, behind
 * gltf_io.cc) and the procedural demo factory live here too.
 *
 * Plain data (sokol style): the structs are public and read directly by the
 * renderer; build them with the mr_scene_add_* functions so bounds and
 * ownership stay consistent.
 *
 * Precision: mesh positions are float and stored relative to the mesh's own
 * double-precision `origin` (the centre of its bounds), so vertices far from
 * the glTF origin keep their precision; a node's world transform is double.
 * The model matrix of a mesh drawn by node n is n.world * T(mesh.origin).
 */
#ifndef MR_SCENE_H
#define MR_SCENE_H

#include "mr_core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mr_layer { MR_LAYER_VISIBLE = 0, MR_LAYER_HIDDEN = 1, MR_LAYER_COUNT = 2 } mr_layer;

/* One triangle list with one material (a glTF primitive). */
typedef struct mr_mesh {
    char name[64];
    double origin[3];        /* scene units; positions are relative to it */
    float *positions;        /* 3 * vertex_count */
    float *normals;          /* 3 * vertex_count, unit length */
    float *uvs;              /* 2 * vertex_count, or NULL */
    uint32_t *indices;       /* index_count, a multiple of 3 */
    uint32_t vertex_count, index_count;
    int32_t material;        /* index into materials, or -1 (default grey) */
    float bounds_min[3], bounds_max[3]; /* of positions (relative to origin) */
} mr_mesh;

typedef struct mr_material {
    char name[64];
    float base_color[4];         /* linear RGBA factor, default 1 1 1 1 */
    int32_t base_color_texture;  /* index into textures, or -1 */
} mr_material;

typedef struct mr_texture {
    mr_image image;   /* RGBA8, sRGB-encoded as glTF stores colour */
    bool nearest;     /* magnification filter NEAREST (AprilTag plates) */
} mr_texture;

typedef struct mr_node {
    char name[96];
    int32_t parent;       /* -1 for roots */
    mr_dmat4 world;       /* world_from_node, flattened */
    int32_t mesh_first;   /* first of mesh_count consecutive meshes, or -1 */
    int32_t mesh_count;
    uint8_t layer;        /* mr_layer */
} mr_node;

/* A directional light: `direction` points from the scene towards the light,
 * in world space. */
typedef struct mr_light {
    double direction[3];
    float color[3];       /* linear, multiplies the albedo */
} mr_light;

#define MR_SCENE_MAX_LIGHTS 8

typedef struct mr_scene {
    mr_mesh *meshes;         int32_t mesh_count, mesh_cap;
    mr_material *materials;  int32_t material_count, material_cap;
    mr_texture *textures;    int32_t texture_count, texture_cap;
    mr_node *nodes;          int32_t node_count, node_cap;
    mr_light lights[MR_SCENE_MAX_LIGHTS];
    int32_t light_count;     /* 0: the renderer's default sun */
    float ambient;           /* ambient term in [0,1], default 0.35 */
    double bounds_min[3], bounds_max[3]; /* world, over all drawn nodes */
    char source[512];        /* file it came from ("" if built in memory) */
} mr_scene;

/* ------------------------------------------------------------- building */

mr_scene *mr_scene_create(void);
void mr_scene_destroy(mr_scene **scene); /* NULLs, accepts NULL */

/* Takes ownership of the arrays in *mesh (malloc'd). Recentres positions on
 * their bounds centre (moving the difference into mesh->origin), generates
 * normals if mesh->normals is NULL, and validates indices and finiteness.
 * Returns the new mesh index, or -1 + err. */
int32_t mr_scene_add_mesh(mr_scene *s, mr_mesh *mesh, mr_error *err);
int32_t mr_scene_add_material(mr_scene *s, const mr_material *mat);
/* Takes ownership of tex->image.data. */
int32_t mr_scene_add_texture(mr_scene *s, mr_texture *tex);
int32_t mr_scene_add_node(mr_scene *s, const mr_node *node);
/* Recomputes bounds_min/max from nodes and meshes. */
void mr_scene_update_bounds(mr_scene *s);
/* Counts over drawn nodes (instances counted each time they are drawn). */
uint64_t mr_scene_triangle_count(const mr_scene *s);
/* Area-weighted smooth normals for a triangle list (out: 3*vertex_count). */
void mr_mesh_generate_normals(const float *positions, uint32_t vertex_count,
                              const uint32_t *indices, uint32_t index_count, float *normals);

/* ------------------------------------------------------------- loading */

typedef struct mr_scene_params {
    const char *const *hidden_globs; /* node-name globs for the hidden layer */
    int hidden_glob_count;
} mr_scene_params;
#define MR_SCENE_DEFAULTS {0}

/* Loads a scene from a .gltf/.glb (recognised by content, not extension)
 * or a scene config JSON: {"gltf": "rel/path.glb", "hidden": ["Pipe*"],
 * "lights": [{"direction": [x,y,z], "color": [r,g,b]}], "ambient": 0.35}.
 * A node is hidden if any glob matches its name (or an ancestor's) or its
 * glTF extras has "mrcheck_layer": "hidden" (inherited by children). */
mr_scene *mr_scene_load(const char *path, const mr_scene_params *params, mr_error *err);
/* glTF only, from memory (used by load and by fuzz tests). base_dir resolves
 * external buffers/images; NULL forbids external files. */
mr_scene *mr_scene_load_gltf_memory(const void *data, size_t size, const char *base_dir,
                                    const mr_scene_params *params, mr_error *err);
/* Writes the scene as a binary glTF (.glb), atomically. Nodes are written
 * flat (world transforms as matrices); hidden nodes get
 * extras.mrcheck_layer = "hidden". */
bool mr_scene_save_glb(const mr_scene *s, const char *path, mr_error *err);

/* Shell-style glob: '*' any run, '?' one char, '[abc]' a set. */
bool mr_glob_match(const char *pattern, const char *text);

/* ----------------------------------------------------------- demo hall */

typedef struct mr_demo_params {
    uint64_t seed;            /* default 1 */
    double tag_size;          /* AprilTag black-square edge in metres, default 0.4 */
    const mr_image *tag_images; /* tag_image_count AprilTag images (gray8, with
                                   white border), tag i has id i; may be NULL */
    int tag_image_count;
    int tag_border_px;        /* white border width in those images (px), default 1 */
    bool pipes_like_partition; /* ghosting conflict case: the hidden pipes get the
                                  partition's colour; default false */
} mr_demo_params;
#define MR_DEMO_DEFAULTS {1, 0.4, NULL, 0, 1, false}

/* One AprilTag plate of the demo hall. */
typedef struct mr_demo_tag {
    int id;
    mr_dmat4 world_from_tag; /* tag frame: origin at centre, x right, y down
                                as seen facing the tag, z into the surface */
} mr_demo_tag;

typedef struct mr_demo_hall {
    mr_scene *planned;        /* as planned */
    mr_scene *built;          /* as built: with the discrepancies */
    mr_demo_tag *tags; int tag_count;
    double tag_size;
    cJSON *discrepancies;     /* array of {id, kind, node, description, ...} */
    const char *const *hidden_globs; int hidden_glob_count; /* for configs */
} mr_demo_hall;

/* ------------------------------------------------------ outline meshes */

/* Corner masking (Park & Baek): the integrated-normal extrusion direction of
 * every vertex of mesh m (unit length, mesh space) into out (3 *
 * vertex_count floats): vertices welded by position, the distinct face
 * normals around each averaged. An outline mesh is the mesh with each vertex
 * moved by radius * out[v]. Computed once per mesh by the renderer. */
bool mr_mesh_outline_dirs(const mr_mesh *m, float *out, mr_error *err);

bool mr_demo_build(const mr_demo_params *params, mr_demo_hall *out, mr_error *err);
void mr_demo_free(mr_demo_hall *hall);

/* ------------------------------------------------------------ curvature */

/* Per-vertex maximum principal curvature magnitude |kappa_max| of a mesh in
 * 1/scene units (out: vertex_count floats), estimated from the normal
 * variation along the edges that share the vertex: for an edge e = p_j - p_i,
 * the normal curvature is (n_j - n_i).e / |e|^2 (exact for a sphere). Only
 * edges of the same smooth patch count (shared vertex indices): at a crease
 * (split vertices, as CAD exports flat faces) the curvature is a line
 * singularity that the renderer finds in screen space from the normals.
 * Degenerate edges are skipped; the result is finite and >= 0. Linear time
 * in index_count. Scale: kappa(s * mesh) = kappa(mesh) / s. */
void mr_mesh_curvature(const mr_mesh *mesh, float *out);

#ifdef __cplusplus
}
#endif
#endif
