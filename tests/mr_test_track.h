/* mr_test_track.h — tracking helpers shared by the tracking tests
 * (include after mr_test.h). */
#ifndef MR_TEST_TRACK_H
#define MR_TEST_TRACK_H

#include "mr_track.h"

/* The weak-perspective mirror of the truth (what IPPE's second solution
 * approximates): the tag turned about its centre so that its normal is
 * reflected about the line of sight. A pose nearer this than the truth
 * has flipped to the wrong branch. */
static inline mr_dmat4 mr_test_mirror_pose(const mr_marker *m, const mr_dmat4 *wfc) {
    mr_dmat4 cfw = mr_m4_invert_rigid(wfc), cft = mr_m4_mul(&cfw, &m->world_from_tag);
    mr_dvec3 c = mr_v3(cft.m[3], cft.m[7], cft.m[11]), r = mr_v3_normalize(c);
    mr_dvec3 n = mr_v3(cft.m[2], cft.m[6], cft.m[10]);
    mr_dvec3 n2 = mr_v3_sub(mr_v3_scale(r, 2 * mr_v3_dot(n, r)), n);
    mr_dvec3 ax = mr_v3_cross(n, n2);
    double ang = atan2(mr_v3_len(ax), mr_v3_dot(n, n2));
    mr_dmat4 Q = mr_m4_rotate_axis(ax, ang), cft2 = mr_m4_mul(&Q, &cft);
    cft2.m[3] = c.x;
    cft2.m[7] = c.y;
    cft2.m[11] = c.z;
    mr_dmat4 tfc2 = mr_m4_invert_rigid(&cft2);
    return mr_m4_mul(&m->world_from_tag, &tfc2);
}

#endif
