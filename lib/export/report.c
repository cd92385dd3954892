/* The findings report: a folder that opens from disk with no server.
 * index.html (inline CSS and an inline SVG plan view, images beside it in
 * img/), report.md (the same in Markdown), img/mark_N_photo.png (the frame
 * undistorted, as in the BCF), img/mark_N_overlay.png (the screen as the
 * planner saw it, where recorded), img/plan.svg. Written into
 * OUT.tmp.<pid> and renamed into place. */
/* nftw */
#define _XOPEN_SOURCE 700
#include "export_internal.h"

#include <dirent.h>
#include <errno.h>
#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* Marks an output folder as ours, so a later export may replace it. */
#define MARKER ".mrcheck-report"

typedef struct plan {
    double lo[2], hi[2];   /* plan extent: glTF x and z, scene units */
    double scale;          /* px per scene unit */
    double pad;            /* px */
    int w, h;              /* px */
} plan;

static void grow(plan *p, double x, double z) {
    if (!isfinite(x) || !isfinite(z)) return;
    p->lo[0] = fmin(p->lo[0], x), p->hi[0] = fmax(p->hi[0], x);
    p->lo[1] = fmin(p->lo[1], z), p->hi[1] = fmax(p->hi[1], z);
}

/* Where a finding sits in the plan: its picked point, else its camera. */
static void mark_xz(const mr_finding *f, double *x, double *z) {
    const mr_annotation *a = f->mark;
    if (a->hit) {
        *x = a->world[0], *z = a->world[2];
    } else {
        *x = a->world_from_camera.m[3], *z = a->world_from_camera.m[11];
    }
}

static void plan_px(const plan *p, double x, double z, double *u, double *v) {
    *u = p->pad + (x - p->lo[0]) * p->scale;
    *v = p->pad + (z - p->lo[1]) * p->scale; /* seen from above: +z down the page */
}

/* A judged mark's colour: red out of tolerance, green within, amber
 * undecided; marks without a verdict red as before. */
static const char *verdict_colour(const mr_annotation *a) {
    if (!a->has_verdict) return "#d32f2f";
    return a->verdict.kind == MR_VERDICT_WITHIN ? "#2e7d32" : a->verdict.kind == MR_VERDICT_UNDECIDED ? "#ef8f00" : "#d32f2f";
}

/* The summary's verdict cell: "out of tolerance (95 %: 224 .. 372 mm;
 * limit +-20 mm, DIN 18202 Table 1, 6-15 m)", "-" when not judged. */
static void verdict_cell(const mr_annotation *a, char *out, size_t n) {
    if (!a->has_verdict || a->verdict.kind == MR_VERDICT_NONE) {
        snprintf(out, n, "-");
        return;
    }
    const mr_verdict *v = &a->verdict;
    snprintf(out, n, "%s (95 %%: %.0f .. %.0f mm; limit +- %.0f mm, %s)", mr_verdict_words(v->kind), v->lo_m * 1e3,
             v->hi_m * 1e3, v->tol.limit_m * 1e3, v->tol.source);
}

/* The plan view as SVG: the scene's node footprints, each camera with its
 * viewing direction, each mark numbered. */
static void plan_svg(mr_xml *x, const mr_findings *fs, const mr_scene *s) {
    plan p = {{INFINITY, INFINITY}, {-INFINITY, -INFINITY}, 1, 24, 0, 0};
    if (s && s->node_count > 0 && isfinite(s->bounds_min[0]) && s->bounds_max[0] >= s->bounds_min[0]) {
        grow(&p, s->bounds_min[0], s->bounds_min[2]);
        grow(&p, s->bounds_max[0], s->bounds_max[2]);
    }
    for (int i = 0; i < fs->count; i++) {
        double mx, mz;
        mark_xz(&fs->items[i], &mx, &mz);
        grow(&p, mx, mz);
        const double *m = fs->items[i].mark->world_from_camera.m;
        grow(&p, m[3], m[11]);
    }
    double ex = p.hi[0] - p.lo[0], ez = p.hi[1] - p.lo[1];
    double span = fmax(fmax(ex, ez), 1e-9);
    /* A little room around single points. */
    if (ex < span * 0.05) p.lo[0] -= span * 0.05, p.hi[0] += span * 0.05, ex = p.hi[0] - p.lo[0];
    if (ez < span * 0.05) p.lo[1] -= span * 0.05, p.hi[1] += span * 0.05, ez = p.hi[1] - p.lo[1];
    p.scale = 760.0 / fmax(ex, ez);
    p.w = (int)ceil(ex * p.scale + 2 * p.pad);
    p.h = (int)ceil(ez * p.scale + 2 * p.pad);
    mr_xml_raw(x, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
                  "font-family=\"sans-serif\" font-size=\"12\">\n", p.w, p.h, p.w, p.h);
    mr_xml_raw(x, "<rect width=\"%d\" height=\"%d\" fill=\"#fafafa\"/>\n", p.w, p.h);
    if (s) {
        int drawn = 0;
        for (int32_t n = 0; n < s->node_count && drawn < 5000; n++) {
            double lo[3], hi[3];
            if (s->nodes[n].layer != MR_LAYER_VISIBLE || !mr_scene_node_bounds(s, n, lo, hi)) continue;
            double u0, v0, u1, v1;
            plan_px(&p, lo[0], lo[2], &u0, &v0);
            plan_px(&p, hi[0], hi[2], &u1, &v1);
            mr_xml_raw(x, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#dde3ea\" "
                          "fill-opacity=\"0.5\" stroke=\"#8a96a3\" stroke-width=\"0.6\"><title>",
                       u0, v0, fmax(u1 - u0, 0.5), fmax(v1 - v0, 0.5));
            mr_xml_escape_into(x, s->nodes[n].name);
            mr_xml_raw(x, "</title></rect>\n");
            drawn++;
        }
    }
    double arrow = 1.0 / fmax(1e-12, 1.0) * span * 0.04;
    for (int i = 0; i < fs->count; i++) {
        const mr_finding *f = &fs->items[i];
        const double *m = f->mark->world_from_camera.m;
        double cu, cv, du, dv, mu, mv, mx, mz;
        plan_px(&p, m[3], m[11], &cu, &cv);
        double dx = m[2], dz = m[10], dl = hypot(dx, dz);
        if (dl < 1e-9) dx = 0, dz = 0, dl = 1;
        plan_px(&p, m[3] + dx / dl * arrow, m[11] + dz / dl * arrow, &du, &dv);
        mark_xz(f, &mx, &mz);
        plan_px(&p, mx, mz, &mu, &mv);
        mr_xml_raw(x, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#888\" stroke-dasharray=\"3 3\"/>\n",
                   cu, cv, mu, mv);
        mr_xml_raw(x, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#1565c0\" stroke-width=\"2\"/>"
                      "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"#1565c0\"/>\n", cu, cv, du, dv, cu, cv);
        mr_xml_raw(x, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"9\" fill=\"%s\" stroke=\"white\" stroke-width=\"1.5\">"
                      "<title>", mu, mv, verdict_colour(f->mark));
        mr_xml_escape_into(x, f->title);
        mr_xml_raw(x, "</title></circle><text x=\"%.1f\" y=\"%.1f\" fill=\"white\" text-anchor=\"middle\" "
                      "font-weight=\"bold\">%d</text>\n", mu, mv + 4, f->number);
    }
    /* A scale bar: 1, 2, 5 x 10^k scene units near a sixth of the width. */
    double want = (p.w - 2 * p.pad) / 6 / p.scale, b = pow(10, floor(log10(want)));
    double bar = want >= 5 * b ? 5 * b : want >= 2 * b ? 2 * b : b;
    mr_xml_raw(x, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"black\" stroke-width=\"2\"/>"
                  "<text x=\"%.1f\" y=\"%d\">%g m</text>\n", p.pad, p.h - 8, p.pad + bar * p.scale, p.h - 8,
               p.pad + bar * p.scale + 6, p.h - 4, bar);
    mr_xml_raw(x, "</svg>\n");
}

/* Deviations and uncertainties: always mm. */
static void fmt_len(bool has, double m, char *out, size_t n) {
    if (!has) snprintf(out, n, "n/a");
    else snprintf(out, n, "%.0f mm", m * 1000);
}

/* The planner's words on a mark: status, priority, assignee, labels. */
static void topic_words(const mr_annotation *a, char *out, size_t n) {
    size_t k = (size_t)snprintf(out, n, "%s", a->status[0] ? a->status : "open");
    if (a->priority[0] && k < n) k += (size_t)snprintf(out + k, n - k, ", priority %s", a->priority);
    if (a->assignee[0] && k < n) k += (size_t)snprintf(out + k, n - k, ", assigned to %s", a->assignee);
    for (int i = 0; i < a->label_count && k < n; i++)
        k += (size_t)snprintf(out + k, n - k, "%s%s", i ? ", " : ", labels: ", a->labels[i]);
}

/* "+- sigma" after a measured distance that has one. */
static void dist_sigma(const mr_finding *f, char *d, size_t n) {
    if (!f->has_distance_sigma) return;
    char s[32];
    fmt_len(true, f->distance_sigma_m, s, sizeof s);
    size_t k = strlen(d);
    if (k < n) snprintf(d + k, n - k, " +- %s", s);
}

static void fmt_time(double t_unix, char *out, size_t n) {
    if (!(t_unix > 0 && t_unix < 253402300799.0)) {
        snprintf(out, n, "unknown");
        return;
    }
    time_t t = (time_t)t_unix;
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(out, n, "%Y-%m-%d %H:%M:%S UTC", &tm);
}

static bool copy_file(const char *from, const char *to, mr_error *err) {
    size_t n = 0;
    void *d = mr_file_read(from, &n, 0, err);
    if (!d) return false;
    bool ok = mr_file_write_atomic(to, d, n, err);
    free(d);
    return ok;
}

static bool write_images(const char *tmp, mr_findings *fs, const mr_export_params *p, bool *overlay, mr_error *err) {
    char dir[4300], path[4400];
    snprintf(dir, sizeof dir, "%s/img", tmp);
    if (!mr_mkdirs(dir, err)) return false;
    for (int i = 0; i < fs->count; i++) {
        mr_finding *f = &fs->items[i];
        mr_bcf_frame fr;
        mr_image snap;
        if (!mr_bcf_frame_of(&f->camera, p->max_side, &fr, err) ||
            !mr_bcf_snapshot(&f->frame, &f->camera, &fr, &snap, err)) {
            mr_error_prefix(err, "mark %d", f->number);
            return false;
        }
        snprintf(path, sizeof path, "%s/mark_%d_photo.png", dir, f->number);
        bool ok = mr_image_save_png(path, &snap, err);
        mr_image_free(&snap);
        if (!ok) return false;
        overlay[i] = f->screen_path[0] != 0;
        if (overlay[i]) {
            snprintf(path, sizeof path, "%s/mark_%d_overlay.png", dir, f->number);
            if (!copy_file(f->screen_path, path, err)) return false;
        }
    }
    return true;
}

static const char *k_css =
    "body{font-family:sans-serif;margin:2em auto;max-width:1100px;color:#222}"
    "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px 8px;text-align:left}"
    "th{background:#eee}.f{border-top:2px solid #ddd;margin-top:2em;padding-top:1em}"
    ".pics{display:flex;gap:12px;flex-wrap:wrap}.pics figure{margin:0}.pics img{max-width:520px;width:100%;"
    "border:1px solid #999}figcaption{font-size:90%;color:#555}.n{display:inline-block;background:#d32f2f;"
    "color:#fff;border-radius:50%;width:1.6em;text-align:center;font-weight:bold}";

static char *html_doc(const mr_findings *fs, const mr_export_params *p, const bool *overlay, size_t *n) {
    mr_xml x;
    memset(&x, 0, sizeof x);
    mr_xml_raw(&x, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>");
    mr_xml_escape_into(&x, p->title);
    mr_xml_raw(&x, "</title><style>%s</style></head><body>\n<h1>", k_css);
    mr_xml_escape_into(&x, p->title);
    mr_xml_raw(&x, "</h1>\n<p>%d finding%s. <b>distance to the plan</b>: how far the built part is from the planned "
                   "surface, measured from two or more camera frames (mm, &plusmn; 1&nbsp;sigma); "
                   "<b>registration</b>: the uncertainty of the model's placement over the camera picture at the mark "
                   "(mm, 1&nbsp;sigma); <b>camera to the point</b>: how far the camera was from the marked point "
                   "(m); <b>verdict</b>: the distance to the plan judged against the tolerance with its 95&nbsp;%% interval "
                   "(&plusmn; 2&nbsp;sigma, the registration's uncertainty included): <b>within tolerance</b> when the "
                   "whole interval is inside the limit, <b>out of tolerance</b> when it is wholly outside, "
                   "<b>undecided</b> when it straddles the limit (measure again, closer or from a wider baseline); the "
                   "limit is DIN 18202 Table 1's for the nominal size unless the hall's table gives one for the part "
                   "or layer. n/a: not measured or not available.</p>\n", fs->count, fs->count == 1 ? "" : "s");
    mr_xml_raw(&x, "<h2>Summary</h2>\n<table><tr><th>#</th><th>finding</th><th>part</th><th>status</th>"
                   "<th>distance to the plan</th><th>verdict</th><th>registration</th><th>camera to the point</th><th>frame</th>"
                   "<th>time in recording</th><th>marked</th></tr>\n");
    for (int i = 0; i < fs->count; i++) {
        const mr_finding *f = &fs->items[i];
        char d[64], u[64], when[64], seen[64], vc[256];
        fmt_len(f->has_distance, f->distance_m, d, sizeof d);
        dist_sigma(f, d, sizeof d);
        fmt_len(f->has_uncertainty, f->uncertainty_m, u, sizeof u);
        fmt_time(f->mark->time_unix, when, sizeof when);
        verdict_cell(f->mark, vc, sizeof vc);
        if (f->depth_m >= 0) snprintf(seen, sizeof seen, "%.2f m", f->depth_m);
        else snprintf(seen, sizeof seen, "n/a");
        mr_xml_raw(&x, "<tr><td><a href=\"#f%d\">%d</a></td><td>", f->number, f->number);
        mr_xml_escape_into(&x, f->title);
        mr_xml_raw(&x, "</td><td>");
        mr_xml_escape_into(&x, f->mark->node[0] ? f->mark->node : "-");
        mr_xml_raw(&x, "</td><td>");
        mr_xml_escape_into(&x, f->mark->status[0] ? f->mark->status : "open");
        mr_xml_raw(&x, "</td><td>%s</td><td style=\"color:%s\">", d, verdict_colour(f->mark));
        mr_xml_escape_into(&x, vc);
        mr_xml_raw(&x, "</td><td>%s</td><td>%s</td><td>%lld</td><td>%.2f s</td><td>%s</td></tr>\n", u, seen,
                   (long long)f->mark->frame_index, f->mark->timestamp, when);
    }
    mr_xml_raw(&x, "</table>\n<h2>Plan view</h2>\n<p>Seen from above (x to the right, z down the page). "
                   "Pins: the marks, numbered as above (green within tolerance, amber undecided, red out of "
                   "tolerance or not judged); blue: the camera and where it looked.</p>\n");
    plan_svg(&x, fs, p->scene);
    for (int i = 0; i < fs->count; i++) {
        const mr_finding *f = &fs->items[i];
        mr_xml_raw(&x, "<div class=\"f\" id=\"f%d\"><h2><span class=\"n\">%d</span> ", f->number, f->number);
        mr_xml_escape_into(&x, f->title);
        mr_xml_raw(&x, "</h2>\n<p>");
        mr_xml_escape_into(&x, f->description);
        char words[512];
        topic_words(f->mark, words, sizeof words);
        mr_xml_raw(&x, "</p>\n<p>Status: ");
        mr_xml_escape_into(&x, words);
        mr_xml_raw(&x, ".</p>\n<div class=\"pics\">");
        if (overlay[i])
            mr_xml_raw(&x, "<figure><img src=\"img/mark_%d_overlay.png\" alt=\"with the overlay\">"
                           "<figcaption>the plan over the camera picture, as marked (magenta pin: the marked point)"
                           "</figcaption></figure>", f->number);
        mr_xml_raw(&x, "<figure><img src=\"img/mark_%d_photo.png\" alt=\"camera image\">"
                       "<figcaption>the camera picture, undistorted (the BCF snapshot; magenta pin: the marked point)"
                       "</figcaption></figure></div>\n",
                   f->number);
        const double *m = f->mark->world_from_camera.m;
        mr_xml_raw(&x, "<p>Camera at (%.3f, %.3f, %.3f), frame %lld, t = %.2f s", m[3], m[7], m[11],
                   (long long)f->mark->frame_index, f->mark->timestamp);
        if (f->mark->hit)
            mr_xml_raw(&x, "; mark at (%.3f, %.3f, %.3f)", f->mark->world[0], f->mark->world[1], f->mark->world[2]);
        mr_xml_raw(&x, " (scene units).</p></div>\n");
    }
    mr_xml_raw(&x, "</body></html>\n");
    return mr_xml_take(&x, n);
}

static char *md_doc(const mr_findings *fs, const mr_export_params *p, const bool *overlay, size_t *n) {
    mr_xml x;
    memset(&x, 0, sizeof x);
    mr_xml_raw(&x, "# %s\n\n%d finding%s. ", p->title, fs->count, fs->count == 1 ? "" : "s");
    mr_xml_raw(&x, "Distance to the plan: how far the built part is from the planned surface (mm, +- 1 sigma); "
                   "registration: the uncertainty of the model's placement at the mark (mm, 1 sigma); camera to the "
                   "point: how far the camera was from the marked point (m); verdict: the distance judged against the "
                   "tolerance with its 95 %% interval (+- 2 sigma, the registration included): within, out of tolerance, "
                   "or undecided (the interval straddles the limit: measure again, closer or from a wider baseline). "
                   "n/a: not measured or not available.\n\n");
    mr_xml_raw(&x, "| # | finding | part | distance to the plan | verdict | registration | camera to the point | frame | time |\n"
                   "|---|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < fs->count; i++) {
        const mr_finding *f = &fs->items[i];
        char d[64], u[64], seen[64], vc[256];
        verdict_cell(f->mark, vc, sizeof vc);
        fmt_len(f->has_distance, f->distance_m, d, sizeof d);
        dist_sigma(f, d, sizeof d);
        fmt_len(f->has_uncertainty, f->uncertainty_m, u, sizeof u);
        if (f->depth_m >= 0) snprintf(seen, sizeof seen, "%.2f m", f->depth_m);
        else snprintf(seen, sizeof seen, "n/a");
        /* A '|' in a note would end its cell. */
        char title[sizeof f->title];
        snprintf(title, sizeof title, "%s", f->title);
        for (char *c = title; *c; c++)
            if (*c == '|' || *c == '\n') *c = '/';
        mr_xml_raw(&x, "| %d | %s | %s | %s | %s | %s | %s | %lld | %.2f s |\n", f->number, title,
                   f->mark->node[0] ? f->mark->node : "-", d, vc, u, seen, (long long)f->mark->frame_index,
                   f->mark->timestamp);
    }
    mr_xml_raw(&x, "\n![plan view](img/plan.svg)\n");
    for (int i = 0; i < fs->count; i++) {
        const mr_finding *f = &fs->items[i];
        mr_xml_raw(&x, "\n## %d. %s\n\n%s\n\n", f->number, f->title, f->description);
        if (overlay[i]) mr_xml_raw(&x, "![with the overlay](img/mark_%d_overlay.png) ", f->number);
        mr_xml_raw(&x, "![camera image, undistorted](img/mark_%d_photo.png)\n", f->number);
    }
    return mr_xml_take(&x, n);
}

static int rm_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
    (void)st, (void)flag, (void)ftw;
    return remove(path);
}

static void rm_tree(const char *path) { nftw(path, rm_entry, 16, FTW_DEPTH | FTW_PHYS); }

/* True if dir does not exist, is empty, or holds an earlier report. */
static bool replaceable(const char *dir, bool *exists) {
    struct stat st;
    *exists = stat(dir, &st) == 0;
    if (!*exists) return true;
    if (!S_ISDIR(st.st_mode)) return false;
    char m[4200];
    snprintf(m, sizeof m, "%s/" MARKER, dir);
    if (mr_file_exists(m)) return true;
    DIR *d = opendir(dir);
    if (!d) return false;
    bool empty = true;
    struct dirent *e;
    while (empty && (e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) empty = false;
    closedir(d);
    return empty;
}

bool mr_export_report(const char *session_dir, const char *out_dir, const mr_export_params *params, mr_error *err) {
    mr_export_params p = mr_export_params_resolved(params);
    char out[4096];
    snprintf(out, sizeof out, "%s", out_dir);
    size_t ol = strlen(out);
    while (ol > 1 && out[ol - 1] == '/') out[--ol] = 0;
    bool exists = false;
    if (!replaceable(out, &exists))
        return mr_fail(err, MR_ERR_IO, "%s exists and is not an earlier mrcheck report; choose a new folder", out);
    mr_findings fs;
    if (!mr_findings_load(session_dir, &p, &fs, err)) return false;
    char tmp[4200], path[4400];
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld", out, (long)getpid());
    rm_tree(tmp);
    bool *overlay = calloc((size_t)fs.count, sizeof *overlay);
    bool ok = overlay && mr_mkdirs(tmp, err);
    if (!overlay) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    if (ok) ok = write_images(tmp, &fs, &p, overlay, err);
    size_t n = 0;
    char *doc = NULL;
    if (ok) {
        doc = html_doc(&fs, &p, overlay, &n);
        snprintf(path, sizeof path, "%s/index.html", tmp);
        ok = doc ? mr_file_write_atomic(path, doc, n, err) : mr_fail(err, MR_ERR_NOMEM, "out of memory");
        free(doc);
    }
    if (ok) {
        doc = md_doc(&fs, &p, overlay, &n);
        snprintf(path, sizeof path, "%s/report.md", tmp);
        ok = doc ? mr_file_write_atomic(path, doc, n, err) : mr_fail(err, MR_ERR_NOMEM, "out of memory");
        free(doc);
    }
    if (ok) {
        mr_xml x;
        memset(&x, 0, sizeof x);
        mr_xml_raw(&x, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        plan_svg(&x, &fs, p.scene);
        doc = mr_xml_take(&x, &n);
        snprintf(path, sizeof path, "%s/img/plan.svg", tmp);
        ok = doc ? mr_file_write_atomic(path, doc, n, err) : mr_fail(err, MR_ERR_NOMEM, "out of memory");
        free(doc);
    }
    if (ok) {
        snprintf(path, sizeof path, "%s/" MARKER, tmp);
        ok = mr_file_write_atomic(path, "mrcheck export --html\n", 22, err);
    }
    /* Into place: an earlier report is moved aside first, then removed. */
    char old[4300] = "";
    if (ok && exists) {
        snprintf(old, sizeof old, "%s.old.%ld", out, (long)getpid());
        if (rename(out, old) != 0) ok = mr_fail(err, MR_ERR_IO, "cannot replace %s: %s", out, strerror(errno));
    }
    if (ok && rename(tmp, out) != 0) {
        ok = mr_fail(err, MR_ERR_IO, "cannot write %s: %s", out, strerror(errno));
        if (old[0]) rename(old, out);
        old[0] = 0;
    }
    if (old[0]) rm_tree(old);
    if (!ok) rm_tree(tmp);
    free(overlay);
    mr_findings_free(&fs);
    return ok;
}
