/* The last part of `mrcheck demo`: three marks at the hall's known
 * discrepancies, as a planner would place them in `mrcheck view` while
 * walking the demo's recording (a frame of it, the tracker's pose of that
 * frame with its covariance, the plan overlaid, a pick on the plan), the
 * moved part measured from several frames and judged against the
 * tolerance, then the findings as BCF 2.1 and 3.0 and as the HTML report
 * (lib/export). */
#include "bench_internal.h"
#include "mr_export.h"
#include "mr_session.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The standing viewpoint that looks most directly at target, moved to look
 * straight at it: the fallback when no close view below is clear. */
static mr_dmat4 pose_towards(mr_dvec3 target) {
    double best = -2;
    mr_dvec3 eye = mr_v3(0, 1.6, 0);
    for (int i = 0; i < mr_demo_view_count(); i++) {
        mr_view v = mr_demo_view(i);
        const double *m = v.world_from_camera.m;
        mr_dvec3 e = mr_v3(m[3], m[7], m[11]), ax = mr_v3(m[2], m[6], m[10]);
        mr_dvec3 to = mr_v3_sub(target, e);
        double d = mr_v3_len(to);
        if (d < 2) continue;
        double c = mr_v3_dot(ax, to) / d;
        if (c > best) best = c, eye = e;
    }
    return mr_m4_look_at_cv(eye, target, mr_v3(0, 1, 0));
}

/* Where a planner would stand: a few metres from the part at eye height,
 * inside the hall, with a clear line of sight on the plan (the pick at the
 * part's pixel lands on the part, or, for a hidden part, on what hides it
 * just in front). Tried on small renders, nearest first. */
static mr_dmat4 pose_for(const mr_bench_gpu *g, const mr_scene *planned, const char *node, mr_dvec3 target, bool hidden) {
    mr_camera small = mr_demo_camera();
    small = mr_camera_resized(&small, 160, 120);
    memset(small.dist, 0, sizeof small.dist);
    const double *lo = planned->bounds_min, *hi = planned->bounds_max;
    static const double dist[] = {5, 7, 9};
    for (int di = 0; di < 3; di++)
        for (int k = 0; k < 12; k++) {
            double a = k * (2 * M_PI / 12) + 0.3;
            mr_dvec3 eye = mr_v3(target.x + dist[di] * cos(a), 1.6, target.z + dist[di] * sin(a));
            if (eye.x < lo[0] + 1 || eye.x > hi[0] - 1 || eye.z < lo[2] + 1 || eye.z > hi[2] - 1) continue;
            mr_view v = {small, mr_m4_look_at_cv(eye, target, mr_v3(0, 1, 0))};
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            mr_frame_result res = {0};
            mr_pick pick = {0};
            mr_error e = {0};
            bool ok = mr_render_frame(g->renderer, &v, &fp, &res, &e) &&
                      mr_renderer_pick(g->renderer, small.cx, small.cy, &pick, &e);
            mr_frame_result_free(&res);
            if (!ok || !pick.hit || pick.node < 0 || pick.node >= planned->node_count) continue;
            double d = mr_v3_len(mr_v3_sub(target, eye));
            bool on_part = strcmp(planned->nodes[pick.node].name, node) == 0;
            if (hidden ? pick.depth < d && pick.depth > d - 1.0 : on_part) return v.world_from_camera;
        }
    return pose_towards(target);
}

/* Whether the plan, seen from view, shows the part at target's pixel (or,
 * for a hidden part, what hides it just in front): a pick on a small render. */
static bool clear_view(const mr_bench_gpu *g, const mr_scene *planned, const char *node, const mr_view *view,
                       mr_dvec3 target, bool hidden) {
    mr_view v = *view;
    v.camera = mr_camera_resized(&view->camera, 160, 120);
    memset(v.camera.dist, 0, sizeof v.camera.dist);
    mr_dmat4 cw = mr_m4_invert_rigid(&v.world_from_camera);
    mr_dvec3 pc = mr_m4_point(&cw, target);
    if (!(pc.z > 0.5)) return false;
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    mr_frame_result res = {0};
    mr_pick pick = {0};
    mr_error e = {0};
    bool ok = mr_render_frame(g->renderer, &v, &fp, &res, &e) &&
              mr_renderer_pick(g->renderer, v.camera.fx * pc.x / pc.z + v.camera.cx, v.camera.fy * pc.y / pc.z + v.camera.cy,
                               &pick, &e);
    mr_frame_result_free(&res);
    if (!ok || !pick.hit || pick.node < 0 || pick.node >= planned->node_count) return false;
    double d = mr_v3_len(mr_v3_sub(target, mr_v3(v.world_from_camera.m[3], v.world_from_camera.m[7], v.world_from_camera.m[11])));
    return hidden ? pick.depth < d && pick.depth > d - 1.0 : strcmp(planned->nodes[pick.node].name, node) == 0;
}

/* The recording's frame to mark target on: a tracked pose with its
 * covariance from at least two tags, target well inside the image and
 * within 12 m, a clear view of the part on the plan; of those the one with
 * the smallest registration sigma at target (mr_pose_point_sigma). -1: none. */
#define MARK_CANDIDATES 8
static int pick_frame(const mr_recording *rec, const mr_bench_gpu *g, const mr_scene *planned, const char *node,
                      mr_dvec3 target, bool hidden, double *sigma_out) {
    int cand[MARK_CANDIDATES];
    double cs[MARK_CANDIDATES];
    int nc = 0;
    for (int i = 0; i < rec->frame_count; i++) {
        const mr_pose *p = &rec->frames[i].pose;
        if (!p->valid || p->tags_used < 2 || !(p->corner_sigma_px > 0)) continue;
        mr_camera cam = rec->camera;
        mr_dmat4 cw = mr_m4_invert_rigid(&p->world_from_camera);
        mr_dvec3 pc = mr_m4_point(&cw, target);
        if (!(pc.z > 0.5) || mr_v3_len(pc) > 12) continue;
        double u = cam.fx * pc.x / pc.z + cam.cx, v = cam.fy * pc.y / pc.z + cam.cy;
        if (u < 0.15 * cam.width || u > 0.85 * cam.width || v < 0.15 * cam.height || v > 0.85 * cam.height) continue;
        double sigma = 0;
        if (!mr_pose_point_sigma(p, target, &sigma, NULL) || !isfinite(sigma)) continue;
        /* keep the MARK_CANDIDATES smallest, sorted */
        int k = nc < MARK_CANDIDATES ? nc++ : MARK_CANDIDATES - 1;
        if (k == MARK_CANDIDATES - 1 && nc == MARK_CANDIDATES && sigma >= cs[k]) continue;
        while (k > 0 && cs[k - 1] > sigma) {
            cand[k] = cand[k - 1];
            cs[k] = cs[k - 1];
            k--;
        }
        cand[k] = i;
        cs[k] = sigma;
    }
    for (int k = 0; k < nc; k++) {
        mr_view v = {rec->camera, rec->frames[cand[k]].pose.world_from_camera};
        if (clear_view(g, planned, node, &v, target, hidden)) {
            *sigma_out = cs[k];
            return cand[k];
        }
    }
    return -1;
}

static void print_measured(const mr_demo_measured *d) {
    char line[320];
    mr_verdict_format(&d->verdict, line, sizeof line);
    printf("    measured from %d frames (baseline %.0f deg): %.0f mm +/- %.0f mm from the plan (known: %.0f mm)\n"
           "    verdict: %s\n", d->m.taps, d->m.tri.angle_deg, d->m.distance_m * 1e3, d->m.distance_sigma_m * 1e3,
           d->truth_m * 1e3, line);
}

static bool one_mark(const char *session, int i, const cJSON *d, const mr_bench_gpu *g, const mr_scene *built,
                     const mr_scene *planned, const mr_recording *rec, mr_error *err) {
    const cJSON *desc = cJSON_GetObjectItemCaseSensitive(d, "description");
    const cJSON *node = cJSON_GetObjectItemCaseSensitive(d, "node");
    const cJSON *kind = cJSON_GetObjectItemCaseSensitive(d, "kind");
    double at[3], delta[3] = {0, 0, 0};
    bool has_delta = mr_json_numbers(d, "delta", delta, 3, NULL);
    if (!mr_json_numbers(d, "built_position", at, 3, NULL) && !mr_json_numbers(d, "planned_position", at, 3, err))
        return false;
    /* Floor-standing parts are listed at their foot: aim at their middle. */
    if (fabs(at[1]) < 1e-9) at[1] = 1.0;
    mr_dvec3 target = mr_v3(at[0], at[1], at[2]);
    mr_camera cam = mr_demo_camera();
    const char *node_name = cJSON_IsString(node) ? node->valuestring : "";
    int32_t ni = -1;
    for (int32_t n = 0; n < planned->node_count && ni < 0; n++)
        if (strcmp(planned->nodes[n].name, node_name) == 0) ni = n;
    bool hidden = ni >= 0 && planned->nodes[ni].layer == MR_LAYER_HIDDEN;
    if (!mr_renderer_set_scene(g->renderer, planned, err)) return false;
    /* A frame of the recording, with the tracker's pose and its sigma. */
    double sigma = -1;
    int fi = rec ? pick_frame(rec, g, planned, node_name, target, hidden, &sigma) : -1;
    mr_view view = {cam, mr_m4_identity()};
    mr_frame_result res = {0};
    mr_image frame = {0};
    bool ok = true;
    const mr_pose *tracked = fi >= 0 ? &rec->frames[fi].pose : NULL;
    if (tracked) {
        cam = rec->camera;
        view.camera = cam;
        view.world_from_camera = tracked->world_from_camera;
        ok = mr_recording_load_image(rec, fi, false, &frame, err);
    } else {
        /* No frame of the recording sees it well: a rendered camera frame
         * of the as-built hall (lens, blur, noise) from where a planner
         * would stand, its pose known, not tracked (no uncertainty). */
        view.world_from_camera = pose_for(g, planned, node_name, target, hidden);
        const int margin = 48, scale = 2;
        mr_view wide = view;
        wide.camera = mr_demo_wide_camera(&cam, margin);
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.width = wide.camera.width * scale;
        fp.height = wide.camera.height * scale;
        mr_rng rng;
        mr_rng_seed(&rng, 2000u + (uint64_t)i);
        ok = mr_renderer_set_scene(g->renderer, built, err) && mr_render_frame(g->renderer, &wide, &fp, &res, err) &&
             mr_demo_camera_frame(&cam, &res.color, 1, margin, scale, 1.0, 2.5, &rng, &frame, err);
    }
    mr_frame_result_free(&res);
    /* A part that was built elsewhere is measured, as the planner would
     * with Measure: its edge tapped in several frames. A missing part has
     * nothing to measure, a hidden one is not in the pictures. */
    mr_demo_measured meas;
    bool measured = false;
    if (ok && tracked && has_delta && !hidden && cJSON_IsString(node)) {
        mr_error me = {0};
        measured = mr_demo_measure(rec, g, built, node->valuestring, mr_v3(delta[0], delta[1], delta[2]),
                                   3000u + (uint64_t)i, &meas, &me);
        if (!measured) mr_log(MR_LOG_WARN, "demo: mark %d not measured: %s", i + 1, me.msg);
        ok = mr_renderer_set_scene(g->renderer, planned, err);
    }
    /* The check: the plan over the frame, and the pick on the plan. */
    mr_frame_params op = MR_FRAME_DEFAULTS;
    op.video = &frame; /* at MR_FRAME_DEFAULT_ALPHA */
    op.ghost.mode = MR_GHOST_ADAPTIVE;
    ok = ok && mr_renderer_set_scene(g->renderer, planned, err) && mr_render_frame(g->renderer, &view, &op, &res, err);
    mr_dmat4 cw = mr_m4_invert_rigid(&view.world_from_camera);
    mr_dvec3 pc = mr_m4_point(&cw, target);
    double px = cam.fx * pc.x / pc.z + cam.cx, py = cam.fy * pc.y / pc.z + cam.cy;
    mr_pick pick = {0};
    ok = ok && mr_renderer_pick(g->renderer, px, py, &pick, err);
    /* The sigma where the pick landed, as the view shows it there. */
    double s_hit = 0;
    if (ok && tracked && pick.hit && mr_pose_point_sigma(tracked, pick.world, &s_hit, NULL) && isfinite(s_hit))
        sigma = s_hit;
    mr_annotation m;
    memset(&m, 0, sizeof m);
    snprintf(m.type, sizeof m.type, "discrepancy");
    m.time_unix = 1764619200.0 + 60.0 * i; /* fixed: the demo's output is the same every run */
    m.frame_index = tracked ? rec->frames[fi].index : i;
    m.timestamp = tracked ? rec->frames[fi].t : 0;
    snprintf(m.note, sizeof m.note, "%s", cJSON_IsString(desc) ? desc->valuestring : "discrepancy");
    /* The discrepancy's kind as a mark's category (a height is a move up;
     * the control measurement is "other"). */
    const char *k = cJSON_IsString(kind) ? kind->valuestring : "";
    bool move = strcmp(k, "moved") == 0 || strcmp(k, "height") == 0;
    snprintf(m.category, sizeof m.category, "%s", move ? "moved" : strcmp(k, "missing") == 0 || strcmp(k, "extra") == 0 ? k
                                                  : "other");
    m.has_pixel = true;
    m.pixel[0] = px, m.pixel[1] = py;
    m.hit = pick.hit;
    m.world[0] = pick.world.x, m.world[1] = pick.world.y, m.world[2] = pick.world.z;
    m.depth = pick.depth;
    m.node_index = -1;
    if (pick.node >= 0 && pick.node < planned->node_count) {
        m.node_index = pick.node;
        snprintf(m.node, sizeof m.node, "%s", planned->nodes[pick.node].name);
        snprintf(m.layer, sizeof m.layer, "%s", pick.layer == MR_LAYER_HIDDEN ? "hidden" : "visible");
        mr_element_words ew = mr_scene_element_words(planned, pick.node);
        snprintf(m.element_guid, sizeof m.element_guid, "%s", ew.guid);
        snprintf(m.element_class, sizeof m.element_class, "%s", ew.ifc_class);
        snprintf(m.element_name, sizeof m.element_name, "%s", ew.name);
    }
    m.has_pose = m.pose_valid = true;
    m.world_from_camera = view.world_from_camera;
    m.pose_tags_seen = tracked ? tracked->tags_seen : -1;
    m.pose_rms_px = tracked ? tracked->rms_px : -1;
    m.has_measurement = m.has_verdict = measured;
    if (measured) m.measurement = meas.m, m.verdict = meas.verdict;
    /* Titled by the part the discrepancy is about (a hidden part's pick
     * lands on what hides it). */
    mr_annotation about = m;
    if (node_name[0]) snprintf(about.node, sizeof about.node, "%s", node_name);
    mr_mark_title(&about, m.title, sizeof m.title);
    char stem[32];
    snprintf(stem, sizeof stem, "mark_%04d", i + 1);
    mr_mark_files fl = {.stem = stem, .frame = &frame, .screen = &res.color, .camera = &cam,
                        /* the known displacement, where nothing measured it */
                        .distance_m = has_delta && !measured ? mr_v3_len(mr_v3(delta[0], delta[1], delta[2])) : -1,
                        .uncertainty_m = tracked ? sigma : -1};
    ok = ok && mr_export_mark_write(session, &m, &fl, err);
    if (ok && tracked)
        printf("  mark %d at (%.2f, %.2f, %.2f) on %s, recording frame %lld, +/- %.0f mm: %s\n", i + 1, target.x,
               target.y, target.z, cJSON_IsString(node) ? node->valuestring : "?", (long long)m.frame_index, sigma * 1e3,
               m.note);
    else if (ok)
        printf("  mark %d at (%.2f, %.2f, %.2f) on %s (no recorded frame sees it: a rendered view): %s\n", i + 1,
               target.x, target.y, target.z, cJSON_IsString(node) ? node->valuestring : "?", m.note);
    if (ok && measured) print_measured(&meas);
    mr_frame_result_free(&res);
    mr_image_free(&frame);
    return ok;
}

bool mr_demo_marks(const char *dir, const mr_bench_gpu *g, const mr_scene *built, const mr_scene *planned, mr_error *err) {
    char path[4096], session[4096];
    mr_path_join(dir, "discrepancies.json", path, sizeof path);
    cJSON *list = mr_json_load(path, err);
    if (!list) return false;
    /* The demo's own recording (written before the marks), if it is there. */
    mr_path_join(dir, "recording", path, sizeof path);
    mr_error re = {0};
    mr_recording *rec = mr_is_recording(path) ? mr_recording_open(path, &re) : NULL;
    if (!rec && re.code) mr_log(MR_LOG_WARN, "demo: %s: %s (marks on rendered views)", path, re.msg);
    mr_path_join(dir, "session", session, sizeof session);
    /* The demo rebuilds its session: an earlier run's marks would add up. */
    mr_path_join(session, "annotations.jsonl", path, sizeof path);
    remove(path);
    bool ok = mr_mkdirs(session, err);
    printf("marks at the known discrepancies (%s/session/):\n", dir);
    int nd = cJSON_GetArraySize(list);
    for (int i = 0; ok && i < nd; i++)
        ok = one_mark(session, i, cJSON_GetArrayItem(list, i), g, built, planned, rec, err);
    /* A control: an unchanged column measured the same way, so that the
     * findings show what "within tolerance" looks like next to the rest. */
    const char *col = rec ? mr_demo_control_part(rec, built, planned) : NULL;
    int32_t ci = -1;
    for (int32_t n = 0; col && n < planned->node_count && ci < 0; n++)
        if (strcmp(planned->nodes[n].name, col) == 0) ci = n;
    double lo[3], hi[3];
    if (ok && ci >= 0 && mr_scene_node_bounds(planned, ci, lo, hi)) {
        char words[160];
        snprintf(words, sizeof words, "control: %s stands where it was planned", col);
        double at[3] = {0.5 * (lo[0] + hi[0]), fmin(lo[1] + 0.75 * (hi[1] - lo[1]), lo[1] + 1.5), 0.5 * (lo[2] + hi[2])},
               zero[3] = {0, 0, 0};
        cJSON *c = cJSON_CreateObject();
        cJSON_AddStringToObject(c, "kind", "control");
        cJSON_AddStringToObject(c, "node", col);
        cJSON_AddStringToObject(c, "description", words);
        cJSON_AddItemToObject(c, "built_position", mr_json_from_doubles(at, 3));
        cJSON_AddItemToObject(c, "delta", mr_json_from_doubles(zero, 3));
        ok = one_mark(session, nd, c, g, built, planned, rec, err);
        cJSON_Delete(c);
    }
    cJSON_Delete(list);
    mr_recording_close(&rec);
    mr_export_params p = MR_EXPORT_DEFAULTS;
    p.scene = planned;
    p.title = "mrcheck demo: the hall as built against the plan";
    mr_path_join(dir, "findings.bcf", path, sizeof path);
    ok = ok && mr_export_bcf(session, path, &p, err);
    p.bcf_version = MR_BCF_3_0;
    mr_path_join(dir, "findings-3.0.bcf", path, sizeof path);
    ok = ok && mr_export_bcf(session, path, &p, err);
    mr_path_join(dir, "report", path, sizeof path);
    ok = ok && mr_export_report(session, path, &p, err);
    if (ok) {
        printf("  BCF (open in BIMcollab, Solibri, xeokit, ...): %s/findings.bcf (2.1), %s/findings-3.0.bcf\n", dir,
               dir);
        printf("  report:                        %s/report/index.html\n", dir);
    }
    return ok;
}
