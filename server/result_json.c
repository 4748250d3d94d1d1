/* result_json.c -- gp_specimen2d -> JSON (format in result_json.h). */
#include "result_json.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

json_t *gpd_jreal(double x)
{
    return isfinite(x) ? json_real(x) : json_null();
}

static json_t *reals(const double *v, size_t n)
{
    if (!v) return json_null();
    json_t *a = json_array();
    for (size_t i = 0; i < n; i++) json_array_append_new(a, gpd_jreal(v[i]));
    return a;
}

static json_t *hist_json(const gp_hist *h)
{
    if (!h || h->nclasses == 0 || !h->edges) return json_null();
    return json_pack("{s:o, s:o, s:o}", "edges", reals(h->edges, h->nclasses + 1), "target",
                     reals(h->target, h->nclasses), "achieved", reals(h->achieved, h->nclasses));
}

static json_t *point(gp_vec2 p)
{
    return json_pack("[o, o]", gpd_jreal(p.x), gpd_jreal(p.y));
}

static json_t *ring(const gp_vec2 *p, size_t n)
{
    json_t *a = json_array();
    for (size_t i = 0; i < n; i++) json_array_append_new(a, point(p[i]));
    return a;
}

static json_t *descriptors(const gp_descriptors *d)
{
    return json_pack("{s:o, s:o, s:o, s:o}", "elongation", gpd_jreal(d->elongation), "roundness",
                     gpd_jreal(d->roundness), "circularity", gpd_jreal(d->circularity),
                     "regularity", gpd_jreal(d->regularity));
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

/* ------------------------------------------------------------------ fit (api.md stats.fit) */

static json_t *mean_cov(double mean, double cov)
{
    return json_pack("{s:o, s:o}", "mean", gpd_jreal(mean), "cov", gpd_jreal(cov));
}

static json_t *pair(double a, double b)
{
    return json_pack("[o, o]", gpd_jreal(a), gpd_jreal(b));
}

static json_t *fit_area(const gp_fit_area *a, int with_curves)
{
    const char *law = gp_law_name(a->law);
    json_t *o = json_pack("{s:s, s:o, s:o, s:o, s:o, s:o, s:I}", "law", law ? law : "",
                          "target", mean_cov(a->target_mean, a->target_cov), "achieved",
                          mean_cov(a->mean, a->cov), "ks", gpd_jreal(a->ks), "ks_critical",
                          gpd_jreal(a->ks_critical), "w1", gpd_jreal(a->w1), "n",
                          (json_int_t)a->n);
    if (!o) return NULL;
    json_object_set_new(o, "range", json_pack("{s:o, s:o}", "achieved", pair(a->min, a->max),
                                              "target_p001_p999", pair(a->q001, a->q999)));
    if (with_curves && a->ncurve > 0 && a->curve_x && a->curve_target && a->curve_achieved)
        json_object_set_new(o, "cdf",
                            json_pack("{s:o, s:o, s:o}", "x", reals(a->curve_x, a->ncurve),
                                      "target", reals(a->curve_target, a->ncurve), "achieved",
                                      reals(a->curve_achieved, a->ncurve)));
    return o;
}

static json_t *fit_orient(const gp_fit_orient *o)
{
    return json_pack("{s:{s:o, s:o}, s:o, s:o, s:I}", "target", "mean_deg",
                     gpd_jreal(o->target_mean_deg), "anisotropy",
                     gpd_jreal(o->target_anisotropy), "ks", gpd_jreal(o->ks), "ks_critical",
                     gpd_jreal(o->ks_critical), "n", (json_int_t)o->n);
}

static json_t *fit_passing(const gp_fit_passing *p)
{
    return json_pack("{s:o, s:o, s:o, s:o}", "diameters", reals(p->diameters, p->n), "target",
                     reals(p->target, p->n), "achieved", reals(p->achieved, p->n),
                     "max_error_pp", gpd_jreal(p->max_error_pp));
}

json_t *gpd_fit_2d(const gp_fit2d *f, int with_curves)
{
    json_t *o = json_object();
    if (!o || !f) return o;
    if (f->cell_area.present)
        json_object_set_new(o, "cell_area", fit_area(&f->cell_area, with_curves));
    if (f->grain_area.present)
        json_object_set_new(o, "grain_area", fit_area(&f->grain_area, with_curves));
    if (f->cell_orientation.present)
        json_object_set_new(o, "cell_orientation", fit_orient(&f->cell_orientation));
    if (f->grain_orientation.present)
        json_object_set_new(o, "grain_orientation", fit_orient(&f->grain_orientation));
    if (f->passing.n > 0) json_object_set_new(o, "passing", fit_passing(&f->passing));
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

/* The worker's cancel flag, raised by another thread with an atomic store. The big arrays
 * (grains, cells, spheres, contacts) take seconds to build for a large specimen (a 233,000-sphere
 * tiling with its contacts: 1.5 s), so their loops look at it every few thousand numbers. */
static int cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

/* A tree whose building was cancelled goes back as it stands: freeing it can take a second
 * (with a sanitizer, more), which the caller hands to another thread; it sees the flag. */
static json_t *abandon(json_t *r) { return r; }

json_t *gpd_result_2d(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json)
{
    return gpd_result_2d_c(s, spec, spec_json, NULL);
}

json_t *gpd_result_2d_c(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json,
                        const volatile int *cancel)
{
    json_t *r = json_object();
    if (!r) return NULL;
    unsigned out = spec->outputs;
    json_object_set_new(r, "kind", json_string("fourier-voronoi-2d"));
    json_object_set_new(r, "seed", json_integer((json_int_t)spec->seed));
    json_t *o = json_object_get(spec_json, "outputs");
    if (o) json_object_set(r, "outputs", o);
    json_t *c = json_object_get(spec_json, "container");
    if (c) json_object_set(r, "container", c);

    json_t *st = json_object();
    /* achieved: the cells the IMC made (the grains, when they were asked for, are as many) */
    json_object_set_new(st, "particles",
                        json_pack("{s:I, s:I}", "target",
                                  (json_int_t)target_particles(s, spec), "achieved",
                                  (json_int_t)s->fit.cell_area.n));
    json_object_set_new(st, "imc_error", imc_error(s, spec));
    json_object_set_new(st, "imc_steps",
                        json_pack("{s:I, s:I}", "max", (json_int_t)spec->imc_max_steps,
                                  "achieved", (json_int_t)s->imc_steps));
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
    if (out & GP_OUT2_DESCRIPTORS) {
        static const char *names[4] = {"elongation", "roundness", "circularity", "regularity"};
        const double means[4] = {s->descriptor_mean.elongation, s->descriptor_mean.roundness,
                                 s->descriptor_mean.circularity, s->descriptor_mean.regularity};
        json_t *d = json_object();
        for (int k = 0; k < 4; k++) {
            json_t *h = hist_json(&s->descriptor_hist[k]);
            if (!json_is_object(h)) {
                json_decref(h);
                h = json_object();
            }
            json_object_set_new(h, "mean", gpd_jreal(means[k]));
            json_object_set_new(d, names[k], h);
        }
        json_object_set_new(st, "descriptors", d);
    }
    json_object_set_new(st, "fit", gpd_fit_2d(&s->fit, 1));
    json_object_set_new(r, "stats", st);
    json_object_set_new(r, "warnings", gpd_warnings_2d(s));

    json_object_set_new(
        r, "timings",
        json_pack("{s:o, s:o, s:o, s:o, s:o, s:o}", "tessellation", gpd_jreal(s->t_tessellation),
                  "imc", gpd_jreal(s->t_imc), "fill", gpd_jreal(s->t_fill), "odec",
                  gpd_jreal(s->t_odec), "descriptors", gpd_jreal(s->t_descriptors), "total",
                  gpd_jreal(s->t_total)));

    if (out & (GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS)) {
        json_t *ga = json_array();
        json_object_set_new(r, "grains", ga); /* (filled in place: dropped with r on cancel) */
        for (size_t i = 0; i < s->ngrains; i++) {
            /* a grain is ~70 us at 128 contour points, ~2 ms at 4096 */
            if (i % 16 == 0 && cancel_raised(cancel)) return abandon(r);
            const gp_grain2d *g = &s->grains[i];
            json_t *gj = json_object();
            json_object_set_new(gj, "id", json_integer((json_int_t)i));
            json_object_set_new(gj, "cell", json_integer((json_int_t)g->cell));
            json_object_set_new(gj, "contour", ring(g->contour, g->ncontour));
            json_object_set_new(gj, "area", gpd_jreal(g->area));
            json_object_set_new(gj, "orientation_deg", gpd_jreal(g->orientation_deg));
            json_object_set_new(gj, "cell_fraction", gpd_jreal(g->cell_fraction));
            if (out & GP_OUT2_DESCRIPTORS)
                json_object_set_new(gj, "descriptors", descriptors(&g->descriptors));
            if (out & GP_OUT2_ODEC) {
                json_t *da = json_array();
                for (size_t k = 0; k < g->ndiscs && g->discs; k++)
                    json_array_append_new(da, json_pack("[o, o, o]", gpd_jreal(g->discs[3 * k]),
                                                        gpd_jreal(g->discs[3 * k + 1]),
                                                        gpd_jreal(g->discs[3 * k + 2])));
                json_object_set_new(gj, "discs", da);
            }
            json_array_append_new(ga, gj);
        }
    }
    if ((out & GP_OUT2_CELLS) && s->cells) {
        json_t *ca = json_array();
        json_object_set_new(r, "cells", ca);
        for (size_t i = 0; i < s->ncells; i++) {
            if (i % 256 == 0 && cancel_raised(cancel)) return abandon(r);
            const gp_cell2d *cl = &s->cells[i];
            json_t *polys = json_array();
            for (size_t k = 0; k < cl->npolygons; k++)
                json_array_append_new(polys, ring(cl->polygons[k].pts, cl->polygons[k].n));
            json_array_append_new(
                ca, json_pack("{s:I, s:o, s:o, s:o, s:o}", "id", (json_int_t)i, "seed",
                              point(cl->seed), "polygons", polys, "area", gpd_jreal(cl->area),
                              "orientation_deg", gpd_jreal(cl->orientation_deg)));
        }
    }
    return r;
}

/* ------------------------------------------------------------------ 3D */

static json_t *vec3(const double *v)
{
    return json_pack("[o, o, o]", gpd_jreal(v[0]), gpd_jreal(v[1]), gpd_jreal(v[2]));
}

static json_t *mat3(const double m[3][3])
{
    return json_pack("[o, o, o]", vec3(m[0]), vec3(m[1]), vec3(m[2]));
}

json_t *gpd_result_3d(const gp_specimen3d *s, const gp_spec3d *spec, const json_t *spec_json)
{
    return gpd_result_3d_c(s, spec, spec_json, NULL);
}

json_t *gpd_result_3d_c(const gp_specimen3d *s, const gp_spec3d *spec, const json_t *spec_json,
                        const volatile int *cancel)
{
    json_t *r = json_object();
    if (!r) return NULL;
    unsigned out = spec->outputs;
    const gp_stats3d *t = &s->stats;
    json_object_set_new(r, "kind", json_string("spheres-3d"));
    json_object_set_new(r, "seed", json_integer((json_int_t)spec->seed));
    json_t *o = json_object_get(spec_json, "outputs");
    if (o) json_object_set(r, "outputs", o);
    json_object_set_new(r, "box", vec3(s->box));
    json_object_set_new(r, "sample_box", vec3(s->sample_box));
    json_object_set_new(r, "tiling", json_pack("[i, i, i]", spec->tiling[0], spec->tiling[1],
                                               spec->tiling[2]));

    json_t *st = json_object();
    json_object_set_new(st, "porosity",
                        json_pack("{s:o, s:o, s:o, s:o}", "target", gpd_jreal(t->porosity_target),
                                  "achieved", gpd_jreal(t->porosity), "sample",
                                  gpd_jreal(t->sample_porosity), "deposition",
                                  gpd_jreal(t->deposition_porosity)));
    json_object_set_new(st, "coordination_number", gpd_jreal(t->coordination_number));
    json_object_set_new(st, "coordination_spheres", gpd_jreal(t->coordination_spheres));
    if (out & GP_OUT3_FABRIC) json_object_set_new(st, "fabric", mat3(t->fabric));
    if (out & GP_OUT3_STRESS) json_object_set_new(st, "stress", mat3(t->stress));
    const gp_psd3d *p = &t->psd;
    json_object_set_new(
        st, "psd",
        json_pack("{s:o, s:o, s:o, s:o, s:o, s:o}", "diameters", reals(p->diameter, p->n),
                  "target_weight", reals(p->target_weight, p->n), "achieved_weight",
                  reals(p->achieved_weight, p->n), "target_number", reals(p->target_number, p->n),
                  "target_number_midbin", reals(p->target_number_midbin, p->n),
                  "achieved_number", reals(p->achieved_number, p->n)));
    json_object_set_new(st, "particles", json_integer((json_int_t)t->particles));
    json_object_set_new(st, "sample_particles", json_integer((json_int_t)t->sample_particles));
    json_object_set_new(st, "contacts", json_integer((json_int_t)t->contacts));
    json_object_set_new(st, "wall_contacts", json_integer((json_int_t)t->wall_contacts));
    json_object_set_new(st, "stop_reason", json_string(t->stop_reason ? t->stop_reason : ""));
    json_object_set_new(st, "stability", gpd_jreal(t->stability));
    json_object_set_new(st, "tiled_stability", gpd_jreal(t->tiled_stability));
    json_object_set_new(st, "compaction_friction_deg", gpd_jreal(t->compaction_friction_deg));
    json_object_set_new(st, "steps", json_integer((json_int_t)t->steps));
    json_object_set_new(st, "dt", gpd_jreal(t->dt));
    json_object_set_new(r, "stats", st);

    json_object_set_new(r, "timings",
                        json_pack("{s:o, s:o, s:o, s:o, s:o}", "deposition",
                                  gpd_jreal(s->t_deposition), "compaction",
                                  gpd_jreal(s->t_compaction), "relaxation",
                                  gpd_jreal(s->t_relaxation), "tiling", gpd_jreal(s->t_tiling),
                                  "total", gpd_jreal(s->t_total)));
    if ((out & GP_OUT3_SPHERES) && s->spheres) {
        json_t *a = json_array();
        json_object_set_new(r, "spheres", a);
        for (size_t i = 0; i < s->count; i++) {
            if (i % 4096 == 0 && cancel_raised(cancel)) return abandon(r);
            const double *q = s->spheres + 4 * i;
            json_array_append_new(a, json_pack("[o, o, o, o]", gpd_jreal(q[0]), gpd_jreal(q[1]),
                                               gpd_jreal(q[2]), gpd_jreal(q[3])));
        }
    }
    if ((out & GP_OUT3_CONTACTS) && s->contacts) {
        json_t *a = json_array();
        json_object_set_new(r, "contacts", a);
        for (size_t i = 0; i < s->ncontacts; i++) {
            if (i % 2048 == 0 && cancel_raised(cancel)) return abandon(r);
            const gp_contact3d *c = &s->contacts[i];
            json_array_append_new(a, json_pack("{s:I, s:I, s:o, s:o, s:o}", "i",
                                               (json_int_t)c->i, "j", (json_int_t)c->j, "normal",
                                               vec3(c->normal), "overlap", gpd_jreal(c->overlap),
                                               "force", vec3(c->force)));
        }
    }
    return r;
}

/* ------------------------------------------------------------------ writing */

typedef struct dump_buf {
    char *p;
    size_t len, cap;
    unsigned long calls;
    const volatile int *cancel;
} dump_buf;

/* json_dump_callback's sink: appends, and gives up (-1: jansson stops writing) when the flag
 * is up, looked at every 4096 pieces (a piece is a number, a string or a bracket). */
static int dump_piece(const char *buffer, size_t size, void *data)
{
    dump_buf *b = data;
    if (++b->calls % 4096 == 0 && cancel_raised(b->cancel)) return -1;
    if (b->len + size + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 65536;
        while (cap < b->len + size + 1) cap *= 2;
        char *q = realloc(b->p, cap);
        if (!q) return -1;
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->len, buffer, size);
    b->len += size;
    return 0;
}

char *gpd_dumps_c(const json_t *r, size_t flags, const volatile int *cancel)
{
    dump_buf b = {NULL, 0, 0, 0, cancel};
    if (!r || json_dump_callback(r, dump_piece, &b, flags) != 0 || !b.p) {
        free(b.p);
        return NULL;
    }
    b.p[b.len] = '\0';
    char *fit = realloc(b.p, b.len + 1); /* the doubling's slack back (up to half of it) */
    return fit ? fit : b.p;
}
