/* Camera calibration from a folder of tag-board images
 * (mr_calibrate_board, `mrcheck calibrate`). */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool board_is_planar(const mr_marker_map *map) {
    for (int i = 0; i < map->count; i++) {
        mr_dvec3 c[4];
        mr_marker_corners_world(map, &map->tags[i], c);
        for (int k = 0; k < 4; k++)
            if (fabs(c[k].z) > 1e-9 * (1 + map->tag_size)) return false;
    }
    return true;
}

/* The board corners seen in one image and their pixels: a view that owns
 * its arrays. */
static bool view_from_detections(const mr_marker_map *map, const mr_detection *d, int n, int used, mr_calib_view *v) {
    double *o = malloc((size_t)used * 4 * 3 * sizeof *o), *p = malloc((size_t)used * 4 * 2 * sizeof *p);
    if (!o || !p) {
        free(o);
        free(p);
        return false;
    }
    int m = 0;
    for (int i = 0; i < n; i++) {
        const mr_marker *mk = mr_marker_map_find(map, d[i].id);
        if (!mk) continue;
        mr_dvec3 c[4];
        mr_marker_corners_world(map, mk, c);
        for (int k = 0; k < 4; k++, m++) {
            o[3 * m] = c[k].x;
            o[3 * m + 1] = c[k].y;
            o[3 * m + 2] = 0;
            p[2 * m] = d[i].corners[k][0];
            p[2 * m + 1] = d[i].corners[k][1];
        }
    }
    *v = (mr_calib_view){o, p, m};
    return true;
}

bool mr_calibrate_board(const mr_board_calib_params *p, mr_board_calib *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    const mr_marker_map *map = p->board;
    if (!p->images || !map) return mr_fail(err, MR_ERR_INVALID, "calibration needs images and a board");
    if (!board_is_planar(map))
        return mr_fail(err, MR_ERR_INVALID, "%s: the board must be planar (all tags in the z = 0 plane)",
                       p->board_name ? p->board_name : "board");
    const int min_tags = p->min_tags > 0 ? p->min_tags : MR_BOARD_CALIB_DEFAULT_MIN_TAGS;
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = true;
    mr_source *src = mr_source_open(p->images, &sp, err);
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    dp.family = map->family;
    dp.decimate = 1; /* full resolution: corner accuracy matters here */
    mr_detector *det = src ? mr_detector_create(&dp, err) : NULL;
    if (!det) {
        mr_source_close(&src);
        return false;
    }
    int cap = 0, nv = 0, width = 0, height = 0;
    mr_calib_view *views = NULL;
    bool ok = true;
    for (;;) {
        mr_frame f;
        mr_read_status st = mr_source_read(src, &f, err);
        if (st == MR_READ_END) break;
        if (st == MR_READ_ERROR) {
            ok = false;
            break;
        }
        if (width == 0) {
            width = f.image.width;
            height = f.image.height;
        } else if (f.image.width != width || f.image.height != height) {
            fprintf(stderr, "mrcheck: calibrate: warning: %s is %dx%d, not %dx%d; skipped\n", f.name, f.image.width,
                    f.image.height, width, height);
            out->skipped++;
            continue;
        }
        int n = 0;
        mr_error fe = {0};
        const mr_detection *d = mr_detector_detect(det, &f.image, &n, &fe);
        if (!d) {
            fprintf(stderr, "mrcheck: calibrate: warning: %s: %s\n", f.name, fe.msg);
            out->skipped++;
            continue;
        }
        int used = 0;
        for (int i = 0; i < n; i++) used += mr_marker_map_find(map, d[i].id) != NULL;
        if (used < min_tags) {
            mr_log(MR_LOG_INFO, "%s: %d board tags, skipped", f.name, used);
            out->skipped++;
            continue;
        }
        if (nv == cap) {
            cap = cap ? 2 * cap : 16;
            mr_calib_view *nvw = realloc(views, (size_t)cap * sizeof *nvw);
            char(*nn)[256] = realloc(out->names, (size_t)cap * sizeof *nn);
            if (nvw) views = nvw;
            if (nn) out->names = nn;
            if (!nvw || !nn) {
                ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
                break;
            }
        }
        if (!view_from_detections(map, d, n, used, &views[nv])) {
            ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
            break;
        }
        snprintf(out->names[nv], 256, "%s", f.name);
        nv++;
    }
    out->views = nv;
    out->view_rms_px = nv ? calloc((size_t)nv, sizeof *out->view_rms_px) : NULL;
    ok = ok && mr_calibrate(views, nv, width, height, &out->camera, &out->rms_px, out->view_rms_px, err);
    for (int v = 0; v < nv; v++) {
        free((void *)views[v].object);
        free((void *)views[v].image);
    }
    free(views);
    mr_detector_destroy(&det);
    mr_source_close(&src);
    if (!ok) mr_board_calib_free(out);
    return ok;
}

void mr_board_calib_free(mr_board_calib *c) {
    free(c->names);
    free(c->view_rms_px);
    memset(c, 0, sizeof *c);
}
