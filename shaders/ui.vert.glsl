// 2D layer: vertices in framebuffer pixels (origin top-left), turned into
// clip space here so the CPU side never needs to know the window size.
#include "mr_bindings.h"
layout(location = MR_ATTR_UI_POS) in vec2 a_pos;
layout(location = MR_ATTR_UI_UV) in vec2 a_uv;
layout(location = MR_ATTR_UI_COLOR) in vec4 a_color;   // sRGB bytes, normalised

layout(location = MR_LOC_UI_FB_SIZE) uniform vec2 u_fb_size;

out vec2 v_uv;
out vec4 v_color;

void main() {
    v_uv = a_uv;
    v_color = a_color;
    vec2 ndc = a_pos / u_fb_size * 2.0 - 1.0;
    gl_Position = vec4(ndc.x, -ndc.y, 0.0, 1.0);
}
