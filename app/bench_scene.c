/* mrcheck bench scene: option parsing; the bench is mr_bench_scene
 * (lib/bench/scene.c). */
#include "app.h"
#include "mr_bench.h"

int bench_scene(int argc, char **argv) {
    static const char *cmd = "bench scene";
    mr_cli_opt opts[] = {
        {"out", "DIR", "write bench_scene.csv, bench_scene.svg and the scenes there (default bench-out)", NULL},
        {"sizes", "LIST", "drawn-triangle targets (default 1M,5M,20M)", NULL},
        {"size", "WxH", "frame size (default 1024x768)", NULL},
        {"unique", NULL, "unique CAD-like geometry (every part its own mesh) instead of instanced parts", NULL},
        {"unit", "U", "scene units per metre of the unique factory (default 1; 1000: millimetres)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_scene_params p = {MR_BENCH_SCENE_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_scene_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck bench scene [--out DIR] [--sizes 1M,5M,20M] [--size WxH] [--frames N] [--unique [--unit U]]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    int nsizes = mr_cli_counts(mr_cli_get(opts, "sizes") ? mr_cli_get(opts, "sizes") : "1M,5M,20M", 1e4, 1e9, p.sizes,
                               MR_BENCH_SCENE_MAX_SIZES);
    if (nsizes <= 0) return mr_cli_errorf(cmd, "--sizes must be a list like 1M,5M,20M (10k..1000M each)"), 2;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) return 2;
    p.size_count = nsizes;
    p.out = stdout;
    p.unique = mr_cli_get(opts, "unique") != NULL;
    if (mr_cli_get(opts, "unit") && !mr_cli_double("unit", mr_cli_get(opts, "unit"), 1e-6, 1e9, &p.unit)) return 2;
    mr_error err = {0};
    bool ok = mr_gfx_open(&p.gfx, &err) && mr_bench_scene(&p, &err);
    mr_gfx_close(&p.gfx);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
