/* The task family's stimuli (Kalkofen et al.'s experiments): a panelled
 * wall in front of hidden structure -- a tall and a wide box at different
 * depths, and a pipe that runs up to the wall from behind -- seen through
 * the ghosting modes. Each target is its own arrangement with one question
 * and its right answer: which hidden box is nearer, or where the pipe
 * meets the wall (its projection, and the scene units per pixel there).
 * Experiment 1's conflict: the hidden parts take the wall's colour;
 * Experiment 2: they are clearly coloured. Written as
 * DIR/<condition>/<mode>/scene<k>.t<j>.png and DIR/<condition>/answers.json. */
#include "mr_scene.h"
#include "mr_study.h"
#include "study_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A unit cube (24 vertices, flat normals) of one material: the six faces
 * from the axis, its sign and the two axes spanning it. */
static int32_t cube_mesh(mr_scene *s, int32_t material, mr_error *err) {
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "task_cube");
    m.material = material;
    m.vertex_count = 24;
    m.index_count = 36;
    m.positions = malloc(72 * sizeof(float));
    m.normals = malloc(72 * sizeof(float));
    m.indices = malloc(36 * sizeof(uint32_t));
    if (!m.positions || !m.normals || !m.indices) {
        free(m.positions), free(m.normals), free(m.indices);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return -1;
    }
    for (int f = 0; f < 6; f++) {
        int ax = f / 2, u = (ax + 1) % 3, v = (ax + 2) % 3;
        float sg = f % 2 ? -0.5f : 0.5f;
        static const float cu[4] = {-0.5f, 0.5f, 0.5f, -0.5f}, cv[4] = {-0.5f, -0.5f, 0.5f, 0.5f};
        for (int k = 0; k < 4; k++) {
            float *p = &m.positions[(f * 4 + k) * 3], *n = &m.normals[(f * 4 + k) * 3];
            p[ax] = sg, p[u] = cu[k] * (sg > 0 ? 1 : -1), p[v] = cv[k];
            n[0] = n[1] = n[2] = 0;
            n[ax] = sg > 0 ? 1.0f : -1.0f;
        }
        const uint32_t q[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++) m.indices[f * 6 + k] = (uint32_t)(f * 4) + q[k];
    }
    return mr_scene_add_mesh(s, &m, err);
}

typedef struct builder {
    mr_scene *s;
    int32_t mesh[6];          /* wall, panel, floor, tall, wide, pipe */
    int count;
    bool ok;
} builder;

static void put(builder *b, int mesh, mr_dvec3 c, mr_dvec3 size, mr_layer layer) {
    if (!b->ok) return;
    mr_dmat4 t = mr_m4_translate(c.x, c.y, c.z), sc = mr_m4_scale(size.x, size.y, size.z);
    mr_node n;
    memset(&n, 0, sizeof n);
    snprintf(n.name, sizeof n.name, "%s_%d", layer == MR_LAYER_HIDDEN ? "Hidden" : "Part", b->count++);
    n.parent = -1;
    n.world = mr_m4_mul(&t, &sc);
    n.mesh_first = b->mesh[mesh];
    n.mesh_count = 1;
    n.layer = (uint8_t)layer;
    if (mr_scene_add_node(b->s, &n) < 0) b->ok = false;
}

/* One target's arrangement, drawn from rng. */
typedef struct target {
    mr_dvec3 tall, wide;      /* box centres */
    mr_dvec3 pipe_end;        /* where the pipe meets the wall's back */
    mr_dvec3 eye, at;
} target;

static void draw_target(mr_rng *rng, target *t) {
    double xt = -2.2 + 4.4 * mr_rng_uniform(rng), xw;
    do xw = -2.0 + 4.0 * mr_rng_uniform(rng);
    while (fabs(xw - xt) < 1.3);
    double zt = -0.7 - 2.4 * mr_rng_uniform(rng), zw;
    do zw = -0.7 - 2.4 * mr_rng_uniform(rng);
    while (fabs(zw - zt) < 0.8);
    t->tall = mr_v3(xt, 0.65, zt);
    t->wide = mr_v3(xw, 0.175, zw);
    t->pipe_end = mr_v3(-2.4 + 4.8 * mr_rng_uniform(rng), 0.5 + 2.0 * mr_rng_uniform(rng), -0.1);
    t->eye = mr_v3(-1.2 + 2.4 * mr_rng_uniform(rng), 1.8, 5.5);
    t->at = mr_v3(0, 1.3, -1.0);
}

static mr_scene *build(const target *t, bool conflict, mr_error *err) {
    builder b = {mr_scene_create(), {0}, 0, true};
    if (!b.s) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    const float wall[3] = {0.74f, 0.69f, 0.60f}, panel[3] = {0.62f, 0.57f, 0.50f}, floor_c[3] = {0.55f, 0.55f, 0.57f};
    /* Experiment 1: the hidden parts nearly the wall's colour (their
     * colours clash with the occluder's); Experiment 2: clear colours. */
    const float hidden_conflict[3][3] = {{0.72f, 0.67f, 0.58f}, {0.70f, 0.66f, 0.57f}, {0.66f, 0.61f, 0.53f}};
    const float hidden_clear[3][3] = {{0.15f, 0.35f, 0.85f}, {0.92f, 0.45f, 0.10f}, {0.10f, 0.62f, 0.22f}};
    const float *colors[6] = {wall, panel, floor_c, conflict ? hidden_conflict[0] : hidden_clear[0],
                              conflict ? hidden_conflict[1] : hidden_clear[1], conflict ? hidden_conflict[2] : hidden_clear[2]};
    for (int i = 0; i < 6 && b.ok; i++) {
        mr_material m;
        memset(&m, 0, sizeof m);
        snprintf(m.name, sizeof m.name, "task_%d", i);
        for (int k = 0; k < 3; k++) m.base_color[k] = colors[i][k];
        m.base_color[3] = 1;
        m.base_color_texture = -1;
        int32_t mi = mr_scene_add_material(b.s, &m);
        b.mesh[i] = mi >= 0 ? cube_mesh(b.s, mi, err) : -1;
        b.ok = b.mesh[i] >= 0;
    }
    put(&b, 0, mr_v3(0, 1.5, 0), mr_v3(6, 3, 0.2), MR_LAYER_VISIBLE);
    /* Raised panels: structure the importance of the ghosted views keeps. */
    for (int r = 0; r < 2; r++)
        for (int c = 0; c < 3; c++)
            put(&b, 1, mr_v3(-1.9 + 1.9 * c, 0.85 + 1.35 * r, 0.13), mr_v3(1.6, 1.1, 0.06), MR_LAYER_VISIBLE);
    put(&b, 2, mr_v3(0, -0.05, 0), mr_v3(12, 0.1, 12), MR_LAYER_VISIBLE);
    put(&b, 3, t->tall, mr_v3(0.35, 1.3, 0.35), MR_LAYER_HIDDEN);
    put(&b, 4, t->wide, mr_v3(1.3, 0.35, 0.35), MR_LAYER_HIDDEN);
    put(&b, 5, mr_v3(t->pipe_end.x, t->pipe_end.y, t->pipe_end.z - 1.7), mr_v3(0.14, 0.14, 3.4), MR_LAYER_HIDDEN);
    if (!b.ok) {
        mr_scene_destroy(&b.s);
        if (!err->msg[0]) mr_fail(err, MR_ERR_NOMEM, "cannot build the task scene");
        return NULL;
    }
    mr_scene_update_bounds(b.s);
    return b.s;
}

static mr_view view_of(const target *t, int w, int h) {
    mr_view v;
    memset(&v, 0, sizeof v);
    v.camera.width = w;
    v.camera.height = h;
    v.camera.fx = v.camera.fy = 0.95 * w;
    v.camera.cx = 0.5 * w - 0.5;
    v.camera.cy = 0.5 * h - 0.5;
    v.world_from_camera = mr_m4_look_at_cv(t->eye, t->at, mr_v3(0, 1, 0));
    return v;
}

/* The target's key into o: "nearer" for even j, "crossing" for odd j. */
static bool key_json(const target *t, const mr_view *v, int j, cJSON *o) {
    mr_dmat4 cam = mr_m4_invert_rigid(&v->world_from_camera);
    if (j % 2 == 0) {
        double zt = mr_m4_point(&cam, t->tall).z, zw = mr_m4_point(&cam, t->wide).z;
        cJSON_AddStringToObject(o, "question", "nearer");
        cJSON_AddStringToObject(o, "text", "Which hidden box is nearer to you: the tall one or the wide one?");
        cJSON *l = cJSON_AddArrayToObject(o, "labels");
        cJSON_AddItemToArray(l, cJSON_CreateString("tall"));
        cJSON_AddItemToArray(l, cJSON_CreateString("wide"));
        cJSON_AddStringToObject(o, "correct", zt < zw ? "tall" : "wide");
        return true;
    }
    mr_dvec3 p = mr_m4_point(&cam, t->pipe_end);
    double u = v->camera.fx * p.x / p.z + v->camera.cx, w = v->camera.fy * p.y / p.z + v->camera.cy;
    if (!(p.z > 0) || u < 10 || w < 10 || u > v->camera.width - 11 || w > v->camera.height - 11) return false;
    cJSON_AddStringToObject(o, "question", "crossing");
    cJSON_AddStringToObject(o, "text", "Tap where the hidden pipe meets the wall.");
    cJSON_AddNumberToObject(o, "x", u);
    cJSON_AddNumberToObject(o, "y", w);
    cJSON_AddNumberToObject(o, "units_per_px", p.z / v->camera.fx);
    return true;
}

bool mr_study_task_stimuli_render(mr_renderer *r, const mr_study_family *fam, const mr_study_stimuli_params *p,
                                  int ss, const char *dir, int *count, mr_error *err) {
    int nm = 0;
    while (fam->methods[nm]) nm++;
    bool ok = true;
    for (int cond = 1; ok && cond <= 2; cond++) {
        char sub[4200], path[4400];
        mr_path_join(dir, mr_study_condition_name(MR_STUDY_TASK, cond), sub, sizeof sub);
        cJSON *keys = cJSON_CreateObject();
        ok = keys && mr_mkdirs(sub, err);
        for (int k = 0; ok && k < p->views; k++)
            for (int j = 0; ok && j < p->targets; j++) {
                /* The same arrangements in both conditions: only the colours differ. */
                mr_rng rng;
                mr_rng_seed(&rng, 0x7a5c0000u + (uint64_t)k * 64 + (uint64_t)j);
                target t;
                mr_view view;
                cJSON *o = cJSON_CreateObject();
                int tries = 0;
                do {
                    cJSON_Delete(o);
                    o = cJSON_CreateObject();
                    draw_target(&rng, &t);
                    view = view_of(&t, p->width, p->height);
                } while (!key_json(&t, &view, j, o) && ++tries < 100);
                char stim[MR_STUDY_NAME_MAX];
                snprintf(stim, sizeof stim, "scene%d.t%d", k, j);
                cJSON_AddItemToObject(keys, stim, o);
                mr_scene *s = build(&t, cond == 1, err);
                ok = s && mr_renderer_set_scene(r, s, err);
                for (int m = 0; ok && m < nm; m++) {
                    mr_frame_params fp = MR_FRAME_DEFAULTS;
                    fp.width = p->width * ss;
                    fp.height = p->height * ss;
                    fam->setup(&fp, m);
                    mr_frame_result res = {0};
                    char md[4400];
                    mr_path_join(sub, fam->methods[m], md, sizeof md);
                    ok = mr_render_frame(r, &view, &fp, &res, err) && mr_mkdirs(md, err) &&
                         mr_study_save_frame(sub, fam->methods[m], stim, &res.color, ss, err);
                    mr_frame_result_free(&res);
                    if (ok && count) (*count)++;
                }
                mr_renderer_set_scene(r, NULL, NULL);
                mr_scene_destroy(&s);
            }
        mr_path_join(sub, "answers.json", path, sizeof path);
        if (ok) ok = mr_json_save(path, keys, err);
        cJSON_Delete(keys);
    }
    return ok;
}
