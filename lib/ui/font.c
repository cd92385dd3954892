/* Font: a system TrueType file baked into one 8-bit atlas with stb_truetype
 * (Debian's libstb carries the implementation; we only include the header). */
#include "mr_ui.h"

#include <stdlib.h>
#include <string.h>

#include <stb_truetype.h>

#include "ui_internal.h"

#define FIRST_CHAR 32
#define CHAR_COUNT 95 /* printable ASCII */
#define WHITE_ROWS 4   /* opaque rows at the top of the atlas */

struct mr_ui_font {
    unsigned char *ttf;             /* the file; stb_truetype keeps pointers into it */
    uint8_t *atlas;
    int atlas_w, atlas_h;
    float pixel_height;
    float ascent;                   /* baseline below the top, pixels at pixel_height */
    stbtt_packedchar chars[CHAR_COUNT];
};

/* Well-known locations first: they need no helper program and cover Debian,
 * Fedora, Arch and Alpine. */
static const char *const k_font_paths[] = {
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/noto/NotoSans-Regular.ttf",
    "/usr/share/fonts/noto/NotoSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/usr/share/fonts/gnu-free/FreeSans.ttf",
    NULL,
};

static bool is_ttf(const char *path) {
    size_t n = strlen(path);
    return n > 4 && (strcmp(path + n - 4, ".ttf") == 0 || strcmp(path + n - 4, ".TTF") == 0 ||
                     strcmp(path + n - 4, ".otf") == 0);
}

bool mr_ui_font_find(char *out, size_t n, mr_error *err) {
    const char *env = getenv("MR_FONT");
    if (env && env[0]) {
        if (!mr_file_exists(env)) return mr_fail(err, MR_ERR_IO, "MR_FONT=%s does not exist", env);
        snprintf(out, n, "%s", env);
        return true;
    }
    for (int i = 0; k_font_paths[i]; i++)
        if (mr_file_exists(k_font_paths[i])) {
            snprintf(out, n, "%s", k_font_paths[i]);
            return true;
        }
    /* fontconfig knows every installed font; ask for a TrueType sans. */
    FILE *p = popen("fc-match -f '%{file}' 'sans-serif:fontformat=TrueType' 2>/dev/null", "r");
    if (p) {
        char buf[1024] = "";
        size_t got = fread(buf, 1, sizeof buf - 1, p);
        buf[got] = 0;
        pclose(p);
        if (got > 0 && is_ttf(buf) && mr_file_exists(buf)) {
            snprintf(out, n, "%s", buf);
            return true;
        }
    }
    return mr_fail(err, MR_ERR_IO,
                   "no TrueType font found (install fonts-dejavu-core, or set MR_FONT to a .ttf file)");
}

mr_ui_font *mr_ui_font_create(const mr_ui_font_params *params, mr_error *err) {
    mr_ui_font_params p = MR_UI_FONT_DEFAULTS;
    if (params) p = *params;
    if (!(p.pixel_height > 0)) p.pixel_height = 20.0f;
    if (p.pixel_height > 200.0f) p.pixel_height = 200.0f;
    char found[1024];
    if (!p.path) {
        if (!mr_ui_font_find(found, sizeof found, err)) return NULL;
        p.path = found;
    }
    mr_ui_font *f = calloc(1, sizeof *f);
    if (!f) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    size_t size = 0;
    f->ttf = mr_file_read(p.path, &size, 64u << 20, err);
    stbtt_fontinfo info;
    if (!f->ttf || size < 12 || !stbtt_InitFont(&info, f->ttf, stbtt_GetFontOffsetForIndex(f->ttf, 0))) {
        if (f->ttf) mr_fail(err, MR_ERR_PARSE, "%s is not a TrueType font", p.path);
        mr_ui_font_destroy(&f);
        return NULL;
    }
    f->pixel_height = p.pixel_height;
    int asc = 0, desc = 0, gap = 0;
    stbtt_GetFontVMetrics(&info, &asc, &desc, &gap);
    f->ascent = (float)asc * stbtt_ScaleForPixelHeight(&info, p.pixel_height);
    /* The atlas grows until the glyphs fit (big text on dense screens).
     * The top WHITE_ROWS rows are kept out of the packer and filled white:
     * solid shapes sample there, so shapes and text share one texture and
     * one draw call. */
    for (int side = 256; side <= 4096; side *= 2) {
        free(f->atlas);
        f->atlas = calloc((size_t)side * side, 1);
        if (!f->atlas) break;
        stbtt_pack_context pc;
        if (!stbtt_PackBegin(&pc, f->atlas + (size_t)side * WHITE_ROWS, side, side - WHITE_ROWS, side, 1, NULL))
            continue;
        stbtt_PackSetOversampling(&pc, 1, 1);
        int ok = stbtt_PackFontRange(&pc, f->ttf, 0, p.pixel_height, FIRST_CHAR, CHAR_COUNT, f->chars);
        stbtt_PackEnd(&pc);
        if (!ok) continue;
        for (int i = 0; i < CHAR_COUNT; i++) {
            f->chars[i].y0 = (unsigned short)(f->chars[i].y0 + WHITE_ROWS);
            f->chars[i].y1 = (unsigned short)(f->chars[i].y1 + WHITE_ROWS);
        }
        memset(f->atlas, 255, (size_t)side * WHITE_ROWS);
        f->atlas_w = f->atlas_h = side;
        return f;
    }
    mr_fail(err, MR_ERR_NOMEM, "font atlas for %.0f px glyphs does not fit", (double)p.pixel_height);
    mr_ui_font_destroy(&f);
    return NULL;
}

void mr_ui_font_destroy(mr_ui_font **fp) {
    if (!fp || !*fp) return;
    free((*fp)->ttf);
    free((*fp)->atlas);
    free(*fp);
    *fp = NULL;
}

float mr_ui_font_height(const mr_ui_font *f) { return f ? f->pixel_height : 0.0f; }

float mr_ui_text_width(const mr_ui_font *f, const char *text, float height) {
    if (!f || !text) return 0.0f;
    float w = 0;
    for (const unsigned char *c = (const unsigned char *)text; *c; c++) {
        int k = *c >= FIRST_CHAR && *c < FIRST_CHAR + CHAR_COUNT ? *c - FIRST_CHAR : '?' - FIRST_CHAR;
        w += f->chars[k].xadvance;
    }
    return w * height / f->pixel_height;
}

void mr_ui_font_internal(const mr_ui_font *f, const uint8_t **atlas, int *w, int *h, float *white_u, float *white_v) {
    *atlas = f->atlas;
    *w = f->atlas_w;
    *h = f->atlas_h;
    /* The middle of the white rows: bilinear filtering stays fully white. */
    *white_u = 0.5f;
    *white_v = (WHITE_ROWS * 0.5f) / (float)f->atlas_h;
}

bool mr_ui_font_quad(const mr_ui_font *f, int ch, float *x, float y_baseline, float scale, float q[8]) {
    int k = ch >= FIRST_CHAR && ch < FIRST_CHAR + CHAR_COUNT ? ch - FIRST_CHAR : '?' - FIRST_CHAR;
    const stbtt_packedchar *b = &f->chars[k];
    float iw = 1.0f / (float)f->atlas_w, ih = 1.0f / (float)f->atlas_h;
    q[0] = *x + b->xoff * scale;
    q[1] = y_baseline + b->yoff * scale;
    q[2] = *x + b->xoff2 * scale;
    q[3] = y_baseline + b->yoff2 * scale;
    q[4] = b->x0 * iw;
    q[5] = b->y0 * ih;
    q[6] = b->x1 * iw;
    q[7] = b->y1 * ih;
    *x += b->xadvance * scale;
    return b->x1 > b->x0 && b->y1 > b->y0;
}

float mr_ui_font_ascent_px(const mr_ui_font *f) { return f->ascent; }
