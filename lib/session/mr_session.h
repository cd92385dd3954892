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

#ifdef __cplusplus
}
#endif
#endif
