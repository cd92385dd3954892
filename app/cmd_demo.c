/* mrcheck demo: the built-in job. Builds the procedural hall as planned and
 * as built, writes both as .glb with configs, marker map, discrepancy list
 * and views; renders synthetic camera frames of the as-built hall (lens
 * distortion, slight blur, sensor noise) and overlays the as-planned model on
 * them at alpha = 0.5. */
#include "app.h"
#include "app_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEMO_TAGS 16

/* The demo tablet camera: 640x480, ~65 degrees horizontal, mild barrel
 * distortion as a real tablet lens has. */
mr_camera app_demo_camera(void) {
    mr_camera c = {640, 480, 500.0, 500.0, 319.5, 239.5, {-0.10, 0.04, 0.0005, -0.0005, 0.0}};
    return c;
}

/* Standing viewpoints at eye height, looking at different parts of the
 * hall (tags, machines, the partition with the pipes behind it). */
static const double k_views[][6] = {
    {-4.0, 1.6, -2.0, -14.0, 2.0, 8.0},  /* the partition: pipes hidden behind it */
    {12.0, 1.7, 9.0, -4.0, 1.6, -9.0},   /* down the hall from the south-east */
    {0.0, 1.6, 6.0, 0.0, 2.2, -12.0},    /* the north wall and its tags */
    {16.0, 1.6, -9.0, -8.0, 1.5, 6.0},   /* under the suspended ceiling */
    {-2.0, 7.5, -11.0, -8.0, 0.0, 6.0},  /* overview from high up */
};
#define DEMO_VIEWS (int)(sizeof k_views / sizeof k_views[0])

int app_demo_view_count(void) { return DEMO_VIEWS; }

mr_view app_demo_view(int i) {
    mr_view v;
    v.camera = app_demo_camera();
    i = i < 0 ? 0 : i >= DEMO_VIEWS ? DEMO_VIEWS - 1 : i;
    v.world_from_camera = mr_m4_look_at_cv(mr_v3(k_views[i][0], k_views[i][1], k_views[i][2]),
                                           mr_v3(k_views[i][3], k_views[i][4], k_views[i][5]), mr_v3(0, 1, 0));
    return v;
}

bool app_demo_hall(mr_demo_hall *hall, mr_error *err) {
    mr_image *tags = NULL;
    int border = 1;
    memset(hall, 0, sizeof *hall);
    if (!app_tag_images(DEMO_TAGS, &tags, &border, err)) return false;
    mr_demo_params dp = MR_DEMO_DEFAULTS;
    dp.tag_images = tags;
    dp.tag_image_count = DEMO_TAGS;
    dp.tag_border_px = border;
    bool ok = mr_demo_build(&dp, hall, err);
    app_tag_images_free(tags, DEMO_TAGS);
    return ok;
}

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
    if (!app_demo_hall(&hall, err)) return false;
    bool ok;

    /* Files: both halls as .glb through tinygltf, configs, markers, the
     * list of discrepancies, the camera and the views. */
    mr_camera cam = app_demo_camera();
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
    mr_view views[DEMO_VIEWS];
    for (int i = 0; ok && i < DEMO_VIEWS; i++) {
        views[i] = app_demo_view(i);
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

    /* Render from the files just written, as a user's run would. */
    mr_scene *built = NULL, *planned = NULL;
    mr_path_join(dir, "scene_built.json", path, sizeof path);
    built = mr_scene_load(path, NULL, err);
    mr_path_join(dir, "scene_planned.json", path, sizeof path);
    planned = built ? mr_scene_load(path, NULL, err) : NULL;
    app_gfx gfx = {0};
    ok = planned && app_gfx_open(&gfx, err);
    const int margin = 48, scale = 2;
    mr_camera wide = cam;
    wide.width += 2 * margin;
    wide.height += 2 * margin;
    wide.cx += margin;
    wide.cy += margin;
    memset(wide.dist, 0, sizeof wide.dist);
    for (int i = 0; ok && i < DEMO_VIEWS; i++) {
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
             app_synth_frame(&cam, &res.color, 1, margin, scale, 1.0, 2.5, &rng, &frame, err);
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
    if (gfx.gpu) app_gfx_close(&gfx);
    uint64_t tri = planned ? mr_scene_triangle_count(planned) : 0;
    mr_scene_destroy(&built);
    mr_scene_destroy(&planned);
    if (!ok) return false;
    if (!app_demo_ghost(dir, err)) return false;
    printf("demo hall: %llu triangles as planned, %d known discrepancies (%.1f s to build)\n", (unsigned long long)tri,
           discrepancy_count, t_build);
    printf("wrote %s/: hall_planned.glb hall_built.glb scene_*.json markers.json discrepancies.json camera.json\n", dir);
    printf("  camera frames (as built):     %s/frames/frame_000..%03d.png\n", dir, DEMO_VIEWS - 1);
    printf("  overlays (planned, alpha 0.5): %s/overlay/overlay_000..%03d.png\n", dir, DEMO_VIEWS - 1);
    printf("  virtual only (planned):        %s/virtual/virtual_000..%03d.png\n", dir, DEMO_VIEWS - 1);
    if (!app_demo_track(dir, err)) return false; /* tracking: recording + calibration set (demo_track.c) */
    printf("done in %.1f s\n", mr_time_now() - t0);
    return true;
}

int cmd_demo(int argc, char **argv) {
    app_opt opts[] = {
        {"out", "DIR", "output folder (default: demo-out)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!app_parse(argc, argv, 2, opts, NULL, 0, NULL, "usage: mrcheck demo [--out DIR]", &help)) return 2;
    if (help) return 0;
    app_log_level(opts);
    const char *dir = app_get(opts, "out") ? app_get(opts, "out") : "demo-out";
    mr_error err = {0};
    if (!run_demo(dir, &err)) return app_error("demo", &err);
    return 0;
}
