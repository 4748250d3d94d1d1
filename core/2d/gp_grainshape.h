/* gp_grainshape.h -- each grain's own amplitude spectrum (api.md "2D shape", spread): the
 * grains of a specimen vary around a mean spectrum as the grains of a real material do.
 *
 * Law. For grain g and mode n >= 1, D_n = mean_n exp(sigma_n z_n - sigma_n^2 / 2) with
 * sigma_n^2 = ln(1 + cov_n^2): the lognormal law whose mean is mean_n and whose coefficient of
 * variation is cov_n (amplitudes are positive and right-skewed, as those measured on real
 * outlines are; a normal law would need clipping at 0). D_0 = 1 and a mode of mean 0 stays 0.
 * The modes are drawn independently: the outlines' analysis (gp_outline.h) measures one cov per
 * mode and nothing of their correlation.
 *
 * Randomness. z_1 .. z_{nmodes-1} are standard normal draws (gp_rng_gaussian) from the grain's
 * own stream (seed, GP_GRAINSHAPE_STREAM + g), in mode order, one set per try; so a grain's
 * spectrum depends only on (seed, g, its phases), never on the order of work or the thread
 * count, and the same grain drawn again (a refill, the descriptors' pass) gets the same bits.
 * GP_GRAINSHAPE_STREAM = 2^62 is far above the specimen's other streams (0 for the IMC, 1 + i
 * for cell i's phases, i < 10^6 cells).
 *
 * Star shape. A draw is kept when the grain it makes with its phases (the caller's: the cell's
 * random phases, as Sec. 2.3 generates a grain) is star-shaped, by the test of gp_fourier.h
 * (r > 0 on the continuous curve, checked on 4 Np points with a margin). Otherwise all modes
 * are drawn again, up to GP_GRAINSHAPE_TRIES draws. Why redraw and not clip each draw: a
 * clipped draw piles grains at the bound, a redraw only thins the far tail, where there is
 * one; redraws are rare, and clipping rarer still (docs/design/shape.md). If every draw
 * fails, the last one is
 * clipped: pulled toward the mean in log space, D_n = mean_n exp(lambda (sigma_n z_n -
 * sigma_n^2 / 2)) with lambda = 1/2, 1/4, 1/8, 1/16, and the first star-shaped one is kept;
 * failing that, the mean spectrum itself (which the cell filling then handles as without
 * spread). The outcome says which.
 *
 * Threads: the functions keep no state; a gp_fourier plan is used by one thread at a time.
 */
#ifndef GP_GRAINSHAPE_H
#define GP_GRAINSHAPE_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_fourier.h"

#define GP_GRAINSHAPE_STREAM (UINT64_C(1) << 62)
#define GP_GRAINSHAPE_TRIES 8
#define GP_GRAINSHAPE_CLIP_STEPS 4

typedef struct gp_grainshape {
    size_t nmodes;        /* D_0 .. D_{nmodes-1} */
    const double *mean;   /* the mean spectrum (mean[0] = 1, the others >= 0) */
    const double *cov;    /* per mode coefficient of variation (>= 0); NULL: no spread */
    uint64_t seed;        /* the specimen's seed */
} gp_grainshape;

/* how a draw ended */
typedef enum {
    GP_GRAINSHAPE_DRAWN = 0,    /* the first draw was star-shaped */
    GP_GRAINSHAPE_REDRAWN = 1,  /* a later draw was */
    GP_GRAINSHAPE_CLIPPED = 2,  /* every draw failed: a clipped one (or the mean) is used */
} gp_grainshape_outcome;

/* 1 if some cov_n > 0 (grains then differ), else 0. */
int gp_grainshape_varies(const gp_grainshape *gs);

/* Grain g's spectrum into D (gs->nmodes values), judged star-shaped with the phases delta
 * (gs->nmodes values, delta[0] ignored) on f's Np rays (nmodes <= gp_fourier_max_modes(Np));
 * scratch holds Np + nmodes doubles. Without spread D is the mean. *outcome (may be NULL)
 * says how it ended. GP_ERR_INVALID for bad arguments, GP_ERR_NOMEM. */
gp_status gp_grainshape_draw(const gp_grainshape *gs, size_t g, const double *delta,
                             gp_fourier *f, double *scratch, double *D,
                             gp_grainshape_outcome *outcome, gp_error *err);

#endif /* GP_GRAINSHAPE_H */
