/* The view's settings file: read tolerantly, written atomically. */
#include "mr_view.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const double mr_view_rates[MR_VIEW_RATE_COUNT] = {0.25, 0.5, 1.0, 2.0, 4.0};
const char *const mr_view_notes[MR_VIEW_NOTE_COUNT] = {"missing", "extra", "moved", "wrong size", "clash", "other"};

static const char *const k_ghost_names[] = {"off", "alpha", "g0", "adaptive"};
#define GHOST_COUNT (int)(sizeof k_ghost_names / sizeof k_ghost_names[0])

const char *mr_view_ghost_name(mr_ghost_mode m) {
    return (int)m >= 0 && (int)m < GHOST_COUNT ? k_ghost_names[m] : "off";
}

bool mr_view_ghost_parse(const char *name, mr_ghost_mode *out) {
    for (int i = 0; name && i < GHOST_COUNT; i++)
        if (strcmp(name, k_ghost_names[i]) == 0) {
            *out = (mr_ghost_mode)i;
            return true;
        }
    return false;
}

void mr_view_default_config_path(char *out, size_t n) {
    const char *x = getenv("XDG_CONFIG_HOME"), *home = getenv("HOME");
    if (x && x[0]) snprintf(out, n, "%s/mrcheck/view.json", x);
    else if (home && home[0]) snprintf(out, n, "%s/.config/mrcheck/view.json", home);
    else snprintf(out, n, ".mrcheck-view.json");
}

static void warn_add(char *warn, size_t n, const char *what) {
    if (!warn || !n) return;
    size_t l = strlen(warn);
    snprintf(warn + l, n - l, "%s%s", l ? "; " : "", what);
}

void mr_view_settings_load(const char *path, mr_view_settings *s, char *warn, size_t warn_n) {
    static const mr_view_settings defaults = MR_VIEW_SETTINGS_DEFAULTS;
    *s = defaults;
    if (warn && warn_n) warn[0] = 0;
    if (!path || !path[0] || !mr_file_exists(path)) return;
    mr_error err = {0};
    cJSON *j = mr_json_load(path, &err);
    if (!j || !cJSON_IsObject(j)) {
        char m[sizeof err.msg + 64];
        snprintf(m, sizeof m, "ignoring settings, using defaults: %s", j ? "not a JSON object" : err.msg);
        warn_add(warn, warn_n, m);
        cJSON_Delete(j);
        return;
    }
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(j, "alpha");
    if (it && !(cJSON_IsNumber(it) && it->valuedouble >= 0 && it->valuedouble <= 1))
        warn_add(warn, warn_n, "alpha must be a number in [0, 1]");
    else if (it) s->alpha = (float)it->valuedouble;
    it = cJSON_GetObjectItemCaseSensitive(j, "rate");
    if (it) {
        int k = -1;
        for (int i = 0; cJSON_IsNumber(it) && i < MR_VIEW_RATE_COUNT; i++)
            if (fabs(mr_view_rates[i] - it->valuedouble) < 1e-9) k = i;
        if (k < 0) warn_add(warn, warn_n, "rate must be 0.25, 0.5, 1, 2 or 4");
        else s->rate_i = k;
    }
    it = cJSON_GetObjectItemCaseSensitive(j, "show_video");
    if (it && !cJSON_IsBool(it)) warn_add(warn, warn_n, "show_video must be true or false");
    else if (it) s->show_video = cJSON_IsTrue(it);
    it = cJSON_GetObjectItemCaseSensitive(j, "hide_hidden_layer");
    if (it && !cJSON_IsBool(it)) warn_add(warn, warn_n, "hide_hidden_layer must be true or false");
    else if (it) s->hide_hidden = cJSON_IsTrue(it);
    it = cJSON_GetObjectItemCaseSensitive(j, "ao");
    mr_ao_method m;
    if (it && !(cJSON_IsString(it) && mr_ao_method_parse(it->valuestring, &m) && m < MR_AO_METHOD_COUNT))
        warn_add(warn, warn_n, "ao is not a known AO method");
    else if (it) s->ao = m;
    it = cJSON_GetObjectItemCaseSensitive(j, "ghost");
    mr_ghost_mode g;
    if (it && !(cJSON_IsString(it) && mr_view_ghost_parse(it->valuestring, &g)))
        warn_add(warn, warn_n, "ghost must be off, alpha, g0 or adaptive");
    else if (it) s->ghost = g;
    cJSON_Delete(j);
}

bool mr_view_settings_save(const char *path, const mr_view_settings *s, mr_error *err) {
    char dir[4096];
    mr_path_dir(path, dir, sizeof dir);
    cJSON *j = cJSON_CreateObject();
    if (!j) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int ri = s->rate_i < 0 || s->rate_i >= MR_VIEW_RATE_COUNT ? 2 : s->rate_i;
    cJSON_AddNumberToObject(j, "alpha", s->alpha);
    cJSON_AddBoolToObject(j, "show_video", s->show_video);
    cJSON_AddBoolToObject(j, "hide_hidden_layer", s->hide_hidden);
    cJSON_AddNumberToObject(j, "rate", mr_view_rates[ri]);
    cJSON_AddStringToObject(j, "ao", mr_ao_method_name(s->ao));
    cJSON_AddStringToObject(j, "ghost", mr_view_ghost_name(s->ghost));
    /* mr_json_save writes a temporary file and renames it. */
    bool ok = (!dir[0] || mr_mkdirs(dir, err)) && mr_json_save(path, j, err);
    cJSON_Delete(j);
    return ok;
}
