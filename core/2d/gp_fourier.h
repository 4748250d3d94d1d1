/* gp_fourier.h -- Fourier-descriptor grains (Mollon & Zhao 2012, Eqs. 5-15).
 *
 * Convention (shared/papers/NOTES.md): a grain of mean radius r0, normalised amplitude
 * spectrum D_0 = 1, D_1, D_2, ... and phases delta_n has the polar contour
 *
 *     r(theta) = r0 (1 + sum_{n>=1} D_n cos(n theta - delta_n)),
 *
 * sampled at theta_i = 2 pi i / Np, i = 0 .. Np-1 (counter-clockwise, starting on +x). The
 * analysis is the exact inverse on those samples:
 *
 *     r0 = (1/Np) sum_i r_i,   D_n = 2 |Y_n| / (Np r0),   delta_n = -arg(Y_n),
 *     Y_n = sum_i r_i e^{-i n theta_i},  1 <= n < Np/2,
 *
 * so that A_n = r0 D_n cos(delta_n), B_n = r0 D_n sin(delta_n) (Eqs. 14-15) and analysing a
 * generated contour returns its own spectrum and phases. A spectrum array D[0 .. nmodes-1]
 * holds D_0 .. D_{nmodes-1}; only modes n < Np/2 can be represented on Np samples (the Nyquist
 * mode loses its phase), so nmodes <= gp_fourier_max_modes(Np) = (Np + 1) / 2, i.e. 64 for the
 * default Np = 128. Phases are arrays of the same length; delta[0] is ignored.
 *
 * Star shape: a contour is returned only if r > 0 everywhere on the continuous curve, not only
 * on the samples. When sum_{n>=1} D_n < 1 this holds by the triangle inequality; otherwise
 * r is evaluated on 4 Np points (zero-padded FFT) and the true minimum is bounded below by
 * min_fine - r0 * (1/2) sum n^2 D_n * (pi / (4 Np))^2 (Taylor about the true minimum); if that
 * bound is not positive the call fails with GP_ERR_NOT_STAR (conservative: a contour that
 * comes within about 1e-3 r0 of its centre is refused too).
 *
 * Where r(theta) is evaluated: here, by inverse FFT on a plan's Np samples; gp_shape_curve_points
 * (gp_shape.h), by direct summation at any number of angles (the regularity's perimeters);
 * gp_fill, from its own cos / sin tables, because its search re-evaluates the shape thousands
 * of times per cell with only modes 2-7 changing.
 *
 * Threads: a gp_fourier plan object holds FFTW plans and buffers for one Np; use one object
 * per thread (the calls that take a non-const gp_fourier* write its buffers). Creating and
 * destroying objects is safe from several threads at once (the FFTW planner is made thread
 * safe, once per process, with fftw_make_planner_thread_safe()). Plans use FFTW_ESTIMATE, so
 * the same input gives the same output bytes on a given machine and build.
 */
#ifndef GP_FOURIER_H
#define GP_FOURIER_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_geom.h" /* gp_vec2 only; gp_fourier does not link gp_geom */

#define GP_FOURIER_NP_MIN 16
#define GP_FOURIER_NP_DEFAULT 128

typedef struct gp_fourier gp_fourier;

/* Uniform [0, 1) generator callback, e.g. gp_rng_uniform with a gp_rng* state. */
typedef double (*gp_fourier_u01_fn)(void *state);

/* Largest usable spectrum length on np samples: (np + 1) / 2 (modes 0 .. ceil(np/2) - 1). */
size_t gp_fourier_max_modes(size_t np);

/* The three-parameter spectrum of Eqs. 10-12: D[0] = 1, D[1] = 0, D[2] = D2, D[3] = D3,
 * D[n] = D3 (n/3)^alpha for 3 < n < 8, D[8] = D8, D[n] = D8 (n/8)^beta for n > 8, up to
 * n = nmodes - 1 (nmodes >= 1; usually Np/2). GP_ERR_INVALID on NaN/inf, negative D2/D3/D8,
 * or a non-finite result. The star-shape of the result is checked only when a contour is made. */
gp_status gp_fourier_spectrum(double D2, double D3, double D8, double alpha, double beta,
                              size_t nmodes, double *D, gp_error *err);

/* Validates a user spectrum D[0 .. nmodes-1] (e.g. the API's "spectrum": [D0, D1, ...]):
 * nmodes >= 1, |D0 - 1| <= 1e-9 (normalised), every D_n finite and >= 0. */
gp_status gp_fourier_spectrum_check(const double *D, size_t nmodes, gp_error *err);

/* Plan object for np >= GP_FOURIER_NP_MIN samples (any np, not only powers of two). NULL on
 * failure (err says why). */
gp_fourier *gp_fourier_create(size_t np, gp_error *err);
void gp_fourier_destroy(gp_fourier *f);
size_t gp_fourier_np(const gp_fourier *f);

/* Fills delta[0] = 0 and delta[n] = -pi + 2 pi u01(state) for n = 1 .. nmodes-1, drawing
 * exactly nmodes - 1 values in that order. GP_ERR_INVALID if a draw is not in [0, 1]. */
gp_status gp_fourier_random_phases(size_t nmodes, gp_fourier_u01_fn u01, void *state,
                                   double *delta, gp_error *err);

/* r_i = r(theta_i), i = 0 .. np-1, by one inverse real FFT. r0 > 0 finite, D checked as by
 * gp_fourier_spectrum_check, nmodes <= gp_fourier_max_modes(np), delta finite.
 * GP_ERR_NOT_STAR (r untouched) if the contour is not star-shaped (see above). */
gp_status gp_fourier_radii(gp_fourier *f, double r0, const double *D, const double *delta,
                           size_t nmodes, double *r, gp_error *err);

/* Contour points pts[i] = center + r_i (cos theta_i, sin theta_i), counter-clockwise. r (np
 * values) may be NULL. On error nothing is written. */
gp_status gp_fourier_contour(gp_fourier *f, gp_vec2 center, double r0, const double *D,
                             const double *delta, size_t nmodes, gp_vec2 *pts, double *r,
                             gp_error *err);

/* gp_fourier_random_phases + gp_fourier_contour. delta_out (nmodes) receives the phases and
 * may be NULL. On GP_ERR_NOT_STAR the phases were still drawn (and are in delta_out). */
gp_status gp_fourier_contour_random(gp_fourier *f, gp_vec2 center, double r0, const double *D,
                                    size_t nmodes, gp_fourier_u01_fn u01, void *state,
                                    double *delta_out, gp_vec2 *pts, double *r, gp_error *err);

/* Forward DFT of np radii r_i at theta_i (see the convention above): *r0 and, for
 * n < nmodes <= gp_fourier_max_modes(np), D[n] and delta[n] (delta in (-pi, pi]; D[0] = 1,
 * delta[0] = 0). D and delta may each be NULL. GP_ERR_INVALID for non-finite radii or a
 * non-positive mean radius. */
gp_status gp_fourier_analyse(gp_fourier *f, const double *r, size_t nmodes, double *r0,
                             double *D, double *delta, gp_error *err);

/* Radial distances from center to the boundary of polygon poly (n >= 3 vertices, either
 * orientation) along theta_i = 2 pi i / np: r[i] is the distance to the FIRST boundary
 * crossing of the ray (the r_max,i of Eq. 19). center must be strictly inside the polygon
 * (GP_ERR_INVALID otherwise). If some ray crosses the boundary more than once (the polygon is
 * not star-shaped from center): with star != NULL, *star = 0 and GP_OK (first-exit distances
 * are still returned); with star == NULL, GP_ERR_NOT_STAR. *star = 1 when every ray crosses
 * once. Crossings are counted with the half-open vertex rule, so a ray through a vertex or
 * along an edge is counted correctly. O(np n); no allocation, no plan needed. */
gp_status gp_fourier_polygon_radii(const gp_vec2 *poly, size_t n, gp_vec2 center, size_t np,
                                   double *r, int *star, gp_error *err);

/* gp_fourier_polygon_radii on f's np angles followed by gp_fourier_analyse: the starting
 * point the paper suggests for the cell filling (r0 and delta_n of the cell itself). */
gp_status gp_fourier_analyse_polygon(gp_fourier *f, const gp_vec2 *poly, size_t n,
                                     gp_vec2 center, size_t nmodes, double *r0, double *D,
                                     double *delta, int *star, gp_error *err);

#endif /* GP_FOURIER_H */
