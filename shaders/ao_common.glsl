// Shared by the AO passes: G-buffer reads in view space (OpenCV axes) and a
// per-pixel hash. Pulled in with #include "ao_common.glsl" (which includes
// nothing itself: includes are one level deep).

// Reversed-Z float depth d = near / z, cleared to 0 (infinity): z = near / d.
// A pixel is geometry when d > 0 and z is finite; d denormal gives z = inf,
// which counts as sky so that nothing downstream divides by it.
bool ao_view_pos(sampler2D depth_tex, sampler2D pos_tex, bool use_pos, float near_plane, vec4 intr,
                 ivec2 q, out vec3 p) {
    p = vec3(0.0);
    if (use_pos) {
        vec4 t = texelFetch(pos_tex, q, 0);
        p = t.xyz;
        return t.w > 0.0;
    }
    float d = texelFetch(depth_tex, q, 0).r;
    if (!(d > 0.0)) return false;
    float z = near_plane / d;
    if (isinf(z) || isnan(z)) return false;
    p = vec3((vec2(q) - intr.zw) / intr.xy * z, z);
    return true;
}

// A unit normal from the G-buffer; a zero or broken one becomes the
// direction towards the camera, so no normalize() ever sees a zero vector.
vec3 ao_normal(sampler2D normal_tex, ivec2 q, vec3 p) {
    vec3 n = texelFetch(normal_tex, q, 0).xyz;
    float l2 = dot(n, n);
    if (!(l2 > 1e-12) || isinf(l2)) {
        float pl = dot(p, p);
        return pl > 0.0 && !isinf(pl) ? -p * inversesqrt(pl) : vec3(0.0, 0.0, -1.0);
    }
    return n * inversesqrt(l2);
}

// PCG-style integer hash: decorrelated per-pixel random numbers in [0,1).
uvec3 ao_pcg3(uvec3 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    v ^= v >> 16u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    return v;
}
vec3 ao_rand3(ivec2 q) {
    return vec3(ao_pcg3(uvec3(uint(q.x), uint(q.y), 0x9e3779b9u)) >> 8u) * (1.0 / 16777216.0);
}
