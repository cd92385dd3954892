/* mr_batch_replay (lib/batch) on the shipped recording and the demo hall as
 * planned (built in memory through the shipped scene config): the range
 * and step select the frames, every selected frame gets one image and one
 * replay.jsonl line in order, a frame without a pose is the camera frame
 * alone, the per-frame hook replaces the overlay, and bad ranges fail
 * before anything is written. */
#include "mr_batch.h"
#include "mr_test.h"

#include <string.h>

static int count_lines(const char *path, int *overlays) {
    size_t n = 0;
    mr_error err = {0};
    char *text = mr_file_read(path, &n, 0, &err);
    int lines = 0;
    *overlays = 0;
    for (char *l = text; l && *l;) {
        char *e = strchr(l, '\n');
        if (!e) break;
        *e = 0;
        lines++;
        *overlays += strstr(l, "\"overlay\":true") != NULL;
        l = e + 1;
    }
    free(text);
    return lines;
}

static int g_hook_calls;
static int g_stop_at; /* the hook call that asks for a stop as SIGINT would; 0: none */
static bool hook(void *user, mr_renderer *r, const mr_view *view, const mr_frame_params *fp, int64_t index, char *name,
                 size_t name_n, mr_error *err) {
    (void)user, (void)r, (void)view, (void)fp, (void)err;
    g_hook_calls++;
    if (g_hook_calls == g_stop_at) mr_stop_request(2);
    snprintf(name, name_n, "hook_%lld", (long long)index);
    return true;
}

int main(void) {
    char dir[4096], rec_dir[4200], cfg[4200], path[8400];
    CHECK(mr_test_fresh_dir("batch", dir, sizeof dir));
    const char *src = getenv("MR_SOURCE_DIR");
    snprintf(rec_dir, sizeof rec_dir, "%s/recordings/demo", src ? src : ".");
    snprintf(cfg, sizeof cfg, "%s/configs/scenes/demo_planned.json", src ? src : ".");
    mr_error err = {0};

    /* Checks that need no recording and no GPU. */
    mr_batch_replay_params p = MR_BATCH_REPLAY_DEFAULTS;
    p.out_dir = dir;
    p.from = 5;
    p.to = 4;
    CHECK(!mr_batch_replay_check(&p, &err) && strstr(err.msg, "before"));
    p.to = -1;
    p.render = hook;
    p.video_path = "x.avi";
    memset(&err, 0, sizeof err);
    CHECK(!mr_batch_replay_check(&p, &err) && strstr(err.msg, "single views"));
    p.render = NULL;
    p.video_path = NULL;
    CHECK(mr_batch_replay_check(&p, &err));

    mr_recording *rec = mr_recording_open(rec_dir, &err);
    CHECK_MSG(rec, "%s", err.msg);
    mr_scene *scene = rec ? mr_scene_load(cfg, NULL, &err) : NULL;
    CHECK_MSG(scene, "%s", err.msg);
    if (!scene) {
        mr_recording_close(&rec);
        return mr_test_finish("test_batch");
    }
    /* Frames 10..13 of the shipped walk: 10, 11 tracked, 12, 13 not. */
    bool tracked[4];
    for (int i = 0; i < 4; i++) tracked[i] = rec->frames[10 + i].has_filtered || rec->frames[10 + i].pose.valid;
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) {
        mr_scene_destroy(&scene);
        mr_recording_close(&rec);
        return mr_test_no_gpu("test_batch", &err);
    }
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r, "%s", err.msg);
    p.recording = rec;
    p.from = 10;
    p.to = 13;
    p.every = 1;
    p.frame.width = 80;
    p.frame.height = 60;
    mr_batch_replay_stats st;
    CHECK_MSG(r && mr_batch_replay(&p, r, scene, &st, &err), "%s", err.msg);
    int want_overlays = tracked[0] + tracked[1] + tracked[2] + tracked[3];
    CHECK_MSG(st.overlays == want_overlays && st.plain == 4 - want_overlays, "%d overlays, %d plain; %d tracked",
              st.overlays, st.plain, want_overlays);
    snprintf(path, sizeof path, "%s/replay.jsonl", dir);
    int overlays = 0;
    CHECK(count_lines(path, &overlays) == 4 && overlays == want_overlays);
    for (int i = 10; i <= 13; i++) {
        snprintf(path, sizeof path, "%s/overlay_%06d.png", dir, i);
        CHECK_MSG(mr_file_exists(path), "%s missing", path);
    }
    snprintf(path, sizeof path, "%s/overlay_%06d.png", dir, 14);
    CHECK(!mr_file_exists(path)); /* past --to */

    /* Every second frame from 10: 10 and 12 only. */
    char dir2[4200];
    snprintf(dir2, sizeof dir2, "%s/every2", dir);
    p.out_dir = dir2;
    p.every = 2;
    CHECK_MSG(r && mr_batch_replay(&p, r, scene, &st, &err), "%s", err.msg);
    CHECK(st.overlays + st.plain == 2);
    snprintf(path, sizeof path, "%s/overlay_%06d.png", dir2, 11);
    CHECK(!mr_file_exists(path));

    /* The hook replaces the overlay; frames without a pose are listed as "-". */
    char dir3[4200];
    snprintf(dir3, sizeof dir3, "%s/hook", dir);
    p.out_dir = dir3;
    p.every = 1;
    p.render = hook;
    g_hook_calls = 0;
    CHECK_MSG(r && mr_batch_replay(&p, r, scene, &st, &err), "%s", err.msg);
    CHECK(g_hook_calls == want_overlays && st.overlays == want_overlays);
    snprintf(path, sizeof path, "%s/overlay_%06d.png", dir3, 10);
    CHECK(!mr_file_exists(path));

    /* A folder that holds files is refused before anything is drawn;
     * --force writes into it. */
    memset(&err, 0, sizeof err);
    g_hook_calls = 0;
    CHECK(!mr_batch_replay_check(&p, &err) && strstr(err.msg, "not empty"));
    CHECK(r && !mr_batch_replay(&p, r, scene, &st, &err) && g_hook_calls == 0);
    p.force = true;
    CHECK_MSG(r && mr_batch_replay(&p, r, scene, &st, &err), "%s", err.msg);
    p.force = false;

    /* A stop (SIGINT) during the first tracked frame ends the run before
     * the next one: the index lists exactly the frames done, the error
     * says interrupted. */
    char dir4[4200];
    snprintf(dir4, sizeof dir4, "%s/stopped", dir);
    p.out_dir = dir4;
    g_hook_calls = 0;
    g_stop_at = 1;
    memset(&err, 0, sizeof err);
    CHECK(r && !mr_batch_replay(&p, r, scene, &st, &err) && err.code == MR_ERR_INTERRUPTED);
    CHECK_MSG(st.interrupted && st.written >= 1 && st.written < 4, "%d written", st.written);
    snprintf(path, sizeof path, "%s/replay.jsonl", dir4);
    CHECK(count_lines(path, &overlays) == st.written && overlays == 1);
    CHECK(g_hook_calls == 1);
    mr_stop_request(0);
    g_stop_at = 0;
    /* Stopped before the first frame: nothing written, no folder left. */
    char dir5[4200];
    snprintf(dir5, sizeof dir5, "%s/new/stopped_early", dir);
    p.out_dir = dir5;
    mr_stop_request(15);
    memset(&err, 0, sizeof err);
    CHECK(r && !mr_batch_replay(&p, r, scene, &st, &err) && err.code == MR_ERR_INTERRUPTED);
    mr_stop_request(0);
    snprintf(path, sizeof path, "%s/new", dir);
    CHECK_MSG(!mr_file_exists(path), "%s left behind", path);

    /* A range past the recording's end selects nothing: an error, and no
     * folder is left behind. */
    char dir6[4200];
    snprintf(dir6, sizeof dir6, "%s/past_end", dir);
    p.out_dir = dir6;
    p.render = NULL;
    p.from = 100000;
    p.to = -1;
    memset(&err, 0, sizeof err);
    CHECK(r && !mr_batch_replay(&p, r, scene, &st, &err) && strstr(err.msg, "no recorded frame"));
    CHECK(!mr_file_exists(dir6));

    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    mr_scene_destroy(&scene);
    mr_recording_close(&rec);
    return mr_test_finish("test_batch");
}
