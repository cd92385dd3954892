// The GPU's CIE L*a*b* conversion (mr_ghost_lab) and the CPU one of the
// legibility measure (mr_eval_rgb_to_lab) against OpenCV's cvtColor, the
// reference: within 0.5 Delta E (CIE76) over a grid of the RGB cube and
// random colours. (OpenCV's saliency module is used in lib/eval/saliency.cc.)
// Exit 77 without an EGL device.
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_test.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <vector>

static float srgb_encode(float c) { return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f; }

int main() {
    mr_error err = {};
    mr_gpu *gpu = mr_gpu_create_headless(nullptr, &err);
    if (!gpu) return mr_test_no_gpu("test_ghost_opencv", &err);
    mr_renderer *r = mr_renderer_create(gpu, &err);
    int failures = 0;
    if (!r) {
        std::fprintf(stderr, "renderer: %s\n", err.msg);
        mr_gpu_destroy(&gpu);
        return 1;
    }
    // 17^3 grid (the cube's corners and edges included) plus random colours.
    const int n = 17, w = 128;
    std::vector<float> lin;
    for (int r_ = 0; r_ < n; r_++)
        for (int g = 0; g < n; g++)
            for (int b = 0; b < n; b++) {
                lin.push_back(r_ / float(n - 1));
                lin.push_back(g / float(n - 1));
                lin.push_back(b / float(n - 1));
            }
    mr_rng rng;
    mr_rng_seed(&rng, 11);
    while (lin.size() / 3 % w != 0) lin.push_back(float(mr_rng_uniform(&rng)));
    int h = int(lin.size() / 3 / w);
    mr_image in = {w, h, 3, MR_PIX_F32, lin.data()};
    mr_image lab = {};
    if (!mr_ghost_lab(r, &in, false, &lab, &err)) {
        std::fprintf(stderr, "mr_ghost_lab: %s\n", err.msg);
        failures++;
    } else {
        // OpenCV's RGB2Lab on float input takes sRGB-encoded values in [0,1].
        cv::Mat enc(h, w, CV_32FC3), ref;
        for (int i = 0; i < w * h * 3; i++) enc.ptr<float>()[i] = srgb_encode(lin[size_t(i)]);
        cv::cvtColor(enc, ref, cv::COLOR_RGB2Lab);
        double worst = 0;
        int worst_i = 0;
        const float *gl = static_cast<const float *>(lab.data);
        for (int i = 0; i < w * h; i++) {
            double d2 = 0;
            for (int c = 0; c < 3; c++) {
                double d = gl[i * 3 + c] - ref.ptr<float>()[i * 3 + c];
                d2 += d * d;
            }
            if (std::sqrt(d2) > worst) {
                worst = std::sqrt(d2);
                worst_i = i;
            }
        }
        const float *rf = ref.ptr<float>() + worst_i * 3, *gf = gl + worst_i * 3;
        std::printf("test_ghost_opencv: worst Delta E %.4f at linear rgb (%.3f %.3f %.3f): GPU %.3f %.3f %.3f, "
                    "OpenCV %.3f %.3f %.3f\n",
                    worst, lin[size_t(worst_i) * 3], lin[size_t(worst_i) * 3 + 1], lin[size_t(worst_i) * 3 + 2], gf[0],
                    gf[1], gf[2], rf[0], rf[1], rf[2]);
        if (!(worst <= 0.5)) {
            std::fprintf(stderr, "test_ghost_opencv: Delta E %.4f > 0.5 against cvtColor\n", worst);
            failures++;
        }
        double worst_cpu = 0;
        for (int i = 0; i < w * h; i++) {
            double rgb[3] = {lin[size_t(i) * 3], lin[size_t(i) * 3 + 1], lin[size_t(i) * 3 + 2]}, l[3], d2 = 0;
            mr_eval_rgb_to_lab(rgb, l);
            for (int c = 0; c < 3; c++) d2 += (l[c] - ref.ptr<float>()[i * 3 + c]) * (l[c] - ref.ptr<float>()[i * 3 + c]);
            worst_cpu = std::fmax(worst_cpu, std::sqrt(d2));
        }
        std::printf("test_ghost_opencv: legibility's CPU L*a*b*: worst Delta E %.4f against cvtColor\n", worst_cpu);
        if (!(worst_cpu <= 0.5)) {
            std::fprintf(stderr, "test_ghost_opencv: CPU L*a*b* (mr_eval_rgb_to_lab) Delta E %.4f > 0.5 against cvtColor\n",
                         worst_cpu);
            failures++;
        }
        mr_image_free(&lab);
    }
    mr_renderer_destroy(&r);
    mr_gpu_destroy(&gpu);
    std::printf("test_ghost_opencv: %s\n", failures ? "FAILED" : "passed");
    return failures ? 1 : 0;
}
