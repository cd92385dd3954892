/* Frame sources: a video written from the shipped recording reads back with
 * the same tags; truncated and corrupt videos end or fail cleanly; image
 * folders skip damaged files; V4L2 reports a missing device. */
#include "mr_session.h"
#include "mr_test.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static char g_tmp[1024];

static int count_frames(const char *path, int *tags, bool *error) {
    mr_error err = {0};
    *error = false;
    *tags = 0;
    mr_source *s = mr_source_open(path, NULL, &err);
    if (!s) {
        *error = true;
        CHECK(err.msg[0] && !strchr(err.msg, '\n'));
        return -1;
    }
    mr_detector *d = mr_detector_create(NULL, &err);
    int n = 0;
    mr_frame f;
    mr_read_status st;
    while ((st = mr_source_read(s, &f, &err)) == MR_READ_FRAME) {
        int c = 0;
        if (mr_detector_detect(d, &f.image, &c, &err)) *tags += c;
        n++;
    }
    if (st == MR_READ_ERROR) *error = true;
    mr_detector_destroy(&d);
    mr_source_close(&s);
    return n;
}

static void copy_prefix(const char *from, const char *to, long bytes) {
    FILE *a = fopen(from, "rb"), *b = fopen(to, "wb");
    char buf[65536];
    long left = bytes;
    while (a && b && left > 0) {
        size_t n = fread(buf, 1, (size_t)(left < (long)sizeof buf ? left : (long)sizeof buf), a);
        if (n == 0) break;
        fwrite(buf, 1, n, b);
        left -= (long)n;
    }
    if (a) fclose(a);
    if (b) fclose(b);
}

int main(void) {
    const char *t = getenv("MR_TEST_TMP"), *src = getenv("MR_SOURCE_DIR");
    snprintf(g_tmp, sizeof g_tmp, "%s/test_sources", t ? t : "/tmp/mrcheck-test");
    mr_error err = {0};
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_tmp); /* a clean start: no video from an earlier run */
    if (system(cmd) != 0) return 1;
    CHECK(mr_mkdirs(g_tmp, &err));
    char dir[2048], video[2048], cut[2048], path[4200];
    snprintf(dir, sizeof dir, "%s/recordings/demo", src ? src : ".");
    snprintf(video, sizeof video, "%s/demo.avi", g_tmp);
    mr_recording *rec = mr_recording_open(dir, &err);
    CHECK_MSG(rec != NULL, "%s", err.msg);
    if (!rec) return mr_test_finish("test_sources");
    /* 20 frames with tags into a video; count the tags from the images. */
    mr_video_writer *w = NULL;
    mr_detector *d = mr_detector_create(NULL, &err);
    int written = 0, tags_img = 0;
    for (int i = 0; i < rec->frame_count && written < 20; i++) {
        if (rec->frames[i].detection_count == 0) continue;
        mr_image img;
        if (!mr_recording_load_image(rec, i, true, &img, &err)) continue;
        if (!w) w = mr_video_writer_open(video, img.width, img.height, 10, &err);
        CHECK(w && mr_video_writer_add(w, &img, &err));
        int c = 0;
        mr_detector_detect(d, &img, &c, &err);
        tags_img += c;
        written++;
        mr_image_free(&img);
    }
    CHECK(!mr_file_exists(video)); /* not under its name until closed */
    CHECK(mr_video_writer_close(&w, &err) && mr_file_exists(video));
    mr_detector_destroy(&d);
    int tags = 0;
    bool error = false;
    int n = count_frames(video, &tags, &error);
    printf("video: %d frames, %d tags (images: %d frames, %d tags)\n", n, tags, written, tags_img);
    CHECK(n == written && !error);
    CHECK(tags >= tags_img * 9 / 10); /* MJPEG recompression may lose a marginal tag */
    /* Truncated to half: fewer frames, then the end (or an error) — no crash. */
    struct stat st;
    stat(video, &st);
    snprintf(cut, sizeof cut, "%s/half.avi", g_tmp);
    copy_prefix(video, cut, (long)st.st_size / 2);
    n = count_frames(cut, &tags, &error);
    printf("truncated video: %d frames%s\n", n, error ? " then an error" : "");
    CHECK(n < written);
    /* Nearly nothing left, or garbage: a clear failure to open. */
    snprintf(cut, sizeof cut, "%s/stub.avi", g_tmp);
    copy_prefix(video, cut, 100);
    n = count_frames(cut, &tags, &error);
    CHECK(n <= 0);
    snprintf(path, sizeof path, "%s/garbage.mp4", g_tmp);
    FILE *f = fopen(path, "wb");
    for (int i = 0; f && i < 5000; i++) fputc((i * 7919) & 0xff, f);
    if (f) fclose(f);
    CHECK(count_frames(path, &tags, &error) < 0 && error);
    snprintf(path, sizeof path, "%s/empty.mp4", g_tmp);
    f = fopen(path, "wb");
    if (f) fclose(f);
    CHECK(count_frames(path, &tags, &error) < 0 && error);
    /* An image folder with a damaged file: it is skipped. */
    char imgdir[2048];
    snprintf(imgdir, sizeof imgdir, "%s/images", g_tmp);
    CHECK(mr_mkdirs(imgdir, &err));
    mr_image img;
    CHECK(mr_recording_load_image(rec, 0, true, &img, &err));
    snprintf(path, sizeof path, "%s/a.png", imgdir);
    CHECK(mr_image_save_png(path, &img, &err));
    snprintf(path, sizeof path, "%s/c.png", imgdir);
    CHECK(mr_image_save_png(path, &img, &err));
    snprintf(path, sizeof path, "%s/b.png", imgdir);
    f = fopen(path, "wb");
    if (f) {
        fputs("\x89PNG broken", f);
        fclose(f);
    }
    mr_image_free(&img);
    n = count_frames(imgdir, &tags, &error);
    CHECK(n == 2 && !error && tags == 2 * rec->frames[0].detection_count);
    /* Missing things. */
    CHECK(count_frames("/dev/video99", &tags, &error) < 0 && error);
    mr_source *s = mr_source_open("/dev/video99", NULL, &err);
    CHECK(!s && err.code == MR_ERR_IO && strstr(err.msg, "no such device"));
    s = mr_source_open("/dev/null", NULL, &err);
    CHECK(!s && err.msg[0]); /* a character device, but not V4L2 */
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.pixel_format = "RGB3";
    s = mr_source_open_v4l2("/dev/video99", &sp, &err);
    CHECK(!s && err.code == MR_ERR_UNSUPPORTED);
    snprintf(path, sizeof path, "%s/nothing-here", g_tmp);
    CHECK(count_frames(path, &tags, &error) < 0);
    mr_recording_close(&rec);
    return mr_test_finish("test_sources");
}
