/* Private to app/: subcommands and the small helpers they share. The app
 * only parses arguments and wires the libraries together. */
#ifndef MR_APP_H
#define MR_APP_H

#include "mr_core.h"
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_scene.h"

/* A declared option table: name, whether it takes a value, help text. */
typedef struct app_opt {
    const char *name;   /* without the leading "--" */
    const char *arg;    /* value placeholder, or NULL for a flag */
    const char *help;
    const char *value;  /* filled by app_parse: the value, "1" for a set flag, or NULL */
} app_opt;

/* Parses argv[first..argc) into opts (terminated by a NULL name); positional
 * arguments go to *pos (up to max_pos). --help prints usage and returns 0 via
 * *done. Returns false (after printing one line) on a bad argument. */
bool app_parse(int argc, char **argv, int first, app_opt *opts, const char **pos, int max_pos, int *npos,
               const char *usage, bool *help_shown);
const char *app_get(const app_opt *opts, const char *name);
bool app_flag(const app_opt *opts, const char *name);
/* Number parsing with range checks; print one line and return false on error. */
bool app_double(const char *opt, const char *s, double lo, double hi, double *out);
bool app_int(const char *opt, const char *s, long lo, long hi, long *out);
bool app_size(const char *opt, const char *s, int *w, int *h);
/* Exit status of a command that found no GPU device, GL context or display
 * (MR_ERR_NODEVICE): EX_UNAVAILABLE of sysexits.h. Tests skip on this status
 * only, never on the text of a message. */
#define APP_EXIT_NODEVICE 69
/* Prints "mrcheck: <cmd>: <message>" on stderr and returns 1, or
 * APP_EXIT_NODEVICE for MR_ERR_NODEVICE. */
int app_error(const char *cmd, const mr_error *err);
int app_errorf(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Sets the log level from --verbose / --quiet. */
void app_log_level(const app_opt *opts);


/* A headless GPU, a renderer and (optionally) a scene set on it. */
typedef struct app_gfx {
    mr_gpu *gpu;
    mr_renderer *renderer;
} app_gfx;
bool app_gfx_open(app_gfx *g, mr_error *err);
void app_gfx_close(app_gfx *g);
/* The AO option rows, to splice into a command's option table. */
#define APP_AO_OPTS                                                                                                 \
    {"ao", "METHOD", "ambient occlusion: none, scheer, crytek, filion, hbao, alchemy, groundtruth (default none)", NULL}, \
    {"ao-radius-mode", "MODE", "screen (radius grows with depth, default) or view (constant radius)", NULL},              \
    {"ao-radius", "R", "view-space radius in scene units (implies --ao-radius-mode view; default 2% of the scene)", NULL}, \
    {"ao-screen-radius", "F", "screen mode: projected radius as a fraction of the image height (default 0.05)", NULL},  \
    {"ao-samples", "N", "samples per pixel, 1..64 (default 16)", NULL},                                                  \
    {"ao-kernel", "K", "sample kernel: uniform, stratified, latin, poisson (default uniform)", NULL},                    \
    {"ao-rmin", "F", "kernel inner radius as a fraction of the radius (default 0.8; 0 = the whole ball)", NULL},          \
    {"ao-rmax", "F", "kernel outer radius as a fraction of the radius (default 1)", NULL},                                \
    {"ao-radii", "K", "multi-radius: K radii R, R/2, .., K in 1..5; the darkest wins (default 1)", NULL},                  \
    {"ao-c", "C", "scheer attenuation c in [0,1e7] (default 1)", NULL},                                                    \
    {"ao-bias", "B", "bias (cosine / depth fraction of the radius, default 0.05)", NULL},                                  \
    {"ao-strength", "S", "AO = 1 - S * occlusion (default per method, e.g. scheer 3)", NULL},                                                      \
    {"ao-blur", "PX", "bilateral blur half-width in AO pixels, 0 = off (default 4)", NULL},                              \
    {"ao-half", NULL, "AO at half resolution with a joint bilateral upsample", NULL},                                    \
    {"ao-positions", NULL, "AO from a view-space positions texture", NULL},                                              \
    {"ao-mask", "M", "corner masking: off, on, standalone (default off)", NULL},                                          \
    {"ao-mask-strength", "S", "standalone mask: AO = 1 - S in the corners before the blur, S in (0,1] (default 0.5)", NULL}, \
    {"ao-rays", "N", "groundtruth: rays per pixel (default 256)", NULL}
/* Reads the APP_AO_OPTS values into ao (and gt for --ao groundtruth);
 * prints one line and returns false on a bad value. */
bool app_ao_parse(const char *cmd, const app_opt *opts, mr_ao_params *ao, bool *groundtruth, mr_gt_params *gt);

/* Writes what --aux asks for: depth.pfm, normal.pfm, ao.pfm into dir. */
bool app_write_aux(const char *dir, const mr_frame_result *res, mr_error *err);



/* The ghosting option rows, to splice into a command's option table. */
#define APP_GHOST_OPTS                                                                                           \
    {"ghost", "MODE", "ghosted views of the hidden layer: off|alpha|g0|adaptive (default off)", NULL},            \
    {"ghost-importance", "SRC", "importance map: curvature|saliency|auto (default auto)", NULL},                  \
    {"ghost-saliency", "IMPL", "saliency pyramid: mipmap|gauss (default mipmap)", NULL},                         \
    {"ghost-t", "T", "user transparency t in [0,1]: alpha = t * IM (default 1)", NULL},                          \
    {"ghost-curv-scale", "S", "curvature (rad/px) to importance scale (default 2)", NULL},                        \
    {"ghost-curv-bias", "B", "importance bias: higher = denser occluder (default 0.35)", NULL},                  \
    {"ghost-tc-min", "C", "minimal desired contrast tc_minimal (default 0.1)", NULL},                            \
    {"ghost-gamma", "G", "multiplier of IM in C_desired (default 0.5)", NULL},                                   \
    {"ghost-tc-sil", "C", "extra desired contrast on hidden silhouettes (default 0.15)", NULL}
/* Fills gp from the --ghost, --ghost-importance, --ghost-saliency and
 * --ghost-* number options present in opts; one line + false if bad. */
bool app_ghost_options(const app_opt *opts, mr_ghost_params *gp);

/* The demo hall with (conflict) or without the hidden pipes coloured like
 * the partition, and the ghosting triptychs of `mrcheck demo`. In
 * demo_ghost.c. */
bool app_demo_ghost_hall(bool conflict, mr_demo_hall *hall, mr_error *err);
bool app_demo_ghost(const char *dir, mr_error *err);
/* mrcheck bench ghost (bench_ghost.c). */
int app_bench_ghost(int argc, char **argv);

int cmd_demo(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_bench(int argc, char **argv);
/* Opens the headless GPU a bench renders with (close g with app_gfx_close,
 * also after a failure). In cmd_bench.c. */
typedef struct mr_bench_gpu mr_bench_gpu;
bool app_bench_gpu(app_gfx *g, mr_bench_gpu *out, mr_error *err);
int cmd_view(int argc, char **argv);
int bench_ao(int argc, char **argv);

/* Big scenes (scene_load.c): load with progress on a terminal and report
 * time and memory; LOD levels through the cache next to the scene; the
 * shared draw options. */
typedef struct app_load_info {
    double load_s;             /* wall-clock seconds for mr_scene_load */
    uint64_t file_bytes;
    uint64_t triangles;        /* drawn (instances counted each time) */
    uint64_t unique_triangles; /* stored */
    size_t peak_rss;           /* bytes, after the load */
} app_load_info;
mr_scene *app_load_scene(const char *path, const mr_scene_params *params, app_load_info *info, mr_error *err);
mr_lod *app_load_lod(const mr_scene *s, const char *scene_path, bool use_cache, mr_error *err);
/* Reads --cull --batch --instancing --lod --occlusion (on|off),
 * --lod-tolerance and --lod-pixels; prints one line and returns false on a
 * bad value. */
bool app_draw_params(const app_opt *opts, mr_draw_params *dp);
/* --lod auto (the default): levels only for scenes that draw at least
 * APP_LOD_AUTO_TRIANGLES, where simplifying pays for its one-off cost. */
bool app_lod_auto(const app_opt *opts);
#define APP_LOD_AUTO_TRIANGLES 500000u
#define APP_DRAW_OPTS                                                                                          \
    {"cull", "on|off", "BVH frustum culling (default on)", NULL},                                              \
    {"batch", "on|off", "multi-draw-indirect batching (default on)", NULL},                                   \
    {"instancing", "on|off", "one command per mesh instead of per node (default on)", NULL},                   \
    {"lod", "auto|on|off", "simplified levels within the tolerance, cached next to the scene (default auto: on for scenes over 500k triangles)", NULL}, \
    {"lod-tolerance", "UNITS", "largest geometric error of a level in scene units (default 0.005)", NULL},     \
    {"lod-pixels", "PX", "largest projected error of a level in pixels (default 1)", NULL},                    \
    {"occlusion", "on|off", "occlusion culling (default off)", NULL}

int cmd_synth(int argc, char **argv);
int cmd_factory(int argc, char **argv);
int bench_scene(int argc, char **argv);

#endif
