/* test_fit.c -- goodness of fit of a specimen (gp_fit.h): KS, W1, moments, curves, orientation
 * and passing by mass, each held to an independent truth (closed forms through GSL's normal
 * distribution, brute force on a fine grid, hand-counted masses). */
#include "gp_fit.h"
#include "gp_test.h"

#include <gsl/gsl_cdf.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- independent lognormal truth (mean m, cov c) through GSL ---- */

typedef struct { double m, mu, s; } logn;

static logn logn_of(double mean, double cov)
{
    logn L;
    L.m = mean;
    L.s = sqrt(log(1 + cov * cov));
    L.mu = log(mean) - 0.5 * L.s * L.s;
    return L;
}

static double logn_q(logn L, double p) { return gsl_cdf_lognormal_Pinv(p, L.mu, L.s); }
static double logn_F(logn L, double x) { return x > 0 ? gsl_cdf_lognormal_P(x, L.mu, L.s) : 0; }

/* integral over p in [pa, pb] of Q(p) dp = E[X; Q(pa) < X <= Q(pb)] = m [Phi(za - s) ..] */
static double logn_partial(logn L, double pa, double pb)
{
    double za = pa <= 0 ? -INFINITY : gsl_cdf_ugaussian_Pinv(pa);
    double zb = pb >= 1 ? INFINITY : gsl_cdf_ugaussian_Pinv(pb);
    double lo = isinf(za) ? 0 : gsl_cdf_ugaussian_P(za - L.s);
    double hi = isinf(zb) ? 1 : gsl_cdf_ugaussian_P(zb - L.s);
    return L.m * (hi - lo);
}

/* W1 of sorted x against the lognormal, in closed form: on ((i-1)/n, i/n] Q_n = x_i, and
 * |x_i - Q| splits at p* = F(x_i). */
static double logn_w1(logn L, const double *x, size_t n)
{
    double w = 0;
    for (size_t i = 0; i < n; i++) {
        double pa = (double)i / n, pb = (double)(i + 1) / n;
        double ps = fmin(fmax(logn_F(L, x[i]), pa), pb);
        w += x[i] * (ps - pa) - logn_partial(L, pa, ps) + logn_partial(L, ps, pb) - x[i] * (pb - ps);
    }
    return w;
}

static double *logn_sample(logn L, size_t n)
{
    double *x = malloc(n * sizeof *x);
    for (size_t i = 0; i < n; i++)
        x[i] = logn_q(L, (i + 0.5) / n);
    return x;
}

/* brute-force KS on a fine log grid, with the empirical CDF's left and right limits */
static int cmpd(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double brute_ks(logn L, const double *xs, size_t n)
{
    double *x = malloc(n * sizeof *x);
    memcpy(x, xs, n * sizeof *x);
    qsort(x, n, sizeof *x, cmpd);
    double a = x[0] / 4, b = x[n - 1] * 4, d = 0;
    size_t i = 0, m = 2000000;
    for (size_t j = 0; j <= m; j++) {
        double v = a * pow(b / a, (double)j / m);
        size_t below = i;               /* values < v */
        while (i < n && x[i] <= v)
            i++;
        double F = logn_F(L, v);
        d = fmax(d, fmax(fabs(F - (double)below / n), fabs(F - (double)i / n)));
    }
    free(x);
    return d;
}

/* ---- tests ---- */

static void test_ks_quantile_placed(void)
{
    gp_error e;
    const gp_law_kind kinds[3] = {GP_LAW_LOGNORMAL, GP_LAW_NORMAL, GP_LAW_UNIFORM};
    const size_t n = 200;
    double x[200];
    for (int k = 0; k < 3; k++) {
        gp_law *law = gp_law_create(kinds[k], 2.0, 0.3, &e);
        for (size_t i = 0; i < n; i++)
            x[i] = gp_law_quantile(law, (i + 0.5) / n);
        gp_fit_area f;
        CHECK(gp_fit_area_measure(x, n, law, 0, &f, &e) == GP_OK);
        CHECK(f.present == 1 && f.n == n && f.law == kinds[k]);
        CHECK_NEAR(f.ks, 0.5 / n, 1e-12);
        CHECK_NEAR(f.ks_critical, 1.36 / sqrt(200.0), 1e-15);
        gp_fit_area_free(&f);
        gp_law_destroy(law);
    }
    /* a sieve law too (bounded, kinked CDF), values given in any order */
    const double d[4] = {1, 2, 4, 8}, pw[4] = {0, 10, 60, 100};
    gp_law *sv = gp_law_create_sieve(d, pw, 4, &e);
    for (size_t i = 0; i < n; i++)
        x[(i * 7) % n] = gp_law_quantile(sv, (i + 0.5) / n);
    gp_fit_area f;
    CHECK(gp_fit_area_measure(x, n, sv, 0, &f, &e) == GP_OK);
    CHECK_NEAR(f.ks, 0.5 / n, 1e-12);
    gp_fit_area_free(&f);
    gp_law_destroy(sv);
}

/* values of a lognormal COV 0.4 against the COV 0.2 law of the same mean */
static void test_ks_w1_other_law(void)
{
    gp_error e;
    const size_t n = 300;
    logn wide = logn_of(3.0, 0.4), target = logn_of(3.0, 0.2);
    double *x = logn_sample(wide, n);
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 3.0, 0.2, &e);
    gp_fit_area f;
    CHECK(gp_fit_area_measure(x, n, law, 64, &f, &e) == GP_OK);
    double kb = brute_ks(target, x, n);
    CHECK(f.ks >= kb - 1e-12);          /* a grid only sees less */
    CHECK_NEAR(f.ks, kb, 2e-5);
    CHECK(f.ks > f.ks_critical);        /* and it is a clear misfit */
    /* W1 against the closed form */
    double w = logn_w1(target, x, n);
    CHECK_REL(f.w1, w / 3.0, 1e-9);
    CHECK(f.w1 > 0.05);
    /* the achieved moments and range */
    CHECK_NEAR(f.target_mean, 3.0, 1e-12);
    CHECK_NEAR(f.target_cov, 0.2, 1e-12);
    CHECK_NEAR(f.q001, logn_q(target, 0.001), 1e-9);
    CHECK_NEAR(f.q999, logn_q(target, 0.999), 1e-9);
    CHECK(f.min == x[0] && f.max == x[n - 1]);
    CHECK_NEAR(f.cov, 0.4, 0.02);
    gp_fit_area_free(&f);
    gp_law_destroy(law);
    free(x);
}

/* a sample placed at its own law's quantiles: W1 is small and equals the closed form */
static void test_w1_own_law(void)
{
    gp_error e;
    const size_t n = 500;
    logn L = logn_of(1.5, 1.0);
    double *x = logn_sample(L, n);
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.5, 1.0, &e);
    gp_fit_area f;
    CHECK(gp_fit_area_measure(x, n, law, 0, &f, &e) == GP_OK);
    double w = logn_w1(L, x, n);
    CHECK_REL(f.w1, w / 1.5, 1e-9);
    CHECK(f.w1 < 0.02);
    CHECK(f.curve_x == NULL && f.ncurve == 0);
    gp_fit_area_free(&f);
    gp_law_destroy(law);
    free(x);
}

/* uniform laws: W1 in closed form */
static void test_w1_uniform(void)
{
    gp_error e;
    const size_t n = 100;
    gp_law *u = gp_law_create(GP_LAW_UNIFORM, 1.0, 0.2, &e);
    double lo, hi, x[100];
    gp_law_support(u, &lo, &hi);
    for (size_t i = 0; i < n; i++)
        x[i] = gp_law_quantile(u, (i + 0.5) / n);
    gp_fit_area f;
    /* own law: Q linear of slope w = hi - lo, |x_i - Q| on each 1/n: w / (4 n^2) */
    CHECK(gp_fit_area_measure(x, n, u, 0, &f, &e) == GP_OK);
    CHECK_REL(f.w1, (hi - lo) / (4.0 * n) / 1.0, 1e-10);
    gp_fit_area_free(&f);
    /* the same width shifted by 0.1 (> w / 2n): Q_n - Q never changes sign, W1 = 0.1 */
    gp_law *s = gp_law_create(GP_LAW_UNIFORM, 1.1, 0.2 / 1.1, &e);
    CHECK(gp_fit_area_measure(x, n, s, 0, &f, &e) == GP_OK);
    CHECK_REL(f.w1, 0.1 / 1.1, 1e-10);
    gp_fit_area_free(&f);
    /* one value v in [a, b]: W1 = ((v - a)^2 + (b - v)^2) / (2 (b - a)); outside: |v - mean| */
    gp_law *w = gp_law_create(GP_LAW_UNIFORM, 1.0, 0.5, &e);
    gp_law_support(w, &lo, &hi);
    const double vs[4] = {0.3, 1.0, 1.7, 2.5};
    for (int k = 0; k < 4; k++) {
        double v = vs[k];
        double want = v <= hi ? ((v - lo) * (v - lo) + (hi - v) * (hi - v)) / (2 * (hi - lo))
                              : v - 1.0;
        CHECK(gp_fit_area_measure(&v, 1, w, 0, &f, &e) == GP_OK);
        CHECK_REL(f.w1, want, 1e-10);
        CHECK(f.cov == 0 && f.mean == v);
        gp_fit_area_free(&f);
    }
    gp_law_destroy(u);
    gp_law_destroy(s);
    gp_law_destroy(w);
}

/* one value against a lognormal: W1 = E|X - v| = m - v + 2 (v F(v) - m Phi(z - s)) */
static void test_w1_one_value_lognormal(void)
{
    gp_error e;
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 2.0, 3.0, &e);   /* heavy tail */
    logn L = logn_of(2.0, 3.0);
    const double vs[3] = {0.01, 2.0, 50.0};
    for (int k = 0; k < 3; k++) {
        double v = vs[k], z = (log(v) - L.mu) / L.s;
        double want = 2.0 - v + 2 * (v * logn_F(L, v) - 2.0 * gsl_cdf_ugaussian_P(z - L.s));
        gp_fit_area f;
        CHECK(gp_fit_area_measure(&v, 1, law, 0, &f, &e) == GP_OK);
        CHECK_REL(f.w1, want / 2.0, 1e-9);
        gp_fit_area_free(&f);
    }
    gp_law_destroy(law);
}

/* a sieve law (kinks in F): W1 against a fine midpoint rule in p on Q (bounded) */
static void test_w1_sieve(void)
{
    gp_error e;
    const double d[5] = {1, 2, 3, 5, 8}, pw[5] = {0, 5, 40, 80, 100};
    gp_law *sv = gp_law_create_sieve(d, pw, 5, &e);
    gp_law *sc = gp_law_scaled(sv, 2.5, &e);
    const gp_law *laws[2] = {sv, sc};
    double x[7] = {0.5, 2.0, 3.0, 6.0, 9.0, 20.0, 70.0};   /* some outside the support */
    for (int k = 0; k < 2; k++) {
        double w = 0;                   /* each step ((i-1)/7, i/7] of Q_n on its own grid */
        size_t m = 300000;
        for (size_t i = 0; i < 7; i++)
            for (size_t j = 0; j < m; j++) {
                double p = (i + (j + 0.5) / m) / 7;
                w += fabs(x[i] - gp_law_quantile(laws[k], p)) / (7.0 * m);
            }
        gp_fit_area f;
        CHECK(gp_fit_area_measure(x, 7, laws[k], 0, &f, &e) == GP_OK);
        CHECK_REL(f.w1 * gp_law_mean(laws[k]), w, 1e-7);
        gp_fit_area_free(&f);
    }
    gp_law_destroy(sv);
    gp_law_destroy(sc);
}

static void test_moments_and_curve(void)
{
    gp_error e;
    const double x[5] = {4, 1, 2, 2, 6};
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 3.0, 1.0, &e);
    gp_fit_area f;
    CHECK(gp_fit_area_measure(x, 5, law, 50, &f, &e) == GP_OK);
    /* mean 3, squared deviations 1 + 4 + 1 + 1 + 9 = 16, sd = sqrt(16 / 4) = 2 */
    CHECK_NEAR(f.mean, 3.0, 1e-15);
    CHECK_NEAR(f.cov, 2.0 / 3.0, 1e-15);
    CHECK(f.min == 1 && f.max == 6);
    /* the curve: over [q001, q999] (wider than the sample), log-spaced (> a decade) */
    CHECK(f.ncurve == 50);
    CHECK_NEAR(f.curve_x[0], gp_law_quantile(law, 0.001), 1e-12);
    CHECK(f.curve_x[49] == gp_law_quantile(law, 0.999));
    double r = f.curve_x[1] / f.curve_x[0];
    for (size_t j = 1; j < 50; j++) {
        CHECK_REL(f.curve_x[j] / f.curve_x[j - 1], r, 1e-9);
        CHECK(f.curve_target[j] >= f.curve_target[j - 1]);
    }
    for (size_t j = 0; j < 50; j++) {
        double v = f.curve_x[j];
        int c = 0;
        for (int i = 0; i < 5; i++)
            c += x[i] <= v;
        CHECK(f.curve_achieved[j] == c / 5.0);
        CHECK(f.curve_target[j] == gp_law_cdf(law, v));
    }
    CHECK(f.curve_achieved[0] == 0 && f.curve_achieved[49] == 1);
    gp_fit_area_free(&f);
    gp_fit_area_free(&f);               /* safe twice */
    /* a narrow law and a sample beyond it: linear spacing over [min, q999] */
    gp_law *u = gp_law_create(GP_LAW_UNIFORM, 3.0, 0.1, &e);
    CHECK(gp_fit_area_measure(x, 5, u, 11, &f, &e) == GP_OK);
    CHECK(f.curve_x[0] == 1.0 && f.curve_x[10] == 6.0);
    CHECK_NEAR(f.curve_x[5], 3.5, 1e-12);
    CHECK_NEAR(f.curve_x[6] - f.curve_x[5], 0.5, 1e-12);
    gp_fit_area_free(&f);
    gp_law_destroy(u);
    gp_law_destroy(law);
}

/* The wrong specimen: the right mean, a middle that keeps KS under its critical value, but no
 * tails (the 5 % at each end pulled in to the 5 % / 95 % quantiles). KS does not see it; the
 * COV, the range and W1 do. */
static void test_wrong_tails(void)
{
    gp_error e;
    const size_t n = 200;
    const double mean = 1.0, cov = 0.5;
    logn L = logn_of(mean, cov);
    double *good = logn_sample(L, n), *bad = logn_sample(L, n);
    double q05 = logn_q(L, 0.05), q95 = logn_q(L, 0.95), s = 0;
    for (size_t i = 0; i < n; i++) {
        bad[i] = fmin(fmax(bad[i], q05), q95);
        s += bad[i];
    }
    for (size_t i = 0; i < n; i++)
        bad[i] *= mean * n / s;         /* the mean put back exactly */
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, mean, cov, &e);
    gp_fit_area g, b;
    CHECK(gp_fit_area_measure(good, n, law, 0, &g, &e) == GP_OK);
    CHECK(gp_fit_area_measure(bad, n, law, 0, &b, &e) == GP_OK);
    CHECK_NEAR(b.mean, mean, 1e-12);
    CHECK(b.ks < b.ks_critical);        /* KS alone passes it */
    CHECK(b.cov < 0.9 * cov);           /* 0.43 for 0.5 */
    CHECK(g.cov > 0.97 * cov);
    CHECK(b.max < 0.7 * b.q999);        /* the largest areas are missing */
    CHECK(g.max > 0.8 * g.q999);        /* the sample that has them */
    CHECK(b.w1 > 4 * g.w1);
    CHECK_REL(b.w1 * mean, logn_w1(L, bad, n), 1e-9);
    gp_fit_area_free(&g);
    gp_fit_area_free(&b);
    gp_law_destroy(law);
    free(good);
    free(bad);
}

/* the cosine law's CDF on [mean - 90, mean + 90), written out independently */
static double orient_F(double mean, double a, double th)
{
    double x = th - (mean - 90);
    x = fmod(x, 180.0);
    if (x < 0) x += 180;
    x *= M_PI / 180;
    return ((1 + a) / 2 * x - (1 - a) / 4 * sin(2 * x)) / ((1 + a) * M_PI / 2);
}

static void test_orientation(void)
{
    gp_error e;
    gp_fit_orient o;
    const size_t n = 90;
    double th[90];
    /* isotropic, evenly spaced on the window: D = 0.5 / n; +-180 k changes nothing */
    for (size_t i = 0; i < n; i++)
        th[i] = -90 + 180.0 * (i + 0.5) / n + 180.0 * ((int)(i % 5) - 2);
    CHECK(gp_fit_orient_measure(th, n, 0.0, 1.0, &o, &e) == GP_OK);
    CHECK(o.present == 1 && o.n == n);
    CHECK_NEAR(o.ks, 0.5 / n, 1e-12);
    CHECK_NEAR(o.ks_critical, 1.36 / sqrt(90.0), 1e-15);
    /* the window: for mean 0, 179 deg is -1 deg, so u = 89 / 180 and D = 91 / 180 */
    double t179 = 179, tm1 = -1;
    gp_fit_orient p;
    CHECK(gp_fit_orient_measure(&t179, 1, 0.0, 1.0, &o, &e) == GP_OK);
    CHECK(gp_fit_orient_measure(&tm1, 1, 0.0, 1.0, &p, &e) == GP_OK);
    CHECK_NEAR(o.ks, 91.0 / 180.0, 1e-12);
    CHECK(o.ks == p.ks);
    /* for mean 30 the window is [-60, 120): 179 is -1 there too, u = 59 / 180 */
    CHECK(gp_fit_orient_measure(&t179, 1, 30.0, 1.0, &o, &e) == GP_OK);
    CHECK_NEAR(o.ks, 121.0 / 180.0, 1e-12);
    /* anisotropic: against the closed-form CDF, KS computed here */
    const double a = 0.4, mean = 25;
    double u[90];
    for (size_t i = 0; i < n; i++) {
        th[i] = 10.0 + 37.0 * sin(1.7 * i) + 180.0 * (i % 3);
        u[i] = orient_F(mean, a, th[i]);
    }
    qsort(u, n, sizeof *u, cmpd);
    double d = 0;
    for (size_t i = 0; i < n; i++)
        d = fmax(d, fmax((i + 1.0) / n - u[i], u[i] - (double)i / n));
    CHECK(gp_fit_orient_measure(th, n, mean, a, &o, &e) == GP_OK);
    CHECK_NEAR(o.ks, d, 1e-12);
    CHECK(o.target_mean_deg == mean && o.target_anisotropy == a);
}

static void test_passing(void)
{
    gp_error e;
    /* discs of diameters 1, 2, 3, 4 (mass ~ d^2: 1, 4, 9, 16 of 30) */
    double areas[4];
    const double dd[4] = {3, 1, 4, 2};
    for (int i = 0; i < 4; i++)
        areas[i] = M_PI / 4 * dd[i] * dd[i];
    const double d[4] = {0.5, 2.5, 3.5, 5}, pw[4] = {0, 20, 60, 100};
    gp_law *sv = gp_law_create_sieve(d, pw, 4, &e);
    gp_fit_passing p;
    CHECK(gp_fit_passing_measure(areas, 4, sv, &p, &e) == GP_OK);
    CHECK(p.n == 4);
    const double want[4] = {0, 100.0 * 5 / 30, 100.0 * 14 / 30, 100};
    for (int k = 0; k < 4; k++) {
        CHECK(p.diameters[k] == d[k]);
        CHECK(p.target[k] == pw[k]);
        CHECK_NEAR(p.achieved[k], want[k], 1e-12);
    }
    CHECK_NEAR(p.max_error_pp, 60 - 100.0 * 14 / 30, 1e-12);
    gp_fit_passing_free(&p);
    gp_fit_passing_free(&p);            /* safe twice */
    /* a scaled law (areas x 4): its sieves are at twice the diameters */
    gp_law *sc = gp_law_scaled(sv, 4.0, &e);
    for (int i = 0; i < 4; i++)
        areas[i] *= 4;
    CHECK(gp_fit_passing_measure(areas, 4, sc, &p, &e) == GP_OK);
    for (int k = 0; k < 4; k++) {
        CHECK_REL(p.diameters[k], 2 * d[k], 1e-14);
        CHECK_NEAR(p.achieved[k], want[k], 1e-12);
    }
    gp_fit_passing_free(&p);
    /* not a sieve law, or no grains: nothing to report */
    gp_law *ln = gp_law_create(GP_LAW_LOGNORMAL, 1.0, 0.5, &e);
    CHECK(gp_fit_passing_measure(areas, 4, ln, &p, &e) == GP_OK && p.n == 0);
    CHECK(gp_fit_passing_measure(NULL, 0, sv, &p, &e) == GP_OK && p.n == 0);
    areas[2] = -1;
    CHECK(gp_fit_passing_measure(areas, 4, sv, &p, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "area[2]") != NULL);
    gp_law_destroy(ln);
    gp_law_destroy(sc);
    gp_law_destroy(sv);
}

static void test_degenerate(void)
{
    gp_error e;
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 2.0, 0.5, &e);
    gp_fit_area f;
    CHECK(gp_fit_area_measure(NULL, 0, law, 10, &f, &e) == GP_OK);
    CHECK(f.present == 0 && f.n == 0 && f.ncurve == 0 && f.curve_x == NULL);
    CHECK(f.target_mean == 2.0 && f.target_cov == 0.5);
    gp_fit_area_free(&f);
    double x[5] = {1, 2, 3, NAN, 5};
    CHECK(gp_fit_area_measure(x, 5, law, 10, &f, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "[3]") != NULL);
    CHECK(f.present == 0 && f.curve_x == NULL);
    x[3] = INFINITY;
    CHECK(gp_fit_area_measure(x, 5, law, 10, &f, &e) == GP_ERR_INVALID);
    CHECK(gp_fit_area_measure(x, 5, NULL, 10, &f, NULL) == GP_ERR_INVALID);
    gp_fit_orient o;
    CHECK(gp_fit_orient_measure(NULL, 0, 0, 0.5, &o, &e) == GP_OK && o.present == 0);
    CHECK(gp_fit_orient_measure(x, 5, 0, 0.5, &o, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "theta_deg[3]") != NULL);
    CHECK(gp_fit_orient_measure(x, 3, 0, 0.0, &o, &e) == GP_ERR_INVALID);
    CHECK(gp_fit_orient_measure(x, 3, 0, 1.5, &o, &e) == GP_ERR_INVALID);
    gp_law_destroy(law);
}

/* a large specimen: W1 stays accurate (closed form) and the whole report is quick */
static void test_large(void)
{
    gp_error e;
    const size_t n = 100000;
    logn L = logn_of(1.0, 0.8), T = logn_of(1.0, 0.7);
    double *x = logn_sample(L, n);
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.0, 0.7, &e);
    gp_fit_area f;
    CHECK(gp_fit_area_measure(x, n, law, 200, &f, &e) == GP_OK);
    CHECK_REL(f.w1, logn_w1(T, x, n), 1e-9);
    gp_fit_area_free(&f);
    gp_law_destroy(law);
    free(x);
}

int main(void)
{
    test_ks_quantile_placed();
    test_ks_w1_other_law();
    test_w1_own_law();
    test_w1_uniform();
    test_w1_one_value_lognormal();
    test_w1_sieve();
    test_moments_and_curve();
    test_wrong_tails();
    test_orientation();
    test_passing();
    test_degenerate();
    test_large();
    return gp_test_summary();
}
