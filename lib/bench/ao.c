/* mrcheck bench ao (mr_bench_ao): ambient occlusion, error against run time.
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
 * and paper-pure: no cosine bias, whole-ball uniform kernel, c = 1,
 * strength 1, the reference's radius, nothing tuned), D3 = "standard SSAO
 * with a decreasing size of the sample radius in depth" = crytek
 * (Mittring) with a constant view-space radius; scheer with a constant
 * radius is an extra row (scheer-view), not D3. A second table times the
 * AO pass alone on scenes of very different triangle counts. Measurements
 * only: nothing here passes or fails. */

#include "bench_internal.h"
#include "mr_session.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_VIEWS MR_BENCH_AO_MAX_VIEWS
enum { MAXC = 32, MAXS = 4 };
enum { SEQ_METHODS = 3, SEQ_CFG = 4, COST_METHODS = 3 }; /* the moving sequence, the cost steps */

/* The methods raced. role: Scheer & Keutel's rendering it stands for, or
 * "-", set from mr_ao_sk_role at the start (NULL here). radius: TUNE_RADIUS (tuned with the rest), REF_RADIUS (the
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

static const contender k_contenders[] = {
    {"scheer", NULL, MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, TUNE_RADIUS, {0}},
    {"scheer@R", NULL, MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, REF_RADIUS, {0}},
    {"scheer-paper", NULL, MR_AO_SCHEER, MR_AO_RADIUS_SCREEN, PAPER, {0}},
    {"crytek", NULL, MR_AO_CRYTEK, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"crytek@R", NULL, MR_AO_CRYTEK, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    {"scheer-view", NULL, MR_AO_SCHEER, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"scheer-view@R", NULL, MR_AO_SCHEER, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    {"filion", NULL, MR_AO_FILION, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"filion@R", NULL, MR_AO_FILION, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    {"hbao", NULL, MR_AO_HBAO, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"hbao@R", NULL, MR_AO_HBAO, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    {"alchemy", NULL, MR_AO_ALCHEMY, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"alchemy@R", NULL, MR_AO_ALCHEMY, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    /* The modern integrators, with the depth-scaled and the fixed radius */
    {"gtao", NULL, MR_AO_GTAO, MR_AO_RADIUS_SCREEN, TUNE_RADIUS, {0}},
    {"gtao@R", NULL, MR_AO_GTAO, MR_AO_RADIUS_SCREEN, REF_RADIUS, {0}},
    {"gtao-view", NULL, MR_AO_GTAO, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"gtao-view@R", NULL, MR_AO_GTAO, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    {"bitmask", NULL, MR_AO_BITMASK, MR_AO_RADIUS_SCREEN, TUNE_RADIUS, {0}},
    {"bitmask@R", NULL, MR_AO_BITMASK, MR_AO_RADIUS_SCREEN, REF_RADIUS, {0}},
    {"bitmask-view", NULL, MR_AO_BITMASK, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"bitmask-view@R", NULL, MR_AO_BITMASK, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    {"scheer-gt", NULL, MR_AO_SCHEER_GT, MR_AO_RADIUS_SCREEN, TUNE_RADIUS, {0}},
    {"scheer-gt@R", NULL, MR_AO_SCHEER_GT, MR_AO_RADIUS_SCREEN, REF_RADIUS, {0}},
    {"scheer-gt-view", NULL, MR_AO_SCHEER_GT, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"scheer-gt-view@R", NULL, MR_AO_SCHEER_GT, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
    /* Scheer's attenuation in the bitmask's sector weights */
    {"scheer-bm", NULL, MR_AO_SCHEER_BM, MR_AO_RADIUS_SCREEN, TUNE_RADIUS, {0}},
    {"scheer-bm@R", NULL, MR_AO_SCHEER_BM, MR_AO_RADIUS_SCREEN, REF_RADIUS, {0}},
    {"scheer-bm-view", NULL, MR_AO_SCHEER_BM, MR_AO_RADIUS_VIEW, TUNE_RADIUS, {0}},
    {"scheer-bm-view@R", NULL, MR_AO_SCHEER_BM, MR_AO_RADIUS_VIEW, REF_RADIUS, {0}},
};
#define NC (int)(sizeof k_contenders / sizeof k_contenders[0])
_Static_assert(NC <= MAXC, "MAXC bounds the contenders");

typedef struct view_data {
    char name[256];
    mr_view view;
    mr_image depth, normal, gt_fixed, gt_screen;
} view_data;

/* Means over views for the plot and the summary: [contender][samples][res][mask]. */
typedef double agg_table[MAXC][MAXS][2][2];

/* One run of the bench: the settings, the scene, the references per view,
 * the tuned contenders and what the steps measured. vd[0] is the tuning
 * view, vd[1..nv] the reported ones. */
typedef struct ao_bench {
    mr_bench_ao_params p;
    int w, h;
    double radius, screen_radius;
    const int *samples;
    int nsamp, nres, s16; /* s16: the reported sample count's index */
    mr_scene *scene;
    mr_demo_hall hall;
    mr_bench_gpu gfx; /* the caller's */
    mr_eval_gt *gt;
    double t0;
    int nv;
    view_data vd[MAX_VIEWS + 1];
    contender cs[NC];
    agg_table agg_ms, agg_rf, agg_rs, agg_sf, agg_ss, agg_bf, agg_bs, agg_mf;
    agg_table agg_ret; /* mask on: darkening kept, sum(1 - AO) masked / unmasked (Park & Baek promise 1) */
    agg_table agg_sync, agg_floor, agg_ratio; /* glFinish-timed ms, the fetch floor, their ratio */
    double pv_rf[MAX_VIEWS + 1][MAXC + 1], pv_rs[MAX_VIEWS + 1][MAXC + 1]; /* per view, reported samples, full, mask off */
    double none_rf, none_rs, none_sf, none_ss, none_bf, none_bs;
    mr_image *montage[MAX_VIEWS * 10];
    bool owned[MAX_VIEWS * 10]; /* montage tiles this run allocated */
    int nmont;
    double tri_ms[4], tri_gb[4];
    uint64_t tri_count[4];
    int ntri;
    mr_image ao; /* scratch: the last AO map */
    /* The moving sequence (step 6b) */
    int seq_frames;
    char seq_name[1100];
    double seq_rmse[SEQ_METHODS][SEQ_CFG][2], seq_ms[SEQ_METHODS][SEQ_CFG]; /* {all frames, second half}, median ms */
    /* The cost steps (step 6c): [method][full, +mips, half, half+mips] */
    /* [4] full + deinterleave, [5] half + deinterleave */
    double cost_ratio[COST_METHODS][6], cost_sync[COST_METHODS][6], cost_floor[COST_METHODS][6], cost_rmse[COST_METHODS][6];
    int cost_rounds;
    char cost_view[256], loadavg[128];
    double deint_full, deint_sub; /* the fetch floor of one full pass, of 16 deinterleaved sub-image passes */
} ao_bench;

/* Renders `frames` timed frames (plus one warm-up) and returns the median
 * GPU ms of the AO passes (0 untimed); the last frame's AO goes to *ao. */
static bool run_ao(mr_renderer *r, const mr_view *v, const mr_ao_params *ao, int w, int h, int frames, double *ms,
                   double *sync_ms, mr_image *out_ao, double *masked, mr_error *err) {
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = w;
    fp.height = h;
    fp.timing = frames > 0;
    fp.timing_sync = true; /* each pass's whole cost, glFinish before and after */
    fp.ao = *ao;
    fp.ao.no_reuse = true;
    fp.ao.want_ao = true;
    double t[64], ts[64];
    int n = frames < 64 ? frames : 64;
    for (int f = -1; f < (n > 0 ? n : 0); f++) {
        mr_frame_result res;
        if (!mr_render_frame(r, v, &fp, &res, err)) return false;
        double s = 0, sc = 0;
        for (int k = 0; k < res.pass_count; k++)
            if (strncmp(res.passes[k], "ao", 2) == 0) {
                s += res.gpu_ms[k];
                sc += res.cpu_ms[k];
            }
        if (f >= 0) t[f] = s;
        if (f >= 0) ts[f] = sc;
        if (f == n - 1 || n <= 0) {
            mr_image_free(out_ao);
            *out_ao = res.ao;
            res.ao.data = NULL;
            if (masked) *masked = res.ao_masked_fraction;
        }
        mr_frame_result_free(&res);
    }
    *ms = n > 0 ? mr_median(t, n) : 0; /* untimed runs report 0 ms */
    if (sync_ms) *sync_ms = n > 0 ? mr_median(ts, n) : 0;
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

/* contender,role,radius_policy,tuned */
static void csv_contender(mr_csv *csv, const contender *c) {
    mr_csv_text(csv, c->label);
    mr_csv_text(csv, c->role);
    mr_csv_text(csv, k_radius_policy[c->radius]);
    mr_csv_text(csv, c->radius == PAPER ? "no" : "yes");
}

/* radius_mode,radius,screen_radius,strength,bias,c,kernel,r_min,r_max */
static void csv_params(mr_csv *csv, const mr_ao_params *p) {
    mr_csv_text(csv, p->radius_mode == MR_AO_RADIUS_SCREEN ? "screen" : "view");
    const double v[5] = {p->radius, p->screen_radius, p->strength, p->bias, p->c};
    for (int k = 0; k < 5; k++) mr_csv_num(csv, "%g", v[k]);
    mr_csv_text(csv, mr_ao_kernel_name(p->kernel));
    mr_csv_num(csv, "%g", p->r_min);
    mr_csv_num(csv, "%g", p->r_max);
}

static bool save_csv(mr_csv *csv, const char *dir, const char *name, mr_error *err) {
    char path[4096];
    mr_path_join(dir, name, path, sizeof path);
    bool ok = mr_csv_save(csv, path, err);
    mr_csv_destroy(&csv);
    return ok;
}

/* Step 0: the tuning view vd[0], the reported views, the scene and the
 * reference's fixed radius (2% of the scene diagonal unless given). */
static bool ao_setup(ao_bench *b, mr_error *err) {
    const mr_bench_ao_params *p = &b->p;
    if (p->view_count > MAX_VIEWS) return mr_fail(err, MR_ERR_INVALID, "bench ao: at most %d views", MAX_VIEWS);
    if (p->tune_view) {
        b->vd[0].view = *p->tune_view;
        snprintf(b->vd[0].name, sizeof b->vd[0].name, "%s", p->tune_name ? p->tune_name : "tune-view");
    } else {
        b->vd[0].view = mr_demo_view(2);
        snprintf(b->vd[0].name, sizeof b->vd[0].name, "demo-tune(north wall)");
    }
    if (p->view_count > 0) {
        for (b->nv = 0; b->nv < p->view_count; b->nv++) {
            b->vd[b->nv + 1].view = p->views[b->nv];
            snprintf(b->vd[b->nv + 1].name, sizeof b->vd[0].name, "%s",
                     p->view_names && p->view_names[b->nv] ? p->view_names[b->nv] : "view");
        }
    } else {
        static const int idx[3] = {0, 1, 4};
        static const char *const names[3] = {"demo-near(partition)", "demo-mid(down the hall)", "demo-far(overview)"};
        for (b->nv = 0; b->nv < 3; b->nv++) {
            b->vd[b->nv + 1].view = mr_demo_view(idx[b->nv]);
            snprintf(b->vd[b->nv + 1].name, sizeof b->vd[0].name, "%s", names[b->nv]);
        }
    }
    if (p->scene) {
        if (!(b->scene = mr_scene_load(p->scene, NULL, err))) return false;
    } else {
        if (!mr_demo_build_tagged(NULL, 0, &b->hall, err)) return false;
        b->scene = b->hall.planned;
    }
    if (!(b->radius > 0)) b->radius = mr_ao_default_radius(b->scene);
    return mr_mkdirs(p->out_dir, err) &&
           mr_renderer_set_scene(b->gfx.renderer, b->scene, err) && (b->gt = mr_eval_gt_create(b->scene, false, err));
}

/* Step 1: G-buffer and both ray-traced references for every view. */
static bool ao_references(ao_bench *b, mr_error *err) {
    bool ok = true;
    for (int i = 0; ok && i <= b->nv; i++) {
        view_data *vd = &b->vd[i];
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.width = b->w;
        fp.height = b->h;
        fp.want_depth = fp.want_normals = true;
        mr_frame_result res;
        if (!mr_render_frame(b->gfx.renderer, &vd->view, &fp, &res, err)) return false;
        vd->depth = res.depth;
        vd->normal = res.normal;
        res.depth.data = res.normal.data = NULL;
        mr_frame_result_free(&res);
        mr_gt_params gp = MR_GT_DEFAULTS;
        gp.rays = b->p.rays;
        gp.radius = b->radius;
        ok = mr_eval_ao_groundtruth(b->gt, &vd->view, &vd->depth, &vd->normal, &gp, &vd->gt_fixed, err);
        gp.radius_mode = MR_AO_RADIUS_SCREEN;
        gp.screen_radius = b->screen_radius;
        ok = ok && mr_eval_ao_groundtruth(b->gt, &vd->view, &vd->depth, &vd->normal, &gp, &vd->gt_screen, err);
    }
    if (ok)
        BENCH_PRINT(b->p.out, "bench ao: %s, %dx%d, %llu triangles; ground truth (%d rays, R = %g, screen %g) for %d views in %.1f s\n",
                    mr_gpu_description(b->gfx.gpu), b->w, b->h, (unsigned long long)mr_scene_triangle_count(b->scene),
                    b->p.rays, b->radius, b->screen_radius, b->nv + 1, mr_time_now() - b->t0);
    return ok;
}

/* Step 2: tuning on vd[0]: radius (unless fixed at the reference's),
 * strength, bias and (scheer) c for the lowest RMSE against the reference
 * of the method's own radius mode (bench_ao_tuning.csv). */
static bool ao_tune(ao_bench *b, mr_error *err) {
    const bool quick = b->p.quick;
    const double rscale[] = {1, 0.5, 2, 0.25}, strengths[] = {0.5, 1, 1.5, 2, 3, 4, 6, 8, 12}, biases[] = {0.02, 0.1},
                 cvals[] = {1, 0.25, 4};
    const int nr = quick ? 3 : 4, ns = quick ? 2 : 9, nb = quick ? 1 : 2;
    const double qs[] = {1, 3};
    /* The assumed thickness of the methods that use it (the
     * first entry is the default) */
    const double thick[] = {MR_AO_DEFAULT_THICKNESS, 0.25, 1, 2};
    const view_data *vd = &b->vd[0];
    mr_csv *tune = mr_csv_create(err);
    if (!tune) return false;
    mr_csv_comment(tune, "rmse_own_reference: RMSE on the tuning view against the reference of the method's radius mode");
    char tc[400];
    snprintf(tc, sizeof tc, "tuning view: '%s' (not reported); the lowest row of each contender is frozen for every reported view",
             vd->name);
    mr_csv_comment(tune, tc);
    mr_csv_header(tune, "contender,role,radius_policy,tuned,radius_mode,radius,screen_radius,strength,bias,c,kernel,r_min,r_max,"
                        "rmse_own_reference,thickness");
    bool ok = true;
    for (int c = 0; ok && c < NC; c++) {
        contender *cs = &b->cs[c];
        double best = INFINITY;
        bool paper = cs->radius == PAPER;
        /* The radius grid's first entry is the reference's own radius. */
        int na = cs->radius == TUNE_RADIUS ? nr : 1, nbb = paper ? 1 : ns, nk = paper ? 1 : nb,
            ncv = (cs->method == MR_AO_SCHEER || cs->method == MR_AO_SCHEER_GT || cs->method == MR_AO_SCHEER_BM) && !paper ? 3 : 1,
            nth = cs->method == MR_AO_GTAO || cs->method == MR_AO_BITMASK || cs->method == MR_AO_SCHEER_BM ? 4 : 1;
        for (int a = 0; ok && a < na; a++)
            for (int bi = 0; ok && bi < nbb; bi++)
                for (int k = 0; ok && k < nk; k++)
                    for (int cv = 0; ok && cv < ncv; cv++)
                    for (int ti = 0; ok && ti < nth; ti++) {
                        mr_ao_params p = MR_AO_DEFAULTS;
                        p.thickness = (float)thick[ti];
                        p.method = cs->method;
                        p.radius_mode = cs->mode;
                        p.radius = b->radius * rscale[a];
                        p.screen_radius = b->screen_radius * rscale[a];
                        p.strength = (float)(quick ? qs[bi] : strengths[bi]);
                        p.bias = (float)biases[k];
                        p.c = (float)cvals[cv];
                        if (paper) {
                            /* Scheer & Keutel as printed: cosine weight without a
                             * bias, offsets uniform in the ball (the hemisphere
                             * after the flip), c = 1, strength 1 (the printed o(v)
                             * averaged, nothing scaled). */
                            p.strength = 1;
                            p.bias = 0;
                            p.c = 1;
                            p.kernel = MR_AO_KERNEL_UNIFORM;
                            p.r_min = 0;
                            p.r_max = 1;
                        }
                        double ms;
                        mr_image_metrics m;
                        ok = run_ao(b->gfx.renderer, &vd->view, &p, b->w, b->h, 0, &ms, NULL, &b->ao, NULL, err) &&
                             mr_image_compare(&b->ao, cs->mode == MR_AO_RADIUS_SCREEN ? &vd->gt_screen : &vd->gt_fixed,
                                              &vd->depth, &m, err);
                        if (!ok) break;
                        csv_contender(tune, cs);
                        csv_params(tune, &p);
                        mr_csv_num(tune, "%.5f", m.rmse);
                        mr_csv_num(tune, "%g", p.thickness);
                        mr_csv_end_row(tune);
                        if (m.rmse < best) {
                            best = m.rmse;
                            cs->tuned = p;
                        }
                    }
        if (ok && b->p.verbose)
            BENCH_PRINT(b->p.out, "  tuned %-14s radius %g screen %g strength %g bias %g c %g thickness %g: RMSE %.4f\n",
                        cs->label, cs->tuned.radius, cs->tuned.screen_radius, cs->tuned.strength, cs->tuned.bias, cs->tuned.c,
                        cs->tuned.thickness, best);
    }
    if (!ok) {
        mr_csv_destroy(&tune);
        return false;
    }
    return save_csv(tune, b->p.out_dir, "bench_ao_tuning.csv", err);
}

/* The fetch floor of one row, measured right after it (the
 * machine is shared and noisy: side by side): as many R32F fetches per AO
 * pixel as the row has samples (times its radii), over the AO target's
 * size, spread over the depth-scaled radius in pixels. */
static bool fetch_floor(ao_bench *b, const mr_ao_params *p, double *ms, mr_error *err) {
    int step = p->half_res ? 2 : 1, aw = (b->w + step - 1) / step, ah = (b->h + step - 1) / step;
    int n = b->p.frames < 64 ? b->p.frames : 64, fetches = p->samples * (p->radii > 0 ? p->radii : 1);
    double t[64];
    if (fetches > MR_AO_MAX_SAMPLES) fetches = MR_AO_MAX_SAMPLES;
    if (!mr_render_fetch_probe(b->gfx.renderer, aw, ah, fetches, b->screen_radius * b->h / step, n, t, err)) return false;
    *ms = mr_median(t, n);
    return true;
}

/* One reported view of step 3: plain shading (D1: AO = 1 everywhere), then
 * every contender over samples x resolution x mask. */
static bool ao_grid_view(ao_bench *b, int v, mr_csv *csv, mr_error *err) {
    view_data *vd = &b->vd[v];
    const int nv = b->nv, w = b->w, h = b->h, frames = b->p.frames;
    mr_ao_params p0 = MR_AO_DEFAULTS;
    double ms = 0;
    mr_image_metrics mf, msr;
    if (!run_ao(b->gfx.renderer, &vd->view, &p0, w, h, 0, &ms, NULL, &b->ao, NULL, err) || !metrics(&b->ao, vd, &mf, &msr, err))
        return false;
    mr_csv_quoted(csv, vd->name);
    static const char *const d1[] = {"none", "D1", "-", "no", "", "", "", "", "", "", "", "", "", "0", "full", "off"};
    for (int k = 0; k < (int)(sizeof d1 / sizeof d1[0]); k++) mr_csv_text(csv, d1[k]);
    mr_csv_int(csv, w);
    mr_csv_int(csv, h);
    mr_csv_int(csv, 0);
    mr_csv_int(csv, 0);
    const double d1m[6] = {mf.rmse, mf.ssim, mf.bias, msr.rmse, msr.ssim, msr.bias};
    for (int k = 0; k < 6; k++) mr_csv_num(csv, "%.5f", d1m[k]);
    mr_csv_int(csv, -1);
    mr_csv_int(csv, 0);
    mr_csv_text(csv, "");
    mr_csv_text(csv, "");
    mr_csv_text(csv, ""); /* thickness */
    mr_csv_text(csv, ""); /* retained */
    mr_csv_end_row(csv);
    b->pv_rf[v][0] = mf.rmse;
    b->pv_rs[v][0] = msr.rmse;
    b->none_rf += mf.rmse / nv;
    b->none_rs += msr.rmse / nv;
    b->none_sf += mf.ssim / nv;
    b->none_ss += msr.ssim / nv;
    b->none_bf += mf.bias / nv;
    b->none_bs += msr.bias / nv;
    b->montage[b->nmont++] = &vd->gt_fixed;
    b->montage[b->nmont++] = &vd->gt_screen;
    for (int c = 0; c < NC; c++)
        for (int si = 0; si < b->nsamp; si++)
            for (int res = 0; res < b->nres; res++) {
                double dark_off = 0; /* the unmasked row's darkening, for the masked row's "retained" */
                for (int mk = 0; mk < 2; mk++) {
                    mr_ao_params p = b->cs[c].tuned;
                    p.samples = b->samples[si];
                    p.half_res = res == 1;
                    p.mask = mk ? MR_AO_MASK_ON : MR_AO_MASK_OFF;
                    double masked = -1, sync = 0, floor_ms = 0;
                    if (!run_ao(b->gfx.renderer, &vd->view, &p, w, h, frames, &ms, &sync, &b->ao, &masked, err) ||
                        !metrics(&b->ao, vd, &mf, &msr, err) || !fetch_floor(b, &p, &floor_ms, err))
                        return false;
                    mr_csv_quoted(csv, vd->name);
                    csv_contender(csv, &b->cs[c]);
                    csv_params(csv, &p);
                    mr_csv_int(csv, p.samples);
                    mr_csv_text(csv, res ? "half" : "full");
                    mr_csv_text(csv, mk ? "on" : "off");
                    mr_csv_int(csv, w);
                    mr_csv_int(csv, h);
                    mr_csv_num(csv, "%.4f", ms);
                    mr_csv_int(csv, frames);
                    const double m6[6] = {mf.rmse, mf.ssim, mf.bias, msr.rmse, msr.ssim, msr.bias};
                    for (int k = 0; k < 6; k++) mr_csv_num(csv, "%.5f", m6[k]);
                    mr_csv_num(csv, "%.4f", masked);
                    mr_csv_num(csv, "%.4f", sync);
                    mr_csv_num(csv, "%.4f", floor_ms);
                    mr_csv_num(csv, "%.3f", floor_ms > 0 ? sync / floor_ms : 0.0);
                    mr_csv_num(csv, "%g", p.thickness);
                    double dark = 0;
                    const float *a = b->ao.data;
                    for (size_t i = 0; a && i < (size_t)b->ao.width * b->ao.height; i++)
                        if (isfinite(a[i])) dark += 1.0 - a[i];
                    if (!mk) dark_off = dark;
                    double retained = mk ? (dark_off > 0 ? dark / dark_off : 1.0) : 1.0;
                    mr_csv_num(csv, "%.4f", retained);
                    mr_csv_end_row(csv);
                    b->agg_ret[c][si][res][mk] += retained / nv;
                    b->agg_sync[c][si][res][mk] += sync / nv;
                    b->agg_floor[c][si][res][mk] += floor_ms / nv;
                    b->agg_ratio[c][si][res][mk] += (floor_ms > 0 ? sync / floor_ms : 0.0) / nv;
                    b->agg_ms[c][si][res][mk] += ms / nv;
                    b->agg_rf[c][si][res][mk] += mf.rmse / nv;
                    b->agg_rs[c][si][res][mk] += msr.rmse / nv;
                    b->agg_sf[c][si][res][mk] += mf.ssim / nv;
                    b->agg_ss[c][si][res][mk] += msr.ssim / nv;
                    b->agg_bf[c][si][res][mk] += mf.bias / nv;
                    b->agg_bs[c][si][res][mk] += msr.bias / nv;
                    b->agg_mf[c][si][res][mk] += masked / nv;
                    if (si == b->s16 && res == 0 && mk == 0) {
                        b->pv_rf[v][c + 1] = mf.rmse;
                        b->pv_rs[v][c + 1] = msr.rmse;
                    }
                    if (si == b->s16 && res == 0 && mk == 0 && b->nmont < MAX_VIEWS * 10) {
                        mr_image *keep = malloc(sizeof *keep);
                        if (keep) {
                            *keep = b->ao;
                            b->ao.data = NULL;
                            b->owned[b->nmont] = true;
                            b->montage[b->nmont++] = keep;
                        }
                    }
                }
            }
    return true;
}

/* Scheer & Keutel's Tables 1 and 2 (bench_ao_sk.csv, bench_ao_sk.md): their
 * method as printed (scheer, depth-scaled radius at the reference's, bias 0,
 * whole-ball kernel, c 1, strength 1) at 16, 36, 64 and 128 samples, full
 * and half resolution: AO time and RMSE against both references (Table 1);
 * and the frame split into geometry (G-buffer), SSAO and blur at 16 samples
 * with a 13 x 13 blur and 36 samples with a 9 x 9 one (Table 2). Means over
 * the reported views; times are each pass between glFinish (llvmpipe
 * defers its work past timer queries) and the timer-query GPU ms. */
static bool ao_sk_tables(ao_bench *b, mr_error *err) {
    static const int k_samp[4] = {16, 36, 64, 128};
    static const double k_paper_t1[4][2] = {{12.4, 1.6}, {24.6, 3.5}, {47.0, 6.1}, {96.9, 12.4}};
    double t1_sync[4][2] = {{0}}, t1_gpu[4][2] = {{0}}, t1_rf[4][2] = {{0}}, t1_rs[4][2] = {{0}};
    double t2[2][4] = {{0}}; /* geometry, ssao, blur, whole frame (sync ms) */
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "Scheer & Keutel as printed: scheer, depth-scaled radius (the reference's), bias 0, whole-ball uniform "
                        "kernel, c 1, strength 1; table 1: AO passes; table 2: G-buffer, AO (+ upsample), blur and the whole "
                        "frame, each pass between glFinish (sync) and by timer query (gpu)");
    mr_csv_header(csv, "view,table,samples,resolution,blur,width,height,geometry_sync_ms,ssao_sync_ms,blur_sync_ms,frame_sync_ms,"
                       "ssao_gpu_ms,rmse_fixed,rmse_screen");
    const int nv = b->nv, frames = b->p.frames > 0 ? b->p.frames : 1;
    for (int v = 1; v <= nv; v++) {
        view_data *vd = &b->vd[v];
        for (int row = 0; row < 4 * 2 + 2; row++) {
            int table = row < 8 ? 1 : 2, si = row < 8 ? row / 2 : (row == 8 ? 0 : 1), half = row < 8 ? row % 2 : 0;
            mr_ao_params ao = MR_AO_DEFAULTS;
            ao.method = MR_AO_SCHEER;
            ao.radius_mode = MR_AO_RADIUS_SCREEN;
            ao.screen_radius = b->screen_radius;
            ao.strength = 1;
            ao.bias = 0;
            ao.c = 1;
            ao.kernel = MR_AO_KERNEL_UNIFORM;
            ao.r_min = 0;
            ao.r_max = 1;
            ao.samples = k_samp[si];
            ao.half_res = half;
            ao.blur_radius = table == 1 ? 0 : (row == 8 ? 6 : 4);
            ao.no_reuse = true;
            ao.want_ao = true;
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = b->w;
            fp.height = b->h;
            fp.timing = true;
            fp.timing_sync = true;
            fp.ao = ao;
            double g[64], a[64], bl[64], fr[64], ag[64];
            int n = frames < 64 ? frames : 64;
            mr_image_metrics mf = {0}, msr = {0};
            for (int f = -1; f < n; f++) {
                mr_frame_result res;
                if (!mr_render_frame(b->gfx.renderer, &vd->view, &fp, &res, err)) {
                    mr_csv_destroy(&csv);
                    return false;
                }
                double sg = 0, sa = 0, sb = 0, sf = 0, sag = 0;
                for (int k = 0; k < res.pass_count; k++) {
                    const char *pn = res.passes[k];
                    sf += res.cpu_ms[k];
                    if (strcmp(pn, "gbuffer") == 0) sg += res.cpu_ms[k];
                    else if (strcmp(pn, "ao_blur") == 0) sb += res.cpu_ms[k];
                    else if (strncmp(pn, "ao", 2) == 0) {
                        sa += res.cpu_ms[k];
                        sag += res.gpu_ms[k];
                    }
                }
                if (f >= 0) g[f] = sg, a[f] = sa, bl[f] = sb, fr[f] = sf, ag[f] = sag;
                if (f == n - 1 && !metrics(&res.ao, vd, &mf, &msr, err)) {
                    mr_frame_result_free(&res);
                    mr_csv_destroy(&csv);
                    return false;
                }
                mr_frame_result_free(&res);
            }
            double mg = mr_median(g, n), ma = mr_median(a, n), mb = mr_median(bl, n), mfr = mr_median(fr, n), mag = mr_median(ag, n);
            mr_csv_quoted(csv, vd->name);
            mr_csv_int(csv, table);
            mr_csv_int(csv, ao.samples);
            mr_csv_text(csv, half ? "half" : "full");
            mr_csv_int(csv, ao.blur_radius ? 2 * ao.blur_radius + 1 : 0);
            mr_csv_int(csv, b->w);
            mr_csv_int(csv, b->h);
            const double vals[7] = {mg, ma, mb, mfr, mag, mf.rmse, msr.rmse};
            for (int k = 0; k < 7; k++) mr_csv_num(csv, "%.4f", vals[k]);
            mr_csv_end_row(csv);
            if (table == 1) {
                t1_sync[si][half] += ma / nv;
                t1_gpu[si][half] += mag / nv;
                t1_rf[si][half] += mf.rmse / nv;
                t1_rs[si][half] += msr.rmse / nv;
            } else {
                const double t[4] = {mg, ma, mb, mfr};
                for (int k = 0; k < 4; k++) t2[row - 8][k] += t[k] / nv;
            }
        }
    }
    if (!save_csv(csv, b->p.out_dir, "bench_ao_sk.csv", err)) return false;
    char md[8192];
    size_t len = 0;
    len += (size_t)snprintf(md + len, sizeof md - len,
                            "Scheer & Keutel, Table 1 (SSAO computation time), their method as printed, %dx%d, mean of %d views, "
                            "median of %d frames; the paper: 800x800 (Sec. 4), GTX 285; here: this machine's GL (`sync` = the AO "
                            "passes between glFinish)\n\n| samples | paper full ms | paper half ms | full sync ms | half sync ms | "
                            "full GPU ms | half GPU ms | half / full (paper) | half / full (here) | RMSE fixed full / half | RMSE "
                            "depth-scaled full / half |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
                            b->w, b->h, nv, frames);
    for (int si = 0; si < 4; si++)
        len += (size_t)snprintf(md + len, sizeof md - len,
                                "| %d | %.1f | %.1f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.4f / %.4f | %.4f / %.4f |\n", k_samp[si],
                                k_paper_t1[si][0], k_paper_t1[si][1], t1_sync[si][0], t1_sync[si][1], t1_gpu[si][0], t1_gpu[si][1],
                                k_paper_t1[si][1] / k_paper_t1[si][0], t1_sync[si][0] > 0 ? t1_sync[si][1] / t1_sync[si][0] : 0,
                                t1_rf[si][0], t1_rf[si][1], t1_rs[si][0], t1_rs[si][1]);
    len += (size_t)snprintf(md + len, sizeof md - len,
                            "\nScheer & Keutel, Table 2 (overall performance), same setting (sync ms)\n\n| samples | blur | paper "
                            "geo / SSAO / blur / frame ms | geometry | SSAO | blur | frame | SSAO share (paper) | SSAO share (here) |\n"
                            "|---|---|---|---|---|---|---|---|---|\n");
    static const double k_paper_t2[2][4] = {{3.6, 12.4, 3.6, 19.6}, {3.6, 24.6, 2.8, 31.0}};
    for (int r = 0; r < 2; r++)
        len += (size_t)snprintf(md + len, sizeof md - len, "| %d | %s | %.1f / %.1f / %.1f / %.1f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n",
                                r ? 36 : 16, r ? "9x9" : "13x13", k_paper_t2[r][0], k_paper_t2[r][1], k_paper_t2[r][2],
                                k_paper_t2[r][3], t2[r][0], t2[r][1], t2[r][2], t2[r][3], k_paper_t2[r][1] / k_paper_t2[r][3],
                                t2[r][3] > 0 ? t2[r][1] / t2[r][3] : 0);
    char path[4096];
    mr_path_join(b->p.out_dir, "bench_ao_sk.md", path, sizeof path);
    if (b->p.out) fputs(md, b->p.out);
    return mr_file_write_atomic(path, md, len, err);
}

/* Doronin et al.'s sampling strategies and multi-radius AO, raced
 * (bench_ao_sampling.csv, bench_ao_sampling.md): crytek (their SSAO's
 * base: sphere samples against the depth buffer, constant radius) and
 * scheer (D2) at their tuned settings, kernel (uniform, jittered, Latin,
 * Poisson) x samples (4..64) x radii (1..5), RMSE against the reference of
 * the method's radius mode (Embree), mean over the reported views; then
 * each (kernel, radii) curve's RMSE at equal time: interpolated in log ms
 * at the ms of the uniform kernel, one radius, 16 samples (`*`: outside
 * the curve, its nearest end). */
enum { SMP_KERNELS = 4, SMP_COUNTS = 5, SMP_RADII = 5, SMP_METHODS = 2 };
static bool ao_sampling(ao_bench *b, mr_error *err) {
    static const int k_n[SMP_COUNTS] = {4, 8, 16, 32, 64};
    static const char *const k_method_label[SMP_METHODS] = {"crytek", "scheer"};
    static double ms[SMP_METHODS][SMP_KERNELS][SMP_RADII][SMP_COUNTS], rm[SMP_METHODS][SMP_KERNELS][SMP_RADII][SMP_COUNTS];
    memset(ms, 0, sizeof ms);
    memset(rm, 0, sizeof rm);
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "Doronin et al.'s kernels and multi-radius AO: rmse_own = against the reference of the method's radius "
                        "mode (crytek: fixed R, scheer: depth-scaled); gpu_ms: AO passes, median of the frames");
    mr_csv_header(csv, "view,method,kernel,radii,samples,width,height,gpu_ms,rmse_own,rmse_fixed,rmse_screen");
    const int nv = b->nv;
    for (int mi = 0; mi < SMP_METHODS; mi++) {
        const contender *cs = NULL;
        for (int c = 0; c < NC && !cs; c++)
            if (strcmp(b->cs[c].label, k_method_label[mi]) == 0) cs = &b->cs[c];
        if (!cs) continue;
        for (int v = 1; v <= nv; v++)
            for (int k = 0; k < SMP_KERNELS; k++)
                for (int ra = 0; ra < SMP_RADII; ra++)
                    for (int si = 0; si < SMP_COUNTS; si++) {
                        mr_ao_params p = cs->tuned;
                        p.kernel = (mr_ao_kernel)k;
                        p.radii = ra + 1;
                        p.samples = k_n[si];
                        double t = 0;
                        mr_image_metrics mf, msr;
                        if (!run_ao(b->gfx.renderer, &b->vd[v].view, &p, b->w, b->h, b->p.frames, &t, NULL, &b->ao, NULL, err) ||
                            !metrics(&b->ao, &b->vd[v], &mf, &msr, err)) {
                            mr_csv_destroy(&csv);
                            return false;
                        }
                        double own = cs->mode == MR_AO_RADIUS_SCREEN ? msr.rmse : mf.rmse;
                        mr_csv_quoted(csv, b->vd[v].name);
                        mr_csv_text(csv, k_method_label[mi]);
                        mr_csv_text(csv, mr_ao_kernel_name(p.kernel));
                        mr_csv_int(csv, p.radii);
                        mr_csv_int(csv, p.samples);
                        mr_csv_int(csv, b->w);
                        mr_csv_int(csv, b->h);
                        mr_csv_num(csv, "%.4f", t);
                        mr_csv_num(csv, "%.5f", own);
                        mr_csv_num(csv, "%.5f", mf.rmse);
                        mr_csv_num(csv, "%.5f", msr.rmse);
                        mr_csv_end_row(csv);
                        ms[mi][k][ra][si] += t / nv;
                        rm[mi][k][ra][si] += own / nv;
                    }
    }
    if (!save_csv(csv, b->p.out_dir, "bench_ao_sampling.csv", err)) return false;
    static char md[16384];
    size_t len = 0;
    for (int mi = 0; mi < SMP_METHODS; mi++) {
        double target = ms[mi][0][0][2];
        len += (size_t)snprintf(md + len, sizeof md - len,
                                "\n%s, %dx%d, mean of %d views: RMSE against its own reference at %d samples, and at equal "
                                "time (%.2f ms: uniform, 1 radius, 16 samples; `*` outside the curve)\n\n| kernel | radii | "
                                "RMSE 4 | RMSE 8 | RMSE 16 | RMSE 32 | RMSE 64 | ms 16 | RMSE at %.2f ms |\n|---|---|---|---|---|---|---|---|---|\n",
                                k_method_label[mi], b->w, b->h, nv, 16, target, target);
        for (int k = 0; k < SMP_KERNELS; k++)
            for (int ra = 0; ra < SMP_RADII; ra++) {
                const double *x = ms[mi][k][ra], *y = rm[mi][k][ra];
                double at = y[0];
                bool outside = true;
                if (target <= x[0]) at = y[0];
                else if (target >= x[SMP_COUNTS - 1]) at = y[SMP_COUNTS - 1];
                for (int i = 0; i + 1 < SMP_COUNTS; i++)
                    if (x[i] > 0 && x[i + 1] > x[i] && target >= x[i] && target <= x[i + 1]) {
                        double f = log(target / x[i]) / log(x[i + 1] / x[i]);
                        at = y[i] + f * (y[i + 1] - y[i]);
                        outside = false;
                        break;
                    }
                len += (size_t)snprintf(md + len, sizeof md - len, "| %s | %d | %.4f | %.4f | %.4f | %.4f | %.4f | %.2f | %.4f%s |\n",
                                        mr_ao_kernel_name((mr_ao_kernel)k), ra + 1, y[0], y[1], y[2], y[3], y[4], x[2], at,
                                        outside ? "*" : "");
            }
    }
    char path[4096];
    mr_path_join(b->p.out_dir, "bench_ao_sampling.md", path, sizeof path);
    if (b->p.out) fputs(md, b->p.out);
    return mr_file_write_atomic(path, md, len, err);
}

/* Step 3: the grid on the reported views (bench_ao.csv). */
static bool ao_grid(ao_bench *b, mr_error *err) {
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "role: Scheer & Keutel's D1 (no AO), D2 (scheer, depth-scaled radius), D3 (standard SSAO = crytek, "
                        "constant radius) or -; radius_policy: tuned, or the reference's own radius; tuned: no = the paper's "
                        "parameters; strength <= 0: the method's default; *_fixed: against ray-traced AO with fixed R, *_screen: with "
                        "the depth-scaled R; sync_ms: the AO passes timed between glFinish (llvmpipe defers rasterisation past "
                        "a timer query); floor_ms: a full-screen pass of as many R32F fetches per AO pixel and nothing else, "
                        "timed the same way right after the row; floor_ratio = sync_ms / floor_ms; thickness: the "
                        "bitmask / gtao / scheer-bm occluder thickness (fraction of the radius); retained: with the mask on, "
                        "the darkening sum(1 - AO) kept of the same row unmasked (Park & Baek promise the same image: 1)");
    char tc[400];
    snprintf(tc, sizeof tc, "parameters tuned on the tuning view '%s' (not reported, bench_ao_tuning.csv) and frozen for these views",
             b->vd[0].name);
    mr_csv_comment(csv, tc);
    mr_csv_header(csv, "view,contender,role,radius_policy,tuned,radius_mode,radius,screen_radius,strength,bias,c,kernel,r_min,"
                       "r_max,samples,resolution,mask,width,height,"
                       "gpu_ms_median,frames,rmse_fixed,ssim_fixed,bias_fixed,rmse_screen,ssim_screen,bias_screen,masked_fraction,"
                       "sync_ms_median,floor_ms_median,floor_ratio,thickness,retained");
    for (int v = 1; v <= b->nv; v++) {
        if (!ao_grid_view(b, v, csv, err)) {
            mr_csv_destroy(&csv);
            return false;
        }
        if (b->p.progress) fprintf(stderr, "bench ao: view %d/%d done (%.0f s)\n", v, b->nv, mr_time_now() - b->t0);
    }
    return save_csv(csv, b->p.out_dir, "bench_ao.csv", err);
}

/* Step 4: AO cost against triangle count (scheer, 16 samples, full
 * resolution) on terrains of 128, 20k and 2M triangles and on the scene
 * (bench_ao_triangles.csv). */
static bool ao_triangles(ao_bench *b, mr_error *err) {
    mr_csv *tcsv = mr_csv_create(err);
    if (!tcsv) return false;
    mr_csv_header(tcsv, "scene,triangles,ao_gpu_ms_median,gbuffer_gpu_ms_median,width,height,frames");
    const int grid_n[] = {8, 100, 1000};
    const int n = b->p.frames;
    bool ok = true;
    for (int gi = 0; ok && gi < 4; gi++) {
        mr_scene *ts = gi < 3 ? terrain_scene(grid_n[gi], err) : b->scene;
        if (!ts) { ok = false; break; }
        mr_view tv;
        tv.camera = mr_demo_camera();
        tv.world_from_camera = mr_m4_look_at_cv(mr_v3(-15, 6, -15), mr_v3(5, 0, 5), mr_v3(0, 1, 0));
        if (gi == 3) tv = b->vd[1].view;
        ok = mr_renderer_set_scene(b->gfx.renderer, ts, err);
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.width = b->w;
        fp.height = b->h;
        fp.timing = true;
        fp.ao = b->cs[0].tuned;
        fp.ao.samples = 16;
        fp.ao.no_reuse = true;
        double aoms[64], gbms[64];
        for (int f = -1; ok && f < n; f++) {
            mr_frame_result res;
            ok = mr_render_frame(b->gfx.renderer, &tv, &fp, &res, err);
            if (!ok) break;
            double a = 0, g = 0;
            for (int k = 0; k < res.pass_count; k++) {
                if (strncmp(res.passes[k], "ao", 2) == 0) a += res.gpu_ms[k];
                if (strcmp(res.passes[k], "gbuffer") == 0) g += res.gpu_ms[k];
            }
            if (f >= 0) { aoms[f] = a; gbms[f] = g; }
            b->tri_count[b->ntri] = res.triangles;
            mr_frame_result_free(&res);
        }
        if (ok) {
            b->tri_ms[b->ntri] = mr_median(aoms, n);
            b->tri_gb[b->ntri] = mr_median(gbms, n);
            mr_csv_text(tcsv, gi < 3 ? "terrain" : "scene");
            mr_csv_int(tcsv, (long long)b->tri_count[b->ntri]);
            mr_csv_num(tcsv, "%.4f", b->tri_ms[b->ntri]);
            mr_csv_num(tcsv, "%.4f", b->tri_gb[b->ntri]);
            mr_csv_int(tcsv, b->w);
            mr_csv_int(tcsv, b->h);
            mr_csv_int(tcsv, n);
            mr_csv_end_row(tcsv);
            b->ntri++;
        }
        mr_renderer_set_scene(b->gfx.renderer, NULL, NULL);
        if (gi < 3) mr_scene_destroy(&ts);
    }
    if (!ok) {
        mr_csv_destroy(&tcsv);
        return false;
    }
    return save_csv(tcsv, b->p.out_dir, "bench_ao_triangles.csv", err);
}

/* Step 5: error against GPU time, one plot per reference (bench_ao.svg,
 * bench_ao_screen.svg), and the AO montage (bench_ao_montage.png). */
static bool ao_plots(ao_bench *b, mr_error *err) {
    char path[4096];
    bool ok = true;
    for (int ref = 0; ok && ref < 2; ref++) {
        mr_plot_series ser[2 * MAXC];
        memset(ser, 0, sizeof ser); /* fields not set here take their defaults */
        static double xs[2 * MAXC][MAXS], ys[2 * MAXC][MAXS];
        static char names[2 * MAXC][64];
        int nser = 0;
        for (int c = 0; c < NC; c++)
            for (int res = 0; res < b->nres; res++) {
                for (int si = 0; si < b->nsamp; si++) {
                    xs[nser][si] = b->agg_sync[c][si][res][0]; /* glFinish-timed */
                    ys[nser][si] = ref ? b->agg_rs[c][si][res][0] : b->agg_rf[c][si][res][0];
                }
                snprintf(names[nser], sizeof names[nser], "%s%s", b->cs[c].label, res ? " half" : "");
                ser[nser].name = names[nser];
                ser[nser].x = xs[nser];
                ser[nser].y = ys[nser];
                ser[nser].count = b->nsamp;
                nser++;
            }
        char title[256];
        snprintf(title, sizeof title, "AO error vs GPU time, %dx%d, samples %d..%d, mean of %d views; reference: %s", b->w, b->h,
                 b->samples[0], b->samples[b->nsamp - 1], b->nv, ref ? "depth-scaled R" : "fixed R");
        mr_path_join(b->p.out_dir, ref ? "bench_ao_screen.svg" : "bench_ao.svg", path, sizeof path);
        ok = mr_plot_svg(path, title, "AO passes, ms between glFinish (median)", "RMSE against ray-traced AO", ser, nser, true,
                         err);
    }
    mr_path_join(b->p.out_dir, "bench_ao_montage.png", path, sizeof path);
    return ok && mr_montage_png(path, (const mr_image *const *)b->montage, b->nmont, 2 + NC, b->w, b->h, err);
}

/* Step 6: Scheer & Keutel's three renderings, shaded as in the paper (Phong
 * with specular): D1 no AO, D2 scheer, D3 standard SSAO (crytek, constant
 * radius), plus scheer-paper; 16 samples, one row per view
 * (bench_ao_shaded.png). */
static bool ao_shaded(ao_bench *b, mr_error *err) {
    const int shaded_c[3] = {0, 3, 2};
    mr_image shots[MAX_VIEWS * 4];
    const mr_image *tiles[MAX_VIEWS * 4];
    int nshot = 0;
    bool ok = mr_renderer_set_scene(b->gfx.renderer, b->scene, err); /* step 4 changed it */
    for (int v = 1; ok && v <= b->nv; v++)
        for (int k = 0; ok && k < 4; k++) {
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = b->w;
            fp.height = b->h;
            fp.specular = 0.35f;
            if (k > 0) {
                fp.ao = b->cs[shaded_c[k - 1]].tuned;
                fp.ao.samples = 16;
                fp.ao.no_reuse = true;
            }
            mr_frame_result res;
            ok = mr_render_frame(b->gfx.renderer, &b->vd[v].view, &fp, &res, err);
            if (!ok) break;
            shots[nshot] = res.color;
            res.color.data = NULL;
            tiles[nshot] = &shots[nshot];
            nshot++;
            mr_frame_result_free(&res);
        }
    char path[4096];
    mr_path_join(b->p.out_dir, "bench_ao_shaded.png", path, sizeof path);
    if (ok) ok = mr_montage_png(path, tiles, nshot, 4, b->w, b->h, err);
    for (int i = 0; i < nshot; i++) mr_image_free(&shots[i]);
    return ok;
}

/* RMSE of contender c at `ms` (full resolution, mask off): linear in
 * log ms between the two sample counts around it on its curve; outside
 * the curve the nearest end, flagged. */
static double rmse_at_ms(const ao_bench *b, int c, bool screen, double ms, bool *outside) {
    int n = b->nsamp;
    double x[MAXS], y[MAXS];
    for (int si = 0; si < n; si++) {
        x[si] = log(fmax(b->agg_sync[c][si][0][0], 1e-6));
        y[si] = screen ? b->agg_rs[c][si][0][0] : b->agg_rf[c][si][0][0];
    }
    double lx = log(fmax(ms, 1e-6));
    *outside = false;
    int lo = 0, hi = 0;
    for (int si = 1; si < n; si++) {
        if (x[si] < x[lo]) lo = si;
        if (x[si] > x[hi]) hi = si;
    }
    if (lx <= x[lo]) {
        *outside = lx < x[lo];
        return y[lo];
    }
    if (lx >= x[hi]) {
        *outside = lx > x[hi];
        return y[hi];
    }
    /* the nearest points below and above (the curve need not be sorted in ms) */
    int a = lo, bb = hi;
    for (int si = 0; si < n; si++) {
        if (x[si] <= lx && x[si] > x[a]) a = si;
        if (x[si] >= lx && x[si] < x[bb]) bb = si;
    }
    if (x[bb] - x[a] < 1e-12) return y[a];
    double t = (lx - x[a]) / (x[bb] - x[a]);
    return y[a] + t * (y[bb] - y[a]);
}

/* The table at equal ms: every contender's RMSE interpolated on
 * its error-against-ms curve at the ms of scheer (D2, tuned) at the
 * reported sample count, and at that of the fetch floor's ratio. */
static size_t equal_ms_table(const ao_bench *b, char *md, size_t cap, size_t len) {
    const int s16 = b->s16;
    double target = b->agg_sync[0][s16][0][0];
    len += (size_t)snprintf(md + len, cap - len,
                            "\nAt equal ms (%.2f ms: scheer at %d samples, full resolution, mask off; each method's RMSE "
                            "interpolated in log ms between its sample counts %d..%d, `*` = outside its curve, its nearest "
                            "end). x floor: its own ms over the fetch floor of as many fetches, at %d samples.\n\n"
                            "| method | RMSE fixed R | RMSE depth-scaled R | ms at %d samples | x floor at %d samples |\n"
                            "|---|---|---|---|---|\n",
                            target, b->samples[s16], b->samples[0], b->samples[b->nsamp - 1], b->samples[s16], b->samples[s16],
                            b->samples[s16]);
    for (int c = 0; c < NC; c++) {
        bool of, os;
        double rf = rmse_at_ms(b, c, false, target, &of), rs = rmse_at_ms(b, c, true, target, &os);
        len += (size_t)snprintf(md + len, cap - len, "| %s | %.4f%s | %.4f%s | %.2f | %.2f |\n", b->cs[c].label, rf,
                                of ? "*" : "", rs, os ? "*" : "", b->agg_sync[c][s16][0][0], b->agg_ratio[c][s16][0][0]);
    }
    /* The question the bench answers: the best scheer-family row against the best of
     * gtao, bitmask, hbao and filion, at this ms, per reference (rows
     * outside their curve count with their nearest end). */
    for (int ref = 1; ref >= 0; ref--) {
        int bs = -1, bp = -1;
        double es = INFINITY, ep = INFINITY;
        for (int c = 0; c < NC; c++) {
            bool o;
            double e = rmse_at_ms(b, c, ref == 1, target, &o);
            mr_ao_method m = b->cs[c].method;
            bool fam = m == MR_AO_SCHEER || m == MR_AO_SCHEER_GT || m == MR_AO_SCHEER_BM;
            bool peer = m == MR_AO_GTAO || m == MR_AO_BITMASK || m == MR_AO_HBAO || m == MR_AO_FILION;
            if (fam && e < es) es = e, bs = c;
            if (peer && e < ep) ep = e, bp = c;
        }
        if (bs >= 0 && bp >= 0)
            len += (size_t)snprintf(md + len, cap - len,
                                    "%sAgainst the %s reference at %.2f ms: best scheer family %s %.4f, best of gtao / bitmask "
                                    "/ hbao / filion %s %.4f: %+.1f %% RMSE.\n",
                                    ref ? "\n" : "", ref ? "depth-scaled" : "fixed-radius", target, b->cs[bs].label, es,
                                    b->cs[bp].label, ep, ep > 0 ? 100.0 * (es / ep - 1.0) : 0.0);
    }
    return len;
}

/* Step 6b: temporal accumulation on a moving sequence, the
 * poses of a recording (--sequence DIR; default the shipped
 * recordings/demo when it is there, else the step is left out) at the
 * bench's size: per frame the depth-scaled reference, and each of the
 * tuned scheer (D2), gtao and scheer-bm at 4, 8 and 16 samples per frame
 * and at 4 with accumulation (restarted at the first frame); RMSE per
 * frame against that frame's reference, the AO passes timed between
 * glFinish (bench_ao_sequence.csv). Judged at equal ms: the per-frame
 * curve (4, 8, 16 samples) is interpolated in log ms at the accumulating
 * run's ms, so accumulation is compared with what the same time buys
 * without it. */
enum { SEQ_MAX = 24 };
static int contender_of(const char *label) {
    for (int c = 0; c < NC; c++)
        if (strcmp(k_contenders[c].label, label) == 0) return c;
    return 0;
}
static const char *const k_seq_method[SEQ_METHODS] = {"scheer", "gtao", "scheer-bm"};
static const int k_seq_samples[SEQ_CFG] = {4, 8, 16, 4}; /* the last accumulates */

/* y at x on the curve (xs, ys) of n points, linear in log x between the
 * nearest points below and above; outside the curve its nearest end. */
static double interp_log(const double *xs, const double *ys, int n, double x, bool *outside) {
    int lo = 0, hi = 0;
    for (int i = 1; i < n; i++) {
        if (xs[i] < xs[lo]) lo = i;
        if (xs[i] > xs[hi]) hi = i;
    }
    *outside = x < xs[lo] || x > xs[hi];
    if (x <= xs[lo]) return ys[lo];
    if (x >= xs[hi]) return ys[hi];
    int a = lo, c = hi;
    for (int i = 0; i < n; i++) {
        if (xs[i] <= x && xs[i] > xs[a]) a = i;
        if (xs[i] >= x && xs[i] < xs[c]) c = i;
    }
    double la = log(fmax(xs[a], 1e-9)), lc = log(fmax(xs[c], 1e-9));
    if (lc - la < 1e-12) return ys[a];
    return ys[a] + (log(fmax(x, 1e-9)) - la) / (lc - la) * (ys[c] - ys[a]);
}

static bool ao_sequence(ao_bench *b, mr_error *err) {
    const char *dir = b->p.sequence ? b->p.sequence : "recordings/demo";
    mr_error oe = {0};
    mr_recording *rec = mr_recording_open(dir, &oe);
    if (!rec) {
        if (b->p.sequence) {
            *err = oe;
            return false;
        }
        BENCH_PRINT(b->p.out, "bench ao: no moving sequence (%s: %s); --sequence DIR gives one\n", dir, oe.msg);
        return true;
    }
    snprintf(b->seq_name, sizeof b->seq_name, "%s", dir);
    mr_view views[SEQ_MAX];
    int nf = 0;
    for (int i = 0; i < rec->frame_count && nf < SEQ_MAX; i++) {
        const mr_rec_frame *f = &rec->frames[i];
        if (!f->has_gt && !f->pose.valid) continue;
        views[nf].camera = mr_camera_resized(&rec->camera, b->w, b->h);
        views[nf].world_from_camera = f->has_gt ? f->gt : f->pose.world_from_camera;
        nf++;
    }
    mr_recording_close(&rec);
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "temporal accumulation on a moving sequence: RMSE per frame against the frame's depth-scaled "
                        "reference; sync_ms: the AO passes between glFinish; parameters: each method's, tuned on the "
                        "tuning view and frozen");
    mr_csv_header(csv, "sequence,frame,config,samples,temporal,rmse_screen,sync_ms");
    static double rm[SEQ_METHODS][SEQ_CFG][SEQ_MAX], ms[SEQ_METHODS][SEQ_CFG][SEQ_MAX];
    mr_image depth[SEQ_MAX], ref[SEQ_MAX];
    memset(depth, 0, sizeof depth);
    memset(ref, 0, sizeof ref);
    bool ok = mr_renderer_set_scene(b->gfx.renderer, b->scene, err);
    /* the references, and the per-frame configurations */
    for (int k = 0; ok && k < nf; k++) {
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.width = b->w;
        fp.height = b->h;
        fp.want_depth = fp.want_normals = true;
        mr_frame_result res;
        ok = mr_render_frame(b->gfx.renderer, &views[k], &fp, &res, err);
        if (!ok) break;
        mr_gt_params gp = MR_GT_DEFAULTS;
        gp.rays = b->p.rays;
        gp.radius_mode = MR_AO_RADIUS_SCREEN;
        gp.screen_radius = b->screen_radius;
        ok = mr_eval_ao_groundtruth(b->gt, &views[k], &res.depth, &res.normal, &gp, &ref[k], err);
        depth[k] = res.depth;
        res.depth.data = NULL;
        mr_frame_result_free(&res);
        for (int m = 0; ok && m < SEQ_METHODS; m++)
            for (int c = 0; ok && c < SEQ_CFG - 1; c++) {
                mr_ao_params p = b->cs[contender_of(k_seq_method[m])].tuned;
                p.samples = k_seq_samples[c];
                p.no_reuse = true;
                double sync = 0, gms = 0;
                mr_image_metrics mt;
                ok = run_ao(b->gfx.renderer, &views[k], &p, b->w, b->h, 1, &gms, &sync, &b->ao, NULL, err) &&
                     mr_image_compare(&b->ao, &ref[k], &depth[k], &mt, err);
                if (ok) {
                    rm[m][c][k] = mt.rmse;
                    ms[m][c][k] = sync;
                }
            }
    }
    /* The accumulating runs: each a pass over the sequence of its own (the
     * history must see consecutive frames). */
    const int ct = SEQ_CFG - 1;
    for (int m = 0; ok && m < SEQ_METHODS; m++)
        for (int k = 0; ok && k < nf; k++) {
            mr_ao_params p = b->cs[contender_of(k_seq_method[m])].tuned;
            p.samples = k_seq_samples[ct];
            p.temporal = true;
            p.temporal_reset = k == 0;
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.width = b->w;
            fp.height = b->h;
            fp.timing = fp.timing_sync = true;
            fp.ao = p;
            fp.ao.want_ao = true;
            mr_frame_result res;
            ok = mr_render_frame(b->gfx.renderer, &views[k], &fp, &res, err);
            if (!ok) break;
            double sync = 0;
            for (int q = 0; q < res.pass_count; q++)
                if (strncmp(res.passes[q], "ao", 2) == 0) sync += res.cpu_ms[q];
            mr_image_metrics mt;
            ok = mr_image_compare(&res.ao, &ref[k], &depth[k], &mt, err);
            mr_frame_result_free(&res);
            if (ok) {
                rm[m][ct][k] = mt.rmse;
                ms[m][ct][k] = sync;
            }
        }
    for (int k = 0; k < nf; k++) {
        mr_image_free(&depth[k]);
        mr_image_free(&ref[k]);
    }
    for (int m = 0; ok && m < SEQ_METHODS; m++)
        for (int c = 0; c < SEQ_CFG; c++) {
            char name[64];
            snprintf(name, sizeof name, "%s %d%s", k_seq_method[m], k_seq_samples[c], c == ct ? " + temporal" : "");
            double all = 0, late = 0;
            int nl = 0;
            for (int k = 0; k < nf; k++) {
                mr_csv_quoted(csv, dir);
                mr_csv_int(csv, k);
                mr_csv_text(csv, name);
                mr_csv_int(csv, k_seq_samples[c]);
                mr_csv_text(csv, c == ct ? "on" : "off");
                mr_csv_num(csv, "%.5f", rm[m][c][k]);
                mr_csv_num(csv, "%.4f", ms[m][c][k]);
                mr_csv_end_row(csv);
                all += rm[m][c][k] / nf;
                if (k >= nf / 2) {
                    late += rm[m][c][k];
                    nl++;
                }
            }
            b->seq_rmse[m][c][0] = all;
            b->seq_rmse[m][c][1] = nl ? late / nl : 0;
            double t[SEQ_MAX];
            memcpy(t, ms[m][c], sizeof t);
            b->seq_ms[m][c] = nf > 0 ? mr_median(t, nf) : 0;
        }
    b->seq_frames = ok ? nf : 0;
    if (!ok) {
        mr_csv_destroy(&csv);
        return false;
    }
    return save_csv(csv, b->p.out_dir, "bench_ao_sequence.csv", err);
}

/* Step 6c: the cost steps towards the fetch floor. On the first
 * reported view, at 16 samples, each of the slice methods (tuned, depth-
 * scaled) at full and half resolution, with and without the depth mip
 * chain, and deinterleaved at full and half
 * resolution; every configuration timed (glFinish, median of --frames) with its
 * fetch floor right after, in `rounds` rounds that alternate the
 * configurations (the machine is shared: side by side, the median of the
 * rounds' ratios). bench_ao_cost.csv. */
static const char *const k_cost_method[COST_METHODS] = {"gtao", "bitmask", "scheer-bm"};
static bool ao_cost(ao_bench *b, mr_error *err) {
    enum { ROUNDS = 5 };
    const view_data *vd = &b->vd[b->nv >= 1 ? 1 : 0];
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "cost steps at 16 samples on the first reported view: sync_ms (AO passes between glFinish, median "
                        "of the frames), floor_ms (the fetch floor of as many fetches per AO pixel, right after), "
                        "ratio = sync / floor; each round runs every configuration once");
    mr_csv_header(csv, "view,method,resolution,mips,round,sync_ms_median,floor_ms_median,floor_ratio,rmse_screen");
    bool ok = mr_renderer_set_scene(b->gfx.renderer, b->scene, err);
    double ratio[COST_METHODS][6][ROUNDS], sync[COST_METHODS][6][ROUNDS], flo[COST_METHODS][6][ROUNDS];
    for (int rd = 0; ok && rd < ROUNDS; rd++)
        for (int m = 0; ok && m < COST_METHODS; m++)
            for (int cfg = 0; ok && cfg < 6; cfg++) {
                mr_ao_params p = b->cs[contender_of(k_cost_method[m])].tuned;
                p.samples = 16;
                p.half_res = cfg == 2 || cfg == 3 || cfg == 5;
                p.mips = cfg == 1 || cfg == 3;
                p.deinterleave = cfg >= 4;
                double gms = 0, s = 0, fl = 0;
                mr_image_metrics mt;
                ok = run_ao(b->gfx.renderer, &vd->view, &p, b->w, b->h, b->p.frames, &gms, &s, &b->ao, NULL, err) &&
                     fetch_floor(b, &p, &fl, err) && mr_image_compare(&b->ao, &vd->gt_screen, &vd->depth, &mt, err);
                if (!ok) break;
                sync[m][cfg][rd] = s;
                flo[m][cfg][rd] = fl;
                ratio[m][cfg][rd] = fl > 0 ? s / fl : 0;
                b->cost_rmse[m][cfg] = mt.rmse;
                mr_csv_quoted(csv, vd->name);
                mr_csv_text(csv, k_cost_method[m]);
                mr_csv_text(csv, p.deinterleave ? (p.half_res ? "half+deinterleave" : "full+deinterleave")
                                                : (p.half_res ? "half" : "full"));
                mr_csv_text(csv, p.mips ? "on" : "off");
                mr_csv_int(csv, rd);
                mr_csv_num(csv, "%.4f", s);
                mr_csv_num(csv, "%.4f", fl);
                mr_csv_num(csv, "%.3f", ratio[m][cfg][rd]);
                mr_csv_num(csv, "%.5f", mt.rmse);
                mr_csv_end_row(csv);
            }
    if (!ok) {
        mr_csv_destroy(&csv);
        return false;
    }
    for (int m = 0; m < COST_METHODS; m++)
        for (int cfg = 0; cfg < 6; cfg++) {
            b->cost_ratio[m][cfg] = mr_median(ratio[m][cfg], ROUNDS);
            b->cost_sync[m][cfg] = mr_median(sync[m][cfg], ROUNDS);
            b->cost_floor[m][cfg] = mr_median(flo[m][cfg], ROUNDS);
        }
    /* Deinterleaved 4 x 4 rendering, probed before it is built: its gain on
     * a machine is the fetch floor's, the same fetches from 16 sub-images
     * of a quarter the size each with a quarter the spread (a sub-image
     * holds every 4th pixel, so its samples lie 4x closer in memory),
     * against one full-size pass. Each sub-image pass is timed alone
     * (glFinish around it), so the sum carries 16 synchronisations. */
    double dfull[ROUNDS], dsub[ROUNDS];
    const int fn = b->p.frames < 64 ? b->p.frames : 64;
    const double rpx = b->screen_radius * b->h;
    for (int rd = 0; ok && rd < ROUNDS; rd++) {
        double t[64];
        ok = mr_render_fetch_probe(b->gfx.renderer, b->w, b->h, 16, rpx, fn, t, err);
        if (!ok) break;
        dfull[rd] = mr_median(t, fn);
        ok = mr_render_fetch_probe(b->gfx.renderer, (b->w + 3) / 4, (b->h + 3) / 4, 16, rpx / 4, fn, t, err);
        if (!ok) break;
        dsub[rd] = 16 * mr_median(t, fn);
        for (int q = 0; q < 2; q++) {
            mr_csv_quoted(csv, vd->name);
            mr_csv_text(csv, "fetch-floor");
            mr_csv_text(csv, q ? "deinterleaved-4x4" : "full");
            mr_csv_text(csv, "-");
            mr_csv_int(csv, rd);
            mr_csv_num(csv, "%.4f", q ? dsub[rd] : dfull[rd]);
            mr_csv_num(csv, "%.4f", dfull[rd]);
            mr_csv_num(csv, "%.3f", dfull[rd] > 0 ? (q ? dsub[rd] : dfull[rd]) / dfull[rd] : 0.0);
            mr_csv_text(csv, "");
            mr_csv_end_row(csv);
        }
    }
    if (!ok) {
        mr_csv_destroy(&csv);
        return false;
    }
    b->deint_full = mr_median(dfull, ROUNDS);
    b->deint_sub = mr_median(dsub, ROUNDS);
    b->cost_rounds = ROUNDS;
    snprintf(b->cost_view, sizeof b->cost_view, "%s", vd->name);
    /* the load average (Linux), so a reader can judge how quiet it was */
    b->loadavg[0] = 0;
    FILE *la = fopen("/proc/loadavg", "r");
    if (la) {
        if (!fgets(b->loadavg, sizeof b->loadavg, la)) b->loadavg[0] = 0;
        fclose(la);
        size_t n = strlen(b->loadavg);
        while (n > 0 && (b->loadavg[n - 1] == '\n' || b->loadavg[n - 1] == ' ')) b->loadavg[--n] = 0;
    }
    return save_csv(csv, b->p.out_dir, "bench_ao_cost.csv", err);
}

/* Step 7: the summary table (bench_ao.md, also printed). */
static bool ao_summary(ao_bench *b, mr_error *err) {
    char path[4096];
    bool ok;
    static char md[65536];
    size_t len = 0;
    len += (size_t)snprintf(md + len, sizeof md - len,
                            "AO at %dx%d, %d samples (%s), mean over %d views; tuned on '%s'\n\n"
                            "D1 = no AO, D2 = scheer (depth-scaled radius), D3 = standard SSAO (crytek, constant "
                            "radius), as Scheer & Keutel name them. `@R`: the radius is the reference's own (R = %g "
                            "units, or %g of the height), only strength / bias / c tuned; `scheer-paper`: the "
                            "paper's parameters (bias 0, whole-ball uniform kernel, c 1, strength 1), nothing "
                            "tuned.\n\n"
                            "| method | role | radius | strength | bias | c | kernel | res | mask | GPU ms | RMSE fixed R | SSIM fixed | bias fixed | RMSE depth-scaled R | SSIM d-s | bias d-s | masked | sync ms | floor ms | x floor |\n"
                            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
                            b->w, b->h, b->samples[b->p.quick ? 0 : 1], "GPU ms: median of timer queries", b->nv, b->vd[0].name, b->radius,
                            b->screen_radius);
    len += (size_t)snprintf(md + len, sizeof md - len, "| none | D1 | - | - | - | - | - | full | off | 0 | %.4f | %.3f | %+.4f | %.4f | %.3f | %+.4f | - | 0 | - | - |\n",
                            b->none_rf, b->none_sf, b->none_bf, b->none_rs, b->none_ss, b->none_bs);
    const int s16 = b->s16;
    for (int c = 0; c < NC; c++)
        for (int res = 0; res < b->nres; res++)
            for (int mk = 0; mk < 2; mk++) {
                char rad[64];
                if (b->cs[c].mode == MR_AO_RADIUS_SCREEN) snprintf(rad, sizeof rad, "%.3g of height", b->cs[c].tuned.screen_radius);
                else snprintf(rad, sizeof rad, "%.3g units", b->cs[c].tuned.radius);
                if (b->cs[c].radius != TUNE_RADIUS) snprintf(rad + strlen(rad), sizeof rad - strlen(rad), " (ref.)");
                char kern[64], strength[32] = "default";
                if (b->cs[c].tuned.strength > 0) snprintf(strength, sizeof strength, "%g", b->cs[c].tuned.strength);
                snprintf(kern, sizeof kern, "%s [%g,%g]", mr_ao_kernel_name(b->cs[c].tuned.kernel), b->cs[c].tuned.r_min,
                         b->cs[c].tuned.r_max);
                char masked[32] = "-";
                if (mk) snprintf(masked, sizeof masked, "%.3f", b->agg_mf[c][s16][res][mk]);
                len += (size_t)snprintf(md + len, sizeof md - len,
                                        "| %s | %s | %s | %s | %g | %g | %s | %s | %s | %.2f | %.4f | %.3f | %+.4f | %.4f | %.3f | %+.4f | %s | %.2f | %.2f | %.2f |\n",
                                        b->cs[c].label, b->cs[c].role, rad, strength, b->cs[c].tuned.bias,
                                        b->cs[c].tuned.c, kern, res ? "half" : "full",
                                        mk ? "on" : "off", b->agg_ms[c][s16][res][mk], b->agg_rf[c][s16][res][mk],
                                        b->agg_sf[c][s16][res][mk], b->agg_bf[c][s16][res][mk], b->agg_rs[c][s16][res][mk],
                                        b->agg_ss[c][s16][res][mk], b->agg_bs[c][s16][res][mk], masked,
                                        b->agg_sync[c][s16][res][mk], b->agg_floor[c][s16][res][mk],
                                        b->agg_ratio[c][s16][res][mk]);
            }
    len += (size_t)snprintf(md + len, sizeof md - len,
                            "\nCorner mask (Park & Baek: the same image, faster), %d samples, full resolution: darkening kept "
                            "(sum of 1 - AO, masked / unmasked; the paper promises 1) and time with the mask against without "
                            "(GPU ms; pays: < 1):\n\n| method | retained | ms off | ms on | on / off | masked fraction |\n|---|---|---|---|---|---|\n",
                            b->samples[s16]);
    for (int c = 0; c < NC; c++) {
        double off = b->agg_ms[c][s16][0][0], on = b->agg_ms[c][s16][0][1];
        len += (size_t)snprintf(md + len, sizeof md - len, "| %s | %.4f | %.2f | %.2f | %.2f | %.3f |\n", b->cs[c].label,
                                b->agg_ret[c][s16][0][1], off, on, off > 0 ? on / off : 0, b->agg_mf[c][s16][0][1]);
    }
    len = equal_ms_table(b, md, sizeof md, len);
    len += (size_t)snprintf(md + len, sizeof md - len, "\nRMSE per view (fixed R / depth-scaled R), %d samples, full resolution, mask off:\n\n| view | none |",
                            b->samples[s16]);
    for (int c = 0; c < NC; c++) len += (size_t)snprintf(md + len, sizeof md - len, " %s |", b->cs[c].label);
    len += (size_t)snprintf(md + len, sizeof md - len, "\n|---|---|");
    for (int c = 0; c < NC; c++) len += (size_t)snprintf(md + len, sizeof md - len, "---|");
    for (int v = 1; v <= b->nv; v++) {
        len += (size_t)snprintf(md + len, sizeof md - len, "\n| %s |", b->vd[v].name);
        for (int c = 0; c <= NC; c++)
            len += (size_t)snprintf(md + len, sizeof md - len, " %.4f / %.4f |", b->pv_rf[v][c], b->pv_rs[v][c]);
    }
    len += (size_t)snprintf(md + len, sizeof md - len, "\n");
    if (b->seq_frames > 0) {
        len += (size_t)snprintf(md + len, sizeof md - len,
                                "\nTemporal accumulation on the moving sequence %s (%d posed frames, %dx%d; RMSE against "
                                "each frame's depth-scaled reference; ms: AO passes between glFinish, median; parameters "
                                "tuned on '%s' and frozen). At equal ms: the per-frame RMSE (4, 8, 16 samples, second "
                                "half) interpolated in log ms at the accumulating run's ms, `*` = outside that curve:\n\n"
                                "| configuration | RMSE all frames | RMSE second half | ms | per-frame RMSE at equal ms |\n"
                                "|---|---|---|---|---|\n",
                                b->seq_name, b->seq_frames, b->w, b->h, b->vd[0].name);
        for (int m = 0; m < SEQ_METHODS; m++)
            for (int c = 0; c < SEQ_CFG; c++) {
                char eq[48] = "-";
                if (c == SEQ_CFG - 1) {
                    double xs[SEQ_CFG - 1], ys[SEQ_CFG - 1];
                    for (int q = 0; q < SEQ_CFG - 1; q++) xs[q] = b->seq_ms[m][q], ys[q] = b->seq_rmse[m][q][1];
                    bool out;
                    double e = interp_log(xs, ys, SEQ_CFG - 1, b->seq_ms[m][c], &out);
                    snprintf(eq, sizeof eq, "%.4f%s", e, out ? "*" : "");
                }
                len += (size_t)snprintf(md + len, sizeof md - len, "| %s %d%s | %.4f | %.4f | %.2f | %s |\n", k_seq_method[m],
                                        k_seq_samples[c], c == SEQ_CFG - 1 ? " + temporal" : "", b->seq_rmse[m][c][0],
                                        b->seq_rmse[m][c][1], b->seq_ms[m][c], eq);
            }
    }
    if (b->cost_rounds > 0) {
        static const char *const cfg[6] = {"full", "full + mips", "half", "half + mips", "full + deinterleave",
                                           "half + deinterleave"};
        len += (size_t)snprintf(md + len, sizeof md - len,
                                "\nCost towards the fetch floor, 16 samples, '%s' (medians of %d rounds side by side; load "
                                "average at the end: %s). x floor = AO passes (glFinish) / a pass of as many R32F fetches "
                                "per AO pixel and nothing else; RMSE against the depth-scaled reference:\n\n"
                                "| method | configuration | ms | floor ms | x floor | RMSE d-s |\n|---|---|---|---|---|---|\n",
                                b->cost_view, b->cost_rounds, b->loadavg[0] ? b->loadavg : "-");
        for (int m = 0; m < COST_METHODS; m++)
            for (int c = 0; c < 6; c++)
                len += (size_t)snprintf(md + len, sizeof md - len, "| %s | %s | %.2f | %.2f | %.2f | %.4f |\n", k_cost_method[m],
                                        cfg[c], b->cost_sync[m][c], b->cost_floor[m][c], b->cost_ratio[m][c], b->cost_rmse[m][c]);
        len += (size_t)snprintf(md + len, sizeof md - len,
                                "\nDeinterleaved 4 x 4, probed: the fetch floor of 16 fetches per pixel over %dx%d in one pass "
                                "%.2f ms, in 16 sub-image passes of a quarter the size and spread %.2f ms (x %.2f; each sub-pass "
                                "timed between glFinish).\n",
                                b->w, b->h, b->deint_full, b->deint_sub, b->deint_full > 0 ? b->deint_sub / b->deint_full : 0.0);
    }
    len += (size_t)snprintf(md + len, sizeof md - len, "\nAO passes against triangle count (scheer, 16 samples, %dx%d):\n\n"
                                                       "| triangles | AO GPU ms | G-buffer GPU ms |\n|---|---|---|\n", b->w, b->h);
    for (int i = 0; i < b->ntri; i++)
        len += (size_t)snprintf(md + len, sizeof md - len, "| %llu | %.2f | %.2f |\n", (unsigned long long)b->tri_count[i],
                                b->tri_ms[i], b->tri_gb[i]);
    if (b->p.out) fputs(md, b->p.out);
    mr_path_join(b->p.out_dir, "bench_ao.md", path, sizeof path);
    ok = mr_file_write_atomic(path, md, len, err);
    if (ok) BENCH_PRINT(b->p.out, "\nwrote %s/bench_ao.csv, bench_ao_tuning.csv, bench_ao_triangles.csv, bench_ao.svg, bench_ao_screen.svg, "
                   "bench_ao_montage.png (rows: views; columns: reference fixed R, reference depth-scaled R, then "
                   "%d methods at %d samples), bench_ao_shaded.png (Phong-shaded D1, D2, D3, scheer-paper), "
                   "bench_ao.md in %.0f s\n", b->p.out_dir, NC, b->samples[b->p.quick ? 0 : 1], mr_time_now() - b->t0);
    return ok;
}


static void ao_free(ao_bench *b) {
    for (int i = 0; i < b->nmont; i++)
        if (b->owned[i]) {
            mr_image_free(b->montage[i]);
            free(b->montage[i]);
        }
    for (int i = 0; i <= b->nv; i++) {
        mr_image_free(&b->vd[i].depth);
        mr_image_free(&b->vd[i].normal);
        mr_image_free(&b->vd[i].gt_fixed);
        mr_image_free(&b->vd[i].gt_screen);
    }
    mr_image_free(&b->ao);
    mr_eval_gt_destroy(&b->gt);
    if (b->gfx.renderer) mr_renderer_set_scene(b->gfx.renderer, NULL, NULL); /* the scene goes now */
    if (b->hall.planned) mr_demo_free(&b->hall);
    else mr_scene_destroy(&b->scene);
    free(b);
}

bool mr_bench_ao(const mr_bench_ao_params *params, mr_error *err) {
    const mr_bench_ao_params dflt = {MR_BENCH_AO_DEFAULTS};
    ao_bench *b = calloc(1, sizeof *b);
    if (!b) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    b->p = params ? *params : dflt;
    mr_bench_ao_params *p = &b->p;
    b->gfx = p->gfx;
    if (!bench_gpu_check(&b->gfx, "bench ao", err)) {
        free(b);
        return false;
    }
    if (!p->out_dir) p->out_dir = dflt.out_dir;
    if (p->width <= 0 || p->height <= 0) p->width = dflt.width, p->height = dflt.height;
    if (p->frames <= 0) p->frames = dflt.frames;
    if (p->frames > 64) p->frames = 64; /* run_ao keeps at most 64 samples */
    if (p->rays <= 0) p->rays = dflt.rays;
    b->w = p->width;
    b->h = p->height;
    b->radius = p->radius;
    b->screen_radius = p->screen_radius > 0 ? p->screen_radius : dflt.screen_radius;
    static const int samples_full[] = {8, 16, 32, 64}, samples_quick[] = {8, 32};
    b->samples = p->quick ? samples_quick : samples_full;
    b->nsamp = p->quick ? 2 : 4;
    b->nres = p->quick ? 1 : 2;
    b->s16 = p->quick ? 0 : 1;
    memcpy(b->cs, k_contenders, sizeof b->cs);
    for (int c = 0; c < NC; c++) b->cs[c].role = mr_ao_sk_role(b->cs[c].method, b->cs[c].mode);
    b->t0 = mr_time_now();
    bool ok = ao_setup(b, err) && ao_references(b, err) && ao_tune(b, err) && ao_grid(b, err) && ao_sk_tables(b, err) && ao_sampling(b, err) && ao_triangles(b, err) &&
              ao_plots(b, err) && ao_shaded(b, err) && ao_sequence(b, err) && ao_cost(b, err) &&
              ao_summary(b, err);
    ao_free(b);
    return ok;
}
