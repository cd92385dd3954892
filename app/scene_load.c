/* Scene loading for the commands that draw big scenes: progress on a
 * terminal for loads that take over a second, load time and peak memory,
 * LOD levels from the cache next to the scene, and the draw options
 * (--cull, --batch, --instancing, --lod, ...) shared by render and bench. */
#include "app.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct progress_state {
    const char *label;
    double t0;
    bool shown;
} progress_state;

/* Prints only on a terminal, and only once the load has taken a second:
 * quick loads stay silent, logs and pipes never see carriage returns. */
static void show_progress(void *user, const char *stage, double fraction) {
    progress_state *p = user;
    if (mr_time_now() - p->t0 < 1.0) return;
    fprintf(stderr, "\r%s: %-6s %3.0f%%   ", p->label, stage, 100.0 * fraction);
    fflush(stderr);
    p->shown = true;
}

static void end_progress(progress_state *p) {
    if (p->shown) fprintf(stderr, "\r%*s\r", 60, "");
}

mr_scene *app_load_scene(const char *path, const mr_scene_params *params, app_load_info *info, mr_error *err) {
    mr_scene_params sp = MR_SCENE_DEFAULTS;
    if (params) sp = *params;
    progress_state ps = {path, mr_time_now(), false};
    if (isatty(2)) {
        sp.progress = show_progress;
        sp.progress_user = &ps;
    }
    mr_scene *s = mr_scene_load(path, &sp, err);
    end_progress(&ps);
    if (!s) return NULL;
    app_load_info li;
    memset(&li, 0, sizeof li);
    li.load_s = mr_time_now() - ps.t0;
    FILE *f = fopen(path, "rb");
    if (f) {
        if (fseek(f, 0, SEEK_END) == 0) li.file_bytes = (uint64_t)ftell(f);
        fclose(f);
    }
    li.triangles = mr_scene_triangle_count(s);
    for (int32_t i = 0; i < s->mesh_count; i++) li.unique_triangles += s->meshes[i].index_count / 3;
    li.peak_rss = mr_peak_rss_bytes();
    mr_log(MR_LOG_INFO, "loaded %s: %d nodes, %d meshes, %llu triangles drawn (%llu stored), %.1f MB in %.2f s (%.0f MB/s), peak RSS %.0f MB",
           path, (int)s->node_count, (int)s->mesh_count, (unsigned long long)li.triangles,
           (unsigned long long)li.unique_triangles, li.file_bytes / 1e6, li.load_s,
           li.load_s > 0 ? li.file_bytes / 1e6 / li.load_s : 0.0, li.peak_rss / 1048576.0);
    if (info) *info = li;
    return s;
}

mr_lod *app_load_lod(const mr_scene *s, const char *scene_path, bool use_cache, mr_error *err) {
    char cache[4096];
    mr_lod_cache_path(scene_path, cache, sizeof cache);
    mr_lod_params lp = MR_LOD_DEFAULTS;
    lp.progress = isatty(2);
    mr_lod_info info;
    mr_lod *lod = mr_lod_load_or_build(s, use_cache ? cache : NULL, &lp, &info, err);
    if (lod && info.from_cache)
        mr_log(MR_LOG_INFO, "LOD: %llu levels read from the cache", (unsigned long long)info.levels);
    else if (lod)
        mr_log(MR_LOG_INFO, "LOD: %llu levels built in %.2f s (%.0f input triangles/s, %s kernel)%s",
               (unsigned long long)info.levels, info.build_s, info.build_s > 0 ? info.triangles / info.build_s : 0.0,
               mr_lod_kernel(&lp),
               info.cache_written ? " (cache written)" : "");
    return lod;
}

void app_lod_auto(const mr_cli_opt *opts, const mr_scene *s, mr_draw_params *dp) {
    const char *v = mr_cli_get(opts, "lod");
    if ((!v || strcmp(v, "auto") == 0) && mr_scene_triangle_count(s) < MR_LOD_AUTO_TRIANGLES) dp->no_lod = true;
}

bool app_draw_lod(const char *cmd, const mr_cli_opt *opts, mr_draw_params *dp) {
    const char *v = mr_cli_get(opts, "lod");
    if (!v || strcmp(v, "auto") == 0 || strcmp(v, "on") == 0) dp->no_lod = false;
    else if (strcmp(v, "off") == 0) dp->no_lod = true;
    else return mr_cli_errorf(cmd, "--lod must be 'on' or 'off' or 'auto', not '%s'", v), false;
    return true;
}
