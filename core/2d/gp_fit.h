/* gp_fit.h -- goodness of fit of a 2D specimen to the laws it was asked for (api.md `stats.fit`).
 *
 * What: measured on the specimen's own values (cell or grain areas, orientations), never on the
 * IMC's working state, so that the report says what the user gets:
 *   - area laws (gp_law.h): achieved mean and COV, the Kolmogorov-Smirnov distance D to the
 *     law's CDF with its 5 % critical value 1.36 / sqrt(n), the 1-Wasserstein distance W1
 *     divided by the target mean, the achieved range next to the law's 0.1 % .. 99.9 % range,
 *     and the two CDFs sampled for a picture;
 *   - orientations: D against the cosine law of gp_law.h on its window [mean - 90, mean + 90);
 *   - sieve laws: percent passing by mass of the grains at each sieve, next to the target.
 * Why these three numbers for areas: D alone is blind to the tails (a sample whose largest
 * cells are missing can keep D under its critical value), while the COV, the range and W1 (the
 * mean absolute gap between the achieved and target quantiles, i.e. the area between the two
 * CDFs) see them; W1 / mean is a fraction of the mean area, comparable across specimens.
 *
 * Algorithm:
 *   - D exactly: on the sorted values x_(1) <= .. <= x_(n), D = max_i max(i/n - F(x_(i)),
 *     F(x_(i)) - (i-1)/n) (ties included).
 *   - W1 = integral over x of |F_n(x) - F(x)|: F_n is the constant i/n between two sorted
 *     values, so W1 is a sum of integrals of |i/n - F| over the gaps, each split where F
 *     crosses i/n (gp_law_quantile) and at the law's kinks (support ends, sieve rows) so that
 *     every piece is smooth; each piece by adaptive Gauss-Kronrod (7/15 points), the unbounded
 *     tail (x_(n), +inf) of 1 - F after x = x_(n) + s t / (1 - t). Accurate to ~1e-12 of the
 *     mean (the tests hold it to closed forms); O(n) CDF evaluations times a small constant.
 *   - Curves: x log-spaced over [min(q0.001, min), max(q0.999, max)] when that spans more
 *     than a decade (areas of a COV 1 lognormal do), else evenly spaced.
 *   - Passing: d = sqrt(4 A / pi); mass proportional to A in 2D; a grain passes sieve k when
 *     d < d_k (as gp_sieve_passing).
 *
 * Ownership: the *_measure functions overwrite *out (free a previous result first) and, on
 * success, the arrays in it belong to the caller: gp_fit_area_free / gp_fit_passing_free
 * (safe on a zeroed or failed result, and twice). On failure *out is left zeroed.
 * Thread safety: pure functions of their arguments (the law is read only); any number may run
 * at once. No global state, no GSL error handler involved.
 */
#ifndef GP_FIT_H
#define GP_FIT_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_law.h"

/* Goodness of fit of an area law, measured on the specimen (api.md `stats.fit`). */
typedef struct gp_fit_area {
    int present;
    gp_law_kind law;
    double target_mean, target_cov;
    double mean, cov;           /* achieved (sample standard deviation, n - 1) */
    double ks, ks_critical;     /* Kolmogorov-Smirnov distance to the law's CDF; 1.36 / sqrt(n) */
    double w1;                  /* 1-Wasserstein distance / target mean */
    double min, max;            /* achieved range, next to the law's p = 0.001 .. 0.999 range */
    double q001, q999;
    size_t n;
    /* the CDFs for a picture: ncurve points x (area units, increasing), target F(x) and
     * achieved empirical CDF at x */
    size_t ncurve;
    double *curve_x, *curve_target, *curve_achieved;
} gp_fit_area;

typedef struct gp_fit_orient {
    int present;
    double target_mean_deg, target_anisotropy;
    double ks, ks_critical;
    size_t n;
} gp_fit_orient;

/* Passing by mass of the grains at the sieve's diameters (sieve law only). */
typedef struct gp_fit_passing {
    size_t n;                   /* 0 without a sieve law */
    double *diameters;          /* container length units */
    double *target, *achieved;  /* percent */
    double max_error_pp;
} gp_fit_passing;

/* 5 % critical value of D: 1.36 / sqrt(n) (asymptotic; 0 for n = 0). */
double gp_fit_ks_critical(size_t n);

/* The two-sided KS distance to the uniform law of the ascending values u[0..n) in [0, 1] (the
 * u_i = F(x_(i)) of a sample against its law's CDF F). */
double gp_fit_ks_uniform(const double *u, size_t n);

/* The two-sided KS distance of the ascending values x[0..n) to law's CDF (the ks that
 * gp_fit_area_measure reports, alone and without a copy). */
double gp_fit_ks_sorted(const double *x, size_t n, const gp_law *law);

/* Fit of n values (areas) to law. n = 0: present = 0 with the target fields filled, GP_OK
 * (values may then be NULL). A non-finite value: GP_ERR_INVALID naming its index. ncurve: the
 * number of curve points (0: no curve). COV is 0 for n = 1. */
gp_status gp_fit_area_measure(const double *values, size_t n, const gp_law *law, size_t ncurve,
                              gp_fit_area *out, gp_error *err);
void gp_fit_area_free(gp_fit_area *f);

/* Fit of n directions (degrees, any value: taken modulo 180 into the law's window) to the
 * cosine law of mean mean_deg and anisotropy in (0, 1]. n = 0: present = 0, GP_OK. */
gp_status gp_fit_orient_measure(const double *theta_deg, size_t n, double mean_deg,
                                double anisotropy, gp_fit_orient *out, gp_error *err);

/* Percent passing by mass of n grain areas (>= 0) at the sieve diameters of sieve_law (the law
 * the grains must follow, not the cell law scaled from it): its rows (gp_law_sieve_rows), in the
 * length unit of sqrt(area), times sqrt(factor) for a law made by gp_law_scaled. A sieve on
 * volumes (gp_law_create_sieve3d) takes grain volumes: d = (6 V / pi)^(1/3), cbrt(factor). A law
 * that is not a sieve, or n = 0, gives out->n = 0 and GP_OK. */
gp_status gp_fit_passing_measure(const double *areas, size_t n, const gp_law *sieve_law,
                                 gp_fit_passing *out, gp_error *err);
void gp_fit_passing_free(gp_fit_passing *p);

#endif /* GP_FIT_H */
