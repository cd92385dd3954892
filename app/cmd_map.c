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

static void photo_progress(void *user, int n) {
    (void)user;
    fprintf(stderr, "\rmap: detecting, photo %d   ", n);
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
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_map_params mp = MR_MAP_DEFAULTS;
    mr_cli_table table = {.prefix = "", .table = mr_map_opts, .params = &mp};
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
    if (mr_cli_get(opts, "tag-sizes") && !mr_map_tag_sizes_parse(mr_cli_get(opts, "tag-sizes"), &size_ids, &sizes, &mp.size_count)) {
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
    mr_map_photo_set ps = {0};
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
            if (!mr_map_fix_pose_load(mr_cli_get(opts, "fix-pose"), &fix_pose, &err)) goto fail;
            mp.fix_pose = &fix_pose;
        }
    } else {
        if (!mr_map_controls_load(mr_cli_get(opts, "control"), &ctl, &mp.control_count, &err)) goto fail;
        mp.controls = ctl;
    }

    bool tty = isatty(2) && mr_log_get_level() >= MR_LOG_WARN;
    mr_stop_catch();
    if (!mr_map_photos_detect(in, family, cmd, &cam, tty ? photo_progress : NULL, NULL, &ps, &err)) {
        if (tty) fprintf(stderr, "\n");
        goto fail;
    }
    if (tty) {
        fprintf(stderr, "\n");
        mp.progress = progress;
    }
    if (!mr_map_build(&cam, ps.photos, ps.n, &mp, &res, &err)) {
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
    mr_map_photo_set_free(&ps);
    free(size_ids);
    free(sizes);
    free(ctl);
    mr_map_result_free(&res);
    mr_marker_map_free(&mm);
    return rc;
}
