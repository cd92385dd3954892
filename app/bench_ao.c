/* mrcheck bench ao: option parsing and the view files; the bench is
 * mr_bench_ao (lib/bench/ao.c). */
#include "app.h"
#include "mr_bench.h"

#define MAX_VIEWS MR_BENCH_AO_MAX_VIEWS

int bench_ao(int argc, char **argv) {
    static const char *cmd = "bench ao";
    mr_cli_opt opts[] = {
        {"scene", "FILE", "glTF/GLB or scene config (default: the demo hall as planned)", NULL},
        {"views", "V.json", "a reported view; more view files may follow as plain arguments (default: the demo "
                            "hall's near, mid-hall and far views)", NULL},
        {"tune-view", "V.json", "view the parameters are tuned on, not reported (default: a demo view not reported)", NULL},
        {"size", "WxH", "resolution (default 320x240)", NULL},
        {"sequence", "DIR", "recording whose poses are the moving sequence for temporal accumulation (default recordings/demo if there)", NULL},
        {"out", "DIR", "output folder (default bench-out)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[MAX_VIEWS];
    int npos = 0;
    mr_bench_ao_params p = {MR_BENCH_AO_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_ao_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, pos, MAX_VIEWS - 1, &npos,
                   "usage: mrcheck bench ao [--scene S] [--views V1.json [V2.json ...]] [--tune-view T.json] [--size WxH] [--out DIR]",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) return 2;
    if (npos > 0 && !mr_cli_get(opts, "views")) return mr_cli_errorf(cmd, "view files given without --views"), 2;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.scene = mr_cli_get(opts, "scene");
    p.verbose = mr_cli_flag(opts, "verbose");
    p.progress = !mr_cli_flag(opts, "quiet");
    p.sequence = mr_cli_get(opts, "sequence");
    p.out = stdout;
    mr_error err = {0};
    mr_view tune, views[MAX_VIEWS];
    const char *names[MAX_VIEWS];
    if (mr_cli_get(opts, "tune-view")) {
        if (!mr_view_load(mr_cli_get(opts, "tune-view"), &tune, &err)) return mr_cli_error(cmd, &err);
        p.tune_view = &tune;
        p.tune_name = mr_cli_get(opts, "tune-view");
    }
    if (mr_cli_get(opts, "views")) {
        names[p.view_count++] = mr_cli_get(opts, "views");
        for (int i = 0; i < npos; i++) names[p.view_count++] = pos[i];
        for (int i = 0; i < p.view_count; i++)
            if (!mr_view_load(names[i], &views[i], &err)) return mr_cli_error(cmd, &err);
        p.views = views;
        p.view_names = names;
    }
    bool ok = mr_gfx_open(&p.gfx, &err) && mr_bench_ao(&p, &err);
    mr_gfx_close(&p.gfx);
    return ok ? 0 : mr_cli_error(cmd, &err);
}
