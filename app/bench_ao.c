/* mrcheck bench ao: ambient occlusion, error against run time.
 *
 * Every method runs over a grid of sample counts (8..64), full and half
 * resolution, corner masking off and on, on the reported views; each row of
 * the CSV has the GPU time of the AO passes (timer queries, median of N
 * frames) and RMSE, SSIM and signed bias against two ray-traced references
 * (Embree): a fixed radius R in scene units, and a radius that grows with
 * depth exactly like scheer's (the reference a depth-scaled method aims at).
 * Free parameters (radius, strength, bias, and scheer's attenuation c) are
 * tuned once per method for the lowest RMSE on a tuning view that is not
 * reported, then frozen. Each method runs twice: with its radius tuned, and
 * with its radius at the reference's own (R, or the depth-scaled fraction
 * of the height), only strength / bias / c tuned, so a method cannot win by
 * choosing a radius the reference does not use. Scheer & Keutel's three
 * renderings: D1 = no AO (AO = 1; the AO maps compared here do not depend
 * on the shading model), D2 = scheer with its depth-scaled radius (tuned,
 * and paper-pure: no cosine bias, whole-ball uniform kernel, c = 1, default
 * strength, the reference's radius, nothing tuned), D3 = "standard SSAO
 * with a decreasing size of the sample radius in depth" = crytek
 * (Mittring) with a constant view-space radius; scheer with a constant
 * radius is an extra row (scheer-view), not D3. A second table times the
 * AO pass alone on scenes of very different triangle counts. Measurements
 * only: nothing here passes or fails. */
#include "app.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_VIEWS 16

/* The methods raced. role: Scheer & Keutel's rendering it stands for, or
 * "-". radius: TUNE_RADIUS (tuned with the rest), REF_RADIUS (the
 * reference's own; the rest tuned) or PAPER (the reference's radius and
 * the paper's parameters; nothing tuned). */
enum { TUNE_RADIUS, REF_RADIUS, PAPER };
typedef struct contender {
    const char *label, *role;
    mr_ao_method method;
    mr_ao_radius_mode mode;
    int radius;
    mr_ao_params tuned;
} contender;

static const char *const k_radius_policy[3] = {"tuned", "reference", "reference"};

typedef struct view_data {
    char name[256];
    mr_view view;
    mr_image depth, normal, gt_fixed, gt_screen;
} view_data;

/* Renders `frames` timed frames (plus one warm-up) and returns the median
 * GPU ms of the AO passes; the last frame's AO goes to *ao. */
static bool run_ao(mr_renderer *r, const mr_view *v, const mr_ao_params *ao, int w, int h, int frames, double *ms,
                   mr_image *out_ao, double *masked, mr_error *err) {
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = w;
    fp.height = h;
    fp.timing = frames > 0;
    fp.ao = *ao;
    fp.ao.no_reuse = true;
    fp.ao.want_ao = true;
    double t[64];
    int n = frames < 64 ? frames : 64;
    for (int f = -1; f < (n > 0 ? n : 0); f++) {
        mr_frame_result res;
        if (!mr_render_frame(r, v, &fp, &res, err)) return false;
        double s = 0;
        for (int k = 0; k < res.pass_count; k++)
            if (strncmp(res.passes[k], "ao", 2) == 0) s += res.gpu_ms[k];
        if (f >= 0) t[f] = s;
        if (f == n - 1 || n <= 0) {
            mr_image_free(out_ao);
            *out_ao = res.ao;
            res.ao.data = NULL;
            if (masked) *masked = res.ao_masked_fraction;
        }
        mr_frame_result_free(&res);
    }
    *ms = n > 0 ? mr_median(t, n) : 0; /* untimed runs report 0 ms */
    return true;
}

static bool metrics(const mr_image *ao, const view_data *vd, mr_image_metrics *mf, mr_image_metrics *ms, mr_error *err) {
    return mr_image_compare(ao, &vd->gt_fixed, &vd->depth, mf, err) &&
           mr_image_compare(ao, &vd->gt_screen, &vd->depth, ms, err);
}

/* A wavy terrain of 2 n^2 triangles covering 40 x 40 units, plus 9 boxes of
 * 12 triangles: the same picture at any n, so only the triangle count
 * changes between the scenes of the triangle-count table. */
static mr_scene *terrain_scene(int n, mr_error *err) {
    mr_scene *s = mr_scene_create();
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "terrain%d", n);
    m.material = -1;
    m.vertex_count = (uint32_t)((n + 1) * (n + 1));
    m.index_count = (uint32_t)(6 * n * n);
    m.positions = malloc((size_t)m.vertex_count * 3 * sizeof(float));
    m.indices = malloc((size_t)m.index_count * sizeof(uint32_t));
    if (!m.positions || !m.indices) {
        free(m.positions);
        free(m.indices);
        mr_scene_destroy(&s);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            float *p = m.positions + 3 * (size_t)(j * (n + 1) + i);
            double x = -20 + 40.0 * i / n, z = -20 + 40.0 * j / n;
            p[0] = (float)x;
            p[1] = (float)(0.4 * sin(0.7 * x) * cos(0.5 * z));
            p[2] = (float)z;
        }
    uint32_t *ix = m.indices;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
            *ix++ = a; *ix++ = c; *ix++ = b;
            *ix++ = b; *ix++ = c; *ix++ = d;
        }
    int32_t t = mr_scene_add_mesh(s, &m, err);
    mr_node nd;
    memset(&nd, 0, sizeof nd);
    nd.parent = -1;
    nd.world = mr_m4_identity();
    nd.mesh_first = t;
    nd.mesh_count = 1;
    snprintf(nd.name, sizeof nd.name, "terrain");
    if (t < 0 || mr_scene_add_node(s, &nd) < 0) {
        mr_scene_destroy(&s);
        return NULL;
    }
    mr_scene_update_bounds(s);
    return s;
}

static void fmt_params(char *buf, size_t n, const mr_ao_params *p) {
    snprintf(buf, n, "%s,%g,%g,%g,%g,%g,%s,%g,%g", p->radius_mode == MR_AO_RADIUS_SCREEN ? "screen" : "view", p->radius,
             p->screen_radius, p->strength, p->bias, p->c, mr_ao_kernel_name(p->kernel), p->r_min, p->r_max);
}

/* contender,role,radius_policy,tuned */
static void fmt_contender(char *buf, size_t n, const contender *c) {
    snprintf(buf, n, "%s,%s,%s,%s", c->label, c->role, k_radius_policy[c->radius], c->radius == PAPER ? "no" : "yes");
}

int bench_ao(int argc, char **argv) {
    static const char *cmd = "bench ao";
    app_opt opts[] = {
        {"scene", "FILE", "glTF/GLB or scene config (default: the demo hall as planned)", NULL},
        {"views", "V.json", "a reported view; more view files may follow as plain arguments (default: the demo "
                            "hall's near, mid-hall and far views)", NULL},
        {"tune-view", "V.json", "view the parameters are tuned on, not reported (default: a demo view not reported)", NULL},
        {"size", "WxH", "resolution (default 320x240)", NULL},
        {"frames", "N", "timed frames per configuration, median reported (default 5)", NULL},
        {"rays", "N", "ground-truth rays per pixel (default 256)", NULL},
        {"radius", "R", "ground truth's fixed radius in scene units (default 2% of the scene diagonal)", NULL},
        {"screen-radius", "F", "depth-scaled reference: radius as a fraction of image height at each depth (default 0.05)", NULL},
        {"quick", NULL, "a reduced grid (samples 8 and 32, full resolution only, 2-point tuning)", NULL},
        {"out", "DIR", "output folder (default bench-out)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[MAX_VIEWS];
    int npos = 0;
    bool help;
    if (!app_parse(argc, argv, 3, opts, pos, MAX_VIEWS - 1, &npos,
                   "usage: mrcheck bench ao [--scene S] [--views V1.json [V2.json ...]] [--tune-view T.json] [--size WxH] [--out DIR]",
                   &help))
        return 2;
    if (help) return 0;
    app_log_level(opts);
    int w = 320, h = 240;
    long frames = 5, rays = 256;
    double radius = 0, screen_radius = 0.05;
    if (app_get(opts, "size") && !app_size("size", app_get(opts, "size"), &w, &h)) return 2;
    if (app_get(opts, "frames") && !app_int("frames", app_get(opts, "frames"), 1, 64, &frames)) return 2;
    if (app_get(opts, "rays") && !app_int("rays", app_get(opts, "rays"), 1, 1 << 20, &rays)) return 2;
    if (app_get(opts, "radius") && !app_double("radius", app_get(opts, "radius"), 1e-30, 1e30, &radius)) return 2;
    if (app_get(opts, "screen-radius") && !app_double("screen-radius", app_get(opts, "screen-radius"), 1e-4, 1, &screen_radius))
        return 2;
    bool quick = app_flag(opts, "quick");
    const char *out_dir = app_get(opts, "out") ? app_get(opts, "out") : "bench-out";
    if (npos > 0 && !app_get(opts, "views")) return app_errorf(cmd, "view files given without --views"), 2;

    mr_error err = {0};
    static view_data vd[MAX_VIEWS + 1];
    memset(vd, 0, sizeof vd);
    int nv = 0;
    /* vd[0] is the tuning view. */
    if (app_get(opts, "tune-view")) {
        if (!mr_view_load(app_get(opts, "tune-view"), &vd[0].view, &err)) return app_error(cmd, &err);
        snprintf(vd[0].name, sizeof vd[0].name, "%s", app_get(opts, "tune-view"));
    } else {
        vd[0].view = mr_demo_view(2);
        snprintf(vd[0].name, sizeof vd[0].name, "demo-tune(north wall)");
    }
    if (app_get(opts, "views")) {
        const char *files[MAX_VIEWS];
        files[nv++] = app_get(opts, "views");
        for (int i = 0; i < npos; i++) files[nv++] = pos[i];
        for (int i = 0; i < nv; i++) {
            if (!mr_view_load(files[i], &vd[i + 1].view, &err)) return app_error(cmd, &err);
            snprintf(vd[i + 1].name, sizeof vd[i + 1].name, "%s", files[i]);
        }
    } else {
        static const int idx[3] = {0, 1, 4};
        static const char *const names[3] = {"demo-near(partition)", "demo-mid(down the hall)", "demo-far(overview)"};
        for (nv = 0; nv < 3; nv++) {
            vd[nv + 1].view = mr_demo_view(idx[nv]);
            snprintf(vd[nv + 1].name, sizeof vd[nv + 1].name, "%s", names[nv]);
        }
    }
    mr_scene *scene = NULL;
    mr_demo_hall hall;
    memset(&hall, 0, sizeof hall);
    if (app_get(opts, "scene")) {
        if (!(scene = mr_scene_load(app_get(opts, "scene"), NULL, &err))) return app_error(cmd, &err);
    } else {
        if (!mr_demo_build_tagged(NULL, 0, &hall, &err)) return app_error(cmd, &err);
        scene = hall.planned;
    }
    if (!(radius > 0)) {
        double d2 = 0;
        for (int i = 0; i < 3; i++) d2 += (scene->bounds_max[i] - scene->bounds_min[i]) * (scene->bounds_max[i] - scene->bounds_min[i]);
        radius = d2 > 0 ? 0.02 * sqrt(d2) : 1;
    }

    app_gfx gfx = {0};
    mr_eval_gt *gt = NULL;
    FILE *csv = NULL;
    int rc = 0;
    bool ok = mr_mkdirs(out_dir, &err) && app_gfx_open(&gfx, &err) && mr_renderer_set_scene(gfx.renderer, scene, &err) &&
              (gt = mr_eval_gt_create(scene, false, &err));
    char path[4096];
    double t0 = mr_time_now();
    /* 1. G-buffer and both references for every view. */
    for (int i = 0; ok && i <= nv; i++) {
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.width = w;
        fp.height = h;
        fp.want_depth = fp.want_normals = true;
        mr_frame_result res;
        ok = mr_render_frame(gfx.renderer, &vd[i].view, &fp, &res, &err);
        if (!ok) break;
        vd[i].depth = res.depth;
        vd[i].normal = res.normal;
        res.depth.data = res.normal.data = NULL;
        mr_frame_result_free(&res);
        mr_gt_params gp = MR_GT_DEFAULTS;
        gp.rays = (int)rays;
        gp.radius = radius;
        ok = mr_eval_ao_groundtruth(gt, &vd[i].view, &vd[i].depth, &vd[i].normal, &gp, &vd[i].gt_fixed, &err);
        gp.radius_mode = MR_AO_RADIUS_SCREEN;
        gp.screen_radius = screen_radius;
        ok = ok && mr_eval_ao_groundtruth(gt, &vd[i].view, &vd[i].depth, &vd[i].normal, &gp, &vd[i].gt_screen, &err);
    }
    double t_gt = mr_time_now() - t0;
    if (ok) printf("bench ao: %s, %dx%d, %llu triangles; ground truth (%ld rays, R = %g, screen %g) for %d views in %.1f s\n",
                   mr_gpu_description(gfx.gpu), w, h, (unsigned long long)mr_scene_triangle_count(scene), rays, radius,
                   screen_radius, nv + 1, t_gt);

    /* 2. Tuning on vd[0]: radius (unless fixed at the reference's), strength,
     * bias and (scheer) c for the lowest RMSE against the reference of the
     * method's own radius mode. */
    contender cs[] = {
        {"scheer", "D2", MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, TUNE_RADIUS, {0}},
        {"scheer@R", "D2", MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, REF_RADIUS, {0}},
        {"scheer-paper", "D2", MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, PAPER, {0}},
        {"crytek", "D3", MR_AO_CRYTEK, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
        {"crytek@R", "D3", MR_AO_CRYTEK, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
        {"scheer-view", "-", MR_AO_SCHEER, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
        {"scheer-view@R", "-", MR_AO_SCHEER, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
        {"filion", "-", MR_AO_FILION, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
        {"filion@R", "-", MR_AO_FILION, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
        {"hbao", "-", MR_AO_HBAO, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
        {"hbao@R", "-", MR_AO_HBAO, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
        {"alchemy", "-", MR_AO_ALCHEMY, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
        {"alchemy@R", "-", MR_AO_ALCHEMY, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    };
    const int nc = (int)(sizeof cs / sizeof cs[0]);
    const double rscale[] = {1, 0.5, 2, 0.25}, strengths[] = {0.5, 1, 1.5, 2, 3, 4, 6, 8, 12}, biases[] = {0.02, 0.1},
                 cvals[] = {1, 0.25, 4};
    const int nr = quick ? 3 : 4, ns = quick ? 2 : 9, nb = quick ? 1 : 2;
    const double qs[] = {1, 3};
    mr_image ao = {0};
    mr_path_join(out_dir, "bench_ao_tuning.csv", path, sizeof path);
    FILE *tune = ok ? fopen(path, "w") : NULL;
    if (ok && !tune) ok = mr_fail(&err, MR_ERR_IO, "cannot write %s", path);
    if (tune)
        fprintf(tune, "# rmse_own_reference: RMSE on the tuning view against the reference of the method's radius mode\n"
                      "contender,role,radius_policy,tuned,radius_mode,radius,screen_radius,strength,bias,c,kernel,r_min,r_max,"
                      "rmse_own_reference\n");
    for (int c = 0; ok && c < nc; c++) {
        double best = INFINITY;
        bool paper = cs[c].radius == PAPER;
        /* The radius grid's first entry is the reference's own radius. */
        int na = cs[c].radius == TUNE_RADIUS ? nr : 1, nbb = paper ? 1 : ns, nk = paper ? 1 : nb,
            ncv = cs[c].method == MR_AO_SCHEER && !paper ? 3 : 1;
        for (int a = 0; ok && a < na; a++)
            for (int b = 0; ok && b < nbb; b++)
                for (int k = 0; ok && k < nk; k++)
                for (int cv = 0; ok && cv < ncv; cv++) {
                    mr_ao_params p = MR_AO_DEFAULTS;
                    p.method = cs[c].method;
                    p.radius_mode = cs[c].mode;
                    p.radius = radius * rscale[a];
                    p.screen_radius = screen_radius * rscale[a];
                    p.strength = (float)(quick ? qs[b] : strengths[b]);
                    p.bias = (float)biases[k];
                    p.c = (float)cvals[cv];
                    if (paper) {
                        /* Scheer & Keutel as printed: cosine weight without a
                         * bias, offsets uniform in the ball (the hemisphere
                         * after the flip), c = 1, the method's default strength. */
                        p.strength = 0;
                        p.bias = 0;
                        p.c = 1;
                        p.kernel = MR_AO_KERNEL_UNIFORM;
                        p.r_min = 0;
                        p.r_max = 1;
                    }
                    double ms;
                    mr_image_metrics m;
                    ok = run_ao(gfx.renderer, &vd[0].view, &p, w, h, 0, &ms, &ao, NULL, &err) &&
                         mr_image_compare(&ao, cs[c].mode == MR_AO_RADIUS_SCREEN ? &vd[0].gt_screen : &vd[0].gt_fixed,
                                          &vd[0].depth, &m, &err);
                    if (!ok) break;
                    char pb[256], pc[128];
                    fmt_params(pb, sizeof pb, &p);
                    fmt_contender(pc, sizeof pc, &cs[c]);
                    fprintf(tune, "%s,%s,%.5f\n", pc, pb, m.rmse);
                    if (m.rmse < best) {
                        best = m.rmse;
                        cs[c].tuned = p;
                    }
                }
        if (ok && app_flag(opts, "verbose"))
            printf("  tuned %-14s radius %g screen %g strength %g bias %g c %g: RMSE %.4f\n", cs[c].label,
                   cs[c].tuned.radius, cs[c].tuned.screen_radius, cs[c].tuned.strength, cs[c].tuned.bias, cs[c].tuned.c, best);
    }
    if (tune) fclose(tune);

    /* 3. The grid on the reported views. */
    const int samples_full[] = {8, 16, 32, 64}, samples_quick[] = {8, 32};
    const int *samples = quick ? samples_quick : samples_full;
    const int nsamp = quick ? 2 : 4, nres = quick ? 1 : 2;
    enum { MAXC = 16, MAXS = 4 };
    /* Means over views for the plot and the summary: [contender][samples][res][mask]. */
    static double agg_ms[MAXC][MAXS][2][2], agg_rf[MAXC][MAXS][2][2], agg_rs[MAXC][MAXS][2][2], agg_sf[MAXC][MAXS][2][2],
        agg_ss[MAXC][MAXS][2][2], agg_bf[MAXC][MAXS][2][2], agg_bs[MAXC][MAXS][2][2], agg_mf[MAXC][MAXS][2][2];
    memset(agg_ms, 0, sizeof agg_ms); memset(agg_rf, 0, sizeof agg_rf); memset(agg_rs, 0, sizeof agg_rs);
    memset(agg_sf, 0, sizeof agg_sf); memset(agg_ss, 0, sizeof agg_ss); memset(agg_bf, 0, sizeof agg_bf);
    memset(agg_bs, 0, sizeof agg_bs); memset(agg_mf, 0, sizeof agg_mf);
    static double pv_rf[MAX_VIEWS + 1][MAXC + 1], pv_rs[MAX_VIEWS + 1][MAXC + 1]; /* per view, reported samples, full, mask off */
    double none_rf = 0, none_rs = 0, none_sf = 0, none_ss = 0, none_bf = 0, none_bs = 0;
    mr_image *montage[MAX_VIEWS * 10];
    bool owned[MAX_VIEWS * 10] = {false}; /* montage tiles this function allocated */
    int nmont = 0;
    mr_path_join(out_dir, "bench_ao.csv", path, sizeof path);
    if (ok && !(csv = fopen(path, "w"))) ok = mr_fail(&err, MR_ERR_IO, "cannot write %s", path);
    if (csv)
        fprintf(csv, "# role: Scheer & Keutel's D1 (no AO), D2 (scheer, depth-scaled radius), D3 (standard SSAO = crytek, "
                     "constant radius) or -; radius_policy: tuned, or the reference's own radius; tuned: no = the paper's "
                     "parameters; strength <= 0: the method's default; *_fixed: against ray-traced AO with fixed R, *_screen: with "
                     "the depth-scaled R\n"
                     "view,contender,role,radius_policy,tuned,radius_mode,radius,screen_radius,strength,bias,c,kernel,r_min,"
                     "r_max,samples,resolution,mask,width,height,"
                     "gpu_ms_median,frames,rmse_fixed,ssim_fixed,bias_fixed,rmse_screen,ssim_screen,bias_screen,masked_fraction\n");
    for (int v = 1; ok && v <= nv; v++) {
        /* Plain shading (D1): AO = 1 everywhere. */
        mr_ao_params p0 = MR_AO_DEFAULTS;
        double ms = 0;
        mr_image_metrics mf, msr;
        ok = run_ao(gfx.renderer, &vd[v].view, &p0, w, h, 0, &ms, &ao, NULL, &err) && metrics(&ao, &vd[v], &mf, &msr, &err);
        if (!ok) break;
        fprintf(csv, "\"%s\",none,D1,-,no,,,,,,,,,,0,full,off,%d,%d,0,0,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,-1\n", vd[v].name, w, h, mf.rmse,
                mf.ssim, mf.bias, msr.rmse, msr.ssim, msr.bias);
        pv_rf[v][0] = mf.rmse;
        pv_rs[v][0] = msr.rmse;
        none_rf += mf.rmse / nv; none_rs += msr.rmse / nv; none_sf += mf.ssim / nv; none_ss += msr.ssim / nv;
        none_bf += mf.bias / nv; none_bs += msr.bias / nv;
        montage[nmont++] = &vd[v].gt_fixed;
        montage[nmont++] = &vd[v].gt_screen;
        for (int c = 0; ok && c < nc; c++)
            for (int si = 0; ok && si < nsamp; si++)
                for (int res = 0; ok && res < nres; res++)
                    for (int mk = 0; ok && mk < 2; mk++) {
                        mr_ao_params p = cs[c].tuned;
                        p.samples = samples[si];
                        p.half_res = res == 1;
                        p.mask = mk ? MR_AO_MASK_ON : MR_AO_MASK_OFF;
                        double masked = -1;
                        ok = run_ao(gfx.renderer, &vd[v].view, &p, w, h, (int)frames, &ms, &ao, &masked, &err) &&
                             metrics(&ao, &vd[v], &mf, &msr, &err);
                        if (!ok) break;
                        char pb[256], pc[128];
                        fmt_params(pb, sizeof pb, &p);
                        fmt_contender(pc, sizeof pc, &cs[c]);
                        fprintf(csv, "\"%s\",%s,%s,%d,%s,%s,%d,%d,%.4f,%ld,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,%.4f\n", vd[v].name,
                                pc, pb, p.samples, res ? "half" : "full", mk ? "on" : "off", w, h, ms, frames, mf.rmse,
                                mf.ssim, mf.bias, msr.rmse, msr.ssim, msr.bias, masked);
                        agg_ms[c][si][res][mk] += ms / nv;
                        agg_rf[c][si][res][mk] += mf.rmse / nv;
                        agg_rs[c][si][res][mk] += msr.rmse / nv;
                        agg_sf[c][si][res][mk] += mf.ssim / nv;
                        agg_ss[c][si][res][mk] += msr.ssim / nv;
                        agg_bf[c][si][res][mk] += mf.bias / nv;
                        agg_bs[c][si][res][mk] += msr.bias / nv;
                        agg_mf[c][si][res][mk] += masked / nv;
                        if (si == (quick ? 0 : 1) && res == 0 && mk == 0) {
                            pv_rf[v][c + 1] = mf.rmse;
                            pv_rs[v][c + 1] = msr.rmse;
                        }
                        if (si == (quick ? 0 : 1) && res == 0 && mk == 0 && nmont < MAX_VIEWS * 10) {
                            mr_image *keep = malloc(sizeof *keep);
                            if (keep) {
                                *keep = ao;
                                ao.data = NULL;
                                owned[nmont] = true;
                                montage[nmont++] = keep;
                            }
                        }
                    }
        if (ok && !app_flag(opts, "quiet")) fprintf(stderr, "bench ao: view %d/%d done (%.0f s)\n", v, nv, mr_time_now() - t0);
    }
    if (csv) fclose(csv);

    /* 4. AO cost against triangle count (scheer, 16 samples, full resolution). */
    FILE *tcsv = NULL;
    mr_path_join(out_dir, "bench_ao_triangles.csv", path, sizeof path);
    if (ok && !(tcsv = fopen(path, "w"))) ok = mr_fail(&err, MR_ERR_IO, "cannot write %s", path);
    if (tcsv) fprintf(tcsv, "scene,triangles,ao_gpu_ms_median,gbuffer_gpu_ms_median,width,height,frames\n");
    const int grid_n[] = {8, 100, 1000};
    double tri_ms[4], tri_gb[4];
    uint64_t tri_count[4];
    int ntri = 0;
    for (int gi = 0; ok && gi < 4; gi++) {
        mr_scene *ts = gi < 3 ? terrain_scene(grid_n[gi], &err) : scene;
        if (!ts) { ok = false; break; }
        mr_view tv;
        tv.camera = mr_demo_camera();
        tv.world_from_camera = mr_m4_look_at_cv(mr_v3(-15, 6, -15), mr_v3(5, 0, 5), mr_v3(0, 1, 0));
        if (gi == 3) tv = vd[1].view;
        ok = mr_renderer_set_scene(gfx.renderer, ts, &err);
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.width = w;
        fp.height = h;
        fp.timing = true;
        fp.ao = cs[0].tuned;
        fp.ao.samples = 16;
        fp.ao.no_reuse = true;
        double aoms[64], gbms[64];
        int n = (int)frames;
        for (int f = -1; ok && f < n; f++) {
            mr_frame_result res;
            ok = mr_render_frame(gfx.renderer, &tv, &fp, &res, &err);
            if (!ok) break;
            double a = 0, g = 0;
            for (int k = 0; k < res.pass_count; k++) {
                if (strncmp(res.passes[k], "ao", 2) == 0) a += res.gpu_ms[k];
                if (strcmp(res.passes[k], "gbuffer") == 0) g += res.gpu_ms[k];
            }
            if (f >= 0) { aoms[f] = a; gbms[f] = g; }
            tri_count[ntri] = res.triangles;
            mr_frame_result_free(&res);
        }
        if (ok) {
            tri_ms[ntri] = mr_median(aoms, n);
            tri_gb[ntri] = mr_median(gbms, n);
            fprintf(tcsv, "%s,%llu,%.4f,%.4f,%d,%d,%d\n", gi < 3 ? "terrain" : "scene", (unsigned long long)tri_count[ntri],
                    tri_ms[ntri], tri_gb[ntri], w, h, n);
            ntri++;
        }
        mr_renderer_set_scene(gfx.renderer, NULL, NULL);
        if (gi < 3) mr_scene_destroy(&ts);
    }
    if (tcsv) fclose(tcsv);

    /* 5. Plot, montage, summary. */
    if (ok) {
        for (int ref = 0; ok && ref < 2; ref++) {
            mr_plot_series ser[2 * MAXC];
            static double xs[2 * MAXC][MAXS], ys[2 * MAXC][MAXS];
            static char names[2 * MAXC][64];
            int nser = 0;
            for (int c = 0; c < nc; c++)
                for (int res = 0; res < nres; res++) {
                    for (int si = 0; si < nsamp; si++) {
                        xs[nser][si] = agg_ms[c][si][res][0];
                        ys[nser][si] = ref ? agg_rs[c][si][res][0] : agg_rf[c][si][res][0];
                    }
                    snprintf(names[nser], sizeof names[nser], "%s%s", cs[c].label, res ? " half" : "");
                    ser[nser].name = names[nser];
                    ser[nser].x = xs[nser];
                    ser[nser].y = ys[nser];
                    ser[nser].count = nsamp;
                    nser++;
                }
            char title[256];
            snprintf(title, sizeof title, "AO error vs GPU time, %dx%d, samples %d..%d, mean of %d views; reference: %s", w, h,
                     samples[0], samples[nsamp - 1], nv, ref ? "depth-scaled R" : "fixed R");
            mr_path_join(out_dir, ref ? "bench_ao_screen.svg" : "bench_ao.svg", path, sizeof path);
            ok = mr_plot_svg(path, title, "AO passes, GPU ms (median)", "RMSE against ray-traced AO", ser, nser, true, &err);
        }
        mr_path_join(out_dir, "bench_ao_montage.png", path, sizeof path);
        if (ok) ok = mr_montage_png(path, (const mr_image *const *)montage, nmont, 2 + nc, w, h, &err);
        /* Scheer & Keutel's three renderings, shaded as in the paper (Phong
         * with specular): D1 no AO, D2 scheer, D3 standard SSAO (crytek,
         * constant radius), plus scheer-paper; 16 samples, one row per view. */
        const int shaded_c[3] = {0, 3, 2};
        mr_image shots[MAX_VIEWS * 4];
        const mr_image *tiles[MAX_VIEWS * 4];
        int nshot = 0;
        ok = ok && mr_renderer_set_scene(gfx.renderer, scene, &err); /* step 4 changed it */
        for (int v = 1; ok && v <= nv; v++)
            for (int k = 0; ok && k < 4; k++) {
                mr_frame_params fp = MR_FRAME_DEFAULTS;
                fp.width = w;
                fp.height = h;
                fp.specular = 0.35f;
                if (k > 0) {
                    fp.ao = cs[shaded_c[k - 1]].tuned;
                    fp.ao.samples = 16;
                    fp.ao.no_reuse = true;
                }
                mr_frame_result res;
                ok = mr_render_frame(gfx.renderer, &vd[v].view, &fp, &res, &err);
                if (!ok) break;
                shots[nshot] = res.color;
                res.color.data = NULL;
                tiles[nshot] = &shots[nshot];
                nshot++;
                mr_frame_result_free(&res);
            }
        mr_path_join(out_dir, "bench_ao_shaded.png", path, sizeof path);
        if (ok) ok = mr_montage_png(path, tiles, nshot, 4, w, h, &err);
        for (int i = 0; i < nshot; i++) mr_image_free(&shots[i]);
    }
    if (ok) {
        static char md[65536];
        size_t len = 0;
        len += (size_t)snprintf(md + len, sizeof md - len,
                                "AO at %dx%d, %d samples (%s), mean over %d views; tuned on '%s'\n\n"
                                "D1 = no AO, D2 = scheer (depth-scaled radius), D3 = standard SSAO (crytek, constant "
                                "radius), as Scheer & Keutel name them. `@R`: the radius is the reference's own (R = %g "
                                "units, or %g of the height), only strength / bias / c tuned; `scheer-paper`: the "
                                "paper's parameters (bias 0, whole-ball uniform kernel, c 1, default strength), nothing "
                                "tuned.\n\n"
                                "| method | role | radius | strength | bias | c | kernel | res | mask | GPU ms | RMSE fixed R | SSIM fixed | bias fixed | RMSE depth-scaled R | SSIM d-s | bias d-s | masked |\n"
                                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
                                w, h, samples[quick ? 0 : 1], "GPU ms: median of timer queries", nv, vd[0].name, radius,
                                screen_radius);
        len += (size_t)snprintf(md + len, sizeof md - len, "| none | D1 | - | - | - | - | - | full | off | 0 | %.4f | %.3f | %+.4f | %.4f | %.3f | %+.4f | - |\n",
                                none_rf, none_sf, none_bf, none_rs, none_ss, none_bs);
        int s16 = quick ? 0 : 1;
        for (int c = 0; c < nc; c++)
            for (int res = 0; res < nres; res++)
                for (int mk = 0; mk < 2; mk++) {
                    char rad[64];
                    if (cs[c].mode == MR_AO_RADIUS_SCREEN) snprintf(rad, sizeof rad, "%.3g of height", cs[c].tuned.screen_radius);
                    else snprintf(rad, sizeof rad, "%.3g units", cs[c].tuned.radius);
                    if (cs[c].radius != TUNE_RADIUS) snprintf(rad + strlen(rad), sizeof rad - strlen(rad), " (ref.)");
                    char kern[64], strength[32] = "default";
                    if (cs[c].tuned.strength > 0) snprintf(strength, sizeof strength, "%g", cs[c].tuned.strength);
                    snprintf(kern, sizeof kern, "%s [%g,%g]", mr_ao_kernel_name(cs[c].tuned.kernel), cs[c].tuned.r_min,
                             cs[c].tuned.r_max);
                    char masked[32] = "-";
                    if (mk) snprintf(masked, sizeof masked, "%.3f", agg_mf[c][s16][res][mk]);
                    len += (size_t)snprintf(md + len, sizeof md - len,
                                            "| %s | %s | %s | %s | %g | %g | %s | %s | %s | %.2f | %.4f | %.3f | %+.4f | %.4f | %.3f | %+.4f | %s |\n",
                                            cs[c].label, cs[c].role, rad, strength, cs[c].tuned.bias,
                                            cs[c].tuned.c, kern, res ? "half" : "full",
                                            mk ? "on" : "off", agg_ms[c][s16][res][mk], agg_rf[c][s16][res][mk],
                                            agg_sf[c][s16][res][mk], agg_bf[c][s16][res][mk], agg_rs[c][s16][res][mk],
                                            agg_ss[c][s16][res][mk], agg_bs[c][s16][res][mk], masked);
                }
        len += (size_t)snprintf(md + len, sizeof md - len, "\nRMSE per view (fixed R / depth-scaled R), %d samples, full resolution, mask off:\n\n| view | none |",
                                samples[s16]);
        for (int c = 0; c < nc; c++) len += (size_t)snprintf(md + len, sizeof md - len, " %s |", cs[c].label);
        len += (size_t)snprintf(md + len, sizeof md - len, "\n|---|---|");
        for (int c = 0; c < nc; c++) len += (size_t)snprintf(md + len, sizeof md - len, "---|");
        for (int v = 1; v <= nv; v++) {
            len += (size_t)snprintf(md + len, sizeof md - len, "\n| %s |", vd[v].name);
            for (int c = 0; c <= nc; c++)
                len += (size_t)snprintf(md + len, sizeof md - len, " %.4f / %.4f |", pv_rf[v][c], pv_rs[v][c]);
        }
        len += (size_t)snprintf(md + len, sizeof md - len, "\n");
        len += (size_t)snprintf(md + len, sizeof md - len, "\nAO passes against triangle count (scheer, 16 samples, %dx%d):\n\n"
                                                           "| triangles | AO GPU ms | G-buffer GPU ms |\n|---|---|---|\n", w, h);
        for (int i = 0; i < ntri; i++)
            len += (size_t)snprintf(md + len, sizeof md - len, "| %llu | %.2f | %.2f |\n", (unsigned long long)tri_count[i],
                                    tri_ms[i], tri_gb[i]);
        fputs(md, stdout);
        mr_path_join(out_dir, "bench_ao.md", path, sizeof path);
        ok = mr_file_write_atomic(path, md, len, &err);
        if (ok) printf("\nwrote %s/bench_ao.csv, bench_ao_tuning.csv, bench_ao_triangles.csv, bench_ao.svg, bench_ao_screen.svg, "
                       "bench_ao_montage.png (rows: views; columns: reference fixed R, reference depth-scaled R, then "
                       "%d methods at %d samples), bench_ao_shaded.png (Phong-shaded D1, D2, D3, scheer-paper), "
                       "bench_ao.md in %.0f s\n", out_dir, nc, samples[quick ? 0 : 1], mr_time_now() - t0);
    }
    if (!ok) rc = app_error(cmd, &err);
    for (int i = 0; i < nmont; i++)
        if (owned[i]) {
            mr_image_free(montage[i]);
            free(montage[i]);
        }
    for (int i = 0; i <= nv; i++) {
        mr_image_free(&vd[i].depth);
        mr_image_free(&vd[i].normal);
        mr_image_free(&vd[i].gt_fixed);
        mr_image_free(&vd[i].gt_screen);
    }
    mr_image_free(&ao);
    mr_eval_gt_destroy(&gt);
    app_gfx_close(&gfx);
    if (hall.planned) mr_demo_free(&hall);
    else mr_scene_destroy(&scene);
    return rc;
}
