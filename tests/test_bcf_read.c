/* lib/export's BCF reader: hand-written 2.0, 2.1 and 3.0 archives with
 * every viewpoint element, an unzipped folder, and the archive attacks
 * (missing markup, no camera, unknown components, a zip bomb, "../" in
 * entry names, entity expansion): one warning each, nothing written, the
 * rest read. */
#include "mr_export.h"
#include "mr_test.h"

#include <sys/stat.h>
#include <zip.h>

static char g_tmp[1024];

#define T1 "0a1b2c3d-0000-4000-8000-000000000001"
#define T2 "0a1b2c3d-0000-4000-8000-000000000002"
#define T3 "0a1b2c3d-0000-4000-8000-000000000003"
#define V1 "0a1b2c3d-1111-4000-8000-000000000001"
#define G1 "2O2Fr$t4X7Zf8NOew3FLOH"
#define G2 "1kTvXnbbzCWw8lcMd1dR4o"

typedef struct entry { const char *name; const char *text; size_t size; } entry;

/* A zip archive of the entries, in memory (caller frees). */
static void *make_zip(const entry *e, int n, size_t *out_n) {
    zip_error_t ze;
    zip_error_init(&ze);
    zip_source_t *src = zip_source_buffer_create(NULL, 0, 0, &ze);
    zip_source_keep(src);
    zip_t *z = zip_open_from_source(src, ZIP_CREATE | ZIP_TRUNCATE, &ze);
    for (int i = 0; i < n; i++) {
        size_t sz = e[i].size ? e[i].size : strlen(e[i].text);
        zip_source_t *s = zip_source_buffer(z, e[i].text, sz, 0);
        zip_file_add(z, e[i].name, s, ZIP_FL_ENC_UTF_8);
    }
    zip_close(z);
    zip_stat_t st;
    zip_stat_init(&st);
    zip_source_stat(src, &st);
    void *buf = malloc(st.size);
    zip_source_open(src);
    zip_source_read(src, buf, st.size);
    zip_source_close(src);
    zip_source_free(src);
    *out_n = st.size;
    return buf;
}

static bool warned(const mr_bcf *b, const char *what) {
    for (int i = 0; i < b->warning_count; i++)
        if (strstr(b->warnings[i], what)) return true;
    return false;
}

static const char k_markup21[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Markup>\n"
    " <Topic Guid=\"" T1 "\" TopicType=\"Clash\" TopicStatus=\"Open\">\n"
    "  <Title>Duct &amp; beam &#x2014; clash</Title><Priority>High</Priority><Index>4</Index>\n"
    "  <Labels>MEP</Labels><Labels>Level 2</Labels>\n"
    "  <CreationDate>2025-11-30T08:00:00Z</CreationDate><CreationAuthor>a@office.example</CreationAuthor>\n"
    "  <AssignedTo>b@site.example</AssignedTo><Description><![CDATA[see <here>]]></Description>\n"
    " </Topic>\n"
    " <Comment Guid=\"0a1b2c3d-2222-4000-8000-000000000001\"><Date>2025-11-30T08:01:00Z</Date>"
    "<Author>a@office.example</Author><Comment>Please check on site</Comment>"
    "<Viewpoint Guid=\"" V1 "\"/></Comment>\n"
    " <Viewpoints Guid=\"" V1 "\"><Viewpoint>viewpoint.bcfv</Viewpoint><Snapshot>snapshot.png</Snapshot></Viewpoints>\n"
    " <Viewpoints Guid=\"0a1b2c3d-1111-4000-8000-000000000002\"><Viewpoint>top.bcfv</Viewpoint></Viewpoints>\n"
    "</Markup>\n";

static const char k_vis21[] =
    "<?xml version=\"1.0\"?>\n<VisualizationInfo Guid=\"" V1 "\">\n"
    " <Components>\n"
    "  <ViewSetupHints SpacesVisible=\"true\" SpaceBoundariesVisible=\"false\" OpeningsVisible=\"true\"/>\n"
    "  <Selection><Component IfcGuid=\"" G1 "\"><OriginatingSystem>Revit</OriginatingSystem>"
    "<AuthoringToolId>123456</AuthoringToolId></Component></Selection>\n"
    "  <Visibility DefaultVisibility=\"false\"><Exceptions><Component IfcGuid=\"" G1 "\"/>"
    "<Component IfcGuid=\"" G2 "\"/></Exceptions></Visibility>\n"
    "  <Coloring><Color Color=\"FF0000\"><Component IfcGuid=\"" G1 "\"/></Color>"
    "<Color Color=\"8000ff00\"><Component IfcGuid=\"" G2 "\"/></Color></Coloring>\n"
    " </Components>\n"
    " <PerspectiveCamera><CameraViewPoint><X>3456789.125</X><Y>5432109.5</Y><Z>12.25</Z></CameraViewPoint>"
    "<CameraDirection><X>0</X><Y>1</Y><Z>0</Z></CameraDirection><CameraUpVector><X>0</X><Y>0</Y><Z>1</Z>"
    "</CameraUpVector><FieldOfView>55</FieldOfView></PerspectiveCamera>\n"
    " <ClippingPlanes><ClippingPlane><Location><X>1</X><Y>2</Y><Z>3</Z></Location>"
    "<Direction><X>0</X><Y>0</Y><Z>1</Z></Direction></ClippingPlane>"
    "<ClippingPlane><Location><X>0</X><Y>0</Y><Z>0</Z></Location>"
    "<Direction><X>1</X><Y>0</Y><Z>0</Z></Direction></ClippingPlane></ClippingPlanes>\n"
    "</VisualizationInfo>\n";

static const char k_top21[] =
    "<VisualizationInfo Guid=\"0a1b2c3d-1111-4000-8000-000000000002\">"
    "<OrthogonalCamera><CameraViewPoint><X>0</X><Y>0</Y><Z>50</Z></CameraViewPoint>"
    "<CameraDirection><X>0</X><Y>0</Y><Z>-1</Z></CameraDirection><CameraUpVector><X>0</X><Y>1</Y><Z>0</Z>"
    "</CameraUpVector><ViewToWorldScale>42.5</ViewToWorldScale></OrthogonalCamera></VisualizationInfo>";

static const char k_png[] = "\x89PNG\r\n\x1a\n-not-really-";

static void check_topic21(const mr_bcf *b, const mr_bcf_topic *t) {
    (void)b;
    CHECK(strcmp(t->guid, T1) == 0);
    CHECK(strcmp(t->type, "Clash") == 0 && strcmp(t->status, "Open") == 0);
    CHECK_MSG(strcmp(t->title, "Duct & beam \xe2\x80\x94 clash") == 0, "title %s", t->title);
    CHECK(strcmp(t->priority, "High") == 0 && t->index == 4);
    CHECK(t->label_count == 2 && strcmp(t->labels[1], "Level 2") == 0);
    CHECK(strcmp(t->creation_author, "a@office.example") == 0 && strcmp(t->assigned_to, "b@site.example") == 0);
    CHECK(t->description && strcmp(t->description, "see <here>") == 0);
    CHECK(t->comment_count == 1 && strcmp(t->comments[0].text, "Please check on site") == 0 &&
          strcmp(t->comments[0].viewpoint_guid, V1) == 0);
    CHECK(t->viewpoint_count == 2);
    if (t->viewpoint_count != 2) return;
    const mr_bcf_viewpoint *v = &t->viewpoints[0];
    CHECK(strcmp(v->guid, V1) == 0);
    CHECK(v->camera_kind == MR_BCF_CAMERA_PERSPECTIVE);
    CHECK(v->camera.view_point[0] == 3456789.125 && v->camera.view_point[1] == 5432109.5);
    CHECK(v->camera.fov_deg == 55 && v->camera.up[2] == 1);
    CHECK(v->has_components && !v->default_visibility);
    CHECK(v->spaces_visible && !v->space_boundaries_visible && v->openings_visible);
    CHECK(v->selection_count == 1 && strcmp(v->selection[0].ifc_guid, G1) == 0 &&
          strcmp(v->selection[0].originating, "Revit") == 0 && strcmp(v->selection[0].authoring_id, "123456") == 0);
    CHECK(v->exception_count == 2 && strcmp(v->exceptions[1].ifc_guid, G2) == 0);
    CHECK(v->coloring_count == 2 && v->colorings[0].argb == 0xffff0000u && v->colorings[1].argb == 0x8000ff00u &&
          v->colorings[1].count == 1 && strcmp(v->colorings[1].items[0].ifc_guid, G2) == 0);
    CHECK(v->clip_count == 2 && v->clips[0].location[2] == 3 && v->clips[1].direction[0] == 1);
    CHECK(v->snapshot && v->snapshot_size == sizeof k_png - 1 && memcmp(v->snapshot, k_png, 8) == 0);
    const mr_bcf_viewpoint *o = &t->viewpoints[1];
    CHECK(o->camera_kind == MR_BCF_CAMERA_ORTHOGONAL && o->view_to_world_scale == 42.5 && o->camera.direction[2] == -1);
    CHECK(!o->snapshot);
}

static void test_21(void) {
    entry e[] = {{"bcf.version", "<Version VersionId=\"2.1\"><DetailedVersion>2.1</DetailedVersion></Version>", 0},
                 {T1 "/markup.bcf", k_markup21, 0},
                 {T1 "/viewpoint.bcfv", k_vis21, 0},
                 {T1 "/top.bcfv", k_top21, 0},
                 {T1 "/snapshot.png", k_png, sizeof k_png - 1}};
    size_t n = 0;
    void *zip = make_zip(e, 5, &n);
    mr_bcf b;
    mr_error err = {0};
    CHECK_MSG(mr_bcf_read_memory(zip, n, &b, &err), "%s", err.msg);
    CHECK(strcmp(b.version, "2.1") == 0 && b.topic_count == 1);
    if (b.topic_count == 1) check_topic21(&b, &b.topics[0]);
    CHECK_MSG(b.warning_count == 0, "%s", b.warning_count ? b.warnings[0] : "");
    /* Written back (3.0, then 2.1) and read again: the same topic, GUIDs kept. */
    for (int ver = 0; ver < 2; ver++) {
        void *out = NULL;
        size_t on = 0;
        CHECK_MSG(mr_bcf_write_memory(&b, ver ? MR_BCF_2_1 : MR_BCF_3_0, &out, &on, &err), "%s", err.msg);
        mr_bcf c;
        CHECK_MSG(mr_bcf_read_memory(out, on, &c, &err), "%s", err.msg);
        CHECK(strcmp(c.version, ver ? "2.1" : "3.0") == 0);
        if (c.topic_count == 1) check_topic21(&c, &c.topics[0]);
        mr_bcf_free(&c);
        free(out);
    }
    /* The planner's answer: a comment, a status, a new snapshot; written
     * as 2.1 and read again, the topic keeps its GUID and all it had. */
    mr_bcf_answer_params ans = {.comment = "fixed on site", .status = "Closed", .snapshot = (const unsigned char *)k_png,
                                .snapshot_size = sizeof k_png - 1, .author = "me@site.example"};
    CHECK(b.topic_count == 1 && mr_bcf_answer(&b.topics[0], &ans, &err));
    void *out = NULL;
    size_t on = 0;
    mr_bcf c;
    CHECK(mr_bcf_write_memory(&b, MR_BCF_2_1, &out, &on, &err) && mr_bcf_read_memory(out, on, &c, &err));
    free(out);
    const mr_bcf_topic *t = c.topic_count == 1 ? &c.topics[0] : NULL;
    CHECK(t && strcmp(t->guid, T1) == 0 && strcmp(t->status, "Closed") == 0 && t->comment_count == 2 &&
          t->viewpoint_count == 3 && strcmp(t->modified_author, "me@site.example") == 0);
    if (t && t->comment_count == 2 && t->viewpoint_count == 3) {
        CHECK(strcmp(t->comments[0].text, "Please check on site") == 0 && strcmp(t->comments[1].text, "fixed on site") == 0);
        CHECK(strcmp(t->comments[1].viewpoint_guid, t->viewpoints[2].guid) == 0 && t->viewpoints[2].snapshot);
        CHECK(t->viewpoints[2].camera.fov_deg == 55 && t->viewpoints[2].selection_count == 1);
    }
    mr_bcf_free(&c);
    mr_bcf_free(&b);
    free(zip);

    /* The same archive unzipped in a folder. */
    char dir[1200], p[1400];
    snprintf(dir, sizeof dir, "%s/unzipped", g_tmp);
    snprintf(p, sizeof p, "%s/%s", dir, T1);
    CHECK(mr_mkdirs(p, &err));
    for (int i = 0; i < 5; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, e[i].name);
        CHECK(mr_file_write_atomic(p, e[i].text, e[i].size ? e[i].size : strlen(e[i].text), &err));
    }
    CHECK_MSG(mr_bcf_read(dir, &b, &err), "%s", err.msg);
    if (b.topic_count == 1) check_topic21(&b, &b.topics[0]);
    mr_bcf_free(&b);
}

/* 3.0: Comments and Viewpoints inside Topic, Labels/Label, ViewSetupHints
 * inside Visibility, Color holding Components, AspectRatio. */
static void test_30(void) {
    const char *markup =
        "<Markup><Topic Guid=\"" T2 "\" TopicType=\"Issue\" TopicStatus=\"Closed\"><Title>Wall moved</Title>"
        "<Labels><Label>Arch</Label></Labels><CreationDate>2025-01-01T00:00:00Z</CreationDate>"
        "<CreationAuthor>x</CreationAuthor><Comments><Comment Guid=\"0a1b2c3d-2222-4000-8000-000000000009\">"
        "<Date>2025-01-01T00:00:00Z</Date><Author>x</Author><Comment>ok</Comment></Comment></Comments>"
        "<Viewpoints><ViewPoint Guid=\"" V1 "\"><Viewpoint>viewpoint.bcfv</Viewpoint></ViewPoint></Viewpoints>"
        "</Topic></Markup>";
    const char *vis =
        "<VisualizationInfo Guid=\"" V1 "\"><Components><Selection><Component IfcGuid=\"" G2 "\"/></Selection>"
        "<Visibility DefaultVisibility=\"true\"><ViewSetupHints OpeningsVisible=\"true\"/></Visibility>"
        "<Coloring><Color Color=\"00FF00\"><Components><Component IfcGuid=\"" G2 "\"/></Components></Color></Coloring>"
        "</Components><PerspectiveCamera><CameraViewPoint><X>1</X><Y>2</Y><Z>3</Z></CameraViewPoint>"
        "<CameraDirection><X>1</X><Y>0</Y><Z>0</Z></CameraDirection><CameraUpVector><X>0</X><Y>0</Y><Z>1</Z>"
        "</CameraUpVector><FieldOfView>40</FieldOfView><AspectRatio>1.5</AspectRatio></PerspectiveCamera>"
        "</VisualizationInfo>";
    entry e[] = {{"bcf.version", "<Version VersionId=\"3.0\"/>", 0}, {T2 "/markup.bcf", markup, 0},
                 {T2 "/viewpoint.bcfv", vis, 0}};
    size_t n = 0;
    void *zip = make_zip(e, 3, &n);
    mr_bcf b;
    mr_error err = {0};
    CHECK_MSG(mr_bcf_read_memory(zip, n, &b, &err), "%s", err.msg);
    const mr_bcf_topic *t = b.topic_count == 1 ? &b.topics[0] : NULL;
    CHECK(t && strcmp(b.version, "3.0") == 0);
    if (t) {
        CHECK(strcmp(t->status, "Closed") == 0 && t->label_count == 1 && strcmp(t->labels[0], "Arch") == 0);
        CHECK(t->comment_count == 1 && strcmp(t->comments[0].text, "ok") == 0);
        const mr_bcf_viewpoint *v = t->viewpoint_count == 1 ? &t->viewpoints[0] : NULL;
        CHECK(v && v->default_visibility && v->openings_visible && !v->spaces_visible);
        CHECK(v && v->selection_count == 1 && v->coloring_count == 1 && v->colorings[0].count == 1 &&
              v->colorings[0].argb == 0xff00ff00u);
        CHECK(v && v->camera.fov_deg == 40 && v->camera.aspect == 1.5);
    }
    mr_bcf_free(&b);
    free(zip);
}

/* 2.0: one Components list with Selected / Visible / Color attributes,
 * no viewpoint references in the markup (the default files are read). */
static void test_20(void) {
    const char *markup = "<Markup><Topic Guid=\"" T3 "\"><Title>old</Title></Topic></Markup>";
    const char *vis =
        "<VisualizationInfo><Components><Component IfcGuid=\"" G1 "\" Selected=\"true\" Visible=\"false\" "
        "Color=\"0000FF\"><OriginatingSystem>X</OriginatingSystem></Component></Components>"
        "<PerspectiveCamera><CameraViewPoint><X>0</X><Y>0</Y><Z>0</Z></CameraViewPoint><CameraDirection><X>0</X>"
        "<Y>1</Y><Z>0</Z></CameraDirection><CameraUpVector><X>0</X><Y>0</Y><Z>1</Z></CameraUpVector>"
        "<FieldOfView>60</FieldOfView></PerspectiveCamera></VisualizationInfo>";
    entry e[] = {{"bcf.version", "<Version VersionId=\"2.0\"/>", 0}, {T3 "/markup.bcf", markup, 0},
                 {T3 "/viewpoint.bcfv", vis, 0}, {T3 "/snapshot.png", k_png, sizeof k_png - 1}};
    size_t n = 0;
    void *zip = make_zip(e, 4, &n);
    mr_bcf b;
    mr_error err = {0};
    CHECK_MSG(mr_bcf_read_memory(zip, n, &b, &err), "%s", err.msg);
    const mr_bcf_topic *t = b.topic_count == 1 ? &b.topics[0] : NULL;
    const mr_bcf_viewpoint *v = t && t->viewpoint_count == 1 ? &t->viewpoints[0] : NULL;
    CHECK(v != NULL);
    if (v) {
        CHECK(mr_bcf_guid_valid(v->guid)); /* given one, so it can be written back */
        CHECK(v->selection_count == 1 && v->exception_count == 1 && v->default_visibility);
        CHECK(v->coloring_count == 1 && v->colorings[0].argb == 0xff0000ffu);
        CHECK(v->snapshot != NULL && v->camera_kind == MR_BCF_CAMERA_PERSPECTIVE);
    }
    mr_bcf_free(&b);
    free(zip);
}

static void test_attacks(void) {
    /* An entity bomb in one viewpoint, a viewpoint with no camera, a topic
     * without markup, a "../" entry, a viewpoint file and a snapshot named
     * outside the topic, an entry past the size cap: each is one warning and
     * the good topic is still read. */
    const char *bomb =
        "<?xml version=\"1.0\"?><!DOCTYPE lolz [<!ENTITY lol \"lol\"><!ENTITY lol2 \"&lol;&lol;&lol;&lol;\">]>"
        "<VisualizationInfo Guid=\"" V1 "\"><Components><Selection><Component AuthoringToolId=\"&lol2;\"/>"
        "</Selection></Components></VisualizationInfo>";
    const char *markup2 =
        "<Markup><Topic Guid=\"" T2 "\"><Title>t2</Title></Topic>"
        "<Viewpoints Guid=\"" V1 "\"><Viewpoint>viewpoint.bcfv</Viewpoint><Snapshot>../../evil.png</Snapshot></Viewpoints>"
        "<Viewpoints Guid=\"0a1b2c3d-1111-4000-8000-000000000005\"><Viewpoint>../" T1 "/viewpoint.bcfv</Viewpoint></Viewpoints>"
        "<Viewpoints Guid=\"0a1b2c3d-1111-4000-8000-000000000006\"><Viewpoint>bomb.bcfv</Viewpoint></Viewpoints>"
        "</Markup>";
    const char *nocam = "<VisualizationInfo Guid=\"" V1 "\"><Components><Selection><Component IfcGuid=\"" G2
                        "\"/></Selection></Components></VisualizationInfo>";
    size_t big = MR_BCF_MAX_ENTRY_BYTES + 16;
    char *huge = malloc(big);
    memset(huge, ' ', big);
    memcpy(huge, "<Markup>", 8);
    entry e[] = {{"bcf.version", "<Version VersionId=\"2.1\"/>", 0},
                 {T1 "/markup.bcf", k_markup21, 0},
                 {T1 "/viewpoint.bcfv", k_vis21, 0},
                 {T1 "/top.bcfv", k_top21, 0},
                 {T1 "/snapshot.png", k_png, sizeof k_png - 1},
                 {T2 "/markup.bcf", markup2, 0},
                 {T2 "/viewpoint.bcfv", nocam, 0},
                 {T2 "/bomb.bcfv", bomb, 0},
                 {T3 "/snapshot.png", k_png, sizeof k_png - 1}, /* a topic folder without markup */
                 {"../escape/markup.bcf", k_markup21, 0},
                 {"0a1b2c3d-0000-4000-8000-000000000004/markup.bcf", huge, big}};
    size_t n = 0;
    void *zip = make_zip(e, 11, &n);
    free(huge);
    mr_bcf b;
    mr_error err = {0};
    CHECK_MSG(mr_bcf_read_memory(zip, n, &b, &err), "%s", err.msg);
    CHECK_MSG(b.topic_count == 2, "%d topics", b.topic_count);
    if (b.topic_count >= 1) check_topic21(&b, &b.topics[0]);
    CHECK(warned(&b, "../escape/markup.bcf\": a name that leaves"));
    CHECK(warned(&b, "../../evil.png\" leaves the topic's folder"));
    CHECK(warned(&b, "viewpoint.bcfv\" leaves the topic's folder"));
    CHECK(warned(&b, "bomb.bcfv: XML: a DOCTYPE"));
    CHECK(warned(&b, T2 "/viewpoint.bcfv: names no camera"));
    CHECK(warned(&b, "larger than 64 MiB uncompressed"));
    CHECK(warned(&b, "topic " T3 ": no readable markup.bcf"));
    for (int i = 0; i < b.warning_count; i++) CHECK(strchr(b.warnings[i], '\n') == NULL);
    if (b.topic_count == 2) {
        const mr_bcf_topic *t = &b.topics[1];
        /* The camera-less viewpoint is kept (its components still say what
         * the topic is about); its snapshot is not read. */
        CHECK(t->viewpoint_count == 2 && t->viewpoints[0].camera_kind == MR_BCF_CAMERA_NONE &&
              t->viewpoints[0].selection_count == 1 && !t->viewpoints[0].snapshot);
    }
    mr_bcf_free(&b);
    free(zip);
    /* Nothing was written beside the scratch folder. */
    struct stat st;
    CHECK(stat("../evil.png", &st) != 0 && stat("escape", &st) != 0);

    /* Not a zip, no version it knows, no topic: one line and a failure. */
    CHECK(!mr_bcf_read_memory("hello", 5, &b, &err) && strstr(err.msg, "not a zip"));
    entry v9[] = {{"bcf.version", "<Version VersionId=\"9.9\"/>", 0}, {T1 "/markup.bcf", k_markup21, 0}};
    zip = make_zip(v9, 2, &n);
    CHECK(!mr_bcf_read_memory(zip, n, &b, &err) && strstr(err.msg, "9.9"));
    free(zip);
    entry none[] = {{"bcf.version", "<Version VersionId=\"2.1\"/>", 0}};
    zip = make_zip(none, 1, &n);
    CHECK(!mr_bcf_read_memory(zip, n, &b, &err) && strstr(err.msg, "no readable topic"));
    free(zip);
    CHECK(!mr_bcf_read("/nonexistent/x.bcf", &b, &err));
}

int main(void) {
    if (!mr_test_fresh_dir("bcf_read", g_tmp, sizeof g_tmp)) return 1;
    test_21();
    test_30();
    test_20();
    test_attacks();
    return mr_test_finish("test_bcf_read");
}
