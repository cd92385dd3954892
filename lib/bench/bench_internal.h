/* Private to lib/bench: what the runners share. */
#ifndef MR_BENCH_INTERNAL_H
#define MR_BENCH_INTERNAL_H

#include "mr_bench.h"

/* The runners' tables go to params.out, or nowhere when it is NULL. */
#define BENCH_PRINT(out, ...) \
    do {                       \
        if (out) fprintf(out, __VA_ARGS__); \
    } while (0)

/* A headless GPU and a renderer on it. */
typedef struct bench_gfx {
    mr_gpu *gpu;
    mr_renderer *renderer;
} bench_gfx;
bool bench_gfx_open(bench_gfx *g, mr_error *err);
void bench_gfx_close(bench_gfx *g);

#endif
