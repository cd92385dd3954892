/* mrcheck demo: the built-in job (mr_demo_run, lib/bench): the procedural
 * hall as planned and as built with its files, a synthetic recording, camera
 * frames with the planned model over them, marks as BCF and a report, and
 * the ghosted views. */
#include "app.h"
#include "mr_bench.h"

int cmd_demo(int argc, char **argv) {
    mr_cli_opt opts[] = {
        {"out", "DIR", "output folder (default: demo-out)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!mr_cli_parse(argc, argv, 2, opts, NULL, 0, NULL, "usage: mrcheck demo [--out DIR]", &help)) return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *dir = mr_cli_get(opts, "out") ? mr_cli_get(opts, "out") : "demo-out";
    mr_error err = {0};
    if (!mr_demo_run(dir, &err)) return mr_cli_error("demo", &err);
    return 0;
}
