/* Runs a fuzz target without libFuzzer, for ctest: every seed file in the
 * corpus folder, then deterministic mutations of them (bit flips, byte
 * overwrites with interesting values, truncations, insertions, splices).
 * Usage: fuzz_X_smoke CORPUS_DIR [ITERATIONS]. A crash fails the test; it
 * says which seed or mutation crashed and saves that input as
 * fuzz-crash-NAME.bin in the working folder, to replay by hand. */
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mr_core.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* What runs now, for the crash handler (which may only write(2)). */
static char g_what[2300], g_crash_path[600];
static const uint8_t *g_input;
static size_t g_input_size;

static void on_crash(int sig) {
    ssize_t r = write(2, g_what, strlen(g_what));
    int fd = open(g_crash_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
        r = write(fd, g_input, g_input_size);
        close(fd);
    }
    (void)r;
    signal(sig, SIG_DFL);
    raise(sig);
}

static void run_one(const uint8_t *data, size_t size) {
    g_input = data;
    g_input_size = size;
    LLVMFuzzerTestOneInput(data, size);
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s CORPUS_DIR [ITERATIONS]\n", argv[0]);
        return 2;
    }
    long iters = argc > 2 ? atol(argv[2]) : 2000;
    uint8_t *seeds[64];
    size_t sizes[64];
    char names[64][256];
    int n = 0;
    DIR *d = opendir(argv[1]);
    if (!d) {
        fprintf(stderr, "cannot open %s\n", argv[1]);
        return 2;
    }
    struct dirent *e;
    while ((e = readdir(d)) && n < 64) {
        if (e->d_name[0] == '.') continue;
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", argv[1], e->d_name);
        size_t sz;
        void *buf = mr_file_read(path, &sz, 1 << 24, NULL);
        if (!buf) continue;
        snprintf(names[n], sizeof names[n], "%s", e->d_name);
        seeds[n] = buf;
        sizes[n++] = sz;
    }
    closedir(d);
    if (n == 0) {
        fprintf(stderr, "no seeds in %s\n", argv[1]);
        return 2;
    }
    const char *self = strrchr(argv[0], '/') ? strrchr(argv[0], '/') + 1 : argv[0];
    snprintf(g_crash_path, sizeof g_crash_path, "fuzz-crash-%s.bin", self);
    static const int sigs[] = {SIGSEGV, SIGILL, SIGABRT, SIGBUS, SIGFPE, SIGTRAP};
    for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; i++) signal(sigs[i], on_crash);
    for (int i = 0; i < n; i++) {
        snprintf(g_what, sizeof g_what, "%s: CRASH on seed %s/%s (input saved as %s)\n", self, argv[1], names[i],
                 g_crash_path);
        run_one(seeds[i], sizes[i]);
    }
    mr_rng rng;
    mr_rng_seed(&rng, 12345);
    static const uint8_t interesting[] = {0, 1, 0x7f, 0x80, 0xff, '"', '[', '{', '-', '9', 'e'};
    for (long it = 0; it < iters; it++) {
        int s = (int)(mr_rng_u64(&rng) % (uint64_t)n);
        size_t sz = sizes[s];
        uint8_t *buf = malloc(sz + 64);
        memcpy(buf, seeds[s], sz);
        int edits = 1 + (int)(mr_rng_u64(&rng) % 4);
        for (int k = 0; k < edits && sz > 0; k++) {
            size_t pos = (size_t)(mr_rng_u64(&rng) % sz);
            switch (mr_rng_u64(&rng) % 5) {
            case 0: buf[pos] ^= (uint8_t)(1u << (mr_rng_u64(&rng) % 8)); break;
            case 1: buf[pos] = interesting[mr_rng_u64(&rng) % sizeof interesting]; break;
            case 2: sz = pos; break;                                   /* truncate */
            case 3:                                                    /* insert a byte */
                memmove(buf + pos + 1, buf + pos, sz - pos);
                buf[pos] = interesting[mr_rng_u64(&rng) % sizeof interesting];
                sz++;
                break;
            default: {                                                 /* splice 4 bytes from elsewhere */
                size_t from = (size_t)(mr_rng_u64(&rng) % sz);
                for (int b = 0; b < 4 && pos + b < sz && from + b < sz; b++) buf[pos + b] = buf[from + b];
            }
            }
            if (sz + 1 >= sizes[s] + 64) break;
        }
        snprintf(g_what, sizeof g_what, "%s: CRASH on mutation %ld of seed %s/%s (input saved as %s)\n", self, it,
                 argv[1], names[s], g_crash_path);
        run_one(buf, sz);
        free(buf);
    }
    for (int i = 0; i < n; i++) free(seeds[i]);
    printf("%s: %d seeds, %ld mutations, no crash\n", argv[0], n, iters);
    return 0;
}
