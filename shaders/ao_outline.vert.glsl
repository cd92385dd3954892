// Outline volumes for corner masking (Park & Baek): every vertex pushed out
// along its integrated normal by the AO radius. In screen mode the radius
// grows with the vertex's depth (r = k z), like scheer's sampling radius.
#include "mr_bindings.h"
layout(location = MR_ATTR_POSITION) in vec3 a_position;
layout(location = MR_ATTR_OUTLINE_DIR) in vec3 a_dir;             // integrated normal (mesh space)

layout(location = MR_LOC_MODELVIEW) uniform mat4 u_modelview;
layout(location = MR_LOC_NORMAL_MATRIX) uniform mat3 u_normal_mat;
layout(location = MR_LOC_PROJECTION) uniform mat4 u_proj;
layout(location = MR_LOC_OUTLINE_RADIUS_MODE) uniform int u_radius_mode; // 0 screen, 1 view
layout(location = MR_LOC_OUTLINE_RADIUS) uniform float u_radius;    // view mode (scene units)
layout(location = MR_LOC_OUTLINE_SCREEN_K) uniform float u_screen_k;  // screen mode

out vec3 v_pos;
out vec3 v_dir;

void main() {
    vec4 p = u_modelview * vec4(a_position, 1.0);
    vec3 d = u_normal_mat * a_dir;
    float l = length(d);
    d = l > 0.0 ? d / l : vec3(0.0);
    float r = u_radius_mode == 0 ? u_screen_k * max(p.z, 0.0) : u_radius;
    p.xyz += d * r;
    v_pos = p.xyz;
    v_dir = d;
    gl_Position = u_proj * p;
}
