/* A hall on any command line: `mrcheck CMD HALL ...` or `--hall HALL`
 * stands for the files the hall names. The command sees the flags as if
 * they had been typed, so a hall changes no command's behaviour beyond
 * what those flags do; flags given on the line always win. */
#include "mr_session.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

enum { OUT_NONE = 0, OUT_SESSION, OUT_NEW_SESSION, OUT_REPLAY, OUT_ITEM };
#define BIT(i) (1u << (i))

/* Which files a command takes from a hall. "Live" commands take the
 * camera, the marker map and the live input, except when their session is
 * a recording (which carries its own camera and map). */
typedef struct hall_cmd {
    const char *name;
    unsigned fill;       /* items whose flags are filled (bits of mr_hall_item) */
    bool live;           /* camera, markers and --input from the hall (see above) */
    const char *session; /* the flag naming a session; "" the first positional; NULL none */
    const char *unless;  /* given, this flag keeps the control points out (map --fix) */
    int out;             /* what --out defaults to */
    int out_item;        /* OUT_ITEM: the file written, recorded in the manifest */
    const char *help;
} hall_cmd;

static const hall_cmd k_cmds[] = {
    {"view", BIT(MR_HALL_SCENE) | BIT(MR_HALL_TOLERANCES), true, "replay", NULL, OUT_SESSION, 0,
     "--scene, --tolerances, and for live input --camera, --markers and --input (the manifest's, default /dev/video0);\n"
     "  --replay SESSION: a folder in HALL/sessions/ (or a path); --out: that session's folder in the hall,\n"
     "  a new HALL/sessions/<date-time>/ when live"},
    {"record", 0, true, NULL, NULL, OUT_NEW_SESSION, 0,
     "--camera, --markers and --input (default /dev/video0); --out: a new HALL/sessions/rec-<date-time>/"},
    {"track", 0, true, "input", NULL, OUT_NONE, 0,
     "--camera and --markers (not for a recorded session, which carries its own), --input (default the\n"
     "  hall's live camera; a folder in HALL/sessions/ by its name)"},
    {"replay", BIT(MR_HALL_SCENE), false, "", NULL, OUT_REPLAY, 0,
     "--scene; SESSION: a folder in HALL/sessions/ (or a path); --out: SESSION/replay in the hall"},
    {"measure", BIT(MR_HALL_SCENE) | BIT(MR_HALL_TOLERANCES), false, "recording", NULL, OUT_NONE, 0,
     "--scene and --tolerances; --recording SESSION: a folder in HALL/sessions/ (or a path)"},
    {"export", BIT(MR_HALL_SCENE), false, "", NULL, OUT_NONE, 0,
     "--scene (the report's plan view); SESSION: a folder in HALL/sessions/ (or a path)"},
    {"render", BIT(MR_HALL_SCENE), false, NULL, NULL, OUT_NONE, 0, "--scene"},
    {"map", BIT(MR_HALL_CAMERA) | BIT(MR_HALL_CONTROL), false, NULL, "fix", OUT_ITEM, MR_HALL_MARKERS,
     "--camera and --control (not with --fix); --out: HALL/markers.json, then named in hall.json"},
    {"calibrate", 0, false, NULL, NULL, OUT_ITEM, MR_HALL_CAMERA,
     "--out: HALL/camera.json, then named in hall.json"},
};

static const hall_cmd *find_cmd(const char *name) {
    for (size_t i = 0; i < sizeof k_cmds / sizeof k_cmds[0]; i++)
        if (strcmp(k_cmds[i].name, name) == 0) return &k_cmds[i];
    return NULL;
}

const char *mr_hall_args_help(const char *cmd) {
    const hall_cmd *c = find_cmd(cmd);
    if (!c) return NULL;
    static char buf[1024];
    snprintf(buf, sizeof buf,
             "\nhall (`mrcheck %s HALL ...` or --hall HALL; HALL: a folder with hall.json, see docs/formats.md):\n"
             "  what is not given comes from the hall: %s\n",
             cmd, c->help);
    return buf;
}

static char *keep(mr_hall_args *a, const char *s) {
    if (a->pool_count >= (int)(sizeof a->pool / sizeof a->pool[0])) return NULL;
    char *d = strdup(s);
    if (d) a->pool[a->pool_count++] = d;
    return d;
}

/* The index of --flag (or --flag=...) among argv[2..argc); -1 if absent.
 * *value gets its value. */
static int find_flag(int argc, char **argv, const char *flag, const char **value) {
    size_t n = strlen(flag);
    for (int i = 2; i < argc; i++) {
        const char *t = argv[i];
        if (strncmp(t, "--", 2) != 0 || strncmp(t + 2, flag, n) != 0) continue;
        if (t[2 + n] == '=') {
            if (value) *value = t + 3 + n;
            return i;
        }
        if (!t[2 + n]) {
            if (value) *value = i + 1 < argc ? argv[i + 1] : NULL;
            return i;
        }
    }
    return -1;
}

static bool add_flag(mr_hall_args *a, const char *flag, const char *value) {
    char f[64];
    snprintf(f, sizeof f, "--%s", flag);
    char *fv = keep(a, f), *vv = keep(a, value);
    if (!fv || !vv) return false;
    a->argv[a->argc++] = fv;
    a->argv[a->argc++] = vv;
    a->argv[a->argc] = NULL;
    return true;
}

static void base_name(const char *path, char *out, size_t n) {
    char tmp[1024];
    snprintf(tmp, sizeof tmp, "%s", path);
    size_t l = strlen(tmp);
    while (l > 1 && tmp[l - 1] == '/') tmp[--l] = 0;
    const char *s = strrchr(tmp, '/');
    snprintf(out, n, "%s", s ? s + 1 : tmp);
}

/* Where a session's outputs go: the session itself when it lies in the
 * hall, else a folder of its name in the hall's sessions. */
static void session_out(const mr_hall *h, const char *session, char *out, size_t n) {
    if (mr_hall_contains(h, session)) {
        snprintf(out, n, "%s", session);
        return;
    }
    char sd[4096], b[256];
    mr_hall_sessions_dir(h, sd, sizeof sd);
    base_name(session, b, sizeof b);
    mr_path_join(sd, b, out, n);
}

static bool fill(mr_hall_args *a, const hall_cmd *c, const char *session, mr_error *err) {
    const mr_hall *h = &a->hall;
    char p[4096];
    bool recorded = session && mr_is_recording(session);
    for (int i = 0; i < MR_HALL_ITEM_COUNT; i++) {
        bool want = (c->fill & BIT(i)) != 0;
        if (c->live && (i == MR_HALL_CAMERA || i == MR_HALL_MARKERS)) want = !recorded;
        if (i == MR_HALL_CONTROL && c->unless && find_flag(a->argc, a->argv, c->unless, NULL) >= 0) want = false;
        if (!want || find_flag(a->argc, a->argv, mr_hall_item_keys[i], NULL) >= 0) continue;
        if (!mr_hall_path(h, (mr_hall_item)i, p, sizeof p)) {
            /* Live tracking needs both: say how the hall gets them. */
            if (c->live && i == MR_HALL_CAMERA && find_flag(a->argc, a->argv, "view", NULL) < 0)
                return mr_fail(err, MR_ERR_INVALID, "hall %s has no camera yet: mrcheck calibrate %s --images DIR --board B.json "
                               "(or mrcheck hall add %s --camera C.json)", h->dir, h->dir, h->dir);
            if (c->live && i == MR_HALL_MARKERS && find_flag(a->argc, a->argv, "view", NULL) < 0)
                return mr_fail(err, MR_ERR_INVALID, "hall %s has no marker map yet: mrcheck map %s --images DIR --tag-size S "
                               "(or mrcheck hall add %s --markers M.json)", h->dir, h->dir, h->dir);
            continue; /* the command says what it lacks */
        }
        if (!add_flag(a, mr_hall_item_keys[i], p)) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    if (c->live && !session && find_flag(a->argc, a->argv, "input", NULL) < 0 && find_flag(a->argc, a->argv, "view", NULL) < 0 &&
        !add_flag(a, "input", h->input[0] ? h->input : MR_HALL_DEFAULT_INPUT))
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    if (c->out == OUT_NONE || find_flag(a->argc, a->argv, "out", NULL) >= 0) return true;
    if (c->out == OUT_ITEM) {
        mr_path_join(h->dir, mr_hall_item_keys[c->out_item], p, sizeof p);
        snprintf(p + strlen(p), sizeof p - strlen(p), ".json");
        a->update_item = c->out_item;
        snprintf(a->update_path, sizeof a->update_path, "%s", p);
    } else if (c->out == OUT_SESSION && session) {
        session_out(h, session, p, sizeof p);
    } else if (c->out == OUT_REPLAY && session) {
        char s[4096];
        session_out(h, session, s, sizeof s);
        mr_path_join(s, "replay", p, sizeof p);
    } else if (c->out == OUT_SESSION || c->out == OUT_NEW_SESSION) {
        mr_hall_new_session(h, c->out == OUT_NEW_SESSION ? "rec-" : "", (double)time(NULL), p, sizeof p);
    } else {
        return true;
    }
    return add_flag(a, "out", p) ? true : mr_fail(err, MR_ERR_NOMEM, "out of memory");
}

bool mr_hall_args_expand(int argc, char **argv, mr_hall_args *a, mr_error *err) {
    memset(a, 0, sizeof *a);
    a->update_item = -1;
    /* Room for the line, plus a flag and value per item, --input and --out. */
    a->argv = calloc((size_t)argc + 2 * MR_HALL_ITEM_COUNT + 8, sizeof *a->argv);
    if (!a->argv) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    const hall_cmd *c = argc >= 2 ? find_cmd(argv[1]) : NULL;
    const char *hall = NULL;
    int skip_a = -1, skip_b = -1;
    if (c) {
        const char *v = NULL;
        int i = find_flag(argc, argv, "hall", &v);
        if (i >= 0) {
            if (!v) return mr_fail(err, MR_ERR_INVALID, "--hall needs a value (a hall folder)");
            hall = v, skip_a = i, skip_b = strchr(argv[i], '=') ? -1 : i + 1;
        } else if (argc >= 3 && argv[2][0] != '-' && mr_hall_is(argv[2])) {
            hall = argv[2], skip_a = 2;
        }
    }
    for (int i = 0; i < argc; i++)
        if (i != skip_a && i != skip_b) a->argv[a->argc++] = argv[i];
    if (!hall) return true;
    if (!mr_hall_load(hall, &a->hall, err)) return false;
    a->have_hall = true;
    /* The session argument, looked up in the hall. */
    const char *session = NULL;
    int si = -1;
    if (c->session && !c->session[0]) {
        if (a->argc >= 3 && a->argv[2][0] != '-') si = 2;
    } else if (c->session) {
        int fi = find_flag(a->argc, a->argv, c->session, NULL);
        if (fi >= 0 && !strchr(a->argv[fi], '=') && fi + 1 < a->argc) si = fi + 1;
    }
    if (si >= 0) {
        char p[4096];
        mr_hall_session_resolve(&a->hall, a->argv[si], p, sizeof p);
        if (!(a->argv[si] = keep(a, p))) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        session = a->argv[si];
    }
    return fill(a, c, session, err);
}

bool mr_hall_args_finish(mr_hall_args *a, int rc, mr_error *err) {
    if (rc != 0 || !a->have_hall || a->update_item < 0) return true;
    /* The command wrote the file into the hall: name it in the manifest (it
     * is checked as hall add would, which also keeps a broken one out). */
    mr_hall_update u = MR_HALL_UPDATE_DEFAULTS;
    u.files[a->update_item] = a->update_path;
    return mr_hall_update_files(a->hall.dir, &u, false, NULL, err);
}

void mr_hall_args_free(mr_hall_args *a) {
    for (int i = 0; i < a->pool_count; i++) free(a->pool[i]);
    free(a->argv);
    memset(a, 0, sizeof *a);
}

int mr_hall_run(int (*cmd)(int argc, char **argv), int argc, char **argv) {
    mr_hall_args ha;
    mr_error err = {0};
    int rc = 2;
    if (mr_hall_args_expand(argc, argv, &ha, &err)) rc = cmd(ha.argc, ha.argv);
    else mr_cli_error(argv[1], &err);
    const char *help = argc >= 2 ? mr_hall_args_help(argv[1]) : NULL;
    for (int i = 2; rc == 0 && help && i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(help, stdout);
            break;
        }
    if (!mr_hall_args_finish(&ha, rc, &err)) rc = mr_cli_error(argv[1], &err);
    mr_hall_args_free(&ha);
    return rc;
}
