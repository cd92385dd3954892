/* libFuzzer target: the recording readers (frames.jsonl, groundtruth.jsonl
 * and meta.json), all from memory. */
#include "mr_session.h"

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_recording rec;
    memset(&rec, 0, sizeof rec);
    mr_error err = {0};
    mr_recording_parse_frames(&rec, (const char *)data, size, &err);
    mr_recording_parse_ground_truth(&rec, (const char *)data, size);
    for (int i = 0; i < rec.frame_count; i++) {
        if (rec.frames[i].pose.valid && !mr_m4_is_rigid(&rec.frames[i].pose.world_from_camera, 1e-5)) __builtin_trap();
        if (rec.frames[i].image[0] == '/' || strstr(rec.frames[i].image, "..")) __builtin_trap();
        free(rec.frames[i].detections);
    }
    free(rec.frames);
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
