/* lib/study's private helpers shared by its analyses and stimuli (not a
 * public header: nothing outside lib/study includes it). */
#ifndef MR_STUDY_INTERNAL_H
#define MR_STUDY_INTERNAL_H

#include "mr_study.h"

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

/* Stimuli: img (ss times the size) averaged down ss x ss and written as
 * dir/method/stim.png (stimuli.c). */
bool mr_study_save_frame(const char *dir, const char *method, const char *stim, const mr_image *img, int ss,
                         mr_error *err);
/* The task family's conditions, scenes and targets (task_scene.c). */
bool mr_study_task_stimuli_render(mr_renderer *r, const mr_study_family *fam, const mr_study_stimuli_params *p, int ss,
                                  const char *dir, int *count, mr_error *err);

#endif
