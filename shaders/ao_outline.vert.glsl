// Outline volumes for corner masking (Park & Baek): every vertex moved by
// the AO radius times its miter offset (mr_mesh_outline: length >= 1 at
// edges and corners, so each face plane moves out by the whole radius).
// In screen mode the AO radius belongs to the shaded pixel (r = k z_pixel),
// not to the occluder: a pixel within k z_p of this vertex has
// z_p <= z_v / (1 - k), so the vertex moves by k z_v / (1 - k), the largest
// radius of any pixel that can reach it (k capped at 0.9: a radius that
// large masks almost nothing away anyway).
#include "mr_bindings.h"
layout(location = MR_ATTR_POSITION) in vec3 a_position;
layout(location = MR_ATTR_OUTLINE_DIR) in vec3 a_dir;             // miter offset per unit radius (mesh space)

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
    // Direction through the normal matrix, length kept: exact under rotation
    // and uniform scale (the miter is a sum of face normals).
    vec3 d = u_normal_mat * a_dir;
    float l = length(d);
    d = l > 0.0 ? d * (length(a_dir) / l) : vec3(0.0);
    float k = min(u_screen_k, 0.9);
    float r = u_radius_mode == 0 ? k * max(p.z, 0.0) / (1.0 - k) : u_radius;
    p.xyz += d * r;
    v_pos = p.xyz;
    v_dir = d;
    gl_Position = u_proj * p;
}
