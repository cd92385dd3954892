/* Private to lib/bench: what the runners share. */
#ifndef MR_BENCH_INTERNAL_H
#define MR_BENCH_INTERNAL_H

#include "mr_bench.h"

/* The runners' tables go to params.out, or nowhere when it is NULL. */
#define BENCH_PRINT(out, ...) \
    do {                       \
        if (out) fprintf(out, __VA_ARGS__); \
    } while (0)

/* false with MR_ERR_INVALID when a bench was given no renderer. */
bool bench_gpu_check(const mr_bench_gpu *g, const char *bench, mr_error *err);

#endif
