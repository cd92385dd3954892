/* Automatic occlusion culling's decision (geometry.c), as a state machine
 * of plain numbers so that it can be tested on injected timings (no GL;
 * tests/test_rules.c). Internal to lib/render.
 *
 * The test pays when the triangles it skips cost more to draw than the
 * test costs. Both are measured on the frames that run it: the read-back
 * waits for the occluders to be drawn, so its time minus that of a
 * read-back alone (measured once per size, after a glFinish) is what
 * drawing the occluders cost, hence a cost per triangle; the gain is the
 * skipped triangles (at the frame's LOD ratio) times that, minus the
 * read-back alone and the CPU test. Smoothed over frames, with hysteresis:
 * the test stays on while the gain is positive and goes off when it turns
 * negative by more than 10 % of the read-back; while off, one frame in
 * OCC_PROBE_FRAMES tries it again (the view may have moved into a hall),
 * and a trial's gain starts afresh. */
#ifndef MR_OCC_RULE_H
#define MR_OCC_RULE_H

#include <stdbool.h>
#include <stdint.h>

#define OCC_PROBE_FRAMES 32

typedef struct occ_auto {
    bool on;        /* test every frame */
    int probe;      /* while off: frames until the next trial; -1 while on */
    double gain_ms; /* smoothed measured gain (saved - cost), ms */
} occ_auto;

/* On, and the next frame measures afresh (a new upload, a reset). */
void occ_auto_reset(occ_auto *s);
/* Whether this frame runs the test: on, or a trial frame while off
 * (counts the frames down). */
bool occ_auto_frame(occ_auto *s);
/* One frame's gain, ms: skipped_tris times the occluders' cost per
 * triangle ((sync_ms - rb_ms) / occluder_tris), minus the read-back alone
 * (rb_ms; < 0: not measured, taken as 0) and the CPU test (cpu_ms). */
double occ_auto_gain_ms(double rb_ms, double sync_ms, double cpu_ms, uint64_t occluder_tris, uint64_t skipped_tris);
/* Learns from a frame that ran the test: on or off for the next ones. */
void occ_auto_learn(occ_auto *s, double rb_ms, double sync_ms, double cpu_ms, uint64_t occluder_tris,
                    uint64_t skipped_tris);

#endif
