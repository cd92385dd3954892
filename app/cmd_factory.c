/* mrcheck factory: big synthetic factories as .glb, with views to render them. */
#include "app.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int cmd_factory(int argc, char **argv) {
    static const char *cmd = "factory";
    mr_cli_opt opts[] = {
        {"out", "FILE.glb", "output scene (required)", NULL},
        {"triangles", "N", "drawn triangles to aim for, e.g. 1M, 5M, 20M (default 1M)", NULL},
        {"seed", "S", "random seed (default 1)", NULL},
        {"offset", "X,Z", "move the whole plant (tests far from the origin)", NULL},
        {"views", "DIR", "also write view_floor.json, view_aisle.json, view_overview.json there", NULL},
        {"unique", NULL, "unique CAD-like geometry: every part its own mesh (20k triangles), split at normal seams", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    mr_synth_params sp = MR_SYNTH_DEFAULTS;
    mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
    mr_cli_table tables[] = {{.prefix = "", .table = mr_synth_opts, .params = &sp}, {.prefix = "", .table = mr_synth_cad_opts, .params = &cp}};
    if (!mr_cli_parse_tables(argc, argv, 2, opts, tables, 2, NULL, 0, NULL,
                   "usage: mrcheck factory --out FILE.glb [--triangles N | --halls N] [--seed S] [--views DIR] [--unique [--unit U]]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *out = mr_cli_get(opts, "out");
    if (!out) return mr_cli_errorf(cmd, "--out is required"), 2;
    const bool unique = mr_cli_get(opts, "unique") != NULL;
    const bool halls = mr_cli_table_given(&tables[0], "halls");
    if (unique && halls) return mr_cli_errorf(cmd, "--halls is for the instanced factory, not --unique"), 2;
    if (!unique && mr_cli_table_given(&tables[1], "unit")) return mr_cli_errorf(cmd, "--unit needs --unique"), 2;
    if (halls && mr_cli_get(opts, "triangles")) return mr_cli_errorf(cmd, "give --halls or --triangles, not both"), 2;
    if (!halls) {
        double tri = 1e6;
        if (mr_cli_get(opts, "triangles") && mr_cli_counts(mr_cli_get(opts, "triangles"), 1, 1e11, &tri, 1) != 1)
            return mr_cli_errorf(cmd, "--triangles: '%s' is not a count like 5M", mr_cli_get(opts, "triangles")), 2;
        sp.halls = mr_synth_halls_for((uint64_t)tri);
        cp.parts = mr_synth_cad_parts_for(&cp, tri);
    }
    if (mr_cli_get(opts, "seed")) {
        long seed;
        if (!mr_cli_int("seed", mr_cli_get(opts, "seed"), 0, 2147483647L, &seed)) return 2;
        sp.seed = (uint64_t)seed;
        cp.seed = (uint64_t)seed;
    }
    if (mr_cli_get(opts, "offset")) {
        char *e1 = NULL, *e2 = NULL;
        const char *v = mr_cli_get(opts, "offset");
        sp.origin[0] = strtod(v, &e1);
        if (e1 == v || *e1 != ',' || (sp.origin[2] = strtod(e1 + 1, &e2), e2 == e1 + 1 || *e2) || !isfinite(sp.origin[0]) ||
            !isfinite(sp.origin[2]) || fabs(sp.origin[0]) > 1e9 || fabs(sp.origin[2]) > 1e9)
            return mr_cli_errorf(cmd, "--offset must be X,Z (finite, |v| <= 1e9)"), 2;
        cp.origin[0] = sp.origin[0]; /* metres */
        cp.origin[2] = sp.origin[2];
    }
    mr_error err = {0};
    double t0 = mr_time_now();
    mr_scene *s = unique ? mr_synth_cad_build(&cp, &err) : mr_synth_build(&sp, &err);
    if (!s) return mr_cli_error(cmd, &err);
    uint64_t uniq = 0;
    for (int32_t i = 0; i < s->mesh_count; i++) uniq += s->meshes[i].index_count / 3;
    if (unique)
        printf("factory: %d unique parts in unit %g per metre, %d nodes, %d meshes, %llu triangles drawn (%llu stored), built in %.2f s\n",
               cp.parts, cp.unit, (int)s->node_count, (int)s->mesh_count, (unsigned long long)mr_scene_triangle_count(s),
               (unsigned long long)uniq, mr_time_now() - t0);
    else
        printf("factory: %d halls, %d nodes, %d meshes, %llu triangles drawn (%llu stored), built in %.2f s\n", sp.halls,
               (int)s->node_count, (int)s->mesh_count, (unsigned long long)mr_scene_triangle_count(s),
               (unsigned long long)uniq, mr_time_now() - t0);
    char dir[4096];
    mr_path_dir(out, dir, sizeof dir);
    bool ok = mr_mkdirs(dir, &err) && mr_scene_save_glb(s, out, &err);
    mr_scene_destroy(&s);
    const char *views = mr_cli_get(opts, "views");
    if (ok && views) ok = mr_synth_save_views(views, &sp, unique ? &cp : NULL, &err);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("wrote %s%s%s\n", out, views ? " and views in " : "", views ? views : "");
    return 0;
}
