/* test_imc.c -- inverse Monte-Carlo: convergence on the paper's two configurations and N = 2000
 * with the paper's E3 and with the default Anderson-Darling objective (whose value is recomputed
 * here from the cells with an independent lognormal CDF and sort), a specimen that E3 passes
 * and the AD objective does not, the error floor, the hard cases (they converge or stop with a
 * reason, never hang), determinism, cancellation, the report against an independent
 * recount of the final tessellation, and the seeds' numbering along a Hilbert curve. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_geom.h"
#include "gp_imc.h"
#include "gp_test.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* A^2 of sorted u (brute force, the textbook formula) */
static double a2_sorted(const double *u, size_t n)
{
    double s = 0.0;
    for (size_t i = 1; i <= n; i++)
        s += (2.0 * i - 1.0) * (log(u[i - 1]) + log1p(-u[n - i]));
    return -(double)n - s / n;
}

/* The direction (radians, (-pi/2, pi/2]) of the thinnest side of cell i's seed part, by
 * gp_min_caliper on the part's polygon (not the tessellation's own orientation). */
static double caliper_angle(const gp_voronoi *v, size_t i)
{
    size_t part = gp_voronoi_cell_seed_part(v, i), m = gp_voronoi_cell_polygon(v, i, part, NULL, 0);
    gp_vec2 *poly = malloc(m * sizeof *poly);
    double w, ang = NAN, len;
    gp_voronoi_cell_polygon(v, i, part, poly, m);
    gp_min_caliper(poly, m, &w, &ang, &len, NULL);
    free(poly);
    return ang;
}

/* Cells of the unit square whose thinnest side lies along a wall: at 0 and at 90 deg */
static void wall_ties(const gp_voronoi *v, long k[2])
{
    k[0] = k[1] = 0;
    for (size_t i = 0; i < gp_voronoi_count(v); i++) {
        double a = caliper_angle(v, i);
        k[0] += fabs(a) < 1e-9;
        k[1] += fabs(fabs(a) - M_PI / 2) < 1e-9;
    }
}

/* Sample statistics of the cells, computed here from the tessellation: the cell-area KS
 * distance to the lognormal, the COV, the orientation KS, and the AD size and orientation
 * errors as gp_imc.h defines them (excess over the floor; the size error adds
 * N (COV / COV_t - 1)^2 for the population COV whose sample (n - 1) COV is the law's, the orientation error sum k (k - 1) / N over the square's two wall
 * directions with k cells on them). */
typedef struct cell_stats {
    double ks, cov, ad_size, ad_orient, ks_orient;
} cell_stats;

static cell_stats cell_stats_of(const gp_voronoi *v, const gp_imc_params *p)
{
    size_t n = gp_voronoi_count(v);
    double mu = gp_voronoi_container_area(v) / n, s = sqrt(log(1 + p->cov * p->cov));
    double m = log(mu) - 0.5 * s * s;
    double *a = malloc(n * sizeof *a), *u = malloc(n * sizeof *u), *t = malloc(n * sizeof *t);
    double sum2 = 0.0, fl = 0.0;
    for (size_t i = 0; i < n; i++) {
        a[i] = gp_voronoi_cell_area(v, i);
        sum2 += (a[i] - mu) * (a[i] - mu);
        /* orientation CDF on the window [mean - 90, mean + 90), written out here */
        double th = gp_voronoi_cell_orientation(v, i) * 180 / M_PI - (p->mean_deg - 90);
        th = fmod(fmod(th, 180) + 180, 180) * M_PI / 180;
        double al = p->anisotropy;
        double w = ((1 + al) / 2 * th - (1 - al) / 4 * sin(2 * th)) / ((1 + al) * M_PI / 2);
        t[i] = fmin(fmax(w, 0.25 / n), 1 - 0.25 / n);
    }
    qsort(a, n, sizeof *a, cmp_double);
    qsort(t, n, sizeof *t, cmp_double);
    cell_stats c = {0, 0, 0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        u[i] = 0.5 * erfc(-(log(a[i]) - m) / s / sqrt(2.0));
        c.ks = fmax(c.ks, fmax((i + 1.0) / n - u[i], u[i] - (double)i / n));
        c.ks_orient = fmax(c.ks_orient, fmax((i + 1.0) / n - t[i], t[i] - (double)i / n));
        double pq = (2.0 * i + 1.0) / (2.0 * n);
        fl += (2.0 * i + 1.0) * 2.0 * log(pq);
    }
    double floor_ad = -(double)n - fl / n;
    c.cov = sqrt(sum2 / (n - 1)) / mu;
    double covp = sqrt(sum2 / n) / mu, covt = p->cov * sqrt((n - 1.0) / n);
    c.ad_size = a2_sorted(u, n) - floor_ad + n * pow(covp / covt - 1, 2);
    long k[2];
    wall_ties(v, k);
    c.ad_orient = a2_sorted(t, n) - floor_ad + (double)(k[0] * (k[0] - 1) + k[1] * (k[1] - 1)) / n;
    free(a);
    free(u);
    free(t);
    return c;
}

static const gp_vec2 SQ[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

/* recount the histograms from the tessellation itself and compare with the report */
static void check_report(const gp_voronoi *v, const gp_imc_report *r, const gp_imc_params *p)
{
    size_t n = gp_voronoi_count(v);
    double *hs = calloc(r->nsize, sizeof(double)), *ht = calloc(r->norient, sizeof(double));
    for (size_t i = 0; i < n; i++) {
        double a = gp_voronoi_cell_area(v, i);
        size_t k = 0;
        while (k + 1 < r->nsize && a >= r->size_edges[k + 1]) k++;
        hs[k] += 1.0 / n;
        /* the documented class of an orientation th in (-pi/2, pi/2]: floor((th + pi/2) k / pi) mod k */
        double th = gp_voronoi_cell_orientation(v, i);
        size_t c = (size_t)floor((th + M_PI / 2) * (double)r->norient / M_PI);
        if (c >= r->norient) c -= r->norient;
        ht[c] += 1.0 / n;
    }
    double s2 = 0, t2 = 0, st = 0, tt = 0;
    int same = 1;
    for (size_t k = 0; k < r->nsize; k++) {
        s2 += (hs[k] - r->size_target[k]) * (hs[k] - r->size_target[k]);
        st += r->size_target[k];
        if (fabs(hs[k] - r->size_achieved[k]) > 1e-12) same = 0;
    }
    for (size_t k = 0; k < r->norient; k++) {
        t2 += (ht[k] - r->orient_target[k]) * (ht[k] - r->orient_target[k]);
        tt += r->orient_target[k];
        if (fabs(ht[k] - r->orient_achieved[k]) > 1e-12) same = 0;
    }
    CHECK(same);
    if (!same) {
        for (size_t k = 0; k < r->nsize; k++) fprintf(stderr, "S%zu %g %g\n", k, hs[k] * n, r->size_achieved[k] * n);
        for (size_t k = 0; k < r->norient; k++) fprintf(stderr, "T%zu %g %g\n", k, ht[k] * n, r->orient_achieved[k] * n);
    }
    CHECK_NEAR(st, 1.0, 1e-12);
    CHECK_NEAR(tt, 1.0, 1e-12);
    if (p->error_kind == 3) CHECK_NEAR(fmax(sqrt(s2), sqrt(t2)), r->error, 1e-12);
    /* the targets themselves: lognormal quantile edges (each class 1/k), cosine law */
    double mu = gp_voronoi_container_area(v) / n, s = sqrt(log(1 + p->cov * p->cov));
    double m = log(mu) - 0.5 * s * s;
    if (r->nsize >= 2) {
        /* lower edge of class 1 = quantile 1/k: Phi((ln q - m)/s) = 1/k */
        double z = (log(r->size_edges[1]) - m) / s;
        CHECK_NEAR(0.5 * erfc(-z / sqrt(2.0)), 1.0 / r->nsize, 1e-9);
    }
    for (size_t k = 0; k < r->norient; k++) {
        /* numeric integral of the density over the class */
        double a = r->orient_edges[k] * M_PI / 180, b = r->orient_edges[k + 1] * M_PI / 180, acc = 0;
        double tb = p->mean_deg * M_PI / 180, al = p->anisotropy;
        for (int q = 0; q < 2000; q++) {
            double th = a + (q + 0.5) * (b - a) / 2000;
            acc += ((1 + al) / 2 + (1 - al) / 2 * cos(2 * (th - tb))) * (b - a) / 2000;
        }
        CHECK_NEAR(acc / ((1 + al) * M_PI / 2), r->orient_target[k], 1e-7);
    }
    free(hs);
    free(ht);
}

static gp_status run(const gp_vec2 *outer, size_t no, const gp_vec2 *const *holes, const size_t *nh,
                     size_t nholes, size_t n, const gp_imc_params *p, gp_voronoi **v, gp_imc_report *r,
                     const char *name)
{
    gp_error e;
    gp_status st = gp_imc_run(outer, no, holes, nh, nholes, n, p, NULL, NULL, NULL, v, r, &e);
    printf("%-28s N=%5zu: %-9s steps %7ld accepted %5ld error %.5f (initial %.4f, floor %.2g, %zux%zu classes)%s%s\n",
           name, n, gp_imc_stop_name(r->stop_reason), r->steps, r->accepted, r->error, r->error_initial,
           r->floor, r->nsize, r->norient, st == GP_OK ? "" : " -- ", st == GP_OK ? "" : e.message);
    return st;
}

static void converge(int kind, size_t n, double cov, double aniso, double mean, int init, long max_steps,
                     const char *name)
{
    gp_imc_params p;
    gp_imc_params_defaults(&p);
    p.error_kind = kind;
    p.threshold = gp_imc_default_threshold(kind);
    p.cov = cov;
    p.anisotropy = aniso;
    p.mean_deg = mean;
    p.init = init;
    p.max_steps = max_steps;
    gp_voronoi *v = NULL;
    gp_imc_report r;
    gp_status st = run(SQ, 4, NULL, NULL, 0, n, &p, &v, &r, name);
    CHECK(st == GP_OK);
    CHECK(r.stop_reason == GP_IMC_STOP_THRESHOLD);
    CHECK(r.error <= p.threshold);
    CHECK(v != NULL);
    if (v) {
        CHECK(gp_voronoi_count(v) == n);
        check_report(v, &r, &p);
    }
    if (v && kind == GP_IMC_ERROR_AD) {
        /* the reported errors are the statistic of the cells, and the cells follow the law:
         * KS far inside its 5 % critical value, COV within 2 % */
        cell_stats c = cell_stats_of(v, &p);
        printf("    AD size %.5f (recomputed %.5f), orient %.5f (%.5f); KS %.4f (critical %.4f), COV %.4f for %.2f\n",
               r.error_size_ad, c.ad_size, r.error_orient_ad, c.ad_orient, c.ks, 1.36 / sqrt(n), c.cov, cov);
        CHECK_NEAR(r.error_size_ad, c.ad_size, 1e-6 * (1 + fabs(c.ad_size)));
        CHECK_NEAR(r.error_orient_ad, c.ad_orient, 1e-6 * (1 + fabs(c.ad_orient)));
        CHECK(fmax(c.ad_size, c.ad_orient / 2) <= p.threshold * (1 + 1e-6)); /* gp_imc.h: half weight */
        CHECK(c.ks < 0.5 * 1.36 / sqrt(n));
        CHECK(fabs(c.cov / cov - 1) < 0.02);
    }
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
}

/* Walls tie orientations (gp_imc.h): the cells of random seeds in a square have many at exactly
 * 0 and 90 deg, a step in the orientations' CDF; the default run leaves few, and the orientation
 * KS (recomputed here, ties and all) inside 0.3 of its critical value. */
static void walls_untie(size_t n, uint64_t seed)
{
    gp_imc_params p;
    gp_imc_params_defaults(&p);
    p.cov = 0.8;
    p.seed = seed;
    p.max_steps = 0;
    gp_voronoi *v = NULL;
    gp_imc_report r;
    long k0[2], k1[2];
    run(SQ, 4, NULL, NULL, 0, n, &p, &v, &r, "walls, start");
    wall_ties(v, k0);
    cell_stats c0 = cell_stats_of(v, &p);
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
    p.max_steps = 1000000;
    CHECK(run(SQ, 4, NULL, NULL, 0, n, &p, &v, &r, "walls, default run") == GP_OK);
    wall_ties(v, k1);
    cell_stats c1 = cell_stats_of(v, &p);
    double crit = 1.36 / sqrt((double)n);
    printf("    cells at 0 / 90 deg: %ld / %ld at the start, %ld / %ld at the end; orientation KS %.2f -> %.2f of "
           "critical\n", k0[0], k0[1], k1[0], k1[1], c0.ks_orient / crit, c1.ks_orient / crit);
    CHECK(k0[0] + k0[1] > sqrt((double)n)); /* the case is real: a third of the wall cells */
    CHECK((double)(k1[0] * (k1[0] - 1) + k1[1] * (k1[1] - 1)) / n <= 2 * p.threshold);
    CHECK(c1.ks_orient <= 0.3 * crit);
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
}

/* The default stopping rule asks the KS goals the threshold stands for (gp_imc.h "Stopping"):
 * over seeds 1 .. nseeds, runs without the check leave some cells' area or orientation KS
 * (recomputed here from the cells) beyond 0.15 / 0.3 of the critical value; with it none is. */
static void ks_goals(size_t n, double cov, double aniso, int nseeds)
{
    double crit = 1.36 / sqrt((double)n), worst[2][2] = {{0, 0}, {0, 0}};
    long steps[2] = {0, 0};
    for (int g = 0; g < 2; g++)
        for (int seed = 1; seed <= nseeds; seed++) {
            gp_imc_params p;
            gp_imc_params_defaults(&p);
            p.cov = cov;
            p.anisotropy = aniso;
            p.seed = (uint64_t)seed;
            p.ks_goals = g;
            gp_voronoi *v = NULL;
            gp_imc_report r;
            CHECK(run(SQ, 4, NULL, NULL, 0, n, &p, &v, &r, g ? "  with the KS check" : "  without") == GP_OK);
            CHECK(r.stop_reason == GP_IMC_STOP_THRESHOLD && r.error <= p.threshold);
            cell_stats c = cell_stats_of(v, &p);
            worst[g][0] = fmax(worst[g][0], c.ks / crit);
            worst[g][1] = fmax(worst[g][1], c.ks_orient / crit);
            steps[g] += r.steps;
            gp_voronoi_destroy(v);
            gp_imc_report_free(&r);
        }
    printf("KS goals, N %zu, COV %.1f, a %.1f, seeds 1-%d: worst area / orientation KS of critical %.3f / %.3f "
           "without the check (%ld steps), %.3f / %.3f with it (%ld steps)\n", n, cov, aniso, nseeds, worst[0][0],
           worst[0][1], steps[0], worst[1][0], worst[1][1], steps[1]);
    CHECK(worst[0][0] > 0.2 || worst[0][1] > 0.3); /* the case is real: beyond even 0.2 */
    CHECK(worst[1][0] <= 0.15 && worst[1][1] <= 0.3);
}

/* Near-regular cells meet the goals the default threshold stands for long before the threshold:
 * over seeds 1 .. nseeds at N = 500, COV 0.1, runs without the check (ks_goals 0) reach the
 * threshold in 92,000-215,000 steps; default runs stop on the slow descent (gp_imc.h
 * "Stopping") in a fraction of that, as stalled, with the areas' KS distance within 0.15 and the
 * orientations' within 0.25 of the critical value and the COV within 1 % (all recomputed here
 * from the cells). */
static void slow_at_goals(size_t n, double cov, int nseeds)
{
    double crit = 1.36 / sqrt((double)n), worst[3] = {0, 0, 0};
    long steps[2] = {0, 0};
    int stalled = 0;
    for (int g = 0; g < 2; g++)
        for (int seed = 1; seed <= nseeds; seed++) {
            gp_imc_params p;
            gp_imc_params_defaults(&p);
            p.cov = cov;
            p.seed = (uint64_t)seed;
            p.ks_goals = g;
            gp_voronoi *v = NULL;
            gp_imc_report r;
            gp_status st = run(SQ, 4, NULL, NULL, 0, n, &p, &v, &r, g ? "  default" : "  without the goals");
            CHECK(g ? st == GP_OK || st == GP_ERR_NOT_CONVERGED : st == GP_OK);
            if (!g) CHECK(r.stop_reason == GP_IMC_STOP_THRESHOLD);
            stalled += g && r.stop_reason == GP_IMC_STOP_STALLED;
            steps[g] += r.steps;
            if (g && v) {
                cell_stats c = cell_stats_of(v, &p);
                worst[0] = fmax(worst[0], c.ks / crit);
                worst[1] = fmax(worst[1], c.ks_orient / crit);
                worst[2] = fmax(worst[2], fabs(c.cov / cov - 1));
            }
            gp_voronoi_destroy(v);
            gp_imc_report_free(&r);
        }
    printf("slow at the goals, N %zu, COV %.2f, seeds 1-%d: %ld steps to the threshold, %ld by default "
           "(%d stalled); worst area / orientation KS of critical %.3f / %.3f, COV off by %.2f %%\n", n, cov,
           nseeds, steps[0], steps[1], stalled, worst[0], worst[1], 100 * worst[2]);
    CHECK(stalled > 0);
    CHECK(3 * steps[1] < steps[0]);
    CHECK(worst[0] <= 0.15 && worst[1] <= 0.25 && worst[2] <= 0.01);
}

/* The slow descent alone does not stop a run: at N = 2,000, COV 0.1 the error falls slowly in
 * its first steps too (259 at step 12,288, projected to need more steps than made) while the
 * cells are far from the goals (area KS 2.3 of critical); the run goes on until they meet
 * them (recomputed here from the cells). */
static void slow_only_at_goals(void)
{
    size_t n = 2000;
    gp_imc_params p;
    gp_imc_params_defaults(&p);
    p.cov = 0.1;
    gp_voronoi *v = NULL;
    gp_imc_report r;
    run(SQ, 4, NULL, NULL, 0, n, &p, &v, &r, "slow only at the goals");
    CHECK(v != NULL);
    if (v) {
        cell_stats c = cell_stats_of(v, &p);
        double crit = 1.36 / sqrt((double)n);
        printf("    area / orientation KS of critical %.3f / %.3f, COV off by %.2f %%\n", c.ks / crit,
               c.ks_orient / crit, 100 * fabs(c.cov / p.cov - 1));
        CHECK(r.stop_reason == GP_IMC_STOP_STALLED && r.at_goals && r.steps > 12288);
        CHECK(c.ks <= 0.15 * crit && c.ks_orient <= 0.25 * crit && fabs(c.cov / p.cov - 1) <= 0.01);
    }
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
}

/* Past the threshold the KS phase accepts no move that takes the error back above it (moves are
 * judged on the descent, a sum, which can fall while the error, a max, rises): this run first
 * reaches 0.05 at step 1883, and a move at step 1888 used to lift the error to 0.0502, so that a
 * max_steps of 1900 ended it "not converged". Checked on one and two threads. */
static void ks_phase_keeps_threshold(void)
{
    for (int threads = 1; threads <= 2; threads++) {
        gp_imc_params p;
        gp_imc_params_defaults(&p);
        p.cov = 0.8;
        p.seed = 3;
        p.max_steps = 1900;
        p.threads = threads;
        gp_voronoi *v = NULL;
        gp_imc_report r;
        gp_status st = run(SQ, 4, NULL, NULL, 0, 200, &p, &v, &r, "KS phase, max_steps 1900");
        CHECK(st == GP_OK && r.stop_reason == GP_IMC_STOP_THRESHOLD && r.error <= p.threshold);
        cell_stats c = cell_stats_of(v, &p);
        CHECK(fmax(c.ad_size, c.ad_orient / 2) <= p.threshold * (1 + 1e-6));
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
    }
}

/* a hard case: converges, or stops at max_steps with the error not above the start */
static void hard(const char *name, const gp_vec2 *outer, size_t no, const gp_vec2 *const *holes, const size_t *nh,
                 size_t nholes, size_t n, gp_imc_params *p)
{
    gp_voronoi *v = NULL;
    gp_imc_report r;
    gp_status st = run(outer, no, holes, nh, nholes, n, p, &v, &r, name);
    CHECK(st == GP_OK || st == GP_ERR_NOT_CONVERGED);
    CHECK(v != NULL);
    CHECK(r.steps <= p->max_steps);
    /* the descent: E1-E3 never rise; AD descends on the sum of its two errors */
    if (p->error_kind == GP_IMC_ERROR_AD) CHECK(r.error_size_ad + r.error_orient_ad <= 2 * r.error_initial);
    else CHECK(r.error <= r.error_initial);
    CHECK(st != GP_OK || r.error <= p->threshold);
    CHECK(st != GP_ERR_NOT_CONVERGED || r.stop_reason == GP_IMC_STOP_MAX_STEPS ||
          r.stop_reason == GP_IMC_STOP_STALLED);
    if (v) check_report(v, &r, p);
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
}

static int cb_calls = 0;
static long cb_last = 0;
static int progress_cb(void *user, const gp_progress *p)
{
    cb_calls++;
    cb_last = p->steps;
    return user ? (p->steps >= 8192) : 0;
}

/* 10,000 IMC steps (moves of every kind, most of them rolled back), then the tessellation the
 * run kept against a fresh gp_voronoi_create of its final seeds: every cell's area,
 * orientation, parts and neighbours bit for bit. The moves recompute cells from the neighbour
 * lists (gp_voronoi.c, "Moves"), the fresh build from the grid: two independent routes to the
 * same cells. */
static void rebuild_matches(const char *name, const gp_vec2 *outer, size_t no,
                            const gp_vec2 *const *holes, const size_t *nh, size_t nholes, size_t n,
                            int threads)
{
    gp_imc_params p;
    gp_imc_params_defaults(&p);
    p.threads = threads; /* > 1: the run's tessellation takes other lanes' moves by copy */
    p.cov = 0.8;
    p.threshold = 1e-12; /* never reached: exactly max_steps steps */
    p.max_steps = 10000;
    p.seed = 5;
    gp_voronoi *v = NULL;
    gp_imc_report r;
    gp_imc_run(outer, no, holes, nh, nholes, n, &p, NULL, NULL, NULL, &v, &r, NULL);
    CHECK(v != NULL && r.steps == 10000 && r.accepted > 100 && r.accepted < r.steps);
    if (!v) return;
    gp_vec2 *s = malloc(n * sizeof *s);
    for (size_t i = 0; i < n; i++) s[i] = gp_voronoi_seed(v, i);
    gp_voronoi *f = gp_voronoi_create(outer, no, holes, nh, nholes, s, n, NULL);
    CHECK(f != NULL);
    int bad = 0;
    static size_t na[256], nb[256];
    for (size_t i = 0; f && i < n; i++) {
        double a = gp_voronoi_cell_area(v, i), b = gp_voronoi_cell_area(f, i);
        double oa = gp_voronoi_cell_orientation(v, i), ob = gp_voronoi_cell_orientation(f, i);
        size_t ka = gp_voronoi_neighbours(v, i, na, 256), kb = gp_voronoi_neighbours(f, i, nb, 256);
        int ok = !memcmp(&a, &b, sizeof a) && !memcmp(&oa, &ob, sizeof oa) && ka == kb &&
                 !memcmp(na, nb, ka * sizeof *na) && gp_voronoi_cell_parts(v, i) == gp_voronoi_cell_parts(f, i);
        if (!ok && bad++ < 3)
            fprintf(stderr, "%s: cell %zu area %.17g vs %.17g, orient %.17g vs %.17g, nb %zu vs %zu\n", name,
                    i, a, b, oa, ob, ka, kb);
    }
    printf("%s, %d thread(s): %ld steps (%ld accepted), rebuilt, %d cells differ\n", name, threads, r.steps,
           r.accepted, bad);
    CHECK(bad == 0);
    gp_voronoi_destroy(f);
    gp_voronoi_destroy(v);
    gp_imc_report_free(&r);
    free(s);
}

/* The same run on 1, 2 and 3 threads: the same stop, steps, accepted moves and error, and the
 * same seeds and cell areas bit for bit (gp_imc.h, "Threads"). Stopped by max_steps at a step
 * no round boundary needs to fall on (15,001), by a progress callback cancelling at step
 * 8192, or by the threshold. */
static void threads_agree(const char *name, const gp_vec2 *outer, size_t no, const gp_vec2 *const *holes,
                          const size_t *nh, size_t nholes, size_t n, double cov, long max_steps, int cancel)
{
    gp_imc_report r[3];
    gp_voronoi *v[3] = {NULL, NULL, NULL};
    for (int t = 0; t < 3; t++) {
        gp_imc_params p;
        gp_imc_params_defaults(&p);
        p.cov = cov;
        p.anisotropy = 0.5;
        p.max_steps = max_steps;
        p.seed = 21;
        p.threads = t + 1;
        if (cancel) p.threshold = 1e-9; /* the callback stops it */
        int user = 1;
        gp_imc_run(outer, no, holes, nh, nholes, n, &p, progress_cb, cancel ? &user : NULL, NULL, &v[t], &r[t],
                   NULL);
    }
    int same = v[0] && v[1] && v[2];
    for (int t = 1; same && t < 3; t++) {
        same = r[t].steps == r[0].steps && r[t].accepted == r[0].accepted &&
               r[t].stop_reason == r[0].stop_reason && !memcmp(&r[t].error, &r[0].error, sizeof(double));
        for (size_t i = 0; same && i < n; i++) {
            gp_vec2 a = gp_voronoi_seed(v[0], i), b = gp_voronoi_seed(v[t], i);
            double x = gp_voronoi_cell_area(v[0], i), y = gp_voronoi_cell_area(v[t], i);
            same = !memcmp(&a, &b, sizeof a) && !memcmp(&x, &y, sizeof x);
        }
    }
    printf("%s: %s after %ld steps (%ld accepted), error %.6g; 2 and 3 threads %s\n", name,
           gp_imc_stop_name(r[0].stop_reason), r[0].steps, r[0].accepted, r[0].error, same ? "the same" : "DIFFER");
    CHECK(same);
    CHECK(r[0].accepted > 50);
    if (cancel) CHECK(r[0].stop_reason == GP_IMC_STOP_CANCELLED && r[0].steps == 8192);
    else if (max_steps < 100000) CHECK(r[0].stop_reason == GP_IMC_STOP_MAX_STEPS && r[0].steps == max_steps);
    else if (cov <= 0.1) CHECK(r[0].stop_reason == GP_IMC_STOP_STALLED && r[0].at_goals); /* slow_at_goals */
    else CHECK(r[0].stop_reason == GP_IMC_STOP_THRESHOLD);
    for (int t = 0; t < 3; t++) {
        gp_voronoi_destroy(v[t]);
        gp_imc_report_free(&r[t]);
    }
}

/* The Hilbert index of (x, y) on a 2^16 grid, by the state table of Hacker's Delight (Warren,
 * fig. 16-8): an implementation independent of gp_imc.c's bit-twiddling one, with the same
 * convention (from (0, 0), first up the y axis, ending at (2^16 - 1, 0)). */
static uint64_t hilbert_table(uint32_t x, uint32_t y)
{
    uint64_t s = 0;
    uint32_t state = 0;
    for (int i = 15; i >= 0; i--) {
        uint32_t row = 4 * state | 2 * ((x >> i) & 1) | ((y >> i) & 1);
        s = (s << 2) | ((0x361E9CB4u >> (2 * row)) & 3);
        state = (0x8FE65831u >> (2 * row)) & 3;
    }
    return s;
}

/* Generated seeds come numbered along a Hilbert curve over the container's bounding box
 * (gp_imc.c, hilbert_sort): their curve indices, recomputed here, never decrease; consecutive
 * seeds lie close (in draw order they would lie ~0.5 apart in a unit square; along the curve
 * ~1 / sqrt(N)), and Voronoi neighbours have close indices. The caller's seeds keep their
 * order. No step is taken, so the seeds are the initial ones. */
static void seed_order(const char *name, const gp_vec2 *outer, size_t no, const gp_vec2 *const *holes,
                       const size_t *nh, size_t nholes, size_t n, int init)
{
    gp_imc_params p;
    gp_imc_params_defaults(&p);
    p.max_steps = 0;
    p.threshold = 1e-12;
    p.init = init;
    gp_voronoi *v = NULL;
    gp_imc_run(outer, no, holes, nh, nholes, n, &p, NULL, NULL, NULL, &v, NULL, NULL);
    CHECK(v != NULL);
    if (!v) return;
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (size_t k = 0; k < no; k++) {
        x0 = fmin(x0, outer[k].x), y0 = fmin(y0, outer[k].y);
        x1 = fmax(x1, outer[k].x), y1 = fmax(y1, outer[k].y);
    }
    double scale = 65536.0 / fmax(x1 - x0, y1 - y0), step = 0.0;
    uint64_t prev = 0;
    int monotone = 1;
    for (size_t i = 0; i < n; i++) {
        gp_vec2 s = gp_voronoi_seed(v, i);
        double fx = fmin(fmax((s.x - x0) * scale, 0.0), 65535.0);
        double fy = fmin(fmax((s.y - y0) * scale, 0.0), 65535.0);
        uint64_t h = hilbert_table((uint32_t)fx, (uint32_t)fy);
        monotone &= i == 0 || h >= prev;
        prev = h;
        if (i > 0) {
            gp_vec2 r = gp_voronoi_seed(v, i - 1);
            step += hypot(s.x - r.x, s.y - r.y);
        }
    }
    /* mean |i - j| over neighbour pairs: N / 3 for a random numbering */
    static size_t nb[256];
    double gap = 0.0, pairs = 0.0;
    for (size_t i = 0; i < n; i++) {
        size_t k = gp_voronoi_neighbours(v, i, nb, 256);
        for (size_t q = 0; q < k; q++) gap += fabs((double)nb[q] - (double)i);
        pairs += (double)k;
    }
    step /= (double)(n - 1) * sqrt(gp_voronoi_container_area(v) / (double)n); /* in cell sizes */
    gap /= pairs;
    printf("%s: curve order %s, mean step %.2f cell sizes, mean neighbour index gap %.1f of %zu\n", name,
           monotone ? "yes" : "NO", step, gap, n);
    CHECK(monotone);
    CHECK(step < 2.0);
    CHECK(gap < 0.05 * (double)n);
    /* the caller's seeds are kept as given: a reversed copy stays reversed */
    gp_vec2 *s = malloc(n * sizeof *s);
    for (size_t i = 0; i < n; i++) s[i] = gp_voronoi_seed(v, n - 1 - i);
    p.seeds = s;
    gp_voronoi *w = NULL;
    gp_imc_run(outer, no, holes, nh, nholes, n, &p, NULL, NULL, NULL, &w, NULL, NULL);
    CHECK(w != NULL);
    int same = w != NULL;
    for (size_t i = 0; same && i < n; i++) {
        gp_vec2 a = gp_voronoi_seed(w, i);
        same = memcmp(&a, &s[i], sizeof a) == 0;
    }
    CHECK(same);
    gp_voronoi_destroy(w);
    gp_voronoi_destroy(v);
    free(s);
}

/* How unevenly the cells' area is spread over the unit square: the sum over its 4 x 4 squares
 * of z^2, z = (the mean area of the cells whose seed lies in the square - the mean of all) /
 * (sd / sqrt(cells in the square)). */
static double unevenness(const gp_voronoi *v)
{
    size_t n = gp_voronoi_count(v), m[16] = {0};
    double sum[16] = {0}, s1 = 0.0, s2 = 0.0;
    for (size_t i = 0; i < n; i++) {
        double a = gp_voronoi_cell_area(v, i);
        gp_vec2 q = gp_voronoi_seed(v, i);
        int gx = (int)fmin(3.0, floor(4.0 * q.x)), gy = (int)fmin(3.0, floor(4.0 * q.y));
        sum[4 * gy + gx] += a;
        m[4 * gy + gx]++;
        s1 += a;
        s2 += a * a;
    }
    double mean = s1 / (double)n, sd = sqrt(fmax(s2 / (double)n - mean * mean, 0.0)), chi = 0.0;
    for (int g = 0; g < 16; g++) {
        if (m[g] == 0) continue;
        double z = (sum[g] / (double)m[g] - mean) / (sd / sqrt((double)m[g]));
        chi += z * z;
    }
    return chi;
}

/* The two-sample KS distance between the areas of the cells on either side of the line
 * x = 0.5 (axis 0) or y = 0.5 (axis 1): whether both halves follow the same law, which a
 * mean cannot tell (the cells tile each half, whatever their law). */
static double halves_ks(const gp_voronoi *v, int axis)
{
    size_t n = gp_voronoi_count(v), na = 0, nb = 0;
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), d = 0.0;
    for (size_t i = 0; i < n; i++) {
        gp_vec2 q = gp_voronoi_seed(v, i);
        if ((axis ? q.y : q.x) < 0.5) a[na++] = gp_voronoi_cell_area(v, i);
        else b[nb++] = gp_voronoi_cell_area(v, i);
    }
    qsort(a, na, sizeof *a, cmp_double);
    qsort(b, nb, sizeof *b, cmp_double);
    for (size_t i = 0, j = 0; i < na && j < nb;) {
        double x = a[i] <= b[j] ? a[i] : b[j];
        while (i < na && a[i] <= x) i++;
        while (j < nb && b[j] <= x) j++;
        d = fmax(d, fabs((double)i / (double)na - (double)j / (double)nb));
    }
    free(a);
    free(b);
    return d;
}

/* A specimen must follow its laws in every part of the container, not only as a whole: the AD
 * and KS distances see the areas' distribution and nothing of where the cells lie. gp_imc
 * takes the seeds in a sweep along their Hilbert order (gp_imc.c, sweep_seed), where the paper
 * picks them at random; a sweep that left large cells where it starts or ends would still pass
 * every distribution check. So its specimens are compared with ones the same code makes with
 * the sweep's locality taken away: seeds given by the caller keep their order, so seeds drawn
 * uniformly and given in draw order are swept in random order -- a random pick without
 * replacement. Over 4 seeds (N = 4,000, COV 0.8, to the AD threshold) the mean unevenness
 * must stay within 1.5x of theirs (42 against 45); cells 3x larger on one side than the
 * other (seeds of density 0.5 + x, the control) score 78x theirs, and must score 25x. Neither is a sample of 16 independent z's
 * (the cells tile the square, so a square's mean area is its area over its count): only the
 * comparison is meaningful. The same comparison for the law itself, half against half
 * (halves_ks, the larger of the two cuts): a sweep that tuned one part of the container and
 * left another as drawn (Poisson cells, COV 0.53) would keep the mean area even and fail this;
 * within 1.5x of the reference's as well (0.044 against 0.042). A sweep broken on purpose to
 * move only the first half of the seeds (the left half of the square) still reached the AD
 * threshold on all 4 seeds, and failed both checks: unevenness 198 against 50, KS 0.145
 * against 0.035. */
static void even_in_space(void)
{
    const size_t n = 4000;
    gp_vec2 *s = malloc(n * sizeof *s);
    double swept = 0.0, picked = 0.0, ks_swept = 0.0, ks_picked = 0.0;
    uint64_t x = 88172645463325252ull; /* xorshift64: the reference's seeds */
    for (int k = 1; k <= 4; k++) {
        gp_imc_params p;
        gp_imc_params_defaults(&p);
        p.cov = 0.8;
        p.seed = (uint64_t)k;
        gp_voronoi *v = NULL, *w = NULL;
        gp_imc_report r, q;
        CHECK(run(SQ, 4, NULL, NULL, 0, n, &p, &v, &r, "even: along the curve") == GP_OK);
        for (size_t i = 0; i < 2 * n; i++) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17;
            double u = (double)(x >> 11) * 0x1p-53;
            if (i % 2 == 0) s[i / 2].x = u;
            else s[i / 2].y = u;
        }
        p.seeds = s;
        CHECK(run(SQ, 4, NULL, NULL, 0, n, &p, &w, &q, "even: in draw order") == GP_OK);
        if (v && w) {
            swept += unevenness(v) / 4.0;
            picked += unevenness(w) / 4.0;
            ks_swept += fmax(halves_ks(v, 0), halves_ks(v, 1)) / 4.0;
            ks_picked += fmax(halves_ks(w, 0), halves_ks(w, 1)) / 4.0;
        }
        gp_voronoi_destroy(v);
        gp_voronoi_destroy(w);
        gp_imc_report_free(&r);
        gp_imc_report_free(&q);
    }
    for (size_t i = 0; i < n; i++) { /* the control: density 0.5 + x by its inverse CDF */
        double u = (i + 0.5) / (double)n;
        s[i].x = -0.5 + sqrt(0.25 + 2.0 * u);
        s[i].y = fmod(0.6180339887498949 * (double)(i + 1), 1.0);
    }
    gp_voronoi *g = gp_voronoi_create(SQ, 4, NULL, NULL, 0, s, n, NULL);
    double control = g ? unevenness(g) : 0.0;
    printf("even in space: unevenness %.1f along the curve, %.1f in draw order, %.0f the control; "
           "halves' KS %.4f along the curve, %.4f in draw order\n",
           swept, picked, control, ks_swept, ks_picked);
    CHECK(swept < 1.5 * picked);
    CHECK(ks_swept < 1.5 * ks_picked);
    CHECK(control > 25.0 * picked);
    gp_voronoi_destroy(g);
    free(s);
}

int main(void)
{
    /* --- the paper's two configurations (Mollon & Zhao §3.3.3) and N = 2000 --- */
    converge(3, 500, 0.8, 1.0, 0.0, 0, 1000000, "E3: config 1 (cov 0.8, a 1)");
    converge(3, 500, 0.2, 0.1, 0.0, 1, 1000000, "E3: config 2 (cov 0.2, a 0.1)");
    converge(3, 2000, 0.8, 1.0, 0.0, 0, 1000000, "E3: N 2000 (cov 0.8, a 1)");
    converge(GP_IMC_ERROR_AD, 500, 0.8, 1.0, 0.0, 0, 1000000, "AD: config 1 (cov 0.8, a 1)");
    converge(GP_IMC_ERROR_AD, 500, 0.2, 0.1, 0.0, 1, 1000000, "AD: config 2 (cov 0.2, a 0.1)");
    converge(GP_IMC_ERROR_AD, 2000, 1.2, 0.3, 30.0, 0, 1000000, "AD: N 2000 (cov 1.2, a 0.3)");

    walls_untie(500, 1);
    walls_untie(2000, 2);
    ks_goals(500, 1.2, 0.3, 8);
    ks_goals(200, 0.8, 1.0, 8);
    ks_phase_keeps_threshold();
    slow_at_goals(500, 0.1, 3);
    slow_only_at_goals();

    gp_imc_params p;
    /* --- a wrong specimen that a histogram error passes: 4 equal-probability classes at
     * COV 0.2 are matched exactly by cells whose COV is far from 0.2; the AD error is not --- */
    gp_imc_params_defaults(&p);
    p.error_kind = 3;
    p.threshold = 1e-9;
    p.cov = 0.2;
    p.classes_size = p.classes_orient = 4;
    {
        gp_voronoi *v = NULL;
        gp_imc_report r;
        gp_status st = run(SQ, 4, NULL, NULL, 0, 500, &p, &v, &r, "E3, 4 classes, cov 0.2");
        cell_stats c = cell_stats_of(v, &p);
        printf("    E3 %.5f but KS %.4f (critical %.4f), COV %.4f for 0.2, AD size error %.2f\n", r.error, c.ks,
               1.36 / sqrt(500), c.cov, c.ad_size);
        CHECK(st == GP_OK && r.error == 0.0);
        CHECK(c.ks > 1.36 / sqrt(500) || fabs(c.cov / 0.2 - 1) > 0.2);
        CHECK(c.ad_size > 10 * gp_imc_default_threshold(GP_IMC_ERROR_AD));
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
    }
    /* --- N = 1: nothing can move; the run says so at once --- */
    gp_imc_params_defaults(&p);
    {
        gp_voronoi *v = NULL;
        gp_imc_report r;
        gp_status st = run(SQ, 4, NULL, NULL, 0, 1, &p, &v, &r, "one cell");
        CHECK(st == GP_ERR_NOT_CONVERGED && r.stop_reason == GP_IMC_STOP_SINGLE_CELL && r.steps == 0);
        CHECK(v && gp_voronoi_cell_area(v, 0) == 1.0);
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
    }
    /* --- floor: 25 classes at N = 500 cannot reach 0.002 (NOTES.md: ~0.0029) --- */
    gp_imc_params_defaults(&p);
    p.error_kind = 3;
    p.threshold = 0.002;
    p.cov = 0.3;
    p.anisotropy = 0.3;
    p.classes_size = 25;
    p.classes_orient = 25;
    {
        gp_voronoi *v = NULL;
        gp_imc_report r;
        gp_error e;
        gp_status st = gp_imc_run(SQ, 4, NULL, NULL, 0, 500, &p, NULL, NULL, NULL, &v, &r, &e);
        CHECK(st == GP_ERR_INFEASIBLE);
        CHECK(r.stop_reason == GP_IMC_STOP_FLOOR);
        CHECK(r.steps == 0);
        CHECK(r.floor > 0.002 && r.floor < 0.004);
        CHECK(strstr(e.message, "floor") != NULL);
        CHECK(gp_imc_reachable_threshold(&p, 500) == r.floor);
        CHECK(v != NULL);
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
    }
    /* floor of uniform targets 1/k at N divisible by k is 0; sqrt(k/12)/N on average otherwise */
    {
        double t[25];
        for (int k = 0; k < 10; k++) t[k] = 0.1;
        CHECK_NEAR(gp_imc_floor(t, 10, 500, 3), 0.0, 1e-15);
        /* 3 classes of 1/3 at N = 100: counts 34, 33, 33 -> sqrt(4/9 + 1/9 + 1/9) / 100 */
        for (int k = 0; k < 3; k++) t[k] = 1.0 / 3;
        CHECK_NEAR(gp_imc_floor(t, 3, 100, 3), sqrt(6.0 / 9.0) / 100, 1e-12);
        CHECK_NEAR(gp_imc_floor(t, 3, 100, 2), (2.0 / 3.0) / 100, 1e-12);
    }
    /* automatic classes keep the threshold reachable; AD has no floor */
    gp_imc_params_defaults(&p);
    CHECK(gp_imc_reachable_threshold(&p, 20) == 0.0);
    p.error_kind = 3;
    p.threshold = 0.002;
    CHECK(gp_imc_reachable_threshold(&p, 20) > 0.01); /* 3 x 3 classes at N = 20 */
    p.max_steps = 0;
    {
        gp_voronoi *v = NULL;
        gp_imc_report r;
        gp_imc_run(SQ, 4, NULL, NULL, 0, 500, &p, NULL, NULL, NULL, &v, &r, NULL);
        CHECK(r.floor <= 0.5 * p.threshold);
        CHECK(r.stop_reason == GP_IMC_STOP_MAX_STEPS || r.stop_reason == GP_IMC_STOP_THRESHOLD);
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
    }

    /* --- seeds numbered along a Hilbert curve (memory locality), the caller's kept --- */
    {
        gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
        gp_vec2 strip[4] = {{0, 0}, {10, 0}, {10, 1}, {0, 1}};
        seed_order("order: square, uniform", SQ, 4, NULL, NULL, 0, 5000, 0);
        seed_order("order: square, Halton", SQ, 4, NULL, NULL, 0, 5000, 1);
        seed_order("order: L-shape", L, 6, NULL, NULL, 0, 3000, 0);
        seed_order("order: 10:1 strip", strip, 4, NULL, NULL, 0, 3000, 0);
    }

    /* --- determinism: same seed, same tessellation bit for bit; another seed differs --- */
    gp_imc_params_defaults(&p);
    p.cov = 0.6;
    p.max_steps = 20000;
    {
        gp_voronoi *a = NULL, *b = NULL, *c = NULL;
        gp_imc_report ra, rb, rc;
        gp_imc_run(SQ, 4, NULL, NULL, 0, 300, &p, NULL, NULL, NULL, &a, &ra, NULL);
        gp_imc_run(SQ, 4, NULL, NULL, 0, 300, &p, NULL, NULL, NULL, &b, &rb, NULL);
        p.seed = 2;
        gp_imc_run(SQ, 4, NULL, NULL, 0, 300, &p, NULL, NULL, NULL, &c, &rc, NULL);
        int same = a && b, diff = 0;
        for (size_t i = 0; same && i < 300; i++) {
            gp_vec2 x = gp_voronoi_seed(a, i), y = gp_voronoi_seed(b, i), z = gp_voronoi_seed(c, i);
            same &= memcmp(&x, &y, sizeof x) == 0;
            diff |= memcmp(&x, &z, sizeof x) != 0;
        }
        CHECK(same);
        CHECK(diff);
        CHECK(ra.steps == rb.steps && ra.error == rb.error);
        gp_voronoi_destroy(a);
        gp_voronoi_destroy(b);
        gp_voronoi_destroy(c);
        gp_imc_report_free(&ra);
        gp_imc_report_free(&rb);
        gp_imc_report_free(&rc);
    }

    /* --- cancellation: the flag, and the progress callback --- */
    gp_imc_params_defaults(&p);
    p.classes_size = 20; /* will not converge */
    p.classes_orient = 20;
    p.threshold = 1e-9;
    p.max_steps = 100000;
    {
        volatile int flag = 1;
        gp_voronoi *v = NULL;
        gp_imc_report r;
        gp_status st = gp_imc_run(SQ, 4, NULL, NULL, 0, 200, &p, NULL, NULL, &flag, &v, &r, NULL);
        CHECK(st == GP_ERR_CANCELLED && r.stop_reason == GP_IMC_STOP_CANCELLED && r.steps == 0);
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
        int stop = 1;
        st = gp_imc_run(SQ, 4, NULL, NULL, 0, 200, &p, progress_cb, &stop, NULL, &v, &r, NULL);
        CHECK(st == GP_ERR_CANCELLED && r.steps == 8192 && cb_calls >= 2);
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
        cb_calls = 0;
        p.max_steps = 10000;
        st = gp_imc_run(SQ, 4, NULL, NULL, 0, 200, &p, progress_cb, NULL, NULL, &v, &r, NULL);
        CHECK(st == GP_ERR_NOT_CONVERGED && r.stop_reason == GP_IMC_STOP_MAX_STEPS && r.steps == 10000);
        CHECK(cb_calls == 3 && cb_last == 10000); /* 4096, 8192, and the end */
        gp_voronoi_destroy(v);
        gp_imc_report_free(&r);
    }

    /* --- bad input --- */
    gp_imc_params_defaults(&p);
    {
        gp_voronoi *v = (gp_voronoi *)1;
        gp_error e;
        p.anisotropy = 0;
        CHECK(gp_imc_run(SQ, 4, NULL, NULL, 0, 100, &p, NULL, NULL, NULL, &v, NULL, &e) == GP_ERR_INVALID && !v);
        gp_imc_params_defaults(&p);
        p.cov = -1;
        CHECK(gp_imc_run(SQ, 4, NULL, NULL, 0, 100, &p, NULL, NULL, NULL, &v, NULL, &e) == GP_ERR_INVALID);
        gp_imc_params_defaults(&p);
        /* duplicate initial seeds: a clear error */
        gp_vec2 s[3] = {{0.1, 0.1}, {0.5, 0.5}, {0.1, 0.1}};
        p.seeds = s;
        CHECK(gp_imc_run(SQ, 4, NULL, NULL, 0, 3, &p, NULL, NULL, NULL, &v, NULL, &e) == GP_ERR_INVALID);
        CHECK(strstr(e.message, "duplicate") != NULL);
    }

    /* --- hard cases --- */
    const long HS = 30000;
    gp_imc_params_defaults(&p);
    p.max_steps = HS;
    {
        /* collinear initial seeds (a diagonal), seeds on the boundary and at corners */
        enum { N = 200 };
        gp_vec2 s[N];
        for (int i = 0; i < N; i++) s[i] = (gp_vec2){(i + 0.5) / N, (i + 0.5) / N};
        p.seeds = s;
        hard("collinear seeds", SQ, 4, NULL, NULL, 0, N, &p);
        for (int i = 0; i < N; i++) {
            double t = (double)i / N;
            s[i] = i % 4 == 0 ? (gp_vec2){t, 0} : i % 4 == 1 ? (gp_vec2){1, t} : i % 4 == 2 ? (gp_vec2){1 - t, 1} : (gp_vec2){0, 1 - t};
        }
        s[0] = (gp_vec2){0, 0};
        s[1] = (gp_vec2){1, 1};
        hard("seeds on the boundary", SQ, 4, NULL, NULL, 0, N, &p);
        p.seeds = NULL;
    }
    {
        /* same statistics at scales 1e-6 and 1e6 */
        gp_vec2 a[4], b[4];
        for (int k = 0; k < 4; k++) {
            a[k] = (gp_vec2){SQ[k].x * 1e-6, SQ[k].y * 1e-6};
            b[k] = (gp_vec2){SQ[k].x * 1e6, SQ[k].y * 1e6};
        }
        gp_imc_params q;
        gp_imc_params_defaults(&q);
        q.cov = 0.8;
        q.max_steps = 300000;
        gp_voronoi *v1 = NULL, *v2 = NULL, *v0 = NULL;
        gp_imc_report r1, r2, r0;
        gp_status s0 = run(SQ, 4, NULL, NULL, 0, 300, &q, &v0, &r0, "unit square");
        gp_status s1 = run(a, 4, NULL, NULL, 0, 300, &q, &v1, &r1, "unit square x 1e-6");
        gp_status s2 = run(b, 4, NULL, NULL, 0, 300, &q, &v2, &r2, "unit square x 1e6");
        CHECK(s0 == GP_OK && s1 == GP_OK && s2 == GP_OK);
        CHECK(r1.nsize == r0.nsize && r2.nsize == r0.nsize && r1.norient == r0.norient);
        CHECK_REL(r1.size_edges[1], r0.size_edges[1] * 1e-12, 1e-12);
        CHECK_REL(r2.size_edges[1], r0.size_edges[1] * 1e12, 1e-12);
        if (v1) check_report(v1, &r1, &q);
        if (v2) check_report(v2, &r2, &q);
        gp_voronoi_destroy(v0);
        gp_voronoi_destroy(v1);
        gp_voronoi_destroy(v2);
        gp_imc_report_free(&r0);
        gp_imc_report_free(&r1);
        gp_imc_report_free(&r2);
    }
    {
        gp_vec2 strip[4] = {{0, 0}, {1000, 0}, {1000, 1}, {0, 1}};
        hard("1000:1 strip", strip, 4, NULL, NULL, 0, 300, &p);
        gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
        hard("L-shape", L, 6, NULL, NULL, 0, 300, &p);
        gp_vec2 *c, *h;
        size_t nc, nh;
        gp_voronoi_circle_polygon((gp_vec2){0, 0}, 1.0, 1e-3, &c, &nc, NULL);
        gp_voronoi_circle_polygon((gp_vec2){0, 0}, 0.4, 1e-3, &h, &nh, NULL);
        const gp_vec2 *holes[1] = {h};
        hard("annulus", c, nc, holes, &nh, 1, 300, &p);
        p.init = 1;
        hard("annulus, Halton", c, nc, holes, &nh, 1, 300, &p);
        p.init = 0;
        free(c);
        free(h);
        p.cov = 0.05;
        hard("cov 0.05", SQ, 4, NULL, NULL, 0, 300, &p);
        p.cov = 1.5;
        hard("cov 1.5", SQ, 4, NULL, NULL, 0, 300, &p);
        p.cov = 0.5;
        p.anisotropy = 0.05;
        p.mean_deg = 30;
        hard("anisotropy 0.05, 30 deg", SQ, 4, NULL, NULL, 0, 300, &p);
        p.error_kind = 1;
        p.threshold = 0.002;
        hard("E1", SQ, 4, NULL, NULL, 0, 300, &p);
        p.error_kind = 2;
        hard("E2", SQ, 4, NULL, NULL, 0, 300, &p);
    }
    {
        gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
        gp_vec2 *c, *h;
        size_t nc, nh;
        gp_voronoi_circle_polygon((gp_vec2){0, 0}, 1.0, 1e-3, &c, &nc, NULL);
        gp_voronoi_circle_polygon((gp_vec2){0, 0}, 0.4, 1e-3, &h, &nh, NULL);
        const gp_vec2 *holes[1] = {h};
        for (int t = 1; t <= 3; t += 2) {
            rebuild_matches("rebuild: square", SQ, 4, NULL, NULL, 0, 400, t);
            rebuild_matches("rebuild: L-shape", L, 6, NULL, NULL, 0, 400, t);
            rebuild_matches("rebuild: annulus", c, nc, holes, &nh, 1, 300, t);
        }
        threads_agree("threads: square, max_steps", SQ, 4, NULL, NULL, 0, 500, 0.1, 15001, 0);
        threads_agree("threads: annulus, cancel at 8192", c, nc, holes, &nh, 1, 300, 0.8, 1000000, 1);
        threads_agree("threads: L-shape, threshold", L, 6, NULL, NULL, 0, 400, 0.5, 1000000, 0);
        threads_agree("threads: square, stalled at the goals", SQ, 4, NULL, NULL, 0, 500, 0.1, 1000000, 0);
        /* from 20,000 cells on the run warms its jumps' cells ahead (gp_imc.c warm_ahead): reads only */
        threads_agree("threads: square, N 20000, jumps warmed", SQ, 4, NULL, NULL, 0, 20000, 0.8, 3000, 0);
        even_in_space();
        free(c);
        free(h);
    }
    return gp_test_summary();
}
