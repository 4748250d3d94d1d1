/* test_fill3d.c -- one grain in one convex cell (gp_fill3d.h), against independent truth: the LP
 * against every vertex of the feasible set; a sphere's and a box's largest scale against the
 * widths of the cell; every point inside by brute force; units and offsets; bad input. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_fill3d.h"
#include "gp_test.h"

static unsigned long long rng_state = 88172645463325252ULL;
static double u01(void *s)
{
    unsigned long long *x = s;
    *x ^= *x << 13;
    *x ^= *x >> 7;
    *x ^= *x << 17;
    return (double)(*x >> 11) / 9007199254740992.0;
}

/* ---------------------------------------------------------------- the LP by brute force */

static int solve4(double M[4][5], double x[4])
{
    for (int c = 0; c < 4; c++) {
        int p = c;
        for (int r = c + 1; r < 4; r++)
            if (fabs(M[r][c]) > fabs(M[p][c])) p = r;
        if (fabs(M[p][c]) < 1e-12) return 0;
        for (int k = 0; k < 5; k++) {
            double t = M[c][k];
            M[c][k] = M[p][k];
            M[p][k] = t;
        }
        for (int r = 0; r < 4; r++) {
            if (r == c) continue;
            double f = M[r][c] / M[c][c];
            for (int k = c; k < 5; k++) M[r][k] -= f * M[c][k];
        }
    }
    for (int c = 0; c < 4; c++) x[c] = M[c][4] / M[c][c];
    return 1;
}

/* max x3 over every vertex (four tight rows) that satisfies all rows */
static double lp_brute(const double *a, const double *b, size_t m)
{
    double best = -INFINITY;
    for (size_t i = 0; i < m; i++)
        for (size_t j = i + 1; j < m; j++)
            for (size_t k = j + 1; k < m; k++)
                for (size_t l = k + 1; l < m; l++) {
                    size_t r[4] = {i, j, k, l};
                    double M[4][5], x[4];
                    for (int q = 0; q < 4; q++) {
                        memcpy(M[q], a + 4 * r[q], 4 * sizeof(double));
                        M[q][4] = b[r[q]];
                    }
                    if (!solve4(M, x)) continue;
                    int ok = 1;
                    for (size_t q = 0; q < m && ok; q++)
                        ok = a[4 * q] * x[0] + a[4 * q + 1] * x[1] + a[4 * q + 2] * x[2] + a[4 * q + 3] * x[3] <=
                             b[q] + 1e-9;
                    if (ok && x[3] > best) best = x[3];
                }
    return best;
}

static void lp_against_vertices(void)
{
    int agree = 0, trials = 200;
    double worst = 0.0;
    for (int t = 0; t < trials; t++) {
        size_t m = 6 + (size_t)(u01(&rng_state) * 12);
        double a[4 * 24] = {0}, b[24], x[4];
        for (size_t k = 0; k < m; k++) {
            for (int c = 0; c < 3; c++) a[4 * k + c] = 2.0 * u01(&rng_state) - 1.0;
            a[4 * k + 3] = 0.05 + u01(&rng_state);
            b[k] = 0.1 + u01(&rng_state);
        }
        for (int c = 0; c < 6; c++, m++) { /* |x_c| <= 10: bounded */
            a[4 * m + c / 2] = c % 2 ? -1.0 : 1.0;
            b[m] = 10.0;
        }
        if (gp_fill3d_lp(a, b, m, x) != 0) continue;
        double ref = lp_brute(a, b, m), gap = fabs(ref - x[3]);
        int feasible = 1;
        for (size_t k = 0; k < m; k++)
            feasible &= a[4 * k] * x[0] + a[4 * k + 1] * x[1] + a[4 * k + 2] * x[2] + a[4 * k + 3] * x[3] <= b[k] + 1e-12;
        worst = fmax(worst, gap);
        agree += feasible && gap <= 1e-9 * fmax(1.0, fabs(ref));
    }
    printf("LP: %d of %d random LPs equal the best of their vertices (largest gap %.1e)\n", agree, trials, worst);
    CHECK(agree == trials);
    /* unbounded: one row, x3 free to grow along x0 */
    double a1[4] = {1, 0, 0, 0}, b1[1] = {1}, x[4];
    CHECK(gp_fill3d_lp(a1, b1, 1, x) == 1);
}

/* ----------------------------------------------------------------------- cells and grains */

static void box_planes(const double R[9], const double half[3], const double o[3], double *planes)
{
    for (int k = 0; k < 3; k++)
        for (int s = 0; s < 2; s++) {
            double *P = planes + 4 * (2 * k + s), sg = s ? -1.0 : 1.0;
            for (int r = 0; r < 3; r++) P[r] = sg * R[3 * r + k]; /* column k of R: the box's axis */
            P[3] = P[0] * o[0] + P[1] * o[1] + P[2] * o[2] + half[k];
        }
}

static void box_inertia(const double R[9], const double half[3], double I[9])
{
    double a = 2 * half[0], b = 2 * half[1], c = 2 * half[2], V = a * b * c;
    double D[3] = {V * (b * b + c * c) / 12, V * (a * a + c * c) / 12, V * (a * a + b * b) / 12};
    for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) {
            I[3 * r + q] = 0;
            for (int k = 0; k < 3; k++) I[3 * r + q] += R[3 * r + k] * D[k] * R[3 * q + k];
        }
}

static void random_rotation(double R[9])
{
    double q[4], n = 0;
    for (int k = 0; k < 4; k++) {
        q[k] = 2 * u01(&rng_state) - 1;
        n += q[k] * q[k];
    }
    n = sqrt(n);
    double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                   2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                   2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    memcpy(R, M, sizeof M);
}

/* points on an ellipsoid of semi-axes e (a Fibonacci lattice), its volume and inertia */
static void ellipsoid(const double e[3], double *pts, size_t n, double *V, double I[9])
{
    for (size_t i = 0; i < n; i++) {
        double z = 1 - (2 * i + 1.0) / n, r = sqrt(1 - z * z), ph = i * M_PI * (3 - sqrt(5.0));
        pts[3 * i] = e[0] * r * cos(ph);
        pts[3 * i + 1] = e[1] * r * sin(ph);
        pts[3 * i + 2] = e[2] * z;
    }
    *V = 4.0 / 3.0 * M_PI * e[0] * e[1] * e[2];
    memset(I, 0, 9 * sizeof(double));
    I[0] = *V * (e[1] * e[1] + e[2] * e[2]) / 5;
    I[4] = *V * (e[0] * e[0] + e[2] * e[2]) / 5;
    I[8] = *V * (e[0] * e[0] + e[1] * e[1]) / 5;
}

/* every point of the placed grain inside every face, by brute force: the worst n.x - d over
 * the cell's size */
static double worst_outside(const gp_fill3d_cell *c, const gp_fill3d_grain *g, const gp_fill3d_result *r)
{
    double worst = -INFINITY, L = cbrt(c->volume);
    for (size_t i = 0; i < g->n; i++) {
        const double *p = g->points + 3 * i;
        double x[3];
        for (int k = 0; k < 3; k++)
            x[k] = r->centre[k] + r->scale * (r->R[3 * k] * p[0] + r->R[3 * k + 1] * p[1] + r->R[3 * k + 2] * p[2]);
        for (size_t f = 0; f < c->nplanes; f++) {
            const double *P = c->planes + 4 * f;
            double len = sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2]);
            worst = fmax(worst, ((P[0] * x[0] + P[1] * x[1] + P[2] * x[2]) - P[3]) / len / L);
        }
    }
    return worst;
}

/* a 2 x 1 x 0.5 box grain in a turned 4 x 2 x 1 box cell: aligned, it fits at scale 2 exactly;
 * at F_S 0.5 it is centred in the cell */
static void box_in_box(void)
{
    double R[9], half[3] = {2, 1, 0.5}, o[3] = {0.3, -1.2, 5.0}, planes[24];
    random_rotation(R);
    box_planes(R, half, o, planes);
    gp_fill3d_cell c = {planes, 6, {o[0] + 0.1, o[1] - 0.05, o[2] + 0.02}, 8.0, {0}};
    box_inertia(R, half, c.inertia);
    double pts[24], gh[3] = {1, 0.5, 0.25}, I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) pts[3 * i + k] = (i >> k & 1) ? gh[k] : -gh[k];
    gp_fill3d_grain g = {pts, 8, 1.0, {0}};
    box_inertia(I3, gh, g.inertia);
    gp_fill3d_params p;
    gp_fill3d_params_defaults(&p);
    p.solid_fraction = 1.0;
    gp_fill3d_result r;
    CHECK(gp_fill3d_place(&c, &g, &p, u01, &rng_state, &r, NULL) == GP_OK);
    CHECK_NEAR(r.scale_max, 2.0, 1e-9);
    CHECK_NEAR(r.fraction, 1.0, 1e-7);
    CHECK(worst_outside(&c, &g, &r) <= 0.0);
    p.solid_fraction = 0.5;
    CHECK(gp_fill3d_place(&c, &g, &p, u01, &rng_state, &r, NULL) == GP_OK);
    CHECK(r.target_met);
    CHECK_NEAR(r.fraction, 0.5, 1e-12);
    CHECK_NEAR(r.scale, cbrt(4.0), 1e-12);
    for (int k = 0; k < 3; k++) CHECK_NEAR(r.centre[k], o[k], 1e-9);
    printf("box in box: largest scale %.12f (2), at F_S 0.5 centred within %.1e\n", r.scale_max,
           fmax(fabs(r.centre[0] - o[0]), fmax(fabs(r.centre[1] - o[1]), fabs(r.centre[2] - o[2]))));
}

/* an ellipsoid in a turned box: the largest scale for the returned R equals the least of the
 * box's widths over the grain's widths along its axes, recomputed from the points */
static void ellipsoid_in_box(double offset, double unit)
{
    double R[9], half[3] = {1.5 * unit, 1.0 * unit, 0.6 * unit}, o[3] = {offset, -offset, 2 * offset}, planes[24];
    random_rotation(R);
    box_planes(R, half, o, planes);
    gp_fill3d_cell c = {planes, 6, {o[0], o[1], o[2]}, 8 * half[0] * half[1] * half[2], {0}};
    box_inertia(R, half, c.inertia);
    enum { N = 3000 };
    static double pts[3 * N];
    double e[3] = {1.0, 0.8, 0.5}, V;
    gp_fill3d_grain g = {pts, N, 0, {0}};
    ellipsoid(e, pts, N, &V, g.inertia);
    g.volume = V;
    gp_fill3d_params p;
    gp_fill3d_params_defaults(&p);
    p.solid_fraction = 0.9; /* out of reach: the ellipsoid fills pi/6 of its box at most */
    p.rotations = 0;
    gp_fill3d_result r;
    CHECK(gp_fill3d_place(&c, &g, &p, NULL, NULL, &r, NULL) == GP_OK);
    double smax = INFINITY;
    for (int k = 0; k < 3; k++) {
        double hp = -INFINITY, hm = -INFINITY;
        for (size_t i = 0; i < N; i++) {
            double x = 0;
            for (int q = 0; q < 3; q++)
                x += R[3 * q + k] * (r.R[3 * q] * pts[3 * i] + r.R[3 * q + 1] * pts[3 * i + 1] + r.R[3 * q + 2] * pts[3 * i + 2]);
            hp = fmax(hp, x);
            hm = fmax(hm, -x);
        }
        smax = fmin(smax, 2 * half[k] / (hp + hm));
    }
    /* the coordinates' own rounding, relative to the cell */
    double tol = 1e-9 + 64 * 2.2e-16 * fabs(offset) / unit;
    CHECK(!r.target_met);
    CHECK_NEAR(r.scale_max / smax, 1.0, tol);
    CHECK(r.scale <= r.scale_max && r.scale >= r.scale_max * (1 - 1e-8 - 4 * tol));
    CHECK(worst_outside(&c, &g, &r) <= 0.0);
    /* aligned, long on long: the least of 3 / 2, 2 / 1.6, 1.2 / 1 (the points fall short of the
     * poles by a hair) */
    CHECK(fabs(r.scale_max / unit - 1.2) < 1e-3);
    printf("ellipsoid in box (offset %g, unit %g): largest scale / widths' %.12f, scale %.5f (aligned 1.2)\n",
           offset, unit, r.scale_max / smax, r.scale_max / unit);
}

/* random convex cells (a dozen planes about the origin) and an ellipsoid: every point inside,
 * the fraction never above F_S, the climb never worse than the aligned pose, the same bytes
 * twice */
static void random_cells(void)
{
    enum { N = 1500 };
    static double pts[3 * N];
    double e[3] = {1.0, 0.7, 0.45}, V;
    gp_fill3d_grain g = {pts, N, 0, {0}};
    ellipsoid(e, pts, N, &V, g.inertia);
    g.volume = V;
    int inside = 0, met = 0, climbed_ok = 0, same = 0, cells = 60;
    for (int t = 0; t < cells; t++) {
        double planes[4 * 20] = {0};
        for (int f = 14; f < 20; f++) { /* a box of +-2 keeps the cell bounded */
            planes[4 * f + (f - 14) / 2] = f % 2 ? -1.0 : 1.0;
            planes[4 * f + 3] = 2.0;
        }
        for (int f = 0; f < 14; f++) {
            double z = 2 * u01(&rng_state) - 1, ph = 2 * M_PI * u01(&rng_state), r = sqrt(1 - z * z);
            double n[3] = {r * cos(ph), 1.6 * r * sin(ph), 0.7 * z};
            memcpy(planes + 4 * f, n, sizeof n);
            planes[4 * f + 3] = 0.5 + u01(&rng_state);
        }
        gp_fill3d_cell c = {planes, 20, {0, 0, 0}, 1.0, {1, 0, 0, 0, 2, 0.3, 0, 0.3, 3}};
        gp_fill3d_params p;
        gp_fill3d_params_defaults(&p);
        p.solid_fraction = 0.05 + 0.5 * u01(&rng_state);
        p.rotations = 0;
        gp_fill3d_result r0, r1, r2;
        unsigned long long s1 = 7 + t, s2 = 7 + t;
        CHECK(gp_fill3d_place(&c, &g, &p, NULL, NULL, &r0, NULL) == GP_OK);
        p.rotations = 24;
        CHECK(gp_fill3d_place(&c, &g, &p, u01, &s1, &r1, NULL) == GP_OK);
        CHECK(gp_fill3d_place(&c, &g, &p, u01, &s2, &r2, NULL) == GP_OK);
        inside += worst_outside(&c, &g, &r0) <= 0.0 && worst_outside(&c, &g, &r1) <= 0.0;
        met += r1.target_met;
        climbed_ok += r1.scale_max >= r0.scale_max * (1 - 1e-12) || r0.target_met;
        same += memcmp(&r1, &r2, sizeof r1) == 0;
        CHECK(r1.fraction <= p.solid_fraction * (1 + 1e-12));
    }
    printf("random cells: %d of %d inside, %d met F_S, climb never worse in %d, same bytes %d\n", inside, cells,
           met, climbed_ok, same);
    CHECK(inside == cells && climbed_ok == cells && same == cells);
}

static void bad_input(void)
{
    double planes[24], R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, half[3] = {1, 1, 1}, o[3] = {0, 0, 0};
    box_planes(R, half, o, planes);
    double pts[24], gh[3] = {1, 1, 1};
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) pts[3 * i + k] = (i >> k & 1) ? gh[k] : -gh[k];
    gp_fill3d_cell c = {planes, 6, {0, 0, 0}, 8.0, {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    gp_fill3d_grain g = {pts, 8, 8.0, {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    gp_fill3d_params p;
    gp_fill3d_params_defaults(&p);
    gp_fill3d_result r;
    gp_error e;
    p.solid_fraction = 0;
    CHECK(gp_fill3d_place(&c, &g, &p, u01, &rng_state, &r, &e) == GP_ERR_INVALID && strstr(e.message, "solid_fraction"));
    gp_fill3d_params_defaults(&p);
    c.interior[0] = 1.5;
    CHECK(gp_fill3d_place(&c, &g, &p, u01, &rng_state, &r, &e) == GP_ERR_DEGENERATE && strstr(e.message, "interior"));
    c.interior[0] = 0;
    for (int i = 0; i < 8; i++) pts[3 * i] += 2.0; /* the origin outside the grain */
    CHECK(gp_fill3d_place(&c, &g, &p, u01, &rng_state, &r, &e) == GP_ERR_DEGENERATE && strstr(e.message, "origin"));
    g.n = 3;
    CHECK(gp_fill3d_place(&c, &g, &p, u01, &rng_state, &r, &e) == GP_ERR_INVALID);
}

int main(void)
{
    lp_against_vertices();
    box_in_box();
    ellipsoid_in_box(0.0, 1.0);
    ellipsoid_in_box(1e6, 1e-3);
    ellipsoid_in_box(-3e-4, 1e-6);
    random_cells();
    bad_input();
    return gp_test_summary();
}
