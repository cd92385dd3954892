/* Private to lib/view: the controller's state, shared by controller.c and
 * script.c. */
#ifndef MR_VIEW_INTERNAL_H
#define MR_VIEW_INTERNAL_H

#include "mr_view.h"

typedef enum script_op { S_TAP, S_DOWN, S_UP, S_MOVE, S_DRAG, S_KEY, S_RESIZE, S_SHOT, S_STATE, S_QUIT } script_op;

typedef struct script_cmd {
    double t;
    script_op op;
    char target[24];     /* widget name (`@name`), or "" for coordinates */
    double a, b;
    int key;
    char path[1024];
} script_cmd;

struct mr_view_script {
    script_cmd *cmds;
    int count;
};

struct mr_viewer {
    mr_viewer_params p;
    char config_path[4096];
    mr_ui_font *font;
    mr_ui *ui;
    /* settings */
    mr_view_settings s;
    bool dirty;
    double last_save;
    /* modes */
    bool frozen, mark_mode, help, note_open;
    float mark_u, mark_v;        /* the mark, as fractions of the picture */
    char toast[300];
    double toast_until;
    double now;
    /* input: queued events, the pointer as the UI sees it */
    mr_event *queue;
    int qhead, qcount, qcap;
    mr_ui_input input;
    /* what the last frame showed */
    mr_viewer_frame f;           /* pointers cleared; strings copied below */
    char passes[256];
    char status[512];            /* the status line as last drawn */
    bool sigma_known;            /* "± N mm here" of the last frame */
    double sigma_m;
    mr_view_layout lay;
    int64_t frames;              /* mr_viewer_ui calls */
    /* script */
    mr_view_script *script;
    int script_next;
    double script_t0;
    int64_t script_frame;
    bool script_started;
};

mr_view_action *vw_emit(mr_view_actions *out, mr_view_action_type t);
/* Runs the script commands that are due (before the queued input is taken). */
void vw_script_tick(mr_viewer *v, bool busy, mr_view_actions *out);

#endif
