/* mrcheck bench multiview: N views at a fixed total pixel budget and at a
 * fixed per-view size (ms per frame and per view, AO error against the ray-
 * traced reference under the pinhole and the light-field display mapping,
 * cross-view AO consistency with the pixel and the world-position noise),
 * the display mapping's slices (band width against time, mapping and AO
 * error), and Doronin et al.'s Table 1 shape (per-view ms without and with
 * SSAO for three scenes). */
#include "bench_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEG (3.14159265358979323846 / 180.0)

static double now_ms(void) { return mr_time_now() * 1e3; }

/* The AO both the frames and the reference use: a fixed radius, so the
 * reference is the same surface integral in every view. */
static mr_frame_params ao_frame(int w, int h, double radius, mr_ao_noise noise, const mr_view *anchor, bool no_blur) {
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = w;
    fp.height = h;
    fp.ao.method = MR_AO_CRYTEK;
    fp.ao.radius_mode = MR_AO_RADIUS_VIEW;
    fp.ao.radius = radius;
    fp.ao.positions = true;
    fp.ao.no_reuse = true;
    fp.ao.noise = noise;
    if (no_blur) fp.ao.blur_radius = 0; /* the noise itself */
    if (anchor) {
        fp.ao.noise_anchor = anchor->world_from_camera;
        fp.ao.noise_anchor_set = true;
    }
    return fp;
}

/* RMSE over the surface pixels (depth > 0); NAN where there are none. */
static double rmse_over_surface(const mr_image *a, const mr_image *b, const mr_image *depth) {
    mr_image_metrics m;
    mr_error e = {0};
    return mr_image_compare(a, b, depth, &m, &e) && m.count > 0 ? m.rmse : NAN;
}

/* AO of one frame against its ray-traced reference (the frame's own
 * surface points; the display mapping's exact rays when m is given). */
static bool ao_error(mr_renderer *r, const mr_eval_gt *gt, const mr_view *v, const mr_frame_params *base,
                     const mr_display_map *m, double radius, int rays, double *rmse, mr_error *err) {
    mr_frame_params fp = *base;
    fp.want_depth = fp.want_normals = true;
    fp.ao.want_ao = true;
    fp.display = m;
    mr_frame_result res;
    if (!mr_render_frame(r, v, &fp, &res, err)) return false;
    mr_gt_params gp = MR_GT_DEFAULTS;
    gp.radius = radius;
    gp.rays = rays;
    gp.display = m;
    mr_image ref = {0};
    bool ok = mr_eval_ao_groundtruth(gt, v, &res.depth, &res.normal, &gp, &ref, err);
    if (ok) *rmse = rmse_over_surface(&res.ao, &ref, &res.depth);
    mr_image_free(&ref);
    mr_frame_result_free(&res);
    return ok;
}

/* Mean over neighbouring views of the AO's RMSE, reprojected through depth. */
static bool consistency(mr_renderer *r, const mr_rig *rig, const mr_view *centre, const mr_frame_params *base,
                        double *rmse, double *fraction, mr_error *err) {
    mr_frame_params fp = *base;
    fp.want_depth = true;
    fp.ao.want_ao = true;
    mr_frame_result prev = {0}, cur;
    mr_view vprev;
    memset(&vprev, 0, sizeof vprev);
    double sum = 0, fsum = 0;
    int pairs = 0;
    for (int i = 0; i < rig->views; i++) {
        mr_view v = mr_rig_view(rig, centre, i, fp.width, fp.height);
        if (!mr_render_frame(r, &v, &fp, &cur, err)) {
            mr_frame_result_free(&prev);
            return false;
        }
        if (i > 0) {
            mr_view_consistency c;
            if (!mr_eval_view_consistency(&vprev, &prev.depth, &prev.ao, &v, &cur.depth, &cur.ao, 0.01, &c, err)) {
                mr_frame_result_free(&prev);
                mr_frame_result_free(&cur);
                return false;
            }
            if (c.pixels > 0) {
                sum += c.rmse;
                fsum += c.fraction;
                pairs++;
            }
        }
        mr_frame_result_free(&prev);
        prev = cur;
        vprev = v;
    }
    mr_frame_result_free(&prev);
    *rmse = pairs ? sum / pairs : NAN;
    *fraction = pairs ? fsum / pairs : NAN;
    return true;
}

/* Median wall-clock ms of rendering all the rig's views (glFinish'ed: each
 * frame reads its image back). */
static bool time_rig(mr_renderer *r, const mr_rig *rig, const mr_view *centre, const mr_frame_params *fp, int frames,
                     double *ms, mr_error *err) {
    double t[64];
    if (frames > 64) frames = 64;
    mr_quilt_layout l;
    if (!mr_quilt_layout_make(NULL, rig->views, fp->width, fp->height, &l, err)) return false;
    for (int f = -1; f < frames; f++) {
        double t0 = now_ms();
        mr_image q = {0};
        if (!mr_render_rig(r, rig, centre, fp, &l, NULL, &q, NULL, err)) return false;
        mr_image_free(&q);
        if (f >= 0) t[f] = now_ms() - t0; /* the first one compiles and allocates */
    }
    *ms = mr_median(t, frames);
    return true;
}

static bool time_frame(mr_renderer *r, const mr_view *v, const mr_frame_params *fp, int frames, double *ms, mr_error *err) {
    double t[64];
    if (frames > 64) frames = 64;
    for (int f = -1; f < frames; f++) {
        mr_frame_result res;
        double t0 = now_ms();
        if (!mr_render_frame(r, v, fp, &res, err)) return false;
        mr_frame_result_free(&res);
        if (f >= 0) t[f] = now_ms() - t0;
    }
    *ms = mr_median(t, frames);
    return true;
}

/* The shared work. Median ms of a rig frame (all views, read
 * back) with one cull and one shadow map per frame against the old per-view
 * work, side by side in one run (alternating, so load drifts hit both), on
 * the demo hall and the synthetic factory (many nodes: culling counts). */
typedef struct shared_row {
    const char *scene;
    int views;
    double ms_per_view_work, ms_shared, cull_per_view_work, cull_shared;
    double geo_loop, geo_layered; /* the G-buffer geometry alone, per-view loop vs layered */
    int maps_per_view_work, maps_shared, culls_per_view_work, culls_shared;
} shared_row;

static bool bench_shared(const mr_bench_multiview_params *p, mr_scene *const scenes[2], const char *const names[2],
                         const mr_view views[2], mr_error *err) {
    mr_renderer *r = p->gfx.renderer;
    static const int k_n[3] = {8, 24, 48};
    shared_row rows[6];
    int nrows = 0;
    bool ok = true;
    for (int sc = 0; ok && sc < 2; sc++) {
        ok = mr_renderer_set_scene(r, scenes[sc], err);
        for (int k = 0; ok && k < 3; k++) {
            shared_row *rw = &rows[nrows];
            memset(rw, 0, sizeof *rw);
            rw->scene = names[sc];
            rw->views = k_n[k];
            mr_rig_params rp = MR_RIG_DEFAULTS;
            rp.views = k_n[k];
            mr_rig rig[2];
            /* Focused on the scene's centre; the pinhole views' own fov. */
            const mr_view *c = &views[sc];
            rp.fov_deg = 2 * atan(0.5 * c->camera.height / c->camera.fy) / DEG;
            double focal = mr_rig_auto_focal_distance(scenes[sc], c);
            if (!(focal > 0)) focal = 10;
            ok = mr_rig_make(&rp, (double)p->view_w / p->view_h, focal, &rig[0], err);
            rig[1] = rig[0];
            rig[1].per_view_work = true;
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = p->view_w;
            fp.height = p->view_h;
            fp.shadow.method = MR_SHADOW_PCF;
            /* Every frame draws its maps (a moving rig): nothing is handed
             * over from the last frame, only between a frame's views. */
            fp.shadow.no_reuse = true;
            mr_quilt_layout l;
            ok = ok && mr_quilt_layout_make(NULL, rig[0].views, fp.width, fp.height, &l, err);
            double t[2][64], cm[2][64];
            int frames = p->frames > 64 ? 64 : p->frames;
            mr_rig_result rr[2];
            for (int f = -1; ok && f < frames; f++)
                for (int m = 0; ok && m < 2; m++) {
                    mr_image q = {0};
                    double t0 = now_ms();
                    ok = mr_render_rig(r, &rig[m], c, &fp, &l, NULL, &q, &rr[m], err);
                    mr_image_free(&q);
                    if (f >= 0) t[m][f] = now_ms() - t0, cm[m][f] = rr[m].cull_ms;
                }
            if (!ok) break;
            rw->ms_shared = mr_median(t[0], frames);
            rw->ms_per_view_work = mr_median(t[1], frames);
            rw->cull_shared = mr_median(cm[0], frames);
            rw->cull_per_view_work = mr_median(cm[1], frames);
            rw->maps_shared = rr[0].shadow_maps;
            rw->maps_per_view_work = rr[1].shadow_maps;
            rw->culls_shared = rr[0].frustum_culls;
            rw->culls_per_view_work = rr[1].frustum_culls;
            /* The layered experiment: the first run of each compiles the
             * shader variants; alternating pairs of runs after it. */
            double gl[2][65];
            for (int f = 0; ok && f <= frames; f++)
                for (int m = 0; ok && m < 2; m++)
                    ok = mr_rig_geometry_time(r, &rig[0], c, fp.width, fp.height, m == 1, 1, &gl[m][f], NULL, err);
            if (!ok) break;
            rw->geo_loop = mr_median(gl[0] + 1, frames);
            rw->geo_layered = mr_median(gl[1] + 1, frames);
            if (p->progress) fprintf(stderr, "bench multiview: shared work, %s, %d views done\n", rw->scene, rw->views);
            nrows++;
        }
        mr_renderer_set_scene(r, NULL, NULL);
    }
    if (!ok) return false;
    char path[4096];
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "mrcheck bench multiview: shared work per rig frame, pcf shadows, no AO");
    mr_csv_header(csv, "scene,views,width,height,ms_frame_per_view_work,ms_frame_shared,speedup,cull_ms_per_view_work,"
                       "cull_ms_shared,shadow_maps_per_view_work,shadow_maps_shared,frustum_culls_per_view_work,"
                       "frustum_culls_shared,gbuffer_geometry_ms_loop,gbuffer_geometry_ms_layered");
    for (int i = 0; i < nrows; i++) {
        const shared_row *rw = &rows[i];
        mr_csv_quoted(csv, rw->scene);
        mr_csv_int(csv, rw->views);
        mr_csv_int(csv, p->view_w);
        mr_csv_int(csv, p->view_h);
        mr_csv_num(csv, "%.2f", rw->ms_per_view_work);
        mr_csv_num(csv, "%.2f", rw->ms_shared);
        mr_csv_num(csv, "%.3f", rw->ms_per_view_work / rw->ms_shared);
        mr_csv_num(csv, "%.3f", rw->cull_per_view_work);
        mr_csv_num(csv, "%.3f", rw->cull_shared);
        mr_csv_int(csv, rw->maps_per_view_work);
        mr_csv_int(csv, rw->maps_shared);
        mr_csv_int(csv, rw->culls_per_view_work);
        mr_csv_int(csv, rw->culls_shared);
        mr_csv_num(csv, "%.2f", rw->geo_loop);
        mr_csv_num(csv, "%.2f", rw->geo_layered);
        mr_csv_end_row(csv);
    }
    mr_path_join(p->out_dir, "bench_multiview_shared.csv", path, sizeof path);
    ok = mr_csv_save(csv, path, err);
    mr_csv_destroy(&csv);
    double xs[4][3], ys[4][3];
    int cnt[4] = {0};
    for (int i = 0; i < nrows; i++) {
        int sc = i / 3;
        for (int m = 0; m < 2; m++) {
            xs[2 * sc + m][cnt[2 * sc + m]] = rows[i].views;
            ys[2 * sc + m][cnt[2 * sc + m]++] = m ? rows[i].ms_per_view_work : rows[i].ms_shared;
        }
    }
    char sn[4][96];
    mr_plot_series ser[4];
    for (int k = 0; k < 4; k++) {
        snprintf(sn[k], sizeof sn[k], "%s, %s", names[k / 2], k & 1 ? "per-view work" : "shared");
        ser[k] = (mr_plot_series){.name = sn[k], .x = xs[k], .y = ys[k], .count = cnt[k], .dashed = (k & 1) != 0,
                                  .mark = k & 1 ? MR_PLOT_MARK_SQUARE : MR_PLOT_MARK_CIRCLE};
    }
    mr_plot_params pp = {.title = "mrcheck bench multiview: ms per rig frame, shared vs per-view culling and shadow maps",
                         .xlabel = "views", .ylabel = "ms per frame", .log_x = true, .log_y = true};
    mr_path_join(p->out_dir, "bench_multiview_shared.svg", path, sizeof path);
    ok = ok && mr_plot_write(path, &pp, ser, 4, err);
    size_t cap = 8192, len = 0;
    char *md = malloc(cap);
    if (!md) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
#define MD(...) do { if (len < cap) len += (size_t)snprintf(md + len, cap - len, __VA_ARGS__); } while (0)
    MD("# mrcheck bench multiview: shared work\n\nGPU: %s. A rig frame of N views of %dx%d (35 degree "
       "cone, focused on the scene's centre), pcf shadows (sun, cascades as the scene needs), no AO, read back; median "
       "of %d frames, the two ways alternating. Shared: one frustum cull + LOD choice for the union of the views' "
       "frusta and one shadow map fitted to the union per frame; per-view work: each view culls and fits and draws its "
       "own maps (--views-per-view-work). cull ms: CPU culling, LOD and instance data, all views. Layered "
       "experiment: the G-buffer pass's geometry alone (depth only, the shared list) for all views into one quilt, "
       "one draw per view with its own instance matrices (loop) against one instanced draw per 16 views through "
       "gl_ViewportIndex (layered); not part of the frame times.\n\n",
       mr_gpu_description(p->gfx.gpu), p->view_w, p->view_h, p->frames);
    MD("| scene | views | ms/frame per-view work | ms/frame shared | speed-up | cull ms per-view | cull ms shared | "
       "shadow maps per-view | shared | culls per-view | shared | geometry ms loop | geometry ms layered |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < nrows; i++)
        MD("| %s | %d | %.1f | %.1f | %.2f | %.2f | %.2f | %d | %d | %d | %d | %.1f | %.1f |\n", rows[i].scene,
           rows[i].views, rows[i].ms_per_view_work, rows[i].ms_shared, rows[i].ms_per_view_work / rows[i].ms_shared,
           rows[i].cull_per_view_work, rows[i].cull_shared, rows[i].maps_per_view_work, rows[i].maps_shared,
           rows[i].culls_per_view_work, rows[i].culls_shared, rows[i].geo_loop, rows[i].geo_layered);
#undef MD
    mr_path_join(p->out_dir, "bench_multiview_shared.md", path, sizeof path);
    ok = ok && mr_file_write_atomic(path, md, len < cap ? len : cap - 1, err);
    if (ok) BENCH_PRINT(p->out, "%.*s\nwrote %s/bench_multiview_shared{.csv,.svg,.md}\n", (int)len, md, p->out_dir);
    free(md);
    return ok;
}

typedef struct row {
    const char *mode;
    int views, w, h;
    double ms_frame, ms_view, err_pin, err_disp, cons_world, cons_pixel, cons_world0, cons_pixel0, shared;
} row;

static const int k_views[] = {1, 8, 24, 48};
static const int k_bands[] = {1, 4, 16};
static const char *const k_table_scenes[3] = {"demo hall (planned)", "demo hall (built)", "synthetic factory"};

/* One run's state: what is set up once, then the three tables in the
 * order they are measured. */
typedef struct mv_run {
    mr_bench_multiview_params p;
    mr_renderer *r;
    mr_demo_hall hall;
    mr_view centre;
    mr_eval_gt *gt;
    double radius, fov, focal;
    row rows[8];
    int nrows;
    double band_ms[3], band_err_mean[3], band_err_max[3], band_ao[3];
    double t_no[3], t_ao[3];
    uint64_t t_tris[3];
} mv_run;

/* The AO radius, the reference and the rig's cone (the display defaults'
 * 35 degrees around the camera's own vertical field of view), focused
 * where the centre view looks. */
static bool mv_setup(mv_run *m, mr_error *err) {
    mr_scene *scene = m->hall.planned;
    m->radius = mr_ao_default_radius(scene);
    m->fov = 2 * atan(0.5 * m->centre.camera.height / m->centre.camera.fy) / DEG;
    if (!mr_renderer_set_scene(m->r, scene, err) || !(m->gt = mr_eval_gt_create(scene, false, err))) return false;
    mr_frame_params dp = MR_FRAME_DEFAULTS;
    dp.want_depth = true;
    dp.width = m->p.view_w;
    dp.height = m->p.view_h;
    mr_frame_result fr;
    bool ok = mr_render_frame(m->r, &m->centre, &dp, &fr, err);
    if (ok) m->focal = mr_rig_focal_from_depth(&fr.depth);
    mr_frame_result_free(&fr);
    if (ok && !(m->focal > 0)) ok = mr_fail(err, MR_ERR_INVALID, "bench multiview: the view sees nothing to focus on");
    return ok;
}

/* One row of the views table: n views at the total budget (mode 0) or at
 * the fixed per-view size (mode 1). */
static bool mv_rig_row(mv_run *m, int mode, int n, row *rw, mr_error *err) {
    const mr_bench_multiview_params *p = &m->p;
    memset(rw, 0, sizeof *rw);
    rw->mode = mode == 0 ? "budget" : "per_view";
    rw->views = n;
    rw->w = mode == 0 ? (int)lround(p->budget_w / sqrt((double)n)) : p->view_w;
    rw->h = mode == 0 ? (int)lround(p->budget_h / sqrt((double)n)) : p->view_h;
    mr_rig_params rp = MR_RIG_DEFAULTS;
    rp.views = n;
    rp.fov_deg = m->fov;
    mr_rig rig;
    bool ok = mr_rig_make(&rp, (double)rw->w / rw->h, m->focal, &rig, err);
    mr_frame_params fw = ao_frame(rw->w, rw->h, m->radius, MR_AO_NOISE_WORLD, &m->centre, false);
    mr_frame_params fpx = ao_frame(rw->w, rw->h, m->radius, MR_AO_NOISE_PIXEL, NULL, false);
    mr_frame_params fw0 = ao_frame(rw->w, rw->h, m->radius, MR_AO_NOISE_WORLD, &m->centre, true);
    mr_frame_params fpx0 = ao_frame(rw->w, rw->h, m->radius, MR_AO_NOISE_PIXEL, NULL, true);
    ok = ok && time_rig(m->r, &rig, &m->centre, &fw, p->frames, &rw->ms_frame, err);
    rw->ms_view = rw->ms_frame / n;
    /* AO error against the reference on the outer and middle views. */
    int probe[3] = {0, n / 2, n - 1}, np = n >= 3 ? 3 : 1;
    double se = 0;
    for (int j = 0; ok && j < np; j++) {
        mr_view v = mr_rig_view(&rig, &m->centre, probe[j], rw->w, rw->h);
        double e = 0;
        ok = ao_error(m->r, m->gt, &v, &fw, NULL, m->radius, p->rays, &e, err);
        se += e;
    }
    rw->err_pin = se / np;
    /* The display mapping at the same size and cone (exact slices). */
    mr_rig_params one = rp;
    one.views = 1;
    mr_rig crig;
    ok = ok && mr_rig_make(&one, (double)rw->w / rw->h, m->focal, &crig, err);
    crig.cone = rp.cone_deg * DEG;
    mr_display_map dm = mr_display_from_rig(&crig, 1);
    mr_view cv = mr_rig_view(&crig, &m->centre, 0, rw->w, rw->h);
    ok = ok && ao_error(m->r, m->gt, &cv, &fw, &dm, m->radius, p->rays, &rw->err_disp, err);
    rw->cons_world = rw->cons_pixel = rw->cons_world0 = rw->cons_pixel0 = rw->shared = NAN;
    if (ok && n > 1) {
        double f1, f2;
        ok = consistency(m->r, &rig, &m->centre, &fw, &rw->cons_world, &f1, err) &&
             consistency(m->r, &rig, &m->centre, &fpx, &rw->cons_pixel, &f2, err) &&
             consistency(m->r, &rig, &m->centre, &fw0, &rw->cons_world0, &f2, err) &&
             consistency(m->r, &rig, &m->centre, &fpx0, &rw->cons_pixel0, &f2, err);
        rw->shared = f1;
    }
    if (ok && p->progress) fprintf(stderr, "bench multiview: %s %d views done\n", rw->mode, n);
    return ok;
}

/* The display mapping's slices k_bands[b] columns wide at the per-view
 * size: time, where the exact mapping puts each pixel's surface point
 * (from the depth the slices rendered), AO error. */
static bool mv_band(mv_run *m, int b, mr_error *err) {
    const int w = m->p.view_w, h = m->p.view_h;
    mr_rig_params one = MR_RIG_DEFAULTS;
    one.views = 1;
    one.fov_deg = m->fov;
    mr_rig crig;
    bool ok = mr_rig_make(&one, (double)w / h, m->focal, &crig, err);
    mr_display_map dm = mr_display_from_rig(&crig, k_bands[b]);
    mr_view cv = mr_rig_view(&crig, &m->centre, 0, w, h);
    mr_frame_params fw = ao_frame(w, h, m->radius, MR_AO_NOISE_WORLD, &m->centre, false);
    fw.display = &dm;
    ok = ok && time_frame(m->r, &cv, &fw, m->p.frames, &m->band_ms[b], err);
    mr_frame_params fd = fw;
    fd.want_depth = true;
    mr_frame_result res;
    if (ok && (ok = mr_render_frame(m->r, &cv, &fd, &res, err))) {
        double sum = 0, mx = 0;
        long cnt = 0;
        const float *d = res.depth.data;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                double z = d[(size_t)y * w + x];
                if (!(z > 0)) continue;
                double e = fabs(mr_display_column_error(&dm, &cv.camera, x, z));
                if (!isfinite(e)) continue;
                sum += e;
                mx = fmax(mx, e);
                cnt++;
            }
        m->band_err_mean[b] = cnt ? sum / cnt : NAN;
        m->band_err_max[b] = mx;
        mr_frame_result_free(&res);
    }
    fw.display = NULL;
    return ok && ao_error(m->r, m->gt, &cv, &fw, &dm, m->radius, m->p.rays, &m->band_ao[b], err);
}

/* Table 1's shape: three scenes, per-view ms without and with SSAO. On
 * the light-field path, as the paper times it: one optical module's image
 * through the display mapping (4-column slices, the middle row of the band
 * table), the AO reading the positions texture the G-buffer writes (the
 * paper's G-buffer "position texture"). */
static bool mv_table1(mv_run *m, mr_error *err) {
    const mr_bench_multiview_params *p = &m->p;
    mr_synth_params sp = MR_SYNTH_DEFAULTS;
    mr_scene *synth = mr_synth_build(&sp, err);
    bool ok = synth != NULL;
    mr_rig_params trp = MR_RIG_DEFAULTS;
    trp.views = 1;
    trp.fov_deg = m->fov;
    mr_rig trig;
    ok = ok && mr_rig_make(&trp, (double)p->table_w / p->table_h, m->focal, &trig, err);
    mr_display_map tmap = mr_display_from_rig(&trig, 4);
    for (int s = 0; ok && s < 3; s++) {
        mr_scene *sc = s == 0 ? m->hall.planned : s == 1 ? m->hall.built : synth;
        mr_view vc = m->centre;
        if (s == 2) vc.world_from_camera = mr_synth_viewpoint(&sp, MR_SYNTH_VIEW_AISLE);
        mr_view v = mr_rig_view(&trig, &vc, 0, p->table_w, p->table_h);
        ok = mr_renderer_set_scene(m->r, sc, err);
        mr_frame_params f0 = MR_FRAME_DEFAULTS;
        f0.width = p->table_w;
        f0.height = p->table_h;
        f0.display = &tmap;
        mr_frame_params f1 = f0;
        f1.ao.method = MR_AO_CRYTEK; /* Mittring's, as the paper */
        f1.ao.positions = true;
        f1.ao.no_reuse = true;
        ok = ok && time_frame(m->r, &v, &f0, p->frames, &m->t_no[s], err) &&
             time_frame(m->r, &v, &f1, p->frames, &m->t_ao[s], err);
        if (ok) {
            mr_frame_result res;
            if ((ok = mr_render_frame(m->r, &v, &f0, &res, err))) m->t_tris[s] = res.triangles;
            mr_frame_result_free(&res);
        }
        mr_renderer_set_scene(m->r, NULL, NULL);
    }
    mr_scene_destroy(&synth);
    return ok;
}

/* bench_multiview.csv, _display.csv and _table1.csv. */
static bool mv_write_csvs(const mv_run *m, mr_error *err) {
    const mr_bench_multiview_params *p = &m->p;
    char path[4096];
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "mrcheck bench multiview: demo hall, crytek AO (view radius, positions), 35 degree cone; table 1: one optical "
                         "module through the display mapping (4-column slices), crytek with the positions texture");
    mr_csv_header(csv, "mode,views,width,height,ms_frame,ms_per_view,ao_rmse_pinhole,ao_rmse_display,"
                       "consistency_rmse_world,consistency_rmse_pixel,consistency_rmse_world_noblur,"
                       "consistency_rmse_pixel_noblur,shared_fraction");
    for (int i = 0; i < m->nrows; i++) {
        const row *rw = &m->rows[i];
        mr_csv_text(csv, rw->mode);
        mr_csv_int(csv, rw->views);
        mr_csv_int(csv, rw->w);
        mr_csv_int(csv, rw->h);
        mr_csv_num(csv, "%.2f", rw->ms_frame);
        mr_csv_num(csv, "%.3f", rw->ms_view);
        mr_csv_num(csv, "%.4f", rw->err_pin);
        mr_csv_num(csv, "%.4f", rw->err_disp);
        mr_csv_num(csv, "%.4f", rw->cons_world);
        mr_csv_num(csv, "%.4f", rw->cons_pixel);
        mr_csv_num(csv, "%.4f", rw->cons_world0);
        mr_csv_num(csv, "%.4f", rw->cons_pixel0);
        mr_csv_num(csv, "%.3f", rw->shared);
        mr_csv_end_row(csv);
    }
    mr_path_join(p->out_dir, "bench_multiview.csv", path, sizeof path);
    bool ok = mr_csv_save(csv, path, err);
    mr_csv_destroy(&csv);
    if (!ok || !(csv = mr_csv_create(err))) return false;
    mr_csv_header(csv, "band,width,height,ms_frame,column_error_mean_px,column_error_max_px,ao_rmse_display");
    for (int b = 0; b < 3; b++) {
        mr_csv_int(csv, k_bands[b]);
        mr_csv_int(csv, p->view_w);
        mr_csv_int(csv, p->view_h);
        mr_csv_num(csv, "%.2f", m->band_ms[b]);
        mr_csv_num(csv, "%.4f", m->band_err_mean[b]);
        mr_csv_num(csv, "%.4f", m->band_err_max[b]);
        mr_csv_num(csv, "%.4f", m->band_ao[b]);
        mr_csv_end_row(csv);
    }
    mr_path_join(p->out_dir, "bench_multiview_display.csv", path, sizeof path);
    ok = mr_csv_save(csv, path, err);
    mr_csv_destroy(&csv);
    if (!ok || !(csv = mr_csv_create(err))) return false;
    mr_csv_header(csv, "scene,triangles,width,height,ms_no_ssao,ms_ssao,ms_difference");
    for (int s = 0; s < 3; s++) {
        mr_csv_quoted(csv, k_table_scenes[s]);
        mr_csv_int(csv, (long long)m->t_tris[s]);
        mr_csv_int(csv, p->table_w);
        mr_csv_int(csv, p->table_h);
        mr_csv_num(csv, "%.2f", m->t_no[s]);
        mr_csv_num(csv, "%.2f", m->t_ao[s]);
        mr_csv_num(csv, "%.2f", m->t_ao[s] - m->t_no[s]);
        mr_csv_end_row(csv);
    }
    mr_path_join(p->out_dir, "bench_multiview_table1.csv", path, sizeof path);
    ok = mr_csv_save(csv, path, err);
    mr_csv_destroy(&csv);
    return ok;
}

/* bench_multiview.svg: ms per view against the number of views, both ways. */
static bool mv_write_plot(const mv_run *m, mr_error *err) {
    double xs[2][4], ys[2][4];
    int cnt[2] = {0, 0};
    for (int i = 0; i < m->nrows; i++) {
        int k = strcmp(m->rows[i].mode, "budget") == 0 ? 0 : 1;
        xs[k][cnt[k]] = m->rows[i].views;
        ys[k][cnt[k]] = m->rows[i].ms_view;
        cnt[k]++;
    }
    char s0[96], s1[96], path[4096];
    snprintf(s0, sizeof s0, "total %dx%d px", m->p.budget_w, m->p.budget_h);
    snprintf(s1, sizeof s1, "%dx%d px per view", m->p.view_w, m->p.view_h);
    mr_plot_series ser[2] = {{.name = s0, .x = xs[0], .y = ys[0], .count = cnt[0]},
                             {.name = s1, .x = xs[1], .y = ys[1], .count = cnt[1], .mark = MR_PLOT_MARK_SQUARE}};
    mr_plot_params pp = {.title = "mrcheck bench multiview: ms per view (median, crytek AO, llvmpipe)",
                         .xlabel = "views", .ylabel = "ms per view", .log_x = true, .log_y = true};
    mr_path_join(m->p.out_dir, "bench_multiview.svg", path, sizeof path);
    return mr_plot_write(path, &pp, ser, 2, err);
}

/* bench_multiview.md, the three tables, also printed on p.out. */
static bool mv_write_markdown(const mv_run *m, mr_error *err) {
    const mr_bench_multiview_params *p = &m->p;
    size_t cap = 16384, len = 0;
    char *md = malloc(cap);
    if (!md) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
#define MD(...) do { if (len < cap) len += (size_t)snprintf(md + len, cap - len, __VA_ARGS__); } while (0)
    MD("# mrcheck bench multiview\n\nGPU: %s. Demo hall, crytek AO with a fixed view radius (%.3g units) read from the "
       "positions texture, 35 degree cone, focal plane at %.3g units (where the centre view looks), median of %d runs. "
       "AO error: RMSE against the Embree reference (%d rays) over surface pixels, mean of views 0, N/2 and N-1; "
       "the display column renders the light-field mapping at the same size in 1-column slices. Consistency: RMSE "
       "of view i's AO reprojected into view i+1 through the depth, mean over neighbouring pairs, with the "
       "default blur (what is shown) and without (the noise itself); world = the kernel rotation hashed from the "
       "position in the centre camera's pixel grid (4 px cells), pixel = hashed from the pixel.\n\n",
       mr_gpu_description(p->gfx.gpu), m->radius, m->focal, p->frames, p->rays);
    MD("| mode | views | size | ms/frame | ms/view | AO RMSE pinhole | AO RMSE display | consistency world | "
       "consistency pixel | no blur: world | no blur: pixel |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < m->nrows; i++) {
        const row *rw = &m->rows[i];
        MD("| %s | %d | %dx%d | %.1f | %.2f | %.4f | %.4f | %.4f | %.4f | %.4f | %.4f |\n", rw->mode, rw->views, rw->w,
           rw->h, rw->ms_frame, rw->ms_view, rw->err_pin, rw->err_disp, rw->cons_world, rw->cons_pixel, rw->cons_world0,
           rw->cons_pixel0);
    }
    MD("\n## The display mapping's slices (%dx%d)\n\n| band (columns) | ms/frame | column error mean px | max px | AO "
       "RMSE |\n|---|---|---|---|---|\n",
       p->view_w, p->view_h);
    for (int b = 0; b < 3; b++)
        MD("| %d | %.1f | %.4f | %.3f | %.4f |\n", k_bands[b], m->band_ms[b], m->band_err_mean[b], m->band_err_max[b],
           m->band_ao[b]);
    MD("\n## Doronin et al.'s Table 1 on this machine (%dx%d, one optical module through the display mapping, 4-column "
       "slices; crytek with the positions texture)\n\n| scene | triangles | no SSAO ms | SSAO ms | "
       "difference |\n|---|---|---|---|---|\n",
       p->table_w, p->table_h);
    for (int s = 0; s < 3; s++)
        MD("| %s | %llu | %.1f | %.1f | %.1f |\n", k_table_scenes[s], (unsigned long long)m->t_tris[s], m->t_no[s],
           m->t_ao[s], m->t_ao[s] - m->t_no[s]);
#undef MD
    char path[4096];
    mr_path_join(p->out_dir, "bench_multiview.md", path, sizeof path);
    bool ok = mr_file_write_atomic(path, md, len < cap ? len : cap - 1, err);
    if (ok) BENCH_PRINT(p->out, "%.*s\nwrote %s/bench_multiview{.csv,.svg,.md,_display.csv,_table1.csv}\n", (int)len, md,
                        p->out_dir);
    free(md);
    return ok;
}

/* The shared-work table alone (--shared). */
static bool mv_shared_only(mv_run *m, mr_error *err) {
    mr_synth_params sp = MR_SYNTH_DEFAULTS;
    mr_scene *synth = mr_synth_build(&sp, err);
    bool ok = synth != NULL;
    if (ok) {
        mr_scene *sc[2] = {m->hall.planned, synth};
        const char *nm[2] = {"demo hall (planned)", "synthetic factory"};
        mr_view vs[2] = {m->centre, m->centre};
        vs[1].world_from_camera = mr_synth_viewpoint(&sp, MR_SYNTH_VIEW_AISLE);
        ok = bench_shared(&m->p, sc, nm, vs, err);
    }
    mr_scene_destroy(&synth);
    return ok;
}

bool mr_bench_multiview(const mr_bench_multiview_params *params, mr_error *err) {
    mv_run *m = calloc(1, sizeof *m);
    if (!m) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    mr_bench_multiview_params *p = &m->p;
    *p = (mr_bench_multiview_params){MR_BENCH_MULTIVIEW_DEFAULTS};
    if (params) *p = *params;
    const mr_bench_multiview_params dflt = {MR_BENCH_MULTIVIEW_DEFAULTS};
    if (!p->out_dir) p->out_dir = dflt.out_dir;
    if (p->budget_w <= 0 || p->budget_h <= 0) p->budget_w = dflt.budget_w, p->budget_h = dflt.budget_h;
    if (p->view_w <= 0 || p->view_h <= 0) p->view_w = dflt.view_w, p->view_h = dflt.view_h;
    if (p->table_w <= 0 || p->table_h <= 0) p->table_w = dflt.table_w, p->table_h = dflt.table_h;
    if (p->frames <= 0) p->frames = dflt.frames;
    if (p->rays <= 0) p->rays = dflt.rays;
    m->r = p->gfx.renderer;
    bool ok = bench_gpu_check(&p->gfx, "bench multiview", err) && mr_mkdirs(p->out_dir, err) &&
              mr_demo_build_tagged(NULL, 0, &m->hall, err);
    if (ok) {
        m->centre = p->view ? *p->view : mr_demo_view(0);
        memset(m->centre.camera.dist, 0, sizeof m->centre.camera.dist);
    }
    if (ok && p->shared_only) {
        ok = mv_shared_only(m, err);
    } else if (ok) {
        ok = mv_setup(m, err);
        int nviews = p->quick ? 2 : 4;
        for (int mode = 0; ok && mode < 2; mode++)
            for (int k = 0; ok && k < nviews; k++) ok = mv_rig_row(m, mode, k_views[k], &m->rows[m->nrows++], err);
        for (int b = 0; ok && b < 3; b++) ok = mv_band(m, b, err);
        mr_eval_gt_destroy(&m->gt);
        mr_renderer_set_scene(m->r, NULL, NULL);
        ok = ok && mv_table1(m, err) && mv_write_csvs(m, err) && mv_write_plot(m, err) && mv_write_markdown(m, err);
    }
    mr_eval_gt_destroy(&m->gt);
    mr_demo_free(&m->hall);
    free(m);
    return ok;
}
