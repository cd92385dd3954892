/* The light-field display mapping: each band of columns seen from its own
 * eye on the rig's baseline, converging at the focal distance D (pure
 * functions; the G-buffer pass draws a mapped frame band by band). */
#include "mr_render.h"

#include <math.h>

mr_display_map mr_display_from_rig(const mr_rig *rig, int band) {
    mr_display_map m = {rig->distance, rig->distance * tan(0.5 * rig->cone), band > 0 ? band : MR_DISPLAY_DEFAULT_BAND};
    return m;
}

double mr_display_eye(const mr_display_map *m, int width, double u) { return (2 * (u + 0.5) / width - 1) * m->eye_half; }

mr_dvec3 mr_display_point(const mr_display_map *m, const mr_camera *cam, double u, double v, double z) {
    /* The ray of u in its band's camera: a pinhole at the band's eye e whose
     * principal point is moved by fx e / D (the rig's shear); at band 1,
     * column u's own ray. */
    int k = m->band > 0 ? m->band : 1, b = (int)floor((u + 0.5) / k), x0, x1;
    if (b < 0) b = 0;
    double e;
    mr_display_band_camera(m, cam, b, &x0, &x1, &e);
    if (k == 1) e = mr_display_eye(m, cam->width, u); /* exact between pixel centres too */
    return mr_v3((u - cam->cx - cam->fx * e / m->distance) / cam->fx * z + e, (v - cam->cy) / cam->fy * z, z);
}

bool mr_display_project(const mr_display_map *m, const mr_camera *cam, mr_dvec3 p, double *u, double *v) {
    /* u = fx X/z + cx + g e(u) with g = fx (1/D - 1/z) and e linear in u:
     * e(u) = a (u + 0.5) - E, a = 2E/W; solved for u. */
    if (!(p.z > 0)) return false;
    double a = 2 * m->eye_half / cam->width, g = cam->fx * (1 / m->distance - 1 / p.z), den = 1 - g * a;
    if (!(fabs(den) > 1e-12)) return false;
    *u = (cam->fx * p.x / p.z + cam->cx + g * (0.5 * a - m->eye_half)) / den;
    *v = cam->fy * p.y / p.z + cam->cy;
    return isfinite(*u) && isfinite(*v);
}

int mr_display_band_count(const mr_display_map *m, int width) {
    int k = m->band > 0 ? m->band : 1;
    return (width + k - 1) / k;
}

mr_camera mr_display_band_camera(const mr_display_map *m, const mr_camera *cam, int b, int *x0, int *x1, double *eye) {
    int k = m->band > 0 ? m->band : 1;
    *x0 = b * k;
    *x1 = *x0 + k < cam->width ? *x0 + k : cam->width;
    *eye = mr_display_eye(m, cam->width, 0.5 * (*x0 + *x1 - 1));
    mr_camera c = *cam;
    c.cx += cam->fx * *eye / m->distance;
    return c;
}

double mr_display_column_error(const mr_display_map *m, const mr_camera *cam, int u, double z) {
    /* The band camera's ray through column u's centre, at depth z. */
    mr_dvec3 p = mr_display_point(m, cam, u, cam->cy, z);
    double uu, vv;
    if (!mr_display_project(m, cam, p, &uu, &vv)) return NAN;
    return uu - u;
}
