/* mr_study.h — user studies of rendering methods, in the three designs of
 * the papers mrcheck follows, with one plan format, one run window, one
 * vote log and one statistics module:
 *  - pairwise (Hecher's soft-shadow study, thesis ch. 4.3 and 5): all pairs
 *    plus an identical pair per category, blocks I-III (II with the
 *    reference, III split into groups A and B), two scenes per category
 *    alternating; consistence, agreement, indifference, binomial tests,
 *    Bradley-Terry and Davidson scores, inconsistent participants excluded;
 *  - rating (Scheer & Keutel): one image rated 1..7 on named scales,
 *    virtual and with video; RM-ANOVA (Mauchly, Greenhouse-Geisser),
 *    Bonferroni post hoc, paired t between the conditions;
 *  - task (Kalkofen et al.): one image and a question with a right answer;
 *    scores, RM-ANOVA where its assumptions hold, else Friedman + Wilcoxon.
 * Stimuli (`study stimuli`), a plan per participant, a durable vote log a
 * killed run resumes from, the run window's controller, the analyses.
 *
 * A pairwise stimulus folder is DIR/<method>/<stimulus>.png; the method
 * folder named "reference" (MR_STUDY_REFERENCE) is the ground truth: a
 * method like the others in the pairs, shown above the pair in block II,
 * fixed at theta = 0 in the scores. Rating and task folders add a
 * condition level: DIR/<condition>/<method>/<stimulus>.png.
 *
 * Depends on: lib/core; lib/session (the durable line append); lib/ui (the
 * run controller's widgets); lib/eval (CSV, SVG plots, ray-traced AO); lib/render
 * and lib/scene for the stimuli; lib/window for the run window, its events
 * (mr_event) and its 2D layer. One way only.
 */
#ifndef MR_STUDY_H
#define MR_STUDY_H

#include "mr_core.h"
#include "mr_render.h"
#include "mr_ui.h"
#include "mr_window.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MR_STUDY_REFERENCE "reference"
#define MR_STUDY_NAME_MAX 64      /* method, stimulus and participant names, with the NUL */
#define MR_STUDY_MAX_METHODS 16
#define MR_STUDY_MAX_BLOCKS 3     /* I, II, III */

/* "I", "II", "III" for blocks 1..3; "?" otherwise. */
const char *mr_study_block_name(int block);
/* "I,II,III" (any subset, any order, no repeats) into a mask: bit b-1 for
 * block b. false + err naming the bad item. */
bool mr_study_blocks_parse(const char *text, unsigned *mask, mr_error *err);

/* ------------------------------------------------------------- stimuli */

/* What a stimulus folder holds: the methods (sorted, "reference" among them
 * when present) and the stimuli every method has. A stimulus missing for
 * some method is left out with a warning (in the log). */
typedef struct mr_study_set {
    int method_count;
    char methods[MR_STUDY_MAX_METHODS][MR_STUDY_NAME_MAX];
    int reference;            /* index of "reference", or -1 */
    int stimulus_count;
    char (*stimuli)[MR_STUDY_NAME_MAX]; /* sorted */
} mr_study_set;

/* Scans DIR/<method>/<stimulus>.png. Needs at least two methods (the
 * reference counts) and one stimulus they all have; names are
 * [A-Za-z0-9_.-]+ (others are skipped with a warning). */
bool mr_study_scan(const char *dir, mr_study_set *out, mr_error *err);
void mr_study_set_free(mr_study_set *s);

/* The families `study stimuli --family` renders, one row each, so a family
 * is one more row. ao and ghost render the demo hall (lib/scene) from
 * `views` of its standing viewpoints through mr_render_frame. shadows is
 * Hecher's stimulus set (thesis sec. 4.1-4.3): the 13 categories of the
 * shadow suite (12 systematic and the factory), each as two scenes
 * <category>.a and <category>.b (b: the objects turned 90 degrees about
 * the vertical under the same light, a different arrangement; the
 * factory's b is the hall as built), the thesis's four methods (pcf, pcss,
 * bp and the ground truth as the reference; hard shadows with `hard`), at
 * 800x450, ambient 0.4 and antialiased. depth is Scheer & Keutel's rating
 * set: D1, D2, D3 (mr_ao_sk_setup: no AO, scheer with the depth-scaled
 * radius, crytek with a constant radius) of the hall's views in DIR/virtual/ and, over a
 * camera image at alpha 0.5, in DIR/video/. xray is Kalkofen et al.'s
 * task set: `views` scenes of `targets` arrangements each (a panelled wall,
 * a tall and a wide hidden box, a hidden pipe up to the wall) through the
 * ghosting modes, the hidden parts in the wall's colours (conflict/) and
 * in clear ones (no-conflict/), each with its answers.json. */
typedef struct mr_study_stimuli_params {
    int family;               /* index into mr_study_families; default 0 (ao) */
    int width, height;        /* image size, px; 0 = the family's (shadows 800x450, else 320x240) */
    int views;                /* demo viewpoints, 1..MR_DEMO_VIEWS; default 3 */
    int gt_rays;              /* reference AO: rays per pixel; default 128 */
    int cases;                /* shadows: categories, 1..MR_STUDY_SHADOW_CASES; default all 13 */
    int gt_samples;           /* reference shadows: light samples, 1..1024; default 256 */
    int supersample;          /* render at N times the size, average N x N pixels; 0 = the
                                 family's (shadows 2: the thesis's 2x MSAA, which the renderer
                                 has no multisample target for, else 1) */
    float ambient;            /* the scene's ambient term; 0 = the family's (shadows 0.4, the
                                 thesis's; else the scene's own) */
    bool hard;                /* shadows: also hard shadows (not in the thesis); default false */
    int targets;              /* xray: targets per scene (`views` scenes); default 6 (Kalkofen's) */
} mr_study_stimuli_params;
/* The shadow-suite cases the shadows family draws from, in suite order. */
#define MR_STUDY_SHADOW_CASES 13
extern const char *const mr_study_shadow_cases[MR_STUDY_SHADOW_CASES];
#define MR_STUDY_STIMULI_DEFAULTS {.family = 0, .width = 0, .height = 0, .views = 3, .gt_rays = 128, \
                                   .cases = MR_STUDY_SHADOW_CASES, .gt_samples = MR_SHADOW_DEFAULT_GT_SAMPLES, \
                                   .supersample = 0, .ambient = 0.0f, .hard = false, \
                                   .targets = 6}
extern const mr_opt mr_study_stimuli_opts[];   /* family, width, height, views, gt-rays, cases, gt-samples,
                                                  supersample, ambient, targets, hard */

/* A family's reference of one stimulus into res (its color is saved). */
typedef bool (*mr_study_reference_fn)(mr_renderer *r, const mr_scene *scene, const mr_view *view,
                                      const mr_frame_params *base, const mr_study_stimuli_params *p,
                                      mr_frame_result *res, mr_error *err);

typedef struct mr_study_family {
    const char *name;         /* "ao", "ghost", "shadows", "depth", "xray" */
    const char *help;
    const char *const *methods; /* NULL-terminated folder names */
    bool has_reference;       /* also renders DIR/reference/ (with `reference`) */
    /* Sets fp up for method m (index into methods). */
    void (*setup)(mr_frame_params *fp, int m);
    mr_study_reference_fn reference; /* NULL without a reference */
    bool shadow_suite;        /* the shadow suite's categories (`cases`, two scenes each) instead of the hall's views */
    int width, height;        /* default image size */
    int supersample;          /* default supersampling */
    float ambient;            /* default ambient (0: the scene's) */
    const char *optional;     /* a method rendered only when asked (shadows: "hard"), or NULL */
    bool conditions;          /* rating stimuli: DIR/virtual/ and DIR/video/ (camera image at alpha 0.5) */
    bool task;                /* task stimuli: DIR/conflict/ and DIR/no-conflict/ with answers.json */
} mr_study_family;
extern const mr_study_family mr_study_families[];
extern const int mr_study_family_count;
/* NULL-terminated family names, for the option table's enum row. */
extern const char *const mr_study_family_names[];

/* Renders every method (and the reference) for every stimulus into
 * DIR/<method>/<stimulus>.png (each written atomically) with the caller's
 * renderer (a headless GPU). *count gets the images written. */
bool mr_study_stimuli_render(mr_renderer *r, const mr_study_stimuli_params *p, const char *dir, int *count,
                             mr_error *err);

/* ---------------------------------------------------------------- plan */

/* The three designs one plan, runner and vote log serve:
 *  - pairwise (Hecher): pairs of methods, blocks I-III, DIR/<method>/<stimulus>.png;
 *  - rating (Scheer & Keutel): one image rated 1..7 (or "X": no judgement)
 *    on named scales; block I shows the virtual rendering, block II the
 *    same with the camera image blended at alpha 0.5;
 *  - task (Kalkofen et al.): one image and a question with a right answer
 *    (which of two marked hidden objects is nearer; tap where the hidden
 *    pipe crosses the wall); block I the conflicting-colour scenes
 *    (Experiment 1), block II the non-conflicting ones (Experiment 2).
 * Rating and task stimuli are DIR/<condition>/<method>/<stimulus>.png with
 * the conditions named by mr_study_condition_name; a task condition folder
 * also holds answers.json (see mr_study_key). */
typedef enum mr_study_design { MR_STUDY_PAIRWISE = 0, MR_STUDY_RATING, MR_STUDY_TASK } mr_study_design;
extern const char *const mr_study_design_names[];  /* "pairwise", "rating", "task", NULL */
/* A block's condition: pairwise "I", "II", "III"; rating "virtual",
 * "video"; task "conflict", "no-conflict"; "?" otherwise. */
const char *mr_study_condition_name(mr_study_design d, int block);
/* The category of a stimulus: its name up to the last '.' ("fence.a" ->
 * "fence"), or the whole name without a '.'. Two stimuli of one category
 * are its two scenes (Hecher's design alternates them between blocks). */
void mr_study_category_of(const char *stimulus, char *out, size_t n);

/* Block III's question per participant group (thesis sec. 4.3). */
typedef enum mr_study_group { MR_STUDY_GROUP_NONE = 0, MR_STUDY_GROUP_A, MR_STUDY_GROUP_B } mr_study_group;
const char *mr_study_group_name(mr_study_group g); /* "", "A", "B" */
/* The question of a pairwise block: "better" (I, III group A) or
 * "plausible" (II, III group B). */
const char *mr_study_question_of(int block, mr_study_group g);

#define MR_STUDY_MAX_SCALES 8
/* Scheer & Keutel's depth cues, the rating design's default scales. */
#define MR_STUDY_DEFAULT_SCALES \
    "occlusion,contrast,light_and_shadow,relative_brightness,linear_perspective,relative_size,detail_perspective,aerial_perspective"

/* The right answer of a task stimulus, from DIR/<condition>/answers.json:
 * {"<stimulus>": {"question": "nearer", "text": "...", "labels": ["A","B"], "correct": "A"}
 *                 | {"question": "crossing", "text": "...", "x": px, "y": px, "units_per_px": u}}
 * (x, y in image pixels; units_per_px: scene units per pixel at the
 * answer's depth, so a tap error converts to scene units). */
typedef enum mr_study_question { MR_STUDY_Q_NONE = 0, MR_STUDY_Q_CHOICE, MR_STUDY_Q_TAP } mr_study_question;
typedef struct mr_study_key {
    mr_study_question question;
    char text[160];
    char labels[2][32];
    int correct;              /* choice: 0 or 1 */
    double x, y, units_per_px;
} mr_study_key;

typedef struct mr_study_trial {
    int block;                /* 1..3 */
    int stimulus;             /* index into the plan's stimuli */
    int left, right;          /* pairwise: method indices, equal for an identical pair;
                                 rating, task: left is the method, right = left; a rating
                                 plan's overall question: left = -1 and right = r, every
                                 method side by side, position i showing method (r + i) mod t */
} mr_study_trial;

/* One participant's trials (a plan made with participants > 0), or the
 * one schedule everyone shares (id ""). */
typedef struct mr_study_schedule {
    char id[MR_STUDY_NAME_MAX];
    mr_study_group group;
    int trial_count;
    mr_study_trial *trials;
} mr_study_schedule;

typedef struct mr_study_plan_params {
    int seed;                 /* default 1 */
    int fixation_ms;          /* fixation cross before each trial; default 2000 */
    unsigned blocks;          /* mask (bit b-1: block b); 0 = I,II,III with a reference, I without
                                 (rating, task: every condition folder present) */
    int design;               /* mr_study_design; default pairwise */
    int participants;         /* > 0: one schedule per participant P01.. with its own order
                                 (pairwise: its own scene per block and a balanced group);
                                 0: one schedule shared by all; default 0 */
    const char *scales;       /* rating: comma-separated scale names; NULL = MR_STUDY_DEFAULT_SCALES */
#define MR_STUDY_OVERALL_MAX 4   /* methods side by side in the overall question */
    bool overall;             /* rating: first in each condition, per stimulus, Scheer & Keutel's
                                 question which rendering supports the depth cues best as a whole
                                 (all methods side by side); default false */
} mr_study_plan_params;
#define MR_STUDY_PLAN_DEFAULTS {.seed = 1, .fixation_ms = 2000, .blocks = 0, .design = 0, .participants = 0, .scales = NULL, \
                                .overall = false}
extern const mr_opt mr_study_plan_opts[];      /* seed, fixation-ms, design, participants */

typedef struct mr_study_plan {
    char id[17];              /* 16 hex digits: FNV-1a of the plan's content */
    char dir[4096];           /* the stimulus folder (as given) */
    mr_study_design design;
    mr_study_set set;
    int seed, fixation_ms;
    unsigned blocks;
    bool overall;             /* rating: the overall question trials (left = -1) */
    int scale_count;          /* rating */
    char scales[MR_STUDY_MAX_SCALES][MR_STUDY_NAME_MAX];
    mr_study_key *keys;       /* task: [(block - 1) * stimulus_count + stimulus], else NULL */
    int schedule_count;       /* >= 1 */
    mr_study_schedule *schedules;
    /* The selected schedule (mr_study_plan_select; the first at first). */
    int selected;
    mr_study_group group;
    int trial_count;
    mr_study_trial *trials;   /* in presentation order; the trial number is the index */
} mr_study_plan;

/* Pairwise, per schedule and block in order I, II, III: for each category
 * all C(t,2) pairs plus one identical pair of a random method, each with a
 * random side, shuffled (Fisher-Yates). A category with two scenes shows
 * one in block I and the other in block II (which one: random per
 * participant and category) and in block III half of the pairs on each.
 * Block II needs a reference. Rating and task: per block every method on
 * every stimulus, shuffled; a task plan with participants rotates the
 * methods over the scenes instead (participant p sees category c with
 * method (c + p) mod t, Kalkofen's "each technique in a different scene").
 * All from one seeded RNG: a seed gives the same plan on every machine.
 * dir is the stimulus folder; set its scan (pairwise: of dir; rating,
 * task: of a condition folder; mr_study_plan_scan does that). */
bool mr_study_plan_make(const char *dir, const mr_study_set *set, const mr_study_plan_params *p, mr_study_plan *out,
                        mr_error *err);
/* Scans what a design needs under dir (pairwise: dir itself; rating and
 * task: each condition folder, which must hold the same methods and
 * stimuli) and makes the plan. */
bool mr_study_plan_scan_make(const char *dir, const mr_study_plan_params *p, mr_study_plan *out, mr_error *err);
bool mr_study_plan_save(const char *path, const mr_study_plan *plan, mr_error *err);
/* One line on f: the plan's id, design, trials, schedules, methods,
 * stimuli and blocks, and where it was written (plan.c). */
void mr_study_plan_describe(const mr_study_plan *plan, const char *path, FILE *f);
/* Checks the id against the content (an edited plan is an error) and
 * resolves dir as given, else relative to the plan file's folder. */
bool mr_study_plan_load(const char *path, mr_study_plan *plan, mr_error *err);
void mr_study_plan_free(mr_study_plan *plan);
/* Points trials at a participant's schedule: the shared one takes anyone;
 * a plan with participants needs one of its ids. */
bool mr_study_plan_select(mr_study_plan *plan, const char *participant, mr_error *err);
/* The image of a method on a stimulus in a block: DIR/<method>/<stimulus>.png
 * (pairwise) or DIR/<condition>/<method>/<stimulus>.png. */
void mr_study_plan_image(const mr_study_plan *plan, int block, int stimulus, int method, char *out, size_t n);
/* Images the plan holds: 1 block x methods x stimuli (pairwise), else 3;
 * the index of one (mr_study_images_load's order). */
int mr_study_plan_image_count(const mr_study_plan *plan);
int mr_study_plan_image_index(const mr_study_plan *plan, int block, int method, int stimulus);
/* The key of a task trial (NULL for other designs). */
const mr_study_key *mr_study_plan_key(const mr_study_plan *plan, int block, int stimulus);
/* Every stimulus image of the plan's blocks (mr_study_plan_image_index;
 * blocks not in the plan stay empty), RGB; false + err (nothing kept)
 * when one cannot be read or differs in size from the first (images.c). */
bool mr_study_images_load(const mr_study_plan *plan, mr_image **out, mr_error *err);
void mr_study_images_free(const mr_study_plan *plan, mr_image **images); /* NULLs *images */

/* --------------------------------------------------------------- votes */

typedef enum mr_study_answer { MR_STUDY_LEFT = -1, MR_STUDY_NEUTRAL = 0, MR_STUDY_RIGHT = 1 } mr_study_answer;

/* One line of votes.jsonl, the one log of all three designs:
 * {"plan","participant","block":"II","trial","stimulus","left","right",
 *  "answer":"left|neutral|right","slider","ms","time_unix"} and, where
 * they apply, "design" (absent: pairwise), "group" ("A"/"B"), "question"
 * ("better"/"plausible"); rating: "ratings": {"<scale>": 1..7 or "X"};
 * task: "choice": 0|1 or "tap": [x, y] (image pixels). Rating and task
 * lines carry the method in left and right. */
#define MR_STUDY_RATING_X 0       /* "X": no judgement on a scale */
typedef struct mr_study_vote {
    char plan[17];
    char participant[MR_STUDY_NAME_MAX];
    mr_study_design design;
    int block;                /* 1..3 */
    int trial;                /* index in the plan */
    char stimulus[MR_STUDY_NAME_MAX], left[MR_STUDY_NAME_MAX], right[MR_STUDY_NAME_MAX];
    mr_study_group group;     /* pairwise: the participant's group (block III's question) */
    mr_study_answer answer;   /* pairwise */
    double slider;            /* pairwise: [-1, 1]: -1 left, 0 neutral, +1 right */
    int rating_count;         /* rating: one per scale of the plan, in its order */
    int ratings[MR_STUDY_MAX_SCALES]; /* 1..7, or MR_STUDY_RATING_X */
    int choice;               /* task, choice question: 0 or 1; rating, overall question: the
                                 method chosen (index in the plan); -1 none */
    bool has_tap;             /* task, tap question */
    double tap_x, tap_y;      /* image pixels */
    double ms;                /* response time from the stimulus's appearance */
    double time_unix;
} mr_study_vote;

/* Appends one vote durably (lib/session's append: one O_APPEND write +
 * fsync), so a kill -9 right after loses nothing. */
bool mr_study_vote_append(const char *path, const mr_study_vote *v, mr_error *err);

typedef struct mr_study_votes {
    mr_study_vote *v;
    int count, cap;
    int bad_lines;            /* lines that did not parse (a torn last line among them) */
    int duplicates;           /* a participant's second answer to a trial: dropped */
    bool torn_tail;           /* the file does not end with a newline */
} mr_study_votes;

/* Reads a votes file and adds its votes to *out (tolerant: a line that
 * does not parse is counted and skipped with a warning in the log, a torn
 * last line too; a participant's second answer to the same trial of the
 * same plan is dropped with a warning, the first kept). A missing file is
 * no error when missing_ok. false + err only for an unreadable file. */
bool mr_study_votes_read(const char *path, bool missing_ok, mr_study_votes *out, mr_error *err);
void mr_study_votes_free(mr_study_votes *v);
/* Ends a torn last line with a newline (one appended byte, fsync'd) so the
 * next append starts a line of its own; what was written stays as it is. */
bool mr_study_votes_seal(const char *path, mr_error *err);

/* Where a participant's run of a plan resumes: answered[k] is set for each
 * trial k they answered (plan->trial_count entries, caller's array); the
 * return value is the first unanswered trial (trial_count when done), or
 * -1 + err when the log holds this participant's votes for another plan
 * or votes that do not match the plan's trials. */
int mr_study_resume(const mr_study_plan *plan, const mr_study_votes *votes, const char *participant, bool *answered,
                    mr_error *err);
/* The same from the votes file (a missing one: nothing answered), with the
 * count answered and whether the file ends in a torn line (seal it with
 * mr_study_votes_seal before the first append) (resume.c). */
typedef struct mr_study_resume_point {
    bool *answered;           /* plan->trial_count entries, owned */
    int first;                /* the first unanswered trial; trial_count when done */
    int answered_count;
    bool torn_tail;
} mr_study_resume_point;
bool mr_study_resume_open(const mr_study_plan *plan, const char *votes_path, const char *participant,
                          mr_study_resume_point *out, mr_error *err);
void mr_study_resume_point_free(mr_study_resume_point *p);

/* ---------------------------------------------------------- statistics */

/* All matrices are t x t, row-major, m[i*t + j]; w[i*t+j] = times i was
 * preferred over j, ties[i*t+j] = ties[j*t+i] = no-preference answers.
 * A = w + ties/2 (the no-preference answers split half to each side,
 * thesis sec. 5.2). */
void mr_study_split_ties(const double *w, const double *ties, int t, double *A);

/* Coefficient of consistence of one participant's (complete) comparison
 * matrix A (eq. 5.1-5.2): a_i the row sums, c = t(t^2-1)/24 - sum (a_i -
 * mean)^2 / 2 (Kendall's count of circular triads, continuous with split
 * ties), xi = 1 - 24c/(t(t^2-1)) (the thesis's normalisation, for every t).
 * xi_kendall normalises by Kendall's true maximum, (t^3-t)/24 for odd t and
 * (t^3-4t)/24 for even t; with split ties c can exceed it for even t, so
 * xi_kendall is clamped to [0, 1]. */
typedef struct mr_study_consistence {
    double c, xi, xi_kendall;
} mr_study_consistence;
mr_study_consistence mr_study_consistence_of(const double *A, int t);

/* Coefficient of agreement (eq. 5.3-5.5): tau = sum_{i!=j} C(A_ij, 2) with
 * C(a,2) = a(a-1)/2 (the continuous form, exact for whole numbers),
 * u = 2 tau / sum_{i<j} C(n_ij, 2) - 1 with n_ij = A_ij + A_ji (which is
 * C(t,2) C(N,2) when every pair has N answers). NaN when no pair has two
 * answers. */
double mr_study_agreement(const double *A, int t);

/* Degree of indifference (eq. 5.6) normalised to [0, 1]: the fraction of
 * no-preference answers among the distinct pairs (sum_{i<j} A0_ij / sum
 * n_ij, i.e. eq. 5.6's numerator over C(t,2)) divided by the fraction among
 * the identical pairs (the eq.'s denominator), clamped to 1. Without an
 * identical-pair baseline (none shown, or never answered "no preference")
 * the denominator is taken as 1 and *baseline is false. */
double mr_study_indifference(double neutral_distinct, double n_distinct, double neutral_identical,
                             double n_identical, bool *baseline);
/* Eq. 5.6 as printed: iota = ((1/N) sum_{i<j} A0_ij) / ((1/N0) sum_i A0_ii)
 * with N the answers per pair (the participants, in the thesis) and N0 the
 * identical-pair answers: not divided by C(t,2) and not clamped, so it
 * runs to C(t,2) when every answer is "no preference". NaN without an
 * identical-pair "no preference" (no baseline) or without answers. */
double mr_study_indifference_eq56(double neutral_distinct, double n_per_pair, double neutral_identical,
                                  double n_identical);

/* Exact binomial test (p = 1/2): P(X >= k) for X ~ B(n, 1/2). */
double mr_study_binom_upper_tail(int n, int k);
/* The smallest k with P(X >= k) < alpha (alpha per tail; the thesis's
 * 0.025): i is preferred significantly over j when A_ij >= k; the lower
 * threshold is n - k. n + 1 when no k is (n too small). */
int mr_study_binom_threshold(int n, double alpha);

/* Bradley-Terry scores. */
typedef struct mr_study_scores {
    int t;
    double theta[MR_STUDY_MAX_METHODS];  /* log strength; the reference's is 0, else centred (mean 0) */
    double se[MR_STUDY_MAX_METHODS];     /* standard error from the inverse Hessian (0 for the reference) */
    double p[MR_STUDY_MAX_METHODS];      /* e^theta_i / sum_k e^theta_k */
    bool has_nu;                         /* Davidson with ties seen */
    double log_nu, se_log_nu;            /* Davidson's tie parameter */
    int iterations;
    bool converged;
    bool pseudo;                         /* the pseudo-count was added */
    int isolated;                        /* then: a method the others never beat or tie, else -1 */
    char note[256];                      /* one line when pseudo (which method was never beaten, ...) */
} mr_study_scores;

typedef struct mr_study_fit_params {
    int reference;            /* method fixed at theta = 0, or -1: centred */
    double pseudo;            /* added to w both ways for every pair when the comparison
                                 graph is not strongly connected; default 0.5 */
    int max_iter;             /* default 10000 (MM), 100 (Newton) */
    double tol;               /* default 1e-10 */
} mr_study_fit_params;
#define MR_STUDY_FIT_DEFAULTS {.reference = -1, .pseudo = 0.5, .max_iter = 0, .tol = 0.0}

/* Is the comparison graph (edge i -> j where i beat j, or they tied)
 * strongly connected? If not, *who gets a method that no other beats or
 * ties (a source component), or -1. */
bool mr_study_graph_connected(const double *w, const double *ties, int t, int *who);

/* Bradley-Terry without ties by Hunter's MM (2004): gamma_i <- W_i /
 * sum_j n_ij / (gamma_i + gamma_j). Fits w as given (callers wanting ties
 * in pass w from mr_study_split_ties). */
bool mr_study_bt_fit(const double *w, int t, const mr_study_fit_params *p, mr_study_scores *out, mr_error *err);
/* Davidson (1970) with ties: P(i) = pi_i / D, P(tie) = nu sqrt(pi_i pi_j) / D,
 * by Newton's method with step halving on the concave log-likelihood in
 * (theta, log nu). Without any tie it is mr_study_bt_fit (has_nu false). */
bool mr_study_davidson_fit(const double *w, const double *ties, int t, const mr_study_fit_params *p,
                           mr_study_scores *out, mr_error *err);

/* ------------------------------------- inferential statistics (infer.c) */

/* Distributions. Regularized incomplete beta I_x(a, b); the two-sided p of
 * Student's t; the upper tails of F and chi-square; the normal CDF. */
double mr_stat_beta_inc(double a, double b, double x);
double mr_stat_t_p2(double t, double df);
double mr_stat_f_sf(double F, double d1, double d2);
double mr_stat_chi2_sf(double x, double k);
double mr_stat_normal_cdf(double z);

/* Multiple-comparison adjustment of m p-values (out may be p). */
typedef enum mr_study_adjust { MR_STUDY_ADJUST_NONE = 0, MR_STUDY_ADJUST_BONFERRONI, MR_STUDY_ADJUST_HOLM } mr_study_adjust;
void mr_study_p_adjust(const double *p, int m, mr_study_adjust how, double *out);
const char *mr_study_adjust_name(mr_study_adjust a); /* "none", "bonferroni", "holm" */

/* Paired t-test of x - y (two-sided). false when n < 2. */
typedef struct mr_study_ttest {
    int n;
    double mean_diff, sd_diff, t, df, p;
} mr_study_ttest;
bool mr_study_paired_t(const double *x, const double *y, int n, mr_study_ttest *out);

/* One-way repeated-measures ANOVA of y[i*k + j] (participant i, condition
 * j; complete cases): F on (k-1, (k-1)(n-1)) df, Mauchly's test of
 * sphericity (W, Bartlett's chi^2 on k(k-1)/2 - 1 df, its p with
 * Anderson's second-order term as SPSS gives it), the
 * Greenhouse-Geisser and Huynh-Feldt epsilons (HF capped at 1) and the p
 * of F on the corrected df. */
#define MR_STUDY_MAX_CONDITIONS 16
typedef struct mr_study_rm_anova_result {
    int n, k;
    double mean[MR_STUDY_MAX_CONDITIONS];
    double ss_cond, ss_subj, ss_error;
    double df1, df2, F, p, eta_p2;   /* eta_p2: partial eta squared */
    double mauchly_w, mauchly_chi2, mauchly_df, mauchly_p; /* p NaN when n - 1 < k - 1 */
    double eps_gg, eps_hf, eps_lb;
    double p_gg, p_hf;
} mr_study_rm_anova_result;
bool mr_study_rm_anova(const double *y, int n, int k, mr_study_rm_anova_result *out, mr_error *err);

/* D'Agostino-Pearson K^2 omnibus normality test (skewness after
 * D'Agostino 1970, kurtosis after Anscombe & Glynn 1983); needs n >= 8. */
typedef struct mr_study_normality_result {
    int n;
    double z_skew, z_kurt, k2, p;
} mr_study_normality_result;
bool mr_study_normality(const double *x, int n, mr_study_normality_result *out);

/* Friedman's test of y[i*k + j] (mid-ranks within each participant, the
 * tie correction applied): chi^2 on k - 1 df; Kendall's W = chi^2/(n(k-1)). */
typedef struct mr_study_friedman_result {
    int n, k;
    double chi2, df, p, kendall_w;
    double mean_rank[MR_STUDY_MAX_CONDITIONS];
} mr_study_friedman_result;
bool mr_study_friedman(const double *y, int n, int k, mr_study_friedman_result *out, mr_error *err);

/* Wilcoxon's signed-rank test of x - y (two-sided): zero differences
 * dropped (Wilcoxon's rule), mid-ranks for ties; the exact null
 * distribution when n <= MR_STUDY_WILCOXON_EXACT_MAX and there are no ties
 * and no zeros, else the normal approximation (tie-corrected variance,
 * continuity correction). z is always the normal approximation's. */
#define MR_STUDY_WILCOXON_EXACT_MAX 50
typedef struct mr_study_wilcoxon_result {
    int n, zeros;            /* n: non-zero differences */
    double w_plus, w_minus, z, p;
    bool exact;
} mr_study_wilcoxon_result;
bool mr_study_wilcoxon(const double *x, const double *y, int n, mr_study_wilcoxon_result *out);

/* ------------------------------------------------------------ analysis */

typedef enum mr_study_test { MR_STUDY_TEST_AUTO = 0, MR_STUDY_TEST_ANOVA, MR_STUDY_TEST_FRIEDMAN } mr_study_test;
typedef struct mr_study_analyze_params {
    double alpha;             /* pairwise: binomial test, per tail; default 0.025 */
    double min_consistence;   /* pairwise: participants whose mean xi is below are excluded; default 0.3 */
    double pseudo;            /* see mr_study_fit_params; default 0.5 */
    double z;                 /* confidence interval theta +- z se; default 1.96 */
    double level;             /* rating, task: significance level (Mauchly, normality, post hoc); default 0.05 */
    int adjust;               /* rating, task: post hoc adjustment (mr_study_adjust); default bonferroni */
    int test;                 /* task: mr_study_test; auto = RM-ANOVA when the residuals pass
                                 D'Agostino's test, else Friedman + Wilcoxon; rating: auto and anova
                                 = RM-ANOVA (Scheer & Keutel's), friedman = Friedman + Wilcoxon
                                 (Kalkofen et al.'s comparison stage); default auto */
    double tap_tolerance;     /* task: a tap this near the answer (image px) is correct; default 40 */
} mr_study_analyze_params;
#define MR_STUDY_ANALYZE_DEFAULTS {.alpha = 0.025, .min_consistence = 0.3, .pseudo = 0.5, .z = 1.96, .level = 0.05, \
                                   .adjust = MR_STUDY_ADJUST_BONFERRONI, .test = MR_STUDY_TEST_AUTO, .tap_tolerance = 40}
extern const mr_opt mr_study_analyze_opts[];   /* alpha, min-consistence, pseudo, z, level, adjust, test, tap-tolerance */

/* A pairwise study's analysis. Writes into out_dir: pairs.csv, scores.csv,
 * consistence.csv, participants.csv, agreement.csv, identical.csv,
 * chart_<block>.svg and summary.md, per block I, II, III-A, III-B and per
 * category (a category's two scenes pooled) -- without the participants
 * whose mean consistence is below min_consistence; the same files with
 * everyone in out_dir/all_participants/, and the summary compares both. plan may be NULL (methods from the votes); when given, votes
 * of another plan are left out with a warning. Lines for the user (warnings,
 * the not-connected note) go to the log. */
bool mr_study_analyze(const mr_study_votes *votes, const mr_study_plan *plan, const mr_study_analyze_params *p,
                      const char *out_dir, mr_error *err);
/* A rating study (analyze_rt.c; the plan is required: its scales). Per
 * participant, condition, method and scale the mean over stimuli of the
 * ratings ("X" left out); per condition and scale a repeated-measures
 * ANOVA over the methods of the participants with every method rated
 * (Mauchly's test; Greenhouse-Geisser's p where sphericity is rejected),
 * paired t post hoc (adjusted), and per method and scale a paired t-test
 * between the conditions. Writes means.csv, anova.csv, posthoc.csv,
 * ttest.csv, chart_<condition>.svg and summary.md (the paper's Tables 3
 * and 4). */
bool mr_study_analyze_rating(const mr_study_votes *votes, const mr_study_plan *plan, const mr_study_analyze_params *p,
                             const char *out_dir, mr_error *err);
/* A task study (analyze_rt.c; the plan is required: its answer keys).
 * Each answer scored (choice: right or wrong; tap: error in px and scene
 * units, right within tap_tolerance px); per participant, condition and
 * method the share right and the mean tap error; per condition and
 * measure an RM-ANOVA (as for ratings) where the residuals pass
 * D'Agostino's normality test, else Friedman's test with Wilcoxon
 * signed-rank post hoc (adjusted). Writes trials.csv, scores.csv,
 * tests.csv, posthoc.csv, chart_<condition>.svg and summary.md. */
bool mr_study_analyze_task(const mr_study_votes *votes, const mr_study_plan *plan, const mr_study_analyze_params *p,
                           const char *out_dir, mr_error *err);
/* `study analyze` over files (analyze.c): the votes of n files, read and
 * analysed by the design of the plan at plan_path (NULL: pairwise votes
 * only; other designs need their plan); *vote_count out. */
bool mr_study_analyze_files(const char *const *votes_paths, int n, const char *plan_path,
                            const mr_study_analyze_params *p, const char *out_dir, int *vote_count, mr_error *err);

/* ------------------------------------------------------------- run window */

/* The run's controller, without a window: the caller feeds events and the
 * clock, draws the images where it says, draws its draw list on top, and
 * appends the votes it hands out. Script commands (`T COMMAND ARGS`, T in
 * seconds from the start; a command also waits until its widget is on
 * screen and the previous one's input was taken):
 *   tap @left|@neutral|@right|@vote|@r1..@r7|@rx|@a|@b|@confirm|@continue
 *   | tap @image FX FY (fractions of the image) | tap X Y | drag @slider F0 F1
 *   key K (left, right, down/space = neutral, enter = vote) | shot OUT.png | state OUT.json | quit */
typedef struct mr_study_runner mr_study_runner;

typedef struct mr_study_run_params {
    const mr_study_plan *plan;    /* outlives the runner */
    const char *participant;
    int first_trial;              /* where to start (mr_study_resume) */
    const bool *answered;         /* plan->trial_count entries (skipped trials), or NULL */
    bool slider;                  /* a slider (centre snaps to neutral) + a vote button
                                     instead of three buttons; default false */
    double px_per_mm;             /* 0 = 96 dpi */
    const char *font_path;        /* NULL = a system sans font */
    int image_w, image_h;         /* stimulus size in pixels (for the aspect); 0 = 4:3 */
    double now;                   /* clock at start, seconds */
} mr_study_run_params;
#define MR_STUDY_RUN_DEFAULTS {NULL, NULL, 0, NULL, false, 0.0, NULL, 0, 0, 0.0}
/* Slider values within this distance of the centre snap to 0 (neutral). */
#define MR_STUDY_SNAP 0.08

typedef struct mr_study_script mr_study_script;
mr_study_script *mr_study_script_load(const char *path, mr_error *err);
void mr_study_script_destroy(mr_study_script **s);

/* One participant's session in a window (window.c, `mrcheck study run`):
 * the plan and its stimuli, the vote log resumed (a torn last line ended),
 * the window, then the runner until it or the window quits; every vote is
 * appended and fsync'd as it is cast. */
typedef struct mr_study_window_params {
    const char *plan_path;        /* plan.json (required) */
    const char *participant;      /* anonymous id (required, < MR_STUDY_NAME_MAX) */
    const char *votes_path;       /* the vote log, appended (required) */
    bool slider;                  /* answer with a slider; default false */
    bool fullscreen;              /* default false */
    int width, height;            /* window size, px; 0 = 1280 x 800 */
    double ui_scale;              /* the UI beyond the screen's density; 0 = 1 */
    const char *script_path;      /* timed input (tests), or NULL */
    int group;                    /* mr_study_group for a shared pairwise plan's block III;
                                     0 = A (a plan with participants says it) */
    FILE *out;                    /* the "starting / resuming / stored" lines; NULL: none */
} mr_study_window_params;
#define MR_STUDY_WINDOW_DEFAULT_WIDTH 1280
#define MR_STUDY_WINDOW_DEFAULT_HEIGHT 800
#define MR_STUDY_WINDOW_DEFAULTS {NULL, NULL, NULL, false, false, 0, 0, 0.0, NULL, 0, NULL}
/* true also when every trial was answered before (said on out); false +
 * err when the plan, the log, the stimuli, the script or the window fail. */
bool mr_study_window_run(const mr_study_window_params *p, mr_error *err);

mr_study_runner *mr_study_runner_create(const mr_study_run_params *p, mr_error *err);
void mr_study_runner_destroy(mr_study_runner **r);
/* The runner owns the script from then on (*s = NULL). */
void mr_study_runner_set_script(mr_study_runner *r, mr_study_script **s);
void mr_study_runner_push_event(mr_study_runner *r, const mr_event *e);

/* What to draw this frame and what happened. */
typedef struct mr_study_frame {
    int trial;                    /* shown trial, -1 during fixation / when done */
    bool fixation, done;
    int image_count;              /* 0..3, or every method (a rating plan's overall question) */
    int image_method[MR_STUDY_MAX_METHODS]; /* method index of each placed image */
    mr_ui_rect image_rect[MR_STUDY_MAX_METHODS]; /* where (framebuffer px) */
    bool vote;                    /* a vote was cast this frame: *vote_out is filled */
    bool quit;                    /* the script or Esc asked to stop */
    char shot_path[1024], state_path[1024]; /* scripts: save the screen / the state (empty: none) */
} mr_study_frame;

/* One frame: script, input, layout, widgets. fb_w x fb_h framebuffer px.
 * Returns the draw list (valid until the next call). */
const mr_ui_draw_list *mr_study_runner_frame(mr_study_runner *r, double now, float fb_w, float fb_h,
                                             mr_study_frame *out, mr_study_vote *vote_out);
/* The caller could not store the vote: the runner stays on that trial. */
void mr_study_runner_vote_failed(mr_study_runner *r, const char *msg);
/* Trials answered in this run, the next trial, and a state JSON for tests. */
int mr_study_runner_answered(const mr_study_runner *r);
cJSON *mr_study_runner_state_json(const mr_study_runner *r);
bool mr_study_runner_wants_input(const mr_study_runner *r);

#ifdef __cplusplus
}
#endif
#endif
