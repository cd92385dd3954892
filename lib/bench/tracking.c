/* mrcheck bench tracking (mr_bench_tracking): error against run time of the tag detector
 * settings (and OpenCV's aruco detector as the peer) on a recording with
 * ground truth. CSV + SVG; measures, never asserts. */
#include "bench_internal.h"
#include "mr_session.h"
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct setting {
    char name[48];
    bool aruco;
    bool adaptive;              /* the tracker's own detector, adaptive decimation (mrcheck track's default) */
    double decimate;
    int threads;
    int refine;                 /* apriltag: edge refinement 0/1; aruco: mr_aruco_refine */
} setting;

typedef struct result {
    double ms_med, ms_p95, det_ms_med;
    double t_err_mm, t_err_pct, r_err_deg, rms_px;
    double det_rate, det_rate56, det_rate_still, pose_rate, flip_rate;
    double pose_rate20;         /* frames with a pose / frames where a tag of >= 20 px is in view */
    double dec_mean;            /* mean decimation used (adaptive) */
    double jit_raw_mm, jit_raw_deg, jit_filt_mm, jit_filt_deg;
    int frames;
} result;

/* Which tags the ground-truth camera sees: all corners in the image (2 px
 * margin), the tag facing the camera; shortest projected edge in *edge. */
static bool gt_visible(const mr_camera *cam, const mr_marker_map *map, const mr_marker *m, const mr_dmat4 *gt, double *edge) {
    mr_dvec3 w[4];
    mr_marker_corners_world(map, m, w);
    double uv[4][2];
    for (int k = 0; k < 4; k++) {
        if (!mr_project_point(cam, gt, w[k], &uv[k][0], &uv[k][1])) return false;
        if (uv[k][0] < 2 || uv[k][1] < 2 || uv[k][0] > cam->width - 3 || uv[k][1] > cam->height - 3) return false;
    }
    /* facing: the tag's -z (its outward normal) points towards the camera */
    mr_dvec3 n = mr_v3(-m->world_from_tag.m[2], -m->world_from_tag.m[6], -m->world_from_tag.m[10]);
    mr_dvec3 c = mr_v3(m->world_from_tag.m[3], m->world_from_tag.m[7], m->world_from_tag.m[11]);
    mr_dvec3 to_cam = mr_v3_sub(mr_v3(gt->m[3], gt->m[7], gt->m[11]), c);
    if (mr_v3_dot(n, to_cam) <= 0) return false;
    *edge = INFINITY;
    for (int k = 0; k < 4; k++) *edge = fmin(*edge, hypot(uv[(k + 1) % 4][0] - uv[k][0], uv[(k + 1) % 4][1] - uv[k][1]));
    return true;
}

/* Standard deviation of poses over each pause (a run of still ground-truth
 * frames), combined as an RMS over pauses. */
typedef struct jitter_acc { double sum_t2, sum_r2; int n; } jitter_acc;

static void jitter_segment(const mr_dmat4 *p, int n, jitter_acc *acc) {
    if (n < 3) return;
    mr_dvec3 mean = mr_v3(0, 0, 0);
    for (int i = 0; i < n; i++) mean = mr_v3_add(mean, mr_v3(p[i].m[3], p[i].m[7], p[i].m[11]));
    mean = mr_v3_scale(mean, 1.0 / n);
    /* rotation spread about the middle sample */
    const mr_dmat4 *ref = &p[n / 2];
    for (int i = 0; i < n; i++) {
        double d = mr_v3_len(mr_v3_sub(mr_v3(p[i].m[3], p[i].m[7], p[i].m[11]), mean));
        double a = mr_pose_angle_deg(&p[i], ref);
        acc->sum_t2 += d * d;
        acc->sum_r2 += a * a;
        acc->n++;
    }
}

/* The tracking of one frame: detection by the setting under test
 * (AprilTag, or OpenCV aruco as the peer), timed on its own, then
 * everything after detection by lib/track's one tracker (undistortion, the
 * solve with its previous-pose policy, the One Euro filter), so the bench
 * measures what `track` and `view` run. ms: detection + pose + filter. */
typedef struct tracker {
    mr_detector *det; /* or */
    mr_aruco *ar;
    mr_tracker *trk;
} tracker;
typedef struct track_out {
    const mr_detection *dets;
    int count;
    mr_pose pose;     /* raw */
    mr_dmat4 filtered; /* = the raw pose when there is no filtered one */
    double detect_ms, ms;
    double decimate;   /* the tracker's own detector: what it used */
} track_out;

static bool track_step(tracker *t, const mr_image *img, double ts, track_out *o, mr_error *err) {
    double t0 = mr_time_now();
    if (!t->det && !t->ar) {
        /* The tracker's own detector: mr_tracker_frame as `track` runs it. */
        mr_tracker_result r;
        bool ok = mr_tracker_frame(t->trk, img, ts, &r, err);
        o->ms = o->detect_ms = (mr_time_now() - t0) * 1e3;
        o->dets = r.detections;
        o->count = r.detection_count;
        o->pose = r.pose;
        o->filtered = ok && r.has_filtered ? r.filtered : r.pose.world_from_camera;
        o->decimate = r.decimate;
        return ok;
    }
    o->count = 0;
    o->dets = t->ar ? mr_aruco_detect(t->ar, img, &o->count, err) : mr_detector_detect(t->det, img, &o->count, err);
    double t1 = mr_time_now();
    if (!o->dets) return false;
    mr_tracker_result r;
    bool ok = mr_tracker_detections(t->trk, o->dets, o->count, img->width, img->height, ts, &r, err);
    double t2 = mr_time_now();
    o->ms = (t2 - t0) * 1e3;
    o->detect_ms = (t1 - t0) * 1e3;
    o->pose = r.pose;
    o->filtered = ok && r.has_filtered ? r.filtered : r.pose.world_from_camera;
    return ok;
}

static bool run_setting(const setting *s, const mr_recording *rec, const mr_image *imgs, const int *fidx, int nf,
                        const mr_filter_params *fparams, result *res, mr_error *err) {
    memset(res, 0, sizeof *res);
    mr_detector *det = NULL;
    mr_aruco *ar = NULL;
    if (s->aruco) {
        ar = mr_aruco_create((mr_aruco_refine)s->refine, err);
        if (!ar) return false;
    } else if (!s->adaptive) {
        mr_detector_params dp = MR_DETECTOR_DEFAULTS;
        dp.family = rec->markers.family;
        dp.decimate = s->decimate;
        dp.threads = s->threads;
        dp.refine_edges = s->refine ? 1 : -1;
        det = mr_detector_create(&dp, err);
        if (!det) return false;
    }
    mr_tracker_params trp = MR_TRACKER_DEFAULTS;
    trp.camera = &rec->camera;
    trp.markers = &rec->markers;
    trp.detector.family = rec->markers.family;
    trp.filter = *fparams;
    mr_tracker *trk = mr_tracker_create(&trp, err);
    double *ms = calloc((size_t)nf, sizeof *ms), *dms = calloc((size_t)nf, sizeof *dms);
    double *te = calloc((size_t)nf, sizeof *te), *tp = calloc((size_t)nf, sizeof *tp), *re = calloc((size_t)nf, sizeof *re);
    double *rm = calloc((size_t)nf, sizeof *rm);
    mr_dmat4 *seg_raw = calloc((size_t)nf, sizeof *seg_raw), *seg_f = calloc((size_t)nf, sizeof *seg_f);
    bool ok = trk && ms && dms && te && tp && re && rm && seg_raw && seg_f;
    if (!ok && trk) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int nposes = 0, nflip = 0, vis = 0, vis_hit = 0, vis56 = 0, vis56_hit = 0, vis_st = 0, vis_st_hit = 0, seg_n = 0;
    int f20 = 0, f20_hit = 0;
    double dec_sum = 0;
    jitter_acc jr = {0}, jf = {0};
    tracker tk = {det, ar, trk};
    /* one untimed warm-up frame: thread pools, first allocations */
    int wn;
    if (ok && nf > 0) {
        if (ar) mr_aruco_detect(ar, &imgs[0], &wn, NULL);
        else if (det) mr_detector_detect(det, &imgs[0], &wn, NULL);
    }
    for (int i = 0; ok && i < nf; i++) {
        const mr_rec_frame *f = &rec->frames[fidx[i]];
        mr_camera cam = mr_camera_resized(&rec->camera, imgs[i].width, imgs[i].height);
        track_out tr;
        if (!(ok = track_step(&tk, &imgs[i], f->t, &tr, err))) break;
        const mr_detection *d = tr.dets;
        const int n = tr.count;
        const mr_pose pose = tr.pose;
        ms[i] = tr.ms;
        dms[i] = tr.detect_ms;
        /* detection rate against the tags the ground truth sees */
        double dist_sum = 0;
        int dist_n = 0;
        bool has20 = false;
        dec_sum += tr.decimate;
        for (int m = 0; m < rec->markers.count; m++) {
            double edge;
            if (!gt_visible(&cam, &rec->markers, &rec->markers.tags[m], &f->gt, &edge) || edge < 10) continue;
            has20 = has20 || edge >= 20;
            bool hit = false;
            for (int k = 0; k < n; k++) hit = hit || d[k].id == rec->markers.tags[m].id;
            vis++;
            vis_hit += hit;
            if (edge >= 56) {
                vis56++;
                vis56_hit += hit;
            }
            if (f->still) {
                vis_st++;
                vis_st_hit += hit;
            }
        }
        f20 += has20;
        f20_hit += has20 && pose.valid;
        const mr_dmat4 filtered = tr.filtered;
        if (pose.valid) {
            for (int k = 0; k < pose.tags_used && k < MR_POSE_MAX_IDS; k++) {
                const mr_marker *mk = mr_marker_map_find(&rec->markers, pose.ids_used[k]);
                if (!mk) continue;
                dist_sum += mr_v3_len(mr_v3(f->gt.m[3] - mk->world_from_tag.m[3], f->gt.m[7] - mk->world_from_tag.m[7],
                                            f->gt.m[11] - mk->world_from_tag.m[11]));
                dist_n++;
            }
            double e = mr_pose_dist(&pose.world_from_camera, &f->gt), a = mr_pose_angle_deg(&pose.world_from_camera, &f->gt);
            te[nposes] = e * 1e3;
            tp[nposes] = dist_n ? 100.0 * e / (dist_sum / dist_n) : NAN;
            re[nposes] = a;
            rm[nposes] = pose.rms_px;
            nflip += a > 5.0;
            nposes++;
        }
        /* pauses: consecutive still frames with a pose */
        bool in_pause = f->still && pose.valid;
        if (in_pause) {
            seg_raw[seg_n] = pose.world_from_camera;
            seg_f[seg_n] = filtered;
            seg_n++;
        }
        bool next_still = i + 1 < nf && rec->frames[fidx[i + 1]].still;
        if (!in_pause || !next_still || i + 1 == nf) {
            /* the filter needs a few frames to settle after the walk */
            if (seg_n > 4) {
                jitter_segment(seg_raw + 2, seg_n - 2, &jr);
                jitter_segment(seg_f + 2, seg_n - 2, &jf);
            }
            seg_n = 0;
        }
    }
    if (ok) {
        res->frames = nf;
        res->det_ms_med = mr_quantile(dms, nf, 0.5);
        res->ms_med = mr_quantile(ms, nf, 0.5);
        res->ms_p95 = mr_quantile(ms, nf, 0.95);
        res->t_err_mm = mr_quantile(te, nposes, 0.5);
        int np = 0;
        for (int i = 0; i < nposes; i++)
            if (isfinite(tp[i])) tp[np++] = tp[i];
        res->t_err_pct = mr_quantile(tp, np, 0.5);
        res->r_err_deg = mr_quantile(re, nposes, 0.5);
        res->rms_px = mr_quantile(rm, nposes, 0.5);
        res->det_rate = vis ? (double)vis_hit / vis : NAN;
        res->det_rate56 = vis56 ? (double)vis56_hit / vis56 : NAN;
        res->det_rate_still = vis_st ? (double)vis_st_hit / vis_st : NAN;
        res->pose_rate = nf ? (double)nposes / nf : 0;
        res->flip_rate = nposes ? (double)nflip / nposes : NAN;
        res->pose_rate20 = f20 ? (double)f20_hit / f20 : NAN;
        res->dec_mean = s->adaptive && nf ? dec_sum / nf : s->aruco ? NAN : s->decimate;
        res->jit_raw_mm = jr.n ? 1e3 * sqrt(jr.sum_t2 / jr.n) : NAN;
        res->jit_raw_deg = jr.n ? sqrt(jr.sum_r2 / jr.n) : NAN;
        res->jit_filt_mm = jf.n ? 1e3 * sqrt(jf.sum_t2 / jf.n) : NAN;
        res->jit_filt_deg = jf.n ? sqrt(jf.sum_r2 / jf.n) : NAN;
    }
    free(ms);
    free(dms);
    free(te);
    free(tp);
    free(re);
    free(rm);
    free(seg_raw);
    free(seg_f);
    mr_tracker_destroy(&trk);
    mr_detector_destroy(&det);
    mr_aruco_destroy(&ar);
    return ok;
}

/* Error against run time: median ms per frame (x) against median
 * translation error (y), both log scale over whole decades, one numbered
 * point per setting; the legend on the right names the numbers. */
static bool write_svg(const char *path, const char *title, const setting *s, const result *r, int n, mr_error *err) {
    double xmin = 1e9, xmax = 0, ymin = 1e9, ymax = 0;
    for (int i = 0; i < n; i++) {
        if (!isfinite(r[i].ms_med) || !isfinite(r[i].t_err_mm) || r[i].ms_med <= 0 || r[i].t_err_mm <= 0) continue;
        xmin = fmin(xmin, r[i].ms_med);
        xmax = fmax(xmax, r[i].ms_med);
        ymin = fmin(ymin, r[i].t_err_mm);
        ymax = fmax(ymax, r[i].t_err_mm);
    }
    if (xmax <= 0) xmin = 0.1, xmax = 1, ymin = 1, ymax = 10;
    xmin = pow(10, floor(log10(xmin)));
    xmax = pow(10, ceil(log10(fmax(xmax, xmin * 10))));
    ymin = pow(10, floor(log10(ymin)));
    ymax = pow(10, ceil(log10(fmax(ymax, ymin * 10))));
    mr_plot_series *ser = calloc((size_t)n + 1, sizeof *ser);
    char (*names)[160] = calloc((size_t)n + 1, sizeof *names), (*nums)[12] = calloc((size_t)n + 1, sizeof *nums);
    if (!ser || !names || !nums) {
        free(ser);
        free(names);
        free(nums);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < n; i++) {
        snprintf(names[i], sizeof names[i], "%2d %.47s: %.2f ms, %.1f mm, %.2f%%, flip %.0f%%", i + 1, s[i].name, r[i].ms_med,
                 r[i].t_err_mm, r[i].t_err_pct, 100 * r[i].flip_rate);
        snprintf(nums[i], sizeof nums[i], "%d", i + 1);
        ser[i] = (mr_plot_series){.name = names[i], .x = &r[i].ms_med, .y = &r[i].t_err_mm, .count = 1,
                                  .color = s[i].aruco ? "#e08a2c" : s[i].adaptive ? "#c0392b" : s[i].threads > 1 ? "#2c8a3b" : "#3b6fb6",
                                  .no_line = true, .point_label = nums[i]};
    }
    static const char *const notes[4] = {"blue: apriltag, 1 thread", "green: apriltag, 2 threads",
                                         "red: the tracker's adaptive decimation (default)",
                                         "orange: OpenCV aruco DICT_APRILTAG_36h11"};
    mr_plot_params pp = {.title = title, .xlabel = "median ms per frame (detection + pose, log scale)",
                         .ylabel = "median translation error, mm (log scale)", .log_x = true, .log_y = true,
                         .x_min = xmin, .x_max = xmax, .y_min = ymin, .y_max = ymax, .width = 1000,
                         .height = 120 + 18 * (n + 3), .legend_width = 330, .notes = notes, .note_count = 4};
    if (pp.height < 600) pp.height = 600;
    bool ok = mr_plot_write(path, &pp, ser, n, err);
    free(ser);
    free(names);
    free(nums);
    return ok;
}

bool mr_bench_tracking(const mr_bench_tracking_params *params, mr_error *err) {
    const mr_bench_tracking_params dflt = {MR_BENCH_TRACKING_DEFAULTS};
    mr_bench_tracking_params p = params ? *params : dflt;
    const char *dir = p.recording ? p.recording : dflt.recording;
    const char *out_dir = p.out_dir ? p.out_dir : dflt.out_dir;
    const long max_frames = p.max_frames > 0 ? p.max_frames : 1L << 30;
    FILE *out = p.out;
    mr_filter_params fparams = MR_FILTER_DEFAULTS;
    if (p.min_cutoff > 0) fparams.min_cutoff = p.min_cutoff;
    if (p.beta > 0) fparams.beta = p.beta;
    fparams.rot_min_cutoff = fparams.min_cutoff;
    mr_recording *rec = mr_recording_open(dir, err);
    if (!rec) return false;
    if (!rec->has_markers) {
        mr_recording_close(&rec);
        return mr_fail(err, MR_ERR_INVALID, "%s: the recording has no marker map", dir);
    }
    /* Decode every frame with ground truth once, up front (not timed). */
    int nf = 0;
    mr_image *imgs = calloc((size_t)rec->frame_count + 1, sizeof *imgs);
    int *fidx = calloc((size_t)rec->frame_count + 1, sizeof *fidx);
    bool ok = imgs && fidx;
    for (int i = 0; ok && i < rec->frame_count && nf < max_frames; i++) {
        if (!rec->frames[i].has_gt) continue;
        mr_error fe = {0};
        if (!mr_recording_load_image(rec, i, true, &imgs[nf], &fe)) {
            mr_log(MR_LOG_WARN, "bench tracking: %s", fe.msg);
            continue;
        }
        fidx[nf++] = i;
    }
    if (ok && nf == 0) ok = mr_fail(err, MR_ERR_INVALID, "%s: no frames with ground truth", dir);
    setting set[64];
    int ns = 0;
    static const double decs[] = {1, 1.5, 2, 3, 4};
    for (int di = 0; di < 5; di++)
        for (int th = 1; th <= 2; th++)
            for (int rf = 0; rf <= 1; rf++) {
                if (p.quick && (th == 2 || di % 2)) continue;
                setting *s = &set[ns++];
                memset(s, 0, sizeof *s);
                s->decimate = decs[di];
                s->threads = th;
                s->refine = rf;
                snprintf(s->name, sizeof s->name, "apriltag d%g t%d r%d", decs[di], th, rf);
            }
    /* The tracker as `track` runs it by default: adaptive decimation. */
    {
        setting *s = &set[ns++];
        memset(s, 0, sizeof *s);
        s->adaptive = true;
        s->threads = 1;
        s->refine = 1;
        snprintf(s->name, sizeof s->name, "tracker adaptive t1 r1");
    }
    for (int m = 0; m < 4; m++) {
        setting *s = &set[ns++];
        memset(s, 0, sizeof *s);
        s->aruco = true;
        s->refine = m;
        s->threads = 0;
        snprintf(s->name, sizeof s->name, "aruco %s", mr_aruco_refine_name((mr_aruco_refine)m));
    }
    result res[64];
    mr_csv *csv = ok ? mr_csv_create(err) : NULL;
    ok = ok && csv;
    if (ok) {
        mr_csv_header(csv, "detector,decimate,threads,refine,frames,ms_median,ms_p95,detect_ms_median,t_err_mm_median,"
                           "t_err_pct_median,r_err_deg_median,reproj_rms_px_median,detection_rate,detection_rate_56px,"
                           "detection_rate_still,pose_rate,flip_rate,jitter_raw_mm,jitter_raw_deg,jitter_filtered_mm,"
                           "jitter_filtered_deg,pose_rate_20px,decimate_mean");
        BENCH_PRINT(out, "bench tracking: %s, %d frames %dx%d, %s\n", dir, nf, imgs[0].width, imgs[0].height,
               "ms = detection + pose per frame (median / p95)");
        BENCH_PRINT(out, "%-22s %7s %7s %8s %7s %7s %6s %6s %6s %6s %6s %6s %13s %13s %6s %5s\n", "setting", "ms med", "ms p95", "t err mm",
               "t err %", "r err", "rms px", "det", "det56", "still", "pose", "flip", "jitter raw", "jitter filt", "pose20", "dec");
    }
    for (int i = 0; ok && i < ns; i++) {
        ok = run_setting(&set[i], rec, imgs, fidx, nf, &fparams, &res[i], err);
        if (!ok) break;
        const result *r = &res[i];
        BENCH_PRINT(out, "%-22s %7.2f %7.2f %8.1f %7.2f %7.3f %6.3f %5.1f%% %5.1f%% %5.1f%% %5.1f%% %5.1f%% %5.2fmm/%.3f° %5.2fmm/%.3f° %5.1f%% %5.2f\n",
               set[i].name, r->ms_med, r->ms_p95, r->t_err_mm, r->t_err_pct, r->r_err_deg, r->rms_px, 100 * r->det_rate,
               100 * r->det_rate56, 100 * r->det_rate_still, 100 * r->pose_rate, 100 * r->flip_rate, r->jit_raw_mm, r->jit_raw_deg, r->jit_filt_mm,
               r->jit_filt_deg, 100 * r->pose_rate20, r->dec_mean);
        if (out) fflush(out);
        mr_csv_text(csv, set[i].aruco ? "opencv-aruco" : set[i].adaptive ? "apriltag-adaptive" : "apriltag");
        mr_csv_num(csv, "%g", set[i].aruco ? 1.0 : set[i].adaptive ? 0.0 : set[i].decimate);
        mr_csv_int(csv, set[i].threads);
        mr_csv_text(csv, set[i].aruco ? mr_aruco_refine_name((mr_aruco_refine)set[i].refine) : set[i].refine ? "1" : "0");
        mr_csv_int(csv, r->frames);
        const double v[] = {r->ms_med,     r->ms_p95,       r->det_ms_med, r->t_err_mm,  r->t_err_pct,  r->r_err_deg,
                            r->rms_px,     r->det_rate,     r->det_rate56, r->det_rate_still, r->pose_rate, r->flip_rate,
                            r->jit_raw_mm, r->jit_raw_deg,  r->jit_filt_mm, r->jit_filt_deg,
                            r->pose_rate20, r->dec_mean};
        for (int k = 0; k < (int)(sizeof v / sizeof v[0]); k++) mr_csv_num(csv, k == 3 ? "%.3f" : "%.4f", v[k]); /* t_err_mm: %.3f */
        mr_csv_end_row(csv);
    }
    char path[4096];
    if (ok) ok = mr_mkdirs(out_dir, err);
    if (ok) {
        mr_path_join(out_dir, "bench_tracking.csv", path, sizeof path);
        ok = mr_csv_save(csv, path, err);
    }
    if (ok) {
        char title[256];
        snprintf(title, sizeof title, "mrcheck bench tracking: %d frames %dx%d — error against run time", nf, imgs[0].width,
                 imgs[0].height);
        mr_path_join(out_dir, "bench_tracking.svg", path, sizeof path);
        ok = write_svg(path, title, set, res, ns, err);
    }
    if (ok) BENCH_PRINT(out, "wrote %s/bench_tracking.csv and bench_tracking.svg\n", out_dir);
    mr_csv_destroy(&csv);
    for (int i = 0; imgs && i < nf; i++) mr_image_free(&imgs[i]);
    free(imgs);
    free(fidx);
    mr_recording_close(&rec);
    return ok;
}
