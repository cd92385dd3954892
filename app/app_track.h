/* Private to app/: the tracking commands (track, record, replay, synth,
 * calibrate, bench tracking) and what they share. Kept apart from app.h so
 * the tracking work merges without touching the foundation's header. */
#ifndef MR_APP_TRACK_H
#define MR_APP_TRACK_H

#include "app.h"
#include "mr_session.h"
#include "mr_track.h"

/* The input, camera, marker and filter options every tracking command
 * takes; the detector's numbers come with APP_TRACK_TABLE. */
#define APP_TRACK_OPTS                                                                                  \
    {"camera", "CAMERA.json", "camera intrinsics (default: the recording's, if the input is one)", NULL}, \
    {"markers", "MARKERS.json", "marker map (default: the recording's, if the input is one)", NULL},      \
    {"family", "F", "tag family (default: the marker map's, else tag36h11)", NULL},                       \
    {"no-filter", NULL, "no One Euro filtering of the pose", NULL},                                       \
    {"freeze", NULL, "freeze the filtered pose at the first valid one (still-image check)", NULL},     \
    {"size", "WxH", "V4L2: requested frame size (default 1280x720)", NULL},                               \
    {"fps", "F", "V4L2: requested frame rate; image folders: timestamp rate (default 30)", NULL},          \
    {"pixel-format", "YUYV|MJPG", "V4L2: pixel format (default: YUYV if offered, else MJPG)", NULL}

/* The detector rows (--decimate, --threads, --refine-edges, --sharpening)
 * from mr_detector_opts, parsed into *dp (an mr_detector_params holding its
 * defaults) by mr_cli_parse_tables. */
#define APP_TRACK_TABLE(dp) {.prefix = "", .table = mr_detector_opts, .params = (dp), .research = true}

/* A command's tracker: the one mr_tracker (lib/track) set up from the
 * options, plus what was loaded for it. */
typedef struct app_tracker {
    mr_tracker *tracker;
    bool has_camera, has_markers; /* both: poses are solved */
    const mr_camera *camera;      /* the tracker's copies (NULL if none) */
    const mr_marker_map *markers;
} app_tracker;

/* The input: a recording folder (its camera and markers become defaults),
 * /dev/videoN, a video file, an image or a folder of images. */
mr_source *app_open_input(const char *uri, bool gray, mr_recording **rec_info, mr_error *err);
/* The same with --size/--fps/--pixel-format from opts (false: a bad value,
 * already reported; *src NULL + err: the input could not be opened). */
bool app_open_input_opts(const char *cmd, const mr_cli_opt *opts, bool gray, mr_recording **rec_info, mr_source **src,
                         mr_error *err);

/* Sets up the tracker from the options and the detector params parsed from
 * APP_TRACK_TABLE (--family fills in its family); rec (may be NULL)
 * supplies the camera and markers by default. Prints one line and returns
 * false on error. */
bool app_tracker_init(app_tracker *t, const char *cmd, const mr_cli_opt *opts, const mr_detector_params *dp,
                      const mr_recording *rec);
void app_tracker_free(app_tracker *t);

int cmd_track(int argc, char **argv);
int cmd_record(int argc, char **argv);
int cmd_replay(int argc, char **argv);
int cmd_synth(int argc, char **argv);
int cmd_calibrate(int argc, char **argv);
int cmd_map(int argc, char **argv);
int cmd_measure(int argc, char **argv);
int bench_tracking(int argc, char **argv);

#endif
