/* gp_fill.h -- fill one Voronoi cell with a Fourier grain to a target solid fraction
 * (Mollon & Zhao 2012, Sect. 4.1, Eq. 19).
 *
 * The grain is r(theta) = r0 (1 + sum_{n>=1} D_n cos(n (theta - phi) - delta_n)) about a
 * centre c, sampled at Np equally spaced angles: the paper's curve turned by phi. The
 * amplitudes D_n are the spectrum's; the phases delta_2..delta_7, r0, the centre and phi (a
 * whole number of rays, so the contour's samples are the curve's own) are optimised; the
 * other phases are the caller's (random, from the cell's own reproducible stream). Turning
 * the grain only moves those random phases to delta_n + n phi, so it is the same shape.
 *
 * How the constraint is handled (why not a penalty): the grain polygon's area is r0^2 A with
 * A a constant of the spectrum, so Eq. 19 is solved exactly by maximising the largest
 * feasible r0 over the phases (stopping as soon as F_S is reachable) and then setting
 * r0 = sqrt(F_S S / A) -- no penalty weight to tune and never an infeasible answer.
 * - For fixed phases and centre, the paper's constraint r_i <= rmax_i at every ray gives
 *   r0max = min_i rmax_i / rho_i, rho_i = 1 + sum_n D_n cos(n theta_i - delta_n).
 * - In a convex cell (every Voronoi cell of a convex container) the polygon is inside iff
 *   its vertices are, i.e. iff n_k . c + r0 s_k <= h_k for every edge (normal n_k, offset
 *   h_k), s_k the grain's support along n_k: linear in (c, r0). So the best centre and r0 for
 *   a shape are a 3-variable LP, solved exactly at every evaluation.
 * The search, Nelder-Mead over the phases (GSL's nmsimplex2 moves, on plain arrays): (A) the
 * paper's, from the phases of the DFT of the cell's contour seen from its centroid, with mode
 * 2's axis on the cell's orientation (its minimum-caliper axis), so that the grain takes the
 * cell's orientation; centre fixed there; most cells reach F_S here. Then in convex cells:
 * (B) the same with the best centre for each shape; (C) the random modes turned under the
 * cell-aligned modes 2..7 (phi); (D) for cells close to F_S, three random starts seeded from
 * the caller's phases.
 * Each simplex run ends at F_S, at its budget, or once its best has stalled (grown by less
 * than 1e-4 in 45 evaluations): most of the work would go to cells that cannot reach F_S,
 * whose runs crawl to a collapsed simplex (docs/design/fill.md). No bound on the reachable
 * fraction is used to stop earlier: the cheap one (the cell's least width over the grain's
 * least possible width, its even modes 2, 4, 6 all aligned) ignores that such a grain's
 * support lies off that axis and by a hand estimate is some 30 % loose for Example 1's
 * spectrum -- too loose to stop on.
 * A non-convex cell instead moves the centre inside the simplex (rays from it). A grain
 * smaller than the largest is centred with the largest clearance to the cell's edges.
 *
 * What limits the fraction: a cell much longer than the grain can be (D_2 fixes the grain's
 * elongation) cannot be filled to F_S; such cells get the largest grain found (target_met 0).
 *
 * The sampled-ray constraint alone does not keep a grain inside a non-convex cell (an edge
 * between two rays can cut a reflex corner), so the final polygon is checked for exact
 * containment (gp_poly_inside_poly) and shrunk until it holds.
 */
#ifndef GP_FILL_H
#define GP_FILL_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_geom.h"

typedef struct gp_fill_params {
    double solid_fraction;  /* F_S in (0, 1] */
    const double *D;        /* amplitude spectrum D_0..D_{nmodes-1}; D_0 is ignored (1) */
    size_t nmodes;          /* modes used, <= contour_points / 2 */
    size_t contour_points;  /* Np >= 16 */
    double margin;          /* relative clearance from the cell boundary (default 1e-9) */
    int optimise_centre;    /* non-convex cells: also move the centre when the phases alone miss
                             * F_S (default 1; convex cells always place the centre best) */
    int max_evals;          /* Nelder-Mead evaluations per simplex run (default 400) */
} gp_fill_params;

void gp_fill_params_defaults(gp_fill_params *p);

/* Per-thread workspace: trigonometric tables and buffers. */
typedef struct gp_fill_workspace gp_fill_workspace;

gp_fill_workspace *gp_fill_workspace_create(const gp_fill_params *p, gp_error *err);
void gp_fill_workspace_destroy(gp_fill_workspace *ws);

/* Gives the workspace another spectrum of the same nmodes (a grain's own: gp_grainshape.h):
 * D (not copied; it must outlive the fills that use it) is checked as at creation.
 * GP_ERR_INVALID leaves the workspace as it was. */
gp_status gp_fill_workspace_set_spectrum(gp_fill_workspace *ws, const double *D, gp_error *err);

typedef struct gp_fill_result {
    gp_vec2 centre;
    double r0;
    double phases[8];       /* delta_0..delta_7 as used (0 and 1 unused when D_1 = 0) */
    double rotation;        /* phi (radians, a multiple of 2 pi / Np): the grain is the curve of
                             * centre, r0, phases (and the caller's phases above 7) turned by
                             * phi about the centre, i.e. its phases are delta_n + n phi */
    double area;            /* area of the grain polygon */
    double cell_area;
    double fraction;        /* area / cell_area */
    double max_fraction;    /* the best fraction the search found reachable */
    int target_met;         /* fraction >= F_S (1e-9 relative) */
    int evals;              /* objective evaluations spent */
    int shrinks;            /* exact-containment shrink steps applied */
} gp_fill_result;

/* Fills the simple polygon `cell` (either orientation, n >= 3). phases[n] for n in
 * [0, nmodes) are the caller's random phases (entries 2..7 are only the fallback: they are
 * optimised). Writes Np contour points, counter-clockwise, to `contour`.
 * Returns GP_OK also when the target was not met (then res->target_met = 0 and the grain is
 * the largest found); GP_ERR_DEGENERATE for a cell without area, GP_ERR_NOT_STAR when the
 * spectrum makes rho <= 0 for every phase tried. */
gp_status gp_fill_cell(gp_fill_workspace *ws, const gp_vec2 *cell, size_t ncell,
                       const double *phases, gp_vec2 *contour, gp_fill_result *res,
                       gp_error *err);

/* gp_fill_cell starting from `start` (may be NULL: gp_fill_cell), the result of an earlier
 * fill of the same cell with the same phases and spectrum to a lower fraction (a refill,
 * aiming higher): in a convex cell the search only goes on from that grain's phases and
 * rotation (stage B of the header; at least as large a grain as start's), a tenth of a cold
 * search's evaluations. A non-convex cell runs the whole search. */
gp_status gp_fill_cell_from(gp_fill_workspace *ws, const gp_vec2 *cell, size_t ncell,
                            const double *phases, const gp_fill_result *start,
                            gp_vec2 *contour, gp_fill_result *res, gp_error *err);

#endif /* GP_FILL_H */
