/* The text buffer and SVG text of lib/study's analyses. */
#include "study_internal.h"

#include <stdarg.h>
#include <stdlib.h>

void mr_sb_printf(mr_sbuf *b, const char *fmt, ...) {
    if (b->oom) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        size_t room = b->cap - b->len;
        int n = vsnprintf(b->s ? b->s + b->len : NULL, b->s ? room : 0, fmt, ap);
        va_end(ap);
        if (n < 0) return;
        if ((size_t)n < room) {
            b->len += (size_t)n;
            return;
        }
        size_t cap = b->cap ? b->cap * 2 : 4096;
        while (cap - b->len <= (size_t)n) cap *= 2;
        char *p = realloc(b->s, cap);
        if (!p) {
            b->oom = true;
            return;
        }
        b->s = p;
        b->cap = cap;
    }
}

bool mr_sb_save(mr_sbuf *b, const char *path, mr_error *err) {
    if (b->oom) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    return mr_file_write_atomic(path, b->s ? b->s : "", b->len, err);
}

void mr_svg_text(mr_sbuf *b, double x, double y, const char *anchor, int size, const char *fill, const char *text) {
    mr_sb_printf(b, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"%s\" font-size=\"%d\" fill=\"%s\">", x, y, anchor, size,
              fill);
    for (const char *c = text; *c; c++) {
        if (*c == '<') mr_sb_printf(b, "&lt;");
        else if (*c == '>') mr_sb_printf(b, "&gt;");
        else if (*c == '&') mr_sb_printf(b, "&amp;");
        else mr_sb_printf(b, "%c", *c);
    }
    mr_sb_printf(b, "</text>\n");
}
