/* The headless GPU + renderer pair of commands and benches, and the
 * verbose frame report of `mrcheck render`. */
#include "mr_render.h"

#include <string.h>

bool mr_gfx_open(mr_gfx *g, mr_error *err) {
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

void mr_gfx_close(mr_gfx *g) {
    mr_renderer_destroy(&g->renderer);
    mr_gpu_destroy(&g->gpu);
}

void mr_render_report(FILE *f, const mr_renderer *r, const mr_frame_result *res, double upload_s) {
    char passes[256];
    mr_frame_result_passes(res, passes, sizeof passes);
    fprintf(f, "mrcheck: render: passes: %s; %u draw calls, %llu triangles, near plane %g\n", passes, res->draw_calls,
            (unsigned long long)res->triangles, res->near_plane);
    mr_draw_stats ds;
    mr_renderer_draw_stats(r, &ds);
    fprintf(f, "mrcheck: render: geometry: %u of %u nodes visible, %u instances (%u at a simplified level) in %u "
            "commands, %llu of %llu triangles, culling %.2f ms; peak RSS %.0f MB\n", ds.nodes_visible,
            ds.nodes_drawable, ds.instances, ds.lod_instances, ds.commands, (unsigned long long)ds.triangles,
            (unsigned long long)ds.triangles_full, ds.cull_ms, mr_peak_rss_bytes() / 1048576.0);
    if (ds.hlod_proxies)
        fprintf(f, "mrcheck: render: LOD hierarchy: %u proxies, %llu triangles\n", ds.hlod_proxies,
                (unsigned long long)ds.hlod_triangles);
    if (ds.clusters_tested)
        fprintf(f, "mrcheck: render: clusters: %llu of %llu meshlets drawn (%llu occluded)\n",
                (unsigned long long)ds.clusters_drawn, (unsigned long long)ds.clusters_tested,
                (unsigned long long)ds.clusters_occluded);
    mr_cluster_info ci;
    mr_renderer_cluster_info(r, &ci);
    fprintf(f, "mrcheck: render: upload %.2f s; meshlets: %llu levels from the cache, %llu built in %.2f s%s\n", upload_s,
            (unsigned long long)ci.levels_cached, (unsigned long long)ci.levels_built, ci.build_s,
            ci.cache_written ? " (cache written)" : "");
}
