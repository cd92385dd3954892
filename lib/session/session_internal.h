/* Private to lib/session: the line I/O every .jsonl file shares. */
#ifndef MR_SESSION_INTERNAL_H
#define MR_SESSION_INTERNAL_H

#include "mr_session.h"

/* Writes n bytes at fd (opened O_APPEND) and fsyncs it. 0 on success, else
 * the errno of the failing call; *synced false if it was the fsync. */
int mr_sess_write_line(int fd, const char *line, size_t n, bool *sync_failed);

/* Calls fn for each complete, non-blank line; a last line without '\n' is
 * torn (a crash mid-write): it sets *torn and is not passed on. Lines fn
 * refuses are counted in *bad. */
typedef bool (*mr_sess_line_fn)(void *ctx, const char *line, size_t n);
void mr_sess_for_lines(const char *text, size_t size, mr_sess_line_fn fn, void *ctx, bool *torn, int *bad);

/* cJSON of an object without its trailing newline, as one malloc'd line
 * ending in '\n' (*n its length); NULL when out of memory. */
char *mr_sess_json_line(const cJSON *obj, size_t *n);

/* Makes room for one more element in a growing array (items holding count
 * elements, capacity *cap, doubling from first): returns the array to use
 * from now on, or NULL when out of memory (items is then left as it was). */
void *mr_sess_grow(void *items, int count, int *cap, int first, size_t elem);

/* The pose object annotation lines and snapshot files share:
 * {valid, world_from_camera, tags_seen, rms_px}. */
cJSON *mr_sess_pose_json(bool valid, const mr_dmat4 *world_from_camera, int tags_seen, double rms_px);

#endif
