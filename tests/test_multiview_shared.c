/* The work a multi-view rig frame shares (issue 14, must have 5):
 *  - the union volume (mr_rig_cull_frustum) holds random points of every
 *    view's off-axis frustum, for rigs of 2..48 views, rotated cameras far
 *    from the origin; its left/right planes support the outer views (a
 *    point just outside lies outside every view); one view: its own frustum;
 *  - on the GPU (a hall with cubes close to the rig that only the outer
 *    views see, and poles casting shadows): a rig frame culls once for the G-buffer and draws one
 *    shadow map (cascaded), the other views reuse it; every view's depth is
 *    the same as its own independent render (the shared cull drops nothing
 *    a view sees) and its shadow buffer agrees with an independent render
 *    within a tolerance; per_view_work does all of it per view;
 *  - the layered experiment (one instanced draw into a viewport array)
 *    gives the quilt of depths the per-view loop gives. */
#include "mr_test.h"
#include "mr_test_scene.h"

#include "mr_render.h"

static double plane_dist(const mr_frustum *f, int k, mr_dvec3 p) {
    return f->planes[k][0] * p.x + f->planes[k][1] * p.y + f->planes[k][2] * p.z + f->planes[k][3];
}

/* The smallest plane distance of p (>= 0: inside). */
static double inside_by(const mr_frustum *f, mr_dvec3 p) {
    double m = INFINITY;
    for (int k = 0; k < f->plane_count; k++) m = fmin(m, plane_dist(f, k, p));
    return m;
}

/* A camera-frame point of view v at pixel (u, w) and depth z, in world. */
static mr_dvec3 view_point(const mr_view *v, double u, double w, double z) {
    const mr_camera *c = &v->camera;
    return mr_m4_point(&v->world_from_camera, mr_v3((u - c->cx) / c->fx * z, (w - c->cy) / c->fy * z, z));
}

static void test_union_conservative(void) {
    mr_rng rng;
    mr_rng_seed(&rng, 14);
    const int views[] = {2, 3, 8, 48};
    const double cones[] = {35, 10, 120, 170};
    const double offsets[] = {0, 1e3, 1e7};
    int bad = 0, checked = 0, loose = 0;
    double worst = 0;
    for (int vi = 0; vi < 4; vi++)
        for (int ci = 0; ci < 4; ci++)
            for (int oi = 0; oi < 3; oi++) {
                mr_rig_params p = MR_RIG_DEFAULTS;
                p.views = views[vi];
                p.cone_deg = cones[ci];
                p.fov_deg = 10 + 60 * mr_rng_uniform(&rng);
                double D = 0.5 + 20 * mr_rng_uniform(&rng), aspect = 0.5 + mr_rng_uniform(&rng);
                mr_rig rig;
                mr_error err = {0};
                CHECK_MSG(mr_rig_make(&p, aspect, D, &rig, &err), "%s", err.msg);
                int w = 40 + (int)(80 * mr_rng_uniform(&rng)), h = 30 + (int)(60 * mr_rng_uniform(&rng));
                mr_view centre;
                memset(&centre, 0, sizeof centre);
                mr_dvec3 eye = mr_v3(offsets[oi] + mr_rng_uniform(&rng), 2 * mr_rng_uniform(&rng), -offsets[oi]);
                mr_dvec3 at = mr_v3_add(eye, mr_v3(mr_rng_uniform(&rng) - 0.5, mr_rng_uniform(&rng) - 0.5, 1));
                centre.world_from_camera = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
                double near_plane = 0.01 + 0.1 * mr_rng_uniform(&rng), margin = 1.0;
                mr_frustum f = mr_rig_cull_frustum(&rig, &centre, w, h, near_plane, margin);
                double scale = 1 + offsets[oi];
                /* Random points of every view's frustum (its image widened
                 * by the margin), near to far. */
                for (int i = 0; i < rig.views; i++) {
                    mr_view v = mr_rig_view(&rig, &centre, i, w, h);
                    for (int k = 0; k < 200; k++) {
                        double u = -0.5 - margin + (w + 2 * margin) * mr_rng_uniform(&rng);
                        double t = -0.5 - margin + (h + 2 * margin) * mr_rng_uniform(&rng);
                        if (k < 8) { /* the corners exactly */
                            u = k & 1 ? w - 0.5 + margin : -0.5 - margin;
                            t = k & 2 ? h - 0.5 + margin : -0.5 - margin;
                        }
                        double z = near_plane * pow(1e6, mr_rng_uniform(&rng));
                        if (k == 8) z = near_plane;
                        mr_dvec3 pw = view_point(&v, u, t, z);
                        double d = inside_by(&f, pw);
                        checked++;
                        /* Rounding: relative to the point's magnitude. */
                        double tol = 1e-12 * (scale + z) * 64;
                        if (d < -tol) {
                            if (bad < 3)
                                fprintf(stderr, "  view %d/%d cone %g offset %g: point at z %g outside by %g\n", i,
                                        rig.views, cones[ci], offsets[oi], z, -d);
                            bad++;
                            worst = fmax(worst, -d);
                        }
                    }
                }
                /* Supporting: just outside the left plane at depth z, next
                 * to the last view's left edge, lies outside every view;
                 * the same for the right plane and view 0. */
                for (int side = 0; side < 2; side++) {
                    mr_view v = mr_rig_view(&rig, &centre, side == 0 ? rig.views - 1 : 0, w, h);
                    double z = 1e5 * D, u = side == 0 ? -0.5 - margin : w - 0.5 + margin;
                    mr_dvec3 pc = mr_v3((u - v.camera.cx) / v.camera.fx * z, 0, z);
                    /* Move it outwards along the camera x axis by 1e-3 of z. */
                    pc.x += (side == 0 ? -1 : 1) * 1e-3 * z;
                    mr_dvec3 pw = mr_m4_point(&v.world_from_camera, pc);
                    int in_any = 0;
                    for (int i = 0; i < rig.views; i++) {
                        mr_view vv = mr_rig_view(&rig, &centre, i, w, h);
                        mr_dmat4 cw = mr_m4_invert_rigid(&vv.world_from_camera);
                        mr_dvec3 q = mr_m4_point(&cw, pw);
                        double uu = vv.camera.fx * q.x / q.z + vv.camera.cx;
                        in_any += uu >= -0.5 - margin && uu <= w - 0.5 + margin;
                    }
                    CHECK_MSG(in_any == 0, "the test point is inside %d views", in_any);
                    /* ... and the union's plane is that close to it (not a
                     * needlessly wide volume): within 2e-3 of z. */
                    double d = plane_dist(&f, side, pw);
                    if (!(d < 0 && d > -2e-3 * z * 1.01 - 1e-9 * scale)) loose++;
                }
            }
    printf("union volume: %d points of %d views' frusta, %d outside (worst %g); %d loose sides\n", checked, 4, bad,
           worst, loose);
    CHECK_MSG(bad == 0, "%d frustum points outside the union volume", bad);
    CHECK_MSG(loose == 0, "%d sides of the union do not support the outer views", loose);

    /* One view: the union is the view's own frustum. */
    mr_rig_params p = MR_RIG_DEFAULTS;
    p.views = 1;
    mr_rig rig;
    mr_error err = {0};
    CHECK(mr_rig_make(&p, 1.3, 5, &rig, &err));
    mr_view centre;
    memset(&centre, 0, sizeof centre);
    centre.world_from_camera = mr_m4_look_at_cv(mr_v3(1, 2, 3), mr_v3(0, 0, 10), mr_v3(0, 1, 0));
    mr_view v = mr_rig_view(&rig, &centre, 0, 64, 48);
    mr_frustum a = mr_rig_cull_frustum(&rig, &centre, 64, 48, 0.1, 1.0);
    mr_frustum b = mr_frustum_from_camera(&v.camera, &v.world_from_camera, 0.1, 1.0);
    double diff = 0;
    for (int k = 0; k < 5; k++)
        for (int j = 0; j < 4; j++) diff = fmax(diff, fabs(a.planes[k][j] - b.planes[k][j]));
    CHECK_MSG(a.plane_count == 5 && diff < 1e-12, "one view's union differs from its frustum by %g", diff);
}

static void add_node(mr_scene *s, mr_dmat4 world, int32_t mesh) { mr_test_add_node(s, "n", world, mesh, MR_LAYER_VISIBLE); }

/* A floor, a back wall, boxes in a row across the whole width (some seen
 * by the outer views only) and poles that cast shadows. */
static mr_scene *hall(void) {
    mr_scene *s = mr_scene_create();
    add_node(s, mr_m4_translate(0, -0.1, 4), mr_test_add_box(s, 40, 0.2, 30, -1));
    add_node(s, mr_m4_translate(0, 3, 9), mr_test_add_box(s, 40, 6, 0.2, -1));
    int32_t box = mr_test_add_box(s, 0.5, 0.5, 0.5, -1), pole = mr_test_add_box(s, 0.15, 2.0, 0.15, -1);
    for (int i = -12; i <= 12; i++) add_node(s, mr_m4_translate(0.55 * i, 0.25, 3.0 + 0.1 * (i & 3)), box);
    for (int i = -4; i <= 4; i++) add_node(s, mr_m4_translate(1.3 * i + 0.3, 1.0, 5.0), pole);
    /* Near the rig (1.5 in front of it, the focal plane at 5): the outer
     * views see further sideways than the centre one. */
    int32_t cube = mr_test_add_box(s, 0.12, 0.12, 0.12, -1);
    for (int i = -10; i <= 10; i++) add_node(s, mr_m4_translate(0.2 * i, 1.45, -0.5), cube);
    mr_scene_update_bounds(s);
    return s;
}

typedef struct shot {
    mr_image depth, shadow;
    char passes[256];
    uint32_t culls;
    bool reused;
} shot;

static bool shoot(mr_renderer *r, const mr_view *v, const mr_frame_params *fp, shot *out) {
    mr_error err = {0};
    mr_frame_result res;
    memset(out, 0, sizeof *out);
    if (!mr_render_frame(r, v, fp, &res, &err)) {
        CHECK_MSG(false, "render: %s", err.msg);
        return false;
    }
    out->depth = res.depth;
    out->shadow = res.shadow;
    memset(&res.depth, 0, sizeof res.depth);
    memset(&res.shadow, 0, sizeof res.shadow);
    mr_frame_result_passes(&res, out->passes, sizeof out->passes);
    out->reused = res.shadow_reused;
    mr_draw_stats ds;
    mr_renderer_draw_stats(r, &ds);
    out->culls = ds.frustum_culls;
    mr_frame_result_free(&res);
    return out->depth.data && out->shadow.data;
}

static void shot_free(shot *s) {
    mr_image_free(&s->depth);
    mr_image_free(&s->shadow);
}

static int test_gpu(void) {
    mr_error err = {0};
    mr_gpu_params gp = MR_GPU_DEFAULTS;
    mr_gpu *gpu = mr_gpu_create_headless(&gp, &err);
    if (!gpu) return mr_test_no_gpu("test_multiview_shared", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    mr_scene *s = hall();
    CHECK(mr_renderer_set_scene(r, s, &err));
    enum { W = 64, H = 48, N = 8, CASC = 3 };
    mr_view centre;
    memset(&centre, 0, sizeof centre);
    centre.world_from_camera = mr_m4_look_at_cv(mr_v3(0, 1.8, -2.0), mr_v3(0, 0.5, 4.0), mr_v3(0, 1, 0));
    mr_rig_params rp = MR_RIG_DEFAULTS;
    rp.views = N;
    rp.fov_deg = 40;
    rp.cone_deg = 40;
    mr_rig rig;
    CHECK(mr_rig_make(&rp, (double)W / H, 5.0, &rig, &err));
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = W;
    fp.height = H;
    fp.want_depth = true;
    fp.shadow.method = MR_SHADOW_HARD;
    fp.shadow.want_shadow = true;
    fp.shadow.cascades = CASC;
    fp.shadow.map_size = 512;

    /* The rig frame: one cull and one shadow map. */
    shot sh[N], ind[N];
    CHECK_MSG(mr_render_rig_begin(r, &rig, &centre, W, H, &err), "%s", err.msg);
    int maps = 0;
    uint32_t culls = 0;
    for (int i = 0; i < N; i++) {
        mr_view v = mr_rig_view(&rig, &centre, i, W, H);
        shoot(r, &v, &fp, &sh[i]);
        maps += strstr(sh[i].passes, "shadow_map") != NULL;
        culls += sh[i].culls;
        CHECK_MSG(i == 0 || sh[i].reused, "view %d drew its own shadow map: %s", i, sh[i].passes);
    }
    mr_render_rig_end(r);
    printf("rig frame of %d views: %d shadow map passes, %u frustum culls (view 0: %s)\n", N, maps, culls, sh[0].passes);
    CHECK_MSG(maps == 1, "%d shadow map passes in one rig frame", maps);
    CHECK_MSG(culls == 1 + CASC, "%u frustum culls in one rig frame (want 1 + %d cascades)", culls, CASC);

    /* Every view alone: its own cull and maps. */
    for (int i = 0; i < N; i++) {
        mr_view v = mr_rig_view(&rig, &centre, i, W, H);
        shoot(r, &v, &fp, &ind[i]);
        CHECK(!ind[i].reused && strstr(ind[i].passes, "shadow_map") && ind[i].culls == 1 + CASC);
    }
    int depth_bad = 0, surf_total = 0;
    double worst_mean = 0, worst_frac = 0, sum_sh = 0;
    for (int i = 0; i < N; i++) {
        if (!sh[i].depth.data || !ind[i].depth.data) continue;
        const float *da = sh[i].depth.data, *db = ind[i].depth.data, *sa = sh[i].shadow.data, *sb = ind[i].shadow.data;
        double sum = 0;
        int n = 0, off = 0;
        for (int k = 0; k < W * H; k++) {
            depth_bad += da[k] != db[k];
            if (!(db[k] > 0)) continue;
            double d = fabs((double)sa[k] - sb[k]);
            sum += d;
            off += d > 0.5;
            sum_sh += 1 - sa[k];
            n++;
        }
        surf_total += n;
        if (n) {
            worst_mean = fmax(worst_mean, sum / n);
            worst_frac = fmax(worst_frac, (double)off / n);
        }
    }
    printf("shared vs independent views: %d depth pixels differ; shadow: worst view mean |diff| %.4f, %.3f of its "
           "pixels flipped; mean shadow %.3f over %d pixels\n",
           depth_bad, worst_mean, worst_frac, sum_sh / (surf_total ? surf_total : 1), surf_total);
    CHECK_MSG(depth_bad == 0, "%d depth pixels differ between the shared cull and each view's own", depth_bad);
    CHECK_MSG(surf_total > N * W * H / 2, "the views see little: %d surface pixels", surf_total);
    /* Something is in shadow, or the comparison says nothing. */
    CHECK_MSG(sum_sh / surf_total > 0.02, "almost nothing is in shadow (%.3f)", sum_sh / surf_total);
    /* The shared map's texels lie elsewhere than each view's own: edges may
     * move by a texel, nothing more. */
    CHECK_MSG(worst_mean < 0.02 && worst_frac < 0.03, "shared shadow maps differ: mean %.4f, %.3f flipped", worst_mean,
              worst_frac);

    /* mr_render_rig counts the same; per_view_work does everything N times. */
    mr_quilt_layout l;
    CHECK(mr_quilt_layout_make(NULL, N, W, H, &l, &err));
    mr_image q1 = {0}, q2 = {0};
    mr_rig_result r1, r2;
    fp.want_depth = fp.shadow.want_shadow = false;
    CHECK_MSG(mr_render_rig(r, &rig, &centre, &fp, &l, NULL, &q1, &r1, &err), "%s", err.msg);
    mr_rig per = rig;
    per.per_view_work = true;
    CHECK_MSG(mr_render_rig(r, &per, &centre, &fp, &l, NULL, &q2, &r2, &err), "%s", err.msg);
    printf("mr_render_rig: shared %d culls, %d maps; per view %d culls, %d maps\n", r1.frustum_culls, r1.shadow_maps,
           r2.frustum_culls, r2.shadow_maps);
    CHECK(r1.shadow_maps == 1 && r1.frustum_culls == 1 + CASC);
    CHECK(r2.shadow_maps == N && r2.frustum_culls == N * (1 + CASC));
    mr_image_free(&q1);
    mr_image_free(&q2);

    /* The layered experiment draws what the per-view loop draws: the same
     * quilt of depths (the eye shift is applied in float on the GPU rather
     * than in double per instance: a few ulps). 17 views: a batch of 16
     * and one of 1. */
    for (int nv = 8; nv <= 17; nv += 9) {
        mr_rig r17;
        rp.views = nv;
        CHECK(mr_rig_make(&rp, (double)W / H, 5.0, &r17, &err));
        mr_image dl = {0}, dp = {0};
        double ms[2];
        bool ok = mr_rig_geometry_time(r, &r17, &centre, W, H, false, 1, &ms[0], &dl, &err) &&
                  mr_rig_geometry_time(r, &r17, &centre, W, H, true, 1, &ms[1], &dp, &err);
        CHECK_MSG(ok, "layered experiment: %s", err.msg);
        if (ok) {
            const float *a = dl.data, *b = dp.data;
            int differ = 0, covered = 0;
            for (size_t k = 0; k < (size_t)dl.width * dl.height; k++) {
                covered += a[k] > 0;
                differ += fabsf(a[k] - b[k]) > 1e-5f * fmaxf(a[k], 1e-3f);
            }
            printf("layered vs per-view loop, %d views: %d of %d quilt pixels differ, %d covered (%.1f vs %.1f ms)\n", nv,
                   differ, dl.width * dl.height, covered, ms[1], ms[0]);
            CHECK_MSG(covered > nv * W * H / 2, "the quilt is mostly empty: %d", covered);
            CHECK_MSG(differ <= covered / 200, "%d quilt pixels differ between layered and per-view", differ);
        }
        mr_image_free(&dl);
        mr_image_free(&dp);
    }

    for (int i = 0; i < N; i++) shot_free(&sh[i]), shot_free(&ind[i]);
    CHECK(mr_renderer_set_scene(r, NULL, &err));
    mr_scene_destroy(&s);
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    return 0;
}

int main(void) {
    test_union_conservative();
    int rc = test_gpu();
    if (rc) return rc;
    return mr_test_finish("test_multiview_shared");
}
