/* A view for any model: the whole scene framed from a corner above it. */
#include "mr_scene.h"

#include <math.h>
#include <string.h>

mr_view mr_scene_auto_view(const mr_scene *s, int width, int height) {
    mr_view v;
    memset(&v, 0, sizeof v);
    int w = width > 0 ? width : MR_AUTO_VIEW_DEFAULT_WIDTH;
    int h = height > 0 ? height : (width > 0 ? (int)lround(width * 0.75) : MR_AUTO_VIEW_DEFAULT_HEIGHT);
    if (h < 1) h = 1;
    double f = h * 0.5 / tan(MR_AUTO_VIEW_FOV_DEG * M_PI / 360.0);
    v.camera.width = w;
    v.camera.height = h;
    v.camera.fx = v.camera.fy = f;
    v.camera.cx = (w - 1) * 0.5;
    v.camera.cy = (h - 1) * 0.5;

    /* The bounds (nothing finite: a unit box at the origin). */
    double lo[3] = {-0.5, -0.5, -0.5}, hi[3] = {0.5, 0.5, 0.5};
    bool ok = s && s->node_count > 0;
    for (int i = 0; ok && i < 3; i++) ok = isfinite(s->bounds_min[i]) && isfinite(s->bounds_max[i]) && s->bounds_min[i] <= s->bounds_max[i];
    if (ok) memcpy(lo, s->bounds_min, sizeof lo), memcpy(hi, s->bounds_max, sizeof hi);
    mr_dvec3 centre = mr_v3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(diag > 0)) diag = 1;

    /* From the corner at +x +z, MR_AUTO_VIEW_ELEVATION_DEG above the horizon
     * (Y up); the axes do not depend on the distance. */
    double el = MR_AUTO_VIEW_ELEVATION_DEG * M_PI / 180.0, az = M_PI / 4;
    mr_dvec3 back = mr_v3(cos(el) * sin(az), sin(el), cos(el) * cos(az));
    mr_dmat4 R = mr_m4_look_at_cv(mr_v3_add(centre, back), centre, mr_v3(0, 1, 0));
    mr_dvec3 X = mr_v3(R.m[0], R.m[4], R.m[8]), Y = mr_v3(R.m[1], R.m[5], R.m[9]), Z = mr_v3(R.m[2], R.m[6], R.m[10]);

    /* The distance t back from the centre at which every corner of the
     * bounds (so every point inside them) lies within the image, a margin
     * of MR_AUTO_VIEW_MARGIN of each side left free, in front of the eye. */
    double ax = (v.camera.cx - MR_AUTO_VIEW_MARGIN * w) / f, ay = (v.camera.cy - MR_AUTO_VIEW_MARGIN * h) / f;
    if (!(ax > 0)) ax = 0.5 / f;
    if (!(ay > 0)) ay = 0.5 / f;
    double t = 0;
    for (int c = 0; c < 8; c++) {
        mr_dvec3 p = mr_v3((c & 1 ? hi[0] : lo[0]) - centre.x, (c & 2 ? hi[1] : lo[1]) - centre.y, (c & 4 ? hi[2] : lo[2]) - centre.z);
        double x = mr_v3_dot(p, X), y = mr_v3_dot(p, Y), z = mr_v3_dot(p, Z);
        t = fmax(t, fabs(x) / ax - z);
        t = fmax(t, fabs(y) / ay - z);
        t = fmax(t, 1e-3 * diag - z);
    }
    mr_dvec3 eye = mr_v3_sub(centre, mr_v3_scale(Z, t));
    R.m[3] = eye.x, R.m[7] = eye.y, R.m[11] = eye.z;
    v.world_from_camera = R;
    return v;
}
