/* mr_core.h — the bottom layer of mrcheck: errors, logging, double-precision
 * math and poses, camera model and view files (JSON through cJSON), image
 * buffers and image files, atomic file writes, clocks, a deterministic RNG.
 *
 * Conventions used everywhere (see shared DESIGN.md §2):
 *  - matrices are 4x4, row-major, double: m[r*4 + c]; points are column
 *    vectors, so p' = M p, and a_from_c = a_from_b * b_from_c;
 *  - a pose is world_from_camera with OpenCV camera axes (x right, y down,
 *    z forward);
 *  - pixel coordinates follow OpenCV: the centre of the top-left pixel is
 *    (0,0), x to the right, y down.
 *
 * Functions that can fail return bool (or NULL) and fill an mr_error; nothing
 * in lib/ calls exit() or keeps global state except the log level.
 */
#ifndef MR_CORE_H
#define MR_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cjson/cJSON.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- errors */

typedef enum mr_err_code {
    MR_OK = 0,
    MR_ERR_IO,          /* file missing, unreadable or unwritable */
    MR_ERR_PARSE,       /* malformed content (JSON, glTF, image) */
    MR_ERR_INVALID,     /* well-formed but meaningless values */
    MR_ERR_NOMEM,       /* allocation failed or input too large */
    MR_ERR_UNSUPPORTED, /* valid but not handled by this build */
    MR_ERR_NODEVICE,    /* no EGL/GL device, GL context or display (only these: the
                           command-line exit status and test skips rely on it) */
    MR_ERR_GL,          /* a GL call or shader failed */
    MR_ERR_INTERRUPTED, /* stopped by SIGINT/SIGTERM (mr_stop_requested) */
} mr_err_code;

/* An error: a stable code and one human-readable line (no newline). */
typedef struct mr_error {
    mr_err_code code;
    char msg[512];
} mr_error;

/* Sets *err (if err is non-NULL) and returns false, so callers can write
 * `return mr_fail(err, MR_ERR_IO, "cannot open %s", path);`. */
bool mr_fail(mr_error *err, mr_err_code code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Prefixes an existing message with context ("loading x.glb: ..."). */
void mr_error_prefix(mr_error *err, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
const char *mr_err_name(mr_err_code code);

/* --------------------------------------------------------------- logging */

typedef enum mr_log_level { MR_LOG_ERROR = 0, MR_LOG_WARN, MR_LOG_INFO, MR_LOG_DEBUG } mr_log_level;
void mr_log_set_level(mr_log_level level); /* default MR_LOG_WARN */
mr_log_level mr_log_get_level(void);
void mr_log(mr_log_level level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* ----------------------------------------------------------------- clock */

double mr_time_now(void); /* monotonic seconds */
/* Peak resident set size of this process in bytes (0 where unknown). */
size_t mr_peak_rss_bytes(void);

/* ------------------------------------------------------------------ math */

typedef struct mr_dvec3 { double x, y, z; } mr_dvec3;
typedef struct mr_dmat4 { double m[16]; } mr_dmat4; /* row-major */

static inline mr_dvec3 mr_v3(double x, double y, double z) { mr_dvec3 v = {x, y, z}; return v; }
mr_dvec3 mr_v3_add(mr_dvec3 a, mr_dvec3 b);
mr_dvec3 mr_v3_sub(mr_dvec3 a, mr_dvec3 b);
mr_dvec3 mr_v3_scale(mr_dvec3 a, double s);
double mr_v3_dot(mr_dvec3 a, mr_dvec3 b);
mr_dvec3 mr_v3_cross(mr_dvec3 a, mr_dvec3 b);
double mr_v3_len(mr_dvec3 a);
mr_dvec3 mr_v3_normalize(mr_dvec3 a); /* zero vector stays zero */

mr_dmat4 mr_m4_identity(void);
mr_dmat4 mr_m4_mul(const mr_dmat4 *a, const mr_dmat4 *b); /* a * b */
mr_dmat4 mr_m4_translate(double x, double y, double z);
mr_dmat4 mr_m4_scale(double x, double y, double z);
/* Rotation from a unit quaternion (x, y, z, w) as glTF stores it. */
mr_dmat4 mr_m4_from_quat(double x, double y, double z, double w);
mr_dmat4 mr_m4_rotate_axis(mr_dvec3 axis, double radians);
/* glTF node: T * R * S. */
mr_dmat4 mr_m4_from_trs(const double t[3], const double q[4], const double s[3]);
/* General inverse; false if singular (|det| tiny relative to the scale). */
bool mr_m4_invert(const mr_dmat4 *a, mr_dmat4 *out);
/* Inverse of a rigid transform (rotation + translation). */
mr_dmat4 mr_m4_invert_rigid(const mr_dmat4 *a);
mr_dvec3 mr_m4_point(const mr_dmat4 *a, mr_dvec3 p);
mr_dvec3 mr_m4_dir(const mr_dmat4 *a, mr_dvec3 d);
/* True if the upper 3x3 is orthonormal with det +1 (within tol) and the
 * last row is 0 0 0 1 and all entries are finite. */
bool mr_m4_is_rigid(const mr_dmat4 *a, double tol);
bool mr_m4_is_finite(const mr_dmat4 *a);
/* Column-major float copy for GL (caller composes camera-relative first). */
void mr_m4_to_gl(const mr_dmat4 *a, float out[16]);
/* world_from_camera (OpenCV axes) of a camera at eye looking at target;
 * up is the world's up direction (the image's y axis points against it). */
mr_dmat4 mr_m4_look_at_cv(mr_dvec3 eye, mr_dvec3 target, mr_dvec3 up);

/* ---------------------------------------------------------------- camera */

/* Pinhole camera with OpenCV's 5-coefficient distortion (k1 k2 p1 p2 k3).
 * Units: pixels. */
typedef struct mr_camera {
    int width, height;    /* image size in pixels */
    double fx, fy;        /* focal lengths in pixels */
    double cx, cy;        /* principal point in pixels (OpenCV convention) */
    double dist[5];       /* k1 k2 p1 p2 k3 */
} mr_camera;

bool mr_camera_validate(const mr_camera *cam, mr_error *err);
bool mr_camera_has_distortion(const mr_camera *cam);
/* Normalised undistorted (x,y) -> normalised distorted (OpenCV model). */
void mr_camera_distort(const mr_camera *cam, double x, double y, double *xd, double *yd);
/* Inverse of mr_camera_distort by fixed-point iteration; false if it did not
 * converge (far outside the valid field of view). */
bool mr_camera_undistort(const mr_camera *cam, double xd, double yd, double *x, double *y);
/* The same camera for another image size (intrinsics scaled). */
mr_camera mr_camera_resized(const mr_camera *cam, int width, int height);

/* ------------------------------------------------------------------ JSON */

/* Reads and parses a JSON file; NULL + err on failure. */
cJSON *mr_json_load(const char *path, mr_error *err);
/* Writes JSON atomically (temp file + rename), pretty-printed. */
bool mr_json_save(const char *path, const cJSON *json, mr_error *err);
/* Field readers: false + err if missing (when required) or wrong type.
 * `what` names the object in error messages. */
bool mr_json_number(const cJSON *obj, const char *key, double *out, bool required, mr_error *err);
bool mr_json_numbers(const cJSON *obj, const char *key, double *out, int n, mr_error *err);
bool mr_json_dmat4(const cJSON *obj, const char *key, mr_dmat4 *out, mr_error *err);
/* The known key nearest to key (edit distance, case-insensitive), or NULL
 * if none is within half of key's length (+1). known ends with NULL. */
const char *mr_nearest_key(const char *key, const char *const *known);
/* Warns (MR_LOG_WARN) about each key of obj not in known: "what: unknown
 * key \"hiden\" (did you mean \"hidden\"?)"; keys starting with '_' or
 * "comment" are notes and pass. Returns the number of unknown keys. */
int mr_json_warn_unknown(const cJSON *obj, const char *const *known, const char *what);
cJSON *mr_json_from_dmat4(const mr_dmat4 *m);
cJSON *mr_json_from_doubles(const double *v, int n);

bool mr_camera_from_json(const cJSON *obj, mr_camera *cam, mr_error *err);
cJSON *mr_camera_to_json(const mr_camera *cam);
bool mr_camera_load(const char *path, mr_camera *cam, mr_error *err);

/* A view for headless rendering: a camera plus its pose. */
typedef struct mr_view {
    mr_camera camera;
    mr_dmat4 world_from_camera; /* rigid, OpenCV camera axes */
} mr_view;

/* View JSON: {"camera": {...} or "path/to/camera.json",
 *             "world_from_camera": [16 numbers, row-major]}.
 * Relative camera paths are resolved against the view file's folder. */
bool mr_view_load(const char *path, mr_view *view, mr_error *err);
bool mr_view_from_json(const cJSON *obj, const char *base_dir, mr_view *view, mr_error *err);
cJSON *mr_view_to_json(const mr_view *view);

/* ----------------------------------------------------------------- files */

/* Reads a whole file; the buffer is NUL-terminated (not counted in *size).
 * Files over max_bytes (0 = 4 GiB) are refused. Free with free(). */
void *mr_file_read(const char *path, size_t *size, size_t max_bytes, mr_error *err);
/* Writes data to path.tmp.<pid> then renames over path, so a reader never
 * sees a half-written file. */
bool mr_file_write_atomic(const char *path, const void *data, size_t size, mr_error *err);
/* JSON Lines gathered in memory and written at once with
 * mr_file_write_atomic: for outputs that are whole only when a run ends
 * (poses.jsonl, replay.jsonl), so an interrupted run leaves no half file.
 * Zero-initialise; an allocation failure is remembered and reported by
 * mr_jsonl_save. */
typedef struct mr_jsonl {
    char *text;
    size_t len, cap;
    bool failed;
} mr_jsonl;
/* Appends one line (the item unformatted); false if memory ran out. */
bool mr_jsonl_add(mr_jsonl *b, const cJSON *item);
bool mr_jsonl_save(const mr_jsonl *b, const char *path, mr_error *err);
void mr_jsonl_free(mr_jsonl *b);
bool mr_file_exists(const char *path);
bool mr_mkdirs(const char *path, mr_error *err); /* mkdir -p */

/* The output folder of a batch run (--out DIR). mr_outdir_check refuses a
 * folder that exists and holds anything (or a path that is a file) unless
 * force, so a rerun never mixes its files with an earlier run's; it writes
 * nothing, so it can run before any slow work. mr_outdir_create makes the
 * folder (mkdir -p) and remembers the folders it made; after a failure
 * mr_outdir_abandon removes those of them that are still empty, so a run
 * that failed before writing leaves no folder behind. */
typedef struct mr_outdir {
    char path[4096];
    char made[4096]; /* the topmost folder this run created ("" if none) */
} mr_outdir;
bool mr_outdir_check(const char *path, bool force, mr_error *err);
bool mr_outdir_create(mr_outdir *d, const char *path, bool force, mr_error *err);
void mr_outdir_abandon(mr_outdir *d);
/* True if path is a folder with at least one entry besides . and .. */
bool mr_dir_has_entries(const char *path);

/* ------------------------------------------------------------- stopping */

/* Batch runs stop cleanly on SIGINT and SIGTERM: mr_stop_catch installs a
 * handler (sigaction) that only sets a flag; the libraries' per-frame loops
 * ask mr_stop_requested() and end at the next frame, with their index
 * written and MR_ERR_INTERRUPTED in err, and mr_cli_error turns that into
 * exit status 128 + the signal. The flag is, with the log level, the only
 * process-wide state. A second signal while a stop is pending ends the
 * process at once (the default action), so a stuck run can still be
 * killed. */
void mr_stop_catch(void);
bool mr_stop_requested(void);
/* The signal that asked (SIGINT, SIGTERM; tests may pass any), 0 if none. */
int mr_stop_signal(void);
/* Asks for a stop as a signal would (tests, a UI's stop button); 0 clears
 * the request. */
void mr_stop_request(int sig);
/* Directory part of a path ("." if none), into out (size n). */
void mr_path_dir(const char *path, char *out, size_t n);
/* Joins dir and rel unless rel is absolute. */
void mr_path_join(const char *dir, const char *rel, char *out, size_t n);

/* ---------------------------------------------------------------- images */

typedef enum mr_pixel_type { MR_PIX_U8 = 0, MR_PIX_F32 = 1 } mr_pixel_type;

/* A tightly packed image, rows top to bottom. */
typedef struct mr_image {
    int width, height;
    int channels;       /* 1..4 */
    mr_pixel_type type;
    void *data;         /* width*height*channels elements */
} mr_image;

bool mr_image_alloc(mr_image *img, int width, int height, int channels, mr_pixel_type type, mr_error *err);
void mr_image_free(mr_image *img); /* frees data, zeroes the struct */
size_t mr_image_bytes(const mr_image *img);
/* 8-bit images: mean and standard deviation of all sample values (0..255);
 * a blank picture has no spread. 0, 0 for an empty or non-8-bit image. */
void mr_image_u8_stats(const mr_image *img, double *mean, double *std);
/* 8-bit images of one size and layout: mean absolute difference of their
 * samples (0..255); -1 if they cannot be compared. */
double mr_image_u8_mean_abs_diff(const mr_image *a, const mr_image *b);
/* Loads PNG/JPEG/etc. (stb_image) as 8-bit with `channels` channels (0 =
 * as stored). */
bool mr_image_load(const char *path, int channels, mr_image *img, mr_error *err);
/* PNG (8-bit only) and PFM (float, 1 or 3 channels), written atomically. */
bool mr_image_save_png(const char *path, const mr_image *img, mr_error *err);
bool mr_image_save_pfm(const char *path, const mr_image *img, mr_error *err);
/* The PNG file's bytes in memory (free with free()); NULL + err on failure. */
void *mr_image_encode_png(const mr_image *img, size_t *size, mr_error *err);
bool mr_image_load_pfm(const char *path, mr_image *img, mr_error *err);
/* Bilinear sample of an 8-bit image at OpenCV pixel coordinates; out gets
 * img->channels values in [0,255]; false if outside. */
bool mr_image_sample_bilinear(const mr_image *img, double x, double y, float *out);

/* --------------------------------------------------------------- options */

/* A declared option table: one row per tunable field of a params struct,
 * so that a default and a range are written once and the command line,
 * --help, settings files and UI cycling all read them from here. A table is
 * an array ended by a row with key NULL. Values are checked against
 * [lo, hi] (enums: against their names). */
typedef enum mr_opt_type {
    MR_OPT_INT = 0, /* int field */
    MR_OPT_DOUBLE,  /* double field */
    MR_OPT_FLOAT,   /* float field */
    MR_OPT_BOOL,    /* bool field; a flag on the command line */
    MR_OPT_ENUM,    /* enum field (int-sized): the index into names */
} mr_opt_type;

/* 0 is the default and means "chosen at run time" (e.g. 2% of the scene):
 * it may lie outside [lo, hi], which bounds what a user may set. */
#define MR_OPT_ZERO_AUTO 1u
/* lib/track's convention: the field's 0 stands for the default (so a
 * zero-initialised struct is the defaults) and a negative field for "off".
 * The row speaks the user's values: a value v is stored as v, the user's 0
 * as -1 ("off"), and the field reads back (mr_opt_get, format, JSON) as def
 * for 0 and as 0 for < 0; mr_opt_defaults writes 0. Rows with this flag have
 * lo >= 0, so that no user value is negative. A plain range row cannot
 * express this mapping (e.g. --refine-edges 0 -> -1), and changing the
 * fields' meaning would break every zero-initialised params struct. */
#define MR_OPT_ZERO_DEFAULT 2u
/* The default is negative and means "chosen at run time" (--to: the last
 * frame); a user sets values in [lo, hi] only. */
#define MR_OPT_NEG_AUTO 4u
/* Bool rows: the field holds the negation of the option (no_cull for
 * --cull), so a zero-initialised struct keeps the option on. */
#define MR_OPT_NEGATE 8u
/* Bool rows: on the command line the option takes a value, on or off
 * (--cull off), instead of being a flag. */
#define MR_OPT_ONOFF 16u
/* A research setting (a method's tuning), listed under "research options"
 * in --help, after the options a planner uses. */
#define MR_OPT_RESEARCH 32u

typedef struct mr_opt {
    const char *key;          /* file / UI name; on the command line prefix + key,
                                 and "" names the prefix itself (--ao) */
    mr_opt_type type;
    size_t offset;            /* offsetof the field in its params struct */
    double lo, hi;            /* accepted range (numbers) */
    double def;               /* default (enums: the index) */
    const char *const *names; /* enums: names by value, NULL-terminated */
    const char *help;         /* one line, no default or range (added from the row) */
    unsigned flags;           /* MR_OPT_ZERO_AUTO, _ZERO_DEFAULT, _NEG_AUTO, _NEGATE, _ONOFF, _RESEARCH */
} mr_opt;

/* The row named key; NULL if none. */
const mr_opt *mr_opt_find(const mr_opt *table, const char *key);
/* Number of rows. */
int mr_opt_count(const mr_opt *table);
/* Parses text into the field of `key` (bool: 1/0, true/false, on/off;
 * enum: a name). On a bad value: false and one line in err that starts with
 * the key and names the range or the names and the value, e.g.
 * "samples must be a whole number in [1, 64], got '0'". */
bool mr_opt_set(const mr_opt *table, void *params, const char *key, const char *text, mr_error *err);
/* The same for one row. */
bool mr_opt_set_row(const mr_opt *o, void *params, const char *text, mr_error *err);
/* Sets a row from a JSON value (number, bool, or enum name); same checks. */
bool mr_opt_set_json(const mr_opt *o, void *params, const cJSON *item, mr_error *err);
/* The field as a double (bool 0/1, enum its index). */
double mr_opt_get(const mr_opt *o, const void *params);
/* The field as text ("%g", "true"/"false", the enum's name) into out. */
void mr_opt_format(const mr_opt *o, const void *params, char *out, size_t n);
/* The row's default and range as text: "N in [1, 64] (default 16)",
 * "one of a, b, c (default a)", "(default off)"; for --help. */
void mr_opt_describe(const mr_opt *o, char *out, size_t n);
/* Writes every row's default into params (other fields untouched). */
void mr_opt_defaults(const mr_opt *table, void *params);
/* Adds each row to obj (number, bool or enum name) under its key. */
bool mr_opt_to_json(const mr_opt *table, const void *params, cJSON *obj);
/* Enum rows: the name of value v (NULL if out of range), the value of a
 * name (-1 if unknown), the number of names, and the next value after v
 * (cycling back to the first). */
const char *mr_opt_enum_name(const mr_opt *o, int v);
int mr_opt_enum_value(const mr_opt *o, const char *name);
int mr_opt_enum_count(const mr_opt *o);
int mr_opt_enum_next(const mr_opt *o, int v);

/* ------------------------------------------------------------ command line */

/* mrcheck's subcommands: a command declares its own options (mr_cli_opt)
 * and splices in the option tables of the params structs it fills
 * (mr_cli_table), so the flags, their --help lines and range checks come
 * from the tables. Messages are one line on stderr, "mrcheck: ...". */
/* A command's own option: name, whether it takes a value, help text. */
typedef struct mr_cli_opt {
    const char *name;   /* without the leading "--" */
    const char *arg;    /* value placeholder, or NULL for a flag */
    const char *help;
    const char *value;  /* filled by mr_cli_parse: the value, "1" for a set flag, or NULL */
} mr_cli_opt;
/* A row of a command's options after which its own options are research
 * settings: --help lists them under "research options", after the options
 * a planner uses (the tables' rows likewise, by mr_cli_table.research and
 * MR_OPT_RESEARCH). */
#define MR_CLI_RESEARCH_ROWS {"", NULL, NULL, NULL}

/* A params struct whose option table is spliced into a command's options:
 * --PREFIX (the table's "" row) and --PREFIX-KEY for each other row, with
 * their help lines made from the table. Values are checked and written into
 * params (which holds its defaults) after the whole line was read, so that
 * --help always wins. */
#define MR_CLI_TABLE_MAX 32
typedef struct mr_cli_table {
    const char *prefix;       /* "ao", "ghost" */
    const mr_opt *table;      /* at most MR_CLI_TABLE_MAX rows */
    void *params;
    const char *extra;        /* one more value --PREFIX accepts beyond the table's
                                 names (--ao groundtruth), or NULL */
    bool extra_given;         /* filled: --PREFIX EXTRA was given */
    const char *values[MR_CLI_TABLE_MAX]; /* filled: the text given for each row, or NULL */
    bool research;            /* every row is a research setting (--help lists it
                                 under "research options") */
} mr_cli_table;
/* True if the row `key` of t was on the command line. */
bool mr_cli_table_given(const mr_cli_table *t, const char *key);
/* mr_cli_parse with tables: rows of opts first, then each table's rows. */
bool mr_cli_parse_tables(int argc, char **argv, int first, mr_cli_opt *opts, mr_cli_table *tables, int ntables,
                         const char **pos, int max_pos, int *npos, const char *usage, bool *help_shown);
/* Parses argv[first..argc) into opts (terminated by a NULL name); positional
 * arguments go to *pos (up to max_pos). --help prints the usage and the
 * options' help, sets *help_shown and returns true. Returns false (after
 * printing one line) on a bad argument. */
bool mr_cli_parse(int argc, char **argv, int first, mr_cli_opt *opts, const char **pos, int max_pos, int *npos,
                  const char *usage, bool *help_shown);
const char *mr_cli_get(const mr_cli_opt *opts, const char *name);
bool mr_cli_flag(const mr_cli_opt *opts, const char *name);
/* Number parsing with range checks; print one line and return false on error. */
bool mr_cli_double(const char *opt, const char *s, double lo, double hi, double *out);
bool mr_cli_int(const char *opt, const char *s, long lo, long hi, long *out);
bool mr_cli_size(const char *opt, const char *s, int *w, int *h);
/* A count at the start of s: a number with an optional k (1e3) or M (1e6),
 * like "5M", "200k", "1e6"; *end is where it stops. false if s does not
 * start with a number. */
bool mr_cli_count_prefix(const char *s, double *out, const char **end);
/* A comma list of such counts ("1M,5M,20M"; one count is a list of one),
 * each within [lo, hi]: how many were read into out (at most max), or -1
 * where s is not such a list. */
int mr_cli_counts(const char *s, double lo, double hi, double *out, int max);
/* Exit status of a command that found no GPU device, GL context or display
 * (MR_ERR_NODEVICE): EX_UNAVAILABLE of sysexits.h. Tests skip on this status
 * only, never on the text of a message. */
#define MR_CLI_EXIT_NODEVICE 69
/* Prints "mrcheck: <cmd>: <message>" on stderr and returns 1, or
 * MR_CLI_EXIT_NODEVICE for MR_ERR_NODEVICE, or 128 + the signal for
 * MR_ERR_INTERRUPTED (130 after Ctrl-C). */
int mr_cli_error(const char *cmd, const mr_error *err);
int mr_cli_errorf(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Sets the log level from --verbose / --quiet. */
void mr_cli_log_level(const mr_cli_opt *opts);
/* The two rows of every command that mr_cli_log_level reads. */
#define MR_CLI_LOG_OPTS {"verbose", NULL, "more output", NULL}, {"quiet", NULL, "errors only", NULL}

/* ------------------------------------------------------------------- RNG */

/* Deterministic generator (splitmix64 seeded xoshiro256**), so that demo
 * data and tests are the same on every machine. */
typedef struct mr_rng { uint64_t s[4]; } mr_rng;
void mr_rng_seed(mr_rng *r, uint64_t seed);
uint64_t mr_rng_u64(mr_rng *r);
double mr_rng_uniform(mr_rng *r);  /* [0,1) */
double mr_rng_normal(mr_rng *r);   /* standard normal */

/* ------------------------------------------------------------------ hash */

/* A 64-bit hash of 8-byte words (multiply-xorshift, in four lanes: 4.4 GB/s
 * here, 2.0 in one): cache keys and checksums (LOD levels, meshlets). Not
 * cryptographic. mr_hash64_mix folds one word into h; mr_hash64 a byte
 * range (its length too). */
uint64_t mr_hash64_mix(uint64_t h, uint64_t w);
uint64_t mr_hash64(uint64_t h, const void *data, size_t n);

/* -------------------------------------------------------------- threads */

/* Calls fn(ctx, i) for every i in [0, count) on up to `threads` threads,
 * this one included (0: one per core; never more than count or 64); items
 * are handed out one at a time in increasing order, so the caller orders
 * them (largest first, say) for balance. fn returning false stops the
 * handing out (items already running finish). fn must be safe to run
 * concurrently with itself. Returns false if fn stopped it. */
bool mr_parallel_for(size_t count, int threads, bool (*fn)(void *ctx, size_t i), void *ctx);

#ifdef __cplusplus
}
#endif
#endif
