/* A topic's viewpoint as a picture of the scene: its camera as a view (a
 * far, narrow perspective camera stands in for an orthogonal one), and its
 * visibility, colouring, selection and clipping planes written into the
 * scene itself (nodes emptied, meshes copied with a material of their own,
 * straddling parts cut on the CPU), so every pass of the renderer draws it
 * without knowing about BCF. */
#include "export_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* BCF (Z up) -> glTF (Y up): the inverse of mr_bcf_from_gltf. */
static mr_dvec3 gltf_of(const double b[3]) { return mr_v3(b[0], b[2], -b[1]); }

static bool finite3(const double v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

/* The depth extent of the scene's bounds along unit direction d (scene units). */
static double extent_along(const mr_scene *s, mr_dvec3 d) {
    double lo = INFINITY, hi = -INFINITY;
    for (int c = 0; c < 8; c++) {
        mr_dvec3 p = mr_v3(c & 1 ? s->bounds_max[0] : s->bounds_min[0], c & 2 ? s->bounds_max[1] : s->bounds_min[1],
                           c & 4 ? s->bounds_max[2] : s->bounds_min[2]);
        double t = mr_v3_dot(p, d);
        lo = fmin(lo, t);
        hi = fmax(hi, t);
    }
    return isfinite(hi - lo) ? hi - lo : 0;
}

bool mr_bcf_viewpoint_view(const mr_bcf_viewpoint *vp, const mr_scene *s, const mr_bcf_view_params *p, mr_view *out,
                           mr_error *err) {
    memset(out, 0, sizeof *out);
    const mr_bcf_camera *c = &vp->camera;
    if (vp->camera_kind == MR_BCF_CAMERA_NONE) return mr_fail(err, MR_ERR_INVALID, "the viewpoint has no camera");
    if (!finite3(c->view_point) || !finite3(c->direction) || !finite3(c->up))
        return mr_fail(err, MR_ERR_INVALID, "the viewpoint's camera is not finite");
    double unit = p && p->unit_m > 0 ? p->unit_m : 1.0;
    mr_dvec3 d = mr_v3_normalize(gltf_of(c->direction)), u = mr_v3_normalize(gltf_of(c->up));
    mr_dvec3 x = mr_v3_cross(d, u);
    if (!(mr_v3_len(d) > 0.5) || !(mr_v3_len(x) > 1e-6))
        return mr_fail(err, MR_ERR_INVALID, "the viewpoint's camera direction and up vector are parallel or zero");
    mr_dvec3 eye = mr_v3_scale(gltf_of(c->view_point), 1.0 / unit);

    int w = p ? p->width : 0, h = p ? p->height : 0;
    double aspect = c->aspect > 0 ? c->aspect : 4.0 / 3.0;
    if (w <= 0 && h <= 0) w = MR_BCF_VIEW_DEFAULT_WIDTH;
    if (w <= 0) w = (int)lround(h * aspect);
    if (h <= 0) h = (int)lround(w / aspect);
    if (w < 1) w = 1;
    if (h < 1) h = 1;
    double f;
    if (vp->camera_kind == MR_BCF_CAMERA_PERSPECTIVE) {
        /* 3.0 gives the vertical angle; 2.x, as mrcheck writes it, the
         * horizontal one. */
        double half = tan(c->fov_deg * M_PI / 360.0);
        if (!(half > 0) || !isfinite(half)) return mr_fail(err, MR_ERR_INVALID, "the viewpoint's field of view is unusable");
        f = (p && p->fov_vertical ? h : w) * 0.5 / half;
    } else {
        /* Orthogonal: ViewToWorldScale metres over the image height at
         * every depth. A pinhole at MR_BCF_ORTHO_DISTANCE times the larger
         * of that height and the scene's depth from the scene's middle
         * depth, with that scale there, is within 1 / (2 *
         * MR_BCF_ORTHO_DISTANCE) of it across the scene. */
        double height = vp->view_to_world_scale / unit;
        if (!(height > 0) || !isfinite(height)) return mr_fail(err, MR_ERR_INVALID, "the viewpoint's ViewToWorldScale is unusable");
        double mid = 0, depth = 0;
        if (s && s->node_count > 0 && isfinite(s->bounds_max[0] - s->bounds_min[0])) {
            mr_dvec3 centre = mr_v3(0.5 * (s->bounds_min[0] + s->bounds_max[0]), 0.5 * (s->bounds_min[1] + s->bounds_max[1]),
                                    0.5 * (s->bounds_min[2] + s->bounds_max[2]));
            mid = mr_v3_dot(mr_v3_sub(centre, eye), d);
            depth = extent_along(s, d);
        }
        double back = MR_BCF_ORTHO_DISTANCE * fmax(height, depth);
        eye = mr_v3_add(eye, mr_v3_scale(d, mid - back));
        f = h * back / height;
    }
    if (!(f > 0) || !isfinite(f)) return mr_fail(err, MR_ERR_INVALID, "the viewpoint's camera is unusable");
    out->camera.width = w;
    out->camera.height = h;
    out->camera.fx = out->camera.fy = f;
    out->camera.cx = (w - 1) * 0.5;
    out->camera.cy = (h - 1) * 0.5;
    out->world_from_camera = mr_m4_look_at_cv(eye, mr_v3_add(eye, d), u);
    if (!mr_m4_is_finite(&out->world_from_camera)) return mr_fail(err, MR_ERR_INVALID, "the viewpoint's camera is not finite");
    return true;
}

/* ------------------------------------------------ components to nodes */

typedef struct key {
    const char *text;
    int list;      /* -1 selection, -2 exceptions, k >= 0 colouring k */
    bool *used;
} key;

typedef struct keyset {
    key *guids, *names;
    int guid_count, name_count;
    bool *used;     /* one per component reference */
    int refs;
} keyset;

static int key_cmp(const void *a, const void *b) {
    const key *x = a, *y = b;
    int c = strcmp(x->text, y->text);
    return c ? c : (x->list > y->list) - (x->list < y->list);
}

static bool keyset_build(keyset *ks, const mr_bcf_viewpoint *vp) {
    memset(ks, 0, sizeof *ks);
    int n = vp->selection_count + vp->exception_count;
    for (int k = 0; k < vp->coloring_count; k++) n += vp->colorings[k].count;
    ks->refs = n;
    ks->guids = calloc((size_t)n + 1, sizeof *ks->guids);
    ks->names = calloc((size_t)n + 1, sizeof *ks->names);
    ks->used = calloc((size_t)n + 1, sizeof *ks->used);
    if (!ks->guids || !ks->names || !ks->used) return false;
    int r = 0;
    for (int list = -2; list < vp->coloring_count; list++) {
        const mr_bcf_component *c = list == -1 ? vp->selection : list == -2 ? vp->exceptions : vp->colorings[list].items;
        int cn = list == -1 ? vp->selection_count : list == -2 ? vp->exception_count : vp->colorings[list].count;
        for (int i = 0; i < cn; i++, r++) {
            if (c[i].ifc_guid[0]) ks->guids[ks->guid_count++] = (key){c[i].ifc_guid, list, &ks->used[r]};
            if (c[i].authoring_id[0]) ks->names[ks->name_count++] = (key){c[i].authoring_id, list, &ks->used[r]};
        }
    }
    qsort(ks->guids, (size_t)ks->guid_count, sizeof *ks->guids, key_cmp);
    qsort(ks->names, (size_t)ks->name_count, sizeof *ks->names, key_cmp);
    return true;
}

static void keyset_free(keyset *ks) {
    free(ks->guids);
    free(ks->names);
    free(ks->used);
    memset(ks, 0, sizeof *ks);
}

/* What the viewpoint says about one node. */
typedef struct node_state {
    bool in_exceptions, selected;
    int colouring;   /* -1 none; the last colouring that names it wins */
} node_state;

/* Every key equal to text (all lists) applied to st. */
static void apply_matches(const key *keys, int n, const char *text, node_state *st) {
    if (!text || !text[0] || n == 0) return;
    /* lower bound */
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (strcmp(keys[mid].text, text) < 0) lo = mid + 1;
        else hi = mid;
    }
    for (int i = lo; i < n && strcmp(keys[i].text, text) == 0; i++) {
        *keys[i].used = true;
        if (keys[i].list == -1) st->selected = true;
        else if (keys[i].list == -2) st->in_exceptions = true;
        else if (keys[i].list > st->colouring) st->colouring = keys[i].list;
    }
}

static node_state state_of(const mr_scene *s, const keyset *ks, int32_t n) {
    node_state st = {false, false, -1};
    const mr_element *el = mr_scene_element_of(s, n);
    if (el) apply_matches(ks->guids, ks->guid_count, el->guid, &st);
    /* AuthoringToolId: the node's name or an ancestor's (the element's node
     * is named by the product, its meshes' nodes may be below it). */
    for (int32_t a = n, depth = 0; a >= 0 && a < s->node_count && depth < 256; a = s->nodes[a].parent, depth++)
        apply_matches(ks->names, ks->name_count, s->nodes[a].name, &st);
    return st;
}

/* ------------------------------------------------------- scene edits */

static float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f); }

/* A material for colour (linear RGB), memoised over the run. */
typedef struct mat_memo {
    float rgb[3];
    int32_t id;
} mat_memo;

static int32_t material_for(mr_scene *s, const float rgb[3], mat_memo **memo, int *n) {
    for (int i = 0; i < *n; i++)
        if (memcmp((*memo)[i].rgb, rgb, sizeof (*memo)[i].rgb) == 0) return (*memo)[i].id;
    mr_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "bcf %.3f %.3f %.3f", rgb[0], rgb[1], rgb[2]);
    memcpy(m.base_color, rgb, 3 * sizeof(float));
    m.base_color[3] = 1;
    m.base_color_texture = -1;
    int32_t id = mr_scene_add_material(s, &m);
    if (id < 0) return -1;
    mat_memo *g = realloc(*memo, (size_t)(*n + 1) * sizeof *g);
    if (!g) return -1;
    *memo = g;
    g[*n].id = id;
    memcpy(g[*n].rgb, rgb, sizeof g[*n].rgb);
    (*n)++;
    return id;
}

static void *dup_array(const void *p, size_t bytes) {
    if (!p) return NULL;
    void *q = malloc(bytes ? bytes : 1);
    if (q) memcpy(q, p, bytes);
    return q;
}

/* A copy of mesh mi drawn with material mat; its index or -1. */
static int32_t copy_mesh(mr_scene *s, int32_t mi, int32_t mat, mr_error *err) {
    mr_mesh src = s->meshes[mi], m = src;
    size_t v = src.vertex_count;
    m.positions = dup_array(src.positions, v * 3 * sizeof(float));
    m.normals = dup_array(src.normals, v * 3 * sizeof(float));
    m.uvs = dup_array(src.uvs, v * 2 * sizeof(float));
    m.indices = dup_array(src.indices, src.index_count * sizeof(uint32_t));
    m.material = mat;
    if (!m.positions || !m.indices || (src.normals && !m.normals) || (src.uvs && !m.uvs)) {
        free(m.positions), free(m.normals), free(m.uvs), free(m.indices);
        mr_fail(err, MR_ERR_NOMEM, "out of memory copying a mesh");
        return -1;
    }
    int32_t id = mr_scene_add_mesh(s, &m, err);
    if (id < 0) free(m.positions), free(m.normals), free(m.uvs), free(m.indices);
    return id;
}

/* A polygon vertex while clipping: world position, normal, uv. */
typedef struct cvert {
    double p[3];
    double n[3];
    double uv[2];
} cvert;

#define MAX_POLY (3 + 2 * 16)

/* Clips poly (in place, via tmp) against plane (point q, normal nrm
 * pointing to the side cut away). */
static int clip_poly(cvert *poly, int n, cvert *tmp, const double q[3], const double nrm[3]) {
    int m = 0;
    for (int i = 0; i < n; i++) {
        const cvert *a = &poly[i], *b = &poly[(i + 1) % n];
        double da = (a->p[0] - q[0]) * nrm[0] + (a->p[1] - q[1]) * nrm[1] + (a->p[2] - q[2]) * nrm[2];
        double db = (b->p[0] - q[0]) * nrm[0] + (b->p[1] - q[1]) * nrm[1] + (b->p[2] - q[2]) * nrm[2];
        if (da <= 0 && m < MAX_POLY) tmp[m++] = *a;
        if ((da <= 0) != (db <= 0) && m < MAX_POLY) {
            double t = da / (da - db);
            cvert c;
            for (int k = 0; k < 3; k++) c.p[k] = a->p[k] + t * (b->p[k] - a->p[k]);
            for (int k = 0; k < 3; k++) c.n[k] = a->n[k] + t * (b->n[k] - a->n[k]);
            for (int k = 0; k < 2; k++) c.uv[k] = a->uv[k] + t * (b->uv[k] - a->uv[k]);
            tmp[m++] = c;
        }
    }
    memcpy(poly, tmp, (size_t)m * sizeof *poly);
    return m;
}

typedef struct growbuf {
    float *pos, *nrm, *uv;
    uint32_t count, cap;
} growbuf;

static bool grow_push(growbuf *g, const cvert *v, const double origin[3], bool uvs) {
    if (g->count == g->cap) {
        uint32_t nc = g->cap ? g->cap * 2 : 192;
        float *p = realloc(g->pos, (size_t)nc * 3 * sizeof(float));
        if (p) g->pos = p;
        float *n = realloc(g->nrm, (size_t)nc * 3 * sizeof(float));
        if (n) g->nrm = n;
        float *u = uvs ? realloc(g->uv, (size_t)nc * 2 * sizeof(float)) : g->uv;
        if (u) g->uv = u;
        if (!p || !n || (uvs && !u)) return false;
        g->cap = nc;
    }
    uint32_t i = g->count++;
    double len = sqrt(v->n[0] * v->n[0] + v->n[1] * v->n[1] + v->n[2] * v->n[2]);
    for (int k = 0; k < 3; k++) {
        g->pos[i * 3 + k] = (float)(v->p[k] - origin[k]);
        g->nrm[i * 3 + k] = (float)(len > 0 ? v->n[k] / len : (k == 1));
    }
    if (uvs) g->uv[i * 2] = (float)v->uv[0], g->uv[i * 2 + 1] = (float)v->uv[1];
    return true;
}

/* The part of mesh mi under world transform w that lies on the kept side of
 * every plane, in world coordinates (around origin), as a new mesh drawn
 * with material mat. *id -1 when nothing is left. */
static bool clip_mesh(mr_scene *s, int32_t mi, const mr_dmat4 *w, const mr_bcf_plane *planes, int np, int32_t mat,
                      const double origin[3], int32_t *id, mr_error *err) {
    *id = -1;
    const mr_mesh *m = &s->meshes[mi];
    const double *a = w->m;
    /* Normals by the cofactor matrix (det times the inverse transpose). */
    double C[9] = {a[5] * a[10] - a[6] * a[9], a[6] * a[8] - a[4] * a[10], a[4] * a[9] - a[5] * a[8],
                   a[2] * a[9] - a[1] * a[10], a[0] * a[10] - a[2] * a[8], a[1] * a[8] - a[0] * a[9],
                   a[1] * a[6] - a[2] * a[5], a[2] * a[4] - a[0] * a[6], a[0] * a[5] - a[1] * a[4]};
    double det = a[0] * C[0] + a[1] * C[1] + a[2] * C[2];
    double sgn = det < 0 ? -1 : 1;
    bool uvs = m->uvs != NULL;
    growbuf g = {0};
    bool ok = true;
    for (uint32_t t = 0; ok && t + 2 < m->index_count; t += 3) {
        cvert poly[MAX_POLY], tmp[MAX_POLY];
        for (int k = 0; k < 3; k++) {
            uint32_t vi = m->indices[t + k];
            const float *p = &m->positions[vi * 3];
            mr_dvec3 wp = mr_m4_point(w, mr_v3(m->origin[0] + p[0], m->origin[1] + p[1], m->origin[2] + p[2]));
            poly[k].p[0] = wp.x, poly[k].p[1] = wp.y, poly[k].p[2] = wp.z;
            const float *n = m->normals ? &m->normals[vi * 3] : NULL;
            for (int r = 0; r < 3; r++)
                poly[k].n[r] = n ? sgn * (C[r * 3] * n[0] + C[r * 3 + 1] * n[1] + C[r * 3 + 2] * n[2]) : 0;
            poly[k].uv[0] = uvs ? m->uvs[vi * 2] : 0;
            poly[k].uv[1] = uvs ? m->uvs[vi * 2 + 1] : 0;
        }
        int n = 3;
        for (int pl = 0; pl < np && n >= 3; pl++) n = clip_poly(poly, n, tmp, planes[pl].location, planes[pl].direction);
        for (int k = 1; ok && k + 1 < n; k++)
            ok = grow_push(&g, &poly[0], origin, uvs) && grow_push(&g, &poly[k], origin, uvs) &&
                 grow_push(&g, &poly[k + 1], origin, uvs);
    }
    if (ok && g.count == 0) {
        free(g.pos), free(g.nrm), free(g.uv);
        return true;
    }
    mr_mesh out;
    memset(&out, 0, sizeof out);
    snprintf(out.name, sizeof out.name, "%.50s clipped", m->name);
    memcpy(out.origin, origin, sizeof out.origin);
    out.positions = g.pos;
    out.normals = g.nrm;
    out.uvs = uvs ? g.uv : NULL;
    if (!uvs) free(g.uv);
    out.vertex_count = g.count;
    out.index_count = g.count;
    out.indices = ok ? malloc((size_t)g.count * sizeof(uint32_t)) : NULL;
    out.material = mat;
    if (!out.indices) {
        free(out.positions), free(out.normals), free(out.uvs);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory clipping a mesh");
    }
    for (uint32_t i = 0; i < g.count; i++) out.indices[i] = i;
    *id = mr_scene_add_mesh(s, &out, err);
    if (*id < 0) {
        free(out.positions), free(out.normals), free(out.uvs), free(out.indices);
        return false;
    }
    return true;
}

/* World bounds of node n's meshes against a plane: -1 all kept, +1 all cut
 * away, 0 straddling. */
static int plane_side(const mr_scene *s, int32_t n, const mr_bcf_plane *pl) {
    const mr_node *nd = &s->nodes[n];
    bool any_in = false, any_out = false;
    for (int32_t k = 0; k < nd->mesh_count; k++) {
        const mr_mesh *m = &s->meshes[nd->mesh_first + k];
        for (int c = 0; c < 8; c++) {
            mr_dvec3 p = mr_v3(m->origin[0] + (c & 1 ? m->bounds_max[0] : m->bounds_min[0]),
                               m->origin[1] + (c & 2 ? m->bounds_max[1] : m->bounds_min[1]),
                               m->origin[2] + (c & 4 ? m->bounds_max[2] : m->bounds_min[2]));
            p = mr_m4_point(&nd->world, p);
            double d = (p.x - pl->location[0]) * pl->direction[0] + (p.y - pl->location[1]) * pl->direction[1] +
                       (p.z - pl->location[2]) * pl->direction[2];
            if (d > 0) any_out = true;
            else any_in = true;
        }
    }
    return any_in && any_out ? 0 : any_out ? 1 : -1;
}

static bool class_is(const mr_element *el, const char *cls) {
    return el && strncasecmp(el->ifc_class, cls, strlen(cls)) == 0;
}

bool mr_bcf_viewpoint_apply(mr_scene *s, const mr_bcf_viewpoint *vp, const mr_bcf_view_params *p,
                            mr_bcf_view_info *info, mr_error *err) {
    mr_bcf_view_info dummy;
    if (!info) info = &dummy;
    memset(info, 0, sizeof *info);
    double unit = p && p->unit_m > 0 ? p->unit_m : 1.0;
    /* The planes in scene units and axes. */
    mr_bcf_plane *planes = calloc((size_t)vp->clip_count + 1, sizeof *planes);
    if (!planes) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int np = 0;
    for (int i = 0; i < vp->clip_count; i++) {
        mr_dvec3 q = mr_v3_scale(gltf_of(vp->clips[i].location), 1.0 / unit);
        mr_dvec3 d = mr_v3_normalize(gltf_of(vp->clips[i].direction));
        if (!finite3(vp->clips[i].location) || !(mr_v3_len(d) > 0.5)) {
            info->bad_planes++;
            continue;
        }
        planes[np].location[0] = q.x, planes[np].location[1] = q.y, planes[np].location[2] = q.z;
        planes[np].direction[0] = d.x, planes[np].direction[1] = d.y, planes[np].direction[2] = d.z;
        np++;
    }
    keyset ks;
    mat_memo *memo = NULL;
    int memo_n = 0;
    bool ok = keyset_build(&ks, vp);
    if (!ok) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    float hl[3] = {MR_BCF_HIGHLIGHT_R, MR_BCF_HIGHLIGHT_G, MR_BCF_HIGHLIGHT_B};
    int32_t nodes = s->node_count;
    for (int32_t n = 0; ok && n < nodes; n++) {
        if (s->nodes[n].mesh_count <= 0 || s->nodes[n].mesh_first < 0) continue;
        node_state st = state_of(s, &ks, n);
        const mr_element *el = mr_scene_element_of(s, n);
        bool visible = vp->default_visibility != st.in_exceptions;
        if ((!vp->spaces_visible && class_is(el, "IfcSpace")) || (!vp->openings_visible && class_is(el, "IfcOpening")))
            visible = false;
        int side = -1;
        for (int k = 0; visible && k < np; k++) {
            int sd = plane_side(s, n, &planes[k]);
            if (sd > 0) visible = false;
            else if (sd == 0) side = 0;
        }
        if (!visible) {
            s->nodes[n].mesh_first = -1;
            s->nodes[n].mesh_count = 0;
            info->hidden_nodes++;
            continue;
        }
        bool recolour = st.colouring >= 0 || st.selected;
        info->coloured_nodes += st.colouring >= 0;
        info->selected_nodes += st.selected;
        if (!recolour && side < 0) continue;
        int32_t first = s->nodes[n].mesh_first, count = s->nodes[n].mesh_count, new_first = -1, new_count = 0;
        /* The first mesh's centre in the world: the clipped meshes' origin,
         * so their float positions stay small at any offset. */
        mr_dmat4 world = s->nodes[n].world;
        const double *mo = s->meshes[first].origin;
        mr_dvec3 oc = mr_m4_point(&world, mr_v3(mo[0], mo[1], mo[2]));
        double origin[3] = {oc.x, oc.y, oc.z};
        for (int32_t k = 0; ok && k < count; k++) {
            int32_t mi = first + k, mat = s->meshes[mi].material;
            if (recolour) {
                float rgb[3] = {0.7f, 0.7f, 0.7f};
                if (mat >= 0 && mat < s->material_count) memcpy(rgb, s->materials[mat].base_color, sizeof rgb);
                if (st.colouring >= 0) {
                    uint32_t c = vp->colorings[st.colouring].argb;
                    rgb[0] = srgb_to_linear((float)((c >> 16) & 0xff) / 255.0f);
                    rgb[1] = srgb_to_linear((float)((c >> 8) & 0xff) / 255.0f);
                    rgb[2] = srgb_to_linear((float)(c & 0xff) / 255.0f);
                }
                if (st.selected)
                    for (int i = 0; i < 3; i++) rgb[i] += MR_BCF_HIGHLIGHT_MIX * (hl[i] - rgb[i]);
                mat = material_for(s, rgb, &memo, &memo_n);
                if (mat < 0) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
            }
            int32_t id = -1;
            if (!ok) break;
            if (side == 0) ok = clip_mesh(s, mi, &world, planes, np, mat, origin, &id, err);
            else if ((id = copy_mesh(s, mi, mat, err)) < 0) ok = false;
            if (ok && id >= 0) {
                if (new_first < 0) new_first = id;
                new_count++;
            }
        }
        if (!ok) break;
        if (side == 0) {
            s->nodes[n].world = mr_m4_identity();
            info->clipped_nodes++;
        }
        s->nodes[n].mesh_first = new_count ? new_first : -1;
        s->nodes[n].mesh_count = new_count;
        if (!new_count) info->hidden_nodes++;
    }
    for (int i = 0; ok && i < ks.refs; i++) info->unresolved += !ks.used[i];
    keyset_free(&ks);
    free(memo);
    free(planes);
    /* No longer the file's scene: nothing cached beside the file is read or
     * written for it. */
    s->source[0] = '\0';
    s->source_key[0] = '\0';
    mr_scene_update_bounds(s);
    return ok;
}

bool mr_bcf_topic_view(mr_scene *s, const mr_bcf *b, const mr_bcf_topic *t, const mr_bcf_view_params *p, mr_view *view,
                       mr_bcf_view_info *info, mr_error *err) {
    int vi = -1;
    for (int i = 0; i < t->viewpoint_count && vi < 0; i++)
        if (t->viewpoints[i].camera_kind != MR_BCF_CAMERA_NONE) vi = i;
    if (vi < 0) return mr_fail(err, MR_ERR_INVALID, "topic %s has no viewpoint with a camera", t->guid);
    mr_bcf_view_params q = p ? *p : (mr_bcf_view_params)MR_BCF_VIEW_DEFAULTS;
    q.fov_vertical = strncmp(b->version, "3.", 2) == 0;
    const mr_bcf_viewpoint *vp = &t->viewpoints[vi];
    /* The camera first (the orthogonal one measures the scene as given). */
    if (!mr_bcf_viewpoint_view(vp, s, &q, view, err) || !mr_bcf_viewpoint_apply(s, vp, &q, info, err)) return false;
    if (info) info->viewpoint = vi;
    return true;
}

bool mr_bcf_render_setup(const char *bcf_path, const char *topic, mr_scene *s, const mr_bcf_view_params *p,
                         mr_view *view, mr_error *err) {
    mr_bcf b;
    if (!mr_bcf_read(bcf_path, &b, err)) return false;
    for (int i = 0; i < b.warning_count; i++) mr_log(MR_LOG_WARN, "%s: %s", bcf_path, b.warnings[i]);
    mr_bcf_topic *t = mr_bcf_find_topic(&b, topic, err);
    mr_bcf_view_info info;
    bool ok = t && mr_bcf_topic_view(s, &b, t, p, view, &info, err);
    if (ok) {
        const mr_bcf_viewpoint *vp = &t->viewpoints[info.viewpoint];
        mr_log(MR_LOG_INFO,
               "BCF topic %s, viewpoint %d (%s camera): %d nodes hidden, %d coloured, %d selected, %d clipped; "
               "%d clipping planes",
               t->guid, info.viewpoint + 1, vp->camera_kind == MR_BCF_CAMERA_ORTHOGONAL ? "orthogonal" : "perspective",
               info.hidden_nodes, info.coloured_nodes, info.selected_nodes, info.clipped_nodes, vp->clip_count);
        if (info.unresolved)
            mr_log(MR_LOG_WARN, "BCF topic %s: %d component references name nothing in the scene", t->guid,
                   info.unresolved);
        if (info.bad_planes)
            mr_log(MR_LOG_WARN, "BCF topic %s: %d clipping planes without a usable normal, ignored", t->guid,
                   info.bad_planes);
    }
    mr_bcf_free(&b);
    return ok;
}
