in vec3 v_pos;
in vec3 v_normal;
in vec2 v_uv;
flat in vec4 v_color;   // linear RGBA
flat in uvec3 v_ids;    // node index + 1, layer, has texture

#include "mr_bindings.h"
layout(binding = MR_TEX_GBUFFER_BASE_COLOR) uniform sampler2D u_base_tex; // sRGB texture: sampled linear
layout(location = MR_LOC_GBUFFER_POS_OFFSET) uniform vec3 u_pos_offset;   // this band's eye in the frame camera (display mapping)

layout(location = MR_OUT_GBUFFER_ALBEDO) out vec4 o_albedo;  // sRGB8 target: linear in, encoded on write
layout(location = MR_OUT_GBUFFER_NORMAL) out vec4 o_normal;  // xyz view normal, w = 1 where geometry
layout(location = MR_OUT_GBUFFER_IDS) out uvec2 o_ids;
layout(location = MR_OUT_GBUFFER_POSITIONS) out vec4 o_pos;    // view-space position, w = 1 (AO positions path)

void main() {
    vec4 c = v_color;
    if (v_ids.z != 0u) c *= texture(u_base_tex, v_uv);
    vec3 n = normalize(v_normal);
    // CAD exports have arbitrary winding and open shells: light both sides
    // by turning the normal towards the camera (which sits at the origin).
    if (dot(n, v_pos) > 0.0) n = -n;
    if (any(isnan(n))) n = normalize(-v_pos);
    o_albedo = vec4(c.rgb, 1.0);
    o_normal = vec4(n, 1.0);
    o_ids = v_ids.xy;
    o_pos = vec4(v_pos + u_pos_offset, 1.0);
}
