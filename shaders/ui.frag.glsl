// 2D layer: mode 0 draws the UI (colour x atlas coverage, blended in sRGB
// space as UI toolkits do); mode 1 draws the renderer's finished frame,
// whose sRGB texture is decoded on sampling and re-encoded here because
// the window framebuffer is not assumed to be sRGB-capable.
#include "mr_bindings.h"
#include "common.glsl"

in vec2 v_uv;
in vec4 v_color;

layout(location = MR_LOC_UI_MODE) uniform int u_mode;
layout(binding = MR_TEX_UI_TEX) uniform sampler2D u_tex;

layout(location = 0) out vec4 o_color;

void main() {
    if (u_mode == 1) {
        o_color = vec4(linear_to_srgb(texture(u_tex, v_uv).rgb), 1.0);
    } else {
        float a = texture(u_tex, v_uv).r;
        o_color = vec4(v_color.rgb, v_color.a * a);
    }
}
