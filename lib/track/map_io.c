/* The marker map's files: the result as a marker map with its evidence
 * (σ, RMS, control residuals), and the control points file. */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool mr_map_result_markers(const mr_map_result *r, const char *family, double tag_size, mr_marker_map *out,
                           mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!r || r->tag_count < 1) return mr_fail(err, MR_ERR_INVALID, "map: no tags mapped");
    snprintf(out->family, sizeof out->family, "%s", family ? family : "tag36h11");
    out->tag_size = tag_size > 0 ? tag_size : r->tags[0].size;
    out->tags = calloc((size_t)r->tag_count, sizeof *out->tags);
    if (!out->tags) return mr_fail(err, MR_ERR_NOMEM, "map: out of memory");
    for (int i = 0; i < r->tag_count; i++) {
        out->tags[i].id = r->tags[i].id;
        out->tags[i].world_from_tag = r->tags[i].world_from_tag;
        out->tags[i].size = r->tags[i].size != out->tag_size ? r->tags[i].size : 0;
        /* A covariance that could not be computed is unknown: the tag
         * counts as exact (what the map said before it carried one). */
        bool fin = true;
        for (int k = 0; k < 36; k++) fin = fin && isfinite(r->tags[i].cov[k]);
        if (fin) memcpy(out->tags[i].cov, r->tags[i].cov, sizeof out->tags[i].cov);
    }
    out->count = r->tag_count;
    return true;
}

/* A number, or null when it is not finite (JSON has no NaN). */
static void add_num(cJSON *o, const char *key, double v) {
    if (isfinite(v))
        cJSON_AddNumberToObject(o, key, v);
    else
        cJSON_AddNullToObject(o, key);
}

static cJSON *vec_mm(const double v[3]) {
    if (!isfinite(v[0]) || !isfinite(v[1]) || !isfinite(v[2])) return cJSON_CreateNull();
    double mm[3] = {v[0] * 1e3, v[1] * 1e3, v[2] * 1e3};
    return mr_json_from_doubles(mm, 3);
}

cJSON *mr_map_result_to_json(const mr_map_result *r, const mr_marker_map *markers, const mr_map_params *params) {
    cJSON *j = mr_marker_map_to_json(markers);
    if (!j) return NULL;
    cJSON *tags = cJSON_GetObjectItemCaseSensitive(j, "tags");
    for (int i = 0; i < r->tag_count; i++) {
        cJSON *t = cJSON_GetArrayItem(tags, i);
        const mr_map_tag *m = &r->tags[i];
        cJSON_AddNumberToObject(t, "photos", m->photos);
        cJSON_AddItemToObject(t, "sigma_mm", vec_mm(m->sigma_xyz));
        add_num(t, "sigma_pos_mm", m->sigma_pos * 1e3);
        add_num(t, "sigma_deg", m->sigma_deg);
        add_num(t, "rms_px", m->rms_px);
        bool fin = true;
        for (int k = 0; k < 36; k++) fin = fin && isfinite(m->cov[k]);
        cJSON_DeleteItemFromObjectCaseSensitive(t, "covariance"); /* the marker's copy, if any */
        cJSON_AddItemToObject(t, "covariance", fin ? mr_json_from_doubles(m->cov, 36) : cJSON_CreateNull());
    }
    cJSON *mp = cJSON_AddObjectToObject(j, "map");
    add_num(mp, "rms_px", r->rms_px);
    add_num(mp, "sigma_px", r->sigma_px);
    cJSON_AddBoolToObject(mp, "adjusted", r->adjusted);
    cJSON_AddNumberToObject(mp, "photos_used", r->photos_used);
    cJSON_AddNumberToObject(mp, "photos_total", r->photos_total);
    cJSON_AddNumberToObject(mp, "observations", r->observations);
    cJSON_AddNumberToObject(mp, "iterations", r->iterations);
    if (params && params->control_count > 0) {
        cJSON_AddStringToObject(mp, "gauge", "control");
    } else {
        cJSON *g = cJSON_AddObjectToObject(mp, "gauge");
        cJSON_AddNumberToObject(g, "fixed_tag", params ? params->fix_id : 0);
    }
    cJSON *u = cJSON_AddArrayToObject(mp, "unconnected");
    for (int i = 0; i < r->unconnected_count; i++) cJSON_AddItemToArray(u, cJSON_CreateNumber(r->unconnected[i]));
    cJSON *up = cJSON_AddArrayToObject(mp, "unplaced");
    for (int i = 0; i < r->unplaced_count; i++) cJSON_AddItemToArray(up, cJSON_CreateNumber(r->unplaced[i]));
    cJSON *us = cJSON_AddArrayToObject(mp, "unsized");
    for (int i = 0; i < r->unsized_count; i++) cJSON_AddItemToArray(us, cJSON_CreateNumber(r->unsized[i]));
    if (r->refined_intrinsics) cJSON_AddItemToObject(mp, "camera", mr_camera_to_json(&r->camera));
    cJSON *cp = cJSON_AddArrayToObject(mp, "control_points");
    for (int q = 0; params && q < r->control_count && q < params->control_count; q++) {
        const mr_map_control *c = &params->controls[q];
        const mr_map_control_result *cr = &r->controls[q];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", c->name);
        cJSON_AddNumberToObject(o, "tag", c->tag_id);
        if (c->corner < 0)
            cJSON_AddStringToObject(o, "corner", "centre");
        else
            cJSON_AddNumberToObject(o, "corner", c->corner);
        cJSON_AddItemToObject(o, "residual_mm", vec_mm(cr->residual));
        cJSON_AddItemToObject(o, "loo_mm", vec_mm(cr->loo));
        add_num(o, "loo_sigma", cr->loo_sigma);
        cJSON_AddBoolToObject(o, "used", cr->used);
        cJSON_AddBoolToObject(o, "outlier", cr->outlier);
        cJSON_AddItemToArray(cp, o);
    }
    return j;
}

#define MAX_CONTROLS 10000

bool mr_map_controls_parse(const char *text, size_t size, mr_map_control **out, int *count, mr_error *err) {
    *out = NULL;
    *count = 0;
    cJSON *j = cJSON_ParseWithLength(text, size);
    if (!j) return mr_fail(err, MR_ERR_PARSE, "control points: not valid JSON");
    bool ok = false;
    mr_map_control *c = NULL;
    const cJSON *pts = cJSON_GetObjectItemCaseSensitive(j, "points");
    double def_sigma = 0.002;
    int n = cJSON_GetArraySize(pts), i = 0;
    if (!cJSON_IsObject(j) || !cJSON_IsArray(pts)) {
        mr_fail(err, MR_ERR_PARSE, "control points: expected {\"points\": [...]}");
        goto out;
    }
    if (cJSON_GetObjectItemCaseSensitive(j, "sigma") &&
        (!mr_json_number(j, "sigma", &def_sigma, true, err) || !isfinite(def_sigma) || !(def_sigma > 0))) {
        mr_fail(err, MR_ERR_INVALID, "control points: \"sigma\" must be a number > 0");
        goto out;
    }
    if (n < 1 || n > MAX_CONTROLS) {
        mr_fail(err, MR_ERR_INVALID, "control points: %d points (expected 1..%d)", n, MAX_CONTROLS);
        goto out;
    }
    c = calloc((size_t)n, sizeof *c);
    if (!c) {
        mr_fail(err, MR_ERR_NOMEM, "control points: out of memory");
        goto out;
    }
    const cJSON *p;
    cJSON_ArrayForEach(p, pts) {
        mr_map_control *q = &c[i];
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(p, "name");
        if (cJSON_IsString(name))
            snprintf(q->name, sizeof q->name, "%s", name->valuestring);
        else
            snprintf(q->name, sizeof q->name, "#%d", i + 1);
        double tag = -1, xyz[3], s = def_sigma;
        if (!cJSON_IsObject(p) || !mr_json_number(p, "tag", &tag, true, err) || !mr_json_numbers(p, "xyz", xyz, 3, err)) {
            if (!cJSON_IsObject(p)) mr_fail(err, MR_ERR_PARSE, "not an object");
            mr_error_prefix(err, "control points: %s", q->name);
            goto out;
        }
        if (!(tag >= 0 && tag <= 1e6 && tag == floor(tag))) {
            mr_fail(err, MR_ERR_INVALID, "control points: %s: tag must be a whole number >= 0", q->name);
            goto out;
        }
        if (cJSON_GetObjectItemCaseSensitive(p, "sigma") && !mr_json_number(p, "sigma", &s, true, err)) {
            mr_error_prefix(err, "control points: %s", q->name);
            goto out;
        }
        if (!isfinite(xyz[0]) || !isfinite(xyz[1]) || !isfinite(xyz[2]) || !isfinite(s) || !(s > 0)) {
            mr_fail(err, MR_ERR_INVALID, "control points: %s: xyz must be finite and sigma > 0", q->name);
            goto out;
        }
        const cJSON *corner = cJSON_GetObjectItemCaseSensitive(p, "corner");
        q->corner = -1;
        if (cJSON_IsNumber(corner)) {
            double k = corner->valuedouble;
            if (!(k >= 0 && k <= 3 && k == floor(k))) {
                mr_fail(err, MR_ERR_INVALID, "control points: %s: corner must be 0..3 or \"centre\"", q->name);
                goto out;
            }
            q->corner = (int)k;
        } else if (corner && !(cJSON_IsString(corner) && (strcmp(corner->valuestring, "centre") == 0 ||
                                                          strcmp(corner->valuestring, "center") == 0))) {
            mr_fail(err, MR_ERR_INVALID, "control points: %s: corner must be 0..3 or \"centre\"", q->name);
            goto out;
        }
        q->tag_id = (int)tag;
        q->world = mr_v3(xyz[0], xyz[1], xyz[2]);
        q->sigma = s;
        for (int k = 0; k < i; k++)
            if (strcmp(c[k].name, q->name) == 0) {
                mr_fail(err, MR_ERR_INVALID, "control points: duplicate name %s", q->name);
                goto out;
            }
        i++;
    }
    *out = c;
    *count = n;
    c = NULL;
    ok = true;
out:
    free(c);
    cJSON_Delete(j);
    return ok;
}

bool mr_map_controls_load(const char *path, mr_map_control **out, int *count, mr_error *err) {
    size_t n = 0;
    char *text = mr_file_read(path, &n, 16u << 20, err);
    if (!text) return false;
    bool ok = mr_map_controls_parse(text, n, out, count, err);
    free(text);
    if (!ok) mr_error_prefix(err, "%s", path);
    return ok;
}

void mr_map_result_report(const mr_map_result *r, const mr_map_params *params, const char *written, FILE *out) {
    for (int i = 0; i < r->unsized_count; i++)
        fprintf(stderr, "mrcheck: map: warning: tag %d has no size (--tag-sizes): not mapped\n", r->unsized[i]);
    for (int i = 0; i < r->unconnected_count; i++)
        fprintf(stderr, "mrcheck: map: warning: tag %d is not connected to the mapped part: no shared photo\n",
                r->unconnected[i]);
    for (int i = 0; i < r->unplaced_count; i++)
        fprintf(stderr, "mrcheck: map: warning: tag %d: no sighting agrees with the adjusted map: not mapped\n",
                r->unplaced[i]);
    fprintf(out, "mapped %d tags from %d of %d photos (%d sightings)%s; reprojection RMS %.3f px", r->tag_count,
           r->photos_used, r->photos_total, r->observations, r->adjusted ? "" : " by chaining (no adjustment)",
           r->rms_px);
    if (r->adjusted) fprintf(out, ", corner sigma %.3f px", r->sigma_px);
    fprintf(out, "; wrote %s\n", written);
    double worst = 0;
    int worst_id = -1;
    for (int i = 0; i < r->tag_count; i++)
        if (isfinite(r->tags[i].sigma_pos) && r->tags[i].sigma_pos > worst)
            worst = r->tags[i].sigma_pos, worst_id = r->tags[i].id;
    if (worst_id >= 0) fprintf(out, "largest tag sigma: tag %d, %.1f mm\n", worst_id, worst * 1e3);
    for (int i = 0; i < r->tag_count && mr_log_get_level() >= MR_LOG_INFO; i++)
        fprintf(out, "  tag %d: %d photos, sigma %.1f mm %.2f deg, rms %.3f px\n", r->tags[i].id, r->tags[i].photos,
               r->tags[i].sigma_pos * 1e3, r->tags[i].sigma_deg, r->tags[i].rms_px);
    for (int q = 0; q < r->control_count; q++) {
        const mr_map_control_result *c = &r->controls[q];
        fprintf(out, "control %s: residual %.1f mm", params->controls[q].name,
               1e3 * sqrt(c->residual[0] * c->residual[0] + c->residual[1] * c->residual[1] + c->residual[2] * c->residual[2]));
        if (isfinite(c->loo_sigma))
            fprintf(out, ", left out %.1f mm (%.1f sigma)",
                   1e3 * sqrt(c->loo[0] * c->loo[0] + c->loo[1] * c->loo[1] + c->loo[2] * c->loo[2]), c->loo_sigma);
        fprintf(out, "%s\n", c->outlier ? " OUTLIER: left out of the gauge" : c->used ? "" : " (tag not mapped)");
    }
}
