/* gp_specimen2d_shape.c -- the shape of a specimen's grains (api.md "2D shape"): the mean
 * spectrum of each shape form, the per-mode spread, and the table step of the descriptors'
 * calibration. See gp_specimen2d_internal.h; gp_specimen2d.h says what the result reports. */
#include "gp_specimen2d_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_fourier.h"
#include "gp_outline.h"
#include "gp_shapemap.h"

/* The descriptor fit samples its grains from streams (fit seed, g), g < 256. A seed other than
 * the spec's keeps them apart from the specimen's own streams (spec seed: 0, 1 + i, 2^62 + i),
 * so that the fit's grains are not the cells' phases; any fixed odd constant does. */
#define FIT_SEED_MIX UINT64_C(0x9E3779B97F4A7C15)
/* The fit samples its grains at the specimen's contour_points up to this: the descriptors
 * barely move with Np (elongation 0.7520, 0.7522, 0.7523, 0.7523 and circularity 0.7998,
 * 0.7987, 0.7984, 0.7982 at Np = 128, 256, 512, 1024 for one spectrum) while a sampled
 * evaluation costs 0.14, 0.25, 0.37, 1.2 s; the calibration on the specimen's own grains
 * then works at the real Np. */
#define FIT_NP_MAX 512

void gp_specimen2d_shape_free(gp_shape_used *used)
{
    if (!used)
        return;
    free(used->spectrum);
    free(used->cov);
    memset(used, 0, sizeof *used);
}

/* D2, D3, D8 as the spectrum has them (the reported figures of the spectrum and outlines
 * forms, whose decay exponents are not those of Eqs. 10-11) */
static void d_of_spectrum(gp_shape_used *u)
{
    u->D2 = u->nmodes > 2 ? u->spectrum[2] : 0.0;
    u->D3 = u->nmodes > 3 ? u->spectrum[3] : 0.0;
    u->D8 = u->nmodes > 8 ? u->spectrum[8] : 0.0;
    u->alpha = u->beta = NAN;
}

gp_status gp_specimen2d_shape_set_d(gp_shape_used *used, const double *p, gp_error *err)
{
    gp_status st = gp_fourier_spectrum(p[0], p[1], p[2], GP_SHAPEMAP_ALPHA, GP_SHAPEMAP_BETA,
                                       used->nmodes, used->spectrum, err);
    if (st != GP_OK)
        return st;
    used->D2 = p[0];
    used->D3 = p[1];
    used->D8 = p[2];
    used->alpha = GP_SHAPEMAP_ALPHA;
    used->beta = GP_SHAPEMAP_BETA;
    return GP_OK;
}

/* shape.spectrum, padded with zeros (or cut) to nmodes; D_0 is 1 */
static gp_status setup_spectrum(const gp_spec2d *s, gp_shape_used *u, gp_error *err)
{
    if (!s->spectrum || s->nspectrum < 1)
        return gp_error_set(err, GP_ERR_INVALID, "shape.spectrum is empty");
    for (size_t n = 0; n < u->nmodes; n++)
        u->spectrum[n] = n < s->nspectrum ? s->spectrum[n] : 0.0;
    u->spectrum[0] = 1.0;
    d_of_spectrum(u);
    return gp_fourier_spectrum_check(u->spectrum, u->nmodes, err);
}

/* the target descriptors: gp_shapemap_fit, sampled at the specimen's contour_points */
static gp_status setup_descriptors(const gp_spec2d *s, gp_shape_used *u, gp_error *err)
{
    gp_shapemap_target t;
    memset(&t, 0, sizeof t);
    t.given = s->desc_given;
    for (int k = 0; k < GP_SHAPEMAP_NDESC; k++)
        if (t.given & GP_SHAPEMAP_BIT(k))
            t.value[k] = u->target[k] = s->desc_target[k];
    u->targets = t.given;
    gp_shapemap_params p;
    gp_shapemap_params_defaults(&p);
    p.contour_points = s->contour_points < FIT_NP_MAX ? s->contour_points : FIT_NP_MAX;
    p.seed = s->seed ^ FIT_SEED_MIX;
    gp_shapemap_result r;
    gp_status st = gp_shapemap_fit(&t, &p, &r, err);
    if (st != GP_OK)
        return st;
    u->fit_evaluations = r.evaluations;
    u->missed = r.missed;
    memcpy(u->predicted, r.mean, sizeof u->predicted);
    double d[3] = {r.D2, r.D3, r.D8};
    return gp_specimen2d_shape_set_d(u, d, err);
}

/* the first refused outline, as an error (the schema refuses them at submit already) */
static gp_status refused_outline(const gp_outline_set_result *res, gp_error *err)
{
    size_t i = res->refused[0];
    return gp_error_set(err, GP_ERR_INVALID, "shape.outlines[%zu] refused (%zu of %zu): %s", i,
                        res->nrefused, res->n, res->info[i].error.message);
}

/* the set's statistics into u: mean spectrum, descriptor means as targets, and its per-mode
 * cov (capped) as the spread unless the spec gives one */
static gp_status take_outline_stats(const gp_spec2d *s, const gp_outline_set_result *res,
                                    gp_shape_used *u, gp_error *err)
{
    memcpy(u->spectrum, res->mean, u->nmodes * sizeof *u->spectrum);
    u->spectrum[0] = 1.0;
    d_of_spectrum(u);
    u->noutlines = res->n;
    u->noutlines_analysed = res->nanalysed;
    const gp_outline_stat *d[4] = {&res->elongation, &res->roundness, &res->circularity,
                                   &res->regularity};
    u->targets = res->ndescribed > 0 ? GP_SHAPEMAP_ALL : 0;
    for (int k = 0; k < 4 && u->targets; k++) {
        u->target[k] = d[k]->mean;
        u->target_sd[k] = d[k]->sd;
    }
    if (s->spread_given || s->spread > 0.0)
        return GP_OK;
    u->cov = malloc(u->nmodes * sizeof *u->cov);
    if (!u->cov)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    double num = 0.0, den = 0.0;
    for (size_t n = 0; n < u->nmodes; n++) {
        u->cov[n] = n == 0 ? 0.0 : fmin(res->cov[n], GP_SHAPE_SPREAD_MAX);
        if (n >= 2) {
            num += u->spectrum[n] * u->cov[n];
            den += u->spectrum[n];
        }
    }
    /* one figure for the report: the shape modes' cov weighted by their amplitudes (D_1, the
     * pole's offset, is no shape) */
    u->spread = den > 0.0 ? num / den : 0.0;
    u->spread_from_outlines = 1;
    return GP_OK;
}

/* the outlines: gp_outline_set_analyze at the specimen's rays and modes */
static gp_status setup_outlines(const gp_spec2d *s, const volatile int *cancel,
                                gp_progress_fn progress, void *user, gp_shape_used *u,
                                gp_error *err)
{
    if (!s->outlines || s->noutlines < GP_SHAPE_OUTLINES_MIN)
        return gp_error_set(err, GP_ERR_INVALID, "shape.outlines: %zu outlines, need >= %d",
                            s->outlines ? s->noutlines : 0, GP_SHAPE_OUTLINES_MIN);
    gp_outline_points *pts = malloc(s->noutlines * sizeof *pts);
    if (!pts)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < s->noutlines; i++)
        pts[i] = (gp_outline_points){s->outlines[i].pts, s->outlines[i].n};
    gp_outline_params p;
    gp_outline_params_defaults(&p);
    p.np = s->contour_points;
    p.nmodes = u->nmodes;
    p.min_outlines = GP_SHAPE_OUTLINES_MIN;
    p.progress = progress;
    p.progress_user = user;
    gp_outline_set_result res;
    gp_status st = gp_outline_set_analyze(pts, s->noutlines, &p, cancel, &res, err);
    free(pts);
    if (st == GP_OK && res.nrefused > 0)
        st = refused_outline(&res, err);
    else if (st == GP_OK)
        st = take_outline_stats(s, &res, u, err);
    gp_outline_set_result_free(&res);
    return st;
}

/* shape.spread for every mode; none (or 0) and no outlines' own: every grain the mean */
static gp_status setup_spread(const gp_spec2d *s, gp_shape_used *u, gp_error *err)
{
    if (!(s->spread >= 0.0 && s->spread <= GP_SHAPE_SPREAD_MAX))
        return gp_error_set(err, GP_ERR_INVALID, "shape.spread must be in [0, %g], got %g",
                            GP_SHAPE_SPREAD_MAX, s->spread);
    if (u->spread_from_outlines)
        return GP_OK;
    u->spread = s->spread;
    if (!(s->spread > 0.0))
        return GP_OK;
    u->cov = malloc(u->nmodes * sizeof *u->cov);
    if (!u->cov)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    for (size_t n = 0; n < u->nmodes; n++)
        u->cov[n] = n == 0 ? 0.0 : s->spread;
    return GP_OK;
}

gp_status gp_specimen2d_shape_setup(const gp_spec2d *s, size_t nmodes,
                                    const volatile int *cancel, gp_progress_fn progress,
                                    void *user, gp_shape_used *used, gp_error *err)
{
    memset(used, 0, sizeof *used);
    used->form = s->has_spectrum ? GP_SHAPE_FORM_SPECTRUM : s->shape_form;
    used->nmodes = nmodes;
    used->spectrum = calloc(nmodes ? nmodes : 1, sizeof *used->spectrum);
    if (!used->spectrum)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    gp_status st;
    switch (used->form) {
    case GP_SHAPE_FORM_D:
        used->D2 = s->D2, used->D3 = s->D3, used->D8 = s->D8;
        used->alpha = s->alpha, used->beta = s->beta;
        st = gp_fourier_spectrum(s->D2, s->D3, s->D8, s->alpha, s->beta, nmodes, used->spectrum,
                                 err);
        break;
    case GP_SHAPE_FORM_SPECTRUM: st = setup_spectrum(s, used, err); break;
    case GP_SHAPE_FORM_DESCRIPTORS: st = setup_descriptors(s, used, err); break;
    case GP_SHAPE_FORM_OUTLINES: st = setup_outlines(s, cancel, progress, user, used, err); break;
    default: st = gp_error_set(err, GP_ERR_INVALID, "unknown shape form %d", (int)used->form);
    }
    if (st == GP_OK)
        st = setup_spread(s, used, err);
    return st;
}

double gp_specimen2d_shape_misfit(const gp_shape_used *used, const double *m, unsigned *missed)
{
    double f = 0.0;
    unsigned bits = 0;
    for (int k = 0; k < GP_SHAPEMAP_NDESC; k++) {
        if (!(used->targets & GP_SHAPEMAP_BIT(k)))
            continue;
        double e = (m[k] - used->target[k]) / gp_shapemap_tolerance(k);
        f += e * e;
        if (fabs(e) > 1.0)
            bits |= GP_SHAPEMAP_BIT(k);
    }
    if (missed)
        *missed = bits;
    return f;
}

/* a goal kept inside the range gp_shapemap accepts: (0, 1], regularity (0, 5] */
static double clamp_goal(int k, double v)
{
    double hi = k == GP_SHAPEMAP_REGULARITY ? 5.0 : 1.0;
    return fmin(hi, fmax(1e-3, v));
}

gp_status gp_specimen2d_shape_correct(const gp_shape_used *used, const double *measured,
                                      double *next, gp_error *err)
{
    double m[GP_SHAPEMAP_NDESC];
    gp_status st = gp_shapemap_predict(used->D2, used->D3, used->D8, m, NULL, err);
    if (st != GP_OK)
        return st;
    gp_shapemap_target t;
    memset(&t, 0, sizeof t);
    t.given = used->targets;
    for (int k = 0; k < GP_SHAPEMAP_NDESC; k++)
        if (t.given & GP_SHAPEMAP_BIT(k))
            t.value[k] = clamp_goal(k, used->target[k] - (measured[k] - m[k]));
    gp_shapemap_result r;
    st = gp_shapemap_check(&t, &r, err);
    /* a shifted goal the table cannot reach: its nearest reachable spectrum is the step */
    if (st != GP_OK && st != GP_ERR_INFEASIBLE)
        return st;
    gp_error_clear(err);
    next[0] = r.D2;
    next[1] = r.D3;
    next[2] = r.D8;
    return GP_OK;
}
