/* mr_batch_track (lib/batch) on the shipped recording: max_frames bounds
 * the run, each frame gives one pose line (into the file, or on `lines`),
 * --print-detections lines carry the detections and the pose, and poses
 * without a marker map are refused before anything is read. No GPU. */
#include "mr_batch.h"
#include "mr_test.h"

#include <string.h>

static int lines_with(const char *text, const char *word) {
    int n = 0;
    for (const char *l = text; l && *l;) {
        const char *e = strchr(l, '\n');
        if (!e) break;
        const char *w = strstr(l, word);
        n += w && w < e;
        l = e + 1;
    }
    return n;
}

/* Runs the tracker over the first `frames` frames of rec_dir; with_map
 * false: the tracker has no marker map. Returns what went to `lines`. */
static char *run(const char *rec_dir, bool with_map, mr_batch_track_params *p, mr_batch_track_stats *st, bool *ok,
                 mr_error *err) {
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = true;
    mr_recording *rec = NULL;
    mr_source *src = mr_input_open(rec_dir, &sp, &rec, err);
    CHECK_MSG(src && rec, "%s", err->msg);
    mr_tracker_params tp = MR_TRACKER_DEFAULTS;
    mr_tracker *t = src ? mr_input_tracker_create(NULL, NULL, with_map ? rec : NULL, &tp, err) : NULL;
    CHECK_MSG(t, "%s", err->msg);
    char *buf = NULL;
    size_t n = 0;
    FILE *mem = open_memstream(&buf, &n);
    p->source = src;
    p->tracker = t;
    p->lines = mem;
    *ok = src && t && mr_batch_track(p, st, err);
    fclose(mem);
    mr_tracker_destroy(&t);
    mr_source_close(&src);
    mr_recording_close(&rec);
    return buf;
}

int main(void) {
    char dir[4096], rec_dir[4200], out[8400];
    CHECK(mr_test_fresh_dir("batch_track", dir, sizeof dir));
    const char *src = getenv("MR_SOURCE_DIR");
    snprintf(rec_dir, sizeof rec_dir, "%s/recordings/demo", src ? src : ".");
    snprintf(out, sizeof out, "%s/poses.jsonl", dir);
    mr_error err = {0};
    mr_batch_track_stats st;
    bool ok;

    /* Pose lines on `lines`, four frames. */
    mr_batch_track_params p = MR_BATCH_TRACK_DEFAULTS;
    p.max_frames = 4;
    char *text = run(rec_dir, true, &p, &st, &ok, &err);
    CHECK_MSG(ok, "%s", err.msg);
    CHECK(st.frames == 4 && st.failed == 0 && !st.interrupted);
    CHECK(lines_with(text, "\"world_from_camera\"") == 4);
    CHECK(st.with_pose >= 1 && st.with_pose <= 4);
    free(text);

    /* --print-detections: one line per frame with detections and pose. */
    p.print_detections = true;
    text = run(rec_dir, true, &p, &st, &ok, &err);
    CHECK(ok && lines_with(text, "{\"frame\":") == 4 && lines_with(text, "\"detections\":[") == 4);
    CHECK(lines_with(text, "\"pose\":{") == 4);
    CHECK(st.with_tags >= 1);
    free(text);

    /* --out: nothing on `lines`, the file holds one line per frame. */
    p.print_detections = false;
    p.out = out;
    p.max_frames = 3;
    text = run(rec_dir, true, &p, &st, &ok, &err);
    CHECK_MSG(ok, "%s", err.msg);
    CHECK(text && text[0] == 0);
    free(text);
    size_t n = 0;
    char *file = mr_file_read(out, &n, 0, &err);
    CHECK(file && lines_with(file, "\"world_from_camera\"") == 3);
    free(file);

    /* Poses need a marker map: refused before a frame is read. */
    remove(out);
    text = run(rec_dir, false, &p, &st, &ok, &err);
    CHECK(!ok && strstr(err.msg, "--markers") && st.frames == 0);
    CHECK(!mr_file_exists(out));
    free(text);
    return mr_test_finish("test_batch_track");
}
