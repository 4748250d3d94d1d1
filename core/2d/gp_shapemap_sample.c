/* gp_shapemap_sample.c -- the sampler of gp_shapemap.h: a fixed set of random-phase grains
 * described with the specimen's own geometry. Used by the table generator (every node) and by
 * the refinement (every evaluation), so that both measure the same way. */
#include "gp_shapemap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_fourier.h"
#include "gp_rng.h"
#include "gp_shape.h"

struct gp_shapemap_sampler {
    gp_fourier *plan;
    size_t np, nmodes, ngrains;
    double *phases;   /* ngrains * nmodes: grain g's phases at g * nmodes (common numbers) */
    double *D;        /* nmodes: the spectrum being measured */
    gp_vec2 *pts;     /* np contour points */
    double *values;   /* ngrains * 4 descriptors of the last measure, for the two-pass sd */
};

static double rng_u01(void *state)
{
    return gp_rng_uniform(state);
}

/* Grain g's phases from its own stream (seed, g): independent of ngrains and of the order in
 * which grains are drawn, so a sampler of n grains holds the first n of a larger one. */
static gp_status draw_phases(gp_shapemap_sampler *s, uint64_t seed, gp_error *err)
{
    for (size_t g = 0; g < s->ngrains; g++) {
        gp_rng *rng = gp_rng_create(seed, (uint64_t)g, err);
        if (!rng)
            return GP_ERR_NOMEM;
        gp_status st = gp_fourier_random_phases(s->nmodes, rng_u01, rng,
                                                s->phases + g * s->nmodes, err);
        gp_rng_destroy(rng);
        if (st != GP_OK)
            return st;
    }
    return GP_OK;
}

gp_shapemap_sampler *gp_shapemap_sampler_create(size_t contour_points, size_t ngrains,
                                                uint64_t seed, gp_error *err)
{
    if (contour_points < GP_FOURIER_NP_MIN || ngrains < 2) {
        gp_error_set(err, GP_ERR_INVALID, "sampler: contour_points must be >= %d and ngrains >= 2",
                     GP_FOURIER_NP_MIN);
        return NULL;
    }
    gp_shapemap_sampler *s = calloc(1, sizeof *s);
    if (!s) {
        gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        return NULL;
    }
    s->np = contour_points;
    s->nmodes = contour_points / 2; /* as the specimen (gp_specimen2d.c job_setup) */
    s->ngrains = ngrains;
    s->phases = malloc(ngrains * s->nmodes * sizeof *s->phases);
    s->D = malloc(s->nmodes * sizeof *s->D);
    s->pts = malloc(s->np * sizeof *s->pts);
    s->values = malloc(ngrains * GP_SHAPEMAP_NDESC * sizeof *s->values);
    if (!s->phases || !s->D || !s->pts || !s->values) {
        gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        gp_shapemap_sampler_destroy(s);
        return NULL;
    }
    s->plan = gp_fourier_create(s->np, err);
    if (!s->plan || draw_phases(s, seed, err) != GP_OK) {
        gp_shapemap_sampler_destroy(s);
        return NULL;
    }
    return s;
}

void gp_shapemap_sampler_destroy(gp_shapemap_sampler *s)
{
    if (!s)
        return;
    gp_fourier_destroy(s->plan);
    free(s->phases);
    free(s->D);
    free(s->pts);
    free(s->values);
    free(s);
}

/* Describes grain g into v[4]; GP_ERR_NOT_STAR when its contour is not star-shaped. */
static gp_status describe_grain(gp_shapemap_sampler *s, size_t g, double *v, gp_error *err)
{
    const double *delta = s->phases + g * s->nmodes;
    gp_vec2 c = {0.0, 0.0};
    gp_status st = gp_fourier_contour(s->plan, c, 1.0, s->D, delta, s->nmodes, s->pts, NULL, err);
    if (st != GP_OK)
        return st;
    gp_shape_curve curve = {c, 1.0, s->D, delta, s->nmodes};
    gp_shape_result r;
    st = gp_shape_describe_fourier(s->pts, s->np, &curve, NULL, &r, err);
    if (st != GP_OK)
        return st;
    v[GP_SHAPEMAP_ELONGATION] = r.elongation;
    v[GP_SHAPEMAP_ROUNDNESS] = r.roundness;
    v[GP_SHAPEMAP_CIRCULARITY] = r.circularity;
    v[GP_SHAPEMAP_REGULARITY] = r.regularity;
    return GP_OK;
}

/* Two-pass mean and sample sd of the n rows of values (n >= 2). */
static void summarise(const double *values, size_t n, gp_shapemap_stats *out)
{
    for (int k = 0; k < GP_SHAPEMAP_NDESC; k++) {
        double m = 0.0, ss = 0.0;
        for (size_t g = 0; g < n; g++)
            m += values[g * GP_SHAPEMAP_NDESC + (size_t)k];
        m /= (double)n;
        for (size_t g = 0; g < n; g++) {
            double d = values[g * GP_SHAPEMAP_NDESC + (size_t)k] - m;
            ss += d * d;
        }
        out->mean[k] = m;
        out->sd[k] = sqrt(ss / (double)(n - 1));
    }
}

gp_status gp_shapemap_sampler_measure(gp_shapemap_sampler *s, double D2, double D3, double D8,
                                      double alpha, double beta, gp_shapemap_stats *out,
                                      gp_error *err)
{
    if (!s || !out)
        return gp_error_set(err, GP_ERR_INVALID, "sampler_measure: NULL argument");
    memset(out, 0, sizeof *out);
    gp_status st = gp_fourier_spectrum(D2, D3, D8, alpha, beta, s->nmodes, s->D, err);
    if (st != GP_OK)
        return st;
    size_t n = 0;
    for (size_t g = 0; g < s->ngrains; g++) {
        st = describe_grain(s, g, s->values + n * GP_SHAPEMAP_NDESC, err);
        if (st == GP_ERR_NOT_STAR) {
            out->not_star++;
            continue;
        }
        if (st != GP_OK)
            return st;
        n++;
    }
    if (n < 2)
        return gp_error_set(err, GP_ERR_NOT_STAR,
                            "D2 %g, D3 %g, D8 %g: %zu of %zu phase draws are star-shaped",
                            D2, D3, D8, n, s->ngrains);
    summarise(s->values, n, out);
    out->ngrains = n;
    gp_error_clear(err);
    return GP_OK;
}
