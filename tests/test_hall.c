/* The hall folder (lib/session/hall.c, hall_args.c): init checks every file
 * before writing anything, copies the small files in and references the
 * plan by a path relative to the hall; the paths resolve from any working
 * directory; a hall on a command line stands for its files. */
#include "mr_test.h"

#include "mr_scene.h"
#include "mr_session.h"

#include <stdarg.h>
#include <sys/stat.h>
#include <unistd.h>

static char g_src[2048];

static void src_path(const char *rel, char *out, size_t n) { snprintf(out, n, "%s/%s", g_src, rel); }

static bool check_scene(void *user, const char *path, mr_error *err) {
    (void)user;
    mr_scene *s = mr_scene_load(path, NULL, err);
    if (!s) return false;
    mr_scene_destroy(&s);
    return true;
}

static bool write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    if (!f) return false;
    fputs(text, f);
    return fclose(f) == 0;
}

static char *read_text(const char *path) {
    size_t n;
    mr_error err = {0};
    return mr_file_read(path, &n, 0, &err);
}

/* argv of a line (the strings are literals). */
static int line(char **argv, const char *a0, ...) {
    va_list ap;
    int n = 0;
    va_start(ap, a0);
    for (const char *s = a0; s; s = va_arg(ap, const char *)) argv[n++] = (char *)s;
    va_end(ap);
    argv[n] = NULL;
    return n;
}

/* The value after --flag in a's line, NULL if absent (and how often). */
static const char *value_of(const mr_hall_args *a, const char *flag, int *count) {
    const char *v = NULL;
    int c = 0;
    for (int i = 2; i + 1 < a->argc; i++)
        if (strncmp(a->argv[i], "--", 2) == 0 && strcmp(a->argv[i] + 2, flag) == 0) v = a->argv[i + 1], c++;
    if (count) *count = c;
    return v;
}

int main(void) {
    const char *s = getenv("MR_SOURCE_DIR");
    snprintf(g_src, sizeof g_src, "%s", s ? s : ".");
    mr_error err = {0};
    char tmp[1024], hall[1200], scene[2100], camera[2100], markers[2100], bad[1200], p[4096];
    if (!mr_test_fresh_dir("hall", tmp, sizeof tmp)) return 1;
    /* The plan is given relative to the working directory at init (tmp),
     * and must be named relative to the hall in the manifest. */
    char cwd[4096];
    CHECK(getcwd(cwd, sizeof cwd) != NULL);
    src_path("configs/scenes/demo_planned.json", p, sizeof p);
    char *plan = read_text(p);
    snprintf(scene, sizeof scene, "%s/plan", tmp);
    CHECK(plan && mr_mkdirs(scene, &err));
    snprintf(scene, sizeof scene, "%s/plan/demo_planned.json", tmp);
    CHECK(plan && write_text(scene, plan));
    free(plan);
    CHECK(chdir(tmp) == 0);
    snprintf(scene, sizeof scene, "plan/demo_planned.json");
    src_path("configs/cameras/demo_640x480.json", camera, sizeof camera);
    src_path("configs/markers/demo_hall.json", markers, sizeof markers);

    /* A bad file of each kind is refused, naming it, and nothing is made. */
    snprintf(hall, sizeof hall, "h");
    snprintf(bad, sizeof bad, "%s/bad.json", tmp);
    CHECK(write_text(bad, "{\"width\": 640, \"default_mm\": -1}\n")); /* bad as every kind */
    for (int i = 0; i < MR_HALL_ITEM_COUNT; i++) {
        mr_hall_update u = MR_HALL_UPDATE_DEFAULTS;
        u.check_scene = check_scene;
        u.files[MR_HALL_SCENE] = scene;
        u.files[i] = bad;
        memset(&err, 0, sizeof err);
        CHECK_MSG(!mr_hall_update_files(hall, &u, true, NULL, &err), "a bad %s was accepted", mr_hall_item_keys[i]);
        CHECK_MSG(strstr(err.msg, "bad.json") && strncmp(err.msg, mr_hall_item_keys[i], strlen(mr_hall_item_keys[i])) == 0,
                  "%s: %s", mr_hall_item_keys[i], err.msg);
        CHECK_MSG(!strchr(err.msg, '\n'), "two lines: %s", err.msg);
        CHECK_MSG(!mr_file_exists(hall), "a refused %s left %s behind", mr_hall_item_keys[i], hall);
    }
    /* A missing file, and a new hall without a plan. */
    mr_hall_update u = MR_HALL_UPDATE_DEFAULTS;
    u.check_scene = check_scene;
    snprintf(p, sizeof p, "%s/none.json", tmp);
    u.files[MR_HALL_SCENE] = scene;
    u.files[MR_HALL_CAMERA] = p;
    CHECK(!mr_hall_update_files(hall, &u, true, NULL, &err) && strstr(err.msg, "none.json"));
    u.files[MR_HALL_SCENE] = NULL;
    u.files[MR_HALL_CAMERA] = camera;
    CHECK(!mr_hall_update_files(hall, &u, true, NULL, &err) && strstr(err.msg, "--scene"));
    CHECK(!mr_file_exists(hall));

    /* Good files: the plan referenced relative to the hall, the camera and
     * map copied in. */
    u.files[MR_HALL_SCENE] = scene;
    u.files[MR_HALL_MARKERS] = markers;
    u.input = "/dev/video2";
    mr_hall h;
    memset(&err, 0, sizeof err);
    CHECK_MSG(mr_hall_update_files(hall, &u, true, &h, &err), "%s", err.msg);
    CHECK(mr_hall_is(hall));
    CHECK(strcmp(h.items[MR_HALL_CAMERA], "camera.json") == 0 && strcmp(h.items[MR_HALL_MARKERS], "markers.json") == 0);
    CHECK_MSG(h.items[MR_HALL_SCENE][0] && h.items[MR_HALL_SCENE][0] != '/', "scene path %s", h.items[MR_HALL_SCENE]);
    CHECK(!h.items[MR_HALL_CONTROL][0] && !h.items[MR_HALL_TOLERANCES][0]);
    CHECK(strcmp(h.input, "/dev/video2") == 0 && strcmp(h.sessions, "sessions") == 0);
    snprintf(p, sizeof p, "%s/camera.json", hall);
    char *a = read_text(p), *b = read_text(camera);
    CHECK(a && b && strcmp(a, b) == 0); /* copied byte for byte */
    free(a);
    free(b);

    /* From another working directory, by a relative hall path, the paths
     * name the same files. */
    CHECK(strcmp(h.items[MR_HALL_SCENE], "../plan/demo_planned.json") == 0);
    struct stat s1, s2;
    CHECK(stat(scene, &s2) == 0);
    snprintf(p, sizeof p, "%s/elsewhere/deeper", tmp);
    CHECK(mr_mkdirs(p, &err) && chdir(p) == 0);
    mr_hall h2;
    CHECK_MSG(mr_hall_load("../../h", &h2, &err), "%s", err.msg);
    char q[4096];
    CHECK(mr_hall_path(&h2, MR_HALL_SCENE, q, sizeof q));
    CHECK_MSG(stat(q, &s1) == 0 && s1.st_ino == s2.st_ino, "scene from elsewhere: %s", q);
    CHECK(mr_hall_path(&h2, MR_HALL_MARKERS, q, sizeof q) && strcmp(q, "../../h/markers.json") == 0);
    CHECK(!mr_hall_path(&h2, MR_HALL_CONTROL, q, sizeof q) && !q[0]);

    /* A hall on a command line: `view HALL --replay NAME` gets the plan, a
     * session looked up in the hall, its folder as --out, and no camera
     * or map (the recording carries its own). */
    CHECK(mr_mkdirs("../../h/sessions/walk", &err));
    CHECK(write_text("../../h/sessions/walk/meta.json", "{}") && write_text("../../h/sessions/walk/frames.jsonl", ""));
    char *argv[32];
    int argc = line(argv, "mrcheck", "view", "../../h", "--replay", "walk", "--size", "480x360", NULL);
    mr_hall_args ha;
    CHECK_MSG(mr_hall_args_expand(argc, argv, &ha, &err), "%s", err.msg);
    int n = 0;
    const char *v = value_of(&ha, "scene", &n);
    CHECK_MSG(v && n == 1 && stat(v, &s1) == 0 && s1.st_ino == s2.st_ino, "--scene %s", v ? v : "(none)");
    CHECK(strcmp(ha.argv[1], "view") == 0 && strcmp(ha.argv[2], "--replay") == 0);
    CHECK_MSG(strcmp(value_of(&ha, "replay", NULL), "../../h/sessions/walk") == 0, "%s", value_of(&ha, "replay", NULL));
    CHECK(value_of(&ha, "out", NULL) && strcmp(value_of(&ha, "out", NULL), "../../h/sessions/walk") == 0);
    CHECK(!value_of(&ha, "camera", NULL) && !value_of(&ha, "markers", NULL) && !value_of(&ha, "input", NULL));
    CHECK(strcmp(value_of(&ha, "size", NULL), "480x360") == 0);
    for (int i = 0; i < ha.argc; i++) CHECK(strcmp(ha.argv[i], "../../h") != 0); /* the hall itself is gone */
    mr_hall_args_free(&ha);

    /* Live, with --hall: camera, map and the manifest's input; a flag
     * given on the line wins; the marks go to a new session in the hall. */
    argc = line(argv, "mrcheck", "view", "--camera", "mine.json", "--hall=../../h", NULL);
    CHECK_MSG(mr_hall_args_expand(argc, argv, &ha, &err), "%s", err.msg);
    CHECK(value_of(&ha, "camera", &n) && n == 1 && strcmp(value_of(&ha, "camera", NULL), "mine.json") == 0);
    CHECK(value_of(&ha, "markers", NULL) && strcmp(value_of(&ha, "markers", NULL), "../../h/markers.json") == 0);
    CHECK(value_of(&ha, "input", NULL) && strcmp(value_of(&ha, "input", NULL), "/dev/video2") == 0);
    v = value_of(&ha, "out", NULL);
    CHECK_MSG(v && strncmp(v, "../../h/sessions/", 17) == 0, "--out %s", v ? v : "(none)");
    mr_hall_args_free(&ha);

    /* Live without a marker map in the hall: one line that says how the
     * hall gets one (a recorded session needs none). */
    CHECK(write_text("../../h/hall.json.bak", "x") && rename("../../h/hall.json", "../../h/hall.json.bak") == 0);
    CHECK(write_text("../../h/hall.json", "{\"scene\": \"../plan/demo_planned.json\", \"camera\": \"camera.json\"}"));
    argc = line(argv, "mrcheck", "view", "../../h", NULL);
    memset(&err, 0, sizeof err);
    CHECK(!mr_hall_args_expand(argc, argv, &ha, &err) && strstr(err.msg, "no marker map") && strstr(err.msg, "mrcheck map"));
    mr_hall_args_free(&ha);
    argc = line(argv, "mrcheck", "view", "../../h", "--replay", "walk", NULL);
    CHECK_MSG(mr_hall_args_expand(argc, argv, &ha, &err), "%s", err.msg);
    mr_hall_args_free(&ha);
    CHECK(rename("../../h/hall.json.bak", "../../h/hall.json") == 0);

    /* A recording outside the hall: its marks go into the hall, never
     * next to it (shipped recordings stay as they are). */
    char rec[4096];
    src_path("recordings/demo", rec, sizeof rec);
    argc = line(argv, "mrcheck", "replay", "../../h", rec, NULL);
    CHECK_MSG(mr_hall_args_expand(argc, argv, &ha, &err), "%s", err.msg);
    CHECK(strcmp(ha.argv[2], rec) == 0);
    v = value_of(&ha, "out", NULL);
    CHECK_MSG(v && strcmp(v, "../../h/sessions/demo/replay") == 0, "--out %s", v ? v : "(none)");
    mr_hall_args_free(&ha);

    /* map writes the marker map into the hall; a line without a hall is
     * passed through as it is. */
    argc = line(argv, "mrcheck", "map", "../../h", "--images", "x", "--fix", "0", NULL);
    CHECK(mr_hall_args_expand(argc, argv, &ha, &err));
    CHECK(value_of(&ha, "out", NULL) && strcmp(value_of(&ha, "out", NULL), "../../h/markers.json") == 0);
    CHECK(value_of(&ha, "camera", NULL) && !value_of(&ha, "control", NULL) && ha.update_item == MR_HALL_MARKERS);
    mr_hall_args_free(&ha);
    argc = line(argv, "mrcheck", "view", "--scene", "s.json", "--replay", "walk", NULL);
    CHECK(mr_hall_args_expand(argc, argv, &ha, &err) && !ha.have_hall && ha.argc == argc);
    for (int i = 0; i < argc && i < ha.argc; i++) CHECK(ha.argv[i] == argv[i]);
    mr_hall_args_free(&ha);

    /* hall add replaces one file and keeps the rest (and notes); a bad
     * replacement leaves the manifest as it was. */
    CHECK(chdir(tmp) == 0);
    snprintf(p, sizeof p, "%s/hall.json", hall);
    char *before = read_text(p);
    mr_hall_update u2 = MR_HALL_UPDATE_DEFAULTS;
    u2.files[MR_HALL_CAMERA] = bad;
    CHECK(!mr_hall_update_files(hall, &u2, false, NULL, &err));
    char *after = read_text(p);
    CHECK(before && after && strcmp(before, after) == 0);
    free(before);
    free(after);
    src_path("configs/cameras/demo_tablet.json", q, sizeof q);
    u2.files[MR_HALL_CAMERA] = q;
    CHECK_MSG(mr_hall_update_files(hall, &u2, false, &h, &err), "%s", err.msg);
    CHECK(strcmp(h.items[MR_HALL_MARKERS], "markers.json") == 0 && strcmp(h.input, "/dev/video2") == 0);
    snprintf(p, sizeof p, "%s/camera.json", hall);
    a = read_text(p), b = read_text(q);
    CHECK(a && b && strcmp(a, b) == 0);
    free(a);
    free(b);
    /* add needs a hall. */
    snprintf(p, sizeof p, "%s/nohall", tmp);
    CHECK(!mr_hall_update_files(p, &u2, false, NULL, &err) && !mr_file_exists(p));
    /* A manifest with a key of the wrong type is one clear error. */
    snprintf(p, sizeof p, "%s/h/hall.json", tmp);
    CHECK(write_text(p, "{\"mrcheck_hall\": 1, \"scene\": 3}"));
    CHECK(!mr_hall_load(hall, &h, &err) && strstr(err.msg, "\"scene\""));
    CHECK(chdir(cwd) == 0);
    return mr_test_finish("test_hall");
}
