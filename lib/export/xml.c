/* A small XML writer: elements in the order they are written (the schema's
 * order is the caller's job), escaped text and attributes, two-space
 * indentation. */
#include "export_internal.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

static void put(mr_xml *x, const char *s, size_t n) {
    if (x->oom) return;
    if (x->len + n + 1 > x->cap) {
        size_t cap = x->cap ? x->cap : 1024;
        while (x->len + n + 1 > cap) cap *= 2;
        char *b = realloc(x->buf, cap);
        if (!b) {
            x->oom = true;
            return;
        }
        x->buf = b;
        x->cap = cap;
    }
    memcpy(x->buf + x->len, s, n);
    x->len += n;
    x->buf[x->len] = 0;
}

static void puts_(mr_xml *x, const char *s) { put(x, s, strlen(s)); }

void mr_xml_raw(mr_xml *x, const char *fmt, ...) {
    char tmp[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    if ((size_t)n < sizeof tmp) {
        put(x, tmp, (size_t)n);
        return;
    }
    char *big = malloc((size_t)n + 1);
    if (!big) {
        x->oom = true;
        return;
    }
    va_start(ap, fmt);
    vsnprintf(big, (size_t)n + 1, fmt, ap);
    va_end(ap);
    put(x, big, (size_t)n);
    free(big);
}

void mr_xml_escape_into(mr_xml *x, const char *text) {
    for (const unsigned char *p = (const unsigned char *)(text ? text : ""); *p; p++) {
        switch (*p) {
        case '&': puts_(x, "&amp;"); break;
        case '<': puts_(x, "&lt;"); break;
        case '>': puts_(x, "&gt;"); break;
        case '"': puts_(x, "&quot;"); break;
        case '\'': puts_(x, "&apos;"); break;
        default:
            /* XML 1.0 has no way to write most control characters. */
            if (*p < 0x20 && *p != '\t' && *p != '\n' && *p != '\r') break;
            put(x, (const char *)p, 1);
        }
    }
}

static void indent(mr_xml *x) {
    puts_(x, "\n");
    for (int i = 0; i < x->depth; i++) puts_(x, "  ");
}

static void end_start_tag(mr_xml *x) {
    if (x->tag_open) {
        puts_(x, ">");
        x->tag_open = false;
    }
}

void mr_xml_begin(mr_xml *x) {
    memset(x, 0, sizeof *x);
    puts_(x, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
}

void mr_xml_open(mr_xml *x, const char *name) {
    end_start_tag(x);
    if (x->depth >= (int)(sizeof x->stack / sizeof x->stack[0])) {
        x->oom = true;
        return;
    }
    indent(x);
    puts_(x, "<");
    puts_(x, name);
    x->stack[x->depth++] = name;
    x->tag_open = true;
    x->has_child = false;
}

void mr_xml_attr(mr_xml *x, const char *name, const char *value) {
    if (!x->tag_open) {
        x->oom = true; /* misuse: an attribute after content */
        return;
    }
    puts_(x, " ");
    puts_(x, name);
    puts_(x, "=\"");
    mr_xml_escape_into(x, value);
    puts_(x, "\"");
}

void mr_xml_close(mr_xml *x) {
    if (x->depth <= 0) {
        x->oom = true;
        return;
    }
    const char *name = x->stack[--x->depth];
    if (x->tag_open) {
        puts_(x, "/>");
        x->tag_open = false;
    } else {
        if (x->has_child) indent(x);
        puts_(x, "</");
        puts_(x, name);
        puts_(x, ">");
    }
    x->has_child = true; /* the parent now has a child element */
}

void mr_xml_text_elem(mr_xml *x, const char *name, const char *text) {
    mr_xml_open(x, name);
    end_start_tag(x);
    mr_xml_escape_into(x, text);
    x->has_child = false;
    mr_xml_close(x);
}

void mr_xml_num_elem(mr_xml *x, const char *name, double v) {
    char t[64];
    /* 15 significant digits: a millimetre at 1e7 m offsets and -0 printed as 0. */
    snprintf(t, sizeof t, "%.15g", v == 0 ? 0.0 : v);
    mr_xml_text_elem(x, name, t);
}

char *mr_xml_take(mr_xml *x, size_t *len) {
    if (!x->oom && x->depth == 0) puts_(x, "\n");
    char *b = NULL;
    if (!x->oom && x->depth == 0) {
        b = x->buf;
        if (len) *len = x->len;
        x->buf = NULL;
    }
    mr_xml_free(x);
    return b;
}

void mr_xml_free(mr_xml *x) {
    free(x->buf);
    memset(x, 0, sizeof *x);
}
