/* gp_imc.h -- inverse Monte-Carlo (IMC) constrained Voronoi tessellation, with local updates.
 *
 * Mollon & Zhao 2012 §3.3 (improved algorithm, steps d1-d5), with the corrections of
 * shared/papers/NOTES.md.
 *
 * Targets. Cell areas follow an area law (gp_law.h: lognormal -- the paper's --, normal,
 * uniform or a sieve curve) whose mean must be the container area / N; cell orientations
 * theta (gp_voronoi_cell_orientation, Fig. 1a) follow the cosine law of gp_law.h with mean
 * theta_bar and anisotropy a in (0, 1].
 *
 * Objective (error_kind). The default, GP_IMC_ERROR_AD, is the Anderson-Darling statistic of the
 * cell areas against the area law and of the cell orientations against the orientation law:
 *     A^2 = -N - (1/N) sum_i (2i - 1) [ln u_(i) + ln(1 - u_(N+1-i))],   u = F(value),
 * reported as the excess over its least value for N values, A^2_min(N) (all u_(i) at
 * (2i - 1) / 2N), so that 0 is a perfect match at any N: error = max(excess_size,
 * excess_orient / 2); a move is accepted when excess_size + excess_orient / 2 does not
 * increase. The orientations count half: their KS goal is 0.3 of the critical value where the
 * areas' is 0.2, and the orientations of near-regular cells (COV <= 0.1) are the last to come
 * (bench_fit2d: at COV 0.1 and full weight, N = 500 stalls at 0.053 after 400,000 steps).
 * Why this measure: a histogram of a few classes can be matched exactly by a wrong law (a far
 * wider COV than the target's fits 5 classes exactly), and its integer floor ties the class
 * count to the threshold. A^2 sees every value, has no integer floor, moves with every step,
 * and weighs the tails by 1 / (F (1 - F)), so that the few largest cells that carry a COV
 * cannot drift (a Cramer-von Mises distance weighs them by 1). A^2 alone still leaves the
 * largest cells of a wide law short, hence a COV term in the area excess (gp_imc.c
 * cov_term_of); and the paper's move alone is rarely accepted near convergence, hence the
 * mixed moves (gp_imc.c propose_ad). Walls tie orientations: a cell whose thinnest side lies
 * across a straight wall has the wall's direction exactly, a step in the orientations' CDF that
 * A^2 barely sees and the KS distance does, hence a tie term in the orientation excess,
 * sum over the container's edge directions of k (k - 1) / N for k cells on a direction
 * (gp_imc.c wall_tie_of). The figures that decided all four, AD against E3:
 * docs/design/imc.md.
 * Incremental: A^2 is linear in the ranks, so it is kept exactly (integer sums of fixed-point
 * logs) by an order-statistic structure (gp_adstat.h) in O(log N) per changed cell; a
 * rolled-back move restores it bit for bit, and a move is judged by the exact A^2 it would give.
 *
 * The paper's histogram errors stay selectable (error_kind 1-3), with h and H the achieved and
 * target normalised histograms:
 *   E1 = (|h_S - H_S|_2 + |h_t - H_t|_2) / 2,  E2 = max(|h_S - H_S|_inf, |h_t - H_t|_inf),
 *   E3 = max(|h_S - H_S|_2, |h_t - H_t|_2).
 * Area classes are k_S classes of equal target probability (law quantiles, open ends);
 * orientation classes k_theta of equal width over [-90, 90). Counts are integers, so a
 * histogram cannot come closer than the best integer allocation (NOTES.md): gp_imc_floor().
 * With classes 0 the counts are chosen automatically (the largest k <= min(20, N/25), >= 3,
 * whose floor is at most half the threshold). A threshold below the floor stops at once
 * ("floor", GP_ERR_INFEASIBLE); gp_imc_reachable_threshold() tells the caller beforehand.
 *
 * Histograms for the report are always computed (gp_imc_report), on the law's quantile classes,
 * whatever the objective.
 *
 * Stopping. A run stops at its threshold, at max_steps, when it stalls (the descent not 1 %
 * lower over gp_imc_stall_window(N) steps) or when cancelled. The AD threshold stands for KS
 * goals, the cell areas' KS distance within 0.15 and the orientations' within 0.3 of the 5 %
 * critical value 1.36 / sqrt(N) (0.15: Neper's fits sit at 0.16-0.2 of it at COV 0.8, the
 * tool to be no worse than); A^2 and KS weigh a CDF's misfit differently (a narrow step costs A^2 little), so with
 * ks_goals (the default) a run at its threshold measures both distances (O(N log N), from the
 * values the statistics hold) and, while either misses its goal, goes on to 0.7 of the
 * threshold in force, down to a quarter of the params', for at most twice the steps (and at
 * least N) it took to reach the params'; in that phase no move that lifts the error above the
 * params' threshold is accepted (moves are judged on the descent, a sum, which can fall while
 * the error, a max, rises). It then stops for "threshold" whatever ends it. (bench_fit2d, three
 * seeds a row: the worst area KS of a row was 0.23 of critical without it, 0.15 with it, for
 * up to 3x the steps at N = 500 -- still under a second.) The other way round, with ks_goals a
 * run still above its threshold looks at its error every max(8,192, N) steps (at a progress
 * report): when the error, falling at its rate since the last look, would take more steps than
 * the run has made to reach the threshold, and the cells already meet the goals (the areas' KS
 * within 0.15, the orientations' within 0.25, the areas' COV within 1 % of the aimed one), it
 * stops as stalled (report.at_goals). Near-regular cells (COV 0.1) meet them after a fifth of
 * the steps the threshold takes and then creep towards it: N = 500 in 20,000-45,000 steps
 * where the threshold took 92,000-215,000 (or stalled after 254,000-419,000).
 *
 * Step (d1-d5): take the next seed of a sweep along the seeds' order (the paper picks one at
 * random: gp_imc.c sweep_seed says why not, and what it changed); move it to a point uniform
 * in the union of its cell and its neighbours' cells (a cell chosen by area, then a point
 * uniform in it); update the cells locally (gp_voronoi_try_move); update the objective for the
 * changed cells; accept if the error does not increase (plateaus are crossed), otherwise roll
 * the tessellation back.
 *
 * Seed numbering: generated seeds (init uniform or Halton) are renumbered along a Hilbert curve
 * over the container's bounding box before the tessellation is built, so that neighbouring
 * cells have nearby indices and everything stored per cell (cells, neighbour lists, bins, AD
 * values) lies close in memory: a step touches ~9 neighbouring cells, which in draw order lie
 * scattered over every per-cell array, so that large runs would wait on the memory
 * (docs/design/imc.md). Cell i of the result is the i-th seed along the curve; seeds given by
 * the caller (params.seeds) keep their order.
 *
 * Threads (params.threads, gp_imc.c "lanes"). Each step draws its proposal from a random stream
 * of its own, named by (seed, step number), so what step s + 1 proposes depends only on the
 * tessellation it starts from. Near the end most steps are refused, and a
 * refused step leaves the tessellation as it was: so T threads evaluate steps s + 1 .. s + k
 * at once, each on its own replica of the tessellation (read-only on the statistics), and the
 * round's steps are then taken in order. An accepted step's move is copied into the other
 * replicas (gp_voronoi_apply); a later step of the round stands if its footprint is clear of
 * that move's cells (gp_voronoi_footprint) and is judged again, else it is evaluated again next
 * round, with the same stream. Every step is judged exactly as one thread judges it, against
 * the same error, so the run is the one-thread run bit for bit. Only AD runs use more than one
 * thread; the replicas hold at most 500,000 cells together (a replica is a whole tessellation,
 * ~660 bytes a cell): one thread from N = 500,000 on; no more threads than CPUs online; and the
 * run times stretches alone and on its threads and keeps the faster (a busy machine). The
 * settling of a round is serial, so two threads gain most when few steps are accepted (the end
 * of a run, small N) and little while many are (docs/design/imc.md has the speeds); while the
 * run goes alone, the other replicas still take each accepted move.
 *
 * Determinism: the same container, N and params (seed included) give the same tessellation bit
 * for bit, whatever params.threads. Thread-safety: one run per call, no shared state; a run
 * on more than one thread starts its own threads and joins them before it returns.
 */
#ifndef GP_IMC_H
#define GP_IMC_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_geom.h"
#include "gp_law.h"
#include "gp_progress.h"
#include "gp_voronoi.h"

/* error_kind values: 1, 2, 3 for E1, E2, E3, 4 for AD (the same numbers as gp_imc_error_kind
 * in gp_specimen2d.h). init values: 0 uniform, 1 Halton (as gp_init_kind). */
#define GP_IMC_ERROR_AD 4

typedef struct gp_imc_params {
    const gp_law *law;   /* the cell area law (not owned); NULL: lognormal of `cov` with mean
                          * container area / n */
    double cov;          /* COV(S) of cell areas when law is NULL, > 0 */
    double mean_deg;     /* theta_bar, degrees (any value; taken modulo 180) */
    double anisotropy;   /* min/max ratio of the orientation density, in (0, 1] */
    int error_kind;      /* 1, 2, 3 or GP_IMC_ERROR_AD */
    double threshold;    /* stop when the error is <= threshold (> 0) */
    int ks_goals;        /* AD: the threshold stands for the KS goals: at it, ask them too;
                          * before it, stop when slow within them ("Stopping" above) */
    long max_steps;      /* >= 0 */
    int init;            /* 0 uniform, 1 Halton (bases 2, 3), rejected outside / in holes */
    int classes_size;    /* number of area classes, 0 = automatic */
    int classes_orient;  /* number of orientation classes, 0 = automatic */
    uint64_t seed;       /* random seed (stream 0 of gp_rng) */
    const gp_vec2 *seeds;/* optional: n initial seeds instead of init (copied; cell i is seeds[i]) */
    int threads;         /* steps evaluated in parallel (0 or 1: one thread); the result is the
                          * same bit for bit whatever the count ("Threads" above) */
} gp_imc_params;

/* AD with its default threshold, 1e6 steps, uniform start, automatic classes, lognormal cov
 * 0.5, isotropic, seed 1. */
void gp_imc_params_defaults(gp_imc_params *p);

/* The default threshold of an error kind: 0.002 for E1-E3 (the paper), and for AD the value
 * that puts the KS distance well inside its 5 % critical value at every N (gp_imc.c
 * GP_IMC_AD_THRESHOLD). */
double gp_imc_default_threshold(int error_kind);

/* The least threshold a run with these params can reach for n cells: the integer-count floor
 * of the classes it would use (E1-E3), 0 for AD. For refusing a spec before it is queued. */
double gp_imc_reachable_threshold(const gp_imc_params *p, size_t n);

typedef enum gp_imc_stop {
    GP_IMC_STOP_THRESHOLD = 0,
    GP_IMC_STOP_MAX_STEPS,
    GP_IMC_STOP_FLOOR,
    GP_IMC_STOP_CANCELLED,
    GP_IMC_STOP_STALLED,     /* AD: no gain of 1 % in the last gp_imc_stall_window() steps */
    GP_IMC_STOP_SINGLE_CELL  /* N = 1: the cell is the container, nothing can move */
} gp_imc_stop;

/* The COV term of the AD size excess: n (COV / cov_t - 1)^2 for n values of mean mu whose
 * squares sum to sum_sq (COV the population one; cov_t the population COV aimed at, that of
 * the law as a sample COV: gp_imc.c cov_term_of says why). Shared with the 3D IMC. */
double gp_imc_cov_term(size_t n, double mu, double cov_t, double sum_sq);

/* Steps without a 1 % gain of the AD error after which a run stops as "stalled":
 * 20,000 + 50 N (a few seconds at most at small N, where the least error of N cells can lie
 * above the threshold; far beyond the gaps between gains of a run that still converges). */
long gp_imc_stall_window(size_t n);

/* "threshold", "max_steps", "floor", "cancelled", "stalled", "single_cell" (static strings). */
const char *gp_imc_stop_name(gp_imc_stop s);

typedef struct gp_imc_report {
    long steps;          /* steps done (each a proposed move, accepted or not) */
    long accepted;
    double error;        /* final error of the chosen kind */
    double error_initial;
    double error_size;   /* |h_S - H_S|_2 and |h_t - H_t|_2 at the end */
    double error_orient;
    double t_init;       /* seconds spent building the initial tessellation (the rest is steps) */
    double floor;        /* E1-E3: the integer-count floor of these classes; AD: 0 */
    double error_size_ad;   /* AD excess of the areas and orientations at the end (all kinds) */
    double error_orient_ad;
    size_t wall_ties;       /* AD: cells at the end whose orientation is a container edge's
                             * direction, shared with another cell (the walls' ties) */
    double error_orient_ties; /* AD: their term in error_orient_ad, sum k (k - 1) / N */
    gp_imc_stop stop_reason;
    int at_goals;           /* stalled before the threshold, falling slowly with the cells within
                             * the goals the default threshold stands for ("Stopping") */
    size_t nsize, norient;
    double *size_edges;     /* nsize + 1, area units; size_edges[nsize] = +inf */
    double *size_target;    /* nsize */
    double *size_achieved;  /* nsize */
    double *orient_edges;   /* norient + 1, degrees, -90 .. 90 */
    double *orient_target;
    double *orient_achieved;
} gp_imc_report;

void gp_imc_report_free(gp_imc_report *r);

/* Runs IMC in the container (as gp_voronoi_create) with n cells.
 * progress (gp_progress.h, the one callback type of core) is called every 4096 steps and at the
 * end with phase "imc", the steps done, the current error, and as the fraction how far
 * log(error) has come from its value at the first report towards log(threshold), in [0, 1]; a
 * non-zero return cancels the run.
 * Returns GP_OK when the threshold was reached; GP_ERR_NOT_CONVERGED at max_steps, when
 * stalled, or for a single cell;
 * GP_ERR_INFEASIBLE when the threshold is below the floor (stop reason "floor", no step done);
 * GP_ERR_CANCELLED when *cancel became non-zero or progress returned non-zero. In these four
 * cases *out is the tessellation as it stands (free it with gp_voronoi_destroy) and *rep
 * (optional) is filled (free with gp_imc_report_free) -- except a cancel that came while the
 * seeds were placed or the initial tessellation built (*cancel is looked at there too, every
 * few thousand seeds or cells): then *out is NULL, as for other errors (GP_ERR_INVALID, ...).
 * cancel and progress may be NULL. */
gp_status gp_imc_run(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                     const size_t *nhole, size_t nholes, size_t n, const gp_imc_params *p,
                     gp_progress_fn progress, void *user, const volatile int *cancel,
                     gp_voronoi **out, gp_imc_report *rep, gp_error *err);

/* The exact integer-count floor of one normalised histogram: min over integer counts c with
 * sum N of |c/N - target|_2 (kind 1 or 3) or |c/N - target|_inf (kind 2, from the same
 * largest-remainder allocation). */
double gp_imc_floor(const double *target, size_t k, size_t n, int kind);

#endif /* GP_IMC_H */
