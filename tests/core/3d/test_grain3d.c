/* test_grain3d.c -- 3D Fourier grains, each against a truth of its own:
 *  harmonics against GSL's older sphPlm (another code path), the table against direct sums;
 *  (a) the spectrum comes back from a least-squares fit of the mesh radii (gsl_multifit_linear,
 *      with this file's own harmonics), with and without spread;
 *  (b) a smooth stretched grain is the ellipsoid (its vertices on the ellipsoid's equation, its
 *      descriptors), a rough stretched grain is the affine image of the rough one;
 *  (c) star shape: a large spectrum refused, tilted zonal fields on either side of their known
 *      critical amplitude, random fields scaled on either side of their brute-force minimum,
 *      the accepted ones checked positive on a level-7 icosphere;
 *  (d) determinism and the number of draws;
 *  (e) projections of a sphere and of an ellipsoid (2D descriptors, outlines);
 *  (f) the section's leakage: a great circle of a degree-2 field shows 3/4 of its power at 2D
 *      mode 2;
 *  bad arguments. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_multifit.h>
#include <gsl/gsl_sf_legendre.h>

#include "gp_fourier.h"
#include "gp_grain3d.h"
#include "gp_test.h"

#define PI 3.14159265358979323846

typedef struct stream {
    uint64_t s;
    long draws;
} stream;

static double u01(void *p)
{
    stream *st = p;
    st->s ^= st->s << 13;
    st->s ^= st->s >> 7;
    st->s ^= st->s << 17;
    st->draws++;
    return (double)(st->s >> 11) * (1.0 / 9007199254740992.0);
}

static stream stream_of(uint64_t k)
{
    stream s = {0x9E3779B97F4A7C15ull * (k + 1) ^ 0xD1B54A32D192ED03ull, 0};
    for (int i = 0; i < 10; i++) u01(&s);
    s.draws = 0;
    return s;
}

static double bad_u01(void *p)
{
    (void)p;
    return 1.5;
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* This file's real harmonics: GSL's sphPlm (with the Condon-Shortley phase, removed here) and
 * cos / sin of m atan2, index n^2 + n + m. */
static void my_harmonics(int N, const double *u, double *Y)
{
    double r = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), x = u[2] / r, p = atan2(u[1], u[0]), P[32];
    x = x > 1 ? 1 : x < -1 ? -1 : x;
    for (int m = 0; m <= N; m++) {
        gsl_sf_legendre_sphPlm_array(N, m, x, P); /* P[l - m], l = m .. N */
        double c = m ? (m % 2 ? -1 : 1) * sqrt(2.0) * cos(m * p) : 1, sn = (m % 2 ? -1 : 1) * sqrt(2.0) * sin(m * p);
        for (int n = m; n <= N; n++) {
            Y[n * n + n + m] = c * P[n - m];
            if (m) Y[n * n + n - m] = sn * P[n - m];
        }
    }
}

static double my_field(const gp_grain3d_shape *s, const double *u)
{
    double Y[961], r = 1;
    my_harmonics((int)s->degree, u, Y);
    for (size_t k = 1; k < GP_GRAIN3D_NCOEF(s->degree); k++) r += s->c[k] * Y[k];
    return r;
}

static void the_spectrum(double *D, size_t nmodes)
{
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, nmodes, D, NULL) == GP_OK);
}

static void test_harmonics(const gp_grain3d_basis *b)
{
    double Y[961], Z[961], worst = 0;
    stream st = stream_of(7);
    for (int t = 0; t < 200; t++) {
        double u[3] = {2 * u01(&st) - 1, 2 * u01(&st) - 1, 2 * u01(&st) - 1};
        if (t == 0) u[0] = u[1] = 0; /* the pole */
        gp_grain3d_harmonics(30, u, Y);
        my_harmonics(30, u, Z);
        for (int k = 0; k < 961; k++) worst = fmax(worst, fabs(Y[k] - Z[k]));
    }
    printf("harmonics to degree 30 against sphPlm: largest difference %.1e\n", worst);
    CHECK(worst < 1e-12);
    /* orthonormal on the sphere: a quadrature of degree 2 x 8 (Gauss in cos t, 32 x 64) */
    double G[81] = {0};
    int nt = 1000, np = 64;
    for (int i = 0; i < nt; i++) {
        double x = cos(PI * (i + 0.5) / nt), w = PI / nt * sqrt(1 - x * x) * 2 * PI / np; /* midpoint in t */
        for (int j = 0; j < np; j++) {
            double p = 2 * PI * j / np, s = sqrt(1 - x * x), u[3] = {s * cos(p), s * sin(p), x};
            gp_grain3d_harmonics(8, u, Y);
            for (int a = 0; a < 81; a++) G[a] += w * Y[a] * Y[a];
        }
    }
    double dev = 0;
    for (int a = 0; a < 81; a++) dev = fmax(dev, fabs(G[a] - 1));
    CHECK(dev < 1e-3);
    /* the table gives the direct sum's bits at the basis' directions */
    gp_grain3d_shape s;
    double D[16];
    the_spectrum(D, 16);
    gp_grain3d_law law = {D, NULL, 16, 15, 1, 1};
    CHECK(gp_grain3d_draw(&law, u01, &st, &s, NULL) == GP_OK);
    size_t nv = gp_grain3d_basis_count(b);
    double *r = malloc(nv * sizeof(double));
    CHECK(gp_grain3d_radii(b, &s, r, NULL) == GP_OK);
    const double *d = gp_mesh3d_vertices(gp_grain3d_basis_mesh(b));
    double kappa = gp_grain3d_basis_kappa(b);
    int same = 1;
    double diff = 0;
    for (size_t i = 0; i < nv; i++) {
        same &= gp_grain3d_field(&s, d + 3 * i) * kappa == r[i];
        diff = fmax(diff, fabs(kappa * my_field(&s, d + 3 * i) - r[i]));
    }
    CHECK(same);
    CHECK(diff < 1e-12);
    free(r);
}

/* (a) least-squares fit of degrees 0 .. NF to the radii of ngrains grains; mean power per degree */
static void fit_power(const gp_grain3d_basis *b, const gp_grain3d_law *law, int ngrains, int NF,
                      double *mean_power, double *mean_amp, double *worst_rel)
{
    size_t nv = gp_grain3d_basis_count(b), p = (size_t)(NF + 1) * (NF + 1);
    const double *d = gp_mesh3d_vertices(gp_grain3d_basis_mesh(b));
    gsl_matrix *X = gsl_matrix_alloc(nv, p);
    gsl_vector *y = gsl_vector_alloc(nv), *c = gsl_vector_alloc(p);
    gsl_multifit_linear_workspace *w = gsl_multifit_linear_alloc(nv, p);
    double Y[961];
    for (size_t i = 0; i < nv; i++) {
        my_harmonics(NF, d + 3 * i, Y);
        for (size_t k = 0; k < p; k++) gsl_matrix_set(X, i, k, Y[k]);
    }
    gsl_multifit_linear_svd(X, w);
    for (int n = 0; n <= NF; n++) mean_power[n] = mean_amp[n] = worst_rel[n] = 0;
    double *r = malloc(nv * sizeof(double));
    int made = 0, refused = 0;
    for (uint64_t g = 0; made < ngrains; g++) {
        stream st = stream_of(1000 + g);
        gp_grain3d_shape s;
        CHECK(gp_grain3d_draw(law, u01, &st, &s, NULL) == GP_OK);
        if (gp_grain3d_radii(b, &s, r, NULL) != GP_OK) {
            refused++;
            continue;
        }
        double own[31], rn, sn;
        gp_grain3d_power(&s, own);
        for (size_t i = 0; i < nv; i++) gsl_vector_set(y, i, r[i] / gp_grain3d_basis_kappa(b));
        gsl_multifit_linear_solve(0.0, X, y, c, &rn, &sn, w);
        CHECK_NEAR(gsl_vector_get(c, 0), sqrt(4 * PI), 1e-10);
        for (int n = 1; n <= NF; n++) {
            double pw = 0;
            for (int m = -n; m <= n; m++) pw += gsl_vector_get(c, (size_t)(n * n + n + m)) * gsl_vector_get(c, (size_t)(n * n + n + m));
            mean_power[n] += pw / ngrains;
            mean_amp[n] += sqrt(pw / (2 * PI)) / ngrains;
            if (n <= (int)s.degree && own[n] > 0) worst_rel[n] = fmax(worst_rel[n], fabs(pw - own[n]) / own[n]);
            else worst_rel[n] = fmax(worst_rel[n], pw);
        }
        made++;
    }
    if (refused) printf("  (%d grains refused as not star-shaped and redrawn)\n", refused);
    free(r);
    gsl_multifit_linear_free(w);
    gsl_matrix_free(X);
    gsl_vector_free(y);
    gsl_vector_free(c);
}

static void test_spectrum(const gp_grain3d_basis *b)
{
    double D[16], cov[16], mp[18], ma[18], wr[18];
    the_spectrum(D, 16);
    gp_grain3d_law law = {D, NULL, 16, 15, 1, 1};
    fit_power(b, &law, 200, 17, mp, ma, wr);
    printf("(a) spectrum of 200 grains by a least-squares fit of degrees 0-17 to the 2,562 radii\n");
    printf("  n   D_n       2 pi D_n^2   mean fitted   rel. error   worst grain\n");
    for (int n = 1; n <= 17; n++) {
        double target = n < 16 ? 2 * PI * D[n] * D[n] : 0;
        double rel = target > 0 ? fabs(mp[n] - target) / target : mp[n];
        printf("  %-2d  %.5f  %.4e   %.4e    %.1e      %.1e\n", n, n < 16 ? D[n] : 0, target, mp[n], rel, wr[n]);
        if (target > 1e-6) {
            CHECK(rel < 0.05);
            CHECK(wr[n] < 1e-9); /* each grain has exactly 2 pi D_n^2 */
        } else {
            CHECK(mp[n] < 1e-20); /* D_1 = 0 and the degrees above 15: nothing */
        }
    }
    for (int n = 1; n < 16; n++) cov[n] = 0.3;
    law.cov = cov;
    fit_power(b, &law, 200, 15, mp, ma, wr);
    printf("  with spread 0.3: mean fitted D_n / D_n = ");
    for (int n = 2; n < 16; n++) {
        printf("%.3f ", ma[n] / D[n]);
        CHECK(fabs(ma[n] / D[n] - 1) < 0.05); /* E[D_n] = D_n: 200 grains, 2.1 % s.d. */
    }
    printf("\n");
}

/* (b) ellipsoids and stretched rough grains */
static void test_stretch(const gp_grain3d_basis *b)
{
    size_t nv = gp_grain3d_basis_count(b);
    const double *d = gp_mesh3d_vertices(gp_grain3d_basis_mesh(b));
    double *r = malloc(nv * sizeof(double));
    gp_grain3d_shape s;
    memset(&s, 0, sizeof s);
    s.elongation = 0.5;
    s.flatness = 0.6;
    CHECK(gp_grain3d_radii(b, &s, r, NULL) == GP_OK);
    double kappa = gp_grain3d_basis_kappa(b), worst = 0;
    for (size_t i = 0; i < nv; i++) { /* on the ellipsoid (1, 0.5, 0.3) times kappa */
        double x = r[i] * d[3 * i], y = r[i] * d[3 * i + 1], z = r[i] * d[3 * i + 2];
        worst = fmax(worst, fabs((x * x + y * y / 0.25 + z * z / 0.09) / (kappa * kappa) - 1));
    }
    CHECK(worst < 1e-12);
    gp_grain3d_descriptors ds;
    CHECK(gp_grain3d_describe(b, r, &ds, NULL) == GP_OK);
    CHECK_NEAR(ds.elongation, 0.5, 1e-12);
    CHECK_NEAR(ds.flatness, 0.6, 1e-12);
    /* on a basis without the stretch, the ellipsoid's points along the icosphere's directions are
     * not an affine image of the icosphere: the mesh is not quite convex, and coarser near the
     * sharp ends (on a basis made for the stretch it is, below) */
    CHECK(ds.convexity > 0.999 && ds.convexity <= 1);
    CHECK_NEAR(ds.axes.extent[0], 2 * kappa, 1e-12);
    CHECK_NEAR(fabs(ds.axes.axis[0][0]), 1, 1e-12);
    CHECK_NEAR(fabs(ds.axes.axis[2][2]), 1, 1e-12);
    /* the ellipsoid's volume and Wadell sphericity (its area by quadrature) */
    double a = 1, bb = 0.5, c = 0.3, A = 0;
    for (int i = 0; i < 4000; i++) {
        double t = -1 + (i + 0.5) / 2000.0;
        for (int j = 0; j < 256; j++) {
            double p = (j + 0.5) * 2 * PI / 256, cp = cos(p), sp = sin(p);
            A += sqrt(bb * bb * c * c * (1 - t * t) * cp * cp + a * a * c * c * (1 - t * t) * sp * sp + a * a * bb * bb * t * t);
        }
    }
    A *= (2.0 / 4000) * (2 * PI / 256);
    double V = 4.0 / 3.0 * PI * a * bb * c, sph = cbrt(PI) * pow(6 * V, 2.0 / 3.0) / A;
    printf("(b) ellipsoid (1, 0.5, 0.3) on level 4: I/L %.15f, S/I %.15f, volume %.2e, sphericity %.4f (true %.4f), convexity %.5f\n",
           ds.elongation, ds.flatness, fabs(ds.mass.volume - V) / V, ds.sphericity, sph, ds.convexity);
    CHECK_REL(ds.mass.volume, V, 5e-3);
    CHECK_REL(ds.sphericity, sph, 2e-3);
    /* a rough grain stretched: every vertex x satisfies |S^-1 x| = r(S^-1 x) (the field of the
     * unstretched grain, by this file's harmonics) */
    double D[16];
    the_spectrum(D, 16);
    gp_grain3d_law law = {D, NULL, 16, 15, 0.7, 0.5};
    stream st = stream_of(3);
    CHECK(gp_grain3d_draw(&law, u01, &st, &s, NULL) == GP_OK);
    CHECK(gp_grain3d_radii(b, &s, r, NULL) == GP_OK);
    worst = 0;
    for (size_t i = 0; i < nv; i++) {
        double q[3] = {r[i] * d[3 * i] / kappa, r[i] * d[3 * i + 1] / (0.7 * kappa), r[i] * d[3 * i + 2] / (0.35 * kappa)};
        worst = fmax(worst, fabs(sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) - my_field(&s, q)));
    }
    CHECK(worst < 1e-12);
    /* the same grain on a basis made for its stretch: one table product, and its mesh the affine
     * image S (kappa r(u_i) u_i) of the grain sampled on the icosphere's u_i */
    gp_grain3d_basis *bs = gp_grain3d_basis_create_ex(4, 15, 0.7, 0.5, NULL);
    gp_mesh3d *ico = gp_mesh3d_icosphere(4, NULL);
    const double *u = gp_mesh3d_vertices(ico), *dsb = gp_mesh3d_vertices(gp_grain3d_basis_mesh(bs));
    double *r2 = malloc(nv * sizeof(double));
    CHECK(bs && gp_grain3d_basis_elongation(bs) == 0.7 && gp_grain3d_basis_flatness(bs) == 0.5);
    CHECK(gp_grain3d_basis_kappa(bs) == kappa);
    CHECK(gp_grain3d_radii(bs, &s, r2, NULL) == GP_OK);
    worst = 0;
    for (size_t i = 0; i < nv; i++) {
        double f = kappa * my_field(&s, u + 3 * i), S[3] = {1, 0.7, 0.35};
        for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(r2[i] * dsb[3 * i + k] - S[k] * f * u[3 * i + k]));
    }
    printf("    stretched basis against the affine image of the direct sums: %.1e\n", worst);
    CHECK(worst < 1e-13);
    /* and the ellipsoid on a basis for (0.5, 0.6) */
    gp_grain3d_basis *be = gp_grain3d_basis_create_ex(4, 15, 0.5, 0.6, NULL);
    gp_grain3d_shape sm;
    memset(&sm, 0, sizeof sm);
    sm.elongation = 0.5;
    sm.flatness = 0.6;
    CHECK(gp_grain3d_radii(be, &sm, r2, NULL) == GP_OK);
    const double *de = gp_mesh3d_vertices(gp_grain3d_basis_mesh(be));
    worst = 0;
    for (size_t i = 0; i < nv; i++) {
        double x = r2[i] * de[3 * i], y = r2[i] * de[3 * i + 1], z = r2[i] * de[3 * i + 2];
        worst = fmax(worst, fabs((x * x + y * y / 0.25 + z * z / 0.09) / (kappa * kappa) - 1));
    }
    CHECK(worst < 1e-12);
    CHECK(gp_grain3d_describe(be, r2, &ds, NULL) == GP_OK);
    printf("    on a basis for (0.5, 0.6): volume %.1e, convexity %.6f\n", fabs(ds.mass.volume - V) / V, ds.convexity);
    CHECK_REL(ds.mass.volume, V, 1e-12); /* the affine image of the volume-exact sphere */
    CHECK(ds.convexity > 1 - 1e-12);
    gp_mesh3d_destroy(ico);
    /* a stretched basis judges the star shape on its own directions: the zonal fields of (c) */
    double ac = 2 * sqrt(4 * PI / 5), w[3] = {0.3, -0.5, 0.8}, Y[9];
    my_harmonics(2, w, Y);
    for (int q = 0; q < 2; q++) {
        gp_grain3d_shape z;
        memset(&z, 0, sizeof z);
        z.degree = 2;
        z.elongation = 0.7;
        z.flatness = 0.5;
        for (int k = 4; k < 9; k++) z.c[k] = (q ? 1.005 : 0.995) * ac * sqrt(4 * PI / 5) * Y[k];
        CHECK(gp_grain3d_radii(bs, &z, r2, NULL) == (q ? GP_ERR_NOT_STAR : GP_OK));
    }
    gp_grain3d_basis_destroy(bs);
    gp_grain3d_basis_destroy(be);
    free(r2);
    CHECK(gp_grain3d_describe(b, r, &ds, NULL) == GP_OK);
    printf("    rough grain stretched by (1, 0.7, 0.35): I/L %.3f, S/I %.3f, sphericity %.3f, convexity %.3f\n",
           ds.elongation, ds.flatness, ds.sphericity, ds.convexity);
    CHECK(fabs(ds.elongation - 0.7) < 0.1 && fabs(ds.flatness - 0.5) < 0.1);
    CHECK(ds.convexity < 1 && ds.convexity > 0.8);
    free(r);
}

/* r(t) of the zonal body r = 1 + a Y_20 at polar angle t */
static double zonal_r(double a, double t)
{
    double c = cos(t);
    return 1 + a * sqrt(5 / (4 * PI)) * 0.5 * (3 * c * c - 1);
}

/* Its volume and inertia about z and x by Simpson's rule in t (the body is axisymmetric):
 * V = 2 pi / 3 int r^3 sin t, I_zz = 2 pi / 5 int r^5 sin^3 t,
 * I_xx = 1 / 5 int r^5 (pi sin^2 t + 2 pi cos^2 t) sin t. */
static void zonal_truth(double a, double *V, double *Izz, double *Ixx)
{
    const int n = 20000;
    double h = PI / n, v = 0, z = 0, x = 0;
    for (int i = 0; i <= n; i++) {
        double t = i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2), r = zonal_r(a, t), st = sin(t), ct = cos(t);
        v += w * r * r * r * st;
        z += w * pow(r, 5) * st * st * st;
        x += w * pow(r, 5) * (PI * st * st + 2 * PI * ct * ct) * st;
    }
    *V = 2 * PI / 3 * v * h / 3;
    *Izz = 2 * PI / 5 * z * h / 3;
    *Ixx = x / 5 * h / 3;
}

/* (g) the mesh against the smooth body: a sphere, an ellipsoid (the basis' stretch) and the
 * zonal body r = 1 + 0.6 Y_20, volume, centroid and inertia by level against the formulas and
 * a quadrature of their own */
static void test_mesh_volume(void)
{
    double Vz, Izz, Ixx, a = 0.6;
    zonal_truth(a, &Vz, &Izz, &Ixx);
    /* the quadrature against the closed form: (4 pi + 3 a^2 + a^3 int Y_20^3) / 3 */
    CHECK_REL(Vz, (4 * PI + 3 * a * a + a * a * a * pow(5 / (4 * PI), 1.5) * 2 * PI * 4 / 35) / 3, 1e-13);
    double Ve = 4 * PI / 3 * 0.15;
    double Ie[3] = {Ve * (0.25 + 0.09) / 5, Ve * (1 + 0.09) / 5, Ve * (1 + 0.25) / 5};
    double e[7][4]; /* sphere inertia, ellipsoid inertia, zonal volume, zonal inertia */
    printf("(g) the mesh against the smooth body (relative errors)\n  level  sphere I  ellipsoid V  ellipsoid I  zonal V   zonal I   centroids\n");
    for (unsigned l = 2; l <= 6; l++) {
        gp_grain3d_basis *bs = gp_grain3d_basis_create(l, 2, NULL), *be = gp_grain3d_basis_create_ex(l, 0, 0.5, 0.6, NULL);
        CHECK(bs && be);
        if (!bs || !be) return;
        size_t nv = gp_grain3d_basis_count(bs);
        double *r = malloc(nv * sizeof *r), cen = 0;
        gp_grain3d_shape sh;
        memset(&sh, 0, sizeof sh);
        sh.elongation = sh.flatness = 1;
        gp_grain3d_descriptors ds;
        CHECK(gp_grain3d_radii(bs, &sh, r, NULL) == GP_OK && gp_grain3d_describe(bs, r, &ds, NULL) == GP_OK);
        e[l][0] = fabs(ds.mass.inertia[0] - 8 * PI / 15) / (8 * PI / 15);
        CHECK_REL(ds.mass.volume, 4 * PI / 3, 1e-13); /* kappa's definition */
        cen = fmax(cen, fabs(ds.mass.centroid[0]) + fabs(ds.mass.centroid[1]) + fabs(ds.mass.centroid[2]));
        sh.elongation = 0.5;
        sh.flatness = 0.6;
        CHECK(gp_grain3d_radii(be, &sh, r, NULL) == GP_OK && gp_grain3d_describe(be, r, &ds, NULL) == GP_OK);
        double ve = fabs(ds.mass.volume - Ve) / Ve, ie = 0;
        for (int k = 0; k < 3; k++) ie = fmax(ie, fabs(ds.mass.inertia[4 * k] - Ie[k]) / Ie[k]);
        e[l][1] = ie;
        cen = fmax(cen, fabs(ds.mass.centroid[0]) + fabs(ds.mass.centroid[1]) + fabs(ds.mass.centroid[2]));
        sh.elongation = sh.flatness = 1;
        sh.degree = 2;
        sh.c[GP_GRAIN3D_INDEX(2, 0)] = a;
        CHECK(gp_grain3d_radii(bs, &sh, r, NULL) == GP_OK && gp_grain3d_describe(bs, r, &ds, NULL) == GP_OK);
        e[l][2] = fabs(ds.mass.volume - Vz) / Vz;
        e[l][3] = fmax(fabs(ds.mass.inertia[8] - Izz) / Izz, fmax(fabs(ds.mass.inertia[0] - Ixx) / Ixx, fabs(ds.mass.inertia[4] - Ixx) / Ixx));
        cen = fmax(cen, fabs(ds.mass.centroid[0]) + fabs(ds.mass.centroid[1]) + fabs(ds.mass.centroid[2]));
        printf("  %u      %.2e  %.2e     %.2e     %.2e  %.2e  %.0e\n", l, e[l][0], ve, e[l][1], e[l][2], e[l][3], cen);
        CHECK(ve < 1e-13 && cen < 1e-13);
        free(r);
        gp_grain3d_basis_destroy(bs);
        gp_grain3d_basis_destroy(be);
    }
    /* the bound at level 4 for the sphere and the ellipsoid; the zonal body (radius
     * 0.81 to 1.38) has its volume within it, its inertia within 2.1e-3 */
    CHECK(e[4][0] < 1e-6 && e[4][1] < 1e-6 && e[4][2] < 1e-3 && e[4][3] < 2.1e-3);
    for (unsigned l = 2; l < 6; l++) {
        CHECK(e[l + 1][0] < e[l][0] / 12 && e[l + 1][1] < e[l][1] / 12); /* fourth order */
        CHECK(e[l + 1][2] < e[l][2] / 3.5 && e[l + 1][2] > e[l][2] / 4.5); /* second order */
        CHECK(e[l + 1][3] < e[l][3] / 3.5 && e[l + 1][3] > e[l][3] / 4.5);
    }
}

/* min of 1 + f over the level-7 icosphere (163,842 directions), by this file's harmonics */
static double brute_min(const gp_grain3d_shape *s, const gp_mesh3d *fine)
{
    const double *d = gp_mesh3d_vertices(fine);
    double m = INFINITY;
    for (size_t i = 0; i < gp_mesh3d_vertex_count(fine); i++) m = fmin(m, my_field(s, d + 3 * i));
    return m;
}

static void scale_shape(gp_grain3d_shape *s, double k)
{
    for (size_t i = 1; i < GP_GRAIN3D_NCOEF(s->degree); i++) s->c[i] *= k;
}

/* (c) star shape */
static void test_star(const gp_grain3d_basis *b)
{
    size_t nv = gp_grain3d_basis_count(b);
    double *r = malloc(nv * sizeof(double));
    gp_mesh3d *fine = gp_mesh3d_icosphere(7, NULL);
    gp_error err;
    /* a spectrum far too large: D2 = 1.5 (min of 1 + f at most 1 - 0.315 |c_2| = -0.19) */
    double Dbig[3] = {1, 0, 1.5};
    gp_grain3d_law big = {Dbig, NULL, 3, 15, 1, 1};
    int refused = 0;
    for (int g = 0; g < 20; g++) {
        stream st = stream_of(500 + g);
        gp_grain3d_shape s;
        gp_grain3d_draw(&big, u01, &st, &s, NULL);
        refused += gp_grain3d_radii(b, &s, r, &err) == GP_ERR_NOT_STAR;
    }
    CHECK(refused == 20);
    printf("(c) D2 = 1.5: %d / 20 refused (\"%s\")\n", refused, err.message);
    /* tilted zonal degree-2 fields: f = a sqrt(5 / 4 pi) P_2(w . u), minimum -a sqrt(5 / 4 pi) / 2,
     * so r > 0 exactly for a < a_c = 2 sqrt(4 pi / 5) */
    double ac = 2 * sqrt(4 * PI / 5), ks[4] = {0.98, 0.995, 1.005, 1.02};
    stream st = stream_of(77);
    for (int trial = 0; trial < 2; trial++) {
        double w[3] = {2 * u01(&st) - 1, 2 * u01(&st) - 1, 2 * u01(&st) - 1}, Y[9];
        my_harmonics(2, w, Y);
        for (int q = 0; q < 4; q++) {
            gp_grain3d_shape s;
            memset(&s, 0, sizeof s);
            s.degree = 2;
            s.elongation = s.flatness = 1;
            for (int k = 4; k < 9; k++) s.c[k] = ks[q] * ac * sqrt(4 * PI / 5) * Y[k];
            gp_status stt = gp_grain3d_radii(b, &s, r, &err);
            double m = brute_min(&s, fine);
            if (trial == 0) printf("    zonal a = %.3f a_c: %s, brute-force min r / r0 %.5f (exact %.5f)\n", ks[q],
                                   stt == GP_OK ? "accepted" : "refused", m, 1 - ks[q]);
            CHECK(stt == (ks[q] < 1 ? GP_OK : GP_ERR_NOT_STAR));
            if (ks[q] < 1) CHECK(m > 0);
            CHECK(m >= 1 - ks[q] - 1e-12 && m < 1 - ks[q] + 1e-3);
        }
    }
    /* random fields scaled to either side of their brute-force minimum (level 6: 40,962
     * directions), the accepted ones checked again on level 7 */
    double D[16];
    the_spectrum(D, 16);
    gp_grain3d_law law = {D, NULL, 16, 15, 1, 1};
    gp_mesh3d *l6 = gp_mesh3d_icosphere(6, NULL);
    double t0 = now();
    int checks = 0;
    for (int g = 0; g < 4; g++) {
        stream sg = stream_of(900 + g);
        gp_grain3d_shape s, t;
        gp_grain3d_draw(&law, u01, &sg, &s, NULL);
        double m = brute_min(&s, l6) - 1; /* min f < 0 */
        double kin[2] = {0.9, 0.97}, kout = 1.02;
        for (int q = 0; q < 2; q++) {
            t = s;
            scale_shape(&t, kin[q] / -m);
            double t1 = now();
            gp_status stt = gp_grain3d_radii(b, &t, r, &err);
            if (g == 0) printf("    random field at %.2f of its critical scale: %s in %.2f ms\n", kin[q],
                               stt == GP_OK ? "accepted" : "refused", 1e3 * (now() - t1));
            CHECK(stt == GP_OK);
            if (stt) printf("    %s\n", err.message);
            if (g == 0) CHECK(brute_min(&t, fine) > 0);
            checks++;
        }
        t = s;
        scale_shape(&t, kout / -m);
        CHECK(gp_grain3d_radii(b, &t, r, &err) == GP_ERR_NOT_STAR);
    }
    printf("    %d random fields checked in %.2f s (brute force included)\n", checks, now() - t0);
    gp_mesh3d_destroy(l6);
    gp_mesh3d_destroy(fine);
    free(r);
}

/* (d) determinism */
static void test_determinism(const gp_grain3d_basis *b)
{
    double D[16], cov[16];
    the_spectrum(D, 16);
    for (int n = 0; n < 16; n++) cov[n] = 0.2;
    gp_grain3d_law law = {D, cov, 16, 15, 0.8, 0.7};
    size_t nv = gp_grain3d_basis_count(b);
    double *r1 = malloc(nv * sizeof(double)), *r2 = malloc(nv * sizeof(double)), *r3 = malloc(nv * sizeof(double));
    gp_grain3d_shape s1, s2, s3;
    stream a = stream_of(42), c = stream_of(42), e = stream_of(43);
    CHECK(gp_grain3d_draw(&law, u01, &a, &s1, NULL) == GP_OK);
    CHECK(gp_grain3d_draw(&law, u01, &c, &s2, NULL) == GP_OK);
    CHECK(gp_grain3d_draw(&law, u01, &e, &s3, NULL) == GP_OK);
    CHECK(memcmp(&s1, &s2, sizeof s1) == 0);
    CHECK(memcmp(&s1, &s3, sizeof s1) != 0);
    /* 15 degrees: 15 x 17 = 255 direction variates, 15 spread ones: 270, 270 draws */
    CHECK(a.draws == 270);
    law.cov = NULL;
    stream f = stream_of(42);
    gp_grain3d_shape s4;
    gp_grain3d_draw(&law, u01, &f, &s4, NULL);
    CHECK(f.draws == 256); /* 255 variates: 128 pairs */
    CHECK(gp_grain3d_radii(b, &s1, r1, NULL) == GP_OK);
    CHECK(gp_grain3d_radii(b, &s2, r2, NULL) == GP_OK);
    CHECK(gp_grain3d_radii(b, &s3, r3, NULL) == GP_OK);
    CHECK(memcmp(r1, r2, nv * sizeof(double)) == 0);
    CHECK(memcmp(r1, r3, nv * sizeof(double)) != 0);
    gp_grain3d_descriptors d1, d2;
    gp_grain3d_describe(b, r1, &d1, NULL);
    gp_grain3d_describe(b, r2, &d2, NULL);
    CHECK(memcmp(&d1, &d2, sizeof d1) == 0);
    free(r1);
    free(r2);
    free(r3);
}

/* (e) projections */
static void test_projections(const gp_grain3d_basis *b)
{
    size_t nv = gp_grain3d_basis_count(b);
    double *r = malloc(nv * sizeof(double));
    gp_grain3d_shape s;
    memset(&s, 0, sizeof s);
    s.elongation = s.flatness = 1;
    CHECK(gp_grain3d_radii(b, &s, r, NULL) == GP_OK);
    gp_grain3d_descriptors ds;
    gp_shape_result pr[3];
    CHECK(gp_grain3d_describe(b, r, &ds, NULL) == GP_OK);
    CHECK(gp_grain3d_describe_projections(b, r, &ds.axes, NULL, pr, NULL) == GP_OK);
    printf("(e) sphere: sphericity %.4f, convexity %.15f; projections: elongation %.4f %.4f %.4f, circularity %.4f %.4f %.4f\n",
           ds.sphericity, ds.convexity, pr[0].elongation, pr[1].elongation, pr[2].elongation, pr[0].circularity,
           pr[1].circularity, pr[2].circularity);
    CHECK(ds.sphericity > 0.998 && ds.sphericity <= 1);
    CHECK_NEAR(ds.convexity, 1, 1e-12);
    for (int k = 0; k < 3; k++) {
        CHECK(pr[k].elongation > 0.99);
        CHECK(pr[k].circularity > 0.99);
    }
    /* the ellipsoid (1, 0.5, 0.3) */
    s.elongation = 0.5;
    s.flatness = 0.6;
    CHECK(gp_grain3d_radii(b, &s, r, NULL) == GP_OK);
    CHECK(gp_grain3d_describe(b, r, &ds, NULL) == GP_OK);
    double t0 = now();
    CHECK(gp_grain3d_describe_projections(b, r, &ds.axes, NULL, pr, NULL) == GP_OK);
    double dt = now() - t0;
    printf("    ellipsoid (1, 0.5, 0.3): projections' elongation %.4f (0.6), %.4f (0.3), %.4f (0.5) in %.2f ms\n",
           pr[0].elongation, pr[1].elongation, pr[2].elongation, 1e3 * dt);
    CHECK_REL(pr[0].elongation, 0.6, 0.01);
    CHECK_REL(pr[1].elongation, 0.3, 0.01);
    CHECK_REL(pr[2].elongation, 0.5, 0.01);
    /* the outline along the short axis is the ellipse x^2 + 4 y^2 = 1 within the mesh's sagitta,
     * never outside kappa times it (the vertices' own ellipse) */
    gp_vec2 c[256];
    double eu[3] = {1, 0, 0}, ev[3] = {0, 1, 0}, worst = 0;
    CHECK(gp_grain3d_projection(b, r, eu, ev, 256, c, NULL) == GP_OK);
    for (int j = 0; j < 256; j++) {
        double th = 2 * PI * j / 256, re = 1 / sqrt(cos(th) * cos(th) + 4 * sin(th) * sin(th));
        double rr = hypot(c[j].x, c[j].y);
        CHECK(rr <= re * gp_grain3d_basis_kappa(b) * (1 + 1e-12));
        worst = fmax(worst, fabs(re - rr) / re);
        CHECK_NEAR(atan2(c[j].y, c[j].x), atan2(sin(th), cos(th)), 1e-12);
    }
    printf("    its outline along z: within %.1e of the ellipse\n", worst);
    CHECK(worst < 1.2e-2); /* the mesh's vertices near the sharp x ends lie off the equator */
    free(r);
}

/* (f) what a great circle sees of a degree-2 field */
static void test_section(void)
{
    double sum = 0;
    for (unsigned n = 1; n <= 30; n++) {
        double t = 0;
        for (unsigned k = 0; k <= n; k++) t += gp_grain3d_section_weight(n, k);
        sum = fmax(sum, fabs(t - 1));
    }
    CHECK(sum < 1e-12);
    CHECK_NEAR(gp_grain3d_section_weight(2, 2), 0.75, 1e-15);
    CHECK_NEAR(gp_grain3d_section_weight(2, 0), 0.25, 1e-15);
    CHECK(gp_grain3d_section_weight(2, 1) == 0);
    double D[3] = {1, 0, 0.1};
    gp_grain3d_law law = {D, NULL, 3, 2, 1, 1};
    gp_fourier *f = gp_fourier_create(128, NULL);
    double r[128], Ds[8], r0, m2 = 0, m1 = 0, m3 = 0, m0 = 0;
    int G = 4000;
    for (int g = 0; g < G; g++) {
        stream st = stream_of(20000 + g);
        gp_grain3d_shape s;
        gp_grain3d_draw(&law, u01, &st, &s, NULL);
        for (int i = 0; i < 128; i++) {
            double u[3] = {cos(2 * PI * i / 128), sin(2 * PI * i / 128), 0};
            r[i] = gp_grain3d_field(&s, u);
        }
        CHECK(gp_fourier_analyse(f, r, 8, &r0, Ds, NULL, NULL) == GP_OK);
        m2 += Ds[2] * Ds[2] * r0 * r0 / G; /* the mode's amplitude over the grain's r0 = 1 */
        m1 += Ds[1] * Ds[1] / G;
        m3 += Ds[3] * Ds[3] / G;
        m0 += (r0 - 1) * (r0 - 1) / G;
    }
    double frac2 = m2 / (D[2] * D[2]), frac0 = m0 / (D[2] * D[2] / 2);
    printf("(f) great circles of 4,000 degree-2 fields (D2 = 0.1): mode 2 has %.4f of the power (3/4), mode 0 %.4f (1/4), modes 1 and 3 %.1e\n",
           frac2, frac0, m1 + m3);
    CHECK(fabs(frac2 - 0.75) < 0.03);
    CHECK(fabs(frac0 - 0.25) < 0.03);
    CHECK(m1 + m3 < 1e-25);
    gp_fourier_destroy(f);
}

static void test_bad(const gp_grain3d_basis *b)
{
    gp_error err;
    double D[4] = {1, 0, 0.1, 0.05};
    gp_grain3d_shape s;
    gp_grain3d_law law = {D, NULL, 4, 15, 1, 1};
    stream st = stream_of(1);
    CHECK(gp_grain3d_draw(&law, bad_u01, &st, &s, &err) == GP_ERR_INVALID);
    law.elongation = 1.2;
    CHECK(gp_grain3d_draw(&law, u01, &st, &s, &err) == GP_ERR_INVALID);
    law.elongation = 1;
    law.degree = 31;
    CHECK(gp_grain3d_draw(&law, u01, &st, &s, &err) == GP_ERR_INVALID);
    law.degree = 15;
    D[0] = 0.9;
    CHECK(gp_grain3d_draw(&law, u01, &st, &s, &err) == GP_ERR_INVALID);
    D[0] = 1;
    D[2] = -0.1;
    CHECK(gp_grain3d_draw(&law, u01, &st, &s, &err) == GP_ERR_INVALID);
    D[2] = 0.1;
    CHECK(gp_grain3d_draw(&law, u01, &st, &s, &err) == GP_OK && s.degree == 3);
    CHECK(gp_grain3d_basis_create(4, 31, &err) == NULL && err.code == GP_ERR_INVALID);
    CHECK(gp_grain3d_basis_create(GP_MESH3D_ICOSPHERE_LEVEL_MAX + 1, 4, &err) == NULL);
    CHECK(gp_grain3d_basis_create(8, 30, &err) == NULL && err.code == GP_ERR_INVALID); /* 5 GB table */
    gp_grain3d_basis *small = gp_grain3d_basis_create(2, 2, &err);
    size_t nv = gp_grain3d_basis_count(b);
    double *r = malloc(nv * sizeof(double));
    CHECK(gp_grain3d_radii(small, &s, r, &err) == GP_ERR_INVALID); /* degree 3 > 2 */
    s.c[5] = NAN;
    CHECK(gp_grain3d_radii(b, &s, r, &err) == GP_ERR_INVALID);
    s.c[5] = 0;
    s.flatness = 0;
    CHECK(gp_grain3d_radii(b, &s, r, &err) == GP_ERR_INVALID);
    s.flatness = 1;
    CHECK(gp_grain3d_radii(b, &s, r, &err) == GP_OK);
    r[7] = -1;
    gp_grain3d_descriptors ds;
    CHECK(gp_grain3d_describe(b, r, &ds, &err) == GP_ERR_INVALID);
    gp_vec2 c[16];
    double eu[3] = {1, 0, 0}, ev[3] = {1, 0, 0};
    r[7] = 1;
    CHECK(gp_grain3d_projection(b, r, eu, ev, 16, c, &err) == GP_ERR_INVALID); /* not orthogonal */
    gp_grain3d_basis_destroy(small);
    free(r);
}

int main(void)
{
    gp_error err;
    double t0 = now();
    gp_grain3d_basis *b = gp_grain3d_basis_create(4, 15, &err);
    printf("basis level 4, degree 15: %.1f ms\n", 1e3 * (now() - t0));
    CHECK(b != NULL);
    if (!b) return gp_test_summary();
    CHECK(gp_grain3d_basis_count(b) == 2562 && gp_grain3d_basis_degree(b) == 15 && gp_grain3d_basis_level(b) == 4);
    test_harmonics(b);
    test_spectrum(b);
    test_stretch(b);
    test_star(b);
    test_determinism(b);
    test_projections(b);
    test_section();
    test_mesh_volume();
    test_bad(b);
    gp_grain3d_basis_destroy(b);
    return gp_test_summary();
}
