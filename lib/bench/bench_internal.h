/* Private to lib/bench: what the runners share. */
#ifndef MR_BENCH_INTERNAL_H
#define MR_BENCH_INTERNAL_H

#include "mr_bench.h"
#include "mr_session.h"

/* The runners' tables go to params.out, or nowhere when it is NULL. */
#define BENCH_PRINT(out, ...) \
    do {                       \
        if (out) fprintf(out, __VA_ARGS__); \
    } while (0)

/* false with MR_ERR_INVALID when a bench was given no renderer. */
bool bench_gpu_check(const mr_bench_gpu *g, const char *bench, mr_error *err);

/* `mrcheck demo`'s Measure (demo_measure.c): a vertical edge of part
 * `node` of the hall as built, tapped in up to six frames of the recording
 * that see it (ground truth, half a pixel of tap noise seeded by seed),
 * triangulated with the tracked poses and their covariances; its distance
 * to the same edge on the plan (the edge minus delta, the part's known
 * displacement) judged against DIN 18202 Table 1. */
typedef struct mr_demo_measured {
    mr_measurement m;          /* taps, point, distance to the plan */
    mr_verdict verdict;
    double truth_m;            /* |delta| */
} mr_demo_measured;
bool mr_demo_measure(const mr_recording *rec, const mr_bench_gpu *g, const mr_scene *built, const char *node,
                     mr_dvec3 delta, uint64_t seed, mr_demo_measured *out, mr_error *err);
/* The control measurement's part: the unchanged column (same bounds as
 * planned and as built) seen closest in the most frames; NULL if none. */
const char *mr_demo_control_part(const mr_recording *rec, const mr_scene *built, const mr_scene *planned);

#endif
