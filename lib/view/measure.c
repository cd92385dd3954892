/* The view's Measure: taps of one real feature in
 * several frames, each with its frame's pose and pose covariance,
 * triangulated by lib/track's mr_triangulate as soon as two taps from
 * different places exist. The distance to the plan comes back from the
 * caller (mr_viewer_measure_distance), which owns the scene. */
#include "view_internal.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

/* A toast, kept as the measurement's last message for the state snapshot. */
static void say(mr_viewer *v, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void say(mr_viewer *v, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(v->measure_msg, sizeof v->measure_msg, fmt, ap);
    va_end(ap);
    mr_viewer_toast(v, "%s", v->measure_msg);
}

bool mr_viewer_measuring(const mr_viewer *v) { return v->measure_mode; }

bool mr_viewer_measurement(const mr_viewer *v, mr_measurement *out) {
    if (!v->measure_have) return false;
    if (out) *out = v->measure;
    return true;
}

void vw_measure_toggle(mr_viewer *v, mr_view_actions *out) {
    if (!v->measure_mode) {
        v->measure_mode = true;
        v->mark_mode = false;
        v->measure_have = true;
        v->measure_solved = v->measure_judged = v->verdict_note = false;
        v->verdict_banner[0] = 0;
        memset(&v->measure, 0, sizeof v->measure);
        v->measure_msg[0] = 0;
        return;
    }
    if (v->measure_solved) {
        v->measure_mode = false;
        vw_emit(out, MR_VA_MEASURE_DONE);
        return;
    }
    vw_measure_cancel(v);
}

void vw_measure_cancel(mr_viewer *v) {
    if (!v->measure_mode) return;
    v->measure_mode = v->measure_have = v->measure_solved = false;
    say(v, "measure cancelled");
}

/* Triangulates the taps so far (the picture's camera without its
 * distortion: taps are made on the undistorted picture). */
static void solve(mr_viewer *v, const mr_camera *camera) {
    mr_measurement *m = &v->measure;
    m->has_distance = false;
    v->measure_solved = false;
    if (m->taps < 2) {
        say(v, "1 tap: now tap the same feature in a frame seen from another place");
        return;
    }
    mr_camera cam = *camera;
    memset(cam.dist, 0, sizeof cam.dist);
    mr_tap taps[MR_MEASURE_MAX_TAPS];
    for (int i = 0; i < m->taps; i++)
        taps[i] = (mr_tap){v->measure_pose[i], v->measure_has_cov[i] ? v->measure_cov[i] : NULL,
                           {m->px[i][0], m->px[i][1]}, NULL};
    mr_error err = {0};
    if (!mr_triangulate(&cam, taps, m->taps, NULL, &m->tri, &err)) {
        const char *msg = strncmp(err.msg, "triangulate: ", 13) == 0 ? err.msg + 13 : err.msg;
        say(v, "cannot measure yet: %s", msg);
        return;
    }
    v->measure_solved = true;
    say(v, "%d taps: point +/- %.1f mm (baseline %.1f deg); tap more frames, or Measure to finish",
                    m->taps, m->tri.sigma * 1e3, m->tri.angle_deg);
}

void vw_measure_tap(mr_viewer *v, const mr_viewer_frame *f, float x, float y) {
    mr_ui_rect r = f->image_rect;
    if (!f->have_image || !f->camera || !(r.w > 0 && r.h > 0) || !mr_ui_rect_contains(r, x, y)) {
        say(v, "tap the feature on the picture");
        return;
    }
    if (!f->have_frame || !f->have_pose || !f->pose_valid) {
        say(v, "no tracked pose in this frame: the tap cannot be measured");
        return;
    }
    mr_measurement *m = &v->measure;
    int i = 0;
    while (i < m->taps && m->frames[i] != f->index) i++;
    if (i == MR_MEASURE_MAX_TAPS) {
        say(v, "%d taps is the most: press Measure to finish", MR_MEASURE_MAX_TAPS);
        return;
    }
    if (i == m->taps) m->taps++;
    /* Window pixel -> camera pixel, as a mark's (the picture fills r). */
    m->frames[i] = f->index;
    m->px[i][0] = (x - r.x) * f->camera->width / r.w - 0.5;
    m->px[i][1] = (y - r.y) * f->camera->height / r.h - 0.5;
    v->measure_pose[i] = f->world_from_camera;
    v->measure_has_cov[i] = f->pose_cov && f->corner_sigma_px > 0;
    if (v->measure_has_cov[i]) memcpy(v->measure_cov[i], f->pose_cov, sizeof v->measure_cov[i]);
    solve(v, f->camera);
}

void mr_viewer_measure_distance(mr_viewer *v, mr_dvec3 planned, double dist_m, double sigma_m, const char *node,
                                const char *layer) {
    if (!v->measure_have || !v->measure_solved) return;
    mr_measurement *m = &v->measure;
    m->has_distance = isfinite(dist_m) && isfinite(sigma_m);
    m->distance_m = dist_m;
    m->distance_sigma_m = sigma_m;
    m->planned = planned;
    snprintf(m->planned_node, sizeof m->planned_node, "%s", node ? node : "");
    v->measure_judged = false;
    if (!m->has_distance) return;
    /* The verdict: the distance's 95 % interval (its sigma carries the taps'
     * noise and each frame's pose covariance) against the tolerance of the
     * part, its layer or its nominal size. */
    double p[3] = {planned.x, planned.y, planned.z};
    mr_error err = {0};
    v->measure_judged = mr_verdict_measure(v->p.tolerances, node, layer, p, -1, dist_m, sigma_m, &v->measure_verdict, &err);
    if (!v->measure_judged) {
        say(v, "measured: %.1f mm +/- %.1f mm from the plan%s%s (no verdict: %s)", dist_m * 1e3, sigma_m * 1e3,
            m->planned_node[0] ? " at " : "", m->planned_node, err.msg);
        return;
    }
    const mr_verdict *vd = &v->measure_verdict;
    say(v, "measured: %.1f mm +/- %.1f mm from the plan%s%s: %s", dist_m * 1e3, sigma_m * 1e3,
        m->planned_node[0] ? " at " : "", m->planned_node, mr_verdict_words(vd->kind));
    /* The result stays on screen while the mark is filed, in the
     * verdict's colour: the numbers a planner acts on. */
    vw_verdict_words(vd, m->planned_node, v->verdict_banner, sizeof v->verdict_banner);
    v->verdict_kind = vd->kind;
    v->verdict_until = v->now + 6.0;
    v->verdict_note = true; /* the mark's chooser opens next */
}

void vw_verdict_words(const mr_verdict *vd, const char *part, char *buf, size_t n) {
    snprintf(buf, n, "%s%s%s: %.0f mm, 95 %% %.0f..%.0f mm, limit +/-%.0f mm (%s)%s",
             vd->kind == MR_VERDICT_OUT ? "OUT OF TOLERANCE" : vd->kind == MR_VERDICT_WITHIN ? "WITHIN TOLERANCE" : "UNDECIDED",
             part && part[0] ? " " : "", part ? part : "", vd->deviation_m * 1e3, vd->lo_m * 1e3, vd->hi_m * 1e3,
             vd->tol.limit_m * 1e3, vd->tol.source,
             vd->kind == MR_VERDICT_UNDECIDED ? ": measure again, closer or from a wider baseline" : "");
}

bool mr_viewer_measure_verdict(const mr_viewer *v, mr_verdict *out) {
    if (!v->measure_have || !v->measure_judged) return false;
    if (out) *out = v->measure_verdict;
    return true;
}

void vw_measure_draw(mr_viewer *v, const mr_viewer_frame *f) {
    if (!v->measure_mode || !f->have_image || !f->camera || f->camera->width <= 0 || f->camera->height <= 0) return;
    const mr_measurement *m = &v->measure;
    mr_ui_rect r = f->image_rect;
    float s = mr_ui_mm(v->ui, 2.5f), t = fmaxf(2, mr_ui_mm(v->ui, 0.4f));
    for (int i = 0; i < m->taps; i++) {
        if (m->frames[i] != f->index) continue; /* another frame's tap is elsewhere in this picture */
        float x = r.x + (float)((m->px[i][0] + 0.5) * r.w / f->camera->width),
              y = r.y + (float)((m->px[i][1] + 0.5) * r.h / f->camera->height);
        mr_ui_draw_rect(mr_ui_list(v->ui), mr_ui_rect_make(x - s, y - t / 2, 2 * s, t), MR_UI_RGBA(60, 170, 255, 255));
        mr_ui_draw_rect(mr_ui_list(v->ui), mr_ui_rect_make(x - t / 2, y - s, t, 2 * s), MR_UI_RGBA(60, 170, 255, 255));
    }
}

void vw_measure_banner(const mr_viewer *v, char *buf, size_t n) {
    const mr_measurement *m = &v->measure;
    if (v->measure_solved)
        snprintf(buf, n, "MEASURE: %d taps, +/- %.1f mm: more frames, or Measure to finish (Esc cancels)", m->taps,
                 m->tri.sigma * 1e3);
    else
        snprintf(buf, n, "MEASURE: tap one feature in 2+ frames from different places (%d tap%s, Esc cancels)",
                 m->taps, m->taps == 1 ? "" : "s");
}

void vw_measure_state_json(const mr_viewer *v, cJSON *j) {
    cJSON_AddBoolToObject(j, "measure_mode", v->measure_mode);
    cJSON_AddStringToObject(j, "measure_message", v->measure_msg);
    if (!v->measure_have) {
        cJSON_AddNullToObject(j, "measure");
        return;
    }
    const mr_measurement *m = &v->measure;
    cJSON *o = cJSON_AddObjectToObject(j, "measure");
    cJSON_AddNumberToObject(o, "taps", m->taps);
    cJSON_AddBoolToObject(o, "solved", v->measure_solved);
    if (!v->measure_solved) return;
    double p[3] = {m->tri.point.x, m->tri.point.y, m->tri.point.z};
    cJSON_AddItemToObject(o, "point", mr_json_from_doubles(p, 3));
    cJSON_AddNumberToObject(o, "sigma_mm", m->tri.sigma * 1e3);
    cJSON_AddNumberToObject(o, "angle_deg", m->tri.angle_deg);
    if (m->has_distance) {
        cJSON_AddNumberToObject(o, "distance_mm", m->distance_m * 1e3);
        cJSON_AddNumberToObject(o, "distance_sigma_mm", m->distance_sigma_m * 1e3);
    }
    /* How many taps carried their frame's pose covariance: the
     * registration's share of the sigma (0: only the taps' noise). */
    int with_cov = 0;
    for (int i = 0; i < m->taps; i++) with_cov += v->measure_has_cov[i];
    cJSON_AddNumberToObject(o, "taps_with_pose_covariance", with_cov);
    if (v->measure_judged) cJSON_AddItemToObject(o, "verdict", mr_verdict_to_json(&v->measure_verdict));
}
