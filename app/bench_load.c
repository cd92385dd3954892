/* mrcheck bench load: wiring for mr_bench_load (lib/bench/load.c). */
#include "app.h"
#include "mr_bench.h"

int bench_load(int argc, char **argv) {
    static const char *cmd = "bench load";
    mr_cli_opt opts[] = {
        {"out", "DIR", "write the factories, their gltfpack files, bench_load.csv and .svg there (default bench-out)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_load_params p = {MR_BENCH_LOAD_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_load_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                             "usage: mrcheck bench load [--out DIR] [--runs N] [--triangles N] [--unique-triangles N]\n"
                             "First-load time of the instanced and the unique factory as .glb and as gltfpack writes them\n"
                             "(default, -c, -cc): CPU s, wall s, MB/s, peak RSS, one fresh process per load. Needs gltfpack.",
                             &help))
        return 2;
    if (help) return 0;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.out = stdout;
    mr_error err = {0};
    return mr_bench_load(&p, &err) ? 0 : mr_cli_error(cmd, &err);
}
