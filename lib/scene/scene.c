/* Scene building: meshes, materials, textures, nodes, bounds, globs.
 * glTF import/export lives in gltf_io.cc; the demo hall in demo.c. */
#include "mr_scene.h"
#include "prepare_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

mr_scene *mr_scene_create(void) {
    mr_scene *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->ambient = 0.35f;
    return s;
}

/* Blocks: see mr_scene. Kept in address order (sorted when first looked
 * up after an adoption), so that an array is found in log time. */
struct mr_scene_block {
    char *p;
    size_t n;
};

static int block_cmp(const void *a, const void *b) {
    uintptr_t x = (uintptr_t)((const struct mr_scene_block *)a)->p, y = (uintptr_t)((const struct mr_scene_block *)b)->p;
    return x < y ? -1 : x > y;
}

bool mr_scene_adopt_block(mr_scene *s, void *p, size_t n) {
    if (!s || !p) return false;
    if (s->block_count == s->block_cap) {
        if (s->block_cap >= INT32_MAX / 2) return false;
        int32_t cap = s->block_cap ? 2 * s->block_cap : 8;
        struct mr_scene_block *b = realloc(s->blocks, (size_t)cap * sizeof *b);
        if (!b) return false;
        s->blocks = b;
        s->block_cap = cap;
    }
    s->blocks[s->block_count].p = p;
    s->blocks[s->block_count].n = n;
    s->block_count++;
    s->blocks_sorted = false;
    return true;
}

bool mr_scene_block_holds(mr_scene *s, const void *p) {
    if (!s || !p || s->block_count == 0) return false;
    if (!s->blocks_sorted) {
        qsort(s->blocks, (size_t)s->block_count, sizeof *s->blocks, block_cmp);
        s->blocks_sorted = true;
    }
    const uintptr_t a = (uintptr_t)p;
    int32_t lo = 0, hi = s->block_count - 1;
    while (lo <= hi) { /* the last block starting at or before p */
        int32_t mid = lo + (hi - lo) / 2;
        if ((uintptr_t)s->blocks[mid].p <= a) lo = mid + 1;
        else hi = mid - 1;
    }
    return hi >= 0 && a - (uintptr_t)s->blocks[hi].p < s->blocks[hi].n;
}

void mr_scene_array_free(mr_scene *s, void *p) {
    if (!mr_scene_block_holds(s, p)) free(p);
}

static void mesh_free(mr_scene *s, mr_mesh *m) {
    mr_scene_array_free(s, m->positions);
    mr_scene_array_free(s, m->normals);
    mr_scene_array_free(s, m->uvs);
    mr_scene_array_free(s, m->indices);
}

void mr_scene_destroy(mr_scene **scene) {
    if (!scene || !*scene) return;
    mr_scene *s = *scene;
    for (int32_t i = 0; i < s->mesh_count; i++) mesh_free(s, &s->meshes[i]);
    for (int32_t i = 0; i < s->block_count; i++) free(s->blocks[i].p);
    free(s->blocks);
    for (int32_t i = 0; i < s->texture_count; i++) mr_image_free(&s->textures[i].image);
    free(s->meshes);
    free(s->materials);
    free(s->textures);
    free(s->nodes);
    mr_scene_elements_free(s);
    free(s);
    *scene = NULL;
}

/* Makes room for one more element of `elem` bytes; capacity doubles. */
static bool grow(void **arr, int32_t count, int32_t *cap, size_t elem) {
    if (count < *cap) return true;
    if (*cap >= INT32_MAX / 2) return false;
    int32_t ncap = *cap ? *cap * 2 : 8;
    void *p = realloc(*arr, (size_t)ncap * elem);
    if (!p) return false;
    *arr = p;
    *cap = ncap;
    return true;
}

static const float k_fallback_normal[3] = {0.0f, 1.0f, 0.0f};

/* Unit vector from double components; degenerate or non-finite input gets
 * the fallback so that shading never sees NaN. */
static void store_unit(double x, double y, double z, float *out) {
    double len = sqrt(x * x + y * y + z * z);
    if (!(len > 1e-300) || !isfinite(len)) {
        memcpy(out, k_fallback_normal, sizeof k_fallback_normal);
        return;
    }
    out[0] = (float)(x / len);
    out[1] = (float)(y / len);
    out[2] = (float)(z / len);
}

void mr_mesh_generate_normals(const float *positions, uint32_t vertex_count,
                              const uint32_t *indices, uint32_t index_count, float *normals) {
    if (!normals || vertex_count == 0) return;
    /* Accumulate in double: cross products of huge or tiny triangles stay
     * representable, and many small faces do not lose precision. */
    double *acc = calloc((size_t)vertex_count * 3, sizeof *acc);
    if (acc && positions && indices) {
        for (uint32_t t = 0; t + 2 < index_count; t += 3) {
            uint32_t i0 = indices[t], i1 = indices[t + 1], i2 = indices[t + 2];
            if (i0 >= vertex_count || i1 >= vertex_count || i2 >= vertex_count) continue;
            const float *a = positions + 3 * (size_t)i0;
            const float *b = positions + 3 * (size_t)i1;
            const float *c = positions + 3 * (size_t)i2;
            double e1[3] = {(double)b[0] - a[0], (double)b[1] - a[1], (double)b[2] - a[2]};
            double e2[3] = {(double)c[0] - a[0], (double)c[1] - a[1], (double)c[2] - a[2]};
            /* |e1 x e2| = 2 * area, so the sum is area-weighted. */
            double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                           e1[0] * e2[1] - e1[1] * e2[0]};
            if (!isfinite(n[0]) || !isfinite(n[1]) || !isfinite(n[2])) continue;
            const uint32_t tri[3] = {i0, i1, i2};
            for (int k = 0; k < 3; k++) {
                double *d = acc + 3 * (size_t)tri[k];
                d[0] += n[0];
                d[1] += n[1];
                d[2] += n[2];
            }
        }
    }
    for (uint32_t v = 0; v < vertex_count; v++) {
        if (acc) store_unit(acc[3 * (size_t)v], acc[3 * (size_t)v + 1], acc[3 * (size_t)v + 2], normals + 3 * (size_t)v);
        else memcpy(normals + 3 * (size_t)v, k_fallback_normal, sizeof k_fallback_normal);
    }
    free(acc);
}


/* The prepare step's passes over whole arrays (index check, bounds,
 * recentring, unit normals) were half of a gltfpack file's load CPU on the
 * 2M unique factory (perf, 30 loads): each is written once as a scalar
 * loop, and on x86-64 also with SSE2 (always there), four xyz vertices as
 * three vectors whose lanes keep one component each through the loop
 * (phases x y z x | y z x y | z x y z). The vector forms give the scalar
 * loops' values exactly: the same IEEE operations per element in the same
 * order, exact min/max and finite tests; only the sign of a zero bound may
 * differ (-0 == +0). tests/test_scene.c holds them to that. */
#if defined(__SSE2__)
#include <emmintrin.h>

/* Component c's lanes of a phase-ordered triple (flat index i of the 12
 * floats holds component i % 3) reduced to one value. */
static float phase_reduce(const __m128 acc[3], int c, bool is_min) {
    float l[12];
    for (int k = 0; k < 3; k++) _mm_storeu_ps(l + 4 * k, acc[k]);
    float r = l[c];
    for (int i = c + 3; i < 12; i += 3) r = is_min ? (l[i] < r ? l[i] : r) : (l[i] > r ? l[i] : r);
    return r;
}

/* All four lanes' exponent bits set: not finite. */
static __m128i nonfinite_mask(__m128 v) {
    const __m128i e = _mm_set1_epi32(0x7f800000);
    return _mm_cmpeq_epi32(_mm_and_si128(_mm_castps_si128(v), e), e);
}
#endif

/* A value is finite unless all its exponent bits are set: so whole
 * vectors are tested at once (the scalar loop, a branch per value, was 5 ms
 * of the unpacked 2M factory's 70 ms load, and ran twice on its normals). */
bool mr_floats_finite(const float *v, size_t n) {
    size_t i = 0;
#if defined(__SSE2__)
    for (; i + 64 <= n; i += 64) { /* a verdict every 64 values */
        __m128i bad = _mm_setzero_si128();
        for (size_t k = 0; k < 64; k += 4) bad = _mm_or_si128(bad, nonfinite_mask(_mm_loadu_ps(v + i + k)));
        if (_mm_movemask_epi8(bad)) return false;
    }
#endif
    for (; i < n; i++)
        if (!isfinite(v[i])) return false;
    return true;
}

static void make_unit_scalar(float *nrm, size_t n) {
    for (size_t v = 0; v < n; v++) {
        float *p = nrm + 3 * v;
        float l2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        if (l2 > 1.0f - 0x1p-20f && l2 < 1.0f + 0x1p-20f) continue;
        if (l2 > 1e-30f && l2 < 1e30f) {
            float inv = 1.0f / sqrtf(l2);
            p[0] *= inv;
            p[1] *= inv;
            p[2] *= inv;
        } else {
            store_unit(p[0], p[1], p[2], p);
        }
    }
}

/* Makes n xyz normals unit length in place: in float where the squared
 * length cannot overflow or underflow (0.57 of the double path's time on
 * 500k normals, measured; within 1.8e-7 of its result), else store_unit. A
 * normal already unit to float precision (as this makes them) is left as it
 * is, so that a mesh saved and loaded again keeps its normals bit for bit.
 * Vector form: a group of four whose every length is in float's range is
 * scaled by 1 (already unit) or 1/sqrt(l2), each vertex's factor spread
 * back over its three lanes; any other group goes the scalar way. */
static void make_unit(float *nrm, size_t n) {
    size_t v = 0;
#if defined(__SSE2__)
    const __m128 one = _mm_set1_ps(1.0f), tlo = _mm_set1_ps(1.0f - 0x1p-20f), thi = _mm_set1_ps(1.0f + 0x1p-20f);
    const __m128 rlo = _mm_set1_ps(1e-30f), rhi = _mm_set1_ps(1e30f);
    for (; v + 4 <= n; v += 4) {
        float *p = nrm + 3 * v;
        __m128 a = _mm_loadu_ps(p), b = _mm_loadu_ps(p + 4), c = _mm_loadu_ps(p + 8);
        /* a = x0 y0 z0 x1, b = y1 z1 x2 y2, c = z2 x3 y3 z3 */
        __m128 x = _mm_shuffle_ps(_mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 3, 0, 0)), _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2)),
                                  _MM_SHUFFLE(2, 0, 2, 0));
        __m128 y = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1)), _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3)),
                                  _MM_SHUFFLE(2, 0, 2, 0));
        __m128 z = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2)), _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)),
                                  _MM_SHUFFLE(2, 0, 2, 0));
        __m128 l2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y)), _mm_mul_ps(z, z));
        __m128 keep = _mm_and_ps(_mm_cmpgt_ps(l2, tlo), _mm_cmplt_ps(l2, thi));
        __m128 in_range = _mm_and_ps(_mm_cmpgt_ps(l2, rlo), _mm_cmplt_ps(l2, rhi));
        if (_mm_movemask_ps(_mm_or_ps(keep, in_range)) != 15) {
            make_unit_scalar(p, 4);
            continue;
        }
        if (_mm_movemask_ps(keep) == 15) continue;
        __m128 inv = _mm_div_ps(one, _mm_sqrt_ps(l2));
        __m128 s = _mm_or_ps(_mm_and_ps(keep, one), _mm_andnot_ps(keep, inv));
        _mm_storeu_ps(p, _mm_mul_ps(a, _mm_shuffle_ps(s, s, _MM_SHUFFLE(1, 0, 0, 0))));
        _mm_storeu_ps(p + 4, _mm_mul_ps(b, _mm_shuffle_ps(s, s, _MM_SHUFFLE(2, 2, 1, 1))));
        _mm_storeu_ps(p + 8, _mm_mul_ps(c, _mm_shuffle_ps(s, s, _MM_SHUFFLE(3, 3, 3, 2))));
    }
#endif
    make_unit_scalar(nrm + 3 * v, n - v);
}

bool mr_mesh_check_indices(const uint32_t *idx, uint32_t count, uint32_t vertex_count, const char *name, mr_error *err) {
    uint32_t worst = 0; /* a branch-free scan; the error path finds the first */
    uint32_t i = 0;
#if defined(__SSE2__)
    /* SSE2 has no unsigned max: compare with the sign bit flipped. */
    const __m128i flip = _mm_set1_epi32((int)0x80000000u);
    __m128i w = flip; /* 0, flipped */
    for (; i + 4 <= count; i += 4) {
        __m128i q = _mm_xor_si128(_mm_loadu_si128((const __m128i *)(idx + i)), flip);
        __m128i gt = _mm_cmpgt_epi32(q, w);
        w = _mm_or_si128(_mm_and_si128(gt, q), _mm_andnot_si128(gt, w));
    }
    uint32_t l[4];
    _mm_storeu_si128((__m128i *)l, _mm_xor_si128(w, flip));
    for (int k = 0; k < 4; k++) worst = l[k] > worst ? l[k] : worst;
#endif
    for (; i < count; i++) worst = idx[i] > worst ? idx[i] : worst;
    if (count == 0 || worst < vertex_count) return true;
    for (i = 0; i < count; i++)
        if (idx[i] >= vertex_count)
            return mr_fail(err, MR_ERR_INVALID, "mesh '%s': index %u (at %u) is out of range (%u vertices)", name, idx[i], i,
                           vertex_count);
    return true;
}

/* One pass with a branch per value; in double as it was first written (a
 * float version with a branch-free finite test measured half as fast):
 * the float min/max of the vector form converts to the same doubles. */
bool mr_mesh_bounds_add(const float *pos, size_t n, double lo[3], double hi[3]) {
    size_t i = 0;
#if defined(__SSE2__)
    if (n >= 4) {
        __m128 mn[3], mx[3];
        __m128i bad = _mm_setzero_si128();
        for (int k = 0; k < 3; k++) {
            mn[k] = _mm_set1_ps(INFINITY);
            mx[k] = _mm_set1_ps(-INFINITY);
        }
        for (; i + 4 <= n; i += 4)
            for (int k = 0; k < 3; k++) {
                __m128 v = _mm_loadu_ps(pos + 3 * i + 4 * (size_t)k);
                bad = _mm_or_si128(bad, nonfinite_mask(v));
                mn[k] = _mm_min_ps(v, mn[k]);
                mx[k] = _mm_max_ps(v, mx[k]);
            }
        if (_mm_movemask_epi8(bad)) return false;
        for (int c = 0; c < 3; c++) {
            double a = phase_reduce(mn, c, true), b = phase_reduce(mx, c, false);
            if (a < lo[c]) lo[c] = a;
            if (b > hi[c]) hi[c] = b;
        }
    }
#endif
    for (; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double p = pos[3 * i + (size_t)k];
            if (!isfinite(p)) return false;
            if (p < lo[k]) lo[k] = p;
            if (p > hi[k]) hi[k] = p;
        }
    return true;
}

void mr_mesh_recentre_within(float *pos, uint32_t n, const double lo[3], const double hi[3], double origin[3], float bmin[3],
                             float bmax[3]) {
    double centre[3];
    for (int k = 0; k < 3; k++) {
        centre[k] = 0.5 * lo[k] + 0.5 * hi[k]; /* halves first: no overflow near FLT_MAX */
        origin[k] += centre[k];
        bmin[k] = INFINITY;
        bmax[k] = -INFINITY;
    }
    size_t v = 0;
#if defined(__SSE2__)
    if (n >= 4) {
        /* Each phase's four lanes as two double pairs: (cx cy)(cz cx),
         * (cy cz)(cx cy), (cz cx)(cy cz). */
        const __m128d cxy = _mm_set_pd(centre[1], centre[0]), czx = _mm_set_pd(centre[0], centre[2]),
                      cyz = _mm_set_pd(centre[2], centre[1]);
        const __m128d c_lo[3] = {cxy, cyz, czx}, c_hi[3] = {czx, cxy, cyz};
        __m128 mn[3], mx[3];
        for (int k = 0; k < 3; k++) {
            mn[k] = _mm_set1_ps(INFINITY);
            mx[k] = _mm_set1_ps(-INFINITY);
        }
        for (; v + 4 <= n; v += 4)
            for (int k = 0; k < 3; k++) {
                float *p = pos + 3 * v + 4 * (size_t)k;
                __m128 f = _mm_loadu_ps(p);
                __m128d d0 = _mm_sub_pd(_mm_cvtps_pd(f), c_lo[k]);
                __m128d d1 = _mm_sub_pd(_mm_cvtps_pd(_mm_movehl_ps(f, f)), c_hi[k]);
                __m128 r = _mm_movelh_ps(_mm_cvtpd_ps(d0), _mm_cvtpd_ps(d1));
                _mm_storeu_ps(p, r);
                mn[k] = _mm_min_ps(r, mn[k]);
                mx[k] = _mm_max_ps(r, mx[k]);
            }
        for (int c = 0; c < 3; c++) {
            bmin[c] = phase_reduce(mn, c, true);
            bmax[c] = phase_reduce(mx, c, false);
        }
    }
#endif
    /* The float bounds in the same pass. */
    for (; v < n; v++)
        for (int k = 0; k < 3; k++) {
            float *p = &pos[3 * v + (size_t)k];
            *p = (float)((double)*p - centre[k]);
            if (*p < bmin[k]) bmin[k] = *p;
            if (*p > bmax[k]) bmax[k] = *p;
        }
}

/* Positions recentred (mr_mesh_recentre_within) after their finite check
 * and bounds; false + err, nothing changed, if one is not finite. */
static bool recentre(float *pos, uint32_t n, double origin[3], float bmin[3], float bmax[3], const char *name,
                     mr_error *err) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    if (!mr_mesh_bounds_add(pos, n, lo, hi)) return mr_fail(err, MR_ERR_INVALID, "mesh '%s' has a non-finite position", name);
    mr_mesh_recentre_within(pos, n, lo, hi, origin, bmin, bmax);
    return true;
}

void mr_mesh_unit_normals(float *nrm, uint32_t n) { make_unit(nrm, n); }

bool mr_mesh_prepare(mr_mesh *mesh, mr_error *err) {
    if (!mesh) return mr_fail(err, MR_ERR_INVALID, "mr_mesh_prepare: NULL argument");
    char name[80];
    snprintf(name, sizeof name, "%.*s", (int)sizeof mesh->name, mesh->name[0] ? mesh->name : "(unnamed)");
    size_t nv = mesh->vertex_count;
    if (nv == 0 || !mesh->positions) return mr_fail(err, MR_ERR_INVALID, "mesh '%s' has no vertices", name);
    if (mesh->index_count % 3 != 0)
        return mr_fail(err, MR_ERR_INVALID, "mesh '%s' has %u indices, not a multiple of 3", name, mesh->index_count);
    if (mesh->index_count > 0 && !mesh->indices)
        return mr_fail(err, MR_ERR_INVALID, "mesh '%s' has an index count but no indices", name);
    if (!mr_mesh_check_indices(mesh->indices, mesh->index_count, mesh->vertex_count, name, err)) return false;
    if (mesh->normals && !mr_floats_finite(mesh->normals, 3 * nv))
        return mr_fail(err, MR_ERR_INVALID, "mesh '%s' has a non-finite normal", name);
    if (mesh->uvs && !mr_floats_finite(mesh->uvs, 2 * nv))
        return mr_fail(err, MR_ERR_INVALID, "mesh '%s' has a non-finite texture coordinate", name);
    for (int k = 0; k < 3; k++)
        if (!isfinite(mesh->origin[k])) return mr_fail(err, MR_ERR_INVALID, "mesh '%s' has a non-finite origin", name);
    float *gen_normals = NULL;
    if (!mesh->normals) {
        gen_normals = malloc(3 * nv * sizeof *gen_normals);
        if (!gen_normals) return mr_fail(err, MR_ERR_NOMEM, "out of memory generating normals for mesh '%s'", name);
    }
    /* The last check (positions) and the first change: after it nothing
     * fails. */
    if (!recentre(mesh->positions, mesh->vertex_count, mesh->origin, mesh->bounds_min, mesh->bounds_max, name, err)) {
        free(gen_normals);
        return false;
    }
    if (gen_normals) {
        mr_mesh_generate_normals(mesh->positions, mesh->vertex_count, mesh->indices, mesh->index_count, gen_normals);
        mesh->normals = gen_normals;
    } else {
        make_unit(mesh->normals, nv);
    }
    mesh->name[sizeof mesh->name - 1] = 0;
    return true;
}

/* Checks what depends on the scene (its materials) and makes room: false
 * leaves everything as it was. */
static bool can_add(mr_scene *s, const mr_mesh *mesh, mr_error *err) {
    if (mesh->material < -1 || mesh->material >= s->material_count)
        return mr_fail(err, MR_ERR_INVALID, "mesh '%.*s' refers to material %d (scene has %d)", (int)sizeof mesh->name,
                       mesh->name[0] ? mesh->name : "(unnamed)", mesh->material, s->material_count);
    if (!grow((void **)&s->meshes, s->mesh_count, &s->mesh_cap, sizeof *s->meshes))
        return mr_fail(err, MR_ERR_NOMEM, "out of memory adding mesh '%.*s'", (int)sizeof mesh->name, mesh->name);
    return true;
}

static int32_t append(mr_scene *s, mr_mesh *mesh) {
    int32_t idx = s->mesh_count++;
    s->meshes[idx] = *mesh;
    mesh->positions = NULL;
    mesh->normals = NULL;
    mesh->uvs = NULL;
    mesh->indices = NULL;
    return idx;
}

int32_t mr_scene_add_prepared_mesh(mr_scene *s, mr_mesh *mesh, mr_error *err) {
    if (!s || !mesh) {
        mr_fail(err, MR_ERR_INVALID, "mr_scene_add_prepared_mesh: NULL argument");
        return -1;
    }
    return can_add(s, mesh, err) ? append(s, mesh) : -1;
}

/* On failure nothing is freed or changed: the caller keeps ownership of the
 * arrays in *mesh (room made by can_add stays unused). On success the arrays
 * belong to the scene and the pointers in *mesh are set to NULL (so a
 * caller's cleanup cannot double-free), while origin, bounds and vertex data
 * there reflect the stored mesh. */
int32_t mr_scene_add_mesh(mr_scene *s, mr_mesh *mesh, mr_error *err) {
    if (!s || !mesh) {
        mr_fail(err, MR_ERR_INVALID, "mr_scene_add_mesh: NULL argument");
        return -1;
    }
    if (!can_add(s, mesh, err) || !mr_mesh_prepare(mesh, err)) return -1;
    return append(s, mesh);
}

int32_t mr_scene_add_material(mr_scene *s, const mr_material *mat) {
    if (!s || !mat) return -1;
    if (mat->base_color_texture < -1 || mat->base_color_texture >= s->texture_count) {
        mr_log(MR_LOG_WARN, "material '%.64s': texture %d out of range", mat->name, mat->base_color_texture);
        return -1;
    }
    if (!grow((void **)&s->materials, s->material_count, &s->material_cap, sizeof *s->materials)) return -1;
    int32_t idx = s->material_count++;
    s->materials[idx] = *mat;
    s->materials[idx].name[sizeof mat->name - 1] = 0;
    return idx;
}

/* Any 8-bit image with 1..4 channels becomes RGBA8 (gray -> rgb, alpha 255). */
static bool to_rgba8(mr_image *img) {
    if (img->channels == 4) return true;
    size_t n = (size_t)img->width * (size_t)img->height;
    uint8_t *dst = malloc(n * 4);
    if (!dst) return false;
    const uint8_t *src = img->data;
    int c = img->channels;
    for (size_t i = 0; i < n; i++) {
        const uint8_t *p = src + i * (size_t)c;
        uint8_t *q = dst + i * 4;
        if (c <= 2) {
            q[0] = q[1] = q[2] = p[0];
            q[3] = c == 2 ? p[1] : 255;
        } else {
            q[0] = p[0];
            q[1] = p[1];
            q[2] = p[2];
            q[3] = 255;
        }
    }
    free(img->data);
    img->data = dst;
    img->channels = 4;
    return true;
}

/* Takes ownership of tex->image.data on success (the caller's pointer is
 * NULLed); 8-bit images with fewer channels are expanded to RGBA8. */
int32_t mr_scene_add_texture(mr_scene *s, mr_texture *tex) {
    if (!s || !tex) return -1;
    const mr_image *im = &tex->image;
    if (!im->data || im->width <= 0 || im->height <= 0 || im->channels < 1 || im->channels > 4 ||
        im->type != MR_PIX_U8) {
        mr_log(MR_LOG_WARN, "texture rejected: needs an 8-bit image with 1-4 channels");
        return -1;
    }
    if (!grow((void **)&s->textures, s->texture_count, &s->texture_cap, sizeof *s->textures)) return -1;
    mr_texture t = *tex;
    if (!to_rgba8(&t.image)) return -1;
    int32_t idx = s->texture_count++;
    s->textures[idx] = t;
    memset(&tex->image, 0, sizeof tex->image);
    return idx;
}

int32_t mr_scene_add_node(mr_scene *s, const mr_node *node) {
    if (!s || !node) return -1;
    /* Parents come first so that a node's parent index is always valid. */
    if (node->parent < -1 || node->parent >= s->node_count) {
        mr_log(MR_LOG_WARN, "node '%.96s': parent %d out of range", node->name, node->parent);
        return -1;
    }
    if (node->mesh_first >= 0 &&
        (node->mesh_count < 0 || node->mesh_first > s->mesh_count - node->mesh_count)) {
        mr_log(MR_LOG_WARN, "node '%.96s': meshes %d+%d out of range", node->name, node->mesh_first,
               node->mesh_count);
        return -1;
    }
    if (node->layer >= MR_LAYER_COUNT || !mr_m4_is_finite(&node->world)) {
        mr_log(MR_LOG_WARN, "node '%.96s': bad layer or non-finite transform", node->name);
        return -1;
    }
    if (!grow((void **)&s->nodes, s->node_count, &s->node_cap, sizeof *s->nodes)) return -1;
    int32_t idx = s->node_count++;
    s->nodes[idx] = *node;
    s->nodes[idx].name[sizeof node->name - 1] = 0;
    if (node->mesh_first < 0) {
        s->nodes[idx].mesh_first = -1;
        s->nodes[idx].mesh_count = 0;
    }
    return idx;
}

/* Meshes a node draws, clamped to what exists. */
static bool node_meshes(const mr_scene *s, const mr_node *n, int32_t *first, int32_t *count) {
    if (n->mesh_first < 0 || n->mesh_count <= 0 || n->mesh_first >= s->mesh_count) return false;
    *first = n->mesh_first;
    *count = n->mesh_count;
    if (*count > s->mesh_count - *first) *count = s->mesh_count - *first;
    return true;
}

double mr_scene_diagonal(const mr_scene *s) {
    if (!s) return 0;
    double d2 = 0;
    for (int i = 0; i < 3; i++) d2 += (s->bounds_max[i] - s->bounds_min[i]) * (s->bounds_max[i] - s->bounds_min[i]);
    double d = sqrt(d2);
    return d > 0 && isfinite(d) ? d : 0;
}

void mr_scene_update_bounds(mr_scene *s) {
    if (!s) return;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = 0; i < s->node_count; i++) {
        const mr_node *n = &s->nodes[i];
        int32_t first, count;
        if (!node_meshes(s, n, &first, &count)) continue;
        for (int32_t j = first; j < first + count; j++) {
            const mr_mesh *m = &s->meshes[j];
            if (m->vertex_count == 0) continue;
            mr_dmat4 t = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
            mr_dmat4 model = mr_m4_mul(&n->world, &t);
            for (int c = 0; c < 8; c++) {
                mr_dvec3 p = mr_v3((c & 1) ? m->bounds_max[0] : m->bounds_min[0],
                                   (c & 2) ? m->bounds_max[1] : m->bounds_min[1],
                                   (c & 4) ? m->bounds_max[2] : m->bounds_min[2]);
                mr_dvec3 w = mr_m4_point(&model, p);
                double wv[3] = {w.x, w.y, w.z};
                for (int k = 0; k < 3; k++) {
                    if (wv[k] < lo[k]) lo[k] = wv[k];
                    if (wv[k] > hi[k]) hi[k] = wv[k];
                }
            }
        }
    }
    for (int k = 0; k < 3; k++) {
        if (!(lo[k] <= hi[k])) lo[k] = hi[k] = 0.0; /* nothing drawn */
        s->bounds_min[k] = lo[k];
        s->bounds_max[k] = hi[k];
    }
}

uint64_t mr_scene_triangle_count(const mr_scene *s) {
    if (!s) return 0;
    uint64_t total = 0;
    for (int32_t i = 0; i < s->node_count; i++) {
        int32_t first, count;
        if (!node_meshes(s, &s->nodes[i], &first, &count)) continue;
        for (int32_t j = first; j < first + count; j++) total += s->meshes[j].index_count / 3;
    }
    return total;
}

/* Matches one bracket expression at *pp against c; advances *pp past it.
 * Returns -1 if the bracket is unterminated (then '[' is a literal). */
static int glob_class(const char **pp, unsigned char c) {
    const char *p = *pp + 1;
    bool negate = false, match = false;
    if (*p == '!' || *p == '^') {
        negate = true;
        p++;
    }
    bool first = true;
    while (*p && (*p != ']' || first)) {
        unsigned char lo = (unsigned char)*p, hi = lo;
        if (p[1] == '-' && p[2] && p[2] != ']') {
            hi = (unsigned char)p[2];
            p += 3;
        } else {
            p++;
        }
        if (c >= lo && c <= hi) match = true;
        first = false;
    }
    if (*p != ']') return -1;
    *pp = p + 1;
    return match != negate;
}

bool mr_glob_match(const char *pattern, const char *text) {
    if (!pattern || !text) return false;
    const char *p = pattern, *t = text;
    const char *star_p = NULL, *star_t = NULL; /* backtrack point of the last '*' */
    while (*t) {
        if (*p == '*') {
            while (*p == '*') p++;
            if (!*p) return true;
            star_p = p;
            star_t = t;
            continue;
        }
        bool ok = false;
        const char *next = p + 1;
        if (*p == '?') {
            ok = true;
        } else if (*p == '[') {
            const char *q = p;
            int r = glob_class(&q, (unsigned char)*t);
            if (r < 0) ok = (*t == '[');
            else {
                ok = r == 1;
                next = q;
            }
        } else if (*p) {
            ok = (*p == *t);
        }
        if (ok) {
            p = next;
            t++;
        } else if (star_p) {
            p = star_p;
            t = ++star_t;
        } else {
            return false;
        }
    }
    while (*p == '*') p++;
    return *p == 0;
}
