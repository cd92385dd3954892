/* V4L2 capture: memory-mapped streaming, YUYV or MJPEG, size and frame-rate
 * negotiation; a device that vanishes mid-stream (ENODEV/EIO) is closed and
 * reopened `retries` times before the read fails. */
#include "mr_track.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/select.h>
#include <time.h>
#include <unistd.h>

#define NBUF 4

typedef struct v4l2_src {
    char dev[256];
    mr_source_params p;
    int fd;
    uint32_t pixfmt;
    int width, height, stride;
    struct { void *ptr; size_t len; } buf[NBUF];
    int nbuf;
    bool streaming;
    int64_t index;
    mr_image img;
} v4l2_src;

static int xioctl(int fd, unsigned long req, void *arg) {
    int r;
    do r = ioctl(fd, req, arg);
    while (r == -1 && errno == EINTR);
    return r;
}

static void fourcc_str(uint32_t f, char out[5]) {
    for (int i = 0; i < 4; i++) {
        char c = (char)((f >> (8 * i)) & 0xff);
        out[i] = c >= 32 && c < 127 ? c : '?';
    }
    out[4] = 0;
}

static void dev_close(v4l2_src *s) {
    if (s->fd < 0) return;
    if (s->streaming) {
        enum v4l2_buf_type t = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        xioctl(s->fd, VIDIOC_STREAMOFF, &t);
        s->streaming = false;
    }
    for (int i = 0; i < s->nbuf; i++)
        if (s->buf[i].ptr && s->buf[i].ptr != MAP_FAILED) munmap(s->buf[i].ptr, s->buf[i].len);
    s->nbuf = 0;
    close(s->fd);
    s->fd = -1;
}

static bool has_format(int fd, uint32_t f) {
    struct v4l2_fmtdesc d;
    for (uint32_t i = 0; i < 256; i++) {
        memset(&d, 0, sizeof d);
        d.index = i;
        d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (xioctl(fd, VIDIOC_ENUM_FMT, &d) < 0) return false;
        if (d.pixelformat == f) return true;
    }
    return false;
}

static bool dev_open(v4l2_src *s, mr_error *err) {
    s->fd = open(s->dev, O_RDWR | O_NONBLOCK);
    if (s->fd < 0) {
        int e = errno;
        if (e == ENOENT || e == ENODEV || e == ENXIO) return mr_fail(err, MR_ERR_IO, "%s: no such device", s->dev);
        if (e == EBUSY) return mr_fail(err, MR_ERR_IO, "%s: device is busy (used by another program)", s->dev);
        if (e == EACCES) return mr_fail(err, MR_ERR_IO, "%s: permission denied (video group?)", s->dev);
        return mr_fail(err, MR_ERR_IO, "%s: cannot open (%s)", s->dev, strerror(e));
    }
    struct v4l2_capability cap;
    memset(&cap, 0, sizeof cap);
    if (xioctl(s->fd, VIDIOC_QUERYCAP, &cap) < 0) {
        dev_close(s);
        return mr_fail(err, MR_ERR_UNSUPPORTED, "%s: not a V4L2 device", s->dev);
    }
    uint32_t caps = cap.capabilities & V4L2_CAP_DEVICE_CAPS ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
        dev_close(s);
        return mr_fail(err, MR_ERR_UNSUPPORTED, "%s: not a streaming video capture device", s->dev);
    }
    /* Pixel format: as asked, else YUYV, else MJPEG. */
    uint32_t want = 0;
    if (s->p.pixel_format) {
        if (strcmp(s->p.pixel_format, "YUYV") == 0) want = V4L2_PIX_FMT_YUYV;
        else if (strcmp(s->p.pixel_format, "MJPG") == 0 || strcmp(s->p.pixel_format, "MJPEG") == 0) want = V4L2_PIX_FMT_MJPEG;
        else {
            dev_close(s);
            return mr_fail(err, MR_ERR_UNSUPPORTED, "pixel format '%.8s' is not supported (YUYV or MJPG)", s->p.pixel_format);
        }
        if (!has_format(s->fd, want)) {
            dev_close(s);
            return mr_fail(err, MR_ERR_UNSUPPORTED, "%s: does not offer pixel format %s", s->dev, s->p.pixel_format);
        }
    } else {
        want = has_format(s->fd, V4L2_PIX_FMT_YUYV) ? V4L2_PIX_FMT_YUYV
               : has_format(s->fd, V4L2_PIX_FMT_MJPEG) ? V4L2_PIX_FMT_MJPEG : 0;
        if (!want) {
            dev_close(s);
            return mr_fail(err, MR_ERR_UNSUPPORTED, "%s: offers neither YUYV nor MJPEG", s->dev);
        }
    }
    struct v4l2_format fmt;
    memset(&fmt, 0, sizeof fmt);
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = (uint32_t)(s->p.width > 0 ? s->p.width : 1280);
    fmt.fmt.pix.height = (uint32_t)(s->p.height > 0 ? s->p.height : 720);
    fmt.fmt.pix.pixelformat = want;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (xioctl(s->fd, VIDIOC_S_FMT, &fmt) < 0) {
        int e = errno;
        dev_close(s);
        return mr_fail(err, e == EBUSY ? MR_ERR_IO : MR_ERR_UNSUPPORTED, "%s: cannot set the format (%s)", s->dev,
                       strerror(e));
    }
    if (fmt.fmt.pix.pixelformat != want) {
        char got[5];
        fourcc_str(fmt.fmt.pix.pixelformat, got);
        dev_close(s);
        return mr_fail(err, MR_ERR_UNSUPPORTED, "%s: driver chose unsupported pixel format %s", s->dev, got);
    }
    s->pixfmt = want;
    s->width = (int)fmt.fmt.pix.width;
    s->height = (int)fmt.fmt.pix.height;
    s->stride = (int)fmt.fmt.pix.bytesperline;
    if (s->stride < 2 * s->width) s->stride = 2 * s->width;
    /* Frame rate: a request, the driver may round it. */
    struct v4l2_streamparm parm;
    memset(&parm, 0, sizeof parm);
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    double fps = s->p.fps > 0 ? s->p.fps : 30.0;
    parm.parm.capture.timeperframe.numerator = 1000;
    parm.parm.capture.timeperframe.denominator = (uint32_t)(fps * 1000.0 + 0.5);
    if (xioctl(s->fd, VIDIOC_S_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator)
        mr_log(MR_LOG_INFO, "%s: %dx%d at %.2f fps", s->dev, s->width, s->height,
               (double)parm.parm.capture.timeperframe.denominator / parm.parm.capture.timeperframe.numerator);
    struct v4l2_requestbuffers req;
    memset(&req, 0, sizeof req);
    req.count = NBUF;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(s->fd, VIDIOC_REQBUFS, &req) < 0 || req.count < 2) {
        int e = errno;
        dev_close(s);
        if (e == EBUSY) return mr_fail(err, MR_ERR_IO, "%s: device is busy (streaming to another program)", s->dev);
        return mr_fail(err, MR_ERR_UNSUPPORTED, "%s: memory-mapped streaming is not available", s->dev);
    }
    s->nbuf = req.count > NBUF ? NBUF : (int)req.count;
    for (int i = 0; i < s->nbuf; i++) {
        struct v4l2_buffer b;
        memset(&b, 0, sizeof b);
        b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        b.memory = V4L2_MEMORY_MMAP;
        b.index = (uint32_t)i;
        s->buf[i].ptr = NULL;
        if (xioctl(s->fd, VIDIOC_QUERYBUF, &b) < 0) {
            dev_close(s);
            return mr_fail(err, MR_ERR_IO, "%s: cannot query buffer %d", s->dev, i);
        }
        s->buf[i].len = b.length;
        s->buf[i].ptr = mmap(NULL, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, s->fd, b.m.offset);
        if (s->buf[i].ptr == MAP_FAILED || xioctl(s->fd, VIDIOC_QBUF, &b) < 0) {
            dev_close(s);
            return mr_fail(err, MR_ERR_IO, "%s: cannot map/queue buffer %d", s->dev, i);
        }
    }
    enum v4l2_buf_type t = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(s->fd, VIDIOC_STREAMON, &t) < 0) {
        int e = errno;
        dev_close(s);
        return mr_fail(err, MR_ERR_IO, "%s: cannot start streaming (%s)", s->dev, strerror(e));
    }
    s->streaming = true;
    return true;
}

static bool yuyv_convert(v4l2_src *s, const unsigned char *src, size_t len, mr_error *err) {
    if (len < (size_t)s->stride * (size_t)(s->height - 1) + 2u * (size_t)s->width)
        return mr_fail(err, MR_ERR_PARSE, "short YUYV frame (%zu bytes)", len);
    int ch = s->p.gray ? 1 : 3;
    if (s->img.width != s->width || s->img.height != s->height || s->img.channels != ch || !s->img.data) {
        mr_image_free(&s->img);
        if (!mr_image_alloc(&s->img, s->width, s->height, ch, MR_PIX_U8, err)) return false;
    }
    unsigned char *o = s->img.data;
    for (int y = 0; y < s->height; y++) {
        const unsigned char *r = src + (size_t)y * s->stride;
        for (int x = 0; x < s->width; x++) {
            int Y = r[2 * x];
            if (ch == 1) {
                o[(size_t)y * s->width + x] = (unsigned char)Y;
                continue;
            }
            /* YUYV: Y0 U Y1 V per pixel pair; BT.601 limited range. */
            int U = r[(x & ~1) * 2 + 1] - 128, V = r[(x & ~1) * 2 + 3] - 128, C = 298 * (Y - 16);
            int rgb[3] = {(C + 409 * V + 128) >> 8, (C - 100 * U - 208 * V + 128) >> 8, (C + 516 * U + 128) >> 8};
            unsigned char *px = o + ((size_t)y * s->width + x) * 3;
            for (int c = 0; c < 3; c++) px[c] = (unsigned char)(rgb[c] < 0 ? 0 : rgb[c] > 255 ? 255 : rgb[c]);
        }
    }
    return true;
}

static bool sleep_s(double s) {
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    return nanosleep(&ts, NULL) == 0;
}

static mr_read_status v4l2_read(void *impl, mr_frame *frame, mr_error *err) {
    v4l2_src *s = impl;
    int retries = s->p.retries == 0 ? 5 : s->p.retries < 0 ? 0 : s->p.retries;
    double retry_s = s->p.retry_s > 0 ? s->p.retry_s : 1.0;
    int attempt = 0, timeouts = 0;
    for (;;) {
        bool lost = s->fd < 0;
        if (!lost) {
            fd_set fds;
            FD_ZERO(&fds);
            FD_SET(s->fd, &fds);
            struct timeval tv = {2, 0};
            int r = select(s->fd + 1, &fds, NULL, NULL, &tv);
            if (r < 0 && errno == EINTR) continue;
            if (r == 0) {
                if (++timeouts >= 3) {
                    mr_fail(err, MR_ERR_IO, "%s: no frame for 6 s", s->dev);
                    return MR_READ_ERROR;
                }
                continue;
            }
            struct v4l2_buffer b;
            memset(&b, 0, sizeof b);
            b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            b.memory = V4L2_MEMORY_MMAP;
            if (r > 0 && xioctl(s->fd, VIDIOC_DQBUF, &b) == 0) {
                bool ok = b.index < (uint32_t)s->nbuf;
                mr_error e = {0};
                if (ok && s->pixfmt == V4L2_PIX_FMT_YUYV) {
                    ok = yuyv_convert(s, s->buf[b.index].ptr, b.bytesused ? b.bytesused : s->buf[b.index].len, &e);
                } else if (ok) {
                    mr_image dec;
                    ok = mr_image_decode(s->buf[b.index].ptr, b.bytesused, s->p.gray ? 1 : 3, &dec, &e);
                    if (ok) {
                        mr_image_free(&s->img);
                        s->img = dec;
                    }
                }
                double ts = (double)b.timestamp.tv_sec + 1e-6 * (double)b.timestamp.tv_usec;
                xioctl(s->fd, VIDIOC_QBUF, &b);
                if (!ok) {
                    /* A corrupt MJPEG frame happens on USB hiccups: skip it. */
                    mr_log(MR_LOG_WARN, "%s: dropping a bad frame: %s", s->dev, e.msg);
                    continue;
                }
                memset(frame, 0, sizeof *frame);
                frame->image = s->img;
                frame->index = s->index++;
                frame->timestamp = ts;
                return MR_READ_FRAME;
            }
            if (r > 0 && errno == EAGAIN) continue;
            lost = true;
            mr_log(MR_LOG_WARN, "%s: capture failed (%s); reopening", s->dev, strerror(errno));
        }
        dev_close(s);
        if (attempt >= retries) {
            mr_fail(err, MR_ERR_IO, "%s: device vanished and did not come back after %d attempts", s->dev, retries);
            return MR_READ_ERROR;
        }
        attempt++;
        sleep_s(retry_s);
        mr_error e = {0};
        if (!dev_open(s, &e)) mr_log(MR_LOG_WARN, "%s: reopen %d/%d failed: %s", s->dev, attempt, retries, e.msg);
    }
}

static void v4l2_close(void *impl) {
    v4l2_src *s = impl;
    dev_close(s);
    mr_image_free(&s->img);
    free(s);
}

static const mr_source_ops k_v4l2_ops = {"v4l2", v4l2_read, v4l2_close};

mr_source *mr_source_open_v4l2(const char *device, const mr_source_params *params, mr_error *err) {
    v4l2_src *s = calloc(1, sizeof *s);
    if (!s) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    s->p = params ? *params : (mr_source_params)MR_SOURCE_DEFAULTS;
    s->p.pixel_format = NULL;
    snprintf(s->dev, sizeof s->dev, "%s", device);
    /* Keep a copy of the format name: the caller's string may not outlive us. */
    static const char *const known[] = {"YUYV", "MJPG", "MJPEG"};
    if (params && params->pixel_format) {
        for (size_t i = 0; i < 3; i++)
            if (strcmp(params->pixel_format, known[i]) == 0) s->p.pixel_format = known[i];
        if (!s->p.pixel_format) {
            free(s);
            mr_fail(err, MR_ERR_UNSUPPORTED, "pixel format '%.8s' is not supported (YUYV or MJPG)", params->pixel_format);
            return NULL;
        }
    }
    s->fd = -1;
    if (!dev_open(s, err)) {
        free(s);
        return NULL;
    }
    return mr_source_from_ops(&k_v4l2_ops, s, err);
}
