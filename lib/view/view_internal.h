/* Private to lib/view: the controller's state, shared by controller.c and
 * script.c. */
#ifndef MR_VIEW_INTERNAL_H
#define MR_VIEW_INTERNAL_H

#include "mr_view.h"
#include "mr_track.h"

typedef enum script_op { S_TAP, S_DOWN, S_UP, S_MOVE, S_DRAG, S_KEY, S_RESIZE, S_SHOT, S_STATE, S_QUIT, S_FRAME, S_TEXT, S_SEEK } script_op;

typedef struct script_cmd {
    double t;
    script_op op;
    char target[24];     /* widget name (`@name`), or "" for coordinates */
    double a, b;
    int key;
    char path[1024];     /* shot, state: the file; text: the words */
} script_cmd;

/* A saved mark's pin and where it is on screen this frame. */
typedef struct vw_pin {
    mr_view_pin p;
    bool shown;
    float x, y;          /* window px */
} vw_pin;

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
    char status[600];            /* the status line as last drawn */
    bool sigma_known;            /* "± N mm here" of the last frame */
    double sigma_m;
    mr_view_layout lay;
    int64_t frames;              /* mr_viewer_ui calls */
    /* script */
    mr_view_script *script;
    int script_next;
    double script_t0;
    int64_t script_frame;
    int64_t script_seek;         /* `seek N`: what follows waits until frame N is shown; -1 none */
    double script_seek_t;
    bool script_started;
    /* Measure (measure.c) */
    bool measure_mode;           /* collecting taps */
    bool measure_have;           /* a measurement exists (being made or finished) */
    bool measure_solved;         /* its taps triangulate */
    mr_measurement measure;
    mr_dmat4 measure_pose[MR_MEASURE_MAX_TAPS];
    double measure_cov[MR_MEASURE_MAX_TAPS][36];
    bool measure_has_cov[MR_MEASURE_MAX_TAPS];
    char measure_msg[200];       /* its last message (also toasted) */
    bool measure_judged;         /* its distance has a verdict */
    mr_verdict measure_verdict;
    /* The verdict's banner: over the picture while the mark is filed and a
     * while after, in the verdict's colour */
    char verdict_banner[300];
    mr_verdict_kind verdict_kind;
    double verdict_until;
    bool verdict_note;           /* the note chooser open is the measurement's mark */
    /* the note chooser: the text field, and the mark it edits */
    char note_text[512];
    bool text_focus;             /* keys go into the field */
    int edit_pin;                /* -1: a new mark */
    /* "Quit?" */
    bool quit_open;
    /* the settings that differ from the defaults, told at start */
    char notice[400];
    double notice_until;
    bool notice_done;
    /* saved marks */
    vw_pin *pins;
    int pin_count, pin_cap;
};

mr_view_action *vw_emit(mr_view_actions *out, mr_view_action_type t);
/* Runs the script commands that are due (before the queued input is taken). */
void vw_script_tick(mr_viewer *v, bool busy, mr_view_actions *out);
/* Measure (measure.c): the button / key (start, finish or cancel),
 * Esc, a tap on the picture, the banner text, the tap's cross, the state
 * snapshot's part. */
void vw_measure_toggle(mr_viewer *v, mr_view_actions *out);
void vw_measure_cancel(mr_viewer *v);
void vw_measure_tap(mr_viewer *v, const mr_viewer_frame *f, float x, float y);
void vw_measure_banner(const mr_viewer *v, char *buf, size_t n);
void vw_measure_draw(mr_viewer *v, const mr_viewer_frame *f); /* a cross at this frame's tap */
void vw_measure_state_json(const mr_viewer *v, cJSON *j);
/* The verdict in the planner's words, for the banner: "OUT OF TOLERANCE
 * Machine_2: 298 mm, 95 % 224..372 mm, limit +/-20 mm (DIN 18202 ...)". */
void vw_verdict_words(const mr_verdict *vd, const char *part, char *buf, size_t n);

#endif
