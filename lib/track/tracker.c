/* The one tracker: detect -> solve (previous pose by one policy) -> filter
 * (see mr_track.h for the policy and why). */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct mr_tracker {
    mr_detector *det;
    bool has_camera, has_markers;
    mr_camera camera;
    mr_marker_map markers;      /* own copy */
    mr_pose_params pose_params;
    mr_pose_filter *filter;     /* NULL with no_filter */
    bool freeze_first;
    double prev_max_age_s;      /* resolved, > 0 */
    mr_pose prev;               /* last valid raw pose */
    double prev_t;
    /* adaptive decimation (mr_track.h): on unless a decimation was given */
    bool adaptive;
    double next_dec;            /* picked from the last frame's tags; 0 = conservative */
    int since_probe;            /* frames since the last conservative one */
    int last_n;                 /* tags the last frame found */
    double corner_var;          /* learnt corner noise^2 (px^2), 0 = none yet */
    mr_pose_fusion fusion;      /* the still camera's poses */
};

static bool copy_markers(const mr_marker_map *src, mr_marker_map *dst, mr_error *err) {
    *dst = *src;
    dst->tags = NULL;
    if (src->count <= 0) return true;
    dst->tags = malloc((size_t)src->count * sizeof *dst->tags);
    if (!dst->tags) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    memcpy(dst->tags, src->tags, (size_t)src->count * sizeof *dst->tags);
    return true;
}

mr_tracker *mr_tracker_create(const mr_tracker_params *params, mr_error *err) {
    mr_tracker_params p = params ? *params : (mr_tracker_params)MR_TRACKER_DEFAULTS;
    if (!(p.prev_max_age_s >= 0) || !isfinite(p.prev_max_age_s)) {
        mr_fail(err, MR_ERR_INVALID, "tracker: prev_max_age_s must be finite and >= 0");
        return NULL;
    }
    if (p.camera && !mr_camera_validate(p.camera, err)) return NULL;
    mr_tracker *t = calloc(1, sizeof *t);
    if (!t) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    if (p.camera) {
        t->camera = *p.camera;
        t->has_camera = true;
    }
    if (p.markers) {
        if (!copy_markers(p.markers, &t->markers, err)) goto fail;
        t->has_markers = true;
    }
    mr_detector_params dp = p.detector;
    if (!dp.family && t->has_markers) dp.family = t->markers.family;
    t->adaptive = dp.decimate == 0;
    t->det = mr_detector_create(&dp, err);
    if (!t->det) goto fail;
    if (!p.no_filter) {
        t->filter = mr_pose_filter_create(&p.filter, err);
        if (!t->filter) goto fail;
    }
    t->pose_params = p.pose;
    t->freeze_first = p.freeze_first;
    /* The filter's own default gap (filter.c) when neither is given. */
    t->prev_max_age_s = p.prev_max_age_s > 0 ? p.prev_max_age_s : p.filter.max_gap_s > 0 ? p.filter.max_gap_s : 0.5;
    return t;
fail:
    mr_tracker_destroy(&t);
    return NULL;
}

void mr_tracker_destroy(mr_tracker **t) {
    if (!t || !*t) return;
    mr_detector_destroy(&(*t)->det);
    mr_pose_filter_destroy(&(*t)->filter);
    mr_marker_map_free(&(*t)->markers);
    free(*t);
    *t = NULL;
}

void mr_tracker_reset(mr_tracker *t) {
    memset(&t->prev, 0, sizeof t->prev);
    mr_pose_fusion_reset(&t->fusion);
    t->prev_t = 0;
    t->next_dec = 0;
    t->since_probe = 0;
    t->last_n = 0;
    if (t->filter) {
        mr_pose_filter_freeze(t->filter, false);
        mr_pose_filter_reset(t->filter);
    }
}

void mr_tracker_freeze(mr_tracker *t, bool frozen) {
    if (t->filter) mr_pose_filter_freeze(t->filter, frozen);
}

bool mr_tracker_frozen(const mr_tracker *t) { return t->filter && mr_pose_filter_frozen(t->filter); }

const mr_camera *mr_tracker_camera(const mr_tracker *t) { return t->has_camera ? &t->camera : NULL; }

const mr_marker_map *mr_tracker_markers(const mr_tracker *t) { return t->has_markers ? &t->markers : NULL; }

double mr_tracker_pick_decimate(double e) {
    if (!(e >= 0)) return MR_DETECTOR_DEFAULT_DECIMATE;
    return e >= 64 ? 4 : e >= 48 ? 3 : e >= 16 ? 2 : 1;
}

/* The tag size the decimation is picked by: the shortest edge (px) of the
 * second largest tag detected (of the only one, if one). Two tags keep the
 * pose multi-tag (no single tag's mirror ambiguity); smaller, further tags
 * add little to the pose and would hold the decimation down for all. */
static double pick_edge_px(const mr_detection *d, int n) {
    double first = 0, second = 0;
    for (int i = 0; i < n; i++) {
        double e = INFINITY;
        for (int k = 0; k < 4; k++)
            e = fmin(e, hypot(d[i].corners[(k + 1) % 4][0] - d[i].corners[k][0],
                              d[i].corners[(k + 1) % 4][1] - d[i].corners[k][1]));
        if (e > first) second = first, first = e;
        else if (e > second) second = e;
    }
    return n == 1 ? first : second;
}

/* The decimation for this frame, no coarser than the frame allows (the
 * detector refuses fewer than 8 decimated px a side). */
static double frame_decimate(const mr_tracker *t, const mr_image *image, bool *conservative) {
    const double cons = MR_DETECTOR_DEFAULT_DECIMATE;
    double dec = t->next_dec > 0 ? t->next_dec : cons;
    /* The probe: finer never misses what coarser finds, so only a coarse
     * pick is interrupted. */
    if (dec > cons && t->since_probe >= MR_TRACKER_PROBE_FRAMES - 1) dec = cons;
    *conservative = dec <= cons;
    double most = fmin(image->width, image->height) / 8.0;
    if (dec > most) dec = most < 1 ? 1 : floor(most);
    return dec;
}

bool mr_tracker_frame(mr_tracker *t, const mr_image *image, double timestamp, mr_tracker_result *out, mr_error *err) {
    int n = 0;
    double dec = 0;
    bool redetected = false;
    if (t->adaptive && image && image->width > 0 && image->height > 0) {
        bool cons;
        dec = frame_decimate(t, image, &cons);
        mr_detector_set_decimate(t->det, dec);
        t->since_probe = cons ? 0 : t->since_probe + 1;
    }
    const mr_detection *d = mr_detector_detect(t->det, image, &n, err);
    if (d && t->adaptive && n < 2 && n < t->last_n && dec > MR_DETECTOR_DEFAULT_DECIMATE) {
        /* A coarse decimation lost the tags of the last frame (or all but
         * one: a single tag's pose may be its mirror): look again. */
        dec = MR_DETECTOR_DEFAULT_DECIMATE;
        mr_detector_set_decimate(t->det, dec);
        d = mr_detector_detect(t->det, image, &n, err);
        redetected = true;
    }
    if (!d) {
        memset(out, 0, sizeof *out);
        out->filtered = mr_m4_identity();
        return false;
    }
    if (t->adaptive) {
        t->last_n = n;
        t->next_dec = n > 0 ? mr_tracker_pick_decimate(pick_edge_px(d, n)) : 0;
    }
    bool ok = mr_tracker_detections(t, d, n, image->width, image->height, timestamp, out, err);
    out->decimate = mr_detector_decimate(t->det);
    out->redetected = redetected;
    return ok;
}

bool mr_tracker_detections(mr_tracker *t, const mr_detection *dets, int count, int width, int height, double timestamp,
                           mr_tracker_result *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    out->filtered = mr_m4_identity();
    if (count < 0 || (count > 0 && !dets) || width <= 0 || height <= 0)
        return mr_fail(err, MR_ERR_INVALID, "tracker: bad detections or frame size");
    out->detections = dets;
    out->detection_count = count;
    out->frozen = mr_tracker_frozen(t);
    if (!t->has_camera || !t->has_markers) return true;
    out->solved = true;
    mr_camera cam = t->camera;
    if (width != cam.width || height != cam.height) {
        /* Same lens, other resolution (e.g. a camera delivering 640x480
         * for a 1280x960 calibration): scale the intrinsics. */
        cam = mr_camera_resized(&t->camera, width, height);
    }
    double age = timestamp - t->prev_t;
    const mr_pose *prev = t->prev.valid && age >= 0 && age < t->prev_max_age_s ? &t->prev : NULL;
    out->prev_used = prev != NULL;
    /* The corner noise as the frames with 3 or more tags (18 degrees of
     * freedom and up) tell it, for the frames with fewer. */
    mr_pose_params pp = t->pose_params;
    if (!(pp.corner_sigma_px > 0) && t->corner_var > 0) pp.corner_sigma_px = sqrt(t->corner_var);
    if (!mr_pose_solve(&cam, &t->markers, dets, count, prev, &pp, &out->pose, err)) return false;
    if (out->pose.valid && out->pose.tags_used >= 3 && out->pose.corner_sigma_px > 0) {
        double v = out->pose.corner_sigma_px * out->pose.corner_sigma_px;
        t->corner_var = t->corner_var > 0 ? 0.9 * t->corner_var + 0.1 * v : v;
    }
    /* A frame without a pose leaves the fusion as it was: the camera may
     * still stand where it stood. */
    if (out->pose.valid) mr_pose_fusion_add(&t->fusion, &out->pose);
    if (t->fusion.frames > 0) {
        out->fused = t->fusion.pose;
        out->fused_frames = t->fusion.frames;
    }
    if (out->pose.valid) {
        t->prev = out->pose;
        t->prev_t = timestamp;
        if (t->filter) {
            out->filter_reset = mr_pose_filter_update(t->filter, timestamp, &out->pose.world_from_camera, &out->filtered);
            if (t->freeze_first && !mr_pose_filter_frozen(t->filter)) mr_pose_filter_freeze(t->filter, true);
            out->has_filtered = true;
        }
    } else if (t->filter && mr_pose_filter_frozen(t->filter)) {
        /* Frozen: the held pose stands even when the tags are lost. */
        out->has_filtered = mr_pose_filter_last(t->filter, &out->filtered);
    }
    out->frozen = mr_tracker_frozen(t);
    return true;
}
