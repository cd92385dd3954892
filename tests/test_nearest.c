/* The nearest point on the planned model (issue 15, item 4: "distance to
 * the planned surface"): Embree's point query with the exact closest point
 * per triangle in double. Known geometry (a point above a plane, beside a
 * box face, off a box corner, on a face), the same at an offset of 1e7, the
 * distance's sigma along the right direction, and the demo hall against a
 * brute-force search over all of its triangles. */
#include "mr_eval.h"
#include "mr_test.h"
#include "mr_test_scene.h"

static mr_eval_nearest *nearest_of(mr_scene *s) {
    mr_scene_update_bounds(s);
    mr_error err = {0};
    mr_eval_nearest *n = mr_eval_nearest_create(s, false, &err);
    CHECK_MSG(n != NULL, "%s", err.msg);
    return n;
}

/* A 10 m floor (y = 0) and a 1 m box centred at (5, 0.5, 0), all moved by off. */
static void known_geometry(double off) {
    mr_scene *s = mr_scene_create();
    int32_t quad = mr_test_add_quad(s, 10, 10, -1, false), box = mr_test_add_box(s, 1, 1, 1, -1);
    mr_dmat4 floor_xf = mr_m4_rotate_axis(mr_v3(1, 0, 0), -0.5 * M_PI); /* quad's z = 0 plane -> y = 0 */
    mr_dmat4 shift = mr_m4_translate(off, off, off);
    mr_dmat4 fw = mr_m4_mul(&shift, &floor_xf), bt = mr_m4_translate(off + 5, off + 0.5, off);
    mr_test_add_node(s, "Floor", fw, quad, MR_LAYER_VISIBLE);
    mr_test_add_node(s, "Box", bt, box, MR_LAYER_VISIBLE);
    mr_eval_nearest *n = nearest_of(s);
    CHECK(mr_eval_nearest_triangles(n) == 2 + 12);
    mr_nearest_hit h;
    /* 0.3 m above the floor, far from the box. */
    CHECK(mr_eval_nearest_point(n, mr_v3(off - 2, off + 0.3, off + 1), &h));
    CHECK_NEAR(h.distance, 0.3, 1e-9);
    CHECK_NEAR(h.point.y - off, 0.0, 1e-9);
    CHECK(strcmp(s->nodes[h.node].name, "Floor") == 0);
    CHECK_NEAR(fabs(h.direction.y), 1.0, 1e-12);
    /* The distance's sigma is the covariance along the direction (y here). */
    const double cov[9] = {1e-4, 0, 0, 0, 4e-4, 0, 0, 0, 9e-4};
    CHECK_NEAR(mr_eval_nearest_sigma(&h, cov), 0.02, 1e-12);
    /* 0.3 m beside the box's +x face (nearer than the floor, 0.5 below). */
    CHECK(mr_eval_nearest_point(n, mr_v3(off + 5.8, off + 0.5, off + 0.1), &h));
    CHECK_NEAR(h.distance, 0.3, 1e-9);
    CHECK(strcmp(s->nodes[h.node].name, "Box") == 0);
    CHECK_NEAR(h.point.x - off, 5.5, 1e-9);
    CHECK_NEAR(h.direction.x, 1.0, 1e-12);
    CHECK_NEAR(mr_eval_nearest_sigma(&h, cov), 0.01, 1e-12);
    /* Off the box's top corner (5.5, 1, 0.5) by (0.3, 0.4, 0): 0.5 m, to the corner. */
    CHECK(mr_eval_nearest_point(n, mr_v3(off + 5.8, off + 1.4, off + 0.5), &h));
    CHECK_NEAR(h.distance, 0.5, 1e-9);
    CHECK_NEAR(h.point.x - off, 5.5, 1e-9);
    CHECK_NEAR(h.point.y - off, 1.0, 1e-9);
    CHECK_NEAR(h.point.z - off, 0.5, 1e-9);
    /* Along (0.6, 0.8, 0): sigma^2 = 0.36e-4 + 0.64 * 4e-4. */
    CHECK_NEAR(mr_eval_nearest_sigma(&h, cov), sqrt(0.36e-4 + 0.64 * 4e-4), 1e-9);
    /* On the top face: distance 0, sigma along the face's normal (y). */
    CHECK(mr_eval_nearest_point(n, mr_v3(off + 5.1, off + 1.0, off - 0.2), &h));
    CHECK(h.distance < 1e-9);
    CHECK_NEAR(fabs(h.direction.y), 1.0, 1e-9);
    CHECK_NEAR(mr_eval_nearest_sigma(&h, cov), 0.02, 1e-9);
    /* Not a point. */
    CHECK(!mr_eval_nearest_point(n, mr_v3(NAN, 0, 0), &h) && !h.found);
    mr_eval_nearest_destroy(&n);
    CHECK(n == NULL);
    mr_eval_nearest_destroy(&n);
    mr_scene_destroy(&s);
}

static double brute(const mr_scene *s, mr_dvec3 p) {
    double best = INFINITY;
    for (int32_t ni = 0; ni < s->node_count; ni++) {
        const mr_node *nd = &s->nodes[ni];
        for (int32_t k = 0; nd->mesh_first >= 0 && k < nd->mesh_count; k++) {
            const mr_mesh *m = &s->meshes[nd->mesh_first + k];
            mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]), W = mr_m4_mul(&nd->world, &T);
            for (uint32_t t = 0; t + 2 < m->index_count; t += 3) {
                mr_dvec3 v[3];
                for (int q = 0; q < 3; q++) {
                    const float *x = &m->positions[3 * m->indices[t + (uint32_t)q]];
                    v[q] = mr_m4_point(&W, mr_v3(x[0], x[1], x[2]));
                }
                double d = mr_v3_len(mr_v3_sub(p, mr_closest_point_triangle(p, v[0], v[1], v[2])));
                if (d < best) best = d;
            }
        }
    }
    return best;
}

/* Every region of the closest point on a triangle: three vertices, three
 * edges, the face, and a degenerate triangle. */
static void triangle_regions(void) {
    mr_dvec3 a = mr_v3(0, 0, 0), b = mr_v3(1, 0, 0), c = mr_v3(0, 1, 0);
    static const double cases[][6] = {
        {-1, -1, 0.5, 0, 0, 0},     {2, -0.5, 0.3, 1, 0, 0},  {-0.5, 2, -1, 0, 1, 0}, {0.5, -1, 0, 0.5, 0, 0},
        {-1, 0.5, 2, 0, 0.5, 0},    {1, 1, 0, 0.5, 0.5, 0},   {0.2, 0.3, 5, 0.2, 0.3, 0},
        {0.25, 0.25, -1, 0.25, 0.25, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const double *k = cases[i];
        mr_dvec3 q = mr_closest_point_triangle(mr_v3(k[0], k[1], k[2]), a, b, c);
        /* The same triangle given in every vertex order. */
        mr_dvec3 r = mr_closest_point_triangle(mr_v3(k[0], k[1], k[2]), c, a, b);
        mr_dvec3 t = mr_closest_point_triangle(mr_v3(k[0], k[1], k[2]), b, c, a);
        CHECK_MSG(mr_v3_len(mr_v3_sub(q, mr_v3(k[3], k[4], k[5]))) < 1e-12 &&
                      mr_v3_len(mr_v3_sub(r, q)) < 1e-12 && mr_v3_len(mr_v3_sub(t, q)) < 1e-12,
                  "case %zu: (%g %g %g), want (%g %g %g)", i, q.x, q.y, q.z, k[3], k[4], k[5]);
    }
    mr_dvec3 d = mr_closest_point_triangle(mr_v3(3, 1, 0), a, b, mr_v3(2, 0, 0)); /* zero area */
    CHECK(isfinite(d.x) && isfinite(d.y) && isfinite(d.z));
}

int main(void) {
    triangle_regions();
    known_geometry(0);
    known_geometry(1e7);

    /* Empty scene: nothing to be near. */
    mr_scene *e = mr_scene_create();
    mr_eval_nearest *ne = nearest_of(e);
    mr_nearest_hit h;
    CHECK(!mr_eval_nearest_point(ne, mr_v3(0, 0, 0), &h) && !h.found);
    mr_eval_nearest_destroy(&ne);
    mr_scene_destroy(&e);

    /* The demo hall: the pruned search equals the exhaustive one. */
    mr_demo_hall hall;
    mr_error err = {0};
    CHECK_MSG(mr_demo_build(NULL, &hall, &err), "%s", err.msg);
    mr_eval_nearest *n = mr_eval_nearest_create(hall.planned, false, &err);
    CHECK_MSG(n != NULL, "%s", err.msg);
    mr_rng rng;
    mr_rng_seed(&rng, 5);
    const mr_scene *s = hall.planned;
    double worst = 0;
    for (int i = 0; i < 40; i++) {
        mr_dvec3 p;
        double u[3];
        for (int k = 0; k < 3; k++) {
            double lo = s->bounds_min[k], hi = s->bounds_max[k];
            u[k] = lo + (hi - lo) * (1.4 * mr_rng_uniform(&rng) - 0.2);
        }
        p = mr_v3(u[0], u[1], u[2]);
        CHECK(mr_eval_nearest_point(n, p, &h));
        double b = brute(s, p);
        double dd = fabs(h.distance - b);
        if (dd > worst) worst = dd;
        CHECK_MSG(dd < 1e-9, "point %d: embree %.9f, brute force %.9f", i, h.distance, b);
        CHECK_NEAR(mr_v3_len(mr_v3_sub(p, h.point)), h.distance, 1e-12);
    }
    printf("demo hall: %d triangles, 40 points, worst |embree - brute force| %.3g m\n", mr_eval_nearest_triangles(n),
           worst);
    mr_eval_nearest_destroy(&n);
    mr_demo_free(&hall);
    return mr_test_finish("test_nearest");
}
