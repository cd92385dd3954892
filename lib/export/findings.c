/* The marks of a session folder, each with what its exports need: the raw
 * frame and its camera, the screen with the overlay, the optional measured
 * distance and registration uncertainty, GUIDs, title, description, date. */
#include "export_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

mr_export_params mr_export_params_resolved(const mr_export_params *p) {
    mr_export_params r = MR_EXPORT_DEFAULTS;
    if (p) {
        r = *p;
        if (r.bcf_version != MR_BCF_3_0) r.bcf_version = MR_BCF_2_1;
        if (r.max_side <= 0) r.max_side = MR_EXPORT_DEFAULT_MAX_SIDE;
        if (!(r.unit_m > 0) || !isfinite(r.unit_m)) r.unit_m = 1;
    }
    if (!r.author || !r.author[0]) r.author = "mrcheck";
    if (!r.title || !r.title[0]) r.title = "mrcheck findings";
    return r;
}

/* A relative path of the mark's "snapshot" object, resolved against dir;
 * false if the field is absent. */
static bool snap_path(const cJSON *line, const char *key, const char *dir, char *out, size_t n) {
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(line, "snapshot");
    const cJSON *v = cJSON_IsObject(s) ? cJSON_GetObjectItemCaseSensitive(s, key) : NULL;
    if (!cJSON_IsString(v) || !v->valuestring[0]) return false;
    mr_path_join(dir, v->valuestring, out, n);
    return true;
}

/* An optional non-negative finite number of the line. */
static bool opt_num(const cJSON *line, const char *key, double *out) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(line, key);
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble < 0) return false;
    *out = v->valuedouble;
    return true;
}

/* Deviations and uncertainties always in mm, so they compare at a glance. */
static void format_len(double m, char *out, size_t n) { snprintf(out, n, "%.0f mm", m * 1000); }

static bool load_one(const char *dir, const mr_export_params *p, mr_finding *f, mr_error *err) {
    const mr_annotation *a = f->mark;
    const cJSON *line = a->json;
    if (!a->has_pose) return mr_fail(err, MR_ERR_INVALID, "mark %d has no camera pose", f->number);
    char path[4096];
    if (!line || !snap_path(line, "frame", dir, path, sizeof path))
        return mr_fail(err, MR_ERR_INVALID, "mark %d has no snapshot frame", f->number);
    if (!mr_file_exists(path)) return mr_fail(err, MR_ERR_IO, "mark %d: snapshot %s is missing", f->number, path);
    if (!mr_image_load(path, 0, &f->frame, err)) {
        mr_error_prefix(err, "mark %d", f->number);
        return false;
    }
    /* The camera: the snapshot's JSON, else the recording's meta.json. */
    char jpath[4096];
    cJSON *j = NULL;
    mr_error je = {0};
    if (snap_path(line, "pose", dir, jpath, sizeof jpath)) j = mr_json_load(jpath, &je);
    const cJSON *cj = j ? cJSON_GetObjectItemCaseSensitive(j, "camera") : NULL;
    bool have_cam = false;
    if (cj) have_cam = mr_camera_from_json(cj, &f->camera, &je);
    cJSON_Delete(j);
    if (!have_cam) {
        char mpath[4096];
        mr_path_join(dir, "meta.json", mpath, sizeof mpath);
        cJSON *meta = mr_file_exists(mpath) ? mr_json_load(mpath, &je) : NULL;
        const cJSON *mc = meta ? cJSON_GetObjectItemCaseSensitive(meta, "camera") : NULL;
        if (mc) have_cam = mr_camera_from_json(mc, &f->camera, &je);
        cJSON_Delete(meta);
    }
    if (!have_cam) return mr_fail(err, MR_ERR_INVALID, "mark %d: no camera for its snapshot", f->number);
    f->camera = mr_camera_resized(&f->camera, f->frame.width, f->frame.height);
    if (snap_path(line, "screen", dir, f->screen_path, sizeof f->screen_path) && !mr_file_exists(f->screen_path))
        f->screen_path[0] = 0;
    f->has_distance = opt_num(line, "distance_m", &f->distance_m);
    f->has_uncertainty = opt_num(line, "uncertainty_m", &f->uncertainty_m);
    /* A mark made by Measure carries its triangulated distance
     * to the plan and that distance's sigma. */
    if (!f->has_distance) f->has_distance = opt_num(line, "measured_distance_m", &f->distance_m);
    f->has_distance_sigma = f->has_distance && opt_num(line, "measured_sigma_m", &f->distance_sigma_m);
    f->depth_m = a->hit ? a->depth * p->unit_m : -1;

    /* GUIDs from the mark's identity: the same mark gives the same topic,
     * and an edit of it (a later line of the same mark) updates that topic
     * in a BCF tool instead of adding one. Lines of older sessions without
     * an id: from the line itself, as before. */
    char *text = a->id[0] ? NULL : cJSON_PrintUnformatted(line);
    if (!a->id[0] && !text) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    const char *key = a->id[0] ? a->id : text;
    size_t n = strlen(key);
    mr_bcf_guid(key, n, 1, f->topic_guid);
    mr_bcf_guid(key, n, 2, f->viewpoint_guid);
    mr_bcf_guid(key, n, 3, f->comment_guid);
    free(text);

    if (a->title[0]) snprintf(f->title, sizeof f->title, "%s", a->title);
    else mr_mark_title(a, f->title, sizeof f->title);
    char len[64];
    size_t k = 0, cap = sizeof f->description;
    char *d = f->description;
#define ADD(...) do { int w_ = snprintf(d + k, cap - k, __VA_ARGS__); if (w_ > 0) k = k + (size_t)w_ < cap ? k + (size_t)w_ : cap - 1; } while (0)
    ADD("%s", f->title);
    if (a->note[0]) ADD(". Note: %s", a->note);
    if (f->has_distance) {
        format_len(f->distance_m, len, sizeof len);
        ADD(". Measured distance: %s", len);
        if (f->has_distance_sigma) {
            format_len(f->distance_sigma_m, len, sizeof len);
            ADD(" +- %s (1 sigma", len);
            if (a->has_measurement) ADD(", triangulated from %d taps", a->measurement.taps);
            if (a->has_measurement && a->measurement.planned_node[0]) ADD(", to the planned %s", a->measurement.planned_node);
            ADD(")");
        }
    } else {
        ADD(". Measured distance: not measured");
    }
    /* The verdict in words, with its interval and the tolerance it used. */
    if (a->has_verdict && a->verdict.kind != MR_VERDICT_NONE) {
        char vline[320];
        mr_verdict_format(&a->verdict, vline, sizeof vline);
        ADD(". Verdict: %s", vline);
    } else if (f->has_distance) {
        ADD(". No verdict (no uncertainty of the distance to judge it with)");
    }
    if (f->has_uncertainty) {
        format_len(f->uncertainty_m, len, sizeof len);
        ADD(". Registration uncertainty at the mark: %s (1 sigma)", len);
    } else {
        ADD(". Registration uncertainty: not available");
    }
    if (f->depth_m >= 0) ADD(". The camera was %.2f m from the marked point", f->depth_m);
    else ADD(". Camera");
    if (!a->pose_valid) ADD(" (pose not tracked)");
    ADD(" (frame %lld, t = %.2f s).", (long long)a->frame_index, a->timestamp);
    if (strcmp(a->status, "closed") == 0) ADD(" Closed.");
#undef ADD
    const cJSON *ed = cJSON_GetObjectItemCaseSensitive(line, "edited_unix");
    if (cJSON_IsNumber(ed) && ed->valuedouble > 0 && ed->valuedouble < 253402300799.0) {
        time_t te = (time_t)ed->valuedouble;
        struct tm tme;
        gmtime_r(&te, &tme);
        strftime(f->modified, sizeof f->modified, "%Y-%m-%dT%H:%M:%SZ", &tme);
    }
    time_t t = a->time_unix > 0 && a->time_unix < 253402300799.0 ? (time_t)a->time_unix : time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(f->date, sizeof f->date, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return true;
}

bool mr_findings_load(const char *dir, const mr_export_params *p, mr_findings *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    char path[4096];
    mr_path_join(dir, "annotations.jsonl", path, sizeof path);
    if (!mr_file_exists(path)) return mr_fail(err, MR_ERR_IO, "%s: no marks to export (no annotations.jsonl)", dir);
    if (!mr_annotations_load(path, &out->marks, err)) return false;
    if (out->marks.torn_tail) mr_log(MR_LOG_WARN, "%s: ignored a torn last line", path);
    mr_annotations_current(&out->marks); /* the newest line of each mark */
    if (out->marks.count == 0) {
        mr_findings_free(out);
        return mr_fail(err, MR_ERR_INVALID, "%s: no marks to export", path);
    }
    out->items = calloc((size_t)out->marks.count, sizeof *out->items);
    if (!out->items) {
        mr_findings_free(out);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < out->marks.count; i++) {
        /* A judged mark is labelled with its verdict's words, so a BIM
         * tool can filter the topics that are out of tolerance. */
        mr_annotation *m = &out->marks.items[i];
        const char *vw = m->has_verdict ? mr_verdict_words(m->verdict.kind) : "";
        bool have = !vw[0];
        for (int l = 0; l < m->label_count; l++) have |= strcmp(m->labels[l], vw) == 0;
        if (!have && m->label_count < MR_MARK_MAX_LABELS) snprintf(m->labels[m->label_count++], sizeof m->labels[0], "%s", vw);
        mr_finding *f = &out->items[out->count++];
        f->mark = &out->marks.items[i];
        f->number = i + 1;
        if (!load_one(dir, p, f, err)) {
            mr_findings_free(out);
            return false;
        }
    }
    return true;
}

void mr_findings_free(mr_findings *f) {
    for (int i = 0; i < f->count; i++) mr_image_free(&f->items[i].frame);
    free(f->items);
    mr_annotations_free(&f->marks);
    memset(f, 0, sizeof *f);
}

bool mr_export_mark_write(const char *dir, const mr_annotation *m, const mr_mark_files *fl, mr_error *err) {
    if (!fl || !fl->stem || !fl->stem[0] || !fl->frame || !fl->camera)
        return mr_fail(err, MR_ERR_INVALID, "a mark needs a stem, a frame and a camera");
    char sdir[4096], path[8192], name[512];
    mr_path_join(dir, "snapshots", sdir, sizeof sdir);
    if (!mr_mkdirs(sdir, err)) return false;
    cJSON *line = mr_annotation_to_json(m);
    cJSON *snap = line ? cJSON_AddObjectToObject(line, "snapshot") : NULL;
    if (!snap) {
        cJSON_Delete(line);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    bool ok = true;
    snprintf(name, sizeof name, "snapshots/%s_frame.png", fl->stem);
    mr_path_join(dir, name, path, sizeof path);
    ok = mr_image_save_png(path, fl->frame, err);
    cJSON_AddStringToObject(snap, "frame", name);
    if (ok && fl->screen) {
        snprintf(name, sizeof name, "snapshots/%s_screen.png", fl->stem);
        mr_path_join(dir, name, path, sizeof path);
        ok = mr_image_save_png(path, fl->screen, err);
        cJSON_AddStringToObject(snap, "screen", name);
    }
    if (ok) {
        cJSON *j = cJSON_CreateObject();
        cJSON_AddItemToObject(j, "camera", mr_camera_to_json(fl->camera));
        cJSON_AddNumberToObject(j, "frame_index", (double)m->frame_index);
        cJSON_AddNumberToObject(j, "timestamp", m->timestamp);
        cJSON *pose = cJSON_AddObjectToObject(j, "pose");
        cJSON_AddBoolToObject(pose, "valid", m->pose_valid);
        cJSON_AddItemToObject(pose, "world_from_camera", mr_json_from_dmat4(&m->world_from_camera));
        snprintf(name, sizeof name, "snapshots/%s.json", fl->stem);
        mr_path_join(dir, name, path, sizeof path);
        ok = mr_json_save(path, j, err);
        cJSON_Delete(j);
        cJSON_AddStringToObject(snap, "pose", name);
    }
    if (ok && fl->distance_m >= 0) cJSON_AddNumberToObject(line, "distance_m", fl->distance_m);
    if (ok && fl->uncertainty_m >= 0) cJSON_AddNumberToObject(line, "uncertainty_m", fl->uncertainty_m);
    mr_path_join(dir, "annotations.jsonl", path, sizeof path);
    if (ok) ok = mr_annotation_append(path, line, err);
    cJSON_Delete(line);
    return ok;
}
