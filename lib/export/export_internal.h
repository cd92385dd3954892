/* Private to lib/export: the XML writer and the findings of a session. */
#ifndef MR_EXPORT_INTERNAL_H
#define MR_EXPORT_INTERNAL_H

#include "mr_export.h"

/* ------------------------------------------------------------- XML writer
 * A growing buffer; elements are opened and closed in order, attributes go
 * right after mr_xml_open, text is escaped. Out of memory is remembered and
 * reported by mr_xml_take. */
typedef struct mr_xml {
    char *buf;
    size_t len, cap;
    int depth;
    bool tag_open;     /* "<Name attr=..." written, ">" not yet */
    bool has_child;    /* the open element has child elements (indent its end) */
    bool oom;
    const char *stack[32];
} mr_xml;

void mr_xml_begin(mr_xml *x);                 /* writes the XML declaration */
void mr_xml_open(mr_xml *x, const char *name);
void mr_xml_attr(mr_xml *x, const char *name, const char *value);
void mr_xml_close(mr_xml *x);                 /* closes the innermost open element */
void mr_xml_text_elem(mr_xml *x, const char *name, const char *text);
void mr_xml_num_elem(mr_xml *x, const char *name, double v);
/* Escaped text (& < > " ', control characters dropped) appended to a plain
 * buffer too: the report's HTML uses it. */
void mr_xml_escape_into(mr_xml *x, const char *text);
void mr_xml_raw(mr_xml *x, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* The document (caller frees) and its length; NULL when out of memory or
 * when elements are still open. Resets x. */
char *mr_xml_take(mr_xml *x, size_t *len);
void mr_xml_free(mr_xml *x);

/* ------------------------------------------------------------- XML reader
 * xml_read.c: a tree of elements (namespace prefixes dropped), their
 * attributes and text (entities decoded, CDATA kept, surrounding white
 * space kept). A DOCTYPE or an entity other than XML's five is refused, so
 * nothing expands; depth and element count are capped. */
typedef struct mr_xml_node {
    char *name;
    char **attrs;                /* name, value, name, value, ... */
    int attr_count;
    char *text;                  /* the element's own text, "" none */
    struct mr_xml_node **children;
    int child_count;
} mr_xml_node;
mr_xml_node *mr_xml_parse(const char *data, size_t size, mr_error *err);
void mr_xml_node_free(mr_xml_node *n);
const mr_xml_node *mr_xml_child(const mr_xml_node *n, const char *name);   /* the first, or NULL */
const char *mr_xml_get_attr(const mr_xml_node *n, const char *name);       /* NULL if absent */
const char *mr_xml_child_text(const mr_xml_node *n, const char *name);     /* NULL if no such child */

/* ------------------------------------------------------------------ BCF */

/* mrcheck's topic types (the mark categories in words, then "Issue" for a
 * mark without one) and statuses. */
#define MR_BCF_TOPIC_TYPE_COUNT 7
#define MR_BCF_TOPIC_STATUS_COUNT 3
extern const char *const mr_bcf_topic_types[MR_BCF_TOPIC_TYPE_COUNT];
extern const char *const mr_bcf_topic_statuses[MR_BCF_TOPIC_STATUS_COUNT];

/* --------------------------------------------------------------- findings */

typedef struct mr_finding {
    const mr_annotation *mark;   /* borrowed from the mr_annotations */
    int number;                  /* 1-based, in file order */
    mr_camera camera;            /* of the raw frame (resized to it) */
    mr_image frame;              /* the raw frame, 8-bit */
    char screen_path[4096];      /* the screen with the overlay, "" none */
    bool has_distance, has_uncertainty;
    double distance_m, uncertainty_m;
    bool has_distance_sigma;     /* the view's Measure (measured_sigma_m) */
    double distance_sigma_m;
    double depth_m;              /* camera to the marked point (hit only), metres */
    char modified[32];           /* xs:dateTime of its last edit, "" never edited */
    char topic_guid[37], viewpoint_guid[37], comment_guid[37];
    char title[200];
    char description[1024];
    char date[32];               /* xs:dateTime, UTC */
} mr_finding;

typedef struct mr_findings {
    mr_annotations marks;
    mr_finding *items;
    int count;
} mr_findings;

/* Reads session_dir's marks and each mark's frame and camera; fails with
 * one line naming the mark when one is unusable, or when there are none. */
bool mr_findings_load(const char *session_dir, const mr_export_params *p, mr_findings *out, mr_error *err);
void mr_findings_free(mr_findings *f);
/* Fills the defaults of a params struct (zero fields). */
mr_export_params mr_export_params_resolved(const mr_export_params *p);

#endif
