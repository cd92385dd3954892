/* test_rules.c — the renderer's decision rules as pure functions, on
 * injected inputs on both sides of each threshold (no GL): a rule that
 * only the fixtures' one scene reaches is otherwise never seen to switch. */
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

int main(void) {
    test_cascade_count();
    return mr_test_finish("test_rules");
}
