/* Scene and LOD loading as the commands do it: progress on a terminal for
 * loads that take over a second, load time and peak memory in the log,
 * and the one rule for whether a scene gets levels of detail at all. */
#include "mr_scene.h"

#include <string.h>
#include <unistd.h>

bool mr_lod_mode_parse(const char *s, mr_lod_mode *out, mr_error *err) {
    if (!s || strcmp(s, "auto") == 0) *out = MR_LOD_MODE_AUTO;
    else if (strcmp(s, "on") == 0) *out = MR_LOD_MODE_ON;
    else if (strcmp(s, "off") == 0) *out = MR_LOD_MODE_OFF;
    else return mr_fail(err, MR_ERR_INVALID, "--lod must be 'on' or 'off' or 'auto', not '%s'", s);
    return true;
}

bool mr_lod_wanted(mr_lod_mode mode, const mr_scene *s) {
    if (mode != MR_LOD_MODE_AUTO) return mode == MR_LOD_MODE_ON;
    return mr_scene_triangle_count(s) >= MR_LOD_AUTO_TRIANGLES;
}

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

mr_scene *mr_scene_load_logged(const char *path, const mr_scene_params *params, mr_error *err) {
    mr_scene_params sp = MR_SCENE_DEFAULTS;
    if (params) sp = *params;
    progress_state ps = {path, mr_time_now(), false};
    if (isatty(2)) {
        sp.progress = show_progress;
        sp.progress_user = &ps;
    }
    mr_scene *s = mr_scene_load(path, &sp, err);
    if (ps.shown) fprintf(stderr, "\r%*s\r", 60, "");
    if (!s) return NULL;
    const double load_s = mr_time_now() - ps.t0;
    uint64_t file_bytes = 0, unique = 0;
    FILE *f = fopen(path, "rb");
    if (f) {
        if (fseek(f, 0, SEEK_END) == 0) file_bytes = (uint64_t)ftell(f);
        fclose(f);
    }
    for (int32_t i = 0; i < s->mesh_count; i++) unique += s->meshes[i].index_count / 3;
    mr_log(MR_LOG_INFO, "loaded %s: %d nodes, %d meshes, %llu triangles drawn (%llu stored), %.1f MB in %.2f s (%.0f MB/s), peak RSS %.0f MB",
           path, (int)s->node_count, (int)s->mesh_count, (unsigned long long)mr_scene_triangle_count(s),
           (unsigned long long)unique, file_bytes / 1e6, load_s, load_s > 0 ? file_bytes / 1e6 / load_s : 0.0,
           mr_peak_rss_bytes() / 1048576.0);
    return s;
}

mr_lod *mr_lod_load_logged(const mr_scene *s, const char *scene_path, bool use_cache, mr_error *err) {
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
               mr_lod_kernel(&lp), info.cache_written ? " (cache written)" : "");
    return lod;
}

bool mr_hlod_mode_check(const char *mode, mr_error *err) {
    if (!mode || strcmp(mode, "auto") == 0 || strcmp(mode, "on") == 0 || strcmp(mode, "off") == 0) return true;
    return mr_fail(err, MR_ERR_INVALID, "--hlod must be 'on' or 'off' or 'auto', not '%s'", mode);
}

typedef struct hlod_progress {
    double t0;
    bool tty, shown;
} hlod_progress;

/* Progress on a terminal after a second; false (stop) once SIGINT or
 * SIGTERM was caught. */
static bool hlod_on_progress(void *user, double fraction) {
    hlod_progress *p = user;
    if (p->tty && mr_time_now() - p->t0 >= 1.0) {
        fprintf(stderr, "\rLOD hierarchy: %3.0f%%   ", 100.0 * fraction);
        fflush(stderr);
        p->shown = true;
    }
    return !mr_stop_requested();
}

bool mr_hlod_wanted_scene(const char *mode, const mr_scene *s) {
    int32_t drawn = 0;
    for (int32_t i = 0; s && i < s->node_count; i++) drawn += s->nodes[i].mesh_count > 0 && !s->nodes[i].shadow_catcher;
    return s && mr_hlod_wanted(mode, mr_scene_triangle_count(s), drawn);
}

bool mr_hlod_load_logged(const mr_scene *s, const mr_lod *lod, const char *scene_path, const char *mode, bool use_cache,
                         mr_hlod **out, mr_error *err) {
    *out = NULL;
    if (!mr_hlod_mode_check(mode, err)) return false;
    if (!lod || !mr_hlod_wanted_scene(mode, s)) return true;
    char cache[4096];
    mr_hlod_cache_path(scene_path, cache, sizeof cache);
    hlod_progress pr = {mr_time_now(), isatty(2) != 0, false};
    mr_hlod_params hp = MR_HLOD_DEFAULTS;
    hp.on_progress = hlod_on_progress;
    hp.progress_user = &pr;
    mr_hlod_info info;
    *out = mr_hlod_load_or_build(s, lod, use_cache && scene_path && scene_path[0] ? cache : NULL, &hp, &info, err);
    if (pr.shown) fprintf(stderr, "\r%*s\r", 30, "");
    if (!*out) return false;
    if (info.from_cache)
        mr_log(MR_LOG_INFO, "LOD hierarchy: %d tree nodes, %llu proxy triangles read from the cache", (int)(*out)->node_count,
               (unsigned long long)(*out)->proxy_triangles);
    else
        mr_log(MR_LOG_INFO, "LOD hierarchy: %d tree nodes, %llu proxy triangles built in %.2f s (%.0f input triangles/s)%s",
               (int)(*out)->node_count, (unsigned long long)(*out)->proxy_triangles, info.build_s,
               info.build_s > 0 ? info.input_triangles / info.build_s : 0.0, info.cache_written ? " (cache written)" : "");
    return true;
}
