/* Rectangles, RectCut layout and the draw list. */
#include "ui_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool mr_ui_rect_contains(mr_ui_rect r, float px, float py) {
    return px >= r.x && px < r.x + r.w && py >= r.y && py < r.y + r.h;
}

mr_ui_rect mr_ui_rect_inset(mr_ui_rect r, float d) {
    float dx = d * 2 > r.w ? r.w * 0.5f : d, dy = d * 2 > r.h ? r.h * 0.5f : d;
    return mr_ui_rect_make(r.x + dx, r.y + dy, r.w - 2 * dx, r.h - 2 * dy);
}

static float clampf(float v, float lo, float hi) { return v < lo ? lo : v > hi ? hi : v; }

mr_ui_rect mr_ui_cut_left(mr_ui_rect *r, float a) {
    a = clampf(a, 0, r->w);
    mr_ui_rect out = mr_ui_rect_make(r->x, r->y, a, r->h);
    r->x += a;
    r->w -= a;
    return out;
}

mr_ui_rect mr_ui_cut_right(mr_ui_rect *r, float a) {
    a = clampf(a, 0, r->w);
    r->w -= a;
    return mr_ui_rect_make(r->x + r->w, r->y, a, r->h);
}

mr_ui_rect mr_ui_cut_top(mr_ui_rect *r, float a) {
    a = clampf(a, 0, r->h);
    mr_ui_rect out = mr_ui_rect_make(r->x, r->y, r->w, a);
    r->y += a;
    r->h -= a;
    return out;
}

mr_ui_rect mr_ui_cut_bottom(mr_ui_rect *r, float a) {
    a = clampf(a, 0, r->h);
    r->h -= a;
    return mr_ui_rect_make(r->x, r->y + r->h, r->w, a);
}

mr_ui_rect mr_ui_fit(mr_ui_rect area, double w, double h) {
    if (!(w > 0) || !(h > 0) || !(area.w > 0) || !(area.h > 0)) return area;
    double s = fmin(area.w / w, area.h / h);
    float fw = (float)(w * s), fh = (float)(h * s);
    return mr_ui_rect_make(area.x + (area.w - fw) * 0.5f, area.y + (area.h - fh) * 0.5f, fw, fh);
}

static bool reserve(mr_ui_draw_list *dl, int nv, int ni) {
    if (dl->vertex_count + nv > dl->vertex_cap) {
        int cap = dl->vertex_cap ? dl->vertex_cap * 2 : 1024;
        while (cap < dl->vertex_count + nv) cap *= 2;
        mr_ui_vertex *v = realloc(dl->vertices, (size_t)cap * sizeof *v);
        if (!v) return false;
        dl->vertices = v;
        dl->vertex_cap = cap;
    }
    if (dl->index_count + ni > dl->index_cap) {
        int cap = dl->index_cap ? dl->index_cap * 2 : 1536;
        while (cap < dl->index_count + ni) cap *= 2;
        uint32_t *ix = realloc(dl->indices, (size_t)cap * sizeof *ix);
        if (!ix) return false;
        dl->indices = ix;
        dl->index_cap = cap;
    }
    return true;
}

/* Axis-aligned quad with atlas coordinates (s0,t0)-(s1,t1). */
static bool quad(mr_ui_draw_list *dl, float x0, float y0, float x1, float y1, float s0, float t0, float s1, float t1,
                 uint32_t rgba) {
    if (!reserve(dl, 4, 6)) return false;
    uint32_t b = (uint32_t)dl->vertex_count;
    mr_ui_vertex *v = dl->vertices + dl->vertex_count;
    v[0] = (mr_ui_vertex){x0, y0, s0, t0, rgba};
    v[1] = (mr_ui_vertex){x1, y0, s1, t0, rgba};
    v[2] = (mr_ui_vertex){x1, y1, s1, t1, rgba};
    v[3] = (mr_ui_vertex){x0, y1, s0, t1, rgba};
    uint32_t *ix = dl->indices + dl->index_count;
    ix[0] = b; ix[1] = b + 1; ix[2] = b + 2;
    ix[3] = b; ix[4] = b + 2; ix[5] = b + 3;
    dl->vertex_count += 4;
    dl->index_count += 6;
    return true;
}

/* Solid shapes sample the atlas's white texel (white_u, white_v). */

bool mr_ui_draw_rect(mr_ui_draw_list *dl, mr_ui_rect r, uint32_t rgba) {
    if (!(r.w > 0) || !(r.h > 0)) return true;
    return quad(dl, r.x, r.y, r.x + r.w, r.y + r.h, dl->white_u, dl->white_v, dl->white_u, dl->white_v, rgba);
}

bool mr_ui_draw_frame(mr_ui_draw_list *dl, mr_ui_rect r, float t, uint32_t rgba) {
    if (t * 2 >= r.w || t * 2 >= r.h) return mr_ui_draw_rect(dl, r, rgba);
    return mr_ui_draw_rect(dl, mr_ui_rect_make(r.x, r.y, r.w, t), rgba) &&
           mr_ui_draw_rect(dl, mr_ui_rect_make(r.x, r.y + r.h - t, r.w, t), rgba) &&
           mr_ui_draw_rect(dl, mr_ui_rect_make(r.x, r.y + t, t, r.h - 2 * t), rgba) &&
           mr_ui_draw_rect(dl, mr_ui_rect_make(r.x + r.w - t, r.y + t, t, r.h - 2 * t), rgba);
}

bool mr_ui_draw_text(mr_ui_draw_list *dl, const mr_ui_font *font, float x, float y, float height, const char *text,
                     uint32_t rgba) {
    if (!font || !text) return true;
    float scale = height / mr_ui_font_height(font);
    /* Snap the baseline to whole pixels: crisper glyphs at 1:1 scale. */
    float base = floorf(y + mr_ui_font_ascent_px(font) * scale + 0.5f);
    float pen = floorf(x + 0.5f);
    for (const unsigned char *c = (const unsigned char *)text; *c; c++) {
        float q[8];
        if (mr_ui_font_quad(font, *c, &pen, base, scale, q) && !quad(dl, q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], rgba))
            return false;
    }
    return true;
}

void mr_ui_draw_list_clear(mr_ui_draw_list *dl) {
    dl->vertex_count = 0;
    dl->index_count = 0;
}

void mr_ui_draw_list_free(mr_ui_draw_list *dl) {
    if (!dl) return;
    free(dl->vertices);
    free(dl->indices);
    memset(dl, 0, sizeof *dl);
}
