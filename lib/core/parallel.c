/* mr_parallel_for: the one worker loop of the LOD build, the ray-traced
 * references and the meshlet build. */
#include "mr_core.h"

#include <pthread.h>
#include <unistd.h>

typedef struct pfor {
    size_t count, next;
    bool stopped;
    bool (*fn)(void *ctx, size_t i);
    void *ctx;
    pthread_mutex_t lock;
} pfor;

static void *pfor_worker(void *arg) {
    pfor *q = arg;
    for (;;) {
        pthread_mutex_lock(&q->lock);
        size_t i = q->stopped ? q->count : q->next;
        if (i < q->count) q->next++;
        pthread_mutex_unlock(&q->lock);
        if (i >= q->count) return NULL;
        if (!q->fn(q->ctx, i)) {
            pthread_mutex_lock(&q->lock);
            q->stopped = true;
            pthread_mutex_unlock(&q->lock);
        }
    }
}

bool mr_parallel_for(size_t count, int threads, bool (*fn)(void *ctx, size_t i), void *ctx) {
    if (count == 0 || !fn) return true;
    long nt = threads > 0 ? threads : sysconf(_SC_NPROCESSORS_ONLN);
    if (nt < 1) nt = 1;
    if (nt > 64) nt = 64;
    if ((size_t)nt > count) nt = (long)count;
    pfor q = {count, 0, false, fn, ctx, PTHREAD_MUTEX_INITIALIZER};
    pthread_t th[64];
    int started = 0;
    for (long t = 1; t < nt; t++)
        if (pthread_create(&th[started], NULL, pfor_worker, &q) == 0) started++;
    pfor_worker(&q); /* this thread works too */
    for (int t = 0; t < started; t++) pthread_join(th[t], NULL);
    pthread_mutex_destroy(&q.lock);
    return !q.stopped;
}
