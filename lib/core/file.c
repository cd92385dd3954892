/* Whole-file reads, atomic writes, paths. */
#include "mr_core.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

void *mr_file_read(const char *path, size_t *size, size_t max_bytes, mr_error *err) {
    if (max_bytes == 0) max_bytes = (size_t)4 << 30;
    FILE *f = fopen(path, "rb");
    if (!f) {
        mr_fail(err, MR_ERR_IO, "cannot open %s: %s", path, strerror(errno));
        return NULL;
    }
    struct stat st;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(f);
        mr_fail(err, MR_ERR_IO, "%s is not a regular file", path);
        return NULL;
    }
    if ((uint64_t)st.st_size > (uint64_t)max_bytes) {
        fclose(f);
        mr_fail(err, MR_ERR_NOMEM, "%s is too large (%lld bytes, limit %zu)", path, (long long)st.st_size, max_bytes);
        return NULL;
    }
    size_t n = (size_t)st.st_size;
    char *buf = malloc(n + 1);
    if (!buf) {
        fclose(f);
        mr_fail(err, MR_ERR_NOMEM, "out of memory reading %s (%zu bytes)", path, n);
        return NULL;
    }
    size_t got = n ? fread(buf, 1, n, f) : 0;
    int rerr = ferror(f);
    fclose(f);
    if (got != n || rerr) {
        free(buf);
        mr_fail(err, MR_ERR_IO, "cannot read %s", path);
        return NULL;
    }
    buf[n] = 0;
    if (size) *size = n;
    return buf;
}

bool mr_file_write_atomic(const char *path, const void *data, size_t size, mr_error *err) {
    char tmp[4096];
    if (snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid()) >= (int)sizeof tmp)
        return mr_fail(err, MR_ERR_IO, "path too long: %s", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) return mr_fail(err, MR_ERR_IO, "cannot write %s: %s", path, strerror(errno));
    bool ok = (size == 0 || fwrite(data, 1, size, f) == size);
    ok = (fflush(f) == 0) && ok;
    /* fsync so a crash right after the rename never leaves an empty file. */
    ok = (fsync(fileno(f)) == 0 || errno == EINVAL) && ok;
    ok = (fclose(f) == 0) && ok;
    if (!ok) {
        int e = errno;
        remove(tmp);
        return mr_fail(err, MR_ERR_IO, "cannot write %s: %s", path, strerror(e));
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        remove(tmp);
        return mr_fail(err, MR_ERR_IO, "cannot write %s: %s", path, strerror(e));
    }
    return true;
}

bool mr_file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

bool mr_mkdirs(const char *path, mr_error *err) {
    char buf[4096];
    size_t n = strlen(path);
    if (n == 0) return true;
    if (n >= sizeof buf) return mr_fail(err, MR_ERR_IO, "path too long: %s", path);
    memcpy(buf, path, n + 1);
    for (size_t i = 1; i <= n; i++) {
        if (buf[i] != '/' && buf[i] != 0) continue;
        char c = buf[i];
        buf[i] = 0;
        if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
            int e = errno;
            return mr_fail(err, MR_ERR_IO, "cannot create folder %s: %s", buf, strerror(e));
        }
        buf[i] = c;
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))
        return mr_fail(err, MR_ERR_IO, "%s exists and is not a folder", path);
    return true;
}

void mr_path_dir(const char *path, char *out, size_t n) {
    const char *slash = strrchr(path, '/');
    if (!slash) { snprintf(out, n, "."); return; }
    size_t len = (size_t)(slash - path);
    if (len == 0) len = 1; /* "/file" -> "/" */
    if (len >= n) len = n - 1;
    memcpy(out, path, len);
    out[len] = 0;
}

void mr_path_join(const char *dir, const char *rel, char *out, size_t n) {
    if (rel[0] == '/' || !dir || !dir[0] || strcmp(dir, ".") == 0) snprintf(out, n, "%s", rel);
    else snprintf(out, n, "%s/%s", dir, rel);
}

bool mr_jsonl_add(mr_jsonl *b, const cJSON *item) {
    char *s = b->failed ? NULL : cJSON_PrintUnformatted(item);
    size_t n = s ? strlen(s) : 0;
    if (s && b->len + n + 2 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + n + 2) cap *= 2;
        char *t = realloc(b->text, cap);
        if (t) {
            b->text = t;
            b->cap = cap;
        } else {
            free(s);
            s = NULL;
        }
    }
    if (!s) return !(b->failed = true);
    memcpy(b->text + b->len, s, n);
    b->len += n;
    b->text[b->len++] = '\n';
    b->text[b->len] = 0;
    free(s);
    return true;
}

bool mr_jsonl_save(const mr_jsonl *b, const char *path, mr_error *err) {
    if (b->failed) return mr_fail(err, MR_ERR_NOMEM, "%s: out of memory", path);
    return mr_file_write_atomic(path, b->text ? b->text : "", b->len, err);
}

void mr_jsonl_free(mr_jsonl *b) {
    free(b->text);
    memset(b, 0, sizeof *b);
}
