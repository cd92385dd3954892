// Initial ghosted view G0 = O*alpha + D*(1-alpha) (paper eq. 2).
//  region:              alpha = t * IM, or for mode alpha t * mean(IM)
//  D visible, unoccluded: alpha = 0 (D as it is)
//  elsewhere:           alpha = 1 (O as it is)
// Writes G0 (linear, alpha in .a) and the finished sRGB image.
#include "mr_bindings.h"
#include "ghost_lab.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_G0_MODE) uniform int u_mode;   // 1 alpha, 2 g0, 3 adaptive
layout(location = MR_LOC_G0_T) uniform float u_t;
layout(binding = MR_TEX_G0_O) uniform sampler2D u_o;     // occluder, linear
layout(binding = MR_TEX_G0_D) uniform sampler2D u_d;     // occludee, linear
layout(binding = MR_TEX_G0_MASK) uniform sampler2D u_mask;
layout(binding = MR_IMG_G0_G0, rgba32f) uniform writeonly image2D u_g0;
layout(binding = MR_IMG_G0_OUT, rgba8) uniform writeonly image2D u_out; // storage of an sRGB view: encoded here
layout(std430, binding = MR_SSBO_G0_STATS) buffer Stats { uint im_sum; uint im_count; };
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_g0);
    if (p.x >= n.x || p.y >= n.y) return;
    vec4 m = texelFetch(u_mask, p, 0);
    float a;
    if (m.y > 0.5) {
        float im = u_mode == 1 ? (im_count > 0u ? float(im_sum) / (256.0 * float(im_count)) : 0.0) : m.x;
        a = clamp(u_t * im, 0.0, 1.0);
    } else {
        a = m.w > 0.5 ? 0.0 : 1.0;
    }
    vec3 o = texelFetch(u_o, p, 0).rgb, d = texelFetch(u_d, p, 0).rgb;
    vec3 g = o * a + d * (1.0 - a);
    imageStore(u_g0, p, vec4(g, a));
    imageStore(u_out, p, vec4(ghost_linear_to_srgb(g), 1.0));
}
