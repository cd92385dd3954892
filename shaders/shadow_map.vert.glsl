// Shadow map: the scene seen from the casting light, linear light-space
// depth. Positions arrive camera (= light eye) relative from the shared
// instance records, composed in double on the CPU, so the floats stay small
// at any offset. Perspective lights (rect, sphere) project with u_proj like
// any view; the sun projects orthographically onto the fitted rectangle.
// Ground-truth samples move the eye (u_offset, perspective) or shear the
// projection direction (u_shear, sun): the frustum is translated, never
// rotated, so every sample map shares the receiver's parametrisation.
#include "mr_bindings.h"
layout(location = MR_ATTR_POSITION) in vec3 a_position;
layout(location = MR_ATTR_INST_MODELVIEW) in mat4 a_modelview;   // light eye (OpenCV axes) from mesh

layout(location = MR_LOC_PROJECTION) uniform mat4 u_proj;          // perspective lights
layout(location = MR_LOC_SHADOW_MAP_ORTHO) uniform int u_ortho;
layout(location = MR_LOC_SHADOW_MAP_RECT) uniform vec4 u_rect;     // ortho: x0, y0, 1/wx, 1/wy
layout(location = MR_LOC_SHADOW_MAP_DEPTH) uniform vec2 u_depth;   // ortho: z0, 1/(z1 - z0)
layout(location = MR_LOC_SHADOW_MAP_OFFSET) uniform vec3 u_offset; // sample eye offset (light axes)
layout(location = MR_LOC_SHADOW_MAP_SHEAR) uniform vec2 u_shear;   // sun sample: dx/dz, dy/dz

out float v_z;

void main() {
    vec3 p = (a_modelview * vec4(a_position, 1.0)).xyz - u_offset;
    p.xy -= u_shear * p.z;
    v_z = p.z;
    if (u_ortho == 0)
        gl_Position = u_proj * vec4(p, 1.0);
    else // reversed: nearer the light is larger, like the perspective depth
        gl_Position = vec4((p.xy - u_rect.xy) * u_rect.zw * 2.0 - 1.0, 1.0 - (p.z - u_depth.x) * u_depth.y, 1.0);
}
