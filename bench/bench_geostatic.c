/* bench_geostatic.c -- the geostatic state of the paper's final packing (Dang & Meguid 2010,
 * "Stress Distribution", Fig. 8): S0 built with the gp_specimen3d defaults (0.5 m cube, Tables
 * 1 and 2, porosity 0.38) at seed 7, tiled N x N x N by gp_flip (4: ~155,000 spheres, the
 * paper's 2 m cube), settled at rest under gravity in its box (gp_geostatic_run) and measured
 * in slabs of 5 d50. Prints one table: spheres, steps, seconds, S_c reached, peak memory
 * (getrusage), K0 mean / sd against 1 - sin 23.7 deg, the equilibrium error (slab sigma_v
 * against the weight above) and the whole packing's Love-Weber stress against its walls.
 * Usage: bench_geostatic [threads] [--tiling N] [--profile] [--trace]. --profile adds the
 * profile per slab and the sigma_v map (cells of the sample's size) after the table; --trace
 * prints S_c at every progress report to stderr (else every 30 s).
 */
#include "gp_clock.h"
#include "gp_flip.h"
#include "gp_geostatic.h"
#include "gp_specimen3d.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double peak_mb(void)
{
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return (double)u.ru_maxrss / 1024.0; /* KB on Linux */
}

static int trace = 0;

static int progress(void *user, const gp_progress *p)
{
    double *last = user;
    double t = gp_clock_seconds();
    if (trace || t - *last > 30) {
        fprintf(stderr, "  %s: %ld steps, S_c %.3g\n", p->phase, p->steps, p->stability);
        *last = t;
    }
    return 0;
}

int main(int argc, char **argv)
{
    int threads = 1, tiling = 4, profile = 0;
    for (int a = 1; a < argc; a++) {
        if (strcmp(argv[a], "--tiling") == 0 && a + 1 < argc)
            tiling = atoi(argv[++a]);
        else if (strcmp(argv[a], "--profile") == 0)
            profile = 1;
        else if (strcmp(argv[a], "--trace") == 0)
            trace = 1;
        else
            threads = atoi(argv[a]);
    }
    if (tiling < 1 || tiling > 16 || threads < 1) {
        fprintf(stderr, "usage: bench_geostatic [threads] [--tiling N] [--profile]\n");
        return 2;
    }
    gp_spec3d s;
    gp_spec3d_defaults(&s);
    s.seed = 7;
    s.threads = threads;
    s.outputs = GP_OUT3_SPHERES | GP_OUT3_STRESS; /* (the measures do not change the build) */
    gp_specimen3d *sp = NULL;
    gp_error e;
    double t0 = gp_clock_seconds();
    gp_status st = gp_specimen3d_build(&s, NULL, NULL, NULL, &sp, &e);
    if (!sp) {
        printf("build failed: %s\n", e.message);
        return 1;
    }
    double t_build = gp_clock_seconds() - t0;
    int tiles[3] = {tiling, tiling, tiling};
    double *x = NULL;
    size_t n = 0;
    t0 = gp_clock_seconds();
    if (gp_flip_tile(sp->spheres, sp->count, sp->box, tiles, 50000000, NULL, &x, &n, &e)) {
        printf("tiling failed: %s\n", e.message);
        return 1;
    }
    double t_tile = gp_clock_seconds() - t0;
    double lo[3] = {0, 0, 0}, hi[3];
    for (int a = 0; a < 3; a++)
        hi[a] = sp->box[a] * tiling;
    gp_geostatic_params p;
    gp_geostatic_params_defaults(&p);
    p.material = s.material;
    p.threads = threads;
    p.map_cell = sp->box[0]; /* the sample's size: the seams show */
    gp_geostatic_result *r = NULL;
    double last = gp_clock_seconds(), c0 = cpu_seconds();
    gp_status gs = gp_geostatic_run(&p, x, n, lo, hi, progress, &last, NULL, &r, &e);
    double cpu = cpu_seconds() - c0;
    if (!r) {
        printf("geostatic failed: %s\n", e.message);
        return 1;
    }
    const gp_stats3d *S = &sp->stats;
    printf("## geostatic state, S0 (seed 7, %s, %.0f s; as built: Love-Weber xx %.0f yy %.0f zz "
           "%.0f Pa, K %.3f, friction at the target porosity %.2f deg) tiled %dx%dx%d (%.2f s), "
           "%d thread%s: %s\n", st ? gp_status_name(st) : "built", t_build, S->stress[0][0],
           S->stress[1][1], S->stress[2][2], 0.5 * (S->stress[0][0] + S->stress[1][1]) /
           S->stress[2][2], S->compaction_friction_deg, tiling, tiling, tiling, t_tile, threads,
           threads > 1 ? "s" : "", gs ? e.message : "at rest");
    printf("| spheres | steps | dt (us) | settling s | CPU s | measure s | S_c | S_c of the list "
           "| peak MB | K0 mean | K0 sd | slabs | 1 - sin 23.7 | K0 bulk | K0 full-width mean | "
           "equilibrium error | core error | Love-Weber vs walls | dt cuts |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    double kf = 0;
    size_t nkf = 0;
    for (size_t k = 0; k < r->profile.n; k++)
        if (r->profile.k0_counted[k]) {
            kf += r->profile.k0_full[k];
            nkf++;
        }
    printf("| %zu | %ld | %.1f | %.1f | %.1f | %.2f | %.2g | %.2g | %.0f | %.3f | %.3f | %zu "
           "| %.3f | %.3f | %.3f | %.2f %% | %.2f %% | %.3f %% | %ld |\n", r->n, r->steps,
           1e6 * r->dt, r->seconds_settling, cpu, r->seconds_measure, r->stability,
           r->stability_list, peak_mb(),
           r->k0.mean, r->k0.sd, r->k0.slabs, r->k0.theory, r->k0.bulk, nkf ? kf / nkf : NAN,
           100 * r->equilibrium.max_error, 100 * r->equilibrium.core_max_error,
           100 * r->whole.max_error, r->dt_cuts);
    if (profile) {
        const gp_geostatic_profile *q = &r->profile;
        printf("\n| depth m | sigma_xx kPa | sigma_yy | sigma_zz | weight | sigma_zz full | K0 | "
               "K0 full | porosity | Z | counted |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|\n");
        for (size_t k = 0; k < q->n; k++)
            printf("| %.3f | %.2f | %.2f | %.2f | %.2f | %.2f | %.3f | %.3f | %.3f | %.2f "
                   "| %s%s |\n",
                   q->depth[k], q->sigma_xx[k] / 1e3, q->sigma_yy[k] / 1e3, q->sigma_zz[k] / 1e3,
                   q->weight[k] / 1e3, q->sigma_zz_full[k] / 1e3, q->k0[k], q->k0_full[k],
                   q->porosity[k], q->coordination[k], q->k0_counted[k] ? "K0" : "",
                   q->equilibrium_counted[k] ? " eq" : "");
        const gp_geostatic_map *m = &r->map;
        printf("\nsigma_v map (kPa), %zu x %zu cells of %.3f x %.3f m, row 0 at the top:\n", m->nx,
               m->nz, m->dx, m->dz);
        for (size_t z = 0; z < m->nz; z++) {
            for (size_t c = 0; c < m->nx; c++)
                printf(" %7.2f", m->sigma_v[z * m->nx + c] / 1e3);
            printf("\n");
        }
        printf("sigma_h / sigma_v per cell:\n");
        for (size_t z = 0; z < m->nz; z++) {
            for (size_t c = 0; c < m->nx; c++)
                printf(" %6.3f", m->sigma_h[z * m->nx + c] / m->sigma_v[z * m->nx + c]);
            printf("\n");
        }
        printf("whole: Love-Weber %.1f %.1f %.1f Pa, walls %.1f %.1f %.1f Pa, porosity %.4f, "
               "Z %.3f, surface %.4f m, friction mobilised %.3f, sliding %.3f\n",
               r->whole.love_weber[0][0], r->whole.love_weber[1][1], r->whole.love_weber[2][2],
               r->whole.walls[0], r->whole.walls[1], r->whole.walls[2], r->whole.porosity,
               r->whole.coordination, r->whole.surface, r->whole.friction_mobilised,
               r->whole.sliding);
    }
    gp_geostatic_result_destroy(r);
    free(x);
    gp_specimen3d_destroy(sp);
    return gs != GP_OK;
}
