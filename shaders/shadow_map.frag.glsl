// Linear light-space depth (scene units along the light's axis) into R32F.
in float v_z;
layout(location = 0) out float o_z;
void main() { o_z = v_z; }
