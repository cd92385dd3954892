/* The view's marks as session data: the frame a mark was made on (copied,
 * so the live frame can move on), the annotation fields that come from it,
 * and the mark's files (snapshot + the annotations.jsonl line). */
#include "session_internal.h"

#include <string.h>

bool mr_capture_frame_copy(mr_capture_frame *dst, const mr_capture_frame *src, mr_error *err) {
    mr_capture_frame_free(dst);
    *dst = *src;
    memset(&dst->image, 0, sizeof dst->image);
    if (!src->image.data) return true;
    if (!mr_image_alloc(&dst->image, src->image.width, src->image.height, src->image.channels, MR_PIX_U8, err))
        return false;
    memcpy(dst->image.data, src->image.data, mr_image_bytes(&src->image));
    return true;
}

void mr_annotation_from_frame(mr_annotation *m, const mr_capture_frame *f, const char *category, double time_unix) {
    memset(m, 0, sizeof *m);
    snprintf(m->type, sizeof m->type, "discrepancy");
    m->time_unix = time_unix;
    m->frame_index = f->index;
    m->timestamp = f->timestamp;
    snprintf(m->category, sizeof m->category, "%s", category ? category : "");
    m->revision = 1;
    m->node_index = -1;
    m->has_pose = true;
    m->pose_valid = f->pose_valid;
    m->world_from_camera = f->pose;
    m->pose_tags_seen = f->tags_seen;
    m->pose_rms_px = f->rms_px;
}

bool mr_mark_save(const char *session_dir, const char *stem, cJSON *line, const mr_snapshot *sn, bool *snapshot_ok,
                  mr_error *snapshot_err, mr_error *err) {
    cJSON *snap = cJSON_CreateObject();
    *snapshot_ok = mr_snapshot_write(session_dir, stem, sn, snap, snapshot_err);
    cJSON_AddItemToObject(line, "snapshot", snap);
    char path[8192];
    mr_path_join(session_dir, "annotations.jsonl", path, sizeof path);
    /* The line goes out even if the snapshot failed: the mark matters more. */
    return mr_mkdirs(session_dir, err) && mr_annotation_append(path, line, err);
}

const char *mr_capture_status_name(mr_capture_status st) {
    return st == MR_CAPTURE_RUNNING ? "running" : st == MR_CAPTURE_NO_CAMERA ? "no_camera" : st == MR_CAPTURE_ENDED ? "ended" : "starting";
}
