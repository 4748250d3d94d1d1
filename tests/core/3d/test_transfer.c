/* test_transfer.c -- did the flip tiling keep the sample's structure? (gp_transfer.h; Dang &
 * Meguid 2010, Table 3). g(r) on packings whose answer is known (a simple cubic lattice, an
 * ideal gas, a brute-force O(n^2) count), the flip of a real specimen (exact where the flip is
 * exact), and wrong specimens, each built to fool some of the figures. */
#include "gp_flip.h"
#include "gp_sieve.h"
#include "gp_specimen3d.h"
#include "gp_test.h"
#include "gp_transfer.h"
#include "specimen3d_test.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

__extension__ typedef unsigned __int128 u128;

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return *s >> 11;
}
static double unif(uint64_t *s) { return (double)lcg(s) / 9007199254740992.0; /* [0, 1) */ }

static gp_transfer_packing packing(const double *xyzr, size_t n, const double box[3],
                                   gp_transfer_contacts_kind kind, const gp_contact3d *c,
                                   size_t nc)
{
    gp_transfer_packing p;
    memset(&p, 0, sizeof p);
    p.xyzr = xyzr;
    p.n = n;
    memcpy(p.box, box, sizeof p.box);
    p.contact_kind = kind;
    p.contacts = c;
    p.ncontacts = nc;
    return p;
}

/* sides are large (~20 KB): static storage, one per use */
static gp_transfer_side side_a, side_b, side_c, side_d;

/* ---- a simple cubic lattice: the coordination shells, exactly ----
 * m^3 points (i + 1/2) a in a box m a, spheres of diameter 0.9 a (d50 = 0.9 a). For every
 * lattice vector h there are prod_a (m - |h_a|) pairs, each weighted V / gamma(h) = m^3 / that:
 * each vector adds exactly 1 to N. So N_k is the number of lattice vectors in bin k (6 at a,
 * 12 at a sqrt 2, 8 at a sqrt 3, ...) and pairs_k their pair count, exactly. */
static void test_lattice(void)
{
    const int m = 12;
    const double a = 0.01;
    size_t n = (size_t)m * m * m;
    double *s = malloc(4 * n * sizeof *s);
    size_t q = 0;
    for (int z = 0; z < m; z++)
        for (int y = 0; y < m; y++)
            for (int x = 0; x < m; x++, q++) {
                s[4 * q] = (x + 0.5) * a;
                s[4 * q + 1] = (y + 0.5) * a;
                s[4 * q + 2] = (z + 0.5) * a;
                s[4 * q + 3] = 0.45 * a;
            }
    double box[3] = {m * a, m * a, m * a};
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    gp_transfer_packing p = packing(s, n, box, GP_TRANSFER_CONTACTS_GEOMETRIC, NULL, 0);
    gp_error e;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_OK);
    CHECK(side_a.d50 == 0.9 * a);
    CHECK(side_a.nbins == 100);
    /* the expected shells: lattice vectors within r_max = 4.5 a (0.9 a x 5) */
    double N[GP_TRANSFER_MAX_BINS] = {0};
    uint64_t P[GP_TRANSFER_MAX_BINS] = {0};
    double dra = 0.05 * 0.9 * a;
    for (int hz = -5; hz <= 5; hz++)
        for (int hy = -5; hy <= 5; hy++)
            for (int hx = -5; hx <= 5; hx++) {
                int h2 = hx * hx + hy * hy + hz * hz;
                if (h2 == 0 || sqrt((double)h2) * a >= 100 * dra)
                    continue;
                size_t k = (size_t)(sqrt((double)h2) * a / dra);
                N[k] += 1;
                P[k] += (uint64_t)(m - abs(hx)) * (m - abs(hy)) * (m - abs(hz));
            }
    /* with the walls as mirrors (half a spacing beyond the last plane) the lattice is
     * infinite: g_mirror counts the same shells, from every sphere, with no weight */
    int shells_ok = 1, pairs_ok = 1, empty_ok = 1, mirror_ok = 1;
    double V = box[0] * box[1] * box[2];
    for (size_t k = 0; k < side_a.nbins; k++) {
        double kk = (double)k;
        double shell = 4.0 / 3.0 * M_PI * dra * dra * dra * (3 * kk * kk + 3 * kk + 1);
        shells_ok &= fabs(side_a.neighbours[k] - N[k]) <= 1e-12 * (N[k] + 1);
        pairs_ok &= side_a.pairs[k] == P[k] / 2;
        empty_ok &= (N[k] == 0) == (side_a.g[k] == 0);
        mirror_ok &= fabs(side_a.g_mirror[k] * (n / V) * shell - N[k]) <= 1e-12 * (N[k] + 1);
    }
    CHECK(shells_ok);
    CHECK(pairs_ok);
    CHECK(empty_ok); /* peaks in the shells' bins and nowhere else */
    CHECK(mirror_ok);
    /* the first three shells: a, a sqrt 2, a sqrt 3 with 6, 12 and 8 neighbours */
    const double r1[3] = {1, sqrt(2.0), sqrt(3.0)}, z1[3] = {6, 12, 8};
    for (int k = 0; k < 3; k++) {
        size_t b = (size_t)(r1[k] * a / dra);
        CHECK_NEAR(side_a.neighbours[b], z1[k], 1e-12);
        CHECK(side_a.g[b] > 4);
        CHECK(side_a.g[b - 1] == 0 && side_a.g[b + 1] == 0);
        double shell = 4.0 / 3.0 * M_PI * (pow(b + 1.0, 3) - pow((double)b, 3)) * dra * dra * dra;
        CHECK_REL(side_a.g[b], z1[k] / ((n - 1) / (box[0] * box[1] * box[2]) * shell), 1e-12);
    }
    /* touching-free lattice: no contact; porosity 1 - n (pi/6) 0.9^3 a^3 / V */
    CHECK(side_a.contacts == 0 && side_a.wall_contacts == 0);
    CHECK_NEAR(side_a.porosity, 1 - M_PI / 6 * 0.729, 1e-12);
    /* the same with three threads, bit for bit */
    par.threads = 3;
    CHECK(gp_transfer_measure(&p, &par, &side_b, &e) == GP_OK);
    CHECK(memcmp(&side_a, &side_b, sizeof side_a) == 0);
    printf("lattice: N = %.12g, %.12g, %.12g at a, a sqrt 2, a sqrt 3\n",
           side_a.neighbours[(size_t)(a / dra)], side_a.neighbours[(size_t)(r1[1] * a / dra)],
           side_a.neighbours[(size_t)(r1[2] * a / dra)]);
    free(s);
}

/* ---- an ideal gas: uniform random centres give g = 1 within the statistical error ----
 * M independent gases of n points in a box of 1 x 0.8 x 0.6 m; for each bin the mean of g
 * over the gases against 1, in units of the scatter between the gases (the counting error
 * g / sqrt(pairs) leaves out the variance that the partly empty shells near the walls add:
 * its ratio to the true scatter is printed). */
static void test_ideal_gas(void)
{
    enum { M = 12 };
    size_t n = 20000;
    double box[3] = {1.0, 0.8, 0.6};
    double *s = malloc(4 * n * sizeof *s);
    uint64_t rs = 42;
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    par.dr = 0.1; /* 50 bins of 2 mm, the first with ~14 pairs a gas */
    static double sum[GP_TRANSFER_MAX_BINS], sum2[GP_TRANSFER_MAX_BINS], err2[GP_TRANSFER_MAX_BINS];
    double gall = 0, gall2 = 0;
    gp_error e;
    int ok = 1;
    for (int m = 0; m < M; m++) {
        for (size_t i = 0; i < n; i++) {
            for (int a = 0; a < 3; a++)
                s[4 * i + a] = box[a] * unif(&rs);
            s[4 * i + 3] = 0.01;
        }
        gp_transfer_packing p = packing(s, n, box, GP_TRANSFER_CONTACTS_GEOMETRIC, NULL, 0);
        ok &= gp_transfer_measure(&p, &par, &side_a, &e) == GP_OK;
        double gs = 0;
        uint64_t ps = 0;
        for (size_t k = 0; k < side_a.nbins; k++) {
            sum[k] += side_a.g[k];
            sum2[k] += side_a.g[k] * side_a.g[k];
            err2[k] += side_a.g_err[k] * side_a.g_err[k];
            gs += side_a.g[k] * (double)side_a.pairs[k];
            ps += side_a.pairs[k];
        }
        gall += gs / (double)ps;
        gall2 += gs / (double)ps * (gs / (double)ps);
    }
    CHECK(ok);
    CHECK(side_a.unit == 0.02 && side_a.nbins == 50);
    double zmax = 0, chi2 = 0, ratio_lo = 1e9, ratio_hi = 0;
    for (size_t k = 0; k < side_a.nbins; k++) {
        double mean = sum[k] / M, sd = sqrt((sum2[k] - M * mean * mean) / (M - 1));
        double z = (mean - 1) / (sd / sqrt((double)M));
        zmax = fmax(zmax, fabs(z));
        chi2 += z * z;
        double ratio = sd / sqrt(err2[k] / M);
        ratio_lo = fmin(ratio_lo, ratio);
        ratio_hi = fmax(ratio_hi, ratio);
    }
    chi2 /= (double)side_a.nbins;
    double gm = gall / M, gsd = sqrt((gall2 - M * gm * gm) / (M - 1));
    printf("ideal gas: %d gases of %zu points; mean g over the bins %.5f +- %.5f; per bin "
           "largest |z| %.2f, chi2 / bin %.2f; scatter / counting error %.2f to %.2f\n", M, n,
           gm, gsd / sqrt((double)M), zmax, chi2, ratio_lo, ratio_hi);
    CHECK(zmax < 4.5);
    CHECK(chi2 > 0.4 && chi2 < 2.0);
    CHECK(fabs(gm - 1) < 4 * gsd / sqrt((double)M));
    CHECK(ratio_lo > 0.45 && ratio_hi < 2.0);
    /* without the edge correction the last bin would be low by the part of the shells
     * outside the box (g_raw = 2 pairs / n / (rho shell)): the correction does the work */
    size_t k = side_a.nbins - 1;
    double dra = side_a.dr * side_a.unit, V = box[0] * box[1] * box[2];
    double shell = 4.0 / 3.0 * M_PI * (pow(k + 1.0, 3) - pow((double)k, 3)) * dra * dra * dra;
    double graw = 2.0 * (double)side_a.pairs[k] / (double)n / ((n - 1) / V * shell);
    printf("ideal gas at r = %.3f m: g %.4f (mean %.4f), uncorrected %.4f\n", (k + 0.5) * dra,
           side_a.g[k], sum[k] / M, graw);
    CHECK(graw < 0.85 && fabs(sum[k] / M - 1) < 0.02);
    /* the gas has the contacts its overlaps make: about rho (4 pi / 3) (2 r)^3 per sphere */
    double zexp = (n - 1) / V * 4.0 / 3.0 * M_PI * 0.02 * 0.02 * 0.02;
    CHECK_REL(side_a.coordination_spheres, zexp, 0.1);
    free(s);
}

/* ---- a small random packing against brute force ---- */

/* random spheres (radii 0.01-0.03) with small overlaps, some pushed into the walls */
static size_t random_packing(double *xyzr, size_t nmax, const double b[3], uint64_t *rs)
{
    size_t n = 0;
    for (int t = 0; t < 100000 && n < nmax; t++) {
        double r = 0.01 + 0.02 * unif(rs), p[3];
        for (int a = 0; a < 3; a++) {
            p[a] = r + (b[a] - 2 * r) * unif(rs);
            double u = unif(rs);
            if (u < 0.1) p[a] = r - 1e-3 * unif(rs);
            else if (u < 0.2) p[a] = b[a] - r + 1e-3 * unif(rs);
        }
        int ok = 1;
        for (size_t j = 0; j < n && ok; j++) {
            double dx = p[0] - xyzr[4 * j], dy = p[1] - xyzr[4 * j + 1];
            double dz = p[2] - xyzr[4 * j + 2];
            double rr = r + xyzr[4 * j + 3] - 2e-3;
            ok = dx * dx + dy * dy + dz * dz >= rr * rr;
        }
        if (ok) {
            memcpy(xyzr + 4 * n, p, sizeof p);
            xyzr[4 * n + 3] = r;
            n++;
        }
    }
    return n;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static void test_brute_force(void)
{
    const double box[3] = {0.3, 0.25, 0.2};
    double *s = malloc(4 * 800 * sizeof *s);
    uint64_t rs = 7;
    size_t n = random_packing(s, 800, box, &rs);
    const double sieve[4] = {0.025, 0.035, 0.045, 0.06};
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    par.sieve = sieve;
    par.nsieve = 4;
    par.unit = 0.04;
    par.r_max = 3.6; /* 0.144 m, 0.72 of the shortest side: weights up to 1 / 0.28^3 */
    par.dr = 0.04;
    gp_transfer_packing p = packing(s, n, box, GP_TRANSFER_CONTACTS_GEOMETRIC, NULL, 0);
    gp_error e;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_OK);
    size_t nb = side_a.nbins;
    CHECK(nb == 90);
    /* every pair, the weights summed as the module sums them */
    static u128 W[GP_TRANSFER_MAX_BINS];
    static uint64_t C[GP_TRANSFER_MAX_BINS];
    memset(W, 0, sizeof W);
    memset(C, 0, sizeof C);
    double dra = par.dr * par.unit, V = box[0] * box[1] * box[2];
    size_t overlaps = 0, walls = 0;
    for (size_t i = 0; i < n; i++) {
        const double *a = s + 4 * i;
        for (int w = 0; w < 6; w++) {
            double dist = w % 2 ? box[w / 2] - a[w / 2] : a[w / 2];
            walls += dist < a[3];
        }
        for (size_t j = i + 1; j < n; j++) {
            const double *b = s + 4 * j;
            double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
            double d2 = dx * dx + dy * dy + dz * dz;
            overlaps += sqrt(d2) < a[3] + b[3];
            size_t k = (size_t)(sqrt(d2) * (1.0 / dra));
            if (k >= nb)
                continue;
            double gam = (box[0] - fabs(dx)) * (box[1] - fabs(dy)) * (box[2] - fabs(dz));
            W[k] += (uint64_t)(V / gam * 0x1p56 + 0.5);
            C[k]++;
        }
    }
    /* with the walls as mirrors: every sphere against every sphere's 27 images (per axis x,
     * -x, 2 L - x), itself as it is left out */
    static uint64_t Mc[GP_TRANSFER_MAX_BINS];
    memset(Mc, 0, sizeof Mc);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++)
            for (int c = 0; c < 27; c++) {
                if (c == 0 && j == i)
                    continue;
                int m3[3] = {c % 3, (c / 3) % 3, c / 9};
                double im[3];
                for (int a = 0; a < 3; a++) {
                    double x = s[4 * j + a];
                    im[a] = m3[a] == 0 ? x : (m3[a] == 1 ? -x : 2 * box[a] - x);
                }
                const double *a = s + 4 * i;
                double dx = im[0] - a[0], dy = im[1] - a[1], dz = im[2] - a[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                size_t k = (size_t)(sqrt(d2) * (1.0 / dra));
                if (k < nb)
                    Mc[k]++;
            }
    int pairs_ok = 1, g_ok = 1, mirror_ok = 1;
    uint64_t total = 0;
    double rho = (n - 1) / V, dr3 = dra * dra * dra;
    for (size_t k = 0; k < nb; k++) {
        double kk = (double)k;
        double shell = 4.0 / 3.0 * M_PI * dr3 * (3 * kk * kk + 3 * kk + 1);
        double N = 2.0 * ((double)W[k] / 0x1p56) / (double)n;
        pairs_ok &= C[k] == side_a.pairs[k];
        g_ok &= N == side_a.neighbours[k] && N / (rho * shell) == side_a.g[k];
        mirror_ok &= (double)Mc[k] / (double)n / ((double)n / V * shell) == side_a.g_mirror[k];
        total += C[k];
    }
    printf("brute force: %zu spheres, %llu pairs within r_max, %zu overlaps, %zu wall crossings\n",
           n, (unsigned long long)total, overlaps, walls);
    CHECK(n > 300);
    CHECK(pairs_ok);
    CHECK(g_ok); /* bit for bit: integer sums do not care for the order */
    CHECK(mirror_ok);
    CHECK(side_a.contacts == overlaps && side_a.wall_contacts == walls);
    CHECK(overlaps > 50 && walls > 50);
    /* PSD against gp_sieve_passing; d50 against a sort with the same integer weights */
    double *d = malloc(n * sizeof *d), pw[4], pn[4];
    double dmax = 0;
    for (size_t i = 0; i < n; i++) {
        d[i] = 2 * s[4 * i + 3];
        dmax = fmax(dmax, d[i]);
    }
    gp_sieve_passing(d, n, sieve, 4, pw, pn);
    for (int k = 0; k < 4; k++) {
        CHECK(side_a.psd_number[k] == pn[k]);
        CHECK_NEAR(side_a.psd_weight[k], pw[k], 1e-12);
    }
    qsort(d, n, sizeof *d, cmp_double);
    u128 tot = 0, cum = 0;
    for (size_t i = 0; i < n; i++) {
        double f = d[i] / dmax;
        tot += (uint64_t)(f * f * f * 0x1p62 + 0.5);
    }
    double d50 = 0;
    for (size_t i = 0; i < n; i++) {
        double f = d[i] / dmax;
        cum += (uint64_t)(f * f * f * 0x1p62 + 0.5);
        if (2 * cum >= tot) {
            d50 = d[i];
            break;
        }
    }
    CHECK(side_a.d50 == d50);
    CHECK(side_a.d_max == dmax && side_a.d_min == d[0]);
    /* any thread count, the same bits */
    for (int t = 2; t <= 3; t++) {
        par.threads = t;
        CHECK(gp_transfer_measure(&p, &par, &side_b, &e) == GP_OK);
        CHECK(memcmp(&side_a, &side_b, sizeof side_a) == 0);
    }
    free(d);
    free(s);
}

/* ---- arguments refused ---- */
static void test_invalid(void)
{
    double s[8] = {0.1, 0.1, 0.1, 0.01, 0.2, 0.1, 0.1, 0.01};
    double box[3] = {0.3, 0.3, 0.3};
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    gp_transfer_packing p = packing(s, 2, box, GP_TRANSFER_CONTACTS_GEOMETRIC, NULL, 0);
    gp_error e;
    /* r_max = 5 d50 = 0.1 m: fine; 12 d50 = 0.24 m > 3/4 of 0.3 m: refused */
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_OK);
    par.r_max = 12;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "r_max") != NULL);
    par.r_max = 5;
    par.dr = 0.001; /* 5000 bins */
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_INVALID);
    par.dr = 0.05;
    double sieve[2] = {0.02, 0.01};
    par.sieve = sieve;
    par.nsieve = 2;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "sieve[1]") != NULL);
    par.nsieve = 0;
    p.tiles[0] = p.tiles[1] = p.tiles[2] = 2; /* 2 spheres are not 8 tiles */
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_INVALID);
    memset(p.tiles, 0, sizeof p.tiles);
    gp_contact3d c;
    memset(&c, 0, sizeof c);
    c.i = 0;
    c.j = 2; /* no sphere 2 */
    p.contact_kind = GP_TRANSFER_CONTACTS_GIVEN;
    p.contacts = &c;
    p.ncontacts = 1;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_INVALID);
    p.contact_kind = GP_TRANSFER_CONTACTS_FLIPPED; /* flipped without tiles */
    c.j = 1;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_INVALID);
    p.contact_kind = GP_TRANSFER_CONTACTS_GEOMETRIC;
    s[4] = NAN;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_INVALID);
    s[4] = 0.2;
    volatile int flag = 1;
    par.cancel = &flag;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_ERR_CANCELLED);
    par.cancel = NULL;
    /* sides with other bins or sieves are not compared */
    gp_transfer_diff d;
    CHECK(gp_transfer_measure(&p, &par, &side_a, &e) == GP_OK);
    par.dr = 0.1;
    CHECK(gp_transfer_measure(&p, &par, &side_b, &e) == GP_OK);
    CHECK(gp_transfer_compare(&side_a, &side_b, &d, &e) == GP_ERR_INVALID);
    CHECK(gp_transfer_compare(&side_a, &side_a, &d, &e) == GP_OK && d.rdf == 0 && d.porosity == 0);
}

/* ---- a real specimen and its flip ---- */

static const gp_sieve_row SMALL[3] = {{0.004, 0}, {0.006, 30}, {0.010, 100}};
static const double SMALL_SIEVE[3] = {0.004, 0.006, 0.010};

static void print_side(const char *name, const gp_transfer_side *s)
{
    printf("  %-16s n %6zu  porosity %.6f  Z %.4f  Z_ss %.4f  F %.4f %.4f %.4f (xy %+.1e)  "
           "PSD w %.2f n %.2f at 6 mm  g(1 d50) %.3f\n", name, s->n, s->porosity, s->coordination,
           s->coordination_spheres, s->fabric[0][0], s->fabric[1][1], s->fabric[2][2],
           s->fabric[0][1], s->psd_weight[1], s->psd_number[1], s->g[(size_t)(1.0 / s->dr)]);
}

static void print_diff(const char *name, const gp_transfer_diff *d)
{
    printf("  %-24s |dporosity| %.1e  |dZ| %.3f  |dZ_ss| %.3f  |dF| %.1e (diagonal %.1e)  "
           "|dPSD| %.1e / %.1e  |dg| %.3f at %.3f d50, rms %.4f, %.1f counting errors\n", name,
           d->porosity, d->coordination, d->coordination_spheres, d->fabric, d->fabric_diagonal,
           d->psd_number, d->psd_weight, d->rdf, d->rdf_r, d->rdf_rms, d->rdf_z);
}

static gp_specimen3d *build_small(uint64_t seed, int tiles)
{
    gp_spec3d s;
    spec_in_cube(&s, 0.06, SMALL, 3, 0.42);
    s.seed = seed;
    s.outputs = GP_OUT3_SPHERES | GP_OUT3_CONTACTS | GP_OUT3_FABRIC;
    s.tiling[0] = s.tiling[1] = s.tiling[2] = tiles;
    gp_specimen3d *r = NULL;
    gp_error e;
    gp_status st = gp_specimen3d_build(&s, NULL, NULL, NULL, &r, &e);
    CHECK(st == GP_OK);
    if (st != GP_OK) {
        fprintf(stderr, "build: %s\n", e.message);
        gp_specimen3d_destroy(r);
        return NULL;
    }
    return r;
}

/* the sphere-sphere overlaps of a packing, mean, in units of the mean radius */
static double mean_overlap(const double *x, size_t n)
{
    size_t *pr = NULL, np = 0;
    gp_error e;
    gp_dem3d_find_pairs(x, n, 0, &pr, &np, &e);
    double sum = 0, rsum = 0;
    for (size_t q = 0; q < np; q++) {
        const double *a = x + 4 * pr[2 * q], *b = x + 4 * pr[2 * q + 1];
        double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
        sum += a[3] + b[3] - sqrt(dx * dx + dy * dy + dz * dz);
    }
    for (size_t i = 0; i < n; i++)
        rsum += x[4 * i + 3];
    free(pr);
    return np ? sum / (double)np / (rsum / (double)n) : 0;
}

static void test_specimen_flip(const gp_specimen3d *r)
{
    size_t n = r->count;
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    par.sieve = SMALL_SIEVE;
    par.nsieve = 3;
    gp_error e;
    /* S0: the figures gp_specimen3d reports, bit for bit */
    gp_transfer_packing p0 = packing(r->spheres, n, r->box, GP_TRANSFER_CONTACTS_GIVEN,
                                     r->contacts, r->ncontacts);
    gp_transfer_side *s0 = &side_a;
    CHECK(gp_transfer_measure(&p0, &par, s0, &e) == GP_OK);
    CHECK(s0->porosity == r->stats.porosity);
    CHECK(s0->coordination == r->stats.coordination_number);
    CHECK(s0->coordination_spheres == r->stats.coordination_spheres);
    CHECK(memcmp(s0->fabric, r->stats.fabric, sizeof s0->fabric) == 0);
    for (size_t k = 0; k < 3; k++) {
        CHECK(s0->psd_number[k] == r->stats.psd.achieved_number[k]);
        CHECK_NEAR(s0->psd_weight[k], r->stats.psd.achieved_weight[k], 1e-12);
    }
    /* the contacts found from the geometry: the DEM's own list, as sets go */
    gp_transfer_packing pg = p0;
    pg.contact_kind = GP_TRANSFER_CONTACTS_GEOMETRIC;
    CHECK(gp_transfer_measure(&pg, &par, &side_d, &e) == GP_OK);
    printf("S0: %zu spheres, DEM %zu + %zu wall contacts, geometry %zu + %zu\n", n,
           s0->contacts, s0->wall_contacts, side_d.contacts, side_d.wall_contacts);
    CHECK(side_d.contacts == s0->contacts && side_d.wall_contacts == s0->wall_contacts);
    CHECK_NEAR(side_d.fabric[2][2], s0->fabric[2][2], 1e-12);

    /* S0 tiled 2 x 2 x 2 by gp_flip; its contacts streamed from S0's */
    int T[3] = {2, 2, 2};
    double *tx = NULL;
    size_t nt = 0;
    CHECK(gp_flip_tile(r->spheres, n, r->box, T, 1u << 30, NULL, &tx, &nt, &e) == GP_OK);
    double tbox[3] = {2 * r->box[0], 2 * r->box[1], 2 * r->box[2]};
    gp_transfer_packing pt = packing(tx, nt, tbox, GP_TRANSFER_CONTACTS_FLIPPED, r->contacts,
                                     r->ncontacts);
    memcpy(pt.tiles, T, sizeof T);
    par.unit = s0->d50;
    gp_transfer_side *st = &side_b;
    CHECK(gp_transfer_measure(&pt, &par, st, &e) == GP_OK);
    gp_transfer_diff d;
    CHECK(gp_transfer_compare(s0, st, &d, &e) == GP_OK);
    print_side("S0", s0);
    print_side("S0 2x2x2", st);
    print_diff("S0 / its 2x2x2", &d);
    CHECK(d.porosity <= 1e-12);
    CHECK(st->coordination == s0->coordination); /* the flip is exact, and so is the count */
    CHECK(st->coordination_spheres > s0->coordination_spheres); /* inner walls became pairs */
    CHECK(st->contacts + st->wall_contacts == 8 * s0->contacts + 8 * s0->wall_contacts -
                                                  (8 * s0->wall_contacts - st->wall_contacts) / 2);
    CHECK(d.fabric_diagonal <= 1e-12);
    /* off-diagonals: times m_a m_b = 0 for two tiles on every axis */
    CHECK(fabs(st->fabric[0][1]) <= 1e-12 && fabs(st->fabric[0][2]) <= 1e-12 &&
          fabs(st->fabric[1][2]) <= 1e-12);
    CHECK(fabs(s0->fabric[0][1]) > 1e-4 || fabs(s0->fabric[0][2]) > 1e-4 ||
          fabs(s0->fabric[1][2]) > 1e-4);
    CHECK(d.psd_number == 0 && d.psd_weight == 0 && st->d50 == s0->d50);
    /* g(r): the same structure, up to the pairs across the inner faces */
    CHECK(d.rdf < 0.15 && d.rdf_rms < 0.04);
    /* with the walls as mirrors both are S0's infinite tiling: the same g, bit for bit (the
     * counts are integers, 8 times S0's; n / V is the same number) */
    CHECK(memcmp(s0->g_mirror, st->g_mirror, sizeof s0->g_mirror) == 0);
    double mg = 0;
    for (size_t k = 0; k < s0->nbins; k++)
        mg = fmax(mg, fabs(s0->g_mirror[k] - s0->g[k]));
    printf("  g_mirror - g of S0: at most %.3f; g_mirror of S0 and its 2x2x2: %.1e apart\n", mg,
           d.rdf_mirror);

    /* the same tiling from gp_specimen3d itself: the same sample, spheres and figures */
    gp_specimen3d *r2 = build_small(11, 2);
    if (r2) {
        CHECK(memcmp(r2->sample_spheres, r->spheres, 4 * n * sizeof *tx) == 0);
        CHECK(r2->count == nt && memcmp(r2->spheres, tx, 4 * nt * sizeof *tx) == 0);
        CHECK_NEAR(r2->stats.porosity, st->porosity, 1e-15);
        CHECK(r2->stats.coordination_number == st->coordination);
        CHECK(r2->stats.coordination_spheres == st->coordination_spheres);
        CHECK(memcmp(r2->stats.fabric, st->fabric, sizeof st->fabric) == 0);
        /* its contact list as GIVEN: the stream's figures, bit for bit */
        gp_transfer_packing pl = packing(tx, nt, tbox, GP_TRANSFER_CONTACTS_GIVEN, r2->contacts,
                                         r2->ncontacts);
        memcpy(pl.tiles, T, sizeof T);
        CHECK(gp_transfer_measure(&pl, &par, &side_c, &e) == GP_OK);
        CHECK(memcmp(&side_c, st, sizeof side_c) == 0);
        gp_specimen3d_destroy(r2);
    }
    free(tx);

    /* three tiles along x only: F_xy and F_xz are divided by 3, F_yz is kept */
    int T3[3] = {3, 1, 1};
    CHECK(gp_flip_tile(r->spheres, n, r->box, T3, 1u << 30, NULL, &tx, &nt, &e) == GP_OK);
    double box3[3] = {3 * r->box[0], r->box[1], r->box[2]};
    gp_transfer_packing p3 = packing(tx, nt, box3, GP_TRANSFER_CONTACTS_FLIPPED, r->contacts,
                                     r->ncontacts);
    memcpy(p3.tiles, T3, sizeof T3);
    CHECK(gp_transfer_measure(&p3, &par, &side_c, &e) == GP_OK);
    CHECK(side_c.coordination == s0->coordination);
    CHECK_NEAR(side_c.porosity, s0->porosity, 1e-12);
    CHECK_NEAR(side_c.fabric[0][1], s0->fabric[0][1] / 3, 1e-12);
    CHECK_NEAR(side_c.fabric[0][2], s0->fabric[0][2] / 3, 1e-12);
    CHECK_NEAR(side_c.fabric[1][2], s0->fabric[1][2], 1e-12);
    for (int a = 0; a < 3; a++)
        CHECK_NEAR(side_c.fabric[a][a], s0->fabric[a][a], 1e-12);
    CHECK(gp_transfer_compare(s0, &side_c, &d, &e) == GP_OK);
    CHECK(d.rdf_mirror < 1e-12);
    free(tx);
}

/* ---- wrong specimens: what each figure cannot see ----
 * PSD sees no position, porosity no arrangement, g(r) of the centres no size (swap the radii
 * and it does not move), the coordination number counts overlaps as contacts (a random gas
 * of these grains at this solid fraction overlaps about as often as S0 touches), and any
 * isotropic packing has S0's fabric to 0.01. Two wrong specimens, each passing some figures
 * and caught by another:
 *   gas:      S0's grains at uniform random centres inside the box (not crossing it): the
 *             same PSD, porosity within 0.002; g(r) has no excluded core and no shell.
 *   swapped:  S0's centres with its radii shuffled among them: the same PSD and g(r) to the
 *             last bit, porosity within 0.02 (large grains on the wall sites lose caps); its
 *             overlaps are deep (large grains on small grains' sites), and its geometric
 *             coordination is off by more than one.
 * And one right one: S0 of another seed, the same material: every figure within the noise of
 * a sample this size, and g(r) far closer than the gas's. */
static void test_wrong_specimens(const gp_specimen3d *r)
{
    size_t n = r->count;
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    par.sieve = SMALL_SIEVE;
    par.nsieve = 3;
    gp_error e;
    /* S0 measured on its geometry, as the wrong ones are (they come without contacts) */
    gp_transfer_packing p0 =
        packing(r->spheres, n, r->box, GP_TRANSFER_CONTACTS_GEOMETRIC, NULL, 0);
    gp_transfer_side *s0 = &side_a, *w = &side_b;
    CHECK(gp_transfer_measure(&p0, &par, s0, &e) == GP_OK);
    par.unit = s0->d50;
    double ov0 = mean_overlap(r->spheres, n);
    gp_transfer_diff d;

    double *x = malloc(4 * n * sizeof *x);
    uint64_t rs = 99;
    for (size_t i = 0; i < n; i++) {
        double rad = r->spheres[4 * i + 3];
        for (int a = 0; a < 3; a++)
            x[4 * i + a] = rad + (r->box[a] - 2 * rad) * unif(&rs);
        x[4 * i + 3] = rad;
    }
    gp_transfer_packing pw = packing(x, n, r->box, GP_TRANSFER_CONTACTS_GEOMETRIC, NULL, 0);
    CHECK(gp_transfer_measure(&pw, &par, w, &e) == GP_OK);
    CHECK(gp_transfer_compare(s0, w, &d, &e) == GP_OK);
    print_side("S0 (geometry)", s0);
    print_side("gas", w);
    print_diff("S0 / gas", &d);
    printf("  mean overlap / mean radius: S0 %.4f, gas %.4f\n", ov0, mean_overlap(x, n));
    CHECK(d.psd_number == 0 && d.psd_weight == 0);
    CHECK(d.porosity < 0.002);
    CHECK(d.rdf > 0.8 && d.rdf_z > 8);
    double gas_rdf = d.rdf, gas_rms = d.rdf_rms;

    memcpy(x, r->spheres, 4 * n * sizeof *x);
    for (size_t i = n - 1; i > 0; i--) { /* Fisher-Yates on the radii */
        size_t j = (size_t)(unif(&rs) * (double)(i + 1));
        double t = x[4 * i + 3];
        x[4 * i + 3] = x[4 * j + 3];
        x[4 * j + 3] = t;
    }
    CHECK(gp_transfer_measure(&pw, &par, w, &e) == GP_OK);
    CHECK(gp_transfer_compare(s0, w, &d, &e) == GP_OK);
    print_side("swapped radii", w);
    print_diff("S0 / swapped radii", &d);
    double ovs = mean_overlap(x, n);
    printf("  mean overlap / mean radius: swapped %.4f\n", ovs);
    CHECK(d.rdf == 0 && memcmp(s0->g, w->g, sizeof s0->g) == 0);
    CHECK(d.psd_number == 0 && d.psd_weight == 0);
    CHECK(d.porosity < 0.02);
    CHECK(d.coordination > 1);
    CHECK(ovs > 20 * ov0);
    free(x);

    /* the right one: another seed */
    gp_specimen3d *r2 = build_small(12, 1);
    if (r2) {
        gp_transfer_packing p2 = packing(r2->spheres, r2->count, r2->box,
                                         GP_TRANSFER_CONTACTS_GEOMETRIC, NULL, 0);
        CHECK(gp_transfer_measure(&p2, &par, w, &e) == GP_OK);
        CHECK(gp_transfer_compare(s0, w, &d, &e) == GP_OK);
        print_side("S0, seed 12", w);
        print_diff("S0 / seed 12", &d);
        CHECK(d.porosity < 0.005 && d.coordination < 0.3 && d.fabric_diagonal < 0.02);
        CHECK(d.psd_weight < 1.0);
        CHECK(d.rdf < gas_rdf / 2 && d.rdf_rms < gas_rms / 3);
        gp_specimen3d_destroy(r2);
    }
}

int main(void)
{
    test_lattice();
    test_ideal_gas();
    test_brute_force();
    test_invalid();
    gp_specimen3d *r = build_small(11, 1);
    if (r) {
        test_specimen_flip(r);
        test_wrong_specimens(r);
    }
    gp_specimen3d_destroy(r);
    return gp_test_summary();
}
