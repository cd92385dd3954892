// The layered-rendering experiment: the G-buffer pass's vertex
// work for up to MR_RIG_LAYERED_MAX views of a rig in one instanced draw.
// The instance records are the centre camera's (attribute divisor = views):
// view v = gl_InstanceID % views only moves the point along the camera's x
// axis by its eye's shift and projects it with its own sheared frustum into
// its own viewport (a tile of the quilt).
#extension GL_ARB_shader_viewport_layer_array : require
#include "mr_bindings.h"
layout(location = MR_ATTR_POSITION) in vec3 a_position;
layout(location = MR_ATTR_INST_MODELVIEW) in mat4 a_modelview;

layout(location = MR_LOC_PROJECTION) uniform mat4 u_proj[MR_RIG_LAYERED_MAX];
layout(location = MR_LOC_RIG_SHIFT) uniform float u_shift[MR_RIG_LAYERED_MAX];
layout(location = MR_LOC_RIG_VIEWS) uniform int u_views;

void main() {
    int v = gl_InstanceID % u_views;
    vec4 p = a_modelview * vec4(a_position, 1.0);
    p.x -= u_shift[v];
    gl_Position = u_proj[v] * p;
    gl_ViewportIndex = v;
}
