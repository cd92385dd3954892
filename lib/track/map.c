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
 * fraction of the image diagonal (px RMS; 100 px at 320 x 240) is a
 * misdetection or a wrong IPPE branch of a lone tag: left out of the
 * adjustment rather than merely down-weighted. A fraction, not pixels: the
 * initial map's angular error is what it must allow for. */
#define OBS_REJECT_FRAC 0.25
/* After an adjustment, sightings whose corners miss by more than this many
 * estimated corner sigmas (and at least OBS_REJECT_MIN_PX) are left out
 * and the adjustment runs again. */
#define OBS_REJECT_SIGMA 6.0
#define OBS_REJECT_MIN_PX 3.0
/* Placing a tag through a sighting: its pose may be off by this fraction
 * of the sightings' distances before the sighting counts as wrong. */
#define PLACE_LEVER 0.1

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
    free(r->unplaced);
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

/* Does one of candidate e's poses (a new tag's pose through a placed
 * tag, e->a and e->b the two sightings) agree with the mean m? Within
 * twice the pair angle, and lim_t plus PLACE_LEVER of both sightings'
 * distances: a few degrees of a far tag's IPPE rotation move the other
 * tag by that lever, and far sightings are not misdetections for it. */
static bool agrees(const ctx_t *c, const pair_t *e, const mr_dmat4 *m, double lim_t) {
    const mr_dmat4 *ca = &c->obs[e->a].cft[0], *cb = &c->obs[e->b].cft[0];
    double lim = lim_t + PLACE_LEVER * (mr_v3_len(mr_v3(ca->m[3], ca->m[7], ca->m[11])) +
                                        mr_v3_len(mr_v3(cb->m[3], cb->m[7], cb->m[11])));
    for (int k = 0; k < e->n; k++) {
        mr_dvec3 d = mr_v3(e->rel[k].m[3] - m->m[3], e->rel[k].m[7] - m->m[7], e->rel[k].m[11] - m->m[11]);
        if (mr_pose_angle_deg(&e->rel[k], m) <= 2 * PAIR_INLIER_DEG && mr_v3_len(d) <= lim) return true;
    }
    return false;
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
            bool in = agrees(c, &buf[i], &m, lim_t);
            /* Out: either sighting may be the wrong one; the new tag's is
             * dropped unless it agrees through another placed tag. */
            if (!in) {
                bool other = false;
                for (int q = 0; q < n && !other; q++)
                    if (q != i && buf[q].a == buf[i].a) other = agrees(c, &buf[q], &m, lim_t);
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

/* Everything mr_map_build carries from one step to the next. Each step
 * below reads what the earlier ones left here and fails with err set. */
typedef struct map_state {
    ctx_t c;                     /* camera, params, tags and sightings */
    const mr_map_photo *photos;
    int photo_count;
    mr_map_result *out;
    mr_error *err;
    int nall;                    /* detections in all photos */
    pair_t *pairs;               /* per-photo tag pairs (scratch) */
    edge_t *edges;               /* robust mean per pair */
    int ne;
    int *parent;                 /* union-find over tags */
    int *tag_obs_count;          /* sightings per tag */
    int *ctl_tag;                /* control point -> tag index, -1 unseen */
    bool *ctl_use;               /* control point in the gauge */
    int root;                    /* the gauge's tag (fixed or most seen) */
    int *tag_of;                 /* tag index -> slot in the part, -1 */
    int nt;                      /* tags in the part */
    int *order;                  /* tags in tree order, root first */
    int norder;
    mr_dmat4 *rft;               /* root_from_tag, per tag index */
    mr_dmat4 *wft;               /* world_from_tag, per slot */
    mr_dmat4 *cfw;               /* camera_from_world, per used photo */
    int *photo_slot;             /* photo -> slot in cfw, -1 unused */
    int nphot;
    mr_camera cam_adj;           /* the camera after the adjustment */
    double *cov;                 /* per slot 6x6 */
    mr_dmat4 *wft_loo, *cfw_loo; /* leave-one-out solves */
    double *cov_loo;
} map_state;

static bool nomem(map_state *s) {
    return mr_fail(s->err, MR_ERR_NOMEM, "map: out of memory");
}

static void map_state_free(map_state *s) {
    free(s->parent);
    free(s->tag_of);
    free(s->photo_slot);
    free(s->order);
    free(s->ctl_tag);
    free(s->ctl_use);
    free(s->tag_obs_count);
    free(s->pairs);
    free(s->edges);
    free(s->rft);
    free(s->wft);
    free(s->cfw);
    free(s->wft_loo);
    free(s->cfw_loo);
    free(s->cov);
    free(s->cov_loo);
    free(s->c.ids);
    free(s->c.size);
    free(s->c.obs);
}

/* One adjustment's inputs that change between calls, and its results. */
typedef struct ba_run {
    mr_dmat4 *wft, *cfw;         /* refined in place */
    mr_camera *cam;              /* refined in place if asked */
    int fixed;                   /* gauge tag slot, -1: control points */
    double *cov;                 /* per slot 6x6 */
    double rms, sigma;           /* px */
    int iters;
} ba_run;

/* The BA problem's observation and control arrays, from the used
 * sightings and controls of the part. */
typedef struct ba_arrays {
    int *ot, *op, *cc, *ct;
    double *px, *sz, *cw, *cs;
    bool *cu;
} ba_arrays;

static void ba_arrays_free(ba_arrays *a) {
    free(a->ot);
    free(a->op);
    free(a->px);
    free(a->sz);
    free(a->cc);
    free(a->ct);
    free(a->cw);
    free(a->cs);
    free(a->cu);
}

/* Fills a (allocating it); returns the used sightings, -1 when out of memory. */
static int ba_arrays_fill(const map_state *s, ba_arrays *a) {
    const ctx_t *c = &s->c;
    const mr_map_params *p = c->p;
    int no = 0, nc = p->control_count;
    for (int i = 0; i < c->nobs; i++) no += c->obs[i].use;
    a->ot = malloc((size_t)(no + 1) * sizeof *a->ot), a->op = malloc((size_t)(no + 1) * sizeof *a->op);
    a->px = malloc((size_t)(no + 1) * 8 * sizeof *a->px), a->sz = malloc((size_t)(s->nt + 1) * sizeof *a->sz);
    a->cc = malloc((size_t)(nc + 1) * sizeof *a->cc), a->ct = malloc((size_t)(nc + 1) * sizeof *a->ct);
    a->cw = malloc((size_t)(nc + 1) * 3 * sizeof *a->cw), a->cs = malloc((size_t)(nc + 1) * sizeof *a->cs);
    a->cu = malloc((size_t)(nc + 1) * sizeof *a->cu);
    if (!a->ot || !a->op || !a->px || !a->sz || !a->cc || !a->ct || !a->cw || !a->cs || !a->cu) return -1;
    int k = 0;
    for (int i = 0; i < c->nobs; i++) {
        const obs_t *o = &c->obs[i];
        if (!o->use) continue;
        a->ot[k] = s->tag_of[o->tag];
        a->op[k] = s->photo_slot[o->photo];
        memcpy(&a->px[8 * k], o->px, sizeof o->px);
        k++;
    }
    for (int i = 0; i < c->ntags; i++)
        if (s->tag_of[i] >= 0) a->sz[s->tag_of[i]] = c->size[i];
    for (int i = 0; i < nc; i++) {
        const mr_map_control *q = &p->controls[i];
        a->cu[i] = s->ctl_use[i] && s->ctl_tag[i] >= 0 && s->tag_of[s->ctl_tag[i]] >= 0;
        a->ct[i] = a->cu[i] ? s->tag_of[s->ctl_tag[i]] : 0;
        a->cc[i] = q->corner;
        a->cw[3 * i] = q->world.x;
        a->cw[3 * i + 1] = q->world.y;
        a->cw[3 * i + 2] = q->world.z;
        a->cs[i] = q->sigma;
    }
    return no;
}

/* One bundle adjustment of the part's tags and the used photos' poses,
 * controls as s->ctl_use says; the covariance is always asked for. */
static bool run_ba(const map_state *s, ba_run *r, mr_error *err) {
    const mr_map_params *p = s->c.p;
    ba_arrays a = {0};
    int no = ba_arrays_fill(s, &a);
    bool ok = no >= 0;
    if (!ok) mr_fail(err, MR_ERR_NOMEM, "map: out of memory");
    if (ok) {
        mr_camera *cam = r->cam;
        mr_ba_problem b = {
            .ntags = s->nt,
            .nphotos = s->nphot,
            .nobs = no,
            .tag = (double *)r->wft,
            .cam = (double *)r->cfw,
            .tag_size = a.sz,
            .intr = {cam->fx, cam->fy, cam->cx, cam->cy, cam->dist[0], cam->dist[1], cam->dist[2], cam->dist[3],
                     cam->dist[4]},
            .refine_intrinsics = p->refine_intrinsics,
            .obs_tag = a.ot,
            .obs_photo = a.op,
            .obs_px = a.px,
            .fixed_tag = r->fixed,
            .ncontrol = p->control_count,
            .ctl_tag = a.ct,
            .ctl_corner = a.cc,
            .ctl_world = a.cw,
            .ctl_sigma = a.cs,
            .ctl_use = a.cu,
            .loss_px = p->loss_px > 0 ? p->loss_px : MR_MAP_DEFAULT_LOSS_PX,
            .max_iterations = p->max_iterations > 0 ? p->max_iterations : 100,
            .threads = p->threads > 0 ? p->threads : 1,
            .want_cov = true,
            .tag_cov = r->cov,
        };
        char msg[256] = "";
        ok = mr_ba_solve(&b, msg, sizeof msg);
        if (!ok) mr_fail(err, mr_stop_requested() ? MR_ERR_INTERRUPTED : MR_ERR_INVALID, "map: %s", msg);
        if (ok) {
            cam->fx = b.intr[0], cam->fy = b.intr[1], cam->cx = b.intr[2], cam->cy = b.intr[3];
            for (int i = 0; i < 5; i++) cam->dist[i] = b.intr[4 + i];
            r->rms = b.rms_px;
            r->sigma = b.sigma_px;
            r->iters = b.iterations;
        }
    }
    ba_arrays_free(&a);
    return ok;
}

static bool check_inputs(const mr_camera *cam, const mr_map_photo *photos, int photo_count, const mr_map_params *p,
                         mr_error *err) {
    if (!cam || !p || photo_count < 0 || (photo_count > 0 && !photos))
        return mr_fail(err, MR_ERR_INVALID, "map: bad arguments");
    if (!mr_camera_validate(cam, err)) return false;
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
    return true;
}

/* Step 1: the tags seen (sorted ids) and their sizes; unsized ones listed. */
static bool collect_tags(map_state *s) {
    const mr_map_params *p = s->c.p;
    mr_map_result *out = s->out;
    for (int j = 0; j < s->photo_count; j++) s->nall += s->photos[j].count > 0 ? s->photos[j].count : 0;
    if (s->nall == 0)
        return mr_fail(s->err, MR_ERR_INVALID, "map: no tag seen in any of the %d photos", s->photo_count);
    /* One photo is one view: no tag pose is checked by a second one, and
     * a map of it is what a single PnP gives: refused. */
    int seeing = 0;
    for (int j = 0; j < s->photo_count; j++) seeing += s->photos[j].count > 0;
    if (seeing < 2)
        return mr_fail(s->err, MR_ERR_INVALID,
                       "map: only 1 of the %d photos sees a tag; a map needs two or more photos of the tags, taken "
                       "from different places", s->photo_count);
    int *all_ids = malloc((size_t)s->nall * sizeof *all_ids);
    if (!all_ids) return nomem(s);
    int k = 0;
    for (int j = 0; j < s->photo_count; j++)
        for (int i = 0; i < s->photos[j].count; i++) all_ids[k++] = s->photos[j].dets[i].id;
    qsort(all_ids, (size_t)s->nall, sizeof *all_ids, cmp_int);
    int u = 0;
    for (int i = 0; i < s->nall; i++)
        if (u == 0 || all_ids[u - 1] != all_ids[i]) all_ids[u++] = all_ids[i];
    s->c.ids = malloc((size_t)u * sizeof *s->c.ids);
    s->c.size = malloc((size_t)u * sizeof *s->c.size);
    out->unsized = malloc((size_t)u * sizeof *out->unsized);
    if (!s->c.ids || !s->c.size || !out->unsized) {
        free(all_ids);
        return nomem(s);
    }
    for (int i = 0; i < u; i++) {
        double sz = p->tag_size;
        for (int q = 0; q < p->size_count; q++)
            if (p->size_ids[q] == all_ids[i]) sz = p->sizes[q];
        if (sz > 0) {
            s->c.ids[s->c.ntags] = all_ids[i];
            s->c.size[s->c.ntags++] = sz;
        } else {
            out->unsized[out->unsized_count++] = all_ids[i];
        }
    }
    free(all_ids);
    if (s->c.ntags == 0)
        return mr_fail(s->err, MR_ERR_INVALID, "map: no tag of known size seen (tag %d has no size)", out->unsized[0]);
    return true;
}

static int tag_index(const ctx_t *c, int id) {
    for (int lo = 0, hi = c->ntags - 1; lo <= hi;) {
        int mid = (lo + hi) / 2;
        if (c->ids[mid] == id) return mid;
        if (c->ids[mid] < id)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}

/* One detection as sighting o of tag ti in photo j: undistorted corners
 * and both IPPE solutions. False when it is unusable (too small, corners
 * not finite, no pose). */
static bool make_sighting(const ctx_t *c, const mr_detection *d, int ti, int j, double min_tag, obs_t *o) {
    const mr_camera *cam = c->cam;
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
    if (!fin || !(edge >= min_tag)) return false;
    mr_dvec3 tc[4];
    mr_marker_corners_tag(c->size[ti], tc);
    double objt[12], R[2][9], t[2][3];
    for (int k = 0; k < 4; k++) {
        objt[3 * k] = tc[k].x;
        objt[3 * k + 1] = tc[k].y;
        objt[3 * k + 2] = tc[k].z;
    }
    o->ns = mr_cv_ippe_square(objt, o->norm, R, t);
    if (o->ns < 1) return false;
    for (int q = 0; q < o->ns; q++) o->cft[q] = m4_rt(R[q], t[q]);
    o->use = true;
    return true;
}

/* Step 2: the sightings, one per tag and photo (the detector's first). */
static bool collect_sightings(map_state *s) {
    ctx_t *c = &s->c;
    double min_tag = c->p->min_tag_px > 0 ? c->p->min_tag_px : 8.0;
    c->obs = malloc((size_t)s->nall * sizeof *c->obs);
    if (!c->obs) return nomem(s);
    for (int j = 0; j < s->photo_count; j++) {
        for (int i = 0; i < s->photos[j].count; i++) {
            const mr_detection *d = &s->photos[j].dets[i];
            int ti = tag_index(c, d->id);
            if (ti < 0) continue;
            bool dup = false;
            for (int k = c->nobs - 1; k >= 0 && c->obs[k].photo == j; k--) dup |= c->obs[k].tag == ti;
            if (dup) continue;
            if (make_sighting(c, d, ti, j, min_tag, &c->obs[c->nobs])) c->nobs++;
        }
    }
    if (c->nobs == 0)
        return mr_fail(s->err, MR_ERR_INVALID, "map: no usable tag sighting (tags too small, or corners invalid)");
    progress(c->p, "pairs", 0);
    return true;
}

/* Step 3: pairwise relative poses, a robust mean per pair, and the
 * connected parts of the tags (union-find over the pairs). */
static bool connect_tags(map_state *s) {
    ctx_t *c = &s->c;
    size_t np = 0;
    for (int a = 0; a < c->nobs;) {
        int b = a;
        while (b < c->nobs && c->obs[b].photo == c->obs[a].photo) b++;
        np += (size_t)(b - a) * (size_t)(b - a - 1) / 2;
        a = b;
    }
    s->pairs = malloc((np + 1) * sizeof *s->pairs);
    s->edges = malloc((np + 1) * sizeof *s->edges);
    if (!s->pairs || !s->edges) return nomem(s);
    s->ne = build_edges(c, false, s->pairs, s->edges);
    s->parent = malloc((size_t)c->ntags * sizeof *s->parent);
    s->tag_obs_count = calloc((size_t)c->ntags, sizeof *s->tag_obs_count);
    if (!s->parent || !s->tag_obs_count) return nomem(s);
    for (int i = 0; i < c->ntags; i++) s->parent[i] = i;
    for (int i = 0; i < c->nobs; i++) s->tag_obs_count[c->obs[i].tag]++;
    for (int e = 0; e < s->ne; e++) {
        int ra = uf_find(s->parent, s->edges[e].a), rb = uf_find(s->parent, s->edges[e].b);
        if (ra != rb) s->parent[ra] = rb;
    }
    return true;
}

/* The root with control points: the part with the most control points
 * (ties: the most seen), its most seen tag; controls elsewhere unused. */
static bool control_root(map_state *s) {
    const ctx_t *c = &s->c;
    const mr_map_params *p = c->p;
    int best = -1, bestn = 0, bests = 0;
    for (int i = 0; i < c->ntags; i++) {
        if (uf_find(s->parent, i) != i) continue;
        int n = 0, sum = 0;
        for (int q = 0; q < p->control_count; q++)
            n += s->ctl_tag[q] >= 0 && uf_find(s->parent, s->ctl_tag[q]) == i;
        for (int t = 0; t < c->ntags; t++) sum += uf_find(s->parent, t) == i ? s->tag_obs_count[t] : 0;
        if (n > bestn || (n == bestn && n > 0 && sum > bests)) best = i, bestn = n, bests = sum;
    }
    if (best < 0) return mr_fail(s->err, MR_ERR_INVALID, "map: none of the control points' tags is seen in any photo");
    int most = -1;
    for (int i = 0; i < c->ntags; i++)
        if (uf_find(s->parent, i) == best && (most < 0 || s->tag_obs_count[i] > s->tag_obs_count[most])) most = i;
    s->root = most;
    for (int q = 0; q < p->control_count; q++)
        if (s->ctl_use[q] && uf_find(s->parent, s->ctl_tag[q]) != best) s->ctl_use[q] = false;
    if (bestn < 3)
        return mr_fail(s->err, MR_ERR_INVALID,
                       "map: only %d control point(s) lie on tags connected to each other; the gauge needs 3", bestn);
    return true;
}

/* Step 4: the gauge's part (the fixed tag's, or the controls'), its
 * tags' slots; sightings of other parts leave. */
static bool choose_part(map_state *s) {
    ctx_t *c = &s->c;
    const mr_map_params *p = c->p;
    mr_map_result *out = s->out;
    s->root = -1;
    s->ctl_tag = malloc((size_t)(p->control_count + 1) * sizeof *s->ctl_tag);
    s->ctl_use = malloc((size_t)(p->control_count + 1) * sizeof *s->ctl_use);
    out->controls = calloc((size_t)(p->control_count + 1), sizeof *out->controls);
    if (!s->ctl_tag || !s->ctl_use || !out->controls) return nomem(s);
    for (int q = 0; q < p->control_count; q++) {
        s->ctl_tag[q] = -1;
        for (int i = 0; i < c->ntags; i++)
            if (c->ids[i] == p->controls[q].tag_id && s->tag_obs_count[i] > 0) s->ctl_tag[q] = i;
        s->ctl_use[q] = s->ctl_tag[q] >= 0;
        for (int a = 0; a < 3; a++) out->controls[q].residual[a] = out->controls[q].loo[a] = NAN;
        out->controls[q].loo_sigma = NAN;
    }
    if (p->control_count == 0) {
        for (int i = 0; i < c->ntags; i++)
            if (c->ids[i] == p->fix_id && s->tag_obs_count[i] > 0) s->root = i;
        if (s->root < 0) return mr_fail(s->err, MR_ERR_INVALID, "map: the fixed tag %d is not seen in any photo", p->fix_id);
    } else if (!control_root(s)) {
        return false;
    }
    int comp = uf_find(s->parent, s->root);
    s->tag_of = malloc((size_t)c->ntags * sizeof *s->tag_of);
    out->unconnected = malloc((size_t)c->ntags * sizeof *out->unconnected);
    if (!s->tag_of || !out->unconnected) return nomem(s);
    s->nt = 0;
    for (int i = 0; i < c->ntags; i++) {
        s->tag_of[i] = uf_find(s->parent, i) == comp ? s->nt++ : -1;
        if (s->tag_of[i] < 0) out->unconnected[out->unconnected_count++] = c->ids[i];
    }
    for (int i = 0; i < c->nobs; i++) c->obs[i].use = c->obs[i].use && s->tag_of[c->obs[i].tag] >= 0;
    return true;
}

/* Step 5: the maximum spanning tree by shared photos (Kruskal), then the
 * root_from_tag poses along it, breadth first from the root. */
static bool spanning_tree(map_state *s) {
    const ctx_t *c = &s->c;
    edge_t *edges = s->edges;
    int ne = s->ne;
    qsort(edges, (size_t)ne, sizeof *edges, cmp_edge_count);
    for (int i = 0; i < c->ntags; i++) s->parent[i] = i;
    s->order = malloc((size_t)c->ntags * sizeof *s->order);
    s->rft = malloc((size_t)c->ntags * sizeof *s->rft);
    bool *in_tree = calloc((size_t)c->ntags, sizeof *in_tree);
    bool *tree_edge = calloc((size_t)ne + 1, sizeof *tree_edge);
    if (!s->order || !s->rft || !in_tree || !tree_edge) {
        free(in_tree);
        free(tree_edge);
        return nomem(s);
    }
    for (int e = 0; e < ne; e++) {
        if (s->tag_of[edges[e].a] < 0) continue;
        int ra = uf_find(s->parent, edges[e].a), rb = uf_find(s->parent, edges[e].b);
        if (ra != rb) {
            s->parent[ra] = rb;
            tree_edge[e] = true;
        }
    }
    int no = 0;
    s->order[no++] = s->root;
    in_tree[s->root] = true;
    s->rft[s->root] = mr_m4_identity();
    for (int h = 0; h < no; h++) {
        int i = s->order[h];
        for (int e = 0; e < ne; e++) {
            if (!tree_edge[e] || (edges[e].a != i && edges[e].b != i)) continue;
            int j = edges[e].a == i ? edges[e].b : edges[e].a;
            if (in_tree[j]) continue;
            mr_dmat4 ifj = edges[e].a == i ? edges[e].rel : mr_m4_invert_rigid(&edges[e].rel);
            s->rft[j] = mr_m4_mul(&s->rft[i], &ifj);
            in_tree[j] = true;
            s->order[no++] = j;
        }
    }
    s->norder = no;
    free(in_tree);
    free(tree_edge);
    return true;
}

/* tag i's pose through edge e's other tag: jfi and j. */
static mr_dmat4 edge_from(const edge_t *e, int i, int *j) {
    *j = e->a == i ? e->b : e->a;
    return e->b == i ? e->rel : mr_m4_invert_rigid(&e->rel);
}

/* Rotation averaging over every pair of the part (20 sweeps in tree
 * order, weighted by shared photos), then the positions with the
 * rotations held (50 sweeps). */
static bool average_edges(map_state *s) {
    const edge_t *edges = s->edges;
    mr_dmat4 *rft = s->rft;
    int ne = s->ne;
    double *R = malloc((size_t)(ne + 1) * 9 * sizeof *R), *w = malloc((size_t)(ne + 1) * sizeof *w);
    if (!R || !w) {
        free(R);
        free(w);
        return nomem(s);
    }
    for (int sweep = 0; sweep < 20; sweep++)
        for (int h = 1; h < s->norder; h++) {
            int i = s->order[h], m = 0;
            for (int e = 0; e < ne; e++) {
                if (edges[e].a != i && edges[e].b != i) continue;
                int j;
                mr_dmat4 jfi = edge_from(&edges[e], i, &j);
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
        for (int h = 1; h < s->norder; h++) {
            int i = s->order[h];
            double t[3] = {0, 0, 0}, sw = 0;
            for (int e = 0; e < ne; e++) {
                if (edges[e].a != i && edges[e].b != i) continue;
                int j;
                mr_dmat4 jfi = edge_from(&edges[e], i, &j);
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
    return true;
}

/* Step 6 (unless no_adjust): the tags placed again one by one with the
 * sightings that disagree left out, the pairs made again without them,
 * then the pose averaging over every pair (the tree is only the start). */
static bool average_poses(map_state *s) {
    ctx_t *c = &s->c;
    bool *part = calloc((size_t)c->ntags, sizeof *part), *placed = calloc((size_t)c->ntags, sizeof *placed);
    pair_t *buf = malloc(((size_t)c->nobs * 8 + 1) * sizeof *buf);
    if (!part || !placed || !buf) {
        free(part);
        free(placed);
        free(buf);
        return nomem(s);
    }
    for (int i = 0; i < c->ntags; i++) part[i] = s->tag_of[i] >= 0;
    int dropped = place_tags(c, part, s->root, s->rft, placed, buf);
    if (dropped) mr_log(MR_LOG_INFO, "map: %d sightings disagree with the others: left out", dropped);
    free(part);
    free(placed);
    free(buf);
    s->ne = build_edges(c, true, s->pairs, s->edges);
    return average_edges(s);
}

/* Step 7: the gauge, world_from_root (the fixed pose, or the controls'
 * rigid fit), and every tag's world pose. */
static bool apply_gauge(map_state *s) {
    const ctx_t *c = &s->c;
    const mr_map_params *p = c->p;
    mr_dmat4 wfr = p->fix_pose ? *p->fix_pose : mr_m4_identity();
    if (p->control_count > 0) {
        int n = 0;
        double *loc = malloc((size_t)p->control_count * 3 * sizeof *loc);
        double *wor = malloc((size_t)p->control_count * 3 * sizeof *wor);
        double *wt = malloc((size_t)p->control_count * sizeof *wt);
        bool fit = loc && wor && wt;
        for (int q = 0; fit && q < p->control_count; q++) {
            if (!s->ctl_use[q]) continue;
            mr_dvec3 l = mr_m4_point(&s->rft[s->ctl_tag[q]], tag_point(c->size[s->ctl_tag[q]], p->controls[q].corner));
            loc[3 * n] = l.x, loc[3 * n + 1] = l.y, loc[3 * n + 2] = l.z;
            wor[3 * n] = p->controls[q].world.x, wor[3 * n + 1] = p->controls[q].world.y,
            wor[3 * n + 2] = p->controls[q].world.z;
            wt[n++] = 1.0 / (p->controls[q].sigma * p->controls[q].sigma);
        }
        fit = fit && mr_ba_rigid_fit(loc, wor, wt, n, wfr.m);
        free(loc);
        free(wor);
        free(wt);
        if (!fit)
            return mr_fail(s->err, MR_ERR_INVALID, "map: the control points are (nearly) collinear: they fix no rotation");
    }
    s->wft = malloc((size_t)s->nt * sizeof *s->wft);
    s->cfw = malloc((size_t)s->photo_count * sizeof *s->cfw);
    s->photo_slot = malloc((size_t)s->photo_count * sizeof *s->photo_slot);
    if (!s->wft || !s->cfw || !s->photo_slot) return nomem(s);
    for (int i = 0; i < c->ntags; i++)
        if (s->tag_of[i] >= 0) s->wft[s->tag_of[i]] = mr_m4_mul(&wfr, &s->rft[i]);
    return true;
}

/* The photo's camera_from_world that best explains sightings [a, b): the
 * candidate through each tag and IPPE branch, scored with capped errors. */
static double best_candidate(const map_state *s, int a, int b, mr_dmat4 *best_p) {
    const ctx_t *c = &s->c;
    double best_s = INFINITY;
    *best_p = mr_m4_identity();
    for (int x = a; x < b; x++) {
        if (!c->obs[x].use) continue;
        mr_dmat4 tfw = mr_m4_invert_rigid(&s->wft[s->tag_of[c->obs[x].tag]]);
        for (int k = 0; k < c->obs[x].ns; k++) {
            mr_dmat4 cand = mr_m4_mul(&c->obs[x].cft[k], &tfw);
            double sum = 0, cap = 4 * (20 / c->cam->fx) * (20 / c->cam->fx); /* 20 px per corner */
            for (int y = a; y < b; y++)
                if (c->obs[y].use)
                    sum += fmin(obs_sq(&c->obs[y], c->size[c->obs[y].tag], &cand, &s->wft[s->tag_of[c->obs[y].tag]]),
                                cap);
            if (sum < best_s) best_s = sum, *best_p = cand;
        }
    }
    return best_s;
}

/* LM over the n kept corners of sightings [a, b), world points relative
 * to the first tag's centre (far offsets stay precise); refines *cfw. */
static bool refine_photo(const map_state *s, int a, int b, int n, mr_dmat4 *cfw) {
    const ctx_t *c = &s->c;
    double *obj = malloc((size_t)n * 12 * sizeof *obj), *img = malloc((size_t)n * 8 * sizeof *img);
    if (!obj || !img) {
        free(obj);
        free(img);
        return false;
    }
    mr_dvec3 o0 = {0, 0, 0};
    int m = 0;
    for (int y = a; y < b; y++) {
        const obs_t *o = &c->obs[y];
        if (!o->use) continue;
        const mr_dmat4 *w = &s->wft[s->tag_of[o->tag]];
        if (m == 0) o0 = mr_v3(w->m[3], w->m[7], w->m[11]);
        mr_dvec3 tc[4];
        mr_marker_corners_tag(c->size[o->tag], tc);
        for (int k = 0; k < 4; k++) {
            mr_dvec3 q = mr_v3_sub(mr_m4_point(w, tc[k]), o0);
            obj[12 * m + 3 * k] = q.x, obj[12 * m + 3 * k + 1] = q.y, obj[12 * m + 3 * k + 2] = q.z;
        }
        memcpy(&img[8 * m], o->norm, sizeof o->norm);
        m++;
    }
    mr_dmat4 shift = mr_m4_translate(o0.x, o0.y, o0.z), cfo = mr_m4_mul(cfw, &shift);
    double R[9], t[3];
    m4_R(&cfo, R);
    t[0] = cfo.m[3], t[1] = cfo.m[7], t[2] = cfo.m[11];
    if (mr_cv_refine_lm(obj, img, 4 * n, R, t)) {
        mr_dmat4 r = m4_rt(R, t), unshift = mr_m4_translate(-o0.x, -o0.y, -o0.z);
        *cfw = mr_m4_mul(&r, &unshift);
    }
    free(obj);
    free(img);
    return true;
}

/* Step 8: each photo's pose from all its tags of the part; sightings
 * that miss it by OBS_REJECT_FRAC leave; photos without one keep slot -1. */
static bool photo_poses(map_state *s) {
    ctx_t *c = &s->c;
    double lim = OBS_REJECT_FRAC * hypot(c->cam->width, c->cam->height);
    for (int a = 0; a < c->nobs;) {
        int b = a;
        while (b < c->nobs && c->obs[b].photo == c->obs[a].photo) b++;
        int j = c->obs[a].photo;
        s->photo_slot[j] = -1;
        mr_dmat4 best_p;
        if (isfinite(best_candidate(s, a, b, &best_p))) {
            mr_dmat4 wfc = mr_m4_invert_rigid(&best_p);
            int n = 0;
            for (int y = a; y < b; y++) {
                obs_t *o = &c->obs[y];
                if (!o->use) continue;
                o->use = obs_rms_px(c->cam, o, c->size[o->tag], &wfc, &s->wft[s->tag_of[o->tag]]) < lim;
                n += o->use;
            }
            if (n > 0) {
                if (!refine_photo(s, a, b, n, &best_p)) return nomem(s);
                s->cfw[s->nphot] = best_p;
                s->photo_slot[j] = s->nphot++;
            }
        }
        a = b;
    }
    for (int j = 0; j < s->photo_count; j++) {
        bool seen = false;
        for (int i = 0; i < c->nobs && !seen; i++) seen = c->obs[i].photo == j;
        if (!seen) s->photo_slot[j] = -1;
    }
    for (int i = 0; i < c->nobs; i++) c->obs[i].use = c->obs[i].use && s->photo_slot[c->obs[i].photo] >= 0;
    s->out->photos_used = s->nphot;
    return true;
}

/* A tag of the part none of whose sightings is in use: its initial place
 * was wrong (a bad pair mean along its tree path), so every sighting
 * disagreed with it and left. It is placed again from the adjusted photo
 * poses: the candidate through each of its sightings and IPPE branches
 * that explains most of them (capped errors, as best_candidate), and the
 * sightings within lim px of it are used again. Each tag once (tried).
 * Returns how many tags came back. */
static int replace_lost_tags(map_state *s, bool *tried, double lim) {
    ctx_t *c = &s->c;
    int back = 0;
    for (int i = 0; i < c->ntags; i++) {
        int ti = s->tag_of[i];
        if (ti < 0 || tried[i]) continue;
        bool used = false, posed = false;
        for (int x = 0; x < c->nobs && !used; x++) {
            if (c->obs[x].tag != i) continue;
            used = c->obs[x].use;
            posed = posed || s->photo_slot[c->obs[x].photo] >= 0;
        }
        if (used || !posed) continue;
        tried[i] = true;
        double best_s = INFINITY, cap = 4 * (20 / c->cam->fx) * (20 / c->cam->fx);
        mr_dmat4 best = s->wft[ti];
        for (int x = 0; x < c->nobs; x++) {
            const obs_t *o = &c->obs[x];
            if (o->tag != i || s->photo_slot[o->photo] < 0) continue;
            mr_dmat4 wfc = mr_m4_invert_rigid(&s->cfw[s->photo_slot[o->photo]]);
            for (int k = 0; k < o->ns; k++) {
                mr_dmat4 cand = mr_m4_mul(&wfc, &o->cft[k]);
                double sum = 0;
                for (int y = 0; y < c->nobs; y++)
                    if (c->obs[y].tag == i && s->photo_slot[c->obs[y].photo] >= 0)
                        sum += fmin(obs_sq(&c->obs[y], c->size[i], &s->cfw[s->photo_slot[c->obs[y].photo]], &cand), cap);
                if (sum < best_s) best_s = sum, best = cand;
            }
        }
        int n = 0;
        for (int y = 0; y < c->nobs; y++) {
            obs_t *o = &c->obs[y];
            if (o->tag != i || s->photo_slot[o->photo] < 0) continue;
            mr_dmat4 wfc = mr_m4_invert_rigid(&s->cfw[s->photo_slot[o->photo]]);
            o->use = obs_rms_px(&s->cam_adj, o, c->size[i], &wfc, &best) < lim;
            n += o->use;
        }
        if (n > 0) {
            s->wft[ti] = best;
            back++;
            mr_log(MR_LOG_INFO, "map: tag %d placed again from %d sightings", c->ids[i], n);
        }
    }
    return back;
}

/* Adjustments until no sighting is off by more than OBS_REJECT_SIGMA
 * estimated sigmas and no lost tag comes back (at most 6 rounds): wrong
 * ids, a lone tag's wrong branch leave; then once more. */
static bool adjust_rounds(map_state *s) {
    ctx_t *c = &s->c;
    mr_map_result *out = s->out;
    ba_run r = {.wft = s->wft, .cfw = s->cfw, .cam = &s->cam_adj, .cov = s->cov,
                .fixed = c->p->control_count > 0 ? -1 : s->tag_of[s->root]};
    bool *tried = calloc((size_t)c->ntags + 1, sizeof *tried);
    if (!tried) return nomem(s);
    bool ok = true;
    for (int round = 0;; round++) {
        if (!(ok = run_ba(s, &r, s->err))) break;
        out->rms_px = r.rms, out->sigma_px = r.sigma, out->iterations = r.iters;
        if (round == 5) break;
        int rejected = 0;
        double lim = fmax(OBS_REJECT_MIN_PX, OBS_REJECT_SIGMA * out->sigma_px);
        for (int i = 0; i < c->nobs; i++) {
            obs_t *o = &c->obs[i];
            if (!o->use) continue;
            mr_dmat4 wfc = mr_m4_invert_rigid(&s->cfw[s->photo_slot[o->photo]]);
            if (obs_rms_px(&s->cam_adj, o, c->size[o->tag], &wfc, &s->wft[s->tag_of[o->tag]]) > lim) {
                o->use = false;
                rejected++;
            }
        }
        int back = replace_lost_tags(s, tried, lim);
        if (!rejected && !back) break;
        if (rejected) mr_log(MR_LOG_INFO, "map: %d sightings off by more than %.1f px left out", rejected, lim);
    }
    free(tried);
    out->adjusted = ok;
    return ok;
}

/* Control q left out: its prediction by the others (loo, loo_sigma) into
 * out->controls[q]; *rest: how well the others agree without it. False
 * when that solve failed. */
static bool leave_one_out(map_state *s, int q, double *rest) {
    const ctx_t *c = &s->c;
    const mr_map_params *p = c->p;
    memcpy(s->wft_loo, s->wft, (size_t)s->nt * sizeof *s->wft);
    memcpy(s->cfw_loo, s->cfw, (size_t)s->nphot * sizeof *s->cfw);
    mr_camera cl = s->cam_adj;
    ba_run r = {.wft = s->wft_loo, .cfw = s->cfw_loo, .cam = &cl, .fixed = -1, .cov = s->cov_loo};
    s->ctl_use[q] = false;
    bool lok = run_ba(s, &r, s->err);
    s->ctl_use[q] = true;
    if (!lok) return false;
    int ti = s->tag_of[s->ctl_tag[q]];
    mr_dvec3 pr = mr_m4_point(&s->wft_loo[ti], tag_point(c->size[s->ctl_tag[q]], p->controls[q].corner));
    mr_map_control_result *cr = &s->out->controls[q];
    cr->loo[0] = pr.x - p->controls[q].world.x;
    cr->loo[1] = pr.y - p->controls[q].world.y;
    cr->loo[2] = pr.z - p->controls[q].world.z;
    /* Expected spread: the survey's sigma and the point's own uncertainty
     * in the solve without it (the left perturbation: d = w x (p - t) +
     * dt, world axes). */
    const double *C = &s->cov_loo[36 * ti];
    mr_dvec3 a = mr_v3_sub(pr, mr_v3(s->wft_loo[ti].m[3], s->wft_loo[ti].m[7], s->wft_loo[ti].m[11]));
    double A[3][6] = {{0, a.z, -a.y, 1, 0, 0}, {-a.z, 0, a.x, 0, 1, 0}, {a.y, -a.x, 0, 0, 0, 1}};
    double tr = 0;
    for (int r3 = 0; r3 < 3; r3++)
        for (int x = 0; x < 6; x++)
            for (int y = 0; y < 6; y++) tr += A[r3][x] * C[6 * x + y] * A[r3][y];
    double sig = sqrt(3 * p->controls[q].sigma * p->controls[q].sigma + (isfinite(tr) ? tr : 0));
    cr->loo_sigma = sqrt(cr->loo[0] * cr->loo[0] + cr->loo[1] * cr->loo[1] + cr->loo[2] * cr->loo[2]) / sig;
    /* One bad point bends the map towards itself, so with few points a
     * good one can look as far off as the bad one (4 points, one 30 cm
     * off: the good one named before); the one whose leaving makes the
     * rest agree is the outlier. */
    *rest = 0;
    for (int q2 = 0; q2 < p->control_count; q2++) {
        if (!s->ctl_use[q2] || q2 == q) continue;
        mr_dvec3 p2 = mr_m4_point(&s->wft_loo[s->tag_of[s->ctl_tag[q2]]],
                                  tag_point(c->size[s->ctl_tag[q2]], p->controls[q2].corner));
        mr_dvec3 d2 = mr_v3_sub(p2, p->controls[q2].world);
        *rest += mr_v3_dot(d2, d2) / (p->controls[q2].sigma * p->controls[q2].sigma);
    }
    return true;
}

/* Each used control's leave-one-out; returns the outlier to drop (the
 * one beyond outlier_sigma whose leaving makes the rest agree best), or
 * -1; *worst_s its sigmas. */
static int worst_control(map_state *s, int nused, double *worst_s) {
    const mr_map_params *p = s->c.p;
    int worst = -1;
    double worst_rest = INFINITY, lim = p->outlier_sigma > 0 ? p->outlier_sigma : 5.0;
    for (int q = 0, done_n = 0; q < p->control_count; q++) {
        if (!s->ctl_use[q]) continue;
        progress(p, "leave-one-out", (double)done_n++ / nused);
        double rest;
        if (!leave_one_out(s, q, &rest)) continue;
        const mr_map_control_result *cr = &s->out->controls[q];
        if (cr->loo_sigma > lim && (worst < 0 || rest < worst_rest)) worst = q, *worst_s = cr->loo_sigma, worst_rest = rest;
    }
    return worst;
}

/* The adjustment from the initial poses, again without each outlying
 * control point in turn (one bad point skews every other's
 * leave-one-out), until none is left or fewer than 4 are used. */
static bool adjust_with_controls(map_state *s) {
    const mr_map_params *p = s->c.p;
    mr_map_result *out = s->out;
    int nt = s->nt, nphot = s->nphot;
    mr_dmat4 *wft0 = malloc((size_t)nt * sizeof *wft0), *cfw0 = malloc((size_t)(nphot + 1) * sizeof *cfw0);
    s->wft_loo = malloc((size_t)nt * sizeof *s->wft_loo);
    s->cov_loo = malloc((size_t)nt * 36 * sizeof *s->cov_loo);
    s->cfw_loo = malloc((size_t)(nphot + 1) * sizeof *s->cfw_loo);
    bool ok = wft0 && cfw0 && s->wft_loo && s->cfw_loo && s->cov_loo;
    if (!ok) nomem(s);
    if (ok) {
        memcpy(wft0, s->wft, (size_t)nt * sizeof *s->wft);
        memcpy(cfw0, s->cfw, (size_t)nphot * sizeof *s->cfw);
    }
    while (ok) {
        memcpy(s->wft, wft0, (size_t)nt * sizeof *s->wft);
        memcpy(s->cfw, cfw0, (size_t)nphot * sizeof *s->cfw);
        s->cam_adj = *s->c.cam;
        progress(p, "adjust", 0);
        if (!(ok = adjust_rounds(s))) break;
        int nused = 0;
        for (int q = 0; q < p->control_count; q++) nused += s->ctl_use[q];
        if (p->control_count == 0 || nused < 4) break;
        double worst_s = 0;
        int worst = worst_control(s, nused, &worst_s);
        if (worst < 0) break;
        out->controls[worst].outlier = true;
        s->ctl_use[worst] = false;
        mr_log(MR_LOG_WARN, "map: control point %s disagrees by %.1f sigma: left out", p->controls[worst].name, worst_s);
        if (nused - 1 < 3) {
            ok = mr_fail(s->err, MR_ERR_INVALID,
                         "map: control point %s is an outlier (%.1f sigma) and fewer than 3 remain",
                         p->controls[worst].name, worst_s);
            break;
        }
        for (int q = 0; q < p->control_count; q++)
            if (s->ctl_use[q]) {
                for (int a = 0; a < 3; a++) out->controls[q].loo[a] = NAN;
                out->controls[q].loo_sigma = NAN;
            }
    }
    free(wft0);
    free(cfw0);
    return ok;
}

/* Step 9: the adjustment (with leave-one-out and control outliers), or
 * with no_adjust the initial map's reprojection RMS. */
static bool adjust(map_state *s) {
    const ctx_t *c = &s->c;
    mr_map_result *out = s->out;
    s->cam_adj = *c->cam;
    s->cov = malloc((size_t)s->nt * 36 * sizeof *s->cov);
    if (!s->cov) return nomem(s);
    for (int i = 0; i < 36 * s->nt; i++) s->cov[i] = NAN;
    if (!c->p->no_adjust) {
        if (!adjust_with_controls(s)) return false;
    } else {
        double ss = 0;
        int n = 0;
        for (int i = 0; i < c->nobs; i++) {
            const obs_t *o = &c->obs[i];
            if (!o->use) continue;
            mr_dmat4 wfc = mr_m4_invert_rigid(&s->cfw[s->photo_slot[o->photo]]);
            double r = obs_rms_px(c->cam, o, c->size[o->tag], &wfc, &s->wft[s->tag_of[o->tag]]);
            ss += r * r;
            n++;
        }
        out->rms_px = n ? sqrt(ss / n) : 0;
        out->sigma_px = NAN;
    }
    out->camera = s->cam_adj;
    out->refined_intrinsics = out->adjusted && c->p->refine_intrinsics;
    return true;
}

/* Step 10: the tags (pose, covariance, sigmas, reprojection RMS) and the
 * control points' residuals. */
static bool fill_result(map_state *s) {
    const ctx_t *c = &s->c;
    const mr_map_params *p = c->p;
    mr_map_result *out = s->out;
    out->tags = calloc((size_t)s->nt + 1, sizeof *out->tags);
    out->unplaced = malloc((size_t)s->nt * sizeof *out->unplaced + 1);
    if (!out->tags || !out->unplaced) return nomem(s);
    int nk = 0;
    for (int i = 0; i < c->ntags; i++) {
        int ti = s->tag_of[i];
        if (ti < 0) continue;
        mr_map_tag *t = &out->tags[nk];
        t->id = c->ids[i];
        t->size = c->size[i];
        t->world_from_tag = s->wft[ti];
        double ss = 0;
        int n = 0;
        for (int k = 0; k < c->nobs; k++) {
            const obs_t *o = &c->obs[k];
            if (!o->use || o->tag != i) continue;
            mr_dmat4 wfc = mr_m4_invert_rigid(&s->cfw[s->photo_slot[o->photo]]);
            double r = obs_rms_px(&out->camera, o, t->size, &wfc, &t->world_from_tag);
            ss += r * r;
            n++;
        }
        /* Every sighting left and none came back: its place is a guess
         * (the fixed tag of a tag-fixed gauge stays: it is given). */
        if (n == 0 && !(c->p->control_count == 0 && i == s->root)) {
            out->unplaced[out->unplaced_count++] = t->id;
            memset(t, 0, sizeof *t);
            continue;
        }
        nk++;
        t->photos = n;
        t->rms_px = n ? sqrt(ss / n) : NAN;
        out->observations += n;
        memcpy(t->cov, &s->cov[36 * ti], sizeof t->cov);
        double tr = 0, rr = 0;
        for (int a = 0; a < 3; a++) {
            rr += t->cov[7 * a];
            tr += t->cov[7 * (a + 3)];
            t->sigma_xyz[a] = sqrt(t->cov[7 * (a + 3)]);
        }
        t->sigma_pos = sqrt(tr);
        t->sigma_deg = sqrt(rr) * DEG;
    }
    out->tag_count = nk;
    for (int q = 0; q < p->control_count; q++) {
        mr_map_control_result *cr = &out->controls[q];
        cr->used = s->ctl_use[q];
        if (s->ctl_tag[q] < 0 || s->tag_of[s->ctl_tag[q]] < 0) continue;
        mr_dvec3 pr = mr_m4_point(&s->wft[s->tag_of[s->ctl_tag[q]]], tag_point(c->size[s->ctl_tag[q]], p->controls[q].corner));
        cr->residual[0] = pr.x - p->controls[q].world.x;
        cr->residual[1] = pr.y - p->controls[q].world.y;
        cr->residual[2] = pr.z - p->controls[q].world.z;
    }
    return true;
}

bool mr_map_build(const mr_camera *cam, const mr_map_photo *photos, int photo_count, const mr_map_params *params,
                  mr_map_result *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!check_inputs(cam, photos, photo_count, params, err)) return false;
    out->photos_total = photo_count;
    out->camera = *cam;
    out->control_count = params->control_count;
    map_state s = {.c = {.cam = cam, .p = params}, .photos = photos, .photo_count = photo_count, .out = out, .err = err};
    bool ok = collect_tags(&s) && collect_sightings(&s) && connect_tags(&s) && choose_part(&s) && spanning_tree(&s) &&
              (params->no_adjust || average_poses(&s)) && apply_gauge(&s) && photo_poses(&s) && adjust(&s) &&
              fill_result(&s);
    /* A stop (SIGINT/SIGTERM) ends the adjustment at its next iteration;
     * whatever step noticed it, the map is not finished. */
    if (mr_stop_requested() && (ok || !err || err->code != MR_ERR_INTERRUPTED))
        ok = mr_fail(err, MR_ERR_INTERRUPTED, "interrupted while building the map; nothing written");
    map_state_free(&s);
    if (!ok) mr_map_result_free(out);
    return ok;
}
