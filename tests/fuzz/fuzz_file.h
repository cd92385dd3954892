/* fuzz_file.h — for fuzz targets whose parser takes a path, not a buffer:
 * the input is written to a file in a private folder of this process (in
 * /dev/shm where it exists, so thousands of writes stay cheap). */
#ifndef MR_FUZZ_FILE_H
#define MR_FUZZ_FILE_H
#include "mr_core.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char fuzz_dir_path[512];

/* At exit: the folder and what the target wrote into it go. */
static void fuzz_dir_remove(void) {
    DIR *d = opendir(fuzz_dir_path);
    char p[1024];
    for (struct dirent *e; d && (e = readdir(d));) {
        if (e->d_name[0] == '.') continue;
        snprintf(p, sizeof p, "%s/%s", fuzz_dir_path, e->d_name);
        remove(p);
    }
    if (d) closedir(d);
    rmdir(fuzz_dir_path);
}

/* The folder, created on first use ("" if it cannot be). */
static const char *fuzz_dir(void) {
    if (!fuzz_dir_path[0]) {
        const char *base = mr_file_exists("/dev/shm") ? "/dev/shm" : getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
        snprintf(fuzz_dir_path, sizeof fuzz_dir_path, "%s/mrcheck-fuzz-%ld", base, (long)getpid());
        if (mr_mkdirs(fuzz_dir_path, NULL)) atexit(fuzz_dir_remove);
        else fuzz_dir_path[0] = 0;
    }
    return fuzz_dir_path;
}

/* Writes data to fuzz_dir()/name; out receives the path. False on failure. */
static bool fuzz_put(const char *name, const void *data, size_t size, char *out, size_t n) {
    snprintf(out, n, "%s/%s", fuzz_dir(), name);
    FILE *f = fopen(out, "wb");
    if (!f) return false;
    bool ok = fwrite(data, 1, size, f) == size;
    return (fclose(f) == 0) && ok;
}
#endif
