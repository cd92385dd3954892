/* lib/session: recording round trip, torn and garbage lines, no overwrite,
 * the recording as a frame source, a small mutation fuzz of the reader,
 * the replay index (random access, seek by frame and by time), the durable
 * annotation append (fsync calls seen through the linker: --wrap=fsync)
 * and the tolerant annotations reader. The kill -9 case runs in
 * tests/cli_track.sh and tests/cli_view.sh. */
#include "mr_session.h"
#include "mr_test.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* fsync as the linker sees it: counts file and folder syncs, or fails. */
int __real_fsync(int fd);
int __wrap_fsync(int fd);
static int g_sync_files, g_sync_dirs;
static bool g_sync_fail;
int __wrap_fsync(int fd) {
    struct stat st;
    if (fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) g_sync_dirs++;
    else g_sync_files++;
    if (g_sync_fail) {
        errno = EIO;
        return -1;
    }
    return __real_fsync(fd);
}

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

/* A recorder in dir and a 64x48 grey image for its frames. */
static mr_recorder *open_recorder(const char *dir, const mr_recorder_params *rp, mr_image *img) {
    mr_error err = {0};
    mr_recorder *r = mr_recorder_create(dir, rp, &err);
    CHECK_MSG(r != NULL, "recorder in %s: %s", dir, err.msg);
    if (r) mr_image_alloc(img, 64, 48, 1, MR_PIX_U8, NULL);
    return r;
}

static mr_dmat4 pose_of(int i) {
    return mr_m4_look_at_cv(mr_v3(1.0 + 0.1 * i, 1.6, 3.0 - 0.05 * i), mr_v3(0.1 * i, 1.5, 0), mr_v3(0, 1, 0));
}

/* A 64x48 camera and a two-tag map, and recorder params that record them
 * (PNG frames). */
static mr_recorder_params rec_params(mr_camera *cam, mr_marker tags[2], mr_marker_map *map) {
    *cam = (mr_camera){64, 48, 50, 50, 31.5, 23.5, {0.01, 0, 0, 0, 0}};
    tags[0] = (mr_marker){.id = 3, .world_from_tag = mr_m4_translate(0, 1, 0)};
    tags[1] = (mr_marker){.id = 8, .world_from_tag = mr_m4_translate(1, 1, 0)};
    *map = (mr_marker_map){"tag36h11", 0.2, tags, 2};
    mr_recorder_params rp = MR_RECORDER_DEFAULTS;
    rp.camera = cam;
    rp.markers = map;
    rp.source = "test";
    rp.frame_ext = ".png";
    return rp;
}

static void test_round_trip(void) {
    char dir[1100], path[1200];
    tmp_path("rec_rt", dir, sizeof dir);
    mr_camera cam;
    mr_marker tags[2];
    mr_marker_map map;
    mr_recorder_params rp = rec_params(&cam, tags, &map);
    rp.ground_truth = true;
    mr_error err = {0};
    mr_image img;
    mr_recorder *r = open_recorder(dir, &rp, &img);
    if (!r) return;
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

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "wb");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* The replay index: positions in file order, frame numbers with a gap,
 * seeks by frame number and by time at and around every boundary. */
static void test_replay(void) {
    char dir[1100], path[1200];
    tmp_path("rec_replay", dir, sizeof dir);
    mr_camera cam = {64, 48, 50, 50, 31.5, 23.5, {0, 0, 0, 0, 0}};
    mr_recorder_params rp = MR_RECORDER_DEFAULTS;
    rp.camera = &cam;
    rp.frame_ext = ".png";
    mr_error err = {0};
    mr_image img;
    mr_recorder *r = open_recorder(dir, &rp, &img);
    if (!r) return;
    for (int i = 0; i < 4; i++) {
        memset(img.data, 40 * i + 10, 64 * 48);
        mr_frame_record fr = {0};
        fr.t = 0.5 * i;
        fr.pose.valid = i != 1;
        fr.pose.world_from_camera = pose_of(i);
        fr.pose.tags_seen = i + 1;
        fr.pose.rms_px = 0.5 + i;
        fr.has_filtered = i == 2;
        fr.filtered = pose_of(10 + i);
        CHECK(mr_recorder_append(r, &fr, &img, &err));
    }
    mr_recorder_close(&r);
    /* A frame number gap (frames 4-6 lost) at t = 3. */
    snprintf(path, sizeof path, "%s/frames.jsonl", dir);
    append_text(path, "{\"frame\":7,\"t\":3,\"image\":\"frames/000001.png\"}\n");
    mr_replay *rp_ = mr_replay_open(dir, &err);
    CHECK_MSG(rp_ != NULL, "replay of a recording: %s", err.msg);
    if (!rp_) return;
    CHECK_MSG(mr_replay_count(rp_) == 5 && mr_replay_recording(rp_) != NULL, "replay count %lld",
              (long long)mr_replay_count(rp_));
    const mr_replay_frame *f0 = mr_replay_frame_at(rp_, 0), *f1 = mr_replay_frame_at(rp_, 1),
                          *f2 = mr_replay_frame_at(rp_, 2), *f4 = mr_replay_frame_at(rp_, 4);
    CHECK_MSG(f0 && f1 && f2 && f4 && mr_replay_frame_at(rp_, 5) == NULL && mr_replay_frame_at(rp_, -1) == NULL,
              "frame_at range");
    if (f0 && f1 && f2 && f4) {
        mr_dmat4 raw0 = pose_of(0), filt2 = pose_of(12);
        CHECK_MSG(f0->has_pose && same_m4(&f0->pose, &raw0) && f0->tags_seen == 1 && f0->rms_px == 0.5,
                  "replay frame 0: the raw pose (nothing filtered recorded)");
        CHECK_MSG(f2->has_pose && same_m4(&f2->pose, &filt2) && f2->t == 1.0, "replay frame 2: the filtered pose wins");
        CHECK_MSG(!f1->has_pose && f1->rms_px == -1, "replay frame 1: no pose, rms unknown");
        CHECK_MSG(f4->index == 7 && f4->t == 3.0 && !f4->has_pose, "replay position 4 is frame 7 at 3 s");
    }
    /* By frame number: the first position at or after it. */
    static const int64_t by_frame[][2] = {{-5, 0}, {0, 0}, {1, 1}, {3, 3}, {4, 4}, {6, 4}, {7, 4}, {100, 4}};
    for (size_t k = 0; k < sizeof by_frame / sizeof by_frame[0]; k++)
        CHECK_MSG(mr_replay_seek_frame(rp_, by_frame[k][0]) == by_frame[k][1], "seek to frame %lld gave %lld, want %lld",
                  (long long)by_frame[k][0], (long long)mr_replay_seek_frame(rp_, by_frame[k][0]),
                  (long long)by_frame[k][1]);
    /* By time: the frame showing then (last with t <= time). */
    static const double by_time[][2] = {{-1, 0}, {0, 0}, {0.49, 0}, {0.5, 1}, {0.51, 1}, {1.5, 3},
                                        {2.99, 3}, {3.0, 4}, {1e9, 4}};
    for (size_t k = 0; k < sizeof by_time / sizeof by_time[0]; k++)
        CHECK_MSG(mr_replay_seek_time(rp_, by_time[k][0]) == (int64_t)by_time[k][1], "seek to %g s gave %lld, want %g",
                  by_time[k][0], (long long)mr_replay_seek_time(rp_, by_time[k][0]), by_time[k][1]);
    /* Random access to the images, backwards too. */
    for (int i = 3; i >= 0; i--) {
        mr_image back;
        CHECK_MSG(mr_replay_load_image(rp_, i, true, &back, &err), "load %d: %s", i, err.msg);
        CHECK_MSG(back.data && ((unsigned char *)back.data)[100] == 40 * i + 10, "replay image %d is another frame", i);
        mr_image_free(&back);
    }
    mr_image back;
    CHECK(!mr_replay_load_image(rp_, 5, true, &back, &err));
    mr_replay_close(&rp_);
    CHECK(rp_ == NULL);
    mr_replay_close(NULL);

    /* A plain folder of frames, with a frames.jsonl in the recording format. */
    tmp_path("plain/frames", dir, sizeof dir);
    CHECK(mr_mkdirs(dir, &err));
    for (int i = 0; i < 3; i++) {
        memset(img.data, 50 * i + 20, 64 * 48);
        snprintf(path, sizeof path, "%s/%c.png", dir, 'c' - i); /* c, b, a: sorted by name */
        CHECK(mr_image_save_png(path, &img, &err));
    }
    tmp_path("plain", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/frames.jsonl", dir);
    write_text(path, "{\"frame\":1,\"t\":0.7,\"pose\":{\"valid\":true,\"world_from_camera\":"
                     "[1,0,0,1,0,1,0,2,0,0,1,3,0,0,0,1],\"tags_seen\":2,\"rms_px\":0.3}}\nnot json\n");
    rp_ = mr_replay_open(dir, &err);
    CHECK_MSG(rp_ != NULL, "replay of a plain folder: %s", err.msg);
    if (rp_) {
        const mr_replay_frame *a = mr_replay_frame_at(rp_, 0), *b = mr_replay_frame_at(rp_, 1),
                              *c = mr_replay_frame_at(rp_, 2);
        CHECK_MSG(mr_replay_count(rp_) == 3 && mr_replay_recording(rp_) == NULL, "plain folder: 3 frames");
        CHECK_MSG(a && b && c && a->t == 0 && b->t == 0.7 && c->t == 2.0 / 30 && !a->has_pose && b->has_pose &&
                      !c->has_pose && b->pose.m[7] == 2 && b->tags_seen == 2 && b->rms_px == 0.3,
                  "plain folder: frame 1 from frames.jsonl, the others at 30 fps without a pose");
        CHECK(mr_replay_load_image(rp_, 0, true, &back, &err) && ((unsigned char *)back.data)[0] == 120);
        mr_image_free(&back);
        mr_replay_close(&rp_);
    }
    tmp_path("empty", dir, sizeof dir);
    CHECK(mr_mkdirs(dir, &err));
    err.msg[0] = 0;
    CHECK_MSG(mr_replay_open(dir, &err) == NULL && strstr(err.msg, "no frames"), "an empty folder must be refused");
    mr_image_free(&img);
}

/* One mark as the view writes it (lib/view/run.c's finish_mark). */
static cJSON *mark_json(int k, bool hit) {
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "type", "discrepancy");
    cJSON_AddNumberToObject(o, "time_unix", 1.7e9 + k);
    cJSON_AddNumberToObject(o, "frame_index", 10 + k);
    cJSON_AddNumberToObject(o, "timestamp", 0.25 * k);
    cJSON_AddStringToObject(o, "note", k ? "moved" : "missing");
    double px[2] = {12.5 + k, 7.25};
    cJSON_AddItemToObject(o, "pixel", mr_json_from_doubles(px, 2));
    cJSON_AddBoolToObject(o, "hit", hit);
    if (hit) {
        double w[3] = {1.5, 2.5, -3.5 + k};
        cJSON_AddItemToObject(o, "world", mr_json_from_doubles(w, 3));
        cJSON_AddNumberToObject(o, "depth", 4.5);
        cJSON_AddStringToObject(o, "node", "pipe_03");
        cJSON_AddStringToObject(o, "layer", "hidden");
    } else {
        cJSON_AddNullToObject(o, "world");
        cJSON_AddNullToObject(o, "node");
    }
    cJSON *p = cJSON_AddObjectToObject(o, "pose");
    cJSON_AddBoolToObject(p, "valid", true);
    mr_dmat4 m = pose_of(k);
    cJSON_AddItemToObject(p, "world_from_camera", mr_json_from_dmat4(&m));
    cJSON *snap = cJSON_AddObjectToObject(o, "snapshot");
    cJSON_AddStringToObject(snap, "screen", "snapshots/x_screen.png");
    return o;
}

static char *print_line(const cJSON *o) {
    char *s = cJSON_PrintUnformatted(o);
    size_t n = strlen(s);
    char *l = malloc(n + 2);
    memcpy(l, s, n);
    memcpy(l + n, "\n", 2);
    free(s);
    return l;
}

static void test_annotation_append(void) {
    char dir[1100], path[1200];
    tmp_path("session_ann", dir, sizeof dir);
    mr_error err = {0};
    CHECK(mr_mkdirs(dir, &err));
    snprintf(path, sizeof path, "%s/annotations.jsonl", dir);
    cJSON *a = mark_json(0, true), *b = mark_json(1, false);
    char *la = print_line(a), *lb = print_line(b);
    /* A new file: the line, then the file synced and its folder too. */
    g_sync_files = g_sync_dirs = 0;
    CHECK_MSG(mr_annotation_append(path, a, &err), "append: %s", err.msg);
    CHECK_MSG(g_sync_files == 1 && g_sync_dirs == 1, "a new annotations file: %d file and %d folder fsyncs (want 1, 1)",
              g_sync_files, g_sync_dirs);
    size_t size = 0;
    char *text = mr_file_read(path, &size, 0, &err);
    CHECK_MSG(text && strcmp(text, la) == 0, "the file holds other than the one line: %.100s", text ? text : "");
    free(text);
    /* An existing file: appended after what is there, only the file synced. */
    g_sync_files = g_sync_dirs = 0;
    CHECK(mr_annotation_append(path, b, &err));
    CHECK_MSG(g_sync_files == 1 && g_sync_dirs == 0, "appending: %d file and %d folder fsyncs (want 1, 0)", g_sync_files,
              g_sync_dirs);
    text = mr_file_read(path, &size, 0, &err);
    size_t na = strlen(la);
    CHECK_MSG(text && size == na + strlen(lb) && memcmp(text, la, na) == 0 && strcmp(text + na, lb) == 0,
              "the second line must follow the first whole (O_APPEND)");
    free(text);
    /* A failing sync is an error, with the file named. */
    g_sync_fail = true;
    err.msg[0] = 0;
    CHECK_MSG(!mr_annotation_append(path, a, &err) && strstr(err.msg, "annotations.jsonl"),
              "a failed fsync must fail the append: %s", err.msg);
    g_sync_fail = false;
    /* A folder that does not exist: an error, not a crash. */
    snprintf(path, sizeof path, "%s/missing/annotations.jsonl", dir);
    CHECK(!mr_annotation_append(path, a, &err) && err.msg[0]);

    /* Read back: two marks, then the third (its sync failed, but the line
     * was written). */
    snprintf(path, sizeof path, "%s/annotations.jsonl", dir);
    mr_annotations an;
    CHECK(mr_annotations_load(path, &an, &err));
    CHECK_MSG(an.count == 3 && an.bad_lines == 0 && !an.torn_tail, "read %d marks, %d bad", an.count, an.bad_lines);
    if (an.count >= 2) {
        const mr_annotation *x = &an.items[0], *y = &an.items[1];
        mr_dmat4 p0 = pose_of(0);
        CHECK_MSG(strcmp(x->type, "discrepancy") == 0 && x->time_unix == 1.7e9 && x->frame_index == 10 &&
                      x->timestamp == 0 && strcmp(x->category, "missing") == 0 && !x->note[0] && x->has_pixel && x->pixel[0] == 12.5 &&
                      x->pixel[1] == 7.25 && x->hit && x->world[2] == -3.5 && x->depth == 4.5 &&
                      strcmp(x->node, "pipe_03") == 0 && strcmp(x->layer, "hidden") == 0 && x->has_pose &&
                      x->pose_valid && same_m4(&x->world_from_camera, &p0),
                  "mark 1 read back with other fields");
        CHECK_MSG(!y->hit && y->node[0] == 0 && y->frame_index == 11 && strcmp(y->category, "moved") == 0 &&
                      cJSON_IsString(cJSON_GetObjectItem(cJSON_GetObjectItem(y->json, "snapshot"), "screen")),
                  "mark 2 read back with other fields");
    }
    mr_annotations_free(&an);
    CHECK(an.count == 0 && an.items == NULL);
    /* A missing file is no marks. */
    snprintf(path, sizeof path, "%s/none.jsonl", dir);
    CHECK(mr_annotations_load(path, &an, &err) && an.count == 0);
    cJSON_Delete(a);
    cJSON_Delete(b);
    free(la);
    free(lb);
}

/* Issue 15: a mark carries the registration's 1-sigma at its point as
 * "uncertainty_m"; absent when unknown (older lines read as unknown). */
static void test_annotation_uncertainty(void) {
    mr_annotation m;
    memset(&m, 0, sizeof m);
    snprintf(m.type, sizeof m.type, "discrepancy");
    m.frame_index = 3;
    m.node_index = -1;
    m.hit = true;
    m.world[0] = 1, m.world[1] = 2, m.world[2] = 3;
    m.has_pose = m.pose_valid = true;
    m.world_from_camera = mr_m4_identity();
    for (int k = 0; k < 2; k++) {
        m.has_uncertainty = k == 1;
        m.uncertainty_m = k == 1 ? 0.0123 : 0.5;
        cJSON *o = mr_annotation_to_json(&m);
        const cJSON *u = cJSON_GetObjectItemCaseSensitive(o, "uncertainty_m");
        CHECK_MSG(k == 1 ? cJSON_IsNumber(u) && u->valuedouble == 0.0123 : u == NULL,
                  "case %d: uncertainty_m %s in the line", k, u ? "present" : "missing");
        char *line = print_line(o);
        cJSON_Delete(o);
        mr_annotations an;
        mr_error err = {0};
        CHECK(mr_annotations_parse(line, strlen(line), &an, &err) && an.count == 1);
        if (an.count == 1)
            CHECK_MSG(an.items[0].has_uncertainty == (k == 1) && (k == 0 || an.items[0].uncertainty_m == 0.0123),
                      "case %d: read back has %d, %g", k, an.items[0].has_uncertainty, an.items[0].uncertainty_m);
        mr_annotations_free(&an);
        free(line);
    }
    /* A recording's pose covariance reaches the replay frames (the view's
     * capture shows it); a line without one (an older recording) has none. */
    const char *text =
        "{\"frame\":0,\"t\":0,\"image\":\"frames/000000.png\",\"pose\":{\"valid\":true,\"world_from_camera\":"
        "[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],\"tags_seen\":1,\"rms_px\":0.2,\"corner_sigma_px\":0.3,\"covariance\":"
        "[1e-6,0,0,0,0,0, 0,1e-6,0,0,0,0, 0,0,1e-6,0,0,0, 0,0,0,4e-6,0,0, 0,0,0,0,4e-6,0, 0,0,0,0,0,4e-6]}}\n"
        "{\"frame\":1,\"t\":0.1,\"image\":\"frames/000001.png\",\"pose\":{\"valid\":true,\"world_from_camera\":"
        "[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],\"tags_seen\":1,\"rms_px\":0.2}}\n";
    mr_recording *rec = calloc(1, sizeof *rec);
    mr_error err = {0};
    CHECK(rec && mr_recording_parse_frames(rec, text, strlen(text), &err) && rec->frame_count == 2);
    mr_replay *rp = rec ? mr_replay_from_recording(rec, &err) : NULL;
    CHECK_MSG(rp != NULL, "replay: %s", err.msg);
    if (rp) {
        const mr_replay_frame *f0 = mr_replay_frame_at(rp, 0), *f1 = mr_replay_frame_at(rp, 1);
        CHECK_MSG(f0->corner_sigma_px == 0.3 && f0->cov[21] == 4e-6 && f0->cov[0] == 1e-6,
                  "replay frame 0: corner sigma %g, cov[21] %g", f0->corner_sigma_px, f0->cov[21]);
        CHECK_MSG(f1->corner_sigma_px == 0, "replay frame 1 (no covariance) has corner sigma %g", f1->corner_sigma_px);
    }
    mr_replay_close(&rp);
}

/* The tolerant reader: every kind of bad line counted, a torn tail skipped. */
static void test_annotations_reader(void) {
    cJSON *a = mark_json(2, true);
    char *good = print_line(a);
    cJSON_Delete(a);
    static const char *const bad[] = {
        "garbage {{{\n",
        "[1,2,3]\n",                                                     /* not an object */
        "{\"note\":\"no type\"}\n",                                      /* no type */
        "{\"type\":5}\n",                                                /* type not a string */
        "{\"type\":\"\"}\n",                                               /* empty type */
        "{\"type\":\"discrepancy\",\"pixel\":[1]}\n",                    /* pixel not [x,y] */
        "{\"type\":\"discrepancy\",\"world\":[1,2]}\n",                  /* world not [x,y,z] */
        "{\"type\":\"discrepancy\",\"hit\":true,\"world\":null}\n",      /* a hit without a point */
        "{\"type\":\"discrepancy\",\"frame_index\":1.5}\n",              /* not a frame number */
        "{\"type\":\"discrepancy\",\"pose\":{\"world_from_camera\":[2,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}}\n",
        "{\"type\":\"discrepancy\",\"timestamp\":\"soon\"}\n",           /* not a number */
        "{\"type\":\"discrepancy\",\"uncertainty_m\":\"small\"}\n",       /* issue 15: not a number */
        "{\"type\":\"discrepancy\",\"uncertainty_m\":-0.01}\n",          /* a negative sigma */
    };
    int nbad = (int)(sizeof bad / sizeof bad[0]);
    char text[8192] = "";
    strcat(text, good);
    for (int i = 0; i < nbad; i++) strcat(text, bad[i]);
    strcat(text, "\n  \n");
    strcat(text, good);
    strcat(text, "{\"type\":\"discrepancy\",\"note\":\"torn");
    mr_annotations an;
    mr_error err = {0};
    CHECK(mr_annotations_parse(text, strlen(text), &an, &err));
    CHECK_MSG(an.count == 2 && an.bad_lines == nbad && an.torn_tail,
              "annotations: %d read (want 2), %d bad (want %d), torn %d (want 1)", an.count, an.bad_lines, nbad,
              an.torn_tail);
    for (int i = 0; i < an.count; i++) CHECK(an.items[i].frame_index == 12 && an.items[i].world[2] == -1.5);
    mr_annotations_free(&an);
    /* Each bad line alone is refused (and the good one alone read). */
    for (int i = 0; i < nbad; i++) {
        CHECK(mr_annotations_parse(bad[i], strlen(bad[i]), &an, &err));
        CHECK_MSG(an.count == 0 && an.bad_lines == 1, "bad annotation line %d was accepted: %s", i, bad[i]);
        mr_annotations_free(&an);
    }
    CHECK(mr_annotations_parse(good, strlen(good), &an, &err) && an.count == 1 && an.bad_lines == 0);
    mr_annotations_free(&an);
    /* A whole object without its newline is still a torn write (the crash
     * came before the '\n'): skipped, not read. */
    CHECK(mr_annotations_parse(good, strlen(good) - 1, &an, &err));
    CHECK_MSG(an.count == 0 && an.bad_lines == 0 && an.torn_tail,
              "a last line without newline was read (%d marks) or not reported torn", an.count);
    mr_annotations_free(&an);
    free(good);
}

/* The camera and marker map of a replay folder: inline in meta.json, named
 * by it (relative paths), or camera.json / markers.json beside the frames;
 * what the caller already has is kept; no map is fine, a broken file is not. */
static void test_replay_meta(void) {
    char dir[1100], path[1200];
    mr_error err = {0};
    mr_camera given = {32, 24, 20, 20, 15.5, 11.5, {0, 0, 0, 0, 0}};
    mr_camera cam = {64, 48, 50, 51, 31.5, 23.5, {0.1, 0, 0, 0, 0}};
    cJSON *cj = mr_camera_to_json(&cam);
    char *ctext = cJSON_PrintUnformatted(cj);
    const char *map_text = "{\"family\": \"tag36h11\", \"tag_size\": 0.2, \"tags\": [{\"id\": 3, "
                           "\"world_from_tag\": [1,0,0,0, 0,1,0,0, 0,0,1,2, 0,0,0,1]}]}";
    /* 1. inline camera, the map named by a relative path */
    tmp_path("meta_inline", dir, sizeof dir);
    CHECK(mr_mkdirs(dir, &err));
    char meta[4096];
    snprintf(meta, sizeof meta, "{\"camera\": %s, \"markers\": \"map.json\"}", ctext);
    snprintf(path, sizeof path, "%s/meta.json", dir);
    write_text(path, meta);
    snprintf(path, sizeof path, "%s/map.json", dir);
    write_text(path, map_text);
    mr_camera got = given;
    mr_marker_map map = {0};
    bool have_map = false;
    CHECK_MSG(mr_replay_meta_load(dir, &got, false, &map, &have_map, &err), "inline meta: %s", err.msg);
    CHECK_MSG(got.fx == 50 && got.fy == 51 && got.width == 64 && got.dist[0] == 0.1, "inline camera not read (fx %g)", got.fx);
    CHECK_MSG(have_map && map.count == 1 && map.tags[0].id == 3 && map.tags[0].world_from_tag.m[11] == 2,
              "map named by meta.json not read (have %d, count %d)", have_map, map.count);
    mr_marker_map_free(&map);
    /* the caller's camera and map win */
    got = given;
    have_map = true;
    CHECK(mr_replay_meta_load(dir, &got, true, &map, &have_map, &err) && got.fx == 20 && map.count == 0);
    /* 2. no meta.json: camera.json beside the frames, no map (not an error) */
    tmp_path("meta_beside", dir, sizeof dir);
    CHECK(mr_mkdirs(dir, &err));
    snprintf(path, sizeof path, "%s/camera.json", dir);
    write_text(path, ctext);
    got = given;
    have_map = false;
    CHECK_MSG(mr_replay_meta_load(dir, &got, false, &map, &have_map, &err) && got.fx == 50 && !have_map,
              "camera.json beside the frames: %s (fx %g, map %d)", err.msg, got.fx, have_map);
    /* 3. a damaged meta.json fails with a message */
    snprintf(path, sizeof path, "%s/meta.json", dir);
    write_text(path, "{\"camera\": ");
    err.msg[0] = 0;
    CHECK_MSG(!mr_replay_meta_load(dir, &got, false, &map, &have_map, &err) && err.msg[0], "a damaged meta.json was accepted");
    free(ctext);
    cJSON_Delete(cj);
}

/* The writer and the reader of annotation lines agree: every field comes
 * back, a mark without a hit or a node writes nulls, and the line the
 * writer makes is what the view has always written (key order). */
static void test_annotation_round_trip(void) {
    mr_annotation m;
    memset(&m, 0, sizeof m);
    snprintf(m.type, sizeof m.type, "discrepancy");
    m.time_unix = 1764600000;
    m.frame_index = 42;
    m.timestamp = 1.4;
    snprintf(m.note, sizeof m.note, "pipe moved");
    m.pixel[0] = 120.5;
    m.pixel[1] = 80.25;
    m.hit = true;
    m.world[0] = 1e7 + 0.125;
    m.world[1] = -2;
    m.world[2] = 3.5;
    m.depth = 4.75;
    m.node_index = 7;
    snprintf(m.node, sizeof m.node, "Pipe_3");
    snprintf(m.layer, sizeof m.layer, "hidden");
    m.pose_valid = true;
    m.world_from_camera = mr_m4_translate(1, 2, 3);
    m.pose_tags_seen = 2;
    m.pose_rms_px = 0.5;
    for (int variant = 0; variant < 2; variant++) {
        if (variant == 1) {
            m.hit = false;
            m.node_index = -1;
        }
        cJSON *o = mr_annotation_to_json(&m);
        char *text = cJSON_PrintUnformatted(o);
        size_t n = strlen(text);
        char *line = malloc(n + 2);
        memcpy(line, text, n);
        line[n] = '\n';
        line[n + 1] = 0;
        if (variant == 0)
            CHECK_MSG(strncmp(text, "{\"type\":\"discrepancy\",\"time_unix\":1764600000,\"frame_index\":42,\"timestamp\":1.4,"
                                  "\"note\":\"pipe moved\",\"pixel\":[120.5,80.25],\"hit\":true,\"world\":[",
                              110) == 0,
                      "annotation line starts differently: %.200s", text);
        mr_annotations got = {0};
        mr_error err = {0};
        CHECK(mr_annotations_parse(line, n + 1, &got, &err) && got.count == 1 && got.bad_lines == 0);
        if (got.count == 1) {
            const mr_annotation *g = &got.items[0];
            CHECK_MSG(strcmp(g->type, m.type) == 0 && g->time_unix == m.time_unix && g->frame_index == 42 &&
                          g->timestamp == m.timestamp && strcmp(g->note, m.note) == 0 && g->has_pixel &&
                          g->pixel[0] == m.pixel[0] && g->pixel[1] == m.pixel[1] && g->hit == m.hit,
                      "variant %d: the mark's header fields do not come back: %s", variant, text);
            if (m.hit)
                CHECK_MSG(g->world[0] == m.world[0] && g->world[1] == -2 && g->world[2] == 3.5 && g->depth == 4.75,
                          "the picked point does not come back: %s", text);
            CHECK_MSG(g->node_index == m.node_index && strcmp(g->node, variant ? "" : "Pipe_3") == 0 &&
                          strcmp(g->layer, variant ? "" : "hidden") == 0,
                      "variant %d: node %d '%s' layer '%s' back, want %d", variant, g->node_index, g->node, g->layer,
                      m.node_index);
            CHECK_MSG(g->has_pose && g->pose_valid && same_m4(&g->world_from_camera, &m.world_from_camera) &&
                          g->pose_tags_seen == 2 && g->pose_rms_px == 0.5,
                      "the pose does not come back: %s", text);
        }
        mr_annotations_free(&got);
        free(line);
        cJSON_free(text);
        cJSON_Delete(o);
    }
}

/* The view's marks as session data (mark.c): a frame copy owns its own
 * image; the annotation takes the frame's index, time and pose; a mark's
 * line is written even when its snapshot cannot be, and reads back. */
static void test_mark_files(void) {
    mr_capture_frame src = {0}, dst = {0};
    mr_error err = {0};
    CHECK(mr_image_alloc(&src.image, 4, 2, 3, MR_PIX_U8, &err));
    memset(src.image.data, 7, mr_image_bytes(&src.image));
    src.index = 42;
    src.timestamp = 4.2;
    src.pose_valid = src.have_pose = true;
    src.pose = mr_m4_translate(1, 2, 3);
    src.tags_seen = 3;
    src.rms_px = 0.5;
    CHECK(mr_capture_frame_copy(&dst, &src, &err));
    CHECK(dst.image.data && dst.image.data != src.image.data && dst.index == 42);
    ((unsigned char *)src.image.data)[0] = 9;
    CHECK(dst.image.data && ((unsigned char *)dst.image.data)[0] == 7);
    mr_annotation m;
    mr_annotation_from_frame(&m, &src, "extra", 1000);
    CHECK(!strcmp(m.type, "discrepancy") && !strcmp(m.category, "extra") && m.frame_index == 42 && m.timestamp == 4.2);
    CHECK(m.has_pose && m.pose_valid && m.world_from_camera.m[3] == 1 && m.pose_tags_seen == 3 && m.node_index == -1);
    char dir[1200];
    tmp_path("marks", dir, sizeof dir);
    mr_camera cam = {4, 2, 4, 4, 1.5, 0.5, {0}};
    mr_image none = {0};
    mr_snapshot sn = {&none, &dst, &cam, 0.5, "gbuffer"};
    cJSON *line = mr_annotation_to_json(&m);
    bool snap_ok = true;
    mr_error serr = {0};
    CHECK_MSG(mr_mark_save(dir, "mark_1", line, &sn, &snap_ok, &serr, &err), "%s", err.msg);
    CHECK_MSG(!snap_ok && serr.msg[0], "a snapshot without a screen was written");
    cJSON_Delete(line);
    char path[1300];
    snprintf(path, sizeof path, "%s/annotations.jsonl", dir);
    mr_annotations a = {0};
    CHECK(mr_annotations_load(path, &a, &err));
    CHECK_MSG(a.count == 1 && a.items[0].frame_index == 42 && !strcmp(a.items[0].category, "extra"),
              "mark line: %d read back", a.count);
    mr_annotations_free(&a);
    mr_capture_frame_free(&src);
    mr_capture_frame_free(&dst);
}

/* The tracking commands' input and tracker (mr_input_open,
 * mr_input_tracker_create): a recording supplies the camera and marker
 * map, a file given wins over it, a bad file is an error. */
static void test_input(void) {
    char dir[1100], cam_path[1200], bad_path[1200];
    tmp_path("rec_input", dir, sizeof dir);
    mr_camera cam;
    mr_marker tags[2];
    mr_marker_map map;
    mr_recorder_params rp = rec_params(&cam, tags, &map);
    mr_error err = {0};
    mr_image img;
    mr_recorder *r = open_recorder(dir, &rp, &img);
    if (!r) return;
    for (int i = 0; i < 3; i++) {
        mr_frame_record fr = {0};
        fr.t = 0.1 * i;
        CHECK(mr_recorder_append(r, &fr, &img, &err));
    }
    mr_recorder_close(&r);
    mr_image_free(&img);

    mr_recording *rec = NULL;
    mr_source *src = mr_input_open(dir, NULL, &rec, &err);
    CHECK_MSG(src != NULL && rec != NULL, "input %s: %s", dir, err.msg);
    if (!src || !rec) {
        mr_source_close(&src);
        mr_recording_close(&rec);
        return;
    }
    CHECK(rec->frame_count == 3 && rec->camera.fx == 50 && rec->has_markers);
    mr_frame fr;
    memset(&fr, 0, sizeof fr);
    CHECK(mr_source_read(src, &fr, &err) == MR_READ_FRAME && fr.image.width == 64); /* (the image is the source's) */
    mr_source_close(&src);

    /* The recording's camera and markers by default. */
    mr_tracker *t = mr_input_tracker_create(NULL, NULL, rec, NULL, &err);
    CHECK_MSG(t != NULL, "%s", err.msg);
    CHECK(t && mr_tracker_camera(t) && mr_tracker_camera(t)->fx == 50);
    CHECK(t && mr_tracker_markers(t) && mr_tracker_markers(t)->count == 2);
    mr_tracker_destroy(&t);
    /* A camera file wins over the recording's; the markers still come from it. */
    tmp_path("input_cam.json", cam_path, sizeof cam_path);
    mr_camera other = cam;
    other.fx = other.fy = 77;
    cJSON *j = mr_camera_to_json(&other);
    CHECK(j && mr_json_save(cam_path, j, &err));
    cJSON_Delete(j);
    t = mr_input_tracker_create(cam_path, NULL, rec, NULL, &err);
    CHECK(t && mr_tracker_camera(t) && mr_tracker_camera(t)->fx == 77);
    CHECK(t && mr_tracker_markers(t) && mr_tracker_markers(t)->count == 2);
    mr_tracker_destroy(&t);
    /* Neither: detection only. */
    t = mr_input_tracker_create(NULL, NULL, NULL, NULL, &err);
    CHECK(t && !mr_tracker_camera(t) && !mr_tracker_markers(t));
    mr_tracker_destroy(&t);
    /* A bad file is an error, not a silent fallback to the recording's. */
    tmp_path("input_missing.json", bad_path, sizeof bad_path);
    err.msg[0] = 0;
    CHECK(mr_input_tracker_create(bad_path, NULL, rec, NULL, &err) == NULL && err.msg[0]);
    err.msg[0] = 0;
    CHECK(mr_input_tracker_create(NULL, bad_path, rec, NULL, &err) == NULL && err.msg[0]);
    mr_recording_close(&rec);
    /* Not a recording: mr_source_open's error. */
    err.msg[0] = 0;
    CHECK(mr_input_open(bad_path, NULL, &rec, &err) == NULL && rec == NULL && err.msg[0]);
}

/* What the planner says about a mark: the note with its inline fields,
 * the title in words, and edits as new lines that supersede the old one
 * (readers take the newest; the log only grows). */
static void test_mark_words_and_edits(void) {
    mr_annotation a;
    memset(&a, 0, sizeof a);
    a.node_index = -1;
    snprintf(a.type, sizeof a.type, "discrepancy");
    mr_mark_set_note(&a, "  duct   clashes @ann #hvac #level2 !high with tray ");
    CHECK_MSG(!strcmp(a.note, "duct clashes with tray") && !strcmp(a.assignee, "ann") && !strcmp(a.priority, "high") &&
                  a.label_count == 2 && !strcmp(a.labels[0], "hvac") && !strcmp(a.labels[1], "level2"),
              "note '%s' assignee '%s' priority '%s' labels %d", a.note, a.assignee, a.priority, a.label_count);
    /* Titles: the category and part; the measured offset's size and axis. */
    char t[200];
    snprintf(a.category, sizeof a.category, "moved");
    snprintf(a.node, sizeof a.node, "Machine_2");
    mr_mark_title(&a, t, sizeof t);
    CHECK_MSG(!strcmp(t, "Moved: Machine_2"), "title '%s'", t);
    a.has_measurement = true;
    a.measurement.has_distance = true;
    a.measurement.distance_m = 0.3;
    a.measurement.tri.point = mr_v3(4.3, 1.5, -2.0);
    a.measurement.planned = mr_v3(4.0, 1.49, -2.02);
    mr_mark_title(&a, t, sizeof t);
    CHECK_MSG(!strcmp(t, "Moved: Machine_2, 0.30 m along +x"), "title '%s'", t);
    a.measurement.tri.point = mr_v3(4.0, 1.5, -2.5);
    a.measurement.distance_m = 0.048;
    mr_mark_title(&a, t, sizeof t);
    CHECK_MSG(!strcmp(t, "Moved: Machine_2, 48 mm along -z"), "title '%s'", t);
    a.has_measurement = false;
    a.node[0] = 0;
    a.category[0] = 0;
    mr_mark_title(&a, t, sizeof t);
    CHECK_MSG(!strcmp(t, "duct clashes with tray"), "a mark without a category is titled by its note: '%s'", t);
    /* Edits: mark 1 (with an id) edited twice and closed, mark 2 (an
     * older line without an id) edited once; mark 3 untouched. */
    const char *text =
        "{\"type\":\"discrepancy\",\"id\":\"m1\",\"revision\":1,\"category\":\"moved\",\"note\":\"first\","
        "\"snapshot\":{\"frame\":\"s/a.png\"}}\n"
        "{\"type\":\"discrepancy\",\"time_unix\":5,\"frame_index\":3,\"note\":\"extra\",\"pixel\":[1,2]}\n"
        "{\"type\":\"discrepancy\",\"id\":\"m3\",\"category\":\"clash\"}\n";
    mr_annotations an;
    mr_error err = {0};
    CHECK(mr_annotations_parse(text, strlen(text), &an, &err) && an.count == 3);
    CHECK_MSG(an.count == 3 && !strcmp(an.items[1].category, "extra") && !an.items[1].note[0],
              "an older line's note did not become its category");
    char log[8192];
    snprintf(log, sizeof log, "%s", text);
    for (int round = 0; an.count == 3 && round < 3; round++) {
        mr_annotation e;
        memset(&e, 0, sizeof e);
        int which = round == 1 ? 1 : 0;
        snprintf(e.category, sizeof e.category, "%s", round == 0 ? "wrong size" : an.items[which].category);
        mr_mark_set_note(&e, round == 2 ? "done @bob" : "edited");
        snprintf(e.status, sizeof e.status, "%s", round == 2 ? "closed" : "");
        cJSON *line = mr_annotation_edit_line(&an.items[which], &e, 100 + round);
        char *l = line ? cJSON_PrintUnformatted(line) : NULL;
        CHECK(l != NULL);
        if (l) snprintf(log + strlen(log), sizeof log - strlen(log), "%s\n", l);
        free(l);
        cJSON_Delete(line);
        mr_annotations_free(&an);
        CHECK(mr_annotations_parse(log, strlen(log), &an, &err));
        int dropped = mr_annotations_current(&an);
        CHECK_MSG(an.count == 3 && dropped == round + 1, "round %d: %d marks, %d lines superseded", round, an.count, dropped);
    }
    if (an.count == 3) {
        const mr_annotation *m1 = &an.items[0], *m2 = &an.items[1], *m3 = &an.items[2];
        CHECK_MSG(!strcmp(m1->id, "m1") && m1->revision == 3 && !strcmp(m1->status, "closed") &&
                      !strcmp(m1->category, "wrong size") && !strcmp(m1->note, "done") && !strcmp(m1->assignee, "bob"),
                  "mark 1 after two edits: rev %d status '%s' category '%s' note '%s'", m1->revision, m1->status,
                  m1->category, m1->note);
        /* The edit keeps what it did not change (the snapshot). */
        CHECK(cJSON_GetObjectItem(cJSON_GetObjectItem(m1->json, "snapshot"), "frame") != NULL);
        CHECK(!strcmp(m1->title, "Wrong size") && cJSON_IsNumber(cJSON_GetObjectItem(m1->json, "edited_unix")));
        CHECK_MSG(m2->revision == 2 && !strcmp(m2->note, "edited") && m2->frame_index == 3 && m2->id[0],
                  "the older mark's edit did not supersede it (rev %d, note '%s')", m2->revision, m2->note);
        CHECK(!strcmp(m3->id, "m3") && m3->revision == 0);
    }
    mr_annotations_free(&an);
}

int main(void) {
    if (!mr_test_fresh_dir("test_session", g_tmp, sizeof g_tmp)) return 1;
    test_mark_words_and_edits();
    test_round_trip();
    test_mutations();
    test_replay();
    test_replay_meta();
    test_annotation_append();
    test_annotations_reader();
    test_annotation_uncertainty();
    test_annotation_round_trip();
    test_mark_files();
    test_input();
    return mr_test_finish("test_session");
}
