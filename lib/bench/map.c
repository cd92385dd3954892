/* bench map: the marker map from synthetic photo sets (synth_map.c) of
 * 10..200 photos with corner noise and wrong ids, ours (bundle adjustment)
 * against chaining relative poses along the spanning tree (no global
 * adjustment, what bundle calibrations without one give): map error in mm
 * and degrees against the true tag poses, and run time. Medians over seeds. */
#include "bench_internal.h"
#include "mr_bench.h"
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void map_error(const mr_map_result *r, const mr_marker_map *truth, double *rms_mm, double *max_mm,
                      double *max_deg) {
    double ss = 0, mx = 0, dg = 0;
    int n = 0;
    for (int i = 0; i < r->tag_count; i++) {
        const mr_marker *t = mr_marker_map_find(truth, r->tags[i].id);
        if (!t) continue;
        double d = mr_pose_dist(&r->tags[i].world_from_tag, &t->world_from_tag);
        ss += d * d;
        mx = fmax(mx, d);
        dg = fmax(dg, mr_pose_angle_deg(&r->tags[i].world_from_tag, &t->world_from_tag));
        n++;
    }
    *rms_mm = n ? 1e3 * sqrt(ss / n) : NAN;
    *max_mm = 1e3 * mx;
    *max_deg = dg;
}

bool mr_bench_map(const mr_bench_map_params *params, mr_error *err) {
    mr_bench_map_params p = params ? *params : (mr_bench_map_params){MR_BENCH_MAP_DEFAULTS};
    static const int k_counts[] = {10, 20, 50, 100, 200};
    int counts[5], ncounts = 0;
    for (int i = 0; i < 5; i++)
        if (p.max_photos <= 0 || k_counts[i] <= p.max_photos) counts[ncounts++] = k_counts[i];
    if (ncounts == 0) return mr_fail(err, MR_ERR_INVALID, "bench map: --max-photos below 10");
    int seeds = p.seeds > 0 ? p.seeds : 5;
    if (!mr_mkdirs(p.out_dir, err)) return false;
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_header(csv, "photos,method,err_rms_mm,err_max_mm,err_max_deg,time_s,tags_mapped,sightings_used,rms_px,sigma_max_mm");
    double xs[5], ys[2][5];
    bool ok = true;
    if (p.out) fprintf(p.out, "%7s  %-8s %12s %12s %12s %9s\n", "photos", "method", "rms mm", "max mm", "max deg", "time s");
    for (int ci = 0; ok && ci < ncounts; ci++) {
        for (int method = 0; ok && method < 2; method++) {
            double *v[7];
            for (int k = 0; k < 7; k++) v[k] = calloc((size_t)seeds, sizeof *v[k]);
            int tags = 0, used = 0;
            for (int s = 0; ok && s < seeds; s++) {
                mr_synth_map_params sp = {MR_SYNTH_MAP_DEFAULTS};
                sp.seed = (uint64_t)s + 1;
                sp.tags = p.tags;
                sp.photos = counts[ci];
                sp.width = 1280;
                sp.height = 960;
                sp.tag_size = 0.3;
                sp.radius = p.radius;
                sp.corner_noise_px = p.noise_px;
                sp.misdetect = p.misdetect;
                mr_synth_map set;
                ok = mr_synth_map_make(&sp, &set, err);
                if (!ok) break;
                mr_map_photo *ph = calloc((size_t)set.photo_count, sizeof *ph);
                for (int j = 0; ph && j < set.photo_count; j++) ph[j] = (mr_map_photo){set.dets[j], set.counts[j], NULL};
                mr_map_params mp = MR_MAP_DEFAULTS;
                mp.tag_size = sp.tag_size;
                mp.fix_id = 0;
                mp.fix_pose = &set.truth.tags[0].world_from_tag;
                mp.no_adjust = method == 1;
                mr_map_result r;
                double t0 = mr_time_now();
                bool built = ph && mr_map_build(&set.camera, ph, set.photo_count, &mp, &r, err);
                double t1 = mr_time_now();
                if (built) {
                    map_error(&r, &set.truth, &v[0][s], &v[1][s], &v[2][s]);
                    v[3][s] = t1 - t0;
                    v[4][s] = r.rms_px;
                    double smax = 0;
                    for (int i = 0; i < r.tag_count; i++)
                        if (isfinite(r.tags[i].sigma_pos)) smax = fmax(smax, r.tags[i].sigma_pos);
                    v[5][s] = method == 0 ? 1e3 * smax : NAN;
                    tags = r.tag_count;
                    used = r.observations;
                    mr_map_result_free(&r);
                } else {
                    /* A set too sparse to map (few photos): counted as a
                     * miss, not an error of the bench. */
                    for (int k = 0; k < 6; k++) v[k][s] = NAN;
                    mr_log(MR_LOG_INFO, "bench map: %d photos, seed %d: %s", counts[ci], s + 1, err->msg);
                    memset(err, 0, sizeof *err);
                }
                free(ph);
                mr_synth_map_free(&set);
            }
            double med[6];
            for (int k = 0; k < 6; k++) {
                int m = 0;
                for (int s = 0; s < seeds; s++)
                    if (isfinite(v[k][s])) v[k][m++] = v[k][s];
                med[k] = m ? mr_median(v[k], m) : NAN;
            }
            for (int k = 0; k < 7; k++) free(v[k]);
            const char *name = method == 0 ? "ours" : "chaining";
            mr_csv_int(csv, counts[ci]);
            mr_csv_text(csv, name);
            mr_csv_num(csv, "%.3f", med[0]);
            mr_csv_num(csv, "%.3f", med[1]);
            mr_csv_num(csv, "%.4f", med[2]);
            mr_csv_num(csv, "%.4f", med[3]);
            mr_csv_int(csv, tags);
            mr_csv_int(csv, used);
            mr_csv_num(csv, "%.4f", med[4]);
            mr_csv_num(csv, "%.3f", med[5]);
            mr_csv_end_row(csv);
            xs[ci] = counts[ci];
            ys[method][ci] = med[0];
            if (p.out)
                fprintf(p.out, "%7d  %-8s %12.2f %12.2f %12.3f %9.3f\n", counts[ci], name, med[0], med[1], med[2], med[3]);
        }
    }
    char path[4096];
    if (ok) {
        mr_path_join(p.out_dir, "bench_map.csv", path, sizeof path);
        ok = mr_csv_save(csv, path, err);
    }
    if (ok) {
        mr_plot_series ser[2] = {{.name = "ours (bundle adjustment)", .x = xs, .y = ys[0], .count = ncounts},
                                 {.name = "chaining (spanning tree)", .x = xs, .y = ys[1], .count = ncounts,
                                  .dashed = true, .mark = MR_PLOT_MARK_SQUARE}};
        char note[128];
        snprintf(note, sizeof note, "%d tags, %.1f px corners, %.0f%% wrong ids", p.tags, p.noise_px, 100 * p.misdetect);
        const char *notes[1] = {note};
        mr_plot_params pp = {.title = "marker map error against photo count (median over seeds)",
                             .xlabel = "photos",
                             .ylabel = "tag position error RMS (mm)",
                             .log_x = true,
                             .log_y = true,
                             .notes = notes,
                             .note_count = 1};
        mr_path_join(p.out_dir, "bench_map.svg", path, sizeof path);
        ok = mr_plot_write(path, &pp, ser, 2, err);
    }
    mr_csv_destroy(&csv);
    return ok;
}
