/* annotations.jsonl: durable append and a tolerant reader (mr_session.h). */
#include "session_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

bool mr_annotation_append(const char *path, const cJSON *obj, mr_error *err) {
    size_t n = 0;
    char *line = mr_sess_json_line(obj, &n);
    if (!line) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    bool existed = mr_file_exists(path);
    int fd = open(path, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
        int e = errno;
        free(line);
        return mr_fail(err, MR_ERR_IO, "cannot open %s: %s", path, strerror(e));
    }
    /* One write: with O_APPEND the line lands whole at the end. */
    bool sync_failed;
    int e = mr_sess_write_line(fd, line, n, &sync_failed);
    free(line);
    close(fd);
    if (e) return mr_fail(err, MR_ERR_IO, "cannot append to %s: %s", path, strerror(e));
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

/* A string field into buf; absent is fine, a non-string or too long is not. */
static bool get_str(const cJSON *o, const char *key, char *buf, size_t n, bool required) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!v || cJSON_IsNull(v)) return !required;
    if (!cJSON_IsString(v) || strlen(v->valuestring) >= n) return false;
    snprintf(buf, n, "%s", v->valuestring);
    return true;
}

/* A finite number; absent is fine. */
static bool get_num(const cJSON *o, const char *key, double *out) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!v) return true;
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) return false;
    *out = v->valuedouble;
    return true;
}

/* An array of exactly n finite numbers; absent or null: *has false. */
static bool get_vec(const cJSON *o, const char *key, double *out, int n, bool *has) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    *has = false;
    if (!v || cJSON_IsNull(v)) return true;
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n) return false;
    for (int i = 0; i < n; i++) {
        const cJSON *x = cJSON_GetArrayItem(v, i);
        if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble)) return false;
        out[i] = x->valuedouble;
    }
    *has = true;
    return true;
}

/* The view's Measure, flat measured_* fields of the mark. */
static void measurement_json(cJSON *line, const mr_measurement *m) {
    const mr_triangulation *t = &m->tri;
    double pt[3] = {t->point.x, t->point.y, t->point.z};
    cJSON_AddItemToObject(line, "measured_point", mr_json_from_doubles(pt, 3));
    cJSON_AddItemToObject(line, "measured_covariance", mr_json_from_doubles(t->cov, 9));
    cJSON_AddNumberToObject(line, "measured_point_sigma_m", t->sigma);
    cJSON_AddNumberToObject(line, "measured_angle_deg", t->angle_deg);
    cJSON_AddNumberToObject(line, "measured_rms_px", t->rms_px);
    int n = m->taps < 0 ? 0 : m->taps > MR_MEASURE_MAX_TAPS ? MR_MEASURE_MAX_TAPS : m->taps;
    cJSON *fr = cJSON_AddArrayToObject(line, "measured_frames"), *px = cJSON_AddArrayToObject(line, "measured_pixels");
    for (int i = 0; i < n; i++) {
        cJSON_AddItemToArray(fr, cJSON_CreateNumber((double)m->frames[i]));
        cJSON_AddItemToArray(px, mr_json_from_doubles(m->px[i], 2));
    }
    if (!m->has_distance) return;
    double pl[3] = {m->planned.x, m->planned.y, m->planned.z};
    cJSON_AddNumberToObject(line, "measured_distance_m", m->distance_m);
    cJSON_AddNumberToObject(line, "measured_sigma_m", m->distance_sigma_m);
    cJSON_AddItemToObject(line, "measured_planned", mr_json_from_doubles(pl, 3));
    cJSON_AddStringToObject(line, "measured_planned_node", m->planned_node);
}

static bool parse_measurement(const cJSON *o, mr_annotation *a) {
    mr_measurement *m = &a->measurement;
    double pt[3], pl[3];
    bool has = false, hp = false, hc = false;
    if (!get_vec(o, "measured_point", pt, 3, &has)) return false;
    if (!has) return true; /* no measurement: the other measured_* fields are ignored */
    a->has_measurement = true;
    m->tri.point = mr_v3(pt[0], pt[1], pt[2]);
    m->tri.sigma = m->tri.angle_deg = m->tri.rms_px = NAN;
    if (!get_vec(o, "measured_covariance", m->tri.cov, 9, &hc) || !get_num(o, "measured_point_sigma_m", &m->tri.sigma) ||
        !get_num(o, "measured_angle_deg", &m->tri.angle_deg) || !get_num(o, "measured_rms_px", &m->tri.rms_px))
        return false;
    if (!hc) return false; /* a point without its covariance is no measurement */
    const cJSON *fr = cJSON_GetObjectItemCaseSensitive(o, "measured_frames"),
                *px = cJSON_GetObjectItemCaseSensitive(o, "measured_pixels");
    if (fr || px) {
        if (!cJSON_IsArray(fr) || !cJSON_IsArray(px) || cJSON_GetArraySize(fr) != cJSON_GetArraySize(px) ||
            cJSON_GetArraySize(fr) > MR_MEASURE_MAX_TAPS)
            return false;
        m->taps = cJSON_GetArraySize(fr);
        for (int i = 0; i < m->taps; i++) {
            const cJSON *f = cJSON_GetArrayItem(fr, i), *p = cJSON_GetArrayItem(px, i);
            if (!cJSON_IsNumber(f) || !(f->valuedouble >= 0 && f->valuedouble < 1e15 && f->valuedouble == floor(f->valuedouble)) ||
                !cJSON_IsArray(p) || cJSON_GetArraySize(p) != 2)
                return false;
            m->frames[i] = (int64_t)f->valuedouble;
            for (int k = 0; k < 2; k++) {
                const cJSON *x = cJSON_GetArrayItem(p, k);
                if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble)) return false;
                m->px[i][k] = x->valuedouble;
            }
        }
    }
    double d = NAN, ds = NAN;
    if (!get_num(o, "measured_distance_m", &d) || !get_num(o, "measured_sigma_m", &ds) ||
        !get_vec(o, "measured_planned", pl, 3, &hp) ||
        !get_str(o, "measured_planned_node", m->planned_node, sizeof m->planned_node, false))
        return false;
    if (isfinite(d)) {
        if (!(d >= 0) || !(ds >= 0) || !hp) return false;
        m->has_distance = true;
        m->distance_m = d;
        m->distance_sigma_m = ds;
        m->planned = mr_v3(pl[0], pl[1], pl[2]);
    }
    return true;
}

cJSON *mr_annotation_to_json(const mr_annotation *a) {
    cJSON *line = cJSON_CreateObject();
    if (!line) return NULL;
    cJSON_AddStringToObject(line, "type", a->type);
    cJSON_AddNumberToObject(line, "time_unix", a->time_unix);
    cJSON_AddNumberToObject(line, "frame_index", (double)a->frame_index);
    cJSON_AddNumberToObject(line, "timestamp", a->timestamp);
    if (a->id[0]) cJSON_AddStringToObject(line, "id", a->id);
    if (a->revision > 0) cJSON_AddNumberToObject(line, "revision", a->revision);
    if (a->category[0]) cJSON_AddStringToObject(line, "category", a->category);
    cJSON_AddStringToObject(line, "note", a->note);
    if (a->title[0]) cJSON_AddStringToObject(line, "title", a->title);
    if (a->status[0]) cJSON_AddStringToObject(line, "status", a->status);
    if (a->priority[0]) cJSON_AddStringToObject(line, "priority", a->priority);
    if (a->assignee[0]) cJSON_AddStringToObject(line, "assignee", a->assignee);
    if (a->label_count > 0) {
        cJSON *l = cJSON_AddArrayToObject(line, "labels");
        for (int i = 0; i < a->label_count && i < MR_MARK_MAX_LABELS; i++)
            cJSON_AddItemToArray(l, cJSON_CreateString(a->labels[i]));
    }
    cJSON_AddItemToObject(line, "pixel", mr_json_from_doubles(a->pixel, 2));
    cJSON_AddBoolToObject(line, "hit", a->hit);
    if (a->hit) {
        cJSON_AddItemToObject(line, "world", mr_json_from_doubles(a->world, 3));
        cJSON_AddNumberToObject(line, "depth", a->depth);
    } else {
        cJSON_AddNullToObject(line, "world");
    }
    if (a->node_index >= 0) {
        cJSON_AddStringToObject(line, "node", a->node);
        cJSON_AddNumberToObject(line, "node_index", a->node_index);
        cJSON_AddStringToObject(line, "layer", a->layer);
    } else {
        cJSON_AddNullToObject(line, "node");
    }
    if (a->element_guid[0] || a->element_name[0]) {
        cJSON *e = cJSON_AddObjectToObject(line, "element");
        cJSON_AddStringToObject(e, "guid", a->element_guid);
        cJSON_AddStringToObject(e, "class", a->element_class);
        cJSON_AddStringToObject(e, "name", a->element_name);
    }
    cJSON_AddItemToObject(line, "pose",
                          mr_sess_pose_json(a->pose_valid, &a->world_from_camera, a->pose_tags_seen, a->pose_rms_px));
    /* Absent, not null, when unknown: the exports read it as optional. */
    if (a->has_uncertainty && isfinite(a->uncertainty_m) && a->uncertainty_m >= 0)
        cJSON_AddNumberToObject(line, "uncertainty_m", a->uncertainty_m);
    if (a->has_measurement) measurement_json(line, &a->measurement);
    if (a->has_verdict) cJSON_AddItemToObject(line, "verdict", mr_verdict_to_json(&a->verdict));
    return line;
}

cJSON *mr_sess_pose_json(bool valid, const mr_dmat4 *world_from_camera, int tags_seen, double rms_px) {
    cJSON *p = cJSON_CreateObject();
    cJSON_AddBoolToObject(p, "valid", valid);
    cJSON_AddItemToObject(p, "world_from_camera", mr_json_from_dmat4(world_from_camera));
    cJSON_AddNumberToObject(p, "tags_seen", tags_seen);
    cJSON_AddNumberToObject(p, "rms_px", rms_px);
    return p;
}

const char *const mr_mark_categories[MR_MARK_CATEGORY_COUNT] = {"missing", "extra", "moved", "wrong size", "clash", "other"};

static int category_index(const char *s) {
    for (int i = 0; i < MR_MARK_CATEGORY_COUNT; i++)
        if (strcasecmp(s, mr_mark_categories[i]) == 0) return i;
    return -1;
}

/* What the planner said: id, revision, category, note, title, status,
 * priority, assignee, labels. */
static bool parse_topic(const cJSON *o, mr_annotation *a) {
    double rev = 0;
    if (!get_str(o, "id", a->id, sizeof a->id, false) || !get_num(o, "revision", &rev) ||
        !(rev >= 0 && rev < 1e9 && rev == floor(rev)) || !get_str(o, "category", a->category, sizeof a->category, false) ||
        !get_str(o, "note", a->note, sizeof a->note, false) || !get_str(o, "title", a->title, sizeof a->title, false) ||
        !get_str(o, "status", a->status, sizeof a->status, false) ||
        !get_str(o, "priority", a->priority, sizeof a->priority, false) ||
        !get_str(o, "assignee", a->assignee, sizeof a->assignee, false))
        return false;
    a->revision = (int)rev;
    const cJSON *l = cJSON_GetObjectItemCaseSensitive(o, "labels");
    if (l && !cJSON_IsNull(l)) {
        if (!cJSON_IsArray(l) || cJSON_GetArraySize(l) > MR_MARK_MAX_LABELS) return false;
        const cJSON *x;
        cJSON_ArrayForEach(x, l) {
            if (!cJSON_IsString(x) || strlen(x->valuestring) >= sizeof a->labels[0]) return false;
            snprintf(a->labels[a->label_count++], sizeof a->labels[0], "%s", x->valuestring);
        }
    }
    /* Before marks had a category, the chosen word was the note. */
    if (!cJSON_GetObjectItemCaseSensitive(o, "category") && category_index(a->note) >= 0) {
        snprintf(a->category, sizeof a->category, "%s", mr_mark_categories[category_index(a->note)]);
        a->note[0] = 0;
    }
    return true;
}

static bool parse_annotation(const cJSON *o, mr_annotation *a) {
    memset(a, 0, sizeof *a);
    a->frame_index = -1;
    a->node_index = -1;
    a->pose_tags_seen = -1;
    a->pose_rms_px = -1;
    a->world_from_camera = mr_m4_identity();
    if (!cJSON_IsObject(o) || !get_str(o, "type", a->type, sizeof a->type, true) || !a->type[0]) return false;
    double fi = -1;
    if (!get_num(o, "time_unix", &a->time_unix) || !get_num(o, "timestamp", &a->timestamp) ||
        !get_num(o, "frame_index", &fi) || !get_num(o, "depth", &a->depth))
        return false;
    if (fi != -1 && !(fi >= 0 && fi < 1e15 && fi == floor(fi))) return false;
    a->frame_index = (int64_t)fi;
    bool has_world = false;
    if (!parse_topic(o, a)) return false;
    if (!get_str(o, "node", a->node, sizeof a->node, false) ||
        !get_str(o, "layer", a->layer, sizeof a->layer, false) || !get_vec(o, "pixel", a->pixel, 2, &a->has_pixel) ||
        !get_vec(o, "world", a->world, 3, &has_world))
        return false;
    double ni = -1;
    if (!get_num(o, "node_index", &ni) || !(ni == -1 || (ni >= 0 && ni < 2147483647.0 && ni == floor(ni)))) return false;
    a->node_index = (int32_t)ni;
    const cJSON *el = cJSON_GetObjectItemCaseSensitive(o, "element");
    if (el && !cJSON_IsNull(el) &&
        (!cJSON_IsObject(el) || !get_str(el, "guid", a->element_guid, sizeof a->element_guid, false) ||
         !get_str(el, "class", a->element_class, sizeof a->element_class, false) ||
         !get_str(el, "name", a->element_name, sizeof a->element_name, false)))
        return false;
    a->hit = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, "hit"));
    if (a->hit && !has_world) return false; /* a hit names its point */
    const cJSON *p = cJSON_GetObjectItemCaseSensitive(o, "pose");
    if (p) {
        if (!cJSON_IsObject(p)) return false;
        if (cJSON_GetObjectItemCaseSensitive(p, "world_from_camera")) {
            if (!mr_json_dmat4(p, "world_from_camera", &a->world_from_camera, NULL) ||
                !mr_m4_is_rigid(&a->world_from_camera, 1e-6))
                return false;
            a->has_pose = true;
        }
        a->pose_valid = a->has_pose && cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(p, "valid"));
        double ts = -1;
        if (!get_num(p, "tags_seen", &ts) || !get_num(p, "rms_px", &a->pose_rms_px)) return false;
        a->pose_tags_seen = ts >= 0 && ts < 1e6 ? (int)ts : -1;
    }
    const cJSON *u = cJSON_GetObjectItemCaseSensitive(o, "uncertainty_m");
    if (u && !cJSON_IsNull(u)) {
        if (!cJSON_IsNumber(u) || !isfinite(u->valuedouble) || u->valuedouble < 0) return false;
        a->has_uncertainty = true;
        a->uncertainty_m = u->valuedouble;
    }
    const cJSON *vd = cJSON_GetObjectItemCaseSensitive(o, "verdict");
    if (vd && !cJSON_IsNull(vd)) {
        if (!mr_verdict_from_json(vd, &a->verdict, NULL)) return false;
        a->has_verdict = true;
    }
    return parse_measurement(o, a);
}

typedef struct ann_ctx { mr_annotations *a; int cap; bool oom; } ann_ctx;

static bool ann_line(void *vctx, const char *line, size_t n) {
    ann_ctx *c = vctx;
    cJSON *o = cJSON_ParseWithLength(line, n);
    if (!o) return false;
    mr_annotation an;
    if (!parse_annotation(o, &an)) {
        cJSON_Delete(o);
        return false;
    }
    mr_annotations *a = c->a;
    mr_annotation *ni = mr_sess_grow(a->items, a->count, &c->cap, 16, sizeof *ni);
    if (!ni) {
        cJSON_Delete(o);
        c->oom = true;
        return false;
    }
    a->items = ni;
    an.json = o;
    a->items[a->count++] = an;
    return true;
}

bool mr_annotations_parse(const char *text, size_t size, mr_annotations *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    ann_ctx c = {out, 0, false};
    mr_sess_for_lines(text, size, ann_line, &c, &out->torn_tail, &out->bad_lines);
    if (c.oom) {
        mr_annotations_free(out);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory reading annotations");
    }
    return true;
}

bool mr_annotations_load(const char *path, mr_annotations *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!mr_file_exists(path)) return true;
    size_t size = 0;
    char *text = mr_file_read(path, &size, 0, err);
    if (!text) return false;
    bool ok = mr_annotations_parse(text, size, out, err);
    free(text);
    if (ok && out->bad_lines) mr_log(MR_LOG_WARN, "%s: skipped %d unreadable line(s)", path, out->bad_lines);
    return ok;
}

void mr_annotation_key(const mr_annotation *a, char *out, size_t n) {
    if (a->id[0]) snprintf(out, n, "%s", a->id);
    else snprintf(out, n, "t%.3f-f%lld-p%.2f,%.2f", a->time_unix, (long long)a->frame_index, a->pixel[0], a->pixel[1]);
}

cJSON *mr_annotation_edit_line(const mr_annotation *a, const mr_annotation *edited, double time_unix) {
    mr_annotation e = *a;
    e.json = NULL;
    mr_annotation_key(a, e.id, sizeof e.id);
    e.revision = (a->revision > 0 ? a->revision : 1) + 1;
    snprintf(e.category, sizeof e.category, "%s", edited->category);
    snprintf(e.note, sizeof e.note, "%s", edited->note);
    snprintf(e.status, sizeof e.status, "%s", edited->status);
    snprintf(e.priority, sizeof e.priority, "%s", edited->priority);
    snprintf(e.assignee, sizeof e.assignee, "%s", edited->assignee);
    memcpy(e.labels, edited->labels, sizeof e.labels);
    e.label_count = edited->label_count;
    mr_mark_title(&e, e.title, sizeof e.title);
    cJSON *line = mr_annotation_to_json(&e);
    if (!line) return NULL;
    /* What the struct does not hold (the snapshot, distances, verdicts)
     * comes along from the line edited. */
    const cJSON *it;
    if (a->json)
        cJSON_ArrayForEach(it, a->json) {
            if (!it->string || cJSON_GetObjectItemCaseSensitive(line, it->string)) continue;
            /* fields the edit may have emptied stay empty */
            static const char *const topic[] = {"id", "category", "note", "title", "status", "priority", "assignee", "labels"};
            bool skip = false;
            for (size_t k = 0; k < sizeof topic / sizeof topic[0]; k++) skip |= strcmp(it->string, topic[k]) == 0;
            if (!skip) cJSON_AddItemToObject(line, it->string, cJSON_Duplicate(it, true));
        }
    cJSON_DeleteItemFromObjectCaseSensitive(line, "edited_unix");
    cJSON_AddNumberToObject(line, "edited_unix", time_unix);
    return line;
}

int mr_annotations_current(mr_annotations *a) {
    int kept = 0, dropped = 0;
    for (int i = 0; i < a->count; i++) {
        mr_annotation *x = &a->items[i];
        int first = -1;
        char kx[64], kk[64];
        mr_annotation_key(x, kx, sizeof kx);
        for (int k = 0; k < kept && first < 0; k++) {
            mr_annotation_key(&a->items[k], kk, sizeof kk);
            if (strcmp(kk, kx) == 0) first = k;
        }
        if (first >= 0) {
            /* The newer line takes the place of the mark's first line. */
            cJSON_Delete(a->items[first].json);
            a->items[first] = *x;
            dropped++;
        } else {
            a->items[kept++] = *x;
        }
    }
    a->count = kept;
    return dropped;
}

void mr_mark_set_note(mr_annotation *a, const char *typed) {
    char buf[sizeof a->note];
    snprintf(buf, sizeof buf, "%s", typed ? typed : "");
    size_t k = 0;
    a->note[0] = 0;
    for (char *save = NULL, *w = strtok_r(buf, " \t\r\n", &save); w; w = strtok_r(NULL, " \t\r\n", &save)) {
        if (w[0] == '@' && w[1]) snprintf(a->assignee, sizeof a->assignee, "%s", w + 1);
        else if (w[0] == '!' && w[1]) snprintf(a->priority, sizeof a->priority, "%s", w + 1);
        else if (w[0] == '#' && w[1] && a->label_count < MR_MARK_MAX_LABELS)
            snprintf(a->labels[a->label_count++], sizeof a->labels[0], "%s", w + 1);
        else if (k + strlen(w) + 2 < sizeof a->note)
            k += (size_t)snprintf(a->note + k, sizeof a->note - k, "%s%s", k ? " " : "", w);
    }
}

void mr_mark_new_id(double time_unix, int counter, char *out, size_t n) {
    snprintf(out, n, "m%llx-%x", (unsigned long long)(time_unix > 0 ? time_unix * 1000.0 : 0), (unsigned)counter);
}

/* "0.30 m" from 0.1 m up, "25 mm" below. */
static void words_len(double m, char *out, size_t n) {
    if (m >= 0.1) snprintf(out, n, "%.2f m", m);
    else snprintf(out, n, "%.0f mm", m * 1000);
}

void mr_mark_title(const mr_annotation *a, char *out, size_t n) {
    /* A mark without a category (written by another program): its note. */
    if (!a->category[0] && a->note[0]) {
        snprintf(out, n, "%.120s", a->note);
        return;
    }
    char cat[32];
    snprintf(cat, sizeof cat, "%s", a->category[0] ? a->category : "discrepancy");
    if (cat[0] >= 'a' && cat[0] <= 'z') cat[0] = (char)(cat[0] - 'a' + 'A');
    const char *part = a->node[0] ? a->node : a->has_measurement && a->measurement.planned_node[0]
                                                  ? a->measurement.planned_node : "";
    size_t k = (size_t)snprintf(out, n, "%s%s%s", cat, part[0] ? ": " : "", part);
    if (k >= n || !a->has_measurement || !a->measurement.has_distance) return;
    const mr_measurement *m = &a->measurement;
    double d[3] = {m->tri.point.x - m->planned.x, m->tri.point.y - m->planned.y, m->tri.point.z - m->planned.z};
    int ax = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(d[i]) > fabs(d[ax])) ax = i;
    char len[32];
    words_len(m->distance_m, len, sizeof len);
    /* Under half a millimetre there is no direction to speak of. */
    if (m->distance_m < 0.0005) k += (size_t)snprintf(out + k, n - k, "%s%s", part[0] ? ", " : ": ", len);
    else k += (size_t)snprintf(out + k, n - k, "%s%s along %c%c", part[0] ? ", " : ": ", len, d[ax] < 0 ? '-' : '+', "xyz"[ax]);
    if (k < n && a->has_verdict && a->verdict.kind != MR_VERDICT_NONE)
        snprintf(out + k, n - k, ", %s", mr_verdict_words(a->verdict.kind));
}

void mr_annotations_free(mr_annotations *a) {
    if (!a) return;
    for (int i = 0; i < a->count; i++) cJSON_Delete(a->items[i].json);
    free(a->items);
    memset(a, 0, sizeof *a);
}
