/* Marker map and camera readers, tag geometry. */
#include "mr_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const k_families[] = {
    "tag36h11", "tag25h9", "tag16h5", "tagCircle21h7", "tagCircle49h12", "tagStandard41h12", "tagStandard52h13",
    "tagCustom48h12",
};

bool mr_tag_family_known(const char *name) {
    if (!name) return false;
    for (size_t i = 0; i < sizeof k_families / sizeof k_families[0]; i++)
        if (strcmp(name, k_families[i]) == 0) return true;
    return false;
}

/* Ids in a family are small; more tags than this in one map is a broken file. */
#define MAX_MAP_TAGS 100000

bool mr_marker_map_from_json(const cJSON *obj, mr_marker_map *map, mr_error *err) {
    memset(map, 0, sizeof *map);
    if (!cJSON_IsObject(obj)) return mr_fail(err, MR_ERR_PARSE, "marker map: not a JSON object");
    const cJSON *fam = cJSON_GetObjectItemCaseSensitive(obj, "family");
    const char *family = "tag36h11";
    if (fam) {
        if (!cJSON_IsString(fam)) return mr_fail(err, MR_ERR_PARSE, "marker map: \"family\" must be a string");
        family = fam->valuestring;
    }
    if (!mr_tag_family_known(family))
        return mr_fail(err, MR_ERR_UNSUPPORTED, "marker map: unknown tag family '%.40s'", family);
    snprintf(map->family, sizeof map->family, "%s", family);
    double size = 0;
    if (!mr_json_number(obj, "tag_size", &size, true, err)) {
        mr_error_prefix(err, "marker map");
        return false;
    }
    if (!isfinite(size) || !(size > 0))
        return mr_fail(err, MR_ERR_INVALID, "marker map: tag_size must be > 0 (got %g)", size);
    map->tag_size = size;
    const cJSON *tags = cJSON_GetObjectItemCaseSensitive(obj, "tags");
    if (!cJSON_IsArray(tags)) return mr_fail(err, MR_ERR_PARSE, "marker map: \"tags\" must be an array");
    int n = cJSON_GetArraySize(tags);
    if (n < 1) return mr_fail(err, MR_ERR_INVALID, "marker map: no tags");
    if (n > MAX_MAP_TAGS) return mr_fail(err, MR_ERR_NOMEM, "marker map: too many tags (%d)", n);
    map->tags = calloc((size_t)n, sizeof *map->tags);
    if (!map->tags) return mr_fail(err, MR_ERR_NOMEM, "marker map: out of memory");
    int i = 0;
    const cJSON *t;
    cJSON_ArrayForEach(t, tags) {
        mr_marker *m = &map->tags[i];
        double id = -1;
        if (!cJSON_IsObject(t) || !mr_json_number(t, "id", &id, true, err) || !mr_json_dmat4(t, "world_from_tag", &m->world_from_tag, err)) {
            if (!cJSON_IsObject(t)) mr_fail(err, MR_ERR_PARSE, "not an object");
            mr_error_prefix(err, "marker map: tag %d", i);
            mr_marker_map_free(map);
            return false;
        }
        if (!(id >= 0 && id <= 1e6 && id == floor(id))) {
            mr_marker_map_free(map);
            return mr_fail(err, MR_ERR_INVALID, "marker map: tag %d: id must be a whole number >= 0 (got %g)", i, id);
        }
        m->id = (int)id;
        if (cJSON_GetObjectItemCaseSensitive(t, "tag_size")) {
            double ts = 0;
            if (!mr_json_number(t, "tag_size", &ts, true, err) || !isfinite(ts) || !(ts > 0)) {
                mr_marker_map_free(map);
                return mr_fail(err, MR_ERR_INVALID, "marker map: tag id %d: tag_size must be a number > 0", (int)id);
            }
            m->size = ts;
        }
        const cJSON *cv = cJSON_GetObjectItemCaseSensitive(t, "covariance");
        if (cv && !cJSON_IsNull(cv)) {
            bool good = cJSON_IsArray(cv) && cJSON_GetArraySize(cv) == 36;
            int k = 0;
            const cJSON *e;
            if (good)
                cJSON_ArrayForEach(e, cv) {
                    good = good && cJSON_IsNumber(e) && isfinite(e->valuedouble);
                    if (good) m->cov[k++] = e->valuedouble;
                }
            for (k = 0; good && k < 6; k++) {
                good = m->cov[7 * k] >= 0;
                for (int q = 0; q < k; q++)
                    good = good && fabs(m->cov[6 * k + q] - m->cov[6 * q + k]) <=
                                       1e-6 * (m->cov[7 * k] + m->cov[7 * q]) + 1e-300;
            }
            if (!good) {
                mr_marker_map_free(map);
                return mr_fail(err, MR_ERR_INVALID,
                               "marker map: tag id %d: covariance must be 36 finite numbers, symmetric, with a "
                               "diagonal >= 0",
                               (int)id);
            }
        }
        if (!mr_m4_is_rigid(&m->world_from_tag, 1e-4)) {
            mr_marker_map_free(map);
            return mr_fail(err, MR_ERR_INVALID, "marker map: tag id %d: world_from_tag is not a rigid transform", (int)id);
        }
        for (int k = 0; k < i; k++)
            if (map->tags[k].id == m->id) {
                mr_marker_map_free(map);
                return mr_fail(err, MR_ERR_INVALID, "marker map: duplicate tag id %d", (int)id);
            }
        i++;
    }
    map->count = n;
    return true;
}

bool mr_marker_map_parse(const char *text, size_t size, mr_marker_map *map, mr_error *err) {
    memset(map, 0, sizeof *map);
    cJSON *j = cJSON_ParseWithLength(text, size);
    if (!j) return mr_fail(err, MR_ERR_PARSE, "marker map: malformed JSON");
    bool ok = mr_marker_map_from_json(j, map, err);
    cJSON_Delete(j);
    return ok;
}

bool mr_marker_map_load(const char *path, mr_marker_map *map, mr_error *err) {
    memset(map, 0, sizeof *map);
    cJSON *j = mr_json_load(path, err);
    if (!j) return false;
    bool ok = mr_marker_map_from_json(j, map, err);
    cJSON_Delete(j);
    if (!ok) mr_error_prefix(err, "%s", path);
    return ok;
}

cJSON *mr_marker_map_to_json(const mr_marker_map *map) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "family", map->family);
    cJSON_AddNumberToObject(j, "tag_size", map->tag_size);
    cJSON *tags = cJSON_AddArrayToObject(j, "tags");
    for (int i = 0; i < map->count; i++) {
        cJSON *t = cJSON_CreateObject();
        cJSON_AddNumberToObject(t, "id", map->tags[i].id);
        cJSON_AddItemToObject(t, "world_from_tag", mr_json_from_dmat4(&map->tags[i].world_from_tag));
        if (map->tags[i].size > 0 && map->tags[i].size != map->tag_size)
            cJSON_AddNumberToObject(t, "tag_size", map->tags[i].size);
        bool any = false;
        for (int k = 0; k < 36; k++) any = any || (map->tags[i].cov[k] != 0 && isfinite(map->tags[i].cov[k]));
        if (any) cJSON_AddItemToObject(t, "covariance", mr_json_from_doubles(map->tags[i].cov, 36));
        cJSON_AddItemToArray(tags, t);
    }
    return j;
}

void mr_marker_map_free(mr_marker_map *map) {
    if (!map) return;
    free(map->tags);
    memset(map, 0, sizeof *map);
}

const mr_marker *mr_marker_map_find(const mr_marker_map *map, int id) {
    for (int i = 0; i < map->count; i++)
        if (map->tags[i].id == id) return &map->tags[i];
    return NULL;
}

void mr_marker_corners_tag(double s, mr_dvec3 out[4]) {
    double h = 0.5 * s;
    out[0] = mr_v3(-h, h, 0);
    out[1] = mr_v3(h, h, 0);
    out[2] = mr_v3(h, -h, 0);
    out[3] = mr_v3(-h, -h, 0);
}

double mr_marker_size(const mr_marker_map *map, const mr_marker *m) {
    return m && m->size > 0 ? m->size : map->tag_size;
}

void mr_marker_corners_world(const mr_marker_map *map, const mr_marker *m, mr_dvec3 out[4]) {
    mr_dvec3 c[4];
    mr_marker_corners_tag(mr_marker_size(map, m), c);
    for (int i = 0; i < 4; i++) out[i] = mr_m4_point(&m->world_from_tag, c[i]);
}

bool mr_camera_parse(const char *text, size_t size, mr_camera *cam, mr_error *err) {
    cJSON *j = cJSON_ParseWithLength(text, size);
    if (!j) return mr_fail(err, MR_ERR_PARSE, "camera: malformed JSON");
    bool ok = mr_camera_from_json(j, cam, err);
    cJSON_Delete(j);
    return ok;
}
