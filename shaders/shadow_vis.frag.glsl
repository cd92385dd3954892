// Visibility of the casting light at each G-buffer pixel, from the shadow
// map (Hecher's comparison, ch. 3): hard, PCF, PCSS (Fernando 2005),
// backprojection (Guennebaud et al. 2006), or one hard sample of the
// ground truth's average (weighted, blended additively by the caller).
//
// Light space: the light eye's OpenCV axes (z along the light's axis).
// Perspective lights (rect, sphere) sit at z = 0 with uv = 0.5 + k xy/z;
// the sun projects orthographically, uv = (xy - x0y0) / wxy. Sizes: u_half
// is the light's half-width (scene units) for a perspective light and
// tan(angle / 2) for the sun, so the formulas below stay scale-free.
//
// Receiver-plane depth bias: the receiver's light-space depth is treated as
// a plane over the kernel, dz/duv = J^-T (dz/dx, dz/dy), with J the Jacobian
// of uv with respect to the screen. The screen differences are taken from
// the neighbour pixel on the side with the smaller depth step (dFdx's
// one-sided choice at depth edges, where a 2x2 quad would straddle two
// surfaces). Each tap compares at its texel centre, where the map's depth
// was rasterised, so planar receivers compare exactly.
#include "mr_bindings.h"
#include "common.glsl"

layout(location = MR_LOC_SHADOW_INTR) uniform vec4 u_intr;            // fx fy cx cy of the output
layout(location = MR_LOC_SHADOW_NEAR) uniform float u_near;
layout(location = MR_LOC_SHADOW_LIGHT_FROM_CAM) uniform mat4 u_light_from_cam;
layout(location = MR_LOC_SHADOW_ORTHO) uniform int u_ortho;
layout(location = MR_LOC_SHADOW_RECT) uniform vec4 u_rect0;           // ortho: x0, y0, 1/wx, 1/wy (one map)
layout(location = MR_LOC_SHADOW_K) uniform float u_k;                 // perspective: uv per unit of x/z
layout(location = MR_LOC_SHADOW_ZRANGE) uniform vec2 u_zrange;        // nearest caster, farthest receiver
layout(location = MR_LOC_SHADOW_LIGHT_HALF) uniform float u_half;
layout(location = MR_LOC_SHADOW_METHOD) uniform int u_method;
layout(location = MR_LOC_SHADOW_TAPS) uniform int u_taps;
layout(location = MR_LOC_SHADOW_PCF_RADIUS) uniform float u_pcf_radius; // texels
layout(location = MR_LOC_SHADOW_MAP_SIZE) uniform int u_size;
layout(location = MR_LOC_SHADOW_OFFSET) uniform vec3 u_offset;        // ground-truth sample (as the map)
layout(location = MR_LOC_SHADOW_SHEAR) uniform vec2 u_shear;
layout(location = MR_LOC_SHADOW_WEIGHT) uniform float u_weight;       // ground truth: 1 / samples
layout(location = MR_LOC_SHADOW_MAX_SEARCH) uniform float u_max_search; // texels
layout(location = MR_LOC_SHADOW_LIGHT_AREA) uniform vec2 u_light_half2; // BP: half extents on the light plane
layout(location = MR_LOC_SHADOW_KERNEL) uniform vec2 u_kernel[MR_SHADOW_KERNEL_SIZE]; // unit-disk taps
// Sun cascades: the maps are tiles of one atlas, cascade k at
// ((k & 1) S, (k >> 1) S); each has its own rectangle in the shared light
// frame (same axes and depth), so every size below that is in texels or uv
// follows the chosen cascade's texel. A pixel takes the cascade of its
// camera depth; over a band past each split both neighbours cover it
// (the nearer was fitted that far) and the visibility blends linearly.
layout(location = MR_LOC_SHADOW_CASCADES) uniform int u_cascades;     // 0: one map (u_rect0)
layout(location = MR_LOC_SHADOW_SPLITS) uniform vec4 u_splits;
layout(location = MR_LOC_SHADOW_BAND) uniform float u_band;
layout(location = MR_LOC_SHADOW_RECTS) uniform vec4 u_rects[MR_SHADOW_CASCADES_MAX];

layout(binding = MR_TEX_SHADOW_DEPTH) uniform sampler2D u_depth;      // reversed-Z G-buffer depth
layout(binding = MR_TEX_SHADOW_MAP) uniform sampler2D u_map;          // R32F linear light depth
layout(binding = MR_TEX_SHADOW_NORMAL) uniform sampler2D u_normal;    // G-buffer view normal

layout(location = 0) out float o_vis;

vec4 u_rect;     // the cascade's rectangle (ortho: x0, y0, 1/wx, 1/wy)
ivec2 g_tile;    // the cascade's texel offset in the atlas

bool nn_valid(vec3 n) { return dot(n, n) > 0.25; }

vec3 cam_pos(ivec2 px) {
    float d = texelFetch(u_depth, px, 0).r;
    if (d <= 0.0) return vec3(0.0);
    float z = u_near / d;
    vec2 p = vec2(px);
    return vec3((p - u_intr.zw) / u_intr.xy * z, z);
}

vec3 light_pos(vec3 pc) {
    vec3 l = (u_light_from_cam * vec4(pc, 1.0)).xyz - u_offset;
    l.xy -= u_shear * l.z;
    return l;
}

vec2 light_uv(vec3 l) { return u_ortho != 0 ? (l.xy - u_rect.xy) * u_rect.zw : 0.5 + u_k * l.xy / l.z; }

// uv per unit of the kernel's radius (world units for the sun, x/z for perspective)
vec2 uv_scale() { return u_ortho != 0 ? u_rect.zw : vec2(u_k); }

// The blocker-search / penumbra radius for depth z: how far (kernel units)
// the light, seen from the receiver at zR, reaches in the map at depth z.
float light_reach(float z, float zR) {
    return u_ortho != 0 ? u_half * max(zR - z, 0.0) : u_half * max(1.0 / z - 1.0 / zR, 0.0);
}

float g_zR;      // receiver depth
vec2 g_uvR;      // receiver uv
vec2 g_grad;     // dz/duv of the receiver plane
float g_bias;
vec3 g_lR;       // receiver in light space (normal-offset)

float tap_depth(ivec2 t) { return texelFetch(u_map, t + g_tile, 0).r; }
bool inside(ivec2 t) { return all(greaterThanEqual(t, ivec2(0))) && all(lessThan(t, ivec2(u_size))); }
vec2 texel_centre(ivec2 t) { return (vec2(t) + 0.5) / float(u_size); }
float ref_depth(ivec2 t) { return g_zR + dot(g_grad, texel_centre(t) - g_uvR) - g_bias; }
float lit(ivec2 t) { return !inside(t) || tap_depth(t) >= ref_depth(t) ? 1.0 : 0.0; }
ivec2 texel_of(vec2 uv) { return ivec2(floor(uv * float(u_size))); }

mat2 g_rot;
vec2 tap(int i, vec2 radius_uv) { return g_uvR + (g_rot * u_kernel[i]) * radius_uv; }

float pcf(vec2 radius_uv) {
    float s = 0.0;
    for (int i = 0; i < u_taps; i++) s += lit(texel_of(tap(i, radius_uv)));
    return s / float(u_taps);
}

// Mean depth of the blockers in the search disk; < 0: none.
float blocker_depth(vec2 radius_uv) {
    float sum = 0.0, n = 0.0;
    for (int i = 0; i < u_taps; i++) {
        ivec2 t = texel_of(tap(i, radius_uv));
        if (!inside(t)) continue;
        float z = tap_depth(t);
        if (z < ref_depth(t)) { sum += z; n += 1.0; }
    }
    return n > 0.0 ? sum / n : -1.0;
}

// A point of the map (uv, depth z) in light-space xy (scene units).
vec2 map_xy(vec2 uv, float z) { return u_ortho != 0 ? u_rect.xy + uv / u_rect.zw : (uv - 0.5) / u_k * z; }
// Where the line from the receiver through a point at (xy, z) meets the
// light: the light plane z = 0 for perspective lights (scene units), the
// direction's tangent for the sun.
vec2 on_light(vec3 r, vec2 xy, float z) {
    float t = r.z - z;
    return u_ortho != 0 ? (xy - r.xy) / t : r.xy + (xy - r.xy) * r.z / t;
}

// Backprojection: every blocking texel of the search area is a
// light-parallel micro-patch at its depth; its projection through the
// receiver onto the light, clipped to the light, occludes that area. Gap
// filling: a patch reaches to its right and lower neighbour's edge when the
// neighbour blocks too (projected at the neighbour's depth), so a tilted
// blocker leaves no cracks between the patches of its texels.
//
// A texel blocks when it lies nearer the light than the receiver's plane
// there and than the receiver point itself, both by a clearance of two
// texels. The receiver point matters where the plane falls away from the
// light (a wall the sun grazes): extrapolated over the search area the plane
// runs deeper than the receiver, and a patch between the two depths is
// behind the receiver, yet its projection (through a point it does not face)
// would be huge or flipped and black out the light.
//
// The search area comes from the min / max depth pyramid (Guennebaud et al.
// 2006): the blockers of a receiver lie in the pyramid from it to the light,
// no nearer than the least depth under the area, so the area is the
// pyramid's slice at that depth; a finer level's least depth under the
// smaller area shrinks it again. Traversed by pyramid cells: a cell whose
// least depth is behind every texel's threshold is skipped whole; a cell
// whose greatest depth blocks everywhere (one surface: a depth range of a
// few texels) hides the part of the light that its footprint covers at both
// its least and its greatest depth, the whole light: umbra.
layout(location = MR_LOC_SHADOW_PYRAMID) uniform ivec2 u_pyr;         // P, top level (-1: none, full search)
layout(binding = MR_TEX_SHADOW_MINMAX) uniform sampler2D u_minmax;    // RG32F min / max depth pyramid
ivec2 g_ptile;   // the cascade's pyramid tile origin at level 0
float g_clear;   // the blocker clearance (scene depth)

vec2 cell_mm(int l, ivec2 c) {
    int n = u_pyr.x >> l;
    if (any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, ivec2(n)))) return vec2(1e30);
    return texelFetch(u_minmax, (g_ptile >> l) + c, l).rg;
}

// Depth under which texel t blocks the receiver.
float bp_thr(ivec2 t) { return min(ref_depth(t), g_zR - g_bias) - g_clear; }
// The least and the greatest bp_thr over the texels t0..t1 (it is linear).
vec2 bp_thr_range(ivec2 t0, ivec2 t1) {
    vec2 c = 0.5 * (texel_centre(t0) + texel_centre(t1)), h = 0.5 * (texel_centre(t1) - texel_centre(t0));
    float m = g_zR + dot(g_grad, c - g_uvR), e = dot(abs(g_grad), h);
    return vec2(min(m - e, g_zR), min(m + e, g_zR)) - g_bias - g_clear;
}
bool bp_blocks(ivec2 t, float z) { return inside(t) && z > 0.0 && z < bp_thr(t); }

// The search area's half extents (uv) for blockers no nearer than z.
vec2 bp_reach(float z) {
    float f = u_ortho != 0 ? max(g_zR - z, 0.0) : max(1.0 / z - 1.0 / g_zR, 0.0);
    return min(u_light_half2 * f * uv_scale(), vec2(u_max_search / float(u_size)));
}

float bp_patch(vec3 r, ivec2 t, float z, vec2 lh) {
    float S = float(u_size);
    vec2 lo = vec2(t) / S, hi = (vec2(t) + 1.0) / S;
    ivec2 tx = t + ivec2(1, 0), ty = t + ivec2(0, 1);
    float zx = inside(tx) ? tap_depth(tx) : z, zy = inside(ty) ? tap_depth(ty) : z;
    // Only neighbours of the same surface (a depth step under four
    // texels' length, i.e. tilted less than ~76 degrees) are joined:
    // across a depth edge the gap is real.
    float tl = u_ortho != 0 ? 1.0 / (S * min(u_rect.z, u_rect.w)) : z / (S * u_k);
    bool bx = bp_blocks(tx, zx) && abs(zx - z) < 4.0 * tl;
    bool by = bp_blocks(ty, zy) && abs(zy - z) < 4.0 * tl;
    // Corners on the light of the patch (at its own depth).
    vec2 a = on_light(r, map_xy(lo, z), z), b = on_light(r, map_xy(hi, z), z);
    vec2 pmin = min(a, b), pmax = max(a, b);
    // Gap filling: stretch to the neighbour's shared edge.
    if (bx) {
        float ex = on_light(r, map_xy(vec2(hi.x, lo.y), zx), zx).x;
        pmin.x = min(pmin.x, ex); pmax.x = max(pmax.x, ex);
    }
    if (by) {
        float ey = on_light(r, map_xy(vec2(lo.x, hi.y), zy), zy).y;
        pmin.y = min(pmin.y, ey); pmax.y = max(pmax.y, ey);
    }
    vec2 e = max(min(pmax, lh) - max(pmin, -lh), vec2(0.0));
    return e.x * e.y;
}

// The part of the light (as its area) that the texels t0..t1 cover from
// the receiver at every depth in [za, zb]: their footprint projected at
// both depths, intersected, clipped to the light.
float bp_cover(vec3 r, ivec2 t0, ivec2 t1, float za, float zb, vec2 lh) {
    float S = float(u_size);
    vec2 lo = vec2(t0) / S, hi = (vec2(t1) + 1.0) / S;
    vec2 a0 = on_light(r, map_xy(lo, za), za), a1 = on_light(r, map_xy(hi, za), za);
    vec2 b0 = on_light(r, map_xy(lo, zb), zb), b1 = on_light(r, map_xy(hi, zb), zb);
    vec2 c0 = max(max(min(a0, a1), min(b0, b1)), -lh), c1 = min(min(max(a0, a1), max(b0, b1)), lh);
    vec2 e = max(c1 - c0, vec2(0.0));
    return e.x * e.y;
}

float backprojection(vec3 r) {
    vec2 lh = u_light_half2;
    float area_l = 4.0 * lh.x * lh.y;
    float S = float(u_size);
    int top = u_pyr.y;
    bool hier = top >= 0;
    g_clear = 2.0 * (u_ortho != 0 ? 1.0 / (S * min(u_rect.z, u_rect.w)) : g_zR / (S * u_k));
    // The search area: from the tile's least depth, then each level's least
    // depth under the area found so far.
    float zmin = hier ? cell_mm(top, ivec2(0)).x : u_zrange.x;
    vec2 rad = bp_reach(zmin);
    ivec2 t0 = texel_of(g_uvR - rad), t1 = texel_of(g_uvR + rad);
    for (int it = 0; hier && it < 4; it++) {
        if (zmin >= bp_thr_range(t0, t1).y) return 1.0; // nothing there is nearer than the receiver
        int side = max(t1.x - t0.x, t1.y - t0.y) + 1;
        // Cells of at least half the area's side: at most 3 x 3 of them.
        int l = clamp(int(ceil(log2(0.5 * float(side)))), 0, top);
        ivec2 c0 = t0 >> l, c1 = t1 >> l;
        float zl = 1e30;
        for (int y = c0.y; y <= c1.y; y++)
            for (int x = c0.x; x <= c1.x; x++) zl = min(zl, cell_mm(l, ivec2(x, y)).x);
        bool tighter = zl > zmin;
        zmin = max(zmin, zl);
        if (!tighter) break;
        rad = min(rad, bp_reach(zmin));
        t0 = texel_of(g_uvR - rad);
        t1 = texel_of(g_uvR + rad);
        if (l == 0) break;
    }
    if (hier && zmin >= bp_thr_range(t0, t1).y) return 1.0;
    // Off the map is lit.
    t0 = max(t0, ivec2(0));
    t1 = min(t1, ivec2(u_size - 1));
    if (any(greaterThan(t0, t1))) return 1.0;
    int side = max(t1.x - t0.x, t1.y - t0.y) + 1;
    int lc = hier ? clamp(int(ceil(log2(float(side) / 8.0))), 0, top) : 0; // at most 9 x 9 cells
    int cs = 1 << lc;
    float occ = 0.0;
    ivec2 c0 = t0 >> lc, c1 = t1 >> lc;
    for (int cy = c0.y; cy <= c1.y; cy++)
        for (int cx = c0.x; cx <= c1.x; cx++) {
            ivec2 c = ivec2(cx, cy);
            ivec2 a = max(c * cs, t0), b = min(c * cs + (cs - 1), t1);
            vec2 mm = hier ? cell_mm(lc, c) : vec2(0.0, 1e30);
            vec2 thr = bp_thr_range(a, b);
            if (mm.x >= thr.y) continue; // no texel of the cell blocks
            float tlc = u_ortho != 0 ? 1.0 / (S * min(u_rect.z, u_rect.w)) : mm.x / (S * u_k);
            if (mm.y < thr.x && mm.x > 0.0 && mm.y - mm.x < 6.0 * tlc * float(cs) &&
                bp_cover(r, a, b, mm.x, mm.y, lh) >= area_l * 0.9999)
                return 0.0; // umbra
            for (int y = a.y; y <= b.y; y++)
                for (int x = a.x; x <= b.x; x++) {
                    ivec2 t = ivec2(x, y);
                    float z = tap_depth(t);
                    if (bp_blocks(t, z)) occ += bp_patch(r, t, z, lh);
                }
        }
    return 1.0 - min(1.0, occ / area_l);
}

float visibility(ivec2 px, vec3 pc) {
    vec3 l = light_pos(pc);
    if (u_ortho == 0 && l.z <= 0.0) return 1.0; // behind the light's plane
    // Normal offset: a receiver seen edge-on by the light (a wall under a
    // light straight above) has no plane the map can resolve; lifting it a
    // map texel off its surface, more the more it turns away, keeps it off
    // its own texels. Scale-free: a texel's length at the receiver.
    {
        vec3 n = texelFetch(u_normal, px, 0).xyz;
        float tl = u_ortho != 0 ? 1.0 / (float(u_size) * min(u_rect.z, u_rect.w)) : l.z / (float(u_size) * u_k);
        vec3 ln = nn_valid(n) ? normalize(mat3(u_light_from_cam) * n) : vec3(0.0, 0.0, -1.0);
        float edge = clamp(1.0 - abs(ln.z), 0.0, 1.0);
        // A surface turned away from the light (from its sample, for the
        // ground truth) gets none of it: its own far side blocks it, which
        // the map of an edge-on surface cannot tell.
        vec3 to_light = u_ortho != 0 ? normalize(vec3(-u_shear, -1.0)) : normalize(u_offset - (l + u_offset));
        if (dot(ln, to_light) <= 0.0 && nn_valid(n)) return 0.0;
        vec3 lo = light_pos(pc + n * (1.5 * tl * edge));
        g_lR = lo;
        g_zR = lo.z;
        g_uvR = light_uv(lo);
    }
    // Receiver plane from the screen neighbours.
    vec3 d[2];
    vec2 duv[2];
    for (int a = 0; a < 2; a++) {
        ivec2 e = a == 0 ? ivec2(1, 0) : ivec2(0, 1);
        vec3 pp = cam_pos(px + e), pm = cam_pos(px - e);
        bool use_p = pp.z > 0.0 && (pm.z <= 0.0 || abs(pp.z - pc.z) <= abs(pm.z - pc.z));
        vec3 q = use_p ? pp : pm;
        float sgn = use_p ? 1.0 : -1.0;
        if (q.z <= 0.0) { d[a] = vec3(0.0); duv[a] = vec2(0.0); continue; }
        vec3 lq = light_pos(q);
        duv[a] = (light_uv(lq) - light_uv(l)) * sgn;
        d[a] = vec3(0.0, 0.0, (lq.z - l.z) * sgn);
    }
    mat2 J = mat2(duv[0], duv[1]);   // columns: d uv / d screen x, d uv / d screen y
    float det = determinant(J);
    g_grad = vec2(0.0);
    if (abs(det) > 1e-20) g_grad = transpose(inverse(J)) * vec2(d[0].z, d[1].z);
    // A slope steeper than 89 degrees is an edge, not a plane.
    float texel_len = u_ortho != 0 ? 1.0 / (float(u_size) * max(u_rect.z, u_rect.w))
                                   : l.z / (float(u_size) * u_k);
    float max_slope = 57.0 * texel_len * float(u_size);
    float gl = length(g_grad);
    if (!(gl <= max_slope)) g_grad = gl > 0.0 && !isinf(gl) && !isnan(gl) ? g_grad * (max_slope / gl) : vec2(0.0);
    // Float rounding of the two depth paths, relative to the depth range.
    g_bias = 2e-5 * max(u_zrange.y, abs(l.z)) + 0.02 * texel_len;
    float ang = 6.2831853 * fract(sin(dot(vec2(px), vec2(12.9898, 78.233))) * 43758.5453);
    g_rot = mat2(cos(ang), sin(ang), -sin(ang), cos(ang));
    float texel_uv = 1.0 / float(u_size);
    float max_uv = u_max_search * texel_uv;
    float v;
    if (u_method == MR_SHADOW_METHOD_ID_HARD || u_method == MR_SHADOW_METHOD_ID_GROUNDTRUTH) {
        v = lit(texel_of(g_uvR));
    } else if (u_method == MR_SHADOW_METHOD_ID_PCF) {
        v = pcf(vec2(u_pcf_radius * texel_uv));
    } else {
        vec2 sc = uv_scale();
        vec2 search = min(light_reach(u_zrange.x, g_zR) * sc, vec2(max_uv));
        if (u_method == MR_SHADOW_METHOD_ID_BP) {
            v = backprojection(g_lR);
        } else {
            float zb = blocker_depth(search);
            if (zb < 0.0) {
                v = 1.0;
            } else {
                vec2 pen = clamp(light_reach(zb, g_zR) * sc, vec2(0.5 * texel_uv), vec2(max_uv));
                v = pcf(pen);
            }
        }
    }
    return v;
}

void use_cascade(int k) {
    u_rect = u_cascades > 0 ? u_rects[k] : u_rect0;
    g_tile = ivec2(k & 1, k >> 1) * u_size;
    g_ptile = ivec2(k & 1, k >> 1) * u_pyr.x;
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec3 pc = cam_pos(px);
    if (pc.z <= 0.0) { o_vis = u_weight; return; }
    int k = 0;
    while (k + 1 < u_cascades && pc.z > u_splits[k]) k++;
    use_cascade(k);
    float v = visibility(px, pc);
    // The seam band past the previous split: from its cascade to this one.
    if (k > 0) {
        float s = u_splits[k - 1], t = (pc.z - s) / (u_band * s);
        if (t < 1.0) {
            use_cascade(k - 1);
            v = mix(visibility(px, pc), v, clamp(t, 0.0, 1.0));
        }
    }
    o_vis = v * u_weight;
}
