/* Measure what was built (issue 15, item 4): a feature of the as-built
 * demo hall tapped in frames whose poses come from the tracker (corners
 * with noise, so each pose has its error and its covariance), triangulated
 * and compared with the plan. The moved machine's reference point must come
 * out 0.30 m from its planned place within 2 sigma, a correctly placed
 * column's 0 m within 2 sigma; taps from nearly one pose are refused. */
#include "mr_eval.h"
#include "mr_scene.h"
#include "mr_test.h"
#include "mr_track.h"

static bool node_origin(const mr_scene *s, const char *name, mr_dvec3 *out) {
    for (int i = 0; i < s->node_count; i++)
        if (strcmp(s->nodes[i].name, name) == 0) {
            *out = mr_v3(s->nodes[i].world.m[3], s->nodes[i].world.m[7], s->nodes[i].world.m[11]);
            return true;
        }
    return false;
}

/* Taps of `built` from n camera positions around it (radius 3 m), each
 * pose solved from the tags it sees. */
static bool measure(mr_dvec3 built, int n, double spread_rad, uint64_t seed, mr_triangulation *t, mr_error *err) {
    mr_camera cam = mr_demo_camera();
    /* 0.6 m tags on the walls of a 10 m room around the feature, two rows. */
    mr_marker tags[24];
    for (int i = 0; i < 24; i++) {
        double a = 2 * M_PI * (i % 12 + 0.5 * (i / 12)) / 12;
        mr_dvec3 c = mr_v3(built.x + 5 * cos(a), i < 12 ? 1.2 : 2.6, built.z + 5 * sin(a));
        tags[i] = (mr_marker){.id = i, .world_from_tag = mr_m4_look_at_cv(c, mr_v3(c.x + cos(a), c.y, c.z + sin(a)), mr_v3(0, 1, 0))};
    }
    mr_marker_map map = {.family = "tag36h11", .tag_size = 0.6, .tags = tags, .count = 24};
    mr_rng rng;
    mr_rng_seed(&rng, seed);
    mr_tap taps[8];
    static mr_pose poses[8];
    int m = 0;
    for (int k = 0; k < n; k++) {
        double a = spread_rad * (k - 0.5 * (n - 1)) / (n > 1 ? n - 1 : 1);
        mr_dvec3 eye = mr_v3(built.x - 3 * cos(a), 1.5, built.z - 3 * sin(a));
        mr_dmat4 wfc = mr_m4_look_at_cv(eye, mr_v3(built.x, 0.8, built.z), mr_v3(0, 1, 0));
        mr_detection det[24];
        int nd = 0;
        for (int i = 0; i < 24; i++) {
            mr_dvec3 c[4];
            mr_marker_corners_world(&map, &tags[i], c);
            bool in = true;
            det[nd] = (mr_detection){.id = i};
            for (int q = 0; q < 4 && in; q++) {
                double u, v;
                in = mr_project_point(&cam, &wfc, c[q], &u, &v) && u > 0 && v > 0 && u < cam.width && v < cam.height;
                det[nd].corners[q][0] = u + 0.5 * mr_rng_normal(&rng);
                det[nd].corners[q][1] = v + 0.5 * mr_rng_normal(&rng);
            }
            nd += in;
        }
        mr_pose *pose = &poses[m];
        if (!mr_pose_solve(&cam, &map, det, nd, NULL, NULL, pose, err) || !pose->valid) continue;
        double u, v;
        if (!mr_project_point(&cam, &wfc, built, &u, &v)) continue;
        taps[m] = (mr_tap){pose->world_from_camera, pose->cov, {u + mr_rng_normal(&rng), v + mr_rng_normal(&rng)}, pose->cov_map};
        m++;
    }
    mr_triangulate_params tp = MR_TRIANGULATE_DEFAULTS;
    return mr_triangulate(&cam, taps, m, &tp, t, err);
}

/* A point on the +x side of node `name`'s first mesh's bounds at height y
 * (node frame), in world: on its +z edge (zf 1) or in the middle of the
 * face (zf 0). */
static bool node_side(const mr_scene *s, const char *name, double y, double zf, mr_dvec3 *out) {
    for (int i = 0; i < s->node_count; i++)
        if (strcmp(s->nodes[i].name, name) == 0 && s->nodes[i].mesh_first >= 0) {
            const mr_mesh *m = &s->meshes[s->nodes[i].mesh_first];
            double zc = 0.5 * (m->bounds_min[2] + m->bounds_max[2]), zh = 0.5 * (m->bounds_max[2] - m->bounds_min[2]);
            mr_dvec3 p = mr_v3(m->origin[0] + m->bounds_max[0], y, m->origin[2] + zc + zf * zh);
            *out = mr_m4_point(&s->nodes[i].world, p);
            return true;
        }
    return false;
}

/* Against the planned surface (the nearest point of the model, lib/eval):
 * the moved machine's +x,+z edge is 0.30 m from the planned housing (it
 * moved 0.30 m along +x), a point on a column's face lies on its planned
 * column (a face, not an edge: off an edge the distance is not the
 * one-sided |N(0, sigma)| that "within 2 sigma" assumes). */
static void surface_case(const mr_demo_hall *hall, const char *moved_node) {
    mr_error err = {0};
    mr_eval_nearest *n = mr_eval_nearest_create(hall->planned, false, &err);
    CHECK_MSG(n != NULL, "%s", err.msg);
    if (!n) return;
    mr_dvec3 me, ce;
    CHECK(node_side(hall->built, moved_node, 1.0, 1, &me) && node_side(hall->built, "Column_0_0", 1.0, 0, &ce));
    mr_nearest_hit h;
    /* The true points first: the geometry says what the answer must be. */
    CHECK(mr_eval_nearest_point(n, me, &h));
    CHECK_NEAR(h.distance, 0.30, 1e-6);
    CHECK(mr_eval_nearest_point(n, ce, &h));
    CHECK_NEAR(h.distance, 0.0, 1e-6);
    int in_moved = 0, in_col = 0, runs = 20;
    double first_m = 0, first_ms = 0, first_c = 0, first_cs = 0;
    for (int s = 0; s < runs; s++) {
        mr_triangulation t;
        CHECK_MSG(measure(me, 4, 1.2, 300 + s, &t, &err), "%s", err.msg);
        CHECK(mr_eval_nearest_point(n, t.point, &h));
        double sig = mr_eval_nearest_sigma(&h, t.cov);
        in_moved += fabs(h.distance - 0.30) <= 2 * sig;
        if (s == 0) first_m = h.distance, first_ms = sig;
        CHECK_MSG(measure(ce, 4, 1.2, 400 + s, &t, &err), "%s", err.msg);
        CHECK(mr_eval_nearest_point(n, t.point, &h));
        sig = mr_eval_nearest_sigma(&h, t.cov);
        /* Near the surface the direction is the face's normal or the way
         * the point lies off it: the distance is |N(0, sig)|, within 2 sig
         * 95 % of the time. */
        in_col += h.distance <= 2 * sig;
        if (s == 0) first_c = h.distance, first_cs = sig;
    }
    printf("planned surface: moved machine edge %d/%d within 2 sigma of 0.30 m (first: %.1f mm +- %.1f mm); "
           "column face %d/%d within 2 sigma of 0 (first: %.1f mm +- %.1f mm)\n",
           in_moved, runs, first_m * 1e3, first_ms * 1e3, in_col, runs, first_c * 1e3, first_cs * 1e3);
    CHECK(in_moved >= 17 && in_col >= 17);
    mr_eval_nearest_destroy(&n);
}

int main(void) {
    mr_demo_hall hall;
    mr_error err = {0};
    CHECK_MSG(mr_demo_build(NULL, &hall, &err), "%s", err.msg);
    const cJSON *d, *moved = NULL;
    cJSON_ArrayForEach(d, hall.discrepancies) {
        const cJSON *k = cJSON_GetObjectItem(d, "kind");
        if (cJSON_IsString(k) && strcmp(k->valuestring, "moved") == 0) moved = d;
    }
    CHECK(moved != NULL);
    const char *node = moved ? cJSON_GetObjectItem(moved, "node")->valuestring : "";
    mr_dvec3 mp, mb, cp, cb;
    CHECK(node_origin(hall.planned, node, &mp) && node_origin(hall.built, node, &mb));
    CHECK(node_origin(hall.planned, "Column_0_0", &cp) && node_origin(hall.built, "Column_0_0", &cb));
    CHECK_NEAR(mr_v3_len(mr_v3_sub(mb, mp)), 0.30, 1e-9);
    CHECK_NEAR(mr_v3_len(mr_v3_sub(cb, cp)), 0.0, 1e-9);
    /* 2 sigma holds ~95 % of the time for a correct sigma: the check runs
     * over 20 seeds and asks for >= 85 % (a sigma half the true one would
     * give ~68 %), and for the median distance near the truth. */
    int in_moved = 0, in_col = 0, runs = 20;
    double dm[20], dc[20], sm = 0, sc = 0;
    for (int s = 0; s < runs; s++) {
        mr_triangulation t;
        double dist, sig;
        CHECK_MSG(measure(mb, 4, 1.2, 100 + s, &t, &err), "%s", err.msg);
        mr_triangulation_distance(&t, mp, &dist, &sig);
        dm[s] = dist;
        sm += sig / runs;
        in_moved += fabs(dist - 0.30) <= 2 * sig;
        CHECK_MSG(measure(cb, 4, 1.2, 200 + s, &t, &err), "%s", err.msg);
        mr_triangulation_distance(&t, cp, &dist, &sig);
        dc[s] = dist;
        sc += sig / runs;
        /* A distance is >= 0: "0 within 2 sigma" is dist <= 2 sigma of
         * the 3D point (its sqrt(trace / 3) per axis, times sqrt 3). */
        in_col += dist <= 2 * t.sigma;
    }
    printf("moved machine: %d/%d within 2 sigma of 0.30 m (first: %.1f mm +- %.1f mm); column: %d/%d within 2 sigma "
           "of 0 (first: %.1f mm, sigma %.1f mm)\n",
           in_moved, runs, dm[0] * 1e3, sm * 1e3, in_col, runs, dc[0] * 1e3, sc * 1e3);
    CHECK(in_moved >= 17 && in_col >= 17);
    surface_case(&hall, node);
    /* Nearly the same pose twice: refused, naming the angle. */
    mr_triangulation t;
    CHECK(!measure(mb, 2, 0.005, 7, &t, &err) && strstr(err.msg, "baseline angle"));
    CHECK(!measure(mb, 1, 0, 7, &t, &err) && strstr(err.msg, "2 or more"));
    mr_demo_free(&hall);
    return mr_test_finish("test_measure");
}
