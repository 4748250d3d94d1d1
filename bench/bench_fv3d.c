/* bench_fv3d.c -- the 3D Fourier-Voronoi specimen end to end (gp_fv3d.h): seconds per phase
 * next to what it reached (solid fraction asked and reached, grains short of it, the volume and
 * orientation KS of the grains against critical, the clumps' volume error), and peak memory.
 *
 *   bench_fv3d fraction [N] [THREADS]   asked 0.30 .. 0.60, round and elongated grains
 *   bench_fv3d scale [THREADS]          N = 1,000 and 10,000 with every output
 *   bench_fv3d one N FS ELONG [THREADS] one row
 *   bench_fv3d sieve [SCALE] [THRESHOLD] a sieve of grains by mass (d 0.06-0.16 m x SCALE) at 0.3:
 *                                       the IMC's steps and the passing reached (BENCH_PROGRESS=1
 *                                       prints the IMC's error every 4,096 steps)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "gp_fourier.h"
#include "gp_fv3d.h"

static double D[16];

static double peak_mb(void)
{
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss / 1024.0;
}

static void header(void)
{
    printf("| N | asked | elong. | outputs | threads | IMC s | grains s | total s | reached | per grain min / mean "
           "| short | grain vol KS/crit | grain orient KS/crit | clump vol err | peak MB |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
}

static void row(size_t n, double fs, double el, unsigned outputs, int threads)
{
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.0 / n, 0.5, NULL);
    gp_fv3d_spec sp;
    gp_fv3d_spec_defaults(&sp);
    sp.particles = n;
    sp.law = law;
    sp.D = D;
    sp.nmodes = 16;
    sp.solid_fraction = fs;
    sp.elongation = el;
    sp.flatness = el < 1.0 ? (el < 0.7 ? 0.8 : el) : 1.0;
    sp.outputs = outputs;
    sp.threads = threads;
    sp.seed = 1;
    gp_fv3d *s = NULL;
    gp_error e;
    if (gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e) != GP_OK) {
        printf("| %zu | %.2f | %.2f | failed: %s |\n", n, fs, el, e.message);
        gp_law_destroy(law);
        return;
    }
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    const gp_fv3d_timings *tm = gp_fv3d_timings_of(s);
    double lo = 1, mean = 0;
    for (size_t i = 0; i < n; i++) {
        const gp_fv3d_grain *g = gp_fv3d_grain_at(s, i);
        double f = g->volume / gp_voronoi3d_cell_volume(gp_fv3d_cells(s), g->cell);
        lo = fmin(lo, f);
        mean += f / n;
    }
    printf("| %zu | %.2f | %.2f | %s | %d | %.2f | %.2f | %.2f | %.4f | %.3f / %.3f | %zu | %.2f | %.2f | %.3f | %.0f |\n", n,
           fs, el, outputs & GP_OUT3_CLUMPS ? "all" : "grains", threads, tm->imc, tm->grains, tm->total,
           t->solid_fraction, lo, mean, t->grains_short, t->grain_volume.ks / t->grain_volume.ks_critical,
           t->grain_orientation.ks / t->grain_orientation.ks_critical, t->clump_volume_error_mean, peak_mb());
    fflush(stdout);
    gp_fv3d_destroy(s);
    gp_law_destroy(law);
}

static int show(void *user, const gp_progress *p)
{
    (void)user;
    if (!strcmp(p->phase, "imc")) fprintf(stderr, "  imc step %ld error %.4f\n", p->steps, p->error);
    return 0;
}

/* a sieve of grains: N from the solid fraction, the IMC's work, the passing by mass */
static void sieve(double scale, double threshold)
{
    const double d0[4] = {0.06, 0.09, 0.12, 0.16}, pw[4] = {0, 30, 80, 100};
    double d[4];
    for (int k = 0; k < 4; k++) d[k] = d0[k] * scale;
    gp_law *law = gp_law_create_sieve3d(d, pw, 4, NULL);
    gp_fv3d_spec sp;
    gp_fv3d_spec_defaults(&sp);
    sp.particles = (size_t)lround(0.3 / gp_law_mean(law));
    sp.law = law;
    sp.law_of_grains = 1;
    sp.D = D;
    sp.nmodes = 16;
    sp.solid_fraction = 0.3;
    sp.seed = 7;
    if (threshold > 0) sp.imc_threshold = threshold;
    gp_fv3d *s = NULL;
    gp_error e;
    if (gp_fv3d_build(&sp, getenv("BENCH_PROGRESS") ? show : NULL, NULL, NULL, &s, &e) != GP_OK) {
        printf("sieve x %.2f: failed: %s\n", scale, e.message);
    } else {
        const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
        printf("| sieve x %.2f | N %zu | IMC %ld steps, stop %d, error %.4f, %.1f s | grains %.1f s | passing within "
               "%.2f pp | grain volume KS/crit %.2f | short %zu | reached %.4f |\n", scale, sp.particles, t->imc_steps,
               t->imc_stop, t->imc_error, gp_fv3d_timings_of(s)->imc, gp_fv3d_timings_of(s)->grains,
               t->passing.max_error_pp, t->grain_volume.ks / t->grain_volume.ks_critical, t->grains_short,
               t->solid_fraction);
    }
    gp_fv3d_destroy(s);
    gp_law_destroy(law);
}

int main(int argc, char **argv)
{
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 16, D, NULL);
    const char *mode = argc > 1 ? argv[1] : "fraction";
    unsigned all = GP_OUT3_GRAINS | GP_OUT3_CLUMPS | GP_OUT3_DESCRIPTORS;
    header();
    if (!strcmp(mode, "fraction")) {
        size_t n = argc > 2 ? (size_t)atol(argv[2]) : 1000;
        int th = argc > 3 ? atoi(argv[3]) : 1;
        const double fs[4] = {0.30, 0.45, 0.55, 0.60}, el[2] = {1.0, 0.6};
        for (int j = 0; j < 2; j++)
            for (int k = 0; k < 4; k++) row(n, fs[k], el[j], GP_OUT3_GRAINS, th);
    } else if (!strcmp(mode, "scale")) {
        int th = argc > 2 ? atoi(argv[2]) : 1;
        row(1000, 0.45, 1.0, all, th);
        row(10000, 0.45, 1.0, all, th);
    } else if (!strcmp(mode, "sieve")) {
        sieve(argc > 2 ? atof(argv[2]) : 1.0, argc > 3 ? atof(argv[3]) : 0.0);
    } else if (!strcmp(mode, "one") && argc >= 5) {
        row((size_t)atol(argv[2]), atof(argv[3]), atof(argv[4]), all, argc > 5 ? atoi(argv[5]) : 1);
    } else {
        fprintf(stderr, "usage: bench_fv3d fraction [N] [THREADS] | scale [THREADS] | one N FS ELONG [THREADS] | "
                        "sieve [SCALE] [THRESHOLD]\n");
        return 2;
    }
    return 0;
}
