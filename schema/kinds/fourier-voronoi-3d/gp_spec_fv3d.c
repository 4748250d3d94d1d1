/* gp_spec_fv3d.c -- the kind "fourier-voronoi-3d": the field rules that the schema cannot
 * express (on the spec as posted), the defaults that depend on other fields, the reader of an
 * effective spec into gp_spec_fv3d, its semantic checks (the container, the size law, the
 * orientation axis, the spectrum and how often its grains are star-shaped, a sieve's count, the
 * memory and the work budget) and its work and result bounds. See gp_spec_fv3d.h. */
#include "gp_spec_internal.h"

#include "gp_spec_fv.h"
#include "gp_spec_fv3d.h"

#include "gp_fourier.h"
#include "gp_grain3d.h"
#include "gp_imc.h"
#include "gp_rng.h"
#include "gp_voronoi3d.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gp_spec_kind gp_spec_kind_fourier_voronoi_3d; /* this kind, defined at the end */

extern const unsigned char gp_schema_text_fourier_voronoi_3d[];

const char *const gp_spec_fv3d_outputs[4] = {"grains", "clumps", "descriptors", "cells"};

/* the star-shape sampling at submit draws from this stream of seed 0, whatever the spec's
 * seed: whether a spec is accepted does not depend on its seed */
#define STAR_STREAM 1
#define STAR_LEVEL 2 /* the basis the sampled grains are checked on (the test is exact anyway) */

static double u01(void *rng) { return gp_rng_uniform(rng); }

/* ------------------------------------------------------------------------------------------ */
/* the spec as posted, and the defaults that depend on other fields */

/* size.law decides which size fields belong (particles and size.cov have schema defaults) */
static int check_posted_fv3d(const json_t *spec, gp_spec_problem *p)
{
    return gp_spec_fv_check_size_posted(spec, "the container's volume", p);
}

/* the forms of an object of oneOf branches by the fields that start them (index), -1 for a
 * field any form has */
static int form_of(const char *const (*forms)[6], int nforms, const char *key)
{
    for (int f = 0; f < nforms; f++)
        for (int k = 0; k < 6 && forms[f][k]; k++)
            if (!strcmp(key, forms[f][k])) return f;
    return -1;
}

/* the member of o that starts a second form ("" none), and the first form's first member */
static int mixed_forms(const json_t *o, const char *const (*forms)[6], int nforms,
                       const char **first, const char **second)
{
    int form = -1;
    const char *key;
    const json_t *v;
    json_object_foreach((json_t *)o, key, v) {
        int f = form_of(forms, nforms, key);
        if (f < 0) continue;
        if (form < 0) {
            form = f;
            *first = key;
        } else if (f != form) {
            *second = key;
            return 1;
        }
    }
    return 0;
}

/* explain: a shape or a container that mixes two forms fits no branch of the schema's oneOf,
 * which can only say "expected <every form>"; name the field that starts the second form */
static int explain_fv3d(const json_t *spec, gp_spec_problem *p)
{
    static const char *const shapes[][6] = {{"D2", "D3", "D8", "alpha", "beta", NULL},
                                            {"spectrum", NULL}};
    static const char *const containers[][6] = {{"box", NULL}, {"cylinder", NULL},
                                                {"polyhedron", NULL}};
    const char *first = NULL, *second = NULL;
    char ptr[96];
    if (!strcmp(p->pointer, "/shape")) {
        const json_t *shape = json_object_get(spec, "shape");
        if (!json_is_object(shape) || !mixed_forms(shape, shapes, 2, &first, &second)) return 0;
        snprintf(ptr, sizeof ptr, "/shape/%s", second);
        gp_problem(p, "invalid_spec", ptr, "cannot be combined with \"%s\": give the shape one "
                   "way -- D2, D3, D8 (with alpha, beta) or spectrum -- each with optional "
                   "elongation, flatness and spread", first);
        return 1;
    }
    if (!strcmp(p->pointer, "/container")) {
        const json_t *c = json_object_get(spec, "container");
        if (!json_is_object(c) || !mixed_forms(c, containers, 3, &first, &second)) return 0;
        snprintf(ptr, sizeof ptr, "/container/%s", second);
        gp_problem(p, "invalid_spec", ptr, "cannot be combined with \"%s\": give one container "
                   "-- box, cylinder or polyhedron", first);
        return 1;
    }
    return 0;
}

/* a sieve law has no particles (derived) and no cov, and is a law of the grains; sieve_units
 * belongs to a sieve; the IMC's threshold is the AD default. 0, or -1 out of memory */
static int settle_defaults_fv3d(json_t *full)
{
    return gp_spec_fv_settle(full, GP_IMC_ERROR_AD);
}

/* ------------------------------------------------------------------------------------------ */
/* the reader (an effective spec: nothing is checked but its form) */

void gp_spec_fv3d_free(gp_spec_fv3d *s)
{
    if (!s) return;
    free(s->planes);
    free(s->sieve_d);
    free(s->sieve_pass);
    free(s->spectrum);
    gp_law_destroy(s->law);
    memset(s, 0, sizeof *s);
}

/* the container's form and numbers; -1 out of memory */
static int read_container(gp_spec_reader *r, const json_t *c, gp_spec_fv3d *out)
{
    const json_t *box = gp_rd_array(r, c, "/container/box", 3, 3, 1);
    const json_t *cyl = gp_rd_member(r, c, "/container/cylinder", JSON_OBJECT, 1);
    if (box) {
        out->container = GP_SPEC_FV3D_BOX;
        for (size_t i = 0; i < 3; i++)
            out->box[i] = gp_rd_value(r, json_array_get(box, i), "/container/box", -GP_RD_ANY,
                                      GP_RD_ANY);
        return 0;
    }
    if (cyl) {
        out->container = GP_SPEC_FV3D_CYLINDER;
        out->radius = gp_rd_num(r, cyl, "/container/cylinder/radius", -GP_RD_ANY, GP_RD_ANY);
        out->height = gp_rd_num(r, cyl, "/container/cylinder/height", -GP_RD_ANY, GP_RD_ANY);
        return 0;
    }
    out->container = GP_SPEC_FV3D_POLYHEDRON;
    const json_t *poly = gp_rd_member(r, c, "/container/polyhedron", JSON_OBJECT, 0);
    const json_t *hs = gp_rd_array(r, poly, "/container/polyhedron/halfspaces", 1, SIZE_MAX, 0);
    size_t n = json_array_size(hs);
    out->planes = malloc((n ? n : 1) * 4 * sizeof *out->planes);
    if (!out->planes) return -1;
    out->nplanes = n;
    for (size_t i = 0; i < n; i++) {
        const json_t *row = json_array_get(hs, i);
        if (json_array_size(row) != 4) gp_rd_bad(r, "/container/polyhedron/halfspaces");
        for (size_t k = 0; k < 4; k++)
            out->planes[4 * i + k] = gp_rd_value(r, json_array_get(row, k),
                                                 "/container/polyhedron/halfspaces", -GP_RD_ANY,
                                                 GP_RD_ANY);
    }
    return 0;
}

/* the law, its cov or its sieve (in metres); -1 out of memory */
static int read_size(gp_spec_reader *r, const json_t *size, gp_spec_fv3d *out)
{
    gp_spec_fv_size z;
    int rc = gp_spec_fv_read_size(r, size, &z);
    out->law_kind = z.law;
    out->of_grains = z.law == GP_LAW_SIEVE ? 1 : z.of_grains; /* a sieve is a law of the grains */
    out->cov = z.cov;
    out->sieve_d = z.sieve_d;
    out->sieve_pass = z.sieve_pass;
    out->nsieve = z.nsieve;
    return rc;
}

/* the D form's numbers or the spectrum (as given: D0 first), the stretch and the spread; -1
 * out of memory */
static int read_shape(gp_spec_reader *r, const json_t *shape, gp_spec_fv3d *out)
{
    out->core.elongation = gp_rd_num(r, shape, "/shape/elongation", -GP_RD_ANY, GP_RD_ANY);
    out->core.flatness = gp_rd_num(r, shape, "/shape/flatness", -GP_RD_ANY, GP_RD_ANY);
    out->core.spread = gp_rd_num(r, shape, "/shape/spread", -GP_RD_ANY, GP_RD_ANY);
    double *const num[5] = {&out->D2, &out->D3, &out->D8, &out->alpha, &out->beta};
    int form = gp_spec_fv_read_shape(r, shape, num, &out->spectrum, &out->nspectrum);
    if (form < 0) return -1;
    out->shape_form = form;
    return 0;
}

/* Every field into *out, without the checks and without the law or the container's volume
 * (prepare makes them). 0, or -1 with *p (*out owns what it holds either way). */
static int read_raw(const json_t *full, gp_spec_fv3d *out, gp_spec_problem *p)
{
    if (gp_spec_read_begin(&gp_spec_kind_fourier_voronoi_3d, full, out, sizeof *out, p))
        return -1;
    gp_fv3d_spec_defaults(&out->core);
    out->threads = 1;
    gp_spec_reader r = {0};
    gp_fv3d_spec *c = &out->core;
    c->seed = (uint64_t)gp_rd_num(&r, full, "/seed", 0, GP_RD_COUNT);
    const json_t *size = gp_rd_member(&r, full, "/size", JSON_OBJECT, 0);
    int rc = read_size(&r, size, out);
    if (out->law_kind != GP_LAW_SIEVE)
        c->particles = (size_t)gp_rd_num(&r, full, "/particles", 0, GP_RD_COUNT);
    const json_t *ori = gp_rd_member(&r, full, "/orientation", JSON_OBJECT, 0);
    const json_t *axis = gp_rd_array(&r, ori, "/orientation/axis", 3, 3, 0);
    for (size_t i = 0; i < 3; i++)
        c->axis[i] = gp_rd_value(&r, json_array_get(axis, i), "/orientation/axis", -GP_RD_ANY,
                                 GP_RD_ANY);
    c->anisotropy = gp_rd_num(&r, ori, "/orientation/anisotropy", -GP_RD_ANY, GP_RD_ANY);
    c->solid_fraction = gp_rd_num(&r, full, "/solid_fraction", -GP_RD_ANY, GP_RD_ANY);
    const json_t *clump = gp_rd_member(&r, full, "/clump", JSON_OBJECT, 0);
    c->spheres_max = (int)gp_rd_num(&r, clump, "/clump/spheres_max", 0, GP_RD_INT);
    c->min_radius_ratio = gp_rd_num(&r, clump, "/clump/min_radius_ratio", -GP_RD_ANY, GP_RD_ANY);
    const json_t *imc = gp_rd_member(&r, full, "/imc", JSON_OBJECT, 0);
    c->imc_threshold = gp_rd_num(&r, imc, "/imc/threshold", -GP_RD_ANY, GP_RD_ANY);
    c->imc_max_steps = (long)gp_rd_num(&r, imc, "/imc/max_steps", 0, GP_RD_COUNT);
    c->mesh_level = (unsigned)gp_rd_num(&r, full, "/mesh_level", 0, GP_MESH3D_ICOSPHERE_LEVEL_MAX);
    c->outputs = gp_rd_flags(&r, full, "/outputs", gp_spec_fv3d_outputs, 4);
    c->threads = 1;
    const json_t *cont = gp_rd_member(&r, full, "/container", JSON_OBJECT, 0);
    const json_t *shape = gp_rd_member(&r, full, "/shape", JSON_OBJECT, 0);
    if (rc || read_container(&r, cont, out) || read_shape(&r, shape, out))
        return gp_spec_no_memory(p);
    return gp_rd_finish(&r, p);
}

/* ------------------------------------------------------------------------------------------ */
/* making what the core reads: the container and its volume, the spectrum, the law, the count */

/* the core's container of the spec's */
static void container_of(gp_spec_fv3d *s)
{
    if (s->container == GP_SPEC_FV3D_BOX) {
        const double lo[3] = {0, 0, 0};
        s->core.container = gp_voronoi3d_box(lo, s->box);
    } else if (s->container == GP_SPEC_FV3D_CYLINDER) {
        s->core.container = gp_voronoi3d_cylinder(0, 0, s->radius, 0, s->height,
                                                  GP_SPEC_FV3D_CYLINDER_FACETS);
    } else {
        s->core.container = gp_voronoi3d_convex(s->planes, s->nplanes);
    }
}

/* The container's volume and bounding box: a box's and the cylinder's prism's by their
 * formulas, a polyhedron's measured (GP_ERR_INVALID when it is empty, flat or unbounded). */
static gp_status measure(gp_spec_fv3d *s, gp_error *err)
{
    container_of(s);
    if (s->container == GP_SPEC_FV3D_BOX) {
        s->volume = s->box[0] * s->box[1] * s->box[2];
        for (int k = 0; k < 3; k++) s->lo[k] = 0, s->hi[k] = s->box[k];
        return GP_OK;
    }
    if (s->container == GP_SPEC_FV3D_CYLINDER) {
        double m = GP_SPEC_FV3D_CYLINDER_FACETS;
        s->volume = m / 2 * s->radius * s->radius * sin(2 * M_PI / m) * s->height;
        s->lo[0] = s->lo[1] = -s->radius;
        s->hi[0] = s->hi[1] = s->radius;
        s->lo[2] = 0;
        s->hi[2] = s->height;
        return GP_OK;
    }
    return gp_voronoi3d_container_measure(&s->core.container, &s->volume, s->lo, s->hi, err);
}

/* the amplitudes D[0 .. n) with D0 = 1, and the bound of the star shape */
static gp_status spectrum_of(gp_spec_fv3d *s, gp_error *err)
{
    if (s->shape_form == 0) {
        free(s->spectrum);
        s->nspectrum = GP_SPEC_FV3D_MODES;
        if (!(s->spectrum = malloc(s->nspectrum * sizeof *s->spectrum)))
            return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        gp_status st = gp_fourier_spectrum(s->D2, s->D3, s->D8, s->alpha, s->beta, s->nspectrum,
                                           s->spectrum, err);
        if (st != GP_OK) return st;
    } else {
        double d0 = s->spectrum[0];
        for (size_t n = 0; n < s->nspectrum; n++) s->spectrum[n] /= d0;
        s->spectrum[0] = 1;
    }
    s->star_bound = 0;
    for (size_t n = 1; n < s->nspectrum; n++)
        s->star_bound += s->spectrum[n] * sqrt((2.0 * n + 1) / 2);
    s->core.D = s->spectrum;
    s->core.nmodes = s->nspectrum;
    return GP_OK;
}

/* the law of the core: a parametric law of mean 1 (its shape), or the sieve on volumes */
static gp_status law_of(gp_spec_fv3d *s, gp_error *err)
{
    gp_law_destroy(s->law);
    if (s->law_kind == GP_LAW_SIEVE)
        s->law = gp_law_create_sieve3d(s->sieve_d, s->sieve_pass, s->nsieve, err);
    else
        s->law = gp_law_create((gp_law_kind)s->law_kind, 1.0, s->cov, err);
    if (!s->law) return err ? err->code : GP_ERR_NOMEM;
    s->core.law = s->law;
    s->core.law_of_grains = s->of_grains || s->law_kind == GP_LAW_SIEVE;
    return GP_OK;
}

/* a sieve's count: round(solid_fraction x container volume / the law's mean volume), as a
 * double (it may be far beyond what a size_t of grains means) */
static double sieve_count(const gp_spec_fv3d *s)
{
    return floor(s->core.solid_fraction * s->volume / gp_law_mean(s->law) + 0.5);
}

/* The container, the spectrum, the law and (sieve) the count. GP_OK, or the failure with err. */
static gp_status prepare(gp_spec_fv3d *s, gp_error *err)
{
    gp_status st = measure(s, err);
    if (st == GP_OK) st = spectrum_of(s, err);
    if (st == GP_OK) st = law_of(s, err);
    if (st == GP_OK && s->law_kind == GP_LAW_SIEVE) {
        double n = sieve_count(s);
        s->particles_derived = 1;
        s->core.particles = n >= 1 && n <= 1e15 ? (size_t)n : 0;
    }
    return st;
}

int gp_spec_fv3d_read(const json_t *full, gp_spec_fv3d *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    p = gp_spec_begin(p, &local);
    gp_error err;
    memset(&err, 0, sizeof err);
    if (read_raw(full, out, p)) return -1;
    if (prepare(out, &err) != GP_OK)
        return err.code == GP_ERR_NOMEM ? gp_spec_no_memory(p)
                                        : gp_problem(p, "internal", "", "%s", err.message);
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* the semantic checks */

/* a polyhedron: no zero normal; bounded, with a volume, filling enough of its box */
static int check_container(gp_spec_fv3d *s, gp_spec_problem *p)
{
    static const char *hs = "/container/polyhedron/halfspaces";
    char ptr[80];
    for (size_t i = 0; s->container == GP_SPEC_FV3D_POLYHEDRON && i < s->nplanes; i++) {
        const double *q = s->planes + 4 * i;
        if (q[0] != 0 || q[1] != 0 || q[2] != 0) continue;
        snprintf(ptr, sizeof ptr, "%s/%zu", hs, i);
        return gp_problem(p, "invalid_spec", ptr, "the normal [%g, %g, %g] is zero: expected a "
                          "half-space n . x <= d with n not zero", q[0], q[1], q[2]);
    }
    gp_error err;
    memset(&err, 0, sizeof err);
    gp_status st = measure(s, &err);
    if (st == GP_ERR_NOMEM) return gp_spec_no_memory(p);
    if (st != GP_OK || !(s->volume > 0) || !isfinite(s->volume))
        return gp_problem(p, "invalid_spec", hs, "the half-spaces do not bound a convex "
                          "polyhedron with a volume (%s): expected rows [nx, ny, nz, d], n . x "
                          "<= d inside, that enclose a bounded, non-empty region",
                          st != GP_OK ? err.message : "its volume is 0");
    if (s->container != GP_SPEC_FV3D_POLYHEDRON) return 0;
    double boxv = 1;
    for (int k = 0; k < 3; k++) boxv *= s->hi[k] - s->lo[k];
    double fill = s->volume / boxv;
    if (fill >= GP_SPEC_FV3D_FILL_MIN) return 0;
    return gp_problem(p, "invalid_spec", hs, "the polyhedron fills %.3g of its bounding box, "
                      "less than %g: its seeds are placed by rejection in that box, and a sliver "
                      "this thin cannot hold a specimen", fill, GP_SPEC_FV3D_FILL_MIN);
}

static int check_axis_spectrum(const gp_spec_fv3d *s, gp_spec_problem *p)
{
    const double *a = s->core.axis;
    if (!(a[0] != 0 || a[1] != 0 || a[2] != 0))
        return gp_problem(p, "invalid_spec", "/orientation/axis", "the axis [%g, %g, %g] is "
                          "zero: expected a direction", a[0], a[1], a[2]);
    if (s->shape_form == 1 && s->nspectrum > GP_SPEC_FV3D_MODES)
        return gp_problem(p, "invalid_spec", "/shape/spectrum", "%zu amplitudes are too many: "
                          "at most %d (degrees 0 to %d, the most a grain's radius field has)",
                          s->nspectrum, GP_SPEC_FV3D_MODES, GP_GRAIN3D_DEGREE_MAX);
    return 0;
}

/* the schema's particles maximum: the bound of a derived count too */
static double max_particles(void)
{
    const json_t *props =
        json_object_get(gp_spec_schema(&gp_spec_kind_fourier_voronoi_3d), "properties");
    double m = 1e6;
    gp_schema_number(json_object_get(props, "particles"), "maximum", &m);
    return m;
}

/* a sieve: its largest grain's cell fits in the container, at least one grain, at most
 * particles' maximum */
static int check_sieve_count(const gp_spec_fv3d *s, gp_spec_problem *p)
{
    if (s->law_kind != GP_LAW_SIEVE) return 0;
    double dmax = s->sieve_d[s->nsieve - 1];
    double cell = M_PI / 6 * dmax * dmax * dmax / s->core.solid_fraction;
    char ptr[64];
    snprintf(ptr, sizeof ptr, "/size/sieve/%zu/0", s->nsieve - 1);
    if (cell > s->volume)
        return gp_problem(p, "invalid_spec", ptr, "a grain of the largest sieve diameter (%.6g "
                          "m) needs a cell of %.6g m³ at solid_fraction %g, more than the "
                          "container's volume %.6g m³; check sieve_units", dmax, cell,
                          s->core.solid_fraction, s->volume);
    double n = sieve_count(s);
    if (n < 1)
        return gp_problem(p, "invalid_spec", "/size/sieve", "the container (%.6g m³) holds no "
                          "grain of this sieve curve at solid_fraction %g (mean grain %.6g m³); "
                          "check sieve_units", s->volume, s->core.solid_fraction,
                          gp_law_mean(s->law));
    if (n <= max_particles()) return 0;
    return gp_spec_too_large(p, "/size/sieve", "this sieve curve makes about %.3g grains in the "
                             "container (volume %.6g m³, solid_fraction %g), over the limit of "
                             "%.0f (the most particles allows); check sieve_units or use a "
                             "smaller container", n, s->volume, s->core.solid_fraction,
                             max_particles());
}

/* The field whose amplitudes weigh most in the star bound: D2, D3 (modes 3 to 7, alpha) or D8
 * (modes 8 and up, beta); the spectrum itself for that form. */
static const char *star_field(const gp_spec_fv3d *s)
{
    if (s->shape_form == 1) return "/shape/spectrum";
    double part[3] = {0, 0, 0};
    for (size_t n = 2; n < s->nspectrum; n++)
        part[n == 2 ? 0 : n < 8 ? 1 : 2] += s->spectrum[n] * sqrt((2.0 * n + 1) / 2);
    static const char *const names[3] = {"/shape/D2", "/shape/D3", "/shape/D8"};
    int k = part[1] > part[0] ? 1 : 0;
    if (part[2] > part[k]) k = 2;
    return names[k];
}

/* Star shape: when the bound is below 1 every grain drawn is star-shaped (gp_grain3d.h). Else
 * (or with a spread, whose draws go beyond the mean amplitudes) GP_SPEC_FV3D_STAR_DRAWS grains
 * are drawn from the shape's law and checked exactly; the run draws a grain up to 100 times
 * before it fails the job, so a shape whose draws are star-shaped less than
 * GP_SPEC_FV3D_STAR_MIN times in GP_SPEC_FV3D_STAR_DRAWS is refused (the job would likely fail,
 * and its grains would be the few smooth draws of the law). */
static int check_star(const gp_spec_fv3d *s, gp_spec_problem *p)
{
    if (s->star_bound < 1 && s->core.spread == 0) return 0;
    unsigned degree = (unsigned)(s->nspectrum - 1);
    double cov[GP_SPEC_FV3D_MODES];
    for (size_t n = 0; n < s->nspectrum; n++) cov[n] = s->core.spread;
    gp_grain3d_law law = {s->spectrum, s->core.spread > 0 ? cov : NULL, s->nspectrum, degree,
                          1.0, 1.0};
    gp_error err;
    memset(&err, 0, sizeof err);
    gp_grain3d_basis *b = gp_grain3d_basis_create(STAR_LEVEL, degree, &err);
    gp_rng *r = b ? gp_rng_create(0, STAR_STREAM, &err) : NULL;
    gp_grain3d_shape *shape = r ? malloc(sizeof *shape) : NULL;
    int star = 0, drawn = 0, failed = !shape;
    for (; !failed && drawn < GP_SPEC_FV3D_STAR_DRAWS; drawn++) {
        if (gp_grain3d_draw(&law, u01, r, shape, &err) != GP_OK) {
            failed = 1;
            break;
        }
        gp_status st = gp_grain3d_star_check(b, shape, NULL, &err);
        if (st == GP_OK) star++;
        else if (st != GP_ERR_NOT_STAR) failed = 1;
        if (star >= GP_SPEC_FV3D_STAR_MIN) break;
    }
    free(shape);
    gp_rng_destroy(r);
    gp_grain3d_basis_destroy(b);
    if (failed)
        return err.code == GP_ERR_NOMEM ? gp_spec_no_memory(p)
                                        : gp_problem(p, "internal", "/shape", "%s", err.message);
    if (star >= GP_SPEC_FV3D_STAR_MIN) return 0;
    const char *field = s->star_bound < 1 ? "/shape/spread" : star_field(s);
    return gp_problem(p, "invalid_spec", field, "only %d of %d grains drawn from this shape are "
                      "star-shaped (r > 0 in every direction); a grain is drawn at most 100 "
                      "times, so at least %d of %d are needed: lower the amplitudes%s (the bound "
                      "sum of D_n sqrt((2n + 1) / 2) over n >= 1 is %.3g; below 1 every draw is "
                      "star-shaped)", star, drawn, GP_SPEC_FV3D_STAR_MIN, GP_SPEC_FV3D_STAR_DRAWS,
                      s->core.spread > 0 ? " or the spread" : "", s->star_bound);
}

/* ------------------------------------------------------------------------------------------ */
/* work, memory and result bounds (gp_spec.h) */

/* Costs per unit on one core, from bench/bench_imc3d and bench_fv3d and the kind's own timing
 * of a job (docs/api.md "Limits"); estimates within a factor of a few, which is all a budget
 * needs. */
#define COST_CELL_S 15e-6        /* a Voronoi cell (the first tessellation: 70k cells/s) ... */
#define COST_CELL_PLANE_S 0.1e-6 /* ... and each of a polyhedron's half-spaces it is cut by */
#define CELLS_A_MOVE 20.0        /* cells an IMC move recomputes */
#define COST_IMC_DECADE 0.2      /* 20 % more a move per tenfold more cells (2,203 against
                                  * 3,232 moves/s at 100,000 and 1,000) */
/* a grain at level 4 (2,562 directions, degree 30): its radii, star check, fill and mass;
 * its descriptors (hull and three projections); its clump of 30 spheres (~8 ms) */
#define COST_GRAIN_S 6e-3
#define COST_DESC_S 3e-3
#define COST_CLUMP_S 8e-3
#define COST_SPHERE_S 0.25e-3    /* each sphere of a clump beyond 30 */
#define COST_POLY_PLANES_S 2e-9  /* the IMC's box of a polyhedron: m^4 plane tests */

/* the result's text (reals at 17 digits): a radius, a grain's own members, its descriptors; a
 * cell's members and each of its vertices and faces; a clump's members and a sphere; the
 * icosphere a direction; the head */
#define BYTES_RADIUS 20.0
#define BYTES_GRAIN 260.0
#define BYTES_DESC 700.0
#define BYTES_CELL 120.0
#define BYTES_CELL_VERTEX 60.0
#define BYTES_CELL_FACE 40.0
#define CELL_VERTICES 32.0
#define CELL_FACES 16.0
#define BYTES_CLUMP 100.0
#define BYTES_SPHERE 80.0
#define BYTES_DIRECTION 90.0
#define BYTES_HEAD 40000.0

/* directions of a grain's mesh at its level */
static double directions(unsigned level)
{
    return 10.0 * pow(4.0, level) + 2.0;
}

/* seconds of one cell's computation among n cells */
static double cell_cost(const gp_spec_fv3d *s, double n)
{
    double planes = s->container == GP_SPEC_FV3D_POLYHEDRON ? (double)s->nplanes : 0;
    return (COST_CELL_S + COST_CELL_PLANE_S * planes) *
           (1 + COST_IMC_DECADE * log10(fmax(n, 1000) / 1000));
}

/* seconds of one grain */
static double grain_cost(const gp_spec_fv3d *s)
{
    double scale = directions(s->core.mesh_level) / directions(GP_GRAIN3D_LEVEL_DEFAULT);
    double per = COST_GRAIN_S * scale;
    if (s->core.outputs & GP_OUT3_DESCRIPTORS) per += COST_DESC_S * scale;
    if (s->core.outputs & GP_OUT3_CLUMPS)
        per += COST_CLUMP_S + COST_SPHERE_S * fmax(0, s->core.spheres_max - 30);
    return per;
}

static void bounds_of(const gp_spec_fv3d *s, gp_spec_bounds_t *b)
{
    memset(b, 0, sizeof *b);
    double n = (double)s->core.particles, nv = directions(s->core.mesh_level);
    int sieve = s->law_kind == GP_LAW_SIEVE;
    unsigned o = s->core.outputs;
    b->cells = b->items = n;
    b->steps = (double)s->core.imc_max_steps;
    double cell = cell_cost(s, n);
    double m = s->container == GP_SPEC_FV3D_POLYHEDRON ? (double)s->nplanes : 0;
    double imc = n * cell + b->steps * CELLS_A_MOVE * cell + COST_POLY_PLANES_S * m * m * m * m;
    double grains = n * grain_cost(s);
    b->work_s = imc + grains;
    b->work_pointer = imc > grains ? "/imc/max_steps" : sieve ? "/size/sieve" : "/particles";
    double per = 0;
    if (o & (GP_OUT3_GRAINS | GP_OUT3_DESCRIPTORS)) per += BYTES_GRAIN;
    if (o & GP_OUT3_GRAINS) per += BYTES_RADIUS * nv;
    if (o & GP_OUT3_DESCRIPTORS) per += BYTES_DESC;
    if (o & GP_OUT3_CELLS)
        per += BYTES_CELL + BYTES_CELL_VERTEX * CELL_VERTICES + BYTES_CELL_FACE * CELL_FACES;
    if (o & GP_OUT3_CLUMPS) per += BYTES_CLUMP + BYTES_SPHERE * s->core.spheres_max;
    double head = BYTES_HEAD + ((o & GP_OUT3_GRAINS) ? BYTES_DIRECTION * nv : 0);
    b->result_bytes = head + n * per;
    b->result_pointer = sieve ? "/size/sieve" : "/particles";
}

static const gp_spec_advice g_work_advice[] = {
    {"/imc/max_steps", "ask for fewer imc.max_steps (the IMC stops at its threshold or stalls "
                       "long before)"},
    {NULL, "ask for fewer grains, a lower mesh_level, fewer clump spheres or fewer outputs"}};

static const gp_spec_advice g_result_advice[] = {
    {"/particles", "particles, a lower mesh_level or fewer outputs"},
    {NULL, "grains (a smaller container or a coarser sieve), a lower mesh_level or fewer "
           "outputs"}};

/* the memory of the build (gp_fv3d_estimate_bytes) and the work (too_large) */
static int check_budget(const gp_spec_fv3d *s, gp_spec_problem *p)
{
    double bytes = gp_fv3d_estimate_bytes(&s->core);
    const char *at = s->law_kind == GP_LAW_SIEVE ? "/size/sieve" : "/particles";
    if (bytes > GP_SPEC_FV3D_MEMORY_MAX)
        return gp_spec_too_large(p, s->core.mesh_level > GP_GRAIN3D_LEVEL_DEFAULT ? "/mesh_level"
                                                                                  : at,
                                 "the build would hold about %.3g GB (%zu grains of %.0f "
                                 "directions each), over the limit of %.0f GB; ask for fewer "
                                 "grains or a lower mesh_level", bytes / 1e9, s->core.particles,
                                 directions(s->core.mesh_level), GP_SPEC_FV3D_MEMORY_MAX / 1e9);
    gp_spec_bounds_t b;
    bounds_of(s, &b);
    char what[200];
    snprintf(what, sizeof what, "%.3g IMC moves at most (imc.max_steps) on %zu cells, then %zu "
             "grains of %.0f directions", b.steps, s->core.particles, s->core.particles,
             directions(s->core.mesh_level));
    return gp_spec_over_budget(&b, what, g_work_advice, p);
}

/* ------------------------------------------------------------------------------------------ */
/* the kind */

/* the checks of an effective spec, in the order of its dependencies */
static int check_fv3d(const json_t *full, gp_spec_problem *p)
{
    gp_spec_fv3d s;
    gp_error err;
    memset(&err, 0, sizeof err);
    int rc = read_raw(full, &s, p) || check_container(&s, p) ||
             gp_spec_fv_check_size(full, s.law_kind, s.cov, "volume", p) ||
             check_axis_spectrum(&s, p);
    if (!rc && (spectrum_of(&s, &err) != GP_OK || law_of(&s, &err) != GP_OK))
        rc = err.code == GP_ERR_NOMEM ? gp_spec_no_memory(p)
                                      : gp_problem(p, "invalid_spec", "/size", "%s", err.message);
    if (!rc && s.law_kind == GP_LAW_SIEVE) {
        rc = check_sieve_count(&s, p);
        s.core.particles = rc ? 0 : (size_t)sieve_count(&s);
    }
    if (!rc) rc = check_star(&s, p) || check_budget(&s, p);
    gp_spec_fv3d_free(&s);
    return rc ? -1 : 0;
}

static int spec_bounds_fv3d(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    gp_spec_fv3d s;
    int rc = gp_spec_fv3d_read(full, &s, p);
    if (rc == 0) bounds_of(&s, b);
    gp_spec_fv3d_free(&s);
    return rc;
}

const gp_spec_kind gp_spec_kind_fourier_voronoi_3d = {
    .name = "fourier-voronoi-3d",
    .schema_text = gp_schema_text_fourier_voronoi_3d,
    .explain = explain_fv3d,
    .check_posted = check_posted_fv3d,
    .settle_defaults = settle_defaults_fv3d,
    .check = check_fv3d,
    .bounds = spec_bounds_fv3d,
    .items = "grains",
    .result_advice = g_result_advice,
};
