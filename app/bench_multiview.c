/* mrcheck bench multiview: option parsing; the bench is mr_bench_multiview
 * (lib/bench/multiview.c). */
#include "app.h"
#include "mr_bench.h"

#include <unistd.h>

int bench_multiview(int argc, char **argv) {
    static const char *cmd = "bench multiview";
    mr_cli_opt opts[] = {
        {"view", "VIEW.json", "the rig's centre view (default: the demo's first viewpoint)", NULL},
        {"budget", "WxH", "total pixels of all views in the budget rows (default 1024x768)", NULL},
        {"view-size", "WxH", "per-view size of the fixed-size rows and the display slices (default 160x120)", NULL},
        {"table-size", "WxH", "size of the no-SSAO / SSAO table (default 1024x768, as the paper)", NULL},
        {"out", "DIR", "output folder (default bench-out)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_multiview_params p = {MR_BENCH_MULTIVIEW_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_multiview_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck bench multiview [--budget WxH] [--view-size WxH] [--table-size WxH] [--frames N] "
                   "[--rays N] [--quick] [--shared-only] [--out DIR]",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (mr_cli_get(opts, "budget") && !mr_cli_size("budget", mr_cli_get(opts, "budget"), &p.budget_w, &p.budget_h)) return 2;
    if (mr_cli_get(opts, "view-size") && !mr_cli_size("view-size", mr_cli_get(opts, "view-size"), &p.view_w, &p.view_h)) return 2;
    if (mr_cli_get(opts, "table-size") && !mr_cli_size("table-size", mr_cli_get(opts, "table-size"), &p.table_w, &p.table_h))
        return 2;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.out = mr_cli_flag(opts, "quiet") ? NULL : stdout;
    p.progress = isatty(2);
    mr_error err = {0};
    mr_view view;
    if (mr_cli_get(opts, "view")) {
        if (!mr_view_load(mr_cli_get(opts, "view"), &view, &err)) return mr_cli_error(cmd, &err);
        p.view = &view;
    }
    bool ok = mr_gfx_open(&p.gfx, &err) && mr_bench_multiview(&p, &err);
    mr_gfx_close(&p.gfx);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
