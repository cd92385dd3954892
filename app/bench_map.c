/* mrcheck bench map: wiring for mr_bench_map (lib/bench/map.c). */
#include "app.h"
#include "mr_bench.h"

int bench_map(int argc, char **argv) {
    static const char *cmd = "bench map";
    mr_cli_opt opts[] = {
        {"out", "DIR", "write bench_map.csv and .svg there (default bench-out)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_map_params p = {MR_BENCH_MAP_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_map_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck bench map [--out DIR] [--seeds N] [--max-photos N]\n"
                   "Marker maps of synthetic halls (16 tags on a 3 m ring) from 10..200 photos: tag position\n"
                   "error against the truth and run time, bundle adjustment against chaining relative poses.",
                   &help))
        return 2;
    if (help) return 0;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.out = stdout;
    mr_error err = {0};
    return mr_bench_map(&p, &err) ? 0 : mr_cli_error(cmd, &err);
}

/* mrcheck bench measure: wiring for mr_bench_measure (lib/bench/measure.c). */
int bench_measure(int argc, char **argv) {
    static const char *cmd = "bench measure";
    mr_cli_opt opts[] = {{"out", "DIR", "write bench_measure.csv and .svg there (default bench-out)", NULL},
                         {NULL, NULL, NULL, NULL}};
    mr_bench_measure_params p = {MR_BENCH_MEASURE_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_measure_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL,
                             "usage: mrcheck bench measure [--out DIR] [--maps N] [--points N] [--quick]\n"
                             "A measured point against known built deviations in synthetic halls: error, predicted\n"
                             "sigma, 95 % coverage and verdicts against the tolerance.",
                             &help))
        return 2;
    if (help) return 0;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.out = stdout;
    p.progress = true;
    mr_error err = {0};
    return mr_bench_measure(&p, &err) ? 0 : mr_cli_error(cmd, &err);
}
