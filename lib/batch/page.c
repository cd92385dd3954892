/* Printable pages: black rectangles and text, written as PDF 1.4 or
 * rasterised to a PNG at a stated dpi (tag sheets, calibration boards). */
#include "mr_batch.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define PT_PER_MM (72.0 / 25.4)

static mr_page_item *page_push(mr_page *p) {
    if (p->failed) return NULL;
    if (p->count == p->cap) {
        int cap = p->cap ? 2 * p->cap : 64;
        mr_page_item *n = realloc(p->items, (size_t)cap * sizeof *n);
        if (!n) {
            p->failed = true;
            return NULL;
        }
        p->items = n;
        p->cap = cap;
    }
    mr_page_item *it = &p->items[p->count++];
    memset(it, 0, sizeof *it);
    return it;
}

void mr_page_rect(mr_page *p, double x, double y, double w, double h) {
    mr_page_item *it = page_push(p);
    if (it) *it = (mr_page_item){.kind = MR_PAGE_RECT, .x = x, .y = y, .w = w, .h = h};
}

void mr_page_text(mr_page *p, double x, double y, double size_pt, const char *fmt, ...) {
    mr_page_item *it = page_push(p);
    if (!it) return;
    *it = (mr_page_item){.kind = MR_PAGE_TEXT, .x = x, .y = y, .h = size_pt};
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(it->text, sizeof it->text, fmt, ap);
    va_end(ap);
    for (char *c = it->text; *c; c++)
        if (*c < 32 || *c > 126) *c = '?';
}

void mr_page_free(mr_page *p) {
    free(p->items);
    memset(p, 0, sizeof *p);
}

bool mr_paper_size(const char *name, double *width_mm, double *height_mm) {
    static const struct {
        const char *name;
        double w, h;
    } k[] = {{"a4", 210, 297}, {"a3", 297, 420}, {"letter", 215.9, 279.4}};
    for (size_t i = 0; name && i < sizeof k / sizeof k[0]; i++)
        if (strcasecmp(name, k[i].name) == 0) {
            *width_mm = k[i].w;
            *height_mm = k[i].h;
            return true;
        }
    return false;
}

/* ------------------------------------------------------------------ PDF */

typedef struct buf {
    char *s;
    size_t len, cap;
    bool failed;
} buf;

static void put(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(buf *b, const char *fmt, ...) {
    if (b->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(b->s ? b->s + b->len : NULL, b->s ? b->cap - b->len : 0, fmt, ap);
        va_end(ap);
        if (n < 0) {
            b->failed = true;
            return;
        }
        if (b->s && b->len + (size_t)n < b->cap) {
            b->len += (size_t)n;
            return;
        }
        size_t cap = b->cap ? b->cap : 4096;
        while (cap <= b->len + (size_t)n) cap *= 2;
        char *s = realloc(b->s, cap);
        if (!s) {
            b->failed = true;
            return;
        }
        b->s = s;
        b->cap = cap;
    }
}

/* A page's content stream: rectangles filled black, text in /F1. */
static void page_content(const mr_page *p, buf *c) {
    const double H = p->height_mm * PT_PER_MM;
    put(c, "0 g\n");
    for (int i = 0; i < p->count; i++) {
        const mr_page_item *it = &p->items[i];
        if (it->kind == MR_PAGE_RECT) {
            put(c, "%.3f %.3f %.3f %.3f re f\n", it->x * PT_PER_MM, H - (it->y + it->h) * PT_PER_MM, it->w * PT_PER_MM,
                it->h * PT_PER_MM);
            continue;
        }
        put(c, "BT /F1 %.2f Tf %.3f %.3f Td (", it->h, it->x * PT_PER_MM, H - it->y * PT_PER_MM);
        for (const char *s = it->text; *s; s++) put(c, "%s%c", *s == '(' || *s == ')' || *s == '\\' ? "\\" : "", *s);
        put(c, ") Tj ET\n");
    }
}

bool mr_pdf_save(const char *path, const mr_page *pages, int n, mr_error *err) {
    if (n < 1) return mr_fail(err, MR_ERR_INVALID, "a PDF needs a page");
    for (int i = 0; i < n; i++)
        if (pages[i].failed) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    /* Objects: 1 catalog, 2 page tree, 3 font, 4 info, then per page its
     * page object and its content stream. */
    const int objs = 4 + 2 * n;
    size_t *off = calloc((size_t)objs + 1, sizeof *off);
    buf b = {0};
    if (!off) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    put(&b, "%%PDF-1.4\n%%\xe2\xe3\xcf\xd3\n");
    off[1] = b.len;
    put(&b, "1 0 obj\n<< /Type /Catalog /Pages 2 0 R >>\nendobj\n");
    off[2] = b.len;
    put(&b, "2 0 obj\n<< /Type /Pages /Count %d /Kids [", n);
    for (int i = 0; i < n; i++) put(&b, "%s%d 0 R", i ? " " : "", 5 + 2 * i);
    put(&b, "] >>\nendobj\n");
    off[3] = b.len;
    put(&b, "3 0 obj\n<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica /Encoding /WinAnsiEncoding >>\nendobj\n");
    off[4] = b.len;
    put(&b, "4 0 obj\n<< /Producer (mrcheck) /Creator (mrcheck) >>\nendobj\n");
    for (int i = 0; i < n; i++) {
        const mr_page *p = &pages[i];
        off[5 + 2 * i] = b.len;
        put(&b,
            "%d 0 obj\n<< /Type /Page /Parent 2 0 R /MediaBox [0 0 %.3f %.3f] /Resources << /Font << /F1 3 0 R >> >> "
            "/Contents %d 0 R >>\nendobj\n",
            5 + 2 * i, p->width_mm * PT_PER_MM, p->height_mm * PT_PER_MM, 6 + 2 * i);
        buf c = {0};
        page_content(p, &c);
        off[6 + 2 * i] = b.len;
        put(&b, "%d 0 obj\n<< /Length %zu >>\nstream\n", 6 + 2 * i, c.len);
        if (c.failed) b.failed = true;
        else put(&b, "%.*s", (int)c.len, c.s);
        put(&b, "\nendstream\nendobj\n");
        free(c.s);
    }
    size_t xref = b.len;
    put(&b, "xref\n0 %d\n0000000000 65535 f \n", objs + 1);
    for (int i = 1; i <= objs; i++) put(&b, "%010zu 00000 n \n", off[i]);
    put(&b, "trailer\n<< /Size %d /Root 1 0 R /Info 4 0 R >>\nstartxref\n%zu\n%%%%EOF\n", objs + 1, xref);
    free(off);
    bool ok = b.failed ? mr_fail(err, MR_ERR_NOMEM, "out of memory") : mr_file_write_atomic(path, b.s, b.len, err);
    free(b.s);
    return ok;
}

/* ----------------------------------------------------------- rasterising */

/* A 5x7 pixel font of our own (rows of 5 cells, '#' = ink; rows 7 and 8
 * are the descender). Letters are lower case; upper case is drawn with
 * them. Anything else is a hollow box. */
static const struct {
    char c;
    const char *rows[9];
} k_glyphs[] = {
    {' ', {"     ", "     ", "     ", "     ", "     ", "     ", "     "}},
    {'0', {" ### ", "#   #", "#  ##", "# # #", "##  #", "#   #", " ### "}},
    {'1', {"  #  ", " ##  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'2', {" ### ", "#   #", "    #", "   # ", "  #  ", " #   ", "#####"}},
    {'3', {"#####", "   # ", "  #  ", "   # ", "    #", "#   #", " ### "}},
    {'4', {"   # ", "  ## ", " # # ", "#  # ", "#####", "   # ", "   # "}},
    {'5', {"#####", "#    ", "#### ", "    #", "    #", "#   #", " ### "}},
    {'6', {"  ## ", " #   ", "#    ", "#### ", "#   #", "#   #", " ### "}},
    {'7', {"#####", "    #", "   # ", "  #  ", " #   ", " #   ", " #   "}},
    {'8', {" ### ", "#   #", "#   #", " ### ", "#   #", "#   #", " ### "}},
    {'9', {" ### ", "#   #", "#   #", " ####", "    #", "   # ", " ##  "}},
    {'a', {"     ", "     ", " ### ", "    #", " ####", "#   #", " ####"}},
    {'b', {"#    ", "#    ", "# ## ", "##  #", "#   #", "#   #", "#### "}},
    {'c', {"     ", "     ", " ### ", "#    ", "#    ", "#   #", " ### "}},
    {'d', {"    #", "    #", " ## #", "#  ##", "#   #", "#   #", " ####"}},
    {'e', {"     ", "     ", " ### ", "#   #", "#####", "#    ", " ### "}},
    {'f', {"  ## ", " #  #", " #   ", "###  ", " #   ", " #   ", " #   "}},
    {'g', {"     ", "     ", " ####", "#   #", "#   #", "#   #", " ####", "    #", " ### "}},
    {'h', {"#    ", "#    ", "# ## ", "##  #", "#   #", "#   #", "#   #"}},
    {'i', {"  #  ", "     ", " ##  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'j', {"   # ", "     ", "  ## ", "   # ", "   # ", "   # ", "   # ", "#  # ", " ##  "}},
    {'k', {"#    ", "#    ", "#  # ", "# #  ", "##   ", "# #  ", "#  # "}},
    {'l', {" ##  ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'m', {"     ", "     ", "## # ", "# # #", "# # #", "#   #", "#   #"}},
    {'n', {"     ", "     ", "# ## ", "##  #", "#   #", "#   #", "#   #"}},
    {'o', {"     ", "     ", " ### ", "#   #", "#   #", "#   #", " ### "}},
    {'p', {"     ", "     ", "#### ", "#   #", "#   #", "#   #", "#### ", "#    ", "#    "}},
    {'q', {"     ", "     ", " ####", "#   #", "#   #", "#   #", " ####", "    #", "    #"}},
    {'r', {"     ", "     ", "# ## ", "##  #", "#    ", "#    ", "#    "}},
    {'s', {"     ", "     ", " ####", "#    ", " ### ", "    #", "#### "}},
    {'t', {" #   ", " #   ", "###  ", " #   ", " #   ", " #  #", "  ## "}},
    {'u', {"     ", "     ", "#   #", "#   #", "#   #", "#  ##", " ## #"}},
    {'v', {"     ", "     ", "#   #", "#   #", "#   #", " # # ", "  #  "}},
    {'w', {"     ", "     ", "#   #", "#   #", "# # #", "# # #", " # # "}},
    {'x', {"     ", "     ", "#   #", " # # ", "  #  ", " # # ", "#   #"}},
    {'y', {"     ", "     ", "#   #", "#   #", "#   #", "#   #", " ####", "    #", " ### "}},
    {'z', {"     ", "     ", "#####", "   # ", "  #  ", " #   ", "#####"}},
    {'-', {"     ", "     ", "     ", "#####", "     ", "     ", "     "}},
    {'+', {"     ", "  #  ", "  #  ", "#####", "  #  ", "  #  ", "     "}},
    {'=', {"     ", "     ", "#####", "     ", "#####", "     ", "     "}},
    {'.', {"     ", "     ", "     ", "     ", "     ", " ##  ", " ##  "}},
    {',', {"     ", "     ", "     ", "     ", "     ", " ##  ", "  #  ", " #   "}},
    {':', {"     ", " ##  ", " ##  ", "     ", " ##  ", " ##  ", "     "}},
    {';', {"     ", " ##  ", " ##  ", "     ", " ##  ", "  #  ", " #   "}},
    {'/', {"    #", "    #", "   # ", "  #  ", " #   ", "#    ", "#    "}},
    {'(', {"   # ", "  #  ", " #   ", " #   ", " #   ", "  #  ", "   # "}},
    {')', {" #   ", "  #  ", "   # ", "   # ", "   # ", "  #  ", " #   "}},
    {'%', {"##   ", "##  #", "   # ", "  #  ", " #   ", "#  ##", "   ##"}},
    {'_', {"     ", "     ", "     ", "     ", "     ", "     ", "#####"}},
    {'?', {"#####", "#   #", "#   #", "#   #", "#   #", "#   #", "#####"}},
};

static int glyph_index(char c) {
    if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
    int box = 0;
    for (size_t i = 0; i < sizeof k_glyphs / sizeof k_glyphs[0]; i++) {
        if (k_glyphs[i].c == c) return (int)i;
        if (k_glyphs[i].c == '?') box = (int)i;
    }
    return box;
}

/* Pixels whose centre lies in [x0, x1) x [y0, y1) (pixel units). */
static void fill(mr_image *img, double x0, double y0, double x1, double y1) {
    int i0 = (int)ceil(x0 - 0.5), i1 = (int)ceil(x1 - 0.5), j0 = (int)ceil(y0 - 0.5), j1 = (int)ceil(y1 - 0.5);
    if (i0 < 0) i0 = 0;
    if (j0 < 0) j0 = 0;
    if (i1 > img->width) i1 = img->width;
    if (j1 > img->height) j1 = img->height;
    unsigned char *d = img->data;
    for (int j = j0; j < j1; j++)
        if (i1 > i0) memset(d + (size_t)j * img->width + i0, 0, (size_t)(i1 - i0));
}

bool mr_page_raster(const mr_page *p, double dpi, mr_image *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    if (p->failed) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    const double s = dpi / 25.4; /* px per mm */
    const long w = lround(p->width_mm * s), h = lround(p->height_mm * s);
    if (!(dpi > 0) || w < 1 || h < 1 || (double)w * (double)h > 4e8)
        return mr_fail(err, MR_ERR_INVALID, "%g dpi gives a %ldx%ld image", dpi, w, h);
    if (!mr_image_alloc(out, (int)w, (int)h, 1, MR_PIX_U8, err)) return false;
    memset(out->data, 255, (size_t)w * (size_t)h);
    for (int i = 0; i < p->count; i++) {
        const mr_page_item *it = &p->items[i];
        if (it->kind == MR_PAGE_RECT) {
            fill(out, it->x * s, it->y * s, (it->x + it->w) * s, (it->y + it->h) * s);
            continue;
        }
        /* Helvetica's cap height is 0.718 of the size; the font's is 7 cells. */
        const double u = it->h * 0.718 / 7 / PT_PER_MM * s;
        double x = it->x * s;
        const double top = it->y * s - 7 * u;
        for (const char *c = it->text; *c; c++, x += 6 * u) {
            const int g = glyph_index(*c);
            for (int r = 0; r < 9 && k_glyphs[g].rows[r]; r++)
                for (int k = 0; k < 5; k++)
                    if (k_glyphs[g].rows[r][k] == '#') fill(out, x + k * u, top + r * u, x + (k + 1) * u, top + (r + 1) * u);
        }
    }
    return true;
}

/* PNG's CRC-32 (ISO 3309), bit by bit: a chunk of 13 bytes needs no table. */
static uint32_t crc32_png(const unsigned char *d, size_t n) {
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= d[i];
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return c ^ 0xffffffffu;
}

static void be32(unsigned char *o, uint32_t v) {
    o[0] = (unsigned char)(v >> 24);
    o[1] = (unsigned char)(v >> 16);
    o[2] = (unsigned char)(v >> 8);
    o[3] = (unsigned char)v;
}

bool mr_page_png_save(const char *path, const mr_image *img, double dpi, mr_error *err) {
    size_t n = 0;
    unsigned char *png = mr_image_encode_png(img, &n, err);
    if (!png) return false;
    /* The signature (8 bytes) and IHDR (25) come first; pHYs goes right
     * after them: 9 bytes of data, pixels per metre in x and y, unit 1. */
    const size_t at = 33;
    if (n < at || memcmp(png + 12, "IHDR", 4) != 0) {
        free(png);
        return mr_fail(err, MR_ERR_IO, "%s: unexpected PNG layout", path);
    }
    unsigned char chunk[21];
    be32(chunk, 9);
    memcpy(chunk + 4, "pHYs", 4);
    const uint32_t ppm = (uint32_t)lround(dpi / 0.0254);
    be32(chunk + 8, ppm);
    be32(chunk + 12, ppm);
    chunk[16] = 1;
    be32(chunk + 17, crc32_png(chunk + 4, 13));
    unsigned char *o = malloc(n + sizeof chunk);
    bool ok = o != NULL;
    if (ok) {
        memcpy(o, png, at);
        memcpy(o + at, chunk, sizeof chunk);
        memcpy(o + at + sizeof chunk, png + at, n - at);
        ok = mr_file_write_atomic(path, o, n + sizeof chunk, err);
    } else {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    free(o);
    free(png);
    return ok;
}
