/* Frame sources behind one interface: image files and folders here, video
 * files in video.cc, V4L2 in v4l2.c, recordings (lib/session) through
 * mr_source_ops. */
#include "track_internal.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

struct mr_source {
    mr_source_ops ops;
    void *impl;
};

mr_source *mr_source_from_ops(const mr_source_ops *ops, void *impl, mr_error *err) {
    mr_source *s = calloc(1, sizeof *s);
    if (!s) {
        if (ops->close) ops->close(impl);
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    s->ops = *ops;
    s->impl = impl;
    return s;
}

void mr_source_close(mr_source **src) {
    if (!src || !*src) return;
    if ((*src)->ops.close) (*src)->ops.close((*src)->impl);
    free(*src);
    *src = NULL;
}

const char *mr_source_kind(const mr_source *src) { return src->ops.kind; }

mr_read_status mr_source_read(mr_source *src, mr_frame *frame, mr_error *err) {
    return src->ops.read(src->impl, frame, err);
}

/* ----------------------------------------------------------- image files */

typedef struct image_seq {
    char dir[2048];
    char **names;
    int count, next;
    double fps;
    bool gray;
    mr_image img;
} image_seq;

static bool is_image_name(const char *n) {
    const char *e = strrchr(n, '.');
    if (!e || n[0] == '.') return false;
    static const char *const exts[] = {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".pnm", ".bmp", ".tga"};
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; i++)
        if (strcasecmp(e, exts[i]) == 0) return true;
    return false;
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

bool mr_image_folder_list(const char *dir, char ***names, int *count, mr_error *err) {
    *names = NULL;
    *count = 0;
    DIR *d = opendir(dir);
    if (!d) return mr_fail(err, MR_ERR_IO, "%s: cannot open the folder", dir);
    int cap = 0;
    bool ok = true;
    struct dirent *e;
    while (ok && (e = readdir(d))) {
        if (!is_image_name(e->d_name)) continue;
        if (*count == cap) {
            cap = cap ? 2 * cap : 64;
            char **nn = realloc(*names, (size_t)cap * sizeof *nn);
            if (!nn) ok = false;
            else *names = nn;
        }
        if (ok && !((*names)[*count] = strdup(e->d_name))) ok = false;
        if (ok) (*count)++;
    }
    closedir(d);
    if (!ok) {
        mr_image_folder_free(names, *count);
        *count = 0;
        return mr_fail(err, MR_ERR_NOMEM, "out of memory listing %s", dir);
    }
    if (*count) qsort(*names, (size_t)*count, sizeof **names, cmp_str);
    return true;
}

void mr_image_folder_free(char ***names, int count) {
    if (!names || !*names) return;
    for (int i = 0; i < count; i++) free((*names)[i]);
    free(*names);
    *names = NULL;
}
static void seq_close(void *impl) {
    image_seq *s = impl;
    for (int i = 0; i < s->count; i++) free(s->names[i]);
    free(s->names);
    mr_image_free(&s->img);
    free(s);
}

static mr_read_status seq_read(void *impl, mr_frame *frame, mr_error *err) {
    image_seq *s = impl;
    while (s->next < s->count) {
        int i = s->next++;
        char path[4096];
        mr_path_join(s->dir, s->names[i], path, sizeof path);
        mr_image_free(&s->img);
        mr_error e = {0};
        if (!mr_image_load(path, s->gray ? 1 : 3, &s->img, &e)) {
            /* A damaged file in a sequence: say so and go on. */
            mr_log(MR_LOG_WARN, "skipping frame %d: %s", i, e.msg);
            continue;
        }
        memset(frame, 0, sizeof *frame);
        frame->image = s->img;
        frame->index = i;
        frame->timestamp = i / s->fps;
        snprintf(frame->name, sizeof frame->name, "%s", s->names[i]);
        return MR_READ_FRAME;
    }
    (void)err;
    return MR_READ_END;
}

static const mr_source_ops k_seq_ops = {"images", seq_read, seq_close};

static mr_source *open_images(const char *uri, bool is_dir, const mr_source_params *p, mr_error *err) {
    image_seq *s = calloc(1, sizeof *s);
    if (!s) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    s->fps = p->fps > 0 ? p->fps : 30.0;
    s->gray = p->gray;
    if (!is_dir) {
        mr_path_dir(uri, s->dir, sizeof s->dir);
        const char *base = strrchr(uri, '/');
        s->names = malloc(sizeof *s->names);
        if (s->names) s->names[0] = strdup(base ? base + 1 : uri);
        if (!s->names || !s->names[0]) {
            free(s->names);
            s->names = NULL;
            seq_close(s);
            mr_fail(err, MR_ERR_NOMEM, "out of memory");
            return NULL;
        }
        s->count = 1;
        return mr_source_from_ops(&k_seq_ops, s, err);
    }
    snprintf(s->dir, sizeof s->dir, "%s", uri);
    if (!mr_image_folder_list(uri, &s->names, &s->count, err)) {
        seq_close(s);
        return NULL;
    }
    if (s->count == 0) {
        seq_close(s);
        mr_fail(err, MR_ERR_INVALID, "%s: no image files (png, jpg, pgm, ppm, bmp) in the folder", uri);
        return NULL;
    }
    return mr_source_from_ops(&k_seq_ops, s, err);
}

/* ----------------------------------------------------------- video files */

typedef struct video_src {
    mr_cv_video *v;
    bool gray;
    int64_t index;
    mr_image img;
} video_src;

static void video_close(void *impl) {
    video_src *s = impl;
    mr_cv_video_close(s->v);
    mr_image_free(&s->img);
    free(s);
}

static mr_read_status video_read(void *impl, mr_frame *frame, mr_error *err) {
    video_src *s = impl;
    double t = 0;
    int r = mr_cv_video_read(s->v, s->gray, &s->img, &t, err);
    if (r <= 0) return r == 0 ? MR_READ_END : MR_READ_ERROR;
    memset(frame, 0, sizeof *frame);
    frame->image = s->img;
    frame->index = s->index++;
    frame->timestamp = t;
    return MR_READ_FRAME;
}

static const mr_source_ops k_video_ops = {"video", video_read, video_close};

/* -------------------------------------------------------------- dispatch */

mr_source *mr_source_open(const char *uri, const mr_source_params *params, mr_error *err) {
    mr_source_params p = params ? *params : (mr_source_params)MR_SOURCE_DEFAULTS;
    if (!uri || !uri[0]) {
        mr_fail(err, MR_ERR_INVALID, "no input given");
        return NULL;
    }
    if (strncmp(uri, "/dev/", 5) == 0) return mr_source_open_v4l2(uri, &p, err);
    struct stat st;
    if (stat(uri, &st) != 0) {
        mr_fail(err, MR_ERR_IO, "%s: no such file or folder", uri);
        return NULL;
    }
    if (S_ISCHR(st.st_mode)) return mr_source_open_v4l2(uri, &p, err);
    if (S_ISDIR(st.st_mode)) return open_images(uri, true, &p, err);
    if (st.st_size == 0) {
        mr_fail(err, MR_ERR_PARSE, "%s: empty file", uri);
        return NULL;
    }
    if (is_image_name(uri)) return open_images(uri, false, &p, err);
    video_src *s = calloc(1, sizeof *s);
    if (!s) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    s->gray = p.gray;
    s->v = mr_cv_video_open(uri, err);
    if (!s->v) {
        free(s);
        return NULL;
    }
    return mr_source_from_ops(&k_video_ops, s, err);
}
