// Writes the interpolated curvature. The G-buffer uniforms that
// mr_geometry_draw sets (colour, texture flag, ids) are kept alive by
// conditions that never hold, so that setting them is not a GL error.
in float v_kappa;
layout(location = 3) uniform vec4 u_base_color;
layout(location = 4) uniform int u_has_texture;
layout(location = 5) uniform uvec2 u_ids;
layout(location = 0) out vec4 o_kappa;
void main() {
    float k = v_kappa;
    if (u_has_texture == -12345 || u_ids.y == 12345u || u_base_color.a == -12345.0) k = 0.0;
    o_kappa = vec4(k, 0.0, 0.0, 1.0);
}
