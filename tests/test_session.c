/* lib/session: recording round trip, torn and garbage lines, no overwrite,
 * the recording as a frame source, and a small mutation fuzz of the reader.
 * The kill -9 case runs in tests/cli_track.sh. */
#include "mr_session.h"
#include "mr_test.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_tmp[1024];

static void tmp_path(const char *name, char *out, size_t n) { snprintf(out, n, "%s/%s", g_tmp, name); }

static void append_text(const char *path, const char *text) {
    FILE *f = fopen(path, "ab");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* cJSON prints doubles with 15 digits when they read back within an ulp
 * or so, else 17: equal to ~1e-15 relative, not bit for bit. */
static bool same_m4(const mr_dmat4 *a, const mr_dmat4 *b) {
    for (int i = 0; i < 16; i++)
        if (fabs(a->m[i] - b->m[i]) > 1e-14 * (1 + fabs(b->m[i]))) return false;
    return true;
}

static mr_dmat4 pose_of(int i) {
    return mr_m4_look_at_cv(mr_v3(1.0 + 0.1 * i, 1.6, 3.0 - 0.05 * i), mr_v3(0.1 * i, 1.5, 0), mr_v3(0, 1, 0));
}

static void test_round_trip(void) {
    char dir[1100], path[1200];
    tmp_path("rec_rt", dir, sizeof dir);
    mr_camera cam = {64, 48, 50, 50, 31.5, 23.5, {0.01, 0, 0, 0, 0}};
    mr_marker tags[2] = {{3, mr_m4_translate(0, 1, 0)}, {8, mr_m4_translate(1, 1, 0)}};
    mr_marker_map map = {"tag36h11", 0.2, tags, 2};
    mr_recorder_params rp = MR_RECORDER_DEFAULTS;
    rp.camera = &cam;
    rp.markers = &map;
    rp.source = "test";
    rp.frame_ext = ".png";
    rp.ground_truth = true;
    mr_error err = {0};
    mr_recorder *r = mr_recorder_create(dir, &rp, &err);
    CHECK_MSG(r != NULL, "%s", err.msg);
    if (!r) return;
    mr_image img;
    mr_image_alloc(&img, 64, 48, 1, MR_PIX_U8, NULL);
    for (int i = 0; i < 5; i++) {
        for (int k = 0; k < 64 * 48; k++) ((unsigned char *)img.data)[k] = (unsigned char)(k * 7 + i * 31);
        mr_detection d[2] = {{3, 0, 40, {{1.25, 2.5}, {10, 2.5}, {10, 11}, {1.25, 11}}},
                             {8, 1, 20, {{20.125, 2}, {30, 2}, {30, 12}, {20.125, 12}}}};
        mr_frame_record fr = {0};
        fr.t = 0.1 * i + 1e-9;
        fr.detections = d;
        fr.detection_count = i % 3;
        fr.pose.valid = i != 2;
        fr.pose.world_from_camera = pose_of(i);
        fr.pose.tags_used = 2;
        fr.pose.tags_seen = 2;
        fr.pose.ids_used[0] = 3;
        fr.pose.ids_used[1] = 8;
        fr.pose.rms_px = 0.25 * i;
        fr.has_filtered = i != 2;
        fr.filtered = pose_of(i + 1);
        CHECK(mr_recorder_append(r, &fr, &img, &err));
        CHECK(fr.index == i);
        CHECK(mr_recorder_ground_truth(r, fr.index, fr.t, &fr.filtered, i >= 3, &err));
    }
    CHECK(mr_recorder_frame_count(r) == 5);
    mr_recorder_close(&r);
    CHECK(r == NULL);
    /* Never over an existing recording. */
    CHECK(mr_recorder_create(dir, &rp, &err) == NULL && strstr(err.msg, "already"));

    mr_recording *rec = mr_recording_open(dir, &err);
    CHECK_MSG(rec != NULL, "%s", err.msg);
    if (!rec) return;
    CHECK(rec->frame_count == 5 && rec->bad_lines == 0 && !rec->torn_tail);
    CHECK(rec->camera.fx == 50 && rec->camera.dist[0] == 0.01 && rec->has_markers && rec->markers.count == 2);
    for (int i = 0; i < rec->frame_count; i++) {
        const mr_rec_frame *f = &rec->frames[i];
        CHECK(f->index == i && fabs(f->t - (0.1 * i + 1e-9)) < 1e-15);
        CHECK(f->pose.valid == (i != 2) && f->has_filtered == (i != 2));
        if (f->pose.valid) {
            mr_dmat4 want = pose_of(i), wantf = pose_of(i + 1);
            CHECK(same_m4(&f->pose.world_from_camera, &want));
            CHECK(same_m4(&f->filtered, &wantf));
            CHECK(f->pose.tags_used == 2 && f->pose.ids_used[1] == 8 && f->pose.rms_px == 0.25 * i);
        }
        CHECK(f->detection_count == i % 3);
        if (f->detection_count == 2) CHECK(f->detections[1].id == 8 && f->detections[1].corners[0][0] == 20.125);
        CHECK(f->has_gt && f->still == (i >= 3));
        mr_image back;
        CHECK(mr_recording_load_image(rec, i, true, &back, &err));
        for (int k = 0; k < 64 * 48; k++) ((unsigned char *)img.data)[k] = (unsigned char)(k * 7 + i * 31);
        CHECK(back.width == 64 && back.height == 48 && memcmp(back.data, img.data, 64 * 48) == 0);
        mr_image_free(&back);
    }
    mr_recording_close(&rec);

    /* A torn last line (a crash mid-write) is skipped quietly ... */
    snprintf(path, sizeof path, "%s/frames.jsonl", dir);
    append_text(path, "{\"frame\":5,\"t\":0.5,\"image\":\"frames/0000");
    rec = mr_recording_open(dir, &err);
    CHECK(rec && rec->frame_count == 5 && rec->torn_tail && rec->bad_lines == 0);
    mr_recording_close(&rec);
    /* ... a garbage line is counted and skipped, later lines still read. */
    append_text(path, "\ngarbage ]]\n{\"frame\":6,\"t\":0.6,\"image\":\"frames/000001.png\"}\n"
                      "{\"frame\":7,\"t\":0.7,\"image\":\"../../etc/passwd\"}\n"
                      "{\"frame\":8,\"t\":0.8,\"pose\":{\"valid\":true,\"world_from_camera\":[2,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}}\n");
    rec = mr_recording_open(dir, &err);
    CHECK(rec != NULL);
    if (rec) {
        /* the old torn line, now ended by the newline, the garbage, the
         * path escape and the non-rigid pose: 4 bad lines */
        CHECK_MSG(rec->frame_count == 6 && rec->bad_lines == 4 && !rec->torn_tail, "frames %d bad %d", rec->frame_count,
                  rec->bad_lines);
        /* as a frame source: 6 frames, in order, timestamps as recorded */
        mr_source *src = mr_recording_source(rec, true, &err);
        int n = 0;
        mr_frame f;
        double last_t = -1;
        while (src && mr_source_read(src, &f, &err) == MR_READ_FRAME) {
            CHECK(f.image.width == 64 && f.timestamp > last_t);
            last_t = f.timestamp;
            n++;
        }
        CHECK(n == 6);
        CHECK(strcmp(mr_source_kind(src), "recording") == 0);
        mr_source_close(&src);
    }
    /* A missing image is skipped by the source, with a warning. */
    snprintf(path, sizeof path, "%s/frames/000003.png", dir);
    CHECK(unlink(path) == 0);
    rec = mr_recording_open(dir, &err);
    mr_source *src = rec ? mr_recording_source(rec, false, &err) : NULL;
    int n = 0;
    mr_frame f;
    while (src && mr_source_read(src, &f, &err) == MR_READ_FRAME) {
        CHECK(f.index != 3 && f.image.channels == 3);
        n++;
    }
    CHECK(n == 5);
    mr_source_close(&src);
    mr_image_free(&img);
    /* Not a recording. */
    CHECK(mr_recording_open(g_tmp, &err) == NULL && err.msg[0]);
    CHECK(!mr_is_recording(g_tmp) && mr_is_recording(dir));
}

/* Mutations of valid lines must never crash the reader or yield a
 * non-rigid pose. */
static void test_mutations(void) {
    const char *seed =
        "{\"frame\":0,\"t\":0,\"image\":\"frames/000000.jpg\",\"detections\":[{\"id\":2,\"hamming\":0,\"corners\":"
        "[[43.2,232.5],[72.0,232.5],[72.7,202.4],[44.2,202.3]]}],\"pose\":{\"valid\":true,\"world_from_camera\":"
        "[1,0,0,12.4,0,-1,0,1.6,0,0,-1,-5.5,0,0,0,1],\"tags_seen\":1,\"tags_used\":1,\"rms_px\":0.2,\"ambiguous\":false,"
        "\"ids\":[2]},\"filtered\":[1,0,0,12.4,0,-1,0,1.6,0,0,-1,-5.5,0,0,0,1]}\n";
    size_t n = strlen(seed);
    char buf[2048];
    mr_rng rng;
    mr_rng_seed(&rng, 11);
    int frames = 0;
    for (int it = 0; it < 3000; it++) {
        memcpy(buf, seed, n);
        int muts = 1 + (int)(mr_rng_u64(&rng) % 4);
        for (int m = 0; m < muts; m++) buf[mr_rng_u64(&rng) % n] = (char)(mr_rng_u64(&rng) & 0xff);
        size_t len = it % 7 == 0 ? mr_rng_u64(&rng) % n : n;
        mr_recording rec;
        memset(&rec, 0, sizeof rec);
        mr_error err = {0};
        mr_recording_parse_frames(&rec, buf, len, &err);
        mr_recording_parse_ground_truth(&rec, buf, len);
        for (int i = 0; i < rec.frame_count; i++) {
            frames++;
            if (rec.frames[i].pose.valid) CHECK(mr_m4_is_rigid(&rec.frames[i].pose.world_from_camera, 1e-5));
            CHECK(rec.frames[i].detection_count >= 0 && rec.frames[i].detection_count <= 10000);
            free(rec.frames[i].detections);
        }
        free(rec.frames);
    }
    printf("mutations: %d of 3000 still parsed as a frame\n", frames);
    CHECK(frames > 0 && frames < 3000);
}

int main(void) {
    const char *t = getenv("MR_TEST_TMP");
    snprintf(g_tmp, sizeof g_tmp, "%s/test_session", t ? t : "/tmp/mrcheck-test");
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_tmp);
    if (system(cmd) != 0) return 1;
    mr_error err = {0};
    if (!mr_mkdirs(g_tmp, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    test_round_trip();
    test_mutations();
    return mr_test_finish("test_session");
}
