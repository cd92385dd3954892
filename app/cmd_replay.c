/* mrcheck replay: headless overlays of a recording's frames with the
 * planned model at their recorded poses (mr_batch_replay, lib/batch). */
#include "app_track.h"
#include "mr_batch.h"

int cmd_replay(int argc, char **argv) {
    static const char *cmd = "replay";
    mr_cli_opt opts[] = {
        {"scene", "S", "glTF/GLB or scene config of the plan (required)", NULL},
        {"out", "OUTDIR", "where overlay_NNNNNN.png and replay.jsonl go (required)", NULL},
        {"video", "FILE.avi", "also write the overlays as a Motion-JPEG AVI at the recording's rate", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[1];
    int npos = 0;
    mr_batch_replay_params p = MR_BATCH_REPLAY_DEFAULTS;
    /* Depth cues as on render: the same option tables and checks. */
    mr_gt_params gtp = MR_GT_DEFAULTS;
    mr_cli_table tables[] = {{"", mr_batch_replay_opts, &p, NULL, false, {0}}, APP_AO_TABLE(&p.frame.ao),
                             APP_GT_TABLE(&gtp), APP_GHOST_TABLE(&p.frame.ghost), APP_SHADOW_TABLE(&p.frame.shadow)};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, tables, 5, pos, 1, &npos,
                             "usage: mrcheck replay DIR --scene S --out OUTDIR [--alpha A] [--every N] [--from F --to T] "
                             "[--raw] [--video F.avi] [--ao METHOD ...] [--ghost MODE ...] [--shadows METHOD ...]",
                             &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (npos != 1 || !mr_cli_get(opts, "scene") || !mr_cli_get(opts, "out"))
        return mr_cli_errorf(cmd, "needs a recording folder, --scene and --out (see --help)"), 2;
    bool groundtruth = false;
    if (!app_ao_check(cmd, &tables[1], &groundtruth, &gtp)) return 2;
    if (groundtruth) return mr_cli_errorf(cmd, "--ao groundtruth is for single frames (mrcheck render), not replays"), 2;
    p.out_dir = mr_cli_get(opts, "out");
    p.video_path = mr_cli_get(opts, "video");
    p.progress = true;
    mr_error err = {0};
    /* Everything that can be checked without a GPU is checked first. */
    if (!mr_batch_replay_check(&p, &err)) return mr_cli_error(cmd, &err), 2;
    mr_recording *rec = mr_recording_open(pos[0], &err);
    if (!rec) return mr_cli_error(cmd, &err);
    p.recording = rec;
    mr_scene *scene = mr_scene_load(mr_cli_get(opts, "scene"), NULL, &err);
    if (scene && !app_shadow_scene_default(cmd, &tables[4], scene, &p.frame.shadow)) {
        mr_scene_destroy(&scene);
        mr_recording_close(&rec);
        return 2;
    }
    app_gfx gfx = {0};
    mr_batch_replay_stats st;
    bool ok = scene && app_gfx_open(&gfx, &err) && mr_batch_replay(&p, gfx.renderer, scene, &st, &err);
    app_gfx_close(&gfx);
    mr_scene_destroy(&scene);
    mr_recording_close(&rec);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("replayed %d frames to %s/: %d overlays, %d without a pose (camera frame only)\n", st.overlays + st.plain,
           p.out_dir, st.overlays, st.plain);
    return 0;
}
