/* Image metrics (RMSE, SSIM, signed bias) and PNG montages (the plots are
 * in plot.c). */
#include "mr_eval.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool is_f32x1(const mr_image *a) { return a && a->data && a->type == MR_PIX_F32 && a->channels == 1; }
static bool is_u8x3(const mr_image *a) { return a && a->data && a->type == MR_PIX_U8 && a->channels == 3; }

/* Separable Gaussian (sigma 1.5, 11 taps) with clamp-to-edge borders. */
static void gauss11(const double *in, double *tmp, double *out, int w, int h) {
    double k[11], s = 0;
    for (int i = 0; i < 11; i++) s += k[i] = exp(-(i - 5) * (i - 5) / (2 * 1.5 * 1.5));
    for (int i = 0; i < 11; i++) k[i] /= s;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double a = 0;
            for (int i = 0; i < 11; i++) {
                int xx = x + i - 5;
                xx = xx < 0 ? 0 : xx >= w ? w - 1 : xx;
                a += k[i] * in[(size_t)y * w + xx];
            }
            tmp[(size_t)y * w + x] = a;
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double a = 0;
            for (int i = 0; i < 11; i++) {
                int yy = y + i - 5;
                yy = yy < 0 ? 0 : yy >= h ? h - 1 : yy;
                a += k[i] * tmp[(size_t)yy * w + x];
            }
            out[(size_t)y * w + x] = a;
        }
}

bool mr_image_compare(const mr_image *a, const mr_image *ref, const mr_image *mask, mr_image_metrics *out,
                      mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!is_f32x1(a) || !is_f32x1(ref) || a->width != ref->width || a->height != ref->height ||
        (mask && (!is_f32x1(mask) || mask->width != a->width || mask->height != a->height)))
        return mr_fail(err, MR_ERR_INVALID, "image compare needs F32x1 images of one size");
    int w = a->width, h = a->height;
    size_t n = (size_t)w * h;
    const float *pa = a->data, *pr = ref->data, *pm = mask ? mask->data : NULL;
    double *buf = malloc(n * 8 * sizeof *buf);
    if (!buf) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    double *x = buf, *y = buf + n, *xx = buf + 2 * n, *yy = buf + 3 * n, *xy = buf + 4 * n, *tmp = buf + 5 * n;
    double se = 0, sb = 0, mx = 0;
    long long cnt = 0;
    for (size_t i = 0; i < n; i++) {
        double va = pa[i], vr = pr[i];
        bool bad = !isfinite(va) || !isfinite(vr);
        x[i] = bad ? 0 : va;
        y[i] = bad ? 1 : vr;
        if (pm && !(pm[i] > 0)) continue;
        double d = bad ? 1.0 : va - vr;
        se += d * d;
        sb += d;
        if (fabs(d) > mx) mx = fabs(d);
        cnt++;
    }
    for (size_t i = 0; i < n; i++) {
        xx[i] = x[i] * x[i];
        yy[i] = y[i] * y[i];
        xy[i] = x[i] * y[i];
    }
    /* Local statistics, in place: mu_x, mu_y, E[x^2], E[y^2], E[xy]. */
    double *bufs[5] = {x, y, xx, yy, xy};
    double *res = malloc(n * sizeof *res);
    if (!res) {
        free(buf);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int k = 0; k < 5; k++) {
        gauss11(bufs[k], tmp, res, w, h);
        memcpy(bufs[k], res, n * sizeof *res);
    }
    free(res);
    const double C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
    double ss = 0;
    long long sc = 0;
    for (size_t i = 0; i < n; i++) {
        if (pm && !(pm[i] > 0)) continue;
        double mx_ = x[i], my = y[i];
        double vx = xx[i] - mx_ * mx_, vy = yy[i] - my * my, cxy = xy[i] - mx_ * my;
        ss += ((2 * mx_ * my + C1) * (2 * cxy + C2)) / ((mx_ * mx_ + my * my + C1) * (vx + vy + C2));
        sc++;
    }
    free(buf);
    out->count = cnt;
    out->rmse = cnt ? sqrt(se / cnt) : 0;
    out->bias = cnt ? sb / cnt : 0;
    out->max_abs = mx;
    out->ssim = sc ? ss / sc : 1;
    return true;
}

/* ------------------------------------------------------------ image
 * difference off depth edges (definition at mr_image_diff_depth). */

static bool has_surface(float z) { return isfinite(z) && z > 0; }

/* Inverse depth, affine in the pixel coordinates on any plane. */
static double inv_depth(const float *z, int w, int x, int y) { return 1.0 / (double)z[(size_t)y * w + x]; }

/* A depth-edge pixel (see mr_image_diff_depth): coverage differs within
 * its 3x3 neighbourhood, or along one of the 4 directions through it the
 * inverse depth bends by more than rel of its own (second difference; a
 * plane has none, however grazing, while a step between two surfaces gives
 * the step on both sides of it). On the image border, where a direction has
 * one neighbour, the second difference of p and the next two pixels inwards
 * stands in. */
static bool depth_edge(const float *z, int w, int h, int x, int y, double rel) {
    bool sc = has_surface(z[(size_t)y * w + x]);
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            int xx = x + dx, yy = y + dy;
            if (xx >= 0 && yy >= 0 && xx < w && yy < h && has_surface(z[(size_t)yy * w + xx]) != sc) return true;
        }
    if (!sc) return false;
    static const int dirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
    double wc = inv_depth(z, w, x, y);
    for (int k = 0; k < 4; k++) {
        int ddx = dirs[k][0], ddy = dirs[k][1];
        for (int side = 0; side < 3; side++) {
            /* centred, else one-sided from p towards the inside */
            int s0 = side == 0 ? -1 : side == 1 ? 0 : -2, xs = x + s0 * ddx, ys = y + s0 * ddy;
            int xe = xs + 2 * ddx, ye = ys + 2 * ddy;
            if (xs < 0 || ys < 0 || xs >= w || ys >= h || xe < 0 || ye < 0 || xe >= w || ye >= h) continue;
            /* (the 3x3 pixels have surfaces here; a pixel two away without
             * one is the edge of that pixel's neighbours, not p's) */
            if (!has_surface(z[(size_t)ys * w + xs]) || !has_surface(z[(size_t)ye * w + xe])) continue;
            double bend = inv_depth(z, w, xs, ys) - 2 * inv_depth(z, w, xs + ddx, ys + ddy) + inv_depth(z, w, xe, ye);
            if (fabs(bend) > rel * wc) return true;
            break; /* the first triple that fits decides */
        }
    }
    return false;
}

bool mr_image_diff_depth(const mr_image *a, const mr_image *depth_a, const mr_image *b, const mr_image *depth_b,
                         const mr_image_diff_params *params, mr_image_diff *out, mr_error *err) {
    const mr_image_diff_params dflt = MR_IMAGE_DIFF_DEFAULTS;
    mr_image_diff_params p = params ? *params : dflt;
    memset(out, 0, sizeof *out);
    if (!is_u8x3(a) || !is_u8x3(b) || !is_f32x1(depth_a) || !is_f32x1(depth_b))
        return mr_fail(err, MR_ERR_INVALID, "image difference needs RGB8 colour and F32x1 depth images");
    int w = a->width, h = a->height;
    if (b->width != w || b->height != h || depth_a->width != w || depth_a->height != h || depth_b->width != w ||
        depth_b->height != h)
        return mr_fail(err, MR_ERR_INVALID, "image difference needs images of one size");
    if (!(p.tolerance >= 0) || !(p.depth_rel >= 0))
        return mr_fail(err, MR_ERR_INVALID, "image difference: tolerance and depth step must be >= 0");
    /* Differences of 8-bit values: above tolerance * 255 (rounded down, so
     * 8/255 means "more than 8"). */
    int tol = (int)floor(p.tolerance * 255.0 + 1e-9);
    const unsigned char *pa = a->data, *pb = b->data;
    const float *za = depth_a->data, *zb = depth_b->data;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            if (depth_edge(za, w, h, x, y, p.depth_rel) || depth_edge(zb, w, h, x, y, p.depth_rel)) {
                out->edge++;
                continue;
            }
            for (int c = 0; c < 3; c++)
                if (abs((int)pa[3 * i + c] - (int)pb[3 * i + c]) > tol) {
                    out->differ++;
                    break;
                }
        }
    out->pixels = (long long)w * h;
    out->differ_pct = out->pixels ? 100.0 * (double)out->differ / (double)out->pixels : 0;
    out->edge_pct = out->pixels ? 100.0 * (double)out->edge / (double)out->pixels : 0;
    return true;
}

bool mr_montage_png(const char *path, const mr_image *const *images, int count, int cols, int tile_w, int tile_h,
                    mr_error *err) {
    if (count <= 0 || cols <= 0 || tile_w <= 0 || tile_h <= 0) return mr_fail(err, MR_ERR_INVALID, "empty montage");
    int rows = (count + cols - 1) / cols, gap = 2, ch = 1;
    for (int k = 0; k < count; k++)
        if (is_u8x3(images[k])) ch = 3;
    mr_image m = {0};
    if (!mr_image_alloc(&m, cols * (tile_w + gap), rows * (tile_h + gap), ch, MR_PIX_U8, err)) return false;
    memset(m.data, 255, mr_image_bytes(&m));
    unsigned char *d = m.data;
    for (int k = 0; k < count; k++) {
        const mr_image *im = images[k];
        bool rgb = is_u8x3(im);
        if (!rgb && !is_f32x1(im)) continue;
        int ox = (k % cols) * (tile_w + gap), oy = (k / cols) * (tile_h + gap);
        for (int y = 0; y < tile_h; y++)
            for (int x = 0; x < tile_w; x++) {
                size_t si = (size_t)(y * im->height / tile_h) * im->width + (size_t)(x * im->width / tile_w);
                unsigned char *o = d + ((size_t)(oy + y) * m.width + ox + x) * ch;
                if (rgb) {
                    memcpy(o, (const unsigned char *)im->data + si * 3, 3);
                    continue;
                }
                float v = ((const float *)im->data)[si];
                v = isfinite(v) ? (v < 0 ? 0 : v > 1 ? 1 : v) : 0;
                memset(o, (unsigned char)lrintf(v * 255.0f), (size_t)ch);
            }
    }
    bool ok = mr_image_save_png(path, &m, err);
    mr_image_free(&m);
    return ok;
}
