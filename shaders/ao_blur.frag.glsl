// Separable depth- and normal-aware bilateral blur of the AO buffer. A tap
// counts by a Gaussian in pixels times how close it lies to the centre's
// tangent plane (relative to the centre's depth, so any scene scale and
// grazing planes blur alike) times the agreement of the normals.
#include "mr_bindings.h"
#include "ao_common.glsl"

layout(location = MR_LOC_AO_INTR) uniform vec4 u_intr;    // G-buffer intrinsics
layout(location = MR_LOC_AO_FULL) uniform ivec2 u_full;   // G-buffer size
layout(location = MR_LOC_AO_STEP) uniform int u_step;     // G-buffer pixels per AO pixel
layout(location = MR_LOC_AO_NEAR) uniform float u_near;
layout(location = MR_LOC_AO_BLUR_DIR) uniform ivec2 u_dir;    // (1,0) or (0,1)
layout(location = MR_LOC_AO_BLUR_RADIUS) uniform int u_radius;   // taps each side
layout(location = MR_LOC_AO_SIZE) uniform ivec2 u_ao_size;

layout(binding = MR_TEX_AO_DEPTH) uniform sampler2D u_depth;
layout(binding = MR_TEX_AO_NORMAL) uniform sampler2D u_normal;
layout(binding = MR_TEX_AO_POSITIONS) uniform sampler2D u_pos;  // unused here
layout(binding = MR_TEX_AO_INPUT) uniform sampler2D u_ao;

layout(location = 0) out float o_ao;

void main() {
    ivec2 ap = ivec2(gl_FragCoord.xy);
    vec3 P;
    if (!ao_view_pos(u_depth, u_pos, false, u_near, u_intr, ap * u_step, P)) { o_ao = 1.0; return; }
    vec3 n = ao_normal(u_normal, ap * u_step, P);
    float sigma = 0.5 * float(u_radius) + 0.5;
    float inv2s2 = 1.0 / (2.0 * sigma * sigma);
    float inv_tol = 1.0 / (0.02 * P.z * float(u_step));
    float sum = 0.0, wsum = 0.0;
    for (int i = -u_radius; i <= u_radius; i++) {
        ivec2 q = ap + u_dir * i;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, u_ao_size))) continue;
        vec3 Q;
        if (!ao_view_pos(u_depth, u_pos, false, u_near, u_intr, q * u_step, Q)) continue;
        vec3 nq = ao_normal(u_normal, q * u_step, Q);
        float dp = dot(Q - P, n) * inv_tol;
        // One exp for the spatial and plane terms; (n.nq)^8 by squaring.
        float c = max(dot(n, nq), 0.0);
        c *= c; c *= c; c *= c;
        float w = exp(-float(i * i) * inv2s2 - dp * dp) * c;
        float a = texelFetch(u_ao, q, 0).r;
        if (!(w > 0.0) || isnan(a)) continue;
        sum += w * a;
        wsum += w;
    }
    o_ao = wsum > 1e-6 ? clamp(sum / wsum, 0.0, 1.0) : texelFetch(u_ao, ap, 0).r;
}
