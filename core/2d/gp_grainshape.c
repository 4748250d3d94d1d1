/* gp_grainshape.c -- each grain's own spectrum; see gp_grainshape.h for the law and why. */
#include "gp_grainshape.h"

#include <math.h>
#include <string.h>

#include "gp_rng.h"

int gp_grainshape_varies(const gp_grainshape *gs)
{
    for (size_t n = 1; gs && gs->cov && n < gs->nmodes; n++)
        if (gs->cov[n] > 0.0 && gs->mean[n] > 0.0)
            return 1;
    return 0;
}

/* the log-normal exponent of mode n for the standard normal z, scaled by lambda */
static double log_factor(const gp_grainshape *gs, size_t n, double z, double lambda)
{
    double c = gs->cov[n] > 0.0 ? gs->cov[n] : 0.0;
    double s2 = log1p(c * c);
    return lambda * (sqrt(s2) * z - 0.5 * s2);
}

/* D from the z of one try (z[n] for n >= 1), pulled toward the mean by lambda (1: none) */
static void spectrum_of(const gp_grainshape *gs, const double *z, double lambda, double *D)
{
    D[0] = 1.0;
    for (size_t n = 1; n < gs->nmodes; n++)
        D[n] = gs->mean[n] > 0.0 ? gs->mean[n] * exp(log_factor(gs, n, z[n], lambda)) : 0.0;
}

/* GP_OK if D with delta is star-shaped (gp_fourier.h's test), GP_ERR_NOT_STAR if not (err
 * cleared), another error if the test could not be made */
static gp_status star(const gp_grainshape *gs, const double *D, const double *delta,
                      gp_fourier *f, double *r, gp_error *err)
{
    gp_status st = gp_fourier_radii(f, 1.0, D, delta, gs->nmodes, r, err);
    if (st == GP_ERR_NOT_STAR)
        gp_error_clear(err);
    return st;
}

/* every draw failed: the last one pulled toward the mean, else the mean (see the header) */
static gp_status clip(const gp_grainshape *gs, const double *z, const double *delta,
                      gp_fourier *f, double *r, double *D, gp_error *err)
{
    double lambda = 1.0;
    for (int k = 0; k < GP_GRAINSHAPE_CLIP_STEPS; k++) {
        lambda *= 0.5;
        spectrum_of(gs, z, lambda, D);
        gp_status st = star(gs, D, delta, f, r, err);
        if (st != GP_ERR_NOT_STAR)
            return st;
    }
    memcpy(D, gs->mean, gs->nmodes * sizeof *D);
    D[0] = 1.0;
    return GP_OK;
}

static gp_status check_args(const gp_grainshape *gs, const double *delta, gp_fourier *f,
                            const double *r, const double *D, gp_error *err)
{
    if (!gs || !gs->mean || !delta || !f || !r || !D || gs->nmodes < 1)
        return gp_error_set(err, GP_ERR_INVALID, "grainshape: NULL argument or no modes");
    if (gs->nmodes > gp_fourier_max_modes(gp_fourier_np(f)))
        return gp_error_set(err, GP_ERR_INVALID, "grainshape: %zu modes on %zu rays",
                            gs->nmodes, gp_fourier_np(f));
    for (size_t n = 1; gs->cov && n < gs->nmodes; n++)
        if (!(gs->cov[n] >= 0.0 && isfinite(gs->cov[n])))
            return gp_error_set(err, GP_ERR_INVALID, "grainshape: cov of mode %zu is %g", n,
                                gs->cov[n]);
    return GP_OK;
}

/* the z of one try: nmodes - 1 standard normal draws, in mode order (z[0] unused) */
static void draw_z(gp_rng *rng, size_t nmodes, double *z)
{
    z[0] = 0.0;
    for (size_t n = 1; n < nmodes; n++)
        z[n] = gp_rng_gaussian(rng, 1.0);
}

gp_status gp_grainshape_draw(const gp_grainshape *gs, size_t g, const double *delta,
                             gp_fourier *f, double *scratch, double *D,
                             gp_grainshape_outcome *outcome, gp_error *err)
{
    gp_status st = check_args(gs, delta, f, scratch, D, err);
    if (st != GP_OK)
        return st;
    if (outcome)
        *outcome = GP_GRAINSHAPE_DRAWN;
    if (!gp_grainshape_varies(gs)) {
        memcpy(D, gs->mean, gs->nmodes * sizeof *D);
        return GP_OK;
    }
    gp_rng *rng = gp_rng_create(gs->seed, GP_GRAINSHAPE_STREAM + (uint64_t)g, err);
    if (!rng)
        return GP_ERR_NOMEM;
    double *r = scratch, *z = scratch + gp_fourier_np(f);
    st = GP_ERR_NOT_STAR;
    for (int t = 0; t < GP_GRAINSHAPE_TRIES && st == GP_ERR_NOT_STAR; t++) {
        draw_z(rng, gs->nmodes, z);
        spectrum_of(gs, z, 1.0, D);
        st = star(gs, D, delta, f, r, err);
        if (st == GP_OK && t > 0 && outcome)
            *outcome = GP_GRAINSHAPE_REDRAWN;
    }
    gp_rng_destroy(rng);
    if (st != GP_ERR_NOT_STAR)
        return st;
    if (outcome)
        *outcome = GP_GRAINSHAPE_CLIPPED;
    return clip(gs, z, delta, f, r, D, err);
}
