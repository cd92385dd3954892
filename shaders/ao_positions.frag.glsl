// View-space positions texture (xyz, w = 1 where geometry) for the AO
// path that reads positions instead of un-projecting depth: with it, AO
// needs only the forward projection of sample points.
#include "ao_common.glsl"

layout(location = 0) uniform vec4 u_intr;
layout(location = 3) uniform float u_near;
layout(binding = 0) uniform sampler2D u_depth;
layout(binding = 2) uniform sampler2D u_pos;

layout(location = 0) out vec4 o_pos;

void main() {
    vec3 P;
    bool ok = ao_view_pos(u_depth, u_pos, false, u_near, u_intr, ivec2(gl_FragCoord.xy), P);
    o_pos = ok ? vec4(P, 1.0) : vec4(0.0);
}
