// One direction of a separable Gaussian (clamp-to-edge), all four channels.
// The kernel is cut at u_radius and renormalised over what is kept, so a
// flat image stays exactly flat.
#include "mr_bindings.h"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_GBLUR_DIR) uniform ivec2 u_dir;
layout(location = MR_LOC_GBLUR_SIGMA) uniform float u_sigma;   // pixels
layout(location = MR_LOC_GBLUR_RADIUS) uniform int u_radius;
layout(binding = MR_TEX_GBLUR_SRC) uniform sampler2D u_src;
layout(binding = MR_IMG_GBLUR_DST, rgba32f) uniform writeonly image2D u_dst;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_dst);
    if (p.x >= n.x || p.y >= n.y) return;
    vec4 acc = vec4(0.0);
    float wsum = 0.0;
    float k = -0.5 / max(u_sigma * u_sigma, 1e-6);
    for (int i = -u_radius; i <= u_radius; i++) {
        ivec2 q = clamp(p + u_dir * i, ivec2(0), n - 1);
        float w = exp(k * float(i * i));
        acc += w * texelFetch(u_src, q, 0);
        wsum += w;
    }
    imageStore(u_dst, p, acc / wsum);
}
