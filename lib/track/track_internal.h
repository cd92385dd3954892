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

#ifdef __cplusplus
}
#endif
#endif
