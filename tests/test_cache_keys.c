/* test_cache_keys.c — the level-of-detail caches beside a scene file
 * (.mrlod, lib/scene/lod.c; .mrhlod, lib/scene/hlod.c) against each input
 * that can change alone: a cache written before the change must not be
 * used after it, and one written for the same input must be. (The
 * meshlet cache's key is in test_rules.) */
#include "mr_test.h"
#include "mr_test_scene.h"

static mr_scene *two_spheres(void) {
    mr_scene *s = mr_scene_create();
    mr_error err = {0};
    for (int k = 0; k < 2; k++) {
        mr_mesh m = mr_test_sphere_mesh(k ? "b" : "a", 0.3 + 0.05 * k, 24, 12, 0.15, 5, 3);
        CHECK_MSG(mr_scene_add_mesh(s, &m, &err) >= 0, "%s", err.msg);
    }
    return s;
}

static void flip_last_bit(float *f) {
    uint32_t b;
    memcpy(&b, f, 4);
    b ^= 1;
    memcpy(f, &b, 4);
}

static char g_dir[1024];

/* Builds the .mrlod for (s, lp) fresh, then loads it for (s2, lp2): was
 * it used? */
static bool lod_reused(mr_scene *s, const mr_lod_params *lp, mr_scene *s2, const mr_lod_params *lp2) {
    char path[1200];
    snprintf(path, sizeof path, "%s/scene.mrlod", g_dir);
    remove(path);
    mr_error err = {0};
    mr_lod_info info;
    mr_lod *a = mr_lod_load_or_build(s, path, lp, &info, &err);
    CHECK_MSG(a && !info.from_cache && info.cache_written, "%s", err.msg);
    mr_lod_destroy(&a);
    a = mr_lod_load_or_build(s2, path, lp2, &info, &err);
    CHECK_MSG(a != NULL, "%s", err.msg);
    mr_lod_destroy(&a);
    return info.from_cache;
}

static void test_lod_key(void) {
    mr_scene *s = two_spheres(), *same = two_spheres();
    mr_lod_params lp = MR_LOD_DEFAULTS;
    CHECK_MSG(lod_reused(s, &lp, same, &lp), "the same scene and params did not reuse the cache");
    mr_mesh *m = &s->meshes[1];
    /* one position's last bit */
    float *f = &m->positions[3 * (m->vertex_count - 1) + 2];
    flip_last_bit(f);
    CHECK_MSG(!lod_reused(same, &lp, s, &lp), "a position is not in the key");
    flip_last_bit(f);
    /* one normal's last bit: the levels pick, at a seam, the vertex whose
     * normal is nearest the face's */
    CHECK(m->normals != NULL);
    if (m->normals) {
        f = &m->normals[3 * (m->vertex_count / 2)];
        flip_last_bit(f);
        CHECK_MSG(!lod_reused(same, &lp, s, &lp), "a normal is not in the key");
        flip_last_bit(f);
    }
    /* one index, first and last */
    for (uint32_t at = 0; at < m->index_count; at += m->index_count - 1) {
        uint32_t old = m->indices[at];
        m->indices[at] = (old + 1) % m->vertex_count;
        CHECK_MSG(!lod_reused(same, &lp, s, &lp), "index %u is not in the key", at);
        m->indices[at] = old;
    }
    /* the index count (the last triangle dropped) */
    m->index_count -= 3;
    CHECK_MSG(!lod_reused(same, &lp, s, &lp), "the index count is not in the key");
    m->index_count += 3;
    /* the vertex count (one unused vertex less) */
    m->vertex_count -= 1;
    bool used_last = false;
    for (uint32_t i = 0; i < m->index_count; i++) used_last |= m->indices[i] >= m->vertex_count;
    if (!used_last) CHECK_MSG(!lod_reused(same, &lp, s, &lp), "the vertex count is not in the key");
    m->vertex_count += 1;
    /* the mesh count */
    s->mesh_count = 1;
    CHECK_MSG(!lod_reused(same, &lp, s, &lp), "the mesh count is not in the key");
    s->mesh_count = 2;
    CHECK(lod_reused(same, &lp, s, &lp)); /* all restored */
    /* each parameter that shapes the levels */
    mr_lod_params p2 = lp;
    p2.max_error = 0.004;
    CHECK_MSG(!lod_reused(s, &lp, s, &p2), "max_error is not in the key");
    p2 = lp;
    p2.min_triangles = 100;
    CHECK_MSG(!lod_reused(s, &lp, s, &p2), "min_triangles is not in the key");
    p2 = lp;
    p2.rel_error = 0.04;
    CHECK_MSG(!lod_reused(s, &lp, s, &p2), "rel_error is not in the key");
    /* what does not shape them */
    p2 = lp;
    p2.progress = true;
    CHECK(lod_reused(s, &lp, s, &p2));
    mr_scene_destroy(&s);
    mr_scene_destroy(&same);
}

/* Six nodes drawing the two meshes in a row, one on the hidden layer. */
static mr_scene *row_of_parts(void) {
    mr_scene *s = two_spheres();
    for (int i = 0; i < 6; i++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "part_%d", i);
        n.parent = -1;
        n.world = mr_m4_translate(0.8 * i, 0, 0);
        n.mesh_first = i % 2;
        n.mesh_count = 1;
        n.layer = i == 5 ? MR_LAYER_HIDDEN : MR_LAYER_VISIBLE;
        mr_scene_add_node(s, &n);
    }
    mr_scene_update_bounds(s);
    return s;
}

static bool hlod_reused(mr_scene *s, const mr_lod *lod, double red, mr_scene *s2, const mr_lod *lod2, double red2) {
    char path[1200];
    snprintf(path, sizeof path, "%s/scene.mrhlod", g_dir);
    remove(path);
    mr_error err = {0};
    mr_hlod_info info;
    mr_hlod_params hp = MR_HLOD_DEFAULTS;
    hp.threads = 1;
    hp.reduction = red;
    mr_hlod *h = mr_hlod_load_or_build(s, lod, path, &hp, &info, &err);
    CHECK_MSG(h && !info.from_cache && info.cache_written, "%s", err.msg);
    mr_hlod_destroy(&h);
    hp.reduction = red2;
    mr_scene_update_bounds(s2);
    h = mr_hlod_load_or_build(s2, lod2, path, &hp, &info, &err);
    CHECK_MSG(h != NULL, "%s", err.msg);
    mr_hlod_destroy(&h);
    return info.from_cache;
}

static void test_hlod_key(void) {
    mr_scene *s = row_of_parts(), *same = row_of_parts();
    CHECK_MSG(hlod_reused(s, NULL, 0.5, same, NULL, 0.5), "the same scene did not reuse the cache");
    /* the geometry: one position's last bit */
    float *f = &s->meshes[0].positions[5];
    flip_last_bit(f);
    CHECK_MSG(!hlod_reused(same, NULL, 0.5, s, NULL, 0.5), "a position is not in the key");
    flip_last_bit(f);
    /* a part moved (its node's world transform alone): the proxies are in world space */
    s->nodes[2].world.m[7] += 0.25;
    CHECK_MSG(!hlod_reused(same, NULL, 0.5, s, NULL, 0.5), "a node's transform is not in the key");
    s->nodes[2].world.m[7] -= 0.25;
    /* a part drawing the other mesh */
    s->nodes[2].mesh_first = 1;
    CHECK_MSG(!hlod_reused(same, NULL, 0.5, s, NULL, 0.5), "a node's mesh is not in the key");
    s->nodes[2].mesh_first = 0;
    /* a part on another layer (another hidden-layer rule) */
    s->nodes[1].layer = MR_LAYER_HIDDEN;
    CHECK_MSG(!hlod_reused(same, NULL, 0.5, s, NULL, 0.5), "a node's layer is not in the key");
    s->nodes[1].layer = MR_LAYER_VISIBLE;
    /* a mesh's origin (positions are relative to it) */
    s->meshes[1].origin[0] += 0.5;
    CHECK_MSG(!hlod_reused(same, NULL, 0.5, s, NULL, 0.5), "a mesh's origin is not in the key");
    s->meshes[1].origin[0] -= 0.5;
    CHECK(hlod_reused(same, NULL, 0.5, s, NULL, 0.5)); /* all restored */
    /* the reduction */
    CHECK_MSG(!hlod_reused(s, NULL, 0.5, s, NULL, 0.4), "the reduction is not in the key");
    /* the part levels it was built from */
    mr_error err = {0};
    mr_lod_params lp = MR_LOD_DEFAULTS;
    mr_lod *lod = mr_lod_build(s, &lp, &err);
    CHECK_MSG(lod != NULL, "%s", err.msg);
    if (lod) {
        CHECK_MSG(!hlod_reused(s, NULL, 0.5, s, lod, 0.5), "the part levels are not in the key");
        CHECK(hlod_reused(s, lod, 0.5, s, lod, 0.5));
    }
    mr_lod_destroy(&lod);
    mr_scene_destroy(&s);
    mr_scene_destroy(&same);
}

int main(void) {
    if (!mr_test_fresh_dir("test_cache_keys", g_dir, sizeof g_dir)) return 1;
    mr_log_set_level(MR_LOG_ERROR);
    test_lod_key();
    test_hlod_key();
    return mr_test_finish("test_cache_keys");
}
