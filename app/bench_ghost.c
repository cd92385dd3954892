/* mrcheck bench ghost: option parsing; the bench is mr_bench_ghost (lib/bench/ghost.c). */
#include "app.h"
#include "mr_bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int app_bench_ghost(int argc, char **argv) {
    static const char *cmd = "bench ghost";
    mr_cli_opt opts[] = {
        {"size", "WxH", "output size (default 640x480, the demo camera)", NULL},
        {"frames", "N", "frames to time per configuration after 2 warm-up frames (default 5)", NULL},
        {"view", "I", "demo viewpoint (default 0: the partition with the pipes behind it)", NULL},
        {"out", "DIR", "write bench_ghost.csv and bench_ghost.svg there (default bench-out)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 3, opts, NULL, 0, NULL,
                   "usage: mrcheck bench ghost [--size WxH] [--frames N] [--view I] [--out DIR]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    int w = 640, h = 480;
    long frames = 5, view_index = 0;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &w, &h)) return 2;
    if (mr_cli_get(opts, "frames") && !mr_cli_int("frames", mr_cli_get(opts, "frames"), 1, 100000, &frames)) return 2;
    if (mr_cli_get(opts, "view") && !mr_cli_int("view", mr_cli_get(opts, "view"), 0, mr_demo_view_count() - 1, &view_index))
        return 2;
    const char *out_dir = mr_cli_get(opts, "out") ? mr_cli_get(opts, "out") : "bench-out";
    mr_bench_ghost_params p = {MR_BENCH_GHOST_DEFAULTS};
    p.out_dir = out_dir;
    p.width = w;
    p.height = h;
    p.frames = (int)frames;
    p.view = (int)view_index;
    p.progress = isatty(2) && !mr_cli_flag(opts, "quiet");
    p.out = stdout;
    mr_error err = {0};
    app_gfx g;
    bool ok = app_bench_gpu(&g, &p.gfx, &err) && mr_bench_ghost(&p, &err);
    app_gfx_close(&g);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
