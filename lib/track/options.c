/* The option tables of the tracker's params (mr_detector_opts,
 * mr_filter_opts): key, type, field, range, default and help of each
 * tunable, for the command line, --help and settings files. Defaults are
 * the MR_*_DEFAULT_* macros of mr_track.h, which detector.c and filter.c
 * substitute for a 0 field, so each is written once. Every row is
 * MR_OPT_ZERO_DEFAULT: the params keep "0 = default" (zero-initialised
 * structs, MR_TRACKER_DEFAULTS' nested params) while a row speaks the
 * user's values. */
#include "mr_track.h"

#include <stddef.h>

#define DT(f) offsetof(mr_detector_params, f)
const mr_opt mr_detector_opts[] = {
    /* 0 = auto: the tracker's adaptive decimation (mr_track.h); a bare
     * detector takes MR_DETECTOR_DEFAULT_DECIMATE for it. */
    {"decimate", MR_OPT_DOUBLE, DT(decimate), 1, 16, 0, NULL,
     "detector decimation (auto: adaptive, from the tags of the frame before)", MR_OPT_ZERO_AUTO},
    /* The detector takes up to 256; the command line has always stopped at 64. */
    {"threads", MR_OPT_INT, DT(threads), 1, 64, MR_DETECTOR_DEFAULT_THREADS, NULL, "detector threads",
     MR_OPT_ZERO_DEFAULT},
    /* 0/1 rather than a flag: the default is on, and 0 must be sayable. */
    {"refine-edges", MR_OPT_INT, DT(refine_edges), 0, 1, 1, NULL, "edge refinement, 0 = off", MR_OPT_ZERO_DEFAULT},
    {"sharpening", MR_OPT_DOUBLE, DT(sharpening), 0, 10, MR_DETECTOR_DEFAULT_SHARPENING, NULL,
     "decode sharpening, 0 = none", MR_OPT_ZERO_DEFAULT},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef DT

/* filter.c replaces any field <= 0 by its default, so no range holds 0. */
#define FI(f) offsetof(mr_filter_params, f)
const mr_opt mr_filter_opts[] = {
    {"min-cutoff", MR_OPT_DOUBLE, FI(min_cutoff), 1e-3, 100, MR_FILTER_DEFAULT_MIN_CUTOFF, NULL,
     "One Euro cutoff at rest, Hz", MR_OPT_ZERO_DEFAULT},
    {"beta", MR_OPT_DOUBLE, FI(beta), 1e-6, 1000, MR_FILTER_DEFAULT_BETA, NULL,
     "cutoff increase per unit speed (1/scene unit)", MR_OPT_ZERO_DEFAULT},
    {"d-cutoff", MR_OPT_DOUBLE, FI(d_cutoff), 1e-3, 100, MR_FILTER_DEFAULT_D_CUTOFF, NULL,
     "cutoff of the speed estimate, Hz", MR_OPT_ZERO_DEFAULT},
    {"rot-min-cutoff", MR_OPT_DOUBLE, FI(rot_min_cutoff), 1e-3, 100, MR_FILTER_DEFAULT_ROT_MIN_CUTOFF, NULL,
     "rotation cutoff at rest, Hz", MR_OPT_ZERO_DEFAULT},
    {"rot-beta", MR_OPT_DOUBLE, FI(rot_beta), 1e-6, 1000, MR_FILTER_DEFAULT_ROT_BETA, NULL,
     "rotation cutoff increase per rad/s", MR_OPT_ZERO_DEFAULT},
    {"jump-dist", MR_OPT_DOUBLE, FI(jump_dist), 1e-6, 1e6, MR_FILTER_DEFAULT_JUMP_DIST, NULL,
     "reset when the raw pose moves more than this between frames, scene units", MR_OPT_ZERO_DEFAULT},
    {"jump-deg", MR_OPT_DOUBLE, FI(jump_deg), 1e-3, 180, MR_FILTER_DEFAULT_JUMP_DEG, NULL,
     "reset when the raw pose turns more than this between frames, degrees", MR_OPT_ZERO_DEFAULT},
    {"max-gap", MR_OPT_DOUBLE, FI(max_gap_s), 1e-3, 3600, MR_FILTER_DEFAULT_MAX_GAP_S, NULL,
     "reset after a gap longer than this, seconds", MR_OPT_ZERO_DEFAULT},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef FI

#define MP(f) offsetof(mr_map_params, f)
const mr_opt mr_map_opts[] = {
    /* No unit is assumed: any positive length (required unless every tag's size is given). */
    {"tag-size", MR_OPT_DOUBLE, MP(tag_size), 1e-9, 1e9, 0, NULL,
     "black-square edge of the tags, scene units (auto: only --tag-sizes)", MR_OPT_ZERO_AUTO},
    {"loss", MR_OPT_DOUBLE, MP(loss_px), 1e-3, 1e3, MR_MAP_DEFAULT_LOSS_PX, NULL, "Huber scale of the corner residuals, px",
     MR_OPT_ZERO_DEFAULT | MR_OPT_RESEARCH},
    {"refine-intrinsics", MR_OPT_BOOL, MP(refine_intrinsics), 0, 1, 0, NULL, "also adjust fx fy cx cy k1 k2", MR_OPT_RESEARCH},
    {"chain", MR_OPT_BOOL, MP(no_adjust), 0, 1, 0, NULL,
     "no global adjustment: chain relative poses along the spanning tree (baseline)", MR_OPT_RESEARCH},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef MP

const mr_opt mr_board_calib_opts[] = {
    {"min-tags", MR_OPT_INT, offsetof(mr_board_calib_params, min_tags), 1, 10000, MR_BOARD_CALIB_DEFAULT_MIN_TAGS, NULL,
     "images with fewer board tags are skipped", MR_OPT_ZERO_DEFAULT | MR_OPT_RESEARCH},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

#define TP(f) offsetof(mr_triangulate_params, f)
const mr_opt mr_triangulate_opts[] = {
    {"tap-sigma", MR_OPT_DOUBLE, TP(tap_sigma_px), 1e-3, 100, MR_TRIANGULATE_DEFAULT_TAP_SIGMA_PX, NULL,
     "1-sigma of a tap per axis, px", MR_OPT_ZERO_DEFAULT | MR_OPT_RESEARCH},
    {"min-angle", MR_OPT_DOUBLE, TP(min_angle_deg), 1e-3, 90, MR_TRIANGULATE_DEFAULT_MIN_ANGLE_DEG, NULL,
     "refuse rays closer than this, degrees", MR_OPT_ZERO_DEFAULT | MR_OPT_RESEARCH},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef TP
