/* bench_imc.c -- IMC speed and convergence, in one table (speed next to error).
 *
 * Part 1, speed: steps/s at N = 1k, 10k, 100k in the unit square (20 x 20 classes and a
 * threshold of 1e-9, so the run never stops early; the rate should not depend on N).
 * Part 2, convergence (Mollon & Zhao Fig. 10b, c): steps and seconds to reach E3 = 0.002 in the
 * unit square versus N (cov 0.8, isotropic) and versus COV (N = 1000, isotropic) from uniform
 * and Halton starts. Usage: bench_imc [speed_steps] [max_steps] */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "gp_imc.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static const gp_vec2 SQ[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

static void row(const char *what, size_t n, double cov, double aniso, int init, int classes, double thr,
                long max_steps)
{
    gp_imc_params p;
    gp_imc_params_default(&p);
    p.cov = cov;
    p.anisotropy = aniso;
    p.init = init;
    p.classes_size = p.classes_orient = classes;
    p.threshold = thr;
    p.max_steps = max_steps;
    gp_voronoi *v = NULL;
    gp_imc_report r;
    gp_error e;
    double t0 = now();
    gp_imc_run(SQ, 4, NULL, NULL, 0, n, &p, NULL, NULL, NULL, &v, &r, &e);
    double t1 = now();
    /* the rate of the loop alone: time a fresh tessellation of the final seeds and subtract */
    double tb = 0.0;
    if (v) {
        gp_vec2 *s = malloc(n * sizeof *s);
        for (size_t i = 0; i < n; i++) s[i] = gp_voronoi_seed(v, i);
        double a = now();
        gp_voronoi *w = gp_voronoi_create(SQ, 4, NULL, NULL, 0, s, n, NULL);
        tb = now() - a;
        gp_voronoi_destroy(w);
        free(s);
    }
    double loop = t1 - t0 - tb;
    printf("| %-22s | %6zu | %4.2f | %-7s | %2zux%-2zu | %-9s | %8ld | %6ld | %.5f | %7.2f | %9.0f |\n", what, n, cov,
           init ? "halton" : "uniform", r.nsize, r.norient, gp_imc_stop_name(r.stop_reason), r.steps, r.accepted,
           r.error, t1 - t0, loop > 0 ? (double)r.steps / loop : 0.0);
    fflush(stdout);
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
}

int main(int argc, char **argv)
{
    long speed_steps = argc > 1 ? atol(argv[1]) : 200000;
    long max_steps = argc > 2 ? atol(argv[2]) : 2000000;
    printf("| case                   |      N |  COV | start   | classes | stop      |    steps | accept | E3      | seconds |   steps/s |\n");
    printf("|------------------------|--------|------|---------|---------|-----------|----------|--------|---------|---------|-----------|\n");
    const size_t ns[3] = {1000, 10000, 100000};
    for (int k = 0; k < 3; k++) row("speed", ns[k], 0.8, 1.0, 0, 20, 1e-9, speed_steps);
    const size_t nc[4] = {500, 1000, 2000, 5000};
    for (int k = 0; k < 4; k++) row("E3=0.002 vs N", nc[k], 0.8, 1.0, 0, 0, 0.002, max_steps);
    const double covs[5] = {0.1, 0.2, 0.4, 0.8, 1.2};
    for (int init = 0; init < 2; init++)
        for (int k = 0; k < 5; k++) row("E3=0.002 vs COV", 1000, covs[k], 1.0, init, 0, 0.002, max_steps);
    return 0;
}
