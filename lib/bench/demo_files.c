/* `mrcheck demo`'s files (the first part of the job): both halls as .glb
 * with their scene configs, the marker map, the list of discrepancies, the
 * camera and the views; then the synthetic camera frames of the hall as
 * built with the planned model over them. */
#include "mr_bench.h"
#include "mr_session.h"

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

bool mr_demo_write_files(const char *dir, mr_view *views, int *discrepancy_count, mr_error *err) {
    char path[4096], sub[4096];
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
    for (int i = 0; ok && i < mr_demo_view_count(); i++) {
        views[i] = mr_demo_view(i);
        cJSON *vj = mr_view_to_json(&views[i]);
        snprintf(sub, sizeof sub, "views/view_%03d.json", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = mr_json_save(path, vj, err);
        cJSON_Delete(vj);
    }
    /* The folder is a hall too: `mrcheck view DIR --replay recording`. */
    const char *items[MR_HALL_ITEM_COUNT] = {[MR_HALL_SCENE] = "scene_planned.json", [MR_HALL_CAMERA] = "camera.json",
                                             [MR_HALL_MARKERS] = "markers.json"};
    ok = ok && mr_hall_write_manifest(dir, items, "mrcheck demo hall (as planned)", err);
    *discrepancy_count = cJSON_GetArraySize(hall.discrepancies);
    mr_demo_free(&hall);
    return ok;
}

bool mr_demo_render_frames(const char *dir, const mr_bench_gpu *g, const mr_scene *built, const mr_scene *planned,
                           const mr_view *views, mr_error *err) {
    char path[4096], sub[4096];
    mr_camera cam = mr_demo_camera();
    bool ok = true;
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
        ok = mr_renderer_set_scene(g->renderer, built, err) && mr_render_frame(g->renderer, &v, &fp, &res, err) &&
             mr_demo_camera_frame(&cam, &res.color, 1, margin, scale, 1.0, 2.5, &rng, &frame, err);
        mr_frame_result_free(&res);
        snprintf(sub, sizeof sub, "frames/frame_%03d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &frame, err);
        /* The check itself: the planned model over the camera frame. */
        mr_frame_params op = MR_FRAME_DEFAULTS;
        op.video = &frame; /* at MR_FRAME_DEFAULT_ALPHA */
        ok = ok && mr_renderer_set_scene(g->renderer, planned, err) &&
             mr_render_frame(g->renderer, &views[i], &op, &res, err);
        snprintf(sub, sizeof sub, "overlay/overlay_%03d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &res.color, err);
        mr_frame_result_free(&res);
        mr_frame_params vp = MR_FRAME_DEFAULTS;
        ok = ok && mr_render_frame(g->renderer, &views[i], &vp, &res, err);
        snprintf(sub, sizeof sub, "virtual/virtual_%03d.png", i);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &res.color, err);
        mr_frame_result_free(&res);
        mr_image_free(&frame);
    }
    return ok;
}
