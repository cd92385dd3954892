/* mrcheck bench: measurements (CSV + SVG plot), never pass/fail. */
#include "app.h"
#include "app_track.h"
#include "mr_bench.h"

#include <stdlib.h>
#include <string.h>

static int bench_frame(int argc, char **argv) {
    static const char *cmd = "bench frame";
    mr_cli_opt opts[] = {
        {"scene", "FILE", "glTF/GLB or scene config (default: the demo hall as planned)", NULL},
        {"view", "VIEW.json", "view (default: the demo's first viewpoint)", NULL},
        {"size", "WxH", "output size (default 1024x768)", NULL},
        {"video", "IMG", "camera frame to overlay (default: a synthetic frame, so the overlay pass runs)", NULL},
        {"out", "DIR", "write bench_frame.csv and bench_frame.svg there (default bench-out)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_bench_frame_params p = {MR_BENCH_FRAME_DEFAULTS};
    mr_cli_table table = {.prefix = "", .table = mr_bench_frame_opts, .params = &p};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, &table, 1, NULL, 0, NULL, "usage: mrcheck bench frame [--scene S] [--view V] [--size WxH] [--frames N] [--out DIR]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) return 2;
    if (mr_cli_get(opts, "out")) p.out_dir = mr_cli_get(opts, "out");
    p.scene = mr_cli_get(opts, "scene");
    p.out = stdout;
    mr_error err = {0};
    mr_view view;
    if (mr_cli_get(opts, "view")) {
        if (!mr_view_load(mr_cli_get(opts, "view"), &view, &err)) return mr_cli_error(cmd, &err);
        p.view = &view;
    }
    mr_image video = {0};
    if (mr_cli_get(opts, "video")) {
        if (!mr_image_load(mr_cli_get(opts, "video"), 3, &video, &err)) return mr_cli_error(cmd, &err);
        p.video = &video;
    }
    bool ok = mr_gfx_open(&p.gfx, &err) && mr_bench_frame(&p, &err);
    mr_gfx_close(&p.gfx);
    mr_image_free(&video);
    return ok ? 0 : mr_cli_error(cmd, &err);
}

int cmd_bench(int argc, char **argv) {
    if (argc >= 3 && strcmp(argv[2], "frame") == 0) return bench_frame(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "scene") == 0) return bench_scene(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "ao") == 0) return bench_ao(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "ghost") == 0) return app_bench_ghost(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "tracking") == 0) return bench_tracking(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "shadows") == 0) return app_bench_shadows(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "multiview") == 0) return bench_multiview(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "map") == 0) return bench_map(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "measure") == 0) return bench_measure(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "load") == 0) return bench_load(argc, argv);
    if (argc >= 3 && (strcmp(argv[2], "--help") == 0 || strcmp(argv[2], "-h") == 0)) {
        printf("usage: mrcheck bench {frame,ao,ghost,tracking,map,measure,scene,shadows,multiview,load} [options]   (mrcheck bench NAME --help)\n");
        return 0;
    }
    fprintf(stderr, "mrcheck: bench: unknown or missing benchmark%s%s (available: frame, ao, ghost, tracking, map, measure, scene, shadows, multiview, load)\n", argc >= 3 ? " " : "",
            argc >= 3 ? argv[2] : "");
    return 2;
}
