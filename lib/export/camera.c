/* The BCF camera of a pose and the snapshot that matches it: glTF's Y up to
 * BCF's Z up, the largest centred frustum of the undistorted image, square
 * pixels, the field of view of that frustum. */
#include "export_internal.h"

#include <math.h>
#include <string.h>

mr_dvec3 mr_bcf_from_gltf(mr_dvec3 p) { return mr_v3(p.x, -p.z, p.y); }

/* Normalised extents (tan of the half angles) of the largest centred
 * rectangle inside the undistorted image of cam: along each edge of the
 * raw image, the undistorted point nearest the axis bounds it. */
static bool centred_extent(const mr_camera *c, double *tx, double *ty) {
    double W = c->width, H = c->height;
    if (!mr_camera_has_distortion(c)) {
        *tx = fmin(c->cx + 0.5, W - 0.5 - c->cx) / c->fx;
        *ty = fmin(c->cy + 0.5, H - 0.5 - c->cy) / c->fy;
        return *tx > 0 && *ty > 0;
    }
    double bx = INFINITY, by = INFINITY;
    const int n = 256;
    for (int i = 0; i <= n; i++) {
        double s = (double)i / n;
        double u[4] = {-0.5, W - 0.5, -0.5 + s * W, -0.5 + s * W};
        double v[4] = {-0.5 + s * H, -0.5 + s * H, -0.5, H - 0.5};
        for (int e = 0; e < 4; e++) {
            double x, y;
            if (!mr_camera_undistort(c, (u[e] - c->cx) / c->fx, (v[e] - c->cy) / c->fy, &x, &y)) continue;
            if (e == 0) bx = fmin(bx, -x);
            if (e == 1) bx = fmin(bx, x);
            if (e == 2) by = fmin(by, -y);
            if (e == 3) by = fmin(by, y);
        }
    }
    if (!(bx > 0 && by > 0 && isfinite(bx) && isfinite(by))) return false;
    /* The edges' nearest points bound a convex-ish region; check that the
     * rectangle's corners and edge midpoints really land inside the raw
     * image and shrink until they do (strong pincushion). */
    for (int it = 0; it < 200; it++) {
        bool inside = true;
        for (int k = 0; k < 8 && inside; k++) {
            static const double sx[8] = {-1, 1, -1, 1, 0, 0, -1, 1}, sy[8] = {-1, -1, 1, 1, -1, 1, 0, 0};
            double xd, yd;
            mr_camera_distort(c, sx[k] * bx, sy[k] * by, &xd, &yd);
            double uu = c->fx * xd + c->cx, vv = c->fy * yd + c->cy;
            inside = uu >= -0.5 - 1e-6 && uu <= W - 0.5 + 1e-6 && vv >= -0.5 - 1e-6 && vv <= H - 0.5 + 1e-6;
        }
        if (inside) break;
        bx *= 0.99;
        by *= 0.99;
    }
    *tx = bx;
    *ty = by;
    return true;
}

bool mr_bcf_frame_of(const mr_camera *cam, int max_side, mr_bcf_frame *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!mr_camera_validate(cam, err)) return false;
    if (max_side <= 0) max_side = MR_EXPORT_DEFAULT_MAX_SIDE;
    double tx, ty;
    if (!centred_extent(cam, &tx, &ty))
        return mr_fail(err, MR_ERR_INVALID, "the camera's principal point lies outside its image");
    /* The finer of the two focal lengths would upsample the other axis. */
    double f = fmin(cam->fx, cam->fy);
    double w = floor(2 * tx * f), h = floor(2 * ty * f);
    double longest = fmax(w, h);
    if (longest > max_side) {
        f *= max_side / longest;
        w = floor(2 * tx * f);
        h = floor(2 * ty * f);
    }
    if (w < 1 || h < 1 || !isfinite(f))
        return mr_fail(err, MR_ERR_INVALID, "the camera leaves no centred view to export");
    out->width = (int)w;
    out->height = (int)h;
    out->f = f;
    return true;
}

mr_bcf_camera mr_bcf_camera_of(const mr_dmat4 *wc, const mr_bcf_frame *fr, double unit_m, mr_bcf_version v) {
    mr_bcf_camera c;
    memset(&c, 0, sizeof c);
    if (!(unit_m > 0)) unit_m = 1;
    const double *m = wc->m;
    mr_dvec3 pos = mr_v3(m[3] * unit_m, m[7] * unit_m, m[11] * unit_m);
    mr_dvec3 dir = mr_v3_normalize(mr_v3(m[2], m[6], m[10]));     /* camera +z */
    mr_dvec3 up = mr_v3_normalize(mr_v3(-m[1], -m[5], -m[9]));    /* camera -y */
    mr_dvec3 p = mr_bcf_from_gltf(pos), d = mr_bcf_from_gltf(dir), u = mr_bcf_from_gltf(up);
    c.view_point[0] = p.x, c.view_point[1] = p.y, c.view_point[2] = p.z;
    c.direction[0] = d.x, c.direction[1] = d.y, c.direction[2] = d.z;
    c.up[0] = u.x, c.up[1] = u.y, c.up[2] = u.z;
    double half = v == MR_BCF_3_0 ? fr->height / (2 * fr->f) : fr->width / (2 * fr->f);
    c.fov_deg = 2 * atan(half) * 180 / M_PI;
    c.aspect = (double)fr->width / fr->height;
    return c;
}

bool mr_bcf_snapshot(const mr_image *src, const mr_camera *cam, const mr_bcf_frame *fr, mr_image *out,
                     mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!src->data || src->type != MR_PIX_U8 || src->width < 2 || src->height < 2)
        return mr_fail(err, MR_ERR_INVALID, "snapshot: not an 8-bit image");
    mr_camera c = mr_camera_resized(cam, src->width, src->height);
    int ch = src->channels >= 3 ? 3 : 1;
    if (!mr_image_alloc(out, fr->width, fr->height, ch, MR_PIX_U8, err)) return false;
    uint8_t *o = out->data;
    float px[4];
    for (int j = 0; j < fr->height; j++)
        for (int i = 0; i < fr->width; i++) {
            /* The snapshot's pixel centre through its own pinhole (the centre
             * of the frame is the axis), then the camera's distortion. */
            double x = (i + 0.5 - fr->width * 0.5) / fr->f, y = (j + 0.5 - fr->height * 0.5) / fr->f;
            double xd, yd;
            mr_camera_distort(&c, x, y, &xd, &yd);
            double u = fmin(fmax(c.fx * xd + c.cx, 0), src->width - 1.0);
            double v = fmin(fmax(c.fy * yd + c.cy, 0), src->height - 1.0);
            uint8_t *q = o + ((size_t)j * fr->width + i) * ch;
            if (!mr_image_sample_bilinear(src, u, v, px)) {
                memset(q, 0, (size_t)ch);
                continue;
            }
            for (int k = 0; k < ch; k++) {
                float s = src->channels >= 3 ? px[k] : px[0];
                q[k] = (uint8_t)(s < 0 ? 0 : s > 255 ? 255 : s + 0.5f);
            }
        }
    return true;
}

/* FNV-1a over the bytes, then splitmix to spread. */
static uint64_t mix(uint64_t z) {
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

void mr_bcf_guid(const void *data, size_t n, uint64_t salt, char out[37]) {
    uint64_t h = 0xcbf29ce484222325ull ^ mix(salt);
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ull;
    uint64_t a = mix(h ^ salt), b = mix(a ^ 0x5bd1e995ull);
    /* Version 4 and the RFC 4122 variant, so tools that check accept it. */
    a = (a & ~0xf000ull) | 0x4000ull;
    b = (b & ~(0xc000000000000000ull)) | 0x8000000000000000ull;
    snprintf(out, 37, "%08x-%04x-%04x-%04x-%012llx", (unsigned)(a >> 32), (unsigned)((a >> 16) & 0xffff),
             (unsigned)(a & 0xffff), (unsigned)(b >> 48), (unsigned long long)(b & 0xffffffffffffull));
}
