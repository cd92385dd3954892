/* LOD levels off the caller's thread: a window's event loop starts the
 * build (or the cache read), draws the full detail meanwhile, polls once per
 * frame and takes the levels when they are done; quitting cancels a build
 * of many seconds after the meshes in progress instead of waiting for it.
 * The levels above the part follow on the same thread where asked for. */
#include "mr_scene.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct mr_lod_builder {
    pthread_t thread;
    pthread_mutex_t lock;
    const mr_scene *scene;
    char *cache_path;     /* NULL: no cache */
    mr_lod_params params; /* on_progress hooked to this builder */
    bool hier;            /* then the hierarchy (mr_lod_build_async_hlod) */
    char *hlod_path;      /* NULL: no cache */
    char hlod_mode[8];
    bool (*user_progress)(void *, double);
    void *user_data;
    /* guarded by lock */
    double fraction;
    bool cancel, done;
    mr_lod *lod;
    mr_hlod *hlod;
    mr_lod_info info;
    mr_error err;
};

static bool on_progress(void *user, double fraction) {
    mr_lod_builder *b = user;
    pthread_mutex_lock(&b->lock);
    b->fraction = fraction;
    bool go = !b->cancel;
    pthread_mutex_unlock(&b->lock);
    if (go && b->user_progress) go = b->user_progress(b->user_data, fraction);
    return go;
}

static void *run(void *arg) {
    mr_lod_builder *b = arg;
    mr_error err = {0};
    mr_lod_info info;
    memset(&info, 0, sizeof info);
    mr_lod *l = mr_lod_load_or_build(b->scene, b->cache_path, &b->params, &info, &err);
    mr_hlod *h = NULL;
    if (l && b->hier && mr_hlod_wanted_scene(b->hlod_mode, b->scene)) {
        mr_hlod_params hp = MR_HLOD_DEFAULTS;
        hp.on_progress = on_progress;
        hp.progress_user = b;
        mr_error he = {0};
        if (!(h = mr_hlod_load_or_build(b->scene, l, b->hlod_path, &hp, NULL, &he)) && he.code != MR_ERR_INTERRUPTED)
            mr_log(MR_LOG_WARN, "no levels above the part: %s", he.msg);
    }
    pthread_mutex_lock(&b->lock);
    b->lod = l;
    b->hlod = h;
    b->info = info;
    b->err = err;
    b->done = true;
    pthread_mutex_unlock(&b->lock);
    return NULL;
}

static void builder_free(mr_lod_builder *b) {
    pthread_mutex_destroy(&b->lock);
    free(b->cache_path);
    free(b->hlod_path);
    free(b);
}

/* hlod_mode NULL: levels only. */
static mr_lod_builder *start(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                             const char *hlod_mode, const char *hlod_path, mr_error *err) {
    if (!s) {
        mr_fail(err, MR_ERR_INVALID, "mr_lod_build_async: no scene");
        return NULL;
    }
    if (hlod_mode && !mr_hlod_mode_check(hlod_mode, err)) return NULL;
    mr_lod_builder *b = calloc(1, sizeof *b);
    if (!b || (cache_path && !(b->cache_path = strdup(cache_path))) || (hlod_path && !(b->hlod_path = strdup(hlod_path)))) {
        if (b) free(b->cache_path);
        free(b);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    b->scene = s;
    b->hier = hlod_mode != NULL;
    if (hlod_mode) snprintf(b->hlod_mode, sizeof b->hlod_mode, "%s", hlod_mode);
    mr_lod_params d = MR_LOD_DEFAULTS;
    b->params = params ? *params : d;
    b->user_progress = b->params.on_progress;
    b->user_data = b->params.progress_user;
    b->params.on_progress = on_progress;
    b->params.progress_user = b;
    pthread_mutex_init(&b->lock, NULL);
    if (pthread_create(&b->thread, NULL, run, b) != 0) {
        builder_free(b);
        mr_fail(err, MR_ERR_NOMEM, "cannot start the LOD thread");
        return NULL;
    }
    return b;
}

bool mr_lod_builder_poll(mr_lod_builder *b, double *fraction) {
    if (!b) return true;
    pthread_mutex_lock(&b->lock);
    bool done = b->done;
    if (fraction) *fraction = done ? 1.0 : b->fraction;
    pthread_mutex_unlock(&b->lock);
    return done;
}

mr_lod_builder *mr_lod_build_async(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                                   mr_error *err) {
    return start(s, cache_path, params, NULL, NULL, err);
}

mr_lod_builder *mr_lod_build_async_hlod(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                                        const char *hlod_mode, const char *hlod_cache_path, mr_error *err) {
    return start(s, cache_path, params, hlod_mode ? hlod_mode : "auto", hlod_cache_path, err);
}

mr_lod *mr_lod_builder_finish(mr_lod_builder **bp, mr_lod_info *info, mr_error *err) {
    return mr_lod_builder_finish_hlod(bp, info, NULL, err);
}

mr_lod *mr_lod_builder_finish_hlod(mr_lod_builder **bp, mr_lod_info *info, mr_hlod **hlod, mr_error *err) {
    mr_lod_builder *b = bp ? *bp : NULL;
    if (hlod) *hlod = NULL;
    if (!b) {
        mr_fail(err, MR_ERR_INVALID, "mr_lod_builder_finish: no builder");
        return NULL;
    }
    *bp = NULL;
    pthread_join(b->thread, NULL);
    mr_lod *l = b->lod;
    if (hlod) *hlod = b->hlod;
    else mr_hlod_destroy(&b->hlod);
    if (info) *info = b->info;
    if (!l && err) *err = b->err;
    builder_free(b);
    return l;
}

void mr_lod_builder_cancel(mr_lod_builder **bp) {
    mr_lod_builder *b = bp ? *bp : NULL;
    if (!b) return;
    pthread_mutex_lock(&b->lock);
    b->cancel = true;
    pthread_mutex_unlock(&b->lock);
    mr_lod *l = mr_lod_builder_finish(bp, NULL, NULL); /* and its hierarchy */
    mr_lod_destroy(&l); /* a build that ended before it saw the cancel */
}
