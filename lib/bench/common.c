/* What the bench runners share. */
#include "bench_internal.h"

#include <string.h>

bool bench_gfx_open(bench_gfx *g, mr_error *err) {
    memset(g, 0, sizeof *g);
    mr_gpu_params gp = MR_GPU_DEFAULTS;
    gp.debug = mr_log_get_level() >= MR_LOG_DEBUG;
    g->gpu = mr_gpu_create_headless(&gp, err);
    if (!g->gpu) return false;
    g->renderer = mr_renderer_create(g->gpu, err);
    if (!g->renderer) {
        mr_gpu_destroy(&g->gpu);
        return false;
    }
    return true;
}

void bench_gfx_close(bench_gfx *g) {
    mr_renderer_destroy(&g->renderer);
    mr_gpu_destroy(&g->gpu);
}
