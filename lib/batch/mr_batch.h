/* mr_batch.h — headless runs of the libraries over a whole recording: what
 * `mrcheck replay` does, as library code with a params struct and an option
 * table, so the command is argument parsing and one call.
 *
 * Depends on: lib/render (the frame), lib/scene, lib/session (recordings),
 * lib/eval (the median),
 * lib/track (the video writer), lib/core. Nothing below includes it.
 */
#ifndef MR_BATCH_H
#define MR_BATCH_H

#include "mr_core.h"
#include "mr_render.h"
#include "mr_scene.h"
#include "mr_session.h"
#include "mr_track.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Overlays of a recording's frames with the planned model at their
 * recorded poses: out_dir/overlay_NNNNNN.png per selected frame (the camera
 * frame alone where the frame has no pose, so the sequence stays complete),
 * out_dir/replay.jsonl ({"frame", "t", "image", "overlay",
 * "world_from_camera"} per written image, written atomically at the end),
 * The folder must be new or empty unless force. A stop (SIGINT/SIGTERM,
 * mr_stop_requested) ends the run at the next frame, a failure at the
 * frame that failed; either way replay.jsonl then lists exactly the images
 * written so far (and the video holds them), or, if none was, the folder
 * this run made is removed again. A stop returns false with
 * MR_ERR_INTERRUPTED and the summary in err.
 * and optionally a Motion-JPEG AVI at the recording's median frame rate
 * divided by `every` (no half-written video after a failure).
 * Deterministic: the same recording gives the same images. */

/* A caller's own output per frame in place of the overlay (the multi-view
 * rig: a quilt and its views): called for each selected frame with a pose,
 * with the frame's view and depth cues; writes its files under out_dir and
 * puts the name replay.jsonl lists into name. Frames without a pose are
 * then listed as "-" and nothing is written for them. */
typedef bool (*mr_batch_replay_render_fn)(void *user, mr_renderer *r, const mr_view *view, const mr_frame_params *fp,
                                          int64_t index, char *name, size_t name_n, mr_error *err);

typedef struct mr_batch_replay_params {
    const mr_recording *recording; /* required (mr_recording_open) */
    const char *out_dir;        /* required; created */
    const char *video_path;     /* the AVI, or NULL */
    mr_frame_params frame;      /* depth cues (AO, ghosting, ...), frame.alpha (--alpha); the video is set per frame */
    int every;                  /* every Nth frame counted from `from`; default 1 */
    int from;                   /* first frame number; default 0 */
    int to;                     /* last frame number; < 0 (the default): the last */
    bool raw;                   /* the raw pose, not the filtered one */
    bool progress;              /* "replay: frame N (i/n)" on a terminal */
    bool force;                 /* write into a folder that already holds files (else refused) */
    mr_batch_replay_render_fn render; /* NULL: the overlay PNG (and the AVI) */
    void *render_user;
    /* --views / --quilt: per frame a quilt overlay_NNNNNN_qs..png and its
     * views in overlay_NNNNNN/ (mr_render_rig_files) instead of the overlay;
     * the camera frame is seen from one eye only, so the views show the
     * plan alone; the first frame's focal distance is kept. NULL: none. */
    const mr_rig_params *rig;
    const mr_quilt *quilt;      /* with rig */
    const mr_lod *lod;          /* the scene's levels of detail (built for it), or NULL: full detail */
    const mr_hlod *hlod;        /* levels above the part, built from lod, or NULL: none */
} mr_batch_replay_params;
#define MR_BATCH_REPLAY_DEFAULTS                                                                   \
    {.frame = MR_FRAME_DEFAULTS, .every = 1, .from = 0, .to = -1}
/* alpha, every, from, to, raw. */
extern const mr_opt mr_batch_replay_opts[];

typedef struct mr_batch_replay_stats {
    int overlays;               /* frames rendered with the model */
    int plain;                  /* frames written without a pose (camera frame only) */
    uint64_t triangles;         /* submitted, summed over the overlays (a rig's: its last draw per frame) */
    uint64_t lod_instances;     /* instances drawn at a simplified level, summed likewise */
    int written;                /* images listed in replay.jsonl */
    int64_t last_frame;         /* the last one written */
    bool interrupted;           /* stopped by mr_stop_requested() */
} mr_batch_replay_stats;

/* The checks that need neither the recording nor a GPU: a folder is given
 * and new or empty (or force), to is not before from. False + one line in
 * err. */
bool mr_batch_replay_check(const mr_batch_replay_params *p, mr_error *err);
/* Sets scene on r, renders, and leaves no scene set. A frame whose image
 * cannot be read is skipped with a warning on stderr; no frame in the
 * range or a failed write: false + err. */
bool mr_batch_replay(const mr_batch_replay_params *p, mr_renderer *r, const mr_scene *scene,
                     mr_batch_replay_stats *stats, mr_error *err);

/* `mrcheck measure` (measure.c): the feature tapped in the recording's
 * frames (observations: mr_observations_load) triangulated with the taps'
 * noise and each frame's pose covariance; its distance to the planned point
 * and, with a scene, to the planned surface's nearest point (lib/eval), in
 * mm with its 1-sigma uncertainty, each with its verdict against the
 * tolerance. Report lines on out; with out_json also the result as JSON. */
typedef struct mr_batch_measure_params {
    const char *recording;    /* folder, required */
    const char *observations; /* OBS.json, required */
    const char *scene;        /* the plan; NULL: no surface distance */
    const char *tolerances;   /* T.json; NULL: DIN 18202 Table 1 by nominal size */
    double nominal;           /* m; < 0 (default): the planned point's distance from the table's reference point */
    const char *part;         /* the planned point's part (its tolerance); NULL: none */
    const char *out_json;     /* NULL: no file */
    mr_triangulate_params triangulate;
    FILE *out;                /* required */
} mr_batch_measure_params;
#define MR_BATCH_MEASURE_DEFAULTS {.nominal = -1, .triangulate = MR_TRIANGULATE_DEFAULTS}
bool mr_batch_measure(const mr_batch_measure_params *p, mr_error *err);

/* `mrcheck track` (track.c): the tracker over the source's frames. A frame
 * the tracker refuses is skipped with a warning on stderr. With the
 * tracker's camera and markers each frame has a pose line
 * (mr_pose_line_json): on lines, or into out (written atomically when the
 * run ends); print_detections puts {"frame","detections"[,"pose"]} per
 * frame on lines instead. A stop (mr_stop_requested) ends the run at the
 * next frame and returns true with stats->interrupted. False + one line:
 * no frames, no frame processed, --out without camera and markers, a read
 * or write failure. */
typedef struct mr_batch_track_params {
    mr_source *source;        /* required */
    mr_tracker *tracker;      /* required */
    const char *input;        /* its name, for messages */
    const char *out;          /* poses.jsonl; NULL: pose lines on `lines` */
    bool print_detections;
    long max_frames;          /* < 0 (default): all */
    bool progress;            /* "track: frame N" on a terminal */
    bool summary;             /* the counts as one line on stderr at the end */
    FILE *lines;              /* required (stdout) */
} mr_batch_track_params;
#define MR_BATCH_TRACK_DEFAULTS {.max_frames = -1}
typedef struct mr_batch_track_stats {
    long frames, failed, with_tags, with_pose;
    bool interrupted;
} mr_batch_track_stats;
bool mr_batch_track(const mr_batch_track_params *p, mr_batch_track_stats *stats, mr_error *err);

#ifdef __cplusplus
}
#endif
#endif
