/* Scripted input for tests and demos: timed commands that enter the
 * controller's event queue, the path real input takes. */
#include "view_internal.h"

#include <stdlib.h>
#include <string.h>

bool mr_view_key_parse(const char *s, int *key) {
    static const struct { const char *n; int k; } names[] = {
        {"esc", MR_KEY_ESCAPE}, {"enter", MR_KEY_ENTER}, {"left", MR_KEY_LEFT}, {"right", MR_KEY_RIGHT},
        {"up", MR_KEY_UP}, {"down", MR_KEY_DOWN}, {"home", MR_KEY_HOME}, {"end", MR_KEY_END},
        {"f1", MR_KEY_F1}, {"f11", MR_KEY_F11}, {"space", ' '}, {"tab", MR_KEY_TAB}, {"backspace", MR_KEY_BACKSPACE},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strcmp(s, names[i].n) == 0) {
            *key = names[i].k;
            return true;
        }
    if (strlen(s) == 1 && s[0] > 32 && s[0] < 127) {
        *key = s[0];
        return true;
    }
    return false;
}

/* One line into *c; false with err on a bad command. */
static bool parse_line(const char *path, int line_no, char *line, script_cmd *c, bool *empty, mr_error *err) {
    /* '#' starts a comment, except in typed text (where it names a label). */
    char first_op[8] = "";
    double t0;
    bool is_text = sscanf(line, "%lf %7s", &t0, first_op) == 2 && strcmp(first_op, "text") == 0;
    char *hash = is_text ? NULL : strchr(line, '#');
    if (hash) *hash = 0;
    memset(c, 0, sizeof *c);
    char op[32] = "", arg[4][1000];
    memset(arg, 0, sizeof arg);
    int n = sscanf(line, "%lf %31s %999s %999s %999s %999s", &c->t, op, arg[0], arg[1], arg[2], arg[3]);
    *empty = n <= 0;
    if (n <= 0) return true;
    if (n < 2) return mr_fail(err, MR_ERR_PARSE, "%s:%d: expected `TIME COMMAND ...`", path, line_no);
    int na = n - 2;
    bool target = na >= 1 && arg[0][0] == '@';
    if (target) snprintf(c->target, sizeof c->target, "%.23s", arg[0] + 1);
    int first = target ? 1 : 0;
    double v[2] = {0, 0};
    for (int i = first; i < na && i - first < 2; i++) v[i - first] = atof(arg[i]);
    c->a = v[0];
    c->b = v[1];
    bool ok;
    if (!strcmp(op, "tap")) c->op = S_TAP, ok = target || na >= 2;
    else if (!strcmp(op, "down")) c->op = S_DOWN, ok = target || na >= 2;
    else if (!strcmp(op, "up")) c->op = S_UP, ok = target || na >= 2;
    else if (!strcmp(op, "move")) c->op = S_MOVE, ok = target || na >= 2;
    else if (!strcmp(op, "drag")) c->op = S_DRAG, ok = target && na >= 3;
    else if (!strcmp(op, "key")) c->op = S_KEY, ok = na >= 1 && mr_view_key_parse(arg[0], &c->key);
    else if (!strcmp(op, "resize")) c->op = S_RESIZE, ok = na >= 2 && c->a > 0 && c->b > 0;
    else if (!strcmp(op, "shot")) c->op = S_SHOT, ok = na >= 1;
    else if (!strcmp(op, "state")) c->op = S_STATE, ok = na >= 1;
    else if (!strcmp(op, "quit")) c->op = S_QUIT, ok = true;
    else if (!strcmp(op, "frame")) c->op = S_FRAME, ok = na >= 1 && !target && c->a >= 0;
    else if (!strcmp(op, "seek")) c->op = S_SEEK, ok = na >= 1 && !target && c->a >= 0 && c->a < 1e15;
    else if (!strcmp(op, "text")) {
        /* The rest of the line after the command, as typed. */
        const char *w = strstr(line, "text") + 4;
        while (*w == ' ' || *w == '\t') w++;
        snprintf(c->path, sizeof c->path, "%s", w);
        size_t l = strlen(c->path);
        while (l > 0 && (c->path[l - 1] == '\r' || c->path[l - 1] == ' ')) c->path[--l] = 0;
        c->op = S_TEXT, ok = l > 0;
    }
    else ok = false;
    if ((c->op == S_SHOT || c->op == S_STATE) && na >= 1) snprintf(c->path, sizeof c->path, "%s", arg[0]);
    if (!ok) return mr_fail(err, MR_ERR_PARSE, "%s:%d: bad command '%s'", path, line_no, op);
    return true;
}

mr_view_script *mr_view_script_load(const char *path, mr_error *err) {
    size_t size = 0;
    char *text = mr_file_read(path, &size, 1 << 20, err);
    if (!text) return NULL;
    mr_view_script *sc = calloc(1, sizeof *sc);
    int cap = 0, line_no = 0;
    bool ok = sc != NULL || mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (char *line = text; ok && line && *line;) {
        char *nl = strchr(line, '\n');
        if (nl) *nl = 0;
        script_cmd c;
        bool empty;
        ok = parse_line(path, ++line_no, line, &c, &empty, err);
        line = nl ? nl + 1 : NULL;
        if (!ok || empty) continue;
        if (sc->count == cap) {
            cap = cap ? cap * 2 : 32;
            script_cmd *p = realloc(sc->cmds, (size_t)cap * sizeof *p);
            if (!p) {
                ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
                break;
            }
            sc->cmds = p;
        }
        sc->cmds[sc->count++] = c;
    }
    free(text);
    if (!ok) mr_view_script_destroy(&sc);
    return sc;
}

void mr_view_script_destroy(mr_view_script **s) {
    if (!s || !*s) return;
    free((*s)->cmds);
    free(*s);
    *s = NULL;
}

void mr_viewer_set_script(mr_viewer *v, mr_view_script **s) {
    mr_view_script_destroy(&v->script);
    v->script = *s;
    *s = NULL;
    v->script_next = 0;
    v->script_started = false;
    v->script_seek = -1;
}

static void push(mr_viewer *v, mr_event_type t, double x, double y) {
    mr_event e = {t, x, y, 0};
    mr_viewer_push_event(v, &e);
}

/* How long a command naming a widget waits for it to be shown. */
#define MR_VIEW_SCRIPT_WIDGET_WAIT_S 10.0
/* How long `frame N` waits for the picture to reach frame N: generous, as
 * a loaded machine may play a recording far slower than its rate. */
#define MR_VIEW_SCRIPT_FRAME_WAIT_S 60.0

void vw_script_tick(mr_viewer *v, bool busy, mr_view_actions *out) {
    if (!v->script || v->script_next >= v->script->count) return;
    if (!v->script_started) {
        /* Time starts with the first picture on screen, or after a while
         * without one (no camera), so slow starts do not shift the script. */
        if (!v->f.have_image && v->now - v->p.now < v->p.script_wait_s) return;
        v->script_started = true;
        v->script_t0 = v->now;
    }
    /* Times are earliest times: a command also waits until the input of
     * the one before has been taken and its effect drawn, so a slow machine
     * shifts the script but never reorders it. */
    if (mr_viewer_pending(v) > 0 || busy || v->frames < v->script_frame + 2) return;
    /* After `seek N`: wait until frame N itself is shown (a seek back is
     * not done while a later frame is still on screen). */
    if (v->script_seek >= 0) {
        bool there = v->f.have_frame && v->f.index == v->script_seek;
        if (!there && v->now - v->script_seek_t < MR_VIEW_SCRIPT_FRAME_WAIT_S) return;
        if (!there) mr_log(MR_LOG_WARN, "view: script: frame %lld not shown after a seek", (long long)v->script_seek);
        v->script_seek = -1;
    }
    const script_cmd *c = &v->script->cmds[v->script_next];
    if (c->t > v->now - v->script_t0) return;
    double x = c->a, y = c->b;
    mr_ui_rect r = mr_ui_rect_make((float)x, (float)y, 0, 0);
    int id = -1;
    /* `@picture U V`: fractions of the camera picture as shown (wherever
     * the layout put it), so a script can tap a point of the image. */
    bool picture = strcmp(c->target, "picture") == 0;
    if (picture && !v->f.have_image && v->now - v->script_t0 - c->t < MR_VIEW_SCRIPT_WIDGET_WAIT_S) return;
    if (c->target[0] && !picture) {
        for (int i = 0; i < MR_VW_COUNT; i++)
            if (v->lay.shown[i] && strcmp(mr_view_widget_name((mr_view_widget_id)i), c->target) == 0) id = i;
        /* A widget that an earlier command brings up (the note chooser
         * after a tap in mark mode) may take a few frames on a slow
         * machine: wait for it, for a while. */
        if (id < 0 && v->now - v->script_t0 - c->t < MR_VIEW_SCRIPT_WIDGET_WAIT_S) return;
    }
    /* `frame N`: the commands after it wait until frame N (or later) is
     * shown, so a test of play does not depend on how fast the machine is. */
    bool frame_reached = v->f.have_frame && v->f.index >= (int64_t)c->a;
    if (c->op == S_FRAME && !frame_reached && v->now - v->script_t0 - c->t < MR_VIEW_SCRIPT_FRAME_WAIT_S) return;
    v->script_next++;
    v->script_frame = v->frames;
    if (picture) {
        r = v->f.image_rect;
        x = r.x + r.w * c->a;
        y = r.y + r.h * c->b;
    } else if (c->target[0]) {
        if (id < 0) {
            mr_log(MR_LOG_WARN, "view: script: no widget named @%s on screen", c->target);
            return;
        }
        r = v->lay.rect[id];
        x = r.x + r.w * 0.5;
        y = r.y + r.h * 0.5;
    }
    switch (c->op) {
    case S_TAP:
        push(v, MR_EVENT_POINTER_MOVE, x, y);
        push(v, MR_EVENT_POINTER_DOWN, x, y);
        push(v, MR_EVENT_POINTER_UP, x, y);
        break;
    case S_DOWN:
        push(v, MR_EVENT_POINTER_MOVE, x, y);
        push(v, MR_EVENT_POINTER_DOWN, x, y);
        break;
    case S_UP: push(v, MR_EVENT_POINTER_UP, x, y); break;
    case S_MOVE: push(v, MR_EVENT_POINTER_MOVE, x, y); break;
    case S_DRAG: {
        double x0 = r.x + r.w * c->a, x1 = r.x + r.w * c->b;
        push(v, MR_EVENT_POINTER_MOVE, x0, y);
        push(v, MR_EVENT_POINTER_DOWN, x0, y);
        for (int i = 1; i <= 8; i++) push(v, MR_EVENT_POINTER_MOVE, x0 + (x1 - x0) * i / 8.0, y);
        push(v, MR_EVENT_POINTER_UP, x1, y);
        break;
    }
    case S_KEY: {
        mr_event e = {MR_EVENT_KEY, v->input.x, v->input.y, c->key};
        mr_viewer_push_event(v, &e);
        break;
    }
    case S_TEXT:
        for (const char *ch = c->path; *ch; ch++) {
            mr_event e = {MR_EVENT_KEY, v->input.x, v->input.y, (unsigned char)*ch};
            mr_viewer_push_event(v, &e);
        }
        break;
    case S_RESIZE: {
        mr_view_action *a = vw_emit(out, MR_VA_RESIZE);
        a->x = c->a;
        a->y = c->b;
        break;
    }
    case S_SHOT: vw_emit(out, MR_VA_SHOT)->path = c->path; break;
    case S_STATE: vw_emit(out, MR_VA_STATE)->path = c->path; break;
    case S_QUIT: vw_emit(out, MR_VA_QUIT); break;
    case S_SEEK:
        vw_emit(out, MR_VA_SEEK)->i = (int64_t)c->a;
        v->script_seek = (int64_t)c->a;
        v->script_seek_t = v->now;
        break;
    case S_FRAME:
        if (!frame_reached) mr_log(MR_LOG_WARN, "view: script: frame %.0f not shown in %.0f s", c->a, MR_VIEW_SCRIPT_FRAME_WAIT_S);
        break;
    }
}
