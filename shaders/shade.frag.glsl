// Lambert + ambient shading of the G-buffer, with an optional Phong
// specular term (Scheer & Keutel's D1 is "standard Phong shading"): white
// highlights r = reflect(-l, n), (r . v)^shininess, viewer at infinity along
// the camera axis as in fixed-function OpenGL (camera frame: z forward).
#include "mr_bindings.h"
#include "common.glsl"

#define MAX_LIGHTS MR_SHADE_MAX_LIGHTS
layout(location = MR_LOC_SHADE_LIGHT_COUNT) uniform int u_light_count;
layout(location = MR_LOC_SHADE_LIGHT_DIR) uniform vec3 u_light_dir[MAX_LIGHTS];   // view space, towards the light
layout(location = MR_LOC_SHADE_LIGHT_COLOR) uniform vec3 u_light_color[MAX_LIGHTS];
layout(location = MR_LOC_SHADE_AMBIENT) uniform float u_ambient;
layout(location = MR_LOC_SHADE_BACKGROUND) uniform vec3 u_background;              // linear
layout(location = MR_LOC_SHADE_HAVE_AO) uniform int u_use_ao;                    // AO texture bound at 2
layout(location = MR_LOC_SHADE_SPECULAR) uniform float u_specular;                // 0 = Lambert only
layout(location = MR_LOC_SHADE_SHININESS) uniform float u_shininess;
layout(location = MR_LOC_SHADE_SHADOW_LIGHT) uniform int u_shadow_light;            // -1: no shadows

layout(binding = MR_TEX_SHADE_ALBEDO) uniform sampler2D u_albedo;
layout(binding = MR_TEX_SHADE_NORMAL) uniform sampler2D u_normal;
layout(binding = MR_TEX_SHADE_AO) uniform sampler2D u_ao;      // ambient visibility, 1 = unoccluded
layout(binding = MR_TEX_SHADE_SHADOW) uniform sampler2D u_shadow; // visibility of light u_shadow_light

layout(location = 0) out vec4 o_color; // sRGB8 target

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 nn = texelFetch(u_normal, px, 0);
    if (nn.w == 0.0) { o_color = vec4(u_background, 1.0); return; }
    vec3 albedo = texelFetch(u_albedo, px, 0).rgb;
    vec3 n = nn.xyz;
    // AO is the visibility of the ambient (sky) light, so it scales only
    // the ambient term; direct light has its own (shadow) visibility.
    float ao = u_use_ao != 0 ? texelFetch(u_ao, px, 0).r : 1.0;
    vec3 light = vec3(u_ambient * ao);
    vec3 spec = vec3(0.0);
    const vec3 to_viewer = vec3(0.0, 0.0, -1.0);
    float sv = u_shadow_light >= 0 ? texelFetch(u_shadow, px, 0).r : 1.0;
    for (int i = 0; i < u_light_count; i++) {
        float ndl = dot(n, u_light_dir[i]);
        // Only the casting light's direct terms are shadowed; without
        // shadows this branch is never taken, so the image stays bit for bit.
        vec3 c = u_light_color[i];
        if (i == u_shadow_light) c *= sv;
        light += c * max(ndl, 0.0);
        if (u_specular > 0.0 && ndl > 0.0)
            spec += c * pow(max(dot(reflect(-u_light_dir[i], n), to_viewer), 0.0), u_shininess);
    }
    o_color = vec4(albedo * light + u_specular * spec, 1.0);
}
