/* bench_specimen2d.c -- the 2D specimen end to end, speed next to error.
 *
 * Rows: the paper's Example 1 and 2 (500 grains, filled to F_S = 0.65, ODEC and descriptors)
 * with the default AD objective and with the paper's E3, the filling rate with 1 and 2 threads,
 * a law on the grains ("of": "grains", COV 0.5; 500 and 10,000 grains: the larger one sizes
 * its cells for their grains, a second IMC run, whose steps the IMC column adds), a sieve
 * curve by mass (0.5-4 mm in a 0.1 m square), and a 10,000-grain specimen.
 * Columns: seconds per phase, grains filled per second, the IMC error and steps, and what the
 * specimen achieved (from its fit report, measured on the cells and grains): cell- and
 * grain-area KS over its 5 % critical value, the grains' COV error, the sieve's largest
 * passing error, the solid fraction and the mean orientation gap between grains and cells.
 *
 * A second table times the filling alone (issue #16): the cells of Examples 1 and 2 refilled
 * one by one on one thread with the specimen's own spectrum and per-cell phases, timed by the
 * thread's CPU clock (steadier than wall time on a shared machine), next to what the fill
 * achieved: cells that met F_S, the solid fraction of the refilled grains and the mean
 * shortfall of the cells that missed, and whether each grain is the specimen's bit for bit.
 *
 * A third form times the per-grain phases of one specimen alone (issue #16: fill, ODEC and
 * descriptors) next to what they produced: the solid fraction, cells meeting F_S, the mean
 * disc count and the four mean descriptors, and 32-bit hashes of the grains' contours, discs
 * and descriptors, so that two builds can be compared bit for bit in one line.
 *
 * A fourth form runs one law of grains at N grains with the default imc.max_steps for N: the
 * steps of its two IMC runs, and the grain areas' fit before and after the cells' resize.
 *
 * Usage: bench_specimen2d [quick|fill|phases [N [THREADS]]|grainlaw N [THREADS [MAX_STEPS]]]
 * ("quick" skips the 10,000-grain row, "fill" prints only the second table, "phases" only the
 * third: N grains (10,000) on THREADS threads (2), the 10,000-grain row's spec; "grainlaw" the
 * fourth, MAX_STEPS instead of the default)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gp_fill.h"
#include "gp_fourier.h"
#include "gp_imc.h"
#include "gp_rng.h"
#include "gp_specimen2d.h"

typedef struct row {
    const char *name;
    size_t n;
    double cov, aniso, D2, D3, D8;
    int threads;
    unsigned outputs;
    int error;       /* gp_imc_error_kind */
    int law;         /* 0 lognormal on cells, 1 lognormal on grains, 2 the sieve */
} row;

static const gp_vec2 SQ10[4] = {{0, 0}, {0.1, 0}, {0.1, 0.1}, {0, 0.1}};
static const double SIEVE_D[5] = {0.5e-3, 1e-3, 2e-3, 3e-3, 4e-3}, SIEVE_P[5] = {0, 10, 50, 90, 100};

static void setup(const row *r, gp_spec2d *s)
{
    gp_spec2d_defaults(s);
    s->seed = 2012;
    s->particles = r->n;
    s->cov = r->cov;
    s->anisotropy = r->aniso;
    s->D2 = r->D2;
    s->D3 = r->D3;
    s->D8 = r->D8;
    s->threads = r->threads;
    s->outputs = r->outputs;
    s->imc_error = (gp_imc_error_kind)r->error;
    s->imc_threshold = gp_imc_default_threshold(r->error == GP_IMC_AD ? GP_IMC_ERROR_AD : r->error);
    s->size_of_grains = r->law == 1;
    if (r->law == 2) {
        s->outer.pts = (gp_vec2 *)SQ10;
        s->outer.n = 4;
        s->size_law = GP_LAW_SIEVE;
        s->sieve_d = SIEVE_D;
        s->sieve_pass = SIEVE_P;
        s->nsieve = 5;
        s->particles = 0;
    }
}

static void run(const row *r)
{
    gp_spec2d s;
    setup(r, &s);
    gp_specimen2d *sp = NULL;
    gp_error e;
    gp_status st = gp_specimen2d_build(&s, NULL, NULL, NULL, &sp, &e);
    if (st != GP_OK) {
        printf("| %-24s | failed: %s |\n", r->name, e.message);
        return;
    }
    const gp_fit2d *f = &sp->fit;
    double fill_rate = sp->t_fill > 0 ? (double)sp->ngrains / sp->t_fill : 0.0;
    printf("| %-24s | %6zu | %2d | %-2s %8ld | %7.2f | %6.2f | %6.2f | %6.2f | %7.2f | %7.0f | %7.4f | %5.2f | %5.2f | %+6.1f %% | %5.2f | %6.4f | %5zu | %5.2f |\n",
           r->name, sp->ngrains, r->threads, sp->imc_error_kind, sp->imc_steps, sp->t_imc, sp->t_fill,
           sp->t_odec, sp->t_descriptors, sp->t_total, fill_rate, sp->imc_error,
           f->cell_area.ks / f->cell_area.ks_critical, f->grain_area.ks / f->grain_area.ks_critical,
           100.0 * (f->grain_area.cov / f->grain_area.target_cov - 1.0),
           f->passing.n ? f->passing.max_error_pp : 0.0, sp->solid_fraction,
           sp->cells_target_met, sp->mean_orientation_gap_deg);
    fflush(stdout);
    gp_specimen2d_destroy(sp);
}

/* ------------------------------------------------------------------ the filling alone */

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double rng_u01(void *state) { return gp_rng_uniform((gp_rng *)state); }

typedef struct fill_tally {
    size_t cells, met;
    double cpu, short_sum;
    long evals;
} fill_tally;

/* Fills cell i of sp as the specimen does (its spectrum, the phases of stream 1 + i) to the
 * workspace's fraction, a refill from the cell's grain so far (prev[i], when warm); keeps the
 * grain in contour[i] and its result in prev[i] when it is larger than area[i]. */
static int refill_cell(const gp_specimen2d *sp, const gp_spec2d *s, gp_fill_workspace *ws,
                       size_t i, double *phases, gp_vec2 *contour, double *area,
                       gp_fill_result *prev, int warm, fill_tally *t)
{
    const gp_ring *cell = &sp->cells[i].polygons[0];
    size_t nm = sp->shape.nmodes, np = s->contour_points;
    gp_error e;
    gp_rng *rng = gp_rng_create(s->seed, 1 + (uint64_t)i, &e);
    if (!rng || gp_fourier_random_phases(nm, rng_u01, rng, phases, &e) != GP_OK) {
        gp_rng_destroy(rng);
        return -1;
    }
    gp_rng_destroy(rng);
    gp_fill_result r;
    double t0 = cpu_seconds();
    gp_status st = gp_fill_cell_from(ws, cell->pts, cell->n, phases, warm ? &prev[i] : NULL,
                                     contour + np * s->particles, &r, &e);
    t->cpu += cpu_seconds() - t0;
    if (st != GP_OK)
        return -1;
    t->cells++;
    t->met += (size_t)r.target_met;
    t->evals += r.evals;
    if (!r.target_met)
        t->short_sum += s->solid_fraction - r.fraction;
    if (r.area > area[i]) {
        area[i] = r.area;
        prev[i] = r;
        memcpy(contour + np * i, contour + np * s->particles, np * sizeof *contour);
    }
    return 0;
}

/* One pass over the cells of list (all when NULL: the first, else refills) at fraction fs. */
static int fill_pass(const gp_specimen2d *sp, const gp_spec2d *s, double fs, const size_t *list,
                     size_t n, double *phases, gp_vec2 *contour, double *area,
                     gp_fill_result *prev, fill_tally *t)
{
    gp_fill_params fp;
    gp_fill_params_defaults(&fp);
    fp.solid_fraction = fs;
    fp.D = sp->shape.spectrum;
    fp.nmodes = sp->shape.nmodes;
    fp.contour_points = s->contour_points;
    gp_error e;
    gp_fill_workspace *ws = gp_fill_workspace_create(&fp, &e);
    int ok = ws != NULL;
    for (size_t k = 0; ok && k < n; k++) {
        size_t i = list ? list[k] : k;
        ok = sp->cells[i].npolygons == 1 &&
             refill_cell(sp, s, ws, i, phases, contour, area, prev, list != NULL, t) == 0;
    }
    gp_fill_workspace_destroy(ws);
    return ok ? 0 : -1;
}

/* The specimen's refills (gp_specimen2d.c, refill): while the grains fall short of F_S of the
 * container, the cells that met the last fraction asked are refilled to one higher fraction,
 * from their grains, at most 4 times (REFILL_PASSES). Returns the passes run, or -1. */
static int refills(const gp_specimen2d *sp, const gp_spec2d *s, double *phases, gp_vec2 *contour,
                   double *area, gp_fill_result *prev, size_t *met, fill_tally *t)
{
    double goal = s->solid_fraction * sp->container_area * (1.0 - 1e-6);
    double fs = s->solid_fraction;
    int pass = 0;
    for (; pass < 4; pass++) {
        double total = 0.0, met_cells = 0.0, met_grains = 0.0;
        size_t nmet = 0;
        for (size_t i = 0; i < sp->ncells; i++) {
            total += area[i];
            if (area[i] >= fs * sp->cells[i].area * (1.0 - 1e-9)) {
                met[nmet++] = i;
                met_cells += sp->cells[i].area;
                met_grains += area[i];
            }
        }
        if (total >= goal || nmet == 0)
            break;
        fs = fmin(1.0, (met_grains + goal - total) / met_cells);
        if (fill_pass(sp, s, fs, met, nmet, phases, contour, area, prev, t) != 0)
            return -1;
    }
    return pass;
}

static void fill_row(const char *name, const row *r, uint64_t seed)
{
    gp_spec2d s;
    setup(r, &s);
    s.seed = seed;
    s.outputs = GP_OUT2_GRAINS | GP_OUT2_CELLS;
    gp_specimen2d *sp = NULL;
    gp_error e;
    if (gp_specimen2d_build(&s, NULL, NULL, NULL, &sp, &e) != GP_OK) {
        printf("| %-24s | failed: %s |\n", name, e.message);
        return;
    }
    size_t n = sp->ncells, np = s.contour_points;
    double *phases = malloc(sp->shape.nmodes * sizeof *phases), *area = malloc(n * sizeof *area);
    gp_vec2 *contour = malloc((n + 1) * np * sizeof *contour);
    size_t *met = malloc(n * sizeof *met);
    gp_fill_result *prev = malloc(n * sizeof *prev);
    fill_tally t1 = {0}, t2 = {0};
    int ok = phases && area && contour && met && prev && n == sp->ngrains && n == s.particles, passes = -1;
    for (size_t i = 0; ok && i < n; i++)
        area[i] = -1.0;
    ok = ok && fill_pass(sp, &s, s.solid_fraction, NULL, n, phases, contour, area, prev, &t1) == 0;
    double a1 = 0.0, a2 = 0.0;
    for (size_t i = 0; ok && i < n; i++)
        a1 += area[i];
    if (ok)
        passes = refills(sp, &s, phases, contour, area, prev, met, &t2);
    size_t same = 0;
    for (size_t i = 0; passes >= 0 && i < n; i++) {
        a2 += area[i];
        same += memcmp(sp->grains[i].contour, contour + np * i, np * sizeof *contour) == 0;
    }
    if (passes < 0)
        printf("| %-24s | failed |\n", name);
    else
        printf("| %-24s | %5zu | %6.3f | %7.0f | %7.1f | %5zu | %6.4f | %8.5f | %6.3f | %7.0f | %5d | %8.6f | %6.3f | %7.0f | %5zu |\n",
               name, t1.cells, t1.cpu, (double)t1.cells / t1.cpu, (double)t1.evals / (double)t1.cells,
               t1.met, a1 / sp->container_area,
               t1.cells > t1.met ? t1.short_sum / (double)(t1.cells - t1.met) : 0.0, t2.cpu,
               t2.cells ? (double)t2.evals / (double)t2.cells : 0.0, passes,
               a2 / sp->container_area, t1.cpu + t2.cpu, (double)n / (t1.cpu + t2.cpu), same);
    fflush(stdout);
    free(phases);
    free(area);
    free(contour);
    free(met);
    free(prev);
    gp_specimen2d_destroy(sp);
}

static void fill_table(void)
{
    row ex[] = {
        {"Example 1", 500, 0.8, 1.0, 0.1, 0.06, 0.03, 1, 0, GP_IMC_AD, 0},
        {"Example 2", 500, 0.2, 0.1, 0.2, 0.01, 0.0, 1, 0, GP_IMC_AD, 0},
        {"Example 1, seed 7", 500, 0.8, 1.0, 0.1, 0.06, 0.03, 1, 0, GP_IMC_AD, 0},
        {"10,000 grains (seed 7)", 10000, 0.5, 1.0, 0.1, 0.05, 0.02, 1, 0, GP_IMC_AD, 0},
    };
    printf("\nThe filling alone, on one thread (F_S = 0.65, Np = 128): the first pass over every cell "
           "(cpu s = thread CPU time in gp_fill_cell, evals per cell, met = cells that reached F_S, "
           "SF = grain area / container area, short = mean F_S - fraction of the cells that "
           "missed), then the specimen's refills of the cells that met F_S (cpu s, evals per "
           "cell, passes, SF after them) and the whole (grains/s of CPU); same = grains equal "
           "to the specimen's bit for bit\n\n");
    printf("| %-24s | %5s | %6s | %7s | %7s | %5s | %6s | %8s | %6s | %7s | %5s | %8s | %6s | %7s | %5s |\n",
           "case", "cells", "cpu s", "fill/s", "evals", "met", "SF", "short", "ref s", "evals",
           "pass", "SF", "all s", "fill/s", "same");
    printf("|--------------------------|-------|--------|---------|---------|-------|--------|----------|--------|---------|-------|----------|--------|---------|-------|\n");
    for (size_t i = 0; i < sizeof ex / sizeof ex[0]; i++)
        fill_row(ex[i].name, &ex[i], i >= 2 ? 7 : 2012);
}

/* ------------------------------------------------------------------ the per-grain phases */

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 0x100000001b3ull;
    return h;
}

static unsigned fold(uint64_t h) { return (unsigned)(h ^ (h >> 32)); }

static void phases_table(size_t n, int threads)
{
    unsigned all = GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS;
    row r = {"phases", n, 0.5, 1.0, 0.1, 0.05, 0.02, threads, all, GP_IMC_AD, 0};
    gp_spec2d s;
    setup(&r, &s);
    gp_specimen2d *sp = NULL;
    gp_error e;
    if (gp_specimen2d_build(&s, NULL, NULL, NULL, &sp, &e) != GP_OK) {
        printf("failed: %s\n", e.message);
        return;
    }
    uint64_t hc = 0xcbf29ce484222325ull, hd = hc, hq = hc;
    double m[5] = {0};
    for (size_t i = 0; i < sp->ngrains; i++) {
        const gp_grain2d *g = &sp->grains[i];
        const gp_descriptors *d = &g->descriptors;
        hc = fnv(hc, g->contour, g->ncontour * sizeof *g->contour);
        hd = fnv(hd, g->discs, 3 * g->ndiscs * sizeof *g->discs);
        hq = fnv(hq, d, sizeof *d);
        m[0] += (double)g->ndiscs;
        m[1] += d->roundness;
        m[2] += d->circularity;
        m[3] += d->regularity;
        m[4] += d->elongation;
    }
    double k = sp->ngrains ? 1.0 / (double)sp->ngrains : 0.0;
    printf("Per-grain phases of the 10,000-grain row's spec with %zu grains on %d thread(s) "
           "(seconds; f+o+d = fill + odec + desc), what they made (SF, cells meeting F_S, mean "
           "discs and descriptors) and hashes of the grains' contours, discs and descriptors\n\n",
           n, threads);
    printf("| grains | th | IMC steps | IMC err | IMC s | fill s | odec s | desc s | f+o+d s | SF | met | discs | "
           "round | circ | regul | elong | contours | discs | desc |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    printf("| %zu | %d | %ld | %.4f | %.2f | %.2f | %.2f | %.2f | %.2f | %.5f | %zu | %.3f | %.5f | %.5f | "
           "%.5f | %.5f | %08x | %08x | %08x |\n",
           sp->ngrains, threads, (long)sp->imc_steps, sp->imc_error, sp->t_imc, sp->t_fill, sp->t_odec, sp->t_descriptors,
           sp->t_fill + sp->t_odec + sp->t_descriptors, sp->solid_fraction, sp->cells_target_met,
           m[0] * k, m[1] * k, m[2] * k, m[3] * k, m[4] * k, fold(hc), fold(hd), fold(hq));
    gp_specimen2d_destroy(sp);
}

/* ------------------------------------------------------------------ a law of grains */

/* One law of grains (COV 0.5, outputs grains) at N grains with the default imc.max_steps for N
 * (or max_steps): the steps of each IMC run against that budget, whether the cells were
 * resized for their grains, and the grain areas' miss before (pass A's grains matched to the
 * law: KS by number or by mass, the larger) and after (the specimen's KS by number). */
static void grain_law_row(size_t n, int threads, long max_steps)
{
    row r = {"grain law", n, 0.5, 1.0, 0.1, 0.05, 0.02, threads, GP_OUT2_GRAINS, GP_IMC_AD, 1};
    gp_spec2d s;
    setup(&r, &s);
    s.imc_max_steps = max_steps > 0 ? max_steps : gp_spec2d_default_max_steps(n);
    s.imc_max_steps_default = max_steps <= 0;
    gp_specimen2d *sp = NULL;
    gp_error e;
    if (gp_specimen2d_build(&s, NULL, NULL, NULL, &sp, &e) != GP_OK) {
        printf("failed: %s\n", e.message);
        return;
    }
    double crit = sp->fit.grain_area.ks_critical;
    long second = sp->imc_steps_resize;
    printf("A law of grains (COV 0.5, seed 2012, outputs grains): IMC steps of each run against "
           "max_steps, the power kappa the cells were drawn together by (1: not resized), grain-area "
           "miss before the resize and KS after, over the 5 %% critical value\n\n");
    printf("| grains | th | max_steps | run 1 | run 2 | stop | AD error | kappa | blocked | before/crit | "
           "after/crit | IMC s | fill s | total s |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    printf("| %zu | %d | %ld%s | %ld | %ld | %s | %.4f | %.3f | %d | %.2f | %.2f | %.1f | %.1f | %.1f |\n",
           sp->ngrains, threads, s.imc_max_steps, s.imc_max_steps_default ? " (default)" : "",
           sp->imc_steps - second, second, sp->imc_stop_reason, sp->imc_error, sp->cell_law_power,
           sp->cells_resize_blocked, sp->grain_law_miss / crit, sp->fit.grain_area.ks / crit,
           sp->t_imc, sp->t_fill, sp->t_total);
    gp_specimen2d_destroy(sp);
}

int main(int argc, char **argv)
{
    if (argc > 2 && strcmp(argv[1], "grainlaw") == 0) {
        grain_law_row((size_t)strtoul(argv[2], NULL, 10), argc > 3 ? atoi(argv[3]) : 2,
                      argc > 4 ? atol(argv[4]) : 0);
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "phases") == 0) {
        phases_table(argc > 2 ? (size_t)strtoul(argv[2], NULL, 10) : 10000,
                     argc > 3 ? atoi(argv[3]) : 2);
        return 0;
    }
    int quick = argc > 1 && strcmp(argv[1], "quick") == 0;
    if (argc > 1 && strcmp(argv[1], "fill") == 0) {
        fill_table();
        return 0;
    }
    unsigned all = GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS;
    row rows[] = {
        {"Example 1 (all outputs)", 500, 0.8, 1.0, 0.1, 0.06, 0.03, 1, all, GP_IMC_AD, 0},
        {"Example 1, paper's E3", 500, 0.8, 1.0, 0.1, 0.06, 0.03, 1, all, GP_IMC_E3, 0},
        {"Example 2 (all outputs)", 500, 0.2, 0.1, 0.2, 0.01, 0.0, 1, all, GP_IMC_AD, 0},
        {"Example 2, paper's E3", 500, 0.2, 0.1, 0.2, 0.01, 0.0, 1, all, GP_IMC_E3, 0},
        {"Example 1, grains only", 500, 0.8, 1.0, 0.1, 0.06, 0.03, 1, GP_OUT2_GRAINS, GP_IMC_AD, 0},
        {"Example 1, 2 threads", 500, 0.8, 1.0, 0.1, 0.06, 0.03, 2, all, GP_IMC_AD, 0},
        {"of grains, COV 0.5", 500, 0.5, 1.0, 0.1, 0.05, 0.02, 2, GP_OUT2_GRAINS, GP_IMC_AD, 1},
        {"sieve 0.5-4 mm, 0.1 m", 0, 0.0, 1.0, 0.1, 0.05, 0.02, 2, GP_OUT2_GRAINS, GP_IMC_AD, 2},
        {"of grains, 10,000", 10000, 0.5, 1.0, 0.1, 0.05, 0.02, 2, GP_OUT2_GRAINS, GP_IMC_AD, 1},
        {"10,000 grains, 2 thr.", 10000, 0.5, 1.0, 0.1, 0.05, 0.02, 2, all, GP_IMC_AD, 0},
    };
    printf("2D Fourier-Voronoi specimen, end to end (F_S = 0.65, Np = 128; AD threshold %g, E3 %g)\n", gp_imc_default_threshold(GP_IMC_ERROR_AD), gp_imc_default_threshold(3));
    printf("fill/s = grains filled per second of the fill phase (wall); KS/c = KS distance over its 5 %% "
           "critical value (<= 1 passes); pass = largest sieve error, percentage points\n\n");
    printf("| %-24s | %6s | %2s | %11s | %7s | %6s | %6s | %6s | %7s | %7s | %7s | %5s | %5s | %8s | %5s | %6s | %5s | %5s |\n",
           "case", "grains", "th", "IMC steps", "IMC s", "fill s", "odec s", "desc s", "total s",
           "fill/s", "error", "cellK", "grnK", "grn COV", "pass", "SF", "met", "gap");
    printf("|%s|\n", "--------------------------|--------|----|-------------|---------|--------|--------|--------|---------|---------|---------|-------|-------|----------|-------|--------|-------|------");
    size_t nrows = sizeof rows / sizeof rows[0];
    for (size_t i = 0; i < nrows; i++) {
        if (quick && rows[i].n > 1000)
            continue;
        run(&rows[i]);
    }
    fill_table();
    return 0;
}
