// Connected regions of the video occluder (region pixels without a model
// occluder), for the one-sign-per-object rule: u_init writes each such
// pixel's own index + 1; every further step takes the smallest label of the
// 4-neighbourhood and then jumps to the label of the pixel that label names
// (pointer jumping), so long regions converge in few steps.
#include "mr_bindings.h"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_LABEL_INIT) uniform int u_init;
layout(binding = MR_TEX_LABEL_MASK) uniform sampler2D u_mask;
layout(binding = MR_TEX_LABEL_KEY) uniform usampler2D u_key;
layout(binding = MR_TEX_LABEL_SRC) uniform usampler2D u_src;
layout(binding = MR_IMG_LABEL_DST, r32ui) uniform writeonly uimage2D u_dst;
bool member(ivec2 q) { return texelFetch(u_mask, q, 0).y > 0.5 && texelFetch(u_key, q, 0).x == 0u; }
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_dst);
    if (p.x >= n.x || p.y >= n.y) return;
    if (!member(p)) { imageStore(u_dst, p, uvec4(0u)); return; }
    if (u_init != 0) { imageStore(u_dst, p, uvec4(uint(p.y * n.x + p.x) + 1u)); return; }
    uint l = texelFetch(u_src, p, 0).x;
    const ivec2 off[4] = ivec2[](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    for (int i = 0; i < 4; i++) {
        ivec2 q = p + off[i];
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, n))) continue;
        uint lq = texelFetch(u_src, q, 0).x;
        if (lq != 0u) l = min(l, lq);
    }
    uint idx = l - 1u;
    uint lj = texelFetch(u_src, ivec2(int(idx % uint(n.x)), int(idx / uint(n.x))), 0).x;
    if (lj != 0u) l = min(l, lj);
    imageStore(u_dst, p, uvec4(l));
}
