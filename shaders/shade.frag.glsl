// Lambert + ambient shading of the G-buffer.
#include "common.glsl"

#define MAX_LIGHTS 8
layout(location = 0) uniform int u_light_count;
layout(location = 1) uniform vec3 u_light_dir[MAX_LIGHTS];   // view space, towards the light
layout(location = 9) uniform vec3 u_light_color[MAX_LIGHTS];
layout(location = 17) uniform float u_ambient;
layout(location = 18) uniform vec3 u_background;              // linear

layout(binding = 0) uniform sampler2D u_albedo;
layout(binding = 1) uniform sampler2D u_normal;

layout(location = 0) out vec4 o_color; // sRGB8 target

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 nn = texelFetch(u_normal, px, 0);
    if (nn.w == 0.0) { o_color = vec4(u_background, 1.0); return; }
    vec3 albedo = texelFetch(u_albedo, px, 0).rgb;
    vec3 n = nn.xyz;
    vec3 light = vec3(u_ambient);
    for (int i = 0; i < u_light_count; i++)
        light += u_light_color[i] * max(dot(n, u_light_dir[i]), 0.0);
    o_color = vec4(albedo * light, 1.0);
}
