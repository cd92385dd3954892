// Counts outline crossings: +1 where the view ray enters an outline volume
// (the face looks at the camera), -1 where it leaves. Facing is decided
// from the face's geometric normal oriented outwards by the extrusion
// direction, not from the winding, because CAD exports come with any winding.
// Additive blending sums the counts into a float target.
in vec3 v_pos;
in vec3 v_dir;
layout(location = 0) out float o_count;

void main() {
    vec3 nf = cross(dFdx(v_pos), dFdy(v_pos));
    if (dot(nf, v_dir) < 0.0) nf = -nf;
    o_count = dot(nf, v_pos) < 0.0 ? 1.0 : -1.0;
}
