/* The nearest point on the planned model (`mrcheck measure`):
 * Embree 3's point query walks its BVH (float, relative to the scene's
 * centre) and hands each candidate triangle to a callback that computes the
 * closest point exactly, in double, from the scene's own vertices and
 * world transforms. The query radius shrinks to the best distance plus a
 * margin that covers the float BVH's rounding, so pruning never drops a
 * triangle that could be nearer. */
#include "eval_internal.h"
#include "mr_eval.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <embree3/rtcore.h>

typedef struct near_geom {
    int32_t node, mesh;
    mr_dmat4 M; /* world from the mesh's stored positions (its origin included) */
} near_geom;

struct mr_eval_nearest {
    RTCDevice device;
    RTCScene scene;
    const mr_scene *s;
    double origin[3]; /* world position of the Embree frame's origin */
    double extent;    /* largest |coordinate| in the Embree frame */
    near_geom *geoms; /* by Embree geometry id */
    unsigned ngeom;
};

static void near_error(void *user, enum RTCError code, const char *str) {
    (void)user;
    mr_log(MR_LOG_ERROR, "embree: error %d: %s", (int)code, str ? str : "");
}

mr_eval_nearest *mr_eval_nearest_create(const mr_scene *s, bool skip_hidden, mr_error *err) {
    if (!s) {
        mr_fail(err, MR_ERR_INVALID, "nearest: no scene");
        return NULL;
    }
    /* One geometry per (node, mesh) pair; grown as needed. */
    unsigned cap = (unsigned)s->mesh_count + (unsigned)s->node_count + 1;
    mr_eval_nearest *n = calloc(1, sizeof *n);
    if (!n || !(n->geoms = calloc(cap, sizeof *n->geoms))) {
        free(n);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    n->s = s;
    n->device = rtcNewDevice(NULL);
    if (!n->device) {
        free(n->geoms);
        free(n);
        mr_fail(err, MR_ERR_UNSUPPORTED, "embree: cannot create a device (error %d)", (int)rtcGetDeviceError(NULL));
        return NULL;
    }
    rtcSetDeviceErrorFunction(n->device, near_error, NULL);
    n->scene = rtcNewScene(n->device);
    for (int i = 0; i < 3; i++) {
        n->origin[i] = 0.5 * (s->bounds_min[i] + s->bounds_max[i]);
        if (!isfinite(n->origin[i])) n->origin[i] = 0;
    }
    mr_dmat4 shift = mr_m4_translate(-n->origin[0], -n->origin[1], -n->origin[2]);
    for (int32_t ni = 0; ni < s->node_count; ni++) {
        const mr_node *nd = &s->nodes[ni];
        if (nd->mesh_first < 0 || nd->mesh_count <= 0) continue;
        if (skip_hidden && nd->layer == MR_LAYER_HIDDEN) continue;
        for (int32_t k = 0; k < nd->mesh_count; k++) {
            int32_t mi = nd->mesh_first + k;
            if (mi < 0 || mi >= s->mesh_count) continue;
            const mr_mesh *m = &s->meshes[mi];
            if (m->index_count < 3 || m->vertex_count == 0) continue;
            if (n->ngeom == cap) {
                near_geom *g = realloc(n->geoms, 2 * (size_t)cap * sizeof *g);
                if (!g) {
                    mr_eval_nearest_destroy(&n);
                    mr_fail(err, MR_ERR_NOMEM, "out of memory");
                    return NULL;
                }
                n->geoms = g;
                cap *= 2;
            }
            mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
            mr_dmat4 W = mr_m4_mul(&nd->world, &T), rel = mr_m4_mul(&shift, &W);
            RTCGeometry geom = mr_eval_embree_mesh(n->device, m, &rel, &n->extent);
            if (!geom) {
                mr_eval_nearest_destroy(&n);
                mr_fail(err, MR_ERR_NOMEM, "embree: out of memory for mesh %s", m->name);
                return NULL;
            }
            unsigned id = rtcAttachGeometry(n->scene, geom);
            rtcReleaseGeometry(geom);
            /* Ids are handed out 0, 1, 2, ... in attach order. */
            if (id != n->ngeom) {
                mr_eval_nearest_destroy(&n);
                mr_fail(err, MR_ERR_UNSUPPORTED, "embree: unexpected geometry id %u", id);
                return NULL;
            }
            n->geoms[n->ngeom++] = (near_geom){ni, mi, W};
        }
    }
    rtcCommitScene(n->scene);
    if (rtcGetDeviceError(n->device) != RTC_ERROR_NONE) {
        mr_eval_nearest_destroy(&n);
        mr_fail(err, MR_ERR_UNSUPPORTED, "embree: building the scene failed");
        return NULL;
    }
    return n;
}

void mr_eval_nearest_destroy(mr_eval_nearest **np) {
    if (!np || !*np) return;
    mr_eval_nearest *n = *np;
    if (n->scene) rtcReleaseScene(n->scene);
    if (n->device) rtcReleaseDevice(n->device);
    free(n->geoms);
    free(n);
    *np = NULL;
}

int mr_eval_nearest_triangles(const mr_eval_nearest *n) {
    int t = 0;
    for (unsigned g = 0; n && g < n->ngeom; g++) t += (int)(n->s->meshes[n->geoms[g].mesh].index_count / 3);
    return t;
}

/* The closest point of triangle abc to p by the region of p's projection
 * (vertex, edge or face regions, in barycentric terms). */
mr_dvec3 mr_closest_point_triangle(mr_dvec3 p, mr_dvec3 a, mr_dvec3 b, mr_dvec3 c) {
    mr_dvec3 ab = mr_v3_sub(b, a), ac = mr_v3_sub(c, a), ap = mr_v3_sub(p, a);
    double d1 = mr_v3_dot(ab, ap), d2 = mr_v3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    mr_dvec3 bp = mr_v3_sub(p, b);
    double d3 = mr_v3_dot(ab, bp), d4 = mr_v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) return mr_v3_add(a, mr_v3_scale(ab, d1 / (d1 - d3)));
    mr_dvec3 cp = mr_v3_sub(p, c);
    double d5 = mr_v3_dot(ab, cp), d6 = mr_v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) return mr_v3_add(a, mr_v3_scale(ac, d2 / (d2 - d6)));
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0 && (d4 - d3) + (d5 - d6) > 0)
        return mr_v3_add(b, mr_v3_scale(mr_v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    double den = va + vb + vc;
    if (!(den > 0)) {
        /* Degenerate (zero area): the nearest of its three edges' points
         * is the nearest vertex or a point on the longest edge; the
         * vertices are a safe, finite answer. */
        double da = mr_v3_len(ap), db = mr_v3_len(bp), dc = mr_v3_len(cp);
        return da <= db && da <= dc ? a : db <= dc ? b : c;
    }
    double v = vb / den, w = vc / den;
    return mr_v3_add(a, mr_v3_add(mr_v3_scale(ab, v), mr_v3_scale(ac, w)));
}

typedef struct near_query {
    const mr_eval_nearest *n;
    mr_dvec3 p;
    double margin;
    unsigned geom; /* Embree id of the best triangle's geometry */
    mr_nearest_hit hit;
} near_query;

static void tri_world(const mr_eval_nearest *n, unsigned geom, unsigned prim, mr_dvec3 v[3]) {
    const near_geom *g = &n->geoms[geom];
    const mr_mesh *m = &n->s->meshes[g->mesh];
    for (int k = 0; k < 3; k++) {
        uint32_t i = m->indices[3 * prim + (unsigned)k];
        if (i >= m->vertex_count) i = 0;
        v[k] = mr_m4_point(&g->M, mr_v3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]));
    }
}

static bool near_cb(struct RTCPointQueryFunctionArguments *args) {
    near_query *q = args->userPtr;
    const mr_eval_nearest *n = q->n;
    if (args->geomID >= n->ngeom) return false;
    const mr_mesh *m = &n->s->meshes[n->geoms[args->geomID].mesh];
    if ((size_t)args->primID >= m->index_count / 3) return false;
    mr_dvec3 v[3];
    tri_world(n, args->geomID, args->primID, v);
    mr_dvec3 c = mr_closest_point_triangle(q->p, v[0], v[1], v[2]);
    double d = mr_v3_len(mr_v3_sub(q->p, c));
    if (!isfinite(d) || (q->hit.found && !(d < q->hit.distance))) return false;
    q->hit.found = true;
    q->hit.point = c;
    q->hit.distance = d;
    q->hit.node = n->geoms[args->geomID].node;
    q->hit.mesh = n->geoms[args->geomID].mesh;
    q->hit.triangle = args->primID;
    q->geom = args->geomID;
    float r = (float)(d + q->margin);
    args->query->radius = nextafterf(r, INFINITY);
    return true;
}

bool mr_eval_nearest_point(const mr_eval_nearest *n, mr_dvec3 p, mr_nearest_hit *out) {
    memset(out, 0, sizeof *out);
    out->node = out->mesh = -1;
    if (!n || !isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z)) return false;
    near_query q = {n, p, 0, 0, *out};
    double rel[3] = {p.x - n->origin[0], p.y - n->origin[1], p.z - n->origin[2]};
    /* The float BVH and query point are off by a few ulps of the largest
     * coordinate in play: the margin keeps every triangle that the double
     * computation could find nearer. */
    q.margin = 8 * FLT_EPSILON * (n->extent + fmax(fabs(rel[0]), fmax(fabs(rel[1]), fabs(rel[2])))) + FLT_MIN;
    struct RTCPointQuery pq;
    pq.x = (float)rel[0];
    pq.y = (float)rel[1];
    pq.z = (float)rel[2];
    pq.time = 0;
    pq.radius = INFINITY;
    struct RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    rtcPointQuery(n->scene, &pq, &ctx, near_cb, &q);
    *out = q.hit;
    if (!out->found) return false;
    mr_dvec3 v[3];
    tri_world(n, q.geom, out->triangle, v);
    mr_dvec3 nrm = mr_v3_cross(mr_v3_sub(v[1], v[0]), mr_v3_sub(v[2], v[0]));
    double ln = mr_v3_len(nrm);
    out->normal = ln > 0 ? mr_v3_scale(nrm, 1 / ln) : mr_v3(0, 0, 0);
    /* Off the surface the distance grows along p - c; on it (within
     * rounding of the coordinates) along the face's normal. */
    double scale = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))) + 1e-300;
    if (out->distance > 1e-12 * scale) out->direction = mr_v3_scale(mr_v3_sub(p, out->point), 1 / out->distance);
    else out->direction = out->normal;
    return true;
}

double mr_eval_nearest_sigma(const mr_nearest_hit *h, const double cov[9]) {
    if (!h || !h->found || !cov) return NAN;
    double u[3] = {h->direction.x, h->direction.y, h->direction.z}, v = 0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) v += u[r] * cov[3 * r + c] * u[c];
    return sqrt(fmax(v, 0));
}
