/* Errors, logging, clocks. */
#include "mr_core.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

/* Messages are single lines: a newline in a formatted message (e.g. from a
 * third-party library's error text) becomes a space. */
static void one_line(char *s) {
    for (; *s; s++)
        if (*s == '\n' || *s == '\r') *s = ' ';
}

bool mr_fail(mr_error *err, mr_err_code code, const char *fmt, ...) {
    if (!err) return false;
    err->code = code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    one_line(err->msg);
    return false;
}

void mr_error_prefix(mr_error *err, const char *fmt, ...) {
    if (!err) return;
    char pre[256], old[sizeof err->msg];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(pre, sizeof pre, fmt, ap);
    va_end(ap);
    memcpy(old, err->msg, sizeof old);
    /* Truncation is acceptable here: the message stays one bounded line. */
    size_t n = strlen(pre);
    if (n > sizeof err->msg - 3) n = sizeof err->msg - 3;
    memcpy(err->msg, pre, n);
    memcpy(err->msg + n, ": ", 2);
    size_t room = sizeof err->msg - n - 3;
    size_t ol = strlen(old);
    if (ol > room) ol = room;
    memcpy(err->msg + n + 2, old, ol);
    err->msg[n + 2 + ol] = 0;
    one_line(err->msg);
}

const char *mr_err_name(mr_err_code code) {
    switch (code) {
    case MR_OK: return "ok";
    case MR_ERR_IO: return "io";
    case MR_ERR_PARSE: return "parse";
    case MR_ERR_INVALID: return "invalid";
    case MR_ERR_NOMEM: return "nomem";
    case MR_ERR_UNSUPPORTED: return "unsupported";
    case MR_ERR_NODEVICE: return "nodevice";
    case MR_ERR_GL: return "gl";
    case MR_ERR_INTERRUPTED: return "interrupted";
    }
    return "unknown";
}

/* The log level is the one piece of process-wide state: it is set once by
 * the application from --verbose/--quiet. */
static mr_log_level g_log_level = MR_LOG_WARN;

void mr_log_set_level(mr_log_level level) { g_log_level = level; }
mr_log_level mr_log_get_level(void) { return g_log_level; }

void mr_log(mr_log_level level, const char *fmt, ...) {
    if (level > g_log_level) return;
    static const char *names[] = {"error", "warning", "info", "debug"};
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fprintf(stderr, "mrcheck: %s: %s\n", names[level], buf);
}

double mr_time_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

size_t mr_peak_rss_bytes(void) {
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (size_t)ru.ru_maxrss * 1024u; /* Linux reports KiB */
}

/* xoshiro256** seeded through splitmix64. */
static uint64_t splitmix64(uint64_t *x) {
    uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

void mr_rng_seed(mr_rng *r, uint64_t seed) {
    for (int i = 0; i < 4; i++) r->s[i] = splitmix64(&seed);
}

uint64_t mr_hash64_mix(uint64_t h, uint64_t w) {
    w *= 0x9E3779B97F4A7C15ull;
    w ^= w >> 29;
    h ^= w;
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 32);
}

uint64_t mr_hash64(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    size_t i = 0;
    /* Four independent lanes over 32-byte blocks, folded into h: one chain
     * of multiplies is latency-bound (2.0 GB/s here against 4.4; a tenth of a
     * second per 10M-triangle scene for the LOD cache key alone). */
    if (n >= 64) {
        /* (Four variables, not an array: kept in registers.) */
        uint64_t l0 = h ^ 0x243F6A8885A308D3ull, l1 = h ^ 0x13198A2E03707344ull, l2 = h ^ 0xA4093822299F31D0ull,
                 l3 = h ^ 0x082EFA98EC4E6C89ull;
        for (; i + 32 <= n; i += 32) {
            uint64_t w0, w1, w2, w3;
            memcpy(&w0, p + i, 8);
            memcpy(&w1, p + i + 8, 8);
            memcpy(&w2, p + i + 16, 8);
            memcpy(&w3, p + i + 24, 8);
            l0 = mr_hash64_mix(l0, w0);
            l1 = mr_hash64_mix(l1, w1);
            l2 = mr_hash64_mix(l2, w2);
            l3 = mr_hash64_mix(l3, w3);
        }
        h = mr_hash64_mix(mr_hash64_mix(mr_hash64_mix(mr_hash64_mix(h, l0), l1), l2), l3);
    }
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        memcpy(&w, p + i, 8);
        h = mr_hash64_mix(h, w);
    }
    uint64_t t = 0;
    for (size_t k = 0; i + k < n; k++) t |= (uint64_t)p[i + k] << (8 * k);
    return mr_hash64_mix(mr_hash64_mix(h, t), (uint64_t)n);
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t mr_rng_u64(mr_rng *r) {
    uint64_t *s = r->s;
    uint64_t result = rotl(s[1] * 5, 7) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

double mr_rng_uniform(mr_rng *r) { return (double)(mr_rng_u64(r) >> 11) * 0x1.0p-53; }

double mr_rng_normal(mr_rng *r) {
    /* Box-Muller; u1 is kept away from 0 so the log stays finite. */
    double u1 = mr_rng_uniform(r), u2 = mr_rng_uniform(r);
    if (u1 < 1e-300) u1 = 1e-300;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}
