/* mr_session.h — recordings: a folder written as it goes and read back for
 * replay (shared DESIGN.md §2).
 *
 *   meta.json          camera, marker map (inline), source, start time;
 *                      written once, atomically, when recording starts
 *   frames/NNNNNN.jpg  one image per frame, each written atomically
 *                      (temp + rename) before its line below
 *   frames.jsonl       one line per frame: {"frame", "t", "image",
 *                      "detections": [{"id","hamming","corners"}],
 *                      "pose": {"valid","world_from_camera","tags_used",
 *                      "tags_seen","rms_px","ambiguous","ids"},
 *                      "filtered": [16]}
 *   groundtruth.jsonl  synthetic recordings: {"frame","t",
 *                      "world_from_camera", "still"}
 *   annotations.jsonl  discrepancy marks of `mrcheck view` (in its session
 *                      folder): {"type","time_unix","frame_index",
 *                      "timestamp","id","revision","category","note",
 *                      "title","status","priority","assignee","labels",
 *                      "pixel":[x,y],"hit",
 *                      "world":[3]|null,"depth","node","layer",
 *                      "pose":{"valid","world_from_camera",...},
 *                      "snapshot":{"screen","frame","pose"}}
 *
 * Crash safety: the .jsonl files are append-only; each line is written
 * whole, flushed and fsync'd before the next frame, so after a kill -9 at
 * most the frame being written is lost. Nothing written is ever rewritten in
 * place. The reader skips a torn last line (no newline) silently and a
 * garbage line anywhere with a warning.
 */
#ifndef MR_SESSION_H
#define MR_SESSION_H

#include "mr_core.h"
#include "mr_track.h"

#ifdef __cplusplus
extern "C" {
#endif

/* -------------------------------------------------------------- writing */

typedef struct mr_recorder_params {
    const mr_camera *camera;        /* required */
    const mr_marker_map *markers;   /* copied into meta.json; may be NULL */
    const char *source;             /* what was recorded ("/dev/video0", a path) */
    const char *frame_ext;          /* ".jpg" (default) or ".png" */
    int jpeg_quality;               /* 1..100, default 90 */
    bool ground_truth;              /* also open groundtruth.jsonl */
} mr_recorder_params;
#define MR_RECORDER_DEFAULTS {NULL, NULL, NULL, NULL, 0, false}
#define MR_RECORDER_DEFAULT_JPEG_QUALITY 90
extern const mr_opt mr_recorder_opts[]; /* jpeg (lib/session/options.c) */

/* One frame's tracking result as recorded. */
typedef struct mr_frame_record {
    int64_t index;                  /* frame number in the recording */
    double t;                       /* seconds since the start */
    char image[64];                 /* relative path of the image ("" if none) */
    const mr_detection *detections; /* detection_count entries */
    int detection_count;
    mr_pose pose;                   /* raw pose (pose.valid false: none) */
    bool has_filtered;
    mr_dmat4 filtered;              /* filtered pose, if has_filtered */
} mr_frame_record;

typedef struct mr_recorder mr_recorder;
/* Creates dir (mkdir -p) and writes meta.json; refuses a folder that
 * already holds a recording (nothing is overwritten). */
mr_recorder *mr_recorder_create(const char *dir, const mr_recorder_params *params, mr_error *err);
/* Writes the image (may be NULL: no image) and appends the frame line;
 * rec->index is assigned by the recorder (0, 1, ...) and rec->image is
 * filled. */
bool mr_recorder_append(mr_recorder *r, mr_frame_record *rec, const mr_image *image, mr_error *err);
/* Detections as the line formats write them: [{"id", "hamming", "corners":
 * [[x, y] x 4]}]. quantum_px > 0 rounds the corners to multiples of it (the
 * `track` output uses 1/1000 px, far below the detector's accuracy); 0
 * keeps them exact (recordings, which are read back). */
cJSON *mr_detections_json(const mr_detection *d, int n, double quantum_px);
/* One line of `track`'s poses.jsonl: {"frame", "t", "valid",
 * "world_from_camera" (if valid), "filtered" (if any), "tags_seen",
 * "tags_used", "rms_px", "ambiguous"}. */
cJSON *mr_pose_line_json(int64_t frame, double t, const mr_tracker_result *r);
/* Appends a ground-truth line (recorders created with ground_truth). */
bool mr_recorder_ground_truth(mr_recorder *r, int64_t index, double t, const mr_dmat4 *world_from_camera, bool still,
                              mr_error *err);
int64_t mr_recorder_frame_count(const mr_recorder *r);
void mr_recorder_close(mr_recorder **r);

/* -------------------------------------------------------------- reading */

typedef struct mr_rec_frame {
    int64_t index;
    double t;
    char image[64];
    mr_detection *detections;
    int detection_count;
    mr_pose pose;
    bool has_filtered;
    mr_dmat4 filtered;
    bool has_gt;                    /* a ground-truth line for this frame */
    mr_dmat4 gt;
    bool still;                     /* ground truth: the camera is not moving */
} mr_rec_frame;

typedef struct mr_recording {
    char dir[1024];
    mr_camera camera;
    bool has_markers;
    mr_marker_map markers;
    char source[512];
    double start_time;              /* Unix seconds */
    mr_rec_frame *frames;           /* in file order */
    int frame_count;
    int bad_lines;                  /* garbage lines skipped (warned) */
    bool torn_tail;                 /* a torn last line was ignored */
} mr_recording;

/* Reads meta.json, frames.jsonl and groundtruth.jsonl (if present). */
mr_recording *mr_recording_open(const char *dir, mr_error *err);
void mr_recording_close(mr_recording **rec);

/* A measurement's taps (`mrcheck measure --observations OBS.json`:
 * {"taps": [{"frame": N, "px": [u, v]}, ...], "planned": [x, y, z]}) read
 * against the recording whose frames were tapped: each tap takes its
 * frame's pose and, where the recording carries one, its covariance
 * (no_cov counts the frames without). One clear error for a tap that names
 * a frame not in the recording or without a pose. */
#define MR_OBSERVATIONS_MAX 64
typedef struct mr_observations {
    mr_tap taps[MR_OBSERVATIONS_MAX];
    int count, no_cov;
    bool has_planned;
    double planned[3];
} mr_observations;
bool mr_observations_load(const char *path, const mr_recording *rec, mr_observations *o, mr_error *err);
/* Parses frames.jsonl / groundtruth.jsonl text into rec (used by open and
 * by the fuzz target). Never fails on content: bad lines are counted. */
bool mr_recording_parse_frames(mr_recording *rec, const char *text, size_t size, mr_error *err);
void mr_recording_parse_ground_truth(mr_recording *rec, const char *text, size_t size);
/* Loads frame i's image (8-bit, grey if gray else RGB). */
bool mr_recording_load_image(const mr_recording *rec, int i, bool gray, mr_image *img, mr_error *err);
/* Parses a meta.json object into rec's camera / markers / source. */
bool mr_recording_parse_meta(mr_recording *rec, const cJSON *meta, mr_error *err);

/* The recording's frames as a frame source (timestamps as recorded);
 * frames whose image is missing or damaged are skipped with a warning.
 * Takes ownership of rec. */
mr_source *mr_recording_source(mr_recording *rec, bool gray, mr_error *err);
/* True if dir looks like a recording (has meta.json and frames.jsonl). */
bool mr_is_recording(const char *dir);

/* ------------------------------------------------------ tracking input */

/* The input of a tracking command: a recording folder (its frames as a
 * source; *rec_info, if asked for, a second read-only copy whose camera and
 * markers serve as defaults), else mr_source_open's (/dev/videoN, a video
 * file, an image or a folder of images). NULL + err if it cannot be opened. */
mr_source *mr_input_open(const char *uri, const mr_source_params *params, mr_recording **rec_info, mr_error *err);

/* A tracker whose camera and marker map come from the files given
 * (camera_path, markers_path; NULL: none), else from rec (may be NULL):
 * a file always wins over the recording. tp's camera and markers are
 * ignored; its other fields are used as they are. A --family that differs
 * from the map's is warned about. NULL + err on a bad file. */
mr_tracker *mr_input_tracker_create(const char *camera_path, const char *markers_path, const mr_recording *rec,
                                    const mr_tracker_params *tp, mr_error *err);

/* ---------------------------------------------------------- replay index */

/* A recording (or a plain folder of frames) opened for random access, so a
 * replay can seek, step backwards and pace itself by timestamps. Positions
 * are 0 .. count-1 in file order (recordings) or name order (folders). */
typedef struct mr_replay_frame {
    int64_t index;                  /* the recorded frame number (folders: the position) */
    double t;                       /* seconds; folders without frames.jsonl: position / 30 */
    bool has_pose;                  /* a recorded pose to show */
    mr_dmat4 pose;                  /* the filtered pose where recorded (as the
                                       live view showed it), else the raw one */
    int tags_seen;                  /* recorded tags seen, -1 unknown */
    double rms_px;                  /* recorded RMS of a valid pose, -1 unknown */
    /* The recorded pose's covariance (mr_pose.cov's convention); recordings
     * made before it was written have none: corner_sigma_px 0. */
    double cov[36];
    double corner_sigma_px;
} mr_replay_frame;

typedef struct mr_replay mr_replay;
/* A recording folder (meta.json + frames.jsonl), or a folder of images
 * (DIR/frames/ or DIR itself; a frames.jsonl beside them, in the recording
 * line format, supplies timestamps and poses by "frame" number). Fails if
 * there are no frames. */
mr_replay *mr_replay_open(const char *dir, mr_error *err);
/* The index of a recording already read (takes ownership of rec, also on
 * failure; used by mr_replay_open and the fuzz target). */
mr_replay *mr_replay_from_recording(mr_recording *rec, mr_error *err);
void mr_replay_close(mr_replay **r); /* NULLs *r; accepts NULL */
int64_t mr_replay_count(const mr_replay *r);
/* Frame at position i; NULL if out of range. */
const mr_replay_frame *mr_replay_frame_at(const mr_replay *r, int64_t i);
/* Seek by frame number: the position of the first frame whose number is
 * >= index (the last position if none; 0 for index <= the first). */
int64_t mr_replay_seek_frame(const mr_replay *r, int64_t index);
/* Seek by time: the frame showing at t, i.e. the last position whose
 * timestamp is <= t (0 before the first). Timestamps are taken in file
 * order as non-decreasing, as every writer produces them. */
int64_t mr_replay_seek_time(const mr_replay *r, double t);
/* Loads the image at position i (8-bit, grey if gray else RGB). */
bool mr_replay_load_image(const mr_replay *r, int64_t i, bool gray, mr_image *img, mr_error *err);
/* The recording behind it (NULL for a plain folder). */
const mr_recording *mr_replay_recording(const mr_replay *r);
/* The camera and marker map a replay folder names, for what the caller was
 * not given: a recording's meta.json (the map is moved into *map); for a
 * plain folder a meta.json whose "camera" / "markers" (or "marker_map")
 * are inline objects or paths relative to the folder, else camera.json and
 * markers.json next to the frames. No marker map is not an error (the
 * frames may carry their poses): *have_map says whether one was found. */
bool mr_replay_meta_load(const char *dir, mr_camera *cam, bool have_cam, mr_marker_map *map, bool *have_map,
                         mr_error *err);

/* ------------------------------------------------------------- verdicts
 * verdict.c: a measured deviation judged against a tolerance.
 *
 * The tolerance is a limit deviation (±limit) that depends on the nominal
 * size, the dimension the deviation belongs to. By default DIN 18202:2019
 * Table 1, row 1 (dimensions in plan: lengths, widths, axis and grid
 * dimensions):
 *
 *   nominal size   <= 1 m   1-3 m   3-6 m   6-15 m   15-30 m   > 30 m
 *   limit          ±10 mm   ±12     ±16     ±20      ±24       ±30
 *
 * Each class includes its upper edge ("over 1 up to 3 m": 3.000 m is
 * ±12 mm, 3.001 m ±16 mm). Under 1 m the standard (since its 2013 edition)
 * gives ±10 mm in row 1; that is what applies to a nominal size of 0 to 1 m.
 * For the position of a part, DIN 18202 (4.6) measures the deviation
 * against a reference point, and the nominal size is the distance between
 * the planned point and that reference (mr_tolerances.reference, default
 * the world origin, i.e. the marker map's).
 *
 * A hall may replace the default by its own table (the file hall.json's
 * "tolerances" names):
 *   {"default_mm": 20,                      (optional; absent: DIN 18202)
 *    "layers": {"hidden": 30},              (layer name -> ±mm)
 *    "parts": {"Machine_*": 5, "Column_3": 10},   (node-name glob -> ±mm)
 *    "reference": [x, y, z]}                (optional, scene units)
 * A part rule wins over a layer rule, which wins over default_mm; the first
 * matching part glob in file order applies.
 *
 * The verdict uses the measurement's 95 % interval, deviation ± k·sigma
 * with k = 2 (sigma the 1-sigma of the deviation, the registration's
 * uncertainty included, as mr_triangulate gives it):
 *   within            |deviation| + k·sigma <= limit
 *   out of tolerance  |deviation| - k·sigma >  limit
 *   undecided         otherwise: the interval straddles the limit (measure
 *                     again, closer or from a wider baseline).
 * Deviations are in scene units taken as metres. */

#define MR_VERDICT_K 2.0             /* coverage factor of the 95 % interval */
#define MR_TOLERANCE_RULES_MAX 64

typedef enum mr_verdict_kind {
    MR_VERDICT_NONE = 0,             /* not judged */
    MR_VERDICT_WITHIN,
    MR_VERDICT_OUT,
    MR_VERDICT_UNDECIDED,
} mr_verdict_kind;

typedef struct mr_tolerance_rule {
    char pattern[96];                /* node-name glob ("parts") or layer name */
    double limit_m;                  /* ± limit, metres (> 0) */
} mr_tolerance_rule;

typedef struct mr_tolerances {
    double default_m;                /* hall-wide ± limit; 0: DIN 18202 Table 1 */
    mr_tolerance_rule parts[MR_TOLERANCE_RULES_MAX];
    int part_count;
    mr_tolerance_rule layers[MR_TOLERANCE_RULES_MAX];
    int layer_count;
    double reference[3];             /* the nominal size's reference point */
} mr_tolerances;
#define MR_TOLERANCES_DEFAULTS {0}

/* The tolerance that applies to one deviation. */
typedef struct mr_tolerance {
    double limit_m;                  /* ± limit, metres */
    double nominal_m;                /* the nominal size it was looked up for */
    char source[96];                 /* "DIN 18202 Table 1, 6-15 m", "part Machine_*", ... */
} mr_tolerance;

typedef struct mr_verdict {
    mr_verdict_kind kind;
    double deviation_m;              /* as measured (a distance: >= 0) */
    double sigma_m;                  /* its 1-sigma */
    double k;                        /* coverage factor (MR_VERDICT_K) */
    double lo_m, hi_m;               /* the 95 % interval, deviation ± k·sigma;
                                        for a deviation >= 0 (a distance) lo_m >= 0 */
    mr_tolerance tol;
} mr_verdict;

/* ------------------------------------------------------------ annotations */

/* Appends obj as one line to path durably: O_APPEND and one write (the line
 * lands whole at the end even with other writers), fsync of the file, and
 * fsync of its folder when the file is new (a new name is only durable
 * once its folder entry is), so a kill -9 right after loses nothing. */
bool mr_annotation_append(const char *path, const cJSON *obj, mr_error *err);

/* One mark as read back (the fields the exports need; `json` holds the
 * whole line for the rest). */
/* The categories a mark is filed under (the view's chooser, in its order). */
#define MR_MARK_CATEGORY_COUNT 6
extern const char *const mr_mark_categories[MR_MARK_CATEGORY_COUNT]; /* missing extra moved "wrong size" clash other */
#define MR_MARK_MAX_LABELS 8

typedef struct mr_annotation {
    char type[32];                  /* "discrepancy" */
    double time_unix;               /* when it was marked, Unix seconds; 0 unknown */
    int64_t frame_index;            /* -1 unknown */
    double timestamp;               /* the frame's time, seconds */
    /* What the planner said. Lines written before marks had a category
     * carried it as "note" (one of the six words): read back, such a note
     * becomes the category and the note is empty. */
    char id[40];                    /* the mark's identity across edits; "" (older lines): the line's own */
    int revision;                   /* 1 the first line of a mark, +1 per edit; 0 unknown */
    char category[24];              /* one of mr_mark_categories, "" none */
    char note[512];                 /* free text typed by the planner, "" none */
    char title[200];                /* "Moved: Machine_2, 0.30 m along +x" (mr_mark_title) */
    char status[24];                /* "open" (default, "" read as open), "in progress", "closed" */
    char priority[24];              /* "" none, else e.g. "low", "normal", "high" */
    char assignee[96];              /* "" none */
    char labels[MR_MARK_MAX_LABELS][32];
    int label_count;
    bool has_pixel;
    double pixel[2];                /* where it was marked, screen pixels */
    bool hit;                       /* the mark lies on the model */
    double world[3];                /* the picked point (hit only), scene units */
    double depth;                   /* distance along the view ray (hit only) */
    char node[256];                 /* picked node name, "" none */
    int32_t node_index;             /* its index in the scene, -1 none */
    char layer[16];                 /* "visible" / "hidden" / "" */
    /* The building element the mark is about (the picked node's element,
     * see mr_scene_element_of): line field "element" {guid, class, name},
     * absent when nothing was picked. */
    char element_guid[24];          /* IFC GlobalId, "" none (a model without IFC identity) */
    char element_class[48];         /* e.g. "IfcWall", "" unknown */
    char element_name[128];         /* the element's name (its node's), "" none */
    bool has_pose;                  /* pose.world_from_camera present */
    bool pose_valid;
    mr_dmat4 world_from_camera;
    int pose_tags_seen;             /* -1 unknown */
    double pose_rms_px;             /* -1 unknown */
    bool has_uncertainty;           /* "uncertainty_m" present */
    double uncertainty_m;           /* the registration's 1-σ at world (3D,
                                       scene units taken as metres) */
    bool has_measurement;           /* "measured_point" present */
    mr_measurement measurement;     /* the view's Measure (measured_* fields) */
    bool has_verdict;               /* "verdict" present: the measured distance judged */
    mr_verdict verdict;             /* against the tolerance (mr_verdict_to_json) */
    cJSON *json;                    /* the whole line (owned); NULL for one
                                       not read from a file */
} mr_annotation;

/* The line of a mark, as `mrcheck view` writes it and the reader reads it
 * back (one place for the format): type, time_unix, frame_index,
 * timestamp, id and revision (when set), category, note, title, status,
 * priority, assignee, labels (each when not empty), pixel, hit, world
 * (null when no hit), depth (hit only),
 * node (null when none; then node_index and layer), element {guid,
 * class, name} (when element_name or element_guid is set), pose {valid,
 * world_from_camera, tags_seen, rms_px}, uncertainty_m (only when
 * has_uncertainty; older lines have none), and with has_measurement
 * (the view's Measure) measured_point [x,y,z], measured_covariance
 * (9, row-major), measured_point_sigma_m, measured_angle_deg,
 * measured_rms_px, measured_frames [..], measured_pixels [[u,v]..] and,
 * when it has a distance, measured_distance_m, measured_sigma_m (the
 * distance's 1-sigma), measured_planned [x,y,z], measured_planned_node,
 * and with has_verdict "verdict" (mr_verdict_to_json's object).
 * The caller may add fields (the
 * view adds "snapshot") before mr_annotation_append. NULL when out of
 * memory. */
cJSON *mr_annotation_to_json(const mr_annotation *a);

/* The title of a mark in words, from its category, its part and (where
 * measured) its distance to the plan and the direction of the largest
 * component of that offset in scene axes: "Moved: Machine_2, 0.30 m
 * along +x", "Missing: Column_3", "Other" without a part; a judged
 * measurement adds the verdict ("..., 0.30 m along +x, out of tolerance");
 * a mark with a note but no category (written by another program) is
 * titled by its note. */
void mr_mark_title(const mr_annotation *a, char *out, size_t n);
/* The note as typed in the view, with its optional fields written inline:
 * "@name" the assignee, "#word" a label (up to MR_MARK_MAX_LABELS), "!word"
 * the priority; the rest (words joined by single spaces) is the note.
 * Fields not named in the text are left as they are. */
void mr_mark_set_note(mr_annotation *a, const char *typed);
/* A new mark id ("m" + time + counter in hex), unique within a session. */
void mr_mark_new_id(double time_unix, int counter, char *out, size_t n);

typedef struct mr_annotations {
    mr_annotation *items;
    int count;
    int bad_lines;                  /* garbage lines skipped */
    bool torn_tail;                 /* a torn last line (no newline) was ignored */
} mr_annotations;

/* Tolerant reader: a torn last line is skipped, a garbage line anywhere is
 * counted and skipped; a line is garbage if it is not a JSON object with a
 * non-empty string "type", or if a present field has the wrong shape (non-finite
 * numbers, pixel not [x,y], world not [x,y,z] or null, a non-rigid pose,
 * uncertainty_m not a number >= 0, measured_* fields of the wrong shape,
 * a verdict mr_verdict_from_json refuses).
 * Fails only when out of memory. mr_annotations_load: a missing file is
 * zero annotations. */
bool mr_annotations_parse(const char *text, size_t size, mr_annotations *out, mr_error *err);
bool mr_annotations_load(const char *path, mr_annotations *out, mr_error *err);
void mr_annotations_free(mr_annotations *a); /* zeroes it */
/* Edits and closings are new lines with the same "id" (the log stays
 * append-only): keeps, for each mark, the newest line in the place of the
 * mark's first line, and drops the lines it superseded (returns how many). */
int mr_annotations_current(mr_annotations *a);
/* The id a mark is known by: its "id", or for a line written before marks
 * had one, an id made from its time, frame and pixel (an edit of such a
 * mark carries that id, and so supersedes it). */
void mr_annotation_key(const mr_annotation *a, char *out, size_t n);
/* An edit of mark a: its line (a->json, all fields kept, those of edited
 * replacing them) with edited's category, note, status, priority,
 * assignee, labels, the revision after a's, the key as its id, a new title
 * and "edited_unix". NULL when out of memory. */
cJSON *mr_annotation_edit_line(const mr_annotation *a, const mr_annotation *edited, double time_unix);

/* -------------------------------------------------------------- capture
 * capture.c: `mrcheck view`'s capture and tracking off the render thread.
 * A reader thread (live source, or a recording replayed with mr_replay) and
 * a tracker thread (mr_tracker), with a one-frame mailbox each, newest frame
 * wins; the render thread only swaps pointers. */

/* One camera frame as the render thread gets it. */
typedef struct mr_capture_frame {
    mr_image image;           /* raw (distorted) camera frame, 8-bit, owned */
    double timestamp;         /* seconds, source clock */
    int64_t index;            /* frame number in the source */
    int64_t count;            /* frames in the source, -1 if unknown (live) */
    bool pose_valid;          /* tracking found a pose in this frame */
    bool have_pose;           /* pose holds this or an earlier good pose */
    mr_dmat4 pose;            /* filtered world_from_camera */
    int tags_seen, tags_used;
    double rms_px;            /* reprojection RMS of the pose, pixels */
    /* The covariance of the pose shown (mr_pose.cov's convention: camera
     * axes, rad then scene units), held with it while tracking is lost;
     * corner_sigma_px 0: unknown (a fixed pose, an older recording). */
    double cov[36];
    double corner_sigma_px;
    double track_ms;          /* detection + pose + filter for this frame */
    uint64_t seq;             /* increases with every published frame */
} mr_capture_frame;

typedef enum mr_capture_status {
    MR_CAPTURE_STARTING = 0,
    MR_CAPTURE_RUNNING,
    MR_CAPTURE_NO_CAMERA,             /* cannot open the input; retrying */
    MR_CAPTURE_ENDED,                 /* the video or recording ran out */
} mr_capture_status;

typedef struct mr_capture_params {
    const char *input;        /* /dev/videoN, a video file, an image or a folder */
    const char *replay_dir;   /* or a recording folder (frames/ + poses) */
    const mr_camera *camera;  /* intrinsics of the raw frames (required) */
    const mr_marker_map *markers; /* for tracking; NULL: poses must come from
                                     the recording or fixed_pose */
    const mr_dmat4 *fixed_pose; /* a still with a known view: no tracking */
    bool retrack;             /* replay: detect and solve again instead of
                                 using the recorded poses */
    bool start_paused;        /* replay: start paused on the first frame
                                 (nothing is read past it until asked) */
    double retry_s;           /* between attempts to reopen a lost camera */
    void (*wake)(void *ctx);  /* called after a new frame is published */
    void *wake_ctx;
} mr_capture_params;

typedef struct mr_capture mr_capture;

mr_capture *mr_capture_start(const mr_capture_params *p, mr_error *err);
void mr_capture_stop(mr_capture **c);
/* Swaps in the newest frame if it is newer than f->seq (f->image is reused).
 * Returns true if f changed. */
bool mr_capture_latest(mr_capture *c, mr_capture_frame *f);
void mr_capture_frame_free(mr_capture_frame *f);
mr_capture_status mr_capture_state(mr_capture *c, char *msg, size_t n);
/* "starting", "running", "no_camera", "ended" (the view's state snapshot). */
const char *mr_capture_status_name(mr_capture_status st);
bool mr_capture_seekable(mr_capture *c);   /* replay: seek, step, rate */
/* Replay controls (ignored for live input). */
void mr_capture_play(mr_capture *c, bool playing);
bool mr_capture_playing(mr_capture *c);
void mr_capture_step(mr_capture *c, int delta);
void mr_capture_seek(mr_capture *c, int64_t index);
void mr_capture_rate(mr_capture *c, double rate);
/* Freeze: the reader pauses (replay) and the pose filter holds its pose. */
void mr_capture_freeze(mr_capture *c, bool frozen);
/* Totals for --stats: frames read, frames tracked, frames dropped because a
 * newer one arrived first (newest wins), tracking time sum in ms. */
void mr_capture_counts(mr_capture *c, int64_t *read, int64_t *tracked, int64_t *dropped, double *track_ms_sum);

/* ------------------------------------------------------------ snapshots
 * snapshot.c: what the view writes when the planner freezes a picture or
 * marks a discrepancy. */

typedef struct mr_snapshot {
    const mr_image *screen;          /* required: the picture as shown */
    const mr_capture_frame *frame;   /* the camera frame it was drawn from, or NULL */
    const mr_camera *camera;         /* required */
    double alpha;                    /* the video transparency it was shown with */
    const char *passes;              /* the frame's pass list, or NULL */
} mr_snapshot;

/* session_dir/snapshots/<stem>_screen.png, <stem>_frame.png (when the frame
 * has an image) and <stem>.json ({camera, frame_index, timestamp, pose,
 * alpha, passes}; pose as in annotation lines), each written atomically.
 * rel (may be NULL) gets "screen", "frame" and "pose": the written paths
 * relative to session_dir, for an annotation line to point at. */
bool mr_snapshot_write(const char *session_dir, const char *stem, const mr_snapshot *s, cJSON *rel, mr_error *err);
/* The next "<prefix>_NNNN" (counting on from *counter, which it advances)
 * whose <stem>.json no earlier session wrote, into stem: never overwrite. */
void mr_snapshot_next_stem(const char *session_dir, const char *prefix, int *counter, char *stem, size_t n);

/* ----------------------------------------------- the view's marks (mark.c) */

/* A deep copy of src (its image too) into dst, whose image is freed first;
 * false + err (dst without an image) when out of memory. */
bool mr_capture_frame_copy(mr_capture_frame *dst, const mr_capture_frame *src, mr_error *err);
/* A "discrepancy" annotation of a mark made on frame f, filed under
 * category (revision 1): the frame's index, time and pose; the rest zero
 * (node_index -1) for the caller to fill (id, note, pixel, pick,
 * uncertainty, measurement, title). */
void mr_annotation_from_frame(mr_annotation *m, const mr_capture_frame *f, const char *category, double time_unix);
/* A finished mark's files: the snapshot (sn) as session_dir/snapshots/<stem>_*
 * and line, with the snapshot's paths under "snapshot", appended to
 * session_dir/annotations.jsonl. The line is written even when the snapshot
 * fails (*snapshot_ok false, snapshot_err says why): the mark matters more.
 * False + err when the line could not be saved. */
bool mr_mark_save(const char *session_dir, const char *stem, cJSON *line, const mr_snapshot *sn, bool *snapshot_ok,
                  mr_error *snapshot_err, mr_error *err);

/* ------------------------------------------------- verdicts (verdict.c)
 * The rule and the types are above, before the annotations that carry a
 * verdict. */

/* DIN 18202 Table 1 row 1's limit for a nominal size (metres, >= 0; a
 * negative or non-finite size gives NAN); *cls (may be NULL) gets the
 * class's words ("6-15 m"). */
double mr_din18202_limit_m(double nominal_m, const char **cls);
/* Parses a tolerance table (format above) into t (defaults first). Unknown
 * keys are warned about with the nearest known key; a limit that is not a
 * positive number is an error. */
bool mr_tolerances_from_json(const cJSON *obj, mr_tolerances *t, mr_error *err);
bool mr_tolerances_load(const char *path, mr_tolerances *t, mr_error *err);
/* The tolerance for a deviation of part (node name, may be NULL or "") on
 * layer ("visible" / "hidden", may be NULL) at nominal size nominal_m;
 * t NULL: DIN 18202. */
mr_tolerance mr_tolerance_lookup(const mr_tolerances *t, const char *part, const char *layer, double nominal_m);
/* The nominal size of a planned point: its distance from t's reference
 * (the origin if t is NULL). */
double mr_tolerance_nominal(const mr_tolerances *t, const double planned[3]);
/* Judges deviation_m ± MR_VERDICT_K·sigma_m against tol. False + err for a
 * non-finite deviation, a negative or non-finite sigma or a limit <= 0. */
bool mr_verdict_judge(double deviation_m, double sigma_m, const mr_tolerance *tol, mr_verdict *out, mr_error *err);
/* The whole rule for one measured distance: the tolerance for part / layer
 * (either may be NULL) at the nominal size of planned (its distance from
 * t's reference; nominal_m >= 0 overrides it), then the verdict. t NULL:
 * DIN 18202. */
bool mr_verdict_measure(const mr_tolerances *t, const char *part, const char *layer, const double planned[3],
                        double nominal_m, double deviation_m, double sigma_m, mr_verdict *out, mr_error *err);
/* "within", "out", "undecided" (JSON), and the planner's words: "within
 * tolerance", "out of tolerance", "undecided". "" for NONE. */
const char *mr_verdict_key(mr_verdict_kind k);
const char *mr_verdict_words(mr_verdict_kind k);
/* One line: "out of tolerance: 300.2 mm, 95 % interval 290.0 .. 310.4 mm,
 * limit ±20 mm (DIN 18202 Table 1, 6-15 m)". */
void mr_verdict_format(const mr_verdict *v, char *buf, size_t n);
/* {"verdict", "deviation_mm", "sigma_mm", "k", "interval_mm": [lo, hi],
 *  "limit_mm", "nominal_m", "tolerance"}; and back (false + err when a
 * field is missing or of the wrong kind). */
cJSON *mr_verdict_to_json(const mr_verdict *v);
bool mr_verdict_from_json(const cJSON *obj, mr_verdict *v, mr_error *err);

/* ------------------------------------------------------------ the hall
 * hall.c: one folder that holds what a check needs, named by a small
 * manifest, HALL/hall.json (paths relative to the folder):
 *
 *   {"mrcheck_hall": 1,
 *    "name": "Hall 3",                     (optional, for people)
 *    "scene": "../plan/hall3.json",        the plan: glTF/GLB, IFC or a scene config
 *    "camera": "camera.json",              the tablet camera (mrcheck calibrate)
 *    "markers": "markers.json",            the marker map (mrcheck map)
 *    "control": "control.json",            surveyed control points (optional)
 *    "tolerances": "tolerances.json",      the tolerance table (optional;
 *                                          absent: DIN 18202 Table 1)
 *    "input": "/dev/video0",               the live camera (default /dev/video0)
 *    "sessions": "sessions"}               recordings and marks, one folder each
 *
 * Adding a file checks it first (it must load as what it is named for). The
 * small files (camera, markers, control, tolerances) are copied into the
 * folder under those names, so the hall keeps its own calibration and map
 * and a later calibration replaces them in place; the plan is referenced
 * by a path relative to the folder (a plan is big, and a scene config
 * points at further files beside it). Unknown keys are warned about with
 * the nearest known key; keys starting with '_' are notes. */

typedef enum mr_hall_item {
    MR_HALL_SCENE = 0,
    MR_HALL_CAMERA,
    MR_HALL_MARKERS,
    MR_HALL_CONTROL,
    MR_HALL_TOLERANCES,
    MR_HALL_ITEM_COUNT
} mr_hall_item;
/* The manifest keys (and command-line flags) of the items, by item:
 * "scene", "camera", "markers", "control", "tolerances". */
extern const char *const mr_hall_item_keys[MR_HALL_ITEM_COUNT];
#define MR_HALL_MANIFEST "hall.json"
#define MR_HALL_DEFAULT_INPUT "/dev/video0"
#define MR_HALL_DEFAULT_SESSIONS "sessions"

typedef struct mr_hall {
    char dir[1024];                        /* the folder as given (relative to the working directory) */
    char items[MR_HALL_ITEM_COUNT][1024];  /* as in the manifest (relative to dir, or absolute); "" not set */
    char name[128];                        /* "" none */
    char input[256];                       /* the live camera; "" none (MR_HALL_DEFAULT_INPUT applies) */
    char sessions[1024];                   /* relative to dir; MR_HALL_DEFAULT_SESSIONS when not set */
} mr_hall;

/* True if dir holds a hall.json. */
bool mr_hall_is(const char *dir);
/* Reads dir/hall.json. false + err (one line naming the file) when it is
 * missing, not JSON, or a known key has the wrong type. */
bool mr_hall_load(const char *dir, mr_hall *h, mr_error *err);
/* An item's file as a path from the working directory (dir joined with
 * the manifest's path); false (out "") when the hall names none. */
bool mr_hall_path(const mr_hall *h, mr_hall_item item, char *out, size_t n);
/* The sessions folder from the working directory. */
void mr_hall_sessions_dir(const mr_hall *h, char *out, size_t n);
/* A session named on a command line: an existing path as given, else
 * HALL/sessions/NAME, else HALL/NAME when either exists; else name as given
 * (the command then says what is missing). */
void mr_hall_session_resolve(const mr_hall *h, const char *name, char *out, size_t n);
/* True if path lies inside the hall folder (after resolving links). */
bool mr_hall_contains(const mr_hall *h, const char *path);
/* A new session folder's path (not created): HALL/sessions/PREFIXYYYYmmdd-
 * HHMMSS (local time of t_unix), with "-2", "-3", ... if taken. */
void mr_hall_new_session(const mr_hall *h, const char *prefix, double t_unix, char *out, size_t n);

/* Loads a plan to check it (the scene loader lives above lib/session). */
typedef bool (*mr_hall_scene_check_fn)(void *user, const char *path, mr_error *err);
/* What hall init / add set: each file given replaces the hall's. */
typedef struct mr_hall_update {
    const char *files[MR_HALL_ITEM_COUNT]; /* paths from the working directory; NULL: keep */
    const char *input;                     /* NULL: keep */
    const char *name;                      /* NULL: keep */
    mr_hall_scene_check_fn check_scene;    /* required when a scene is given */
    void *check_user;
} mr_hall_update;
#define MR_HALL_UPDATE_DEFAULTS {{NULL}, NULL, NULL, NULL, NULL}
/* Checks path as the file of item (scene: through check). false + err
 * naming the file and what is wrong. */
bool mr_hall_check_file(mr_hall_item item, const char *path, mr_hall_scene_check_fn check, void *user, mr_error *err);
/* hall init (create true: the folder may be new; a new hall needs a scene)
 * and hall add (create false: dir must be a hall). Every given file is
 * checked before anything is written; then the small files are copied in
 * and hall.json is written (each atomically), keeping the manifest's
 * other keys. *out (may be NULL) gets the hall as written. */
bool mr_hall_update_files(const char *dir, const mr_hall_update *u, bool create, mr_hall *out, mr_error *err);
/* Prints the hall, each file checked ("  camera      camera.json: ok" or
 * what is wrong), the live input and the sessions folder, to out; returns
 * the number of files that do not load. */
int mr_hall_print(const mr_hall *h, mr_hall_scene_check_fn check, void *user, FILE *out);
/* Writes a new hall.json for dir naming the given items' paths as they are
 * (relative to dir, not checked, nothing copied): for programs that write
 * a hall's files themselves (mrcheck demo). */
bool mr_hall_write_manifest(const char *dir, const char *const items[MR_HALL_ITEM_COUNT], const char *name,
                            mr_error *err);

/* ------------------------------------------- a hall on any command line
 * hall_args.c: `mrcheck CMD HALL ...` (HALL: the first argument, a folder
 * with hall.json) or `mrcheck CMD ... --hall HALL` stands for the files the
 * hall names: each flag of the command's row that was not given is added
 * from the manifest, a session argument is looked up in the hall's
 * sessions, and an output not given goes inside the hall. */
typedef struct mr_hall_args {
    int argc;
    char **argv;                /* the command line to run (owned) */
    bool have_hall;
    mr_hall hall;
    int update_item;            /* after a successful run: record this file
                                   in the manifest (-1 none) */
    char update_path[1024];
    char *pool[24];             /* strings argv points at (owned) */
    int pool_count;
} mr_hall_args;
/* Expands argv (argv[1] the command) into a; a command without a hall on
 * its line is passed through unchanged. false + err on a bad hall (the
 * caller prints one line). */
bool mr_hall_args_expand(int argc, char **argv, mr_hall_args *a, mr_error *err);
/* The help section of a command that takes a hall (NULL if it takes none). */
const char *mr_hall_args_help(const char *cmd);
/* Called with the command's exit status: records the file the command
 * wrote into the hall (map, calibrate) when it succeeded. false + err if
 * the manifest could not be written. */
bool mr_hall_args_finish(mr_hall_args *a, int rc, mr_error *err);
void mr_hall_args_free(mr_hall_args *a);
/* Runs a command (argv[1] its name) with its hall expanded: a bad hall is
 * one line and exit status 2; --help adds mr_hall_args_help; after a
 * successful run the file it wrote into the hall is named in hall.json.
 * Returns the command's exit status. */
int mr_hall_run(int (*cmd)(int argc, char **argv), int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
