/* Private to app/: subcommands and the small helpers they share. The app
 * only parses arguments and wires the libraries together. */
#ifndef MR_APP_H
#define MR_APP_H

#include "mr_core.h"
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_scene.h"
#include "mr_ui.h"

/* A headless GPU, a renderer and (optionally) a scene set on it. */
typedef struct app_gfx {
    mr_gpu *gpu;
    mr_renderer *renderer;
} app_gfx;
bool app_gfx_open(app_gfx *g, mr_error *err);
void app_gfx_close(app_gfx *g);
/* The AO and ghosting tables of a command (fill .params, then parse). */
#define APP_AO_TABLE(p) {.prefix = "ao", .table = mr_ao_opts, .params = (p), .extra = "groundtruth", .research = true}
/* The ground truth's rays, --ao-rays (its params live in lib/eval). */
#define APP_GT_TABLE(p) {.prefix = "ao", .table = mr_gt_opts, .params = (p), .research = true}
#define APP_GHOST_TABLE(p) {.prefix = "ghost", .table = mr_ghost_opts, .params = (p), .research = true}

/* Shadows: --shadows METHOD, --shadows-KEY from mr_shadow_opts;
 * without --shadows the scene config's "shadows" names the method (one line
 * and false if it names none). In shadow_opts.c. */
#define APP_SHADOW_TABLE(p) {.prefix = "shadows", .table = mr_shadow_opts, .params = (p), .research = true}
bool app_shadow_scene_default(const char *cmd, const mr_cli_table *t, const mr_scene *s, mr_shadow_params *p);




/* The demo hall with (conflict) or without the hidden pipes coloured like
 * the partition, and the ghosting triptychs of `mrcheck demo`. In
 * demo_ghost.c. */
bool app_demo_ghost_hall(bool conflict, mr_demo_hall *hall, mr_error *err);
bool app_demo_ghost(const char *dir, mr_error *err);
/* mrcheck bench ghost (bench_ghost.c). */
int app_bench_ghost(int argc, char **argv);
/* mrcheck bench shadows (bench_shadows.c). */
int app_bench_shadows(int argc, char **argv);

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
/* --lod: "auto" (or not given), "on" or "off" into dp->no_lod (auto: on,
 * decided by app_lod_auto once the scene is loaded); prints one line and
 * returns false on a bad value. */
bool app_draw_lod(const char *cmd, const mr_cli_opt *opts, mr_draw_params *dp);
/* --lod auto (the default), once the scene is loaded: no levels (dp->no_lod)
 * for scenes that draw under MR_LOD_AUTO_TRIANGLES (lib/scene), where
 * simplifying does not pay for its one-off cost. */
void app_lod_auto(const mr_cli_opt *opts, const mr_scene *s, mr_draw_params *dp);
/* The draw table (no prefix) and --lod auto|on|off, which decides whether
 * levels are built or read at all. */
#define APP_DRAW_TABLE(p) {.prefix = "", .table = mr_draw_opts, .params = (p), .research = true}
#define APP_DRAW_OPTS                                                                                          \
    {"lod", "auto|on|off", "simplified levels within the tolerance, cached next to the scene (default auto: on for scenes over 500k triangles)", NULL}

/* mrcheck study {stimuli,plan,run,analyze} (cmd_study.c). */
int cmd_study(int argc, char **argv);
/* Multi-view output (rig_opts.c): the rig table (no prefix: --views,
 * --view-cone, --view-fov, --focal-distance) and --quilt, shared by render
 * and replay. */
#define APP_RIG_OPTS {"quilt", "SPEC", "multi-view quilt: portrait, go, 4k, 8k, CxR or CxR@WxH (default: about square)", NULL}, \
    {"lightfield", "BAND", "one image under a light-field display's mapping (each column its own eye on the observer line of --view-cone), drawn in slices of BAND columns (1 = exact)", NULL}
#define APP_RIG_TABLE(p) {.prefix = "", .table = mr_rig_opts, .params = (p), .research = true}
/* --quilt into quilt (zeroed when not given); rig options without --views
 * or --quilt are a mistake. Prints one line and returns false on bad input. */
bool app_rig_check(const char *cmd, const mr_cli_table *t, const mr_cli_opt *opts, mr_quilt *quilt, bool *have_quilt);
/* mrcheck bench multiview (bench_multiview.c). */
int bench_multiview(int argc, char **argv);

int cmd_synth(int argc, char **argv);
int cmd_factory(int argc, char **argv);
/* mrcheck export (cmd_export.c) */
int cmd_export(int argc, char **argv);
int cmd_hall(int argc, char **argv); /* cmd_hall.c */
int bench_scene(int argc, char **argv);
/* mrcheck bench map (bench_map.c). */
int bench_map(int argc, char **argv);
int bench_measure(int argc, char **argv); /* bench_map.c */

/* mrcheck bench load (bench_load.c). */
int bench_load(int argc, char **argv);

#endif
