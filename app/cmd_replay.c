/* mrcheck replay: headless overlays of a recording's frames with the
 * planned model at their recorded poses. Deterministic: the same recording
 * gives the same poses and the same images. */
#include "app_track.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int cmd_replay(int argc, char **argv) {
    static const char *cmd = "replay";
    app_opt opts[] = {
        {"scene", "S", "glTF/GLB or scene config of the plan (required)", NULL},
        {"out", "OUTDIR", "where overlay_NNNNNN.png and replay.jsonl go (required)", NULL},
        {"alpha", "A", "video transparency: 0 = virtual only, 1 = video only (default 0.5)", NULL},
        {"every", "N", "every Nth frame (default 1)", NULL},
        {"from", "F", "first frame number (default 0)", NULL},
        {"to", "T", "last frame number (default: the last)", NULL},
        {"raw", NULL, "use the raw pose instead of the filtered one", NULL},
        {"video", "FILE.avi", "also write the overlays as a Motion-JPEG AVI at the recording's rate", NULL},
        APP_AO_OPTS,
        APP_RIG_OPTS,
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[1];
    int npos = 0;
    /* Depth cues as on render: the same option tables and checks. */
    mr_frame_params base = MR_FRAME_DEFAULTS;
    mr_rig_params rp = MR_RIG_DEFAULTS;
    app_table tables[] = {APP_AO_TABLE(&base.ao), APP_GHOST_TABLE(&base.ghost), APP_RIG_TABLE(&rp)};
    bool help;
    if (!app_parse_tables(argc, argv, 2, opts, tables, 3, pos, 1, &npos,
                   "usage: mrcheck replay DIR --scene S --out OUTDIR [--alpha A] [--every N] [--from F --to T] [--raw] "
                   "[--video F.avi] [--ao METHOD ...] [--ghost MODE ...] "
                   "[--views N --view-cone DEG [--focal-distance D] [--quilt SPEC]]",
                   &help))
        return 2;
    if (help) return 0;
    app_log_level(opts);
    if (npos != 1 || !app_get(opts, "scene") || !app_get(opts, "out"))
        return app_errorf(cmd, "needs a recording folder, --scene and --out (see --help)"), 2;
    double alpha = 0.5;
    long every = 1, from = 0, to = -1;
    if (app_get(opts, "alpha") && !app_double("alpha", app_get(opts, "alpha"), 0, 1, &alpha)) return 2;
    if (app_get(opts, "every") && !app_int("every", app_get(opts, "every"), 1, 1L << 30, &every)) return 2;
    if (app_get(opts, "from") && !app_int("from", app_get(opts, "from"), 0, 1L << 40, &from)) return 2;
    if (app_get(opts, "to") && !app_int("to", app_get(opts, "to"), 0, 1L << 40, &to)) return 2;
    if (to >= 0 && to < from) return app_errorf(cmd, "--to %ld is before --from %ld", to, from), 2;
    const char *out = app_get(opts, "out");
    bool raw = app_flag(opts, "raw");
    bool groundtruth = false;
    mr_gt_params gtp = MR_GT_DEFAULTS;
    if (!app_ao_check(cmd, &tables[0], opts, &groundtruth, &gtp)) return 2;
    if (groundtruth) return app_errorf(cmd, "--ao groundtruth is for single frames (mrcheck render), not replays"), 2;
    mr_quilt quilt = {0};
    bool have_quilt;
    if (!app_rig_check(cmd, &tables[2], opts, &quilt, &have_quilt)) return 2;
    if (app_get(opts, "lightfield")) return app_errorf(cmd, "--lightfield is for single frames (mrcheck render)"), 2;
    /* Multi-view: per frame a quilt overlay_NNNNNN_qs..png and its views in
     * overlay_NNNNNN/; the camera frame is seen from one eye only, so the
     * views show the plan alone. */
    bool multiview = rp.views > 0 || have_quilt;
    if (multiview && app_get(opts, "video")) return app_errorf(cmd, "--video is for single views, not --views"), 2;
    double focal = 0;

    mr_error err = {0};
    mr_recording *rec = mr_recording_open(pos[0], &err);
    if (!rec) return app_error(cmd, &err);
    if (multiview) {
        /* A quilt too small for the views is bad input: found before any
         * output folder or GPU context is made. */
        mr_quilt_layout ql;
        mr_rig_params chk = rp;
        if (chk.views == 0) chk.views = quilt.cols * quilt.rows;
        if (!mr_quilt_layout_make(quilt.cols ? &quilt : NULL, chk.views, rec->camera.width, rec->camera.height, &ql, &err)) {
            mr_recording_close(&rec);
            return app_error(cmd, &err);
        }
    }
    mr_scene *scene = mr_scene_load(app_get(opts, "scene"), NULL, &err);
    app_gfx gfx = {0};
    bool ok = scene && mr_mkdirs(out, &err) && app_gfx_open(&gfx, &err) && mr_renderer_set_scene(gfx.renderer, scene, &err);
    cJSON *log = cJSON_CreateArray();
    int rendered = 0, plain = 0, selected = 0;
    mr_video_writer *vw = NULL;
    /* the video's rate: the recording's median frame interval */
    double fps = 10;
    if (rec->frame_count > 1) {
        double *dt = malloc((size_t)rec->frame_count * sizeof *dt);
        int n = 0;
        for (int i = 1; dt && i < rec->frame_count; i++)
            if (rec->frames[i].t > rec->frames[i - 1].t) dt[n++] = rec->frames[i].t - rec->frames[i - 1].t;
        if (n > 0) fps = 1.0 / mr_median(dt, n) / (double)every;
        free(dt);
    }
    for (int i = 0; ok && i < rec->frame_count; i++) {
        const mr_rec_frame *f = &rec->frames[i];
        if (f->index < from || (to >= 0 && f->index > to) || (f->index - from) % every != 0) continue;
        selected++;
        if (isatty(2)) fprintf(stderr, "\rreplay: frame %lld", (long long)f->index);
        mr_image img;
        mr_error fe = {0};
        if (!mr_recording_load_image(rec, i, false, &img, &fe)) {
            fprintf(stderr, "mrcheck: replay: warning: frame %lld: %s\n", (long long)f->index, fe.msg);
            continue;
        }
        bool has_pose = (!raw && f->has_filtered) || f->pose.valid;
        mr_dmat4 pose = !raw && f->has_filtered ? f->filtered : f->pose.world_from_camera;
        char name[64], path[4096];
        snprintf(name, sizeof name, "overlay_%06lld.png", (long long)f->index);
        mr_path_join(out, name, path, sizeof path);
        if (has_pose && multiview) {
            mr_view view = {mr_camera_resized(&rec->camera, img.width, img.height), pose};
            char stem[64], vdir[4096];
            snprintf(stem, sizeof stem, "overlay_%06lld", (long long)f->index);
            mr_path_join(out, stem, vdir, sizeof vdir);
            mr_quilt_layout ql;
            ok = app_rig_render(gfx.renderer, scene, &rp, &quilt, &view, &base, vdir, out, stem, &focal, &ql, NULL, &err);
            if (ok) mr_quilt_file_name(stem, &ql, name, sizeof name);
            rendered++;
        } else if (multiview) {
            /* No pose: nothing to show on a 3D display; the log says so. */
            snprintf(name, sizeof name, "-");
            plain++;
        } else if (has_pose) {
            mr_view view = {mr_camera_resized(&rec->camera, img.width, img.height), pose};
            mr_frame_params fp = base;
            fp.video = &img;
            fp.alpha = (float)alpha;
            mr_frame_result res;
            ok = mr_render_frame(gfx.renderer, &view, &fp, &res, &err) && mr_image_save_png(path, &res.color, &err);
            if (ok && app_get(opts, "video") && !vw) vw = mr_video_writer_open(app_get(opts, "video"), res.color.width, res.color.height, fps, &err);
            if (ok && app_get(opts, "video")) ok = vw && mr_video_writer_add(vw, &res.color, &err);
            if (ok) mr_frame_result_free(&res);
            rendered++;
        } else {
            /* No pose: the camera frame alone keeps the sequence complete. */
            ok = mr_image_save_png(path, &img, &err);
            if (ok && app_get(opts, "video") && !vw) vw = mr_video_writer_open(app_get(opts, "video"), img.width, img.height, fps, &err);
            if (ok && app_get(opts, "video")) ok = vw && mr_video_writer_add(vw, &img, &err);
            plain++;
        }
        mr_image_free(&img);
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "frame", (double)f->index);
        cJSON_AddNumberToObject(o, "t", f->t);
        cJSON_AddStringToObject(o, "image", name);
        cJSON_AddBoolToObject(o, "overlay", has_pose);
        if (has_pose) cJSON_AddItemToObject(o, "world_from_camera", mr_json_from_dmat4(&pose));
        cJSON_AddItemToArray(log, o);
    }
    if (isatty(2) && selected) fprintf(stderr, "\r\033[K");
    if (ok && selected == 0) ok = mr_fail(&err, MR_ERR_INVALID, "no recorded frame in the selected range");
    if (ok) {
        /* replay.jsonl: one line per written image, written atomically. */
        size_t cap = 1024, len = 0;
        char *buf = malloc(cap);
        cJSON *o;
        cJSON_ArrayForEach(o, log) {
            char *s = cJSON_PrintUnformatted(o);
            size_t n = s ? strlen(s) : 0;
            if (buf && len + n + 2 > cap) {
                while (len + n + 2 > cap) cap *= 2;
                char *nb = realloc(buf, cap);
                if (!nb) free(buf);
                buf = nb;
            }
            if (buf && s) {
                memcpy(buf + len, s, n);
                len += n;
                buf[len++] = '\n';
            }
            free(s);
        }
        char path[4096];
        mr_path_join(out, "replay.jsonl", path, sizeof path);
        ok = buf ? mr_file_write_atomic(path, buf, len, &err) : mr_fail(&err, MR_ERR_NOMEM, "out of memory");
        free(buf);
    }
    cJSON_Delete(log);
    if (ok && vw) ok = mr_video_writer_close(&vw, &err);
    mr_video_writer_abort(&vw); /* after a failure: no half-written video */
    app_gfx_close(&gfx);
    mr_scene_destroy(&scene);
    mr_recording_close(&rec);
    if (!ok) return app_error(cmd, &err);
    printf("replayed %d frames to %s/: %d overlays, %d without a pose (camera frame only)\n", rendered + plain, out,
           rendered, plain);
    return 0;
}
