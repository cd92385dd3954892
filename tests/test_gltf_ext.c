/* test_gltf_ext.c — what the field's tools write (issue 17, item 7) and big
 * or lying files (item 6): KHR_mesh_quantization, EXT_meshopt_compression
 * (encoded here with meshoptimizer), KHR_draco_mesh_compression (encoded
 * with libdraco, tests/draco_encode.cc), KHR_texture_transform, accessors
 * without a bufferView, sparse accessors, GLB BIN chunks; then truncated
 * and lying files (sizes past the end, counts of 2^31, byteLength lies,
 * bad meshopt streams, bad draco data), which must fail with one line, no
 * crash and bounded memory, and files over 2 and 4 GiB (sparse files: no
 * disk used). */
#include "mr_test.h"

#include <fcntl.h>
#include <math.h>
#include <meshoptimizer.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "mr_scene.h"

unsigned char *test_draco_encode(const float *pos, unsigned nv, const unsigned *idx, unsigned ntri, int bits,
                                 size_t *out_n, int *pos_id);

static char g_tmp[1024];

static bool one_line(const mr_error *e) { return e->msg[0] && !strchr(e->msg, '\n'); }

static double peak_rss_mb(void) {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss / 1024.0;
}

/* GLB container around json and bin (both padded to 4 bytes). */
static unsigned char *make_glb(const char *json, const void *bin, size_t bin_n, size_t *out_n) {
    size_t jn = strlen(json), jp = (jn + 3) & ~(size_t)3, bp = (bin_n + 3) & ~(size_t)3;
    size_t n = 12 + 8 + jp + (bin ? 8 + bp : 0);
    unsigned char *g = calloc(1, n);
    uint32_t h[5] = {0x46546C67u, 2, (uint32_t)n, (uint32_t)jp, 0x4E4F534Au};
    memcpy(g, h, 20);
    memcpy(g + 20, json, jn);
    memset(g + 20 + jn, ' ', jp - jn);
    if (bin) {
        uint32_t c[2] = {(uint32_t)bp, 0x004E4942u};
        memcpy(g + 20 + jp, c, 8);
        memcpy(g + 28 + jp, bin, bin_n);
    }
    *out_n = n;
    return g;
}

static mr_scene *load_glb(const char *json, const void *bin, size_t bin_n, mr_error *err) {
    size_t n;
    unsigned char *g = make_glb(json, bin, bin_n, &n);
    mr_scene *s = mr_scene_load_gltf_memory(g, n, NULL, NULL, err);
    free(g);
    return s;
}

/* Refused with one line containing needle, in bounded memory. */
static void expect_refused(const char *json, const void *bin, size_t bin_n, const char *needle, int line) {
    mr_error err = {0};
    double before = peak_rss_mb();
    mr_scene *s = load_glb(json, bin, bin_n, &err);
    CHECK_MSG(s == NULL, "line %d: loaded", line);
    CHECK_MSG(one_line(&err), "line %d: message '%s'", line, err.msg);
    if (needle) CHECK_MSG(strstr(err.msg, needle) != NULL, "line %d: '%s' lacks '%s'", line, err.msg, needle);
    CHECK_MSG(peak_rss_mb() - before < 64, "line %d: peak RSS grew by %.0f MB", line, peak_rss_mb() - before);
    mr_scene_destroy(&s);
}

static const float k_grid_step = 0.25f;

/* A 4x4 vertex grid in z = 0: 16 vertices, 18 triangles. */
static void grid(float pos[48], uint32_t idx[54]) {
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            pos[(y * 4 + x) * 3 + 0] = x * k_grid_step;
            pos[(y * 4 + x) * 3 + 1] = y * k_grid_step;
            pos[(y * 4 + x) * 3 + 2] = 0.1f * (float)(x * y);
        }
    int k = 0;
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 3; x++) {
            uint32_t a = (uint32_t)(y * 4 + x), b = a + 1, c = a + 4, d = a + 5;
            idx[k++] = a, idx[k++] = b, idx[k++] = d;
            idx[k++] = a, idx[k++] = d, idx[k++] = c;
        }
}

static const char *k_head = "\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"scene\":0,"
                            "\"nodes\":[{\"name\":\"N\",\"mesh\":0}],";

/* KHR_mesh_quantization: integer positions (plain and normalised), byte
 * normals, and the node transform that dequantises them. */
static void test_quantization(void) {
    /* 3 ushort positions (stride 8, padded), 3 normalised byte normals (stride 4), normalised short positions. */
    unsigned char bin[24 + 12 + 24];
    memset(bin, 0, sizeof bin);
    const uint16_t up[3][4] = {{0, 0, 0, 0}, {16383, 0, 0, 0}, {0, 16383, 7, 0}};
    memcpy(bin, up, 24);
    const int8_t nb[3][4] = {{0, 0, 127, 0}, {0, 0, -128, 0}, {127, 127, 0, 0}};
    memcpy(bin + 24, nb, 12);
    const int16_t sp[3][4] = {{0, 0, 0, 0}, {32767, 0, 0, 0}, {0, -32768, 0, 0}};
    memcpy(bin + 36, sp, 24);
    char json[4096];
    const char *fmt = "{%s\"extensionsUsed\":[\"KHR_mesh_quantization\"],\"extensionsRequired\":[\"KHR_mesh_quantization\"],"
                      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":%d,\"NORMAL\":1}}]}],"
                      "\"buffers\":[{\"byteLength\":60}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":24,\"byteStride\":8},"
                      "{\"buffer\":0,\"byteOffset\":24,\"byteLength\":12,\"byteStride\":4},"
                      "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":24,\"byteStride\":8}],"
                      "\"accessors\":[{\"bufferView\":0,\"componentType\":5123,\"count\":3,\"type\":\"VEC3\"},"
                      "{\"bufferView\":1,\"componentType\":5120,\"normalized\":true,\"count\":3,\"type\":\"VEC3\"},"
                      "{\"bufferView\":2,\"componentType\":5122,\"normalized\":true,\"count\":3,\"type\":\"VEC3\"}]}";
    snprintf(json, sizeof json, fmt, k_head, 0);
    mr_error err = {0};
    mr_scene *s = load_glb(json, bin, sizeof bin, &err);
    CHECK_MSG(s != NULL, "quantized: %s", err.msg);
    if (s) {
        const mr_mesh *m = &s->meshes[0];
        CHECK(m->vertex_count == 3 && m->normals != NULL);
        /* Stored relative to the mesh origin (the bounds centre). */
        CHECK_NEAR(m->positions[3] - m->positions[0], 16383.0, 1e-3);
        CHECK_NEAR(m->positions[7] - m->positions[1], 16383.0, 1e-3);
        CHECK_NEAR(m->positions[8] - m->positions[2], 7.0, 1e-4);
        if (m->normals) {
            CHECK_NEAR(m->normals[2], 1.0, 1e-6);
            CHECK_NEAR(m->normals[5], -1.0, 1e-6); /* -128 clamps to -1 */
            CHECK_NEAR(m->normals[6], sqrt(0.5), 1e-6); /* renormalised */
        }
    }
    mr_scene_destroy(&s);
    snprintf(json, sizeof json, fmt, k_head, 2);
    s = load_glb(json, bin, sizeof bin, &err);
    CHECK_MSG(s != NULL, "normalised short positions: %s", err.msg);
    if (s) {
        const mr_mesh *m = &s->meshes[0];
        CHECK_NEAR(m->positions[3] - m->positions[0], 1.0, 1e-6);
        CHECK_NEAR(m->positions[7] - m->positions[1], -1.0, 1e-6); /* -32768 -> -1 */
    }
    mr_scene_destroy(&s);
    /* Without the extension, integer positions stay refused (core glTF). */
    char plain[4096];
    snprintf(plain, sizeof plain, fmt, k_head, 0);
    char *ext = strstr(plain, "\"extensionsUsed\"");
    char *end = strstr(plain, "\"meshes\"");
    memmove(ext, end, strlen(end) + 1);
    expect_refused(plain, bin, sizeof bin, "KHR_mesh_quantization", __LINE__);
}

/* Accessors without a bufferView are zeros; sparse values replace elements. */
/* Every 8- and 16-bit component type, plain and normalised, as POSITION
 * (three per element) and TEXCOORD_0 (two), packed tightly and
 * interleaved, 39 vertices (the vector loop's tail too): each value as the
 * specification's conversion gives it, bit for bit; the extremes of each
 * type among them (-128 clamps to -1). */
static void test_quantized_values(void) {
    enum { nv = 39 };
    static const int types[4] = {5120, 5121, 5122, 5123};
    uint32_t rng = 99;
    int bad = 0, loaded = 0;
    for (int t = 0; t < 4; t++)
        for (int norm = 0; norm < 2; norm++)
            for (int inter = 0; inter < 2; inter++) {
                const int cs = types[t] <= 5121 ? 1 : 2;
                const bool sgn = types[t] == 5120 || types[t] == 5122;
                const double vmax = cs == 1 ? (sgn ? 127 : 255) : (sgn ? 32767 : 65535), vmin = sgn ? -vmax - 1 : 0;
                /* interleaved: position then uv in one stride (padded to 4); else two tight views */
                const size_t pe = 3 * (size_t)cs, ue = 2 * (size_t)cs, stride = inter ? ((pe + ue + 3) & ~(size_t)3) : 0;
                unsigned char bin[nv * 16 + nv * 8 + 16];
                memset(bin, 0, sizeof bin);
                int32_t val[nv][5];
                for (int v = 0; v < nv; v++)
                    for (int k = 0; k < 5; k++) {
                        rng = rng * 1664525u + 1013904223u;
                        double x = vmin + (double)(rng >> 8) / 16777216.0 * (vmax - vmin + 1);
                        if (v == 1) x = vmin; /* extremes in the vector loop */
                        if (v == 2) x = vmax;
                        if (v == nv - 1 && k == 4) x = vmin; /* and in the tail */
                        val[v][k] = (int32_t)floor(x);
                        size_t at = inter ? v * stride + (k < 3 ? (size_t)k * cs : pe + (size_t)(k - 3) * cs)
                                          : (k < 3 ? v * pe + (size_t)k * cs : nv * pe + 4 + v * ue + (size_t)(k - 3) * cs);
                        if (cs == 1) bin[at] = (unsigned char)(val[v][k] & 0xff);
                        else {
                            uint16_t h = (uint16_t)(val[v][k] & 0xffff);
                            memcpy(bin + at, &h, 2);
                        }
                    }
                const size_t bin_n = inter ? nv * stride : nv * pe + 4 + nv * ue;
                char views[256], json[2048];
                if (inter)
                    snprintf(views, sizeof views, "{\"buffer\":0,\"byteLength\":%zu,\"byteStride\":%zu}", bin_n, stride);
                else
                    snprintf(views, sizeof views, "{\"buffer\":0,\"byteLength\":%zu},{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}",
                             nv * pe, nv * pe + 4, nv * ue);
                snprintf(json, sizeof json,
                         "{%s\"extensionsUsed\":[\"KHR_mesh_quantization\"],\"extensionsRequired\":[\"KHR_mesh_quantization\"],"
                         "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1}}]}],"
                         "\"buffers\":[{\"byteLength\":%zu}],\"bufferViews\":[%s],"
                         "\"accessors\":[{\"bufferView\":0,\"componentType\":%d,%s\"count\":%d,\"type\":\"VEC3\"},"
                         "{\"bufferView\":%d,\"byteOffset\":%zu,\"componentType\":%d,%s\"count\":%d,\"type\":\"VEC2\"}]}",
                         k_head, bin_n, views, types[t], norm ? "\"normalized\":true," : "", nv, inter ? 0 : 1,
                         inter ? pe : 0, types[t], norm ? "\"normalized\":true," : "", nv);
                mr_error err = {0};
                mr_scene *s = load_glb(json, bin, bin_n, &err);
                CHECK_MSG(s && s->mesh_count == 1, "type %d norm %d inter %d: %s", types[t], norm, inter, err.msg);
                if (!s || s->mesh_count != 1) {
                    mr_scene_destroy(&s);
                    continue;
                }
                loaded++;
                const mr_mesh *m = &s->meshes[0];
                float f[nv][5];
                double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
                for (int v = 0; v < nv; v++)
                    for (int k = 0; k < 5; k++) {
                        f[v][k] = norm ? (float)fmax(val[v][k] * (1.0 / vmax), sgn ? -1.0 : 0.0) : (float)val[v][k];
                        if (k < 3) lo[k] = fmin(lo[k], f[v][k]), hi[k] = fmax(hi[k], f[v][k]);
                    }
                for (int v = 0; v < nv; v++)
                    for (int k = 0; k < 5; k++) {
                        float want = k < 3 ? (float)((double)f[v][k] - (0.5 * lo[k] + 0.5 * hi[k])) : f[v][k];
                        float got = k < 3 ? m->positions[3 * v + k] : (m->uvs ? m->uvs[2 * v + k - 3] : NAN);
                        bad += memcmp(&want, &got, sizeof want) != 0 && !(want == 0.0f && got == 0.0f);
                    }
                mr_scene_destroy(&s);
            }
    CHECK_MSG(loaded == 16, "%d of 16 quantised files loaded", loaded);
    CHECK_MSG(bad == 0, "%d converted values differ from the specification's", bad);
}

static void test_sparse_and_zeros(void) {
    /* sparse indices (ushort 1, 2) and values (2 float3). */
    unsigned char bin[4 + 24];
    const uint16_t si[2] = {1, 2};
    const float sv[6] = {1, 0, 0, 0, 2, 0};
    memcpy(bin, si, 4);
    memcpy(bin + 4, sv, 24);
    char json[4096];
    snprintf(json, sizeof json,
             "{%s\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"buffers\":[{\"byteLength\":28}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":4},"
             "{\"buffer\":0,\"byteOffset\":4,\"byteLength\":24}],"
             "\"accessors\":[{\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"sparse\":{\"count\":2,"
             "\"indices\":{\"bufferView\":0,\"componentType\":5123},\"values\":{\"bufferView\":1}}}]}",
             k_head);
    mr_error err = {0};
    mr_scene *s = load_glb(json, bin, sizeof bin, &err);
    CHECK_MSG(s != NULL, "sparse without bufferView: %s", err.msg);
    if (s) {
        const mr_mesh *m = &s->meshes[0];
        float o[3] = {(float)-m->origin[0], (float)-m->origin[1], (float)-m->origin[2]};
        (void)o;
        /* vertex 0 zero, 1 (1,0,0), 2 (0,2,0): relative differences */
        CHECK_NEAR(m->positions[3] - m->positions[0], 1.0, 1e-6);
        CHECK_NEAR(m->positions[7] - m->positions[1], 2.0, 1e-6);
        CHECK_NEAR(m->positions[4] - m->positions[1], 0.0, 1e-6);
    }
    mr_scene_destroy(&s);
    /* Sparse index out of range, sparse count past the values, count 2^31. */
    char bad[4096];
    const uint16_t si_bad[2] = {1, 9};
    unsigned char bin2[28];
    memcpy(bin2, bin, 28);
    memcpy(bin2, si_bad, 4);
    expect_refused(json, bin2, sizeof bin2, "sparse index", __LINE__);
    snprintf(bad, sizeof bad, "%s", json);
    char *c = strstr(bad, "\"count\":2");
    c[8] = '3';
    expect_refused(bad, bin, sizeof bin, "sparse", __LINE__);
    snprintf(bad, sizeof bad,
             "{%s\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"accessors\":[{\"componentType\":5126,\"count\":2147483648,\"type\":\"VEC3\"}]}",
             k_head);
    expect_refused(bad, NULL, 0, "without a bufferView", __LINE__);
}

/* Sparse accessors over a strided bufferView, every part at its own
 * non-zero offset (accessor, sparse indices, sparse values) and other
 * bytes where a wrong offset would land: float POSITION with ushort
 * indices, normalised SHORT TEXCOORD_0 with ubyte indices. Every value
 * bit for bit as the specification converts it (c / 32767, -32768 clamps
 * to -1). */
static void put16(unsigned char *b, size_t at, int v) {
    uint16_t h = (uint16_t)(v & 0xffff);
    memcpy(b + at, &h, 2);
}

static void test_sparse_offsets(void) {
    enum { nv = 6 };
    unsigned char bin[256];
    for (size_t i = 0; i < sizeof bin; i++) bin[i] = (unsigned char)(0x5a ^ (i * 37)); /* no zeros to hide in */
    /* view 0 (0..100): positions, stride 16, accessor offset 4 */
    float pos[nv][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 1}, {3, 0, 1}, {2, 1.5f, 1}};
    for (int v = 0; v < nv; v++) memcpy(bin + 4 + 16 * v, pos[v], 12);
    /* view 1 (100..176): uvs, stride 12, accessor offset 4, normalised SHORT */
    int uv[nv][2] = {{100, -200}, {3000, 4000}, {-5000, 6000}, {7000, -8000}, {9000, 10000}, {-11000, 12000}};
    for (int v = 0; v < nv; v++) put16(bin, 100 + 4 + 12 * (size_t)v, uv[v][0]), put16(bin, 100 + 6 + 12 * (size_t)v, uv[v][1]);
    /* view 2 (176..184): position sparse indices (ushort 0, 3) at offset 2 */
    put16(bin, 178, 0), put16(bin, 180, 3);
    /* view 3 (184..216): position sparse values (2 float3) at offset 6 */
    const float spv[2][3] = {{-1.25f, 0.5f, 0.75f}, {2.5f, -0.5f, 1.125f}};
    memcpy(bin + 190, spv, 24);
    /* view 4 (216..224): uv sparse indices (ubyte 1, 4, 5) at offset 3 */
    bin[219] = 1, bin[220] = 4, bin[221] = 5;
    /* view 5 (224..256): uv sparse values (3 short2) at offset 8 */
    const int suv[3][2] = {{32767, -32768}, {-32767, 12345}, {1, -1}};
    for (int i = 0; i < 3; i++) put16(bin, 224 + 8 + 4 * (size_t)i, suv[i][0]), put16(bin, 224 + 10 + 4 * (size_t)i, suv[i][1]);
    char json[4096];
    snprintf(json, sizeof json,
             "{%s\"extensionsUsed\":[\"KHR_mesh_quantization\"],\"extensionsRequired\":[\"KHR_mesh_quantization\"],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1}}]}],"
             "\"buffers\":[{\"byteLength\":256}],\"bufferViews\":["
             "{\"buffer\":0,\"byteLength\":100,\"byteStride\":16},{\"buffer\":0,\"byteOffset\":100,\"byteLength\":76,\"byteStride\":12},"
             "{\"buffer\":0,\"byteOffset\":176,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":184,\"byteLength\":32},"
             "{\"buffer\":0,\"byteOffset\":216,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":224,\"byteLength\":32}],"
             "\"accessors\":[{\"bufferView\":0,\"byteOffset\":4,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\","
             "\"sparse\":{\"count\":2,\"indices\":{\"bufferView\":2,\"byteOffset\":2,\"componentType\":5123},"
             "\"values\":{\"bufferView\":3,\"byteOffset\":6}}},"
             "{\"bufferView\":1,\"byteOffset\":4,\"componentType\":5122,\"normalized\":true,\"count\":%d,\"type\":\"VEC2\","
             "\"sparse\":{\"count\":3,\"indices\":{\"bufferView\":4,\"byteOffset\":3,\"componentType\":5121},"
             "\"values\":{\"bufferView\":5,\"byteOffset\":8}}}]}",
             k_head, nv, nv);
    memcpy(pos[0], spv[0], 12);
    memcpy(pos[3], spv[1], 12);
    for (int i = 0; i < 3; i++) uv[(int[]){1, 4, 5}[i]][0] = suv[i][0], uv[(int[]){1, 4, 5}[i]][1] = suv[i][1];
    mr_error err = {0};
    mr_scene *s = load_glb(json, bin, sizeof bin, &err);
    CHECK_MSG(s && s->mesh_count == 1 && s->meshes[0].vertex_count == nv && s->meshes[0].uvs, "sparse offsets: %s",
              err.msg);
    if (s && s->mesh_count == 1 && s->meshes[0].vertex_count == nv && s->meshes[0].uvs) {
        const mr_mesh *m = &s->meshes[0];
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int v = 0; v < nv; v++)
            for (int k = 0; k < 3; k++) lo[k] = fmin(lo[k], pos[v][k]), hi[k] = fmax(hi[k], pos[v][k]);
        int bad = 0;
        for (int v = 0; v < nv; v++) {
            for (int k = 0; k < 3; k++) {
                float want = (float)((double)pos[v][k] - (0.5 * lo[k] + 0.5 * hi[k]));
                bad += memcmp(&want, &m->positions[3 * v + k], 4) != 0 && !(want == 0 && m->positions[3 * v + k] == 0);
            }
            for (int k = 0; k < 2; k++) {
                float want = (float)fmax(uv[v][k] / 32767.0, -1.0);
                CHECK_MSG(memcmp(&want, &m->uvs[2 * v + k], 4) == 0, "uv %d.%d: %.9g, want %.9g", v, k, m->uvs[2 * v + k],
                          want);
            }
        }
        CHECK_MSG(bad == 0, "%d sparse-substituted positions differ", bad);
    }
    mr_scene_destroy(&s);
}

/* The GLB container and its lies. */
static void test_glb_lies(void) {
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    char json[4096];
    const char *fmt = "{%s\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                      "\"buffers\":[{\"byteLength\":%s}],\"bufferViews\":[{\"buffer\":0,\"byteOffset\":%s,\"byteLength\":36}],"
                      "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%s,\"type\":\"VEC3\"}]}";
    snprintf(json, sizeof json, fmt, k_head, "36", "0", "3");
    mr_error err = {0};
    mr_scene *s = load_glb(json, pos, sizeof pos, &err);
    CHECK_MSG(s != NULL && s->mesh_count == 1, "plain GLB: %s", err.msg);
    mr_scene_destroy(&s);
    snprintf(json, sizeof json, fmt, k_head, "4294967296", "0", "3");
    expect_refused(json, pos, sizeof pos, "byteLength", __LINE__);
    snprintf(json, sizeof json, fmt, k_head, "36", "4294967200", "3");
    expect_refused(json, pos, sizeof pos, "outside its buffer", __LINE__);
    snprintf(json, sizeof json, fmt, k_head, "36", "0", "2147483648");
    expect_refused(json, pos, sizeof pos, "runs past the end", __LINE__);
    /* Truncations: every prefix fails with one line (or loads, never crashes). */
    snprintf(json, sizeof json, fmt, k_head, "36", "0", "3");
    size_t n;
    unsigned char *g = make_glb(json, pos, sizeof pos, &n);
    int refused = 0;
    for (size_t cut = 0; cut < n; cut += 7) {
        mr_scene *t = mr_scene_load_gltf_memory(g, cut, NULL, NULL, &err);
        if (!t) {
            refused++;
            CHECK_MSG(one_line(&err), "cut %zu: '%s'", cut, err.msg);
        }
        mr_scene_destroy(&t);
    }
    CHECK(refused > 0);
    /* The header's length past the data, and a JSON chunk past the end. */
    mr_scene *t = mr_scene_load_gltf_memory(g, n - 4, NULL, NULL, &err);
    CHECK_MSG(!t && strstr(err.msg, "truncated"), "'%s'", err.msg);
    mr_scene_destroy(&t);
    uint32_t big = 0x7FFFFFF0u;
    memcpy(g + 12, &big, 4);
    memcpy(g + 8, &big, 4);
    t = mr_scene_load_gltf_memory(g, n, NULL, NULL, &err);
    CHECK_MSG(!t && one_line(&err), "'%s'", err.msg);
    mr_scene_destroy(&t);
    free(g);
    /* A buffer without uri that is not the BIN chunk. */
    snprintf(json, sizeof json,
             "{%s\"buffers\":[{\"byteLength\":36},{\"byteLength\":8}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"bufferViews\":[{\"buffer\":1,\"byteLength\":8}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}]}",
             k_head);
    expect_refused(json, pos, sizeof pos, "buffer 1 has no data", __LINE__);
    /* Anything still unsupported is refused by name. */
    snprintf(json, sizeof json, "{%s\"extensionsRequired\":[\"EXT_mesh_gpu_instancing\"],\"buffers\":[{\"byteLength\":99}]}", k_head);
    expect_refused(json, NULL, 0, "EXT_mesh_gpu_instancing", __LINE__);
    /* Buffers as data: URIs with the glTF buffer MIME type. */
    const char *du = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],"
                     "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                     "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/gltf-buffer;base64,"
                     "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
                     "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                     "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}]}";
    s = mr_scene_load_gltf_memory(du, strlen(du), NULL, NULL, &err);
    CHECK_MSG(s != NULL && s->mesh_count == 1 && s->meshes[0].vertex_count == 3, "data URI: %s", err.msg);
    mr_scene_destroy(&s);
}

/* EXT_meshopt_compression: vertex and index streams from meshoptimizer's
 * encoders, with the fallback buffer gltfpack writes; then broken streams. */
static void test_meshopt(void) {
    float pos[48];
    uint32_t idx[54];
    grid(pos, idx);
    unsigned char vb[1024], ib[1024];
    size_t vn = meshopt_encodeVertexBuffer(vb, sizeof vb, pos, 16, 12);
    size_t in = meshopt_encodeIndexBuffer(ib, sizeof ib, idx, 54);
    CHECK(vn > 0 && in > 0);
    size_t vp = (vn + 3) & ~(size_t)3;
    unsigned char bin[2048];
    memcpy(bin, vb, vn);
    memset(bin + vn, 0, vp - vn);
    memcpy(bin + vp, ib, in);
    size_t bn = vp + in;
    char json[4096];
    const char *fmt =
        "{%s\"extensionsUsed\":[\"EXT_meshopt_compression\"],\"extensionsRequired\":[\"EXT_meshopt_compression\"],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"buffers\":[{\"byteLength\":%zu},{\"byteLength\":300,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
        "\"bufferViews\":[{\"buffer\":1,\"byteLength\":192,\"byteStride\":12,\"extensions\":{\"EXT_meshopt_compression\":"
        "{\"buffer\":0,\"byteLength\":%zu,\"byteStride\":12,\"count\":%s,\"mode\":\"ATTRIBUTES\"}}},"
        "{\"buffer\":1,\"byteOffset\":192,\"byteLength\":108,\"extensions\":{\"EXT_meshopt_compression\":"
        "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":2,\"count\":54,\"mode\":\"%s\"}}}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":54,\"type\":\"SCALAR\"}]}";
    snprintf(json, sizeof json, fmt, k_head, bn, vn, "16", vp, in, "TRIANGLES");
    mr_error err = {0};
    mr_scene *s = load_glb(json, bin, bn, &err);
    CHECK_MSG(s != NULL, "meshopt: %s", err.msg);
    if (s) {
        const mr_mesh *m = &s->meshes[0];
        CHECK(m->vertex_count == 16 && m->index_count == 54);
        double worst = 0;
        for (int i = 0; i < 48 && m->vertex_count == 16; i++)
            worst = fmax(worst, fabs(m->positions[i] + m->origin[i % 3] - pos[i]));
        CHECK_MSG(worst < 1e-6, "meshopt positions off by %g", worst); /* the vertex codec is lossless */
        bool same = m->index_count == 54;
        for (int i = 0; same && i < 54; i++) same = m->indices[i] < 16;
        CHECK(same);
    }
    mr_scene_destroy(&s);
    /* tinygltf's reference parse (bench scene's raw_parse_s) reads it too:
     * it took the fallback buffer for the GLB's BIN chunk. */
    size_t gn = 0;
    unsigned char *g = make_glb(json, bin, bn, &gn);
    CHECK_MSG(mr_gltf_parse_only(g, gn, &err), "parse only, meshopt fallback buffer: %s", err.msg);
    free(g);
    /* Lies and damage: counts of 2^31, streams cut short, garbage. */
    snprintf(json, sizeof json, fmt, k_head, bn, vn, "2147483648", vp, in, "TRIANGLES");
    expect_refused(json, bin, bn, "meshopt", __LINE__);
    /* 1e8 vertices (1.2 GB) from a 100-byte stream: refused before allocating. */
    snprintf(json, sizeof json, fmt, k_head, bn, vn, "100000000", vp, in, "TRIANGLES");
    expect_refused(json, bin, bn, "can hold", __LINE__);
    snprintf(json, sizeof json, fmt, k_head, bn, vn - 5, "16", vp, in, "TRIANGLES");
    expect_refused(json, bin, bn, "malformed meshopt", __LINE__);
    snprintf(json, sizeof json, fmt, k_head, bn, vn, "16", vp, in, "SPIRALS");
    expect_refused(json, bin, bn, "SPIRALS", __LINE__);
    snprintf(json, sizeof json, fmt, k_head, bn + 64, vn, "16", vp, in, "TRIANGLES");
    expect_refused(json, bin, bn, "byteLength", __LINE__);
    snprintf(json, sizeof json, fmt, k_head, bn, vn, "16", vp, in, "TRIANGLES");
    unsigned char junk[2048];
    memcpy(junk, bin, bn);
    for (size_t i = 0; i < vn; i++) junk[i] = (unsigned char)(i * 37 + 11);
    expect_refused(json, junk, bn, "meshopt", __LINE__);
    for (int trial = 0; trial < 200; trial++) { /* random damage: one line or a load, never a crash */
        memcpy(junk, bin, bn);
        junk[(size_t)(trial * 7919) % bn] ^= (unsigned char)(1 + trial % 255);
        mr_scene *t = load_glb(json, junk, bn, &err);
        if (!t) CHECK_MSG(one_line(&err), "trial %d: '%s'", trial, err.msg);
        mr_scene_destroy(&t);
    }
    /* A view of the fallback buffer without the extension has no data. */
    char nofb[4096];
    snprintf(nofb, sizeof nofb,
             "{%s\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"buffers\":[{\"byteLength\":4},{\"byteLength\":36,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
             "\"bufferViews\":[{\"buffer\":1,\"byteLength\":36}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}]}",
             k_head);
    expect_refused(nofb, "abcd", 4, "fallback", __LINE__);
}

/* A 32-bit index view holding two primitives' lists stays one buffer,
 * owned by the scene, each mesh's indices a part of it (no copy): the
 * meshes are right, the scene frees it once; an index out of range in the
 * second list fails the load with one line and frees nothing twice (ASan
 * runs this too). */
static void test_meshopt_slices(void) {
    float pos[48];
    uint32_t idx[54], two[108];
    grid(pos, idx);
    unsigned char vb[1024], ib[1024];
    size_t vn = meshopt_encodeVertexBuffer(vb, sizeof vb, pos, 16, 12);
    CHECK(vn > 0);
    for (int bad = 0; bad < 2; bad++) {
        for (int i = 0; i < 54; i++) two[i] = idx[i], two[54 + i] = idx[53 - i];
        if (bad) two[54 + 40] = 16; /* the grid has 16 vertices */
        size_t in = meshopt_encodeIndexBuffer(ib, sizeof ib, two, 108);
        CHECK(in > 0);
        size_t vp = (vn + 3) & ~(size_t)3;
        unsigned char bin[4096];
        memset(bin, 0, sizeof bin);
        memcpy(bin, vb, vn);
        memcpy(bin + vp, ib, in);
        char json[4096];
        snprintf(json, sizeof json,
                 "{%s\"extensionsUsed\":[\"EXT_meshopt_compression\"],\"extensionsRequired\":[\"EXT_meshopt_compression\"],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":2},"
                 "{\"attributes\":{\"POSITION\":1},\"indices\":3}]}],"
                 "\"buffers\":[{\"byteLength\":%zu},{\"byteLength\":1000,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
                 "\"bufferViews\":[{\"buffer\":1,\"byteLength\":192,\"byteStride\":12,\"extensions\":{\"EXT_meshopt_compression\":"
                 "{\"buffer\":0,\"byteLength\":%zu,\"byteStride\":12,\"count\":16,\"mode\":\"ATTRIBUTES\"}}},"
                 "{\"buffer\":1,\"byteOffset\":192,\"byteLength\":432,\"extensions\":{\"EXT_meshopt_compression\":"
                 "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":4,\"count\":108,\"mode\":\"TRIANGLES\"}}}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
                 "{\"bufferView\":0,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
                 "{\"bufferView\":1,\"componentType\":5125,\"count\":54,\"type\":\"SCALAR\"},"
                 "{\"bufferView\":1,\"byteOffset\":216,\"componentType\":5125,\"count\":54,\"type\":\"SCALAR\"}]}",
                 k_head, vp + in, vn, vp, in);
        if (bad) {
            expect_refused(json, bin, vp + in, "out of range", __LINE__);
            continue;
        }
        mr_error err = {0};
        mr_scene *s = load_glb(json, bin, vp + in, &err);
        CHECK_MSG(s && s->mesh_count == 2, "slices: %s", err.msg);
        if (!s || s->mesh_count != 2) {
            mr_scene_destroy(&s);
            continue;
        }
        CHECK_MSG(s->block_count == 1, "%d blocks: the index lists were copied", (int)s->block_count);
        const mr_mesh *a = &s->meshes[0], *b = &s->meshes[1];
        CHECK(a->index_count == 54 && b->index_count == 54 && b->indices == a->indices + 54);
        bool same = a->index_count == 54 && b->index_count == 54;
        for (int t = 0; same && t < 54; t += 3) /* the codec may rotate a triangle's corners */
            for (int k = 0; k < 2; k++) {
                const uint32_t *x = (k ? b : a)->indices + t, *y = two + 54 * k + t;
                same = same && ((x[0] == y[0] && x[1] == y[1] && x[2] == y[2]) || (x[0] == y[1] && x[1] == y[2] && x[2] == y[0]) ||
                                (x[0] == y[2] && x[1] == y[0] && x[2] == y[1]));
            }
        CHECK_MSG(same, "slices: indices differ");
        mr_scene_destroy(&s);
    }
}

/* gltfpack's layout: one meshopt view holds the vertices (and one the
 * indices) of several primitives, each an accessor at its own offset;
 * these are converted straight into the meshes' arrays. An accessor read by
 * two primitives, and a NORMAL that does not fit its primitive, take the
 * general path. Every mesh must be exactly its own grid. */
static void test_meshopt_shared(void) {
    float pos[96], nrm[96];
    uint32_t idx[54];
    uint32_t idx2[108];
    grid(pos, idx);
    for (int i = 0; i < 48; i++) pos[48 + i] = pos[i] + (i % 3 == 0 ? 5.0f : 0.0f); /* grid B: 5 to the right */
    /* Tile B lists the grid's triangles in reverse order. */
    for (int i = 0; i < 54; i++) idx2[i] = idx[i], idx2[54 + i] = idx[(17 - i / 3) * 3 + i % 3];
    for (int i = 0; i < 96; i++) nrm[i] = i % 3 == 2 ? 1.0f : 0.0f;
    unsigned char vb[2048], nb[2048], ib[1024];
    size_t vn = meshopt_encodeVertexBuffer(vb, sizeof vb, pos, 32, 12);
    size_t nn = meshopt_encodeVertexBuffer(nb, sizeof nb, nrm, 32, 12);
    size_t in = meshopt_encodeIndexBuffer(ib, sizeof ib, idx2, 108);
    CHECK(vn > 0 && nn > 0 && in > 0);
    size_t vp = (vn + 3) & ~(size_t)3, np = (nn + 3) & ~(size_t)3;
    unsigned char bin[8192];
    memset(bin, 0, sizeof bin);
    memcpy(bin, vb, vn);
    memcpy(bin + vp, nb, nn);
    memcpy(bin + vp + np, ib, in);
    size_t bn = vp + np + in;
    for (int variant = 0; variant < 4; variant++) {
        /* 0: two primitives in two tiles of each view; 1: and a second mesh
         * reading mesh 0's first accessors again; 2: the second normal
         * accessor is 15 long for 16 vertices; 3: 32-bit indices, whose
         * view (decoded last) becomes the first mesh's index array. */
        const int is = variant == 3 ? 4 : 2;
        char json[8192];
        snprintf(json, sizeof json,
                 "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0%s]}],\"scene\":0,"
                 "\"nodes\":[{\"name\":\"N\",\"mesh\":0}%s],"
                 "\"extensionsUsed\":[\"EXT_meshopt_compression\"],\"extensionsRequired\":[\"EXT_meshopt_compression\"],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":4},\"indices\":2},"
                 "{\"attributes\":{\"POSITION\":1,\"NORMAL\":5},\"indices\":3}]}%s],"
                 "\"buffers\":[{\"byteLength\":%zu},{\"byteLength\":1000,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
                 "\"bufferViews\":[{\"buffer\":1,\"byteLength\":384,\"byteStride\":12,\"extensions\":{\"EXT_meshopt_compression\":"
                 "{\"buffer\":0,\"byteLength\":%zu,\"byteStride\":12,\"count\":32,\"mode\":\"ATTRIBUTES\"}}},"
                 "{\"buffer\":1,\"byteOffset\":384,\"byteLength\":%d,\"extensions\":{\"EXT_meshopt_compression\":"
                 "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":%d,\"count\":108,\"mode\":\"TRIANGLES\"}}},"
                 "{\"buffer\":1,\"byteOffset\":600,\"byteLength\":384,\"byteStride\":12,\"extensions\":{\"EXT_meshopt_compression\":"
                 "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":12,\"count\":32,\"mode\":\"ATTRIBUTES\"}}}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
                 "{\"bufferView\":0,\"byteOffset\":192,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
                 "{\"bufferView\":1,\"componentType\":%d,\"count\":54,\"type\":\"SCALAR\"},"
                 "{\"bufferView\":1,\"byteOffset\":%d,\"componentType\":%d,\"count\":54,\"type\":\"SCALAR\"},"
                 "{\"bufferView\":2,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
                 "{\"bufferView\":2,\"byteOffset\":192,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"}]}",
                 variant == 1 ? ",1" : "", variant == 1 ? ",{\"name\":\"M\",\"mesh\":1}" : "",
                 variant == 1 ? ",{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":4},\"indices\":2}]}" : "", bn, vn, 108 * is, vp + np,
                 in, is, vp, nn, is == 4 ? 5125 : 5123, 54 * is, is == 4 ? 5125 : 5123, variant == 2 ? 15 : 16);
        mr_error err = {0};
        mr_scene *s = load_glb(json, bin, bn, &err);
        CHECK_MSG(s != NULL, "variant %d: %s", variant, err.msg);
        if (!s) continue;
        CHECK_MSG(s->mesh_count == (variant == 1 ? 3 : 2), "variant %d: %d meshes", variant, (int)s->mesh_count);
        for (int32_t k = 0; k < s->mesh_count; k++) {
            const mr_mesh *m = &s->meshes[k];
            const float *want = pos + (k == 1 ? 48 : 0); /* mesh 1's second primitive is grid B */
            double worst = 0;
            for (int i = 0; i < 48 && m->vertex_count == 16; i++)
                worst = fmax(worst, fabs(m->positions[i] + m->origin[i % 3] - want[i]));
            CHECK_MSG(m->vertex_count == 16 && m->index_count == 54 && worst < 1e-6,
                      "variant %d mesh %d: %u vertices, %u indices, off by %g", variant, (int)k, m->vertex_count,
                      m->index_count, worst);
            bool same = m->index_count == 54; /* the codec may rotate a triangle's corners */
            const uint32_t *want_idx = idx2 + (k == 1 ? 54 : 0);
            for (int t = 0; same && t < 54; t += 3) {
                const uint32_t *a = m->indices + t, *b = want_idx + t;
                same = (a[0] == b[0] && a[1] == b[1] && a[2] == b[2]) || (a[0] == b[1] && a[1] == b[2] && a[2] == b[0]) ||
                       (a[0] == b[2] && a[1] == b[0] && a[2] == b[1]);
            }
            CHECK_MSG(same, "variant %d mesh %d: indices differ", variant, (int)k);
            double nz = 0;
            for (uint32_t v = 0; v < m->vertex_count; v++) nz += m->normals[3 * v + 2];
            /* The file's normals (0,0,1); variant 2's second mesh makes its own
             * from the grid (whose z rises with x*y: not all (0,0,1)). */
            if (!(variant == 2 && k == 1)) CHECK_MSG(nz == 16.0, "variant %d mesh %d: normals not the file's", variant, (int)k);
            else CHECK_MSG(nz < 15.99, "variant %d: the short NORMAL was used", variant);
        }
        mr_scene_destroy(&s);
    }
}

/* A meshopt view big enough (over 8 MB decoded) to be converted on two
 * threads, each primitive's elements split in halves: every vertex exact
 * (the codec is lossless), in both primitives. */
static void test_meshopt_big(void) {
    const size_t nv = 400000, n = 2 * nv; /* two primitives of 400k vertices: 9.6 MB of floats */
    float *pos = malloc(n * 12);
    size_t cap = meshopt_encodeVertexBufferBound(n, 12);
    unsigned char *bin = malloc(cap + 64);
    CHECK(pos && bin);
    if (!pos || !bin) {
        free(pos);
        free(bin);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        pos[3 * i + 0] = (float)(i % 1000) * 0.01f;
        pos[3 * i + 1] = (float)(i / 1000) * 0.01f;
        pos[3 * i + 2] = (float)((i * 7) % 13) * 0.1f;
    }
    size_t vn = meshopt_encodeVertexBuffer(bin, cap, pos, n, 12);
    CHECK(vn > 0);
    size_t vp = (vn + 3) & ~(size_t)3;
    uint32_t tri[3] = {0, 1, 2};
    unsigned char ib[64];
    size_t in = meshopt_encodeIndexBuffer(ib, sizeof ib, tri, 3);
    memset(bin + vn, 0, vp - vn);
    memcpy(bin + vp, ib, in);
    size_t bn = vp + in;
    char json[4096];
    snprintf(json, sizeof json,
             "{%s\"extensionsUsed\":[\"EXT_meshopt_compression\"],\"extensionsRequired\":[\"EXT_meshopt_compression\"],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":2},{\"attributes\":{\"POSITION\":1},\"indices\":3}]}],"
             "\"buffers\":[{\"byteLength\":%zu},{\"byteLength\":%zu,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
             "\"bufferViews\":[{\"buffer\":1,\"byteLength\":%zu,\"byteStride\":12,\"extensions\":{\"EXT_meshopt_compression\":"
             "{\"buffer\":0,\"byteLength\":%zu,\"byteStride\":12,\"count\":%zu,\"mode\":\"ATTRIBUTES\"}}},"
             "{\"buffer\":1,\"byteOffset\":%zu,\"byteLength\":6,\"extensions\":{\"EXT_meshopt_compression\":"
             "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":2,\"count\":3,\"mode\":\"TRIANGLES\"}}}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%zu,\"type\":\"VEC3\"},"
             "{\"bufferView\":0,\"byteOffset\":%zu,\"componentType\":5126,\"count\":%zu,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]}",
             k_head, bn, n * 12 + 12, n * 12, vn, n, n * 12, vp, in, nv, nv * 12, nv);
    mr_error err = {0};
    mr_scene *s = load_glb(json, bin, bn, &err);
    CHECK_MSG(s != NULL, "big meshopt view: %s", err.msg);
    for (int32_t k = 0; s && k < 2 && k < s->mesh_count; k++) {
        const mr_mesh *m = &s->meshes[k];
        size_t bad = 0;
        for (size_t i = 0; i < nv * 3 && m->vertex_count == nv; i++)
            bad += (double)m->positions[i] + m->origin[i % 3] != (double)pos[(k ? nv * 3 : 0) + i] &&
                   fabs((double)m->positions[i] + m->origin[i % 3] - pos[(k ? nv * 3 : 0) + i]) > 1e-5;
        CHECK_MSG(m->vertex_count == nv && bad == 0, "big meshopt view, mesh %d: %u vertices, %zu values off", (int)k,
                  m->vertex_count, bad);
    }
    CHECK(s && s->mesh_count == 2);
    mr_scene_destroy(&s);
    free(pos);
    free(bin);
}

/* The loader's pipeline (both cores): big primitives are prepared on the
 * pool and added in file order, a node whose meshes are still pending gets
 * them once they are in, and several meshopt views are decoded and
 * converted as tasks. Three primitives of 60k vertices (two in mesh 0,
 * drawn by two nodes; one in mesh 1), float positions and non-unit
 * normals, 32-bit indices; the same file compressed (three views, 6.5 MB
 * decoded: one batch) and plain. Then failures: the error is the one that
 * comes first in the file even when a later one is found first, and a
 * broken view in a batch fails the load with one line. */
enum { k_pipe_nv = 60000, k_pipe_prims = 3, k_pipe_ni = 3 * (k_pipe_nv - 2) };

typedef struct {
    float *pos, *nrm, *nrm4; /* nrm4: the normals unit, xyz0 (meshopt_encodeFilterOct's input) */
    uint32_t *idx;
} pipe_data;

static void pipe_fill(pipe_data *d) {
    for (size_t i = 0; i < (size_t)k_pipe_prims * k_pipe_nv; i++) {
        size_t p = i / k_pipe_nv, v = i % k_pipe_nv;
        d->pos[3 * i + 0] = (float)(v % 300) * 0.01f + (float)p * 10.0f;
        d->pos[3 * i + 1] = (float)(v / 300) * 0.01f;
        d->pos[3 * i + 2] = (float)((v * 7) % 13) * 0.1f;
        d->nrm[3 * i + 0] = 0.5f * (float)(v % 3);
        d->nrm[3 * i + 1] = 2.0f;
        d->nrm[3 * i + 2] = -1.0f * (float)(p + 1);
    }
    for (size_t i = 0; i < (size_t)k_pipe_prims * k_pipe_nv; i++) {
        const float *n = d->nrm + 3 * i;
        float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int c = 0; c < 3; c++) d->nrm4[4 * i + (size_t)c] = n[c] / l;
        d->nrm4[4 * i + 3] = 0.0f;
    }
    for (size_t p = 0; p < k_pipe_prims; p++)
        for (size_t t = 0; t < k_pipe_ni / 3; t++)
            for (int c = 0; c < 3; c++) d->idx[p * k_pipe_ni + 3 * t + (size_t)c] = (uint32_t)(t + (size_t)c);
}

/* The file's JSON and BIN for d: compressed (three meshopt views) or plain.
 * tail: more nodes after the three (",{...}"), or "". oct: 0, or the bits
 * (8, 16) of OCTAHEDRAL-filtered normals (compressed only). */
static unsigned char *pipe_file_oct(const pipe_data *d, bool packed, const char *tail, char *json, size_t json_cap,
                                    size_t *bin_n, size_t view_off[3], size_t view_len[3], int oct) {
    const size_t nv = (size_t)k_pipe_prims * k_pipe_nv, ni = (size_t)k_pipe_prims * k_pipe_ni;
    const size_t nst = oct == 8 ? 4 : oct == 16 ? 8 : 12; /* the normals' stride */
    const size_t raw[3] = {nv * 12, nv * nst, ni * 4};
    size_t cap = 2 * meshopt_encodeVertexBufferBound(nv, 12) + meshopt_encodeIndexSequenceBound(ni, nv) + raw[0] + raw[1] + raw[2] + 64;
    unsigned char *bin = malloc(cap);
    if (!bin) return NULL;
    size_t at = 0;
    for (int v = 0; v < 3; v++) {
        size_t n;
        if (!packed) {
            memcpy(bin + at, v == 0 ? (const void *)d->pos : v == 1 ? (const void *)d->nrm : (const void *)d->idx, raw[v]);
            n = raw[v];
        } else if (v == 1 && oct) {
            unsigned char *f = malloc(raw[1]);
            if (!f) {
                free(bin);
                return NULL;
            }
            meshopt_encodeFilterOct(f, nv, nst, oct, d->nrm4);
            n = meshopt_encodeVertexBuffer(bin + at, cap - at, f, nv, nst);
            free(f);
        } else if (v < 2) {
            n = meshopt_encodeVertexBuffer(bin + at, cap - at, v == 0 ? d->pos : d->nrm, nv, 12);
        } else {
            n = meshopt_encodeIndexSequence(bin + at, cap - at, d->idx, ni);
        }
        view_off[v] = at;
        view_len[v] = n;
        at += n;
        while (at % 4) bin[at++] = 0;
    }
    *bin_n = at;
    char views[2048], acc[4096];
    size_t vo = 0, ao = 0;
    for (int v = 0; v < 3; v++) {
        const size_t st = v == 0 ? 12 : v == 1 ? nst : 4;
        char vst[32] = "";
        if (v < 2) snprintf(vst, sizeof vst, ",\"byteStride\":%zu", st);
        if (packed)
            vo += (size_t)snprintf(views + vo, sizeof views - vo,
                                   "%s{\"buffer\":1,\"byteOffset\":%zu,\"byteLength\":%zu%s,\"extensions\":{\"EXT_meshopt_compression\":"
                                   "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":%zu,\"count\":%zu,\"mode\":\"%s\"%s}}}",
                                   v ? "," : "", v == 0 ? 0 : v == 1 ? raw[0] : raw[0] + raw[1], raw[v], vst, view_off[v],
                                   view_len[v], st, v < 2 ? nv : ni, v < 2 ? "ATTRIBUTES" : "INDICES",
                                   v == 1 && oct ? ",\"filter\":\"OCTAHEDRAL\"" : "");
        else
            vo += (size_t)snprintf(views + vo, sizeof views - vo, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu%s}",
                                   v ? "," : "", view_off[v], view_len[v], v < 2 ? ",\"byteStride\":12" : "");
    }
    for (int p = 0; p < k_pipe_prims; p++) /* accessors 3p: POSITION, 3p+1: NORMAL, 3p+2: indices */
        ao += (size_t)snprintf(acc + ao, sizeof acc - ao,
                               "%s{\"bufferView\":0,\"byteOffset\":%zu,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"},"
                               "{\"bufferView\":1,\"byteOffset\":%zu,\"componentType\":%d%s,\"count\":%d,\"type\":\"VEC3\"},"
                               "{\"bufferView\":2,\"byteOffset\":%zu,\"componentType\":5125,\"count\":%d,\"type\":\"SCALAR\"}",
                               p ? "," : "", (size_t)p * k_pipe_nv * 12, k_pipe_nv, (size_t)p * k_pipe_nv * nst,
                               oct == 8 ? 5120 : oct == 16 ? 5122 : 5126, oct ? ",\"normalized\":true" : "", k_pipe_nv,
                               (size_t)p * k_pipe_ni * 4, k_pipe_ni);
    char fallback[160] = "";
    if (packed)
        snprintf(fallback, sizeof fallback, ",{\"byteLength\":%zu,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}",
                 raw[0] + raw[1] + raw[2]);
    snprintf(json, json_cap,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1,2%s]}],\"scene\":0,"
             "\"nodes\":[{\"name\":\"A\",\"mesh\":0},{\"name\":\"B\",\"mesh\":0,\"translation\":[0,0,5]},{\"name\":\"C\",\"mesh\":1}%s],"
             "%s\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2},"
             "{\"attributes\":{\"POSITION\":3,\"NORMAL\":4},\"indices\":5}]},"
             "{\"primitives\":[{\"attributes\":{\"POSITION\":6,\"NORMAL\":7},\"indices\":8}]}],"
             "\"buffers\":[{\"byteLength\":%zu}%s],\"bufferViews\":[%s],\"accessors\":[%s]}",
             tail[0] ? ",3" : "", tail,
             !packed ? ""
             : oct  ? "\"extensionsUsed\":[\"EXT_meshopt_compression\",\"KHR_mesh_quantization\"],"
                      "\"extensionsRequired\":[\"EXT_meshopt_compression\",\"KHR_mesh_quantization\"],"
                    : "\"extensionsUsed\":[\"EXT_meshopt_compression\"],\"extensionsRequired\":[\"EXT_meshopt_compression\"],",
             at, fallback, views, acc);
    return bin;
}

static unsigned char *pipe_file(const pipe_data *d, bool packed, const char *tail, char *json, size_t json_cap,
                                size_t *bin_n, size_t view_off[3], size_t view_len[3]) {
    return pipe_file_oct(d, packed, tail, json, json_cap, bin_n, view_off, view_len, 0);
}

/* OCTAHEDRAL normals (8 and 16 bits, as gltfpack -cc writes them) are
 * filtered while converted to floats: each loaded normal is unit and
 * within the filter's rounding of what meshoptimizer's own decoder makes
 * of the same bytes, and of the normal encoded. */
static void test_pipeline_oct(pipe_data *d) {
    const size_t nv = (size_t)k_pipe_prims * k_pipe_nv;
    char *json = malloc(16384);
    if (!json) return;
    for (int bits = 8; bits <= 16; bits += 8) {
        size_t bn, off[3], len[3], st = bits == 8 ? 4 : 8;
        unsigned char *bin = pipe_file_oct(d, true, "", json, 16384, &bn, off, len, bits);
        unsigned char *ref = malloc(nv * st);
        CHECK(bin && ref);
        if (!bin || !ref) {
            free(bin);
            free(ref);
            continue;
        }
        meshopt_encodeFilterOct(ref, nv, st, bits, d->nrm4);
        meshopt_decodeFilterOct(ref, nv, st);
        mr_error err = {0};
        mr_scene *s = load_glb(json, bin, bn, &err);
        CHECK_MSG(s != NULL && s->mesh_count == 3, "oct %d: %s", bits, err.msg);
        double worst_ref = 0, worst_dot = 1, worst_len = 0;
        const double one = bits == 8 ? 127.0 : 32767.0;
        for (int32_t k = 0; s && k < s->mesh_count && s->mesh_count == 3; k++) {
            const mr_mesh *m = &s->meshes[k];
            for (size_t v = 0; v < (size_t)k_pipe_nv; v++) {
                const size_t g = (size_t)k * k_pipe_nv + v;
                const float *n = m->normals + 3 * v, *w = d->nrm4 + 4 * g;
                double r[3], rl = 0;
                for (int c = 0; c < 3; c++) {
                    int q = bits == 8 ? ((const int8_t *)(ref + g * st))[c] : ((const int16_t *)(ref + g * st))[c];
                    r[c] = q / one;
                    rl += r[c] * r[c];
                }
                rl = sqrt(rl);
                double dot = 0, l = 0;
                for (int c = 0; c < 3; c++) {
                    worst_ref = fmax(worst_ref, fabs(n[c] - r[c] / rl));
                    dot += n[c] * w[c];
                    l += (double)n[c] * n[c];
                }
                worst_dot = fmin(worst_dot, dot);
                worst_len = fmax(worst_len, fabs(sqrt(l) - 1.0));
            }
        }
        /* meshopt rounds each component to 1/one: its normal is that far off. */
        CHECK_MSG(worst_ref < 1.5 / one + 1e-6, "oct %d: %g from meshopt's decoder", bits, worst_ref);
        CHECK_MSG(worst_dot > (bits == 8 ? 0.999 : 0.9999999), "oct %d: a normal %g off the encoded one (dot)", bits, worst_dot);
        CHECK_MSG(worst_len < 1e-6, "oct %d: normals off unit length by %g", bits, worst_len);
        mr_scene_destroy(&s);
        free(bin);
        free(ref);
    }
    free(json);
}

static void test_pipeline(void) {
    const size_t nv = (size_t)k_pipe_prims * k_pipe_nv, ni = (size_t)k_pipe_prims * k_pipe_ni;
    pipe_data d = {malloc(nv * 12), malloc(nv * 12), malloc(nv * 16), malloc(ni * 4)};
    char *json = malloc(16384);
    CHECK(d.pos && d.nrm && d.nrm4 && d.idx && json);
    if (!d.pos || !d.nrm || !d.nrm4 || !d.idx || !json) goto out;
    pipe_fill(&d);
    test_pipeline_oct(&d);
    for (int packed = 0; packed < 2; packed++) {
        size_t bn, off[3], len[3];
        unsigned char *bin = pipe_file(&d, packed, "", json, 16384, &bn, off, len);
        CHECK(bin != NULL);
        if (!bin) continue;
        mr_error err = {0};
        mr_scene *s = load_glb(json, bin, bn, &err);
        CHECK_MSG(s != NULL, "pipeline, %s: %s", packed ? "meshopt" : "plain", err.msg);
        if (s) {
            CHECK_MSG(s->mesh_count == 3 && s->node_count == 3, "%s: %d meshes, %d nodes", packed ? "meshopt" : "plain",
                      (int)s->mesh_count, (int)s->node_count);
            for (int32_t k = 0; k < s->node_count && s->node_count == 3; k++)
                CHECK_MSG(s->nodes[k].mesh_first == (k < 2 ? 0 : 2) && s->nodes[k].mesh_count == (k < 2 ? 2 : 1),
                          "%s: node %d draws meshes %d+%d", packed ? "meshopt" : "plain", (int)k, (int)s->nodes[k].mesh_first,
                          (int)s->nodes[k].mesh_count);
            for (int32_t k = 0; k < s->mesh_count && s->mesh_count == 3; k++) {
                const mr_mesh *m = &s->meshes[k];
                size_t bad_pos = 0, bad_nrm = 0, bad_idx = 0;
                const float *wp = d.pos + (size_t)k * k_pipe_nv * 3, *wn = d.nrm + (size_t)k * k_pipe_nv * 3;
                for (size_t v = 0; v < (size_t)k_pipe_nv && m->vertex_count == k_pipe_nv; v++) {
                    double l = sqrt((double)wn[3 * v] * wn[3 * v] + (double)wn[3 * v + 1] * wn[3 * v + 1] +
                                    (double)wn[3 * v + 2] * wn[3 * v + 2]);
                    for (int c = 0; c < 3; c++) {
                        bad_pos += fabs((double)m->positions[3 * v + c] + m->origin[c] - wp[3 * v + c]) > 1e-5;
                        bad_nrm += fabs((double)m->normals[3 * v + c] - wn[3 * v + c] / l) > 1e-6;
                    }
                }
                for (size_t i = 0; i < (size_t)k_pipe_ni && m->index_count == k_pipe_ni; i++)
                    bad_idx += m->indices[i] != d.idx[(size_t)k * k_pipe_ni + i];
                CHECK_MSG(m->vertex_count == k_pipe_nv && m->index_count == k_pipe_ni && !bad_pos && !bad_nrm && !bad_idx,
                          "%s mesh %d: %u vertices, %u indices; %zu positions, %zu normals, %zu indices off",
                          packed ? "meshopt" : "plain", (int)k, m->vertex_count, m->index_count, bad_pos, bad_nrm, bad_idx);
            }
        }
        mr_scene_destroy(&s);
        free(bin);

        /* Mesh 0's second primitive (prepared on the pool) has an index out
         * of range; node D, read after it, names a mesh that does not
         * exist: the index is the load's error. */
        uint32_t keep = d.idx[k_pipe_ni + 7];
        d.idx[k_pipe_ni + 7] = k_pipe_nv;
        bin = pipe_file(&d, packed, ",{\"name\":\"D\",\"mesh\":9}", json, 16384, &bn, off, len);
        d.idx[k_pipe_ni + 7] = keep;
        if (bin) expect_refused(json, bin, bn, "out of range", __LINE__);
        free(bin);
        /* A NaN normal in mesh 1: its normals are regenerated (a warning),
         * every one unit; the load goes on. */
        float keep_n = d.nrm[(size_t)2 * k_pipe_nv * 3 + 50];
        d.nrm[(size_t)2 * k_pipe_nv * 3 + 50] = NAN;
        bin = pipe_file(&d, packed, "", json, 16384, &bn, off, len);
        d.nrm[(size_t)2 * k_pipe_nv * 3 + 50] = keep_n;
        s = bin ? load_glb(json, bin, bn, &err) : NULL;
        CHECK_MSG(s != NULL && s->mesh_count == 3, "%s, NaN normal: %s", packed ? "meshopt" : "plain", err.msg);
        if (s && s->mesh_count == 3) {
            double worst = 0;
            const mr_mesh *m = &s->meshes[2];
            for (uint32_t v = 0; v < m->vertex_count; v++) {
                const float *n = m->normals + 3 * v;
                double l = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
                worst = isfinite(l) ? fmax(worst, fabs(l - 1.0)) : 1e9;
            }
            CHECK_MSG(worst < 1e-5, "%s, NaN normal: regenerated normals off unit by %g", packed ? "meshopt" : "plain", worst);
        }
        mr_scene_destroy(&s);
        free(bin);
        /* Mesh 1 has an infinite position; nothing later fails. */
        float keep_p = d.pos[(size_t)2 * k_pipe_nv * 3 + 100];
        d.pos[(size_t)2 * k_pipe_nv * 3 + 100] = INFINITY;
        bin = pipe_file(&d, packed, "", json, 16384, &bn, off, len);
        d.pos[(size_t)2 * k_pipe_nv * 3 + 100] = keep_p;
        if (bin) expect_refused(json, bin, bn, "non-finite position", __LINE__);
        free(bin);
        if (!packed) continue;
        /* A broken stream in the batch: the view asked for first
         * (positions) and one decoded ahead of it (normals), each cut. */
        for (int v = 0; v < 2; v++) {
            bin = pipe_file(&d, packed, "", json, 16384, &bn, off, len);
            if (!bin) continue;
            memset(bin + off[v] + len[v] / 2, 0xA5, len[v] - len[v] / 2 - 1);
            expect_refused(json, bin, bn, "malformed meshopt", __LINE__);
            free(bin);
        }
        /* Random damage anywhere in the three streams: one line or a load. */
        bin = pipe_file(&d, packed, "", json, 16384, &bn, off, len);
        for (int trial = 0; bin && trial < 12; trial++) {
            unsigned char *junk = malloc(bn);
            if (!junk) break;
            memcpy(junk, bin, bn);
            for (int k = 0; k < 8; k++) junk[(size_t)(trial * 7919 + k * 104729) * 31 % bn] ^= (unsigned char)(1 + (trial + k) % 255);
            mr_scene *t = load_glb(json, junk, bn, &err);
            if (!t) CHECK_MSG(one_line(&err), "trial %d: '%s'", trial, err.msg);
            mr_scene_destroy(&t);
            free(junk);
        }
        free(bin);
    }
out:
    free(d.pos);
    free(d.nrm);
    free(d.nrm4);
    free(d.idx);
    free(json);
}

/* KHR_draco_mesh_compression on real draco data; then damaged data. */
static void test_draco(void) {
    float pos[48];
    uint32_t idx[54];
    grid(pos, idx);
    size_t dn = 0;
    int pid = -1;
    unsigned char *d = test_draco_encode(pos, 16, idx, 18, 14, &dn, &pid);
    CHECK(d != NULL && dn > 0);
    if (!d) return;
    char json[4096];
    snprintf(json, sizeof json,
             "{%s\"extensionsUsed\":[\"KHR_draco_mesh_compression\"],\"extensionsRequired\":[\"KHR_draco_mesh_compression\"],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"extensions\":"
             "{\"KHR_draco_mesh_compression\":{\"bufferView\":0,\"attributes\":{\"POSITION\":%d}}}}]}],"
             "\"buffers\":[{\"byteLength\":%zu}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu}],"
             "\"accessors\":[{\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
             "{\"componentType\":5125,\"count\":54,\"type\":\"SCALAR\"}]}",
             k_head, pid, dn, dn);
    mr_error err = {0};
    mr_scene *s = load_glb(json, d, dn, &err);
    CHECK_MSG(s != NULL, "draco: %s", err.msg);
    if (s) {
        const mr_mesh *m = &s->meshes[0];
        CHECK_MSG(m->vertex_count == 16 && m->index_count == 54, "%u vertices, %u indices", m->vertex_count,
                  m->index_count);
        /* Every decoded vertex is one of the grid's within 14-bit quantisation
         * of the largest extent (0.9): 0.9 / 16383 / 2 per axis. */
        double tol = 0.9 / 16383.0 * 0.5 * 1.01, worst = 0;
        for (uint32_t v = 0; v < m->vertex_count; v++) {
            double best = 1e9;
            for (int k = 0; k < 16; k++) {
                double e = 0;
                for (int c = 0; c < 3; c++) e = fmax(e, fabs(m->positions[v * 3 + c] + m->origin[c] - pos[k * 3 + c]));
                best = fmin(best, e);
            }
            worst = fmax(worst, best);
        }
        CHECK_MSG(worst <= tol, "draco vertex off by %g (tolerance %g)", worst, tol);
    }
    mr_scene_destroy(&s);
    /* tinygltf alone refuses draco's index accessor without a bufferView. */
    size_t gn = 0;
    unsigned char *g = make_glb(json, d, dn, &gn);
    CHECK_MSG(mr_gltf_parse_only(g, gn, &err), "parse only, draco: %s", err.msg);
    free(g);
    /* Damage: cut short, garbage, random flips. */
    expect_refused(json, d, dn / 2, NULL, __LINE__);
    unsigned char *junk = malloc(dn);
    for (size_t i = 0; i < dn; i++) junk[i] = (unsigned char)(i * 53 + 7);
    expect_refused(json, junk, dn, "draco", __LINE__);
    for (int trial = 0; trial < 200; trial++) {
        memcpy(junk, d, dn);
        junk[(size_t)(trial * 7919) % dn] ^= (unsigned char)(1 + trial % 255);
        mr_scene *t = load_glb(json, junk, dn, &err);
        if (!t) CHECK_MSG(one_line(&err), "trial %d: '%s'", trial, err.msg);
        mr_scene_destroy(&t);
    }
    free(junk);
    free(d);
}

/* KHR_texture_transform maps the texture coordinates (T * R * S). */
static void test_texture_transform(void) {
    float bin[9 + 6] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1};
    char json[4096];
    snprintf(json, sizeof json,
             "{%s\"extensionsUsed\":[\"KHR_texture_transform\"],"
             "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0,\"extensions\":"
             "{\"KHR_texture_transform\":{\"offset\":[0.5,0.25],\"rotation\":1.5707963267948966,\"scale\":[2,4]}}}}}],"
             "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"missing.png\"}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"material\":0}]}],"
             "\"buffers\":[{\"byteLength\":60}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},"
             "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":24}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}]}",
             k_head);
    mr_error err = {0};
    mr_scene *s = load_glb(json, bin, sizeof bin, &err);
    CHECK_MSG(s != NULL, "texture transform: %s", err.msg);
    if (s && s->meshes[0].uvs) {
        const float *uv = s->meshes[0].uvs;
        /* (1,0): scale -> (2,0), rotate 90 deg (u' = cos u + sin v, v' = -sin u + cos v) -> (0,-2), offset -> (0.5,-1.75) */
        CHECK_NEAR(uv[2], 0.5, 1e-5);
        CHECK_NEAR(uv[3], -1.75, 1e-5);
        /* (0,1): scale -> (0,4), rotate -> (4,0), offset -> (4.5,0.25) */
        CHECK_NEAR(uv[4], 4.5, 1e-5);
        CHECK_NEAR(uv[5], 0.25, 1e-5);
    } else {
        CHECK_MSG(0, "no uvs");
    }
    mr_scene_destroy(&s);
}

/* A big file (over 16 MB) of medium meshes, whose arrays the loader carves
 * from huge-page blocks that the scene owns: every mesh as written; a mesh
 * with a NaN normal gets its normals made (the file's array given back to
 * its block, not freed); an index out of range in one mesh fails the load
 * with one line (and, under ASan, frees nothing that malloc did not give). */
static void test_medium_meshes(void) {
    enum { meshes = 36, gw = 100, gh = 120, nv = gw * gh, ni = (gw - 1) * (gh - 1) * 6 };
    const size_t per = (size_t)nv * 24 + (size_t)ni * 4, bin_n = per * meshes;
    unsigned char *bin = malloc(bin_n);
    char *json = malloc(64 << 10);
    CHECK(bin && json);
    if (!bin || !json) {
        free(bin);
        free(json);
        return;
    }
    for (int variant = 0; variant < 3; variant++) {
        for (int k = 0; k < meshes; k++) {
            float *pos = (float *)(bin + per * k), *nrm = pos + 3 * nv;
            uint32_t *idx = (uint32_t *)(nrm + 3 * nv);
            for (int y = 0; y < gh; y++)
                for (int x = 0; x < gw; x++) {
                    float *p = pos + 3 * (y * gw + x), *n = nrm + 3 * (y * gw + x);
                    p[0] = (float)x * 0.01f + (float)k, p[1] = (float)y * 0.01f, p[2] = 0.001f * (float)((x * y + k) % 7);
                    n[0] = 0.0f, n[1] = 0.0f, n[2] = 1.0f;
                }
            int t = 0;
            for (int y = 0; y + 1 < gh; y++)
                for (int x = 0; x + 1 < gw; x++) {
                    uint32_t a = (uint32_t)(y * gw + x), b = a + 1, c = a + gw, d = c + 1;
                    idx[t++] = a, idx[t++] = b, idx[t++] = d, idx[t++] = a, idx[t++] = d, idx[t++] = c;
                }
            if (variant == 1 && k == 5) nrm[3 * 777 + 1] = NAN;
            if (variant == 2 && k == 7) idx[ni - 4] = nv;
        }
        int at = snprintf(json, 64 << 10, "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[");
        for (int k = 0; k < meshes; k++) at += snprintf(json + at, (64 << 10) - at, "%s%d", k ? "," : "", k);
        at += snprintf(json + at, (64 << 10) - at, "]}],\"scene\":0,\"nodes\":[");
        for (int k = 0; k < meshes; k++) at += snprintf(json + at, (64 << 10) - at, "%s{\"mesh\":%d}", k ? "," : "", k);
        at += snprintf(json + at, (64 << 10) - at, "],\"meshes\":[");
        for (int k = 0; k < meshes; k++)
            at += snprintf(json + at, (64 << 10) - at,
                           "%s{\"primitives\":[{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d},\"indices\":%d}]}", k ? "," : "",
                           3 * k, 3 * k + 1, 3 * k + 2);
        at += snprintf(json + at, (64 << 10) - at, "],\"buffers\":[{\"byteLength\":%zu}],\"bufferViews\":[", bin_n);
        for (int k = 0; k < meshes; k++)
            at += snprintf(json + at, (64 << 10) - at,
                           "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%d},{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%d},"
                           "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%d}",
                           k ? "," : "", per * k, nv * 12, per * k + (size_t)nv * 12, nv * 12, per * k + (size_t)nv * 24, ni * 4);
        at += snprintf(json + at, (64 << 10) - at, "],\"accessors\":[");
        for (int k = 0; k < meshes; k++)
            at += snprintf(json + at, (64 << 10) - at,
                           "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\",\"min\":[%d,0,0],\"max\":[%g,1.19,0.006]},"
                           "{\"bufferView\":%d,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"},"
                           "{\"bufferView\":%d,\"componentType\":5125,\"count\":%d,\"type\":\"SCALAR\"}",
                           k ? "," : "", 3 * k, nv, k, k + 0.99, 3 * k + 1, nv, 3 * k + 2, ni);
        snprintf(json + at, (64 << 10) - at, "]}");
        if (variant == 2) {
            expect_refused(json, bin, bin_n, "out of range", __LINE__);
            continue;
        }
        mr_error err = {0};
        mr_scene *s = load_glb(json, bin, bin_n, &err);
        CHECK_MSG(s && s->mesh_count == meshes, "medium meshes, variant %d: %s", variant, err.msg);
        if (!s || s->mesh_count != meshes) {
            mr_scene_destroy(&s);
            continue;
        }
        CHECK_MSG(s->block_count >= 1, "medium meshes: no array came from a block");
        int bad = 0;
        for (int k = 0; k < meshes; k++) {
            const mr_mesh *m = &s->meshes[k];
            const float *pos = (const float *)(bin + per * k);
            const uint32_t *idx = (const uint32_t *)(pos + 6 * nv);
            if (m->vertex_count != nv || m->index_count != ni) {
                bad++;
                continue;
            }
            for (int i = 0; i < 3 * nv; i++) bad += fabs(m->positions[i] + m->origin[i % 3] - pos[i]) > 1e-5;
            bad += memcmp(m->indices, idx, (size_t)ni * 4) != 0;
            for (int v = 0; v < nv; v++) {
                const float *n = m->normals + 3 * v;
                bad += !(fabs(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0) < 1e-5) || (n[2] < 0.99f && variant == 0);
            }
        }
        CHECK_MSG(bad == 0, "medium meshes, variant %d: %d values differ", variant, bad);
        mr_scene_destroy(&s);
    }
    free(bin);
    free(json);
}

/* Files over 2 GiB load (mapped, only the pages read are touched) and over
 * 4 GiB are refused with one line: sparse files, so no disk is used. */
static void test_big_files(void) {
    char path[1200];
    snprintf(path, sizeof path, "%s/big.glb", g_tmp);
    const size_t total = (size_t)2200 << 20; /* 2.2 GiB */
    char json[1024];
    size_t bin_n = total - 4096 - 8 - 20;
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"buffers\":[{\"byteLength\":%zu}],\"bufferViews\":[{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":36}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}]}",
             bin_n, bin_n - 36);
    unsigned char head[4096 + 28];
    memset(head, ' ', sizeof head);
    uint32_t h[5] = {0x46546C67u, 2, (uint32_t)total, 4096, 0x4E4F534Au};
    memcpy(head, h, 20);
    memcpy(head + 20, json, strlen(json));
    uint32_t c[2] = {(uint32_t)bin_n, 0x004E4942u};
    memcpy(head + 20 + 4096, c, 8);
    int fd = open(path, O_CREAT | O_TRUNC | O_WRONLY, 0644);
    CHECK(fd >= 0);
    if (fd < 0) return;
    const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bool wrote = write(fd, head, 4096 + 28) == 4096 + 28 && ftruncate(fd, (off_t)total) == 0 &&
                 pwrite(fd, tri, 36, (off_t)(total - 36)) == 36;
    close(fd);
    CHECK(wrote);
    mr_error err = {0};
    double before = peak_rss_mb();
    mr_scene *s = mr_scene_load(path, NULL, &err);
    CHECK_MSG(s != NULL && s->mesh_count == 1, "2.2 GiB GLB: %s", err.msg);
    CHECK_MSG(peak_rss_mb() - before < 64, "2.2 GiB sparse GLB grew peak RSS by %.0f MB", peak_rss_mb() - before);
    mr_scene_destroy(&s);
    /* The header's length is 32-bit: over 4 GiB cannot be a GLB. */
    fd = open(path, O_WRONLY);
    bool grew = fd >= 0 && ftruncate(fd, (off_t)((size_t)4400 << 20)) == 0;
    if (fd >= 0) close(fd);
    CHECK(grew);
    s = mr_scene_load(path, NULL, &err);
    CHECK_MSG(s == NULL && one_line(&err) && strstr(err.msg, "4 GiB"), "4.3 GiB: '%s'", err.msg);
    mr_scene_destroy(&s);
    unlink(path);
}

/* Non-tight strides out of EXT_meshopt_compression: (a) one ATTRIBUTES
 * view of 24-byte elements holding float POSITION and NORMAL interleaved
 * (accessor offsets 0 and 12); (b) with KHR_mesh_quantization, unsigned
 * short positions in 8-byte elements and normalised byte normals in
 * 4-byte elements, each padded with junk that a tight read would take for
 * a component. Each vertex must come back as written. */
static void test_meshopt_strides(void) {
    float pos[48];
    uint32_t idx[54];
    grid(pos, idx);
    float inter[16 * 6];
    float nrm[48];
    for (int i = 0; i < 16; i++) {
        double a = 0.1 * i;
        nrm[3 * i] = (float)sin(a), nrm[3 * i + 1] = 0, nrm[3 * i + 2] = (float)cos(a);
        for (int k = 0; k < 3; k++) inter[6 * i + k] = pos[3 * i + k], inter[6 * i + 3 + k] = nrm[3 * i + k];
    }
    uint16_t qpos[16][4];
    int8_t qnrm[16][4];
    for (int i = 0; i < 16; i++) {
        qpos[i][0] = (uint16_t)(i % 4 * 100), qpos[i][1] = (uint16_t)(i / 4 * 100), qpos[i][2] = (uint16_t)(i * 7);
        qpos[i][3] = 0xBEEF;
        qnrm[i][0] = (int8_t)(i % 2 ? 127 : 0), qnrm[i][1] = 0, qnrm[i][2] = (int8_t)(i % 2 ? 0 : 127), qnrm[i][3] = 0x55;
    }
    unsigned char ib[1024];
    size_t in = meshopt_encodeIndexBuffer(ib, sizeof ib, idx, 54);
    for (int variant = 0; variant < 2; variant++) {
        unsigned char bin[4096], v0[2048], v1[2048];
        size_t n0, n1 = 0;
        if (variant == 0) n0 = meshopt_encodeVertexBuffer(v0, sizeof v0, inter, 16, 24);
        else {
            n0 = meshopt_encodeVertexBuffer(v0, sizeof v0, qpos, 16, 8);
            n1 = meshopt_encodeVertexBuffer(v1, sizeof v1, qnrm, 16, 4);
        }
        CHECK(n0 > 0 && in > 0 && (variant == 0 || n1 > 0));
        size_t p0 = (n0 + 3) & ~(size_t)3, p1 = (n1 + 3) & ~(size_t)3;
        memset(bin, 0, sizeof bin);
        memcpy(bin, v0, n0);
        memcpy(bin + p0, v1, n1);
        memcpy(bin + p0 + p1, ib, in);
        size_t bn = p0 + p1 + in;
        char json[4096];
        if (variant == 0)
            snprintf(json, sizeof json,
                     "{%s\"extensionsUsed\":[\"EXT_meshopt_compression\"],\"extensionsRequired\":[\"EXT_meshopt_compression\"],"
                     "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2}]}],"
                     "\"buffers\":[{\"byteLength\":%zu},{\"byteLength\":600,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
                     "\"bufferViews\":[{\"buffer\":1,\"byteLength\":384,\"byteStride\":24,\"extensions\":{\"EXT_meshopt_compression\":"
                     "{\"buffer\":0,\"byteLength\":%zu,\"byteStride\":24,\"count\":16,\"mode\":\"ATTRIBUTES\"}}},"
                     "{\"buffer\":1,\"byteOffset\":384,\"byteLength\":108,\"extensions\":{\"EXT_meshopt_compression\":"
                     "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":2,\"count\":54,\"mode\":\"TRIANGLES\"}}}],"
                     "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
                     "{\"bufferView\":0,\"byteOffset\":12,\"componentType\":5126,\"count\":16,\"type\":\"VEC3\"},"
                     "{\"bufferView\":1,\"componentType\":5123,\"count\":54,\"type\":\"SCALAR\"}]}",
                     k_head, bn, n0, p0 + p1, in);
        else
            snprintf(json, sizeof json,
                     "{%s\"extensionsUsed\":[\"EXT_meshopt_compression\",\"KHR_mesh_quantization\"],"
                     "\"extensionsRequired\":[\"EXT_meshopt_compression\",\"KHR_mesh_quantization\"],"
                     "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2}]}],"
                     "\"buffers\":[{\"byteLength\":%zu},{\"byteLength\":600,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}],"
                     "\"bufferViews\":[{\"buffer\":1,\"byteLength\":128,\"byteStride\":8,\"extensions\":{\"EXT_meshopt_compression\":"
                     "{\"buffer\":0,\"byteLength\":%zu,\"byteStride\":8,\"count\":16,\"mode\":\"ATTRIBUTES\"}}},"
                     "{\"buffer\":1,\"byteOffset\":128,\"byteLength\":64,\"byteStride\":4,\"extensions\":{\"EXT_meshopt_compression\":"
                     "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":4,\"count\":16,\"mode\":\"ATTRIBUTES\"}}},"
                     "{\"buffer\":1,\"byteOffset\":192,\"byteLength\":108,\"extensions\":{\"EXT_meshopt_compression\":"
                     "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":2,\"count\":54,\"mode\":\"TRIANGLES\"}}}],"
                     "\"accessors\":[{\"bufferView\":0,\"componentType\":5123,\"count\":16,\"type\":\"VEC3\"},"
                     "{\"bufferView\":1,\"componentType\":5120,\"normalized\":true,\"count\":16,\"type\":\"VEC3\"},"
                     "{\"bufferView\":2,\"componentType\":5123,\"count\":54,\"type\":\"SCALAR\"}]}",
                     k_head, bn, n0, p0, n1, p0 + p1, in);
        mr_error err = {0};
        mr_scene *s = load_glb(json, bin, bn, &err);
        CHECK_MSG(s != NULL, "strides variant %d: %s", variant, err.msg);
        if (!s) continue;
        const mr_mesh *m = &s->meshes[0];
        CHECK_MSG(m->vertex_count == 16 && m->index_count == 54 && m->normals, "strides variant %d: %u vertices",
                  variant, m->vertex_count);
        double wp = 0, wn = 0;
        for (int i = 0; i < 16 && m->vertex_count == 16 && m->normals; i++)
            for (int k = 0; k < 3; k++) {
                double want_p = variant == 0 ? pos[3 * i + k] : qpos[i][k];
                double want_n = variant == 0 ? nrm[3 * i + k] : qnrm[i][k] / 127.0;
                wp = fmax(wp, fabs(m->positions[3 * i + k] + m->origin[k] - want_p));
                wn = fmax(wn, fabs(m->normals[3 * i + k] - want_n));
            }
        CHECK_MSG(wp < 1e-5 && wn < 1e-6, "strides variant %d: positions off by %g, normals by %g", variant, wp, wn);
        mr_scene_destroy(&s);
    }
}

int main(void) {
    const char *tmp = getenv("MR_TEST_TMP");
    snprintf(g_tmp, sizeof g_tmp, "%s/gltf_ext", tmp && tmp[0] ? tmp : "/tmp/mrcheck_test");
    mr_error err = {0};
    if (!mr_mkdirs(g_tmp, &err)) {
        printf("cannot create %s: %s\n", g_tmp, err.msg);
        return 1;
    }
    mr_log_set_level(MR_LOG_ERROR);
    test_quantization();
    test_quantized_values();
    test_sparse_and_zeros();
    test_sparse_offsets();
    test_glb_lies();
    test_meshopt();
    test_meshopt_shared();
    test_meshopt_slices();
    test_meshopt_big();
    test_meshopt_strides();
    test_pipeline();
    test_draco();
    test_texture_transform();
    test_medium_meshes();
    test_big_files();
    return mr_test_finish("test_gltf_ext");
}
