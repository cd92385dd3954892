/* A frame's auxiliary buffers as files (`mrcheck render --aux`). */
#include "mr_render.h"

#include <stddef.h>

bool mr_frame_result_save_aux(const char *dir, const mr_frame_result *res, mr_error *err) {
    static const struct {
        const char *name;
        size_t off;
    } bufs[] = {{"depth.pfm", offsetof(mr_frame_result, depth)},
                {"normal.pfm", offsetof(mr_frame_result, normal)},
                {"ao.pfm", offsetof(mr_frame_result, ao)},
                {"shadow.pfm", offsetof(mr_frame_result, shadow)}};
    char path[4096];
    if (!mr_mkdirs(dir, err)) return false;
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++) {
        const mr_image *im = (const mr_image *)((const char *)res + bufs[i].off);
        if (!im->data) continue;
        mr_path_join(dir, bufs[i].name, path, sizeof path);
        if (!mr_image_save_pfm(path, im, err)) return false;
    }
    return true;
}
