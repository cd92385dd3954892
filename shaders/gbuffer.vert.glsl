// G-buffer geometry pass. Positions arrive relative to their mesh origin;
// u_modelview is camera-relative (composed in double on the CPU), so the
// float values here stay small however far the scene is from the origin.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;

layout(location = 0) uniform mat4 u_modelview;  // camera (OpenCV axes) from mesh
layout(location = 1) uniform mat3 u_normal_mat; // inverse transpose of its 3x3
layout(location = 2) uniform mat4 u_proj;       // reversed-Z, infinite far

out vec3 v_pos;     // view space, OpenCV axes
out vec3 v_normal;  // view space
out vec2 v_uv;

void main() {
    vec4 p = u_modelview * vec4(a_position, 1.0);
    v_pos = p.xyz;
    v_normal = u_normal_mat * a_normal;
    v_uv = a_uv;
    gl_Position = u_proj * p;
}
