// Joint bilateral upsampling of a half-resolution AO buffer: the four
// low-resolution texels around a full-resolution pixel, weighted bilinearly
// and by how well their G-buffer samples (taken at 2*j) agree with this
// pixel's depth plane and normal; so AO never leaks across silhouettes.
#include "mr_bindings.h"
#include "ao_common.glsl"

layout(location = MR_LOC_AO_INTR) uniform vec4 u_intr;
layout(location = MR_LOC_AO_FULL) uniform ivec2 u_full;
layout(location = MR_LOC_AO_STEP) uniform int u_step;     // 2
layout(location = MR_LOC_AO_NEAR) uniform float u_near;
layout(location = MR_LOC_AO_SIZE) uniform ivec2 u_ao_size;

layout(binding = MR_TEX_AO_DEPTH) uniform sampler2D u_depth;
layout(binding = MR_TEX_AO_NORMAL) uniform sampler2D u_normal;
layout(binding = MR_TEX_AO_POSITIONS) uniform sampler2D u_pos;
layout(binding = MR_TEX_AO_INPUT) uniform sampler2D u_ao;

layout(location = 0) out float o_ao;

void main() {
    ivec2 fp = ivec2(gl_FragCoord.xy);
    vec3 P;
    if (!ao_view_pos(u_depth, u_pos, false, u_near, u_intr, fp, P)) { o_ao = 1.0; return; }
    vec3 n = ao_normal(u_normal, fp, P);
    vec2 lp = vec2(fp) / float(u_step);              // low-res texel j sits at full pixel j * step
    ivec2 j0 = ivec2(floor(lp));
    vec2 f = lp - vec2(j0);
    float tol = 0.02 * P.z * float(u_step);
    float sum = 0.0, wsum = 0.0, best = 1.0, best_d = 1e30;
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 j = min(j0 + o, u_ao_size - 1);
        vec3 Q;
        if (!ao_view_pos(u_depth, u_pos, false, u_near, u_intr, j * u_step, Q)) continue;
        vec3 nq = ao_normal(u_normal, j * u_step, Q);
        float a = texelFetch(u_ao, j, 0).r;
        float dp = abs(dot(Q - P, n)) / tol;
        float bw = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y) + 1e-3;
        float w = bw * exp(-dp * dp) * pow(max(dot(n, nq), 0.0), 8.0);
        if (dp < best_d) { best_d = dp; best = a; }
        sum += w * a;
        wsum += w;
    }
    o_ao = wsum > 1e-5 ? clamp(sum / wsum, 0.0, 1.0) : best;
}
