/* Meshlet cache beside the scene file: the
 * meshlets of every clustered mesh level (their reordered indices and
 * meshopt's bounds), so a second upload of the same file does not rebuild
 * them. Internal to lib/render (geometry.c and cluster_cache.c).
 *
 * File "<scene>.mrclu": a header (magic, format version, meshlet limits,
 * cluster threshold, meshoptimizer version, entry count, size, checksum of
 * everything after the header), then one entry per clustered level: its
 * mesh and level, a key hashing the level's input (its indices, the mesh's
 * positions, the threshold and the limits), its counts, its meshlets and
 * their indices. A level is taken from the file only if its key and counts
 * match and every meshlet and index is in range; a file that is short,
 * damaged, of another version or otherwise wrong is ignored with one
 * warning, and the levels are built and the file rewritten (temp + rename,
 * so a reader never sees half a file). Entries of levels not uploaded this
 * time (the scene's first upload has no LOD levels yet) are kept. */
#ifndef MR_CLUSTER_CACHE_H
#define MR_CLUSTER_CACHE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define CL_VERTS 64
#define CL_TRIS 124

/* One meshlet: its contiguous index range in the shared index buffer and
 * meshopt's bounds, in the mesh's own (vertex) coordinates: float is
 * enough there, the instance's camera-relative double transform carries
 * them to the camera. In the cache, `first` is relative to its level. */
typedef struct geo_cluster {
    uint32_t first, count;          /* index range (global offset, indices) */
    float center[3], radius;        /* bounding sphere */
    float apex[3], axis[3], cutoff; /* back-facing cone */
} geo_cluster;

typedef struct clu_level {
    int32_t mesh, level;
    uint64_t key;
    uint32_t in_count;      /* indices given to the meshlet builder */
    uint32_t vertex_count;  /* of the mesh: every index is below */
    uint32_t out_count;     /* indices written, meshlet by meshlet */
    uint32_t cluster_count;
    const geo_cluster *clusters; /* first relative to the level */
    const uint32_t *indices;
    bool owned;             /* built this time: clusters/indices are malloc'd */
} clu_level;

typedef struct clu_cache {
    char path[4096];
    uint32_t threshold;
    uint8_t *file;          /* the file read at open (entries point into it) */
    clu_level *old;
    size_t old_count;
    clu_level *cur;         /* levels of this upload */
    size_t cur_count, cur_cap;
    bool dirty;             /* a level was built: rewrite at close */
} clu_cache;

/* Key of one level's meshlets. */
uint64_t clu_level_key(const float *positions, uint32_t vertex_count, const uint32_t *indices, uint32_t count,
                       uint32_t threshold);
/* Reads and checks the file (a missing file is silent, a bad one warns). */
void clu_cache_open(clu_cache *c, const char *path, uint32_t threshold);
/* The file's entry for this level, or NULL. */
const clu_level *clu_cache_find(const clu_cache *c, int32_t mesh, int32_t level, uint64_t key, uint32_t in_count,
                                uint32_t vertex_count);
/* Records a level of this upload (owned: the cache frees clusters and
 * indices); false if out of memory (then the cache is not written). */
bool clu_cache_add(clu_cache *c, const clu_level *lv);
/* Writes the file if a level was built (write: the upload succeeded);
 * frees everything. Returns true if the file was written. */
bool clu_cache_close(clu_cache *c, bool write);

#endif
