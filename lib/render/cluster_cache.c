/* Meshlet cache beside the scene file; the format
 * and the rules are in cluster_cache.h. */
#include "cluster_cache.h"

#include "mr_core.h"

#include <math.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>

#define CLU_VERSION 2u /* 2: meshlets scanned in vertex-cache order */
#define CLU_HEADER 64
#define CLU_ENTRY 40
static const char k_magic[8] = {'M', 'R', 'C', 'L', 'U', '\r', '\n', 0x1a};

uint64_t clu_level_key(const float *positions, uint32_t vertex_count, const uint32_t *indices, uint32_t count,
                       uint32_t threshold) {
    uint64_t h = mr_hash64_mix(0x6d72636c75ull, ((uint64_t)CLU_VERSION << 32) | threshold);
    h = mr_hash64_mix(h, ((uint64_t)CL_VERTS << 32) | CL_TRIS);
    h = mr_hash64_mix(h, MESHOPTIMIZER_VERSION);
    h = mr_hash64(h, positions, (size_t)vertex_count * 12);
    return mr_hash64(h, indices, (size_t)count * 4);
}

static void put32(uint8_t *p, uint32_t v) { memcpy(p, &v, 4); }
static void put64(uint8_t *p, uint64_t v) { memcpy(p, &v, 8); }
static uint32_t get32(const uint8_t *p) {
    uint32_t v;
    memcpy(&v, p, 4);
    return v;
}
static uint64_t get64(const uint8_t *p) {
    uint64_t v;
    memcpy(&v, p, 8);
    return v;
}

static int level_cmp(const void *a, const void *b) {
    const clu_level *x = a, *y = b;
    if (x->mesh != y->mesh) return x->mesh < y->mesh ? -1 : 1;
    return (x->level > y->level) - (x->level < y->level);
}

/* Every meshlet and index of an entry in range; NULL or the reason. */
static const char *check_level(const clu_level *lv) {
    if (lv->mesh < 0 || lv->level < 0 || lv->out_count > lv->in_count || lv->out_count % 3)
        return "an entry's counts are out of range";
    uint64_t at = 0;
    for (uint32_t k = 0; k < lv->cluster_count; k++) {
        const geo_cluster *q = &lv->clusters[k];
        if (q->first != at || q->count == 0 || q->count % 3 || q->count > 3 * CL_TRIS) return "a meshlet's range is wrong";
        at += q->count;
        bool fin = isfinite(q->radius) && isfinite(q->cutoff);
        for (int j = 0; j < 3; j++) fin = fin && isfinite(q->center[j]) && isfinite(q->apex[j]) && isfinite(q->axis[j]);
        if (!fin) return "a meshlet's bounds are not finite";
        if (!(q->radius >= 0) || !(q->cutoff >= -1 && q->cutoff <= 1)) return "a meshlet's bounds are out of range";
    }
    if (at != lv->out_count) return "the meshlets do not cover the level";
    for (uint32_t i = 0; i < lv->out_count; i++)
        if (lv->indices[i] >= lv->vertex_count) return "an index is out of range";
    return NULL;
}

static const char *parse(clu_cache *c, size_t size) {
    const uint8_t *d = c->file;
    if (size < CLU_HEADER || memcmp(d, k_magic, 8) != 0) return "not a cluster cache";
    if (get32(d + 8) != CLU_VERSION) return "another format version";
    if (get32(d + 12) != CL_VERTS || get32(d + 16) != CL_TRIS || get32(d + 20) != c->threshold ||
        get32(d + 24) != MESHOPTIMIZER_VERSION)
        return "built with other meshlet settings";
    uint32_t n = get32(d + 28);
    uint64_t payload = get64(d + 32);
    if (payload != size - CLU_HEADER) return "truncated or too long";
    if (get64(d + 40) != mr_hash64(0x636c75, d + CLU_HEADER, (size_t)payload)) return "checksum mismatch (damaged)";
    if (n > payload / CLU_ENTRY) return "entry count out of range";
    c->old = calloc((size_t)n + 1, sizeof *c->old);
    if (!c->old) return "out of memory";
    size_t at = CLU_HEADER;
    for (uint32_t e = 0; e < n; e++) {
        if (size - at < CLU_ENTRY) return "truncated entry";
        const uint8_t *h = d + at;
        clu_level *lv = &c->old[e];
        lv->mesh = (int32_t)get32(h);
        lv->level = (int32_t)get32(h + 4);
        lv->key = get64(h + 8);
        lv->in_count = get32(h + 16);
        lv->vertex_count = get32(h + 20);
        lv->out_count = get32(h + 24);
        lv->cluster_count = get32(h + 28);
        uint64_t need = (uint64_t)lv->cluster_count * sizeof(geo_cluster) + (uint64_t)lv->out_count * 4;
        at += CLU_ENTRY;
        if (need > size - at) return "an entry reaches past the end";
        lv->clusters = (const geo_cluster *)(const void *)(d + at);
        lv->indices = (const uint32_t *)(const void *)(d + at + (size_t)lv->cluster_count * sizeof(geo_cluster));
        at += (size_t)need;
        const char *why = check_level(lv);
        if (why) return why;
        c->old_count = e + 1;
    }
    if (at != size) return "trailing bytes";
    qsort(c->old, c->old_count, sizeof *c->old, level_cmp);
    for (size_t i = 1; i < c->old_count; i++)
        if (level_cmp(&c->old[i - 1], &c->old[i]) == 0) return "a level appears twice";
    return NULL;
}

void clu_cache_open(clu_cache *c, const char *path, uint32_t threshold) {
    memset(c, 0, sizeof *c);
    snprintf(c->path, sizeof c->path, "%s", path);
    c->threshold = threshold;
    size_t size = 0;
    mr_error e = {0};
    FILE *f = fopen(path, "rb");
    if (!f) return; /* no cache yet: built and written, silently */
    fclose(f);
    c->file = mr_file_read(path, &size, 0, &e);
    const char *why = c->file ? parse(c, size) : e.msg;
    if (why) {
        mr_log(MR_LOG_WARN, "%s: ignored (%s); rebuilding the meshlets", path, why);
        free(c->file);
        free(c->old);
        c->file = NULL;
        c->old = NULL;
        c->old_count = 0;
    }
}

const clu_level *clu_cache_find(const clu_cache *c, int32_t mesh, int32_t level, uint64_t key, uint32_t in_count,
                                uint32_t vertex_count) {
    clu_level probe;
    memset(&probe, 0, sizeof probe);
    probe.mesh = mesh;
    probe.level = level;
    const clu_level *lv = c->old_count ? bsearch(&probe, c->old, c->old_count, sizeof *c->old, level_cmp) : NULL;
    if (!lv || lv->key != key || lv->in_count != in_count || lv->vertex_count != vertex_count) return NULL;
    return lv;
}

bool clu_cache_add(clu_cache *c, const clu_level *lv) {
    if (c->cur_count == c->cur_cap) {
        size_t cap = c->cur_cap ? 2 * c->cur_cap : 64;
        clu_level *p = realloc(c->cur, cap * sizeof *p);
        if (!p) {
            if (lv->owned) {
                free((void *)lv->clusters);
                free((void *)lv->indices);
            }
            c->path[0] = 0; /* incomplete: not written */
            return false;
        }
        c->cur = p;
        c->cur_cap = cap;
    }
    c->cur[c->cur_count++] = *lv;
    if (lv->owned) c->dirty = true;
    return true;
}

static bool write_file(clu_cache *c) {
    /* This upload's levels, and the file's others (levels not uploaded
     * this time), sorted by (mesh, level). */
    size_t n = c->cur_count, total = CLU_HEADER;
    clu_level *all = malloc((c->cur_count + c->old_count + 1) * sizeof *all);
    if (!all) return false;
    memcpy(all, c->cur, c->cur_count * sizeof *all);
    qsort(all, n, sizeof *all, level_cmp);
    size_t ncur = n;
    for (size_t i = 0; i < c->old_count; i++)
        if (!bsearch(&c->old[i], all, ncur, sizeof *all, level_cmp)) all[n++] = c->old[i];
    qsort(all, n, sizeof *all, level_cmp);
    for (size_t i = 0; i < n; i++)
        total += CLU_ENTRY + (size_t)all[i].cluster_count * sizeof(geo_cluster) + (size_t)all[i].out_count * 4;
    uint8_t *buf = malloc(total);
    bool ok = buf != NULL && n <= UINT32_MAX;
    size_t at = CLU_HEADER;
    for (size_t i = 0; ok && i < n; i++) {
        const clu_level *lv = &all[i];
        uint8_t *h = buf + at;
        put32(h, (uint32_t)lv->mesh);
        put32(h + 4, (uint32_t)lv->level);
        put64(h + 8, lv->key);
        put32(h + 16, lv->in_count);
        put32(h + 20, lv->vertex_count);
        put32(h + 24, lv->out_count);
        put32(h + 28, lv->cluster_count);
        put64(h + 32, 0);
        at += CLU_ENTRY;
        memcpy(buf + at, lv->clusters, (size_t)lv->cluster_count * sizeof(geo_cluster));
        at += (size_t)lv->cluster_count * sizeof(geo_cluster);
        memcpy(buf + at, lv->indices, (size_t)lv->out_count * 4);
        at += (size_t)lv->out_count * 4;
    }
    if (ok) {
        memset(buf, 0, CLU_HEADER);
        memcpy(buf, k_magic, 8);
        put32(buf + 8, CLU_VERSION);
        put32(buf + 12, CL_VERTS);
        put32(buf + 16, CL_TRIS);
        put32(buf + 20, c->threshold);
        put32(buf + 24, MESHOPTIMIZER_VERSION);
        put32(buf + 28, (uint32_t)n);
        put64(buf + 32, total - CLU_HEADER);
        put64(buf + 40, mr_hash64(0x636c75, buf + CLU_HEADER, total - CLU_HEADER));
        mr_error e = {0};
        ok = mr_file_write_atomic(c->path, buf, total, &e);
        if (!ok) mr_log(MR_LOG_WARN, "meshlet cache not written: %s", e.msg);
    }
    free(buf);
    free(all);
    return ok;
}

bool clu_cache_close(clu_cache *c, bool write) {
    bool written = write && c->dirty && c->path[0] && write_file(c);
    for (size_t i = 0; i < c->cur_count; i++)
        if (c->cur[i].owned) {
            free((void *)c->cur[i].clusters);
            free((void *)c->cur[i].indices);
        }
    free(c->cur);
    free(c->old);
    free(c->file);
    c->cur = c->old = NULL;
    c->file = NULL;
    c->cur_count = c->old_count = c->cur_cap = 0;
    return written;
}
