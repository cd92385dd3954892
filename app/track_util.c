/* Shared wiring of the tracking commands: input, tracker, line formats. */
#include "app_track.h"

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

static volatile sig_atomic_t g_interrupted = 0; /* app only: signal flag */

static void on_signal(int sig) {
    (void)sig;
    g_interrupted = 1;
}

void app_catch_signals(void) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

bool app_interrupted(void) { return g_interrupted != 0; }

static mr_source *open_input(const char *uri, const mr_source_params *sp, mr_recording **rec_info, mr_error *err) {
    if (rec_info) *rec_info = NULL;
    if (uri && mr_is_recording(uri)) {
        mr_recording *rec = mr_recording_open(uri, err);
        if (!rec) return NULL;
        if (rec_info) {
            /* A second, read-only copy for the caller's defaults. */
            *rec_info = mr_recording_open(uri, err);
            if (!*rec_info) {
                mr_recording_close(&rec);
                return NULL;
            }
        }
        return mr_recording_source(rec, sp->gray, err);
    }
    return mr_source_open(uri, sp, err);
}

mr_source *app_open_input(const char *uri, bool gray, mr_recording **rec_info, mr_error *err) {
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = gray;
    return open_input(uri, &sp, rec_info, err);
}

bool app_open_input_opts(const char *cmd, const app_opt *opts, bool gray, mr_recording **rec_info, mr_source **src,
                         mr_error *err) {
    (void)cmd;
    *src = NULL;
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = gray;
    if (app_get(opts, "size") && !app_size("size", app_get(opts, "size"), &sp.width, &sp.height)) return false;
    if (app_get(opts, "fps") && !app_double("fps", app_get(opts, "fps"), 0.1, 1000, &sp.fps)) return false;
    sp.pixel_format = app_get(opts, "pixel-format");
    *src = open_input(app_get(opts, "input"), &sp, rec_info, err);
    return true;
}

bool app_tracker_init(app_tracker *t, const char *cmd, const app_opt *opts, const mr_detector_params *dp,
                      const mr_recording *rec) {
    memset(t, 0, sizeof *t);
    mr_error err = {0};
    mr_camera cam;
    mr_marker_map loaded = {0};
    mr_tracker_params tp = MR_TRACKER_DEFAULTS;
    const char *cam_path = app_get(opts, "camera"), *mk = app_get(opts, "markers");
    if (cam_path) {
        if (!mr_camera_load(cam_path, &cam, &err)) return app_error(cmd, &err), false;
        tp.camera = &cam;
    } else if (rec) {
        tp.camera = &rec->camera;
    }
    if (mk) {
        if (!mr_marker_map_load(mk, &loaded, &err)) return app_error(cmd, &err), false;
        tp.markers = &loaded;
    } else if (rec && rec->has_markers) {
        tp.markers = &rec->markers;
    }
    const char *family = app_get(opts, "family");
    tp.detector = *dp;
    tp.detector.family = family;
    bool ok = false;
    tp.no_filter = app_flag(opts, "no-filter");
    tp.freeze_first = app_flag(opts, "freeze");
    t->tracker = mr_tracker_create(&tp, &err);
    if (!t->tracker) {
        app_error(cmd, &err);
        goto done;
    }
    t->camera = mr_tracker_camera(t->tracker);
    t->markers = mr_tracker_markers(t->tracker);
    t->has_camera = t->camera != NULL;
    t->has_markers = t->markers != NULL;
    if (t->markers && family && strcmp(family, t->markers->family) != 0)
        mr_log(MR_LOG_WARN, "--family %s differs from the marker map's %s", family, t->markers->family);
    ok = true;
done:
    mr_marker_map_free(&loaded); /* the tracker keeps its own copy */
    return ok;
}

void app_tracker_free(app_tracker *t) {
    mr_tracker_destroy(&t->tracker);
    memset(t, 0, sizeof *t);
}

cJSON *app_pose_line(int64_t frame, double t, const mr_tracker_result *r) {
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
