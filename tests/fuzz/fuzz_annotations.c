/* libFuzzer target: the tolerant annotations.jsonl reader. Whatever comes
 * in, every mark read back has a type, finite numbers and a rigid pose,
 * and marks + bad lines never exceed the lines given. */
#include "mr_session.h"

#include <math.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_annotations an;
    mr_error err = {0};
    if (!mr_annotations_parse((const char *)data, size, &an, &err)) return 0;
    size_t lines = 1;
    for (size_t i = 0; i < size; i++) lines += data[i] == '\n';
    if ((size_t)an.count + (size_t)an.bad_lines > lines) __builtin_trap();
    for (int i = 0; i < an.count; i++) {
        const mr_annotation *a = &an.items[i];
        if (!a->json || !a->type[0] || memchr(a->type, 0, sizeof a->type) == NULL) __builtin_trap();
        if (!isfinite(a->time_unix) || !isfinite(a->timestamp) || !isfinite(a->depth) || a->frame_index < -1) __builtin_trap();
        for (int k = 0; k < 3; k++)
            if (!isfinite(a->world[k])) __builtin_trap();
        if (a->hit && !cJSON_IsArray(cJSON_GetObjectItemCaseSensitive(a->json, "world"))) __builtin_trap();
        if (a->has_pose && !mr_m4_is_rigid(&a->world_from_camera, 1e-5)) __builtin_trap();
    }
    mr_annotations_free(&an);
    return 0;
}
