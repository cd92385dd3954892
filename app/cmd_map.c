/* mrcheck map: the marker map from photos (lib/track's mr_map_build). */
#include "app_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void progress(void *user, const char *stage, double f) {
    (void)user;
    fprintf(stderr, "\rmap: %s %3.0f%%   ", stage, 100 * f);
}

/* "id=size,id=size" into arrays (malloc'd). */
static bool parse_sizes(const char *s, int **ids, double **sizes, int *n) {
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

/* The photos' detections as mr_map_build takes them, gathered by
 * mr_detect_each (lib/track). */
typedef struct photo_set {
    mr_camera *cam;
    mr_detection **dets;
    mr_map_photo *photos;
    char (*names)[256];
    int n, cap;
    bool tty;
} photo_set;

static bool take_photo(void *user, const mr_frame *f, const mr_detection *d, int k, mr_error *err) {
    photo_set *ps = user;
    if (ps->n == ps->cap) {
        ps->cap = ps->cap ? 2 * ps->cap : 64;
        mr_detection **nd = realloc(ps->dets, (size_t)ps->cap * sizeof *nd);
        if (nd) ps->dets = nd;
        mr_map_photo *np = realloc(ps->photos, (size_t)ps->cap * sizeof *np);
        if (np) ps->photos = np;
        char(*nn)[256] = realloc(ps->names, (size_t)ps->cap * sizeof *nn);
        if (nn) ps->names = nn;
        if (!nd || !np || !nn) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    /* Intrinsics are for the camera's size: photos of another size get them
     * rescaled (the same lens at another resolution; mr_detect_each keeps
     * the first photo's size for all). */
    if (ps->n == 0 && (f->image.width != ps->cam->width || f->image.height != ps->cam->height))
        *ps->cam = mr_camera_resized(ps->cam, f->image.width, f->image.height);
    int i = ps->n;
    ps->dets[i] = k ? malloc((size_t)k * sizeof **ps->dets) : NULL;
    if (k && !ps->dets[i]) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    if (k) memcpy(ps->dets[i], d, (size_t)k * sizeof *d);
    snprintf(ps->names[i], sizeof ps->names[i], "%s", f->name[0] ? f->name : "frame");
    ps->photos[i] = (mr_map_photo){ps->dets[i], k, ps->names[i]};
    ps->n++;
    if (ps->tty) fprintf(stderr, "\rmap: detecting, photo %d   ", ps->n);
    mr_log(MR_LOG_INFO, "%s: %d tags", ps->names[i], k);
    return true;
}

int cmd_map(int argc, char **argv) {
    static const char *cmd = "map";
    mr_cli_opt opts[] = {
        {"images", "DIR", "folder of photos of the tags (png, jpg, ...)", NULL},
        {"video", "FILE", "instead: a video walked past the tags (every frame is a photo)", NULL},
        {"camera", "C.json", "camera intrinsics (mrcheck calibrate)", NULL},
        {"family", "F", "tag family (default tag36h11)", NULL},
        {"tag-sizes", "ID=S,...", "tags of other sizes", NULL},
        {"fix", "ID", "gauge: this tag's pose is given (--fix-pose, default identity)", NULL},
        {"fix-pose", "P.json", "{\"world_from_tag\": [16]} for the --fix tag", NULL},
        {"control", "P.json", "gauge: >= 3 control points with plan coordinates and sigma", NULL},
        {"out", "MARKERS.json", "marker map to write (with sigma, RMS, control residuals)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_map_params mp = MR_MAP_DEFAULTS;
    mr_cli_table table = {"", mr_map_opts, &mp, NULL, false, {0}};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, &table, 1, NULL, 0, NULL,
                   "usage: mrcheck map (--images DIR | --video FILE) --camera C.json --tag-size S\n"
                   "                   [--tag-sizes ID=S,...] (--fix ID [--fix-pose P.json] | --control P.json)\n"
                   "                   --out MARKERS.json\n"
                   "Detects the tags in every photo, chains their relative poses into an initial map and\n"
                   "adjusts all tag and photo poses together (bundle adjustment, Ceres). Writes the marker\n"
                   "map with each tag's sigma, the reprojection RMS, control-point residuals with a\n"
                   "leave-one-out check, and the tags that could not be connected (the largest part is mapped).",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *in = mr_cli_get(opts, "images") ? mr_cli_get(opts, "images") : mr_cli_get(opts, "video");
    const char *camf = mr_cli_get(opts, "camera"), *out = mr_cli_get(opts, "out");
    if (!in || !camf || !out) return mr_cli_errorf(cmd, "--images (or --video), --camera and --out are required (see --help)"), 2;
    if (mr_cli_get(opts, "images") && mr_cli_get(opts, "video")) return mr_cli_errorf(cmd, "give --images or --video, not both"), 2;
    if (!mr_cli_get(opts, "fix") == !mr_cli_get(opts, "control"))
        return mr_cli_errorf(cmd, "give the gauge: --fix ID or --control P.json (one of them)"), 2;
    if (!(mp.tag_size > 0) && !mr_cli_get(opts, "tag-sizes"))
        return mr_cli_errorf(cmd, "--tag-size (or --tag-sizes) is required"), 2;
    const char *family = mr_cli_get(opts, "family") ? mr_cli_get(opts, "family") : "tag36h11";
    if (!mr_tag_family_known(family)) return mr_cli_errorf(cmd, "unknown tag family '%s'", family), 2;

    int *size_ids = NULL;
    double *sizes = NULL;
    if (mr_cli_get(opts, "tag-sizes") && !parse_sizes(mr_cli_get(opts, "tag-sizes"), &size_ids, &sizes, &mp.size_count)) {
        free(size_ids);
        free(sizes);
        return mr_cli_errorf(cmd, "--tag-sizes: expected ID=SIZE,... with sizes > 0, got '%s'", mr_cli_get(opts, "tag-sizes")), 2;
    }
    mp.size_ids = size_ids;
    mp.sizes = sizes;

    mr_error err = {0};
    mr_camera cam;
    mr_dmat4 fix_pose;
    mr_map_control *ctl = NULL;
    mr_detection **dets = NULL;
    mr_map_photo *photos = NULL;
    char (*names)[256] = NULL;
    int n = 0;
    int rc = 1;
    mr_map_result res = {0};
    mr_marker_map mm = {0};
    if (!mr_camera_load(camf, &cam, &err)) goto fail;
    if (mr_cli_get(opts, "fix")) {
        long id;
        if (!mr_cli_int("fix", mr_cli_get(opts, "fix"), 0, 1000000, &id)) {
            rc = 2;
            goto out;
        }
        mp.fix_id = (int)id;
        if (mr_cli_get(opts, "fix-pose")) {
            cJSON *j = mr_json_load(mr_cli_get(opts, "fix-pose"), &err);
            if (!j) goto fail; /* the loader's message names the file */
            bool ok = mr_json_dmat4(j, "world_from_tag", &fix_pose, &err);
            cJSON_Delete(j);
            if (ok && !mr_m4_is_rigid(&fix_pose, 1e-4))
                ok = mr_fail(&err, MR_ERR_INVALID, "world_from_tag is not a rigid transform");
            if (!ok) {
                mr_error_prefix(&err, "%s", mr_cli_get(opts, "fix-pose"));
                goto fail;
            }
            mp.fix_pose = &fix_pose;
        }
    } else {
        if (!mr_map_controls_load(mr_cli_get(opts, "control"), &ctl, &mp.control_count, &err)) goto fail;
        mp.controls = ctl;
    }

    photo_set ps = {&cam, NULL, NULL, NULL, 0, 0, isatty(2) && mr_log_get_level() >= MR_LOG_WARN};
    bool tty = ps.tty;
    bool detected = mr_detect_each(in, family, cmd, take_photo, &ps, NULL, &err);
    dets = ps.dets;
    photos = ps.photos;
    names = ps.names;
    n = ps.n;
    if (!detected) goto fail;
    if (tty) {
        fprintf(stderr, "\n");
        mp.progress = progress;
    }
    if (!mr_map_build(&cam, photos, n, &mp, &res, &err)) {
        if (tty) fprintf(stderr, "\n");
        goto fail;
    }
    if (tty) fprintf(stderr, "\n");
    if (!mr_map_result_markers(&res, family, mp.tag_size, &mm, &err)) goto fail;
    cJSON *j = mr_map_result_to_json(&res, &mm, &mp);
    bool saved = j && mr_json_save(out, j, &err);
    cJSON_Delete(j);
    if (!saved) goto fail;
    mr_map_result_report(&res, &mp, out, stdout);
    rc = 0;
    goto out;
fail:
    rc = mr_cli_error(cmd, &err);
out:
    for (int i = 0; i < n; i++) free(dets[i]);
    free(dets);
    free(photos);
    free(names);
    free(size_ids);
    free(sizes);
    free(ctl);
    mr_map_result_free(&res);
    mr_marker_map_free(&mm);
    return rc;
}
