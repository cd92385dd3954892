/* Legibility of hidden structure in a ghosted view, measured without the
 * ghosting's own target.
 *
 * The adaptive stage raises the saliency of G0 towards C_desired; counting
 * pixels that reach C_desired would measure the optimiser against itself.
 * Here the yardstick comes from the hidden layer D alone: its important
 * edges are the neighbour pairs (p, q) (right and down neighbours, at least
 * one of them in the ghosting region) whose colour difference in D is
 * large, gain * dE(D_p, D_q) / 100 > edge_threshold (the saliency's units,
 * so 0.5 lies above the curvature bias 0.35: a flat wall never counts).
 * For each such edge the contrast the hidden structure adds to the final
 * image F beyond the occluder O is h_F = dF - dO (CIE L*a*b* vectors of the
 * pair's difference); showing D in full (R = D in the region, O outside)
 * would add h_R = dR - dO. An edge's transfer is the part of h_F along
 * h_R, clamp(h_F . h_R / |h_R|^2, 0, 1): a change in F that does not
 * follow D's edge (the occluder's own edges strengthened, noise, an edge of
 * the wrong polarity) shows nothing of D. Legibility is the mean transfer
 * over the important edges: 0 when F is the occluder alone, 1 when F shows
 * D in full, about 1 - alpha for a plain alpha blend. Edges where D adds
 * nothing over O (|h_R| < 1 dE) are left out: there is nothing to show. */
#include "mr_eval.h"

#include <math.h>
#include <stdlib.h>

static double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4); }

static double lab_f(double t) { return t > 0.008856 ? cbrt(t) : 7.787 * t + 16.0 / 116.0; }

void mr_eval_rgb_to_lab(const double rgb[3], double lab[3]) {
    double c[3];
    for (int k = 0; k < 3; k++) c[k] = rgb[k] > 0 ? (rgb[k] < 1 ? rgb[k] : 1) : 0;
    double x = (0.412453 * c[0] + 0.357580 * c[1] + 0.180423 * c[2]) / 0.950456;
    double y = 0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2];
    double z = (0.019334 * c[0] + 0.119193 * c[1] + 0.950227 * c[2]) / 1.088754;
    double fy = lab_f(y);
    lab[0] = y > 0.008856 ? 116.0 * fy - 16.0 : 903.3 * y;
    lab[1] = 500.0 * (lab_f(x) - fy);
    lab[2] = 200.0 * (fy - lab_f(z));
}

/* Pixel i of an RGB image (U8: sRGB-encoded; F32: linear) as L*a*b*. */
static void lab_at(const mr_image *im, size_t i, double lab[3]) {
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = im->type == MR_PIX_U8 ? srgb_decode(((const unsigned char *)im->data)[i * 3 + k] / 255.0)
                                     : ((const float *)im->data)[i * 3 + k];
    mr_eval_rgb_to_lab(c, lab);
}

static bool rgb_ok(const mr_image *im, int w, int h) {
    return im && im->data && im->channels == 3 && im->width == w && im->height == h &&
           (im->type == MR_PIX_U8 || im->type == MR_PIX_F32);
}

static double norm3(const double a[3]) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

bool mr_eval_ghost_legibility(const mr_ghost_legibility_images *in, const mr_legibility_params *params,
                              mr_legibility *out, mr_error *err) {
    mr_legibility_params lp = MR_LEGIBILITY_DEFAULTS;
    if (params) lp = *params;
    out->region = out->edges = out->important = out->occluder_important = 0;
    out->important_fraction = out->legibility = out->edge_contrast = out->full_contrast = out->occluder_kept = NAN;
    if (!in || !in->final || !in->region) return mr_fail(err, MR_ERR_INVALID, "legibility: missing image");
    int w = in->final->width, h = in->final->height;
    if (!rgb_ok(in->final, w, h) || !rgb_ok(in->occluder, w, h) || !rgb_ok(in->hidden, w, h) ||
        in->region->width != w || in->region->height != h || in->region->channels != 1 ||
        in->region->type != MR_PIX_F32)
        return mr_fail(err, MR_ERR_INVALID, "legibility: final, occluder, hidden (RGB) and region (F32x1) must be %dx%d", w, h);
    if (!(lp.edge_threshold > 0) || !(lp.gain > 0))
        return mr_fail(err, MR_ERR_INVALID, "legibility: edge_threshold and gain must be > 0");
    size_t n = (size_t)w * h;
    double *lab = malloc(n * 9 * sizeof *lab); /* F, O, D per pixel */
    if (!lab) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    const float *reg = in->region->data;
    for (size_t i = 0; i < n; i++) {
        lab_at(in->final, i, lab + i * 9);
        lab_at(in->occluder, i, lab + i * 9 + 3);
        lab_at(in->hidden, i, lab + i * 9 + 6);
        if (reg[i] > 0.5f) out->region++;
    }
    double sum_leg = 0, sum_hf = 0, sum_hr = 0, sum_kept = 0;
    long long used = 0, used_o = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t p = (size_t)y * w + x;
            for (int dir = 0; dir < 2; dir++) {
                if ((dir == 0 && x + 1 >= w) || (dir == 1 && y + 1 >= h)) continue;
                size_t q = dir == 0 ? p + 1 : p + (size_t)w;
                bool in_p = reg[p] > 0.5f, in_q = reg[q] > 0.5f;
                if (!in_p && !in_q) continue;
                out->edges++;
                const double *a = lab + p * 9, *b = lab + q * 9;
                double dd[3], hf[3], hr[3], dob[3], gf[3], gr[3];
                for (int k = 0; k < 3; k++) {
                    double dO = a[3 + k] - b[3 + k];
                    dob[k] = dO;
                    dd[k] = a[6 + k] - b[6 + k];
                    hf[k] = (a[k] - b[k]) - dO;
                    /* R = D inside the region, O outside. */
                    double rp = in_p ? a[6 + k] : a[3 + k], rq = in_q ? b[6 + k] : b[3 + k];
                    hr[k] = (rp - rq) - dO;
                    gf[k] = (a[k] - b[k]) - (rp - rq);
                    gr[k] = dO - (rp - rq);
                }
                if (lp.gain * norm3(dob) / 100.0 > lp.edge_threshold) {
                    out->occluder_important++;
                    double ng = norm3(gr);
                    if (ng >= 1.0) {
                        double t = (gf[0] * gr[0] + gf[1] * gr[1] + gf[2] * gr[2]) / (ng * ng);
                        sum_kept += t > 0 ? (t < 1 ? t : 1) : 0;
                        used_o++;
                    }
                }
                if (!(lp.gain * norm3(dd) / 100.0 > lp.edge_threshold)) continue;
                out->important++;
                double nf = norm3(hf), nr = norm3(hr);
                if (!(nr >= 1.0)) continue;
                double t = (hf[0] * hr[0] + hf[1] * hr[1] + hf[2] * hr[2]) / (nr * nr);
                sum_leg += t > 0 ? (t < 1 ? t : 1) : 0;
                sum_hf += nf;
                sum_hr += nr;
                used++;
            }
        }
    free(lab);
    if (out->edges > 0) out->important_fraction = (double)out->important / (double)out->edges;
    if (used_o > 0) out->occluder_kept = sum_kept / used_o;
    if (used > 0) {
        out->legibility = sum_leg / used;
        out->edge_contrast = sum_hf / used;
        out->full_contrast = sum_hr / used;
    }
    return true;
}
