/* mrcheck view: the in-situ check. A window shows the camera frame with the
 * planned model over it; big touch controls fade between them, switch the
 * depth cues, freeze the picture, snapshot it and mark discrepancies; a
 * recording replays with play/pause, step, seek and rate.
 *
 * Wiring only: the flags, the source's files (mr_view_source_load) and the
 * window loop (mr_view_run) in lib/view; Measure's planned surface from
 * lib/eval, handed in as functions because lib/view is below lib/eval. */
#include "app.h"

#include "mr_eval.h"
#include "mr_view.h"

#include <stdio.h>

static const char *const k_cmd = "view";

static void *nearest_create(void *user, const mr_scene *scene, mr_error *err) {
    return mr_eval_nearest_create(scene, false, err);
}

static bool nearest_query(void *user, void *search, mr_dvec3 p, const double cov[9], mr_view_nearest_hit *out) {
    mr_nearest_hit h = {0};
    bool ok = mr_eval_nearest_point(search, p, &h);
    mr_view_nearest_hit v = {h.found, h.point, h.distance, ok ? mr_eval_nearest_sigma(&h, cov) : 0.0, h.node};
    *out = v;
    return ok;
}

static void nearest_destroy(void *user, void *search) {
    mr_eval_nearest *n = search;
    mr_eval_nearest_destroy(&n);
}

/* --ao and --ghost, checked before any window opens through the settings
 * file's rows (so the names are the ones A and G cycle); left unset where
 * not given. */
static int parse_start_modes(const mr_cli_opt *opts, mr_view_run_params *p) {
    static const char *const keys[2] = {"ao", "ghost"};
    for (int i = 0; i < 2; i++) {
        const mr_opt *o = mr_opt_find(mr_view_settings_opts, keys[i]);
        mr_view_settings s = MR_VIEW_SETTINGS_DEFAULTS;
        mr_error err = {0};
        if (!mr_cli_get(opts, keys[i])) continue;
        if (!mr_opt_set_row(o, &s, mr_cli_get(opts, keys[i]), &err)) return mr_cli_errorf(k_cmd, "--%s", err.msg);
        int v = (int)mr_opt_get(o, &s);
        if (i == 0) p->ao_given = true, p->ao = (mr_ao_method)v;
        else p->ghost_given = true, p->ghost = (mr_ghost_mode)v;
    }
    return 0;
}

int cmd_view(int argc, char **argv) {
    /* The names and defaults of --ao and --ghost from the settings table. */
    char ao_help[400], ghost_help[400], desc[256];
    mr_opt_describe(mr_opt_find(mr_view_settings_opts, "ao"), desc, sizeof desc);
    snprintf(ao_help, sizeof ao_help, "start with AO on with this method (none: off) instead of the saved setting: %s", desc);
    mr_opt_describe(mr_opt_find(mr_view_settings_opts, "ghost"), desc, sizeof desc);
    snprintf(ghost_help, sizeof ghost_help, "start with ghosting on in this mode (off: off) instead of the saved setting: %s",
             desc);
    mr_cli_opt opts[] = {
        {"scene", "FILE", "glTF/GLB or scene config JSON (required)", NULL},
        {"input", "PATH", "live input: /dev/videoN, a video file, an image or a folder of images", NULL},
        {"camera", "C.json", "camera intrinsics of the input (required with --input)", NULL},
        {"markers", "M.json", "marker map (required with --input unless --view is given)", NULL},
        {"replay", "DIR", "replay a recording (frames/ + frames.jsonl + meta.json)", NULL},
        {"out", "DIR", "where annotations.jsonl and snapshots go (default: the recording, or ./mrcheck-session)", NULL},
        {"tolerances", "T.json", "Measure's tolerance table (default: DIN 18202 Table 1 by nominal size)", NULL},
        {"config", "FILE", "settings file (default ~/.config/mrcheck/view.json)", NULL},
        {"size", "WxH", "window size (default 960x720)", NULL},
        {"fullscreen", NULL, "start fullscreen (F11 toggles)", NULL},
        {"ui-scale", "S", "scale the UI beyond the screen's density (default 1)", NULL},
        {"paused", NULL, "replay: start paused", NULL},
        {"verbose", NULL, "more log output", NULL},
        {"quiet", NULL, "errors only", NULL},
        MR_CLI_RESEARCH_ROWS,
        {"view", "V.json", "with --input IMG: a fixed pose instead of tracking", NULL},
        {"retrack", NULL, "replay: track the frames again instead of using the recorded poses", NULL},
        {"script", "FILE", "timed input events (tests, demos): see lib/view/mr_view.h", NULL},
        {"stats", NULL, "show the frame rate and render passes in the status line; print the frame-time split on exit", NULL},
        {"ao", "METHOD", ao_help, NULL},
        {"ghost", "MODE", ghost_help, NULL},
        {"ao-temporal", NULL, "accumulate the AO over frames (reprojected; restarts when tracking is regained)", NULL},
        {"shadows", "METHOD", "soft shadows: off, hard, pcf, pcss, bp, groundtruth (default: the scene config's, else off)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 2, opts, NULL, 0, NULL,
                   "usage: mrcheck view HALL [--replay SESSION]\n"
                   "       mrcheck view --scene S (--input /dev/videoN|VIDEO --camera C --markers M | --replay DIR) "
                   "[--out DIR] [--fullscreen]",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *scene_path = mr_cli_get(opts, "scene"), *input = mr_cli_get(opts, "input"), *replay = mr_cli_get(opts, "replay");
    if (!scene_path) return mr_cli_errorf(k_cmd, "--scene is required"), 2;
    if (!input == !replay) return mr_cli_errorf(k_cmd, "give either --input or --replay"), 2;

    mr_view_run_params p = MR_VIEW_RUN_DEFAULTS;
    p.start_time = mr_time_now();
    p.scene_path = scene_path;
    p.out_dir = mr_cli_get(opts, "out");
    p.config_path = mr_cli_get(opts, "config");
    p.fullscreen = mr_cli_flag(opts, "fullscreen");
    p.paused = mr_cli_flag(opts, "paused");
    p.retrack = mr_cli_flag(opts, "retrack");
    p.stats = mr_cli_flag(opts, "stats") ? stdout : NULL;
    p.ao_temporal = mr_cli_flag(opts, "ao-temporal");
    p.tolerances_path = mr_cli_get(opts, "tolerances");
    p.nearest = (mr_view_nearest_fns){nearest_create, nearest_query, nearest_destroy, NULL};
    mr_view_source_params sp = {input, replay, mr_cli_get(opts, "camera"), mr_cli_get(opts, "markers"),
                                mr_cli_get(opts, "view")};
    mr_view_source src = {0};
    mr_view_script *script = NULL;
    int rc = 0;
    mr_error err = {0};
    /* Inputs that can be checked without a window are checked first. */
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &p.width, &p.height)) { rc = 2; goto done; }
    if (mr_cli_get(opts, "ui-scale") && !mr_cli_double("ui-scale", mr_cli_get(opts, "ui-scale"), 0.25, 8, &p.ui_scale)) {
        rc = 2;
        goto done;
    }
    if (!mr_view_source_load(&sp, &src, &err)) { rc = mr_cli_error(k_cmd, &err); goto done; }
    p.source = &src;
    if (mr_cli_get(opts, "script") && !(script = mr_view_script_load(mr_cli_get(opts, "script"), &err))) {
        rc = mr_cli_error(k_cmd, &err);
        goto done;
    }
    p.script = &script;
    if ((rc = parse_start_modes(opts, &p)) != 0) goto done;
    if (mr_cli_get(opts, "shadows")) {
        if (!mr_shadow_method_parse(mr_cli_get(opts, "shadows"), &p.shadows)) {
            mr_cli_errorf(k_cmd, "--shadows must be off, hard, pcf, pcss, bp or groundtruth, not '%s'", mr_cli_get(opts, "shadows"));
            rc = 2;
            goto done;
        }
        p.shadows_given = true;
    }
    if (!mr_view_run(&p, &err)) rc = mr_cli_error(k_cmd, &err);

done:
    mr_view_script_destroy(&script);
    mr_view_source_free(&src);
    return rc;
}
