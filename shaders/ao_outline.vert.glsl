// Outline volumes for corner masking (Park & Baek): every vertex pushed out
// along its integrated normal by the AO radius. In screen mode the radius
// grows with the vertex's depth (r = k z), like scheer's sampling radius.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_dir;             // integrated normal (mesh space)

layout(location = 0) uniform mat4 u_modelview;
layout(location = 1) uniform mat3 u_normal_mat;
layout(location = 2) uniform mat4 u_proj;
layout(location = 3) uniform int u_radius_mode; // 0 screen, 1 view
layout(location = 4) uniform float u_radius;    // view mode (scene units)
layout(location = 5) uniform float u_screen_k;  // screen mode

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
