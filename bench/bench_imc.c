/* bench_imc.c -- IMC speed next to the fidelity it buys, in one table.
 *
 * For every case (N in {500, 2000} on the unit square x lognormal COV in {0.1, 0.2, 0.5, 0.8,
 * 1.2} x anisotropy in {1, 0.3, 0.1}, the L-shape with a hole, COV 0.05) and each objective
 * (the default AD at its default threshold, and the paper's E3 at 0.002 with automatic classes),
 * it prints the steps and seconds the run took and what the cells achieved, measured here on
 * the tessellation (not the run's own numbers): the cell-area KS distance to the target law
 * as a fraction of its 5 % critical value 1.36/sqrt(N), the COV error, and the orientation KS
 * fraction. Then the raw step rate at N = 1k, 10k, 100k (COV 0.8, threshold 1e-12 and no KS
 * goals: the run never stops) and the ratio of the 100k rate to the 1k rate, on one thread and then on `threads`
 * (gp_imc.h "Threads": the same steps, accepted moves and error whatever the count): the rate
 * is timed between the first progress report (step 4096) and the end, so that neither the
 * initial tessellation (nor the replicas' builds) nor the O(N) set-up of the objective counts,
 * in wall time and in the process's CPU time (all threads'); the error reached is printed
 * beside it. The 100k rows' 10^5 steps are the first step per cell of that run (a third of them
 * accepted), the 1k rows' the 4th to the 100th (2 % accepted), so one more row times N = 1,000
 * at the same stage, its first N steps (a third accepted as well), and one more ratio sets the
 * 100k rate against it; a progress report comes only every 4,096 steps, so that row takes the
 * least time of several runs of N steps less the least of as many runs of none (the set-up).
 * Usage: bench_imc [max_steps] [speed_steps] [N] [threads]   (max_steps 0 skips the fidelity
 * table; N > 0: only that rate row, on `threads` -- for callgrind, with threads 1: the
 * instructions per step are the difference of two runs of different speed_steps over their
 * difference, the set-up cancelling out; threads defaults to 2) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "gp_imc.h"
#include "gp_law.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double ks_sorted(double *u, size_t n)
{
    qsort(u, n, sizeof *u, cmp_double);
    double d = 0.0;
    for (size_t i = 0; i < n; i++) d = fmax(d, fmax((i + 1.0) / n - u[i], u[i] - (double)i / n));
    return d;
}

typedef struct shape {
    const char *name;
    const gp_vec2 *outer;
    size_t nouter;
    const gp_vec2 *const *holes;
    const size_t *nhole;
    size_t nholes;
} shape;

static const gp_vec2 SQ[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
static const gp_vec2 LSH[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
static const gp_vec2 HOLE[4] = {{0.3, 0.3}, {0.6, 0.3}, {0.6, 0.6}, {0.3, 0.6}};

static void row(const shape *sh, size_t n, double cov, double aniso, int kind, long max_steps)
{
    gp_imc_params p;
    gp_imc_params_defaults(&p);
    p.cov = cov;
    p.anisotropy = aniso;
    p.error_kind = kind;
    p.threshold = gp_imc_default_threshold(kind);
    p.max_steps = max_steps;
    p.seed = 11;
    gp_voronoi *v = NULL;
    gp_imc_report r;
    gp_error e;
    double t0 = now();
    gp_imc_run(sh->outer, sh->nouter, sh->holes, sh->nhole, sh->nholes, n, &p, NULL, NULL, NULL, &v, &r, &e);
    double t = now() - t0;
    if (!v) {
        printf("| %-12s | %5zu | %4.2f | %4.2f | %-3s | failed: %s |\n", sh->name, n, cov, aniso,
               kind == GP_IMC_ERROR_AD ? "AD" : "E3", e.message);
        return;
    }
    double area = gp_voronoi_container_area(v), mu = area / n, s2 = 0.0;
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, mu, cov, NULL);
    double *u = malloc(n * sizeof *u), *w = malloc(n * sizeof *w);
    for (size_t i = 0; i < n; i++) {
        double a = gp_voronoi_cell_area(v, i);
        s2 += (a - mu) * (a - mu);
        u[i] = gp_law_cdf(law, a);
        w[i] = gp_orient_cdf(0.0, aniso, gp_voronoi_cell_orientation(v, i) * 180.0 / M_PI);
    }
    double crit = 1.36 / sqrt((double)n), ks = ks_sorted(u, n), kso = ks_sorted(w, n);
    double cov_err = 100.0 * (sqrt(s2 / (n - 1)) / mu / cov - 1.0);
    printf("| %-12s | %5zu | %4.2f | %4.2f | %-3s | %-11s | %8ld | %7.2f | %9.0f | %6.4f | %5.2f | %+6.1f %% | %5.2f |\n",
           sh->name, n, cov, aniso, kind == GP_IMC_ERROR_AD ? "AD" : "E3", gp_imc_stop_name(r.stop_reason),
           r.steps, t, t > 0 ? r.steps / t : 0.0, r.error, ks / crit, cov_err, kso / crit);
    fflush(stdout);
    free(u);
    free(w);
    gp_law_destroy(law);
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
}

/* the process's CPU time, all threads' (the speed rows print it beside wall time: with one
 * thread it is steadier on a shared machine; with more it shows what the steps cost in all) */
static double cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* the progress reports' times: the first (step 4096) and the last (the end) */
typedef struct clock_marks {
    double t0, t1, c0, c1;
    long s0, s1;
} clock_marks;

static int mark(void *user, const gp_progress *pr)
{
    clock_marks *m = user;
    double t = now(), c = cpu_now();
    if (m->s0 < 0) {
        m->t0 = t;
        m->c0 = c;
        m->s0 = pr->steps;
    }
    m->t1 = t;
    m->c1 = c;
    m->s1 = pr->steps;
    return 0;
}

/* The rate of the first n steps at N = n, one thread (early_rate's reps runs of n steps and of
 * none, the least time of each) */
static double early_rate(size_t n, int reps, double *cpu_rate)
{
    double tw[2] = {INFINITY, INFINITY}, tc[2] = {INFINITY, INFINITY}, err = 0.0;
    long acc = 0;
    for (int r = 0; r < reps; r++)
        for (int k = 0; k < 2; k++) {
            gp_imc_params p;
            gp_imc_params_defaults(&p);
            p.threads = 1;
            p.cov = 0.8;
            p.threshold = 1e-12;
            p.ks_goals = 0; /* never stop at the goals either */
            p.max_steps = k ? (long)n : 0;
            gp_voronoi *v = NULL;
            gp_imc_report rep;
            double w0 = now(), c0 = cpu_now();
            gp_imc_run(SQ, 4, NULL, NULL, 0, n, &p, NULL, NULL, NULL, &v, &rep, NULL);
            tw[k] = fmin(tw[k], now() - w0);
            tc[k] = fmin(tc[k], cpu_now() - c0);
            if (k) {
                acc = rep.accepted;
                err = rep.error;
            }
            gp_voronoi_destroy(v);
            gp_imc_report_free(&rep);
        }
    double t = tw[1] - tw[0], c = tc[1] - tc[0];
    double rate = t > 0 ? (double)n / t : 0.0, crate = c > 0 ? (double)n / c : 0.0;
    printf("| first N steps |       1 | %6zu | %8zu | %8ld | %7.4f | %9.0f | %9.0f | %9.4g |\n", n, n, acc, t, rate,
           crate, err);
    fflush(stdout);
    if (cpu_rate) *cpu_rate = crate;
    return rate;
}

static double speed(size_t n, long steps, int threads, double *cpu_rate)
{
    gp_imc_params p;
    gp_imc_params_defaults(&p);
    p.threads = threads;
    p.cov = 0.8;
    p.threshold = 1e-12;
    p.ks_goals = 0; /* never stop at the goals either */
    p.max_steps = steps;
    gp_voronoi *v = NULL;
    gp_imc_report r;
    clock_marks m = {0.0, 0.0, 0.0, 0.0, -1, -1};
    gp_imc_run(SQ, 4, NULL, NULL, 0, n, &p, mark, &m, NULL, &v, &r, NULL);
    double t = m.t1 - m.t0, rate = t > 0 ? (double)(m.s1 - m.s0) / t : 0.0;
    double c = m.c1 - m.c0, crate = c > 0 ? (double)(m.s1 - m.s0) / c : 0.0;
    printf("| speed, AD   | %7d | %6zu | %8ld | %8ld | %7.2f | %9.0f | %9.0f | %9.4g |\n", threads, n, r.steps,
           r.accepted, t, rate, crate, r.error);
    fflush(stdout);
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
    if (cpu_rate) *cpu_rate = crate;
    return rate;
}

int main(int argc, char **argv)
{
    long max_steps = argc > 1 ? atol(argv[1]) : 1000000;
    long speed_steps = argc > 2 ? atol(argv[2]) : 100000;
    size_t only_n = argc > 3 ? (size_t)atol(argv[3]) : 0;
    int threads = argc > 4 ? atoi(argv[4]) : 2;
    shape square = {"square", SQ, 4, NULL, NULL, 0};
    const gp_vec2 *holes[1] = {HOLE};
    size_t nh[1] = {4};
    shape lshape = {"L with hole", LSH, 6, holes, nh, 1};
    if (only_n > 0) {
        speed(only_n, speed_steps, threads, NULL);
        return 0;
    }
    if (max_steps == 0) goto rates;
    printf("KS/crit: the cells' KS distance over its 5 %% critical value (<= 1 passes); COV err: achieved vs target\n\n");
    printf("| container    |     N |  COV |    a | obj | stop        |    steps | seconds |   steps/s |  error | KS/crit | COV err  | orient KS/crit |\n");
    printf("|--------------|-------|------|------|-----|-------------|----------|---------|-----------|--------|---------|----------|-------|\n");
    const size_t ns[2] = {500, 2000};
    const double covs[5] = {0.1, 0.2, 0.5, 0.8, 1.2}, an[3] = {1.0, 0.3, 0.1};
    for (int k = 0; k < 2; k++)
        for (int c = 0; c < 5; c++)
            for (int a = 0; a < 3; a++) {
                row(&square, ns[k], covs[c], an[a], GP_IMC_ERROR_AD, max_steps);
                row(&square, ns[k], covs[c], an[a], 3, max_steps);
            }
    for (int c = 1; c < 4; c += 2) {
        row(&lshape, 500, covs[c], 0.3, GP_IMC_ERROR_AD, max_steps);
        row(&lshape, 500, covs[c], 0.3, 3, max_steps);
    }
    row(&square, 500, 0.05, 1.0, GP_IMC_ERROR_AD, max_steps);
    row(&square, 500, 0.05, 1.0, 3, max_steps);
rates:
    printf("\n| rate        | threads |      N |    steps | accepted | seconds |   steps/s | steps/CPU s |     error |\n"
           "|---|---|---|---|---|---|---|---|---|\n");
    const size_t sn[3] = {1000, 10000, 100000};
    int tc[2] = {1, threads};
    for (int c = 0; c < (threads > 1 ? 2 : 1); c++) {
        double rate[3][2];
        for (int k = 0; k < 3; k++) rate[k][0] = speed(sn[k], speed_steps, tc[c], &rate[k][1]);
        printf("| ratio 100k/1k | %7d |      |          |          |         | %9.3f | %9.3f |           |\n", tc[c],
               rate[0][0] > 0 ? rate[2][0] / rate[0][0] : 0.0, rate[0][1] > 0 ? rate[2][1] / rate[0][1] : 0.0);
        if (c > 0) continue;
        double early[2];
        early[0] = early_rate(sn[0], 20, &early[1]);
        printf("| ratio 100k/1k, first N steps each | 1 |  |  |  |  | %9.3f | %9.3f |           |\n",
               early[0] > 0 ? rate[2][0] / early[0] : 0.0, early[1] > 0 ? rate[2][1] / early[1] : 0.0);
    }
    return 0;
}
