/* Measurement verdicts: a deviation with its 95 % interval against a
 * tolerance (DIN 18202 Table 1 by default, or the hall's own table). The
 * rule and the table are documented in mr_session.h. */
#include "mr_session.h"

#include <fnmatch.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* DIN 18202 Table 1, row 1: upper edge of each nominal-size class (metres,
 * inclusive) and its limit deviation (mm). */
static const struct {
    double upto_m, limit_mm;
    const char *cls;
} din18202[] = {
    {1.0, 10, "up to 1 m"}, {3.0, 12, "1-3 m"}, {6.0, 16, "3-6 m"},
    {15.0, 20, "6-15 m"},   {30.0, 24, "15-30 m"}, {INFINITY, 30, "over 30 m"},
};

double mr_din18202_limit_m(double nominal_m, const char **cls) {
    if (cls) *cls = "";
    if (!isfinite(nominal_m) || nominal_m < 0) return NAN;
    for (size_t i = 0; i < sizeof din18202 / sizeof din18202[0]; i++)
        if (nominal_m <= din18202[i].upto_m) {
            if (cls) *cls = din18202[i].cls;
            return din18202[i].limit_mm * 1e-3;
        }
    return NAN; /* not reached: the last class has no upper edge */
}

static bool limit_mm(const cJSON *v, const char *what, const char *name, double *out_m, mr_error *err) {
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble <= 0)
        return mr_fail(err, MR_ERR_PARSE, "tolerances: %s \"%s\" must be a positive number of mm", what, name);
    *out_m = v->valuedouble * 1e-3;
    return true;
}

static bool rules(const cJSON *obj, const char *what, mr_tolerance_rule *r, int *count, mr_error *err) {
    if (!obj) return true;
    if (!cJSON_IsObject(obj))
        return mr_fail(err, MR_ERR_PARSE, "tolerances: \"%s\" must be an object of name: mm", what);
    const cJSON *it;
    cJSON_ArrayForEach(it, obj) {
        if (*count >= MR_TOLERANCE_RULES_MAX)
            return mr_fail(err, MR_ERR_PARSE, "tolerances: more than %d %s rules", MR_TOLERANCE_RULES_MAX, what);
        if (strlen(it->string) >= sizeof r->pattern)
            return mr_fail(err, MR_ERR_PARSE, "tolerances: %s name \"%.40s...\" is too long", what, it->string);
        if (!limit_mm(it, what, it->string, &r[*count].limit_m, err)) return false;
        snprintf(r[*count].pattern, sizeof r->pattern, "%s", it->string);
        (*count)++;
    }
    return true;
}

bool mr_tolerances_from_json(const cJSON *obj, mr_tolerances *t, mr_error *err) {
    mr_tolerances d = MR_TOLERANCES_DEFAULTS;
    *t = d;
    if (!cJSON_IsObject(obj)) return mr_fail(err, MR_ERR_PARSE, "tolerances: not a JSON object");
    static const char *const known[] = {"default_mm", "layers", "parts", "reference", NULL};
    mr_json_warn_unknown(obj, known, "tolerances");
    const cJSON *def = cJSON_GetObjectItemCaseSensitive(obj, "default_mm");
    if (def && !limit_mm(def, "limit", "default_mm", &t->default_m, err)) return false;
    if (!rules(cJSON_GetObjectItemCaseSensitive(obj, "parts"), "parts", t->parts, &t->part_count, err) ||
        !rules(cJSON_GetObjectItemCaseSensitive(obj, "layers"), "layers", t->layers, &t->layer_count, err))
        return false;
    if (cJSON_GetObjectItemCaseSensitive(obj, "reference") && !mr_json_numbers(obj, "reference", t->reference, 3, err))
        return false;
    return true;
}

bool mr_tolerances_load(const char *path, mr_tolerances *t, mr_error *err) {
    cJSON *j = mr_json_load(path, err);
    if (!j) return false;
    bool ok = mr_tolerances_from_json(j, t, err);
    cJSON_Delete(j);
    if (!ok) {
        char msg[sizeof err->msg];
        snprintf(msg, sizeof msg, "%s", err->msg);
        mr_fail(err, err->code, "%s: %s", path, msg);
    }
    return ok;
}

mr_tolerance mr_tolerance_lookup(const mr_tolerances *t, const char *part, const char *layer, double nominal_m) {
    mr_tolerance r;
    memset(&r, 0, sizeof r);
    r.nominal_m = nominal_m;
    if (t && part && *part)
        for (int i = 0; i < t->part_count; i++)
            if (fnmatch(t->parts[i].pattern, part, 0) == 0) {
                r.limit_m = t->parts[i].limit_m;
                snprintf(r.source, sizeof r.source, "hall table, part %s", t->parts[i].pattern);
                return r;
            }
    if (t && layer && *layer)
        for (int i = 0; i < t->layer_count; i++)
            if (strcmp(t->layers[i].pattern, layer) == 0) {
                r.limit_m = t->layers[i].limit_m;
                snprintf(r.source, sizeof r.source, "hall table, layer %s", t->layers[i].pattern);
                return r;
            }
    if (t && t->default_m > 0) {
        r.limit_m = t->default_m;
        snprintf(r.source, sizeof r.source, "hall table, default");
        return r;
    }
    const char *cls = "";
    r.limit_m = mr_din18202_limit_m(nominal_m, &cls);
    snprintf(r.source, sizeof r.source, "DIN 18202 Table 1, %s", cls);
    return r;
}

double mr_tolerance_nominal(const mr_tolerances *t, const double planned[3]) {
    const double o[3] = {0, 0, 0};
    const double *ref = t ? t->reference : o;
    double dx = planned[0] - ref[0], dy = planned[1] - ref[1], dz = planned[2] - ref[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

bool mr_verdict_judge(double deviation_m, double sigma_m, const mr_tolerance *tol, mr_verdict *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!isfinite(deviation_m)) return mr_fail(err, MR_ERR_INVALID, "verdict: the deviation is not a finite number");
    if (!isfinite(sigma_m) || sigma_m < 0)
        return mr_fail(err, MR_ERR_INVALID, "verdict: the uncertainty must be a finite number >= 0");
    if (!(tol->limit_m > 0) || !isfinite(tol->limit_m))
        return mr_fail(err, MR_ERR_INVALID, "verdict: the tolerance must be a positive number");
    double u = MR_VERDICT_K * sigma_m, a = fabs(deviation_m);
    out->deviation_m = deviation_m;
    out->sigma_m = sigma_m;
    out->k = MR_VERDICT_K;
    /* A distance cannot be negative: nor can its interval. */
    out->lo_m = deviation_m >= 0 && deviation_m - u < 0 ? 0 : deviation_m - u;
    out->hi_m = deviation_m + u;
    out->tol = *tol;
    if (a + u <= tol->limit_m)
        out->kind = MR_VERDICT_WITHIN;
    else if (a - u > tol->limit_m)
        out->kind = MR_VERDICT_OUT;
    else
        out->kind = MR_VERDICT_UNDECIDED;
    return true;
}

bool mr_verdict_measure(const mr_tolerances *t, const char *part, const char *layer, const double planned[3],
                        double nominal_m, double deviation_m, double sigma_m, mr_verdict *out, mr_error *err) {
    double nom = nominal_m >= 0 ? nominal_m : mr_tolerance_nominal(t, planned);
    mr_tolerance tol = mr_tolerance_lookup(t, part, layer, nom);
    return mr_verdict_judge(deviation_m, sigma_m, &tol, out, err);
}

const char *mr_verdict_key(mr_verdict_kind k) {
    switch (k) {
    case MR_VERDICT_WITHIN: return "within";
    case MR_VERDICT_OUT: return "out";
    case MR_VERDICT_UNDECIDED: return "undecided";
    default: return "";
    }
}

const char *mr_verdict_words(mr_verdict_kind k) {
    switch (k) {
    case MR_VERDICT_WITHIN: return "within tolerance";
    case MR_VERDICT_OUT: return "out of tolerance";
    case MR_VERDICT_UNDECIDED: return "undecided";
    default: return "";
    }
}

void mr_verdict_format(const mr_verdict *v, char *buf, size_t n) {
    snprintf(buf, n, "%s: %.1f mm, 95 %% interval %.1f .. %.1f mm, limit ±%.0f mm (%s)%s", mr_verdict_words(v->kind),
             v->deviation_m * 1e3, v->lo_m * 1e3, v->hi_m * 1e3, v->tol.limit_m * 1e3, v->tol.source,
             v->kind == MR_VERDICT_UNDECIDED ? "; measure again, closer or from a wider baseline" : "");
}

cJSON *mr_verdict_to_json(const mr_verdict *v) {
    cJSON *j = cJSON_CreateObject();
    if (!j) return NULL;
    double iv[2] = {v->lo_m * 1e3, v->hi_m * 1e3};
    cJSON_AddStringToObject(j, "verdict", mr_verdict_key(v->kind));
    cJSON_AddNumberToObject(j, "deviation_mm", v->deviation_m * 1e3);
    cJSON_AddNumberToObject(j, "sigma_mm", v->sigma_m * 1e3);
    cJSON_AddNumberToObject(j, "k", v->k);
    cJSON_AddItemToObject(j, "interval_mm", mr_json_from_doubles(iv, 2));
    cJSON_AddNumberToObject(j, "limit_mm", v->tol.limit_m * 1e3);
    cJSON_AddNumberToObject(j, "nominal_m", v->tol.nominal_m);
    cJSON_AddStringToObject(j, "tolerance", v->tol.source);
    return j;
}

bool mr_verdict_from_json(const cJSON *obj, mr_verdict *v, mr_error *err) {
    memset(v, 0, sizeof *v);
    if (!cJSON_IsObject(obj)) return mr_fail(err, MR_ERR_PARSE, "verdict: not an object");
    const cJSON *kind = cJSON_GetObjectItemCaseSensitive(obj, "verdict");
    const cJSON *src = cJSON_GetObjectItemCaseSensitive(obj, "tolerance");
    if (!cJSON_IsString(kind) || !cJSON_IsString(src)) return mr_fail(err, MR_ERR_PARSE, "verdict: no verdict or tolerance");
    for (int k = MR_VERDICT_WITHIN; k <= MR_VERDICT_UNDECIDED; k++)
        if (strcmp(kind->valuestring, mr_verdict_key((mr_verdict_kind)k)) == 0) v->kind = (mr_verdict_kind)k;
    if (v->kind == MR_VERDICT_NONE) return mr_fail(err, MR_ERR_PARSE, "verdict: unknown verdict \"%s\"", kind->valuestring);
    double dev, sig, k, lim, nom, iv[2];
    if (!mr_json_number(obj, "deviation_mm", &dev, true, err) || !mr_json_number(obj, "sigma_mm", &sig, true, err) ||
        !mr_json_number(obj, "k", &k, true, err) || !mr_json_number(obj, "limit_mm", &lim, true, err) ||
        !mr_json_number(obj, "nominal_m", &nom, true, err) || !mr_json_numbers(obj, "interval_mm", iv, 2, err))
        return false;
    v->deviation_m = dev * 1e-3;
    v->sigma_m = sig * 1e-3;
    v->k = k;
    v->lo_m = iv[0] * 1e-3;
    v->hi_m = iv[1] * 1e-3;
    v->tol.limit_m = lim * 1e-3;
    v->tol.nominal_m = nom;
    snprintf(v->tol.source, sizeof v->tol.source, "%s", src->valuestring);
    return true;
}
