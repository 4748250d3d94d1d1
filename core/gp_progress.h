/* gp_progress.h -- progress reports of a long computation (both pipelines, and IMC).
 *
 * A report names its phase ("tessellation", "imc", "fill", "odec" in 2D; "deposition",
 * "compaction", "relaxation", "tiling" in 3D; "done" at the end), the fraction of the whole job
 * done in [0, 1] (by fixed phase weights), how far its phase has come, and the figures that
 * phase has: IMC or DEM steps, the IMC error, the DEM porosity (by the top-wall height) and
 * stability S_c. A figure a phase does not have is 0.
 *
 * The callback is called at a bounded rate from the computing thread; a non-zero return asks
 * the computation to stop (it then returns GP_ERR_CANCELLED). */
#ifndef GP_PROGRESS_H
#define GP_PROGRESS_H

#include <math.h>

#include "gp_clock.h"

typedef struct gp_progress {
    const char *phase;
    double fraction;
    /* how far the current phase has come, in [0, 1], made roughly proportional to its time
     * (steps or items done of those planned, the log of a converging error or gap), so that
     * a caller can weigh the phases itself (the daemon's progress model, server/progress.h).
     * It only grows within a phase, except when the phase runs again (2D refill passes of
     * "fill" start again from 0). */
    double phase_fraction;
    long steps;
    double error;     /* 2D: the IMC error */
    double porosity;  /* 3D */
    double stability; /* 3D: S_c */
} gp_progress;

typedef int (*gp_progress_fn)(void *user, const gp_progress *p);

/* 1 when a cancel flag (another thread's atomic store; NULL: none) is up. */
static inline int gp_progress_cancelled(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

/* A caller's callback and cancel flag, paced: gp_progress_pace hands report r on at most every
 * GP_PROGRESS_PERIOD seconds (always when forced), its fractions clamped to [0, 1] and a
 * stability that is not finite given as 0. Non-zero when the computation is to stop (the flag
 * is up, or the callback asked). The clock decides only which reports are sent. */
#define GP_PROGRESS_PERIOD 0.05

typedef struct gp_progress_pacer {
    gp_progress_fn fn;          /* NULL: no reports (the cancel flag is still read) */
    void *user;
    const volatile int *cancel; /* may be NULL */
    double last;                /* when the last report was sent (gp_clock_seconds) */
} gp_progress_pacer;

static inline int gp_progress_pace(gp_progress_pacer *c, gp_progress r, int force)
{
    if (gp_progress_cancelled(c->cancel))
        return 1;
    if (!c->fn)
        return 0;
    double t = gp_clock_seconds();
    if (!force && t - c->last < GP_PROGRESS_PERIOD)
        return 0;
    c->last = t;
    r.fraction = r.fraction < 0 ? 0 : (r.fraction > 1 ? 1 : r.fraction);
    r.phase_fraction = r.phase_fraction < 0 ? 0 : (r.phase_fraction > 1 ? 1 : r.phase_fraction);
    r.stability = isfinite(r.stability) ? r.stability : 0;
    return c->fn(c->user, &r) != 0;
}

#endif /* GP_PROGRESS_H */
