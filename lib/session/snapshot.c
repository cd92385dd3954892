/* Snapshots of the view (mr_snapshot_write): the screen, the raw camera
 * frame and a JSON of the camera and pose they were made with. */
#include "session_internal.h"

#include <string.h>

/* Adds path, relative to dir, to rel under key. */
static void add_rel(cJSON *rel, const char *key, const char *dir, const char *path) {
    if (rel) cJSON_AddItemToObject(rel, key, cJSON_CreateString(path + strlen(dir) + 1));
}

bool mr_snapshot_write(const char *session_dir, const char *stem, const mr_snapshot *s, cJSON *rel, mr_error *err) {
    if (!s->screen || !s->screen->data || !s->camera) return mr_fail(err, MR_ERR_INVALID, "no screen image");
    char dir[4096], path[8192], name[256];
    mr_path_join(session_dir, "snapshots", dir, sizeof dir);
    if (!mr_mkdirs(dir, err)) return false;
    snprintf(name, sizeof name, "%s_screen.png", stem);
    mr_path_join(dir, name, path, sizeof path);
    if (!mr_image_save_png(path, s->screen, err)) return false;
    add_rel(rel, "screen", session_dir, path);
    const mr_capture_frame *f = s->frame;
    if (f && f->image.data) {
        snprintf(name, sizeof name, "%s_frame.png", stem);
        mr_path_join(dir, name, path, sizeof path);
        if (!mr_image_save_png(path, &f->image, err)) return false;
        add_rel(rel, "frame", session_dir, path);
    }
    cJSON *j = cJSON_CreateObject();
    cJSON_AddItemToObject(j, "camera", mr_camera_to_json(s->camera));
    if (f) {
        cJSON_AddNumberToObject(j, "frame_index", (double)f->index);
        cJSON_AddNumberToObject(j, "timestamp", f->timestamp);
        cJSON_AddItemToObject(j, "pose", mr_sess_pose_json(f->pose_valid, &f->pose, f->tags_seen, f->rms_px));
    }
    cJSON_AddNumberToObject(j, "alpha", s->alpha);
    cJSON_AddStringToObject(j, "passes", s->passes ? s->passes : "");
    snprintf(name, sizeof name, "%s.json", stem);
    mr_path_join(dir, name, path, sizeof path);
    bool ok = mr_json_save(path, j, err);
    cJSON_Delete(j);
    if (ok) add_rel(rel, "pose", session_dir, path);
    return ok;
}

void mr_snapshot_next_stem(const char *session_dir, const char *prefix, int *counter, char *stem, size_t n) {
    char probe[8192];
    for (;;) {
        snprintf(stem, n, "%s_%04d", prefix, ++*counter);
        snprintf(probe, sizeof probe, "%s/snapshots/%s.json", session_dir, stem);
        if (!mr_file_exists(probe)) return;
    }
}
