/* The BCF archive: bcf.version, (3.0) extensions.xml, and per topic a
 * folder named by its GUID with markup.bcf, viewpoint.bcfv and
 * snapshot.png. Built in memory with libzip (directory entries, forward
 * slashes) and written with mr_file_write_atomic (temp + rename). */
#include "export_internal.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <zip.h>

/* Topic types: the marks' categories in words; "Issue" for a mark
 * without one. Statuses: the mark's, in BCF's usual words. */
static const char *const k_types[] = {"Missing", "Extra", "Moved", "Wrong size", "Clash", "Other", "Issue"};
#define K_TYPE_ISSUE 6
_Static_assert(sizeof k_types / sizeof k_types[0] == MR_MARK_CATEGORY_COUNT + 1, "a type per category, and Issue");
static const char *const k_statuses[] = {"Open", "In Progress", "Closed"};

static const char *topic_type(const mr_annotation *a) {
    for (int i = 0; i < MR_MARK_CATEGORY_COUNT; i++)
        if (strcmp(a->category, mr_mark_categories[i]) == 0) return k_types[i];
    return k_types[K_TYPE_ISSUE];
}

static const char *topic_status(const mr_annotation *a) {
    if (strcasecmp(a->status, "closed") == 0) return k_statuses[2];
    if (strcasecmp(a->status, "in progress") == 0 || strcasecmp(a->status, "in_progress") == 0) return k_statuses[1];
    return k_statuses[0];
}

/* Adds s to a list of distinct strings (at most cap). */
static void add_distinct(const char **list, int *n, int cap, const char *s) {
    if (!s || !s[0]) return;
    for (int i = 0; i < *n; i++)
        if (strcmp(list[i], s) == 0) return;
    if (*n < cap) list[(*n)++] = s;
}

static char *version_xml(mr_bcf_version v, size_t *n) {
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "Version");
    mr_xml_attr(&x, "VersionId", v == MR_BCF_3_0 ? "3.0" : "2.1");
    if (v == MR_BCF_2_1) mr_xml_text_elem(&x, "DetailedVersion", "2.1");
    mr_xml_close(&x);
    return mr_xml_take(&x, n);
}

/* 3.0: the values the topics use must be declared (the schema's order:
 * TopicTypes, TopicStatuses, Priorities, TopicLabels, Stages, Users). */
static char *extensions_xml(const mr_findings *fs, const mr_export_params *p, size_t *n) {
    enum { CAP = 256 };
    const char *prio[CAP], *labels[CAP], *users[CAP];
    int np = 0, nl = 0, nu = 0;
    add_distinct(users, &nu, CAP, p->author);
    for (int i = 0; i < fs->count; i++) {
        const mr_annotation *a = fs->items[i].mark;
        add_distinct(prio, &np, CAP, a->priority);
        for (int l = 0; l < a->label_count; l++) add_distinct(labels, &nl, CAP, a->labels[l]);
        add_distinct(users, &nu, CAP, a->assignee);
    }
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "Extensions");
    mr_xml_open(&x, "TopicTypes");
    for (size_t i = 0; i < sizeof k_types / sizeof k_types[0]; i++) mr_xml_text_elem(&x, "TopicType", k_types[i]);
    mr_xml_close(&x);
    mr_xml_open(&x, "TopicStatuses");
    for (size_t i = 0; i < sizeof k_statuses / sizeof k_statuses[0]; i++) mr_xml_text_elem(&x, "TopicStatus", k_statuses[i]);
    mr_xml_close(&x);
    if (np) {
        mr_xml_open(&x, "Priorities");
        for (int i = 0; i < np; i++) mr_xml_text_elem(&x, "Priority", prio[i]);
        mr_xml_close(&x);
    }
    if (nl) {
        mr_xml_open(&x, "TopicLabels");
        for (int i = 0; i < nl; i++) mr_xml_text_elem(&x, "TopicLabel", labels[i]);
        mr_xml_close(&x);
    }
    mr_xml_open(&x, "Users");
    for (int i = 0; i < nu; i++) mr_xml_text_elem(&x, "User", users[i]);
    mr_xml_close(&x);
    mr_xml_close(&x);
    return mr_xml_take(&x, n);
}

static void viewpoint_ref(mr_xml *x, const mr_finding *f, const char *elem) {
    mr_xml_open(x, elem);
    mr_xml_attr(x, "Guid", f->viewpoint_guid);
    mr_xml_text_elem(x, "Viewpoint", "viewpoint.bcfv");
    mr_xml_text_elem(x, "Snapshot", "snapshot.png");
    mr_xml_close(x);
}

/* markup.bcf in the schema's order: 2.1 has Comment and Viewpoints after
 * Topic; 3.0 moves them into Topic as Comments / Viewpoints lists. */
static char *markup_xml(const mr_finding *f, const mr_export_params *p, size_t *n) {
    bool v3 = p->bcf_version == MR_BCF_3_0;
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "Markup");
    const mr_annotation *a = f->mark;
    mr_xml_open(&x, "Topic");
    mr_xml_attr(&x, "Guid", f->topic_guid);
    mr_xml_attr(&x, "TopicType", topic_type(a));
    mr_xml_attr(&x, "TopicStatus", topic_status(a));
    mr_xml_text_elem(&x, "Title", f->title);
    if (a->priority[0]) mr_xml_text_elem(&x, "Priority", a->priority);
    char idx[32];
    snprintf(idx, sizeof idx, "%d", f->number);
    mr_xml_text_elem(&x, "Index", idx);
    /* 2.1: one Labels element per label; 3.0: Labels holds Label elements. */
    if (a->label_count > 0 && v3) mr_xml_open(&x, "Labels");
    for (int l = 0; l < a->label_count; l++) mr_xml_text_elem(&x, v3 ? "Label" : "Labels", a->labels[l]);
    if (a->label_count > 0 && v3) mr_xml_close(&x);
    mr_xml_text_elem(&x, "CreationDate", f->date);
    mr_xml_text_elem(&x, "CreationAuthor", p->author);
    if (f->modified[0]) {
        mr_xml_text_elem(&x, "ModifiedDate", f->modified);
        mr_xml_text_elem(&x, "ModifiedAuthor", p->author);
    }
    if (a->assignee[0]) mr_xml_text_elem(&x, "AssignedTo", a->assignee);
    mr_xml_text_elem(&x, "Description", f->description);
    if (v3) {
        mr_xml_open(&x, "Comments");
        mr_xml_open(&x, "Comment");
        mr_xml_attr(&x, "Guid", f->comment_guid);
        mr_xml_text_elem(&x, "Date", f->date);
        mr_xml_text_elem(&x, "Author", p->author);
        mr_xml_text_elem(&x, "Comment", f->description);
        mr_xml_open(&x, "Viewpoint");
        mr_xml_attr(&x, "Guid", f->viewpoint_guid);
        mr_xml_close(&x);
        mr_xml_close(&x);
        mr_xml_close(&x);
        mr_xml_open(&x, "Viewpoints");
        viewpoint_ref(&x, f, "ViewPoint");
        mr_xml_close(&x);
        mr_xml_close(&x); /* Topic */
    } else {
        mr_xml_close(&x); /* Topic */
        mr_xml_open(&x, "Comment");
        mr_xml_attr(&x, "Guid", f->comment_guid);
        mr_xml_text_elem(&x, "Date", f->date);
        mr_xml_text_elem(&x, "Author", p->author);
        mr_xml_text_elem(&x, "Comment", f->description);
        mr_xml_open(&x, "Viewpoint");
        mr_xml_attr(&x, "Guid", f->viewpoint_guid);
        mr_xml_close(&x);
        mr_xml_close(&x);
        viewpoint_ref(&x, f, "Viewpoints");
    }
    mr_xml_close(&x); /* Markup */
    return mr_xml_take(&x, n);
}

static void xyz(mr_xml *x, const char *name, const double v[3]) {
    mr_xml_open(x, name);
    mr_xml_num_elem(x, "X", v[0]);
    mr_xml_num_elem(x, "Y", v[1]);
    mr_xml_num_elem(x, "Z", v[2]);
    mr_xml_close(x);
}

static char *viewpoint_xml(const mr_finding *f, const mr_bcf_camera *c, const mr_export_params *p, size_t *n) {
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "VisualizationInfo");
    mr_xml_attr(&x, "Guid", f->viewpoint_guid);
    mr_xml_open(&x, "PerspectiveCamera");
    xyz(&x, "CameraViewPoint", c->view_point);
    xyz(&x, "CameraDirection", c->direction);
    xyz(&x, "CameraUpVector", c->up);
    mr_xml_num_elem(&x, "FieldOfView", c->fov_deg);
    if (p->bcf_version == MR_BCF_3_0) mr_xml_num_elem(&x, "AspectRatio", c->aspect);
    mr_xml_close(&x);
    mr_xml_close(&x);
    return mr_xml_take(&x, n);
}

/* Every entry's time: the newest mark's, so the same marks give the same
 * bytes (set by build_zip). */
typedef struct zipw { zip_t *z; time_t mtime; } zipw;

static void stamp(zipw *w, zip_int64_t idx) {
    if (idx >= 0) zip_file_set_mtime(w->z, (zip_uint64_t)idx, w->mtime, 0);
}

/* Adds data (taken over, freed by libzip) as name. */
static bool add_file(zipw *w, const char *name, void *data, size_t n, mr_error *err) {
    zip_t *z = w->z;
    if (!data) return mr_fail(err, MR_ERR_NOMEM, "out of memory writing %s", name);
    zip_source_t *s = zip_source_buffer(z, data, n, 1);
    if (!s) {
        free(data);
        return mr_fail(err, MR_ERR_NOMEM, "zip: %s", zip_strerror(z));
    }
    zip_int64_t idx = zip_file_add(z, name, s, ZIP_FL_ENC_UTF_8);
    if (idx < 0) {
        zip_source_free(s);
        return mr_fail(err, MR_ERR_IO, "zip: %s: %s", name, zip_strerror(z));
    }
    stamp(w, idx);
    return true;
}

static bool add_topic(zipw *w, const mr_finding *f, const mr_export_params *p, mr_error *err) {
    mr_bcf_frame fr;
    if (!mr_bcf_frame_of(&f->camera, p->max_side, &fr, err)) {
        mr_error_prefix(err, "mark %d", f->number);
        return false;
    }
    mr_bcf_camera cam = mr_bcf_camera_of(&f->mark->world_from_camera, &fr, p->unit_m, p->bcf_version);
    mr_image snap;
    if (!mr_bcf_snapshot(&f->frame, &f->camera, &fr, &snap, err)) return false;
    size_t pn = 0;
    void *png = mr_image_encode_png(&snap, &pn, err);
    mr_image_free(&snap);
    if (!png) return false;
    zip_int64_t di = zip_dir_add(w->z, f->topic_guid, ZIP_FL_ENC_UTF_8);
    if (di < 0) {
        free(png);
        return mr_fail(err, MR_ERR_IO, "zip: %s", zip_strerror(w->z));
    }
    stamp(w, di);
    char name[128];
    size_t n = 0;
    snprintf(name, sizeof name, "%s/markup.bcf", f->topic_guid);
    char *m = markup_xml(f, p, &n);
    if (!add_file(w, name, m, n, err)) {
        free(png);
        return false;
    }
    snprintf(name, sizeof name, "%s/viewpoint.bcfv", f->topic_guid);
    char *v = viewpoint_xml(f, &cam, p, &n);
    if (!add_file(w, name, v, n, err)) {
        free(png);
        return false;
    }
    snprintf(name, sizeof name, "%s/snapshot.png", f->topic_guid);
    return add_file(w, name, png, pn, err);
}

/* The archive's bytes: libzip writes into a buffer source we keep. */
static bool build_zip(const mr_findings *fs, const mr_export_params *p, void **out, size_t *out_n, mr_error *err) {
    zip_error_t ze;
    zip_error_init(&ze);
    zip_source_t *src = zip_source_buffer_create(NULL, 0, 0, &ze);
    if (!src) return mr_fail(err, MR_ERR_NOMEM, "zip: %s", zip_error_strerror(&ze));
    zip_source_keep(src);
    zip_t *z = zip_open_from_source(src, ZIP_CREATE | ZIP_TRUNCATE, &ze);
    if (!z) {
        zip_source_free(src);
        bool r = mr_fail(err, MR_ERR_IO, "zip: %s", zip_error_strerror(&ze));
        zip_error_fini(&ze);
        return r;
    }
    /* (The length is set by the call, so it is made before add_file reads it.) */
    zipw w = {z, 315532800}; /* 1980-01-01, the zip format's first day */
    for (int i = 0; i < fs->count; i++)
        if (fs->items[i].mark->time_unix > (double)w.mtime && fs->items[i].mark->time_unix < 4e9)
            w.mtime = (time_t)fs->items[i].mark->time_unix;
    size_t n = 0;
    char *doc = version_xml(p->bcf_version, &n);
    bool ok = add_file(&w, "bcf.version", doc, n, err);
    if (ok && p->bcf_version == MR_BCF_3_0) {
        doc = extensions_xml(fs, p, &n);
        ok = add_file(&w, "extensions.xml", doc, n, err);
    }
    for (int i = 0; ok && i < fs->count; i++) ok = add_topic(&w, &fs->items[i], p, err);
    if (!ok) {
        zip_discard(z);
        zip_source_free(src);
        return false;
    }
    if (zip_close(z) < 0) {
        ok = mr_fail(err, MR_ERR_IO, "zip: %s", zip_strerror(z));
        zip_discard(z);
        zip_source_free(src);
        return ok;
    }
    zip_stat_t st;
    zip_stat_init(&st);
    void *buf = NULL;
    if (zip_source_stat(src, &st) == 0 && (st.valid & ZIP_STAT_SIZE) && zip_source_open(src) == 0) {
        buf = malloc(st.size ? st.size : 1);
        if (buf && zip_source_read(src, buf, st.size) != (zip_int64_t)st.size) {
            free(buf);
            buf = NULL;
        }
        zip_source_close(src);
    }
    zip_source_free(src);
    if (!buf) return mr_fail(err, MR_ERR_IO, "zip: cannot read back the archive");
    *out = buf;
    *out_n = st.size;
    return true;
}

bool mr_export_bcf(const char *dir, const char *out_path, const mr_export_params *params, mr_error *err) {
    mr_export_params p = mr_export_params_resolved(params);
    mr_findings fs;
    if (!mr_findings_load(dir, &p, &fs, err)) return false;
    void *data = NULL;
    size_t n = 0;
    bool ok = build_zip(&fs, &p, &data, &n, err) && mr_file_write_atomic(out_path, data, n, err);
    free(data);
    mr_findings_free(&fs);
    return ok;
}
