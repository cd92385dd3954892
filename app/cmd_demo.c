/* mrcheck demo: the built-in job. Builds the procedural hall as planned and
 * as built, writes both as .glb with configs, marker map, discrepancy list
 * and views; renders synthetic camera frames of the as-built hall (lens
 * distortion, slight blur, sensor noise) and overlays the as-planned model on
 * them at alpha = 0.5. */
#include "app.h"
#include "app_track.h"
#include "mr_bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool write_markers(const char *path, const mr_demo_hall *hall, mr_error *err) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "family", "tag36h11");
    cJSON_AddNumberToObject(j, "tag_size", hall->tag_size);
    cJSON_AddStringToObject(j, "tag_frame",
                            "origin at the tag centre, x right, y down as seen facing the tag, z into the surface; "
                            "corners (apriltag order) at (-s/2,+s/2), (+s/2,+s/2), (+s/2,-s/2), (-s/2,-s/2)");
    cJSON *tags = cJSON_AddArrayToObject(j, "tags");
    for (int i = 0; i < hall->tag_count; i++) {
        cJSON *t = cJSON_CreateObject();
        cJSON_AddNumberToObject(t, "id", hall->tags[i].id);
        cJSON_AddItemToObject(t, "world_from_tag", mr_json_from_dmat4(&hall->tags[i].world_from_tag));
        cJSON_AddItemToArray(tags, t);
    }
    bool ok = mr_json_save(path, j, err);
    cJSON_Delete(j);
    return ok;
}

static bool write_scene_config(const char *path, const char *glb, const mr_demo_hall *hall, mr_error *err) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "gltf", glb);
    cJSON *h = cJSON_AddArrayToObject(j, "hidden");
    for (int i = 0; i < hall->hidden_glob_count; i++) cJSON_AddItemToArray(h, cJSON_CreateString(hall->hidden_globs[i]));
    cJSON_AddNumberToObject(j, "ambient", 0.35);
    bool ok = mr_json_save(path, j, err);
    cJSON_Delete(j);
    return ok;
}


static bool run_demo(const char *dir, mr_error *err) {
    char path[4096], sub[4096];
    double t0 = mr_time_now();
    if (!mr_mkdirs(dir, err)) return false;
    static const char *subs[] = {"frames", "overlay", "virtual", "views"};
    for (int i = 0; i < 4; i++) {
        mr_path_join(dir, subs[i], sub, sizeof sub);
        if (!mr_mkdirs(sub, err)) return false;
    }

    mr_demo_hall hall;
    if (!mr_demo_build_tagged(NULL, 0, &hall, err)) return false;
    bool ok;

    /* Files: both halls as .glb through tinygltf, configs, markers, the
     * list of discrepancies, the camera and the views. */
    mr_camera cam = mr_demo_camera();
    mr_path_join(dir, "hall_planned.glb", path, sizeof path);
    ok = mr_scene_save_glb(hall.planned, path, err);
    mr_path_join(dir, "hall_built.glb", path, sizeof path);
    ok = ok && mr_scene_save_glb(hall.built, path, err);
    mr_path_join(dir, "scene_planned.json", path, sizeof path);
    ok = ok && write_scene_config(path, "hall_planned.glb", &hall, err);
    mr_path_join(dir, "scene_built.json", path, sizeof path);
    ok = ok && write_scene_config(path, "hall_built.glb", &hall, err);
    mr_path_join(dir, "markers.json", path, sizeof path);
    ok = ok && write_markers(path, &hall, err);
    mr_path_join(dir, "discrepancies.json", path, sizeof path);
    ok = ok && mr_json_save(path, hall.discrepancies, err);
    cJSON *cj = mr_camera_to_json(&cam);
    mr_path_join(dir, "camera.json", path, sizeof path);
    ok = ok && mr_json_save(path, cj, err);
    cJSON_Delete(cj);
    mr_view views[MR_DEMO_VIEWS];
    for (int i = 0; ok && i < mr_demo_view_count(); i++) {
        views[i] = mr_demo_view(i);
        cJSON *vj = mr_view_to_json(&views[i]);
        snprintf(sub, sizeof sub, "views/view_%03d.json", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = mr_json_save(path, vj, err);
        cJSON_Delete(vj);
    }
    int discrepancy_count = cJSON_GetArraySize(hall.discrepancies);
    mr_demo_free(&hall);
    if (!ok) return false;
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
    ok = planned && app_gfx_open(&gfx, err);
    const int margin = 48, scale = 2;
    mr_camera wide = mr_demo_wide_camera(&cam, margin);
    for (int i = 0; ok && i < mr_demo_view_count(); i++) {
        mr_frame_result res = {0};
        mr_rng rng;
        mr_rng_seed(&rng, 1000u + (uint64_t)i); /* a different noise pattern per frame, the same every run */
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        mr_view v = views[i];
        v.camera = wide;
        fp.width = wide.width * scale;
        fp.height = wide.height * scale;
        mr_image frame = {0};
        ok = mr_renderer_set_scene(gfx.renderer, built, err) && mr_render_frame(gfx.renderer, &v, &fp, &res, err) &&
             mr_demo_camera_frame(&cam, &res.color, 1, margin, scale, 1.0, 2.5, &rng, &frame, err);
        mr_frame_result_free(&res);
        snprintf(sub, sizeof sub, "frames/frame_%03d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &frame, err);
        /* The check itself: the planned model over the camera frame. */
        mr_frame_params op = MR_FRAME_DEFAULTS;
        op.video = &frame;
        op.alpha = 0.5f;
        ok = ok && mr_renderer_set_scene(gfx.renderer, planned, err) &&
             mr_render_frame(gfx.renderer, &views[i], &op, &res, err);
        snprintf(sub, sizeof sub, "overlay/overlay_%03d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &res.color, err);
        mr_frame_result_free(&res);
        mr_frame_params vp = MR_FRAME_DEFAULTS;
        ok = ok && mr_render_frame(gfx.renderer, &views[i], &vp, &res, err);
        snprintf(sub, sizeof sub, "virtual/virtual_%03d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &res.color, err);
        mr_frame_result_free(&res);
        mr_image_free(&frame);
    }
    /* issue 16: marks at the known discrepancies, as BCF and a report */
    mr_bench_gpu bg = {gfx.gpu, gfx.renderer};
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
