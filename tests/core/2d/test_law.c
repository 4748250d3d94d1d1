/* test_law.c -- area and orientation laws (gp_law.h), each against a truth the test computes
 * itself: moments by quadrature of the quantile function, the sieve's number law by brute-force
 * integration of its density, tails by erfc and the asymptotic series, and the percent passing
 * by mass of a quantile sample. */
#include "gp_law.h"
#include "gp_test.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double phi_cdf(double z) { return 0.5 * erfc(-z / sqrt(2.0)); }

/* E[A] and COV of A as integrals of the quantile function, p = Phi(z) (Simpson in z on
 * [-8.2, 8.2], beyond which p rounds to 0 or 1; the mass left out is 2e-16) */
static void quantile_moments(const gp_law *l, double *mean, double *cov)
{
    const int n = 16400;
    const double z0 = -8.2, h = 16.4 / n;
    double s0 = 0, s1 = 0, s2 = 0;
    for (int i = 0; i <= n; i++) {
        double z = z0 + i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        double f = w * exp(-0.5 * z * z) / sqrt(2 * M_PI), a = gp_law_quantile(l, phi_cdf(z));
        s0 += f;
        s1 += f * a;
        s2 += f * a * a;
    }
    *mean = s1 / s0;
    *cov = sqrt(s2 / s0 - *mean * *mean) / *mean;
}

static const double P_GRID[] = {1e-12, 1e-9, 1e-6, 1e-3, 0.01, 0.1, 0.25, 0.5,
                                0.75,  0.9,  0.99, 0.999, 1 - 1e-6, 1 - 1e-9, 1 - 1e-12};
#define NP (sizeof P_GRID / sizeof P_GRID[0])

/* CDF(quantile(p)) == p to 1e-10 relative to min(p, 1 - p), plus what F moves across a couple
 * of ulps of the quantile (a double quantile has no more: near a bounded law's ends, and near 1,
 * where F itself is a double) and, for the normal, 1e-15 absolute (its quantile near A = 0 is
 * mu + sigma z with z near -mu / sigma, a cancellation) */
static void check_round_trip(const gp_law *l)
{
    for (size_t k = 0; k < NP; k++) {
        double p = P_GRID[k], q = gp_law_quantile(l, p), f = gp_law_cdf(l, q);
        double step = gp_law_cdf(l, q + 2 * (nextafter(q, INFINITY) - q)) -
                      gp_law_cdf(l, q - 2 * (nextafter(q, INFINITY) - q));
        double tol = 1e-10 * (p < 0.5 ? p : 1 - p) + 4 * DBL_EPSILON * p + step +
                     (gp_law_kind_of(l) == GP_LAW_NORMAL ? 1e-15 : 0);
        CHECK_NEAR(f, p, tol);
    }
}

static void test_parametric(void)
{
    const double covs[] = {0.01, 0.05, 0.3, 0.5, 1.0, 3.0};
    for (int kind = GP_LAW_LOGNORMAL; kind <= GP_LAW_UNIFORM; kind++) {
        for (size_t c = 0; c < sizeof covs / sizeof covs[0]; c++) {
            double cov = covs[c], mean = 2.5, qm, qc, lo, hi;
            if (kind == GP_LAW_NORMAL && cov > GP_LAW_NORMAL_COV_MAX) cov = GP_LAW_NORMAL_COV_MAX;
            if (kind == GP_LAW_UNIFORM && cov > GP_LAW_UNIFORM_COV_MAX) cov = GP_LAW_UNIFORM_COV_MAX;
            gp_error e;
            gp_law *l = gp_law_create((gp_law_kind)kind, mean, cov, &e);
            CHECK(l != NULL);
            if (!l) continue;
            CHECK(gp_law_kind_of(l) == (gp_law_kind)kind);
            CHECK_REL(gp_law_mean(l), mean, 1e-12);
            CHECK_REL(gp_law_cov(l), cov, 1e-12);
            quantile_moments(l, &qm, &qc);
            CHECK_REL(qm, mean, 1e-9);
            /* the lognormal's top beyond p = 1 - 1e-16 holds 1e-7 of E[A^2] at cov 3 */
            CHECK_REL(qc, cov, kind == GP_LAW_LOGNORMAL && cov > 1 ? 1e-6 : 1e-8);
            check_round_trip(l);
            gp_law_support(l, &lo, &hi);
            if (kind == GP_LAW_UNIFORM) {
                double w = sqrt(3.0) * cov * mean;
                CHECK_REL(lo + 1.0, mean - w + 1.0, 1e-14);
                CHECK_REL(hi, mean + w, 1e-14);
                CHECK(gp_law_cdf(l, lo) == 0.0 && gp_law_cdf(l, hi) == 1.0);
                CHECK_NEAR(gp_law_cdf(l, mean - 0.5 * w), 0.25, 1e-14);
                CHECK(gp_law_quantile(l, 0) == lo && gp_law_quantile(l, 1) == hi);
            } else {
                CHECK(lo == 0.0 && isinf(hi) && hi > 0);
                CHECK(gp_law_quantile(l, 0) == 0.0 && isinf(gp_law_quantile(l, 1)));
            }
            if (kind == GP_LAW_LOGNORMAL)
                CHECK_NEAR(gp_law_cdf(l, mean / sqrt(1 + cov * cov)), 0.5, 1e-14);
            if (kind == GP_LAW_NORMAL) {
                /* the truncated law by its CDF alone: E[A] = int (1 - F), E[A^2] = int 2a (1 - F)
                 * (Simpson on [0, mean (1 + 12 cov)]) */
                const int n = 200000;
                double top = mean * (1 + 12 * cov), h = top / n, s1 = 0, s2 = 0;
                for (int i = 0; i <= n; i++) {
                    double a = i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
                    double sf = 1 - gp_law_cdf(l, a);
                    s1 += w * sf;
                    s2 += w * 2 * a * sf;
                }
                s1 *= h / 3;
                s2 *= h / 3;
                CHECK_REL(s1, mean, 1e-9);
                CHECK_REL(sqrt(s2 - s1 * s1) / s1, cov, 1e-8);
                CHECK(gp_law_cdf(l, 0.0) == 0.0 && gp_law_cdf(l, -1.0) == 0.0);
            }
            gp_law_destroy(l);
        }
    }
    CHECK(!strcmp(gp_law_name(GP_LAW_LOGNORMAL), "lognormal") && !strcmp(gp_law_name(GP_LAW_SIEVE), "sieve"));
    CHECK(gp_law_name((gp_law_kind)7) == NULL);
}

/* ln Phi(z) for z << 0 from its asymptotic series (error ~ 105 / z^8) */
static double log_phi_asym(double z)
{
    double r = 1 / (z * z);
    return -0.5 * z * z - log(-z) - 0.5 * log(2 * M_PI) + log(1 - r + 3 * r * r - 15 * r * r * r);
}

static void test_log_cdf_sf(void)
{
    const double mean = 3.0, cov = 0.4, s = sqrt(log1p(cov * cov)), m = log(mean) - 0.5 * s * s;
    gp_law *l = gp_law_create(GP_LAW_LOGNORMAL, mean, cov, NULL);
    CHECK(l != NULL);
    double lf, ls;
    for (double z = -6; z <= 6; z += 0.25) {
        double a = exp(m + s * z);
        gp_law_log_cdf_sf(l, a, &lf, &ls);
        CHECK_REL(lf, log(0.5 * erfc(-z / sqrt(2.0))), 1e-11);
        CHECK_REL(ls, log(0.5 * erfc(z / sqrt(2.0))), 1e-11);
        CHECK_NEAR(exp(lf) + exp(ls), 1.0, 1e-14);
    }
    /* far tails, on both sides of the libm / GSL switch at |z| = 30 */
    const double zs[] = {29.5, 30.0, 30.5, 40.0, 100.0};
    for (size_t k = 0; k < sizeof zs / sizeof zs[0]; k++) {
        double z = zs[k];
        gp_law_log_cdf_sf(l, exp(m - s * z), &lf, &ls);
        CHECK_REL(lf, log_phi_asym(-z), 1e-9);
        CHECK(ls <= 0 && ls > -1e-15);
        gp_law_log_cdf_sf(l, exp(m + s * z), &lf, &ls);
        CHECK_REL(ls, log_phi_asym(-z), 1e-9);
        CHECK(lf <= 0 && lf > -1e-15);
    }
    gp_law_destroy(l);

    /* bounded laws: the working law stays finite everywhere, rises through the support and
     * equals F inside it to 1e-6 */
    const double sd[] = {0.5, 1, 2, 3, 4}, sp[] = {0, 10, 50, 90, 100};
    gp_law *b[2] = {gp_law_create(GP_LAW_UNIFORM, 2.0, 0.3, NULL), gp_law_create_sieve(sd, sp, 5, NULL)};
    for (int j = 0; j < 2; j++) {
        CHECK(b[j] != NULL);
        if (!b[j]) continue;
        double lo, hi, plf = -INFINITY, pls = INFINITY;
        gp_law_support(b[j], &lo, &hi);
        /* ln F_w rises (strictly below the top of the support, where it reaches 0 in double)
         * and ln(1 - F_w) falls (strictly above the bottom) */
        int finite = 1, rising = 1, falling = 1, near_f = 1;
        for (double a = 1e-300; a < 1e300; a *= a < lo * 1e-3 || a > hi * 1e3 ? 1e10 : 1.01) {
            gp_law_log_cdf_sf(b[j], a, &lf, &ls);
            /* (ln(1 - F_w) rounds to +6e-22 far below the support: logs to 1e-15) */
            finite &= isfinite(lf) && isfinite(ls) && lf <= 1e-15 && ls <= 1e-15;
            rising &= a < hi ? lf > plf : lf >= plf;
            falling &= a > lo ? ls < pls : ls <= pls;
            double f = gp_law_cdf(b[j], a);
            near_f &= fabs(exp(lf) - f) <= 2e-6 && fabs(-expm1(ls) - f) <= 2e-6;
            if (a > lo && a < hi && f > 1e-3 && f < 1 - 1e-3) CHECK_NEAR(exp(lf) + exp(ls), 1.0, 1e-12);
            plf = lf;
            pls = ls;
        }
        CHECK(finite);
        CHECK(rising);
        CHECK(falling);
        CHECK(near_f);
        gp_law_log_cdf_sf(b[j], 0.0, &lf, &ls);
        CHECK(isfinite(lf) && isfinite(ls));
        gp_law_destroy(b[j]);
    }
}

/* header: "both finite for finite a > 0" -- for every kind, down to tiny areas */
static void test_log_cdf_sf_finite(void)
{
    const double sd[] = {0.5, 1, 2, 3, 4}, sp[] = {0, 10, 50, 90, 100};
    gp_law *ls4[4] = {gp_law_create(GP_LAW_LOGNORMAL, 1.0, 0.3, NULL), gp_law_create(GP_LAW_NORMAL, 1.0, 0.3, NULL),
                      gp_law_create(GP_LAW_UNIFORM, 1.0, 0.3, NULL), gp_law_create_sieve(sd, sp, 5, NULL)};
    const double as[] = {1e-300, 1e-100, 1e-20, 1e-12, 1e-6, 1e6, 1e50, 1e100};
    for (int j = 0; j < 4; j++) {
        for (size_t k = 0; k < sizeof as / sizeof as[0]; k++) {
            double lf, ls;
            gp_law_log_cdf_sf(ls4[j], as[k], &lf, &ls);
            if (!(isfinite(lf) && isfinite(ls)))
                fprintf(stderr, "  %s at a = %g: ln F = %g, ln(1 - F) = %g\n",
                        gp_law_name((gp_law_kind)j), as[k], lf, ls);
            CHECK(isfinite(lf) && isfinite(ls));
        }
        gp_law_destroy(ls4[j]);
    }
}

/* the sieve's number law, by brute-force integration of its number density s_k / d^2 */
static const double SD[5] = {0.5, 1, 2, 3, 4}, SP[5] = {0, 10, 50, 90, 100};

static void sieve_truth(double cdf[5], double *mean, double *cov)
{
    double z = 0, e1 = 0, e2 = 0;
    cdf[0] = 0;
    for (int k = 0; k < 4; k++) {
        const int n = 20000;
        double a = SD[k], h = (SD[k + 1] - a) / n, s = (SP[k + 1] - SP[k]) / (SD[k + 1] - a);
        for (int i = 0; i <= n; i++) {
            double d = a + i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
            double nd = w * h / 3 * s / (d * d), area = M_PI / 4 * d * d;
            z += nd;
            e1 += nd * area;
            e2 += nd * area * area;
        }
        cdf[k + 1] = z;
    }
    for (int k = 0; k < 5; k++) cdf[k] /= z;
    *mean = e1 / z;
    *cov = sqrt(e2 / z - *mean * *mean) / *mean;
}

static void test_sieve(void)
{
    gp_error e;
    gp_law *l = gp_law_create_sieve(SD, SP, 5, &e);
    CHECK(l != NULL);
    if (!l) return;
    CHECK(gp_law_kind_of(l) == GP_LAW_SIEVE);
    double cdf[5], mean, cov, lo, hi;
    sieve_truth(cdf, &mean, &cov);
    for (int k = 0; k < 5; k++) CHECK_NEAR(gp_law_cdf(l, M_PI / 4 * SD[k] * SD[k]), cdf[k], 1e-12);
    CHECK_REL(gp_law_mean(l), mean, 1e-12);
    CHECK_REL(gp_law_cov(l), cov, 1e-11);
    gp_law_support(l, &lo, &hi);
    CHECK_REL(lo, M_PI / 4 * 0.25, 1e-15);
    CHECK_REL(hi, M_PI / 4 * 16, 1e-15);
    CHECK(gp_law_cdf(l, lo * 0.99) == 0.0 && gp_law_cdf(l, hi * 1.01) == 1.0);
    CHECK_REL(gp_law_quantile(l, 0), lo, 1e-15);
    CHECK_REL(gp_law_quantile(l, 1), hi, 1e-15);
    check_round_trip(l);
    for (int i = 1; i < 100; i++) { /* and the other way, through every bin */
        double a = lo + (hi - lo) * i / 100.0;
        CHECK_REL(gp_law_quantile(l, gp_law_cdf(l, a)), a, 1e-11);
    }
    const double *rd, *rp;
    CHECK(gp_law_sieve_rows(l, &rd, &rp) == 5 && rd[2] == 2 && rp[3] == 90);

    /* the physical check: a quantile sample passes the sieves by mass as the curve says */
    const int M = 200000;
    double tot = 0, pass[5] = {0};
    for (int i = 1; i <= M; i++) {
        double a = gp_law_quantile(l, (i - 0.5) / M);
        tot += a;
        for (int k = 0; k < 5; k++)
            if (a < M_PI / 4 * SD[k] * SD[k]) pass[k] += a;
    }
    for (int k = 0; k < 5; k++) CHECK_NEAR(100 * pass[k] / tot, SP[k], 0.1);
    CHECK_NEAR(100 * pass[2] / tot, SP[2], 0.01); /* in fact far closer */

    /* quantile moments agree as well */
    double qm, qc;
    quantile_moments(l, &qm, &qc); /* (Q has kinks at the sieves: Simpson to 1e-8 only) */
    CHECK_REL(qm, mean, 1e-7);
    CHECK_REL(qc, cov, 1e-7);
    gp_law_destroy(l);

    /* an empty middle bin: nothing between 2 and 3, the rest as before */
    const double p2[5] = {0, 10, 50, 50, 100};
    l = gp_law_create_sieve(SD, p2, 5, &e);
    CHECK(l != NULL);
    CHECK(gp_law_cdf(l, M_PI / 4 * 2 * 2) == gp_law_cdf(l, M_PI / 4 * 3 * 3));
    check_round_trip(l);
    gp_law_destroy(l);
}

/* the sieve on volumes: number density s_k / d^3, V = pi d^3 / 6, integrated by the test */
static double vol3(double d) { return M_PI / 6 * d * d * d; }

static void test_sieve3d(void)
{
    gp_error e;
    gp_law *l = gp_law_create_sieve3d(SD, SP, 5, &e);
    CHECK(l != NULL);
    if (!l) return;
    double z = 0, e1 = 0, e2 = 0, cdf[5] = {0};
    for (int k = 0; k < 4; k++) {
        const int n = 20000;
        double a = SD[k], h = (SD[k + 1] - a) / n, s = (SP[k + 1] - SP[k]) / (SD[k + 1] - a);
        for (int i = 0; i <= n; i++) {
            double d = a + i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2), nd = w * h / 3 * s / (d * d * d);
            z += nd;
            e1 += nd * vol3(d);
            e2 += nd * vol3(d) * vol3(d);
        }
        cdf[k + 1] = z;
    }
    double mean = e1 / z, cov = sqrt(e2 / z - mean * mean) / mean;
    for (int k = 0; k < 5; k++) CHECK_NEAR(gp_law_cdf(l, vol3(SD[k])), cdf[k] / z, 1e-11);
    CHECK_REL(gp_law_mean(l), mean, 1e-11);
    CHECK_REL(gp_law_cov(l), cov, 1e-10);
    double lo, hi;
    gp_law_support(l, &lo, &hi);
    CHECK_REL(lo, vol3(0.5), 1e-15);
    CHECK_REL(hi, vol3(4), 1e-15);
    check_round_trip(l);
    for (int i = 1; i < 100; i++) {
        double a = lo + (hi - lo) * i / 100.0;
        CHECK_REL(gp_law_quantile(l, gp_law_cdf(l, a)), a, 1e-11);
    }
    /* a quantile sample passes the sieves by mass (volume) as the curve says */
    const int M = 200000;
    double tot = 0, pass[5] = {0};
    for (int i = 1; i <= M; i++) {
        double a = gp_law_quantile(l, (i - 0.5) / M);
        tot += a;
        for (int k = 0; k < 5; k++)
            if (a < vol3(SD[k])) pass[k] += a;
    }
    for (int k = 0; k < 5; k++) CHECK_NEAR(100 * pass[k] / tot, SP[k], 0.1);
    printf("3D sieve: mean %.6g (test %.6g), COV %.6g (test %.6g), 50 %% passing %.4f %% by mass\n",
           gp_law_mean(l), mean, gp_law_cov(l), cov, 100 * pass[2] / tot);
    /* scaled, it keeps its kind and its rows */
    gp_law *sc = gp_law_scaled(l, 2.0, &e);
    CHECK(sc && fabs(gp_law_cdf(sc, 2 * vol3(2)) - cdf[2] / z) < 1e-11);
    gp_law_destroy(sc);
    gp_law_destroy(l);
}

static void test_scaled(void)
{
    const double f = 0.65;
    gp_law *base[4] = {gp_law_create(GP_LAW_LOGNORMAL, 2.0, 0.5, NULL), gp_law_create(GP_LAW_NORMAL, 2.0, 0.3, NULL),
                       gp_law_create(GP_LAW_UNIFORM, 2.0, 0.4, NULL), gp_law_create_sieve(SD, SP, 5, NULL)};
    for (int j = 0; j < 4; j++) {
        gp_error e;
        gp_law *s = gp_law_scaled(base[j], f, &e), *s2 = gp_law_scaled(s, 1 / f, &e);
        CHECK(s != NULL && s2 != NULL);
        if (!s || !s2) continue;
        CHECK(gp_law_kind_of(s) == gp_law_kind_of(base[j]));
        CHECK_REL(gp_law_mean(s), f * gp_law_mean(base[j]), 1e-14);
        CHECK_REL(gp_law_cov(s), gp_law_cov(base[j]), 1e-14);
        double lo0, hi0, lo1, hi1;
        gp_law_support(base[j], &lo0, &hi0);
        gp_law_support(s, &lo1, &hi1);
        CHECK_REL(lo1, f * lo0, 1e-14);
        CHECK(isinf(hi0) ? isinf(hi1) : fabs(hi1 - f * hi0) <= 1e-14 * hi1);
        for (size_t k = 0; k < NP; k++) {
            double p = P_GRID[k], x = gp_law_quantile(base[j], p);
            CHECK_NEAR(gp_law_quantile(s, p), f * x, 1e-13 * f * x + 1e-15 * gp_law_mean(s));
            CHECK_NEAR(gp_law_cdf(s, f * x), gp_law_cdf(base[j], x), 1e-13);
            CHECK_NEAR(gp_law_quantile(s2, p), x, 1e-13 * x + 1e-15 * gp_law_mean(s2));
            double lf0, ls0, lf1, ls1;
            gp_law_log_cdf_sf(base[j], x, &lf0, &ls0);
            gp_law_log_cdf_sf(s, f * x, &lf1, &ls1);
            CHECK_NEAR(lf1, lf0, 1e-9 * fabs(lf0) + 1e-13);
            CHECK_NEAR(ls1, ls0, 1e-9 * fabs(ls0) + 1e-13);
        }
        double qm, qc;
        quantile_moments(s, &qm, &qc);
        CHECK_REL(qm, gp_law_mean(s), j == 3 ? 1e-7 : 1e-9);
        CHECK_REL(qc, gp_law_cov(s), j == 3 ? 1e-7 : 1e-8);
        gp_law_destroy(s);
        gp_law_destroy(s2);
        gp_law_destroy(base[j]);
    }
    /* a scaled sieve keeps its rows as given (the scale is separate) */
    gp_law *b = gp_law_create_sieve(SD, SP, 5, NULL), *s = gp_law_scaled(b, f, NULL);
    const double *rd, *rp;
    CHECK(gp_law_sieve_rows(s, &rd, &rp) == 5 && rd[4] == 4 && rp[1] == 10);
    gp_law_destroy(b); /* the scaled law owns its own rows: still the same law without b */
    double cdf[5], mean, cov;
    sieve_truth(cdf, &mean, &cov);
    CHECK_NEAR(gp_law_cdf(s, f * M_PI / 4 * 2 * 2), cdf[2], 1e-12);
    CHECK_REL(gp_law_mean(s), f * mean, 1e-12);
    gp_law_destroy(s);
}

static int invalid(gp_law *l, gp_error *e)
{
    int ok = l == NULL && e->code == GP_ERR_INVALID && e->message[0] != '\0';
    gp_law_destroy(l);
    return ok;
}

static void test_invalid(void)
{
    gp_error e;
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_LOGNORMAL, 1.0, GP_LAW_COV_MIN * 0.9, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_LOGNORMAL, 1.0, 3.01, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_NORMAL, 1.0, 0.61, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_UNIFORM, 1.0, 0.578, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_UNIFORM, 0.0, 0.3, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_NORMAL, NAN, 0.3, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_NORMAL, 1.0, NAN, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create(GP_LAW_SIEVE, 1.0, 0.3, &e), &e));
    /* the limits themselves are accepted */
    gp_law *ok[3] = {gp_law_create(GP_LAW_NORMAL, 1.0, GP_LAW_NORMAL_COV_MAX, NULL),
                     gp_law_create(GP_LAW_UNIFORM, 1.0, GP_LAW_UNIFORM_COV_MAX, NULL),
                     gp_law_create(GP_LAW_LOGNORMAL, 1.0, GP_LAW_COV_MIN, NULL)};
    for (int j = 0; j < 3; j++) {
        CHECK(ok[j] != NULL);
        gp_law_destroy(ok[j]);
    }
    const double d_flat[5] = {0.5, 1, 1, 3, 4}, d_down[5] = {0.5, 2, 1, 3, 4}, d_neg[5] = {-0.5, 1, 2, 3, 4};
    const double p_99[5] = {0, 10, 50, 90, 99}, p_start[5] = {5, 10, 50, 90, 100}, p_down[5] = {0, 50, 40, 90, 100};
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create_sieve(d_flat, SP, 5, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create_sieve(d_down, SP, 5, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create_sieve(d_neg, SP, 5, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create_sieve(SD, p_99, 5, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create_sieve(SD, p_start, 5, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create_sieve(SD, p_down, 5, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_create_sieve(SD, SP, 1, &e), &e));
    gp_law *l = gp_law_create(GP_LAW_LOGNORMAL, 1.0, 0.3, NULL);
    gp_error_clear(&e);
    CHECK(invalid(gp_law_scaled(l, 0.0, &e), &e));
    gp_error_clear(&e);
    CHECK(invalid(gp_law_scaled(l, -2.0, &e), &e));
    CHECK(isnan(gp_law_quantile(l, 1.5)) && isnan(gp_law_quantile(l, -0.1)));
    CHECK(gp_law_sieve_rows(l, NULL, NULL) == 0);
    gp_law_destroy(l);
}

/* orientation: the CDF against Simpson's rule on the density over [mean - 90, theta) */
static double orient_truth(double mean, double a, double theta)
{
    double w = theta - (mean - 90);
    while (w < 0) w += 180;
    while (w >= 180) w -= 180;
    const int n = 2000;
    double tot = 0, part = 0;
    for (int i = 0; i <= n; i++) {
        double wt = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        double t1 = mean - 90 + 180.0 * i / n, t2 = mean - 90 + w * i / n;
        tot += wt * ((1 + a) / 2 + (1 - a) / 2 * cos(2 * (t1 - mean) * M_PI / 180)) * 180.0 / n;
        part += wt * ((1 + a) / 2 + (1 - a) / 2 * cos(2 * (t2 - mean) * M_PI / 180)) * w / n;
    }
    return part / tot;
}

static void test_orientation(void)
{
    const double means[] = {0, 30, -75, 170};
    for (size_t j = 0; j < sizeof means / sizeof means[0]; j++) {
        double mean = means[j];
        CHECK(gp_orient_cdf(mean, 0.4, mean - 90) == 0.0);
        CHECK(gp_orient_cdf(mean, 0.4, mean + 90) == 0.0); /* the window's end is its start */
        CHECK_NEAR(gp_orient_cdf(mean, 0.4, mean), 0.5, 1e-15);
        for (double th = -400; th <= 400; th += 7.3) {
            double wrapped = gp_orient_wrap(mean, th);
            CHECK(wrapped >= mean - 90 && wrapped < mean + 90);
            CHECK_NEAR(fmod(fabs(wrapped - th), 180.0) * (180.0 - fmod(fabs(wrapped - th), 180.0)), 0, 1e-8);
            CHECK_NEAR(gp_orient_cdf(mean, 1.0, th), (wrapped - (mean - 90)) / 180, 1e-14);
            const double as[] = {0.05, 0.3, 0.8};
            for (int k = 0; k < 3; k++) {
                double u = gp_orient_cdf(mean, as[k], th);
                CHECK_NEAR(u, orient_truth(mean, as[k], th), 1e-12);
                CHECK(u >= 0 && u < 1);
                CHECK_NEAR(gp_orient_cdf(mean, as[k], th + 540), u, 1e-12);
            }
        }
    }
    /* mean 30: the window is [-60, 120); 125 is out and wraps to -55, just past the start */
    CHECK_NEAR(gp_orient_wrap(30, 125), -55, 1e-12);
    CHECK_NEAR(gp_orient_cdf(30, 0.5, 125), gp_orient_cdf(30, 0.5, -55), 1e-15);
    CHECK(gp_orient_cdf(30, 0.5, 125) < 5.0 / 180); /* rare: less than uniform near the cut */
    CHECK_NEAR(gp_orient_wrap(30, 120), -60, 1e-12);
    CHECK(gp_orient_cdf(30, 0.5, nextafter(120.0, 0)) < 1.0);
}

/* gp_law_powered: the law of lam A^kappa. Checked against the base law itself: its quantile is
 * lam Q(p)^kappa (lam from the ratio at the median), its CDF at that point is p, its mean and
 * COV are the quantile's integrals (quantile_moments, Simpson, not the code's QAGS), a lognormal
 * stays a lognormal of ln-sd kappa s, a scaled powered law scales, and the rows of a powered
 * sieve are not offered (they are the base's). */
static void test_powered(void)
{
    gp_law *base[4] = {gp_law_create(GP_LAW_LOGNORMAL, 2.0, 0.5, NULL),
                       gp_law_create(GP_LAW_NORMAL, 2.0, 0.3, NULL),
                       gp_law_create(GP_LAW_UNIFORM, 2.0, 0.4, NULL),
                       gp_law_create_sieve(SD, SP, 5, NULL)};
    const double kappas[3] = {0.6, 0.85, 1.3};
    for (int j = 0; j < 4; j++) {
        for (int c = 0; c < 3; c++) {
            double kappa = kappas[c], mean = 3.0;
            gp_error e;
            gp_law *l = gp_law_powered(base[j], kappa, mean, &e);
            CHECK(l != NULL);
            if (!l) continue;
            CHECK(gp_law_kind_of(l) == gp_law_kind_of(base[j]));
            CHECK_REL(gp_law_mean(l), mean, 1e-12);
            double qm, qc;
            quantile_moments(l, &qm, &qc);
            CHECK_REL(qm, mean, j == 3 ? 1e-7 : 1e-8);
            CHECK_REL(qc, gp_law_cov(l), j == 3 ? 1e-6 : 1e-7);
            double lam = gp_law_quantile(l, 0.5) / pow(gp_law_quantile(base[j], 0.5), kappa);
            for (size_t k = 0; k < NP; k++) {
                double p = P_GRID[k], x = gp_law_quantile(base[j], p), y = lam * pow(x, kappa);
                if (x > 0 && isfinite(x)) {
                    CHECK_NEAR(gp_law_quantile(l, p), y, 1e-12 * y);
                    CHECK_NEAR(gp_law_cdf(l, y), gp_law_cdf(base[j], x), 1e-11);
                }
            }
            check_round_trip(l);
            if (j == 0) { /* ln-sd of the base: sqrt(ln(1 + 0.25)) */
                double s0 = sqrt(log1p(0.25));
                CHECK_REL(gp_law_cov(l), sqrt(expm1(kappa * kappa * s0 * s0)), 1e-12);
            }
            gp_law *t = gp_law_scaled(l, 0.5, &e);
            CHECK(t != NULL && fabs(gp_law_quantile(t, 0.3) - 0.5 * gp_law_quantile(l, 0.3)) <=
                  1e-14 * gp_law_quantile(l, 0.3));
            CHECK(t && gp_law_sieve_rows(t, NULL, NULL) == 0);
            gp_law_destroy(t);
            gp_law_destroy(l);
        }
        gp_error e;
        CHECK(invalid(gp_law_powered(base[j], 0.0, 1.0, &e), &e));
        CHECK(invalid(gp_law_powered(base[j], 0.8, -1.0, &e), &e));
        gp_law_destroy(base[j]);
    }
}

int main(void)
{
    test_parametric();
    test_log_cdf_sf();
    test_log_cdf_sf_finite();
    test_sieve();
    test_sieve3d();
    test_scaled();
    test_powered();
    test_invalid();
    test_orientation();
    return gp_test_summary();
}
