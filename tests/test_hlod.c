/* Levels of detail above the part (lib/scene/hlod.c): the proxies' error
 * bound against brute force at scales 1e-3, 1 and 1e3 and 1e7 from the
 * origin; the same cut in metres and millimetres; proxies naming real
 * parts of their own layer; the decision function; the cache file
 * detected when truncated or damaged, and rebuilt. */
#include "mr_test.h"
#include "mr_test_lod.h"
#include "mr_scene.h"
#include "mr_render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *tmp_dir(void) {
    const char *t = getenv("MR_TEST_TMP");
    return t && *t ? t : "/tmp";
}

static mr_scene *cad(double unit, double ox, int parts, uint32_t tris) {
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    cp.parts = parts;
    cp.part_triangles = tris;
    cp.unit = unit;
    cp.origin[0] = ox;
    cp.origin[2] = -ox;
    mr_error err = {0};
    mr_scene *s = mr_synth_cad_build(&cp, &err);
    /* every third part in the hidden layer */
    for (int32_t i = 0; s && i < s->node_count; i++)
        if (s->nodes[i].mesh_count > 0 && i % 3 == 1) s->nodes[i].layer = MR_LAYER_HIDDEN;
    if (!s) fprintf(stderr, "synth: %s\n", err.msg);
    return s;
}

typedef struct fbuf {
    float *pos;
    uint32_t *a, *b;
    size_t nv, na, nb, cv, ca, cb;
} fbuf;

static void push_v(fbuf *f, const double p[3], const double ref[3]) {
    if (f->nv == f->cv) {
        f->cv = f->cv ? 2 * f->cv : 4096;
        f->pos = realloc(f->pos, f->cv * 3 * sizeof *f->pos);
    }
    for (int k = 0; k < 3; k++) f->pos[3 * f->nv + k] = (float)(p[k] - ref[k]);
    f->nv++;
}

static void push_i(uint32_t **a, size_t *n, size_t *c, uint32_t v) {
    if (*n == *c) {
        *c = *c ? 2 * *c : 4096;
        *a = realloc(*a, *c * sizeof **a);
    }
    (*a)[(*n)++] = v;
}

/* The full detail of the scene nodes below tree node id (world, relative
 * to ref) as list a. */
static void gather_full(const mr_scene *s, const mr_hlod *h, int32_t id, const double ref[3], fbuf *f) {
    const mr_hlod_node *n = &h->nodes[id];
    if (n->item < 0) {
        gather_full(s, h, n->child[0], ref, f);
        gather_full(s, h, n->child[1], ref, f);
        return;
    }
    const mr_node *sn = &s->nodes[n->item];
    for (int32_t mi = sn->mesh_first; mi < sn->mesh_first + sn->mesh_count; mi++) {
        const mr_mesh *m = &s->meshes[mi];
        uint32_t base = (uint32_t)f->nv;
        for (uint32_t v = 0; v < m->vertex_count; v++) {
            const float *p = m->positions + 3 * v;
            mr_dvec3 w = mr_m4_point(&sn->world, mr_v3(m->origin[0] + p[0], m->origin[1] + p[1], m->origin[2] + p[2]));
            double q[3] = {w.x, w.y, w.z};
            push_v(f, q, ref);
        }
        for (uint32_t k = 0; k < m->index_count; k++) push_i(&f->a, &f->na, &f->ca, base + m->indices[k]);
    }
}

/* Brute force: the largest sampled distance between the proxy of id and
 * the full detail below it, both ways. */
static double brute(const mr_scene *s, const mr_hlod *h, int32_t id) {
    const mr_hlod_node *n = &h->nodes[id];
    fbuf f;
    memset(&f, 0, sizeof f);
    gather_full(s, h, id, n->center, &f);
    uint32_t base = (uint32_t)f.nv;
    for (uint32_t v = 0; v < n->vertex_count; v++) {
        double q[3] = {n->positions[3 * v], n->positions[3 * v + 1], n->positions[3 * v + 2]}, z[3] = {0, 0, 0};
        push_v(&f, q, z);
    }
    for (uint32_t k = 0; k < n->index_count; k++) push_i(&f.b, &f.nb, &f.cb, base + n->indices[k]);
    double d = 0;
    if (f.na >= 3 && f.nb >= 3) {
        double ab = mr_test_sampled_distance(f.pos, f.a, (uint32_t)f.na, f.b, (uint32_t)f.nb, 3);
        double ba = mr_test_sampled_distance(f.pos, f.b, (uint32_t)f.nb, f.a, (uint32_t)f.na, 3);
        d = ab > ba ? ab : ba;
    }
    free(f.pos);
    free(f.a);
    free(f.b);
    return d;
}

static void check_runs(const mr_scene *s, const mr_hlod *h) {
    for (int32_t i = 0; i < h->node_count; i++) {
        const mr_hlod_node *n = &h->nodes[i];
        uint32_t at = 0;
        for (uint32_t r = 0; r < n->run_count; r++) {
            const mr_hlod_run *q = &n->runs[r];
            CHECK(q->first == at && q->count % 3 == 0 && q->count > 0);
            CHECK(q->node >= 0 && q->node < s->node_count);
            const mr_node *sn = &s->nodes[q->node];
            CHECK(q->mesh >= sn->mesh_first && q->mesh < sn->mesh_first + sn->mesh_count); /* a mesh of that part */
            CHECK(sn->layer == n->layer);                                               /* never across layers */
            at += q->count;
        }
        CHECK(at == n->index_count);
    }
}

static void test_bound(double unit, double offset) {
    mr_scene *s = cad(unit, offset, 6, 600);
    CHECK(s != NULL);
    if (!s) return;
    mr_error err = {0};
    mr_lod_params lp = MR_LOD_DEFAULTS;
    mr_lod *lod = mr_lod_build(s, &lp, &err);
    CHECK(lod != NULL);
    mr_hlod_params hp = MR_HLOD_DEFAULTS;
    mr_hlod *h = mr_hlod_build(s, lod, &hp, &err);
    CHECK_MSG(h != NULL, "%s", err.msg);
    if (h) {
        check_runs(s, h);
        int tested = 0, nonzero = 0;
        double diag = mr_scene_diagonal(s);
        for (int32_t i = 0; i < h->node_count; i++) {
            const mr_hlod_node *n = &h->nodes[i];
            if (n->item >= 0) continue;
            double b = brute(s, h, i);
            tested++;
            nonzero += b > 1e-6 * diag;
            CHECK(isfinite(n->error) && n->error >= 0);
            CHECK_MSG(b <= n->error * (1 + 1e-9) + 1e-12 * diag,
                         "unit %g offset %g: node %d sampled %.6g > bound %.6g", unit, offset, (int)i, b, n->error);
            /* ... and not a bound that says nothing */
            CHECK_MSG(n->error < 0.5 * diag, "node %d bound %.6g of a diagonal %.6g", (int)i, n->error, diag);
        }
        CHECK(tested >= 3);
        CHECK(nonzero >= 1); /* the proxies do simplify */
        /* Fewer triangles up the tree */
        int32_t root = h->root[MR_LAYER_VISIBLE];
        CHECK(root >= 0);
        uint64_t full = 0;
        for (int32_t i = 0; i < s->mesh_count; i++) full += s->meshes[i].index_count / 3;
        if (root >= 0) CHECK(h->nodes[root].index_count / 3 < full / 4);
    }
    mr_hlod_destroy(&h);
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
}

static void cut_view(const mr_hlod *h, int which, double unit, double px, int32_t *buf, int32_t n, int32_t *np,
                     int32_t *nn) {
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    cp.parts = 24;
    cp.part_triangles = 800;
    cp.unit = unit;
    mr_view v = mr_synth_view(NULL, &cp, which);
    mr_hlod_cut_params c;
    memset(&c, 0, sizeof c);
    c.cam_from_world = mr_m4_invert_rigid(&v.world_from_camera);
    c.near_plane = 0.05 * unit;
    c.fmax = mr_lod_fmax(&v.camera);
    c.pixels = px;
    c.tolerance = INFINITY;
    c.layers = 3;
    mr_frustum fr = mr_frustum_from_camera(&v.camera, &v.world_from_camera, c.near_plane, 1.0);
    c.frustum = &fr;
    CHECK(mr_hlod_cut(h, &c, buf, np, buf + n, nn));
}

/* The same hall in metres and in millimetres. The cut is a function of
 * projected errors only: the metre tree with its bounds, centres and
 * errors in millimetres, seen from the millimetre viewpoints, is cut at
 * exactly the same nodes. The two builds' certified errors agree to
 * within the spread of the simplifier on float-rounded input (meshopt's
 * collapse order tips on the last bits, as for the part levels). */
static void test_units(void) {
    mr_scene *s[2] = {cad(1, 0, 24, 800), cad(1000, 0, 24, 800)};
    CHECK(s[0] && s[1]);
    if (!s[0] || !s[1]) return;
    mr_hlod *h[2] = {NULL, NULL};
    mr_lod *lod[2] = {NULL, NULL};
    for (int k = 0; k < 2; k++) {
        mr_error err = {0};
        mr_lod_params lp = MR_LOD_DEFAULTS;
        lod[k] = mr_lod_build(s[k], &lp, &err);
        mr_hlod_params hp = MR_HLOD_DEFAULTS;
        h[k] = mr_hlod_build(s[k], lod[k], &hp, &err);
        CHECK(h[k] != NULL);
    }
    if (h[0] && h[1]) {
        CHECK(h[0]->node_count == h[1]->node_count);
        int32_t n = h[0]->node_count;
        double worst = 1;
        for (int32_t i = 0; i < n && i < h[1]->node_count; i++) {
            double e0 = h[0]->nodes[i].error, e1 = h[1]->nodes[i].error / 1000;
            CHECK(h[0]->nodes[i].item == h[1]->nodes[i].item); /* the same tree */
            if (isfinite(e0)) worst = fmax(worst, fmax(e0 / e1, e1 / e0));
        }
        CHECK_MSG(worst < 2.5, "errors in m and mm differ by a factor %.3g", worst);
        /* The metre tree expressed in millimetres */
        mr_hlod mm = *h[0];
        mm.nodes = malloc((size_t)n * sizeof *mm.nodes);
        memcpy(mm.nodes, h[0]->nodes, (size_t)n * sizeof *mm.nodes);
        for (int32_t i = 0; i < n; i++) {
            for (int k = 0; k < 3; k++) {
                mm.nodes[i].lo[k] *= 1000;
                mm.nodes[i].hi[k] *= 1000;
                mm.nodes[i].center[k] *= 1000;
            }
            mm.nodes[i].error *= 1000;
        }
        int32_t *buf = malloc(4 * (size_t)n * sizeof *buf);
        int used_proxies = 0, used_nodes = 0;
        for (int which = 0; which < MR_SYNTH_VIEW_COUNT; which++)
            for (int px = 1; px <= 16; px *= 4) {
                int32_t np[2], nn[2];
                cut_view(h[0], which, 1, px, buf, n, &np[0], &nn[0]);
                cut_view(&mm, which, 1000, px, buf + 2 * n, n, &np[1], &nn[1]);
                CHECK_MSG(np[0] == np[1] && nn[0] == nn[1], "view %d, %d px: %d/%d proxies, %d/%d nodes", which, px,
                          (int)np[0], (int)np[1], (int)nn[0], (int)nn[1]);
                if (np[0] == np[1]) CHECK(memcmp(buf, buf + 2 * n, (size_t)np[0] * sizeof *buf) == 0);
                if (nn[0] == nn[1]) CHECK(memcmp(buf + n, buf + 3 * n, (size_t)nn[0] * sizeof *buf) == 0);
                used_proxies += np[0];
                used_nodes += nn[0];
            }
        CHECK(used_proxies > 0 && used_nodes > 0); /* the views cut both above and at the parts */
        free(buf);
        free(mm.nodes);
    }
    for (int k = 0; k < 2; k++) {
        mr_hlod_destroy(&h[k]);
        mr_lod_destroy(&lod[k]);
        mr_scene_destroy(&s[k]);
    }
}

static void test_wanted(void) {
    CHECK(!mr_hlod_wanted(NULL, MR_HLOD_AUTO_TRIANGLES - 1, 1000));
    CHECK(mr_hlod_wanted(NULL, MR_HLOD_AUTO_TRIANGLES, MR_HLOD_AUTO_NODES));
    CHECK(!mr_hlod_wanted("auto", MR_HLOD_AUTO_TRIANGLES, MR_HLOD_AUTO_NODES - 1));
    CHECK(mr_hlod_wanted("on", 10, 2));
    CHECK(!mr_hlod_wanted("on", 10, 1));
    CHECK(!mr_hlod_wanted("off", 1u << 30, 100000));
}

static bool same(const mr_hlod *a, const mr_hlod *b) {
    if (a->node_count != b->node_count) return false;
    for (int32_t i = 0; i < a->node_count; i++) {
        const mr_hlod_node *x = &a->nodes[i], *y = &b->nodes[i];
        if (x->index_count != y->index_count || x->vertex_count != y->vertex_count || x->run_count != y->run_count ||
            x->item != y->item || !(x->error == y->error || (isinf(x->error) && isinf(y->error))))
            return false;
        if (x->index_count && memcmp(x->indices, y->indices, x->index_count * 4u)) return false;
        if (x->vertex_count && memcmp(x->positions, y->positions, x->vertex_count * 12u)) return false;
    }
    return true;
}

static bool write_bytes(const char *path, const unsigned char *d, size_t n) {
    FILE *f = fopen(path, "wb");
    if (!f) return false;
    bool ok = fwrite(d, 1, n, f) == n;
    return fclose(f) == 0 && ok;
}

typedef struct progress_log {
    int calls, stop_at;
    double last;
    bool monotone;
} progress_log;

static bool log_progress(void *user, double fraction) {
    progress_log *p = user;
    if (fraction < p->last || fraction > 1) p->monotone = false;
    p->last = fraction;
    return ++p->calls != p->stop_at;
}

/* A build stopped by its progress callback (as SIGINT stops the
 * commands') ends with MR_ERR_INTERRUPTED and writes no cache; a whole
 * build reports rising fractions up to 1. */
static void test_interrupt(void) {
    mr_scene *s = cad(1, 0, 8, 600);
    CHECK(s != NULL);
    if (!s) return;
    mr_error err = {0};
    mr_lod_params lp = MR_LOD_DEFAULTS;
    mr_lod *lod = mr_lod_build(s, &lp, &err);
    char path[4096];
    snprintf(path, sizeof path, "%s/test_hlod_stop.mrhlod", tmp_dir());
    remove(path);
    progress_log pl = {0, 3, 0, true};
    mr_hlod_params hp = MR_HLOD_DEFAULTS;
    hp.on_progress = log_progress;
    hp.progress_user = &pl;
    hp.threads = 1;
    mr_hlod_info info;
    mr_hlod *h = mr_hlod_load_or_build(s, lod, path, &hp, &info, &err);
    CHECK_MSG(!h && err.code == MR_ERR_INTERRUPTED, "stopped build: %p, error %d", (void *)h, (int)err.code);
    CHECK(pl.calls == 3);
    FILE *f = fopen(path, "rb");
    CHECK(f == NULL); /* nothing half-written */
    if (f) fclose(f);
    mr_hlod_destroy(&h);
    pl = (progress_log){0, -1, 0, true};
    err = (mr_error){0};
    h = mr_hlod_load_or_build(s, lod, path, &hp, &info, &err);
    CHECK_MSG(h && info.cache_written, "%s", err.msg);
    CHECK(pl.monotone && pl.calls > 3 && pl.last == 1.0);
    mr_hlod_destroy(&h);
    remove(path);
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
}

static void test_cache(void) {
    mr_scene *s = cad(1, 0, 8, 600);
    CHECK(s != NULL);
    if (!s) return;
    mr_error err = {0};
    mr_lod_params lp = MR_LOD_DEFAULTS;
    mr_lod *lod = mr_lod_build(s, &lp, &err);
    char path[4096];
    snprintf(path, sizeof path, "%s/test_hlod.mrhlod", tmp_dir());
    remove(path);
    mr_hlod_params hp = MR_HLOD_DEFAULTS;
    mr_hlod_info info;
    mr_hlod *ref = mr_hlod_load_or_build(s, lod, path, &hp, &info, &err);
    CHECK(ref && !info.from_cache && info.cache_written);
    mr_hlod *again = mr_hlod_load_or_build(s, lod, path, &hp, &info, &err);
    CHECK(again && info.from_cache && same(ref, again));
    mr_hlod_destroy(&again);
    size_t size = 0;
    unsigned char *good = mr_file_read(path, &size, 0, &err);
    CHECK(good && size > 100);
    if (good && ref) {
        /* truncated, a byte flipped, an index out of range behind a valid
         * checksum: each detected, rebuilt (the same as built), rewritten */
        for (int k = 0; k < 3; k++) {
            unsigned char *bad = malloc(size);
            memcpy(bad, good, size);
            size_t n = size;
            if (k == 0) n = size / 2;
            if (k == 1) bad[size / 2] ^= 0x40;
            if (k == 2) {
                /* the last node with indices: its first index made huge */
                const mr_hlod_node *last = NULL;
                for (int32_t i = ref->node_count; i-- > 0 && !last;)
                    if (ref->nodes[i].index_count) last = &ref->nodes[i];
                size_t off = size - 8 - last->run_count * sizeof(mr_hlod_run) - (size_t)last->index_count * 4;
                /* (nodes after it carry nothing: they are leaves) */
                uint32_t huge = 0x7fffffff;
                memcpy(bad + off, &huge, 4);
                uint64_t sum = mr_hash64(0x9e3779b97f4a7c15ull, bad, size - 8);
                memcpy(bad + size - 8, &sum, 8);
            }
            CHECK(write_bytes(path, bad, n));
            free(bad);
            mr_hlod *h = mr_hlod_load_or_build(s, lod, path, &hp, &info, &err);
            CHECK_MSG(h && !info.from_cache && info.cache_written, "damage %d not detected", k);
            if (h) CHECK(same(ref, h));
            mr_hlod_destroy(&h);
            h = mr_hlod_load_or_build(s, lod, path, &hp, &info, &err);
            CHECK(h && info.from_cache);
            mr_hlod_destroy(&h);
        }
        /* another scene's file is not used */
        mr_scene *other = cad(1, 0, 8, 700);
        mr_lod *olod = mr_lod_build(other, &lp, &err);
        mr_hlod *h = mr_hlod_load_or_build(other, olod, path, &hp, &info, &err);
        CHECK(h && !info.from_cache);
        mr_hlod_destroy(&h);
        mr_lod_destroy(&olod);
        mr_scene_destroy(&other);
    }
    free(good);
    remove(path);
    mr_hlod_destroy(&ref);
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
}

int main(void) {
    test_wanted();
    test_bound(1, 0);
    test_bound(1e-3, 0);
    test_bound(1e3, 0);
    test_bound(1, 1e7);
    test_units();
    test_cache();
    test_interrupt();
    return mr_test_finish("test_hlod");
}
