/* mr_export.h — findings that leave the tablet: the marks of a session
 * folder (annotations.jsonl + snapshots/, as `mrcheck view` writes them) as
 * BCF 2.1 / 3.0 topics (buildingSMART's BIM Collaboration Format, read by
 * BIMcollab, Solibri, Revit, Trimble Connect, xeokit) and as a
 * self-contained HTML + Markdown report.
 *
 * What each mark needs: a "pose" with world_from_camera, and a "snapshot"
 * whose "frame" (the raw camera image) and "pose" (the snapshot's JSON with
 * its "camera") exist, relative to the session folder. Optional inputs of a
 * mark line, used where present (the registration and measurement issues
 * fill them):
 *   "distance_m"     the measured deviation from the plan, metres
 *   "uncertainty_m"  the registration uncertainty (1 sigma) at the mark, metres
 *   "measured_distance_m", "measured_sigma_m"  a mark made by the view's
 *                    Measure: the triangulated distance to the plan
 *                    (used when "distance_m" is absent) and its 1 sigma
 *   "snapshot": {"screen"}  the screen with the overlay (report only)
 *   "verdict"        a measured distance judged against the tolerance
 *                    (mr_verdict_to_json): in the description with its
 *                    interval and tolerance, and its words ("out of
 *                    tolerance") added to the topic's labels
 *
 * BCF conventions (the standard's, not ours): Z up, metres. glTF is Y up, so
 * a point (x, y, z) of the scene becomes (x, -z, y) (a rotation of +90°
 * about X). BCF cameras have no principal point and no lens distortion, so
 * the snapshot is the frame undistorted and cropped to the largest frustum
 * centred on the optical axis, with square pixels; FieldOfView is that
 * frustum's horizontal angle in 2.1 and its vertical angle in 3.0 (which
 * adds AspectRatio = width / height). GUIDs are lowercase and derived from
 * the mark's line, so exporting the same marks again gives the same topics
 * (a BCF tool then updates instead of duplicating them).
 */
#ifndef MR_EXPORT_H
#define MR_EXPORT_H

#include <stdio.h>

#include "mr_core.h"
#include "mr_scene.h"
#include "mr_session.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mr_bcf_version { MR_BCF_2_1 = 0, MR_BCF_3_0 = 1 } mr_bcf_version;

typedef struct mr_export_params {
    int bcf_version;          /* mr_bcf_version; default MR_BCF_2_1 */
    int max_side;             /* snapshot's long side at most, px; default 1500 */
    double unit_m;            /* metres per scene unit; default 1 (glTF) */
    const char *author;       /* CreationAuthor; NULL or "": "mrcheck" */
    const char *title;        /* report title; NULL: "mrcheck findings" */
    const mr_scene *scene;    /* report: node footprints in the plan view
                                 (NULL: the marks and cameras only) */
} mr_export_params;
#define MR_EXPORT_DEFAULT_MAX_SIDE 1500
#define MR_EXPORT_DEFAULTS {.bcf_version = MR_BCF_2_1, .max_side = MR_EXPORT_DEFAULT_MAX_SIDE, .unit_m = 1.0}
/* bcf-version (2.1|3.0), snapshot-max (px), unit-m */
extern const mr_opt mr_export_opts[];

/* ----------------------------------------------------------- the camera */

/* The centred frustum a camera's image is cropped to: a pinhole with square
 * pixels and its principal point at the image centre. */
typedef struct mr_bcf_frame {
    int width, height;        /* snapshot size, px */
    double f;                 /* focal length, px */
} mr_bcf_frame;

/* The largest centred frustum inside cam's (undistorted) image, at most
 * max_side px on the long side and never sampled finer than the camera's
 * own pixels. Fails for an invalid camera or one with no usable view. */
bool mr_bcf_frame_of(const mr_camera *cam, int max_side, mr_bcf_frame *out, mr_error *err);

typedef struct mr_bcf_camera {
    double view_point[3];     /* BCF world (Z up), metres */
    double direction[3];      /* unit, along the optical axis */
    double up[3];             /* unit, the image's up (against its y axis) */
    double fov_deg;           /* horizontal (2.1) or vertical (3.0), degrees */
    double aspect;            /* width / height of the snapshot */
} mr_bcf_camera;

/* A scene point / direction in BCF's Z-up frame: (x, y, z) -> (x, -z, y). */
mr_dvec3 mr_bcf_from_gltf(mr_dvec3 p);
/* The PerspectiveCamera of a pose (OpenCV camera axes, scene units times
 * unit_m) seen through frame fr. */
mr_bcf_camera mr_bcf_camera_of(const mr_dmat4 *world_from_camera, const mr_bcf_frame *fr, double unit_m,
                               mr_bcf_version v);
/* The snapshot: src (the raw frame of camera cam; resized to src's size)
 * undistorted and resampled (bilinear) into fr. out is RGB or grey as src. */
bool mr_bcf_snapshot(const mr_image *src, const mr_camera *cam, const mr_bcf_frame *fr, mr_image *out,
                     mr_error *err);
/* A lowercase GUID (8-4-4-4-12 hex, version 4 layout) derived from data
 * and salt. out needs 37 bytes. */
void mr_bcf_guid(const void *data, size_t n, uint64_t salt, char out[37]);

/* ------------------------------------------------------------ BCF topics
 * A BCF archive as data: what the reader fills from BCF 2.0, 2.1 or 3.0
 * (a .bcf/.bcfzip archive or its unzipped folder), what the writer writes
 * as 2.1 or 3.0. The session's marks go out through it, and topics read
 * from elsewhere go back out through it with their GUIDs kept. Strings are
 * as the file gives them (truncated to the field's size); numbers in BCF's
 * frame (Z up, metres). */
#define MR_BCF_MAX_LABELS 16
typedef struct mr_bcf_component {
    char ifc_guid[24];          /* IfcGuid (22 chars), "" none */
    char originating[64];       /* OriginatingSystem, "" none */
    char authoring_id[128];     /* AuthoringToolId, "" none */
} mr_bcf_component;

typedef struct mr_bcf_coloring {
    uint32_t argb;              /* 0xAARRGGBB; alpha 0xff when the file gives RRGGBB */
    mr_bcf_component *items;
    int count;
} mr_bcf_coloring;

typedef struct mr_bcf_plane {
    double location[3];         /* a point of the plane, metres */
    double direction[3];        /* its normal: what lies on this side is clipped away */
} mr_bcf_plane;

typedef enum mr_bcf_camera_kind {
    MR_BCF_CAMERA_NONE = 0, MR_BCF_CAMERA_PERSPECTIVE, MR_BCF_CAMERA_ORTHOGONAL
} mr_bcf_camera_kind;

typedef struct mr_bcf_viewpoint {
    char guid[37];
    char file[128];             /* the .bcfv's name in the topic folder */
    char snapshot_name[128];    /* "" none */
    int index;                  /* -1 none */
    int camera_kind;            /* mr_bcf_camera_kind */
    mr_bcf_camera camera;       /* fov_deg as written (2.x horizontal-ish, 3.0 vertical);
                                   aspect 0 when the file gives none */
    double view_to_world_scale; /* orthogonal: the view's height in metres */
    bool has_components;        /* a <Components> element was read / is to be written */
    bool default_visibility;    /* BCF's default: false in 2.1/3.0 when absent, true in 2.0 */
    bool spaces_visible, space_boundaries_visible, openings_visible;
    mr_bcf_component *selection; int selection_count;
    mr_bcf_component *exceptions; int exception_count; /* the visibility exceptions */
    mr_bcf_coloring *colorings; int coloring_count;
    mr_bcf_plane *clips; int clip_count;
    unsigned char *snapshot;    /* the snapshot's bytes (PNG or JPEG), NULL none */
    size_t snapshot_size;
} mr_bcf_viewpoint;

typedef struct mr_bcf_comment {
    char guid[37];
    char date[32], author[128], modified_date[32], modified_author[128];
    char viewpoint_guid[37];    /* "" none */
    char *text;                 /* malloc'd, never NULL once added */
} mr_bcf_comment;

typedef struct mr_bcf_topic {
    char guid[37];
    char type[64], status[64];  /* TopicType, TopicStatus; "" none */
    char title[256], priority[64];
    int index;                  /* -1 none */
    char labels[MR_BCF_MAX_LABELS][64];
    int label_count;
    char creation_date[32], creation_author[128], modified_date[32], modified_author[128];
    char due_date[32], assigned_to[128], stage[64];
    char *description;          /* malloc'd, NULL none */
    mr_bcf_comment *comments; int comment_count;
    mr_bcf_viewpoint *viewpoints; int viewpoint_count;
} mr_bcf_topic;

typedef struct mr_bcf {
    char version[16];           /* as read ("2.0", "2.1", "3.0"); "" built in memory */
    mr_bcf_topic *topics; int topic_count;
    /* What the reader skipped or could not use, one line each ("topic
     * 1b2c...: viewpoint.bcfv names no camera"). */
    char (*warnings)[256]; int warning_count;
} mr_bcf;

/* Limits the reader keeps to (bad input is refused, not followed). */
#define MR_BCF_MAX_ENTRY_BYTES (64u << 20)   /* one entry, uncompressed */
#define MR_BCF_MAX_TOTAL_BYTES (512u << 20)  /* all entries read, uncompressed */
#define MR_BCF_MAX_ENTRIES 100000

/* True for BCF's GUID form: 8-4-4-4-12 lowercase hex. */
bool mr_bcf_guid_valid(const char *g);
/* Growing the lists: a zeroed new item (index -1 where it has one), NULL
 * when out of memory. */
mr_bcf_topic *mr_bcf_add_topic(mr_bcf *b);
mr_bcf_comment *mr_bcf_add_comment(mr_bcf_topic *t);
mr_bcf_viewpoint *mr_bcf_add_viewpoint(mr_bcf_topic *t);
bool mr_bcf_add_component(mr_bcf_component **list, int *count, const mr_bcf_component *c);
mr_bcf_coloring *mr_bcf_add_coloring(mr_bcf_viewpoint *v, uint32_t argb);
void mr_bcf_warn(mr_bcf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void mr_bcf_free(mr_bcf *b); /* zeroes it */

/* Writes b as a BCF v archive to out_path (temp file + rename; on failure
 * out_path is as it was): bcf.version, (3.0) extensions.xml declaring the
 * values the topics use, and per topic a folder named by its GUID with
 * markup.bcf and each viewpoint's .bcfv and snapshot, the first viewpoint
 * as viewpoint.bcfv / snapshot.png. Elements in the schemas' order.
 * Names inside the archive are made here, never taken from b. Fails for a
 * topic, comment or viewpoint without a valid GUID. In 2.1 a perspective
 * FieldOfView outside 45..60 is fitted (mr_bcf_fit_fov_21, 5 m) in the copy
 * written; callers that know a better distance fit it first. */
bool mr_bcf_write(const mr_bcf *b, mr_bcf_version v, const char *out_path, mr_error *err);
/* The archive's bytes (caller frees) instead of a file. */
bool mr_bcf_write_memory(const mr_bcf *b, mr_bcf_version v, void **out, size_t *out_size, mr_error *err);

/* BCF 2.1's schema allows a FieldOfView of 45..60 degrees only. A camera
 * outside is moved along its axis so that the region it shows at distance
 * depth_m (> 0: the marked point; otherwise 5 m) stays the same at the
 * nearest allowed angle; the fov is taken as horizontal. Returns how far it
 * moved (metres, + backwards), 0 when it was inside. */
double mr_bcf_fit_fov_21(mr_bcf_camera *c, double depth_m);

/* Reads a BCF 2.0, 2.1 or 3.0 archive (zip) or unzipped folder. What is
 * unusable inside (a topic without markup, a viewpoint without a camera,
 * an entry too large, a name with "..", XML with a DOCTYPE) is skipped
 * with a warning and the rest is read. Fails with one line when path
 * cannot be opened, is neither zip nor folder, names no version it knows,
 * or holds no topic at all. Nothing is written anywhere. */
bool mr_bcf_read(const char *path, mr_bcf *out, mr_error *err);
/* The same for a zip archive's bytes (tests, fuzzing). */
bool mr_bcf_read_memory(const void *data, size_t size, mr_bcf *out, mr_error *err);

/* The topic of b named by sel: a 1-based number, or a GUID (or its unique
 * prefix); NULL with a message when none matches. */
mr_bcf_topic *mr_bcf_find_topic(mr_bcf *b, const char *sel, mr_error *err);

/* ------------------------------------------------- a viewpoint rendered
 * (bcf_view.c) A topic's viewpoint as a view of the scene and as edits of
 * the scene, so that any renderer draws what the viewpoint shows:
 * - the camera: perspective with square pixels and the principal point at
 *   the centre (FieldOfView vertical for 3.0, horizontal for 2.x as
 *   mrcheck writes it); orthogonal as a pinhole far back along its axis
 *   (MR_BCF_ORTHO_DISTANCE times the larger of the view's height and the
 *   scene's depth from the scene's middle depth), ViewToWorldScale metres
 *   over the image height there, so the scale differs by at most
 *   1 / (2 MR_BCF_ORTHO_DISTANCE) across the scene;
 * - visibility: DefaultVisibility with its exceptions; IfcSpace and
 *   IfcOpeningElement elements hidden unless the hints show them; a hidden
 *   node draws nothing;
 * - colouring: the node's meshes copied with the colour (sRGB hex, alpha
 *   ignored) as a flat material; selection: the colour blended
 *   MR_BCF_HIGHLIGHT_MIX towards the highlight colour (linear RGB);
 * - clipping planes: a node wholly on a plane's cut side is hidden, one
 *   that straddles it is cut on the CPU (its triangles clipped in world
 *   space, in double).
 * Components match a node by IfcGuid (its element's GlobalId) or by
 * AuthoringToolId (its name or an ancestor's). */
typedef struct mr_bcf_view_params {
    double unit_m;            /* metres per scene unit; 0 = 1 (glTF, IFC) */
    int width, height;        /* output px; 0 = MR_BCF_VIEW_DEFAULT_WIDTH wide,
                                 the other side from AspectRatio (else 4:3) */
    bool fov_vertical;        /* FieldOfView is vertical (3.0); mr_bcf_topic_view sets it */
} mr_bcf_view_params;
#define MR_BCF_VIEW_DEFAULT_WIDTH 800
#define MR_BCF_VIEW_DEFAULTS {.unit_m = 1.0}
#define MR_BCF_ORTHO_DISTANCE 200.0
#define MR_BCF_HIGHLIGHT_R 0.05f
#define MR_BCF_HIGHLIGHT_G 0.45f
#define MR_BCF_HIGHLIGHT_B 1.0f
#define MR_BCF_HIGHLIGHT_MIX 0.6f

typedef struct mr_bcf_view_info {
    int viewpoint;            /* index of the viewpoint used in the topic */
    int hidden_nodes;         /* drawing nodes left out (hidden or clipped away) */
    int coloured_nodes, selected_nodes, clipped_nodes;
    int unresolved;           /* component references that name nothing in the scene */
    int bad_planes;           /* clipping planes without a usable normal, ignored */
} mr_bcf_view_info;

/* The view of vp's camera (s: the scene, for an orthogonal camera's depth;
 * may be NULL). Fails with one line for a viewpoint without a camera or
 * with an unusable one. */
bool mr_bcf_viewpoint_view(const mr_bcf_viewpoint *vp, const mr_scene *s, const mr_bcf_view_params *p, mr_view *out,
                           mr_error *err);
/* Writes vp's visibility, colouring, selection and clipping into s (see
 * above); s->source is cleared, since s is no longer its file's scene (no
 * cache beside the file is used for it). info may be NULL. */
bool mr_bcf_viewpoint_apply(mr_scene *s, const mr_bcf_viewpoint *vp, const mr_bcf_view_params *p,
                            mr_bcf_view_info *info, mr_error *err);
/* Both for topic t of b: its first viewpoint with a camera. */
bool mr_bcf_topic_view(mr_scene *s, const mr_bcf *b, const mr_bcf_topic *t, const mr_bcf_view_params *p, mr_view *view,
                       mr_bcf_view_info *info, mr_error *err);
/* `render --bcf FILE --topic SEL`: reads the BCF (its warnings logged),
 * finds the topic and does mr_bcf_topic_view, logging what it changed. */
bool mr_bcf_render_setup(const char *bcf_path, const char *topic, mr_scene *s, const mr_bcf_view_params *p,
                         mr_view *view, mr_error *err);
/* One line per topic on out: number, GUID, status, title, viewpoints (and
 * how many have a camera), comments, distinct components, and with a
 * scene how many of those it has (by IfcGuid, else by node name). */
void mr_bcf_print_list(const mr_bcf *b, const mr_scene *scene, FILE *out);

/* The planner's answer to a topic: a comment, a new status, a new
 * snapshot (a viewpoint of its own with the first viewpoint's camera and
 * selection, which the comment points at); each optional. The topic's
 * ModifiedDate / ModifiedAuthor are set; its GUID and everything it had
 * are kept, so the office's tool updates the topic it sent. */
typedef struct mr_bcf_answer_params {
    const char *comment;            /* NULL or "": none */
    const char *status;             /* NULL or "": unchanged, e.g. "Closed" */
    const unsigned char *snapshot;  /* PNG or JPEG bytes, NULL none */
    size_t snapshot_size;
    const char *author;             /* NULL: "mrcheck" */
} mr_bcf_answer_params;
bool mr_bcf_answer(mr_bcf_topic *t, const mr_bcf_answer_params *a, mr_error *err);

/* `mrcheck bcf list`: reads the BCF at path (warnings, one line each, on
 * warn unless NULL) and prints its topics on out (mr_bcf_print_list), with
 * scene_path (NULL: none) loaded to count the components it has. */
bool mr_bcf_list_file(const char *path, const char *scene_path, FILE *out, FILE *warn, mr_error *err);
/* `mrcheck bcf answer`: reads in, answers the topic named by topic (as
 * mr_bcf_find_topic) with answer (its snapshot read from snapshot_path,
 * if given) and writes all topics as BCF version to out (atomic). */
typedef struct mr_bcf_answer_file_params {
    const char *in;             /* BCF archive or folder, required */
    const char *topic;          /* 1-based number or GUID (prefix), required */
    mr_bcf_answer_params answer; /* comment, status, author (its snapshot is read from snapshot_path) */
    const char *snapshot_path;  /* PNG, NULL none */
    mr_bcf_version version;     /* of the file written */
    const char *out;            /* required */
    FILE *warn;                 /* the reader's warnings; NULL: not shown */
} mr_bcf_answer_file_params;
bool mr_bcf_answer_file(const mr_bcf_answer_file_params *p, mr_error *err);

/* ------------------------------------------------------------ the exports */

/* Writes the BCF archive of session_dir's marks to out_path (a temporary
 * file in the same folder, renamed when complete). Fails with one line, and
 * leaves out_path as it was, when there are no marks, a mark has no pose or
 * its snapshot is missing, or the file cannot be written. */
bool mr_export_bcf(const char *session_dir, const char *out_path, const mr_export_params *p, mr_error *err);

/* Writes the report folder out_dir: index.html (opens from disk, images
 * beside it), report.md, img/. It is written as out_dir.tmp.<pid> and
 * renamed; an existing earlier report at out_dir is replaced, any other
 * existing non-empty folder is refused. Same failures as mr_export_bcf. */
bool mr_export_report(const char *session_dir, const char *out_dir, const mr_export_params *p, mr_error *err);

/* ------------------------------------------------------------ writing marks */

/* A mark as `mrcheck view` writes it, for programs that place marks
 * themselves (the demo, tests): snapshots/<stem>_frame.png (frame, the raw
 * camera image of camera), snapshots/<stem>_screen.png (screen, may be
 * NULL), snapshots/<stem>.json (camera, frame index, time, pose), then the
 * line of m (mr_annotation_to_json) with its "snapshot" paths and the
 * optional distance_m / uncertainty_m (< 0: absent) appended durably to
 * session_dir/annotations.jsonl. */
typedef struct mr_mark_files {
    const char *stem;           /* file name stem, e.g. "mark_0001" */
    const mr_image *frame;      /* required */
    const mr_image *screen;     /* NULL: none */
    const mr_camera *camera;    /* required: of the raw frame */
    double distance_m;          /* < 0: not measured */
    double uncertainty_m;       /* < 0: not available */
} mr_mark_files;
bool mr_export_mark_write(const char *session_dir, const mr_annotation *m, const mr_mark_files *files, mr_error *err);

#ifdef __cplusplus
}
#endif
#endif
