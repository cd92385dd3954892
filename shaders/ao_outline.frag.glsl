// Counts outline crossings behind the visible surface (the pass depth-tests
// farther than the G-buffer): +1 where the ray leaves an outline volume
// (the face looks away from the camera), -1 where it enters, so the sum is
// the number of volumes that hold the surface point, wherever the camera
// is. Facing is decided from the face's geometric normal oriented outwards
// by the extrusion direction, not from the winding, because CAD exports
// come with any winding. Additive blending sums the counts into a float
// target.
in vec3 v_pos;
in vec3 v_dir;
layout(location = 0) out float o_count;

void main() {
    vec3 nf = cross(dFdx(v_pos), dFdy(v_pos));
    if (dot(nf, v_dir) < 0.0) nf = -nf;
    o_count = dot(nf, v_pos) < 0.0 ? -1.0 : 1.0;
}
