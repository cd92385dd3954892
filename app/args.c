/* Argument parsing shared by the subcommands. */
#include "app.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

static void print_usage(const char *usage, const app_opt *opts) {
    printf("%s\n\noptions:\n", usage);
    for (const app_opt *o = opts; o->name; o++) {
        char left[64];
        snprintf(left, sizeof left, "--%s%s%s", o->name, o->arg ? " " : "", o->arg ? o->arg : "");
        printf("  %-24s %s\n", left, o->help);
    }
    printf("  %-24s %s\n", "--help", "show this help");
}

bool app_parse(int argc, char **argv, int first, app_opt *opts, const char **pos, int max_pos, int *npos,
               const char *usage, bool *help_shown) {
    *help_shown = false;
    if (npos) *npos = 0;
    for (int i = first; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            print_usage(usage, opts);
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
        app_opt *o = opts;
        for (; o->name; o++)
            if (strlen(o->name) == nlen && strncmp(o->name, name, nlen) == 0) break;
        if (!o->name) {
            fprintf(stderr, "mrcheck: unknown option '--%.*s' (see --help)\n", (int)nlen, name);
            return false;
        }
        if (!o->arg) {
            if (eq) {
                fprintf(stderr, "mrcheck: option '--%s' takes no value\n", o->name);
                return false;
            }
            o->value = "1";
        } else if (eq) {
            o->value = eq + 1;
        } else if (i + 1 < argc) {
            o->value = argv[++i];
        } else {
            fprintf(stderr, "mrcheck: option '--%s' needs a value (%s)\n", o->name, o->arg);
            return false;
        }
    }
    return true;
}

const char *app_get(const app_opt *opts, const char *name) {
    for (const app_opt *o = opts; o->name; o++)
        if (strcmp(o->name, name) == 0) return o->value;
    return NULL;
}

bool app_flag(const app_opt *opts, const char *name) { return app_get(opts, name) != NULL; }

bool app_double(const char *opt, const char *s, double lo, double hi, double *out) {
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (!s[0] || *end || errno || !isfinite(v) || v < lo || v > hi) {
        fprintf(stderr, "mrcheck: --%s must be a number in [%g, %g], got '%s'\n", opt, lo, hi, s);
        return false;
    }
    *out = v;
    return true;
}

bool app_int(const char *opt, const char *s, long lo, long hi, long *out) {
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

bool app_size(const char *opt, const char *s, int *w, int *h) {
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

int app_error(const char *cmd, const mr_error *err) {
    fprintf(stderr, "mrcheck: %s: %s\n", cmd, err->msg[0] ? err->msg : "failed");
    return err->code == MR_ERR_NODEVICE ? APP_EXIT_NODEVICE : 1;
}

int app_errorf(const char *cmd, const char *fmt, ...) {
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fprintf(stderr, "mrcheck: %s: %s\n", cmd, buf);
    return 1;
}

void app_log_level(const app_opt *opts) {
    if (app_get(opts, "quiet")) mr_log_set_level(MR_LOG_ERROR);
    else if (app_get(opts, "verbose")) mr_log_set_level(MR_LOG_INFO);
}
