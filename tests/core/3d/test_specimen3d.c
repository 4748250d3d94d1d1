/* test_specimen3d.c -- the 3D pipeline end to end (Dang & Meguid 2010; NOTES.md).
 *
 * Under ASan/UBSan only the small specimens run (a 0.06 m box, a 4-10 mm sieve, ~860 spheres,
 * the same physics; porosity 0.42 because six walls 6 to 15 grains apart loosen a packing);
 * without sanitizers the paper's example (0.5 m cube, Table 1, Table 2, porosity 0.38) runs
 * too. */
#include "gp_clock.h"
#include "gp_specimen3d.h"
#include "gp_test.h"
#include "specimen3d_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#if defined(__SANITIZE_ADDRESS__)
#define GP_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define GP_SANITIZED 1
#endif
#endif

static const gp_sieve_row SMALL[3] = {{0.004, 0}, {0.006, 30}, {0.010, 100}};

/* seed 5, a 0.045 m box at porosity 0.44, stopped at 6000 steps (NOT_CONVERGED) */
static void short_spec(gp_spec3d *s)
{
    spec_in_cube(s, 0.045, SMALL, 3, 0.44);
    s->seed = 5;
    s->max_steps = 6000;
}

static void check_specimen(const gp_specimen3d *r, double target)
{
    const gp_stats3d *S = &r->stats;
    CHECK(strcmp(S->stop_reason, "stable") == 0);
    CHECK(S->stability <= 1e-4);
    CHECK_NEAR(S->sample_porosity, target, 0.005);
    CHECK_NEAR(S->porosity, target, 0.005);
    for (size_t k = 0; k < S->psd.n; k++)
        CHECK_NEAR(S->psd.achieved_weight[k], S->psd.target_weight[k], 3.0);
    /* isotropic-ish fabric: each diagonal term near 1/3, trace 1 */
    CHECK_NEAR(S->fabric[0][0] + S->fabric[1][1] + S->fabric[2][2], 1.0, 1e-12);
    for (int a = 0; a < 3; a++)
        CHECK_NEAR(S->fabric[a][a], 1.0 / 3.0, 0.04);
    /* a stable frictional packing: 4 (the paper's "sufficient") to 7 contacts per sphere */
    CHECK(S->coordination_number > 4.0 && S->coordination_number < 7.0);
    /* stress: compressive, vertical at least the weight of the grains over half the height */
    CHECK(S->stress[2][2] > 0 && S->stress[0][0] > 0 && S->stress[1][1] > 0);
    /* spheres inside the box up to their wall overlaps */
    size_t out = spheres_outside(r);
    if (out) fprintf(stderr, "spheres out: %zu (n %zu)\n", out, r->count);
    CHECK(out == 0);
}

/* builds s (GP_OK expected) and checks the specimen against its target porosity; NULL when
 * there is none */
static gp_specimen3d *build_and_check(const gp_spec3d *s)
{
    gp_specimen3d *r = NULL;
    gp_error e;
    CHECK(gp_specimen3d_build(s, NULL, NULL, NULL, &r, &e) == GP_OK);
    if (r)
        check_specimen(r, s->porosity);
    return r;
}

/* The time step of each DEM phase, recomputed from the spheres (untiled: their full radii)
 * and the scaling radius: dt = 0.4 tmin (1.7 / (1 + c))^0.45, c the phase's damping (the
 * material's 0.2 in deposition and compaction, 0.7 in relaxation), tmin = min sqrt(m_i /
 * (2 E R_i)) with the density-scaled masses (gp_dem3d.h; DT_SAFETY and DT_DAMPING_EXP of
 * gp_specimen3d.c), and the fraction of its own limit below 1 in each phase without a cut. */
static void check_phase_steps(const gp_specimen3d *r, const gp_spec3d *s)
{
    const gp_stats3d *S = &r->stats;
    double rs = S->scaled_radius, tmin = INFINITY, rho = s->material.density;
    for (size_t i = 0; i < r->count; i++) {
        double R = r->spheres[4 * i + 3];
        double mi = R < rs ? 4.0 / 3.0 * M_PI * rs * rs * rs * rho * R / rs
                           : 4.0 / 3.0 * M_PI * R * R * R * rho;
        tmin = fmin(tmin, sqrt(mi / (2 * s->material.young * R)));
    }
    const double c[3] = {s->material.damping, s->material.damping, 0.7};
    for (int k = 0; k < 3; k++) {
        CHECK_REL(S->phase_dt[k], 0.4 * tmin * pow(1.7 / (1 + c[k]), 0.45), 1e-9);
        CHECK(S->phase_steps[k] > 0);
        CHECK(S->phase_dt_ratio[k] > 0.3 && S->phase_dt_ratio[k] < 1);
    }
    CHECK(S->phase_steps[0] + S->phase_steps[1] + S->phase_steps[2] == S->steps);
    CHECK(S->dt == S->phase_dt[2]);
    CHECK(S->dt_cuts == 0);
    printf("phase steps: %ld / %ld / %ld, dt %.3g / %.3g / %.3g s, fraction of the limit "
           "%.3f / %.3f / %.3f\n", S->phase_steps[0], S->phase_steps[1], S->phase_steps[2],
           S->phase_dt[0], S->phase_dt[1], S->phase_dt[2], S->phase_dt_ratio[0],
           S->phase_dt_ratio[1], S->phase_dt_ratio[2]);
}

/* the spheres of tiles [1, 3) on every axis of a 4 x 4 x 4 tiling (t n + i), moved by -1 tile:
 * the central block where the final packing's g(r) is measured */
static double *central_block(const gp_specimen3d *rt, size_t n, size_t *m)
{
    double *x = malloc(8 * 4 * n * sizeof *x);
    *m = 0;
    for (size_t t = 0; x && t < 64; t++) {
        size_t k[3] = {t % 4, (t / 4) % 4, t / 16};
        if (k[0] < 1 || k[0] > 2 || k[1] < 1 || k[1] > 2 || k[2] < 1 || k[2] > 2)
            continue;
        for (size_t i = 0; i < n; i++, (*m)++) {
            const double *q = rt->spheres + 4 * (t * n + i);
            for (int a = 0; a < 3; a++)
                x[4 * *m + a] = q[a] - rt->sample_box[a];
            x[4 * *m + 3] = q[3];
        }
    }
    return x;
}

/* stats.transfer of rt (spec s tiled 4 x 4 x 4) against r (s untiled: the same sample): the
 * final side's porosity, coordination and fabric are rt's own stats; the sample side is
 * gp_transfer_measure on r's spheres and contacts; the final g(r) that of the central
 * 2 x 2 x 2 tiles; the diff gp_transfer_compare's */
static void check_transfer(const gp_specimen3d *r, const gp_specimen3d *rt, const gp_spec3d *s)
{
    const gp_transfer_side *A = rt->transfer_sample, *F = rt->transfer_final;
    CHECK(A != NULL && F != NULL);
    if (!A || !F)
        return;
    CHECK_NEAR(F->porosity, rt->stats.porosity, 1e-15);
    CHECK(F->coordination == rt->stats.coordination_number);
    CHECK(F->coordination_spheres == rt->stats.coordination_spheres);
    CHECK(memcmp(F->fabric, rt->stats.fabric, sizeof F->fabric) == 0);
    CHECK(F->n == rt->count && A->n == r->count);
    CHECK(rt->transfer_diff.porosity <= 1e-12 && rt->transfer_diff.coordination == 0);
    /* the sample side, measured here */
    double sieve[3];
    for (size_t k = 0; k < s->nsieve; k++)
        sieve[k] = s->sieve[k].diameter;
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    par.sieve = sieve;
    par.nsieve = s->nsieve;
    par.r_max = A->r_max;
    par.dr = 0.05;
    CHECK(A->r_max == 5.0 && A->nbins == 100 && A->dr == 0.05 && A->unit == A->d50);
    gp_transfer_packing p = {.xyzr = r->spheres, .n = r->count,
                             .contact_kind = GP_TRANSFER_CONTACTS_GIVEN, .contacts = r->contacts,
                             .ncontacts = r->ncontacts};
    memcpy(p.box, r->box, sizeof p.box);
    gp_transfer_side *mine = malloc(sizeof *mine);
    gp_error e;
    CHECK(mine && gp_transfer_measure(&p, &par, mine, &e) == GP_OK);
    if (mine)
        CHECK(memcmp(mine, A, sizeof *mine) == 0);
    /* the final g(r): the central block's, in units of the sample's d50 */
    for (int a = 0; a < 3; a++)
        CHECK(rt->transfer_block[a] == 2 && rt->transfer_block_origin[a] == 1);
    CHECK(rt->transfer_block_spheres == 8 * r->count);
    size_t m = 0;
    double *bx = central_block(rt, r->count, &m);
    gp_transfer_packing pb = {.xyzr = bx, .n = m, .contact_kind = GP_TRANSFER_CONTACTS_GIVEN};
    for (int a = 0; a < 3; a++)
        pb.box[a] = 2 * rt->sample_box[a];
    par.unit = A->d50;
    CHECK(mine && bx && gp_transfer_measure(&pb, &par, mine, &e) == GP_OK);
    if (mine && bx) {
        CHECK(F->nbins == A->nbins && F->unit == A->unit && F->r_max == A->r_max);
        CHECK(memcmp(F->g, mine->g, sizeof F->g) == 0);
        CHECK(memcmp(F->pairs, mine->pairs, sizeof F->pairs) == 0);
        CHECK(memcmp(F->g_mirror, mine->g_mirror, sizeof F->g_mirror) == 0);
    }
    gp_transfer_diff d;
    CHECK(gp_transfer_compare(A, F, &d, &e) == GP_OK);
    CHECK(memcmp(&d, &rt->transfer_diff, sizeof d) == 0);
    /* the PSD of the flip is the sample's (by number, exactly) */
    for (size_t k = 0; k < A->nsieve; k++)
        CHECK(F->psd_number[k] == A->psd_number[k]);
    printf("transfer, 4x4x4 of %zu spheres: g(r) largest difference %.3f at %.3f d50 (rms %.3f) "
           "on the central %zu spheres, %.3f s\n", r->count, d.rdf, d.rdf_r, d.rdf_rms, m,
           rt->t_transfer);
    free(bx);
    free(mine);
}

static void test_small_and_tiled(void)
{
    gp_spec3d s;
    spec_in_cube(&s, 0.06, SMALL, 3, 0.42);
    s.seed = 11;
    s.outputs = GP_OUT3_SPHERES | GP_OUT3_FABRIC | GP_OUT3_STRESS | GP_OUT3_CONTACTS;
    gp_specimen3d *r = build_and_check(&s);
    if (!r)
        return;
    CHECK(r->count == r->stats.sample_particles);
    CHECK(r->ncontacts == r->stats.contacts + r->stats.wall_contacts);
    check_phase_steps(r, &s);
    /* the same spec tiled 4 x 4 x 4: porosity within 0.002, fabric within 0.01, z kept */
    gp_spec3d t = s;
    t.tiling[0] = t.tiling[1] = t.tiling[2] = 4;
    gp_specimen3d *rt = NULL;
    gp_error e;
    CHECK(gp_specimen3d_build(&t, NULL, NULL, NULL, &rt, &e) == GP_OK);
    if (rt) {
        CHECK(rt->count == 64 * r->count);
        CHECK_NEAR(rt->box[2], 4 * r->box[2], 1e-12);
        CHECK_NEAR(rt->stats.porosity, r->stats.porosity, 0.002);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                CHECK_NEAR(rt->stats.fabric[a][b], r->stats.fabric[a][b], 0.01);
        CHECK_NEAR(rt->stats.coordination_number, r->stats.coordination_number, 1e-9);
        for (int a = 0; a < 3; a++)
            CHECK_REL(rt->stats.stress[a][a], r->stats.stress[a][a], 1e-6);
        /* the sample inside is the same packing, bit for bit (tile 0 is the sample) */
        CHECK(memcmp(rt->spheres, r->spheres, 4 * r->count * sizeof(double)) == 0);
        check_transfer(r, rt, &s);
    }
    /* untiled: no transfer */
    CHECK(r->transfer_sample == NULL && r->transfer_final == NULL);
    gp_specimen3d_destroy(rt);
    gp_specimen3d_destroy(r);
}

static void test_threads_deterministic(void)
{
    gp_spec3d s;
    short_spec(&s);
    gp_specimen3d *a = NULL, *b = NULL;
    gp_error e;
    s.threads = 1;
    gp_status sa = gp_specimen3d_build(&s, NULL, NULL, NULL, &a, &e);
    s.threads = 2;
    gp_status sb = gp_specimen3d_build(&s, NULL, NULL, NULL, &b, &e);
    CHECK(sa == sb);
    CHECK(a != NULL && b != NULL);
    if (a && b) {
        CHECK(a->count == b->count);
        CHECK(memcmp(a->spheres, b->spheres, 4 * a->count * sizeof(double)) == 0);
        CHECK(a->stats.steps == b->stats.steps);
    }
    gp_specimen3d_destroy(a);
    gp_specimen3d_destroy(b);
}

static void test_one_size(void)
{
    /* one-size spheres (a 1e-6 wide bin), 8 mm, porosity 0.45 (7.5 grains between walls: the
     * frictionless packing of this box stalls near 0.43) */
    gp_spec3d s;
    spec_in_cube(&s, 0.06, ONE_SIZE_8MM, 2, 0.45);
    s.outputs = GP_OUT3_SPHERES | GP_OUT3_FABRIC | GP_OUT3_STRESS;
    gp_specimen3d *r = build_and_check(&s);
    gp_specimen3d_destroy(r);
    /* one-size at 0.20: denser than any random packing of equal spheres (and than FCC, 0.2595):
     * a clear reason, quickly, not a hang */
    s.porosity = 0.20;
    r = NULL;
    gp_error e;
    double t0 = gp_clock_seconds();
    gp_status st = gp_specimen3d_build(&s, NULL, NULL, NULL, &r, &e);
    CHECK(st == GP_ERR_INFEASIBLE);
    CHECK(gp_clock_seconds() - t0 < 60);
    CHECK(strstr(e.message, "denser") != NULL);
    CHECK(r != NULL);
    if (r) {
        CHECK(strcmp(r->stats.stop_reason, "target_too_dense") == 0);
        /* what it reached: about the frictionless packing of equal spheres in this box */
        CHECK(r->stats.sample_porosity > 0.36 && r->stats.sample_porosity < 0.48);
    }
    gp_specimen3d_destroy(r);
}

static int cancel_at_compaction(void *user, const gp_progress *p)
{
    int *seen = user;
    (*seen)++;
    return strcmp(p->phase, "compaction") == 0;
}

static void test_errors(void)
{
    gp_spec3d s;
    gp_spec3d_defaults(&s);
    gp_specimen3d *r = (gp_specimen3d *)&s;
    gp_error e;
    /* a box smaller than the largest grain (100 mm) */
    s.box[2] = 0.09;
    CHECK(gp_specimen3d_build(&s, NULL, NULL, NULL, &r, &e) == GP_ERR_INVALID);
    CHECK(r == NULL);
    CHECK(strstr(e.message, "largest grain") != NULL);
    gp_spec3d_defaults(&s);
    s.porosity = 1.0;
    CHECK(gp_specimen3d_build(&s, NULL, NULL, NULL, &r, &e) == GP_ERR_INVALID);
    gp_spec3d_defaults(&s);
    s.tiling[1] = 0;
    CHECK(gp_specimen3d_build(&s, NULL, NULL, NULL, &r, &e) == GP_ERR_INVALID);
    gp_spec3d_defaults(&s);
    static const gp_sieve_row bad[2] = {{0.01, 5}, {0.02, 100}};
    s.sieve = bad;
    s.nsieve = 2;
    CHECK(gp_specimen3d_build(&s, NULL, NULL, NULL, &r, &e) == GP_ERR_INVALID);
    /* cancelled from the progress callback */
    spec_in_cube(&s, 0.06, SMALL, 3, 0.38); /* 0.38: the default */
    int seen = 0;
    CHECK(gp_specimen3d_build(&s, cancel_at_compaction, &seen, NULL, &r, &e) == GP_ERR_CANCELLED);
    CHECK(r == NULL && seen > 0);
    volatile int flag = 1;
    CHECK(gp_specimen3d_build(&s, NULL, NULL, &flag, &r, &e) == GP_ERR_CANCELLED);
}

/* the measures of a tiled packing are summed over its contacts as they are streamed from the
 * flip: asking for the contact list (which is then collected too) changes no bit of them;
 * untiled, tiled (3 x 2 x 2), and with a raised cancel flag in the tiling phase */
static int raise_at_tiling(void *user, const gp_progress *p)
{
    if (strcmp(p->phase, "tiling") == 0)
        __atomic_store_n((int *)user, 1, __ATOMIC_RELAXED);
    return 0;
}

static void test_contacts_output_invariant(void)
{
    gp_spec3d s;
    short_spec(&s); /* NOT_CONVERGED is fine: the specimen is still tiled and measured */
    const int tilings[2][3] = {{1, 1, 1}, {3, 2, 2}};
    for (int k = 0; k < 2; k++) {
        memcpy(s.tiling, tilings[k], sizeof s.tiling);
        gp_specimen3d *a = NULL, *b = NULL;
        gp_error e;
        s.outputs = GP_OUT3_FABRIC | GP_OUT3_STRESS;
        gp_status sa = gp_specimen3d_build(&s, NULL, NULL, NULL, &a, &e);
        s.outputs = GP_OUT3_FABRIC | GP_OUT3_STRESS | GP_OUT3_CONTACTS | GP_OUT3_SPHERES;
        gp_status sb = gp_specimen3d_build(&s, NULL, NULL, NULL, &b, &e);
        CHECK(sa == sb && a && b);
        if (!a || !b) {
            gp_specimen3d_destroy(a);
            gp_specimen3d_destroy(b);
            continue;
        }
        const gp_stats3d *A = &a->stats, *B = &b->stats;
        CHECK(memcmp(A->fabric, B->fabric, sizeof A->fabric) == 0);
        CHECK(memcmp(A->stress, B->stress, sizeof A->stress) == 0);
        CHECK(memcmp(&A->coordination_number, &B->coordination_number, sizeof(double)) == 0);
        CHECK(memcmp(&A->coordination_spheres, &B->coordination_spheres, sizeof(double)) == 0);
        CHECK(A->contacts == B->contacts && A->wall_contacts == B->wall_contacts);
        CHECK(a->contacts == NULL && a->ncontacts == 0 && a->spheres == NULL);
        CHECK(b->ncontacts == B->contacts + B->wall_contacts);
        CHECK(a->count == b->count && a->count == (k ? 12 : 1) * A->sample_particles);
        CHECK(A->stress[2][2] > 0 && A->fabric[2][2] > 0.2);
        /* the list: sphere pairs (i < j, sorted by (i, j)), then wall contacts; indices in
         * range; z and the counts follow from it */
        size_t pairs = 0, order = 0, range = 0;
        for (size_t q = 0; q < b->ncontacts; q++) {
            const gp_contact3d *c = b->contacts + q;
            if (c->j >= 0) {
                pairs++;
                range += c->i >= (size_t)c->j || (size_t)c->j >= b->count;
                if (q > 0 && (b->contacts[q - 1].i > c->i ||
                              (b->contacts[q - 1].i == c->i && b->contacts[q - 1].j >= c->j)))
                    order++;
            } else {
                range += c->j < -6 || c->i >= b->count;
            }
        }
        CHECK(pairs == B->contacts && order == 0 && range == 0);
        CHECK_NEAR(B->coordination_number,
                   (2.0 * (double)pairs + (double)(b->ncontacts - pairs)) / (double)b->count,
                   1e-12);
        gp_specimen3d_destroy(a);
        gp_specimen3d_destroy(b);
    }
    /* a flag raised in the tiling phase: cancelled, nothing returned (ASan: nothing leaked) */
    volatile int flag = 0;
    gp_specimen3d *r = NULL;
    gp_error e;
    s.outputs = GP_OUT3_FABRIC | GP_OUT3_STRESS;
    CHECK(gp_specimen3d_build(&s, raise_at_tiling, (void *)&flag, &flag, &r, &e) == GP_ERR_CANCELLED);
    CHECK(r == NULL && flag == 1);
}

/* stats.transfer of a tiling the same bit for bit for 1 and 2 threads (3 x 2 x 2: the block
 * is 2 x 2 x 2 from tile 0), and of a relaxed tiling measured on the DEM's own contacts */
static void test_transfer_threads_relaxed(void)
{
    gp_spec3d s;
    short_spec(&s);
    s.tiling[0] = 3;
    s.tiling[1] = s.tiling[2] = 2;
    s.outputs = GP_OUT3_FABRIC;
    gp_specimen3d *a = NULL, *b = NULL;
    gp_error e;
    s.threads = 1;
    gp_specimen3d_build(&s, NULL, NULL, NULL, &a, &e);
    s.threads = 2;
    gp_specimen3d_build(&s, NULL, NULL, NULL, &b, &e);
    CHECK(a && b && a->transfer_sample && b->transfer_sample && a->transfer_final &&
          b->transfer_final);
    if (a && b && a->transfer_sample && b->transfer_sample && a->transfer_final &&
        b->transfer_final) {
        CHECK(memcmp(a->transfer_sample, b->transfer_sample, sizeof *a->transfer_sample) == 0);
        CHECK(memcmp(a->transfer_final, b->transfer_final, sizeof *a->transfer_final) == 0);
        CHECK(memcmp(&a->transfer_diff, &b->transfer_diff, sizeof a->transfer_diff) == 0);
        CHECK(a->transfer_block[0] == 2 && a->transfer_block_origin[0] == 0);
        CHECK(a->transfer_block_spheres == 8 * a->stats.sample_particles);
        CHECK(a->transfer_final->coordination == a->stats.coordination_number);
    }
    gp_specimen3d_destroy(a);
    gp_specimen3d_destroy(b);
    /* relaxed by the DEM: the tiling's own contacts, the whole tiling (2 x 1 x 1) */
    s.tiling[0] = 2;
    s.tiling[1] = s.tiling[2] = 1;
    s.tile_relax_steps = 300;
    gp_specimen3d *c = NULL;
    gp_specimen3d_build(&s, NULL, NULL, NULL, &c, &e);
    CHECK(c && c->transfer_final);
    if (c && c->transfer_final) {
        const gp_transfer_side *F = c->transfer_final;
        CHECK(F->coordination == c->stats.coordination_number);
        CHECK(F->coordination_spheres == c->stats.coordination_spheres);
        CHECK(memcmp(F->fabric, c->stats.fabric, sizeof F->fabric) == 0);
        CHECK_NEAR(F->porosity, c->stats.porosity, 1e-15);
        CHECK(c->transfer_block_spheres == c->count && c->transfer_block[0] == 2);
    }
    gp_specimen3d_destroy(c);
}

#ifndef GP_SANITIZED
static void test_paper_example(void)
{
    gp_spec3d s;
    gp_spec3d_defaults(&s); /* 0.5 m cube, Table 1, Table 2, porosity 0.38 */
    s.seed = 7;
    s.outputs = GP_OUT3_SPHERES | GP_OUT3_FABRIC | GP_OUT3_STRESS;
    gp_specimen3d *r = build_and_check(&s);
    if (!r)
        return;
    /* the count follows from V_s = 0.62 * 0.125 m^3 and Table 2 (test_sieve: 2429.6) */
    CHECK(r->stats.sample_particles == 2430);
    /* phase 0: a poured packing, looser than the target (paper: 0.43) */
    CHECK(r->stats.deposition_porosity > 0.40 && r->stats.deposition_porosity < 0.47);
    printf("paper example: %zu spheres, porosity %.4f, z %.3f, fabric %.4f %.4f %.4f, Sc %.2g, "
           "%ld steps, %.2f s\n", r->count, r->stats.porosity, r->stats.coordination_number,
           r->stats.fabric[0][0], r->stats.fabric[1][1], r->stats.fabric[2][2], r->stats.stability,
           r->stats.steps, r->t_total);
    gp_specimen3d_destroy(r);
}
#endif

int main(void)
{
    test_errors();
    test_small_and_tiled();
    test_threads_deterministic();
    test_contacts_output_invariant();
    test_transfer_threads_relaxed();
    test_one_size();
#ifndef GP_SANITIZED
    test_paper_example();
#endif
    return gp_test_summary();
}
