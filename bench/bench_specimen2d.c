/* bench_specimen2d.c -- the 2D specimen end to end, speed next to error.
 *
 * Rows: the paper's Example 1 and 2 (500 grains, E3 <= 0.002, filled to F_S = 0.65, ODEC and
 * descriptors), the filling rate with 1 and 2 threads, and a 10,000-grain specimen.
 * Columns: seconds per phase, grains filled per second (wall, and per thread), the IMC error
 * reached, the achieved solid fraction, the mean orientation gap between grains and their
 * cells, and the error of the mean elongation against (1 - D2)/(1 + D2).
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
} row;

static void run(const row *r)
{
    gp_spec2d s;
    gp_spec2d_defaults(&s);
    s.seed = 2012;
    s.particles = r->n;
    s.cov = r->cov;
    s.anisotropy = r->aniso;
    s.D2 = r->D2;
    s.D3 = r->D3;
    s.D8 = r->D8;
    s.threads = r->threads;
    s.outputs = r->outputs;
    gp_specimen2d *sp = NULL;
    gp_error e;
    gp_status st = gp_specimen2d_build(&s, NULL, NULL, NULL, &sp, &e);
    if (st != GP_OK) {
        printf("| %-22s | failed: %s |\n", r->name, e.message);
        return;
    }
    double fill_rate = sp->t_fill > 0 ? (double)sp->ngrains / sp->t_fill : 0.0;
    double el_err = (r->outputs & GP_OUT_DESCRIPTORS)
                        ? fabs(sp->descriptor_mean.elongation - (1 - r->D2) / (1 + r->D2)) : NAN;
    printf("| %-22s | %6zu | %2d | %8ld | %7.2f | %6.2f | %6.2f | %6.2f | %7.2f | %8.0f | %8.5f | %6.4f | %5.2f | %7.4f |\n",
           r->name, sp->ngrains, r->threads, sp->imc_steps, sp->t_imc, sp->t_fill, sp->t_odec,
           sp->t_descriptors, sp->t_total, fill_rate, sp->imc_error, sp->solid_fraction,
           sp->mean_orientation_gap_deg, el_err);
    fflush(stdout);
    gp_specimen2d_destroy(sp);
}

int main(int argc, char **argv)
{
    int quick = argc > 1 && strcmp(argv[1], "quick") == 0;
    unsigned all = GP_OUT_GRAINS | GP_OUT_ODEC | GP_OUT_DESCRIPTORS;
    row rows[] = {
        {"Example 1 (all outputs)", 500, 0.8, 1.0, 0.1, 0.05, 0.02, 1, all},
        {"Example 2 (all outputs)", 500, 0.2, 0.1, 0.2, 0.01, 0.0, 1, all},
        {"Example 1, grains only", 500, 0.8, 1.0, 0.1, 0.05, 0.02, 1, GP_OUT_GRAINS},
        {"Example 1, 2 threads", 500, 0.8, 1.0, 0.1, 0.05, 0.02, 2, all},
        {"10,000 grains, 2 thr.", 10000, 0.5, 1.0, 0.1, 0.05, 0.02, 2, all},
    };
    printf("2D Fourier-Voronoi specimen, end to end (F_S = 0.65, E3 threshold 0.002, Np = 128)\n");
    printf("fill/s = grains filled per second of the fill phase (wall time; per thread divide by th)\n\n");
    printf("| %-22s | %6s | %2s | %8s | %7s | %6s | %6s | %6s | %7s | %8s | %8s | %6s | %5s | %7s |\n",
           "case", "grains", "th", "IMC step", "IMC s", "fill s", "odec s", "desc s", "total s",
           "fill/s", "E3", "SF", "gap", "|dElong|");
    printf("|%s|\n", "------------------------|--------|----|----------|---------|--------|--------|--------|---------|----------|----------|--------|-------|---------");
    size_t nrows = sizeof rows / sizeof rows[0];
    for (size_t i = 0; i < nrows; i++) {
        if (quick && rows[i].n > 1000)
            continue;
        run(&rows[i]);
    }
    return 0;
}
