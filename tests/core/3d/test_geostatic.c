/* test_geostatic.c -- the geostatic state of a packing (Dang & Meguid 2010, "Stress
 * Distribution", Eqs. 15-16): the measures on a hand-made column whose forces are known, the
 * same column with gravity along +x, then a small flipped specimen settled at rest: the slabs'
 * sigma_v against the weight above (computed here from the spheres), the whole packing's
 * Love-Weber stress against its walls, the same bits on 1 and 2 threads, and the states and
 * measures that must not pass (the packing as tiled, before it settles; a run stopped early; a
 * slab measure that counts the branches crossing a plane twice). */
#include "gp_flip.h"
#include "gp_geostatic.h"
#include "gp_specimen3d.h"
#include "gp_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* the volume of a sphere of radius r above the plane at d over its centre, written as the
 * integral of the discs (not as gp_geostatic's cap) */
static double above(double r, double d)
{
    if (d >= r) return 0;
    if (d < -r) d = -r;
    return M_PI * (r * r * (r - d) - (r * r * r - d * d * d) / 3.0);
}

/* the weight above height z over the area A, from the spheres */
static double weight_above(const double *x, size_t n, int v, double sg, double z, double rho,
                           double g, double A)
{
    double vol = 0;
    for (size_t i = 0; i < n; i++)
        vol += above(x[4 * i + 3], sg * (z - x[4 * i + v]));
    return rho * g * vol / A;
}

/* the ways of giving a contact to a slab: its branch split by the slab's planes, its whole
 * branch to the slab that holds its contact point, its whole branch to every slab it touches
 * (the crossing ones counted twice: wrong) */
enum { SPLIT, CONTACT_POINT, TWICE };

/* sigma_v of the slab [zb, zt) (heights along +z) over the area A from the contacts */
static double slab_sigma_zz(const double *x, const gp_contact3d *c, size_t nc, double zb,
                            double zt, double A, int how)
{
    double sum = 0;
    for (size_t k = 0; k < nc; k++) {
        const double *p = x + 4 * c[k].i;
        double lz, zc;
        if (c[k].j >= 0) {
            lz = x[4 * c[k].j + 2] - p[2];
            zc = p[2] + (p[3] - 0.5 * c[k].overlap) * c[k].normal[2];
        } else {
            lz = (p[3] - c[k].overlap) * c[k].normal[2];
            zc = p[2] + lz;
        }
        double z0 = fmin(p[2], p[2] + lz), z1 = fmax(p[2], p[2] + lz), frac;
        if (how == CONTACT_POINT)
            frac = zc >= zb && zc < zt;
        else if (lz == 0)
            frac = p[2] >= zb && p[2] < zt;
        else if (how == TWICE)
            frac = z1 > zb && z0 < zt;
        else
            frac = fmax(0, fmin(zt, z1) - fmax(zb, z0)) / fabs(lz);
        sum -= frac * lz * c[k].force[2];
    }
    return sum / (A * (zt - zb));
}

/* sigma_xx and sigma_zz of the box [lo, hi) from the contacts, each branch's share inside it
 * counted on 2000 points along the branch (the module clips exactly) */
static void box_sigma_sampled(const double *x, const gp_contact3d *c, size_t nc,
                              const double lo[3], const double hi[3], double out[2])
{
    const int m = 2000;
    out[0] = out[1] = 0;
    for (size_t k = 0; k < nc; k++) {
        const double *p = x + 4 * c[k].i;
        double l[3];
        for (int a = 0; a < 3; a++)
            l[a] = c[k].j >= 0 ? x[4 * c[k].j + a] - p[a]
                               : (p[3] - c[k].overlap) * c[k].normal[a];
        int in = 0;
        for (int t = 0; t < m; t++) {
            double u = (t + 0.5) / m;
            int ok = 1;
            for (int a = 0; a < 3 && ok; a++) {
                double y = p[a] + u * l[a];
                ok = y >= lo[a] && y < hi[a];
            }
            in += ok;
        }
        double frac = (double)in / m;
        out[0] -= frac * l[0] * c[k].force[0];
        out[1] -= frac * l[2] * c[k].force[2];
    }
    double V = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    out[0] /= V;
    out[1] /= V;
}

/* ---- a hand-made column: three spheres stacked on the bottom wall, forces from statics ---- */

#define R0 0.01
#define RHO 2600.0
#define G 9.81

/* the column along axis v (gravity along -v when sg > 0, +v when sg < 0) in the box [0, L]^2 x
 * [0, 6 R0]: spheres at heights R0, 3 R0, 5 R0 above the bottom wall; contacts: the wall under
 * sphere 0 (3 w), pairs 0-1 (2 w) and 1-2 (w) */
static void column(int v, double sg, double L, double x[12], double lo[3], double hi[3],
                   gp_contact3d c[3])
{
    double w = RHO * G * 4.0 / 3.0 * M_PI * R0 * R0 * R0;
    for (int a = 0; a < 3; a++) {
        lo[a] = 0;
        hi[a] = a == v ? 6 * R0 : L;
    }
    for (int i = 0; i < 3; i++) {
        for (int a = 0; a < 3; a++)
            x[4 * i + a] = 0.5 * L;
        double h = (2 * i + 1) * R0;
        x[4 * i + v] = sg > 0 ? h : 6 * R0 - h;
        x[4 * i + 3] = R0;
    }
    memset(c, 0, 3 * sizeof *c);
    c[0].i = 0; c[0].j = -1 - (2 * v + (sg > 0 ? 0 : 1)); /* the bottom wall */
    c[0].normal[v] = -sg; c[0].force[v] = 3 * w * sg; c[0].overlap = 0;
    c[1].i = 0; c[1].j = 1; c[1].normal[v] = sg; c[1].force[v] = -2 * w * sg;
    c[2].i = 1; c[2].j = 2; c[2].normal[v] = sg; c[2].force[v] = -w * sg;
}

/* P(h): the vertical force across the plane at height h above the bottom */
static double column_P(double h)
{
    double w = RHO * G * 4.0 / 3.0 * M_PI * R0 * R0 * R0;
    return h < R0 ? 3 * w : (h < 3 * R0 ? 2 * w : (h < 5 * R0 ? w : 0));
}

/* the integral of P over [a, b] (heights above the bottom), by its pieces */
static double column_P_integral(double a, double b)
{
    double cuts[5] = {0, R0, 3 * R0, 5 * R0, 6 * R0}, s = 0;
    for (int k = 0; k < 4; k++) {
        double u = fmax(a, cuts[k]), t = fmin(b, cuts[k + 1]);
        if (t > u) s += (t - u) * column_P(0.5 * (cuts[k] + cuts[k + 1]));
    }
    return s;
}

/* the volume of the three spheres inside the box [lo, hi], counted on a grid of points */
static double grid_volume(const double *x, size_t n, const double lo[3], const double hi[3],
                          int m)
{
    double d[3], vol = 0;
    for (int a = 0; a < 3; a++) d[a] = (hi[a] - lo[a]) / m;
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++)
            for (int k = 0; k < m; k++) {
                double p[3] = {lo[0] + (i + 0.5) * d[0], lo[1] + (j + 0.5) * d[1],
                               lo[2] + (k + 0.5) * d[2]};
                for (size_t s = 0; s < n; s++) {
                    double dx = p[0] - x[4 * s], dy = p[1] - x[4 * s + 1], dz = p[2] - x[4 * s + 2];
                    if (dx * dx + dy * dy + dz * dz < x[4 * s + 3] * x[4 * s + 3]) {
                        vol += 1;
                        break;
                    }
                }
            }
    return vol * d[0] * d[1] * d[2];
}

static void test_column(void)
{
    double L = 4 * R0, x[12], lo[3], hi[3];
    gp_contact3d c[3];
    column(2, 1, L, x, lo, hi, c);
    gp_geostatic_params p;
    gp_geostatic_params_defaults(&p);
    p.material.density = RHO;
    p.slab = 1.2 * R0;           /* 5 slabs: planes cut the branches */
    p.wall_margin_dmax = 0.375;  /* the core: the middle 2.5 R0 x 2.5 R0, cutting every sphere */
    p.map_cell = 1.2 * R0;
    gp_geostatic_result *r = NULL;
    gp_error e;
    CHECK(gp_geostatic_measure(&p, x, 3, lo, hi, c, 3, NULL, NULL, &r, &e) == GP_OK);
    if (!r)
        return;
    const gp_geostatic_profile *q = &r->profile;
    CHECK(q->n == 5);
    CHECK_NEAR(q->thickness, 1.2 * R0, 1e-15);
    CHECK_NEAR(q->margin, 0.75 * R0, 1e-15);
    double A = L * L, core = 2.5 * R0 * 2.5 * R0;
    for (size_t k = 0; k < q->n; k++) {
        double zt = 6 * R0 - k * 1.2 * R0, zb = zt - 1.2 * R0;
        double want = column_P_integral(zb, zt) / (A * 1.2 * R0);
        CHECK_REL(q->sigma_zz_full[k], want, 1e-12);
        /* the branches run through the core's middle: the core carries all of P */
        CHECK_REL(q->sigma_zz[k], want * A / core, 1e-12);
        CHECK_NEAR(q->sigma_xx_full[k], 0, 1e-12);
        double wz = weight_above(x, 3, 2, 1, 0.5 * (zt + zb), RHO, G, A);
        CHECK_REL(q->weight[k], wz, 1e-12);
        CHECK_NEAR(q->depth[k], 6 * R0 - 0.5 * (zt + zb), 1e-15);
        /* porosity of the core slab: the spheres cut by the core's four sides, counted on a
         * grid of 120^3 points */
        double clo[3] = {0.75 * R0, 0.75 * R0, zb}, chi[3] = {3.25 * R0, 3.25 * R0, zt};
        double solid = grid_volume(x, 3, clo, chi, 120);
        CHECK_NEAR(q->porosity[k], 1 - solid / (core * 1.2 * R0), 2e-3);
        /* the map, cells of the slab's height over the whole depth: each row's mean is the
         * slab's */
        const gp_geostatic_map *m = &r->map;
        double row = 0;
        for (size_t j = 0; j < m->nx; j++)
            row += m->sigma_v[k * m->nx + j];
        CHECK_REL(row / m->nx, q->sigma_zz_full[k], 1e-12);
    }
    /* the whole packing's porosity: the spheres wholly inside the box */
    gp_geostatic_params p2 = p;
    p2.wall_margin_dmax = 0;
    gp_geostatic_result *r2 = NULL;
    CHECK(gp_geostatic_measure(&p2, x, 3, lo, hi, c, 3, NULL, NULL, &r2, &e) == GP_OK);
    CHECK(r2 && fabs(r2->whole.porosity - (1 - 3 * 4.0 / 3.0 * M_PI * R0 * R0 * R0 / (A * 6 * R0)))
                    < 1e-12);
    gp_geostatic_result_destroy(r2);
    /* the whole packing: Love-Weber 9 R0 w / V, the walls' way (bottom force 3 w times the
     * centroid 3 R0, over V) the same; S_c of the list 0 */
    double w = RHO * G * 4.0 / 3.0 * M_PI * R0 * R0 * R0, V = A * 6 * R0;
    CHECK_REL(r->whole.love_weber[2][2], 9 * R0 * w / V, 1e-12);
    CHECK_REL(r->whole.walls[2], 9 * R0 * w / V, 1e-12);
    CHECK_NEAR(r->whole.max_error, 0, 1e-12);
    CHECK_NEAR(r->whole.centroid_height, 3 * R0, 1e-15);
    CHECK_REL(r->whole.weight, 3 * w, 1e-12);
    CHECK(r->stability_list < 1e-12);
    CHECK(r->whole.contacts == 2 && r->whole.wall_contacts == 1);
    CHECK(r->whole.friction_mobilised == 0 && r->whole.sliding == 0); /* normal forces only */
    CHECK_REL(r->d50, 2 * R0, 1e-15);
    /* the equilibrium: exact in the slabs away from the top (the top one is left out) */
    CHECK(!q->equilibrium_counted[0] && q->equilibrium_counted[1]);
    CHECK(r->equilibrium.slabs == 4);

    /* the same column along x with gravity along +x: the profile moves to sigma_xx, the bottom
     * is the x+ wall */
    double x2[12], lo2[3], hi2[3];
    gp_contact3d c2[3];
    column(0, -1, L, x2, lo2, hi2, c2);
    gp_geostatic_params px = p;
    px.gravity[0] = G;
    px.gravity[2] = 0;
    gp_geostatic_result *rx = NULL;
    CHECK(gp_geostatic_measure(&px, x2, 3, lo2, hi2, c2, 3, NULL, NULL, &rx, &e) == GP_OK);
    if (rx) {
        CHECK(rx->axis_v == 0 && rx->up_sign == -1);
        CHECK(rx->map.axis_h == 1 && rx->map.axis_v == 0);
        for (size_t k = 0; k < q->n; k++) {
            CHECK_REL(rx->profile.sigma_xx_full[k], q->sigma_zz_full[k], 1e-12);
            CHECK_REL(rx->profile.weight[k], q->weight[k], 1e-12);
            CHECK_NEAR(rx->profile.porosity[k], q->porosity[k], 1e-12);
        }
        CHECK_REL(rx->whole.walls[0], r->whole.walls[2], 1e-12);
        CHECK_NEAR(rx->whole.max_error, 0, 1e-12);
    }
    gp_geostatic_result_destroy(rx);
    gp_geostatic_result_destroy(r);

    /* refused: gravity off an axis, wall friction, a margin that leaves no core */
    gp_geostatic_params bad = p;
    bad.gravity[0] = 1;
    CHECK(gp_geostatic_measure(&bad, x, 3, lo, hi, c, 3, NULL, NULL, &r, &e) == GP_ERR_INVALID
          && !r);
    bad = p;
    bad.wall_friction_deg = 10;
    CHECK(gp_geostatic_run(&bad, x, 3, lo, hi, NULL, NULL, NULL, &r, &e) == GP_ERR_INVALID && !r);
    bad = p;
    bad.wall_margin_dmax = 1.0;
    CHECK(gp_geostatic_measure(&bad, x, 3, lo, hi, c, 3, NULL, NULL, &r, &e) == GP_ERR_INVALID
          && !r);
}

/* the volume check of a sphere clipped by two sides and a corner of a box, against a grid */
static void test_clipped_volume(void)
{
    double x[4] = {0.5, 0.5, 0.5, 0.3}, lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    gp_contact3d none;
    memset(&none, 0, sizeof none);
    gp_geostatic_params p;
    gp_geostatic_params_defaults(&p);
    p.slab = 0.25;
    p.wall_margin_dmax = 0.45 / 0.6; /* d_max 0.6, margin 0.45: core [0.45, 0.55]^2 */
    gp_geostatic_result *r = NULL;
    gp_error e;
    CHECK(gp_geostatic_measure(&p, x, 1, lo, hi, &none, 0, NULL, NULL, &r, &e) == GP_OK);
    if (!r)
        return;
    for (size_t k = 0; k < r->profile.n; k++) {
        double zt = 1 - 0.25 * k, zb = zt - 0.25;
        double clo[3] = {0.45, 0.45, zb}, chi[3] = {0.55, 0.55, zt};
        double solid = grid_volume(x, 1, clo, chi, 160);
        double vol = 0.1 * 0.1 * 0.25;
        CHECK_NEAR(r->profile.porosity[k], 1 - solid / vol, 3e-3);
    }
    gp_geostatic_result_destroy(r);
    /* off-centre: the core's corner inside the sphere's reach */
    double y[4] = {0.52, 0.47, 0.4, 0.3};
    p.wall_margin_dmax = 0.4 / 0.6;
    CHECK(gp_geostatic_measure(&p, y, 1, lo, hi, &none, 0, NULL, NULL, &r, &e) == GP_OK);
    if (!r)
        return;
    for (size_t k = 0; k < r->profile.n; k++) {
        double zt = 1 - 0.25 * k, zb = zt - 0.25;
        double clo[3] = {0.4, 0.4, zb}, chi[3] = {0.6, 0.6, zt};
        double solid = grid_volume(y, 1, clo, chi, 200);
        CHECK_NEAR(r->profile.porosity[k], 1 - solid / (0.2 * 0.2 * 0.25), 2e-3);
    }
    gp_geostatic_result_destroy(r);
}

/* ---- a small flipped specimen, settled ---- */

static const gp_sieve_row SIEVE[2] = {{0.008, 0}, {0.012, 100}};

static int stop_at_once(void *user, const gp_progress *pr)
{
    (void)pr;
    (*(int *)user)++;
    return 1;
}

static void test_settled(void)
{
    gp_spec3d s;
    gp_spec3d_defaults(&s);
    s.seed = 3;
    s.box[0] = 0.06;
    s.box[1] = 0.06;
    s.box[2] = 0.08;
    s.sieve = SIEVE;
    s.nsieve = 2;
    s.porosity = 0.44;
    s.tiling[0] = 2;
    s.tiling[1] = 1;
    s.tiling[2] = 2;
    s.outputs = GP_OUT3_SPHERES | GP_OUT3_CONTACTS;
    gp_specimen3d *sp = NULL;
    gp_error e;
    gp_status st = gp_specimen3d_build(&s, NULL, NULL, NULL, &sp, &e);
    CHECK(st == GP_OK);
    if (!sp) {
        fprintf(stderr, "build: %s\n", e.message);
        return;
    }
    size_t n = sp->count;
    CHECK(n > 300 && n < 1500);
    double lo[3] = {0, 0, 0}, hi[3] = {sp->box[0], sp->box[1], sp->box[2]};
    double A = hi[0] * hi[1];
    gp_geostatic_params p;
    gp_geostatic_params_defaults(&p);
    p.material = s.material;
    p.slab = 0.02;              /* 8 slabs of ~2 d50 */
    p.wall_margin_dmax = 1.0;
    p.map_cell = 0.02;
    p.keep_contacts = 1;

    /* the packing as tiled, not settled: the compaction's stress locked in at the top, the
     * odd tiles upside down under gravity; the slabs and the walls must both see it */
    gp_geostatic_result *r0 = NULL;
    CHECK(gp_geostatic_measure(&p, sp->spheres, n, lo, hi, sp->contacts, sp->ncontacts, NULL,
                               NULL, &r0, &e) == GP_OK);
    if (r0) {
        printf("as tiled: equilibrium error %.3f, walls %.3f, S_c of the list %.3g\n",
               r0->equilibrium.max_error, r0->whole.max_error, r0->stability_list);
        CHECK(r0->equilibrium.max_error > 0.2);
        CHECK(r0->whole.max_error > 0.02);
        CHECK(r0->stability_list > 1e-2);
    }
    gp_geostatic_result_destroy(r0);

    /* settled, 1 and 2 threads */
    gp_geostatic_result *r1 = NULL, *r2 = NULL;
    st = gp_geostatic_run(&p, sp->spheres, n, lo, hi, NULL, NULL, NULL, &r1, &e);
    CHECK(st == GP_OK);
    if (!r1) {
        fprintf(stderr, "run: %s\n", e.message);
        gp_specimen3d_destroy(sp);
        return;
    }
    printf("settled: %zu spheres, %ld steps (dt %.3g s, %ld cuts), S_c %.3g (list %.3g), %zu "
           "slabs, equilibrium %.4f (core %.4f), walls %.5f, K0 %.3f +- %.3f (%zu slabs, theory "
           "%.3f), %.2f s\n", n, r1->steps, r1->dt, r1->dt_cuts, r1->stability,
           r1->stability_list, r1->profile.n,
           r1->equilibrium.max_error, r1->equilibrium.core_max_error, r1->whole.max_error,
           r1->k0.mean, r1->k0.sd, r1->k0.slabs, r1->k0.theory, r1->seconds_settling);
    CHECK(r1->converged && r1->stability <= 1e-4);
    CHECK(r1->stability_list < 1e-3);
    const gp_geostatic_profile *q = &r1->profile;
    CHECK(q->n == 8);
    CHECK(r1->equilibrium.slabs == 7);
    /* the slabs away from the top: sigma_v equals the weight above over the area within 2 %
     * plus the S_c tolerance (the weight computed here from the spheres) */
    double top = hi[2], h = q->thickness, worst = 0, worst_twice = 0, worst_split = 0;
    double worst_cp = 0;
    for (size_t k = 1; k < q->n; k++) {
        double zt = top - k * h, zb = k + 1 == q->n ? 0 : top - (k + 1) * h;
        double wz = weight_above(r1->spheres, n, 2, 1, top - q->depth[k], p.material.density,
                                 -p.gravity[2], A);
        CHECK_REL(q->weight[k], wz, 1e-9);
        double err = fabs(q->sigma_zz_full[k] - wz) / wz;
        CHECK(err <= 0.02 + 1e-4);
        worst = fmax(worst, err);
        /* the test's own split of the branches gives the module's sigma_v */
        double mine = slab_sigma_zz(r1->spheres, r1->contacts, r1->ncontacts, zb, zt, A, SPLIT);
        CHECK_REL(mine, q->sigma_zz_full[k], 1e-9);
        worst_split = fmax(worst_split, fabs(mine - wz) / wz);
        double cp = slab_sigma_zz(r1->spheres, r1->contacts, r1->ncontacts, zb, zt, A,
                                  CONTACT_POINT);
        worst_cp = fmax(worst_cp, fabs(cp - wz) / wz);
        double twice = slab_sigma_zz(r1->spheres, r1->contacts, r1->ncontacts, zb, zt, A, TWICE);
        worst_twice = fmax(worst_twice, fabs(twice - wz) / wz);
    }
    printf("slabs: sigma_v against the weight above: worst %.4f (split here %.4f); branches by "
           "their contact point: worst %.4f; counted twice: worst %.3f\n", worst, worst_split,
           worst_cp, worst_twice);
    CHECK(worst_twice > 0.1); /* the 2 % check catches the double count */
    /* the core (branches clipped by the lateral planes too), against branches sampled here */
    for (size_t k = 0; k < q->n; k++) {
        double zt = top - k * h, zb = k + 1 == q->n ? 0 : top - (k + 1) * h;
        double m = q->margin;
        double clo[3] = {m, m, zb}, chi[3] = {hi[0] - m, hi[1] - m, zt}, got[2];
        box_sigma_sampled(r1->spheres, r1->contacts, r1->ncontacts, clo, chi, got);
        CHECK_REL(got[0], q->sigma_xx[k], 2e-3);
        CHECK_REL(got[1], q->sigma_zz[k], 2e-3);
    }
    /* the map's columns split the rows exactly: a row's mean is its slab's (full width) */
    CHECK(r1->map.nz == q->n && r1->map.nx == 6);
    for (size_t k = 0; k < q->n && r1->map.nz == q->n; k++) {
        double row = 0;
        for (size_t j = 0; j < r1->map.nx; j++)
            row += r1->map.sigma_v[k * r1->map.nx + j];
        CHECK_REL(row / r1->map.nx, q->sigma_zz_full[k], 1e-9);
    }
    CHECK(r1->whole.max_error <= 0.02);
    CHECK(r1->whole.friction_mobilised > 0 && r1->whole.friction_mobilised <= 1 + 1e-9);
    CHECK(r1->whole.sliding >= 0 && r1->whole.sliding < 1);
    printf("friction mobilised %.3f, sliding %.3f\n", r1->whole.friction_mobilised,
           r1->whole.sliding);
    CHECK(r1->k0.slabs >= 4);
    CHECK(r1->k0.mean > 0.2 && r1->k0.mean < 2);
    CHECK_NEAR(r1->k0.theory, 1 - sin(23.7 * M_PI / 180), 1e-15);
    for (size_t k = 0; k < q->n; k++) {
        CHECK(q->porosity[k] > 0.2 && q->porosity[k] < 0.7);
        CHECK(q->coordination[k] >= 0 && q->coordination[k] < 12);
    }
    /* the wall margin of 1 d_max: the profile says so */
    CHECK_REL(q->margin, r1->dmax, 1e-15);

    p.threads = 2;
    st = gp_geostatic_run(&p, sp->spheres, n, lo, hi, NULL, NULL, NULL, &r2, &e);
    CHECK(st == GP_OK);
    if (r2) {
        CHECK(r2->steps == r1->steps);
        CHECK(memcmp(r2->spheres, r1->spheres, 4 * n * sizeof *r1->spheres) == 0);
        CHECK(r2->ncontacts == r1->ncontacts
              && memcmp(r2->contacts, r1->contacts, r1->ncontacts * sizeof *r1->contacts) == 0);
        CHECK(memcmp(r2->profile.sigma_zz, q->sigma_zz, q->n * sizeof(double)) == 0);
        CHECK(memcmp(r2->profile.k0, q->k0, q->n * sizeof(double)) == 0);
        CHECK(memcmp(r2->map.sigma_v, r1->map.sigma_v,
                     r1->map.nx * r1->map.nz * sizeof(double)) == 0);
        CHECK(memcmp(&r2->k0, &r1->k0, sizeof r1->k0) == 0);
        CHECK(memcmp(&r2->whole, &r1->whole, sizeof r1->whole) == 0);
    }
    gp_geostatic_result_destroy(r2);
    p.threads = 1;

    /* stopped early: not at rest, and said so */
    p.max_steps = 300;
    gp_geostatic_result *r3 = NULL;
    st = gp_geostatic_run(&p, sp->spheres, n, lo, hi, NULL, NULL, NULL, &r3, &e);
    CHECK(st == GP_ERR_NOT_CONVERGED);
    CHECK(r3 && !r3->converged && r3->steps == 300 && r3->stability > 1e-4);
    CHECK(r3 && r3->equilibrium.max_error > 0.02); /* the slabs see it too */
    if (r3)
        printf("after 300 steps: S_c %.3g, equilibrium error %.3f\n", r3->stability,
               r3->equilibrium.max_error);
    gp_geostatic_result_destroy(r3);
    p.max_steps = 0;

    /* cancelled: by the flag, by the callback */
    int flag = 1, calls = 0;
    gp_geostatic_result *r4 = NULL;
    CHECK(gp_geostatic_run(&p, sp->spheres, n, lo, hi, NULL, NULL, &flag, &r4, &e)
          == GP_ERR_CANCELLED && !r4);
    CHECK(gp_geostatic_run(&p, sp->spheres, n, lo, hi, stop_at_once, &calls, NULL, &r4, &e)
          == GP_ERR_CANCELLED && !r4 && calls == 1);

    gp_geostatic_result_destroy(r1);
    gp_specimen3d_destroy(sp);
}

int main(void)
{
    test_column();
    test_clipped_volume();
    test_settled();
    return gp_test_summary();
}
