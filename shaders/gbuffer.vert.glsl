// G-buffer geometry pass, instanced. Positions arrive relative to their mesh
// origin; each instance's model-view is camera-relative (composed in double
// on the CPU per instance, then cast to float), so the float values here stay
// small however far the scene is from the origin. Per-instance data lives in
// an SSBO indexed by a per-instance attribute (the indirect command's
// baseInstance offsets it), so one multi-draw covers many meshes and nodes.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in uint a_instance;

layout(location = 2) uniform mat4 u_proj;       // reversed-Z, infinite far

struct Instance {
    mat4 modelview;   // camera (OpenCV axes) from mesh
    vec4 normal[3];   // columns of the inverse transpose of its 3x3
    vec4 color;       // linear RGBA base colour
    uvec4 ids;        // node index + 1, layer, has texture, unused
};
layout(std430, binding = 0) readonly buffer Instances { Instance u_inst[]; };

out vec3 v_pos;     // view space, OpenCV axes
out vec3 v_normal;  // view space
out vec2 v_uv;
flat out vec4 v_color;
flat out uvec3 v_ids;

void main() {
    Instance I = u_inst[a_instance];
    vec4 p = I.modelview * vec4(a_position, 1.0);
    v_pos = p.xyz;
    v_normal = mat3(I.normal[0].xyz, I.normal[1].xyz, I.normal[2].xyz) * a_normal;
    v_uv = a_uv;
    v_color = I.color;
    v_ids = I.ids.xyz;
    gl_Position = u_proj * p;
}
