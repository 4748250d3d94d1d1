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

#endif /* GP_PROGRESS_H */
