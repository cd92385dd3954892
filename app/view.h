/* Private to `mrcheck view`: the capture/tracking threads, the replay
 * index, and the session files (settings, annotations, snapshots). */
#ifndef MR_VIEW_H
#define MR_VIEW_H

#include "app.h"
#include "mr_track.h"

/* One camera frame as the render thread gets it. */
typedef struct vw_frame {
    mr_image image;           /* raw (distorted) camera frame, 8-bit, owned */
    double timestamp;         /* seconds, source clock */
    int64_t index;            /* frame number in the source */
    int64_t count;            /* frames in the source, -1 if unknown (live) */
    bool pose_valid;          /* tracking found a pose in this frame */
    bool have_pose;           /* pose holds this or an earlier good pose */
    mr_dmat4 pose;            /* filtered world_from_camera */
    int tags_seen, tags_used;
    double rms_px;            /* reprojection RMS of the pose, pixels */
    double track_ms;          /* detection + pose + filter for this frame */
    uint64_t seq;             /* increases with every published frame */
} vw_frame;

typedef enum vw_state {
    VW_STARTING = 0,
    VW_RUNNING,
    VW_NO_CAMERA,             /* cannot open the input; retrying */
    VW_ENDED,                 /* the video or recording ran out */
} vw_state;

typedef struct vw_capture_params {
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
} vw_capture_params;

typedef struct vw_capture vw_capture;

vw_capture *vw_capture_start(const vw_capture_params *p, mr_error *err);
void vw_capture_stop(vw_capture **c);
/* Swaps in the newest frame if it is newer than f->seq (f->image is reused).
 * Returns true if f changed. */
bool vw_capture_latest(vw_capture *c, vw_frame *f);
void vw_frame_free(vw_frame *f);
vw_state vw_capture_state(vw_capture *c, char *msg, size_t n);
bool vw_capture_seekable(vw_capture *c);   /* replay: seek, step, rate */
/* Replay controls (ignored for live input). */
void vw_capture_play(vw_capture *c, bool playing);
bool vw_capture_playing(vw_capture *c);
void vw_capture_step(vw_capture *c, int delta);
void vw_capture_seek(vw_capture *c, int64_t index);
void vw_capture_rate(vw_capture *c, double rate);
/* Freeze: the reader pauses (replay) and the pose filter holds its pose. */
void vw_capture_freeze(vw_capture *c, bool frozen);
/* Totals for --stats: frames read, frames tracked, frames dropped because a
 * newer one arrived first (newest wins), tracking time sum in ms. */
void vw_capture_counts(vw_capture *c, int64_t *read, int64_t *tracked, int64_t *dropped, double *track_ms_sum);

/* Appends one JSON line to path durably: mr_annotation_append (lib/session),
 * kept under this name for the view's callers. */
bool vw_append_line(const char *path, const cJSON *obj, mr_error *err);

#endif
