/* fuzz_spec_check.h -- one input through the spec validator and parsers, with the contracts of
 * schema/gp_spec.h checked. Shared by the libFuzzer target (fuzz/fuzz_spec.c, which aborts on a
 * broken contract) and the regression ctest (tests/schema/test_spec_regressions.c, which counts it as
 * a failed check), so a reproducer runs the very same calls under the normal build.
 *
 * For every input that jansson reads as JSON (as the daemon reads a POST body: duplicate keys
 * refused, at most GP_FUZZ_SPEC_MAX_INPUT bytes):
 *   - gp_spec_validate and gp_spec_with_defaults agree (same verdict, same problem), and a
 *     problem is well formed (a known code: invalid_spec, too_large or internal; an RFC 6901
 *     pointer; a message);
 *   - the parsers take only effective specs and do not validate, but whatever they are given
 *     (here: the input as posted, to both of them) they return 0, or -1 with a well-formed
 *     problem, and leave nothing allocated after their _free;
 *   - for a valid spec: the parser of its kind reads the effective spec, and the parsed struct
 *     holds what the core relies on (a polygon of >= 3 points or a circle of positive radius,
 *     a cell count or a sieve of >= 2 rows, a spectrum of at most contour_points / 2
 *     amplitudes, a 3D box, sieve and tiling in range); the other kind's parser refuses it at
 *     /kind; the effective spec is its own effective spec (gp_spec.h); and that effective
 *     spec, written as the daemon stores it (json_dumps JSON_COMPACT) and read back as a
 *     worker does, parses again -- a spec accepted at submit must not fail on the worker;
 *     where gp_spec.h has the work and result bounds (gp_spec_bounds), they are finite, under
 *     the work budget, and gp_spec_check_result refuses a result over its bound with
 *     too_large.
 * Everything is freed: under ASan (libFuzzer, GP_SANITIZE) a leak is a failure too.
 */
#ifndef GP_FUZZ_SPEC_CHECK_H
#define GP_FUZZ_SPEC_CHECK_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_spec.h"
#include "kinds/triaxial-3d/gp_spec_triax.h"

/* the daemon's default --max-body: larger bodies never reach the validator */
#define GP_FUZZ_SPEC_MAX_INPUT (1u << 20)

/* outcome of one input, for reporting */
typedef struct gp_fuzz_spec_result {
    int json_ok;                /* the bytes are a JSON document */
    int valid;                  /* gp_spec_validate said 0 */
    gp_spec_problem problem;    /* the validator's problem when not valid */
} gp_fuzz_spec_result;

/* NULL when p is a well-formed problem, else what is wrong with it */
static const char *gp_fuzz_problem_broken(const gp_spec_problem *p)
{
    if (!memchr(p->code, 0, sizeof p->code) || !memchr(p->pointer, 0, sizeof p->pointer) ||
        !memchr(p->message, 0, sizeof p->message))
        return "a problem string is not NUL-terminated";
    if (strcmp(p->code, "invalid_spec") && strcmp(p->code, "too_large") &&
        strcmp(p->code, "internal"))
        return "a problem's code is not invalid_spec, too_large or internal";
    if (p->pointer[0] && p->pointer[0] != '/') return "a problem's pointer is not a JSON pointer";
    if (!p->message[0]) return "a problem has no message";
    return NULL;
}

static int gp_fuzz_same_problem(const gp_spec_problem *a, const gp_spec_problem *b)
{
    return !strcmp(a->code, b->code) && !strcmp(a->pointer, b->pointer) &&
           !strcmp(a->message, b->message);
}

/* NULL when the parsed 2D spec holds what gp_specimen2d_build relies on */
static const char *gp_fuzz_check_2d(const gp_spec2d *s)
{
    if (s->container == GP_CONTAINER_POLYGON) {
        if (!s->outer.pts || s->outer.n < 3) return "2D: a polygon container of < 3 points";
        if (s->nholes && !s->holes) return "2D: holes counted but not there";
        for (size_t i = 0; i < s->nholes; i++)
            if (!s->holes[i].pts || s->holes[i].n < 3) return "2D: a hole of < 3 points";
    } else if (!(s->circle_radius > 0)) {
        return "2D: a circle container of radius <= 0";
    }
    if (s->size_law == GP_LAW_SIEVE) {
        if (s->nsieve < 2 || !s->sieve_d || !s->sieve_pass) return "2D: a sieve law of < 2 rows";
        if (s->particles != 0) return "2D: a sieve law with particles";
    } else if (s->particles < 1) {
        return "2D: no particles";
    }
    if (s->has_spectrum && (!s->spectrum || s->nspectrum > s->contour_points / 2))
        return "2D: a spectrum longer than contour_points / 2";
    if (s->shape_form == GP_SHAPE_FORM_DESCRIPTORS && (s->desc_given == 0 || s->desc_given > 15))
        return "2D: target descriptors without a descriptor";
    if (s->shape_form == GP_SHAPE_FORM_OUTLINES) {
        if (!s->outlines || s->noutlines < GP_SHAPE_OUTLINES_MIN) return "2D: too few outlines";
        for (size_t i = 0; i < s->noutlines; i++)
            if (!s->outlines[i].pts || s->outlines[i].n < 3) return "2D: an outline of < 3 points";
    }
    if (!(s->spread >= 0 && s->spread <= GP_SHAPE_SPREAD_MAX)) return "2D: spread out of [0, 1]";
    if (s->contour_points < 16) return "2D: contour_points < 16";
    if (!(s->solid_fraction > 0 && s->solid_fraction <= 1)) return "2D: solid_fraction out of (0, 1]";
    if (!(s->imc_threshold > 0)) return "2D: imc threshold <= 0";
    if (s->outputs == 0) return "2D: no outputs";
    return NULL;
}

/* NULL when the parsed 3D spec holds what gp_specimen3d_build relies on */
static const char *gp_fuzz_check_3d(const gp_spec3d *s)
{
    for (int i = 0; i < 3; i++) {
        if (!(s->box[i] > 0)) return "3D: a box side <= 0";
        if (s->tiling[i] < 1 || s->tiling[i] > 16) return "3D: tiling out of [1, 16]";
    }
    if (s->nsieve < 2 || !s->sieve) return "3D: a sieve of < 2 rows";
    if (!(s->porosity > 0 && s->porosity < 1)) return "3D: porosity out of (0, 1)";
    if (s->outputs == 0) return "3D: no outputs";
    return NULL;
}

#ifdef GP_SPEC_WORK_BUDGET_S
/* NULL when the work and result bounds of a valid effective spec hold together: finite,
 * non-negative, under the work budget (validation refuses more), both pointers named; and
 * gp_spec_check_result refuses a tiny result bound with a well-formed 422 too_large */
static const char *gp_fuzz_check_bounds(const json_t *full)
{
    gp_spec_bounds_t b;
    gp_spec_problem p;
    if (gp_spec_bounds(full, &b, &p) != 0) return "gp_spec_bounds fails on a valid effective spec";
    const double v[6] = {b.cells, b.items, b.steps, b.dt, b.work_s, b.result_bytes};
    for (int i = 0; i < 6; i++)
        if (!(v[i] >= 0 && v[i] < INFINITY)) return "a bound is negative, infinite or NaN";
    if (b.work_s > GP_SPEC_WORK_BUDGET_S) return "a valid spec's work is over the budget";
    if (!b.work_pointer || b.work_pointer[0] != '/' || !b.result_pointer ||
        b.result_pointer[0] != '/')
        return "a bound names no field";
    if (gp_spec_check_result(full, INFINITY, &p) != 0)
        return "gp_spec_check_result refuses a result under an infinite bound";
    if (b.result_bytes > 1 && gp_spec_check_result(full, 1, &p) == 0)
        return "gp_spec_check_result accepts a result over its bound";
    if (b.result_bytes > 1) {
        const char *broken = gp_fuzz_problem_broken(&p);
        if (broken) return broken;
        if (strcmp(p.code, "too_large") || strcmp(p.pointer, b.result_pointer))
            return "a result over its bound is not too_large at result_pointer";
    }
    return NULL;
}
#endif

/* the kinds' parsers, by index: 0 the 2D kind, 1 the 3D kind, 2 the triaxial test */
#define GP_FUZZ_NKINDS 3

/* parses spec as kind k (< GP_FUZZ_NKINDS); 0 or -1 as the parser said; *broken set when the
 * parsed struct is inconsistent */
static int gp_fuzz_parse(const json_t *spec, int k, gp_spec_problem *p, const char **broken)
{
    int rc;
    if (k == 0) {
        gp_spec2d s;
        rc = gp_spec2d_read(spec, &s, p);
        if (rc == 0 && !*broken) *broken = gp_fuzz_check_2d(&s);
        gp_spec2d_free(&s);
    } else if (k == 1) {
        gp_spec3d s;
        rc = gp_spec3d_read(spec, &s, p);
        if (rc == 0 && !*broken) *broken = gp_fuzz_check_3d(&s);
        gp_spec3d_free(&s);
    } else {
        gp_spec_triax s;
        rc = gp_spec_triax_read(spec, &s, p);
        if (rc == 0 && !*broken) *broken = gp_fuzz_check_3d(&s.specimen);
        gp_spec_triax_free(&s);
    }
    return rc;
}

/* the parser of a spec's kind (the 2D kind's for anything that names no other) */
static int gp_fuzz_kind_index(const json_t *spec)
{
    const char *kind = json_string_value(json_object_get(spec, "kind"));
    static const char *const parsers[GP_FUZZ_NKINDS] = {"fourier-voronoi-2d", "spheres-3d",
                                                        "triaxial-3d"};
    for (int k = 0; kind && k < GP_FUZZ_NKINDS; k++)
        if (!strcmp(kind, parsers[k])) return k;
    return 0;
}

/* Runs the calls on one input. Returns NULL when every contract holds, else a one-line
 * description of the first one broken. res (may be NULL) gets the verdict. */
static const char *gp_fuzz_spec_one(const uint8_t *data, size_t size, gp_fuzz_spec_result *res)
{
    gp_fuzz_spec_result local;
    if (!res) res = &local;
    memset(res, 0, sizeof *res);
    if (size > GP_FUZZ_SPEC_MAX_INPUT) return NULL;
    json_error_t je;
    json_t *spec = json_loadb((const char *)data, size, JSON_REJECT_DUPLICATES, &je);
    if (!spec) return NULL;
    res->json_ok = 1;
    const char *broken = NULL;

    gp_spec_problem pv, pd, pp;
    int valid = gp_spec_validate(spec, &pv) == 0;
    res->valid = valid;
    res->problem = pv;
    json_t *full = gp_spec_with_defaults(spec, &pd);
    if (valid != (full != NULL)) broken = "gp_spec_validate and gp_spec_with_defaults disagree";
    else if (!valid && !gp_fuzz_same_problem(&pv, &pd))
        broken = "gp_spec_validate and gp_spec_with_defaults report different problems";
    else if (!valid) broken = gp_fuzz_problem_broken(&pv);
    else if (pv.code[0]) broken = "a valid spec left a problem code";

    /* both parsers on the input as posted: no contract on the verdict (they take effective
     * specs), but a refusal is a well-formed problem, and nothing leaks or crashes */
    for (int as = 0; as < GP_FUZZ_NKINDS && !broken; as++) {
        const char *unchecked = NULL; /* the struct of a spec as posted may be anything */
        if (gp_fuzz_parse(spec, as, &pp, &unchecked) != 0) broken = gp_fuzz_problem_broken(&pp);
    }

    int k = gp_fuzz_kind_index(spec);
    if (valid && full) {
        if (gp_fuzz_parse(full, k, &pp, &broken) != 0 && !broken)
            broken = "the parser refuses a valid spec's effective spec";
        /* every other kind's parser refuses it at /kind */
        for (int other = 0; other < GP_FUZZ_NKINDS && !broken; other++) {
            if (other == k) continue;
            if (gp_fuzz_parse(full, other, &pp, &broken) == 0 && !broken)
                broken = "a spec parses as two kinds";
            else if (!broken && strcmp(pp.pointer, "/kind"))
                broken = "another kind's parser does not refuse at /kind";
        }
        /* the effective spec is its own effective spec */
        json_t *again = gp_spec_with_defaults(full, &pd);
        if (!again && !broken) broken = "the effective spec of a valid spec is not valid";
        else if (again && !json_equal(again, full) && !broken)
            broken = "the effective spec of the effective spec differs";
        json_decref(again);
#ifdef GP_SPEC_WORK_BUDGET_S
        if (!broken) broken = gp_fuzz_check_bounds(full);
#endif
        /* as stored by the daemon and read back by a worker */
        char *text = json_dumps(full, JSON_COMPACT);
        json_t *back = text ? json_loads(text, 0, &je) : NULL;
        if (!back && !broken) broken = "the effective spec does not read back from its text";
        if (back && gp_fuzz_parse(back, k, &pp, &broken) != 0 && !broken)
            broken = "the stored effective spec fails to parse on the worker";
        json_decref(back);
        free(text);
    }
    json_decref(full);
    json_decref(spec);
    return broken;
}

#endif /* GP_FUZZ_SPEC_CHECK_H */
