// Screen-space ambient occlusion: one program, the method picked by a
// uniform (a branch every pixel takes the same way). Output: visibility in
// [0,1], 1 = unoccluded. The AO target may be half the G-buffer's size: AO
// pixel i reads the G-buffer at i * u_step, everything else works at full
// resolution with the full-resolution intrinsics.
#include "mr_bindings.h"
#include "ao_common.glsl"

layout(location = MR_LOC_AO_INTR) uniform vec4 u_intr;        // fx fy cx cy of the G-buffer (pixels)
layout(location = MR_LOC_AO_FULL) uniform ivec2 u_full;       // G-buffer size
layout(location = MR_LOC_AO_STEP) uniform int u_step;         // 1 full resolution, 2 half
layout(location = MR_LOC_AO_NEAR) uniform float u_near;       // near plane (scene units)
layout(location = MR_LOC_AO_METHOD) uniform int u_method;       // mr_ao_method; 100 = standalone corner mask
layout(location = MR_LOC_AO_SAMPLES) uniform int u_samples;      // 1..64
layout(location = MR_LOC_AO_RADIUS_MODE) uniform int u_radius_mode;  // 0 screen (r = k z), 1 view (r constant)
layout(location = MR_LOC_AO_RADIUS) uniform float u_radius;     // view mode radius (scene units)
layout(location = MR_LOC_AO_SCREEN_K) uniform float u_screen_k;   // screen mode: r = k * z
layout(location = MR_LOC_AO_C) uniform float u_c;          // scheer attenuation
layout(location = MR_LOC_AO_BIAS) uniform float u_bias;      // fraction of the radius / cosine
layout(location = MR_LOC_AO_STRENGTH) uniform float u_strength;
layout(location = MR_LOC_AO_RADII) uniform int u_radii;       // multi-radius count
layout(location = MR_LOC_AO_USE_POS) uniform int u_use_pos;
layout(location = MR_LOC_AO_USE_MASK) uniform int u_use_mask;
layout(location = MR_LOC_AO_MASK_STRENGTH) uniform float u_mask_strength; // standalone mask: 1 - this inside, in [0,1]
layout(location = MR_LOC_AO_KERNEL) uniform vec4 u_kernel[MR_AO_KERNEL_SIZE];  // xyz in the unit ball shell [r_min, r_max]
layout(location = MR_LOC_AO_KERNEL2) uniform vec4 u_kernel2[MR_AO_KERNEL_SIZE]; // xy in the unit disk annulus [r_min, r_max]

// The slice integrators (gtao, bitmask, scheer-gt).
layout(location = MR_LOC_AO_SLICES) uniform vec4 u_slices[MR_AO_SLICES_SIZE]; // xy: unit slice directions over half a turn
layout(location = MR_LOC_AO_SLICE_COUNT) uniform int u_slice_count;  // 1..16
layout(location = MR_LOC_AO_STEPS) uniform int u_steps;              // samples per slice side
layout(location = MR_LOC_AO_THICKNESS) uniform float u_thickness;    // fraction of the radius
layout(location = MR_LOC_AO_FRAME) uniform int u_frame;              // temporal accumulation: frame index
layout(location = MR_LOC_AO_NOISE) uniform int u_noise;         // 0 pixel hash, 1 world-position hash
layout(location = MR_LOC_AO_NOISE_CELL) uniform float u_noise_cell; // grid cell of the hash (scene units)
layout(location = MR_LOC_AO_NOISE_FRAME) uniform mat4 u_noise_frame; // anchor_from_camera

layout(location = MR_LOC_AO_DISPLAY) uniform vec3 u_display;       // D, E, width; D = 0: pinhole
// The slice methods' depth mip chain
layout(location = MR_LOC_AO_MIPS) uniform int u_mips;              // levels above 0; 0 = off (level 0 only)
layout(location = MR_LOC_AO_MIP_NEAR) uniform float u_mip_near;    // samples nearer than this (px) read level 0

layout(binding = MR_TEX_AO_DEPTH) uniform sampler2D u_depth;
layout(binding = MR_TEX_AO_NORMAL) uniform sampler2D u_normal;
layout(binding = MR_TEX_AO_POSITIONS) uniform sampler2D u_pos;
layout(binding = MR_TEX_AO_MASK) uniform sampler2D u_mask;
layout(binding = MR_TEX_AO_DEPTH_MIP) uniform sampler2D u_depth_mip; // reversed-Z depth, box-filtered levels
// Deinterleaved AO. The target is a 4x4 atlas of
// quarter-size layers; the fragment in tile o at texel t is AO pixel
// 4 t + o, and every depth it samples comes from its own tile (the AO
// pixels congruent to o mod 4), so a layer's reads stay in one small block.
layout(location = MR_LOC_AO_DEINT) uniform int u_deint;           // 0 off, 1 on
layout(location = MR_LOC_AO_DEINT_Q) uniform ivec2 u_dq;          // one layer's size
layout(location = MR_LOC_AO_DEINT_NEAR) uniform float u_dnear;    // nearer samples read the G-buffer itself
layout(binding = MR_TEX_AO_DEINT_DEPTH) uniform sampler2D u_dz;   // reversed-Z depth atlas (ao_deint_split)
ivec2 g_layer = ivec2(0);                                         // this fragment's tile
ivec2 g_tmax = ivec2(0);                                          // its last texel (the image's edge)
ivec2 g_fp = ivec2(0);                                            // the fragment's G-buffer pixel

layout(location = 0) out float o_ao;

#define M_SCHEER MR_AO_METHOD_ID_SCHEER
#define M_CRYTEK MR_AO_METHOD_ID_CRYTEK
#define M_FILION MR_AO_METHOD_ID_FILION
#define M_HBAO MR_AO_METHOD_ID_HBAO
#define M_ALCHEMY MR_AO_METHOD_ID_ALCHEMY
#define M_MASK_STANDALONE MR_AO_METHOD_MASK_STANDALONE
#define M_GTAO MR_AO_METHOD_ID_GTAO
#define M_BITMASK MR_AO_METHOD_ID_BITMASK
#define M_SCHEER_GT MR_AO_METHOD_ID_SCHEER_GT
#define M_SCHEER_BM MR_AO_METHOD_ID_SCHEER_BM

bool fetch_pos(ivec2 q, out vec3 p) {
    // A sample nearer than u_dnear would snap onto the layer's grid (4 AO
    // pixels) by a large part of its offset: it reads the G-buffer, which
    // near the pixel is as cache-coherent as the layer.
    ivec2 dq = abs(q - g_fp);
    if (u_deint != 0 && u_use_pos == 0 && float(max(dq.x, dq.y)) >= u_dnear) {
        // The layer's AO pixel nearest to q (a sample moves by up to 2 AO
        // pixels), un-projected at that pixel's own position.
        ivec2 t = ivec2(floor((vec2(q) / float(u_step) - vec2(g_layer)) * 0.25 + 0.5));
        t = clamp(t, ivec2(0), g_tmax);
        ivec2 fq = (4 * t + g_layer) * u_step;
        p = vec3(0.0);
        float d = texelFetch(u_dz, g_layer * u_dq + t, 0).r;
        if (!(d > 0.0)) return false;
        float z = u_near / d;
        if (isinf(z) || isnan(z)) return false;
        p = vec3((vec2(fq) - u_intr.zw) / u_intr.xy * z, z);
        return true;
    }
    return ao_view_pos(u_depth, u_pos, u_use_pos != 0, u_near, u_intr, q, p);
}

// View point to the nearest G-buffer pixel; false behind the camera or
// outside the image (such samples find no occluder).
bool project(vec3 s, out ivec2 q) {
    q = ivec2(0);
    if (!(s.z > 0.0)) return false;
    vec2 uv = s.xy / s.z * u_intr.xy + u_intr.zw;
    if (u_display.x > 0.0) {
        // Light-field display: the column whose own eye e(u) = a (u + 0.5) - E
        // sees s; solved from u = fx x/z + cx + fx e(u) (1/D - 1/z).
        float a = 2.0 * u_display.y / u_display.z, g = u_intr.x * (1.0 / u_display.x - 1.0 / s.z);
        float den = 1.0 - g * a;
        if (!(abs(den) > 1e-6)) return false;
        uv.x = (uv.x + g * (0.5 * a - u_display.y)) / den;
    }
    if (!(uv.x > -0.5 && uv.y > -0.5 && uv.x < float(u_full.x) - 0.5 && uv.y < float(u_full.y) - 0.5)) return false;
    q = ivec2(floor(uv + 0.5));
    return true;
}

// A random unit vector per pixel: the plane the kernel is reflected on
// (Mittring), which turns a fixed kernel into per-pixel noise the blur
// removes instead of banding.
vec3 random_plane(vec3 rnd) {
    float z = 1.0 - 2.0 * rnd.x, phi = 6.28318530718 * rnd.y;
    float s = sqrt(max(0.0, 1.0 - z * z));
    return vec3(s * cos(phi), s * sin(phi), z);
}

// Scheer & Keutel: occlusion vectors v = Q - P to the surface points Q seen
// at the projected samples; only v inside the normal's hemisphere occludes,
// weighted by cos(v, n) / (1 + c |v|'^2) with |v|' = |v| / r.
float occ_scheer(vec3 P, vec3 n, float r, vec3 plane) {
    float occ = 0.0;
    for (int i = 0; i < u_samples; i++) {
        vec3 k = reflect(u_kernel[i].xyz, plane);
        if (dot(k, n) < 0.0) k = -k;                 // flip into the hemisphere
        ivec2 q; vec3 Q;
        if (!project(P + k * r, q) || !fetch_pos(q, Q)) continue;
        vec3 v = Q - P;
        float len = length(v);
        if (!(len > 0.0) || isinf(len)) continue;
        float cosv = dot(v, n) / len;
        if (cosv <= u_bias) continue;                // outside the hemisphere (with a small bias)
        float l = len / r;
        occ += (cosv - u_bias) / (1.0 - u_bias) / (1.0 + u_c * l * l);
    }
    return occ / float(u_samples);
}

// Mittring (Crysis): sphere samples, occluded when the depth buffer is in
// front of the sample. Failing the range check (the occluder more than r in
// front) counts as half occluded, neutral under the remap: half the sphere
// is behind any flat surface, so the ratio is remapped to flat = 0.
float occ_crytek(vec3 P, vec3 n, float r, vec3 plane) {
    float hits = 0.0, used = 0.0;
    for (int i = 0; i < u_samples; i++) {
        vec3 k = reflect(u_kernel[i].xyz, plane);
        vec3 s = P + k * r;
        ivec2 q; vec3 Q;
        if (!project(s, q)) continue;
        used += 1.0;
        if (!fetch_pos(q, Q)) continue;
        float dz = s.z - Q.z;
        if (dz > u_bias * r) hits += dz < r ? 1.0 : 0.5;
    }
    return used > 0.0 ? max(0.0, 2.0 * hits / used - 1.0) : 0.0;
}

// Filion & McNaughton (StarCraft II): hemisphere samples; the occlusion of
// a sample is a function of the depth difference: none when the sample is
// in front, full up to r, fading to none at 2r.
float occ_filion(vec3 P, vec3 n, float r, vec3 plane) {
    float occ = 0.0;
    for (int i = 0; i < u_samples; i++) {
        vec3 k = reflect(u_kernel[i].xyz, plane);
        if (dot(k, n) < 0.0) k = -k;
        vec3 s = P + k * r;
        ivec2 q; vec3 Q;
        if (!project(s, q) || !fetch_pos(q, Q)) continue;
        float dz = s.z - Q.z;
        if (dz <= u_bias * r) continue;
        occ += dz < r ? 1.0 : max(0.0, 2.0 - dz / r);
    }
    return occ / float(u_samples);
}

// Bavoil et al.: per image-space direction, march over the projected
// radius and integrate the rise of the horizon elevation above the tangent
// plane (sin h - sin t, t the tangent angle), attenuated by 1 - (|v|/r)^2.
float occ_hbao(vec3 P, vec3 n, float r, vec3 rnd, vec2 px) {
    int ndir = u_samples <= 16 ? 4 : 8;
    int steps = max(1, u_samples / ndir);
    float rpx = r * u_intr.x / P.z;                  // projected radius in pixels
    if (!(rpx >= 1.0)) return 0.0;
    rpx = min(rpx, float(max(u_full.x, u_full.y)));
    float step_px = rpx / float(steps);
    float occ = 0.0;
    for (int d = 0; d < ndir; d++) {
        float a = 6.28318530718 * (float(d) + rnd.x) / float(ndir);
        vec2 dir = vec2(cos(a), sin(a));
        float sin_max = u_bias;                      // tangent-plane bias angle
        float ao_d = 0.0;
        for (int j = 0; j < steps; j++) {
            vec2 uv = px + dir * max(1.0, (float(j) + rnd.y) * step_px);
            ivec2 q = ivec2(floor(uv + 0.5));
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, u_full))) break;
            vec3 S;
            if (!fetch_pos(q, S)) continue;
            vec3 v = S - P;
            float len2 = dot(v, v);
            if (!(len2 > 0.0) || len2 > r * r) continue;
            float sinh = dot(v, n) * inversesqrt(len2);
            if (sinh > sin_max) {
                ao_d += (sinh - sin_max) * (1.0 - len2 / (r * r));
                sin_max = sinh;
            }
        }
        occ += ao_d;
    }
    return occ / float(ndir);
}

// McGuire et al. (Alchemy AO): samples on a screen-space disk of the
// projected radius; A = 1 - 2 sigma / s * sum max(0, v.n - beta) / (v.v + eps),
// made scale-free by measuring lengths in units of r.
float occ_alchemy(vec3 P, vec3 n, float r, vec3 rnd, vec2 px) {
    float rpx = r * u_intr.x / P.z;
    float ca = cos(6.28318530718 * rnd.x), sa = sin(6.28318530718 * rnd.x);
    float sum = 0.0;
    for (int i = 0; i < u_samples; i++) {
        vec2 o = u_kernel2[i].xy;
        o = vec2(ca * o.x - sa * o.y, sa * o.x + ca * o.y) * rpx;
        vec2 uv = px + o;
        ivec2 q = ivec2(floor(uv + 0.5));
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, u_full))) continue;
        vec3 Q;
        if (!fetch_pos(q, Q)) continue;
        vec3 v = (Q - P) / r;
        float vv = dot(v, v);
        if (!(vv < 1.0)) continue;                   // only occluders inside the ball of radius r
        sum += max(0.0, dot(v, n) - u_bias) / (vv + 0.01);
    }
    return sum / float(u_samples);                   // 2 sigma / s with sigma = 0.5
}

// ------------------------------------------------------ slice integrators
// The slice integrators. A slice is the plane through the view vector V
// (towards the camera) and a screen direction d; in it an angle t is
// measured from V, positive towards +d. The normal projected into the
// slice has length nl and angle g. The cosine-weighted solid angle of the
// arc between 0 and t, signed (negative for t < 0), is
//   A(t) = sign(t) (cos g + 2 t sin g - cos(2 t - g)) / 4
// (Jimenez et al. 2016, eq. 10), so the visible part of a slice between
// the horizons t0 <= 0 <= t1 weighs nl (A(t1) - A(t0)); averaged over
// slice directions uniform in [0, pi) this is exactly the cosine-weighted
// visibility the ray-traced reference measures (heightfield assumption).
// With a few slices per pixel the sum scatters around 1 even on a plane,
// and the clamp to [0,1] would cut the overshoot off (a plane came out
// 0.03 dark), so all three divide by the same sum over the pixel's slices
// with nothing occluded (a ratio estimator): a plane is exactly 1.
const float AO_PI = 3.14159265359;
const float AO_HALF_PI = 1.57079632679;
// gtao: the width (fraction of the radius) of the distance falloff over
// which a sample's horizon fades to the tangent, centred on r: short,
// because the reference counts an occluder fully up to r and not at all
// beyond, and centred, so that what it drops inside r it adds outside.
const float GTAO_FALLOFF = 0.1;

float slice_arc(float t, float g) {
    return sign(t) * 0.25 * (cos(g) + 2.0 * t * sin(g) - cos(2.0 * t - g));
}

struct ao_slice {
    vec2 d;      // screen direction (pixels), = view direction (OpenCV axes)
    vec3 V;      // towards the camera
    float g;     // signed angle of the projected normal from V
    float nl;    // length of the projected normal
};

ao_slice make_slice(vec3 P, vec3 n, vec2 d) {
    ao_slice s;
    s.d = d;
    s.V = normalize(-P);
    vec3 D = vec3(d, 0.0);
    vec3 ortho = D - dot(D, s.V) * s.V;              // +d side of the slice, orthogonal to V
    vec3 axis = normalize(cross(ortho, s.V));
    vec3 np = n - axis * dot(n, axis);
    s.nl = length(np);
    float cg = s.nl > 1e-6 ? clamp(dot(np, s.V) / s.nl, -1.0, 1.0) : 1.0;
    s.g = (dot(np, ortho) < 0.0 ? -1.0 : 1.0) * acos(cg);
    return s;
}

// The sample j of side `side` (0: +d, 1: -d) of a slice, at jittered
// even steps over the projected radius; false outside the image or sky.
// The point is taken on the ray through the sample's own (sub-pixel)
// position, with the reversed-Z depth filtered bilinearly there (pass_ao.c
// binds a linear sampler for these methods): 1/z is affine across a plane
// in the image, so a plane's points come out exactly on it and in the
// slice. The nearest pixel's point lies off the slice by up to half a
// pixel, which reads as a horizon above the tangent (a plane came out
// 0.02 dark). With a positions texture the nearest pixel is used.
bool slice_sample(vec2 px, vec2 d, int side, int j, float jitter, float rpx, out vec3 S) {
    S = vec3(0.0);
    float off = max(1.0, (float(j) + jitter) / float(u_steps) * rpx);
    vec2 uv = px + (side == 0 ? d : -d) * off;
    if (!(uv.x > -0.5 && uv.y > -0.5 && uv.x < float(u_full.x) - 0.5 && uv.y < float(u_full.y) - 0.5)) return false;
    if (u_use_pos != 0) return fetch_pos(ivec2(floor(uv + 0.5)), S);
    float dz;
    // A far sample reads a coarser level of the depth chain, one
    // whose texels (2^L pixels) stay below the spacing of the samples
    // around it: level L for offsets in [near 2^(L-1), near 2^L). Nearer
    // ones read the G-buffer itself, exactly as without the chain.
    if (u_mips > 0 && off >= u_mip_near) {
        float lod = min(floor(log2(off / u_mip_near)) + 1.0, float(u_mips));
        dz = textureLod(u_depth_mip, (uv + 0.5) / vec2(u_full), lod).r;
    } else if (u_deint != 0 && off >= u_dnear) {
        // Bilinear inside the layer's tile (clamped to it, so no texel of
        // another layer mixes in); the point is taken at the position the
        // filtered coordinate stands for: on a plane still exactly on it.
        vec2 tf = clamp((uv / float(u_step) - vec2(g_layer)) * 0.25, vec2(0.0), vec2(g_tmax));
        uv = (4.0 * tf + vec2(g_layer)) * float(u_step);
        dz = textureLod(u_dz, (vec2(g_layer * u_dq) + tf + 0.5) / vec2(4 * u_dq), 0.0).r;
    } else {
        dz = textureLod(u_depth, (uv + 0.5) / vec2(u_full), 0.0).r;
    }
    if (!(dz > 0.0)) return false;
    float z = u_near / dz;
    if (isinf(z) || isnan(z)) return false;
    S = vec3((uv - u_intr.zw) / u_intr.xy * z, z);
    return true;
}

// The per-pixel rotation of the slice set (one cos/sin per pixel; the
// directions themselves are the uniform array).
vec2 slice_dir(int i, vec2 rot) {
    vec2 d0 = u_slices[i].xy;
    return vec2(rot.x * d0.x - rot.y * d0.y, rot.y * d0.x + rot.x * d0.y);
}

// Jimenez et al. 2016 (GTAO): per slice the highest horizon on each side
// within r (cosines, with the distance falloff towards the tangent), the
// thickness heuristic (a sample below the running horizon pulls it down by
// beta = 0.05 / thickness: a thin occluder's horizon decays behind it),
// the horizons clamped to the normal's hemisphere, then the arc integral.
float occ_gtao(vec3 P, vec3 n, float r, vec3 rnd, vec2 px) {
    float rpx = r * u_intr.x / P.z;
    if (!(rpx >= 1.0)) return 0.0;
    rpx = min(rpx, float(max(u_full.x, u_full.y)));
    float a = rnd.x * AO_PI / float(u_slice_count);
    vec2 rot = vec2(cos(a), sin(a));
    float beta = clamp(0.05 / max(u_thickness, 1e-3), 0.0, 1.0);
    float vis = 0.0, total = 0.0;
    for (int i = 0; i < u_slice_count; i++) {
        ao_slice sl = make_slice(P, n, slice_dir(i, rot));
        float lo[2] = float[2](-sin(sl.g), sin(sl.g)); // cos(g + pi/2), cos(g - pi/2)
        float hc[2] = float[2](lo[0], lo[1]);
        for (int j = 0; j < u_steps; j++)
            for (int side = 0; side < 2; side++) {
                vec3 S;
                if (!slice_sample(px, sl.d, side, j, rnd.y, rpx, S)) continue;
                vec3 v = S - P;
                float l = length(v);
                if (!(l > 0.0) || isinf(l)) continue;
                float c = dot(v, sl.V) / l;
                float w = clamp(((1.0 + 0.5 * GTAO_FALLOFF) * r - l) / (GTAO_FALLOFF * r), 0.0, 1.0);
                c = mix(lo[side], c, w);
                if (c > hc[side]) hc[side] = c;
                else if (w >= 1.0) hc[side] = mix(hc[side], c, beta);
            }
        float t1 = min(acos(clamp(hc[0], -1.0, 1.0)), sl.g + AO_HALF_PI);
        float t0 = max(-acos(clamp(hc[1], -1.0, 1.0)), sl.g - AO_HALF_PI);
        vis += sl.nl * (slice_arc(t1, sl.g) - slice_arc(t0, sl.g));
        total += sl.nl * (slice_arc(sl.g + AO_HALF_PI, sl.g) - slice_arc(sl.g - AO_HALF_PI, sl.g));
    }
    return total > 0.0 ? 1.0 - vis / total : 0.0;
}

// Sectors [t0, t1] of a slice as bits: the arc between the normal's
// hemisphere ends, cut into 32 sectors of equal cosine-weighted mass; a
// sector is set when its centre lies in [t0, t1].
uint sector_bits(float t0, float t1, float g, float a0, float inv_mass) {
    float u0 = (slice_arc(clamp(t0, g - AO_HALF_PI, g + AO_HALF_PI), g) - a0) * inv_mass;
    float u1 = (slice_arc(clamp(t1, g - AO_HALF_PI, g + AO_HALF_PI), g) - a0) * inv_mass;
    uint b0 = uint(clamp(floor(u0 * 32.0 + 0.5), 0.0, 32.0));
    uint b1 = uint(clamp(floor(u1 * 32.0 + 0.5), 0.0, 32.0));
    if (b1 <= b0) return 0u;
    uint cnt = b1 - b0;
    return cnt >= 32u ? 0xffffffffu : ((1u << cnt) - 1u) << b0;
}

// Therrien, Levesque & Gilet 2023 (visibility bitmasks): every sample
// within r occludes the angles between its front face and a point
// `thickness * r` behind it along the view ray; the slice's visibility is
// its share of unset sectors (sectors of equal cosine-weighted mass, so
// the count is the cosine-weighted visibility).
float occ_bitmask(vec3 P, vec3 n, float r, vec3 rnd, vec2 px) {
    float rpx = r * u_intr.x / P.z;
    if (!(rpx >= 1.0)) return 0.0;
    rpx = min(rpx, float(max(u_full.x, u_full.y)));
    float a = rnd.x * AO_PI / float(u_slice_count);
    vec2 rot = vec2(cos(a), sin(a));
    float th = u_thickness * r;
    float vis = 0.0, total = 0.0;
    for (int i = 0; i < u_slice_count; i++) {
        ao_slice sl = make_slice(P, n, slice_dir(i, rot));
        float a0 = slice_arc(sl.g - AO_HALF_PI, sl.g), mass = slice_arc(sl.g + AO_HALF_PI, sl.g) - a0;
        if (!(mass > 1e-6)) continue;
        float inv_mass = 1.0 / mass;
        uint bits = 0u;
        for (int j = 0; j < u_steps; j++)
            for (int side = 0; side < 2; side++) {
                vec3 S;
                if (!slice_sample(px, sl.d, side, j, rnd.y, rpx, S)) continue;
                vec3 v = S - P;
                float l = length(v);
                if (!(l > 0.0) || !(l <= r)) continue;
                vec3 vb = S + normalize(S) * th - P;
                float tf = acos(clamp(dot(v, sl.V) / l, -1.0, 1.0));
                float tb = acos(clamp(dot(vb, sl.V) / max(length(vb), 1e-30), -1.0, 1.0));
                float sg = side == 0 ? 1.0 : -1.0;
                bits |= sector_bits(min(sg * tf, sg * tb), max(sg * tf, sg * tb), sl.g, a0, inv_mass);
            }
        vis += sl.nl * mass * (1.0 - float(bitCount(bits)) / 32.0);
        total += sl.nl * mass;
    }
    return total > 0.0 ? 1.0 - vis / total : 0.0;
}

// scheer-gt: Scheer & Keutel's idea on GTAO's integrator. Each sample
// within r occludes the cosine-weighted arc between the tangent and its
// horizon, attenuated by Scheer's quasi-normalised 1/(1 + c l^2), l = |v|/r
// (so a near occluder counts fully, one at the radius 1/(1+c)); per side
// the largest attenuated arc wins (no double counting), and the occluded
// mass is normalised by the slices' own unoccluded mass (a ratio
// estimator: a plane is exactly 1 whatever the slice directions).
float occ_scheer_gt(vec3 P, vec3 n, float r, vec3 rnd, vec2 px) {
    float rpx = r * u_intr.x / P.z;
    if (!(rpx >= 1.0)) return 0.0;
    rpx = min(rpx, float(max(u_full.x, u_full.y)));
    float a = rnd.x * AO_PI / float(u_slice_count);
    vec2 rot = vec2(cos(a), sin(a));
    float occ = 0.0, total = 0.0;
    for (int i = 0; i < u_slice_count; i++) {
        ao_slice sl = make_slice(P, n, slice_dir(i, rot));
        float lo1 = sl.g + AO_HALF_PI, lo0 = sl.g - AO_HALF_PI;
        float m1 = slice_arc(lo1, sl.g), m0 = slice_arc(lo0, sl.g);
        float best[2] = float[2](0.0, 0.0);
        for (int j = 0; j < u_steps; j++)
            for (int side = 0; side < 2; side++) {
                vec3 S;
                if (!slice_sample(px, sl.d, side, j, rnd.y, rpx, S)) continue;
                vec3 v = S - P;
                float l = length(v);
                if (!(l > 0.0) || !(l <= r)) continue;
                float t = acos(clamp(dot(v, sl.V) / l, -1.0, 1.0));
                float ln = l / r, att = 1.0 / (1.0 + u_c * ln * ln);
                // occluded arc: from the horizon down to the hemisphere's end
                float arc = side == 0 ? m1 - slice_arc(min(t, lo1), sl.g) : slice_arc(max(-t, lo0), sl.g) - m0;
                best[side] = max(best[side], att * max(arc - u_bias * (side == 0 ? m1 : -m0), 0.0));
            }
        occ += sl.nl * (best[0] + best[1]);
        total += sl.nl * (m1 - m0);
    }
    return total > 0.0 ? occ / total : 0.0;
}

// scheer-bm: Scheer & Keutel's quasi-normalised
// attenuation inside the visibility bitmask's sector weights. The samples
// of a slice side march outwards; each marks the sectors between its front
// face and `thickness * r` behind it like the bitmask, but only the sectors
// no nearer sample has claimed count, and they count with that sample's
// 1/(1 + c l^2), l = |v| / r. A near occluder darkens fully, one at the
// radius by 1/(1+c); with c = 0 it is the bitmask exactly. With the
// depth-scaled radius the whole estimate is scale-free (l, the sectors
// and the thickness are all in units of r).
float occ_scheer_bm(vec3 P, vec3 n, float r, vec3 rnd, vec2 px) {
    float rpx = r * u_intr.x / P.z;
    if (!(rpx >= 1.0)) return 0.0;
    rpx = min(rpx, float(max(u_full.x, u_full.y)));
    float a = rnd.x * AO_PI / float(u_slice_count);
    vec2 rot = vec2(cos(a), sin(a));
    float th = u_thickness * r;
    float occ = 0.0, total = 0.0;
    for (int i = 0; i < u_slice_count; i++) {
        ao_slice sl = make_slice(P, n, slice_dir(i, rot));
        float a0 = slice_arc(sl.g - AO_HALF_PI, sl.g), mass = slice_arc(sl.g + AO_HALF_PI, sl.g) - a0;
        if (!(mass > 1e-6)) continue;
        float inv_mass = 1.0 / mass;
        uint bits = 0u;
        float occw = 0.0;                            // attenuated count of claimed sectors
        for (int j = 0; j < u_steps; j++)
            for (int side = 0; side < 2; side++) {
                vec3 S;
                if (!slice_sample(px, sl.d, side, j, rnd.y, rpx, S)) continue;
                vec3 v = S - P;
                float l = length(v);
                if (!(l > 0.0) || !(l <= r)) continue;
                vec3 vb = S + normalize(S) * th - P;
                float tf = acos(clamp(dot(v, sl.V) / l, -1.0, 1.0));
                float tb = acos(clamp(dot(vb, sl.V) / max(length(vb), 1e-30), -1.0, 1.0));
                float sg = side == 0 ? 1.0 : -1.0;
                uint nb = sector_bits(min(sg * tf, sg * tb), max(sg * tf, sg * tb), sl.g, a0, inv_mass) & ~bits;
                float ln = l / r;
                occw += float(bitCount(nb)) / (1.0 + u_c * ln * ln);
                bits |= nb;
            }
        occ += sl.nl * mass * occw / 32.0;
        total += sl.nl * mass;
    }
    return total > 0.0 ? occ / total : 0.0;
}

void main() {
    ivec2 ap = ivec2(gl_FragCoord.xy);
    if (u_deint != 0) {
        g_layer = min(ap / u_dq, ivec2(3));
        ivec2 t = ap - g_layer * u_dq;
        ap = 4 * t + g_layer;
        ivec2 an = (u_full + u_step - 1) / u_step;   // the AO image's size
        if (any(greaterThanEqual(ap, an))) { o_ao = 1.0; return; } // a layer's padding texel
        g_tmax = (an - 1 - g_layer) / 4;
    }
    ivec2 fp = ap * u_step;
    g_fp = fp;
    vec3 P;
    if (!fetch_pos(fp, P)) { o_ao = 1.0; return; }   // sky: unoccluded
    if (u_use_mask != 0 || u_method == M_MASK_STANDALONE) {
        bool in_mask = texelFetch(u_mask, fp, 0).r > 1.5;
        // Stand-alone (Park & Baek sec. 5): the highlighted corners are the
        // occlusion, with a strength of their own (clamped to [0,1] on the
        // CPU) so the value is a visibility before the blur averages it.
        if (u_method == M_MASK_STANDALONE) { o_ao = in_mask ? 1.0 - u_mask_strength : 1.0; return; }
        if (!in_mask) { o_ao = 1.0; return; }        // OdSSAO: nothing to do here
    }
    vec3 n = ao_normal(u_normal, fp, P);
    vec3 rnd = ao_rand3(ap);
    if (u_deint != 0) {
        // One rotation per layer, the 16 layers spread by a 4x4 Bayer
        // order (neighbours differ most), so the blur's window sees all 16.
        const int bayer[16] = int[16](0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5);
        float b = float(bayer[g_layer.y * 4 + g_layer.x]);
        rnd = vec3((b + 0.5) / 16.0, fract(0.31 + b * 0.6180339887), fract(0.17 + b * 0.7548776662));
    }
    if (u_noise != 0) {
        // The surface point's cell in the anchor's frame, the same in every
        // view that shares the anchor: a grid of u_noise_cell scene units
        // (1), or the anchor camera's pixels grouped u_noise_cell x
        // u_noise_cell (2: cells as fine as the image wherever the point is).
        vec3 a = (u_noise_frame * vec4(P, 1.0)).xyz;
        vec3 w = a / u_noise_cell;
        if (u_noise == 2) w = a.z > 0.0 ? vec3(a.xy / a.z * u_intr.xy / u_noise_cell, 0.0) : vec3(vec2(ap), 1.0);
        ivec3 c = ivec3(clamp(floor(w), vec3(-2.0e9), vec3(2.0e9)));
        rnd = vec3(ao_pcg3(uvec3(c) ^ uvec3(0x9e3779b9u, 0x85ebca6bu, 0xc2b2ae35u)) >> 8u) * (1.0 / 16777216.0);
    }
    // Temporal accumulation: the per-pixel numbers move on every frame (a
    // Cranley-Patterson shift by the R3 sequence), so frames average to
    // more samples; frame 0 keeps the fixed noise of a single frame.
    if (u_frame != 0) rnd = fract(rnd + vec3(0.8191725134, 0.6710436067, 0.5497004779) * float(u_frame));
    vec3 plane = random_plane(rnd);
    float r0 = u_radius_mode == 0 ? u_screen_k * P.z : u_radius;
    float occ = 0.0;
    for (int k = 0; k < u_radii; k++) {
        float r = r0 * exp2(-float(k));
        if (!(r > 0.0) || isinf(r)) continue;
        float o = 0.0;
        if (u_method == M_SCHEER) o = occ_scheer(P, n, r, plane);
        else if (u_method == M_CRYTEK) o = occ_crytek(P, n, r, plane);
        else if (u_method == M_FILION) o = occ_filion(P, n, r, plane);
        else if (u_method == M_HBAO) o = occ_hbao(P, n, r, rnd, vec2(fp));
        else if (u_method == M_ALCHEMY) o = occ_alchemy(P, n, r, rnd, vec2(fp));
        else if (u_method == M_GTAO) o = occ_gtao(P, n, r, rnd, vec2(fp));
        else if (u_method == M_BITMASK) o = occ_bitmask(P, n, r, rnd, vec2(fp));
        else if (u_method == M_SCHEER_GT) o = occ_scheer_gt(P, n, r, rnd, vec2(fp));
        else if (u_method == M_SCHEER_BM) o = occ_scheer_bm(P, n, r, rnd, vec2(fp));
        occ = max(occ, o);                           // multi-radius: the darkest radius wins
    }
    float ao = 1.0 - u_strength * occ;
    o_ao = isnan(ao) ? 1.0 : clamp(ao, 0.0, 1.0);
}
