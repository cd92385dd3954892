/* Levels of detail above the part: a tree over the scene's nodes whose
 * inner nodes carry simplified proxies of everything below them, merged
 * across node and mesh boundaries (see mr_scene.h, "hlod.c").
 *
 * Build, bottom-up (all proxies of one height at a time, in parallel):
 * a node's input is its children's proxies, or for a leaf child the
 * node's meshes at their coarsest part level, re-expressed relative to the
 * node's centre (double, then float). The input is welded by position
 * (parts that touch become one surface, so the simplifier may collapse
 * across them), simplified to `reduction` of its triangles (edge
 * collapses; vertex clustering where they stall), and the result is
 * certified against the input with the part levels' branch-and-bound
 * Hausdorff bound. The error of the proxy against the full detail then
 * follows from the triangle inequality of the Hausdorff distance and from
 * H(A1 u A2, B1 u B2) <= max(H(A1, B1), H(A2, B2)):
 *
 *   e(node) = max(e(children)) + H(proxy, input) + rounding,
 *
 * where a leaf child's e is its coarsest level's certified error times the
 * node's stretch bound, and rounding bounds what casting the input's
 * positions to float relative to this node's centre moved them.
 *
 * Corners are mapped back from the welded vertices to an input vertex of
 * the same position whose normal fits the face best (creases stay sharp,
 * as in the part levels), and each triangle keeps the source (scene node,
 * mesh) of its first corner, so picking names a real part and each part
 * keeps its colour. Proxies never carry textures (their parts' base
 * colours only). */
#include "mr_scene.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <meshoptimizer.h>

#define HL_MAGIC "MRHLOD01"
#define HL_VERSION 2u

double mr_stretch_bound(const mr_dmat4 *w) {
    double mtm[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double acc = 0;
            for (int k = 0; k < 3; k++) acc += w->m[k * 4 + i] * w->m[k * 4 + j];
            mtm[i][j] = acc;
        }
    double best = 0;
    for (int i = 0; i < 3; i++) {
        double row = fabs(mtm[i][0]) + fabs(mtm[i][1]) + fabs(mtm[i][2]);
        if (row > best) best = row;
    }
    return sqrt(best);
}

double mr_lod_fmax(const mr_camera *c) {
    double ax = fmax(fabs((-1.5 - c->cx) / c->fx), fabs((c->width + 0.5 - c->cx) / c->fx));
    double ay = fmax(fabs((-1.5 - c->cy) / c->fy), fabs((c->height + 0.5 - c->cy) / c->fy));
    return fmax(c->fx, c->fy) * sqrt(1 + ax * ax + ay * ay);
}

bool mr_hlod_wanted(const char *mode, uint64_t drawn_triangles, int32_t drawn_nodes) {
    if (drawn_nodes < 2) return false;
    if (mode && strcmp(mode, "off") == 0) return false;
    if (mode && strcmp(mode, "on") == 0) return true;
    return drawn_triangles >= MR_HLOD_AUTO_TRIANGLES && drawn_nodes >= MR_HLOD_AUTO_NODES;
}

void mr_hlod_cache_path(const char *scene_path, char *out, size_t n) {
    snprintf(out, n, "%s.mrhlod", scene_path ? scene_path : "scene");
}

static void node_free(mr_hlod_node *n) {
    free(n->positions);
    free(n->normals);
    free(n->indices);
    free(n->runs);
    n->positions = n->normals = NULL;
    n->indices = NULL;
    n->runs = NULL;
}

void mr_hlod_destroy(mr_hlod **hp) {
    if (!hp || !*hp) return;
    mr_hlod *h = *hp;
    for (int32_t i = 0; h->nodes && i < h->node_count; i++) node_free(&h->nodes[i]);
    free(h->nodes);
    free(h);
    *hp = NULL;
}

uint64_t mr_hlod_lod_hash(const mr_lod *lod) {
    uint64_t h = 0x84222325cbf29ce4ull;
    if (!lod) return h;
    h = mr_hash64(h, &lod->mesh_count, sizeof lod->mesh_count);
    h = mr_hash64_mix(h, lod->scene_hash);
    for (int32_t i = 0; i < lod->mesh_count; i++) {
        const mr_mesh_lods *ml = &lod->meshes[i];
        h = mr_hash64(h, &ml->level_count, sizeof ml->level_count);
        if (ml->level_count > 0) {
            const mr_lod_level *lv = &ml->levels[ml->level_count - 1];
            h = mr_hash64(h, &lv->index_count, sizeof lv->index_count);
            h = mr_hash64(h, &lv->error, sizeof lv->error);
            h = mr_hash64(h, lv->indices, (size_t)lv->index_count * 4);
        }
    }
    return h;
}

/* ------------------------------------------------------------- the tree */

typedef struct item_key {
    double key;
    int32_t item;
} item_key;

static int cmp_key(const void *a, const void *b) {
    const item_key *x = a, *y = b;
    if (x->key < y->key) return -1;
    if (x->key > y->key) return 1;
    return (x->item > y->item) - (x->item < y->item);
}

/* Breadth-first over [first, first + count) ranges of `items` (sorted in
 * place): every node's children come after it. */
typedef struct tree_job {
    int32_t node, first, count;
} tree_job;

static bool build_tree(mr_hlod *h, const double *bounds, item_key *items, int32_t nitems_total, int32_t *layer_first,
                       int32_t *layer_count) {
    int32_t cap = 2 * nitems_total + 2;
    h->nodes = calloc((size_t)cap, sizeof *h->nodes);
    tree_job *q = malloc((size_t)cap * sizeof *q);
    if (!h->nodes || !q) {
        free(q);
        return false;
    }
    int32_t qn = 0;
    h->node_count = 0;
    for (int l = 0; l < MR_LAYER_COUNT; l++) {
        h->root[l] = -1;
        if (layer_count[l] <= 0) continue;
        int32_t id = h->node_count++;
        h->root[l] = id;
        h->nodes[id].layer = (uint8_t)l;
        q[qn++] = (tree_job){id, layer_first[l], layer_count[l]};
    }
    for (int32_t qi = 0; qi < qn; qi++) {
        tree_job j = q[qi];
        mr_hlod_node *n = &h->nodes[j.node];
        for (int k = 0; k < 3; k++) {
            n->lo[k] = INFINITY;
            n->hi[k] = -INFINITY;
        }
        double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int32_t i = j.first; i < j.first + j.count; i++) {
            const double *b = bounds + 6 * (size_t)items[i].item;
            for (int k = 0; k < 3; k++) {
                n->lo[k] = fmin(n->lo[k], b[k]);
                n->hi[k] = fmax(n->hi[k], b[3 + k]);
                double c = 0.5 * (b[k] + b[3 + k]);
                clo[k] = fmin(clo[k], c);
                chi[k] = fmax(chi[k], c);
            }
        }
        for (int k = 0; k < 3; k++) n->center[k] = 0.5 * (n->lo[k] + n->hi[k]);
        n->child[0] = n->child[1] = -1;
        if (j.count == 1) {
            n->item = items[j.first].item;
            n->error = INFINITY;
            continue;
        }
        n->item = -1;
        int axis = 0;
        for (int k = 1; k < 3; k++)
            if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
        for (int32_t i = j.first; i < j.first + j.count; i++) {
            const double *b = bounds + 6 * (size_t)items[i].item;
            items[i].key = 0.5 * (b[axis] + b[3 + axis]);
        }
        qsort(items + j.first, (size_t)j.count, sizeof *items, cmp_key);
        int32_t half = j.count / 2;
        for (int c = 0; c < 2; c++) {
            int32_t id = h->node_count++;
            h->nodes[j.node].child[c] = id;
            h->nodes[id].layer = h->nodes[j.node].layer;
            q[qn++] = (tree_job){id, c == 0 ? j.first : j.first + half, c == 0 ? half : j.count - half};
        }
    }
    free(q);
    return true;
}

/* ------------------------------------------------------------ proxies */

typedef struct build_ctx {
    const mr_scene *s;
    const mr_lod *lod;
    mr_hlod *h;
    double reduction;
    const int32_t *order; /* inner nodes in order of height */
    bool (*on_progress)(void *, double);
    void *progress_user;
    pthread_mutex_t mu;
    size_t done, total;
    bool stop, failed;
    uint64_t input_tris;
} build_ctx;

/* Growing input of one proxy. */
typedef struct input {
    double *pos; /* relative to the node's centre, double until all is gathered */
    float *nrm;
    uint32_t *src; /* per vertex: index into pairs */
    uint32_t *idx;
    size_t nv, ni, cap_v, cap_i;
    int32_t (*pairs)[2];
    size_t np, cap_p;
} input;

static bool grow(void **p, size_t *cap, size_t need, size_t elem) {
    if (need <= *cap) return true;
    size_t c = *cap ? *cap : 1024;
    while (c < need) c *= 2;
    void *q = realloc(*p, c * elem);
    if (!q) return false;
    *p = q;
    *cap = c;
    return true;
}

static bool input_room(input *in, size_t nv, size_t ni) {
    size_t cv = in->cap_v, ci = in->cap_i;
    bool ok = true;
    size_t c = cv;
    ok = ok && grow((void **)&in->pos, &c, in->nv + nv, 3 * sizeof *in->pos);
    c = cv;
    ok = ok && grow((void **)&in->nrm, &c, in->nv + nv, 3 * sizeof *in->nrm);
    c = cv;
    ok = ok && grow((void **)&in->src, &c, in->nv + nv, sizeof *in->src);
    if (ok) in->cap_v = c;
    ok = ok && grow((void **)&in->idx, &ci, in->ni + ni, sizeof *in->idx);
    if (ok) in->cap_i = ci;
    return ok;
}

static uint32_t input_pair(input *in, int32_t node, int32_t mesh) {
    for (size_t i = in->np; i-- > 0;)
        if (in->pairs[i][0] == node && in->pairs[i][1] == mesh) return (uint32_t)i;
    if (!grow((void **)&in->pairs, &in->cap_p, in->np + 1, sizeof *in->pairs)) return UINT32_MAX;
    in->pairs[in->np][0] = node;
    in->pairs[in->np][1] = mesh;
    return (uint32_t)in->np++;
}

/* A leaf's meshes at their coarsest level; *err_out: the largest level
 * error in world units. */
static bool add_leaf(const build_ctx *x, input *in, int32_t ni, const double center[3], double *err_out,
                     uint32_t *scratch, size_t scratch_n) {
    const mr_scene *s = x->s;
    const mr_node *n = &s->nodes[ni];
    double stretch = mr_stretch_bound(&n->world);
    const double *W = n->world.m;
    /* Normals: the inverse transpose's direction is the cofactor matrix. */
    double C[9];
    C[0] = W[5] * W[10] - W[6] * W[9];
    C[1] = W[6] * W[8] - W[4] * W[10];
    C[2] = W[4] * W[9] - W[5] * W[8];
    C[3] = W[2] * W[9] - W[1] * W[10];
    C[4] = W[0] * W[10] - W[2] * W[8];
    C[5] = W[1] * W[8] - W[0] * W[9];
    C[6] = W[1] * W[6] - W[2] * W[5];
    C[7] = W[2] * W[4] - W[0] * W[6];
    C[8] = W[0] * W[5] - W[1] * W[4];
    double det = W[0] * C[0] + W[1] * C[1] + W[2] * C[2];
    double sg = det < 0 ? -1 : 1;
    for (int32_t mi = n->mesh_first; mi >= 0 && mi < n->mesh_first + n->mesh_count && mi < s->mesh_count; mi++) {
        const mr_mesh *m = &s->meshes[mi];
        const uint32_t *idx = m->indices;
        uint32_t cnt = m->index_count;
        double e = 0;
        const mr_mesh_lods *ml = x->lod && mi < x->lod->mesh_count ? &x->lod->meshes[mi] : NULL;
        if (ml && ml->level_count > 0 && ml->levels[ml->level_count - 1].indices) {
            idx = ml->levels[ml->level_count - 1].indices;
            cnt = ml->levels[ml->level_count - 1].index_count;
            e = ml->levels[ml->level_count - 1].error;
        }
        if (cnt < 3 || m->vertex_count == 0) continue;
        if (m->vertex_count > scratch_n) return false;
        uint32_t pair = input_pair(in, ni, mi);
        if (pair == UINT32_MAX) return false;
        *err_out = fmax(*err_out, e * stretch);
        for (uint32_t v = 0; v < m->vertex_count; v++) scratch[v] = UINT32_MAX;
        uint32_t used = 0;
        for (uint32_t k = 0; k < cnt; k++)
            if (scratch[idx[k]] == UINT32_MAX) scratch[idx[k]] = used++;
        if (!input_room(in, used, cnt)) return false;
        uint32_t base = (uint32_t)in->nv;
        for (uint32_t v = 0; v < m->vertex_count; v++) {
            if (scratch[v] == UINT32_MAX) continue;
            size_t o = base + scratch[v];
            const float *p = m->positions + 3 * (size_t)v;
            double q[3] = {m->origin[0] + p[0], m->origin[1] + p[1], m->origin[2] + p[2]};
            for (int r = 0; r < 3; r++)
                in->pos[3 * o + r] = W[r * 4] * q[0] + W[r * 4 + 1] * q[1] + W[r * 4 + 2] * q[2] + W[r * 4 + 3] - center[r];
            const float *nn = m->normals + 3 * (size_t)v;
            double t[3], len = 0;
            for (int r = 0; r < 3; r++) {
                t[r] = sg * (C[r * 3] * nn[0] + C[r * 3 + 1] * nn[1] + C[r * 3 + 2] * nn[2]);
                len += t[r] * t[r];
            }
            len = len > 0 ? 1 / sqrt(len) : 0;
            for (int r = 0; r < 3; r++) in->nrm[3 * o + r] = (float)(t[r] * len);
            in->src[o] = pair;
        }
        for (uint32_t k = 0; k < cnt; k++) in->idx[in->ni + k] = base + scratch[idx[k]];
        in->nv += used;
        in->ni += cnt;
    }
    return true;
}

static bool add_proxy(input *in, const mr_hlod_node *c, const double center[3]) {
    if (!input_room(in, c->vertex_count, c->index_count)) return false;
    uint32_t base = (uint32_t)in->nv;
    double d[3] = {c->center[0] - center[0], c->center[1] - center[1], c->center[2] - center[2]};
    for (uint32_t v = 0; v < c->vertex_count; v++) {
        for (int r = 0; r < 3; r++) {
            in->pos[3 * (base + v) + r] = (double)c->positions[3 * v + r] + d[r];
            in->nrm[3 * (base + v) + r] = c->normals[3 * v + r];
        }
        in->src[base + v] = UINT32_MAX;
    }
    for (uint32_t r = 0; r < c->run_count; r++) {
        uint32_t pair = input_pair(in, c->runs[r].node, c->runs[r].mesh);
        if (pair == UINT32_MAX) return false;
        for (uint32_t k = c->runs[r].first; k < c->runs[r].first + c->runs[r].count; k++)
            if (in->src[base + c->indices[k]] == UINT32_MAX) in->src[base + c->indices[k]] = pair;
    }
    for (uint32_t k = 0; k < c->index_count; k++) in->idx[in->ni + k] = base + c->indices[k];
    in->nv += c->vertex_count;
    in->ni += c->index_count;
    return true;
}

static void input_free(input *in) {
    free(in->pos);
    free(in->nrm);
    free(in->src);
    free(in->idx);
    free(in->pairs);
    memset(in, 0, sizeof *in);
}

/* The proxy of inner node `id` from its gathered input. */
static bool make_proxy(build_ctx *x, int32_t id, input *in, double e_in) {
    mr_hlod_node *n = &x->h->nodes[id];
    size_t nv = in->nv, ni = in->ni;
    if (ni < 3 || nv == 0) {
        n->error = e_in; /* nothing below draws: an empty proxy is exact */
        return true;
    }
    /* Float positions relative to the centre; the rounding moved each by at
     * most half an ulp of the largest coordinate per axis. */
    float *fpos = malloc(nv * 3 * sizeof *fpos);
    uint32_t *remap = malloc(nv * sizeof *remap);
    uint32_t *widx = malloc(ni * sizeof *widx), *dst = malloc(ni * sizeof *dst), *dst2 = malloc(ni * sizeof *dst2);
    float *wpos = NULL;
    uint32_t *first = NULL, *list = NULL, *vmap = NULL, *tri_src = NULL, *order = NULL;
    bool ok = false;
    if (!fpos || !remap || !widx || !dst || !dst2) goto out;
    double maxabs = 0;
    for (size_t k = 0; k < nv * 3; k++) {
        fpos[k] = (float)in->pos[k];
        if (fabs(in->pos[k]) > maxabs) maxabs = fabs(in->pos[k]);
    }
    double rounding = sqrt(3.0) * maxabs * ldexp(1.0, -23); /* both the input's and (same vertices) the proxy's */
    size_t wn = meshopt_generateVertexRemap(remap, NULL, nv, fpos, nv, 12);
    wpos = malloc((wn ? wn : 1) * 3 * sizeof *wpos);
    if (!wpos) goto out;
    meshopt_remapVertexBuffer(wpos, fpos, nv, 12, remap);
    for (size_t k = 0; k < ni; k++) widx[k] = remap[in->idx[k]];
    size_t target = (size_t)((double)(ni / 3) * x->reduction) * 3;
    if (target < 3) target = 3;
    float est = 0, est2 = 0;
    size_t n1 = meshopt_simplify(dst, widx, ni, wpos, wn, 12, target, 1.0f, 0, &est);
    const uint32_t *res = dst;
    size_t rn = n1;
    if (n1 > target + target / 4 || n1 < 3) {
        size_t n2 = meshopt_simplifySloppy(dst2, widx, ni, wpos, wn, 12, target, 1.0f, &est2);
        if (n2 >= 3 && (n2 < n1 || n1 < 3)) {
            res = dst2;
            rn = n2;
            est = est2;
        }
    }
    double h_err = 0;
    if (rn < 3) {
        /* Nothing left: keep the input as it is (exact). */
        memcpy(dst, widx, ni * sizeof *dst);
        res = dst;
        rn = ni;
    } else {
        float scale = meshopt_simplifyScale(wpos, wn, 12);
        double est_abs = (double)est * scale;
        double res_tol = fmax(0.05 * est_abs, 1e-6 * scale);
        h_err = mr_lod_hausdorff_bound_within(wpos, (uint32_t)wn, widx, (uint32_t)ni, res, (uint32_t)rn, est_abs, res_tol,
                                              INFINITY);
        if (!isfinite(h_err)) {
            memcpy(dst, widx, ni * sizeof *dst); /* not certified: the input itself */
            res = dst;
            rn = ni;
            h_err = 0;
        }
    }
    /* Welded corners back to an input vertex of that position whose normal
     * fits the face: CSR lists of the input vertices per welded vertex. */
    first = calloc(wn + 1, sizeof *first);
    list = malloc(nv * sizeof *list);
    vmap = malloc(nv * sizeof *vmap);
    tri_src = malloc((rn / 3 + 1) * sizeof *tri_src);
    order = malloc((rn / 3 + 1) * sizeof *order);
    if (!first || !list || !vmap || !tri_src || !order) goto out;
    for (size_t v = 0; v < nv; v++) first[remap[v] + 1]++;
    for (size_t w = 0; w < wn; w++) first[w + 1] += first[w];
    {
        uint32_t *fill = malloc((wn + 1) * sizeof *fill);
        if (!fill) goto out;
        memcpy(fill, first, (wn + 1) * sizeof *fill);
        for (size_t v = 0; v < nv; v++) list[fill[remap[v]]++] = (uint32_t)v;
        free(fill);
    }
    uint32_t *corner = malloc(rn * sizeof *corner);
    if (!corner) goto out;
    for (size_t t = 0; t < rn; t += 3) {
        const float *a = wpos + 3 * (size_t)res[t], *b = wpos + 3 * (size_t)res[t + 1], *c = wpos + 3 * (size_t)res[t + 2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double fn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++) {
            uint32_t w = res[t + k], best = list[first[w]];
            double bd = -INFINITY;
            for (uint32_t j = first[w]; j < first[w + 1]; j++) {
                const float *nn = in->nrm + 3 * (size_t)list[j];
                double d = nn[0] * fn[0] + nn[1] * fn[1] + nn[2] * fn[2];
                if (d > bd) {
                    bd = d;
                    best = list[j];
                }
            }
            corner[t + k] = best;
        }
        uint32_t sp = in->src[corner[t]];
        tri_src[t / 3] = sp == UINT32_MAX ? 0 : sp;
    }
    /* Compact the used input vertices; triangles sorted by source. */
    for (size_t v = 0; v < nv; v++) vmap[v] = UINT32_MAX;
    uint32_t used = 0;
    for (size_t k = 0; k < rn; k++)
        if (vmap[corner[k]] == UINT32_MAX) vmap[corner[k]] = used++;
    size_t ntri = rn / 3, np = in->np ? in->np : 1;
    uint32_t *cnt = calloc(np + 1, sizeof *cnt);
    n->positions = malloc((size_t)used * 3 * sizeof *n->positions);
    n->normals = malloc((size_t)used * 3 * sizeof *n->normals);
    n->indices = malloc(rn * sizeof *n->indices);
    if (!cnt || !n->positions || !n->normals || !n->indices) {
        free(cnt);
        free(corner);
        goto out;
    }
    for (size_t v = 0; v < nv; v++) {
        if (vmap[v] == UINT32_MAX) continue;
        memcpy(n->positions + 3 * (size_t)vmap[v], fpos + 3 * v, 12);
        memcpy(n->normals + 3 * (size_t)vmap[v], in->nrm + 3 * v, 12);
    }
    for (size_t t = 0; t < ntri; t++) cnt[tri_src[t] + 1]++;
    uint32_t runs = 0;
    for (size_t p = 0; p < np; p++) runs += cnt[p + 1] > 0;
    n->runs = malloc((runs ? runs : 1) * sizeof *n->runs);
    if (!n->runs) {
        free(cnt);
        free(corner);
        goto out;
    }
    uint32_t r = 0;
    for (size_t p = 0; p < np; p++) {
        uint32_t c = cnt[p + 1];
        cnt[p + 1] += cnt[p];
        if (c == 0) continue;
        n->runs[r++] = (mr_hlod_run){cnt[p] * 3, c * 3, in->np ? in->pairs[p][0] : -1, in->np ? in->pairs[p][1] : -1};
    }
    for (size_t t = 0; t < ntri; t++) order[cnt[tri_src[t]]++] = (uint32_t)t;
    for (size_t k = 0; k < ntri; k++)
        for (int j = 0; j < 3; j++) n->indices[3 * k + j] = vmap[corner[3 * (size_t)order[k] + j]];
    free(cnt);
    free(corner);
    n->vertex_count = used;
    n->index_count = (uint32_t)rn;
    n->run_count = r;
    n->error = e_in + h_err + rounding;
    ok = true;
out:
    if (!ok) node_free(n);
    free(fpos);
    free(remap);
    free(widx);
    free(dst);
    free(dst2);
    free(wpos);
    free(first);
    free(list);
    free(vmap);
    free(tri_src);
    free(order);
    return ok;
}

static bool build_one(void *arg, size_t k) {
    build_ctx *x = arg;
    if (x->stop) return false;
    int32_t id = x->order[k];
    mr_hlod_node *n = &x->h->nodes[id];
    input in;
    memset(&in, 0, sizeof in);
    double e_in = 0;
    bool ok = true;
    uint32_t *scratch = NULL;
    size_t scratch_n = 0;
    uint64_t tris = 0;
    for (int c = 0; c < 2 && ok; c++) {
        const mr_hlod_node *ch = &x->h->nodes[n->child[c]];
        if (ch->item >= 0) {
            const mr_node *sn = &x->s->nodes[ch->item];
            uint32_t maxv = 0;
            for (int32_t mi = sn->mesh_first; mi >= 0 && mi < sn->mesh_first + sn->mesh_count && mi < x->s->mesh_count; mi++)
                if (x->s->meshes[mi].vertex_count > maxv) maxv = x->s->meshes[mi].vertex_count;
            if (maxv > scratch_n) {
                free(scratch);
                scratch = malloc((size_t)maxv * sizeof *scratch);
                scratch_n = scratch ? maxv : 0;
                if (!scratch) ok = false;
            }
            size_t before = in.ni;
            ok = ok && add_leaf(x, &in, ch->item, n->center, &e_in, scratch, scratch_n);
            tris += (in.ni - before) / 3;
        } else {
            if (!isfinite(ch->error)) ok = false;
            e_in = fmax(e_in, ch->error);
            size_t before = in.ni;
            ok = ok && add_proxy(&in, ch, n->center);
            tris += (in.ni - before) / 3;
        }
    }
    free(scratch);
    ok = ok && make_proxy(x, id, &in, e_in);
    input_free(&in);
    pthread_mutex_lock(&x->mu);
    x->input_tris += tris;
    if (!ok) {
        x->failed = true;
        x->stop = true;
    } else {
        x->done++;
        if (x->on_progress && !x->on_progress(x->progress_user, (double)x->done / (double)x->total)) x->stop = true;
    }
    pthread_mutex_unlock(&x->mu);
    return !x->stop;
}

static mr_hlod *build(const mr_scene *s, const mr_lod *lod, const mr_hlod_params *params, uint64_t *input_tris,
                      mr_error *err) {
    mr_hlod_params p = MR_HLOD_DEFAULTS;
    if (params) p = *params;
    if (!(p.reduction > 0 && p.reduction < 1)) p.reduction = 0.5;
    if (!s) {
        mr_fail(err, MR_ERR_INVALID, "no scene");
        return NULL;
    }
    if (lod && lod->mesh_count != s->mesh_count) lod = NULL;
    size_t nn = (size_t)s->node_count;
    double *bounds = malloc((nn + 1) * 6 * sizeof *bounds);
    item_key *items = malloc((nn + 1) * sizeof *items);
    mr_hlod *h = calloc(1, sizeof *h);
    if (!bounds || !items || !h) {
        free(bounds);
        free(items);
        free(h);
        mr_fail(err, MR_ERR_NOMEM, "out of memory building the LOD hierarchy");
        return NULL;
    }
    int32_t lf[MR_LAYER_COUNT], lc[MR_LAYER_COUNT], total = 0;
    for (int l = 0; l < MR_LAYER_COUNT; l++) {
        lf[l] = total;
        lc[l] = 0;
        for (size_t i = 0; i < nn; i++) {
            const mr_node *n = &s->nodes[i];
            double *b = bounds + 6 * i;
            if (n->layer != l || n->shadow_catcher || !mr_scene_node_bounds(s, (int32_t)i, b, b + 3)) continue;
            if (!isfinite(b[0] + b[1] + b[2] + b[3] + b[4] + b[5])) continue;
            items[total++] = (item_key){0, (int32_t)i};
            lc[l]++;
        }
    }
    h->scene_hash = mr_lod_scene_hash(s);
    h->lod_hash = mr_hlod_lod_hash(lod);
    h->scene_node_count = s->node_count;
    h->scene_mesh_count = s->mesh_count;
    if (total < 2) {
        free(bounds);
        free(items);
        free(h);
        mr_fail(err, MR_ERR_INVALID, "a LOD hierarchy needs at least two drawn nodes");
        return NULL;
    }
    bool ok = build_tree(h, bounds, items, total, lf, lc);
    free(bounds);
    free(items);
    int32_t *height = ok ? calloc((size_t)h->node_count, sizeof *height) : NULL;
    int32_t *order = ok ? malloc((size_t)h->node_count * sizeof *order) : NULL;
    if (!ok || !height || !order) {
        free(height);
        free(order);
        mr_hlod_destroy(&h);
        mr_fail(err, MR_ERR_NOMEM, "out of memory building the LOD hierarchy");
        return NULL;
    }
    /* Children come after their parent (breadth first): heights from the
     * back. */
    int32_t maxh = 0, ninner = 0;
    for (int32_t i = h->node_count; i-- > 0;) {
        const mr_hlod_node *n = &h->nodes[i];
        if (n->child[0] < 0) continue;
        int32_t a = height[n->child[0]], b = height[n->child[1]];
        height[i] = 1 + (a > b ? a : b);
        if (height[i] > maxh) maxh = height[i];
        ninner++;
    }
    build_ctx x;
    memset(&x, 0, sizeof x);
    x.s = s;
    x.lod = lod;
    x.h = h;
    x.reduction = p.reduction;
    x.order = order;
    x.on_progress = p.on_progress;
    x.progress_user = p.progress_user;
    x.total = (size_t)ninner;
    pthread_mutex_init(&x.mu, NULL);
    for (int32_t hh = 1; hh <= maxh && !x.stop; hh++) {
        size_t cnt = 0;
        for (int32_t i = 0; i < h->node_count; i++)
            if (height[i] == hh) order[cnt++] = i;
        mr_parallel_for(cnt, p.threads, build_one, &x);
    }
    pthread_mutex_destroy(&x.mu);
    free(height);
    free(order);
    if (x.stop) {
        mr_hlod_destroy(&h);
        if (x.failed) mr_fail(err, MR_ERR_NOMEM, "out of memory building the LOD hierarchy");
        else mr_fail(err, MR_ERR_INTERRUPTED, "LOD hierarchy build interrupted");
        return NULL;
    }
    for (int32_t i = 0; i < h->node_count; i++) h->proxy_triangles += h->nodes[i].index_count / 3;
    if (input_tris) *input_tris = x.input_tris;
    return h;
}

mr_hlod *mr_hlod_build(const mr_scene *s, const mr_lod *lod, const mr_hlod_params *params, mr_error *err) {
    return build(s, lod, params, NULL, err);
}

/* ---------------------------------------------------------------- cut */

bool mr_hlod_cut(const mr_hlod *h, const mr_hlod_cut_params *p, int32_t *proxies, int32_t *proxy_count,
                 int32_t *nodes, int32_t *node_count) {
    *proxy_count = 0;
    *node_count = 0;
    if (!h || !p || !proxies || !nodes) return false;
    int32_t stack[128];
    const double *M = p->cam_from_world.m;
    for (int l = 0; l < MR_LAYER_COUNT; l++) {
        if (!(p->layers & (1u << l)) || h->root[l] < 0) continue;
        int sp = 0;
        stack[sp++] = h->root[l];
        while (sp > 0) {
            int32_t id = stack[--sp];
            const mr_hlod_node *n = &h->nodes[id];
            if (p->frustum && mr_frustum_test_box(p->frustum, n->lo, n->hi) < 0) continue;
            if (n->item >= 0) {
                nodes[(*node_count)++] = n->item;
                continue;
            }
            /* Nearest depth of the box (as the part levels' choice). */
            double c = M[11], e = 0;
            for (int k = 0; k < 3; k++) {
                double mid = 0.5 * n->lo[k] + 0.5 * n->hi[k], half = 0.5 * n->hi[k] - 0.5 * n->lo[k];
                c += M[8 + k] * mid;
                e += fabs(M[8 + k]) * half;
            }
            double zmin = c - e;
            bool use = zmin > p->near_plane && isfinite(n->error) && n->error <= p->tolerance &&
                       n->error * (p->fmax / zmin) <= p->pixels;
            if (use) {
                proxies[(*proxy_count)++] = id;
                continue;
            }
            if (sp + 2 > (int)(sizeof stack / sizeof *stack)) return false; /* deeper than any median split */
            stack[sp++] = n->child[1];
            stack[sp++] = n->child[0];
        }
    }
    return true;
}

/* -------------------------------------------------------------- cache */

typedef struct wbuf {
    unsigned char *p;
    size_t n, cap;
    bool oom;
} wbuf;

static void put(wbuf *b, const void *d, size_t n) {
    if (b->oom || n == 0) return;
    if (!grow((void **)&b->p, &b->cap, b->n + n, 1)) {
        b->oom = true;
        return;
    }
    memcpy(b->p + b->n, d, n);
    b->n += n;
}

typedef struct disk_node {
    double lo[3], hi[3], center[3], error;
    int32_t child[2], item;
    uint32_t layer, vertex_count, index_count, run_count, pad;
} disk_node;

/* Where the parts are drawn: the proxies are merged in world space, so a
 * node moved, drawing other meshes or on another layer, or a mesh's origin
 * moved, makes a cache stale although every mesh is the same. */
static uint64_t placement_hash(const mr_scene *s) {
    uint64_t h = 0x243f6a8885a308d3ull;
    h = mr_hash64(h, &s->node_count, sizeof s->node_count);
    for (int32_t i = 0; i < s->node_count; i++) {
        const mr_node *n = &s->nodes[i];
        uint8_t flags[2] = {n->layer, n->shadow_catcher};
        h = mr_hash64(h, n->world.m, sizeof n->world.m);
        h = mr_hash64(h, &n->mesh_first, sizeof n->mesh_first);
        h = mr_hash64(h, &n->mesh_count, sizeof n->mesh_count);
        h = mr_hash64(h, flags, sizeof flags);
    }
    for (int32_t i = 0; i < s->mesh_count; i++) h = mr_hash64(h, s->meshes[i].origin, sizeof s->meshes[i].origin);
    return h;
}

static bool cache_write(const mr_scene *s, const mr_hlod *h, double reduction, const char *path, mr_error *err) {
    wbuf b = {0};
    uint32_t ver = HL_VERSION, nc = (uint32_t)h->node_count;
    put(&b, HL_MAGIC, 8);
    put(&b, &ver, 4);
    put(&b, &nc, 4);
    put(&b, &h->scene_hash, 8);
    put(&b, &h->lod_hash, 8);
    put(&b, &reduction, 8);
    uint64_t ph = placement_hash(s);
    put(&b, &ph, 8);
    put(&b, &h->scene_node_count, 4);
    put(&b, &h->scene_mesh_count, 4);
    put(&b, h->root, sizeof h->root);
    for (int32_t i = 0; i < h->node_count; i++) {
        const mr_hlod_node *n = &h->nodes[i];
        disk_node d;
        memset(&d, 0, sizeof d);
        memcpy(d.lo, n->lo, sizeof d.lo);
        memcpy(d.hi, n->hi, sizeof d.hi);
        memcpy(d.center, n->center, sizeof d.center);
        d.error = n->error;
        d.child[0] = n->child[0];
        d.child[1] = n->child[1];
        d.item = n->item;
        d.layer = n->layer;
        d.vertex_count = n->vertex_count;
        d.index_count = n->index_count;
        d.run_count = n->run_count;
        put(&b, &d, sizeof d);
        put(&b, n->positions, (size_t)n->vertex_count * 12);
        put(&b, n->normals, (size_t)n->vertex_count * 12);
        put(&b, n->indices, (size_t)n->index_count * 4);
        put(&b, n->runs, (size_t)n->run_count * sizeof *n->runs);
    }
    uint64_t sum = b.oom ? 0 : mr_hash64(0x9e3779b97f4a7c15ull, b.p, b.n);
    put(&b, &sum, 8);
    bool ok = !b.oom && mr_file_write_atomic(path, b.p, b.n, err);
    if (b.oom) mr_fail(err, MR_ERR_NOMEM, "out of memory writing %s", path);
    free(b.p);
    return ok;
}

typedef struct rbuf {
    const unsigned char *p;
    size_t n, at;
} rbuf;

static bool get(rbuf *r, void *d, size_t n) {
    if (n > r->n - r->at) return false;
    if (n) memcpy(d, r->p + r->at, n);
    r->at += n;
    return true;
}

static bool get_array(rbuf *r, void **out, size_t n) {
    if (n > r->n - r->at) return false;
    *out = malloc(n ? n : 1);
    return *out && get(r, *out, n);
}

static bool node_valid(const mr_hlod *h, int32_t i, const mr_scene *s) {
    const mr_hlod_node *n = &h->nodes[i];
    if (n->layer >= MR_LAYER_COUNT) return false;
    for (int k = 0; k < 3; k++)
        if (!isfinite(n->lo[k]) || !isfinite(n->hi[k]) || !isfinite(n->center[k]) || !(n->lo[k] <= n->hi[k])) return false;
    if (n->item >= 0) {
        return n->child[0] == -1 && n->child[1] == -1 && n->item < s->node_count && n->vertex_count == 0 &&
               n->index_count == 0 && n->run_count == 0;
    }
    if (n->item != -1 || !(n->error >= 0) || !isfinite(n->error)) return false;
    for (int c = 0; c < 2; c++)
        if (n->child[c] <= i || n->child[c] >= h->node_count) return false;
    if (n->index_count % 3) return false;
    for (uint32_t k = 0; k < n->vertex_count * 3; k++)
        if (!isfinite(n->positions[k]) || !isfinite(n->normals[k])) return false;
    for (uint32_t k = 0; k < n->index_count; k++)
        if (n->indices[k] >= n->vertex_count) return false;
    uint32_t at = 0;
    for (uint32_t r = 0; r < n->run_count; r++) {
        const mr_hlod_run *q = &n->runs[r];
        if (q->first != at || q->count == 0 || q->count % 3 || q->count > n->index_count - at) return false;
        if (q->node < 0 || q->node >= s->node_count || q->mesh < 0 || q->mesh >= s->mesh_count) return false;
        at += q->count;
    }
    return at == n->index_count;
}

static mr_hlod *cache_read(const mr_scene *s, const mr_lod *lod, double reduction, const char *path, const char **why) {
    size_t size = 0;
    mr_error e;
    unsigned char *data = mr_file_read(path, &size, 0, &e);
    if (!data) {
        *why = "no cache";
        return NULL;
    }
    rbuf r = {data, size, 0};
    mr_hlod *h = NULL;
    char magic[8];
    uint32_t ver, nc;
    uint64_t sum, sh, lh, ph;
    double red;
    *why = "not a LOD hierarchy cache";
    if (size < 16 || !get(&r, magic, 8) || memcmp(magic, HL_MAGIC, 8) != 0) goto out;
    memcpy(&sum, data + size - 8, 8);
    *why = "checksum mismatch (truncated or damaged)";
    if (mr_hash64(0x9e3779b97f4a7c15ull, data, size - 8) != sum) goto out;
    r.n = size - 8;
    *why = "written for another scene or other levels";
    if (!get(&r, &ver, 4) || ver != HL_VERSION || !get(&r, &nc, 4) || !get(&r, &sh, 8) || sh != mr_lod_scene_hash(s) ||
        !get(&r, &lh, 8) || lh != mr_hlod_lod_hash(lod) || !get(&r, &red, 8) || red != reduction ||
        !get(&r, &ph, 8) || ph != placement_hash(s))
        goto out;
    *why = "malformed";
    if (nc == 0 || nc > (uint32_t)(2 * s->node_count + 2)) goto out;
    h = calloc(1, sizeof *h);
    if (!h || !(h->nodes = calloc(nc, sizeof *h->nodes))) goto fail;
    h->node_count = (int32_t)nc;
    h->scene_hash = sh;
    h->lod_hash = lh;
    if (!get(&r, &h->scene_node_count, 4) || h->scene_node_count != s->node_count || !get(&r, &h->scene_mesh_count, 4) ||
        h->scene_mesh_count != s->mesh_count || !get(&r, h->root, sizeof h->root))
        goto fail;
    for (int l = 0; l < MR_LAYER_COUNT; l++)
        if (h->root[l] < -1 || h->root[l] >= h->node_count) goto fail;
    for (uint32_t i = 0; i < nc; i++) {
        mr_hlod_node *n = &h->nodes[i];
        disk_node d;
        if (!get(&r, &d, sizeof d)) goto fail;
        memcpy(n->lo, d.lo, sizeof d.lo);
        memcpy(n->hi, d.hi, sizeof d.hi);
        memcpy(n->center, d.center, sizeof d.center);
        n->error = d.error;
        n->child[0] = d.child[0];
        n->child[1] = d.child[1];
        n->item = d.item;
        n->layer = (uint8_t)(d.layer < 256 ? d.layer : 255);
        if (d.layer >= MR_LAYER_COUNT) goto fail;
        if ((uint64_t)d.vertex_count * 24 + (uint64_t)d.index_count * 4 + (uint64_t)d.run_count * sizeof(mr_hlod_run) >
            r.n - r.at)
            goto fail;
        n->vertex_count = d.vertex_count;
        n->index_count = d.index_count;
        n->run_count = d.run_count;
        if (!get_array(&r, (void **)&n->positions, (size_t)n->vertex_count * 12) ||
            !get_array(&r, (void **)&n->normals, (size_t)n->vertex_count * 12) ||
            !get_array(&r, (void **)&n->indices, (size_t)n->index_count * 4) ||
            !get_array(&r, (void **)&n->runs, (size_t)n->run_count * sizeof *n->runs))
            goto fail;
        if (!node_valid(h, (int32_t)i, s)) goto fail;
        h->proxy_triangles += n->index_count / 3;
    }
    if (r.at != r.n) goto fail;
    *why = NULL;
    goto out;
fail:
    mr_hlod_destroy(&h);
out:
    free(data);
    return h;
}

mr_hlod *mr_hlod_load_or_build(const mr_scene *s, const mr_lod *lod, const char *cache_path,
                               const mr_hlod_params *params, mr_hlod_info *info, mr_error *err) {
    mr_hlod_info hi;
    memset(&hi, 0, sizeof hi);
    if (!s) {
        mr_fail(err, MR_ERR_INVALID, "no scene");
        return NULL;
    }
    if (lod && lod->mesh_count != s->mesh_count) lod = NULL;
    double reduction = params && params->reduction > 0 && params->reduction < 1 ? params->reduction : 0.5;
    mr_hlod *h = NULL;
    if (cache_path) {
        const char *why = NULL;
        h = cache_read(s, lod, reduction, cache_path, &why);
        if (h) hi.from_cache = true;
        else if (why && strcmp(why, "no cache") != 0)
            mr_log(MR_LOG_WARN, "%s: ignored (%s); rebuilding the LOD hierarchy", cache_path, why);
    }
    if (!h) {
        double t0 = mr_time_now();
        h = build(s, lod, params, &hi.input_triangles, err);
        if (!h) return NULL;
        hi.build_s = mr_time_now() - t0;
        if (cache_path) {
            mr_error we = {0};
            hi.cache_written = cache_write(s, h, reduction, cache_path, &we);
            if (!hi.cache_written) mr_log(MR_LOG_WARN, "LOD hierarchy cache not written: %s", we.msg);
        }
    }
    if (info) *info = hi;
    return h;
}
