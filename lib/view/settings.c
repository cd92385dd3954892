/* The view's settings file: read tolerantly, written atomically. */
#include "mr_view.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

const double mr_view_rates[MR_VIEW_RATE_COUNT] = {0.25, 0.5, 1.0, 2.0, 4.0};
const char *const mr_view_notes[MR_VIEW_NOTE_COUNT] = {"missing", "extra", "moved", "wrong size", "clash", "other"};

/* The shadow methods fit to look around in, in mr_shadow_method's order
 * (the ground truth, last there, is left out: seconds per frame). */
static const char *const k_view_shadow_names[] = {"off", "hard", "pcf", "pcss", "bp", NULL};
_Static_assert(MR_SHADOW_BP == 4 && MR_SHADOW_OFF == 0, "k_view_shadow_names follows mr_shadow_method");

#define VS(f) offsetof(mr_view_settings, f)
const mr_opt mr_view_settings_opts[] = {
    {"alpha", MR_OPT_FLOAT, VS(alpha), 0, 1, MR_VIEW_DEFAULT_ALPHA, NULL,
     "video transparency: 0 model only, 1 video only", 0},
    {"show_video", MR_OPT_BOOL, VS(show_video), 0, 1, 1, NULL, "show the camera image", 0},
    {"hide_hidden_layer", MR_OPT_BOOL, VS(hide_hidden), 0, 1, 0, NULL, "leave the hidden layer out", 0},
    {"ao", MR_OPT_ENUM, VS(ao), 0, 0, MR_AO_NONE, mr_ao_method_names, "ambient occlusion method", 0},
    {"ghost", MR_OPT_ENUM, VS(ghost), 0, 0, MR_GHOST_OFF, mr_ghost_mode_names, "ghosting mode", 0},
    {"shadows", MR_OPT_ENUM, VS(shadows), 0, 0, MR_SHADOW_OFF, k_view_shadow_names, "soft shadow method", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef VS

const char *mr_view_ghost_name(mr_ghost_mode m) {
    const char *n = mr_opt_enum_name(mr_opt_find(mr_view_settings_opts, "ghost"), (int)m);
    return n ? n : "off";
}

bool mr_view_ghost_parse(const char *name, mr_ghost_mode *out) {
    int v = mr_opt_enum_value(mr_opt_find(mr_view_settings_opts, "ghost"), name);
    if (v >= 0) *out = (mr_ghost_mode)v;
    return v >= 0;
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
    for (const mr_opt *o = mr_view_settings_opts; o->key; o++) {
        const cJSON *it = cJSON_GetObjectItemCaseSensitive(j, o->key);
        mr_error e = {0};
        if (it && !mr_opt_set_json(o, s, it, &e)) warn_add(warn, warn_n, e.msg);
    }
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(j, "rate");
    if (it) {
        int k = -1;
        for (int i = 0; cJSON_IsNumber(it) && i < MR_VIEW_RATE_COUNT; i++)
            if (fabs(mr_view_rates[i] - it->valuedouble) < 1e-9) k = i;
        if (k < 0) warn_add(warn, warn_n, "rate must be 0.25, 0.5, 1, 2 or 4");
        else s->rate_i = k;
    }
    cJSON_Delete(j);
}

bool mr_view_settings_save(const char *path, const mr_view_settings *s, mr_error *err) {
    char dir[4096];
    mr_path_dir(path, dir, sizeof dir);
    cJSON *j = cJSON_CreateObject();
    if (!j) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int ri = s->rate_i < 0 || s->rate_i >= MR_VIEW_RATE_COUNT ? 2 : s->rate_i;
    if (!mr_opt_to_json(mr_view_settings_opts, s, j) || !cJSON_AddNumberToObject(j, "rate", mr_view_rates[ri])) {
        cJSON_Delete(j);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    /* mr_json_save writes a temporary file and renames it. */
    bool ok = (!dir[0] || mr_mkdirs(dir, err)) && mr_json_save(path, j, err);
    cJSON_Delete(j);
    return ok;
}
