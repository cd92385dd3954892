/* Geometry: the scene on the GPU and its submission into the G-buffer.
 *
 * Upload: all meshes share a few large buffers, one interleaved vertex
 * buffer per vertex layout (position + normal; position + normal + uv for
 * textured meshes, so UVs cost nothing where no texture is sampled) and one
 * index buffer holding every mesh's full index list followed by its LOD
 * levels. A mesh is (layout, base vertex, first index, count) into them, so
 * a glTF mesh used by many nodes is stored once and drawn as instances.
 *
 * Per draw: the BVH (double precision, world space) culls nodes against the
 * frustum; each visible (node, mesh) pair picks a LOD level, and the pairs
 * are bucketed by (draw group, mesh, level) with a counting sort. One bucket
 * is one indirect command whose instances read their camera-relative
 * matrices (composed in double per instance, then cast to float), colour
 * and ids as per-instance attributes; all commands of a group (layout + texture) go out in
 * one glMultiDrawElementsIndirect. GL calls therefore grow with the number
 * of textures, not with the number of nodes, and a culled node costs nothing
 * on the GPU. */
#include "geo_internal.h"
#include "cluster_cache.h"
#include "occ_rule.h"

#include <math.h>
#include <meshoptimizer.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#define LEVELS (MR_LOD_MAX_LEVELS + 1) /* full detail + simplified levels */

typedef struct geo_mesh {
    int32_t group;                 /* draw group: 0 untextured, 1 + t for texture t */
    int32_t pool;                  /* vertex layout: 0 pos+normal, 1 pos+normal+uv */
    int32_t base_vertex;
    int32_t level_count;           /* 1 + simplified levels */
    uint32_t first[LEVELS], count[LEVELS];
    double error[LEVELS];          /* certified error of each level, mesh units */
    float color[4];
    uint32_t has_tex;
    uint32_t cl_first[LEVELS], cl_count[LEVELS]; /* meshlets of each level in mr_geo.clusters */
    bool single_sided;             /* its material's back faces are culled */
} geo_mesh;

/* One meshlet: geo_cluster, in cluster_cache.h (the meshlets are cached
 * beside the file). */

/* The face-culling class of a (node, mesh) pair:
 * both faces drawn; single-sided; single-sided under a mirroring node (glTF:
 * a negative determinant turns the front face clockwise). Classes are the
 * outermost sort key, so each (class, draw group) is one contiguous run of
 * commands, submitted with its own face-culling state. */
enum { CLS_DOUBLE, CLS_SINGLE, CLS_MIRROR, CLS_COUNT };

typedef struct geo_rec {
    int32_t node, mesh;
    uint32_t key;                  /* (class * meshes + rank(mesh)) * LEVELS + level */
} geo_rec;

struct mr_geo {
    GLuint vao[2], vbo[2], ibo;
    GLuint inst_buf;               /* instance records (per-instance attributes) */
    uint32_t inst_cap;
    GLuint cmd_buf;
    geo_mesh *meshes;
    int32_t mesh_count;
    int32_t *rank;                 /* mesh -> position in group order */
    int32_t *by_rank;              /* position -> mesh */
    int32_t group_count;
    double *node_scale;            /* upper bound of each node's linear stretch */
    mr_bvh *bvh;
    const mr_lod *lod;
    size_t max_recs;               /* (node, mesh) pairs over all nodes */
    uint32_t drawable[MR_LAYER_COUNT]; /* nodes that draw something, per layer */
    /* per-draw scratch, sized at upload */
    int32_t *visible;
    geo_rec *recs, *sorted;
    uint32_t *key_count;           /* mesh_count * LEVELS + 1 */
    gpu_instance *inst;
    draw_cmd *cmds;
    int32_t *group_first, *group_cmds;
    /* occlusion culling scratch */
    int32_t *occ_rest;
    float *depth, *hz;
    size_t depth_cap, hz_cap, hz_off[24];
    int hz_w[24], hz_h[24];
    occ_auto occ;                  /* the automatic decision (occ_rule.h) */
    double occ_rb_ms;              /* read-back of a finished frame, ms (< 0: not measured) */
    int occ_rb_w, occ_rb_h;
    geo_cluster *clusters;
    uint32_t cluster_count;
    size_t cmd_cap;                /* g->cmds (clusters add commands) */
    uint8_t *node_mirror;          /* the node's world 3x3 has a negative determinant */
    clu_cache *cc;                 /* during upload: the meshlet cache (NULL: none) */
    int occ_levels;                /* > 0 while the occluded-tested nodes are drawn: meshlets test the pyramid too */
    int occ_w, occ_h;
    uint64_t occ_cl_tris;          /* triangles of the meshlets it skipped this frame */
    double occ_cl_ms;              /* and what testing them cost */
};

/* ------------------------------------------------------------- params */

bool mr_renderer_set_draw_params(mr_renderer *r, const mr_draw_params *params, mr_error *err) {
    if (!r) return mr_fail(err, MR_ERR_INVALID, "no renderer");
    mr_draw_params d = MR_DRAW_DEFAULTS;
    if (params) d = *params;
    if (!isfinite(d.lod_tolerance) || !isfinite(d.lod_pixels) || d.lod_pixels < 0)
        return mr_fail(err, MR_ERR_INVALID, "LOD tolerance and pixel error must be finite, pixels >= 0");
    r->draw = d;
    return true;
}

void mr_renderer_draw_stats(const mr_renderer *r, mr_draw_stats *out) {
    if (!out) return;
    if (!r) {
        memset(out, 0, sizeof *out);
        return;
    }
    *out = r->stats;
}

void mr_geometry_begin_frame(mr_renderer *r) { memset(&r->stats, 0, sizeof r->stats); }

bool mr_renderer_set_cluster_cache(mr_renderer *r, const char *path, mr_error *err) {
    if (!r) return mr_fail(err, MR_ERR_INVALID, "no renderer");
    if (path && strlen(path) >= sizeof r->cluster_cache)
        return mr_fail(err, MR_ERR_INVALID, "meshlet cache path too long");
    snprintf(r->cluster_cache, sizeof r->cluster_cache, "%s", path ? path : "");
    return true;
}

void mr_renderer_cluster_info(const mr_renderer *r, mr_cluster_info *out) {
    if (!out) return;
    if (!r) memset(out, 0, sizeof *out);
    else *out = r->cluster_info;
}

void mr_cluster_cache_path(const char *scene_path, char *out, size_t n) {
    if (n) snprintf(out, n, "%s.mrclu", scene_path ? scene_path : "");
}

/* ------------------------------------------------------------- upload */

void mr_geometry_free(mr_renderer *r) {
    mr_geometry_share_end(r); /* its lists index this geometry */
    mr_hlod_gpu_free(r);      /* its proxies name this scene's nodes */
    struct mr_geo *g = r->geo;
    if (g) {
        glDeleteVertexArrays(2, g->vao);
        glDeleteBuffers(2, g->vbo);
        glDeleteBuffers(1, &g->ibo);
        glDeleteBuffers(1, &g->inst_buf);
        glDeleteBuffers(1, &g->cmd_buf);
        free(g->meshes);
        free(g->rank);
        free(g->by_rank);
        free(g->node_scale);
        mr_bvh_destroy(&g->bvh);
        free(g->visible);
        free(g->recs);
        free(g->sorted);
        free(g->key_count);
        free(g->inst);
        free(g->cmds);
        free(g->group_first);
        free(g->group_cmds);
        free(g->occ_rest);
        free(g->depth);
        free(g->hz);
        free(g->clusters);
        free(g->node_mirror);
        if (g->cc) clu_cache_close(g->cc, false); /* a failed upload writes nothing */
        free(g->cc);
        free(g);
        r->geo = NULL;
    }
    if (r->textures) glDeleteTextures(r->texture_count, r->textures);
    free(r->textures);
    r->textures = NULL;
    r->texture_count = 0;
    r->scene = NULL;
}

static bool upload_textures(mr_renderer *r, const mr_scene *s, mr_error *err) {
    r->textures = calloc((size_t)s->texture_count + 1, sizeof *r->textures);
    if (!r->textures) return mr_fail(err, MR_ERR_NOMEM, "out of memory uploading textures");
    for (int32_t i = 0; i < s->texture_count; i++) {
        const mr_texture *t = &s->textures[i];
        if (!t->image.data || t->image.channels != 4 || t->image.type != MR_PIX_U8)
            return mr_fail(err, MR_ERR_INVALID, "texture %d is not RGBA8", (int)i);
        int w = t->image.width, h = t->image.height, levels = 1;
        while ((w >> levels) > 0 || (h >> levels) > 0) levels++;
        GLuint tex;
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, levels, GL_SRGB8_ALPHA8, w, h);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTextureSubImage2D(tex, 0, 0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, t->image.data);
        glGenerateTextureMipmap(tex);
        glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, t->nearest ? GL_NEAREST : GL_LINEAR);
        r->textures[i] = tex;
        r->texture_count = i + 1;
    }
    return true;
}

/* Makes the instance buffer hold at least `need` records; the VAOs keep
 * pointing at it (binding 1). */
static bool ensure_instances(struct mr_geo *g, uint32_t need) {
    if (need <= g->inst_cap && g->inst_buf) return true;
    uint32_t cap = g->inst_cap ? g->inst_cap : 1024;
    while (cap < need) cap *= 2;
    glDeleteBuffers(1, &g->inst_buf);
    glCreateBuffers(1, &g->inst_buf);
    glNamedBufferStorage(g->inst_buf, (GLsizeiptr)cap * (GLsizeiptr)sizeof(gpu_instance), NULL, GL_DYNAMIC_STORAGE_BIT);
    g->inst_cap = cap;
    for (int p = 0; p < 2; p++) glVertexArrayVertexBuffer(g->vao[p], 1, g->inst_buf, 0, sizeof(gpu_instance));
    return glGetError() == GL_NO_ERROR;
}

/* Index data of one level into the shared index buffer. A level of at
 * least cluster_triangles triangles is split into meshlets first
 * (up to 64 vertices, 124 triangles; see build_meshlets) and its indices
 * are written meshlet by meshlet, so each meshlet is one contiguous range
 * that a draw can keep or skip (same triangles, another order). Done at
 * upload: about 60 ms of one core per million triangles, hence taken
 * from the cache beside the file where it has them. */

/* The meshlets of one level, without GL: clusters (firsts relative to the
 * level) and the indices meshlet by meshlet. Thread-safe: the upload builds
 * the levels on both cores (level_jobs). false if out of memory. */
typedef struct level_build {
    geo_cluster *clusters;
    uint32_t *out;
    size_t cnt, w;
} level_build;

/* Built by a scan of the level in vertex-cache order (meshopt's FIFO
 * optimiser, which walks adjacent triangles whatever the input order), not
 * by meshopt_buildMeshlets: measured on the 2M unique factory's full meshes
 * (one core), 0.12 s instead of 0.53 s with bounds, and over the same
 * meshes shuffled 0.15 s; the meshlets' spheres are 8 % larger but their
 * normal cones tighter (90 % instead of 77 % of the meshlets have a cone
 * that can cull, cutoff under 0.9: cone_weight 0 builds for locality
 * only). On a first load the meshlets are part of what the user waits
 * for. */
static bool build_meshlets(const mr_mesh *m, const uint32_t *indices, size_t n, level_build *b) {
    memset(b, 0, sizeof *b);
    size_t maxm = meshopt_buildMeshletsBound(n, CL_VERTS, CL_TRIS);
    struct meshopt_Meshlet *ml = malloc(maxm * sizeof *ml);
    unsigned int *mv = malloc(maxm * CL_VERTS * sizeof *mv);
    unsigned char *mt = malloc(maxm * CL_TRIS * 3);
    b->out = malloc((n + 1) * sizeof *b->out);
    bool ok = ml && mv && mt && b->out;
    /* The vertex-cache order goes into out: the scan has read all of it
     * before out is written meshlet by meshlet below (no second array of
     * fresh pages). */
    if (ok) meshopt_optimizeVertexCacheFifo(b->out, indices, n, m->vertex_count, 16);
    b->cnt = ok ? meshopt_buildMeshletsScan(ml, mv, mt, b->out, n, m->vertex_count, CL_VERTS, CL_TRIS) : 0;
    b->clusters = ok ? malloc((b->cnt + 1) * sizeof *b->clusters) : NULL;
    ok = ok && b->clusters;
    for (size_t c = 0; ok && c < b->cnt; c++) {
        const struct meshopt_Meshlet *me = &ml[c];
        geo_cluster *gc = &b->clusters[c];
        gc->first = (uint32_t)b->w;
        gc->count = me->triangle_count * 3;
        for (size_t t = 0; t < (size_t)me->triangle_count * 3; t++) b->out[b->w++] = mv[me->vertex_offset + mt[me->triangle_offset + t]];
        struct meshopt_Bounds bd = meshopt_computeMeshletBounds(mv + me->vertex_offset, mt + me->triangle_offset,
                                                                me->triangle_count, m->positions, m->vertex_count, 12);
        memcpy(gc->center, bd.center, sizeof gc->center);
        gc->radius = bd.radius;
        memcpy(gc->apex, bd.cone_apex, sizeof gc->apex);
        memcpy(gc->axis, bd.cone_axis, sizeof gc->axis);
        gc->cutoff = bd.cone_cutoff;
    }
    free(ml);
    free(mv);
    free(mt);
    if (!ok) {
        free(b->out);
        free(b->clusters);
        memset(b, 0, sizeof *b);
    }
    return ok;
}

/* A level to split into meshlets, looked up in the cache and, if not there,
 * built ahead of the upload on both cores (upload_level takes the result). */
typedef struct level_job {
    const mr_mesh *m;
    const uint32_t *indices;
    size_t n;
    int32_t mesh, level;
    uint64_t key;
    const clu_level *hit;
    level_build built;
    bool ok; /* built (or hit) */
} level_job;

static bool upload_level(mr_renderer *r, struct mr_geo *g, const mr_mesh *m, int32_t mi, int level,
                         const uint32_t *indices, level_job *job, mr_error *err) {
    geo_mesh *gm = &g->meshes[mi];
    size_t n = gm->count[level];
    int32_t thr = r->draw.cluster_triangles > 0 ? r->draw.cluster_triangles : MR_DRAW_DEFAULT_CLUSTER_TRIANGLES;
    gm->cl_first[level] = gm->cl_count[level] = 0;
    if (n / 3 < (size_t)thr || !m->positions || m->vertex_count == 0) {
        glNamedBufferSubData(g->ibo, (GLintptr)gm->first[level] * 4, (GLsizeiptr)n * 4, indices);
        return true;
    }
    /* The cache's copy of this level. */
    uint64_t key = 0;
    if (g->cc) {
        key = job ? job->key : clu_level_key(m->positions, m->vertex_count, indices, (uint32_t)n, (uint32_t)thr);
        const clu_level *hit = job ? job->hit : clu_cache_find(g->cc, mi, level, key, (uint32_t)n, m->vertex_count);
        geo_cluster *cl = hit ? realloc(g->clusters, ((size_t)g->cluster_count + hit->cluster_count + 1) * sizeof *cl) : NULL;
        if (hit && cl && clu_cache_add(g->cc, hit)) {
            g->clusters = cl;
            gm->cl_first[level] = g->cluster_count;
            gm->cl_count[level] = hit->cluster_count;
            for (uint32_t c = 0; c < hit->cluster_count; c++) {
                cl[g->cluster_count + c] = hit->clusters[c];
                cl[g->cluster_count + c].first += gm->first[level];
            }
            g->cluster_count += hit->cluster_count;
            gm->count[level] = hit->out_count;
            glNamedBufferSubData(g->ibo, (GLintptr)gm->first[level] * 4, (GLsizeiptr)hit->out_count * 4, hit->indices);
            r->cluster_info.levels_cached++;
            return true;
        }
        if (hit && cl) g->clusters = cl;
    }
    double t_build = mr_time_now();
    level_build b;
    bool ok;
    if (job && job->ok && !job->hit) {
        b = job->built; /* built ahead on both cores */
        memset(&job->built, 0, sizeof job->built);
        ok = true;
    } else {
        ok = build_meshlets(m, indices, n, &b);
    }
    geo_cluster *cl = ok ? realloc(g->clusters, ((size_t)g->cluster_count + b.cnt + 1) * sizeof *cl) : NULL;
    if (!cl) {
        free(b.out);
        free(b.clusters);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory building the meshlets of mesh '%s'", m->name);
    }
    g->clusters = cl;
    gm->cl_first[level] = g->cluster_count;
    gm->cl_count[level] = (uint32_t)b.cnt;
    for (size_t c = 0; c < b.cnt; c++) {
        cl[g->cluster_count + c] = b.clusters[c];
        cl[g->cluster_count + c].first += gm->first[level];
    }
    g->cluster_count += (uint32_t)b.cnt;
    size_t cnt = b.cnt, w = b.w;
    uint32_t *out = b.out;
    geo_cluster *rel = b.clusters; /* firsts relative to the level: the cache's form */
    /* meshopt drops degenerate triangles only if they repeat an index;
     * whatever it wrote is what the level draws. */
    gm->count[level] = (uint32_t)w;
    glNamedBufferSubData(g->ibo, (GLintptr)gm->first[level] * 4, (GLsizeiptr)w * 4, out);
    if (g->cc) {
        /* Into the cache, firsts relative to the level */
        clu_level lv = {mi, level, key, (uint32_t)n, m->vertex_count, (uint32_t)w, (uint32_t)cnt, rel, out, true};
        if (!clu_cache_add(g->cc, &lv)) {
            g->cc->path[0] = 0; /* incomplete: not written (clu_cache_add freed them) */
        }
        out = NULL; /* the cache owns them now */
        rel = NULL;
    }
    r->cluster_info.levels_built++;
    r->cluster_info.build_s += mr_time_now() - t_build;
    free(out);
    free(rel);
    return true;
}

typedef struct level_jobs {
    level_job *job;
    uint32_t threshold;
    const clu_cache *cc;
} level_jobs;

static bool level_run(void *arg, size_t k) {
    level_jobs *q = arg;
    level_job *j = &q->job[k];
    j->key = clu_level_key(j->m->positions, j->m->vertex_count, j->indices, (uint32_t)j->n, q->threshold);
    j->hit = clu_cache_find(q->cc, j->mesh, j->level, j->key, (uint32_t)j->n, j->m->vertex_count);
    j->ok = j->hit || build_meshlets(j->m, j->indices, j->n, &j->built);
    return true; /* a level that failed is built again (and fails) in upload_level */
}

/* The levels that get meshlets, looked up and built on both cores before
 * the upload (which is GL, one thread): measured, building them is most of
 * a first upload. Only with the cache: it keeps every built level until the
 * upload ends anyway, so building them ahead costs no memory beyond it.
 * NULL (and upload_level builds each itself) without the cache. */
static level_job *level_jobs_run(const mr_scene *s, const mr_lod *lod, const clu_cache *cc, uint32_t threshold,
                                 size_t *count_out) {
    *count_out = 0;
    if (!cc || s->mesh_count <= 0) return NULL;
    /* At most every level of every mesh (the full one and the simplified). */
    level_jobs q = {calloc((size_t)s->mesh_count * LEVELS, sizeof(level_job)), threshold, cc};
    if (!q.job) return NULL;
    size_t count = 0;
    for (int32_t i = 0; i < s->mesh_count; i++) {
        const mr_mesh *m = &s->meshes[i];
        if (!m->positions || m->vertex_count == 0) continue;
        if (m->index_count / 3 >= threshold) q.job[count++] = (level_job){m, m->indices, m->index_count, i, 0, 0, NULL, {0}, false};
        const mr_mesh_lods *ml = lod ? &lod->meshes[i] : NULL;
        for (int32_t k = 0, l = 1; ml && k < ml->level_count && k < MR_LOD_MAX_LEVELS; k++) {
            if (!ml->levels[k].indices || ml->levels[k].index_count == 0) continue;
            if (ml->levels[k].index_count / 3 >= threshold)
                q.job[count++] = (level_job){m, ml->levels[k].indices, ml->levels[k].index_count, i, l, 0, NULL, {0}, false};
            l++;
        }
    }
    mr_parallel_for(count, 0, level_run, &q);
    *count_out = count;
    return q.job;
}

static void level_jobs_free(level_job *job, size_t count) {
    for (size_t k = 0; job && k < count; k++) {
        free(job[k].built.out);
        free(job[k].built.clusters);
    }
    free(job);
}

/* The job of (mesh, level) in jobs (in upload order: *cursor walks it). */
static level_job *level_job_at(level_job *job, size_t count, size_t *cursor, int32_t mesh, int32_t level) {
    if (*cursor < count && job[*cursor].mesh == mesh && job[*cursor].level == level) return &job[(*cursor)++];
    return NULL;
}

void mr_geo_vao_instances(GLuint vao) {
    for (GLuint a = 0; a < MR_ATTR_INSTANCE_SLOTS; a++) {
        GLuint slot = MR_ATTR_INSTANCE + a;
        glEnableVertexArrayAttrib(vao, slot);
        if (slot == MR_ATTR_INST_IDS)
            glVertexArrayAttribIFormat(vao, slot, 4, GL_UNSIGNED_INT, (GLuint)offsetof(gpu_instance, ids));
        else glVertexArrayAttribFormat(vao, slot, 4, GL_FLOAT, GL_FALSE, a * 16);
        glVertexArrayAttribBinding(vao, slot, 1);
    }
    glVertexArrayBindingDivisor(vao, 1, 1);
}

static bool upload(mr_renderer *r, const mr_scene *s, const mr_lod *lod, mr_error *err) {
    if (lod && lod->mesh_count != s->mesh_count) lod = NULL;
    if (!upload_textures(r, s, err)) return false;
    struct mr_geo *g = calloc(1, sizeof *g);
    if (!g) return mr_fail(err, MR_ERR_NOMEM, "out of memory uploading the scene");
    r->geo = g;
    g->lod = lod;
    /* The meshlet cache beside the file */
    memset(&r->cluster_info, 0, sizeof r->cluster_info);
    if (r->cluster_cache[0] && !r->draw.no_cluster_cull) {
        g->cc = calloc(1, sizeof *g->cc);
        int32_t thr = r->draw.cluster_triangles > 0 ? r->draw.cluster_triangles : MR_DRAW_DEFAULT_CLUSTER_TRIANGLES;
        if (g->cc) clu_cache_open(g->cc, r->cluster_cache, (uint32_t)thr);
    }
    occ_auto_reset(&g->occ); /* the first frames measure */
    g->occ_rb_ms = -1;
    size_t nm = (size_t)s->mesh_count, nn = (size_t)s->node_count;
    g->mesh_count = s->mesh_count;
    g->meshes = calloc(nm + 1, sizeof *g->meshes);
    g->rank = calloc(nm + 1, sizeof *g->rank);
    g->by_rank = calloc(nm + 1, sizeof *g->by_rank);
    g->node_scale = calloc(nn + 1, sizeof *g->node_scale);
    g->group_count = 1 + s->texture_count;
    g->group_first = calloc((size_t)g->group_count * CLS_COUNT, sizeof *g->group_first);
    g->group_cmds = calloc((size_t)g->group_count * CLS_COUNT, sizeof *g->group_cmds);
    g->node_mirror = calloc(nn + 1, 1);
    if (!g->meshes || !g->rank || !g->by_rank || !g->node_scale || !g->group_first || !g->group_cmds || !g->node_mirror)
        return mr_fail(err, MR_ERR_NOMEM, "out of memory uploading the scene");

    /* Layout, group and place of each mesh in the shared buffers. */
    uint64_t verts[2] = {0, 0}, indices = 0;
    for (size_t i = 0; i < nm; i++) {
        const mr_mesh *m = &s->meshes[i];
        geo_mesh *gm = &g->meshes[i];
        const mr_material *mat = m->material >= 0 && m->material < s->material_count ? &s->materials[m->material] : NULL;
        bool textured = m->uvs && mat && mat->base_color_texture >= 0 && mat->base_color_texture < r->texture_count;
        gm->pool = textured ? 1 : 0;
        gm->group = textured ? 1 + mat->base_color_texture : 0;
        gm->has_tex = textured;
        static const float grey[4] = {0.7f, 0.7f, 0.7f, 1.0f};
        memcpy(gm->color, mat ? mat->base_color : grey, sizeof gm->color);
        gm->single_sided = mat && mat->single_sided;
        gm->base_vertex = (int32_t)verts[gm->pool];
        verts[gm->pool] += m->vertex_count;
        gm->level_count = 1;
        gm->first[0] = (uint32_t)indices;
        gm->count[0] = m->index_count;
        gm->error[0] = 0;
        indices += m->index_count;
        const mr_mesh_lods *ml = lod ? &lod->meshes[i] : NULL;
        for (int32_t k = 0; ml && k < ml->level_count && k < MR_LOD_MAX_LEVELS; k++) {
            if (!ml->levels[k].indices || ml->levels[k].index_count == 0) continue;
            int32_t l = gm->level_count++;
            gm->first[l] = (uint32_t)indices;
            gm->count[l] = ml->levels[k].index_count;
            gm->error[l] = ml->levels[k].error;
            indices += ml->levels[k].index_count;
        }
        if (verts[0] > INT32_MAX || verts[1] > INT32_MAX || indices > UINT32_MAX / 4 ||
            (nm + 1) * LEVELS * CLS_COUNT > UINT32_MAX)
            return mr_fail(err, MR_ERR_NOMEM, "scene too large for one upload (%llu vertices, %llu indices)",
                           (unsigned long long)(verts[0] + verts[1]), (unsigned long long)indices);
    }
    /* Meshes in group order, so that a group's commands are contiguous. */
    {
        int32_t pos = 0;
        for (int32_t grp = 0; grp < g->group_count; grp++)
            for (size_t i = 0; i < nm; i++)
                if (g->meshes[i].group == grp) {
                    g->rank[i] = pos;
                    g->by_rank[pos++] = (int32_t)i;
                }
    }

    /* The shared buffers, filled mesh by mesh (no scene-sized staging copy). */
    static const GLsizei stride[2] = {24, 32};
    for (int p = 0; p < 2; p++) {
        glCreateVertexArrays(1, &g->vao[p]);
        glCreateBuffers(1, &g->vbo[p]);
        glNamedBufferStorage(g->vbo[p], (GLsizeiptr)(verts[p] ? verts[p] : 1) * stride[p], NULL, GL_DYNAMIC_STORAGE_BIT);
        glVertexArrayVertexBuffer(g->vao[p], 0, g->vbo[p], 0, stride[p]);
        glEnableVertexArrayAttrib(g->vao[p], MR_ATTR_POSITION);
        glVertexArrayAttribFormat(g->vao[p], MR_ATTR_POSITION, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(g->vao[p], MR_ATTR_POSITION, 0);
        glEnableVertexArrayAttrib(g->vao[p], MR_ATTR_NORMAL);
        glVertexArrayAttribFormat(g->vao[p], MR_ATTR_NORMAL, 3, GL_FLOAT, GL_FALSE, 12);
        glVertexArrayAttribBinding(g->vao[p], MR_ATTR_NORMAL, 0);
        if (p == 1) {
            glEnableVertexArrayAttrib(g->vao[p], MR_ATTR_UV);
            glVertexArrayAttribFormat(g->vao[p], MR_ATTR_UV, 2, GL_FLOAT, GL_FALSE, 24);
            glVertexArrayAttribBinding(g->vao[p], MR_ATTR_UV, 0);
        }
        /* Attributes 3..11: the instance record, one per instance (divisor
         * 1); the command's baseInstance offsets into it, so this works on
         * plain GL 4.5 (no gl_BaseInstance needed), and llvmpipe fetches
         * attributes much faster than it loads from an SSBO per vertex. */
        mr_geo_vao_instances(g->vao[p]);
    }
    glCreateBuffers(1, &g->ibo);
    glNamedBufferStorage(g->ibo, (GLsizeiptr)(indices ? indices : 1) * 4, NULL, GL_DYNAMIC_STORAGE_BIT);
    for (int p = 0; p < 2; p++) glVertexArrayElementBuffer(g->vao[p], g->ibo);
    float *tmp = NULL;
    size_t tmp_cap = 0;
    size_t njobs = 0, cursor = 0;
    double t_jobs = mr_time_now();
    level_job *jobs = level_jobs_run(s, lod, g->cc,
                                     (uint32_t)(r->draw.cluster_triangles > 0 ? r->draw.cluster_triangles
                                                                              : MR_DRAW_DEFAULT_CLUSTER_TRIANGLES),
                                     &njobs);
    r->cluster_info.build_s += mr_time_now() - t_jobs; /* (lookups included) */
    for (size_t i = 0; i < nm; i++) {
        const mr_mesh *m = &s->meshes[i];
        const geo_mesh *gm = &g->meshes[i];
        size_t fl = gm->pool ? 8 : 6, need = (size_t)m->vertex_count * fl;
        if (need > tmp_cap) {
            float *t = realloc(tmp, need * sizeof *t);
            if (!t) {
                free(tmp);
                return mr_fail(err, MR_ERR_NOMEM, "out of memory uploading mesh '%s'", m->name);
            }
            tmp = t;
            tmp_cap = need;
        }
        for (size_t v = 0; v < m->vertex_count; v++) {
            float *d = tmp + v * fl;
            memcpy(d, m->positions + 3 * v, 12);
            memcpy(d + 3, m->normals + 3 * v, 12);
            if (gm->pool) memcpy(d + 6, m->uvs + 2 * v, 8);
        }
        if (m->vertex_count)
            glNamedBufferSubData(g->vbo[gm->pool], (GLintptr)gm->base_vertex * stride[gm->pool],
                                 (GLsizeiptr)(need * sizeof *tmp), tmp);
        if (m->index_count && !upload_level(r, g, m, (int32_t)i, 0, m->indices,
                                            level_job_at(jobs, njobs, &cursor, (int32_t)i, 0), err)) {
            free(tmp);
            level_jobs_free(jobs, njobs);
            return false;
        }
        const mr_mesh_lods *ml = lod ? &lod->meshes[i] : NULL;
        for (int32_t k = 0, l = 1; ml && k < ml->level_count && k < MR_LOD_MAX_LEVELS; k++) {
            if (!ml->levels[k].indices || ml->levels[k].index_count == 0) continue;
            if (!upload_level(r, g, m, (int32_t)i, l, ml->levels[k].indices,
                              level_job_at(jobs, njobs, &cursor, (int32_t)i, l), err)) {
                free(tmp);
                level_jobs_free(jobs, njobs);
                return false;
            }
            l++;
        }
    }
    free(tmp);
    level_jobs_free(jobs, njobs);

    /* Per node: stretch bound; count of (node, mesh) pairs for scratch. */
    size_t recs = 0;
    for (size_t i = 0; i < nn; i++) {
        const mr_node *n = &s->nodes[i];
        g->node_scale[i] = mr_stretch_bound(&n->world);
        const double *w = n->world.m; /* mirroring? */
        double det = w[0] * (w[5] * w[10] - w[6] * w[9]) - w[1] * (w[4] * w[10] - w[6] * w[8]) +
                     w[2] * (w[4] * w[9] - w[5] * w[8]);
        g->node_mirror[i] = det < 0;
        double lo[3], hi[3];
        if (n->layer < MR_LAYER_COUNT && mr_scene_node_bounds(s, (int32_t)i, lo, hi)) g->drawable[n->layer]++;
        if (n->mesh_first >= 0 && n->mesh_count > 0 && n->mesh_first < s->mesh_count) {
            int32_t c = n->mesh_count;
            if (c > s->mesh_count - n->mesh_first) c = s->mesh_count - n->mesh_first;
            recs += (size_t)c;
        }
    }
    g->max_recs = recs;
    g->bvh = mr_bvh_build(s, err);
    if (!g->bvh) return false;
    g->visible = malloc((nn + 1) * sizeof *g->visible);
    g->occ_rest = malloc((nn + 1) * sizeof *g->occ_rest);
    g->recs = malloc((recs + 1) * sizeof *g->recs);
    g->sorted = malloc((recs + 1) * sizeof *g->sorted);
    g->key_count = malloc((nm * LEVELS * CLS_COUNT + 1) * sizeof *g->key_count);
    g->inst = malloc((recs + 1) * sizeof *g->inst);
    g->cmds = malloc((recs + 1) * sizeof *g->cmds);
    g->cmd_cap = recs + 1;
    if (!g->visible || !g->occ_rest || !g->recs || !g->sorted || !g->key_count || !g->inst || !g->cmds)
        return mr_fail(err, MR_ERR_NOMEM, "out of memory for %zu mesh instances", recs);
    glCreateBuffers(1, &g->cmd_buf);
    ensure_instances(g, 1024);
    if (g->cc) {
        r->cluster_info.cache_written = clu_cache_close(g->cc, true);
        free(g->cc);
        g->cc = NULL;
    }
    if (r->cluster_info.levels_built || r->cluster_info.levels_cached) {
        mr_log(MR_LOG_INFO, "meshlets: %llu levels read from the cache, %llu built in %.2f s%s",
               (unsigned long long)r->cluster_info.levels_cached, (unsigned long long)r->cluster_info.levels_built,
               r->cluster_info.build_s, r->cluster_info.cache_written ? " (cache written)" : "");
    }
    r->scene = s;
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) return mr_fail(err, MR_ERR_GL, "GL error 0x%x while uploading the scene", e);
    return true;
}

bool mr_geometry_upload(mr_renderer *r, const mr_scene *s, const mr_lod *lod, mr_error *err) {
    if (lod && lod->mesh_count != s->mesh_count)
        return mr_fail(err, MR_ERR_INVALID, "LOD levels are for %d meshes, the scene has %d", lod->mesh_count, s->mesh_count);
    if (!upload(r, s, lod, err)) {
        mr_geometry_free(r);
        return false;
    }
    return true;
}

bool mr_renderer_set_lod(mr_renderer *r, const mr_lod *lod, mr_error *err) {
    if (!r) return mr_fail(err, MR_ERR_INVALID, "no renderer");
    const mr_scene *s = r->scene;
    if (!s) return lod ? mr_fail(err, MR_ERR_INVALID, "set a scene before its LOD levels") : true;
    if (lod && lod->mesh_count != s->mesh_count)
        return mr_fail(err, MR_ERR_INVALID, "LOD levels are for %d meshes, the scene has %d", lod->mesh_count, s->mesh_count);
    mr_geometry_free(r);
    if (!upload(r, s, lod, err)) {
        mr_geometry_free(r);
        return false;
    }
    return true;
}

/* --------------------------------------------------------------- draw */

/* Projected-error factor for a node box: pixels per scene unit of error at
 * the box's nearest depth. A displacement e at depth z moves the image point
 * by at most f e sqrt(1 + t^2) / z, where t bounds |(x, y) / z| inside the
 * view. Returns INFINITY where the box reaches the near plane. */
static double pixels_per_unit(const mr_geo_view *vw, const double *bb, double fmax_t) {
    const double *M = vw->cam_from_world.m;
    double c = M[11], e = 0;
    for (int k = 0; k < 3; k++) {
        double mid = 0.5 * bb[k] + 0.5 * bb[3 + k], half = 0.5 * bb[3 + k] - 0.5 * bb[k];
        c += M[8 + k] * mid;
        e += fabs(M[8 + k]) * half;
    }
    double zmin = c - e;
    if (!(zmin > vw->near_plane)) return INFINITY;
    return fmax_t / zmin;
}

static int choose_level(const geo_mesh *gm, double scale, double ppu, double tol, double pix) {
    int best = 0;
    for (int l = 1; l < gm->level_count; l++) {
        double e = gm->error[l] * scale; /* scene units */
        if (!(e <= tol)) break;          /* never beyond the tolerance: errors increase */
        if (!(e * ppu <= pix)) break;
        best = l;
    }
    return best;
}

bool mr_geo_instance_matrices(const mr_dmat4 *mvp, gpu_instance *out) {
    const mr_dmat4 mv = *mvp;
    const double *a = mv.m;
    /* Cofactors of the 3x3 = det * inverse transpose; normals are
     * renormalised in the shader, the sign keeps det's orientation. */
    double c00 = a[5] * a[10] - a[6] * a[9], c01 = a[6] * a[8] - a[4] * a[10], c02 = a[4] * a[9] - a[5] * a[8];
    double c10 = a[2] * a[9] - a[1] * a[10], c11 = a[0] * a[10] - a[2] * a[8], c12 = a[1] * a[8] - a[0] * a[9];
    double c20 = a[1] * a[6] - a[2] * a[5], c21 = a[2] * a[4] - a[0] * a[6], c22 = a[0] * a[5] - a[1] * a[4];
    double det = a[0] * c00 + a[1] * c01 + a[2] * c02, mx = 0;
    for (int k = 0; k < 12; k++)
        if (k % 4 != 3 && fabs(a[k]) > mx) mx = fabs(a[k]);
    if (!(fabs(det) > 1e-14 * mx * mx * mx) || !isfinite(det)) return false;
    mr_m4_to_gl(&mv, out->modelview);
    double inv = 1.0 / det;
    /* Column j of the normal matrix = row j of the cofactor matrix / det
     * transposed: N = (A^-1)^T = C / det with C[i][j] = cofactor(i, j). */
    const double C[3][3] = {{c00, c01, c02}, {c10, c11, c12}, {c20, c21, c22}};
    for (int col = 0; col < 3; col++) {
        for (int row = 0; row < 3; row++) out->normal[col * 4 + row] = (float)(C[row][col] * inv);
        out->normal[col * 4 + 3] = 0;
    }
    return true;
}

/* Camera-relative model-view of one instance, in double, then float. */
static bool fill_instance(const mr_geo_view *vw, const mr_node *n, const mr_mesh *m, const geo_mesh *gm, int32_t node,
                          gpu_instance *out) {
    mr_dmat4 cn = mr_m4_mul(&vw->cam_from_world, &n->world);
    mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
    mr_dmat4 mv = mr_m4_mul(&cn, &T);
    if (!mr_geo_instance_matrices(&mv, out)) return false; /* degenerate: nothing to draw */
    memcpy(out->color, gm->color, sizeof out->color);
    out->ids[0] = (uint32_t)node + 1;
    out->ids[1] = n->layer;
    out->ids[2] = gm->has_tex;
    out->ids[3] = 0;
    return true;
}

/* Meshlet culling of one instance, in camera
 * space: the instance's model-view is composed in double from the
 * camera-relative transforms (fill_instance), so a plant 1e7 units away
 * tests as precisely as one at the origin. A sphere is kept unless it lies
 * wholly behind the near plane or outside one of the four side planes of
 * the image (with the margin of mr_geometry_lod_fmax, 1.5 pixels); radii
 * grow by the node's stretch bound. The cone test (cluster_cone) is exact
 * only under a similarity, so it runs only for those (mirrors excluded).
 * Surviving consecutive meshlets merge into one command. Returns the
 * triangles submitted. */
static bool occluded(const struct mr_geo *g, int levels, const double rect[4], double near_depth, int w, int h);

/* A meshlet's sphere (camera space p, radius rad)
 * wholly behind the occluders' depth pyramid. Its projection lies within
 * that of the cube around it, whose nearest point is at depth p.z - rad. */
static bool sphere_occluded(const struct mr_geo *g, const mr_geo_view *vw, const double p[3], double rad) {
    double z0 = p[2] - rad;
    if (!(z0 > vw->near_plane)) return false; /* reaches the camera: cannot be tested */
    double rect[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; c++) {
        double x = p[0] + ((c & 1) ? rad : -rad), y = p[1] + ((c & 2) ? rad : -rad), z = p[2] + ((c & 4) ? rad : -rad);
        double u = vw->cam.fx * x / z + vw->cam.cx, v = vw->cam.fy * y / z + vw->cam.cy;
        rect[0] = fmin(rect[0], u);
        rect[1] = fmin(rect[1], v);
        rect[2] = fmax(rect[2], u);
        rect[3] = fmax(rect[3], v);
    }
    return occluded(g, g->occ_levels, rect, vw->near_plane / z0, g->occ_w, g->occ_h);
}

static uint64_t emit_clusters(mr_renderer *r, const mr_geo_view *vw, const mr_node *n, const mr_mesh *m,
                              const geo_mesh *gm, int level, double scale, uint32_t inst, uint32_t *ncmd, int grp,
                              bool cone) {
    struct mr_geo *g = r->geo;
    const geo_cluster *cl = g->clusters + gm->cl_first[level];
    uint32_t cnt = gm->cl_count[level]; /* emit_recs made room for cnt commands */
    mr_dmat4 cn = mr_m4_mul(&vw->cam_from_world, &n->world);
    mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
    mr_dmat4 mvm = mr_m4_mul(&cn, &T);
    const double *a = mvm.m; /* row-major: a[row * 4 + col] */
    const mr_camera *c = &vw->cam;
    double u0 = -1.5, u1 = c->width + 0.5, v0 = -1.5, v1 = c->height + 0.5;
    /* Inward side planes through the camera centre: n . p >= 0 inside. */
    double pl[4][3] = {{c->fx, 0, c->cx - u0}, {-c->fx, 0, u1 - c->cx}, {0, c->fy, c->cy - v0}, {0, -c->fy, v1 - c->cy}};
    for (int k = 0; k < 4; k++) {
        double l = sqrt(pl[k][0] * pl[k][0] + pl[k][1] * pl[k][1] + pl[k][2] * pl[k][2]);
        for (int j = 0; j < 3; j++) pl[k][j] /= l;
    }
    /* A pass with depth clamping (the shadow map) draws what lies before
     * its near plane too: there only the side planes cull. */
    double near_cut = glIsEnabled(GL_DEPTH_CLAMP) ? -INFINITY : vw->near_plane;
    if (cone) {
        double col[3][3], s2[3];
        for (int j = 0; j < 3; j++) {
            for (int i = 0; i < 3; i++) col[j][i] = a[i * 4 + j];
            s2[j] = col[j][0] * col[j][0] + col[j][1] * col[j][1] + col[j][2] * col[j][2];
        }
        double det = col[0][0] * (col[1][1] * col[2][2] - col[1][2] * col[2][1]) -
                     col[1][0] * (col[0][1] * col[2][2] - col[0][2] * col[2][1]) +
                     col[2][0] * (col[0][1] * col[1][2] - col[0][2] * col[1][1]);
        for (int j = 0; j < 3 && cone; j++) {
            if (fabs(s2[j] - s2[0]) > 1e-6 * s2[0]) cone = false;
            double d = col[j][0] * col[(j + 1) % 3][0] + col[j][1] * col[(j + 1) % 3][1] + col[j][2] * col[(j + 1) % 3][2];
            if (fabs(d) > 1e-6 * s2[0]) cone = false;
        }
        if (!(det > 0)) cone = false;
    }
    uint64_t tris = 0, drawn = 0, occl = 0;
    uint32_t last_end = UINT32_MAX;
    bool occ = g->occ_levels > 0 && !r->draw.no_cluster_occlusion;
    double t_occ = occ ? mr_time_now() : 0;
    for (uint32_t k = 0; k < cnt; k++) {
        const geo_cluster *q = &cl[k];
        double p[3];
        for (int i = 0; i < 3; i++)
            p[i] = a[i * 4] * q->center[0] + a[i * 4 + 1] * q->center[1] + a[i * 4 + 2] * q->center[2] + a[i * 4 + 3];
        double rad = (double)q->radius * scale * (1 + 1e-6) + 1e-9 * fabs(p[2]);
        bool keep = p[2] > near_cut - rad;
        for (int j = 0; j < 4 && keep; j++) keep = pl[j][0] * p[0] + pl[j][1] * p[1] + pl[j][2] * p[2] >= -rad;
        if (keep && cone && q->cutoff < 1) {
            /* meshopt: back-facing when dot(normalize(apex - eye), axis) >=
             * cutoff; here the eye is the camera-space origin. A small
             * slack keeps edge-on clusters. */
            double ap[3], ax[3], la = 0, lx = 0, d = 0;
            for (int i = 0; i < 3; i++) {
                ap[i] = a[i * 4] * q->apex[0] + a[i * 4 + 1] * q->apex[1] + a[i * 4 + 2] * q->apex[2] + a[i * 4 + 3];
                ax[i] = a[i * 4] * q->axis[0] + a[i * 4 + 1] * q->axis[1] + a[i * 4 + 2] * q->axis[2];
                la += ap[i] * ap[i];
                lx += ax[i] * ax[i];
                d += ap[i] * ax[i];
            }
            if (la > 0 && lx > 0 && d / sqrt(la * lx) >= (double)q->cutoff + 1e-3) keep = false;
        }
        if (keep && occ && sphere_occluded(g, vw, p, rad)) {
            keep = false;
            occl++;
            g->occ_cl_tris += q->count / 3;
        }
        if (!keep) continue;
        drawn++;
        tris += q->count / 3;
        if (last_end == q->first) {
            g->cmds[*ncmd - 1].count += q->count;
        } else {
            g->cmds[*ncmd] = (draw_cmd){q->count, 1, q->first, gm->base_vertex, inst};
            if (g->group_first[grp] < 0) g->group_first[grp] = (int32_t)*ncmd;
            g->group_cmds[grp]++;
            (*ncmd)++;
        }
        last_end = q->first + q->count;
    }
    r->stats.clusters_tested += cnt;
    r->stats.clusters_drawn += drawn;
    r->stats.clusters_occluded += occl;
    if (occ) g->occ_cl_ms += (mr_time_now() - t_occ) * 1e3;
    return tris;
}

/* Largest pixels per unit of x/z over the image (its corners, with the
 * margin): the LOD choice's projected-error factor. */
double mr_geometry_lod_fmax(const mr_camera *c) { return mr_lod_fmax(c); }

/* Step 2 for a list of visible nodes: LOD choice (the depth row of
 * vw->cam_from_world, its near plane and fmax_t decide) and bucketing of
 * the (node, mesh) pairs into dst, sorted by key; returns their count. */
static size_t select_recs(mr_renderer *r, const mr_geo_view *vw, double fmax_t, const int32_t *nodes, int32_t nvis,
                          geo_rec *dst) {
    const mr_scene *s = r->scene;
    struct mr_geo *g = r->geo;
    const mr_draw_params *dp = &r->draw;
    /* No absolute cap by default: the projected error alone decides, which
     * knows no unit (a hall in millimetres picks the levels it picks in
     * metres); an explicit tolerance, in the scene's own units, caps it. */
    double tol = dp->lod_tolerance == 0 ? INFINITY : dp->lod_tolerance;
    double pix = dp->lod_pixels == 0 ? MR_DRAW_DEFAULT_LOD_PIXELS : dp->lod_pixels;
    bool use_lod = g->lod && !dp->no_lod && tol > 0;
    size_t nkeys = (size_t)g->mesh_count * LEVELS * CLS_COUNT;
    memset(g->key_count, 0, (nkeys + 1) * sizeof *g->key_count);
    size_t nrec = 0;
    for (int32_t vi = 0; vi < nvis; vi++) {
        int32_t ni = nodes[vi];
        const mr_node *n = &s->nodes[ni];
        int32_t last = n->mesh_first + n->mesh_count;
        if (last > g->mesh_count) last = g->mesh_count;
        double ppu = use_lod ? pixels_per_unit(vw, mr_bvh_bounds(g->bvh, ni), fmax_t) : INFINITY;
        for (int32_t mi = n->mesh_first; mi < last; mi++) {
            const geo_mesh *gm = &g->meshes[mi];
            if (gm->count[0] == 0) continue;
            int level = use_lod && gm->level_count > 1 && isfinite(ppu) ? choose_level(gm, g->node_scale[ni], ppu, tol, pix) : 0;
            uint32_t cls = !gm->single_sided ? CLS_DOUBLE : g->node_mirror[ni] ? CLS_MIRROR : CLS_SINGLE;
            uint32_t key = (cls * (uint32_t)g->mesh_count + (uint32_t)g->rank[mi]) * LEVELS + (uint32_t)level;
            g->recs[nrec++] = (geo_rec){ni, mi, key};
            g->key_count[key]++;
        }
    }
    /* Counting sort by key: stable, so instances keep node order. */
    uint32_t sum = 0;
    for (size_t k = 0; k < nkeys; k++) {
        uint32_t c = g->key_count[k];
        g->key_count[k] = sum;
        sum += c;
    }
    for (size_t i = 0; i < nrec; i++) dst[g->key_count[g->recs[i].key]++] = g->recs[i];
    return nrec;
}

/* Steps 3-4 for sorted records: instance data through vw's camera,
 * commands, submission. Adds to the frame's statistics. replicate >= 1
 * (the layered-rendering experiment): every instance drawn that many times
 * (attribute divisor = replicate), the caller sets the projections; 0: a
 * plain draw. */
static void emit_recs(mr_renderer *r, const mr_geo_view *vw, mr_frame_result *out, const geo_rec *sorted, size_t nrec,
                      int replicate) {
    const mr_scene *s = r->scene;
    struct mr_geo *g = r->geo;
    const mr_draw_params *dp = &r->draw;
    double t0 = mr_time_now();

    /* 3. Instance data and commands, one per bucket (or per instance);
     * an instance of a mesh level with meshlets can take one command per
     * meshlet. */
    bool clusters = !dp->no_cluster_cull && replicate == 0 && g->cluster_count > 0;
    size_t need = nrec + 1;
    for (size_t i = 0; clusters && i < nrec; i++) need += g->meshes[sorted[i].mesh].cl_count[sorted[i].key % LEVELS];
    if (need > g->cmd_cap) {
        draw_cmd *c = realloc(g->cmds, need * sizeof *c);
        if (!c) clusters = false; /* whole levels then: nrec + 1 commands fit */
        else {
            g->cmds = c;
            g->cmd_cap = need;
        }
    }
    uint32_t ninst = 0, ncmd = 0, last_key = UINT32_MAX, lod_inst = 0;
    uint64_t tris = 0, tri_full = 0;
    int32_t ngroups = g->group_count * CLS_COUNT; /* (class, draw group) */
    uint32_t cls_keys = (uint32_t)g->mesh_count * LEVELS;
    memset(g->group_cmds, 0, (size_t)ngroups * sizeof *g->group_cmds);
    for (int32_t k = 0; k < ngroups; k++) g->group_first[k] = -1;
    /* Back-facing meshlets are skipped only where
     * this draw culls back faces (then it is exact); mirrored instances
     * never test cones (emit_clusters: similarities of det > 0 only). */
    bool cone_ok = !dp->no_cluster_cone && vw->cull_back;
    for (size_t i = 0; i < nrec; i++) {
        const geo_rec *rc = &sorted[i];
        const geo_mesh *gm = &g->meshes[rc->mesh];
        int level = (int)(rc->key % LEVELS);
        lod_inst += level > 0;
        r->stats.level_instances[level]++;
        if (level > 0 && gm->error[level] * g->node_scale[rc->node] > r->stats.lod_max_error)
            r->stats.lod_max_error = gm->error[level] * g->node_scale[rc->node];
        tri_full += gm->count[0] / 3;
        if (!fill_instance(vw, &s->nodes[rc->node], &s->meshes[rc->mesh], gm, rc->node, &g->inst[ninst])) continue;
        uint32_t cls = rc->key / cls_keys;
        int grp = (int)cls * g->group_count + gm->group;
        if (clusters && gm->cl_count[level] > 0) {
            /* This instance's visible meshlets */
            tris += emit_clusters(r, vw, &s->nodes[rc->node], &s->meshes[rc->mesh], gm, level, g->node_scale[rc->node],
                                  ninst, &ncmd, grp, cone_ok && cls == CLS_SINGLE);
            last_key = UINT32_MAX; /* its commands take no other instance */
            ninst++;
            continue;
        }
        /* Same bucket as the last command (records skipped as degenerate
         * leave no gap: the command's instances stay contiguous). */
        bool extend = !dp->no_instancing && ncmd > 0 && last_key == rc->key;
        last_key = rc->key;
        if (extend) {
            g->cmds[ncmd - 1].instance_count++;
        } else {
            g->cmds[ncmd] = (draw_cmd){gm->count[level], 1, gm->first[level], gm->base_vertex, ninst};
            if (g->group_first[grp] < 0) g->group_first[grp] = (int32_t)ncmd;
            g->group_cmds[grp]++;
            ncmd++;
        }
        tris += gm->count[level] / 3;
        ninst++;
    }
    bool have_room = ensure_instances(g, ninst);
    r->stats.cull_ms += (mr_time_now() - t0) * 1e3;
    r->stats.instances += ninst;
    r->stats.commands += ncmd;
    r->stats.triangles += tris;
    r->stats.triangles_full += tri_full;
    r->stats.lod_instances += lod_inst;
    if (ninst == 0 || !have_room) return; /* nothing to draw costs nothing */

    /* 4. Submission. */
    if (replicate >= 1) {
        for (uint32_t c = 0; c < ncmd; c++) g->cmds[c].instance_count *= (uint32_t)replicate;
        for (int p = 0; p < 2; p++) glVertexArrayBindingDivisor(g->vao[p], 1, (GLuint)replicate);
    }
    glNamedBufferSubData(g->inst_buf, 0, (GLsizeiptr)ninst * (GLsizeiptr)sizeof(gpu_instance), g->inst);
    glNamedBufferData(g->cmd_buf, (GLsizeiptr)ncmd * (GLsizeiptr)sizeof(draw_cmd), g->cmds, GL_STREAM_DRAW);
    glUseProgram(vw->program);
    if (replicate == 0) {
        float proj[16];
        mr_gl_projection(&vw->cam, vw->near_plane, proj);
        glUniformMatrix4fv(MR_LOC_PROJECTION, 1, GL_FALSE, proj);
    }
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, g->cmd_buf);
    uint32_t calls = 0;
    bool culling = false;
    for (int32_t cg = 0; cg < ngroups; cg++) {
        int32_t first = g->group_first[cg], count = g->group_cmds[cg];
        if (first < 0 || count == 0) continue;
        int32_t grp = cg % g->group_count, cls = cg / g->group_count;
        /* glTF's front faces are counter-clockwise
         * in the node's frame; the camera's axes (OpenCV: y down) unflipped
         * by the projection put them clockwise in the window, and a
         * mirroring node turns them back. */
        bool cull = vw->cull_back && cls != CLS_DOUBLE;
        if (cull) {
            if (!culling) glEnable(GL_CULL_FACE);
            glCullFace(GL_BACK);
            glFrontFace(cls == CLS_MIRROR ? GL_CCW : GL_CW);
        } else if (culling) {
            glDisable(GL_CULL_FACE);
        }
        culling = cull;
        glBindVertexArray(g->vao[grp > 0 ? 1 : 0]);
        if (grp > 0) glBindTextureUnit(MR_TEX_GBUFFER_BASE_COLOR, r->textures[grp - 1]);
        if (!dp->no_batch) {
            glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT, (const void *)((size_t)first * sizeof(draw_cmd)),
                                        count, 0);
            calls++;
        } else {
            for (int32_t c = first; c < first + count; c++) {
                const draw_cmd *dc = &g->cmds[c];
                glDrawElementsInstancedBaseVertexBaseInstance(GL_TRIANGLES, (GLsizei)dc->count, GL_UNSIGNED_INT,
                                                              (const void *)((size_t)dc->first_index * 4),
                                                              (GLsizei)dc->instance_count, dc->base_vertex,
                                                              dc->base_instance);
                calls++;
            }
        }
    }
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    glBindVertexArray(0);
    if (culling) glDisable(GL_CULL_FACE);
    glFrontFace(GL_CCW);
    if (replicate > 1)
        for (int p = 0; p < 2; p++) glVertexArrayBindingDivisor(g->vao[p], 1, 1);
    r->stats.gl_draw_calls += calls;
    if (out) {
        out->triangles += tris;
        out->draw_calls += calls;
    }
}

/* Steps 2-4 for a list of visible nodes through one view. */
static void submit_nodes(mr_renderer *r, const mr_geo_view *vw, mr_frame_result *out, const int32_t *nodes,
                         int32_t nvis) {
    struct mr_geo *g = r->geo;
    double t0 = mr_time_now();
    double fmax_t = !g->lod || r->draw.no_lod ? 0 : vw->lod_fmax > 0 ? vw->lod_fmax : mr_geometry_lod_fmax(&vw->cam);
    size_t nrec = select_recs(r, vw, fmax_t, nodes, nvis, g->sorted);
    r->stats.cull_ms += (mr_time_now() - t0) * 1e3;
    emit_recs(r, vw, out, g->sorted, nrec, 0);
}

/* ---------------------------------------------------- occlusion culling
 *
 * Within the frame, so it is exact and needs no previous frame: the nodes
 * whose boxes cover a good part of the image (floors, walls, big machines)
 * are drawn first; their depth is read back and reduced to a pyramid of the
 * farthest depth per tile (reversed Z: the smallest value); every other
 * visible node whose box lies wholly behind that depth over the tiles its
 * projection touches is skipped. The tiles cover the box's pixels and the
 * box encloses the geometry, so no visible node is dropped: the image is
 * the same with and without (the tests check it). The read-back is a sync
 * point: a win when much is hidden (a hall seen from its floor), a cost in
 * open views, hence behind a flag. */

#define HZ_TILE 8

static bool box_screen(const mr_geo_view *vw, const double *bb, double rect[4], double *near_depth) {
    const double *M = vw->cam_from_world.m;
    double zmin = INFINITY;
    rect[0] = rect[1] = INFINITY;
    rect[2] = rect[3] = -INFINITY;
    for (int c = 0; c < 8; c++) {
        double p[3] = {(c & 1) ? bb[3] : bb[0], (c & 2) ? bb[4] : bb[1], (c & 4) ? bb[5] : bb[2]};
        double x = M[0] * p[0] + M[1] * p[1] + M[2] * p[2] + M[3];
        double y = M[4] * p[0] + M[5] * p[1] + M[6] * p[2] + M[7];
        double z = M[8] * p[0] + M[9] * p[1] + M[10] * p[2] + M[11];
        if (!(z > vw->near_plane)) return false; /* reaches the camera: cannot be tested */
        double u = vw->cam.fx * x / z + vw->cam.cx, v = vw->cam.fy * y / z + vw->cam.cy;
        rect[0] = fmin(rect[0], u);
        rect[1] = fmin(rect[1], v);
        rect[2] = fmax(rect[2], u);
        rect[3] = fmax(rect[3], v);
        zmin = fmin(zmin, z);
    }
    *near_depth = vw->near_plane / zmin; /* reversed Z: the box's nearest depth */
    return true;
}

/* Level 0: the farthest (smallest) depth per HZ_TILE^2 tile; level k+1
 * halves each side. Returns the level count (0 if out of memory). */
static int build_pyramid(struct mr_geo *g, const float *depth, int w, int h) {
    int tw = (w + HZ_TILE - 1) / HZ_TILE, th = (h + HZ_TILE - 1) / HZ_TILE;
    size_t need = 0;
    for (int lw = tw, lh = th;; lw = (lw + 1) / 2, lh = (lh + 1) / 2) {
        need += (size_t)lw * lh;
        if (lw == 1 && lh == 1) break;
    }
    if (need > g->hz_cap) {
        float *p = realloc(g->hz, need * sizeof *p);
        if (!p) return 0;
        g->hz = p;
        g->hz_cap = need;
    }
    float *lvl = g->hz;
    for (int ty = 0; ty < th; ty++)
        for (int tx = 0; tx < tw; tx++) {
            float m = INFINITY;
            for (int y = ty * HZ_TILE; y < ty * HZ_TILE + HZ_TILE && y < h; y++)
                for (int x = tx * HZ_TILE; x < tx * HZ_TILE + HZ_TILE && x < w; x++) m = fminf(m, depth[(size_t)y * w + x]);
            lvl[(size_t)ty * tw + tx] = m;
        }
    int levels = 1;
    g->hz_w[0] = tw;
    g->hz_h[0] = th;
    g->hz_off[0] = 0;
    size_t off = (size_t)tw * th;
    while ((tw > 1 || th > 1) && levels < 24) {
        int nw = (tw + 1) / 2, nh = (th + 1) / 2;
        const float *src = g->hz + g->hz_off[levels - 1];
        float *dst = g->hz + off;
        for (int y = 0; y < nh; y++)
            for (int x = 0; x < nw; x++) {
                float m = INFINITY;
                for (int dy = 0; dy < 2; dy++)
                    for (int dx = 0; dx < 2; dx++) {
                        int sx = 2 * x + dx, sy = 2 * y + dy;
                        if (sx < tw && sy < th) m = fminf(m, src[(size_t)sy * tw + sx]);
                    }
                dst[(size_t)y * nw + x] = m;
            }
        g->hz_off[levels] = off;
        g->hz_w[levels] = nw;
        g->hz_h[levels] = nh;
        off += (size_t)nw * nh;
        tw = nw;
        th = nh;
        levels++;
    }
    return levels;
}

static bool occluded(const struct mr_geo *g, int levels, const double rect[4], double near_depth, int w, int h) {
    if (!(rect[0] > -1e9 && rect[1] > -1e9 && rect[2] < 1e9 && rect[3] < 1e9)) return false; /* not finite: keep */
    /* Pixels the projection can touch (pixel centres at integers), widened
     * by a pixel for rasterisation rounding. */
    double x0 = floor(rect[0] - 1), y0 = floor(rect[1] - 1), x1 = ceil(rect[2] + 1), y1 = ceil(rect[3] + 1);
    if (x1 < 0 || y1 < 0 || x0 > w - 1 || y0 > h - 1) return false; /* the frustum's business */
    x0 = fmax(x0, 0);
    y0 = fmax(y0, 0);
    x1 = fmin(x1, w - 1);
    y1 = fmin(y1, h - 1);
    int tx0 = (int)x0 / HZ_TILE, ty0 = (int)y0 / HZ_TILE, tx1 = (int)x1 / HZ_TILE, ty1 = (int)y1 / HZ_TILE;
    int lv = 0;
    while (lv + 1 < levels && (tx1 - tx0 > 3 || ty1 - ty0 > 3)) {
        tx0 >>= 1;
        ty0 >>= 1;
        tx1 >>= 1;
        ty1 >>= 1;
        lv++;
    }
    const float *t = g->hz + g->hz_off[lv];
    for (int y = ty0; y <= ty1 && y < g->hz_h[lv]; y++)
        for (int x = tx0; x <= tx1 && x < g->hz_w[lv]; x++)
            if (!(near_depth < (double)t[(size_t)y * g->hz_w[lv] + x])) return false;
    return true;
}

/* ------------------------------------------- shared culling
 *
 * A multi-view rig's views differ by a translation along the camera's x
 * axis only. Between share_begin and share_end, a draw through one of them
 * (mr_geo_view.shared) culls once per layer set against the union volume
 * and picks LOD levels once (the views' depth row is the same; the nearest
 * near plane and the largest pixel factor of all views make the choice the
 * finest any view would make); every view then only writes its own
 * camera-relative instance matrices and draws that list. */

#define SHARE_LISTS 4

typedef struct share_list {
    uint32_t mask;
    int32_t nvis;
    size_t nrec;
    geo_rec *recs;
} share_list;

struct mr_geo_share {
    mr_frustum cull;
    mr_geo_view lod_view;
    double fmax_t;
    int n;
    share_list list[SHARE_LISTS];
};

bool mr_geometry_share_begin(mr_renderer *r, const mr_frustum *cull, const mr_dmat4 *cam_from_world, double near_plane,
                             double fmax_t, mr_error *err) {
    mr_geometry_share_end(r);
    if (!r->geo) return true; /* nothing to draw: nothing to share */
    struct mr_geo_share *sh = calloc(1, sizeof *sh);
    if (!sh) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    sh->cull = *cull;
    sh->lod_view.cam_from_world = *cam_from_world;
    sh->lod_view.near_plane = near_plane;
    sh->fmax_t = fmax_t;
    r->share = sh;
    return true;
}

void mr_geometry_share_end(mr_renderer *r) {
    struct mr_geo_share *sh = r->share;
    if (!sh) return;
    for (int i = 0; i < sh->n; i++) free(sh->list[i].recs);
    free(sh);
    r->share = NULL;
}

/* The shared list of this draw's layers (culled and chosen on first use);
 * NULL: none can be made (then the draw culls on its own). */
static const share_list *shared_list(mr_renderer *r, uint32_t mask) {
    struct mr_geo_share *sh = r->share;
    struct mr_geo *g = r->geo;
    for (int i = 0; i < sh->n; i++)
        if (sh->list[i].mask == mask) return &sh->list[i];
    if (sh->n == SHARE_LISTS) return NULL;
    share_list *l = &sh->list[sh->n];
    l->recs = malloc((g->max_recs + 1) * sizeof *l->recs);
    if (!l->recs) return NULL;
    double t0 = mr_time_now();
    mr_bvh_stats bst;
    l->nvis = mr_bvh_cull(g->bvh, r->draw.no_cull ? NULL : &sh->cull, mask, g->visible, &bst);
    r->stats.frustum_culls++;
    l->nrec = select_recs(r, &sh->lod_view, sh->fmax_t, g->visible, l->nvis, l->recs);
    l->mask = mask;
    sh->n++;
    r->stats.cull_ms += (mr_time_now() - t0) * 1e3;
    return l;
}

/* The learnt state back to the upload's (see
 * upload): the next frame tests and measures. */
void mr_renderer_reset_occlusion(mr_renderer *r) {
    struct mr_geo *g = r ? r->geo : NULL;
    if (!g) return;
    occ_auto_reset(&g->occ);
}

void mr_geometry_draw(mr_renderer *r, const mr_geo_view *vw, mr_frame_result *out) {
    uint32_t layer_mask = vw->layers;
    const mr_scene *s = r->scene;
    struct mr_geo *g = r->geo;
    if (!s || !g) return;
    const mr_draw_params *dp = &r->draw;
    double t0 = mr_time_now();

    /* A rig's view draws the frame's shared list (occlusion culling reads
     * each view's own depth, so it stays per view). */
    bool hier = mr_hlod_active(r);
    if (vw->shared && r->share && !hier && !(dp->occlusion && !dp->no_cull)) {
        const share_list *l = shared_list(r, layer_mask);
        if (l) {
            for (int k = 0; k < MR_LAYER_COUNT; k++)
                if (layer_mask & (1u << k)) r->stats.nodes_drawable += g->drawable[k];
            r->stats.nodes_visible += (uint32_t)l->nvis;
            emit_recs(r, vw, out, l->recs, l->nrec, 0);
            return;
        }
    }

    /* 1. Frustum culling. */
    mr_frustum fr = mr_frustum_from_camera(&vw->cam, &vw->world_from_camera, vw->near_plane, 1.0);
    mr_bvh_stats bst;
    /* With the LOD hierarchy its cut replaces the BVH's: proxies first
     * (drawn now, so they are occluders too), the nodes it reached after. */
    int32_t nvis = hier ? mr_hlod_draw(r, vw, dp->no_cull ? NULL : &fr, g->visible, out)
                        : mr_bvh_cull(g->bvh, dp->no_cull ? NULL : &fr, layer_mask, g->visible, &bst);
    r->stats.frustum_culls++;
    uint32_t ndrawable = 0;
    for (int l = 0; l < MR_LAYER_COUNT; l++)
        if (layer_mask & (1u << l)) ndrawable += g->drawable[l];
    r->stats.nodes_drawable += ndrawable;
    r->stats.nodes_visible += (uint32_t)nvis;
    r->stats.cull_ms += (mr_time_now() - t0) * 1e3;
    GLint vp[4];
    glGetIntegerv(GL_VIEWPORT, vp);
    int w = vp[2], h = vp[3];
    /* Occlusion needs a depth buffer that this draw tests and writes with
     * reversed Z (a pass drawing without depth, e.g. an x-ray view of the
     * hidden layer, gets plain frustum culling). */
    bool depth_ok = false;
    bool want = dp->occlusion;
    if (!want && dp->occlusion_auto && !dp->no_cull && nvis >= 64) {
        want = occ_auto_frame(&g->occ);
    }
    if (want && !dp->no_cull && nvis >= 64 && w == vw->cam.width && h == vw->cam.height) {
        GLint fbo = 0, type = GL_NONE, func = 0;
        GLboolean mask = GL_FALSE;
        glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fbo);
        if (fbo != 0)
            glGetNamedFramebufferAttachmentParameteriv((GLuint)fbo, GL_DEPTH_ATTACHMENT, GL_FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE, &type);
        glGetIntegerv(GL_DEPTH_FUNC, &func);
        glGetBooleanv(GL_DEPTH_WRITEMASK, &mask);
        depth_ok = fbo != 0 && type != GL_NONE && glIsEnabled(GL_DEPTH_TEST) && mask &&
                   (func == GL_GREATER || func == GL_GEQUAL);
    }
    if (!depth_ok) {
        submit_nodes(r, vw, out, g->visible, nvis);
        return;
    }

    /* 2. Occluders first: boxes covering at least 1/256 of the image (or
     * reaching the camera). */
    t0 = mr_time_now();
    int32_t nocc = 0, nrest = 0;
    int32_t *rest = g->occ_rest;
    double min_area = (double)w * h / 256.0;
    for (int32_t i = 0; i < nvis; i++) {
        double rect[4], nd;
        const double *bb = mr_bvh_bounds(g->bvh, g->visible[i]);
        bool big = !box_screen(vw, bb, rect, &nd) ||
                   (fmin(rect[2], w) - fmax(rect[0], 0)) * (fmin(rect[3], h) - fmax(rect[1], 0)) >= min_area;
        if (big) g->visible[nocc++] = g->visible[i];
        else rest[nrest++] = g->visible[i];
    }
    r->stats.cull_ms += (mr_time_now() - t0) * 1e3;
    uint64_t tris_before = r->stats.triangles, full_before = r->stats.triangles_full;
    submit_nodes(r, vw, out, g->visible, nocc);
    uint64_t occluder_tris = r->stats.triangles - tris_before, occluder_full = r->stats.triangles_full - full_before;
    bool learn = !dp->occlusion && dp->occlusion_auto;
    r->stats.occlusion_frames++;

    /* 3. Their depth as a pyramid; the rest tested against it. */
    if (learn && (g->occ_rb_ms < 0 || g->occ_rb_w != w || g->occ_rb_h != h) && (size_t)w * h <= g->depth_cap) {
        /* Once per size: what a read-back costs alone (a sync point). */
        glFinish();
        double tr = mr_time_now();
        GLint fb = 0;
        glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fb);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, (GLuint)fb);
        glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, g->depth);
        g->occ_rb_ms = (mr_time_now() - tr) * 1e3;
        g->occ_rb_w = w;
        g->occ_rb_h = h;
    }
    t0 = mr_time_now();
    size_t npx = (size_t)w * h;
    if (npx > g->depth_cap) {
        float *d = realloc(g->depth, npx * sizeof *d);
        if (!d) {
            submit_nodes(r, vw, out, rest, nrest);
            return;
        }
        g->depth = d;
        g->depth_cap = npx;
    }
    GLint draw_fbo = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw_fbo);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, (GLuint)draw_fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, g->depth);
    double t_sync = mr_time_now();
    int levels = build_pyramid(g, g->depth, w, h);
    int32_t nkeep = 0;
    uint64_t skipped_full = 0;
    for (int32_t i = 0; i < nrest; i++) {
        double rect[4], nd;
        const double *bb = mr_bvh_bounds(g->bvh, rest[i]);
        if (levels > 0 && box_screen(vw, bb, rect, &nd) && occluded(g, levels, rect, nd, w, h)) {
            if (learn) {
                const mr_node *n = &s->nodes[rest[i]];
                for (int32_t mi = n->mesh_first; mi >= 0 && mi < n->mesh_first + n->mesh_count && mi < g->mesh_count; mi++)
                    skipped_full += g->meshes[mi].count[0] / 3;
            }
            continue;
        }
        rest[nkeep++] = rest[i];
    }
    r->stats.nodes_occluded += (uint32_t)(nrest - nkeep);
    double t_end = mr_time_now();
    r->stats.cull_ms += (t_end - t0) * 1e3;
    /* The surviving nodes' meshlets are tested
     * against the same pyramid (emit_clusters); what they skip and cost
     * counts in the same decision. */
    g->occ_levels = levels;
    g->occ_w = w;
    g->occ_h = h;
    g->occ_cl_tris = 0;
    g->occ_cl_ms = 0;
    submit_nodes(r, vw, out, rest, nkeep);
    g->occ_levels = 0;
    if (learn) {
        /* Skipped triangles at the occluders' LOD ratio (full-detail counts
         * would overstate the gain where LOD engages); skipped meshlets are
         * counted at the level drawn. */
        double ratio = occluder_full > 0 ? (double)occluder_tris / (double)occluder_full : 1;
        occ_auto_learn(&g->occ, g->occ_rb_ms, (t_sync - t0) * 1e3, (t_end - t_sync) * 1e3 + g->occ_cl_ms, occluder_tris,
                        (uint64_t)(skipped_full * ratio) + g->occ_cl_tris);
    }
}

bool mr_geometry_draw_replicated(mr_renderer *r, const mr_geo_view *vw, int replicate) {
    if (!r->scene || !r->geo || !r->share) return false;
    const share_list *l = shared_list(r, vw->layers);
    if (!l) return false;
    emit_recs(r, vw, NULL, l->recs, l->nrec, replicate);
    return true;
}

/* ------------------------------------------------------ auxiliary streams */

bool mr_geometry_aux_create(mr_renderer *r, float *const *per_mesh, int comps, GLuint attrib, mr_geo_aux *aux) {
    memset(aux, 0, sizeof *aux);
    struct mr_geo *g = r->geo;
    const mr_scene *s = r->scene;
    if (!g || !s || comps < 1 || comps > 4) return false;
    static const GLsizei stride[2] = {24, 32};
    size_t verts[2] = {0, 0};
    for (int32_t i = 0; i < g->mesh_count && i < s->mesh_count; i++) {
        size_t end = (size_t)g->meshes[i].base_vertex + s->meshes[i].vertex_count;
        if (end > verts[g->meshes[i].pool]) verts[g->meshes[i].pool] = end;
    }
    for (int p = 0; p < 2; p++) {
        size_t n = (verts[p] ? verts[p] : 1) * (size_t)comps;
        float *buf = calloc(n, sizeof *buf);
        if (!buf) {
            mr_geometry_aux_free(aux);
            return false;
        }
        for (int32_t i = 0; i < g->mesh_count && i < s->mesh_count; i++)
            if (g->meshes[i].pool == p && per_mesh[i])
                memcpy(buf + (size_t)g->meshes[i].base_vertex * comps, per_mesh[i],
                       (size_t)s->meshes[i].vertex_count * comps * sizeof *buf);
        glCreateBuffers(1, &aux->vbo[p]);
        glNamedBufferStorage(aux->vbo[p], (GLsizeiptr)(n * sizeof *buf), buf, 0);
        free(buf);
        glCreateVertexArrays(1, &aux->vao[p]);
        glVertexArrayVertexBuffer(aux->vao[p], 0, g->vbo[p], 0, stride[p]);
        glEnableVertexArrayAttrib(aux->vao[p], MR_ATTR_POSITION);
        glVertexArrayAttribFormat(aux->vao[p], MR_ATTR_POSITION, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(aux->vao[p], MR_ATTR_POSITION, 0);
        glVertexArrayVertexBuffer(aux->vao[p], 1, aux->vbo[p], 0, comps * (GLsizei)sizeof(float));
        glEnableVertexArrayAttrib(aux->vao[p], attrib);
        glVertexArrayAttribFormat(aux->vao[p], attrib, comps, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(aux->vao[p], attrib, 1);
        glVertexArrayElementBuffer(aux->vao[p], g->ibo);
    }
    aux->valid = true;
    return true;
}

void mr_geometry_aux_free(mr_geo_aux *aux) {
    if (!aux) return;
    glDeleteVertexArrays(2, aux->vao);
    glDeleteBuffers(2, aux->vbo);
    memset(aux, 0, sizeof *aux);
}

/* Every node of the view's layers, each of its meshes with its camera-
 * relative model-view (composed in double) and normal matrix set; draw()
 * issues that mesh's own draw call. */
typedef void (*instance_draw_fn)(const void *ctx, int32_t mesh);
static void draw_instances(mr_renderer *r, const mr_geo_view *vw, int32_t mesh_limit, instance_draw_fn draw, const void *ctx) {
    const mr_scene *s = r->scene;
    glUseProgram(vw->program);
    float proj[16];
    mr_gl_projection(&vw->cam, vw->near_plane, proj);
    glUniformMatrix4fv(MR_LOC_PROJECTION, 1, GL_FALSE, proj);
    for (int32_t ni = 0; ni < s->node_count; ni++) {
        const mr_node *n = &s->nodes[ni];
        if (n->mesh_first < 0 || n->mesh_count <= 0 || !(vw->layers & (1u << n->layer))) continue;
        mr_dmat4 cam_from_node = mr_m4_mul(&vw->cam_from_world, &n->world);
        for (int32_t k = 0; k < n->mesh_count; k++) {
            int32_t mi = n->mesh_first + k;
            if (mi >= mesh_limit || mi >= s->mesh_count) break;
            const mr_mesh *m = &s->meshes[mi];
            /* Camera-relative in double, then float, as the main path. */
            mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
            mr_dmat4 mv = mr_m4_mul(&cam_from_node, &T), inv;
            if (!mr_m4_invert(&mv, &inv)) continue;
            float mvf[16], nm[9];
            mr_m4_to_gl(&mv, mvf);
            for (int rr = 0; rr < 3; rr++)
                for (int cc = 0; cc < 3; cc++) nm[cc * 3 + rr] = (float)inv.m[cc * 4 + rr];
            glUniformMatrix4fv(MR_LOC_MODELVIEW, 1, GL_FALSE, mvf);
            glUniformMatrix3fv(MR_LOC_NORMAL_MATRIX, 1, GL_FALSE, nm);
            draw(ctx, mi);
        }
    }
    glBindVertexArray(0);
}

typedef struct aux_ctx {
    const struct mr_geo *g;
    const mr_geo_aux *aux;
} aux_ctx;

static void draw_aux_mesh(const void *ctx, int32_t mi) {
    const aux_ctx *c = ctx;
    const geo_mesh *gm = &c->g->meshes[mi];
    glBindVertexArray(c->aux->vao[gm->pool]);
    glDrawElementsBaseVertex(GL_TRIANGLES, (GLsizei)gm->count[0], GL_UNSIGNED_INT, (const void *)((size_t)gm->first[0] * 4),
                             gm->base_vertex);
}

void mr_geometry_aux_draw(mr_renderer *r, const mr_geo_view *vw, const mr_geo_aux *aux) {
    struct mr_geo *g = r->geo;
    if (!g || !r->scene || !aux->valid) return;
    aux_ctx c = {g, aux};
    draw_instances(r, vw, g->mesh_count, draw_aux_mesh, &c);
}

/* ------------------------------------------------------ meshes of a pass's own */

bool mr_geometry_own_create(const mr_geo_own_mesh *meshes, int32_t n, GLuint attrib, mr_geo_own *o) {
    memset(o, 0, sizeof *o);
    size_t nv = 0, ni = 0;
    for (int32_t i = 0; i < n; i++) {
        nv += meshes[i].vertex_count;
        ni += meshes[i].index_count;
    }
    o->first = calloc((size_t)n + 1, sizeof *o->first);
    o->count = calloc((size_t)n + 1, sizeof *o->count);
    o->base = calloc((size_t)n + 1, sizeof *o->base);
    float *v = malloc((nv ? nv : 1) * 6 * sizeof *v);
    uint32_t *idx = malloc((ni ? ni : 1) * sizeof *idx);
    if (!o->first || !o->count || !o->base || !v || !idx || nv > INT32_MAX) {
        free(v);
        free(idx);
        mr_geometry_own_free(o);
        return false;
    }
    size_t vb = 0, ib = 0;
    for (int32_t i = 0; i < n; i++) {
        const mr_geo_own_mesh *m = &meshes[i];
        o->first[i] = (uint32_t)ib;
        o->count[i] = m->index_count;
        o->base[i] = (int32_t)vb;
        for (uint32_t k = 0; k < m->vertex_count; k++) {
            memcpy(v + 6 * (vb + k), m->positions + 3 * (size_t)k, 3 * sizeof *v);
            memcpy(v + 6 * (vb + k) + 3, m->attr + 3 * (size_t)k, 3 * sizeof *v);
        }
        if (m->index_count) memcpy(idx + ib, m->indices, m->index_count * sizeof *idx);
        vb += m->vertex_count;
        ib += m->index_count;
    }
    o->mesh_count = n;
    glCreateBuffers(1, &o->vbo);
    glNamedBufferStorage(o->vbo, (GLsizeiptr)((nv ? nv : 1) * 6 * sizeof *v), v, 0);
    glCreateBuffers(1, &o->ibo);
    glNamedBufferStorage(o->ibo, (GLsizeiptr)((ni ? ni : 1) * sizeof *idx), idx, 0);
    free(v);
    free(idx);
    glCreateVertexArrays(1, &o->vao);
    glVertexArrayVertexBuffer(o->vao, 0, o->vbo, 0, 6 * sizeof(float));
    glEnableVertexArrayAttrib(o->vao, MR_ATTR_POSITION);
    glVertexArrayAttribFormat(o->vao, MR_ATTR_POSITION, 3, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(o->vao, MR_ATTR_POSITION, 0);
    glEnableVertexArrayAttrib(o->vao, attrib);
    glVertexArrayAttribFormat(o->vao, attrib, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float));
    glVertexArrayAttribBinding(o->vao, attrib, 0);
    glVertexArrayElementBuffer(o->vao, o->ibo);
    o->valid = true;
    return true;
}

void mr_geometry_own_free(mr_geo_own *o) {
    if (!o) return;
    if (o->vao) glDeleteVertexArrays(1, &o->vao);
    if (o->vbo) glDeleteBuffers(1, &o->vbo);
    if (o->ibo) glDeleteBuffers(1, &o->ibo);
    free(o->first);
    free(o->count);
    free(o->base);
    memset(o, 0, sizeof *o);
}

static void draw_own_mesh(const void *ctx, int32_t mi) {
    const mr_geo_own *o = ctx;
    if (!o->count[mi]) return;
    glBindVertexArray(o->vao);
    glDrawElementsBaseVertex(GL_TRIANGLES, (GLsizei)o->count[mi], GL_UNSIGNED_INT, (const void *)((size_t)o->first[mi] * 4),
                             o->base[mi]);
}

void mr_geometry_own_draw(mr_renderer *r, const mr_geo_view *vw, const mr_geo_own *o) {
    if (!r->scene || !o->valid) return;
    draw_instances(r, vw, o->mesh_count, draw_own_mesh, o);
}
