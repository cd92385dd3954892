// A second opinion on ghosting legibility: OpenCV contrib's spectral-residual
// saliency (Hou & Zhang 2007, cv::saliency::StaticSaliencySpectralResidual),
// a model that knows nothing of our centre-surround analysis or its targets.
// OpenCV stays inside this file; mr_eval.h sees plain images.
#include "mr_eval.h"

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/saliency.hpp>

extern "C" bool mr_eval_saliency_ratio(const mr_image *final, const mr_image *region, double *ratio, mr_error *err) {
    *ratio = NAN;
    if (!final || !final->data || !region || !region->data || final->channels != 3 || region->channels != 1 ||
        region->type != MR_PIX_F32 || final->width != region->width || final->height != region->height)
        return mr_fail(err, MR_ERR_INVALID, "saliency: need an RGB image and an F32x1 region of the same size");
    const int w = final->width, h = final->height;
    cv::Mat bgr(h, w, CV_8UC3);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = ((size_t)y * w + x) * 3;
            unsigned char c[3];
            for (int k = 0; k < 3; k++) {
                if (final->type == MR_PIX_U8) {
                    c[k] = static_cast<const unsigned char *>(final->data)[i + k];
                } else {
                    /* linear -> sRGB 8-bit, as the image is displayed */
                    double v = static_cast<const float *>(final->data)[i + k];
                    v = v > 0 ? (v < 1 ? v : 1) : 0;
                    v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
                    c[k] = (unsigned char)(v * 255.0 + 0.5);
                }
            }
            bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(c[2], c[1], c[0]);
        }
    cv::Mat sal;
    try {
        cv::Ptr<cv::saliency::StaticSaliencySpectralResidual> sr = cv::saliency::StaticSaliencySpectralResidual::create();
        if (!sr->computeSaliency(bgr, sal)) return mr_fail(err, MR_ERR_INVALID, "saliency: OpenCV computed nothing");
    } catch (const cv::Exception &e) {
        return mr_fail(err, MR_ERR_INVALID, "saliency: %s", e.what());
    }
    double in = 0, out = 0;
    long long nin = 0, nout = 0;
    const float *reg = static_cast<const float *>(region->data);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double s = sal.at<float>(y, x);
            if (reg[(size_t)y * w + x] > 0.5f) { in += s; nin++; }
            else { out += s; nout++; }
        }
    if (nin > 0 && nout > 0 && out > 0) *ratio = (in / nin) / (out / nout);
    return true;
}
