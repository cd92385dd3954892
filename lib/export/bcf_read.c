/* The BCF reader: 2.0, 2.1 and 3.0, from a zip archive (libzip, in
 * memory) or an unzipped folder, into an mr_bcf. Entries are read only by
 * names made here from topic GUIDs and the file names markup.bcf gives,
 * and those are refused when they climb (".."), start at the root or hold
 * a separator; every entry is read to a size cap whatever its header says
 * (a zip bomb ends at the cap). Problems inside are warnings; the rest of
 * the archive is read. */
#include "export_internal.h"

#include <ctype.h>
#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <zip.h>

typedef struct archive {
    zip_t *zip;             /* or */
    const char *dir;        /* a folder */
    size_t total;           /* bytes read so far */
} archive;

/* True for a name that stays inside the archive's folder. */
static bool safe_name(const char *name) {
    if (!name || !name[0] || name[0] == '/' || name[0] == '\\' || strchr(name, ':')) return false;
    const char *p = name;
    while (*p) {
        const char *e = p + strcspn(p, "/\\");
        if ((e - p == 2 && p[0] == '.' && p[1] == '.') || e == p) return false;
        p = *e ? e + 1 : e;
    }
    return true;
}

/* The entry's bytes (NUL-terminated, caller frees), NULL with a reason. */
static char *read_entry(mr_bcf *b, archive *a, const char *name, size_t *size, bool quiet) {
    *size = 0;
    if (!safe_name(name)) {
        mr_bcf_warn(b, "%s: a name that leaves the archive's folder, skipped", name);
        return NULL;
    }
    size_t cap = MR_BCF_MAX_ENTRY_BYTES;
    if (a->total >= MR_BCF_MAX_TOTAL_BYTES) {
        mr_bcf_warn(b, "%s: the archive's entries exceed %u MiB in all, skipped", name, MR_BCF_MAX_TOTAL_BYTES >> 20);
        return NULL;
    }
    if (cap > MR_BCF_MAX_TOTAL_BYTES - a->total) cap = MR_BCF_MAX_TOTAL_BYTES - a->total;
    char *buf = NULL;
    size_t n = 0, bufcap = 0;
    bool too_big = false;
    if (a->zip) {
        zip_int64_t idx = zip_name_locate(a->zip, name, 0);
        if (idx < 0) {
            if (!quiet) mr_bcf_warn(b, "%s: missing", name);
            return NULL;
        }
        zip_file_t *f = zip_fopen_index(a->zip, (zip_uint64_t)idx, 0);
        if (!f) {
            mr_bcf_warn(b, "%s: %s", name, zip_strerror(a->zip));
            return NULL;
        }
        for (;;) {
            if (n + 65536 + 1 > bufcap) {
                size_t nc = bufcap ? bufcap * 2 : 65536 + 1;
                if (nc > cap + 65536 + 1) nc = cap + 65536 + 1;
                char *q = realloc(buf, nc);
                if (!q) break;
                buf = q;
                bufcap = nc;
            }
            zip_int64_t got = zip_fread(f, buf + n, 65536);
            if (got < 0) {
                mr_bcf_warn(b, "%s: %s", name, zip_file_strerror(f));
                zip_fclose(f);
                free(buf);
                return NULL;
            }
            if (got == 0) break;
            n += (size_t)got;
            if (n > cap) {
                too_big = true;
                break;
            }
        }
        zip_fclose(f);
    } else {
        char path[8192];
        snprintf(path, sizeof path, "%s/%s", a->dir, name);
        struct stat st;
        if (stat(path, &st) != 0 || !S_ISREG(st.st_mode)) {
            if (!quiet) mr_bcf_warn(b, "%s: missing", name);
            return NULL;
        }
        if ((uint64_t)st.st_size > cap) too_big = true;
        else {
            mr_error e = {0};
            buf = mr_file_read(path, &n, 0, &e);
            if (!buf) {
                mr_bcf_warn(b, "%s: %s", name, e.msg);
                return NULL;
            }
        }
    }
    if (too_big) {
        free(buf);
        mr_bcf_warn(b, "%s: larger than %zu MiB uncompressed, skipped", name, cap >> 20);
        return NULL;
    }
    if (!buf) buf = malloc(1);
    if (!buf) return NULL;
    buf[n] = 0;
    a->total += n;
    *size = n;
    return buf;
}

static mr_xml_node *read_xml(mr_bcf *b, archive *a, const char *name, bool quiet) {
    size_t n = 0;
    char *data = read_entry(b, a, name, &n, quiet);
    if (!data) return NULL;
    mr_error e = {0};
    mr_xml_node *x = mr_xml_parse(data, n, &e);
    free(data);
    if (!x) mr_bcf_warn(b, "%s: %s", name, e.msg);
    return x;
}

static void copy(char *dst, size_t n, const char *src) {
    if (!src) src = "";
    while (isspace((unsigned char)*src)) src++;
    size_t k = strnlen(src, n - 1);
    while (k > 0 && isspace((unsigned char)src[k - 1])) k--;
    memcpy(dst, src, k);
    dst[k] = 0;
}

static char *dup(const char *s) {
    size_t n = strlen(s ? s : "");
    char *d = malloc(n + 1);
    if (d) memcpy(d, s ? s : "", n + 1);
    return d;
}

/* A GUID as BCF writes it (lowercase); "" when it is not one. */
static void guid_of(char out[37], const char *s) {
    copy(out, 37, s);
    for (char *p = out; *p; p++) *p = (char)tolower((unsigned char)*p);
    if (!mr_bcf_guid_valid(out)) out[0] = 0;
}

static bool num(const char *s, double *out) {
    if (!s) return false;
    char *end = NULL;
    double v = strtod(s, &end);
    while (end && isspace((unsigned char)*end)) end++;
    if (!end || end == s || *end || !isfinite(v)) return false;
    *out = v;
    return true;
}

static bool xyz(const mr_xml_node *n, double out[3]) {
    return n && num(mr_xml_child_text(n, "X"), &out[0]) && num(mr_xml_child_text(n, "Y"), &out[1]) &&
           num(mr_xml_child_text(n, "Z"), &out[2]);
}

static bool truthy(const char *s) { return s && (strcasecmp(s, "true") == 0 || strcmp(s, "1") == 0); }

static void component_of(const mr_xml_node *c, mr_bcf_component *out) {
    memset(out, 0, sizeof *out);
    const char *g = mr_xml_get_attr(c, "IfcGuid");
    if (g && mr_ifc_guid_valid(g)) copy(out->ifc_guid, sizeof out->ifc_guid, g);
    copy(out->originating, sizeof out->originating, mr_xml_child_text(c, "OriginatingSystem"));
    copy(out->authoring_id, sizeof out->authoring_id, mr_xml_child_text(c, "AuthoringToolId"));
    /* 2.0 had AuthoringToolId as an attribute. */
    if (!out->authoring_id[0]) copy(out->authoring_id, sizeof out->authoring_id, mr_xml_get_attr(c, "AuthoringToolId"));
}

static bool components_in(const mr_xml_node *list, mr_bcf_component **arr, int *n) {
    for (int i = 0; list && i < list->child_count; i++) {
        const mr_xml_node *c = list->children[i];
        if (strcmp(c->name, "Component") != 0) continue;
        mr_bcf_component comp;
        component_of(c, &comp);
        if (!mr_bcf_add_component(arr, n, &comp)) return false;
    }
    return true;
}

static bool parse_colour(const char *s, uint32_t *argb) {
    if (!s) return false;
    size_t n = strlen(s);
    if (n != 6 && n != 8) return false;
    uint32_t v = 0;
    for (size_t i = 0; i < n; i++) {
        int c = tolower((unsigned char)s[i]);
        int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
        if (d < 0) return false;
        v = v << 4 | (uint32_t)d;
    }
    *argb = n == 6 ? 0xff000000u | v : v;
    return true;
}

static void hints(mr_bcf_viewpoint *v, const mr_xml_node *h) {
    if (!h) return;
    v->spaces_visible = truthy(mr_xml_get_attr(h, "SpacesVisible"));
    v->space_boundaries_visible = truthy(mr_xml_get_attr(h, "SpaceBoundariesVisible"));
    v->openings_visible = truthy(mr_xml_get_attr(h, "OpeningsVisible"));
}

static bool components(mr_bcf_viewpoint *v, const mr_xml_node *c, bool v20) {
    v->has_components = true;
    v->default_visibility = true;
    if (v20) {
        /* 2.0: one list of Component with Selected / Visible / Color. */
        for (int i = 0; i < c->child_count; i++) {
            const mr_xml_node *e = c->children[i];
            if (strcmp(e->name, "Component") != 0) continue;
            mr_bcf_component comp;
            component_of(e, &comp);
            uint32_t argb;
            if (truthy(mr_xml_get_attr(e, "Selected")) && !mr_bcf_add_component(&v->selection, &v->selection_count, &comp))
                return false;
            const char *vis = mr_xml_get_attr(e, "Visible");
            if (vis && !truthy(vis) && !mr_bcf_add_component(&v->exceptions, &v->exception_count, &comp)) return false;
            if (parse_colour(mr_xml_get_attr(e, "Color"), &argb)) {
                mr_bcf_coloring *col = mr_bcf_add_coloring(v, argb);
                if (!col || !mr_bcf_add_component(&col->items, &col->count, &comp)) return false;
            }
        }
        return true;
    }
    hints(v, mr_xml_child(c, "ViewSetupHints"));
    if (!components_in(mr_xml_child(c, "Selection"), &v->selection, &v->selection_count)) return false;
    const mr_xml_node *vis = mr_xml_child(c, "Visibility");
    /* The schemas' default when the attribute is absent is false. */
    v->default_visibility = vis ? truthy(mr_xml_get_attr(vis, "DefaultVisibility")) : true;
    hints(v, mr_xml_child(vis, "ViewSetupHints"));
    if (!components_in(mr_xml_child(vis, "Exceptions"), &v->exceptions, &v->exception_count)) return false;
    const mr_xml_node *col = mr_xml_child(c, "Coloring");
    for (int i = 0; col && i < col->child_count; i++) {
        const mr_xml_node *e = col->children[i];
        uint32_t argb;
        if (strcmp(e->name, "Color") != 0 || !parse_colour(mr_xml_get_attr(e, "Color"), &argb)) continue;
        mr_bcf_coloring *cc = mr_bcf_add_coloring(v, argb);
        if (!cc) return false;
        /* 2.1: Component children; 3.0: a Components list. */
        const mr_xml_node *list = mr_xml_child(e, "Components");
        if (!components_in(list ? list : e, &cc->items, &cc->count)) return false;
    }
    return true;
}

static bool camera(mr_bcf_viewpoint *v, const mr_xml_node *c, bool ortho) {
    mr_bcf_camera *k = &v->camera;
    if (!xyz(mr_xml_child(c, "CameraViewPoint"), k->view_point) || !xyz(mr_xml_child(c, "CameraDirection"), k->direction) ||
        !xyz(mr_xml_child(c, "CameraUpVector"), k->up))
        return false;
    double len = sqrt(k->direction[0] * k->direction[0] + k->direction[1] * k->direction[1] + k->direction[2] * k->direction[2]);
    if (!(len > 0)) return false;
    double a = 0;
    if (num(mr_xml_child_text(c, "AspectRatio"), &a) && a > 0) k->aspect = a;
    if (ortho) {
        double s = 0;
        if (!num(mr_xml_child_text(c, "ViewToWorldScale"), &s) || !(s > 0)) return false;
        v->view_to_world_scale = s;
        v->camera_kind = MR_BCF_CAMERA_ORTHOGONAL;
    } else {
        double f = 0;
        if (!num(mr_xml_child_text(c, "FieldOfView"), &f) || !(f > 0 && f < 180)) return false;
        k->fov_deg = f;
        v->camera_kind = MR_BCF_CAMERA_PERSPECTIVE;
    }
    return true;
}

static bool read_viewpoint(mr_bcf *b, archive *a, const char *topic, mr_bcf_viewpoint *v, bool v20) {
    char name[512];
    snprintf(name, sizeof name, "%s/%s", topic, v->file);
    mr_xml_node *x = read_xml(b, a, name, false);
    if (!x) return true;
    if (!v->guid[0]) guid_of(v->guid, mr_xml_get_attr(x, "Guid"));
    const mr_xml_node *c = mr_xml_child(x, "Components");
    bool ok = true;
    if (c) ok = components(v, c, v20);
    else v->default_visibility = true;
    const mr_xml_node *pc = mr_xml_child(x, "PerspectiveCamera"), *oc = mr_xml_child(x, "OrthogonalCamera");
    if (pc || oc) {
        if (!camera(v, pc ? pc : oc, !pc)) {
            v->camera_kind = MR_BCF_CAMERA_NONE;
            mr_bcf_warn(b, "%s: a camera with missing or bad values, ignored", name);
        }
    } else {
        mr_bcf_warn(b, "%s: names no camera", name);
    }
    const mr_xml_node *cp = mr_xml_child(x, "ClippingPlanes");
    for (int i = 0; ok && cp && i < cp->child_count; i++) {
        const mr_xml_node *p = cp->children[i];
        if (strcmp(p->name, "ClippingPlane") != 0) continue;
        mr_bcf_plane pl;
        if (!xyz(mr_xml_child(p, "Location"), pl.location) || !xyz(mr_xml_child(p, "Direction"), pl.direction)) {
            mr_bcf_warn(b, "%s: a clipping plane with missing values, ignored", name);
            continue;
        }
        mr_bcf_plane *d = realloc(v->clips, (size_t)(v->clip_count + 1) * sizeof *d);
        if (!d) {
            ok = false;
            break;
        }
        v->clips = d;
        v->clips[v->clip_count++] = pl;
    }
    mr_xml_node_free(x);
    return ok;
}

static bool read_comment(mr_bcf_topic *t, const mr_xml_node *c) {
    mr_bcf_comment *m = mr_bcf_add_comment(t);
    if (!m) return false;
    guid_of(m->guid, mr_xml_get_attr(c, "Guid"));
    copy(m->date, sizeof m->date, mr_xml_child_text(c, "Date"));
    copy(m->author, sizeof m->author, mr_xml_child_text(c, "Author"));
    copy(m->modified_date, sizeof m->modified_date, mr_xml_child_text(c, "ModifiedDate"));
    copy(m->modified_author, sizeof m->modified_author, mr_xml_child_text(c, "ModifiedAuthor"));
    guid_of(m->viewpoint_guid, mr_xml_get_attr(mr_xml_child(c, "Viewpoint"), "Guid"));
    free(m->text);
    m->text = dup(mr_xml_child_text(c, "Comment"));
    return m->text != NULL;
}

/* A viewpoint reference of markup.bcf (2.x Viewpoints, 3.0 ViewPoint). */
static bool viewpoint_ref(mr_bcf *b, mr_bcf_topic *t, const mr_xml_node *r, const char *topic) {
    const char *file = mr_xml_child_text(r, "Viewpoint");
    char fname[128];
    copy(fname, sizeof fname, file);
    if (!fname[0]) return true; /* a reference without a file has nothing to show */
    if (!safe_name(fname) || strchr(fname, '/') || strchr(fname, '\\')) {
        mr_bcf_warn(b, "topic %s: viewpoint file \"%s\" leaves the topic's folder, skipped", topic, fname);
        return true;
    }
    mr_bcf_viewpoint *v = mr_bcf_add_viewpoint(t);
    if (!v) return false;
    copy(v->file, sizeof v->file, fname);
    guid_of(v->guid, mr_xml_get_attr(r, "Guid"));
    double idx = 0;
    if (num(mr_xml_child_text(r, "Index"), &idx) && idx >= 0 && idx < 1e9) v->index = (int)idx;
    copy(v->snapshot_name, sizeof v->snapshot_name, mr_xml_child_text(r, "Snapshot"));
    return true;
}

static bool read_topic(mr_bcf *b, archive *a, const char *folder, bool v20) {
    char name[512];
    snprintf(name, sizeof name, "%s/markup.bcf", folder);
    mr_xml_node *x = read_xml(b, a, name, true);
    if (!x) {
        mr_bcf_warn(b, "topic %s: no readable markup.bcf, skipped", folder);
        return true;
    }
    const mr_xml_node *tp = mr_xml_child(x, "Topic");
    char g[37];
    guid_of(g, tp ? mr_xml_get_attr(tp, "Guid") : NULL);
    if (!tp || !g[0]) {
        mr_bcf_warn(b, "topic %s: markup.bcf has no Topic with a GUID, skipped", folder);
        mr_xml_node_free(x);
        return true;
    }
    for (int i = 0; i < b->topic_count; i++)
        if (strcmp(b->topics[i].guid, g) == 0) {
            mr_bcf_warn(b, "topic %s: a second topic with GUID %s, skipped", folder, g);
            mr_xml_node_free(x);
            return true;
        }
    mr_bcf_topic *t = mr_bcf_add_topic(b);
    if (!t) {
        mr_xml_node_free(x);
        return false;
    }
    memcpy(t->guid, g, sizeof g);
    copy(t->type, sizeof t->type, mr_xml_get_attr(tp, "TopicType"));
    copy(t->status, sizeof t->status, mr_xml_get_attr(tp, "TopicStatus"));
    copy(t->title, sizeof t->title, mr_xml_child_text(tp, "Title"));
    copy(t->priority, sizeof t->priority, mr_xml_child_text(tp, "Priority"));
    double idx = 0;
    if (num(mr_xml_child_text(tp, "Index"), &idx) && idx >= 0 && idx < 1e9) t->index = (int)idx;
    copy(t->creation_date, sizeof t->creation_date, mr_xml_child_text(tp, "CreationDate"));
    copy(t->creation_author, sizeof t->creation_author, mr_xml_child_text(tp, "CreationAuthor"));
    copy(t->modified_date, sizeof t->modified_date, mr_xml_child_text(tp, "ModifiedDate"));
    copy(t->modified_author, sizeof t->modified_author, mr_xml_child_text(tp, "ModifiedAuthor"));
    copy(t->due_date, sizeof t->due_date, mr_xml_child_text(tp, "DueDate"));
    copy(t->assigned_to, sizeof t->assigned_to, mr_xml_child_text(tp, "AssignedTo"));
    copy(t->stage, sizeof t->stage, mr_xml_child_text(tp, "Stage"));
    const char *d = mr_xml_child_text(tp, "Description");
    if (d) t->description = dup(d);
    bool ok = !d || t->description;
    for (int i = 0; i < tp->child_count; i++) {
        const mr_xml_node *l = tp->children[i];
        if (strcmp(l->name, "Labels") != 0) continue;
        const mr_xml_node *inner = mr_xml_child(l, "Label");
        if (!inner && t->label_count < MR_BCF_MAX_LABELS) copy(t->labels[t->label_count++], sizeof t->labels[0], l->text);
        for (int k = 0; k < l->child_count && t->label_count < MR_BCF_MAX_LABELS; k++)
            if (strcmp(l->children[k]->name, "Label") == 0)
                copy(t->labels[t->label_count++], sizeof t->labels[0], l->children[k]->text);
    }
    /* Comments and viewpoint references: 2.x beside Topic, 3.0 inside it. */
    const mr_xml_node *cl = mr_xml_child(tp, "Comments");
    const mr_xml_node *owner = cl ? cl : x;
    for (int i = 0; ok && i < owner->child_count; i++)
        if (strcmp(owner->children[i]->name, "Comment") == 0) ok = read_comment(t, owner->children[i]);
    const mr_xml_node *vl = mr_xml_child(tp, "Viewpoints");
    if (vl && vl->child_count > 0 && mr_xml_child(vl, "ViewPoint")) {
        for (int i = 0; ok && i < vl->child_count; i++)
            if (strcmp(vl->children[i]->name, "ViewPoint") == 0) ok = viewpoint_ref(b, t, vl->children[i], g);
    } else {
        for (int i = 0; ok && i < x->child_count; i++)
            if (strcmp(x->children[i]->name, "Viewpoints") == 0) ok = viewpoint_ref(b, t, x->children[i], g);
    }
    mr_xml_node_free(x);
    /* 2.0 archives may list no viewpoint but carry the default one. */
    if (ok && t->viewpoint_count == 0) {
        snprintf(name, sizeof name, "%s/viewpoint.bcfv", folder);
        size_t n = 0;
        char *probe = read_entry(b, a, name, &n, true);
        if (probe) {
            free(probe);
            mr_bcf_viewpoint *v = mr_bcf_add_viewpoint(t);
            if (!v) return false;
            snprintf(v->file, sizeof v->file, "viewpoint.bcfv");
            snprintf(name, sizeof name, "%s/snapshot.png", folder);
            probe = read_entry(b, a, name, &n, true);
            if (probe) snprintf(v->snapshot_name, sizeof v->snapshot_name, "snapshot.png");
            free(probe);
        }
    }
    for (int i = 0; ok && i < t->viewpoint_count; i++) {
        mr_bcf_viewpoint *v = &t->viewpoints[i];
        ok = read_viewpoint(b, a, folder, v, v20);
        for (int k = 0; k < i && v->guid[0]; k++)
            if (strcmp(t->viewpoints[k].guid, v->guid) == 0) v->guid[0] = 0; /* a copy's GUID: a new one */
        if (!v->guid[0]) {
            /* A viewpoint needs an identity to be written back. */
            char key[600];
            snprintf(key, sizeof key, "%s/%s/%d", t->guid, v->file, i);
            mr_bcf_guid(key, strlen(key), 4, v->guid);
        }
        if (v->snapshot_name[0]) {
            if (!safe_name(v->snapshot_name) || strchr(v->snapshot_name, '/') || strchr(v->snapshot_name, '\\')) {
                mr_bcf_warn(b, "topic %s: snapshot \"%s\" leaves the topic's folder, skipped", t->guid, v->snapshot_name);
                v->snapshot_name[0] = 0;
                continue;
            }
            snprintf(name, sizeof name, "%s/%s", folder, v->snapshot_name);
            size_t n = 0;
            v->snapshot = (unsigned char *)read_entry(b, a, name, &n, false);
            v->snapshot_size = v->snapshot ? n : 0;
        }
    }
    for (int i = 0; i < t->comment_count; i++)
        if (!t->comments[i].guid[0]) {
            char key[100];
            snprintf(key, sizeof key, "%s/comment/%d", t->guid, i);
            mr_bcf_guid(key, strlen(key), 5, t->comments[i].guid);
        }
    return ok;
}

static int by_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* The topic folders: first path components that are GUID-shaped names
 * (any case) holding a markup.bcf, or, for a folder, subfolders. */
static bool read_all(archive *a, mr_bcf *b, mr_error *err) {
    mr_xml_node *ver = read_xml(b, a, "bcf.version", true);
    const char *vid = ver ? mr_xml_get_attr(ver, "VersionId") : NULL;
    copy(b->version, sizeof b->version, vid);
    mr_xml_node_free(ver);
    if (!b->version[0]) {
        mr_bcf_warn(b, "bcf.version: missing or unreadable, read as 2.1");
        snprintf(b->version, sizeof b->version, "2.1");
    }
    bool v20 = strncmp(b->version, "2.0", 3) == 0;
    if (!v20 && strncmp(b->version, "2.1", 3) != 0 && strncmp(b->version, "3.0", 3) != 0)
        return mr_fail(err, MR_ERR_PARSE, "BCF version \"%s\" is not one this reader knows (2.0, 2.1, 3.0)", b->version);
    char **names = NULL;
    int count = 0;
    bool ok = true;
    if (a->zip) {
        zip_int64_t n = zip_get_num_entries(a->zip, 0);
        if (n > MR_BCF_MAX_ENTRIES) {
            mr_bcf_warn(b, "the archive has %lld entries: only the first %d are looked at", (long long)n, MR_BCF_MAX_ENTRIES);
            n = MR_BCF_MAX_ENTRIES;
        }
        for (zip_int64_t i = 0; ok && i < n; i++) {
            const char *nm = zip_get_name(a->zip, (zip_uint64_t)i, 0);
            if (!nm) continue;
            if (!safe_name(nm)) {
                mr_bcf_warn(b, "entry \"%.200s\": a name that leaves the archive's folder, skipped", nm);
                continue;
            }
            /* Every top folder is a topic (3.0's Documents aside): one
             * without a markup.bcf is reported, not silently dropped. */
            const char *slash = strchr(nm, '/');
            if (!slash || ((size_t)(slash - nm) == 9 && strncmp(nm, "Documents", 9) == 0)) continue;
            if (count > 0 && strncmp(names[count - 1], nm, (size_t)(slash - nm)) == 0 &&
                names[count - 1][slash - nm] == 0)
                continue;
            size_t len = (size_t)(slash - nm);
            char *folder = malloc(len + 1);
            char **grown = realloc(names, (size_t)(count + 1) * sizeof *names);
            if (!folder || !grown) {
                free(folder);
                ok = false;
                break;
            }
            names = grown;
            memcpy(folder, nm, len);
            folder[len] = 0;
            names[count++] = folder;
        }
    } else {
        DIR *d = opendir(a->dir);
        struct dirent *e;
        while (ok && d && (e = readdir(d))) {
            if (e->d_name[0] == '.') continue;
            char p[8192];
            struct stat st;
            snprintf(p, sizeof p, "%s/%s", a->dir, e->d_name);
            if (stat(p, &st) != 0 || !S_ISDIR(st.st_mode) || strcmp(e->d_name, "Documents") == 0) continue;
            char **grown = realloc(names, (size_t)(count + 1) * sizeof *names);
            char *folder = dup(e->d_name);
            if (!grown || !folder) {
                free(folder);
                if (grown) names = grown;
                ok = false;
                break;
            }
            names = grown;
            names[count++] = folder;
        }
        if (d) closedir(d);
    }
    /* A folder lists in no fixed order: by name, so runs agree; a zip's
     * folders may repeat when its entries are not grouped. */
    if (count > 1) qsort(names, (size_t)count, sizeof *names, by_name); /* names is NULL when empty */
    int kept = 0;
    for (int i = 0; i < count; i++) {
        if (kept > 0 && strcmp(names[kept - 1], names[i]) == 0) free(names[i]);
        else names[kept++] = names[i];
    }
    count = kept;
    for (int i = 0; ok && i < count; i++) ok = read_topic(b, a, names[i], v20);
    for (int i = 0; i < count; i++) free(names[i]);
    free(names);
    if (!ok) return mr_fail(err, MR_ERR_NOMEM, "out of memory reading the BCF");
    if (b->topic_count == 0) return mr_fail(err, MR_ERR_PARSE, "no readable topic in the archive");
    /* Topics in their Index order where they have one, then by GUID. */
    return true;
}

bool mr_bcf_read_memory(const void *data, size_t size, mr_bcf *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    zip_error_t ze;
    zip_error_init(&ze);
    zip_source_t *src = zip_source_buffer_create(data, size, 0, &ze);
    zip_t *z = src ? zip_open_from_source(src, ZIP_RDONLY, &ze) : NULL;
    if (!z) {
        bool r = mr_fail(err, MR_ERR_PARSE, "not a zip archive (%s)", zip_error_strerror(&ze));
        if (src) zip_source_free(src);
        zip_error_fini(&ze);
        return r;
    }
    archive a = {z, NULL, 0};
    bool ok = read_all(&a, out, err);
    zip_discard(z);
    if (!ok) mr_bcf_free(out);
    return ok;
}

bool mr_bcf_read(const char *path, mr_bcf *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    struct stat st;
    if (stat(path, &st) != 0) return mr_fail(err, MR_ERR_IO, "%s: cannot open", path);
    if (S_ISDIR(st.st_mode)) {
        archive a = {NULL, path, 0};
        bool ok = read_all(&a, out, err);
        if (!ok) {
            mr_bcf_free(out);
            mr_error_prefix(err, "%s", path);
        }
        return ok;
    }
    /* The archive's compressed size is capped like an entry's. */
    if ((uint64_t)st.st_size > MR_BCF_MAX_TOTAL_BYTES)
        return mr_fail(err, MR_ERR_INVALID, "%s: larger than %u MiB", path, MR_BCF_MAX_TOTAL_BYTES >> 20);
    size_t n = 0;
    char *data = mr_file_read(path, &n, 0, err);
    if (!data) return false;
    bool ok = mr_bcf_read_memory(data, n, out, err);
    free(data);
    if (!ok) mr_error_prefix(err, "%s", path);
    return ok;
}
