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

/* The views gathered so far, as mr_detect_each hands the photos over. */
typedef struct gather {
    const mr_marker_map *map;
    int min_tags;
    mr_board_calib *out;
    mr_calib_view *views;
    int cap, width, height;
    bool progress;
} gather;

static bool take_photo(void *user, const mr_frame *f, const mr_detection *d, int n, mr_error *err) {
    gather *g = user;
    mr_board_calib *out = g->out;
    if (g->progress) fprintf(stderr, "\rcalibrate: image %d (%d used)   ", out->views + out->skipped + 1, out->views);
    int used = 0;
    for (int i = 0; i < n; i++) used += mr_marker_map_find(g->map, d[i].id) != NULL;
    if (used < g->min_tags) {
        mr_log(MR_LOG_INFO, "%s: %d board tags, skipped", f->name, used);
        out->skipped++;
        return true;
    }
    if (out->views == g->cap) {
        g->cap = g->cap ? 2 * g->cap : 16;
        mr_calib_view *nvw = realloc(g->views, (size_t)g->cap * sizeof *nvw);
        char(*nn)[256] = realloc(out->names, (size_t)g->cap * sizeof *nn);
        if (nvw) g->views = nvw;
        if (nn) out->names = nn;
        if (!nvw || !nn) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    if (!view_from_detections(g->map, d, n, used, &g->views[out->views])) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    snprintf(out->names[out->views], 256, "%s", f->name);
    out->views++;
    g->width = f->image.width;
    g->height = f->image.height;
    return true;
}

bool mr_calibrate_board(const mr_board_calib_params *p, mr_board_calib *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    const mr_marker_map *map = p->board;
    if (!p->images || !map) return mr_fail(err, MR_ERR_INVALID, "calibration needs images and a board");
    if (!board_is_planar(map))
        return mr_fail(err, MR_ERR_INVALID, "%s: the board must be planar (all tags in the z = 0 plane)",
                       p->board_name ? p->board_name : "board");
    gather g = {map, p->min_tags > 0 ? p->min_tags : MR_BOARD_CALIB_DEFAULT_MIN_TAGS, out, NULL, 0, 0, 0, p->progress};
    int skipped = 0;
    bool ok = mr_detect_each(p->images, map->family, "calibrate", take_photo, &g, &skipped, err);
    if (p->progress && (out->views || out->skipped)) fprintf(stderr, "\n");
    out->skipped += skipped;
    const int nv = out->views;
    out->view_rms_px = nv ? calloc((size_t)nv, sizeof *out->view_rms_px) : NULL;
    ok = ok && mr_calibrate(g.views, nv, g.width, g.height, &out->camera, &out->rms_px, out->view_rms_px, err);
    for (int v = 0; v < nv; v++) {
        free((void *)g.views[v].object);
        free((void *)g.views[v].image);
    }
    free(g.views);
    if (!ok) mr_board_calib_free(out);
    return ok;
}

void mr_board_calib_free(mr_board_calib *c) {
    free(c->names);
    free(c->view_rms_px);
    memset(c, 0, sizeof *c);
}
