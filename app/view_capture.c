/* `mrcheck view`: capture and tracking off the render thread.
 *
 * Two threads and two one-frame mailboxes, newest frame wins at each:
 *   reader  -> [raw slot]  -> tracker -> [out slot] -> render thread
 * The reader drains the camera (or paces a replay by its timestamps), so a
 * slow detector never makes the camera queue up stale frames, and the
 * render thread only ever swaps pointers, so it never waits for either. */
#include "view.h"

#include "mr_session.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* A recording (or a folder of frames) opened for random access, so replay
 * can seek and step backwards. */
typedef struct replay_index {
    char dir[2048];           /* folder holding the frame images */
    char **names;
    int64_t count;
    double *t;                /* timestamps, seconds */
    bool *has_pose;
    mr_dmat4 *pose;           /* recorded world_from_camera per frame */
    int *tags;                /* recorded tags seen, -1 unknown */
    double *rms;
    mr_recording *rec;        /* a recording (lib/session), or NULL: a plain
                                 folder of frames */
} replay_index;

struct vw_capture {
    vw_capture_params p;
    char input[4096];
    pthread_t reader, tracker;
    bool reader_started, tracker_started;
    pthread_mutex_t mu;
    pthread_cond_t cv;          /* raw slot filled, controls changed, stop */
    bool stop;
    vw_state state;
    char msg[512];
    /* raw slot */
    mr_image raw;
    double raw_t;
    int64_t raw_index;
    uint64_t raw_seq, raw_taken;
    /* out slot */
    vw_frame out;
    /* replay controls */
    replay_index rp;
    bool seekable, playing, frozen;
    double rate;
    int64_t cur, seek_req;
    int step_req;
    bool rate_changed;
    /* counters */
    int64_t n_read, n_tracked, n_dropped;
    double track_ms_sum;
};

static void sleep_s(double s) {
    if (s <= 0) return;
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

/* Waits on the condition for at most s seconds (mutex held). */
static void wait_s(vw_capture *c, double s) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    double t = (double)ts.tv_sec + ts.tv_nsec * 1e-9 + s;
    ts.tv_sec = (time_t)t;
    ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
    pthread_cond_timedwait(&c->cv, &c->mu, &ts);
}

static void set_state(vw_capture *c, vw_state s, const char *msg) {
    pthread_mutex_lock(&c->mu);
    c->state = s;
    snprintf(c->msg, sizeof c->msg, "%s", msg ? msg : "");
    pthread_mutex_unlock(&c->mu);
    if (c->p.wake) c->p.wake(c->p.wake_ctx);
}

/* Hands a frame to the tracker; an unconsumed older one is dropped. */
static void put_raw(vw_capture *c, mr_image *img, double t, int64_t index) {
    pthread_mutex_lock(&c->mu);
    mr_image_free(&c->raw);
    c->raw = *img;
    memset(img, 0, sizeof *img);
    c->raw_t = t;
    c->raw_index = index;
    c->raw_seq++;
    c->n_read++;
    if (c->state != VW_RUNNING) {
        c->state = VW_RUNNING;
        c->msg[0] = 0;
    }
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->mu);
}

/* ------------------------------------------------------------- replay */

static bool is_image_name(const char *n) {
    const char *e = strrchr(n, '.');
    if (!e || n[0] == '.') return false;
    static const char *const exts[] = {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp"};
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; i++)
        if (strcasecmp(e, exts[i]) == 0) return true;
    return false;
}

static int cmp_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static bool list_images(replay_index *r, const char *dir) {
    DIR *d = opendir(dir);
    if (!d) return false;
    struct dirent *e;
    int64_t cap = 0;
    while ((e = readdir(d))) {
        if (!is_image_name(e->d_name)) continue;
        if (r->count == cap) {
            cap = cap ? cap * 2 : 256;
            char **n = realloc(r->names, (size_t)cap * sizeof *n);
            if (!n) break;
            r->names = n;
        }
        r->names[r->count++] = strdup(e->d_name);
    }
    closedir(d);
    if (r->count == 0) return false;
    qsort(r->names, (size_t)r->count, sizeof *r->names, cmp_name);
    snprintf(r->dir, sizeof r->dir, "%s", dir);
    return true;
}

/* frames.jsonl (DESIGN.md §2): one object per frame with its index,
 * timestamp and pose. Field names vary between writers, so a few are
 * accepted; a torn or unreadable line is skipped. */
static void read_frames_jsonl(replay_index *r, const char *path) {
    size_t size = 0;
    char *text = mr_file_read(path, &size, 0, NULL);
    if (!text) return;
    int64_t line_no = 0;
    for (char *line = text; line && *line; line_no++) {
        char *nl = strchr(line, '\n');
        if (nl) *nl = 0;
        cJSON *j = cJSON_Parse(line);
        if (j) {
            double idx = (double)line_no, t = -1;
            mr_json_number(j, "index", &idx, false, NULL);
            if (!mr_json_number(j, "timestamp", &t, false, NULL)) mr_json_number(j, "t", &t, false, NULL);
            int64_t i = (int64_t)idx;
            if (i >= 0 && i < r->count) {
                if (t >= 0) r->t[i] = t;
                const cJSON *pose = cJSON_GetObjectItemCaseSensitive(j, "pose");
                const cJSON *holder = j;
                if (cJSON_IsObject(pose)) holder = pose;
                mr_dmat4 m;
                const cJSON *valid = cJSON_GetObjectItemCaseSensitive(holder, "valid");
                bool ok = !cJSON_IsFalse(valid);
                if (ok && (mr_json_dmat4(holder, "world_from_camera", &m, NULL) ||
                           (cJSON_IsArray(pose) && mr_json_dmat4(j, "pose", &m, NULL))) &&
                    mr_m4_is_rigid(&m, 1e-4)) {
                    r->has_pose[i] = true;
                    r->pose[i] = m;
                }
                double v;
                if (mr_json_number(holder, "tags_seen", &v, false, NULL)) r->tags[i] = (int)v;
                if (mr_json_number(holder, "rms_px", &v, false, NULL)) r->rms[i] = v;
            }
            cJSON_Delete(j);
        }
        line = nl ? nl + 1 : NULL;
    }
    free(text);
}

static void replay_free(replay_index *r) {
    mr_recording_close(&r->rec);
    for (int64_t i = 0; r->names && i < r->count; i++) free(r->names[i]);
    free(r->names);
    free(r->t);
    free(r->has_pose);
    free(r->pose);
    free(r->tags);
    free(r->rms);
    memset(r, 0, sizeof *r);
}

static bool replay_open(replay_index *r, const char *dir, mr_error *err) {
    char sub[4096];
    if (mr_is_recording(dir)) {
        r->rec = mr_recording_open(dir, err);
        if (!r->rec) return false;
        r->count = r->rec->frame_count;
        if (r->count <= 0) {
            replay_free(r);
            return mr_fail(err, MR_ERR_IO, "recording %s has no frames", dir);
        }
    } else {
        mr_path_join(dir, "frames", sub, sizeof sub);
        if (!list_images(r, sub) && !list_images(r, dir))
            return mr_fail(err, MR_ERR_IO, "%s holds no frames (expected a recording or images in %s/frames/)", dir,
                           dir);
    }
    r->t = calloc((size_t)r->count, sizeof *r->t);
    r->has_pose = calloc((size_t)r->count, sizeof *r->has_pose);
    r->pose = calloc((size_t)r->count, sizeof *r->pose);
    r->tags = calloc((size_t)r->count, sizeof *r->tags);
    r->rms = calloc((size_t)r->count, sizeof *r->rms);
    if (!r->t || !r->has_pose || !r->pose || !r->tags || !r->rms) {
        replay_free(r);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int64_t i = 0; i < r->count; i++) {
        r->t[i] = (double)i / 30.0; /* without timestamps: 30 fps */
        r->tags[i] = -1;
        r->rms[i] = -1;
    }
    if (r->rec) {
        /* The recording's own poses: the filtered one where recorded, as
         * the live view showed it, else the raw pose. */
        for (int64_t i = 0; i < r->count; i++) {
            const mr_rec_frame *f = &r->rec->frames[i];
            r->t[i] = f->t;
            r->tags[i] = f->pose.tags_seen;
            r->rms[i] = f->pose.valid ? f->pose.rms_px : -1;
            if (f->pose.valid) {
                r->has_pose[i] = true;
                r->pose[i] = f->has_filtered ? f->filtered : f->pose.world_from_camera;
            }
        }
        return true;
    }
    mr_path_join(dir, "frames.jsonl", sub, sizeof sub);
    read_frames_jsonl(r, sub);
    return true;
}

static void *replay_reader(void *arg) {
    vw_capture *c = arg;
    replay_index *r = &c->rp;
    double anchor_wall = 0, anchor_t = 0;
    bool anchored = false;
    pthread_mutex_lock(&c->mu);
    c->state = VW_RUNNING;
    while (!c->stop) {
        int64_t next = -1;
        bool paced = false;
        if (c->seek_req >= 0) {
            next = c->seek_req;
            c->seek_req = -1;
            anchored = false;
        } else if (c->step_req) {
            next = c->cur + c->step_req;
            c->step_req = 0;
            c->playing = false;
        } else if (c->cur < 0) {
            next = 0; /* the first frame shows even when paused */
        } else if (c->playing && !c->frozen) {
            next = c->cur + 1;
            paced = true;
        }
        if (c->rate_changed) {
            anchored = false;
            c->rate_changed = false;
        }
        if (next < 0) {
            anchored = false;
            wait_s(c, 0.2);
            continue;
        }
        if (next >= r->count) {
            next = r->count - 1;
            if (paced) {
                c->playing = false;
                c->state = VW_ENDED;
                snprintf(c->msg, sizeof c->msg, "end of the recording");
                if (c->p.wake) c->p.wake(c->p.wake_ctx);
                continue;
            }
        }
        if (next < 0) next = 0;
        if (paced) {
            /* Timestamps drive playback, scaled by the rate; the anchor is
             * reset on play, seek and rate change so nothing jumps. */
            if (!anchored) {
                anchor_wall = mr_time_now();
                anchor_t = r->t[c->cur >= 0 ? c->cur : 0];
                anchored = true;
            }
            double due = anchor_wall + (r->t[next] - anchor_t) / (c->rate > 0 ? c->rate : 1);
            double now = mr_time_now();
            if (due > now + 0.001) {
                wait_s(c, due - now > 0.2 ? 0.2 : due - now);
                continue; /* re-check controls after waking */
            }
        }
        c->cur = next;
        if (c->state == VW_ENDED && next < r->count - 1) {
            c->state = VW_RUNNING;
            c->msg[0] = 0;
        }
        pthread_mutex_unlock(&c->mu);
        mr_image img = {0};
        mr_error e = {0};
        bool loaded;
        if (r->rec) {
            loaded = mr_recording_load_image(r->rec, (int)next, false, &img, &e);
        } else {
            char path[8192];
            mr_path_join(r->dir, r->names[next], path, sizeof path);
            loaded = mr_image_load(path, 3, &img, &e);
        }
        if (loaded) put_raw(c, &img, r->t[next], next);
        else mr_log(MR_LOG_WARN, "replay: skipping frame %lld: %s", (long long)next, e.msg);
        pthread_mutex_lock(&c->mu);
    }
    pthread_mutex_unlock(&c->mu);
    return NULL;
}

/* --------------------------------------------------------------- live */

static bool stopping(vw_capture *c) {
    pthread_mutex_lock(&c->mu);
    bool s = c->stop;
    pthread_mutex_unlock(&c->mu);
    return s;
}

static void *live_reader(void *arg) {
    vw_capture *c = arg;
    mr_source *src = NULL;
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.width = c->p.camera->width;
    sp.height = c->p.camera->height;
    sp.retries = -1; /* we retry ourselves, forever, and say so in the UI */
    bool ended = false;
    /* Files (video, image folders) play at their own pace, by timestamp, as
     * a camera would deliver them; a camera paces itself. */
    bool paced = false;
    double t0_wall = 0, t0_src = 0;
    while (!stopping(c)) {
        if (ended) {
            sleep_s(0.1);
            continue;
        }
        if (!src) {
            mr_error e = {0};
            src = mr_source_open(c->input, &sp, &e);
            paced = src && strcmp(mr_source_kind(src), "v4l2") != 0;
            t0_wall = -1;
            if (!src) {
                char m[512];
                snprintf(m, sizeof m, "no camera: %.440s (retrying)", e.msg);
                set_state(c, VW_NO_CAMERA, m);
                for (double t = 0; t < c->p.retry_s && !stopping(c); t += 0.05) sleep_s(0.05);
                continue;
            }
        }
        mr_frame fr;
        memset(&fr, 0, sizeof fr);
        mr_error e = {0};
        mr_read_status st = mr_source_read(src, &fr, &e);
        if (st == MR_READ_FRAME) {
            if (paced) {
                if (t0_wall < 0) {
                    t0_wall = mr_time_now();
                    t0_src = fr.timestamp;
                }
                double due = t0_wall + (fr.timestamp - t0_src);
                while (!stopping(c) && mr_time_now() < due - 1e-3) {
                    double left = due - mr_time_now();
                    sleep_s(left > 0.05 ? 0.05 : left);
                }
            }
            mr_image img = {0};
            if (mr_image_alloc(&img, fr.image.width, fr.image.height, fr.image.channels, MR_PIX_U8, &e)) {
                memcpy(img.data, fr.image.data, mr_image_bytes(&img));
                put_raw(c, &img, fr.timestamp, fr.index);
            }
        } else if (st == MR_READ_END) {
            ended = true;
            set_state(c, VW_ENDED, "end of the input");
        } else {
            char m[512];
            snprintf(m, sizeof m, "camera lost: %.440s (retrying)", e.msg);
            mr_source_close(&src);
            set_state(c, VW_NO_CAMERA, m);
            for (double t = 0; t < c->p.retry_s && !stopping(c); t += 0.05) sleep_s(0.05);
        }
    }
    mr_source_close(&src);
    return NULL;
}

/* ------------------------------------------------------------ tracker */

static void *tracker(void *arg) {
    vw_capture *c = arg;
    mr_error err = {0};
    mr_detector *det = NULL;
    mr_pose_filter *filt = NULL;
    if (c->p.markers) {
        mr_detector_params dp = MR_DETECTOR_DEFAULTS;
        dp.family = c->p.markers->family;
        det = mr_detector_create(&dp, &err);
        if (!det) mr_log(MR_LOG_ERROR, "view: %s", err.msg);
        filt = mr_pose_filter_create(NULL, &err);
    }
    mr_pose prev;
    memset(&prev, 0, sizeof prev);
    bool have_pose = false, was_frozen = false;
    mr_dmat4 last_pose = mr_m4_identity();
    mr_image work = {0};
    pthread_mutex_lock(&c->mu);
    while (!c->stop) {
        if (c->raw_seq == c->raw_taken) {
            wait_s(c, 0.2);
            continue;
        }
        c->n_dropped += (int64_t)(c->raw_seq - c->raw_taken - 1);
        c->raw_taken = c->raw_seq;
        mr_image_free(&work);
        work = c->raw;
        memset(&c->raw, 0, sizeof c->raw);
        double t = c->raw_t;
        int64_t index = c->raw_index;
        bool frozen = c->frozen;
        pthread_mutex_unlock(&c->mu);

        double t0 = mr_time_now();
        vw_frame f;
        memset(&f, 0, sizeof f);
        f.timestamp = t;
        f.index = index;
        f.count = c->seekable ? c->rp.count : -1;
        f.tags_seen = -1;
        f.rms_px = -1;
        if (filt && frozen != was_frozen) mr_pose_filter_freeze(filt, frozen);
        was_frozen = frozen;
        if (c->p.fixed_pose) {
            f.pose_valid = true;
            last_pose = *c->p.fixed_pose;
        } else if (c->seekable && !c->p.retrack && index >= 0 && index < c->rp.count && c->rp.has_pose[index]) {
            /* A recording's own poses: the replay shows what was seen. */
            f.pose_valid = true;
            last_pose = c->rp.pose[index];
            f.tags_seen = c->rp.tags[index];
            f.rms_px = c->rp.rms[index];
        } else if (det && c->p.markers) {
            int n = 0;
            mr_error e = {0};
            const mr_detection *d = mr_detector_detect(det, &work, &n, &e);
            mr_pose pose;
            memset(&pose, 0, sizeof pose);
            /* Intrinsics follow the frame size actually delivered (a
             * camera may not honour the requested size). */
            mr_camera cam = *c->p.camera;
            if (work.width != cam.width || work.height != cam.height) cam = mr_camera_resized(&cam, work.width, work.height);
            if (d && mr_pose_solve(&cam, c->p.markers, d, n, &prev, NULL, &pose, &e)) {
                f.tags_seen = pose.tags_seen;
                f.tags_used = pose.tags_used;
                f.rms_px = pose.valid ? pose.rms_px : -1;
                if (pose.valid) {
                    prev = pose;
                    mr_dmat4 out;
                    mr_pose_filter_update(filt, t, &pose.world_from_camera, &out);
                    f.pose_valid = true;
                    last_pose = out;
                }
            } else if (!d) {
                mr_log(MR_LOG_DEBUG, "view: detection failed: %s", e.msg);
            }
        }
        if (f.pose_valid) have_pose = true;
        f.have_pose = have_pose;
        f.pose = last_pose;
        f.track_ms = (mr_time_now() - t0) * 1e3;

        pthread_mutex_lock(&c->mu);
        c->n_tracked++;
        c->track_ms_sum += f.track_ms;
        mr_image_free(&c->out.image);
        f.image = work;
        memset(&work, 0, sizeof work);
        f.seq = c->out.seq + 1;
        c->out = f;
        pthread_mutex_unlock(&c->mu);
        if (c->p.wake) c->p.wake(c->p.wake_ctx);
        pthread_mutex_lock(&c->mu);
    }
    pthread_mutex_unlock(&c->mu);
    mr_image_free(&work);
    mr_detector_destroy(&det);
    mr_pose_filter_destroy(&filt);
    return NULL;
}

/* ------------------------------------------------------------- public */

vw_capture *vw_capture_start(const vw_capture_params *p, mr_error *err) {
    vw_capture *c = calloc(1, sizeof *c);
    if (!c) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    c->p = *p;
    if (!(c->p.retry_s > 0)) c->p.retry_s = 1.0;
    c->rate = 1.0;
    c->cur = -1;
    c->seek_req = -1;
    c->playing = true;
    pthread_mutex_init(&c->mu, NULL);
    pthread_cond_init(&c->cv, NULL);
    if (p->replay_dir) {
        if (!replay_open(&c->rp, p->replay_dir, err)) {
            vw_capture_stop(&c);
            return NULL;
        }
        c->seekable = true;
    } else {
        snprintf(c->input, sizeof c->input, "%s", p->input ? p->input : "");
    }
    c->tracker_started = pthread_create(&c->tracker, NULL, tracker, c) == 0;
    c->reader_started = pthread_create(&c->reader, NULL, c->seekable ? replay_reader : live_reader, c) == 0;
    if (!c->tracker_started || !c->reader_started) {
        vw_capture_stop(&c);
        mr_fail(err, MR_ERR_NOMEM, "cannot start the capture threads");
        return NULL;
    }
    return c;
}

void vw_capture_stop(vw_capture **cp) {
    if (!cp || !*cp) return;
    vw_capture *c = *cp;
    pthread_mutex_lock(&c->mu);
    c->stop = true;
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->mu);
    if (c->reader_started) pthread_join(c->reader, NULL);
    if (c->tracker_started) pthread_join(c->tracker, NULL);
    mr_image_free(&c->raw);
    vw_frame_free(&c->out);
    replay_free(&c->rp);
    pthread_mutex_destroy(&c->mu);
    pthread_cond_destroy(&c->cv);
    free(c);
    *cp = NULL;
}

bool vw_capture_latest(vw_capture *c, vw_frame *f) {
    pthread_mutex_lock(&c->mu);
    bool newer = c->out.seq > f->seq && c->out.image.data;
    if (newer) {
        mr_image mine = f->image;
        *f = c->out;
        c->out.image = mine; /* the old buffer goes back and is freed next time */
        mr_image_free(&c->out.image);
    }
    pthread_mutex_unlock(&c->mu);
    return newer;
}

void vw_frame_free(vw_frame *f) {
    if (f) mr_image_free(&f->image);
}

vw_state vw_capture_state(vw_capture *c, char *msg, size_t n) {
    pthread_mutex_lock(&c->mu);
    vw_state s = c->state;
    if (msg && n) snprintf(msg, n, "%s", c->msg);
    pthread_mutex_unlock(&c->mu);
    return s;
}

bool vw_capture_seekable(vw_capture *c) { return c->seekable; }

#define CONTROL(body)                    \
    do {                                 \
        pthread_mutex_lock(&c->mu);      \
        body;                            \
        pthread_cond_broadcast(&c->cv);  \
        pthread_mutex_unlock(&c->mu);    \
    } while (0)

void vw_capture_play(vw_capture *c, bool playing) {
    CONTROL({
        /* Play at the end starts over. */
        if (playing && !c->playing && c->seekable && c->cur >= c->rp.count - 1) c->seek_req = 0;
        c->playing = playing;
        c->rate_changed = true;
    });
}
bool vw_capture_playing(vw_capture *c) {
    pthread_mutex_lock(&c->mu);
    bool p = c->playing;
    pthread_mutex_unlock(&c->mu);
    return p;
}
void vw_capture_step(vw_capture *c, int delta) { CONTROL(c->step_req += delta); }
void vw_capture_seek(vw_capture *c, int64_t index) {
    CONTROL(c->seek_req = index < 0 ? 0 : c->seekable && index >= c->rp.count ? c->rp.count - 1 : index);
}
void vw_capture_rate(vw_capture *c, double rate) { CONTROL({ c->rate = rate; c->rate_changed = true; }); }
void vw_capture_freeze(vw_capture *c, bool frozen) { CONTROL({ c->frozen = frozen; c->rate_changed = true; }); }

void vw_capture_counts(vw_capture *c, int64_t *read, int64_t *tracked, int64_t *dropped, double *track_ms_sum) {
    pthread_mutex_lock(&c->mu);
    *read = c->n_read;
    *tracked = c->n_tracked;
    *dropped = c->n_dropped;
    *track_ms_sum = c->track_ms_sum;
    pthread_mutex_unlock(&c->mu);
}

/* ------------------------------------------------------ durable append */

bool vw_append_line(const char *path, const cJSON *obj, mr_error *err) {
    char *text = cJSON_PrintUnformatted(obj);
    if (!text) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    size_t n = strlen(text);
    char *line = malloc(n + 2);
    if (!line) {
        free(text);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    memcpy(line, text, n);
    line[n] = '\n';
    free(text);
    bool existed = mr_file_exists(path);
    int fd = open(path, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
        free(line);
        return mr_fail(err, MR_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    }
    /* One write: with O_APPEND the line lands whole at the end. */
    size_t done = 0;
    while (done < n + 1) {
        ssize_t w = write(fd, line + done, n + 1 - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) break;
        done += (size_t)w;
    }
    free(line);
    bool ok = done == n + 1 && fsync(fd) == 0;
    int e = errno;
    close(fd);
    if (!ok) return mr_fail(err, MR_ERR_IO, "cannot append to %s: %s", path, strerror(e));
    if (!existed) {
        /* A new file is only durable once its folder entry is. */
        char dir[4096];
        mr_path_dir(path, dir, sizeof dir);
        int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (dfd >= 0) {
            fsync(dfd);
            close(dfd);
        }
    }
    return true;
}
