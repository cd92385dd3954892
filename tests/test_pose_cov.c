/* The pose covariance of mr_pose_solve against the observed spread of
 * poses over 500 draws of known corner noise (issue 15, item 3): the
 * predicted sigma of a point in view must match the spread within 25 %. */
#include "mr_test.h"
#include "mr_scene.h"
#include "mr_track.h"

static mr_dmat4 facing(mr_dvec3 c) { return mr_m4_look_at_cv(c, mr_v3_add(c, mr_v3(0, 0, 1)), mr_v3(0, 1, 0)); }

/* Spread of `point` (camera frame) over draws against the RMS predicted
 * sigma; ntags tags in a row 2 m ahead. */
static void run(int ntags, double noise, double *observed, double *predicted, double *obs_lat, double *pred_lat,
                double *sigma_px) {
    mr_camera cam = mr_demo_camera();
    mr_marker tags[4];
    for (int i = 0; i < ntags; i++) {
        tags[i] = (mr_marker){.id = i, .world_from_tag = facing(mr_v3(-0.6 + 0.4 * i, 0.2 * (i % 2), 2.0 + 0.3 * i))};
    }
    mr_marker_map map = {.family = "tag36h11", .tag_size = 0.2, .tags = tags, .count = ntags};
    mr_dmat4 wfc = mr_m4_look_at_cv(mr_v3(0, 0.1, 0), mr_v3(0, 0.1, 3), mr_v3(0, 1, 0));
    mr_dvec3 point = mr_v3(0.3, -0.2, 4.0); /* a spot of the model beyond the tags */
    mr_rng rng;
    mr_rng_seed(&rng, 5);
    enum { N = 500 };
    static mr_dvec3 q[N];
    double pred = 0, plat = 0, spx = 0;
    int n = 0;
    for (int d = 0; d < N; d++) {
        mr_detection det[4];
        for (int i = 0; i < ntags; i++) {
            mr_dvec3 c[4];
            mr_marker_corners_world(&map, &tags[i], c);
            det[i] = (mr_detection){.id = i};
            for (int k = 0; k < 4; k++) {
                double u, v;
                mr_project_point(&cam, &wfc, c[k], &u, &v);
                det[i].corners[k][0] = u + noise * mr_rng_normal(&rng);
                det[i].corners[k][1] = v + noise * mr_rng_normal(&rng);
            }
        }
        mr_pose pose;
        mr_error err = {0};
        if (!mr_pose_solve(&cam, &map, det, ntags, NULL, NULL, &pose, &err) || !pose.valid) continue;
        double s3, sl;
        if (!mr_pose_point_sigma(&pose, point, &s3, &sl)) continue;
        pred += s3 * s3;
        plat += sl * sl;
        spx += pose.corner_sigma_px;
        mr_dmat4 cfw = mr_m4_invert_rigid(&pose.world_from_camera);
        q[n++] = mr_m4_point(&cfw, point);
    }
    CHECK(n > N * 0.95);
    mr_dvec3 mean = {0, 0, 0};
    for (int i = 0; i < n; i++) mean = mr_v3_add(mean, mr_v3_scale(q[i], 1.0 / n));
    double ss = 0, along = 0;
    mr_dvec3 dir = mr_v3_normalize(mean);
    for (int i = 0; i < n; i++) {
        mr_dvec3 e = mr_v3_sub(q[i], mean);
        ss += mr_v3_dot(e, e);
        along += mr_v3_dot(e, dir) * mr_v3_dot(e, dir);
    }
    *observed = sqrt(ss / (n - 1));
    *obs_lat = sqrt((ss - along) / (n - 1));
    *predicted = sqrt(pred / n);
    *pred_lat = sqrt(plat / n);
    *sigma_px = spx / n;
}

int main(void) {
    int counts[2] = {4, 1};
    for (int t = 0; t < 2; t++) {
        double obs, pred, olat, plat, spx;
        run(counts[t], 0.5, &obs, &pred, &olat, &plat, &spx);
        printf("%d tag(s), 0.5 px corners: observed %.2f mm (lateral %.2f), predicted %.2f mm (lateral %.2f), "
               "ratio %.3f (lateral %.3f); estimated corner noise %.3f px\n",
               counts[t], obs * 1e3, olat * 1e3, pred * 1e3, plat * 1e3, pred / obs, plat / olat, spx);
        if (t == 0) {
            /* Four tags: the 25 %. */
            CHECK(pred / obs > 0.75 && pred / obs < 1.25);
            CHECK(plat / olat > 0.75 && plat / olat < 1.25);
            CHECK(spx > 0.4 && spx < 0.6);
        } else {
            /* A lone tag estimates its noise from 2 degrees of freedom:
             * only the order of magnitude holds. */
            CHECK(pred / obs > 0.3 && pred / obs < 3);
        }
    }
    /* Exact corners: the floor keeps the sigma honest, never zero. */
    double obs, pred, olat, plat, spx;
    run(4, 0.0, &obs, &pred, &olat, &plat, &spx);
    CHECK(fabs(spx - MR_POSE_MIN_CORNER_SIGMA_PX) < 1e-12 && pred > 0);
    return mr_test_finish("test_pose_cov");
}
