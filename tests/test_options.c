/* The declared option tables (mr_opt, lib/core/options.c) and every table
 * the libraries declare: mr_ao_opts, mr_ghost_opts (lib/render),
 * mr_view_settings_opts (lib/view), mr_detector_opts and mr_filter_opts
 * (lib/track), mr_gt_opts (lib/eval) and the benches' mr_bench_*_opts
 * (lib/bench). Each table is walked: keys unique,
 * offsets inside the struct, aligned and not overlapping, each default in
 * its range (or the documented 0 = auto), enum defaults valid names,
 * mr_opt_defaults equal to the MR_*_DEFAULTS macro field by field, and
 * every numeric option accepts its bounds and rejects a value just outside
 * them with one line naming the option, the range and the value. */
#include "mr_batch.h"
#include "mr_bench.h"
#include "mr_core.h"
#include "mr_eval.h"
#include "mr_export.h"
#include "mr_study.h"
#include "mr_render.h"
#include "mr_test.h"
#include "mr_track.h"
#include "mr_view.h"

#include <float.h>
#include <string.h>

/* The enum fields are written through an int. */
_Static_assert(sizeof(mr_ao_method) == sizeof(int), "mr_ao_method is int-sized");
_Static_assert(sizeof(mr_ao_radius_mode) == sizeof(int), "mr_ao_radius_mode is int-sized");
_Static_assert(sizeof(mr_ao_kernel) == sizeof(int), "mr_ao_kernel is int-sized");
_Static_assert(sizeof(mr_ao_mask) == sizeof(int), "mr_ao_mask is int-sized");
_Static_assert(sizeof(mr_ghost_mode) == sizeof(int), "mr_ghost_mode is int-sized");
_Static_assert(sizeof(mr_ghost_importance) == sizeof(int), "mr_ghost_importance is int-sized");
_Static_assert(sizeof(mr_saliency_impl) == sizeof(int), "mr_saliency_impl is int-sized");

static size_t type_size(mr_opt_type t) {
    switch (t) {
    case MR_OPT_INT:
    case MR_OPT_ENUM: return sizeof(int);
    case MR_OPT_DOUBLE: return sizeof(double);
    case MR_OPT_FLOAT: return sizeof(float);
    case MR_OPT_BOOL: return sizeof(bool);
    }
    return 0;
}

/* One line: non-empty, no newline, starts with the key, names the value. */
static bool one_line(const mr_error *e, const char *key, const char *value) {
    return e->msg[0] && !strchr(e->msg, '\n') && strncmp(e->msg, key, strlen(key)) == 0 && strstr(e->msg, value);
}

/* Sets text on a copy of params; true if accepted. On rejection checks the
 * message and that the field was left alone. */
static bool try_set(const char *table, const mr_opt *o, const void *params, size_t size, const char *text) {
    unsigned char buf[1024], before[1024];
    memcpy(buf, params, size);
    memcpy(before, params, size);
    mr_error e = {0};
    bool ok = mr_opt_set_row(o, buf, text, &e);
    if (!ok) {
        CHECK_MSG(one_line(&e, o->key, text), "%s.%s rejected '%s' without one line naming it and the value: '%s'",
                  table, o->key, text, e.msg);
        CHECK_MSG(memcmp(buf, before, size) == 0, "%s.%s: the rejected '%s' still changed the struct", table, o->key,
                  text);
    }
    return ok;
}

/* A MR_OPT_ZERO_DEFAULT row: the macro's field is 0 and reads as the
 * row's default; every accepted user value is stored as a non-zero field
 * (never mistaken for "the default") and reads back as itself, the user's
 * 0 as a negative field ("off"). */
/* The int or double field itself, without the row's mapping. */
static double raw_field(const mr_opt *o, const void *params) {
    const char *f = (const char *)params + o->offset;
    if (o->type == MR_OPT_INT) return *(const int *)f;
    double d;
    memcpy(&d, f, sizeof d);
    return d;
}

static void zero_default_row(const char *name, const mr_opt *o, size_t size, const void *macro) {
    unsigned char a[1024];
    CHECK_MSG(o->type == MR_OPT_INT || o->type == MR_OPT_DOUBLE, "%s.%s: a zero-default row must be int or double",
              name, o->key);
    CHECK_MSG(raw_field(o, macro) == 0, "%s.%s: the DEFAULTS macro's field is %g, not 0", name, o->key,
              raw_field(o, macro));
    CHECK_MSG(mr_opt_get(o, macro) == o->def, "%s.%s: the macro's 0 reads as %g, not the default %g", name, o->key,
              mr_opt_get(o, macro), o->def);
    CHECK_MSG(o->lo >= 0, "%s.%s: a zero-default row with negative values [%g, %g]", name, o->key, o->lo, o->hi);
    const double probe[3] = {o->lo, o->hi, o->type == MR_OPT_INT ? (double)(long)((o->lo + o->hi) / 2)
                                                                : (o->lo + o->hi) / 2};
    for (int k = 0; k < 3; k++) {
        char t[64];
        if (o->type == MR_OPT_INT) snprintf(t, sizeof t, "%ld", (long)probe[k]);
        else snprintf(t, sizeof t, "%.17g", probe[k]);
        memcpy(a, macro, size);
        mr_error e = {0};
        bool ok = mr_opt_set_row(o, a, t, &e);
        double field = raw_field(o, a);
        CHECK_MSG(ok && mr_opt_get(o, a) == probe[k], "%s.%s: '%s' reads back as %g (%s)", name, o->key, t,
                  mr_opt_get(o, a), e.msg);
        CHECK_MSG(probe[k] == 0 ? field < 0 : field == probe[k],
                  "%s.%s: the user's '%s' is stored as %g in the field (0 -> < 0 'off', else itself)", name, o->key, t,
                  field);
    }
}

static void walk_table(const char *name, const mr_opt *table, size_t size, const void *macro) {
    /* The scratch copies below hold 1024 bytes. */
    if (size > 1024) {
        CHECK_MSG(false, "%s: params struct of %zu bytes, more than this test's buffers", name, size);
        return;
    }
    int n = mr_opt_count(table);
    CHECK_MSG(n > 0, "%s is empty", name);
    for (int i = 0; i < n; i++) {
        const mr_opt *o = &table[i];
        size_t fs = type_size(o->type);
        CHECK_MSG(fs && o->offset + fs <= size, "%s.%s: offset %zu + %zu bytes lies outside the struct (%zu bytes)", name,
                  o->key, o->offset, fs, size);
        CHECK_MSG(fs && o->offset % fs == 0, "%s.%s: offset %zu is not aligned for its type", name, o->key, o->offset);
        CHECK_MSG(o->help && o->help[0] && !strchr(o->help, '\n'), "%s.%s has no one-line help", name, o->key);
        CHECK_MSG(mr_opt_find(table, o->key) == o, "%s.%s: key not unique (found row %d first)", name, o->key,
                  (int)(mr_opt_find(table, o->key) - table));
        for (int j = 0; j < i; j++) {
            const mr_opt *p = &table[j];
            bool overlap = o->offset < p->offset + type_size(p->type) && p->offset < o->offset + fs;
            CHECK_MSG(!overlap, "%s.%s and %s.%s write the same bytes (offsets %zu and %zu)", name, o->key, name, p->key,
                      o->offset, p->offset);
        }
        char def[64];
        mr_opt_format(o, macro, def, sizeof def);
        if (o->type == MR_OPT_ENUM) {
            int count = mr_opt_enum_count(o);
            CHECK_MSG(count > 0, "%s.%s: an enum without names", name, o->key);
            CHECK_MSG(o->def == (int)o->def && o->def >= 0 && o->def < count,
                      "%s.%s: default %g is not one of its %d names", name, o->key, o->def, count);
            for (int k = 0; k < count; k++) {
                CHECK_MSG(mr_opt_enum_value(o, o->names[k]) == k, "%s.%s: name '%s' is not unique", name, o->key,
                          o->names[k]);
                CHECK_MSG(try_set(name, o, macro, size, o->names[k]), "%s.%s refused its own name '%s'", name, o->key,
                          o->names[k]);
            }
            CHECK_MSG(!try_set(name, o, macro, size, "no-such-name"), "%s.%s accepted an unknown name", name, o->key);
            /* Cycling visits every name once and comes back. */
            int v = (int)o->def, seen = 0;
            for (int k = 0; k < count; k++) {
                seen |= 1 << v;
                v = mr_opt_enum_next(o, v);
            }
            CHECK_MSG(v == (int)o->def && seen == (1 << count) - 1, "%s.%s: cycling does not visit the %d names", name,
                      o->key, count);
        } else if (o->type == MR_OPT_BOOL) {
            CHECK_MSG(o->def == 0 || o->def == 1, "%s.%s: bool default %g", name, o->key, o->def);
            CHECK_MSG(try_set(name, o, macro, size, "1") && !try_set(name, o, macro, size, "maybe"),
                      "%s.%s: a bool must take 1 and refuse 'maybe'", name, o->key);
        } else {
            bool in = o->def >= o->lo && o->def <= o->hi;
            bool automatic = ((o->flags & MR_OPT_ZERO_AUTO) && o->def == 0) || ((o->flags & MR_OPT_NEG_AUTO) && o->def < 0);
            CHECK_MSG(o->lo <= o->hi, "%s.%s: empty range [%g, %g]", name, o->key, o->lo, o->hi);
            CHECK_MSG(in || automatic, "%s.%s: default %g outside its range [%g, %g]", name, o->key, o->def, o->lo,
                      o->hi);
            char t[64];
            if (o->type == MR_OPT_INT) {
                CHECK_MSG(o->lo == (long)o->lo && o->hi == (long)o->hi && o->def == (long)o->def,
                          "%s.%s: a whole-number row with fractional range or default", name, o->key);
                const long probe[4] = {(long)o->lo, (long)o->hi, (long)o->lo - 1, (long)o->hi + 1};
                for (int k = 0; k < 4; k++) {
                    snprintf(t, sizeof t, "%ld", probe[k]);
                    CHECK_MSG(try_set(name, o, macro, size, t) == (k < 2), "%s.%s: '%s' %s (range [%g, %g])", name,
                              o->key, t, k < 2 ? "refused" : "accepted", o->lo, o->hi);
                }
                CHECK_MSG(!try_set(name, o, macro, size, "1.5"), "%s.%s accepted a fraction", name, o->key);
            } else {
                /* The bounds and the nearest doubles outside them. */
                const double probe[4] = {o->lo, o->hi, nextafter(o->lo, -INFINITY), nextafter(o->hi, INFINITY)};
                for (int k = 0; k < 4; k++) {
                    snprintf(t, sizeof t, "%.17g", probe[k]);
                    CHECK_MSG(try_set(name, o, macro, size, t) == (k < 2), "%s.%s: '%s' %s (range [%g, %g])", name,
                              o->key, t, k < 2 ? "refused" : "accepted", o->lo, o->hi);
                }
                CHECK_MSG(!try_set(name, o, macro, size, "nan") && !try_set(name, o, macro, size, "1x"),
                          "%s.%s accepted 'nan' or '1x'", name, o->key);
            }
            CHECK_MSG(!try_set(name, o, macro, size, ""), "%s.%s accepted an empty value", name, o->key);
        }
        if (o->flags & MR_OPT_ZERO_DEFAULT) zero_default_row(name, o, size, macro);
        /* The default, formatted from the macro's struct, reads back to the same bytes. */
        unsigned char a[1024];
        memcpy(a, macro, size);
        mr_error e = {0};
        bool back = o->type == MR_OPT_ENUM || o->type == MR_OPT_BOOL ||
                    !(((o->flags & MR_OPT_ZERO_AUTO) && o->def == 0) || ((o->flags & MR_OPT_NEG_AUTO) && o->def < 0));
        if (back && (o->flags & MR_OPT_ZERO_DEFAULT)) {
            /* The default given by hand is the default the 0 stands for. */
            bool ok = mr_opt_set_row(o, a, def, &e);
            CHECK_MSG(ok && mr_opt_get(o, a) == mr_opt_get(o, macro), "%s.%s: the default '%s' reads back as %g (%s)",
                      name, o->key, def, mr_opt_get(o, a), e.msg);
        } else if (back) {
            bool ok = mr_opt_set_row(o, a, o->type == MR_OPT_BOOL ? (o->def ? "1" : "0") : def, &e);
            CHECK_MSG(ok && memcmp(a, macro, size) == 0, "%s.%s: the default '%s' does not read back (%s)", name, o->key,
                      def, e.msg);
        }
    }
    /* mr_opt_defaults gives the macro's value in every field the table names,
     * whatever was there before. */
    unsigned char d[1024];
    memset(d, 0xA5, size);
    mr_opt_defaults(table, d);
    for (const mr_opt *o = table; o->key; o++) {
        char got[64], want[64];
        mr_opt_format(o, d, got, sizeof got);
        mr_opt_format(o, macro, want, sizeof want);
        CHECK_MSG(memcmp(d + o->offset, (const char *)macro + o->offset, type_size(o->type)) == 0,
                  "%s.%s: mr_opt_defaults gives %s, the DEFAULTS macro %s (read through the row; the fields differ)",
                  name, o->key, got, want);
    }
}

/* Which field each option drives and what it accepts (its range, or its
 * names in value order): written here a second time on purpose, as the
 * command line's contract, so that a row pointing at the wrong field or a
 * range off by one fails. */
typedef struct expect {
    const char *key;
    size_t offset;
    double lo, hi;     /* numbers */
    const char *names; /* enums: space-separated */
} expect;

static void check_rows(const char *name, const mr_opt *table, const expect *ex, int n) {
    CHECK_MSG(mr_opt_count(table) == n, "%s has %d rows, expected %d", name, mr_opt_count(table), n);
    for (int i = 0; i < n; i++) {
        const mr_opt *o = mr_opt_find(table, ex[i].key);
        CHECK_MSG(o, "%s has no row '%s'", name, ex[i].key);
        if (!o) continue;
        CHECK_MSG(o->offset == ex[i].offset, "%s.%s drives the field at offset %zu, expected %zu", name, ex[i].key,
                  o->offset, ex[i].offset);
        if (o->type == MR_OPT_ENUM) {
            char got[256] = "";
            for (int k = 0; k < mr_opt_enum_count(o); k++)
                snprintf(got + strlen(got), sizeof got - strlen(got), "%s%s", k ? " " : "", o->names[k]);
            CHECK_MSG(ex[i].names && strcmp(got, ex[i].names) == 0, "%s.%s names '%s', expected '%s'", name, ex[i].key,
                      got, ex[i].names ? ex[i].names : "(not an enum)");
        } else if (o->type != MR_OPT_BOOL) {
            CHECK_MSG(o->lo == ex[i].lo && o->hi == ex[i].hi, "%s.%s accepts [%g, %g], expected [%g, %g]", name,
                      ex[i].key, o->lo, o->hi, ex[i].lo, ex[i].hi);
        }
    }
}

static void test_tables(void) {
    const mr_ao_params ao = MR_AO_DEFAULTS;
    const mr_ghost_params gh = MR_GHOST_DEFAULTS;
    const mr_view_settings vs = MR_VIEW_SETTINGS_DEFAULTS;
    walk_table("mr_ao_opts", mr_ao_opts, sizeof ao, &ao);
    walk_table("mr_ghost_opts", mr_ghost_opts, sizeof gh, &gh);
    const mr_shadow_params sh = MR_SHADOW_DEFAULTS;
    walk_table("mr_shadow_opts", mr_shadow_opts, sizeof sh, &sh);
    walk_table("mr_view_settings_opts", mr_view_settings_opts, sizeof vs, &vs);
    const mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    const mr_filter_params fp = MR_FILTER_DEFAULTS;
    walk_table("mr_detector_opts", mr_detector_opts, sizeof dp, &dp);
    walk_table("mr_filter_opts", mr_filter_opts, sizeof fp, &fp);
    const mr_synth_params syp = MR_SYNTH_DEFAULTS;
    const mr_synth_cad_params scp = MR_SYNTH_CAD_DEFAULTS;
    const mr_recorder_params rcp = MR_RECORDER_DEFAULTS;
    walk_table("mr_synth_opts", mr_synth_opts, sizeof syp, &syp);
    walk_table("mr_synth_cad_opts", mr_synth_cad_opts, sizeof scp, &scp);
    walk_table("mr_recorder_opts", mr_recorder_opts, sizeof rcp, &rcp);
    const mr_map_params mpp = MR_MAP_DEFAULTS;
    walk_table("mr_map_opts", mr_map_opts, sizeof mpp, &mpp);
    const mr_frame_params frp = MR_FRAME_DEFAULTS;
    walk_table("mr_frame_opts", mr_frame_opts, sizeof frp, &frp);
    const mr_draw_params dr = MR_DRAW_DEFAULTS;
    walk_table("mr_draw_opts", mr_draw_opts, sizeof dr, &dr);
    const mr_gt_params gt = MR_GT_DEFAULTS;
    walk_table("mr_gt_opts", mr_gt_opts, sizeof gt, &gt);
    const mr_bench_ao_params bao = {MR_BENCH_AO_DEFAULTS};
    const mr_bench_frame_params bfr = {MR_BENCH_FRAME_DEFAULTS};
    const mr_bench_ghost_params bgh = {MR_BENCH_GHOST_DEFAULTS};
    const mr_bench_scene_params bsc = {MR_BENCH_SCENE_DEFAULTS};
    const mr_bench_tracking_params btr = {MR_BENCH_TRACKING_DEFAULTS};
    walk_table("mr_bench_ao_opts", mr_bench_ao_opts, sizeof bao, &bao);
    walk_table("mr_bench_frame_opts", mr_bench_frame_opts, sizeof bfr, &bfr);
    walk_table("mr_bench_ghost_opts", mr_bench_ghost_opts, sizeof bgh, &bgh);
    walk_table("mr_bench_scene_opts", mr_bench_scene_opts, sizeof bsc, &bsc);
    walk_table("mr_bench_tracking_opts", mr_bench_tracking_opts, sizeof btr, &btr);
    const mr_bench_shadows_params bsh = {MR_BENCH_SHADOWS_DEFAULTS};
    const mr_bench_multiview_params bmv = {MR_BENCH_MULTIVIEW_DEFAULTS};
    const mr_bench_map_params bmp = {MR_BENCH_MAP_DEFAULTS};
    walk_table("mr_bench_shadows_opts", mr_bench_shadows_opts, sizeof bsh, &bsh);
    walk_table("mr_bench_multiview_opts", mr_bench_multiview_opts, sizeof bmv, &bmv);
    walk_table("mr_bench_map_opts", mr_bench_map_opts, sizeof bmp, &bmp);
    const mr_board_calib_params bcp = {.min_tags = 0};
    const mr_triangulate_params trp = MR_TRIANGULATE_DEFAULTS;
    const mr_synth_recording_params srp = {MR_SYNTH_RECORDING_DEFAULTS};
    walk_table("mr_board_calib_opts", mr_board_calib_opts, sizeof bcp, &bcp);
    walk_table("mr_triangulate_opts", mr_triangulate_opts, sizeof trp, &trp);
    walk_table("mr_synth_recording_opts", mr_synth_recording_opts, sizeof srp, &srp);
    /* The study's and the export's own tables (their rows are pinned by
     * test_study and test_export). */
    const mr_study_stimuli_params sst = MR_STUDY_STIMULI_DEFAULTS;
    const mr_study_plan_params spl = MR_STUDY_PLAN_DEFAULTS;
    const mr_study_analyze_params san = MR_STUDY_ANALYZE_DEFAULTS;
    const mr_export_params exp = MR_EXPORT_DEFAULTS;
    walk_table("mr_study_stimuli_opts", mr_study_stimuli_opts, sizeof sst, &sst);
    walk_table("mr_study_plan_opts", mr_study_plan_opts, sizeof spl, &spl);
    walk_table("mr_study_analyze_opts", mr_study_analyze_opts, sizeof san, &san);
    walk_table("mr_export_opts", mr_export_opts, sizeof exp, &exp);
    const mr_batch_replay_params rp = MR_BATCH_REPLAY_DEFAULTS;
    walk_table("mr_batch_replay_opts", mr_batch_replay_opts, sizeof rp, &rp);
    const mr_sheet_params shp = MR_SHEET_DEFAULTS;
    walk_table("mr_sheet_opts", mr_sheet_opts, sizeof shp, &shp);

#define E(t, k, f, names) {k, offsetof(t, f), 0, 0, names}
#define N(t, k, f, lo, hi) {k, offsetof(t, f), lo, hi, NULL}
    const expect ex_ao[] = {
        E(mr_ao_params, "", method, "none scheer crytek filion hbao alchemy gtao bitmask scheer-gt scheer-bm"),
        E(mr_ao_params, "radius-mode", radius_mode, "screen view"),
        N(mr_ao_params, "radius", radius, 1e-30, 1e30),
        N(mr_ao_params, "screen-radius", screen_radius, 1e-6, 10),
        N(mr_ao_params, "samples", samples, 1, MR_AO_MAX_SAMPLES),
        E(mr_ao_params, "kernel", kernel, "uniform stratified latin poisson"),
        N(mr_ao_params, "rmin", r_min, 0, 1),
        N(mr_ao_params, "rmax", r_max, 1e-3, 1),
        N(mr_ao_params, "radii", radii, 1, MR_AO_MAX_RADII),
        N(mr_ao_params, "c", c, 0, 1e7),
        N(mr_ao_params, "bias", bias, 0, 0.5),
        N(mr_ao_params, "strength", strength, 0.01, 10),
        N(mr_ao_params, "blur", blur_radius, 0, 32),
        N(mr_ao_params, "half", half_res, 0, 1),
        N(mr_ao_params, "positions", positions, 0, 1),
        E(mr_ao_params, "mask", mask, "off on standalone"),
        N(mr_ao_params, "mask-strength", mask_strength, 1e-3, 1),
        N(mr_ao_params, "thickness", thickness, 1e-3, 100), /* issue 18 */
        N(mr_ao_params, "temporal", temporal, 0, 1),
        E(mr_ao_params, "noise", noise, "pixel world"),
        N(mr_ao_params, "mips", mips, 0, 1), /* issue 18 (lane ao) */
        N(mr_ao_params, "deinterleave", deinterleave, 0, 1), /* issue 18 (lane deint) */
    };
    /* multi-view rig (no prefix) */
    const mr_rig_params rg = MR_RIG_DEFAULTS;
    walk_table("mr_rig_opts", mr_rig_opts, sizeof rg, &rg);
    const expect ex_rg[] = {
        N(mr_rig_params, "views", views, 1, MR_RIG_MAX_VIEWS),
        N(mr_rig_params, "view-cone", cone_deg, 0, 179),
        N(mr_rig_params, "view-fov", fov_deg, 0.01, 179),
        N(mr_rig_params, "focal-distance", focal_distance, 1e-30, 1e30),
        N(mr_rig_params, "views-per-view-work", per_view_work, 0, 1), /* issue 14 */
    };
    check_rows("mr_rig_opts", mr_rig_opts, ex_rg, (int)(sizeof ex_rg / sizeof ex_rg[0]));
    const expect ex_gh[] = {
        E(mr_ghost_params, "", mode, "off alpha g0 adaptive"),
        E(mr_ghost_params, "importance", importance, "auto curvature saliency"),
        E(mr_ghost_params, "saliency", saliency, "mipmap gauss"),
        N(mr_ghost_params, "opacity", opacity, 0, 1),
        N(mr_ghost_params, "curv-scale", curv_scale, 0, 1e3),
        N(mr_ghost_params, "curv-bias", curv_bias, -1, 1),
        N(mr_ghost_params, "tc-min", tc_minimal, 0, 4),
        N(mr_ghost_params, "gamma", gamma, 0, 100),
        N(mr_ghost_params, "tc-sil", tc_silhouette, 0, 4),
    };
    const expect ex_sh[] = {
        E(mr_shadow_params, "", method, "off hard pcf pcss bp groundtruth"),
        N(mr_shadow_params, "map-size", map_size, 64, 8192),
        N(mr_shadow_params, "taps", taps, 1, MR_SHADOW_MAX_TAPS),
        N(mr_shadow_params, "pcf-radius", pcf_radius, 0.01f, 64),
        N(mr_shadow_params, "samples", gt_samples, 1, 1024),
        N(mr_shadow_params, "light-scale", light_scale, 1e-6f, 1e6f),
        N(mr_shadow_params, "cascades", cascades, 0, MR_SHADOW_MAX_CASCADES),
    };
    const expect ex_vs[] = {
        N(mr_view_settings, "alpha", alpha, 0, 1),
        N(mr_view_settings, "show_video", show_video, 0, 1),
        N(mr_view_settings, "hide_hidden_layer", hide_hidden, 0, 1),
        N(mr_view_settings, "ao_on", ao_on, 0, 1),
        N(mr_view_settings, "ghost_on", ghost_on, 0, 1),
        N(mr_view_settings, "shadows_on", shadows_on, 0, 1),
        E(mr_view_settings, "ao", ao, "none scheer crytek filion hbao alchemy gtao bitmask scheer-gt scheer-bm"),
        E(mr_view_settings, "ghost", ghost, "off alpha g0 adaptive"),
        E(mr_view_settings, "shadows", shadows, "off hard pcf pcss bp"),
    };
    const expect ex_dt[] = {
        N(mr_detector_params, "decimate", decimate, 1, 16),
        N(mr_detector_params, "threads", threads, 1, 64),
        N(mr_detector_params, "refine-edges", refine_edges, 0, 1),
        N(mr_detector_params, "sharpening", sharpening, 0, 10),
    };
    const expect ex_fi[] = {
        N(mr_filter_params, "min-cutoff", min_cutoff, 1e-3, 100),
        N(mr_filter_params, "beta", beta, 1e-6, 1000),
        N(mr_filter_params, "d-cutoff", d_cutoff, 1e-3, 100),
        N(mr_filter_params, "rot-min-cutoff", rot_min_cutoff, 1e-3, 100),
        N(mr_filter_params, "rot-beta", rot_beta, 1e-6, 1000),
        N(mr_filter_params, "jump-dist", jump_dist, 1e-6, 1e6),
        N(mr_filter_params, "jump-deg", jump_deg, 1e-3, 180),
        N(mr_filter_params, "max-gap", max_gap_s, 1e-3, 3600),
    };
    const expect ex_dr[] = {
        N(mr_draw_params, "cull", no_cull, 0, 1),
        N(mr_draw_params, "batch", no_batch, 0, 1),
        N(mr_draw_params, "instancing", no_instancing, 0, 1),
        N(mr_draw_params, "lod-tolerance", lod_tolerance, 1e-12, 1e12),
        N(mr_draw_params, "lod-pixels", lod_pixels, 1e-3, 1e4),
        N(mr_draw_params, "occlusion", occlusion, 0, 1),
        N(mr_draw_params, "occlusion-auto", occlusion_auto, 0, 1), /* issue 17 */
        /* issue 17 (lane meshlet) */
        N(mr_draw_params, "cluster-cull", no_cluster_cull, 0, 1),
        N(mr_draw_params, "cluster-triangles", cluster_triangles, 64, 1 << 30),
        N(mr_draw_params, "cluster-cone", no_cluster_cone, 0, 1), /* issue 17 (lane cluster): default on */
        N(mr_draw_params, "cluster-occlusion", no_cluster_occlusion, 0, 1), /* issue 17 (lane cluster) */
    };
    const expect ex_mp[] = {
        N(mr_map_params, "tag-size", tag_size, 1e-9, 1e9),
        N(mr_map_params, "loss", loss_px, 1e-3, 1e3),
        N(mr_map_params, "refine-intrinsics", refine_intrinsics, 0, 1),
        N(mr_map_params, "chain", no_adjust, 0, 1),
    };
    const expect ex_bsh[] = {
        N(mr_bench_shadows_params, "frames", frames, 1, 64),
        N(mr_bench_shadows_params, "rays", rays, 1, 1 << 16),
        N(mr_bench_shadows_params, "first", first, 0, MR_SHADOW_SUITE_COUNT - 1),
        N(mr_bench_shadows_params, "count", count, 1, MR_SHADOW_SUITE_COUNT),
        N(mr_bench_shadows_params, "views", views, 1, 2),
    };
    const expect ex_bmv[] = {
        N(mr_bench_multiview_params, "frames", frames, 1, 64),
        N(mr_bench_multiview_params, "rays", rays, 1, 1 << 16),
        N(mr_bench_multiview_params, "quick", quick, 0, 1),
        N(mr_bench_multiview_params, "shared-only", shared_only, 0, 1), /* issue 14 */
    };
    const expect ex_bmp[] = {
        N(mr_bench_map_params, "seeds", seeds, 1, 1000),
        N(mr_bench_map_params, "max-photos", max_photos, 10, 200),
        N(mr_bench_map_params, "noise", noise_px, 0, 10),
        N(mr_bench_map_params, "misdetect", misdetect, 0, 1),
    };
    const expect ex_bcp[] = {N(mr_board_calib_params, "min-tags", min_tags, 1, 10000)};
    const expect ex_trp[] = {N(mr_triangulate_params, "tap-sigma", tap_sigma_px, 1e-3, 100),
                             N(mr_triangulate_params, "min-angle", min_angle_deg, 1e-3, 90)};
    const expect ex_srp[] = {
        N(mr_synth_recording_params, "frames", frames, 1, 100000),
        N(mr_synth_recording_params, "noise", noise, 0, 100),
        N(mr_synth_recording_params, "motion-blur", motion_blur, 1, 16),
        N(mr_synth_recording_params, "shutter", shutter, 1, 100000),
        N(mr_synth_recording_params, "exposure", exposure, 0, 0.9),
        N(mr_synth_recording_params, "jpeg", jpeg_quality, 1, 100),
        N(mr_synth_recording_params, "fps", fps, 0.1, 1000),
    };
    const expect ex_frp[] = {N(mr_frame_params, "alpha", alpha, 0, 1), N(mr_frame_params, "hide-hidden", hide_hidden_layer, 0, 1)};
    const expect ex_gt[] = {N(mr_gt_params, "rays", rays, 1, 1 << 20)};
    const expect ex_bao[] = {
        N(mr_bench_ao_params, "frames", frames, 1, 64),
        N(mr_bench_ao_params, "rays", rays, 1, 1 << 20),
        N(mr_bench_ao_params, "radius", radius, 1e-30, 1e30),
        N(mr_bench_ao_params, "screen-radius", screen_radius, 1e-4, 1),
        N(mr_bench_ao_params, "quick", quick, 0, 1),
    };
    const expect ex_bfr[] = {N(mr_bench_frame_params, "frames", frames, 1, 100000),
                             N(mr_bench_frame_params, "no-video", no_video, 0, 1)};
    const expect ex_bgh[] = {N(mr_bench_ghost_params, "frames", frames, 1, 100000),
                             N(mr_bench_ghost_params, "view", view, 0, MR_DEMO_VIEWS - 1)};
    const expect ex_bsc[] = {N(mr_bench_scene_params, "frames", frames, 1, 1000),
                             /* issue 17 (lane bench) */
                             N(mr_bench_scene_params, "full-detail-frames", full_frames, 0, 1000)};
    const expect ex_btr[] = {
        N(mr_bench_tracking_params, "frames", max_frames, 1, 1 << 30),
        N(mr_bench_tracking_params, "quick", quick, 0, 1),
        N(mr_bench_tracking_params, "min-cutoff", min_cutoff, 1e-3, 100),
        N(mr_bench_tracking_params, "beta", beta, 1e-6, 1000),
    };
    const expect ex_rp[] = {
        N(mr_batch_replay_params, "alpha", frame.alpha, 0, 1),
        N(mr_batch_replay_params, "every", every, 1, 1 << 30),
        N(mr_batch_replay_params, "from", from, 0, 2147483647),
        N(mr_batch_replay_params, "to", to, 0, 2147483647),
        N(mr_batch_replay_params, "raw", raw, 0, 1),
    };
#undef E
#undef N
#define ROWS(t, ex) check_rows(#t, t, ex, (int)(sizeof ex / sizeof ex[0]))
    ROWS(mr_gt_opts, ex_gt);
    ROWS(mr_draw_opts, ex_dr);
    ROWS(mr_frame_opts, ex_frp);
    ROWS(mr_map_opts, ex_mp);
    ROWS(mr_bench_shadows_opts, ex_bsh);
    ROWS(mr_bench_multiview_opts, ex_bmv);
    ROWS(mr_bench_map_opts, ex_bmp);
    ROWS(mr_board_calib_opts, ex_bcp);
    ROWS(mr_triangulate_opts, ex_trp);
    ROWS(mr_synth_recording_opts, ex_srp);
    /* The negated switches: the option on is the field off, both ways. */
    {
        mr_draw_params d = MR_DRAW_DEFAULTS;
        mr_error e = {0};
        CHECK(mr_opt_set(mr_draw_opts, &d, "cull", "off", &e) && d.no_cull && mr_opt_get(mr_opt_find(mr_draw_opts, "cull"), &d) == 0);
        CHECK(mr_opt_set(mr_draw_opts, &d, "cull", "on", &e) && !d.no_cull && mr_opt_get(mr_opt_find(mr_draw_opts, "cull"), &d) == 1);
        CHECK(mr_opt_set(mr_draw_opts, &d, "occlusion", "on", &e) && d.occlusion);
        CHECK(!mr_opt_set(mr_draw_opts, &d, "batch", "maybe", &e) && strstr(e.msg, "on or off"));
    }
    ROWS(mr_batch_replay_opts, ex_rp);
    ROWS(mr_bench_ao_opts, ex_bao);
    ROWS(mr_bench_frame_opts, ex_bfr);
    ROWS(mr_bench_ghost_opts, ex_bgh);
    ROWS(mr_bench_scene_opts, ex_bsc);
    ROWS(mr_bench_tracking_opts, ex_btr);
#undef ROWS
    check_rows("mr_detector_opts", mr_detector_opts, ex_dt, (int)(sizeof ex_dt / sizeof ex_dt[0]));
    check_rows("mr_filter_opts", mr_filter_opts, ex_fi, (int)(sizeof ex_fi / sizeof ex_fi[0]));
    /* The defaults the 0s stand for, written a second time as the contract:
     * the same as the detector's and the filter's own (test_track);
     * decimate's 0 is auto, the tracker's adaptive decimation. */
    const double want_dt[] = {0.0, 1, 1, 0.25}, want_fi[] = {0.5, 2.0, 1.0, 0.5, 1.0, 0.5, 20.0, 0.5};
    for (int i = 0; i < 4; i++)
        CHECK_MSG(mr_detector_opts[i].def == want_dt[i], "mr_detector_opts.%s: default %g, expected %g",
                  mr_detector_opts[i].key, mr_detector_opts[i].def, want_dt[i]);
    for (int i = 0; i < 8; i++)
        CHECK_MSG(mr_filter_opts[i].def == want_fi[i], "mr_filter_opts.%s: default %g, expected %g",
                  mr_filter_opts[i].key, mr_filter_opts[i].def, want_fi[i]);
    check_rows("mr_ao_opts", mr_ao_opts, ex_ao, (int)(sizeof ex_ao / sizeof ex_ao[0]));
    check_rows("mr_ghost_opts", mr_ghost_opts, ex_gh, (int)(sizeof ex_gh / sizeof ex_gh[0]));
    check_rows("mr_shadow_opts", mr_shadow_opts, ex_sh, (int)(sizeof ex_sh / sizeof ex_sh[0]));
    CHECK_MSG(mr_opt_enum_count(mr_opt_find(mr_shadow_opts, "")) == MR_SHADOW_METHOD_COUNT,
              "the shadow method row does not name every method");
    check_rows("mr_view_settings_opts", mr_view_settings_opts, ex_vs, (int)(sizeof ex_vs / sizeof ex_vs[0]));
    /* The enums' names in their value order, for every value. */
    const mr_opt *m = mr_opt_find(mr_ao_opts, "");
    CHECK_MSG(m && mr_opt_enum_count(m) == MR_AO_METHOD_COUNT, "the AO method row does not name every method");
    const mr_opt *g = mr_opt_find(mr_ghost_opts, "");
    CHECK_MSG(g && mr_opt_enum_count(g) == MR_GHOST_ADAPTIVE + 1, "the ghost mode row does not name every mode");
    CHECK_MSG(mr_opt_find(mr_view_settings_opts, "ao")->names == mr_ao_method_names &&
                  mr_opt_find(mr_view_settings_opts, "ghost")->names == mr_ghost_mode_names,
              "the view's settings do not share the renderer's names");
    /* The view's shadow methods: the renderer's, in its order, less the ground truth. */
    const mr_opt *vs_sh = mr_opt_find(mr_view_settings_opts, "shadows");
    bool same_names = vs_sh && mr_opt_enum_count(vs_sh) == MR_SHADOW_BP + 1;
    for (int i = 0; same_names && i <= MR_SHADOW_BP; i++) same_names = strcmp(vs_sh->names[i], mr_shadow_method_names[i]) == 0;
    CHECK_MSG(same_names, "the view's shadow methods are not the renderer's off..bp");
}

/* The facility itself, on a small struct of its own. */
typedef struct toy {
    int n;
    double d;
    float f;
    bool b;
    int e;
    int z;
} toy;
static const char *const k_toy_names[] = {"red", "green", "blue", NULL};
static const mr_opt k_toy[] = {
    {"n", MR_OPT_INT, offsetof(toy, n), -3, 7, 2, NULL, "a count", 0},
    {"d", MR_OPT_DOUBLE, offsetof(toy, d), 0, 1, 0, NULL, "a fraction", MR_OPT_ZERO_AUTO},
    {"f", MR_OPT_FLOAT, offsetof(toy, f), -1, 1, 0.25, NULL, "a float", 0},
    {"b", MR_OPT_BOOL, offsetof(toy, b), 0, 1, 1, NULL, "a flag", 0},
    {"e", MR_OPT_ENUM, offsetof(toy, e), 0, 0, 1, k_toy_names, "a colour", 0},
    {"z", MR_OPT_INT, offsetof(toy, z), 0, 3, 2, NULL, "0 = default 2, < 0 = off", MR_OPT_ZERO_DEFAULT},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

static void test_facility(void) {
    toy t;
    memset(&t, 0x5A, sizeof t);
    mr_opt_defaults(k_toy, &t);
    CHECK_MSG(t.n == 2 && t.d == 0 && t.f == 0.25f && t.b && t.e == 1, "defaults: n %d d %g f %g b %d e %d", t.n, t.d,
              t.f, t.b, t.e);
    mr_error e = {0};
    /* The zero-default row: the field keeps 0 = default and < 0 = off. */
    const mr_opt *z = mr_opt_find(k_toy, "z");
    CHECK_MSG(t.z == 0 && mr_opt_get(z, &t) == 2, "zero-default: defaults give field %d reading %g", t.z,
              mr_opt_get(z, &t));
    CHECK_MSG(mr_opt_set(k_toy, &t, "z", "0", &e) && t.z < 0 && mr_opt_get(z, &t) == 0,
              "zero-default: the user's 0 gives field %d reading %g (want < 0, 0)", t.z, mr_opt_get(z, &t));
    char zs[32];
    mr_opt_format(z, &t, zs, sizeof zs);
    CHECK_MSG(strcmp(zs, "0") == 0, "zero-default: 'off' formats as '%s'", zs);
    CHECK_MSG(mr_opt_set(k_toy, &t, "z", "3", &e) && t.z == 3 && mr_opt_get(z, &t) == 3, "zero-default: 3 gives %d",
              t.z);
    CHECK_MSG(!mr_opt_set(k_toy, &t, "z", "-1", &e) && t.z == 3, "zero-default: -1 accepted");
    mr_opt_describe(z, zs, sizeof zs);
    CHECK_MSG(strcmp(zs, "0..3 (default 2)") == 0, "describe z: '%s'", zs);
    t.z = 0;
    CHECK_MSG(mr_opt_set(k_toy, &t, "n", "-3", &e) && t.n == -3, "n -3: %s", e.msg);
    CHECK_MSG(!mr_opt_set(k_toy, &t, "n", "8", &e) && t.n == -3, "n 8 accepted or changed n");
    CHECK_MSG(strcmp(e.msg, "n must be a whole number in [-3, 7], got '8'") == 0, "int message: '%s'", e.msg);
    CHECK_MSG(!mr_opt_set(k_toy, &t, "f", "1.5", &e), "f 1.5 accepted");
    CHECK_MSG(strcmp(e.msg, "f must be a number in [-1, 1], got '1.5'") == 0, "number message: '%s'", e.msg);
    CHECK_MSG(!mr_opt_set(k_toy, &t, "e", "pink", &e), "e pink accepted");
    CHECK_MSG(strcmp(e.msg, "e must be red, green or blue, got 'pink'") == 0, "enum message: '%s'", e.msg);
    CHECK_MSG(!mr_opt_set(k_toy, &t, "zz", "1", &e) && strstr(e.msg, "zz"), "an unknown key: '%s'", e.msg);
    CHECK_MSG(mr_opt_set(k_toy, &t, "e", "blue", &e) && t.e == 2 && mr_opt_get(mr_opt_find(k_toy, "e"), &t) == 2,
              "e blue: %d", t.e);
    CHECK_MSG(mr_opt_enum_next(mr_opt_find(k_toy, "e"), 2) == 0, "cycling after the last name is not the first");
    CHECK_MSG(mr_opt_set(k_toy, &t, "b", "off", &e) && !t.b, "b off");
    CHECK_MSG(mr_opt_set(k_toy, &t, "d", "0.125", &e) && t.d == 0.125, "d 0.125");
    char s[128];
    mr_opt_format(mr_opt_find(k_toy, "e"), &t, s, sizeof s);
    CHECK_MSG(strcmp(s, "blue") == 0, "format of e: '%s'", s);
    mr_opt_describe(mr_opt_find(k_toy, "n"), s, sizeof s);
    CHECK_MSG(strcmp(s, "-3..7 (default 2)") == 0, "describe n: '%s'", s);
    mr_opt_describe(mr_opt_find(k_toy, "d"), s, sizeof s);
    CHECK_MSG(strcmp(s, "in [0, 1] (default auto)") == 0, "describe d: '%s'", s);
    mr_opt_describe(mr_opt_find(k_toy, "e"), s, sizeof s);
    CHECK_MSG(strcmp(s, "red, green or blue (default green)") == 0, "describe e: '%s'", s);
    /* JSON round trip: every row comes back as it went out. */
    cJSON *j = cJSON_CreateObject();
    CHECK(mr_opt_to_json(k_toy, &t, j));
    toy u;
    mr_opt_defaults(k_toy, &u);
    for (const mr_opt *o = k_toy; o->key; o++) {
        CHECK_MSG(mr_opt_set_json(o, &u, cJSON_GetObjectItemCaseSensitive(j, o->key), &e), "json %s: %s", o->key, e.msg);
        CHECK_MSG(mr_opt_get(o, &u) == mr_opt_get(o, &t), "json %s: %g back, %g out", o->key, mr_opt_get(o, &u),
                  mr_opt_get(o, &t));
    }
    cJSON *bad = cJSON_CreateString("3");
    CHECK_MSG(!mr_opt_set_json(mr_opt_find(k_toy, "n"), &u, bad, &e) && strncmp(e.msg, "n ", 2) == 0,
              "json: a string for a number accepted ('%s')", e.msg);
    cJSON_Delete(bad);
    cJSON_Delete(j);
}

/* Counts with k / M (factory --triangles, bench scene --sizes). */
static void test_count_prefix(void) {
    double v = 0;
    const char *end = NULL;
    CHECK(mr_cli_count_prefix("5M,200k", &v, &end) && v == 5e6 && *end == ',');
    CHECK(mr_cli_count_prefix(end + 1, &v, &end) && v == 2e5 && *end == 0);
    CHECK(mr_cli_count_prefix("1e6", &v, &end) && v == 1e6 && *end == 0);
    CHECK(mr_cli_count_prefix("12x", &v, &end) && v == 12 && *end == 'x');
    CHECK(!mr_cli_count_prefix("M5", &v, &end));
    double list[3];
    CHECK(mr_cli_counts("1M,5M,20M", 1e4, 1e9, list, 3) == 3 && list[0] == 1e6 && list[2] == 2e7);
    CHECK(mr_cli_counts("200k", 1, 1e11, list, 1) == 1 && list[0] == 2e5);
    CHECK(mr_cli_counts("1M,5M", 1e4, 1e9, list, 1) == -1); /* more than max */
    CHECK(mr_cli_counts("1M,", 1e4, 1e9, list, 3) == -1);
    CHECK(mr_cli_counts("5k", 1e4, 1e9, list, 3) == -1);     /* under lo */
    CHECK(mr_cli_counts("5Mx", 1e4, 1e9, list, 3) == -1);
}

int main(void) {
    test_count_prefix();
    test_facility();
    test_tables();
    return mr_test_finish("test_options");
}
