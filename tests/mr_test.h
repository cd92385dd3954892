/* mr_test.h — the smallest test harness: CHECK records a failure and goes
 * on; main returns mr_test_finish(). */
#ifndef MR_TEST_H
#define MR_TEST_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mr_core.h"

static int mr_test_failures = 0;
static int mr_test_checks = 0;

#define CHECK(cond) do { mr_test_checks++; if (!(cond)) { mr_test_failures++; \
    fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); } } while (0)
#define CHECK_NEAR(a, b, tol) do { double a_ = (a), b_ = (b); mr_test_checks++; \
    if (!(fabs(a_ - b_) <= (tol)) ) { mr_test_failures++; \
    fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.9g, %s = %.9g, tol %g\n", \
            __FILE__, __LINE__, #a, a_, #b, b_, (double)(tol)); } } while (0)
#define CHECK_MSG(cond, ...) do { mr_test_checks++; if (!(cond)) { mr_test_failures++; \
    fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond); \
    fprintf(stderr, __VA_ARGS__); fputc('\n', stderr); } } while (0)

static inline int mr_test_finish(const char *name) {
    printf("%s: %d checks, %d failed\n", name, mr_test_checks, mr_test_failures);
    return mr_test_failures ? 1 : 0;
}
#define MR_TEST_SKIP 77

/* An empty scratch folder $MR_TEST_TMP/name (default /tmp/mrcheck-test/name)
 * into out; false (with a message) if it cannot be made. */
static inline bool mr_test_fresh_dir(const char *name, char *out, size_t n) {
    const char *t = getenv("MR_TEST_TMP");
    snprintf(out, n, "%s/%s", t ? t : "/tmp/mrcheck-test", name);
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", out);
    mr_error err;
    memset(&err, 0, sizeof err);
    if (system(cmd) != 0 || !mr_mkdirs(out, &err)) {
        fprintf(stderr, "%s: cannot make a fresh folder: %s\n", out, err.msg);
        return false;
    }
    return true;
}

/* Under AddressSanitizer no shared library is unloaded in a test. Mesa's GL
 * driver (swrast_dri.so, dlopen'ed through libglvnd) keeps ~240 bytes in its
 * globals for the life of the process; unloaded at exit, they look like a
 * leak from an "<unknown module>" that no LeakSanitizer suppression can name
 * (suppressions match function, file or module names, and the module is
 * gone). Kept loaded, they stay reachable and leak checking stays on for
 * everything else. Each test is one translation unit, so this defines
 * dlclose once per executable; libraries resolve it here first. */
#if defined(__SANITIZE_ADDRESS__)
#define MR_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MR_TEST_ASAN 1
#endif
#endif
#ifdef MR_TEST_ASAN
#ifdef __cplusplus
extern "C"
#endif
int dlclose(void *handle);
int dlclose(void *handle) {
    (void)handle;
    return 0;
}
#endif

/* For main() of a GPU test whose context could not be made: a skip (77)
 * only when the error says there is no device (MR_ERR_NODEVICE; ctest
 * reports it and scripts/test.sh fails on it where deps.sh installed EGL)
 * and nothing before failed; any other error is a failure. */
static inline int mr_test_no_gpu(const char *name, const mr_error *err) {
    if (err->code == MR_ERR_NODEVICE) {
        printf("%s: SKIPPED (GPU part): no GL device (%s)\n", name, err->msg);
        return mr_test_failures ? mr_test_finish(name) : MR_TEST_SKIP;
    }
    fprintf(stderr, "%s: FAILED: cannot create a GL context (%s)\n", name, err->msg);
    mr_test_failures++;
    return mr_test_finish(name);
}
#endif
