/* gp_imc.h -- inverse Monte-Carlo (IMC) constrained Voronoi tessellation, with local updates.
 *
 * Mollon & Zhao 2012 §3.3 (improved algorithm, steps d1-d5), with the corrections of
 * shared/papers/NOTES.md:
 *
 * Targets. Cell area S is lognormal with mean mu = S_D / N (container area over cell count) and
 * standard deviation COV * mu. Cell orientation theta (gp_voronoi_cell_orientation, Fig. 1a) has
 * the pi-periodic density f(theta) = [(1+a)/2 + (1-a)/2 cos(2(theta - theta_bar))] / ((1+a) pi/2),
 * maximal at theta_bar, with min/max ratio a (the anisotropy, in (0, 1]).
 *
 * Classes (histograms are normalised by N: each sums to 1).
 * - Area: k_S classes of equal target probability 1/k_S, the edges being the lognormal quantiles
 *   q_j = F^-1(j / k_S): edges[0] = 0, edges[k_S] = +inf. Every cell falls in a class; none is
 *   outside the range. Equal-probability classes weigh the tails as much as the mode.
 * - Orientation: k_theta classes of equal width 180 / k_theta degrees over [-90, 90); an
 *   orientation th (radians, in (-pi/2, pi/2]) is in class floor((th + pi/2) k_theta / pi) mod
 *   k_theta (so +90 deg is -90 deg); the target of a class is the integral of f over it.
 *
 * Errors (Eqs. 16-18), with h and H the achieved and target normalised histograms:
 *   E1 = (|h_S - H_S|_2 + |h_t - H_t|_2) / 2,  E2 = max(|h_S - H_S|_inf, |h_t - H_t|_inf),
 *   E3 = max(|h_S - H_S|_2, |h_t - H_t|_2)  (the default, threshold 0.002).
 *
 * Error floor (NOTES.md). Counts are integers, so a histogram cannot come closer to its target
 * than the best integer allocation of N cells (largest remainders); about sqrt(k/12)/N for k
 * classes with arbitrary targets. gp_imc_floor() computes it exactly for given classes. With
 * classes_* = 0 the class counts are chosen automatically: the largest k <= min(20, N/25) (and
 * >= 4) whose floor is at most half the threshold (headroom to converge). If the threshold is
 * below the floor of the classes in use, gp_imc_run() stops at once with stop reason "floor"
 * (GP_ERR_INFEASIBLE, message says the floor) instead of running to max_steps.
 *
 * Step (d1-d5): pick a seed uniformly; move it to a point uniform in the union of its cell and
 * its neighbours' cells (a cell chosen by area, then a point uniform in it); update the cells
 * locally (gp_voronoi_try_move); update the class counts of the changed cells; accept if the
 * error strictly decreases, otherwise roll the tessellation back bit for bit.
 *
 * Determinism: the same container, N and params (seed included) give the same tessellation bit
 * for bit. Thread-safety: one run per call, no shared state.
 */
#ifndef GP_IMC_H
#define GP_IMC_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_geom.h"
#include "gp_voronoi.h"

/* error_kind values: 1, 2, 3 for E1, E2, E3 (the same numbers as gp_imc_error_kind in
 * gp_specimen2d.h). init values: 0 uniform, 1 Halton (as gp_init_kind). */
typedef struct gp_imc_params {
    double cov;          /* COV(S) of cell areas, > 0 */
    double mean_deg;     /* theta_bar, degrees (any value; taken modulo 180) */
    double anisotropy;   /* min/max ratio of the orientation density, in (0, 1] */
    int error_kind;      /* 1, 2 or 3 */
    double threshold;    /* stop when the error is <= threshold (> 0) */
    long max_steps;      /* >= 0 */
    int init;            /* 0 uniform, 1 Halton (bases 2, 3), rejected outside / in holes */
    int classes_size;    /* number of area classes, 0 = automatic */
    int classes_orient;  /* number of orientation classes, 0 = automatic */
    uint64_t seed;       /* random seed (stream 0 of gp_rng) */
    const gp_vec2 *seeds;/* optional: n initial seeds instead of init (copied) */
} gp_imc_params;

/* E3, threshold 0.002, 1e6 steps, uniform start, automatic classes, cov 0.5, isotropic, seed 1. */
void gp_imc_params_default(gp_imc_params *p);

typedef enum gp_imc_stop {
    GP_IMC_STOP_THRESHOLD = 0,
    GP_IMC_STOP_MAX_STEPS,
    GP_IMC_STOP_FLOOR,
    GP_IMC_STOP_CANCELLED
} gp_imc_stop;

/* "threshold", "max_steps", "floor", "cancelled" (static strings). */
const char *gp_imc_stop_name(gp_imc_stop s);

typedef struct gp_imc_report {
    long steps;          /* steps done (each a proposed move, accepted or not) */
    long accepted;
    double error;        /* final error of the chosen kind */
    double error_initial;
    double error_size;   /* |h_S - H_S|_2 and |h_t - H_t|_2 at the end */
    double error_orient;
    double t_init;       /* seconds spent building the initial tessellation (the rest is steps) */
    double floor;        /* the integer-count floor of the chosen kind for these classes */
    gp_imc_stop stop_reason;
    size_t nsize, norient;
    double *size_edges;     /* nsize + 1, area units; size_edges[nsize] = +inf */
    double *size_target;    /* nsize */
    double *size_achieved;  /* nsize */
    double *orient_edges;   /* norient + 1, degrees, -90 .. 90 */
    double *orient_target;
    double *orient_achieved;
} gp_imc_report;

void gp_imc_report_free(gp_imc_report *r);

/* Called every 4096 steps (and at the end) with the step count and current error; a non-zero
 * return cancels the run. */
typedef int (*gp_imc_progress_fn)(void *user, long steps, double error);

/* Runs IMC in the container (as gp_voronoi_create) with n cells.
 * Returns GP_OK when the threshold was reached; GP_ERR_NOT_CONVERGED at max_steps;
 * GP_ERR_INFEASIBLE when the threshold is below the floor (stop reason "floor", no step done);
 * GP_ERR_CANCELLED when *cancel became non-zero or progress returned non-zero. In these four
 * cases *out is the tessellation as it stands (free it with gp_voronoi_destroy) and *rep
 * (optional) is filled (free with gp_imc_report_free). Other errors (GP_ERR_INVALID, ...) leave
 * *out NULL. cancel and progress may be NULL. */
gp_status gp_imc_run(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                     const size_t *nhole, size_t nholes, size_t n, const gp_imc_params *p,
                     gp_imc_progress_fn progress, void *user, const volatile int *cancel,
                     gp_voronoi **out, gp_imc_report *rep, gp_error *err);

/* The exact integer-count floor of one normalised histogram: min over integer counts c with
 * sum N of |c/N - target|_2 (kind 1 or 3) or |c/N - target|_inf (kind 2, from the same
 * largest-remainder allocation). */
double gp_imc_floor(const double *target, size_t k, size_t n, int kind);

#endif /* GP_IMC_H */
