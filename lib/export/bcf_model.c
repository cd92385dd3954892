/* A BCF archive as data: growing its lists, its warnings, finding a topic,
 * freeing it. */
#include "export_internal.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* A zeroed item appended to *list (count in *n); NULL when out of memory. */
static void *push(void **list, int *n, size_t size) {
    if (*n >= (1 << 24)) return NULL;
    /* Capacity doubles at powers of two: the count alone says when to grow. */
    int cap = 1;
    while (cap < *n) cap *= 2;
    if (*n == 0 || *n == cap) {
        void *p = realloc(*list, (size_t)(*n ? 2 * cap : 1) * size);
        if (!p) return NULL;
        *list = p;
    }
    char *item = (char *)*list + (size_t)*n * size;
    memset(item, 0, size);
    (*n)++;
    return item;
}

mr_bcf_topic *mr_bcf_add_topic(mr_bcf *b) {
    mr_bcf_topic *t = push((void **)&b->topics, &b->topic_count, sizeof *t);
    if (t) t->index = -1;
    return t;
}

mr_bcf_comment *mr_bcf_add_comment(mr_bcf_topic *t) {
    mr_bcf_comment *c = push((void **)&t->comments, &t->comment_count, sizeof *c);
    if (!c) return NULL;
    c->text = calloc(1, 1);
    if (!c->text) {
        t->comment_count--;
        return NULL;
    }
    return c;
}

mr_bcf_viewpoint *mr_bcf_add_viewpoint(mr_bcf_topic *t) {
    mr_bcf_viewpoint *v = push((void **)&t->viewpoints, &t->viewpoint_count, sizeof *v);
    if (v) v->index = -1;
    return v;
}

bool mr_bcf_add_component(mr_bcf_component **list, int *count, const mr_bcf_component *c) {
    mr_bcf_component *d = push((void **)list, count, sizeof *d);
    if (!d) return false;
    *d = *c;
    return true;
}

mr_bcf_coloring *mr_bcf_add_coloring(mr_bcf_viewpoint *v, uint32_t argb) {
    mr_bcf_coloring *c = push((void **)&v->colorings, &v->coloring_count, sizeof *c);
    if (c) c->argb = argb;
    return c;
}

void mr_bcf_warn(mr_bcf *b, const char *fmt, ...) {
    /* A hostile archive could warn without end: the first thousand say enough. */
    if (b->warning_count >= 1000) return;
    char(*w)[256] = push((void **)&b->warnings, &b->warning_count, sizeof *w);
    if (!w) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(*w, sizeof *w, fmt, ap);
    va_end(ap);
}

static void free_viewpoint(mr_bcf_viewpoint *v) {
    free(v->selection);
    free(v->exceptions);
    for (int i = 0; i < v->coloring_count; i++) free(v->colorings[i].items);
    free(v->colorings);
    free(v->clips);
    free(v->snapshot);
}

void mr_bcf_free(mr_bcf *b) {
    if (!b) return;
    for (int i = 0; i < b->topic_count; i++) {
        mr_bcf_topic *t = &b->topics[i];
        for (int c = 0; c < t->comment_count; c++) free(t->comments[c].text);
        free(t->comments);
        for (int v = 0; v < t->viewpoint_count; v++) free_viewpoint(&t->viewpoints[v]);
        free(t->viewpoints);
        free(t->description);
    }
    free(b->topics);
    free(b->warnings);
    memset(b, 0, sizeof *b);
}

mr_bcf_topic *mr_bcf_find_topic(mr_bcf *b, const char *sel, mr_error *err) {
    if (!sel || !sel[0]) {
        mr_fail(err, MR_ERR_INVALID, "no topic named");
        return NULL;
    }
    char *end = NULL;
    long n = strtol(sel, &end, 10);
    if (end && !*end && strlen(sel) < 9) {
        if (n >= 1 && n <= b->topic_count) return &b->topics[n - 1];
        mr_fail(err, MR_ERR_INVALID, "topic %s: the archive has %d topic(s)", sel, b->topic_count);
        return NULL;
    }
    mr_bcf_topic *found = NULL;
    size_t len = strlen(sel);
    for (int i = 0; i < b->topic_count; i++)
        if (strncasecmp(b->topics[i].guid, sel, len) == 0) {
            if (found) {
                mr_fail(err, MR_ERR_INVALID, "topic %s: more than one topic's GUID starts so", sel);
                return NULL;
            }
            found = &b->topics[i];
        }
    if (!found) mr_fail(err, MR_ERR_INVALID, "topic %s: no topic has that GUID", sel);
    return found;
}
