/* mrcheck track: detection and pose per frame. */
#include "app_track.h"
#include "mr_batch.h"

int cmd_track(int argc, char **argv) {
    static const char *cmd = "track";
    mr_cli_opt opts[] = {
        {"input", "PATH", "recording folder, /dev/videoN, video file, image or folder of images", NULL},
        APP_TRACK_OPTS,
        {"out", "POSES.jsonl", "write one pose line per frame there (written when the run ends)", NULL},
        {"print-detections", NULL, "print {\"frame\",\"detections\"} per frame on stdout", NULL},
        {"max-frames", "N", "stop after N frames", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    mr_cli_table tables[] = {APP_TRACK_TABLE(&dp)};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, tables, 1, NULL, 0, NULL,
                   "usage: mrcheck track --input PATH|/dev/videoN [--camera C] [--markers M] [--family F] [--decimate D]\n"
                   "                     [--threads N] [--refine-edges 0|1] [--out poses.jsonl] [--print-detections]\n"
                   "Detects AprilTags per frame (corners in pixels, OpenCV convention: centre of the top-left pixel\n"
                   "is (0,0)); with a camera and a marker map also the pose world_from_camera (OpenCV axes).",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *input = mr_cli_get(opts, "input");
    if (!input) return mr_cli_errorf(cmd, "--input is required (see --help)"), 2;
    long max_frames = -1;
    if (mr_cli_get(opts, "max-frames") && !mr_cli_int("max-frames", mr_cli_get(opts, "max-frames"), 1, 1L << 40, &max_frames))
        return 2;
    mr_error err = {0};
    mr_recording *rec = NULL;
    mr_source *src = NULL;
    if (!app_open_input_opts(cmd, opts, true, &rec, &src, &err)) return 2;
    if (!src) return mr_cli_error(cmd, &err);
    app_tracker t;
    bool ok = app_tracker_init(&t, cmd, opts, &dp, rec);
    mr_recording_close(&rec);
    mr_batch_track_params p = MR_BATCH_TRACK_DEFAULTS;
    p.source = src;
    p.tracker = t.tracker;
    p.input = input;
    p.out = mr_cli_get(opts, "out");
    p.print_detections = mr_cli_flag(opts, "print-detections");
    p.max_frames = max_frames;
    p.progress = p.summary = mr_log_get_level() >= MR_LOG_WARN;
    p.lines = stdout;
    mr_batch_track_stats st;
    mr_stop_catch();
    int rc = !ok ? 1 : !mr_batch_track(&p, &st, &err) ? mr_cli_error(cmd, &err) : st.interrupted ? 128 + mr_stop_signal() : 0;
    app_tracker_free(&t);
    mr_source_close(&src);
    return rc;
}
