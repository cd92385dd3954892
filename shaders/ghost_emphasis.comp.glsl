// Emphasis (paper section 3.3 with the "lightness only" and "unified sign"
// rules of section 3.4).
//  u_stage 0 (vote): per pixel the lightness direction that raises contrast
//    to the smoothed occludee, eq. 5-6 restricted to L*:
//      L_max = 50 + sgn(50 - L*(GK(D))) * 50,  dir = sgn(L_max - L*(O)),
//    added, weighted by GK(C), to its occluder object's vote.
//  u_stage 1 (apply): each object takes the sign of its vote, so it is
//    either lightened or darkened, never both:
//      L*(O_A) = L*(O) + gain * GK(C) * sign,  G_A = LAB^-1(O_A)*alpha + D*(1-alpha).
#include "mr_bindings.h"
#include "ghost_lab.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(location = MR_LOC_EMPH_STAGE) uniform int u_stage;
layout(location = MR_LOC_EMPH_KEY_BASE) uniform uint u_key_base;  // first key of the video regions
layout(location = MR_LOC_EMPH_GAIN) uniform float u_gain;
layout(binding = MR_TEX_EMPH_O) uniform sampler2D u_o;
layout(binding = MR_TEX_EMPH_D) uniform sampler2D u_d;
layout(binding = MR_TEX_EMPH_DGK) uniform sampler2D u_dgk;   // GK(D), linear
layout(binding = MR_TEX_EMPH_GKC) uniform sampler2D u_gkc;   // GK(C) in .r
layout(binding = MR_TEX_EMPH_MASK) uniform sampler2D u_mask;
layout(binding = MR_TEX_EMPH_G0) uniform sampler2D u_g0;
layout(binding = MR_TEX_EMPH_KEY) uniform usampler2D u_key;
layout(binding = MR_TEX_EMPH_LABEL) uniform usampler2D u_label;
layout(binding = MR_IMG_EMPH_OUT, rgba8) uniform writeonly image2D u_out;
layout(binding = MR_IMG_EMPH_OA, rgba32f) uniform writeonly image2D u_oa;
layout(binding = MR_IMG_EMPH_GA, rgba32f) uniform writeonly image2D u_ga;
layout(std430, binding = MR_SSBO_EMPH_VOTES) buffer Votes { int votes[]; };

// Votes are pre-summed per workgroup: each invocation posts (key, vote) in
// shared memory and the first invocation adds runs of equal keys, so a large
// object costs one global atomic per workgroup instead of one per pixel.
shared uint s_key[64];
shared int s_vote[64];

void vote(uint key, int v) {
    uint i = gl_LocalInvocationIndex;
    s_key[i] = key;
    s_vote[i] = v;
    barrier();
    if (i == 0u) {
        uint k = s_key[0];
        int acc = 0;
        for (uint j = 0u; j < 64u; j++) {
            if (s_key[j] != k) {
                if (acc != 0) atomicAdd(votes[k], acc);
                k = s_key[j];
                acc = 0;
            }
            acc += s_vote[j];
        }
        if (acc != 0) atomicAdd(votes[k], acc);
    }
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy), n = textureSize(u_mask, 0);
    if (u_stage == 0) {
        // Every invocation reaches the barrier in vote(), inside or not.
        uint key = 0u;
        int v = 0;
        if (p.x < n.x && p.y < n.y) {
            vec4 m = texelFetch(u_mask, p, 0);
            float gkc = texelFetch(u_gkc, p, 0).r;
            if (m.y > 0.5 && gkc > 1e-4) {
                key = texelFetch(u_key, p, 0).x;
                if (key == 0u) key = u_key_base + texelFetch(u_label, p, 0).x;
                float lo = rgb_to_lab(texelFetch(u_o, p, 0).rgb).x;
                float ld = rgb_to_lab(texelFetch(u_dgk, p, 0).rgb).x;
                float d = sign(50.0 + sign(50.0 - ld) * 50.0 - lo);
                v = int(round(clamp(gkc, 0.0, 4.0) * d * 1024.0));
            }
        }
        vote(key, v);
        return;
    }
    if (p.x >= n.x || p.y >= n.y) return;
    vec4 m = texelFetch(u_mask, p, 0);
    float gkc = texelFetch(u_gkc, p, 0).r;
    vec3 o = texelFetch(u_o, p, 0).rgb;
    bool act = m.y > 0.5 && gkc > 1e-4;
    uint key = texelFetch(u_key, p, 0).x;
    if (key == 0u) key = u_key_base + texelFetch(u_label, p, 0).x;
    vec3 lab = rgb_to_lab(o);
    float ld = rgb_to_lab(texelFetch(u_dgk, p, 0).rgb).x;
    float lmax = 50.0 + sign(50.0 - ld) * 50.0;
    float dir = sign(lmax - lab.x);
    vec4 g0 = texelFetch(u_g0, p, 0);
    vec3 ga = g0.rgb, oa = o;
    if (act) {
        int v = votes[key];
        float s = v > 0 ? 1.0 : v < 0 ? -1.0 : dir;
        lab.x = clamp(lab.x + u_gain * gkc * s, 0.0, 100.0);
        oa = clamp(lab_to_rgb(lab), 0.0, 1.0);
        vec3 d = texelFetch(u_d, p, 0).rgb;
        ga = oa * g0.a + d * (1.0 - g0.a);
    }
    imageStore(u_out, p, vec4(ghost_linear_to_srgb(ga), 1.0));
    imageStore(u_oa, p, vec4(oa, 1.0));
    imageStore(u_ga, p, vec4(ga, 1.0));
}
