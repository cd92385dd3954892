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

/* A params struct whose option table is spliced into a command's options:
 * --PREFIX (the table's "" row) and --PREFIX-KEY for each other row, with
 * their help lines made from the table. Values are checked and written into
 * params (which holds its defaults) after the whole line was read, so that
 * --help always wins. */
#define APP_TABLE_MAX 32
typedef struct app_table {
    const char *prefix;       /* "ao", "ghost" */
    const mr_opt *table;      /* at most APP_TABLE_MAX rows */
    void *params;
    const char *extra;        /* one more value --PREFIX accepts beyond the table's
                                 names (--ao groundtruth), or NULL */
    bool extra_given;         /* filled: --PREFIX EXTRA was given */
    const char *values[APP_TABLE_MAX]; /* filled: the text given for each row, or NULL */
} app_table;
/* True if the row `key` of t was on the command line. */
bool app_table_given(const app_table *t, const char *key);
/* app_parse with tables: rows of opts first, then each table's rows. */
bool app_parse_tables(int argc, char **argv, int first, app_opt *opts, app_table *tables, int ntables,
                      const char **pos, int max_pos, int *npos, const char *usage, bool *help_shown);
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
/* The AO rows beyond mr_ao_opts, to splice into a command's option table:
 * the ground truth's rays (its params live in lib/eval). */
#define APP_AO_OPTS {"ao-rays", "N", "groundtruth: rays per pixel (default 256)", NULL}
/* The AO and ghosting tables of a command (fill .params, then parse). */
#define APP_AO_TABLE(p) {.prefix = "ao", .table = mr_ao_opts, .params = (p), .extra = "groundtruth"}
#define APP_GHOST_TABLE(p) {.prefix = "ghost", .table = mr_ghost_opts, .params = (p)}
/* The checks of the AO table's values that are not a plain range (--ao-radius
 * only in view mode, --ao-rmin <= --ao-rmax, --ao-mask-strength only for the
 * standalone mask), --ao groundtruth and --ao-rays into gt; prints one line
 * and returns false on a bad value. */
bool app_ao_check(const char *cmd, const app_table *t, const app_opt *opts, bool *groundtruth, mr_gt_params *gt);

/* Writes what --aux asks for: depth.pfm, normal.pfm, ao.pfm into dir. */
bool app_write_aux(const char *dir, const mr_frame_result *res, mr_error *err);



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
    {"lod-tolerance", "UNITS", "largest geometric error of a level in scene units (default: none, pixels decide)", NULL},     \
    {"lod-pixels", "PX", "largest projected error of a level in pixels (default 1)", NULL},                    \
    {"occlusion", "on|off", "occlusion culling (default off)", NULL}

int cmd_synth(int argc, char **argv);
int cmd_factory(int argc, char **argv);
int bench_scene(int argc, char **argv);

#endif
