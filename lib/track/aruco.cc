// OpenCV aruco (DICT_APRILTAG_36h11) as a peer detector for the bench, and
// camera calibration, behind the extern "C" face in mr_track.h.
#include "track_internal.h"

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cstring>
#include <vector>

struct mr_aruco {
    cv::Ptr<cv::aruco::Dictionary> dict;
    cv::Ptr<cv::aruco::DetectorParameters> params;
    std::vector<mr_detection> dets;
};

extern "C" const char *mr_aruco_refine_name(mr_aruco_refine r) {
    switch (r) {
    case MR_ARUCO_REFINE_NONE: return "none";
    case MR_ARUCO_REFINE_SUBPIX: return "subpix";
    case MR_ARUCO_REFINE_CONTOUR: return "contour";
    case MR_ARUCO_REFINE_APRILTAG: return "apriltag";
    }
    return "?";
}

extern "C" mr_aruco *mr_aruco_create(mr_aruco_refine refine, mr_error *err) {
    try {
        mr_aruco *a = new mr_aruco;
        a->dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_APRILTAG_36h11);
        a->params = cv::aruco::DetectorParameters::create();
        static const int modes[] = {cv::aruco::CORNER_REFINE_NONE, cv::aruco::CORNER_REFINE_SUBPIX,
                                    cv::aruco::CORNER_REFINE_CONTOUR, cv::aruco::CORNER_REFINE_APRILTAG};
        a->params->cornerRefinementMethod = modes[refine < 0 || refine > 3 ? 0 : refine];
        return a;
    } catch (const std::exception &e) {
        mr_fail(err, MR_ERR_UNSUPPORTED, "OpenCV aruco: %.200s", e.what());
        return nullptr;
    }
}

extern "C" void mr_aruco_destroy(mr_aruco **a) {
    if (!a) return;
    delete *a;
    *a = nullptr;
}

extern "C" const mr_detection *mr_aruco_detect(mr_aruco *a, const mr_image *img, int *count, mr_error *err) {
    *count = 0;
    if (!img || !img->data || img->type != MR_PIX_U8 || img->channels != 1 || img->width < MR_DETECTOR_MIN_SIDE ||
        img->height < MR_DETECTOR_MIN_SIDE) {
        mr_fail(err, MR_ERR_INVALID, "aruco: needs an 8-bit grey frame of at least %dx%d", MR_DETECTOR_MIN_SIDE,
                MR_DETECTOR_MIN_SIDE);
        return nullptr;
    }
    try {
        cv::Mat m(img->height, img->width, CV_8UC1, img->data);
        std::vector<std::vector<cv::Point2f>> corners;
        std::vector<int> ids;
        cv::aruco::detectMarkers(m, a->dict, corners, ids, a->params);
        a->dets.resize(ids.size() + 1);
        for (size_t i = 0; i < ids.size(); i++) {
            mr_detection &d = a->dets[i];
            d.id = ids[i];
            d.hamming = 0;
            d.decision_margin = 0;
            // OpenCV's DICT_APRILTAG_36h11 starts at another corner and turns
            // the other way than the apriltag library (checked on the demo
            // recording: apriltag corner k = aruco corner (5 - k) mod 4).
            for (int k = 0; k < 4; k++) {
                d.corners[k][0] = corners[i][(size_t)((5 - k) % 4)].x;
                d.corners[k][1] = corners[i][(size_t)((5 - k) % 4)].y;
            }
        }
        std::sort(a->dets.begin(), a->dets.begin() + (long)ids.size(),
                  [](const mr_detection &x, const mr_detection &y) { return x.id < y.id; });
        *count = (int)ids.size();
        return a->dets.data();
    } catch (const std::exception &e) {
        mr_fail(err, MR_ERR_UNSUPPORTED, "OpenCV aruco: %.200s", e.what());
        return nullptr;
    }
}

extern "C" bool mr_calibrate(const mr_calib_view *views, int nviews, int width, int height, mr_camera *out,
                             double *rms_px, double *per_view_rms, mr_error *err) {
    if (nviews < 3) return mr_fail(err, MR_ERR_INVALID, "calibration needs at least 3 usable images (got %d)", nviews);
    try {
        std::vector<std::vector<cv::Point3f>> obj((size_t)nviews);
        std::vector<std::vector<cv::Point2f>> img((size_t)nviews);
        for (int v = 0; v < nviews; v++) {
            for (int i = 0; i < views[v].n; i++) {
                obj[(size_t)v].emplace_back((float)views[v].object[3 * i], (float)views[v].object[3 * i + 1],
                                            (float)views[v].object[3 * i + 2]);
                img[(size_t)v].emplace_back((float)views[v].image[2 * i], (float)views[v].image[2 * i + 1]);
            }
        }
        cv::Mat K, dist;
        std::vector<cv::Mat> rvecs, tvecs;
        cv::Mat std_in, std_ex, per_view;
        double rms = cv::calibrateCamera(obj, img, cv::Size(width, height), K, dist, rvecs, tvecs, std_in, std_ex,
                                         per_view, cv::CALIB_FIX_K3);
        std::memset(out, 0, sizeof *out);
        out->width = width;
        out->height = height;
        out->fx = K.at<double>(0, 0);
        out->fy = K.at<double>(1, 1);
        out->cx = K.at<double>(0, 2);
        out->cy = K.at<double>(1, 2);
        for (int i = 0; i < 5 && i < (int)dist.total(); i++) out->dist[i] = dist.at<double>(i);
        *rms_px = rms;
        if (per_view_rms)
            for (int v = 0; v < nviews; v++) per_view_rms[v] = per_view.at<double>(v);
        return mr_camera_validate(out, err);
    } catch (const std::exception &e) {
        return mr_fail(err, MR_ERR_INVALID, "calibration failed (%.200s)", e.what());
    }
}
