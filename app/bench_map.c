/* mrcheck bench map: wiring for mr_bench_map (lib/bench/map.c). */
#include "app.h"
#include "mr_bench.h"

int bench_map(int argc, char **argv) {
    static const char *cmd = "bench map";
    mr_cli_opt opts[] = {
        {"out", "DIR", "write bench_map.csv and .svg there (default bench-out)", NULL},
        {"seeds", "N", "photo sets per photo count (default 5)", NULL},
        {"max-photos", "N", "photo counts up to N only (default all: 10 20 50 100 200)", NULL},
        {"noise", "PX", "corner noise sigma (default 0.3)", NULL},
        {"misdetect", "F", "fraction of photos with one wrong tag id (default 0.05)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 3, opts, NULL, 0, NULL,
                   "usage: mrcheck bench map [--out DIR] [--seeds N] [--max-photos N]\n"
                   "Marker maps of synthetic halls (16 tags on a 3 m ring) from 10..200 photos: tag position\n"
                   "error against the truth and run time, bundle adjustment against chaining relative poses.",
                   &help))
        return 2;
    if (help) return 0;
    mr_bench_map_params p = {MR_BENCH_MAP_DEFAULTS};
    long v;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    if (mr_cli_get(opts, "seeds")) {
        if (!mr_cli_int("seeds", mr_cli_get(opts, "seeds"), 1, 1000, &v)) return 2;
        p.seeds = (int)v;
    }
    if (mr_cli_get(opts, "max-photos")) {
        if (!mr_cli_int("max-photos", mr_cli_get(opts, "max-photos"), 10, 200, &v)) return 2;
        p.max_photos = (int)v;
    }
    if (mr_cli_get(opts, "noise") && !mr_cli_double("noise", mr_cli_get(opts, "noise"), 0, 10, &p.noise_px)) return 2;
    if (mr_cli_get(opts, "misdetect") && !mr_cli_double("misdetect", mr_cli_get(opts, "misdetect"), 0, 1, &p.misdetect)) return 2;
    p.out = stdout;
    mr_error err = {0};
    return mr_bench_map(&p, &err) ? 0 : mr_cli_error(cmd, &err);
}
