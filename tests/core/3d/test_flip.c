/* test_flip.c -- flip tiling (Dang & Meguid 2010, Phase 2, Figs 2-4, Eqs 11-13). */
#include "gp_flip.h"
#include "gp_test.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return *s >> 11;
}
static double unif(uint64_t *s) { return (double)(lcg(s) % 1000000) / 1e6; }

/* a sample with many wall contacts: random spheres, some pushed slightly into the walls */
static size_t make_sample(double *xyzr, size_t nmax, const double b[3], uint64_t *rs)
{
    size_t n = 0;
    for (int t = 0; t < 200000 && n < nmax; t++) {
        double r = 0.01 + 0.02 * unif(rs), p[3];
        for (int a = 0; a < 3; a++) {
            p[a] = r + (b[a] - 2 * r) * unif(rs);
            double u = unif(rs);
            if (u < 0.1) p[a] = r - 1e-4 * unif(rs);            /* touching the low wall */
            else if (u < 0.2) p[a] = b[a] - r + 1e-4 * unif(rs); /* touching the high wall */
        }
        int ok = 1;
        for (size_t j = 0; j < n && ok; j++) {
            double dx = p[0] - xyzr[4 * j], dy = p[1] - xyzr[4 * j + 1], dz = p[2] - xyzr[4 * j + 2];
            double rr = r + xyzr[4 * j + 3] - 2e-4; /* allow small sphere overlaps */
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

/* ---- the streaming form (gp_flip_contacts_each) ---- */

/* the DEM's contacts (*c, malloc'ed) of the n spheres s in the box [0, b] after one step
 * without gravity: the forces of the law, nothing moved measurably (s gets the positions) */
static void one_step_contacts(double *s, size_t n, const double b[3], gp_contact3d **c,
                              size_t *nc)
{
    gp_dem3d_params p;
    gp_dem3d_params_defaults(&p);
    p.gravity[2] = 0;
    gp_dem3d *d;
    gp_error e;
    double lo[3] = {0, 0, 0};
    CHECK(gp_dem3d_create(&p, s, n, lo, b, &d, &e) == GP_OK);
    gp_dem3d_run(d, 1, &e);
    gp_dem3d_spheres(d, s);
    gp_dem3d_contacts(d, c, nc, &e);
    gp_dem3d_destroy(d);
}

/* a sample and its DEM contacts */
static size_t small_sample(const double b[3], uint64_t seed, double **xyzr, gp_contact3d **c,
                           size_t *nc)
{
    uint64_t rs = seed;
    double *s = malloc(4 * 150 * sizeof *s);
    size_t n = make_sample(s, 150, b, &rs);
    one_step_contacts(s, n, b, c, nc);
    *xyzr = s;
    return n;
}

/* the mapping written out plainly (Eq. 13; what gp_flip.h says), one tile at a time, no
 * order: the reference for the multiset */
static size_t ref_contacts(const gp_contact3d *c, size_t nc, size_t n, const int T[3],
                           gp_contact3d *o)
{
    size_t m = 0;
    for (int kz = 0; kz < T[2]; kz++)
        for (int ky = 0; ky < T[1]; ky++)
            for (int kx = 0; kx < T[0]; kx++) {
                int k[3] = {kx, ky, kz};
                size_t t = ((size_t)kz * T[1] + ky) * T[0] + kx;
                for (size_t q = 0; q < nc; q++) {
                    gp_contact3d e = c[q];
                    for (int a = 0; a < 3; a++)
                        if (k[a] % 2) {
                            e.normal[a] = -e.normal[a];
                            e.force[a] = -e.force[a];
                        }
                    e.i = t * n + c[q].i;
                    if (c[q].j >= 0) {
                        e.j = (long)(t * n + (size_t)c[q].j);
                        o[m++] = e;
                        continue;
                    }
                    int a = (int)(-1 - c[q].j) / 2, hi = (int)(-1 - c[q].j) % 2;
                    int high = k[a] % 2 ? !hi : hi; /* the wall's face in the tiled box */
                    if (high ? k[a] == T[a] - 1 : k[a] == 0) {
                        e.j = -1 - (2 * a + high);
                        o[m++] = e;
                    } else if (high) { /* the pair with the image above; the lower tile lists it */
                        size_t up = a == 0 ? 1 : (a == 1 ? (size_t)T[0] : (size_t)T[0] * T[1]);
                        e.j = (long)((t + up) * n + c[q].i);
                        e.overlap = 2 * c[q].overlap;
                        o[m++] = e;
                    }
                }
            }
    return m;
}

static int cmp_ij(const void *pa, const void *pb)
{
    const gp_contact3d *a = pa, *b = pb;
    if (a->i != b->i) return a->i < b->i ? -1 : 1;
    return a->j < b->j ? -1 : a->j > b->j;
}

/* what a visitor sees: the contacts, chunk sizes, the measures as accumulators */
typedef struct sink {
    gp_contact3d *all;
    size_t m, cap, chunks, bad_chunk;
    size_t pairs, walls;
    gp_dem3d_fabric_acc F;
    gp_dem3d_stress_acc S;
    volatile int *raise_after; /* raise this flag after the first chunk */
    int fail_at;               /* return GP_ERR_INTERNAL at this chunk (0 = never) */
} sink;

static gp_status sink_visit(void *user, const gp_contact3d *c, size_t k, gp_error *err)
{
    sink *s = user;
    s->chunks++;
    if (k == 0 || k > s->cap)
        s->bad_chunk++;
    if (s->fail_at && (int)s->chunks == s->fail_at)
        return gp_error_set(err, GP_ERR_INTERNAL, "visitor says stop");
    if (s->all)
        memcpy(s->all + s->m, c, k * sizeof *c);
    s->m += k;
    for (size_t q = 0; q < k; q++) {
        if (c[q].j >= 0) s->pairs++;
        else s->walls++;
    }
    gp_dem3d_fabric_acc_add(&s->F, c, k);
    gp_dem3d_stress_acc_add(&s->S, c, k);
    if (s->raise_after)
        __atomic_store_n((int *)s->raise_after, 1, __ATOMIC_RELAXED);
    return GP_OK;
}

/* the measures summed plainly in long double: an independent check of the formulas */
static void brute_measures(const gp_contact3d *c, size_t nc, const double *x, double V,
                           double F[3][3], double S[3][3])
{
    long double f[3][3] = {{0}}, st[3][3] = {{0}}, w = 0;
    for (size_t k = 0; k < nc; k++) {
        double l[3], wk = c[k].j >= 0 ? 2 : 1;
        for (int a = 0; a < 3; a++)
            l[a] = c[k].j >= 0 ? x[4 * c[k].j + a] - x[4 * c[k].i + a]
                               : (x[4 * c[k].i + 3] - c[k].overlap) * c[k].normal[a];
        w += wk;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) {
                f[a][b] += (long double)wk * c[k].normal[a] * c[k].normal[b];
                st[a][b] -= (long double)l[a] * c[k].force[b];
            }
    }
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            F[a][b] = (double)(f[a][b] / w);
            S[a][b] = (double)(st[a][b] / V);
        }
}

static void test_streaming(void)
{
    const double b[3] = {0.12, 0.1, 0.14};
    double *s;
    gp_contact3d *c;
    size_t nc, n = small_sample(b, 7, &s, &c, &nc), nwall = 0;
    for (size_t k = 0; k < nc; k++)
        nwall += c[k].j < 0;
    CHECK(n > 60 && nwall > 20);
    const int T[3] = {2, 3, 2};
    size_t nt = 12 * n, cap = 12 * nc;
    gp_error e;
    gp_contact3d *ex, *ref = malloc(cap * sizeof *ref);
    size_t nex, nref = ref_contacts(c, nc, n, T, ref);
    CHECK(gp_flip_contacts(c, nc, n, T, NULL, &ex, &nex, &e) == GP_OK);
    double *t;
    CHECK(gp_flip_tile(s, n, b, T, 10000000, NULL, &t, &nt, &e) == GP_OK);
    double V = 12 * b[0] * b[1] * b[2];
    /* (a) every chunk size gives the array of gp_flip_contacts, in its order; sorted, it
     * is the reference multiset */
    const size_t caps[4] = {1, 7, 4096, 100000};
    for (int r = 0; r < 4; r++) {
        sink k = {malloc(cap * sizeof *k.all), 0, caps[r], 0, 0, 0, 0, {{{0}}, 0}, {0}, NULL, 0};
        gp_dem3d_fabric_acc_init(&k.F);
        gp_dem3d_stress_acc_init(&k.S, t);
        gp_contact3d *buf = malloc(caps[r] * sizeof *buf);
        CHECK(gp_flip_contacts_each(c, nc, n, T, NULL, buf, caps[r], sink_visit, &k, &e) == GP_OK);
        CHECK(k.bad_chunk == 0 && k.m == nex && k.m == nref);
        CHECK(k.chunks == (nex + caps[r] - 1) / caps[r]);
        CHECK(memcmp(k.all, ex, nex * sizeof *ex) == 0);
        qsort(k.all, k.m, sizeof *k.all, cmp_ij);
        if (r == 0)
            qsort(ref, nref, sizeof *ref, cmp_ij);
        CHECK(memcmp(k.all, ref, nref * sizeof *ref) == 0);
        /* (b) the accumulators: the same bits as the array functions on the same contacts,
         * and within 1e-12 of a plain long-double sum; the counts those of the array */
        double F[3][3], S[3][3], Fa[3][3], Sa[3][3], Fb[3][3], Sb[3][3];
        gp_dem3d_fabric_acc_finish(&k.F, F);
        gp_dem3d_stress_acc_finish(&k.S, V, S);
        gp_dem3d_fabric(ex, nex, Fa);
        gp_dem3d_stress(ex, nex, t, V, Sa);
        brute_measures(ref, nref, t, V, Fb, Sb);
        CHECK(memcmp(F, Fa, sizeof F) == 0 && memcmp(S, Sa, sizeof S) == 0);
        double smax = 0;
        for (int a = 0; a < 3; a++)
            smax = fmax(smax, fabs(Sb[a][a]));
        for (int a = 0; a < 3; a++)
            for (int bb = 0; bb < 3; bb++) {
                CHECK_NEAR(F[a][bb], Fb[a][bb], 1e-12);
                CHECK_NEAR(S[a][bb], Sb[a][bb], 1e-12 * smax);
            }
        size_t pairs = 0;
        for (size_t q = 0; q < nex; q++)
            pairs += ex[q].j >= 0;
        CHECK(k.pairs == pairs && k.walls == nex - pairs);
        free(buf);
        free(k.all);
    }
    /* (d) cancel: a raised flag stops before the first tile; a flag raised by the visitor
     * stops at the next tile; a visitor's error comes back as it is (ASan: nothing leaks) */
    volatile int flag = 1;
    gp_contact3d buf[16];
    sink k = {NULL, 0, 16, 0, 0, 0, 0, {{{0}}, 0}, {0}, NULL, 0};
    gp_dem3d_stress_acc_init(&k.S, t);
    CHECK(gp_flip_contacts_each(c, nc, n, T, &flag, buf, 16, sink_visit, &k, &e) == GP_ERR_CANCELLED);
    CHECK(k.chunks == 0);
    gp_contact3d *o2 = ex;
    size_t no2 = 1;
    CHECK(gp_flip_contacts(c, nc, n, T, &flag, &o2, &no2, &e) == GP_ERR_CANCELLED);
    CHECK(o2 == NULL && no2 == 0);
    flag = 0;
    k.raise_after = &flag;
    CHECK(gp_flip_contacts_each(c, nc, n, T, &flag, buf, 16, sink_visit, &k, &e) == GP_ERR_CANCELLED);
    CHECK(k.chunks >= 1 && k.m < nex);
    sink f = {NULL, 0, 16, 0, 0, 0, 0, {{{0}}, 0}, {0}, NULL, 3};
    gp_dem3d_stress_acc_init(&f.S, t);
    CHECK(gp_flip_contacts_each(c, nc, n, T, NULL, buf, 16, sink_visit, &f, &e) == GP_ERR_INTERNAL);
    CHECK(f.chunks == 3 && strstr(e.message, "visitor") != NULL);
    CHECK(gp_flip_contacts_each(c, nc, n, T, NULL, buf, 0, sink_visit, &f, &e) == GP_ERR_INVALID);
    const int bad[3] = {2, 0, 1};
    CHECK(gp_flip_contacts_each(c, nc, n, bad, NULL, buf, 16, sink_visit, &f, &e) == GP_ERR_INVALID);
    /* tiling 1 x 1 x 1: the sample's own contacts, as they are */
    const int one[3] = {1, 1, 1};
    sink u = {malloc((nc ? nc : 1) * sizeof *u.all), 0, 16, 0, 0, 0, 0, {{{0}}, 0}, {0}, NULL, 0};
    gp_dem3d_stress_acc_init(&u.S, s);
    CHECK(gp_flip_contacts_each(c, nc, n, one, NULL, buf, 16, sink_visit, &u, &e) == GP_OK);
    CHECK(u.m == nc && memcmp(u.all, c, nc * sizeof *c) == 0);
    free(u.all);
    free(t);
    free(ex);
    free(ref);
    free(c);
    free(s);
}

int main(void)
{
    test_streaming();
    const double b[3] = {0.2, 0.15, 0.25};
    uint64_t rs = 99;
    double *s = malloc(4 * 400 * sizeof *s);
    size_t n = make_sample(s, 400, b, &rs);
    CHECK(n > 250);
    /* forces from the DEM law (one step, no gravity, so nothing moves measurably) */
    gp_contact3d *c;
    size_t nc;
    one_step_contacts(s, n, b, &c, &nc);
    gp_dem3d_params p; /* the law's E, as one_step_contacts used it */
    gp_dem3d_params_defaults(&p);
    gp_error e;
    double lo[3] = {0, 0, 0};
    size_t nwall = 0;
    for (size_t k = 0; k < nc; k++)
        nwall += c[k].j < 0;
    CHECK(nwall > 50);

    const int tiles[3] = {4, 4, 4};
    double *t;
    size_t nt;
    CHECK(gp_flip_tile(s, n, b, tiles, 10000000, NULL, &t, &nt, &e) == GP_OK);
    CHECK(nt == 64 * n);
    gp_contact3d *tc;
    size_t ntc;
    CHECK(gp_flip_contacts(c, nc, n, tiles, NULL, &tc, &ntc, &e) == GP_OK);

    /* porosity: clipped solid volume, sample vs tiled (each copy clipped to its tile) */
    double vs = gp_dem3d_solid_volume(s, n, lo, b), vt = 0;
    for (size_t k = 0; k < 64; k++) {
        double tl[3] = {(double)(k % 4) * b[0], (double)((k / 4) % 4) * b[1], (double)(k / 16) * b[2]};
        double th[3] = {tl[0] + b[0], tl[1] + b[1], tl[2] + b[2]};
        vt += gp_dem3d_solid_volume(t + 4 * k * n, n, tl, th);
    }
    double ps = 1 - vs / (b[0] * b[1] * b[2]), pt = 1 - vt / (64 * b[0] * b[1] * b[2]);
    CHECK_NEAR(pt, ps, 0.002);
    CHECK_NEAR(pt, ps, 1e-12);
    /* the whole tiled box, clipped at its outer walls only: the inner caps overlap their images,
     * counted twice, which is tiny */
    double tb[3] = {4 * b[0], 4 * b[1], 4 * b[2]};
    CHECK_NEAR(1 - gp_dem3d_solid_volume(t, nt, lo, tb) / (tb[0] * tb[1] * tb[2]), ps, 0.002);

    /* every mapped sphere contact is a real overlap of the tiled spheres, same overlap (for
     * former wall contacts: Eq. 13, half the overlap with the image = the wall penetration) */
    size_t pairs = 0, bad = 0, images = 0;
    for (size_t k = 0; k < ntc; k++) {
        if (tc[k].j < 0)
            continue;
        pairs++;
        const double *a = t + 4 * tc[k].i, *q = t + 4 * tc[k].j;
        double dx = q[0] - a[0], dy = q[1] - a[1], dz = q[2] - a[2];
        double dist = sqrt(dx * dx + dy * dy + dz * dz);
        double ov = a[3] + q[3] - dist;
        if (fabs(ov - tc[k].overlap) > 1e-12 || fabs(dx / dist - tc[k].normal[0]) > 1e-9)
            bad++;
        if (tc[k].i % n == (size_t)tc[k].j % n) {
            images++;
            /* Eq. 11 penetration 0.5 (R1 + R2 - O1O1') equals Eq. 12's R - O1W; the force is the
             * wall force 2 E R delta */
            double delta = 0.5 * ov, f = sqrt(tc[k].force[0] * tc[k].force[0] +
                                              tc[k].force[1] * tc[k].force[1] +
                                              tc[k].force[2] * tc[k].force[2]);
            if (fabs(f - 2 * p.young * a[3] * delta) > 1e-9 * f)
                bad++;
        }
    }
    CHECK(bad == 0);
    /* inner faces: per axis a, 3 inner planes per column, each holds both walls' contacts of
     * the sample: count = sum over axes of (tiles_a - 1) * (64 / tiles_a) * (n_lo + n_hi) / 2 ... by
     * direct count: every wall contact of every tile either stays a wall contact (outer face) or
     * becomes half of an image pair */
    size_t outer = 0;
    for (size_t k = 0; k < ntc; k++)
        outer += tc[k].j < 0;
    CHECK(outer + 2 * images == 64 * nwall);
    /* independent detection finds exactly these pairs */
    size_t *pr, npr;
    CHECK(gp_dem3d_find_pairs(t, nt, 0, &pr, &npr, &e) == GP_OK);
    CHECK(npr == pairs);
    size_t match = 0, q = 0;
    for (size_t k = 0; k < ntc && q < npr; k++) {
        if (tc[k].j < 0)
            break;
        if (pr[2 * q] == tc[k].i && pr[2 * q + 1] == (size_t)tc[k].j) {
            match++;
            q++;
        }
    }
    CHECK(match == pairs);
    free(pr);

    /* coordination (walls counted) is kept exactly; fabric diagonal within 0.01 */
    double z0 = (2.0 * (double)(nc - nwall) + (double)nwall) / (double)n;
    double z1 = (2.0 * (double)pairs + (double)outer) / (double)nt;
    CHECK_NEAR(z1, z0, 1e-12);
    double F0[3][3], F1[3][3];
    gp_dem3d_fabric(c, nc, F0);
    gp_dem3d_fabric(tc, ntc, F1);
    for (int a = 0; a < 3; a++) {
        CHECK_NEAR(F1[a][a], F0[a][a], 0.01);
        CHECK_NEAR(F1[a][a], F0[a][a], 1e-12); /* per-sphere counting makes it exact */
    }
    /* the stress (Eq. 15) diagonal is kept: mirrored l and f flip together */
    double S0[3][3], S1[3][3];
    gp_dem3d_stress(c, nc, s, b[0] * b[1] * b[2], S0);
    gp_dem3d_stress(tc, ntc, t, 64 * b[0] * b[1] * b[2], S1);
    for (int a = 0; a < 3; a++)
        CHECK_REL(S1[a][a], S0[a][a], 1e-9);

    /* errors */
    const int bad_tiles[3] = {0, 1, 1};
    double *t2;
    size_t nt2;
    CHECK(gp_flip_tile(s, n, b, bad_tiles, 10000000, NULL, &t2, &nt2, &e) == GP_ERR_INVALID);
    CHECK(gp_flip_tile(s, n, b, tiles, 1000, NULL, &t2, &nt2, &e) == GP_ERR_INVALID);
    free(t);
    free(tc);
    free(c);
    free(s);
    return gp_test_summary();
}
