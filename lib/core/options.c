/* Declared option tables: parse, check, format and default the fields of a
 * params struct from one row per field (see mr_opt in mr_core.h). */
#include "mr_core.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const mr_opt *mr_opt_find(const mr_opt *table, const char *key) {
    for (const mr_opt *o = table; key && o->key; o++)
        if (strcmp(o->key, key) == 0) return o;
    return NULL;
}

int mr_opt_count(const mr_opt *table) {
    int n = 0;
    while (table[n].key) n++;
    return n;
}

int mr_opt_enum_count(const mr_opt *o) {
    int n = 0;
    while (o->names && o->names[n]) n++;
    return n;
}

const char *mr_opt_enum_name(const mr_opt *o, int v) {
    return v >= 0 && v < mr_opt_enum_count(o) ? o->names[v] : NULL;
}

int mr_opt_enum_value(const mr_opt *o, const char *name) {
    for (int i = 0; name && o->names && o->names[i]; i++)
        if (strcmp(o->names[i], name) == 0) return i;
    return -1;
}

int mr_opt_enum_next(const mr_opt *o, int v) {
    int n = mr_opt_enum_count(o);
    return n > 0 && v >= 0 ? (v + 1) % n : 0;
}

/* "a, b, c or d" into out. */
static void join_names(const mr_opt *o, char *out, size_t n) {
    int count = mr_opt_enum_count(o);
    size_t l = 0;
    out[0] = 0;
    for (int i = 0; i < count && l < n; i++) {
        const char *sep = i == 0 ? "" : i + 1 == count ? " or " : ", ";
        int w = snprintf(out + l, n - l, "%s%s", sep, o->names[i]);
        if (w < 0) break;
        l += (size_t)w;
    }
}

static void store(const mr_opt *o, void *params, double v) {
    char *f = (char *)params + o->offset;
    switch (o->type) {
    case MR_OPT_INT:
    case MR_OPT_ENUM: *(int *)f = (int)v; break;
    case MR_OPT_DOUBLE: *(double *)f = v; break;
    case MR_OPT_FLOAT: *(float *)f = (float)v; break;
    case MR_OPT_BOOL: *(bool *)f = (v != 0) != ((o->flags & MR_OPT_NEGATE) != 0); break;
    }
}

/* The field's own value (without the MR_OPT_ZERO_DEFAULT mapping). */
static double load(const mr_opt *o, const void *params) {
    const char *f = (const char *)params + o->offset;
    switch (o->type) {
    case MR_OPT_INT:
    case MR_OPT_ENUM: return *(const int *)f;
    case MR_OPT_DOUBLE: return *(const double *)f;
    case MR_OPT_FLOAT: return *(const float *)f;
    case MR_OPT_BOOL: return *(const bool *)f != ((o->flags & MR_OPT_NEGATE) != 0);
    }
    return 0;
}

/* The user's value v as the field stores it, and back. */
static double to_field(const mr_opt *o, double v) { return (o->flags & MR_OPT_ZERO_DEFAULT) && v == 0 ? -1 : v; }

double mr_opt_get(const mr_opt *o, const void *params) {
    double v = load(o, params);
    if (!(o->flags & MR_OPT_ZERO_DEFAULT)) return v;
    return v == 0 ? o->def : v < 0 ? 0 : v;
}

static bool range_fail(const mr_opt *o, const char *text, mr_error *err) {
    if (o->type == MR_OPT_INT)
        return mr_fail(err, MR_ERR_INVALID, "%s must be a whole number in [%ld, %ld], got '%s'", o->key, (long)o->lo,
                       (long)o->hi, text);
    return mr_fail(err, MR_ERR_INVALID, "%s must be a number in [%g, %g], got '%s'", o->key, o->lo, o->hi, text);
}

bool mr_opt_set_row(const mr_opt *o, void *params, const char *text, mr_error *err) {
    if (!text) text = "";
    char *end = NULL;
    errno = 0;
    switch (o->type) {
    case MR_OPT_INT: {
        long v = strtol(text, &end, 10);
        if (!text[0] || *end || errno || v < o->lo || v > o->hi) return range_fail(o, text, err);
        store(o, params, to_field(o, (double)v));
        return true;
    }
    case MR_OPT_DOUBLE:
    case MR_OPT_FLOAT: {
        double v = strtod(text, &end);
        if (!text[0] || *end || errno || !isfinite(v) || v < o->lo || v > o->hi) return range_fail(o, text, err);
        store(o, params, to_field(o, v));
        return true;
    }
    case MR_OPT_BOOL:
        if (!strcmp(text, "1") || !strcmp(text, "true") || !strcmp(text, "on")) store(o, params, 1);
        else if (!strcmp(text, "0") || !strcmp(text, "false") || !strcmp(text, "off")) store(o, params, 0);
        else if (o->flags & MR_OPT_ONOFF) return mr_fail(err, MR_ERR_INVALID, "%s must be on or off, got '%s'", o->key, text);
        else return mr_fail(err, MR_ERR_INVALID, "%s must be true or false, got '%s'", o->key, text);
        return true;
    case MR_OPT_ENUM: {
        int v = mr_opt_enum_value(o, text);
        if (v < 0) {
            char names[256];
            join_names(o, names, sizeof names);
            return mr_fail(err, MR_ERR_INVALID, "%s must be %s, got '%s'", o->key, names, text);
        }
        store(o, params, v);
        return true;
    }
    }
    return mr_fail(err, MR_ERR_INVALID, "%s: unknown option type", o->key);
}

bool mr_opt_set(const mr_opt *table, void *params, const char *key, const char *text, mr_error *err) {
    const mr_opt *o = mr_opt_find(table, key);
    if (!o) return mr_fail(err, MR_ERR_INVALID, "%s is not an option", key ? key : "(null)");
    return mr_opt_set_row(o, params, text, err);
}

bool mr_opt_set_json(const mr_opt *o, void *params, const cJSON *item, mr_error *err) {
    if (o->type == MR_OPT_BOOL) {
        if (!cJSON_IsBool(item)) return mr_fail(err, MR_ERR_INVALID, "%s must be true or false", o->key);
        store(o, params, cJSON_IsTrue(item));
        return true;
    }
    if (o->type == MR_OPT_ENUM) {
        if (!cJSON_IsString(item)) return mr_opt_set_row(o, params, "(not a string)", err);
        return mr_opt_set_row(o, params, item->valuestring, err);
    }
    char text[64];
    if (!cJSON_IsNumber(item)) return range_fail(o, "(not a number)", err);
    double v = item->valuedouble;
    /* Whole numbers are printed so that strtol reads them back exactly. */
    if (o->type == MR_OPT_INT && v == floor(v) && fabs(v) < 1e15) snprintf(text, sizeof text, "%.0f", v);
    else snprintf(text, sizeof text, "%.17g", v);
    return mr_opt_set_row(o, params, text, err);
}

static void format_value(const mr_opt *o, double v, char *out, size_t n) {
    switch (o->type) {
    case MR_OPT_BOOL: snprintf(out, n, "%s", v != 0 ? "true" : "false"); break;
    case MR_OPT_ENUM: {
        const char *name = mr_opt_enum_name(o, (int)v);
        snprintf(out, n, "%s", name ? name : "?");
        break;
    }
    case MR_OPT_INT: snprintf(out, n, "%d", (int)v); break;
    /* Floats print at float precision, so 0.05f reads "0.05". */
    case MR_OPT_FLOAT: snprintf(out, n, "%.7g", (double)(float)v); break;
    case MR_OPT_DOUBLE: snprintf(out, n, "%.15g", v); break;
    }
}

void mr_opt_format(const mr_opt *o, const void *params, char *out, size_t n) {
    format_value(o, mr_opt_get(o, params), out, n);
}

void mr_opt_describe(const mr_opt *o, char *out, size_t n) {
    char def[64];
    if (((o->flags & MR_OPT_ZERO_AUTO) && o->def == 0) || ((o->flags & MR_OPT_NEG_AUTO) && o->def < 0))
        snprintf(def, sizeof def, "auto");
    else format_value(o, o->def, def, sizeof def);
    switch (o->type) {
    case MR_OPT_BOOL: snprintf(out, n, "(default %s)", o->def != 0 ? "on" : "off"); break;
    case MR_OPT_ENUM: {
        char names[256];
        join_names(o, names, sizeof names);
        snprintf(out, n, "%s (default %s)", names, def);
        break;
    }
    case MR_OPT_INT: snprintf(out, n, "%ld..%ld (default %s)", (long)o->lo, (long)o->hi, def); break;
    case MR_OPT_FLOAT:
    case MR_OPT_DOUBLE: snprintf(out, n, "in [%g, %g] (default %s)", o->lo, o->hi, def); break;
    }
}

void mr_opt_defaults(const mr_opt *table, void *params) {
    for (const mr_opt *o = table; o->key; o++) store(o, params, (o->flags & MR_OPT_ZERO_DEFAULT) ? 0 : o->def);
}

bool mr_opt_to_json(const mr_opt *table, const void *params, cJSON *obj) {
    for (const mr_opt *o = table; o->key; o++) {
        double v = mr_opt_get(o, params);
        cJSON *item = NULL;
        if (o->type == MR_OPT_BOOL) item = cJSON_CreateBool(v != 0);
        else if (o->type == MR_OPT_ENUM) item = cJSON_CreateString(mr_opt_enum_name(o, (int)v) ? mr_opt_enum_name(o, (int)v) : "");
        else item = cJSON_CreateNumber(v);
        if (!item || !cJSON_AddItemToObject(obj, o->key, item)) {
            cJSON_Delete(item);
            return false;
        }
    }
    return true;
}
