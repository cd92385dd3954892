/* libFuzzer target: the recording readers (frames.jsonl, groundtruth.jsonl
 * and meta.json), all from memory, and the replay index over what they
 * read: random access and seeks by frame number and by time stay in range
 * and agree with the frames. */
#include "mr_session.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void check_replay(mr_recording *rec, const uint8_t *data, size_t size) {
    mr_error err = {0};
    mr_replay *r = mr_replay_from_recording(rec, &err); /* takes rec */
    if (!r) return;
    int64_t n = mr_replay_count(r);
    if (n <= 0 || mr_replay_frame_at(r, n) || mr_replay_frame_at(r, -1)) __builtin_trap();
    for (int64_t i = 0; i < n; i++) {
        const mr_replay_frame *f = mr_replay_frame_at(r, i);
        if (!f || !isfinite(f->t) || (f->has_pose && !mr_m4_is_rigid(&f->pose, 1e-5))) __builtin_trap();
    }
    /* Seek targets from the input's bytes, plus every frame's own. */
    for (size_t k = 0; k + 8 <= size && k < 64; k += 8) {
        double t;
        int64_t idx;
        memcpy(&t, data + k, 8);
        memcpy(&idx, data + k, 8);
        int64_t a = mr_replay_seek_time(r, t), b = mr_replay_seek_frame(r, idx);
        if (a < 0 || a >= n || b < 0 || b >= n) __builtin_trap();
    }
    for (int64_t i = 0; i < n; i++) {
        const mr_replay_frame *f = mr_replay_frame_at(r, i);
        int64_t a = mr_replay_seek_time(r, f->t), b = mr_replay_seek_frame(r, f->index);
        if (a < 0 || a >= n || b < 0 || b >= n) __builtin_trap();
    }
    mr_replay_close(&r);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_recording *rec = calloc(1, sizeof *rec);
    if (!rec) return 0;
    mr_error err = {0};
    mr_recording_parse_frames(rec, (const char *)data, size, &err);
    mr_recording_parse_ground_truth(rec, (const char *)data, size);
    for (int i = 0; i < rec->frame_count; i++) {
        if (rec->frames[i].pose.valid && !mr_m4_is_rigid(&rec->frames[i].pose.world_from_camera, 1e-5)) __builtin_trap();
        if (rec->frames[i].image[0] == '/' || strstr(rec->frames[i].image, "..")) __builtin_trap();
    }
    check_replay(rec, data, size);
    cJSON *meta = cJSON_ParseWithLength((const char *)data, size);
    if (meta) {
        mr_recording m;
        memset(&m, 0, sizeof m);
        mr_recording_parse_meta(&m, meta, &err);
        mr_marker_map_free(&m.markers);
        cJSON_Delete(meta);
    }
    return 0;
}
