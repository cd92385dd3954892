/* `mrcheck demo`'s measurements: a feature of the hall as built measured
 * from several frames of the demo's recording, as a planner does with the
 * view's Measure, then judged against the tolerance. The feature is a
 * vertical edge of the part (the corner seen in the most frames, at three
 * quarters of its height); each tap is where that edge is in the frame (the
 * recording's ground-truth pose, the lens, a little tap noise), each with
 * the tracker's pose of that frame and its covariance, so the interval
 * carries the registration's uncertainty. */
#include "bench_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The frames whose tracked pose has a covariance and whose ground truth
 * sees X unoccluded by the hall as built, written into ok[] (one render of
 * the built hall per usable frame, shared by all candidates). */
#define DM_MAX_CAND 4
#define DM_PICK_W 320
#define DM_PICK_H 240

static bool usable(const mr_rec_frame *f) {
    return f->has_gt && f->pose.valid && f->pose.tags_used >= 2 && f->pose.corner_sigma_px > 0;
}

/* Where X is in the frame of camera cam (distorted pixel), inside the
 * picture with a margin; false if not. */
static bool in_picture(const mr_camera *cam, const mr_dmat4 *wfc, mr_dvec3 X, double *u, double *v) {
    if (!mr_project_point(cam, wfc, X, u, v)) return false;
    return *u > 0.05 * cam->width && *u < 0.95 * cam->width && *v > 0.05 * cam->height && *v < 0.95 * cam->height;
}

static double edge_height(const double lo[3], const double hi[3]) {
    return fmin(lo[1] + 0.75 * (hi[1] - lo[1]), lo[1] + 1.5);
}

/* Edge X tapped in the frames (of frames[0..nf)) where seen[] says it is
 * seen, at most MR_MEASURE_MAX_TAPS spread over them, triangulated, and its
 * distance to X - delta (the same edge on the plan); false if the taps do
 * not triangulate (too narrow a baseline). */
static bool measure_edge(const mr_recording *rec, const int *frames, int nf, const bool *seen, mr_dvec3 X, mr_dvec3 delta,
                         uint64_t seed, mr_measurement *m) {
    memset(m, 0, sizeof *m);
    int idx[MR_MEASURE_MAX_TAPS * 8], n = 0;
    for (int k = 0; k < nf; k++)
        if (seen[k]) idx[n++] = frames[k];
    int take = n < MR_MEASURE_MAX_TAPS ? n : MR_MEASURE_MAX_TAPS;
    mr_tap taps[MR_MEASURE_MAX_TAPS];
    mr_rng rng;
    mr_rng_seed(&rng, seed);
    for (int t = 0; t < take; t++) {
        const mr_rec_frame *f = &rec->frames[idx[take == 1 ? 0 : (int)lround(t * (n - 1.0) / (take - 1.0))]];
        double u, v;
        mr_project_point(&rec->camera, &f->gt, X, &u, &v);
        /* A planner's tap is good to about half a pixel. */
        u += 0.5 * mr_rng_normal(&rng);
        v += 0.5 * mr_rng_normal(&rng);
        taps[t] = (mr_tap){f->pose.world_from_camera, f->pose.cov, {u, v}, f->pose.cov_map};
        m->frames[t] = f->index;
        m->px[t][0] = u, m->px[t][1] = v;
    }
    m->taps = take;
    mr_error e = {0};
    if (!mr_triangulate(&rec->camera, taps, take, NULL, &m->tri, &e)) return false;
    m->planned = mr_v3_sub(X, delta);
    mr_triangulation_distance(&m->tri, m->planned, &m->distance_m, &m->distance_sigma_m);
    m->has_distance = true;
    return true;
}

bool mr_demo_measure(const mr_recording *rec, const mr_bench_gpu *g, const mr_scene *built, const char *node,
                     mr_dvec3 delta, uint64_t seed, mr_demo_measured *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    int32_t ni = -1;
    for (int32_t n = 0; n < built->node_count && ni < 0; n++)
        if (strcmp(built->nodes[n].name, node) == 0) ni = n;
    double lo[3], hi[3];
    if (ni < 0 || !mr_scene_node_bounds(built, ni, lo, hi))
        return mr_fail(err, MR_ERR_INVALID, "demo measure: no part %s in the hall as built", node);
    /* The four vertical edges, at three quarters of the part's height, or
     * at 1.5 m for a tall one (what a planner taps, standing). */
    double y = edge_height(lo, hi);
    mr_dvec3 cand[DM_MAX_CAND] = {mr_v3(hi[0], y, hi[2]), mr_v3(lo[0], y, hi[2]), mr_v3(hi[0], y, lo[2]),
                                  mr_v3(lo[0], y, lo[2])};
    bool seen[DM_MAX_CAND][MR_MEASURE_MAX_TAPS * 8];
    int nseen[DM_MAX_CAND] = {0}, frames[MR_MEASURE_MAX_TAPS * 8];
    int nf = 0;
    memset(seen, 0, sizeof seen);
    if (!mr_renderer_set_scene(g->renderer, built, err)) return false;
    mr_camera small = mr_camera_resized(&rec->camera, DM_PICK_W, DM_PICK_H);
    memset(small.dist, 0, sizeof small.dist);
    for (int i = 0; i < rec->frame_count && nf < MR_MEASURE_MAX_TAPS * 8; i++) {
        const mr_rec_frame *f = &rec->frames[i];
        if (!usable(f)) continue;
        double u, v;
        bool any = false;
        for (int c = 0; c < DM_MAX_CAND; c++) any |= in_picture(&rec->camera, &f->gt, cand[c], &u, &v);
        if (!any) continue;
        mr_view view = {small, f->gt};
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        mr_frame_result res = {0};
        bool ok = mr_render_frame(g->renderer, &view, &fp, &res, err);
        mr_frame_result_free(&res);
        if (!ok) return false;
        mr_dmat4 cw = mr_m4_invert_rigid(&f->gt);
        for (int c = 0; c < DM_MAX_CAND; c++) {
            if (!in_picture(&rec->camera, &f->gt, cand[c], &u, &v)) continue;
            /* The edge is seen where nothing stands in front of it: the
             * model's depth at its (undistorted) pixel is its own, or
             * beyond (the ray grazes past the edge). */
            mr_dvec3 q = mr_m4_point(&cw, cand[c]);
            mr_pick pick = {0};
            if (!mr_renderer_pick(g->renderer, small.fx * q.x / q.z + small.cx, small.fy * q.y / q.z + small.cy, &pick, err))
                return false;
            if (!pick.hit || pick.depth > q.z - 0.1) seen[c][nf] = true, nseen[c]++;
        }
        frames[nf++] = i;
    }
    /* Of the edges seen in two frames or more, the one that measures best
     * (the smallest sigma of its distance to the plan), as a planner keeps
     * the measurement with the smallest +/- the view shows. */
    int best = -1;
    mr_measurement *m = &out->m;
    for (int c = 0; c < DM_MAX_CAND; c++) {
        if (nseen[c] < 2) continue;
        mr_measurement mc;
        if (!measure_edge(rec, frames, nf, seen[c], cand[c], delta, seed, &mc)) continue;
        if (best < 0 || mc.distance_sigma_m < m->distance_sigma_m) best = c, *m = mc;
    }
    if (best < 0) return mr_fail(err, MR_ERR_INVALID, "demo measure: no edge of %s is seen in two frames from apart", node);
    snprintf(m->planned_node, sizeof m->planned_node, "%s", node);
    double p[3] = {m->planned.x, m->planned.y, m->planned.z};
    const char *layer = built->nodes[ni].layer == MR_LAYER_HIDDEN ? "hidden" : "visible";
    if (!mr_verdict_measure(NULL, node, layer, p, -1, m->distance_m, m->distance_sigma_m, &out->verdict, err)) return false;
    out->truth_m = mr_v3_len(delta);
    return true;
}

const char *mr_demo_control_part(const mr_recording *rec, const mr_scene *built, const mr_scene *planned) {
    const char *best = NULL;
    int best_n = 0;
    for (int32_t n = 0; n < planned->node_count; n++) {
        const mr_node *pn = &planned->nodes[n];
        if (strncmp(pn->name, "Column_", 7) != 0 || pn->layer != MR_LAYER_VISIBLE) continue;
        /* Unchanged: the same part with the same bounds in the hall as built. */
        int32_t b = -1;
        for (int32_t k = 0; k < built->node_count && b < 0; k++)
            if (strcmp(built->nodes[k].name, pn->name) == 0) b = k;
        double plo[3], phi[3], blo[3], bhi[3];
        if (b < 0 || !mr_scene_node_bounds(planned, n, plo, phi) || !mr_scene_node_bounds(built, b, blo, bhi)) continue;
        bool same = true;
        for (int a = 0; a < 3; a++) same &= fabs(plo[a] - blo[a]) < 1e-6 && fabs(phi[a] - bhi[a]) < 1e-6;
        if (!same) continue;
        mr_dvec3 c = mr_v3(0.5 * (plo[0] + phi[0]), edge_height(plo, phi), 0.5 * (plo[2] + phi[2]));
        int seen = 0;
        for (int i = 0; i < rec->frame_count; i++) {
            const mr_rec_frame *f = &rec->frames[i];
            double u, v;
            if (usable(f) && in_picture(&rec->camera, &f->gt, c, &u, &v) &&
                mr_v3_len(mr_v3_sub(c, mr_v3(f->gt.m[3], f->gt.m[7], f->gt.m[11]))) < 12)
                seen++;
        }
        if (seen > best_n) best = pn->name, best_n = seen;
    }
    return best;
}
