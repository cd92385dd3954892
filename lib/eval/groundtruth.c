/* Ray-traced ambient-occlusion ground truth with Embree 3: cosine-weighted
 * hemisphere rays of length R from each visible surface point; the result
 * is the fraction that escapes. */
#include "eval_internal.h"
#include "mr_eval.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <embree3/rtcore.h>

struct mr_eval_gt {
    RTCDevice device;
    RTCScene scene;
    double origin[3]; /* world position of the Embree frame's origin */
    double diag;      /* bounding-box diagonal of the scene */
};

static void gt_error(void *user, enum RTCError code, const char *str) {
    (void)user;
    mr_log(MR_LOG_ERROR, "embree: error %d: %s", (int)code, str ? str : "");
}

mr_eval_gt *mr_eval_gt_create(const mr_scene *s, bool skip_hidden, mr_error *err) {
    mr_eval_gt *g = calloc(1, sizeof *g);
    if (!g) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    g->device = rtcNewDevice(NULL);
    if (!g->device) {
        free(g);
        mr_fail(err, MR_ERR_UNSUPPORTED, "embree: cannot create a device (error %d)", (int)rtcGetDeviceError(NULL));
        return NULL;
    }
    rtcSetDeviceErrorFunction(g->device, gt_error, NULL);
    g->scene = rtcNewScene(g->device);
    rtcSetSceneBuildQuality(g->scene, RTC_BUILD_QUALITY_HIGH);
    for (int i = 0; i < 3; i++) {
        g->origin[i] = 0.5 * (s->bounds_min[i] + s->bounds_max[i]);
        if (!isfinite(g->origin[i])) g->origin[i] = 0;
    }
    g->diag = mr_scene_diagonal(s);
    if (!(g->diag > 0)) g->diag = 1.0;
    mr_dmat4 shift = mr_m4_translate(-g->origin[0], -g->origin[1], -g->origin[2]);
    for (int32_t ni = 0; ni < s->node_count; ni++) {
        const mr_node *n = &s->nodes[ni];
        if (n->mesh_first < 0 || n->mesh_count <= 0) continue;
        if (skip_hidden && n->layer == MR_LAYER_HIDDEN) continue;
        mr_dmat4 rel = mr_m4_mul(&shift, &n->world);
        for (int32_t k = 0; k < n->mesh_count; k++) {
            int32_t mi = n->mesh_first + k;
            if (mi < 0 || mi >= s->mesh_count) continue;
            const mr_mesh *m = &s->meshes[mi];
            if (m->index_count < 3 || m->vertex_count == 0) continue;
            mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
            mr_dmat4 M = mr_m4_mul(&rel, &T);
            RTCGeometry geom = mr_eval_embree_mesh(g->device, m, &M, NULL);
            if (!geom) {
                mr_eval_gt_destroy(&g);
                mr_fail(err, MR_ERR_NOMEM, "embree: out of memory for mesh %s", m->name);
                return NULL;
            }
            rtcAttachGeometry(g->scene, geom);
            rtcReleaseGeometry(geom);
        }
    }
    rtcCommitScene(g->scene);
    if (rtcGetDeviceError(g->device) != RTC_ERROR_NONE) {
        mr_eval_gt_destroy(&g);
        mr_fail(err, MR_ERR_UNSUPPORTED, "embree: building the scene failed");
        return NULL;
    }
    return g;
}

void mr_eval_gt_destroy(mr_eval_gt **gp) {
    if (!gp || !*gp) return;
    mr_eval_gt *g = *gp;
    if (g->scene) rtcReleaseScene(g->scene);
    if (g->device) rtcReleaseDevice(g->device);
    free(g);
    *gp = NULL;
}

double mr_eval_ao_wall_analytic(double d, double radius) {
    if (!(radius > 0)) return 1.0;
    double a = d / radius;
    if (a >= 1) return 1.0;
    if (a < 0) a = 0;
    return 1.0 - (acos(a) - a * sqrt(1 - a * a)) / 3.14159265358979323846;
}

/* Visibility at p (Embree frame, double) with unit normal n: `rays`
 * cosine-weighted directions, stratified on a jittered grid (the square
 * part of `rays`), the rest independent. */
static double visibility(const mr_eval_gt *g, const double p[3], const double n[3], double radius, int rays,
                         mr_rng *rng) {
    if (!(radius > 0) || rays <= 0) return 1.0;
    /* Orthonormal basis around n (Duff et al. 2017). */
    double sign = n[2] >= 0 ? 1.0 : -1.0, a = -1.0 / (sign + n[2]), b = n[0] * n[1] * a;
    double t[3] = {1 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]};
    double bt[3] = {b, sign + n[1] * n[1] * a, -n[1]};
    int grid = (int)floor(sqrt((double)rays));
    int escaped = 0;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int i = 0; i < rays; i++) {
        double u1 = mr_rng_uniform(rng), u2 = mr_rng_uniform(rng);
        if (i < grid * grid) {
            u1 = ((i % grid) + u1) / grid;
            u2 = ((i / grid) + u2) / grid;
        }
        double r = sqrt(u1), phi = 2 * 3.14159265358979323846 * u2;
        double lx = r * cos(phi), ly = r * sin(phi), lz = sqrt(fmax(0.0, 1 - u1));
        struct RTCRay ray;
        ray.org_x = (float)p[0];
        ray.org_y = (float)p[1];
        ray.org_z = (float)p[2];
        ray.dir_x = (float)(lx * t[0] + ly * bt[0] + lz * n[0]);
        ray.dir_y = (float)(lx * t[1] + ly * bt[1] + lz * n[1]);
        ray.dir_z = (float)(lx * t[2] + ly * bt[2] + lz * n[2]);
        ray.tnear = 0.0f;
        ray.tfar = (float)radius;
        ray.time = 0.0f;
        ray.mask = 0xFFFFFFFFu;
        ray.id = 0;
        ray.flags = 0;
        rtcOccluded1(g->scene, &ctx, &ray);
        if (ray.tfar >= 0.0f) escaped++;
    }
    return (double)escaped / rays;
}

double mr_eval_ao_point(const mr_eval_gt *g, mr_dvec3 p, mr_dvec3 n, double radius, int rays, uint64_t seed) {
    mr_dvec3 nn = mr_v3_normalize(n);
    if (mr_v3_len(nn) == 0) return 1.0;
    double q[3] = {p.x - g->origin[0], p.y - g->origin[1], p.z - g->origin[2]}, nv[3] = {nn.x, nn.y, nn.z};
    mr_rng rng;
    mr_rng_seed(&rng, seed ? seed : 1);
    return visibility(g, q, nv, radius, rays, &rng);
}

typedef struct gt_job {
    const mr_eval_gt *g;
    mr_gt_params p;
} gt_job;

/* The G-buffer's surface at pixel (x, y), depth z, in camera space (through
 * the display mapping when one is given) with its unit normal (facing the
 * camera where the buffer has none), lifted off the surface by a little
 * more than the depth buffer's error so rays do not hit their own
 * triangle. The AO and the shadow ground truth trace from here. */
static void surface_point(const mr_camera *cam, const mr_display_map *dm, int x, int y, float z, const float *n3,
                          mr_dvec3 *pc, mr_dvec3 *nc) {
    mr_dvec3 p = dm ? mr_display_point(dm, cam, x, y, z) : mr_v3((x - cam->cx) / cam->fx * z, (y - cam->cy) / cam->fy * z, z);
    mr_dvec3 n = mr_v3_normalize(mr_v3(n3[0], n3[1], n3[2]));
    if (mr_v3_len(n) == 0) n = mr_v3_normalize(mr_v3_scale(p, -1));
    *pc = mr_v3_add(p, mr_v3_scale(n, 2e-4 * z));
    *nc = n;
}

/* The pixels both ground truths trace from, split over threads by rows
 * (mutex-counted): each visible pixel's surface point and normal in the
 * Embree frame go to `pixel`, whose value is written; 1 where nothing is
 * visible. */
typedef struct gt_rows {
    const mr_image *depth, *normal;
    mr_image *out;
    mr_camera cam;
    const mr_display_map *display;
    mr_dmat4 rel_from_camera; /* Embree frame from camera */
    float (*pixel)(const struct gt_rows *r, size_t i, float z, mr_dvec3 pw, mr_dvec3 nw);
    const void *ctx;
} gt_rows;

static bool row_run(void *arg, size_t row) {
    gt_rows *r = arg;
    int w = r->depth->width, y = (int)row;
    const float *dep = r->depth->data, *nor = r->normal->data;
    float *out = r->out->data;
    for (int x = 0; x < w; x++) {
        size_t i = (size_t)y * w + x;
        float z = dep[i];
        out[i] = 1.0f;
        if (!(z > 0) || !isfinite(z)) continue;
        mr_dvec3 pc, nc;
        surface_point(&r->cam, r->display, x, y, z, nor + 3 * i, &pc, &nc);
        out[i] = r->pixel(r, i, z, mr_m4_point(&r->rel_from_camera, pc), mr_m4_dir(&r->rel_from_camera, nc));
    }
    return true;
}

/* Runs `pixel` over every pixel of depth/normal into out (allocated by the
 * caller), seen from view, on `threads` threads (0: one per core), a row at
 * a time. */
static void rows_run(gt_rows *r, const mr_eval_gt *g, const mr_view *view, int threads) {
    r->cam = mr_camera_resized(&view->camera, r->depth->width, r->depth->height);
    mr_dmat4 shift = mr_m4_translate(-g->origin[0], -g->origin[1], -g->origin[2]);
    r->rel_from_camera = mr_m4_mul(&shift, &view->world_from_camera);
    mr_parallel_for((size_t)r->depth->height, threads, row_run, r);
}

static float ao_pixel(const gt_rows *r, size_t i, float z, mr_dvec3 pw, mr_dvec3 nw) {
    const gt_job *j = r->ctx;
    double R = j->p.radius_mode == MR_AO_RADIUS_SCREEN ? j->p.screen_radius * z * r->cam.height / r->cam.fy
                                                       : j->p.radius;
    double q[3] = {pw.x, pw.y, pw.z}, nv[3] = {nw.x, nw.y, nw.z};
    mr_rng rng;
    mr_rng_seed(&rng, j->p.seed * 0x9E3779B97F4A7C15ull + i);
    return (float)visibility(j->g, q, nv, R, j->p.rays, &rng);
}

bool mr_eval_ao_groundtruth(const mr_eval_gt *g, const mr_view *view, const mr_image *depth, const mr_image *normal,
                            const mr_gt_params *params, mr_image *out, mr_error *err) {
    mr_gt_params p = MR_GT_DEFAULTS;
    if (params) p = *params;
    if (!depth || !normal || !depth->data || !normal->data || depth->type != MR_PIX_F32 || normal->type != MR_PIX_F32 ||
        depth->channels != 1 || normal->channels != 3 || depth->width != normal->width || depth->height != normal->height)
        return mr_fail(err, MR_ERR_INVALID, "ground truth needs an F32 depth image and an F32x3 normal image of one size");
    if (p.rays <= 0) p.rays = 256;
    if (p.seed == 0) p.seed = 1;
    if (!(p.radius > 0) || !isfinite(p.radius)) p.radius = MR_AO_DEFAULT_RADIUS_FRACTION * g->diag;
    if (!(p.screen_radius > 0) || !isfinite(p.screen_radius)) p.screen_radius = MR_AO_DEFAULT_SCREEN_RADIUS;
    if (!mr_image_alloc(out, depth->width, depth->height, 1, MR_PIX_F32, err)) return false;
    gt_job j = {g, p};
    gt_rows rows = {.depth = depth, .normal = normal, .out = out, .display = p.display, .pixel = ao_pixel, .ctx = &j};
    rows_run(&rows, g, view, p.threads);
    return true;
}

/* ------------------------------------------------ area-light shadows
 * Visibility of a light with size: shadow rays from each visible
 * surface point to stratified points on the light (a jittered g x g grid,
 * n = g^2: the rectangle's area, the sphere's disk facing the point, the
 * sun's disk of directions), unweighted: the fraction of the light's area
 * seen, as the shadow-map methods estimate it. */

typedef struct sgt_job {
    const mr_eval_gt *g;
    mr_light light;
    double pos[3];          /* light centre in the Embree frame */
    mr_dvec3 u, v, dir;     /* the light's axes (rect, sun) and its direction */
    double hx, hy;          /* rect half sizes / sphere radius / sun tan(angle/2) */
    int grid;
    uint64_t seed;
} sgt_job;

static bool occluded(const mr_eval_gt *g, const double o[3], mr_dvec3 d, double tfar) {
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay ray;
    ray.org_x = (float)o[0];
    ray.org_y = (float)o[1];
    ray.org_z = (float)o[2];
    ray.dir_x = (float)d.x;
    ray.dir_y = (float)d.y;
    ray.dir_z = (float)d.z;
    ray.tnear = 0.0f;
    ray.tfar = (float)tfar;
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(g->scene, &ctx, &ray);
    return ray.tfar < 0.0f;
}

static double light_visibility(const sgt_job *j, const double q[3], mr_dvec3 n, mr_rng *rng) {
    int g = j->grid, seen = 0, total = g * g;
    mr_dvec3 p = mr_v3(q[0], q[1], q[2]);
    mr_dvec3 c = mr_v3(j->pos[0], j->pos[1], j->pos[2]);
    /* The sphere's disk faces the point. */
    mr_dvec3 su = j->u, sv = j->v;
    if (j->light.kind == MR_LIGHT_SPHERE) {
        mr_dvec3 a = mr_v3_normalize(mr_v3_sub(c, p));
        mr_dvec3 t = fabs(a.x) < 0.9 ? mr_v3(1, 0, 0) : mr_v3(0, 0, 1);
        su = mr_v3_normalize(mr_v3_sub(t, mr_v3_scale(a, mr_v3_dot(t, a))));
        sv = mr_v3_cross(a, su);
    }
    for (int i = 0; i < total; i++) {
        double u1 = ((i % g) + mr_rng_uniform(rng)) / g, u2 = ((i / g) + mr_rng_uniform(rng)) / g;
        mr_dvec3 d;
        double tfar;
        if (j->light.kind == MR_LIGHT_RECT) {
            mr_dvec3 s = mr_v3_add(c, mr_v3_add(mr_v3_scale(su, (2 * u1 - 1) * j->hx), mr_v3_scale(sv, (2 * u2 - 1) * j->hy)));
            d = mr_v3_sub(s, p);
            tfar = mr_v3_len(d);
            d = mr_v3_scale(d, 1 / tfar);
        } else {
            double r = sqrt(u1) * j->hx, phi = 2 * 3.14159265358979323846 * u2;
            mr_dvec3 off = mr_v3_add(mr_v3_scale(su, r * cos(phi)), mr_v3_scale(sv, r * sin(phi)));
            if (j->light.kind == MR_LIGHT_SUN) {
                d = mr_v3_normalize(mr_v3_add(j->dir, off));
                tfar = INFINITY;
            } else {
                d = mr_v3_sub(mr_v3_add(c, off), p);
                tfar = mr_v3_len(d);
                d = mr_v3_scale(d, 1 / tfar);
            }
        }
        /* Light below the surface's tangent plane is blocked by the surface. */
        if (mr_v3_dot(d, n) <= 0) continue;
        if (!occluded(j->g, q, d, tfar * (1 - 1e-6))) seen++;
    }
    return (double)seen / total;
}

static float shadow_pixel(const gt_rows *r, size_t i, float z, mr_dvec3 pw, mr_dvec3 nw) {
    (void)z;
    const sgt_job *j = r->ctx;
    double q[3] = {pw.x, pw.y, pw.z};
    mr_rng rng;
    mr_rng_seed(&rng, j->seed * 0x9E3779B97F4A7C15ull + i);
    return (float)light_visibility(j, q, nw, &rng);
}

bool mr_eval_shadow_groundtruth(const mr_eval_gt *g, const mr_view *view, const mr_image *depth, const mr_image *normal,
                                const mr_light *light, const mr_shadow_gt_params *params, mr_image *out, mr_error *err) {
    mr_shadow_gt_params p = MR_SHADOW_GT_DEFAULTS;
    if (params) p = *params;
    if (!depth || !normal || !depth->data || !normal->data || depth->type != MR_PIX_F32 || normal->type != MR_PIX_F32 ||
        depth->channels != 1 || normal->channels != 3 || depth->width != normal->width || depth->height != normal->height)
        return mr_fail(err, MR_ERR_INVALID, "ground truth needs an F32 depth image and an F32x3 normal image of one size");
    double scale = p.light_scale > 0 ? p.light_scale : 1.0;
    if (p.rays <= 0) p.rays = 256;
    if (p.seed == 0) p.seed = 1;
    sgt_job j;
    memset(&j, 0, sizeof j);
    j.light = *light;
    j.dir = mr_v3_normalize(mr_v3(light->direction[0], light->direction[1], light->direction[2]));
    if (mr_v3_len(j.dir) == 0) return mr_fail(err, MR_ERR_INVALID, "the light's direction is zero");
    mr_dvec3 t = light->kind == MR_LIGHT_RECT ? mr_v3(light->axis_u[0], light->axis_u[1], light->axis_u[2])
                                              : (fabs(j.dir.x) < 0.9 ? mr_v3(1, 0, 0) : mr_v3(0, 0, 1));
    j.u = mr_v3_normalize(mr_v3_sub(t, mr_v3_scale(j.dir, mr_v3_dot(t, j.dir))));
    j.v = mr_v3_cross(j.dir, j.u);
    if (light->kind == MR_LIGHT_RECT) {
        j.hx = 0.5 * light->size[0] * scale;
        j.hy = 0.5 * light->size[1] * scale;
    } else if (light->kind == MR_LIGHT_SPHERE) {
        j.hx = light->size[0] * scale;
    } else {
        j.hx = tan(0.5 * light->angle * scale * 3.14159265358979323846 / 180.0);
    }
    if (!(j.hx >= 0) || !isfinite(j.hx) || !(j.hy >= 0) || !isfinite(j.hy))
        return mr_fail(err, MR_ERR_INVALID, "the light's size is out of range");
    for (int k = 0; k < 3; k++) j.pos[k] = light->position[k] - g->origin[k];
    if (!mr_image_alloc(out, depth->width, depth->height, 1, MR_PIX_F32, err)) return false;
    j.g = g;
    j.grid = (int)floor(sqrt((double)p.rays) + 0.5);
    if (j.grid < 1) j.grid = 1;
    j.seed = p.seed;
    gt_rows rows = {.depth = depth, .normal = normal, .out = out, .pixel = shadow_pixel, .ctx = &j};
    rows_run(&rows, g, view, p.threads);
    return true;
}

bool mr_eval_render_groundtruth_ao(mr_renderer *r, const mr_scene *scene, const mr_view *view,
                                   const mr_frame_params *fp, const mr_gt_params *gtp, mr_frame_result *res,
                                   mr_error *err) {
    mr_frame_params gp = *fp;
    gp.want_depth = gp.want_normals = true;
    mr_frame_result g = {0};
    mr_image ao = {0};
    mr_eval_gt *gt = NULL;
    double t0 = mr_time_now();
    bool ok = mr_render_frame(r, view, &gp, &g, err) && (gt = mr_eval_gt_create(scene, fp->hide_hidden_layer, err)) &&
              mr_eval_ao_groundtruth(gt, view, &g.depth, &g.normal, gtp, &ao, err);
    mr_frame_result_free(&g);
    mr_eval_gt_destroy(&gt);
    if (ok) {
        mr_log(MR_LOG_INFO, "ground truth: %d rays per pixel in %.0f ms", gtp->rays, (mr_time_now() - t0) * 1e3);
        mr_frame_result_free(res);
        mr_frame_params sp = *fp;
        sp.ao.external = &ao;
        ok = mr_render_frame(r, view, &sp, res, err);
    }
    mr_image_free(&ao);
    return ok;
}
