/* bench_spheres3d.c -- the paper's 3D example (Dang & Meguid 2010: 0.5 m cube, Table 1,
 * Table 2, porosity 0.38) timed per phase, the DEM's sphere-steps per second, and the flip
 * tiling to 4 x 4 x 4 and to ~230,000 spheres, with the porosity and PSD errors next to the
 * timings; then a size ratio of 20 (1-20 mm, issue #6) the same way.
 * Usage: bench_spheres3d [threads] [seed] [--sample], or [threads] --phases. --sample: the
 * paper's sample only, one table row (wall and CPU seconds, steps, sphere-steps/s, S_c,
 * porosity, PSD error, z, and the DEM's time step of the relaxation: below DT_SAFETY's when
 * the stability check had to cut it), the row bench/bench_peers.py reads (by column name).
 * bench_spheres3d [threads] --phases: the DEM per phase, one table: the paper's sample at
 * seeds 0-9, the small specs of the integration tests (1-2 mm at porosity 0.5 and 0.45, at
 * the seeds they use) and the three 1-20 mm cases below, each with its steps, time step and
 * largest fraction of the proven stability limit per phase (deposition / compaction /
 * relaxation), the DEM's cuts of dt, wall seconds, S_c, porosity, z, PSD error and how it
 * stopped; then the paper's mean and largest steps over the ten seeds. */
#include "gp_clock.h"
#include "gp_dem3d.h"
#include "gp_flip.h"
#include "gp_specimen3d.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double psd_error(const gp_stats3d *S)
{
    double werr = 0;
    for (size_t k = 0; k < S->psd.n; k++)
        werr = fmax(werr, fabs(S->psd.achieved_weight[k] - S->psd.target_weight[k]));
    return werr;
}

/* The specimen of spec s, timed: *cpu the process CPU seconds of the build, *st its status
 * (and e its message); NULL (after printing why) when there is nothing to report. */
static gp_specimen3d *build_timed(const gp_spec3d *s, double *cpu, gp_status *st, gp_error *e)
{
    gp_specimen3d *r = NULL;
    double c0 = cpu_seconds();
    *st = gp_specimen3d_build(s, NULL, NULL, NULL, &r, e);
    *cpu = cpu_seconds() - c0;
    if (!r)
        printf("build failed: %s\n", e->message);
    return r;
}

/* the DEM's millions of sphere-steps per second over its three phases */
static double dem_rate(const gp_specimen3d *r)
{
    double dem = r->t_deposition + r->t_compaction + r->t_relaxation;
    return r->stats.steps * (double)r->stats.sample_particles / dem / 1e6;
}

/* --sample: the paper's sample alone, one row */
static int sample_row(int threads, unsigned long long seed)
{
    gp_spec3d s;
    gp_spec3d_defaults(&s);
    s.threads = threads;
    s.seed = seed;
    double cpu;
    gp_status st;
    gp_error e;
    gp_specimen3d *r = build_timed(&s, &cpu, &st, &e);
    if (!r)
        return 1;
    const gp_stats3d *S = &r->stats;
    printf("| code | threads | spheres | steps | wall s | CPU s | M sphere-steps/s | S_c | stop | "
           "porosity | porosity error | max PSD error (pp) | z | dt (us) |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    printf("| grainpack | %d | %zu | %ld | %.3f | %.3f | %.2f | %.3g | %s%s%s | %.4f | %+.1e | %.2g | %.3f | %.2f |\n",
           threads, S->sample_particles, S->steps, r->t_total, cpu, dem_rate(r), S->stability,
           S->stop_reason, st ? ": " : "", st ? e.message : "", S->porosity,
           S->porosity - S->porosity_target, psd_error(S), S->coordination_number, 1e6 * S->dt);
    gp_specimen3d_destroy(r);
    return st != GP_OK;
}

static const gp_sieve_row WIDE[4] = {{0.001, 0}, {0.005, 1}, {0.010, 10}, {0.020, 100}};
static const double WIDE_CASES[3][2] = {{0.1, 0.46}, {0.1, 0.42}, {0.15, 0.42}};

/* the spec of WIDE_CASES[b] (seed 1, no outputs) */
static gp_spec3d wide_case(int b, int threads)
{
    gp_spec3d w;
    gp_spec3d_defaults(&w);
    w.threads = threads;
    w.seed = 1;
    w.box[0] = w.box[1] = w.box[2] = WIDE_CASES[b][0];
    w.sieve = WIDE;
    w.nsieve = 4;
    w.porosity = WIDE_CASES[b][1];
    w.outputs = 0;
    return w;
}

/* the small 3D specs of the integration tests (tests/integration: gpd.SMALL_3D, 1-2 mm in a
 * 6 mm box at porosity 0.5, at the default seed 0, seed 7 and test_exports' seeds at its
 * density; test_cancel_phases' 12 mm box at 0.45) */
static const gp_sieve_row SMALL[2] = {{0.001, 0}, {0.002, 100}};
static const struct { unsigned long long seed; double box, porosity, density; } SMALL_CASES[] = {
    {0, 0.006, 0.5, 2600},   {7, 0.006, 0.5, 2600},   {3, 0.006, 0.5, 2650.5},
    {7, 0.006, 0.5, 2650.5}, {11, 0.006, 0.5, 2650.5}, {1, 0.006, 0.5, 2650.5},
    {2, 0.006, 0.5, 2650.5}, {5, 0.006, 0.5, 2650.5}, {13, 0.006, 0.5, 2650.5},
    {7, 0.012, 0.45, 2600}};

/* per-row sums for the paper's rows: steps per phase, all */
typedef struct phase_sum { long n, steps[4], max_steps; double ratio[3]; } phase_sum;

/* one row of --phases: the build of s, per phase; the paper's rows also into *sum */
static void phase_row(const char *name, const gp_spec3d *s, phase_sum *sum)
{
    double cpu;
    gp_status st;
    gp_error e;
    gp_specimen3d *r = build_timed(s, &cpu, &st, &e);
    if (!r)
        return;
    const gp_stats3d *S = &r->stats;
    printf("| %s | %zu | %ld / %ld / %ld = %ld | %.2f / %.2f / %.2f | %.3f / %.3f / %.3f | %ld "
           "| %.3f | %.3g | %.4f (%+.1e) | %.3f | %.2g | %s |\n", name, S->sample_particles,
           S->phase_steps[0], S->phase_steps[1], S->phase_steps[2], S->steps,
           1e6 * S->phase_dt[0], 1e6 * S->phase_dt[1], 1e6 * S->phase_dt[2],
           S->phase_dt_ratio[0], S->phase_dt_ratio[1], S->phase_dt_ratio[2], S->dt_cuts,
           r->t_total, S->stability, S->porosity, S->porosity - S->porosity_target,
           S->coordination_number, psd_error(S), S->stop_reason);
    if (sum) {
        sum->n++;
        for (int k = 0; k < 3; k++) {
            sum->steps[k] += S->phase_steps[k];
            sum->ratio[k] = fmax(sum->ratio[k], S->phase_dt_ratio[k]);
        }
        sum->steps[3] += S->steps;
        if (S->steps > sum->max_steps) sum->max_steps = S->steps;
    }
    gp_specimen3d_destroy(r);
}

/* --phases: the paper's sample at seeds 0-9, the integration tests' small specs and the
 * 1-20 mm cases, one table; then the paper's mean and max */
static int phases_table(int threads)
{
    printf("| case | spheres | steps dep / comp / relax = all | dt (us) dep / comp / relax | "
           "max fraction of the limit dep / comp / relax | cuts | wall s | S_c | porosity "
           "(error) | z | max PSD error (pp) | stop |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    phase_sum sum = {0};
    for (unsigned long long seed = 0; seed < 10; seed++) {
        gp_spec3d s;
        gp_spec3d_defaults(&s);
        s.threads = threads;
        s.seed = seed;
        char name[64];
        snprintf(name, sizeof name, "paper, seed %llu", seed);
        phase_row(name, &s, &sum);
    }
    for (size_t k = 0; k < sizeof SMALL_CASES / sizeof *SMALL_CASES; k++) {
        gp_spec3d w;
        gp_spec3d_defaults(&w);
        w.threads = threads;
        w.seed = SMALL_CASES[k].seed;
        w.box[0] = w.box[1] = w.box[2] = SMALL_CASES[k].box;
        w.sieve = SMALL;
        w.nsieve = 2;
        w.porosity = SMALL_CASES[k].porosity;
        w.material.density = SMALL_CASES[k].density;
        w.outputs = 0;
        char name[80];
        snprintf(name, sizeof name, "1-2 mm, %.3f m, %.2f, rho %g, seed %llu", w.box[0],
                 w.porosity, w.material.density, (unsigned long long)w.seed);
        phase_row(name, &w, NULL);
    }
    for (int b = 0; b < 3; b++) {
        gp_spec3d w = wide_case(b, threads);
        char name[64];
        snprintf(name, sizeof name, "1-20 mm, %.2f m, %.2f", WIDE_CASES[b][0], WIDE_CASES[b][1]);
        phase_row(name, &w, NULL);
    }
    double n = sum.n ? (double)sum.n : 1;
    printf("| paper, seeds 0-9: mean | | %.0f / %.0f / %.0f = %.0f (max %ld) | | %.3f / %.3f / "
           "%.3f (max) | | | | | | | |\n", sum.steps[0] / n, sum.steps[1] / n, sum.steps[2] / n,
           sum.steps[3] / n, sum.max_steps, sum.ratio[0], sum.ratio[1], sum.ratio[2]);
    return 0;
}

static void tile_row(const gp_specimen3d *r, const gp_contact3d *c, size_t nc, int nx, int ny,
                     int nz)
{
    int tiles[3] = {nx, ny, nz};
    double t0 = gp_clock_seconds();
    double *t;
    size_t nt;
    gp_contact3d *tc;
    size_t ntc;
    gp_error e;
    if (gp_flip_tile(r->spheres, r->count, r->box, tiles, 50000000, NULL, &t, &nt, &e)
        || gp_flip_contacts(c, nc, r->count, tiles, NULL, &tc, &ntc, &e)) {
        printf("tiling failed: %s\n", e.message);
        return;
    }
    double solid = 0;
    for (size_t k = 0; k < (size_t)nx * ny * nz; k++) {
        size_t kx = k % nx, ky = (k / nx) % ny, kz = k / ((size_t)nx * ny);
        double lo[3] = {kx * r->box[0], ky * r->box[1], kz * r->box[2]};
        double hi[3] = {lo[0] + r->box[0], lo[1] + r->box[1], lo[2] + r->box[2]};
        solid += gp_dem3d_solid_volume(t + 4 * k * r->count, r->count, lo, hi);
    }
    double F[3][3];
    gp_dem3d_fabric(tc, ntc, F);
    double dt = gp_clock_seconds() - t0;
    double por = 1 - solid / (nx * ny * nz * r->box[0] * r->box[1] * r->box[2]);
    printf("| flip %dx%dx%d | %zu spheres, %zu contacts | %.3f s | porosity %.4f (sample %+.1e) | "
           "fabric diag %.4f %.4f %.4f |\n", nx, ny, nz, nt, ntc, dt, por,
           por - r->stats.porosity, F[0][0], F[1][1], F[2][2]);
    free(t);
    free(tc);
}

int main(int argc, char **argv)
{
    gp_spec3d s;
    gp_spec3d_defaults(&s);
    s.threads = argc > 1 ? atoi(argv[1]) : 1;
    s.seed = argc > 2 ? strtoull(argv[2], NULL, 10) : 7;
    if (argc > 3 && strcmp(argv[3], "--sample") == 0)
        return sample_row(s.threads, s.seed);
    if (argc > 2 && strcmp(argv[2], "--phases") == 0)
        return phases_table(s.threads);
    s.outputs = GP_OUT3_SPHERES | GP_OUT3_CONTACTS | GP_OUT3_FABRIC | GP_OUT3_STRESS;
    double cpu;
    gp_status st;
    gp_error e;
    gp_specimen3d *r = build_timed(&s, &cpu, &st, &e);
    if (!r)
        return 1;
    const gp_stats3d *S = &r->stats;
    printf("## spheres-3d, paper example (0.5 m cube, Table 1, Table 2, porosity 0.38), "
           "threads %d, seed %llu: %s%s\n", s.threads, (unsigned long long)s.seed,
           gp_status_name(st), st ? e.message : "");
    printf("| phase | seconds |\n|---|---|\n");
    printf("| deposition | %.2f |\n| compaction | %.2f |\n| relaxation | %.2f |\n| total | %.2f "
           "(CPU %.2f) |\n", r->t_deposition, r->t_compaction, r->t_relaxation, r->t_total, cpu);
    printf("| DEM | %ld steps x %zu spheres, dt %.3g s, %.2f M sphere-steps/s |\n", S->steps,
           S->sample_particles, S->dt, dem_rate(r));
    printf("| result | porosity %.4f (target %.2f, error %+.1e), phase 0 %.3f, S_c %.2g (%s), "
           "z %.3f (spheres only %.3f) |\n", S->porosity, S->porosity_target,
           S->porosity - S->porosity_target, S->deposition_porosity, S->stability,
           S->stop_reason, S->coordination_number, S->coordination_spheres);
    printf("| fabric | xx %.4f yy %.4f zz %.4f xy %+.4f xz %+.4f yz %+.4f |\n", S->fabric[0][0],
           S->fabric[1][1], S->fabric[2][2], S->fabric[0][1], S->fabric[0][2], S->fabric[1][2]);
    printf("| stress (Pa) | xx %.0f yy %.0f zz %.0f |\n", S->stress[0][0], S->stress[1][1],
           S->stress[2][2]);
    printf("| sieve (mm) | target wt | achieved wt | target no. (uniform) | achieved no. | paper no. (mid-bin) |\n");
    for (size_t k = 0; k < S->psd.n; k++)
        printf("| %.0f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", 1000 * S->psd.diameter[k],
               S->psd.target_weight[k], S->psd.achieved_weight[k], S->psd.target_number[k],
               S->psd.achieved_number[k], S->psd.target_number_midbin[k]);
    printf("| PSD | max error by weight %.2g pp |\n", psd_error(S));
    tile_row(r, r->contacts, r->ncontacts, 4, 4, 4);
    tile_row(r, r->contacts, r->ncontacts, 4, 4, 6);
    gp_specimen3d_destroy(r);

    /* size ratio 20: the sieve and seed of tests/core/3d/test_specimen3d_wide.c, at its target 0.46
     * (just below the deposit) and at 0.42, and in a 0.15 m cube (~2,600 spheres) */
    printf("## size ratio 20 (1-20 mm: 1 %% below 5 mm, 10 %% below 10 mm)\n");
    printf("| box (m) | target | spheres | steps | seconds | porosity | S_c | friction at target | "
           "max PSD error (pp) | stop |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (int b = 0; b < 3; b++) {
        gp_spec3d w = wide_case(b, s.threads);
        gp_specimen3d *q = NULL;
        gp_status sq = gp_specimen3d_build(&w, NULL, NULL, NULL, &q, &e);
        if (!q) {
            printf("| %.2f | build failed: %s |\n", w.box[0], e.message);
            continue;
        }
        double we = psd_error(&q->stats);
        printf("| %.2f | %.2f | %zu | %ld | %.2f | %.4f | %.2g | %.2f deg | %.2g | %s%s%s |\n",
               w.box[0], w.porosity, q->count, q->stats.steps, q->t_total, q->stats.porosity,
               q->stats.stability, q->stats.compaction_friction_deg, we, q->stats.stop_reason, sq ? ": " : "",
               sq ? e.message : "");
        gp_specimen3d_destroy(q);
    }
    return 0;
}
