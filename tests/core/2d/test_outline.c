/* test_outline.c -- gp_outline against independent truth: spectra of circles, ellipses and a
 * triangle from their exact r(theta) summed directly here; invariance to translation, scale,
 * rotation, orientation and repeated points; the kernel against brute-force clipping and the
 * radii against gp_fourier_polygon_radii on random warped polygons; L, C, spiral and pentagram
 * outlines; a 1,000-grain round trip through gp_fourier with a lognormal spread of D_n; images
 * rendered here, traced by gp_trace and analysed; a 10,000-outline set. */
#include "gp_fourier.h"
#include "gp_outline.h"
#include "gp_rng.h"
#include "gp_test.h"
#include "gp_trace.h"

#include <gsl/gsl_randist.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PI 3.14159265358979323846
#define NP 128
#define NM 64

/* ------------------------------------------------------------------------------------------ */
/* helpers: the truth computed here, independently of the module                               */

/* D_n of radii r[0 .. N) at theta_i = 2 pi i / N by direct summation */
static double direct_D(const double *r, size_t N, size_t n)
{
    double re = 0, im = 0, m = 0;
    for (size_t i = 0; i < N; i++) {
        double th = 2 * PI * (double)n * (double)i / (double)N;
        re += r[i] * cos(th);
        im -= r[i] * sin(th);
        m += r[i];
    }
    m /= (double)N;
    return 2 * hypot(re, im) / ((double)N * m);
}

/* exact radius of the ellipse x^2/a^2 + y^2/b^2 = 1 about its centre */
static double ellipse_r(double th, double a, double b)
{
    return a * b / hypot(b * cos(th), a * sin(th));
}

static double rng_u01(void *s)
{
    return gp_rng_uniform(s);
}

static double max_abs_diff(const double *a, const double *b, size_t n)
{
    double m = 0;
    for (size_t i = 0; i < n; i++)
        m = fmax(m, fabs(a[i] - b[i]));
    return m;
}

static gp_outline *workspace(size_t np, size_t nmodes, int descriptors)
{
    gp_outline_params p;
    gp_outline_params_defaults(&p);
    p.np = np;
    p.nmodes = nmodes;
    p.descriptors = descriptors;
    return gp_outline_create(&p, NULL);
}

/* A grain of spectrum D (NM modes) with random phases from rng, NP points about c. Retries
 * the phases when the draw is not star-shaped; returns the number of tries. */
static int fourier_grain(gp_fourier *f, const double *D, gp_rng *rng, gp_vec2 c, double r0,
                         gp_vec2 *pts)
{
    for (int tries = 1;; tries++) {
        if (gp_fourier_contour_random(f, c, r0, D, NM, rng_u01, rng, NULL, pts, NULL, NULL) ==
            GP_OK)
            return tries;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* analytic shapes                                                                             */

static void test_circle(void)
{
    gp_outline *o = workspace(NP, NM, 1);
    double D[NM];
    gp_outline_info in;
    enum { N = 1024 };
    gp_vec2 p[N];
    /* vertices on the rays: every D_n (n >= 1) is rounding */
    for (size_t k = 0; k < N; k++)
        p[k] = (gp_vec2){3 + 2 * cos(2 * PI * k / N), -1 + 2 * sin(2 * PI * k / N)};
    CHECK(gp_outline_analyze(o, p, N, D, NULL, &in, NULL) == GP_OK);
    double mx = 0;
    for (size_t n = 1; n < NM; n++)
        mx = fmax(mx, D[n]);
    printf("circle, 1024 vertices: max D_n (n >= 1) = %.2e\n", mx);
    CHECK(mx < 1e-12);
    CHECK(D[0] == 1.0 && in.flags == 0);
    CHECK_NEAR(in.r0, 2.0, 1e-12);
    CHECK_NEAR(in.pole.x, 3, 1e-12);
    CHECK_NEAR(in.pole.y, -1, 1e-12);
    CHECK_NEAR(in.elongation, 1.0, 1e-3);
    CHECK_NEAR(in.circularity, 1.0, 1e-3);
    CHECK_NEAR(in.roundness, 1.0, 1e-3);
    CHECK(in.regularity == 5.0);
    /* 500 vertices at random angles: the chords' sag, < 1e-3 */
    gp_rng *rng = gp_rng_create(7, 0, NULL);
    double th[500];
    for (size_t k = 0; k < 500; k++)
        th[k] = 2 * PI * gp_rng_uniform(rng);
    for (size_t k = 1; k < 500; k++) /* insertion sort */
        for (size_t j = k; j > 0 && th[j - 1] > th[j]; j--) {
            double t = th[j];
            th[j] = th[j - 1];
            th[j - 1] = t;
        }
    for (size_t k = 0; k < 500; k++)
        p[k] = (gp_vec2){cos(th[k]), sin(th[k])};
    CHECK(gp_outline_analyze(o, p, 500, D, NULL, &in, NULL) == GP_OK);
    mx = 0;
    for (size_t n = 1; n < NM; n++)
        mx = fmax(mx, D[n]);
    printf("circle, 500 random vertices: max D_n (n >= 1) = %.2e\n", mx);
    CHECK(mx < 1e-3);
    gp_rng_destroy(rng);
    gp_outline_destroy(o);
}

/* An ellipse with its vertices on the analysis rays (1024 = 8 x 128 of them): D_n equal the
 * direct DFT of the exact r(theta) at the 128 rays. */
static void test_ellipse(void)
{
    gp_outline *o = workspace(NP, NM, 1);
    enum { N = 1024 };
    gp_vec2 p[N];
    const double as[3] = {1.2, 1.5, 3.0}, bs[3] = {0.9, 1.0, 1.0};
    for (int t = 0; t < 3; t++) {
        double a = as[t], b = bs[t];
        for (size_t k = 0; k < N; k++) {
            double th = 2 * PI * k / N, r = ellipse_r(th, a, b);
            p[k] = (gp_vec2){10 + r * cos(th), 20 + r * sin(th)};
        }
        double r[NP], D[NM], want[NM];
        for (size_t i = 0; i < NP; i++)
            r[i] = ellipse_r(2 * PI * i / NP, a, b);
        for (size_t n = 0; n < NM; n++)
            want[n] = n ? direct_D(r, NP, n) : 1.0;
        gp_outline_info in;
        CHECK(gp_outline_analyze(o, p, N, D, NULL, &in, NULL) == GP_OK);
        double err = max_abs_diff(D, want, NM);
        printf("ellipse %.1f x %.1f: D2 = %.6f (direct sum %.6f, first order (a-b)/(a+b) = "
               "%.6f), D4 = %.6f, max |D_n - direct| = %.1e, elongation %.4f (b/a %.4f)\n",
               a, b, D[2], want[2], (a - b) / (a + b), D[4], err, in.elongation, b / a);
        CHECK(err < 1e-12);
        CHECK(D[1] < 1e-12 && D[3] < 1e-12);
        CHECK_REL(D[2], (a - b) / (a + b), 0.1); /* first order only */
        CHECK_NEAR(in.elongation, b / a, 2e-3);
        CHECK(!(in.flags & GP_OUTLINE_POLE_MOVED));
    }
    /* np = 512 rays with 64 modes (less aliasing) agrees with np = 128 on a smooth outline */
    gp_outline *o4 = workspace(512, NM, 0);
    double D1[NM], D4[NM];
    gp_outline_info in;
    CHECK(gp_outline_analyze(o, p, N, D1, NULL, &in, NULL) == GP_OK);
    CHECK(gp_outline_analyze(o4, p, N, D4, NULL, &in, NULL) == GP_OK);
    CHECK(max_abs_diff(D1, D4, 20) < 1e-6);
    gp_outline_destroy(o4);
    gp_outline_destroy(o);
}

/* An equilateral triangle (3 points: star-shaped, so analysed) against its exact r(theta)
 * about the centroid, r = h / cos(theta - psi), psi the nearest edge normal. */
static void test_triangle(void)
{
    gp_outline *o = workspace(NP, NM, 1);
    const double R = 2.0, phi = 0.3, h = R / 2;
    gp_vec2 p[3];
    for (int k = 0; k < 3; k++)
        p[k] = (gp_vec2){-4 + R * cos(phi + 2 * PI * k / 3), 5 + R * sin(phi + 2 * PI * k / 3)};
    double r[NP], D[NM], want[NM];
    for (size_t i = 0; i < NP; i++) {
        double d = 2 * PI * i / NP - (phi + PI / 3);
        d = fmod(fmod(d + PI / 3, 2 * PI / 3) + 2 * PI / 3, 2 * PI / 3) - PI / 3;
        r[i] = h / cos(d);
    }
    for (size_t n = 0; n < NM; n++)
        want[n] = n ? direct_D(r, NP, n) : 1.0;
    gp_outline_info in;
    CHECK(gp_outline_analyze(o, p, 3, D, NULL, &in, NULL) == GP_OK);
    double err = max_abs_diff(D, want, NM);
    printf("triangle: D3 = %.6f (direct %.6f), D6 = %.6f, D2 = %.1e (mode 126 aliased: 128 rays "
           "are not 3-fold symmetric), max |D_n - direct| = %.1e\n", D[3], want[3], D[6], D[2],
           err);
    CHECK(err < 1e-12);
    CHECK(D[2] < 1e-3 && D[3] > 0.1);
    CHECK(in.nvertices == 3 && !(in.flags & GP_OUTLINE_REFUSED));
    gp_outline_destroy(o);
}

/* ------------------------------------------------------------------------------------------ */
/* invariance and cleaning                                                                     */

static void test_invariance(void)
{
    gp_fourier *f = gp_fourier_create(NP, NULL);
    gp_outline *o = workspace(NP, NM, 0);
    double Dm[NM];
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, NM, Dm, NULL);
    gp_rng *rng = gp_rng_create(42, 1, NULL);
    gp_vec2 p[NP], q[NP + 8];
    fourier_grain(f, Dm, rng, (gp_vec2){0.3, -0.2}, 1.0, p);
    double D[NM], Dq[NM];
    gp_outline_info in, iq;
    CHECK(gp_outline_analyze(o, p, NP, D, NULL, &in, NULL) == GP_OK);

    for (size_t i = 0; i < NP; i++)
        q[i] = (gp_vec2){p[i].x + 1e6, p[i].y - 1e6};
    CHECK(gp_outline_analyze(o, q, NP, Dq, NULL, &iq, NULL) == GP_OK);
    double dt = max_abs_diff(D, Dq, NM), d2t = fabs(D[2] - Dq[2]) / D[2];
    CHECK(dt <= 1e-9);
    CHECK(d2t <= 1e-8);
    CHECK_NEAR(iq.pole.x - 1e6, in.pole.x, 1e-9);
    for (size_t i = 0; i < NP; i++)
        q[i] = (gp_vec2){p[i].x * 1e-6, p[i].y * 1e-6};
    CHECK(gp_outline_analyze(o, q, NP, Dq, NULL, &iq, NULL) == GP_OK);
    double ds = max_abs_diff(D, Dq, NM);
    CHECK(ds <= 1e-12);
    CHECK_REL(iq.r0, in.r0 * 1e-6, 1e-12);
    /* a quarter turn maps rays onto rays (np divisible by 4) */
    for (size_t i = 0; i < NP; i++)
        q[i] = (gp_vec2){-p[i].y, p[i].x};
    CHECK(gp_outline_analyze(o, q, NP, Dq, NULL, &iq, NULL) == GP_OK);
    double dr = max_abs_diff(D, Dq, NM);
    CHECK(dr <= 1e-12);
    printf("invariance: translated by 1e6: max |dD_n| = %.1e (D2 relative %.1e); scaled by 1e-6: "
           "%.1e; quarter turn: %.1e\n", dt, d2t, ds, dr);

    /* clockwise: reversed, same spectrum */
    for (size_t i = 0; i < NP; i++)
        q[i] = p[NP - 1 - i];
    CHECK(gp_outline_analyze(o, q, NP, Dq, NULL, &iq, NULL) == GP_OK);
    CHECK(iq.flags == GP_OUTLINE_REVERSED);
    CHECK(max_abs_diff(D, Dq, NM) <= 1e-13);
    /* repeated points and the closing duplicate: dropped, same spectrum */
    size_t m = 0;
    for (size_t i = 0; i < NP; i++) {
        q[m++] = p[i];
        if (i % 40 == 0)
            q[m++] = p[i];
    }
    q[m++] = p[0];
    CHECK(gp_outline_analyze(o, q, m, Dq, NULL, &iq, NULL) == GP_OK);
    CHECK(iq.flags == GP_OUTLINE_DEDUPED && iq.ndropped == m - NP && iq.nvertices == NP);
    CHECK(max_abs_diff(D, Dq, NM) <= 1e-13);
    gp_rng_destroy(rng);
    gp_outline_destroy(o);
    gp_fourier_destroy(f);
}

static void test_refusals(void)
{
    gp_outline *o = workspace(NP, NM, 1);
    double D[NM];
    gp_outline_info in;
    gp_error e;
    const gp_vec2 two[4] = {{0, 0}, {1, 0}, {1, 0}, {0, 0}};
    CHECK(gp_outline_analyze(o, two, 4, D, NULL, &in, &e) == GP_ERR_INVALID);
    CHECK(in.flags & GP_OUTLINE_REFUSED);
    CHECK(in.error.code == GP_ERR_INVALID && strstr(in.error.message, "distinct") != NULL);
    const gp_vec2 line[4] = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
    CHECK(gp_outline_analyze(o, line, 4, D, NULL, &in, &e) == GP_ERR_DEGENERATE);
    CHECK(strstr(e.message, "no area") != NULL);
    const gp_vec2 nan[3] = {{0, 0}, {1, NAN}, {0, 1}};
    CHECK(gp_outline_analyze(o, nan, 3, D, NULL, &in, &e) == GP_ERR_INVALID);
    CHECK(gp_outline_analyze(o, NULL, 0, D, NULL, &in, &e) == GP_ERR_INVALID);
    CHECK(D[0] == 0.0);
    /* a C: the inner half-planes y <= 1 and y >= 2 of its slot's edges exclude each other */
    const gp_vec2 c[8] = {{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 2}, {3, 2}, {3, 3}, {0, 3}};
    CHECK(gp_outline_analyze(o, c, 8, D, NULL, &in, &e) == GP_ERR_NOT_STAR);
    CHECK(in.error.code == GP_ERR_NOT_STAR && strstr(e.message, "kernel is empty") != NULL);
    size_t nk = 99;
    gp_vec2 kern[12];
    CHECK(gp_outline_kernel(c, 8, kern, &nk, &e) == GP_OK && nk == 0);
    /* a square spiral */
    const gp_vec2 sp[12] = {{0, 0}, {6, 0}, {6, 6}, {1, 6}, {1, 2}, {4, 2},
                            {4, 3}, {2, 3}, {2, 5}, {5, 5}, {5, 1}, {0, 1}};
    CHECK(gp_outline_analyze(o, sp, 12, D, NULL, &in, &e) == GP_ERR_NOT_STAR);
    /* a pentagram {5/2}: every edge faces its centre, but it winds twice round it */
    gp_vec2 star[5];
    for (int k = 0; k < 5; k++)
        star[k] = (gp_vec2){cos(4 * PI * k / 5), sin(4 * PI * k / 5)};
    CHECK(gp_outline_analyze(o, star, 5, D, NULL, &in, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "winds 2 times") != NULL);
    gp_outline_destroy(o);
}

/* A thin L: its centroid (19/14, 19/14) is outside its kernel, the unit square at the corner;
 * the pole is the kernel's centroid (0.5, 0.5), flagged, and the radii are the exact ray
 * distances about it (gp_fourier_polygon_radii, an independent ray caster). */
static void test_L(void)
{
    gp_outline *o = workspace(NP, NM, 1);
    gp_fourier *f = gp_fourier_create(NP, NULL);
    const gp_vec2 L[6] = {{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 4}, {0, 4}};
    double D[NM], want[NM], r[NP], r0;
    gp_outline_info in;
    gp_error e;
    CHECK(gp_outline_analyze(o, L, 6, D, NULL, &in, &e) == GP_OK);
    CHECK(in.flags == GP_OUTLINE_POLE_MOVED);
    CHECK_NEAR(in.centroid.x, 19.0 / 14, 1e-12);
    CHECK_NEAR(in.pole.x, 0.5, 1e-12);
    CHECK_NEAR(in.pole.y, 0.5, 1e-12);
    CHECK_NEAR(in.kernel_fraction, 1.0 / 7, 1e-12);
    CHECK(gp_fourier_polygon_radii(L, 6, (gp_vec2){0.5, 0.5}, NP, r, NULL, NULL) == GP_OK);
    CHECK(gp_fourier_analyse(f, r, NM, &r0, want, NULL, NULL) == GP_OK);
    CHECK(max_abs_diff(D, want, NM) < 1e-12);
    CHECK_NEAR(in.r0, r0, 1e-12);
    printf("thin L: pole (%.3f, %.3f), centroid (%.3f, %.3f), pole offset %.3f r0, D1 = %.3f, "
           "D2 = %.3f, kernel %.3f of the area, elongation %.3f\n", in.pole.x, in.pole.y,
           in.centroid.x, in.centroid.y, in.pole_offset, D[1], D[2], in.kernel_fraction,
           in.elongation);
    CHECK(D[1] > 0.2); /* the pole is ~0.9 r0 from the centroid */
    size_t nk;
    gp_vec2 kern[10];
    CHECK(gp_outline_kernel(L, 6, kern, &nk, &e) == GP_OK);
    CHECK(nk >= 4 && fabs(gp_poly_signed_area(kern, nk) - 1.0) < 1e-12);
    /* a square with a needle 9 long and 0.02 wide at its base: one ray of 128 sees the needle,
     * and the 64-mode curve through that spike rings below zero between the rays (Gibbs), so
     * the grain keeps its spectrum but has no descriptors */
    const gp_vec2 needle[7] = {{-1, -1}, {1, -1}, {1, -0.01}, {10, 0}, {1, 0.01}, {1, 1}, {-1, 1}};
    CHECK(gp_outline_analyze(o, needle, 7, D, NULL, &in, &e) == GP_OK);
    CHECK(in.flags == GP_OUTLINE_NO_DESCRIPTORS);
    CHECK(in.error.code == GP_ERR_NOT_STAR && in.elongation == 0.0 && D[0] == 1.0);
    gp_fourier_destroy(f);
    gp_outline_destroy(o);
}

/* ------------------------------------------------------------------------------------------ */
/* random warped polygons: kernel vs brute force, radii vs gp_fourier_polygon_radii            */

/* Sutherland-Hodgman: clips the convex polygon k (nk points, capacity cap) by the left side
 * of a -> b. Returns the new count. */
static size_t clip(gp_vec2 *k, size_t nk, gp_vec2 a, gp_vec2 b, gp_vec2 *tmp)
{
    size_t m = 0;
    for (size_t i = 0; i < nk; i++) {
        gp_vec2 p = k[i], q = k[(i + 1) % nk];
        double sp = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
        double sq = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
        if (sp >= 0)
            tmp[m++] = p;
        if ((sp >= 0) != (sq >= 0)) {
            double t = sp / (sp - sq);
            tmp[m++] = (gp_vec2){p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
        }
    }
    memcpy(k, tmp, m * sizeof *k);
    return m;
}

static double brute_kernel_area(const gp_vec2 *p, size_t n)
{
    gp_vec2 *k = malloc((2 * n + 8) * sizeof *k), *tmp = malloc((2 * n + 8) * sizeof *k);
    k[0] = (gp_vec2){-100, -100};
    k[1] = (gp_vec2){100, -100};
    k[2] = (gp_vec2){100, 100};
    k[3] = (gp_vec2){-100, 100};
    size_t nk = 4;
    for (size_t i = 0; i < n && nk > 0; i++)
        nk = clip(k, nk, p[i], p[(i + 1) % n], tmp);
    double a = nk >= 3 ? gp_poly_area(k, nk) : 0.0;
    free(k);
    free(tmp);
    return a;
}

/* A polar polygon (star-shaped from the origin) pushed through the plane homeomorphism
 * (x, y) -> (x + c y^2, y + s x^2), which keeps it (nearly always) simple but not star. */
static size_t warped_polygon(gp_rng *rng, gp_vec2 *p)
{
    size_t n = 12 + gp_rng_uint(rng, 60);
    double c = gp_rng_range(rng, -0.8, 0.8), s = gp_rng_range(rng, -0.8, 0.8);
    double amp = gp_rng_range(rng, 0.0, 0.6);
    for (size_t k = 0; k < n; k++) {
        double th = 2 * PI * ((double)k + 0.8 * gp_rng_uniform(rng)) / (double)n;
        double r = 1 + amp * (gp_rng_uniform(rng) - 0.5);
        double x = r * cos(th), y = r * sin(th);
        p[k] = (gp_vec2){x + c * y * y, y + s * x * x};
    }
    return n;
}

static void test_random_kernels(void)
{
    gp_rng *rng = gp_rng_create(2024, 3, NULL);
    gp_outline *o = workspace(NP, NM, 0);
    gp_vec2 p[80], kern[90];
    double D[NM], r_ours[NP], r_ref[NP], worst_area = 0, worst_r = 0;
    size_t tried = 0, star_c = 0, moved = 0, empty = 0, agree = 0;
    for (int t = 0; t < 3000; t++) {
        size_t n = warped_polygon(rng, p);
        if (!gp_poly_is_simple(p, n) || gp_poly_signed_area(p, n) <= 0)
            continue;
        tried++;
        size_t nk;
        CHECK(gp_outline_kernel(p, n, kern, &nk, NULL) == GP_OK);
        double a = nk ? gp_poly_area(kern, nk) : 0.0, b = brute_kernel_area(p, n);
        worst_area = fmax(worst_area, fabs(a - b));
        agree += (nk > 0) == (b > 1e-9) || fabs(a - b) < 1e-9;
        gp_outline_info in;
        gp_status st = gp_outline_analyze(o, p, n, D, NULL, &in, NULL);
        if (st == GP_ERR_NOT_STAR) {
            empty++;
            CHECK(b < 1e-9);
            continue;
        }
        CHECK(st == GP_OK);
        if (st != GP_OK)
            continue;
        CHECK(b > 0);
        star_c += !(in.flags & GP_OUTLINE_POLE_MOVED);
        moved += !!(in.flags & GP_OUTLINE_POLE_MOVED);
        CHECK(gp_outline_star_radii(p, n, in.pole, NP, r_ours, NULL) == GP_OK);
        CHECK(gp_fourier_polygon_radii(p, n, in.pole, NP, r_ref, NULL, NULL) == GP_OK);
        for (size_t i = 0; i < NP; i++)
            worst_r = fmax(worst_r, fabs(r_ours[i] - r_ref[i]) / r_ref[i]);
    }
    printf("random warped polygons: %zu simple; star from the centroid %zu, pole moved %zu, "
           "refused (empty kernel) %zu; kernel area vs brute force max diff %.1e; radii vs "
           "gp_fourier_polygon_radii max rel diff %.1e\n", tried, star_c, moved, empty,
           worst_area, worst_r);
    CHECK(agree == tried);
    CHECK(worst_area < 1e-9);
    CHECK(worst_r < 1e-12);
    CHECK(star_c > 100 && moved > 100 && empty > 100); /* all three cases exercised */
    gp_outline_destroy(o);
    gp_rng_destroy(rng);
}

/* ------------------------------------------------------------------------------------------ */
/* sets                                                                                        */

/* n grains of the spectrum D2 = 0.1, D3 = 0.05, D8 = 0.02, alpha = beta = -2, each D_n (n >= 2)
 * multiplied by its own lognormal factor of mean 1 and cov 0.2; drawn[i * NM + n] keeps the
 * drawn spectra (may be NULL). */
static gp_vec2 *make_grains(size_t n, uint64_t seed, double *Dmean, double *drawn)
{
    gp_fourier *f = gp_fourier_create(NP, NULL);
    gp_rng *rng = gp_rng_create(seed, 0, NULL);
    gp_vec2 *pts = malloc(n * NP * sizeof *pts);
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, NM, Dmean, NULL);
    const double s2 = log(1 + 0.2 * 0.2), sigma = sqrt(s2), mu = -0.5 * s2;
    double D[NM];
    for (size_t i = 0; i < n; i++) {
        D[0] = 1;
        D[1] = 0;
        for (size_t k = 2; k < NM; k++)
            D[k] = Dmean[k] * gsl_ran_lognormal(gp_rng_gsl(rng), mu, sigma);
        if (drawn)
            memcpy(drawn + i * NM, D, sizeof D);
        gp_vec2 c = {gp_rng_range(rng, -50, 50), gp_rng_range(rng, -50, 50)};
        fourier_grain(f, D, rng, c, gp_rng_range(rng, 0.5, 2.0), pts + i * NP);
    }
    gp_rng_destroy(rng);
    gp_fourier_destroy(f);
    return pts;
}

static void test_round_trip(void)
{
    enum { N = 1000 };
    double Dm[NM], *drawn = malloc(N * NM * sizeof *drawn);
    gp_vec2 *pts = make_grains(N, 17, Dm, drawn);
    gp_outline_points *set = malloc(N * sizeof *set);
    for (size_t i = 0; i < N; i++)
        set[i] = (gp_outline_points){pts + i * NP, NP};
    gp_outline_set_result res;
    gp_error e;
    CHECK(gp_outline_set_analyze(set, N, NULL, NULL, &res, &e) == GP_OK);
    CHECK(res.n == N && res.nanalysed == N && res.nrefused == 0 && res.ndescribed == N);
    CHECK(res.nmodes == NM && res.mean[0] == 1.0 && res.cov[0] == 0.0);
    double worst = 0, dmean2 = 0, dd2[N];
    for (size_t i = 0; i < N; i++)
        dd2[i] = drawn[i * NM + 2];
    for (size_t i = 0; i < N; i++)
        dmean2 += dd2[i] / N;
    double dsd2 = 0;
    for (size_t i = 0; i < N; i++)
        dsd2 += (dd2[i] - dmean2) * (dd2[i] - dmean2) / (N - 1);
    printf("round trip, %d grains: n  mean D_n  (generating, error)  cov\n", N);
    for (size_t n = 2; n <= 8; n++) {
        double rel = res.mean[n] / Dm[n] - 1;
        worst = fmax(worst, fabs(rel));
        printf("  D%zu  %.5f  (%.5f, %+.2f %%)  %.3f\n", n, res.mean[n], Dm[n], 100 * rel,
               res.cov[n]);
        CHECK_REL(res.mean[n], Dm[n], 0.10);
    }
    printf("  worst mean error D2..D8 %.2f %%; cov D2 %.4f (drawn sample %.4f, target 0.2); "
           "mean D1 %.4f; D20 %.5f (gen %.5f); D40 %.6f (gen %.6f)\n", 100 * worst, res.cov[2],
           sqrt(dsd2) / dmean2, res.mean[1], res.mean[20], Dm[20], res.mean[40], Dm[40]);
    printf("  descriptors: elongation %.3f +- %.3f, roundness %.3f +- %.3f, circularity %.3f +- "
           "%.3f, regularity %.3f +- %.3f\n", res.elongation.mean, res.elongation.sd,
           res.roundness.mean, res.roundness.sd, res.circularity.mean, res.circularity.sd,
           res.regularity.mean, res.regularity.sd);
    CHECK_NEAR(res.cov[2], 0.2, 0.03);
    CHECK(res.mean[1] < 0.01); /* about the centroid D_1 is second order */
    CHECK(res.elongation.mean > 0.6 && res.elongation.mean < 0.95 && res.elongation.sd > 0);
    CHECK(res.circularity.mean > 0.6 && res.circularity.mean < 1);
    /* the result's rows are the single-outline analyses */
    gp_outline *o = workspace(NP, NM, 1);
    double D[NM];
    gp_outline_info in;
    CHECK(gp_outline_analyze(o, set[5].pts, NP, D, NULL, &in, NULL) == GP_OK);
    CHECK(memcmp(D, res.spectra + 5 * NM, sizeof D) == 0);
    CHECK(in.elongation == res.info[5].elongation);
    gp_outline_destroy(o);
    gp_outline_set_result_free(&res);
    CHECK(res.mean == NULL && res.n == 0);
    free(set);
    free(pts);
    free(drawn);
}

/* Refused outlines: reported by index with their reason; the set is analysed without them
 * while 10 remain, else GP_ERR_INFEASIBLE with the report. */
static void test_set_refusals(void)
{
    enum { N = 12 };
    double Dm[NM];
    gp_vec2 *pts = make_grains(N, 5, Dm, NULL);
    const gp_vec2 c[8] = {{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 2}, {3, 2}, {3, 3}, {0, 3}};
    const gp_vec2 seg[2] = {{0, 0}, {1, 1}};
    const gp_vec2 L[6] = {{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 4}, {0, 4}};
    gp_outline_points set[N];
    for (size_t i = 0; i < N; i++)
        set[i] = (gp_outline_points){pts + i * NP, NP};
    set[3] = (gp_outline_points){c, 8};
    set[7] = (gp_outline_points){seg, 2};
    set[9] = (gp_outline_points){L, 6};
    gp_outline_set_result res;
    gp_error e;
    CHECK(gp_outline_set_analyze(set, N, NULL, NULL, &res, &e) == GP_OK);
    CHECK(res.nanalysed == 10 && res.nrefused == 2 && res.npole_moved == 1);
    CHECK(res.refused[0] == 3 && res.refused[1] == 7);
    CHECK(res.info[3].error.code == GP_ERR_NOT_STAR && res.info[7].error.code == GP_ERR_INVALID);
    CHECK(res.info[9].flags & GP_OUTLINE_POLE_MOVED);
    double z = 0;
    for (size_t n = 0; n < NM; n++)
        z += res.spectra[3 * NM + n];
    CHECK(z == 0.0);
    gp_outline_set_result_free(&res);

    CHECK(gp_outline_set_analyze(set, N - 1, NULL, NULL, &res, &e) == GP_ERR_INFEASIBLE);
    printf("infeasible set: %s\n", e.message);
    CHECK(strstr(e.message, "3 (not_star), 7 (invalid)") != NULL);
    CHECK(res.nrefused == 2 && res.nanalysed == 9 && res.info != NULL && res.mean[2] == 0.0);
    gp_outline_set_result_free(&res);

    gp_outline_params p;
    gp_outline_params_defaults(&p);
    p.min_outlines = 9;
    p.descriptors = 0;
    CHECK(gp_outline_set_analyze(set, N - 1, &p, NULL, &res, &e) == GP_OK);
    CHECK(res.ndescribed == 0 && res.elongation.mean == 0.0 && res.mean[2] > 0.05);
    gp_outline_set_result_free(&res);

    volatile int cancel = 1;
    CHECK(gp_outline_set_analyze(set, N, NULL, &cancel, &res, &e) == GP_ERR_CANCELLED);
    CHECK(res.info == NULL);
    CHECK(gp_outline_set_analyze(set, 0, NULL, NULL, &res, &e) == GP_ERR_INVALID);
    p.nmodes = 65;
    CHECK(gp_outline_set_analyze(set, N, &p, NULL, &res, &e) == GP_ERR_INVALID);
    p.nmodes = 8;
    p.np = 8;
    CHECK(gp_outline_create(&p, &e) == NULL && e.code == GP_ERR_INVALID);
    free(pts);
}

static void test_ten_thousand(void)
{
    enum { N = 10000 };
    double Dm[NM];
    gp_vec2 *pts = make_grains(N, 99, Dm, NULL);
    gp_outline_points *set = malloc(N * sizeof *set);
    for (size_t i = 0; i < N; i++)
        set[i] = (gp_outline_points){pts + i * NP, NP};
    struct timespec t0, t1;
    gp_outline_set_result res;
    for (int desc = 0; desc <= 1; desc++) {
        gp_outline_params p;
        gp_outline_params_defaults(&p);
        p.descriptors = desc;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        CHECK(gp_outline_set_analyze(set, N, &p, NULL, &res, NULL) == GP_OK);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        CHECK(res.nanalysed == N);
        CHECK_REL(res.mean[2], Dm[2], 0.05);
        printf("10,000 outlines, descriptors %s: %.2f s, mean D2 %.4f, cov D2 %.3f\n",
               desc ? "on" : "off",
               (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec),
               res.mean[2], res.cov[2]);
        gp_outline_set_result_free(&res);
    }
    free(set);
    free(pts);
}

/* ------------------------------------------------------------------------------------------ */
/* images: render -> gp_trace -> gp_outline                                                    */

static void test_traced_grains(void)
{
    enum { W = 300, H = 300 };
    gp_fourier *f = gp_fourier_create(NP, NULL);
    gp_outline *o = workspace(NP, NM, 1);
    unsigned char *img = malloc(W * H);
    double Dm[NM], D[NM], Dp[NM];
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, NM, Dm, NULL);
    gp_rng *rng = gp_rng_create(11, 0, NULL);
    gp_vec2 p[NP];
    double worst2 = 0, worst3 = 0, worstp = 0;
    for (int g = 0; g < 8; g++) {
        fourier_grain(f, Dm, rng, (gp_vec2){150.2, 149.7}, 108.0, p);
        gp_vec2 lo, hi;
        gp_poly_bbox(p, NP, &lo, &hi, NULL);
        memset(img, 0, W * H);
        for (size_t r = 0; r < H; r++)
            for (size_t c = 0; c < W; c++)
                img[r * W + c] = (unsigned char)gp_poly_contains(
                    p, NP, (gp_vec2){(double)c + 0.5, (double)H - (double)r - 0.5});
        gp_trace_result tr;
        CHECK(gp_trace_image(img, W, H, NULL, &tr, NULL) == GP_OK);
        CHECK(tr.n == 1);
        if (tr.n != 1)
            continue;
        gp_outline_info in, ip;
        CHECK(gp_outline_analyze(o, tr.outlines[0].pts, tr.outlines[0].n, D, NULL, &in, NULL) ==
              GP_OK);
        CHECK(gp_outline_analyze(o, p, NP, Dp, NULL, &ip, NULL) == GP_OK);
        double e2 = D[2] / Dm[2] - 1, e3 = D[3] / Dm[3] - 1;
        worst2 = fmax(worst2, fabs(e2));
        worst3 = fmax(worst3, fabs(e3));
        for (size_t n = 2; n <= 8; n++)
            worstp = fmax(worstp, fabs(D[n] - Dp[n]));
        if (g == 0)
            printf("traced grain (%.0f x %.0f px, %zu vertices): D2 %.4f (%+.1f %%), D3 %.4f "
                   "(%+.1f %%); the polygon itself: D2 %.4f, D3 %.4f; elongation %.3f vs %.3f\n",
                   hi.x - lo.x, hi.y - lo.y, tr.outlines[0].n, D[2], 100 * e2, D[3], 100 * e3,
                   Dp[2], Dp[3], in.elongation, ip.elongation);
        CHECK_REL(D[2], Dm[2], 0.10);
        CHECK_REL(D[3], Dm[3], 0.10);
        gp_trace_result_free(&tr);
    }
    printf("traced grains, 8 at ~230 px: worst D2 error %.1f %%, D3 %.1f %%; max |D_n(traced) - "
           "D_n(polygon)|, n = 2..8: %.4f\n", 100 * worst2, 100 * worst3, worstp);
    CHECK(worstp < 0.005);
    gp_rng_destroy(rng);
    free(img);
    gp_outline_destroy(o);
    gp_fourier_destroy(f);
}

int main(void)
{
    test_circle();
    test_ellipse();
    test_triangle();
    test_invariance();
    test_refusals();
    test_L();
    test_random_kernels();
    test_round_trip();
    test_set_refusals();
    test_traced_grains();
    test_ten_thousand();
    return gp_test_summary();
}
