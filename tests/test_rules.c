/* test_rules.c — the renderer's decision rules as pure functions, on
 * injected inputs on both sides of each threshold (no GL): a rule that
 * only the fixtures' one scene reaches is otherwise never seen to switch. */
#include "cluster_cache.h"
#include "mr_render.h"
#include "mr_scene.h"
#include "occ_rule.h"
#include "mr_test.h"

/* Sun cascades: one more per factor 16 of far over near visible depth, at
 * most 4; what is asked for wins; a 2 x 2 atlas that does not fit in a
 * texture, or no visible depth range, gives one map. */
static void test_cascade_count(void) {
    const int S = 1024, T = 16384;
    static const struct { double ratio; int want; } autos[] = {
        {1.01, 1}, {15.9, 1}, {16.1, 2}, {255, 2}, {257, 3}, {4095, 3}, {4097, 4}, {1e5, 4}, {1e12, 4}};
    for (size_t i = 0; i < sizeof autos / sizeof autos[0]; i++) {
        int n = mr_shadow_cascade_count(0, S, T, 0.5, 0.5 * autos[i].ratio);
        CHECK_MSG(n == autos[i].want, "far/near %g: %d cascades, want %d", autos[i].ratio, n, autos[i].want);
        /* the same at any scale: only the ratio counts */
        CHECK(mr_shadow_cascade_count(0, S, T, 2e6, 2e6 * autos[i].ratio) == autos[i].want);
    }
    for (int asked = 1; asked <= 6; asked++)
        CHECK_MSG(mr_shadow_cascade_count(asked, S, T, 1, 2) == (asked > 4 ? 4 : asked), "asked %d", asked);
    CHECK(mr_shadow_cascade_count(-1, S, T, 1, 100) == 2); /* negative: auto */
    /* the atlas: 2 S must fit */
    CHECK(mr_shadow_cascade_count(3, 8192, 16384, 1, 1e4) == 3);
    CHECK(mr_shadow_cascade_count(3, 8193, 16384, 1, 1e4) == 1);
    CHECK(mr_shadow_cascade_count(0, 8192, 16384, 1, 1e4) == 4);
    CHECK(mr_shadow_cascade_count(0, 8193, 16384, 1, 1e4) == 1);
    /* no visible depth range */
    CHECK(mr_shadow_cascade_count(0, S, T, 0, 100) == 1);
    CHECK(mr_shadow_cascade_count(0, S, T, 5, 5) == 1);
    CHECK(mr_shadow_cascade_count(0, S, T, NAN, 100) == 1);
    CHECK(mr_shadow_cascade_count(0, S, T, 1, INFINITY) == 1);
}

/* The meshlet cache's key of a level changes with each input alone: one
 * position's last bit, one index (an index-only edit of a cached mesh,
 * last of all or first), the index count, the vertex count and the
 * cluster threshold; copies of the same input give the same key. */
static void test_cluster_key(void) {
    enum { nv = 40, ni = 120 };
    float pos[nv * 3], pos2[nv * 3];
    uint32_t idx[ni], idx2[ni];
    for (int i = 0; i < nv * 3; i++) pos[i] = (float)(i * 0.37 - 3);
    for (int i = 0; i < ni; i++) idx[i] = (uint32_t)((i * 7) % nv);
    memcpy(pos2, pos, sizeof pos);
    memcpy(idx2, idx, sizeof idx);
    const uint64_t k = clu_level_key(pos, nv, idx, ni, 4096);
    CHECK(clu_level_key(pos2, nv, idx2, ni, 4096) == k);
    uint32_t bits;
    memcpy(&bits, &pos2[nv * 3 - 1], 4);
    bits ^= 1;
    memcpy(&pos2[nv * 3 - 1], &bits, 4);
    CHECK_MSG(clu_level_key(pos2, nv, idx, ni, 4096) != k, "the last position's last bit is not in the key");
    for (int at = 0; at < ni; at += ni - 1) {
        memcpy(idx2, idx, sizeof idx);
        idx2[at] = (idx2[at] + 1) % nv;
        CHECK_MSG(clu_level_key(pos, nv, idx2, ni, 4096) != k, "index %d is not in the key", at);
    }
    /* two indices swapped: same multiset, other triangles */
    memcpy(idx2, idx, sizeof idx);
    uint32_t t = idx2[ni - 1];
    idx2[ni - 1] = idx2[ni - 2], idx2[ni - 2] = t;
    CHECK(clu_level_key(pos, nv, idx2, ni, 4096) != k);
    CHECK(clu_level_key(pos, nv, idx, ni - 3, 4096) != k);
    CHECK(clu_level_key(pos, nv - 1, idx, ni, 4096) != k);
    CHECK(clu_level_key(pos, nv, idx, ni, 4097) != k);
}

/* Automatic occlusion culling on injected timings: a read-back of 1 ms
 * alone, 2 ms while 1000 occluder triangles are drawn (1 us each). */
static void test_occlusion_rule(void) {
    /* the gain: skipped x cost per triangle - read-back - CPU test */
    CHECK(fabs(occ_auto_gain_ms(1, 2, 0.25, 1000, 3000) - (3 - 1 - 0.25)) < 1e-12);
    CHECK(fabs(occ_auto_gain_ms(-1, 2, 0, 1000, 3000) - 6) < 1e-12); /* no read-back measured: 0 */
    CHECK(occ_auto_gain_ms(1, 0.5, 0, 1000, 3000) == -1);            /* sync under the read-back: no cost per tri */
    CHECK(occ_auto_gain_ms(1, 2, 0, 0, 3000) == -1);                 /* no occluders */
    /* A new upload tests the first frame and keeps testing while it pays. */
    occ_auto s;
    occ_auto_reset(&s);
    CHECK(occ_auto_frame(&s) && occ_auto_frame(&s));
    occ_auto_learn(&s, 1, 2, 0, 1000, 5000);
    CHECK(s.on && s.probe == -1 && fabs(s.gain_ms - 4) < 1e-12);
    /* Both sides of the hysteresis: on while the gain is above -10 % of
     * the read-back, off below (from a fresh measurement each). */
    occ_auto_reset(&s);
    occ_auto_learn(&s, 1, 2, 0, 1000, 910); /* gain -0.09 */
    CHECK_MSG(s.on, "a gain of -0.09 ms against a 1 ms read-back turned the test off");
    occ_auto_reset(&s);
    occ_auto_learn(&s, 1, 2, 0, 1000, 890); /* gain -0.11 */
    CHECK_MSG(!s.on && s.probe == OCC_PROBE_FRAMES, "a gain of -0.11 ms kept the test on");
    /* While on, the gain is smoothed: one bad frame after a good one
     * (4 then -1) averages to 1.5 and stays on; two more turn it off. */
    occ_auto_reset(&s);
    occ_auto_learn(&s, 1, 2, 0, 1000, 5000);
    occ_auto_learn(&s, 1, 2, 0, 1000, 0);
    CHECK(s.on && fabs(s.gain_ms - 1.5) < 1e-12);
    occ_auto_learn(&s, 1, 2, 0, 1000, 0);
    CHECK(s.on && fabs(s.gain_ms - 0.25) < 1e-12);
    occ_auto_learn(&s, 1, 2, 0, 1000, 0);
    CHECK(!s.on);
    /* Off: no test for OCC_PROBE_FRAMES - 1 frames, then one trial. */
    int quiet = 0;
    while (!occ_auto_frame(&s) && quiet < 1000) quiet++;
    CHECK_MSG(quiet == OCC_PROBE_FRAMES - 1, "%d frames without a trial", quiet);
    /* A trial starts afresh: a paying trial turns it on at once, however
     * bad the frames before it were. */
    s.gain_ms = -100;
    occ_auto_learn(&s, 1, 2, 0, 1000, 3000);
    CHECK(s.on && fabs(s.gain_ms - 2) < 1e-12);
    /* A failing trial turns it off for another round. */
    occ_auto_learn(&s, 1, 2, 0, 1000, 0);
    occ_auto_learn(&s, 1, 2, 0, 1000, 0);
    occ_auto_learn(&s, 1, 2, 0, 1000, 0);
    CHECK(!s.on);
    quiet = 0;
    while (!occ_auto_frame(&s) && quiet < 1000) quiet++;
    occ_auto_learn(&s, 1, 2, 0, 1000, 500); /* gain -0.5 */
    CHECK(!s.on && s.probe == OCC_PROBE_FRAMES);
}

/* Levels of detail at all (--lod auto|on|off): auto gives them to scenes
 * drawing MR_LOD_AUTO_TRIANGLES or more, counted per drawn node (a mesh
 * drawn twice counts twice), on and off whatever the scene. */
static void test_lod_rule(void) {
    mr_mesh meshes[2];
    mr_node nodes[3];
    memset(meshes, 0, sizeof meshes);
    memset(nodes, 0, sizeof nodes);
    mr_scene s;
    memset(&s, 0, sizeof s);
    s.meshes = meshes;
    s.nodes = nodes;
    s.mesh_count = 2;
    const uint32_t T = MR_LOD_AUTO_TRIANGLES;
    meshes[0].index_count = 3 * (T / 2);
    meshes[1].index_count = 3;
    nodes[0] = (mr_node){.mesh_first = 0, .mesh_count = 1, .parent = -1};
    nodes[1] = (mr_node){.mesh_first = 0, .mesh_count = 1, .parent = -1};
    nodes[2] = (mr_node){.mesh_first = 1, .mesh_count = 1, .parent = -1};
    s.node_count = 2; /* T / 2 stored, T drawn */
    CHECK(mr_scene_triangle_count(&s) == T);
    CHECK_MSG(mr_lod_wanted(MR_LOD_MODE_AUTO, &s), "a scene drawing %u triangles got no levels", T);
    meshes[0].index_count -= 3; /* T - 2 drawn */
    CHECK(!mr_lod_wanted(MR_LOD_MODE_AUTO, &s));
    s.node_count = 3; /* + 1 */
    CHECK(!mr_lod_wanted(MR_LOD_MODE_AUTO, &s));
    meshes[1].index_count = 6; /* + 2: T */
    CHECK(mr_lod_wanted(MR_LOD_MODE_AUTO, &s));
    CHECK(!mr_lod_wanted(MR_LOD_MODE_OFF, &s));
    s.node_count = 0;
    CHECK(!mr_lod_wanted(MR_LOD_MODE_AUTO, &s));
    CHECK(mr_lod_wanted(MR_LOD_MODE_ON, &s));
    mr_lod_mode m;
    mr_error err = {0};
    CHECK(mr_lod_mode_parse(NULL, &m, &err) && m == MR_LOD_MODE_AUTO);
    CHECK(mr_lod_mode_parse("on", &m, &err) && m == MR_LOD_MODE_ON);
    CHECK(mr_lod_mode_parse("off", &m, &err) && m == MR_LOD_MODE_OFF);
    CHECK(!mr_lod_mode_parse("yes", &m, &err));
}

/* The hierarchy above the parts: auto needs both MR_HLOD_AUTO_TRIANGLES
 * drawn and MR_HLOD_AUTO_NODES nodes; on needs two nodes; off never. */
static void test_hlod_rule(void) {
    const uint64_t T = MR_HLOD_AUTO_TRIANGLES;
    const int32_t N = MR_HLOD_AUTO_NODES;
    CHECK(mr_hlod_wanted("auto", T, N));
    CHECK(mr_hlod_wanted(NULL, T, N));
    CHECK_MSG(!mr_hlod_wanted("auto", T - 1, N), "one triangle under the threshold");
    CHECK_MSG(!mr_hlod_wanted("auto", T, N - 1), "one node under the threshold");
    CHECK(!mr_hlod_wanted(NULL, 100 * T, N - 1));
    CHECK(!mr_hlod_wanted(NULL, T - 1, 100 * N));
    CHECK(mr_hlod_wanted("on", 6, 2));
    CHECK(!mr_hlod_wanted("on", 100 * T, 1));
    CHECK(!mr_hlod_wanted("off", 100 * T, 100 * N));
}

int main(void) {
    test_cascade_count();
    test_cluster_key();
    test_occlusion_rule();
    test_lod_rule();
    test_hlod_rule();
    return mr_test_finish("test_rules");
}
