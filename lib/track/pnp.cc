// OpenCV PnP behind an extern "C" face (track_internal.h).
#include "track_internal.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <vector>

namespace {

void to_cv(const double R[9], const double t[3], cv::Mat &rvec, cv::Mat &tvec) {
    cv::Mat Rm(3, 3, CV_64F);
    for (int i = 0; i < 9; i++) Rm.at<double>(i / 3, i % 3) = R[i];
    cv::Rodrigues(Rm, rvec);
    tvec = (cv::Mat_<double>(3, 1) << t[0], t[1], t[2]);
}

void from_cv(const cv::Mat &rvec, const cv::Mat &tvec, double R[9], double t[3]) {
    cv::Mat Rm;
    cv::Rodrigues(rvec, Rm);
    Rm.convertTo(Rm, CV_64F);
    cv::Mat tv;
    tvec.convertTo(tv, CV_64F);
    for (int i = 0; i < 9; i++) R[i] = Rm.at<double>(i / 3, i % 3);
    for (int i = 0; i < 3; i++) t[i] = tv.at<double>(i);
}

void points(const double *obj, const double *img, int n, std::vector<cv::Point3d> &o, std::vector<cv::Point2d> &p) {
    o.resize((size_t)n);
    p.resize((size_t)n);
    for (int i = 0; i < n; i++) {
        o[(size_t)i] = cv::Point3d(obj[3 * i], obj[3 * i + 1], obj[3 * i + 2]);
        p[(size_t)i] = cv::Point2d(img[2 * i], img[2 * i + 1]);
    }
}

}  // namespace

extern "C" int mr_cv_ippe_square(const double obj[12], const double img[8], double R[2][9], double t[2][3]) {
    try {
        std::vector<cv::Point3d> o;
        std::vector<cv::Point2d> p;
        points(obj, img, 4, o, p);
        std::vector<cv::Mat> rvecs, tvecs;
        cv::Mat K = cv::Mat::eye(3, 3, CV_64F);
        int n = cv::solvePnPGeneric(o, p, K, cv::noArray(), rvecs, tvecs, false, cv::SOLVEPNP_IPPE_SQUARE);
        if (n > 2) n = 2;
        for (int i = 0; i < n; i++) from_cv(rvecs[(size_t)i], tvecs[(size_t)i], R[i], t[i]);
        return n;
    } catch (const std::exception &) {
        return 0;  // degenerate input (e.g. collinear corners): no solution
    }
}

extern "C" bool mr_cv_refine_lm(const double *obj, const double *img, int n, double R[9], double t[3]) {
    try {
        std::vector<cv::Point3d> o;
        std::vector<cv::Point2d> p;
        points(obj, img, n, o, p);
        cv::Mat rvec, tvec;
        to_cv(R, t, rvec, tvec);
        cv::Mat K = cv::Mat::eye(3, 3, CV_64F);
        // Normalised coordinates: an error of 1 px is ~1e-3, so stop on a
        // step far below that.
        cv::solvePnPRefineLM(o, p, K, cv::noArray(), rvec, tvec,
                             cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-12));
        from_cv(rvec, tvec, R, t);
        return true;
    } catch (const std::exception &) {
        return false;
    }
}

extern "C" bool mr_cv_sqpnp(const double *obj, const double *img, int n, double R[9], double t[3]) {
    try {
        std::vector<cv::Point3d> o;
        std::vector<cv::Point2d> p;
        points(obj, img, n, o, p);
        cv::Mat rvec, tvec;
        cv::Mat K = cv::Mat::eye(3, 3, CV_64F);
        if (!cv::solvePnP(o, p, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_SQPNP)) return false;
        from_cv(rvec, tvec, R, t);
        return true;
    } catch (const std::exception &) {
        return false;
    }
}
