/* The replay index: random access to a recording's or a folder's frames
 * (mr_session.h). */
#include "session_internal.h"

#include <stdlib.h>
#include <string.h>

struct mr_replay {
    mr_recording *rec;        /* a recording, or NULL: a plain folder */
    char dir[4096];           /* plain folder: where the images are */
    char **names;             /* plain folder: image names, sorted */
    int name_count;
    int64_t count;
    mr_replay_frame *frames;
};

/* What a recorded line shows: the filtered pose where recorded (as the live
 * view showed it), else the raw pose. */
static void from_rec_frame(const mr_rec_frame *f, mr_replay_frame *o) {
    o->t = f->t;
    o->index = f->index;
    o->tags_seen = f->pose.tags_seen;
    o->rms_px = f->pose.valid ? f->pose.rms_px : -1;
    o->has_pose = f->pose.valid;
    o->pose = f->has_filtered ? f->filtered : f->pose.world_from_camera;
    if (!o->has_pose) o->pose = mr_m4_identity();
    o->corner_sigma_px = o->has_pose ? f->pose.corner_sigma_px : 0;
    if (o->corner_sigma_px > 0) memcpy(o->cov, f->pose.cov, sizeof o->cov);
}

/* A plain folder's frames.jsonl (the recording line format, through the
 * one reader): lines are matched to images by their "frame" number. */
static void read_folder_lines(mr_replay *r, const char *dir) {
    char path[4096];
    mr_path_join(dir, "frames.jsonl", path, sizeof path);
    if (!mr_file_exists(path)) return;
    size_t size = 0;
    mr_error e = {0};
    char *text = mr_file_read(path, &size, 0, &e);
    if (!text) {
        mr_log(MR_LOG_WARN, "%s", e.msg);
        return;
    }
    mr_recording tmp;
    memset(&tmp, 0, sizeof tmp);
    if (!mr_recording_parse_frames(&tmp, text, size, &e)) mr_log(MR_LOG_WARN, "%s: %s", path, e.msg);
    free(text);
    for (int k = 0; k < tmp.frame_count; k++) {
        int64_t i = tmp.frames[k].index;
        if (i >= 0 && i < r->count) {
            from_rec_frame(&tmp.frames[k], &r->frames[i]);
            r->frames[i].index = i;
        }
        free(tmp.frames[k].detections);
    }
    free(tmp.frames);
    if (tmp.bad_lines) mr_log(MR_LOG_WARN, "%s: skipped %d unreadable line(s)", path, tmp.bad_lines);
}

/* Positions 0 .. count-1 with their defaults, then what the recording
 * says (a plain folder's frames.jsonl is read by the caller). */
static bool fill_frames(mr_replay *r, mr_error *err) {
    r->frames = calloc((size_t)r->count, sizeof *r->frames);
    if (!r->frames) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int64_t i = 0; i < r->count; i++) {
        mr_replay_frame *f = &r->frames[i];
        f->index = i;
        f->t = (double)i / 30.0; /* without timestamps: 30 fps */
        f->tags_seen = -1;
        f->rms_px = -1;
        f->pose = mr_m4_identity();
        if (r->rec) from_rec_frame(&r->rec->frames[i], f);
    }
    return true;
}

mr_replay *mr_replay_from_recording(mr_recording *rec, mr_error *err) {
    mr_replay *r = calloc(1, sizeof *r);
    if (!r) {
        mr_recording_close(&rec);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    r->rec = rec;
    r->count = rec->frame_count;
    if (r->count <= 0) {
        mr_fail(err, MR_ERR_IO, "recording %s has no frames", rec->dir);
        mr_replay_close(&r);
        return NULL;
    }
    if (!fill_frames(r, err)) mr_replay_close(&r);
    return r;
}

mr_replay *mr_replay_open(const char *dir, mr_error *err) {
    if (mr_is_recording(dir)) {
        mr_recording *rec = mr_recording_open(dir, err);
        return rec ? mr_replay_from_recording(rec, err) : NULL;
    }
    mr_replay *r = calloc(1, sizeof *r);
    if (!r) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    char sub[4096];
    mr_error ignored = {0};
    mr_path_join(dir, "frames", sub, sizeof sub);
    const char *from = sub;
    if (!mr_image_folder_list(sub, &r->names, &r->name_count, &ignored) || r->name_count == 0) {
        mr_image_folder_free(&r->names, r->name_count);
        from = dir;
        if (!mr_image_folder_list(dir, &r->names, &r->name_count, &ignored) || r->name_count == 0) {
            mr_fail(err, MR_ERR_IO, "%s holds no frames (expected a recording or images in %s/frames/)", dir, dir);
            mr_replay_close(&r);
            return NULL;
        }
    }
    snprintf(r->dir, sizeof r->dir, "%s", from);
    r->count = r->name_count;
    if (!fill_frames(r, err)) {
        mr_replay_close(&r);
        return NULL;
    }
    read_folder_lines(r, dir);
    return r;
}

void mr_replay_close(mr_replay **r) {
    if (!r || !*r) return;
    mr_recording_close(&(*r)->rec);
    mr_image_folder_free(&(*r)->names, (*r)->name_count);
    free((*r)->frames);
    free(*r);
    *r = NULL;
}

int64_t mr_replay_count(const mr_replay *r) { return r->count; }

const mr_replay_frame *mr_replay_frame_at(const mr_replay *r, int64_t i) {
    return i >= 0 && i < r->count ? &r->frames[i] : NULL;
}

int64_t mr_replay_seek_frame(const mr_replay *r, int64_t index) {
    /* Frame numbers increase in file order: the first position >= index. */
    int64_t lo = 0, hi = r->count;
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (r->frames[mid].index < index) lo = mid + 1;
        else hi = mid;
    }
    return lo < r->count ? lo : r->count - 1;
}

int64_t mr_replay_seek_time(const mr_replay *r, double t) {
    /* The first position whose time is > t, minus one. */
    int64_t lo = 0, hi = r->count;
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (r->frames[mid].t <= t) lo = mid + 1;
        else hi = mid;
    }
    return lo > 0 ? lo - 1 : 0;
}

bool mr_replay_load_image(const mr_replay *r, int64_t i, bool gray, mr_image *img, mr_error *err) {
    memset(img, 0, sizeof *img);
    if (i < 0 || i >= r->count) return mr_fail(err, MR_ERR_INVALID, "frame %lld is out of range", (long long)i);
    if (r->rec) return mr_recording_load_image(r->rec, (int)i, gray, img, err);
    char path[8192];
    mr_path_join(r->dir, r->names[i], path, sizeof path);
    return mr_image_load(path, gray ? 1 : 3, img, err);
}

const mr_recording *mr_replay_recording(const mr_replay *r) { return r->rec; }

/* ------------------------------------------------- camera and markers */

bool mr_replay_meta_load(const char *dir, mr_camera *cam, bool have_cam, mr_marker_map *map, bool *have_map,
                         mr_error *err) {
    char path[4096], sub[8192];
    if (mr_is_recording(dir)) {
        mr_recording *rec = mr_recording_open(dir, err);
        if (!rec) return false;
        if (!have_cam) *cam = rec->camera;
        if (!*have_map && rec->has_markers) {
            /* Take the map over; the recording is closed right after. */
            *map = rec->markers;
            memset(&rec->markers, 0, sizeof rec->markers);
            rec->has_markers = false;
            *have_map = true;
        }
        mr_recording_close(&rec);
        return true;
    }
    mr_path_join(dir, "meta.json", path, sizeof path);
    cJSON *meta = mr_file_exists(path) ? mr_json_load(path, err) : NULL;
    if (mr_file_exists(path) && !meta) return false;
    bool ok = true;
    if (!have_cam) {
        const cJSON *c = meta ? cJSON_GetObjectItemCaseSensitive(meta, "camera") : NULL;
        if (cJSON_IsObject(c)) ok = mr_camera_from_json(c, cam, err);
        else {
            mr_path_join(dir, cJSON_IsString(c) ? c->valuestring : "camera.json", sub, sizeof sub);
            ok = mr_camera_load(sub, cam, err);
        }
    }
    if (ok && !*have_map) {
        const cJSON *m = meta ? cJSON_GetObjectItemCaseSensitive(meta, "markers") : NULL;
        if (!m && meta) m = cJSON_GetObjectItemCaseSensitive(meta, "marker_map");
        if (cJSON_IsObject(m)) *have_map = mr_marker_map_from_json(m, map, err);
        else {
            mr_path_join(dir, cJSON_IsString(m) ? m->valuestring : "markers.json", sub, sizeof sub);
            if (mr_file_exists(sub)) *have_map = mr_marker_map_load(sub, map, err);
        }
        /* No marker map is fine when frames.jsonl carries the poses. */
        if (!*have_map) err->msg[0] = 0;
    }
    cJSON_Delete(meta);
    return ok;
}
