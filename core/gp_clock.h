/* gp_clock.h -- the monotonic clock the pipelines time their phases with.
 *
 * gp_clock_seconds() reads CLOCK_MONOTONIC (POSIX 2008) in seconds from an arbitrary origin:
 * only differences mean anything (the t_* timings of a specimen). A timing is reported, or
 * decides how work is run (gp_team's spin, gp_imc.c's timed stretches), never what is
 * computed, so no result depends on the clock.
 *
 * Header-only (static inline), so that any core module, test or bench may use it without a
 * link dependency. No state; thread-safe.
 */
#ifndef GP_CLOCK_H
#define GP_CLOCK_H

#include <time.h>

static inline double gp_clock_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#endif /* GP_CLOCK_H */
