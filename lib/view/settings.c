/* The view's settings file: read tolerantly, written atomically. */
#include "mr_view.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

const double mr_view_rates[MR_VIEW_RATE_COUNT] = {0.25, 0.5, 1.0, 2.0, 4.0};

/* The shadow methods fit to look around in, in mr_shadow_method's order
 * (the ground truth, last there, is left out: seconds per frame; "off" is
 * the toggle's, kept so that older files read). */
static const char *const k_view_shadow_names[] = {"off", "hard", "pcf", "pcss", "bp", NULL};
_Static_assert(MR_SHADOW_BP == 4 && MR_SHADOW_OFF == 0, "k_view_shadow_names follows mr_shadow_method");

#define VS(f) offsetof(mr_view_settings, f)
const mr_opt mr_view_settings_opts[] = {
    {"alpha", MR_OPT_FLOAT, VS(alpha), 0, 1, MR_VIEW_DEFAULT_ALPHA, NULL,
     "video transparency: 0 model only, 1 video only", 0},
    {"show_video", MR_OPT_BOOL, VS(show_video), 0, 1, 1, NULL, "show the camera image", 0},
    {"hide_hidden_layer", MR_OPT_BOOL, VS(hide_hidden), 0, 1, 0, NULL, "leave the hidden layer out", 0},
    {"ao_on", MR_OPT_BOOL, VS(ao_on), 0, 1, 0, NULL, "ambient occlusion on", 0},
    {"ghost_on", MR_OPT_BOOL, VS(ghost_on), 0, 1, 0, NULL, "ghosting of the hidden layer on", 0},
    {"shadows_on", MR_OPT_BOOL, VS(shadows_on), 0, 1, 0, NULL, "soft shadows on", 0},
    {"ao", MR_OPT_ENUM, VS(ao), 0, 0, MR_AO_SCHEER, mr_ao_method_names, "ambient occlusion method when on", 0},
    {"ghost", MR_OPT_ENUM, VS(ghost), 0, 0, MR_GHOST_ADAPTIVE, mr_ghost_mode_names, "ghosting mode when on", 0},
    {"shadows", MR_OPT_ENUM, VS(shadows), 0, 0, MR_SHADOW_PCSS, k_view_shadow_names, "soft shadow method when on", 0},
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
    /* Files from before the toggles: a method named means on; "none" or
     * "off" means off, with the default method. */
    static const char *const on_keys[3] = {"ao_on", "ghost_on", "shadows_on"};
    bool *on[3] = {&s->ao_on, &s->ghost_on, &s->shadows_on};
    int *method[3] = {(int *)&s->ao, (int *)&s->ghost, (int *)&s->shadows};
    const int off[3] = {MR_AO_NONE, MR_GHOST_OFF, MR_SHADOW_OFF};
    const int def[3] = {defaults.ao, defaults.ghost, defaults.shadows};
    static const char *const method_keys[3] = {"ao", "ghost", "shadows"};
    for (int i = 0; i < 3; i++) {
        const cJSON *m = cJSON_GetObjectItemCaseSensitive(j, method_keys[i]);
        const char *name = mr_opt_enum_name(mr_opt_find(mr_view_settings_opts, method_keys[i]), *method[i]);
        bool read = cJSON_IsString(m) && name && strcmp(m->valuestring, name) == 0; /* taken, not defaulted */
        if (!cJSON_GetObjectItemCaseSensitive(j, on_keys[i]) && read) *on[i] = *method[i] != off[i];
        if (*method[i] == off[i]) *method[i] = def[i];
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

mr_ao_method mr_view_ao(const mr_view_settings *s) { return s->ao_on ? s->ao : MR_AO_NONE; }
mr_ghost_mode mr_view_ghost(const mr_view_settings *s) { return s->ghost_on ? s->ghost : MR_GHOST_OFF; }
mr_shadow_method mr_view_shadows(const mr_view_settings *s) { return s->shadows_on ? s->shadows : MR_SHADOW_OFF; }

int mr_view_settings_describe_changes(const mr_view_settings *s, char *out, size_t n) {
    static const mr_view_settings d = MR_VIEW_SETTINGS_DEFAULTS;
    int count = 0;
    size_t k = 0;
    out[0] = 0;
#define SAY(...) do { if (k < n) k += (size_t)snprintf(out + k, n - k, count++ ? ", " : ""); \
                      if (k < n) k += (size_t)snprintf(out + k, n - k, __VA_ARGS__); } while (0)
    if (fabsf(s->alpha - d.alpha) > 0.005f) SAY("video %d%%", (int)lroundf(s->alpha * 100));
    if (s->show_video != d.show_video) SAY("video %s", s->show_video ? "on" : "off");
    if (s->hide_hidden != d.hide_hidden) SAY("hidden layer %s", s->hide_hidden ? "hidden" : "shown");
    if (s->rate_i != d.rate_i) SAY("replay at %gx", mr_view_rates[s->rate_i >= 0 && s->rate_i < MR_VIEW_RATE_COUNT ? s->rate_i : 2]);
    if (s->ao_on != d.ao_on) SAY("AO %s", s->ao_on ? "on" : "off");
    if (s->ao != d.ao) SAY("AO method %s", mr_ao_method_name(s->ao));
    if (s->ghost_on != d.ghost_on) SAY("ghosting %s", s->ghost_on ? "on" : "off");
    if (s->ghost != d.ghost) SAY("ghosting mode %s", mr_view_ghost_name(s->ghost));
    if (s->shadows_on != d.shadows_on) SAY("shadows %s", s->shadows_on ? "on" : "off");
    if (s->shadows != d.shadows) SAY("shadow method %s", mr_shadow_method_names[(int)s->shadows >= 0 && s->shadows < MR_SHADOW_METHOD_COUNT ? s->shadows : 0]);
#undef SAY
    return count;
}
