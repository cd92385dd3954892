/* mr_bench.h — the `mrcheck bench` runners as library code: each takes a
 * params struct (zero or the MR_BENCH_*_DEFAULTS designated initialisers
 * mean the documented defaults), writes its CSV, SVG and summary files into
 * out_dir, prints its table to `out` (NULL: nothing printed) and returns
 * false with err set when it cannot run. Measurements only: nothing here
 * passes or fails. The CSVs go through the one CSV writer, the medians
 * through the one median (mr_csv_*, mr_median in mr_eval.h). */
#ifndef MR_BENCH_H
#define MR_BENCH_H

#include <stdio.h>

#include "mr_core.h"
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_scene.h"
#include "mr_track.h" /* the marker map and detections of mr_synth_map */

#ifdef __cplusplus
extern "C" {
#endif

/* The GPU a rendering bench uses: a headless context and a renderer on it
 * (mr_gfx_open), made and destroyed by the caller. A bench sets its scenes
 * on the renderer and leaves none set when it returns. Required by ao,
 * frame, ghost, scene. */
typedef mr_gfx mr_bench_gpu;

/* -------------------------------------------------------------- shadows */

/* Soft shadows, error against run time, on the shadow suite:
 * every method x setting x case x view, GPU ms against RMSE, sqrt(D)/|S|
 * and SSIM over the shadow region against Embree (bench_shadows.csv,
 * bench_shadows.svg, bench_shadows_<case>.png montages: reference, hard,
 * pcf, pcss, bp, GPU ground truth; bench_shadows.md). */
typedef struct mr_bench_shadows_params {
    mr_bench_gpu gfx;
    const char *out_dir;
    int width, height;   /* default 320 x 240 */
    int frames;          /* timed frames per row (median); default 3 */
    int rays;            /* Embree reference rays per pixel; default 256 */
    int first, count;    /* suite cases first .. first + count - 1; 0, 0 = all 13 */
    int views;           /* 1 or 2 (default) views per case */
    FILE *out;           /* progress and the table, or NULL */
    int gt_samples_max;  /* caps the GPU ground truth's light samples (tests: time); 0 = no cap */
} mr_bench_shadows_params;
#define MR_BENCH_SHADOWS_DEFAULTS .out_dir = "bench-out", .width = 320, .height = 240, .frames = 3, .rays = 256
bool mr_bench_shadows(const mr_bench_shadows_params *params, mr_error *err);
extern const mr_opt mr_bench_shadows_opts[]; /* frames, rays, first, count, views */

/* ------------------------------------------------------------------- ao */

/* Ambient occlusion, error against run time: every method over a grid of
 * sample counts, full and half resolution, corner masking off and on, on
 * the reported views, against two ray-traced references; parameters tuned
 * on a view that is not reported (bench_ao.csv, bench_ao_tuning.csv,
 * bench_ao_triangles.csv, bench_ao.svg, bench_ao_screen.svg,
 * bench_ao_montage.png, bench_ao_shaded.png, bench_ao.md). */
#define MR_BENCH_AO_MAX_VIEWS 16
typedef struct mr_bench_ao_params {
    mr_bench_gpu gfx;           /* required */
    const char *out_dir;         /* default "bench-out" */
    const char *scene;           /* glTF/GLB or scene config; NULL: the demo hall as planned */
    const mr_view *views;        /* view_count reported views; 0: the demo's near, mid-hall and far views */
    const char *const *view_names; /* their names in the tables (e.g. the file names) */
    int view_count;              /* at most MR_BENCH_AO_MAX_VIEWS */
    const mr_view *tune_view;    /* NULL: a demo view that is not reported (the north wall) */
    const char *tune_name;
    int width, height;           /* px, default 320x240 */
    int frames;                  /* timed frames per configuration (median), 1..64, default 5 */
    int rays;                    /* ground-truth rays per pixel, default 256 */
    double radius;               /* the fixed reference's R in scene units; 0: 2% of the scene diagonal */
    double screen_radius;        /* the depth-scaled reference: fraction of the image height, default 0.05 */
    const char *sequence;        /* recording whose poses are the moving sequence;
                                    NULL: recordings/demo if it is there, else none */
    bool quick;                  /* samples 8 and 32, full resolution only, 2-point tuning */
    bool verbose;                /* print the tuned parameters */
    bool progress;               /* "view i/n done" on stderr */
    FILE *out;                   /* the tables; NULL: silent */
} mr_bench_ao_params;
#define MR_BENCH_AO_DEFAULTS .out_dir = "bench-out", .width = 320, .height = 240, .frames = 5, .rays = 256, .screen_radius = 0.05
bool mr_bench_ao(const mr_bench_ao_params *params, mr_error *err);
/* Option table of the numbers and switches above (frames, rays, radius,
 * screen-radius, quick); lib/bench/options.c. */
extern const mr_opt mr_bench_ao_opts[];

/* ---------------------------------------------------------------- frame */

/* Per-pass GPU and CPU ms of the whole frame. */
typedef struct mr_bench_frame_params {
    mr_bench_gpu gfx;           /* required */
    const char *out_dir;    /* default "bench-out" */
    const char *scene;      /* glTF/GLB or scene config; NULL: the demo hall as planned */
    const mr_view *view;    /* NULL: the demo's first viewpoint */
    int width, height;      /* px, default 1024x768 */
    int frames;             /* timed frames after 3 warm-up frames, default 30 */
    const mr_image *video;  /* camera frame to overlay; NULL: a synthetic one (seeded noise) */
    bool no_video;          /* no overlay pass; default false */
    FILE *out;              /* the table; NULL: silent */
} mr_bench_frame_params;
#define MR_BENCH_FRAME_DEFAULTS .out_dir = "bench-out", .width = 1024, .height = 768, .frames = 30
bool mr_bench_frame(const mr_bench_frame_params *params, mr_error *err);
extern const mr_opt mr_bench_frame_opts[]; /* frames, no-video */

/* ---------------------------------------------------------------- ghost */

/* Ghosted views on the demo partition: per importance source, saliency
 * implementation, eq. 9's levels and mode, the GPU ms of the ghosting passes
 * against legibility measures (bench_ghost.csv, bench_ghost.svg). */
typedef struct mr_bench_ghost_params {
    mr_bench_gpu gfx;           /* required */
    const char *out_dir;    /* default "bench-out" */
    int width, height;      /* px, default 640x480 (the demo camera) */
    int frames;             /* timed frames per configuration after 2 warm-up frames, default 5 */
    int view;               /* demo viewpoint 0..MR_DEMO_VIEWS-1, default 0 (the partition) */
    bool progress;          /* "n/N configurations" on stderr; default false */
    FILE *out;              /* the table; NULL: silent */
} mr_bench_ghost_params;
#define MR_BENCH_GHOST_DEFAULTS .out_dir = "bench-out", .width = 640, .height = 480, .frames = 5
bool mr_bench_ghost(const mr_bench_ghost_params *params, mr_error *err);
extern const mr_opt mr_bench_ghost_opts[]; /* frames, view */

/* ---------------------------------------------------------------- scene */

/* Cost against scene size: synthetic factories written as .glb into out_dir
 * and loaded back; load / upload / LOD times, peak memory, and per viewpoint
 * and draw configuration the frame time and its parts (bench_scene.csv,
 * bench_scene.svg). */
#define MR_BENCH_SCENE_MAX_SIZES 8
typedef struct mr_bench_scene_params {
    mr_bench_gpu gfx;           /* required */
    const char *out_dir;    /* default "bench-out" */
    double sizes[MR_BENCH_SCENE_MAX_SIZES]; /* drawn-triangle targets */
    int size_count;         /* 0: 1M, 5M, 20M */
    int width, height;      /* px, default 1024x768 */
    int frames;             /* timed frames per case after one warm-up, default 3 */
    FILE *out;              /* the table; NULL: silent */
    /* Unique geometry: the CAD-like factory (mr_synth_cad_build,
     * every part its own mesh of 20k triangles, split at normal seams)
     * instead of the instanced one; bench_scene_unique.csv/.svg, with the
     * LOD's first build and its cached load timed apart. */
    bool unique;
    double unit;            /* scene units per metre of the unique factory; 0 = 1 */
    /* Timed frames of the full-detail configurations
     * (no-lod, none), which cost seconds a frame at 20M; 0: frames. */
    int full_frames;
} mr_bench_scene_params;
#define MR_BENCH_SCENE_DEFAULTS .out_dir = "bench-out", .width = 1024, .height = 768, .frames = 3
bool mr_bench_scene(const mr_bench_scene_params *params, mr_error *err);
extern const mr_opt mr_bench_scene_opts[]; /* frames, full-detail-frames */

/* ------------------------------------------------------------- tracking */

/* Error against run time of the tag detector settings (and OpenCV's aruco
 * detector as the peer) on a recording with ground truth
 * (bench_tracking.csv, bench_tracking.svg). */
typedef struct mr_bench_tracking_params {
    const char *out_dir;    /* default "bench-out" */
    const char *recording;  /* recording folder with groundtruth.jsonl, default "recordings/demo" */
    int max_frames;         /* use at most this many frames with ground truth; 0: all */
    bool quick;             /* a few settings only; default false */
    double min_cutoff;      /* One Euro cutoff at rest in Hz (also for rotation); 0: the filter's default 0.5 */
    double beta;            /* One Euro speed coefficient; 0: the filter's default 2 */
    FILE *out;              /* the table; NULL: silent */
} mr_bench_tracking_params;
#define MR_BENCH_TRACKING_DEFAULTS .out_dir = "bench-out", .recording = "recordings/demo"
bool mr_bench_tracking(const mr_bench_tracking_params *params, mr_error *err);
extern const mr_opt mr_bench_tracking_opts[]; /* frames, quick, min-cutoff, beta */

/* bench map (map.c): synthetic photo sets (mr_synth_map, projected corners
 * with noise and wrong ids, 1280x960, 0.3 m tags on a ring) of 10, 20, 50,
 * 100, 200 photos, mapped with the fixed-tag gauge by the bundle adjustment
 * ("ours") and by chaining along the spanning tree; per photo count and
 * method the median over seeds of the tag position error (RMS, max, mm),
 * the largest rotation error, the run time, the reprojection RMS and the
 * largest predicted sigma: bench_map.csv and bench_map.svg in out_dir. */
typedef struct mr_bench_map_params {
    const char *out_dir;    /* default "bench-out" */
    int seeds;              /* sets per photo count, default 5 */
    int max_photos;         /* only counts up to this; 0 = all (200) */
    int tags;               /* default 16 */
    double radius;          /* m, default 3 */
    double noise_px;        /* corner noise, default 0.3 px */
    double misdetect;       /* fraction of photos with one wrong id, default 0.05 */
    FILE *out;              /* the table; NULL: silent */
} mr_bench_map_params;
#define MR_BENCH_MAP_DEFAULTS \
    .out_dir = "bench-out", .seeds = 5, .tags = 16, .radius = 3.0, .noise_px = 0.3, .misdetect = 0.05
bool mr_bench_map(const mr_bench_map_params *params, mr_error *err);
extern const mr_opt mr_bench_map_opts[]; /* seeds, max-photos, noise, misdetect */

/* bench measure (measure.c): what a measured point is worth to a verdict.
 * Synthetic halls (30 x 20 m with 60 tags on 15 columns; the demo hall)
 * with known tag poses; the marker map from `photos` random photos
 * (projected corners, noise_px) with 4 control points (1 mm); feature
 * points 0.3..3 m up with built deviations of 0, 5, 10, 20 and 50 mm
 * along a horizontal normal, tapped in `taps` frames at `dist` metres on
 * a 30 degree arc, each pose solved against the built map; the deviation
 * triangulated with its predicted sigma. Per row (distance, photos, map
 * and tracking resolution, tag size, taps): the map's error and sigma,
 * the point's median error and sigma, the RMS of error/sigma (1 = honest),
 * the 95 % (k = 2) interval's coverage and the verdict against
 * +-tolerance_mm: correct, undecided, wrong (bench_measure.csv,
 * bench_measure.svg: error and sigma against distance). */
typedef struct mr_bench_measure_params {
    const char *out_dir;    /* default "bench-out" */
    int maps;               /* map seeds per row, default 2 */
    int points;             /* feature points per map (x 5 deviations), default 20 */
    double noise_px;        /* map photos' corner noise, default 0.3 px */
    double track_noise_px;  /* tracked frames' corner noise, default 0.5 px */
    double tap_px;          /* a tap's noise, default 1 px */
    double tolerance_mm;    /* default 20 (DIN 18202, 6..15 m) */
    bool quick;             /* the base row and the distances only */
    bool progress;          /* a line per map on stderr */
    FILE *out;              /* the table; NULL: silent */
} mr_bench_measure_params;
#define MR_BENCH_MEASURE_DEFAULTS \
    .out_dir = "bench-out", .maps = 2, .points = 20, .noise_px = 0.3, .track_noise_px = 0.5, .tap_px = 1.0, \
    .tolerance_mm = 20.0
bool mr_bench_measure(const mr_bench_measure_params *params, mr_error *err);
extern const mr_opt mr_bench_measure_opts[]; /* maps, points, noise, track-noise, tap-px, tolerance, quick */

/* Bench load (load.c): the instanced factory
 * (mr_synth_build, `triangles` drawn) and the unique one (mr_synth_cad_build,
 * `unique_triangles`) as .glb and packed by gltfpack (default, -c, -cc);
 * each file loaded by mr_scene_load in a fresh child process per load, in
 * turn, `runs` rounds: median CPU s (user + system), wall s, MB/s and peak
 * RSS per file (bench_load.csv, bench_load.svg). Needs gltfpack. */
typedef struct mr_bench_load_params {
    const char *out_dir;       /* default "bench-out" */
    int runs;                  /* rounds, default 5 */
    double triangles;          /* instanced factory, drawn; default 4e6 */
    double unique_triangles;   /* unique factory, stored; default 2e6 */
    FILE *out;                 /* the table; NULL: silent */
} mr_bench_load_params;
#define MR_BENCH_LOAD_DEFAULTS .out_dir = "bench-out", .runs = 5, .triangles = 4e6, .unique_triangles = 2e6
bool mr_bench_load(const mr_bench_load_params *params, mr_error *err);
extern const mr_opt mr_bench_load_opts[]; /* runs, triangles, unique-triangles */

/* ------------------------------------------------------ synthetic data */

/* A synthetic recording of the demo hall (as built) along a walking path
 * with pauses (synth_recording.c): each frame rendered on gfx's renderer
 * (left with no scene), made a camera frame by mr_demo_camera_frame,
 * tracked by lib/track's tracker, written by lib/session's recorder with
 * groundtruth.jsonl into dir (never overwritten). The demo camera scaled to
 * width x height (square pixels, focal length with the width). What the
 * tracking bench reads. params NULL: MR_SYNTH_RECORDING_DEFAULTS; otherwise every
 * field is taken as given (noise, exposure and seed 0 are meaningful), out
 * of range: MR_ERR_INVALID. */
typedef struct mr_synth_recording_params {
    int frames;       /* spread over the path (timestamps on the path's clock); 0 = default:
                         one per path step, mr_synth_path_frames() */
    int width, height; /* px, at least 64x48; default 640x480 (the demo camera) */
    double noise;     /* sensor noise sigma in grey levels, >= 0; default 2 */
    int motion_blur;  /* sub-frames averaged over the shutter, 1 (none)..16; default 3 */
    double shutter;   /* exposure time 1/shutter s, 1..100000; default 60 (1/60 s, an indoor
                         tablet's auto-exposure) */
    double exposure;  /* relative exposure swing along the path, 0..<1; default 0.25 */
    int jpeg_quality; /* of the stored frames; default 80 (the shipped recording < 5 MB) */
    uint64_t seed;    /* noise seed; default 1 */
    double fps;       /* path steps per second (the frame rate at one frame per step), > 0; default 10 */
    bool progress;    /* "synth: frame i/n" on stderr */
} mr_synth_recording_params;
#define MR_SYNTH_RECORDING_DEFAULTS \
    .frames = 0, .width = 640, .height = 480, .noise = 2.0, .motion_blur = 3, .shutter = 60, .exposure = 0.25, \
    .jpeg_quality = 80, .seed = 1, .fps = 10.0
/* A stop (SIGINT/SIGTERM, mr_stop_requested) ends it before the next
 * frame: the recording holds every frame made so far; false with
 * MR_ERR_INTERRUPTED and the summary in err. */
bool mr_synth_recording(const char *dir, const mr_synth_recording_params *params, const mr_bench_gpu *gfx, mr_error *err);
/* Steps of the walking path (pauses and walks), the default frame count. */
int mr_synth_path_frames(void);
/* frames, noise, motion-blur, shutter, exposure, jpeg, fps (the seed, 64 bits, and
 * the size stay the command's own options). */
extern const mr_opt mr_synth_recording_opts[];
/* The calibration set: dir/board.json (the board of mr_demo_board_tag as a
 * marker map) and dir/images/board_NN.png, `images` (>= 1) views of it from
 * around, rendered on the CPU through the demo camera. */
bool mr_synth_calibration(const char *dir, int images, mr_error *err);
/* `mrcheck demo` (demo.c): the files, the tracking part (dir/calib and a
 * synthetic recording in dir/recording, never overwritten), the frames, the
 * marks and the ghosted triptychs, on a headless GPU of its own; what was
 * written, on stdout. */
bool mr_demo_run(const char *dir, mr_error *err);
/* The last part of `mrcheck demo` (demo_marks.c): three marks at the
 * hall's known discrepancies in dir/session/, as a planner would place them
 * in `mrcheck view` (the moved part measured from several recorded frames
 * and judged against DIN 18202), a control measurement of an unchanged
 * column, then dir/findings.bcf (2.1), dir/findings-3.0.bcf and
 * dir/report/ through lib/export. */
bool mr_demo_marks(const char *dir, const mr_bench_gpu *g, const mr_scene *built, const mr_scene *planned,
                   mr_error *err);
/* The first parts of `mrcheck demo` (demo_files.c). Files: dir/ and its
 * frames/ overlay/ virtual/ views/ folders, both halls as .glb with
 * scene_planned.json and scene_built.json, markers.json, discrepancies.json,
 * camera.json and views/view_NNN.json; views (MR_DEMO_VIEWS) and the count
 * of known discrepancies out. */
bool mr_demo_write_files(const char *dir, mr_view *views, int *discrepancy_count, mr_error *err);
/* Frames: per view, the hall as built rendered wide and made a camera frame
 * (frames/frame_NNN.png), the planned model over it at alpha 0.5
 * (overlay/overlay_NNN.png) and alone (virtual/virtual_NNN.png). Leaves the
 * planned scene set on g's renderer. */
bool mr_demo_render_frames(const char *dir, const mr_bench_gpu *g, const mr_scene *built, const mr_scene *planned,
                           const mr_view *views, mr_error *err);

/* ------------------------------------------------------------ multiview */

/* Multi-view output on the demo hall (lib/bench/multiview.c): views 1, 8,
 * 24, 48 at a fixed total pixel budget and at a fixed per-view size (ms per
 * frame and per view, AO error against the ray-traced reference under the
 * pinhole and the light-field display mapping, cross-view AO consistency
 * with world and pixel noise); the display mapping's slice width against
 * time and error; Doronin et al.'s Table 1 shape (one view, no SSAO / SSAO,
 * three scenes). bench_multiview.csv, _display.csv, _table1.csv, .svg, .md. */
typedef struct mr_bench_multiview_params {
    mr_bench_gpu gfx;           /* required */
    const char *out_dir;        /* default "bench-out" */
    const mr_view *view;        /* the rig's centre; NULL: the demo's first viewpoint */
    int budget_w, budget_h;     /* total pixels of all views, default 1024x768 */
    int view_w, view_h;         /* the fixed per-view size, default 160x120 */
    int table_w, table_h;       /* Table 1's size, default 1024x768 */
    int frames;                 /* timed runs, median, default 3 */
    int rays;                   /* reference rays per pixel, default 64 */
    bool quick;                 /* views 1 and 8 only */
    bool progress;              /* a line per row on stderr */
    FILE *out;                  /* the tables; NULL: silent */
    bool shared_only;           /* instead of the tables above, the
                                   shared-work table (bench_multiview_shared.*:
                                   8, 24, 48 views at view_w x view_h on the demo
                                   hall and the synthetic factory, shared vs
                                   per-view culling and shadow maps, and the
                                   layered experiment) */
} mr_bench_multiview_params;
#define MR_BENCH_MULTIVIEW_DEFAULTS .out_dir = "bench-out", .budget_w = 1024, .budget_h = 768, .view_w = 160, \
                                    .view_h = 120, .table_w = 1024, .table_h = 768, .frames = 3, .rays = 64
bool mr_bench_multiview(const mr_bench_multiview_params *params, mr_error *err);
extern const mr_opt mr_bench_multiview_opts[]; /* frames, rays, quick */

/* A synthetic photo set for the marker map (synth_map.c): `tags` tags on a
 * ring of walls (radius, facing its centre, a little tilted; with
 * mixed_sizes every third is 1.5x tag_size), `photos` photos from inside
 * it, each seeing a few neighbouring tags; `isolated` more tags in a room
 * of their own far off, seen by two extra photos only (a disconnected
 * part). Either projected corners with Gaussian noise (dets, counts; a
 * fraction `misdetect` of the photos has one sighting with a wrong id) or,
 * with render, CPU ray-cast grey images (images) for the real detector.
 * The demo camera scaled to width x height. */
typedef struct mr_synth_map_params {
    uint64_t seed;          /* default 1 */
    int tags;               /* 3..200, default 16 */
    int photos;             /* 1..10000, default 24 */
    int isolated;           /* 0..50, default 0 */
    double tag_size;        /* m, default 0.2 */
    bool mixed_sizes;
    double radius;          /* m, default 3 */
    double offset;          /* added to every x (far-from-origin sites), m */
    double corner_noise_px; /* projected corners: sigma, default 0.3 */
    double misdetect;       /* 0..1, default 0 */
    bool render;            /* images instead of projected corners */
    double image_noise;     /* grey levels, default 2 */
    int width, height;      /* px, default 320x240 */
} mr_synth_map_params;
#define MR_SYNTH_MAP_DEFAULTS \
    .seed = 1, .tags = 16, .photos = 24, .tag_size = 0.2, .radius = 3.0, .corner_noise_px = 0.3, .image_noise = 2.0, \
    .width = 320, .height = 240
typedef struct mr_synth_map {
    mr_camera camera;
    mr_marker_map truth;          /* the tags' true poses (and sizes) */
    int photo_count;
    mr_dmat4 *world_from_camera;  /* photo_count true poses */
    mr_detection **dets;          /* projected: per photo counts[j] sightings */
    int *counts;
    mr_image *images;             /* render: photo_count grey images */
} mr_synth_map;
bool mr_synth_map_make(const mr_synth_map_params *params, mr_synth_map *out, mr_error *err);
void mr_synth_map_free(mr_synth_map *s);
/* A rendered set on disk (`mrcheck synth --map-photos DIR`): DIR/images/
 * photo_NNN.png, the same photos as a video photos.avi (for `map
 * --video`), camera.json, truth.json (the true marker map) and
 * control.json (four tag centres, sigma 1 mm). params NULL: a small room
 * (MR_SYNTH_MAP_SET_DEFAULTS); images/ is never overwritten. */
#define MR_SYNTH_MAP_SET_DEFAULTS \
    .seed = 1, .tags = 10, .photos = 24, .tag_size = 0.25, .radius = 1.2, .image_noise = 2.0, .render = true, \
    .width = 320, .height = 240
bool mr_synth_map_write(const char *dir, const mr_synth_map_params *params, mr_error *err);

#ifdef __cplusplus
}
#endif
#endif
