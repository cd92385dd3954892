// Legibility measure for the bench: over the region, the important pixels
// (IM > 0.3, above the flat-wall bias) whose saliency in the final image reaches
// C_desired = max(tc_minimal, gamma * IM) (+ tc_silhouette on silhouettes),
// and the mean |L*(O_A) - L*(O)|. Sums in fixed point (1/256; 1/16 for L*).
#include "ghost_lab.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = 0) uniform float u_tc_min;
layout(location = 1) uniform float u_gamma;
layout(location = 2) uniform float u_tc_sil;
layout(binding = 0) uniform sampler2D u_mask;
layout(binding = 1) uniform sampler2D u_sal;   // S(final)
layout(binding = 2) uniform sampler2D u_o;
layout(binding = 3) uniform sampler2D u_oa;
layout(binding = 4) uniform sampler2D u_c;     // C in .r
layout(std430, binding = 2) buffer Sums { uint region; uint important; uint legible; uint im_sum; uint dl_sum; uint c_sum; };
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = textureSize(u_mask, 0);
    if (p.x >= n.x || p.y >= n.y) return;
    vec4 m = texelFetch(u_mask, p, 0);
    if (m.y < 0.5) return;
    atomicAdd(region, 1u);
    atomicAdd(im_sum, uint(m.x * 256.0 + 0.5));
    atomicAdd(c_sum, uint(clamp(texelFetch(u_c, p, 0).r, 0.0, 4.0) * 256.0 + 0.5));
    float dl = abs(rgb_to_lab(texelFetch(u_oa, p, 0).rgb).x - rgb_to_lab(texelFetch(u_o, p, 0).rgb).x);
    atomicAdd(dl_sum, uint(min(dl, 100.0) * 16.0 + 0.5)); // 1/16 L*: no overflow at 4K
    if (m.x > 0.3) {
        atomicAdd(important, 1u);
        float want = max(u_tc_min, u_gamma * m.x) + (m.z > 0.5 ? u_tc_sil : 0.0);
        if (texelFetch(u_sal, p, 0).r >= want) atomicAdd(legible, 1u);
    }
}
