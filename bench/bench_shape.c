/* bench_shape.c -- speed of grain generation + shape description, and the discretisation error
 * of the four descriptors versus the number of contour points.
 *
 * The same NG grains (spectrum D2 = 0.1, D3 = 0.05, D8 = 0.02, alpha = beta = -2, modes
 * 0..31 so that every row can represent them, phases from a fixed seed) are generated with
 * gp_fourier at Np = 64 .. 1024 and described; each descriptor is compared with the same
 * grain's description at Np = 8192 (the reference). Regularity is shown twice: P and P_conv
 * from the Np-point contour (gp_shape_describe) and from the curve at max(Np, 512) points
 * (gp_shape_describe_fourier, the variant the specimen should use).
 *
 * Columns: grains/s = gp_fourier_contour + gp_shape_describe_fourier per grain (best of 3
 * passes, one thread); odec/s = gp_odec_build alone; then mean |descriptor(Np) - reference|.
 * Usage: bench_shape [ngrains]   (default 200)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "gp_fourier.h"
#include "gp_odec.h"
#include "gp_shape.h"

#define NMODES 32
#define NREF 8192

static double u01(void *state)
{
    uint64_t *s = state;
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct desc {
    double el, ro, ci, reg_contour, reg_curve;
} desc;

static int describe(gp_fourier *f, size_t np, const double *D, const double *dl, desc *d,
                    gp_vec2 *pts)
{
    gp_error e;
    if (gp_fourier_contour(f, (gp_vec2){0, 0}, 1.0, D, dl, NMODES, pts, NULL, &e) != GP_OK) {
        fprintf(stderr, "contour: %s\n", e.message);
        return 0;
    }
    gp_shape_result a, b;
    gp_shape_curve cv = {{0, 0}, 1.0, D, dl, NMODES};
    if (gp_shape_describe(pts, np, NULL, &a, &e) != GP_OK ||
        gp_shape_describe_ex(pts, np, NULL, NULL, 0, &cv, &b, &e) != GP_OK) {
        fprintf(stderr, "describe: %s\n", e.message);
        return 0;
    }
    d->el = a.elongation;
    d->ro = a.roundness;
    d->ci = a.circularity;
    d->reg_contour = a.regularity;
    d->reg_curve = b.regularity;
    return 1;
}

int main(int argc, char **argv)
{
    int ng = argc > 1 ? atoi(argv[1]) : 200;
    if (ng < 1)
        ng = 200;
    double D[NMODES];
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, NMODES, D, NULL);
    double *ph = malloc((size_t)ng * NMODES * sizeof *ph);
    desc *ref = malloc((size_t)ng * sizeof *ref);
    gp_vec2 *pts = malloc(NREF * sizeof *pts);
    uint64_t seed = 20120101;
    for (int g = 0; g < ng; g++)
        gp_fourier_random_phases(NMODES, u01, &seed, ph + (size_t)g * NMODES, NULL);

    double t0 = now();
    gp_fourier *fr = gp_fourier_create(NREF, NULL);
    for (int g = 0; g < ng; g++) {
        if (!describe(fr, NREF, D, ph + (size_t)g * NMODES, &ref[g], pts))
            return 1;
    }
    gp_fourier_destroy(fr);
    double tref = now() - t0;

    printf("bench_shape: %d grains, D2=0.1 D3=0.05 D8=0.02 alpha=beta=-2, modes 0..%d; "
           "reference Np=%d (%.1f s)\n", ng, NMODES - 1, NREF, tref);
    printf("%6s | %9s | %8s | %9s | %9s | %9s | %9s | %9s\n", "Np", "grains/s", "odec/s",
           "|d elong|", "|d round|", "|d circ|", "|d reg|", "|d reg512|");
    printf("-------+-----------+----------+-----------+-----------+-----------+-----------+"
           "-----------\n");
    size_t nps[] = {64, 128, 256, 512, 1024};
    for (size_t k = 0; k < sizeof nps / sizeof *nps; k++) {
        size_t np = nps[k];
        gp_fourier *f = gp_fourier_create(np, NULL);
        double se = 0, sr = 0, sc = 0, sg = 0, sg5 = 0;
        int nreg = 0, nreg5 = 0;
        for (int g = 0; g < ng; g++) {
            desc d;
            if (!describe(f, np, D, ph + (size_t)g * NMODES, &d, pts))
                return 1;
            se += fabs(d.el - ref[g].el);
            sr += fabs(d.ro - ref[g].ro);
            sc += fabs(d.ci - ref[g].ci);
            sg += fabs(d.reg_contour - ref[g].reg_contour);
            sg5 += fabs(d.reg_curve - ref[g].reg_contour);
            nreg++;
            nreg5++;
        }
        /* throughput: generate + describe (curve variant), and ODEC alone */
        double best = 1e300, besto = 1e300;
        gp_shape_curve cv = {{0, 0}, 1.0, D, NULL, NMODES};
        for (int pass = 0; pass < 3; pass++) {
            double a = now();
            for (int g = 0; g < ng; g++) {
                gp_shape_result s;
                cv.delta = ph + (size_t)g * NMODES;
                gp_fourier_contour(f, (gp_vec2){0, 0}, 1.0, D, cv.delta, NMODES, pts, NULL, NULL);
                gp_shape_describe_fourier(pts, np, &cv, NULL, &s, NULL);
            }
            double b = now(), to = 0;
            for (int g = 0; g < ng; g++) {
                gp_odec_result od;
                gp_fourier_contour(f, (gp_vec2){0, 0}, 1.0, D, ph + (size_t)g * NMODES, NMODES,
                                   pts, NULL, NULL);
                double c0 = now();
                gp_odec_build(pts, np, NULL, &od, NULL);
                to += now() - c0;
                gp_odec_result_free(&od);
            }
            best = fmin(best, b - a);
            besto = fmin(besto, to);
        }
        gp_fourier_destroy(f);
        printf("%6zu | %9.0f | %8.0f | %9.2e | %9.2e | %9.2e | %9.2e | %9.2e\n", np, ng / best,
               ng / besto, se / ng, sr / ng, sc / ng, sg / nreg, sg5 / nreg5);
    }
    printf("(|d reg|: P, P_conv from the Np-point contour; |d reg512|: from the curve at "
           "max(Np, 512) points; reference: the %d-point contour)\n", NREF);
    free(ph);
    free(ref);
    free(pts);
    return 0;
}
