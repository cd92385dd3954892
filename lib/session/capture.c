/* capture.c — `mrcheck view`: capture and tracking off the render thread.
 *
 * Two threads and two one-frame mailboxes, newest frame wins at each:
 *   reader  -> [raw slot]  -> tracker -> [out slot] -> render thread
 * The reader drains the camera (or paces a replay by its timestamps), so a
 * slow detector never makes the camera queue up stale frames, and the
 * render thread only ever swaps pointers, so it never waits for either. */
#include "mr_session.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct mr_capture {
    mr_capture_params p;
    char input[4096];
    pthread_t reader, tracker;
    bool reader_started, tracker_started;
    pthread_mutex_t mu;
    pthread_cond_t cv;          /* raw slot filled, controls changed, stop */
    bool stop;
    mr_capture_status state;
    char msg[512];
    /* raw slot */
    mr_image raw;
    double raw_t;
    int64_t raw_index;
    uint64_t raw_seq, raw_taken;
    /* out slot */
    mr_capture_frame out;
    /* replay controls */
    mr_replay *rp;            /* replay: random access (lib/session) */
    int64_t rp_count;
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
static void wait_s(mr_capture *c, double s) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    double t = (double)ts.tv_sec + ts.tv_nsec * 1e-9 + s;
    ts.tv_sec = (time_t)t;
    ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
    pthread_cond_timedwait(&c->cv, &c->mu, &ts);
}

static void set_state(mr_capture *c, mr_capture_status s, const char *msg) {
    pthread_mutex_lock(&c->mu);
    c->state = s;
    snprintf(c->msg, sizeof c->msg, "%s", msg ? msg : "");
    pthread_mutex_unlock(&c->mu);
    if (c->p.wake) c->p.wake(c->p.wake_ctx);
}

/* Hands a frame to the tracker; an unconsumed older one is dropped. */
static void put_raw(mr_capture *c, mr_image *img, double t, int64_t index) {
    pthread_mutex_lock(&c->mu);
    mr_image_free(&c->raw);
    c->raw = *img;
    memset(img, 0, sizeof *img);
    c->raw_t = t;
    c->raw_index = index;
    c->raw_seq++;
    c->n_read++;
    if (c->state != MR_CAPTURE_RUNNING) {
        c->state = MR_CAPTURE_RUNNING;
        c->msg[0] = 0;
    }
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->mu);
}

/* ------------------------------------------------------------- replay */

static void *replay_reader(void *arg) {
    mr_capture *c = arg;
    const mr_replay *r = c->rp;
    double anchor_wall = 0, anchor_t = 0;
    bool anchored = false;
    pthread_mutex_lock(&c->mu);
    c->state = MR_CAPTURE_RUNNING;
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
        if (next >= c->rp_count) {
            next = c->rp_count - 1;
            if (paced) {
                c->playing = false;
                c->state = MR_CAPTURE_ENDED;
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
                anchor_t = mr_replay_frame_at(r, c->cur >= 0 ? c->cur : 0)->t;
                anchored = true;
            }
            double due = anchor_wall + (mr_replay_frame_at(r, next)->t - anchor_t) / (c->rate > 0 ? c->rate : 1);
            double now = mr_time_now();
            if (due > now + 0.001) {
                wait_s(c, due - now > 0.2 ? 0.2 : due - now);
                continue; /* re-check controls after waking */
            }
        }
        c->cur = next;
        if (c->state == MR_CAPTURE_ENDED && next < c->rp_count - 1) {
            c->state = MR_CAPTURE_RUNNING;
            c->msg[0] = 0;
        }
        pthread_mutex_unlock(&c->mu);
        mr_image img = {0};
        mr_error e = {0};
        bool loaded = mr_replay_load_image(r, next, false, &img, &e);
        if (loaded) put_raw(c, &img, mr_replay_frame_at(r, next)->t, next);
        else mr_log(MR_LOG_WARN, "replay: skipping frame %lld: %s", (long long)next, e.msg);
        pthread_mutex_lock(&c->mu);
    }
    pthread_mutex_unlock(&c->mu);
    return NULL;
}

/* --------------------------------------------------------------- live */

static bool stopping(mr_capture *c) {
    pthread_mutex_lock(&c->mu);
    bool s = c->stop;
    pthread_mutex_unlock(&c->mu);
    return s;
}

static void *live_reader(void *arg) {
    mr_capture *c = arg;
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
                set_state(c, MR_CAPTURE_NO_CAMERA, m);
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
            set_state(c, MR_CAPTURE_ENDED, "end of the input");
        } else {
            char m[512];
            snprintf(m, sizeof m, "camera lost: %.440s (retrying)", e.msg);
            mr_source_close(&src);
            set_state(c, MR_CAPTURE_NO_CAMERA, m);
            for (double t = 0; t < c->p.retry_s && !stopping(c); t += 0.05) sleep_s(0.05);
        }
    }
    mr_source_close(&src);
    return NULL;
}

/* ------------------------------------------------------------ tracker */

/* One frame through the one tracker (lib/track), as `mrcheck track` runs
 * it: the view shows the filtered pose of a frame with a valid pose and
 * otherwise keeps the last one it showed. */
static void track_frame(mr_tracker *trk, const mr_image *img, double t, mr_capture_frame *f, mr_dmat4 *last_pose,
                        mr_pose *last_cov) {
    mr_tracker_result r;
    mr_error e = {0};
    if (!mr_tracker_frame(trk, img, t, &r, &e)) {
        mr_log(MR_LOG_DEBUG, "view: tracking failed: %s", e.msg);
        return;
    }
    f->tags_seen = r.pose.tags_seen;
    f->tags_used = r.pose.tags_used;
    f->rms_px = r.pose.valid ? r.pose.rms_px : -1;
    if (r.pose.valid) {
        f->pose_valid = true;
        *last_pose = r.has_filtered ? r.filtered : r.pose.world_from_camera;
        *last_cov = r.pose;
    }
}

static void *tracker(void *arg) {
    mr_capture *c = arg;
    mr_tracker *trk = NULL;
    if (c->p.markers) {
        /* Intrinsics follow the frame size actually delivered (a camera may
         * not honour the requested size): the tracker rescales them. */
        mr_tracker_params tp = MR_TRACKER_DEFAULTS;
        tp.camera = c->p.camera;
        tp.markers = c->p.markers;
        mr_error err = {0};
        trk = mr_tracker_create(&tp, &err);
        if (!trk) mr_log(MR_LOG_ERROR, "view: %s", err.msg);
    }
    bool have_pose = false, was_frozen = false;
    mr_dmat4 last_pose = mr_m4_identity();
    /* The covariance that goes with last_pose (only cov and corner_sigma_px
     * are used): the raw solve's, taken for the filtered pose it was
     * filtered from (the filter moves the pose by far less than its σ). */
    mr_pose last_cov;
    memset(&last_cov, 0, sizeof last_cov);
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
        mr_capture_frame f;
        memset(&f, 0, sizeof f);
        f.timestamp = t;
        f.index = index;
        f.count = c->seekable ? c->rp_count : -1;
        f.tags_seen = -1;
        f.rms_px = -1;
        if (trk && frozen != was_frozen) mr_tracker_freeze(trk, frozen);
        was_frozen = frozen;
        const mr_replay_frame *rf = c->seekable ? mr_replay_frame_at(c->rp, index) : NULL;
        if (c->p.fixed_pose) {
            f.pose_valid = true;
            last_pose = *c->p.fixed_pose;
            last_cov.corner_sigma_px = 0; /* a given pose: no uncertainty known */
        } else if (rf && !c->p.retrack && rf->has_pose) {
            /* A recording's own poses: the replay shows what was seen. */
            f.pose_valid = true;
            last_pose = rf->pose;
            f.tags_seen = rf->tags_seen;
            f.rms_px = rf->rms_px;
            last_cov.corner_sigma_px = rf->corner_sigma_px;
            memcpy(last_cov.cov, rf->cov, sizeof last_cov.cov);
        } else if (trk && rf) {
            /* A recording retracked: the tracker reads the JPEG's luma (the
             * Y plane, what `track` and the bench read), not grey from the
             * RGB decode on screen. */
            mr_image luma = {0};
            mr_error le = {0};
            bool have_luma = mr_replay_load_image(c->rp, index, true, &luma, &le);
            track_frame(trk, have_luma ? &luma : &work, t, &f, &last_pose, &last_cov);
            mr_image_free(&luma);
        } else if (trk) {
            track_frame(trk, &work, t, &f, &last_pose, &last_cov);
        }
        if (f.pose_valid) have_pose = true;
        f.have_pose = have_pose;
        f.pose = last_pose;
        f.corner_sigma_px = have_pose ? last_cov.corner_sigma_px : 0;
        if (f.corner_sigma_px > 0) memcpy(f.cov, last_cov.cov, sizeof f.cov);
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
    mr_tracker_destroy(&trk);
    return NULL;
}

/* ------------------------------------------------------------- public */

mr_capture *mr_capture_start(const mr_capture_params *p, mr_error *err) {
    mr_capture *c = calloc(1, sizeof *c);
    if (!c) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    c->p = *p;
    if (!(c->p.retry_s > 0)) c->p.retry_s = 1.0;
    c->rate = 1.0;
    c->cur = -1;
    c->seek_req = -1;
    c->playing = !p->start_paused;
    pthread_mutex_init(&c->mu, NULL);
    pthread_cond_init(&c->cv, NULL);
    if (p->replay_dir) {
        c->rp = mr_replay_open(p->replay_dir, err);
        if (!c->rp) {
            mr_capture_stop(&c);
            return NULL;
        }
        c->rp_count = mr_replay_count(c->rp);
        c->seekable = true;
    } else {
        snprintf(c->input, sizeof c->input, "%s", p->input ? p->input : "");
    }
    c->tracker_started = pthread_create(&c->tracker, NULL, tracker, c) == 0;
    c->reader_started = pthread_create(&c->reader, NULL, c->seekable ? replay_reader : live_reader, c) == 0;
    if (!c->tracker_started || !c->reader_started) {
        mr_capture_stop(&c);
        mr_fail(err, MR_ERR_NOMEM, "cannot start the capture threads");
        return NULL;
    }
    return c;
}

void mr_capture_stop(mr_capture **cp) {
    if (!cp || !*cp) return;
    mr_capture *c = *cp;
    pthread_mutex_lock(&c->mu);
    c->stop = true;
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->mu);
    if (c->reader_started) pthread_join(c->reader, NULL);
    if (c->tracker_started) pthread_join(c->tracker, NULL);
    mr_image_free(&c->raw);
    mr_capture_frame_free(&c->out);
    mr_replay_close(&c->rp);
    pthread_mutex_destroy(&c->mu);
    pthread_cond_destroy(&c->cv);
    free(c);
    *cp = NULL;
}

bool mr_capture_latest(mr_capture *c, mr_capture_frame *f) {
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

void mr_capture_frame_free(mr_capture_frame *f) {
    if (f) mr_image_free(&f->image);
}

mr_capture_status mr_capture_state(mr_capture *c, char *msg, size_t n) {
    pthread_mutex_lock(&c->mu);
    mr_capture_status s = c->state;
    if (msg && n) snprintf(msg, n, "%s", c->msg);
    pthread_mutex_unlock(&c->mu);
    return s;
}

bool mr_capture_seekable(mr_capture *c) { return c->seekable; }

#define CONTROL(body)                    \
    do {                                 \
        pthread_mutex_lock(&c->mu);      \
        body;                            \
        pthread_cond_broadcast(&c->cv);  \
        pthread_mutex_unlock(&c->mu);    \
    } while (0)

void mr_capture_play(mr_capture *c, bool playing) {
    CONTROL({
        /* Play at the end starts over. */
        if (playing && !c->playing && c->seekable && c->cur >= c->rp_count - 1) c->seek_req = 0;
        c->playing = playing;
        c->rate_changed = true;
    });
}
bool mr_capture_playing(mr_capture *c) {
    pthread_mutex_lock(&c->mu);
    bool p = c->playing;
    pthread_mutex_unlock(&c->mu);
    return p;
}
void mr_capture_step(mr_capture *c, int delta) { CONTROL(c->step_req += delta); }
void mr_capture_seek(mr_capture *c, int64_t index) {
    CONTROL(c->seek_req = index < 0 ? 0 : c->seekable && index >= c->rp_count ? c->rp_count - 1 : index);
}
void mr_capture_rate(mr_capture *c, double rate) { CONTROL({ c->rate = rate; c->rate_changed = true; }); }
void mr_capture_freeze(mr_capture *c, bool frozen) { CONTROL({ c->frozen = frozen; c->rate_changed = true; }); }

void mr_capture_counts(mr_capture *c, int64_t *read, int64_t *tracked, int64_t *dropped, double *track_ms_sum) {
    pthread_mutex_lock(&c->mu);
    *read = c->n_read;
    *tracked = c->n_tracked;
    *dropped = c->n_dropped;
    *track_ms_sum = c->track_ms_sum;
    pthread_mutex_unlock(&c->mu);
}
