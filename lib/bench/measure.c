/* bench measure: what a measured point is worth to a verdict. Synthetic
 * halls with known tag poses; the marker map from photos (projected
 * corners with noise) with control points; feature points with known
 * built deviations tapped in frames whose poses are solved against that
 * map; the triangulated point's deviation from the plan, its predicted
 * sigma, the 95 % interval's coverage and the verdict against a tolerance.
 * Occlusion is not modelled: a tag is seen when its corners fall in the
 * frame, it faces the camera and its edge is long enough. */
#include "bench_internal.h"
#include "mr_bench.h"
#include "mr_scene.h"
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_HALL_TAGS 128
#define SEEN_MIN_EDGE_PX 12.0
#define SEEN_MIN_COS 0.3
#define SEEN_MAX_DIST 25.0
#define CONTROL_SIGMA 0.001 /* m: a total station's control points */
#define VERDICT_K 2.0       /* the 95 % interval (DESIGN.md: k = 2) */

static const double k_devs_mm[] = {0, 5, 10, 20, 50};
#define NDEV 5

typedef struct hall_t {
    const char *name;
    mr_marker tags[MAX_HALL_TAGS];
    int count;
    double tag_size;
    double lo[2], hi[2]; /* x, z bounds of the places a camera stands */
    int controls[4];     /* tag indices of the control points */
} hall_t;

/* One row of the table: the hall and what varies. */
typedef struct row_t {
    int hall;            /* 0: 30 x 20 m columns, 1: the demo hall */
    double tag_m;        /* 0: the hall's own */
    int photos;
    int map_w, map_h;
    int trk_w, trk_h;
    double dist_m;
    int taps;
} row_t;

static const row_t k_rows[] = {
    {0, 0.3, 100, 4000, 3000, 1920, 1080, 5, 4},  /* the base configuration */
    {0, 0.3, 100, 4000, 3000, 1920, 1080, 2, 4},  {0, 0.3, 100, 4000, 3000, 1920, 1080, 10, 4},
    {0, 0.3, 100, 4000, 3000, 1920, 1080, 15, 4}, {0, 0.3, 100, 4000, 3000, 640, 480, 5, 4},
    {0, 0.3, 100, 4000, 3000, 1920, 1080, 5, 2},  {0, 0.3, 100, 4000, 3000, 1920, 1080, 5, 6},
    {0, 0.3, 50, 4000, 3000, 1920, 1080, 5, 4},   {0, 0.3, 20, 4000, 3000, 1920, 1080, 5, 4},
    {0, 0.3, 100, 1280, 960, 1920, 1080, 5, 4},   {0, 0.15, 100, 4000, 3000, 1920, 1080, 5, 4},
    {1, 0, 50, 4000, 3000, 1920, 1080, 5, 4},
};
#define NROWS ((int)(sizeof k_rows / sizeof k_rows[0]))
#define QUICK_ROWS 4 /* base and the distances */

/* A tag at c whose surface normal (out of the wall) is n. */
static mr_marker tag_at(int id, mr_dvec3 c, mr_dvec3 n) {
    return (mr_marker){.id = id, .world_from_tag = mr_m4_look_at_cv(c, mr_v3_sub(c, n), mr_v3(0, 1, 0))};
}

/* 30 x 20 m, 15 columns (0.5 m) on a 6 x 6 m grid, a tag on each face at
 * 1.6 m; control points on the corner columns. */
static void hall_columns(double tag_size, hall_t *h) {
    memset(h, 0, sizeof *h);
    h->name = "30x20 m";
    h->tag_size = tag_size;
    static const mr_dvec3 faces[4] = {{1, 0, 0}, {0, 0, 1}, {-1, 0, 0}, {0, 0, -1}};
    for (int cz = 0; cz < 3; cz++)
        for (int cx = 0; cx < 5; cx++)
            for (int f = 0; f < 4; f++) {
                mr_dvec3 c = mr_v3(3 + 6 * cx + 0.25 * faces[f].x, 1.6, 4 + 6 * cz + 0.25 * faces[f].z);
                h->tags[h->count] = tag_at(h->count, c, faces[f]);
                h->count++;
            }
    /* Columns (0,0), (4,0), (0,2), (4,2), a face towards the hall each. */
    h->controls[0] = 4 * 0 + 0, h->controls[1] = 4 * 4 + 2, h->controls[2] = 4 * 10 + 3, h->controls[3] = 4 * 14 + 1;
    h->lo[0] = 0.5, h->hi[0] = 29.5, h->lo[1] = 0.5, h->hi[1] = 19.5;
}

static bool hall_demo(double tag_size, hall_t *h, mr_error *err) {
    memset(h, 0, sizeof *h);
    mr_demo_hall d;
    if (!mr_demo_build(NULL, &d, err)) return false;
    h->name = "demo";
    h->tag_size = tag_size > 0 ? tag_size : d.tag_size;
    h->lo[0] = h->lo[1] = INFINITY, h->hi[0] = h->hi[1] = -INFINITY;
    for (int i = 0; i < d.tag_count && h->count < MAX_HALL_TAGS; i++) {
        h->tags[h->count++] = (mr_marker){.id = d.tags[i].id, .world_from_tag = d.tags[i].world_from_tag};
        const double *m = d.tags[i].world_from_tag.m;
        h->lo[0] = fmin(h->lo[0], m[3]), h->hi[0] = fmax(h->hi[0], m[3]);
        h->lo[1] = fmin(h->lo[1], m[11]), h->hi[1] = fmax(h->hi[1], m[11]);
    }
    mr_demo_free(&d);
    for (int a = 0; a < 2; a++) h->lo[a] += 1, h->hi[a] -= 1;
    for (int q = 0; q < 4; q++) h->controls[q] = q * h->count / 4;
    return h->count >= 4;
}

static mr_camera pinhole(int w, int h) {
    mr_camera c = {0};
    c.width = w, c.height = h;
    c.fx = c.fy = 0.8 * w; /* about 64 degrees across */
    c.cx = 0.5 * (w - 1), c.cy = 0.5 * (h - 1);
    return c;
}

/* The tags camera wfc sees, corners projected with noise_px Gaussian
 * noise. Returns the count. */
static int see_tags(const hall_t *h, const mr_camera *cam, const mr_dmat4 *wfc, double noise_px, mr_rng *rng,
                    mr_detection *out) {
    mr_marker_map map = {.family = "tag36h11", .tag_size = h->tag_size, .tags = (mr_marker *)h->tags, .count = h->count};
    mr_dvec3 eye = mr_v3(wfc->m[3], wfc->m[7], wfc->m[11]);
    int n = 0;
    for (int i = 0; i < h->count; i++) {
        const double *m = h->tags[i].world_from_tag.m;
        mr_dvec3 c = mr_v3(m[3], m[7], m[11]), out_n = mr_v3(-m[2], -m[6], -m[10]), to = mr_v3_sub(eye, c);
        double dist = mr_v3_len(to);
        if (dist > SEEN_MAX_DIST || mr_v3_dot(out_n, to) < SEEN_MIN_COS * dist) continue;
        mr_dvec3 w[4];
        mr_marker_corners_world(&map, &h->tags[i], w);
        mr_detection d = {.id = h->tags[i].id};
        bool in = true;
        for (int k = 0; k < 4 && in; k++) {
            double u, v;
            in = mr_project_point(cam, wfc, w[k], &u, &v) && u > 0 && v > 0 && u < cam->width - 1 &&
                 v < cam->height - 1;
            d.corners[k][0] = u, d.corners[k][1] = v;
        }
        double edge = INFINITY;
        for (int k = 0; in && k < 4; k++)
            edge = fmin(edge, hypot(d.corners[(k + 1) % 4][0] - d.corners[k][0], d.corners[(k + 1) % 4][1] - d.corners[k][1]));
        if (!in || edge < SEEN_MIN_EDGE_PX) continue;
        for (int k = 0; k < 4; k++) {
            d.corners[k][0] += noise_px * mr_rng_normal(rng);
            d.corners[k][1] += noise_px * mr_rng_normal(rng);
        }
        out[n++] = d;
    }
    return n;
}

typedef struct built_map {
    mr_marker_map markers;
    double err_rms_mm, sigma_med_mm, z_rms; /* z: RMS of a tag's error / its sigma */
    double tags;                            /* share of the seen tags mapped */
    bool ok;
} built_map;

/* The map from `photos` random photos standing in the hall, with the
 * control points (measured with CONTROL_SIGMA noise). */
static bool build_map(const hall_t *h, const row_t *r, double noise_px, uint64_t seed, built_map *bm, mr_error *err) {
    memset(bm, 0, sizeof *bm);
    mr_rng rng;
    mr_rng_seed(&rng, seed);
    mr_camera cam = pinhole(r->map_w, r->map_h);
    mr_detection *dets = malloc((size_t)r->photos * MAX_HALL_TAGS * sizeof *dets);
    mr_map_photo *ph = calloc((size_t)r->photos, sizeof *ph);
    if (!dets || !ph) {
        free(dets);
        free(ph);
        return mr_fail(err, MR_ERR_NOMEM, "bench measure: out of memory");
    }
    for (int j = 0; j < r->photos; j++) {
        /* As a person maps a hall: each photo aimed near a tag, 2..8 m
         * from it, within 50 degrees of its normal, so that its
         * neighbours come into view too. */
        const double *m = h->tags[(int)(h->count * mr_rng_uniform(&rng))].world_from_tag.m;
        mr_dvec3 c = mr_v3(m[3], m[7], m[11]), out_n = mr_v3(-m[2], -m[6], -m[10]);
        double a = atan2(out_n.z, out_n.x) + (100 * mr_rng_uniform(&rng) - 50) * M_PI / 180, d = 2 + 6 * mr_rng_uniform(&rng);
        mr_dvec3 eye = mr_v3(c.x + d * cos(a), 1.2 + 0.6 * mr_rng_uniform(&rng), c.z + d * sin(a));
        mr_dvec3 at = mr_v3(c.x + 2 * (mr_rng_uniform(&rng) - 0.5), c.y, c.z + 2 * (mr_rng_uniform(&rng) - 0.5));
        mr_dmat4 wfc = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
        ph[j].dets = &dets[(size_t)j * MAX_HALL_TAGS];
        ph[j].count = see_tags(h, &cam, &wfc, noise_px, &rng, (mr_detection *)ph[j].dets);
    }
    mr_map_control ctl[4];
    for (int q = 0; q < 4; q++) {
        const double *m = h->tags[h->controls[q]].world_from_tag.m;
        ctl[q] = (mr_map_control){.tag_id = h->tags[h->controls[q]].id, .corner = -1, .sigma = CONTROL_SIGMA};
        snprintf(ctl[q].name, sizeof ctl[q].name, "P%d", q + 1);
        ctl[q].world = mr_v3(m[3] + CONTROL_SIGMA * mr_rng_normal(&rng), m[7] + CONTROL_SIGMA * mr_rng_normal(&rng),
                             m[11] + CONTROL_SIGMA * mr_rng_normal(&rng));
    }
    mr_map_params mp = MR_MAP_DEFAULTS;
    mp.tag_size = h->tag_size;
    mp.controls = ctl;
    mp.control_count = 4;
    mr_map_result res;
    mr_error e2 = {0};
    bm->ok = mr_map_build(&cam, ph, r->photos, &mp, &res, &e2);
    free(dets);
    free(ph);
    if (!bm->ok) {
        mr_log(MR_LOG_INFO, "bench measure: map of %d photos (seed %llu): %s", r->photos, (unsigned long long)seed,
               e2.msg);
        return true;
    }
    double ss = 0, zz = 0, *sg = malloc((size_t)res.tag_count * sizeof *sg);
    int n = 0, nz = 0;
    for (int i = 0; i < res.tag_count; i++) {
        const mr_marker *t = NULL;
        for (int k = 0; k < h->count; k++)
            if (h->tags[k].id == res.tags[i].id) t = &h->tags[k];
        if (!t) continue;
        double d = mr_pose_dist(&res.tags[i].world_from_tag, &t->world_from_tag);
        if (res.tags[i].sigma_pos > 0 && isfinite(res.tags[i].sigma_pos)) {
            zz += d * d / (res.tags[i].sigma_pos * res.tags[i].sigma_pos);
            nz++;
        }
        ss += d * d;
        if (sg && isfinite(res.tags[i].sigma_pos)) sg[n++] = 1e3 * res.tags[i].sigma_pos;
    }
    bm->err_rms_mm = res.tag_count ? 1e3 * sqrt(ss / res.tag_count) : NAN;
    bm->sigma_med_mm = n ? mr_median(sg, n) : NAN;
    bm->z_rms = nz ? sqrt(zz / nz) : NAN;
    bm->tags = (double)res.tag_count / (res.tag_count + res.unplaced_count + res.unconnected_count);
    free(sg);
    bm->ok = mr_map_result_markers(&res, "tag36h11", h->tag_size, &bm->markers, err);
    mr_map_result_free(&res);
    return bm->ok;
}

/* One measured deviation: its value and predicted sigma along the plan's
 * normal n, and the point's error and 3D sigma. */
typedef struct sample_t {
    double truth_mm, dev_mm, sigma_mm, err_mm, sigma3_mm;
    bool ok;
} sample_t;

/* The feature at p (built; the plan has it dev_mm back along n) tapped
 * from r->taps places r->dist_m away on a 30 degree arc within 40
 * degrees of `face` (radians about y), each pose solved against the map.
 * Tries a few directions until every frame has a pose. */
static void measure_point(const hall_t *h, const built_map *bm, const row_t *r, mr_dvec3 p, double face, mr_dvec3 n,
                          double dev_mm, double track_noise, double tap_px, mr_rng *rng, sample_t *s) {
    memset(s, 0, sizeof *s);
    s->truth_mm = dev_mm;
    mr_camera cam = pinhole(r->trk_w, r->trk_h);
    for (int attempt = 0; attempt < 20 && !s->ok; attempt++) {
        double yaw0 = face + (80 * mr_rng_uniform(rng) - 40) * M_PI / 180, spread = 30 * M_PI / 180;
        mr_tap taps[8];
        mr_pose poses[8];
        int m = 0;
        for (int k = 0; k < r->taps; k++) {
            double yaw = yaw0 + spread * ((double)k / (r->taps - 1) - 0.5);
            mr_dvec3 eye = mr_v3(p.x + r->dist_m * cos(yaw), 1.5, p.z + r->dist_m * sin(yaw));
            if (eye.x < h->lo[0] - 1 || eye.x > h->hi[0] + 1 || eye.z < h->lo[1] - 1 || eye.z > h->hi[1] + 1) break;
            mr_dmat4 wfc = mr_m4_look_at_cv(eye, p, mr_v3(0, 1, 0));
            mr_detection det[MAX_HALL_TAGS];
            int nd = see_tags(h, &cam, &wfc, track_noise, rng, det);
            mr_error e = {0};
            /* Each place is solved alone; a tracker knows the corner
             * noise from its multi-tag frames (mr_tracker learns it). */
            mr_pose_params pp = MR_POSE_DEFAULTS;
            pp.corner_sigma_px = track_noise;
            if (!mr_pose_solve(&cam, &bm->markers, det, nd, NULL, &pp, &poses[m], &e) || !poses[m].valid) break;
            double u, v;
            if (!mr_project_point(&cam, &wfc, p, &u, &v)) break;
            taps[m] = (mr_tap){poses[m].world_from_camera, poses[m].cov,
                               {u + tap_px * mr_rng_normal(rng), v + tap_px * mr_rng_normal(rng)}, poses[m].cov_map};
            m++;
        }
        if (m < r->taps) continue;
        mr_triangulate_params tp = MR_TRIANGULATE_DEFAULTS;
        tp.tap_sigma_px = tap_px;
        mr_triangulation t;
        mr_error e = {0};
        if (!mr_triangulate(&cam, taps, m, &tp, &t, &e)) continue;
        mr_dvec3 planned = mr_v3_sub(p, mr_v3_scale(n, 1e-3 * dev_mm));
        double nn[3] = {n.x, n.y, n.z}, var = 0;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) var += nn[a] * t.cov[3 * a + b] * nn[b];
        s->dev_mm = 1e3 * mr_v3_dot(mr_v3_sub(t.point, planned), n);
        s->sigma_mm = 1e3 * sqrt(fmax(var, 0));
        s->err_mm = 1e3 * mr_v3_len(mr_v3_sub(t.point, p));
        s->sigma3_mm = 1e3 * t.sigma;
        s->ok = isfinite(s->dev_mm) && s->sigma_mm > 0;
    }
}

/* Within (0), out of tolerance (1) or undecided (2) at k = VERDICT_K. */
static int verdict(double dev_mm, double sigma_mm, double tol_mm) {
    if (fabs(dev_mm) + VERDICT_K * sigma_mm <= tol_mm) return 0;
    if (fabs(dev_mm) - VERDICT_K * sigma_mm > tol_mm) return 1;
    return 2;
}

typedef struct row_acc {
    sample_t *s;         /* maps x points x NDEV */
    int n, failed;
    double map_err[16], map_sig[16], map_z[16], map_tags[16];
    int nmaps;
} row_acc;

static bool same_map(const row_t *a, const row_t *b) {
    return a->hall == b->hall && a->tag_m == b->tag_m && a->photos == b->photos && a->map_w == b->map_w &&
           a->map_h == b->map_h;
}

typedef struct row_stats {
    double err_med, sig_med, sig3_med, z_rms, cover, share[3], correct_at[NDEV], wrong_at[NDEV], map_err, map_sig,
        map_z, map_tags;
    int n, failed;
} row_stats;

static void row_summary(row_acc *a, double tol_mm, row_stats *st) {
    memset(st, 0, sizeof *st);
    st->n = a->n, st->failed = a->failed;
    double *v = malloc((size_t)(a->n + 1) * 3 * sizeof *v);
    if (!v) return;
    double *e = v, *sg = v + a->n + 1, *s3 = v + 2 * (a->n + 1), zz = 0;
    int in = 0, nat[NDEV] = {0};
    for (int i = 0; i < a->n; i++) {
        const sample_t *s = &a->s[i];
        int di = 0;
        while (di < NDEV - 1 && k_devs_mm[di] != s->truth_mm) di++;
        double truth = s->truth_mm, z = (s->dev_mm - truth) / s->sigma_mm;
        e[i] = s->err_mm, sg[i] = s->sigma_mm, s3[i] = s->sigma3_mm;
        zz += z * z;
        in += fabs(z) <= VERDICT_K;
        int vd = verdict(s->dev_mm, s->sigma_mm, tol_mm), want = truth <= tol_mm ? 0 : 1;
        int kind = vd == 2 ? 1 : vd == want ? 0 : 2; /* correct, undecided, wrong */
        st->share[kind] += 1;
        nat[di]++;
        st->correct_at[di] += kind == 0;
        st->wrong_at[di] += kind == 2;
    }
    if (a->n > 0) {
        st->err_med = mr_median(e, a->n);
        st->sig_med = mr_median(sg, a->n);
        st->sig3_med = mr_median(s3, a->n);
        st->z_rms = sqrt(zz / a->n);
        st->cover = (double)in / a->n;
        for (int k = 0; k < 3; k++) st->share[k] /= a->n;
    } else {
        st->err_med = st->sig_med = st->sig3_med = st->z_rms = st->cover = NAN;
    }
    for (int d = 0; d < NDEV; d++) {
        st->correct_at[d] = nat[d] ? st->correct_at[d] / nat[d] : NAN;
        st->wrong_at[d] = nat[d] ? st->wrong_at[d] / nat[d] : NAN;
    }
    st->map_err = a->nmaps ? mr_median(a->map_err, a->nmaps) : NAN;
    st->map_sig = a->nmaps ? mr_median(a->map_sig, a->nmaps) : NAN;
    st->map_z = a->nmaps ? mr_median(a->map_z, a->nmaps) : NAN;
    st->map_tags = a->nmaps ? mr_median(a->map_tags, a->nmaps) : NAN;
    free(v);
}

/* All rows over one map seed: maps are built once per distinct map and
 * reused by the rows after it that share it. */
static bool run_seed(const mr_bench_measure_params *p, int nrows, uint64_t seed, row_acc *acc, mr_error *err) {
    built_map bm = {0};
    int have = -1;
    bool ok = true;
    for (int ri = 0; ok && ri < nrows; ri++) {
        const row_t *r = &k_rows[ri];
        hall_t h;
        if (r->hall == 0)
            hall_columns(r->tag_m, &h);
        else if (!hall_demo(r->tag_m, &h, err))
            return false;
        if (have < 0 || !same_map(&k_rows[have], r)) {
            mr_marker_map_free(&bm.markers);
            ok = build_map(&h, r, p->noise_px, seed * 1000 + (uint64_t)ri, &bm, err);
            have = ri;
            if (p->out && p->progress) fprintf(stderr, "bench measure: seed %llu row %d map %.2f mm\n",
                                               (unsigned long long)seed, ri, bm.err_rms_mm);
        }
        if (!ok) break;
        row_acc *a = &acc[ri];
        if (!bm.ok) {
            a->failed += p->points * NDEV;
            continue;
        }
        if (a->nmaps < 16) {
            a->map_err[a->nmaps] = bm.err_rms_mm, a->map_sig[a->nmaps] = bm.sigma_med_mm;
            a->map_z[a->nmaps] = bm.z_rms, a->map_tags[a->nmaps++] = bm.tags;
        }
        mr_rng rng;
        mr_rng_seed(&rng, seed * 7919 + (uint64_t)ri);
        for (int pi = 0; pi < p->points; pi++) {
            /* A feature on the structure near a tag (within 1.5 m along
             * the wall, 0.3..3 m up, 0.3 m out of it), tapped from the
             * side the tag faces. */
            const double *m = h.tags[(int)(h.count * mr_rng_uniform(&rng))].world_from_tag.m;
            mr_dvec3 out_n = mr_v3(-m[2], -m[6], -m[10]), along = mr_v3(m[0], m[4], m[8]);
            mr_dvec3 pt = mr_v3_add(mr_v3(m[3], 0.3 + 2.7 * mr_rng_uniform(&rng), m[11]),
                                    mr_v3_add(mr_v3_scale(along, 3 * (mr_rng_uniform(&rng) - 0.5)), mr_v3_scale(out_n, 0.3)));
            double face = atan2(out_n.z, out_n.x), a_n = 2 * M_PI * mr_rng_uniform(&rng);
            mr_dvec3 n = mr_v3(cos(a_n), 0, sin(a_n));
            for (int di = 0; di < NDEV; di++) {
                sample_t s;
                measure_point(&h, &bm, r, pt, face, n, k_devs_mm[di], p->track_noise_px, p->tap_px, &rng, &s);
                if (s.ok)
                    a->s[a->n++] = s;
                else
                    a->failed++;
            }
        }
    }
    mr_marker_map_free(&bm.markers);
    return ok;
}

static void csv_row(mr_csv *csv, const row_t *r, const char *hall, double tag_m, const row_stats *st) {
    char res[2][32];
    snprintf(res[0], sizeof res[0], "%dx%d", r->map_w, r->map_h);
    snprintf(res[1], sizeof res[1], "%dx%d", r->trk_w, r->trk_h);
    mr_csv_text(csv, hall);
    mr_csv_num(csv, "%.3f", tag_m);
    mr_csv_int(csv, r->photos);
    mr_csv_text(csv, res[0]);
    mr_csv_text(csv, res[1]);
    mr_csv_num(csv, "%.1f", r->dist_m);
    mr_csv_int(csv, r->taps);
    mr_csv_int(csv, st->n);
    mr_csv_int(csv, st->failed);
    mr_csv_num(csv, "%.3f", st->map_err);
    mr_csv_num(csv, "%.3f", st->map_sig);
    mr_csv_num(csv, "%.2f", st->map_z);
    mr_csv_num(csv, "%.3f", st->map_tags);
    mr_csv_num(csv, "%.2f", st->err_med);
    mr_csv_num(csv, "%.2f", st->sig_med);
    mr_csv_num(csv, "%.2f", st->sig3_med);
    mr_csv_num(csv, "%.3f", st->z_rms);
    mr_csv_num(csv, "%.3f", st->cover);
    for (int k = 0; k < 3; k++) mr_csv_num(csv, "%.3f", st->share[k]);
    mr_csv_num(csv, "%.3f", st->correct_at[0]);
    mr_csv_num(csv, "%.3f", st->wrong_at[0]);
    mr_csv_num(csv, "%.3f", st->correct_at[NDEV - 1]);
    mr_csv_num(csv, "%.3f", st->wrong_at[NDEV - 1]);
    mr_csv_end_row(csv);
}

static bool write_plot(const mr_bench_measure_params *p, const row_stats *st, int nrows, mr_error *err) {
    /* The distance rows of the base configuration: rows 1, 0, 2, 3. */
    static const int dist_rows[4] = {1, 0, 2, 3};
    double xs[4], ye[4], ys[4];
    int n = 0;
    for (int i = 0; i < 4; i++) {
        if (dist_rows[i] >= nrows) continue;
        xs[n] = k_rows[dist_rows[i]].dist_m;
        ye[n] = st[dist_rows[i]].err_med;
        ys[n++] = st[dist_rows[i]].sig_med;
    }
    mr_plot_series ser[2] = {{.name = "observed: median point error (mm)", .x = xs, .y = ye, .count = n},
                             {.name = "predicted: median 1-sigma of the deviation (mm)", .x = xs, .y = ys, .count = n,
                              .dashed = true, .mark = MR_PLOT_MARK_SQUARE}};
    char note[160];
    snprintf(note, sizeof note, "30x20 m hall, 0.3 m tags, 100 photos 4000x3000, 1920x1080 taps x4, %.1f px taps",
             p->tap_px);
    const char *notes[1] = {note};
    mr_plot_params pp = {.title = "a measured point: error and predicted sigma against distance",
                         .xlabel = "distance to the point (m)",
                         .ylabel = "mm",
                         .notes = notes,
                         .note_count = 1};
    char path[4096];
    mr_path_join(p->out_dir, "bench_measure.svg", path, sizeof path);
    return mr_plot_write(path, &pp, ser, 2, err);
}

bool mr_bench_measure(const mr_bench_measure_params *params, mr_error *err) {
    mr_bench_measure_params p = params ? *params : (mr_bench_measure_params){MR_BENCH_MEASURE_DEFAULTS};
    int nrows = p.quick ? QUICK_ROWS : NROWS, seeds = p.maps > 0 ? p.maps : 2;
    if (p.points < 1) p.points = 20;
    if (!(p.tolerance_mm > 0)) p.tolerance_mm = 20;
    if (!mr_mkdirs(p.out_dir, err)) return false;
    row_acc acc[NROWS];
    memset(acc, 0, sizeof acc);
    bool ok = true;
    for (int ri = 0; ok && ri < nrows; ri++) {
        acc[ri].s = malloc((size_t)seeds * p.points * NDEV * sizeof *acc[ri].s);
        ok = acc[ri].s != NULL;
    }
    if (!ok) mr_fail(err, MR_ERR_NOMEM, "bench measure: out of memory");
    for (int sd = 0; ok && sd < seeds; sd++) ok = run_seed(&p, nrows, (uint64_t)sd + 1, acc, err);
    row_stats st[NROWS];
    mr_csv *csv = ok ? mr_csv_create(err) : NULL;
    ok = ok && csv;
    if (ok) {
        mr_csv_header(csv, "hall,tag_m,photos,map_res,track_res,dist_m,taps,samples,failed,map_err_rms_mm,"
                           "map_sigma_med_mm,map_z_rms,map_tags_share,point_err_med_mm,dev_sigma_med_mm,point_sigma3d_med_mm,z_rms,"
                           "coverage95,correct,undecided,wrong,correct_at_0,wrong_at_0,correct_at_50,wrong_at_50");
        if (p.out)
            fprintf(p.out, "%-8s %5s %6s %10s %10s %5s %4s %5s %8s %8s %6s %8s %8s %6s %6s %6s %6s %6s\n", "hall", "tag",
                    "photos", "map", "track", "dist", "taps", "n", "map mm", "map sig", "map z", "err mm", "sig mm", "z rms",
                    "cover", "right", "undec", "wrong");
        for (int ri = 0; ri < nrows; ri++) {
            const row_t *r = &k_rows[ri];
            hall_t h;
            if (r->hall == 0)
                hall_columns(r->tag_m, &h);
            else if (!(ok = hall_demo(r->tag_m, &h, err)))
                break;
            row_summary(&acc[ri], p.tolerance_mm, &st[ri]);
            csv_row(csv, r, h.name, h.tag_size, &st[ri]);
            if (p.out)
                fprintf(p.out, "%-8s %5.2f %6d %5dx%-4d %5dx%-4d %5.1f %4d %5d %8.2f %8.2f %6.2f %8.2f %8.2f %6.2f %6.3f %6.3f "
                               "%6.3f %6.3f\n",
                        h.name, h.tag_size, r->photos, r->map_w, r->map_h, r->trk_w, r->trk_h, r->dist_m, r->taps,
                        st[ri].n, st[ri].map_err, st[ri].map_sig, st[ri].map_z, st[ri].err_med, st[ri].sig_med, st[ri].z_rms,
                        st[ri].cover, st[ri].share[0], st[ri].share[1], st[ri].share[2]);
        }
    }
    char path[4096];
    if (ok) {
        mr_path_join(p.out_dir, "bench_measure.csv", path, sizeof path);
        ok = mr_csv_save(csv, path, err);
    }
    if (ok) ok = write_plot(&p, st, nrows, err);
    mr_csv_destroy(&csv);
    for (int ri = 0; ri < nrows; ri++) free(acc[ri].s);
    return ok;
}
