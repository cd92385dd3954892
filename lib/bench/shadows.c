/* mrcheck bench shadows (mr_bench_shadows): soft shadows, error against run
 * time, on the shadow suite (Hecher's categories, mr_shadow_suite_build).
 *
 * Every method runs over its settings (hard: map size; PCF and PCSS: taps;
 * backprojection: map size; the GPU ground truth: light samples), each row
 * with the GPU ms of the shadow passes (timer queries, median of N frames,
 * maps redrawn every frame) and the error of the visibility buffer against
 * Embree's ground truth (mr_eval_shadow_groundtruth) over the shadow region
 * S: the geometry pixels where the reference or the method is below 0.99.
 * RMSE over S, the thesis's sqrt(D) / |S| (D the sum of squared
 * differences over S) and SSIM over S. PCF's kernel radius, its one free
 * parameter, is tuned on the tuning cases (one per group: simple,
 * furniture, fence, plant; view 0, 32 taps) for the lowest mean RMSE and
 * reported with it everywhere; the tuning cases are marked in the CSV and
 * left out of the plot and the summary. Measurements only. */
#include "bench_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct setting {
    mr_shadow_method method;
    const char *key;   /* what varies */
    int value;
    bool is_default;   /* the montage's and the table's column */
} setting;

static const setting k_settings[] = {
    {MR_SHADOW_HARD, "map", 512, false},   {MR_SHADOW_HARD, "map", 1024, true},  {MR_SHADOW_HARD, "map", 2048, false},
    {MR_SHADOW_PCF, "taps", 8, false},     {MR_SHADOW_PCF, "taps", 16, false},   {MR_SHADOW_PCF, "taps", 32, true},
    {MR_SHADOW_PCF, "taps", 64, false},    {MR_SHADOW_PCSS, "taps", 8, false},   {MR_SHADOW_PCSS, "taps", 16, false},
    {MR_SHADOW_PCSS, "taps", 32, true},    {MR_SHADOW_PCSS, "taps", 64, false},  {MR_SHADOW_BP, "map", 256, false},
    {MR_SHADOW_BP, "map", 512, true},      {MR_SHADOW_BP, "map", 1024, false},   {MR_SHADOW_GROUNDTRUTH, "samples", 16, false},
    {MR_SHADOW_GROUNDTRUTH, "samples", 64, true}, {MR_SHADOW_GROUNDTRUTH, "samples", 256, false},
};
#define NS (int)(sizeof k_settings / sizeof k_settings[0])
static const bool k_tuning_case[MR_SHADOW_SUITE_COUNT] = {[0] = true, [4] = true, [8] = true, [10] = true};
static const float k_pcf_radii[] = {1, 2, 4, 8};

typedef struct measure {
    double ms, rmse, sqrtd, ssim;
    long long s_count;
} measure;

static void apply(const setting *st, float pcf_radius, mr_shadow_params *sp) {
    mr_shadow_params d = MR_SHADOW_DEFAULTS;
    *sp = d;
    sp->method = st->method;
    sp->pcf_radius = pcf_radius;
    sp->want_shadow = true;
    sp->no_reuse = true;
    if (strcmp(st->key, "map") == 0) sp->map_size = st->value;
    if (strcmp(st->key, "taps") == 0) sp->taps = st->value;
    if (strcmp(st->key, "samples") == 0) sp->gt_samples = st->value;
}

/* Renders frames times (the ground truth once: it is its own median) and
 * measures the last visibility against ref. vis_out (optional) keeps it. */
static bool run_one(const mr_bench_shadows_params *p, const mr_view *view, const mr_shadow_params *sp,
                    const mr_image *ref, const mr_image *depth, measure *m, mr_image *vis_out, mr_error *err) {
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = p->width;
    fp.height = p->height;
    fp.timing = true;
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

/* The Embree reference of one view (and the depth the region needs). */
static bool reference(const mr_bench_shadows_params *p, const mr_scene *s, const mr_view *view, mr_image *ref,
                      mr_image *depth, mr_error *err) {
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
                        "rmse_S = sqrt(D / |S|), sqrtD_over_S = sqrt(D) / |S| (Hecher's measure), D = sum over S of "
                        "(method - reference)^2; ssim_S = mean SSIM over S.\n"
                        "gpu_ms = median GPU time of the shadow passes (maps redrawn every frame); the ground "
                        "truth's is one frame.\n"
                        "tuning = 1: a case PCF's kernel radius was tuned on (left out of the plot and summary).");
    mr_csv_header(csv, "case,varying,overlap,view,tuning,method,setting,value,pcf_radius,gpu_ms,S_pixels,rmse_S,"
                       "sqrtD_over_S,ssim_S");
    /* Per setting: the values over reported (case, view) pairs. */
    int maxr = MR_SHADOW_SUITE_COUNT * 2;
    double *agg_ms = calloc((size_t)NS * maxr, sizeof(double)), *agg_rmse = calloc((size_t)NS * maxr, sizeof(double));
    int agg_n[NS] = {0};
    /* Per case: the default settings' ms and RMSE (markdown table). */
    double tab_ms[MR_SHADOW_SUITE_COUNT][MR_SHADOW_METHOD_COUNT], tab_rmse[MR_SHADOW_SUITE_COUNT][MR_SHADOW_METHOD_COUNT];
    for (int i = 0; i < MR_SHADOW_SUITE_COUNT; i++)
        for (int m = 0; m < MR_SHADOW_METHOD_COUNT; m++) tab_ms[i][m] = tab_rmse[i][m] = NAN;
    bool ok = csv && agg_ms && agg_rmse;
    if (!agg_ms || !agg_rmse) mr_fail(err, MR_ERR_NOMEM, "out of memory");

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
             reference(&p, sc.scene, &sc.views[0], &ref, &depth, err);
        for (int k = 0; ok && k < nr; k++) {
            setting st = {MR_SHADOW_PCF, "taps", 32, true};
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

    /* 2. Every case, view, method and setting. */
    for (int ci = first; ok && ci < first + count; ci++) {
        mr_shadow_suite_case sc;
        ok = mr_shadow_suite_build(ci, &sc, err) && mr_renderer_set_scene(p.gfx.renderer, sc.scene, err);
        for (int vi = 0; ok && vi < nviews; vi++) {
            mr_image ref = {0}, depth = {0};
            mr_image keep[MR_SHADOW_METHOD_COUNT];
            memset(keep, 0, sizeof keep);
            ok = reference(&p, sc.scene, &sc.views[vi], &ref, &depth, err);
            for (int si = 0; ok && si < NS; si++) {
                const setting *st = &k_settings[si];
                mr_shadow_params sp;
                apply(st, pcf_radius, &sp);
                measure m;
                bool want = vi == 0 && st->is_default;
                ok = run_one(&p, &sc.views[vi], &sp, &ref, &depth, &m, want ? &keep[st->method] : NULL, err);
                if (!ok) break;
                mr_csv_text(csv, sc.name);
                mr_csv_int(csv, sc.varying);
                mr_csv_int(csv, sc.overlap);
                mr_csv_int(csv, vi);
                mr_csv_int(csv, k_tuning_case[ci]);
                mr_csv_text(csv, mr_shadow_method_names[st->method]);
                mr_csv_text(csv, st->key);
                mr_csv_int(csv, st->value);
                mr_csv_num(csv, "%.0f", pcf_radius);
                mr_csv_num(csv, "%.3f", m.ms);
                mr_csv_int(csv, m.s_count);
                mr_csv_num(csv, "%.5f", m.rmse);
                mr_csv_num(csv, "%.3e", m.sqrtd);
                mr_csv_num(csv, "%.4f", m.ssim);
                mr_csv_end_row(csv);
                if (!k_tuning_case[ci]) {
                    agg_ms[si * maxr + agg_n[si]] = m.ms;
                    agg_rmse[si * maxr + agg_n[si]] = m.rmse;
                    agg_n[si]++;
                }
                if (st->is_default && vi == 0) {
                    tab_ms[ci][st->method] = m.ms;
                    tab_rmse[ci][st->method] = m.rmse;
                }
            }
            if (ok && vi == 0) {
                /* reference, hard, pcf, pcss, bp, ground truth (GPU) */
                const mr_image *tiles[6] = {&ref, &keep[1], &keep[2], &keep[3], &keep[4], &keep[5]};
                char path[4096], name[128];
                snprintf(name, sizeof name, "bench_shadows_%s.png", sc.name);
                mr_path_join(p.out_dir, name, path, sizeof path);
                ok = mr_montage_png(path, tiles, 6, 3, p.width, p.height, err);
            }
            for (int k = 0; k < MR_SHADOW_METHOD_COUNT; k++) mr_image_free(&keep[k]);
            mr_image_free(&ref);
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
    /* The plot: median RMSE over S against median ms, one curve per method. */
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
        mr_plot_series *s = &ser[nser++];
        s->name = mr_shadow_method_names[m];
        s->x = xs[m];
        s->y = ys[m];
        for (int si = 0; si < NS; si++)
            if (k_settings[si].method == (mr_shadow_method)m && s->count < 8) {
                xs[m][s->count] = med_ms[si];
                ys[m][s->count] = med_rmse[si];
                s->count++;
            }
    }
    if (ok) {
        mr_plot_params pp = {.title = "soft shadows: error against GPU time (median over the reported cases)",
                             .xlabel = "GPU ms of the shadow passes", .ylabel = "RMSE over S against Embree",
                             .log_x = true};
        mr_path_join(p.out_dir, "bench_shadows.svg", path, sizeof path);
        ok = mr_plot_write(path, &pp, ser, nser, err);
    }
    /* The markdown table: default settings, per case. */
    if (ok) {
        size_t cap = 16384, len = 0;
        char *md = malloc(cap);
        ok = md != NULL;
        if (!ok) mr_fail(err, MR_ERR_NOMEM, "out of memory");
#define MD(...) \
    do { if (md && len < cap) len += (size_t)snprintf(md + len, cap - len, __VA_ARGS__); } while (0)
        MD("# bench shadows\n\nGPU ms of the shadow passes / RMSE over the shadow region S against Embree's ground truth "
           "(%d rays), view 0 of each case, %dx%d, default settings (hard: 1024 map, PCF and PCSS: 32 taps, PCF radius "
           "%.0f texels tuned on the cases marked *, backprojection: 512 map, GPU ground truth: 64 samples). Full grid "
           "in bench_shadows.csv, error against time in bench_shadows.svg.\n\n",
           p.rays > 0 ? p.rays : 256, p.width, p.height, pcf_radius);
        MD("| case | hard | pcf | pcss | bp | groundtruth (GPU) |\n|---|---|---|---|---|---|\n");
        for (int ci = first; ci < first + count; ci++) {
            MD("| %s%s |", mr_shadow_suite_name(ci), k_tuning_case[ci] ? " *" : "");
            for (int m = MR_SHADOW_HARD; m < MR_SHADOW_METHOD_COUNT; m++) MD(" %.2f ms / %.4f |", tab_ms[ci][m], tab_rmse[ci][m]);
            MD("\n");
        }
        MD("\nMedian over the reported cases and views, default settings:\n\n| method | GPU ms | RMSE over S |\n|---|---|---|\n");
        int order[MR_SHADOW_METHOD_COUNT], no = 0;
        for (int si = 0; si < NS; si++)
            if (k_settings[si].is_default) {
                MD("| %s | %.2f | %.4f |\n", mr_shadow_method_names[k_settings[si].method], med_ms[si], med_rmse[si]);
                order[no++] = si;
            }
        /* The ranking by error (worst first), next to Hecher's PCF < PCSS < BP < GT. */
        for (int a = 0; a < no; a++)
            for (int b = a + 1; b < no; b++)
                if (med_rmse[order[b]] > med_rmse[order[a]]) {
                    int t = order[a];
                    order[a] = order[b];
                    order[b] = t;
                }
        MD("\nRanking by RMSE (worst first): ");
        for (int a = 0; a < no; a++) MD("%s%s", a ? " < " : "", mr_shadow_method_names[k_settings[order[a]].method]);
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
    mr_csv_destroy(&csv);
    return ok;
}
