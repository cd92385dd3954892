// Centre-surround saliency (Kalkofen et al. eq. 9, after Veas et al. and
// Itti et al.) on an L*a*b* image, per channel k in {L, a, b}:
//   c_k = sum_{c=0..2} sum_{s=c+2..c+4} (k_c - k_s) / p,   p = 7 levels,
// signed as in Veas et al. With u_printed, the levels as eq. 9 prints them:
//   c_k = sum_{n=0..2} sum_{m=n+2..n+4} (k_n - k_{n+m}) / p,  p = 9 levels. The saliency is the length of (c_L, c_a, c_b) in
// units of 100 L*, times u_gain.
//  impl 0: k_n read from the mip-mapped box pyramid (eq. 10 with a box f_p),
//          bilinear within level n (the paper's "few texture accesses").
//  impl 1: the two-Gaussian approximation: all positive terms together
//          (levels 0,1,2, three times each) as one Gaussian, all negative
//          terms (levels 2..6, or 2..8 printed) as another, so
//          c = 9 (G+ - G-) / p.
#include "mr_bindings.h"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_SAL_IMPL) uniform int u_impl;
layout(location = MR_LOC_SAL_GAIN) uniform float u_gain;
layout(location = MR_LOC_SAL_MAX_LEVEL) uniform int u_max_level;
layout(location = MR_LOC_SAL_PRINTED) uniform int u_printed;
layout(binding = MR_TEX_SAL_PYR) uniform sampler2D u_pyr;      // impl 0: Lab with mips; impl 1: G+ (Lab)
layout(binding = MR_TEX_SAL_SURROUND) uniform sampler2D u_surround; // impl 1: G- (Lab)
layout(binding = MR_IMG_SAL_DST, r32f) uniform writeonly image2D u_dst;
vec3 level(vec2 uv, int n) { return textureLod(u_pyr, uv, float(min(n, u_max_level))).rgb; }
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_dst);
    if (p.x >= n.x || p.y >= n.y) return;
    vec3 c = vec3(0.0);
    if (u_impl == 0) {
        vec2 uv = (vec2(p) + 0.5) / vec2(n);
        vec3 k[9];
        for (int i = 0; i < 9; i++) k[i] = level(uv, i);
        int shift = u_printed != 0 ? 1 : 0; // printed: surround n + m, m = n+2..n+4
        for (int cc = 0; cc <= 2; cc++)
            for (int s = cc + 2; s <= cc + 4; s++) c += k[cc] - k[s + shift * cc];
    } else {
        c = 9.0 * (texelFetch(u_pyr, p, 0).rgb - texelFetch(u_surround, p, 0).rgb);
    }
    c /= u_printed != 0 ? 9.0 : 7.0;
    imageStore(u_dst, p, vec4(u_gain * length(c) / 100.0));
}
