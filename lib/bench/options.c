/* The benches' option tables: the numbers and switches of each
 * mr_bench_*_params (files, folders and the frame size stay the command's
 * own options). The command line, --help and the range checks of
 * `mrcheck bench NAME` come from here. */
#include "mr_bench.h"

#include <stddef.h>

#define AO(f) offsetof(mr_bench_ao_params, f)
const mr_opt mr_bench_ao_opts[] = {
    {"frames", MR_OPT_INT, AO(frames), 1, 64, 5, NULL, "timed frames per configuration, median reported", 0},
    {"rays", MR_OPT_INT, AO(rays), 1, 1 << 20, 256, NULL, "ground-truth rays per pixel", 0},
    {"radius", MR_OPT_DOUBLE, AO(radius), 1e-30, 1e30, 0, NULL,
     "the fixed reference's radius in scene units (auto: 2% of the scene diagonal)", MR_OPT_ZERO_AUTO},
    {"screen-radius", MR_OPT_DOUBLE, AO(screen_radius), 1e-4, 1, 0.05, NULL,
     "depth-scaled reference: radius as a fraction of the image height at each depth", 0},
    {"quick", MR_OPT_BOOL, AO(quick), 0, 1, 0, NULL, "a reduced grid (samples 8 and 32, full resolution only, 2-point tuning)", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef AO

const mr_opt mr_bench_frame_opts[] = {
    {"frames", MR_OPT_INT, offsetof(mr_bench_frame_params, frames), 1, 100000, 30, NULL,
     "frames to time after 3 warm-up frames", 0},
    {"no-video", MR_OPT_BOOL, offsetof(mr_bench_frame_params, no_video), 0, 1, 0, NULL, "no overlay pass", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

const mr_opt mr_bench_ghost_opts[] = {
    {"frames", MR_OPT_INT, offsetof(mr_bench_ghost_params, frames), 1, 100000, 5, NULL,
     "frames to time per configuration after 2 warm-up frames", 0},
    {"view", MR_OPT_INT, offsetof(mr_bench_ghost_params, view), 0, MR_DEMO_VIEWS - 1, 0, NULL,
     "demo viewpoint (0: the partition with the pipes behind it)", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

const mr_opt mr_bench_scene_opts[] = {
    {"frames", MR_OPT_INT, offsetof(mr_bench_scene_params, frames), 1, 1000, 3, NULL,
     "timed frames per case after one warm-up", 0},
    {"full-detail-frames", MR_OPT_INT, offsetof(mr_bench_scene_params, full_frames), 0, 1000, 0, NULL,
     "timed frames of the full-detail cases (no-lod, none; auto: --frames)", MR_OPT_ZERO_AUTO},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

#define TR(f) offsetof(mr_bench_tracking_params, f)
const mr_opt mr_bench_tracking_opts[] = {
    {"frames", MR_OPT_INT, TR(max_frames), 1, 1 << 30, 0, NULL, "use at most N frames with ground truth (auto: all)",
     MR_OPT_ZERO_AUTO},
    {"quick", MR_OPT_BOOL, TR(quick), 0, 1, 0, NULL, "a few settings only", 0},
    /* 0 in the field is the filter's own default, as mr_filter_params reads it. */
    {"min-cutoff", MR_OPT_DOUBLE, TR(min_cutoff), 1e-3, 100, 0.5, NULL, "One Euro filter cutoff at rest, Hz",
     MR_OPT_ZERO_DEFAULT},
    {"beta", MR_OPT_DOUBLE, TR(beta), 1e-6, 1000, 2.0, NULL, "One Euro filter speed coefficient", MR_OPT_ZERO_DEFAULT},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef TR

#define SH(f) offsetof(mr_bench_shadows_params, f)
const mr_opt mr_bench_shadows_opts[] = {
    {"frames", MR_OPT_INT, SH(frames), 1, 64, 3, NULL, "timed frames per row, median reported", 0},
    {"rays", MR_OPT_INT, SH(rays), 1, 1 << 16, 256, NULL, "Embree reference rays per pixel", 0},
    {"first", MR_OPT_INT, SH(first), 0, MR_SHADOW_SUITE_COUNT - 1, 0, NULL, "first suite case", 0},
    {"count", MR_OPT_INT, SH(count), 1, MR_SHADOW_SUITE_COUNT, 0, NULL, "suite cases from --first (auto: to the last)",
     MR_OPT_ZERO_AUTO},
    /* 0 in the field is both views, as mr_bench_shadows reads it. */
    {"views", MR_OPT_INT, SH(views), 1, 2, 2, NULL, "views per case", MR_OPT_ZERO_DEFAULT},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef SH

#define MV(f) offsetof(mr_bench_multiview_params, f)
const mr_opt mr_bench_multiview_opts[] = {
    {"frames", MR_OPT_INT, MV(frames), 1, 64, 3, NULL, "timed runs, median reported", 0},
    {"rays", MR_OPT_INT, MV(rays), 1, 1 << 16, 64, NULL, "reference rays per pixel", 0},
    {"quick", MR_OPT_BOOL, MV(quick), 0, 1, 0, NULL, "views 1 and 8 only", 0},
    {"shared-only", MR_OPT_BOOL, MV(shared_only), 0, 1, 0, NULL,
     "instead: the shared-work table (one cull and shadow map per rig frame vs per view, layered rendering)", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef MV

#define MP(f) offsetof(mr_bench_map_params, f)
const mr_opt mr_bench_map_opts[] = {
    {"seeds", MR_OPT_INT, MP(seeds), 1, 1000, 5, NULL, "photo sets per photo count, median reported", 0},
    {"max-photos", MR_OPT_INT, MP(max_photos), 10, 200, 0, NULL, "photo counts up to this (auto: all, 200)",
     MR_OPT_ZERO_AUTO},
    {"noise", MR_OPT_DOUBLE, MP(noise_px), 0, 10, 0.3, NULL, "corner noise sigma, px", 0},
    {"misdetect", MR_OPT_DOUBLE, MP(misdetect), 0, 1, 0.05, NULL, "fraction of photos with one wrong id", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef MP

#define MS(f) offsetof(mr_bench_measure_params, f)
const mr_opt mr_bench_measure_opts[] = {
    {"maps", MR_OPT_INT, MS(maps), 1, 16, 2, NULL, "map seeds per row", 0},
    {"points", MR_OPT_INT, MS(points), 1, 1000, 20, NULL, "feature points per map (each at 5 deviations)", 0},
    {"noise", MR_OPT_DOUBLE, MS(noise_px), 0, 10, 0.3, NULL, "map photos' corner noise sigma, px", 0},
    {"track-noise", MR_OPT_DOUBLE, MS(track_noise_px), 0, 10, 0.5, NULL, "tracked frames' corner noise sigma, px", 0},
    {"tap-px", MR_OPT_DOUBLE, MS(tap_px), 0.01, 20, 1.0, NULL, "a tap's noise sigma, px", 0},
    {"tolerance", MR_OPT_DOUBLE, MS(tolerance_mm), 1, 1000, 20, NULL, "the verdict's tolerance, +- mm", 0},
    {"quick", MR_OPT_BOOL, MS(quick), 0, 1, 0, NULL, "the base row and the distances only", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef MS

/* Bench load */
#define LD(f) offsetof(mr_bench_load_params, f)
const mr_opt mr_bench_load_opts[] = {
    {"runs", MR_OPT_INT, LD(runs), 1, 99, 5, NULL, "rounds over all files (each a fresh process per file); medians reported", 0},
    {"triangles", MR_OPT_DOUBLE, LD(triangles), 1e5, 1e8, 4e6, NULL, "drawn triangles of the instanced factory", 0},
    {"unique-triangles", MR_OPT_DOUBLE, LD(unique_triangles), 2e4, 5e7, 2e6, NULL,
     "stored triangles of the unique factory", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef LD

#define SR(f) offsetof(mr_synth_recording_params, f)
const mr_opt mr_synth_recording_opts[] = {
    {"frames", MR_OPT_INT, SR(frames), 1, 100000, 0, NULL, "frames spread over the walking path (auto: one per path step, 217)",
     MR_OPT_ZERO_AUTO},
    {"noise", MR_OPT_DOUBLE, SR(noise), 0, 100, 2.0, NULL, "sensor noise in grey levels", MR_OPT_RESEARCH},
    {"motion-blur", MR_OPT_INT, SR(motion_blur), 1, 16, 3, NULL, "sub-frames averaged over the shutter, 1 = none", MR_OPT_RESEARCH},
    {"shutter", MR_OPT_DOUBLE, SR(shutter), 1, 100000, 60, NULL, "exposure time 1/N s (motion blur over it)", MR_OPT_RESEARCH},
    {"exposure", MR_OPT_DOUBLE, SR(exposure), 0, 0.9, 0.25, NULL, "relative exposure swing along the path", MR_OPT_RESEARCH},
    {"jpeg", MR_OPT_INT, SR(jpeg_quality), 1, 100, 80, NULL, "JPEG quality of the stored frames", MR_OPT_RESEARCH},
    {"fps", MR_OPT_DOUBLE, SR(fps), 0.1, 1000, 10.0, NULL, "path steps per second (frame rate at one frame per step)", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef SR
