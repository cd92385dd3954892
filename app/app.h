/* Private to app/: subcommands and the small helpers they share. The app
 * only parses arguments and wires the libraries together. */
#ifndef MR_APP_H
#define MR_APP_H

#include "mr_core.h"
#include "mr_eval.h"
#include "mr_render.h"
#include "mr_scene.h"
#include "mr_ui.h"

/* The AO and ghosting tables of a command (fill .params, then parse). */
#define APP_AO_TABLE(p) {.prefix = "ao", .table = mr_ao_opts, .params = (p), .extra = "groundtruth", .research = true}
/* The ground truth's rays, --ao-rays (its params live in lib/eval). */
#define APP_GT_TABLE(p) {.prefix = "ao", .table = mr_gt_opts, .params = (p), .research = true}
#define APP_GHOST_TABLE(p) {.prefix = "ghost", .table = mr_ghost_opts, .params = (p), .research = true}

/* Shadows: --shadows METHOD, --shadows-KEY from mr_shadow_opts (then
 * mr_shadow_scene_default once the scene is loaded). */
#define APP_SHADOW_TABLE(p) {.prefix = "shadows", .table = mr_shadow_opts, .params = (p), .research = true}

/* mrcheck bench ghost (bench_ghost.c). */
int app_bench_ghost(int argc, char **argv);
/* mrcheck bench shadows (bench_shadows.c). */
int app_bench_shadows(int argc, char **argv);

int cmd_demo(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_view(int argc, char **argv);
int bench_ao(int argc, char **argv);

/* The draw table (no prefix) and --lod auto|on|off (mr_lod_mode_parse),
 * which decides whether levels are built or read at all. */
#define APP_DRAW_TABLE(p) {.prefix = "", .table = mr_draw_opts, .params = (p), .research = true}
#define APP_DRAW_OPTS                                                                                          \
    {"lod", "auto|on|off", "simplified levels within the tolerance, cached next to the scene (default auto: on for scenes over 500k triangles)", NULL}, \
    {"hlod", "auto|on|off", "levels above the part: merged proxies of groups of parts, cut by --lod-pixels, cached in <scene>.mrhlod (default auto: scenes of 1M triangles in 16 parts)", NULL}

/* mrcheck study {stimuli,plan,run,analyze} (cmd_study.c). */
int cmd_study(int argc, char **argv);
/* Multi-view output: the rig table (no prefix: --views, --view-cone,
 * --view-fov, --focal-distance), --quilt and --lightfield, shared by render
 * and replay and checked together by mr_rig_opts_check. */
#define APP_RIG_OPTS {"quilt", "SPEC", "multi-view quilt: portrait, go, 4k, 8k, CxR or CxR@WxH (default: about square)", NULL}, \
    {"lightfield", "BAND", "one image under a light-field display's mapping (each column its own eye on the observer line of --view-cone), drawn in slices of BAND columns (1 = exact)", NULL}
#define APP_RIG_TABLE(p) {.prefix = "", .table = mr_rig_opts, .params = (p), .research = true}
/* mrcheck bench multiview (bench_multiview.c). */
int bench_multiview(int argc, char **argv);

int cmd_synth(int argc, char **argv);
int cmd_factory(int argc, char **argv);
/* mrcheck export (cmd_export.c) */
int cmd_export(int argc, char **argv);
int cmd_bcf(int argc, char **argv); /* bcf list | answer */
int cmd_hall(int argc, char **argv); /* cmd_hall.c */
int cmd_sheets(int argc, char **argv); /* tags | board: cmd_sheets.c */
int bench_scene(int argc, char **argv);
/* mrcheck bench map (bench_map.c). */
int bench_map(int argc, char **argv);
int bench_measure(int argc, char **argv); /* bench_map.c */

/* mrcheck bench load (bench_load.c). */
int bench_load(int argc, char **argv);

#endif
