/* Double-precision vectors and 4x4 row-major matrices. World-space math is
 * always double; only camera-relative results are ever cast to float. */
#include "mr_core.h"

#include <math.h>
#include <string.h>

mr_dvec3 mr_v3_add(mr_dvec3 a, mr_dvec3 b) { return mr_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
mr_dvec3 mr_v3_sub(mr_dvec3 a, mr_dvec3 b) { return mr_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
mr_dvec3 mr_v3_scale(mr_dvec3 a, double s) { return mr_v3(a.x * s, a.y * s, a.z * s); }
double mr_v3_dot(mr_dvec3 a, mr_dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
mr_dvec3 mr_v3_cross(mr_dvec3 a, mr_dvec3 b) {
    return mr_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
double mr_v3_len(mr_dvec3 a) { return sqrt(mr_v3_dot(a, a)); }
mr_dvec3 mr_v3_normalize(mr_dvec3 a) {
    double l = mr_v3_len(a);
    return l > 0 && isfinite(l) ? mr_v3_scale(a, 1.0 / l) : mr_v3(0, 0, 0);
}

mr_dmat4 mr_m4_identity(void) {
    mr_dmat4 r;
    memset(&r, 0, sizeof r);
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0;
    return r;
}

mr_dmat4 mr_m4_mul(const mr_dmat4 *a, const mr_dmat4 *b) {
    mr_dmat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += a->m[i * 4 + k] * b->m[k * 4 + j];
            r.m[i * 4 + j] = s;
        }
    return r;
}

mr_dmat4 mr_m4_translate(double x, double y, double z) {
    mr_dmat4 r = mr_m4_identity();
    r.m[3] = x; r.m[7] = y; r.m[11] = z;
    return r;
}

mr_dmat4 mr_m4_scale(double x, double y, double z) {
    mr_dmat4 r = mr_m4_identity();
    r.m[0] = x; r.m[5] = y; r.m[10] = z;
    return r;
}

mr_dmat4 mr_m4_from_quat(double x, double y, double z, double w) {
    /* Normalise: exporters write quaternions with float round-off. */
    double n = sqrt(x * x + y * y + z * z + w * w);
    if (!(n > 0) || !isfinite(n)) return mr_m4_identity();
    x /= n; y /= n; z /= n; w /= n;
    mr_dmat4 r = mr_m4_identity();
    r.m[0] = 1 - 2 * (y * y + z * z); r.m[1] = 2 * (x * y - z * w);     r.m[2] = 2 * (x * z + y * w);
    r.m[4] = 2 * (x * y + z * w);     r.m[5] = 1 - 2 * (x * x + z * z); r.m[6] = 2 * (y * z - x * w);
    r.m[8] = 2 * (x * z - y * w);     r.m[9] = 2 * (y * z + x * w);     r.m[10] = 1 - 2 * (x * x + y * y);
    return r;
}

mr_dmat4 mr_m4_rotate_axis(mr_dvec3 axis, double radians) {
    mr_dvec3 a = mr_v3_normalize(axis);
    double s = sin(radians * 0.5), c = cos(radians * 0.5);
    return mr_m4_from_quat(a.x * s, a.y * s, a.z * s, c);
}

mr_dmat4 mr_m4_from_trs(const double t[3], const double q[4], const double s[3]) {
    mr_dmat4 T = mr_m4_translate(t[0], t[1], t[2]);
    mr_dmat4 R = mr_m4_from_quat(q[0], q[1], q[2], q[3]);
    mr_dmat4 S = mr_m4_scale(s[0], s[1], s[2]);
    mr_dmat4 RS = mr_m4_mul(&R, &S);
    return mr_m4_mul(&T, &RS);
}

bool mr_m4_invert(const mr_dmat4 *a, mr_dmat4 *out) {
    /* Gauss-Jordan with partial pivoting on a copy. */
    double m[4][8];
    double scale = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            m[i][j] = a->m[i * 4 + j];
            m[i][j + 4] = i == j ? 1.0 : 0.0;
            if (fabs(m[i][j]) > scale) scale = fabs(m[i][j]);
        }
    if (!(scale > 0) || !isfinite(scale)) return false;
    for (int c = 0; c < 4; c++) {
        int p = c;
        for (int r = c + 1; r < 4; r++)
            if (fabs(m[r][c]) > fabs(m[p][c])) p = r;
        if (fabs(m[p][c]) <= 1e-14 * scale) return false;
        if (p != c)
            for (int j = 0; j < 8; j++) { double t = m[c][j]; m[c][j] = m[p][j]; m[p][j] = t; }
        double inv = 1.0 / m[c][c];
        for (int j = 0; j < 8; j++) m[c][j] *= inv;
        for (int r = 0; r < 4; r++) {
            if (r == c) continue;
            double f = m[r][c];
            if (f != 0)
                for (int j = 0; j < 8; j++) m[r][j] -= f * m[c][j];
        }
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) out->m[i * 4 + j] = m[i][j + 4];
    return true;
}

mr_dmat4 mr_m4_invert_rigid(const mr_dmat4 *a) {
    mr_dmat4 r = mr_m4_identity();
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) r.m[i * 4 + j] = a->m[j * 4 + i];
    for (int i = 0; i < 3; i++)
        r.m[i * 4 + 3] = -(r.m[i * 4 + 0] * a->m[3] + r.m[i * 4 + 1] * a->m[7] + r.m[i * 4 + 2] * a->m[11]);
    return r;
}

mr_dvec3 mr_m4_point(const mr_dmat4 *a, mr_dvec3 p) {
    const double *m = a->m;
    return mr_v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
                 m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                 m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

mr_dvec3 mr_m4_dir(const mr_dmat4 *a, mr_dvec3 d) {
    const double *m = a->m;
    return mr_v3(m[0] * d.x + m[1] * d.y + m[2] * d.z,
                 m[4] * d.x + m[5] * d.y + m[6] * d.z,
                 m[8] * d.x + m[9] * d.y + m[10] * d.z);
}

bool mr_m4_is_finite(const mr_dmat4 *a) {
    for (int i = 0; i < 16; i++)
        if (!isfinite(a->m[i])) return false;
    return true;
}

bool mr_m4_is_rigid(const mr_dmat4 *a, double tol) {
    if (!mr_m4_is_finite(a)) return false;
    const double *m = a->m;
    if (fabs(m[12]) > tol || fabs(m[13]) > tol || fabs(m[14]) > tol || fabs(m[15] - 1) > tol) return false;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double d = 0;
            for (int k = 0; k < 3; k++) d += m[k * 4 + i] * m[k * 4 + j];
            if (fabs(d - (i == j ? 1.0 : 0.0)) > tol) return false;
        }
    double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                 m[2] * (m[4] * m[9] - m[5] * m[8]);
    return det > 0;
}

void mr_m4_to_gl(const mr_dmat4 *a, float out[16]) {
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) out[c * 4 + r] = (float)a->m[r * 4 + c];
}

mr_dmat4 mr_m4_look_at_cv(mr_dvec3 eye, mr_dvec3 target, mr_dvec3 up) {
    mr_dvec3 z = mr_v3_normalize(mr_v3_sub(target, eye)); /* forward */
    mr_dvec3 x = mr_v3_cross(z, up);                       /* right = forward x up */
    if (mr_v3_len(x) < 1e-12) {
        /* Looking along up: pick any perpendicular so the pose stays rigid. */
        mr_dvec3 alt = fabs(z.x) < 0.9 ? mr_v3(1, 0, 0) : mr_v3(0, 0, 1);
        x = mr_v3_cross(z, alt);
    }
    x = mr_v3_normalize(x);
    mr_dvec3 y = mr_v3_cross(z, x); /* down */
    mr_dmat4 r = mr_m4_identity();
    r.m[0] = x.x; r.m[1] = y.x; r.m[2] = z.x; r.m[3] = eye.x;
    r.m[4] = x.y; r.m[5] = y.y; r.m[6] = z.y; r.m[7] = eye.y;
    r.m[8] = x.z; r.m[9] = y.z; r.m[10] = z.z; r.m[11] = eye.z;
    return r;
}
