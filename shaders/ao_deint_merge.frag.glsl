// AO pixel 4 t + o back from texel t of tile o of
// the AO atlas, so the blur and upsample see an ordinary AO image.
#include "mr_bindings.h"

layout(binding = MR_TEX_AO_DEINT_SRC) uniform sampler2D u_src;
layout(location = MR_LOC_AO_DEINT_SPLIT_Q) uniform ivec2 u_q;

layout(location = 0) out float o_ao;

void main() {
    ivec2 ap = ivec2(gl_FragCoord.xy);
    ivec2 o = ap & 3, t = ap >> 2;
    o_ao = texelFetch(u_src, o * u_q + t, 0).r;
}
