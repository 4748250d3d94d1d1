/* gp_law.c -- area and orientation laws of a 2D specimen. See gp_law.h.
 *
 * The normal family goes through GSL (gsl_cdf_ugaussian_*, gsl_sf_log_erfc) so that the tails
 * are exact where a naive 1 - F would round to 0. The sieve law is closed-form per bin.
 */
#include "gp_law.h"

#include <gsl/gsl_cdf.h>
#include <gsl/gsl_integration.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_sf_erf.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LAW_PI 3.14159265358979323846
#define LAW_SQRT2 1.41421356237309504880
#define LAW_LN_HALF (-0.69314718055994530942)
/* weight of the lognormal tail law mixed into bounded laws for the IMC (gp_law.h) */
#define LAW_ETA 1e-6
#define LAW_SIEVE_MAX 1000

struct gp_law {
    gp_law_kind kind;
    double scale;          /* areas of the base law are multiplied by scale */
    double mean, cov;      /* of the scaled law, by number */
    /* lognormal: ln A ~ N(m, s^2) (base, scale folded into m) */
    double m, s;
    /* normal: underlying N(mu, sigma^2) truncated to A > 0; z0 = -mu / sigma, q0 = P(Z > z0) */
    double mu, sigma, q0;
    /* uniform: [lo, hi] */
    double lo, hi;
    /* sieve (base units): rows d, pw; per bin k (between rows k and k+1) s_k = mass per unit d,
     * cum[k] = number CDF weight below d_k; ztot = total number weight */
    size_t nrows;
    double *d, *pw, *slope, *cum;
    double ztot;
    int dim; /* 2: A = pi d^2 / 4, mass ~ d^2; 3: volumes V = pi d^3 / 6, mass ~ d^3 */
    /* tail law for bounded kinds: lognormal (tm, ts) */
    double tm, ts;
    /* a powered law (gp_law_powered): A = lam B^kappa, B the law above (the "base"; every
     * field above describes B); kappa = lam = 1 otherwise */
    double kappa, lam;
};

const char *gp_law_name(gp_law_kind kind)
{
    switch (kind) {
    case GP_LAW_LOGNORMAL: return "lognormal";
    case GP_LAW_NORMAL: return "normal";
    case GP_LAW_UNIFORM: return "uniform";
    case GP_LAW_SIEVE: return "sieve";
    }
    return NULL;
}

/* ---------------------------------------------------------------- normal-family helpers */

/* ln P(Z <= z) and ln P(Z > z) for a standard normal Z, accurate in both tails */
static double log_phic(double z)
{
    /* libm's erfc is accurate to the last bits until it underflows (z ~ 37); GSL's log-erfc
     * beyond, up to where it breaks down (NaN near z ~ 1e61); then the asymptotic series,
     * exact to double precision there. libm first because the IMC calls this for every
     * changed cell of every step. */
    if (z < 30.0) return log(0.5 * erfc(z / LAW_SQRT2));
    if (z < 1e6) return LAW_LN_HALF + gsl_sf_log_erfc(z / LAW_SQRT2);
    if (!(z < INFINITY)) return -INFINITY;
    return -0.5 * z * z - log(z) - 0.5 * log(2.0 * LAW_PI);
}
static double log_phi(double z) { return log_phic(-z); }

static double log_add(double a, double b)
{
    if (a == -INFINITY) return b;
    if (b == -INFINITY) return a;
    double hi = a > b ? a : b, lo = a > b ? b : a;
    return hi + log1p(exp(lo - hi));
}

static void lognormal_params(double mean, double cov, double *m, double *s)
{
    double s2 = log1p(cov * cov);
    *s = sqrt(s2);
    *m = log(mean) - 0.5 * s2;
}

/* mean and sd of N(mu, sigma^2) truncated to x > 0 */
static void trunc_moments(double mu, double sigma, double *mean, double *sd)
{
    double a = -mu / sigma, q = gsl_cdf_ugaussian_Q(a), lam = gsl_ran_ugaussian_pdf(a) / q;
    *mean = mu + sigma * lam;
    double var = sigma * sigma * (1.0 + a * lam - lam * lam);
    *sd = sqrt(var > 0 ? var : 0);
}

/* the underlying mu, sigma whose truncation to x > 0 has the given mean and sd: a fixed point
 * that converges in a few dozen steps for cov <= 0.6 (truncation removes < 5 %) */
static void trunc_solve(double mean, double sd, double *mu, double *sigma)
{
    double m = mean, s = sd;
    for (int it = 0; it < 200; it++) {
        double tm, ts;
        trunc_moments(m, s, &tm, &ts);
        double dm = mean - tm, rs = sd / ts;
        m += dm;
        s *= rs;
        if (fabs(dm) < 1e-15 * mean && fabs(rs - 1.0) < 1e-15) break;
    }
    *mu = m;
    *sigma = s;
}

/* ---------------------------------------------------------------- creation */

static gp_law *law_alloc(gp_law_kind kind)
{
    gp_law *l = calloc(1, sizeof *l);
    if (l) {
        l->kind = kind;
        l->scale = 1.0;
        l->kappa = l->lam = 1.0;
        l->dim = 2;
    }
    return l;
}

gp_law *gp_law_create(gp_law_kind kind, double mean, double cov, gp_error *err)
{
    if (!(mean > 0) || !isfinite(mean)) {
        gp_error_set(err, GP_ERR_INVALID, "law: mean must be > 0 and finite (got %g)", mean);
        return NULL;
    }
    double cmax = kind == GP_LAW_NORMAL ? GP_LAW_NORMAL_COV_MAX
                : kind == GP_LAW_UNIFORM ? GP_LAW_UNIFORM_COV_MAX : 3.0;
    if (kind == GP_LAW_SIEVE || !gp_law_name(kind)) {
        gp_error_set(err, GP_ERR_INVALID, "law: kind %d is not parametric", (int)kind);
        return NULL;
    }
    if (!(cov >= GP_LAW_COV_MIN && cov <= cmax * (1 + 1e-12))) {
        gp_error_set(err, GP_ERR_INVALID, "law: %s cov must be in [%g, %.4g] (got %g)",
                     gp_law_name(kind), GP_LAW_COV_MIN, cmax, cov);
        return NULL;
    }
    gp_law *l = law_alloc(kind);
    if (!l) {
        gp_error_set(err, GP_ERR_NOMEM, "law: out of memory");
        return NULL;
    }
    l->mean = mean;
    l->cov = cov;
    lognormal_params(mean, cov, &l->m, &l->s);
    if (kind == GP_LAW_NORMAL) {
        trunc_solve(mean, cov * mean, &l->mu, &l->sigma);
        l->q0 = gsl_cdf_ugaussian_Q(-l->mu / l->sigma);
    } else if (kind == GP_LAW_UNIFORM) {
        double h = sqrt(3.0) * cov * mean;
        l->lo = fmax(0.0, mean - h);
        l->hi = mean + h;
    }
    lognormal_params(mean, cov > 1 ? cov : 1.0, &l->tm, &l->ts);
    return l;
}

static gp_status sieve_check(const double *d, const double *pw, size_t n, gp_error *err)
{
    if (!d || !pw || n < 2 || n > LAW_SIEVE_MAX)
        return gp_error_set(err, GP_ERR_INVALID, "law: a sieve needs 2..%d rows", LAW_SIEVE_MAX);
    for (size_t k = 0; k < n; k++) {
        if (!(d[k] > 0) || !isfinite(d[k]) || (k && !(d[k] > d[k - 1])))
            return gp_error_set(err, GP_ERR_INVALID,
                                "law: sieve diameters must be > 0 and increasing (row %zu)", k);
        if (!(pw[k] >= 0 && pw[k] <= 100) || (k && pw[k] < pw[k - 1]))
            return gp_error_set(err, GP_ERR_INVALID,
                                "law: percent passing must be non-decreasing in [0, 100] (row %zu)", k);
    }
    if (fabs(pw[0]) > 1e-9 || fabs(pw[n - 1] - 100.0) > 1e-9)
        return gp_error_set(err, GP_ERR_INVALID, "law: a sieve goes from 0 to 100 %% passing");
    return GP_OK;
}

/* the number weight of a bin [a, b] of mass slope s: the integral of s / x^dim */
static double sieve_bin_weight(int dim, double s, double a, double x)
{
    return dim == 2 ? s * (1.0 / a - 1.0 / x) : 0.5 * s * (1.0 / (a * a) - 1.0 / (x * x));
}

/* the size of a grain of diameter x: its area (dim 2) or volume (dim 3) */
static double sieve_size(int dim, double x)
{
    return dim == 2 ? LAW_PI / 4 * x * x : LAW_PI / 6 * x * x * x;
}

static gp_law *sieve_create(const double *d, const double *pw, size_t n, int dim, gp_error *err)
{
    if (sieve_check(d, pw, n, err) != GP_OK) return NULL;
    gp_law *l = law_alloc(GP_LAW_SIEVE);
    if (!l || !(l->d = malloc(n * sizeof *l->d)) || !(l->pw = malloc(n * sizeof *l->pw)) ||
        !(l->slope = calloc(n, sizeof *l->slope)) || !(l->cum = calloc(n, sizeof *l->cum))) {
        gp_law_destroy(l);
        gp_error_set(err, GP_ERR_NOMEM, "law: out of memory");
        return NULL;
    }
    memcpy(l->d, d, n * sizeof *d);
    memcpy(l->pw, pw, n * sizeof *pw);
    l->nrows = n;
    l->dim = dim;
    /* a grain's size is c x^dim and its mass ~ x^dim, so the number density of bin k is
     * s_k / x^dim; by number E[A] Z = c sum s_k (b - a) and E[A^2] Z = c^2 sum s_k
     * (b^(dim+1) - a^(dim+1)) / (dim + 1) */
    double z = 0.0, ea = 0.0, ea2 = 0.0, c = sieve_size(dim, 1.0);
    for (size_t k = 0; k + 1 < n; k++) {
        double a = d[k], b = d[k + 1], s = (pw[k + 1] - pw[k]) / (b - a);
        l->slope[k] = s;
        l->cum[k] = z;
        z += sieve_bin_weight(dim, s, a, b);
        ea += s * (b - a);
        ea2 += dim == 2 ? s * (b * b * b - a * a * a) / 3.0 : s * (b * b * b * b - a * a * a * a) / 4.0;
    }
    l->cum[n - 1] = z;
    l->ztot = z;
    l->lo = sieve_size(dim, d[0]);
    l->hi = sieve_size(dim, d[n - 1]);
    l->mean = c * ea / z;
    double c2 = dim == 2 ? LAW_PI * LAW_PI / 16 : LAW_PI * LAW_PI / 36;
    double m2 = c2 * ea2 / z, var = m2 - l->mean * l->mean;
    l->cov = sqrt(var > 0 ? var : 0) / l->mean;
    lognormal_params(l->mean, l->cov > 1 ? l->cov : 1.0, &l->tm, &l->ts);
    return l;
}

gp_law *gp_law_create_sieve(const double *d, const double *pw, size_t n, gp_error *err)
{
    return sieve_create(d, pw, n, 2, err);
}

gp_law *gp_law_create_sieve3d(const double *d, const double *pw, size_t n, gp_error *err)
{
    return sieve_create(d, pw, n, 3, err);
}

gp_law *gp_law_scaled(const gp_law *src, double factor, gp_error *err)
{
    if (!src || !(factor > 0) || !isfinite(factor)) {
        gp_error_set(err, GP_ERR_INVALID, "law: scale factor must be > 0 (got %g)", factor);
        return NULL;
    }
    gp_law *l = law_alloc(src->kind);
    if (!l) {
        gp_error_set(err, GP_ERR_NOMEM, "law: out of memory");
        return NULL;
    }
    *l = *src;
    l->d = l->pw = l->slope = l->cum = NULL;
    if (src->kind == GP_LAW_SIEVE) {
        gp_law *c = sieve_create(src->d, src->pw, src->nrows, src->dim, err);
        if (!c) {
            free(l);
            return NULL;
        }
        l->d = c->d;
        l->pw = c->pw;
        l->slope = c->slope;
        l->cum = c->cum;
        free(c);
    }
    l->mean = src->mean * factor;
    if (src->kappa != 1.0) { /* lam B^kappa -> (factor lam) B^kappa: the base stays */
        l->lam = src->lam * factor;
        return l;
    }
    l->scale = src->scale * factor;
    l->m += log(factor);
    l->tm += log(factor);
    l->mu *= factor;
    l->sigma *= factor;
    l->lo *= factor;
    l->hi *= factor;
    return l;
}

static double base_quantile(const gp_law *l, double p);

typedef struct moment_ctx {
    const gp_law *base;
    double power;
} moment_ctx;

static double quantile_power(double p, void *v)
{
    const moment_ctx *c = v;
    double q = base_quantile(c->base, p);
    return q > 0 ? pow(q, c->power) : 0.0; /* a normal's quantile near A = 0 can round below */
}

static int cmp_dbl(const void *a, const void *b)
{
    double p = *(const double *)a, q = *(const double *)b;
    return p < q ? -1 : p > q;
}

#define MOMENT_POINTS 32 /* Gauss-Legendre points a piece */

/* E[B^power] = integral over p in (0, 1) of Q_B(p)^power, by GSL's fixed Gauss-Legendre rule on
 * pieces graded geometrically towards both ends (Q may go to 0 or to infinity there: 1e-16,
 * 1e-15, ..., 0.1, 0.5, ..., 1 - 1e-16; the 2e-16 of probability beyond is left out) and cut
 * at a sieve's rows, where its quantile has kinks.
 * A fixed rule, not GSL's adaptive QAGS: QAGS reports a failure through GSL's error handler,
 * process-wide and abort() by default, which a library run on worker threads must neither
 * trigger nor switch. NaN on allocation failure. */
static double base_moment(const gp_law *base, double power)
{
    size_t nrows = base->kind == GP_LAW_SIEVE ? base->nrows : 0, m = 0;
    double *cut = malloc((35 + nrows) * sizeof *cut);
    gsl_integration_glfixed_table *t = gsl_integration_glfixed_table_alloc(MOMENT_POINTS);
    if (!cut || !t) {
        free(cut);
        if (t) gsl_integration_glfixed_table_free(t);
        return NAN;
    }
    cut[m++] = 0.5;
    for (int e = 1; e <= 16; e++) {
        cut[m++] = pow(10.0, -e);
        cut[m++] = 1.0 - pow(10.0, -e);
    }
    for (size_t k = 0; k < nrows; k++)
        cut[m++] = base->cum[k] / base->ztot;
    qsort(cut, m, sizeof *cut, cmp_dbl);
    moment_ctx c = {base, power};
    gsl_function f = {quantile_power, &c};
    double sum = 0.0;
    for (size_t k = 0; k + 1 < m; k++)
        if (cut[k + 1] > cut[k] && cut[k] >= 1e-16 && cut[k + 1] <= 1.0 - 1e-16)
            sum += gsl_integration_glfixed(&f, cut[k], cut[k + 1], t);
    gsl_integration_glfixed_table_free(t);
    free(cut);
    return sum;
}

gp_law *gp_law_powered(const gp_law *src, double kappa, double mean, gp_error *err)
{
    if (!src || !(kappa > 0 && kappa <= 4) || !(mean > 0) || !isfinite(mean)) {
        gp_error_set(err, GP_ERR_INVALID, "law: power must be in (0, 4] and mean > 0 "
                                          "(got %g, %g)", kappa, mean);
        return NULL;
    }
    if (kappa == 1.0)
        return gp_law_scaled(src, mean / src->mean, err);
    if (src->kind == GP_LAW_LOGNORMAL) { /* lognormal again: ln A ~ N(., (kappa s)^2) */
        double cov = sqrt(expm1(kappa * kappa * src->s * src->s));
        return gp_law_create(GP_LAW_LOGNORMAL, mean, fmax(cov, GP_LAW_COV_MIN), err);
    }
    gp_law *l = gp_law_scaled(src, 1.0, err);
    if (!l) return NULL;
    l->kappa = src->kappa * kappa; /* the same base: lam' B^(kappa_src kappa) */
    double m1 = base_moment(l, l->kappa), m2 = base_moment(l, 2 * l->kappa);
    if (!(m1 > 0) || !(m2 > 0) || !isfinite(m1) || !isfinite(m2)) {
        gp_law_destroy(l);
        gp_error_set(err, GP_ERR_INVALID, "law: the moments of the powered law do not converge");
        return NULL;
    }
    l->lam = mean / m1;
    l->mean = mean;
    double var = m2 / (m1 * m1) - 1.0;
    l->cov = sqrt(var > 0 ? var : 0);
    return l;
}

void gp_law_destroy(gp_law *l)
{
    if (!l) return;
    free(l->d);
    free(l->pw);
    free(l->slope);
    free(l->cum);
    free(l);
}

/* ---------------------------------------------------------------- queries */

/* an area of the law -> the base law's, and back (identities unless powered) */
static double to_base(const gp_law *l, double a)
{
    return l->kappa == 1.0 ? a : pow(a / l->lam, 1.0 / l->kappa);
}

static double from_base(const gp_law *l, double b)
{
    return l->kappa == 1.0 ? b : l->lam * pow(b, l->kappa);
}

gp_law_kind gp_law_kind_of(const gp_law *l) { return l->kind; }
double gp_law_mean(const gp_law *l) { return l->mean; }
double gp_law_cov(const gp_law *l) { return l->cov; }

void gp_law_support(const gp_law *l, double *lo, double *hi)
{
    int bounded = l->kind == GP_LAW_UNIFORM || l->kind == GP_LAW_SIEVE;
    if (lo) *lo = bounded ? from_base(l, l->lo) : 0.0;
    if (hi) *hi = bounded ? from_base(l, l->hi) : INFINITY;
}

int gp_law_dim(const gp_law *l)
{
    return l->kind == GP_LAW_SIEVE ? l->dim : 2;
}

double gp_law_sieve_size(const gp_law *l, double d)
{
    return sieve_size(l->kind == GP_LAW_SIEVE ? l->dim : 2, d);
}

double gp_law_sieve_diameter(const gp_law *l, double a)
{
    if (l->kind == GP_LAW_SIEVE && l->dim == 3) return cbrt(6.0 * a / LAW_PI);
    return sqrt(4.0 * a / LAW_PI);
}

size_t gp_law_sieve_rows(const gp_law *l, const double **d, const double **pw)
{
    if (l->kind != GP_LAW_SIEVE || l->kappa != 1.0) return 0;
    if (d) *d = l->d;
    if (pw) *pw = l->pw;
    return l->nrows;
}

/* sieve: number CDF at base-unit diameter x */
static double sieve_cdf_d(const gp_law *l, double x)
{
    size_t n = l->nrows;
    if (x <= l->d[0]) return 0.0;
    if (x >= l->d[n - 1]) return 1.0;
    size_t lo = 0, hi = n - 1; /* bin k with d[k] <= x < d[k+1] */
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (l->d[mid] <= x) lo = mid; else hi = mid;
    }
    double c = l->cum[lo] + l->slope[lo] * (1.0 / l->d[lo] - 1.0 / x);
    return fmin(1.0, c / l->ztot);
}

static double sieve_quantile_d(const gp_law *l, double p)
{
    size_t n = l->nrows;
    double t = p * l->ztot;
    size_t k = 0;
    while (k + 2 < n && l->cum[k + 1] <= t) k++;
    while (k + 2 < n && l->slope[k] == 0.0) k++; /* skip empty bins */
    if (l->slope[k] == 0.0) return l->d[k];
    double inv = 1.0 / l->d[k] - (t - l->cum[k]) / l->slope[k];
    double x = inv > 0 ? 1.0 / inv : l->d[k + 1];
    return fmin(fmax(x, l->d[k]), l->d[k + 1]);
}

/* sieve on volumes: the number CDF at base-unit volume v. In bin k (lower row a, volume v_a)
 * the weight s / (2 a^2) (1 - (v_a / v)^(2/3)) is taken as -expm1(-(2/3) log1p((v - v_a) / v_a)):
 * v - v_a is exact near v_a, so the CDF keeps its relative precision at the bottom of a bin */
static double sieve3_cdf_v(const gp_law *l, double v)
{
    size_t n = l->nrows;
    double x = cbrt(6.0 * v / LAW_PI);
    if (x <= l->d[0] && v <= l->lo) return 0.0;
    if (v >= l->hi) return 1.0;
    size_t lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (l->d[mid] <= x) lo = mid; else hi = mid;
    }
    double a = l->d[lo], va = sieve_size(3, a), r = (v - va) / va;
    double w = r > 0 ? l->slope[lo] / (2.0 * a * a) * -expm1(-2.0 / 3.0 * log1p(r)) : 0.0;
    return fmin(1.0, (l->cum[lo] + w) / l->ztot);
}

/* its quantile: t - cum = s / (2 a^2) (1 - (v_a / v)^(2/3)) solved for v */
static double sieve3_quantile_v(const gp_law *l, double p)
{
    size_t n = l->nrows;
    double t = p * l->ztot;
    size_t k = 0;
    while (k + 2 < n && l->cum[k + 1] <= t) k++;
    while (k + 2 < n && l->slope[k] == 0.0) k++;
    double va = sieve_size(3, l->d[k]), vb = sieve_size(3, l->d[k + 1]);
    if (l->slope[k] == 0.0) return va;
    double a = l->d[k], e = 2.0 * a * a * (t - l->cum[k]) / l->slope[k];
    double v = e < 1.0 ? va * exp(-1.5 * log1p(-e)) : vb;
    return fmin(fmax(v, va), vb);
}

static double base_cdf(const gp_law *l, double a)
{
    if (!(a > 0)) return 0.0;
    switch (l->kind) {
    case GP_LAW_LOGNORMAL:
        return gsl_cdf_ugaussian_P((log(a) - l->m) / l->s);
    case GP_LAW_NORMAL: {
        double q = gsl_cdf_ugaussian_Q((a - l->mu) / l->sigma);
        return fmax(0.0, 1.0 - q / l->q0);
    }
    case GP_LAW_UNIFORM:
        return a <= l->lo ? 0.0 : a >= l->hi ? 1.0 : (a - l->lo) / (l->hi - l->lo);
    case GP_LAW_SIEVE:
        if (l->dim == 3) return sieve3_cdf_v(l, a / l->scale);
        return sieve_cdf_d(l, sqrt(4.0 * (a / l->scale) / LAW_PI));
    }
    return NAN;
}

static double base_quantile(const gp_law *l, double p)
{
    if (!(p >= 0 && p <= 1)) return NAN;
    switch (l->kind) {
    case GP_LAW_LOGNORMAL:
        if (p == 0) return 0.0;
        if (p == 1) return INFINITY;
        return exp(l->m + l->s * gsl_cdf_ugaussian_Pinv(p));
    case GP_LAW_NORMAL:
        if (p == 0) return 0.0;
        if (p == 1) return INFINITY;
        /* F(a) = 1 - Q(z)/q0 = p  <=>  Q(z) = (1 - p) q0 */
        return l->mu + l->sigma * gsl_cdf_ugaussian_Qinv((1.0 - p) * l->q0);
    case GP_LAW_UNIFORM:
        return l->lo + p * (l->hi - l->lo);
    case GP_LAW_SIEVE: {
        if (l->dim == 3) return sieve3_quantile_v(l, p) * l->scale;
        double x = sieve_quantile_d(l, p);
        return LAW_PI / 4 * x * x * l->scale;
    }
    }
    return NAN;
}

/* ln F and ln(1 - F) of the law itself (may be -inf outside a bounded support) */
static void log_cdf_sf_exact(const gp_law *l, double a, double *lf, double *ls)
{
    switch (l->kind) {
    case GP_LAW_LOGNORMAL: {
        double z = (log(a) - l->m) / l->s;
        *lf = log_phi(z);
        *ls = log_phic(z);
        return;
    }
    case GP_LAW_NORMAL: {
        double z = (a - l->mu) / l->sigma, lq0 = log(l->q0), z0 = -l->mu / l->sigma;
        double dz = a / l->sigma;
        *ls = fmin(0.0, log_phic(z) - lq0);
        /* F = (Phi(z) - Phi(z0)) / q0. Near a = 0 that difference cancels (z rounds to z0
         * below a ~ 1e-16 sigma): there F = phi(z0) dz (1 - z0 dz / 2 + O(dz^2)) / q0. */
        double f = base_cdf(l, a);
        if (f > 1e-3)
            *lf = log(f);
        else if (dz > 1e-5)
            *lf = log(gsl_cdf_ugaussian_P(z) - gsl_cdf_ugaussian_P(z0)) - lq0;
        else
            *lf = -0.5 * z0 * z0 - 0.5 * log(2.0 * LAW_PI) + log(dz) + log1p(-0.5 * z0 * dz) - lq0;
        return;
    }
    default: {
        double f = base_cdf(l, a);
        *lf = f > 0 ? log(f) : -INFINITY;
        *ls = f < 1 ? log1p(-f) : -INFINITY;
        return;
    }
    }
}

double gp_law_cdf(const gp_law *l, double a)
{
    return a > 0 ? base_cdf(l, to_base(l, a)) : 0.0;
}

double gp_law_quantile(const gp_law *l, double p)
{
    return from_base(l, base_quantile(l, p));
}

void gp_law_log_cdf_sf(const gp_law *l, double a, double *lf, double *ls)
{
    if (!(a > 0)) a = 1e-300;
    a = to_base(l, a);
    if (!(a > 0)) a = 1e-300;
    log_cdf_sf_exact(l, a, lf, ls);
    if (l->kind == GP_LAW_LOGNORMAL || l->kind == GP_LAW_NORMAL) return;
    double z = (log(a) - l->tm) / l->ts;
    *lf = fmin(0.0, log_add(log1p(-LAW_ETA) + *lf, log(LAW_ETA) + log_phi(z)));
    *ls = fmin(0.0, log_add(log1p(-LAW_ETA) + *ls, log(LAW_ETA) + log_phic(z)));
}

/* ---------------------------------------------------------------- orientation */

double gp_orient_wrap(double mean_deg, double theta_deg)
{
    double lo = mean_deg - 90.0, t = fmod(theta_deg - lo, 180.0);
    if (t < 0) t += 180.0;
    if (t >= 180.0) t = 0.0;
    return lo + t;
}

double gp_orient_cdf(double mean_deg, double a, double theta_deg)
{
    /* with x = theta - theta_bar + 90 deg in [0, 180): density (1+a)/2 - (1-a)/2 cos 2x' where
     * x' = x in radians (the cosine law shifted so that the window starts at its minimum) */
    double x = (gp_orient_wrap(mean_deg, theta_deg) - mean_deg + 90.0) * LAW_PI / 180.0;
    double num = (1.0 + a) / 2.0 * x - (1.0 - a) / 4.0 * sin(2.0 * x);
    double u = num / ((1.0 + a) * LAW_PI / 2.0);
    return u < 0 ? 0.0 : u >= 1.0 ? nextafter(1.0, 0.0) : u;
}
