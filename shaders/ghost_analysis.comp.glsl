// Contrast map (paper eq. 3 and section 3.2): where blending happens
// (0 < alpha < 1, in the region)
//   C_desired = max(tc_minimal, gamma * IM) + tc_silhouette on the hidden
//               structure's silhouette,
//   C = max(0, C_desired - S(G0)).
#include "mr_bindings.h"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_ANA_TC_MIN) uniform float u_tc_min;
layout(location = MR_LOC_ANA_GAMMA) uniform float u_gamma;
layout(location = MR_LOC_ANA_TC_SIL) uniform float u_tc_sil;
layout(binding = MR_TEX_ANA_MASK) uniform sampler2D u_mask;
layout(binding = MR_TEX_ANA_SAL) uniform sampler2D u_sal;   // S(G0)
layout(binding = MR_TEX_ANA_G0) uniform sampler2D u_g0;    // .a = alpha
layout(binding = MR_IMG_ANA_C, rgba32f) uniform writeonly image2D u_c;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_c);
    if (p.x >= n.x || p.y >= n.y) return;
    vec4 m = texelFetch(u_mask, p, 0);
    float a = texelFetch(u_g0, p, 0).a;
    float c = 0.0, want = 0.0;
    if (m.y > 0.5 && a > 0.0 && a < 1.0) {
        want = max(u_tc_min, u_gamma * m.x) + (m.z > 0.5 ? u_tc_sil : 0.0);
        c = max(0.0, want - texelFetch(u_sal, p, 0).r);
    }
    imageStore(u_c, p, vec4(c, want, 0.0, 1.0));
}
