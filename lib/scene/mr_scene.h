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
    /* glTF's doubleSided = false. Zero (the
     * default of a material built in memory) is double-sided: both faces
     * drawn, as before. A single-sided material's back faces are culled in
     * the G-buffer (and its meshlets' back-facing cones with them); a
     * primitive without material is drawn double-sided. */
    bool single_sided;
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
    bool shadow_catcher;  /* a shadow receiver of the scene config: over video it is not
                             drawn, it darkens the camera image by its shadow */
} mr_node;

/* A light: `direction` points from the scene towards the light, in world
 * space; the shading treats every light as directional along it. For
 * shadows a light has a size, in scene units or as an angle, never a fixed
 * scale: */
typedef enum mr_light_kind {
    MR_LIGHT_SUN = 0,     /* at infinity along direction, angular diameter `angle` */
    MR_LIGHT_RECT,        /* a rectangle centred at position, facing -direction
                             (it emits away from `direction`), size[0] along axis_u,
                             size[1] along direction x axis_u */
    MR_LIGHT_SPHERE,      /* a sphere of radius size[0] centred at position */
} mr_light_kind;

typedef struct mr_light {
    double direction[3];
    float color[3];       /* linear, multiplies the albedo */
    /* Shadows; all zero = a sun of angle 0 that casts nothing. */
    uint8_t kind;         /* mr_light_kind */
    bool casts;           /* casts shadows when a shadow method is on */
    double angle;         /* sun: angular diameter in degrees, [0, 90) */
    double position[3];   /* rect, sphere: centre (world, scene units) */
    double size[2];       /* rect: width, height; sphere: radius in size[0] (scene units) */
    double axis_u[3];     /* rect: unit direction of the width side, orthogonal to direction */
} mr_light;
/* The sun's angular diameter where a scene does not give one (degrees): a
 * slightly overcast sun, so that contact hardening is visible. */
#define MR_LIGHT_DEFAULT_SUN_ANGLE 2.0

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
    char shadow_method[16];  /* the scene config's "shadows" (a method name the
                                renderer parses), "" = not given: off */
    /* Internal (scene.c): buffers that each hold several meshes' arrays
     * (a compressed glTF file's decoded index lists, a big file's
     * medium-sized arrays), freed with the scene; an array inside one is
     * not freed on its own. */
    struct mr_scene_block *blocks;
    int32_t block_count, block_cap;
    bool blocks_sorted;
    /* What the model says its parts are (element.c): IFC identity of the
     * nodes that have one, sorted by node; the storeys they name. */
    struct mr_element *elements; int32_t element_count, element_cap;
    struct mr_storey *storeys;   int32_t storey_count, storey_cap;
    /* Where the scene came from, for a cache beside a converted file: a key
     * of the source bytes ("" none); written into and read from the .glb's
     * asset extras ("mrcheck_source"). */
    char source_key[40];
} mr_scene;

/* ------------------------------------------------- elements (element.c)
 * A node that stands for a building element: an IFC product (an IFC file,
 * or a glTF whose node extras or names carry IFC identity). Other nodes
 * have none. The element of a node is its own or its nearest ancestor's. */
typedef struct mr_element {
    int32_t node;             /* the scene node */
    char guid[24];            /* IFC GlobalId (22 chars, IFC base64), "" if none */
    char ifc_class[48];       /* e.g. "IfcWall", "" if unknown */
    int32_t storey;           /* index into scene->storeys, -1: none */
    char *props;              /* property sets as a JSON object
                                 {"Pset_WallCommon": {"IsExternal": true}} (values in the
                                 file's units), malloc'd and owned by the scene, or NULL */
} mr_element;

typedef struct mr_storey {
    char name[64];
    char guid[24];
    double elevation;         /* metres, as the file gives it (0 if not) */
} mr_storey;

/* Copies *e (taking over e->props) and keeps the list sorted by node;
 * returns false (e->props freed) for a bad node or no memory. A node's
 * second element replaces its first. */
bool mr_scene_add_element(mr_scene *s, mr_element *e);
/* The storey named `name` (guid may be NULL or ""), added if new; -1 on no
 * memory. */
int32_t mr_scene_storey(mr_scene *s, const char *name, const char *guid, double elevation);
/* The element of node (its own or its nearest ancestor's), or NULL. */
const mr_element *mr_scene_element_of(const mr_scene *s, int32_t node);
/* What a mark says about the element under node: the element's GlobalId
 * and class ("" none) and its name (its node's name; without an element,
 * node's own name). All "" for node < 0 or out of range. */
typedef struct mr_element_words {
    char guid[24], ifc_class[48], name[128];
} mr_element_words;
mr_element_words mr_scene_element_words(const mr_scene *s, int32_t node);
/* The element under node in one line for the view's tap: "Wall A ·
 * IfcWall · Level 1 · IsExternal=true, ..." (name, class, storey, then up
 * to max_props properties of its property sets). "" for no node. */
void mr_scene_element_describe(const mr_scene *s, int32_t node, int max_props, char *out, size_t n);
/* The node whose element has this GlobalId, or -1. */
int32_t mr_scene_node_of_guid(const mr_scene *s, const char *guid);
/* True if text is 22 characters of IFC's base64 alphabet (0-9A-Za-z_$)
 * with a first character of 0-3: the shape of an IFC GlobalId. */
bool mr_ifc_guid_valid(const char *text);
/* The default hidden layer of a model: IFC's distribution elements (pipes,
 * ducts, cable carriers and their fittings, terminals, equipment: the
 * subtypes of IfcDistributionElement in IFC2x3 and IFC4). Case-insensitive;
 * a trailing "StandardCase" or "Type" is ignored. */
bool mr_ifc_class_is_distribution(const char *ifc_class);
/* Sets the layer of every node with an element from its class: hidden if
 * any of the globs (case-insensitive, over the class name) matches, or, when
 * globs is NULL, if mr_ifc_class_is_distribution. Children follow their
 * parents' hidden layer. Nodes are only ever moved into the hidden layer. */
void mr_scene_hide_classes(mr_scene *s, const char *const *globs, int glob_count);
void mr_scene_elements_free(mr_scene *s); /* called by mr_scene_destroy */
/* A node's element from its glTF extras (cJSON object, may be NULL) and its
 * name (element.c lists the keys read); false if it carries no identity. */
bool mr_scene_element_from_extras(mr_scene *s, int32_t node, const cJSON *extras);
/* The extras mr_scene_save_glb writes for node's own element (caller frees),
 * or NULL: ifc_guid, ifc_class, ifc_storey, ifc_storey_elevation, ifc_props. */
cJSON *mr_scene_element_extras(const mr_scene *s, int32_t node);

/* ------------------------------------------------------------- building */

mr_scene *mr_scene_create(void);
void mr_scene_destroy(mr_scene **scene); /* NULLs, accepts NULL */

/* Takes ownership of the arrays in *mesh (malloc'd). Recentres positions on
 * their bounds centre (moving the difference into mesh->origin), generates
 * normals if mesh->normals is NULL, and validates indices and finiteness.
 * Returns the new mesh index, or -1 + err. */
int32_t mr_scene_add_mesh(mr_scene *s, mr_mesh *mesh, mr_error *err);
/* mr_scene_add_mesh in two steps, so that a loader can prepare meshes on
 * another thread: mr_mesh_prepare does all of it that needs no scene (the
 * checks, the recentring, the normals; it touches only *mesh, and on failure
 * changes nothing), mr_scene_add_prepared_mesh checks the material and takes
 * the arrays (false/-1: the caller still owns them). Only a mesh that
 * mr_mesh_prepare accepted, unchanged since, may be added prepared. */
bool mr_mesh_prepare(mr_mesh *mesh, mr_error *err);
int32_t mr_scene_add_prepared_mesh(mr_scene *s, mr_mesh *mesh, mr_error *err);
int32_t mr_scene_add_material(mr_scene *s, const mr_material *mat);
/* Takes ownership of tex->image.data. */
int32_t mr_scene_add_texture(mr_scene *s, mr_texture *tex);
int32_t mr_scene_add_node(mr_scene *s, const mr_node *node);
/* Recomputes bounds_min/max from nodes and meshes. */
void mr_scene_update_bounds(mr_scene *s);
/* Counts over drawn nodes (instances counted each time they are drawn). */
uint64_t mr_scene_triangle_count(const mr_scene *s);
/* Length of the diagonal of the scene's world bounds (scene units): the
 * scale every scene-relative default is a fraction of. 0 for NULL, an empty
 * scene or bounds that are not finite; callers choose their own fallback. */
double mr_scene_diagonal(const mr_scene *s);
/* A view for any model (auto_view.c): the whole scene seen from the corner
 * of its bounds at +x +z (Y up), MR_AUTO_VIEW_ELEVATION_DEG above the
 * horizon, looking at the bounds' centre from the nearest distance at
 * which every point of the bounds (so every vertex) projects inside the
 * image with MR_AUTO_VIEW_MARGIN of each side left free. A pinhole without
 * distortion, square pixels, vertical field of view MR_AUTO_VIEW_FOV_DEG,
 * width x height px (0: MR_AUTO_VIEW_DEFAULT_WIDTH x ..._HEIGHT, or 3:4 of
 * a given width). Double precision throughout: any scale, any offset. An
 * empty scene gets a view of a unit box at the origin. */
#define MR_AUTO_VIEW_DEFAULT_WIDTH 800
#define MR_AUTO_VIEW_DEFAULT_HEIGHT 600
#define MR_AUTO_VIEW_FOV_DEG 50.0
#define MR_AUTO_VIEW_ELEVATION_DEG 30.0
#define MR_AUTO_VIEW_MARGIN 0.05
mr_view mr_scene_auto_view(const mr_scene *s, int width, int height);
/* Area-weighted smooth normals for a triangle list (out: 3*vertex_count). */
void mr_mesh_generate_normals(const float *positions, uint32_t vertex_count,
                              const uint32_t *indices, uint32_t index_count, float *normals);

/* ------------------------------------------------------------- loading */

typedef struct mr_scene_params {
    const char *const *hidden_globs; /* node-name globs for the hidden layer */
    int hidden_glob_count;
    /* Called now and then during a load with the stage ("read", "parse",
     * "nodes": meshes are read when a node first uses them; its fraction is
     * of the nodes or of the file's bytes read, whichever is further) and
     * its fraction done in [0,1]; NULL: none. */
    void (*progress)(void *user, const char *stage, double fraction);
    void *progress_user;
    /* IFC class globs (case-insensitive) whose elements form the hidden
     * layer, for models that carry IFC identity (an IFC file, or glTF
     * extras); NULL: the distribution elements (mr_ifc_class_is_distribution);
     * non-NULL with count 0: none by class. A scene config sets it with
     * "hidden_classes": ["IfcPipe*", ...]. */
    const char *const *hidden_classes;
    int hidden_class_count;
    /* IFC: no cache beside the file (neither read nor written). */
    bool no_cache;
} mr_scene_params;
#define MR_SCENE_DEFAULTS {0}

/* Loading on a thread of its own (scene_async.c), so a window's event loop
 * never blocks: start, poll once per frame (non-blocking; true when done,
 * with the stage and fraction for a progress bar), then finish (waits, and
 * returns the scene or NULL + err; frees the loader). The glob strings in
 * params must stay valid until finish; params->progress, if set, is called
 * on the loader's thread. */
typedef struct mr_scene_loader mr_scene_loader;
mr_scene_loader *mr_scene_load_async(const char *path, const mr_scene_params *params, mr_error *err);
bool mr_scene_loader_poll(mr_scene_loader *loader, const char **stage, double *fraction);
mr_scene *mr_scene_loader_finish(mr_scene_loader **loader, mr_error *err);

/* Loads a scene from a .gltf/.glb (recognised by content, not extension)
 * or a scene config JSON: {"gltf": "rel/path.glb", "hidden": ["Pipe*"],
 * "lights": [{"direction": [x,y,z], "color": [r,g,b]}], "ambient": 0.35}.
 * A light may have a size for shadows: "kind": "sun" (default; "angle":
 * angular diameter in degrees, default MR_LIGHT_DEFAULT_SUN_ANGLE), "rect"
 * ("position", "size": [w, h], "axis": the width's direction) or "sphere"
 * ("position", "size": radius); "shadows": false keeps it from casting.
 * "receivers": ["Floor*"] marks shadow catchers (each glob must match a
 * node); "shadows": "pcss" turns a shadow method on by default.
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

/* tinygltf's parse alone (no conversion, no external files): the reference
 * the loader's speed is compared with. */
bool mr_gltf_parse_only(const void *data, size_t size, mr_error *err);

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

/* Corner masking (Park & Baek): the outline volume of a mesh. Vertex v of
 * the volume at AO radius r is positions[v] + r * dirs[v] (mesh space):
 * dirs is the miter of the distinct face normals around the welded vertex
 * (the shortest d with d . n >= 1 for each: n on a face, (1,1,0) on a box
 * edge, (1,1,1) at a box corner), so every point within r of the surface
 * is inside. A closed mesh keeps its own vertices and triangles; an open
 * one (open = true) becomes a shell: a copy moved to each side and a wall
 * along every boundary edge, its rim moved out across the edge by r.
 * Computed once per mesh by the renderer; free with mr_outline_free. */
typedef struct mr_outline {
    float *positions;          /* 3 * vertex_count, mesh space */
    float *dirs;               /* 3 * vertex_count, offset per unit radius (length >= 1) */
    uint32_t *indices;         /* index_count, triangles */
    uint32_t vertex_count, index_count;
    bool open;                 /* built as a two-sided shell */
} mr_outline;
bool mr_mesh_outline(const mr_mesh *m, mr_outline *out, mr_error *err);
void mr_outline_free(mr_outline *o);

bool mr_demo_build(const mr_demo_params *params, mr_demo_hall *out, mr_error *err);

/* ------------------------------------------------- shadow suite
 * Hecher's scene categories as generated scenes (shadow_suite.c): simple
 * objects and furniture-like assemblies with constant or varying penumbra,
 * without or with overlapping penumbrae; fences and plant-like leaves
 * (always overlapping) with constant or varying penumbra; the demo hall.
 * Each with its casting light and two views (320 x 240). */
#define MR_SHADOW_SUITE_COUNT 13
typedef struct mr_shadow_suite_case {
    char name[48];        /* e.g. "simple_varying_overlap" */
    bool varying;         /* the penumbra width varies (contact hardening) */
    bool overlap;         /* penumbrae overlap */
    mr_scene *scene;      /* owned */
    mr_view views[2];
} mr_shadow_suite_case;
bool mr_shadow_suite_build(int index, mr_shadow_suite_case *out, mr_error *err);
void mr_shadow_suite_free(mr_shadow_suite_case *c);
const char *mr_shadow_suite_name(int index); /* NULL out of range */
void mr_demo_free(mr_demo_hall *hall);

/* The demo's camera side (demo_camera.c). */
/* AprilTag images (tag36h11, ids 0..count-1; count is clamped to the
 * family's size), gray8 with the white border; *border gets its width in
 * pixels. Free with mr_demo_tag_images_free. */
bool mr_demo_tag_images(int count, mr_image **out, int *border, mr_error *err);
void mr_demo_tag_images_free(mr_image *imgs, int count);
/* mr_demo_build with tag plates for ids 0..tag_count-1 (0: MR_DEMO_TAGS, the
 * demo hall's 32; params may be NULL: MR_DEMO_DEFAULTS; its tag image
 * fields are replaced; 16 tags on walls and columns, 16 on four tag posts). */
#define MR_DEMO_TAGS 32
bool mr_demo_build_tagged(const mr_demo_params *params, int tag_count, mr_demo_hall *hall, mr_error *err);
/* The demo tablet camera (640x480, mild barrel distortion) and its standing
 * viewpoints (i is clamped to 0..mr_demo_view_count()-1). */
mr_camera mr_demo_camera(void);
#define MR_DEMO_VIEWS 5
int mr_demo_view_count(void); /* MR_DEMO_VIEWS */
mr_view mr_demo_view(int i);
/* A camera frame (RGB8, cam's size) from n ideal pinhole renders (averaged:
 * motion blur), each rendered with a margin of `margin` px per side at
 * `scale` times the resolution: lens distortion of cam, [1 2 1] optical
 * blur, exposure gain, Gaussian sensor noise (sigma in 8-bit levels, drawn
 * from rng). */
bool mr_demo_camera_frame(const mr_camera *cam, const mr_image *ideal, int n, int margin, int scale, double gain,
                          double noise, mr_rng *rng, mr_image *out, mr_error *err);
/* The pinhole camera the ideal renders for mr_demo_camera_frame use: cam
 * grown by `margin` px per side, without distortion (render it at `scale`
 * times its size). */
mr_camera mr_demo_wide_camera(const mr_camera *cam, int margin);

/* The synthetic calibration board (demo_board.c): tag36h11 ids
 * MR_DEMO_BOARD_FIRST_ID.. in a COLS x ROWS grid on a plane; board frame =
 * tag frame convention (x right, y down, z into the board), origin at the
 * top-left tag's centre; a white board one pitch beyond the outer tags. */
#define MR_DEMO_BOARD_COLS 6
#define MR_DEMO_BOARD_ROWS 4
#define MR_DEMO_BOARD_FIRST_ID 100
#define MR_DEMO_BOARD_TAG 0.04   /* m, the black square */
#define MR_DEMO_BOARD_PITCH 0.06 /* m between tag centres */
/* Tag i's (0..COLS*ROWS-1, row-major) id; its pose into *board_from_tag. */
int mr_demo_board_tag(int i, mr_dmat4 *board_from_tag);
/* The board seen by cam (gray8, cam's size, lens distortion exact): ray
 * cast, 3x3 supersampled, dark grey background, Gaussian noise of 1.5
 * levels from rng. tag_imgs: the board's COLS*ROWS tag images in tag order
 * (mr_demo_tag_images from FIRST_ID on). */
bool mr_demo_board_render(const mr_camera *cam, const mr_dmat4 *board_from_camera, const mr_image *tag_imgs,
                          mr_rng *rng, mr_image *out, mr_error *err);

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

/* ------------------------------------------------- culling (bvh.c) */

/* A convex view volume: points x with n.x + d >= 0 for every plane are
 * inside. World space, double precision. */
typedef struct mr_frustum {
    double planes[6][4];  /* nx ny nz d */
    int plane_count;
} mr_frustum;

/* The pinhole frustum of an OpenCV camera at world_from_camera: the image
 * rectangle widened by margin_px pixels on each side (so rounding in the
 * rasteriser can never show a culled node), and the near plane z >= near
 * (infinite far). Lens distortion is ignored: the renderer draws the
 * undistorted image. */
mr_frustum mr_frustum_from_camera(const mr_camera *cam, const mr_dmat4 *world_from_camera, double near_plane,
                                  double margin_px);
/* -1: the box lies outside, 0: it straddles, 1: it lies inside. */
int mr_frustum_test_box(const mr_frustum *f, const double lo[3], const double hi[3]);

/* World-space bounds of what node n draws (its meshes through its world
 * transform, in double); false if it draws nothing. */
bool mr_scene_node_bounds(const mr_scene *s, int32_t node, double lo[3], double hi[3]);

/* A bounding-volume hierarchy over the world bounds of the nodes that draw
 * something, built once per scene (the scene is static while it is set). */
typedef struct mr_bvh mr_bvh;

typedef struct mr_bvh_stats {
    uint32_t boxes_tested;   /* BVH boxes tested against the frustum */
    uint32_t nodes_visible;  /* scene nodes returned */
} mr_bvh_stats;

mr_bvh *mr_bvh_build(const mr_scene *s, mr_error *err);
void mr_bvh_destroy(mr_bvh **bvh); /* NULLs, accepts NULL */
/* Number of scene nodes the BVH holds (those that draw something). */
int32_t mr_bvh_node_count(const mr_bvh *bvh);
/* Writes the indices of the scene nodes whose bounds touch the frustum and
 * whose layer bit (1 << layer) is in layer_mask into out (room for
 * mr_bvh_node_count entries), in BVH order; returns the count.
 * frustum NULL: every node of those layers. */
int32_t mr_bvh_cull(const mr_bvh *bvh, const mr_frustum *frustum, uint32_t layer_mask, int32_t *out,
                    mr_bvh_stats *stats);
/* World bounds of scene node `node` as stored in the BVH (6 doubles: lo, hi),
 * or NULL if the node draws nothing. */
const double *mr_bvh_bounds(const mr_bvh *bvh, int32_t node);

/* ------------------------------------------ level of detail (lod.c) */

/* Simplified index lists of a mesh (meshoptimizer on the mesh welded by
 * position across its normal seams: edge collapses, or vertex clustering
 * where they stall; both keep existing vertices, and each corner is mapped
 * back to the vertex of its position whose normal fits its face, so a level
 * indexes the mesh's own vertex arrays and keeps its creases).
 * `error` is a certified upper bound, in the mesh's units (before the node
 * transform), of the two-sided Hausdorff distance between the level and the
 * full mesh: measured, not the simplifier's estimate (see lod.c). */
typedef struct mr_lod_level {
    uint32_t index_count;
    uint32_t *indices;
    double error;
} mr_lod_level;

#define MR_LOD_MAX_LEVELS 6

typedef struct mr_mesh_lods {
    int32_t level_count;                    /* 0: the mesh is drawn at full detail only */
    mr_lod_level levels[MR_LOD_MAX_LEVELS]; /* finest first, errors increasing */
} mr_mesh_lods;

typedef struct mr_lod {
    int32_t mesh_count;       /* == the scene's */
    mr_mesh_lods *meshes;
    uint64_t scene_hash;      /* of the geometry the levels were built for */
} mr_lod;

typedef struct mr_lod_params {
    double max_error;         /* absolute cap of a kept level's certified
                                 error, in mesh units; 0 = none: the cap is
                                 rel_error times the mesh's size, so the
                                 same part gets the same levels in metres
                                 or in millimetres */
    uint32_t min_triangles;   /* meshes with fewer triangles get no levels; 0 = 64 */
    bool progress;            /* progress line on stderr (caller decides on a tty) */
    double rel_error;         /* coarsest level's error as a fraction of the
                                 mesh's size (largest bounding-box extent);
                                 0 = 0.02 (2 %). Levels are built for the
                                 errors rel_error / 32, / 16, ... / 1 */
    /* Called after each mesh with the fraction of input triangles done,
     * one call at a time from any of the build's threads; returning false
     * stops the build (no further mesh is started, mr_lod_build fails with
     * "LOD build cancelled"). NULL: none. */
    bool (*on_progress)(void *user, double fraction);
    void *progress_user;
    bool portable;            /* the portable build kernel even where the CPU
                                 has a faster one (mr_lod_kernel): the same
                                 algorithm either way; tests compare the two.
                                 false = the fastest this CPU runs */
} mr_lod_params;
#define MR_LOD_DEFAULTS {0.0, 0, false, 0.0, NULL, NULL, false}
/* 2 %, not 1 %: a level is only drawn where its error projects under
 * --lod-pixels, so a coarser last level changes only what far parts cost.
 * Measured (bench scene --unique, 2M/10M/20M, 320x240; 1 % -> 2 % -> 4 %
 * -> 8 %): triangles submitted from the 20M overview 2.37M -> 1.41M ->
 * 0.82M -> 0.52M, from its floor 1.10M -> 0.67M -> 0.41M -> 0.30M; image
 * against full detail at most 0.038 -> 0.085 -> 0.20 -> 0.40 % of pixels
 * off edges (coarse levels' normals, not their geometry). Past 2 % the
 * same part at scale 1 and at scale 1000 no longer gets levels within 10 %
 * of each other's error (rounding tips the simplifier more where it
 * removes more), and more corners keep a normal over 60 degrees off their
 * face (test_cad). */
#define MR_LOD_DEFAULT_REL_ERROR 0.02

typedef struct mr_lod_info {
    bool from_cache;          /* the cache was valid and used */
    bool cache_written;
    double build_s;           /* seconds spent simplifying and certifying */
    uint64_t levels;          /* levels kept over all meshes */
    uint64_t triangles;       /* input triangles simplified (when built) */
} mr_lod_info;

/* Builds the levels of every mesh. */
mr_lod *mr_lod_build(const mr_scene *s, const mr_lod_params *params, mr_error *err);
/* The code that builds them on this CPU with these params: "x86-64-v3"
 * (the kernel compiled for AVX2 and FMA, where the CPU has them) or
 * "portable". */
const char *mr_lod_kernel(const mr_lod_params *params);
void mr_lod_destroy(mr_lod **lod); /* NULLs, accepts NULL */
/* Hash of the scene's mesh geometry (positions, indices, origins): a cache
 * for another geometry is never used. */
uint64_t mr_lod_scene_hash(const mr_scene *s);
/* Reads levels from cache_path if it holds levels for exactly this scene
 * and these params (checked by hash and a checksum; anything else is
 * ignored, never trusted), else builds them and writes the cache atomically
 * (a failed write is only a warning). cache_path NULL: no cache. */
mr_lod *mr_lod_load_or_build(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                             mr_lod_info *info, mr_error *err);
/* Building off the caller's thread, so a window keeps drawing (the full
 * detail meanwhile) while levels are read from the cache or built: start,
 * poll once per frame (non-blocking; true when done, with the fraction of
 * input triangles done), then finish (waits; the levels or NULL + err) or
 * cancel (stops the build after the meshes in progress, waits, frees). The
 * scene must stay unchanged until then; params->on_progress, if set, is
 * called too (on the builder's threads). cache_path NULL: no cache. */
typedef struct mr_lod_builder mr_lod_builder;
mr_lod_builder *mr_lod_build_async(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                                   mr_error *err);
bool mr_lod_builder_poll(mr_lod_builder *b, double *fraction);
mr_lod *mr_lod_builder_finish(mr_lod_builder **b, mr_lod_info *info, mr_error *err); /* NULLs *b */
/* The same, and after the levels the hierarchy above the part where
 * mr_hlod_wanted_scene(hlod_mode) says so (from hlod_cache_path or built;
 * NULL: no cache), taken with finish_hlod (*hlod NULL: none; a failed
 * hierarchy is a warning in the log, the levels still come). */
typedef struct mr_hlod mr_hlod;
mr_lod_builder *mr_lod_build_async_hlod(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                                        const char *hlod_mode, const char *hlod_cache_path, mr_error *err);
mr_lod *mr_lod_builder_finish_hlod(mr_lod_builder **b, mr_lod_info *info, mr_hlod **hlod, mr_error *err);
void mr_lod_builder_cancel(mr_lod_builder **b); /* NULLs *b, accepts NULL */
/* Scenes drawing at least this many triangles get levels by default (the
 * commands' --lod auto): below it, simplifying costs more than it saves. */
#define MR_LOD_AUTO_TRIANGLES 500000u
/* The default cache path next to a scene file: "<scene>.mrlod". */
void mr_lod_cache_path(const char *scene_path, char *out, size_t n);
/* Whether a scene gets levels at all (the commands' --lod auto|on|off;
 * the view draws as auto): auto gives them to scenes drawing
 * MR_LOD_AUTO_TRIANGLES or more. mr_lod_mode_parse takes NULL as auto;
 * a bad value is one line in err. In load_report.c. */
typedef enum mr_lod_mode { MR_LOD_MODE_AUTO, MR_LOD_MODE_ON, MR_LOD_MODE_OFF } mr_lod_mode;
bool mr_lod_mode_parse(const char *s, mr_lod_mode *out, mr_error *err);
bool mr_lod_wanted(mr_lod_mode mode, const mr_scene *s);
/* The commands' loads (load_report.c): the scene with a progress line on
 * a terminal once a load takes a second, then an info line (nodes, meshes,
 * triangles drawn and stored, MB, s, MB/s, peak RSS); the levels from the
 * cache next to scene_path (use_cache) or built, with an info line. */
mr_scene *mr_scene_load_logged(const char *path, const mr_scene_params *params, mr_error *err);
mr_lod *mr_lod_load_logged(const mr_scene *s, const char *scene_path, bool use_cache, mr_error *err);
/* Certified upper bound of the two-sided Hausdorff distance between the
 * triangle lists a and b over the same vertex positions (3 floats each),
 * found by branch and bound on subdivided triangles down to `resolution`
 * (the bound is exact to within resolution). Returns INFINITY where a point
 * lies farther than `limit` from the other surface. */
double mr_lod_hausdorff_bound(const float *positions, uint32_t vertex_count, const uint32_t *a, uint32_t a_count,
                              const uint32_t *b, uint32_t b_count, double resolution, double limit);
/* The same bound, refined only where it exceeds `accept` (and the largest
 * real distance found + resolution): still a true upper bound, at most
 * max(accept, truth + resolution) where refinement reaches, and much
 * cheaper when accept is the error one is prepared to certify (the LOD
 * build passes each level's error budget). */
double mr_lod_hausdorff_bound_within(const float *positions, uint32_t vertex_count, const uint32_t *a,
                                     uint32_t a_count, const uint32_t *b, uint32_t b_count, double accept,
                                     double resolution, double limit);

/* ------------------------- levels of detail above the part (hlod.c)
 *
 * A binary tree over the scene's drawn nodes (one tree per layer; the
 * leaves are the nodes themselves, split at the median of their centres
 * along the longest axis) whose inner nodes carry a proxy: the triangles of
 * everything below, merged across node and mesh boundaries into one
 * triangle list and simplified (meshoptimizer, edge collapses or vertex
 * clustering), built bottom-up from the children's proxies and, at the
 * bottom, from each part's coarsest LOD level. `error` is a certified upper
 * bound (world units) of the two-sided Hausdorff distance between the proxy
 * and the full-detail geometry below: the steps are certified with
 * mr_lod_hausdorff_bound_within and add up by the triangle inequality, plus
 * the rounding of the proxy's float positions. Each proxy triangle keeps
 * the (node, mesh) it came from (`runs`: its triangles are sorted by
 * source), so a frame drawing proxies still names the real part under a
 * pixel and shows each part's colour. */
typedef struct mr_hlod_run {
    uint32_t first, count;      /* index range within the proxy's indices */
    int32_t node, mesh;         /* the scene node and mesh it came from */
} mr_hlod_run;

typedef struct mr_hlod_node {
    double lo[3], hi[3];        /* world bounds of the full detail below */
    double center[3];           /* proxy positions are relative to it */
    double error;               /* certified bound, world units; INFINITY: no proxy (leaves) */
    int32_t child[2];           /* tree nodes; -1 for leaves */
    int32_t item;               /* leaves: the scene node; -1 otherwise */
    uint8_t layer;              /* mr_layer */
    uint32_t vertex_count, index_count, run_count;
    float *positions, *normals; /* 3 * vertex_count each */
    uint32_t *indices;
    mr_hlod_run *runs;
} mr_hlod_node;

struct mr_hlod {
    int32_t node_count;
    mr_hlod_node *nodes;        /* breadth first: roots, then their children, ... */
    int32_t root[MR_LAYER_COUNT]; /* -1: the layer has no tree */
    uint64_t scene_hash;        /* mr_lod_scene_hash of the scene it was built for */
    uint64_t lod_hash;          /* of the part levels it was built from */
    uint64_t proxy_triangles;   /* over all proxies */
    int32_t scene_node_count;
    int32_t scene_mesh_count;
};

typedef struct mr_hlod_params {
    /* Proxy triangles as a fraction of their input (the children's proxies
     * or parts); 0 = 0.5. */
    double reduction;
    /* Called after each proxy with the fraction of proxies done, one call
     * at a time; returning false stops the build. NULL: none. */
    bool (*on_progress)(void *user, double fraction);
    void *progress_user;
    int threads;                /* 0: one per core */
} mr_hlod_params;
#define MR_HLOD_DEFAULTS {0.0, NULL, NULL, 0}

/* The default: a hierarchy only for scenes drawing at least this many
 * triangles in at least MR_HLOD_AUTO_NODES nodes: below, the part levels
 * alone keep the frame cheap and the build would not pay. */
#define MR_HLOD_AUTO_TRIANGLES 1000000u
#define MR_HLOD_AUTO_NODES 16
/* Whether a scene gets a hierarchy: mode "on" always (when it has two or
 * more drawn nodes), "off" never, "auto" (or NULL) above the thresholds. */
bool mr_hlod_wanted(const char *mode, uint64_t drawn_triangles, int32_t drawn_nodes);

/* Builds the hierarchy over s from its part levels (lod may be NULL: full
 * detail then). NULL + err on failure (or when there is nothing to build:
 * fewer than two drawn nodes). */
mr_hlod *mr_hlod_build(const mr_scene *s, const mr_lod *lod, const mr_hlod_params *params, mr_error *err);
void mr_hlod_destroy(mr_hlod **h); /* NULLs, accepts NULL */
/* Hash of the part levels the proxies are built from. */
uint64_t mr_hlod_lod_hash(const mr_lod *lod);

typedef struct mr_hlod_info {
    bool from_cache;
    bool cache_written;
    double build_s;
    uint64_t input_triangles;  /* triangles the proxies were simplified from */
} mr_hlod_info;
/* Reads the hierarchy from cache_path if it holds one for exactly this
 * scene and these part levels (hashes, a checksum and every index and id
 * in range; a short, damaged or stale file is ignored with one warning,
 * never used), else builds it and writes the file atomically (nodes in the
 * order a cut reaches them: breadth first). cache_path NULL: no cache. */
mr_hlod *mr_hlod_load_or_build(const mr_scene *s, const mr_lod *lod, const char *cache_path,
                               const mr_hlod_params *params, mr_hlod_info *info, mr_error *err);
/* "<scene>.mrhlod" */
void mr_hlod_cache_path(const char *scene_path, char *out, size_t n);
/* The commands' hierarchy (--hlod auto|on|off; NULL is auto), in
 * load_report.c: where mr_hlod_wanted says so for the scene's drawn
 * triangles and nodes, and lod is set (--lod off draws full detail
 * everywhere), the hierarchy from <scene_path>.mrhlod (use_cache) or
 * built, with progress on a terminal, stopping at SIGINT/SIGTERM
 * (mr_stop_catch) and an info line. true with *out NULL where the scene
 * does not want one: nothing is read or built then. A bad mode or a
 * failed build: false + err. */
/* mr_hlod_wanted for the scene's drawn triangles and nodes (shadow
 * catchers excluded). */
bool mr_hlod_wanted_scene(const char *mode, const mr_scene *s);
bool mr_hlod_load_logged(const mr_scene *s, const mr_lod *lod, const char *scene_path, const char *mode, bool use_cache,
                         mr_hlod **out, mr_error *err);
bool mr_hlod_mode_check(const char *mode, mr_error *err);

/* Where a view cuts the tree: a node's proxy is drawn where its error,
 * projected at the node's nearest depth (fmax / z pixels per unit, as the
 * part levels are chosen), is at most `pixels` and at most `tolerance`;
 * else its children are visited; a leaf reached hands its scene node to
 * the part levels. Nodes whose bounds miss the frustum (NULL: none) are
 * skipped. */
typedef struct mr_hlod_cut_params {
    mr_dmat4 cam_from_world;
    double near_plane;
    double fmax;               /* mr_geometry_lod_fmax of the camera */
    double pixels;             /* > 0 */
    double tolerance;          /* scene units; INFINITY: none */
    const mr_frustum *frustum; /* NULL: no culling */
    uint32_t layers;           /* 1 << mr_layer */
} mr_hlod_cut_params;
/* Writes the proxies to draw (tree nodes) into proxies (room for
 * h->node_count) and the scene nodes left to the part levels into nodes
 * (room for h->node_count); returns false only for bad arguments. */
bool mr_hlod_cut(const mr_hlod *h, const mr_hlod_cut_params *p, int32_t *proxies, int32_t *proxy_count,
                 int32_t *nodes, int32_t *node_count);
/* Upper bound of the largest singular value of a world transform's 3x3
 * (Gershgorin on M^T M): errors in mesh units times this are world units. */
double mr_stretch_bound(const mr_dmat4 *w);
/* Largest pixels per unit of x/z over the camera's image (its corners, with
 * a 1.5 px margin): a displacement e at depth z moves the image point by at
 * most fmax * e / z pixels. The projected-error factor of every LOD choice. */
double mr_lod_fmax(const mr_camera *c);

/* ------------------------------------ synthetic factories (synth.c) */

typedef struct mr_synth_params {
    uint64_t seed;           /* default 1 */
    int halls;               /* halls in a grid, about 1M drawn triangles
                                and 3000 nodes each; 0 = 1 */
    double hall_width;       /* metres, 0 = 60 */
    double hall_depth;       /* metres, 0 = 30 */
    double origin[3];        /* offset of the whole plant (x and z), metres */
} mr_synth_params;
#define MR_SYNTH_DEFAULTS {1, 1, 0.0, 0.0, {0.0, 0.0, 0.0}}
extern const mr_opt mr_synth_opts[]; /* halls (lib/scene/options.c) */

/* A factory of `halls` halls whose parts (machines, motors, valves, bolts,
 * racks, boxes, pipes, trays, lamps) are shared meshes placed by many
 * nodes; pipes and trays below the roof form the hidden layer. */
mr_scene *mr_synth_build(const mr_synth_params *params, mr_error *err);
/* The hall count whose drawn triangles come closest to the target. */
int mr_synth_halls_for(uint64_t target_triangles);
enum { MR_SYNTH_VIEW_FLOOR = 0, MR_SYNTH_VIEW_AISLE = 1, MR_SYNTH_VIEW_OVERVIEW = 2, MR_SYNTH_VIEW_COUNT = 3 };
/* world_from_camera of a fixed viewpoint: standing on the floor of the
 * first hall, looking down an aisle through the row of halls, or an
 * overview from above. */
mr_dmat4 mr_synth_viewpoint(const mr_synth_params *params, int which);

/* Unique CAD-like geometry: `parts` distinct parts, each its own
 * mesh drawn by one node (nothing instanced), with finely tessellated
 * curved surfaces and split at every normal seam as CAD exporters write
 * them, on a floor; in metres (unit 1), millimetres (unit 1000) or any unit:
 * positions and placements are multiplied by `unit`, so two factories that
 * differ only in unit are the same hall scaled. Deterministic for a seed. */
typedef struct mr_synth_cad_params {
    uint64_t seed;            /* default 1 */
    int parts;                /* 0 = 64 */
    uint32_t part_triangles;  /* about this many triangles per part; 0 = 20000 */
    double unit;              /* scene units per metre; 0 = 1 */
    double origin[3];         /* offset of the whole hall, metres */
} mr_synth_cad_params;
#define MR_SYNTH_CAD_DEFAULTS {1, 64, 20000u, 1.0, {0.0, 0.0, 0.0}}
extern const mr_opt mr_synth_cad_opts[]; /* unit */
mr_scene *mr_synth_cad_build(const mr_synth_cad_params *params, mr_error *err);
/* The same three kinds of viewpoint as mr_synth_viewpoint (floor, aisle,
 * overview), in the factory's unit. */
mr_dmat4 mr_synth_cad_viewpoint(const mr_synth_cad_params *params, int which);
/* A fixed viewpoint as a view for renders: the demo camera without lens
 * distortion at mr_synth_cad_viewpoint (cad non-NULL) or mr_synth_viewpoint.
 * Its name: "floor", "aisle", "overview". */
mr_view mr_synth_view(const mr_synth_params *params, const mr_synth_cad_params *cad, int which);
const char *mr_synth_view_name(int which);
/* The three as dir/view_<name>.json (dir made if missing). */
bool mr_synth_save_views(const char *dir, const mr_synth_params *params, const mr_synth_cad_params *cad, mr_error *err);
/* The part count whose stored triangles come closest to the target, for
 * params' part_triangles (0: the default); in [1, 1e6]. */
int mr_synth_cad_parts_for(const mr_synth_cad_params *params, double target_triangles);

#ifdef __cplusplus
}
#endif
#endif
