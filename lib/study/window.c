/* `mrcheck study run`'s window: loads the plan and the stimuli, resumes the
 * participant's vote log, opens the window and carries out what the runner
 * (run.c) says: draws the images and the UI, appends each vote (fsync'd),
 * writes a script's screenshots and states. Here rather than in app/ so
 * that the command is only its flags. */
#include "mr_study.h"


#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct run_app {
    mr_study_plan plan;
    mr_image *images;          /* method x stimulus, loaded before the window opens */
    mr_window *win;
    mr_draw2d *d2;
    mr_draw2d_image **tex;     /* the same, uploaded */
    mr_study_runner *runner;
    const char *votes_path;
    int stored;
} run_app;

static void run_frame(run_app *a, bool *quit) {
    mr_event e;
    while (mr_window_next_event(a->win, &e)) {
        if (e.type == MR_EVENT_CLOSE) *quit = true;
        mr_study_runner_push_event(a->runner, &e);
    }
    int fw, fh;
    mr_window_framebuffer_size(a->win, &fw, &fh);
    if (fw <= 0 || fh <= 0) return;
    mr_study_frame f;
    mr_study_vote v;
    const mr_ui_draw_list *dl = mr_study_runner_frame(a->runner, mr_time_now(), (float)fw, (float)fh, &f, &v);
    if (f.vote) {
        mr_error err = {0};
        if (mr_study_vote_append(a->votes_path, &v, &err)) a->stored++;
        else {
            mr_log(MR_LOG_ERROR, "study run: vote NOT saved: %s", err.msg);
            mr_study_runner_vote_failed(a->runner, err.msg);
        }
    }
    static const float bg[3] = {0.5f, 0.5f, 0.5f};
    mr_draw2d_begin(a->d2, fw, fh, bg);
    mr_error err = {0};
    const mr_study_trial *tr = f.trial >= 0 ? &a->plan.trials[f.trial] : NULL;
    for (int i = 0; tr && i < f.image_count; i++) {
        mr_ui_rect r = f.image_rect[i];
        int k = mr_study_plan_image_index(&a->plan, tr->block, f.image_method[i], tr->stimulus);
        if (!mr_draw2d_image_draw(a->d2, a->tex[k], r.x, r.y, r.w, r.h, &err))
            mr_log(MR_LOG_ERROR, "study run: %s", err.msg);
    }
    mr_draw2d_ui(a->d2, dl, "study run");
    if (f.shot_path[0] || f.state_path[0]) {
        mr_image screen = {0};
        if (f.shot_path[0] && mr_draw2d_read(a->d2, &screen, &err) && !mr_image_save_png(f.shot_path, &screen, &err))
            mr_log(MR_LOG_ERROR, "study run: %s", err.msg);
        mr_image_free(&screen);
        if (f.state_path[0]) {
            cJSON *j = mr_study_runner_state_json(a->runner);
            cJSON_AddNumberToObject(j, "stored", a->stored);
            if (!mr_json_save(f.state_path, j, &err)) mr_log(MR_LOG_ERROR, "study run: %s", err.msg);
            cJSON_Delete(j);
        }
    }
    mr_window_swap(a->win);
    if (f.quit) *quit = true;
}

/* The window, its textures and the runner, then the loop until quit. */
static bool run_window(run_app *a, const mr_study_window_params *p, const mr_study_resume_point *at,
                       mr_study_script **script, mr_error *err) {
    mr_window_params wp = MR_WINDOW_DEFAULTS;
    wp.width = p->width > 0 ? p->width : MR_STUDY_WINDOW_DEFAULT_WIDTH;
    wp.height = p->height > 0 ? p->height : MR_STUDY_WINDOW_DEFAULT_HEIGHT;
    wp.fullscreen = p->fullscreen;
    wp.title = "mrcheck study";
    if (!(a->win = mr_window_create(&wp, err)) || !(a->d2 = mr_draw2d_create(mr_window_gpu(a->win), err))) return false;
    int n = mr_study_plan_image_count(&a->plan);
    const mr_image *first = NULL;
    a->tex = calloc((size_t)n, sizeof *a->tex);
    for (int i = 0; a->tex && i < n; i++) {
        if (!a->images[i].data) continue; /* a condition the plan leaves out */
        if (!first) first = &a->images[i];
        if (!(a->tex[i] = mr_draw2d_image_create(a->d2, &a->images[i], err))) return false;
    }
    if (!a->tex || !first) return mr_fail(err, MR_ERR_NOMEM, "study run: no stimulus textures");
    mr_study_run_params rp = MR_STUDY_RUN_DEFAULTS;
    rp.plan = &a->plan;
    rp.participant = p->participant;
    rp.first_trial = at->first;
    rp.answered = at->answered;
    rp.slider = p->slider;
    rp.px_per_mm = mr_window_px_per_mm(a->win) * (p->ui_scale > 0 ? p->ui_scale : 1.0);
    rp.image_w = first->width;
    rp.image_h = first->height;
    rp.now = mr_time_now();
    if (!(a->runner = mr_study_runner_create(&rp, err))) return false;
    if (*script) mr_study_runner_set_script(a->runner, script);
    for (bool quit = false; !quit;) {
        run_frame(a, &quit);
        bool busy = mr_study_runner_wants_input(a->runner);
        mr_window_wait(a->win, busy ? 0.0 : 0.05);
        if (busy) {
            struct timespec ts = {0, 4000000};
            nanosleep(&ts, NULL);
        }
    }
    return true;
}

bool mr_study_window_run(const mr_study_window_params *p, mr_error *err) {
    run_app *a = calloc(1, sizeof *a);
    if (!a) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    a->votes_path = p->votes_path;
    mr_study_resume_point at = {0};
    mr_study_script *script = NULL;
    bool ok = false;
    if (!mr_study_plan_load(p->plan_path, &a->plan, err) || !mr_study_plan_select(&a->plan, p->participant, err))
        goto done;
    /* A shared pairwise schedule: block III's group from the command line. */
    if (a->plan.design == MR_STUDY_PAIRWISE && (a->plan.blocks & 4u) && !a->plan.group)
        a->plan.group = p->group ? (mr_study_group)p->group : MR_STUDY_GROUP_A;
    if (!mr_study_resume_open(&a->plan, p->votes_path, p->participant, &at, err)) goto done;
    if (at.first >= a->plan.trial_count) {
        if (p->out)
            fprintf(p->out, "study run: participant %s has answered all %d trials of plan %s\n", p->participant,
                    a->plan.trial_count, a->plan.id);
        ok = true;
        goto done;
    }
    if (p->script_path && !(script = mr_study_script_load(p->script_path, err))) goto done;
    if (!mr_study_images_load(&a->plan, &a->images, err)) goto done;
    /* A torn last line (a kill mid-write) is ended, so our first vote
     * starts a line of its own; nothing written is changed. */
    if (at.torn_tail && !mr_study_votes_seal(p->votes_path, err)) goto done;
    if (p->out) {
        fprintf(p->out, "study run: participant %s, plan %s: %s at trial %d of %d (%d answered)\n", p->participant,
                a->plan.id, at.answered_count ? "resuming" : "starting", at.first + 1, a->plan.trial_count,
                at.answered_count);
        fflush(p->out);
    }
    if (!run_window(a, p, &at, &script, err)) goto done;
    if (p->out) fprintf(p->out, "study run: %d votes stored in %s\n", a->stored, p->votes_path);
    ok = true;
done:
    mr_study_runner_destroy(&a->runner);
    mr_study_script_destroy(&script);
    if (a->tex)
        for (int i = 0; i < mr_study_plan_image_count(&a->plan); i++) mr_draw2d_image_destroy(&a->tex[i]);
    free(a->tex);
    mr_draw2d_destroy(&a->d2);
    mr_window_destroy(&a->win);
    mr_study_images_free(&a->plan, &a->images);
    mr_study_resume_point_free(&at);
    mr_study_plan_free(&a->plan);
    free(a);
    return ok;
}
