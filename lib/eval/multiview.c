/* Cross-view agreement of a per-pixel quantity (AO): what view a computed
 * for a surface point against what view b computed for the same point,
 * found through b's depth. */
#include "mr_eval.h"

#include <math.h>
#include <string.h>

bool mr_eval_view_consistency(const mr_view *va, const mr_image *depth_a, const mr_image *val_a, const mr_view *vb,
                              const mr_image *depth_b, const mr_image *val_b, double rel_tol,
                              mr_view_consistency *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    const mr_image *im[4] = {depth_a, val_a, depth_b, val_b};
    for (int k = 0; k < 4; k++)
        if (!im[k]->data || im[k]->type != MR_PIX_F32 || im[k]->channels != 1)
            return mr_fail(err, MR_ERR_INVALID, "consistency needs F32x1 depth and value images");
    if (depth_a->width != val_a->width || depth_a->height != val_a->height || depth_b->width != val_b->width ||
        depth_b->height != val_b->height)
        return mr_fail(err, MR_ERR_INVALID, "consistency: depth and value images differ in size");
    if (!(rel_tol > 0)) rel_tol = 0.01;
    mr_camera ca = mr_camera_resized(&va->camera, depth_a->width, depth_a->height);
    mr_camera cb = mr_camera_resized(&vb->camera, depth_b->width, depth_b->height);
    /* a_from_b in double: the views may sit far from the world origin. */
    mr_dmat4 a_from_world = mr_m4_invert_rigid(&va->world_from_camera);
    mr_dmat4 a_from_b = mr_m4_mul(&a_from_world, &vb->world_from_camera);
    const float *da = depth_a->data, *db = depth_b->data, *fa = val_a->data, *fb = val_b->data;
    double sum = 0;
    long n = 0, seen = 0;
    for (int y = 0; y < depth_b->height; y++)
        for (int x = 0; x < depth_b->width; x++) {
            double z = db[(size_t)y * depth_b->width + x];
            if (!(z > 0) || !isfinite(z)) continue;
            seen++;
            mr_dvec3 pb = mr_v3((x - cb.cx) / cb.fx * z, (y - cb.cy) / cb.fy * z, z);
            mr_dvec3 pa = mr_m4_point(&a_from_b, pb);
            if (!(pa.z > 0)) continue;
            double u = ca.fx * pa.x / pa.z + ca.cx, v = ca.fy * pa.y / pa.z + ca.cy;
            int qx = (int)floor(u + 0.5), qy = (int)floor(v + 0.5);
            if (qx < 0 || qy < 0 || qx >= depth_a->width || qy >= depth_a->height) continue;
            double za = da[(size_t)qy * depth_a->width + qx];
            if (!(fabs(za - pa.z) <= rel_tol * pa.z)) continue; /* hidden from a, or a silhouette */
            double e = (double)fa[(size_t)qy * depth_a->width + qx] - fb[(size_t)y * depth_b->width + x];
            sum += e * e;
            n++;
        }
    out->pixels = n;
    out->fraction = seen ? (double)n / seen : 0;
    out->rmse = n ? sqrt(sum / n) : NAN;
    return true;
}
