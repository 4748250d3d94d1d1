/* gp_geostatic.h -- the geostatic state of a packing: settled at rest under gravity in its box,
 * then measured in horizontal slabs (Dang & Meguid 2010, "Stress Distribution", Eqs. 15-16,
 * Fig. 8).
 *
 * The run (gp_geostatic_run): the spheres (the final, tiled packing) in their box, on the
 * specimen's DEM (gp_dem3d: the same contact law and time step rule), gravity on, the four
 * lateral walls and the bottom wall rigid and frictionless, the top wall lifted out of reach
 * (2 d_max above the box: the surface is free, so that sigma_v is the weight above it; a
 * packing compacted under a servo wall keeps that wall's stress locked in until then). The
 * DEM runs in chunks of 100 steps until S_c (Eq. 7, on a chunk's last step) <= stability_tol,
 * bounded by max_steps, cancellable between steps. Local damping 0.7 (the specimen's
 * relaxation damping, GP_SPEC3D_RELAX_DAMPING, or the material's if higher), the time step
 * GP_SPEC3D_DT_SAFETY sqrt(m / 2 E R) at it (GP_SPEC3D_DT_DAMPING_EXP), and density scaling
 * to the largest radius by default: every sphere gets the inertia of a sphere whose critical
 * time step is the largest sphere's (gp_dem3d.h), so dt follows the large grains. Gravity acts
 * on the true masses, and a static state has no inertia: the state reached is a state of the
 * same equilibrium, reached sooner. With every sphere scaled, a large grain among many fines
 * holds the stiffest contacts: the DEM's check cuts the step once in the first steps (to 0.9
 * of its proven limit; dt_cuts says so), and the step is then ~2 x the specimen's relaxation
 * step for the paper's sieve (docs/design/geostatic.md).
 * The new DEM starts with the contacts' overlaps and no shear springs: friction is mobilised
 * again while the packing settles.
 * Wall friction: gp_dem3d has none; only wall_friction_deg = 0 is accepted.
 *
 * Frame: gravity must lie along one axis of the box (either sign): that axis is the vertical,
 * "up" is against gravity, the bottom wall is the one gravity pushes the packing against,
 * depth is measured down from the top of the box as given. The horizontal axes are the other
 * two in their order (x and y for gravity along z).
 *
 * The measures (gp_geostatic_measure, also on any static list of contacts):
 *   slabs: the box's height cut from the top into ns = max(1, round(H / slab)) slabs of equal
 *     thickness H / ns (slab 0 = 5 d50, d50 the median diameter by volume of the spheres).
 *   Love-Weber stress of a region (Eq. 15, compression positive): sigma = -(1/V) sum_c w_c l_c
 *     (x) f_c, over every contact (sphere pairs: l the branch O_i O_j, f the force on i; wall
 *     contacts: l from the centre to the contact point), w_c the fraction of the branch
 *     segment that lies inside the region (the segment split by the region's planes), V the
 *     region's volume. Why split and not "the contacts whose contact point lies inside": with
 *     the split, the integral of sigma_v over a slab is the integral over the slab's height of
 *     P(z), the vertical force carried across the plane at z by the segments that cross it,
 *     and P(z) is, exactly at rest with frictionless lateral walls, the weight of the spheres
 *     whose centre is above z. The slab's sigma_v is then the weight above, averaged over the
 *     slab's height, over the area: statics, with no boundary error. Whole branches assigned
 *     by their contact point carry a boundary noise of the order of a branch over the slab's
 *     thickness, and whole branches given to every slab they touch count the crossing ones
 *     twice (tests/core/3d/test_geostatic.c shows both).
 *   Two regions per slab: the full cross-section (the statics above hold exactly: the
 *     equilibrium check) and the core, the cross-section less the margin next to the four
 *     lateral walls (wall_margin_dmax d_max, default 1.5: the walls' layering left out):
 *     sigma, K0, porosity and coordination of the profile are the core's.
 *   weight(z) = |g| density (solid volume above the slab's mid-plane: a sphere the plane cuts
 *     counted by its cap) / the box's cross-section.
 *   porosity: 1 - (the spheres' volume clipped to the core slab) / its volume (the sphere's
 *     disc clipped to the plan exactly, integrated over the height by Gauss-Legendre in
 *     pieces that end where the disc meets a side or a corner: smooth in between).
 *   coordination: contacts per sphere (wall contacts counted) over the spheres whose centre is
 *     in the core slab, rattlers included.
 *   K0 = (sigma_h1 + sigma_h2) / 2 / sigma_v per slab; theory 1 - sin(phi') (Eq. 16).
 *   Which slabs count: the top rows are left out when their upper face is less than
 *     max(one slab, the margin) below the top (sigma_v near 0 there); for K0 also the bottom
 *     rows whose lower face is less than the margin above the bottom wall. k0.mean, k0.sd
 *     (sample), k0.bulk (sum sigma_h / sum sigma_v) over the counted rows; equilibrium.
 *     max_error = max |sigma_v(full) - weight| / weight over the rows away from the top (the
 *     core's beside it, core_max_error: not exact, the load need not spread evenly).
 *   whole packing: the Love-Weber tensor of every contact, V the box as given, against the same
 *     mean stress from the walls: on a horizontal axis the mean of its two walls' forces over
 *     their area (the box as given); on the vertical, the bottom wall's force times the height
 *     of the weight's centroid above it over V (the body force's share: at rest sigma V =
 *     sum over walls x (x) f + sum over spheres x (x) m g, which the two ways compare; the
 *     difference is the spheres' unbalanced forces).
 *   map: a vertical section (the first horizontal axis against the vertical: x-z for gravity
 *     along z) in cells of map_cell (default the slab thickness; rounded so that they tile
 *     the box, row 0 at the top), each cell [x] x [the slice] x [z], the slice map_slice thick
 *     along the other horizontal axis centred in the box (0: all of it): Love-Weber sigma_v
 *     and sigma_h (along the section's axis) split as above. With cells the sample's size the
 *     tiles' seams and corners show.
 *   S_c of the list (Eq. 7 recomputed from the contacts: sum over spheres |sum of contact
 *     forces + m g| / sum over spheres of the |f_n| of their contacts), beside the DEM's; the
 *     friction the sphere pairs mobilise, |f_t| / (tan(phi_mu) |f_n|): its mean, and the
 *     fraction of pairs at the Coulomb limit (>= 0.99).
 *
 * Invariants: the same input gives the same result bit for bit, whatever params.threads (the
 * DEM's guarantee; the measures are serial, in the contacts' order). Ownership: the inputs are
 * only read (the spheres are copied); a gp_geostatic_result and every array in it are the
 * caller's, freed by gp_geostatic_result_destroy. Thread safety: no global state; a run uses
 * params.threads DEM workers of its own; concurrent calls are independent.
 */
#ifndef GP_GEOSTATIC_H
#define GP_GEOSTATIC_H

#include <stddef.h>

#include "gp_dem3d.h" /* gp_contact3d */
#include "gp_error.h"
#include "gp_progress.h"
#include "gp_specimen3d.h" /* gp_material3d */

typedef struct gp_geostatic_params {
    gp_material3d material;   /* Table 1 as the specimen had it */
    double gravity[3];        /* m/s^2, along one axis ((0, 0, -9.81)) */
    double wall_friction_deg; /* must be 0 (gp_dem3d's walls are frictionless) */
    double phi_deg;           /* phi' for K0 = 1 - sin(phi'), in (0, 90) (23.7) */
    double slab;              /* slab thickness, m; 0 = 5 d50 */
    double wall_margin_dmax;  /* margin next to the walls, times d_max, >= 0 (1.5) */
    double map_cell;          /* map cell size, m; 0 = the slab thickness */
    double map_slice;         /* the map's slice along the other horizontal axis, m; 0 = all */
    double stability_tol;     /* S_c at rest, in (0, 1) (1e-4) */
    double scaled_radius;     /* density scaling radius, m; 0 = the largest radius; < 0 none */
    long max_steps;           /* bound on the DEM steps, >= 0; 0 = 2,000,000 */
    int threads;              /* DEM worker threads, 0 = 1; the result does not depend on it */
    int keep_contacts;        /* nonzero: the final contacts into the result */
} gp_geostatic_params;

/* Defaults: Table 1 material (gp_spec3d_defaults'), gravity (0, 0, -9.81), wall friction 0,
 * phi' 23.7 deg, slab 5 d50, margin 1.5 d_max, map cells of the slab's size over the whole
 * depth, S_c 1e-4, scaling to the largest radius, 2,000,000 steps, 1 thread, no contacts. */
void gp_geostatic_params_defaults(gp_geostatic_params *p);

/* The profile, one entry a slab, slab 0 at the top. Stresses in Pa along the box's axes
 * (compression positive). */
typedef struct gp_geostatic_profile {
    size_t n;                 /* slabs */
    double thickness;         /* m (H / n) */
    double margin;            /* m, left out next to the lateral walls (the core) and, for K0,
                                 above the bottom wall */
    double *depth;            /* m, the mid-plane below the top of the box */
    double *sigma_xx, *sigma_yy, *sigma_zz;           /* the core */
    double *sigma_xx_full, *sigma_yy_full, *sigma_zz_full; /* the full cross-section */
    double *weight;           /* Pa, the weight above the mid-plane over the cross-section */
    double *k0, *k0_full;     /* sigma_h / sigma_v (NAN where sigma_v <= 0) */
    double *porosity;         /* the core */
    double *coordination;     /* the core */
    unsigned char *k0_counted;          /* 1: in the K0 statistics */
    unsigned char *equilibrium_counted; /* 1: in the equilibrium check (away from the top) */
} gp_geostatic_profile;

typedef struct gp_geostatic_k0 {
    double theory;            /* 1 - sin(phi') */
    double mean, sd;          /* over the counted slabs (sd: n - 1; 0 for one slab) */
    double bulk;              /* sum sigma_h / sum sigma_v over them */
    size_t slabs;             /* how many counted */
} gp_geostatic_k0;

typedef struct gp_geostatic_equilibrium {
    double max_error;         /* max |sigma_v(full) - weight| / weight, slabs away from the top */
    double core_max_error;    /* the same with the core's sigma_v */
    size_t slabs;
} gp_geostatic_equilibrium;

typedef struct gp_geostatic_whole {
    double love_weber[3][3];  /* Pa, every contact, V = the box as given */
    double walls[3];          /* Pa, the same diagonal from the wall forces (see the top) */
    double wall_stress[6];    /* Pa, each wall's force over its face (walls 0..5 = x-..z+) */
    double max_error;         /* max over the axes of |love_weber - walls| / walls */
    double weight;            /* N, the spheres' weight */
    double centroid_height;   /* m, the weight's centroid above the bottom wall */
    double porosity;          /* 1 - (volume clipped to the box) / the box */
    double coordination;      /* contacts per sphere, wall contacts counted */
    size_t contacts, wall_contacts;
    double friction_mobilised;/* mean over the sphere pairs of |f_t| / (tan(phi_mu) |f_n|) */
    double sliding;           /* fraction of the sphere pairs at the Coulomb limit (>= 0.99) */
    double surface;           /* m, the highest sphere top above the bottom wall */
} gp_geostatic_whole;

typedef struct gp_geostatic_map {
    size_t nx, nz;            /* cells along the section's horizontal axis and the vertical */
    int axis_h;               /* the section's horizontal axis (0 = x), axis_v the vertical */
    int axis_v;
    double dx, dz;            /* m, the cells' size */
    double slice_lo, slice_hi;/* m, the slice along the other horizontal axis */
    double *sigma_v, *sigma_h;/* Pa, nz x nx, row-major from the top row */
} gp_geostatic_map;

typedef struct gp_geostatic_result {
    int converged;            /* S_c <= stability_tol was reached (always 1 for _measure) */
    long steps;               /* DEM steps (0 for _measure) */
    double stability;         /* the DEM's S_c at the end (_measure: the list's) */
    double stability_list;    /* S_c of the final contact list (see the top) */
    double dt;                /* the DEM's time step, s (0 for _measure) */
    long dt_cuts;             /* the DEM's cuts of dt (one, early, with the default scaling) */
    double scaled_radius;     /* the density scaling radius used, m (0: none) */
    int axis_v;               /* the vertical axis; up = +axis_v when up_sign > 0 */
    int up_sign;
    double d50, dmax;         /* m, from the spheres (by volume; the largest diameter) */
    gp_geostatic_profile profile;
    gp_geostatic_k0 k0;
    gp_geostatic_equilibrium equilibrium;
    gp_geostatic_whole whole;
    gp_geostatic_map map;
    double *spheres;          /* n x (x, y, z, r), the final state */
    size_t n;
    gp_contact3d *contacts;   /* with params.keep_contacts: the final contacts (else NULL) */
    size_t ncontacts;
    double seconds_settling, seconds_measure;
} gp_geostatic_result;

/* Settles the n spheres xyzr (x, y, z, r; m) in the box [lo, hi] and measures them. Progress:
 * phase "settling" (phase_fraction by the log of S_c, with steps and S_c), then "measuring".
 * Returns GP_OK with *out; GP_ERR_NOT_CONVERGED with *out measured on the state reached
 * (converged 0) when max_steps came first; or, with *out NULL: GP_ERR_INVALID (a parameter or
 * sphere out of range, named; gravity not along an axis; wall friction), GP_ERR_DEGENERATE (a
 * sphere left the box), GP_ERR_NOMEM, GP_ERR_CANCELLED (the flag or the callback). cancel and
 * progress may be NULL. */
gp_status gp_geostatic_run(const gp_geostatic_params *params, const double *xyzr, size_t n,
                           const double lo[3], const double hi[3], gp_progress_fn progress,
                           void *user, const volatile int *cancel, gp_geostatic_result **out,
                           gp_error *err);

/* The measures alone, on a static state: the spheres, the box as given and their contacts
 * (gp_contact3d: sphere pairs and wall contacts, forces on sphere i). wall_force: the six
 * walls' normal forces (N), or NULL to sum them from the wall contacts. The run's fields of
 * the result are 0 (stability: the list's S_c). The spheres are copied into the result; the
 * contacts too with keep_contacts. Errors as gp_geostatic_run's (but no DEM). */
gp_status gp_geostatic_measure(const gp_geostatic_params *params, const double *xyzr, size_t n,
                               const double lo[3], const double hi[3], const gp_contact3d *c,
                               size_t nc, const double wall_force[6], const volatile int *cancel,
                               gp_geostatic_result **out, gp_error *err);

void gp_geostatic_result_destroy(gp_geostatic_result *r);

#endif /* GP_GEOSTATIC_H */
