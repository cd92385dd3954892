/* Soft shadows from a shadow map (Hecher's comparison, ch. 3-5).
 *
 *   shadow_map   needed: a map method (hard, pcf, pcss, bp), a casting light,
 *                and the maps of the last frame cannot stand in; draws the
 *                scene from the light: linear light depth (R32F), writes
 *                shadow.map
 *   (unlisted)   the same camera, light, scene and map settings as the last
 *                map: hands that map over (a frozen camera with a static
 *                light draws no map)
 *   shadow_pyramid  needed: backprojection, and the map is new (or its
 *                pyramid was not built); reads shadow.map, writes
 *                shadow.pyramid: the min / max depth mip pyramid that bounds
 *                the backprojection's search (Guennebaud et al. 2006)
 *   (unlisted)   backprojection over a kept map: hands its pyramid over
 *   shadow       needed: any method but off and a casting light; reads
 *                depth (+ shadow.map), writes shadow.visibility; the ground
 *                truth draws its own maps here, one per light sample, and
 *                sums their hard visibilities
 *
 * The light frustum is fitted in double precision: the sun's orthographic
 * rectangle to the part of the scene's bounds the camera can see (the
 * casters towards the light all kept), a perspective light's field of view
 * to the scene's bounds. Everything the GPU sees is relative to the light's
 * eye, so a scene 1e7 units from the origin or at any scale shadows the
 * same. */
#include "render_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

_Static_assert(MR_SHADOW_KERNEL_SIZE == MR_SHADOW_MAX_TAPS, "shadow kernel size");
_Static_assert(MR_SHADOW_METHOD_ID_HARD == MR_SHADOW_HARD && MR_SHADOW_METHOD_ID_PCF == MR_SHADOW_PCF &&
                   MR_SHADOW_METHOD_ID_PCSS == MR_SHADOW_PCSS && MR_SHADOW_METHOD_ID_BP == MR_SHADOW_BP &&
                   MR_SHADOW_METHOD_ID_GROUNDTRUTH == MR_SHADOW_GROUNDTRUTH,
               "shadow method ids");

/* The blocker search and the filters reach at most this far (texels): the
 * cost per pixel stays bounded for huge lights; wider penumbrae saturate. */
#define MAX_SEARCH_TEXELS 48.0
/* Backprojection's search is bounded by the depth pyramid instead; this cap
 * only keeps a huge light's cost finite. */
#define BP_MAX_SEARCH_TEXELS 128.0

_Static_assert(MR_SHADOW_CASCADES_MAX == MR_SHADOW_MAX_CASCADES, "shadow cascades");
/* Cascades: the practical split scheme's blend of the logarithmic and the
 * uniform split (1 = all logarithmic), and the seam band past each split
 * (a fraction of its depth) over which both neighbours are fitted and the
 * visibility blends. One more cascade per factor of CASCADE_RATIO between
 * the far and the near visible depth. */
#define CASCADE_LAMBDA 0.75
#define CASCADE_BAND 0.1
#define CASCADE_RATIO 16.0

/* One sun cascade: its rectangle in the light frame (light_frame's axes and
 * depth) and the culling eye that sees it. */
typedef struct cascade {
    double x0, y0, wx, wy;   /* the rectangle in light xy (relative to the light eye) */
    double cx, cy;           /* its centre: the culling eye's xy */
    double cull_back;
    mr_dmat4 cull_world_from_camera;
    mr_camera cam;
    double near_plane;
    double split;            /* far camera depth of its slice (the band not counted) */
} cascade;

/* The fitted light projection of one frame (all double, scene units). */
typedef struct light_frame {
    mr_light light;
    bool ortho;
    mr_dmat4 lcam_from_world, world_from_lcam; /* the light eye: OpenCV axes, z along the light */
    mr_dmat4 cull_world_from_camera;           /* ortho: an eye behind the box that sees all of it */
    double cull_back;                          /* ortho: its distance behind the light eye */
    mr_camera cam;                             /* the map's intrinsics (perspective) / culling (ortho) */
    double near_plane;
    double x0, y0, wx, wy;                     /* ortho: the rectangle in light xy */
    double k;                                  /* perspective: uv per unit of x/z */
    double znear, zfar;                        /* nearest caster, farthest receiver (light z) */
    double half;                               /* perspective: light half-width; sun: tan(angle/2) */
    double half2[2];                           /* backprojection: half extents on the light */
    int ncasc;                                 /* 1: the single fit above; 2..4: casc[] */
    cascade casc[MR_SHADOW_MAX_CASCADES];
    double vis_near, vis_far;                  /* the camera's visible depth range (sun) */
    double ox, oy;                             /* cascades: the light eye's xy in the scene-fixed frame */
} light_frame;

/* What a shadow map depends on: a frame with the same key reuses it. */
typedef struct map_key {
    const mr_scene *scene;
    mr_dmat4 world_from_camera;
    mr_camera cam;
    mr_light light;
    int map_size;
    float light_scale;
    int cascades;
    int rig_views;         /* a rig frame's maps, fitted to all its views */
    mr_dmat4 rig_outer;    /* its last view (with world_from_camera: the first) */
    bool hide_hidden;      /* the hidden layer casts only while it is drawn */
} map_key;

struct mr_shadow_state {
    GLuint prog_map, prog_vis;
    int map_size;
    int atlas_w, atlas_h;  /* the cascades' tiles (one map: map_size square) */
    target map;            /* R32F linear depth + depth attachment */
    int w, h;
    target vis;            /* R32F visibility at the output size */
    light_frame lf;
    bool key_valid;
    map_key key;
    unsigned rig_serial;   /* the rig frame whose first view drew the maps (0: none) */
    float kernel[2 * MR_SHADOW_MAX_TAPS];
    int kernel_taps;
    GLuint catcher_flags;  /* R8UI, node i at (i % ROW, i / ROW): 1 = shadow catcher */
    GLuint prog_minmax;    /* the depth pyramid (backprojection) */
    GLuint pyramid;        /* RG32F min / max, a P x P pyramid per map tile */
    int pyr_side, pyr_levels, pyr_w, pyr_h;
    bool pyr_valid;        /* built from the map now held */
    const mr_scene *catcher_scene;
};


/* The index among the shaded lights (passes.c's loop) of the casting light;
 * -1: none casts. Without scene lights the shading's first default light is
 * the sun, which casts. */
int mr_shadow_light_index(const mr_scene *s) {
    if (!s || s->light_count <= 0) return 0;
    for (int i = 0; i < s->light_count && i < MR_SHADE_MAX_LIGHTS; i++)
        if (s->lights[i].casts) return i;
    return -1;
}

bool mr_shadow_light(const mr_scene *s, mr_light *out) {
    int i = mr_shadow_light_index(s);
    if (i < 0) return false;
    *out = s && s->light_count > 0 ? s->lights[i] : mr_default_lights[0];
    return true;
}

static int map_size(const mr_shadow_params *p) {
    return p->map_size >= 64 && p->map_size <= 8192 ? p->map_size : MR_SHADOW_DEFAULT_MAP_SIZE;
}
static float light_scale(const mr_shadow_params *p) { return p->light_scale > 0 ? p->light_scale : 1.0f; }
static bool map_method(mr_shadow_method m) { return m >= MR_SHADOW_HARD && m <= MR_SHADOW_BP; }

static bool casts(const frame *f) {
    mr_light l;
    return f->r->scene && f->p->shadow.method != MR_SHADOW_OFF && mr_shadow_light(f->r->scene, &l);
}

static void make_key(const frame *f, map_key *k) {
    memset(k, 0, sizeof *k);
    k->scene = f->r->scene;
    k->world_from_camera = f->view->world_from_camera;
    k->cam = f->cam;
    if (f->r->rig) {
        /* Every view of a rig frame fits the same maps. */
        k->world_from_camera = f->r->rig->world_from_camera[0];
        k->cam = f->r->rig->cam[0];
        k->rig_views = f->r->rig->views;
        k->rig_outer = f->r->rig->world_from_camera[1];
    }
    mr_shadow_light(f->r->scene, &k->light);
    k->map_size = map_size(&f->p->shadow);
    k->light_scale = light_scale(&f->p->shadow);
    k->cascades = f->p->shadow.cascades;
    k->hide_hidden = f->p->hide_hidden_layer;
}

static bool reusable(const frame *f) {
    const struct mr_shadow_state *s = f->r->shadow;
    if (!s || !s->key_valid || !s->map.fbo) return false;
    /* no_reuse: nothing from an earlier frame; a rig frame's views still
     * share the maps its first view drew. */
    if (f->p->shadow.no_reuse && !(f->r->rig && s->rig_serial == f->r->rig->serial)) return false;
    map_key k;
    make_key(f, &k);
    return memcmp(&k, &s->key, sizeof k) == 0;
}

/* ------------------------------------------------------ fitting the light */

static mr_dvec3 any_orthogonal(mr_dvec3 d) {
    mr_dvec3 a = fabs(d.x) < 0.9 ? mr_v3(1, 0, 0) : mr_v3(0, 0, 1);
    return mr_v3_normalize(mr_v3_sub(a, mr_v3_scale(d, mr_v3_dot(a, d))));
}

/* What the light is fitted to: one frame's camera, or a rig
 * frame's outer views (the other views' frusta lie in their hull, slice by
 * slice) with the union volume in the centre camera's axes. */
typedef struct fit_views {
    int n;
    const mr_camera *cam[2];
    const mr_dmat4 *world_from_camera[2];
    const mr_dmat4 *cam_from_world; /* the axes of planes and depths */
    double near_plane;
    double planes[5][4];            /* a.xyz . p + a.w >= 0; the last: z >= near */
} fit_views;

static void fit_views_of(const frame *f, fit_views *fv) {
    memset(fv, 0, sizeof *fv);
    const mr_rig_share *rs = f->r->rig;
    if (rs) {
        fv->n = 2;
        for (int i = 0; i < 2; i++) fv->cam[i] = &rs->cam[i], fv->world_from_camera[i] = &rs->world_from_camera[i];
        fv->cam_from_world = &rs->centre_from_world;
        fv->near_plane = rs->near_plane;
        memcpy(fv->planes, rs->planes, sizeof fv->planes);
        return;
    }
    const mr_camera *c = &f->cam;
    fv->n = 1;
    fv->cam[0] = c;
    fv->world_from_camera[0] = &f->view->world_from_camera;
    fv->cam_from_world = &f->cam_from_world;
    fv->near_plane = f->near_plane;
    const double ax0 = (-0.5 - c->cx) / c->fx, ax1 = (c->width - 0.5 - c->cx) / c->fx;
    const double ay0 = (-0.5 - c->cy) / c->fy, ay1 = (c->height - 0.5 - c->cy) / c->fy;
    /* x >= ax0 z, x <= ax1 z, y >= ay0 z, y <= ay1 z, z >= near */
    const double planes[5][4] = {{1, 0, -ax0, 0}, {-1, 0, ax1, 0}, {0, 1, -ay0, 0}, {0, -1, ay1, 0},
                                 {0, 0, 1, -f->near_plane}};
    memcpy(fv->planes, planes, sizeof planes);
}

/* world_from_lcam with axes x, y = z cross x, z at origin o. */
static mr_dmat4 frame_from_axes(mr_dvec3 x, mr_dvec3 z, mr_dvec3 o) {
    mr_dvec3 y = mr_v3_cross(z, x);
    mr_dmat4 m = mr_m4_identity();
    const mr_dvec3 c[4] = {x, y, z, o};
    for (int j = 0; j < 4; j++) {
        m.m[0 * 4 + j] = c[j].x;
        m.m[1 * 4 + j] = c[j].y;
        m.m[2 * 4 + j] = c[j].z;
    }
    return m;
}

static void scene_corners(const mr_scene *s, mr_dvec3 out[8]) {
    for (int i = 0; i < 8; i++)
        out[i] = mr_v3(i & 1 ? s->bounds_max[0] : s->bounds_min[0], i & 2 ? s->bounds_max[1] : s->bounds_min[1],
                       i & 4 ? s->bounds_max[2] : s->bounds_min[2]);
}

static double scene_diag(const mr_scene *s) {
    double d = mr_scene_diagonal(s);
    return d > 0 ? d : 1.0;
}

/* Sutherland-Hodgman: the part of polygon p (n points, camera space) on
 * the side a.xyz . q + a.w >= 0 of a plane; returns the new count (at most
 * n + 1). */
static int clip_poly(const mr_dvec3 *p, int n, const double a[4], mr_dvec3 *out) {
    int m = 0;
    for (int i = 0; i < n; i++) {
        mr_dvec3 c = p[i], d = p[(i + 1) % n];
        double sc = a[0] * c.x + a[1] * c.y + a[2] * c.z + a[3];
        double sd = a[0] * d.x + a[1] * d.y + a[2] * d.z + a[3];
        if (sc >= 0) out[m++] = c;
        if ((sc >= 0) != (sd >= 0)) out[m++] = mr_v3_add(c, mr_v3_scale(mr_v3_sub(d, c), sc / (sc - sd)));
    }
    return m;
}

/* The camera depth range of what it can see: every drawn node's world box,
 * its faces clipped to the view frustum (near plane included; a rig's
 * union volume), the nearest and farthest camera z left. False if nothing
 * is in view. */
int mr_shadow_cascade_count(int asked, int map_size, int max_tex, double vis_near, double vis_far) {
    if (asked == 1 || 2 * (long)map_size > (long)max_tex) return 1;
    int n = asked;
    if (n <= 0) {
        if (!(vis_near > 0) || !(vis_far > vis_near) || !isfinite(vis_far)) return 1;
        n = 1 + (int)floor(log(vis_far / vis_near) / log(CASCADE_RATIO));
    }
    return n < 1 ? 1 : n > MR_SHADOW_MAX_CASCADES ? MR_SHADOW_MAX_CASCADES : n;
}

static bool visible_depth(const frame *f, const fit_views *fv, double *dn, double *df) {
    const mr_scene *s = f->r->scene;
    const double (*planes)[4] = fv->planes;
    static const int faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
    double lo_z = INFINITY, hi_z = 0;
    for (int32_t i = 0; i < s->node_count; i++) {
        if (f->p->hide_hidden_layer && s->nodes[i].layer == MR_LAYER_HIDDEN) continue;
        double lo[3], hi[3];
        if (!mr_scene_node_bounds(s, i, lo, hi)) continue;
        mr_dvec3 corner[8];
        for (int k = 0; k < 8; k++)
            corner[k] = mr_m4_point(fv->cam_from_world, mr_v3(k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1],
                                                              k & 4 ? hi[2] : lo[2]));
        /* A box whose corners' depths lie inside the range found so far
         * cannot widen it: no clipping (most of a big scene's nodes). */
        double zlo = INFINITY, zhi = -INFINITY;
        for (int k = 0; k < 8; k++) zlo = fmin(zlo, corner[k].z), zhi = fmax(zhi, corner[k].z);
        if (zlo >= lo_z && zhi <= hi_z) continue;
        for (int fc = 0; fc < 6; fc++) {
            mr_dvec3 a[12], b[12];
            int n = 4;
            for (int k = 0; k < 4; k++) a[k] = corner[faces[fc][k]];
            for (int pl = 0; pl < 5 && n > 0; pl++) {
                n = clip_poly(a, n, planes[pl], b);
                memcpy(a, b, sizeof(mr_dvec3) * (size_t)n);
            }
            for (int k = 0; k < n; k++) lo_z = fmin(lo_z, a[k].z), hi_z = fmax(hi_z, a[k].z);
        }
    }
    *dn = lo_z;
    *df = hi_z;
    return isfinite(lo_z) && hi_z > lo_z;
}

/* Splits the visible depth into n slices (the practical scheme: lambda
 * blend of the logarithmic and the uniform split) and fits each a
 * rectangle in the light frame: its frustum slice's extent in light xy,
 * cut to the scene's (slo..shi), plus the margin the filters and the
 * ground truth's shear need (reach). Stable: the sizes are rounded up to
 * steps of 2^(1/8) of the scene's diagonal and the centre snapped to whole
 * texels of a frame fixed to the scene (l0), so a camera that moves
 * shifts a cascade by whole texels only and its shadow does not swim; `o`
 * is the light eye's xy in l0. */
static void fit_cascades(const fit_views *fv, light_frame *lf, const mr_dmat4 *l0_from_w, mr_dvec3 x, mr_dvec3 z,
                         double ox, double oy, const double slo[2], const double shi[2], double reach, double diag,
                         int S, int n) {
    double dn = lf->vis_near, dfar = lf->vis_far, d[MR_SHADOW_MAX_CASCADES + 1];
    for (int i = 0; i <= n; i++)
        d[i] = CASCADE_LAMBDA * dn * pow(dfar / dn, (double)i / n) + (1 - CASCADE_LAMBDA) * (dn + (dfar - dn) * i / n);
    d[0] = dn, d[n] = dfar;
    lf->ox = ox;
    lf->oy = oy;
    for (int k = 0; k < n; k++) {
        cascade *cs = &lf->casc[k];
        /* The slice and the seam band past it (the next cascade blends in
         * there); a little deeper both ways: pixel depths round. */
        double z0 = d[k], z1 = k + 1 < n ? fmin(d[k + 1] * (1 + CASCADE_BAND), dfar) : dfar;
        if (k == 0) z0 *= 0.99;
        if (k + 1 == n) z1 *= 1.01;
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        for (int i = 0; i < 8 * fv->n; i++) {
            const mr_camera *c = fv->cam[i / 8];
            double u = i & 1 ? c->width - 0.5 : -0.5, v = i & 2 ? c->height - 0.5 : -0.5, dd = i & 4 ? z1 : z0;
            mr_dvec3 pc = mr_v3((u - c->cx) / c->fx * dd, (v - c->cy) / c->fy * dd, dd);
            mr_dvec3 p = mr_m4_point(l0_from_w, mr_m4_point(fv->world_from_camera[i / 8], pc));
            lo[0] = fmin(lo[0], p.x), hi[0] = fmax(hi[0], p.x);
            lo[1] = fmin(lo[1], p.y), hi[1] = fmax(hi[1], p.y);
        }
        double wa[2], ca[2];
        for (int a = 0; a < 2; a++) {
            double l = fmax(lo[a], slo[a]), h = fmin(hi[a], shi[a]);
            if (!(h > l)) l = slo[a], h = shi[a];
            double w = (h - l) * 1.02 + 2 * reach + 1e-9 * diag;
            w = diag * exp2(ceil(log2(w / diag) * 8) / 8); /* steps relative to the scene: scale-free */
            double texel = w / S;
            wa[a] = w;
            ca[a] = round(0.5 * (l + h) / texel) * texel - (a ? oy : ox);
        }
        cs->wx = wa[0];
        cs->wy = wa[1];
        cs->cx = ca[0];
        cs->cy = ca[1];
        cs->x0 = ca[0] - 0.5 * wa[0];
        cs->y0 = ca[1] - 0.5 * wa[1];
        cs->split = k + 1 < n ? d[k + 1] : INFINITY;
        double D = fmax(fmax(wa[0], wa[1]), lf->zfar);
        cs->cull_back = D;
        mr_dvec3 eye = mr_m4_point(&lf->world_from_lcam, mr_v3(ca[0], ca[1], -D));
        cs->cull_world_from_camera = frame_from_axes(x, z, eye);
        memset(&cs->cam, 0, sizeof cs->cam);
        cs->cam.width = cs->cam.height = S;
        cs->cam.fx = 0.5 * S / (0.5 * wa[0] / D * 1.05);
        cs->cam.fy = 0.5 * S / (0.5 * wa[1] / D * 1.05);
        cs->cam.cx = cs->cam.cy = 0.5 * S - 0.5;
        cs->near_plane = 0.5 * D;
    }
}

static void fit_sun(const frame *f, const mr_light *L, double scale, int S, int max_tex, light_frame *lf) {
    const mr_scene *s = f->r->scene;
    mr_dvec3 dir = mr_v3_normalize(mr_v3(L->direction[0], L->direction[1], L->direction[2]));
    mr_dvec3 z = mr_v3_scale(dir, -1), x = any_orthogonal(z);
    mr_dvec3 c0 = mr_v3(0.5 * (s->bounds_min[0] + s->bounds_max[0]), 0.5 * (s->bounds_min[1] + s->bounds_max[1]),
                        0.5 * (s->bounds_min[2] + s->bounds_max[2]));
    mr_dmat4 w_from_l0 = frame_from_axes(x, z, c0), l0_from_w = mr_m4_invert_rigid(&w_from_l0);
    mr_dvec3 corners[8];
    scene_corners(s, corners);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double eye_far = 0;
    fit_views fv;
    fit_views_of(f, &fv);
    for (int i = 0; i < 8; i++) {
        mr_dvec3 p = mr_m4_point(&l0_from_w, corners[i]);
        const double *pp = &p.x;
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], pp[a]);
            hi[a] = fmax(hi[a], pp[a]);
        }
        /* The farthest over the rig's eyes is at an outer one (convex). */
        for (int e = 0; e < fv.n; e++) {
            const double *m = fv.world_from_camera[e]->m;
            eye_far = fmax(eye_far, mr_v3_len(mr_v3_sub(corners[i], mr_v3(m[3], m[7], m[11]))));
        }
    }
    /* The camera's frustum out to the farthest corner of the scene, in light
     * xy: receivers outside it cannot be seen, so the map's texels go to
     * the visible part (casters towards the light are kept through z). */
    double flo[2] = {INFINITY, INFINITY}, fhi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < 8 * fv.n; i++) {
        const mr_camera *c = fv.cam[i / 8];
        double u = i & 1 ? c->width - 0.5 : -0.5, v = i & 2 ? c->height - 0.5 : -0.5;
        double d = i & 4 ? eye_far : fv.near_plane;
        mr_dvec3 pc = mr_v3((u - c->cx) / c->fx * d, (v - c->cy) / c->fy * d, d);
        mr_dvec3 pw = mr_m4_point(fv.world_from_camera[i / 8], pc);
        mr_dvec3 pl = mr_m4_point(&l0_from_w, pw);
        flo[0] = fmin(flo[0], pl.x); fhi[0] = fmax(fhi[0], pl.x);
        flo[1] = fmin(flo[1], pl.y); fhi[1] = fmax(fhi[1], pl.y);
    }
    double xlo = fmax(lo[0], flo[0]), xhi = fmin(hi[0], fhi[0]);
    double ylo = fmax(lo[1], flo[1]), yhi = fmin(hi[1], fhi[1]);
    if (!(xhi > xlo)) xlo = lo[0], xhi = hi[0];
    if (!(yhi > ylo)) ylo = lo[1], yhi = hi[1];
    double diag = scene_diag(s);
    double zspan = fmax(hi[2] - lo[2], 1e-9 * diag);
    lf->half = tan(0.5 * L->angle * scale * 3.14159265358979323846 / 180.0);
    /* Margins: the ground truth's sheared samples and the filters reach
     * half * zspan sideways; 1% more against rounding at the border. */
    double mx = lf->half * zspan + 0.01 * fmax(xhi - xlo, yhi - ylo) + 1e-9 * diag;
    xlo -= mx, xhi += mx, ylo -= mx, yhi += mx;
    double zmargin = 0.01 * zspan;
    mr_dvec3 o = mr_v3_add(c0, mr_v3_add(mr_v3_scale(x, 0.5 * (xlo + xhi)),
                                         mr_v3_add(mr_v3_scale(mr_v3_cross(z, x), 0.5 * (ylo + yhi)),
                                                   mr_v3_scale(z, lo[2] - zmargin))));
    lf->ortho = true;
    lf->world_from_lcam = frame_from_axes(x, z, o);
    lf->lcam_from_world = mr_m4_invert_rigid(&lf->world_from_lcam);
    lf->wx = xhi - xlo;
    lf->wy = yhi - ylo;
    lf->x0 = -0.5 * lf->wx;
    lf->y0 = -0.5 * lf->wy;
    lf->znear = zmargin;
    lf->zfar = zmargin + zspan + zmargin;
    double eq = lf->half * 0.886226925452758; /* sqrt(pi)/2: the disk as a square of equal area */
    lf->half2[0] = lf->half2[1] = eq;
    /* Culling: an eye at distance D behind the light's plane whose pyramid
     * holds the whole box (|x| <= D tan at depth >= D). */
    double D = fmax(fmax(lf->wx, lf->wy), lf->zfar);
    lf->cull_back = D;
    lf->cull_world_from_camera = frame_from_axes(x, z, mr_v3_sub(o, mr_v3_scale(z, D)));
    double tx = 0.5 * lf->wx / D * 1.05, ty = 0.5 * lf->wy / D * 1.05;
    memset(&lf->cam, 0, sizeof lf->cam);
    lf->cam.width = lf->cam.height = S;
    lf->cam.fx = 0.5 * S / tx;
    lf->cam.fy = 0.5 * S / ty;
    lf->cam.cx = lf->cam.cy = 0.5 * S - 0.5;
    lf->near_plane = 0.5 * D;
    /* Cascades: asked for, or by the ratio of far to near visible depth;
     * the atlas of 2 x 2 tiles must fit in a texture. */
    lf->ncasc = 1;
    int want = f->p->shadow.cascades;
    if (want != 1 && 2 * S <= max_tex && visible_depth(f, &fv, &lf->vis_near, &lf->vis_far)) {
        int n = mr_shadow_cascade_count(want, S, max_tex, lf->vis_near, lf->vis_far);
        if (n >= 2) {
            fit_cascades(&fv, lf, &l0_from_w, x, z, 0.5 * (xlo + xhi), 0.5 * (ylo + yhi), lo, hi, lf->half * zspan, diag, S, n);
            lf->ncasc = n;
        }
    }
}

static void fit_perspective(const frame *f, const mr_light *L, double scale, int S, light_frame *lf) {
    const mr_scene *s = f->r->scene;
    mr_dvec3 pos = mr_v3(L->position[0], L->position[1], L->position[2]);
    mr_dvec3 corners[8];
    scene_corners(s, corners);
    mr_dvec3 z, x;
    if (L->kind == MR_LIGHT_RECT) {
        z = mr_v3_scale(mr_v3_normalize(mr_v3(L->direction[0], L->direction[1], L->direction[2])), -1);
        x = mr_v3_normalize(mr_v3(L->axis_u[0], L->axis_u[1], L->axis_u[2]));
        x = mr_v3_normalize(mr_v3_sub(x, mr_v3_scale(z, mr_v3_dot(x, z))));
        if (!(mr_v3_len(x) > 0.5)) x = any_orthogonal(z);
    } else {
        mr_dvec3 c = mr_v3(0.5 * (s->bounds_min[0] + s->bounds_max[0]), 0.5 * (s->bounds_min[1] + s->bounds_max[1]),
                           0.5 * (s->bounds_min[2] + s->bounds_max[2]));
        z = mr_v3_normalize(mr_v3_sub(c, pos));
        if (!(mr_v3_len(z) > 0.5)) z = mr_v3(0, -1, 0);
        x = any_orthogonal(z);
    }
    lf->ortho = false;
    lf->world_from_lcam = frame_from_axes(x, z, pos);
    lf->lcam_from_world = mr_m4_invert_rigid(&lf->world_from_lcam);
    double hx, hy;
    if (L->kind == MR_LIGHT_RECT) {
        hx = 0.5 * L->size[0] * scale;
        hy = 0.5 * L->size[1] * scale;
        lf->half = sqrt(hx * hy);
        lf->half2[0] = hx;
        lf->half2[1] = hy;
    } else {
        hx = hy = L->size[0] * scale;
        lf->half = hx;
        lf->half2[0] = lf->half2[1] = hx * 0.886226925452758;
    }
    double diag = scene_diag(s);
    double zn = INFINITY, zf = 0, tmax = 0;
    for (int i = 0; i < 8; i++) {
        mr_dvec3 p = mr_m4_point(&lf->lcam_from_world, corners[i]);
        zf = fmax(zf, p.z);
        zn = fmin(zn, p.z);
        /* Seen from every corner of the light (the ground truth's samples
         * translate the eye that far), the base eye's view is their mean. */
        for (int e = 0; e < 4; e++) {
            double ex = e & 1 ? hx : -hx, ey = e & 2 ? hy : -hy;
            if (p.z <= 1e-6 * diag) {
                tmax = INFINITY;
                continue;
            }
            tmax = fmax(tmax, fmax(fabs(p.x - ex), fabs(p.y - ey)) / p.z);
        }
    }
    /* A scene around the light: at most 160 degrees (the map's texels
     * would thin out beyond); the rest is lit. */
    tmax = fmin(tmax * 1.02, 5.67);
    if (!(tmax > 0)) tmax = 1;
    lf->k = 0.5 / tmax;
    lf->zfar = fmax(zf, 1e-6 * diag);
    lf->znear = fmax(zn, 1e-4 * lf->zfar);
    memset(&lf->cam, 0, sizeof lf->cam);
    lf->cam.width = lf->cam.height = S;
    lf->cam.fx = lf->cam.fy = lf->k * S;
    lf->cam.cx = lf->cam.cy = 0.5 * S - 0.5;
    lf->near_plane = 0.5 * lf->znear;
    lf->cull_world_from_camera = lf->world_from_lcam;
    lf->cull_back = 0;
}

static void fit_light(const frame *f, int max_tex, light_frame *lf) {
    memset(lf, 0, sizeof *lf);
    lf->ncasc = 1;
    mr_shadow_light(f->r->scene, &lf->light);
    double scale = light_scale(&f->p->shadow);
    int S = map_size(&f->p->shadow);
    if (lf->light.kind == MR_LIGHT_SUN) fit_sun(f, &lf->light, scale, S, max_tex, lf);
    else fit_perspective(f, &lf->light, scale, S, lf);
}

int mr_shadow_cascade_grid(const mr_renderer *r, int k, double corner[2], double texel[2]) {
    const struct mr_shadow_state *s = r ? r->shadow : NULL;
    if (!s || s->lf.ncasc < 2) return 0;
    if (k >= 0 && k < s->lf.ncasc) {
        const cascade *cs = &s->lf.casc[k];
        int S = s->map_size;
        corner[0] = cs->x0 + s->lf.ox;
        corner[1] = cs->y0 + s->lf.oy;
        texel[0] = cs->wx / S;
        texel[1] = cs->wy / S;
    }
    return s->lf.ncasc;
}

/* ------------------------------------------------------------ the passes */

void mr_pass_shadow_free(mr_renderer *r) {
    struct mr_shadow_state *s = r->shadow;
    if (!s) return;
    mr_gl_target_free(&s->map);
    mr_gl_target_free(&s->vis);
    glDeleteTextures(1, &s->catcher_flags);
    glDeleteTextures(1, &s->pyramid);
    glDeleteProgram(s->prog_minmax);
    glDeleteProgram(s->prog_map);
    glDeleteProgram(s->prog_vis);
    free(s);
    r->shadow = NULL;
}

static void shadow_scene_changed(mr_renderer *r) {
    if (!r->shadow) return;
    r->shadow->key_valid = false;
    glDeleteTextures(1, &r->shadow->catcher_flags);
    r->shadow->catcher_flags = 0;
    r->shadow->catcher_scene = NULL;
}

static bool has_catchers(const mr_scene *s) {
    for (int32_t i = 0; s && i < s->node_count; i++)
        if (s->nodes[i].shadow_catcher) return true;
    return false;
}

bool mr_shadow_catcher_setup(frame *f, GLuint program_unused, mr_error *err) {
    (void)program_unused;
    mr_renderer *r = f->r;
    const mr_scene *sc = r->scene;
    if (!has_catchers(sc)) {
        glUniform1i(MR_LOC_OVERLAY_CATCHER, 0);
        return true;
    }
    if (!r->shadow && !(r->shadow = calloc(1, sizeof *r->shadow))) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    struct mr_shadow_state *s = r->shadow;
    if (!s->catcher_flags || s->catcher_scene != sc) {
        glDeleteTextures(1, &s->catcher_flags);
        int row = MR_SHADOW_CATCHER_ROW, rows = (sc->node_count + row - 1) / row;
        int w = sc->node_count < row ? sc->node_count : row;
        uint8_t *flags = calloc((size_t)row * rows, 1);
        if (!flags) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        for (int32_t i = 0; i < sc->node_count; i++) flags[i] = sc->nodes[i].shadow_catcher ? 1 : 0;
        glCreateTextures(GL_TEXTURE_2D, 1, &s->catcher_flags);
        glTextureStorage2D(s->catcher_flags, 1, GL_R8UI, w, rows);
        /* An integer texture is complete only with nearest filtering. */
        glTextureParameteri(s->catcher_flags, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(s->catcher_flags, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, row);
        glTextureSubImage2D(s->catcher_flags, 0, 0, 0, w, rows, GL_RED_INTEGER, GL_UNSIGNED_BYTE, flags);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
        free(flags);
        s->catcher_scene = sc;
    }
    GLuint vis = frame_get(f, RES_SHADOW);
    glUniform1i(MR_LOC_OVERLAY_CATCHER, vis ? 2 : 1);
    /* The casting light's share of the catcher's shading (overlay.frag). */
    mr_light L;
    if (!mr_shadow_light(sc, &L)) memset(&L, 0, sizeof L);
    mr_dvec3 d = mr_v3_normalize(mr_m4_dir(&f->cam_from_world, mr_v3(L.direction[0], L.direction[1], L.direction[2])));
    glUniform3f(MR_LOC_OVERLAY_CATCHER_LIGHT, (float)d.x, (float)d.y, (float)d.z);
    glUniform1f(MR_LOC_OVERLAY_CATCHER_LIGHT_LUM, (L.color[0] + L.color[1] + L.color[2]) / 3.0f);
    glUniform1f(MR_LOC_OVERLAY_CATCHER_AMBIENT, sc->ambient);
    glBindTextureUnit(MR_TEX_OVERLAY_IDS, frame_get(f, RES_IDS));
    glBindTextureUnit(MR_TEX_OVERLAY_SHADOW, vis);
    glBindTextureUnit(MR_TEX_OVERLAY_CATCHER_FLAGS, s->catcher_flags);
    glBindTextureUnit(MR_TEX_OVERLAY_NORMAL, frame_get(f, RES_NORMAL));
    return true;
}

static struct mr_shadow_state *state(frame *f, mr_error *err) {
    mr_renderer *r = f->r;
    if (!r->shadow && !(r->shadow = calloc(1, sizeof *r->shadow))) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    return r->shadow;
}

static bool prepare_common(frame *f, mr_error *err) {
    struct mr_shadow_state *s = state(f, err);
    if (!s) return false;
    const mr_shadow_params *p = &f->p->shadow;
    if (!(p->taps >= 0 && p->taps <= MR_SHADOW_MAX_TAPS) || !(p->pcf_radius >= 0) || !(p->light_scale >= 0) ||
        !(p->gt_samples >= 0 && p->gt_samples <= 1024) || !(p->map_size == 0 || (p->map_size >= 64 && p->map_size <= 8192)))
        return mr_fail(err, MR_ERR_INVALID, "shadow settings out of range");
    if (!s->prog_map) {
        const char *const files[] = {"shadow_map.vert.glsl", "shadow_map.frag.glsl", NULL};
        if (!(s->prog_map = mr_gl_program(files, err))) return false;
    }
    if (!s->prog_vis) {
        const char *const files[] = {"fullscreen.vert.glsl", "shadow_vis.frag.glsl", NULL};
        if (!(s->prog_vis = mr_gl_program(files, err))) return false;
    }
    int S = map_size(p);
    GLint max_tex = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
    /* A reused map keeps the light it was fitted with (a rig frame's other
     * views). */
    if (!reusable(f)) fit_light(f, max_tex, &s->lf);
    /* Cascade k is the tile ((k & 1) S, (k >> 1) S) of one atlas. */
    int aw = s->lf.ncasc > 1 ? 2 * S : S, ah = s->lf.ncasc > 2 ? 2 * S : S;
    if (s->map_size != S || s->atlas_w != aw || s->atlas_h != ah) {
        mr_gl_target_free(&s->map);
        s->key_valid = false;
        static const GLenum fmt[1] = {GL_R32F};
        if (!mr_gl_target_make(&s->map, aw, ah, fmt, 1, true, err)) return false;
        s->map_size = S;
        s->atlas_w = aw;
        s->atlas_h = ah;
    }
    if (s->w != f->r->w || s->h != f->r->h) {
        mr_gl_target_free(&s->vis);
        static const GLenum fmt[1] = {GL_R32F};
        if (!mr_gl_target_make(&s->vis, f->r->w, f->r->h, fmt, 1, false, err)) return false;
        s->w = f->r->w;
        s->h = f->r->h;
    }
    int taps = p->taps > 0 ? p->taps : MR_SHADOW_DEFAULT_TAPS;
    if (s->kernel_taps != taps) {
        /* Poisson-disk taps in the unit disk, fixed seed: the same pattern
         * every frame, rotated per pixel by the shader. */
        mr_ao_kernel_generate(MR_AO_KERNEL_POISSON, taps, 0.0f, 1.0f, 0x5ad0u, NULL, s->kernel);
        s->kernel_taps = taps;
    }
    return true;
}

static bool need_map(const frame *f) { return casts(f) && map_method(f->p->shadow.method) && !reusable(f); }
/* The pyramid is built from the map of this frame: a new map, or a kept
 * one whose pyramid was never built (the method was not bp then). */
static bool need_pyramid(const frame *f) {
    return casts(f) && f->p->shadow.method == MR_SHADOW_BP &&
           (need_map(f) || !f->r->shadow || !f->r->shadow->pyr_valid);
}
static bool need_pyramid_reuse(const frame *f) {
    return casts(f) && f->p->shadow.method == MR_SHADOW_BP && !need_pyramid(f);
}
static bool need_map_reuse(const frame *f) { return casts(f) && map_method(f->p->shadow.method) && reusable(f); }
static bool need_vis(const frame *f) { return casts(f); }
static uint32_t vis_reads_now(const frame *f) {
    return RES(RES_DEPTH) | RES(RES_NORMAL) | (map_method(f->p->shadow.method) ? RES(RES_SHADOW_MAP) : 0) |
           (f->p->shadow.method == MR_SHADOW_BP ? RES(RES_SHADOW_PYRAMID) : 0);
}

/* Draws the map of one light position: the base eye moved by `offset`
 * (perspective, light axes) or the projection sheared by `shear` (sun);
 * with cascades, every cascade's tile. */
static void draw_map_tile(frame *f, int k, const double offset[3], const double shear[2]);
static void draw_map(frame *f, const double offset[3], const double shear[2]) {
    struct mr_shadow_state *s = f->r->shadow;
    for (int k = 0; k < s->lf.ncasc; k++) draw_map_tile(f, k, offset, shear);
}

static void draw_map_tile(frame *f, int k, const double offset[3], const double shear[2]) {
    struct mr_shadow_state *s = f->r->shadow;
    const light_frame *lf = &s->lf;
    const cascade *cs = lf->ncasc > 1 ? &lf->casc[k] : NULL;
    int S = s->map_size;
    glBindFramebuffer(GL_FRAMEBUFFER, s->map.fbo);
    glViewport((k & 1) * S, (k >> 1) * S, S, S);
    if (cs) {
        glEnable(GL_SCISSOR_TEST); /* the clears below: this tile only */
        glScissor((k & 1) * S, (k >> 1) * S, S, S);
    }
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_DEPTH_CLAMP);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_TRUE);
    const float far_z[4] = {1e30f, 0, 0, 0};
    static const float depth0 = 0.0f;
    glClearNamedFramebufferfv(s->map.fbo, GL_COLOR, 0, far_z);
    glClearNamedFramebufferfv(s->map.fbo, GL_DEPTH, 0, &depth0);
    glUseProgram(s->prog_map);
    glUniform1i(MR_LOC_SHADOW_MAP_ORTHO, lf->ortho);
    if (cs) {
        glDisable(GL_SCISSOR_TEST);
        glUniform4f(MR_LOC_SHADOW_MAP_RECT, (float)cs->x0, (float)cs->y0, (float)(1 / cs->wx), (float)(1 / cs->wy));
    } else {
        glUniform4f(MR_LOC_SHADOW_MAP_RECT, (float)lf->x0, (float)lf->y0, (float)(1 / lf->wx), (float)(1 / lf->wy));
    }
    glUniform2f(MR_LOC_SHADOW_MAP_DEPTH, 0.0f, (float)(1.0 / (lf->zfar * 1.5)));
    /* The culling eye of the sun sits cull_back behind the light's plane
     * (a cascade's over its square's centre): the vertices arrive relative
     * to it. */
    if (cs)
        glUniform3f(MR_LOC_SHADOW_MAP_OFFSET, (float)(offset[0] - cs->cx), (float)(offset[1] - cs->cy),
                    (float)(offset[2] + cs->cull_back));
    else
        glUniform3f(MR_LOC_SHADOW_MAP_OFFSET, (float)offset[0], (float)offset[1], (float)(offset[2] + lf->cull_back));
    glUniform2f(MR_LOC_SHADOW_MAP_SHEAR, (float)shear[0], (float)shear[1]);
    mr_geo_view v;
    memset(&v, 0, sizeof v);
    v.cam = cs ? cs->cam : lf->cam;
    v.world_from_camera = cs ? cs->cull_world_from_camera : lf->cull_world_from_camera;
    v.cam_from_world = mr_m4_invert_rigid(&v.world_from_camera);
    v.near_plane = cs ? cs->near_plane : lf->near_plane;
    v.program = s->prog_map;
    v.layers = (1u << MR_LAYER_VISIBLE) | (f->p->hide_hidden_layer ? 0u : 1u << MR_LAYER_HIDDEN);
    mr_geometry_draw(f->r, &v, f->out);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_DEPTH_CLAMP);
}

static void run_map(frame *f) {
    struct mr_shadow_state *s = f->r->shadow;
    const double zero3[3] = {0, 0, 0}, zero2[2] = {0, 0};
    draw_map(f, zero3, zero2);
    make_key(f, &s->key);
    s->key_valid = true;
    s->rig_serial = f->r->rig ? f->r->rig->serial : 0;
    s->pyr_valid = false;
    frame_put(f, RES_SHADOW_MAP, s->map.color[0]);
}

static void run_map_reuse(frame *f) {
    f->out->shadow_reused = true;
    frame_put(f, RES_SHADOW_MAP, f->r->shadow->map.color[0]);
}

static void draw_vis(frame *f, int method, const double offset[3], const double shear[2], float weight) {
    mr_renderer *r = f->r;
    struct mr_shadow_state *s = r->shadow;
    const light_frame *lf = &s->lf;
    const mr_shadow_params *p = &f->p->shadow;
    glBindFramebuffer(GL_FRAMEBUFFER, s->vis.fbo);
    glViewport(0, 0, r->w, r->h);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glUseProgram(s->prog_vis);
    glUniform4f(MR_LOC_SHADOW_INTR, (float)f->cam.fx, (float)f->cam.fy, (float)f->cam.cx, (float)f->cam.cy);
    glUniform1f(MR_LOC_SHADOW_NEAR, (float)f->near_plane);
    mr_dmat4 lfc = mr_m4_mul(&lf->lcam_from_world, &f->view->world_from_camera);
    float m[16];
    mr_m4_to_gl(&lfc, m);
    glUniformMatrix4fv(MR_LOC_SHADOW_LIGHT_FROM_CAM, 1, GL_FALSE, m);
    glUniform1i(MR_LOC_SHADOW_ORTHO, lf->ortho);
    glUniform4f(MR_LOC_SHADOW_RECT, (float)lf->x0, (float)lf->y0, (float)(1 / lf->wx), (float)(1 / lf->wy));
    {
        float rects[4 * MR_SHADOW_MAX_CASCADES] = {0}, splits[4] = {0};
        int n = lf->ncasc > 1 ? lf->ncasc : 0;
        for (int k = 0; k < n; k++) {
            const cascade *cs = &lf->casc[k];
            rects[4 * k + 0] = (float)cs->x0;
            rects[4 * k + 1] = (float)cs->y0;
            rects[4 * k + 2] = (float)(1 / cs->wx);
            rects[4 * k + 3] = (float)(1 / cs->wy);
            splits[k] = (float)fmin(cs->split, 1e30);
        }
        glUniform1i(MR_LOC_SHADOW_CASCADES, n);
        glUniform4fv(MR_LOC_SHADOW_SPLITS, 1, splits);
        glUniform1f(MR_LOC_SHADOW_BAND, (float)CASCADE_BAND);
        glUniform4fv(MR_LOC_SHADOW_RECTS, MR_SHADOW_MAX_CASCADES, rects);
    }
    glUniform1f(MR_LOC_SHADOW_K, (float)lf->k);
    glUniform2f(MR_LOC_SHADOW_ZRANGE, (float)lf->znear, (float)lf->zfar);
    glUniform1f(MR_LOC_SHADOW_LIGHT_HALF, (float)lf->half);
    glUniform2f(MR_LOC_SHADOW_LIGHT_AREA, (float)lf->half2[0], (float)lf->half2[1]);
    glUniform1i(MR_LOC_SHADOW_METHOD, method);
    glUniform1i(MR_LOC_SHADOW_TAPS, s->kernel_taps);
    glUniform1f(MR_LOC_SHADOW_PCF_RADIUS, p->pcf_radius > 0 ? p->pcf_radius : MR_SHADOW_DEFAULT_PCF_RADIUS);
    glUniform1i(MR_LOC_SHADOW_MAP_SIZE, s->map_size);
    glUniform3f(MR_LOC_SHADOW_OFFSET, (float)offset[0], (float)offset[1], (float)offset[2]);
    glUniform2f(MR_LOC_SHADOW_SHEAR, (float)shear[0], (float)shear[1]);
    glUniform1f(MR_LOC_SHADOW_WEIGHT, weight);
    glUniform1f(MR_LOC_SHADOW_MAX_SEARCH, (float)(method == MR_SHADOW_METHOD_ID_BP ? BP_MAX_SEARCH_TEXELS : MAX_SEARCH_TEXELS));
    /* A top level of -1: no pyramid (bp_no_pyramid), the full search. */
    glUniform2i(MR_LOC_SHADOW_PYRAMID, s->pyr_side, p->bp_no_pyramid ? -1 : s->pyr_levels - 1);
    if (method == MR_SHADOW_METHOD_ID_BP) glBindTextureUnit(MR_TEX_SHADOW_MINMAX, frame_get(f, RES_SHADOW_PYRAMID));
    glUniform2fv(MR_LOC_SHADOW_KERNEL, s->kernel_taps, s->kernel);
    glBindTextureUnit(MR_TEX_SHADOW_DEPTH, frame_get(f, RES_DEPTH));
    glBindTextureUnit(MR_TEX_SHADOW_NORMAL, frame_get(f, RES_NORMAL));
    glBindTextureUnit(MR_TEX_SHADOW_MAP, s->map.color[0]);
    glBindVertexArray(r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
}

/* The ground truth: the mean of n hard shadows from stratified points on
 * the light (a jittered g x g grid, n = g^2, fixed seed): for a rectangle
 * its area, for a sphere and the sun's disk the disk (concentric radii). */
static void run_groundtruth(frame *f) {
    struct mr_shadow_state *s = f->r->shadow;
    const light_frame *lf = &s->lf;
    int n = f->p->shadow.gt_samples > 0 ? f->p->shadow.gt_samples : MR_SHADOW_DEFAULT_GT_SAMPLES;
    int g = (int)floor(sqrt((double)n) + 0.5);
    if (g < 1) g = 1;
    n = g * g;
    static const float zero4[4] = {0, 0, 0, 0};
    glClearNamedFramebufferfv(s->vis.fbo, GL_COLOR, 0, zero4);
    mr_rng rng;
    mr_rng_seed(&rng, 0x6d72u);
    for (int i = 0; i < n; i++) {
        double u = ((i % g) + mr_rng_uniform(&rng)) / g, v = ((i / g) + mr_rng_uniform(&rng)) / g;
        double off[3] = {0, 0, 0}, sh[2] = {0, 0};
        if (lf->light.kind == MR_LIGHT_RECT) {
            off[0] = (2 * u - 1) * lf->half2[0];
            off[1] = (2 * v - 1) * lf->half2[1];
        } else {
            double rad = sqrt(u) * lf->half, phi = 2 * 3.14159265358979323846 * v;
            double *t = lf->light.kind == MR_LIGHT_SUN ? sh : off;
            t[0] = rad * cos(phi);
            t[1] = rad * sin(phi);
        }
        draw_map(f, off, sh);
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        glBlendEquation(GL_FUNC_ADD);
        draw_vis(f, MR_SHADOW_METHOD_ID_GROUNDTRUTH, off, sh, 1.0f / (float)n);
        glDisable(GL_BLEND);
    }
    s->key_valid = false; /* the map holds the last sample's */
    s->pyr_valid = false;
}

static void run_vis(frame *f) {
    struct mr_shadow_state *s = f->r->shadow;
    if (f->p->shadow.method == MR_SHADOW_GROUNDTRUTH) {
        run_groundtruth(f);
    } else {
        const double zero3[3] = {0, 0, 0}, zero2[2] = {0, 0};
        draw_vis(f, (int)f->p->shadow.method, zero3, zero2, 1.0f);
    }
    f->out->shadow_cascades = s->lf.ncasc;
    frame_put(f, RES_SHADOW, s->vis.color[0]);
}

/* ------------------------------------------------ the depth pyramid (bp) */

static bool prepare_pyramid(frame *f, mr_error *err) {
    if (!prepare_common(f, err)) return false;
    struct mr_shadow_state *s = f->r->shadow;
    if (!s->prog_minmax) {
        const char *const files[] = {"shadow_minmax.comp.glsl", NULL};
        if (!(s->prog_minmax = mr_gl_program(files, err))) return false;
    }
    /* A tile's pyramid is the next power of two of the map's side, so each
     * level halves exactly; tiles sit as the map's cascades do. */
    int S = s->map_size, P = 1, levels = 1;
    while (P < S) P *= 2, levels++;
    int pw = s->atlas_w / S * P, ph = s->atlas_h / S * P;
    if (s->pyramid && s->pyr_side == P && s->pyr_w == pw && s->pyr_h == ph) return true;
    glDeleteTextures(1, &s->pyramid);
    glCreateTextures(GL_TEXTURE_2D, 1, &s->pyramid);
    glTextureStorage2D(s->pyramid, levels, GL_RG32F, pw, ph);
    glTextureParameteri(s->pyramid, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    glTextureParameteri(s->pyramid, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    s->pyr_side = P;
    s->pyr_levels = levels;
    s->pyr_w = pw;
    s->pyr_h = ph;
    s->pyr_valid = false;
    return true;
}

static void run_pyramid(frame *f) {
    struct mr_shadow_state *s = f->r->shadow;
    glUseProgram(s->prog_minmax);
    glUniform1i(MR_LOC_SHADOW_MM_SIZE, s->map_size);
    glUniform1i(MR_LOC_SHADOW_MM_PYR, s->pyr_side);
    glBindTextureUnit(MR_TEX_SHADOW_MM_MAP, frame_get(f, RES_SHADOW_MAP));
    for (int l = 0; l < s->pyr_levels; l++) {
        int w = s->pyr_w >> l, h = s->pyr_h >> l;
        glUniform1i(MR_LOC_SHADOW_MM_LEVEL, l);
        glBindImageTexture(MR_IMG_SHADOW_MM_SRC, s->pyramid, l > 0 ? l - 1 : 0, GL_FALSE, 0, GL_READ_ONLY, GL_RG32F);
        glBindImageTexture(MR_IMG_SHADOW_MM_DST, s->pyramid, l, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
        glDispatchCompute((GLuint)(w + 7) / 8, (GLuint)(h + 7) / 8, 1);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    }
    s->pyr_valid = true;
    frame_put(f, RES_SHADOW_PYRAMID, s->pyramid);
}

static void run_pyramid_reuse(frame *f) { frame_put(f, RES_SHADOW_PYRAMID, f->r->shadow->pyramid); }

/* Fills out->shadow (if asked). */
static bool shadow_read_back(frame *f, mr_error *err) {
    if (!f->p->shadow.want_shadow || !frame_get(f, RES_SHADOW)) return true;
    mr_renderer *r = f->r;
    if (!mr_image_alloc(&f->out->shadow, r->w, r->h, 1, MR_PIX_F32, err)) return false;
    glGetTextureImage(frame_get(f, RES_SHADOW), 0, GL_RED, GL_FLOAT, (GLsizei)mr_image_bytes(&f->out->shadow),
                      f->out->shadow.data);
    return true;
}

const pass_desc mr_pass_desc_shadow_map = {
    .name = "shadow_map", .needed = need_map, .prepare = prepare_common, .run = run_map,
    .scene_changed = shadow_scene_changed, .destroy = mr_pass_shadow_free, .writes = RES(RES_SHADOW_MAP)};
const pass_desc mr_pass_desc_shadow_map_reuse = {
    .name = NULL, .needed = need_map_reuse, .prepare = prepare_common, .run = run_map_reuse,
    .writes = RES(RES_SHADOW_MAP)};
const pass_desc mr_pass_desc_shadow_pyramid = {
    .name = "shadow_pyramid", .needed = need_pyramid, .prepare = prepare_pyramid, .run = run_pyramid,
    .reads = RES(RES_SHADOW_MAP), .writes = RES(RES_SHADOW_PYRAMID)};
const pass_desc mr_pass_desc_shadow_pyramid_reuse = {
    .name = NULL, .needed = need_pyramid_reuse, .prepare = prepare_pyramid, .run = run_pyramid_reuse,
    .writes = RES(RES_SHADOW_PYRAMID)};
const pass_desc mr_pass_desc_shadow = {
    .name = "shadow", .needed = need_vis, .prepare = prepare_common, .run = run_vis,
    .reads = RES(RES_DEPTH) | RES(RES_NORMAL) | RES(RES_SHADOW_MAP) | RES(RES_SHADOW_PYRAMID), .reads_now = vis_reads_now,
    .writes = RES(RES_SHADOW), .read_back = shadow_read_back};
