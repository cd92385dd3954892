// Curvature pass of the occluder (visible layer): the same transform as the
// G-buffer (uniform locations 0-2 set by mr_geometry_draw), plus the mesh's
// per-vertex principal curvature (attribute 3, 1/mesh units).
#include "mr_bindings.h"
layout(location = MR_ATTR_POSITION) in vec3 a_position;
layout(location = MR_ATTR_CURVATURE) in float a_kappa;

layout(location = MR_LOC_MODELVIEW) uniform mat4 u_modelview;
layout(location = MR_LOC_NORMAL_MATRIX) uniform mat3 u_normal_mat;
layout(location = MR_LOC_PROJECTION) uniform mat4 u_proj;

out float v_kappa; // 1/view units

void main() {
    vec4 p = u_modelview * vec4(a_position, 1.0);
    // Curvature scales with 1/length: divide by the node's (mean) scale.
    float s = pow(abs(determinant(mat3(u_modelview))), 1.0 / 3.0);
    v_kappa = a_kappa / max(s, 1e-30);
    // mr_geometry_draw sets the normal matrix; keep the uniform alive so
    // that setting it is not an error (it is never this value).
    if (u_normal_mat[2][2] == -12345.0) v_kappa = 0.0;
    gl_Position = u_proj * p;
}
