// Temporal accumulation of the AO. Each pixel's surface point is
// carried into the previous frame's camera (camera-relative: prev_from_cur
// is computed in double on the CPU), the history is fetched at the nearest
// previous pixel and kept only when its stored depth and normal agree with
// the carried point's (otherwise the pixel was disoccluded: its history
// restarts from this frame). The blend is a running mean over up to
// u_max_count frames, then exponential with weight 1 / u_max_count for the
// new frame: history outputs (AO, frames in it, view z) and the normal.
#include "mr_bindings.h"
#include "ao_common.glsl"

layout(location = MR_LOC_AO_INTR) uniform vec4 u_intr;
layout(location = MR_LOC_AO_FULL) uniform ivec2 u_full;
layout(location = MR_LOC_AO_NEAR) uniform float u_near;
layout(location = MR_LOC_TAA_PREV_FROM_CUR) uniform mat4 u_prev_from_cur;  // current view -> previous view (OpenCV axes)
layout(location = MR_LOC_TAA_PREV_INTR) uniform vec4 u_prev_intr;
layout(location = MR_LOC_TAA_HAVE_HISTORY) uniform int u_have_history;
layout(location = MR_LOC_TAA_MAX_COUNT) uniform float u_max_count;
layout(location = MR_LOC_TAA_DEPTH_TOL) uniform float u_depth_tol;          // relative
layout(location = MR_LOC_TAA_NORMAL_COS) uniform float u_normal_cos;

layout(binding = MR_TEX_AO_DEPTH) uniform sampler2D u_depth;
layout(binding = MR_TEX_AO_NORMAL) uniform sampler2D u_normal;
layout(binding = MR_TEX_AO_INPUT) uniform sampler2D u_ao;          // this frame's AO
layout(binding = MR_TEX_TAA_HISTORY) uniform sampler2D u_hist;     // ao, count, z
layout(binding = MR_TEX_TAA_HISTORY_N) uniform sampler2D u_hist_n; // normal (previous view axes)

layout(location = 0) out vec4 o_hist;
layout(location = 1) out vec4 o_n;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec3 P;
    if (!ao_view_pos(u_depth, u_depth, false, u_near, u_intr, px, P)) {
        o_hist = vec4(1.0, 0.0, 0.0, 1.0);          // sky: unoccluded, no history
        o_n = vec4(0.0);
        return;
    }
    vec3 n = ao_normal(u_normal, px, P);
    float cur = texelFetch(u_ao, px, 0).r;
    float cnt = 0.0, hist = 0.0;
    if (u_have_history != 0) {
        vec3 Pp = (u_prev_from_cur * vec4(P, 1.0)).xyz;
        if (Pp.z > 0.0) {
            vec2 uv = Pp.xy / Pp.z * u_prev_intr.xy + u_prev_intr.zw;
            ivec2 q = ivec2(floor(uv + 0.5));
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, u_full))) {
                vec4 h = texelFetch(u_hist, q, 0);
                vec3 hn = texelFetch(u_hist_n, q, 0).xyz;
                vec3 np = mat3(u_prev_from_cur) * n;
                bool depth_ok = h.b > 0.0 && abs(h.b - Pp.z) <= u_depth_tol * Pp.z;
                bool normal_ok = dot(hn, np) >= u_normal_cos;
                if (depth_ok && normal_ok && h.g > 0.0) {
                    cnt = min(h.g, u_max_count - 1.0);
                    hist = h.r;
                }
            }
        }
    }
    float ao = (cnt * hist + cur) / (cnt + 1.0);
    o_hist = vec4(isnan(ao) ? cur : ao, cnt + 1.0, P.z, 1.0);
    o_n = vec4(n, 0.0);
}
