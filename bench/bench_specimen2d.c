/* bench_specimen2d.c -- the 2D specimen end to end, speed next to error.
 *
 * Rows: the paper's Example 1 and 2 (500 grains, filled to F_S = 0.65, ODEC and descriptors)
 * with the default AD objective and with the paper's E3, the filling rate with 1 and 2 threads,
 * a law on the grains ("of": "grains", COV 0.5), a sieve curve by mass (0.5-4 mm in a 0.1 m
 * square), and a 10,000-grain specimen.
 * Columns: seconds per phase, grains filled per second, the IMC error and steps, and what the
 * specimen achieved (from its fit report, measured on the cells and grains): cell- and
 * grain-area KS over its 5 % critical value, the grains' COV error, the sieve's largest
 * passing error, the solid fraction and the mean orientation gap between grains and cells.
 *
 * Usage: bench_specimen2d [quick]   ("quick" skips the 10,000-grain row)
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

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
    s->imc_threshold = r->error == GP_IMC_AD ? 0.1 : 0.002;
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
    printf("| %-24s | %6zu | %2d | %-2s %8ld | %7.2f | %6.2f | %6.2f | %6.2f | %7.2f | %7.0f | %7.4f | %5.2f | %5.2f | %+6.1f %% | %5.2f | %6.4f | %5.2f |\n",
           r->name, sp->ngrains, r->threads, sp->imc_error_kind, sp->imc_steps, sp->t_imc, sp->t_fill,
           sp->t_odec, sp->t_descriptors, sp->t_total, fill_rate, sp->imc_error,
           f->cell_area.ks / f->cell_area.ks_critical, f->grain_area.ks / f->grain_area.ks_critical,
           100.0 * (f->grain_area.cov / f->grain_area.target_cov - 1.0),
           f->passing.n ? f->passing.max_error_pp : 0.0, sp->solid_fraction,
           sp->mean_orientation_gap_deg);
    fflush(stdout);
    gp_specimen2d_destroy(sp);
}

int main(int argc, char **argv)
{
    int quick = argc > 1 && strcmp(argv[1], "quick") == 0;
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
        {"10,000 grains, 2 thr.", 10000, 0.5, 1.0, 0.1, 0.05, 0.02, 2, all, GP_IMC_AD, 0},
    };
    printf("2D Fourier-Voronoi specimen, end to end (F_S = 0.65, Np = 128; AD threshold 0.1, E3 0.002)\n");
    printf("fill/s = grains filled per second of the fill phase (wall); KS/c = KS distance over its 5 %% "
           "critical value (<= 1 passes); pass = largest sieve error, percentage points\n\n");
    printf("| %-24s | %6s | %2s | %11s | %7s | %6s | %6s | %6s | %7s | %7s | %7s | %5s | %5s | %8s | %5s | %6s | %5s |\n",
           "case", "grains", "th", "IMC steps", "IMC s", "fill s", "odec s", "desc s", "total s",
           "fill/s", "error", "cellK", "grnK", "grn COV", "pass", "SF", "gap");
    printf("|%s|\n", "--------------------------|--------|----|-------------|---------|--------|--------|--------|---------|---------|---------|-------|-------|----------|-------|--------|------");
    size_t nrows = sizeof rows / sizeof rows[0];
    for (size_t i = 0; i < nrows; i++) {
        if (quick && rows[i].n > 1000)
            continue;
        run(&rows[i]);
    }
    return 0;
}
