/* gp_fill.h -- fill one Voronoi cell with a Fourier grain to a target solid fraction
 * (Mollon & Zhao 2012, Sect. 4.1, Eq. 19).
 *
 * The grain is r(theta) = r0 (1 + sum_{n>=1} D_n cos(n theta - delta_n)) about a centre c,
 * sampled at Np equally spaced angles. The amplitudes D_n are the spectrum's; the phases
 * delta_2..delta_7 and r0 (and the centre) are optimised, the other phases are given by the
 * caller (random, from the cell's own reproducible stream).
 *
 * How the constraint is handled (why not a penalty): for fixed phases and centre, the
 * constraint r_i <= rmax_i at every ray gives the largest feasible r0 in closed form,
 *     r0max = min_i rmax_i / rho_i,   rho_i = 1 + sum_n D_n cos(n theta_i - delta_n),
 * and the grain area is r0^2 A(delta) with A the area of the unit-r0 polygon. So Eq. 19 is
 * solved exactly by maximising the achievable fraction f = r0max^2 A / S over the phases
 * (and the centre) with GSL's Nelder-Mead simplex, stopping as soon as f >= F_S, and then
 * setting r0 = sqrt(F_S S / A) -- no penalty weight to tune and never an infeasible answer.
 * The search starts from the phases of the DFT of the cell's own contour seen from the
 * centre, as the paper suggests, so the grain takes the cell's orientation.
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
    int optimise_centre;    /* also move the centre when the phases alone miss F_S (default 1) */
    int max_evals;          /* Nelder-Mead evaluations per stage (default 400) */
} gp_fill_params;

void gp_fill_params_defaults(gp_fill_params *p);

/* Per-thread workspace: trigonometric tables, buffers and the GSL minimiser. */
typedef struct gp_fill_workspace gp_fill_workspace;

gp_fill_workspace *gp_fill_workspace_create(const gp_fill_params *p, gp_error *err);
void gp_fill_workspace_destroy(gp_fill_workspace *ws);

typedef struct gp_fill_result {
    gp_vec2 centre;
    double r0;
    double phases[8];       /* delta_0..delta_7 as used (0 and 1 unused when D_1 = 0) */
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

#endif /* GP_FILL_H */
