/* mr_track.h — the tracked camera: marker map, AprilTag detection, camera
 * pose from all seen tags (PnP through OpenCV, behind pnp.cc), the One Euro
 * pose filter, and frame sources (V4L2, video files, image files and
 * sequences; recordings plug in through mr_source_ops).
 *
 * Conventions (shared DESIGN.md §2):
 *  - pixel coordinates follow OpenCV: the centre of the top-left pixel is
 *    (0,0), x right, y down. Detected corners are reported in this
 *    convention (the apriltag library's own +0.5 offset is removed);
 *  - a tag's frame has its origin at the tag centre, x right, y down as seen
 *    facing the tag, z into the surface; the four corners, in the apriltag
 *    library's order, are (-s/2,+s/2), (+s/2,+s/2), (+s/2,-s/2), (-s/2,-s/2)
 *    with s the edge of the black square (`tag_size`, scene units);
 *  - a pose is world_from_camera (row-major double 4x4, OpenCV camera axes).
 *
 * No OpenCV or C++ type crosses this header.
 */
#ifndef MR_TRACK_H
#define MR_TRACK_H

#include "mr_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------ marker map */

typedef struct mr_marker {
    int id;                  /* tag id in the family */
    mr_dmat4 world_from_tag; /* rigid */
    double size;             /* this tag's black-square edge (scene units) in a
                                map of mixed sizes; 0 = the map's tag_size */
    double cov[36];          /* the uncertainty of world_from_tag in a map
                                built from photos (mr_map_tag.cov's convention:
                                rotation about world x y z, radians, then the
                                centre, scene units); all 0 = exact (a planned
                                map), as is any non-finite entry */
} mr_marker;

typedef struct mr_marker_map {
    char family[32];         /* "tag36h11", ... */
    double tag_size;         /* black-square edge, scene units, > 0 */
    mr_marker *tags;         /* count tags, unique ids */
    int count;
} mr_marker_map;

/* {"family": "tag36h11", "tag_size": 0.4, "tags": [{"id": 0,
 *   "world_from_tag": [16]}, ...]}; a tag may carry its own "tag_size"
 * (maps of mixed sizes) and its "covariance" [36] (mr_marker.cov; null or
 * absent: exact), which `mrcheck map` writes and the pose solve weighs.
 * Other keys (the other σ fields `mrcheck map` writes) are ignored. Refuses duplicate ids, a tag size <= 0, non-rigid
 * transforms and unknown families. */
bool mr_marker_map_from_json(const cJSON *obj, mr_marker_map *map, mr_error *err);
bool mr_marker_map_parse(const char *text, size_t size, mr_marker_map *map, mr_error *err);
bool mr_marker_map_load(const char *path, mr_marker_map *map, mr_error *err);
cJSON *mr_marker_map_to_json(const mr_marker_map *map);
void mr_marker_map_free(mr_marker_map *map); /* zeroes the struct */
const mr_marker *mr_marker_map_find(const mr_marker_map *map, int id);
/* The black-square edge of tag m: its own size, else the map's. */
double mr_marker_size(const mr_marker_map *map, const mr_marker *m);
/* World positions of the four corners of tag m, apriltag order. */
void mr_marker_corners_world(const mr_marker_map *map, const mr_marker *m, mr_dvec3 out[4]);
/* Corners in the tag frame (z = 0), apriltag order. */
void mr_marker_corners_tag(double tag_size, mr_dvec3 out[4]);

/* Camera JSON from memory (the reader behind mr_camera_load; fuzzed). */
bool mr_camera_parse(const char *text, size_t size, mr_camera *cam, mr_error *err);

/* Is `name` a tag family the detector knows? */
bool mr_tag_family_known(const char *name);

/* A tag as printed: total_width x total_width cells, cell (x, y) at
 * cells[y * MR_TAG_MAX_CELLS + x], 1 = black, 0 = white; rendered from the
 * family's own code (apriltag's codes, nbits, bit_x, bit_y) the way the
 * detector reads it. The detector's quad, whose edge is a marker map's
 * tag_size, spans the middle width_at_border cells (tag36h11: the black
 * square, 8 of its 10 cells; the outer ring is the white quiet zone). */
#define MR_TAG_MAX_CELLS 16
typedef struct mr_tag_pattern {
    int total_width;          /* cells per side, quiet zone included */
    int width_at_border;      /* cells per side of the detected square */
    int codes;                /* ids in the family: 0 .. codes-1 */
    unsigned char cells[MR_TAG_MAX_CELLS * MR_TAG_MAX_CELLS];
} mr_tag_pattern;
/* false + err: unknown family, id outside the family. */
bool mr_tag_pattern_make(const char *family, int id, mr_tag_pattern *out, mr_error *err);

/* ------------------------------------------------------------- detection */

typedef struct mr_detection {
    int id;
    int hamming;             /* bits corrected */
    double decision_margin;  /* apriltag's decode confidence */
    double corners[4][2];    /* pixels, OpenCV convention, apriltag order */
} mr_detection;

typedef struct mr_detector_params {
    const char *family;      /* default "tag36h11" */
    double decimate;         /* quad_decimate >= 1; 0 = default 2.0 */
    int threads;             /* worker threads; 0 = default 1 */
    int refine_edges;        /* 1 on, -1 off, 0 = default (on) */
    double sharpening;       /* decode_sharpening; 0 = default 0.25, < 0 = none */
    double blur;             /* quad_sigma in px (Gaussian before quads); 0 = none */
    int max_hamming;         /* detections with more corrected bits are dropped;
                                0 = default 1, < 0 = 0 */
} mr_detector_params;
#define MR_DETECTOR_DEFAULTS {NULL, 0.0, 0, 0, 0.0, 0.0, 0}
/* What the 0s above stand for (detector.c and mr_detector_opts read these). */
#define MR_DETECTOR_DEFAULT_DECIMATE 2.0
#define MR_DETECTOR_DEFAULT_THREADS 1
#define MR_DETECTOR_DEFAULT_SHARPENING 0.25
/* The command line's detector options (--decimate, --threads, --refine-edges,
 * --sharpening), in the user's values: the fields' "0 = default, < 0 = off"
 * through MR_OPT_ZERO_DEFAULT (mr_core.h). The family is a name, not a row. */
extern const mr_opt mr_detector_opts[];

/* Frames smaller than this on either side are refused: the apriltag 3.3
 * library crashes on 1x1 images, and no tag fits in fewer pixels anyway. */
#define MR_DETECTOR_MIN_SIDE 16

typedef struct mr_detector mr_detector;
mr_detector *mr_detector_create(const mr_detector_params *params, mr_error *err);
void mr_detector_destroy(mr_detector **det);
/* Detects tags in an 8-bit image (1, 3 or 4 channels; colour is converted to
 * grey). Returns an array of *count detections sorted by id, owned by the
 * detector and valid until the next call; NULL + err on failure (a frame
 * that is too small, a bad image). Zero detections is success. */
const mr_detection *mr_detector_detect(mr_detector *det, const mr_image *img, int *count, mr_error *err);
/* The decimation of the next detection, in [1, 16] (false otherwise); the
 * tracker's adaptive decimation sets it per frame. */
bool mr_detector_set_decimate(mr_detector *det, double decimate);
double mr_detector_decimate(const mr_detector *det);

/* ------------------------------------------------- marker-map building */

/* `mrcheck map` (map.c, the adjustment in map_ba.cc through Ceres):
 *
 *   per photo and tag: undistorted corners -> IPPE camera_from_tag
 *   -> pairwise relative poses tag_a_from_tag_b from photos that see both
 *   -> per pair a robust mean (medoid, then the mean of those within
 *      5 degrees of it: IPPE's mirror branch drops out)
 *   -> connected parts; the part holding the gauge is mapped, the other
 *      tags are reported
 *   -> initial map: maximum spanning tree by shared photos from the root
 *      (the fixed tag, else the most seen), then rotation averaging over
 *      every pair (chordal means, a few sweeps) and the positions by
 *      averaging over every pair
 *   -> each photo's pose from all its tags (best single-tag start, LM)
 *   -> gauge: the fixed tag's given pose, or a weighted rigid fit to the
 *      control points
 *   -> global bundle adjustment of all tag and camera poses (and, asked,
 *      fx fy cx cy k1 k2) on corner reprojection error under a Huber loss,
 *      the control points as weighted residuals in the same problem
 *   -> per tag covariance (Ceres), scaled by the corner variance estimated
 *      from the residuals; control points' residuals and leave-one-out.
 *
 * "Chaining" (params.no_adjust) stops after the spanning tree: each tag's
 * pose is the product of the averaged relative poses along its tree path,
 * what a bundle calibration without global adjustment gives. */

typedef struct mr_map_photo {
    const mr_detection *dets; /* count detections, corners in pixels (distorted) */
    int count;
    const char *name;         /* for messages; may be NULL */
} mr_map_photo;

typedef struct mr_map_control {
    char name[64];
    int tag_id;
    int corner;               /* -1: the tag's centre; 0..3: that corner, apriltag order */
    mr_dvec3 world;           /* measured, scene units */
    double sigma;             /* 1-σ per axis, scene units, > 0 */
} mr_map_control;

typedef struct mr_map_params {
    double tag_size;          /* edge of every tag not in sizes, scene units;
                                 0 = none (such tags are skipped, with a warning) */
    const int *size_ids;      /* size_count tags of their own size */
    const double *sizes;
    int size_count;
    int fix_id;               /* gauge when control_count == 0: this tag */
    const mr_dmat4 *fix_pose; /* its world_from_tag; NULL = identity */
    const mr_map_control *controls; /* >= 3 control points: they are the gauge */
    int control_count;
    bool refine_intrinsics;   /* also adjust fx fy cx cy k1 k2 */
    bool no_adjust;           /* chaining only (the bench's baseline) */
    double loss_px;           /* Huber scale of the corner residuals, px; 0 = 1.0 */
    int max_iterations;       /* 0 = 100 */
    double min_tag_px;        /* shorter tag edges are ignored, px; 0 = 8 */
    double outlier_sigma;     /* a control point whose leave-one-out residual
                                 exceeds this many σ is an outlier; 0 = 5 */
    int threads;              /* Ceres threads; 0 = 1 */
    void (*progress)(void *user, const char *stage, double fraction); /* may be NULL */
    void *progress_user;
} mr_map_params;
#define MR_MAP_DEFAULTS {.tag_size = 0.0, .fix_id = 0, .fix_pose = NULL, .controls = NULL, .control_count = 0}
#define MR_MAP_DEFAULT_LOSS_PX 1.0
/* Option table (lib/track/options.c) of the numbers and switches above:
 * tag-size, loss, refine-intrinsics, chain. */
extern const mr_opt mr_map_opts[];

typedef struct mr_map_tag {
    int id;
    double size;              /* black-square edge, scene units */
    mr_dmat4 world_from_tag;
    int photos;               /* photos that saw it (and were used) */
    double cov[36];           /* 6x6 covariance of (rotation about world x y z,
                                 radians; centre x y z, scene units); the
                                 fixed tag's is 0; NaN = not computable */
    double sigma_xyz[3];      /* sqrt of the position diagonal, scene units */
    double sigma_pos;         /* sqrt(trace) of the position block: 3D 1-σ */
    double sigma_deg;         /* sqrt(trace) of the rotation block, degrees */
    double rms_px;            /* its corners' reprojection RMS */
} mr_map_tag;

typedef struct mr_map_control_result {
    double residual[3];       /* adjusted minus measured, scene units */
    double loo[3];            /* the same with this point left out of the
                                 solve (needs >= 4 points), else NaN */
    double loo_sigma;         /* |loo| over its expected σ; NaN if none */
    bool used;                /* in the gauge (false: an outlier, or its tag
                                 was not mapped) */
    bool outlier;             /* disagrees by more than outlier_sigma σ */
} mr_map_control_result;

typedef struct mr_map_result {
    mr_map_tag *tags;         /* tag_count mapped tags, sorted by id */
    int tag_count;
    int *unconnected;         /* ids seen but not connected to the gauge's part */
    int unconnected_count;
    int *unsized;             /* ids seen without a known size (skipped) */
    int unsized_count;
    int *unplaced;            /* ids of the part none of whose sightings
                                 agreed with the adjusted map, even after
                                 placing it again from the photo poses */
    int unplaced_count;
    mr_camera camera;         /* the intrinsics used (refined if asked) */
    int photos_used;          /* photos with a pose in the map */
    int photos_total;
    int observations;         /* tag sightings in the adjustment */
    double rms_px;            /* corner reprojection RMS after the adjustment
                                 (chaining: of the initial map) */
    double sigma_px;          /* corner noise estimated from the residuals */
    int iterations;
    bool adjusted;            /* the bundle adjustment ran */
    bool refined_intrinsics;  /* camera holds refined intrinsics */
    mr_map_control_result *controls; /* control_count, in the given order */
    int control_count;
} mr_map_result;

/* Builds the map. false + err on bad input (no photo, no tag seen, the
 * fixed tag never seen, < 3 usable control points or collinear ones, more
 * than one outlier too many); unconnected tags are no error. */
bool mr_map_build(const mr_camera *cam, const mr_map_photo *photos, int photo_count, const mr_map_params *params,
                  mr_map_result *out, mr_error *err);
void mr_map_result_free(mr_map_result *r); /* zeroes it */
/* The mapped tags as a marker map (family copied; tag_size: params' or
 * the first tag's; each tag of another size carries its own). */
bool mr_map_result_markers(const mr_map_result *r, const char *family, double tag_size, mr_marker_map *out,
                           mr_error *err);
/* The marker-map JSON (mr_marker_map_to_json) plus the map's evidence:
 * per tag "photos", "sigma_mm" [x y z] and "sigma_pos_mm" (1-σ position,
 * scene units taken as metres), "sigma_deg", "rms_px", "covariance" [36]
 * (rad, scene units), and a top-level "map" object: "rms_px", "sigma_px",
 * "photos_used", "photos_total", "observations", "gauge", "unconnected"
 * [ids], "unsized" [ids], "unplaced" [ids], "control_points" [{name, tag, corner,
 * residual_mm [3], loo_mm [3] or null, loo_sigma, used, outlier}]. */
cJSON *mr_map_result_to_json(const mr_map_result *r, const mr_marker_map *markers, const mr_map_params *params);
/* What `mrcheck map` prints: one warning line on stderr per unsized,
 * unconnected or unplaced tag, then on out the summary (tags, photos, RMS, the file
 * written), the largest tag sigma, each tag at --verbose, and each control
 * point's residual and leave-one-out check. */
void mr_map_result_report(const mr_map_result *r, const mr_map_params *params, const char *written, FILE *out);
/* Control points file: {"points": [{"name": "P1", "tag": 3, "corner":
 * "centre"|0..3, "xyz": [x, y, z], "sigma": s}, ...]} (sigma in scene
 * units; defaults to "sigma" at the top level, else 0.002). */
bool mr_map_controls_parse(const char *text, size_t size, mr_map_control **out, int *count, mr_error *err);
bool mr_map_controls_load(const char *path, mr_map_control **out, int *count, mr_error *err);

/* What `mrcheck map` gathers for mr_map_build (map_photos.c). */
/* "id=size,id=size" (ids >= 0, sizes > 0) into malloc'd arrays; false on a
 * bad list (the arrays may still be allocated: the caller frees them). */
bool mr_map_tag_sizes_parse(const char *s, int **ids, double **sizes, int *n);
/* {"world_from_tag": [16]}, rigid; false + err naming the file. */
bool mr_map_fix_pose_load(const char *path, mr_dmat4 *out, mr_error *err);
/* Every photo's detections (mr_detect_each over input), as mr_map_build
 * takes them; the first photo's size rescales *cam's intrinsics. on_photo
 * (may be NULL) is told the count after each photo. The set is filled as
 * far as it got even on failure: free it with mr_map_photo_set_free. */
typedef struct mr_map_photo_set {
    mr_detection **dets;
    mr_map_photo *photos;
    char (*names)[256];
    int n;
} mr_map_photo_set;
bool mr_map_photos_detect(const char *input, const char *family, const char *who, mr_camera *cam,
                          void (*on_photo)(void *user, int n), void *user, mr_map_photo_set *out, mr_error *err);
void mr_map_photo_set_free(mr_map_photo_set *ps);

/* ------------------------------------------------------------------ pose */

typedef struct mr_pose_params {
    double outlier_px;       /* a tag whose corner RMS exceeds this is dropped,
                                default 3.0 px */
    double max_rms_px;       /* no pose when the final RMS exceeds this,
                                default 4.0 px */
    double ambiguity_ratio;  /* candidate poses whose RMS is within this factor
                                of the best count as ambiguous (then the one
                                nearest the previous pose wins), default 2.5 */
    double ambiguity_px;     /* ... or within this many px of it, default 0.1 */
    double min_tag_px;       /* tags with a shorter edge are ignored, default 8 px */
    double corner_sigma_px;  /* the detector's corner noise where known, px:
                                pooled with the residuals' estimate as
                                MR_POSE_PRIOR_DOF more degrees of freedom, so
                                that a lone tag (2 of its own) cannot claim a
                                noise it has no way to know; 0 = none (the
                                tracker learns it from its multi-tag frames) */
} mr_pose_params;
#define MR_POSE_DEFAULTS {.outlier_px = 0.0, .max_rms_px = 0.0, .ambiguity_ratio = 0.0, .ambiguity_px = 0.0, .min_tag_px = 0.0, .corner_sigma_px = 0.0}
#define MR_POSE_PRIOR_DOF 8

#define MR_POSE_MAX_IDS 32

typedef struct mr_pose {
    bool valid;
    mr_dmat4 world_from_camera;
    int tags_seen;           /* detections that are in the map */
    int tags_used;           /* after outlier rejection */
    int ids_used[MR_POSE_MAX_IDS];
    double rms_px;           /* reprojection RMS over used corners, pixels */
    bool ambiguous;          /* single tag with two plausible IPPE solutions;
                                the one nearest the previous pose was kept */
    /* The pose's uncertainty (valid poses): the 6x6 row-major covariance
     * of camera_from_world's error as a small left perturbation in camera
     * axes, X_cam -> exp([w]x) X_cam + tau: w (rotation vector, radians)
     * then tau (scene units). From the used corners' Jacobian, with the
     * corner noise estimated from the residuals (dof-corrected) and never
     * below MR_POSE_MIN_CORNER_SIGMA_PX. mr_pose_point_sigma turns it into
     * "± N here". With map uncertainty (mr_marker.cov) each tag's corners
     * are weighted by (corner noise)^2 I + B C B^T (B: the corners'
     * pixels against the tag's pose, C: its map covariance), the solve is
     * that weighted least squares, and cov is its covariance: the corner
     * noise part plus the map part, cov_map. The corner noise is then the
     * value that makes the weighted residuals' chi-square equal their
     * degrees of freedom (the map explains part of the residuals). */
    double cov[36];
    double cov_map[36];      /* the part of cov from the map's uncertainty
                                (shared by every frame that sees the same
                                tags, so it does not average out over frames;
                                0 when the map is exact) */
    double corner_sigma_px;  /* the corner noise used, px */
} mr_pose;
/* Corner noise floor of the covariance (px): a lucky frame with near-exact
 * corners must not claim sub-micron registration. */
#define MR_POSE_MIN_CORNER_SIGMA_PX 0.1
/* The uncertainty of a world point's place relative to the camera under
 * pose's covariance: *sigma_3d = sqrt(trace) of its 3x3 covariance (scene
 * units), *sigma_lateral the part across the line of sight (what moves the
 * overlay on screen), either may be NULL. false if the pose is invalid,
 * has no covariance, or the point is behind the camera. */
bool mr_pose_point_sigma(const mr_pose *pose, mr_dvec3 world_point, double *sigma_3d, double *sigma_lateral);

/* Camera pose from the detections: corners undistorted, candidate poses from
 * each tag's two IPPE solutions, the candidate that most tags agree with
 * (ties: nearest the previous pose, then lowest error), Levenberg-Marquardt
 * refinement over all inlier corners, outlier tags dropped. `prev` (may be
 * NULL or invalid) keeps a single tag from flipping. Returns false + err only
 * on bad arguments; "no pose" is out->valid == false. */
bool mr_pose_solve(const mr_camera *cam, const mr_marker_map *map, const mr_detection *dets, int count,
                   const mr_pose *prev, const mr_pose_params *params, mr_pose *out, mr_error *err);

/* Still-camera fusion: the poses of a camera that stands still (or a
 * frozen view), fused over the frames, so the σ shrinks with the frames
 * down to the map's floor. Each pose's own part (cov - cov_map) is
 * independent from frame to frame and is fused by its information; the
 * map part is the same tags' error in every frame and stays as it is (its
 * mean). A frame further from the fused pose than MR_POSE_FUSION_GATE
 * (chi-square, 6 degrees of freedom, p = 1e-4) means the camera moved:
 * the fusion restarts at that frame. Corner noise that repeats from frame
 * to frame (the same pixels of a truly static image) is not independent;
 * fused poses of such frames claim too much. Zero-initialise, or reset. */
typedef struct mr_pose_fusion {
    mr_pose pose;            /* the fused pose (valid once a frame was added):
                                world_from_camera, cov (own + map), cov_map;
                                the quality fields of the latest frame */
    int frames;              /* frames fused since the camera last moved */
    mr_dmat4 ref;            /* internal: the first frame's camera_from_world */
    double info[36], info_d[6], map_sum[36]; /* internal sums */
} mr_pose_fusion;
#define MR_POSE_FUSION_GATE 27.86
void mr_pose_fusion_reset(mr_pose_fusion *f);
/* Adds a frame's pose. true: fused (or the first); false: the camera moved
 * (the fusion restarted at this pose, frames = 1), or the pose is invalid
 * or has no covariance (the fusion is reset, frames = 0). */
bool mr_pose_fusion_add(mr_pose_fusion *f, const mr_pose *pose);

/* Projects a world point with the camera model; false if behind the camera. */
bool mr_project_point(const mr_camera *cam, const mr_dmat4 *world_from_camera, mr_dvec3 p, double *u, double *v);

/* Pose differences: translation distance (scene units) and rotation angle
 * (degrees) between two rigid transforms. */
double mr_pose_dist(const mr_dmat4 *a, const mr_dmat4 *b);
double mr_pose_angle_deg(const mr_dmat4 *a, const mr_dmat4 *b);

/* Rotation vector (axis * angle, radians) <-> rotation matrix (3x3 row-major). */
void mr_rotvec_to_mat(const double rv[3], double R[9]);
void mr_mat_to_rotvec(const double R[9], double rv[3]);

/* ------------------------------------------------------ triangulation */

/* A real feature tapped in several frames (`mrcheck measure`): each tap is
 * a pixel (distorted, OpenCV convention) in a frame with its tracked pose
 * and that pose's covariance (mr_pose.cov; none: only the tap's noise). */
typedef struct mr_tap {
    mr_dmat4 world_from_camera;
    const double *pose_cov;  /* 36, mr_pose.cov's convention; NULL: none */
    double px[2];
    const double *pose_cov_map; /* 36, mr_pose.cov_map: the part of pose_cov
                                   shared between taps (the map's); NULL: the
                                   whole pose_cov is this tap's own */
} mr_tap;
typedef struct mr_triangulate_params {
    double tap_sigma_px;     /* a tap's 1-σ per axis, px; 0 = 1.0 */
    double min_angle_deg;    /* refused below this largest angle between rays; 0 = 2 */
} mr_triangulate_params;
#define MR_TRIANGULATE_DEFAULT_TAP_SIGMA_PX 1.0
#define MR_TRIANGULATE_DEFAULT_MIN_ANGLE_DEG 2.0
#define MR_TRIANGULATE_DEFAULTS {.tap_sigma_px = 0.0, .min_angle_deg = 0.0} /* 0 = the defaults above */
extern const mr_opt mr_triangulate_opts[]; /* tap-sigma, min-angle */
typedef struct mr_triangulation {
    mr_dvec3 point;          /* world, scene units */
    double cov[9];           /* 3x3 covariance of point (taps and poses) */
    double sigma;            /* sqrt(trace(cov)) */
    double angle_deg;        /* the largest angle between two rays */
    double rms_px;           /* reprojection RMS of the taps */
} mr_triangulation;
/* Linear (closest point to all rays), then Gauss-Newton on the taps'
 * reprojection error, each weighted by its tap noise plus its pose's own
 * covariance (pose_cov less pose_cov_map) carried into the image. The
 * shared map part moves every tap's ray alike, so it moves the point as a
 * whole: the point's covariance adds the mean over the taps of the map
 * part carried to the point (it does not shrink with more taps). false + err: fewer than 2 taps, a tap
 * that cannot be undistorted, rays nearly parallel ("baseline angle 0.4
 * deg < 2 deg": taken from nearly the same place), the point behind a
 * camera. */
bool mr_triangulate(const mr_camera *cam, const mr_tap *taps, int n, const mr_triangulate_params *params,
                    mr_triangulation *out, mr_error *err);
/* Distance from planned to measured and its
 * 1-σ (the covariance projected on that direction; with a zero difference,
 * sqrt(trace / 3)). */
void mr_triangulation_distance(const mr_triangulation *t, mr_dvec3 planned, double *dist, double *sigma);

/* A measurement as the view's Measure keeps it and a mark carries it:
 * the taps, the triangulated point, and its distance to the
 * plan (the nearest point of the planned model, or a picked planned point). */
#define MR_MEASURE_MAX_TAPS 16
typedef struct mr_measurement {
    int taps;
    int64_t frames[MR_MEASURE_MAX_TAPS];   /* frame index of each tap */
    double px[MR_MEASURE_MAX_TAPS][2];     /* each tap, camera pixels */
    mr_triangulation tri;                  /* point, covariance, sigma, angle, rms */
    bool has_distance;
    double distance_m, distance_sigma_m;   /* to `planned`, scene units taken as metres, 1-sigma */
    mr_dvec3 planned;                      /* the planned point it was measured to */
    char planned_node[96];                 /* that point's node, "" unknown */
} mr_measurement;

/* ---------------------------------------------------------------- filter */

typedef struct mr_filter_params {
    double min_cutoff;       /* One Euro cutoff at rest, Hz; default 0.5 */
    double beta;             /* cutoff increase per unit speed (1/scene unit for
                                translation); default 2.0 */
    double d_cutoff;         /* cutoff for the speed estimate, Hz; default 1.0 */
    double rot_min_cutoff;   /* for rotation, Hz; default 0.5 */
    double rot_beta;         /* per rad/s; default 1.0 */
    double jump_dist;        /* reset when the raw pose moves more than this
                                between frames, scene units; default 0.5 */
    double jump_deg;         /* ... or turns more than this; default 20 */
    double max_gap_s;        /* reset after a gap longer than this; default 0.5 s */
} mr_filter_params;
#define MR_FILTER_DEFAULTS {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}
/* What the 0s above stand for (filter.c and mr_filter_opts read these). */
#define MR_FILTER_DEFAULT_MIN_CUTOFF 0.5
#define MR_FILTER_DEFAULT_BETA 2.0
#define MR_FILTER_DEFAULT_D_CUTOFF 1.0
#define MR_FILTER_DEFAULT_ROT_MIN_CUTOFF 0.5
#define MR_FILTER_DEFAULT_ROT_BETA 1.0
#define MR_FILTER_DEFAULT_JUMP_DIST 0.5
#define MR_FILTER_DEFAULT_JUMP_DEG 20.0
#define MR_FILTER_DEFAULT_MAX_GAP_S 0.5
/* The One Euro filter's tunables (settings files, benches), in the user's
 * values; every field's 0 is its default (MR_OPT_ZERO_DEFAULT), so each
 * range starts above 0. */
extern const mr_opt mr_filter_opts[];

typedef struct mr_pose_filter mr_pose_filter;
mr_pose_filter *mr_pose_filter_create(const mr_filter_params *params, mr_error *err);
void mr_pose_filter_destroy(mr_pose_filter **f);
void mr_pose_filter_reset(mr_pose_filter *f);
/* While frozen the output stays at the last filtered pose whatever comes in
 * (a check on a still image); unfreezing resets the filter. */
void mr_pose_filter_freeze(mr_pose_filter *f, bool frozen);
bool mr_pose_filter_frozen(const mr_pose_filter *f);
/* Feeds a raw pose at time t (seconds, increasing). *out gets the filtered
 * pose. Returns true if the filter reset on this sample (first sample, jump,
 * gap or time going backwards). */
bool mr_pose_filter_update(mr_pose_filter *f, double t, const mr_dmat4 *raw, mr_dmat4 *out);
/* The last output (identity before the first sample); false if none yet. */
bool mr_pose_filter_last(const mr_pose_filter *f, mr_dmat4 *out);

/* --------------------------------------------------------------- tracker */

/* The one tracking pipeline every command uses (track, record, view
 * --retrack, bench tracking, demo, synth): per frame
 *
 *   detect tags -> undistort + solve the pose (mr_pose_solve, with the
 *   previous pose by the policy below) -> One Euro filter -> quality
 *
 * Previous-pose policy: the last valid raw pose steers the solve (it picks
 * between a single tag's two IPPE solutions) only while it is fresh:
 * 0 <= t - t_prev < prev_max_age_s, which defaults to the filter's gap reset
 * (max_gap_s, 0.5 s). A pose older than that no longer describes where the
 * camera is (the filter itself has forgotten it), so letting it choose
 * between two mirror solutions would be a guess presented as memory; a
 * timestamp going backwards (a seek) also drops it. Without it, the solver
 * takes the candidate most tags agree with, then the lowest error.
 *
 * Adaptive decimation, when detector.decimate is left 0: the
 * detector's decimation for a frame is picked from the tags of the frame
 * before, by the shortest edge e (px, full resolution) of the second
 * largest tag detected (the only one's, if one): 4 for e >= 64, 3 for
 * e >= 48, 2 for e >= 16, 1 below, so two tags keep >= 16 px after
 * decimation at 3 and 4, >= 8 at 2 (the 20 px tags of the shipped
 * recording are found at 2 as at 1). Two tags keep the pose multi-tag (no
 * mirror ambiguity); smaller, further tags add little to the pose and may
 * be lost at 3 or 4. Edge refinement (on by default) fits the corners at
 * full resolution again: decimation 2's accuracy at a fraction of the time
 * on large tags. On the first frame and after a frame without tags it is
 * the conservative MR_DETECTOR_DEFAULT_DECIMATE (2), and a pick coarser
 * than that gives way to 2 on every MR_TRACKER_PROBE_FRAMES-th frame (a
 * probe for tags that came into view). A frame that finds fewer than two
 * tags at a coarser decimation than 2, and fewer than the frame before, is
 * detected once more at 2 (a miss costs one more detection, never the frame
 * or a multi-tag pose). An explicit
 * detector.decimate (--decimate) fixes it. r.decimate says which was used.
 *
 * Usage (all a caller needs):
 *
 *   mr_tracker_params tp = MR_TRACKER_DEFAULTS;
 *   tp.camera = &cam;           // NULL: detection only
 *   tp.markers = &map;          // NULL: detection only
 *   mr_tracker *t = mr_tracker_create(&tp, &err);
 *   while (read a frame) {
 *       mr_tracker_result r;
 *       if (!mr_tracker_frame(t, &frame.image, frame.timestamp, &r, &err)) ...; // bad frame
 *       if (r.pose.valid) use r.pose (raw) or, if r.has_filtered, r.filtered;
 *   }
 *   mr_tracker_destroy(&t);
 */
typedef struct mr_tracker_params {
    const mr_camera *camera;        /* intrinsics (copied); frames of another
                                       size get them rescaled. NULL: detect only */
    const mr_marker_map *markers;   /* marker map (copied). NULL: detect only */
    mr_detector_params detector;    /* family NULL: the marker map's, else tag36h11 */
    mr_pose_params pose;            /* zero = mr_pose_solve's defaults */
    mr_filter_params filter;        /* zero = the One Euro defaults */
    bool no_filter;                 /* raw poses only: has_filtered stays false */
    bool freeze_first;              /* freeze the filter at the first valid pose
                                       (a check on a still image) */
    double prev_max_age_s;          /* previous-pose policy above, seconds;
                                       0 = the filter's max_gap_s (0.5 s) */
} mr_tracker_params;
/* Zero everywhere means default (nested params included). */
#define MR_TRACKER_DEFAULTS {.camera = NULL, .markers = NULL, .no_filter = false, .freeze_first = false, .prev_max_age_s = 0.0}

typedef struct mr_tracker_result {
    const mr_detection *detections; /* detection_count, sorted by id; owned by
                                       the tracker, valid until the next frame */
    int detection_count;
    bool solved;                    /* camera and markers known: a pose was sought */
    mr_pose pose;                   /* raw pose and its quality (valid, tags_seen,
                                       tags_used, ids_used, rms_px, ambiguous) */
    bool prev_used;                 /* the previous pose steered the solve */
    bool has_filtered;              /* filtered holds the filter's output: after a
                                       valid pose, or the held pose while frozen */
    mr_dmat4 filtered;              /* filtered world_from_camera */
    bool filter_reset;              /* the filter restarted on this frame (first
                                       pose, jump, gap) */
    bool frozen;                    /* the filter holds its pose */
    double decimate;                /* the detector's decimation on this frame
                                       (mr_tracker_frame; 0 from mr_tracker_detections) */
    bool redetected;                /* adaptive decimation lost the last frame's tags
                                       and the frame was detected again at 2 */
    mr_pose fused;                  /* the raw poses fused since the camera last
                                       moved (mr_pose_fusion); its σ shrinks while
                                       the camera stands still */
    int fused_frames;               /* frames in fused; 0: none (no pose) */
} mr_tracker_result;
/* Adaptive decimation (above): the probe interval, and the rule. */
#define MR_TRACKER_PROBE_FRAMES 8
double mr_tracker_pick_decimate(double min_edge_px);

typedef struct mr_tracker mr_tracker;
/* NULL + err on bad parameters (an invalid camera, an unknown family). */
mr_tracker *mr_tracker_create(const mr_tracker_params *params, mr_error *err);
void mr_tracker_destroy(mr_tracker **t); /* NULLs *t; accepts NULL */
/* One frame (8-bit, 1, 3 or 4 channels) at `timestamp` (seconds, source
 * clock). false + err only when the frame cannot be processed (too small,
 * bad image); a frame without tags or without a pose is success. */
bool mr_tracker_frame(mr_tracker *t, const mr_image *image, double timestamp, mr_tracker_result *out, mr_error *err);
/* The same from detections found elsewhere (another detector, e.g. the
 * aruco peer in `bench tracking`, or detections read from a recording):
 * everything after detection, for a frame of width x height pixels.
 * out->detections is dets. */
bool mr_tracker_detections(mr_tracker *t, const mr_detection *dets, int count, int width, int height, double timestamp,
                           mr_tracker_result *out, mr_error *err);
/* Forgets the previous pose and restarts the filter (a cut in the input);
 * a freeze is lifted. */
void mr_tracker_reset(mr_tracker *t);
/* While frozen the filtered pose stays where it is whatever the frames show
 * (the view's freeze); unfreezing restarts the filter. */
void mr_tracker_freeze(mr_tracker *t, bool frozen);
bool mr_tracker_frozen(const mr_tracker *t);
/* The copies the tracker works with (NULL if it has none). */
const mr_camera *mr_tracker_camera(const mr_tracker *t);
const mr_marker_map *mr_tracker_markers(const mr_tracker *t);

/* ---------------------------------------------------------- frame sources */

typedef struct mr_frame {
    mr_image image;          /* 8-bit, 1 or 3 channels; owned by the source,
                                valid until the next read */
    double timestamp;        /* seconds (source clock; sequences: index / fps) */
    int64_t index;           /* 0-based, in source order */
    char name[256];          /* file name for image sequences, else "" */
} mr_frame;

typedef enum mr_read_status { MR_READ_FRAME = 0, MR_READ_END = 1, MR_READ_ERROR = 2 } mr_read_status;

typedef struct mr_source_params {
    int width, height;       /* V4L2: requested size; 0 = default 1280x720 */
    double fps;              /* V4L2: requested rate; image sequences: the
                                timestamp step; 0 = default 30 */
    const char *pixel_format;/* V4L2: "YUYV" or "MJPG"; NULL = try YUYV, then MJPG */
    int retries;             /* V4L2: reopen attempts after the device vanished,
                                default 5 (< 0 = none) */
    double retry_s;          /* seconds between attempts, default 1.0 */
    bool gray;               /* deliver grey frames (cheaper for tracking) */
} mr_source_params;
#define MR_SOURCE_DEFAULTS {0, 0, 0.0, NULL, 0, 0.0, false}

/* A source kind implemented elsewhere (e.g. recordings in lib/session). */
typedef struct mr_source_ops {
    const char *kind;
    mr_read_status (*read)(void *impl, mr_frame *frame, mr_error *err);
    void (*close)(void *impl);
} mr_source_ops;

typedef struct mr_source mr_source;
/* Opens /dev/videoN (V4L2), a folder of images (sorted by name), a single
 * image file, or a video file (anything else, through OpenCV). */
mr_source *mr_source_open(const char *uri, const mr_source_params *params, mr_error *err);
mr_source *mr_source_from_ops(const mr_source_ops *ops, void *impl, mr_error *err);
void mr_source_close(mr_source **src);
const char *mr_source_kind(const mr_source *src); /* "v4l2", "images", "video", ... */
/* MR_READ_FRAME: *frame is filled. MR_READ_END: no more frames. MR_READ_ERROR:
 * err says why; for live devices the source already retried. Frames that
 * cannot be decoded are skipped with a warning on the log. */
mr_read_status mr_source_read(mr_source *src, mr_frame *frame, mr_error *err);

/* The image files of a folder (png, jpg, jpeg, pgm, ppm, pnm, bmp, tga;
 * no hidden files), sorted by name: *count malloc'd names in a malloc'd
 * array, freed by mr_image_folder_free. No images is success (*count 0);
 * false + err if the folder cannot be read. */
bool mr_image_folder_list(const char *dir, char ***names, int *count, mr_error *err);
void mr_image_folder_free(char ***names, int count); /* NULLs *names */

/* V4L2 directly (mr_source_open uses it for /dev/... paths). */
mr_source *mr_source_open_v4l2(const char *device, const mr_source_params *params, mr_error *err);

/* ------------------------------------------------- OpenCV aruco (peer) */

/* OpenCV's aruco detector with DICT_APRILTAG_36h11, for comparison in
 * `mrcheck bench tracking`. Corners are converted to the apriltag order
 * above, so the same pose code runs on both. */
typedef enum mr_aruco_refine {
    MR_ARUCO_REFINE_NONE = 0,
    MR_ARUCO_REFINE_SUBPIX,
    MR_ARUCO_REFINE_CONTOUR,
    MR_ARUCO_REFINE_APRILTAG,
} mr_aruco_refine;

typedef struct mr_aruco mr_aruco;
mr_aruco *mr_aruco_create(mr_aruco_refine refine, mr_error *err);
void mr_aruco_destroy(mr_aruco **a);
/* As mr_detector_detect: results owned by a, valid until the next call. */
const mr_detection *mr_aruco_detect(mr_aruco *a, const mr_image *img, int *count, mr_error *err);
const char *mr_aruco_refine_name(mr_aruco_refine refine);

/* ------------------------------------------------ photo sets
 * What calibration and mapping share: every image of a folder, a video or
 * one image (grey, mr_source_open) through one detector at full
 * resolution, since corner accuracy is what they measure. Frames of
 * another size than the first, and frames the detector refuses, are skipped
 * with a warning "mrcheck: WHO: warning: ..." on stderr. fn gets each
 * other frame and its detections (valid during the call); false from fn
 * stops the run and fails it. */
typedef bool (*mr_detect_each_fn)(void *user, const mr_frame *f, const mr_detection *d, int count, mr_error *err);
/* A stop (SIGINT/SIGTERM, mr_stop_requested) ends it before the next frame:
 * false with MR_ERR_INTERRUPTED. */
bool mr_detect_each(const char *input, const char *family, const char *who, mr_detect_each_fn fn, void *user,
                    int *skipped, mr_error *err);

/* ------------------------------------------------------- calibration */

/* One image's correspondences: n board points (board frame, z = 0) and
 * their detected pixels (OpenCV convention). */
typedef struct mr_calib_view {
    const double *object; /* 3n */
    const double *image;  /* 2n */
    int n;
} mr_calib_view;

/* OpenCV calibrateCamera (k1 k2 p1 p2, k3 fixed at 0: a few board views do
 * not constrain it) over >= 3 views. *rms_px gets the RMS reprojection
 * error; per_view_rms (may be NULL) one value per view. */
bool mr_calibrate(const mr_calib_view *views, int nviews, int width, int height, mr_camera *out, double *rms_px,
                  double *per_view_rms, mr_error *err);

/* `mrcheck calibrate`: a folder of images of a planar tag board (a marker
 * map whose tags all lie in its z = 0 plane), each detected at full
 * resolution; images of another size than the first, or with fewer than
 * min_tags board tags, are skipped (with a warning on stderr for the
 * former and unreadable ones); then mr_calibrate over the rest. */
typedef struct mr_board_calib_params {
    const char *images;           /* folder (png, jpg, ...); required */
    const mr_marker_map *board;   /* required */
    const char *board_name;       /* for messages (its file), or NULL */
    int min_tags;                 /* 0 = 4 */
    bool progress;                /* "calibrate: image N" on stderr */
} mr_board_calib_params;
#define MR_BOARD_CALIB_DEFAULT_MIN_TAGS 4
extern const mr_opt mr_board_calib_opts[]; /* min-tags */
typedef struct mr_board_calib {
    mr_camera camera;
    double rms_px;                /* RMS reprojection error over all views */
    int views, skipped;           /* images used and left out */
    char (*names)[256];           /* the used images' names, views of them */
    double *view_rms_px;          /* their own RMS, views of them */
} mr_board_calib;
bool mr_calibrate_board(const mr_board_calib_params *p, mr_board_calib *out, mr_error *err);
void mr_board_calib_free(mr_board_calib *c);

/* ------------------------------------------------------- video writing */

/* Motion-JPEG AVI through OpenCV, written to a temporary file and renamed
 * over `path` by mr_video_writer_close (so no half-written video is ever
 * seen under that name); mr_video_writer_abort removes it instead. */
typedef struct mr_video_writer mr_video_writer;
mr_video_writer *mr_video_writer_open(const char *path, int width, int height, double fps, mr_error *err);
bool mr_video_writer_add(mr_video_writer *w, const mr_image *img, mr_error *err); /* 8-bit grey or RGB */
bool mr_video_writer_close(mr_video_writer **w, mr_error *err);
void mr_video_writer_abort(mr_video_writer **w);

/* ------------------------------------------------------- image coding */

/* JPEG / PNG encoding and decoding through OpenCV (used for recordings and
 * MJPEG). encode: *data is malloc'd. quality 1..100 for JPEG. */
bool mr_image_encode(const mr_image *img, const char *ext, int quality, void **data, size_t *size, mr_error *err);
bool mr_image_decode(const void *data, size_t size, int channels, mr_image *img, mr_error *err);

/* Grey conversion (Rec. 601 luma) of an 8-bit image with 1, 3 or 4 channels. */
bool mr_image_to_gray(const mr_image *src, mr_image *dst, mr_error *err);

#ifdef __cplusplus
}
#endif
#endif
