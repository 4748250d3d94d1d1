/* bench_imc3d.c -- the 3D IMC (gp_imc3d.h): seconds to fit next to what the cells achieved,
 * and the raw step rate.
 *
 * Fit rows: a unit box, lognormal volumes of COV 0.2, 0.5, 1.0, orientations isotropic and
 * a = 0.3 about z, N = 1,000 and 5,000 (and 10,000 at COV 0.5), the default threshold: steps, seconds
 * (the first tessellation and the steps), the volume KS over its 5 % critical value, the COV
 * error, the orientation KS over critical -- measured on the tessellation's cells after the
 * run, not read from the run's error.
 * Rate rows: N = 1,000 and 100,000, COV 0.5, a threshold the run never reaches, `steps` steps
 * timed by the progress reports (the first at step 4,096 to the last), so that the first
 * tessellation does not count.
 * Usage: bench_imc3d [fit|rate|all] [steps]   (all; 20,000) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_clock.h"
#include "gp_fit.h"
#include "gp_imc3d.h"

static const double LO[3] = {0, 0, 0}, HI[3] = {1, 1, 1};

static void fit_row(size_t n, double cov, double a)
{
    gp_voronoi3d_container c = gp_voronoi3d_box(LO, HI);
    gp_imc3d_params p;
    gp_imc3d_params_defaults(&p);
    p.cov = cov;
    p.anisotropy = a;
    gp_voronoi3d *v = NULL;
    gp_imc3d_report r;
    gp_error e;
    double t0 = gp_clock_seconds();
    gp_imc3d_run(&c, n, &p, NULL, NULL, NULL, &v, &r, &e);
    double t = gp_clock_seconds() - t0;
    if (!v) {
        printf("| %6zu | %4.2f | %4.2f | failed: %s |\n", n, cov, a, e.message);
        return;
    }
    double *vol = malloc(n * sizeof *vol), *cs = malloc(n * sizeof *cs), I[9];
    for (size_t i = 0; i < n; i++) {
        vol[i] = gp_voronoi3d_cell_volume(v, i);
        gp_voronoi3d_cell_inertia(v, i, I);
        cs[i] = gp_orient3d_cos(I, p.axis);
    }
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.0 / (double)n, cov, NULL);
    gp_fit_area f;
    gp_fit_area_measure(vol, n, law, 0, &f, NULL);
    double ko = gp_orient3d_ks(cs, n, a);
    printf("| %6zu | %4.2f | %4.2f | %8ld | %-9s | %7.2f | %5.2f | %+6.2f %% | %5.2f |\n", n, cov, a, r.steps,
           gp_imc_stop_name(r.stop_reason), t, f.ks / f.ks_critical, 100 * (f.cov / cov - 1), ko / f.ks_critical);
    fflush(stdout);
    gp_fit_area_free(&f);
    gp_law_destroy(law);
    free(vol);
    free(cs);
    gp_voronoi3d_destroy(v);
}

typedef struct marks {
    double t0, t1;
    long s0, s1;
} marks;

static int mark(void *user, const gp_progress *pr)
{
    marks *m = user;
    double t = gp_clock_seconds();
    if (m->s0 < 0) {
        m->t0 = t;
        m->s0 = pr->steps;
    }
    m->t1 = t;
    m->s1 = pr->steps;
    return 0;
}

static void rate_row(size_t n, long steps)
{
    gp_voronoi3d_container c = gp_voronoi3d_box(LO, HI);
    gp_imc3d_params p;
    gp_imc3d_params_defaults(&p);
    p.threshold = 1e-12;
    p.max_steps = steps;
    gp_voronoi3d *v = NULL;
    gp_imc3d_report r;
    marks m = {0, 0, -1, -1};
    gp_imc3d_run(&c, n, &p, mark, &m, NULL, &v, &r, NULL);
    double t = m.t1 - m.t0;
    printf("| %6zu | %8ld | %8ld | %7.2f | %6.2f | %9.0f | %9.4g |\n", n, r.steps, r.accepted, r.t_init, t,
           t > 0 ? (double)(m.s1 - m.s0) / t : 0.0, r.error);
    fflush(stdout);
    gp_voronoi3d_destroy(v);
}

int main(int argc, char **argv)
{
    const char *mode = argc > 1 ? argv[1] : "all";
    long steps = argc > 2 ? atol(argv[2]) : 20000;
    if (strcmp(mode, "rate") != 0) {
        printf("3D IMC fits (unit box, default threshold %g; one thread)\n\n",
               gp_imc_default_threshold(GP_IMC_ERROR_AD));
        printf("| N | COV | a | steps | stop | s | volume KS/crit | COV err | orient KS/crit |\n");
        printf("|---|---|---|---|---|---|---|---|---|\n");
        const double covs[3] = {0.2, 0.5, 1.0};
        const size_t ns[2] = {1000, 5000};
        for (int j = 0; j < 2; j++)
            for (int k = 0; k < 3; k++) {
                fit_row(ns[j], covs[k], 1.0);
                fit_row(ns[j], covs[k], 0.3);
            }
        fit_row(10000, 0.5, 1.0);
        printf("\n");
    }
    if (strcmp(mode, "fit") != 0) {
        printf("3D IMC step rate (COV 0.5, threshold never reached; timed from step 4,096)\n\n");
        printf("| N | steps | accepted | init s | steps s | steps/s | error |\n");
        printf("|---|---|---|---|---|---|---|\n");
        rate_row(1000, steps);
        rate_row(100000, steps);
    }
    return 0;
}
