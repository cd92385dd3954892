/* test_rules.c — the renderer's decision rules as pure functions, on
 * injected inputs on both sides of each threshold (no GL): a rule that
 * only the fixtures' one scene reaches is otherwise never seen to switch. */
#include "cluster_cache.h"
#include "mr_render.h"
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

int main(void) {
    test_cascade_count();
    test_cluster_key();
    return mr_test_finish("test_rules");
}
