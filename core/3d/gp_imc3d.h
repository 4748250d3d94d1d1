/* gp_imc3d.h -- inverse Monte-Carlo (IMC) of a bounded 3D Voronoi tessellation fitted to a law
 * of cell volumes and a law of cell orientations.
 *
 * The 3D generalisation Mollon & Zhao announce in their §7 (shared/papers/mollon-zhao-2012-
 * fourier-voronoi.md): the 2D IMC of gp_imc.h on the cells of gp_voronoi3d.h.
 *
 * Targets. Cell volumes follow a law of gp_law.h (lognormal, normal, uniform, or any law the
 * caller builds) whose mean must be the container's volume / N (or any mean, with scale_law).
 * A cell's orientation is the angle theta between its longest axis -- the principal axis of its
 * inertia tensor with the least moment -- and a given unit axis; axes are lines, so the value
 * is c = |cos theta| in [0, 1]. The orientation law: density on the sphere proportional to
 * 1 + k P2(cos theta), P2(x) = (3 x^2 - 1) / 2, the sphere's analogue of the circle's cosine
 * law of gp_law.h; for c
 *     f(c) = 1 + k (3 c^2 - 1) / 2,   F(c) = c + k (c^3 - c) / 2   on [0, 1]
 * (an isotropic sphere gives c uniform). As in 2D the anisotropy a in (0, 1] is the ratio of
 * the least density to the largest, (1 - k/2) / (1 + k), so k = 2 (1 - a) / (1 + 2 a): a = 1 is
 * isotropic, a -> 0 puts the long axes along the given axis.
 *
 * Objective: that of the 2D default (gp_imc.h "Objective"), on volumes: the Anderson-Darling
 * excess of the volumes over N's least A^2 plus N (COV / COV_law - 1)^2 (the COV as a sample
 * COV, n - 1), and the excess of the orientations' c; error = max(volumes, orientations / 2);
 * a move is accepted when volumes + orientations / 2 does not increase. Both statistics are
 * kept exactly by gp_adstat.h, set for each changed cell and set back when a move is refused
 * (integer sums: bit for bit). No wall term: a cell's long axis comes from its inertia, which a
 * flat wall does not tie to the wall's direction as it ties the 2D minimum caliper.
 *
 * Step: the next seed of a sweep along the seeds' order; a move of it (40 %: to a point uniform
 * in the union of its cell and its neighbours', a cell chosen by volume -- the paper's move;
 * 40 %: to a point uniform in its own cell; 20 %: anywhere in the container); the cells it
 * changes recomputed (gp_voronoi3d_try_move), the objective updated for them, and the move kept
 * or rolled back. Seeds are drawn uniform in the container (stream 0 of gp_rng for the seed)
 * and numbered along a Morton curve over the container's bounding box, so that neighbouring
 * cells lie close in memory; the steps draw from stream 1.
 *
 * Stopping: at the threshold, at max_steps, "stalled" (no 1 % gain of the error in
 * gp_imc_stall_window(N) steps), cancelled; a single cell stops at once. Progress every 4,096
 * steps (phase "imc").
 *
 * Determinism: the same container, N and params give the same tessellation bit for bit; the
 * run is on one thread (params.threads is accepted and not used: the result cannot depend on
 * it). Thread safety: one run per call, no shared state.
 * Ownership: the caller owns params.law; *out is the caller's (gp_voronoi3d_destroy).
 */
#ifndef GP_IMC3D_H
#define GP_IMC3D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_imc.h"
#include "gp_law.h"
#include "gp_progress.h"
#include "gp_voronoi3d.h"

typedef struct gp_imc3d_params {
    const gp_law *law;   /* the cell volume law (not owned); NULL: lognormal of `cov` with mean
                          * container volume / n */
    int scale_law;       /* 1: only the law's shape counts: it is scaled so that its mean is the
                          * container's volume / n (a law of grains put on cells) */
    double cov;          /* COV of cell volumes when law is NULL, > 0 */
    double axis[3];      /* the orientation law's axis (any length > 0) */
    double anisotropy;   /* in (0, 1]; 1 isotropic */
    double threshold;    /* stop when the error is <= threshold (> 0) */
    long max_steps;      /* >= 0 */
    uint64_t seed;
    int threads;         /* accepted, unused (one thread) */
} gp_imc3d_params;

/* lognormal COV 0.5, axis z, isotropic, the 2D AD default threshold, 10^6 steps, seed 1 */
void gp_imc3d_params_defaults(gp_imc3d_params *p);

/* The orientation law: k of an anisotropy, and F(c) for c = |cos theta| in [0, 1]. */
double gp_orient3d_k(double anisotropy);
double gp_orient3d_cdf(double anisotropy, double c);
/* c = |cos theta| of the longest principal axis (least moment) of the symmetric inertia tensor
 * I (row-major 3 x 3) against the unit vector axis; NAN if I is not finite. */
double gp_orient3d_cos(const double I[9], const double axis[3]);
/* The KS distance of n values c (sorted in place) to F of the anisotropy. */
double gp_orient3d_ks(double *c, size_t n, double anisotropy);

typedef struct gp_imc3d_report {
    long steps, accepted;
    double error, error_initial;
    double error_volume, error_orient; /* the two excesses at the end (orientations unhalved) */
    gp_imc_stop stop_reason;
    double t_init;       /* seconds to place the seeds and build the first tessellation */
} gp_imc3d_report;

/* Runs the IMC with n cells in container c. Returns GP_OK at the threshold;
 * GP_ERR_NOT_CONVERGED at max_steps, stalled or for one cell; GP_ERR_CANCELLED (*cancel non-zero
 * or progress returned non-zero) -- in these three cases *out is the tessellation as it stands;
 * other errors (GP_ERR_INVALID for bad params or container, GP_ERR_NOMEM) leave *out NULL. */
gp_status gp_imc3d_run(const gp_voronoi3d_container *c, size_t n, const gp_imc3d_params *p,
                       gp_progress_fn progress, void *user, const volatile int *cancel,
                       gp_voronoi3d **out, gp_imc3d_report *rep, gp_error *err);

#endif /* GP_IMC3D_H */
