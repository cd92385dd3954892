/* mrcheck bench tracking: option parsing; the bench is mr_bench_tracking
 * (lib/bench/tracking.c). */
#include "app_track.h"
#include "mr_bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int bench_tracking(int argc, char **argv) {
    static const char *cmd = "bench tracking";
    mr_cli_opt opts[] = {
        {"recording", "DIR", "recording with groundtruth.jsonl (default recordings/demo)", NULL},
        {"out", "DIR", "write bench_tracking.csv and .svg there (default bench-out)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_tracking_params p = {MR_BENCH_TRACKING_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_tracking_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck bench tracking [--recording DIR] [--out DIR]\n"
                   "Per detector setting (decimation 1 1.5 2 3 4 x threads 1 2 x edge refinement) and OpenCV aruco\n"
                   "(DICT_APRILTAG_36h11, 4 corner refinements): ms per frame against pose error, detection rate,\n"
                   "flip rate and jitter during the recording's pauses.",
                   &help))
        return 2;
    if (help) return 0;
    if (mr_cli_get(opts, "recording")) p.recording = mr_cli_get(opts, "recording");
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.out = stdout;
    mr_error err = {0};
    return mr_bench_tracking(&p, &err) ? 0 : mr_cli_error(cmd, &err);
}
