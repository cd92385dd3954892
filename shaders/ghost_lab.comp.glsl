// Whole-image conversion linear RGB <-> L*a*b* (u_inverse), into rgba32f.
#include "mr_bindings.h"
#include "ghost_lab.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_LAB_INVERSE) uniform int u_inverse;
layout(binding = MR_TEX_LAB_SRC) uniform sampler2D u_src;       // linear RGB (or Lab when inverse)
layout(binding = MR_IMG_LAB_DST, rgba32f) uniform writeonly image2D u_dst;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_dst);
    if (p.x >= n.x || p.y >= n.y) return;
    vec3 c = texelFetch(u_src, p, 0).rgb;
    imageStore(u_dst, p, vec4(u_inverse != 0 ? lab_to_rgb(c) : rgb_to_lab(c), 1.0));
}
