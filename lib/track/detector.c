/* AprilTag detection with the apriltag library (3.x). */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagCircle49h12.h>
#include <apriltag/tagCustom48h12.h>
#include <apriltag/tagStandard41h12.h>
#include <apriltag/tagStandard52h13.h>

typedef struct family_entry {
    const char *name;
    apriltag_family_t *(*create)(void);
    void (*destroy)(apriltag_family_t *);
} family_entry;

static const family_entry k_family_table[] = {
    {"tag36h11", tag36h11_create, tag36h11_destroy},
    {"tag25h9", tag25h9_create, tag25h9_destroy},
    {"tag16h5", tag16h5_create, tag16h5_destroy},
    {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy},
    {"tagCircle49h12", tagCircle49h12_create, tagCircle49h12_destroy},
    {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
    {"tagStandard52h13", tagStandard52h13_create, tagStandard52h13_destroy},
    {"tagCustom48h12", tagCustom48h12_create, tagCustom48h12_destroy},
};

struct mr_detector {
    apriltag_detector_t *td;
    apriltag_family_t *fam;
    const family_entry *entry;
    int max_hamming;
    mr_image gray;             /* reused conversion buffer */
    mr_detection *dets;
    int det_cap;
};

mr_detector *mr_detector_create(const mr_detector_params *params, mr_error *err) {
    mr_detector_params p = params ? *params : (mr_detector_params)MR_DETECTOR_DEFAULTS;
    const char *family = p.family && p.family[0] ? p.family : "tag36h11";
    const family_entry *e = NULL;
    for (size_t i = 0; i < sizeof k_family_table / sizeof k_family_table[0]; i++)
        if (strcmp(k_family_table[i].name, family) == 0) e = &k_family_table[i];
    if (!e) {
        mr_fail(err, MR_ERR_UNSUPPORTED, "unknown tag family '%.40s'", family);
        return NULL;
    }
    double decimate = p.decimate == 0 ? MR_DETECTOR_DEFAULT_DECIMATE : p.decimate;
    if (!isfinite(decimate) || decimate < 1.0 || decimate > 16.0) {
        mr_fail(err, MR_ERR_INVALID, "decimation must be in [1, 16] (got %g)", decimate);
        return NULL;
    }
    int threads = p.threads == 0 ? MR_DETECTOR_DEFAULT_THREADS : p.threads;
    if (threads < 1 || threads > 256) {
        mr_fail(err, MR_ERR_INVALID, "threads must be in [1, 256] (got %d)", threads);
        return NULL;
    }
    if (!isfinite(p.sharpening) || !isfinite(p.blur) || p.blur < 0 || p.blur > 20) {
        mr_fail(err, MR_ERR_INVALID, "sharpening/blur out of range");
        return NULL;
    }
    mr_detector *d = calloc(1, sizeof *d);
    if (!d) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    d->entry = e;
    /* Room for a few detections up front, so the result is never NULL. */
    d->det_cap = 16;
    d->dets = malloc((size_t)d->det_cap * sizeof *d->dets);
    d->fam = e->create();
    d->td = apriltag_detector_create();
    if (!d->fam || !d->td || !d->dets) {
        mr_fail(err, MR_ERR_NOMEM, "cannot create the apriltag detector");
        mr_detector_destroy(&d);
        return NULL;
    }
    d->max_hamming = p.max_hamming == 0 ? 1 : p.max_hamming < 0 ? 0 : p.max_hamming;
    /* The library allocates a decode table per corrected bit; 2 is its
     * default and enough for the max_hamming filter above. */
    apriltag_detector_add_family_bits(d->td, d->fam, d->max_hamming > 2 ? 2 : d->max_hamming);
    d->td->quad_decimate = (float)decimate;
    d->td->nthreads = threads;
    d->td->refine_edges = p.refine_edges >= 0;
    d->td->decode_sharpening = p.sharpening == 0 ? MR_DETECTOR_DEFAULT_SHARPENING : p.sharpening < 0 ? 0.0 : p.sharpening;
    d->td->quad_sigma = (float)p.blur;
    d->td->debug = false;
    return d;
}

void mr_detector_destroy(mr_detector **det) {
    if (!det || !*det) return;
    mr_detector *d = *det;
    if (d->td) apriltag_detector_destroy(d->td);
    if (d->fam) d->entry->destroy(d->fam);
    mr_image_free(&d->gray);
    free(d->dets);
    free(d);
    *det = NULL;
}

bool mr_image_to_gray(const mr_image *src, mr_image *dst, mr_error *err) {
    if (!src->data || src->type != MR_PIX_U8 || src->channels < 1 || src->channels > 4 || src->width < 1 ||
        src->height < 1)
        return mr_fail(err, MR_ERR_INVALID, "not an 8-bit image");
    if (dst->width != src->width || dst->height != src->height || dst->channels != 1 || !dst->data) {
        mr_image_free(dst);
        if (!mr_image_alloc(dst, src->width, src->height, 1, MR_PIX_U8, err)) return false;
    }
    const unsigned char *s = src->data;
    unsigned char *o = dst->data;
    size_t n = (size_t)src->width * src->height;
    int c = src->channels;
    if (c == 1) {
        memcpy(o, s, n);
    } else if (c == 2) {
        for (size_t i = 0; i < n; i++) o[i] = s[2 * i];
    } else {
        for (size_t i = 0; i < n; i++) {
            const unsigned char *p = s + i * (size_t)c;
            o[i] = (unsigned char)((299u * p[0] + 587u * p[1] + 114u * p[2] + 500u) / 1000u);
        }
    }
    return true;
}

bool mr_detector_set_decimate(mr_detector *d, double decimate) {
    if (!isfinite(decimate) || decimate < 1.0 || decimate > 16.0) return false;
    d->td->quad_decimate = (float)decimate;
    return true;
}

double mr_detector_decimate(const mr_detector *d) { return d->td->quad_decimate; }

static int cmp_det(const void *a, const void *b) {
    const mr_detection *x = a, *y = b;
    if (x->id != y->id) return x->id < y->id ? -1 : 1;
    return x->decision_margin > y->decision_margin ? -1 : x->decision_margin < y->decision_margin;
}

const mr_detection *mr_detector_detect(mr_detector *d, const mr_image *img, int *count, mr_error *err) {
    *count = 0;
    if (!img || !img->data || img->type != MR_PIX_U8 || img->channels < 1 || img->channels > 4) {
        mr_fail(err, MR_ERR_INVALID, "detector: not an 8-bit image");
        return NULL;
    }
    if (img->width < MR_DETECTOR_MIN_SIDE || img->height < MR_DETECTOR_MIN_SIDE) {
        mr_fail(err, MR_ERR_INVALID, "frame %dx%d is too small for the tag detector (minimum %dx%d)", img->width,
                img->height, MR_DETECTOR_MIN_SIDE, MR_DETECTOR_MIN_SIDE);
        return NULL;
    }
    /* Decimation must leave a frame the library can still take. */
    if (img->width / d->td->quad_decimate < 8 || img->height / d->td->quad_decimate < 8) {
        mr_fail(err, MR_ERR_INVALID, "frame %dx%d is too small for decimation %g", img->width, img->height,
                (double)d->td->quad_decimate);
        return NULL;
    }
    const mr_image *g = img;
    if (img->channels != 1) {
        if (!mr_image_to_gray(img, &d->gray, err)) return NULL;
        g = &d->gray;
    }
    image_u8_t im = {g->width, g->height, g->width, g->data};
    zarray_t *zs = apriltag_detector_detect(d->td, &im);
    if (!zs) {
        mr_fail(err, MR_ERR_NOMEM, "apriltag detection failed");
        return NULL;
    }
    int n = zarray_size(zs), k = 0;
    if (n > d->det_cap) {
        mr_detection *nd = realloc(d->dets, (size_t)n * sizeof *nd);
        if (!nd) {
            apriltag_detections_destroy(zs);
            mr_fail(err, MR_ERR_NOMEM, "out of memory");
            return NULL;
        }
        d->dets = nd;
        d->det_cap = n;
    }
    for (int i = 0; i < n; i++) {
        apriltag_detection_t *det;
        zarray_get(zs, i, &det);
        if (det->hamming > d->max_hamming) continue;
        mr_detection *o = &d->dets[k++];
        o->id = det->id;
        o->hamming = det->hamming;
        o->decision_margin = det->decision_margin;
        /* apriltag 3 puts pixel centres at +0.5 (the top-left pixel covers
         * [0,1)); OpenCV puts them at integers. Measured in test_track. */
        for (int c = 0; c < 4; c++) {
            o->corners[c][0] = det->p[c][0] - 0.5;
            o->corners[c][1] = det->p[c][1] - 0.5;
        }
    }
    apriltag_detections_destroy(zs);
    qsort(d->dets, (size_t)k, sizeof *d->dets, cmp_det);
    *count = k;
    return d->dets;
}

/* The printed cells, as apriltag's decoder expects them: the family's
 * one-cell white ring just outside the detected square (inside it for the
 * reversed-border families, whose outside is black), every cell else black
 * unless the code sets its bit. Bit i (most significant first) sits at
 * (bit_x[i], bit_y[i]) cells from the detected square's top-left corner;
 * the reversed families place some bits outside it (negative offsets,
 * stored wrapped in the unsigned fields). */
bool mr_tag_pattern_make(const char *family, int id, mr_tag_pattern *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    const family_entry *e = NULL;
    for (size_t i = 0; family && i < sizeof k_family_table / sizeof k_family_table[0]; i++)
        if (strcmp(k_family_table[i].name, family) == 0) e = &k_family_table[i];
    if (!e) return mr_fail(err, MR_ERR_UNSUPPORTED, "unknown tag family '%.40s'", family ? family : "");
    apriltag_family_t *fam = e->create();
    if (!fam) return mr_fail(err, MR_ERR_NOMEM, "cannot create the %s family", family);
    const int tw = fam->total_width, wb = fam->width_at_border;
    bool ok = true;
    if (tw < 1 || tw > MR_TAG_MAX_CELLS || wb < 1 || wb > tw)
        ok = mr_fail(err, MR_ERR_UNSUPPORTED, "%s: %d cells per side is more than %d", family, tw, MR_TAG_MAX_CELLS);
    else if (id < 0 || (uint32_t)id >= fam->ncodes)
        ok = mr_fail(err, MR_ERR_INVALID, "%s has ids 0..%u; %d is not one", family, fam->ncodes - 1, id);
    if (ok) {
        out->total_width = tw;
        out->width_at_border = wb;
        out->codes = (int)fam->ncodes;
        memset(out->cells, 1, sizeof out->cells);
        const int ring = wb + (fam->reversed_border ? 0 : 2), r0 = (tw - ring) / 2, r1 = r0 + ring - 1;
        for (int y = 0; y < tw; y++)
            for (int x = 0; x < tw; x++) {
                bool on_ring = ((x == r0 || x == r1) && y >= r0 && y <= r1) || ((y == r0 || y == r1) && x >= r0 && x <= r1);
                if (on_ring) out->cells[y * MR_TAG_MAX_CELLS + x] = 0;
            }
        const int b0 = (tw - wb) / 2;
        const uint64_t code = fam->codes[id];
        for (uint32_t i = 0; i < fam->nbits; i++) {
            int x = (int32_t)fam->bit_x[i] + b0, y = (int32_t)fam->bit_y[i] + b0;
            if (x < 0 || y < 0 || x >= tw || y >= tw) {
                ok = mr_fail(err, MR_ERR_UNSUPPORTED, "%s: bit %u lies outside the tag", family, i);
                break;
            }
            if ((code >> (fam->nbits - 1 - i)) & 1u) out->cells[y * MR_TAG_MAX_CELLS + x] = 0;
        }
    }
    e->destroy(fam);
    return ok;
}
