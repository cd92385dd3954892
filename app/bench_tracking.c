/* mrcheck bench tracking: option parsing; the bench is mr_bench_tracking
 * (lib/bench/tracking.c). */
#include "app_track.h"
#include "mr_bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int bench_tracking(int argc, char **argv) {
    static const char *cmd = "bench tracking";
    app_opt opts[] = {
        {"recording", "DIR", "recording with groundtruth.jsonl (default recordings/demo)", NULL},
        {"out", "DIR", "write bench_tracking.csv and .svg there (default bench-out)", NULL},
        {"frames", "N", "use at most N frames (default all)", NULL},
        {"quick", NULL, "a few settings only", NULL},
        {"min-cutoff", "HZ", "One Euro filter cutoff at rest (default 0.5)", NULL},
        {"beta", "B", "One Euro filter speed coefficient (default 2)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!app_parse(argc, argv, 3, opts, NULL, 0, NULL,
                   "usage: mrcheck bench tracking [--recording DIR] [--out DIR]\n"
                   "Per detector setting (decimation 1 1.5 2 3 4 x threads 1 2 x edge refinement) and OpenCV aruco\n"
                   "(DICT_APRILTAG_36h11, 4 corner refinements): ms per frame against pose error, detection rate,\n"
                   "flip rate and jitter during the recording's pauses.",
                   &help))
        return 2;
    if (help) return 0;
    mr_bench_tracking_params p = {MR_BENCH_TRACKING_DEFAULTS};
    if (app_get(opts, "recording")) p.recording = app_get(opts, "recording");
    if (app_get(opts, "out")) p.out_dir = app_get(opts, "out");
    long max_frames = 0;
    if (app_get(opts, "frames") && !app_int("frames", app_get(opts, "frames"), 1, 1L << 30, &max_frames)) return 2;
    if (app_get(opts, "min-cutoff") && !app_double("min-cutoff", app_get(opts, "min-cutoff"), 1e-3, 100, &p.min_cutoff)) return 2;
    if (app_get(opts, "beta") && !app_double("beta", app_get(opts, "beta"), 1e-6, 1000, &p.beta)) return 2;
    p.max_frames = max_frames;
    p.quick = app_flag(opts, "quick");
    p.out = stdout;
    mr_error err = {0};
    return mr_bench_tracking(&p, &err) ? 0 : app_error(cmd, &err);
}
