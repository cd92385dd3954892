// Video overlay: the raw (distorted) camera frame is undistorted on the fly
// by mapping every pixel of the ideal pinhole image through the OpenCV
// distortion model, then blended with the virtual image:
//   out = mix(virtual, video, alpha)   (alpha 0 = virtual only, 1 = video only)
// Blending happens in linear light; both inputs are sRGB textures.
#include "mr_bindings.h"
#include "common.glsl"

layout(location = MR_LOC_OVERLAY_OUT_K) uniform vec4 u_intr;        // fx fy cx cy of the output image
layout(location = MR_LOC_OVERLAY_VIDEO_K) uniform vec4 u_video_intr;  // fx fy cx cy of the video frame
layout(location = MR_LOC_OVERLAY_VIDEO_SIZE) uniform vec2 u_video_size;  // pixels
layout(location = MR_LOC_OVERLAY_DIST) uniform float u_dist[5];    // k1 k2 p1 p2 k3
layout(location = MR_LOC_OVERLAY_ALPHA) uniform float u_alpha;

layout(binding = MR_TEX_OVERLAY_VIRTUAL) uniform sampler2D u_virtual;
layout(binding = MR_TEX_OVERLAY_VIDEO) uniform sampler2D u_video;
// Shadow catcher: receivers of the scene config (the real floor) are not
// drawn; the video shows through them, darkened where the plan shadows them
// by the share of the casting light in their shading:
//   video * (1 - s (1 - V)),  s = c_L max(n.l, 0) / (ambient + c_L max(n.l, 0)).
layout(location = MR_LOC_OVERLAY_CATCHER) uniform int u_catcher;            // 0: no catchers this frame
layout(location = MR_LOC_OVERLAY_CATCHER_LIGHT) uniform vec3 u_catch_light;  // view space, towards the light
layout(location = MR_LOC_OVERLAY_CATCHER_LIGHT_LUM) uniform float u_catch_lum;
layout(location = MR_LOC_OVERLAY_CATCHER_AMBIENT) uniform float u_catch_ambient;
layout(binding = MR_TEX_OVERLAY_IDS) uniform usampler2D u_ids;             // node index + 1, layer
layout(binding = MR_TEX_OVERLAY_SHADOW) uniform sampler2D u_shadow;        // visibility (1 = lit)
layout(binding = MR_TEX_OVERLAY_CATCHER_FLAGS) uniform usampler2D u_flags; // 1: node is a catcher
layout(binding = MR_TEX_OVERLAY_NORMAL) uniform sampler2D u_normal;

layout(location = 0) out vec4 o_color; // sRGB8 target

void main() {
    vec2 px = cv_pixel();
    vec2 xy = (px - u_intr.zw) / u_intr.xy;
    float r2 = dot(xy, xy);
    float k1 = u_dist[0], k2 = u_dist[1], p1 = u_dist[2], p2 = u_dist[3], k3 = u_dist[4];
    float radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    vec2 d = xy * radial + vec2(2.0 * p1 * xy.x * xy.y + p2 * (r2 + 2.0 * xy.x * xy.x),
                                p1 * (r2 + 2.0 * xy.y * xy.y) + 2.0 * p2 * xy.x * xy.y);
    vec2 vp = d * u_video_intr.xy + u_video_intr.zw;          // raw video pixel
    vec2 uv = (vp + 0.5) / u_video_size;
    vec3 video = vec3(0.0);                                   // black outside the frame
    if (all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0))))
        video = texture(u_video, uv).rgb;
    vec3 virt = texelFetch(u_virtual, ivec2(gl_FragCoord.xy), 0).rgb;
    if (u_catcher != 0) {
        ivec2 q = ivec2(gl_FragCoord.xy);
        uint id = texelFetch(u_ids, q, 0).r;
        if (id > 0u) {
            int node = int(id) - 1;
            if (texelFetch(u_flags, ivec2(node % MR_SHADOW_CATCHER_ROW, node / MR_SHADOW_CATCHER_ROW), 0).r != 0u) {
                float v = u_catcher > 1 ? texelFetch(u_shadow, q, 0).r : 1.0;
                float d = u_catch_lum * max(dot(texelFetch(u_normal, q, 0).xyz, u_catch_light), 0.0);
                float sh = d / max(u_catch_ambient + d, 1e-6);
                o_color = vec4(video * (1.0 - sh * (1.0 - v)), 1.0);
                return;
            }
        }
    }
    o_color = vec4(mix(virt, video, u_alpha), 1.0);
}
