/* mr_batch_replay: a recording's frames rendered with the plan at their
 * recorded poses (`mrcheck replay`). */
#include "mr_batch.h"

#include "mr_eval.h"
#include "mr_track.h"

#include <stddef.h>
#include <stdlib.h>
#include <unistd.h>

#define RP(f) offsetof(mr_batch_replay_params, f)
const mr_opt mr_batch_replay_opts[] = {
    {"alpha", MR_OPT_FLOAT, RP(frame.alpha), 0, 1, MR_FRAME_DEFAULT_ALPHA, NULL,
     "video transparency: 0 = virtual only, 1 = video only", 0},
    {"every", MR_OPT_INT, RP(every), 1, 1 << 30, 1, NULL, "every Nth frame", 0},
    {"from", MR_OPT_INT, RP(from), 0, 2147483647, 0, NULL, "first frame number", 0},
    {"to", MR_OPT_INT, RP(to), 0, 2147483647, -1, NULL, "last frame number (auto: the last)", MR_OPT_NEG_AUTO},
    {"raw", MR_OPT_BOOL, RP(raw), 0, 1, 0, NULL, "use the raw pose instead of the filtered one", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef RP

bool mr_batch_replay_check(const mr_batch_replay_params *p, mr_error *err) {
    if (!p->out_dir) return mr_fail(err, MR_ERR_INVALID, "replay needs an output folder");
    if (!mr_outdir_check(p->out_dir, p->force, err)) return false;
    if ((p->render || p->rig) && p->video_path) return mr_fail(err, MR_ERR_INVALID, "--video is for single views, not --views");
    if (p->to >= 0 && p->to < p->from)
        return mr_fail(err, MR_ERR_INVALID, "--to %d is before --from %d", p->to, p->from);
    return true;
}

/* The video's rate: the recording's median frame interval. */
static double recording_fps(const mr_recording *rec, int every) {
    double fps = 10;
    if (rec->frame_count < 2) return fps;
    double *dt = malloc((size_t)rec->frame_count * sizeof *dt);
    int n = 0;
    for (int i = 1; dt && i < rec->frame_count; i++)
        if (rec->frames[i].t > rec->frames[i - 1].t) dt[n++] = rec->frames[i].t - rec->frames[i - 1].t;
    if (n > 0) fps = 1.0 / mr_median(dt, n) / (double)every;
    free(dt);
    return fps;
}

/* The AVI gets every written image; opened at the first one's size. */
static bool video_add(const mr_batch_replay_params *p, mr_video_writer **vw, const mr_image *img, double fps,
                      mr_error *err) {
    if (!p->video_path) return true;
    if (!*vw) *vw = mr_video_writer_open(p->video_path, img->width, img->height, fps, err);
    return *vw && mr_video_writer_add(*vw, img, err);
}

/* What the frame just drawn submitted (a rig: the draws of its last call). */
static void replay_count_draws(const mr_renderer *r, mr_batch_replay_stats *st) {
    mr_draw_stats ds;
    mr_renderer_draw_stats(r, &ds);
    st->triangles += ds.triangles;
    st->lod_instances += ds.lod_instances;
}

/* One rig frame: overlay_NNNNNN_qs...png and its views in overlay_NNNNNN/. */
static bool rig_frame(const mr_batch_replay_params *p, mr_renderer *r, const mr_scene *scene, const mr_view *view,
                      const mr_frame_params *fp, int64_t index, double *focal, char *name, size_t name_n, mr_error *err) {
    char stem[64], vdir[4096];
    snprintf(stem, sizeof stem, "overlay_%06lld", (long long)index);
    mr_path_join(p->out_dir, stem, vdir, sizeof vdir);
    mr_rig_files job = {p->rig, p->quilt, vdir, p->out_dir, stem, *focal, {0}};
    if (!mr_render_rig_files(r, scene, &job, view, fp, NULL, err)) return false;
    *focal = job.focal;
    mr_quilt_file_name(stem, &job.layout, name, name_n);
    return true;
}

/* A frame of the selection (every Nth from `from` up to `to`). */
static bool replay_selected(const mr_batch_replay_params *p, int every, int64_t index) {
    return index >= p->from && (p->to < 0 || index <= p->to) && (index - p->from) % every == 0;
}

/* After the loop: the index of what was written (also after a stop or a
 * failure, so the folder always matches its replay.jsonl), the video
 * closed, or the folder removed again if nothing was written. */
static bool replay_finish(const mr_batch_replay_params *p, mr_outdir *od, mr_jsonl *log, mr_video_writer **vw,
                          const mr_batch_replay_stats *st, bool ok, mr_error *err) {
    const int written = st->written;
    if (written > 0) {
        char path[4096];
        mr_path_join(p->out_dir, "replay.jsonl", path, sizeof path);
        mr_error ie = {0};
        bool indexed = mr_jsonl_save(log, path, &ie);
        if (ok && !indexed) ok = mr_fail(err, ie.code, "%s", ie.msg);
        if (ok || st->interrupted) {
            mr_error ve = {0};
            if (*vw && !mr_video_writer_close(vw, &ve) && ok) ok = mr_fail(err, ve.code, "%s", ve.msg);
        }
    }
    mr_video_writer_abort(vw); /* after a failure: no half-written video */
    if (written == 0) mr_outdir_abandon(od);
    if (ok && st->interrupted) {
        if (written > 0)
            ok = mr_fail(err, MR_ERR_INTERRUPTED, "interrupted after frame %lld: %d images and replay.jsonl in %s/%s",
                         (long long)st->last_frame, written, p->out_dir, p->video_path ? " (and the video)" : "");
        else
            ok = mr_fail(err, MR_ERR_INTERRUPTED, "interrupted before the first frame; nothing written");
    }
    return ok;
}

bool mr_batch_replay(const mr_batch_replay_params *p, mr_renderer *r, const mr_scene *scene,
                     mr_batch_replay_stats *stats, mr_error *err) {
    mr_batch_replay_stats st = {0};
    if (stats) *stats = st;
    if (!mr_batch_replay_check(p, err)) return false;
    if (!p->recording) return mr_fail(err, MR_ERR_INVALID, "replay needs a recording");
    const int every = p->every > 0 ? p->every : 1;
    const mr_recording *rec = p->recording;
    int total = 0;
    for (int i = 0; i < rec->frame_count; i++) total += replay_selected(p, every, rec->frames[i].index);
    if (total == 0) return mr_fail(err, MR_ERR_INVALID, "no recorded frame in the selected range");
    mr_outdir od;
    if (!mr_outdir_create(&od, p->out_dir, p->force, err)) return false;
    bool ok = mr_renderer_set_scene_lod(r, scene, p->lod, err) && mr_renderer_set_hlod(r, p->lod ? p->hlod : NULL, err);
    mr_jsonl log = {0};
    mr_video_writer *vw = NULL;
    const double fps = recording_fps(rec, every);
    const bool tty = p->progress && isatty(2);
    int selected = 0;
    double rig_focal = 0; /* the first rig frame's, kept */
    bool ao_restart = true; /* --ao-temporal restarts after a frame without a pose (a tracking reset) */
    for (int i = 0; ok && i < rec->frame_count; i++) {
        const mr_rec_frame *f = &rec->frames[i];
        if (!replay_selected(p, every, f->index)) continue;
        if (mr_stop_requested()) {
            st.interrupted = true;
            break;
        }
        selected++;
        if (tty) fprintf(stderr, "\rreplay: frame %lld (%d/%d)", (long long)f->index, selected, total);
        mr_image img;
        mr_error fe = {0};
        if (!mr_recording_load_image(rec, i, false, &img, &fe)) {
            fprintf(stderr, "mrcheck: replay: warning: frame %lld: %s\n", (long long)f->index, fe.msg);
            continue;
        }
        bool has_pose = (!p->raw && f->has_filtered) || f->pose.valid;
        bool have_centre_sigma = false;
        double centre_sigma = 0;
        mr_dmat4 pose = !p->raw && f->has_filtered ? f->filtered : f->pose.world_from_camera;
        char name[64], path[4096];
        snprintf(name, sizeof name, "overlay_%06lld.png", (long long)f->index);
        mr_path_join(p->out_dir, name, path, sizeof path);
        if (p->render || p->rig) {
            if (has_pose) {
                mr_view view = {mr_camera_resized(&rec->camera, img.width, img.height), pose};
                mr_frame_params fp = p->frame;
                fp.ao.temporal_reset = ao_restart;
                ao_restart = false;
                ok = p->rig ? rig_frame(p, r, scene, &view, &fp, f->index, &rig_focal, name, sizeof name, err)
                            : p->render(p->render_user, r, &view, &fp, f->index, name, sizeof name, err);
                replay_count_draws(r, &st);
                st.overlays++;
            } else {
                ao_restart = true;
                snprintf(name, sizeof name, "-");
                st.plain++;
            }
        } else if (has_pose) {
            mr_view view = {mr_camera_resized(&rec->camera, img.width, img.height), pose};
            mr_frame_params fp = p->frame;
            fp.video = &img;
            fp.ao.temporal_reset = ao_restart;
            ao_restart = false;
            mr_frame_result res;
            ok = mr_render_frame(r, &view, &fp, &res, err) && mr_image_save_png(path, &res.color, err) &&
                 video_add(p, &vw, &res.color, fps, err);
            const int rw = ok ? res.color.width : 0, rh = ok ? res.color.height : 0;
            if (ok) mr_frame_result_free(&res);
            /* The registration's σ at the model under the centre,
             * when the recording has the pose's covariance (one pixel read
             * back from the frame just drawn). */
            mr_pick cp = {0};
            mr_pose sp = f->pose;
            sp.valid = true;
            sp.world_from_camera = pose;
            if (ok && f->pose.corner_sigma_px > 0 &&
                mr_renderer_pick(r, rw * 0.5 - 0.5, rh * 0.5 - 0.5, &cp, &(mr_error){0}) &&
                cp.hit && mr_pose_point_sigma(&sp, cp.world, &centre_sigma, NULL))
                have_centre_sigma = true;
            replay_count_draws(r, &st);
            st.overlays++;
        } else {
            /* No pose: the camera frame alone keeps the sequence complete. */
            ao_restart = true;
            ok = mr_image_save_png(path, &img, err) && video_add(p, &vw, &img, fps, err);
            st.plain++;
        }
        mr_image_free(&img);
        if (!ok) break;
        st.last_frame = f->index;
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "frame", (double)f->index);
        cJSON_AddNumberToObject(o, "t", f->t);
        cJSON_AddStringToObject(o, "image", name);
        cJSON_AddBoolToObject(o, "overlay", has_pose);
        if (has_pose) cJSON_AddItemToObject(o, "world_from_camera", mr_json_from_dmat4(&pose));
        if (have_centre_sigma) cJSON_AddNumberToObject(o, "centre_uncertainty_m", centre_sigma);
        if (!mr_jsonl_add(&log, o)) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
        else st.written++;
        cJSON_Delete(o);
    }
    if (tty && selected) fprintf(stderr, "\r\033[K");
    ok = replay_finish(p, &od, &log, &vw, &st, ok, err);
    mr_jsonl_free(&log);
    mr_renderer_set_scene(r, NULL, &(mr_error){0});
    if (stats) *stats = st;
    return ok;
}
