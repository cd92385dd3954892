// Lambert + ambient shading of the G-buffer, with an optional Phong
// specular term (Scheer & Keutel's D1 is "standard Phong shading"): white
// highlights r = reflect(-l, n), (r . v)^shininess, viewer at infinity along
// the camera axis as in fixed-function OpenGL (camera frame: z forward).
#include "common.glsl"

#define MAX_LIGHTS 8
layout(location = 0) uniform int u_light_count;
layout(location = 1) uniform vec3 u_light_dir[MAX_LIGHTS];   // view space, towards the light
layout(location = 9) uniform vec3 u_light_color[MAX_LIGHTS];
layout(location = 17) uniform float u_ambient;
layout(location = 18) uniform vec3 u_background;              // linear
layout(location = 19) uniform int u_use_ao;                    // AO texture bound at 2
layout(location = 20) uniform float u_specular;                // 0 = Lambert only
layout(location = 21) uniform float u_shininess;

layout(binding = 0) uniform sampler2D u_albedo;
layout(binding = 1) uniform sampler2D u_normal;
layout(binding = 2) uniform sampler2D u_ao;      // ambient visibility, 1 = unoccluded

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
    for (int i = 0; i < u_light_count; i++) {
        float ndl = dot(n, u_light_dir[i]);
        light += u_light_color[i] * max(ndl, 0.0);
        if (u_specular > 0.0 && ndl > 0.0)
            spec += u_light_color[i] * pow(max(dot(reflect(-u_light_dir[i], n), to_viewer), 0.0), u_shininess);
    }
    o_color = vec4(albedo * light + u_specular * spec, 1.0);
}
