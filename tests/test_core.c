/* Unit tests for lib/core: double math and poses, the camera model, the
 * camera/view JSON formats, atomic files (under real and injected
 * failures), image files, the RNG. */
#include "mr_core.h"
#include "mr_test.h"

#include <dirent.h>
#include <pthread.h>
#include <errno.h>
#include <signal.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

static char g_tmp[1024];

static double max_abs_diff(const mr_dmat4 *a, const mr_dmat4 *b) {
    double m = 0;
    for (int i = 0; i < 16; i++) {
        double d = fabs(a->m[i] - b->m[i]);
        if (d > m) m = d;
    }
    return m;
}

static void test_math(void) {
    mr_dmat4 I = mr_m4_identity();
    double t[3] = {1e7, -2.5, 3e6}, q[4] = {0.1, -0.3, 0.2, 0.9}, s[3] = {2, 3, 0.5};
    mr_dmat4 M = mr_m4_from_trs(t, q, s), Mi;
    CHECK(mr_m4_invert(&M, &Mi));
    mr_dmat4 P = mr_m4_mul(&M, &Mi);
    CHECK(max_abs_diff(&P, &I) < 1e-9);
    /* Quaternions are normalised: the rotation part of TRS with unit scale
     * is rigid even for a non-unit quaternion. */
    double one[3] = {1, 1, 1};
    mr_dmat4 R = mr_m4_from_trs(t, q, one);
    CHECK(mr_m4_is_rigid(&R, 1e-12));
    mr_dmat4 Ri = mr_m4_invert_rigid(&R), Rg;
    CHECK(mr_m4_invert(&R, &Rg));
    CHECK(max_abs_diff(&Ri, &Rg) < 1e-8);
    /* A point 1e7 away survives the round trip to the millimetre's millionth. */
    mr_dvec3 p = mr_v3(1e7 + 0.123456, 5, -1e7), pr = mr_m4_point(&Ri, mr_m4_point(&R, p));
    CHECK(mr_v3_len(mr_v3_sub(p, pr)) < 1e-8);
    CHECK(!mr_m4_is_rigid(&M, 1e-6)); /* scaled */
    mr_dmat4 Z;
    memset(&Z, 0, sizeof Z);
    CHECK(!mr_m4_invert(&Z, &Mi));
    mr_dmat4 N = I;
    N.m[5] = NAN;
    CHECK(!mr_m4_is_rigid(&N, 1e-6) && !mr_m4_is_finite(&N));
    mr_dmat4 mirror = mr_m4_scale(-1, 1, 1);
    CHECK(!mr_m4_is_rigid(&mirror, 1e-6)); /* det -1 is not a pose */
    /* Axis-angle matches the quaternion path. */
    mr_dmat4 Ra = mr_m4_rotate_axis(mr_v3(0, 0, 1), 3.14159265358979323846 / 2);
    mr_dvec3 x = mr_m4_dir(&Ra, mr_v3(1, 0, 0));
    CHECK_NEAR(x.x, 0, 1e-12);
    CHECK_NEAR(x.y, 1, 1e-12);
    /* look_at: OpenCV axes (z forward, y down), rigid, eye is the origin. */
    mr_dvec3 eye = mr_v3(3, 1.6, -2), at = mr_v3(-5, 0.5, 7);
    mr_dmat4 L = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
    CHECK(mr_m4_is_rigid(&L, 1e-12));
    mr_dvec3 fwd = mr_m4_dir(&L, mr_v3(0, 0, 1)), down = mr_m4_dir(&L, mr_v3(0, 1, 0));
    mr_dvec3 want = mr_v3_normalize(mr_v3_sub(at, eye));
    CHECK(mr_v3_dot(fwd, want) > 1 - 1e-12);
    CHECK(down.y < 0);
    mr_dvec3 o = mr_m4_point(&L, mr_v3(0, 0, 0));
    CHECK(mr_v3_len(mr_v3_sub(o, eye)) < 1e-12);
    /* Looking straight down the up axis still gives a rigid pose. */
    mr_dmat4 D = mr_m4_look_at_cv(mr_v3(0, 10, 0), mr_v3(0, 0, 0), mr_v3(0, 1, 0));
    CHECK(mr_m4_is_rigid(&D, 1e-12));
    /* GL export is column-major. */
    float gl[16];
    mr_m4_to_gl(&M, gl);
    CHECK(gl[12] == (float)M.m[3] && gl[1] == (float)M.m[4]);
    CHECK(mr_v3_len(mr_v3_normalize(mr_v3(0, 0, 0))) == 0);
}

static void test_camera(void) {
    mr_camera c = {640, 480, 500, 505, 319.5, 239.5, {-0.12, 0.05, 0.001, -0.0007, 0.01}};
    mr_error err = {0};
    CHECK(mr_camera_validate(&c, &err));
    CHECK(mr_camera_has_distortion(&c));
    /* Undistort inverts distort across the image, corners included. */
    double worst = 0;
    for (int v = 0; v <= 480; v += 40)
        for (int u = 0; u <= 640; u += 40) {
            double xd = (u - c.cx) / c.fx, yd = (v - c.cy) / c.fy, x, y, x2, y2;
            CHECK(mr_camera_undistort(&c, xd, yd, &x, &y));
            mr_camera_distort(&c, x, y, &x2, &y2);
            double e = fabs(x2 - xd) + fabs(y2 - yd);
            if (e > worst) worst = e;
        }
    CHECK(worst < 1e-9);
    /* Far outside the field of view the inversion reports failure instead
     * of returning garbage, and never NaN. */
    double x = 0, y = 0;
    bool ok = mr_camera_undistort(&c, 50, 50, &x, &y);
    CHECK(!ok || (isfinite(x) && isfinite(y)));
    mr_camera r = mr_camera_resized(&c, 320, 240);
    CHECK_NEAR(r.fx, 250, 1e-12);
    CHECK_NEAR(r.cx, 159.5, 1e-12); /* pixel centres stay centres */
    mr_camera bad = c;
    bad.fx = 0;
    CHECK(!mr_camera_validate(&bad, &err) && err.code == MR_ERR_INVALID);
    bad = c;
    bad.dist[1] = NAN;
    CHECK(!mr_camera_validate(&bad, &err));
    bad = c;
    bad.width = 0;
    CHECK(!mr_camera_validate(&bad, &err));
}

static bool parse_camera(const char *text, mr_camera *c, mr_error *err) {
    cJSON *j = cJSON_Parse(text);
    bool ok = j && mr_camera_from_json(j, c, err);
    cJSON_Delete(j);
    return ok;
}

static void test_json(void) {
    mr_camera c;
    mr_error err = {0};
    CHECK(parse_camera("{\"width\":64,\"height\":48,\"fx\":50,\"fy\":51,\"cx\":31.5,\"cy\":23.5,\"dist\":[0.1,0,0,0]}", &c, &err));
    CHECK(c.width == 64 && c.fy == 51 && c.dist[0] == 0.1 && c.dist[4] == 0);
    CHECK(parse_camera("{\"width\":64,\"height\":48,\"fx\":50,\"fy\":51,\"cx\":31.5,\"cy\":23.5,\"dist\":[0,0,0,0,0,0,0,0]}", &c, &err));
    CHECK(!parse_camera("{\"width\":64,\"height\":48,\"fx\":50,\"fy\":51,\"cx\":31.5,\"cy\":23.5,\"dist\":[0,0,0,0,0,0.2,0,0]}", &c, &err) &&
          err.code == MR_ERR_UNSUPPORTED);
    CHECK(!parse_camera("{\"width\":64,\"height\":48,\"fx\":-50,\"fy\":51,\"cx\":31.5,\"cy\":23.5}", &c, &err));
    CHECK(!parse_camera("{\"width\":64.5,\"height\":48,\"fx\":50,\"fy\":51,\"cx\":31.5,\"cy\":23.5}", &c, &err));
    CHECK(!parse_camera("{\"width\":64,\"height\":48,\"fx\":50,\"cx\":31.5,\"cy\":23.5}", &c, &err));
    CHECK(strstr(err.msg, "fy") != NULL && strchr(err.msg, '\n') == NULL);
    CHECK(!parse_camera("{\"width\":\"64\",\"height\":48,\"fx\":50,\"fy\":50,\"cx\":31.5,\"cy\":23.5}", &c, &err));

    /* Camera round trip through a file, then a view referring to it. */
    CHECK(parse_camera("{\"width\":64,\"height\":48,\"fx\":50,\"fy\":51,\"cx\":31.5,\"cy\":23.5,\"dist\":[0.1,-0.01,0.001,0.002,0.003]}", &c, &err));
    char path[1200], vpath[1200];
    snprintf(path, sizeof path, "%s/cam.json", g_tmp);
    cJSON *cj = mr_camera_to_json(&c);
    CHECK(mr_json_save(path, cj, &err));
    cJSON_Delete(cj);
    mr_camera c2;
    CHECK(mr_camera_load(path, &c2, &err) && memcmp(&c, &c2, sizeof c) == 0);
    snprintf(vpath, sizeof vpath, "%s/view.json", g_tmp);
    const char *vtext = "{\"camera\":\"cam.json\",\"world_from_camera\":[0,0,1,10000000,  -1,0,0,2,  0,-1,0,3,  0,0,0,1]}";
    CHECK(mr_file_write_atomic(vpath, vtext, strlen(vtext), &err));
    mr_view v;
    CHECK_MSG(mr_view_load(vpath, &v, &err), "%s", err.msg);
    CHECK(v.camera.width == 64 && v.world_from_camera.m[3] == 1e7);
    /* View written and read back is identical. */
    cJSON *vj = mr_view_to_json(&v);
    mr_view v2;
    CHECK(mr_view_from_json(vj, ".", &v2, &err) && memcmp(&v, &v2, sizeof v) == 0);
    cJSON_Delete(vj);
    const char *bad = "{\"camera\":\"cam.json\",\"world_from_camera\":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]}";
    CHECK(mr_file_write_atomic(vpath, bad, strlen(bad), &err));
    CHECK(!mr_view_load(vpath, &v, &err) && err.code == MR_ERR_INVALID);
    const char *garbage = "{\"camera\": ";
    CHECK(mr_file_write_atomic(vpath, garbage, strlen(garbage), &err));
    CHECK(!mr_view_load(vpath, &v, &err) && err.code == MR_ERR_PARSE);
    CHECK(strstr(err.msg, "view.json") != NULL);
}

static void test_files(void) {
    mr_error err = {0};
    char path[1200], dir[1200];
    snprintf(path, sizeof path, "%s/a/b/c", g_tmp);
    CHECK(mr_mkdirs(path, &err) && mr_mkdirs(path, &err));
    snprintf(path, sizeof path, "%s/a/file.txt", g_tmp);
    CHECK(mr_file_write_atomic(path, "hello", 5, &err));
    CHECK(mr_file_write_atomic(path, "bye", 3, &err)); /* replaces */
    size_t n = 0;
    char *s = mr_file_read(path, &n, 0, &err);
    CHECK(s && n == 3 && strcmp(s, "bye") == 0);
    free(s);
    CHECK(mr_file_read(path, &n, 2, &err) == NULL && err.code == MR_ERR_NOMEM); /* over the limit */
    snprintf(dir, sizeof dir, "%s/a", g_tmp);
    CHECK(mr_file_read(dir, &n, 0, &err) == NULL && err.code == MR_ERR_IO);     /* a folder */
    snprintf(path, sizeof path, "%s/missing/x.txt", g_tmp);
    CHECK(!mr_file_write_atomic(path, "x", 1, &err) && err.code == MR_ERR_IO);
    CHECK(!mr_file_exists(path));
    char out[64];
    mr_path_dir("a/b/c.json", out, sizeof out);
    CHECK(strcmp(out, "a/b") == 0);
    mr_path_dir("c.json", out, sizeof out);
    CHECK(strcmp(out, ".") == 0);
    mr_path_join("a/b", "/abs", out, sizeof out);
    CHECK(strcmp(out, "/abs") == 0);
    mr_path_join("a/b", "rel.glb", out, sizeof out);
    CHECK(strcmp(out, "a/b/rel.glb") == 0);
}

/* ------------------------------------------------- atomic writes */

/* test_core links with -Wl,--wrap=fsync,--wrap=rename (tests/CMakeLists.txt):
 * the calls file.c makes go through these, so the test sees that the temp
 * file is fsynced before it is renamed over the target, and can make either
 * call fail, with nothing in lib/core that exists only for tests. */
int __real_fsync(int fd);
int __real_rename(const char *from, const char *to);
int __wrap_fsync(int fd);
int __wrap_rename(const char *from, const char *to);

static struct {
    int fail_fsync, fail_rename;  /* errno to fail with, 0: pass through */
    int fsyncs, renames;          /* calls seen */
    char synced[1200];            /* file last fsynced (from /proc/self/fd) */
    char renamed_from[1200];
    bool synced_before_rename;    /* the renamed file was fsynced first */
} g_io;

int __wrap_fsync(int fd) {
    char link[64];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    ssize_t n = readlink(link, g_io.synced, sizeof g_io.synced - 1);
    g_io.synced[n > 0 ? n : 0] = 0;
    g_io.fsyncs++;
    if (g_io.fail_fsync) {
        errno = g_io.fail_fsync;
        return -1;
    }
    return __real_fsync(fd);
}

int __wrap_rename(const char *from, const char *to) {
    g_io.renames++;
    snprintf(g_io.renamed_from, sizeof g_io.renamed_from, "%s", from);
    char abs_from[1200];
    g_io.synced_before_rename = realpath(from, abs_from) && strcmp(abs_from, g_io.synced) == 0;
    if (g_io.fail_rename) {
        errno = g_io.fail_rename;
        return -1;
    }
    return __real_rename(from, to);
}

/* Names in `dir` other than `keep` (a leftover temp file, say); 0 if none. */
static int stray_files(const char *dir, const char *keep, char *first, size_t n) {
    DIR *d = opendir(dir);
    int count = 0;
    first[0] = 0;
    if (!d) return -1;
    for (struct dirent *e; (e = readdir(d));) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0 || strcmp(e->d_name, keep) == 0) continue;
        if (!count++) snprintf(first, n, "%s", e->d_name);
    }
    closedir(d);
    return count;
}

/* A failed write keeps the previous file byte for byte and leaves nothing
 * else in its folder. */
static void check_kept(const char *dir, const char *name, const char *old, const char *what) {
    char path[1200], stray[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    mr_error e2 = {0};
    size_t n = 0;
    char *s = mr_file_read(path, &n, 0, &e2);
    CHECK_MSG(s && n == strlen(old) && memcmp(s, old, n) == 0,
              "%s: the previous file must keep its exact content after a failed write (%s, %zu bytes)", what,
              s ? "changed" : "gone", s ? n : 0);
    free(s);
    int k = stray_files(dir, name, stray, sizeof stray);
    CHECK_MSG(k == 0, "%s: a failed write left %d file(s) in the folder, e.g. %s (a temp file not removed)", what, k, stray);
}

static void test_atomic_writes(void) {
    char dir[1200], path[1600], stray[256];
    snprintf(dir, sizeof dir, "%s/atomic", g_tmp);
    mr_error err = {0};
    CHECK(mr_mkdirs(dir, &err));
    /* Start from an empty folder: what an earlier run left is not ours. */
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));) {
        if (e->d_name[0] == '.') continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        remove(path);
    }
    if (d) closedir(d);
    snprintf(path, sizeof path, "%s/settings.json", dir);
    const char *old = "{\"previous\": \"content, kept on failure\"}\n";
    size_t big_n = 256 * 1024;
    char *big = malloc(big_n);
    for (size_t i = 0; i < big_n; i++) big[i] = (char)('a' + i % 26);

    /* Success: complete content, a regular file with the usual mode, the
     * temp file fsynced before it was renamed onto the target, no leftover. */
    CHECK(mr_file_write_atomic(path, old, strlen(old), &err));
    mr_error e2 = {0};
    size_t n = 0;
    char *s = mr_file_read(path, &n, 0, &e2);
    CHECK_MSG(s && n == strlen(old) && memcmp(s, old, n) == 0, "atomic write: content read back differs");
    free(s);
    memset(&g_io, 0, sizeof g_io);
    CHECK_MSG(mr_file_write_atomic(path, big, big_n, &err), "%s", err.msg);
    s = mr_file_read(path, &n, 0, &e2);
    CHECK_MSG(s && n == big_n && memcmp(s, big, n) == 0, "atomic write of %zu bytes: read back %zu bytes, or other bytes",
              big_n, s ? n : 0);
    free(s);
    CHECK_MSG(g_io.renames == 1 && strcmp(g_io.renamed_from, path) != 0,
              "atomic write: the data must go to a temp file renamed onto the target (renames %d, from %s)",
              g_io.renames, g_io.renamed_from);
    CHECK_MSG(g_io.fsyncs >= 1 && g_io.synced_before_rename,
              "atomic write: the temp file must be fsynced before the rename (fsyncs %d, last fsynced %s, renamed %s)",
              g_io.fsyncs, g_io.synced, g_io.renamed_from);
    struct stat st;
    mode_t um = umask(022);
    umask(um);
    CHECK_MSG(stat(path, &st) == 0 && S_ISREG(st.st_mode) && (st.st_mode & 0777) == (0666 & ~um),
              "atomic write: mode %o, want a regular file with 0666 & ~umask = %o", (unsigned)(st.st_mode & 0777),
              (unsigned)(0666 & ~um));
    CHECK_MSG(stray_files(dir, "settings.json", stray, sizeof stray) == 0, "atomic write left %s behind", stray);
    CHECK(mr_file_write_atomic(path, old, strlen(old), &err));

    /* A real failure midway: a file-size limit (RLIMIT_FSIZE binds root
     * too, unlike permissions): the first 4 KiB land, then EFBIG. */
    struct rlimit rl0, rl;
    CHECK(getrlimit(RLIMIT_FSIZE, &rl0) == 0);
    rl = rl0;
    rl.rlim_cur = 4096;
    void (*oldsig)(int) = signal(SIGXFSZ, SIG_IGN);
    CHECK(setrlimit(RLIMIT_FSIZE, &rl) == 0);
    err = (mr_error){0};
    bool ok = mr_file_write_atomic(path, big, big_n, &err);
    CHECK(setrlimit(RLIMIT_FSIZE, &rl0) == 0);
    signal(SIGXFSZ, oldsig);
    CHECK_MSG(!ok && err.code == MR_ERR_IO && strstr(err.msg, path) && !strchr(err.msg, '\n'),
              "write failing after 4 KiB (file-size limit): must fail with one line naming the file (ok %d: %s)", ok,
              err.msg);
    check_kept(dir, "settings.json", old, "file-size limit after 4 KiB");

    /* Injected failures of the fsync and of the rename. */
    memset(&g_io, 0, sizeof g_io);
    g_io.fail_fsync = EIO;
    err = (mr_error){0};
    ok = mr_file_write_atomic(path, big, big_n, &err);
    g_io.fail_fsync = 0;
    CHECK_MSG(!ok && err.code == MR_ERR_IO, "a failing fsync (EIO) must fail the write (ok %d, fsyncs %d)", ok, g_io.fsyncs);
    check_kept(dir, "settings.json", old, "fsync failing with EIO");
    g_io.fail_rename = EXDEV;
    err = (mr_error){0};
    ok = mr_file_write_atomic(path, big, big_n, &err);
    g_io.fail_rename = 0;
    CHECK_MSG(!ok && err.code == MR_ERR_IO, "a failing rename must fail the write (ok %d)", ok);
    check_kept(dir, "settings.json", old, "rename failing with EXDEV");

    /* A full disk, where a small tmpfs can be mounted (root with
     * CAP_SYS_ADMIN; else skipped quietly: the checks above stand alone). */
    char mnt[1300];
    snprintf(mnt, sizeof mnt, "%s/tiny", dir);
    CHECK(mr_mkdirs(mnt, &err));
    if (mount("tmpfs", mnt, "tmpfs", MS_NOSUID | MS_NODEV, "size=64k,mode=0755") == 0) {
        char full[1400];
        snprintf(full, sizeof full, "%s/settings.json", mnt);
        CHECK(mr_file_write_atomic(full, old, strlen(old), &err));
        err = (mr_error){0};
        ok = mr_file_write_atomic(full, big, big_n, &err);
        CHECK_MSG(!ok && err.code == MR_ERR_IO && strstr(err.msg, full),
                  "write of 256 KiB onto a 64 KiB tmpfs must fail naming the file (ok %d: %s)", ok, err.msg);
        check_kept(mnt, "settings.json", old, "full disk (64 KiB tmpfs)");
        CHECK(umount2(mnt, MNT_DETACH) == 0);
    } else {
        printf("  (no tmpfs mount here: %s; the full-disk case is left out)\n", strerror(errno));
    }
    rmdir(mnt);

    /* A missing folder: one clear line, and nothing created. */
    char missing[1400];
    snprintf(missing, sizeof missing, "%s/no/such/dir/out.json", dir);
    err = (mr_error){0};
    ok = mr_file_write_atomic(missing, old, strlen(old), &err);
    CHECK_MSG(!ok && err.code == MR_ERR_IO && strstr(err.msg, missing) && strstr(err.msg, strerror(ENOENT)) &&
                  !strchr(err.msg, '\n'),
              "write into a missing folder: want one line naming the path and the reason, got \"%s\"", err.msg);
    snprintf(missing, sizeof missing, "%s/no", dir);
    CHECK_MSG(!mr_file_exists(missing), "a failed write into a missing folder created %s", missing);
    free(big);
    remove(path);
}

static void test_images(void) {
    mr_error err = {0};
    mr_image f;
    CHECK(mr_image_alloc(&f, 7, 5, 3, MR_PIX_F32, &err));
    float *d = f.data;
    for (int i = 0; i < 7 * 5 * 3; i++) d[i] = (float)i * 0.25f - 3.0f;
    char path[1200];
    snprintf(path, sizeof path, "%s/x.pfm", g_tmp);
    CHECK(mr_image_save_pfm(path, &f, &err));
    mr_image g;
    CHECK(mr_image_load_pfm(path, &g, &err) && g.width == 7 && g.height == 5 && g.channels == 3);
    CHECK(g.data && memcmp(f.data, g.data, mr_image_bytes(&f)) == 0); /* rows flipped on disk and back */
    mr_image_free(&g);
    mr_image_free(&f);
    mr_image p;
    CHECK(mr_image_alloc(&p, 9, 4, 3, MR_PIX_U8, &err));
    for (size_t i = 0; i < mr_image_bytes(&p); i++) ((unsigned char *)p.data)[i] = (unsigned char)(i * 7);
    snprintf(path, sizeof path, "%s/x.png", g_tmp);
    CHECK(mr_image_save_png(path, &p, &err));
    CHECK(mr_image_load(path, 3, &g, &err) && memcmp(p.data, g.data, mr_image_bytes(&p)) == 0);
    float px[3];
    CHECK(mr_image_sample_bilinear(&p, 0, 0, px) && px[0] == ((unsigned char *)p.data)[0]);
    CHECK(!mr_image_sample_bilinear(&p, -1, 0, px));
    mr_image_free(&g);
    mr_image_free(&p);
    CHECK(!mr_image_alloc(&p, 0, 4, 3, MR_PIX_U8, &err));
    CHECK(!mr_image_load_pfm(path, &g, &err)); /* a PNG is not a PFM */
}

static void test_rng_and_errors(void) {
    mr_rng a, b;
    mr_rng_seed(&a, 42);
    mr_rng_seed(&b, 42);
    bool same = true;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < 1000; i++) same = same && mr_rng_u64(&a) == mr_rng_u64(&b);
    for (int i = 0; i < 20000; i++) {
        double z = mr_rng_normal(&a);
        sum += z;
        sum2 += z * z;
        double u = mr_rng_uniform(&a);
        CHECK(u >= 0 && u < 1);
    }
    CHECK(same);
    CHECK(fabs(sum / 20000) < 0.05 && fabs(sum2 / 20000 - 1) < 0.05);
    mr_error err = {0};
    CHECK(!mr_fail(&err, MR_ERR_PARSE, "line one\nline two"));
    CHECK(strchr(err.msg, '\n') == NULL && err.code == MR_ERR_PARSE);
    mr_error_prefix(&err, "file.glb");
    CHECK(strncmp(err.msg, "file.glb: line one", 18) == 0);
    CHECK(strcmp(mr_err_name(MR_ERR_NODEVICE), "nodevice") == 0);
    CHECK(!mr_fail(NULL, MR_ERR_IO, "ignored")); /* NULL err is allowed */
}

/* The view's state numbers (screen spread, distance between renderings)
 * and the JSON Lines buffer of track and replay. */
static void test_image_stats_and_jsonl(void) {
    mr_image a = {0}, b = {0}, f = {0};
    mr_error err = {0};
    CHECK(mr_image_alloc(&a, 4, 2, 3, MR_PIX_U8, &err) && mr_image_alloc(&b, 4, 2, 3, MR_PIX_U8, &err));
    memset(a.data, 10, mr_image_bytes(&a));
    memset(b.data, 10, mr_image_bytes(&b));
    double mean = -1, sd = -1;
    mr_image_u8_stats(&a, &mean, &sd);
    CHECK(mean == 10 && sd == 0); /* a blank picture has no spread */
    ((uint8_t *)a.data)[0] = 250;  /* one sample of 24 differs by 240 */
    mr_image_u8_stats(&a, &mean, &sd);
    CHECK(fabs(mean - 20) < 1e-12 && fabs(sd - sqrt((240.0 * 240 * 23 / 24) / 24)) < 1e-9);
    CHECK(fabs(mr_image_u8_mean_abs_diff(&a, &b) - 10) < 1e-12);
    CHECK(mr_image_u8_mean_abs_diff(&a, &b) == mr_image_u8_mean_abs_diff(&b, &a));
    CHECK(mr_image_alloc(&f, 4, 2, 3, MR_PIX_F32, &err));
    CHECK(mr_image_u8_mean_abs_diff(&a, &f) == -1); /* not comparable */
    mr_image_free(&b);
    CHECK(mr_image_alloc(&b, 2, 4, 3, MR_PIX_U8, &err));
    CHECK(mr_image_u8_mean_abs_diff(&a, &b) == -1);
    mr_image_free(&a);
    mr_image_free(&b);
    mr_image_free(&f);

    mr_jsonl l = {0};
    for (int i = 0; i < 3000; i++) { /* past the first few growths */
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "frame", i);
        CHECK(mr_jsonl_add(&l, o));
        cJSON_Delete(o);
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/lines.jsonl", g_tmp);
    CHECK(mr_jsonl_save(&l, path, &err));
    size_t n = 0;
    char *text = mr_file_read(path, &n, 0, &err);
    CHECK(text && n == l.len && strncmp(text, "{\"frame\":0}\n{\"frame\":1}\n", 24) == 0);
    int lines = 0;
    for (size_t i = 0; text && i < n; i++) lines += text[i] == '\n';
    CHECK(lines == 3000 && text && strstr(text, "{\"frame\":2999}\n") == text + n - 15);
    free(text);
    l.failed = true; /* an earlier allocation failure is reported, nothing written */
    snprintf(path, sizeof path, "%s/lines_failed.jsonl", g_tmp);
    CHECK(!mr_jsonl_save(&l, path, &err) && err.code == MR_ERR_NOMEM && !mr_file_exists(path));
    mr_jsonl_free(&l);
    CHECK(l.text == NULL && l.len == 0);
}

/* mr_parallel_for: every item exactly once, on more than one thread where
 * asked, and a false return stops the handing out. */
typedef struct pf_ctx {
    int hits[1000];
    pthread_t who[1000];
    int stop_at;
    int stopping; /* set by item stop_at just before it returns false */
} pf_ctx;

/* No assumption about scheduling or core count: item 0 holds its thread
 * until another thread has run an item (so a second thread must take one,
 * however loaded the machine), and items after the stop wait until the
 * stopping item is returning, then take 20 ms each: all 1000 would run only
 * if the stop were ignored (or after 18 s with one thread descheduled between
 * two instructions). */
static bool pf_item(void *arg, size_t i) {
    pf_ctx *c = arg;
    c->who[i] = pthread_self();
    __atomic_fetch_add(&c->hits[i], 1, __ATOMIC_RELEASE);
    if (i == 0 && c->stop_at < 0)
        for (int t = 0; t < 100000; t++) { /* up to 10 s */
            bool other = false;
            for (int k = 1; k < 1000 && !other; k++)
                other = __atomic_load_n(&c->hits[k], __ATOMIC_ACQUIRE) && !pthread_equal(c->who[k], pthread_self());
            if (other) break;
            usleep(100);
        }
    if (c->stop_at >= 0 && (int)i > c->stop_at) {
        for (int t = 0; t < 100000 && !__atomic_load_n(&c->stopping, __ATOMIC_ACQUIRE); t++) usleep(100);
        usleep(20000);
    }
    if ((int)i == c->stop_at) __atomic_store_n(&c->stopping, 1, __ATOMIC_RELEASE);
    return (int)i != c->stop_at;
}

static void test_parallel_for(void) {
    static pf_ctx c;
    memset(&c, 0, sizeof c);
    c.stop_at = -1;
    CHECK(mr_parallel_for(1000, 2, pf_item, &c));
    int once = 0, other = 0;
    for (int i = 0; i < 1000; i++) {
        once += c.hits[i] == 1;
        other += !pthread_equal(c.who[i], pthread_self());
    }
    CHECK_MSG(once == 1000, "%d of 1000 items ran exactly once", once);
    CHECK_MSG(other > 0, "no item ran on a second thread");
    memset(&c, 0, sizeof c);
    c.stop_at = 100;
    CHECK(!mr_parallel_for(1000, 2, pf_item, &c));
    int ran = 0, twice = 0, upto = 0;
    for (int i = 0; i < 1000; i++) {
        ran += c.hits[i] > 0;
        twice += c.hits[i] > 1;
        upto += i <= 100 && c.hits[i] == 1;
    }
    /* Items up to 100 ran once; after it, only those the other thread took
     * before it saw the stop (each waits for the stop, then takes 20 ms). */
    CHECK_MSG(upto == 101 && ran < 1000 && twice == 0, "stopped at 100: %d ran (%d of 0..100), %d twice", ran, upto, twice);
    CHECK(mr_parallel_for(0, 0, pf_item, &c)); /* nothing to do */
}

/* mr_hash64 keys the LOD and meshlet caches: every byte, the seed and the
 * length count, across the four-lane blocks (n >= 64), the 8-byte words
 * after them and the tail. */
static void test_hash(void) {
    unsigned char b[203];
    for (int i = 0; i < (int)sizeof b; i++) b[i] = (unsigned char)(i * 37 + 11);
    for (int n = 0; n <= (int)sizeof b; n += n < 70 ? 1 : 19) {
        uint64_t h = mr_hash64(7, b, (size_t)n);
        CHECK_MSG(h == mr_hash64(7, b, (size_t)n), "n %d: not deterministic", n);
        CHECK_MSG(h != mr_hash64(8, b, (size_t)n), "n %d: the seed does not count", n);
        if (n > 0) CHECK_MSG(h != mr_hash64(7, b, (size_t)n - 1), "n %d: the length does not count", n);
        int same = 0;
        for (int i = 0; i < n; i++) {
            b[i] ^= 0x10;
            same += mr_hash64(7, b, (size_t)n) == h;
            b[i] ^= 0x10;
        }
        CHECK_MSG(same == 0, "n %d: %d flipped bytes leave the hash as it was", n, same);
    }
    /* Two equal words in different lanes (or places) are not the same input. */
    uint64_t w[8] = {0};
    uint64_t z = mr_hash64(1, w, sizeof w);
    w[0] = 5;
    uint64_t a = mr_hash64(1, w, sizeof w);
    w[0] = 0;
    w[1] = 5;
    CHECK(a != z && a != mr_hash64(1, w, sizeof w));
}

int main(void) {
    const char *tmp = getenv("MR_TEST_TMP");
    snprintf(g_tmp, sizeof g_tmp, "%s/core", tmp ? tmp : "/tmp/mrcheck-test");
    mr_error err = {0};
    if (!mr_mkdirs(g_tmp, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    test_math();
    test_camera();
    test_json();
    test_files();
    test_atomic_writes();
    test_images();
    test_rng_and_errors();
    test_image_stats_and_jsonl();
    test_parallel_for();
    test_hash();
    return mr_test_finish("test_core");
}
