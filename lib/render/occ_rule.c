/* Automatic occlusion culling's decision: see occ_rule.h. */
#include "occ_rule.h"

#include <math.h>

void occ_auto_reset(occ_auto *s) {
    s->on = true;
    s->probe = 0;
    s->gain_ms = 0;
}

bool occ_auto_frame(occ_auto *s) {
    if (s->on) return true;
    return --s->probe <= 0; /* a trial frame */
}

double occ_auto_gain_ms(double rb_ms, double sync_ms, double cpu_ms, uint64_t occluder_tris, uint64_t skipped_tris) {
    double rb = rb_ms > 0 ? rb_ms : 0;
    double per_tri = occluder_tris > 0 ? fmax(sync_ms - rb, 0) / (double)occluder_tris : 0;
    return (double)skipped_tris * per_tri - rb - cpu_ms;
}

void occ_auto_learn(occ_auto *s, double rb_ms, double sync_ms, double cpu_ms, uint64_t occluder_tris,
                    uint64_t skipped_tris) {
    double rb = rb_ms > 0 ? rb_ms : 0;
    double gain = occ_auto_gain_ms(rb_ms, sync_ms, cpu_ms, occluder_tris, skipped_tris);
    s->gain_ms = s->probe >= 0 ? gain : 0.5 * s->gain_ms + 0.5 * gain; /* a trial starts afresh */
    if (s->gain_ms < -0.1 * rb - 1e-3) {
        s->on = false;
        s->probe = OCC_PROBE_FRAMES;
    } else {
        s->on = true;
        s->probe = -1; /* on: every frame measures */
    }
}
