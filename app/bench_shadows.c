/* mrcheck bench shadows: wiring of mr_bench_shadows (lib/bench/shadows.c). */
#include "app.h"
#include "mr_bench.h"

int app_bench_shadows(int argc, char **argv) {
    static const char *cmd = "bench shadows";
    mr_cli_opt opts[] = {
        {"size", "WxH", "output size (default 320x240)", NULL},
        {"out", "DIR", "write bench_shadows.{csv,svg,md} and the montages there (default bench-out)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_shadows_params p = {MR_BENCH_SHADOWS_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_shadows_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck bench shadows [--size WxH] [--frames N] [--rays N] [--first I --count N] [--views N] "
                   "[--out DIR]",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) return 2;
    if (p.count > 0 && p.first + p.count > MR_SHADOW_SUITE_COUNT)
        return mr_cli_errorf(cmd, "--first %d --count %d goes past the suite's %d cases", p.first, p.count,
                             MR_SHADOW_SUITE_COUNT), 2;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.out = stdout;
    mr_error err = {0};
    bool ok = mr_gfx_open(&p.gfx, &err) && mr_bench_shadows(&p, &err);
    mr_gfx_close(&p.gfx);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
