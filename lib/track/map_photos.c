/* What `mrcheck map` gathers before mr_map_build: the photos' detections
 * (through mr_detect_each), the --tag-sizes list and the --fix-pose file. */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool mr_map_tag_sizes_parse(const char *s, int **ids, double **sizes, int *n) {
    int cap = 1;
    for (const char *c = s; *c; c++) cap += *c == ',';
    *ids = calloc((size_t)cap, sizeof **ids);
    *sizes = calloc((size_t)cap, sizeof **sizes);
    *n = 0;
    if (!*ids || !*sizes) return false;
    const char *c = s;
    while (*c) {
        char *e;
        long id = strtol(c, &e, 10);
        if (e == c || *e != '=' || id < 0) return false;
        c = e + 1;
        double v = strtod(c, &e);
        if (e == c || !isfinite(v) || !(v > 0)) return false;
        (*ids)[*n] = (int)id;
        (*sizes)[(*n)++] = v;
        c = e;
        if (*c == ',') c++;
        else if (*c) return false;
    }
    return *n > 0;
}

bool mr_map_fix_pose_load(const char *path, mr_dmat4 *out, mr_error *err) {
    cJSON *j = mr_json_load(path, err);
    if (!j) return false; /* the loader's message names the file */
    bool ok = mr_json_dmat4(j, "world_from_tag", out, err);
    cJSON_Delete(j);
    if (ok && !mr_m4_is_rigid(out, 1e-4)) ok = mr_fail(err, MR_ERR_INVALID, "world_from_tag is not a rigid transform");
    if (!ok) mr_error_prefix(err, "%s", path);
    return ok;
}

typedef struct photo_ctx {
    mr_map_photo_set *ps;
    mr_camera *cam;
    void (*on_photo)(void *user, int n);
    void *user;
    int cap;
} photo_ctx;

static bool take_photo(void *user, const mr_frame *f, const mr_detection *d, int k, mr_error *err) {
    photo_ctx *c = user;
    mr_map_photo_set *ps = c->ps;
    if (ps->n == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 64;
        mr_detection **nd = realloc(ps->dets, (size_t)c->cap * sizeof *nd);
        if (nd) ps->dets = nd;
        mr_map_photo *np = realloc(ps->photos, (size_t)c->cap * sizeof *np);
        if (np) ps->photos = np;
        char(*nn)[256] = realloc(ps->names, (size_t)c->cap * sizeof *nn);
        if (nn) ps->names = nn;
        if (!nd || !np || !nn) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    /* Intrinsics are for the camera's size: photos of another size get them
     * rescaled (the same lens at another resolution; mr_detect_each keeps
     * the first photo's size for all). */
    if (ps->n == 0 && (f->image.width != c->cam->width || f->image.height != c->cam->height))
        *c->cam = mr_camera_resized(c->cam, f->image.width, f->image.height);
    int i = ps->n;
    ps->dets[i] = k ? malloc((size_t)k * sizeof **ps->dets) : NULL;
    if (k && !ps->dets[i]) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    if (k) memcpy(ps->dets[i], d, (size_t)k * sizeof *d);
    snprintf(ps->names[i], sizeof ps->names[i], "%s", f->name[0] ? f->name : "frame");
    ps->photos[i] = (mr_map_photo){ps->dets[i], k, ps->names[i]};
    ps->n++;
    if (c->on_photo) c->on_photo(c->user, ps->n);
    mr_log(MR_LOG_INFO, "%s: %d tags", ps->names[i], k);
    return true;
}

bool mr_map_photos_detect(const char *input, const char *family, const char *who, mr_camera *cam,
                          void (*on_photo)(void *user, int n), void *user, mr_map_photo_set *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    photo_ctx c = {out, cam, on_photo, user, 0};
    return mr_detect_each(input, family, who, take_photo, &c, NULL, err);
}

void mr_map_photo_set_free(mr_map_photo_set *ps) {
    for (int i = 0; i < ps->n; i++) free(ps->dets[i]);
    free(ps->dets);
    free(ps->photos);
    free(ps->names);
    memset(ps, 0, sizeof *ps);
}
