/* test_grainshape.c -- each grain's own spectrum (gp_grainshape, issue #17 spread): the law
 * (lognormal per mode with the asked mean and coefficient of variation, modes independent),
 * its streams (the same grain gives the same bits, grains differ, the stream is 2^62 + g),
 * the star-shape redraws and the clipping, and the arguments. */
#include "gp_grainshape.h"
#include "gp_rng.h"
#include "gp_test.h"

#include <stdlib.h>
#include <string.h>

#define NP 128
#define NM (NP / 2)
#define NDRAW 4000

static double u01(void *state) { return gp_rng_uniform(state); }

/* phases of grain g, from a stream of its own (as the specimen's cells have) */
static void phases(size_t g, double *delta)
{
    gp_rng *r = gp_rng_create(5, 1 + g, NULL);
    gp_fourier_random_phases(NM, u01, r, delta, NULL);
    gp_rng_destroy(r);
}

/* NDRAW grains of the default spectrum with cov 0.2 on every mode (0.5 on mode 2): the sample
 * mean and cov of each mode are the asked ones within their standard errors (x 4) */
static void test_law(void)
{
    double mean[NM], cov[NM], D[NM], delta[NM], scratch[NP + NM];
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, NM, mean, NULL);
    for (size_t n = 0; n < NM; n++)
        cov[n] = n == 2 ? 0.5 : 0.2;
    gp_grainshape gs = {NM, mean, cov, 42};
    CHECK(gp_grainshape_varies(&gs));
    gp_fourier *f = gp_fourier_create(NP, NULL);
    static double s1[NM], s2[NM], cross;
    size_t redrawn = 0;
    for (size_t g = 0; g < NDRAW; g++) {
        gp_grainshape_outcome oc;
        phases(g, delta);
        CHECK(gp_grainshape_draw(&gs, g, delta, f, scratch, D, &oc, NULL) == GP_OK);
        redrawn += oc != GP_GRAINSHAPE_DRAWN;
        CHECK(D[0] == 1.0 && D[1] == 0.0);
        for (size_t n = 2; n < NM; n++) {
            s1[n] += D[n] / mean[n];
            s2[n] += (D[n] / mean[n]) * (D[n] / mean[n]);
        }
        cross += (D[2] / mean[2] - 1) * (D[3] / mean[3] - 1);
    }
    CHECK(redrawn == 0);
    for (size_t n = 2; n < NM; n += n < 10 ? 1 : 13) {
        double m = s1[n] / NDRAW, c = sqrt(s2[n] / NDRAW - m * m) / m;
        double se_m = cov[n] / sqrt(NDRAW), se_c = cov[n] * sqrt((1 + 2 * cov[n] * cov[n]) /
                                                                  (2.0 * NDRAW));
        printf("mode %2zu: mean / asked %.4f, cov %.4f (asked %.1f)\n", n, m, c, cov[n]);
        CHECK_NEAR(m, 1.0, 4 * se_m);
        CHECK_NEAR(c, cov[n], 4 * se_c + 0.01 * cov[n]);
    }
    /* independent modes: the correlation of modes 2 and 3 is 0 within its standard error */
    double rho = cross / NDRAW / (0.5 * 0.2);
    printf("corr(D2, D3) %.4f\n", rho);
    CHECK(fabs(rho) < 4 / sqrt((double)NDRAW));
    gp_fourier_destroy(f);
}

/* the same grain the same bits; another grain, another spectrum; the stream is 2^62 + g */
static void test_streams(void)
{
    double mean[NM], cov[NM], a[NM], b[NM], c[NM], delta[NM], scratch[NP + NM];
    gp_fourier_spectrum(0.2, 0.05, 0.02, -2, -2, NM, mean, NULL);
    for (size_t n = 0; n < NM; n++) cov[n] = 0.3;
    gp_grainshape gs = {NM, mean, cov, 7};
    gp_fourier *f = gp_fourier_create(NP, NULL);
    phases(3, delta);
    CHECK(gp_grainshape_draw(&gs, 3, delta, f, scratch, a, NULL, NULL) == GP_OK);
    CHECK(gp_grainshape_draw(&gs, 3, delta, f, scratch, b, NULL, NULL) == GP_OK);
    CHECK(gp_grainshape_draw(&gs, 4, delta, f, scratch, c, NULL, NULL) == GP_OK);
    CHECK(memcmp(a, b, sizeof a) == 0 && memcmp(a, c, sizeof a) != 0);
    CHECK(a[1] == 0.0); /* mode 1 has mean 0 and stays 0 */
    /* ... but its z is drawn (the layout of a try does not depend on the means): mode 2 takes
     * the second normal draw of stream 2^62 + 3 */
    gp_rng *r = gp_rng_create(7, GP_GRAINSHAPE_STREAM + 3, NULL);
    gp_rng_gaussian(r, 1.0);
    double z2 = gp_rng_gaussian(r, 1.0), s2 = log(1 + 0.09);
    gp_rng_destroy(r);
    CHECK_NEAR(a[2], mean[2] * exp(sqrt(s2) * z2 - 0.5 * s2), 1e-15);
    /* no spread: the mean, whatever the grain */
    gp_grainshape none = {NM, mean, NULL, 7};
    CHECK(!gp_grainshape_varies(&none));
    CHECK(gp_grainshape_draw(&none, 3, delta, f, scratch, a, NULL, NULL) == GP_OK);
    CHECK(memcmp(a, mean, sizeof a) == 0);
    gp_fourier_destroy(f);
}

/* a spectrum at the edge of star shape (D2 0.95): draws are refused and redrawn, and a spread
 * that no draw survives is clipped toward the mean; every result is star-shaped */
static void test_star(void)
{
    double mean[NM], cov[NM], D[NM], delta[NM], scratch[NP + NM], r[NP];
    gp_fourier_spectrum(0.9, 0.04, 0.01, -2, -2, NM, mean, NULL);
    gp_fourier *f = gp_fourier_create(NP, NULL);
    size_t count[3] = {0, 0, 0}, nstar_mean = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t n = 0; n < NM; n++) cov[n] = pass == 0 ? 0.3 : 1.0;
        gp_grainshape gs = {NM, mean, cov, 3};
        for (size_t g = 0; g < 300; g++) {
            gp_grainshape_outcome oc;
            phases(g, delta);
            nstar_mean += pass == 0 && gp_fourier_radii(f, 1, mean, delta, NM, r, NULL) == GP_OK;
            CHECK(gp_grainshape_draw(&gs, g, delta, f, scratch, D, &oc, NULL) == GP_OK);
            count[oc]++;
            /* a clipped grain may be the mean, which need not be star-shaped itself */
            if (oc != GP_GRAINSHAPE_CLIPPED || memcmp(D, mean, sizeof D) != 0)
                CHECK(gp_fourier_radii(f, 1, D, delta, NM, r, NULL) == GP_OK);
        }
    }
    printf("D2 0.9, 300 grains at cov 0.3 and at 1: drawn %zu, redrawn %zu, clipped %zu (mean "
           "star-shaped for %zu of 300 phase sets)\n", count[0], count[1], count[2], nstar_mean);
    CHECK(count[1] > 0 && count[2] > 0);
    gp_fourier_destroy(f);
}

static void test_arguments(void)
{
    double mean[NM], cov[NM], D[NM], delta[NM], scratch[NP + NM];
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, NM, mean, NULL);
    for (size_t n = 0; n < NM; n++) cov[n] = 0.2;
    memset(delta, 0, sizeof delta);
    gp_fourier *f = gp_fourier_create(NP, NULL), *small = gp_fourier_create(32, NULL);
    gp_grainshape gs = {NM, mean, cov, 1};
    gp_error e;
    CHECK(gp_grainshape_draw(NULL, 0, delta, f, scratch, D, NULL, &e) == GP_ERR_INVALID);
    CHECK(gp_grainshape_draw(&gs, 0, delta, small, scratch, D, NULL, &e) == GP_ERR_INVALID);
    cov[5] = NAN;
    CHECK(gp_grainshape_draw(&gs, 0, delta, f, scratch, D, NULL, &e) == GP_ERR_INVALID);
    cov[5] = -0.1;
    CHECK(gp_grainshape_draw(&gs, 0, delta, f, scratch, D, NULL, &e) == GP_ERR_INVALID);
    gp_fourier_destroy(f);
    gp_fourier_destroy(small);
}

int main(void)
{
    test_law();
    test_streams();
    test_star();
    test_arguments();
    return gp_test_summary();
}
