/* mr_eval.h — measuring the renderer: ray-traced ambient-occlusion ground
 * truth (Embree), image metrics (RMSE, SSIM, signed bias), and small report
 * helpers (SVG line plots, PNG montages). Used by `mrcheck bench`, by
 * `render --ao groundtruth` and by the tests.
 *
 * Precision: the Embree scene is built in float relative to the centre of
 * the scene's bounds (composed in double), so scenes far from the origin
 * trace as accurately as scenes at it.
 */
#ifndef MR_EVAL_H
#define MR_EVAL_H

#include "mr_core.h"
#include "mr_render.h"
#include "mr_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------- ground truth */

typedef struct mr_eval_gt mr_eval_gt;

/* Builds the ray-tracing scene of every drawn node (the hidden layer too
 * unless skip_hidden). NULL + err on failure (MR_ERR_NOMEM, MR_ERR_UNSUPPORTED). */
mr_eval_gt *mr_eval_gt_create(const mr_scene *scene, bool skip_hidden, mr_error *err);
void mr_eval_gt_destroy(mr_eval_gt **gt); /* NULLs, accepts NULL */

typedef struct mr_gt_params {
    mr_ao_radius_mode radius_mode; /* view (default): fixed R; screen: R grows with
                                      depth exactly like the SSAO radius */
    double radius;                 /* R in scene units (view mode); 0 = 2% of the
                                      scene's bounding-box diagonal (as the renderer) */
    double screen_radius;          /* screen mode: R = screen_radius * z * height / fy;
                                      0 = 0.05 (as the renderer) */
    int rays;                      /* cosine-weighted rays per pixel; 0 = 256 */
    uint64_t seed;                 /* 0 = 1 */
    int threads;                   /* 0 = one per online CPU */
    const mr_display_map *display; /* the frame's light-field display mapping: the
                                      surface point of pixel (u, v) lies on the ray the
                                      slices drew it with (mr_display_point; column u's
                                      own ray at band 1); NULL = pinhole */
} mr_gt_params;
#define MR_GT_DEFAULT_RAYS 256
#define MR_GT_DEFAULTS {.radius_mode = MR_AO_RADIUS_VIEW, .radius = 0.0, .screen_radius = MR_AO_DEFAULT_SCREEN_RADIUS, \
                        .rays = MR_GT_DEFAULT_RAYS, .seed = 1, .threads = 0}
/* The option table of what a user sets directly: rays (`--ao-rays` on
 * render, spliced with the "ao" prefix); the radius follows the AO options. */
extern const mr_opt mr_gt_opts[];
/* The checks of the AO table's values (t: mr_ao_opts over mr_ao_params,
 * extra "groundtruth") that are not a plain range: --ao-radius only in view
 * mode, --ao-rmin <= --ao-rmax, --ao-mask-strength only for the standalone
 * mask. Then --ao groundtruth (*groundtruth; the GPU method off) and the
 * AO radius into gt. false + err (one line) on a bad combination. */
bool mr_eval_ao_opts_check(const mr_cli_table *t, bool *groundtruth, mr_gt_params *gt, mr_error *err);

/* Ambient visibility (fraction of cosine-weighted rays of length R that
 * escape; 1 = unoccluded, 1 where depth is 0) for each pixel of a rendered
 * frame, from the surface point and normal the G-buffer saw there: `depth`
 * (F32x1, linear view z) and `normal` (F32x3, camera axes) as
 * mr_render_frame returns them; `view`'s camera is resized to their size.
 * out is allocated (F32x1). */
bool mr_eval_ao_groundtruth(const mr_eval_gt *gt, const mr_view *view, const mr_image *depth, const mr_image *normal,
                            const mr_gt_params *params, mr_image *out, mr_error *err);

/* A frame shaded with ray-traced AO instead of an AO pass (`render --ao
 * groundtruth`, the AO study's reference): one frame for the G-buffer's
 * surface points and normals, their AO by mr_eval_ao_groundtruth (the
 * hidden layer left out as fp says), then the frame again shading with it
 * (fp->ao.external). res may hold an earlier result, which is freed. */
bool mr_eval_render_groundtruth_ao(mr_renderer *r, const mr_scene *scene, const mr_view *view,
                                   const mr_frame_params *fp, const mr_gt_params *gtp, mr_frame_result *res,
                                   mr_error *err);

/* The same for one world-space point p with unit normal n: fraction of
 * `rays` cosine-weighted rays of length `radius` that escape. */
double mr_eval_ao_point(const mr_eval_gt *gt, mr_dvec3 p, mr_dvec3 n, double radius, int rays, uint64_t seed);

/* Closed form for a point on a floor at distance d from an infinite wall
 * standing on it, rays of length R: V = 1 - (acos a - a sqrt(1 - a^2)) / pi,
 * a = d / R, and V = 1 for d >= R. */
double mr_eval_ao_wall_analytic(double d, double radius);

/* Area-light shadows: the fraction of the light's area (sun:
 * its disk of directions) seen from each pixel's surface point, by shadow
 * rays to a jittered g x g grid of points on the light (g = round(sqrt(rays))),
 * the same light the renderer's shadows use (mr_shadow_light). 1 where depth
 * is 0. out is allocated (F32x1). */
typedef struct mr_shadow_gt_params {
    int rays;            /* light samples per pixel; 0 = 256 */
    float light_scale;   /* multiplies the light's size (as mr_shadow_params); 0 = 1 */
    uint64_t seed;       /* 0 = 1 */
    int threads;         /* 0 = one per online CPU */
} mr_shadow_gt_params;
#define MR_SHADOW_GT_DEFAULTS {.rays = 256, .light_scale = 1.0f, .seed = 1, .threads = 0}
bool mr_eval_shadow_groundtruth(const mr_eval_gt *gt, const mr_view *view, const mr_image *depth, const mr_image *normal,
                                const mr_light *light, const mr_shadow_gt_params *params, mr_image *out, mr_error *err);

/* ------------------------------------------------------------ metrics */

typedef struct mr_image_metrics {
    double rmse;     /* root mean square of (a - ref) */
    double ssim;     /* mean SSIM (Gaussian window 11, sigma 1.5, data range 1) */
    double bias;     /* mean of (a - ref): > 0 brighter than the reference */
    double max_abs;  /* largest |a - ref| */
    long long count; /* pixels compared */
} mr_image_metrics;

/* Compares two F32x1 images of equal size over the pixels where `mask`
 * (F32x1, e.g. a depth image) is > 0, or all pixels if mask is NULL.
 * Non-finite values count as an error of 1. */
bool mr_image_compare(const mr_image *a, const mr_image *ref, const mr_image *mask, mr_image_metrics *out,
                      mr_error *err);

/* How much an approximated image (LOD, culling)
 * differs from the full-detail one, silhouettes aside. A pixel counts as
 * differing when one of its colour channels differs by more than
 * `tolerance` (0..1 of the 8-bit range) and it is not a depth-edge pixel of
 * either image. A depth-edge pixel lies next to a depth discontinuity: in
 * its 3x3 neighbourhood one pixel shows a surface and another nothing
 * (depth 0 or not finite), or along one of the 4 directions through it
 * (horizontal, vertical, the diagonals) the inverse depth 1/z bends by more
 * than `depth_rel` of its own value (|w(p-d) - 2 w(p) + w(p+d)| > depth_rel
 * w(p); 1/z is affine on a plane, so a floor seen at a grazing angle has no
 * edges, while a step between two surfaces marks the pixels on both sides
 * of it; on the image border a one-sided second difference stands in). So a
 * silhouette that moves by one pixel (what a 1 px LOD error may do) is not
 * counted, while a missing, added or moved surface is, inside and on flat
 * ground alike. The share is of all pixels of the image. */
typedef struct mr_image_diff_params {
    double tolerance; /* per channel, of 1 (the 8-bit range); default 8/255 */
    double depth_rel; /* bend of 1/z at a discontinuity, of 1/z; default 0.02 */
} mr_image_diff_params;
#define MR_IMAGE_DIFF_DEFAULTS {.tolerance = 8.0 / 255.0, .depth_rel = 0.02}

typedef struct mr_image_diff {
    long long pixels; /* all pixels */
    long long differ; /* beyond the tolerance, off depth edges */
    long long edge;   /* depth-edge pixels of either image (not compared) */
    double differ_pct, edge_pct; /* 100 * differ / pixels, 100 * edge / pixels */
} mr_image_diff;

/* a, b: RGB8 colour images of one size; depth_a, depth_b: F32x1 linear view
 * depths of the same size (0 where nothing), as mr_frame_result gives. */
bool mr_image_diff_depth(const mr_image *a, const mr_image *depth_a, const mr_image *b, const mr_image *depth_b,
                         const mr_image_diff_params *params, mr_image_diff *out, mr_error *err);

/* ------------------------------------------------ ghosting legibility
 * Measured from the hidden layer D alone, never from the ghosting's own
 * target C_desired (see lib/eval/legibility.c for the full definition). */

typedef struct mr_ghost_legibility_images {
    const mr_image *final;    /* the ghosted image F: RGB8 sRGB or F32x3 linear */
    const mr_image *occluder; /* O: what lies in front (the frame without ghosting) */
    const mr_image *hidden;   /* D: the hidden layer rendered alone */
    const mr_image *region;   /* F32x1: 1 where hidden structure lies behind an occluder */
} mr_ghost_legibility_images;

typedef struct mr_legibility_params {
    double edge_threshold; /* an edge of D is important when gain * dE*ab / 100 exceeds this;
                              default 0.5 (above the curvature bias 0.35; dE 12.5 at gain 4) */
    double gain;           /* the saliency gain, so the threshold reads in IM units; default 4 */
} mr_legibility_params;
#define MR_LEGIBILITY_DEFAULTS {0.5, 4.0}

typedef struct mr_legibility {
    long long region;          /* region pixels */
    long long edges;           /* neighbour pairs touching the region */
    long long important;       /* of those, important edges of D */
    double important_fraction; /* important / edges (NaN without edges) */
    double legibility;         /* mean of clamp(h_F . h_R / |h_R|^2, 0, 1) over important edges:
                                  0 = only the occluder, 1 = D in full; NaN if none */
    double edge_contrast;      /* mean |h_F|: dE*ab the hidden edges add over the occluder */
    double full_contrast;      /* mean |h_R|: the same with D shown in full */
    /* The occluder's own features (Kalkofen et al.'s Experiment 2, H2), the
     * same measure with the roles swapped: over O's important edges that
     * touch the region (gain dE(O) / 100 > edge_threshold), the part of O's
     * contrast over R (D in the region, O outside) that the final image
     * shows: mean clamp(g_F . g_R / |g_R|^2, 0, 1), g_F = dF - dR,
     * g_R = dO - dR. 1 = the occluder's edge in full, 0 = gone. NaN if none. */
    long long occluder_important;
    double occluder_kept;
} mr_legibility;

bool mr_eval_ghost_legibility(const mr_ghost_legibility_images *in, const mr_legibility_params *params,
                              mr_legibility *out, mr_error *err);
/* Linear RGB (clamped to [0,1]) -> CIE L*a*b* (D65, as OpenCV's cvtColor),
 * the conversion the legibility measure uses. */
void mr_eval_rgb_to_lab(const double rgb[3], double lab[3]);

/* An independent second opinion: OpenCV contrib's spectral-residual saliency
 * (cv::saliency) of `final` (RGB8 sRGB or F32x3 linear); *ratio = mean
 * saliency inside the region / mean outside it (NaN if a side is empty or
 * nothing outside is salient). > 1: the hidden structure draws the eye. */
bool mr_eval_saliency_ratio(const mr_image *final, const mr_image *region, double *ratio, mr_error *err);

/* ------------------------------------------------------------ reports */

/* The q-quantile (q in [0,1], clamped) of the values of v[0..n) that are not
 * NaN, linearly interpolated between order statistics: q = 0.5 is the median
 * (the mean of the two middle values for an even count). Reorders v. NaN
 * when no value is left. The one median of every bench (report.c). */
/* Multi-view agreement (lib/eval/multiview.c): each pixel of view b with a
 * surface (depth_b > 0) is moved through its depth into view a and read
 * there (nearest pixel); it counts when a sees the same point (a's depth
 * within rel_tol of the point's, 0 = 1%). Depth and values are F32x1 at
 * their views' sizes (cameras scaled to them). */
typedef struct mr_view_consistency {
    double rmse;        /* root mean square of val_a - val_b over the pixels seen by both; NaN if none */
    long pixels;        /* pixels seen by both */
    double fraction;    /* of b's surface pixels */
} mr_view_consistency;
bool mr_eval_view_consistency(const mr_view *va, const mr_image *depth_a, const mr_image *val_a, const mr_view *vb,
                              const mr_image *depth_b, const mr_image *val_b, double rel_tol,
                              mr_view_consistency *out, mr_error *err);

double mr_quantile(double *v, int n, double q);
double mr_median(double *v, int n);

/* A CSV table built in memory and written atomically (report.c): optional
 * "# " comment lines, one header line, then rows of cells. Cell writers
 * append one cell each; mr_csv_end_row ends the row. Errors (out of memory,
 * a row whose cell count differs from the header's) are kept and reported
 * by mr_csv_save, which writes nothing then. All calls accept NULL. */
typedef struct mr_csv mr_csv;
mr_csv *mr_csv_create(mr_error *err);
void mr_csv_destroy(mr_csv **csv);
/* Each line of text as a "# " line (before the header, or between rows). */
void mr_csv_comment(mr_csv *csv, const char *text);
/* The header: column names separated by commas, written as given. */
void mr_csv_header(mr_csv *csv, const char *columns);
/* Text: quoted (RFC 4180, inner quotes doubled) when it holds a comma, a
 * quote or a line break, starts with '#' or has outer spaces. */
void mr_csv_text(mr_csv *csv, const char *s);
/* Text, always quoted (free-form names such as file paths). */
void mr_csv_quoted(mr_csv *csv, const char *s);
/* A number in the printf format fmt (one double conversion, e.g. "%.4f";
 * NULL: "%.17g"); NaN is written "nan", infinities "inf" and "-inf". */
void mr_csv_num(mr_csv *csv, const char *fmt, double v);
void mr_csv_int(mr_csv *csv, long long v);
void mr_csv_end_row(mr_csv *csv);
/* The text so far (never NULL) and its length. */
const char *mr_csv_data(const mr_csv *csv, size_t *len);
bool mr_csv_save(const mr_csv *csv, const char *path, mr_error *err);


/* The one SVG plot writer (plot.c), written atomically. Text is XML-escaped.
 * A point whose x or y is not finite (or not positive on a log axis) is
 * skipped: no marker, no line segment to it, no effect on the range. */
typedef enum mr_plot_mark { MR_PLOT_MARK_CIRCLE = 0, MR_PLOT_MARK_SQUARE, MR_PLOT_MARK_NONE } mr_plot_mark;
typedef struct mr_plot_series {
    const char *name;        /* legend entry; NULL or "": none */
    const double *x, *y;
    int count;
    const char *color;       /* "#rrggbb"; NULL: the palette's colour of this series' index */
    bool no_line;            /* markers only (a scatter); default: a polyline through the points */
    bool dashed;             /* the polyline dashed */
    mr_plot_mark mark;       /* default circles */
    bool hollow;             /* markers filled white, outlined in the colour */
    const char *point_label; /* text beside each marker, or NULL */
} mr_plot_series;
typedef struct mr_plot_params {
    const char *title, *xlabel, *ylabel;
    bool log_x, log_y;       /* logarithmic axes */
    double x_min, x_max;     /* a fixed x range when x_max > x_min; else the data's */
    double y_min, y_max;     /* the same for y; else the data's (linear: from min(0, data), +5%) */
    int width, height;       /* px, default 760x480 */
    int legend_width;        /* px right of the plot, default 170 */
    const char *const *notes; /* note_count lines under the legend */
    int note_count;
} mr_plot_params;
bool mr_plot_write(const char *path, const mr_plot_params *params, const mr_plot_series *series, int nseries, mr_error *err);
/* The x-y plot with lines and markers; log_x: logarithmic x axis. */
bool mr_plot_svg(const char *path, const char *title, const char *xlabel, const char *ylabel,
                 const mr_plot_series *series, int nseries, bool log_x, mr_error *err);
/* Horizontal bars: one row per category, one bar per set (v[count] each,
 * non-finite values left out), scaled to the largest value. */
typedef struct mr_plot_bar_set {
    const char *name;        /* legend */
    const double *v;
    const char *color;       /* NULL: the palette's */
} mr_plot_bar_set;
bool mr_plot_bars(const char *path, const char *title, const char *const *categories, int count, const mr_plot_bar_set *sets,
                  int nsets, mr_error *err);

/* Tiles F32x1 images (values in [0,1]) and RGB8 images, each resized by
 * nearest neighbour to tile_w x tile_h, into a PNG (grey, or RGB when any
 * tile is RGB8), cols tiles per row, row-major. */
bool mr_montage_png(const char *path, const mr_image *const *images, int count, int cols, int tile_w, int tile_h,
                    mr_error *err);

/* ------------------------------ nearest point on the model (nearest.c) */
/* For `mrcheck measure` and the view's Measure: the distance from a
 * measured point to the planned surface. Embree's point query prunes with
 * its float BVH; each candidate triangle's closest point is computed in
 * double from the scene's vertices and world transforms, so the answer is
 * exact to double rounding at any offset. The scene is borrowed: it must
 * outlive the handle. */
typedef struct mr_eval_nearest mr_eval_nearest;
/* Every drawn node's triangles (the hidden layer too unless skip_hidden).
 * NULL + err on failure (MR_ERR_NOMEM, MR_ERR_UNSUPPORTED). */
mr_eval_nearest *mr_eval_nearest_create(const mr_scene *scene, bool skip_hidden, mr_error *err);
void mr_eval_nearest_destroy(mr_eval_nearest **n); /* NULLs, accepts NULL */
int mr_eval_nearest_triangles(const mr_eval_nearest *n); /* triangles it searches */

typedef struct mr_nearest_hit {
    bool found;
    mr_dvec3 point;       /* nearest point on the model, world, scene units */
    double distance;      /* |p - point|, scene units */
    mr_dvec3 normal;      /* unit normal of its triangle (winding order), world */
    mr_dvec3 direction;   /* unit direction along which the distance grows:
                             (p - point) / distance, or the normal when p lies
                             on the surface */
    int32_t node, mesh;   /* scene node and mesh of the triangle, -1 none */
    uint32_t triangle;    /* triangle index within the mesh */
} mr_nearest_hit;
/* false (out->found false) for a non-finite p or a scene without
 * triangles. */
bool mr_eval_nearest_point(const mr_eval_nearest *n, mr_dvec3 p, mr_nearest_hit *out);
/* The distance's 1-sigma from the point's 3x3 covariance (row-major, scene
 * units^2): the covariance projected on hit->direction. NAN without a hit. */
double mr_eval_nearest_sigma(const mr_nearest_hit *hit, const double cov[9]);
/* Closest point of triangle abc to p, in double (degenerate triangles give
 * their nearest vertex). */
mr_dvec3 mr_closest_point_triangle(mr_dvec3 p, mr_dvec3 a, mr_dvec3 b, mr_dvec3 c);

#ifdef __cplusplus
}
#endif
#endif
