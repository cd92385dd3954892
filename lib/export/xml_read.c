/* A small XML reader for BCF's documents: elements, attributes, text,
 * CDATA, the five predefined entities and character references. A DOCTYPE
 * is refused (no entity declaration is ever read, so none can expand), as
 * is any other entity; depth and element count are capped. Namespace
 * prefixes are dropped from names. */
#include "export_internal.h"

#include <stdlib.h>
#include <string.h>

#define MAX_DEPTH 64
#define MAX_NODES 1000000

typedef struct rd {
    const char *p, *end;
    int nodes;
    mr_error *err;
    bool failed;
} rd;

static bool fail(rd *r, const char *msg) {
    if (!r->failed) mr_fail(r->err, MR_ERR_PARSE, "XML: %s", msg);
    r->failed = true;
    return false;
}

static bool starts(rd *r, const char *s) {
    size_t n = strlen(s);
    return (size_t)(r->end - r->p) >= n && memcmp(r->p, s, n) == 0;
}

static bool skip_past(rd *r, const char *s) {
    size_t n = strlen(s);
    for (; (size_t)(r->end - r->p) >= n; r->p++)
        if (memcmp(r->p, s, n) == 0) {
            r->p += n;
            return true;
        }
    return fail(r, "unterminated markup");
}

static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
static bool is_name(char c) {
    return !is_space(c) && c != '<' && c != '>' && c != '/' && c != '=' && c != '"' && c != '\'' && c != '&' &&
           c != '?' && c != '!' && c != 0;
}
static void skip_space(rd *r) {
    while (r->p < r->end && is_space(*r->p)) r->p++;
}

/* A growing string. */
typedef struct sbuf { char *s; size_t n, cap; bool oom; } sbuf;
static void sb_put(sbuf *b, const char *s, size_t n) {
    if (b->oom) return;
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 32;
        while (b->n + n + 1 > cap) cap *= 2;
        char *q = realloc(b->s, cap);
        if (!q) {
            b->oom = true;
            return;
        }
        b->s = q;
        b->cap = cap;
    }
    memcpy(b->s + b->n, s, n);
    b->n += n;
    b->s[b->n] = 0;
}

static void put_utf8(sbuf *b, unsigned long c) {
    char u[4];
    size_t n;
    if (c < 0x80) u[0] = (char)c, n = 1;
    else if (c < 0x800) u[0] = (char)(0xc0 | c >> 6), u[1] = (char)(0x80 | (c & 0x3f)), n = 2;
    else if (c < 0x10000)
        u[0] = (char)(0xe0 | c >> 12), u[1] = (char)(0x80 | ((c >> 6) & 0x3f)), u[2] = (char)(0x80 | (c & 0x3f)), n = 3;
    else
        u[0] = (char)(0xf0 | c >> 18), u[1] = (char)(0x80 | ((c >> 12) & 0x3f)), u[2] = (char)(0x80 | ((c >> 6) & 0x3f)),
        u[3] = (char)(0x80 | (c & 0x3f)), n = 4;
    sb_put(b, u, n);
}

/* An entity reference at r->p ('&'), decoded into b. */
static bool entity(rd *r, sbuf *b) {
    static const struct { const char *name; char c; } k[] = {
        {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++)
        if (starts(r, k[i].name)) {
            sb_put(b, &k[i].c, 1);
            r->p += strlen(k[i].name);
            return true;
        }
    if (starts(r, "&#")) {
        const char *q = r->p + 2;
        int base = 10;
        if (q < r->end && *q == 'x') base = 16, q++;
        unsigned long c = 0;
        int digits = 0;
        for (; q < r->end && *q != ';' && digits < 8; q++, digits++) {
            int d = *q >= '0' && *q <= '9' ? *q - '0' : base == 16 && *q >= 'a' && *q <= 'f' ? *q - 'a' + 10
                    : base == 16 && *q >= 'A' && *q <= 'F' ? *q - 'A' + 10 : -1;
            if (d < 0) return fail(r, "bad character reference");
            c = c * (unsigned long)base + (unsigned long)d;
        }
        if (q >= r->end || *q != ';' || digits == 0 || c == 0 || c > 0x10ffff) return fail(r, "bad character reference");
        put_utf8(b, c);
        r->p = q + 1;
        return true;
    }
    return fail(r, "an entity other than XML's five (entities are not expanded)");
}

/* Attribute value or text up to a stop character, entities decoded. */
static char *text_until(rd *r, char stop) {
    sbuf b = {0};
    sb_put(&b, "", 0);
    while (r->p < r->end && *r->p != stop) {
        if (*r->p == '&') {
            if (!entity(r, &b)) break;
            continue;
        }
        if (stop != '<' && *r->p == '<') {
            fail(r, "'<' inside an attribute");
            break;
        }
        const char *q = r->p;
        while (q < r->end && *q != stop && *q != '&' && (stop == '<' || *q != '<')) q++;
        sb_put(&b, r->p, (size_t)(q - r->p));
        r->p = q;
    }
    if (b.oom) fail(r, "out of memory");
    if (r->failed) {
        free(b.s);
        return NULL;
    }
    return b.s;
}

static char *name_at(rd *r) {
    const char *q = r->p;
    while (q < r->end && is_name(*q)) q++;
    if (q == r->p) {
        fail(r, "expected a name");
        return NULL;
    }
    const char *s = r->p;
    r->p = q;
    /* Drop a namespace prefix: BCF's names are unqualified. */
    for (const char *c = s; c < q; c++)
        if (*c == ':') s = c + 1;
    size_t n = (size_t)(q - s);
    char *out = malloc(n + 1);
    if (!out) {
        fail(r, "out of memory");
        return NULL;
    }
    memcpy(out, s, n);
    out[n] = 0;
    return out;
}

void mr_xml_node_free(mr_xml_node *n) {
    if (!n) return;
    for (int i = 0; i < n->child_count; i++) mr_xml_node_free(n->children[i]);
    free(n->children);
    for (int i = 0; i < 2 * n->attr_count; i++) free(n->attrs[i]);
    free(n->attrs);
    free(n->name);
    free(n->text);
    free(n);
}

static bool push_ptr(void ***arr, int *n, void *p) {
    void **a = realloc(*arr, (size_t)(*n + 1) * sizeof *a);
    if (!a) return false;
    a[(*n)++] = p;
    *arr = a;
    return true;
}

/* Skips comments, processing instructions and white space; false on a
 * DOCTYPE or bad markup. */
static bool skip_misc(rd *r) {
    for (;;) {
        skip_space(r);
        if (starts(r, "<?")) {
            if (!skip_past(r, "?>")) return false;
        } else if (starts(r, "<!--")) {
            if (!skip_past(r, "-->")) return false;
        } else if (starts(r, "<!DOCTYPE") || starts(r, "<!ENTITY")) {
            return fail(r, "a DOCTYPE (its entity declarations are not read)");
        } else {
            return true;
        }
    }
}

static mr_xml_node *element(rd *r, int depth) {
    if (depth > MAX_DEPTH) return fail(r, "elements nested too deep"), NULL;
    if (++r->nodes > MAX_NODES) return fail(r, "too many elements"), NULL;
    if (!starts(r, "<")) return fail(r, "expected an element"), NULL;
    r->p++;
    mr_xml_node *n = calloc(1, sizeof *n);
    if (!n) return fail(r, "out of memory"), NULL;
    n->name = name_at(r);
    if (!n->name) goto bad;
    for (;;) {
        skip_space(r);
        if (r->p >= r->end) {
            fail(r, "unterminated element");
            goto bad;
        }
        if (starts(r, "/>")) {
            r->p += 2;
            return n;
        }
        if (*r->p == '>') {
            r->p++;
            break;
        }
        char *an = name_at(r);
        if (!an) goto bad;
        skip_space(r);
        if (r->p >= r->end || *r->p != '=') {
            free(an);
            fail(r, "attribute without a value");
            goto bad;
        }
        r->p++;
        skip_space(r);
        if (r->p >= r->end || (*r->p != '"' && *r->p != '\'')) {
            free(an);
            fail(r, "attribute value without quotes");
            goto bad;
        }
        char q = *r->p++;
        char *av = text_until(r, q);
        if (!av || r->p >= r->end) {
            free(an), free(av);
            if (!r->failed) fail(r, "unterminated attribute");
            goto bad;
        }
        r->p++;
        if (!push_ptr((void ***)&n->attrs, &(int){2 * n->attr_count}, an)) {
            free(an), free(av);
            fail(r, "out of memory");
            goto bad;
        }
        int k = 2 * n->attr_count + 1;
        if (!push_ptr((void ***)&n->attrs, &k, av)) {
            free(av);
            n->attrs[2 * n->attr_count] = NULL;
            free(an);
            fail(r, "out of memory");
            goto bad;
        }
        n->attr_count++;
    }
    sbuf text = {0};
    sb_put(&text, "", 0);
    for (;;) {
        if (r->p >= r->end) {
            fail(r, "unterminated element");
            break;
        }
        if (starts(r, "</")) {
            r->p += 2;
            char *close = name_at(r);
            bool same = close && strcmp(close, n->name) == 0;
            free(close);
            skip_space(r);
            if (!same || r->p >= r->end || *r->p != '>') {
                fail(r, "mismatched end tag");
                break;
            }
            r->p++;
            break;
        }
        if (starts(r, "<!--")) {
            if (!skip_past(r, "-->")) break;
            continue;
        }
        if (starts(r, "<?")) {
            if (!skip_past(r, "?>")) break;
            continue;
        }
        if (starts(r, "<![CDATA[")) {
            r->p += 9;
            const char *s = r->p;
            if (!skip_past(r, "]]>")) break;
            sb_put(&text, s, (size_t)(r->p - 3 - s));
            continue;
        }
        if (starts(r, "<!")) {
            fail(r, "a declaration inside an element");
            break;
        }
        if (*r->p == '<') {
            mr_xml_node *c = element(r, depth + 1);
            if (!c) break;
            if (!push_ptr((void ***)&n->children, &n->child_count, c)) {
                mr_xml_node_free(c);
                fail(r, "out of memory");
                break;
            }
            continue;
        }
        char *t = text_until(r, '<');
        if (!t) break;
        sb_put(&text, t, strlen(t));
        free(t);
    }
    if (text.oom) fail(r, "out of memory");
    n->text = text.s;
    if (r->failed) goto bad;
    return n;
bad:
    mr_xml_node_free(n);
    return NULL;
}

mr_xml_node *mr_xml_parse(const char *data, size_t size, mr_error *err) {
    rd r = {data, data + size, 0, err, false};
    /* A UTF-8 byte order mark is allowed. */
    if (size >= 3 && memcmp(data, "\xef\xbb\xbf", 3) == 0) r.p += 3;
    if (!skip_misc(&r)) return NULL;
    mr_xml_node *root = element(&r, 0);
    if (!root) return NULL;
    if (!skip_misc(&r) || r.p != r.end) {
        mr_xml_node_free(root);
        if (!r.failed) fail(&r, "content after the root element");
        return NULL;
    }
    return root;
}

const mr_xml_node *mr_xml_child(const mr_xml_node *n, const char *name) {
    for (int i = 0; n && i < n->child_count; i++)
        if (strcmp(n->children[i]->name, name) == 0) return n->children[i];
    return NULL;
}

const char *mr_xml_get_attr(const mr_xml_node *n, const char *name) {
    for (int i = 0; n && i < n->attr_count; i++) {
        const char *a = n->attrs[2 * i];
        const char *c = strrchr(a, ':');
        if (strcmp(c ? c + 1 : a, name) == 0) return n->attrs[2 * i + 1];
    }
    return NULL;
}

const char *mr_xml_child_text(const mr_xml_node *n, const char *name) {
    const mr_xml_node *c = mr_xml_child(n, name);
    return c ? c->text : NULL;
}
