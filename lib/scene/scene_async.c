/* Loading off the caller's thread: a window's event loop starts a load,
 * polls it once per frame (progress for a bar) and takes the scene when it
 * is done, so a big load never blocks drawing or input. */
#include "mr_scene.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

struct mr_scene_loader {
    pthread_t thread;
    pthread_mutex_t lock;
    char *path;
    mr_scene_params params;     /* progress hooked to this loader */
    void (*user_progress)(void *, const char *, double);
    void *user_data;
    const char *stage;          /* guarded by lock */
    double fraction;
    bool done;
    mr_scene *scene;
    mr_error err;
};

static void on_progress(void *user, const char *stage, double fraction) {
    mr_scene_loader *l = user;
    pthread_mutex_lock(&l->lock);
    l->stage = stage;
    l->fraction = fraction;
    pthread_mutex_unlock(&l->lock);
    if (l->user_progress) l->user_progress(l->user_data, stage, fraction);
}

static void *run(void *arg) {
    mr_scene_loader *l = arg;
    mr_error err = {0};
    mr_scene *s = mr_scene_load(l->path, &l->params, &err);
    pthread_mutex_lock(&l->lock);
    l->scene = s;
    l->err = err;
    l->done = true;
    pthread_mutex_unlock(&l->lock);
    return NULL;
}

mr_scene_loader *mr_scene_load_async(const char *path, const mr_scene_params *params, mr_error *err) {
    if (!path) {
        mr_fail(err, MR_ERR_INVALID, "mr_scene_load_async: no path");
        return NULL;
    }
    mr_scene_loader *l = calloc(1, sizeof *l);
    if (!l || !(l->path = strdup(path))) {
        free(l);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    mr_scene_params d = MR_SCENE_DEFAULTS;
    l->params = params ? *params : d;
    l->user_progress = l->params.progress;
    l->user_data = l->params.progress_user;
    l->params.progress = on_progress;
    l->params.progress_user = l;
    l->stage = "start";
    pthread_mutex_init(&l->lock, NULL);
    if (pthread_create(&l->thread, NULL, run, l) != 0) {
        pthread_mutex_destroy(&l->lock);
        free(l->path);
        free(l);
        mr_fail(err, MR_ERR_NOMEM, "cannot start a loader thread");
        return NULL;
    }
    return l;
}

bool mr_scene_loader_poll(mr_scene_loader *l, const char **stage, double *fraction) {
    if (!l) return true;
    pthread_mutex_lock(&l->lock);
    bool done = l->done;
    if (stage) *stage = done ? "done" : l->stage;
    if (fraction) *fraction = done ? 1.0 : l->fraction;
    pthread_mutex_unlock(&l->lock);
    return done;
}

mr_scene *mr_scene_loader_finish(mr_scene_loader **lp, mr_error *err) {
    if (!lp || !*lp) {
        mr_fail(err, MR_ERR_INVALID, "no loader");
        return NULL;
    }
    mr_scene_loader *l = *lp;
    pthread_join(l->thread, NULL);
    mr_scene *s = l->scene;
    if (!s && err) *err = l->err;
    pthread_mutex_destroy(&l->lock);
    free(l->path);
    free(l);
    *lp = NULL;
    return s;
}
