/* mrcheck bench ghost (mr_bench_ghost): ghosted views on the demo partition (pipes hidden
 * behind it), for the conflict case (pipes coloured like the partition) and
 * the no-conflict case: per importance source, saliency implementation,
 * eq. 9's levels and mode, the GPU ms of the ghosting passes against
 * measures that do not use the ghosting's own target:
 *  - legibility (mr_eval_ghost_legibility): the important edges of the
 *    hidden layer D alone (neighbour pairs touching the region with
 *    4 * dE*ab(D) / 100 > 0.5, above the curvature bias 0.35); per edge the
 *    contrast F adds over the occluder O, h_F = dF - dO, projected on what
 *    showing D in full would add, h_R; mean of clamp(h_F.h_R / |h_R|^2, 0, 1).
 *    0: only the occluder; 1: D in full; ~1 - alpha for alpha blending.
 *    With edge_contrast_dE (mean |h_F|) and full_contrast_dE (mean |h_R|).
 *  - cv_saliency_ratio: OpenCV contrib's spectral-residual saliency of the
 *    final image, mean over the region / mean elsewhere, beside the same for
 *    the occluder alone (cv_saliency_ratio_occluder: hidden structure
 *    invisible).
 *  - target_reached: the old measure, the fraction of pixels with IM > 0.3
 *    whose final saliency reaches C_desired: what the adaptive stage itself
 *    optimises, so only a diagnostic of the optimiser.
 * and the occluder's mean lightness change. Kalkofen et al. judge
 * legibility by a user study; these are proxies. CSV + SVG; never
 * pass/fail, never timed in tests. */
#include "bench_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct ghost_row {
    const char *scene, *importance, *saliency, *levels, *mode;
    int mode_index;
    double pass_ms[6]; /* ghost_hidden, ghost_curvature, ghost_importance, ghost_g0, ghost_analysis, ghost_emphasis */
    double ghost_ms, frame_ms;
    mr_ghost_stats st;
    mr_legibility leg;
    double sal_ratio, sal_ratio_occluder;
} ghost_row;

static const char *const k_pass_names[6] = {"ghost_hidden", "ghost_curvature", "ghost_importance",
                                            "ghost_g0",     "ghost_analysis",  "ghost_emphasis"};

/* Legibility (y) against ghosting GPU ms (x), one marker per row of eq. 9's
 * offset levels: colour by mode, filled for the conflict case, hollow for
 * no conflict, circles for the mip-map pyramid, squares for two Gaussians. */
static bool write_svg(const char *path, const char *title, const ghost_row *rows, int n, mr_error *err) {
    static const char *const colours[3] = {"#888888", "#3b6fb6", "#d0452c"};
    static const char *const mode_names[3] = {"alpha", "g0", "adaptive"};
    enum { NS = 3 * 2 * 2 };
    mr_plot_series ser[NS];
    double xs[NS][2 * 2 * 2 * 2 * 3], ys[NS][2 * 2 * 2 * 2 * 3];
    double xmax = 1e-9;
    memset(ser, 0, sizeof ser);
    for (int k = 0; k < NS; k++) {
        int mode = k / 4;
        bool conflict = (k / 2) % 2 == 0, gauss = k % 2 == 1;
        ser[k].name = conflict && !gauss ? mode_names[mode] : NULL; /* one legend entry per mode */
        ser[k].x = xs[k];
        ser[k].y = ys[k];
        ser[k].color = colours[mode];
        ser[k].no_line = true;
        ser[k].hollow = !conflict;
        ser[k].mark = gauss ? MR_PLOT_MARK_SQUARE : MR_PLOT_MARK_CIRCLE;
        for (int i = 0; i < n; i++) {
            const ghost_row *r = &rows[i];
            if (strcmp(r->levels, "offset") != 0 || r->mode_index != mode || (strcmp(r->scene, "conflict") == 0) != conflict ||
                (strcmp(r->saliency, "gauss") == 0) != gauss)
                continue;
            xs[k][ser[k].count] = r->ghost_ms;
            ys[k][ser[k].count++] = r->leg.legibility; /* NaN: not drawn */
            if (isfinite(r->ghost_ms)) xmax = fmax(xmax, r->ghost_ms);
        }
    }
    static const char *const notes[4] = {"filled: conflict", "hollow: no conflict", "circle: mip-map pyramid",
                                         "square: two Gaussians"};
    mr_plot_params pp = {.title = title, .xlabel = "GPU ms of the ghosting passes (median)",
                         .ylabel = "legibility (edge transfer of D)", .x_min = 0, .x_max = 1.1 * xmax, .y_min = 0,
                         .y_max = 1, .notes = notes, .note_count = 4};
    return mr_plot_write(path, &pp, ser, NS, err);
}

/* The demo hall, with (conflict) or without the hidden pipes coloured like
 * the partition. */
static bool build_hall(bool conflict, mr_demo_hall *hall, mr_error *err) {
    mr_demo_params dp = MR_DEMO_DEFAULTS;
    dp.pipes_like_partition = conflict;
    return mr_demo_build_tagged(&dp, 0, hall, err);
}

/* What every configuration's measurement shares. */
typedef struct ghost_run {
    const mr_bench_gpu *gfx;
    const mr_view *view;
    int w, h;
    long frames;
    double *samples; /* 8 x frames: the 6 passes, their sum, the frame's wall ms */
} ghost_run;

/* One configuration (importance im, saliency sa, levels lv, mode mo): the
 * median GPU ms of the ghosting passes over the timed frames after 2
 * warm-up frames, then the legibility measures in one untimed frame.
 * *occ_ratio: the occluder's saliency ratio, measured once per hall. */
static bool measure(const ghost_run *g, int im, int sa, int lv, int mo, float opacity, ghost_row *r, double *occ_ratio,
                    mr_error *err) {
    bool ok = true;
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.ghost.opacity = opacity;
    fp.width = g->w;
    fp.height = g->h;
    fp.timing = true;
    fp.ghost.mode = (mr_ghost_mode)(MR_GHOST_ALPHA + mo);
    fp.ghost.importance = im ? MR_GHOST_IMP_SALIENCY : MR_GHOST_IMP_CURVATURE;
    fp.ghost.saliency = sa ? MR_SALIENCY_GAUSS : MR_SALIENCY_MIPMAP;
    fp.ghost.saliency_levels = lv ? MR_SAL_LEVELS_PRINTED : MR_SAL_LEVELS_OFFSET;
    for (long f = -2; ok && f < g->frames; f++) {
        mr_frame_result res;
        double t0 = mr_time_now();
        ok = mr_render_frame(g->gfx->renderer, g->view, &fp, &res, err);
        if (!ok || f < 0) {
            if (ok) mr_frame_result_free(&res);
            continue;
        }
        g->samples[(size_t)7 * g->frames + f] = (mr_time_now() - t0) * 1e3;
        double tot = 0;
        for (int k = 0; k < 6; k++) g->samples[(size_t)k * g->frames + f] = 0;
        for (int q = 0; q < res.pass_count; q++)
            for (int k = 0; k < 6; k++)
                if (strcmp(res.passes[q], k_pass_names[k]) == 0) {
                    g->samples[(size_t)k * g->frames + f] = res.gpu_ms[q];
                    tot += res.gpu_ms[q];
                }
        g->samples[(size_t)6 * g->frames + f] = tot;
        mr_frame_result_free(&res);
    }
    if (!ok) return false;
    for (int k = 0; k < 6; k++) r->pass_ms[k] = mr_median(&g->samples[(size_t)k * g->frames], (int)g->frames);
    r->ghost_ms = mr_median(&g->samples[(size_t)6 * g->frames], (int)g->frames);
    r->frame_ms = mr_median(&g->samples[(size_t)7 * g->frames], (int)g->frames);
    /* The measure, in one untimed frame (it adds GPU work). */
    fp.timing = false;
    fp.ghost.stats = true;
    mr_frame_result res;
    ok = mr_render_frame(g->gfx->renderer, g->view, &fp, &res, err);
    if (ok) {
        r->st = res.ghost;
        mr_image o, d, reg;
        ok = mr_ghost_read_layers(g->gfx->renderer, &o, &d, &reg, err);
        if (ok) {
            mr_ghost_legibility_images li = {&res.color, &o, &d, &reg};
            ok = mr_eval_ghost_legibility(&li, NULL, &r->leg, err) &&
                 mr_eval_saliency_ratio(&res.color, &reg, &r->sal_ratio, err) &&
                 (!isnan(*occ_ratio) || mr_eval_saliency_ratio(&o, &reg, occ_ratio, err));
            r->sal_ratio_occluder = *occ_ratio;
        }
        mr_image_free(&o);
        mr_image_free(&d);
        mr_image_free(&reg);
        mr_frame_result_free(&res);
    }
    return ok;
}

bool mr_bench_ghost(const mr_bench_ghost_params *params, mr_error *err) {
    const mr_bench_ghost_params dflt = {MR_BENCH_GHOST_DEFAULTS};
    mr_bench_ghost_params p = params ? *params : dflt;
    if (!p.out_dir) p.out_dir = dflt.out_dir;
    if (p.width <= 0 || p.height <= 0) p.width = dflt.width, p.height = dflt.height;
    if (p.frames <= 0) p.frames = dflt.frames;
    if (p.view < 0 || p.view >= MR_DEMO_VIEWS) return mr_fail(err, MR_ERR_INVALID, "bench ghost: view %d is not 0..%d", p.view, MR_DEMO_VIEWS - 1);
    const int w = p.width, h = p.height;
    const long frames = p.frames, view_index = p.view;
    const char *out_dir = p.out_dir;
    FILE *out = p.out;
    mr_view view = mr_demo_view((int)view_index);

    static const char *const scenes[2] = {"conflict", "noconflict"};
    static const char *const imps[2] = {"curvature", "saliency"};
    static const char *const sals[2] = {"mipmap", "gauss"};
    static const char *const modes[3] = {"alpha", "g0", "adaptive"};
    static const char *const levels[2] = {"offset", "printed"};
    enum { NROWS = 2 * 2 * 2 * 2 * 3 };
    ghost_row rows[NROWS];
    int nrows = 0;
    enum { SWEEP_T = 4 };
    static const float k_sweep_t[SWEEP_T] = {0.25f, 0.5f, 0.75f, 1.0f};
    ghost_row sweep[2 * SWEEP_T * 2];
    float sweep_t[2 * SWEEP_T * 2];
    int nsweep = 0;
    const mr_bench_gpu gfx = p.gfx;
    bool ok = bench_gpu_check(&gfx, "bench ghost", err) && mr_mkdirs(out_dir, err);
    double *samples = ok ? calloc((size_t)frames * 8, sizeof *samples) : NULL;
    if (ok && !samples) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    const ghost_run run = {&gfx, &view, w, h, frames, samples};
    for (int sc = 0; ok && sc < 2; sc++) {
        mr_demo_hall hall;
        ok = build_hall(sc == 0, &hall, err) && mr_renderer_set_scene(gfx.renderer, hall.planned, err);
        double occ_ratio = NAN;
        for (int im = 0; ok && im < 2; im++)
            for (int sa = 0; ok && sa < 2; sa++)
                for (int lv = 0; ok && lv < 2; lv++)
                for (int mo = 0; ok && mo < 3; mo++) {
                    ghost_row *r = &rows[nrows];
                    memset(r, 0, sizeof *r);
                    r->scene = scenes[sc];
                    r->importance = imps[im];
                    r->saliency = sals[sa];
                    r->levels = levels[lv];
                    r->mode = modes[mo];
                    r->mode_index = mo;
                    if (!(ok = measure(&run, im, sa, lv, mo, MR_GHOST_DEFAULT_OPACITY, r, &occ_ratio, err))) break;
                    nrows++;
                    if (ok && p.progress)
                        fprintf(stderr, "\rbench ghost: %d/%d configurations", nrows, NROWS);
                }
        /* Fig. 8: the state-of-the-art ghosted view (alpha) against the
         * adaptive one as the opacity t rises (curvature importance). */
        for (int oi = 0; ok && oi < SWEEP_T; oi++)
            for (int mo = 0; ok && mo < 3; mo += 2) {
                ghost_row *r = &sweep[nsweep];
                memset(r, 0, sizeof *r);
                r->scene = scenes[sc];
                r->importance = imps[0];
                r->saliency = sals[0];
                r->levels = levels[0];
                r->mode = modes[mo];
                r->mode_index = mo;
                ok = measure(&run, 0, 0, 0, mo, k_sweep_t[oi], r, &occ_ratio, err);
                if (ok) sweep_t[nsweep++] = k_sweep_t[oi];
            }
        mr_renderer_set_scene(gfx.renderer, NULL, NULL);
        mr_demo_free(&hall);
    }
    if (p.progress) fprintf(stderr, "\n");
    if (ok) {
        mr_csv *csv = mr_csv_create(err);
        ok = csv != NULL;
        mr_csv_comment(csv, "legibility_edge_transfer: mean over D's important edges (4 dE(D)/100 > 0.5) of the part "
                            "of D's contrast over the occluder that the final image shows (0 occluder only, 1 D in full); "
                            "edge_contrast_dE / full_contrast_dE: mean dE the final image / D in full adds over the "
                            "occluder there; cv_saliency_ratio: OpenCV spectral-residual saliency, region mean / mean "
                            "elsewhere (_occluder: of the occluder alone); target_reached: pixels reaching C_desired, the "
                            "adaptive stage's own target (a diagnostic, not legibility); occluder_kept: the same measure "
                            "for the occluder's own important edges (Experiment 2's H2): 1 = kept in full, 0 = gone");
        char cols[1024];
        int cl = snprintf(cols, sizeof cols, "scene,importance,saliency,saliency_levels,mode");
        for (int k = 0; k < 6; k++) cl += snprintf(cols + cl, sizeof cols - (size_t)cl, ",%s_gpu_ms", k_pass_names[k]);
        snprintf(cols + cl, sizeof cols - (size_t)cl,
                 ",ghost_gpu_ms,frame_wall_ms,legibility_edge_transfer,occluder_kept,edge_contrast_dE,full_contrast_dE,"
                 "important_edge_fraction,cv_saliency_ratio,cv_saliency_ratio_occluder,target_reached,"
                 "mean_abs_dL,region_fraction,mean_importance,mean_contrast_missing,width,height,frames");
        mr_csv_header(csv, cols);
        BENCH_PRINT(out, "bench ghost: %s, %dx%d, demo view %ld, median of %ld frames\n", mr_gpu_description(gfx.gpu), w, h,
                    view_index, frames);
        BENCH_PRINT(out, "  %-10s %-9s %-6s %-7s %-8s %8s %8s %8s %8s %8s %8s %9s %10s %7s %7s %7s\n", "scene", "IM", "sal",
                    "levels", "mode", "hidden", "curv", "import", "g0", "analys", "emph", "ghost ms", "legibility",
                    "cv-sal", "target", "|dL*|");
        for (int i = 0; ok && i < nrows; i++) {
            const ghost_row *r = &rows[i];
            const char *names[5] = {r->scene, r->importance, r->saliency, r->levels, r->mode};
            for (int k = 0; k < 5; k++) mr_csv_text(csv, names[k]);
            for (int k = 0; k < 6; k++) mr_csv_num(csv, "%.4f", r->pass_ms[k]);
            /* value, format: the columns after the pass times */
            const struct { double v; const char *f; } cells[] = {
                {r->ghost_ms, "%.4f"}, {r->frame_ms, "%.4f"}, {r->leg.legibility, "%.4f"}, {r->leg.occluder_kept, "%.4f"},
                {r->leg.edge_contrast, "%.3f"}, {r->leg.full_contrast, "%.3f"}, {r->leg.important_fraction, "%.4f"},
                {r->sal_ratio, "%.3f"}, {r->sal_ratio_occluder, "%.3f"}, {r->st.target_reached, "%.4f"},
                {r->st.mean_abs_dL, "%.3f"}, {r->st.region_fraction, "%.4f"}, {r->st.mean_importance, "%.4f"},
                {r->st.mean_contrast_missing, "%.4f"},
            };
            for (size_t k = 0; k < sizeof cells / sizeof cells[0]; k++) mr_csv_num(csv, cells[k].f, cells[k].v);
            mr_csv_int(csv, w);
            mr_csv_int(csv, h);
            mr_csv_int(csv, frames);
            mr_csv_end_row(csv);
            BENCH_PRINT(out, "  %-10s %-9s %-6s %-7s %-8s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %9.2f %10.3f %7.2f %7.3f %7.2f\n",
                   r->scene, r->importance, r->saliency, r->levels, r->mode, r->pass_ms[0], r->pass_ms[1], r->pass_ms[2],
                   r->pass_ms[3], r->pass_ms[4], r->pass_ms[5], r->ghost_ms, r->leg.legibility, r->sal_ratio,
                   r->st.target_reached, r->st.mean_abs_dL);
        }
        char path[4096], title[256];
        if (ok) {
            mr_path_join(out_dir, "bench_ghost.csv", path, sizeof path);
            ok = mr_csv_save(csv, path, err);
        }
        mr_csv_destroy(&csv);
        snprintf(title, sizeof title, "mrcheck bench ghost: legibility against run time, %dx%d, demo view %ld (eq. 9 levels: offset)", w, h,
                 view_index);
        mr_path_join(out_dir, "bench_ghost.svg", path, sizeof path);
        ok = ok && write_svg(path, title, rows, nrows, err);
        if (ok) BENCH_PRINT(out, "wrote %s/bench_ghost.csv and bench_ghost.svg\n", out_dir);
    }
    if (ok) {
        /* Kalkofen et al.'s Fig. 8 as numbers: legibility of the hidden
         * layer over the occluder as the opacity t rises. */
        mr_csv *csv = mr_csv_create(err);
        ok = csv != NULL;
        mr_csv_comment(csv, "Fig. 8's sweep: curvature importance, alpha (state-of-the-art ghosted view) and adaptive, the occluder "
                            "opacity t (alpha = t * IM; the paper's 'transparency') from 0.25 to 1; columns as bench_ghost.csv");
        mr_csv_header(csv, "scene,mode,opacity,legibility_edge_transfer,occluder_kept,edge_contrast_dE,full_contrast_dE,mean_abs_dL,width,"
                           "height");
        BENCH_PRINT(out, "bench ghost, Fig. 8 sweep (curvature importance):\n  %-10s %-8s %7s %10s %9s\n", "scene", "mode", "t",
                    "legibility", "occl.kept");
        for (int i = 0; ok && i < nsweep; i++) {
            const ghost_row *r = &sweep[i];
            mr_csv_text(csv, r->scene);
            mr_csv_text(csv, r->mode);
            mr_csv_num(csv, "%.2f", sweep_t[i]);
            mr_csv_num(csv, "%.4f", r->leg.legibility);
            mr_csv_num(csv, "%.4f", r->leg.occluder_kept);
            mr_csv_num(csv, "%.3f", r->leg.edge_contrast);
            mr_csv_num(csv, "%.3f", r->leg.full_contrast);
            mr_csv_num(csv, "%.3f", r->st.mean_abs_dL);
            mr_csv_int(csv, w);
            mr_csv_int(csv, h);
            mr_csv_end_row(csv);
            BENCH_PRINT(out, "  %-10s %-8s %7.2f %10.3f %9.3f\n", r->scene, r->mode, sweep_t[i], r->leg.legibility, r->leg.occluder_kept);
        }
        char path[4096];
        if (ok) {
            mr_path_join(out_dir, "bench_ghost_sweep.csv", path, sizeof path);
            ok = mr_csv_save(csv, path, err);
        }
        mr_csv_destroy(&csv);
    }
    free(samples);
    return ok;
}
