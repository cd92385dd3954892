/* mr_bindings.h — the interface between lib/render's C code and its GLSL:
 * uniform locations (MR_LOC_*), sampler units (MR_TEX_*), image units
 * (MR_IMG_*) and shader-storage bindings (MR_SSBO_*), grouped by program.
 * Each number is written here only: the shaders include this file (through
 * the shader embedder's one-level #include) and write
 * `layout(location = MR_LOC_X)`, the C side calls glUniform*(MR_LOC_X, ...).
 * Only #define lines and comments, so it is valid C and GLSL alike.
 * Programs that share a group (the three full-screen AO shaders; every
 * program that draws the scene through a view: MODELVIEW, NORMAL_MATRIX,
 * PROJECTION) share its numbers, so one C helper serves all of them. */
#ifndef MR_BINDINGS_H
#define MR_BINDINGS_H

/* Vertex attributes of the scene's geometry (geometry.c lays the buffers
 * out; gbuffer.vert reads all, ao_outline.vert and ghost_curv.vert read the
 * position and a stream of their own in a slot of the same numbering). */
#define MR_ATTR_POSITION                   0
#define MR_ATTR_NORMAL                     1
#define MR_ATTR_UV                         2
#define MR_ATTR_INSTANCE                   3  /* 9 slots: model-view (4), normal matrix (3), colour, ids */
#define MR_ATTR_INST_MODELVIEW             MR_ATTR_INSTANCE
#define MR_ATTR_INST_NORMAL0               (MR_ATTR_INSTANCE + 4)
#define MR_ATTR_INST_NORMAL1               (MR_ATTR_INSTANCE + 5)
#define MR_ATTR_INST_NORMAL2               (MR_ATTR_INSTANCE + 6)
#define MR_ATTR_INST_COLOR                 (MR_ATTR_INSTANCE + 7)
#define MR_ATTR_INST_IDS                   (MR_ATTR_INSTANCE + 8)
#define MR_ATTR_INSTANCE_SLOTS             9
#define MR_ATTR_OUTLINE_DIR                1  /* ao_outline: integrated normal */
#define MR_ATTR_CURVATURE                  3  /* ghost_curv: per-vertex curvature */
/* The UI's 2D vertices (lib/window/draw2d.c). */
#define MR_ATTR_UI_POS                     0
#define MR_ATTR_UI_UV                      1
#define MR_ATTR_UI_COLOR                   2

/* The G-buffer's colour outputs = its target's attachments (passes.c). */
#define MR_OUT_GBUFFER_ALBEDO              0
#define MR_OUT_GBUFFER_NORMAL              1
#define MR_OUT_GBUFFER_IDS                 2
#define MR_OUT_GBUFFER_POSITIONS           3
#define MR_OUT_GBUFFER_COUNT               4

/* The scene drawn through a view (gbuffer, ao_outline, ghost_curv). */
#define MR_LOC_MODELVIEW                   0
#define MR_LOC_NORMAL_MATRIX               1
#define MR_LOC_PROJECTION                  2
#define MR_LOC_GBUFFER_POS_OFFSET          3  /* gbuffer: band eye -> frame camera, added to positions */
/* ao_main, ao_blur, ao_upsample (full screen) */
#define MR_LOC_AO_INTR                     0
#define MR_LOC_AO_FULL                     1
#define MR_LOC_AO_STEP                     2
#define MR_LOC_AO_NEAR                     3
#define MR_LOC_AO_BLUR_DIR                 4
#define MR_LOC_AO_BLUR_RADIUS              5
#define MR_LOC_AO_SIZE                     6
#define MR_TEX_AO_DEPTH                    0
#define MR_TEX_AO_NORMAL                   1
#define MR_TEX_AO_POSITIONS                2
#define MR_TEX_AO_INPUT                    4

#define MR_LOC_AO_METHOD                   4
#define MR_LOC_AO_SAMPLES                  5
#define MR_LOC_AO_RADIUS_MODE              6
#define MR_LOC_AO_RADIUS                   7
#define MR_LOC_AO_SCREEN_K                 8
#define MR_LOC_AO_C                        9
#define MR_LOC_AO_BIAS                     10
#define MR_LOC_AO_STRENGTH                 11
#define MR_LOC_AO_RADII                    12
#define MR_LOC_AO_USE_POS                  13
#define MR_LOC_AO_USE_MASK                 14
#define MR_LOC_AO_MASK_STRENGTH            15
#define MR_LOC_AO_KERNEL                   16
#define MR_AO_KERNEL_SIZE                  128/* = MR_AO_MAX_SAMPLES (checked in pass_ao.c) */
#define MR_LOC_AO_KERNEL2                  (MR_LOC_AO_KERNEL + MR_AO_KERNEL_SIZE)
#define MR_TEX_AO_MASK                     3
/* gtao / bitmask / scheer-gt */
#define MR_LOC_AO_SLICES                   (MR_LOC_AO_KERNEL2 + MR_AO_KERNEL_SIZE) /* vec4[MR_AO_SLICES_SIZE]: xy slice direction */
#define MR_AO_SLICES_SIZE                  16 /* = MR_AO_MAX_SLICES */
#define MR_LOC_AO_SLICE_COUNT              (MR_LOC_AO_SLICES + MR_AO_SLICES_SIZE)
#define MR_LOC_AO_STEPS                    (MR_LOC_AO_SLICE_COUNT + 1)
#define MR_LOC_AO_THICKNESS                (MR_LOC_AO_SLICE_COUNT + 2)
#define MR_LOC_AO_FRAME                    (MR_LOC_AO_SLICE_COUNT + 3) /* temporal: frame index, 0 = the fixed noise */
/* ao_temporal, besides AO_INTR / AO_FULL / AO_NEAR and the AO textures */
#define MR_LOC_TAA_PREV_FROM_CUR           8
#define MR_LOC_TAA_PREV_INTR               9
#define MR_LOC_TAA_HAVE_HISTORY            10
#define MR_LOC_TAA_MAX_COUNT               11
#define MR_LOC_TAA_DEPTH_TOL               12
#define MR_LOC_TAA_NORMAL_COS              13
#define MR_TEX_TAA_HISTORY                 5
#define MR_TEX_TAA_HISTORY_N               6

/* ao_probe (the fetch floor) */
#define MR_LOC_PROBE_FETCHES               0
#define MR_LOC_PROBE_OFFSETS               1  /* vec4[MR_AO_KERNEL_SIZE] */
#define MR_TEX_PROBE_SRC                   0
/* multi-view: AO noise from the world position (after the kernels) */
#define MR_LOC_AO_NOISE                    (MR_LOC_AO_FRAME + 1)
#define MR_LOC_AO_NOISE_CELL               (MR_LOC_AO_NOISE + 1)
#define MR_LOC_AO_NOISE_FRAME              (MR_LOC_AO_NOISE + 2) /* mat4: 4 locations */
#define MR_LOC_AO_DISPLAY                  (MR_LOC_AO_NOISE + 6) /* vec3 D, E, width: light-field mapping */
/* The depth mip chain of the slice methods' far samples */
#define MR_LOC_AO_MIPS                     (MR_LOC_AO_DISPLAY + 1) /* int: levels above 0 in the chain, 0 = off */
#define MR_LOC_AO_MIP_NEAR                 (MR_LOC_AO_DISPLAY + 2) /* float: offset (px) below which level 0 is read */
#define MR_TEX_AO_DEPTH_MIP                5  /* ao_main: reversed-Z depth, R32F, box-filtered levels */
#define MR_TEX_AO_MIP_SRC                  0  /* ao_depth_mip: the G-buffer's depth */
/* Deinterleaved AO, 4x4 quarter-size layers in a tiled atlas */
#define MR_LOC_AO_DEINT                    (MR_LOC_AO_DISPLAY + 3) /* int: 1 = the target is the layer atlas */
#define MR_LOC_AO_DEINT_Q                  (MR_LOC_AO_DISPLAY + 4) /* ivec2: one layer's size (AO pixels / 4) */
#define MR_LOC_AO_DEINT_NEAR               (MR_LOC_AO_DISPLAY + 5) /* float: offsets (G-buffer px) below this read the G-buffer */
#define MR_TEX_AO_DEINT_DEPTH              6  /* ao_main: reversed-Z depth atlas, R32F, 4x4 tiles */
#define MR_TEX_AO_DEINT_SRC                0  /* ao_deint_split: the G-buffer's depth; ao_deint_merge: the AO atlas */
#define MR_LOC_AO_DEINT_SPLIT_Q            0  /* ao_deint_split / merge: ivec2 layer size */
#define MR_LOC_AO_DEINT_SPLIT_STEP         1  /* ao_deint_split: int G-buffer pixels per AO pixel */
#define MR_LOC_AO_DEINT_SPLIT_FULL         2  /* ao_deint_split: ivec2 G-buffer size */

/* ao_outline */
#define MR_LOC_OUTLINE_RADIUS_MODE         3
#define MR_LOC_OUTLINE_RADIUS              4
#define MR_LOC_OUTLINE_SCREEN_K            5

/* gbuffer */
#define MR_TEX_GBUFFER_BASE_COLOR          0

/* ghost_analysis */
#define MR_LOC_ANA_TC_MIN                  0
#define MR_LOC_ANA_GAMMA                   1
#define MR_LOC_ANA_TC_SIL                  2
#define MR_TEX_ANA_MASK                    0
#define MR_TEX_ANA_SAL                     1
#define MR_TEX_ANA_G0                      2
#define MR_IMG_ANA_C                       0

/* ghost_blur */
#define MR_LOC_GBLUR_DIR                   0
#define MR_LOC_GBLUR_SIGMA                 1
#define MR_LOC_GBLUR_RADIUS                2
#define MR_TEX_GBLUR_SRC                   0
#define MR_IMG_GBLUR_DST                   0

/* ghost_emphasis */
#define MR_LOC_EMPH_STAGE                  0
#define MR_LOC_EMPH_KEY_BASE               1
#define MR_LOC_EMPH_GAIN                   2
#define MR_TEX_EMPH_O                      0
#define MR_TEX_EMPH_D                      1
#define MR_TEX_EMPH_DGK                    2
#define MR_TEX_EMPH_GKC                    3
#define MR_TEX_EMPH_MASK                   4
#define MR_TEX_EMPH_G0                     5
#define MR_TEX_EMPH_KEY                    6
#define MR_TEX_EMPH_LABEL                  7
#define MR_IMG_EMPH_OUT                    0
#define MR_IMG_EMPH_OA                     1
#define MR_IMG_EMPH_GA                     2
#define MR_SSBO_EMPH_VOTES                 1

/* ghost_g0 */
#define MR_LOC_G0_MODE                     0
#define MR_LOC_G0_T                        1
#define MR_TEX_G0_O                        0
#define MR_TEX_G0_D                        1
#define MR_TEX_G0_MASK                     2
#define MR_IMG_G0_G0                       0
#define MR_IMG_G0_OUT                      1
#define MR_SSBO_G0_STATS                   0

/* ghost_importance */
#define MR_LOC_IMP_VIDEO                   0
#define MR_LOC_IMP_IMPORTANCE              1
#define MR_LOC_IMP_SCALE                   2
#define MR_LOC_IMP_BIAS                    3
#define MR_LOC_IMP_NEAR                    4
#define MR_LOC_IMP_FX                      5
#define MR_LOC_IMP_HAVE_SALIENCY           6
#define MR_TEX_IMP_DEPTH                   0
#define MR_TEX_IMP_NORMAL                  1
#define MR_TEX_IMP_IDS                     2
#define MR_TEX_IMP_HIDDEN_DEPTH            3
#define MR_TEX_IMP_HIDDEN_IDS              4
#define MR_TEX_IMP_CURVATURE               5
#define MR_TEX_IMP_SAL                     6
#define MR_IMG_IMP_MASK                    0
#define MR_IMG_IMP_KEY                     1
#define MR_SSBO_IMP_STATS                  0

/* ghost_lab */
#define MR_LOC_LAB_INVERSE                 0
#define MR_TEX_LAB_SRC                     0
#define MR_IMG_LAB_DST                     0

/* ghost_label */
#define MR_LOC_LABEL_INIT                  0
#define MR_TEX_LABEL_MASK                  0
#define MR_TEX_LABEL_KEY                   1
#define MR_TEX_LABEL_SRC                   2
#define MR_IMG_LABEL_DST                   0

/* ghost_saliency */
#define MR_LOC_SAL_IMPL                    0
#define MR_LOC_SAL_GAIN                    1
#define MR_LOC_SAL_MAX_LEVEL               2
#define MR_LOC_SAL_PRINTED                 3
#define MR_TEX_SAL_PYR                     0
#define MR_TEX_SAL_SURROUND                1
#define MR_IMG_SAL_DST                     0

/* ghost_stats */
#define MR_LOC_STATS_TC_MIN                0
#define MR_LOC_STATS_GAMMA                 1
#define MR_LOC_STATS_TC_SIL                2
#define MR_TEX_STATS_MASK                  0
#define MR_TEX_STATS_SAL                   1
#define MR_TEX_STATS_O                     2
#define MR_TEX_STATS_OA                    3
#define MR_TEX_STATS_C                     4
#define MR_SSBO_STATS_SUMS                 2

/* overlay */
#define MR_LOC_OVERLAY_OUT_K               0
#define MR_LOC_OVERLAY_VIDEO_K             1
#define MR_LOC_OVERLAY_VIDEO_SIZE          2
#define MR_LOC_OVERLAY_DIST                3
#define MR_LOC_OVERLAY_ALPHA               8
#define MR_TEX_OVERLAY_VIRTUAL             0
#define MR_TEX_OVERLAY_VIDEO               1

/* shade */
#define MR_LOC_SHADE_LIGHT_COUNT           0
#define MR_LOC_SHADE_LIGHT_DIR             1
#define MR_SHADE_MAX_LIGHTS                8
#define MR_LOC_SHADE_LIGHT_COLOR           (MR_LOC_SHADE_LIGHT_DIR + MR_SHADE_MAX_LIGHTS)
#define MR_LOC_SHADE_AMBIENT               (MR_LOC_SHADE_LIGHT_COLOR + MR_SHADE_MAX_LIGHTS)
#define MR_LOC_SHADE_BACKGROUND            18
#define MR_LOC_SHADE_HAVE_AO               19
#define MR_LOC_SHADE_SPECULAR              20
#define MR_LOC_SHADE_SHININESS             21
#define MR_TEX_SHADE_ALBEDO                0
#define MR_TEX_SHADE_NORMAL                1
#define MR_TEX_SHADE_AO                    2

/* shadow_map (draws the scene through a view: 0..2 as above) */
#define MR_LOC_SHADOW_MAP_ORTHO            3
#define MR_LOC_SHADOW_MAP_RECT             4
#define MR_LOC_SHADOW_MAP_DEPTH            5
#define MR_LOC_SHADOW_MAP_OFFSET           6
#define MR_LOC_SHADOW_MAP_SHEAR            7
/* shadow_vis (full screen) */
#define MR_LOC_SHADOW_INTR                 0
#define MR_LOC_SHADOW_NEAR                 1
#define MR_LOC_SHADOW_LIGHT_FROM_CAM       2
#define MR_LOC_SHADOW_ORTHO                3
#define MR_LOC_SHADOW_RECT                 4
#define MR_LOC_SHADOW_K                    5
#define MR_LOC_SHADOW_ZRANGE               6
#define MR_LOC_SHADOW_LIGHT_HALF           7
#define MR_LOC_SHADOW_METHOD               8
#define MR_LOC_SHADOW_TAPS                 9
#define MR_LOC_SHADOW_PCF_RADIUS           10
#define MR_LOC_SHADOW_MAP_SIZE             11
#define MR_LOC_SHADOW_OFFSET               12
#define MR_LOC_SHADOW_SHEAR                13
#define MR_LOC_SHADOW_WEIGHT               14
#define MR_LOC_SHADOW_MAX_SEARCH           15
#define MR_LOC_SHADOW_LIGHT_AREA           16
#define MR_LOC_SHADOW_KERNEL               20
#define MR_SHADOW_KERNEL_SIZE              64 /* = MR_SHADOW_MAX_TAPS (checked in pass_shadow.c) */
/* shadow_vis: sun cascades (after the kernel's 20..83) */
#define MR_LOC_SHADOW_CASCADES             84
#define MR_LOC_SHADOW_SPLITS               85 /* vec4: far camera depth of cascades 0..3 */
#define MR_LOC_SHADOW_BAND                 86 /* seam band: fraction of the split depth */
#define MR_LOC_SHADOW_RECTS                87 /* vec4[MR_SHADOW_CASCADES_MAX]: 87..90 */
#define MR_SHADOW_CASCADES_MAX             4  /* = MR_SHADOW_MAX_CASCADES (checked in pass_shadow.c) */
#define MR_TEX_SHADOW_DEPTH                0
#define MR_TEX_SHADOW_NORMAL               1
#define MR_TEX_SHADOW_MAP                  2
#define MR_TEX_SHADOW_MINMAX               3  /* backprojection: RG32F min / max depth pyramid */
#define MR_LOC_SHADOW_PYRAMID              17 /* ivec2: a tile's pyramid side P (level 0), its top level */
/* shadow_minmax (compute): the backprojection's min / max depth pyramid */
#define MR_LOC_SHADOW_MM_LEVEL             0
#define MR_LOC_SHADOW_MM_SIZE              1
#define MR_LOC_SHADOW_MM_PYR               2
#define MR_TEX_SHADOW_MM_MAP               0
#define MR_IMG_SHADOW_MM_SRC               0
#define MR_IMG_SHADOW_MM_DST               1
/* shadow_vis's methods: mr_shadow_method's values (checked in pass_shadow.c) */
#define MR_SHADOW_METHOD_ID_HARD           1
#define MR_SHADOW_METHOD_ID_PCF            2
#define MR_SHADOW_METHOD_ID_PCSS           3
#define MR_SHADOW_METHOD_ID_BP             4
#define MR_SHADOW_METHOD_ID_GROUNDTRUTH    5
/* overlay: the shadow catcher (pass_shadow.c's flags, passes.c's overlay) */
#define MR_LOC_OVERLAY_CATCHER             9
#define MR_LOC_OVERLAY_CATCHER_LIGHT       10
#define MR_LOC_OVERLAY_CATCHER_LIGHT_LUM   11
#define MR_LOC_OVERLAY_CATCHER_AMBIENT     12
#define MR_TEX_OVERLAY_IDS                 2
#define MR_TEX_OVERLAY_SHADOW              3
#define MR_TEX_OVERLAY_CATCHER_FLAGS       4
#define MR_TEX_OVERLAY_NORMAL              5
#define MR_SHADOW_CATCHER_ROW              4096 /* flags texture: node i at (i % ROW, i / ROW) */
/* shade: the casting light's visibility */
#define MR_LOC_SHADE_SHADOW_LIGHT          22
#define MR_TEX_SHADE_SHADOW                3

/* ui */
#define MR_LOC_UI_MODE                     1
#define MR_TEX_UI_TEX                      0
#define MR_LOC_UI_FB_SIZE                  0

/* ao_main's method ids: mr_ao_method's values, and the standalone corner
 * mask (pass_ao.c checks they agree). */
#define MR_AO_METHOD_ID_SCHEER             1
#define MR_AO_METHOD_ID_CRYTEK             2
#define MR_AO_METHOD_ID_FILION             3
#define MR_AO_METHOD_ID_HBAO               4
#define MR_AO_METHOD_ID_ALCHEMY            5
#define MR_AO_METHOD_ID_GTAO               6
#define MR_AO_METHOD_ID_BITMASK            7
#define MR_AO_METHOD_ID_SCHEER_GT          8
#define MR_AO_METHOD_ID_SCHEER_BM          9
#define MR_AO_METHOD_MASK_STANDALONE       100

/* rig_layered (the layered-rendering experiment): all of a rig
 * frame's views in one instanced draw, gl_ViewportIndex = instance % views;
 * the projections take MR_LOC_PROJECTION .. + MR_RIG_LAYERED_MAX - 1. */
#define MR_RIG_LAYERED_MAX                 16
#define MR_LOC_RIG_SHIFT                   20 /* .. 35: camera x shift of each view */
#define MR_LOC_RIG_VIEWS                   40

#endif
