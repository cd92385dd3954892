// The backprojection's hierarchical shadow map (Guennebaud et al. 2006):
// per map tile a pyramid of (min, max) light depth, level l's texel the
// 2^l x 2^l block of map texels under it. A tile's pyramid is P = the next
// power of two of the map's side, so every level halves exactly; the
// texels past the map (and the map's own empty texels, cleared far) hold
// the far depth: they never block.
#include "mr_bindings.h"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_SHADOW_MM_LEVEL) uniform int u_level;  // the level written
layout(location = MR_LOC_SHADOW_MM_SIZE) uniform int u_size;    // S: a tile's map side
layout(location = MR_LOC_SHADOW_MM_PYR) uniform int u_pyr;      // P: a tile's pyramid side at level 0
layout(binding = MR_TEX_SHADOW_MM_MAP) uniform sampler2D u_map; // R32F light depth (the atlas)
layout(binding = MR_IMG_SHADOW_MM_SRC, rg32f) uniform readonly image2D u_src;   // level - 1
layout(binding = MR_IMG_SHADOW_MM_DST, rg32f) uniform writeonly image2D u_dst;  // level
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_dst);
    if (p.x >= n.x || p.y >= n.y) return;
    vec2 mm;
    if (u_level == 0) {
        ivec2 tile = p / u_pyr, loc = p - tile * u_pyr;
        float z = all(lessThan(loc, ivec2(u_size))) ? texelFetch(u_map, tile * u_size + loc, 0).r : 1e30;
        mm = vec2(z);
    } else {
        ivec2 q = 2 * p;
        vec2 a = imageLoad(u_src, q).rg, b = imageLoad(u_src, q + ivec2(1, 0)).rg;
        vec2 c = imageLoad(u_src, q + ivec2(0, 1)).rg, d = imageLoad(u_src, q + ivec2(1, 1)).rg;
        mm = vec2(min(min(a.x, b.x), min(c.x, d.x)), max(max(a.y, b.y), max(c.y, d.y)));
    }
    imageStore(u_dst, p, vec4(mm, 0.0, 0.0));
}
