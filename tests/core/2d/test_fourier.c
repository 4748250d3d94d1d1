/* test_fourier.c -- gp_fourier: spectrum by hand, synthesis against a direct cosine sum,
 * synthesis/analysis round trip, determinism, star checks against brute force, ray casting. */
#include "gp_fourier.h"
#include "gp_test.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* test-local uniform generator (splitmix64) */
static double u01(void *state)
{
    uint64_t *s = state;
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static double bad_u01(void *state)
{
    (void)state;
    return NAN;
}

/* r(theta) by the direct cosine sum -- the independent truth for the FFT synthesis */
static double direct_r(double th, double r0, const double *D, const double *delta, size_t nm)
{
    double s = 1.0;
    for (size_t n = 1; n < nm; n++)
        s += D[n] * cos((double)n * th - delta[n]);
    return r0 * s;
}

static double wrap_angle(double a)
{
    while (a > PI)
        a -= 2 * PI;
    while (a <= -PI)
        a += 2 * PI;
    return a;
}

/* brute-force minimum caliper: scan directions, width = extent across the direction */
static void brute_caliper(const gp_vec2 *p, size_t n, double *S, double *L)
{
    double best = INFINITY, best_phi = 0;
    int steps = 20000;
    for (int k = 0; k < steps; k++) {
        double phi = PI * k / steps;
        double c = cos(phi), s = sin(phi), lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < n; i++) {
            double t = p[i].x * c + p[i].y * s;
            lo = t < lo ? t : lo;
            hi = t > hi ? t : hi;
        }
        if (hi - lo < best) {
            best = hi - lo;
            best_phi = phi;
        }
    }
    double c = cos(best_phi + PI / 2), s = sin(best_phi + PI / 2), lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        double t = p[i].x * c + p[i].y * s;
        lo = t < lo ? t : lo;
        hi = t > hi ? t : hi;
    }
    *S = best;
    *L = hi - lo;
}

static void test_spectrum(void)
{
    double D[64];
    gp_error e;
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 64, D, &e) == GP_OK);
    CHECK(D[0] == 1.0 && D[1] == 0.0);
    CHECK_NEAR(D[2], 0.1, 0);
    CHECK_NEAR(D[3], 0.05, 0);
    CHECK_NEAR(D[4], 0.028125, 1e-15);          /* 0.05 * (4/3)^-2 = 0.05 * 9/16 (NOTES.md) */
    CHECK_NEAR(D[5], 0.018, 1e-15);             /* 0.05 * 9/25 */
    CHECK_NEAR(D[7], 0.05 * 9.0 / 49.0, 1e-15);
    CHECK_NEAR(D[8], 0.02, 0);
    CHECK_NEAR(D[9], 0.02 * 64.0 / 81.0, 1e-15);
    CHECK_NEAR(D[16], 0.005, 1e-15);            /* 0.02 * (16/8)^-2 */
    CHECK_NEAR(D[63], 0.02 * 64.0 / 3969.0, 1e-15);
    CHECK_NEAR(D[6], 0.0125, 1e-15);            /* 0.05 * 2^-2 */
    /* Eqs. 10-11 as printed (2^(alpha log2(n/3) + log2 D3)) agree for other slopes */
    double D2[16];
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -1.5, -3, 16, D2, NULL) == GP_OK);
    CHECK_NEAR(D2[6], pow(2.0, -1.5 * log2(6.0 / 3.0) + log2(0.05)), 1e-15);
    CHECK_NEAR(D2[12], pow(2.0, -3 * log2(12.0 / 8.0) + log2(0.02)), 1e-15);
    /* short spectra */
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 1, D, NULL) == GP_OK && D[0] == 1.0);
    /* bad input */
    CHECK(gp_fourier_spectrum(NAN, 0.05, 0.02, -2, -2, 64, D, &e) == GP_ERR_INVALID);
    CHECK(e.code == GP_ERR_INVALID && strlen(e.message) > 0);
    CHECK(gp_fourier_spectrum(0.1, -0.05, 0.02, -2, -2, 64, D, NULL) == GP_ERR_INVALID);
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, INFINITY, -2, 64, D, NULL) == GP_ERR_INVALID);
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, 2000, 64, D, NULL) == GP_ERR_INVALID);
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 0, D, NULL) == GP_ERR_INVALID);
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 4, NULL, NULL) == GP_ERR_INVALID);
    /* user spectra */
    double u[5] = {1, 0, 0.1, 0.05, 0.01};
    CHECK(gp_fourier_spectrum_check(u, 5, NULL) == GP_OK);
    u[3] = -0.01;
    CHECK(gp_fourier_spectrum_check(u, 5, &e) == GP_ERR_INVALID);
    u[3] = NAN;
    CHECK(gp_fourier_spectrum_check(u, 5, NULL) == GP_ERR_INVALID);
    u[3] = 0.05;
    u[0] = 2;
    CHECK(gp_fourier_spectrum_check(u, 5, NULL) == GP_ERR_INVALID);
    CHECK(gp_fourier_spectrum_check(u, 0, NULL) == GP_ERR_INVALID);
}

/* synthesis vs direct sum, then analysis recovers amplitudes and phases, for several Np */
static void test_round_trip(size_t np)
{
    gp_error e;
    gp_fourier *f = gp_fourier_create(np, &e);
    CHECK(f != NULL);
    if (!f)
        return;
    CHECK(gp_fourier_np(f) == np);
    size_t nm = gp_fourier_max_modes(np);
    double *D = malloc(nm * sizeof *D), *dl = malloc(nm * sizeof *dl);
    double *D2 = malloc(nm * sizeof *D2), *dl2 = malloc(nm * sizeof *dl2);
    double *r = malloc(np * sizeof *r);
    gp_vec2 *pts = malloc(np * sizeof *pts);
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, nm, D, NULL) == GP_OK);
    D[1] = 0.03; /* a shift term too, so that every mode has a phase to recover */
    uint64_t seed = 12345 + np;
    gp_vec2 c = {0.3, -1.7};
    double r0 = 2.5;
    CHECK(gp_fourier_contour_random(f, c, r0, D, nm, u01, &seed, dl, pts, r, &e) == GP_OK);
    double maxdev = 0;
    for (size_t i = 0; i < np; i++) {
        double th = 2 * PI * (double)i / (double)np;
        double rd = direct_r(th, r0, D, dl, nm);
        maxdev = fmax(maxdev, fabs(r[i] - rd));
        maxdev = fmax(maxdev, fabs(pts[i].x - (c.x + rd * cos(th))));
        maxdev = fmax(maxdev, fabs(pts[i].y - (c.y + rd * sin(th))));
    }
    CHECK_NEAR(maxdev, 0, 1e-13);
    /* phases are in [-pi, pi] */
    int inrange = 1;
    for (size_t n = 1; n < nm; n++)
        inrange &= dl[n] >= -PI && dl[n] <= PI;
    CHECK(inrange);

    double r0b;
    CHECK(gp_fourier_analyse(f, r, nm, &r0b, D2, dl2, &e) == GP_OK);
    CHECK_NEAR(r0b, r0, 1e-12);
    double dD = 0, dP = 0;
    for (size_t n = 1; n < nm; n++) {
        dD = fmax(dD, fabs(D2[n] - D[n]));
        dP = fmax(dP, fabs(wrap_angle(dl2[n] - dl[n])));
    }
    CHECK_NEAR(dD, 0, 1e-12);
    CHECK_NEAR(dP, 0, 1e-9); /* phase error ~ eps / D_n; the smallest D_n here is 3.2e-4 */
    CHECK(D2[0] == 1.0 && dl2[0] == 0.0);

    /* ray casting the generated polygon about its centre hits the vertices: same radii */
    double *rr = malloc(np * sizeof *rr);
    int star = -1;
    CHECK(gp_fourier_polygon_radii(pts, np, c, np, rr, &star, &e) == GP_OK);
    CHECK(star == 1);
    double rd = 0;
    for (size_t i = 0; i < np; i++)
        rd = fmax(rd, fabs(rr[i] - r[i]));
    CHECK_NEAR(rd, 0, 1e-12 * r0);
    double r0c;
    CHECK(gp_fourier_analyse_polygon(f, pts, np, c, nm, &r0c, D2, NULL, NULL, &e) == GP_OK);
    CHECK_NEAR(r0c, r0, 1e-12);
    CHECK_NEAR(D2[2], D[2], 1e-11);

    free(rr);
    free(D);
    free(dl);
    free(D2);
    free(dl2);
    free(r);
    free(pts);
    gp_fourier_destroy(f);
}

static void test_determinism(void)
{
    size_t np = 128, nm = 64;
    gp_fourier *f1 = gp_fourier_create(np, NULL), *f2 = gp_fourier_create(np, NULL);
    CHECK(f1 && f2);
    if (!f1 || !f2)
        return;
    double D[64], d1[64], d2[64];
    gp_fourier_spectrum(0.15, 0.05, 0.02, -2, -2, nm, D, NULL);
    uint64_t s1 = 99, s2 = 99;
    gp_vec2 a[128], b[128], c0 = {0, 0};
    CHECK(gp_fourier_contour_random(f1, c0, 1.0, D, nm, u01, &s1, d1, a, NULL, NULL) == GP_OK);
    CHECK(gp_fourier_random_phases(nm, u01, &s2, d2, NULL) == GP_OK);
    CHECK(memcmp(d1, d2, sizeof d1) == 0);
    /* other object, and the same object after other work in between */
    CHECK(gp_fourier_contour(f2, c0, 1.0, D, d2, nm, b, NULL, NULL) == GP_OK);
    CHECK(memcmp(a, b, sizeof a) == 0);
    gp_vec2 tmp[128];
    double d3[64];
    gp_fourier_random_phases(nm, u01, &s2, d3, NULL);
    CHECK(gp_fourier_contour(f1, c0, 1.0, D, d3, nm, tmp, NULL, NULL) == GP_OK);
    CHECK(memcmp(tmp, a, sizeof a) != 0);
    CHECK(gp_fourier_contour(f1, c0, 1.0, D, d1, nm, tmp, NULL, NULL) == GP_OK);
    CHECK(memcmp(tmp, a, sizeof a) == 0);
    /* NULL delta_out uses the object's scratch and gives the same contour for the same seed */
    uint64_t s3 = 99;
    CHECK(gp_fourier_contour_random(f2, c0, 1.0, D, nm, u01, &s3, NULL, tmp, NULL, NULL) == GP_OK);
    CHECK(memcmp(tmp, a, sizeof a) == 0);
    gp_fourier_destroy(f1);
    gp_fourier_destroy(f2);
}

/* r0 (1 + D2 cos 2 theta): elongation S/L against (1 - D2)/(1 + D2), with a brute-force
 * caliper (independent of gp_geom) */
static void test_elongation(void)
{
    gp_fourier *f = gp_fourier_create(128, NULL);
    double D2s[] = {0.05, 0.1, 0.15, 0.2};
    for (int k = 0; k < 4; k++) {
        double D[3] = {1, 0, D2s[k]}, dl[3] = {0, 0, 0};
        gp_vec2 p[128];
        CHECK(gp_fourier_contour(f, (gp_vec2){0, 0}, 1.0, D, dl, 3, p, NULL, NULL) == GP_OK);
        double S, L;
        brute_caliper(p, 128, &S, &L);
        double want = (1 - D2s[k]) / (1 + D2s[k]);
        CHECK_REL(S / L, want, 0.02);
        CHECK_NEAR(L, 2 * (1 + D2s[k]), 1e-3); /* scan step pi/20000 */
    }
    gp_fourier_destroy(f);
}

static void test_errors(void)
{
    gp_error e;
    CHECK(gp_fourier_create(15, &e) == NULL && e.code == GP_ERR_INVALID);
    CHECK(gp_fourier_create(0, NULL) == NULL);
    gp_fourier *f = gp_fourier_create(64, NULL);
    double D[33] = {1, 0, 0.1, 0.05}, dl[33] = {0};
    gp_vec2 p[64];
    double r[64];
    gp_vec2 c0 = {0, 0};
    CHECK(gp_fourier_contour(f, c0, 1.0, D, dl, 4, p, r, &e) == GP_OK);
    D[2] = NAN;
    CHECK(gp_fourier_contour(f, c0, 1.0, D, dl, 4, p, r, &e) == GP_ERR_INVALID);
    D[2] = -0.1;
    CHECK(gp_fourier_contour(f, c0, 1.0, D, dl, 4, p, r, &e) == GP_ERR_INVALID);
    D[2] = 0.1;
    CHECK(gp_fourier_contour(f, c0, 0.0, D, dl, 4, p, r, &e) == GP_ERR_INVALID);
    CHECK(gp_fourier_contour(f, c0, NAN, D, dl, 4, p, r, &e) == GP_ERR_INVALID);
    dl[2] = INFINITY;
    CHECK(gp_fourier_contour(f, c0, 1.0, D, dl, 4, p, r, &e) == GP_ERR_INVALID);
    dl[2] = 0;
    CHECK(gp_fourier_contour(f, c0, 1.0, D, dl, 33, p, r, &e) == GP_ERR_INVALID); /* > Np/2 */
    CHECK(gp_fourier_contour(NULL, c0, 1.0, D, dl, 4, p, r, &e) == GP_ERR_INVALID);
    uint64_t s = 1;
    CHECK(gp_fourier_contour_random(f, c0, 1.0, D, 4, bad_u01, &s, NULL, p, r, &e) ==
          GP_ERR_INVALID);

    /* D2 = 0.7, D3 = 0.5 with phases that put both troughs at theta = pi/2: r = -0.2 r0 */
    double Dn[4] = {1, 0, 0.7, 0.5}, dn[4] = {0, 0, 0, PI / 2};
    CHECK_NEAR(direct_r(PI / 2, 1, Dn, dn, 4), -0.2, 1e-12);
    for (int i = 0; i < 64; i++)
        p[i] = (gp_vec2){12345, 12345};
    CHECK(gp_fourier_contour(f, c0, 1.0, Dn, dn, 4, p, r, &e) == GP_ERR_NOT_STAR);
    CHECK(e.code == GP_ERR_NOT_STAR && strstr(e.message, "star") != NULL);
    CHECK(p[5].x == 12345); /* nothing written */

    /* a dip between samples: D31 = 1.0006 on 64 points with delta = pi/64 (half a step): every
     * sample has r >= 6e-4 r0, the curve goes to 1 - 1.0006 < 0 between them */
    double Dh[32] = {1}, dh[32] = {0};
    Dh[31] = 1.0006;
    dh[31] = PI / 64;
    double smin = INFINITY;
    for (int i = 0; i < 64; i++)
        smin = fmin(smin, direct_r(2 * PI * i / 64, 1, Dh, dh, 32));
    CHECK(smin > 5e-4);
    CHECK(gp_fourier_radii(f, 1.0, Dh, dh, 32, r, &e) == GP_ERR_NOT_STAR);
    gp_fourier_destroy(f);

    /* random phases for a spectrum with sum D_n > 1: the verdict agrees with a dense brute
     * force (20k points) whenever the brute-force minimum is clearly away from zero */
    f = gp_fourier_create(128, NULL);
    double Db[64], db[64], rb[128];
    gp_fourier_spectrum(0.7, 0.35, 0.0, -4, -2, 64, Db, NULL);
    uint64_t seed = 7;
    int agree = 1, nstar = 0, nnot = 0;
    for (int t = 0; t < 100; t++) {
        gp_fourier_random_phases(64, u01, &seed, db, NULL);
        double bmin = INFINITY; /* D_n = 0 for n >= 8 (D8 = 0) */
        for (int i = 0; i < 20000; i++)
            bmin = fmin(bmin, direct_r(2 * PI * i / 20000, 1, Db, db, 8));
        gp_status st = gp_fourier_radii(f, 1.0, Db, db, 64, rb, NULL);
        if ((bmin > 0.01 && st != GP_OK) || (bmin < 0 && st != GP_ERR_NOT_STAR))
            printf("bmin %g st %d\n", bmin, st);
        if (bmin > 0.01) {
            agree &= st == GP_OK;
            nstar++;
        } else if (bmin < 0) {
            agree &= st == GP_ERR_NOT_STAR;
            nnot++;
        }
    }
    CHECK(agree);
    CHECK(nstar > 10 && nnot > 10); /* both cases exercised */
    gp_fourier_destroy(f);
}

static void test_polygon_radii(void)
{
    gp_error e;
    /* square [-1, 1]^2 from its centre: r = 1 / max(|cos|, |sin|) */
    gp_vec2 sq[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    double r[64];
    int star = -1;
    CHECK(gp_fourier_polygon_radii(sq, 4, (gp_vec2){0, 0}, 64, r, &star, &e) == GP_OK);
    CHECK(star == 1);
    double dev = 0;
    for (int i = 0; i < 64; i++) {
        double th = 2 * PI * i / 64;
        dev = fmax(dev, fabs(r[i] - 1 / fmax(fabs(cos(th)), fabs(sin(th)))));
    }
    CHECK_NEAR(dev, 0, 1e-12);
    /* clockwise orientation and an off-centre point: r along +x from (0.5, 0) is 0.5 */
    gp_vec2 sqcw[4] = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
    CHECK(gp_fourier_polygon_radii(sqcw, 4, (gp_vec2){0.5, 0}, 16, r, NULL, &e) == GP_OK);
    CHECK_NEAR(r[0], 0.5, 1e-15);
    CHECK_NEAR(r[8], 1.5, 1e-15);
    CHECK_NEAR(r[4], 1.0, 1e-15);
    /* a U shape: from a point in the left arm, the ray along +x leaves and re-enters */
    gp_vec2 U[8] = {{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
    CHECK(gp_fourier_polygon_radii(U, 8, (gp_vec2){0.5, 2}, 16, r, &star, &e) == GP_OK);
    CHECK(star == 0);
    CHECK_NEAR(r[0], 0.5, 1e-15); /* first exit */
    CHECK(gp_fourier_polygon_radii(U, 8, (gp_vec2){0.5, 2}, 16, r, NULL, &e) == GP_ERR_NOT_STAR);
    /* from the bottom bar's centre (1.5, 0.5) the U is not star either (the arms hide) */
    CHECK(gp_fourier_polygon_radii(U, 8, (gp_vec2){1.5, 0.5}, 64, r, &star, &e) == GP_OK);
    CHECK(star == 0);
    /* centre outside, or on the boundary */
    CHECK(gp_fourier_polygon_radii(U, 8, (gp_vec2){1.5, 2}, 16, r, &star, &e) == GP_ERR_INVALID);
    CHECK(gp_fourier_polygon_radii(sq, 4, (gp_vec2){5, 0}, 16, r, &star, &e) == GP_ERR_INVALID);
    CHECK(gp_fourier_polygon_radii(sq, 4, (gp_vec2){1, 0}, 16, r, &star, &e) == GP_ERR_INVALID);
    CHECK(gp_fourier_polygon_radii(sq, 2, (gp_vec2){0, 0}, 16, r, &star, &e) == GP_ERR_INVALID);
    /* a ray through a vertex (diamond from its centre at theta = 0) counts one crossing */
    gp_vec2 dm[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    CHECK(gp_fourier_polygon_radii(dm, 4, (gp_vec2){0, 0}, 8, r, &star, &e) == GP_OK);
    CHECK(star == 1);
    CHECK_NEAR(r[0], 1, 1e-15);
    CHECK_NEAR(r[1], sqrt(0.5), 1e-15);
}

/* plans created, used and destroyed on several threads at once give the reference bytes */
typedef struct {
    const double *D, *dl;
    gp_vec2 out[200];
    int ok;
} thread_job;

static void *thread_main(void *arg)
{
    thread_job *j = arg;
    j->ok = 1;
    for (int rep = 0; rep < 50; rep++) {
        gp_fourier *f = gp_fourier_create(200, NULL);
        if (!f || gp_fourier_contour(f, (gp_vec2){1, 2}, 0.5, j->D, j->dl, 100, j->out, NULL,
                                     NULL) != GP_OK)
            j->ok = 0;
        gp_fourier_destroy(f);
    }
    return NULL;
}

static void test_threads(void)
{
    double D[100], dl[100];
    uint64_t s = 4242;
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 100, D, NULL);
    gp_fourier_random_phases(100, u01, &s, dl, NULL);
    gp_vec2 ref[200];
    gp_fourier *f = gp_fourier_create(200, NULL);
    CHECK(gp_fourier_contour(f, (gp_vec2){1, 2}, 0.5, D, dl, 100, ref, NULL, NULL) == GP_OK);
    gp_fourier_destroy(f);
    enum { NT = 4 };
    static thread_job jobs[NT];
    pthread_t th[NT];
    for (int k = 0; k < NT; k++) {
        jobs[k].D = D;
        jobs[k].dl = dl;
        CHECK(pthread_create(&th[k], NULL, thread_main, &jobs[k]) == 0);
    }
    for (int k = 0; k < NT; k++) {
        pthread_join(th[k], NULL);
        CHECK(jobs[k].ok);
        CHECK(memcmp(jobs[k].out, ref, sizeof ref) == 0);
    }
}

int main(void)
{
    test_spectrum();
    test_round_trip(128);
    test_round_trip(100);
    test_round_trip(97);
    test_round_trip(16);
    test_determinism();
    test_elongation();
    test_errors();
    test_polygon_radii();
    test_threads();
    return gp_test_summary();
}
