/* fuzz_outlines_check.h -- one input through the reader of JSON grain outlines, with its
 * contracts checked. Shared by the libFuzzer target (fuzz/fuzz_outlines.c, which aborts on a
 * broken contract) and the regression ctest (tests/schema/test_spec_outline_regressions.c,
 * which counts it as a failed check), so a reproducer runs the very same calls under the
 * normal build.
 *
 * Every input is the JSON of shape.outlines, [[[x, y], ...], ...] -- the array a job spec
 * holds and a POST /v1/shapes/analyze body's "outlines" (which the daemon reads the same way:
 * wrapped into a 2D spec, server/kinds/fourier-voronoi-2d/shapes.c). Read by jansson as the
 * daemon reads a body (duplicate keys refused, at most GP_FUZZ_OUTLINES_MAX_INPUT bytes), put
 * into {"kind": <the 2D kind>, "shape": {"outlines": <input>}}, and then:
 *   - gp_spec_validate and gp_spec_with_defaults agree (same verdict, same problem); a problem
 *     is well formed and points into /shape/outlines, since nothing else of the spec can be at
 *     fault (the daemon answers it at /outlines);
 *   - the 2D parser, given the spec as posted, returns 0 or a well-formed problem, leaking
 *     nothing;
 *   - for valid outlines: the parser reads the effective spec into outlines equal to the
 *     input, number for number, and so does a worker reading the stored effective spec back
 *     from its text (the JSON's doubles survive the round trip bit for bit);
 *   - the submit check analyses at 16 rays and says a refusal does not depend on the rays:
 *     at the job's contour_points every outline is analysed (none refused), the mean
 *     spectrum has D_0 = 1 and finite D_n >= 0, finite covs, and each outline a finite
 *     r0 > 0 and area > 0; the first outline, described as a job describes its outlines (its
 *     Fourier grain's descriptors at contour_points rays), is analysed too, with finite
 *     descriptors in their ranges unless flagged GP_OUTLINE_NO_DESCRIPTORS.
 * Everything is freed: under ASan (libFuzzer, GP_SANITIZE) a leak is a failure too.
 */
#ifndef GP_FUZZ_OUTLINES_CHECK_H
#define GP_FUZZ_OUTLINES_CHECK_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_outline.h"
#include "gp_shape.h"
#include "gp_spec.h"

/* the daemon's default --max-body: larger bodies never reach the reader */
#define GP_FUZZ_OUTLINES_MAX_INPUT (1u << 20)

/* outcome of one input, for reporting */
typedef struct gp_fuzz_outlines_result {
    int json_ok;             /* the bytes are a JSON value */
    int valid;               /* gp_spec_validate said 0 */
    size_t noutlines;        /* outlines read when valid */
    gp_spec_problem problem; /* the validator's problem when not valid */
} gp_fuzz_outlines_result;

/* NULL when p is a well-formed problem of the outlines */
static const char *gp_fuzz_outlines_problem_broken(const gp_spec_problem *p)
{
    if (!memchr(p->code, 0, sizeof p->code) || !memchr(p->pointer, 0, sizeof p->pointer) ||
        !memchr(p->message, 0, sizeof p->message))
        return "a problem string is not NUL-terminated";
    if (strcmp(p->code, "invalid_spec") && strcmp(p->code, "too_large") &&
        strcmp(p->code, "internal"))
        return "a problem's code is not invalid_spec, too_large or internal";
    if (!p->message[0]) return "a problem has no message";
    return NULL;
}

/* NULL when the problem of a refused spec is well formed and at the outlines */
static const char *gp_fuzz_outlines_refusal_broken(const gp_spec_problem *p)
{
    const char *broken = gp_fuzz_outlines_problem_broken(p);
    if (broken) return broken;
    if (!strcmp(p->code, "internal")) return "outlines refused as an internal error";
    if (strncmp(p->pointer, "/shape/outlines", 15) ||
        (p->pointer[15] != '\0' && p->pointer[15] != '/'))
        return "a refusal of the outlines points elsewhere than /shape/outlines";
    return NULL;
}

/* NULL when the parsed outlines s hold exactly the numbers of the JSON array outl */
static const char *gp_fuzz_outlines_same(const gp_spec2d *s, const json_t *outl)
{
    if (s->shape_form != GP_SHAPE_FORM_OUTLINES || !s->outlines)
        return "valid outlines not read as outlines";
    if (s->noutlines != json_array_size(outl) || s->noutlines < GP_SHAPE_OUTLINES_MIN)
        return "the outlines read are not as many as given";
    for (size_t i = 0; i < s->noutlines; i++) {
        const json_t *o = json_array_get(outl, i);
        if (!s->outlines[i].pts || s->outlines[i].n != json_array_size(o) || s->outlines[i].n < 3)
            return "an outline read has not the points given";
        for (size_t k = 0; k < s->outlines[i].n; k++) {
            const json_t *q = json_array_get(o, k);
            double x = json_number_value(json_array_get(q, 0));
            double y = json_number_value(json_array_get(q, 1));
            gp_vec2 v = s->outlines[i].pts[k];
            if (!isfinite(v.x) || !isfinite(v.y) || v.x != x || v.y != y)
                return "a vertex read is not the number given";
        }
    }
    return NULL;
}

/* NULL when two reads of the outlines are the same bit for bit */
static const char *gp_fuzz_outlines_equal(const gp_spec2d *a, const gp_spec2d *b)
{
    if (a->noutlines != b->noutlines) return "the stored spec reads back another outline count";
    for (size_t i = 0; i < a->noutlines; i++) {
        if (a->outlines[i].n != b->outlines[i].n ||
            memcmp(a->outlines[i].pts, b->outlines[i].pts, a->outlines[i].n * sizeof(gp_vec2)))
            return "the stored spec reads back other vertices";
    }
    return NULL;
}

/* NULL when the analysis of a set accepted at submit holds (see the top) */
static const char *gp_fuzz_outlines_result_broken(const gp_outline_set_result *r, size_t n)
{
    if (r->nrefused || r->nanalysed != n)
        return "an outline accepted at submit is refused at the job's contour_points";
    if (!r->mean || r->nmodes < 2 || r->mean[0] != 1.0) return "the mean spectrum has D_0 != 1";
    for (size_t m = 0; m < r->nmodes; m++)
        if (!(r->mean[m] >= 0 && isfinite(r->mean[m])) || !isfinite(r->sd[m]) ||
            !(r->cov[m] >= 0 && isfinite(r->cov[m])))
            return "a mean D_n, sd or cov is negative or not finite";
    for (size_t i = 0; i < n; i++) {
        const gp_outline_info *f = &r->info[i];
        if (f->flags & GP_OUTLINE_REFUSED) return "an outline analysed is flagged refused";
        if (!(f->r0 > 0 && isfinite(f->r0)) || !(f->area > 0 && isfinite(f->area)))
            return "an outline analysed has r0 <= 0 or no area";
        if (!isfinite(f->pole.x) || !isfinite(f->pole.y) || !isfinite(f->pole_offset))
            return "an outline's pole is not finite";
    }
    return NULL;
}

/* NULL when outline 0's descriptors, as a job measures them, are finite and in range */
static const char *gp_fuzz_outlines_described(const gp_spec2d *s)
{
    gp_outline_params op;
    gp_outline_params_defaults(&op);
    op.np = s->contour_points;
    op.nmodes = s->contour_points / 2;
    op.min_outlines = 1;
    gp_outline_points one = {s->outlines[0].pts, s->outlines[0].n};
    gp_outline_set_result r;
    gp_error e;
    gp_status st = gp_outline_set_analyze(&one, 1, &op, NULL, &r, &e);
    const char *broken = NULL;
    if (st == GP_ERR_NOMEM) broken = NULL;
    else if (st != GP_OK) broken = "outline 0 is not analysed with its descriptors";
    else if (!(r.info[0].flags & GP_OUTLINE_NO_DESCRIPTORS)) {
        const gp_outline_info *f = &r.info[0];
        if (!(f->elongation > 0 && f->elongation <= 1) ||
            !(f->circularity > 0 && f->circularity <= 1) ||
            !(f->roundness > 0 && isfinite(f->roundness)) ||
            !(f->regularity >= 0 && f->regularity <= GP_SHAPE_REGULARITY_CAP) ||
            !isfinite(f->orientation_deg))
            broken = "outline 0's descriptors are out of their ranges";
    }
    gp_outline_set_result_free(&r);
    return broken;
}

/* NULL when every outline of s is analysed at the job's contour_points (no descriptors: the
 * submit check's claim is about refusals, and outline 0 stands for the descriptors) */
static const char *gp_fuzz_outlines_analysed(const gp_spec2d *s)
{
    gp_outline_points *pts = malloc(s->noutlines * sizeof *pts);
    if (!pts) return NULL;
    for (size_t i = 0; i < s->noutlines; i++)
        pts[i] = (gp_outline_points){s->outlines[i].pts, s->outlines[i].n};
    gp_outline_params op;
    gp_outline_params_defaults(&op);
    op.np = s->contour_points;
    op.nmodes = s->contour_points / 2;
    op.descriptors = 0;
    op.min_outlines = GP_SHAPE_OUTLINES_MIN;
    gp_outline_set_result r;
    gp_error e;
    gp_status st = gp_outline_set_analyze(pts, s->noutlines, &op, NULL, &r, &e);
    free(pts);
    const char *broken = NULL;
    if (st == GP_ERR_NOMEM) broken = NULL;
    else if (st != GP_OK) broken = "outlines accepted at submit fail the job's analysis";
    else broken = gp_fuzz_outlines_result_broken(&r, s->noutlines);
    gp_outline_set_result_free(&r);
    if (!broken) broken = gp_fuzz_outlines_described(s);
    return broken;
}

/* NULL when the effective spec full, valid, reads into the outlines of outl, the same again
 * after the daemon's store round trip, and analyses as the submit check promised */
static const char *gp_fuzz_outlines_valid(const json_t *full, const json_t *outl,
                                          gp_fuzz_outlines_result *res)
{
    gp_spec2d s, back;
    gp_spec_problem p;
    memset(&back, 0, sizeof back);
    const char *broken = NULL;
    if (gp_spec2d_read(full, &s, &p) != 0) broken = "the 2D parser refuses valid outlines";
    if (!broken) broken = gp_fuzz_outlines_same(&s, outl);
    if (!broken) res->noutlines = s.noutlines;
    if (!broken) {
        json_error_t je;
        char *text = json_dumps(full, JSON_COMPACT);
        json_t *again = text ? json_loads(text, 0, &je) : NULL;
        if (!again) broken = "the effective spec does not read back from its text";
        else if (gp_spec2d_read(again, &back, &p) != 0)
            broken = "the stored effective spec fails to parse on the worker";
        else broken = gp_fuzz_outlines_equal(&s, &back);
        json_decref(again);
        free(text);
    }
    if (!broken) broken = gp_fuzz_outlines_analysed(&s);
    gp_spec2d_free(&back);
    gp_spec2d_free(&s);
    return broken;
}

/* Runs the calls on one input. Returns NULL when every contract holds, else a one-line
 * description of the first one broken. res (may be NULL) gets the verdict. */
static const char *gp_fuzz_outlines_one(const uint8_t *data, size_t size,
                                        gp_fuzz_outlines_result *res)
{
    gp_fuzz_outlines_result local;
    if (!res) res = &local;
    memset(res, 0, sizeof *res);
    if (size > GP_FUZZ_OUTLINES_MAX_INPUT) return NULL;
    json_error_t je;
    json_t *outl = json_loadb((const char *)data, size, JSON_REJECT_DUPLICATES | JSON_DECODE_ANY,
                              &je);
    if (!outl) return NULL;
    res->json_ok = 1;
    json_t *spec = json_pack("{s:s, s:{s:O}}", "kind", gp_spec_kinds()[0], "shape", "outlines",
                             outl);
    if (!spec) {
        json_decref(outl);
        return NULL;
    }
    const char *broken = NULL;
    gp_spec_problem pv, pd, pp;
    int valid = gp_spec_validate(spec, &pv) == 0;
    res->valid = valid;
    res->problem = pv;
    json_t *full = gp_spec_with_defaults(spec, &pd);
    if (valid != (full != NULL)) broken = "gp_spec_validate and gp_spec_with_defaults disagree";
    else if (!valid && (strcmp(pv.code, pd.code) || strcmp(pv.pointer, pd.pointer) ||
                        strcmp(pv.message, pd.message)))
        broken = "gp_spec_validate and gp_spec_with_defaults report different problems";
    else if (!valid) broken = gp_fuzz_outlines_refusal_broken(&pv);

    /* the parser on the spec as posted: any verdict, but a refusal is well formed */
    if (!broken) {
        gp_spec2d posted;
        if (gp_spec2d_read(spec, &posted, &pp) != 0) broken = gp_fuzz_outlines_problem_broken(&pp);
        gp_spec2d_free(&posted);
    }

    if (!broken && valid) broken = gp_fuzz_outlines_valid(full, outl, res);
    json_decref(full);
    json_decref(spec);
    json_decref(outl);
    return broken;
}

#endif /* GP_FUZZ_OUTLINES_CHECK_H */
