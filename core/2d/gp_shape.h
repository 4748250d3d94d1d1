/* gp_shape.h -- the four shape descriptors of Mollon & Zhao 2012, Sec. 2.1 (Eqs. 1-4).
 *
 *  elongation   S / L from the minimum caliper (gp_min_caliper): S the smallest width, L the
 *               extent along the long axis theta; orientation = theta in degrees, (-90, 90].
 *  roundness    Eq. 2 as modified by the paper: the mean radius of ALL the ODEC discs
 *               (gp_odec_build) over R_insc, the radius of the largest inscribed circle.
 *  circularity  sqrt(R_insc / R_circ), R_circ the radius of the smallest enclosing circle.
 *  regularity   log10(P / (P - P_conv)) (log10 per NOTES.md), P the perimeter and P_conv the
 *               perimeter of the convex hull. Capped at GP_SHAPE_REGULARITY_CAP = 5, reached
 *               when P - P_conv <= 1e-5 P (the cap is where the formula itself gives 5, so the
 *               descriptor is continuous). Why 5: a convex grain has P = P_conv and an
 *               infinite regularity; in floating point P - P_conv is then rounding noise
 *               (~1e-15 P, or < 0), which would give arbitrary values around 15. The paper
 *               calls 3-4 "virtually perfect"; 5 sits just above that, so every regularity
 *               >= 5 means "convex to within 1e-5 of the perimeter".
 *
 * Perimeters depend on the discretisation (the paper uses 500 contour points). For Fourier
 * grains use gp_shape_describe_fourier(): it takes P and P_conv from the analytic curve
 * r(theta) evaluated at max(n, GP_SHAPE_PERIMETER_POINTS = 512) angles, and the other three
 * descriptors from the grain's own contour (the polygon whose ODEC goes into the DEM). The
 * specimen should use that variant (with the ODEC it already built, through
 * gp_shape_describe_ex) so that regularity does not depend on its contour_points setting;
 * gp_shape_describe() on a 128-point contour underestimates the roughness-driven part of
 * P - P_conv (see bench/bench_shape.c for the error versus contour points).
 *
 * R_insc is computed by gp_max_inscribed_circle() with tolerance GP_SHAPE_INSC_TOL * R_eq
 * (R_eq = sqrt(area / pi)), i.e. to 1e-6 relative.
 * All functions are thread safe (no state besides the arguments).
 */
#ifndef GP_SHAPE_H
#define GP_SHAPE_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_geom.h"
#include "gp_odec.h"

#define GP_SHAPE_REGULARITY_CAP 5.0
#define GP_SHAPE_PERIMETER_POINTS 512
#define GP_SHAPE_INSC_TOL 1e-6

typedef struct gp_shape_result {
    /* the four descriptors */
    double elongation;      /* S / L, in (0, 1] */
    double orientation_deg; /* direction of the long axis, (-90, 90] */
    double roundness;       /* mean ODEC disc radius / R_insc */
    double circularity;     /* sqrt(R_insc / R_circ) */
    double regularity;      /* log10(P / (P - P_conv)), <= GP_SHAPE_REGULARITY_CAP */
    int regularity_capped;  /* 1 if P - P_conv <= 1e-5 P */
    /* the quantities they come from */
    double width, length;   /* S and L */
    double r_insc, r_circ;
    gp_vec2 insc_center, circ_center;
    double perimeter, perimeter_convex; /* P, P_conv */
    size_t perimeter_points;            /* points P and P_conv were measured on */
    size_t ndiscs;                      /* ODEC discs behind roundness */
    double mean_disc_radius;
} gp_shape_result;

/* The analytic curve r(theta) = r0 (1 + sum_{n>=1} D_n cos(n theta - delta_n)) about center,
 * the convention of gp_fourier.h. */
typedef struct gp_shape_curve {
    gp_vec2 center;
    double r0;
    const double *D;     /* D_0 .. D_{nmodes-1}, D_0 = 1 */
    const double *delta; /* phases, delta[0] ignored */
    size_t nmodes;
} gp_shape_curve;

/* Descriptors of a simple polygon (n >= 3, either orientation): builds its ODEC with params
 * (NULL = gp_odec_params_defaults) and takes P, P_conv from the polygon itself. */
gp_status gp_shape_describe(const gp_vec2 *contour, size_t n, const gp_odec_params *params,
                            gp_shape_result *out, gp_error *err);

/* As gp_shape_describe, but P and P_conv from curve evaluated at
 * max(n, GP_SHAPE_PERIMETER_POINTS) equally spaced angles. contour may be NULL: then the
 * n-point contour is evaluated from curve too (theta_i = 2 pi i / n, as gp_fourier_contour);
 * a contour given must be star-shaped (gp_shape_describe_ex).
 * GP_ERR_NOT_STAR if r <= 0 at an evaluated angle. */
gp_status gp_shape_describe_fourier(const gp_vec2 *contour, size_t n, const gp_shape_curve *curve,
                                    const gp_odec_params *params, gp_shape_result *out,
                                    gp_error *err);

/* The general form: discs (ndiscs > 0) is an ODEC already built for contour (then params is
 * not used; roundness = mean disc radius / R_insc); discs == NULL builds it with params.
 * curve == NULL takes the perimeters from contour. With a curve, the contour must be
 * star-shaped about an interior point (the curve's own points, or points on its rays: a
 * Fourier grain): its hull is then taken in O(n) (gp_min_caliper_star). */
gp_status gp_shape_describe_ex(const gp_vec2 *contour, size_t n, const gp_odec_params *params,
                               const gp_odec_disc *discs, size_t ndiscs,
                               const gp_shape_curve *curve, gp_shape_result *out,
                               gp_error *err);

/* Regularity from P and P_conv with the cap above; *capped (may be NULL) says if it applied.
 * NaN if P <= 0 or either is not finite. */
double gp_shape_regularity(double perimeter, double perimeter_convex, int *capped);

/* Evaluates curve at np angles theta_i = 2 pi i / np into pts (counter-clockwise) by direct
 * summation (no FFT; O(np nmodes), a quarter of it by the basis' symmetry when np % 4 == 0).
 * GP_ERR_NOT_STAR if some r_i <= 0; GP_ERR_INVALID for bad arguments (np >= 3, r0 > 0,
 * finite D and delta). */
gp_status gp_shape_curve_points(const gp_shape_curve *curve, size_t np, gp_vec2 *pts,
                                gp_error *err);

#endif /* GP_SHAPE_H */
