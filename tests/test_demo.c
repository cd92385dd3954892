/* The procedural demo hall: determinism, layers, the three discrepancies,
 * AprilTag plate poses and texture mapping, mesh sanity. */
#include "mr_scene.h"
#include "mr_test.h"

#include <string.h>

#define N_FAKE_TAGS 12
#define FAKE_W 10
#define FAKE_BORDER 1

static uint8_t fake_pixels[N_FAKE_TAGS][FAKE_W * FAKE_W];
static mr_image fake_images[N_FAKE_TAGS];

/* 10x10 gray tags: 1 px white border, black ring, pseudo-random 6x6 bits
 * (asymmetric, so a flipped or rotated mapping would show). */
static void make_fake_tags(void) {
    for (int t = 0; t < N_FAKE_TAGS; t++) {
        uint32_t h = 2166136261u ^ (uint32_t)t;
        for (int r = 0; r < FAKE_W; r++)
            for (int c = 0; c < FAKE_W; c++) {
                uint8_t v;
                if (r < FAKE_BORDER || c < FAKE_BORDER || r >= FAKE_W - FAKE_BORDER || c >= FAKE_W - FAKE_BORDER)
                    v = 255;
                else if (r == 1 || c == 1 || r == FAKE_W - 2 || c == FAKE_W - 2)
                    v = 0;
                else {
                    h = h * 16777619u + (uint32_t)(r * 31 + c);
                    v = (h >> 13) & 1 ? 255 : 0;
                }
                fake_pixels[t][r * FAKE_W + c] = v;
            }
        fake_images[t] = (mr_image){FAKE_W, FAKE_W, 1, MR_PIX_U8, fake_pixels[t]};
    }
}

static bool starts_with(const char *s, const char *prefix) { return strncmp(s, prefix, strlen(prefix)) == 0; }

static int find_node(const mr_scene *s, const char *name) {
    for (int i = 0; i < s->node_count; i++)
        if (strcmp(s->nodes[i].name, name) == 0) return i;
    return -1;
}

static mr_dvec3 translation(const mr_dmat4 *m) { return mr_v3(m->m[3], m->m[7], m->m[11]); }

static bool same_scene(const mr_scene *a, const mr_scene *b) {
    if (a->mesh_count != b->mesh_count || a->node_count != b->node_count ||
        a->material_count != b->material_count || a->texture_count != b->texture_count)
        return false;
    for (int i = 0; i < a->mesh_count; i++) {
        const mr_mesh *x = &a->meshes[i], *y = &b->meshes[i];
        size_t nv = x->vertex_count;
        if (strcmp(x->name, y->name) || x->vertex_count != y->vertex_count || x->index_count != y->index_count ||
            x->material != y->material || memcmp(x->origin, y->origin, sizeof x->origin) ||
            memcmp(x->positions, y->positions, 3 * nv * sizeof(float)) ||
            memcmp(x->normals, y->normals, 3 * nv * sizeof(float)) ||
            memcmp(x->indices, y->indices, x->index_count * sizeof(uint32_t)) || !x->uvs != !y->uvs ||
            (x->uvs && memcmp(x->uvs, y->uvs, 2 * nv * sizeof(float))))
            return false;
    }
    for (int i = 0; i < a->node_count; i++) {
        const mr_node *x = &a->nodes[i], *y = &b->nodes[i];
        if (strcmp(x->name, y->name) || x->parent != y->parent || memcmp(&x->world, &y->world, sizeof x->world) ||
            x->mesh_first != y->mesh_first || x->mesh_count != y->mesh_count || x->layer != y->layer)
            return false;
    }
    for (int i = 0; i < a->material_count; i++)
        if (memcmp(a->materials[i].base_color, b->materials[i].base_color, sizeof(float) * 4) ||
            a->materials[i].base_color_texture != b->materials[i].base_color_texture)
            return false;
    for (int i = 0; i < a->texture_count; i++) {
        const mr_image *x = &a->textures[i].image, *y = &b->textures[i].image;
        if (x->width != y->width || x->height != y->height || mr_image_bytes(x) != mr_image_bytes(y) ||
            memcmp(x->data, y->data, mr_image_bytes(x)))
            return false;
    }
    return true;
}

/* World AABB of a node's meshes. */
static void node_aabb(const mr_scene *s, const mr_node *n, double lo[3], double hi[3]) {
    for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
    for (int j = n->mesh_first; j >= 0 && j < n->mesh_first + n->mesh_count; j++) {
        const mr_mesh *m = &s->meshes[j];
        for (int c = 0; c < 8; c++) {
            mr_dvec3 p = mr_v3(m->origin[0] + ((c & 1) ? m->bounds_max[0] : m->bounds_min[0]),
                               m->origin[1] + ((c & 2) ? m->bounds_max[1] : m->bounds_min[1]),
                               m->origin[2] + ((c & 4) ? m->bounds_max[2] : m->bounds_min[2]));
            mr_dvec3 w = mr_m4_point(&n->world, p);
            double v[3] = {w.x, w.y, w.z};
            for (int k = 0; k < 3; k++) {
                if (v[k] < lo[k]) lo[k] = v[k];
                if (v[k] > hi[k]) hi[k] = v[k];
            }
        }
    }
}

/* Is p inside (a wall or column) of the scene's structure? */
static bool inside_structure(const mr_scene *s, mr_dvec3 p) {
    for (int i = 0; i < s->node_count; i++) {
        const mr_node *n = &s->nodes[i];
        if (!starts_with(n->name, "Wall_") && !starts_with(n->name, "Column_")) continue;
        double lo[3], hi[3];
        node_aabb(s, n, lo, hi);
        if (p.x >= lo[0] && p.x <= hi[0] && p.y >= lo[1] && p.y <= hi[1] && p.z >= lo[2] && p.z <= hi[2])
            return true;
    }
    return false;
}

static void check_scene(const mr_scene *s, const mr_demo_hall *hall) {
    CHECK(s->node_count > 0);
    CHECK(s->mesh_count > 0);
    uint64_t tris = mr_scene_triangle_count(s);
    CHECK_MSG(tris >= 50000 && tris <= 300000, "%llu triangles", (unsigned long long)tris);
    /* The hall's outer shell bounds everything. */
    CHECK_NEAR(s->bounds_min[0], -20.3, 1e-4);
    CHECK_NEAR(s->bounds_max[0], 20.3, 1e-4);
    CHECK_NEAR(s->bounds_min[2], -12.3, 1e-4);
    CHECK_NEAR(s->bounds_max[2], 12.3, 1e-4);
    CHECK_NEAR(s->bounds_min[1], -0.2, 1e-4);
    CHECK_NEAR(s->bounds_max[1], 8.0, 1e-4);

    int hidden = 0, column_mesh = -2, with_mesh = 0;
    char *used = calloc((size_t)s->mesh_count, 1);
    for (int i = 0; i < s->node_count; i++) {
        const mr_node *n = &s->nodes[i];
        bool expect = starts_with(n->name, "Pipe_") || starts_with(n->name, "CableTray_");
        bool globbed = false;
        for (int g = 0; g < hall->hidden_glob_count; g++) globbed |= mr_glob_match(hall->hidden_globs[g], n->name);
        CHECK_MSG((n->layer == MR_LAYER_HIDDEN) == expect, "node %s layer %d", n->name, n->layer);
        CHECK_MSG(globbed == expect, "node %s glob %d", n->name, globbed);
        hidden += n->layer == MR_LAYER_HIDDEN;
        CHECK_MSG(mr_m4_is_rigid(&n->world, 1e-9), "node %s", n->name);
        CHECK(n->parent >= -1 && n->parent < i);
        if (starts_with(n->name, "Column_")) {
            if (column_mesh == -2) column_mesh = n->mesh_first;
            CHECK(n->mesh_first == column_mesh);
        }
        if (n->mesh_first >= 0) {
            with_mesh++;
            for (int j = n->mesh_first; j < n->mesh_first + n->mesh_count; j++) used[j] = 1;
        }
    }
    CHECK(hidden > 0);
    int distinct = 0;
    for (int j = 0; j < s->mesh_count; j++) distinct += used[j];
    free(used);
    CHECK(distinct == s->mesh_count);        /* no orphan meshes */
    CHECK(distinct * 2 < with_mesh);         /* meshes are shared (instancing) */

    /* Finite geometry, unit normals, counter-clockwise front faces. */
    int bad_normals = 0, bad_winding = 0, bad_pos = 0;
    for (int j = 0; j < s->mesh_count; j++) {
        const mr_mesh *m = &s->meshes[j];
        for (uint32_t v = 0; v < m->vertex_count; v++) {
            const float *n = m->normals + 3 * v, *p = m->positions + 3 * v;
            double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
            if (!isfinite(len) || fabs(len - 1.0) > 1e-5) bad_normals++;
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) bad_pos++;
            if (m->uvs && (!isfinite(m->uvs[2 * v]) || !isfinite(m->uvs[2 * v + 1]))) bad_pos++;
        }
        for (uint32_t t = 0; t + 2 < m->index_count; t += 3) {
            const uint32_t *ix = m->indices + t;
            const float *a = m->positions + 3 * ix[0], *b = m->positions + 3 * ix[1], *c = m->positions + 3 * ix[2];
            mr_dvec3 e1 = mr_v3(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
            mr_dvec3 e2 = mr_v3(c[0] - a[0], c[1] - a[1], c[2] - a[2]);
            mr_dvec3 fn = mr_v3_cross(e1, e2), vn = mr_v3(0, 0, 0);
            for (int k = 0; k < 3; k++) {
                const float *n = m->normals + 3 * ix[k];
                vn = mr_v3_add(vn, mr_v3(n[0], n[1], n[2]));
            }
            if (!(mr_v3_dot(fn, vn) > 0.0)) bad_winding++;
        }
    }
    CHECK_MSG(bad_normals == 0, "%d bad normals", bad_normals);
    CHECK_MSG(bad_pos == 0, "%d non-finite positions/uvs", bad_pos);
    CHECK_MSG(bad_winding == 0, "%d triangles wound against their normals", bad_winding);
}

static const cJSON *discrepancy(const cJSON *arr, const char *kind) {
    const cJSON *it;
    cJSON_ArrayForEach(it, arr) {
        const cJSON *k = cJSON_GetObjectItemCaseSensitive(it, "kind");
        if (cJSON_IsString(k) && strcmp(k->valuestring, kind) == 0) return it;
    }
    return NULL;
}

static bool json_vec3(const cJSON *obj, const char *key, mr_dvec3 *v) {
    double d[3];
    mr_error err;
    if (!mr_json_numbers(obj, key, d, 3, &err)) return false;
    *v = mr_v3(d[0], d[1], d[2]);
    return true;
}

static void check_vec_near(mr_dvec3 a, mr_dvec3 b, double tol) {
    CHECK_NEAR(a.x, b.x, tol);
    CHECK_NEAR(a.y, b.y, tol);
    CHECK_NEAR(a.z, b.z, tol);
}

static void check_discrepancies(const mr_demo_hall *hall) {
    const mr_scene *P = hall->planned, *B = hall->built;
    CHECK(cJSON_IsArray(hall->discrepancies));
    CHECK(cJSON_GetArraySize(hall->discrepancies) == 3);
    const cJSON *it;
    cJSON_ArrayForEach(it, hall->discrepancies) {
        CHECK(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(it, "id")));
        CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(it, "node")));
        CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(it, "description")));
    }
    const cJSON *moved = discrepancy(hall->discrepancies, "moved");
    const cJSON *missing = discrepancy(hall->discrepancies, "missing");
    const cJSON *height = discrepancy(hall->discrepancies, "height");
    CHECK(moved && missing && height);
    if (!moved || !missing || !height) return;
    const char *moved_name = cJSON_GetObjectItemCaseSensitive(moved, "node")->valuestring;
    const char *missing_name = cJSON_GetObjectItemCaseSensitive(missing, "node")->valuestring;
    const char *height_name = cJSON_GetObjectItemCaseSensitive(height, "node")->valuestring;
    CHECK(starts_with(moved_name, "Machine_"));
    CHECK(starts_with(missing_name, "Column_"));
    CHECK(starts_with(height_name, "Pipe_"));

    mr_dvec3 pp = {0, 0, 0}, bp = pp, d = pp;
    /* Moved machine: 0.30 m along x, and so are its parts. */
    int pi = find_node(P, moved_name), bi = find_node(B, moved_name);
    CHECK(pi >= 0 && bi >= 0);
    CHECK(json_vec3(moved, "planned_position", &pp) && json_vec3(moved, "built_position", &bp) &&
          json_vec3(moved, "delta", &d));
    check_vec_near(d, mr_v3(0.30, 0, 0), 1e-12);
    mr_dvec3 moved_delta = d;
    if (pi >= 0 && bi >= 0) {
        mr_dvec3 tp = translation(&P->nodes[pi].world), tb = translation(&B->nodes[bi].world);
        check_vec_near(mr_v3_sub(tb, tp), mr_v3(0.30, 0, 0), 1e-9);
        check_vec_near(tp, pp, 1e-9);
        check_vec_near(tb, bp, 1e-9);
    }
    /* Missing column: in the plan, not built. */
    pi = find_node(P, missing_name);
    CHECK(pi >= 0);
    CHECK(find_node(B, missing_name) < 0);
    CHECK(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(missing, "built_position")));
    CHECK(json_vec3(missing, "planned_position", &pp));
    if (pi >= 0) check_vec_near(translation(&P->nodes[pi].world), pp, 1e-9);
    CHECK(B->node_count == P->node_count - 1);
    /* Pipe at another height. */
    pi = find_node(P, height_name);
    bi = find_node(B, height_name);
    CHECK(pi >= 0 && bi >= 0);
    CHECK(json_vec3(height, "planned_position", &pp) && json_vec3(height, "built_position", &bp) &&
          json_vec3(height, "delta", &d));
    CHECK(d.x == 0.0 && d.z == 0.0);
    CHECK_NEAR(d.y, 0.25, 1e-12);
    mr_dvec3 height_delta = d;
    if (pi >= 0 && bi >= 0) {
        mr_dvec3 tp = translation(&P->nodes[pi].world), tb = translation(&B->nodes[bi].world);
        check_vec_near(mr_v3_sub(tb, tp), d, 1e-9);
        check_vec_near(tp, pp, 1e-9);
        check_vec_near(tb, bp, 1e-9);
        CHECK(B->nodes[bi].layer == MR_LAYER_HIDDEN);
    }

    /* Nothing else differs: every other node is where the plan has it. */
    char moved_prefix[112];
    snprintf(moved_prefix, sizeof moved_prefix, "%s_", moved_name);
    int differing = 0;
    for (int i = 0; i < P->node_count; i++) {
        const mr_node *n = &P->nodes[i];
        if (strcmp(n->name, missing_name) == 0) continue;
        int j = find_node(B, n->name);
        CHECK_MSG(j >= 0, "%s missing in built", n->name);
        if (j < 0) continue;
        mr_dvec3 expect = mr_v3(0, 0, 0);
        if (strcmp(n->name, moved_name) == 0 || starts_with(n->name, moved_prefix)) expect = moved_delta;
        if (strcmp(n->name, height_name) == 0) expect = height_delta;
        mr_dvec3 got = mr_v3_sub(translation(&B->nodes[j].world), translation(&n->world));
        bool same_rot = true;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) same_rot &= fabs(B->nodes[j].world.m[r * 4 + c] - n->world.m[r * 4 + c]) < 1e-12;
        CHECK_MSG(same_rot && mr_v3_len(mr_v3_sub(got, expect)) < 1e-9, "node %s moved by %g %g %g", n->name, got.x,
                  got.y, got.z);
        differing += mr_v3_len(got) > 1e-9;
        CHECK(B->nodes[j].mesh_count == n->mesh_count && B->nodes[j].layer == n->layer);
    }
    CHECK(differing >= 2);
}

static void check_tags(const mr_demo_hall *hall, bool with_images, double tag_size) {
    CHECK(hall->tag_count == N_FAKE_TAGS);
    CHECK_NEAR(hall->tag_size, tag_size, 1e-15);
    const double plate = tag_size * FAKE_W / (FAKE_W - 2 * FAKE_BORDER);
    for (int i = 0; i < hall->tag_count; i++) {
        const mr_demo_tag *t = &hall->tags[i];
        const mr_dmat4 *W = &t->world_from_tag;
        CHECK(t->id == i);
        CHECK(mr_m4_is_rigid(W, 1e-12));
        mr_dvec3 o = translation(W);
        mr_dvec3 x = mr_m4_dir(W, mr_v3(1, 0, 0)), y = mr_m4_dir(W, mr_v3(0, 1, 0)), z = mr_m4_dir(W, mr_v3(0, 0, 1));
        check_vec_near(y, mr_v3(0, -1, 0), 1e-12);  /* y down */
        CHECK_NEAR(z.y, 0.0, 1e-12);                  /* plates are vertical */
        /* x is the viewer's right: cross(view direction, up) with view = z. */
        check_vec_near(x, mr_v3_cross(z, mr_v3(0, 1, 0)), 1e-12);
        /* Inside the hall, at a reachable height, facing its centre. */
        CHECK(fabs(o.x) <= 20.0 && fabs(o.z) <= 12.0);
        CHECK(o.y >= 1.5 && o.y <= 2.5);
        mr_dvec3 to_centre = mr_v3_sub(mr_v3(0, o.y, 0), o);
        CHECK_MSG(mr_v3_dot(mr_v3_scale(z, -1.0), to_centre) > 0.0, "tag %d faces away", i);
        /* z points into the surface it sits on, which both variants keep. */
        mr_dvec3 behind = mr_v3_add(o, mr_v3_scale(z, 0.1)), front = mr_v3_sub(o, mr_v3_scale(z, 0.1));
        CHECK_MSG(inside_structure(hall->planned, behind) && inside_structure(hall->built, behind), "tag %d", i);
        CHECK_MSG(!inside_structure(hall->planned, front), "tag %d", i);
        CHECK(!inside_structure(hall->planned, o)); /* in front of the surface */

        char name[32];
        snprintf(name, sizeof name, "Tag_%d", i);
        for (int v = 0; v < 2; v++) {
            const mr_scene *s = v ? hall->built : hall->planned;
            int ni = find_node(s, name);
            CHECK(ni >= 0);
            if (ni < 0) continue;
            const mr_node *n = &s->nodes[ni];
            CHECK(n->layer == MR_LAYER_VISIBLE && n->mesh_count == 1);
            mr_dmat4 tag_from_node = mr_m4_invert_rigid(W);
            tag_from_node = mr_m4_mul(&tag_from_node, &n->world);
            const mr_mesh *m = &s->meshes[n->mesh_first];
            CHECK(m->vertex_count == 4 && m->uvs != NULL);
            if (!m->uvs) continue;
            double xs[4], ys[4];
            for (uint32_t k = 0; k < m->vertex_count && k < 4; k++) {
                const float *p = m->positions + 3 * k;
                mr_dvec3 q = mr_m4_point(&tag_from_node, mr_v3(m->origin[0] + p[0], m->origin[1] + p[1], m->origin[2] + p[2]));
                CHECK_NEAR(q.z, 0.0, 1e-6);
                CHECK_NEAR(fabs(q.x), 0.5 * plate, 1e-6);
                CHECK_NEAR(fabs(q.y), 0.5 * plate, 1e-6);
                /* uv (0,0) is the image's top-left corner, at tag (-p/2, -p/2). */
                CHECK_NEAR(m->uvs[2 * k], q.x / plate + 0.5, 1e-6);
                CHECK_NEAR(m->uvs[2 * k + 1], q.y / plate + 0.5, 1e-6);
                xs[k] = q.x, ys[k] = q.y;
                /* Normal faces out of the wall (-z in the tag frame). */
                const float *nn = m->normals + 3 * k;
                mr_dvec3 wn = mr_m4_dir(&n->world, mr_v3(nn[0], nn[1], nn[2]));
                check_vec_near(wn, mr_v3_scale(z, -1.0), 1e-6);
            }
            /* The four corners are distinct: a full square. */
            double area = 0;
            for (int k = 0; k < 4; k++) area += xs[k] * ys[(k + 1) % 4] - xs[(k + 1) % 4] * ys[k];
            CHECK_NEAR(fabs(area) * 0.5, plate * plate, 1e-6);
            /* The black square's edge (pixel border .. W-border) is tag_size. */
            CHECK_NEAR(((double)FAKE_BORDER / FAKE_W - 0.5) * plate, -0.5 * tag_size, 1e-12);

            const mr_material *mat = &s->materials[m->material];
            if (!with_images) {
                CHECK(mat->base_color_texture == -1);
                CHECK(mat->base_color[0] == 1.0f && mat->base_color[1] == 1.0f && mat->base_color[2] == 1.0f);
                continue;
            }
            CHECK(mat->base_color_texture >= 0 && mat->base_color_texture < s->texture_count);
            if (mat->base_color_texture < 0) continue;
            const mr_texture *tex = &s->textures[mat->base_color_texture];
            CHECK(tex->nearest);
            CHECK(tex->image.width == FAKE_W && tex->image.height == FAKE_W && tex->image.channels == 4 &&
                  tex->image.type == MR_PIX_U8);
            int mismatches = 0;
            const uint8_t *px = tex->image.data;
            for (int k = 0; k < FAKE_W * FAKE_W; k++)
                mismatches += px[4 * k] != fake_pixels[i][k] || px[4 * k + 1] != fake_pixels[i][k] ||
                              px[4 * k + 2] != fake_pixels[i][k] || px[4 * k + 3] != 255;
            CHECK_MSG(mismatches == 0, "tag %d texture: %d pixels differ", i, mismatches);
        }
    }
}

int main(void) {
    make_fake_tags();
    mr_error err = {0};

    /* Default parameters: NULL and MR_DEMO_DEFAULTS give the same hall. */
    mr_demo_hall def = {0}, def2 = {0};
    CHECK(mr_demo_build(NULL, &def, &err));
    mr_demo_params dp = MR_DEMO_DEFAULTS;
    CHECK(mr_demo_build(&dp, &def2, &err));
    if (!def.planned || !def2.planned) {
        fprintf(stderr, "build failed: %s\n", err.msg);
        return mr_test_finish("test_demo");
    }
    CHECK(same_scene(def.planned, def2.planned) && same_scene(def.built, def2.built));
    CHECK(def.hidden_glob_count == 2);
    check_scene(def.planned, &def);
    check_scene(def.built, &def);
    check_discrepancies(&def);
    check_tags(&def, false, 0.4);
    printf("demo hall: %d/%d nodes, %d/%d meshes, %llu/%llu triangles (planned/built)\n", def.planned->node_count,
           def.built->node_count, def.planned->mesh_count, def.built->mesh_count,
           (unsigned long long)mr_scene_triangle_count(def.planned),
           (unsigned long long)mr_scene_triangle_count(def.built));

    /* With tag images: determinism, texture mapping, plate size. */
    mr_demo_params ip = MR_DEMO_DEFAULTS;
    ip.seed = 7;
    ip.tag_size = 0.2;
    ip.tag_images = fake_images;
    ip.tag_image_count = N_FAKE_TAGS;
    ip.tag_border_px = FAKE_BORDER;
    mr_demo_hall a = {0}, b = {0};
    CHECK(mr_demo_build(&ip, &a, &err));
    CHECK(mr_demo_build(&ip, &b, &err));
    if (a.planned && b.planned) {
        CHECK(same_scene(a.planned, b.planned));
        CHECK(same_scene(a.built, b.built));
        CHECK(a.tag_count == b.tag_count && memcmp(a.tags, b.tags, sizeof *a.tags * (size_t)a.tag_count) == 0);
        char *ja = cJSON_PrintUnformatted(a.discrepancies), *jb = cJSON_PrintUnformatted(b.discrepancies);
        CHECK(ja && jb && strcmp(ja, jb) == 0);
        free(ja);
        free(jb);
        CHECK(!same_scene(a.planned, def.planned)); /* another seed, another hall */
        check_scene(a.planned, &a);
        check_scene(a.built, &a);
        check_discrepancies(&a);
        check_tags(&a, true, 0.2);
    }

    /* Free zeroes and may be repeated. */
    mr_demo_free(&b);
    CHECK(b.planned == NULL && b.built == NULL && b.tags == NULL && b.tag_count == 0 && b.discrepancies == NULL);
    mr_demo_free(&b);
    mr_demo_hall zero = {0};
    mr_demo_free(&zero);
    mr_demo_free(NULL);

    /* Bad parameters fail cleanly with nothing left allocated. */
    mr_demo_params bad = ip;
    bad.tag_border_px = 5; /* no black square left in a 10 px image */
    CHECK(!mr_demo_build(&bad, &b, &err));
    CHECK(err.code == MR_ERR_INVALID && b.planned == NULL && b.tags == NULL);
    bad = ip;
    bad.tag_size = -1.0;
    CHECK(!mr_demo_build(&bad, &b, &err));
    CHECK(err.code == MR_ERR_INVALID);
    bad = ip;
    bad.tag_image_count = 0;
    CHECK(!mr_demo_build(&bad, &b, &err));

    mr_demo_free(&a);
    mr_demo_free(&def);
    mr_demo_free(&def2);
    return mr_test_finish("test_demo");
}
