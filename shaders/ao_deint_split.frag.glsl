// The depth atlas of deinterleaved AO. Tile (ox, oy)
// of the 4x4 tiles holds the AO pixels 4 t + (ox, oy): one layer's samples
// then read a quarter-size, contiguous block (cache-coherent), which is
// what interleaved rendering buys (Bavoil & Jansen, deinterleaved texturing).
#include "mr_bindings.h"

layout(binding = MR_TEX_AO_DEINT_SRC) uniform sampler2D u_src;
layout(location = MR_LOC_AO_DEINT_SPLIT_Q) uniform ivec2 u_q;
layout(location = MR_LOC_AO_DEINT_SPLIT_STEP) uniform int u_step;
layout(location = MR_LOC_AO_DEINT_SPLIT_FULL) uniform ivec2 u_full;

layout(location = 0) out float o_d;

void main() {
    ivec2 a = ivec2(gl_FragCoord.xy);
    ivec2 o = a / u_q, t = a - o * u_q;
    ivec2 fp = (4 * t + o) * u_step;
    // past the image's edge (the last layers' extra texel): 0 is sky
    o_d = all(lessThan(fp, u_full)) ? texelFetch(u_src, fp, 0).r : 0.0;
}
