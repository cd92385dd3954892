/* Image buffers and image files (stb_image / stb_image_write from Debian's
 * libstb; PFM written by hand). All writes are atomic. */
#include "mr_core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>
#include <stb_image_write.h>

bool mr_image_alloc(mr_image *img, int w, int h, int c, mr_pixel_type type, mr_error *err) {
    memset(img, 0, sizeof *img);
    if (w < 1 || h < 1 || c < 1 || c > 4 || w > 65536 || h > 65536)
        return mr_fail(err, MR_ERR_INVALID, "image size %dx%dx%d out of range", w, h, c);
    size_t es = type == MR_PIX_F32 ? 4 : 1;
    img->data = calloc((size_t)w * (size_t)h * (size_t)c, es);
    if (!img->data) return mr_fail(err, MR_ERR_NOMEM, "out of memory for a %dx%d image", w, h);
    img->width = w;
    img->height = h;
    img->channels = c;
    img->type = type;
    return true;
}

void mr_image_free(mr_image *img) {
    if (!img) return;
    free(img->data);
    memset(img, 0, sizeof *img);
}

size_t mr_image_bytes(const mr_image *img) {
    return (size_t)img->width * (size_t)img->height * (size_t)img->channels * (img->type == MR_PIX_F32 ? 4u : 1u);
}

bool mr_image_load(const char *path, int channels, mr_image *img, mr_error *err) {
    memset(img, 0, sizeof *img);
    size_t size;
    unsigned char *bytes = mr_file_read(path, &size, (size_t)1 << 30, err);
    if (!bytes) return false;
    int w, h, c;
    unsigned char *px = size <= 0x7fffffff ? stbi_load_from_memory(bytes, (int)size, &w, &h, &c, channels) : NULL;
    free(bytes);
    if (!px) return mr_fail(err, MR_ERR_PARSE, "%s: cannot decode image (%s)", path, stbi_failure_reason());
    img->width = w;
    img->height = h;
    img->channels = channels ? channels : c;
    img->type = MR_PIX_U8;
    /* Copy into a malloc'd buffer so every mr_image is freed with free(). */
    size_t n = mr_image_bytes(img);
    img->data = malloc(n);
    if (!img->data) {
        stbi_image_free(px);
        memset(img, 0, sizeof *img);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory for %s", path);
    }
    memcpy(img->data, px, n);
    stbi_image_free(px);
    return true;
}

typedef struct membuf { unsigned char *p; size_t n, cap; bool failed; } membuf;

static void membuf_write(void *ctx, void *data, int size) {
    membuf *m = ctx;
    if (m->failed || size <= 0) return;
    if (m->n + (size_t)size > m->cap) {
        size_t cap = m->cap ? m->cap * 2 : 65536;
        while (cap < m->n + (size_t)size) cap *= 2;
        unsigned char *p = realloc(m->p, cap);
        if (!p) { m->failed = true; return; }
        m->p = p;
        m->cap = cap;
    }
    memcpy(m->p + m->n, data, (size_t)size);
    m->n += (size_t)size;
}

void *mr_image_encode_png(const mr_image *img, size_t *size, mr_error *err) {
    if (img->type != MR_PIX_U8 || !img->data) {
        mr_fail(err, MR_ERR_INVALID, "PNG needs an 8-bit image");
        return NULL;
    }
    membuf m = {0};
    int ok = stbi_write_png_to_func(membuf_write, &m, img->width, img->height, img->channels, img->data,
                                    img->width * img->channels);
    if (!ok || m.failed) {
        free(m.p);
        mr_fail(err, MR_ERR_NOMEM, "cannot encode a %dx%d PNG", img->width, img->height);
        return NULL;
    }
    *size = m.n;
    return m.p;
}

bool mr_image_save_png(const char *path, const mr_image *img, mr_error *err) {
    if (img->type != MR_PIX_U8 || !img->data) return mr_fail(err, MR_ERR_INVALID, "PNG needs an 8-bit image (%s)", path);
    size_t n = 0;
    void *p = mr_image_encode_png(img, &n, err);
    if (!p) {
        mr_error_prefix(err, "%s", path);
        return false;
    }
    bool r = mr_file_write_atomic(path, p, n, err);
    free(p);
    return r;
}

bool mr_image_save_pfm(const char *path, const mr_image *img, mr_error *err) {
    if (img->type != MR_PIX_F32 || (img->channels != 1 && img->channels != 3))
        return mr_fail(err, MR_ERR_INVALID, "PFM needs a float image with 1 or 3 channels (%s)", path);
    char header[64];
    /* Negative scale = little endian; PFM rows go bottom to top. */
    int hl = snprintf(header, sizeof header, "%s\n%d %d\n-1.0\n", img->channels == 3 ? "PF" : "Pf", img->width, img->height);
    size_t row = (size_t)img->width * (size_t)img->channels * 4;
    size_t n = (size_t)hl + row * (size_t)img->height;
    unsigned char *buf = malloc(n);
    if (!buf) return mr_fail(err, MR_ERR_NOMEM, "out of memory for %s", path);
    memcpy(buf, header, (size_t)hl);
    for (int y = 0; y < img->height; y++)
        memcpy(buf + hl + row * (size_t)y, (const unsigned char *)img->data + row * (size_t)(img->height - 1 - y), row);
    bool ok = mr_file_write_atomic(path, buf, n, err);
    free(buf);
    return ok;
}

bool mr_image_load_pfm(const char *path, mr_image *img, mr_error *err) {
    memset(img, 0, sizeof *img);
    size_t size;
    char *bytes = mr_file_read(path, &size, (size_t)1 << 31, err);
    if (!bytes) return false;
    char kind[3] = {0};
    int w = 0, h = 0, consumed = 0;
    double scale = 0;
    if (sscanf(bytes, "%2s %d %d %lf%n", kind, &w, &h, &scale, &consumed) != 4 || consumed <= 0 ||
        (strcmp(kind, "PF") && strcmp(kind, "Pf")) || w < 1 || h < 1 || w > 65536 || h > 65536 || scale >= 0) {
        free(bytes);
        return mr_fail(err, MR_ERR_PARSE, "%s: not a little-endian PFM file", path);
    }
    int c = kind[1] == 'F' ? 3 : 1;
    size_t off = (size_t)consumed + 1; /* one whitespace byte after the scale */
    size_t row = (size_t)w * (size_t)c * 4;
    if (off > size || size - off < row * (size_t)h) {
        free(bytes);
        return mr_fail(err, MR_ERR_PARSE, "%s: PFM data is truncated", path);
    }
    if (!mr_image_alloc(img, w, h, c, MR_PIX_F32, err)) { free(bytes); return false; }
    for (int y = 0; y < h; y++)
        memcpy((unsigned char *)img->data + row * (size_t)y, bytes + off + row * (size_t)(h - 1 - y), row);
    free(bytes);
    return true;
}

bool mr_image_sample_bilinear(const mr_image *img, double x, double y, float *out) {
    if (!(x >= -0.5 && y >= -0.5 && x <= img->width - 0.5 && y <= img->height - 0.5)) return false;
    int x0 = (int)floor(x), y0 = (int)floor(y);
    double fx = x - x0, fy = y - y0;
    const unsigned char *p = img->data;
    int c = img->channels;
    for (int k = 0; k < c; k++) {
        double acc = 0;
        for (int dy = 0; dy < 2; dy++)
            for (int dx = 0; dx < 2; dx++) {
                int xi = x0 + dx, yi = y0 + dy;
                if (xi < 0) xi = 0;
                if (yi < 0) yi = 0;
                if (xi >= img->width) xi = img->width - 1;
                if (yi >= img->height) yi = img->height - 1;
                double wgt = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
                acc += wgt * p[((size_t)yi * img->width + xi) * c + k];
            }
        out[k] = (float)acc;
    }
    return true;
}

void mr_image_u8_stats(const mr_image *img, double *mean, double *std) {
    *mean = *std = 0;
    if (!img->data || img->type != MR_PIX_U8) return;
    const uint8_t *p = img->data;
    size_t n = mr_image_bytes(img);
    double sum = 0, s2 = 0;
    for (size_t i = 0; i < n; i++) {
        sum += p[i];
        s2 += (double)p[i] * p[i];
    }
    if (!n) return;
    *mean = sum / (double)n;
    *std = sqrt(fmax(0, s2 / (double)n - *mean * *mean));
}

double mr_image_u8_mean_abs_diff(const mr_image *a, const mr_image *b) {
    if (!a->data || !b->data || a->type != MR_PIX_U8 || b->type != MR_PIX_U8 || a->width != b->width ||
        a->height != b->height || a->channels != b->channels)
        return -1;
    const uint8_t *p = a->data, *q = b->data;
    size_t n = mr_image_bytes(a);
    double s = 0;
    for (size_t i = 0; i < n; i++) s += abs((int)p[i] - (int)q[i]);
    return n ? s / (double)n : 0;
}
