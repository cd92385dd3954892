/* mrcheck export: a session's marks as a BCF archive (lib/export) and/or a
 * self-contained HTML + Markdown report. Wiring only. */
#include "app.h"
#include "mr_export.h"

#include <stdlib.h>
#include <string.h>

int cmd_export(int argc, char **argv) {
    static const char *cmd = "export";
    mr_cli_opt opts[] = {
        {"bcf", "OUT.bcf", "write the marks as BCF topics (one per mark)", NULL},
        {"html", "OUTDIR", "write the report: index.html, report.md, img/", NULL},
        {"scene", "S", "report: the plan (glTF/GLB or scene config) for the plan-view map", NULL},
        {"author", "NAME", "CreationAuthor of the topics (default mrcheck)", NULL},
        {"title", "TEXT", "report title (default \"mrcheck findings\")", NULL},
        MR_CLI_LOG_OPTS,
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

/* mrcheck bcf list FILE [--scene S] | bcf answer FILE --topic N ... --out OUT.bcf */
int cmd_bcf(int argc, char **argv) {
    static const char *cmd = "bcf";
    const char *sub = argc > 2 ? argv[2] : "";
    bool answer = strcmp(sub, "answer") == 0, list = strcmp(sub, "list") == 0;
    mr_cli_opt opts[] = {
        {"scene", "S", "list: count the components the scene has", NULL},
        {"topic", "N|GUID", "answer: the topic (number from list, or GUID)", NULL},
        {"comment", "TEXT", "answer: a comment", NULL},
        {"status", "S", "answer: the new TopicStatus (e.g. Closed)", NULL},
        {"snapshot", "PNG", "answer: a new snapshot from site", NULL},
        {"author", "NAME", "answer: the comment's author (an e-mail address for Procore)", NULL},
        {"out", "OUT.bcf", "answer: where to write the topics", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_export_params p = MR_EXPORT_DEFAULTS;
    mr_cli_table tables[] = {{.prefix = "bcf", .table = mr_export_opts, .params = &p}};
    const char *pos[1];
    int npos = 0;
    bool help;
    if (!mr_cli_parse_tables(argc, argv, answer || list ? 3 : 2, opts, tables, 1, pos, 1, &npos,
                             "usage: mrcheck bcf (list FILE [--scene S] | answer FILE --topic N [--comment TEXT] "
                             "[--status S] [--snapshot PNG] [--author NAME] --out OUT.bcf [--bcf-version 2.1|3.0])",
                             &help))
        return 2;
    if (help) return 0;
    if (!answer && !list) return mr_cli_errorf(cmd, "needs list or answer (see --help)"), 2;
    if (npos != 1) return mr_cli_errorf(cmd, "needs a BCF file or folder (see --help)"), 2;
    mr_error err = {0};
    const char *out = mr_cli_get(opts, "out");
    mr_bcf_answer_file_params a = {
        .in = pos[0], .topic = mr_cli_get(opts, "topic"), .snapshot_path = mr_cli_get(opts, "snapshot"),
        .answer = {.comment = mr_cli_get(opts, "comment"), .status = mr_cli_get(opts, "status"),
                   .author = mr_cli_get(opts, "author")},
        .version = (mr_bcf_version)p.bcf_version, .out = out, .warn = stderr};
    if (!(answer ? mr_bcf_answer_file(&a, &err) : mr_bcf_list_file(pos[0], mr_cli_get(opts, "scene"), stdout, stderr, &err)))
        return mr_cli_error(cmd, &err);
    if (answer && !mr_cli_flag(opts, "quiet")) printf("wrote %s (BCF %s)\n", out, p.bcf_version ? "3.0" : "2.1");
    return 0;
}
