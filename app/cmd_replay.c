/* mrcheck replay: headless overlays of a recording's frames with the
 * planned model at their recorded poses (mr_batch_replay, lib/batch). */
#include "app_track.h"
#include "mr_batch.h"

#include <string.h>

int cmd_replay(int argc, char **argv) {
    static const char *cmd = "replay";
    mr_cli_opt opts[] = {
        {"scene", "S", "glTF/GLB or scene config of the plan (required)", NULL},
        {"out", "OUTDIR", "where overlay_NNNNNN.png and replay.jsonl go (required)", NULL},
        {"force", NULL, "write into an --out folder that already holds files", NULL},
        {"video", "FILE.avi", "also write the overlays as a Motion-JPEG AVI at the recording's rate", NULL},
        MR_CLI_LOG_OPTS,
        MR_CLI_RESEARCH_ROWS,
        APP_RIG_OPTS,
        APP_DRAW_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[1];
    int npos = 0;
    mr_batch_replay_params p = MR_BATCH_REPLAY_DEFAULTS;
    /* Depth cues as on render: the same option tables and checks. */
    mr_gt_params gtp = MR_GT_DEFAULTS;
    mr_rig_params rp = MR_RIG_DEFAULTS;
    mr_cli_table tables[] = {{.prefix = "", .table = mr_batch_replay_opts, .params = &p}, APP_AO_TABLE(&p.frame.ao),
                             APP_GT_TABLE(&gtp), APP_GHOST_TABLE(&p.frame.ghost), APP_SHADOW_TABLE(&p.frame.shadow),
                             APP_RIG_TABLE(&rp)};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, tables, 6, pos, 1, &npos,
                             "usage: mrcheck replay DIR --scene S --out OUTDIR [--alpha A] [--every N] [--from F --to T] "
                             "[--raw] [--video F.avi] [--lod auto|on|off] [--ao METHOD ...] [--ghost MODE ...] [--shadows METHOD ...] "
                             "[--views N --view-cone DEG [--focal-distance D] [--quilt SPEC]]",
                             &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    mr_lod_mode lod_mode; /* --lod: whether levels are drawn */
    mr_error lerr = {0};
    if (!mr_lod_mode_parse(mr_cli_get(opts, "lod"), &lod_mode, &lerr) || !mr_hlod_mode_check(mr_cli_get(opts, "hlod"), &lerr))
        return mr_cli_error(cmd, &lerr), 2;
    if (npos != 1 || !mr_cli_get(opts, "scene") || !mr_cli_get(opts, "out"))
        return mr_cli_errorf(cmd, "needs a recording folder, --scene and --out (see --help)"), 2;
    bool groundtruth = false;
    mr_error aerr = {0};
    if (!mr_eval_ao_opts_check(&tables[1], &groundtruth, &gtp, &aerr)) return mr_cli_error(cmd, &aerr), 2;
    if (groundtruth) return mr_cli_errorf(cmd, "--ao groundtruth is for single frames (mrcheck render), not replays"), 2;
    p.out_dir = mr_cli_get(opts, "out");
    p.video_path = mr_cli_get(opts, "video");
    p.progress = true;
    p.force = mr_cli_flag(opts, "force");
    mr_stop_catch();
    mr_quilt quilt = {0};
    bool have_quilt;
    if (!mr_rig_opts_check(&tables[5], mr_cli_get(opts, "quilt"), mr_cli_get(opts, "lightfield") != NULL, &quilt,
                           &have_quilt, &lerr))
        return mr_cli_error(cmd, &lerr), 2;
    if (mr_cli_get(opts, "lightfield")) return mr_cli_errorf(cmd, "--lightfield is for single frames (mrcheck render)"), 2;
    bool multiview = rp.views > 0 || have_quilt;
    if (multiview) {
        p.rig = &rp;
        p.quilt = &quilt;
    }
    mr_error err = {0};
    /* Everything that can be checked without a GPU is checked first. */
    if (!mr_batch_replay_check(&p, &err)) return mr_cli_error(cmd, &err), 2;
    mr_recording *rec = mr_recording_open(pos[0], &err);
    if (!rec) return mr_cli_error(cmd, &err);
    p.recording = rec;
    if (multiview) {
        /* A quilt too small for the views is bad input: found before any
         * output folder or GPU context is made. */
        mr_quilt_layout ql;
        mr_rig_params chk = rp;
        if (chk.views == 0) chk.views = quilt.cols * quilt.rows;
        if (!mr_quilt_layout_make(quilt.cols ? &quilt : NULL, chk.views, rec->camera.width, rec->camera.height, &ql, &err)) {
            mr_recording_close(&rec);
            return mr_cli_error(cmd, &err);
        }
    }
    mr_scene *scene = mr_scene_load(mr_cli_get(opts, "scene"), NULL, &err);
    if (scene && !mr_shadow_scene_default(&tables[4], scene, &p.frame.shadow, &err)) {
        mr_cli_error(cmd, &err);
        mr_scene_destroy(&scene);
        mr_recording_close(&rec);
        return 2;
    }
    /* Levels of detail as render draws them (--lod auto: for a big scene),
     * from the cache next to the scene; where they cannot be had, the
     * frames are drawn in full detail. */
    mr_lod *lod = NULL;
    mr_hlod *hlod = NULL;
    if (scene && mr_lod_wanted(lod_mode, scene)) {
        lod = mr_lod_load_logged(scene, scene->source, scene->source[0] != 0, &lerr);
        if (!lod) mr_log(MR_LOG_WARN, "%s: full detail (no levels of detail: %s)", cmd, lerr.msg);
        else if (!mr_hlod_load_logged(scene, lod, scene->source, mr_cli_get(opts, "hlod"), scene->source[0] != 0, &hlod, &lerr))
            mr_log(MR_LOG_WARN, "%s: no levels above the part: %s", cmd, lerr.msg);
    }
    p.lod = lod;
    p.hlod = hlod;
    mr_gfx gfx = {0};
    mr_batch_replay_stats st;
    bool ok = scene && mr_gfx_open(&gfx, &err) && mr_batch_replay(&p, gfx.renderer, scene, &st, &err);
    mr_gfx_close(&gfx);
    mr_hlod_destroy(&hlod);
    mr_lod_destroy(&lod);
    mr_scene_destroy(&scene);
    mr_recording_close(&rec);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("replayed %d frames to %s/: %d overlays, %d without a pose (camera frame only)\n", st.overlays + st.plain,
           p.out_dir, st.overlays, st.plain);
    mr_log(MR_LOG_INFO, "replay: %llu triangles submitted over the overlays, %llu instances at a simplified level",
           (unsigned long long)st.triangles, (unsigned long long)st.lod_instances);
    return 0;
}
