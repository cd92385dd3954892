/* mrcheck bench shadows (mr_bench_shadows): soft shadows, error against run
 * time, on the shadow suite (Hecher's categories, mr_shadow_suite_build).
 *
 * Every method runs over its settings (hard: map size; PCF and PCSS: taps
 * and map size; backprojection: map size; the GPU ground truth: light
 * samples; every method: the light's size at half and double), each row
 * with the GPU ms of the shadow passes (timer queries, median of N frames,
 * maps redrawn every frame) and the error of the visibility buffer against
 * Embree's ground truth (mr_eval_shadow_groundtruth) over the shadow region
 * S: the geometry pixels where the reference or the method is below 0.99.
 * RMSE over S (the thesis's measure: Hecher calls D "the mean squared
 * error" over the shadow pixels and uses sqrt(D), "the root mean squared
 * error", Sec. 5.1), sqrt(D) / |S| with D the *sum* of squared differences
 * over S (an extra column, not his measure: it shrinks with the shadow's
 * size) and SSIM over S. Measured on the visibility buffer; the thesis
 * measures the shaded image. Tuned on the tuning cases (one per
 * group: simple, furniture, fence, plant), which run first: PCF's kernel
 * radius (view 0, 32 taps) and then each method's reported setting (the
 * lowest mean RMSE there at the case's light size); the other cases are
 * reported with those. The tuning cases are marked in the CSV and the
 * table and left out of the plot and the summary. Measurements only. */
#include "bench_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct setting {
    mr_shadow_method method;
    const char *key;   /* what varies: map, taps, samples or light */
    int map, taps, samples;
    float light;       /* light size factor (1: the case's light) */
    bool is_default;   /* the tuning's fallback (no tuning case run) */
} setting;

/* Per method: its own knob (map size, taps, light samples), the map size
 * for the filters, and the light's size at half and double (against a
 * reference with that light). */
#define SET(m, k, map, taps, smp, light, def) {MR_SHADOW_##m, k, map, taps, smp, light, def}
static const setting k_settings[] = {
    SET(HARD, "map", 512, 0, 0, 1, false),         SET(HARD, "map", 1024, 0, 0, 1, true),
    SET(HARD, "map", 2048, 0, 0, 1, false),        SET(HARD, "light", 1024, 0, 0, 0.5f, false),
    SET(HARD, "light", 1024, 0, 0, 2, false),
    SET(PCF, "taps", 1024, 8, 0, 1, false),        SET(PCF, "taps", 1024, 16, 0, 1, false),
    SET(PCF, "taps", 1024, 32, 0, 1, true),        SET(PCF, "taps", 1024, 64, 0, 1, false),
    SET(PCF, "map", 512, 32, 0, 1, false),         SET(PCF, "map", 2048, 32, 0, 1, false),
    SET(PCF, "light", 1024, 32, 0, 0.5f, false),   SET(PCF, "light", 1024, 32, 0, 2, false),
    SET(PCSS, "taps", 1024, 8, 0, 1, false),       SET(PCSS, "taps", 1024, 16, 0, 1, false),
    SET(PCSS, "taps", 1024, 32, 0, 1, true),       SET(PCSS, "taps", 1024, 64, 0, 1, false),
    SET(PCSS, "map", 512, 32, 0, 1, false),        SET(PCSS, "map", 2048, 32, 0, 1, false),
    SET(PCSS, "light", 1024, 32, 0, 0.5f, false),  SET(PCSS, "light", 1024, 32, 0, 2, false),
    SET(BP, "map", 256, 0, 0, 1, false),           SET(BP, "map", 512, 0, 0, 1, true),
    SET(BP, "map", 1024, 0, 0, 1, false),          SET(BP, "light", 512, 0, 0, 0.5f, false),
    SET(BP, "light", 512, 0, 0, 2, false),
    SET(GROUNDTRUTH, "samples", 1024, 0, 16, 1, false), SET(GROUNDTRUTH, "samples", 1024, 0, 64, 1, true),
    SET(GROUNDTRUTH, "samples", 1024, 0, 256, 1, false), SET(GROUNDTRUTH, "light", 1024, 0, 64, 0.5f, false),
    SET(GROUNDTRUTH, "light", 1024, 0, 64, 2, false),
};
#undef SET
#define NS (int)(sizeof k_settings / sizeof k_settings[0])
/* The reference's light sizes: k_light_scales[i] for the rows with that light. */
static const float k_light_scales[3] = {1, 0.5f, 2};
static int light_index(float l) { return l == 1 ? 0 : l < 1 ? 1 : 2; }
static double setting_value(const setting *st) {
    if (strcmp(st->key, "map") == 0) return st->map;
    if (strcmp(st->key, "taps") == 0) return st->taps;
    if (strcmp(st->key, "samples") == 0) return st->samples;
    return st->light;
}
/* The tuning categories: one per group (simple, furniture, fence, plant). */
static const bool k_tuning_case[MR_SHADOW_SUITE_COUNT] = {[0] = true, [4] = true, [8] = true, [10] = true};
static const float k_pcf_radii[] = {1, 2, 4, 8};

typedef struct measure {
    double ms, rmse, sqrtd, ssim;
    long long s_count;
    double rmse_floor, rmse_objects; /* over S on the floor / on everything else (NaN if empty) */
} measure;

static void apply(const setting *st, float pcf_radius, mr_shadow_params *sp) {
    mr_shadow_params d = MR_SHADOW_DEFAULTS;
    *sp = d;
    sp->method = st->method;
    sp->pcf_radius = pcf_radius;
    sp->want_shadow = true;
    sp->no_reuse = true;
    sp->map_size = st->map;
    if (st->taps) sp->taps = st->taps;
    if (st->samples) sp->gt_samples = st->samples;
    sp->light_scale = st->light;
}

/* The setting as run: the ground truth's samples under the cap. */
static setting capped(const setting *st, int gt_max) {
    setting c = *st;
    if (gt_max > 0 && c.samples > gt_max) c.samples = gt_max;
    return c;
}

/* Renders frames times (the ground truth once: it is its own median) and
 * measures the last visibility against ref. vis_out (optional) keeps it. */
static bool run_one(const mr_bench_shadows_params *p, const mr_view *view, const mr_shadow_params *sp,
                    const mr_image *ref, const mr_image *depth, measure *m, mr_image *vis_out, mr_error *err) {
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = p->width;
    fp.height = p->height;
    fp.timing = true;
    fp.want_depth = fp.want_normals = true; /* the floor / object split (read back after the timed passes) */
    fp.shadow = *sp;
    int frames = sp->method == MR_SHADOW_GROUNDTRUTH ? 1 : (p->frames > 0 ? p->frames : 3);
    double ms[64];
    if (frames > 64) frames = 64;
    mr_frame_result res;
    memset(&res, 0, sizeof res);
    for (int k = 0; k < frames; k++) {
        mr_frame_result_free(&res);
        if (!mr_render_frame(p->gfx.renderer, view, &fp, &res, err)) return false;
        ms[k] = 0;
        for (int i = 0; i < res.pass_count; i++)
            if (strncmp(res.passes[i], "shadow", 6) == 0) ms[k] += res.gpu_ms[i];
    }
    m->ms = mr_median(ms, frames);
    /* The shadow region S and the errors over it. */
    const float *a = res.shadow.data, *b = ref->data, *dz = depth->data;
    size_t n = (size_t)ref->width * ref->height;
    mr_image mask = {0};
    bool ok = mr_image_alloc(&mask, ref->width, ref->height, 1, MR_PIX_F32, err);
    double se = 0;
    long long cnt = 0;
    for (size_t i = 0; ok && i < n; i++) {
        bool in = dz[i] > 0 && (a[i] < 0.99f || b[i] < 0.99f);
        ((float *)mask.data)[i] = in ? 1.0f : 0.0f;
        if (!in) continue;
        double d = (double)a[i] - b[i];
        se += isfinite(d) ? d * d : 1;
        cnt++;
    }
    m->s_count = cnt;
    m->rmse = cnt ? sqrt(se / cnt) : 0;
    /* The floor: up-facing (world normal y > 0.99) and within 1 % of the
     * view's depth range above the lowest up-facing pixel; the rest of S is
     * the objects' own faces (their partly lit sides and tops). */
    m->rmse_floor = m->rmse_objects = NAN;
    if (ok && res.normal.data && res.depth.data && res.depth.width == ref->width && res.depth.height == ref->height) {
        mr_camera c = mr_camera_resized(&view->camera, ref->width, ref->height);
        const mr_dmat4 *W = &view->world_from_camera;
        const float *nv = res.normal.data, *zz = res.depth.data;
        double *wy = malloc(n * sizeof *wy);
        bool *up = malloc(n * sizeof *up);
        double ymin = INFINITY, zmax = 0;
        for (size_t i = 0; wy && up && i < n; i++) {
            up[i] = false;
            double z = zz[i];
            if (!(z > 0)) continue;
            int x = (int)(i % (size_t)ref->width), y = (int)(i / (size_t)ref->width);
            mr_dvec3 pw = mr_m4_point(W, mr_v3((x - c.cx) / c.fx * z, (y - c.cy) / c.fy * z, z));
            double ny = W->m[4] * nv[3 * i] + W->m[5] * nv[3 * i + 1] + W->m[6] * nv[3 * i + 2];
            wy[i] = pw.y;
            up[i] = ny > 0.99;
            if (up[i] && pw.y < ymin) ymin = pw.y;
            if (z > zmax) zmax = z;
        }
        double sf = 0, so = 0;
        long long nf = 0, no = 0;
        for (size_t i = 0; wy && up && i < n; i++) {
            if (!(((float *)mask.data)[i] > 0.5f)) continue;
            double d = (double)a[i] - b[i], e = isfinite(d) ? d * d : 1;
            if (up[i] && wy[i] < ymin + 0.01 * zmax) sf += e, nf++;
            else so += e, no++;
        }
        if (nf) m->rmse_floor = sqrt(sf / nf);
        if (no) m->rmse_objects = sqrt(so / no);
        free(wy);
        free(up);
    }
    m->sqrtd = cnt ? sqrt(se) / cnt : 0;
    mr_image_metrics im;
    m->ssim = NAN;
    if (ok && cnt > 0 && mr_image_compare(&res.shadow, ref, &mask, &im, err)) m->ssim = im.ssim;
    mr_image_free(&mask);
    if (ok && vis_out) {
        *vis_out = res.shadow;
        memset(&res.shadow, 0, sizeof res.shadow);
    }
    mr_frame_result_free(&res);
    return ok;
}

/* The Embree reference of one view with the light's size times
 * light_scale (and the depth the region needs). */
static bool reference(const mr_bench_shadows_params *p, const mr_scene *s, const mr_view *view, float light_scale,
                      mr_image *ref, mr_image *depth, mr_error *err) {
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = p->width;
    fp.height = p->height;
    fp.want_depth = fp.want_normals = true;
    mr_frame_result res;
    if (!mr_render_frame(p->gfx.renderer, view, &fp, &res, err)) return false;
    mr_eval_gt *g = mr_eval_gt_create(s, false, err);
    mr_light L;
    bool ok = g && mr_shadow_light(s, &L);
    if (g && !ok) mr_fail(err, MR_ERR_INVALID, "the case has no casting light");
    mr_shadow_gt_params gp = MR_SHADOW_GT_DEFAULTS;
    gp.rays = p->rays > 0 ? p->rays : 256;
    gp.light_scale = light_scale;
    mr_view v = *view;
    v.camera = mr_camera_resized(&view->camera, res.depth.width, res.depth.height);
    ok = ok && mr_eval_shadow_groundtruth(g, &v, &res.depth, &res.normal, &L, &gp, ref, err);
    mr_eval_gt_destroy(&g);
    if (ok) {
        *depth = res.depth;
        memset(&res.depth, 0, sizeof res.depth);
    }
    mr_frame_result_free(&res);
    return ok;
}

bool mr_bench_shadows(const mr_bench_shadows_params *params, mr_error *err) {
    mr_bench_shadows_params p = *params;
    if (!bench_gpu_check(&p.gfx, "shadows", err)) return false;
    if (p.width <= 0) p.width = 320;
    if (p.height <= 0) p.height = 240;
    int first = p.first > 0 ? p.first : 0, count = p.count > 0 ? p.count : MR_SHADOW_SUITE_COUNT - first;
    if (first >= MR_SHADOW_SUITE_COUNT || first + count > MR_SHADOW_SUITE_COUNT)
        return mr_fail(err, MR_ERR_INVALID, "shadow suite cases %d..%d out of range", first, first + count - 1);
    int nviews = p.views == 1 ? 1 : 2;
    if (!mr_mkdirs(p.out_dir, err)) return false;
    mr_csv *csv = mr_csv_create(err);
    mr_csv_comment(csv, "mrcheck bench shadows: soft-shadow methods on the shadow suite against Embree's ground truth.\n"
                        "S = geometry pixels where the reference or the method is below 0.99.\n"
                        "rmse_S = sqrt(D / |S|) (Hecher's sqrt(D), which he names the RMSE: his D is the mean over S), "
                        "sqrtD_over_S = sqrt(D) / |S| (not his measure), D = sum over S of "
                        "(method - reference)^2, on the visibility buffer (the thesis: the shaded image); "
                        "ssim_S = mean SSIM over S.\n"
                        "gpu_ms = median GPU time of the shadow passes (maps redrawn every frame); the ground "
                        "truth's is one frame.\n"
                        "setting = what varies, value = its value: map (shadow-map side; filters at 32 taps), taps "
                        "(1024 map), samples (GPU ground truth's light samples, 1024 map), light (the light's size "
                        "times value, against a reference with that light; hard, pcf, pcss at a 1024 map and 32 "
                        "taps, bp at 512, the GPU ground truth at 64 samples).\n"
                        "tuning = 1: a tuning category (simple_constant, furniture_constant, fence_constant, "
                        "plant_constant): PCF's kernel radius and each method's reported setting (the lowest mean "
                        "RMSE there, light size 1) were chosen on these; they are left out of the plot and the "
                        "summary.");
    mr_csv_header(csv, "case,varying,overlap,view,tuning,method,setting,value,pcf_radius,gpu_ms,S_pixels,rmse_S,"
                       "sqrtD_over_S,ssim_S,rmse_floor_S,rmse_objects_S");
    /* Per setting: the values over reported (case, view) pairs. */
    int maxr = MR_SHADOW_SUITE_COUNT * 2;
    double *agg_ms = calloc((size_t)NS * maxr, sizeof(double)), *agg_rmse = calloc((size_t)NS * maxr, sizeof(double));
    double *agg_rf = calloc((size_t)NS * maxr, sizeof(double)), *agg_ro = calloc((size_t)NS * maxr, sizeof(double));
    int agg_n[NS] = {0};
    /* Per case and setting, view 0 (the markdown table); per setting, the
     * RMSE summed over the tuning cases' views. */
    static double tab_ms[MR_SHADOW_SUITE_COUNT][NS], tab_rmse[MR_SHADOW_SUITE_COUNT][NS];
    for (int i = 0; i < MR_SHADOW_SUITE_COUNT; i++)
        for (int m = 0; m < NS; m++) tab_ms[i][m] = tab_rmse[i][m] = NAN;
    double tune_sum[NS] = {0};
    int tune_n[NS] = {0};
    bool ok = csv && agg_ms && agg_rmse && agg_rf && agg_ro;
    if (!agg_ms || !agg_rmse || !agg_rf || !agg_ro) mr_fail(err, MR_ERR_NOMEM, "out of memory");

    /* 1. Tuning PCF's radius (tuning cases within the range, view 0). */
    float pcf_radius = MR_SHADOW_DEFAULT_PCF_RADIUS;
    double best = INFINITY;
    int nr = (int)(sizeof k_pcf_radii / sizeof k_pcf_radii[0]);
    double sum_r[8] = {0};
    int n_r = 0;
    for (int ci = first; ok && ci < first + count; ci++) {
        if (!k_tuning_case[ci]) continue;
        mr_shadow_suite_case sc;
        mr_image ref = {0}, depth = {0};
        ok = mr_shadow_suite_build(ci, &sc, err) && mr_renderer_set_scene(p.gfx.renderer, sc.scene, err) &&
             reference(&p, sc.scene, &sc.views[0], 1.0f, &ref, &depth, err);
        for (int k = 0; ok && k < nr; k++) {
            setting st = {MR_SHADOW_PCF, "taps", 1024, 32, 0, 1, true};
            mr_shadow_params sp;
            apply(&st, k_pcf_radii[k], &sp);
            measure m;
            ok = run_one(&p, &sc.views[0], &sp, &ref, &depth, &m, NULL, err);
            sum_r[k] += m.rmse;
        }
        n_r++;
        mr_image_free(&ref);
        mr_image_free(&depth);
        mr_renderer_set_scene(p.gfx.renderer, NULL, NULL);
        mr_shadow_suite_free(&sc);
    }
    for (int k = 0; n_r && k < nr; k++)
        if (sum_r[k] < best) best = sum_r[k], pcf_radius = k_pcf_radii[k];
    BENCH_PRINT(p.out, "bench shadows: PCF radius %.0f texels (tuned on %d cases)\n", pcf_radius, n_r);

    /* 2. Every case, view, method and setting; the tuning cases first, so
     * that each method's setting is chosen on them before the others run
     * (their montages show the chosen settings). */
    int order[MR_SHADOW_SUITE_COUNT], no = 0;
    for (int pass = 0; pass < 2; pass++)
        for (int ci = first; ci < first + count; ci++)
            if (k_tuning_case[ci] == (pass == 0)) order[no++] = ci;
    int chosen[MR_SHADOW_METHOD_COUNT];
    bool tuned = false;
    for (int m = 0; m < MR_SHADOW_METHOD_COUNT; m++) chosen[m] = -1;
    for (int si = 0; si < NS; si++)
        if (k_settings[si].is_default) chosen[k_settings[si].method] = si;
    for (int oi = 0; ok && oi < no; oi++) {
        int ci = order[oi];
        if (!k_tuning_case[ci] && !tuned) {
            /* Each method's setting with the lowest mean RMSE on the tuning
             * cases, light size 1 (the other lights are other problems). */
            for (int m = MR_SHADOW_HARD; m < MR_SHADOW_METHOD_COUNT; m++) {
                double bm = INFINITY;
                for (int si = 0; si < NS; si++)
                    if (k_settings[si].method == (mr_shadow_method)m && k_settings[si].light == 1 && tune_n[si] > 0 &&
                        tune_sum[si] / tune_n[si] < bm)
                        bm = tune_sum[si] / tune_n[si], chosen[m] = si;
            }
            tuned = true;
        }
        mr_shadow_suite_case sc;
        ok = mr_shadow_suite_build(ci, &sc, err) && mr_renderer_set_scene(p.gfx.renderer, sc.scene, err);
        for (int vi = 0; ok && vi < nviews; vi++) {
            mr_image ref[3], depth = {0};
            bool have_ref[3] = {false, false, false};
            memset(ref, 0, sizeof ref);
            mr_image keep[MR_SHADOW_METHOD_COUNT];
            memset(keep, 0, sizeof keep);
            for (int si = 0; ok && si < NS; si++) {
                const setting cst = capped(&k_settings[si], p.gt_samples_max), *st = &cst;
                int li = light_index(st->light);
                if (!have_ref[li]) {
                    mr_image d = {0};
                    ok = reference(&p, sc.scene, &sc.views[vi], k_light_scales[li], &ref[li], &d, err);
                    if (!ok) break;
                    if (!depth.data) depth = d;
                    else mr_image_free(&d);
                    have_ref[li] = true;
                }
                mr_shadow_params sp;
                apply(st, pcf_radius, &sp);
                measure m;
                bool want = vi == 0 && si == chosen[st->method];
                ok = run_one(&p, &sc.views[vi], &sp, &ref[li], &depth, &m, want ? &keep[st->method] : NULL, err);
                if (!ok) break;
                mr_csv_text(csv, sc.name);
                mr_csv_int(csv, sc.varying);
                mr_csv_int(csv, sc.overlap);
                mr_csv_int(csv, vi);
                mr_csv_int(csv, k_tuning_case[ci]);
                mr_csv_text(csv, mr_shadow_method_names[st->method]);
                mr_csv_text(csv, st->key);
                mr_csv_num(csv, "%g", setting_value(st));
                mr_csv_num(csv, "%.0f", pcf_radius);
                mr_csv_num(csv, "%.3f", m.ms);
                mr_csv_int(csv, m.s_count);
                mr_csv_num(csv, "%.5f", m.rmse);
                mr_csv_num(csv, "%.3e", m.sqrtd);
                mr_csv_num(csv, "%.4f", m.ssim);
                mr_csv_num(csv, "%.5f", m.rmse_floor);
                mr_csv_num(csv, "%.5f", m.rmse_objects);
                mr_csv_end_row(csv);
                if (!k_tuning_case[ci]) {
                    agg_ms[si * maxr + agg_n[si]] = m.ms;
                    agg_rmse[si * maxr + agg_n[si]] = m.rmse;
                    agg_rf[si * maxr + agg_n[si]] = isfinite(m.rmse_floor) ? m.rmse_floor : 0;
                    agg_ro[si * maxr + agg_n[si]] = isfinite(m.rmse_objects) ? m.rmse_objects : 0;
                    agg_n[si]++;
                } else {
                    tune_sum[si] += m.rmse;
                    tune_n[si]++;
                }
                if (vi == 0) {
                    tab_ms[ci][si] = m.ms;
                    tab_rmse[ci][si] = m.rmse;
                }
            }
            if (ok && vi == 0) {
                /* reference, hard, pcf, pcss, bp, ground truth (GPU) */
                const mr_image *tiles[6] = {&ref[0], &keep[1], &keep[2], &keep[3], &keep[4], &keep[5]};
                char path[4096], name[128];
                snprintf(name, sizeof name, "bench_shadows_%s.png", sc.name);
                mr_path_join(p.out_dir, name, path, sizeof path);
                ok = mr_montage_png(path, tiles, 6, 3, p.width, p.height, err);
            }
            for (int k = 0; k < MR_SHADOW_METHOD_COUNT; k++) mr_image_free(&keep[k]);
            for (int k = 0; k < 3; k++) mr_image_free(&ref[k]);
            mr_image_free(&depth);
        }
        if (ok) BENCH_PRINT(p.out, "bench shadows: %s done\n", sc.name);
        mr_renderer_set_scene(p.gfx.renderer, NULL, NULL);
        mr_shadow_suite_free(&sc);
    }
    char path[4096];
    if (ok) {
        mr_path_join(p.out_dir, "bench_shadows.csv", path, sizeof path);
        ok = mr_csv_save(csv, path, err);
    }
    /* The plot: median RMSE over S against median ms over the reported
     * cases, one curve per method through its settings (light size 1). */
    double xs[MR_SHADOW_METHOD_COUNT][8], ys[MR_SHADOW_METHOD_COUNT][8];
    mr_plot_series ser[MR_SHADOW_METHOD_COUNT];
    memset(ser, 0, sizeof ser);
    int nser = 0;
    double med_ms[NS], med_rmse[NS];
    for (int si = 0; si < NS; si++) {
        med_ms[si] = agg_n[si] ? mr_median(agg_ms + si * maxr, agg_n[si]) : NAN;
        med_rmse[si] = agg_n[si] ? mr_median(agg_rmse + si * maxr, agg_n[si]) : NAN;
    }
    for (int m = MR_SHADOW_HARD; m < MR_SHADOW_METHOD_COUNT; m++) {
        mr_plot_series *sr = &ser[nser++];
        sr->name = mr_shadow_method_names[m];
        sr->x = xs[m];
        sr->y = ys[m];
        for (int si = 0; si < NS; si++)
            if (k_settings[si].method == (mr_shadow_method)m && k_settings[si].light == 1 && sr->count < 8) {
                xs[m][sr->count] = med_ms[si];
                ys[m][sr->count] = med_rmse[si];
                sr->count++;
            }
    }
    if (ok) {
        mr_plot_params pp = {.title = "soft shadows: error against GPU time (median over the reported cases)",
                             .xlabel = "GPU ms of the shadow passes", .ylabel = "RMSE over S against Embree",
                             .log_x = true};
        mr_path_join(p.out_dir, "bench_shadows.svg", path, sizeof path);
        ok = mr_plot_write(path, &pp, ser, nser, err);
    }
    /* The markdown table: the chosen settings, per case. */
    if (ok) {
        size_t cap = 32768, len = 0;
        char *md = malloc(cap);
        ok = md != NULL;
        if (!ok) mr_fail(err, MR_ERR_NOMEM, "out of memory");
#define MD(...) \
    do { if (md && len < cap) len += (size_t)snprintf(md + len, cap - len, __VA_ARGS__); } while (0)
        char set_desc[512] = "";
        size_t sl = 0;
        for (int m = MR_SHADOW_HARD; m < MR_SHADOW_METHOD_COUNT && sl < sizeof set_desc; m++) {
            const setting *st = &k_settings[chosen[m]];
            sl += (size_t)snprintf(set_desc + sl, sizeof set_desc - sl, "%s%s: %s %g", m > MR_SHADOW_HARD ? ", " : "",
                                   mr_shadow_method_names[m], st->key, setting_value(st));
        }
        MD("# bench shadows\n\nGPU ms of the shadow passes / RMSE over the shadow region S against Embree's ground truth "
           "(%d rays), view 0 of each case, %dx%d. Tuning categories (marked *): simple_constant, furniture_constant, "
           "fence_constant, plant_constant; %s PCF's kernel radius (%.0f texels) and each method's setting "
           "(the lowest mean RMSE at the case's light size: %s); the other categories are reported with those. Full "
           "grid (map size, taps, light samples, light size 0.5 and 2) in bench_shadows.csv, error against time in "
           "bench_shadows.svg, one montage per case (reference, hard, pcf, pcss, bp, GPU ground truth).\n\n",
           p.rays > 0 ? p.rays : 256, p.width, p.height,
           n_r ? "on them were chosen" : "none of them ran here, so the defaults stand for",
           pcf_radius, set_desc);
        MD("| case | hard | pcf | pcss | bp | groundtruth (GPU) |\n|---|---|---|---|---|---|\n");
        for (int oi = 0; oi < no; oi++) {
            int ci = order[oi];
            MD("| %s%s |", mr_shadow_suite_name(ci), k_tuning_case[ci] ? " *" : "");
            for (int m = MR_SHADOW_HARD; m < MR_SHADOW_METHOD_COUNT; m++)
                MD(" %.2f ms / %.4f |", tab_ms[ci][chosen[m]], tab_rmse[ci][chosen[m]]);
            MD("\n");
        }
        MD("\nMedian over the reported categories and views, chosen settings (S split: the floor's penumbrae / the "
           "objects' own faces):\n\n| method | setting | GPU ms | RMSE over S | floor | objects |\n|---|---|---|---|---|---|\n");
        int rank[MR_SHADOW_METHOD_COUNT], nk = 0;
        for (int m = MR_SHADOW_HARD; m < MR_SHADOW_METHOD_COUNT; m++) {
            int si = chosen[m];
            MD("| %s | %s %g | %.2f | %.4f | %.4f | %.4f |\n", mr_shadow_method_names[m], k_settings[si].key,
               setting_value(&k_settings[si]), med_ms[si], med_rmse[si],
               agg_n[si] ? mr_median(agg_rf + si * maxr, agg_n[si]) : NAN, agg_n[si] ? mr_median(agg_ro + si * maxr, agg_n[si]) : NAN);
            rank[nk++] = si;
        }
        MD("\nLight size (median RMSE over S over the reported categories at the default settings: hard, pcf and pcss "
           "a 1024 map and 32 taps, bp a 512 map, the GPU ground truth 64 samples; each against a reference with that "
           "light):\n\n"
           "| method | light x0.5 | light x1 | light x2 |\n|---|---|---|---|\n");
        for (int m = MR_SHADOW_HARD; m < MR_SHADOW_METHOD_COUNT; m++) {
            double v[3] = {NAN, NAN, NAN};
            for (int si = 0; si < NS; si++) {
                const setting *st = &k_settings[si];
                if (st->method != (mr_shadow_method)m) continue;
                if (strcmp(st->key, "light") == 0) v[light_index(st->light)] = med_rmse[si];
                else if (st->is_default) v[0] = med_rmse[si];
            }
            MD("| %s | %.4f | %.4f | %.4f |\n", mr_shadow_method_names[m], v[1], v[0], v[2]);
        }
        /* The ranking by error (worst first), next to Hecher's PCF < PCSS < BP < GT. */
        for (int a = 0; a < nk; a++)
            for (int b = a + 1; b < nk; b++)
                if (med_rmse[rank[b]] > med_rmse[rank[a]]) {
                    int t = rank[a];
                    rank[a] = rank[b];
                    rank[b] = t;
                }
        MD("\nRanking by RMSE (worst first): ");
        for (int a = 0; a < nk; a++) MD("%s%s", a ? " < " : "", mr_shadow_method_names[k_settings[rank[a]].method]);
        MD("; Hecher's study: PCF < PCSS < BP < GT.\n");
#undef MD
        if (md) {
            mr_path_join(p.out_dir, "bench_shadows.md", path, sizeof path);
            ok = mr_file_write_atomic(path, md, len < cap ? len : cap - 1, err);
            BENCH_PRINT(p.out, "%.*s", (int)(len < cap ? len : cap - 1), md);
        }
        free(md);
    }
    free(agg_ms);
    free(agg_rmse);
    free(agg_rf);
    free(agg_ro);
    mr_csv_destroy(&csv);
    return ok;
}
