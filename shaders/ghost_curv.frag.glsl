// Writes the interpolated curvature (drawn through mr_geometry_aux_draw,
// which sets only the model-view and normal matrices).
in float v_kappa;
layout(location = 0) out vec4 o_kappa;
void main() {
    o_kappa = vec4(v_kappa, 0.0, 0.0, 1.0);
}
