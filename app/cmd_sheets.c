/* mrcheck tags | board: printable tag sheets and calibration boards
 * (lib/batch's mr_sheet_tags / mr_sheet_board). */
#include "app.h"
#include "mr_batch.h"

#include <string.h>
#include <unistd.h>

int cmd_sheets(int argc, char **argv) {
    const bool board = strcmp(argv[1], "board") == 0;
    mr_cli_opt opts[] = {
        {"out", "DIR", "folder to write (new or empty)", NULL},
        {"ids", "LIST", "tags: ids to print, e.g. 0-11 or 0,3,7-9 (default 0-11)", NULL},
        {"family", "F", "tag family (default tag36h11)", NULL},
        {"paper", "a4|a3|letter", "paper size (default a4)", NULL},
        {"force", NULL, "write into a folder that already holds files", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_sheet_params sp = MR_SHEET_DEFAULTS;
    mr_cli_table table = {.prefix = "", .table = mr_sheet_opts, .params = &sp};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 2, opts, &table, 1, NULL, 0, NULL,
                   board ? "usage: mrcheck board --out DIR [--size-mm 30] [--cols C --rows R] [--paper a4] [--dpi 300]\n"
                           "A planar calibration board for mrcheck calibrate: board.pdf, board.png and board.json."
                         : "usage: mrcheck tags --out DIR --size-mm MM [--ids 0-11] [--paper a4] [--dpi 300]\n"
                           "Printable AprilTags: tags.pdf, a PNG per page at --dpi and markers_template.json\n"
                           "(the marker map with ids and size, positions to be surveyed by mrcheck map).",
                   &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    if (!(sp.out_dir = mr_cli_get(opts, "out"))) return mr_cli_errorf(argv[1], "--out is required (see --help)"), 2;
    sp.family = mr_cli_get(opts, "family");
    sp.paper = mr_cli_get(opts, "paper") ? mr_cli_get(opts, "paper") : sp.paper;
    sp.ids_text = mr_cli_get(opts, "ids");
    sp.force = mr_cli_flag(opts, "force");
    sp.progress = isatty(2) && mr_log_get_level() >= MR_LOG_WARN;
    mr_stop_catch();
    mr_error err = {0};
    mr_sheet_result r;
    if (!(board ? mr_sheet_board(&sp, &r, &err) : mr_sheet_tags(&sp, &r, &err))) return mr_cli_error(argv[1], &err);
    puts(r.summary);
    return 0;
}
