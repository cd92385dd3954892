/* mr_test.h — the smallest test harness: CHECK records a failure and goes
 * on; main returns mr_test_finish(). */
#ifndef MR_TEST_H
#define MR_TEST_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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
#endif
