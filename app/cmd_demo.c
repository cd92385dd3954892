/* mrcheck demo: the built-in job. Builds the procedural hall as planned and
 * as built, writes both as .glb with configs, marker map, discrepancy list
 * and views; renders synthetic camera frames of the as-built hall (lens
 * distortion, slight blur, sensor noise) and overlays the as-planned model on
 * them at alpha = 0.5. */
#include "app.h"
#include "app_track.h"
#include "mr_bench.h"

#include <stdlib.h>

static bool run_demo(const char *dir, mr_error *err) {
    char path[4096];
    double t0 = mr_time_now();
    /* Files: both halls as .glb through tinygltf, configs, markers, the
     * list of discrepancies, the camera and the views (lib/bench). */
    mr_view views[MR_DEMO_VIEWS];
    int discrepancy_count = 0;
    if (!mr_demo_write_files(dir, views, &discrepancy_count, err)) return false;
    double t_build = mr_time_now() - t0;
    /* tracking: recording + calibration set (demo_track.c); first, as the
     * marks at the end are placed on the recording's tracked frames */
    if (!app_demo_track(dir, err)) return false;

    /* Render from the files just written, as a user's run would. */
    mr_scene *built = NULL, *planned = NULL;
    mr_path_join(dir, "scene_built.json", path, sizeof path);
    built = mr_scene_load(path, NULL, err);
    mr_path_join(dir, "scene_planned.json", path, sizeof path);
    planned = built ? mr_scene_load(path, NULL, err) : NULL;
    app_gfx gfx = {0};
    bool ok = planned && app_gfx_open(&gfx, err);
    /* The camera frames of the hall as built, the overlays and the virtual
     * pictures (lib/bench). */
    mr_bench_gpu bg = {gfx.gpu, gfx.renderer};
    ok = ok && mr_demo_render_frames(dir, &bg, built, planned, views, err);
    /* Marks at the known discrepancies, as BCF and a report */
    ok = ok && mr_demo_marks(dir, &bg, built, planned, err);
    if (gfx.gpu) app_gfx_close(&gfx);
    uint64_t tri = planned ? mr_scene_triangle_count(planned) : 0;
    mr_scene_destroy(&built);
    mr_scene_destroy(&planned);
    if (!ok) return false;
    if (!app_demo_ghost(dir, err)) return false;
    printf("demo hall: %llu triangles as planned, %d known discrepancies (%.1f s to build)\n", (unsigned long long)tri,
           discrepancy_count, t_build);
    printf("wrote %s/: hall_planned.glb hall_built.glb scene_*.json markers.json discrepancies.json camera.json\n", dir);
    printf("  camera frames (as built):     %s/frames/frame_000..%03d.png\n", dir, mr_demo_view_count() - 1);
    printf("  overlays (planned, alpha 0.5): %s/overlay/overlay_000..%03d.png\n", dir, mr_demo_view_count() - 1);
    printf("  virtual only (planned):        %s/virtual/virtual_000..%03d.png\n", dir, mr_demo_view_count() - 1);
    printf("done in %.1f s\n", mr_time_now() - t0);
    return true;
}

int cmd_demo(int argc, char **argv) {
    mr_cli_opt opts[] = {
        {"out", "DIR", "output folder (default: demo-out)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 2, opts, NULL, 0, NULL, "usage: mrcheck demo [--out DIR]", &help)) return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *dir = mr_cli_get(opts, "out") ? mr_cli_get(opts, "out") : "demo-out";
    mr_error err = {0};
    if (!run_demo(dir, &err)) return mr_cli_error("demo", &err);
    return 0;
}
