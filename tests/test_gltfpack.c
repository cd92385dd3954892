/* test_gltfpack.c — gltfpack's output reads as the file it was made from
 * (issue 17, item 7). The demo hall and a generated CAD part are written
 * as .glb, packed with Debian's gltfpack (KHR_mesh_quantization +
 * KHR_texture_transform by default; EXT_meshopt_compression with -c, and
 * with its octahedral-normal filter with -cc; -kn -km keeps the named node
 * tree, whose names must all survive), read by tinygltf's reference parse
 * (mr_gltf_parse_only, bench scene's raw_parse_s) and
 * rendered: depth and colour match the unpacked file's within the
 * quantisation error derived below. Load times are printed (median of 5;
 * never asserted). gltfpack is a dependency (scripts/deps.sh): a missing
 * gltfpack fails, it does not skip.
 *
 * The tolerance: gltfpack quantises positions to 14 bits (-vp 14) on a grid
 * no coarser than the scene's largest extent E / (2^14 - 1), rounding to the
 * nearest step, so every vertex moves by at most step/2 per axis, |d| <=
 * (sqrt 3 / 2) step = eps. A surface moved by eps moves its depth along a
 * ray by at most eps / cos(theta) (theta between the normal and the ray);
 * pixels at grazing angles (cos < 0.25) and within one pixel of a depth
 * edge (where the coverage may change: eps is far below a pixel here, which
 * the test checks) are left out. Normals are 8-bit (-vn 8): a unit normal
 * moves by <= sqrt(3) / 254 ~ 0.007, Lambert shading by as much of the
 * light, which sRGB at most ~13x amplifies near black: colours within 8
 * levels where depth matched (texels at quantised UVs can flip: 1 % may). */
#include "mr_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mr_eval.h"
#include "mr_render.h"
#include "mr_scene.h"

static char g_tmp[1024];

static bool have_gltfpack(void) { return system("command -v gltfpack >/dev/null 2>&1") == 0; }

static bool pack(const char *in, const char *out, const char *flags) {
    char cmd[16384];
    snprintf(cmd, sizeof cmd, "gltfpack %s -i '%s' -o '%s' >'%s.log' 2>&1", flags, in, out, out);
    int rc = system(cmd);
    CHECK_MSG(rc == 0, "gltfpack %s failed (%d): see %s.log", flags, rc, out);
    return rc == 0;
}

/* bench scene's reference parse (tinygltf alone) reads the file too. */
static void check_parse_only(const char *path) {
    mr_error err = {0};
    size_t n = 0;
    void *data = mr_file_read(path, &n, 0, &err);
    CHECK_MSG(data && mr_gltf_parse_only(data, n, &err), "parse only %s: %s", path, err.msg);
    free(data);
}

static mr_scene *load_timed(const char *path, double *median_ms) {
    double t[5];
    mr_scene *s = NULL;
    for (int i = 0; i < 5; i++) {
        mr_scene_destroy(&s);
        mr_error err = {0};
        double t0 = mr_time_now();
        s = mr_scene_load(path, NULL, &err);
        t[i] = (mr_time_now() - t0) * 1e3;
        CHECK_MSG(s != NULL, "%s: %s", path, err.msg);
        if (!s) return NULL;
    }
    *median_ms = mr_median(t, 5);
    return s;
}

static bool render(mr_renderer *r, const mr_scene *s, const mr_view *v, mr_frame_result *out) {
    mr_error err = {0};
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.want_depth = true;
    fp.want_normals = true;
    bool ok = mr_renderer_set_scene(r, s, &err) && mr_render_frame(r, v, &fp, out, &err);
    CHECK_MSG(ok, "render: %s", err.msg);
    return ok;
}

/* Compares b with the reference a as the header says. */
static void compare(const char *what, const mr_frame_result *a, const mr_frame_result *b, const mr_view *v,
                    double eps) {
    const int w = a->depth.width, h = a->depth.height;
    const float *za = a->depth.data, *zb = b->depth.data, *na = a->normal.data;
    const unsigned char *ca = a->color.data, *cb = b->color.data;
    double zmin = INFINITY;
    for (int i = 0; i < w * h; i++)
        if (za[i] > 0) zmin = fmin(zmin, za[i]);
    const double eps_px = eps * v->camera.fx / zmin;
    CHECK_MSG(eps_px < 0.5, "%s: the quantisation error is %.2f px: the view is too close for this test", what, eps_px);
    int checked = 0, bad_z = 0, bad_c = 0, covered = 0;
    double worst_ratio = 0;
    for (int y = 1; y < h - 1; y++)
        for (int x = 1; x < w - 1; x++) {
            int i = y * w + x;
            if (za[i] > 0) covered++;
            bool edge = false;
            for (int dy = -1; dy <= 1 && !edge; dy++)
                for (int dx = -1; dx <= 1 && !edge; dx++) {
                    int j = i + dy * w + dx;
                    edge = (za[j] > 0) != (za[i] > 0) || fabs(za[j] - za[i]) > 0.02 * za[i];
                }
            if (edge || !(za[i] > 0)) continue;
            /* cos theta: the normal (camera axes) against the ray through the
             * pixel; the smallest of the 3x3 neighbourhood, as the normals are
             * interpolated shading normals, not the faces' own. */
            double rx = (x + 0.5 - v->camera.cx) / v->camera.fx, ry = (y + 0.5 - v->camera.cy) / v->camera.fy;
            double rl = sqrt(rx * rx + ry * ry + 1), c = 1;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    const float *n = na + 3 * (i + dy * w + dx);
                    c = fmin(c, fabs(n[0] * rx + n[1] * ry + n[2]) / rl);
                }
            if (c < 0.25) continue;
            checked++;
            double tol = eps / c * 1.0001 + 2e-6 * za[i]; /* + float depth rounding */
            double dz = fabs((double)za[i] - zb[i]);
            if (!(zb[i] > 0) || dz > tol) bad_z++;
            worst_ratio = fmax(worst_ratio, dz / tol);
            int dc = 0;
            for (int k = 0; k < 3; k++) dc = abs(ca[3 * i + k] - cb[3 * i + k]) > dc ? abs(ca[3 * i + k] - cb[3 * i + k]) : dc;
            if (dc > 8) bad_c++;
        }
    printf("%s: %d px compared of %d covered, eps %.3g (%.3f px), depth off %d (worst %.2f of tolerance), colour off %d\n",
           what, checked, covered, eps, eps_px, bad_z, worst_ratio, bad_c);
    CHECK_MSG(checked > w * h / 4, "%s: only %d pixels to compare", what, checked);
    CHECK_MSG(bad_z == 0, "%s: %d pixels deeper or shallower than the quantisation allows", what, bad_z);
    CHECK_MSG(bad_c <= checked / 100, "%s: %d pixels differ in colour by more than 8 levels", what, bad_c);
}

/* gltfpack's default, -c (meshopt), -cc (meshopt with its filters:
 * octahedral normals), and -kn -km (named nodes and materials kept: the
 * node tree stays). */
static const char *const k_flags[] = {"", "-c", "-cc", "-kn -km"};
enum { k_variants = (int)(sizeof k_flags / sizeof k_flags[0]) };

static void check_packed(mr_renderer *r, const char *name, const mr_scene *src, const mr_view *v) {
    char path[1200], packed[k_variants][1200];
    snprintf(path, sizeof path, "%s/%s.glb", g_tmp, name);
    mr_error err = {0};
    CHECK_MSG(mr_scene_save_glb(src, path, &err), "%s", err.msg);
    for (int i = 0; i < k_variants; i++) {
        snprintf(packed[i], sizeof packed[i], "%s/%s_packed%d.glb", g_tmp, name, i);
        if (!pack(path, packed[i], k_flags[i])) return;
        check_parse_only(packed[i]);
    }
    double ms = 0, ms_p[k_variants];
    mr_scene *a = load_timed(path, &ms), *b[k_variants];
    for (int i = 0; i < k_variants; i++) b[i] = load_timed(packed[i], &ms_p[i]);
    printf("%s: load (median of 5) unpacked %.1f ms", name, ms);
    for (int i = 0; i < k_variants; i++) printf(", gltfpack %s %.1f ms", k_flags[i], ms_p[i]);
    printf("\n");
    bool all = a != NULL;
    for (int i = 0; i < k_variants; i++) all = all && b[i];
    if (all) {
        /* gltfpack drops degenerate triangles (the CAD part's poles); the images tell the rest. */
        uint64_t ta = mr_scene_triangle_count(a), tb = mr_scene_triangle_count(b[0]);
        CHECK_MSG(tb <= ta && tb > ta / 2, "%s: triangles %llu, packed %llu", name, (unsigned long long)ta,
                  (unsigned long long)tb);
        for (int i = 1; i < k_variants; i++) {
            uint64_t ti = mr_scene_triangle_count(b[i]);
            CHECK_MSG(ti == tb, "%s: gltfpack %s: %llu triangles, gltfpack %llu", name, k_flags[i],
                      (unsigned long long)ti, (unsigned long long)tb);
        }
        printf("%s: %llu triangles, packed %llu; nodes %d, packed %d, -kn -km %d\n", name, (unsigned long long)ta,
               (unsigned long long)tb, (int)a->node_count, (int)b[0]->node_count, (int)b[3]->node_count);
        /* -kn keeps every named node: each of the file's names is there. */
        int missing = 0;
        for (int32_t i = 0; i < a->node_count; i++) {
            bool found = false;
            for (int32_t j = 0; j < b[3]->node_count && !found; j++) found = strcmp(a->nodes[i].name, b[3]->nodes[j].name) == 0;
            missing += !found;
        }
        CHECK_MSG(missing == 0, "%s: gltfpack -kn -km: %d of %d node names lost", name, missing, (int)a->node_count);
        double e = 0;
        for (int k = 0; k < 3; k++) e = fmax(e, a->bounds_max[k] - a->bounds_min[k]);
        const double eps = sqrt(3.0) / 2.0 * e / 16383.0;
        mr_frame_result fa;
        memset(&fa, 0, sizeof fa);
        if (r && render(r, a, v, &fa)) {
            for (int i = 0; i < k_variants; i++) {
                mr_frame_result fb;
                memset(&fb, 0, sizeof fb);
                if (render(r, b[i], v, &fb)) {
                    char what[256];
                    snprintf(what, sizeof what, "%s gltfpack %s", name, k_flags[i]);
                    compare(what, &fa, &fb, v, eps);
                }
                mr_frame_result_free(&fb);
            }
        }
        mr_frame_result_free(&fa);
        if (r) mr_renderer_set_scene(r, NULL, &err);
    }
    mr_scene_destroy(&a);
    for (int i = 0; i < k_variants; i++) mr_scene_destroy(&b[i]);
}

/* A file whose meshopt views decode to more than a few MB decodes them on
 * both cores (gltf_io.cc, batch_decode): its meshes must be bit for bit
 * those of gltfpack's uncompressed file (the same quantised values; the
 * vertex and index codecs are lossless). A file whose every stream is
 * broken fails in one line, from that path too. */
static void check_batch(void) {
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    cp.parts = 16;
    cp.part_triangles = 40000;
    mr_error err = {0};
    mr_scene *cad = mr_synth_cad_build(&cp, &err);
    CHECK_MSG(cad != NULL, "%s", err.msg);
    if (!cad) return;
    char path[1200], plain[1200], packed[1200], broken[1200];
    snprintf(path, sizeof path, "%s/batch.glb", g_tmp);
    snprintf(plain, sizeof plain, "%s/batch_plain.glb", g_tmp);
    snprintf(packed, sizeof packed, "%s/batch_c.glb", g_tmp);
    snprintf(broken, sizeof broken, "%s/batch_broken.glb", g_tmp);
    CHECK_MSG(mr_scene_save_glb(cad, path, &err), "%s", err.msg);
    mr_scene_destroy(&cad);
    if (!pack(path, plain, "") || !pack(path, packed, "-c")) return;
    mr_scene *a = mr_scene_load(plain, NULL, &err);
    CHECK_MSG(a != NULL, "%s: %s", plain, err.msg);
    mr_scene *b = mr_scene_load(packed, NULL, &err);
    CHECK_MSG(b != NULL, "%s: %s", packed, err.msg);
    if (a && b) {
        uint64_t decoded = 0;
        for (int32_t i = 0; i < b->mesh_count; i++)
            decoded += (uint64_t)b->meshes[i].vertex_count * 6 + (uint64_t)b->meshes[i].index_count * 4;
        CHECK_MSG(decoded > (6u << 20), "the packed file decodes to only %llu bytes: too little for both cores",
                  (unsigned long long)decoded);
        CHECK_MSG(a->mesh_count == b->mesh_count, "meshes: %d plain, %d with -c", (int)a->mesh_count, (int)b->mesh_count);
        int differ = 0;
        for (int32_t i = 0; i < a->mesh_count && i < b->mesh_count; i++) {
            const mr_mesh *x = &a->meshes[i], *y = &b->meshes[i];
            bool same = x->vertex_count == y->vertex_count && x->index_count == y->index_count &&
                        !memcmp(x->positions, y->positions, (size_t)x->vertex_count * 12) &&
                        (x->normals == NULL) == (y->normals == NULL) &&
                        (!x->normals || !memcmp(x->normals, y->normals, (size_t)x->vertex_count * 12));
            /* The index codec keeps each triangle and its winding, not
             * always its first corner. */
            for (uint32_t t = 0; same && t + 2 < x->index_count; t += 3) {
                const uint32_t *p = x->indices + t, *q = y->indices + t;
                same = (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) || (p[0] == q[1] && p[1] == q[2] && p[2] == q[0]) ||
                       (p[0] == q[2] && p[1] == q[0] && p[2] == q[1]);
            }
            differ += !same;
        }
        CHECK_MSG(differ == 0, "%d of %d meshes differ between gltfpack and gltfpack -c", differ, (int)a->mesh_count);
    }
    mr_scene_destroy(&a);
    mr_scene_destroy(&b);
    /* Every byte of the BIN chunk zeroed: no stream has its header. */
    size_t n = 0;
    unsigned char *g = mr_file_read(packed, &n, 0, &err);
    CHECK_MSG(g && n > 28, "%s: %s", packed, err.msg);
    if (!g || n <= 28) {
        free(g);
        return;
    }
    uint32_t jlen;
    memcpy(&jlen, g + 12, 4);
    size_t bin = 20 + (size_t)jlen + 8;
    CHECK_MSG(bin < n, "%s: no BIN chunk", packed);
    if (bin < n) {
        memset(g + bin, 0, n - bin);
        CHECK_MSG(mr_file_write_atomic(broken, g, n, &err), "%s", err.msg);
        mr_error e = {0};
        mr_scene *c = mr_scene_load(broken, NULL, &e);
        CHECK_MSG(c == NULL, "a file with every meshopt stream zeroed loaded");
        CHECK_MSG(strstr(e.msg, "meshopt") && !strchr(e.msg, '\n'), "error: '%s'", e.msg);
        mr_scene_destroy(&c);
    }
    free(g);
}

int main(void) {
    const char *tmp = getenv("MR_TEST_TMP");
    snprintf(g_tmp, sizeof g_tmp, "%s/gltfpack", tmp && tmp[0] ? tmp : "/tmp/mrcheck_test");
    mr_error err = {0};
    if (!mr_mkdirs(g_tmp, &err)) {
        printf("cannot create %s: %s\n", g_tmp, err.msg);
        return 1;
    }
    mr_log_set_level(MR_LOG_ERROR);
    if (!have_gltfpack()) {
        CHECK_MSG(0, "gltfpack is not installed (scripts/deps.sh installs it)");
        return mr_test_finish("test_gltfpack");
    }
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    mr_renderer *r = gpu ? mr_renderer_create(gpu, &err) : NULL;
    const bool no_gpu = r == NULL;
    mr_error gpu_err = err;
    const int w = 160, h = 120;
    mr_camera cam = {w, h, 0.9 * w, 0.9 * w, (w - 1) / 2.0, (h - 1) / 2.0, {0, 0, 0, 0, 0}};

    mr_demo_hall hall;
    memset(&hall, 0, sizeof hall);
    CHECK_MSG(mr_demo_build_tagged(NULL, 0, &hall, &err), "%s", err.msg);
    if (hall.planned) {
        mr_view v = mr_demo_view(0);
        v.camera = cam;
        check_packed(r, "hall", hall.planned, &v);
    }
    mr_demo_free(&hall);

    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    cp.parts = 2;
    cp.part_triangles = 20000;
    mr_scene *cad = mr_synth_cad_build(&cp, &err);
    CHECK_MSG(cad != NULL, "%s", err.msg);
    if (cad) {
        mr_view v;
        v.camera = cam;
        v.world_from_camera = mr_synth_cad_viewpoint(&cp, MR_SYNTH_VIEW_OVERVIEW);
        check_packed(r, "cad", cad, &v);
    }
    mr_scene_destroy(&cad);
    check_batch();
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    if (no_gpu) return mr_test_no_gpu("test_gltfpack", &gpu_err);
    return mr_test_finish("test_gltfpack");
}
