/* mrcheck study {stimuli,plan,run,analyze}: pairwise comparison studies
 * (Hecher's design and analysis). Wiring only: lib/study does the work;
 * `run` opens the window and carries out what the runner says. */
#include "app.h"

#include "mr_study.h"
#include "mr_ui.h"
#include "mr_view.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

_Static_assert(sizeof(mr_ui_vertex) == sizeof(mr_draw2d_vertex), "vertex layouts differ");

static int study_stimuli(int argc, char **argv) {
    static const char *cmd = "study stimuli";
    mr_study_stimuli_params sp = MR_STUDY_STIMULI_DEFAULTS;
    mr_cli_opt opts[] = {
        {"out", "DIR", "where DIR/<method>/<stimulus>.png go (required)", NULL},
        {"verbose", NULL, "more log output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_cli_table tables[] = {{.prefix = "", .table = mr_study_stimuli_opts, .params = &sp}};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, tables, 1, NULL, 0, NULL,
                          "usage: mrcheck study stimuli --family ao|ghost|shadows --out DIR [--views N] [--width W --height H]",
                          &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *out = mr_cli_get(opts, "out");
    if (!out) return mr_cli_errorf(cmd, "--out DIR is required"), 2;
    app_gfx g;
    mr_error err = {0};
    if (!app_gfx_open(&g, &err)) return mr_cli_error(cmd, &err);
    int n = 0;
    bool ok = mr_study_stimuli_render(g.renderer, &sp, out, &n, &err);
    app_gfx_close(&g);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("study stimuli: %d images of family %s in %s\n", n, mr_study_families[sp.family].name, out);
    return 0;
}

static int study_plan(int argc, char **argv) {
    static const char *cmd = "study plan";
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    mr_cli_opt opts[] = {
        {"out", "PLAN.json", "the plan file (required)", NULL},
        {"blocks", "I,II,III", "blocks in the plan (default I,II,III with a reference, I without); II shows the reference", NULL},
        {"verbose", NULL, "more log output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_cli_table tables[] = {{.prefix = "", .table = mr_study_plan_opts, .params = &pp}};
    const char *pos[1];
    int npos = 0;
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, tables, 1, pos, 1, &npos,
                          "usage: mrcheck study plan DIR --out plan.json [--seed S] [--blocks I,II,III] [--fixation-ms 2000]",
                          &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *out = mr_cli_get(opts, "out");
    if (npos != 1) return mr_cli_errorf(cmd, "give the stimulus folder DIR (DIR/<method>/<stimulus>.png)"), 2;
    if (!out) return mr_cli_errorf(cmd, "--out plan.json is required"), 2;
    mr_error err = {0};
    if (mr_cli_get(opts, "blocks") && !mr_study_blocks_parse(mr_cli_get(opts, "blocks"), &pp.blocks, &err))
        return mr_cli_error(cmd, &err), 2;
    mr_study_set set;
    mr_study_plan plan;
    if (!mr_study_scan(pos[0], &set, &err)) return mr_cli_error(cmd, &err);
    bool ok = mr_study_plan_make(pos[0], &set, &pp, &plan, &err) && mr_study_plan_save(out, &plan, &err);
    mr_study_set_free(&set);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("study plan %s: %d trials (%d methods%s, %d stimuli, blocks", plan.id, plan.trial_count,
           plan.set.method_count, plan.set.reference >= 0 ? " with the reference" : "", plan.set.stimulus_count);
    for (int b = 1; b <= MR_STUDY_MAX_BLOCKS; b++)
        if (plan.blocks & (1u << (b - 1))) printf(" %s", mr_study_block_name(b));
    printf(") -> %s\n", out);
    mr_study_plan_free(&plan);
    return 0;
}

static int study_analyze(int argc, char **argv) {
    static const char *cmd = "study analyze";
    mr_study_analyze_params ap = MR_STUDY_ANALYZE_DEFAULTS;
    mr_cli_opt opts[] = {
        {"out", "DIR", "where the tables, charts and summary.md go (required)", NULL},
        {"plan", "PLAN.json", "only votes of this plan (others are left out with a warning)", NULL},
        {"verbose", NULL, "more log output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    mr_cli_table tables[] = {{.prefix = "", .table = mr_study_analyze_opts, .params = &ap}};
    enum { MAX_FILES = 256 };
    const char *pos[MAX_FILES];
    int npos = 0;
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, tables, 1, pos, MAX_FILES, &npos,
                          "usage: mrcheck study analyze votes*.jsonl --out DIR [--plan plan.json]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *out = mr_cli_get(opts, "out");
    if (npos < 1) return mr_cli_errorf(cmd, "give one or more votes files"), 2;
    if (!out) return mr_cli_errorf(cmd, "--out DIR is required"), 2;
    mr_error err = {0};
    mr_study_plan plan;
    bool have_plan = mr_cli_get(opts, "plan") != NULL;
    if (have_plan && !mr_study_plan_load(mr_cli_get(opts, "plan"), &plan, &err)) return mr_cli_error(cmd, &err);
    mr_study_votes votes = {0};
    bool ok = true;
    for (int i = 0; ok && i < npos; i++) ok = mr_study_votes_read(pos[i], false, &votes, &err);
    ok = ok && mr_study_analyze(&votes, have_plan ? &plan : NULL, &ap, out, &err);
    int n = votes.count;
    mr_study_votes_free(&votes);
    if (have_plan) mr_study_plan_free(&plan);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("study analyze: %d votes -> %s/summary.md\n", n, out);
    return 0;
}

/* ------------------------------------------------------------------ run */

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
    int S = a->plan.set.stimulus_count;
    const mr_study_trial *tr = f.trial >= 0 ? &a->plan.trials[f.trial] : NULL;
    for (int i = 0; tr && i < f.image_count; i++) {
        mr_ui_rect r = f.image_rect[i];
        if (!mr_draw2d_image_draw(a->d2, a->tex[f.image_method[i] * S + tr->stimulus], r.x, r.y, r.w, r.h, &err))
            mr_log(MR_LOG_ERROR, "study run: %s", err.msg);
    }
    mr_view_draw_ui(a->d2, dl, "study run");
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

static int study_run(int argc, char **argv) {
    static const char *cmd = "study run";
    mr_cli_opt opts[] = {
        {"participant", "ID", "anonymous participant id (required)", NULL},
        {"out", "VOTES.jsonl", "the vote log: appended and fsync'd per vote; a run resumes from it (required)", NULL},
        {"slider", NULL, "answer with a slider (its centre snaps to no preference) and a vote button", NULL},
        {"size", "WxH", "window size (default 1280x800)", NULL},
        {"fullscreen", NULL, "start fullscreen", NULL},
        {"ui-scale", "S", "scale the UI beyond the screen's density (default 1)", NULL},
        {"script", "FILE", "timed input (tests): see lib/study/mr_study.h", NULL},
        {"verbose", NULL, "more log output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    const char *pos[1];
    int npos = 0;
    bool help;
    if (!mr_cli_parse(argc, argv, 3, opts, pos, 1, &npos,
                   "usage: mrcheck study run plan.json --participant ID --out votes.jsonl [--slider] [--fullscreen]", &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *who = mr_cli_get(opts, "participant"), *out = mr_cli_get(opts, "out");
    if (npos != 1) return mr_cli_errorf(cmd, "give the plan file"), 2;
    if (!who || !who[0] || strlen(who) >= MR_STUDY_NAME_MAX) return mr_cli_errorf(cmd, "--participant ID is required (< 64 characters)"), 2;
    if (!out) return mr_cli_errorf(cmd, "--out votes.jsonl is required"), 2;
    int ww = 1280, wh = 800;
    double ui_scale = 1.0;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &ww, &wh)) return 2;
    if (mr_cli_get(opts, "ui-scale") && !mr_cli_double("ui-scale", mr_cli_get(opts, "ui-scale"), 0.25, 8, &ui_scale)) return 2;
    run_app *a = calloc(1, sizeof *a);
    if (!a) return mr_cli_errorf(cmd, "out of memory");
    a->votes_path = out;
    mr_error err = {0};
    mr_study_resume_point at = {0};
    mr_study_script *script = NULL;
    int rc = 0, first = 0;
    if (!mr_study_plan_load(pos[0], &a->plan, &err) || !mr_study_resume_open(&a->plan, out, who, &at, &err)) {
        rc = mr_cli_error(cmd, &err);
        goto done;
    }
    first = at.first;
    if (first >= a->plan.trial_count) {
        printf("study run: participant %s has answered all %d trials of plan %s\n", who, a->plan.trial_count, a->plan.id);
        goto done;
    }
    if (mr_cli_get(opts, "script") && !(script = mr_study_script_load(mr_cli_get(opts, "script"), &err))) {
        rc = mr_cli_error(cmd, &err);
        goto done;
    }
    if (!mr_study_images_load(&a->plan, &a->images, &err)) {
        rc = mr_cli_error(cmd, &err);
        goto done;
    }
    /* A torn last line (a kill mid-write) is ended, so our first vote
     * starts a line of its own; nothing written is changed. */
    if (at.torn_tail && !mr_study_votes_seal(out, &err)) {
        rc = mr_cli_error(cmd, &err);
        goto done;
    }
    int done_before = at.answered_count;
    printf("study run: participant %s, plan %s: %s at trial %d of %d (%d answered)\n", who, a->plan.id,
           done_before ? "resuming" : "starting", first + 1, a->plan.trial_count, done_before);
    fflush(stdout);
    mr_window_params wp = MR_WINDOW_DEFAULTS;
    wp.width = ww;
    wp.height = wh;
    wp.fullscreen = mr_cli_flag(opts, "fullscreen");
    wp.title = "mrcheck study";
    if (!(a->win = mr_window_create(&wp, &err)) || !(a->d2 = mr_draw2d_create(mr_window_gpu(a->win), &err))) {
        rc = mr_cli_error(cmd, &err);
        goto done;
    }
    int n = a->plan.set.method_count * a->plan.set.stimulus_count;
    a->tex = calloc((size_t)n, sizeof *a->tex);
    for (int i = 0; a->tex && i < n; i++)
        if (!(a->tex[i] = mr_draw2d_image_create(a->d2, &a->images[i], &err))) {
            rc = mr_cli_error(cmd, &err);
            goto done;
        }
    mr_study_run_params rp = MR_STUDY_RUN_DEFAULTS;
    rp.plan = &a->plan;
    rp.participant = who;
    rp.first_trial = first;
    rp.answered = at.answered;
    rp.slider = mr_cli_flag(opts, "slider");
    rp.px_per_mm = mr_window_px_per_mm(a->win) * ui_scale;
    rp.image_w = a->images[0].width;
    rp.image_h = a->images[0].height;
    rp.now = mr_time_now();
    if (!(a->runner = mr_study_runner_create(&rp, &err))) {
        rc = mr_cli_error(cmd, &err);
        goto done;
    }
    if (script) mr_study_runner_set_script(a->runner, &script);
    for (bool quit = false; !quit;) {
        run_frame(a, &quit);
        bool busy = mr_study_runner_wants_input(a->runner);
        mr_window_wait(a->win, busy ? 0.0 : 0.05);
        if (busy) {
            struct timespec ts = {0, 4000000};
            nanosleep(&ts, NULL);
        }
    }
    printf("study run: %d votes stored in %s\n", a->stored, out);
done:
    mr_study_runner_destroy(&a->runner);
    mr_study_script_destroy(&script);
    if (a->tex)
        for (int i = 0; i < a->plan.set.method_count * a->plan.set.stimulus_count; i++) mr_draw2d_image_destroy(&a->tex[i]);
    free(a->tex);
    mr_draw2d_destroy(&a->d2);
    mr_window_destroy(&a->win);
    mr_study_images_free(&a->plan, &a->images);
    mr_study_resume_point_free(&at);
    mr_study_plan_free(&a->plan);
    free(a);
    return rc;
}

int cmd_study(int argc, char **argv) {
    static const struct {
        const char *name;
        int (*run)(int, char **);
        const char *help;
    } subs[] = {
        {"stimuli", study_stimuli, "render one image per method and stimulus: DIR/<method>/<stimulus>.png"},
        {"plan", study_plan, "all pairs + an identical pair per stimulus, random order and sides, blocks I-III"},
        {"run", study_run, "the study window for one participant (resumes a killed run)"},
        {"analyze", study_analyze, "consistence, agreement, indifference, binomial tests, Bradley-Terry/Davidson scores"},
    };
    const char *sub = argc >= 3 ? argv[2] : NULL;
    if (!sub || !strcmp(sub, "--help") || !strcmp(sub, "-h")) {
        FILE *f = sub ? stdout : stderr;
        fprintf(f, "usage: mrcheck study <stimuli|plan|run|analyze> [options]\n\n");
        for (size_t i = 0; i < sizeof subs / sizeof subs[0]; i++) fprintf(f, "  %-8s %s\n", subs[i].name, subs[i].help);
        return sub ? 0 : 2;
    }
    for (size_t i = 0; i < sizeof subs / sizeof subs[0]; i++)
        if (!strcmp(sub, subs[i].name)) return subs[i].run(argc, argv);
    return mr_cli_errorf("study", "unknown subcommand '%s' (stimuli, plan, run, analyze)", sub), 2;
}
