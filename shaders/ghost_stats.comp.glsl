// Legibility measure for the bench: over the region, the important pixels
// (IM > 0.3, above the flat-wall bias) whose saliency in the final image reaches
// C_desired = max(tc_minimal, gamma * IM) (+ tc_silhouette on silhouettes),
// and the mean |L*(O_A) - L*(O)|. Sums in fixed point (1/256; 1/16 for L*).
#include "mr_bindings.h"
#include "ghost_lab.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_STATS_TC_MIN) uniform float u_tc_min;
layout(location = MR_LOC_STATS_GAMMA) uniform float u_gamma;
layout(location = MR_LOC_STATS_TC_SIL) uniform float u_tc_sil;
layout(binding = MR_TEX_STATS_MASK) uniform sampler2D u_mask;
layout(binding = MR_TEX_STATS_SAL) uniform sampler2D u_sal;   // S(final)
layout(binding = MR_TEX_STATS_O) uniform sampler2D u_o;
layout(binding = MR_TEX_STATS_OA) uniform sampler2D u_oa;
layout(binding = MR_TEX_STATS_C) uniform sampler2D u_c;     // C in .r
layout(std430, binding = MR_SSBO_STATS_SUMS) buffer Sums { uint region; uint important; uint legible; uint im_sum; uint dl_sum; uint c_sum; };
// Per-workgroup sums in shared memory, then one global atomic each.
shared uint s_sums[6];

void count(ivec2 p, ivec2 n) {
    vec4 m = texelFetch(u_mask, p, 0);
    if (m.y < 0.5) return;
    atomicAdd(s_sums[0], 1u);
    atomicAdd(s_sums[3], uint(m.x * 256.0 + 0.5));
    atomicAdd(s_sums[5], uint(clamp(texelFetch(u_c, p, 0).r, 0.0, 4.0) * 256.0 + 0.5));
    float dl = abs(rgb_to_lab(texelFetch(u_oa, p, 0).rgb).x - rgb_to_lab(texelFetch(u_o, p, 0).rgb).x);
    atomicAdd(s_sums[4], uint(min(dl, 100.0) * 16.0 + 0.5)); // 1/16 L*: no overflow at 4K
    if (m.x > 0.3) {
        atomicAdd(s_sums[1], 1u);
        float want = max(u_tc_min, u_gamma * m.x) + (m.z > 0.5 ? u_tc_sil : 0.0);
        if (texelFetch(u_sal, p, 0).r >= want) atomicAdd(s_sums[2], 1u);
    }
}

void main() {
    if (gl_LocalInvocationIndex < 6u) s_sums[gl_LocalInvocationIndex] = 0u;
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = textureSize(u_mask, 0);
    if (p.x < n.x && p.y < n.y) count(p, n);
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        atomicAdd(region, s_sums[0]);
        atomicAdd(important, s_sums[1]);
        atomicAdd(legible, s_sums[2]);
        atomicAdd(im_sum, s_sums[3]);
        atomicAdd(dl_sum, s_sums[4]);
        atomicAdd(c_sum, s_sums[5]);
    }
}
