// Video files (cv::VideoCapture) and JPEG/PNG coding (cv::imencode /
// imdecode) behind an extern "C" face. No OpenCV type leaves this file.
#include "track_internal.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdio>
#include <cstdlib>
#include <unistd.h>
#include <cstring>
#include <string>
#include <vector>

struct mr_cv_video {
    cv::VideoCapture cap;
    cv::Mat bgr, out;
};

extern "C" mr_cv_video *mr_cv_video_open(const char *path, mr_error *err) {
    // FFmpeg logs its own complaints ("moov atom not found") on stderr,
    // which breaks the one-line-per-error rule; OpenCV reads this variable
    // once, when its FFmpeg backend starts. A user's own setting is kept.
    setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0);
    try {
        mr_cv_video *v = new mr_cv_video;
        // FFmpeg explicitly: the "any" backend would also try V4L2 and
        // image-sequence patterns, which have their own sources here.
        if (!v->cap.open(path, cv::CAP_FFMPEG) || !v->cap.isOpened()) {
            delete v;
            mr_fail(err, MR_ERR_PARSE, "%s: cannot open as a video (missing, corrupt or unsupported format)", path);
            return nullptr;
        }
        return v;
    } catch (const std::exception &e) {
        mr_fail(err, MR_ERR_PARSE, "%s: cannot open as a video (%.200s)", path, e.what());
        return nullptr;
    }
}

extern "C" int mr_cv_video_read(mr_cv_video *v, bool gray, mr_image *img, double *t_s, mr_error *err) {
    try {
        if (!v->cap.read(v->bgr) || v->bgr.empty()) return 0;
        double ms = v->cap.get(cv::CAP_PROP_POS_MSEC);
        *t_s = ms / 1000.0;
        if (v->bgr.depth() != CV_8U) {
            mr_fail(err, MR_ERR_UNSUPPORTED, "video frame is not 8-bit");
            return -1;
        }
        int code = v->bgr.channels() == 1 ? -1 : gray ? cv::COLOR_BGR2GRAY : cv::COLOR_BGR2RGB;
        if (code >= 0) cv::cvtColor(v->bgr, v->out, code);
        else v->out = v->bgr;
        if (!v->out.isContinuous()) v->out = v->out.clone();
        int ch = v->out.channels();
        if (img->width != v->out.cols || img->height != v->out.rows || img->channels != ch || !img->data) {
            mr_image_free(img);
            if (!mr_image_alloc(img, v->out.cols, v->out.rows, ch, MR_PIX_U8, err)) return -1;
        }
        std::memcpy(img->data, v->out.data, mr_image_bytes(img));
        return 1;
    } catch (const std::exception &e) {
        mr_fail(err, MR_ERR_PARSE, "video decode error (%.200s)", e.what());
        return -1;
    }
}

extern "C" void mr_cv_video_close(mr_cv_video *v) { delete v; }

struct mr_video_writer {
    cv::VideoWriter vw;
    std::string path, tmp;
    int width, height;
    cv::Mat bgr;
};

extern "C" mr_video_writer *mr_video_writer_open(const char *path, int width, int height, double fps, mr_error *err) {
    if (width < 1 || height < 1 || !(fps > 0)) {
        mr_fail(err, MR_ERR_INVALID, "video: bad size or rate");
        return nullptr;
    }
    try {
        mr_video_writer *w = new mr_video_writer;
        w->path = path;
        w->tmp = w->path + ".tmp." + std::to_string((long)getpid()) + ".avi";
        w->width = width;
        w->height = height;
        if (!w->vw.open(w->tmp, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps,
                        cv::Size(width, height), true)) {
            delete w;
            mr_fail(err, MR_ERR_IO, "%s: cannot create the video", path);
            return nullptr;
        }
        return w;
    } catch (const std::exception &e) {
        mr_fail(err, MR_ERR_IO, "%s: cannot create the video (%.200s)", path, e.what());
        return nullptr;
    }
}

extern "C" bool mr_video_writer_add(mr_video_writer *w, const mr_image *img, mr_error *err) {
    if (!img || !img->data || img->type != MR_PIX_U8 || (img->channels != 1 && img->channels != 3) ||
        img->width != w->width || img->height != w->height)
        return mr_fail(err, MR_ERR_INVALID, "video: frame must be 8-bit grey/RGB %dx%d", w->width, w->height);
    try {
        cv::Mat m(img->height, img->width, img->channels == 1 ? CV_8UC1 : CV_8UC3, img->data);
        cv::cvtColor(m, w->bgr, img->channels == 1 ? cv::COLOR_GRAY2BGR : cv::COLOR_RGB2BGR);
        w->vw.write(w->bgr);
        return true;
    } catch (const std::exception &e) {
        return mr_fail(err, MR_ERR_IO, "video: cannot write a frame (%.200s)", e.what());
    }
}

extern "C" bool mr_video_writer_close(mr_video_writer **pw, mr_error *err) {
    if (!pw || !*pw) return true;
    mr_video_writer *w = *pw;
    *pw = nullptr;
    w->vw.release();
    bool ok = std::rename(w->tmp.c_str(), w->path.c_str()) == 0;
    if (!ok) {
        mr_fail(err, MR_ERR_IO, "%s: cannot rename the finished video into place", w->path.c_str());
        std::remove(w->tmp.c_str());
    }
    delete w;
    return ok;
}

extern "C" void mr_video_writer_abort(mr_video_writer **pw) {
    if (!pw || !*pw) return;
    (*pw)->vw.release();
    std::remove((*pw)->tmp.c_str());
    delete *pw;
    *pw = nullptr;
}

extern "C" bool mr_image_encode(const mr_image *img, const char *ext, int quality, void **data, size_t *size,
                                mr_error *err) {
    *data = nullptr;
    *size = 0;
    if (!img || !img->data || img->type != MR_PIX_U8 || (img->channels != 1 && img->channels != 3))
        return mr_fail(err, MR_ERR_INVALID, "encode: needs an 8-bit grey or RGB image");
    try {
        cv::Mat m(img->height, img->width, img->channels == 1 ? CV_8UC1 : CV_8UC3, img->data), bgr;
        if (img->channels == 3) cv::cvtColor(m, bgr, cv::COLOR_RGB2BGR);
        else bgr = m;
        std::vector<int> prm;
        std::string e = ext ? ext : ".png";
        if (e == ".jpg" || e == ".jpeg") prm = {cv::IMWRITE_JPEG_QUALITY, quality < 1 ? 1 : quality > 100 ? 100 : quality};
        std::vector<unsigned char> buf;
        if (!cv::imencode(e, bgr, buf, prm)) return mr_fail(err, MR_ERR_UNSUPPORTED, "cannot encode %s", e.c_str());
        void *p = std::malloc(buf.size() ? buf.size() : 1);
        if (!p) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        std::memcpy(p, buf.data(), buf.size());
        *data = p;
        *size = buf.size();
        return true;
    } catch (const std::exception &ex) {
        return mr_fail(err, MR_ERR_UNSUPPORTED, "encode failed (%.200s)", ex.what());
    }
}

extern "C" bool mr_image_decode(const void *data, size_t size, int channels, mr_image *img, mr_error *err) {
    std::memset(img, 0, sizeof *img);
    if (!data || size == 0 || size > (1u << 30)) return mr_fail(err, MR_ERR_PARSE, "decode: empty or huge buffer");
    try {
        cv::Mat buf(1, (int)size, CV_8UC1, const_cast<void *>(data));
        cv::Mat m = cv::imdecode(buf, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
        if (m.empty()) return mr_fail(err, MR_ERR_PARSE, "cannot decode the image data");
        if (m.channels() == 3) cv::cvtColor(m, m, cv::COLOR_BGR2RGB);
        if (!m.isContinuous()) m = m.clone();
        if (!mr_image_alloc(img, m.cols, m.rows, m.channels(), MR_PIX_U8, err)) return false;
        std::memcpy(img->data, m.data, mr_image_bytes(img));
        return true;
    } catch (const std::exception &ex) {
        return mr_fail(err, MR_ERR_PARSE, "cannot decode the image data (%.200s)", ex.what());
    }
}
