/* lib/export: the BCF camera (Y up -> Z up, centred frustum, field of view
 * per version), the undistorted snapshot, and the round trip: archives of
 * both versions read back with libzip and a small reader here (entries,
 * directory entries, element order, required elements, titles, camera
 * within 1 mm / 0.01 degrees); bad input fails with nothing written. */
#include "mr_export.h"
#include "mr_test.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zip.h>

static char g_tmp[1024];

/* ------------------------------------------------------- the tiny reader */

/* The first "<tag" (followed by space, '>' or '/') at or after s; NULL none. */
static const char *find_tag(const char *s, const char *tag) {
    size_t n = strlen(tag);
    for (const char *p = s; p && (p = strchr(p, '<')); p++)
        if (strncmp(p + 1, tag, n) == 0 && (p[1 + n] == ' ' || p[1 + n] == '>' || p[1 + n] == '/')) return p;
    return NULL;
}

/* The unescaped text of <tag>...</tag> at or after s into out. */
static bool tag_text(const char *s, const char *tag, char *out, size_t n) {
    const char *p = s ? find_tag(s, tag) : NULL;
    if (!p) return false;
    p = strchr(p, '>');
    if (!p || p[-1] == '/') return false;
    p++;
    char close[64];
    snprintf(close, sizeof close, "</%s>", tag);
    const char *e = strstr(p, close);
    if (!e) return false;
    size_t k = 0;
    while (p < e && k + 1 < n) {
        static const struct { const char *ent; char c; } ents[] = {
            {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
        bool done = false;
        for (size_t i = 0; i < 5 && !done; i++)
            if (strncmp(p, ents[i].ent, strlen(ents[i].ent)) == 0) {
                out[k++] = ents[i].c;
                p += strlen(ents[i].ent);
                done = true;
            }
        if (!done) out[k++] = *p++;
    }
    out[k] = 0;
    return true;
}

static bool tag_num(const char *s, const char *tag, double *v) {
    char t[64];
    if (!tag_text(s, tag, t, sizeof t)) return false;
    char *end;
    *v = strtod(t, &end);
    return end != t && *end == 0;
}

static bool tag_xyz(const char *doc, const char *tag, double v[3]) {
    const char *p = find_tag(doc, tag);
    return p && tag_num(p, "X", &v[0]) && tag_num(p, "Y", &v[1]) && tag_num(p, "Z", &v[2]);
}

/* An attribute's value of the element at p. */
static bool attr(const char *p, const char *name, char *out, size_t n) {
    const char *e = p ? strchr(p, '>') : NULL;
    char key[64];
    snprintf(key, sizeof key, " %s=\"", name);
    const char *a = p ? strstr(p, key) : NULL;
    if (!a || a > e) return false;
    a += strlen(key);
    const char *q = strchr(a, '"');
    if (!q || (size_t)(q - a) >= n) return false;
    memcpy(out, a, (size_t)(q - a));
    out[q - a] = 0;
    return true;
}

/* Each tag appears, in this order, after s (and before limit if given). */
static bool in_order(const char *s, const char *limit, const char *const *tags, int n) {
    const char *p = s;
    for (int i = 0; i < n; i++) {
        const char *q = find_tag(p, tags[i]);
        if (!q || (limit && q > limit)) {
            fprintf(stderr, "  tag <%s> missing or out of order\n", tags[i]);
            return false;
        }
        p = q + 1;
    }
    return true;
}

static bool is_lower_guid(const char *g) {
    if (strlen(g) != 36) return false;
    for (int i = 0; i < 36; i++) {
        bool dash = i == 8 || i == 13 || i == 18 || i == 23;
        if (dash ? g[i] != '-' : !(isdigit((unsigned char)g[i]) || (g[i] >= 'a' && g[i] <= 'f'))) return false;
    }
    return true;
}

/* A zip entry's bytes (NUL-terminated) or NULL. */
static char *zip_read(zip_t *z, const char *name, size_t *n) {
    zip_stat_t st;
    if (zip_stat(z, name, 0, &st) != 0) return NULL;
    zip_file_t *f = zip_fopen(z, name, 0);
    if (!f) return NULL;
    char *b = malloc(st.size + 1);
    zip_int64_t r = b ? zip_fread(f, b, st.size) : -1;
    zip_fclose(f);
    if (r != (zip_int64_t)st.size) {
        free(b);
        return NULL;
    }
    b[st.size] = 0;
    if (n) *n = st.size;
    return b;
}

/* ---------------------------------------------------------- the fixture */

static mr_camera test_camera(void) {
    mr_camera c = {.width = 160, .height = 120, .fx = 100, .fy = 100, .cx = 79.5, .cy = 59.5};
    return c;
}

/* A camera at eye looking at target (glTF, Y up). */
static mr_dmat4 pose_at(double ex, double ey, double ez, double tx, double ty, double tz) {
    return mr_m4_look_at_cv(mr_v3(ex, ey, ez), mr_v3(tx, ty, tz), mr_v3(0, 1, 0));
}

/* issue 15: a measurement the next write_mark carries (NULL: none). */
static const mr_measurement *g_mark_measure;
static const mr_verdict *g_mark_verdict;     /* with g_mark_measure: its verdict */

static const char k_pipe_guid[] = "2O2Fr$t4X7Zf8NOew3FLOH";

/* The viewpoint's Components as buildingSMART's visinfo.xsd orders them:
 * 2.1 ViewSetupHints, Selection, Visibility, Coloring (Color holds
 * Component); 3.0 Selection, Visibility (holding ViewSetupHints), Coloring
 * (Color holds Components). The marked element is the selected and
 * coloured component: IfcGuid (22 chars of IFC's base64) where the model
 * has one, else AuthoringToolId = its name. Colours are 6 or 8 hex digits. */
static void check_components(const char *vp, mr_bcf_version v, int k) {
    const char *comps = find_tag(vp, "Components");
    CHECK_MSG(comps && comps < find_tag(vp, "PerspectiveCamera"), "Components before the camera");
    if (!comps) return;
    static const char *const o21[] = {"Components", "ViewSetupHints", "Selection", "Component", "Visibility",
                                      "Coloring", "Color", "Component"};
    static const char *const o30[] = {"Components", "Selection", "Component", "Visibility", "ViewSetupHints",
                                      "Coloring", "Color", "Components", "Component"};
    if (v == MR_BCF_3_0) CHECK(in_order(vp, NULL, o30, 9));
    else CHECK(in_order(vp, NULL, o21, 8));
    char dv[16] = "", col[16] = "", g[64] = "", tool[160] = "", sys[64] = "";
    CHECK(attr(find_tag(vp, "Visibility"), "DefaultVisibility", dv, sizeof dv) && strcmp(dv, "true") == 0);
    CHECK(attr(find_tag(vp, "Color"), "Color", col, sizeof col));
    size_t cl = strlen(col);
    CHECK_MSG(cl == 6 || cl == 8, "colour %s", col);
    for (size_t i = 0; i < cl; i++) CHECK(strchr("0123456789ABCDEF", col[i]) != NULL);
    const char *sel = find_tag(vp, "Selection");
    const char *c = find_tag(sel, "Component");
    bool has_guid = attr(c, "IfcGuid", g, sizeof g);
    tag_text(c, "OriginatingSystem", sys, sizeof sys);
    CHECK(strcmp(sys, "mrcheck") == 0);
    if (k == 0) {
        CHECK_MSG(has_guid && strcmp(g, k_pipe_guid) == 0, "IfcGuid %s", g);
        CHECK(strlen(g) == 22 && strspn(g, "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_$") == 22);
    } else {
        CHECK(!has_guid);
        CHECK(tag_text(c, "AuthoringToolId", tool, sizeof tool) && strcmp(tool, "Conveyor_2") == 0);
    }
    /* The coloured component is the selected one. */
    const char *cc = find_tag(find_tag(vp, "Color"), "Component");
    char g2[64] = "";
    CHECK(cc && (attr(cc, "IfcGuid", g2, sizeof g2) == has_guid) && strcmp(g, g2) == 0);
}

static bool write_mark(const char *dir, int i, const char *note, const mr_dmat4 *pose, double dist, double unc) {
    mr_camera cam = test_camera();
    mr_image img;
    if (!mr_image_alloc(&img, cam.width, cam.height, 3, MR_PIX_U8, NULL)) return false;
    uint8_t *p = img.data;
    for (int y = 0; y < img.height; y++)
        for (int x = 0; x < img.width; x++) {
            p[(y * img.width + x) * 3 + 0] = (uint8_t)(x * 255 / img.width);
            p[(y * img.width + x) * 3 + 1] = (uint8_t)(y * 255 / img.height);
            p[(y * img.width + x) * 3 + 2] = (uint8_t)(40 * i);
        }
    mr_annotation m;
    memset(&m, 0, sizeof m);
    snprintf(m.type, sizeof m.type, "discrepancy");
    m.time_unix = 1764619200 + i; /* 2025-12-01T20:00:00Z + i */
    m.frame_index = 10 * i;
    m.timestamp = i;
    snprintf(m.note, sizeof m.note, "%s", note);
    m.has_pixel = true;
    m.pixel[0] = 80;
    m.pixel[1] = 60;
    m.hit = true;
    m.world[0] = 1, m.world[1] = 1, m.world[2] = 1;
    m.depth = 3.5;
    m.node_index = -1;
    /* Mark 1 is on an IFC element, mark 2 on a part of a model without
     * IFC identity. */
    if (i == 1) {
        snprintf(m.node, sizeof m.node, "Pipe_1");
        m.node_index = 3;
        snprintf(m.element_guid, sizeof m.element_guid, "%s", k_pipe_guid);
        snprintf(m.element_class, sizeof m.element_class, "IfcPipeSegment");
        snprintf(m.element_name, sizeof m.element_name, "Pipe_1");
    } else if (i == 2) {
        snprintf(m.node, sizeof m.node, "Conveyor_2");
        m.node_index = 4;
        snprintf(m.element_name, sizeof m.element_name, "Conveyor_2");
    }
    m.has_pose = m.pose_valid = true;
    m.world_from_camera = *pose;
    m.pose_tags_seen = 3;
    m.pose_rms_px = 0.4;
    if (g_mark_measure) {
        m.has_measurement = true;
        m.measurement = *g_mark_measure;
        m.has_verdict = g_mark_verdict != NULL;
        if (g_mark_verdict) m.verdict = *g_mark_verdict;
    }
    char stem[32];
    snprintf(stem, sizeof stem, "mark_%04d", i);
    mr_mark_files fl = {.stem = stem, .frame = &img, .screen = &img, .camera = &cam, .distance_m = dist,
                        .uncertainty_m = unc};
    mr_error err = {0};
    bool ok = mr_export_mark_write(dir, &m, &fl, &err);
    CHECK_MSG(ok, "mark_write: %s", err.msg);
    mr_image_free(&img);
    return ok;
}

/* ----------------------------------------------------------------- tests */

static void test_camera_conversion(void) {
    /* At glTF (1, 2, 3) looking along -Z, up +Y: BCF (1, -3, 2), looking
     * along +Y, up +Z. */
    mr_dmat4 wc = pose_at(1, 2, 3, 1, 2, -10);
    mr_camera cam = test_camera();
    mr_bcf_frame fr;
    mr_error err = {0};
    CHECK(mr_bcf_frame_of(&cam, 1500, &fr, &err));
    CHECK(fr.width == 160 && fr.height == 120);
    CHECK_NEAR(fr.f, 100, 1e-12);
    mr_bcf_camera c2 = mr_bcf_camera_of(&wc, &fr, 1, MR_BCF_2_1);
    double want_p[3] = {1, -3, 2}, want_d[3] = {0, 1, 0}, want_u[3] = {0, 0, 1};
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(c2.view_point[k], want_p[k], 1e-12);
        CHECK_NEAR(c2.direction[k], want_d[k], 1e-12);
        CHECK_NEAR(c2.up[k], want_u[k], 1e-12);
    }
    CHECK_NEAR(c2.fov_deg, 2 * atan(80.0 / 100) * 180 / M_PI, 1e-9); /* horizontal */
    mr_bcf_camera c3 = mr_bcf_camera_of(&wc, &fr, 1, MR_BCF_3_0);
    CHECK_NEAR(c3.fov_deg, 2 * atan(60.0 / 100) * 180 / M_PI, 1e-9); /* vertical */
    CHECK_NEAR(c3.aspect, 160.0 / 120, 1e-12);
    /* A camera looking down at 45 degrees towards +X: direction (1, 0, -1)/sqrt2
     * in BCF, up (1, 0, 1)/sqrt2; units in millimetres scale the position. */
    wc = pose_at(0, 5, 0, 5, 0, 0);
    mr_bcf_camera c = mr_bcf_camera_of(&wc, &fr, 0.001, MR_BCF_2_1);
    CHECK_NEAR(c.view_point[2], 0.005, 1e-15);
    CHECK_NEAR(c.direction[0], M_SQRT1_2, 1e-12);
    CHECK_NEAR(c.direction[2], -M_SQRT1_2, 1e-12);
    CHECK_NEAR(c.up[0], M_SQRT1_2, 1e-12);
    CHECK_NEAR(c.up[2], M_SQRT1_2, 1e-12);
    CHECK_NEAR(c.direction[1], 0, 1e-12);
    /* Off-centre principal point: the centred frustum is narrower. */
    cam.cx = 69.5;
    CHECK(mr_bcf_frame_of(&cam, 1500, &fr, &err));
    CHECK(fr.width == 140 && fr.height == 120);
    /* The long side is capped; the field of view stays. */
    cam = test_camera();
    CHECK(mr_bcf_frame_of(&cam, 80, &fr, &err));
    CHECK(fr.width == 80 && fr.height == 60);
    CHECK_NEAR(mr_bcf_camera_of(&wc, &fr, 1, MR_BCF_2_1).fov_deg, 2 * atan(0.8) * 180 / M_PI, 1e-9);
    /* A principal point outside the image: no view. */
    cam.cx = -5;
    CHECK(!mr_bcf_frame_of(&cam, 1500, &fr, &err));
    /* Far from the origin: still exact to well below a millimetre. */
    wc = pose_at(1e7 + 0.25, 3, -2e6, 1e7, 3, -2e6 - 5);
    c = mr_bcf_camera_of(&wc, &fr, 1, MR_BCF_2_1);
    CHECK_NEAR(c.view_point[0], 1e7 + 0.25, 1e-6);
    CHECK_NEAR(c.view_point[1], 2e6, 1e-6);
}

/* The snapshot undoes the lens: a source whose value is a linear function
 * of the undistorted x gives a snapshot linear in its own pixel x. */
static void test_undistort(void) {
    mr_camera cam = {.width = 200, .height = 150, .fx = 120, .fy = 118, .cx = 103.0, .cy = 72.0,
                     .dist = {-0.25, 0.08, 0.001, -0.001, 0}};
    mr_image src;
    CHECK(mr_image_alloc(&src, cam.width, cam.height, 1, MR_PIX_U8, NULL));
    uint8_t *p = src.data;
    for (int v = 0; v < src.height; v++)
        for (int u = 0; u < src.width; u++) {
            double x = 0, y = 0;
            mr_camera_undistort(&cam, (u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, &x, &y);
            double g = 128 + 120 * x;
            p[v * src.width + u] = (uint8_t)(g < 0 ? 0 : g > 255 ? 255 : g + 0.5);
        }
    mr_bcf_frame fr;
    mr_error err = {0};
    CHECK(mr_bcf_frame_of(&cam, 1500, &fr, &err));
    /* Barrel distortion: the undistorted view is wider than the raw image. */
    CHECK_MSG(fr.width > 200 && fr.width < 260 && fr.height > 150 && fr.height < 190, "%dx%d f %g", fr.width,
              fr.height, fr.f);
    mr_image out;
    CHECK(mr_bcf_snapshot(&src, &cam, &fr, &out, &err));
    double worst = 0;
    const uint8_t *o = out.data;
    for (int j = 0; j < out.height; j++)
        for (int i = 0; i < out.width; i++) {
            double x = (i + 0.5 - out.width * 0.5) / fr.f;
            double g = 128 + 120 * x;
            if (g < 2 || g > 253) continue;
            worst = fmax(worst, fabs(o[j * out.width + i] - g));
        }
    CHECK_MSG(worst < 2.5, "largest error %.2f grey levels", worst);
    mr_image_free(&out);
    mr_image_free(&src);
}

/* Every Guid="..." attribute of doc, with what it names: a viewpoint's
 * Guid appears where it is defined and where it is referred to
 * (Viewpoints, ViewPoint, Viewpoint, VisualizationInfo); a topic's and a
 * comment's once. Two different things (or two topics' things) sharing a
 * GUID is a broken archive for any BCF reader. */
typedef struct {
    char guid[40];
    char kind[24];
    int topic;
} guid_use;

static int collect_guids(const char *doc, int topic, guid_use *u, int n, int cap) {
    for (const char *p = doc; (p = strstr(p, " Guid=\"")) && n < cap; p++) {
        const char *lt = p;
        while (lt > doc && *lt != '<') lt--;
        char elem[24] = "";
        size_t k = 0;
        for (const char *q = lt + 1; q < p && k + 1 < sizeof elem && *q != ' '; q++) elem[k++] = *q;
        elem[k] = 0;
        bool vp = strcmp(elem, "Viewpoints") == 0 || strcmp(elem, "ViewPoint") == 0 || strcmp(elem, "Viewpoint") == 0 ||
                  strcmp(elem, "VisualizationInfo") == 0;
        snprintf(u[n].kind, sizeof u[n].kind, "%s", vp ? "viewpoint" : elem);
        const char *a = p + 7, *e = strchr(a, '"');
        size_t l = e ? (size_t)(e - a) : 0;
        if (l >= sizeof u[n].guid) l = sizeof u[n].guid - 1;
        memcpy(u[n].guid, a, l);
        u[n].guid[l] = 0;
        u[n].topic = topic;
        n++;
    }
    return n;
}

/* The GUIDs of distinct things are distinct: one GUID, one thing. */
static void check_guids_distinct(const guid_use *u, int n) {
    int things = 0;
    for (int i = 0; i < n; i++) {
        CHECK_MSG(is_lower_guid(u[i].guid), "%s Guid '%s'", u[i].kind, u[i].guid);
        bool first = true;
        for (int j = 0; j < i; j++)
            if (strcmp(u[i].guid, u[j].guid) == 0) {
                first = false;
                CHECK_MSG(strcmp(u[i].kind, u[j].kind) == 0 && u[i].topic == u[j].topic,
                          "GUID %s names a %s of topic %d and a %s of topic %d", u[i].guid, u[i].kind, u[i].topic,
                          u[j].kind, u[j].topic);
            }
        things += first;
    }
    CHECK_MSG(things >= 3, "only %d distinct GUIDs", things);
}

static void check_archive(const char *path, mr_bcf_version v, const mr_dmat4 *poses, const char *const *titles,
                          int n, bool descs) {
    int ze = 0;
    zip_t *z = zip_open(path, ZIP_RDONLY, &ze);
    CHECK_MSG(z != NULL, "cannot open %s", path);
    if (!z) return;
    char *ver = zip_read(z, "bcf.version", NULL);
    CHECK(ver && find_tag(ver, "Version"));
    char vid[16] = "";
    CHECK(attr(find_tag(ver, "Version"), "VersionId", vid, sizeof vid));
    CHECK(strcmp(vid, v == MR_BCF_3_0 ? "3.0" : "2.1") == 0);
    free(ver);
    char *ext = zip_read(z, "extensions.xml", NULL);
    CHECK((ext != NULL) == (v == MR_BCF_3_0));
    if (ext) {
        static const char *const order[] = {"Extensions", "TopicTypes", "TopicType", "TopicStatuses", "TopicStatus"};
        CHECK(in_order(ext, NULL, order, 5));
        char st[32];
        CHECK(tag_text(ext, "TopicStatus", st, sizeof st) && strcmp(st, "Open") == 0);
    }
    free(ext);
    /* Topic folders: a directory entry each, forward slashes only. */
    int topics = 0, dirs = 0;
    zip_int64_t entries = zip_get_num_entries(z, 0);
    for (zip_int64_t i = 0; i < entries; i++) {
        const char *name = zip_get_name(z, (zip_uint64_t)i, 0);
        CHECK(name && !strchr(name, '\\'));
        size_t l = name ? strlen(name) : 0;
        if (l == 37 && name[36] == '/') {
            dirs++;
            char guid[37];
            memcpy(guid, name, 36);
            guid[36] = 0;
            CHECK_MSG(is_lower_guid(guid), "folder %s", name);
        }
    }
    CHECK(dirs == n);
    guid_use guids[64];
    int nguid = 0;
    for (zip_int64_t i = 0; i < entries; i++) {
        const char *name = zip_get_name(z, (zip_uint64_t)i, 0);
        if (!name || strlen(name) != 37 || name[36] != '/') continue;
        char fpath[128];
        snprintf(fpath, sizeof fpath, "%smarkup.bcf", name);
        char *mk = zip_read(z, fpath, NULL);
        snprintf(fpath, sizeof fpath, "%sviewpoint.bcfv", name);
        char *vp = zip_read(z, fpath, NULL);
        snprintf(fpath, sizeof fpath, "%ssnapshot.png", name);
        size_t pn = 0;
        char *png = zip_read(z, fpath, &pn);
        CHECK(mk && vp && png);
        if (!mk || !vp || !png) {
            free(mk), free(vp), free(png);
            continue;
        }
        nguid = collect_guids(mk, (int)i, guids, nguid, 64);
        nguid = collect_guids(vp, (int)i, guids, nguid, 64);
        /* Which mark: the title. */
        char title[160] = "";
        CHECK(tag_text(mk, "Title", title, sizeof title));
        int k = -1;
        for (int t = 0; t < n; t++)
            if (strcmp(title, titles[t]) == 0) k = t;
        CHECK_MSG(k >= 0, "title '%s' is none of the marks", title);
        if (k >= 0) topics++;
        const char *topic = find_tag(mk, "Topic");
        char g[64] = "", st[32] = "", ty[32] = "";
        CHECK(attr(topic, "Guid", g, sizeof g) && strncmp(g, name, 36) == 0);
        CHECK(attr(topic, "TopicStatus", st, sizeof st) && strcmp(st, "Open") == 0);
        CHECK(attr(topic, "TopicType", ty, sizeof ty));
        const char *topic_end = strstr(mk, "</Topic>");
        CHECK(topic_end != NULL);
        static const char *const torder[] = {"Topic", "Title", "CreationDate", "CreationAuthor", "Description"};
        CHECK(in_order(mk, topic_end, torder, 5));
        char date[40];
        CHECK(tag_text(mk, "CreationDate", date, sizeof date) && strlen(date) == 20 && date[19] == 'Z');
        char desc[600];
        CHECK(tag_text(mk, "Description", desc, sizeof desc));
        if (descs && k == 0) CHECK_MSG(strstr(desc, "42 mm") && strstr(desc, "5 mm"), "description: %s", desc);
        if (descs && k == 1) CHECK_MSG(strstr(desc, "not measured") && strstr(desc, "not available"), "description: %s", desc);
        const char *vps = find_tag(mk, "Viewpoints");
        CHECK(vps != NULL);
        if (v == MR_BCF_3_0) {
            /* 3.0: Comments and Viewpoints are lists inside Topic. */
            CHECK(vps && vps < topic_end);
            static const char *const o3[] = {"Description", "Comments", "Comment", "Viewpoints", "ViewPoint",
                                             "Viewpoint", "Snapshot"};
            CHECK(in_order(mk, topic_end, o3, 7));
        } else {
            CHECK(vps && vps > topic_end);
            static const char *const o2[] = {"Topic", "Comment", "Viewpoints", "Viewpoint", "Snapshot"};
            CHECK(in_order(mk, NULL, o2, 5));
            CHECK(find_tag(topic_end, "Comment") < vps);
        }
        char vg[64] = "", vg2[64] = "", file[64] = "";
        const char *vref = v == MR_BCF_3_0 ? find_tag(mk, "ViewPoint") : vps;
        CHECK(attr(vref, "Guid", vg, sizeof vg) && is_lower_guid(vg));
        CHECK(tag_text(vref, "Viewpoint", file, sizeof file) && strcmp(file, "viewpoint.bcfv") == 0);
        const char *vis = find_tag(vp, "VisualizationInfo");
        CHECK(attr(vis, "Guid", vg2, sizeof vg2) && strcmp(vg, vg2) == 0);
        static const char *const oc[] = {"VisualizationInfo", "PerspectiveCamera", "CameraViewPoint",
                                         "CameraDirection", "CameraUpVector", "FieldOfView", "AspectRatio"};
        CHECK(in_order(vp, NULL, oc, v == MR_BCF_3_0 ? 7 : 6));
        CHECK((find_tag(vp, "AspectRatio") != NULL) == (v == MR_BCF_3_0));
        if (k >= 0) {
            /* The camera: the pose seen in Z up, independently computed here. */
            const double *m = poses[k].m;
            double want_p[3] = {m[3], -m[11], m[7]};
            double want_d[3] = {m[2], -m[10], m[6]};
            /* 2.1 allows 45..60 deg only: this camera's 77.3 deg horizontal
             * view is 60 deg from further back along its axis, showing the
             * same width at the marked point (3.5 m away). */
            double back = v == MR_BCF_3_0 ? 0 : 3.5 * 0.8 / tan(M_PI / 6) - 3.5;
            for (int a = 0; a < 3; a++) want_p[a] -= back * want_d[a];
            double p[3], d[3], u[3], fov = 0;
            CHECK(tag_xyz(vp, "CameraViewPoint", p) && tag_xyz(vp, "CameraDirection", d) &&
                  tag_xyz(vp, "CameraUpVector", u) && tag_num(vp, "FieldOfView", &fov));
            double dp = sqrt(pow(p[0] - want_p[0], 2) + pow(p[1] - want_p[1], 2) + pow(p[2] - want_p[2], 2));
            CHECK_MSG(dp < 1e-3, "position off by %g m", dp);
            double dot = (d[0] * want_d[0] + d[1] * want_d[1] + d[2] * want_d[2]) /
                         sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            double ang = acos(fmin(1, dot)) * 180 / M_PI;
            CHECK_MSG(ang < 0.01, "direction off by %g deg", ang);
            CHECK_NEAR(u[0] * d[0] + u[1] * d[1] + u[2] * d[2], 0, 1e-9);
            CHECK(u[2] > 0); /* these poses look upright */
            double want_fov = v == MR_BCF_3_0 ? 2 * atan(0.6) * 180 / M_PI : 60;
            CHECK_NEAR(fov, want_fov, 1e-6);
            CHECK(v == MR_BCF_3_0 || (fov >= 45 && fov <= 60)); /* 2.1's FieldOfView range */
            CHECK(fov > 0 && fov < 180);
            if (v == MR_BCF_2_1)
                CHECK_MSG(strstr(desc, "BCF 2.1 allows 45 to 60 deg"), "the moved camera is noted: %s", desc);
            if (descs) check_components(vp, v, k);
            if (descs && k == 0) CHECK(strstr(desc, "IfcPipeSegment") && strstr(desc, k_pipe_guid));
            if (v == MR_BCF_3_0) {
                double ar = 0;
                CHECK(tag_num(vp, "AspectRatio", &ar));
                CHECK_NEAR(ar, 160.0 / 120, 1e-9);
            }
        }
        /* The snapshot is a PNG of the centred frustum. */
        CHECK(pn > 8 && memcmp(png, "\x89PNG", 4) == 0);
        if (pn > 24) {
            const unsigned char *q = (const unsigned char *)png;
            unsigned w = (unsigned)q[16] << 24 | q[17] << 16 | q[18] << 8 | q[19];
            unsigned h = (unsigned)q[20] << 24 | q[21] << 16 | q[22] << 8 | q[23];
            CHECK(w == 160 && h == 120);
        }
        free(mk), free(vp), free(png);
    }
    CHECK(topics == n);
    check_guids_distinct(guids, nguid);
    zip_close(z);
}

/* What the reader gets back from an exported archive: the marked
 * element's GUID, the camera (position within 1 mm, direction within
 * 0.01 deg of the pose, after 2.1's field-of-view fit) and the comment. */
static void check_read_back(const mr_bcf *b, mr_bcf_version v, const mr_dmat4 *poses, const char *const *titles) {
    CHECK(b->topic_count == 2);
    CHECK(strcmp(b->version, v == MR_BCF_3_0 ? "3.0" : "2.1") == 0);
    CHECK_MSG(b->warning_count == 0, "%s", b->warning_count ? b->warnings[0] : "");
    for (int i = 0; i < b->topic_count; i++) {
        const mr_bcf_topic *t = &b->topics[i];
        int k = strcmp(t->title, titles[0]) == 0 ? 0 : strcmp(t->title, titles[1]) == 0 ? 1 : -1;
        CHECK_MSG(k >= 0, "title %s", t->title);
        if (k < 0 || t->viewpoint_count != 1 || t->comment_count != 1) {
            CHECK(false);
            continue;
        }
        const mr_bcf_viewpoint *vp = &t->viewpoints[0];
        if (k == 0) CHECK(vp->selection_count == 1 && strcmp(vp->selection[0].ifc_guid, k_pipe_guid) == 0);
        else CHECK(vp->selection_count == 1 && strcmp(vp->selection[0].authoring_id, "Conveyor_2") == 0);
        CHECK(t->description && strcmp(t->comments[0].text, t->description) == 0);
        CHECK(strcmp(t->comments[0].viewpoint_guid, vp->guid) == 0);
        const double *m = poses[k].m;
        double want_p[3] = {m[3], -m[11], m[7]}, want_d[3] = {m[2], -m[10], m[6]};
        double back = v == MR_BCF_3_0 ? 0 : 3.5 * 0.8 / tan(M_PI / 6) - 3.5;
        for (int a = 0; a < 3; a++) want_p[a] -= back * want_d[a];
        const mr_bcf_camera *c = &vp->camera;
        CHECK(vp->camera_kind == MR_BCF_CAMERA_PERSPECTIVE);
        double dp = sqrt(pow(c->view_point[0] - want_p[0], 2) + pow(c->view_point[1] - want_p[1], 2) +
                         pow(c->view_point[2] - want_p[2], 2));
        CHECK_MSG(dp < 1e-3, "read back: position off by %g m", dp);
        double dot = (c->direction[0] * want_d[0] + c->direction[1] * want_d[1] + c->direction[2] * want_d[2]) /
                     sqrt(c->direction[0] * c->direction[0] + c->direction[1] * c->direction[1] +
                          c->direction[2] * c->direction[2]);
        CHECK_MSG(acos(fmin(1, dot)) * 180 / M_PI < 0.01, "read back: direction off");
    }
}

static void test_round_trip(void) {
    char dir[1200], out[1300];
    snprintf(dir, sizeof dir, "%s/session", g_tmp);
    mr_dmat4 poses[2] = {pose_at(2, 1.6, 4, 6, 1.2, -3), pose_at(-3.5, 1.4, 0.5, 0, 1, 8)};
    const char *titles[2] = {"pipe <DN50> & valve \"moved\"", "conveyor missing"};
    CHECK(write_mark(dir, 1, titles[0], &poses[0], 0.042, 0.005));
    CHECK(write_mark(dir, 2, titles[1], &poses[1], -1, -1));
    for (int v = 0; v < 2; v++) {
        snprintf(out, sizeof out, "%s/findings_%d.bcf", g_tmp, v);
        mr_export_params p = MR_EXPORT_DEFAULTS;
        p.bcf_version = v;
        mr_error err = {0};
        CHECK_MSG(mr_export_bcf(dir, out, &p, &err), "export: %s", err.msg);
        check_archive(out, (mr_bcf_version)v, poses, titles, 2, true);
        mr_bcf rb;
        CHECK_MSG(mr_bcf_read(out, &rb, &err), "read back: %s", err.msg);
        check_read_back(&rb, (mr_bcf_version)v, poses, titles);
        mr_bcf_free(&rb);
        /* The same marks give the same archive (GUIDs from the marks). */
        char out2[1400];
        snprintf(out2, sizeof out2, "%s.again", out);
        CHECK(mr_export_bcf(dir, out2, &p, &err));
        size_t n1 = 0, n2 = 0;
        char *a = mr_file_read(out, &n1, 0, &err), *b = mr_file_read(out2, &n2, 0, &err);
        CHECK(a && b && n1 == n2 && memcmp(a, b, n1) == 0);
        free(a), free(b);
    }
}

static void test_bad_input(void) {
    char dir[1200], out[1300];
    mr_error err = {0};
    mr_export_params p = MR_EXPORT_DEFAULTS;
    /* No marks at all, and an empty annotations file. */
    snprintf(dir, sizeof dir, "%s/empty", g_tmp);
    mr_mkdirs(dir, NULL);
    snprintf(out, sizeof out, "%s/empty.bcf", g_tmp);
    CHECK(!mr_export_bcf(dir, out, &p, &err) && strstr(err.msg, "no marks"));
    CHECK(!mr_file_exists(out));
    char ann[1300];
    snprintf(ann, sizeof ann, "%s/annotations.jsonl", dir);
    CHECK(mr_file_write_atomic(ann, "", 0, &err));
    CHECK(!mr_export_bcf(dir, out, &p, &err) && strstr(err.msg, "no marks"));
    CHECK(!mr_file_exists(out));
    /* A mark whose snapshot is gone: fails naming it, the old file stays. */
    snprintf(dir, sizeof dir, "%s/missing", g_tmp);
    mr_dmat4 pose = pose_at(0, 1.5, 0, 0, 1.5, -5);
    CHECK(write_mark(dir, 1, "a", &pose, -1, -1));
    CHECK(write_mark(dir, 2, "b", &pose, -1, -1));
    char snap[1400];
    snprintf(snap, sizeof snap, "%s/snapshots/mark_0002_frame.png", dir);
    CHECK(remove(snap) == 0);
    snprintf(out, sizeof out, "%s/missing.bcf", g_tmp);
    CHECK(mr_file_write_atomic(out, "old", 3, &err));
    CHECK(!mr_export_bcf(dir, out, &p, &err));
    CHECK_MSG(strstr(err.msg, "mark 2") && strstr(err.msg, "missing"), "%s", err.msg);
    size_t n = 0;
    char *old = mr_file_read(out, &n, 0, &err);
    CHECK(old && n == 3 && memcmp(old, "old", 3) == 0);
    free(old);
    /* An unwritable output. */
    snprintf(dir, sizeof dir, "%s/session", g_tmp);
    CHECK(!mr_export_bcf(dir, "/nonexistent-dir/x.bcf", &p, &err));
    /* A torn last line: the whole marks before it are exported. */
    snprintf(dir, sizeof dir, "%s/torn", g_tmp);
    CHECK(write_mark(dir, 1, "whole", &pose, -1, -1));
    snprintf(ann, sizeof ann, "%s/annotations.jsonl", dir);
    FILE *f = fopen(ann, "ab");
    if (f) {
        fputs("{\"type\":\"discrepancy\",\"note\":\"tor", f);
        fclose(f);
    }
    snprintf(out, sizeof out, "%s/torn.bcf", g_tmp);
    CHECK_MSG(mr_export_bcf(dir, out, &p, &err), "%s", err.msg);
    const char *titles[1] = {"whole"};
    check_archive(out, MR_BCF_2_1, &pose, titles, 1, false);
}


/* Every src="..." of the page names a file beside it: no server, no web. */
static void check_links(const char *dir, const char *html) {
    int n = 0;
    for (const char *p = html; (p = strstr(p, "src=\"")); n++) {
        p += 5;
        const char *q = strchr(p, '"');
        if (!q) break;
        char rel[256], path[1600];
        snprintf(rel, sizeof rel, "%.*s", (int)(q - p), p);
        CHECK_MSG(!strstr(rel, "://"), "external link %s", rel);
        snprintf(path, sizeof path, "%s/%s", dir, rel);
        CHECK_MSG(mr_file_exists(path), "missing %s", path);
        p = q;
    }
    CHECK(n >= 3);
    CHECK(!strstr(html, "http://") || strstr(html, "http://www.w3.org/2000/svg"));
    CHECK(!strstr(html, "https://"));
}

static void test_report(void) {
    char dir[1200], out[1300], path[1500];
    snprintf(dir, sizeof dir, "%s/session", g_tmp);
    snprintf(out, sizeof out, "%s/report", g_tmp);
    mr_export_params p = MR_EXPORT_DEFAULTS;
    mr_error err = {0};
    CHECK_MSG(mr_export_report(dir, out, &p, &err), "report: %s", err.msg);
    snprintf(path, sizeof path, "%s/index.html", out);
    size_t n = 0;
    char *html = mr_file_read(path, &n, 0, &err);
    CHECK(html != NULL);
    if (html) {
        CHECK(strstr(html, "pipe &lt;DN50&gt; &amp; valve &quot;moved&quot;") != NULL);
        CHECK(!strstr(html, "<DN50>"));
        CHECK(strstr(html, "conveyor missing") != NULL);
        CHECK(strstr(html, "42 mm") && strstr(html, "5 mm") && strstr(html, "<svg"));
        CHECK(strstr(html, "img/mark_1_overlay.png") && strstr(html, "img/mark_2_photo.png"));
        check_links(out, html);
    }
    free(html);
    snprintf(path, sizeof path, "%s/report.md", out);
    char *md = mr_file_read(path, &n, 0, &err);
    CHECK(md && strstr(md, "| 1 | pipe <DN50> & valve \"moved\" |") && strstr(md, "img/mark_2_photo.png"));
    free(md);
    mr_image img;
    snprintf(path, sizeof path, "%s/img/mark_1_photo.png", out);
    CHECK(mr_image_load(path, 0, &img, &err) && img.width == 160 && img.height == 120);
    mr_image_free(&img);
    /* Again: the earlier report is replaced. */
    CHECK_MSG(mr_export_report(dir, out, &p, &err), "again: %s", err.msg);
    /* A folder of something else is refused, untouched. */
    char other[1300];
    snprintf(other, sizeof other, "%s/other", g_tmp);
    snprintf(path, sizeof path, "%s/keep.txt", other);
    mr_mkdirs(other, NULL);
    CHECK(mr_file_write_atomic(path, "x", 1, &err));
    CHECK(!mr_export_report(dir, other, &p, &err) && strstr(err.msg, "not an earlier"));
    CHECK(mr_file_exists(path));
    snprintf(path, sizeof path, "%s/index.html", other);
    CHECK(!mr_file_exists(path));
    /* A missing snapshot: nothing at OUT, no temporary folder left. */
    snprintf(dir, sizeof dir, "%s/missing", g_tmp);
    snprintf(out, sizeof out, "%s/report_missing", g_tmp);
    CHECK(!mr_export_report(dir, out, &p, &err) && strstr(err.msg, "mark 2"));
    CHECK(!mr_file_exists(out));
    char cmd[1500];
    snprintf(cmd, sizeof cmd, "ls -d '%s'.tmp.* >/dev/null 2>&1", out);
    CHECK(system(cmd) != 0);
}

/* issue 15: a mark made by the view's Measure shows its triangulated
 * distance and that distance's sigma in the report and the BCF topic. */
static void test_measured(void) {
    char dir[1200], out[1300], path[1500];
    snprintf(dir, sizeof dir, "%s/measured", g_tmp);
    snprintf(out, sizeof out, "%s/report_measured", g_tmp);
    mr_measurement ms;
    memset(&ms, 0, sizeof ms);
    ms.taps = 3;
    for (int i = 0; i < 3; i++) ms.frames[i] = 10 + i, ms.px[i][0] = 80, ms.px[i][1] = 60;
    ms.tri.point = mr_v3(1.3, 1, 1);
    for (int i = 0; i < 3; i++) ms.tri.cov[4 * i] = 1.6e-5;
    ms.tri.sigma = sqrt(3 * 1.6e-5);
    ms.tri.angle_deg = 20;
    ms.has_distance = true;
    ms.distance_m = 0.301;
    ms.distance_sigma_m = 0.004;
    ms.planned = mr_v3(1, 1, 1);
    snprintf(ms.planned_node, sizeof ms.planned_node, "Machine_2");
    mr_dmat4 pose = pose_at(0, 1.5, 5, 1, 1, 1);
    /* 301 +- 2 * 4 mm against +-20 mm: out of tolerance. */
    mr_tolerance tol = mr_tolerance_lookup(NULL, "Machine_2", "visible", 8.0);
    mr_verdict vd;
    CHECK(mr_verdict_judge(ms.distance_m, ms.distance_sigma_m, &tol, &vd, NULL) && vd.kind == MR_VERDICT_OUT);
    g_mark_measure = &ms;
    g_mark_verdict = &vd;
    bool ok = write_mark(dir, 1, "machine moved", &pose, -1, 0.002);
    g_mark_measure = NULL;
    g_mark_verdict = NULL;
    if (!ok) return;
    mr_export_params p = MR_EXPORT_DEFAULTS;
    mr_error err = {0};
    CHECK_MSG(mr_export_report(dir, out, &p, &err), "report: %s", err.msg);
    snprintf(path, sizeof path, "%s/index.html", out);
    size_t n = 0;
    char *html = mr_file_read(path, &n, 0, &err);
    CHECK_MSG(html && strstr(html, "<td>301 mm +- 4 mm</td>"), "the summary lacks the measured distance and sigma");
    CHECK_MSG(html && strstr(html, "Measured distance: 301 mm +- 4 mm (1 sigma, triangulated from 3 taps, to the "
                                   "planned Machine_2)"),
              "the finding's text lacks the measurement");
    /* The verdict: a column of the summary, and words with the interval
     * and the tolerance used in the finding's text. */
    CHECK_MSG(html && strstr(html, "<th>verdict</th>") &&
                  strstr(html, ">out of tolerance (95 %: 293 .. 309 mm; limit +- 20 mm, DIN 18202 Table 1, 6-15 m)</td>"),
              "the summary lacks the verdict");
    CHECK_MSG(html && strstr(html, "Verdict: out of tolerance: 301.0 mm, 95 % interval 293.0 .. 309.0 mm, limit "
                                   "\xc2\xb1" "20 mm (DIN 18202 Table 1, 6-15 m)"),
              "the finding's text lacks the verdict");
    free(html);
    snprintf(path, sizeof path, "%s/report.md", out);
    char *md = mr_file_read(path, &n, 0, &err);
    CHECK_MSG(md && strstr(md, "| 301 mm +- 4 mm | out of tolerance (95 %: 293 .. 309 mm"), "report.md lacks the verdict");
    free(md);
    /* In both BCF versions: the description, and a label to filter by
     * (declared in 3.0's extensions). */
    for (int v3 = 0; v3 < 2; v3++) {
        p.bcf_version = v3 ? MR_BCF_3_0 : MR_BCF_2_1;
        snprintf(path, sizeof path, "%s/m%d.bcf", g_tmp, v3);
        CHECK_MSG(mr_export_bcf(dir, path, &p, &err), "bcf: %s", err.msg);
        int ze = 0;
        zip_t *z = zip_open(path, ZIP_RDONLY, &ze);
        CHECK(z != NULL);
        if (!z) continue;
        char *mk = NULL;
        for (zip_int64_t i = 0; i < zip_get_num_entries(z, 0) && !mk; i++) {
            const char *name = zip_get_name(z, (zip_uint64_t)i, 0);
            if (name && strstr(name, "/markup.bcf")) mk = zip_read(z, name, NULL);
        }
        CHECK_MSG(mk && strstr(mk, v3 ? "<Label>out of tolerance</Label>" : "<Labels>out of tolerance</Labels>"),
                  "BCF %s: no verdict label", v3 ? "3.0" : "2.1");
        CHECK_MSG(mk && strstr(mk, "Verdict: out of tolerance: 301.0 mm, 95 % interval 293.0 .. 309.0 mm"),
                  "BCF %s: the description lacks the verdict", v3 ? "3.0" : "2.1");
        free(mk);
        char *ext = v3 ? zip_read(z, "extensions.xml", NULL) : NULL;
        CHECK(!v3 || (ext && strstr(ext, "<TopicLabel>out of tolerance</TopicLabel>")));
        free(ext);
        zip_close(z);
    }
}

int main(void) {
    if (!mr_test_fresh_dir("export", g_tmp, sizeof g_tmp)) return 1;
    test_camera_conversion();
    test_undistort();
    test_round_trip();
    test_bad_input();
    test_report();
    test_measured();
    return mr_test_finish("test_export");
}
