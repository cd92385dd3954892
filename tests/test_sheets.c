/* Printable tag sheets and calibration boards (lib/batch sheets.c,
 * page.c): the printed cells are apriltag's own tags; the PNG is detected
 * with every id and each tag's edge at size x dpi within 1 px; the PDF's
 * structure (xref offsets, stream lengths, page count) holds, and, where
 * poppler's pdftoppm is installed, the PDF rendered to an image is detected
 * the same way; the board's PNG gives calibrate's detector every tag at
 * the place board.json says. */
#include "mr_batch.h"
#include "mr_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagStandard41h12.h>

/* The pattern against apriltag_to_image, the library's own picture. */
static void check_pattern(const char *name, apriltag_family_t *(*create)(void), void (*destroy)(apriltag_family_t *)) {
    apriltag_family_t *fam = create();
    const int ids[] = {0, 1, 7, (int)fam->ncodes - 1};
    for (size_t k = 0; k < sizeof ids / sizeof ids[0]; k++) {
        mr_tag_pattern t;
        mr_error err = {0};
        CHECK_MSG(mr_tag_pattern_make(name, ids[k], &t, &err), "%s %d: %s", name, ids[k], err.msg);
        image_u8_t *im = apriltag_to_image(fam, (uint32_t)ids[k]);
        CHECK(t.total_width == im->width && t.width_at_border == fam->width_at_border);
        int diff = 0;
        for (int y = 0; y < im->height && y < MR_TAG_MAX_CELLS; y++)
            for (int x = 0; x < im->width && x < MR_TAG_MAX_CELLS; x++)
                diff += (im->buf[y * im->stride + x] == 0) != (t.cells[y * MR_TAG_MAX_CELLS + x] == 1);
        CHECK_MSG(diff == 0, "%s id %d: %d cells differ from apriltag_to_image", name, ids[k], diff);
        image_u8_destroy(im);
    }
    mr_tag_pattern t;
    CHECK(!mr_tag_pattern_make(name, (int)fam->ncodes, &t, NULL));
    destroy(fam);
}

/* Detects img at full resolution; every id of ids[0..n) once (seen[] counts),
 * each edge of each tag expected_px long within 1 px. */
static void check_detected(const char *what, const mr_image *img, const char *family, double expected_px, int *seen,
                           int first_id, int n) {
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    dp.family = family;
    dp.decimate = 1;
    mr_error err = {0};
    mr_detector *det = mr_detector_create(&dp, &err);
    int count = 0;
    const mr_detection *d = det ? mr_detector_detect(det, img, &count, &err) : NULL;
    CHECK_MSG(d != NULL, "%s: %s", what, err.msg);
    for (int i = 0; d && i < count; i++) {
        const int k = d[i].id - first_id;
        CHECK_MSG(k >= 0 && k < n, "%s: unexpected id %d", what, d[i].id);
        if (k >= 0 && k < n) seen[k]++;
        for (int e = 0; e < 4; e++) {
            const double *a = d[i].corners[e], *b = d[i].corners[(e + 1) % 4];
            double len = hypot(a[0] - b[0], a[1] - b[1]);
            CHECK_MSG(fabs(len - expected_px) <= 1.0, "%s: id %d edge %d is %.2f px, not %.2f", what, d[i].id, e, len,
                      expected_px);
        }
    }
    mr_detector_destroy(&det);
}

/* The PDF's cross-reference table points at each "N 0 obj", each stream
 * is as long as its /Length, and there are `pages` page objects. */
static void check_pdf(const char *path, int pages) {
    size_t n = 0;
    char *s = mr_file_read(path, &n, 0, NULL);
    CHECK_MSG(s != NULL, "cannot read %s", path);
    if (!s) return;
    CHECK(n > 20 && memcmp(s, "%PDF-1.4\n", 9) == 0);
    char *sx = NULL;
    for (char *p = s; (p = strstr(p, "startxref\n")); p++) sx = p;
    CHECK_MSG(sx != NULL, "no startxref");
    size_t xref = sx ? strtoul(sx + 10, NULL, 10) : 0;
    CHECK_MSG(xref < n && strncmp(s + xref, "xref\n0 ", 7) == 0, "startxref %zu does not point at the xref", xref);
    if (xref < n && strncmp(s + xref, "xref\n0 ", 7) == 0) {
        char *e;
        long count = strtol(s + xref + 7, &e, 10);
        CHECK(count >= 5 && *e == '\n');
        const char *row = e + 1;
        CHECK(strncmp(row, "0000000000 65535 f \n", 20) == 0);
        for (long i = 1; i < count; i++) {
            row += 20;
            CHECK_MSG(strlen(row) >= 20 && strncmp(row + 10, " 00000 n \n", 10) == 0,
                      "xref row %ld malformed", i);
            size_t off = strtoul(row, NULL, 10);
            char want[32];
            int wl = snprintf(want, sizeof want, "%ld 0 obj\n", i);
            CHECK_MSG(off < n && strncmp(s + off, want, (size_t)wl) == 0, "xref: object %ld is not at %zu", i, off);
        }
        CHECK(strstr(row + 20, "trailer\n<< /Size ") == row + 20);
        char size_s[32];
        snprintf(size_s, sizeof size_s, "/Size %ld ", count);
        CHECK(strstr(s + xref, size_s) != NULL);
    }
    int streams = 0, page_objs = 0;
    for (char *p = s; (p = strstr(p, "/Length ")); p++) {
        size_t len = strtoul(p + 8, NULL, 10);
        char *st = strstr(p, ">>\nstream\n");
        CHECK(st != NULL);
        if (!st) break;
        st += 10;
        CHECK_MSG((size_t)(st - s) + len + 10 <= n && strncmp(st + len, "\nendstream", 10) == 0,
                  "stream %d: /Length %zu does not end at endstream", streams, len);
        streams++;
    }
    for (char *p = s; (p = strstr(p, "/Type /Page ")); p++) page_objs++;
    CHECK_MSG(page_objs == pages && streams == pages, "%d page objects and %d streams, not %d", page_objs, streams,
              pages);
    CHECK(strstr(s, "/BaseFont /Helvetica") != NULL);
    free(s);
}

static bool have_pdftoppm(void) { return system("command -v pdftoppm >/dev/null 2>&1") == 0; }

static void test_tags(void) {
    char dir[4096], path[4300];
    if (!mr_test_fresh_dir("sheets_tags", dir, sizeof dir)) {
        CHECK(false);
        return;
    }
    strcat(dir, "/out");
    int *ids = NULL, n = 0;
    CHECK(mr_sheet_ids_parse("0-11", &ids, &n) && n == 12 && ids[11] == 11);
    mr_sheet_params p = MR_SHEET_DEFAULTS;
    p.out_dir = dir;
    p.size_mm = 25;
    p.dpi = 100;
    p.ids = ids;
    p.id_count = n;
    mr_sheet_result r;
    mr_error err = {0};
    CHECK_MSG(mr_sheet_tags(&p, &r, &err), "tags: %s", err.msg);
    CHECK(r.pages >= 2 && r.tags == 12);
    const double px = 25 / 25.4 * 100;
    int seen[12] = {0};
    for (int i = 0; i < r.pages; i++) {
        snprintf(path, sizeof path, "%s/tags-%d.png", dir, i + 1);
        mr_image img;
        CHECK_MSG(mr_image_load(path, 1, &img, &err), "%s: %s", path, err.msg);
        check_detected(path, &img, "tag36h11", px, seen, 0, 12);
        mr_image_free(&img);
    }
    for (int k = 0; k < 12; k++) CHECK_MSG(seen[k] == 1, "id %d detected %d times in the PNGs", k, seen[k]);
    check_pdf(r.pdf, r.pages);

    /* The template: the marker map's format, not a map yet. */
    cJSON *j = mr_json_load(r.json, &err);
    CHECK(j != NULL);
    const cJSON *tags = cJSON_GetObjectItem(j, "tags");
    CHECK(cJSON_GetArraySize(tags) == 12);
    CHECK_NEAR(cJSON_GetObjectItem(j, "tag_size")->valuedouble, 0.025, 1e-12);
    CHECK(cJSON_IsNull(cJSON_GetObjectItem(cJSON_GetArrayItem(tags, 5), "world_from_tag")));
    CHECK(cJSON_GetObjectItem(cJSON_GetArrayItem(tags, 5), "id")->valueint == 5);
    cJSON_Delete(j);
    mr_marker_map mm;
    CHECK(!mr_marker_map_load(r.json, &mm, NULL));

    /* The PDF drawn by another program gives the same tags. */
    if (have_pdftoppm()) {
        int seen_pdf[12] = {0};
        for (int i = 0; i < r.pages; i++) {
            snprintf(path, sizeof path, "pdftoppm -r 100 -gray -png -singlefile -f %d -l %d '%s' '%s/pdf-%d'", i + 1,
                     i + 1, r.pdf, dir, i + 1);
            CHECK_MSG(system(path) == 0, "%s failed", path);
            snprintf(path, sizeof path, "%s/pdf-%d.png", dir, i + 1);
            mr_image img;
            CHECK_MSG(mr_image_load(path, 1, &img, &err), "%s: %s", path, err.msg);
            check_detected(path, &img, "tag36h11", px, seen_pdf, 0, 12);
            mr_image_free(&img);
        }
        for (int k = 0; k < 12; k++) CHECK_MSG(seen_pdf[k] == 1, "id %d detected %d times in the PDF", k, seen_pdf[k]);
    } else {
        printf("test_sheets: pdftoppm not installed (poppler-utils): the PDF is checked by structure only\n");
    }

    /* A second run into the folder is refused; --force writes. */
    CHECK(!mr_sheet_tags(&p, &r, &err) && strstr(err.msg, "--force"));
    p.force = true;
    CHECK(mr_sheet_tags(&p, &r, &err));
    /* Bad input: one line, no folder. */
    snprintf(path, sizeof path, "%s/never", dir);
    p.out_dir = path;
    p.size_mm = 400;
    CHECK(!mr_sheet_tags(&p, &r, &err) && !mr_file_exists(path));
    p.size_mm = 25;
    p.family = "tag16h5";
    ids[0] = 40; /* tag16h5 has 30 ids */
    CHECK(!mr_sheet_tags(&p, &r, &err) && strstr(err.msg, "0..29") && !mr_file_exists(path));
    free(ids);
    CHECK(!mr_sheet_ids_parse("3,3", &ids, &n) && !mr_sheet_ids_parse("5-2", &ids, &n) &&
          !mr_sheet_ids_parse("1,", &ids, &n) && !mr_sheet_ids_parse("x", &ids, &n));
    CHECK(mr_sheet_ids_parse("0,3,7-9", &ids, &n) && n == 5 && ids[4] == 9);
    free(ids);
}

/* The board: calibrate's photo reader and detector (mr_detect_each) find
 * every tag, each corner where board.json puts it at dpi / 25.4 px per mm
 * (one offset for all). */
typedef struct board_seen {
    const mr_marker_map *map;
    double scale;               /* px per metre */
    int found;
    double off[2];
    double worst;
    int bad_ids;
} board_seen;

static bool on_board(void *user, const mr_frame *f, const mr_detection *d, int n, mr_error *err) {
    (void)f;
    (void)err;
    board_seen *b = user;
    /* The page offset: the mean over all corners (each cell edge is
     * rounded to a pixel, so one corner alone is off by up to 0.5 px). */
    double sum[2] = {0, 0};
    int m = 0;
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1 && m) {
            b->off[0] = sum[0] / m;
            b->off[1] = sum[1] / m;
        }
        for (int i = 0; i < n; i++) {
            const mr_marker *mk = mr_marker_map_find(b->map, d[i].id);
            if (!mk) {
                b->bad_ids += pass;
                continue;
            }
            b->found += pass;
            mr_dvec3 c[4];
            mr_marker_corners_world(b->map, mk, c);
            for (int k = 0; k < 4; k++) {
                double ex = d[i].corners[k][0] - b->scale * c[k].x, ey = d[i].corners[k][1] - b->scale * c[k].y;
                if (pass == 0) {
                    sum[0] += ex;
                    sum[1] += ey;
                    m++;
                    continue;
                }
                double e = hypot(ex - b->off[0], ey - b->off[1]);
                if (e > b->worst) b->worst = e;
            }
        }
    }
    return true;
}

static void test_board(void) {
    char dir[4096], path[4300];
    if (!mr_test_fresh_dir("sheets_board", dir, sizeof dir)) {
        CHECK(false);
        return;
    }
    mr_sheet_params p = MR_SHEET_DEFAULTS;
    p.out_dir = dir;
    p.dpi = 100;
    mr_sheet_result r;
    mr_error err = {0};
    CHECK_MSG(mr_sheet_board(&p, &r, &err), "board: %s", err.msg);
    CHECK(r.cols >= 4 && r.rows >= 5 && r.tags == r.cols * r.rows);
    check_pdf(r.pdf, 1);
    mr_marker_map map;
    CHECK_MSG(mr_marker_map_load(r.json, &map, &err), "%s", err.msg);
    CHECK(map.count == r.tags && fabs(map.tag_size - 0.030) < 1e-12);
    snprintf(path, sizeof path, "%s/board.png", dir);
    board_seen b = {.map = &map, .scale = 100 / 0.0254};
    int skipped = 0;
    CHECK_MSG(mr_detect_each(path, map.family, "test", on_board, &b, &skipped, &err), "%s", err.msg);
    CHECK_MSG(b.found == map.count && b.bad_ids == 0, "board: %d of %d tags found, %d others", b.found, map.count,
              b.bad_ids);
    CHECK_MSG(b.worst <= 1.0, "board: a corner lies %.2f px from where board.json puts it", b.worst);
    /* Tags on the page pitch apart, in rows: board.json agrees. */
    CHECK_NEAR(map.tags[1].world_from_tag.m[3] - map.tags[0].world_from_tag.m[3], r.pitch_mm / 1000, 1e-12);
    CHECK_NEAR(map.tags[r.cols].world_from_tag.m[7], r.pitch_mm / 1000, 1e-12);
    mr_marker_map_free(&map);
    /* Too many tags for the paper: refused, no files. */
    snprintf(path, sizeof path, "%s/never", dir);
    p.out_dir = path;
    p.cols = 40;
    CHECK(!mr_sheet_board(&p, &r, &err) && strstr(err.msg, "do not fit") && !mr_file_exists(path));
}

int main(void) {
    check_pattern("tag36h11", tag36h11_create, tag36h11_destroy);
    check_pattern("tag16h5", tag16h5_create, tag16h5_destroy);
    check_pattern("tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy);
    test_tags();
    test_board();
    return mr_test_finish("test_sheets");
}
