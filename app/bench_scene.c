/* mrcheck bench scene: option parsing; the bench is mr_bench_scene
 * (lib/bench/scene.c). */
#include "app.h"
#include "mr_bench.h"

#include <stdlib.h>

/* "1M,5M,20M" -> triangle targets. */
static int parse_sizes(const char *spec, double *out, int max) {
    int n = 0;
    const char *p = spec;
    while (*p && n < max) {
        char *end;
        double v = strtod(p, &end);
        if (end == p) return -1;
        if (*end == 'M' || *end == 'm') { v *= 1e6; end++; }
        else if (*end == 'k' || *end == 'K') { v *= 1e3; end++; }
        if (!(v >= 1e4 && v <= 1e9)) return -1;
        out[n++] = v;
        if (*end == ',') end++;
        else if (*end) return -1;
        p = end;
    }
    return n;
}

int bench_scene(int argc, char **argv) {
    static const char *cmd = "bench scene";
    mr_cli_opt opts[] = {
        {"out", "DIR", "write bench_scene.csv, bench_scene.svg and the scenes there (default bench-out)", NULL},
        {"sizes", "LIST", "drawn-triangle targets (default 1M,5M,20M)", NULL},
        {"size", "WxH", "frame size (default 1024x768)", NULL},
        {"frames", "N", "timed frames per case after one warm-up (default 3)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 3, opts, NULL, 0, NULL,
                   "usage: mrcheck bench scene [--out DIR] [--sizes 1M,5M,20M] [--size WxH] [--frames N]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *out_dir = mr_cli_get(opts, "out") ? mr_cli_get(opts, "out") : "bench-out";
    mr_bench_scene_params p = {MR_BENCH_SCENE_DEFAULTS};
    int nsizes = parse_sizes(mr_cli_get(opts, "sizes") ? mr_cli_get(opts, "sizes") : "1M,5M,20M", p.sizes, MR_BENCH_SCENE_MAX_SIZES);
    if (nsizes <= 0) return mr_cli_errorf(cmd, "--sizes must be a list like 1M,5M,20M (10k..1000M each)"), 2;
    int w = 1024, h = 768;
    long frames = 3;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &w, &h)) return 2;
    if (mr_cli_get(opts, "frames") && !mr_cli_int("frames", mr_cli_get(opts, "frames"), 1, 1000, &frames)) return 2;
    p.out_dir = out_dir;
    p.size_count = nsizes;
    p.width = w;
    p.height = h;
    p.frames = (int)frames;
    p.out = stdout;
    mr_error err = {0};
    app_gfx g;
    bool ok = app_bench_gpu(&g, &p.gfx, &err) && mr_bench_scene(&p, &err);
    app_gfx_close(&g);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
