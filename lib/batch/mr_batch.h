/* mr_batch.h — headless runs of the libraries over a whole recording: what
 * `mrcheck replay` does, as library code with a params struct and an option
 * table, so the command is argument parsing and one call.
 *
 * Depends on: lib/render (the frame), lib/scene, lib/session (recordings),
 * lib/eval (the median),
 * lib/track (the video writer), lib/core. Nothing below includes it.
 */
#ifndef MR_BATCH_H
#define MR_BATCH_H

#include "mr_core.h"
#include "mr_render.h"
#include "mr_scene.h"
#include "mr_session.h"
#include "mr_track.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Overlays of a recording's frames with the planned model at their
 * recorded poses: out_dir/overlay_NNNNNN.png per selected frame (the camera
 * frame alone where the frame has no pose, so the sequence stays complete),
 * out_dir/replay.jsonl ({"frame", "t", "image", "overlay",
 * "world_from_camera"} per written image, written atomically at the end),
 * The folder must be new or empty unless force. A stop (SIGINT/SIGTERM,
 * mr_stop_requested) ends the run at the next frame, a failure at the
 * frame that failed; either way replay.jsonl then lists exactly the images
 * written so far (and the video holds them), or, if none was, the folder
 * this run made is removed again. A stop returns false with
 * MR_ERR_INTERRUPTED and the summary in err.
 * and optionally a Motion-JPEG AVI at the recording's median frame rate
 * divided by `every` (no half-written video after a failure).
 * Deterministic: the same recording gives the same images. */

/* A caller's own output per frame in place of the overlay (the multi-view
 * rig: a quilt and its views): called for each selected frame with a pose,
 * with the frame's view and depth cues; writes its files under out_dir and
 * puts the name replay.jsonl lists into name. Frames without a pose are
 * then listed as "-" and nothing is written for them. */
typedef bool (*mr_batch_replay_render_fn)(void *user, mr_renderer *r, const mr_view *view, const mr_frame_params *fp,
                                          int64_t index, char *name, size_t name_n, mr_error *err);

typedef struct mr_batch_replay_params {
    const mr_recording *recording; /* required (mr_recording_open) */
    const char *out_dir;        /* required; created */
    const char *video_path;     /* the AVI, or NULL */
    mr_frame_params frame;      /* depth cues (AO, ghosting, ...), frame.alpha (--alpha); the video is set per frame */
    int every;                  /* every Nth frame counted from `from`; default 1 */
    int from;                   /* first frame number; default 0 */
    int to;                     /* last frame number; < 0 (the default): the last */
    bool raw;                   /* the raw pose, not the filtered one */
    bool progress;              /* "replay: frame N (i/n)" on a terminal */
    bool force;                 /* write into a folder that already holds files (else refused) */
    mr_batch_replay_render_fn render; /* NULL: the overlay PNG (and the AVI) */
    void *render_user;
    /* --views / --quilt: per frame a quilt overlay_NNNNNN_qs..png and its
     * views in overlay_NNNNNN/ (mr_render_rig_files) instead of the overlay;
     * the camera frame is seen from one eye only, so the views show the
     * plan alone; the first frame's focal distance is kept. NULL: none. */
    const mr_rig_params *rig;
    const mr_quilt *quilt;      /* with rig */
    const mr_lod *lod;          /* the scene's levels of detail (built for it), or NULL: full detail */
    const mr_hlod *hlod;        /* levels above the part, built from lod, or NULL: none */
} mr_batch_replay_params;
#define MR_BATCH_REPLAY_DEFAULTS                                                                   \
    {.frame = MR_FRAME_DEFAULTS, .every = 1, .from = 0, .to = -1}
/* alpha, every, from, to, raw. */
extern const mr_opt mr_batch_replay_opts[];

typedef struct mr_batch_replay_stats {
    int overlays;               /* frames rendered with the model */
    int plain;                  /* frames written without a pose (camera frame only) */
    uint64_t triangles;         /* submitted, summed over the overlays (a rig's: its last draw per frame) */
    uint64_t lod_instances;     /* instances drawn at a simplified level, summed likewise */
    int written;                /* images listed in replay.jsonl */
    int64_t last_frame;         /* the last one written */
    bool interrupted;           /* stopped by mr_stop_requested() */
} mr_batch_replay_stats;

/* The checks that need neither the recording nor a GPU: a folder is given
 * and new or empty (or force), to is not before from. False + one line in
 * err. */
bool mr_batch_replay_check(const mr_batch_replay_params *p, mr_error *err);
/* Sets scene on r, renders, and leaves no scene set. A frame whose image
 * cannot be read is skipped with a warning on stderr; no frame in the
 * range or a failed write: false + err. */
bool mr_batch_replay(const mr_batch_replay_params *p, mr_renderer *r, const mr_scene *scene,
                     mr_batch_replay_stats *stats, mr_error *err);

/* `mrcheck measure` (measure.c): the feature tapped in the recording's
 * frames (observations: mr_observations_load) triangulated with the taps'
 * noise and each frame's pose covariance; its distance to the planned point
 * and, with a scene, to the planned surface's nearest point (lib/eval), in
 * mm with its 1-sigma uncertainty, each with its verdict against the
 * tolerance. Report lines on out; with out_json also the result as JSON. */
typedef struct mr_batch_measure_params {
    const char *recording;    /* folder, required */
    const char *observations; /* OBS.json, required */
    const char *scene;        /* the plan; NULL: no surface distance */
    const char *tolerances;   /* T.json; NULL: DIN 18202 Table 1 by nominal size */
    double nominal;           /* m; < 0 (default): the planned point's distance from the table's reference point */
    const char *part;         /* the planned point's part (its tolerance); NULL: none */
    const char *out_json;     /* NULL: no file */
    mr_triangulate_params triangulate;
    FILE *out;                /* required */
} mr_batch_measure_params;
#define MR_BATCH_MEASURE_DEFAULTS {.nominal = -1, .triangulate = MR_TRIANGULATE_DEFAULTS}
bool mr_batch_measure(const mr_batch_measure_params *p, mr_error *err);

/* `mrcheck track` (track.c): the tracker over the source's frames. A frame
 * the tracker refuses is skipped with a warning on stderr. With the
 * tracker's camera and markers each frame has a pose line
 * (mr_pose_line_json): on lines, or into out (written atomically when the
 * run ends); print_detections puts {"frame","detections"[,"pose"]} per
 * frame on lines instead. A stop (mr_stop_requested) ends the run at the
 * next frame and returns true with stats->interrupted. False + one line:
 * no frames, no frame processed, --out without camera and markers, a read
 * or write failure. */
typedef struct mr_batch_track_params {
    mr_source *source;        /* required */
    mr_tracker *tracker;      /* required */
    const char *input;        /* its name, for messages */
    const char *out;          /* poses.jsonl; NULL: pose lines on `lines` */
    bool print_detections;
    long max_frames;          /* < 0 (default): all */
    bool progress;            /* "track: frame N" on a terminal */
    bool summary;             /* the counts as one line on stderr at the end */
    FILE *lines;              /* required (stdout) */
} mr_batch_track_params;
#define MR_BATCH_TRACK_DEFAULTS {.max_frames = -1}
typedef struct mr_batch_track_stats {
    long frames, failed, with_tags, with_pose;
    bool interrupted;
} mr_batch_track_stats;
bool mr_batch_track(const mr_batch_track_params *p, mr_batch_track_stats *stats, mr_error *err);

/* ------------------------------------------------------ printable pages */

/* A page as filled black rectangles and lines of text (page.c), written
 * as PDF 1.4 (vector rectangles, text in the standard Helvetica font) or
 * rasterised to a grey PNG at a given dpi (a pixel is black when its
 * centre lies in a rectangle; text in a built-in 5x7 pixel font scaled to
 * Helvetica's cap height). Lengths in mm from the page's top-left corner,
 * y down. */
typedef enum mr_page_item_kind { MR_PAGE_RECT, MR_PAGE_TEXT } mr_page_item_kind;
typedef struct mr_page_item {
    mr_page_item_kind kind;
    double x, y;              /* mm; rect: top-left corner; text: left end of the baseline */
    double w, h;              /* rect: size, mm; text: w unused, h the font size in points */
    char text[128];           /* printable ASCII */
} mr_page_item;
typedef struct mr_page {
    double width_mm, height_mm;
    mr_page_item *items;
    int count, cap;
    bool failed;              /* an allocation failed: saving reports it */
} mr_page;
void mr_page_rect(mr_page *p, double x, double y, double w, double h);
void mr_page_text(mr_page *p, double x, double y, double size_pt, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
void mr_page_free(mr_page *p); /* zeroes it */
/* n pages as one PDF 1.4 file, written atomically. */
bool mr_pdf_save(const char *path, const mr_page *pages, int n, mr_error *err);
/* The page as an 8-bit grey image at dpi (white paper, black ink). */
bool mr_page_raster(const mr_page *p, double dpi, mr_image *out, mr_error *err);
/* The image as PNG, written atomically, with a pHYs chunk stating dpi so
 * that a viewer prints it at its size. */
bool mr_page_png_save(const char *path, const mr_image *img, double dpi, mr_error *err);
/* Paper sizes (portrait, mm): "a4", "a3", "letter" (any case). */
bool mr_paper_size(const char *name, double *width_mm, double *height_mm);


/* `mrcheck tags` and `mrcheck board` (sheets.c): printable AprilTags at a
 * chosen physical size. Each tag's cells come from the family's own code
 * (mr_tag_pattern_make); size_mm is the edge of the square the detector
 * finds, the marker map's tag_size (tag36h11: the black square). The
 * files go into out_dir, which must be new or empty unless force, and
 * is removed again if the run fails before writing. */
typedef struct mr_sheet_params {
    const char *out_dir;      /* required */
    const char *family;       /* NULL: tag36h11 */
    double size_mm;           /* detected square's edge, mm; tags: required;
                                 board: 0 = MR_SHEET_BOARD_DEFAULT_SIZE_MM */
    const char *paper;        /* "a4" (default), "a3", "letter" */
    double dpi;               /* the PNGs' resolution, default 300 */
    bool force;               /* write into a folder that holds files */
    bool progress;            /* "tags: page i/n" on stderr */
    /* tags: */
    const int *ids;           /* id_count ids to print, in this order; none: */
    int id_count;
    const char *ids_text;     /* ... these, as mr_sheet_ids_parse reads them; NULL: "0-11" */
    /* board: */
    int cols, rows;           /* tags across and down; 0 = as many as fit */
    int first_id;             /* ids first_id, first_id+1, ... row by row */
    double gap_mm;            /* between neighbouring tags' squares; 0 = size_mm / 4 */
} mr_sheet_params;
#define MR_SHEET_DEFAULTS {.family = NULL, .paper = "a4", .dpi = 300.0, .first_id = 100}
#define MR_SHEET_BOARD_DEFAULT_SIZE_MM 30.0
/* size-mm, dpi, cols, rows, first-id, gap-mm. */
extern const mr_opt mr_sheet_opts[];
/* The length of the scale bar printed beside each tag and on the board. */
#define MR_SHEET_SCALE_BAR_MM 100.0

typedef struct mr_sheet_result {
    int pages;
    int tags;                 /* tags printed */
    int per_page;
    int cols, rows;           /* board: its grid */
    double pitch_mm;          /* board: centre to centre */
    char pdf[4096];           /* the files written */
    char json[4096];          /* tags: the marker-map template; board: board.json */
    char summary[4096];       /* what was written, one line for people */
} mr_sheet_result;

/* tags.pdf (every page), tags-N.png (page N at dpi) and
 * markers_template.json: the marker map's format with the family, the
 * size (m) and the ids filled in, each world_from_tag null until
 * surveyed (so no command takes it for a map by mistake). Each tag has
 * its id, family and size printed under it and a 10 cm scale bar. */
bool mr_sheet_tags(const mr_sheet_params *p, mr_sheet_result *res, mr_error *err);
/* A planar calibration board for `mrcheck calibrate`: board.pdf,
 * board.png and board.json (a marker map in the board frame: origin at the
 * first tag's centre, x along a row, y down the page, z into the paper,
 * lengths in metres) with a scale bar. */
bool mr_sheet_board(const mr_sheet_params *p, mr_sheet_result *res, mr_error *err);
/* "0-11", "3,5,7-9": ids >= 0 in order, each once; a malloc'd array.
 * false on a bad list (nothing allocated). */
bool mr_sheet_ids_parse(const char *s, int **ids, int *n);

#ifdef __cplusplus
}
#endif
#endif
