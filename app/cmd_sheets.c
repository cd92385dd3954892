/* mrcheck tags | board: printable tag sheets and calibration boards
 * (lib/batch's mr_sheet_tags / mr_sheet_board). */
#include "app.h"
#include "mr_batch.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int sheets(int argc, char **argv, bool board) {
    const char *cmd = board ? "board" : "tags";
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
    sp.out_dir = mr_cli_get(opts, "out");
    sp.family = mr_cli_get(opts, "family");
    if (mr_cli_get(opts, "paper")) sp.paper = mr_cli_get(opts, "paper");
    sp.force = mr_cli_flag(opts, "force");
    sp.progress = isatty(2) && mr_log_get_level() >= MR_LOG_WARN;
    if (!sp.out_dir) return mr_cli_errorf(cmd, "--out is required (see --help)"), 2;
    if (!board && !(sp.size_mm > 0)) return mr_cli_errorf(cmd, "--size-mm is required: the printed edge of the black square"), 2;
    int *ids = NULL;
    const char *list = mr_cli_get(opts, "ids") ? mr_cli_get(opts, "ids") : "0-11";
    if (!board && !mr_sheet_ids_parse(list, &ids, &sp.id_count))
        return mr_cli_errorf(cmd, "--ids: expected ids like 0-11 or 0,3,7-9 (each once), got '%s'", list), 2;
    sp.ids = ids;
    mr_stop_catch();
    mr_error err = {0};
    mr_sheet_result r;
    bool ok = board ? mr_sheet_board(&sp, &r, &err) : mr_sheet_tags(&sp, &r, &err);
    free(ids);
    if (!ok) return mr_cli_error(cmd, &err);
    if (board)
        printf("board: %dx%d tags, pitch %g mm; wrote %s, %s/board.png at %g dpi and %s\n", r.cols, r.rows, r.pitch_mm,
               r.pdf, sp.out_dir, sp.dpi, r.json);
    else
        printf("tags: %d tags on %d page%s (%d a page); wrote %s, %d PNG%s at %g dpi and %s\n", r.tags, r.pages,
               r.pages == 1 ? "" : "s", r.per_page, r.pdf, r.pages, r.pages == 1 ? "" : "s", sp.dpi, r.json);
    return 0;
}

int cmd_tags(int argc, char **argv) { return sheets(argc, argv, false); }
int cmd_board(int argc, char **argv) { return sheets(argc, argv, true); }
