/* Camera pose from AprilTag detections against the marker map. */
#include "track_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_TAGS 64
#define MAX_CAND (2 * MAX_TAGS + 1)

void mr_rotvec_to_mat(const double rv[3], double R[9]) {
    double th = sqrt(rv[0] * rv[0] + rv[1] * rv[1] + rv[2] * rv[2]);
    double x = 0, y = 0, z = 0, s = sin(th), c = cos(th), C = 1 - c;
    if (th > 1e-12) {
        x = rv[0] / th;
        y = rv[1] / th;
        z = rv[2] / th;
    } else {
        /* First order: R = I + [rv]x. */
        R[0] = 1; R[1] = -rv[2]; R[2] = rv[1];
        R[3] = rv[2]; R[4] = 1; R[5] = -rv[0];
        R[6] = -rv[1]; R[7] = rv[0]; R[8] = 1;
        return;
    }
    R[0] = c + x * x * C;     R[1] = x * y * C - z * s; R[2] = x * z * C + y * s;
    R[3] = y * x * C + z * s; R[4] = c + y * y * C;     R[5] = y * z * C - x * s;
    R[6] = z * x * C - y * s; R[7] = z * y * C + x * s; R[8] = c + z * z * C;
}

void mr_mat_to_rotvec(const double R[9], double rv[3]) {
    double tr = R[0] + R[4] + R[8];
    double c = 0.5 * (tr - 1);
    c = c > 1 ? 1 : c < -1 ? -1 : c;
    double v[3] = {R[7] - R[5], R[2] - R[6], R[3] - R[1]};
    double s2 = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); /* = 2 sin(th) */
    /* atan2, not acos(c): near c = 1 acos turns rounding in the trace into
     * ~1e-8 rad, so a rotation of 1e-16 read as 1.5e-8 (and the pose
     * filter, stepping by a fraction of it, drifted at rest). */
    double th = atan2(0.5 * s2, c);
    if (th < 1e-9) {
        rv[0] = 0.5 * v[0];
        rv[1] = 0.5 * v[1];
        rv[2] = 0.5 * v[2];
        return;
    }
    if (th > M_PI - 1e-4 || s2 < 1e-9) {
        /* Near pi the antisymmetric part vanishes: take the axis from the
         * largest diagonal of (R + I) / 2 = a a^T. */
        double a[3];
        int k = R[0] >= R[4] && R[0] >= R[8] ? 0 : R[4] >= R[8] ? 1 : 2;
        double d = sqrt(fmax(0.0, 0.5 * (R[4 * k] + 1)));
        a[k] = d;
        for (int j = 0; j < 3; j++)
            if (j != k) a[j] = d > 1e-12 ? 0.5 * (R[3 * k + j] + R[3 * j + k]) / (2 * d) : 0;
        /* Sign from the (small) antisymmetric part, if any. */
        if (a[0] * v[0] + a[1] * v[1] + a[2] * v[2] < 0) { a[0] = -a[0]; a[1] = -a[1]; a[2] = -a[2]; }
        double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int j = 0; j < 3; j++) rv[j] = n > 0 ? a[j] / n * th : 0;
        return;
    }
    for (int j = 0; j < 3; j++) rv[j] = v[j] / s2 * th;
}

double mr_pose_dist(const mr_dmat4 *a, const mr_dmat4 *b) {
    return mr_v3_len(mr_v3(a->m[3] - b->m[3], a->m[7] - b->m[7], a->m[11] - b->m[11]));
}

double mr_pose_angle_deg(const mr_dmat4 *a, const mr_dmat4 *b) {
    /* angle of Ra^T Rb from its trace */
    double tr = 0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) tr += a->m[r * 4 + c] * b->m[r * 4 + c];
    double c = 0.5 * (tr - 1);
    c = c > 1 ? 1 : c < -1 ? -1 : c;
    return acos(c) * 180.0 / M_PI;
}

bool mr_project_point(const mr_camera *cam, const mr_dmat4 *wfc, mr_dvec3 p, double *u, double *v) {
    mr_dmat4 cfw = mr_m4_invert_rigid(wfc);
    mr_dvec3 q = mr_m4_point(&cfw, p);
    if (!(q.z > 1e-12 * (fabs(q.x) + fabs(q.y) + 1e-300))) return false;
    double xd, yd;
    mr_camera_distort(cam, q.x / q.z, q.y / q.z, &xd, &yd);
    *u = cam->fx * xd + cam->cx;
    *v = cam->fy * yd + cam->cy;
    return true;
}

/* camera_from_world as R (row-major 3x3) + t. */
typedef struct rt { double R[9], t[3]; } rt;

static mr_dmat4 rt_to_m4(const rt *x) {
    mr_dmat4 m = mr_m4_identity();
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) m.m[r * 4 + c] = x->R[r * 3 + c];
        m.m[r * 4 + 3] = x->t[r];
    }
    return m;
}

static rt m4_to_rt(const mr_dmat4 *m) {
    rt x;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) x.R[r * 3 + c] = m->m[r * 4 + c];
        x.t[r] = m->m[r * 4 + 3];
    }
    return x;
}

typedef struct tag_obs {
    int id;
    double world[4][3];  /* corners in the world */
    double norm[4][2];   /* undistorted normalised image points */
    double centre[3];    /* the tag's centre in the world */
    double C[36];        /* its map covariance (mr_marker.cov) */
    bool has_cov;        /* C is not all 0 */
} tag_obs;

/* RMS reprojection error of one tag under camera_from_world x, in pixels
 * (normalised residuals scaled by the focal lengths); INFINITY if a corner
 * is behind the camera. */
static double tag_rms(const mr_camera *cam, const rt *x, const tag_obs *o) {
    double s = 0;
    for (int k = 0; k < 4; k++) {
        const double *p = o->world[k];
        double q[3];
        for (int r = 0; r < 3; r++) q[r] = x->R[3 * r] * p[0] + x->R[3 * r + 1] * p[1] + x->R[3 * r + 2] * p[2] + x->t[r];
        if (!(q[2] > 0)) return INFINITY;
        double du = cam->fx * (q[0] / q[2] - o->norm[k][0]), dv = cam->fy * (q[1] / q[2] - o->norm[k][1]);
        s += du * du + dv * dv;
    }
    return sqrt(s / 4);
}

typedef struct cand {
    rt x;
    int inliers;
    double sse;      /* sum of squared per-tag RMS over inliers */
    double rms;      /* RMS over inlier corners */
} cand;

static void score(const mr_camera *cam, const tag_obs *obs, int n, double outlier_px, cand *c) {
    c->inliers = 0;
    c->sse = 0;
    for (int i = 0; i < n; i++) {
        double e = tag_rms(cam, &c->x, &obs[i]);
        if (e <= outlier_px) {
            c->inliers++;
            c->sse += e * e;
        }
    }
    c->rms = c->inliers ? sqrt(c->sse / c->inliers) : INFINITY;
}

static bool refine(const tag_obs *obs, const bool *use, int n, rt *x) {
    double o[MAX_TAGS * 12], p[MAX_TAGS * 8];
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (!use[i]) continue;
        for (int k = 0; k < 4; k++) {
            memcpy(&o[3 * m], obs[i].world[k], 3 * sizeof(double));
            memcpy(&p[2 * m], obs[i].norm[k], 2 * sizeof(double));
            m++;
        }
    }
    return m >= 4 && mr_cv_refine_lm(o, p, m, x->R, x->t);
}

static void covariance(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, double outlier_px, double prior,
                       mr_pose *out);

/* A lone tag's two mirror poses: the one kept is wrong with the
 * likelihood p of the other (its corner residuals' chi-square against the
 * kept one's), so the kept pose's mean squared error is its covariance
 * plus p d d^T, d the step from it to the other (mr_pose.cov's
 * perturbation). Without it the covariance is that of one branch alone,
 * and a flipped pose claims millimetres it is metres off. */
static void mirror_spread(const rt *x, const cand *other, double sse_kept, mr_pose *out) {
    double s2 = out->corner_sigma_px * out->corner_sigma_px;
    double dchi = 4 * (other->sse - sse_kept) / s2; /* sse: squared per-tag RMS, 4 corners each */
    double p = dchi > 80 ? 0 : 1 / (1 + exp(0.5 * dchi));
    double Rd[9], d[6];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            Rd[3 * r + c] = other->x.R[3 * r] * x->R[3 * c] + other->x.R[3 * r + 1] * x->R[3 * c + 1] +
                            other->x.R[3 * r + 2] * x->R[3 * c + 2];
    mr_mat_to_rotvec(Rd, d);
    for (int r = 0; r < 3; r++)
        d[3 + r] = other->x.t[r] - (Rd[3 * r] * x->t[0] + Rd[3 * r + 1] * x->t[1] + Rd[3 * r + 2] * x->t[2]);
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) out->cov[6 * a + b] += p * d[a] * d[b];
}
static void weighted_refine(const mr_camera *cam, const tag_obs *obs, int n, double outlier_px, double prior, rt *x);

bool mr_pose_solve(const mr_camera *cam, const mr_marker_map *map, const mr_detection *dets, int count,
                   const mr_pose *prev, const mr_pose_params *params, mr_pose *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    out->world_from_camera = mr_m4_identity();
    if (!cam || !map || (count > 0 && !dets) || count < 0) return mr_fail(err, MR_ERR_INVALID, "pose: bad arguments");
    if (!mr_camera_validate(cam, err)) return false;
    mr_pose_params p = params ? *params : (mr_pose_params)MR_POSE_DEFAULTS;
    double outlier_px = p.outlier_px > 0 ? p.outlier_px : 3.0;
    double max_rms = p.max_rms_px > 0 ? p.max_rms_px : 4.0;
    double amb_px = p.ambiguity_px > 0 ? p.ambiguity_px : 0.1;
    double amb_ratio = p.ambiguity_ratio > 1 ? p.ambiguity_ratio : 2.5;
    double min_tag = p.min_tag_px > 0 ? p.min_tag_px : 8.0;

    tag_obs obs[MAX_TAGS];
    int n = 0;
    for (int i = 0; i < count && n < MAX_TAGS; i++) {
        const mr_marker *m = mr_marker_map_find(map, dets[i].id);
        if (!m) continue;
        /* One detection per id: the detector sorts by id, best first. */
        if (n > 0 && obs[n - 1].id == dets[i].id) continue;
        out->tags_seen++;
        double edge = INFINITY;
        bool ok = true;
        for (int k = 0; k < 4; k++) {
            const double *a = dets[i].corners[k], *b = dets[i].corners[(k + 1) % 4];
            if (!isfinite(a[0]) || !isfinite(a[1])) ok = false;
            edge = fmin(edge, hypot(b[0] - a[0], b[1] - a[1]));
        }
        if (!ok || edge < min_tag) continue;
        tag_obs *o = &obs[n];
        o->id = dets[i].id;
        mr_dvec3 w[4];
        mr_marker_corners_world(map, m, w);
        for (int k = 0; k < 4 && ok; k++) {
            o->world[k][0] = w[k].x;
            o->world[k][1] = w[k].y;
            o->world[k][2] = w[k].z;
            ok = mr_camera_undistort(cam, (dets[i].corners[k][0] - cam->cx) / cam->fx,
                                     (dets[i].corners[k][1] - cam->cy) / cam->fy, &o->norm[k][0], &o->norm[k][1]);
        }
        o->centre[0] = m->world_from_tag.m[3];
        o->centre[1] = m->world_from_tag.m[7];
        o->centre[2] = m->world_from_tag.m[11];
        o->has_cov = false;
        for (int k = 0; k < 36; k++) {
            o->C[k] = isfinite(m->cov[k]) ? m->cov[k] : 0;
            o->has_cov = o->has_cov || o->C[k] != 0;
        }
        if (ok) n++;
    }
    if (n == 0) return true;

    /* Candidates: both IPPE solutions of every tag, in world terms. */
    cand cands[MAX_CAND];
    int nc = 0;
    for (int i = 0; i < n; i++) {
        double R[2][9], t[2][3];
        double img8[8];
        memcpy(img8, obs[i].norm, sizeof img8);
        const mr_marker *m = mr_marker_map_find(map, obs[i].id);
        /* Each tag's own size (maps of mixed sizes). */
        mr_dvec3 tc[4];
        mr_marker_corners_tag(mr_marker_size(map, m), tc);
        double objt[12];
        for (int k = 0; k < 4; k++) {
            objt[3 * k] = tc[k].x;
            objt[3 * k + 1] = tc[k].y;
            objt[3 * k + 2] = tc[k].z;
        }
        int ns = mr_cv_ippe_square(objt, img8, R, t);
        mr_dmat4 tfw = mr_m4_invert_rigid(&m->world_from_tag);
        for (int s = 0; s < ns; s++) {
            rt ct;
            memcpy(ct.R, R[s], sizeof ct.R);
            memcpy(ct.t, t[s], sizeof ct.t);
            mr_dmat4 cft = rt_to_m4(&ct);
            mr_dmat4 cfw = mr_m4_mul(&cft, &tfw);
            cands[nc].x = m4_to_rt(&cfw);
            score(cam, obs, n, outlier_px, &cands[nc]);
            nc++;
        }
    }
    /* And, with several tags, one global SQPnP start over all corners
     * (it may beat every single-tag start when the tags are small). */
    if (n >= 2) {
        double o[MAX_TAGS * 12], q[MAX_TAGS * 8];
        for (int i = 0; i < n; i++) {
            memcpy(&o[12 * i], obs[i].world, sizeof obs[i].world);
            memcpy(&q[8 * i], obs[i].norm, sizeof obs[i].norm);
        }
        if (mr_cv_sqpnp(o, q, 4 * n, cands[nc].x.R, cands[nc].x.t)) {
            score(cam, obs, n, outlier_px, &cands[nc]);
            nc++;
        }
    }
    int best = -1;
    for (int c = 0; c < nc; c++)
        if (cands[c].inliers > 0 &&
            (best < 0 || cands[c].inliers > cands[best].inliers ||
             (cands[c].inliers == cands[best].inliers && cands[c].rms < cands[best].rms)))
            best = c;
    if (best < 0) return true;
    /* Plausible alternatives: as many inlier tags and an error within the
     * ambiguity margin (ratio and slack: the wrong branch of a single tag
     * typically fits 2-4 times worse, a truly ambiguous one about as well).
     * If they differ in rotation, prefer the previous pose's neighbour, so a
     * tag seen head-on does not flip; a clearly better fit still wins, so a
     * wrong start does not stick. */
    bool have_prev = prev && prev->valid;
    mr_dmat4 prev_cfw = have_prev ? mr_m4_invert_rigid(&prev->world_from_camera) : mr_m4_identity();
    mr_dmat4 best_m = rt_to_m4(&cands[best].x);
    int pick = best;
    double pick_angle = have_prev ? mr_pose_angle_deg(&best_m, &prev_cfw) : 0;
    for (int c = 0; c < nc; c++) {
        if (c == best || cands[c].inliers != cands[best].inliers ||
            cands[c].rms > fmax(amb_ratio * cands[best].rms, cands[best].rms + amb_px))
            continue;
        mr_dmat4 cm = rt_to_m4(&cands[c].x);
        if (mr_pose_angle_deg(&cm, &best_m) < 2.0) continue;
        out->ambiguous = true;
        if (have_prev) {
            double a = mr_pose_angle_deg(&cm, &prev_cfw);
            if (a < pick_angle) {
                pick_angle = a;
                pick = c;
            }
        }
    }
    /* The picked pose's strongest rival: the best fitting plausible
     * candidate turned 2 degrees or more from it. */
    int alt = -1;
    if (out->ambiguous) {
        mr_dmat4 pm = rt_to_m4(&cands[pick].x);
        for (int c = 0; c < nc; c++) {
            if (c == pick || cands[c].inliers != cands[best].inliers ||
                cands[c].rms > fmax(amb_ratio * cands[best].rms, cands[best].rms + amb_px))
                continue;
            mr_dmat4 cm = rt_to_m4(&cands[c].x);
            if (mr_pose_angle_deg(&cm, &pm) >= 2.0 && (alt < 0 || cands[c].sse < cands[alt].sse)) alt = c;
        }
    }
    /* Refine over the inlier tags; drop tags that still do not fit and
     * refine once more. */
    rt x = cands[pick].x;
    bool use[MAX_TAGS];
    /* A lone ambiguous tag: IPPE's solution is already the local optimum,
     * and the error valley between the two mirror poses is so flat that LM
     * may slide into the other one; keep the chosen branch as it is. */
    bool lone = cands[pick].inliers == 1 && out->ambiguous;
    for (int round = 0; round < 2 && !lone; round++) {
        int nu = 0;
        for (int i = 0; i < n; i++) nu += use[i] = tag_rms(cam, &x, &obs[i]) <= outlier_px * (round ? 1.0 : 1.5);
        if (nu == 0) return true;
        rt y = x;
        if (refine(obs, use, n, &y)) x = y;
    }
    /* With map uncertainty the least-squares optimum above weighs a badly
     * mapped tag like a good one: refine again under each tag's weight. */
    if (!lone) weighted_refine(cam, obs, n, outlier_px, p.corner_sigma_px, &x);
    double sse = 0;
    int used = 0;
    for (int i = 0; i < n; i++) {
        double e = tag_rms(cam, &x, &obs[i]);
        if (e > outlier_px) continue;
        sse += e * e;
        if (used < MR_POSE_MAX_IDS) out->ids_used[used] = obs[i].id;
        used++;
    }
    if (used == 0) return true;
    out->tags_used = used;
    out->rms_px = sqrt(sse / used);
    mr_dmat4 cfw = rt_to_m4(&x);
    out->world_from_camera = mr_m4_invert_rigid(&cfw);
    out->valid = out->rms_px <= max_rms && mr_m4_is_finite(&out->world_from_camera);
    if (out->valid) covariance(cam, &x, obs, n, outlier_px, p.corner_sigma_px, out);
    if (out->valid && lone && alt >= 0 && out->corner_sigma_px > 0) mirror_spread(&x, &cands[alt], cands[pick].sse, out);
    return true;
}

/* In-place inverse of a symmetric positive definite n x n matrix, n <= 8
 * (Gauss-Jordan with partial pivoting); false if singular. */
static bool invert_n(double *a, int n) {
    double inv[64];
    for (int i = 0; i < n * n; i++) inv[i] = (i / n == i % n) ? 1 : 0;
    double scale = 0;
    for (int i = 0; i < n; i++) scale = fmax(scale, fabs(a[i * n + i]));
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int r = c + 1; r < n; r++)
            if (fabs(a[r * n + c]) > fabs(a[piv * n + c])) piv = r;
        if (!(fabs(a[piv * n + c]) > 1e-14 * scale)) return false;
        for (int k = 0; k < n; k++) {
            double t = a[c * n + k];
            a[c * n + k] = a[piv * n + k];
            a[piv * n + k] = t;
            t = inv[c * n + k];
            inv[c * n + k] = inv[piv * n + k];
            inv[piv * n + k] = t;
        }
        double d = a[c * n + c];
        for (int k = 0; k < n; k++) {
            a[c * n + k] /= d;
            inv[c * n + k] /= d;
        }
        for (int r = 0; r < n; r++) {
            if (r == c) continue;
            double f = a[r * n + c];
            if (f == 0) continue;
            for (int k = 0; k < n; k++) {
                a[r * n + k] -= f * a[c * n + k];
                inv[r * n + k] -= f * inv[c * n + k];
            }
        }
    }
    memcpy(a, inv, (size_t)n * n * sizeof *a);
    return true;
}

/* One tag under camera_from_world x: its 8 pixel residuals e (projection
 * minus detection; the lens only rescales them locally), their Jacobian J
 * in the pose perturbation (mr_pose.cov's: X_cam -> exp([w]x) X_cam + tau)
 * and B in the tag's map perturbation (mr_marker.cov's: corner X ->
 * X + w_m x (X - centre) + dc). false if a corner is behind the camera. */
static bool tag_jac(const mr_camera *cam, const rt *x, const tag_obs *o, double e[8], double J[8][6], double B[8][6]) {
    for (int k = 0; k < 4; k++) {
        const double *p = o->world[k];
        double q[3];
        for (int r = 0; r < 3; r++) q[r] = x->R[3 * r] * p[0] + x->R[3 * r + 1] * p[1] + x->R[3 * r + 2] * p[2] + x->t[r];
        if (!(q[2] > 0)) return false;
        double iz = 1 / q[2], u = q[0] * iz, v = q[1] * iz;
        e[2 * k] = cam->fx * (u - o->norm[k][0]);
        e[2 * k + 1] = cam->fy * (v - o->norm[k][1]);
        /* d(pixel)/dq, then dq/d(w, tau) = [-[q]x | I]. */
        double Pu[3] = {cam->fx * iz, 0, -cam->fx * u * iz}, Pv[3] = {0, cam->fy * iz, -cam->fy * v * iz};
        double a[3] = {p[0] - o->centre[0], p[1] - o->centre[1], p[2] - o->centre[2]};
        for (int row = 0; row < 2; row++) {
            const double *P = row ? Pv : Pu;
            double *Jr = J[2 * k + row], *Br = B[2 * k + row];
            /* P . (-[q]x w) = P . (w x q) = w . (q x P) */
            Jr[0] = q[1] * P[2] - q[2] * P[1];
            Jr[1] = q[2] * P[0] - q[0] * P[2];
            Jr[2] = q[0] * P[1] - q[1] * P[0];
            Jr[3] = P[0];
            Jr[4] = P[1];
            Jr[5] = P[2];
            /* The world displacement dX reaches the pixel through
             * g = R^T P; g . (w_m x a) = w_m . (a x g). */
            double g[3];
            for (int c = 0; c < 3; c++) g[c] = P[0] * x->R[c] + P[1] * x->R[3 + c] + P[2] * x->R[6 + c];
            Br[0] = a[1] * g[2] - a[2] * g[1];
            Br[1] = a[2] * g[0] - a[0] * g[2];
            Br[2] = a[0] * g[1] - a[1] * g[0];
            Br[3] = g[0];
            Br[4] = g[1];
            Br[5] = g[2];
        }
    }
    return true;
}

/* W = (s2 I + B C B^T)^-1, the tag's 8x8 weight. */
static bool tag_weight(const tag_obs *o, const double B[8][6], double s2, double W[64]) {
    for (int r = 0; r < 8; r++)
        for (int c = 0; c < 8; c++) {
            double v = r == c ? s2 : 0;
            if (o->has_cov)
                for (int a = 0; a < 6; a++) {
                    if (B[r][a] == 0) continue;
                    for (int b = 0; b < 6; b++) v += B[r][a] * o->C[6 * a + b] * B[c][b];
                }
            W[8 * r + c] = v;
        }
    return invert_n(W, 8);
}

/* The tags the covariance and the weighted solve use: the inliers. */
static int inliers(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, double outlier_px, bool *use,
                   bool *any_cov) {
    int m = 0;
    *any_cov = false;
    for (int i = 0; i < n; i++) {
        use[i] = tag_rms(cam, x, &obs[i]) <= outlier_px;
        m += use[i];
        *any_cov = *any_cov || (use[i] && obs[i].has_cov);
    }
    return m;
}

/* The weighted residuals' chi-square under corner noise s. */
static double chi2(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, const bool *use, double s) {
    double sum = 0, e[8], J[8][6], B[8][6], W[64];
    for (int i = 0; i < n; i++) {
        if (!use[i]) continue;
        if (!tag_jac(cam, x, &obs[i], e, J, B) || !tag_weight(&obs[i], B, s * s, W)) return INFINITY;
        for (int r = 0; r < 8; r++)
            for (int c = 0; c < 8; c++) sum += e[r] * W[8 * r + c] * e[c];
    }
    return sum;
}

/* The corner noise: without map uncertainty the dof-corrected residual
 * RMS; with it, the s whose chi-square equals the degrees of freedom
 * (chi-square falls as s grows, and at the plain RMS it is at most the
 * dof, so the root lies below it); never below the floor. */
static double corner_sigma_fit(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, const bool *use, int m,
                               bool any_cov);
/* ... pooled with the known noise `prior` (0: none) as MR_POSE_PRIOR_DOF
 * more degrees of freedom. */
static double corner_sigma(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, const bool *use, int m,
                           bool any_cov, double prior) {
    double s = corner_sigma_fit(cam, x, obs, n, use, m, any_cov), dof = 8.0 * m - 6;
    if (!(prior > 0)) return s;
    return fmax(sqrt((dof * s * s + MR_POSE_PRIOR_DOF * prior * prior) / (dof + MR_POSE_PRIOR_DOF)),
                MR_POSE_MIN_CORNER_SIGMA_PX);
}

static double corner_sigma_fit(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, const bool *use, int m,
                               bool any_cov) {
    double dof = 8.0 * m - 6, sse = 0, e[8], J[8][6], B[8][6];
    for (int i = 0; i < n; i++) {
        if (!use[i] || !tag_jac(cam, x, &obs[i], e, J, B)) continue;
        for (int r = 0; r < 8; r++) sse += e[r] * e[r];
    }
    double s0 = sqrt(sse / dof), lo = MR_POSE_MIN_CORNER_SIGMA_PX;
    if (!(s0 > lo)) return lo;
    if (!any_cov) return s0;
    if (chi2(cam, x, obs, n, use, lo) <= dof) return lo;
    double hi = s0;
    for (int it = 0; it < 40 && hi / lo > 1 + 1e-6; it++) {
        double mid = sqrt(lo * hi);
        if (chi2(cam, x, obs, n, use, mid) > dof)
            lo = mid;
        else
            hi = mid;
    }
    return hi;
}

/* The normal matrix N = sum J^T W J (and, with g, the gradient J^T W e) of
 * the weighted problem; with Mmap, the map part's sum K C K^T, K = J^T W B. */
static bool normal(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, const bool *use, double s,
                   double N[36], double g[6], double Mmap[36]) {
    memset(N, 0, 36 * sizeof *N);
    if (g) memset(g, 0, 6 * sizeof *g);
    if (Mmap) memset(Mmap, 0, 36 * sizeof *Mmap);
    double e[8], J[8][6], B[8][6], W[64];
    for (int i = 0; i < n; i++) {
        if (!use[i]) continue;
        if (!tag_jac(cam, x, &obs[i], e, J, B) || !tag_weight(&obs[i], B, s * s, W)) return false;
        double WJ[8][6];
        for (int r = 0; r < 8; r++)
            for (int a = 0; a < 6; a++) {
                double v = 0;
                for (int c = 0; c < 8; c++) v += W[8 * r + c] * J[c][a];
                WJ[r][a] = v;
            }
        for (int a = 0; a < 6; a++) {
            for (int b = 0; b < 6; b++)
                for (int r = 0; r < 8; r++) N[6 * a + b] += J[r][a] * WJ[r][b];
            if (g)
                for (int r = 0; r < 8; r++) g[a] += WJ[r][a] * e[r];
        }
        if (Mmap && obs[i].has_cov) {
            double K[6][6] = {{0}}, KC[6][6] = {{0}};
            for (int a = 0; a < 6; a++)
                for (int b = 0; b < 6; b++)
                    for (int r = 0; r < 8; r++) K[a][b] += WJ[r][a] * B[r][b];
            for (int a = 0; a < 6; a++)
                for (int b = 0; b < 6; b++)
                    for (int c = 0; c < 6; c++) KC[a][b] += K[a][c] * obs[i].C[6 * c + b];
            for (int a = 0; a < 6; a++)
                for (int b = 0; b < 6; b++)
                    for (int c = 0; c < 6; c++) Mmap[6 * a + b] += KC[a][c] * K[b][c];
        }
    }
    return true;
}

/* Gauss-Newton on the weighted problem from the plain optimum x (a few
 * steps: the weights change the answer by a fraction of its sigma). Only
 * with map uncertainty: otherwise the weights are uniform and x is it. */
static void weighted_refine(const mr_camera *cam, const tag_obs *obs, int n, double outlier_px, double prior, rt *x) {
    bool use[MAX_TAGS], any_cov;
    int m = inliers(cam, x, obs, n, outlier_px, use, &any_cov);
    if (!any_cov || m < 1) return;
    for (int round = 0; round < 2; round++) {
        double s = corner_sigma(cam, x, obs, n, use, m, any_cov, prior);
        for (int it = 0; it < 5; it++) {
            double N[36], g[6];
            if (!normal(cam, x, obs, n, use, s, N, g, NULL) || !invert_n(N, 6)) return;
            double d[6] = {0};
            for (int a = 0; a < 6; a++)
                for (int b = 0; b < 6; b++) d[a] -= N[6 * a + b] * g[b];
            double Rw[9];
            mr_rotvec_to_mat(d, Rw);
            rt y;
            for (int r = 0; r < 3; r++) {
                for (int c = 0; c < 3; c++)
                    y.R[3 * r + c] = Rw[3 * r] * x->R[c] + Rw[3 * r + 1] * x->R[3 + c] + Rw[3 * r + 2] * x->R[6 + c];
                y.t[r] = Rw[3 * r] * x->t[0] + Rw[3 * r + 1] * x->t[1] + Rw[3 * r + 2] * x->t[2] + d[3 + r];
            }
            bool fin = true;
            for (int k = 0; k < 9; k++) fin = fin && isfinite(y.R[k]);
            if (!fin) return;
            *x = y;
            double step = 0;
            for (int a = 0; a < 6; a++) step += d[a] * d[a];
            if (step < 1e-24) break;
        }
    }
}

/* Covariance of the solved pose: the weighted problem's N^-1 over the
 * inlier tags (each tag weighed by its corner noise and its map
 * covariance), with the corner noise estimated from the residuals; and the
 * map's part of it, N^-1 (sum K C K^T) N^-1. */
static void covariance(const mr_camera *cam, const rt *x, const tag_obs *obs, int n, double outlier_px, double prior,
                       mr_pose *out) {
    bool use[MAX_TAGS], any_cov;
    int m = inliers(cam, x, obs, n, outlier_px, use, &any_cov);
    if (8 * m <= 6) return;
    double s = corner_sigma(cam, x, obs, n, use, m, any_cov, prior);
    double N[36], Mmap[36];
    if (!normal(cam, x, obs, n, use, s, N, NULL, Mmap) || !invert_n(N, 6)) return;
    out->corner_sigma_px = s;
    memcpy(out->cov, N, sizeof out->cov);
    if (!any_cov) return;
    double T[36] = {0};
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
            for (int c = 0; c < 6; c++) T[6 * a + b] += N[6 * a + c] * Mmap[6 * c + b];
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) {
            double v = 0;
            for (int c = 0; c < 6; c++) v += T[6 * a + c] * N[6 * c + b];
            out->cov_map[6 * a + b] = v;
        }
}

bool mr_pose_point_sigma(const mr_pose *pose, mr_dvec3 world_point, double *sigma_3d, double *sigma_lateral) {
    if (!pose || !pose->valid || !(pose->corner_sigma_px > 0)) return false;
    mr_dmat4 cfw = mr_m4_invert_rigid(&pose->world_from_camera);
    mr_dvec3 q = mr_m4_point(&cfw, world_point);
    if (!(q.z > 0)) return false;
    /* dq = -[q]x w + tau: A = [-[q]x | I], C = A cov A^T. */
    double A[3][6] = {{0, q.z, -q.y, 1, 0, 0}, {-q.z, 0, q.x, 0, 1, 0}, {q.y, -q.x, 0, 0, 0, 1}};
    double C[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double v = 0;
            for (int a = 0; a < 6; a++)
                for (int b = 0; b < 6; b++) v += A[r][a] * pose->cov[6 * a + b] * A[c][b];
            C[r][c] = v;
        }
    double tr = C[0][0] + C[1][1] + C[2][2];
    double len = sqrt(q.x * q.x + q.y * q.y + q.z * q.z), d[3] = {q.x / len, q.y / len, q.z / len};
    double along = 0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) along += d[r] * C[r][c] * d[c];
    if (sigma_3d) *sigma_3d = sqrt(fmax(tr, 0));
    if (sigma_lateral) *sigma_lateral = sqrt(fmax(tr - along, 0));
    return isfinite(tr);
}

void mr_pose_fusion_reset(mr_pose_fusion *f) { memset(f, 0, sizeof *f); }

/* The step from camera_from_world a to b as mr_pose.cov's perturbation:
 * b = exp([w]x) a + tau. */
static void pose_step(const mr_dmat4 *a, const mr_dmat4 *b, double d[6]) {
    rt x = m4_to_rt(a), y = m4_to_rt(b);
    double Rd[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            Rd[3 * r + c] = y.R[3 * r] * x.R[3 * c] + y.R[3 * r + 1] * x.R[3 * c + 1] + y.R[3 * r + 2] * x.R[3 * c + 2];
    mr_mat_to_rotvec(Rd, d);
    for (int r = 0; r < 3; r++) d[3 + r] = y.t[r] - (Rd[3 * r] * x.t[0] + Rd[3 * r + 1] * x.t[1] + Rd[3 * r + 2] * x.t[2]);
}

/* A pose's own part of its covariance as information; false if singular. */
static bool own_info(const mr_pose *p, double I[36]) {
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) {
            double v = 0.5 * (p->cov[6 * a + b] + p->cov[6 * b + a] - p->cov_map[6 * a + b] - p->cov_map[6 * b + a]);
            I[6 * a + b] = v;
        }
    return invert_n(I, 6);
}

static bool fusion_start(mr_pose_fusion *f, const mr_pose *p) {
    mr_pose_fusion_reset(f);
    if (!own_info(p, f->info)) return false;
    f->ref = mr_m4_invert_rigid(&p->world_from_camera);
    memcpy(f->map_sum, p->cov_map, sizeof f->map_sum);
    f->pose = *p;
    f->frames = 1;
    return true;
}

bool mr_pose_fusion_add(mr_pose_fusion *f, const mr_pose *p) {
    if (!p || !p->valid || !(p->corner_sigma_px > 0)) {
        mr_pose_fusion_reset(f);
        return false;
    }
    if (f->frames < 1) return fusion_start(f, p);
    double Ii[36], d[6], C[36], e[6];
    mr_dmat4 cfw = mr_m4_invert_rigid(&p->world_from_camera);
    pose_step(&f->ref, &cfw, d);
    /* The gate: this frame against the fused estimate, own parts only (the
     * map part is common to both). */
    memcpy(C, f->info, sizeof C);
    if (!own_info(p, Ii) || !invert_n(C, 6)) {
        fusion_start(f, p);
        return false;
    }
    double est[6] = {0};
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) est[a] += C[6 * a + b] * f->info_d[b];
    double S[36];
    for (int a = 0; a < 6; a++) {
        e[a] = d[a] - est[a];
        for (int b = 0; b < 6; b++)
            S[6 * a + b] = C[6 * a + b] + 0.5 * (p->cov[6 * a + b] + p->cov[6 * b + a] - p->cov_map[6 * a + b] -
                                                 p->cov_map[6 * b + a]);
    }
    if (!invert_n(S, 6)) {
        fusion_start(f, p);
        return false;
    }
    double m2 = 0;
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) m2 += e[a] * S[6 * a + b] * e[b];
    if (!(m2 <= MR_POSE_FUSION_GATE)) {
        fusion_start(f, p);
        return false;
    }
    for (int a = 0; a < 6; a++) {
        for (int b = 0; b < 6; b++) {
            f->info[6 * a + b] += Ii[6 * a + b];
            f->info_d[a] += Ii[6 * a + b] * d[b];
        }
    }
    for (int k = 0; k < 36; k++) f->map_sum[k] += p->cov_map[k];
    f->frames++;
    /* The fused pose: the information-weighted step from the reference. */
    memcpy(C, f->info, sizeof C);
    if (!invert_n(C, 6)) {
        fusion_start(f, p);
        return false;
    }
    double dh[6] = {0};
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) dh[a] += C[6 * a + b] * f->info_d[b];
    double Rw[9];
    mr_rotvec_to_mat(dh, Rw);
    rt x = m4_to_rt(&f->ref), y;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++)
            y.R[3 * r + c] = Rw[3 * r] * x.R[c] + Rw[3 * r + 1] * x.R[3 + c] + Rw[3 * r + 2] * x.R[6 + c];
        y.t[r] = Rw[3 * r] * x.t[0] + Rw[3 * r + 1] * x.t[1] + Rw[3 * r + 2] * x.t[2] + dh[3 + r];
    }
    mr_pose fused = *p;
    mr_dmat4 cfw_f = rt_to_m4(&y);
    fused.world_from_camera = mr_m4_invert_rigid(&cfw_f);
    for (int k = 0; k < 36; k++) {
        fused.cov_map[k] = f->map_sum[k] / f->frames;
        fused.cov[k] = C[k] + fused.cov_map[k];
    }
    f->pose = fused;
    return true;
}
