/* The hall folder: its manifest (hall.json), the checks a file passes
 * before it joins the hall, and the session folders inside it. The format
 * is documented in mr_session.h and docs/formats.md. */
#include "mr_session.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

const char *const mr_hall_item_keys[MR_HALL_ITEM_COUNT] = {"scene", "camera", "markers", "control", "tolerances"};
/* The file name a copied item gets inside the hall (the plan is referenced). */
static const char *const k_copy_names[MR_HALL_ITEM_COUNT] = {NULL, "camera.json", "markers.json", "control.json",
                                                             "tolerances.json"};
static const char *const k_known[] = {"mrcheck_hall", "name",  "scene", "camera",   "markers",
                                      "control",      "tolerances", "input", "sessions", NULL};

static void manifest_path(const char *dir, char *out, size_t n) { mr_path_join(dir, MR_HALL_MANIFEST, out, n); }

bool mr_hall_is(const char *dir) {
    char p[4096];
    struct stat st;
    manifest_path(dir, p, sizeof p);
    return stat(p, &st) == 0 && S_ISREG(st.st_mode);
}

/* A string key into out ("" when absent); false for another type. */
static bool str_key(const cJSON *j, const char *key, char *out, size_t n, const char *file, mr_error *err) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(j, key);
    out[0] = 0;
    if (!v || cJSON_IsNull(v)) return true;
    if (!cJSON_IsString(v) || !v->valuestring[0])
        return mr_fail(err, MR_ERR_PARSE, "%s: \"%s\" must be a non-empty string (a path relative to the hall)", file,
                       key);
    if (strlen(v->valuestring) >= n) return mr_fail(err, MR_ERR_PARSE, "%s: \"%s\" is too long", file, key);
    snprintf(out, n, "%s", v->valuestring);
    return true;
}

static bool hall_from_json(const cJSON *j, const char *dir, const char *file, bool warn, mr_hall *h, mr_error *err) {
    memset(h, 0, sizeof *h);
    if (strlen(dir) >= sizeof h->dir) return mr_fail(err, MR_ERR_INVALID, "hall folder name too long: %.60s...", dir);
    snprintf(h->dir, sizeof h->dir, "%s", dir);
    if (!cJSON_IsObject(j)) return mr_fail(err, MR_ERR_PARSE, "%s: not a JSON object", file);
    const cJSON *ver = cJSON_GetObjectItemCaseSensitive(j, "mrcheck_hall");
    if (ver && (!cJSON_IsNumber(ver) || ver->valuedouble != 1))
        return mr_fail(err, MR_ERR_UNSUPPORTED, "%s: \"mrcheck_hall\" must be 1 (this version's format)", file);
    if (warn) mr_json_warn_unknown(j, k_known, file);
    for (int i = 0; i < MR_HALL_ITEM_COUNT; i++)
        if (!str_key(j, mr_hall_item_keys[i], h->items[i], sizeof h->items[i], file, err)) return false;
    if (!str_key(j, "name", h->name, sizeof h->name, file, err) ||
        !str_key(j, "input", h->input, sizeof h->input, file, err) ||
        !str_key(j, "sessions", h->sessions, sizeof h->sessions, file, err))
        return false;
    if (!h->sessions[0]) snprintf(h->sessions, sizeof h->sessions, "%s", MR_HALL_DEFAULT_SESSIONS);
    return true;
}

bool mr_hall_load(const char *dir, mr_hall *h, mr_error *err) {
    char file[4096];
    manifest_path(dir, file, sizeof file);
    if (!mr_hall_is(dir)) return mr_fail(err, MR_ERR_IO, "%s is not a hall folder (no %s in it)", dir, MR_HALL_MANIFEST);
    cJSON *j = mr_json_load(file, err);
    if (!j) return false;
    bool ok = hall_from_json(j, dir, file, true, h, err);
    cJSON_Delete(j);
    return ok;
}

bool mr_hall_path(const mr_hall *h, mr_hall_item item, char *out, size_t n) {
    out[0] = 0;
    if (item < 0 || item >= MR_HALL_ITEM_COUNT || !h->items[item][0]) return false;
    mr_path_join(h->dir, h->items[item], out, n);
    return true;
}

void mr_hall_sessions_dir(const mr_hall *h, char *out, size_t n) {
    mr_path_join(h->dir, h->sessions[0] ? h->sessions : MR_HALL_DEFAULT_SESSIONS, out, n);
}

static bool is_dir(const char *p) {
    struct stat st;
    return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

void mr_hall_session_resolve(const mr_hall *h, const char *name, char *out, size_t n) {
    char sd[4096], p[4096];
    if (is_dir(name) || name[0] == '/') {
        snprintf(out, n, "%s", name);
        return;
    }
    mr_hall_sessions_dir(h, sd, sizeof sd);
    mr_path_join(sd, name, p, sizeof p);
    if (!is_dir(p)) mr_path_join(h->dir, name, p, sizeof p);
    snprintf(out, n, "%s", is_dir(p) ? p : name);
}

bool mr_hall_contains(const mr_hall *h, const char *path) {
    char hd[PATH_MAX], pp[PATH_MAX];
    if (!realpath(h->dir, hd) || !realpath(path, pp)) return false;
    size_t l = strlen(hd);
    return strncmp(hd, pp, l) == 0 && (pp[l] == '/' || pp[l] == 0);
}

void mr_hall_new_session(const mr_hall *h, const char *prefix, double t_unix, char *out, size_t n) {
    char sd[4096], stamp[64], name[128];
    time_t t = (time_t)t_unix;
    struct tm tm;
    localtime_r(&t, &tm);
    strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &tm);
    mr_hall_sessions_dir(h, sd, sizeof sd);
    for (int k = 1;; k++) {
        if (k == 1) snprintf(name, sizeof name, "%s%s", prefix ? prefix : "", stamp);
        else snprintf(name, sizeof name, "%s%s-%d", prefix ? prefix : "", stamp, k);
        mr_path_join(sd, name, out, n);
        struct stat st;
        if (stat(out, &st) != 0 || k > 999) return;
    }
}

/* ------------------------------------------------------------ checking */

bool mr_hall_check_file(mr_hall_item item, const char *path, mr_hall_scene_check_fn check, void *user, mr_error *err) {
    struct stat st;
    if (stat(path, &st) != 0) return mr_fail(err, MR_ERR_IO, "%s: cannot open %s: %s", mr_hall_item_keys[item], path, strerror(errno));
    if (!S_ISREG(st.st_mode)) return mr_fail(err, MR_ERR_IO, "%s: %s is not a file", mr_hall_item_keys[item], path);
    bool ok = false;
    switch (item) {
    case MR_HALL_SCENE:
        if (!check) return mr_fail(err, MR_ERR_INVALID, "scene: no scene loader to check %s with", path);
        ok = check(user, path, err);
        break;
    case MR_HALL_CAMERA: {
        mr_camera c;
        ok = mr_camera_load(path, &c, err);
        break;
    }
    case MR_HALL_MARKERS: {
        mr_marker_map m = {0};
        ok = mr_marker_map_load(path, &m, err);
        if (ok && m.count == 0) ok = mr_fail(err, MR_ERR_INVALID, "%s: the marker map has no tags", path);
        mr_marker_map_free(&m);
        break;
    }
    case MR_HALL_CONTROL: {
        mr_map_control *c = NULL;
        int count = 0;
        ok = mr_map_controls_load(path, &c, &count, err);
        free(c);
        break;
    }
    case MR_HALL_TOLERANCES: {
        mr_tolerances t;
        ok = mr_tolerances_load(path, &t, err);
        break;
    }
    default: return mr_fail(err, MR_ERR_INVALID, "no such hall item");
    }
    /* The loaders' messages do not all name the file: the line says which
     * of the hall's files it is and where. */
    if (!ok && !strstr(err->msg, path)) mr_error_prefix(err, "%s %s", mr_hall_item_keys[item], path);
    else if (!ok) mr_error_prefix(err, "%s", mr_hall_item_keys[item]);
    return ok;
}

/* ------------------------------------------------------------- writing */

/* path relative to the folder dir (both made absolute first, component by
 * component); a path that cannot be resolved stays as it is. */
static void relative_to(const char *dir, const char *path, char *out, size_t n) {
    char d[PATH_MAX], p[PATH_MAX];
    if (!realpath(dir, d) || !realpath(path, p)) {
        snprintf(out, n, "%s", path);
        return;
    }
    /* The longest common prefix of whole components ("/" is their end). */
    size_t common = 0;
    for (size_t i = 0;; i++) {
        bool dend = d[i] == '/' || !d[i], pend = p[i] == '/' || !p[i];
        if (dend && pend) common = i;
        if (!d[i] || !p[i] || d[i] != p[i]) break;
    }
    size_t len = 0;
    out[0] = 0;
    for (const char *s = d + common; *s; s++)
        if (*s == '/' && len + 4 < n) len += (size_t)snprintf(out + len, n - len, "../");
    const char *rest = p + common + (p[common] == '/');
    snprintf(out + len, n - len, "%s", rest);
    if (!out[0]) snprintf(out, n, ".");
}

static bool same_file(const char *a, const char *b) {
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

static bool copy_file(const char *from, const char *to, mr_error *err) {
    size_t size;
    void *data = mr_file_read(from, &size, 64u << 20, err);
    if (!data) return false;
    bool ok = mr_file_write_atomic(to, data, size, err);
    free(data);
    return ok;
}

static bool set_str(cJSON *j, const char *key, const char *value) {
    cJSON *s = cJSON_CreateString(value);
    if (!s) return false;
    if (cJSON_GetObjectItemCaseSensitive(j, key)) return cJSON_ReplaceItemInObjectCaseSensitive(j, key, s);
    return cJSON_AddItemToObject(j, key, s);
}

bool mr_hall_update_files(const char *dir, const mr_hall_update *u, bool create, mr_hall *out, mr_error *err) {
    char file[4096], path[4096];
    manifest_path(dir, file, sizeof file);
    bool exists = mr_hall_is(dir);
    if (!exists && !create) return mr_fail(err, MR_ERR_IO, "%s is not a hall folder (mrcheck hall init %s ...)", dir, dir);
    if (!exists && is_dir(dir) == false && mr_file_exists(dir))
        return mr_fail(err, MR_ERR_IO, "%s exists and is not a folder", dir);
    if (!exists && !u->files[MR_HALL_SCENE]) return mr_fail(err, MR_ERR_INVALID, "a new hall needs its plan: --scene FILE");
    /* Everything given is checked before anything is written. */
    mr_hall old;
    cJSON *j = NULL;
    if (exists) {
        if (!mr_hall_load(dir, &old, err) || !(j = mr_json_load(file, err))) return false;
    } else if (!(j = cJSON_CreateObject())) {
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    bool ok = true;
    for (int i = 0; ok && i < MR_HALL_ITEM_COUNT; i++)
        if (u->files[i]) ok = mr_hall_check_file((mr_hall_item)i, u->files[i], u->check_scene, u->check_user, err);
    if (ok && !exists) ok = mr_mkdirs(dir, err);
    /* The copies, then the manifest that names them. */
    if (ok && !cJSON_GetObjectItemCaseSensitive(j, "mrcheck_hall"))
        ok = cJSON_AddNumberToObject(j, "mrcheck_hall", 1) != NULL;
    for (int i = 0; ok && i < MR_HALL_ITEM_COUNT; i++) {
        if (!u->files[i]) continue;
        char rel[4096];
        if (k_copy_names[i]) {
            mr_path_join(dir, k_copy_names[i], path, sizeof path);
            if (!same_file(u->files[i], path)) ok = copy_file(u->files[i], path, err);
            snprintf(rel, sizeof rel, "%s", k_copy_names[i]);
        } else {
            relative_to(dir, u->files[i], rel, sizeof rel);
        }
        ok = ok && set_str(j, mr_hall_item_keys[i], rel);
    }
    if (ok && u->name) ok = set_str(j, "name", u->name);
    if (ok && u->input) ok = set_str(j, "input", u->input);
    if (ok && !cJSON_GetObjectItemCaseSensitive(j, "sessions")) ok = set_str(j, "sessions", MR_HALL_DEFAULT_SESSIONS);
    if (!ok && !err->msg[0]) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    ok = ok && mr_json_save(file, j, err);
    mr_hall h;
    /* The sessions folder, so that a recording can be copied in at once. */
    if (ok) ok = hall_from_json(j, dir, file, false, &h, err);
    char sd[4096];
    if (ok) mr_hall_sessions_dir(&h, sd, sizeof sd), ok = mr_mkdirs(sd, err);
    if (ok && out) *out = h;
    cJSON_Delete(j);
    return ok;
}

bool mr_hall_write_manifest(const char *dir, const char *const items[MR_HALL_ITEM_COUNT], const char *name,
                            mr_error *err) {
    char file[4096];
    manifest_path(dir, file, sizeof file);
    cJSON *j = cJSON_CreateObject();
    bool ok = j && cJSON_AddNumberToObject(j, "mrcheck_hall", 1);
    if (ok && name) ok = set_str(j, "name", name);
    for (int i = 0; ok && i < MR_HALL_ITEM_COUNT; i++)
        if (items[i]) ok = set_str(j, mr_hall_item_keys[i], items[i]);
    ok = ok && set_str(j, "sessions", MR_HALL_DEFAULT_SESSIONS);
    if (!ok) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    ok = ok && mr_json_save(file, j, err);
    cJSON_Delete(j);
    return ok;
}

int mr_hall_print(const mr_hall *h, mr_hall_scene_check_fn check, void *user, FILE *out) {
    int bad = 0;
    fprintf(out, "hall %s%s%s%s\n", h->dir, h->name[0] ? " (" : "", h->name, h->name[0] ? ")" : "");
    for (int i = 0; i < MR_HALL_ITEM_COUNT; i++) {
        char p[4096];
        if (!mr_hall_path(h, (mr_hall_item)i, p, sizeof p)) {
            fprintf(out, "  %-11s -\n", mr_hall_item_keys[i]);
            continue;
        }
        mr_error e = {0};
        bool ok = mr_hall_check_file((mr_hall_item)i, p, check, user, &e);
        bad += !ok;
        fprintf(out, "  %-11s %s: %s\n", mr_hall_item_keys[i], h->items[i], ok ? "ok" : e.msg);
    }
    char sd[4096];
    mr_hall_sessions_dir(h, sd, sizeof sd);
    fprintf(out, "  %-11s %s\n  %-11s %s\n", "input", h->input[0] ? h->input : MR_HALL_DEFAULT_INPUT " (default)",
            "sessions", sd);
    return bad;
}
