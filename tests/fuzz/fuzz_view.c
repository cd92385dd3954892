/* Fuzz target: view / camera JSON. */
#include "mr_core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = 0;
    cJSON *j = cJSON_ParseWithLength(text, size);
    free(text);
    if (!j) return 0;
    mr_error err = {0};
    mr_view v;
    /* "." base dir: a string camera path is looked up relative to the
     * working directory, which holds no camera files in a fuzz run. */
    if (mr_view_from_json(j, ".", &v, &err)) {
        if (!mr_m4_is_rigid(&v.world_from_camera, 1e-5) || !mr_camera_validate(&v.camera, NULL)) __builtin_trap();
    } else if (!err.msg[0]) {
        __builtin_trap();
    }
    mr_camera c;
    if (mr_camera_from_json(j, &c, &err) && !(c.fx > 0 && isfinite(c.cx))) __builtin_trap();
    cJSON_Delete(j);
    return 0;
}
