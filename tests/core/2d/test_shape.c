/* test_shape.c -- gp_shape: the four descriptors against analytic and hand-computed values. */
#include "gp_shape.h"
#include "gp_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

static void ellipse(gp_vec2 *p, size_t n, double a, double b, double phi, gp_vec2 c)
{
    for (size_t i = 0; i < n; i++) {
        double t = 2 * PI * (double)i / (double)n;
        double x = a * cos(t), y = b * sin(t);
        p[i].x = c.x + x * cos(phi) - y * sin(phi);
        p[i].y = c.y + x * sin(phi) + y * cos(phi);
    }
}

static double angle_gap_deg(double a, double b)
{
    double d = fmod(fabs(a - b), 180.0);
    return d > 90 ? 180 - d : d;
}

static void test_circle(void)
{
    enum { N = 1024 };
    gp_vec2 *p = malloc(N * sizeof *p);
    ellipse(p, N, 3.0, 3.0, 0, (gp_vec2){-1, 2});
    gp_shape_result s;
    gp_error e;
    CHECK(gp_shape_describe(p, N, NULL, &s, &e) == GP_OK);
    CHECK_NEAR(s.elongation, 1.0, 1e-3);
    CHECK_NEAR(s.circularity, 1.0, 1e-3);
    CHECK_NEAR(s.roundness, 1.0, 1e-3);
    CHECK(s.regularity == GP_SHAPE_REGULARITY_CAP && s.regularity_capped == 1);
    CHECK_NEAR(s.r_insc, 3.0 * cos(PI / N), 1e-5);
    CHECK_NEAR(s.r_circ, 3.0, 1e-12);
    CHECK_NEAR(s.perimeter, 2 * N * 3.0 * sin(PI / N), 1e-9);
    CHECK_NEAR(s.perimeter_convex, s.perimeter, 1e-9);
    CHECK(s.ndiscs == 1);
    CHECK(s.perimeter_points == N);
    free(p);
}

static void test_ellipse(void)
{
    enum { N = 1024 };
    gp_vec2 *p = malloc(N * sizeof *p);
    double as[] = {2.0, 3.0, 1.25}, bs[] = {1.0, 1.0, 1.0};
    double phis[] = {30.0, -60.0, 89.0};
    for (int k = 0; k < 3; k++) {
        double a = as[k], b = bs[k], phi = phis[k];
        ellipse(p, N, a, b, phi * PI / 180, (gp_vec2){5, -3});
        gp_shape_result s;
        CHECK(gp_shape_describe(p, N, NULL, &s, NULL) == GP_OK);
        CHECK_NEAR(s.elongation, b / a, 1e-4);
        /* the polygon's minimum width has an edge flush with the caliper: the edges at the
         * minor-axis vertex turn by (b/a) 2 pi / N, so theta is within half of that */
        CHECK_NEAR(angle_gap_deg(s.orientation_deg, phi), 0, (b / a) * 180.0 / N + 1e-6);
        CHECK(s.orientation_deg > -90 && s.orientation_deg <= 90);
        CHECK_NEAR(s.width, 2 * b, 1e-4);
        CHECK_NEAR(s.length, 2 * a, 1e-4);
        /* largest inscribed circle of an ellipse: radius b; smallest enclosing: a */
        CHECK_NEAR(s.r_insc, b, 1e-4);
        CHECK_NEAR(s.r_circ, a, 1e-9);
        CHECK_NEAR(s.circularity, sqrt(b / a), 1e-4);
        CHECK(s.regularity == GP_SHAPE_REGULARITY_CAP);
        /* roundness: the ODEC of an ellipse has discs between the tip radius of curvature
         * b^2/a and b, so the mean lies strictly inside */
        CHECK(s.roundness > (b * b / a) / b && s.roundness <= 1.0 + 1e-9);
    }
    free(p);
}

static void test_square(void)
{
    gp_vec2 sq[4] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
    gp_shape_result s;
    CHECK(gp_shape_describe(sq, 4, NULL, &s, NULL) == GP_OK);
    CHECK_NEAR(s.r_insc, 1.0, 1e-6);
    CHECK_NEAR(s.r_circ, sqrt(2.0), 1e-12);
    CHECK_NEAR(s.circularity, pow(1 / sqrt(2.0), 0.5), 1e-6);
    CHECK_NEAR(s.elongation, 1.0, 1e-12);
    CHECK(s.regularity == GP_SHAPE_REGULARITY_CAP);
    CHECK_NEAR(s.perimeter, 8.0, 1e-12);
    /* a square's ODEC: the inscribed disc and ever smaller corner discs -> roundness < 1 */
    CHECK(s.roundness < 1.0 && s.roundness > 0.05);
    /* rotated square (30 deg): same descriptors, orientation 30 or -60 */
    gp_vec2 rs[4];
    double c = cos(PI / 6), sn = sin(PI / 6);
    for (int i = 0; i < 4; i++)
        rs[i] = (gp_vec2){sq[i].x * c - sq[i].y * sn, sq[i].x * sn + sq[i].y * c};
    gp_shape_result t;
    CHECK(gp_shape_describe(rs, 4, NULL, &t, NULL) == GP_OK);
    CHECK_NEAR(t.circularity, s.circularity, 1e-6);
    CHECK_NEAR(angle_gap_deg(fmod(t.orientation_deg + 180, 90), 30), 0, 1e-6);
    CHECK_NEAR(t.roundness, s.roundness, 1e-6);

    /* a rectangle 4 x 1: elongation 1/4, orientation 0, R_insc 1/2, R_circ sqrt(17)/2 */
    gp_vec2 rc[4] = {{0, 0}, {4, 0}, {4, 1}, {0, 1}};
    CHECK(gp_shape_describe(rc, 4, NULL, &t, NULL) == GP_OK);
    CHECK_NEAR(t.elongation, 0.25, 1e-12);
    CHECK_NEAR(t.orientation_deg, 0.0, 1e-9);
    CHECK_NEAR(t.circularity, sqrt(0.5 / (sqrt(17.0) / 2)), 1e-6);
}

/* notched square (side 4, a 1 x 1 notch in the middle of the top edge):
 * P = 18, P_conv = 16 -> regularity log10(18 / 2) = log10(9); R_insc = 1.5 (circle at (2, 1.5)
 * between the bottom and the notch floor; off-centre the walls give < 1.5), R_circ = 2 sqrt 2 */
static void test_notched(void)
{
    gp_vec2 p[8] = {{0, 0}, {4, 0}, {4, 4}, {2.5, 4}, {2.5, 3}, {1.5, 3}, {1.5, 4}, {0, 4}};
    gp_shape_result s;
    gp_error e;
    CHECK(gp_shape_describe(p, 8, NULL, &s, &e) == GP_OK);
    CHECK_NEAR(s.perimeter, 18.0, 1e-12);
    CHECK_NEAR(s.perimeter_convex, 16.0, 1e-12);
    CHECK_NEAR(s.regularity, log10(9.0), 1e-12);
    CHECK(s.regularity_capped == 0);
    CHECK_NEAR(s.r_insc, 1.5, 1e-5);
    CHECK(s.insc_center.x > 1.5 - 1e-5 && s.insc_center.x < 2.5 + 1e-5); /* any x in [1.5, 2.5] */
    CHECK_NEAR(s.insc_center.y, 1.5, 1e-5);
    CHECK_NEAR(s.r_circ, 2 * sqrt(2.0), 1e-12);
    CHECK_NEAR(s.circularity, sqrt(1.5 / (2 * sqrt(2.0))), 1e-5);
    CHECK_NEAR(s.elongation, 1.0, 1e-12);
    /* deeper notch (2 deep): P = 20, P_conv = 16, regularity log10(5) */
    gp_vec2 q[8] = {{0, 0}, {4, 0}, {4, 4}, {2.5, 4}, {2.5, 2}, {1.5, 2}, {1.5, 4}, {0, 4}};
    CHECK(gp_shape_describe(q, 8, NULL, &s, &e) == GP_OK);
    CHECK_NEAR(s.regularity, log10(5.0), 1e-12);
}

static void test_regularity_fn(void)
{
    int c;
    CHECK_NEAR(gp_shape_regularity(10.0, 9.0, &c), 1.0, 1e-15);
    CHECK(c == 0);
    CHECK_NEAR(gp_shape_regularity(1.0, 1.0 - 1e-3, &c), 3.0, 1e-9);
    CHECK(gp_shape_regularity(1.0, 1.0, &c) == GP_SHAPE_REGULARITY_CAP && c == 1);
    CHECK(gp_shape_regularity(1.0, 1.0 + 1e-15, &c) == GP_SHAPE_REGULARITY_CAP && c == 1);
    /* continuity at the cap: just below 1e-5 relative difference the formula gives ~5 */
    CHECK_NEAR(gp_shape_regularity(1.0, 1.0 - 1.0001e-5, &c), 5.0, 1e-4);
    CHECK(c == 0);
    CHECK(isnan(gp_shape_regularity(0.0, 0.0, NULL)));
    CHECK(isnan(gp_shape_regularity(NAN, 1.0, NULL)));
}

/* Fourier grain r0 (1 + D2 cos 2 theta), evaluated here analytically (independent of gp_fourier):
 * S = 2 r0 (1 - D2) (for D2 <= 0.2 the widest point across is theta = pi/2),
 * L = 2 r0 (1 + D2) -> elongation (1 - D2)/(1 + D2) */
static void test_fourier_grain(void)
{
    double D2s[] = {0.05, 0.1, 0.2};
    gp_vec2 p[128];
    for (int k = 0; k < 3; k++) {
        double D2 = D2s[k];
        for (int i = 0; i < 128; i++) {
            double th = 2 * PI * i / 128, r = 1.5 * (1 + D2 * cos(2 * th));
            p[i] = (gp_vec2){r * cos(th), r * sin(th)};
        }
        gp_shape_result s;
        CHECK(gp_shape_describe(p, 128, NULL, &s, NULL) == GP_OK);
        CHECK_REL(s.elongation, (1 - D2) / (1 + D2), 0.02);
        /* flush-edge tilt: at most half the turning angle of the 128-gon at theta = pi/2,
         * kappa r dtheta = (1 - 5 D2)/(1 - D2) * 2 pi/128 <= 2 pi/128 -> 180/128 degrees */
        CHECK_NEAR(s.orientation_deg, 0.0, 180.0 / 128);
        /* the same through the curve variant (contour generated from the curve) */
        double D[3] = {1, 0, D2}, dl[3] = {0, 0, 0};
        gp_shape_curve cv = {{0, 0}, 1.5, D, dl, 3};
        gp_shape_result f;
        CHECK(gp_shape_describe_fourier(NULL, 128, &cv, NULL, &f, NULL) == GP_OK);
        CHECK_NEAR(f.elongation, s.elongation, 1e-12);
        CHECK_NEAR(f.circularity, s.circularity, 1e-9);
        CHECK(f.perimeter_points == GP_SHAPE_PERIMETER_POINTS);
        CHECK(f.regularity == GP_SHAPE_REGULARITY_CAP); /* convex for D2 <= 0.2 */
    }
}

/* the curve variant: P and P_conv from 512 points of the analytic curve, the rest from the
 * given contour */
static void test_curve_variant(void)
{
    enum { NM = 64 };
    double D[NM], dl[NM];
    D[0] = 1;
    D[1] = 0;
    dl[0] = dl[1] = 0;
    for (int n = 2; n < NM; n++) {
        D[n] = n < 8 ? 0.05 * 9.0 / (n * n) : 0.03 * 64.0 / (n * n);
        dl[n] = sin(1.7 * n) * PI; /* fixed "random" phases */
    }
    gp_shape_curve cv = {{0.5, -0.5}, 2.0, D, dl, NM};
    /* curve points against a direct cos() sum (independent of gp_shape's recurrence) */
    gp_vec2 *fine = malloc(512 * sizeof *fine);
    CHECK(gp_shape_curve_points(&cv, 512, fine, NULL) == GP_OK);
    double dev = 0;
    for (int i = 0; i < 512; i++) {
        double th = 2 * PI * i / 512, s = 1;
        for (int n = 1; n < NM; n++)
            s += D[n] * cos(n * th - dl[n]);
        dev = fmax(dev, fabs(fine[i].x - (0.5 + 2 * s * cos(th))));
        dev = fmax(dev, fabs(fine[i].y - (-0.5 + 2 * s * sin(th))));
    }
    CHECK_NEAR(dev, 0, 1e-12);
    /* perimeter of those 512 points by hand */
    double P = 0;
    for (int i = 0; i < 512; i++)
        P += hypot(fine[(i + 1) % 512].x - fine[i].x, fine[(i + 1) % 512].y - fine[i].y);
    gp_vec2 c128[128];
    CHECK(gp_shape_curve_points(&cv, 128, c128, NULL) == GP_OK);
    gp_shape_result a, b;
    CHECK(gp_shape_describe_fourier(c128, 128, &cv, NULL, &a, NULL) == GP_OK);
    CHECK(gp_shape_describe(c128, 128, NULL, &b, NULL) == GP_OK);
    CHECK_NEAR(a.perimeter, P, 1e-9);
    CHECK(a.perimeter_points == 512 && b.perimeter_points == 128);
    CHECK(a.regularity_capped == 0);
    /* the 512-point perimeter is longer (roughness resolved) */
    CHECK(a.perimeter > b.perimeter);
    CHECK(a.elongation == b.elongation && a.roundness == b.roundness &&
          a.circularity == b.circularity);
    /* precomputed ODEC gives the same roundness */
    gp_odec_result od;
    CHECK(gp_odec_build(c128, 128, NULL, &od, NULL) == GP_OK);
    gp_shape_result c;
    CHECK(gp_shape_describe_ex(c128, 128, NULL, od.discs, od.ndiscs, &cv, &c, NULL) == GP_OK);
    CHECK(c.roundness == a.roundness && c.regularity == a.regularity);
    gp_odec_result_free(&od);
    /* a non-star curve */
    double Dn[4] = {1, 0, 0.7, 0.5}, dn[4] = {0, 0, 0, PI / 2};
    gp_shape_curve bad = {{0, 0}, 1.0, Dn, dn, 4};
    gp_error e;
    CHECK(gp_shape_describe_fourier(NULL, 128, &bad, NULL, &a, &e) == GP_ERR_NOT_STAR);
    free(fine);
}

static void test_errors(void)
{
    gp_shape_result s;
    gp_error e;
    gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    CHECK(gp_shape_describe(NULL, 4, NULL, &s, &e) == GP_ERR_INVALID);
    CHECK(gp_shape_describe(sq, 2, NULL, &s, &e) == GP_ERR_INVALID);
    CHECK(gp_shape_describe(sq, 4, NULL, NULL, &e) == GP_ERR_INVALID);
    gp_vec2 nanp[4] = {{0, 0}, {1, 0}, {1, NAN}, {0, 1}};
    CHECK(gp_shape_describe(nanp, 4, NULL, &s, &e) == GP_ERR_INVALID);
    gp_vec2 line[3] = {{0, 0}, {1, 0}, {2, 0}};
    CHECK(gp_shape_describe(line, 3, NULL, &s, &e) == GP_ERR_DEGENERATE);
    gp_odec_params bad = {-1, 0.02, 0};
    CHECK(gp_shape_describe(sq, 4, &bad, &s, &e) == GP_ERR_INVALID);
    CHECK(gp_shape_describe_fourier(sq, 4, NULL, NULL, &s, &e) == GP_ERR_INVALID);
    double D[3] = {1, 0, NAN}, dl[3] = {0};
    gp_shape_curve cv = {{0, 0}, 1.0, D, dl, 3};
    CHECK(gp_shape_describe_fourier(sq, 4, &cv, NULL, &s, &e) == GP_ERR_INVALID);
}

int main(void)
{
    test_circle();
    test_ellipse();
    test_square();
    test_notched();
    test_regularity_fn();
    test_fourier_grain();
    test_curve_variant();
    test_errors();
    return gp_test_summary();
}
