/* mrcheck export: a session's marks as a BCF archive (lib/export) and/or a
 * self-contained HTML + Markdown report. Wiring only. */
#include "app.h"
#include "mr_export.h"

int cmd_export(int argc, char **argv) {
    static const char *cmd = "export";
    mr_cli_opt opts[] = {
        {"bcf", "OUT.bcf", "write the marks as BCF topics (one per mark)", NULL},
        {"html", "OUTDIR", "write the report: index.html, report.md, img/", NULL},
        {"scene", "S", "report: the plan (glTF/GLB or scene config) for the plan-view map", NULL},
        {"author", "NAME", "CreationAuthor of the topics (default mrcheck)", NULL},
        {"title", "TEXT", "report title (default \"mrcheck findings\")", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_export_params p = MR_EXPORT_DEFAULTS;
    mr_cli_table tables[] = {{.prefix = "bcf", .table = mr_export_opts, .params = &p}};
    const char *pos[1];
    int npos = 0;
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, tables, 1, pos, 1, &npos,
                          "usage: mrcheck export DIR (--bcf OUT.bcf [--bcf-version 2.1|3.0] | --html OUTDIR [--scene S]) "
                          "[--author NAME]",
                          &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *bcf = mr_cli_get(opts, "bcf"), *html = mr_cli_get(opts, "html");
    if (npos != 1 || (!bcf && !html))
        return mr_cli_errorf(cmd, "needs a session folder and --bcf and/or --html (see --help)"), 2;
    p.author = mr_cli_get(opts, "author");
    p.title = mr_cli_get(opts, "title");
    mr_error err = {0};
    mr_scene *scene = NULL;
    if (html && mr_cli_get(opts, "scene")) {
        scene = mr_scene_load(mr_cli_get(opts, "scene"), NULL, &err);
        if (!scene) return mr_cli_error(cmd, &err);
        p.scene = scene;
    }
    int rc = 0;
    if (bcf) {
        if (!mr_export_bcf(pos[0], bcf, &p, &err)) rc = mr_cli_error(cmd, &err);
        else if (!mr_cli_flag(opts, "quiet")) printf("wrote %s (BCF %s)\n", bcf, p.bcf_version == MR_BCF_3_0 ? "3.0" : "2.1");
    }
    if (rc == 0 && html) {
        if (!mr_export_report(pos[0], html, &p, &err)) rc = mr_cli_error(cmd, &err);
        else if (!mr_cli_flag(opts, "quiet")) printf("wrote %s/index.html\n", html);
    }
    mr_scene_destroy(&scene);
    return rc;
}
