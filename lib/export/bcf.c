/* The BCF writer: an mr_bcf as a 2.1 or 3.0 archive. bcf.version, (3.0)
 * extensions.xml, and per topic a folder named by its GUID with
 * markup.bcf, its viewpoints and snapshots. Elements follow the schemas'
 * sequences (buildingSMART's markup.xsd / visinfo.xsd of each version).
 * Built in memory with libzip (directory entries, forward slashes) and
 * written with mr_file_write_atomic (temp + rename). */
#include "export_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <zip.h>

/* The words mrcheck's own topics use, always declared in 3.0's extensions
 * (so a tool offers them when the office answers). */
const char *const mr_bcf_topic_types[MR_BCF_TOPIC_TYPE_COUNT] = {"Missing", "Extra",       "Moved", "Wrong size",
                                                                 "Clash",   "Other",       "Issue"};
const char *const mr_bcf_topic_statuses[MR_BCF_TOPIC_STATUS_COUNT] = {"Open", "In Progress", "Closed"};

bool mr_bcf_guid_valid(const char *g) {
    if (!g || strlen(g) != 36) return false;
    for (int i = 0; i < 36; i++) {
        char c = g[i];
        bool dash = i == 8 || i == 13 || i == 18 || i == 23;
        if (dash ? c != '-' : !((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
    }
    return true;
}

/* Adds s to a list of distinct strings (at most cap). */
static void add_distinct(const char **list, int *n, int cap, const char *s) {
    if (!s || !s[0]) return;
    for (int i = 0; i < *n; i++)
        if (strcmp(list[i], s) == 0) return;
    if (*n < cap) list[(*n)++] = s;
}

/* What the schema requires to be non-empty gets a word when empty. */
static const char *or_word(const char *s, const char *word) { return s && s[0] ? s : word; }

static char *version_xml(mr_bcf_version v, size_t *n) {
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "Version");
    mr_xml_attr(&x, "VersionId", v == MR_BCF_3_0 ? "3.0" : "2.1");
    if (v == MR_BCF_2_1) mr_xml_text_elem(&x, "DetailedVersion", "2.1");
    mr_xml_close(&x);
    return mr_xml_take(&x, n);
}

static void list_elem(mr_xml *x, const char *outer, const char *inner, const char **items, int n) {
    if (n <= 0) return;
    mr_xml_open(x, outer);
    for (int i = 0; i < n; i++) mr_xml_text_elem(x, inner, items[i]);
    mr_xml_close(x);
}

/* 3.0: the values the topics use must be declared (the schema's order:
 * TopicTypes, TopicStatuses, Priorities, TopicLabels, Stages, Users). */
static char *extensions_xml(const mr_bcf *b, size_t *n) {
    enum { CAP = 512 };
    const char *types[CAP], *statuses[CAP], *prio[CAP], *labels[CAP], *stages[CAP], *users[CAP];
    int nt = 0, ns = 0, np = 0, nl = 0, ng = 0, nu = 0;
    for (int i = 0; i < MR_BCF_TOPIC_TYPE_COUNT; i++) add_distinct(types, &nt, CAP, mr_bcf_topic_types[i]);
    for (int i = 0; i < MR_BCF_TOPIC_STATUS_COUNT; i++) add_distinct(statuses, &ns, CAP, mr_bcf_topic_statuses[i]);
    for (int i = 0; i < b->topic_count; i++) {
        const mr_bcf_topic *t = &b->topics[i];
        add_distinct(types, &nt, CAP, t->type);
        add_distinct(statuses, &ns, CAP, t->status);
        add_distinct(prio, &np, CAP, t->priority);
        for (int l = 0; l < t->label_count; l++) add_distinct(labels, &nl, CAP, t->labels[l]);
        add_distinct(stages, &ng, CAP, t->stage);
        add_distinct(users, &nu, CAP, t->creation_author);
        add_distinct(users, &nu, CAP, t->modified_author);
        add_distinct(users, &nu, CAP, t->assigned_to);
        for (int c = 0; c < t->comment_count; c++) {
            add_distinct(users, &nu, CAP, t->comments[c].author);
            add_distinct(users, &nu, CAP, t->comments[c].modified_author);
        }
    }
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "Extensions");
    list_elem(&x, "TopicTypes", "TopicType", types, nt);
    list_elem(&x, "TopicStatuses", "TopicStatus", statuses, ns);
    list_elem(&x, "Priorities", "Priority", prio, np);
    list_elem(&x, "TopicLabels", "TopicLabel", labels, nl);
    list_elem(&x, "Stages", "Stage", stages, ng);
    list_elem(&x, "Users", "User", users, nu);
    mr_xml_close(&x);
    return mr_xml_take(&x, n);
}

/* The names a viewpoint gets in the archive: the first one the names
 * BIMcollab and Procore look for, the others by their GUID. */
static bool is_jpeg(const mr_bcf_viewpoint *v) {
    return v->snapshot && v->snapshot_size > 3 && v->snapshot[0] == 0xff && v->snapshot[1] == 0xd8;
}
static void vp_names(const mr_bcf_viewpoint *v, int i, char *file, char *snap, size_t n) {
    const char *ext = is_jpeg(v) ? "jpg" : "png";
    if (i == 0) {
        snprintf(file, n, "viewpoint.bcfv");
        snprintf(snap, n, "snapshot.%s", ext);
    } else {
        snprintf(file, n, "viewpoint_%s.bcfv", v->guid);
        snprintf(snap, n, "snapshot_%s.%s", v->guid, ext);
    }
    if (!v->snapshot) snap[0] = 0;
}

static void viewpoint_ref(mr_xml *x, const mr_bcf_viewpoint *v, int i, const char *elem) {
    char file[128], snap[128];
    vp_names(v, i, file, snap, sizeof file);
    mr_xml_open(x, elem);
    mr_xml_attr(x, "Guid", v->guid);
    mr_xml_text_elem(x, "Viewpoint", file);
    if (snap[0]) mr_xml_text_elem(x, "Snapshot", snap);
    if (v->index >= 0) {
        char idx[32];
        snprintf(idx, sizeof idx, "%d", v->index);
        mr_xml_text_elem(x, "Index", idx);
    }
    mr_xml_close(x);
}

static void comment_xml(mr_xml *x, const mr_bcf_comment *c) {
    mr_xml_open(x, "Comment");
    mr_xml_attr(x, "Guid", c->guid);
    mr_xml_text_elem(x, "Date", c->date);
    mr_xml_text_elem(x, "Author", or_word(c->author, "unknown"));
    mr_xml_text_elem(x, "Comment", c->text ? c->text : "");
    if (mr_bcf_guid_valid(c->viewpoint_guid)) {
        mr_xml_open(x, "Viewpoint");
        mr_xml_attr(x, "Guid", c->viewpoint_guid);
        mr_xml_close(x);
    }
    if (c->modified_date[0]) {
        mr_xml_text_elem(x, "ModifiedDate", c->modified_date);
        mr_xml_text_elem(x, "ModifiedAuthor", or_word(c->modified_author, or_word(c->author, "unknown")));
    }
    mr_xml_close(x);
}

/* markup.bcf in the schema's order: 2.1 has Comment and Viewpoints after
 * Topic; 3.0 moves them into Topic as Comments / Viewpoints lists. */
static char *markup_xml(const mr_bcf_topic *t, mr_bcf_version ver, size_t *n) {
    bool v3 = ver == MR_BCF_3_0;
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "Markup");
    mr_xml_open(&x, "Topic");
    mr_xml_attr(&x, "Guid", t->guid);
    /* 3.0 requires both; 2.1 has them optional, and tools filter by them. */
    mr_xml_attr(&x, "TopicType", or_word(t->type, "Issue"));
    mr_xml_attr(&x, "TopicStatus", or_word(t->status, "Open"));
    mr_xml_text_elem(&x, "Title", or_word(t->title, "(untitled)"));
    if (t->priority[0]) mr_xml_text_elem(&x, "Priority", t->priority);
    if (t->index >= 0) {
        char idx[32];
        snprintf(idx, sizeof idx, "%d", t->index);
        mr_xml_text_elem(&x, "Index", idx);
    }
    /* 2.1: one Labels element per label; 3.0: Labels holds Label elements. */
    if (t->label_count > 0 && v3) mr_xml_open(&x, "Labels");
    for (int l = 0; l < t->label_count; l++) mr_xml_text_elem(&x, v3 ? "Label" : "Labels", t->labels[l]);
    if (t->label_count > 0 && v3) mr_xml_close(&x);
    mr_xml_text_elem(&x, "CreationDate", t->creation_date);
    mr_xml_text_elem(&x, "CreationAuthor", or_word(t->creation_author, "unknown"));
    if (t->modified_date[0]) {
        mr_xml_text_elem(&x, "ModifiedDate", t->modified_date);
        mr_xml_text_elem(&x, "ModifiedAuthor", or_word(t->modified_author, or_word(t->creation_author, "unknown")));
    }
    if (t->due_date[0]) mr_xml_text_elem(&x, "DueDate", t->due_date);
    if (t->assigned_to[0]) mr_xml_text_elem(&x, "AssignedTo", t->assigned_to);
    if (t->stage[0]) mr_xml_text_elem(&x, "Stage", t->stage);
    if (t->description) mr_xml_text_elem(&x, "Description", t->description);
    if (v3) {
        if (t->comment_count > 0) {
            mr_xml_open(&x, "Comments");
            for (int c = 0; c < t->comment_count; c++) comment_xml(&x, &t->comments[c]);
            mr_xml_close(&x);
        }
        if (t->viewpoint_count > 0) {
            mr_xml_open(&x, "Viewpoints");
            for (int v = 0; v < t->viewpoint_count; v++) viewpoint_ref(&x, &t->viewpoints[v], v, "ViewPoint");
            mr_xml_close(&x);
        }
        mr_xml_close(&x); /* Topic */
    } else {
        mr_xml_close(&x); /* Topic */
        for (int c = 0; c < t->comment_count; c++) comment_xml(&x, &t->comments[c]);
        for (int v = 0; v < t->viewpoint_count; v++) viewpoint_ref(&x, &t->viewpoints[v], v, "Viewpoints");
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

static void component_xml(mr_xml *x, const mr_bcf_component *c) {
    mr_xml_open(x, "Component");
    if (mr_ifc_guid_valid(c->ifc_guid)) mr_xml_attr(x, "IfcGuid", c->ifc_guid);
    if (c->originating[0]) mr_xml_text_elem(x, "OriginatingSystem", c->originating);
    if (c->authoring_id[0]) mr_xml_text_elem(x, "AuthoringToolId", c->authoring_id);
    mr_xml_close(x);
}

static void components_list(mr_xml *x, const char *outer, const mr_bcf_component *c, int n) {
    if (n <= 0) return;
    if (outer) mr_xml_open(x, outer);
    for (int i = 0; i < n; i++) component_xml(x, &c[i]);
    if (outer) mr_xml_close(x);
}

static void setup_hints(mr_xml *x, const mr_bcf_viewpoint *v) {
    mr_xml_open(x, "ViewSetupHints");
    mr_xml_attr(x, "SpacesVisible", v->spaces_visible ? "true" : "false");
    mr_xml_attr(x, "SpaceBoundariesVisible", v->space_boundaries_visible ? "true" : "false");
    mr_xml_attr(x, "OpeningsVisible", v->openings_visible ? "true" : "false");
    mr_xml_close(x);
}

/* 2.1: ViewSetupHints, Selection, Visibility, Coloring (Color holds
 * Component elements); 3.0: Selection, Visibility (with ViewSetupHints),
 * Coloring (Color holds a Components list). */
static void components_xml(mr_xml *x, const mr_bcf_viewpoint *v, bool v3) {
    mr_xml_open(x, "Components");
    if (!v3) setup_hints(x, v);
    components_list(x, "Selection", v->selection, v->selection_count);
    mr_xml_open(x, "Visibility");
    mr_xml_attr(x, "DefaultVisibility", v->default_visibility ? "true" : "false");
    if (v3) setup_hints(x, v);
    components_list(x, "Exceptions", v->exceptions, v->exception_count);
    mr_xml_close(x);
    int used = 0;
    for (int i = 0; i < v->coloring_count; i++) used += v->colorings[i].count > 0;
    if (used) {
        mr_xml_open(x, "Coloring");
        for (int i = 0; i < v->coloring_count; i++) {
            const mr_bcf_coloring *c = &v->colorings[i];
            if (c->count <= 0) continue;
            char hex[16];
            /* RRGGBB when opaque: the form every tool reads; ARGB otherwise. */
            if ((c->argb >> 24) == 0xff) snprintf(hex, sizeof hex, "%06X", (unsigned)(c->argb & 0xffffff));
            else snprintf(hex, sizeof hex, "%08X", (unsigned)c->argb);
            mr_xml_open(x, "Color");
            mr_xml_attr(x, "Color", hex);
            components_list(x, v3 ? "Components" : NULL, c->items, c->count);
            mr_xml_close(x);
        }
        mr_xml_close(x);
    }
    mr_xml_close(x);
}

/* Width / height of a PNG's header, 0 when not a PNG. */
static double png_aspect(const unsigned char *p, size_t n) {
    if (!p || n < 24 || memcmp(p, "\x89PNG", 4) != 0) return 0;
    uint32_t w = (uint32_t)p[16] << 24 | (uint32_t)p[17] << 16 | (uint32_t)p[18] << 8 | p[19];
    uint32_t h = (uint32_t)p[20] << 24 | (uint32_t)p[21] << 16 | (uint32_t)p[22] << 8 | p[23];
    return w && h ? (double)w / h : 0;
}

static char *viewpoint_xml(const mr_bcf_viewpoint *v, mr_bcf_version ver, size_t *n) {
    bool v3 = ver == MR_BCF_3_0;
    mr_xml x;
    mr_xml_begin(&x);
    mr_xml_open(&x, "VisualizationInfo");
    mr_xml_attr(&x, "Guid", v->guid);
    if (v->has_components) components_xml(&x, v, v3);
    mr_bcf_camera c = v->camera;
    double aspect = c.aspect > 0 ? c.aspect : png_aspect(v->snapshot, v->snapshot_size);
    if (!(aspect > 0)) aspect = 4.0 / 3.0;
    if (v->camera_kind == MR_BCF_CAMERA_PERSPECTIVE) {
        if (!v3) mr_bcf_fit_fov_21(&c, 0);
        mr_xml_open(&x, "PerspectiveCamera");
        xyz(&x, "CameraViewPoint", c.view_point);
        xyz(&x, "CameraDirection", c.direction);
        xyz(&x, "CameraUpVector", c.up);
        mr_xml_num_elem(&x, "FieldOfView", c.fov_deg);
        if (v3) mr_xml_num_elem(&x, "AspectRatio", aspect);
        mr_xml_close(&x);
    } else if (v->camera_kind == MR_BCF_CAMERA_ORTHOGONAL) {
        mr_xml_open(&x, "OrthogonalCamera");
        xyz(&x, "CameraViewPoint", c.view_point);
        xyz(&x, "CameraDirection", c.direction);
        xyz(&x, "CameraUpVector", c.up);
        mr_xml_num_elem(&x, "ViewToWorldScale", v->view_to_world_scale > 0 ? v->view_to_world_scale : 1);
        if (v3) mr_xml_num_elem(&x, "AspectRatio", aspect);
        mr_xml_close(&x);
    }
    if (v->clip_count > 0) {
        mr_xml_open(&x, "ClippingPlanes");
        for (int i = 0; i < v->clip_count; i++) {
            mr_xml_open(&x, "ClippingPlane");
            xyz(&x, "Location", v->clips[i].location);
            xyz(&x, "Direction", v->clips[i].direction);
            mr_xml_close(&x);
        }
        mr_xml_close(&x);
    }
    mr_xml_close(&x);
    return mr_xml_take(&x, n);
}

double mr_bcf_fit_fov_21(mr_bcf_camera *c, double depth_m) {
    double fov = c->fov_deg;
    if (!(fov > 0 && fov < 180)) fov = 60; /* nothing sensible to keep */
    double fit = fmin(fmax(fov, 45.0), 60.0);
    if (fit == c->fov_deg) return 0;
    double d = depth_m > 0 && isfinite(depth_m) ? depth_m : 5.0;
    /* The half-width shown at distance d stays: d t = d' t'. */
    double t = tan(fov * M_PI / 360), t2 = tan(fit * M_PI / 360);
    double back = d * t / t2 - d;
    for (int k = 0; k < 3; k++) c->view_point[k] -= back * c->direction[k];
    c->fov_deg = fit;
    return back;
}

/* ------------------------------------------------------------ the archive */

/* Every entry's time: the newest date the topics carry, so the same topics
 * give the same bytes. */
typedef struct zipw { zip_t *z; time_t mtime; } zipw;

static void newer(time_t *t, const char *date) {
    struct tm tm;
    memset(&tm, 0, sizeof tm);
    if (!date || sscanf(date, "%4d-%2d-%2dT%2d:%2d:%2d", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour,
                        &tm.tm_min, &tm.tm_sec) != 6)
        return;
    if (tm.tm_year < 1980 || tm.tm_year > 2107) return; /* the zip format's dates */
    tm.tm_year -= 1900;
    tm.tm_mon -= 1;
    time_t v = timegm(&tm);
    if (v > *t) *t = v;
}

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

static bool add_copy(zipw *w, const char *name, const void *data, size_t n, mr_error *err) {
    void *c = malloc(n ? n : 1);
    if (c && n) memcpy(c, data, n);
    return add_file(w, name, c, n, err);
}

static bool add_topic(zipw *w, const mr_bcf_topic *t, mr_bcf_version ver, mr_error *err) {
    if (!mr_bcf_guid_valid(t->guid)) return mr_fail(err, MR_ERR_INVALID, "topic \"%s\": not a GUID", t->guid);
    for (int i = 0; i < t->comment_count; i++)
        if (!mr_bcf_guid_valid(t->comments[i].guid))
            return mr_fail(err, MR_ERR_INVALID, "topic %s: comment %d has no GUID", t->guid, i + 1);
    for (int i = 0; i < t->viewpoint_count; i++)
        if (!mr_bcf_guid_valid(t->viewpoints[i].guid))
            return mr_fail(err, MR_ERR_INVALID, "topic %s: viewpoint %d has no GUID", t->guid, i + 1);
    zip_int64_t di = zip_dir_add(w->z, t->guid, ZIP_FL_ENC_UTF_8);
    if (di < 0) return mr_fail(err, MR_ERR_IO, "zip: %s", zip_strerror(w->z));
    stamp(w, di);
    char name[256];
    size_t n = 0;
    snprintf(name, sizeof name, "%s/markup.bcf", t->guid);
    char *doc = markup_xml(t, ver, &n); /* sets n: not inside add_file's arguments */
    if (!add_file(w, name, doc, n, err)) return false;
    for (int i = 0; i < t->viewpoint_count; i++) {
        const mr_bcf_viewpoint *v = &t->viewpoints[i];
        char file[128], snap[128];
        vp_names(v, i, file, snap, sizeof file);
        snprintf(name, sizeof name, "%s/%s", t->guid, file);
        doc = viewpoint_xml(v, ver, &n);
        if (!add_file(w, name, doc, n, err)) return false;
        snprintf(name, sizeof name, "%s/%s", t->guid, snap);
        if (snap[0] && !add_copy(w, name, v->snapshot, v->snapshot_size, err)) return false;
    }
    return true;
}

bool mr_bcf_write_memory(const mr_bcf *b, mr_bcf_version ver, void **out, size_t *out_n, mr_error *err) {
    *out = NULL;
    *out_n = 0;
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
    zipw w = {z, 315532800}; /* 1980-01-01, the zip format's first day */
    for (int i = 0; i < b->topic_count; i++) {
        newer(&w.mtime, b->topics[i].creation_date);
        newer(&w.mtime, b->topics[i].modified_date);
        for (int c = 0; c < b->topics[i].comment_count; c++) {
            newer(&w.mtime, b->topics[i].comments[c].date);
            newer(&w.mtime, b->topics[i].comments[c].modified_date);
        }
    }
    size_t n = 0;
    char *doc = version_xml(ver, &n);
    bool ok = add_file(&w, "bcf.version", doc, n, err);
    if (ok && ver == MR_BCF_3_0) {
        doc = extensions_xml(b, &n);
        ok = add_file(&w, "extensions.xml", doc, n, err);
    }
    for (int i = 0; ok && i < b->topic_count; i++) ok = add_topic(&w, &b->topics[i], ver, err);
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

bool mr_bcf_write(const mr_bcf *b, mr_bcf_version ver, const char *out_path, mr_error *err) {
    void *data = NULL;
    size_t n = 0;
    bool ok = mr_bcf_write_memory(b, ver, &data, &n, err) && mr_file_write_atomic(out_path, data, n, err);
    free(data);
    return ok;
}
