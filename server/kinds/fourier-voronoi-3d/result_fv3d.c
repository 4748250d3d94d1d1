/* result_fv3d.c -- the result of the 3D kind "fourier-voronoi-3d" (result_json.h for the
 * conventions):
 * {"kind", "seed", "outputs", "container": <the spec's container, echoed>,
 *  "stats": {
 *    "particles":      {"target": N (particles, or the count a sieve gives), "achieved": grains},
 *    "imc_error":      {"target": the threshold, "achieved", "initial", "measure": "AD",
 *                       "stop_reason": "threshold|max_steps|stalled|cancelled|single_cell"},
 *    "imc_steps":      {"max": imc.max_steps, "achieved"},
 *    "solid_fraction": {"target": F_S, "achieved": grain volume / container volume},
 *    "container_volume": V (m³; a cylinder's prism), "lost_volume": π r² h − V (cylinder),
 *    "grains_short": {"count": grains below their target volume, "fraction_mean": their mean
 *                     volume over their cell's (null when none)},
 *    "fit": {"cell_volume", "grain_volume": {"law", "target": {"mean", "cov"}, "achieved":
 *              {"mean", "cov"}, "ks", "ks_critical", "w1", "n", "range": {"achieved",
 *              "target_p001_p999"}, "cdf": {"x", "target", "achieved"}},
 *            "cell_orientation", "grain_orientation": {"target": {"axis": [x, y, z] (unit),
 *              "anisotropy"}, "ks", "ks_critical", "n"},
 *            "passing": {"diameters" (m), "target", "achieved" (% by mass), "max_error_pp"}
 *              (a sieve law)},
 *    "descriptors": {"elongation", "flatness", "sphericity", "convexity": {"target" (the
 *                     stretch asked for elongation and flatness, else null), "mean", "sd",
 *                     "edges", "achieved" (fractions of the grains)},
 *                    "projections": {"long", "intermediate", "short": {"elongation",
 *                     "roundness", "circularity", "regularity": {"mean", "sd"}}}}
 *                   (output descriptors),
 *    "shape": {"form": "D|spectrum", "spectrum": [D0 = 1, ...], "degree", "D2", "D3", "D8",
 *              "alpha", "beta" (null for a spectrum), "elongation", "flatness", "spread",
 *              "star_bound": sum of D_n sqrt((2n + 1) / 2), "star_certain": bound < 1},
 *    "mesh": {"level", "directions", "triangles"},
 *    "clumps": {"spheres_max", "min_radius_ratio", "spheres": {"mean", "max", "total"},
 *               "volume_error": {"mean", "max"}, "inertia_error": {"mean", "max"}}
 *              (output clumps; the errors as |x|, relative)},
 *  "warnings": ["one line each: a target not reached and how close it came"] ([] when none),
 *  "timings": {"imc", "grains", "stats", "total"} (seconds),
 *  "icosphere": {"directions": [[x, y, z], ...], "triangles": [[i, j, k], ...]} (output grains),
 *  "grains": [{"id", "cell", "center": [x, y, z], "rotation": [w, x, y, z], "scale",
 *              "radii": [...] (output grains), "volume",
 *              "descriptors": {"elongation", "flatness", "sphericity", "convexity",
 *                              "projections": {"long", "intermediate", "short":
 *                                 {"elongation", "roundness", "circularity", "regularity"}}}
 *                             (output descriptors)}]                (output grains or descriptors),
 *  "cells": [{"id", "seed": [x, y, z], "vertices": [[x, y, z], ...], "faces": [[i, j, k, ...],
 *             ...] (counter-clockwise seen from outside), "neighbours": [id or -1, one a face],
 *             "volume"}]                                                       (output cells),
 *  "clumps": [{"grain", "spheres": [[x, y, z, r], ...], "volume_error", "inertia_error"}]
 *                                                                             (output clumps)}
 * Vertex i of a grain is center + scale R(rotation) radii[i] directions[i]. */
#include "kinds/fourier-voronoi-3d/result_fv3d.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_imc.h"

#define KIND_NAME "fourier-voronoi-3d"

static const char *const DESC3[4] = {"elongation", "flatness", "sphericity", "convexity"};
static const char *const DESC2[4] = {"elongation", "roundness", "circularity", "regularity"};
static const char *const AXES[3] = {"long", "intermediate", "short"};

/* ------------------------------------------------------------------ stats */

static json_t *vec3(const double *v)
{
    return json_pack("[o, o, o]", gpd_jreal(v[0]), gpd_jreal(v[1]), gpd_jreal(v[2]));
}

static json_t *fit_orient(const gp_fit_orient *o, const double axis[3])
{
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double u[3] = {axis[0] / n, axis[1] / n, axis[2] / n};
    return json_pack("{s:{s:o, s:o}, s:o, s:o, s:I}", "target", "axis", vec3(u), "anisotropy",
                     gpd_jreal(o->target_anisotropy), "ks", gpd_jreal(o->ks), "ks_critical",
                     gpd_jreal(o->ks_critical), "n", (json_int_t)o->n);
}

json_t *result_fv3d_fit(const gp_fv3d *s, const gp_spec_fv3d *spec, int with_curves)
{
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    json_t *o = json_object();
    if (!o) return NULL;
    if (t->cell_volume.present)
        json_object_set_new(o, "cell_volume", gpd_fit_size(&t->cell_volume, with_curves));
    if (t->grain_volume.present)
        json_object_set_new(o, "grain_volume", gpd_fit_size(&t->grain_volume, with_curves));
    if (t->cell_orientation.present)
        json_object_set_new(o, "cell_orientation",
                            fit_orient(&t->cell_orientation, spec->core.axis));
    if (t->grain_orientation.present)
        json_object_set_new(o, "grain_orientation",
                            fit_orient(&t->grain_orientation, spec->core.axis));
    const gp_fit_passing *p = &t->passing;
    if (p->n > 0)
        json_object_set_new(o, "passing", gpd_fit_passing(p));
    return o;
}

/* the grains below their target volume, and their mean fraction of their cell's volume */
static size_t short_grains(const gp_fv3d *s, double *fraction)
{
    size_t n = gp_fv3d_count(s), k = 0;
    double sum = 0;
    for (size_t i = 0; i < n; i++) {
        const gp_fv3d_grain *g = gp_fv3d_grain_at(s, i);
        if (g->target_met) continue;
        k++;
        sum += g->volume / gp_voronoi3d_cell_volume(gp_fv3d_cells(s), g->cell);
    }
    *fraction = k ? sum / (double)k : NAN;
    return k;
}

/* the value of descriptor k of a grain: 0..3 the 3D ones, 4 + 4 a + q projection a's q-th */
static double desc_value(const gp_fv3d_grain *g, int k)
{
    const gp_fv3d_descriptors *d = &g->desc;
    switch (k) {
    case 0: return d->elongation;
    case 1: return d->flatness;
    case 2: return d->sphericity;
    case 3: return d->convexity;
    default: return d->proj[(k - 4) / 4][(k - 4) % 4];
    }
}

/* mean and sd (n - 1) of descriptor k over the grains (NaN ones left out); their count */
static size_t desc_moments(const gp_fv3d *s, int k, double *mean, double *sd, double *lo,
                           double *hi)
{
    size_t n = gp_fv3d_count(s), m = 0;
    double sum = 0, sq = 0;
    *lo = INFINITY;
    *hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        double v = desc_value(gp_fv3d_grain_at(s, i), k);
        if (!isfinite(v)) continue;
        m++;
        sum += v;
        *lo = fmin(*lo, v);
        *hi = fmax(*hi, v);
    }
    *mean = m ? sum / (double)m : NAN;
    for (size_t i = 0; m && i < n; i++) {
        double v = desc_value(gp_fv3d_grain_at(s, i), k);
        if (isfinite(v)) sq += (v - *mean) * (v - *mean);
    }
    *sd = m > 1 ? sqrt(sq / (double)(m - 1)) : NAN;
    return m;
}

/* {"target", "mean", "sd", "edges", "achieved"} of 3D descriptor k: classes of equal width
 * over the grains' range, as many as the grains carry (sqrt n, 8 to 40) */
static json_t *desc3_json(const gp_fv3d *s, int k, double target)
{
    double mean, sd, lo, hi;
    size_t m = desc_moments(s, k, &mean, &sd, &lo, &hi);
    json_t *o = json_pack("{s:o, s:o, s:o}", "target", gpd_jreal(target), "mean",
                          gpd_jreal(mean), "sd", gpd_jreal(sd));
    if (!o || m == 0) return o;
    size_t nc = (size_t)fmin(40, fmax(8, floor(sqrt((double)m) + 0.5)));
    if (!(hi > lo)) lo -= 0.005, hi += 0.005;
    double *edges = malloc((nc + 1) * sizeof *edges), *frac = calloc(nc, sizeof *frac);
    if (edges && frac) {
        for (size_t c = 0; c <= nc; c++) edges[c] = lo + (hi - lo) * (double)c / (double)nc;
        for (size_t i = 0; i < gp_fv3d_count(s); i++) {
            double v = desc_value(gp_fv3d_grain_at(s, i), k);
            if (!isfinite(v)) continue;
            size_t c = (size_t)fmin((double)nc - 1, fmax(0, floor((v - lo) / (hi - lo) * nc)));
            frac[c] += 1.0 / (double)m;
        }
        json_object_set_new(o, "edges", gpd_jreals(edges, nc + 1));
        json_object_set_new(o, "achieved", gpd_jreals(frac, nc));
    }
    free(edges);
    free(frac);
    return o;
}

static json_t *descriptors_json(const gp_fv3d *s, const gp_spec_fv3d *spec)
{
    json_t *d = json_object();
    const double targets[4] = {spec->core.elongation, spec->core.flatness, NAN, NAN};
    for (int k = 0; d && k < 4; k++) json_object_set_new(d, DESC3[k], desc3_json(s, k, targets[k]));
    json_t *pr = json_object();
    for (int a = 0; pr && a < 3; a++) {
        json_t *one = json_object();
        for (int q = 0; one && q < 4; q++) {
            double mean, sd, lo, hi;
            desc_moments(s, 4 + 4 * a + q, &mean, &sd, &lo, &hi);
            json_object_set_new(one, DESC2[q], json_pack("{s:o, s:o}", "mean", gpd_jreal(mean),
                                                         "sd", gpd_jreal(sd)));
        }
        json_object_set_new(pr, AXES[a], one);
    }
    json_object_set_new(d, "projections", pr);
    return d;
}

static json_t *shape_json(const gp_spec_fv3d *spec)
{
    int d = spec->shape_form == 0;
    return json_pack("{s:s, s:o, s:I, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:b}", "form",
                     d ? "D" : "spectrum", "spectrum",
                     gpd_jreals(spec->spectrum, spec->nspectrum), "degree",
                     (json_int_t)(spec->nspectrum - 1), "D2", d ? gpd_jreal(spec->D2) : json_null(),
                     "D3", d ? gpd_jreal(spec->D3) : json_null(), "D8",
                     d ? gpd_jreal(spec->D8) : json_null(), "alpha",
                     d ? gpd_jreal(spec->alpha) : json_null(), "beta",
                     d ? gpd_jreal(spec->beta) : json_null(), "elongation",
                     gpd_jreal(spec->core.elongation), "flatness", gpd_jreal(spec->core.flatness),
                     "spread", gpd_jreal(spec->core.spread), "star_bound",
                     gpd_jreal(spec->star_bound), "star_certain", spec->star_bound < 1);
}

/* the clumps' sphere counts and errors */
static json_t *clumps_json(const gp_fv3d *s, const gp_spec_fv3d *spec)
{
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    size_t n = gp_fv3d_count(s), total = 0, most = 0;
    for (size_t i = 0; i < n; i++) {
        size_t k = gp_fv3d_grain_at(s, i)->nspheres;
        total += k;
        most = k > most ? k : most;
    }
    return json_pack("{s:i, s:o, s:{s:o, s:I, s:I}, s:{s:o, s:o}, s:{s:o, s:o}}", "spheres_max",
                     spec->core.spheres_max, "min_radius_ratio",
                     gpd_jreal(spec->core.min_radius_ratio), "spheres", "mean",
                     gpd_jreal(n ? (double)total / (double)n : NAN), "max", (json_int_t)most,
                     "total", (json_int_t)total, "volume_error", "mean",
                     gpd_jreal(t->clump_volume_error_mean), "max",
                     gpd_jreal(t->clump_volume_error_max), "inertia_error", "mean",
                     gpd_jreal(t->clump_inertia_error_mean), "max",
                     gpd_jreal(t->clump_inertia_error_max));
}

static json_t *stats_json(const gp_fv3d *s, const gp_spec_fv3d *spec)
{
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    const gp_fv3d_spec *c = &spec->core;
    json_t *st = json_object();
    if (!st) return NULL;
    size_t n = gp_fv3d_count(s);
    json_object_set_new(st, "particles", json_pack("{s:I, s:I}", "target",
                                                   (json_int_t)c->particles, "achieved",
                                                   (json_int_t)n));
    json_object_set_new(st, "imc_error",
                        json_pack("{s:o, s:o, s:o, s:s, s:s}", "target",
                                  gpd_jreal(c->imc_threshold), "achieved",
                                  gpd_jreal(t->imc_error), "initial",
                                  gpd_jreal(t->imc_error_initial), "measure", "AD",
                                  "stop_reason", gp_imc_stop_name((gp_imc_stop)t->imc_stop)));
    json_object_set_new(st, "imc_steps", json_pack("{s:I, s:I}", "max",
                                                   (json_int_t)c->imc_max_steps, "achieved",
                                                   (json_int_t)t->imc_steps));
    json_object_set_new(st, "solid_fraction",
                        json_pack("{s:o, s:o}", "target", gpd_jreal(c->solid_fraction),
                                  "achieved", gpd_jreal(t->solid_fraction)));
    json_object_set_new(st, "container_volume",
                        gpd_jreal(gp_voronoi3d_container_volume(gp_fv3d_cells(s))));
    if (spec->container == GP_SPEC_FV3D_CYLINDER)
        json_object_set_new(st, "lost_volume", gpd_jreal(t->lost_volume));
    double frac;
    size_t k = short_grains(s, &frac);
    json_object_set_new(st, "grains_short", json_pack("{s:I, s:o}", "count", (json_int_t)k,
                                                      "fraction_mean", gpd_jreal(frac)));
    json_object_set_new(st, "fit", result_fv3d_fit(s, spec, 1));
    if (c->outputs & GP_OUT3_DESCRIPTORS)
        json_object_set_new(st, "descriptors", descriptors_json(s, spec));
    json_object_set_new(st, "shape", shape_json(spec));
    json_object_set_new(st, "mesh", json_pack("{s:i, s:I, s:I}", "level", (int)c->mesh_level,
                                              "directions",
                                              (json_int_t)gp_fv3d_directions(s, NULL),
                                              "triangles",
                                              (json_int_t)gp_fv3d_triangles(s, NULL)));
    if (c->outputs & GP_OUT3_CLUMPS) json_object_set_new(st, "clumps", clumps_json(s, spec));
    return st;
}

/* ------------------------------------------------------------------ warnings */

static void warn(json_t *a, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void warn(json_t *a, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    json_array_append_new(a, json_string(buf));
}

static void warn_volume(json_t *a, const char *what, const gp_fit_area *f)
{
    if (f->present && f->ks > f->ks_critical)
        warn(a, "%s volumes: KS distance %.4f to the %s law is above its 5 %% critical value "
                "%.4f (mean %.4g for %.4g, COV %.3f for %.3f)", what, f->ks, gp_law_name(f->law),
             f->ks_critical, f->mean, f->target_mean, f->cov, f->target_cov);
}

static void warn_orient(json_t *a, const char *what, const gp_fit_orient *f)
{
    if (f->present && f->ks > f->ks_critical)
        warn(a, "%s orientations: KS distance %.4f of the long axes to their law is above its "
                "5 %% critical value %.4f", what, f->ks, f->ks_critical);
}

json_t *result_fv3d_warnings(const gp_fv3d *s, const gp_spec_fv3d *spec)
{
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    const gp_fv3d_spec *c = &spec->core;
    json_t *a = json_array();
    if (!a) return NULL;
    size_t n = gp_fv3d_count(s);
    if (n == 1)
        warn(a, "1 cell: the tessellation is the container itself; its volume and orientation "
                "cannot be shaped");
    else if (t->imc_error > c->imc_threshold)
        warn(a, "imc: the error %.4g (AD) is above the threshold %.4g: the run stopped (%s) "
                "after %ld steps", t->imc_error, c->imc_threshold,
             gp_imc_stop_name((gp_imc_stop)t->imc_stop), t->imc_steps);
    warn_volume(a, "cell", &t->cell_volume);
    warn_volume(a, "grain", &t->grain_volume);
    warn_orient(a, "cell", &t->cell_orientation);
    warn_orient(a, "grain", &t->grain_orientation);
    if (t->passing.n > 0 && t->passing.max_error_pp > 3.0)
        warn(a, "sieve: passing by mass off by up to %.1f percentage points",
             t->passing.max_error_pp);
    double frac;
    size_t k = short_grains(s, &frac);
    if (k > 0 && !c->law_of_grains)
        warn(a, "%zu of %zu grains could not reach solid fraction %g of their cell (they reached "
                "%.3g on average; the specimen %.3g)", k, n, c->solid_fraction, frac,
             t->solid_fraction);
    else if (k > 0)
        warn(a, "%zu of %zu grains could not reach their volume of the grain law (they fill %.3g "
                "of their cell on average; the specimen's solid fraction %.3g for %g)", k, n, frac,
             t->solid_fraction, c->solid_fraction);
    if (spec->star_bound >= 1)
        warn(a, "shape: not every grain drawn from this spectrum is star-shaped (the bound sum of "
                "D_n sqrt((2n + 1) / 2) is %.3g, not below 1): grains were drawn again until they "
                "were, which favours the smaller amplitudes", spec->star_bound);
    return a;
}

/* ------------------------------------------------------------------ the head */

static void set_reals(json_t *o, const char *const *names, const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++) json_object_set_new(o, names[i], gpd_jreal(v[i]));
}

static json_t *head_json(const gp_fv3d *s, const gp_spec_fv3d *spec, const json_t *spec_json)
{
    json_t *r = gpd_result_new(KIND_NAME, spec->core.seed, spec_json);
    if (!r) return NULL;
    json_t *c = json_object_get(spec_json, "container");
    if (c) json_object_set(r, "container", c);
    json_object_set_new(r, "stats", stats_json(s, spec));
    json_object_set_new(r, "warnings", result_fv3d_warnings(s, spec));
    const gp_fv3d_timings *tm = gp_fv3d_timings_of(s);
    json_t *t = json_object();
    static const char *const phases[] = {"imc", "grains", "stats", "total"};
    set_reals(t, phases, (double[]){tm->imc, tm->grains, tm->stats, tm->total}, 4);
    json_object_set_new(r, "timings", t);
    return r;
}

/* ------------------------------------------------------------------ the arrays */

static void real_member(gpd_jw *w, const char *key, double x)
{
    gpd_jw_key(w, key);
    gpd_jw_real(w, x);
}

static void reals_w(gpd_jw *w, const double *v, size_t n)
{
    gpd_jw_begin_array(w);
    for (size_t i = 0; i < n; i++) gpd_jw_real(w, v[i]);
    gpd_jw_end_array(w);
}

/* the shared icosphere */
static void icosphere_w(gpd_jw *w, const gp_fv3d *s)
{
    const double *xyz;
    const uint32_t *tri;
    size_t nv = gp_fv3d_directions(s, &xyz), nt = gp_fv3d_triangles(s, &tri);
    gpd_jw_key(w, "icosphere");
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "directions");
    gpd_jw_begin_array(w);
    for (size_t i = 0; i < nv; i++) reals_w(w, xyz + 3 * i, 3);
    gpd_jw_end_array(w);
    gpd_jw_key(w, "triangles");
    gpd_jw_begin_array(w);
    for (size_t i = 0; i < nt; i++) {
        gpd_jw_begin_array(w);
        for (int k = 0; k < 3; k++) gpd_jw_integer(w, (long long)tri[3 * i + k]);
        gpd_jw_end_array(w);
    }
    gpd_jw_end_array(w);
    gpd_jw_end_object(w);
}

typedef struct items_ctx {
    const gp_fv3d *s;
    unsigned out;
} items_ctx;

/* a grain's descriptors */
static void descriptors_w(gpd_jw *w, const gp_fv3d_descriptors *d)
{
    gpd_jw_key(w, "descriptors");
    gpd_jw_begin_object(w);
    real_member(w, "elongation", d->elongation);
    real_member(w, "flatness", d->flatness);
    real_member(w, "sphericity", d->sphericity);
    real_member(w, "convexity", d->convexity);
    gpd_jw_key(w, "projections");
    gpd_jw_begin_object(w);
    for (int a = 0; a < 3; a++) {
        gpd_jw_key(w, AXES[a]);
        gpd_jw_begin_object(w);
        for (int q = 0; q < 4; q++) real_member(w, DESC2[q], d->proj[a][q]);
        gpd_jw_end_object(w);
    }
    gpd_jw_end_object(w);
    gpd_jw_end_object(w);
}

/* {"id", "cell", "center", "rotation", "scale", "radii" (grains), "volume", "descriptors"} */
static void grain_item(gpd_jw *w, size_t i, const void *user)
{
    const items_ctx *c = user;
    const gp_fv3d_grain *g = gp_fv3d_grain_at(c->s, i);
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "id");
    gpd_jw_integer(w, (long long)i);
    gpd_jw_key(w, "cell");
    gpd_jw_integer(w, (long long)g->cell);
    gpd_jw_key(w, "center");
    reals_w(w, g->centre, 3);
    gpd_jw_key(w, "rotation");
    reals_w(w, g->rotation, 4);
    real_member(w, "scale", g->scale);
    if (c->out & GP_OUT3_GRAINS) {
        gpd_jw_key(w, "radii");
        reals_w(w, g->radii, gp_fv3d_directions(c->s, NULL));
    }
    real_member(w, "volume", g->volume);
    if (c->out & GP_OUT3_DESCRIPTORS) descriptors_w(w, &g->desc);
    gpd_jw_end_object(w);
}

/* {"id", "seed", "vertices", "faces", "neighbours" (-1: the container), "volume"} */
static void cell_item(gpd_jw *w, size_t i, const void *user)
{
    const items_ctx *c = user;
    const gp_voronoi3d *v = gp_fv3d_cells(c->s);
    size_t nv = gp_voronoi3d_cell_vertices(v, i, NULL, 0), nf = gp_voronoi3d_cell_face_count(v, i);
    double seed[3], *xyz = malloc((nv ? nv : 1) * 3 * sizeof *xyz);
    int32_t *nb = malloc((nf ? nf : 1) * sizeof *nb);
    uint32_t *loop = malloc((nv ? nv : 1) * sizeof *loop); /* a face has at most nv vertices */
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "id");
    gpd_jw_integer(w, (long long)i);
    gpd_jw_key(w, "seed");
    gp_voronoi3d_seed(v, i, seed);
    reals_w(w, seed, 3);
    if (!xyz || !nb || !loop) { /* out of memory: the cell's numbers without its polyhedron */
        nv = nf = 0;
    } else {
        gp_voronoi3d_cell_vertices(v, i, xyz, nv);
    }
    gpd_jw_key(w, "vertices");
    gpd_jw_begin_array(w);
    for (size_t k = 0; k < nv; k++) reals_w(w, xyz + 3 * k, 3);
    gpd_jw_end_array(w);
    gpd_jw_key(w, "faces");
    gpd_jw_begin_array(w);
    for (size_t f = 0; f < nf; f++) {
        size_t m = gp_voronoi3d_cell_face(v, i, f, loop, nv, &nb[f]);
        gpd_jw_begin_array(w);
        for (size_t k = 0; k < m && k < nv; k++) gpd_jw_integer(w, (long long)loop[k]);
        gpd_jw_end_array(w);
    }
    gpd_jw_end_array(w);
    gpd_jw_key(w, "neighbours");
    gpd_jw_begin_array(w);
    for (size_t f = 0; f < nf; f++) gpd_jw_integer(w, nb[f] < 0 ? -1 : (long long)nb[f]);
    gpd_jw_end_array(w);
    real_member(w, "volume", gp_voronoi3d_cell_volume(v, i));
    gpd_jw_end_object(w);
    free(xyz);
    free(nb);
    free(loop);
}

/* {"grain", "spheres", "volume_error", "inertia_error"} */
static void clump_item(gpd_jw *w, size_t i, const void *user)
{
    const items_ctx *c = user;
    const gp_fv3d_grain *g = gp_fv3d_grain_at(c->s, i);
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "grain");
    gpd_jw_integer(w, (long long)i);
    gpd_jw_key(w, "spheres");
    gpd_jw_begin_array(w);
    for (size_t k = 0; k < g->nspheres; k++) reals_w(w, g->spheres + 4 * k, 4);
    gpd_jw_end_array(w);
    real_member(w, "volume_error", g->clump_volume_error);
    real_member(w, "inertia_error", g->clump_inertia_error);
    gpd_jw_end_object(w);
}

/* items a block of gpd_jw_items: ~300 KB of text (a level-4 grain is ~55 KB, a cell ~3 KB, a
 * clump of 30 spheres ~2.5 KB) */
#define GRAINS_BLOCK 8
#define CELLS_BLOCK 128

static void array_w(gpd_jw *w, const char *key, size_t n, gpd_jw_item_fn item,
                    const items_ctx *c, int threads, size_t block)
{
    gpd_jw_key(w, key);
    gpd_jw_begin_array(w);
    gpd_jw_items(w, n, item, c, threads, block);
    gpd_jw_end_array(w);
}

json_t *result_fv3d_write(const gp_fv3d *s, const gp_spec_fv3d *spec, const json_t *spec_json,
                          gpd_jw *w)
{
    json_t *head = head_json(s, spec, spec_json);
    if (!head) return NULL;
    unsigned out = spec->core.outputs;
    size_t n = gp_fv3d_count(s);
    int nt = spec->threads > 0 ? spec->threads : 1; /* the job's: the same bytes whatever */
    items_ctx c = {s, out};
    gpd_jw_begin_object(w);
    gpd_jw_members(w, head);
    if (out & GP_OUT3_GRAINS) icosphere_w(w, s);
    if (out & (GP_OUT3_GRAINS | GP_OUT3_DESCRIPTORS))
        array_w(w, "grains", n, grain_item, &c, nt, GRAINS_BLOCK);
    if (out & GP_OUT3_CELLS) array_w(w, "cells", n, cell_item, &c, nt, CELLS_BLOCK);
    if (out & GP_OUT3_CLUMPS) array_w(w, "clumps", n, clump_item, &c, nt, CELLS_BLOCK);
    gpd_jw_end_object(w);
    return head;
}

json_t *result_fv3d_tree(const gp_fv3d *s, const gp_spec_fv3d *spec, const json_t *spec_json)
{
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    json_decref(result_fv3d_write(s, spec, spec_json, &w));
    char *text = gpd_jw_take(&w, NULL);
    json_t *r = text ? json_loads(text, 0, NULL) : NULL;
    free(text);
    return r;
}

/* the text's bytes: 20 a real at 17 digits, with its separators */
double result_fv3d_bytes(const gp_fv3d *s, unsigned outputs)
{
    size_t n = gp_fv3d_count(s), nv = gp_fv3d_directions(s, NULL);
    double bytes = 40000;
    if (outputs & GP_OUT3_GRAINS) bytes += 90.0 * (double)nv + 20.0 * (double)n * (double)nv;
    if (outputs & (GP_OUT3_GRAINS | GP_OUT3_DESCRIPTORS)) bytes += 260.0 * (double)n;
    if (outputs & GP_OUT3_DESCRIPTORS) bytes += 700.0 * (double)n;
    for (size_t i = 0; i < n; i++) {
        if (outputs & GP_OUT3_CELLS)
            bytes += 120 + 60.0 * (double)gp_voronoi3d_cell_vertices(gp_fv3d_cells(s), i, NULL, 0) +
                     40.0 * (double)gp_voronoi3d_cell_face_count(gp_fv3d_cells(s), i);
        if (outputs & GP_OUT3_CLUMPS) bytes += 100 + 80.0 * (double)gp_fv3d_grain_at(s, i)->nspheres;
    }
    return bytes;
}
