/* mrcheck record: tracks a live camera or a video and writes a recording as
 * it goes (crash-safe: see lib/session/mr_session.h). */
#include "app_track.h"

#include <string.h>
#include <time.h>

static void sleep_until(double t_target) {
    double now = mr_time_now();
    if (t_target <= now) return;
    double d = t_target - now;
    struct timespec ts = {(time_t)d, (long)((d - (double)(time_t)d) * 1e9)};
    nanosleep(&ts, NULL);
}

int cmd_record(int argc, char **argv) {
    static const char *cmd = "record";
    mr_cli_opt opts[] = {
        {"input", "DEV|VIDEO", "/dev/videoN, a video file, images, or a recording", NULL},
        {"out", "DIR", "recording folder to create (an existing recording is never overwritten)", NULL},
        APP_TRACK_OPTS,
        {"max-frames", "N", "stop after N frames (default: until the input ends or Ctrl-C)", NULL},
        {"rate", "FPS", "pace file inputs at this rate, as a live camera would deliver them", NULL},
        {"gray", NULL, "store grey frames (smaller)", NULL},
        {"png", NULL, "store lossless PNG frames instead of JPEG", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    mr_recorder_params rp = MR_RECORDER_DEFAULTS;
    mr_cli_table tables[] = {APP_TRACK_TABLE(&dp), {.prefix = "", .table = mr_recorder_opts, .params = &rp}};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, tables, 2, NULL, 0, NULL,
                   "usage: mrcheck record --input /dev/videoN|VIDEO --camera C --markers M --out DIR\n"
                   "Writes meta.json, frames/NNNNNN.jpg and frames.jsonl (detections, raw and filtered pose,\n"
                   "quality) as it goes; every line is flushed and synced, so a crash loses at most one frame.",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *input = mr_cli_get(opts, "input"), *out = mr_cli_get(opts, "out");
    if (!input || !out) return mr_cli_errorf(cmd, "--input and --out are required (see --help)"), 2;
    long max_frames = -1;
    double rate = 0;
    if (mr_cli_get(opts, "max-frames") && !mr_cli_int("max-frames", mr_cli_get(opts, "max-frames"), 1, 1L << 40, &max_frames)) return 2;
    if (mr_cli_get(opts, "rate") && !mr_cli_double("rate", mr_cli_get(opts, "rate"), 0.01, 10000, &rate)) return 2;

    mr_error err = {0};
    mr_recording *rec_in = NULL;
    mr_source *src = NULL;
    if (!app_open_input_opts(cmd, opts, mr_cli_flag(opts, "gray"), &rec_in, &src, &err)) return 2;
    if (!src) return mr_cli_error(cmd, &err);
    app_tracker t;
    bool ok = app_tracker_init(&t, cmd, opts, &dp, rec_in);
    mr_recording_close(&rec_in);
    if (!ok) {
        mr_source_close(&src);
        return 1;
    }
    if (!t.has_camera || !t.has_markers) {
        app_tracker_free(&t);
        mr_source_close(&src);
        return mr_cli_errorf(cmd, "--camera and --markers are required (unless the input is a recording)");
    }
    rp.camera = t.camera;
    rp.markers = t.markers;
    rp.source = input;
    rp.frame_ext = mr_cli_flag(opts, "png") ? ".png" : ".jpg";
    mr_recorder *rec = mr_recorder_create(out, &rp, &err);
    if (!rec) {
        app_tracker_free(&t);
        mr_source_close(&src);
        return mr_cli_error(cmd, &err);
    }
    mr_stop_catch();
    int rc = 0;
    long frames = 0, with_pose = 0, warned = 0;
    double t_first = 0, wall0 = mr_time_now();
    while (!mr_stop_requested() && (max_frames < 0 || frames < max_frames)) {
        mr_frame f;
        mr_read_status st = mr_source_read(src, &f, &err);
        if (st == MR_READ_END) break;
        if (st == MR_READ_ERROR) {
            rc = mr_cli_error(cmd, &err);
            break;
        }
        if (frames == 0) t_first = f.timestamp;
        if (rate > 0) sleep_until(wall0 + frames / rate);
        mr_tracker_result r;
        mr_error fe = {0};
        mr_frame_record fr = {0};
        fr.t = f.timestamp - t_first;
        if (mr_tracker_frame(t.tracker, &f.image, f.timestamp, &r, &fe)) {
            fr.detections = r.detections;
            fr.detection_count = r.detection_count;
            fr.pose = r.pose;
            fr.has_filtered = r.has_filtered;
            fr.filtered = r.filtered;
            with_pose += r.pose.valid;
        } else if (warned++ < 10) {
            /* The frame is still recorded (without tracking) and the run goes on. */
            fprintf(stderr, "mrcheck: record: warning: frame %lld: %s\n", (long long)f.index, fe.msg);
        }
        if (!mr_recorder_append(rec, &fr, &f.image, &err)) {
            rc = mr_cli_error(cmd, &err);
            break;
        }
        frames++;
        if (frames % 30 == 0) mr_log(MR_LOG_INFO, "record: %ld frames, %ld with a pose", frames, with_pose);
    }
    mr_recorder_close(&rec);
    app_tracker_free(&t);
    mr_source_close(&src);
    if (rc == 0) printf("recorded %ld frames (%ld with a pose) to %s/\n", frames, with_pose, out);
    return rc;
}
