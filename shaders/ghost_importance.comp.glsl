// Importance map and ghosting region.
//  region: the hidden layer D covers the pixel and something occludes it: the
//          model (visible layer nearer than D) or, with video, the real
//          world (the video is then the occluder, image-based).
//  IM (model occluder, curvature): the occluder's principal curvature in
//          radians per pixel, kappa * z / fx (so the same picture at any
//          scene scale), and at creases / object outlines the angle between
//          neighbouring normals (pi/2 across objects): a polyhedral CAD
//          surface keeps all its curvature in its edges.
//          IM = clamp(scale * curvature + bias, 0, 1).
//  IM (saliency): the saliency of O (computed before), clamped to [0,1].
// Writes mask = (IM, region, silhouette, D coverage), the occluder object
// key (node index + 1, or 0 for the video) and the sums for mean(IM).
#include "mr_bindings.h"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_IMP_VIDEO) uniform int u_video;     // 1: the video is an occluder
layout(location = MR_LOC_IMP_IMPORTANCE) uniform int u_importance; // 0 auto, 1 curvature, 2 saliency
layout(location = MR_LOC_IMP_SCALE) uniform float u_scale;
layout(location = MR_LOC_IMP_BIAS) uniform float u_bias;
layout(location = MR_LOC_IMP_NEAR) uniform float u_near;
layout(location = MR_LOC_IMP_FX) uniform float u_fx;
layout(location = MR_LOC_IMP_HAVE_SALIENCY) uniform int u_have_saliency;
layout(binding = MR_TEX_IMP_DEPTH) uniform sampler2D u_depth;     // main (visible layer), reversed Z
layout(binding = MR_TEX_IMP_NORMAL) uniform sampler2D u_normal;
layout(binding = MR_TEX_IMP_IDS) uniform usampler2D u_ids;
layout(binding = MR_TEX_IMP_HIDDEN_DEPTH) uniform sampler2D u_hdepth;    // hidden layer D
layout(binding = MR_TEX_IMP_HIDDEN_IDS) uniform usampler2D u_hids;
layout(binding = MR_TEX_IMP_CURVATURE) uniform sampler2D u_curv;
layout(binding = MR_TEX_IMP_SAL) uniform sampler2D u_sal;
layout(binding = MR_IMG_IMP_MASK, rgba32f) uniform writeonly image2D u_mask;
layout(binding = MR_IMG_IMP_KEY, r32ui) uniform writeonly uimage2D u_key;
layout(std430, binding = MR_SSBO_IMP_STATS) buffer Stats { uint im_sum; uint im_count; };

const float PI = 3.14159265;

// Sums for mean(IM) are reduced per workgroup in shared memory first, so
// the global counters see one atomic per workgroup, not one per pixel.
shared uint s_sum, s_count;
void classify(ivec2 p, ivec2 n);

void main() {
    if (gl_LocalInvocationIndex == 0u) { s_sum = 0u; s_count = 0u; }
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = imageSize(u_mask);
    bool inside = p.x < n.x && p.y < n.y;
    if (inside) classify(p, n);
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_count > 0u) {
        atomicAdd(im_sum, s_sum);
        atomicAdd(im_count, s_count);
    }
}

void classify(ivec2 p, ivec2 n) {
    float d = texelFetch(u_depth, p, 0).r, hd = texelFetch(u_hdepth, p, 0).r;
    bool dcov = hd > 0.0;
    bool model = d > 0.0 && d > hd;  // reversed Z: larger is nearer
    bool region = dcov && (model || u_video != 0);
    uint hid = texelFetch(u_hids, p, 0).x;
    bool sil = false;
    if (dcov) {
        const ivec2 off[4] = ivec2[](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
        for (int i = 0; i < 4; i++) {
            ivec2 q = clamp(p + off[i], ivec2(0), n - 1);
            if (texelFetch(u_hdepth, q, 0).r <= 0.0 || texelFetch(u_hids, q, 0).x != hid) sil = true;
        }
    }
    float im = 0.0;
    bool use_curv = model && u_importance != 2;
    if (use_curv) {
        float z = u_near / d;
        float k = texelFetch(u_curv, p, 0).r * z / u_fx;
        vec3 np = texelFetch(u_normal, p, 0).xyz;
        uint id = texelFetch(u_ids, p, 0).x;
        const ivec2 off[4] = ivec2[](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
        for (int i = 0; i < 4; i++) {
            ivec2 q = clamp(p + off[i], ivec2(0), n - 1);
            if (q == p) continue;
            if (texelFetch(u_depth, q, 0).r <= 0.0 || texelFetch(u_ids, q, 0).x != id) { k = max(k, 0.5 * PI); continue; }
            vec3 nq = texelFetch(u_normal, q, 0).xyz;
            k = max(k, acos(clamp(dot(np, nq), -1.0, 1.0)));
        }
        im = clamp(u_scale * k + u_bias, 0.0, 1.0);
    } else if (u_have_saliency != 0) {
        im = clamp(texelFetch(u_sal, p, 0).r, 0.0, 1.0);
    } else {
        im = clamp(u_bias, 0.0, 1.0);
    }
    if (!(im >= 0.0)) im = 0.0; // NaN guard
    imageStore(u_mask, p, vec4(im, region ? 1.0 : 0.0, sil && region ? 1.0 : 0.0, dcov ? 1.0 : 0.0));
    imageStore(u_key, p, uvec4(model ? texelFetch(u_ids, p, 0).x : 0u));
    if (region) {
        atomicAdd(s_sum, uint(im * 256.0 + 0.5));
        atomicAdd(s_count, 1u);
    }
}
