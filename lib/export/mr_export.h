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
