/* mrcheck bench shadows: wiring of mr_bench_shadows (lib/bench/shadows.c). */
#include "app.h"
#include "mr_bench.h"

int app_bench_shadows(int argc, char **argv) {
    static const char *cmd = "bench shadows";
    mr_cli_opt opts[] = {
        {"size", "WxH", "output size (default 320x240)", NULL},
        {"frames", "N", "timed frames per row, median (default 3)", NULL},
        {"rays", "N", "Embree reference: light samples per pixel (default 256)", NULL},
        {"first", "I", "first suite case, 0..12 (default 0)", NULL},
        {"count", "N", "number of suite cases (default: all from --first)", NULL},
        {"views", "N", "views per case, 1 or 2 (default 2)", NULL},
        {"out", "DIR", "write bench_shadows.{csv,svg,md} and the montages there (default bench-out)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 3, opts, NULL, 0, NULL,
                   "usage: mrcheck bench shadows [--size WxH] [--frames N] [--rays N] [--first I --count N] [--views N] "
                   "[--out DIR]",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    mr_bench_shadows_params p = {MR_BENCH_SHADOWS_DEFAULTS};
    long frames = p.frames, rays = p.rays, first = 0, count = 0, views = 2;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) return 2;
    if (mr_cli_get(opts, "frames") && !mr_cli_int("frames", mr_cli_get(opts, "frames"), 1, 64, &frames)) return 2;
    if (mr_cli_get(opts, "rays") && !mr_cli_int("rays", mr_cli_get(opts, "rays"), 1, 1 << 16, &rays)) return 2;
    if (mr_cli_get(opts, "first") && !mr_cli_int("first", mr_cli_get(opts, "first"), 0, MR_SHADOW_SUITE_COUNT - 1, &first)) return 2;
    if (mr_cli_get(opts, "count") && !mr_cli_int("count", mr_cli_get(opts, "count"), 1, MR_SHADOW_SUITE_COUNT - first, &count))
        return 2;
    if (mr_cli_get(opts, "views") && !mr_cli_int("views", mr_cli_get(opts, "views"), 1, 2, &views)) return 2;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.frames = (int)frames;
    p.rays = (int)rays;
    p.first = (int)first;
    p.count = (int)count;
    p.views = (int)views;
    p.out = stdout;
    mr_error err = {0};
    app_gfx g;
    bool ok = app_bench_gpu(&g, &p.gfx, &err) && mr_bench_shadows(&p, &err);
    app_gfx_close(&g);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
