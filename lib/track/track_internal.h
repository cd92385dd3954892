/* Private to lib/track: the extern "C" face of the OpenCV files (pnp.cc,
 * video.cc). Plain arrays only; no OpenCV or C++ type crosses. */
#ifndef MR_TRACK_INTERNAL_H
#define MR_TRACK_INTERNAL_H

#include "mr_track.h"

#ifdef __cplusplus
extern "C" {
#endif

/* All image points are undistorted and normalised (x/z, y/z), so the
 * solvers see an ideal pinhole with identity intrinsics. R (3x3 row-major)
 * and t map object points into the camera frame. */

/* IPPE for a square: obj are the tag-frame corners (apriltag order, z = 0),
 * img their 4 image points. Returns the number of solutions (0..2), best
 * first. */
int mr_cv_ippe_square(const double obj[12], const double img[8], double R[2][9], double t[2][3]);
/* Levenberg-Marquardt refinement of R, t over n >= 4 correspondences. */
bool mr_cv_refine_lm(const double *obj, const double *img, int n, double R[9], double t[3]);
/* SQPnP over n >= 3 correspondences (global start for the multi-tag case). */
bool mr_cv_sqpnp(const double *obj, const double *img, int n, double R[9], double t[3]);

/* Video files through cv::VideoCapture. */
typedef struct mr_cv_video mr_cv_video;
mr_cv_video *mr_cv_video_open(const char *path, mr_error *err);
/* 1: frame (BGR converted to RGB, or grey), 0: end, -1: error. */
int mr_cv_video_read(mr_cv_video *v, bool gray, mr_image *img, double *t_s, mr_error *err);
void mr_cv_video_close(mr_cv_video *v);


/* Marker-map bundle adjustment through Ceres (map_ba.cc). Poses are
 * row-major 4x4 rigid transforms: tag[i] = world_from_tag, cam[j] =
 * camera_from_world; both are refined in place. Each observation is one
 * tag seen in one photo: its four corners in pixels (distorted, apriltag
 * order). Residuals are per corner, in pixels, under a Huber loss of scale
 * loss_px. The gauge: fixed_tag >= 0 holds that tag's pose constant;
 * otherwise the control points (a tag's centre, corner = -1, or a corner,
 * in world coordinates with a per-axis sigma) tie the map to the world. */
typedef struct mr_ba_problem {
    int ntags, nphotos, nobs;
    double *tag;               /* ntags x 16 */
    double *cam;               /* nphotos x 16 */
    const double *tag_size;    /* ntags, black-square edge */
    double intr[9];            /* fx fy cx cy k1 k2 p1 p2 k3, refined if asked */
    bool refine_intrinsics;    /* fx fy cx cy k1 k2 (p1 p2 k3 stay) */
    const int *obs_tag, *obs_photo; /* nobs */
    const double *obs_px;      /* nobs x 8 */
    int fixed_tag;             /* -1: control points gauge */
    int ncontrol;
    const int *ctl_tag, *ctl_corner;
    const double *ctl_world;   /* ncontrol x 3 */
    const double *ctl_sigma;   /* ncontrol, scene units */
    const bool *ctl_use;       /* ncontrol; NULL = all */
    double loss_px;
    int max_iterations;
    int threads;
    bool want_cov;
    /* out */
    double *tag_cov;           /* ntags x 36 when want_cov: covariance of
                                  (rotation, radians, about world axes;
                                  centre position) of each tag, scaled by the
                                  residual variance; NaN where it could not be
                                  computed */
    double rms_px;             /* corner reprojection RMS after the solve */
    double sigma_px;           /* residual standard deviation (dof-corrected) */
    int iterations;
} mr_ba_problem;
bool mr_ba_solve(mr_ba_problem *p, char *msg, size_t msg_size);
/* Weighted rigid fit (Kabsch/Horn): out = world_from_local minimising
 * sum w_i |out * local_i - world_i|^2 over n >= 3 points; false if they are
 * (nearly) collinear. */
bool mr_ba_rigid_fit(const double *local, const double *world, const double *w, int n, double out[16]);
/* Chordal L2 mean of n rotations (3x3 row-major, weights w): the SVD
 * projection of the weighted sum onto SO(3). */
void mr_ba_rotation_mean(const double *R, const double *w, int n, double out[9]);

#ifdef __cplusplus
}
#endif
#endif
