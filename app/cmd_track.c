/* mrcheck track: detection and pose per frame. */
#include "app_track.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
    const char *out = mr_cli_get(opts, "out");
    bool print_det = mr_cli_flag(opts, "print-detections");

    mr_error err = {0};
    mr_recording *rec = NULL;
    mr_source *src = NULL;
    if (!app_open_input_opts(cmd, opts, true, &rec, &src, &err)) return 2;
    if (!src) return mr_cli_error(cmd, &err);
    app_tracker t;
    bool ok = app_tracker_init(&t, cmd, opts, &dp, rec);
    mr_recording_close(&rec);
    if (!ok) {
        mr_source_close(&src);
        return 1;
    }
    bool want_pose = t.has_camera && t.has_markers;
    if (out && !want_pose) {
        app_tracker_free(&t);
        mr_source_close(&src);
        return mr_cli_errorf(cmd, "--out needs --camera and --markers (or a recording as input)");
    }
    mr_stop_catch();
    mr_jsonl poses = {0};
    long frames = 0, failed = 0, with_tags = 0, with_pose = 0;
    int rc = 0;
    /* The first bad frame's message is held back: if no frame at all can be
     * processed (a single tiny image, say) it becomes the one error line. */
    char held[600] = "";
    const bool tty = isatty(2) && mr_log_get_level() >= MR_LOG_WARN;
    double shown = mr_time_now();
    while (!mr_stop_requested() && (max_frames < 0 || frames < max_frames)) {
        mr_frame f;
        mr_read_status st = mr_source_read(src, &f, &err);
        if (st == MR_READ_END) break;
        if (st == MR_READ_ERROR) {
            rc = mr_cli_error(cmd, &err);
            break;
        }
        frames++;
        if (tty && mr_time_now() - shown > 0.25) {
            fprintf(stderr, "\rtrack: frame %lld, %ld with a pose", (long long)f.index, with_pose);
            shown = mr_time_now();
        }
        mr_tracker_result r;
        mr_error fe = {0};
        if (!mr_tracker_frame(t.tracker, &f.image, f.timestamp, &r, &fe)) {
            /* One bad frame (too small, broken) does not end the run. */
            if (failed == 0 && frames == 1) snprintf(held, sizeof held, "frame %lld: %s", (long long)f.index, fe.msg);
            else fprintf(stderr, "mrcheck: track: warning: frame %lld: %s\n", (long long)f.index, fe.msg);
            failed++;
            continue;
        }
        if (held[0]) {
            fprintf(stderr, "mrcheck: track: warning: %s\n", held);
            held[0] = 0;
        }
        with_tags += r.detection_count > 0;
        with_pose += r.pose.valid;
        if (print_det) {
            cJSON *o = cJSON_CreateObject();
            cJSON_AddNumberToObject(o, "frame", (double)f.index);
            cJSON_AddItemToObject(o, "detections", mr_detections_json(r.detections, r.detection_count, 1e-3));
            /* with camera and markers the line also carries the pose */
            if (want_pose) cJSON_AddItemToObject(o, "pose", mr_pose_line_json(f.index, f.timestamp, &r));
            char *s = cJSON_PrintUnformatted(o);
            cJSON_Delete(o);
            if (s) puts(s);
            free(s);
        }
        if (want_pose) {
            cJSON *o = mr_pose_line_json(f.index, f.timestamp, &r);
            char *s = out || print_det ? NULL : cJSON_PrintUnformatted(o);
            bool added = !out || mr_jsonl_add(&poses, o);
            cJSON_Delete(o);
            if (!added || (!out && !print_det && !s)) {
                free(s);
                rc = mr_cli_errorf(cmd, "out of memory");
                break;
            }
            if (s) puts(s);
            free(s);
        }
        fflush(stdout);
    }
    if (rc == 0 && frames == 0) rc = mr_cli_errorf(cmd, "%s: no frames", input);
    else if (rc == 0 && failed == frames)
        rc = mr_cli_errorf(cmd, "no frame could be processed (%ld failed; %s)", failed, held[0] ? held : "see above");
    if (tty) fprintf(stderr, "\r\033[K");
    if (rc == 0 && out && !mr_jsonl_save(&poses, out, &err)) rc = mr_cli_error(cmd, &err);
    if (rc == 0 && mr_log_get_level() >= MR_LOG_WARN) /* the summary, on stderr: stdout may be the poses */
        fprintf(stderr, "track: %s%ld frames, %ld with tags, %ld with a pose, %ld failed%s%s\n",
                mr_stop_requested() ? "interrupted after " : "", frames, with_tags, with_pose, failed,
                out ? "; wrote " : "", out ? out : "");
    if (rc == 0 && mr_stop_requested()) rc = 128 + mr_stop_signal();
    mr_jsonl_free(&poses);
    app_tracker_free(&t);
    mr_source_close(&src);
    return rc;
}
