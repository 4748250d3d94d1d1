/* gp_triax.h -- a drained (or constant-volume) triaxial test of a sphere specimen in a box of six
 * rigid frictionless walls (Dang & Meguid 2010, "Triaxial Tests", Fig. 7), on the specimen's own
 * DEM (gp_dem3d: the same contact law, damping and time step rule), gravity off.
 *
 * The test, for one confining stress sigma3:
 *   1. isotropic consolidation: the six walls are stress servos (Eq. 10) aiming at sigma3 times
 *      their current face area, until every wall stress is within stress_tol of sigma3 and
 *      S_c (Eq. 7) <= stability_tol, both on the same step; the state there is the test's origin
 *      (height H0, volume V0);
 *   2. axial loading: the top wall (z+, the direction the specimen was deposited in) moves
 *      down so that the logarithmic axial strain grows at strain_rate (1/s); the bottom wall
 *      stays. Drained: the four lateral walls stay servos at sigma3 times their current area.
 *      Constant volume: the lateral walls move together so that the box volume stays V0 (the
 *      cross-section scales as H0 / H; the measured lateral stress is then sigma3's curve).
 *      The loading ends at axial_strain.
 * Measures (compression positive, soil mechanics): eps_a = ln(H0 / H), eps_v = ln(V0 / V) from
 * the wall positions; sigma1 = F_z / A_xy (the mean of the top and bottom walls), sigma3 the
 * mean of the lateral walls' F / A; the Love-Weber tensor (Eq. 15, gp_dem3d_stress, over the
 * sphere and wall contacts, V the current box) beside them; q = sigma1 - sigma3, p = (sigma1 +
 * 2 sigma3) / 3; Z = 2 C / N (C sphere-sphere contacts, N spheres) and the mechanical
 * Z_m = 2 C' / N' over the spheres with at least two contacts (walls counted), C' the
 * sphere-sphere contacts between two such spheres (rattlers removed, once); porosity 1 - solid
 * / V (gp_dem3d_solid_volume); S_c; the inertial number I = strain_rate d50 sqrt(density / p)
 * (the nominal rate, also during the ramp); the servo error, the largest |wall stress -
 * sigma3| / sigma3 over the servo walls (the six at the curve's first point, the end of
 * consolidation; the four lateral ones when drained; none, 0, at constant volume).
 * Summary: the peak of sigma1 / sigma3 (ratio R, its eps_a, phi = asin((R - 1) / (R + 1))), the
 * end state, the largest dilatancy angle psi = asin(-d eps_v / (2 d eps_a - d eps_v)) over the
 * curve (finite differences on the samples, a window of 1 % axial strain centred on each
 * sample, clipped at the curve's ends, at least 0.25 % wide or half the curve), E50 = q_peak /
 * 2 over the axial strain at which q first reaches it (linear between samples), the largest I
 * and servo error of the loading, and still_rising when the ratio at the end is within 1 % of
 * the peak and grew over the last 2 % of axial strain.
 * Mohr-Coulomb (gp_triax_mohr_coulomb): the least-squares line t = s sin(phi) + c cos(phi) through
 * the peak states (s = (sigma1 + sigma3) / 2, t = (sigma1 - sigma3) / 2), with c >= 0; with
 * one test, c = 0 and phi its own.
 *
 * The run (figures behind the choices: docs/design/triax.md):
 *   - the DEM: the material as given (the contact law of gp_dem3d.h, k_s / k_n = poisson,
 *     local damping = material.damping in both phases), TRUE masses (no density scaling: the
 *     loading is dynamic and its inertial number must be honest), no gravity, the specimen's
 *     time step rule (dt = GP_SPEC3D_DT_SAFETY (1.7 / (1 + c))^GP_SPEC3D_DT_DAMPING_EXP
 *     min sqrt(m / 2 E R), c the damping: 0.468 sqrt(m / 2 E R) of the smallest sphere at
 *     c = 0.2) with its stability guard (a step beyond the proven limit cuts dt);
 *   - consolidation: the servos' gain is 0.05 of Eq. 10's displacement a step, their speed
 *     capped at 0.05 /s times half the span of their axis (I below 1e-3 on the way): the
 *     wall stress rises to sigma3 without overshoot or ringing (from the specimen's geostatic
 *     state, the paper's S0 converges in 3,800, 6,000 and 21,800 steps at 50, 100 and 500 kPa;
 *     the cap sets the pace); the stop is looked at every 100 steps;
 *   - loading: the lateral servos' gain 0.25 a step (the DEM's default), their cap 20 times the
 *     strain rate times half the span; the top wall's velocity is set every 100 steps (and
 *     at each sample) so that it reaches the planned height at the end of the stretch; the
 *     strain rate rises linearly from 0 over 10 H0 sqrt(density / E) (about ten periods of the
 *     sample's axial mode), at most 2 x 0.002 / strain_rate, then stays; the samples are at
 *     eps_a = k axial_strain / (samples - 1) exactly, the first one the end of consolidation.
 * Bounds: every run is bounded by max_steps (consolidation and loading together) and can be
 * cancelled between steps (the cancel flag or the progress callback). The loading's share is
 * its planned steps, 1.05 (axial_strain + 0.002) / strain_rate / dt + samples + 100; the
 * consolidation's share is the rest, at most max(5 s, 0.25 (axial_strain + 0.002) /
 * strain_rate) / dt steps (seconds of simulated time). A consolidation that does not converge
 * within its share fails with GP_ERR_NOT_CONVERGED and says which criterion was missed; a
 * loading that would pass max_steps (only after cuts of dt) fails the same way; max_steps
 * below the loading's share plus 100 is GP_ERR_INVALID. gp_triax_estimate_steps gives the sum
 * of both shares at the time step of r_min: with max_steps set to it, a run of spheres no
 * smaller than r_min has its consolidation's full allowance, and uses at most that many steps.
 * Ownership: the spheres are copied; a gp_triax_result and its arrays are the caller's
 * (gp_triax_result_destroy). Thread safety: no global state; a run uses params.threads DEM
 * workers of its own, and its result (but the timings) does not depend on their number, bit
 * for bit.
 */
#ifndef GP_TRIAX_H
#define GP_TRIAX_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_progress.h"
#include "gp_specimen3d.h" /* gp_material3d */

typedef enum gp_triax_drainage {
    GP_TRIAX_DRAINED = 0,        /* lateral walls hold sigma3 */
    GP_TRIAX_CONSTANT_VOLUME = 1 /* lateral walls keep the volume (undrained analogue) */
} gp_triax_drainage;

typedef struct gp_triax_params {
    double confining;      /* sigma3, Pa, in (0, 1e7] */
    double axial_strain;   /* the loading's end, logarithmic, in (0, 0.5] */
    double strain_rate;    /* 1/s, > 0 */
    gp_triax_drainage drainage;
    double stress_tol;     /* consolidation: wall stresses within this fraction of sigma3 (0.01) */
    double stability_tol;  /* consolidation: S_c at most this (1e-4) */
    double d50;            /* m, for the inertial number (the specimen's median diameter) */
    long max_steps;        /* the run's bound on DEM steps, > 0 */
    int samples;           /* points of the curve, in [2, 500] (500) */
    int threads;           /* DEM worker threads; 0 = 1; the result does not depend on it */
} gp_triax_params;

/* Defaults: sigma3 50 kPa, axial strain 0.2, rate 0.01 /s, drained, tolerances 0.01 and 1e-4,
 * 500 samples, 1 thread; d50 0 and max_steps 0 must be set by the caller. */
void gp_triax_params_defaults(gp_triax_params *p);

/* One sample of the loading curve. */
typedef struct gp_triax_point {
    double axial_strain, volumetric_strain;
    double sigma1, sigma3;        /* Pa, from the wall forces */
    double sigma1_lw, sigma3_lw;  /* Pa, Love-Weber: zz and the mean of xx and yy */
    double q, p, ratio;           /* Pa, Pa, sigma1 / sigma3 */
    double coordination, coordination_mechanical, porosity, stability, inertial_number;
    double servo_error;           /* largest |wall stress - sigma3| / sigma3 of the servo walls */
    long step;                    /* the DEM's steps since the run began (consolidation's too) */
} gp_triax_point;

typedef struct gp_triax_result {
    double confining;            /* Pa, as asked */
    /* the end of consolidation: the test's origin */
    long consolidation_steps;
    double consolidation_wall[3];/* Pa, the wall stresses on x, y, z (the mean of each pair) */
    double consolidation_lw[3][3]; /* Pa, the Love-Weber tensor there */
    double consolidation_porosity, consolidation_stability;
    double height0, volume0;     /* m, m^3 */
    /* the loading */
    gp_triax_point *curve;       /* ncurve samples, eps_a from 0 to axial_strain */
    size_t ncurve;
    double peak_ratio, peak_axial_strain, peak_phi_deg;
    double end_ratio, end_phi_deg;
    double dilatancy_deg;        /* the largest psi (negative: contracting throughout) */
    double e50;                  /* Pa */
    double inertial_number_max, servo_error_max;
    int still_rising;
    long steps;                  /* all DEM steps of the run */
    double dt;                   /* the loading's time step at its end, s (the rule's; less if
                                    the stability guard had to cut it) */
    double seconds_consolidation, seconds_loading;
    double *spheres;             /* n x (x, y, z, r) at the end of the loading */
    size_t n;
    double box_lo[3], box_hi[3]; /* the walls at the end */
} gp_triax_result;

/* Runs one test of the n spheres xyzr (x, y, z, r; m) in the box [lo, hi] with the material
 * (Table 1 as the specimen had it). Progress reports name the phases "consolidation" and
 * "loading" (phase_fraction by S_c's log and by axial strain; fraction 0.1 for the first,
 * 0.9 for the second), with steps, porosity and S_c.
 * Returns GP_OK with *out, or: GP_ERR_INVALID (a parameter out of range, named: "confining",
 * "axial_strain", "strain_rate", "drainage", "stress_tol", "stability_tol", "d50",
 * "max_steps", "samples", "threads", "material.<field>", "box"), GP_ERR_NOT_CONVERGED
 * (consolidation within its share, or the loading past max_steps), GP_ERR_DEGENERATE (a
 * sphere left the box), GP_ERR_CANCELLED, GP_ERR_NOMEM; *out is NULL on every error. */
gp_status gp_triax_run(const gp_material3d *material, const double *xyzr, size_t n,
                       const double lo[3], const double hi[3], const gp_triax_params *params,
                       gp_progress_fn progress, void *user, const volatile int *cancel,
                       gp_triax_result **out, gp_error *err);

void gp_triax_result_destroy(gp_triax_result *r);

/* The DEM steps a test would take at most, for the work bound of a spec before it runs: the
 * loading's time over the time step the DEM would start with for spheres down to r_min of this
 * material, plus the consolidation's share (the same rule gp_triax_run applies to max_steps;
 * see "Bounds" above). 0 for a material, r_min or rate that is not > 0. Independent of the
 * box, the number of spheres and sigma3. */
long gp_triax_estimate_steps(const gp_material3d *material, double r_min,
                             const gp_triax_params *params);

/* The Mohr-Coulomb envelope through n peak states (sigma3[i], sigma1[i], Pa): phi (degrees),
 * cohesion c (Pa, >= 0) and the residual, the root-mean-square distance of the points' t from
 * the line (Pa). When the least-squares line would cut t = 0 at s > 0 (c < 0), or the states
 * share one s, the line through the origin is fitted instead (c = 0). GP_ERR_INVALID for
 * n < 1, a NULL pointer, or a state with sigma1 < sigma3, sigma3 <= 0 or a value not finite
 * (the message names the state). */
gp_status gp_triax_mohr_coulomb(const double *sigma3, const double *sigma1, size_t n,
                                double *phi_deg, double *cohesion, double *residual,
                                gp_error *err);

#endif /* GP_TRIAX_H */
