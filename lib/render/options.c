/* The option tables of the renderer's params (mr_ao_opts, mr_ghost_opts):
 * key, type, field, range, default and help of every tunable the command
 * line, --help, settings files and the view's cycling expose. Defaults are
 * the MR_*_DEFAULT_* macros of mr_render.h, so each is written once. */
#include "mr_render.h"

#include <stddef.h>
#include <string.h>

const char *const mr_ao_method_names[MR_AO_METHOD_COUNT + 1] = {"none", "scheer", "crytek", "filion",
                                                                "hbao", "alchemy",
                                                                "gtao", "bitmask", "scheer-gt",
                                                                "scheer-bm", NULL};
static const char *const k_radius_mode_names[] = {"screen", "view", NULL};
static const char *const k_kernel_names[] = {"uniform", "stratified", "latin", "poisson", NULL};
static const char *const k_mask_names[] = {"off", "on", "standalone", NULL};
static const char *const k_noise_names[] = {"pixel", "world", NULL};

#define AO(f) offsetof(mr_ao_params, f)
const mr_opt mr_ao_opts[] = {
    {"", MR_OPT_ENUM, AO(method), 0, 0, MR_AO_NONE, mr_ao_method_names, "ambient occlusion", 0},
    {"radius-mode", MR_OPT_ENUM, AO(radius_mode), 0, 0, MR_AO_RADIUS_SCREEN, k_radius_mode_names,
     "screen: the radius grows with depth; view: a constant radius", 0},
    /* The radius in scene units has no fixed scale: any positive length. */
    {"radius", MR_OPT_DOUBLE, AO(radius), 1e-30, 1e30, 0, NULL,
     "view-space radius in scene units (implies --ao-radius-mode view; auto: 2% of the scene)", MR_OPT_ZERO_AUTO},
    {"screen-radius", MR_OPT_DOUBLE, AO(screen_radius), 1e-6, 10, MR_AO_DEFAULT_SCREEN_RADIUS, NULL,
     "screen mode: projected radius as a fraction of the image height", 0},
    {"samples", MR_OPT_INT, AO(samples), 1, MR_AO_MAX_SAMPLES, MR_AO_DEFAULT_SAMPLES, NULL, "samples per pixel", 0},
    {"kernel", MR_OPT_ENUM, AO(kernel), 0, 0, MR_AO_KERNEL_UNIFORM, k_kernel_names, "sample kernel", 0},
    {"rmin", MR_OPT_FLOAT, AO(r_min), 0, 1, MR_AO_DEFAULT_R_MIN, NULL,
     "kernel inner radius as a fraction of the radius (0 = the whole ball)", 0},
    {"rmax", MR_OPT_FLOAT, AO(r_max), 1e-3, 1, MR_AO_DEFAULT_R_MAX, NULL,
     "kernel outer radius as a fraction of the radius", 0},
    {"radii", MR_OPT_INT, AO(radii), 1, MR_AO_MAX_RADII, MR_AO_DEFAULT_RADII, NULL,
     "multi-radius: K radii R, R/2, ..; the darkest wins", 0},
    {"c", MR_OPT_FLOAT, AO(c), 0, 1e7, MR_AO_DEFAULT_C, NULL, "scheer attenuation c", 0},
    {"bias", MR_OPT_FLOAT, AO(bias), 0, 0.5, MR_AO_DEFAULT_BIAS, NULL,
     "bias (cosine / depth fraction of the radius)", 0},
    {"strength", MR_OPT_FLOAT, AO(strength), 0.01, 10, 0, NULL,
     "AO = 1 - S * occlusion (auto: per method, e.g. scheer 3)", MR_OPT_ZERO_AUTO},
    {"blur", MR_OPT_INT, AO(blur_radius), 0, 32, MR_AO_DEFAULT_BLUR_RADIUS, NULL,
     "bilateral blur half-width in AO pixels, 0 = off", 0},
    {"half", MR_OPT_BOOL, AO(half_res), 0, 1, 0, NULL, "AO at half resolution with a joint bilateral upsample", 0},
    {"positions", MR_OPT_BOOL, AO(positions), 0, 1, 0, NULL, "AO from a view-space positions texture", 0},
    {"mask", MR_OPT_ENUM, AO(mask), 0, 0, MR_AO_MASK_OFF, k_mask_names, "corner masking", 0},
    {"thickness", MR_OPT_FLOAT, AO(thickness), 1e-3, 100, MR_AO_DEFAULT_THICKNESS, NULL,
     "bitmask: assumed occluder depth; gtao, scheer-gt: thickness heuristic (fractions of the radius)", 0},
    {"temporal", MR_OPT_BOOL, AO(temporal), 0, 1, 0, NULL,
     "accumulate AO over frames (replay, view): reprojected history, rejected by depth and normal", 0},
    {"mask-strength", MR_OPT_FLOAT, AO(mask_strength), 1e-3, 1, MR_AO_DEFAULT_MASK_STRENGTH, NULL,
     "standalone mask: AO = 1 - S in the corners before the blur", 0},
    {"noise", MR_OPT_ENUM, AO(noise), 0, 0, MR_AO_NOISE_PIXEL, k_noise_names,
     "kernel rotation from a hash of the pixel or of the world position (stays on the surface across views)", 0},
    {"mips", MR_OPT_BOOL, AO(mips), 0, 1, 0, NULL,
     "gtao, bitmask, scheer-gt, scheer-bm: far samples read a depth mip chain", 0},
    {"deinterleave", MR_OPT_BOOL, AO(deinterleave), 0, 1, 0, NULL,
     "AO over 4x4 deinterleaved quarter-size depth layers, one rotation per layer", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef AO

const char *const mr_ghost_mode_names[] = {"off", "alpha", "g0", "adaptive", NULL};
static const char *const k_importance_names[] = {"auto", "curvature", "saliency", NULL};
static const char *const k_saliency_names[] = {"mipmap", "gauss", NULL};

#define GH(f) offsetof(mr_ghost_params, f)
const mr_opt mr_ghost_opts[] = {
    {"", MR_OPT_ENUM, GH(mode), 0, 0, MR_GHOST_OFF, mr_ghost_mode_names, "ghosted views of the hidden layer", 0},
    {"importance", MR_OPT_ENUM, GH(importance), 0, 0, MR_GHOST_IMP_AUTO, k_importance_names, "importance map", 0},
    {"saliency", MR_OPT_ENUM, GH(saliency), 0, 0, MR_SALIENCY_MIPMAP, k_saliency_names, "saliency pyramid", 0},
    {"opacity", MR_OPT_FLOAT, GH(opacity), 0, 1, MR_GHOST_DEFAULT_OPACITY, NULL, "occluder opacity scale (the paper's t, called a transparency there): alpha = t * IM", 0},
    {"curv-scale", MR_OPT_FLOAT, GH(curv_scale), 0, 1e3, MR_GHOST_DEFAULT_CURV_SCALE, NULL,
     "curvature (rad/px) to importance scale", 0},
    {"curv-bias", MR_OPT_FLOAT, GH(curv_bias), -1, 1, MR_GHOST_DEFAULT_CURV_BIAS, NULL,
     "importance bias: higher = denser occluder", 0},
    {"tc-min", MR_OPT_FLOAT, GH(tc_minimal), 0, 4, MR_GHOST_DEFAULT_TC_MINIMAL, NULL,
     "minimal desired contrast tc_minimal", 0},
    {"gamma", MR_OPT_FLOAT, GH(gamma), 0, 100, MR_GHOST_DEFAULT_GAMMA, NULL, "multiplier of IM in C_desired", 0},
    {"tc-sil", MR_OPT_FLOAT, GH(tc_silhouette), 0, 4, MR_GHOST_DEFAULT_TC_SILHOUETTE, NULL,
     "extra desired contrast on hidden silhouettes", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef GH

/* The names the AO pass and the command line share, through the table. */
const char *mr_ao_method_name(mr_ao_method m) { return mr_opt_enum_name(mr_opt_find(mr_ao_opts, ""), (int)m); }

bool mr_ao_method_parse(const char *name, mr_ao_method *out) {
    int v = mr_opt_enum_value(mr_opt_find(mr_ao_opts, ""), name);
    if (v >= 0) *out = (mr_ao_method)v;
    return v >= 0;
}

const char *mr_ao_kernel_name(mr_ao_kernel k) { return mr_opt_enum_name(mr_opt_find(mr_ao_opts, "kernel"), (int)k); }

bool mr_ao_kernel_parse(const char *name, mr_ao_kernel *out) {
    int v = mr_opt_enum_value(mr_opt_find(mr_ao_opts, "kernel"), name);
    if (v >= 0) *out = (mr_ao_kernel)v;
    return v >= 0;
}

/* Shadows (pass_shadow.c): --shadows METHOD and --shadows-KEY. */
const char *const mr_shadow_method_names[MR_SHADOW_METHOD_COUNT + 1] = {"off", "hard", "pcf", "pcss",
                                                                        "bp", "groundtruth", NULL};
#define SH(f) offsetof(mr_shadow_params, f)
const mr_opt mr_shadow_opts[] = {
    {"", MR_OPT_ENUM, SH(method), 0, 0, MR_SHADOW_OFF, mr_shadow_method_names,
     "soft shadows of the casting light", 0},
    {"map-size", MR_OPT_INT, SH(map_size), 64, 8192, MR_SHADOW_DEFAULT_MAP_SIZE, NULL, "shadow-map side in texels", 0},
    {"taps", MR_OPT_INT, SH(taps), 1, MR_SHADOW_MAX_TAPS, MR_SHADOW_DEFAULT_TAPS, NULL,
     "PCF / PCSS taps (and blocker-search taps)", 0},
    {"pcf-radius", MR_OPT_FLOAT, SH(pcf_radius), 0.01f, 64, MR_SHADOW_DEFAULT_PCF_RADIUS, NULL,
     "PCF kernel radius in shadow-map texels", 0},
    {"samples", MR_OPT_INT, SH(gt_samples), 1, 1024, MR_SHADOW_DEFAULT_GT_SAMPLES, NULL,
     "groundtruth: light samples (rounded to a square)", 0},
    {"light-scale", MR_OPT_FLOAT, SH(light_scale), 1e-6f, 1e6f, 1, NULL, "multiplies the light's size", 0},
    {"cascades", MR_OPT_INT, SH(cascades), 0, MR_SHADOW_MAX_CASCADES, 0, NULL,
     "sun: shadow-map cascades over the visible depth (0 = auto: 1 for a small scene, 2+ for a hall)", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef SH

bool mr_shadow_method_parse(const char *name, mr_shadow_method *out) {
    int v = mr_opt_enum_value(mr_opt_find(mr_shadow_opts, ""), name);
    if (v >= 0) *out = (mr_shadow_method)v;
    return v >= 0;
}

#define DR(f) offsetof(mr_draw_params, f)
const mr_opt mr_draw_opts[] = {
    {"cull", MR_OPT_BOOL, DR(no_cull), 0, 1, 1, NULL, "BVH frustum culling", MR_OPT_NEGATE | MR_OPT_ONOFF},
    {"batch", MR_OPT_BOOL, DR(no_batch), 0, 1, 1, NULL, "multi-draw-indirect batching", MR_OPT_NEGATE | MR_OPT_ONOFF},
    {"instancing", MR_OPT_BOOL, DR(no_instancing), 0, 1, 1, NULL, "one command per mesh instead of per node",
     MR_OPT_NEGATE | MR_OPT_ONOFF},
    /* No unit is assumed: by default only the projected error decides. */
    {"lod-tolerance", MR_OPT_DOUBLE, DR(lod_tolerance), 1e-12, 1e12, 0, NULL,
     "largest geometric error of a level in scene units (auto: none, pixels decide)", MR_OPT_ZERO_AUTO},
    {"lod-pixels", MR_OPT_DOUBLE, DR(lod_pixels), 1e-3, 1e4, MR_DRAW_DEFAULT_LOD_PIXELS, NULL,
     "largest projected error of a level in pixels", 0},
    {"occlusion", MR_OPT_BOOL, DR(occlusion), 0, 1, 0, NULL, "occlusion culling (exact; costs a depth read-back)",
     MR_OPT_ONOFF},
    {"occlusion-auto", MR_OPT_BOOL, DR(occlusion_auto), 0, 1, 1, NULL,
     "occlusion culling where it pays: decided per frame from its measured gain", MR_OPT_ONOFF},
    {"cluster-cull", MR_OPT_BOOL, DR(no_cluster_cull), 0, 1, 1, NULL,
     "frustum culling of the meshlets of big meshes", MR_OPT_NEGATE | MR_OPT_ONOFF},
    {"cluster-triangles", MR_OPT_INT, DR(cluster_triangles), 64, 1 << 30, MR_DRAW_DEFAULT_CLUSTER_TRIANGLES, NULL,
     "triangles from which a mesh level is split into meshlets (at upload)", MR_OPT_ZERO_DEFAULT},
    {"cluster-cone", MR_OPT_BOOL, DR(no_cluster_cone), 0, 1, 1, NULL,
     "also cull back-facing meshlets of single-sided materials (exact: their back faces are culled)",
     MR_OPT_NEGATE | MR_OPT_ONOFF},
    {"cluster-occlusion", MR_OPT_BOOL, DR(no_cluster_occlusion), 0, 1, 1, NULL,
     "also test meshlets against the occlusion pyramid where a frame culls by occlusion (exact)",
     MR_OPT_NEGATE | MR_OPT_ONOFF},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef DR

#define FR(f) offsetof(mr_frame_params, f)
const mr_opt mr_frame_opts[] = {
    {"alpha", MR_OPT_FLOAT, FR(alpha), 0, 1, MR_FRAME_DEFAULT_ALPHA, NULL,
     "video transparency: 0 = virtual only, 1 = video only", 0},
    {"hide-hidden", MR_OPT_BOOL, FR(hide_hidden_layer), 0, 1, 0, NULL, "leave the hidden layer out", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef FR

void mr_ao_sk_setup(mr_ao_sk_rendering d, mr_ao_params *p) {
    p->method = d == MR_AO_SK_D1 ? MR_AO_NONE : d == MR_AO_SK_D2 ? MR_AO_SCHEER : MR_AO_CRYTEK;
    p->radius_mode = d == MR_AO_SK_D3 ? MR_AO_RADIUS_VIEW : MR_AO_RADIUS_SCREEN;
}

const char *mr_ao_sk_role(mr_ao_method m, mr_ao_radius_mode mode) {
    if (m == MR_AO_NONE) return "D1";
    if (m == MR_AO_SCHEER && mode == MR_AO_RADIUS_SCREEN) return "D2";
    if (m == MR_AO_CRYTEK && mode == MR_AO_RADIUS_VIEW) return "D3";
    return "-";
}

bool mr_shadow_scene_default(const mr_cli_table *t, const mr_scene *s, mr_shadow_params *p, mr_error *err) {
    if (mr_cli_table_given(t, "") || !s || !s->shadow_method[0]) return true;
    if (!mr_shadow_method_parse(s->shadow_method, &p->method))
        return mr_fail(err, MR_ERR_INVALID, "%s: 'shadows' must be off, hard, pcf, pcss, bp or groundtruth, not '%s'",
                       s->source[0] ? s->source : "the scene config", s->shadow_method);
    return true;
}

bool mr_rig_opts_check(const mr_cli_table *t, const char *quilt_spec, bool lightfield, mr_quilt *quilt,
                       bool *have_quilt, mr_error *err) {
    const mr_rig_params *rp = t->params;
    *have_quilt = false;
    memset(quilt, 0, sizeof *quilt);
    if (quilt_spec) {
        mr_error qe = {0};
        if (!mr_quilt_parse(quilt_spec, quilt, &qe)) return mr_fail(err, MR_ERR_INVALID, "--quilt: %s", qe.msg);
        *have_quilt = true;
    }
    const bool rig_opt = mr_cli_table_given(t, "view-cone") || mr_cli_table_given(t, "view-fov") ||
                         mr_cli_table_given(t, "focal-distance");
    if (rp->views == 0 && !*have_quilt && !lightfield && rig_opt)
        return mr_fail(err, MR_ERR_INVALID, "--view-cone, --view-fov and --focal-distance need --views, --quilt or --lightfield");
    if (rp->views == 0 && !*have_quilt && mr_cli_table_given(t, "views-per-view-work"))
        return mr_fail(err, MR_ERR_INVALID, "--views-per-view-work needs --views or --quilt");
    if (lightfield && (rp->views > 0 || *have_quilt))
        return mr_fail(err, MR_ERR_INVALID, "--lightfield is one display image: not with --views or --quilt");
    return true;
}
