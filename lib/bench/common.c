/* What the bench runners share. */
#include "bench_internal.h"

bool bench_gpu_check(const mr_bench_gpu *g, const char *bench, mr_error *err) {
    return g->gpu && g->renderer ? true : mr_fail(err, MR_ERR_INVALID, "%s: no GPU and renderer given", bench);
}
