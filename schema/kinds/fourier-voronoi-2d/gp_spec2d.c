/* gp_spec2d.c -- the kind "fourier-voronoi-2d": the field rules that the schema cannot express
 * (on the spec as posted), the defaults that depend on other fields, the reader of an effective
 * spec into gp_spec2d, its semantic checks (the container's rings through gp_rings, the size
 * law, the spectrum, the shape's descriptors and outlines, the cell count, seeding, the IMC
 * threshold, the work budget) and its work and result bounds. See gp_spec.h. */
#include "gp_spec_internal.h"

#include "gp_spec_fv.h"
#include "gp_imc.h"
#include "gp_outline.h"
#include "gp_rings.h"
#include "gp_shapemap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gp_spec_kind gp_spec_kind_fourier_voronoi_2d; /* this kind, defined at the end */

extern const unsigned char gp_schema_text_fourier_voronoi_2d[];

/* the names of the enums, at the index of their value */
static const char *const g_errors[] = {"E1", "E2", "E3", "AD"}; /* gp_imc_error_kind - 1 */
static const char *const g_inits[] = {"uniform", "halton"};     /* gp_init_kind */
static const char *const g_outputs[] = {"grains", "odec", "descriptors", "cells"}; /* GP_OUT2_ */
/* shape.descriptors' names, in the order of gp_descriptors and GP_SHAPEMAP_BIT */
static const char *const g_descriptors[] = {"elongation", "roundness", "circularity",
                                            "regularity"};

/* shape.outlines: vertices in all at most. Why a total: the schema bounds each outline (10,000
 * points) and their number (10,000), but not the product; the submit check (star shape, by
 * index) and the run's analysis are linear in the vertices (~0.1 s per million to check), the
 * stored spec is ~20 bytes a vertex, and a million vertices -- 10,000 outlines of 100 points,
 * or 1,000 traced at 1,000 -- is more than a mean spectrum and its spread need. */
#define OUTLINE_VERTICES_MAX 2000000

/* ------------------------------------------------------------------------------------------ */
/* the spec as posted, and the defaults that depend on other fields */

/* shape.descriptors names at least one (the schema's minProperties, which its engine leaves
 * to this check for a clearer message) */
static int check_shape_posted(const json_t *spec, gp_spec_problem *p)
{
    const json_t *d = json_object_get(json_object_get(spec, "shape"), "descriptors");
    if (!d || json_object_size(d) > 0) return 0;
    return gp_problem(p, "invalid_spec", "/shape/descriptors", "give at least one of "
                      "elongation, roundness, circularity, regularity");
}

static int check_posted_2d(const json_t *spec, gp_spec_problem *p)
{
    if (gp_spec_fv_check_size_posted(spec, "the container area", p)) return -1;
    return check_shape_posted(spec, p) ? -1 : 0;
}

/* The shape's forms, by the fields that make them; spread goes with any. */
static int shape_form_of(const char *key)
{
    static const char *const forms[][5] = {{"D2", "D3", "D8", "alpha", "beta"}, {"spectrum"},
                                           {"descriptors"}, {"outlines"}};
    for (int f = 0; f < 4; f++)
        for (int k = 0; k < 5 && forms[f][k]; k++)
            if (!strcmp(key, forms[f][k])) return f;
    return -1;
}

/* explain: a shape that mixes two forms fits no branch of the schema's oneOf, which can only
 * say "/shape: expected <every form>"; name the field that starts the second form instead */
static int explain_2d(const json_t *spec, gp_spec_problem *p)
{
    const json_t *shape = json_object_get(spec, "shape");
    if (strcmp(p->pointer, "/shape") != 0 || !json_is_object(shape)) return 0;
    const char *first = NULL, *key;
    int form = -1;
    const json_t *v;
    json_object_foreach((json_t *)shape, key, v) {
        int f = shape_form_of(key);
        if (f < 0) continue;
        if (form < 0) {
            form = f;
            first = key;
        } else if (f != form) {
            char ptr[96];
            snprintf(ptr, sizeof ptr, "/shape/%s", key);
            gp_problem(p, "invalid_spec", ptr, "cannot be combined with \"%s\": give the shape "
                       "one way -- D2, D3, D8 (with alpha, beta), spectrum, descriptors or "
                       "outlines -- each with an optional spread", first);
            return 1;
        }
    }
    return 0;
}

/* a sieve law has no particles (derived) and no cov, and is a law of the grains; sieve_units
 * belongs to a sieve; the threshold follows imc.error. 0, or -1 out of memory */
static int settle_defaults_2d(json_t *full)
{
    gp_spec_reader r = {0};
    const json_t *imc = json_object_get(full, "imc");
    return gp_spec_fv_settle(full, gp_rd_enum(&r, imc, "/imc/error", g_errors, 4) + 1);
}

/* ------------------------------------------------------------------------------------------ */
/* the reader (an effective spec: nothing is checked but its form) */

void gp_spec2d_free(gp_spec2d *s)
{
    if (!s) return;
    free(s->outer.pts);
    for (size_t i = 0; i < s->nholes; i++) free(s->holes[i].pts);
    free(s->holes);
    free((double *)s->spectrum);
    free((double *)s->sieve_d);
    free((double *)s->sieve_pass);
    for (size_t i = 0; s->outlines && i < s->noutlines; i++) free(s->outlines[i].pts);
    free((gp_ring *)s->outlines);
    memset(s, 0, sizeof *s);
}

/* a ring of at least 3 points at ptr, dropping repeated consecutive points and a closing point
 * equal to the first; -1 out of memory */
static int read_ring(gp_spec_reader *r, const json_t *arr, const char *ptr, gp_ring *ring)
{
    if (!json_is_array(arr) || json_array_size(arr) < 3) gp_rd_bad(r, ptr);
    size_t n = json_array_size(arr);
    ring->pts = malloc((n ? n : 1) * sizeof *ring->pts);
    ring->n = 0;
    if (!ring->pts) return -1;
    for (size_t i = 0; i < n; i++) {
        double q[2];
        gp_rd_pair(r, json_array_get(arr, i), ptr, q);
        gp_vec2 v = {q[0], q[1]};
        if (ring->n && ring->pts[ring->n - 1].x == v.x && ring->pts[ring->n - 1].y == v.y) continue;
        ring->pts[ring->n++] = v;
    }
    while (ring->n > 1 && ring->pts[ring->n - 1].x == ring->pts[0].x &&
           ring->pts[ring->n - 1].y == ring->pts[0].y)
        ring->n--;
    return 0;
}

/* a circle, or a polygon with its holes; -1 out of memory */
static int read_container_2d(gp_spec_reader *r, const json_t *cont, gp_spec2d *out)
{
    const json_t *circle = gp_rd_member(r, cont, "/container/circle", JSON_OBJECT, 1);
    if (circle) {
        double c[2];
        out->container = GP_CONTAINER_CIRCLE;
        gp_rd_pair(r, gp_rd_member(r, circle, "/container/circle/center", JSON_ARRAY, 0),
                   "/container/circle/center", c);
        out->circle_center = (gp_vec2){c[0], c[1]};
        out->circle_radius =
            gp_rd_num(r, circle, "/container/circle/radius", -GP_RD_ANY, GP_RD_ANY);
        return 0;
    }
    out->container = GP_CONTAINER_POLYGON;
    const json_t *holes = gp_rd_array(r, cont, "/container/holes", 0, SIZE_MAX, 1);
    size_t nh = json_array_size(holes);
    if (read_ring(r, json_object_get(cont, "polygon"), "/container/polygon", &out->outer))
        return -1;
    if (!nh) return 0;
    out->holes = calloc(nh, sizeof *out->holes);
    if (!out->holes) return -1;
    out->nholes = nh;
    for (size_t i = 0; i < nh; i++)
        if (read_ring(r, json_array_get(holes, i), "/container/holes", &out->holes[i])) return -1;
    return 0;
}

/* the law, and its cov or its sieve (in metres); -1 out of memory */
static int read_size_2d(gp_spec_reader *r, const json_t *size, gp_spec2d *out)
{
    gp_spec_fv_size z;
    int rc = gp_spec_fv_read_size(r, size, &z);
    out->size_law = (gp_law_kind)z.law;
    out->size_of_grains = z.of_grains;
    out->cov = z.cov;
    out->sieve_d = z.sieve_d;
    out->sieve_pass = z.sieve_pass;
    out->nsieve = z.nsieve;
    return rc;
}

/* shape.descriptors: the given ones and their values */
static void read_descriptors_2d(gp_spec_reader *r, const json_t *d, gp_spec2d *out)
{
    static const char *const ptrs[4] = {"/shape/descriptors/elongation",
                                        "/shape/descriptors/roundness",
                                        "/shape/descriptors/circularity",
                                        "/shape/descriptors/regularity"};
    out->shape_form = GP_SHAPE_FORM_DESCRIPTORS;
    for (int k = 0; k < 4; k++) {
        const json_t *v = gp_rd_member(r, d, ptrs[k], JSON_REAL, 1);
        if (!v) continue;
        out->desc_given |= GP_SHAPEMAP_BIT(k);
        out->desc_target[k] = gp_rd_value(r, v, ptrs[k], -GP_RD_ANY, GP_RD_ANY);
    }
}

/* shape.outlines, each as given (gp_outline cleans them and says what it dropped); -1 out of
 * memory */
static int read_outlines_2d(gp_spec_reader *r, const json_t *arr, gp_spec2d *out)
{
    size_t n = json_array_size(arr);
    gp_ring *rings = calloc(n ? n : 1, sizeof *rings);
    if (!rings) return -1;
    out->shape_form = GP_SHAPE_FORM_OUTLINES;
    out->outlines = rings;
    out->noutlines = n;
    for (size_t i = 0; i < n; i++) {
        const json_t *o = json_array_get(arr, i);
        size_t m = json_array_size(o);
        if (!json_is_array(o) || m < 3) gp_rd_bad(r, "/shape/outlines");
        rings[i].pts = malloc((m ? m : 1) * sizeof *rings[i].pts);
        if (!rings[i].pts) return -1;
        rings[i].n = m;
        for (size_t k = 0; k < m; k++) {
            double q[2];
            gp_rd_pair(r, json_array_get(o, k), "/shape/outlines", q);
            rings[i].pts[k] = (gp_vec2){q[0], q[1]};
        }
    }
    return 0;
}

/* the descriptors, or a spectrum (D2, D3, D8 then taken from it), or target descriptors, or
 * outlines; and the spread of any; -1 out of memory */
static int read_shape_2d(gp_spec_reader *r, const json_t *shape, gp_spec2d *out)
{
    const json_t *spread = gp_rd_member(r, shape, "/shape/spread", JSON_REAL, 1);
    if (spread) {
        out->spread = gp_rd_value(r, spread, "/shape/spread", 0, GP_SHAPE_SPREAD_MAX);
        out->spread_given = 1;
    }
    const json_t *desc = gp_rd_member(r, shape, "/shape/descriptors", JSON_OBJECT, 1);
    const json_t *outl = gp_rd_array(r, shape, "/shape/outlines", 1, SIZE_MAX, 1);
    if (desc) {
        read_descriptors_2d(r, desc, out);
        return 0;
    }
    if (outl) return read_outlines_2d(r, outl, out);
    double *const num[5] = {&out->D2, &out->D3, &out->D8, &out->alpha, &out->beta};
    double *d = NULL;
    size_t n = 0;
    int form = gp_spec_fv_read_shape(r, shape, num, &d, &n);
    if (form <= 0) return form;
    out->has_spectrum = 1;
    out->shape_form = GP_SHAPE_FORM_SPECTRUM;
    out->spectrum = d;
    out->nspectrum = n;
    /* D2, D3, D8 are still meaningful for reporting: take them from the spectrum */
    out->D2 = n > 2 ? d[2] / d[0] : 0;
    out->D3 = n > 3 ? d[3] / d[0] : 0;
    out->D8 = n > 8 ? d[8] / d[0] : 0;
    out->alpha = out->beta = -2;
    return 0;
}

static void read_imc_2d(gp_spec_reader *r, const json_t *imc, gp_spec2d *out)
{
    out->imc_error = (gp_imc_error_kind)(gp_rd_enum(r, imc, "/imc/error", g_errors, 4) + 1);
    out->imc_threshold = gp_rd_num(r, imc, "/imc/threshold", -GP_RD_ANY, GP_RD_ANY);
    const json_t *ms = gp_rd_member(r, imc, "/imc/max_steps", JSON_REAL, 1);
    out->imc_max_steps = ms ? (long)gp_rd_value(r, ms, "/imc/max_steps", 0, GP_RD_COUNT) : 0;
    out->imc_max_steps_default = !ms; /* resolved from the cell count (default_steps_2d) */
    out->imc_init = (gp_init_kind)gp_rd_enum(r, imc, "/imc/init", g_inits, 2);
    const json_t *cl = gp_rd_member(r, imc, "/imc/classes", JSON_REAL, 1);
    out->imc_classes = cl ? (int)gp_rd_value(r, cl, "/imc/classes", 0, GP_RD_INT) : 0;
}

static long default_steps_2d(const gp_spec2d *s);

/* gp_spec.h. Also the first step of the checks and the bounds (on an effective spec in the
 * making). */
int gp_spec2d_read(const json_t *full, gp_spec2d *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    p = gp_spec_begin(p, &local);
    if (gp_spec_read_begin(&gp_spec_kind_fourier_voronoi_2d, full, out, sizeof *out, p)) return -1;
    gp_spec_reader r = {0};
    const json_t *size = gp_rd_member(&r, full, "/size", JSON_OBJECT, 0);
    const json_t *ori = gp_rd_member(&r, full, "/orientation", JSON_OBJECT, 0);
    int rc = read_size_2d(&r, size, out);
    out->seed = (uint64_t)gp_rd_num(&r, full, "/seed", 0, GP_RD_COUNT);
    if (out->size_law != GP_LAW_SIEVE)
        out->particles = (size_t)gp_rd_num(&r, full, "/particles", 0, GP_RD_COUNT);
    out->mean_deg = gp_rd_num(&r, ori, "/orientation/mean_deg", -GP_RD_ANY, GP_RD_ANY);
    out->anisotropy = gp_rd_num(&r, ori, "/orientation/anisotropy", -GP_RD_ANY, GP_RD_ANY);
    out->contour_points = (size_t)gp_rd_num(&r, full, "/contour_points", 0, GP_RD_COUNT);
    out->solid_fraction = gp_rd_num(&r, full, "/solid_fraction", -GP_RD_ANY, GP_RD_ANY);
    read_imc_2d(&r, gp_rd_member(&r, full, "/imc", JSON_OBJECT, 0), out);
    out->outputs = gp_rd_flags(&r, full, "/outputs", g_outputs, 4);
    out->threads = 0;
    const json_t *cont = gp_rd_member(&r, full, "/container", JSON_OBJECT, 0);
    const json_t *shape = gp_rd_member(&r, full, "/shape", JSON_OBJECT, 0);
    if (rc || read_container_2d(&r, cont, out) || read_shape_2d(&r, shape, out))
        rc = gp_spec_no_memory(p);
    else
        rc = gp_rd_finish(&r, p);
    if (rc) gp_spec2d_free(out);
    else if (out->imc_max_steps_default) out->imc_max_steps = default_steps_2d(out);
    return rc;
}

/* ------------------------------------------------------------------------------------------ */
/* the container */

static void ring_pointer(char *buf, size_t n, size_t ring)
{
    if (ring == 0) snprintf(buf, n, "/container/polygon");
    else snprintf(buf, n, "/container/holes/%zu", ring - 1);
}

/* the fault gp_rings_check found, at its ring's pointer; -1 */
static int ring_problem(const gp_rings_fault *f, gp_spec_problem *p)
{
    char ptr[64], other[64];
    int two = f->kind == GP_RINGS_CROSS && f->ring2 != f->ring; /* two rings meet */
    ring_pointer(ptr, sizeof ptr, two ? f->ring2 : f->ring);
    ring_pointer(other, sizeof other, f->ring);
    const char *code = "invalid_spec";
    switch (f->kind) {
    case GP_RINGS_DEGENERATE:
        return gp_problem(p, code, ptr, "the polygon has no area (its points are collinear or "
                          "repeated)");
    case GP_RINGS_FOLD:
        return gp_problem(p, code, ptr, "the polygon is not simple: edges %zu and %zu fold back "
                          "onto each other", f->edge, f->edge2);
    case GP_RINGS_CROSS:
        if (two)
            return gp_problem(p, code, ptr, "edge %zu of this hole crosses or touches edge %zu "
                              "of %s", f->edge2, f->edge, other);
        return gp_problem(p, code, ptr, "the polygon is not simple: edge %zu (from point %zu) "
                          "crosses or touches edge %zu (from point %zu)", f->edge, f->edge,
                          f->edge2, f->edge2);
    case GP_RINGS_NO_AREA: return gp_problem(p, code, ptr, "the polygon has no area");
    case GP_RINGS_HOLE_OUTSIDE:
        return gp_problem(p, code, ptr, "the hole is not inside the container polygon");
    case GP_RINGS_HOLE_IN_HOLE:
        return gp_problem(p, code, ptr, "the hole lies inside hole %zu", f->ring2 - 1);
    default: return gp_problem(p, "internal", ptr, "the rings check failed");
    }
}

/* the polygon's rings: simple, with an area, holes inside it and apart (gp_rings.h) */
static int check_rings_2d(const gp_spec2d *s, gp_spec_problem *p)
{
    size_t nr = s->nholes + 1;
    gp_ring_ref *refs = malloc(nr * sizeof *refs);
    if (!refs) return gp_spec_no_memory(p);
    refs[0] = (gp_ring_ref){s->outer.pts, s->outer.n};
    for (size_t h = 0; h < s->nholes; h++)
        refs[h + 1] = (gp_ring_ref){s->holes[h].pts, s->holes[h].n};
    gp_rings_fault f;
    gp_status st = gp_rings_check(refs, nr, &f, NULL);
    free(refs);
    if (st == GP_OK) return 0;
    return st == GP_ERR_INVALID ? ring_problem(&f, p) : gp_spec_no_memory(p);
}

/* a circle's radius against its centre's coordinates; with rings set, a polygon's rings */
static int check_container_2d(const gp_spec2d *s, int rings, gp_spec_problem *p)
{
    if (s->container == GP_CONTAINER_POLYGON) return rings ? check_rings_2d(s, p) : 0;
    double m = fmax(fabs(s->circle_center.x), fabs(s->circle_center.y));
    if (s->circle_radius > 1e-12 * m) return 0;
    return gp_problem(p, "invalid_spec", "/container/circle/radius",
                      "the radius is too small next to the centre's coordinates");
}

/* ------------------------------------------------------------------------------------------ */
/* the size law, the shape, the cell count */

static int check_spectrum_2d(const gp_spec2d *s, gp_spec_problem *p)
{
    size_t most = s->contour_points / 2;
    if (!s->has_spectrum || s->nspectrum <= most) return 0;
    return gp_problem(p, "invalid_spec", "/shape/spectrum", "%zu amplitudes are too many for "
                      "contour_points = %zu (at most %zu)", s->nspectrum, s->contour_points, most);
}

/* invalid_spec at the first refused outline: its reason, and the indices of the others */
static int outline_problem(const gp_outline_set_result *res, gp_spec_problem *p)
{
    size_t i = res->refused[0];
    char ptr[64], more[160] = "";
    snprintf(ptr, sizeof ptr, "/shape/outlines/%zu", i);
    size_t len = 0;
    for (size_t k = 1; k < res->nrefused && k <= 8 && len < sizeof more; k++)
        len += (size_t)snprintf(more + len, sizeof more - len, "%s%zu", k > 1 ? ", " : "",
                                res->refused[k]);
    const char *msg = res->info[i].error.message;
    if (!strncmp(msg, "outline: ", 9)) msg += 9; /* the pointer already says what it is */
    if (res->nrefused == 1)
        return gp_problem(p, "invalid_spec", ptr, "%s", msg);
    return gp_problem(p, "invalid_spec", ptr, "%s; %zu more outline%s refused: %s%s", msg,
                      res->nrefused - 1, res->nrefused > 2 ? "s" : "", more,
                      res->nrefused > 9 ? ", ..." : "");
}

/* shape.descriptors: reachable by star-shaped Fourier grains (gp_shapemap_check, the table
 * only: about a millisecond), else invalid_spec at the first unreachable descriptor in the
 * paper's order of scales (elongation, circularity, roundness, regularity), with the nearest
 * reachable value of each in the message */
static int check_descriptors_2d(const gp_spec2d *s, gp_spec_problem *p)
{
    static const int order[4] = {GP_SHAPEMAP_ELONGATION, GP_SHAPEMAP_CIRCULARITY,
                                 GP_SHAPEMAP_ROUNDNESS, GP_SHAPEMAP_REGULARITY};
    gp_shapemap_target t;
    memset(&t, 0, sizeof t);
    t.given = s->desc_given;
    memcpy(t.value, s->desc_target, sizeof t.value);
    gp_shapemap_result r;
    gp_error e;
    gp_status st = gp_shapemap_check(&t, &r, &e);
    if (st == GP_OK) return 0;
    if (st == GP_ERR_NOMEM) return gp_spec_no_memory(p);
    char ptr[64] = "/shape/descriptors";
    for (int q = 0; st == GP_ERR_INFEASIBLE && q < 4; q++)
        if (r.missed & GP_SHAPEMAP_BIT(order[q])) {
            snprintf(ptr, sizeof ptr, "/shape/descriptors/%s", g_descriptors[order[q]]);
            break;
        }
    return gp_problem(p, "invalid_spec", ptr, "%s", e.message);
}

/* shape.outlines: at most OUTLINE_VERTICES_MAX vertices in all (too_large), then each one
 * analysable (gp_outline: cleaned, star-shaped from an interior point, winding once, with an
 * area), else invalid_spec at the first refused one, naming its reason and the others. The
 * refusal does not depend on the rays, so the check analyses at the fewest (16). */
static int check_outlines_2d(const gp_spec2d *s, gp_spec_problem *p)
{
    size_t total = 0;
    for (size_t i = 0; i < s->noutlines; i++) total += s->outlines[i].n;
    if (total > OUTLINE_VERTICES_MAX)
        return gp_spec_too_large(p, "/shape/outlines", "%zu outlines of %zu vertices in all, "
                                 "over the limit of %d; give fewer outlines or simplify them "
                                 "(a few hundred points each carry their spectrum)",
                                 s->noutlines, total, OUTLINE_VERTICES_MAX);
    gp_outline_points *pts = malloc((s->noutlines ? s->noutlines : 1) * sizeof *pts);
    if (!pts) return gp_spec_no_memory(p);
    for (size_t i = 0; i < s->noutlines; i++)
        pts[i] = (gp_outline_points){s->outlines[i].pts, s->outlines[i].n};
    gp_outline_params op;
    gp_outline_params_defaults(&op);
    op.np = 16;
    op.nmodes = 8;
    op.descriptors = 0;
    op.min_outlines = 1;
    gp_outline_set_result res;
    gp_error e;
    gp_status st = gp_outline_set_analyze(pts, s->noutlines, &op, NULL, &res, &e);
    free(pts);
    int rc = 0;
    if (st == GP_ERR_NOMEM) rc = gp_spec_no_memory(p);
    else if (res.nrefused > 0) rc = outline_problem(&res, p);
    else if (st != GP_OK) rc = gp_problem(p, "internal", "/shape/outlines", "%s", e.message);
    gp_outline_set_result_free(&res);
    return rc;
}

static int check_shape_2d(const gp_spec2d *s, gp_spec_problem *p)
{
    if (s->has_spectrum) return 0;
    if (s->shape_form == GP_SHAPE_FORM_DESCRIPTORS) return check_descriptors_2d(s, p);
    if (s->shape_form == GP_SHAPE_FORM_OUTLINES) return check_outlines_2d(s, p);
    return 0;
}

/* the schema's particles maximum: the bound of a derived cell count too */
static double max_particles(void)
{
    const json_t *props = json_object_get(gp_spec_schema(&gp_spec_kind_fourier_voronoi_2d), "properties");
    double m = 1e6;
    gp_schema_number(json_object_get(props, "particles"), "maximum", &m);
    return m;
}

/* too_large at /size/sieve: the count ("what") beyond the bound of particles; -1 */
static int too_many(const gp_spec2d *s, double area, gp_spec_problem *p, const char *what)
{
    return gp_spec_too_large(p, "/size/sieve", "%s in the container (area %.6g m², "
                             "solid_fraction %g), over the limit of %.0f (the most particles "
                             "allows); check sieve_units or use a smaller container", what, area,
                             s->solid_fraction, max_particles());
}

/* a sieve law: its largest grain's cell fits in the container, and the derived count is
 * within particles' bound (too_large) */
static int check_sieve_count(const gp_spec2d *s, double area, size_t n, gp_spec_problem *p)
{
    double dmax = s->sieve_d[s->nsieve - 1];
    double cell = M_PI / 4 * dmax * dmax / s->solid_fraction;
    if (cell > area) {
        char ptr[64];
        snprintf(ptr, sizeof ptr, "/size/sieve/%zu/0", s->nsieve - 1);
        return gp_problem(p, "invalid_spec", ptr, "a grain of the largest sieve diameter (%.6g "
                          "m) needs a cell of %.6g m² at solid_fraction %g, more than the "
                          "container's area %.6g m²; check sieve_units", dmax, cell,
                          s->solid_fraction, area);
    }
    if ((double)n <= max_particles()) return 0;
    char count[64];
    snprintf(count, sizeof count, "this sieve curve makes about %zu grains", n);
    return too_many(s, area, p, count);
}

/* the number of cells: particles, or derived from the container and a sieve law */
static int cell_count_2d(const gp_spec2d *s, size_t *n, gp_spec_problem *p)
{
    double area = 0;
    gp_error err;
    memset(&err, 0, sizeof err);
    if (gp_spec2d_cell_count(s, &area, n, &err) != GP_OK) {
        if (err.code == GP_ERR_NOMEM) return gp_spec_no_memory(p);
        int sieve = s->size_law == GP_LAW_SIEVE;
        /* the rows are checked and the container has an area: the count is out of reach */
        if (sieve && area > 0) return too_many(s, area, p, err.message);
        return gp_problem(p, "invalid_spec", sieve ? "/size/sieve" : "/container", "%s",
                          err.message);
    }
    return s->size_law == GP_LAW_SIEVE ? check_sieve_count(s, area, *n, p) : 0;
}

/* Reads an effective spec into *s (free it with gp_spec2d_free, also on failure) and checks
 * what its cell count needs (the container, with its rings when rings is set; the size law;
 * the spectrum), then counts the cells into *n. 0 or -1 with *p. */
static int read_counted_2d(const json_t *full, gp_spec2d *s, int rings, size_t *n,
                           gp_spec_problem *p)
{
    if (gp_spec2d_read(full, s, p) || check_container_2d(s, rings, p) ||
        gp_spec_fv_check_size(full, s->size_law, s->cov, "area", p) ||
        check_spectrum_2d(s, p))
        return -1;
    return cell_count_2d(s, n, p);
}

/* ------------------------------------------------------------------------------------------ */
/* seeding and the IMC threshold */

/* Seeds are placed uniformly in the container by rejection in its bounding box (gp_imc): n /
 * fill draws on average, fill = the container's area over its box's. A sliver such as
 * [[0,0],[1,1],[1,1.00000002]] fills 1e-8 of its box, and 10 seeds would take 1e9 draws
 * (a minute); refused at submit rather than failed or timed out in the queue. */
#define MAX_SEED_DRAWS 1e8

static int check_seed_draws_2d(const gp_spec2d *s, size_t n, gp_spec_problem *p)
{
    if (s->container != GP_CONTAINER_POLYGON) return 0;
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (size_t k = 0; k < s->outer.n; k++) {
        x0 = fmin(x0, s->outer.pts[k].x);
        x1 = fmax(x1, s->outer.pts[k].x);
        y0 = fmin(y0, s->outer.pts[k].y);
        y1 = fmax(y1, s->outer.pts[k].y);
    }
    double area = gp_poly_area(s->outer.pts, s->outer.n);
    for (size_t h = 0; h < s->nholes; h++) area -= gp_poly_area(s->holes[h].pts, s->holes[h].n);
    double fill = area / ((x1 - x0) * (y1 - y0));
    double draws = (double)n / fill;
    if (draws <= MAX_SEED_DRAWS) return 0;
    return gp_problem(p, "invalid_spec", "/container/polygon", "the container fills %.3g of its "
                      "bounding box: placing %zu seeds uniformly in it (by rejection in that box) "
                      "would take about %.3g draws, over the limit of %.0e; a sliver this thin "
                      "cannot hold a specimen (fill at least %.3g for %zu cells)", fill, n, draws,
                      MAX_SEED_DRAWS, (double)n / MAX_SEED_DRAWS, n);
}

/* v rounded up, as short text that reads back >= v (v > 0) */
static void fmt_up(char *buf, size_t n, double v)
{
    for (int digits = 3; digits <= 17; digits++) {
        double e = pow(10, floor(log10(v)) - (digits - 1));
        snprintf(buf, n, "%.*g", digits, ceil(v / e) * e);
        if (strtod(buf, NULL) >= v) return;
    }
}

/* a short threshold >= least that clears the floor of the classes it picks itself (automatic
 * classes follow the threshold) */
static void suggest_threshold(gp_imc_params *q, size_t n, double least, char *use, size_t len)
{
    double v = least;
    for (int i = 0; i < 8; i++) {
        fmt_up(use, len, v);
        q->threshold = strtod(use, NULL);
        double r = gp_imc_reachable_threshold(q, n);
        if (r <= q->threshold) return;
        v = r;
    }
}

/* E1-E3: the threshold must clear the integer-count floor of n cells (gp_imc.h) */
static int check_threshold_2d(const gp_spec2d *s, size_t n, gp_spec_problem *p)
{
    if (s->imc_error == GP_IMC_AD) return 0;
    gp_imc_params q;
    gp_imc_params_defaults(&q);
    q.error_kind = (int)s->imc_error;
    q.threshold = s->imc_threshold;
    q.classes_size = q.classes_orient = s->imc_classes;
    if (s->size_law != GP_LAW_SIEVE) q.cov = s->cov;
    q.mean_deg = s->mean_deg;
    q.anisotropy = s->anisotropy;
    double least = gp_imc_reachable_threshold(&q, n);
    if (!(s->imc_threshold < least)) return 0;
    char use[40], classes[80];
    suggest_threshold(&q, n, least, use, sizeof use);
    if (s->imc_classes)
        snprintf(classes, sizeof classes, "%d size x %d orientation classes", s->imc_classes,
                 s->imc_classes);
    else snprintf(classes, sizeof classes, "its automatic histogram classes");
    return gp_problem(p, "invalid_spec", "/imc/threshold", "%.6g is below the least error %.4g "
                      "that %zu cells can reach with E%d and %s (integer counts); use >= %s%s or "
                      "the default error AD", s->imc_threshold, least, n, (int)s->imc_error,
                      classes, use, s->imc_classes ? ", fewer imc.classes" : "");
}

/* ------------------------------------------------------------------------------------------ */
/* work and result bounds (gp_spec.h) */

/* Costs per unit, from the benchmarks on one core (bench/bench_imc, bench_specimen2d); estimates
 * within a factor of a few, which is all a budget needs. */
#define COST_IMC_MOVE_S 6e-5      /* one IMC move at 1,000 cells (~17,000 moves/s) ... */
#define COST_IMC_PER_DECADE 0.6   /* ... and 60 % more per tenfold more cells (6,400/s at 1e5) */
/* ... plus the container's edges that the recomputed cells meet: the tessellation bins them
 * with about 2 seeds a bin, and a move clips a dozen cells against the edges of their bins, at
 * about 0.5 us x (edges per bin)^1.5 (measured: a 10,000-edge zigzag with 100 cells, 200 edges
 * a bin, 480 moves/s; with 10 cells, 2,000 a bin, 39 moves/s) */
#define COST_IMC_EDGE_S 0.5e-6
#define COST_FILL_S 2.5e-3        /* filling one grain of 128 contour points (~400-600 grains/s) */
#define COST_ODEC_S 0.5e-3        /* its ODEC discs, at 128 points */
#define COST_DESC_S 0.5e-3        /* its descriptors, at 128 points */
/* shape.descriptors: gp_shapemap_fit (at most 6 x 256 sampled grains, ~0.6 s) and the
 * calibration (gp_specimen2d.c: up to 2 rounds of filling and describing up to 500 cells) */
#define COST_SHAPE_FIT_S 0.6
#define CAL_CELLS 500.0
#define CAL_ROUNDS 2.0

/* result bytes of one 2D grain, by outputs (as server/http/http.c has estimated them) */
static double bytes_per_grain(unsigned outputs, double np)
{
    double per = 400; /* stats, ids, areas, descriptors */
    if (outputs & GP_OUT2_GRAINS) per += 40 * np;
    if (outputs & GP_OUT2_ODEC) per += 40 * np + 60 * 16;
    if (outputs & GP_OUT2_DESCRIPTORS) per += 40 * np + 120;
    if (outputs & GP_OUT2_CELLS) per += 40 * 12 + 100;
    return per;
}

/* the container's edges (0 for a circle) */
static size_t edges_2d(const gp_spec2d *s)
{
    size_t edges = s->outer.n;
    for (size_t h = 0; h < s->nholes; h++) edges += s->holes[h].n;
    return edges;
}

/* the shape's own work: the descriptor fit and calibration, or the outlines' analysis (each
 * outline described like a grain); 0 for the other forms */
static double shape_work_2d(const gp_spec2d *s, double cells)
{
    double np = (double)s->contour_points;
    if (s->has_spectrum) return 0;
    if (s->shape_form == GP_SHAPE_FORM_DESCRIPTORS)
        return COST_SHAPE_FIT_S +
               CAL_ROUNDS * fmin(cells, CAL_CELLS) * (COST_FILL_S + COST_DESC_S) * np / 128;
    if (s->shape_form == GP_SHAPE_FORM_OUTLINES)
        return (double)s->noutlines * COST_DESC_S * np / 128;
    return 0;
}

/* seconds of one IMC move among the cells, and (*edge) of its clipping against the container's
 * edges near them */
static double move_cost_2d(const gp_spec2d *s, double cells, double *edge)
{
    double edges = s->container == GP_CONTAINER_POLYGON ? (double)edges_2d(s) : 0;
    double per_bin = edges / fmax(1, cells / 2);
    *edge = COST_IMC_EDGE_S * per_bin * sqrt(per_bin);
    return COST_IMC_MOVE_S * (1 + COST_IMC_PER_DECADE * log10(fmax(cells, 1000) / 1000));
}

/* seconds of everything but the IMC: the grains (fill, ODEC, descriptors) and the shape */
static double grain_work_2d(const gp_spec2d *s, double cells)
{
    double per = COST_FILL_S;
    if (s->outputs & GP_OUT2_ODEC) per += COST_ODEC_S;
    if (s->outputs & GP_OUT2_DESCRIPTORS) per += COST_DESC_S;
    return cells * per * (double)s->contour_points / 128 + shape_work_2d(s, cells);
}

/* The imc.max_steps of a spec that leaves it out: gp_spec2d_default_max_steps of its cell count,
 * clipped to the moves the work budget leaves after the grains, never below
 * GP_IMC_DEFAULT_STEPS_MIN. So the default never turns a spec away: one that the work bound
 * accepts with 10^6 moves is accepted with its default, and one it refuses with 10^6 moves is
 * refused whatever the default. Within the limits of the API the clip does not bind (10^6
 * cells of 4,096 points with every output, 1.2e7 moves: ~1.1e5 s of the 1.7e5); it keeps the
 * default inside the budget whatever the container's edges. From the spec's numbers alone: the
 * same on every machine. */
static long default_steps_2d(const gp_spec2d *s)
{
    size_t n = 0;
    gp_error err;
    memset(&err, 0, sizeof err);
    if (gp_spec2d_cell_count(s, NULL, &n, &err) != GP_OK) return GP_IMC_DEFAULT_STEPS_MIN;
    double cells = (double)n, edge, move = move_cost_2d(s, cells, &edge);
    /* 1 % short of the budget: the bound refuses work over it, not at it */
    double room = 0.99 * (GP_SPEC_WORK_BUDGET_S - grain_work_2d(s, cells)) / (move + edge);
    double steps = fmin((double)gp_spec2d_default_max_steps(n), floor(room));
    return steps > (double)GP_IMC_DEFAULT_STEPS_MIN ? (long)steps : GP_IMC_DEFAULT_STEPS_MIN;
}

static void bounds_2d(const gp_spec2d *s, size_t n, gp_spec_bounds_t *b)
{
    memset(b, 0, sizeof *b);
    double cells = (double)n, edge;
    int sieve = s->size_law == GP_LAW_SIEVE;
    b->cells = b->items = cells;
    b->steps = (double)s->imc_max_steps;
    double imc = b->steps * move_cost_2d(s, cells, &edge);
    double imc_edges = b->steps * edge;
    double grains = grain_work_2d(s, cells);
    b->work_s = imc + imc_edges + grains;
    b->work_pointer = imc_edges > imc && imc_edges > grains ? "/container"
                      : imc > grains                       ? "/imc/max_steps"
                      : sieve                              ? "/size/sieve"
                                                           : "/particles";
    b->result_bytes = cells * bytes_per_grain(s->outputs, (double)s->contour_points);
    b->result_pointer = sieve ? "/size/sieve" : "/particles";
}

static const gp_spec_advice g_work_advice[] = {
    {"/imc/max_steps", "ask for fewer imc.max_steps (the IMC stops at its threshold long before)"},
    {"/container", "use a container of fewer edges, more particles or fewer imc.max_steps (each "
                   "IMC move clips its cells against the container's edges near them)"},
    {NULL, "ask for fewer grains, contour_points or outputs"}};

static const gp_spec_advice g_result_advice[] = {
    {"/particles", "particles, contour_points or outputs"},
    {NULL, "grains (a smaller container or coarser sieve), contour_points or outputs"}};

/* too_large when the work of n cells is over the budget */
static int check_budget_2d(const gp_spec2d *s, size_t n, gp_spec_problem *p)
{
    gp_spec_bounds_t b;
    bounds_2d(s, n, &b);
    char what[200], where[64] = "a circle";
    size_t edges = edges_2d(s);
    if (edges) snprintf(where, sizeof where, "a container of %zu edges", edges);
    snprintf(what, sizeof what, "%.3g IMC moves at most (imc.max_steps%s) on %zu cells in %s, "
             "then %zu grains of %zu contour points", b.steps,
             s->imc_max_steps_default ? ", the default" : "", n, where, n, s->contour_points);
    return gp_spec_over_budget(&b, what, g_work_advice, p);
}

/* ------------------------------------------------------------------------------------------ */
/* the kind */

static int check_2d(const json_t *full, gp_spec_problem *p)
{
    gp_spec2d s;
    size_t n = 0;
    int rc = read_counted_2d(full, &s, 1, &n, p);
    if (rc == 0 && (check_shape_2d(&s, p) || check_seed_draws_2d(&s, n, p) ||
                    check_threshold_2d(&s, n, p) || check_budget_2d(&s, n, p)))
        rc = -1;
    gp_spec2d_free(&s);
    return rc;
}

/* the bounds (the container's rings are not checked again) */
static int spec_bounds_2d(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    gp_spec2d s;
    size_t n = 0;
    int rc = read_counted_2d(full, &s, 0, &n, p);
    if (rc == 0) bounds_2d(&s, n, b);
    gp_spec2d_free(&s);
    return rc;
}

const gp_spec_kind gp_spec_kind_fourier_voronoi_2d = {
    .name = "fourier-voronoi-2d",
    .schema_text = gp_schema_text_fourier_voronoi_2d,
    .explain = explain_2d,
    .check_posted = check_posted_2d,
    .settle_defaults = settle_defaults_2d,
    .check = check_2d,
    .bounds = spec_bounds_2d,
    .items = "grains",
    .result_advice = g_result_advice,
};
