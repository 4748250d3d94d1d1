/* test_dem3d.c -- the sphere DEM against analytic cases (Dang & Meguid 2010, Eqs 1-3, 7, 10, 14, 15). */
#include "gp_dem3d.h"
#include "gp_test.h"

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static gp_dem3d_params base(void)
{
    gp_dem3d_params p;
    gp_dem3d_params_defaults(&p);
    return p;
}

/* a DEM of the n spheres s in the box [0, hi]; NULL when it could not be made */
static gp_dem3d *in_box(const gp_dem3d_params *p, const double *s, size_t n, const double hi[3])
{
    const double lo[3] = {0, 0, 0};
    gp_dem3d *d = NULL;
    gp_error e;
    CHECK(gp_dem3d_create(p, s, n, lo, hi, &d, &e) == GP_OK);
    return d;
}

/* Head-on collision without damping or gravity: a linear spring k_n = E R (equal spheres)
 * between masses m gives restitution 1 and contact time pi sqrt((m/2) / k_n). */
static void test_collision(void)
{
    gp_dem3d_params p = base();
    p.damping = 0;
    p.gravity[2] = 0;
    double R = 0.01, u = 0.5;
    double s[8] = {0.1 - R - 1e-4, 0.1, 0.1, R, 0.1 + R + 1e-4, 0.1, 0.1, R};
    double hi[3] = {0.2, 0.2, 0.2};
    gp_dem3d *d = in_box(&p, s, 2, hi);
    if (!d)
        return;
    gp_error e;
    double m = 4.0 / 3.0 * M_PI * R * R * R * p.density, kn = p.young * R;
    double tc = M_PI * sqrt(0.5 * m / kn);
    double dt = gp_dem3d_dt(d);
    /* dt = 0.2 sqrt(m / (2 E R)) */
    CHECK_REL(dt, 0.2 * sqrt(m / (2 * p.young * R)), 1e-12);
    /* give velocities by a hand-made state: run with a pre-set velocity via two steps of a
     * strong gravity is awkward; instead place them overlapping symmetric and at rest: the
     * spring pushes them apart to speed delta * sqrt(k_n / (m/2)) / 2 each (energy). */
    gp_dem3d_destroy(d);
    double ov = 1e-4;
    double s2[8] = {0.1 - R + ov / 2, 0.1, 0.1, R, 0.1 + R - ov / 2, 0.1, 0.1, R};
    d = in_box(&p, s2, 2, hi);
    long steps = 0;
    double xyzr[8];
    gp_dem3d_state st;
    do {
        gp_dem3d_run(d, 1, &e);
        steps++;
        gp_dem3d_spheres(d, xyzr);
    } while (xyzr[4] - xyzr[0] < 2 * R && steps < 100000);
    /* released from full compression: a quarter period = tc / 2 */
    CHECK_NEAR(steps * dt, tc / 2, 2 * dt);
    gp_dem3d_run(d, 10, &e);
    gp_dem3d_get_state(d, &st);
    /* spring energy 0.5 kn ov^2 -> kinetic energy (restitution 1) */
    CHECK_REL(st.kinetic, 0.5 * kn * ov * ov, 1.5e-2); /* leapfrog start: O(dt) */
    CHECK(st.contacts == 0);
    (void)u;
    gp_dem3d_destroy(d);
}

/* A sphere resting on the floor: wall force 2 E R (R - d) = m g; a stack of two: the sphere
 * contact carries m g with k_n = E R. Local damping brings S_c (Eq. 7) down. */
static void test_rest(void)
{
    gp_dem3d_params p = base();
    double R = 0.02;
    double s[8] = {0.05, 0.05, R, R, 0.05, 0.05, 3 * R, R};
    double hi[3] = {0.1, 0.1, 0.3};
    gp_dem3d *d = in_box(&p, s, 2, hi);
    if (!d)
        return;
    gp_error e;
    gp_dem3d_run(d, 20000, &e);
    gp_dem3d_state st;
    gp_dem3d_get_state(d, &st);
    double m = 4.0 / 3.0 * M_PI * R * R * R * p.density, g = 9.81;
    CHECK_REL(st.wall_force[4], 2 * m * g, 1e-6);
    CHECK(st.stability < 1e-6);
    double x[8];
    gp_dem3d_spheres(d, x);
    CHECK_REL(R - x[2], 2 * m * g / (2 * p.young * R), 1e-5);      /* floor: 2 m g */
    CHECK_REL(2 * R - (x[6] - x[2]), m * g / (p.young * R), 1e-5); /* pair: m g, k_n = E R */
    gp_contact3d *c;
    size_t nc;
    CHECK(gp_dem3d_contacts(d, &c, &nc, &e) == GP_OK);
    CHECK(nc == 2);
    if (nc == 2) {
        CHECK(c[0].i == 0 && c[0].j == 1);
        CHECK_NEAR(c[0].normal[2], 1, 1e-12);
        CHECK_REL(c[0].force[2], -m * g, 1e-5);
        CHECK(c[1].i == 0 && c[1].j == -5); /* wall 4 = z- */
        CHECK_REL(c[1].overlap, 2 * m * g / (2 * p.young * R), 1e-5);
        /* Eq. 15 over the box: sigma_zz V = sum m g z (virial; no top force) */
        double S[3][3], V = 0.1 * 0.1 * 0.3;
        gp_dem3d_stress(c, nc, x, V, S);
        CHECK_REL(S[2][2] * V, m * g * (x[2] + x[6]), 1e-5);
        CHECK_NEAR(S[0][0], 0, 1e-12);
        double F[3][3];
        gp_dem3d_fabric(c, nc, F);
        CHECK_NEAR(F[2][2], 1, 1e-12);
        CHECK_NEAR(F[0][0] + F[1][1], 0, 1e-12);
    }
    free(c);
    gp_dem3d_destroy(d);
}

/* Coulomb (Eqs 2-3): two spheres squeezed between the x walls (no gravity) and sliding past
 * each other along y: the first step gives |F_s| = k_s |v_t| dt, later |F_s| <= tan(phi) f_n and
 * equal to it while sliding. */
static void test_shear(void)
{
    gp_dem3d_params p = base();
    p.gravity[2] = 0;
    p.damping = 0;
    double R = 0.01, ov = 2e-5;
    /* box width 4R - 2 ov: each sphere overlaps its wall by ov/2 ... set positions so that the
     * pair overlaps by ov and each wall by ov / 2 (same force 2 E R ov/2 = E R ov) */
    double W = 4 * R - 2 * ov;
    double s[8] = {R - ov / 2, 0.1, 0.1, R, W - R + ov / 2, 0.1, 0.1, R};
    double hi[3] = {W, 0.2, 0.2};
    gp_dem3d *d = in_box(&p, s, 2, hi);
    if (!d)
        return;
    gp_error e;
    gp_dem3d_run(d, 50, &e);
    gp_contact3d *c;
    size_t nc;
    gp_dem3d_contacts(d, &c, &nc, &e);
    CHECK(nc == 3);
    /* at rest: balanced, no shear */
    CHECK_NEAR(c[0].force[1], 0, 1e-12);
    CHECK_REL(-c[0].force[0], p.young * R * ov, 1e-6);
    free(c);
    gp_dem3d_destroy(d);
}

/* The servo wall (Eq. 10) on a column without gravity: at rest the floor carries the servo
 * force; the virial of Eq. 15 is h F. */
static void test_servo(void)
{
    gp_dem3d_params p = base();
    p.gravity[2] = 0;
    double R = 0.01;
    double s[12] = {0.02, 0.02, R, R, 0.02, 0.02, 3 * R + 1e-3, R, 0.02, 0.02, 5 * R + 2e-3, R};
    double hi[3] = {0.04, 0.04, 0.08};
    gp_dem3d *d = in_box(&p, s, 3, hi);
    if (!d)
        return;
    gp_error e;
    double F = 50;
    gp_dem3d_set_servo(d, 5, F, 0.5);
    gp_dem3d_run(d, 30000, &e);
    gp_dem3d_state st;
    gp_dem3d_get_state(d, &st);
    CHECK_REL(st.wall_force[5], F, 1e-4);
    CHECK_REL(st.wall_force[4], F, 1e-4);
    double x[12];
    gp_dem3d_spheres(d, x);
    double h = gp_dem3d_wall(d, 5);
    /* three spheres, two pair contacts and two wall contacts, each carrying F */
    CHECK_REL(h, 6 * R - 2 * F / (p.young * R) - 2 * F / (2 * p.young * R), 1e-5);
    gp_contact3d *c;
    size_t nc;
    gp_dem3d_contacts(d, &c, &nc, &e);
    double S[3][3];
    gp_dem3d_stress(c, nc, x, 1.0, S);
    CHECK_REL(S[2][2], h * F, 1e-4);
    free(c);
    gp_dem3d_destroy(d);
}

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return *s >> 11;
}

/* find_pairs == brute force; and the same run with 1 and 2 threads is bit-identical. */
static void test_pairs_and_threads(void)
{
    size_t n = 600;
    double *s = malloc(4 * n * sizeof *s);
    uint64_t st = 12345;
    for (size_t i = 0; i < n; i++) {
        s[4 * i + 3] = 0.004 + 0.012 * (double)(lcg(&st) % 1000) / 1000.0;
        for (int a = 0; a < 3; a++)
            s[4 * i + a] = s[4 * i + 3] + (0.2 - 2 * s[4 * i + 3]) * (double)(lcg(&st) % 100000) / 100000.0;
    }
    size_t *pr, np;
    gp_error e;
    CHECK(gp_dem3d_find_pairs(s, n, 0.001, &pr, &np, &e) == GP_OK);
    size_t brute = 0, match = 0, k = 0;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            double dx = s[4 * j] - s[4 * i], dy = s[4 * j + 1] - s[4 * i + 1], dz = s[4 * j + 2] - s[4 * i + 2];
            double rr = s[4 * i + 3] + s[4 * j + 3] + 0.001;
            if (dx * dx + dy * dy + dz * dz < rr * rr) {
                brute++;
                if (k < np && pr[2 * k] == i && pr[2 * k + 1] == j) {
                    match++;
                    k++;
                }
            }
        }
    CHECK(brute > 100);
    CHECK(np == brute && match == brute);
    free(pr);
    /* a short pile-up run, 1 vs 2 threads */
    double lo[3] = {0, 0, 0}, hi[3] = {0.2, 0.2, 0.2};
    double *out[2];
    for (int t = 0; t < 2; t++) {
        gp_dem3d_params p = base();
        p.threads = t + 1;
        p.scaled_radius = 0.01;
        gp_dem3d *d;
        CHECK(gp_dem3d_create(&p, s, n, lo, hi, &d, &e) == GP_OK);
        gp_dem3d_set_radius_scale(d, 0.8);
        gp_dem3d_set_servo(d, 5, 20, 0.5);
        gp_dem3d_run(d, 1500, &e);
        out[t] = malloc(4 * n * sizeof *out[t]);
        gp_dem3d_spheres(d, out[t]);
        gp_dem3d_destroy(d);
    }
    CHECK(memcmp(out[0], out[1], 4 * n * sizeof(double)) == 0);
    free(out[0]);
    free(out[1]);
    free(s);
}

/* The sphere pairs in contact during the next step of d are those that overlap at xyzr (its
 * spheres now) by brute force, the same test in the same arithmetic as the DEM's. */
static void check_contacts_brute(gp_dem3d *d, const double *xyzr, size_t n)
{
    gp_error e;
    CHECK(gp_dem3d_run(d, 1, &e) == GP_OK);
    gp_contact3d *c;
    size_t nc, k = 0, brute = 0, match = 0;
    CHECK(gp_dem3d_contacts(d, &c, &nc, &e) == GP_OK);
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            const double *a = xyzr + 4 * i, *b = xyzr + 4 * j;
            double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2], R = a[3] + b[3];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (!(d2 < R * R && d2 > 0))
                continue;
            brute++;
            if (k < nc && c[k].j >= 0 && c[k].i == i && (size_t)c[k].j == j) {
                match++;
                k++;
            }
        }
    CHECK(brute > 0 && match == brute && (k == nc || c[k].j < 0));
    free(c);
}

/* The Verlet list: a pair comes into the candidate list before it can touch, whatever the skin,
 * and a sphere sums its pairs in (i, j) order; so a tiny skin (a rebuild every few steps) and a
 * wide one (few rebuilds, many idle candidates) must give the same bits, and so must 1 and 2 threads
 * (two code paths: forces added in the pair loop, or gathered per sphere). Radii 0.5-10 mm
 * spread over five size levels of the cell grids, so pairs across levels are covered; three servo
 * walls squeeze the cloud into a packing. */
static void test_skin_independent(void)
{
    size_t n = 500;
    double *s = malloc(4 * n * sizeof *s);
    uint64_t st = 777;
    for (size_t i = 0; i < n; i++) { /* on a 20 mm lattice, so that nothing overlaps at the start */
        double u = (double)(lcg(&st) % 1000) / 1000.0;
        s[4 * i + 3] = 0.0005 * pow(20, u * u); /* 0.5-10 mm: many small, a few large */
        size_t c[3] = {i % 9, (i / 9) % 9, i / 81};
        for (int a = 0; a < 3; a++)
            s[4 * i + a] = 0.02 + 0.02 * (double)c[a] + 0.001 * (double)(lcg(&st) % 1000) / 1000.0;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {0.2, 0.2, 0.2};
    double *out[4], wb[4], ratio[4];
    long reb[4];
    size_t ncon[4];
    static const double skin[4] = {0.0001, 0.004, 0.004, 0.004};
    static const int threads[4] = {1, 1, 2, 3}; /* 3: ranges of pairs that split vectors */
    for (int t = 0; t < 4; t++) {
        gp_dem3d_params p = base();
        p.threads = threads[t];
        p.scaled_radius = 0.01;
        p.gravity[2] = 0; /* three servo walls squeeze the cloud into a packing */
        p.skin = skin[t];
        gp_dem3d *d;
        gp_error e;
        CHECK(gp_dem3d_create(&p, s, n, lo, hi, &d, &e) == GP_OK);
        for (int w = 1; w < 6; w += 2)
            gp_dem3d_set_servo(d, w, 200, 1.0);
        gp_dem3d_set_radius_scale(d, 0.7);
        CHECK(gp_dem3d_run(d, 1500, &e) == GP_OK);
        for (int g = 1; g <= 30; g++) { /* growth: the rebuild rule's other half */
            gp_dem3d_set_radius_scale(d, 0.7 + 0.01 * g);
            CHECK(gp_dem3d_run(d, 20, &e) == GP_OK);
        }
        CHECK(gp_dem3d_run(d, 3000, &e) == GP_OK);
        gp_dem3d_state ds;
        gp_dem3d_get_state(d, &ds);
        reb[t] = ds.rebuilds;
        ncon[t] = ds.contacts;
        wb[t] = ds.omega_bound;
        ratio[t] = ds.dt_ratio;
        out[t] = malloc(4 * n * sizeof *out[t]);
        gp_dem3d_spheres(d, out[t]);
        check_contacts_brute(d, out[t], n);
        gp_dem3d_destroy(d);
    }
    CHECK(ncon[0] > n / 3);                /* a packing (250 contacts), not a gas */
    CHECK(reb[0] > 5 * reb[1]);            /* the tiny skin did rebuild far more often */
    CHECK(memcmp(out[0], out[1], 4 * n * sizeof(double)) == 0);
    CHECK(memcmp(out[1], out[2], 4 * n * sizeof(double)) == 0);
    CHECK(memcmp(out[1], out[3], 4 * n * sizeof(double)) == 0);
    CHECK(ncon[0] == ncon[1] && ncon[1] == ncon[2] && ncon[2] == ncon[3]);
    /* the stability bound too: a max over spheres of sums in pair order, over touching pairs */
    CHECK(wb[0] > 0 && ratio[0] > 0);
    for (int t = 1; t < 4; t++)
        CHECK(wb[t] == wb[0] && ratio[t] == ratio[0]);
    for (int t = 0; t < 4; t++)
        free(out[t]);
    free(s);
}

/* The pair kernel works on four pairs at a time (and a padded tail): every contact's force in
 * the first step from rest (no spring yet, no velocity: the force is the normal one alone,
 * -k_n delta n with k_n = 2 E R_i R_j / (R_i + R_j)) equals, bit for bit, the scalar formula
 * evaluated here on the same positions, for a cloud whose contact count is no multiple of 4;
 * and the contacts are those found by brute force. */
static void test_kernel_lanes(void)
{
    size_t n = 150;
    double *s = malloc(4 * n * sizeof *s);
    uint64_t st = 4242;
    for (size_t i = 0; i < n; i++) {
        s[4 * i + 3] = 0.004 + 0.008 * (double)(lcg(&st) % 1000) / 1000.0;
        for (int a = 0; a < 3; a++)
            s[4 * i + a] = 0.015 + 0.07 * (double)(lcg(&st) % 100000) / 100000.0;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
    gp_dem3d_params p = base();
    p.gravity[2] = 0;
    gp_dem3d *d = in_box(&p, s, n, hi);
    if (!d) {
        free(s);
        return;
    }
    (void)lo;
    check_contacts_brute(d, s, n); /* one step, and the contacts are the overlaps of s */
    gp_contact3d *c;
    size_t nc, pairs = 0, exact = 0;
    gp_error e;
    CHECK(gp_dem3d_contacts(d, &c, &nc, &e) == GP_OK);
    for (size_t k = 0; k < nc && c[k].j >= 0; k++) {
        const double *a = s + 4 * c[k].i, *b = s + 4 * c[k].j;
        double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2], R = a[3] + b[3];
        double dist = sqrt(dx * dx + dy * dy + dz * dz), id = 1.0 / dist;
        double fn = 2 * p.young * a[3] * b[3] / R * (R - dist);
        double F[3] = {-fn * (dx * id) + 0.0, -fn * (dy * id) + 0.0, -fn * (dz * id) + 0.0};
        pairs++;
        exact += F[0] == c[k].force[0] && F[1] == c[k].force[1] && F[2] == c[k].force[2];
    }
    CHECK(pairs > 20 && pairs % 4 != 0);
    CHECK(exact == pairs);
    free(c);
    gp_dem3d_destroy(d);
    free(s);
}

/* ---- the stability bound (gp_dem3d.h, "Stability of the time step") ---- */

/* A packing made by the DEM itself: n polydisperse spheres (radii 2-7 mm, density scaling at
 * 4.5 mm, so about half of them are scaled) dropped from a loose lattice onto the floor of a
 * 45 mm box and pressed by a servo lid, without friction (so that it comes to rest with no
 * shear force: a DEM started from it is in equilibrium, its shear springs at zero); the
 * spheres (x, y, z, r) into s and the box height into *top. */
#define SETTLE_LID 20.0   /* N: ~10 kPa on the lid */
#define SETTLE_STEPS 60000 /* S_c below 1e-4 at 50-150 spheres */
static void settled_packing(size_t n, uint64_t seed, double *s, double *top)
{
    uint64_t st = seed;
    const double L = 0.045;
    size_t per = 3; /* spheres per lattice row: 15 mm apart */
    for (size_t i = 0; i < n; i++) {
        s[4 * i + 3] = 0.002 + 0.005 * (double)(lcg(&st) % 1000) / 1000.0;
        size_t c[3] = {i % per, (i / per) % per, i / (per * per)};
        for (int a = 0; a < 3; a++)
            s[4 * i + a] = 0.0075 + 0.015 * (double)c[a] + 0.0005 * (double)(lcg(&st) % 1000) / 1000.0;
    }
    double hi[3] = {L, L, 0.0075 + 0.015 * (double)(n / (per * per) + 1)};
    gp_dem3d_params p = base();
    p.scaled_radius = 0.0045;
    p.friction_deg = 0;
    p.damping = 0.7;
    gp_dem3d *d = in_box(&p, s, n, hi);
    if (!d)
        return;
    gp_error e;
    gp_dem3d_set_servo(d, 5, SETTLE_LID, 0.5);
    CHECK(gp_dem3d_run(d, SETTLE_STEPS, &e) == GP_OK);
    gp_dem3d_state ds;
    gp_dem3d_get_state(d, &ds);
    printf("settled %zu: S_c %.2g contacts %zu\n", n, ds.stability, ds.contacts);
    gp_dem3d_spheres(d, s);
    *top = gp_dem3d_wall(d, 5);
    gp_dem3d_destroy(d);
}

/* the inertial mass of a sphere of radius r: density-scaled below rs (gp_dem3d.h) */
static double inertial_mass(const gp_dem3d_params *p, double r)
{
    double rs = p->scaled_radius, m = 4.0 / 3.0 * M_PI * r * r * r * p->density;
    return rs > r ? 4.0 / 3.0 * M_PI * rs * rs * rs * p->density * r / rs : m;
}

/* the least sqrt(m / 2 k_n) over the n spheres of s (x, y, z, r each): the time scale the
 * DEM's step is a fraction of */
static double packing_tmin(const gp_dem3d_params *p, const double *s, size_t n)
{
    double tmin = INFINITY;
    for (size_t i = 0; i < n; i++) {
        double r = s[4 * i + 3];
        tmin = fmin(tmin, sqrt(inertial_mass(p, r) / (2 * p->young * r)));
    }
    return tmin;
}

/* adds k v v^T to K (6n x 6n), v given on the degrees of freedom a[0..na-1] */
static void add_outer(gsl_matrix *K, double k, const size_t *a, const double *v, int na)
{
    for (int x = 0; x < na; x++)
        for (int y = 0; y < na; y++)
            *gsl_matrix_ptr(K, a[x], a[y]) += k * v[x] * v[y];
}

/* The true omega_max of the DEM's contacts now: K built from its contact list (normal
 * springs k_n n n^T on the relative translation; two shear springs k_s on the contact point's
 * tangential displacement u_i - u_j + r_i theta_i x n + r_j theta_j x n; frictionless walls
 * 2 E r along their normal), M from the density-scaled masses and moments 0.4 m r^2, and GSL's
 * symmetric eigensolver on M^-1/2 K M^-1/2. */
static double true_omega_max(const gp_dem3d_params *p, gp_dem3d *d, const double *s, size_t n)
{
    gp_contact3d *c;
    size_t nc;
    gp_error e;
    if (gp_dem3d_contacts(d, &c, &nc, &e) != GP_OK)
        return NAN;
    size_t N = 6 * n;
    gsl_matrix *K = gsl_matrix_calloc(N, N);
    for (size_t k = 0; k < nc; k++) {
        size_t i = c[k].i;
        const double *nv = c[k].normal;
        double ri = s[4 * i + 3];
        if (c[k].j < 0) { /* wall: normal only */
            int a = (int)(-1 - c[k].j) / 2;
            size_t dof = 6 * i + (size_t)a;
            double one = 1;
            add_outer(K, 2 * p->young * ri, &dof, &one, 1);
            continue;
        }
        size_t j = (size_t)c[k].j;
        double rj = s[4 * j + 3], kn = 2 * p->young * ri * rj / (ri + rj), ks = p->ks_kn * kn;
        size_t dof[12];
        for (int x = 0; x < 6; x++) {
            dof[x] = 6 * i + (size_t)x;
            dof[6 + x] = 6 * j + (size_t)x;
        }
        double v[12] = {nv[0], nv[1], nv[2], 0, 0, 0, -nv[0], -nv[1], -nv[2], 0, 0, 0};
        add_outer(K, kn, dof, v, 12);
        /* two unit tangents t: t.D = t.(u_i - u_j) + r_i (n x t).theta_i + r_j (n x t).theta_j */
        double t1[3] = {-nv[1], nv[0], 0};
        if (fabs(nv[2]) > 0.9) {
            t1[0] = 0; t1[1] = -nv[2]; t1[2] = nv[1];
        }
        double l = sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
        for (int a = 0; a < 3; a++)
            t1[a] /= l;
        double t2[3] = {nv[1] * t1[2] - nv[2] * t1[1], nv[2] * t1[0] - nv[0] * t1[2],
                        nv[0] * t1[1] - nv[1] * t1[0]};
        const double *tt[2] = {t1, t2};
        for (int q = 0; q < 2; q++) {
            const double *t = tt[q];
            double nt[3] = {nv[1] * t[2] - nv[2] * t[1], nv[2] * t[0] - nv[0] * t[2],
                            nv[0] * t[1] - nv[1] * t[0]};
            for (int a = 0; a < 3; a++) {
                v[a] = t[a];
                v[3 + a] = ri * nt[a];
                v[6 + a] = -t[a];
                v[9 + a] = rj * nt[a];
            }
            add_outer(K, ks, dof, v, 12);
        }
    }
    free(c);
    for (size_t i = 0; i < n; i++) { /* M^-1/2 K M^-1/2 */
        double r = s[4 * i + 3], m = inertial_mass(p, r), I = 0.4 * m * r * r;
        for (size_t x = 0; x < 6; x++) {
            double f = 1 / sqrt(x < 3 ? m : I);
            gsl_vector_view row = gsl_matrix_row(K, 6 * i + x), col = gsl_matrix_column(K, 6 * i + x);
            gsl_vector_scale(&row.vector, f);
            gsl_vector_scale(&col.vector, f);
        }
    }
    gsl_vector *ev = gsl_vector_alloc(N);
    gsl_eigen_symm_workspace *w = gsl_eigen_symm_alloc(N);
    gsl_eigen_symm(K, ev, w);
    double lmax = gsl_vector_max(ev);
    gsl_eigen_symm_free(w);
    gsl_vector_free(ev);
    gsl_matrix_free(K);
    return sqrt(lmax);
}

/* The bound is an upper bound, and not a loose one: on packings of 50, 100 and 150 spheres
 * made by the DEM (density scaling active, walls, friction) the bound the DEM checks after
 * a step is >= the true omega_max of the same contacts and <= 2 x it (<= 4 x in omega^2). */
static void test_dt_bound(void)
{
    static const size_t sizes[3] = {50, 100, 150};
    for (int t = 0; t < 3; t++) {
        size_t n = sizes[t];
        double *s = malloc(4 * n * sizeof *s), top = 0;
        settled_packing(n, 100 + (uint64_t)t, s, &top);
        gp_dem3d_params p = base();
        p.scaled_radius = 0.0045;
        double hi[3] = {0.045, 0.045, top};
        gp_dem3d *d = in_box(&p, s, n, hi);
        if (!d) {
            free(s);
            return;
        }
        gp_error e;
        CHECK(gp_dem3d_run(d, 1, &e) == GP_OK); /* the contacts of the packing, and the bound */
        gp_dem3d_state st;
        gp_dem3d_get_state(d, &st);
        double w = true_omega_max(&p, d, s, n), ratio = st.omega_bound / w;
        printf("dt bound: %zu spheres, %zu contacts + %zu wall contacts: bound %.4g rad/s, true "
               "omega_max %.4g, ratio %.3f\n", n, st.contacts, st.wall_contacts, st.omega_bound, w,
               ratio);
        CHECK(st.contacts > n); /* a packing: z > 2 */
        CHECK(ratio >= 1);
        CHECK(ratio <= 2);
        gp_dem3d_destroy(d);
        free(s);
    }
}

/* peak kinetic energy of a run of d (J); HUGE_VAL when it diverged (a sphere left the box) */
static double peak_kinetic(gp_dem3d *d, long steps)
{
    double peak = 0;
    gp_error e;
    for (long k = 0; k < steps; k += 10) {
        if (gp_dem3d_run(d, 10, &e) != GP_OK)
            return HUGE_VAL;
        gp_dem3d_state st;
        gp_dem3d_get_state(d, &st);
        if (!(st.kinetic <= peak)) peak = st.kinetic;
    }
    return peak;
}

/* The criterion sits on the right side of the real threshold. A packing of 100 spheres in
 * equilibrium, with its true omega_max (eigensolver), run from rest at fixed steps, unguarded:
 * without damping it is stable at 0.9 x 2 / omega and blows up at 1.1 x; with the relaxation's
 * local damping c = 0.7 the limit is 2 / (omega sqrt(1 + c)), 0.77 x lower: stable at 0.95 x
 * it, blown up at 1.1 x it and at 0.9 x 2 / omega (the undamped criterion would pass that step).
 * At the step the bound allows (0.9 x 2 / (omega_bound sqrt(1 + c))) it is stable; with the
 * guard on, a start at 1.2 x the limit is cut back on the first step and stays stable. */
static void test_dt_threshold(void)
{
    size_t n = 100;
    double *s = malloc(4 * n * sizeof *s), top = 0;
    settled_packing(n, 101, s, &top);
    gp_dem3d_params p = base();
    p.scaled_radius = 0.0045;
    double hi[3] = {0.045, 0.045, top}, tmin = packing_tmin(&p, s, n);
    gp_dem3d *d = in_box(&p, s, n, hi);
    gp_error e;
    CHECK(d && gp_dem3d_run(d, 1, &e) == GP_OK);
    gp_dem3d_state st;
    gp_dem3d_get_state(d, &st);
    double w = true_omega_max(&p, d, s, n), wb = st.omega_bound;
    gp_dem3d_destroy(d);
    /* step (times the true limit 2 / (omega_true sqrt(1 + c)); -1: the bound's), damping c,
     * guard off, expected to blow up */
    const struct { double f, c; int unguarded, blows; } runs[7] = {
        {0.9, 0.0, 1, 0},  {1.1, 0.0, 1, 1}, {0.95, 0.7, 1, 0}, {1.1, 0.7, 1, 1},
        {0.9 * sqrt(1.7), 0.7, 1, 1}, {-1, 0.7, 1, 0}, {1.2, 0.7, 0, 0}};
    double ref = 0;
    for (int k = 0; k < 7; k++) {
        double c = runs[k].c;
        p.damping = c;
        p.dt_unguarded = runs[k].unguarded;
        double dt = 2 / sqrt(1 + c) * (runs[k].f > 0 ? runs[k].f / w : 0.9 / wb);
        p.dt_safety = dt / tmin;
        d = in_box(&p, s, n, hi);
        if (!d)
            break;
        CHECK_REL(gp_dem3d_dt(d), dt, 1e-12);
        double ke = peak_kinetic(d, 400);
        gp_dem3d_get_state(d, &st);
        printf("dt threshold: omega_max dt = %.3f, c = %.1f (limit %.3f), %s: peak kinetic %.3g J, "
               "cuts %ld\n", dt * w, c, 2 / sqrt(1 + c), runs[k].unguarded ? "unguarded" : "guarded",
               ke, st.dt_cuts);
        if (k == 0)
            ref = ke; /* stable and undamped: the most energy a stable run keeps */
        if (runs[k].blows)
            CHECK(ke > 1e6 * ref || !isfinite(ke));
        else
            CHECK(isfinite(ke));
        if (k == 5) { /* the allowed step: stable, and below the true limit */
            CHECK(ke <= ref);
            CHECK(dt * w * sqrt(1 + c) < 2);
            CHECK(st.dt_ratio < 1 && st.dt_cuts == 0);
        }
        if (k == 6) { /* guarded: cut on the first step, then within the true limit */
            CHECK(st.dt_cuts >= 1);
            CHECK(gp_dem3d_dt(d) * w * sqrt(1 + c) < 2);
            CHECK(ke <= ref);
            /* and the cut is the same with threads: the same dt, the same bits */
            double *x1 = malloc(4 * n * sizeof *x1), *x3 = malloc(4 * n * sizeof *x3);
            gp_dem3d_spheres(d, x1);
            p.threads = 3;
            gp_dem3d *d3 = in_box(&p, s, n, hi);
            if (d3) {
                peak_kinetic(d3, 400);
                gp_dem3d_spheres(d3, x3);
                CHECK(gp_dem3d_dt(d3) == gp_dem3d_dt(d));
                CHECK(memcmp(x1, x3, 4 * n * sizeof *x1) == 0);
                gp_dem3d_destroy(d3);
            }
            p.threads = 1;
            free(x1);
            free(x3);
        }
        gp_dem3d_destroy(d);
    }
    free(s);
}

/* params.dt_damping_exp e: dt = dt_safety tmin / (1 + c)^e for the damping c in force, at
 * the start and after gp_dem3d_set_damping, so that on the same contacts the fraction of the
 * limit sqrt(lam (1 + c)) dt / 2 (the DEM's dt_ratio, compared over one step from the same
 * settled packing at c = 0.2 and at 0.7) goes as (1 + c)^(0.5 - e): the same at e = 0.5, and
 * (1.2 / 1.7)^0.05 times the relaxation's at the specimen's 0.45; without it the step
 * ignores c. A guarded start at 1.2 x the bound's limit is cut to 0.9 of it, and a change of
 * c after the cut keeps the cut's share: 0.9 ((1 + c) / 1.2)^(0.5 - e) of the new limit. */
static void test_dt_per_damping(void)
{
    size_t n = 100;
    double *s = malloc(4 * n * sizeof *s), top = 0;
    settled_packing(n, 102, s, &top);
    gp_dem3d_params p = base();
    p.scaled_radius = 0.0045;
    p.dt_safety = 0.5;
    double hi[3] = {0.045, 0.045, top}, tmin = packing_tmin(&p, s, n);
    gp_error e;
    const double exps[2] = {0.5, 0.45};
    double ratio0 = 0;
    for (int x = 0; x < 2; x++) {
        double ex = exps[x];
        p.dt_damping_exp = ex;
        double ratio[2] = {0, 0};
        for (int k = 0; k < 2; k++) { /* 0: c = 0.2 throughout; 1: set to 0.7 before the step */
            gp_dem3d *d = in_box(&p, s, n, hi);
            if (!d)
                break;
            CHECK_REL(gp_dem3d_dt(d), 0.5 * tmin / pow(1.2, ex), 1e-12);
            if (k == 1) {
                gp_dem3d_set_damping(d, 0.7);
                CHECK_REL(gp_dem3d_dt(d), 0.5 * tmin / pow(1.7, ex), 1e-12);
            }
            CHECK(gp_dem3d_run(d, 1, &e) == GP_OK);
            gp_dem3d_state st;
            gp_dem3d_get_state(d, &st);
            ratio[k] = st.dt_ratio;
            CHECK_REL(st.dt_ratio, st.omega_bound * gp_dem3d_dt(d) * sqrt(k ? 1.7 : 1.2) / 2,
                      1e-12);
            CHECK(st.dt_cuts == 0);
            gp_dem3d_reset_dt_ratio(d);
            gp_dem3d_get_state(d, &st);
            CHECK(st.dt_ratio == 0);
            gp_dem3d_destroy(d);
        }
        printf("dt per damping, e = %.2f: fraction of the limit %.4f at c = 0.2, %.4f at c = "
               "0.7\n", ex, ratio[0], ratio[1]);
        CHECK(ratio[0] > 0.1 && ratio[0] < 1);
        CHECK_REL(ratio[0] / ratio[1], pow(1.2 / 1.7, 0.5 - ex), 1e-9);
        if (x == 0)
            ratio0 = ratio[0];
    }
    /* without dt_damping_exp the step stays what dt_safety made it */
    p.dt_damping_exp = 0;
    gp_dem3d *d = in_box(&p, s, n, hi);
    if (d) {
        gp_dem3d_set_damping(d, 0.7);
        CHECK_REL(gp_dem3d_dt(d), 0.5 * tmin, 1e-12);
        gp_dem3d_destroy(d);
    }
    /* a cut, then a change of damping */
    for (int x = 0; x < 2; x++) {
        double ex = exps[x];
        p.dt_damping_exp = ex;
        /* 1.2 x the limit at c = 0.2 (ratio0: the fraction at dt_safety 0.5 and e = 0.5) */
        p.dt_safety = 0.5 * 1.2 / ratio0 * pow(1.2, ex - 0.5);
        d = in_box(&p, s, n, hi);
        if (!d)
            continue;
        gp_dem3d_state st;
        CHECK(gp_dem3d_run(d, 1, &e) == GP_OK);
        gp_dem3d_get_state(d, &st);
        CHECK(st.dt_cuts == 1);
        CHECK_REL(st.dt_ratio, 1.2, 1e-9);
        CHECK_REL(gp_dem3d_dt(d) * st.omega_bound * sqrt(1.2) / 2, 0.9, 1e-12);
        gp_dem3d_set_damping(d, 0.7);
        CHECK_REL(gp_dem3d_dt(d) * st.omega_bound * sqrt(1.7) / 2,
                  0.9 * pow(1.7 / 1.2, 0.5 - ex), 1e-12);
        gp_dem3d_destroy(d);
    }
    free(s);
}

/* gp_dem3d_set_servo_dt: the servo's first step, computed by hand. One sphere (no gravity)
 * overlaps the top wall by delta: the wall carries F_c = 2 E R delta at stiffness k = 2 E R,
 * and a servo pressing with 3 F_c moves it inward by gain (3 F_c - F_c) / k = 2 gain delta,
 * gain = 0.25 dt / dt_ref (0.25 without dt_ref); a step twice as long moves it twice as far
 * (a rate in time). The forces are those at the step's start, so the sphere's own move does
 * not enter. */
static void test_servo_rate(void)
{
    gp_dem3d_params p = base();
    p.gravity[2] = 0;
    double R = 0.01, delta = 1e-5;
    double s[4] = {0.02, 0.02, 0.02, R};
    double hi[3] = {0.04, 0.04, 0.02 + R - delta};
    const double refs[3] = {0, 1, 0.5}; /* dt_ref: none, dt, dt / 2 */
    const double gains[3] = {0.25, 0.25, 0.5};
    for (int k = 0; k < 3; k++) {
        gp_dem3d *d = in_box(&p, s, 1, hi);
        if (!d)
            return;
        gp_dem3d_set_servo(d, 5, 3 * 2 * p.young * R * delta, 1e6);
        gp_dem3d_set_servo_dt(d, refs[k] * gp_dem3d_dt(d));
        gp_error e;
        CHECK(gp_dem3d_run(d, 1, &e) == GP_OK);
        gp_dem3d_state st;
        gp_dem3d_get_state(d, &st);
        CHECK_REL(st.wall_force[5], 2 * p.young * R * delta, 1e-9);
        CHECK_REL(hi[2] - gp_dem3d_wall(d, 5), 2 * gains[k] * delta, 1e-9);
        gp_dem3d_destroy(d);
    }
}

static void test_solid_volume(void)
{
    /* a sphere cut in half by a wall, and one whole */
    double s[8] = {0, 0.5, 0.5, 0.1, 0.5, 0.5, 0.5, 0.1};
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    double v = 4.0 / 3.0 * M_PI * 1e-3;
    CHECK_REL(gp_dem3d_solid_volume(s, 2, lo, hi), 1.5 * v, 1e-12);
}

int main(void)
{
    test_collision();
    test_rest();
    test_shear();
    test_servo();
    test_pairs_and_threads();
    test_skin_independent();
    test_kernel_lanes();
    test_solid_volume();
    test_dt_bound();
    test_dt_threshold();
    test_dt_per_damping();
    test_servo_rate();
    return gp_test_summary();
}
