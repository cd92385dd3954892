/* A real feature from taps in several tracked frames: linear triangulation
 * (closest point to the rays), Gauss-Newton on the reprojection error with
 * each tap weighted by its noise and its pose's uncertainty, and the
 * point's covariance. */
#include "mr_track.h"

#include <math.h>
#include <string.h>

static bool solve3(const double A[9], const double b[3], double x[3]) {
    double d = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
               A[2] * (A[3] * A[7] - A[4] * A[6]);
    double s = fabs(A[0]) + fabs(A[4]) + fabs(A[8]);
    if (!(fabs(d) > 1e-15 * s * s * s)) return false;
    double inv[9] = {(A[4] * A[8] - A[5] * A[7]) / d, (A[2] * A[7] - A[1] * A[8]) / d, (A[1] * A[5] - A[2] * A[4]) / d,
                     (A[5] * A[6] - A[3] * A[8]) / d, (A[0] * A[8] - A[2] * A[6]) / d, (A[2] * A[3] - A[0] * A[5]) / d,
                     (A[3] * A[7] - A[4] * A[6]) / d, (A[1] * A[6] - A[0] * A[7]) / d, (A[0] * A[4] - A[1] * A[3]) / d};
    for (int r = 0; r < 3; r++) x[r] = inv[3 * r] * b[0] + inv[3 * r + 1] * b[1] + inv[3 * r + 2] * b[2];
    return true;
}

static bool inv3(const double A[9], double out[9]) {
    double e[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, col[3];
    for (int c = 0; c < 3; c++) {
        if (!solve3(A, e[c], col)) return false;
        for (int r = 0; r < 3; r++) out[3 * r + c] = col[r];
    }
    return true;
}

/* Pixel of world point X in tap t's camera and its 2x3 Jacobian in X and
 * 2x6 in the pose perturbation (mr_pose.cov's: camera axes, w then tau). */
static bool project(const mr_camera *cam, const mr_tap *t, mr_dvec3 X, double uv[2], double JX[2][3], double JP[2][6]) {
    mr_dmat4 cfw = mr_m4_invert_rigid(&t->world_from_camera);
    mr_dvec3 q = mr_m4_point(&cfw, X);
    if (!(q.z > 1e-9)) return false;
    double iz = 1 / q.z, x = q.x * iz, y = q.y * iz, xd, yd;
    mr_camera_distort(cam, x, y, &xd, &yd);
    uv[0] = cam->fx * xd + cam->cx;
    uv[1] = cam->fy * yd + cam->cy;
    /* The lens's local scale by a finite difference (the distortion model
     * is smooth; 1e-7 in normalised units is far below a pixel). */
    const double h = 1e-7;
    double xa, ya, xb, yb;
    mr_camera_distort(cam, x + h, y, &xa, &ya);
    mr_camera_distort(cam, x, y + h, &xb, &yb);
    double D[2][2] = {{cam->fx * (xa - xd) / h, cam->fx * (xb - xd) / h}, {cam->fy * (ya - yd) / h, cam->fy * (yb - yd) / h}};
    double Pq[2][3];
    for (int r = 0; r < 2; r++) {
        Pq[r][0] = D[r][0] * iz;
        Pq[r][1] = D[r][1] * iz;
        Pq[r][2] = -(D[r][0] * x + D[r][1] * y) * iz;
    }
    for (int r = 0; r < 2; r++) {
        for (int c = 0; c < 3; c++) /* dq/dX = R_cw */
            JX[r][c] = Pq[r][0] * cfw.m[c] + Pq[r][1] * cfw.m[4 + c] + Pq[r][2] * cfw.m[8 + c];
        /* dq = w x q + tau: d/dw = q x P (see pose.c). */
        const double *P = Pq[r];
        JP[r][0] = q.y * P[2] - q.z * P[1];
        JP[r][1] = q.z * P[0] - q.x * P[2];
        JP[r][2] = q.x * P[1] - q.y * P[0];
        JP[r][3] = P[0];
        JP[r][4] = P[1];
        JP[r][5] = P[2];
    }
    return true;
}

bool mr_triangulate(const mr_camera *cam, const mr_tap *taps, int n, const mr_triangulate_params *params,
                    mr_triangulation *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_triangulate_params p = params ? *params : (mr_triangulate_params)MR_TRIANGULATE_DEFAULTS;
    double sig = p.tap_sigma_px > 0 ? p.tap_sigma_px : MR_TRIANGULATE_DEFAULT_TAP_SIGMA_PX,
           min_angle = p.min_angle_deg > 0 ? p.min_angle_deg : MR_TRIANGULATE_DEFAULT_MIN_ANGLE_DEG;
    if (!cam || (n > 0 && !taps)) return mr_fail(err, MR_ERR_INVALID, "triangulate: bad arguments");
    if (n < 2) return mr_fail(err, MR_ERR_INVALID, "triangulate: %d tap(s); a point needs taps in 2 or more frames", n);
    if (!mr_camera_validate(cam, err)) return false;
    /* Rays: centre c_i, direction d_i (world). */
    double A[9] = {0}, b[3] = {0};
    mr_dvec3 dir[64];
    if (n > 64) return mr_fail(err, MR_ERR_INVALID, "triangulate: at most 64 taps (got %d)", n);
    for (int i = 0; i < n; i++) {
        const mr_tap *t = &taps[i];
        double x, y;
        if (!isfinite(t->px[0]) || !isfinite(t->px[1]) || !mr_m4_is_finite(&t->world_from_camera) ||
            !mr_camera_undistort(cam, (t->px[0] - cam->cx) / cam->fx, (t->px[1] - cam->cy) / cam->fy, &x, &y))
            return mr_fail(err, MR_ERR_INVALID, "triangulate: tap %d: pixel (%g, %g) is not usable", i + 1, t->px[0], t->px[1]);
        mr_dvec3 d = mr_v3_normalize(mr_m4_dir(&t->world_from_camera, mr_v3(x, y, 1)));
        mr_dvec3 c = mr_v3(t->world_from_camera.m[3], t->world_from_camera.m[7], t->world_from_camera.m[11]);
        dir[i] = d;
        double dd[3] = {d.x, d.y, d.z}, cc[3] = {c.x, c.y, c.z};
        for (int r = 0; r < 3; r++)
            for (int k = 0; k < 3; k++) {
                double m = (r == k) - dd[r] * dd[k];
                A[3 * r + k] += m;
                b[r] += m * cc[k];
            }
    }
    double angle = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            double c = mr_v3_dot(dir[i], dir[j]);
            angle = fmax(angle, acos(c > 1 ? 1 : c < -1 ? -1 : c) * 180 / M_PI);
        }
    out->angle_deg = angle;
    if (angle < min_angle)
        return mr_fail(err, MR_ERR_INVALID,
                       "triangulate: baseline angle %.2f deg < %.1f deg: the taps were taken from nearly the same pose",
                       angle, min_angle);
    double X[3];
    if (!solve3(A, b, X)) return mr_fail(err, MR_ERR_INVALID, "triangulate: the rays do not meet");
    mr_dvec3 P = mr_v3(X[0], X[1], X[2]);
    /* Gauss-Newton with per-tap weights W_i = (sig^2 I + JP C JP^T)^-1. */
    double H[9];
    for (int it = 0; it < 10; it++) {
        double g[3] = {0};
        memset(H, 0, sizeof H);
        for (int i = 0; i < n; i++) {
            double uv[2], JX[2][3], JP[2][6];
            if (!project(cam, &taps[i], P, uv, JX, JP))
                return mr_fail(err, MR_ERR_INVALID, "triangulate: the point is behind the camera of tap %d", i + 1);
            double S[4] = {sig * sig, 0, 0, sig * sig};
            const double *pc = taps[i].pose_cov, *pm = taps[i].pose_cov_map;
            if (pc)
                for (int r = 0; r < 2; r++)
                    for (int c = 0; c < 2; c++)
                        for (int a = 0; a < 6; a++)
                            for (int e = 0; e < 6; e++)
                                S[2 * r + c] += JP[r][a] * (pc[6 * a + e] - (pm ? pm[6 * a + e] : 0)) * JP[c][e];
            double det = S[0] * S[3] - S[1] * S[2];
            double W[4] = {S[3] / det, -S[1] / det, -S[2] / det, S[0] / det};
            double res[2] = {uv[0] - taps[i].px[0], uv[1] - taps[i].px[1]};
            for (int a = 0; a < 3; a++) {
                for (int e = 0; e < 3; e++)
                    for (int r = 0; r < 2; r++)
                        for (int c = 0; c < 2; c++) H[3 * a + e] += JX[r][a] * W[2 * r + c] * JX[c][e];
                for (int r = 0; r < 2; r++)
                    for (int c = 0; c < 2; c++) g[a] += JX[r][a] * W[2 * r + c] * res[c];
            }
        }
        double step[3];
        if (!solve3(H, g, step)) return mr_fail(err, MR_ERR_INVALID, "triangulate: degenerate geometry");
        P = mr_v3(P.x - step[0], P.y - step[1], P.z - step[2]);
        if (sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]) < 1e-12 * (1 + mr_v3_len(P))) break;
    }
    if (!inv3(H, out->cov)) return mr_fail(err, MR_ERR_INVALID, "triangulate: degenerate geometry");
    /* The map's part: every ray moved by the same world displacement d
     * moves the point by d, so its covariance is that of d, taken as the
     * mean over the taps of their map part carried to the point (camera
     * frame A = [-[q]x | I], then to the world by R^T). */
    for (int i = 0; i < n; i++) {
        const double *pm = taps[i].pose_cov_map;
        if (!pm || !taps[i].pose_cov) continue;
        mr_dmat4 cfw = mr_m4_invert_rigid(&taps[i].world_from_camera);
        mr_dvec3 q = mr_m4_point(&cfw, P);
        double Aq[3][6] = {{0, q.z, -q.y, 1, 0, 0}, {-q.z, 0, q.x, 0, 1, 0}, {q.y, -q.x, 0, 0, 0, 1}}, M[3][6];
        for (int r = 0; r < 3; r++) /* world rows: R^T A */
            for (int a = 0; a < 6; a++) M[r][a] = cfw.m[r] * Aq[0][a] + cfw.m[4 + r] * Aq[1][a] + cfw.m[8 + r] * Aq[2][a];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) {
                double v = 0;
                for (int a = 0; a < 6; a++)
                    for (int e = 0; e < 6; e++) v += M[r][a] * pm[6 * a + e] * M[c][e];
                out->cov[3 * r + c] += v / n;
            }
    }
    double ss = 0;
    for (int i = 0; i < n; i++) {
        double uv[2], JX[2][3], JP[2][6];
        if (!project(cam, &taps[i], P, uv, JX, JP))
            return mr_fail(err, MR_ERR_INVALID, "triangulate: the point is behind the camera of tap %d", i + 1);
        ss += (uv[0] - taps[i].px[0]) * (uv[0] - taps[i].px[0]) + (uv[1] - taps[i].px[1]) * (uv[1] - taps[i].px[1]);
    }
    out->point = P;
    out->sigma = sqrt(fmax(0, out->cov[0] + out->cov[4] + out->cov[8]));
    out->rms_px = sqrt(ss / (2 * n));
    if (!isfinite(out->sigma) || !isfinite(P.x) || !isfinite(P.y) || !isfinite(P.z))
        return mr_fail(err, MR_ERR_INVALID, "triangulate: no finite solution");
    return true;
}

void mr_triangulation_distance(const mr_triangulation *t, mr_dvec3 planned, double *dist, double *sigma) {
    mr_dvec3 d = mr_v3_sub(t->point, planned);
    double len = mr_v3_len(d);
    *dist = len;
    if (!(len > 0)) {
        *sigma = sqrt((t->cov[0] + t->cov[4] + t->cov[8]) / 3);
        return;
    }
    double u[3] = {d.x / len, d.y / len, d.z / len}, v = 0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) v += u[r] * t->cov[3 * r + c] * u[c];
    *sigma = sqrt(fmax(v, 0));
}
