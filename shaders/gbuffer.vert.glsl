// G-buffer geometry pass, instanced. Positions arrive relative to their mesh
// origin; each instance's model-view is camera-relative (composed in double
// on the CPU per instance, then cast to float), so the float values here stay
// small however far the scene is from the origin. The instance record comes
// in as per-instance attributes (the indirect command's baseInstance selects
// it), so one multi-draw covers many meshes and nodes.
#include "mr_bindings.h"
layout(location = MR_ATTR_POSITION) in vec3 a_position;
layout(location = MR_ATTR_NORMAL) in vec3 a_normal;
layout(location = MR_ATTR_UV) in vec2 a_uv;
layout(location = MR_ATTR_INST_MODELVIEW) in mat4 a_modelview;   // camera (OpenCV axes) from mesh; 3..6
layout(location = MR_ATTR_INST_NORMAL0) in vec4 a_normal0;     // columns of the inverse transpose
layout(location = MR_ATTR_INST_NORMAL1) in vec4 a_normal1;     // of the model-view's 3x3
layout(location = MR_ATTR_INST_NORMAL2) in vec4 a_normal2;
layout(location = MR_ATTR_INST_COLOR) in vec4 a_color;      // linear RGBA base colour
layout(location = MR_ATTR_INST_IDS) in uvec4 a_ids;       // node index + 1, layer, has texture

layout(location = MR_LOC_PROJECTION) uniform mat4 u_proj;   // reversed-Z, infinite far

out vec3 v_pos;     // view space, OpenCV axes
out vec3 v_normal;  // view space
out vec2 v_uv;
flat out vec4 v_color;
flat out uvec3 v_ids;

void main() {
    vec4 p = a_modelview * vec4(a_position, 1.0);
    v_pos = p.xyz;
    v_normal = mat3(a_normal0.xyz, a_normal1.xyz, a_normal2.xyz) * a_normal;
    v_uv = a_uv;
    v_color = a_color;
    v_ids = a_ids.xyz;
    gl_Position = u_proj * p;
}
