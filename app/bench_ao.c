/* mrcheck bench ao: option parsing and the view files; the bench is
 * mr_bench_ao (lib/bench/ao.c). */
#include "app.h"
#include "mr_bench.h"

#define MAX_VIEWS MR_BENCH_AO_MAX_VIEWS

int bench_ao(int argc, char **argv) {
    static const char *cmd = "bench ao";
    app_opt opts[] = {
        {"scene", "FILE", "glTF/GLB or scene config (default: the demo hall as planned)", NULL},
        {"views", "V.json", "a reported view; more view files may follow as plain arguments (default: the demo "
                            "hall's near, mid-hall and far views)", NULL},
        {"tune-view", "V.json", "view the parameters are tuned on, not reported (default: a demo view not reported)", NULL},
        {"size", "WxH", "resolution (default 320x240)", NULL},
        {"frames", "N", "timed frames per configuration, median reported (default 5)", NULL},
        {"rays", "N", "ground-truth rays per pixel (default 256)", NULL},
        {"radius", "R", "ground truth's fixed radius in scene units (default 2% of the scene diagonal)", NULL},
        {"screen-radius", "F", "depth-scaled reference: radius as a fraction of image height at each depth (default 0.05)", NULL},
        {"sequence", "DIR", "recording whose poses are the moving sequence for temporal accumulation (default recordings/demo if there)", NULL},
        {"quick", NULL, "a reduced grid (samples 8 and 32, full resolution only, 2-point tuning)", NULL},
        {"out", "DIR", "output folder (default bench-out)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[MAX_VIEWS];
    int npos = 0;
    bool help;
    if (!app_parse(argc, argv, 3, opts, pos, MAX_VIEWS - 1, &npos,
                   "usage: mrcheck bench ao [--scene S] [--views V1.json [V2.json ...]] [--tune-view T.json] [--size WxH] [--out DIR]",
                   &help))
        return 2;
    if (help) return 0;
    app_log_level(opts);
    mr_bench_ao_params p = {MR_BENCH_AO_DEFAULTS};
    long frames = p.frames, rays = p.rays;
    if (app_get(opts, "size") && !app_size("size", app_get(opts, "size"), &p.width, &p.height)) return 2;
    if (app_get(opts, "frames") && !app_int("frames", app_get(opts, "frames"), 1, 64, &frames)) return 2;
    if (app_get(opts, "rays") && !app_int("rays", app_get(opts, "rays"), 1, 1 << 20, &rays)) return 2;
    if (app_get(opts, "radius") && !app_double("radius", app_get(opts, "radius"), 1e-30, 1e30, &p.radius)) return 2;
    if (app_get(opts, "screen-radius") && !app_double("screen-radius", app_get(opts, "screen-radius"), 1e-4, 1, &p.screen_radius))
        return 2;
    if (npos > 0 && !app_get(opts, "views")) return app_errorf(cmd, "view files given without --views"), 2;
    if (app_get(opts, "out")) p.out_dir = app_get(opts, "out");
    p.scene = app_get(opts, "scene");
    p.sequence = app_get(opts, "sequence");
    p.frames = (int)frames;
    p.rays = (int)rays;
    p.quick = app_flag(opts, "quick");
    p.verbose = app_flag(opts, "verbose");
    p.progress = !app_flag(opts, "quiet");
    p.out = stdout;
    mr_error err = {0};
    mr_view tune, views[MAX_VIEWS];
    const char *names[MAX_VIEWS];
    if (app_get(opts, "tune-view")) {
        if (!mr_view_load(app_get(opts, "tune-view"), &tune, &err)) return app_error(cmd, &err);
        p.tune_view = &tune;
        p.tune_name = app_get(opts, "tune-view");
    }
    if (app_get(opts, "views")) {
        names[p.view_count++] = app_get(opts, "views");
        for (int i = 0; i < npos; i++) names[p.view_count++] = pos[i];
        for (int i = 0; i < p.view_count; i++)
            if (!mr_view_load(names[i], &views[i], &err)) return app_error(cmd, &err);
        p.views = views;
        p.view_names = names;
    }
    app_gfx g;
    bool ok = app_bench_gpu(&g, &p.gfx, &err) && mr_bench_ao(&p, &err);
    app_gfx_close(&g);
    return ok ? 0 : app_error(cmd, &err);
}
