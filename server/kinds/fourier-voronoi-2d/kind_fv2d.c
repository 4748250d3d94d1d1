/* kind_fv2d.c -- the 2D kind, "fourier-voronoi-2d": Fourier-Voronoi specimens (core/2d) with
 * their result, export pack, progress and SVG views (svg_views2d.c).
 *
 * The result (result_json.h for the conventions):
 * {"kind": "fourier-voronoi-2d", "seed": 42, "outputs": [...],
 *  "container": <the spec's container, echoed>,
 *  "stats": {
 *    "particles":       {"target": N (`particles`, or the cell count a sieve law gives),
 *                        "achieved": number of grains},
 *    "imc_error":       {"target": the threshold used, "achieved": e,
 *                        "measure": "AD|E1|E2|E3", "floor": f,
 *                        "stop_reason": "threshold|max_steps|floor|..."},
 *    "imc_steps":       {"max": max_steps used, "achieved": steps (every run),
 *                        "default": whether max_steps was the default for the cell count,
 *                        "runs": [steps of the cells' run, (the resize run of a grain law)]},
 *    "solid_fraction":  {"target": F_S, "achieved": grain area / container area},
 *    "container_area":  A,
 *    "cells_target_met": k,            cells whose grain reached F_S
 *    "mean_orientation_gap_deg": g,
 *    "size_histogram":        {"edges": [k+1], "target": [k], "achieved": [k]}  (cell areas)
 *    "grain_size_histogram":  {"edges", "target", "achieved"}                   (grain areas)
 *    "orientation_histogram": {"edges" (deg), "target", "achieved"}
 *    "descriptors": {"elongation": {"edges", "target", "achieved", "mean", "sd"},
 *                    "roundness": ..., "circularity": ..., "regularity": ...}
 *                   (with output "descriptors"; "target" is null, or the target mean where
 *                    there is one: shape.descriptors' asked ones, the outlines' own means;
 *                    "sd" the grains' standard deviation, n - 1)
 *    "fit": {                                           (api.md; a block only when measured)
 *      "cell_area": {"law": "lognormal|normal|uniform|sieve",
 *                    "target": {"mean", "cov"}, "achieved": {"mean", "cov"},
 *                    "ks", "ks_critical" (1.36 / sqrt(n)), "w1" (/ target mean), "n",
 *                    "range": {"achieved": [min, max], "target_p001_p999": [q001, q999]},
 *                    "cdf": {"x": [k] (area, increasing), "target": [k] F(x),
 *                            "achieved": [k] empirical CDF at x}},
 *      "grain_area": the same, against the grains' law (absent when no grains were built),
 *      "cell_orientation":  {"target": {"mean_deg", "anisotropy"}, "ks", "ks_critical", "n"},
 *      "grain_orientation": the same,
 *      "passing": {"diameters": [m], "target": [m] %, "achieved": [m] %, "max_error_pp"}
 *                 (grains by mass; sieve law only)},
 *    "shape": {"form": "D|spectrum|descriptors|outlines",     (every job; gp_shape_used)
 *              "spectrum": [D0 = 1, D1, ...] (the mean spectrum used, contour_points / 2),
 *              "D2", "D3", "D8", "alpha", "beta" (null where NaN: spectrum and outlines),
 *              "spread": s (0: none), "spread_source": "spec|outlines|none",
 *              "spread_cov": [per mode] (only when the grains' spectra vary),
 *              "fit": {"predicted": {<4 names>}, "calibrated": {<4 names>} | null,
 *                      "calibration_grains", "calibration_rounds", "fit_evaluations",
 *                      "missed": [names]}                         (form descriptors),
 *              "outlines": {"n", "analysed",
 *                           "descriptors": {<name>: {"mean", "sd"}}}  (form outlines),
 *              "grains_redrawn", "grains_clipped"}
 *  },
 *  "warnings": ["one line each: a target not reached and how close it came", ...]
 *              (always there; [] when every target was met),
 *  "timings": {"shape" (forms descriptors and outlines: the fit or analysis and the
 *              calibration), "tessellation", "imc", "fill", "odec", "descriptors", "total"}
 *             (seconds),
 *  "grains": [{"id", "cell", "contour": [[x,y],...], "area", "orientation_deg",
 *              "cell_fraction", "descriptors": {...} (output descriptors),
 *              "discs": [[x,y,r],...] (output odec)}]   (with any of grains/odec/descriptors),
 *  "cells": [{"id", "seed": [x,y], "polygons": [[[x,y],...],...], "area",
 *             "orientation_deg"}]                      (with output "cells")}
 * Histogram "target" is null where there is no target.
 */
#include "kinds/fourier-voronoi-2d/kind_fv2d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_export.h"
#include "gp_spec.h"
#include "kinds/kind.h"
#include "jobs/result_json.h"
#include "svg/svg_views.h"
#include "util/util.h"

#define KIND_NAME "fourier-voronoi-2d"

/* ------------------------------------------------------------------ the result */

static json_t *hist_json(const gp_hist *h)
{
    if (!h || h->nclasses == 0 || !h->edges) return json_null();
    return json_pack("{s:o, s:o, s:o}", "edges", gpd_jreals(h->edges, h->nclasses + 1), "target",
                     gpd_jreals(h->target, h->nclasses), "achieved", gpd_jreals(h->achieved, h->nclasses));
}

/* the measure's name: the core's string, else the spec's kind */
static const char *imc_measure(const gp_specimen2d *s, gp_imc_error_kind k)
{
    if (s->imc_error_kind && *s->imc_error_kind) return s->imc_error_kind;
    switch (k) {
    case GP_IMC_E1: return "E1";
    case GP_IMC_E2: return "E2";
    case GP_IMC_E3: return "E3";
    default: return "AD";
    }
}

static json_t *fit_orient(const gp_fit_orient *o)
{
    return json_pack("{s:{s:o, s:o}, s:o, s:o, s:I}", "target", "mean_deg",
                     gpd_jreal(o->target_mean_deg), "anisotropy",
                     gpd_jreal(o->target_anisotropy), "ks", gpd_jreal(o->ks), "ks_critical",
                     gpd_jreal(o->ks_critical), "n", (json_int_t)o->n);
}

json_t *gpd_fit_2d(const gp_fit2d *f, int with_curves)
{
    json_t *o = json_object();
    if (!o || !f) return o;
    if (f->cell_area.present)
        json_object_set_new(o, "cell_area", gpd_fit_size(&f->cell_area, with_curves));
    if (f->grain_area.present)
        json_object_set_new(o, "grain_area", gpd_fit_size(&f->grain_area, with_curves));
    if (f->cell_orientation.present)
        json_object_set_new(o, "cell_orientation", fit_orient(&f->cell_orientation));
    if (f->grain_orientation.present)
        json_object_set_new(o, "grain_orientation", fit_orient(&f->grain_orientation));
    if (f->passing.n > 0) json_object_set_new(o, "passing", gpd_fit_passing(&f->passing));
    return o;
}

json_t *gpd_warnings_2d(const gp_specimen2d *s)
{
    json_t *a = json_array();
    for (size_t i = 0; a && s->warnings && i < s->nwarnings; i++)
        if (s->warnings[i]) json_array_append_new(a, json_string(s->warnings[i]));
    return a;
}

/* the number of cells asked for: `particles`, or derived from a sieve law */
static size_t target_particles(const gp_specimen2d *s, const gp_spec2d *spec)
{
    if (spec->particles > 0) return spec->particles;
    double area;
    size_t n = 0;
    gp_error err;
    if (gp_spec2d_cell_count(spec, &area, &n, &err) == GP_OK) return n;
    return s->fit.cell_area.n;
}

static json_t *imc_error(const gp_specimen2d *s, const gp_spec2d *spec)
{
    double thr = isfinite(s->imc_threshold) && s->imc_threshold > 0 ? s->imc_threshold
                                                                    : spec->imc_threshold;
    return json_pack("{s:o, s:o, s:s, s:o, s:s}", "target", gpd_jreal(thr), "achieved",
                     gpd_jreal(s->imc_error), "measure", imc_measure(s, spec->imc_error),
                     "floor", gpd_jreal(s->imc_error_floor), "stop_reason",
                     s->imc_stop_reason ? s->imc_stop_reason : "");
}

/* ---- stats.shape: the shape the grains were given (gp_shape_used) ---- */

static const char *const DESC_NAMES[4] = {"elongation", "roundness", "circularity",
                                          "regularity"}; /* the order of gp_descriptors */

static const char *shape_form_name(gp_shape_form f)
{
    switch (f) {
    case GP_SHAPE_FORM_SPECTRUM: return "spectrum";
    case GP_SHAPE_FORM_DESCRIPTORS: return "descriptors";
    case GP_SHAPE_FORM_OUTLINES: return "outlines";
    default: return "D";
    }
}

/* the forms whose shape is computed (a descriptor fit, the outlines' analysis): the core
 * reports a "shape" phase for them and times it (t_shape) */
static int shape_computed(gp_shape_form f)
{
    return f == GP_SHAPE_FORM_DESCRIPTORS || f == GP_SHAPE_FORM_OUTLINES;
}

/* {"elongation": v[0], "roundness": v[1], "circularity": v[2], "regularity": v[3]} */
static json_t *per_descriptor(const double *v)
{
    json_t *o = json_object();
    for (int k = 0; o && k < 4; k++) json_object_set_new(o, DESC_NAMES[k], gpd_jreal(v[k]));
    return o;
}

/* the descriptors form: what the fit predicted, what the calibration measured */
static json_t *shape_fit(const gp_shape_used *u)
{
    json_t *missed = json_array();
    for (int k = 0; missed && k < 4; k++)
        if (u->missed & (1u << k)) json_array_append_new(missed, json_string(DESC_NAMES[k]));
    return json_pack("{s:o, s:o, s:I, s:i, s:i, s:o}", "predicted", per_descriptor(u->predicted),
                     "calibrated",
                     u->calibration_grains ? per_descriptor(u->calibrated) : json_null(),
                     "calibration_grains", (json_int_t)u->calibration_grains,
                     "calibration_rounds", u->calibration_rounds, "fit_evaluations",
                     u->fit_evaluations, "missed", missed);
}

/* the outlines form: how many were given and analysed, their descriptors' mean and sd */
static json_t *shape_outlines(const gp_shape_used *u)
{
    json_t *o = json_pack("{s:I, s:I}", "n", (json_int_t)u->noutlines, "analysed",
                          (json_int_t)u->noutlines_analysed);
    if (!o || !u->targets) return o;
    json_t *d = json_object();
    for (int k = 0; d && k < 4; k++)
        if (u->targets & (1u << k))
            json_object_set_new(d, DESC_NAMES[k],
                                json_pack("{s:o, s:o}", "mean", gpd_jreal(u->target[k]), "sd",
                                          gpd_jreal(u->target_sd[k])));
    json_object_set_new(o, "descriptors", d);
    return o;
}

/* o's members names[0 .. n) set to the numbers v[0 .. n), in that order */
static void set_reals(json_t *o, const char *const *names, const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++) json_object_set_new(o, names[i], gpd_jreal(v[i]));
}

/* stats.shape (see the top of the file) */
static json_t *shape_json(const gp_specimen2d *s, const gp_spec2d *spec)
{
    const gp_shape_used *u = &s->shape;
    json_t *o = json_object();
    if (!o) return NULL;
    json_object_set_new(o, "form", json_string(shape_form_name(u->form)));
    json_object_set_new(o, "spectrum", gpd_jreals(u->spectrum, u->nmodes));
    static const char *const names[] = {"D2", "D3", "D8", "alpha", "beta", "spread"};
    set_reals(o, names, (double[]){u->D2, u->D3, u->D8, u->alpha, u->beta, u->spread}, 6);
    json_object_set_new(o, "spread_source",
                        json_string(u->spread_from_outlines                  ? "outlines"
                                    : spec->spread_given || spec->spread > 0 ? "spec"
                                                                             : "none"));
    if (u->cov) json_object_set_new(o, "spread_cov", gpd_jreals(u->cov, u->nmodes));
    if (u->form == GP_SHAPE_FORM_DESCRIPTORS) json_object_set_new(o, "fit", shape_fit(u));
    if (u->form == GP_SHAPE_FORM_OUTLINES) json_object_set_new(o, "outlines", shape_outlines(u));
    json_object_set_new(o, "grains_redrawn", json_integer((json_int_t)u->grains_redrawn));
    json_object_set_new(o, "grains_clipped", json_integer((json_int_t)u->grains_clipped));
    return o;
}

/* the budget of the IMC, whether it was the default for the cell count, and what each run took
 * of it: the cells' law, then (a law of grains whose cells were resized for their grains) the
 * second run */
static json_t *imc_steps(const gp_specimen2d *s, const gp_spec2d *spec)
{
    json_t *runs = json_array();
    json_array_append_new(runs, json_integer((json_int_t)(s->imc_steps - s->imc_steps_resize)));
    if (s->imc_runs > 1)
        json_array_append_new(runs, json_integer((json_int_t)s->imc_steps_resize));
    return json_pack("{s:I, s:I, s:b, s:o}", "max", (json_int_t)spec->imc_max_steps, "achieved",
                     (json_int_t)s->imc_steps, "default", spec->imc_max_steps_default, "runs",
                     runs);
}

/* stats: the targets against what was achieved */
static json_t *stats_2d(const gp_specimen2d *s, const gp_spec2d *spec)
{
    json_t *st = json_object();
    /* achieved: the cells the IMC made (the grains, when they were asked for, are as many) */
    json_object_set_new(st, "particles",
                        json_pack("{s:I, s:I}", "target",
                                  (json_int_t)target_particles(s, spec), "achieved",
                                  (json_int_t)s->fit.cell_area.n));
    json_object_set_new(st, "imc_error", imc_error(s, spec));
    json_object_set_new(st, "imc_steps", imc_steps(s, spec));
    /* without grains nothing was filled: achieved is null, not 0 */
    json_object_set_new(st, "solid_fraction",
                        json_pack("{s:o, s:o}", "target", gpd_jreal(spec->solid_fraction),
                                  "achieved", s->ngrains ? gpd_jreal(s->solid_fraction) : json_null()));
    json_object_set_new(st, "container_area", gpd_jreal(s->container_area));
    json_object_set_new(st, "cells_target_met", json_integer((json_int_t)s->cells_target_met));
    json_object_set_new(st, "mean_orientation_gap_deg", gpd_jreal(s->mean_orientation_gap_deg));
    json_object_set_new(st, "size_histogram", hist_json(&s->size_hist));
    json_object_set_new(st, "grain_size_histogram", hist_json(&s->grain_size_hist));
    json_object_set_new(st, "orientation_histogram", hist_json(&s->orientation_hist));
    if (spec->outputs & GP_OUT2_DESCRIPTORS) {
        const double means[4] = {s->descriptor_mean.elongation, s->descriptor_mean.roundness,
                                 s->descriptor_mean.circularity, s->descriptor_mean.regularity};
        const double sds[4] = {s->descriptor_sd.elongation, s->descriptor_sd.roundness,
                               s->descriptor_sd.circularity, s->descriptor_sd.regularity};
        json_t *d = json_object();
        for (int k = 0; k < 4; k++) {
            json_t *h = hist_json(&s->descriptor_hist[k]);
            if (!json_is_object(h)) {
                json_decref(h);
                h = json_object();
            }
            /* the histogram has no target classes ("target": null): a target mean (shape
             * descriptors, or the outlines' own means) takes its place as a number */
            if (s->shape.targets & (1u << k))
                json_object_set_new(h, "target", gpd_jreal(s->shape.target[k]));
            json_object_set_new(h, "mean", gpd_jreal(means[k]));
            json_object_set_new(h, "sd", gpd_jreal(sds[k]));
            json_object_set_new(d, DESC_NAMES[k], h);
        }
        json_object_set_new(st, "descriptors", d);
    }
    json_object_set_new(st, "fit", gpd_fit_2d(&s->fit, 1));
    json_object_set_new(st, "shape", shape_json(s, spec));
    return st;
}

/* [x, y] */
static void point_w(gpd_jw *w, gp_vec2 p)
{
    gpd_jw_begin_array(w);
    gpd_jw_real(w, p.x);
    gpd_jw_real(w, p.y);
    gpd_jw_end_array(w);
}

static void ring_w(gpd_jw *w, const gp_vec2 *p, size_t n)
{
    gpd_jw_begin_array(w);
    for (size_t i = 0; i < n; i++) point_w(w, p[i]);
    gpd_jw_end_array(w);
}

static void real_member(gpd_jw *w, const char *key, double x)
{
    gpd_jw_key(w, key);
    gpd_jw_real(w, x);
}

/* a grain: {"id", "cell", "contour", "area", "orientation_deg", "cell_fraction",
 * "descriptors" (output descriptors), "discs" (output odec)} */
static void grain_w(gpd_jw *w, size_t i, const gp_grain2d *g, unsigned out)
{
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "id");
    gpd_jw_integer(w, (long long)i);
    gpd_jw_key(w, "cell");
    gpd_jw_integer(w, (long long)g->cell);
    gpd_jw_key(w, "contour");
    ring_w(w, g->contour, g->ncontour);
    real_member(w, "area", g->area);
    real_member(w, "orientation_deg", g->orientation_deg);
    real_member(w, "cell_fraction", g->cell_fraction);
    if (out & GP_OUT2_DESCRIPTORS) {
        gpd_jw_key(w, "descriptors");
        gpd_jw_begin_object(w);
        real_member(w, "elongation", g->descriptors.elongation);
        real_member(w, "roundness", g->descriptors.roundness);
        real_member(w, "circularity", g->descriptors.circularity);
        real_member(w, "regularity", g->descriptors.regularity);
        gpd_jw_end_object(w);
    }
    if (out & GP_OUT2_ODEC) {
        gpd_jw_key(w, "discs");
        gpd_jw_begin_array(w);
        for (size_t k = 0; k < g->ndiscs && g->discs; k++) {
            gpd_jw_begin_array(w);
            for (int c = 0; c < 3; c++) gpd_jw_real(w, g->discs[3 * k + c]);
            gpd_jw_end_array(w);
        }
        gpd_jw_end_array(w);
    }
    gpd_jw_end_object(w);
}

/* a cell: {"id", "seed", "polygons", "area", "orientation_deg"} */
static void cell_w(gpd_jw *w, size_t i, const gp_cell2d *cl)
{
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "id");
    gpd_jw_integer(w, (long long)i);
    gpd_jw_key(w, "seed");
    point_w(w, cl->seed);
    gpd_jw_key(w, "polygons");
    gpd_jw_begin_array(w);
    for (size_t k = 0; k < cl->npolygons; k++)
        ring_w(w, cl->polygons[k].pts, cl->polygons[k].n);
    gpd_jw_end_array(w);
    real_member(w, "area", cl->area);
    real_member(w, "orientation_deg", cl->orientation_deg);
    gpd_jw_end_object(w);
}

/* the arrays' items for gpd_jw_items, in blocks of ~450 KB of text (a grain of 128 points with
 * its discs and descriptors is ~7 KB; a cell less) */
#define GRAINS_BLOCK 64
typedef struct items_ctx {
    const gp_specimen2d *s;
    unsigned out;
} items_ctx;

static void grain_item(gpd_jw *w, size_t i, const void *user)
{
    const items_ctx *c = user;
    grain_w(w, i, &c->s->grains[i], c->out);
}

static void cell_item(gpd_jw *w, size_t i, const void *user)
{
    const items_ctx *c = user;
    cell_w(w, i, &c->s->cells[i]);
}

/* the result without its arrays: kind, seed, outputs, container, stats, warnings, timings */
static json_t *head_2d(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json)
{
    json_t *r = gpd_result_new(KIND_NAME, spec->seed, spec_json);
    if (!r) return NULL;
    json_t *c = json_object_get(spec_json, "container");
    if (c) json_object_set(r, "container", c);
    json_object_set_new(r, "stats", stats_2d(s, spec));
    json_object_set_new(r, "warnings", gpd_warnings_2d(s));
    /* "shape" (first, as it ran first) only when a shape phase ran */
    json_t *tm = json_object();
    if (shape_computed(s->shape.form)) json_object_set_new(tm, "shape", gpd_jreal(s->t_shape));
    static const char *const phases[] = {"tessellation", "imc", "fill", "odec", "descriptors",
                                         "total"};
    set_reals(tm, phases,
              (double[]){s->t_tessellation, s->t_imc, s->t_fill, s->t_odec, s->t_descriptors,
                         s->t_total},
              6);
    json_object_set_new(r, "timings", tm);
    return r;
}

json_t *gpd_result_2d_write(const gp_specimen2d *s, const gp_spec2d *spec,
                            const json_t *spec_json, gpd_jw *w)
{
    json_t *head = head_2d(s, spec, spec_json);
    if (!head) return NULL;
    unsigned out = spec->outputs;
    gpd_jw_begin_object(w);
    gpd_jw_members(w, head);
    /* the arrays, written as they are read from the specimen; the writer stops by itself at
     * the cancel flag (a grain is ~300 numbers at 128 contour points) */
    items_ctx c = {s, out};
    int nt = spec->threads > 0 ? spec->threads : 1; /* the job's: the same bytes whatever */
    if (out & (GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS)) {
        gpd_jw_key(w, "grains");
        gpd_jw_begin_array(w);
        gpd_jw_items(w, s->ngrains, grain_item, &c, nt, GRAINS_BLOCK);
        gpd_jw_end_array(w);
    }
    if ((out & GP_OUT2_CELLS) && s->cells) {
        gpd_jw_key(w, "cells");
        gpd_jw_begin_array(w);
        gpd_jw_items(w, s->ncells, cell_item, &c, nt, GRAINS_BLOCK);
        gpd_jw_end_array(w);
    }
    gpd_jw_end_object(w);
    return head;
}

json_t *gpd_result_2d(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json,
                      const volatile int *cancel)
{
    gpd_jw w;
    gpd_jw_init(&w, cancel);
    json_decref(gpd_result_2d_write(s, spec, spec_json, &w));
    char *text = gpd_jw_take(&w, NULL);
    json_error_t e;
    json_t *r = text ? json_loads(text, 0, &e) : NULL;
    free(text);
    return r;
}

/* ------------------------------------------------------------------ the kind */

GPD_KIND_CORE(gp_spec2d, gp_spec2d_read, gp_spec2d_free, gp_specimen2d, gp_specimen2d_build,
              gp_specimen2d_destroy)

/* {steps, error} */
static json_t *progress_detail(const gp_progress *p)
{
    return json_pack("{s:I, s:o}", "steps", (json_int_t)p->steps, "error", gpd_jreal(p->error));
}

/* ---- the progress plan (progress.h): seconds on one core, measured with
 * bench/bench_progress.py (10,000 grains of 128 points; the 3D kind's figures are of the same
 * run: together they give the machine's speed) ---- */
#define COST_TESS_S 20e-6   /* the first tessellation, a cell */
#define COST_IMC_S 25e-6    /* an IMC move at 1,000 cells ... */
#define COST_IMC_DECADE 0.6 /* ... and this much more per tenfold more cells */
#define IMC_MOVES_GUESS 4   /* moves a cell until the default threshold (a guess: the IMC runs
                               until it converges; its own rate takes over as it runs) */
#define COST_FILL_S 0.85e-3 /* filling a grain of 128 points ... */
#define REFILL_SHARE 0.3    /* ... and the refill passes (law on the cells), a guess: they
                               refill the cells that reached the fraction, each from its grain
                               (bench_specimen2d fill: 0.24 to 0.37 of the first pass) */
#define COST_ODEC_S 0.3e-3  /* its ODEC discs (0.2 to 0.46 of its filling, measured) */
#define COST_DESC_S 0.3e-3  /* its descriptors */
/* the shape phase, timed through the daemon (one worker) on a shared, loaded 2-core
 * machine (figures +-30 %) whose fill and descriptors ran 1.06x and 1.27x the figures above:
 * these are divided by ~1.15 to be at their speed.
 * - shape.descriptors, phase "shape": gp_shapemap_fit, a table search (milliseconds) and
 *   sampled evaluations of 256 grains at min(contour_points, 512) points, 1 or 2 of them
 *   (1.3 on average over six targets, two seeds, Np 64, 128, 256); an evaluation took
 *   0.08-0.09 s at Np 64, 0.10-0.12 s at 128, 0.15-0.19 s at 256: ~Np^0.75. The number of
 *   evaluations is not known beforehand: a guessed (unsized) phase. */
#define COST_FIT_EVAL_S 0.09   /* a sampled evaluation at 128 points ... */
#define FIT_NP_EXPONENT 0.75   /* ... times (Np / 128)^this */
#define FIT_NP_MAX 512         /* the fit samples at most this many points (core's cap) */
#define FIT_EVALS_GUESS 1.3
/* - shape.descriptors, phase "calibration" (grains only): rounds of filling and describing
 *   min(cells, 500) cells at the specimen's Np, one or two (2 in 30 of 48 runs above): a
 *   round measured 1.0-1.7 ms a cell at Np 128 (2.0-2.5 at 256), i.e. a fill and a
 *   description as planned above (COST_FILL_S + COST_DESC_S). The core reports each pass
 *   (fill, then describe) with its own fraction: the plan has the first round's two passes
 *   and the second round as one entry weighted by how often it runs (its describe pass is a
 *   repass of that entry, progress.c). */
#define CAL_ROUND2_SHARE 0.6
/* - shape.outlines, phase "shape": gp_outline_set_analyze, ~0.37 ms an outline at Np 128
 *   and ~1.7 ms at 512 (100-1,000 outlines of 64-1,000 vertices: the vertices barely count) */
#define COST_OUTLINE_S 0.33e-3 /* an outline at 128 points, times Np / 128 */
/* - a law of grains (size.of "grains", a sieve) from about this many cells on usually sizes its
 *   cells again (the core's resize_cells: at 500 grains the first cells do, at 2,000-100,000
 *   the second IMC ran in every case measured), and that IMC took about as many steps again
 *   (10,000 grains: 30,503 + 30,167; the sieve's 3,931 grains: 28,015 + 13,037) */
#define RESIZE_CELLS_MIN 2000
#define DISCS_GUESS 20      /* ODEC discs of a grain, for the plan */
#define CORNERS_GUESS 7     /* corners of a cell, for the plan */
/* bytes of the result's text (at 17 digits): a grain's own members, a contour point, a disc,
 * a cell's own members and a corner of its polygons */
#define BYTES_GRAIN 250
#define BYTES_POINT 40
#define BYTES_DISC 60
#define BYTES_CELL 120

/* The phases, in the core's order: shape (forms descriptors and outlines), tessellation, imc,
 * calibration (descriptors, with grains), fill and its refill, odec (and descriptors),
 * result. */
static int plan(const void *spec_, const json_t *spec_json, gpd_phase *out, int max)
{
    const gp_spec2d *spec = spec_;
    double np = (double)spec->contour_points, scale = np / 128;
    gp_spec_bounds_t b;
    gp_spec_problem p;
    if (gp_spec_bounds(spec_json, &b, &p)) return 0;
    double n = b.cells, moves = fmin((double)spec->imc_max_steps, IMC_MOVES_GUESS * n);
    unsigned o = spec->outputs;
    int grains = (o & (GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS)) != 0;
    int finish = (o & (GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS)) ||
                 spec->size_of_grains || spec->size_law == GP_LAW_SIEVE;
    /* the core's shape_step: only these forms compute their shape (spectrum wins) */
    gp_shape_form form = spec->has_spectrum ? GP_SHAPE_FORM_SPECTRUM : spec->shape_form;
    gpd_phase ph[GPD_PLAN_MAX];
    int k = 0;
    if (form == GP_SHAPE_FORM_DESCRIPTORS)
        ph[k++] = (gpd_phase){"shape", FIT_EVALS_GUESS * COST_FIT_EVAL_S *
                                           pow(fmin(np, FIT_NP_MAX) / 128, FIT_NP_EXPONENT), 0};
    if (form == GP_SHAPE_FORM_OUTLINES)
        ph[k++] = (gpd_phase){"shape", COST_OUTLINE_S * (double)spec->noutlines * scale, 1};
    ph[k++] = (gpd_phase){"tessellation", COST_TESS_S * n, 1};
    int imc = k;
    ph[k++] = (gpd_phase){"imc", moves * COST_IMC_S *
                                     (1 + COST_IMC_DECADE * log10(fmax(n, 1000) / 1000)), 0};
    if (grains && form == GP_SHAPE_FORM_DESCRIPTORS) {
        double m = fmin(n, GP_SPECIMEN2D_CALIBRATION_CELLS) * scale;
        ph[k++] = (gpd_phase){"calibration", COST_FILL_S * m, 1};
        ph[k++] = (gpd_phase){"calibration", COST_DESC_S * m, 1};
        ph[k++] = (gpd_phase){"calibration", CAL_ROUND2_SHARE * (COST_FILL_S + COST_DESC_S) * m,
                              0};
    }
    if (grains) ph[k++] = (gpd_phase){"fill", COST_FILL_S * n * scale, 1};
    if (grains && !spec->size_of_grains && spec->size_law != GP_LAW_SIEVE)
        ph[k++] = (gpd_phase){"fill", REFILL_SHARE * COST_FILL_S * n * scale, 0};
    if (grains && (spec->size_of_grains || spec->size_law == GP_LAW_SIEVE) &&
        n >= RESIZE_CELLS_MIN) { /* the core's resize_cells: the IMC again, a second pass A */
        ph[k++] = (gpd_phase){"imc", ph[imc].cost_s, 0};
        ph[k++] = (gpd_phase){"fill", COST_FILL_S * n * scale, 1};
    }
    if (grains && finish)
        ph[k++] = (gpd_phase){"odec", n * scale * (((o & GP_OUT2_ODEC) ? COST_ODEC_S : 0) +
                                                   ((o & GP_OUT2_DESCRIPTORS) ? COST_DESC_S : 0)),
                              1};
    double bytes = ((o & GP_OUT2_CELLS) ? n * (BYTES_CELL + BYTES_POINT * CORNERS_GUESS) : 0) +
                   (grains ? n * (BYTES_GRAIN + BYTES_POINT * np +
                                  ((o & GP_OUT2_ODEC) ? BYTES_DISC * DISCS_GUESS : 0))
                           : 0);
    ph[k++] = (gpd_phase){"result", GPD_RESULT_S_PER_BYTE * bytes, 1};
    if (k > max) return 0;
    memcpy(out, ph, (size_t)k * sizeof *ph);
    return k;
}

/* the result's bytes: its grains with their contours and discs, its cells with their
 * polygons */
static double result_cost(const void *specimen)
{
    const gp_specimen2d *s = specimen;
    double bytes = 0;
    for (size_t i = 0; i < s->ngrains; i++)
        bytes += BYTES_GRAIN + BYTES_POINT * (double)s->grains[i].ncontour +
                 BYTES_DISC * (double)s->grains[i].ndiscs;
    for (size_t i = 0; s->cells && i < s->ncells; i++) {
        bytes += BYTES_CELL;
        for (size_t k = 0; k < s->cells[i].npolygons; k++)
            bytes += BYTES_POINT * (double)s->cells[i].polygons[k].n;
    }
    return GPD_RESULT_S_PER_BYTE * bytes;
}

static json_t *result(const void *specimen, const void *spec, const json_t *spec_json,
                      gpd_jw *w)
{
    return gpd_result_2d_write(specimen, spec, spec_json, w);
}

/* Exports need the ODEC discs. Without them the grains still get a view pack (their contours
 * and descriptors, no discs): the SVG views read a pack's records about ten times faster
 * than they parse the result's text, and GET .../export answers it 409 naming the output to
 * ask for, as it does a job without a pack. Cells only: no pack. */
static int pack(const void *specimen, const void *spec, void **pack, size_t *len, gp_error *err)
{
    unsigned out = ((const gp_spec2d *)spec)->outputs;
    if (out & GP_OUT2_ODEC)
        return gp_export_pack_2d(specimen, spec, GP_EXPORT_DEFAULT_DENSITY, pack, len, err) ? -1 : 0;
    if (!(out & (GP_OUT2_GRAINS | GP_OUT2_DESCRIPTORS))) return 1;
    return gp_export_pack_2d_view(specimen, spec, pack, len, err) ? -1 : 0;
}

/* How the IMC ended, the warnings and the fit summary (stats.fit without its CDF curves), so
 * that a poller of GET /v1/jobs/{id} sees them without the result. */
static json_t *done_detail(const char *id, const void *specimen)
{
    const gp_specimen2d *s = specimen;
    json_t *w = gpd_warnings_2d(s);
    for (size_t i = 0; i < json_array_size(w); i++)
        gpd_log(GPD_LOG_WARN, "job %s: %s", id, json_string_value(json_array_get(w, i)));
    return json_pack("{s:I, s:o, s:s, s:o, s:o}", "steps", (json_int_t)s->imc_steps, "error",
                     gpd_jreal(s->imc_error), "stop_reason",
                     s->imc_stop_reason ? s->imc_stop_reason : "", "warnings", w ? w : json_array(),
                     "fit", gpd_fit_2d(&s->fit, 0));
}

static const gpd_view views[] = {
    {"packing", "color", svg_views2d_packing, NULL},
    {"cells", "", svg_views2d_cells, NULL},
    {"size", "", svg_stats2d_size, NULL},
    {"orientation", "", svg_stats2d_orientation, NULL},
    {"descriptors", "", svg_stats2d_descriptors, NULL},
    {NULL, NULL, NULL, NULL},
};

/* the api.md example */
static const char example[] =
    "{\"kind\": \"fourier-voronoi-2d\", \"seed\": 42,"
    " \"container\": {\"polygon\": [[0, 0], [1, 0], [1, 1], [0, 1]], \"holes\": []},"
    " \"particles\": 500, \"size\": {\"cov\": 0.8},"
    " \"orientation\": {\"mean_deg\": 0, \"anisotropy\": 1.0},"
    " \"shape\": {\"D2\": 0.1, \"D3\": 0.05, \"D8\": 0.02, \"alpha\": -2, \"beta\": -2},"
    " \"solid_fraction\": 0.65,"
    " \"contour_points\": 128, \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}";

/* the phases of its "timings" (gpd_result_2d; "shape" only in some) */
static const char *const phases[] = {"shape", "tessellation", "imc", "fill", "odec",
                                     "descriptors", "total", NULL};

const gpd_kind gpd_kind_fv2d = {
    .name = KIND_NAME, .example = example, .bounds = gp_spec_check_result, .brief = gpd_brief_cells,
    GPD_KIND_CORE_OPS(gp_spec2d), .progress_detail = progress_detail,
    .plan = plan, .result_cost = result_cost, .result = result, .pack = pack,
    .done_detail = done_detail, .views = views, .export_dim = 2, .pack_what = "ODEC discs",
    .pack_output = "odec", .phases = phases};
