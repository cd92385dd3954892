/* mrcheck hall {init,add,show}: the hall folder (lib/session/hall.c). */
#include "app.h"

#include "mr_session.h"

#include <string.h>

static bool check_scene(void *user, const char *path, mr_error *err) {
    mr_scene *s = mr_scene_load(path, NULL, err);
    if (!s) return false;
    mr_scene_destroy(&s);
    return true;
}

static int show(const char *dir) {
    mr_hall h;
    mr_error err = {0};
    if (!mr_hall_load(dir, &h, &err)) return mr_cli_error("hall show", &err);
    return mr_hall_print(&h, check_scene, NULL, stdout) ? 1 : 0;
}

int cmd_hall(int argc, char **argv) {
    mr_cli_opt opts[] = {
        {"scene", "FILE", "the plan: glTF/GLB, IFC or a scene config (referenced by a path relative to the hall)", NULL},
        {"camera", "C.json", "camera file (mrcheck calibrate); copied in as camera.json", NULL},
        {"markers", "M.json", "marker map (mrcheck map); copied in as markers.json", NULL},
        {"control", "P.json", "surveyed control points; copied in as control.json", NULL},
        {"tolerances", "T.json", "tolerance table (default DIN 18202 Table 1); copied in as tolerances.json", NULL},
        {"input", "DEV", "the live camera (default /dev/video0)", NULL},
        {"name", "TEXT", "the hall's name, for people", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[2];
    int npos = 0;
    bool help;
    if (!mr_cli_parse(argc, argv, 2, opts, pos, 2, &npos,
                      "usage: mrcheck hall init HALL --scene S [--camera C] [--markers M] [--control P] [--tolerances T]\n"
                      "       mrcheck hall add HALL [--camera C] ...   (add or replace files; init on a hall does the same)\n"
                      "       mrcheck hall show HALL                   (its files, each checked)\n"
                      "A hall folder holds what a check needs, named in HALL/hall.json; then `mrcheck view HALL`,\n"
                      "`mrcheck view HALL --replay SESSION`, and every command takes HALL for its files.",
                      &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *sub = npos > 0 ? pos[0] : NULL;
    if (!sub || npos < 2) return mr_cli_errorf("hall", "give init, add or show and a hall folder (see --help)"), 2;
    if (strcmp(sub, "show") == 0) return show(pos[1]);
    bool init = strcmp(sub, "init") == 0;
    if (!init && strcmp(sub, "add") != 0) return mr_cli_errorf("hall", "unknown subcommand '%s' (init, add, show)", sub), 2;
    mr_hall_update u = MR_HALL_UPDATE_DEFAULTS;
    for (int i = 0; i < MR_HALL_ITEM_COUNT; i++) u.files[i] = mr_cli_get(opts, mr_hall_item_keys[i]);
    u.input = mr_cli_get(opts, "input");
    u.name = mr_cli_get(opts, "name");
    u.check_scene = check_scene;
    mr_hall h;
    mr_error err = {0};
    if (!mr_hall_update_files(pos[1], &u, init, &h, &err)) return mr_cli_error(init ? "hall init" : "hall add", &err);
    printf("hall %s: wrote %s/%s\n", pos[1], pos[1], MR_HALL_MANIFEST);
    return 0;
}
