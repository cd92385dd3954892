/* Recordings: crash-safe writer and tolerant reader (see mr_session.h). */
#include "session_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* ---------------------------------------------------------------- writer */

struct mr_recorder {
    char dir[1024];
    int fd_frames, fd_gt;       /* O_APPEND descriptors */
    char ext[8];
    int quality;
    int64_t next;
};

/* Writes one whole line with O_APPEND and syncs it: a crash leaves either
 * the complete line or a torn tail that the reader skips. */
static bool append_line(int fd, const char *line, size_t n, mr_error *err) {
    bool sync_failed = false;
    int e = mr_sess_write_line(fd, line, n, &sync_failed);
    if (e == 0) return true;
    if (sync_failed) return mr_fail(err, MR_ERR_IO, "cannot sync the recording (%s)", strerror(e));
    return mr_fail(err, MR_ERR_IO, "cannot append to the recording (%s)", strerror(e));
}

static int open_append(const char *dir, const char *name, mr_error *err) {
    char path[2048];
    mr_path_join(dir, name, path, sizeof path);
    int fd = open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd < 0) mr_fail(err, MR_ERR_IO, "%s: cannot create (%s)", path, strerror(errno));
    return fd;
}

mr_recorder *mr_recorder_create(const char *dir, const mr_recorder_params *params, mr_error *err) {
    mr_recorder_params p = params ? *params : (mr_recorder_params)MR_RECORDER_DEFAULTS;
    if (!p.camera) {
        mr_fail(err, MR_ERR_INVALID, "recording needs a camera");
        return NULL;
    }
    if (!mr_camera_validate(p.camera, err)) return NULL;
    const char *ext = p.frame_ext ? p.frame_ext : ".jpg";
    if (strcmp(ext, ".jpg") != 0 && strcmp(ext, ".png") != 0) {
        mr_fail(err, MR_ERR_INVALID, "frame format must be .jpg or .png");
        return NULL;
    }
    char path[2048];
    mr_path_join(dir, "frames.jsonl", path, sizeof path);
    if (mr_file_exists(path)) {
        mr_fail(err, MR_ERR_INVALID, "%s already holds a recording (not overwriting it)", dir);
        return NULL;
    }
    mr_path_join(dir, "frames", path, sizeof path);
    if (!mr_mkdirs(path, err)) return NULL;
    cJSON *meta = cJSON_CreateObject();
    cJSON_AddStringToObject(meta, "format", "mrcheck-recording");
    cJSON_AddNumberToObject(meta, "version", 1);
    cJSON_AddItemToObject(meta, "camera", mr_camera_to_json(p.camera));
    if (p.markers) cJSON_AddItemToObject(meta, "markers", mr_marker_map_to_json(p.markers));
    cJSON_AddStringToObject(meta, "source", p.source ? p.source : "");
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    cJSON_AddNumberToObject(meta, "start_time", (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec);
    cJSON_AddStringToObject(meta, "frame_ext", ext);
    mr_path_join(dir, "meta.json", path, sizeof path);
    bool ok = mr_json_save(path, meta, err);
    cJSON_Delete(meta);
    if (!ok) return NULL;
    mr_recorder *r = calloc(1, sizeof *r);
    if (!r) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    snprintf(r->dir, sizeof r->dir, "%s", dir);
    snprintf(r->ext, sizeof r->ext, "%s", ext);
    r->quality = p.jpeg_quality > 0 && p.jpeg_quality <= 100 ? p.jpeg_quality : MR_RECORDER_DEFAULT_JPEG_QUALITY;
    r->fd_gt = -1;
    r->fd_frames = open_append(dir, "frames.jsonl", err);
    if (r->fd_frames >= 0 && p.ground_truth) r->fd_gt = open_append(dir, "groundtruth.jsonl", err);
    if (r->fd_frames < 0 || (p.ground_truth && r->fd_gt < 0)) {
        mr_recorder_close(&r);
        return NULL;
    }
    return r;
}

cJSON *mr_detections_json(const mr_detection *d, int n, double quantum_px) {
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < n; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "id", d[i].id);
        cJSON_AddNumberToObject(o, "hamming", d[i].hamming);
        cJSON *c = cJSON_AddArrayToObject(o, "corners");
        for (int k = 0; k < 4; k++) {
            double p[2] = {d[i].corners[k][0], d[i].corners[k][1]};
            if (quantum_px > 0) {
                double inv = 1.0 / quantum_px; /* 1000 exactly for 1e-3 */
                for (int j = 0; j < 2; j++) p[j] = round(p[j] * inv) / inv;
            }
            cJSON_AddItemToArray(c, mr_json_from_doubles(p, 2));
        }
        cJSON_AddItemToArray(a, o);
    }
    return a;
}

cJSON *mr_pose_line_json(int64_t frame, double t, const mr_tracker_result *r) {
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "frame", (double)frame);
    cJSON_AddNumberToObject(o, "t", t);
    cJSON_AddBoolToObject(o, "valid", r->pose.valid);
    if (r->pose.valid) cJSON_AddItemToObject(o, "world_from_camera", mr_json_from_dmat4(&r->pose.world_from_camera));
    if (r->has_filtered) cJSON_AddItemToObject(o, "filtered", mr_json_from_dmat4(&r->filtered));
    cJSON_AddNumberToObject(o, "tags_seen", r->pose.tags_seen);
    cJSON_AddNumberToObject(o, "tags_used", r->pose.tags_used);
    cJSON_AddNumberToObject(o, "rms_px", r->pose.rms_px);
    cJSON_AddBoolToObject(o, "ambiguous", r->pose.ambiguous);
    if (r->pose.valid && r->pose.corner_sigma_px > 0) {
        /* The pose's uncertainty (mr_pose.cov, camera axes: rad, scene units). */
        cJSON_AddNumberToObject(o, "corner_sigma_px", r->pose.corner_sigma_px);
        cJSON_AddItemToObject(o, "covariance", mr_json_from_doubles(r->pose.cov, 36));
    }
    return o;
}

bool mr_recorder_append(mr_recorder *r, mr_frame_record *rec, const mr_image *image, mr_error *err) {
    rec->index = r->next;
    rec->image[0] = 0;
    if (image) {
        snprintf(rec->image, sizeof rec->image, "frames/%06lld%s", (long long)rec->index, r->ext);
        void *data = NULL;
        size_t size = 0;
        char path[2048];
        mr_path_join(r->dir, rec->image, path, sizeof path);
        bool ok = mr_image_encode(image, r->ext, r->quality, &data, &size, err) &&
                  mr_file_write_atomic(path, data, size, err);
        free(data);
        if (!ok) return false;
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "frame", (double)rec->index);
    cJSON_AddNumberToObject(o, "t", rec->t);
    cJSON_AddStringToObject(o, "image", rec->image);
    cJSON_AddItemToObject(o, "detections", mr_detections_json(rec->detections, rec->detection_count, 0));
    cJSON *p = cJSON_AddObjectToObject(o, "pose");
    cJSON_AddBoolToObject(p, "valid", rec->pose.valid);
    if (rec->pose.valid) cJSON_AddItemToObject(p, "world_from_camera", mr_json_from_dmat4(&rec->pose.world_from_camera));
    cJSON_AddNumberToObject(p, "tags_seen", rec->pose.tags_seen);
    cJSON_AddNumberToObject(p, "tags_used", rec->pose.tags_used);
    cJSON_AddNumberToObject(p, "rms_px", rec->pose.rms_px);
    cJSON_AddBoolToObject(p, "ambiguous", rec->pose.ambiguous);
    if (rec->pose.valid && rec->pose.corner_sigma_px > 0) {
        /* The pose's uncertainty (mr_pose.cov: camera axes, rad, scene units). */
        cJSON_AddNumberToObject(p, "corner_sigma_px", rec->pose.corner_sigma_px);
        cJSON_AddItemToObject(p, "covariance", mr_json_from_doubles(rec->pose.cov, 36));
    }
    cJSON *ids = cJSON_AddArrayToObject(p, "ids");
    for (int i = 0; i < rec->pose.tags_used && i < MR_POSE_MAX_IDS; i++)
        cJSON_AddItemToArray(ids, cJSON_CreateNumber(rec->pose.ids_used[i]));
    if (rec->has_filtered) cJSON_AddItemToObject(o, "filtered", mr_json_from_dmat4(&rec->filtered));
    size_t n = 0;
    char *line = mr_sess_json_line(o, &n);
    cJSON_Delete(o);
    if (!line) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    bool ok = append_line(r->fd_frames, line, n, err);
    free(line);
    if (ok) r->next++;
    return ok;
}

bool mr_recorder_ground_truth(mr_recorder *r, int64_t index, double t, const mr_dmat4 *wfc, bool still, mr_error *err) {
    if (r->fd_gt < 0) return mr_fail(err, MR_ERR_INVALID, "recorder was created without ground truth");
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "frame", (double)index);
    cJSON_AddNumberToObject(o, "t", t);
    cJSON_AddItemToObject(o, "world_from_camera", mr_json_from_dmat4(wfc));
    cJSON_AddBoolToObject(o, "still", still);
    size_t n = 0;
    char *line = mr_sess_json_line(o, &n);
    cJSON_Delete(o);
    if (!line) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    bool ok = append_line(r->fd_gt, line, n, err);
    free(line);
    return ok;
}

int64_t mr_recorder_frame_count(const mr_recorder *r) { return r->next; }

void mr_recorder_close(mr_recorder **r) {
    if (!r || !*r) return;
    if ((*r)->fd_frames >= 0) close((*r)->fd_frames);
    if ((*r)->fd_gt >= 0) close((*r)->fd_gt);
    free(*r);
    *r = NULL;
}

/* ---------------------------------------------------------------- reader */

static bool parse_detections(const cJSON *a, mr_rec_frame *f) {
    if (!a) return true;
    if (!cJSON_IsArray(a)) return false;
    int n = cJSON_GetArraySize(a);
    if (n > 10000) return false;
    if (n == 0) return true;
    f->detections = calloc((size_t)n, sizeof *f->detections);
    if (!f->detections) return false;
    const cJSON *d;
    int i = 0;
    cJSON_ArrayForEach(d, a) {
        mr_detection *o = &f->detections[i];
        double id = 0, ham = 0;
        const cJSON *c = cJSON_GetObjectItemCaseSensitive(d, "corners");
        if (!cJSON_IsObject(d) || !mr_json_number(d, "id", &id, true, NULL) || !mr_json_number(d, "hamming", &ham, false, NULL) ||
            !cJSON_IsArray(c) || cJSON_GetArraySize(c) != 4 || !(id >= 0 && id < 1e7))
            return false;
        o->id = (int)id;
        o->hamming = ham >= 0 && ham < 100 ? (int)ham : 0;
        for (int k = 0; k < 4; k++) {
            const cJSON *pt = cJSON_GetArrayItem(c, k);
            if (!cJSON_IsArray(pt) || cJSON_GetArraySize(pt) != 2) return false;
            for (int j = 0; j < 2; j++) {
                const cJSON *v = cJSON_GetArrayItem(pt, j);
                if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) return false;
                o->corners[k][j] = v->valuedouble;
            }
        }
        i++;
    }
    f->detection_count = n;
    return true;
}

static bool parse_frame_line(const cJSON *o, mr_rec_frame *f) {
    memset(f, 0, sizeof *f);
    double idx = 0, t = 0;
    if (!cJSON_IsObject(o) || !mr_json_number(o, "frame", &idx, true, NULL) || !mr_json_number(o, "t", &t, true, NULL))
        return false;
    if (!(idx >= 0 && idx < 1e12 && idx == floor(idx)) || !isfinite(t)) return false;
    f->index = (int64_t)idx;
    f->t = t;
    const cJSON *im = cJSON_GetObjectItemCaseSensitive(o, "image");
    if (im) {
        if (!cJSON_IsString(im) || strlen(im->valuestring) >= sizeof f->image || strstr(im->valuestring, "..") ||
            im->valuestring[0] == '/')
            return false; /* an image path must stay inside the recording */
        snprintf(f->image, sizeof f->image, "%s", im->valuestring);
    }
    if (!parse_detections(cJSON_GetObjectItemCaseSensitive(o, "detections"), f)) return false;
    const cJSON *p = cJSON_GetObjectItemCaseSensitive(o, "pose");
    if (p) {
        if (!cJSON_IsObject(p)) return false;
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(p, "valid");
        f->pose.valid = cJSON_IsTrue(v);
        f->pose.world_from_camera = mr_m4_identity();
        if (f->pose.valid && (!mr_json_dmat4(p, "world_from_camera", &f->pose.world_from_camera, NULL) ||
                              !mr_m4_is_rigid(&f->pose.world_from_camera, 1e-6)))
            return false;
        double x = 0;
        if (mr_json_number(p, "tags_seen", &x, false, NULL) && x >= 0 && x < 1e6) f->pose.tags_seen = (int)x;
        x = 0;
        if (mr_json_number(p, "tags_used", &x, false, NULL) && x >= 0 && x < 1e6) f->pose.tags_used = (int)x;
        x = 0;
        if (mr_json_number(p, "rms_px", &x, false, NULL) && isfinite(x)) f->pose.rms_px = x;
        f->pose.ambiguous = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(p, "ambiguous"));
        /* The covariance, when written (recordings before it have none);
         * a broken one is dropped, not fatal: the pose stands without it. */
        x = 0;
        if (f->pose.valid && mr_json_number(p, "corner_sigma_px", &x, false, NULL) && isfinite(x) && x > 0 &&
            mr_json_numbers(p, "covariance", f->pose.cov, 36, NULL)) {
            bool fin = true;
            for (int i = 0; i < 36; i++) fin = fin && isfinite(f->pose.cov[i]);
            f->pose.corner_sigma_px = fin ? x : 0;
            if (!fin) memset(f->pose.cov, 0, sizeof f->pose.cov);
        }
        const cJSON *ids = cJSON_GetObjectItemCaseSensitive(p, "ids"), *id;
        int k = 0;
        if (cJSON_IsArray(ids))
            cJSON_ArrayForEach(id, ids) if (cJSON_IsNumber(id) && k < MR_POSE_MAX_IDS) f->pose.ids_used[k++] = id->valueint;
    }
    if (cJSON_GetObjectItemCaseSensitive(o, "filtered")) {
        if (!mr_json_dmat4(o, "filtered", &f->filtered, NULL) || !mr_m4_is_rigid(&f->filtered, 1e-6)) return false;
        f->has_filtered = true;
    }
    return true;
}

void mr_sess_for_lines(const char *text, size_t size, mr_sess_line_fn fn, void *ctx, bool *torn, int *bad) {
    size_t pos = 0;
    while (pos < size) {
        const char *nl = memchr(text + pos, '\n', size - pos);
        if (!nl) {
            /* Whitespace only is not a torn line. */
            for (size_t i = pos; i < size; i++)
                if (text[i] != ' ' && text[i] != '\r' && text[i] != '\t') *torn = true;
            return;
        }
        size_t n = (size_t)(nl - (text + pos));
        bool blank = true;
        for (size_t i = 0; i < n; i++)
            if (text[pos + i] != ' ' && text[pos + i] != '\r' && text[pos + i] != '\t') blank = false;
        if (!blank && !fn(ctx, text + pos, n)) (*bad)++;
        pos += n + 1;
    }
}

int mr_sess_write_line(int fd, const char *line, size_t n, bool *sync_failed) {
    *sync_failed = false;
    size_t off = 0;
    while (off < n) {
        ssize_t w = write(fd, line + off, n - off);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return w < 0 ? errno : EIO;
        off += (size_t)w;
    }
    /* EINVAL: the file does not support syncing (a pipe, some special file
     * systems); nothing more can be done there. */
    if (fsync(fd) != 0 && errno != EINVAL) {
        *sync_failed = true;
        return errno;
    }
    return 0;
}

char *mr_sess_json_line(const cJSON *obj, size_t *n) {
    char *s = cJSON_PrintUnformatted(obj);
    if (!s) return NULL;
    size_t len = strlen(s);
    char *line = malloc(len + 2);
    if (line) {
        memcpy(line, s, len);
        line[len] = '\n';
        line[len + 1] = 0;
        *n = len + 1;
    }
    free(s);
    return line;
}

void *mr_sess_grow(void *items, int count, int *cap, int first, size_t elem) {
    if (items && count < *cap) return items;
    int ncap = *cap ? 2 * *cap : first;
    void *n = realloc(items, (size_t)ncap * elem);
    if (n) *cap = ncap;
    return n;
}

typedef struct frames_ctx { mr_recording *rec; int cap; bool oom; } frames_ctx;

static bool frame_line(void *vctx, const char *line, size_t n) {
    frames_ctx *c = vctx;
    cJSON *o = cJSON_ParseWithLength(line, n);
    if (!o) return false;
    mr_rec_frame f;
    bool ok = parse_frame_line(o, &f);
    cJSON_Delete(o);
    if (!ok) {
        free(f.detections);
        return false;
    }
    mr_recording *r = c->rec;
    mr_rec_frame *nf = mr_sess_grow(r->frames, r->frame_count, &c->cap, 256, sizeof *nf);
    if (!nf) {
        free(f.detections);
        c->oom = true;
        return false;
    }
    r->frames = nf;
    r->frames[r->frame_count++] = f;
    return true;
}

bool mr_recording_parse_frames(mr_recording *rec, const char *text, size_t size, mr_error *err) {
    frames_ctx c = {rec, rec->frame_count, false};
    bool torn = false;
    int bad = 0;
    mr_sess_for_lines(text, size, frame_line, &c, &torn, &bad);
    rec->bad_lines += bad;
    rec->torn_tail = rec->torn_tail || torn;
    if (c.oom) return mr_fail(err, MR_ERR_NOMEM, "out of memory reading the recording");
    return true;
}

static int find_frame(const mr_recording *rec, int64_t index) {
    /* Frames are written in order: binary search, fall back to a scan. */
    int lo = 0, hi = rec->frame_count - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2;
        if (rec->frames[mid].index == index) return mid;
        if (rec->frames[mid].index < index) lo = mid + 1;
        else hi = mid - 1;
    }
    for (int i = 0; i < rec->frame_count; i++)
        if (rec->frames[i].index == index) return i;
    return -1;
}

static bool gt_line(void *vctx, const char *line, size_t n) {
    mr_recording *rec = vctx;
    cJSON *o = cJSON_ParseWithLength(line, n);
    if (!o) return false;
    double idx = 0, t = 0;
    mr_dmat4 m;
    bool ok = cJSON_IsObject(o) && mr_json_number(o, "frame", &idx, true, NULL) && mr_json_number(o, "t", &t, false, NULL) &&
              mr_json_dmat4(o, "world_from_camera", &m, NULL) && mr_m4_is_rigid(&m, 1e-6) && idx >= 0 && idx < 1e12;
    bool still = ok && cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, "still"));
    cJSON_Delete(o);
    if (!ok) return false;
    int i = find_frame(rec, (int64_t)idx);
    if (i < 0) return true; /* ground truth of a frame lost in a crash */
    rec->frames[i].has_gt = true;
    rec->frames[i].gt = m;
    rec->frames[i].still = still;
    return true;
}

void mr_recording_parse_ground_truth(mr_recording *rec, const char *text, size_t size) {
    bool torn = false;
    int bad = 0;
    mr_sess_for_lines(text, size, gt_line, rec, &torn, &bad);
    rec->bad_lines += bad;
}

bool mr_recording_parse_meta(mr_recording *rec, const cJSON *meta, mr_error *err) {
    if (!cJSON_IsObject(meta)) return mr_fail(err, MR_ERR_PARSE, "meta.json: not a JSON object");
    const cJSON *cam = cJSON_GetObjectItemCaseSensitive(meta, "camera");
    if (!cam) return mr_fail(err, MR_ERR_PARSE, "meta.json: no camera");
    if (!mr_camera_from_json(cam, &rec->camera, err)) {
        mr_error_prefix(err, "meta.json");
        return false;
    }
    const cJSON *mk = cJSON_GetObjectItemCaseSensitive(meta, "markers");
    if (mk) {
        if (!mr_marker_map_from_json(mk, &rec->markers, err)) {
            mr_error_prefix(err, "meta.json");
            return false;
        }
        rec->has_markers = true;
    }
    const cJSON *src = cJSON_GetObjectItemCaseSensitive(meta, "source");
    if (cJSON_IsString(src)) snprintf(rec->source, sizeof rec->source, "%s", src->valuestring);
    const cJSON *st = cJSON_GetObjectItemCaseSensitive(meta, "start_time");
    if (cJSON_IsNumber(st)) rec->start_time = st->valuedouble;
    return true;
}

bool mr_is_recording(const char *dir) {
    char p[2048];
    mr_path_join(dir, "meta.json", p, sizeof p);
    if (!mr_file_exists(p)) return false;
    mr_path_join(dir, "frames.jsonl", p, sizeof p);
    return mr_file_exists(p);
}

mr_recording *mr_recording_open(const char *dir, mr_error *err) {
    char path[2048];
    mr_recording *rec = calloc(1, sizeof *rec);
    if (!rec) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    snprintf(rec->dir, sizeof rec->dir, "%s", dir);
    mr_path_join(dir, "meta.json", path, sizeof path);
    if (!mr_file_exists(path)) {
        mr_fail(err, MR_ERR_IO, "%s: not a recording (no meta.json)", dir);
        mr_recording_close(&rec);
        return NULL;
    }
    cJSON *meta = mr_json_load(path, err);
    bool ok = meta && mr_recording_parse_meta(rec, meta, err);
    cJSON_Delete(meta);
    size_t size = 0;
    char *text = NULL;
    if (ok) {
        mr_path_join(dir, "frames.jsonl", path, sizeof path);
        text = mr_file_read(path, &size, 0, err);
        ok = text && mr_recording_parse_frames(rec, text, size, err);
        free(text);
    }
    if (ok) {
        mr_path_join(dir, "groundtruth.jsonl", path, sizeof path);
        if (mr_file_exists(path)) {
            mr_error e = {0};
            text = mr_file_read(path, &size, 0, &e);
            if (text) mr_recording_parse_ground_truth(rec, text, size);
            else mr_log(MR_LOG_WARN, "%s", e.msg);
            free(text);
        }
    }
    if (!ok) {
        mr_recording_close(&rec);
        return NULL;
    }
    if (rec->bad_lines) mr_log(MR_LOG_WARN, "%s: skipped %d unreadable line(s)", dir, rec->bad_lines);
    if (rec->torn_tail) mr_log(MR_LOG_INFO, "%s: ignored a torn last line (interrupted recording)", dir);
    return rec;
}

void mr_recording_close(mr_recording **rec) {
    if (!rec || !*rec) return;
    for (int i = 0; i < (*rec)->frame_count; i++) free((*rec)->frames[i].detections);
    free((*rec)->frames);
    mr_marker_map_free(&(*rec)->markers);
    free(*rec);
    *rec = NULL;
}

bool mr_recording_load_image(const mr_recording *rec, int i, bool gray, mr_image *img, mr_error *err) {
    memset(img, 0, sizeof *img);
    if (i < 0 || i >= rec->frame_count) return mr_fail(err, MR_ERR_INVALID, "frame %d is out of range", i);
    if (!rec->frames[i].image[0]) return mr_fail(err, MR_ERR_IO, "frame %lld has no image", (long long)rec->frames[i].index);
    char path[2048];
    mr_path_join(rec->dir, rec->frames[i].image, path, sizeof path);
    return mr_image_load(path, gray ? 1 : 3, img, err);
}

/* --------------------------------------------------------- frame source */

typedef struct rec_src {
    mr_recording *rec;
    bool gray;
    int next;
    mr_image img;
} rec_src;

static mr_read_status rec_read(void *impl, mr_frame *frame, mr_error *err) {
    rec_src *s = impl;
    (void)err;
    while (s->next < s->rec->frame_count) {
        int i = s->next++;
        mr_image_free(&s->img);
        mr_error e = {0};
        if (!mr_recording_load_image(s->rec, i, s->gray, &s->img, &e)) {
            mr_log(MR_LOG_WARN, "skipping recorded frame %lld: %s", (long long)s->rec->frames[i].index, e.msg);
            continue;
        }
        memset(frame, 0, sizeof *frame);
        frame->image = s->img;
        frame->index = s->rec->frames[i].index;
        frame->timestamp = s->rec->frames[i].t;
        snprintf(frame->name, sizeof frame->name, "%s", s->rec->frames[i].image);
        return MR_READ_FRAME;
    }
    return MR_READ_END;
}

static void rec_close(void *impl) {
    rec_src *s = impl;
    mr_image_free(&s->img);
    mr_recording_close(&s->rec);
    free(s);
}

static const mr_source_ops k_rec_ops = {"recording", rec_read, rec_close};

mr_source *mr_recording_source(mr_recording *rec, bool gray, mr_error *err) {
    rec_src *s = calloc(1, sizeof *s);
    if (!s) {
        mr_recording_close(&rec);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    s->rec = rec;
    s->gray = gray;
    return mr_source_from_ops(&k_rec_ops, s, err);
}
