/* gp_test.h -- a minimal test harness: CHECK macros that count, and a summary line.
 *
 * Each test program calls its checks from main() and ends with `return gp_test_summary();`,
 * which prints "N passed, N failed" and returns non-zero if anything failed or if no check ran
 * at all ("no check ran": a program that checked nothing must not pass). Failures print
 * file:line and the values involved, so a red CI log says what went wrong.
 */
#ifndef GP_TEST_H
#define GP_TEST_H

#include <math.h>
#include <stdio.h>

static int gp_test_passed_ = 0;
static int gp_test_failed_ = 0;

#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (cond) {                                                                   \
            gp_test_passed_++;                                                        \
        } else {                                                                      \
            gp_test_failed_++;                                                        \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);  \
        }                                                                             \
    } while (0)

/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol)                                                          \
    do {                                                                               \
        double a_ = (double)(a), b_ = (double)(b), t_ = (double)(tol);                 \
        if (fabs(a_ - b_) <= t_) {                                                     \
            gp_test_passed_++;                                                         \
        } else {                                                                       \
            gp_test_failed_++;                                                         \
            fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.17g, %s = %.17g, tol %g\n", \
                    __FILE__, __LINE__, #a, a_, #b, b_, t_);                           \
        }                                                                              \
    } while (0)

/* |a - b| <= rel * max(|a|, |b|) */
#define CHECK_REL(a, b, rel)                                                           \
    do {                                                                               \
        double a_ = (double)(a), b_ = (double)(b), r_ = (double)(rel);                 \
        double m_ = fabs(a_) > fabs(b_) ? fabs(a_) : fabs(b_);                         \
        if (fabs(a_ - b_) <= r_ * m_) {                                                \
            gp_test_passed_++;                                                         \
        } else {                                                                       \
            gp_test_failed_++;                                                         \
            fprintf(stderr, "%s:%d: CHECK_REL failed: %s = %.17g, %s = %.17g, rel %g\n", \
                    __FILE__, __LINE__, #a, a_, #b, b_, r_);                           \
        }                                                                              \
    } while (0)

static inline int gp_test_summary(void)
{
    printf("%d passed, %d failed\n", gp_test_passed_, gp_test_failed_);
    if (gp_test_passed_ + gp_test_failed_ == 0) {
        /* a program that checked nothing proves nothing: a skipped body, a main() that
         * returns early, a loop over an empty table */
        fprintf(stderr, "no check ran: a test program must run at least one CHECK\n");
        return 1;
    }
    return gp_test_failed_ ? 1 : 0;
}

#endif /* GP_TEST_H */
