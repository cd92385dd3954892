/* `mrcheck measure`: a real feature tapped in several frames of a
 * recording, triangulated (lib/track's mr_triangulate) and compared with the
 * plan: the planned point and the planned surface's nearest point. */
#include "mr_batch.h"
#include "mr_eval.h"

#include <math.h>

typedef struct measured {
    mr_triangulation tr;
    int taps;
    bool has_planned;
    double planned[3], dist, dsig;   /* to the planned point, m */
    mr_verdict v;
    mr_nearest_hit nh;               /* the planned surface's nearest point */
    double nsig;
    const char *node;
    mr_verdict sv;
} measured;

static cJSON *measured_json(const measured *m) {
    cJSON *r = cJSON_CreateObject();
    double pt[3] = {m->tr.point.x, m->tr.point.y, m->tr.point.z};
    cJSON_AddItemToObject(r, "point", mr_json_from_doubles(pt, 3));
    cJSON_AddItemToObject(r, "covariance", mr_json_from_doubles(m->tr.cov, 9));
    cJSON_AddNumberToObject(r, "sigma_mm", m->tr.sigma * 1e3);
    cJSON_AddNumberToObject(r, "angle_deg", m->tr.angle_deg);
    cJSON_AddNumberToObject(r, "rms_px", m->tr.rms_px);
    cJSON_AddNumberToObject(r, "taps", m->taps);
    if (m->has_planned) {
        cJSON_AddItemToObject(r, "planned", mr_json_from_doubles(m->planned, 3));
        cJSON_AddNumberToObject(r, "distance_mm", m->dist * 1e3);
        cJSON_AddNumberToObject(r, "distance_sigma_mm", m->dsig * 1e3);
        cJSON_AddItemToObject(r, "verdict", mr_verdict_to_json(&m->v));
    }
    if (m->nh.found) {
        double np[3] = {m->nh.point.x, m->nh.point.y, m->nh.point.z};
        cJSON_AddItemToObject(r, "nearest_planned", mr_json_from_doubles(np, 3));
        cJSON_AddStringToObject(r, "nearest_node", m->node ? m->node : "");
        cJSON_AddNumberToObject(r, "surface_distance_mm", m->nh.distance * 1e3);
        cJSON_AddNumberToObject(r, "surface_distance_sigma_mm", m->nsig * 1e3);
        cJSON_AddItemToObject(r, "surface_verdict", mr_verdict_to_json(&m->sv));
    }
    return r;
}

/* The distance to the planned surface (exact, lib/eval) and its verdict. */
static bool measure_surface(const mr_batch_measure_params *p, const mr_tolerances *tol, const mr_scene *scene,
                            mr_eval_nearest *near, measured *m, mr_error *err) {
    char line[320];
    if (!mr_eval_nearest_point(near, m->tr.point, &m->nh))
        return mr_fail(err, MR_ERR_INVALID, "the scene has no surface to measure against");
    m->nsig = mr_eval_nearest_sigma(&m->nh, m->tr.cov);
    const mr_node *sn = m->nh.node >= 0 ? &scene->nodes[m->nh.node] : NULL;
    m->node = sn ? sn->name : NULL;
    fprintf(p->out, "distance to the planned surface: %.1f mm +- %.1f mm (1 sigma), nearest point %.4f %.4f %.4f on %s\n",
            m->nh.distance * 1e3, m->nsig * 1e3, m->nh.point.x, m->nh.point.y, m->nh.point.z, sn ? sn->name : "?");
    double np[3] = {m->nh.point.x, m->nh.point.y, m->nh.point.z};
    if (!mr_verdict_measure(tol, sn ? sn->name : p->part, sn && sn->layer == MR_LAYER_HIDDEN ? "hidden" : "visible", np,
                            p->nominal, m->nh.distance, m->nsig, &m->sv, err))
        return false;
    mr_verdict_format(&m->sv, line, sizeof line);
    fprintf(p->out, "verdict (surface): %s\n", line);
    return true;
}

static bool measure_run(const mr_batch_measure_params *p, const mr_tolerances *tol, const mr_recording *rec,
                        const mr_observations *o, const mr_scene *scene, mr_eval_nearest *near, mr_error *err) {
    measured m = {.taps = o->count, .has_planned = o->has_planned, .dist = NAN, .dsig = NAN, .nsig = NAN};
    char line[320];
    if (!mr_triangulate(&rec->camera, o->taps, o->count, &p->triangulate, &m.tr, err)) return false;
    /* After the solve, so that a refusal stays one line. */
    if (o->no_cov)
        fprintf(stderr, "mrcheck: measure: warning: %d frame(s) carry no pose covariance (an older recording): "
                        "only the taps' noise is counted there\n", o->no_cov);
    fprintf(p->out, "point %.4f %.4f %.4f  sigma %.1f mm  from %d taps, baseline angle %.1f deg, tap RMS %.2f px\n",
            m.tr.point.x, m.tr.point.y, m.tr.point.z, m.tr.sigma * 1e3, o->count, m.tr.angle_deg, m.tr.rms_px);
    if (m.has_planned) {
        for (int i = 0; i < 3; i++) m.planned[i] = o->planned[i];
        mr_triangulation_distance(&m.tr, mr_v3(m.planned[0], m.planned[1], m.planned[2]), &m.dist, &m.dsig);
        fprintf(p->out, "distance to the planned point: %.1f mm +- %.1f mm (1 sigma)\n", m.dist * 1e3, m.dsig * 1e3);
        if (!mr_verdict_measure(tol, p->part, NULL, m.planned, p->nominal, m.dist, m.dsig, &m.v, err)) return false;
        mr_verdict_format(&m.v, line, sizeof line);
        fprintf(p->out, "verdict: %s\n", line);
    }
    if (near && !measure_surface(p, tol, scene, near, &m, err)) return false;
    if (!p->out_json) return true;
    cJSON *r = measured_json(&m);
    bool ok = mr_json_save(p->out_json, r, err);
    cJSON_Delete(r);
    return ok;
}

bool mr_batch_measure(const mr_batch_measure_params *p, mr_error *err) {
    mr_tolerances tols = MR_TOLERANCES_DEFAULTS;
    if (p->tolerances && !mr_tolerances_load(p->tolerances, &tols, err)) return false;
    mr_recording *rec = mr_recording_open(p->recording, err);
    mr_scene *scene = NULL;
    mr_eval_nearest *near = NULL;
    mr_observations o;
    bool ok = rec && mr_observations_load(p->observations, rec, &o, err);
    if (ok && p->scene) {
        scene = mr_scene_load(p->scene, NULL, err);
        ok = scene && (near = mr_eval_nearest_create(scene, false, err)) != NULL;
    }
    ok = ok && measure_run(p, p->tolerances ? &tols : NULL, rec, &o, scene, near, err);
    mr_eval_nearest_destroy(&near);
    mr_scene_destroy(&scene);
    mr_recording_close(&rec);
    return ok;
}
