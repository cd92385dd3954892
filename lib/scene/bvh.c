/* Frustum culling in double precision: a BVH over the world bounds of the
 * scene's nodes, and the pinhole frustum of an OpenCV camera.
 *
 * Bounds are world-space and double, so a hall 1e7 units from the origin
 * culls exactly like one at it. The tree is built top-down by splitting the
 * node centroids at the median of the widest axis (balanced, O(n log n)),
 * with a few scene nodes per leaf; culling walks it with an explicit stack
 * and accepts whole subtrees that lie inside every plane without testing
 * their leaves. */
#include "mr_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LEAF_SIZE 4

typedef struct bvh_box {
    double lo[3], hi[3];
    int32_t left;   /* inner: first child (second is left + 1); leaf: -1 */
    int32_t first;  /* leaf: first item in items[] */
    int32_t count;  /* leaf: item count; inner: items below (for stats) */
    uint32_t layers; /* bit set of the layers below */
} bvh_box;

struct mr_bvh {
    bvh_box *boxes;
    int32_t box_count;
    int32_t *items;      /* scene node indices, grouped by leaf */
    int32_t item_count;
    double *bounds;      /* 6 per scene node (lo, hi); NaN where nothing drawn */
    uint8_t *layer;      /* per scene node */
    int32_t scene_nodes;
};

bool mr_scene_node_bounds(const mr_scene *s, int32_t node, double lo[3], double hi[3]) {
    if (!s || node < 0 || node >= s->node_count) return false;
    const mr_node *n = &s->nodes[node];
    if (n->mesh_first < 0 || n->mesh_count <= 0 || n->mesh_first >= s->mesh_count) return false;
    int32_t last = n->mesh_first + n->mesh_count;
    if (last > s->mesh_count) last = s->mesh_count;
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    bool any = false;
    for (int32_t j = n->mesh_first; j < last; j++) {
        const mr_mesh *m = &s->meshes[j];
        if (m->vertex_count == 0 || m->index_count == 0) continue;
        /* |M| applied to the half extents gives the world box of the
         * transformed box without visiting 8 corners. */
        double c[3], e[3];
        for (int k = 0; k < 3; k++) {
            c[k] = m->origin[k] + 0.5 * ((double)m->bounds_min[k] + (double)m->bounds_max[k]);
            e[k] = 0.5 * ((double)m->bounds_max[k] - (double)m->bounds_min[k]);
        }
        const double *W = n->world.m;
        for (int r = 0; r < 3; r++) {
            double wc = W[r * 4 + 3], we = 0;
            for (int k = 0; k < 3; k++) {
                wc += W[r * 4 + k] * c[k];
                we += fabs(W[r * 4 + k]) * e[k];
            }
            if (wc - we < lo[r]) lo[r] = wc - we;
            if (wc + we > hi[r]) hi[r] = wc + we;
        }
        any = true;
    }
    return any;
}

static double centroid(const mr_bvh *b, int32_t node, int axis) {
    const double *bb = b->bounds + 6 * (size_t)node;
    return 0.5 * bb[axis] + 0.5 * bb[3 + axis];
}

/* Quickselect partition of items[lo..hi) around the k-th centroid. */
static void select_kth(const mr_bvh *b, int32_t *items, int32_t lo, int32_t hi, int32_t k, int axis) {
    while (hi - lo > 1) {
        double pivot = centroid(b, items[lo + (hi - lo) / 2], axis);
        int32_t i = lo, j = hi - 1;
        while (i <= j) {
            while (centroid(b, items[i], axis) < pivot) i++;
            while (centroid(b, items[j], axis) > pivot) j--;
            if (i <= j) {
                int32_t t = items[i];
                items[i] = items[j];
                items[j] = t;
                i++;
                j--;
            }
        }
        if (k <= j) hi = j + 1;
        else if (k >= i) lo = i;
        else return;
    }
}

static void fit(mr_bvh *b, bvh_box *box, int32_t first, int32_t count) {
    for (int k = 0; k < 3; k++) {
        box->lo[k] = INFINITY;
        box->hi[k] = -INFINITY;
    }
    box->layers = 0;
    for (int32_t i = first; i < first + count; i++) {
        const double *bb = b->bounds + 6 * (size_t)b->items[i];
        for (int k = 0; k < 3; k++) {
            if (bb[k] < box->lo[k]) box->lo[k] = bb[k];
            if (bb[3 + k] > box->hi[k]) box->hi[k] = bb[3 + k];
        }
        box->layers |= 1u << b->layer[b->items[i]];
    }
}

mr_bvh *mr_bvh_build(const mr_scene *s, mr_error *err) {
    mr_bvh *b = calloc(1, sizeof *b);
    if (!b || !s) {
        free(b);
        mr_fail(err, s ? MR_ERR_NOMEM : MR_ERR_INVALID, s ? "out of memory building the BVH" : "no scene");
        return NULL;
    }
    size_t n = (size_t)s->node_count;
    b->scene_nodes = s->node_count;
    b->bounds = malloc((n + 1) * 6 * sizeof *b->bounds);
    b->layer = calloc(n + 1, 1);
    b->items = malloc((n + 1) * sizeof *b->items);
    /* A binary tree over m leaves of >= 1 item has < 2m boxes. */
    b->boxes = malloc((2 * n + 2) * sizeof *b->boxes);
    if (!b->bounds || !b->layer || !b->items || !b->boxes) {
        mr_bvh_destroy(&b);
        mr_fail(err, MR_ERR_NOMEM, "out of memory building the BVH (%zu nodes)", n);
        return NULL;
    }
    for (size_t i = 0; i < n; i++) {
        double *bb = b->bounds + 6 * i;
        b->layer[i] = s->nodes[i].layer < MR_LAYER_COUNT ? s->nodes[i].layer : MR_LAYER_VISIBLE;
        if (mr_scene_node_bounds(s, (int32_t)i, bb, bb + 3) && isfinite(bb[0] + bb[1] + bb[2] + bb[3] + bb[4] + bb[5]))
            b->items[b->item_count++] = (int32_t)i;
        else
            for (int k = 0; k < 6; k++) bb[k] = NAN;
    }
    if (b->item_count == 0) return b;
    /* Build with an explicit stack of (box, first, count). */
    typedef struct { int32_t box, first, count; } job;
    job *stack = malloc((size_t)64 * sizeof *stack);
    if (!stack) {
        mr_bvh_destroy(&b);
        mr_fail(err, MR_ERR_NOMEM, "out of memory building the BVH");
        return NULL;
    }
    int sp = 0;
    b->box_count = 1;
    stack[sp++] = (job){0, 0, b->item_count};
    while (sp > 0) {
        job j = stack[--sp];
        bvh_box *box = &b->boxes[j.box];
        fit(b, box, j.first, j.count);
        box->first = j.first;
        box->count = j.count;
        box->left = -1;
        if (j.count <= LEAF_SIZE) continue;
        int axis = 0;
        double ext = -1;
        for (int k = 0; k < 3; k++) {
            double lo = INFINITY, hi = -INFINITY;
            for (int32_t i = j.first; i < j.first + j.count; i++) {
                double c = centroid(b, b->items[i], k);
                if (c < lo) lo = c;
                if (c > hi) hi = c;
            }
            if (hi - lo > ext) {
                ext = hi - lo;
                axis = k;
            }
        }
        int32_t half = j.count / 2;
        select_kth(b, b->items, j.first, j.first + j.count, j.first + half, axis);
        box->left = b->box_count;
        b->box_count += 2;
        /* Depth is about log2(n) (median splits), far below 64. */
        stack[sp++] = (job){box->left, j.first, half};
        stack[sp++] = (job){box->left + 1, j.first + half, j.count - half};
    }
    free(stack);
    return b;
}

void mr_bvh_destroy(mr_bvh **bp) {
    if (!bp || !*bp) return;
    mr_bvh *b = *bp;
    free(b->boxes);
    free(b->items);
    free(b->bounds);
    free(b->layer);
    free(b);
    *bp = NULL;
}

int32_t mr_bvh_node_count(const mr_bvh *b) { return b ? b->item_count : 0; }

const double *mr_bvh_bounds(const mr_bvh *b, int32_t node) {
    if (!b || node < 0 || node >= b->scene_nodes) return NULL;
    const double *bb = b->bounds + 6 * (size_t)node;
    return isnan(bb[0]) ? NULL : bb;
}

int mr_frustum_test_box(const mr_frustum *f, const double lo[3], const double hi[3]) {
    int result = 1;
    for (int i = 0; i < f->plane_count; i++) {
        const double *p = f->planes[i];
        double c = p[3], e = 0;
        for (int k = 0; k < 3; k++) {
            double mid = 0.5 * lo[k] + 0.5 * hi[k], half = 0.5 * hi[k] - 0.5 * lo[k];
            c += p[k] * mid;
            e += fabs(p[k]) * half;
        }
        if (c + e < 0) return -1;  /* wholly behind this plane */
        if (c - e < 0) result = 0; /* straddles it */
    }
    return result;
}

mr_frustum mr_frustum_from_camera(const mr_camera *cam, const mr_dmat4 *wfc, double near_plane, double margin_px) {
    mr_frustum f;
    memset(&f, 0, sizeof f);
    /* Pixel centres run from 0 to w-1, so the image edges are -0.5 and
     * w-0.5 (OpenCV convention); x/z at the edges, widened by the margin. */
    double x0 = (-0.5 - margin_px - cam->cx) / cam->fx, x1 = (cam->width - 0.5 + margin_px - cam->cx) / cam->fx;
    double y0 = (-0.5 - margin_px - cam->cy) / cam->fy, y1 = (cam->height - 0.5 + margin_px - cam->cy) / cam->fy;
    const double cn[5][4] = {
        {1, 0, -x0, 0},  /* x - x0 z >= 0 */
        {-1, 0, x1, 0},  /* x1 z - x >= 0 */
        {0, 1, -y0, 0},
        {0, -1, y1, 0},
        {0, 0, 1, -near_plane}, /* z >= near */
    };
    const double *M = wfc->m;
    mr_dvec3 eye = mr_v3(M[3], M[7], M[11]);
    for (int i = 0; i < 5; i++) {
        /* World normal = R n; the plane passes through eye (+ near along
         * the optical axis for the near plane). */
        double nw[3];
        for (int r = 0; r < 3; r++) nw[r] = M[r * 4 + 0] * cn[i][0] + M[r * 4 + 1] * cn[i][1] + M[r * 4 + 2] * cn[i][2];
        double len = sqrt(nw[0] * nw[0] + nw[1] * nw[1] + nw[2] * nw[2]);
        for (int k = 0; k < 3; k++) f.planes[i][k] = nw[k] / len;
        f.planes[i][3] = -(f.planes[i][0] * eye.x + f.planes[i][1] * eye.y + f.planes[i][2] * eye.z) + cn[i][3] / len;
    }
    f.plane_count = 5;
    return f;
}

int32_t mr_bvh_cull(const mr_bvh *b, const mr_frustum *f, uint32_t layer_mask, int32_t *out, mr_bvh_stats *stats) {
    mr_bvh_stats st = {0, 0};
    int32_t n = 0;
    if (b && b->item_count > 0) {
        int32_t stack[128];
        bool inside_stack[128];
        int sp = 0;
        stack[sp] = 0;
        inside_stack[sp++] = f == NULL;
        while (sp > 0) {
            sp--;
            const bvh_box *box = &b->boxes[stack[sp]];
            bool inside = inside_stack[sp];
            if (!(box->layers & layer_mask)) continue;
            if (!inside) {
                st.boxes_tested++;
                int t = mr_frustum_test_box(f, box->lo, box->hi);
                if (t < 0) continue;
                inside = t > 0;
            }
            if (box->left < 0) {
                for (int32_t i = box->first; i < box->first + box->count; i++) {
                    int32_t node = b->items[i];
                    if (!(layer_mask & (1u << b->layer[node]))) continue;
                    if (!inside) {
                        const double *bb = b->bounds + 6 * (size_t)node;
                        st.boxes_tested++;
                        if (mr_frustum_test_box(f, bb, bb + 3) < 0) continue;
                    }
                    out[n++] = node;
                }
            } else if (sp + 2 <= 128) { /* depth is ~log2(n / LEAF_SIZE) (median splits): never full */
                stack[sp] = box->left + 1;
                inside_stack[sp++] = inside;
                stack[sp] = box->left;
                inside_stack[sp++] = inside;
            }
        }
    }
    st.nodes_visible = (uint32_t)n;
    if (stats) *stats = st;
    return n;
}
