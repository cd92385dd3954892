/* The study window's controller for all three designs: fixation cross;
 * the pair (and the reference above it in block II), one image rated on
 * each scale in turn, or one image with a task question (two answers, or
 * a tap on the image and a confirm); touch-sized answers, one vote out per
 * trial, the scripted input of tests. No GL and no files besides the
 * script: the caller draws and stores. */
#include "mr_study.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ---------------------------------------------------------------- script */

typedef enum sop { S_TAP, S_TAP_XY, S_DRAG, S_KEY, S_SHOT, S_STATE, S_QUIT } sop;

typedef struct scmd {
    double t;
    sop op;
    char target[16];
    double a, b;
    int key;
    char path[1024];
} scmd;

struct mr_study_script {
    scmd *c;
    int n;
};

typedef enum widget {
    W_LEFT = 0, W_NEUTRAL, W_RIGHT, W_SLIDER, W_VOTE,
    W_R1, W_R2, W_R3, W_R4, W_R5, W_R6, W_R7, W_RX, /* rating: 1..7 and X */
    W_CHOICE0, W_CHOICE1, W_IMAGE, W_CONFIRM,       /* task */
    W_CONTINUE,                                     /* the break between blocks */
    W_PICK1, W_PICK2, W_PICK3, W_PICK4,             /* rating: the overall question */
    W_COUNT
} widget;
static const char *const k_widget_names[W_COUNT] = {"left", "neutral", "right", "slider", "vote", "r1", "r2", "r3",
                                                    "r4", "r5", "r6", "r7", "rx", "a", "b", "image", "confirm",
                                                    "continue", "p1", "p2", "p3", "p4"};

static bool key_parse(const char *s, int *key) {
    static const struct { const char *n; int k; } names[] = {
        {"left", MR_KEY_LEFT}, {"right", MR_KEY_RIGHT}, {"down", MR_KEY_DOWN}, {"space", ' '},
        {"enter", MR_KEY_ENTER}, {"esc", MR_KEY_ESCAPE},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(s, names[i].n)) return *key = names[i].k, true;
    if (strlen(s) == 1 && s[0] > 32 && s[0] < 127) return *key = s[0], true;
    return false;
}

mr_study_script *mr_study_script_load(const char *path, mr_error *err) {
    size_t size = 0;
    char *text = mr_file_read(path, &size, 1 << 20, err);
    if (!text) return NULL;
    mr_study_script *sc = calloc(1, sizeof *sc);
    int cap = 0, line_no = 0;
    bool ok = sc != NULL || mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (char *line = text; ok && line && *line;) {
        char *nl = strchr(line, '\n');
        if (nl) *nl = 0;
        line_no++;
        char *hash = strchr(line, '#');
        if (hash) *hash = 0;
        scmd c;
        memset(&c, 0, sizeof c);
        char op[32] = "", a0[1000] = "", a1[64] = "", a2[64] = "";
        int n = sscanf(line, "%lf %31s %999s %63s %63s", &c.t, op, a0, a1, a2);
        line = nl ? nl + 1 : NULL;
        if (n <= 0) continue;
        bool good = n >= 2 && c.t >= 0;
        bool target = a0[0] == '@';
        if (target) {
            snprintf(c.target, sizeof c.target, "%.15s", a0 + 1);
            bool known = false;
            for (int w = 0; w < W_COUNT; w++) known |= !strcmp(c.target, k_widget_names[w]);
            good = good && known;
        }
        if (!strcmp(op, "tap") && target && n >= 4) c.op = S_TAP, c.a = atof(a1), c.b = atof(a2), c.key = 1;
        else if (!strcmp(op, "tap") && target) c.op = S_TAP;
        else if (!strcmp(op, "tap") && n >= 4) c.op = S_TAP_XY, c.a = atof(a0), c.b = atof(a1);
        else if (!strcmp(op, "drag") && target && n >= 5) c.op = S_DRAG, c.a = atof(a1), c.b = atof(a2);
        else if (!strcmp(op, "key") && n >= 3 && key_parse(a0, &c.key)) c.op = S_KEY;
        else if (!strcmp(op, "shot") && n >= 3) c.op = S_SHOT;
        else if (!strcmp(op, "state") && n >= 3) c.op = S_STATE;
        else if (!strcmp(op, "quit")) c.op = S_QUIT;
        else good = false;
        if (c.op == S_SHOT || c.op == S_STATE) snprintf(c.path, sizeof c.path, "%s", a0);
        if (!good) {
            ok = mr_fail(err, MR_ERR_PARSE, "%s:%d: bad command '%s'", path, line_no, op);
            break;
        }
        if (sc->n == cap) {
            cap = cap ? cap * 2 : 32;
            void *p = realloc(sc->c, (size_t)cap * sizeof *sc->c);
            if (!p) {
                ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
                break;
            }
            sc->c = p;
        }
        sc->c[sc->n++] = c;
    }
    free(text);
    if (!ok) mr_study_script_destroy(&sc);
    return sc;
}

void mr_study_script_destroy(mr_study_script **s) {
    if (!s || !*s) return;
    free((*s)->c);
    free(*s);
    *s = NULL;
}

/* ---------------------------------------------------------------- runner */

#define MAX_EVENTS 256

struct mr_study_runner {
    mr_study_run_params p;
    bool *answered;           /* our copy, updated per vote */
    mr_ui_font *font;
    mr_ui *ui;
    int trial;                /* current trial, trial_count when done */
    bool fixation;
    double phase_t0;          /* when the fixation / the pair started */
    double now, t_start;
    float slider;
    int scale;                /* rating: the scale asked now */
    int ratings[MR_STUDY_MAX_SCALES];
    bool tapped;              /* task: a tap on the image, in image pixels */
    double tap_x, tap_y;
    int shown_block;          /* the block of the trial shown last (0: none yet) */
    bool in_break;            /* the break screen before a new block is up */
    int answered_here;
    int last_voted;           /* the trial of the last vote handed out, -1 */
    char msg[256];
    /* input */
    mr_event q[MAX_EVENTS];
    int qn;
    mr_ui_input in;
    bool quit;
    /* layout of the last frame */
    bool shown[W_COUNT];
    mr_ui_rect rect[W_COUNT];
    int image_count;
    /* script */
    mr_study_script *script;
    int script_next;
    int64_t frames, script_frame;
    char shot[1024], state[1024];
};

static int next_unanswered(const mr_study_runner *r, int from) {
    for (int k = from; k < r->p.plan->trial_count; k++)
        if (!r->answered[k]) return k;
    return r->p.plan->trial_count;
}

mr_study_runner *mr_study_runner_create(const mr_study_run_params *p, mr_error *err) {
    if (!p || !p->plan || !p->participant) {
        mr_fail(err, MR_ERR_INVALID, "study run: needs a plan and a participant");
        return NULL;
    }
    mr_study_runner *r = calloc(1, sizeof *r);
    if (!r || !(r->answered = calloc((size_t)p->plan->trial_count + 1, sizeof *r->answered))) {
        free(r);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    r->p = *p;
    if (p->answered) memcpy(r->answered, p->answered, (size_t)p->plan->trial_count * sizeof *r->answered);
    mr_ui_font_params fp = MR_UI_FONT_DEFAULTS;
    fp.path = p->font_path;
    fp.pixel_height = 28;
    r->font = mr_ui_font_create(&fp, err);
    mr_ui_params up = MR_UI_DEFAULTS;
    up.font = r->font;
    up.px_per_mm = p->px_per_mm;
    up.min_target_mm = 12.0f; /* bigger than the view's 9 mm: answering is all there is to do */
    up.text_mm = 4.5f;
    if (!r->font || !(r->ui = mr_ui_create(&up, err))) {
        mr_study_runner_destroy(&r);
        return NULL;
    }
    r->trial = next_unanswered(r, p->first_trial > 0 ? p->first_trial : 0);
    /* Resumed right at a new block: its break screen comes first. */
    if (r->trial > 0 && r->trial < p->plan->trial_count && r->answered[r->trial - 1])
        r->shown_block = p->plan->trials[r->trial - 1].block;
    r->fixation = true;
    r->last_voted = -1;
    r->now = r->t_start = r->phase_t0 = p->now;
    return r;
}

void mr_study_runner_destroy(mr_study_runner **rp) {
    if (!rp || !*rp) return;
    mr_study_runner *r = *rp;
    mr_ui_destroy(&r->ui);
    mr_ui_font_destroy(&r->font);
    mr_study_script_destroy(&r->script);
    free(r->answered);
    free(r);
    *rp = NULL;
}

void mr_study_runner_set_script(mr_study_runner *r, mr_study_script **s) {
    mr_study_script_destroy(&r->script);
    r->script = *s;
    *s = NULL;
    r->script_next = 0;
}

void mr_study_runner_push_event(mr_study_runner *r, const mr_event *e) {
    if (r->qn < MAX_EVENTS) r->q[r->qn++] = *e;
}

int mr_study_runner_answered(const mr_study_runner *r) { return r->answered_here; }

bool mr_study_runner_wants_input(const mr_study_runner *r) {
    return r->qn > 0 || r->in.down || (r->script && r->script_next < r->script->n) || r->fixation;
}

void mr_study_runner_vote_failed(mr_study_runner *r, const char *msg) {
    /* Back to that trial: the answer was not stored, so it is asked again. */
    if (r->last_voted >= 0) {
        r->answered[r->last_voted] = false;
        r->answered_here--;
        r->trial = r->last_voted;
        r->fixation = false;
        r->phase_t0 = r->now;
        r->last_voted = -1;
        r->scale = 0;
        r->tapped = false;
    }
    snprintf(r->msg, sizeof r->msg, "vote NOT saved: %.200s - please answer again", msg);
}

static bool done(const mr_study_runner *r) { return r->trial >= r->p.plan->trial_count; }

static void push(mr_study_runner *r, mr_event_type t, double x, double y) {
    mr_event e = {t, x, y, 0};
    mr_study_runner_push_event(r, &e);
}

/* Runs the script command that is due: after its time, once the previous
 * one's input was taken and drawn, and (except quit) with the pair on
 * screen. */
static void script_tick(mr_study_runner *r) {
    if (!r->script || r->script_next >= r->script->n) return;
    const scmd *c = &r->script->c[r->script_next];
    if (r->qn > 0 || r->frames < r->script_frame + 2 || c->t > r->now - r->t_start) return;
    if (c->op != S_QUIT && r->fixation && !done(r) && !r->in_break) return;
    double x = c->a, y = c->b;
    if (c->op == S_TAP || c->op == S_DRAG) {
        int w = -1;
        for (int i = 0; i < W_COUNT; i++)
            if (!strcmp(c->target, k_widget_names[i])) w = i;
        if (w < 0 || !r->shown[w]) return; /* wait for it (e.g. the next pair) */
        mr_ui_rect rc = r->rect[w];
        x = rc.x + rc.w * (c->op == S_TAP && c->key ? c->a : 0.5);
        y = rc.y + rc.h * (c->op == S_TAP && c->key ? c->b : 0.5);
        if (c->op == S_DRAG) {
            double x0 = rc.x + rc.w * c->a, x1 = rc.x + rc.w * c->b;
            push(r, MR_EVENT_POINTER_MOVE, x0, y);
            push(r, MR_EVENT_POINTER_DOWN, x0, y);
            for (int i = 1; i <= 8; i++) push(r, MR_EVENT_POINTER_MOVE, x0 + (x1 - x0) * i / 8.0, y);
            push(r, MR_EVENT_POINTER_UP, x1, y);
        }
    }
    r->script_next++;
    r->script_frame = r->frames;
    switch (c->op) {
    case S_TAP:
    case S_TAP_XY:
        push(r, MR_EVENT_POINTER_MOVE, x, y);
        push(r, MR_EVENT_POINTER_DOWN, x, y);
        push(r, MR_EVENT_POINTER_UP, x, y);
        break;
    case S_DRAG: break;
    case S_KEY: {
        mr_event e = {MR_EVENT_KEY, r->in.x, r->in.y, c->key};
        mr_study_runner_push_event(r, &e);
        break;
    }
    case S_SHOT: snprintf(r->shot, sizeof r->shot, "%s", c->path); break;
    case S_STATE: snprintf(r->state, sizeof r->state, "%s", c->path); break;
    case S_QUIT: r->quit = true; break;
    }
}

/* Takes queued input: moves and keys at once, at most one press or
 * release per frame (so a quick tap spans two frames and is never lost).
 * Returns a key answer, or 0. */
static int take_input(mr_study_runner *r) {
    int key = 0, i = 0;
    bool button = false;
    for (; i < r->qn; i++) {
        const mr_event *e = &r->q[i];
        if (e->type == MR_EVENT_POINTER_MOVE) r->in.x = (float)e->x, r->in.y = (float)e->y, r->in.inside = true;
        else if (e->type == MR_EVENT_POINTER_LEAVE) r->in.inside = false;
        else if (e->type == MR_EVENT_KEY) {
            if (e->key == MR_KEY_ESCAPE) r->quit = true;
            else if (!key) key = e->key;
        } else if (e->type == MR_EVENT_POINTER_DOWN || e->type == MR_EVENT_POINTER_UP) {
            if (button) break;
            r->in.x = (float)e->x, r->in.y = (float)e->y, r->in.inside = true;
            r->in.down = e->type == MR_EVENT_POINTER_DOWN;
            button = true;
        }
    }
    memmove(r->q, r->q + i, (size_t)(r->qn - i) * sizeof *r->q);
    r->qn -= i;
    return key;
}

static const char *question(const mr_study_plan *plan, const mr_study_trial *t) {
    if (plan->design == MR_STUDY_RATING && t->left < 0)
        return "Which representation supports your perception of depth best as a whole?";
    if (plan->design == MR_STUDY_RATING) return "How well can you perceive this depth cue in the whole scene?";
    if (plan->design == MR_STUDY_TASK) {
        const mr_study_key *k = mr_study_plan_key(plan, t->block, t->stimulus);
        return k ? k->text : "";
    }
    return !strcmp(mr_study_question_of(t->block, plan->group), "plausible")
               ? t->block == 2 ? "Which image is physically more plausible? (top: the correct simulation)"
                               : "Which image is physically more plausible?"
               : "Which image looks better?";
}

/* What the block about to start asks (shown on its break screen). */
static void block_instruction(const mr_study_plan *plan, int block, char *out, size_t n) {
    if (plan->design == MR_STUDY_PAIRWISE)
        snprintf(out, n, "Block %s: %s", mr_study_block_name(block),
                 block == 2 ? "the top image is the physically correct simulation; which image below is "
                              "physically more plausible?"
                 : !strcmp(mr_study_question_of(block, plan->group), "plausible")
                     ? "which image is physically more plausible?"
                     : "which image looks better?");
    else if (plan->design == MR_STUDY_RATING)
        snprintf(out, n, "Part %s: the scenes %s", mr_study_block_name(block),
                 block == 2 ? "over the camera image (50 %)" : "alone");
    else snprintf(out, n, "Part %s: new scenes, the same kind of questions", mr_study_block_name(block));
}

/* A scale's name for people: underscores as spaces, the first letter up. */
static void scale_label(const char *name, char *out, size_t n) {
    snprintf(out, n, "%s", name);
    for (char *c = out; *c; c++)
        if (*c == '_') *c = ' ';
    if (out[0] >= 'a' && out[0] <= 'z') out[0] = (char)(out[0] - 'a' + 'A');
}

/* The answer widgets of a rating trial: 1..7 and X for the current scale.
 * Returns the rating given (1..7, MR_STUDY_RATING_X) or -1. */
static int rating_row(mr_study_runner *r, mr_ui_rect bottom, float pad, int key) {
    float bw = bottom.w / 8;
    int got = -1;
    for (int k = 0; k < 8; k++) {
        mr_ui_rect b = mr_ui_rect_inset(mr_ui_rect_make(bottom.x + k * bw, bottom.y, bw, bottom.h), pad / 2);
        int w = W_R1 + k;
        r->shown[w] = true;
        r->rect[w] = b;
        char label[8];
        snprintf(label, sizeof label, k < 7 ? "%d" : "X", k + 1);
        if (mr_ui_button(r->ui, (uint32_t)(20 + k), b, label, k < 7 ? MR_UI_ACCENT : MR_UI_NORMAL))
            got = k < 7 ? k + 1 : MR_STUDY_RATING_X;
    }
    if (key >= '1' && key <= '7') got = key - '0';
    else if (key == 'x' || key == 'X') got = MR_STUDY_RATING_X;
    return got;
}

const mr_ui_draw_list *mr_study_runner_frame(mr_study_runner *r, double now, float fb_w, float fb_h,
                                             mr_study_frame *out, mr_study_vote *vote_out) {
    memset(out, 0, sizeof *out);
    r->now = now;
    r->frames++;
    script_tick(r);
    int key = take_input(r);
    const mr_study_plan *plan = r->p.plan;
    /* Between blocks a break (the thesis's recreational breaks) with the
     * next block's instruction; the fixation starts after Continue. */
    r->in_break = !done(r) && r->fixation && r->shown_block && plan->trials[r->trial].block != r->shown_block;
    if (r->in_break) r->phase_t0 = now;
    if (!done(r) && !r->in_break && r->fixation && (now - r->phase_t0) * 1000.0 >= plan->fixation_ms) {
        r->fixation = false;
        r->phase_t0 = now;
        r->slider = 0;
    }
    mr_ui_begin(r->ui, &r->in);
    mr_ui_draw_list *dl = mr_ui_list(r->ui);
    memset(r->shown, 0, sizeof r->shown);
    r->image_count = 0;
    out->trial = -1;
    out->done = done(r);
    out->fixation = r->fixation && !out->done && !r->in_break;
    mr_ui_rect screen = mr_ui_rect_make(0, 0, fb_w, fb_h);
    float pad = mr_ui_mm(r->ui, 4), target = mr_ui_target_px(r->ui);
    int answer = MR_STUDY_NEUTRAL; /* pairwise: an mr_study_answer; task: the choice */
    bool answered = false;
    double slider_value = 0;
    if (out->done) {
        mr_ui_label(r->ui, screen, "All trials answered. Thank you!", MR_UI_RGBA(255, 255, 255, 255), true);
    } else if (r->in_break) {
        mr_ui_rect area = mr_ui_rect_inset(screen, pad);
        mr_ui_rect b = mr_ui_cut_bottom(&area, target * 1.2f + pad);
        b = mr_ui_fit(b, 4, 1);
        char text[200];
        block_instruction(plan, plan->trials[r->trial].block, text, sizeof text);
        mr_ui_label(r->ui, mr_ui_cut_top(&area, area.h * 0.5f), text, MR_UI_RGBA(255, 255, 255, 255), true);
        mr_ui_label(r->ui, area, "Take a short break. Continue when you are ready.", MR_UI_RGBA(220, 220, 220, 255), true);
        r->shown[W_CONTINUE] = true;
        r->rect[W_CONTINUE] = b;
        if (mr_ui_button(r->ui, 50, b, "Continue", MR_UI_ACCENT) || key == MR_KEY_ENTER || key == ' ') {
            r->shown_block = plan->trials[r->trial].block;
            r->in_break = false;
            r->phase_t0 = now;
        }
    } else if (out->fixation) {
        /* A black fixation cross on white (thesis sec. 4.3). */
        mr_ui_draw_rect(dl, screen, MR_UI_RGBA(255, 255, 255, 255));
        float arm = mr_ui_mm(r->ui, 10), th = mr_ui_mm(r->ui, 1.2f);
        mr_ui_draw_rect(dl, mr_ui_rect_make(fb_w / 2 - arm, fb_h / 2 - th / 2, 2 * arm, th), MR_UI_RGBA(0, 0, 0, 255));
        mr_ui_draw_rect(dl, mr_ui_rect_make(fb_w / 2 - th / 2, fb_h / 2 - arm, th, 2 * arm), MR_UI_RGBA(0, 0, 0, 255));
    } else {
        const mr_study_trial *t = &plan->trials[r->trial];
        out->trial = r->trial;
        r->shown_block = t->block;
        mr_ui_rect area = mr_ui_rect_inset(screen, pad);
        char status[200];
        if (plan->design == MR_STUDY_PAIRWISE)
            snprintf(status, sizeof status, "Block %s  -  trial %d of %d", mr_study_block_name(t->block), r->trial + 1,
                     plan->trial_count);
        else
            snprintf(status, sizeof status, "Part %s  -  trial %d of %d", mr_study_block_name(t->block), r->trial + 1,
                     plan->trial_count);
        mr_ui_rect top = mr_ui_cut_top(&area, mr_ui_text_px(r->ui) * 1.6f);
        mr_ui_label(r->ui, top, status, MR_UI_RGBA(255, 255, 255, 255), false);
        mr_ui_rect q = mr_ui_cut_top(&area, mr_ui_text_px(r->ui) * 1.6f);
        mr_ui_label(r->ui, q, r->msg[0] ? r->msg : question(plan, t),
                    r->msg[0] ? MR_UI_RGBA(255, 200, 80, 255) : MR_UI_RGBA(255, 255, 255, 255), true);
        /* Buttons at least the touch target after their half-pad inset. */
        mr_ui_rect bottom = mr_ui_cut_bottom(&area, target * 1.2f + 1.5f * pad);
        bottom.h -= pad;
        bottom.y += pad;
        double iw = r->p.image_w > 0 ? r->p.image_w : 4, ih = r->p.image_h > 0 ? r->p.image_h : 3;
        if (plan->design == MR_STUDY_PAIRWISE) {
            if (t->block == 2 && plan->set.reference >= 0) {
                mr_ui_rect ref = mr_ui_cut_top(&area, area.h * 0.5f);
                out->image_rect[r->image_count] = mr_ui_fit(mr_ui_rect_inset(ref, pad / 2), iw, ih);
                out->image_method[r->image_count++] = plan->set.reference;
            }
            mr_ui_rect lh = mr_ui_cut_left(&area, area.w * 0.5f), rh = area;
            out->image_rect[r->image_count] = mr_ui_fit(mr_ui_rect_inset(lh, pad / 2), iw, ih);
            out->image_method[r->image_count++] = t->left;
            out->image_rect[r->image_count] = mr_ui_fit(mr_ui_rect_inset(rh, pad / 2), iw, ih);
            out->image_method[r->image_count++] = t->right;
        } else if (t->left < 0) {
            /* The overall question: every method side by side, position i
             * showing method (r + i) mod t, a button under each. */
            int n = plan->set.method_count;
            float w = area.w / n;
            for (int i = 0; i < n; i++) {
                mr_ui_rect cell = mr_ui_rect_inset(mr_ui_rect_make(area.x + i * w, area.y, w, area.h), pad / 2);
                out->image_rect[r->image_count] = mr_ui_fit(cell, iw, ih);
                out->image_method[r->image_count++] = (t->right + i) % n;
                mr_ui_rect b = mr_ui_rect_inset(mr_ui_rect_make(bottom.x + i * w, bottom.y, w, bottom.h), pad / 2);
                r->shown[W_PICK1 + i] = true;
                r->rect[W_PICK1 + i] = b;
                static const char *const labels[MR_STUDY_OVERALL_MAX] = {"This one (1)", "This one (2)", "This one (3)",
                                                                         "This one (4)"};
                if (mr_ui_button(r->ui, (uint32_t)(60 + i), b, labels[i], MR_UI_ACCENT) || key == '1' + i)
                    answered = true, answer = (t->right + i) % n;
            }
        } else {
            if (plan->design == MR_STUDY_RATING) {
                /* The scale asked now, above its buttons. */
                mr_ui_rect sl = mr_ui_cut_bottom(&area, mr_ui_text_px(r->ui) * 1.8f);
                char name[MR_STUDY_NAME_MAX], text[160];
                scale_label(plan->scales[r->scale], name, sizeof name);
                snprintf(text, sizeof text, "%s  (%d of %d)   1 = poorly ... 7 = very well, X = cannot say", name,
                         r->scale + 1, plan->scale_count);
                mr_ui_label(r->ui, sl, text, MR_UI_RGBA(255, 255, 255, 255), true);
            }
            mr_ui_rect ir = mr_ui_fit(mr_ui_rect_inset(area, pad / 2), iw, ih);
            out->image_rect[r->image_count] = ir;
            out->image_method[r->image_count++] = t->left;
            r->shown[W_IMAGE] = true;
            r->rect[W_IMAGE] = ir;
        }
        if (plan->design == MR_STUDY_RATING && t->left < 0) {
            /* answered above */
        } else if (plan->design == MR_STUDY_RATING) {
            int got = rating_row(r, bottom, pad, key);
            if (got >= 0) {
                r->ratings[r->scale++] = got;
                if (r->scale >= plan->scale_count) answered = true;
            }
        } else if (plan->design == MR_STUDY_TASK) {
            const mr_study_key *k = mr_study_plan_key(plan, t->block, t->stimulus);
            if (k && k->question == MR_STUDY_Q_CHOICE) {
                float bw = bottom.w / 2;
                for (int c = 0; c < 2; c++) {
                    mr_ui_rect b = mr_ui_rect_inset(mr_ui_rect_make(bottom.x + c * bw, bottom.y, bw, bottom.h), pad / 2);
                    char label[64];
                    snprintf(label, sizeof label, "%s is nearer", k->labels[c]);
                    r->shown[W_CHOICE0 + c] = true;
                    r->rect[W_CHOICE0 + c] = b;
                    if (mr_ui_button(r->ui, (uint32_t)(30 + c), b, label, MR_UI_ACCENT)) answered = true, answer = c;
                }
                if (key == MR_KEY_LEFT) answered = true, answer = 0;
                else if (key == MR_KEY_RIGHT) answered = true, answer = 1;
            } else {
                /* A press on the image places the mark (again to move it);
                 * Confirm stores it. */
                mr_ui_rect ir = r->rect[W_IMAGE];
                if (r->in.down && r->in.x >= ir.x && r->in.x < ir.x + ir.w && r->in.y >= ir.y && r->in.y < ir.y + ir.h) {
                    r->tapped = true;
                    r->tap_x = (r->in.x - ir.x) / ir.w * iw;
                    r->tap_y = (r->in.y - ir.y) / ir.h * ih;
                }
                if (r->tapped) {
                    float mx = ir.x + (float)(r->tap_x / iw) * ir.w, my = ir.y + (float)(r->tap_y / ih) * ir.h;
                    float arm = mr_ui_mm(r->ui, 4), th = mr_ui_mm(r->ui, 0.8f);
                    mr_ui_draw_rect(dl, mr_ui_rect_make(mx - arm, my - th / 2, 2 * arm, th), MR_UI_RGBA(255, 40, 40, 255));
                    mr_ui_draw_rect(dl, mr_ui_rect_make(mx - th / 2, my - arm, th, 2 * arm), MR_UI_RGBA(255, 40, 40, 255));
                }
                mr_ui_rect b = mr_ui_rect_inset(mr_ui_cut_right(&bottom, target * 3.0f), pad / 2);
                r->shown[W_CONFIRM] = true;
                r->rect[W_CONFIRM] = b;
                mr_ui_label(r->ui, bottom, r->tapped ? "Tap again to move the mark" : "Tap on the image",
                            MR_UI_RGBA(255, 255, 255, 255), true);
                if ((mr_ui_button(r->ui, 40, b, "Confirm", r->tapped ? MR_UI_ACCENT : MR_UI_NORMAL) ||
                     key == MR_KEY_ENTER) && r->tapped)
                    answered = true;
            }
        } else if (!r->p.slider) {
            float bw = bottom.w / 3;
            static const char *const labels[3] = {"Left is better", "No preference", "Right is better"};
            for (int w = 0; w < 3; w++) {
                mr_ui_rect b = mr_ui_rect_inset(mr_ui_rect_make(bottom.x + w * bw, bottom.y, bw, bottom.h), pad / 2);
                r->shown[w] = true;
                r->rect[w] = b;
                if (mr_ui_button(r->ui, (uint32_t)(w + 1), b, labels[w], w == 1 ? MR_UI_NORMAL : MR_UI_ACCENT))
                    answered = true, answer = (mr_study_answer)(w - 1);
            }
            if (key == MR_KEY_LEFT) answered = true, answer = MR_STUDY_LEFT;
            else if (key == MR_KEY_RIGHT) answered = true, answer = MR_STUDY_RIGHT;
            else if (key == MR_KEY_DOWN || key == ' ') answered = true, answer = MR_STUDY_NEUTRAL;
            slider_value = answer;
        } else {
            mr_ui_rect vote = mr_ui_cut_right(&bottom, target * 2.5f);
            mr_ui_rect sl = mr_ui_rect_inset(bottom, pad / 2);
            r->shown[W_SLIDER] = r->shown[W_VOTE] = true;
            r->rect[W_SLIDER] = sl;
            r->rect[W_VOTE] = mr_ui_rect_inset(vote, pad / 2);
            mr_ui_slider(r->ui, 10, sl, r->slider == 0 ? "no preference" : r->slider < 0 ? "left" : "right",
                         &r->slider, -1.0f, 1.0f);
            /* The centre snaps to "no preference". */
            if (r->slider > -MR_STUDY_SNAP && r->slider < MR_STUDY_SNAP) r->slider = 0;
            if (key == MR_KEY_LEFT) r->slider = r->slider - 0.25f < -1 ? -1 : r->slider - 0.25f;
            if (key == MR_KEY_RIGHT) r->slider = r->slider + 0.25f > 1 ? 1 : r->slider + 0.25f;
            if (mr_ui_button(r->ui, 11, r->rect[W_VOTE], "Vote", MR_UI_ACCENT) || key == MR_KEY_ENTER) {
                answered = true;
                slider_value = r->slider;
                answer = r->slider < 0 ? MR_STUDY_LEFT : r->slider > 0 ? MR_STUDY_RIGHT : MR_STUDY_NEUTRAL;
            }
        }
        if (answered) {
            mr_study_vote *v = vote_out;
            memset(v, 0, sizeof *v);
            snprintf(v->plan, sizeof v->plan, "%s", plan->id);
            snprintf(v->participant, sizeof v->participant, "%s", r->p.participant);
            v->block = t->block;
            v->trial = r->trial;
            snprintf(v->stimulus, sizeof v->stimulus, "%s", plan->set.stimuli[t->stimulus]);
            if (t->left >= 0) {
                snprintf(v->left, sizeof v->left, "%s", plan->set.methods[t->left]);
                snprintf(v->right, sizeof v->right, "%s", plan->set.methods[t->right]);
            }
            v->design = plan->design;
            v->choice = -1;
            if (plan->design == MR_STUDY_PAIRWISE) {
                v->group = plan->group;
                v->answer = answer;
                v->slider = slider_value;
            } else if (plan->design == MR_STUDY_RATING && t->left < 0) {
                v->choice = answer;
                snprintf(v->left, sizeof v->left, "*");
                snprintf(v->right, sizeof v->right, "%d", t->right);
            } else if (plan->design == MR_STUDY_RATING) {
                v->rating_count = plan->scale_count;
                memcpy(v->ratings, r->ratings, sizeof v->ratings);
            } else if (r->tapped) {
                v->has_tap = true;
                v->tap_x = r->tap_x;
                v->tap_y = r->tap_y;
            } else {
                v->choice = (int)answer;
            }
            v->ms = (now - r->phase_t0) * 1000.0;
            v->time_unix = (double)time(NULL);
            out->vote = true;
            r->answered[r->trial] = true;
            r->answered_here++;
            r->last_voted = r->trial;
            r->msg[0] = 0;
            r->trial = next_unanswered(r, r->trial + 1);
            r->fixation = true;
            r->scale = 0;
            r->tapped = false;
            r->phase_t0 = now;
        }
    }
    out->image_count = r->image_count;
    out->quit = r->quit;
    snprintf(out->shot_path, sizeof out->shot_path, "%s", r->shot);
    snprintf(out->state_path, sizeof out->state_path, "%s", r->state);
    r->shot[0] = r->state[0] = 0;
    return mr_ui_end(r->ui);
}

cJSON *mr_study_runner_state_json(const mr_study_runner *r) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "plan", r->p.plan->id);
    cJSON_AddStringToObject(j, "participant", r->p.participant);
    cJSON_AddNumberToObject(j, "trial", done(r) ? -1 : r->trial);
    cJSON_AddStringToObject(j, "block", done(r) ? "" : mr_study_block_name(r->p.plan->trials[r->trial].block));
    cJSON_AddBoolToObject(j, "fixation", r->fixation && !done(r) && !r->in_break);
    cJSON_AddBoolToObject(j, "break", r->in_break);
    cJSON_AddBoolToObject(j, "done", done(r));
    cJSON_AddNumberToObject(j, "images", r->image_count);
    cJSON_AddNumberToObject(j, "answered_here", r->answered_here);
    cJSON_AddNumberToObject(j, "slider", r->slider);
    cJSON_AddStringToObject(j, "design", mr_study_design_names[r->p.plan->design]);
    cJSON_AddNumberToObject(j, "scale", r->scale);
    cJSON_AddBoolToObject(j, "tapped", r->tapped);
    cJSON *w = cJSON_AddObjectToObject(j, "widgets");
    for (int i = 0; i < W_COUNT; i++)
        if (r->shown[i]) {
            cJSON *o = cJSON_AddObjectToObject(w, k_widget_names[i]);
            cJSON_AddNumberToObject(o, "w_mm", r->rect[i].w / mr_ui_mm(r->ui, 1));
            cJSON_AddNumberToObject(o, "h_mm", r->rect[i].h / mr_ui_mm(r->ui, 1));
        }
    return j;
}
