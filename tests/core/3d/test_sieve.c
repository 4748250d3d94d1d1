/* test_sieve.c -- sieve curve -> diameters (Dang & Meguid 2010, Table 2 and Eq. 9; NOTES.md). */
#include "gp_sieve.h"
#include "gp_test.h"

#include <stdlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Table 2, diameters in m */
static const double T2_D[5] = {0.010, 0.020, 0.050, 0.080, 0.100};
static const double T2_W[5] = {0, 2, 50, 95, 100};

static void test_table2_conversion(void)
{
    double pn[5];
    gp_error e;
    /* the printed "% passing (number)" column: the mid-bin cube rule, within 0.5 pp */
    CHECK(gp_sieve_weight_to_number(T2_D, T2_W, 5, GP_SIEVE_MIDBIN, pn, &e) == GP_OK);
    const double printed[5] = {0, 31.47, 90.93, 99.64, 100};
    for (int k = 0; k < 5; k++)
        CHECK_NEAR(pn[k], printed[k], 0.5);
    /* and in fact to the printed rounding */
    for (int k = 0; k < 5; k++)
        CHECK_NEAR(pn[k], printed[k], 0.006);
    /* the exact conversion for uniform-in-bin draws (NOTES.md: 32.49, 90.11, 99.59) */
    CHECK(gp_sieve_weight_to_number(T2_D, T2_W, 5, GP_SIEVE_UNIFORM, pn, &e) == GP_OK);
    const double exact[5] = {0, 32.49, 90.11, 99.59, 100};
    for (int k = 0; k < 5; k++)
        CHECK_NEAR(pn[k], exact[k], 0.006);
    /* by hand, one bin [1, 3] split in two equal weights at 2: mid-bin cubes 1.5^3 and 2.5^3 */
    const double d3[3] = {1, 2, 3}, w3[3] = {0, 50, 100};
    CHECK(gp_sieve_weight_to_number(d3, w3, 3, GP_SIEVE_MIDBIN, pn, &e) == GP_OK);
    CHECK_NEAR(pn[1], 100.0 * (1 / 3.375) / (1 / 3.375 + 1 / 15.625), 1e-12);
    /* uniform: E[d^3] on [1,2] = (16-1)/4 = 3.75, on [2,3] = (81-16)/4 = 16.25 */
    CHECK(gp_sieve_weight_to_number(d3, w3, 3, GP_SIEVE_UNIFORM, pn, &e) == GP_OK);
    CHECK_NEAR(pn[1], 100.0 * (1 / 3.75) / (1 / 3.75 + 1 / 16.25), 1e-12);
}

static void test_validation(void)
{
    double pn[5];
    gp_error e;
    const double w_bad0[5] = {5, 20, 50, 95, 100};
    CHECK(gp_sieve_weight_to_number(T2_D, w_bad0, 5, GP_SIEVE_MIDBIN, pn, &e) == GP_ERR_INVALID);
    const double w_bad1[5] = {0, 20, 10, 95, 100};
    CHECK(gp_sieve_validate(T2_D, w_bad1, 5, &e) == GP_ERR_INVALID);
    const double w_bad2[5] = {0, 20, 50, 95, 99};
    CHECK(gp_sieve_validate(T2_D, w_bad2, 5, &e) == GP_ERR_INVALID);
    const double d_bad[5] = {0.010, 0.020, 0.020, 0.080, 0.100};
    CHECK(gp_sieve_validate(d_bad, T2_W, 5, &e) == GP_ERR_INVALID);
    CHECK(gp_sieve_validate(T2_D, T2_W, 1, &e) == GP_ERR_INVALID);
    CHECK(gp_sieve_validate(T2_D, T2_W, 5, &e) == GP_OK);
}

static double cube_sum(const double *x, size_t n)
{
    double s = 0;
    for (size_t i = 0; i < n; i++)
        s += x[i] * x[i] * x[i];
    return s;
}

static void test_draw_table2(void)
{
    gp_error e;
    gp_rng *rng = gp_rng_create(7, 0, &e);
    CHECK(rng != NULL);
    if (!rng)
        return;
    double vs = (1 - 0.38) * 0.5 * 0.5 * 0.5; /* Eq. 8 corrected: V_s = (1 - p) V */
    double *dm = NULL;
    size_t n = 0;
    CHECK(gp_sieve_draw(T2_D, T2_W, 5, vs, 1000000, rng, &dm, &n, &e) == GP_OK);
    /* the count follows from V_s and mean grain volume of uniform draws: by hand
     * 0.0775 * (0.02/1.9635e-6 + 0.48/2.6573e-5 + 0.45/1.5145e-4 + 0.05/3.8642e-4)
     * = 789.4 + 1399.9 + 230.3 + 10.0 = 2429.6 */
    CHECK_NEAR((double)n, gp_sieve_expected_count(T2_D, T2_W, 5, vs), 0.51);
    CHECK_NEAR((double)n, 2429.6, 0.6);
    /* total solid volume is exact */
    CHECK_REL(M_PI / 6 * cube_sum(dm, n), vs, 1e-9);
    double pw[5], pn[5], pnx[5];
    gp_sieve_passing(dm, n, T2_D, 5, pw, pn);
    for (int k = 0; k < 5; k++)
        CHECK_NEAR(pw[k], T2_W[k], 3.0);   /* the bound */
    for (int k = 0; k < 5; k++)
        CHECK_NEAR(pw[k], T2_W[k], 1e-6);  /* what the quota + warp actually gives */
    /* by number it follows the exact conversion, up to rounding one grain per bin */
    gp_sieve_weight_to_number(T2_D, T2_W, 5, GP_SIEVE_UNIFORM, pnx, &e);
    for (int k = 0; k < 5; k++)
        CHECK_NEAR(pn[k], pnx[k], 100.0 * 2 / n);
    /* the largest bin: 0.05 V_s / (pi/6 E[d^3]) = 10.03 grains -> 10, all in [80, 100) mm */
    size_t big = 0;
    for (size_t i = 0; i < n; i++) {
        CHECK(dm[i] >= 0.010 && dm[i] < 0.100);
        big += dm[i] >= 0.080;
    }
    CHECK(big == 10);
    /* deterministic for a seed */
    gp_rng *r2 = gp_rng_create(7, 0, &e);
    double *dm2 = NULL;
    size_t n2 = 0;
    CHECK(gp_sieve_draw(T2_D, T2_W, 5, vs, 1000000, r2, &dm2, &n2, &e) == GP_OK);
    int same = n2 == n;
    for (size_t i = 0; same && i < n; i++)
        same = dm[i] == dm2[i];
    CHECK(same);
    /* too many grains for the limit */
    double *dm3 = NULL;
    size_t n3 = 0;
    CHECK(gp_sieve_draw(T2_D, T2_W, 5, vs, 1000, rng, &dm3, &n3, &e) == GP_ERR_INVALID);
    CHECK(dm3 == NULL && n3 == 0);
    free(dm);
    free(dm2);
    gp_rng_destroy(rng);
    gp_rng_destroy(r2);
}

static void test_draw_wide_and_single(void)
{
    gp_error e;
    gp_rng *rng = gp_rng_create(3, 1, &e);
    if (!rng) {
        CHECK(0);
        return;
    }
    /* size ratio 20, straight line by weight */
    const double d[3] = {0.005, 0.030, 0.100}, w[3] = {0, 40, 100};
    double *dm;
    size_t n;
    CHECK(gp_sieve_draw(d, w, 3, 0.05, 1000000, rng, &dm, &n, &e) == GP_OK);
    double pw[3];
    gp_sieve_passing(dm, n, d, 3, pw, NULL);
    CHECK_NEAR(pw[1], 40, 1e-6);
    CHECK_REL(M_PI / 6 * cube_sum(dm, n), 0.05, 1e-9);
    free(dm);
    /* near one-size: a narrow bin, count = V / v exactly when the volume is a whole number */
    const double d1[2] = {0.0199999, 0.0200001}, w1[2] = {0, 100};
    double v1 = M_PI / 6 * 0.02 * 0.02 * 0.02;
    CHECK(gp_sieve_draw(d1, w1, 2, 500 * v1, 1000000, rng, &dm, &n, &e) == GP_OK);
    CHECK(n == 500);
    for (size_t i = 0; i < n; i++)
        CHECK_NEAR(dm[i], 0.02, 1.1e-7);
    free(dm);
    gp_rng_destroy(rng);
}

int main(void)
{
    test_table2_conversion();
    test_validation();
    test_draw_table2();
    test_draw_wide_and_single();
    return gp_test_summary();
}
