/* The command line from declared option tables: mrcheck's subcommands parse
 * their arguments, print --help and report bad values here. */
#include "mr_core.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

static void print_row(const char *name, const char *arg, const char *help) {
    char left[96];
    snprintf(left, sizeof left, "--%s%s%s", name, arg ? " " : "", arg ? arg : "");
    printf("  %-24s %s\n", left, help);
}

/* The command-line name of a table row: prefix, or prefix-key; a table
 * without a prefix (the tracker's) names its rows by their keys. */
static void row_name(const mr_cli_table *t, const mr_opt *o, char *out, size_t n) {
    snprintf(out, n, "%s%s%s", t->prefix, t->prefix[0] && o->key[0] ? "-" : "", o->key);
}

static const char *row_arg(const mr_opt *o) {
    switch (o->type) {
    case MR_OPT_BOOL: return (o->flags & MR_OPT_ONOFF) ? "on|off" : NULL;
    case MR_OPT_ENUM: return "NAME";
    case MR_OPT_INT: return "N";
    default: return "X";
    }
}

static void print_table_row(const mr_cli_table *t, const mr_opt *o) {
    char name[64], desc[320], help[512];
    row_name(t, o, name, sizeof name);
    mr_opt_describe(o, desc, sizeof desc);
    const char *sep = o->type == MR_OPT_BOOL ? " " : "; ";
    if (!o->key[0] && t->extra) snprintf(help, sizeof help, "%s%s%s; or %s", o->help, sep, desc, t->extra);
    else snprintf(help, sizeof help, "%s%s%s", o->help, sep, desc);
    print_row(name, row_arg(o), help);
}

/* The options a planner uses first, then the research settings under their
 * own heading: a command's rows after MR_CLI_RESEARCH_ROWS, the rows of
 * research tables and MR_OPT_RESEARCH rows. */
static void print_usage(const char *usage, const mr_cli_opt *opts, const mr_cli_table *tables, int ntables) {
    printf("%s\n\noptions:\n", usage);
    const mr_cli_opt *o = opts;
    for (; o->name && o->name[0]; o++) print_row(o->name, o->arg, o->help);
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1) {
            bool any = o->name != NULL;
            for (int i = 0; i < ntables && !any; i++)
                for (const mr_opt *r = tables[i].table; r->key && !any; r++)
                    any = tables[i].research || (r->flags & MR_OPT_RESEARCH);
            if (!any) break;
            printf("\nresearch options:\n");
            for (o = o->name ? o + 1 : o; o->name; o++) print_row(o->name, o->arg, o->help);
        }
        for (int i = 0; i < ntables; i++)
            for (const mr_opt *r = tables[i].table; r->key; r++)
                if ((tables[i].research || (r->flags & MR_OPT_RESEARCH)) == (pass == 1)) print_table_row(&tables[i], r);
        if (pass == 0) printf("  %-24s %s\n", "--help", "show this help");
    }
}

bool mr_cli_table_given(const mr_cli_table *t, const char *key) {
    const mr_opt *o = mr_opt_find(t->table, key);
    return o && t->values[o - t->table] != NULL;
}

/* Finds --name among the table rows. */
static bool find_table_row(mr_cli_table *tables, int ntables, const char *name, size_t nlen, mr_cli_table **tab,
                           const mr_opt **row) {
    for (int i = 0; i < ntables; i++)
        for (const mr_opt *o = tables[i].table; o->key; o++) {
            char full[64];
            row_name(&tables[i], o, full, sizeof full);
            if (strlen(full) == nlen && strncmp(full, name, nlen) == 0) {
                *tab = &tables[i];
                *row = o;
                return true;
            }
        }
    return false;
}

/* Writes the given table values into their params; one line on error. */
static bool apply_tables(mr_cli_table *tables, int ntables) {
    for (int i = 0; i < ntables; i++) {
        mr_cli_table *t = &tables[i];
        for (const mr_opt *o = t->table; o->key; o++) {
            const char *v = t->values[o - t->table];
            bool extra_row = !o->key[0] && t->extra;
            if (!v) continue;
            if (extra_row && strcmp(v, t->extra) == 0) {
                t->extra_given = true;
                continue;
            }
            mr_error err = {0};
            if (mr_opt_set_row(o, t->params, v, &err)) continue;
            /* err.msg starts with the key: print the option's full name instead. */
            char name[64];
            row_name(t, o, name, sizeof name);
            const char *rest = err.msg + strlen(o->key), *got = extra_row ? strstr(rest, ", got '") : NULL;
            if (got)
                fprintf(stderr, "mrcheck: --%s%.*s (or %s)%s\n", name, (int)(got - rest), rest, t->extra, got);
            else fprintf(stderr, "mrcheck: --%s%s\n", name, rest);
            return false;
        }
    }
    return true;
}

bool mr_cli_parse(int argc, char **argv, int first, mr_cli_opt *opts, const char **pos, int max_pos, int *npos,
               const char *usage, bool *help_shown) {
    return mr_cli_parse_tables(argc, argv, first, opts, NULL, 0, pos, max_pos, npos, usage, help_shown);
}

bool mr_cli_parse_tables(int argc, char **argv, int first, mr_cli_opt *opts, mr_cli_table *tables, int ntables,
                      const char **pos, int max_pos, int *npos, const char *usage, bool *help_shown) {
    *help_shown = false;
    if (npos) *npos = 0;
    for (int i = 0; i < ntables; i++) {
        if (mr_opt_count(tables[i].table) > MR_CLI_TABLE_MAX) {
            fprintf(stderr, "mrcheck: the --%s table has more than %d rows\n", tables[i].prefix, MR_CLI_TABLE_MAX);
            return false;
        }
        tables[i].extra_given = false;
        memset(tables[i].values, 0, sizeof tables[i].values);
    }
    for (int i = first; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            print_usage(usage, opts, tables, ntables);
            *help_shown = true;
            return true;
        }
        if (strncmp(a, "--", 2) != 0) {
            if (!pos || !npos || *npos >= max_pos) {
                fprintf(stderr, "mrcheck: unexpected argument '%s' (see --help)\n", a);
                return false;
            }
            pos[(*npos)++] = a;
            continue;
        }
        const char *name = a + 2;
        const char *eq = strchr(name, '=');
        size_t nlen = eq ? (size_t)(eq - name) : strlen(name);
        mr_cli_opt *o = opts;
        for (; o->name; o++)
            if (o->name[0] && strlen(o->name) == nlen && strncmp(o->name, name, nlen) == 0) break;
        mr_cli_table *tab = NULL;
        const mr_opt *row = NULL;
        if (!o->name && !find_table_row(tables, ntables, name, nlen, &tab, &row)) {
            fprintf(stderr, "mrcheck: unknown option '--%.*s' (see --help)\n", (int)nlen, name);
            return false;
        }
        const char **slot = tab ? &tab->values[row - tab->table] : &o->value;
        const char *arg = tab ? row_arg(row) : o->arg;
        if (!arg) {
            if (eq) {
                fprintf(stderr, "mrcheck: option '--%.*s' takes no value\n", (int)nlen, name);
                return false;
            }
            *slot = "1";
        } else if (eq) {
            *slot = eq + 1;
        } else if (i + 1 < argc) {
            *slot = argv[++i];
        } else {
            fprintf(stderr, "mrcheck: option '--%.*s' needs a value (%s)\n", (int)nlen, name, arg);
            return false;
        }
    }
    return apply_tables(tables, ntables);
}

const char *mr_cli_get(const mr_cli_opt *opts, const char *name) {
    for (const mr_cli_opt *o = opts; o->name; o++)
        if (strcmp(o->name, name) == 0) return o->value;
    return NULL;
}

bool mr_cli_flag(const mr_cli_opt *opts, const char *name) { return mr_cli_get(opts, name) != NULL; }

/* Through a one-row option table, so the number rules and the message are
 * those of every table option. */
bool mr_cli_double(const char *opt, const char *s, double lo, double hi, double *out) {
    const mr_opt row = {opt, MR_OPT_DOUBLE, 0, lo, hi, lo, NULL, "", 0};
    mr_error err = {0};
    if (!mr_opt_set_row(&row, out, s, &err)) {
        fprintf(stderr, "mrcheck: --%s\n", err.msg);
        return false;
    }
    return true;
}

/* Whole numbers stay here: their ranges reach beyond an int (--from). */
bool mr_cli_int(const char *opt, const char *s, long lo, long hi, long *out) {
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (!s[0] || *end || errno || v < lo || v > hi) {
        fprintf(stderr, "mrcheck: --%s must be a whole number in [%ld, %ld], got '%s'\n", opt, lo, hi, s);
        return false;
    }
    *out = v;
    return true;
}

bool mr_cli_size(const char *opt, const char *s, int *w, int *h) {
    char *end = NULL;
    long a = strtol(s, &end, 10), b = 0;
    bool ok = end != s && (*end == 'x' || *end == 'X');
    if (ok) {
        const char *t = end + 1;
        b = strtol(t, &end, 10);
        ok = end != t && *end == 0;
    }
    if (!ok || a < 1 || b < 1 || a > 16384 || b > 16384) {
        fprintf(stderr, "mrcheck: --%s must be WIDTHxHEIGHT (1..16384), got '%s'\n", opt, s);
        return false;
    }
    *w = (int)a;
    *h = (int)b;
    return true;
}

int mr_cli_error(const char *cmd, const mr_error *err) {
    fprintf(stderr, "mrcheck: %s: %s\n", cmd, err->msg[0] ? err->msg : "failed");
    if (err->code == MR_ERR_INTERRUPTED) return 128 + (mr_stop_signal() > 0 ? mr_stop_signal() : 2);
    return err->code == MR_ERR_NODEVICE ? MR_CLI_EXIT_NODEVICE : 1;
}

int mr_cli_errorf(const char *cmd, const char *fmt, ...) {
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fprintf(stderr, "mrcheck: %s: %s\n", cmd, buf);
    return 1;
}

void mr_cli_log_level(const mr_cli_opt *opts) {
    if (mr_cli_get(opts, "quiet")) mr_log_set_level(MR_LOG_ERROR);
    else if (mr_cli_get(opts, "verbose")) mr_log_set_level(MR_LOG_INFO);
}

bool mr_cli_count_prefix(const char *s, double *out, const char **end) {
    char *e = NULL;
    double v = strtod(s, &e);
    if (e == s) return false;
    if (*e == 'k' || *e == 'K') {
        v *= 1e3;
        e++;
    } else if (*e == 'm' || *e == 'M') {
        v *= 1e6;
        e++;
    }
    *out = v;
    *end = e;
    return true;
}

int mr_cli_counts(const char *s, double lo, double hi, double *out, int max) {
    int n = 0;
    for (const char *p = s;; n++) {
        const char *end;
        double v;
        if (n >= max || !mr_cli_count_prefix(p, &v, &end) || !(v >= lo && v <= hi)) return -1;
        out[n] = v;
        if (*end == 0) return n + 1;
        if (*end != ',') return -1;
        p = end + 1;
    }
}
