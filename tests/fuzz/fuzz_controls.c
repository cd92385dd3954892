/* libFuzzer target: the control points reader of `mrcheck map`. Build with
 * -DMR_FUZZ=ON (clang). */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_map_control *c = NULL;
    int n = 0;
    mr_error err = {0};
    if (mr_map_controls_parse((const char *)data, size, &c, &n, &err)) {
        /* what the reader accepts must be usable by mr_map_build */
        if (n < 1 || !c) __builtin_trap();
        for (int i = 0; i < n; i++)
            if (!isfinite(c[i].world.x) || !isfinite(c[i].world.y) || !isfinite(c[i].world.z) || !(c[i].sigma > 0) ||
                c[i].corner < -1 || c[i].corner > 3 || c[i].tag_id < 0)
                __builtin_trap();
        free(c);
    } else if (!err.msg[0]) {
        __builtin_trap(); /* a refusal says why */
    }
    return 0;
}
