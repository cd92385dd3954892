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

layout(location = MR_LOC_AO_NOISE) uniform int u_noise;         // 0 pixel hash, 1 world-position hash
layout(location = MR_LOC_AO_NOISE_CELL) uniform float u_noise_cell; // grid cell of the hash (scene units)
layout(location = MR_LOC_AO_NOISE_FRAME) uniform mat4 u_noise_frame; // anchor_from_camera

layout(location = MR_LOC_AO_DISPLAY) uniform vec3 u_display;       // D, E, width; D = 0: pinhole

layout(binding = MR_TEX_AO_DEPTH) uniform sampler2D u_depth;
layout(binding = MR_TEX_AO_NORMAL) uniform sampler2D u_normal;
layout(binding = MR_TEX_AO_POSITIONS) uniform sampler2D u_pos;
layout(binding = MR_TEX_AO_MASK) uniform sampler2D u_mask;

layout(location = 0) out float o_ao;

#define M_SCHEER MR_AO_METHOD_ID_SCHEER
#define M_CRYTEK MR_AO_METHOD_ID_CRYTEK
#define M_FILION MR_AO_METHOD_ID_FILION
#define M_HBAO MR_AO_METHOD_ID_HBAO
#define M_ALCHEMY MR_AO_METHOD_ID_ALCHEMY
#define M_MASK_STANDALONE MR_AO_METHOD_MASK_STANDALONE

bool fetch_pos(ivec2 q, out vec3 p) {
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

void main() {
    ivec2 ap = ivec2(gl_FragCoord.xy);
    ivec2 fp = ap * u_step;
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
        occ = max(occ, o);                           // multi-radius: the darkest radius wins
    }
    float ao = 1.0 - u_strength * occ;
    o_ao = isnan(ao) ? 1.0 : clamp(ao, 0.0, 1.0);
}
