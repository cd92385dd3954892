// The fetch floor of a full-screen AO pass. Per pixel the same
// number of R32F texel fetches as an AO method's samples, at the same
// spread (the AO disk kernel scaled to the projected radius), and no other
// work than clamping the address and summing (so that no fetch can be
// optimised away). `bench ao` times it beside every AO row.
#include "mr_bindings.h"

layout(location = MR_LOC_PROBE_FETCHES) uniform int u_fetches;
layout(location = MR_LOC_PROBE_OFFSETS) uniform vec4 u_offsets[MR_AO_KERNEL_SIZE]; // xy: pixel offsets
layout(binding = MR_TEX_PROBE_SRC) uniform sampler2D u_src;

layout(location = 0) out float o_sum;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 hi = textureSize(u_src, 0) - 1;
    float s = 0.0;
    for (int i = 0; i < u_fetches; i++) s += texelFetch(u_src, clamp(p + ivec2(u_offsets[i].xy), ivec2(0), hi), 0).r;
    o_sum = s;
}
