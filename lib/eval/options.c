/* lib/eval's option table: the ray-traced AO reference's own numbers. */
#include "mr_eval.h"

#include <stddef.h>

const mr_opt mr_gt_opts[] = {
    {"rays", MR_OPT_INT, offsetof(mr_gt_params, rays), 1, 1 << 20, MR_GT_DEFAULT_RAYS, NULL,
     "groundtruth: cosine-weighted rays per pixel", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
