/* The one median / quantile and the one CSV writer of every bench. */
#include "mr_eval.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ quantiles */

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

double mr_quantile(double *v, int n, double q) {
    /* NaN breaks qsort's ordering: move the numbers to the front first. */
    int m = 0;
    for (int i = 0; i < n; i++)
        if (!isnan(v[i])) {
            double t = v[m];
            v[m++] = v[i];
            v[i] = t;
        }
    if (m <= 0) return NAN;
    qsort(v, (size_t)m, sizeof *v, cmp_double);
    q = q < 0 ? 0 : q > 1 ? 1 : q;
    double pos = q * (m - 1);
    int i = (int)pos;
    return i + 1 < m ? v[i] + (pos - i) * (v[i + 1] - v[i]) : v[i];
}

double mr_median(double *v, int n) { return mr_quantile(v, n, 0.5); }

/* ------------------------------------------------------------------ CSV */

struct mr_csv {
    char *buf;
    size_t len, cap;
    int columns;   /* cells in the header line; 0 before it */
    int cells;     /* cells in the row being written */
    int rows;      /* data rows ended */
    mr_error fail; /* the first error (out of memory, a ragged row) */
};

mr_csv *mr_csv_create(mr_error *err) {
    mr_csv *c = calloc(1, sizeof *c);
    if (!c) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    return c;
}

void mr_csv_destroy(mr_csv **csv) {
    if (!csv || !*csv) return;
    free((*csv)->buf);
    free(*csv);
    *csv = NULL;
}

static void put(mr_csv *c, const char *s, size_t n) {
    if (c->fail.code) return;
    if (c->len + n + 1 > c->cap) {
        size_t cap = c->cap ? c->cap : 4096;
        while (c->len + n + 1 > cap) cap *= 2;
        char *b = realloc(c->buf, cap);
        if (!b) {
            mr_fail(&c->fail, MR_ERR_NOMEM, "CSV: out of memory");
            return;
        }
        c->buf = b;
        c->cap = cap;
    }
    memcpy(c->buf + c->len, s, n);
    c->len += n;
    c->buf[c->len] = 0;
}

static void put_str(mr_csv *c, const char *s) { put(c, s, strlen(s)); }

void mr_csv_comment(mr_csv *c, const char *text) {
    if (!c) return;
    /* Every line of the text becomes its own "# " line, so a newline in
     * the text cannot start a data line. */
    const char *s = text ? text : "";
    do {
        const char *nl = strchr(s, '\n');
        size_t n = nl ? (size_t)(nl - s) : strlen(s);
        put_str(c, "# ");
        put(c, s, n);
        put_str(c, "\n");
        s = nl ? nl + 1 : NULL;
    } while (s && *s);
}

void mr_csv_header(mr_csv *c, const char *columns) {
    if (!c) return;
    if (c->columns) {
        if (!c->fail.code) mr_fail(&c->fail, MR_ERR_INVALID, "CSV: a second header line");
        return;
    }
    int n = 1;
    for (const char *s = columns; *s; s++) n += *s == ',';
    c->columns = n;
    put_str(c, columns);
    put_str(c, "\n");
}

static void sep(mr_csv *c) {
    if (c->cells++ > 0) put_str(c, ",");
}

static void quoted(mr_csv *c, const char *s) {
    put_str(c, "\"");
    for (const char *p = s; *p; p++) {
        put(c, p, 1);
        if (*p == '"') put(c, p, 1); /* a quote inside is doubled */
    }
    put_str(c, "\"");
}

void mr_csv_text(mr_csv *c, const char *s) {
    if (!c) return;
    sep(c);
    s = s ? s : "";
    size_t n = strlen(s);
    /* RFC 4180: quote a field holding a separator, a quote or a line
     * break; also one with outer spaces (readers trim them) or a leading
     * '#' (in the first column it would read as a comment line). */
    bool q = strpbrk(s, ",\"\r\n") != NULL || (n > 0 && (s[0] == ' ' || s[n - 1] == ' ' || s[0] == '#'));
    if (q) quoted(c, s);
    else put(c, s, n);
}

void mr_csv_quoted(mr_csv *c, const char *s) {
    if (!c) return;
    sep(c);
    quoted(c, s ? s : "");
}

void mr_csv_num(mr_csv *c, const char *fmt, double v) {
    if (!c) return;
    sep(c);
    /* One spelling for the non-finite values, whatever the format and the
     * sign bit of a NaN: nan, inf, -inf. */
    if (isnan(v)) put_str(c, "nan");
    else if (isinf(v)) put_str(c, v > 0 ? "inf" : "-inf");
    else {
        char b[512];
        int n = snprintf(b, sizeof b, fmt ? fmt : "%.17g", v);
        if (n < 0 || (size_t)n >= sizeof b) {
            if (!c->fail.code) mr_fail(&c->fail, MR_ERR_INVALID, "CSV: number cell too long");
        } else put(c, b, (size_t)n);
    }
}

void mr_csv_int(mr_csv *c, long long v) {
    if (!c) return;
    sep(c);
    char b[32];
    int n = snprintf(b, sizeof b, "%lld", v);
    put(c, b, (size_t)n);
}

void mr_csv_end_row(mr_csv *c) {
    if (!c) return;
    if (c->columns && c->cells != c->columns && !c->fail.code)
        mr_fail(&c->fail, MR_ERR_INVALID, "CSV: row %d has %d cells, the header %d", c->rows + 1, c->cells, c->columns);
    put_str(c, "\n");
    c->cells = 0;
    c->rows++;
}

const char *mr_csv_data(const mr_csv *c, size_t *len) {
    if (len) *len = c && c->buf ? c->len : 0;
    return c && c->buf ? c->buf : "";
}

bool mr_csv_save(const mr_csv *c, const char *path, mr_error *err) {
    if (!c) return mr_fail(err, MR_ERR_INVALID, "CSV: no table");
    if (c->fail.code) return mr_fail(err, c->fail.code, "%s: %s", path, c->fail.msg);
    if (c->cells) return mr_fail(err, MR_ERR_INVALID, "%s: CSV: the last row was not ended", path);
    return mr_file_write_atomic(path, c->buf ? c->buf : "", c->len, err);
}
