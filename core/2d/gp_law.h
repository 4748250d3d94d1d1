/* gp_law.h -- the target laws of a 2D specimen: cell/grain area laws and the orientation law.
 *
 * Area laws (api.md "2D size laws"), all on areas A > 0 counted by number:
 *   - lognormal (Mollon & Zhao 2012 §3.3.2, NOTES.md): mean m, standard deviation cov * m.
 *   - normal: a normal law truncated to A > 0 whose *truncated* mean and COV are m and cov
 *     (the underlying mu, sigma are solved for, so the law the user asked for is the law
 *     measured); cov <= 0.6.
 *   - uniform: A uniform on [m (1 - sqrt(3) cov), m (1 + sqrt(3) cov)]; cov <= 1/sqrt(3).
 *   - sieve: a curve of percent passing by mass pw_k at equivalent diameters d_k
 *     (d = sqrt(4 A / pi); 2D mass is proportional to area). Between sieves the mass is
 *     uniform in d (passing linear in d), the convention of gp_sieve for 3D. The number
 *     density in d is then proportional to s_k / d^2 in bin k (s_k the mass per unit d), which
 *     gives the number CDF, quantile, mean and COV of A in closed form. The same curve on
 *     volumes (gp_law_create_sieve3d: d = (6 V / pi)^(1/3), mass ~ V) is the 3D law.
 * Every law can be scaled (A -> factor A): a grain law is the cell law scaled by the solid
 * fraction, and a sieve law is put on cells by scaling with 1 / solid fraction.
 *
 * For the Anderson-Darling objective of the IMC (gp_imc.h) the log-CDF ln F and log-survival
 * ln(1 - F) are needed far into the tails, where F underflows: gp_law_log_cdf_sf() computes
 * them with log-erfc for the normal family. Bounded laws (uniform, sieve) have F = 0 or 1 outside
 * their support, which would give a flat -inf penalty (no way back for a cell outside); there
 * the IMC works with F_w = (1 - eta) F + eta T, T the lognormal of the same mean and COV
 * max(cov, 1), eta = 1e-6: finite everywhere, rising towards the support, and the same as F
 * to 1e-6 inside it. Reports (gp_fit) use F itself.
 *
 * Orientation law (Mollon & Zhao Eq. 12, as in gp_imc.h): on the pi-periodic direction theta,
 * density proportional to (1 + a)/2 + (1 - a)/2 cos(2 (theta - theta_bar)), anisotropy a in
 * (0, 1] the ratio of least to most probable density. Its CDF is taken on the window
 * [theta_bar - 90, theta_bar + 90) degrees, which starts where the law is least probable, so
 * that a direction near the cut is rare under the law wherever a < 1.
 *
 * Ownership: gp_law is immutable after creation; its queries are pure and may run from any
 * number of threads at once. No global state.
 */
#ifndef GP_LAW_H
#define GP_LAW_H

#include <stddef.h>

#include "gp_error.h"

typedef enum gp_law_kind {
    GP_LAW_LOGNORMAL = 0,
    GP_LAW_NORMAL = 1,
    GP_LAW_UNIFORM = 2,
    GP_LAW_SIEVE = 3
} gp_law_kind;

#define GP_LAW_NORMAL_COV_MAX 0.6
#define GP_LAW_UNIFORM_COV_MAX 0.5773502691896257 /* 1 / sqrt(3) */
#define GP_LAW_COV_MIN 0.01

/* "lognormal", "normal", "uniform", "sieve" (static strings); NULL for an unknown kind. */
const char *gp_law_name(gp_law_kind kind);

typedef struct gp_law gp_law;

/* A parametric law (lognormal, normal, uniform) of mean > 0 and coefficient of variation cov
 * (GP_LAW_COV_MIN <= cov <= 3, and the kind's own maximum above). */
gp_law *gp_law_create(gp_law_kind kind, double mean, double cov, gp_error *err);

/* A sieve law on areas: n >= 2 rows, d strictly increasing and > 0 (length units of the
 * areas), pw non-decreasing from 0 to 100 (percent passing by mass, within 1e-9). */
gp_law *gp_law_create_sieve(const double *d, const double *pw, size_t n, gp_error *err);

/* The same on volumes V = pi d^3 / 6 with mass proportional to V (the 3D grains of
 * gp_fv3d.h): in bin k the number density is s_k / d^3. Scaled, powered and queried as any law;
 * gp_law_sieve_rows gives its rows. */
gp_law *gp_law_create_sieve3d(const double *d, const double *pw, size_t n, gp_error *err);

/* The same law with every area multiplied by factor > 0. */
gp_law *gp_law_scaled(const gp_law *law, double factor, gp_error *err);

/* The law of lam A^kappa, A of `law`, with lam chosen so that its mean is `mean` (> 0), kappa
 * in (0, 4]: kappa < 1 draws the law together in log scale (ln A's spread times kappa), which
 * keeps its order and shape class. A lognormal stays a lognormal (COV sqrt(exp(kappa^2 s^2) - 1)
 * for ln A's sd s); any other law keeps its kind with the transform on top: its mean and COV
 * integrated from the quantile (GSL fixed Gauss-Legendre, graded pieces), and
 * gp_law_sieve_rows gives none
 * (the rows are the base law's). kappa = 1 is gp_law_scaled. Used by the 2D specimen to size
 * cells for the grains they can hold (gp_specimen2d.h). */
gp_law *gp_law_powered(const gp_law *law, double kappa, double mean, gp_error *err);

void gp_law_destroy(gp_law *law);

gp_law_kind gp_law_kind_of(const gp_law *law);
double gp_law_mean(const gp_law *law);   /* number mean of A */
double gp_law_cov(const gp_law *law);    /* standard deviation / mean of A */
/* Support [lo, hi] of A (hi may be +inf, lo may be 0). */
void gp_law_support(const gp_law *law, double *lo, double *hi);

double gp_law_cdf(const gp_law *law, double a);
/* Quantile for p in [0, 1] (0 and 1 give the support's ends). */
double gp_law_quantile(const gp_law *law, double p);
/* ln F_w(a) and ln(1 - F_w(a)) of the working law (above), both finite for finite a > 0. */
void gp_law_log_cdf_sf(const gp_law *law, double a, double *log_cdf, double *log_sf);

/* The size of a grain of diameter d by the law's convention, pi d^2 / 4 (areas; every law but a
 * 3D sieve) or pi d^3 / 6 (gp_law_create_sieve3d), and its inverse: the diameter of size a. */
double gp_law_sieve_size(const gp_law *law, double d);
/* 3 for a sieve made by gp_law_create_sieve3d (or scaled from one), else 2 */
int gp_law_dim(const gp_law *law);
double gp_law_sieve_diameter(const gp_law *law, double a);

/* Sieve laws only: the rows as given (n, d[], pw[]); 0 rows for other kinds. The pointers
 * stay valid while the law lives. */
size_t gp_law_sieve_rows(const gp_law *law, const double **d, const double **pw);

/* Orientation law: the CDF u in [0, 1) of a direction theta_deg (any value, taken modulo 180
 * into the window [mean_deg - 90, mean_deg + 90)). */
double gp_orient_cdf(double mean_deg, double anisotropy, double theta_deg);
/* theta_deg taken into the window [mean_deg - 90, mean_deg + 90). */
double gp_orient_wrap(double mean_deg, double theta_deg);

#endif /* GP_LAW_H */
