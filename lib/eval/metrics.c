/* Image metrics (RMSE, SSIM, signed bias) and report helpers (SVG line
 * plots, PNG montages). */
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

/* ------------------------------------------------------------- plots */

/* 16 distinguishable colours, so a plot with up to 16 series never repeats one. */
static const char *const k_colors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                       "#bcbd22", "#17becf", "#393b79", "#ad494a", "#637939", "#843c39", "#7b4173", "#000000"};

bool mr_plot_svg(const char *path, const char *title, const char *xlabel, const char *ylabel,
                 const mr_plot_series *series, int nseries, bool log_x, mr_error *err) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = 0, y1 = -INFINITY;
    for (int s = 0; s < nseries; s++)
        for (int i = 0; i < series[s].count; i++) {
            double xv = series[s].x[i], yv = series[s].y[i];
            if (!isfinite(xv) || !isfinite(yv) || (log_x && !(xv > 0))) continue;
            if (log_x) xv = log10(xv);
            if (xv < x0) x0 = xv;
            if (xv > x1) x1 = xv;
            if (yv > y1) y1 = yv;
            if (yv < y0) y0 = yv;
        }
    if (!(x1 >= x0)) { x0 = 0; x1 = 1; }
    if (!(y1 > y0)) y1 = y0 + 1;
    if (x1 - x0 < 1e-9) { x0 -= 0.5; x1 += 0.5; }
    y1 *= 1.05;
    const int W = 760, H = 480, L = 70, R = 170, T = 40, B = 50;
    double pw = W - L - R, ph = H - T - B;
    size_t cap = 16384;
    for (int s = 0; s < nseries; s++) cap += (size_t)series[s].count * 160 + 256;
    char *o = malloc(cap);
    if (!o) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    size_t len = 0;
#define OUT(...) len += (size_t)snprintf(o + len, cap - len, __VA_ARGS__)
    OUT("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" font-size=\"12\">\n", W, H);
    OUT("<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n<text x=\"%d\" y=\"22\" font-size=\"14\">%s</text>\n", L, title);
    OUT("<rect x=\"%d\" y=\"%d\" width=\"%.0f\" height=\"%.0f\" fill=\"none\" stroke=\"#444\"/>\n", L, T, pw, ph);
    for (int k = 0; k <= 4; k++) {
        double fx = x0 + (x1 - x0) * k / 4, fy = y0 + (y1 - y0) * k / 4;
        double px = L + pw * k / 4, py = T + ph - ph * k / 4;
        OUT("<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.3g</text>\n", px, H - B + 16, log_x ? pow(10, fx) : fx);
        OUT("<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%.3g</text>\n", L - 6, py + 4, fy);
        OUT("<line x1=\"%d\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", L, py, L + pw, py);
    }
    OUT("<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%s</text>\n", L + pw / 2, H - 12, xlabel);
    OUT("<text x=\"16\" y=\"%.1f\" transform=\"rotate(-90 16 %.1f)\" text-anchor=\"middle\">%s</text>\n", T + ph / 2,
        T + ph / 2, ylabel);
    for (int s = 0; s < nseries; s++) {
        const char *col = k_colors[s % 16];
        OUT("<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" points=\"", col);
        for (int i = 0; i < series[s].count; i++) {
            double xv = series[s].x[i], yv = series[s].y[i];
            if (!isfinite(xv) || !isfinite(yv) || (log_x && !(xv > 0))) continue;
            if (log_x) xv = log10(xv);
            OUT("%.1f,%.1f ", L + pw * (xv - x0) / (x1 - x0), T + ph - ph * (yv - y0) / (y1 - y0));
        }
        OUT("\"/>\n");
        for (int i = 0; i < series[s].count; i++) {
            double xv = series[s].x[i], yv = series[s].y[i];
            if (!isfinite(xv) || !isfinite(yv) || (log_x && !(xv > 0))) continue;
            if (log_x) xv = log10(xv);
            OUT("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\"/>\n", L + pw * (xv - x0) / (x1 - x0),
                T + ph - ph * (yv - y0) / (y1 - y0), col);
        }
        OUT("<rect x=\"%.0f\" y=\"%d\" width=\"12\" height=\"10\" fill=\"%s\"/><text x=\"%.0f\" y=\"%d\">%s</text>\n",
            L + pw + 14, T + 8 + 18 * s, col, L + pw + 30, T + 17 + 18 * s, series[s].name);
    }
    OUT("</svg>\n");
#undef OUT
    bool ok = len < cap ? mr_file_write_atomic(path, o, len, err) : mr_fail(err, MR_ERR_NOMEM, "plot too large");
    free(o);
    return ok;
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
