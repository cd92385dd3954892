/* Pinhole camera with OpenCV distortion; camera and view JSON formats. */
#include "mr_core.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

bool mr_camera_validate(const mr_camera *c, mr_error *err) {
    if (c->width < 1 || c->height < 1 || c->width > 32768 || c->height > 32768)
        return mr_fail(err, MR_ERR_INVALID, "camera size %dx%d is out of range (1..32768)", c->width, c->height);
    if (!isfinite(c->fx) || !isfinite(c->fy) || !(c->fx > 0) || !(c->fy > 0))
        return mr_fail(err, MR_ERR_INVALID, "camera focal length must be finite and > 0 (fx=%g, fy=%g)", c->fx, c->fy);
    if (!isfinite(c->cx) || !isfinite(c->cy))
        return mr_fail(err, MR_ERR_INVALID, "camera principal point is not finite");
    for (int i = 0; i < 5; i++)
        if (!isfinite(c->dist[i]) || fabs(c->dist[i]) > 1e3)
            return mr_fail(err, MR_ERR_INVALID, "camera distortion coefficient %d is not finite or absurd (%g)", i, c->dist[i]);
    return true;
}

bool mr_camera_has_distortion(const mr_camera *c) {
    for (int i = 0; i < 5; i++)
        if (c->dist[i] != 0) return true;
    return false;
}

void mr_camera_distort(const mr_camera *c, double x, double y, double *xd, double *yd) {
    const double k1 = c->dist[0], k2 = c->dist[1], p1 = c->dist[2], p2 = c->dist[3], k3 = c->dist[4];
    double r2 = x * x + y * y;
    double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    *xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
    *yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
}

bool mr_camera_undistort(const mr_camera *c, double xd, double yd, double *x, double *y) {
    /* Fixed-point iteration as in OpenCV's undistortPoints, with a residual
     * check so a diverging case is reported instead of returned. */
    double ux = xd, uy = yd;
    for (int it = 0; it < 50; it++) {
        double dx, dy;
        mr_camera_distort(c, ux, uy, &dx, &dy);
        double ex = dx - xd, ey = dy - yd;
        if (fabs(ex) < 1e-12 && fabs(ey) < 1e-12) break;
        ux -= ex;
        uy -= ey;
        if (!isfinite(ux) || !isfinite(uy)) return false;
    }
    double dx, dy;
    mr_camera_distort(c, ux, uy, &dx, &dy);
    *x = ux;
    *y = uy;
    return fabs(dx - xd) < 1e-6 && fabs(dy - yd) < 1e-6;
}

mr_camera mr_camera_resized(const mr_camera *c, int width, int height) {
    mr_camera r = *c;
    double sx = (double)width / c->width, sy = (double)height / c->height;
    r.width = width;
    r.height = height;
    r.fx *= sx;
    r.fy *= sy;
    /* Pixel centres at integers: the image edge is at -0.5. */
    r.cx = (c->cx + 0.5) * sx - 0.5;
    r.cy = (c->cy + 0.5) * sy - 0.5;
    return r;
}

/* ------------------------------------------------------------------ JSON */

bool mr_json_number(const cJSON *obj, const char *key, double *out, bool required, mr_error *err) {
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!it) return required ? mr_fail(err, MR_ERR_PARSE, "missing number \"%s\"", key) : true;
    if (!cJSON_IsNumber(it)) return mr_fail(err, MR_ERR_PARSE, "\"%s\" must be a number", key);
    *out = it->valuedouble;
    if (!isfinite(*out)) return mr_fail(err, MR_ERR_INVALID, "\"%s\" is not finite", key);
    return true;
}

bool mr_json_numbers(const cJSON *obj, const char *key, double *out, int n, mr_error *err) {
    const cJSON *arr = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!cJSON_IsArray(arr)) return mr_fail(err, MR_ERR_PARSE, "\"%s\" must be an array of %d numbers", key, n);
    if (cJSON_GetArraySize(arr) != n)
        return mr_fail(err, MR_ERR_PARSE, "\"%s\" has %d entries, expected %d", key, cJSON_GetArraySize(arr), n);
    int i = 0;
    const cJSON *it;
    cJSON_ArrayForEach(it, arr) {
        if (!cJSON_IsNumber(it)) return mr_fail(err, MR_ERR_PARSE, "\"%s\"[%d] is not a number", key, i);
        if (!isfinite(it->valuedouble)) return mr_fail(err, MR_ERR_INVALID, "\"%s\"[%d] is not finite", key, i);
        out[i++] = it->valuedouble;
    }
    return true;
}

bool mr_json_dmat4(const cJSON *obj, const char *key, mr_dmat4 *out, mr_error *err) {
    return mr_json_numbers(obj, key, out->m, 16, err);
}

cJSON *mr_json_from_doubles(const double *v, int n) {
    cJSON *arr = cJSON_CreateArray();
    for (int i = 0; arr && i < n; i++) cJSON_AddItemToArray(arr, cJSON_CreateNumber(v[i]));
    return arr;
}

cJSON *mr_json_from_dmat4(const mr_dmat4 *m) { return mr_json_from_doubles(m->m, 16); }

cJSON *mr_json_load(const char *path, mr_error *err) {
    size_t size;
    char *text = mr_file_read(path, &size, 256u << 20, err);
    if (!text) return NULL;
    const char *end = NULL;
    cJSON *j = cJSON_ParseWithOpts(text, &end, 0);
    if (!j) {
        size_t off = end ? (size_t)(end - text) : 0;
        size_t line = 1;
        for (size_t i = 0; i < off && i < size; i++) line += text[i] == '\n';
        free(text);
        mr_fail(err, MR_ERR_PARSE, "%s: invalid JSON near line %zu", path, line);
        return NULL;
    }
    free(text);
    return j;
}

bool mr_json_save(const char *path, const cJSON *json, mr_error *err) {
    char *s = cJSON_Print(json);
    if (!s) return mr_fail(err, MR_ERR_NOMEM, "cannot serialise JSON for %s", path);
    size_t n = strlen(s);
    /* End with a newline like any text file. */
    char *t = realloc(s, n + 2);
    if (!t) { free(s); return mr_fail(err, MR_ERR_NOMEM, "out of memory"); }
    t[n] = '\n';
    t[n + 1] = 0;
    bool ok = mr_file_write_atomic(path, t, n + 1, err);
    free(t);
    return ok;
}

bool mr_camera_from_json(const cJSON *obj, mr_camera *cam, mr_error *err) {
    if (!cJSON_IsObject(obj)) return mr_fail(err, MR_ERR_PARSE, "camera must be a JSON object");
    memset(cam, 0, sizeof *cam);
    double w = 0, h = 0;
    if (!mr_json_number(obj, "width", &w, true, err) || !mr_json_number(obj, "height", &h, true, err) ||
        !mr_json_number(obj, "fx", &cam->fx, true, err) || !mr_json_number(obj, "fy", &cam->fy, true, err) ||
        !mr_json_number(obj, "cx", &cam->cx, true, err) || !mr_json_number(obj, "cy", &cam->cy, true, err)) {
        mr_error_prefix(err, "camera");
        return false;
    }
    if (w != floor(w) || h != floor(h) || w < 1 || h < 1 || w > 32768 || h > 32768)
        return mr_fail(err, MR_ERR_INVALID, "camera width/height must be whole numbers in 1..32768");
    cam->width = (int)w;
    cam->height = (int)h;
    const cJSON *d = cJSON_GetObjectItemCaseSensitive(obj, "dist");
    if (d) {
        /* OpenCV writes 4, 5, 8, 12 or 14 coefficients; we model the first 5
         * and refuse to silently drop non-zero higher-order terms. */
        if (!cJSON_IsArray(d)) return mr_fail(err, MR_ERR_PARSE, "camera \"dist\" must be an array");
        int n = cJSON_GetArraySize(d), i = 0;
        const cJSON *it;
        cJSON_ArrayForEach(it, d) {
            if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble))
                return mr_fail(err, MR_ERR_PARSE, "camera \"dist\"[%d] is not a finite number", i);
            if (i < 5) cam->dist[i] = it->valuedouble;
            else if (it->valuedouble != 0)
                return mr_fail(err, MR_ERR_UNSUPPORTED, "camera has %d distortion coefficients; only k1 k2 p1 p2 k3 are supported", n);
            i++;
        }
    }
    return mr_camera_validate(cam, err);
}

cJSON *mr_camera_to_json(const mr_camera *c) {
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "width", c->width);
    cJSON_AddNumberToObject(o, "height", c->height);
    cJSON_AddNumberToObject(o, "fx", c->fx);
    cJSON_AddNumberToObject(o, "fy", c->fy);
    cJSON_AddNumberToObject(o, "cx", c->cx);
    cJSON_AddNumberToObject(o, "cy", c->cy);
    cJSON_AddItemToObject(o, "dist", mr_json_from_doubles(c->dist, 5));
    return o;
}

bool mr_camera_load(const char *path, mr_camera *cam, mr_error *err) {
    cJSON *j = mr_json_load(path, err);
    if (!j) return false;
    bool ok = mr_camera_from_json(j, cam, err);
    cJSON_Delete(j);
    if (!ok) mr_error_prefix(err, "%s", path);
    return ok;
}

bool mr_view_from_json(const cJSON *obj, const char *base_dir, mr_view *view, mr_error *err) {
    if (!cJSON_IsObject(obj)) return mr_fail(err, MR_ERR_PARSE, "view must be a JSON object");
    const cJSON *cam = cJSON_GetObjectItemCaseSensitive(obj, "camera");
    if (cJSON_IsString(cam)) {
        char path[1024];
        mr_path_join(base_dir ? base_dir : ".", cam->valuestring, path, sizeof path);
        if (!mr_camera_load(path, &view->camera, err)) return false;
    } else if (cJSON_IsObject(cam)) {
        if (!mr_camera_from_json(cam, &view->camera, err)) return false;
    } else {
        return mr_fail(err, MR_ERR_PARSE, "view needs \"camera\" (an object or a path)");
    }
    if (!mr_json_dmat4(obj, "world_from_camera", &view->world_from_camera, err)) return false;
    /* A pose must be a rotation + translation: a scaled or sheared matrix
     * would silently distort every distance the check relies on. The
     * tolerance allows for JSON round-off of a real rotation. */
    if (!mr_m4_is_rigid(&view->world_from_camera, 1e-5))
        return mr_fail(err, MR_ERR_INVALID, "\"world_from_camera\" is not a rigid transform (rotation + translation, last row 0 0 0 1)");
    return true;
}

bool mr_view_load(const char *path, mr_view *view, mr_error *err) {
    cJSON *j = mr_json_load(path, err);
    if (!j) return false;
    char dir[1024];
    mr_path_dir(path, dir, sizeof dir);
    bool ok = mr_view_from_json(j, dir, view, err);
    cJSON_Delete(j);
    if (!ok) mr_error_prefix(err, "%s", path);
    return ok;
}

cJSON *mr_view_to_json(const mr_view *v) {
    cJSON *o = cJSON_CreateObject();
    cJSON_AddItemToObject(o, "camera", mr_camera_to_json(&v->camera));
    cJSON_AddItemToObject(o, "world_from_camera", mr_json_from_dmat4(&v->world_from_camera));
    return o;
}

/* Levenshtein distance, case-insensitive, of two short keys. */
static int key_distance(const char *a, const char *b) {
    size_t na = strlen(a), nb = strlen(b);
    if (na > 63 || nb > 63) return 1 << 20;
    int row[64];
    for (size_t j = 0; j <= nb; j++) row[j] = (int)j;
    for (size_t i = 1; i <= na; i++) {
        int diag = row[0];
        row[0] = (int)i;
        for (size_t j = 1; j <= nb; j++) {
            int up = row[j];
            int cost = tolower((unsigned char)a[i - 1]) == tolower((unsigned char)b[j - 1]) ? 0 : 1;
            int best = diag + cost;
            if (row[j] + 1 < best) best = row[j] + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[nb];
}

const char *mr_nearest_key(const char *key, const char *const *known) {
    const char *best = NULL;
    int bd = (int)strlen(key) / 2 + 1;
    for (int i = 0; known && known[i]; i++) {
        int d = key_distance(key, known[i]);
        if (d <= bd && (!best || d < key_distance(key, best))) best = known[i];
    }
    return best;
}

int mr_json_warn_unknown(const cJSON *obj, const char *const *known, const char *what) {
    int n = 0;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj) {
        const char *k = it->string;
        if (!k || k[0] == '_' || strncmp(k, "comment", 7) == 0) continue;
        bool found = false;
        for (int i = 0; known[i] && !found; i++) found = strcmp(k, known[i]) == 0;
        if (found) continue;
        n++;
        const char *near = mr_nearest_key(k, known);
        if (near)
            mr_log(MR_LOG_WARN, "%s: unknown key \"%s\" (did you mean \"%s\"?)", what, k, near);
        else {
            char list[512] = "";
            size_t len = 0;
            for (int i = 0; known[i] && len + 1 < sizeof list; i++)
                len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", i ? ", " : "", known[i]);
            mr_log(MR_LOG_WARN, "%s: unknown key \"%s\" ignored (known keys: %s)", what, k, list);
        }
    }
    return n;
}
