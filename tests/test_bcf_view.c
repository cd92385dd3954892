/* A BCF topic's viewpoint drawn (lib/export/bcf_view.c): a hand-written
 * BCF 3.0 folder over a generated row of four boxes, near the origin and
 * at a 1e7 offset. The hidden box's pixels are gone, the coloured box
 * shows its colour, the selected one the highlight, a clipping plane
 * removes the half of a box on its cut side and keeps the other; an
 * orthogonal camera draws every depth at one scale. */
#include "mr_export.h"
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"

/* The binary under ASan unloads Mesa's driver at exit, whose globals then
 * look like a leak from an unknown module (tests/mr_test.h); the library
 * code it runs is leak-checked in this process, so the child skips it. */
#define MR_CHILD_ENV "ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\" "

#define T1 "0a1b2c3d-0000-4000-8000-0000000000a1"
#define T2 "0a1b2c3d-0000-4000-8000-0000000000a2"
#define V1 "0a1b2c3d-1111-4000-8000-0000000000b1"
#define V2 "0a1b2c3d-1111-4000-8000-0000000000b2"
#define GA "0aaaaaaaaaaaaaaaaaaaaa"
#define GB "0bbbbbbbbbbbbbbbbbbbbb"

#define W 160
#define H 120

/* Four unit boxes on a row along x at height 0.5 (glTF, Y up), offset by
 * ox: A (x -3, IfcGuid GA), B (-1, GB), C (1, named "Column C"), D (3). */
static mr_scene *row_scene(double ox) {
    mr_scene *s = mr_scene_create();
    static const char *names[4] = {"Box A", "Box B", "Column C", "Box D"};
    for (int i = 0; i < 4; i++) {
        mr_node n;
        memset(&n, 0, sizeof n);
        snprintf(n.name, sizeof n.name, "%s", names[i]);
        n.parent = -1;
        n.world = mr_m4_translate(ox - 3 + 2 * i, 0.5, 0);
        n.mesh_first = mr_test_add_box(s, 1, 1, 1, -1);
        n.mesh_count = 1;
        int32_t id = mr_scene_add_node(s, &n);
        if (i < 2) {
            mr_element e;
            memset(&e, 0, sizeof e);
            e.node = id;
            e.storey = -1;
            snprintf(e.guid, sizeof e.guid, "%s", i == 0 ? GA : GB);
            snprintf(e.ifc_class, sizeof e.ifc_class, "IfcColumn");
            CHECK(mr_scene_add_element(s, &e));
        }
    }
    mr_scene_update_bounds(s);
    return s;
}

static bool put(const char *dir, const char *name, const char *text) {
    char path[2048];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    mr_error err = {0};
    bool ok = mr_file_write_atomic(path, text, strlen(text), &err);
    CHECK_MSG(ok, "%s", err.msg);
    return ok;
}

/* BCF 3.0: topic 1 seen from the front (perspective, vertical FOV 40°),
 * A hidden, B red, C selected (by AuthoringToolId), D cut at its centre
 * (what lies at larger x is clipped away); topic 2 from above
 * (orthogonal, 6 m high), A hidden. All in BCF's Z up, x offset by ox. */
static bool write_bcf(const char *dir, double ox) {
    char sub[2048], buf[4096];
    snprintf(sub, sizeof sub, "%s/" T1, dir);
    mr_error err = {0};
    if (!mr_mkdirs(sub, &err)) return false;
    snprintf(sub, sizeof sub, "%s/" T2, dir);
    if (!mr_mkdirs(sub, &err)) return false;
    bool ok = put(dir, "bcf.version", "<Version VersionId=\"3.0\"/>");
    for (int t = 0; t < 2; t++) {
        snprintf(buf, sizeof buf,
                 "<Markup><Topic Guid=\"%s\" TopicType=\"Issue\" TopicStatus=\"Open\"><Title>t%d</Title>"
                 "<CreationDate>2025-01-01T00:00:00Z</CreationDate><CreationAuthor>x</CreationAuthor>"
                 "<Viewpoints><ViewPoint Guid=\"%s\"><Viewpoint>viewpoint.bcfv</Viewpoint></ViewPoint></Viewpoints>"
                 "</Topic></Markup>",
                 t ? T2 : T1, t + 1, t ? V2 : V1);
        snprintf(sub, sizeof sub, "%s/%s/markup.bcf", dir, t ? T2 : T1);
        ok = ok && mr_file_write_atomic(sub, buf, strlen(buf), &err);
    }
    snprintf(buf, sizeof buf,
             "<VisualizationInfo Guid=\"" V1 "\"><Components>"
             "<Selection><Component><AuthoringToolId>Column C</AuthoringToolId></Component></Selection>"
             "<Visibility DefaultVisibility=\"true\"><Exceptions><Component IfcGuid=\"" GA "\"/></Exceptions></Visibility>"
             "<Coloring><Color Color=\"FF0000\"><Components><Component IfcGuid=\"" GB "\"/></Components></Color></Coloring>"
             "</Components><PerspectiveCamera><CameraViewPoint><X>%.3f</X><Y>-10</Y><Z>0.5</Z></CameraViewPoint>"
             "<CameraDirection><X>0</X><Y>1</Y><Z>0</Z></CameraDirection><CameraUpVector><X>0</X><Y>0</Y><Z>1</Z>"
             "</CameraUpVector><FieldOfView>40</FieldOfView><AspectRatio>%g</AspectRatio></PerspectiveCamera>"
             "<ClippingPlanes><ClippingPlane><Location><X>%.3f</X><Y>0</Y><Z>0</Z></Location>"
             "<Direction><X>1</X><Y>0</Y><Z>0</Z></Direction></ClippingPlane></ClippingPlanes>"
             "</VisualizationInfo>",
             ox, (double)W / H, ox + 3);
    snprintf(sub, sizeof sub, "%s/" T1 "/viewpoint.bcfv", dir);
    ok = ok && mr_file_write_atomic(sub, buf, strlen(buf), &err);
    snprintf(buf, sizeof buf,
             "<VisualizationInfo Guid=\"" V2 "\"><Components>"
             "<Visibility DefaultVisibility=\"true\"><Exceptions><Component IfcGuid=\"" GA "\"/></Exceptions></Visibility>"
             "</Components><OrthogonalCamera><CameraViewPoint><X>%.3f</X><Y>0</Y><Z>20</Z></CameraViewPoint>"
             "<CameraDirection><X>0</X><Y>0</Y><Z>-1</Z></CameraDirection><CameraUpVector><X>0</X><Y>1</Y><Z>0</Z>"
             "</CameraUpVector><ViewToWorldScale>6</ViewToWorldScale><AspectRatio>%g</AspectRatio></OrthogonalCamera>"
             "</VisualizationInfo>",
             ox, (double)W / H);
    snprintf(sub, sizeof sub, "%s/" T2 "/viewpoint.bcfv", dir);
    ok = ok && mr_file_write_atomic(sub, buf, strlen(buf), &err);
    CHECK_MSG(ok, "%s", err.msg);
    return ok;
}

/* Pixel of world point p in view v. */
static void project(const mr_view *v, mr_dvec3 p, double *u, double *w) {
    mr_dmat4 cw = mr_m4_invert_rigid(&v->world_from_camera);
    mr_dvec3 c = mr_m4_point(&cw, p);
    *u = v->camera.fx * c.x / c.z + v->camera.cx;
    *w = v->camera.fy * c.y / c.z + v->camera.cy;
}

static const uint8_t *px(const mr_image *im, mr_dvec3 p, const mr_view *v) {
    double u, w;
    project(v, p, &u, &w);
    int x = (int)lround(u), y = (int)lround(w);
    static const uint8_t none[3] = {0, 0, 0};
    CHECK_MSG(x >= 0 && y >= 0 && x < im->width && y < im->height, "(%g, %g) outside", u, w);
    if (!(x >= 0 && y >= 0 && x < im->width && y < im->height)) return none;
    return (const uint8_t *)im->data + ((size_t)y * im->width + x) * 3;
}

static bool is_background(const uint8_t *c) {
    /* MR_FRAME_DEFAULT_BACKGROUND, sRGB 8-bit */
    return abs(c[0] - 158) <= 3 && abs(c[1] - 168) <= 3 && abs(c[2] - 179) <= 3;
}

static bool render(mr_renderer *r, const mr_scene *s, const mr_view *v, mr_image *out) {
    mr_error err = {0};
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = W;
    fp.height = H;
    mr_frame_result res = {0};
    bool ok = mr_renderer_set_scene(r, s, &err) && mr_render_frame(r, v, &fp, &res, &err);
    CHECK_MSG(ok, "%s", err.msg);
    *out = res.color;
    res.color.data = NULL;
    mr_frame_result_free(&res);
    mr_renderer_set_scene(r, NULL, &err);
    return ok;
}

static void check_offset(mr_renderer *r, const char *dir, double ox) {
    if (!write_bcf(dir, ox)) return;
    mr_bcf b;
    mr_error err = {0};
    CHECK_MSG(mr_bcf_read(dir, &b, &err), "%s", err.msg);
    if (b.topic_count != 2) {
        CHECK_MSG(0, "%d topics", b.topic_count);
        mr_bcf_free(&b);
        return;
    }
    mr_dvec3 a = mr_v3(ox - 3, 0.5, 0), bb = mr_v3(ox - 1, 0.5, 0), c = mr_v3(ox + 1, 0.5, 0);
    mr_dvec3 d_cut = mr_v3(ox + 3.25, 0.5, 0.5), d_kept = mr_v3(ox + 2.75, 0.5, 0.5);

    /* Topic 1, perspective. */
    mr_scene *s = row_scene(ox);
    mr_bcf_view_params bp = MR_BCF_VIEW_DEFAULTS;
    bp.width = W;
    bp.height = H;
    mr_view v;
    mr_bcf_view_info info;
    CHECK_MSG(mr_bcf_topic_view(s, &b, &b.topics[0], &bp, &v, &info, &err), "%s", err.msg);
    CHECK_NEAR(v.camera.fy, H * 0.5 / tan(20 * M_PI / 180), 1e-9); /* 3.0: vertical */
    CHECK_MSG(info.hidden_nodes == 1 && info.coloured_nodes == 1 && info.selected_nodes == 1 &&
                  info.clipped_nodes == 1 && info.unresolved == 0,
              "hidden %d coloured %d selected %d clipped %d unresolved %d", info.hidden_nodes, info.coloured_nodes,
              info.selected_nodes, info.clipped_nodes, info.unresolved);
    CHECK(s->source[0] == '\0');
    mr_scene *plain = row_scene(ox);
    mr_image before = {0}, after = {0};
    if (render(r, plain, &v, &before) && render(r, s, &v, &after)) {
        /* Before: every box drawn, grey. */
        CHECK(!is_background(px(&before, a, &v)) && !is_background(px(&before, d_cut, &v)));
        const uint8_t *g = px(&before, bb, &v);
        CHECK_MSG(abs(g[0] - g[1]) < 8 && abs(g[1] - g[2]) < 8, "grey %d %d %d", g[0], g[1], g[2]);
        /* After: A gone, B red, C highlighted (blue over grey), D's far half cut away. */
        CHECK_MSG(is_background(px(&after, a, &v)), "hidden box drawn");
        const uint8_t *red = px(&after, bb, &v);
        CHECK_MSG(red[0] > 100 && red[0] > 3 * red[1] && red[0] > 3 * red[2], "red %d %d %d", red[0], red[1], red[2]);
        const uint8_t *sel = px(&after, c, &v);
        CHECK_MSG(sel[2] > sel[0] + 40 && sel[2] > sel[1], "selected %d %d %d", sel[0], sel[1], sel[2]);
        CHECK_MSG(is_background(px(&after, d_cut, &v)), "clipped half drawn");
        CHECK_MSG(!is_background(px(&after, d_kept, &v)), "kept half missing");
    }
    mr_image_free(&before);
    mr_image_free(&after);
    mr_scene_destroy(&s);

    /* Topic 2, orthogonal from above: 6 m over H px at every depth. */
    s = row_scene(ox);
    CHECK_MSG(mr_bcf_topic_view(s, &b, &b.topics[1], &bp, &v, &info, &err), "%s", err.msg);
    double u0, w0, u1, w1, u2, w2;
    project(&v, mr_v3(ox - 1, 1, 0), &u0, &w0);   /* top of B */
    project(&v, mr_v3(ox - 1, 0, 0), &u1, &w1);   /* its foot, 1 m further */
    project(&v, mr_v3(ox + 1, 1, 0), &u2, &w2);
    double ppm = H / 6.0;
    CHECK_NEAR(u0, W * 0.5 - 0.5 - ppm, 0.05);
    CHECK_NEAR(u2 - u0, 2 * ppm, 0.05);
    CHECK_NEAR(u1, u0, fabs(u0 - (W - 1) * 0.5) / MR_BCF_ORTHO_DISTANCE + 1e-6);
    mr_image top = {0};
    if (render(r, s, &v, &top)) {
        CHECK(is_background(px(&top, mr_v3(ox - 3, 1, 0), &v)));
        CHECK(!is_background(px(&top, mr_v3(ox - 1, 1, 0), &v)));
    }
    mr_image_free(&top);
    mr_scene_destroy(&s);
    mr_scene_destroy(&plain);
    mr_bcf_free(&b);
}

/* `mrcheck render --bcf`: the same picture from the command line (the
 * scene saved as .glb); a missing --topic or an unknown topic is one line
 * on stderr, a non-zero exit and no image. */
static void check_cli(const char *dir) {
    const char *mr = getenv("MR_MRCHECK");
    CHECK_MSG(mr && mr[0], "MR_MRCHECK (the mrcheck binary) is not set");
    if (!mr || !mr[0] || !write_bcf(dir, 0)) return;
    char glb[1200], out[1200], cmd[8192], errf[1200];
    snprintf(glb, sizeof glb, "%s/row.glb", dir);
    snprintf(out, sizeof out, "%s/topic1.png", dir);
    snprintf(errf, sizeof errf, "%s/err.txt", dir);
    mr_scene *s = row_scene(0);
    mr_error err = {0};
    CHECK_MSG(mr_scene_save_glb(s, glb, &err), "%s", err.msg);
    mr_scene_destroy(&s);
    snprintf(cmd, sizeof cmd, MR_CHILD_ENV "'%s' render --scene '%s' --bcf '%s' --topic 1 --size %dx%d --out '%s' 2>'%s'", mr, glb, dir,
             W, H, out, errf);
    CHECK_MSG(system(cmd) == 0, "%s failed", cmd);
    mr_image im = {0};
    if (mr_image_load(out, 3, &im, &err)) {
        s = row_scene(0);
        mr_bcf b;
        mr_view v;
        mr_bcf_view_params bp = {.unit_m = 1, .width = W, .height = H};
        if (mr_bcf_read(dir, &b, &err) && mr_bcf_topic_view(s, &b, &b.topics[0], &bp, &v, NULL, &err)) {
            CHECK(is_background(px(&im, mr_v3(-3, 0.5, 0), &v)));
            const uint8_t *red = px(&im, mr_v3(-1, 0.5, 0), &v);
            CHECK_MSG(red[0] > 100 && red[0] > 3 * red[1], "cli red %d %d %d", red[0], red[1], red[2]);
            CHECK(is_background(px(&im, mr_v3(3.25, 0.5, 0.5), &v)));
            CHECK(!is_background(px(&im, mr_v3(2.75, 0.5, 0.5), &v)));
            mr_bcf_free(&b);
        } else {
            CHECK_MSG(0, "%s", err.msg);
        }
        mr_scene_destroy(&s);
    } else {
        CHECK_MSG(0, "%s", err.msg);
    }
    mr_image_free(&im);
    /* No cache beside the file for the edited scene. */
    char lod[1300];
    snprintf(lod, sizeof lod, "%s.mrlod", glb);
    CHECK(!mr_file_exists(lod));
    static const char *bad[2] = {"", "--topic 7"};
    for (int i = 0; i < 2; i++) {
        remove(out);
        snprintf(cmd, sizeof cmd, MR_CHILD_ENV "'%s' render --scene '%s' --bcf '%s' %s --out '%s' 2>'%s'", mr, glb, dir, bad[i], out,
                 errf);
        int rc = system(cmd);
        size_t n = 0;
        char *text = mr_file_read(errf, &n, 0, &err);
        int lines = 0;
        for (size_t k = 0; text && k < n; k++) lines += text[k] == '\n';
        CHECK_MSG(rc != 0 && lines == 1 && !mr_file_exists(out), "bad case %d: rc %d, %d lines: %s", i, rc, lines,
                  text ? text : "");
        free(text);
    }
}

static void check_cpu(void) {
    /* 2.x: the FieldOfView is horizontal; a camera without up or a
     * viewpoint without camera is refused. */
    mr_bcf_viewpoint vp;
    memset(&vp, 0, sizeof vp);
    vp.camera_kind = MR_BCF_CAMERA_PERSPECTIVE;
    vp.camera.direction[1] = 1;
    vp.camera.up[2] = 1;
    vp.camera.fov_deg = 60;
    mr_bcf_view_params bp = MR_BCF_VIEW_DEFAULTS;
    mr_view v;
    mr_error err = {0};
    CHECK(mr_bcf_viewpoint_view(&vp, NULL, &bp, &v, &err));
    CHECK(v.camera.width == MR_BCF_VIEW_DEFAULT_WIDTH && v.camera.height == MR_BCF_VIEW_DEFAULT_WIDTH * 3 / 4);
    CHECK_NEAR(v.camera.fx, MR_BCF_VIEW_DEFAULT_WIDTH * 0.5 / tan(M_PI / 6), 1e-9);
    vp.camera.up[2] = 0;
    vp.camera.up[1] = 1;
    CHECK(!mr_bcf_viewpoint_view(&vp, NULL, &bp, &v, &err) && strstr(err.msg, "parallel"));
    vp.camera_kind = MR_BCF_CAMERA_NONE;
    CHECK(!mr_bcf_viewpoint_view(&vp, NULL, &bp, &v, &err) && strstr(err.msg, "no camera"));
}

int main(void) {
    check_cpu();
    char dir[1024];
    if (!mr_test_fresh_dir("test_bcf_view", dir, sizeof dir)) return 1;
    mr_error err = {0};
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) return mr_test_no_gpu("test_bcf_view", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    if (r) {
        char sub[1100];
        snprintf(sub, sizeof sub, "%s/near", dir);
        check_offset(r, sub, 0);
        snprintf(sub, sizeof sub, "%s/far", dir);
        check_offset(r, sub, 1e7);
        snprintf(sub, sizeof sub, "%s/cli", dir);
        check_cli(sub);
    }
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return mr_test_finish("test_bcf_view");
}
