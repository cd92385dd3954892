/* mrcheck render: one headless frame. */
#include "app.h"
#include "mr_export.h"

#include <stddef.h>
#include <string.h>

int cmd_render(int argc, char **argv) {
    static const char *cmd = "render";
    mr_cli_opt opts[] = {
        {"scene", "FILE", "glTF/GLB file or scene config JSON (required)", NULL},
        {"view", "VIEW.json|auto", "camera + world_from_camera, or auto: the whole scene from a corner above", NULL},
        {"bcf", "FILE", "render a BCF topic's viewpoint (camera, visibility, colours, clipping) instead of --view", NULL},
        {"topic", "N|GUID", "the topic of --bcf (its number in `bcf list`, or its GUID)", NULL},
        {"out", "OUT.png", "output image (required)", NULL},
        {"size", "WxH", "output size (default: the camera's)", NULL},
        {"video", "IMG", "camera frame to overlay (raw, distorted)", NULL},
        {"hidden", "GLOB", "extra node-name glob for the hidden layer", NULL},
        {"verbose", NULL, "print the passes that ran and more", NULL},
        {"quiet", NULL, "errors only", NULL},
        MR_CLI_RESEARCH_ROWS,
        {"aux", "DIR", "also write depth.pfm (linear view depth), normal.pfm, ao.pfm (1 = unoccluded) and shadow.pfm", NULL},
        APP_DRAW_OPTS,
        APP_RIG_OPTS,
        {"lod-cache", "on|off", "read/write LOD levels in <scene>.mrlod and meshlets in <scene>.mrclu (default on)", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    mr_gt_params gtp = MR_GT_DEFAULTS;
    mr_rig_params rp = MR_RIG_DEFAULTS;
    mr_draw_params dp = MR_DRAW_DEFAULTS;
    mr_cli_table tables[] = {{.prefix = "", .table = mr_frame_opts, .params = &fp}, APP_AO_TABLE(&fp.ao), APP_GT_TABLE(&gtp),
                             APP_GHOST_TABLE(&fp.ghost),
                             APP_SHADOW_TABLE(&fp.shadow), APP_RIG_TABLE(&rp), APP_DRAW_TABLE(&dp)};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, tables, 7, NULL, 0, NULL,
                   "usage: mrcheck render --scene FILE (--view VIEW.json|auto | --bcf FILE --topic N) --out OUT.png [--size WxH] "
                   "[--video IMG --alpha A] [--aux DIR] [--ao METHOD ...] [--ghost off|alpha|g0|adaptive] "
                   "[--shadows off|hard|pcf|pcss|bp|groundtruth ...] "
                   "[--views N --view-cone DEG [--focal-distance D] [--quilt SPEC]: --out is then a folder]",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *scene_path = mr_cli_get(opts, "scene"), *view_path = mr_cli_get(opts, "view"), *out = mr_cli_get(opts, "out");
    const char *bcf = mr_cli_get(opts, "bcf");
    if (!scene_path || !out || !(view_path || bcf) || (bcf && (view_path || !mr_cli_get(opts, "topic"))))
        return mr_cli_errorf(cmd, "--scene, --out and --view (or --bcf with --topic) are required"), 2;

    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &fp.width, &fp.height)) return 2;
    mr_error err = {0};
    mr_lod_mode lod_mode;
    if (!mr_lod_mode_parse(mr_cli_get(opts, "lod"), &lod_mode, &err)) return mr_cli_error(cmd, &err), 2;
    const char *lod_cache = mr_cli_get(opts, "lod-cache");
    if (lod_cache && strcmp(lod_cache, "on") != 0 && strcmp(lod_cache, "off") != 0)
        return mr_cli_errorf(cmd, "--lod-cache must be 'on' or 'off'"), 2;
    if (!mr_hlod_mode_check(mr_cli_get(opts, "hlod"), &err)) return mr_cli_error(cmd, &err), 2;
    const char *aux = mr_cli_get(opts, "aux");
    fp.want_depth = fp.want_normals = aux != NULL;
    bool groundtruth = false;
    mr_error aerr = {0};
    if (!mr_eval_ao_opts_check(&tables[1], &groundtruth, &gtp, &aerr)) return mr_cli_error(cmd, &aerr), 2;
    fp.ao.want_ao = aux != NULL;
    fp.ao.temporal = false; /* a single frame has nothing to accumulate */
    fp.shadow.want_shadow = aux != NULL;
    mr_quilt quilt = {0};
    bool have_quilt;
    if (!mr_rig_opts_check(&tables[5], mr_cli_get(opts, "quilt"), mr_cli_get(opts, "lightfield") != NULL, &quilt,
                           &have_quilt, &err))
        return mr_cli_error(cmd, &err), 2;
    bool multiview = rp.views > 0 || have_quilt;
    if (multiview && (aux || groundtruth || mr_cli_get(opts, "video")))
        return mr_cli_errorf(cmd, "--aux, --video and --ao groundtruth are for single views, not --views"), 2;
    long lf_band = 0;
    if (mr_cli_get(opts, "lightfield")) {
        if (!mr_cli_int("lightfield", mr_cli_get(opts, "lightfield"), 1, 16384, &lf_band)) return 2;
        if (mr_cli_get(opts, "video") || fp.ghost.mode != MR_GHOST_OFF)
            return mr_cli_errorf(cmd, "--lightfield draws no --video and no --ghost"), 2;
    }
    /* filled by mr_display_setup once the GPU is there */
    mr_display_map lf_map = {0};
    if (lf_band > 0) fp.display = gtp.display = &lf_map;

    /* Everything that can be checked without a GPU is checked first, so a
     * bad input never costs a context. */
    mr_view view;
    bool auto_view = view_path && strcmp(view_path, "auto") == 0;
    if (!bcf && !auto_view && !mr_view_load(view_path, &view, &err)) return mr_cli_error(cmd, &err);
    mr_image video = {0};
    if (mr_cli_get(opts, "video")) {
        if (!mr_image_load(mr_cli_get(opts, "video"), 3, &video, &err)) return mr_cli_error(cmd, &err);
        fp.video = &video;
    }
    const char *globs[1] = {mr_cli_get(opts, "hidden")};
    mr_scene_params sp = {.hidden_globs = globs, .hidden_glob_count = globs[0] ? 1 : 0}; /* else MR_SCENE_DEFAULTS */
    mr_scene *scene = mr_scene_load_logged(scene_path, &sp, &err);
    if (!scene || (bcf && !mr_bcf_render_setup(bcf, mr_cli_get(opts, "topic"), scene,
                                               &(mr_bcf_view_params){1.0, fp.width, fp.height, false}, &view, &err))) {
        mr_scene_destroy(&scene);
        mr_image_free(&video);
        return mr_cli_error(cmd, &err);
    }
    if (auto_view) view = mr_scene_auto_view(scene, fp.width, fp.height);
    if (!mr_shadow_scene_default(&tables[4], scene, &fp.shadow, &err)) {
        mr_cli_error(cmd, &err);
        mr_scene_destroy(&scene);
        mr_image_free(&video);
        return 2;
    }
    mr_lod *lod = NULL;
    mr_hlod *hlod = NULL; /* levels above the part where the scene wants them (--hlod) */
    const bool use_cache = (!lod_cache || strcmp(lod_cache, "on") == 0) && scene->source[0]; /* none for an edited scene */
    dp.no_lod = !mr_lod_wanted(lod_mode, scene);
    if (!dp.no_lod && (!(lod = mr_lod_load_logged(scene, scene->source, use_cache, &err)) ||
                       !mr_hlod_load_logged(scene, lod, scene->source, mr_cli_get(opts, "hlod"), use_cache, &hlod, &err))) {
        mr_lod_destroy(&lod);
        mr_scene_destroy(&scene);
        mr_image_free(&video);
        return mr_cli_error(cmd, &err);
    }

    int rc = 0;
    mr_gfx gfx;
    mr_frame_result res = {0};
    if (!mr_gfx_open(&gfx, &err)) {
        rc = mr_cli_error(cmd, &err);
    } else {
        /* Meshlets cached beside the file too */
        char clu[4096] = "";
        if (use_cache) mr_cluster_cache_path(scene->source, clu, sizeof clu);
        double t_up = mr_time_now();
        bool set = mr_renderer_set_cluster_cache(gfx.renderer, clu, &err) && mr_renderer_set_draw_params(gfx.renderer, &dp, &err) &&
                   mr_renderer_set_scene_lod(gfx.renderer, scene, lod, &err) && /* one upload, levels included */
                   mr_renderer_set_hlod(gfx.renderer, hlod, &err);
        double t_upload = mr_time_now() - t_up;
        if (!set) {
            rc = mr_cli_error(cmd, &err);
        } else if (multiview) {
            mr_rig_result rr;
            mr_rig_files job = {&rp, &quilt, out, out, "quilt", 0, {0}};
            if (!mr_render_rig_files(gfx.renderer, scene, &job, &view, &fp, &rr, &err))
                rc = mr_cli_error(cmd, &err);
            else if (!mr_cli_flag(opts, "quiet"))
                printf("rendered %d views of %dx%d into %s/ (quilt %dx%d, focal distance %g) in %.0f ms\n", rr.views,
                       job.layout.tile_w, job.layout.tile_h, out, job.layout.cols, job.layout.rows, job.focal, rr.ms_total);
            /* What the views shared. */
            if (rc == 0 && mr_cli_flag(opts, "verbose"))
                fprintf(stderr, "mrcheck: render: %d views: %d frustum culls, %d shadow map passes, culling %.2f ms\n",
                        rr.views, rr.frustum_culls, rr.shadow_maps, rr.cull_ms);
        } else if (lf_band > 0 && !mr_display_setup(gfx.renderer, scene, &rp, (int)lf_band, &view, &fp, &lf_map,
                                                       &err)) {
            rc = mr_cli_error(cmd, &err);
        } else if (!mr_render_frame(gfx.renderer, &view, &fp, &res, &err) ||
                   (groundtruth && !mr_eval_render_groundtruth_ao(gfx.renderer, scene, &view, &fp, &gtp, &res, &err)))
            rc = mr_cli_error(cmd, &err);
        else if (!mr_image_save_png(out, &res.color, &err) || (aux && !mr_frame_result_save_aux(aux, &res, &err)))
            rc = mr_cli_error(cmd, &err);
        if (rc == 0 && !multiview && mr_cli_flag(opts, "verbose")) mr_render_report(stderr, gfx.renderer, &res, t_upload);
        mr_frame_result_free(&res);
        mr_gfx_close(&gfx);
    }
    mr_hlod_destroy(&hlod);
    mr_lod_destroy(&lod);
    mr_scene_destroy(&scene);
    mr_image_free(&video);
    return rc;
}
