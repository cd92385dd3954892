/* lib/scene's option tables: the synthetic factories' sizes and units. */
#include "mr_scene.h"

#include <stddef.h>

const mr_opt mr_synth_opts[] = {
    {"halls", MR_OPT_INT, offsetof(mr_synth_params, halls), 1, 4096, 1, NULL,
     "number of halls (about 0.8M triangles and 2300 nodes each)", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

const mr_opt mr_synth_cad_opts[] = {
    /* No unit is assumed: 1000 writes the same hall in millimetres. */
    {"unit", MR_OPT_DOUBLE, offsetof(mr_synth_cad_params, unit), 1e-6, 1e9, 1.0, NULL, "scene units per metre", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
