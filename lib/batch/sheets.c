/* Printable AprilTag sheets and calibration boards (`mrcheck tags`,
 * `mrcheck board`): pages of tags at a physical size, as PDF and PNG, with
 * the marker-map template or the board's marker map beside them. */
#include "mr_batch.h"

#include <ctype.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#define MARGIN_MM 10.0
#define HEADER_MM 12.0 /* two header lines under the top margin */
#define LINE_MM 0.25   /* the scale bar's outline */
#define BAR_H_MM 3.0

#define SP(f) offsetof(mr_sheet_params, f)
const mr_opt mr_sheet_opts[] = {
    {"size-mm", MR_OPT_DOUBLE, SP(size_mm), 5, 1000, 0, NULL,
     "edge of the square the detector finds, mm (tag36h11: the black square; a marker map's tag_size); "
     "tags: required, board: 30", MR_OPT_ZERO_AUTO},
    {"dpi", MR_OPT_DOUBLE, SP(dpi), 30, 1200, 300, NULL, "resolution of the PNGs", 0},
    {"cols", MR_OPT_INT, SP(cols), 2, 100, 0, NULL, "board: tags across (auto: as many as fit)", MR_OPT_ZERO_AUTO},
    {"rows", MR_OPT_INT, SP(rows), 2, 100, 0, NULL, "board: tags down (auto: as many as fit)", MR_OPT_ZERO_AUTO},
    {"first-id", MR_OPT_INT, SP(first_id), 0, 1000000, 100, NULL, "board: the first tag id, then row by row", 0},
    {"gap-mm", MR_OPT_DOUBLE, SP(gap_mm), 0.1, 1000, 0, NULL, "board: between neighbouring squares, mm (auto: a quarter of the size)",
     MR_OPT_ZERO_AUTO},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};

bool mr_sheet_ids_parse(const char *s, int **ids, int *n) {
    *ids = NULL;
    *n = 0;
    if (!s || !*s) return false;
    int cap = 0, count = 0, *v = NULL;
    const char *c = s;
    for (;;) {
        char *e;
        if (!isdigit((unsigned char)*c)) break;
        long a = strtol(c, &e, 10), b = a;
        c = e;
        if (*c == '-') {
            if (!isdigit((unsigned char)c[1])) break;
            b = strtol(c + 1, &e, 10);
            c = e;
        }
        if (a < 0 || b < a || b > 1000000 || b - a > 100000) break;
        for (long k = a; k <= b; k++) {
            for (int i = 0; i < count; i++)
                if (v[i] == k) goto bad;
            if (count == cap) {
                cap = cap ? 2 * cap : 64;
                int *nv = realloc(v, (size_t)cap * sizeof *nv);
                if (!nv) goto bad;
                v = nv;
            }
            v[count++] = (int)k;
        }
        if (*c == 0) {
            *ids = v;
            *n = count;
            return true;
        }
        if (*c != ',') break;
        c++;
    }
bad:
    free(v);
    return false;
}

/* The black cells of a tag with its top-left cell corner at (x, y), one
 * rectangle per run of black cells in a row (no seams between cells). */
static void draw_tag(mr_page *pg, const mr_tag_pattern *t, double x, double y, double cell) {
    const int w = t->total_width;
    for (int r = 0; r < w; r++)
        for (int c = 0; c < w;) {
            if (!t->cells[r * MR_TAG_MAX_CELLS + c]) {
                c++;
                continue;
            }
            int e = c;
            while (e < w && t->cells[r * MR_TAG_MAX_CELLS + e]) e++;
            mr_page_rect(pg, x + c * cell, y + r * cell, (e - c) * cell, cell);
            c = e;
        }
}

/* A 10 cm bar with its top-left at (x, y): an outline, every other
 * centimetre filled, "0" and "10 cm" under its ends. Its outer length is
 * exactly MR_SHEET_SCALE_BAR_MM. */
static void draw_scale_bar(mr_page *pg, double x, double y) {
    const double L = MR_SHEET_SCALE_BAR_MM;
    mr_page_rect(pg, x, y, L, LINE_MM);
    mr_page_rect(pg, x, y + BAR_H_MM - LINE_MM, L, LINE_MM);
    mr_page_rect(pg, x, y, LINE_MM, BAR_H_MM);
    mr_page_rect(pg, x + L - LINE_MM, y, LINE_MM, BAR_H_MM);
    for (int k = 0; k < 10; k += 2) mr_page_rect(pg, x + k * L / 10, y, L / 10, BAR_H_MM);
    mr_page_text(pg, x, y + BAR_H_MM + 3.5, 7, "0");
    mr_page_text(pg, x + L + 2, y + BAR_H_MM, 7, "10 cm: check with a ruler");
}

typedef struct sheet {
    double W, H, dpi;
    const char *family;
    mr_tag_pattern first;   /* the family's geometry */
    double cell;            /* mm per cell */
    double box;             /* a tag's drawn side, quiet zone included, mm */
    double quiet;           /* cells outside the detected square, each side, mm */
    char paper[16];
} sheet;

static bool sheet_setup(const mr_sheet_params *p, sheet *s, int probe_id, mr_error *err) {
    memset(s, 0, sizeof *s);
    const char *paper = p->paper ? p->paper : "a4";
    if (!mr_paper_size(paper, &s->W, &s->H))
        return mr_fail(err, MR_ERR_INVALID, "unknown paper '%.20s' (a4, a3 or letter)", paper);
    snprintf(s->paper, sizeof s->paper, "%s", paper);
    for (char *c = s->paper; *c; c++) *c = (char)toupper((unsigned char)*c);
    if (strcmp(s->paper, "LETTER") == 0) snprintf(s->paper, sizeof s->paper, "Letter");
    s->dpi = p->dpi;
    if (!isfinite(s->dpi) || s->dpi < 30 || s->dpi > 1200)
        return mr_fail(err, MR_ERR_INVALID, "dpi must be in [30, 1200] (got %g)", s->dpi);
    if (!isfinite(p->size_mm) || !(p->size_mm >= 5) || p->size_mm > 1000)
        return mr_fail(err, MR_ERR_INVALID, "the tag size must be in [5, 1000] mm (got %g)", p->size_mm);
    s->family = p->family ? p->family : "tag36h11";
    if (!mr_tag_pattern_make(s->family, probe_id, &s->first, err)) return false;
    s->cell = p->size_mm / s->first.width_at_border;
    s->box = s->cell * s->first.total_width;
    s->quiet = s->cell * (s->first.total_width - s->first.width_at_border) / 2;
    return true;
}

static const char *square_words(const sheet *s) {
    return s->first.total_width == s->first.width_at_border + 2 ? "black square" : "detected square";
}

/* The pages' PNGs, with progress; then the PDF. */
static bool save_pages(const mr_sheet_params *p, const sheet *s, const mr_page *pages, int n, const char *stem,
                       mr_sheet_result *res, mr_error *err) {
    char path[4200];
    snprintf(res->pdf, sizeof res->pdf, "%s/%s.pdf", p->out_dir, stem);
    if (!mr_pdf_save(res->pdf, pages, n, err)) return false;
    for (int i = 0; i < n; i++) {
        if (mr_stop_requested()) return mr_fail(err, MR_ERR_INTERRUPTED, "interrupted after page %d of %d", i, n);
        if (p->progress) fprintf(stderr, "\r%s: page %d/%d   ", stem, i + 1, n);
        if (n == 1) snprintf(path, sizeof path, "%s/%s.png", p->out_dir, stem);
        else snprintf(path, sizeof path, "%s/%s-%d.png", p->out_dir, stem, i + 1);
        mr_image img;
        bool ok = mr_page_raster(&pages[i], s->dpi, &img, err) && mr_page_png_save(path, &img, s->dpi, err);
        mr_image_free(&img);
        if (!ok) return false;
    }
    if (p->progress) fprintf(stderr, "\n");
    return true;
}

static void free_pages(mr_page *pages, int n) {
    for (int i = 0; i < n; i++) mr_page_free(&pages[i]);
    free(pages);
}

static bool sheet_tags(const mr_sheet_params *p, mr_sheet_result *res, mr_error *err);

bool mr_sheet_tags(const mr_sheet_params *p, mr_sheet_result *res, mr_error *err) {
    memset(res, 0, sizeof *res);
    if (!p->out_dir) return mr_fail(err, MR_ERR_INVALID, "no output folder given");
    if (!(p->size_mm > 0)) return mr_fail(err, MR_ERR_INVALID, "the tag size (--size-mm) is required: the printed edge of the black square");
    int *parsed = NULL, nparsed = 0;
    const char *text = p->ids_text ? p->ids_text : "0-11";
    if ((!p->ids || p->id_count < 1) && !mr_sheet_ids_parse(text, &parsed, &nparsed))
        return mr_fail(err, MR_ERR_INVALID, "--ids: expected ids like 0-11 or 0,3,7-9 (each once), got '%.40s'", text);
    mr_sheet_params pp = *p;
    if (parsed) pp.ids = parsed, pp.id_count = nparsed;
    bool ok = sheet_tags(&pp, res, err);
    free(parsed);
    return ok;
}

static bool sheet_tags(const mr_sheet_params *p, mr_sheet_result *res, mr_error *err) {
    sheet s;
    if (!sheet_setup(p, &s, p->ids[0], err)) return false;
    mr_tag_pattern t;
    for (int i = 0; i < p->id_count; i++)
        if (!mr_tag_pattern_make(s.family, p->ids[i], &t, err)) return false;
    /* A slot: the tag, two lines of text, the scale bar, a gap. */
    const double gap = 8, text1 = 5, text2 = 4.5, bar_gap = 2.5;
    const double slot_w = fmax(s.box, MR_SHEET_SCALE_BAR_MM + 36) + gap;
    const double slot_h = s.box + text1 + text2 + bar_gap + BAR_H_MM + 5 + gap;
    const int cols = (int)floor((s.W - 2 * MARGIN_MM + gap) / slot_w);
    const int rows = (int)floor((s.H - 2 * MARGIN_MM - HEADER_MM + gap) / slot_h);
    if (cols < 1 || rows < 1)
        return mr_fail(err, MR_ERR_INVALID, "a %g mm tag (%.0f mm with its quiet zone and scale) does not fit on %s",
                       p->size_mm, fmax(slot_w, slot_h) - gap, s.paper);
    const int per = cols * rows, npages = (p->id_count + per - 1) / per;
    mr_outdir od;
    if (!mr_outdir_create(&od, p->out_dir, p->force, err)) return false;
    mr_page *pages = calloc((size_t)npages, sizeof *pages);
    if (!pages) {
        mr_outdir_abandon(&od);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int pi = 0; pi < npages; pi++) {
        mr_page *pg = &pages[pi];
        pg->width_mm = s.W;
        pg->height_mm = s.H;
        mr_page_text(pg, MARGIN_MM, MARGIN_MM + 3.5, 9, "mrcheck tags: %s, %s %g mm. Page %d of %d, %s.", s.family,
                     square_words(&s), p->size_mm, pi + 1, npages, s.paper);
        mr_page_text(pg, MARGIN_MM, MARGIN_MM + 8, 8, "Print at 100 %% (actual size, no fit to page); check each scale bar.");
        for (int k = 0; k < per && pi * per + k < p->id_count; k++) {
            const int id = p->ids[pi * per + k];
            const double x = MARGIN_MM + (k % cols) * slot_w, y = MARGIN_MM + HEADER_MM + (k / cols) * slot_h;
            mr_tag_pattern_make(s.family, id, &t, NULL);
            draw_tag(pg, &t, x, y, s.cell);
            double ty = y + s.box + text1;
            mr_page_text(pg, x + s.quiet, ty, 11, "id %d   %s", id, s.family);
            ty += text2;
            mr_page_text(pg, x + s.quiet, ty, 8, "%s %g mm", square_words(&s), p->size_mm);
            draw_scale_bar(pg, x + s.quiet, ty + bar_gap);
        }
    }
    res->pages = npages;
    res->tags = p->id_count;
    res->per_page = per;
    bool ok = save_pages(p, &s, pages, npages, "tags", res, err);
    free_pages(pages, npages);
    if (ok) {
        /* The marker map's format, positions to be surveyed. */
        cJSON *j = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "family", s.family);
        cJSON_AddNumberToObject(j, "tag_size", p->size_mm / 1000.0);
        cJSON_AddStringToObject(j, "_note",
                                "tags printed by mrcheck tags; each world_from_tag is to be surveyed: mrcheck map "
                                "builds them from photos (--tag-size as above)");
        cJSON *tags = cJSON_AddArrayToObject(j, "tags");
        for (int i = 0; i < p->id_count; i++) {
            cJSON *o = cJSON_CreateObject();
            cJSON_AddNumberToObject(o, "id", p->ids[i]);
            cJSON_AddNullToObject(o, "world_from_tag");
            cJSON_AddItemToArray(tags, o);
        }
        snprintf(res->json, sizeof res->json, "%s/markers_template.json", p->out_dir);
        ok = mr_json_save(res->json, j, err);
        cJSON_Delete(j);
        snprintf(res->summary, sizeof res->summary, "tags: %d tags on %d page%s (%d a page); wrote %.1500s, %d PNG%s at %g dpi and %.1500s",
                 res->tags, npages, npages == 1 ? "" : "s", per, res->pdf, npages, npages == 1 ? "" : "s", s.dpi, res->json);
    }
    if (!ok && !mr_dir_has_entries(p->out_dir)) mr_outdir_abandon(&od);
    return ok;
}

bool mr_sheet_board(const mr_sheet_params *p, mr_sheet_result *res, mr_error *err) {
    memset(res, 0, sizeof *res);
    if (!p->out_dir) return mr_fail(err, MR_ERR_INVALID, "no output folder given");
    if (p->first_id < 0) return mr_fail(err, MR_ERR_INVALID, "the first id must be >= 0");
    mr_sheet_params bp = *p;
    if (bp.size_mm == 0) bp.size_mm = MR_SHEET_BOARD_DEFAULT_SIZE_MM;
    p = &bp;
    sheet s;
    if (!sheet_setup(p, &s, p->first_id, err)) return false;
    const double gap = p->gap_mm > 0 ? p->gap_mm : p->size_mm / 4;
    if (!isfinite(gap) || gap < 2 * s.quiet - 1e-9)
        return mr_fail(err, MR_ERR_INVALID, "the gap must leave the quiet zones room: at least %g mm", 2 * s.quiet);
    const double pitch = p->size_mm + gap;
    const double avail_w = s.W - 2 * MARGIN_MM, avail_h = s.H - 2 * MARGIN_MM - HEADER_MM - 12;
    const int fit_c = (int)floor((avail_w - 2 * s.quiet + gap) / pitch), fit_r = (int)floor((avail_h - 2 * s.quiet + gap) / pitch);
    const int cols = p->cols > 0 ? p->cols : fit_c, rows = p->rows > 0 ? p->rows : fit_r;
    if (cols < 2 || rows < 2 || cols > fit_c || rows > fit_r)
        return mr_fail(err, MR_ERR_INVALID, "%dx%d tags of %g mm at %g mm pitch do not fit on %s (at most %dx%d)", cols,
                       rows, p->size_mm, pitch, s.paper, fit_c, fit_r);
    mr_tag_pattern t;
    if (!mr_tag_pattern_make(s.family, p->first_id + cols * rows - 1, &t, err)) return false;
    mr_outdir od;
    if (!mr_outdir_create(&od, p->out_dir, p->force, err)) return false;
    mr_page pg = {.width_mm = s.W, .height_mm = s.H};
    const double grid_w = (cols - 1) * pitch + p->size_mm, grid_h = (rows - 1) * pitch + p->size_mm;
    const double x0 = (s.W - grid_w) / 2, y0 = MARGIN_MM + HEADER_MM + s.quiet; /* first square's corner */
    mr_page_text(&pg, MARGIN_MM, MARGIN_MM + 3.5, 9, "mrcheck board: %dx%d %s, ids %d-%d, %s %g mm, pitch %g mm, %s.",
                 cols, rows, s.family, p->first_id, p->first_id + cols * rows - 1, square_words(&s), p->size_mm, pitch,
                 s.paper);
    mr_page_text(&pg, MARGIN_MM, MARGIN_MM + 8, 8, "Print at 100 %% (actual size, no fit to page); check the scale bar; mount flat.");
    mr_marker_map map = {.tag_size = p->size_mm / 1000.0, .count = cols * rows};
    snprintf(map.family, sizeof map.family, "%s", s.family);
    map.tags = calloc((size_t)map.count, sizeof *map.tags);
    if (!map.tags) {
        mr_outdir_abandon(&od);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int r = 0; r < rows; r++)
        for (int c = 0; c < cols; c++) {
            const int k = r * cols + c, id = p->first_id + k;
            mr_tag_pattern_make(s.family, id, &t, NULL);
            draw_tag(&pg, &t, x0 + c * pitch - s.quiet, y0 + r * pitch - s.quiet, s.cell);
            map.tags[k].id = id;
            map.tags[k].world_from_tag = mr_m4_identity();
            map.tags[k].world_from_tag.m[3] = c * pitch / 1000.0;
            map.tags[k].world_from_tag.m[7] = r * pitch / 1000.0;
        }
    const double by = y0 + grid_h + s.quiet + 4;
    draw_scale_bar(&pg, x0, by);
    mr_page_text(&pg, x0, by + BAR_H_MM + 8, 7, "board.json: origin at id %d's centre, x along a row, y down, in metres",
                 p->first_id);
    res->pages = 1;
    res->tags = map.count;
    res->per_page = map.count;
    res->cols = cols;
    res->rows = rows;
    res->pitch_mm = pitch;
    bool ok = save_pages(p, &s, &pg, 1, "board", res, err);
    mr_page_free(&pg);
    if (ok) {
        cJSON *j = mr_marker_map_to_json(&map);
        cJSON *b = cJSON_AddObjectToObject(j, "board");
        cJSON_AddNumberToObject(b, "cols", cols);
        cJSON_AddNumberToObject(b, "rows", rows);
        cJSON_AddNumberToObject(b, "square_mm", p->size_mm);
        cJSON_AddNumberToObject(b, "pitch_mm", pitch);
        cJSON_AddStringToObject(b, "paper", s.paper);
        snprintf(res->json, sizeof res->json, "%s/board.json", p->out_dir);
        ok = mr_json_save(res->json, j, err);
        cJSON_Delete(j);
        snprintf(res->summary, sizeof res->summary, "board: %dx%d tags, pitch %g mm; wrote %.1500s, board.png at %g dpi and %.1500s",
                 cols, rows, pitch, res->pdf, s.dpi, res->json);
    }
    free(map.tags);
    if (!ok && !mr_dir_has_entries(p->out_dir)) mr_outdir_abandon(&od);
    return ok;
}
