/* The marker map from photos: pairwise relative tag poses, the initial
 * pose graph (spanning tree by shared photos, rotation averaging), the
 * gauge (a fixed tag or control points), then the global bundle adjustment
 * in map_ba.cc. The pipeline is described in mr_track.h. */
#include "track_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEG (180.0 / M_PI)
/* Pairwise relative poses within this angle of the pair's medoid count
 * for its mean: IPPE's mirror branch is typically tens of degrees away. */
#define PAIR_INLIER_DEG 5.0
/* A sighting whose corners miss the photo's initial pose by more than this
 * (px RMS) is a misdetection or a wrong IPPE branch of a lone tag: left
 * out of the adjustment rather than merely down-weighted. */
#define OBS_REJECT_PX 100.0
/* After an adjustment, sightings whose corners miss by more than this many
 * estimated corner sigmas (and at least OBS_REJECT_MIN_PX) are left out
 * and the adjustment runs again. */
#define OBS_REJECT_SIGMA 6.0
#define OBS_REJECT_MIN_PX 3.0

typedef struct obs_t {
    int tag, photo;          /* tag index, photo index */
    double px[8];            /* pixels */
    double norm[8];          /* undistorted, normalised */
    mr_dmat4 cft[2];         /* camera_from_tag, IPPE solutions, best first */
    int ns;
    bool use;
} obs_t;

typedef struct pair_t {
    int a, b;                /* tag indices, a < b */
    int n;                   /* candidates: each IPPE branch of a with each of b */
    mr_dmat4 rel[4];         /* a_from_b, rel[0] from both best branches */
} pair_t;

typedef struct edge_t {
    int a, b, count;
    mr_dmat4 rel;            /* a_from_b, robust mean */
} edge_t;

static mr_dmat4 m4_rt(const double R[9], const double t[3]) {
    mr_dmat4 m = mr_m4_identity();
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) m.m[4 * r + c] = R[3 * r + c];
        m.m[4 * r + 3] = t[r];
    }
    return m;
}

static void m4_R(const mr_dmat4 *m, double R[9]) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) R[3 * r + c] = m->m[4 * r + c];
}

static int cmp_int(const void *a, const void *b) {
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

static int cmp_pair(const void *pa, const void *pb) {
    const pair_t *a = pa, *b = pb;
    if (a->a != b->a) return (a->a > b->a) - (a->a < b->a);
    return (a->b > b->b) - (a->b < b->b);
}

static int cmp_edge_count(const void *pa, const void *pb) {
    const edge_t *a = pa, *b = pb;
    if (a->count != b->count) return (a->count < b->count) - (a->count > b->count); /* descending */
    if (a->a != b->a) return (a->a > b->a) - (a->a < b->a);
    return (a->b > b->b) - (a->b < b->b);
}

static int uf_find(int *p, int i) {
    while (p[i] != i) i = p[i] = p[p[i]];
    return i;
}

/* The tag-frame point of a control point (centre or a corner). */
static mr_dvec3 tag_point(double size, int corner) {
    if (corner < 0 || corner > 3) return mr_v3(0, 0, 0);
    mr_dvec3 c[4];
    mr_marker_corners_tag(size, c);
    return c[corner];
}

/* Sum of squared normalised reprojection errors of o's corners under
 * camera_from_world cfw and the tag's world_from_tag wft. */
static double obs_sq(const obs_t *o, double size, const mr_dmat4 *cfw, const mr_dmat4 *wft) {
    mr_dvec3 c[4];
    mr_marker_corners_tag(size, c);
    mr_dmat4 cft = mr_m4_mul(cfw, wft);
    double s = 0;
    for (int k = 0; k < 4; k++) {
        mr_dvec3 p = mr_m4_point(&cft, c[k]);
        if (!(p.z > 1e-12)) return INFINITY;
        double dx = p.x / p.z - o->norm[2 * k], dy = p.y / p.z - o->norm[2 * k + 1];
        s += dx * dx + dy * dy;
    }
    return s;
}

/* Pixel RMS of o's corners with the full camera model. */
static double obs_rms_px(const mr_camera *cam, const obs_t *o, double size, const mr_dmat4 *wfc, const mr_dmat4 *wft) {
    mr_dvec3 c[4];
    mr_marker_corners_tag(size, c);
    double s = 0;
    for (int k = 0; k < 4; k++) {
        double u, v;
        if (!mr_project_point(cam, wfc, mr_m4_point(wft, c[k]), &u, &v)) return INFINITY;
        s += (u - o->px[2 * k]) * (u - o->px[2 * k]) + (v - o->px[2 * k + 1]) * (v - o->px[2 * k + 1]);
    }
    return sqrt(s / 8);
}

/* Robust mean of the relative poses of one pair from n photos, each
 * with up to 4 candidates (the IPPE branches of both tags): the medoid
 * candidate, scored by how near each photo's closest candidate comes
 * (capped, so one bad photo cannot dominate); then each photo's candidate
 * nearest it, and the chordal rotation mean and translation mean of those
 * within PAIR_INLIER_DEG. Returns the inlier count. */
static int robust_mean(const pair_t *pr, int n, mr_dmat4 *out) {
    int med_i = 0, med_k = 0;
    double best = INFINITY;
    /* O(n^2) in the photos of one pair; beyond 64 a stride keeps it cheap. */
    int stride = n > 64 ? n / 64 : 1;
    for (int i = 0; i < n; i++)
        for (int k = 0; k < pr[i].n; k++) {
            double sc = 0;
            for (int q = 0; q < n; q += stride) {
                double m = 45.0;
                for (int c = 0; c < pr[q].n; c++) m = fmin(m, mr_pose_angle_deg(&pr[i].rel[k], &pr[q].rel[c]));
                sc += m;
            }
            /* Ties (a pair seen once): the best branches, candidate 0. */
            if (sc < best - 1e-9) best = sc, med_i = i, med_k = k;
        }
    const mr_dmat4 *med = &pr[med_i].rel[med_k];
    double *R = malloc((size_t)n * 9 * sizeof *R), *w = malloc((size_t)n * sizeof *w);
    if (!R || !w) {
        free(R);
        free(w);
        *out = *med;
        return 1;
    }
    double t[3] = {0, 0, 0};
    int m = 0;
    for (int i = 0; i < n; i++) {
        int bc = 0;
        double ba = INFINITY;
        for (int c = 0; c < pr[i].n; c++) {
            double a = mr_pose_angle_deg(&pr[i].rel[c], med);
            if (a < ba) ba = a, bc = c;
        }
        if (ba > PAIR_INLIER_DEG) continue;
        m4_R(&pr[i].rel[bc], &R[9 * m]);
        w[m] = 1;
        for (int a = 0; a < 3; a++) t[a] += pr[i].rel[bc].m[4 * a + 3];
        m++;
    }
    double Rm[9];
    mr_ba_rotation_mean(R, w, m, Rm);
    for (int a = 0; a < 3; a++) t[a] /= m;
    *out = m4_rt(Rm, t);
    free(R);
    free(w);
    return m;
}

void mr_map_result_free(mr_map_result *r) {
    if (!r) return;
    free(r->tags);
    free(r->unconnected);
    free(r->unsized);
    free(r->controls);
    memset(r, 0, sizeof *r);
}

static void progress(const mr_map_params *p, const char *stage, double f) {
    if (p->progress) p->progress(p->progress_user, stage, f);
}

typedef struct ctx_t {
    const mr_camera *cam;
    const mr_map_params *p;
    int ntags;
    int *ids;
    double *size;
    obs_t *obs;
    int nobs;
} ctx_t;

/* Pairwise relative poses from every photo that sees both tags (used
 * sightings only, if asked), sorted by pair, and one robust mean per pair
 * into edges. pairs and edges hold the count of all pairs. Returns the
 * number of edges. */
static int build_edges(const ctx_t *c, bool used_only, pair_t *pairs, edge_t *edges) {
    size_t npair = 0;
    for (int a = 0; a < c->nobs;) {
        int b = a;
        while (b < c->nobs && c->obs[b].photo == c->obs[a].photo) b++;
        for (int x = a; x < b; x++)
            for (int y = x + 1; y < b; y++) {
                const obs_t *ox = &c->obs[x], *oy = &c->obs[y];
                if (used_only && (!ox->use || !oy->use)) continue;
                const obs_t *lo = ox->tag < oy->tag ? ox : oy, *hi = ox->tag < oy->tag ? oy : ox;
                pairs[npair].a = lo->tag;
                pairs[npair].b = hi->tag;
                pairs[npair].n = 0;
                for (int sl = 0; sl < lo->ns; sl++) {
                    mr_dmat4 tfc = mr_m4_invert_rigid(&lo->cft[sl]);
                    for (int sh = 0; sh < hi->ns; sh++)
                        pairs[npair].rel[pairs[npair].n++] = mr_m4_mul(&tfc, &hi->cft[sh]);
                }
                npair++;
            }
        a = b;
    }
    qsort(pairs, npair, sizeof *pairs, cmp_pair);
    int ne = 0;
    for (size_t i = 0; i < npair;) {
        size_t e = i;
        while (e < npair && pairs[e].a == pairs[i].a && pairs[e].b == pairs[i].b) e++;
        edges[ne].a = pairs[i].a;
        edges[ne].b = pairs[i].b;
        edges[ne].count = robust_mean(&pairs[i], (int)(e - i), &edges[ne].rel);
        ne++;
        i = e;
    }
    return ne;
}

/* The initial map again, one tag at a time by view count (Prim's order:
 * next the unplaced tag sharing the most photos with placed ones), each
 * from the robust mean of its poses through every such photo. A photo
 * whose pose for the tag disagrees with the others (a wrong id, a wrong
 * IPPE branch of both tags) loses that sighting: it does not reach the
 * rotation averaging or the adjustment. in_part: the tags to place;
 * rft[root] is the identity. Returns the number of sightings dropped. */
static int place_tags(ctx_t *c, const bool *in_part, int root, mr_dmat4 *rft, bool *placed, pair_t *buf) {
    int dropped = 0;
    memset(placed, 0, (size_t)c->ntags * sizeof *placed);
    placed[root] = true;
    rft[root] = mr_m4_identity();
    for (;;) {
        int best = -1, best_n = 0;
        for (int t = 0; t < c->ntags; t++) {
            if (!in_part[t] || placed[t]) continue;
            int n = 0;
            for (int a = 0; a < c->nobs;) {
                int b = a;
                while (b < c->nobs && c->obs[b].photo == c->obs[a].photo) b++;
                bool has_t = false, has_p = false;
                for (int x = a; x < b; x++) {
                    if (!c->obs[x].use) continue;
                    has_t |= c->obs[x].tag == t;
                    has_p |= placed[c->obs[x].tag];
                }
                n += has_t && has_p;
                a = b;
            }
            if (n > best_n) best = t, best_n = n;
        }
        if (best < 0) break;
        /* Candidates: through each placed tag of each photo of best. */
        int n = 0;
        for (int a = 0; a < c->nobs;) {
            int b = a;
            while (b < c->nobs && c->obs[b].photo == c->obs[a].photo) b++;
            const obs_t *ot = NULL;
            for (int x = a; x < b; x++)
                if (c->obs[x].use && c->obs[x].tag == best) ot = &c->obs[x];
            for (int x = a; ot && x < b; x++) {
                const obs_t *op = &c->obs[x];
                if (!op->use || !placed[op->tag]) continue;
                pair_t *e = &buf[n++];
                e->a = (int)(ot - c->obs); /* the sighting, to drop it */
                e->b = x;
                e->n = 0;
                for (int sp = 0; sp < op->ns; sp++) {
                    mr_dmat4 pfc = mr_m4_invert_rigid(&op->cft[sp]), rfc = mr_m4_mul(&rft[op->tag], &pfc);
                    for (int st = 0; st < ot->ns; st++) e->rel[e->n++] = mr_m4_mul(&rfc, &ot->cft[st]);
                }
            }
            a = b;
        }
        mr_dmat4 m;
        robust_mean(buf, n, &m);
        double lim_t = 2 * c->size[best];
        for (int i = 0; i < n; i++) {
            bool in = false;
            for (int k = 0; k < buf[i].n && !in; k++) {
                mr_dvec3 d = mr_v3(buf[i].rel[k].m[3] - m.m[3], buf[i].rel[k].m[7] - m.m[7], buf[i].rel[k].m[11] - m.m[11]);
                in = mr_pose_angle_deg(&buf[i].rel[k], &m) <= 2 * PAIR_INLIER_DEG && mr_v3_len(d) <= lim_t;
            }
            /* Out: either sighting may be the wrong one; the new tag's is
             * dropped unless it agrees through another placed tag. */
            if (!in) {
                bool other = false;
                for (int q = 0; q < n && !other; q++)
                    if (q != i && buf[q].a == buf[i].a)
                        for (int k = 0; k < buf[q].n && !other; k++) {
                            mr_dvec3 d = mr_v3(buf[q].rel[k].m[3] - m.m[3], buf[q].rel[k].m[7] - m.m[7],
                                               buf[q].rel[k].m[11] - m.m[11]);
                            other = mr_pose_angle_deg(&buf[q].rel[k], &m) <= 2 * PAIR_INLIER_DEG && mr_v3_len(d) <= lim_t;
                        }
                obs_t *drop = &c->obs[other ? buf[i].b : buf[i].a];
                if (drop->use && drop->tag != root) {
                    drop->use = false;
                    dropped++;
                }
            }
        }
        rft[best] = m;
        placed[best] = true;
    }
    return dropped;
}

/* One bundle adjustment of the component's tags (wft, nt of them) and the
 * used photos' poses (cfw, np), controls as given by use. */
static bool run_ba(const ctx_t *c, int nt, const int *tag_of, mr_dmat4 *wft, int np, const int *photo_slot,
                   mr_dmat4 *cfw, mr_camera *cam, int fixed, const int *ctl_tag, const bool *ctl_use, bool want_cov,
                   double *cov, double *rms, double *sigma, int *iters, mr_error *err) {
    const mr_map_params *p = c->p;
    int no = 0;
    for (int i = 0; i < c->nobs; i++) no += c->obs[i].use;
    int *ot = malloc((size_t)(no + 1) * sizeof *ot), *op = malloc((size_t)(no + 1) * sizeof *op);
    double *px = malloc((size_t)(no + 1) * 8 * sizeof *px), *sz = malloc((size_t)(nt + 1) * sizeof *sz);
    int nc = p->control_count;
    int *cc = malloc((size_t)(nc + 1) * sizeof *cc), *ct = malloc((size_t)(nc + 1) * sizeof *ct);
    double *cw = malloc((size_t)(nc + 1) * 3 * sizeof *cw), *cs = malloc((size_t)(nc + 1) * sizeof *cs);
    bool *cu = malloc((size_t)(nc + 1) * sizeof *cu);
    bool ok = ot && op && px && sz && cc && ct && cw && cs && cu;
    if (!ok) mr_fail(err, MR_ERR_NOMEM, "map: out of memory");
    if (ok) {
        int k = 0;
        for (int i = 0; i < c->nobs; i++) {
            const obs_t *o = &c->obs[i];
            if (!o->use) continue;
            ot[k] = tag_of[o->tag];
            op[k] = photo_slot[o->photo];
            memcpy(&px[8 * k], o->px, sizeof o->px);
            k++;
        }
        for (int i = 0; i < c->ntags; i++)
            if (tag_of[i] >= 0) sz[tag_of[i]] = c->size[i];
        for (int i = 0; i < nc; i++) {
            const mr_map_control *q = &p->controls[i];
            cu[i] = ctl_use[i] && ctl_tag[i] >= 0 && tag_of[ctl_tag[i]] >= 0;
            ct[i] = cu[i] ? tag_of[ctl_tag[i]] : 0;
            cc[i] = q->corner;
            cw[3 * i] = q->world.x;
            cw[3 * i + 1] = q->world.y;
            cw[3 * i + 2] = q->world.z;
            cs[i] = q->sigma;
        }
        mr_ba_problem b = {
            .ntags = nt,
            .nphotos = np,
            .nobs = no,
            .tag = (double *)wft,
            .cam = (double *)cfw,
            .tag_size = sz,
            .intr = {cam->fx, cam->fy, cam->cx, cam->cy, cam->dist[0], cam->dist[1], cam->dist[2], cam->dist[3],
                     cam->dist[4]},
            .refine_intrinsics = p->refine_intrinsics,
            .obs_tag = ot,
            .obs_photo = op,
            .obs_px = px,
            .fixed_tag = fixed,
            .ncontrol = nc,
            .ctl_tag = ct,
            .ctl_corner = cc,
            .ctl_world = cw,
            .ctl_sigma = cs,
            .ctl_use = cu,
            .loss_px = p->loss_px > 0 ? p->loss_px : MR_MAP_DEFAULT_LOSS_PX,
            .max_iterations = p->max_iterations > 0 ? p->max_iterations : 100,
            .threads = p->threads > 0 ? p->threads : 1,
            .want_cov = want_cov,
            .tag_cov = cov,
        };
        char msg[256] = "";
        ok = mr_ba_solve(&b, msg, sizeof msg);
        if (!ok) mr_fail(err, MR_ERR_INVALID, "map: %s", msg);
        if (ok) {
            cam->fx = b.intr[0], cam->fy = b.intr[1], cam->cx = b.intr[2], cam->cy = b.intr[3];
            for (int i = 0; i < 5; i++) cam->dist[i] = b.intr[4 + i];
            *rms = b.rms_px;
            *sigma = b.sigma_px;
            *iters = b.iterations;
        }
    }
    free(ot);
    free(op);
    free(px);
    free(sz);
    free(cc);
    free(ct);
    free(cw);
    free(cs);
    free(cu);
    return ok;
}

bool mr_map_build(const mr_camera *cam, const mr_map_photo *photos, int photo_count, const mr_map_params *params,
                  mr_map_result *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!cam || !params || photo_count < 0 || (photo_count > 0 && !photos))
        return mr_fail(err, MR_ERR_INVALID, "map: bad arguments");
    if (!mr_camera_validate(cam, err)) return false;
    const mr_map_params *p = params;
    if (photo_count < 1) return mr_fail(err, MR_ERR_INVALID, "map: no photos");
    if (p->control_count > 0 && p->control_count < 3)
        return mr_fail(err, MR_ERR_INVALID, "map: %d control points; a rigid gauge needs at least 3", p->control_count);
    for (int i = 0; i < p->control_count; i++) {
        const mr_map_control *q = &p->controls[i];
        if (!isfinite(q->world.x) || !isfinite(q->world.y) || !isfinite(q->world.z) || !(q->sigma > 0) ||
            !isfinite(q->sigma))
            return mr_fail(err, MR_ERR_INVALID, "map: control point %s: coordinates must be finite and sigma > 0",
                           q->name);
    }
    for (int i = 0; i < p->size_count; i++)
        if (!(p->sizes[i] > 0) || !isfinite(p->sizes[i]))
            return mr_fail(err, MR_ERR_INVALID, "map: tag %d: size must be > 0", p->size_ids[i]);
    double min_tag = p->min_tag_px > 0 ? p->min_tag_px : 8.0;
    out->photos_total = photo_count;
    out->camera = *cam;
    out->control_count = p->control_count;

    ctx_t c = {.cam = cam, .p = p};
    bool ok = false;
    int *all_ids = NULL, *parent = NULL, *tag_of = NULL, *photo_slot = NULL, *order = NULL, *tree_parent = NULL;
    int *ctl_tag = NULL, *tag_obs_count = NULL;
    bool *ctl_use = NULL, *in_tree = NULL;
    pair_t *pairs = NULL;
    edge_t *edges = NULL;
    mr_dmat4 *rft = NULL, *wft = NULL, *cfw = NULL, *wft_loo = NULL, *cfw_loo = NULL;
    double *cov = NULL, *cov_loo = NULL;

    /* 1. The tags seen and their sizes. */
    int nall = 0;
    for (int j = 0; j < photo_count; j++) nall += photos[j].count > 0 ? photos[j].count : 0;
    if (nall == 0) {
        mr_fail(err, MR_ERR_INVALID, "map: no tag seen in any of the %d photos", photo_count);
        goto done;
    }
    {
        /* One photo is one view: no tag pose is checked by a second one,
         * and a map of it is what a single PnP gives: refused. */
        int seeing = 0;
        for (int j = 0; j < photo_count; j++) seeing += photos[j].count > 0;
        if (seeing < 2) {
            mr_fail(err, MR_ERR_INVALID,
                    "map: only 1 of the %d photos sees a tag; a map needs two or more photos of the tags, taken from "
                    "different places", photo_count);
            goto done;
        }
    }
    all_ids = malloc((size_t)nall * sizeof *all_ids);
    if (!all_ids) goto nomem;
    {
        int k = 0;
        for (int j = 0; j < photo_count; j++)
            for (int i = 0; i < photos[j].count; i++) all_ids[k++] = photos[j].dets[i].id;
        qsort(all_ids, (size_t)nall, sizeof *all_ids, cmp_int);
        int u = 0;
        for (int i = 0; i < nall; i++)
            if (u == 0 || all_ids[u - 1] != all_ids[i]) all_ids[u++] = all_ids[i];
        c.ids = malloc((size_t)u * sizeof *c.ids);
        c.size = malloc((size_t)u * sizeof *c.size);
        out->unsized = malloc((size_t)u * sizeof *out->unsized);
        if (!c.ids || !c.size || !out->unsized) goto nomem;
        for (int i = 0; i < u; i++) {
            double s = p->tag_size;
            for (int q = 0; q < p->size_count; q++)
                if (p->size_ids[q] == all_ids[i]) s = p->sizes[q];
            if (s > 0) {
                c.ids[c.ntags] = all_ids[i];
                c.size[c.ntags++] = s;
            } else {
                out->unsized[out->unsized_count++] = all_ids[i];
            }
        }
    }
    if (c.ntags == 0) {
        mr_fail(err, MR_ERR_INVALID, "map: no tag of known size seen (tag %d has no size)", out->unsized[0]);
        goto done;
    }

    /* 2. Sightings: undistorted corners and both IPPE solutions. */
    c.obs = malloc((size_t)nall * sizeof *c.obs);
    if (!c.obs) goto nomem;
    for (int j = 0; j < photo_count; j++) {
        for (int i = 0; i < photos[j].count; i++) {
            const mr_detection *d = &photos[j].dets[i];
            int ti = -1;
            for (int lo = 0, hi = c.ntags - 1; lo <= hi;) {
                int mid = (lo + hi) / 2;
                if (c.ids[mid] == d->id) {
                    ti = mid;
                    break;
                }
                if (c.ids[mid] < d->id)
                    lo = mid + 1;
                else
                    hi = mid - 1;
            }
            if (ti < 0) continue;
            bool dup = false;
            for (int k = c.nobs - 1; k >= 0 && c.obs[k].photo == j; k--) dup |= c.obs[k].tag == ti;
            if (dup) continue; /* one sighting per tag and photo: the detector's first */
            obs_t *o = &c.obs[c.nobs];
            memset(o, 0, sizeof *o);
            o->tag = ti;
            o->photo = j;
            double edge = INFINITY;
            bool fin = true;
            for (int k = 0; k < 4; k++) {
                const double *a = d->corners[k], *b = d->corners[(k + 1) % 4];
                fin = fin && isfinite(a[0]) && isfinite(a[1]);
                edge = fmin(edge, hypot(b[0] - a[0], b[1] - a[1]));
                o->px[2 * k] = a[0];
                o->px[2 * k + 1] = a[1];
                fin = fin && mr_camera_undistort(cam, (a[0] - cam->cx) / cam->fx, (a[1] - cam->cy) / cam->fy,
                                                 &o->norm[2 * k], &o->norm[2 * k + 1]);
            }
            if (!fin || !(edge >= min_tag)) continue;
            mr_dvec3 tc[4];
            mr_marker_corners_tag(c.size[ti], tc);
            double objt[12], R[2][9], t[2][3];
            for (int k = 0; k < 4; k++) {
                objt[3 * k] = tc[k].x;
                objt[3 * k + 1] = tc[k].y;
                objt[3 * k + 2] = tc[k].z;
            }
            o->ns = mr_cv_ippe_square(objt, o->norm, R, t);
            if (o->ns < 1) continue;
            for (int s = 0; s < o->ns; s++) o->cft[s] = m4_rt(R[s], t[s]);
            o->use = true;
            c.nobs++;
        }
    }
    if (c.nobs == 0) {
        mr_fail(err, MR_ERR_INVALID, "map: no usable tag sighting (tags too small, or corners invalid)");
        goto done;
    }
    progress(p, "pairs", 0);

    /* 3. Pairwise relative poses, robust mean per pair. */
    {
        size_t np = 0;
        for (int a = 0; a < c.nobs;) {
            int b = a;
            while (b < c.nobs && c.obs[b].photo == c.obs[a].photo) b++;
            np += (size_t)(b - a) * (size_t)(b - a - 1) / 2;
            a = b;
        }
        pairs = malloc((np + 1) * sizeof *pairs);
        edges = malloc((np + 1) * sizeof *edges);
        if (!pairs || !edges) goto nomem;
        int ne = build_edges(&c, false, pairs, edges);
        /* 4. Connected parts. */
        parent = malloc((size_t)c.ntags * sizeof *parent);
        tag_obs_count = calloc((size_t)c.ntags, sizeof *tag_obs_count);
        if (!parent || !tag_obs_count) goto nomem;
        for (int i = 0; i < c.ntags; i++) parent[i] = i;
        for (int i = 0; i < c.nobs; i++) tag_obs_count[c.obs[i].tag]++;
        for (int e = 0; e < ne; e++) {
            int ra = uf_find(parent, edges[e].a), rb = uf_find(parent, edges[e].b);
            if (ra != rb) parent[ra] = rb;
        }
        int root = -1;
        ctl_tag = malloc((size_t)(p->control_count + 1) * sizeof *ctl_tag);
        ctl_use = malloc((size_t)(p->control_count + 1) * sizeof *ctl_use);
        out->controls = calloc((size_t)(p->control_count + 1), sizeof *out->controls);
        if (!ctl_tag || !ctl_use || !out->controls) goto nomem;
        for (int q = 0; q < p->control_count; q++) {
            ctl_tag[q] = -1;
            for (int i = 0; i < c.ntags; i++)
                if (c.ids[i] == p->controls[q].tag_id && tag_obs_count[i] > 0) ctl_tag[q] = i;
            ctl_use[q] = ctl_tag[q] >= 0;
            for (int a = 0; a < 3; a++) out->controls[q].residual[a] = out->controls[q].loo[a] = NAN;
            out->controls[q].loo_sigma = NAN;
        }
        if (p->control_count == 0) {
            for (int i = 0; i < c.ntags; i++)
                if (c.ids[i] == p->fix_id && tag_obs_count[i] > 0) root = i;
            if (root < 0) {
                mr_fail(err, MR_ERR_INVALID, "map: the fixed tag %d is not seen in any photo", p->fix_id);
                goto done;
            }
        } else {
            /* The part with the most control points (ties: the most seen). */
            int best = -1, bestn = 0, bests = 0;
            for (int i = 0; i < c.ntags; i++) {
                if (uf_find(parent, i) != i) continue;
                int n = 0, s = 0;
                for (int q = 0; q < p->control_count; q++) n += ctl_tag[q] >= 0 && uf_find(parent, ctl_tag[q]) == i;
                for (int t = 0; t < c.ntags; t++) s += uf_find(parent, t) == i ? tag_obs_count[t] : 0;
                if (n > bestn || (n == bestn && n > 0 && s > bests)) best = i, bestn = n, bests = s;
            }
            if (best < 0) {
                mr_fail(err, MR_ERR_INVALID, "map: none of the control points' tags is seen in any photo");
                goto done;
            }
            int most = -1;
            for (int i = 0; i < c.ntags; i++)
                if (uf_find(parent, i) == best && (most < 0 || tag_obs_count[i] > tag_obs_count[most])) most = i;
            root = most;
            for (int q = 0; q < p->control_count; q++)
                if (ctl_use[q] && uf_find(parent, ctl_tag[q]) != best) ctl_use[q] = false;
            if (bestn < 3) {
                mr_fail(err, MR_ERR_INVALID,
                        "map: only %d control point(s) lie on tags connected to each other; the gauge needs 3", bestn);
                goto done;
            }
        }
        int comp = uf_find(parent, root);
        tag_of = malloc((size_t)c.ntags * sizeof *tag_of);
        out->unconnected = malloc((size_t)c.ntags * sizeof *out->unconnected);
        if (!tag_of || !out->unconnected) goto nomem;
        int nt = 0;
        for (int i = 0; i < c.ntags; i++) {
            tag_of[i] = uf_find(parent, i) == comp ? nt++ : -1;
            if (tag_of[i] < 0) out->unconnected[out->unconnected_count++] = c.ids[i];
        }
        for (int i = 0; i < c.nobs; i++) c.obs[i].use = c.obs[i].use && tag_of[c.obs[i].tag] >= 0;

        /* 5. Maximum spanning tree by shared photos (Kruskal), then the
         * root_from_tag poses along it. */
        qsort(edges, (size_t)ne, sizeof *edges, cmp_edge_count);
        for (int i = 0; i < c.ntags; i++) parent[i] = i;
        order = malloc((size_t)c.ntags * sizeof *order);
        tree_parent = malloc((size_t)c.ntags * sizeof *tree_parent);
        in_tree = calloc((size_t)c.ntags, sizeof *in_tree);
        rft = malloc((size_t)c.ntags * sizeof *rft);
        bool *tree_edge = calloc((size_t)ne + 1, sizeof *tree_edge);
        if (!order || !tree_parent || !in_tree || !rft || !tree_edge) {
            free(tree_edge);
            goto nomem;
        }
        for (int e = 0; e < ne; e++) {
            if (tag_of[edges[e].a] < 0) continue;
            int ra = uf_find(parent, edges[e].a), rb = uf_find(parent, edges[e].b);
            if (ra != rb) {
                parent[ra] = rb;
                tree_edge[e] = true;
            }
        }
        int no = 0;
        order[no++] = root;
        in_tree[root] = true;
        rft[root] = mr_m4_identity();
        tree_parent[root] = -1;
        for (int h = 0; h < no; h++) {
            int i = order[h];
            for (int e = 0; e < ne; e++) {
                if (!tree_edge[e] || (edges[e].a != i && edges[e].b != i)) continue;
                int j = edges[e].a == i ? edges[e].b : edges[e].a;
                if (in_tree[j]) continue;
                mr_dmat4 ifj = edges[e].a == i ? edges[e].rel : mr_m4_invert_rigid(&edges[e].rel);
                rft[j] = mr_m4_mul(&rft[i], &ifj);
                tree_parent[j] = i;
                in_tree[j] = true;
                order[no++] = j;
            }
        }
        free(tree_edge);

        /* 6. Rotation averaging over every pair of the part (the tree is
         * only the start), then the positions with the rotations held;
         * before that, the tags placed again one by one with the sightings
         * that disagree left out, and the pairs made again without them. */
        if (!p->no_adjust) {
            bool *part = calloc((size_t)c.ntags, sizeof *part), *placed = calloc((size_t)c.ntags, sizeof *placed);
            pair_t *buf = malloc(((size_t)c.nobs * 8 + 1) * sizeof *buf);
            if (!part || !placed || !buf) {
                free(part);
                free(placed);
                free(buf);
                goto nomem;
            }
            for (int i = 0; i < c.ntags; i++) part[i] = tag_of[i] >= 0;
            int dropped = place_tags(&c, part, root, rft, placed, buf);
            if (dropped) mr_log(MR_LOG_INFO, "map: %d sightings disagree with the others: left out", dropped);
            free(part);
            free(placed);
            free(buf);
            ne = build_edges(&c, true, pairs, edges);
            double *R = malloc((size_t)(ne + 1) * 9 * sizeof *R), *w = malloc((size_t)(ne + 1) * sizeof *w);
            if (!R || !w) {
                free(R);
                free(w);
                goto nomem;
            }
            for (int sweep = 0; sweep < 20; sweep++)
                for (int h = 1; h < no; h++) {
                    int i = order[h], m = 0;
                    for (int e = 0; e < ne; e++) {
                        if (edges[e].a != i && edges[e].b != i) continue;
                        int j = edges[e].a == i ? edges[e].b : edges[e].a;
                        mr_dmat4 jfi = edges[e].b == i ? edges[e].rel : mr_m4_invert_rigid(&edges[e].rel);
                        mr_dmat4 r = mr_m4_mul(&rft[j], &jfi);
                        m4_R(&r, &R[9 * m]);
                        w[m++] = edges[e].count;
                    }
                    double Rm[9], t[3] = {rft[i].m[3], rft[i].m[7], rft[i].m[11]};
                    if (m == 0) continue;
                    mr_ba_rotation_mean(R, w, m, Rm);
                    rft[i] = m4_rt(Rm, t);
                }
            for (int sweep = 0; sweep < 50; sweep++)
                for (int h = 1; h < no; h++) {
                    int i = order[h];
                    double t[3] = {0, 0, 0}, sw = 0;
                    for (int e = 0; e < ne; e++) {
                        if (edges[e].a != i && edges[e].b != i) continue;
                        int j = edges[e].a == i ? edges[e].b : edges[e].a;
                        mr_dmat4 jfi = edges[e].b == i ? edges[e].rel : mr_m4_invert_rigid(&edges[e].rel);
                        mr_dvec3 q = mr_m4_point(&rft[j], mr_v3(jfi.m[3], jfi.m[7], jfi.m[11]));
                        t[0] += edges[e].count * q.x;
                        t[1] += edges[e].count * q.y;
                        t[2] += edges[e].count * q.z;
                        sw += edges[e].count;
                    }
                    if (!(sw > 0)) continue;
                    rft[i].m[3] = t[0] / sw;
                    rft[i].m[7] = t[1] / sw;
                    rft[i].m[11] = t[2] / sw;
                }
            free(R);
            free(w);
        }

        /* 7. The gauge: world_from_root. */
        mr_dmat4 wfr = p->fix_pose ? *p->fix_pose : mr_m4_identity();
        if (p->control_count > 0) {
            int n = 0;
            double *loc = malloc((size_t)p->control_count * 3 * sizeof *loc);
            double *wor = malloc((size_t)p->control_count * 3 * sizeof *wor);
            double *wt = malloc((size_t)p->control_count * sizeof *wt);
            bool fit = loc && wor && wt;
            for (int q = 0; fit && q < p->control_count; q++) {
                if (!ctl_use[q]) continue;
                mr_dvec3 l = mr_m4_point(&rft[ctl_tag[q]], tag_point(c.size[ctl_tag[q]], p->controls[q].corner));
                loc[3 * n] = l.x, loc[3 * n + 1] = l.y, loc[3 * n + 2] = l.z;
                wor[3 * n] = p->controls[q].world.x, wor[3 * n + 1] = p->controls[q].world.y,
                wor[3 * n + 2] = p->controls[q].world.z;
                wt[n++] = 1.0 / (p->controls[q].sigma * p->controls[q].sigma);
            }
            fit = fit && mr_ba_rigid_fit(loc, wor, wt, n, wfr.m);
            free(loc);
            free(wor);
            free(wt);
            if (!fit) {
                mr_fail(err, MR_ERR_INVALID, "map: the control points are (nearly) collinear: they fix no rotation");
                goto done;
            }
        }
        wft = malloc((size_t)nt * sizeof *wft);
        cfw = malloc((size_t)photo_count * sizeof *cfw);
        photo_slot = malloc((size_t)photo_count * sizeof *photo_slot);
        if (!wft || !cfw || !photo_slot) goto nomem;
        for (int i = 0; i < c.ntags; i++)
            if (tag_of[i] >= 0) wft[tag_of[i]] = mr_m4_mul(&wfr, &rft[i]);

        /* 8. Each photo's pose from all its tags of the part. */
        int nphot = 0;
        for (int a = 0; a < c.nobs;) {
            int b = a;
            while (b < c.nobs && c.obs[b].photo == c.obs[a].photo) b++;
            int j = c.obs[a].photo;
            photo_slot[j] = -1;
            double best_s = INFINITY;
            mr_dmat4 best_p = mr_m4_identity();
            for (int x = a; x < b; x++) {
                if (!c.obs[x].use) continue;
                mr_dmat4 tfw = mr_m4_invert_rigid(&wft[tag_of[c.obs[x].tag]]);
                for (int s = 0; s < c.obs[x].ns; s++) {
                    mr_dmat4 cand = mr_m4_mul(&c.obs[x].cft[s], &tfw);
                    double sum = 0, cap = 4 * (20 / cam->fx) * (20 / cam->fx); /* 20 px per corner */
                    for (int y = a; y < b; y++)
                        if (c.obs[y].use)
                            sum += fmin(obs_sq(&c.obs[y], c.size[c.obs[y].tag], &cand, &wft[tag_of[c.obs[y].tag]]),
                                        cap);
                    if (sum < best_s) best_s = sum, best_p = cand;
                }
            }
            if (isfinite(best_s)) {
                mr_dmat4 wfc = mr_m4_invert_rigid(&best_p);
                int n = 0;
                for (int y = a; y < b; y++) {
                    obs_t *o = &c.obs[y];
                    if (!o->use) continue;
                    o->use = obs_rms_px(cam, o, c.size[o->tag], &wfc, &wft[tag_of[o->tag]]) < OBS_REJECT_PX;
                    n += o->use;
                }
                if (n > 0) {
                    /* LM over the kept corners, world points relative to
                     * the first tag's centre (far offsets stay precise). */
                    double *obj = malloc((size_t)n * 12 * sizeof *obj), *img = malloc((size_t)n * 8 * sizeof *img);
                    if (!obj || !img) {
                        free(obj);
                        free(img);
                        goto nomem;
                    }
                    mr_dvec3 o0 = {0, 0, 0};
                    int m = 0;
                    for (int y = a; y < b; y++) {
                        const obs_t *o = &c.obs[y];
                        if (!o->use) continue;
                        const mr_dmat4 *w = &wft[tag_of[o->tag]];
                        if (m == 0) o0 = mr_v3(w->m[3], w->m[7], w->m[11]);
                        mr_dvec3 tc[4];
                        mr_marker_corners_tag(c.size[o->tag], tc);
                        for (int k = 0; k < 4; k++) {
                            mr_dvec3 q = mr_v3_sub(mr_m4_point(w, tc[k]), o0);
                            obj[12 * m + 3 * k] = q.x, obj[12 * m + 3 * k + 1] = q.y, obj[12 * m + 3 * k + 2] = q.z;
                        }
                        memcpy(&img[8 * m], o->norm, sizeof o->norm);
                        m++;
                    }
                    mr_dmat4 shift = mr_m4_translate(o0.x, o0.y, o0.z), cfo = mr_m4_mul(&best_p, &shift);
                    double R[9], t[3];
                    m4_R(&cfo, R);
                    t[0] = cfo.m[3], t[1] = cfo.m[7], t[2] = cfo.m[11];
                    if (mr_cv_refine_lm(obj, img, 4 * n, R, t)) {
                        mr_dmat4 r = m4_rt(R, t), unshift = mr_m4_translate(-o0.x, -o0.y, -o0.z);
                        best_p = mr_m4_mul(&r, &unshift);
                    }
                    free(obj);
                    free(img);
                    cfw[nphot] = best_p;
                    photo_slot[j] = nphot++;
                }
            }
            a = b;
        }
        /* Photos without a usable sighting keep slot -1. */
        for (int j = 0; j < photo_count; j++) {
            bool seen = false;
            for (int i = 0; i < c.nobs && !seen; i++) seen = c.obs[i].photo == j;
            if (!seen) photo_slot[j] = -1;
        }
        for (int i = 0; i < c.nobs; i++) c.obs[i].use = c.obs[i].use && photo_slot[c.obs[i].photo] >= 0;
        out->photos_used = nphot;

        /* 9. The adjustment, with leave-one-out and control outliers. */
        mr_camera cam_adj = *cam;
        cov = malloc((size_t)nt * 36 * sizeof *cov);
        if (!cov) goto nomem;
        for (int i = 0; i < 36 * nt; i++) cov[i] = NAN;
        int fixed = p->control_count > 0 ? -1 : tag_of[root];
        if (!p->no_adjust) {
            mr_dmat4 *wft0 = malloc((size_t)nt * sizeof *wft0), *cfw0 = malloc((size_t)(nphot + 1) * sizeof *cfw0);
            wft_loo = malloc((size_t)nt * sizeof *wft_loo);
            cov_loo = malloc((size_t)nt * 36 * sizeof *cov_loo);
            cfw_loo = malloc((size_t)(nphot + 1) * sizeof *cfw_loo);
            if (!wft0 || !cfw0 || !wft_loo || !cfw_loo || !cov_loo) {
                free(wft0);
                free(cfw0);
                goto nomem;
            }
            memcpy(wft0, wft, (size_t)nt * sizeof *wft);
            memcpy(cfw0, cfw, (size_t)nphot * sizeof *cfw);
            bool bad = false;
            for (;;) {
                memcpy(wft, wft0, (size_t)nt * sizeof *wft);
                memcpy(cfw, cfw0, (size_t)nphot * sizeof *cfw);
                cam_adj = *cam;
                progress(p, "adjust", 0);
                for (int round = 0; !bad; round++) {
                    if (!run_ba(&c, nt, tag_of, wft, nphot, photo_slot, cfw, &cam_adj, fixed, ctl_tag, ctl_use, true,
                                cov, &out->rms_px, &out->sigma_px, &out->iterations, err)) {
                        bad = true;
                        break;
                    }
                    if (round == 3) break;
                    /* Sightings the adjusted map cannot explain (wrong ids,
                     * a lone tag's wrong branch) leave; then once more. */
                    int rejected = 0;
                    double lim = fmax(OBS_REJECT_MIN_PX, OBS_REJECT_SIGMA * out->sigma_px);
                    for (int i = 0; i < c.nobs; i++) {
                        obs_t *o = &c.obs[i];
                        if (!o->use) continue;
                        mr_dmat4 wfc = mr_m4_invert_rigid(&cfw[photo_slot[o->photo]]);
                        if (obs_rms_px(&cam_adj, o, c.size[o->tag], &wfc, &wft[tag_of[o->tag]]) > lim) {
                            o->use = false;
                            rejected++;
                        }
                    }
                    if (!rejected) break;
                    mr_log(MR_LOG_INFO, "map: %d sightings off by more than %.1f px left out", rejected, lim);
                }
                if (bad) break;
                out->adjusted = true;
                int nused = 0;
                for (int q = 0; q < p->control_count; q++) nused += ctl_use[q];
                if (p->control_count == 0 || nused < 4) break;
                /* Leave one out: each used control's prediction by the others. */
                int worst = -1;
                double worst_s = 0, worst_rest = INFINITY, lim = p->outlier_sigma > 0 ? p->outlier_sigma : 5.0;
                for (int q = 0, done_n = 0; q < p->control_count; q++) {
                    if (!ctl_use[q]) continue;
                    progress(p, "leave-one-out", (double)done_n++ / nused);
                    memcpy(wft_loo, wft, (size_t)nt * sizeof *wft);
                    memcpy(cfw_loo, cfw, (size_t)nphot * sizeof *cfw);
                    mr_camera cl = cam_adj;
                    double r1, s1;
                    int it1;
                    ctl_use[q] = false;
                    bool lok = run_ba(&c, nt, tag_of, wft_loo, nphot, photo_slot, cfw_loo, &cl, -1, ctl_tag, ctl_use,
                                      true, cov_loo, &r1, &s1, &it1, err);
                    ctl_use[q] = true;
                    if (!lok) continue;
                    int ti = tag_of[ctl_tag[q]];
                    mr_dvec3 pr = mr_m4_point(&wft_loo[ti], tag_point(c.size[ctl_tag[q]], p->controls[q].corner));
                    mr_map_control_result *cr = &out->controls[q];
                    cr->loo[0] = pr.x - p->controls[q].world.x;
                    cr->loo[1] = pr.y - p->controls[q].world.y;
                    cr->loo[2] = pr.z - p->controls[q].world.z;
                    /* Expected spread: the survey's sigma and the point's
                     * own uncertainty in the solve without it (the left
                     * perturbation: d = w x (p - t) + dt, world axes). */
                    const double *C = &cov_loo[36 * ti];
                    mr_dvec3 a = mr_v3_sub(pr, mr_v3(wft_loo[ti].m[3], wft_loo[ti].m[7], wft_loo[ti].m[11]));
                    double A[3][6] = {{0, a.z, -a.y, 1, 0, 0}, {-a.z, 0, a.x, 0, 1, 0}, {a.y, -a.x, 0, 0, 0, 1}};
                    double tr = 0;
                    for (int r = 0; r < 3; r++)
                        for (int x = 0; x < 6; x++)
                            for (int y = 0; y < 6; y++) tr += A[r][x] * C[6 * x + y] * A[r][y];
                    double sig = sqrt(3 * p->controls[q].sigma * p->controls[q].sigma + (isfinite(tr) ? tr : 0));
                    cr->loo_sigma =
                        sqrt(cr->loo[0] * cr->loo[0] + cr->loo[1] * cr->loo[1] + cr->loo[2] * cr->loo[2]) / sig;
                    /* How well the others agree in the solve without q:
                     * one bad point bends the map towards itself, so with
                     * few points a good one can look as far off as the bad
                     * one (4 points, one 30 cm off: the good one named
                     * before); the one whose leaving makes the rest agree
                     * is the outlier. */
                    double rest = 0;
                    for (int q2 = 0; q2 < p->control_count; q2++) {
                        if (!ctl_use[q2] || q2 == q) continue;
                        mr_dvec3 p2 = mr_m4_point(&wft_loo[tag_of[ctl_tag[q2]]],
                                                  tag_point(c.size[ctl_tag[q2]], p->controls[q2].corner));
                        mr_dvec3 d2 = mr_v3_sub(p2, p->controls[q2].world);
                        rest += mr_v3_dot(d2, d2) / (p->controls[q2].sigma * p->controls[q2].sigma);
                    }
                    if (cr->loo_sigma > lim && (worst < 0 || rest < worst_rest))
                        worst = q, worst_s = cr->loo_sigma, worst_rest = rest;
                }
                if (worst < 0) break;
                /* The worst outlier leaves the gauge; the rest are judged
                 * again without it (one bad point skews every other's
                 * leave-one-out). */
                out->controls[worst].outlier = true;
                ctl_use[worst] = false;
                mr_log(MR_LOG_WARN, "map: control point %s disagrees by %.1f sigma: left out",
                       p->controls[worst].name, worst_s);
                if (nused - 1 < 3) {
                    mr_fail(err, MR_ERR_INVALID, "map: control point %s is an outlier (%.1f sigma) and fewer than 3 remain",
                            p->controls[worst].name, worst_s);
                    bad = true;
                    break;
                }
                for (int q = 0; q < p->control_count; q++)
                    if (ctl_use[q]) {
                        for (int a = 0; a < 3; a++) out->controls[q].loo[a] = NAN;
                        out->controls[q].loo_sigma = NAN;
                    }
            }
            free(wft0);
            free(cfw0);
            if (bad) goto done;
        } else {
            double ss = 0;
            int n = 0;
            for (int i = 0; i < c.nobs; i++) {
                const obs_t *o = &c.obs[i];
                if (!o->use) continue;
                mr_dmat4 wfc = mr_m4_invert_rigid(&cfw[photo_slot[o->photo]]);
                double r = obs_rms_px(cam, o, c.size[o->tag], &wfc, &wft[tag_of[o->tag]]);
                ss += r * r;
                n++;
            }
            out->rms_px = n ? sqrt(ss / n) : 0;
            out->sigma_px = NAN;
        }
        out->camera = cam_adj;
        out->refined_intrinsics = out->adjusted && p->refine_intrinsics;

        /* 10. The result. */
        out->tags = calloc((size_t)nt, sizeof *out->tags);
        if (!out->tags) goto nomem;
        for (int i = 0; i < c.ntags; i++) {
            int ti = tag_of[i];
            if (ti < 0) continue;
            mr_map_tag *t = &out->tags[ti];
            t->id = c.ids[i];
            t->size = c.size[i];
            t->world_from_tag = wft[ti];
            memcpy(t->cov, &cov[36 * ti], sizeof t->cov);
            double tr = 0, rr = 0;
            for (int a = 0; a < 3; a++) {
                rr += t->cov[7 * a];
                tr += t->cov[7 * (a + 3)];
                t->sigma_xyz[a] = sqrt(t->cov[7 * (a + 3)]);
            }
            t->sigma_pos = sqrt(tr);
            t->sigma_deg = sqrt(rr) * DEG;
            double ss = 0;
            int n = 0;
            for (int k = 0; k < c.nobs; k++) {
                const obs_t *o = &c.obs[k];
                if (!o->use || o->tag != i) continue;
                mr_dmat4 wfc = mr_m4_invert_rigid(&cfw[photo_slot[o->photo]]);
                double r = obs_rms_px(&out->camera, o, t->size, &wfc, &t->world_from_tag);
                ss += r * r;
                n++;
            }
            t->photos = n;
            t->rms_px = n ? sqrt(ss / n) : NAN;
            out->observations += n;
        }
        out->tag_count = nt;
        for (int q = 0; q < p->control_count; q++) {
            mr_map_control_result *cr = &out->controls[q];
            cr->used = ctl_use[q];
            if (ctl_tag[q] < 0 || tag_of[ctl_tag[q]] < 0) continue;
            mr_dvec3 pr =
                mr_m4_point(&wft[tag_of[ctl_tag[q]]], tag_point(c.size[ctl_tag[q]], p->controls[q].corner));
            cr->residual[0] = pr.x - p->controls[q].world.x;
            cr->residual[1] = pr.y - p->controls[q].world.y;
            cr->residual[2] = pr.z - p->controls[q].world.z;
        }
    }
    ok = true;
    goto done;
nomem:
    mr_fail(err, MR_ERR_NOMEM, "map: out of memory");
done:
    free(all_ids);
    free(parent);
    free(tag_of);
    free(photo_slot);
    free(order);
    free(tree_parent);
    free(ctl_tag);
    free(ctl_use);
    free(in_tree);
    free(tag_obs_count);
    free(pairs);
    free(edges);
    free(rft);
    free(wft);
    free(cfw);
    free(wft_loo);
    free(cfw_loo);
    free(cov);
    free(cov_loo);
    free(c.ids);
    free(c.size);
    free(c.obs);
    if (!ok) mr_map_result_free(out);
    return ok;
}
