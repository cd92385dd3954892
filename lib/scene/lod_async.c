/* LOD levels off the caller's thread: a window's event loop starts the
 * build (or the cache read), draws the full detail meanwhile, polls once per
 * frame and takes the levels when they are done; quitting cancels a build
 * of many seconds after the meshes in progress instead of waiting for it. */
#include "mr_scene.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

struct mr_lod_builder {
    pthread_t thread;
    pthread_mutex_t lock;
    const mr_scene *scene;
    char *cache_path;     /* NULL: no cache */
    mr_lod_params params; /* on_progress hooked to this builder */
    bool (*user_progress)(void *, double);
    void *user_data;
    /* guarded by lock */
    double fraction;
    bool cancel, done;
    mr_lod *lod;
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
    pthread_mutex_lock(&b->lock);
    b->lod = l;
    b->info = info;
    b->err = err;
    b->done = true;
    pthread_mutex_unlock(&b->lock);
    return NULL;
}

static void builder_free(mr_lod_builder *b) {
    pthread_mutex_destroy(&b->lock);
    free(b->cache_path);
    free(b);
}

mr_lod_builder *mr_lod_build_async(const mr_scene *s, const char *cache_path, const mr_lod_params *params,
                                   mr_error *err) {
    if (!s) {
        mr_fail(err, MR_ERR_INVALID, "mr_lod_build_async: no scene");
        return NULL;
    }
    mr_lod_builder *b = calloc(1, sizeof *b);
    if (!b || (cache_path && !(b->cache_path = strdup(cache_path)))) {
        free(b);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    b->scene = s;
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

mr_lod *mr_lod_builder_finish(mr_lod_builder **bp, mr_lod_info *info, mr_error *err) {
    mr_lod_builder *b = bp ? *bp : NULL;
    if (!b) {
        mr_fail(err, MR_ERR_INVALID, "mr_lod_builder_finish: no builder");
        return NULL;
    }
    *bp = NULL;
    pthread_join(b->thread, NULL);
    mr_lod *l = b->lod;
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
    mr_lod *l = mr_lod_builder_finish(bp, NULL, NULL);
    mr_lod_destroy(&l); /* a build that ended before it saw the cancel */
}
