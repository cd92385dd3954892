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
        {"frames", "N", "use at most N frames (default all)", NULL},
        {"quick", NULL, "a few settings only", NULL},
        {"min-cutoff", "HZ", "One Euro filter cutoff at rest (default 0.5)", NULL},
        {"beta", "B", "One Euro filter speed coefficient (default 2)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 3, opts, NULL, 0, NULL,
                   "usage: mrcheck bench tracking [--recording DIR] [--out DIR]\n"
                   "Per detector setting (decimation 1 1.5 2 3 4 x threads 1 2 x edge refinement) and OpenCV aruco\n"
                   "(DICT_APRILTAG_36h11, 4 corner refinements): ms per frame against pose error, detection rate,\n"
                   "flip rate and jitter during the recording's pauses.",
                   &help))
        return 2;
    if (help) return 0;
    mr_bench_tracking_params p = {MR_BENCH_TRACKING_DEFAULTS};
    if (mr_cli_get(opts, "recording")) p.recording = mr_cli_get(opts, "recording");
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    long max_frames = 0;
    if (mr_cli_get(opts, "frames") && !mr_cli_int("frames", mr_cli_get(opts, "frames"), 1, 1L << 30, &max_frames)) return 2;
    if (mr_cli_get(opts, "min-cutoff") && !mr_cli_double("min-cutoff", mr_cli_get(opts, "min-cutoff"), 1e-3, 100, &p.min_cutoff)) return 2;
    if (mr_cli_get(opts, "beta") && !mr_cli_double("beta", mr_cli_get(opts, "beta"), 1e-6, 1000, &p.beta)) return 2;
    p.max_frames = max_frames;
    p.quick = mr_cli_flag(opts, "quick");
    p.out = stdout;
    mr_error err = {0};
    return mr_bench_tracking(&p, &err) ? 0 : mr_cli_error(cmd, &err);
}
