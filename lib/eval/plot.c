/* The one SVG plot writer of every bench: x-y plots (lines and/or markers,
 * linear or logarithmic axes, fixed or data ranges, a legend and notes) and
 * horizontal bar charts, sharing the text buffer, the XML escaping, the
 * palette and the atomic write. */
#include "mr_eval.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 16 distinguishable colours, so a plot with up to 16 series never repeats one. */
static const char *const k_colors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                       "#bcbd22", "#17becf", "#393b79", "#ad494a", "#637939", "#843c39", "#7b4173", "#000000"};

typedef struct svg {
    char *o;
    size_t len, cap;
    bool oom;
} svg;

static void out(svg *s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void out(svg *s, const char *fmt, ...) {
    if (s->oom) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(s->o ? s->o + s->len : NULL, s->o ? s->cap - s->len : 0, fmt, ap);
        va_end(ap);
        if (n < 0) {
            s->oom = true;
            return;
        }
        if (s->o && s->len + (size_t)n < s->cap) {
            s->len += (size_t)n;
            return;
        }
        size_t cap = s->cap ? s->cap : 16384;
        while (cap <= s->len + (size_t)n) cap *= 2;
        char *b = realloc(s->o, cap);
        if (!b) {
            s->oom = true;
            return;
        }
        s->o = b;
        s->cap = cap;
    }
}

/* Text content and attribute values: & < > " escaped, so any title, file
 * name or series name keeps the SVG well-formed. */
static void text(svg *s, const char *t) {
    for (const char *p = t ? t : ""; *p; p++) {
        switch (*p) {
        case '&': out(s, "&amp;"); break;
        case '<': out(s, "&lt;"); break;
        case '>': out(s, "&gt;"); break;
        case '"': out(s, "&quot;"); break;
        default: out(s, "%c", *p);
        }
    }
}

static bool finish(svg *s, const char *path, mr_error *err) {
    out(s, "</svg>\n");
    bool ok = s->oom ? mr_fail(err, MR_ERR_NOMEM, "plot: out of memory") : mr_file_write_atomic(path, s->o, s->len, err);
    free(s->o);
    return ok;
}

static void begin(svg *s, int w, int h, int x, const char *title) {
    out(s, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" font-size=\"12\">\n", w, h);
    out(s, "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n<text x=\"%d\" y=\"22\" font-size=\"14\">", x);
    text(s, title);
    out(s, "</text>\n");
}

/* ------------------------------------------------------------- x-y plot */

/* A point is drawn when both coordinates are finite and, on a log axis,
 * positive; it is then mapped to the axis value (log10 on a log axis). */
static bool axis_value(double v, bool log_axis, double *a) {
    if (!isfinite(v) || (log_axis && !(v > 0))) return false;
    *a = log_axis ? log10(v) : v;
    return true;
}

bool mr_plot_write(const char *path, const mr_plot_params *params, const mr_plot_series *series, int nseries, mr_error *err) {
    const mr_plot_params p = params ? *params : (mr_plot_params){0};
    const bool lx = p.log_x, ly = p.log_y;
    /* Data range over the drawable points; a linear y axis starts at 0
     * unless the data go below it, and gets 5% headroom. */
    double x0 = INFINITY, x1 = -INFINITY, y0 = ly ? INFINITY : 0, y1 = -INFINITY;
    for (int s = 0; s < nseries; s++)
        for (int i = 0; i < series[s].count; i++) {
            double xv, yv;
            if (!axis_value(series[s].x[i], lx, &xv) || !axis_value(series[s].y[i], ly, &yv)) continue;
            x0 = fmin(x0, xv);
            x1 = fmax(x1, xv);
            y0 = fmin(y0, yv);
            y1 = fmax(y1, yv);
        }
    if (!(x1 >= x0)) { x0 = 0; x1 = 1; }
    if (!(y1 > y0)) y1 = y0 + 1;
    if (x1 - x0 < 1e-9) { x0 -= 0.5; x1 += 0.5; }
    if (ly) { /* 5% margins on both sides of the decades */
        double m = 0.05 * (y1 - y0);
        y0 -= m;
        y1 += m;
    } else y1 *= 1.05;
    double fx0, fx1, fy0, fy1; /* fixed ranges, as axis values */
    if (p.x_max > p.x_min && axis_value(p.x_min, lx, &fx0) && axis_value(p.x_max, lx, &fx1)) x0 = fx0, x1 = fx1;
    if (p.y_max > p.y_min && axis_value(p.y_min, ly, &fy0) && axis_value(p.y_max, ly, &fy1)) y0 = fy0, y1 = fy1;
    const int W = p.width > 0 ? p.width : 760, H = p.height > 0 ? p.height : 480, L = 70,
              R = p.legend_width > 0 ? p.legend_width : 170, T = 40, B = 50;
    const double pw = W - L - R, ph = H - T - B;
    svg o = {0};
    begin(&o, W, H, L, p.title);
    out(&o, "<rect x=\"%d\" y=\"%d\" width=\"%.0f\" height=\"%.0f\" fill=\"none\" stroke=\"#444\"/>\n", L, T, pw, ph);
    for (int k = 0; k <= 4; k++) {
        double fx = x0 + (x1 - x0) * k / 4, fy = y0 + (y1 - y0) * k / 4;
        double px = L + pw * k / 4, py = T + ph - ph * k / 4;
        out(&o, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.3g</text>\n", px, H - B + 16, lx ? pow(10, fx) : fx);
        out(&o, "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%.3g</text>\n", L - 6, py + 4, ly ? pow(10, fy) : fy);
        out(&o, "<line x1=\"%d\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", L, py, L + pw, py);
    }
    out(&o, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">", L + pw / 2, H - 12);
    text(&o, p.xlabel);
    out(&o, "</text>\n<text x=\"16\" y=\"%.1f\" transform=\"rotate(-90 16 %.1f)\" text-anchor=\"middle\">", T + ph / 2, T + ph / 2);
    text(&o, p.ylabel);
    out(&o, "</text>\n");
    int legend = 0;
    for (int s = 0; s < nseries; s++) {
        const mr_plot_series *se = &series[s];
        const char *col = se->color ? se->color : k_colors[s % 16];
        if (!se->no_line) {
            out(&o, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\"%s points=\"", col,
                se->dashed ? " stroke-dasharray=\"6 4\"" : "");
            for (int i = 0; i < se->count; i++) {
                double xv, yv;
                if (!axis_value(se->x[i], lx, &xv) || !axis_value(se->y[i], ly, &yv)) continue;
                out(&o, "%.1f,%.1f ", L + pw * (xv - x0) / (x1 - x0), T + ph - ph * (yv - y0) / (y1 - y0));
            }
            out(&o, "\"/>\n");
        }
        const char *fill = se->hollow ? "white" : col;
        for (int i = 0; i < se->count && se->mark != MR_PLOT_MARK_NONE; i++) {
            double xv, yv;
            if (!axis_value(se->x[i], lx, &xv) || !axis_value(se->y[i], ly, &yv)) continue;
            double cx = L + pw * (xv - x0) / (x1 - x0), cy = T + ph - ph * (yv - y0) / (y1 - y0);
            if (se->mark == MR_PLOT_MARK_SQUARE)
                out(&o, "<rect x=\"%.1f\" y=\"%.1f\" width=\"7\" height=\"7\" fill=\"%s\" stroke=\"%s\"/>\n", cx - 3.5,
                    cy - 3.5, fill, col);
            else if (se->hollow)
                out(&o, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\" stroke=\"%s\"/>\n", cx, cy, fill, col);
            else out(&o, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\"/>\n", cx, cy, col);
            if (se->point_label) {
                out(&o, "<text x=\"%.1f\" y=\"%.1f\" fill=\"%s\" font-size=\"10\">", cx + 5, cy - 4, col);
                text(&o, se->point_label);
                out(&o, "</text>\n");
            }
        }
        if (!se->name || !se->name[0]) continue; /* no legend entry */
        out(&o, "<rect x=\"%.0f\" y=\"%d\" width=\"12\" height=\"10\" fill=\"%s\"/><text x=\"%.0f\" y=\"%d\">", L + pw + 14,
            T + 8 + 18 * legend, col, L + pw + 30, T + 17 + 18 * legend);
        text(&o, se->name);
        out(&o, "</text>\n");
        legend++;
    }
    for (int k = 0; k < p.note_count; k++) {
        out(&o, "<text x=\"%.0f\" y=\"%d\">", L + pw + 14, T + 17 + 18 * (legend + k) + 10);
        text(&o, p.notes[k]);
        out(&o, "</text>\n");
    }
    return finish(&o, path, err);
}

bool mr_plot_svg(const char *path, const char *title, const char *xlabel, const char *ylabel,
                 const mr_plot_series *series, int nseries, bool log_x, mr_error *err) {
    mr_plot_params p = {.title = title, .xlabel = xlabel, .ylabel = ylabel, .log_x = log_x};
    return mr_plot_write(path, &p, series, nseries, err);
}

/* ------------------------------------------------------------ bar chart */

bool mr_plot_bars(const char *path, const char *title, const char *const *categories, int count, const mr_plot_bar_set *sets,
                  int nsets, mr_error *err) {
    double maxv = 1e-9;
    for (int k = 0; k < nsets; k++)
        for (int i = 0; i < count; i++)
            if (isfinite(sets[k].v[i]) && sets[k].v[i] > maxv) maxv = sets[k].v[i];
    const int W = 720, bar = 14, row = 16 * (nsets > 0 ? nsets : 1) + 12, top = 50, H = top + row * count + 40, X = 130;
    svg o = {0};
    begin(&o, W, H, 10, title);
    for (int k = 0; k < nsets; k++) {
        const char *col = sets[k].color ? sets[k].color : k_colors[k % 16];
        out(&o, "<rect x=\"%d\" y=\"32\" width=\"12\" height=\"10\" fill=\"%s\"/><text x=\"%d\" y=\"42\">", 470 + 130 * k, col,
            486 + 130 * k);
        text(&o, sets[k].name);
        out(&o, "</text>\n");
    }
    for (int i = 0; i < count; i++) {
        int y = top + i * row;
        out(&o, "<text x=\"10\" y=\"%d\">", y + 4 + 8 * nsets);
        text(&o, categories[i]);
        out(&o, "</text>\n");
        for (int k = 0; k < nsets; k++) {
            double v = sets[k].v[i];
            if (!isfinite(v)) continue; /* nothing to draw; the label row stays */
            double len = 480.0 * fmax(v, 0) / maxv;
            const char *col = sets[k].color ? sets[k].color : k_colors[k % 16];
            out(&o, "<rect x=\"%d\" y=\"%d\" width=\"%.1f\" height=\"%d\" fill=\"%s\"/><text x=\"%.1f\" y=\"%d\">%.2f</text>\n", X,
                y + 16 * k, len, bar, col, X + 6 + len, y + 16 * k + 12, v);
        }
    }
    return finish(&o, path, err);
}
