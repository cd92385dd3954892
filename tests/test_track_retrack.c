/* `mrcheck track` and `mrcheck view --retrack` give bit-identical poses on
 * the shipped recording (recordings/demo).
 *
 * The track side is cmd_track's own wiring, compiled in (app/track_util.c,
 * app/args.c): the input opened and the tracker set up from the options
 * `track --input DIR` parses to, frames read and tracked as cmd_track's
 * loop does. That it is what the command does is checked too: the real
 * `mrcheck track --input DIR` (MR_MRCHECK names the binary) must print
 * exactly the lines mr_pose_line_json makes of these results (cJSON prints
 * doubles to ~1e-15, not bit for bit, so the bits are compared in
 * process). The view side is the
 * view's own capture code, lib/session/capture.c (mr_capture_*):
 * its replay reader and tracking thread run with --retrack's parameters
 * (the recording's camera and marker map, as lib/view/run.c passes them), and
 * the test steps through the recording one frame at a time, waiting for
 * each tracked frame, so no frame is dropped (the window does the same
 * when paused and stepped). Every frame's validity, tags seen and used,
 * RMS and filtered pose must be the same doubles. */
#include "app_track.h"
#include "mr_test.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define MAXF 512

typedef struct track_line {
    bool seen, valid, has_filtered;
    int tags_seen, tags_used;
    double rms_px;
    mr_dmat4 filtered;
} track_line;

/* The track side in process, as cmd_track runs it. Fills lines[] by
 * frame number and their printed pose lines; returns the frame count. */
static int track_in_process(const char *dir, track_line *lines, char **printed) {
    char *argv[] = {"mrcheck", "track", "--input", (char *)dir, "--quiet", NULL};
    mr_cli_opt opts[] = {
        {"input", "PATH", "", NULL},
        APP_TRACK_OPTS,
        {"quiet", NULL, "", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    mr_cli_table tables[] = {APP_TRACK_TABLE(&dp)};
    bool help = false;
    CHECK(mr_cli_parse_tables(5, argv, 2, opts, tables, 1, NULL, 0, NULL, "", &help) && !help);
    mr_error err = {0};
    mr_recording *rec = NULL;
    mr_source *src = NULL;
    CHECK(app_open_input_opts("track", opts, true, &rec, &src, &err));
    CHECK_MSG(src != NULL, "track input: %s", err.msg);
    app_tracker t;
    bool ok = src && app_tracker_init(&t, "track", opts, &dp, rec);
    mr_recording_close(&rec);
    CHECK_MSG(ok && t.has_camera && t.has_markers, "track's tracker did not set up from the recording");
    if (!ok) {
        mr_source_close(&src);
        return 0;
    }
    int n = 0;
    size_t len = 0, cap = 1 << 20;
    *printed = calloc(1, cap);
    mr_frame f;
    while (mr_source_read(src, &f, &err) == MR_READ_FRAME && f.index < MAXF) {
        mr_tracker_result r;
        CHECK_MSG(mr_tracker_frame(t.tracker, &f.image, f.timestamp, &r, &err), "frame %lld: %s", (long long)f.index,
                  err.msg);
        track_line *l = &lines[f.index];
        l->seen = true;
        l->valid = r.pose.valid;
        l->has_filtered = r.has_filtered;
        l->filtered = r.filtered;
        l->tags_seen = r.pose.tags_seen;
        l->tags_used = r.pose.tags_used;
        l->rms_px = r.pose.rms_px;
        cJSON *o = mr_pose_line_json(f.index, f.timestamp, &r);
        char *s = cJSON_PrintUnformatted(o);
        cJSON_Delete(o);
        size_t k = s ? strlen(s) : 0;
        if (*printed && len + k + 2 < cap) {
            memcpy(*printed + len, s, k);
            len += k;
            (*printed)[len++] = '\n';
        }
        free(s);
        n++;
    }
    app_tracker_free(&t);
    mr_source_close(&src);
    return n;
}

/* Runs `mrcheck track` and returns its stdout (malloc'd). */
static char *run_track(const char *mrcheck, const char *dir) {
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "'%s' track --input '%s' --quiet", mrcheck, dir);
    FILE *p = popen(cmd, "r");
    CHECK_MSG(p != NULL, "cannot run %s", cmd);
    if (!p) return NULL;
    size_t cap = 1 << 20, len = 0;
    char *out = calloc(1, cap);
    size_t k;
    while (out && len + 1 < cap && (k = fread(out + len, 1, cap - 1 - len, p)) > 0) len += k;
    int rc = pclose(p);
    CHECK_MSG(rc == 0, "mrcheck track exited with status %d", rc);
    return out;
}

/* Waits (up to 20 s) for the capture to publish frame `index`. */
static bool wait_frame(mr_capture *c, mr_capture_frame *f, int64_t index) {
    for (int k = 0; k < 4000; k++) {
        if (mr_capture_latest(c, f) && f->index == index) return true;
        struct timespec ts = {0, 5000000};
        nanosleep(&ts, NULL);
    }
    return false;
}

/* Both sides over the recording in dir; with_cli: also the binary. */
static void compare(const char *dir, const char *mrcheck, bool with_cli, const char *what) {
    mr_error err = {0};
    mr_recording *rec = mr_recording_open(dir, &err);
    CHECK_MSG(rec != NULL, "%s: %s", what, err.msg);
    if (!rec) return;
    int nframes = rec->frame_count < MAXF ? rec->frame_count : MAXF;

    static track_line want[MAXF];
    memset(want, 0, sizeof want);
    char *printed = NULL;
    int ntracked = track_in_process(dir, want, &printed);
    CHECK_MSG(ntracked == nframes, "%s: track's loop tracked %d of %d frames", what, ntracked, nframes);
    if (with_cli) {
        char *cli = run_track(mrcheck, dir);
        CHECK_MSG(cli && printed && strcmp(cli, printed) == 0,
                  "%s: `mrcheck track` printed other poses than its wiring gives in this test (the test no longer "
                  "runs track as the command does)",
                  what);
        free(cli);
    }
    free(printed);

    mr_capture_params cp = {0};
    cp.replay_dir = dir;
    cp.camera = &rec->camera;
    cp.markers = &rec->markers;
    cp.retrack = true;
    cp.start_paused = true;
    mr_capture *c = mr_capture_start(&cp, &err);
    CHECK_MSG(c != NULL, "%s: view capture did not start: %s", what, err.msg);
    if (!c) {
        mr_recording_close(&rec);
        return;
    }
    mr_capture_frame f;
    memset(&f, 0, sizeof f);
    int valid = 0, same = 0, first_bad = -1;
    for (int i = 0; i < nframes; i++) {
        if (i > 0) mr_capture_step(c, 1);
        bool got = wait_frame(c, &f, i);
        CHECK_MSG(got, "%s: the view's capture never delivered frame %d", what, i);
        if (!got) break;
        const track_line *w = &want[i];
        CHECK_MSG(w->seen, "%s: track gave no result for frame %d", what, i);
        bool ok = f.pose_valid == w->valid && f.tags_seen == w->tags_seen && f.tags_used == w->tags_used &&
                  f.rms_px == (w->valid ? w->rms_px : -1);
        if (w->valid) {
            valid++;
            ok = ok && w->has_filtered && memcmp(&f.pose, &w->filtered, sizeof f.pose) == 0;
        }
        if (!ok && first_bad < 0) {
            first_bad = i;
            fprintf(stderr,
                    "%s: frame %d: track valid %d tags %d/%d rms %.17g tx %.17g; view --retrack valid %d tags %d/%d "
                    "rms %.17g tx %.17g (difference %.3g)\n",
                    what, i, w->valid, w->tags_seen, w->tags_used, w->rms_px, w->filtered.m[3], f.pose_valid,
                    f.tags_seen, f.tags_used, f.rms_px, f.pose.m[3], f.pose.m[3] - w->filtered.m[3]);
        }
        same += ok;
    }
    int64_t read = 0, tracked = 0, dropped = 0;
    double ms = 0;
    mr_capture_counts(c, &read, &tracked, &dropped, &ms);
    mr_capture_frame_free(&f);
    mr_capture_stop(&c);
    CHECK_MSG(dropped == 0 && tracked == nframes, "%s: the view tracked %lld frames and dropped %lld (want %d, 0)", what,
              (long long)tracked, (long long)dropped, nframes);
    CHECK_MSG(valid >= nframes / 2, "%s: only %d of %d frames have a pose: not a meaningful comparison", what, valid,
              nframes);
    CHECK_MSG(same == nframes,
              "%s: view --retrack differs from track on %d of %d frames (first: frame %d; poses must be the same "
              "doubles)",
              what, nframes - same, nframes, first_bad);
    printf("%s: track vs view --retrack: %d frames, %d with a pose, %d identical\n", what, nframes, valid, same);
    mr_recording_close(&rec);
}

/* The shipped recording never lets the previous-pose rule matter (it
 * sees two or more tags wherever it is tracked), so a second recording is
 * cut from the two frames of the earlier demo recording kept in
 * tests/data/tracker (its frames 0 and 52) where the rule decides: the
 * single ambiguous tag of frame 52 after a pose 0.75 s old (too
 * old: not used), 0.25 s old (used), and after time went backwards (not
 * used). It gives another pose with and without frame 0's pose as the
 * previous one (test_track_tracker). */
static bool make_policy_recording(const char *demo, const char *dir) {
    static const struct { int src; double t; } seq[] = {
        {0, 0.0}, {52, 0.75}, {0, 1.0}, {52, 1.25}, {0, 3.0}, {52, 2.9}, {0, 4.0}, {52, 4.5}};
    char path[4096], from[4096];
    mr_error err = {0};
    snprintf(path, sizeof path, "%s/frames", dir);
    if (!mr_mkdirs(path, &err)) return false;
    snprintf(from, sizeof from, "%s/meta.json", demo);
    size_t size = 0;
    char *meta = mr_file_read(from, &size, 0, &err);
    snprintf(path, sizeof path, "%s/meta.json", dir);
    bool ok = meta && mr_file_write_atomic(path, meta, size, &err);
    free(meta);
    char lines[4096] = "";
    for (size_t i = 0; ok && i < sizeof seq / sizeof seq[0]; i++) {
        snprintf(from, sizeof from, "%s/frames/%06d.jpg", demo, seq[i].src);
        snprintf(path, sizeof path, "%s/frames/%06zu.jpg", dir, i);
        remove(path);
        ok = symlink(from, path) == 0;
        size_t n = strlen(lines);
        snprintf(lines + n, sizeof lines - n, "{\"frame\":%zu,\"t\":%.17g,\"image\":\"frames/%06zu.jpg\"}\n", i, seq[i].t,
                 i);
    }
    snprintf(path, sizeof path, "%s/frames.jsonl", dir);
    ok = ok && mr_file_write_atomic(path, lines, strlen(lines), &err);
    CHECK_MSG(ok, "cannot write the policy recording in %s: %s", dir, err.msg);
    return ok;
}

int main(void) {
    const char *src = getenv("MR_SOURCE_DIR"), *mrcheck = getenv("MR_MRCHECK"), *tmp = getenv("MR_TEST_TMP");
    if (!mrcheck) {
        fprintf(stderr, "test_track_retrack: MR_MRCHECK (the mrcheck binary) is not set\n");
        return 1;
    }
    char demo[2048], dir[2048], old[2048];
    snprintf(demo, sizeof demo, "%s/recordings/demo", src ? src : ".");
    compare(demo, mrcheck, true, "recordings/demo");
    snprintf(old, sizeof old, "%s/tests/data/tracker", src ? src : ".");
    snprintf(dir, sizeof dir, "%s/retrack_policy", tmp ? tmp : "/tmp");
    if (make_policy_recording(old, dir)) compare(dir, mrcheck, true, "policy cut");
    return mr_test_finish("test_track_retrack");
}
