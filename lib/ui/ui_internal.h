/* Private to lib/ui: what the draw list needs from the font. */
#ifndef MR_UI_INTERNAL_H
#define MR_UI_INTERNAL_H

#include "mr_ui.h"

/* The atlas and the atlas coordinates of an opaque white texel. */
void mr_ui_font_internal(const mr_ui_font *f, const uint8_t **atlas, int *w, int *h, float *white_u, float *white_v);
/* One glyph quad q = x0 y0 x1 y1 s0 t0 s1 t1 at pen position *x on the
 * baseline, scaled from the bake; advances *x. False for an empty glyph. */
bool mr_ui_font_quad(const mr_ui_font *f, int ch, float *x, float y_baseline, float scale, float q[8]);
/* Baseline below the top of a line, pixels at the baked height. */
float mr_ui_font_ascent_px(const mr_ui_font *f);

#endif
