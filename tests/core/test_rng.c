/* test_rng.c -- gp_rng: the reference MT19937 vectors, agreement with GSL's mt19937,
 * reproducibility and independence of streams, simple statistics, Halton by hand. */
#include "gp_rng.h"
#include "gp_test.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include <gsl/gsl_rng.h>

/* an independent splitmix64, written from the published constants */
static uint64_t sm64(uint64_t x)
{
    uint64_t z = x + 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double corr(const double *x, const double *y, size_t n)
{
    double mx = 0, my = 0;
    for (size_t i = 0; i < n; i++) {
        mx += x[i];
        my += y[i];
    }
    mx /= (double)n;
    my /= (double)n;
    double sxy = 0, sxx = 0, syy = 0;
    for (size_t i = 0; i < n; i++) {
        sxy += (x[i] - mx) * (y[i] - my);
        sxx += (x[i] - mx) * (x[i] - mx);
        syy += (y[i] - my) * (y[i] - my);
    }
    return sxy / sqrt(sxx * syy);
}

static void test_reference(void)
{
    /* mt19937ar.c test vector: init_by_array({0x123, 0x234, 0x345, 0x456}) */
    const uint32_t key[4] = {0x123, 0x234, 0x345, 0x456};
    const uint32_t want[10] = {1067595299u, 955945823u,  477289528u,  4107218783u, 4228976476u,
                               3344332714u, 3355579695u, 227628506u,  810200273u,  2591290167u};
    gp_error e;
    gp_rng *r = gp_rng_create_from_key(key, 4, &e);
    CHECK(r != NULL);
    int bad = 0;
    for (int i = 0; i < 10; i++)
        if (gp_rng_u32(r) != want[i]) bad++;
    CHECK(bad == 0);
    gp_rng_destroy(r);
    CHECK(gp_rng_create_from_key(key, 0, &e) == NULL && e.code == GP_ERR_INVALID);

    /* with a 32-bit seed the GSL view is word for word gsl_rng_mt19937 */
    gsl_rng *ref = gsl_rng_alloc(gsl_rng_mt19937);
    r = gp_rng_create(1, 2, NULL);
    const unsigned long seeds[4] = {0, 1, 4357, 123456789};
    bad = 0;
    for (int s = 0; s < 4; s++) {
        gsl_rng_set(ref, seeds[s]);
        gsl_rng_set(gp_rng_gsl(r), seeds[s]);
        for (int i = 0; i < 2000; i++)
            if (gsl_rng_get(ref) != gsl_rng_get(gp_rng_gsl(r))) bad++;
    }
    CHECK(bad == 0);
    CHECK(gsl_rng_max(gp_rng_gsl(r)) == 0xffffffffUL && gsl_rng_min(gp_rng_gsl(r)) == 0);
    gsl_rng_free(ref);
    gp_rng_destroy(r);
    gp_rng_destroy(NULL);
}

static void test_streams(void)
{
    /* the documented key derivation */
    uint32_t k[4];
    gp_rng_derive_key(42, 7, k);
    uint64_t a = sm64(sm64(42)), b = sm64(sm64(a ^ sm64(7)));
    CHECK(k[0] == (uint32_t)a && k[1] == (uint32_t)(a >> 32));
    CHECK(k[2] == (uint32_t)b && k[3] == (uint32_t)(b >> 32));

    /* same (seed, stream) -> same sequence, whatever else was created in between */
    gp_rng *r1 = gp_rng_create(2024, 3, NULL);
    gp_rng *other = gp_rng_create(2024, 4, NULL);
    for (int i = 0; i < 1000; i++) gp_rng_uniform(other);
    gp_rng *r2 = gp_rng_create(2024, 3, NULL);
    int diff = 0;
    for (int i = 0; i < 5000; i++)
        if (gp_rng_uniform(r1) != gp_rng_uniform(r2)) diff++;
    CHECK(diff == 0);
    /* the GSL view draws from the same stream */
    gp_rng *r3 = gp_rng_create(2024, 3, NULL), *r4 = gp_rng_create(2024, 3, NULL);
    diff = 0;
    for (int i = 0; i < 100; i++)
        if (gsl_rng_uniform(gp_rng_gsl(r3)) != gp_rng_uniform(r4)) diff++;
    CHECK(diff == 0);
    gp_rng_destroy(r1);
    gp_rng_destroy(r2);
    gp_rng_destroy(r3);
    gp_rng_destroy(r4);
    gp_rng_destroy(other);

    /* different streams (and swapped seed/stream) differ and are decorrelated */
    const uint64_t pairs[6][4] = {{0, 0, 0, 1}, {0, 1, 0, 2}, {1, 0, 0, 1},
                                  {7, 0, 8, 0}, {0, 1000, 0, 1001}, {5, 5, 5, 6}};
    const size_t n = 100000;
    double *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y);
    double lag2 = 0;
    int nlag = 0;
    for (int p = 0; p < 6; p++) {
        gp_rng *ra = gp_rng_create(pairs[p][0], pairs[p][1], NULL);
        gp_rng *rb = gp_rng_create(pairs[p][2], pairs[p][3], NULL);
        int same = 0;
        for (size_t i = 0; i < n; i++) {
            x[i] = gp_rng_uniform(ra);
            y[i] = gp_rng_uniform(rb);
            same += x[i] == y[i];
        }
        CHECK(same < 3);
        CHECK(fabs(corr(x, y, n)) < 0.01); /* sd of the estimate: 1/sqrt(n) = 0.0032 */
        /* lagged cross-correlations: pooled below (one of them alone reaches 3 sd by chance
         * every few hundred) */
        for (size_t lag = 1; lag <= 3; lag++) {
            double c1 = corr(x, y + lag, n - lag), c2 = corr(x + lag, y, n - lag);
            lag2 += c1 * c1 + c2 * c2;
            nlag += 2;
        }
        gp_rng_destroy(ra);
        gp_rng_destroy(rb);
    }
    /* rms of 36 lagged correlations: 1/sqrt(n) for independent streams, with sd ~ 0.0004 */
    CHECK(sqrt(lag2 / nlag) < 2.0 / sqrt((double)n));
    free(x);
    free(y);
}

static void test_statistics(void)
{
    gp_rng *r = gp_rng_create(12345, 0, NULL);
    const int n = 100000;
    double s = 0, s2 = 0, lo = 1, hi = 0;
    for (int i = 0; i < n; i++) {
        double u = gp_rng_uniform(r);
        s += u;
        s2 += u * u;
        lo = fmin(lo, u);
        hi = fmax(hi, u);
    }
    double mean = s / n, var = s2 / n - mean * mean;
    CHECK_NEAR(mean, 0.5, 0.005);
    CHECK_NEAR(var, 1.0 / 12.0, 0.002);
    CHECK(lo >= 0.0 && hi < 1.0);

    double sigma = 2.5, g = 0, g2 = 0;
    for (int i = 0; i < n; i++) {
        double v = gp_rng_gaussian(r, sigma);
        g += v;
        g2 += v * v;
    }
    double gm = g / n, gs = sqrt(g2 / n - gm * gm);
    CHECK_NEAR(gm, 0.0, 0.02 * sigma);
    CHECK_REL(gs, sigma, 0.02);

    int bad = 0;
    for (int i = 0; i < n; i++) {
        double u = gp_rng_uniform_pos(r);
        if (!(u > 0.0 && u < 1.0)) bad++;
        double v = gp_rng_range(r, -3.0, 5.0);
        if (!(v >= -3.0 && v < 5.0)) bad++;
    }
    CHECK(bad == 0);
    CHECK(gp_rng_range(r, 2.0, 2.0) == 2.0);
    CHECK(gp_rng_range(r, 3.0, 2.0) == 3.0);
    /* a range too narrow to represent: stays in [a, b) */
    double a0 = 1.0, b0 = nextafter(1.0, 2.0);
    for (int i = 0; i < 100; i++) bad += gp_rng_range(r, a0, b0) != a0;
    CHECK(bad == 0);

    /* uint: range and a chi-square on 7 classes (df 6: 99.99 % quantile ~ 27.9) */
    long cnt[7] = {0};
    for (int i = 0; i < 70000; i++) {
        unsigned long k = gp_rng_uint(r, 7);
        if (k >= 7) bad++;
        else cnt[k]++;
    }
    CHECK(bad == 0);
    double chi = 0;
    for (int k = 0; k < 7; k++) chi += (cnt[k] - 10000.0) * (cnt[k] - 10000.0) / 10000.0;
    CHECK(chi < 27.9);
    CHECK(gp_rng_uint(r, 0) == 0 && gp_rng_uint(r, 1) == 0);
    unsigned long big = 3000000000UL * 4UL; /* > 2^32 */
    double bs = 0;
    for (int i = 0; i < 10000; i++) {
        unsigned long k = gp_rng_uint(r, big);
        if (k >= big) bad++;
        bs += (double)k;
    }
    CHECK(bad == 0);
    CHECK_REL(bs / 10000 / (double)big, 0.5, 0.03);
    unsigned long top = gp_rng_uint(r, 0xffffffffUL);
    CHECK(top < 0xffffffffUL);
    gp_rng_destroy(r);
}

/* Halton: radical inverse by hand, long double reference for big indices */
static long double halton_ref(uint64_t i, unsigned b)
{
    long double r = 0, f = 1.0L / b;
    while (i) {
        r += f * (long double)(i % b);
        i /= b;
        f /= b;
    }
    return r;
}

static void test_halton(void)
{
    const double b2[8] = {0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875};
    const double b3[9] = {0, 1 / 3.0, 2 / 3.0, 1 / 9.0, 4 / 9.0, 7 / 9.0, 2 / 9.0, 5 / 9.0, 8 / 9.0};
    for (int i = 0; i < 8; i++) CHECK(gp_halton((uint64_t)i, 2) == b2[i]);
    for (int i = 0; i < 9; i++) CHECK_NEAR(gp_halton((uint64_t)i, 3), b3[i], 1e-16);
    CHECK_NEAR(gp_halton(10, 3), 1 / 3.0 + 1 / 27.0, 1e-16); /* 10 = 101_3 -> 0.101_3 */
    CHECK(gp_halton(1, 5) == 0.2);
    CHECK(isnan(gp_halton(3, 1)) && isnan(gp_halton(3, 0)));
    double x, y;
    gp_halton2(5, &x, &y);
    CHECK(x == 0.625);
    CHECK_NEAR(y, 7 / 9.0, 1e-16);
    /* big indices: 2^63 in base 2 is 2^-64; all of them within [0, 1) and ~1 ulp of truth */
    CHECK(gp_halton(1ull << 63, 2) == 0x1p-64);
    CHECK(gp_halton(UINT64_MAX, 2) < 1.0);
    int bad = 0;
    uint64_t s = 0x0123456789abcdefull;
    for (int k = 0; k < 2000; k++) {
        s = sm64(s);
        unsigned base = 2 + (unsigned)(s % 29);
        uint64_t idx = sm64(s + 1) >> (s % 64);
        double h = gp_halton(idx, base);
        long double ref = halton_ref(idx, base);
        if (!(h >= 0.0 && h < 1.0) || fabsl((long double)h - ref) > 4e-16L * (ref + 1e-300L))
            bad++;
    }
    CHECK(bad == 0);
    /* stratification: any 36 consecutive indices put exactly one point in each cell of the
     * 4 x 9 grid (x's first 2 binary digits follow i mod 4, y's first 2 ternary ones i mod 9) */
    int cell[36] = {0};
    for (uint64_t i = 1; i <= 36 * 50; i++) {
        gp_halton2(i, &x, &y);
        cell[(int)(x * 4) * 9 + (int)(y * 9)]++;
    }
    for (int c = 0; c < 36; c++)
        if (cell[c] != 50) bad++;
    CHECK(bad == 0);
}

int main(void)
{
    test_reference();
    test_streams();
    test_statistics();
    test_halton();
    return gp_test_summary();
}
