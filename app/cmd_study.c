/* mrcheck study {stimuli,plan,run,analyze}: the pairwise (Hecher), rating
 * (Scheer & Keutel) and task (Kalkofen et al.) designs. Wiring only: lib/study does the work,
 * `run`'s window included (mr_study_window_run). */
#include "app.h"

#include "mr_study.h"

#include <stdlib.h>
#include <string.h>

static int study_stimuli(int argc, char **argv) {
    static const char *cmd = "study stimuli";
    mr_study_stimuli_params sp = MR_STUDY_STIMULI_DEFAULTS;
    mr_cli_opt opts[] = {
        {"out", "DIR", "where DIR/<method>/<stimulus>.png go (required)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_cli_table tables[] = {{.prefix = "", .table = mr_study_stimuli_opts, .params = &sp}};
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, tables, 1, NULL, 0, NULL,
                          "usage: mrcheck study stimuli --family ao|ghost|shadows|depth|xray --out DIR [--views N] [--width W --height H]",
                          &help))
        return 2;
    if (help) return 0;
    mr_cli_log_level(opts);
    const char *out = mr_cli_get(opts, "out");
    if (!out) return mr_cli_errorf(cmd, "--out DIR is required"), 2;
    mr_gfx g;
    mr_error err = {0};
    if (!mr_gfx_open(&g, &err)) return mr_cli_error(cmd, &err);
    int n = 0;
    bool ok = mr_study_stimuli_render(g.renderer, &sp, out, &n, &err);
    mr_gfx_close(&g);
    if (!ok) return mr_cli_error(cmd, &err);
    printf("study stimuli: %d images of family %s in %s\n", n, mr_study_families[sp.family].name, out);
    return 0;
}

static int study_plan(int argc, char **argv) {
    static const char *cmd = "study plan";
    mr_study_plan_params pp = MR_STUDY_PLAN_DEFAULTS;
    mr_cli_opt opts[] = {
        {"out", "PLAN.json", "the plan file (required)", NULL},
        {"blocks", "I,II,III", "blocks in the plan (default I,II,III with a reference, I without; rating, task: I,II "
                               "= the condition folders present); II shows the reference", NULL},
        {"scales", "A,B,..", "rating: the scales (default Scheer & Keutel's eight depth cues)", NULL},
        {"overall", NULL, "rating: first ask which method supports the depth cues best as a whole (all side by side)", NULL},
        MR_CLI_LOG_OPTS,
        {NULL, NULL, NULL, NULL},
    };
    mr_cli_table tables[] = {{.prefix = "", .table = mr_study_plan_opts, .params = &pp}};
    const char *pos[1];
    int npos = 0;
    bool help;
    if (!mr_cli_parse_tables(argc, argv, 3, opts, tables, 1, pos, 1, &npos,
                          "usage: mrcheck study plan DIR --out plan.json [--design pairwise|rating|task] [--participants N] "
                          "[--seed S] [--blocks I,II,III] [--fixation-ms 2000]",
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
    pp.scales = mr_cli_get(opts, "scales");
    pp.overall = mr_cli_flag(opts, "overall");
    mr_study_plan plan;
    bool ok = mr_study_plan_scan_make(pos[0], &pp, &plan, &err) && mr_study_plan_save(out, &plan, &err);
    if (!ok) return mr_cli_error(cmd, &err);
    mr_study_plan_describe(&plan, out, stdout);
    mr_study_plan_free(&plan);
    return 0;
}

static int study_analyze(int argc, char **argv) {
    static const char *cmd = "study analyze";
    mr_study_analyze_params ap = MR_STUDY_ANALYZE_DEFAULTS;
    mr_cli_opt opts[] = {
        {"out", "DIR", "where the tables, charts and summary.md go (required)", NULL},
        {"plan", "PLAN.json", "only votes of this plan (others are left out with a warning)", NULL},
        MR_CLI_LOG_OPTS,
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
    int n = 0;
    if (!mr_study_analyze_files(pos, npos, mr_cli_get(opts, "plan"), &ap, out, &n, &err)) return mr_cli_error(cmd, &err);
    printf("study analyze: %d votes -> %s/summary.md\n", n, out);
    return 0;
}

/* ------------------------------------------------------------------ run */

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
        {"group", "A|B", "a shared pairwise plan's block III question: A looks better (default), B plausible", NULL},
        MR_CLI_LOG_OPTS,
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
    mr_study_window_params wp = MR_STUDY_WINDOW_DEFAULTS;
    wp.plan_path = pos[0];
    wp.participant = who;
    wp.votes_path = out;
    wp.slider = mr_cli_flag(opts, "slider");
    wp.fullscreen = mr_cli_flag(opts, "fullscreen");
    wp.ui_scale = 1.0;
    wp.script_path = mr_cli_get(opts, "script");
    const char *g = mr_cli_get(opts, "group");
    if (g && strcmp(g, "A") && strcmp(g, "B")) return mr_cli_errorf(cmd, "--group is A or B"), 2;
    wp.group = !g ? 0 : !strcmp(g, "A") ? MR_STUDY_GROUP_A : MR_STUDY_GROUP_B;
    wp.out = stdout;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &wp.width, &wp.height)) return 2;
    if (mr_cli_get(opts, "ui-scale") && !mr_cli_double("ui-scale", mr_cli_get(opts, "ui-scale"), 0.25, 8, &wp.ui_scale)) return 2;
    mr_error err = {0};
    return mr_study_window_run(&wp, &err) ? 0 : mr_cli_error(cmd, &err);
}

int cmd_study(int argc, char **argv) {
    static const struct {
        const char *name;
        int (*run)(int, char **);
        const char *help;
    } subs[] = {
        {"stimuli", study_stimuli, "render the stimuli: DIR/[<condition>/]<method>/<stimulus>.png"},
        {"plan", study_plan, "pairwise (Hecher), rating (Scheer & Keutel) or task (Kalkofen et al.) trials per participant"},
        {"run", study_run, "the study window for one participant (resumes a killed run)"},
        {"analyze", study_analyze, "pairwise: consistence, agreement, indifference, binomial tests, Davidson scores; "
                                   "rating: RM-ANOVA, post hoc, paired t; task: scores, RM-ANOVA or Friedman + Wilcoxon"},
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
