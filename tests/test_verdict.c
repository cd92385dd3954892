/* The verdict rule (lib/session/verdict.c): DIN 18202 Table 1's classes and
 * their edges, a hall's own table, and within / out / undecided on known
 * cases, the undecided band's edges included. */
#include "mr_session.h"
#include "mr_test.h"

static mr_verdict_kind judge(double dev_mm, double sigma_mm, double limit_mm) {
    mr_tolerance t = {limit_mm * 1e-3, 5.0, "test"};
    mr_verdict v;
    mr_error err = {0};
    CHECK(mr_verdict_judge(dev_mm * 1e-3, sigma_mm * 1e-3, &t, &v, &err));
    return v.kind;
}

static void din_table(void) {
    /* Every class at, just below and just above its upper edge. */
    static const struct { double m, mm; } cases[] = {
        {0.0, 10},   {0.5, 10},   {1.0, 10},   {1.0005, 12}, {2.0, 12},   {3.0, 12},   {3.0005, 16},
        {6.0, 16},   {6.0005, 20}, {10.0, 20}, {15.0, 20},   {15.0005, 24}, {30.0, 24}, {30.0005, 30},
        {1000.0, 30}, {1e7, 30},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double lim = mr_din18202_limit_m(cases[i].m, NULL);
        CHECK_MSG(fabs(lim * 1e3 - cases[i].mm) < 1e-9, "nominal %.4f m: ±%.3f mm, want ±%.0f", cases[i].m, lim * 1e3,
                  cases[i].mm);
    }
    const char *cls = NULL;
    mr_din18202_limit_m(10, &cls);
    CHECK(cls && strcmp(cls, "6-15 m") == 0);
    CHECK(isnan(mr_din18202_limit_m(-1, NULL)));
    CHECK(isnan(mr_din18202_limit_m(NAN, NULL)));
    CHECK(isnan(mr_din18202_limit_m(INFINITY, NULL)));
    /* The lookup without a hall table is the DIN table, and says so. */
    mr_tolerance t = mr_tolerance_lookup(NULL, "Machine_2", "visible", 8.0);
    CHECK_NEAR(t.limit_m, 0.020, 1e-12);
    CHECK(strstr(t.source, "DIN 18202") && strstr(t.source, "6-15 m"));
    CHECK_NEAR(t.nominal_m, 8.0, 0);
}

static void verdicts(void) {
    /* The demo's 0.30 m shift, measured to ±10 mm: clearly out. */
    CHECK(judge(300, 10, 20) == MR_VERDICT_OUT);
    /* An unchanged column: 3 mm ± 2 mm against ±20: within. */
    CHECK(judge(3, 2, 20) == MR_VERDICT_WITHIN);
    /* The undecided band: |d| - 2s <= limit < |d| + 2s. */
    CHECK(judge(18, 2, 20) == MR_VERDICT_UNDECIDED);
    CHECK(judge(22, 2, 20) == MR_VERDICT_UNDECIDED);
    CHECK(judge(30.7, 25.7, 20) == MR_VERDICT_UNDECIDED);
    /* Its edges: the interval touching the limit from inside is within,
     * touching it from outside is still undecided (the limit itself is
     * allowed). Values exact in binary to keep the edges exact. */
    CHECK(judge(16, 2, 20) == MR_VERDICT_WITHIN);
    CHECK(judge(16.25, 2, 20) == MR_VERDICT_UNDECIDED);
    CHECK(judge(24, 2, 20) == MR_VERDICT_UNDECIDED);
    CHECK(judge(24.25, 2, 20) == MR_VERDICT_OUT);
    /* A signed deviation counts by its size. */
    CHECK(judge(-300, 10, 20) == MR_VERDICT_OUT);
    CHECK(judge(-3, 2, 20) == MR_VERDICT_WITHIN);
    /* No uncertainty: a crisp rule, the limit inclusive. */
    CHECK(judge(20, 0, 20) == MR_VERDICT_WITHIN);
    CHECK(judge(20.5, 0, 20) == MR_VERDICT_OUT);
    /* The interval and the k used. */
    mr_tolerance t = mr_tolerance_lookup(NULL, NULL, NULL, 10.0);
    mr_verdict v;
    mr_error err = {0};
    CHECK(mr_verdict_judge(0.0307, 0.0257, &t, &v, &err));
    CHECK_NEAR(v.k, 2.0, 0);
    CHECK_NEAR(v.lo_m, 0.0, 0); /* a distance's interval starts at 0 at the least */
    CHECK_NEAR(v.hi_m, 0.0307 + 0.0514, 1e-12);
    char line[256];
    mr_verdict_format(&v, line, sizeof line);
    CHECK_MSG(strstr(line, "undecided") && strstr(line, "±20 mm") && strstr(line, "DIN 18202"), "%s", line);
    CHECK(mr_verdict_judge(-0.0307, 0.0257, &t, &v, &err));
    CHECK_NEAR(v.lo_m, -0.0307 - 0.0514, 1e-12);
    CHECK_NEAR(v.hi_m, -0.0307 + 0.0514, 1e-12);
    /* Bad input is refused, not judged. */
    CHECK(!mr_verdict_judge(NAN, 0.01, &t, &v, &err) && err.code == MR_ERR_INVALID);
    CHECK(!mr_verdict_judge(0.01, -1, &t, &v, &err));
    CHECK(!mr_verdict_judge(0.01, INFINITY, &t, &v, &err));
    mr_tolerance zero = {0, 1, "zero"};
    CHECK(!mr_verdict_judge(0.01, 0.001, &zero, &v, &err));
    /* JSON round trip. */
    CHECK(mr_verdict_judge(0.3, 0.01, &t, &v, &err));
    cJSON *j = mr_verdict_to_json(&v);
    mr_verdict back;
    CHECK(j && mr_verdict_from_json(j, &back, &err));
    CHECK(back.kind == MR_VERDICT_OUT);
    CHECK_NEAR(back.deviation_m, 0.3, 1e-12);
    CHECK_NEAR(back.tol.limit_m, 0.020, 1e-12);
    CHECK_NEAR(back.hi_m, 0.32, 1e-12);
    CHECK(strcmp(back.tol.source, v.tol.source) == 0);
    cJSON_ReplaceItemInObject(j, "verdict", cJSON_CreateString("maybe"));
    CHECK(!mr_verdict_from_json(j, &back, &err));
    cJSON_Delete(j);
    CHECK(strcmp(mr_verdict_words(MR_VERDICT_OUT), "out of tolerance") == 0);
    CHECK(strcmp(mr_verdict_key(MR_VERDICT_UNDECIDED), "undecided") == 0);
}

static void hall_table(void) {
    mr_error err = {0};
    cJSON *j = cJSON_Parse("{\"default_mm\": 25, \"layers\": {\"hidden\": 40},"
                           " \"parts\": {\"Machine_*\": 5, \"Column_3\": 8}, \"reference\": [1, 0, 0]}");
    mr_tolerances t;
    CHECK(mr_tolerances_from_json(j, &t, &err));
    cJSON_Delete(j);
    mr_tolerance r = mr_tolerance_lookup(&t, "Machine_2", "hidden", 10);
    CHECK_NEAR(r.limit_m, 0.005, 1e-12); /* part beats layer */
    CHECK(strstr(r.source, "Machine_*"));
    r = mr_tolerance_lookup(&t, "Column_3", "visible", 10);
    CHECK_NEAR(r.limit_m, 0.008, 1e-12);
    r = mr_tolerance_lookup(&t, "Duct_1", "hidden", 10);
    CHECK_NEAR(r.limit_m, 0.040, 1e-12); /* layer beats the default */
    r = mr_tolerance_lookup(&t, "Column_4", "visible", 10);
    CHECK_NEAR(r.limit_m, 0.025, 1e-12); /* the hall's default beats DIN */
    double p[3] = {4, 4, 0};
    CHECK_NEAR(mr_tolerance_nominal(&t, p), 5.0, 1e-12);
    CHECK_NEAR(mr_tolerance_nominal(NULL, p), sqrt(32.0), 1e-12);
    /* Without a default: DIN 18202 for what no rule names. */
    j = cJSON_Parse("{\"parts\": {\"Machine_*\": 5}}");
    CHECK(mr_tolerances_from_json(j, &t, &err));
    cJSON_Delete(j);
    r = mr_tolerance_lookup(&t, "Column_4", "visible", 2.0);
    CHECK_NEAR(r.limit_m, 0.012, 1e-12);
    /* Bad limits are errors; an unknown key is only a warning. */
    static const char *bad[] = {"{\"default_mm\": 0}", "{\"parts\": {\"A\": -1}}", "{\"layers\": {\"hidden\": \"x\"}}",
                                "{\"parts\": [5]}", "{\"reference\": [1, 2]}", "[]"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        j = cJSON_Parse(bad[i]);
        memset(&err, 0, sizeof err);
        CHECK_MSG(!mr_tolerances_from_json(j, &t, &err) && err.msg[0], "%s accepted", bad[i]);
        cJSON_Delete(j);
    }
    j = cJSON_Parse("{\"default_mn\": 7}");
    CHECK(mr_tolerances_from_json(j, &t, &err));
    cJSON_Delete(j);
}

static void nearest_key(void) {
    static const char *const known[] = {"gltf", "hidden", "ambient", "lights", NULL};
    const char *k = mr_nearest_key("hiden", known);
    CHECK(k && strcmp(k, "hidden") == 0);
    k = mr_nearest_key("Ambiant", known);
    CHECK(k && strcmp(k, "ambient") == 0);
    CHECK(mr_nearest_key("zzzzzzzzzz", known) == NULL);
    cJSON *j = cJSON_Parse("{\"gltf\": 1, \"hiden\": 2, \"_note\": 3, \"comment\": 4, \"xyz\": 5}");
    CHECK(mr_json_warn_unknown(j, known, "test") == 2);
    cJSON_Delete(j);
}

int main(void) {
    din_table();
    verdicts();
    hall_table();
    nearest_key();
    return mr_test_finish("test_verdict");
}
