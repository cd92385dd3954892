/* lib/study's private helpers shared by its analyses (not a public header:
 * nothing outside lib/study includes it). */
#ifndef MR_STUDY_INTERNAL_H
#define MR_STUDY_INTERNAL_H

#include "mr_core.h"

/* A growing text buffer; an allocation failure sticks (oom) and makes
 * mr_sb_save fail. */
typedef struct mr_sbuf {
    char *s;
    size_t len, cap;
    bool oom;
} mr_sbuf;

void mr_sb_printf(mr_sbuf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Written atomically. */
bool mr_sb_save(mr_sbuf *b, const char *path, mr_error *err);
/* An SVG <text> with its text XML-escaped. */
void mr_svg_text(mr_sbuf *b, double x, double y, const char *anchor, int size, const char *fill, const char *text);

#endif
