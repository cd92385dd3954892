/* A session's marks as BCF topics: one topic per mark, its camera and
 * snapshot as the first viewpoint, the marked element selected and
 * coloured, the description as the first comment. Written by bcf.c. */
#include "export_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Each category its colour in the BIM tool, so a list of components reads
 * like the view's marks. */
static const uint32_t k_colours[MR_BCF_TOPIC_TYPE_COUNT] = {
    0xffe53935, /* missing: red */
    0xfffb8c00, /* extra: orange */
    0xfffdd835, /* moved: yellow */
    0xff8e24aa, /* wrong size: purple */
    0xffd81b60, /* clash: magenta */
    0xff1e88e5, /* other: blue */
    0xffe53935, /* issue: red */
};
_Static_assert(MR_BCF_TOPIC_TYPE_COUNT == MR_MARK_CATEGORY_COUNT + 1, "a type per category, and Issue");

static int type_of(const mr_annotation *a) {
    for (int i = 0; i < MR_MARK_CATEGORY_COUNT; i++)
        if (strcmp(a->category, mr_mark_categories[i]) == 0) return i;
    return MR_BCF_TOPIC_TYPE_COUNT - 1;
}

static const char *status_of(const mr_annotation *a) {
    if (strcasecmp(a->status, "closed") == 0) return mr_bcf_topic_statuses[2];
    if (strcasecmp(a->status, "in progress") == 0 || strcasecmp(a->status, "in_progress") == 0)
        return mr_bcf_topic_statuses[1];
    return mr_bcf_topic_statuses[0];
}

/* The element of the mark as a BCF component: its IfcGuid, else (a model
 * without IFC identity) its name as the AuthoringToolId. Marks written
 * before marks named their element get it from the scene, by node name. */
static bool mark_component(const mr_annotation *a, const mr_scene *scene, mr_bcf_component *c) {
    memset(c, 0, sizeof *c);
    mr_element_words w;
    memset(&w, 0, sizeof w);
    snprintf(w.guid, sizeof w.guid, "%s", a->element_guid);
    snprintf(w.ifc_class, sizeof w.ifc_class, "%s", a->element_class);
    const char *name = a->element_name[0] ? a->element_name : a->node;
    size_t nn = strnlen(name, sizeof w.name - 1);
    memcpy(w.name, name, nn);
    w.name[nn] = 0;
    if (!w.guid[0] && scene && a->node[0]) {
        for (int32_t i = 0; i < scene->node_count; i++)
            if (strcmp(scene->nodes[i].name, a->node) == 0) {
                w = mr_scene_element_words(scene, i);
                break;
            }
    }
    if (!w.guid[0] && !w.name[0]) return false;
    snprintf(c->originating, sizeof c->originating, "mrcheck");
    if (mr_ifc_guid_valid(w.guid)) snprintf(c->ifc_guid, sizeof c->ifc_guid, "%s", w.guid);
    else snprintf(c->authoring_id, sizeof c->authoring_id, "%s", w.name);
    return true;
}

static char *dup_text(const char *s) {
    size_t n = strlen(s);
    char *d = malloc(n + 1);
    if (d) memcpy(d, s, n + 1);
    return d;
}

/* Appends text to a malloc'd string (kept as it was when out of memory). */
static void append(char **s, const char *text) {
    size_t a = *s ? strlen(*s) : 0, b = strlen(text);
    char *d = realloc(*s, a + b + 1);
    if (!d) return;
    memcpy(d + a, text, b + 1);
    *s = d;
}

static bool add_finding(mr_bcf *b, const mr_finding *f, const mr_export_params *p, mr_error *err) {
    const mr_annotation *a = f->mark;
    mr_bcf_frame fr;
    if (!mr_bcf_frame_of(&f->camera, p->max_side, &fr, err)) {
        mr_error_prefix(err, "mark %d", f->number);
        return false;
    }
    mr_bcf_topic *t = mr_bcf_add_topic(b);
    mr_bcf_viewpoint *v = t ? mr_bcf_add_viewpoint(t) : NULL;
    mr_bcf_comment *c = v ? mr_bcf_add_comment(t) : NULL;
    if (!c) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int ty = type_of(a);
    snprintf(t->guid, sizeof t->guid, "%s", f->topic_guid);
    snprintf(t->type, sizeof t->type, "%s", mr_bcf_topic_types[ty]);
    snprintf(t->status, sizeof t->status, "%s", status_of(a));
    snprintf(t->title, sizeof t->title, "%s", f->title);
    snprintf(t->priority, sizeof t->priority, "%s", a->priority);
    t->index = f->number;
    for (int l = 0; l < a->label_count && l < MR_BCF_MAX_LABELS; l++)
        snprintf(t->labels[t->label_count++], sizeof t->labels[0], "%s", a->labels[l]);
    snprintf(t->creation_date, sizeof t->creation_date, "%s", f->date);
    snprintf(t->creation_author, sizeof t->creation_author, "%s", p->author);
    if (f->modified[0]) {
        snprintf(t->modified_date, sizeof t->modified_date, "%s", f->modified);
        snprintf(t->modified_author, sizeof t->modified_author, "%s", p->author);
    }
    snprintf(t->assigned_to, sizeof t->assigned_to, "%s", a->assignee);
    t->description = dup_text(f->description);

    snprintf(v->guid, sizeof v->guid, "%s", f->viewpoint_guid);
    v->camera_kind = MR_BCF_CAMERA_PERSPECTIVE;
    v->camera = mr_bcf_camera_of(&a->world_from_camera, &fr, p->unit_m, (mr_bcf_version)p->bcf_version);
    char note[400] = "";
    if (p->bcf_version == MR_BCF_2_1) {
        double fov = v->camera.fov_deg;
        double back = mr_bcf_fit_fov_21(&v->camera, f->depth_m);
        if (back != 0)
            snprintf(note, sizeof note,
                     " The tablet camera saw %.1f deg across; BCF 2.1 allows 45 to 60 deg, so the viewpoint is "
                     "%.0f deg from %.2f m %s along the view, showing the same region at %s.",
                     fov, v->camera.fov_deg, fabs(back), back > 0 ? "further back" : "further forward",
                     f->depth_m > 0 ? "the marked point" : "5 m");
    }
    v->has_components = true;
    v->default_visibility = true;
    mr_bcf_component comp;
    if (mark_component(a, p->scene, &comp)) {
        mr_bcf_coloring *col = mr_bcf_add_coloring(v, k_colours[ty]);
        if (!col || !mr_bcf_add_component(&v->selection, &v->selection_count, &comp) ||
            !mr_bcf_add_component(&col->items, &col->count, &comp))
            return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        char el[600];
        snprintf(el, sizeof el, " Element: %s%s%s%s%s.", a->element_class[0] ? a->element_class : "",
                 a->element_class[0] ? " " : "", comp.ifc_guid[0] ? comp.ifc_guid : comp.authoring_id,
                 comp.ifc_guid[0] && a->element_name[0] ? ", " : "", comp.ifc_guid[0] ? a->element_name : "");
        append(&t->description, el);
    }
    if (note[0]) append(&t->description, note);

    mr_image snap;
    if (!mr_bcf_snapshot(&f->frame, &f->camera, &fr, &snap, err)) return false;
    v->snapshot = mr_image_encode_png(&snap, &v->snapshot_size, err);
    mr_image_free(&snap);
    if (!v->snapshot) return false;

    snprintf(c->guid, sizeof c->guid, "%s", f->comment_guid);
    snprintf(c->date, sizeof c->date, "%s", f->date);
    snprintf(c->author, sizeof c->author, "%s", p->author);
    snprintf(c->viewpoint_guid, sizeof c->viewpoint_guid, "%s", f->viewpoint_guid);
    free(c->text);
    c->text = dup_text(t->description ? t->description : "");
    if (!t->description || !c->text) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    return true;
}

bool mr_export_bcf(const char *dir, const char *out_path, const mr_export_params *params, mr_error *err) {
    mr_export_params p = mr_export_params_resolved(params);
    mr_findings fs;
    if (!mr_findings_load(dir, &p, &fs, err)) return false;
    mr_bcf b;
    memset(&b, 0, sizeof b);
    bool ok = true;
    for (int i = 0; ok && i < fs.count; i++) ok = add_finding(&b, &fs.items[i], &p, err);
    ok = ok && mr_bcf_write(&b, (mr_bcf_version)p.bcf_version, out_path, err);
    mr_bcf_free(&b);
    mr_findings_free(&fs);
    return ok;
}
