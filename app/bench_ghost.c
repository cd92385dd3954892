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
        {"out", "DIR", "write bench_ghost.csv and bench_ghost.svg there (default bench-out)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_ghost_params p = {MR_BENCH_GHOST_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_ghost_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck bench ghost [--size WxH] [--frames N] [--view I] [--out DIR]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) return 2;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.progress = isatty(2) && !mr_cli_flag(opts, "quiet");
    p.out = stdout;
    mr_error err = {0};
    bool ok = mr_gfx_open(&p.gfx, &err) && mr_bench_ghost(&p, &err);
    mr_gfx_close(&p.gfx);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
