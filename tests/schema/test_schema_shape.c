/* test_schema_shape.c -- the 2D shape forms of issue #17 in the spec layer: shape.descriptors,
 * shape.outlines and shape.spread accepted, read into gp_spec2d, and refused with their JSON
 * pointers (unreachable descriptors with the nearest reachable value; 9 outlines; a non-star
 * outline at index 3; a bad spread; two forms mixed; too many vertices); specs without them
 * keep their effective spec; the work bound counts the shape's work. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_spec.h"
#include "gp_test.h"

static json_t *load(const char *text)
{
    json_error_t e;
    json_t *j = json_loads(text, 0, &e);
    if (!j) fprintf(stderr, "bad test JSON: %s: %s\n", e.text, text);
    return j;
}

/* a 2D spec of 50 particles with the given shape (JSON text, stolen into the spec) */
static json_t *spec_with_shape(json_t *shape)
{
    json_t *s = load("{\"kind\": \"fourier-voronoi-2d\", \"seed\": 1, \"particles\": 50}");
    json_object_set_new(s, "shape", shape);
    return s;
}

/* an outline: a smooth star-shaped blob of n points at (cx, cy) */
static json_t *blob(size_t n, double cx, double cy, double r, double wobble)
{
    json_t *a = json_array();
    for (size_t i = 0; i < n; i++) {
        double t = 2 * M_PI * (double)i / (double)n, rr = r * (1 + wobble * cos(3 * t));
        json_array_append_new(a, json_pack("[f, f]", cx + rr * cos(t), cy + rr * sin(t)));
    }
    return a;
}

/* the U: no interior point sees both arms' inner edges (the kernel is empty) */
static json_t *u_shape(void)
{
    return load("[[0,0],[3,0],[3,3],[2,3],[2,1],[1,1],[1,3],[0,3]]");
}

static json_t *outlines(size_t n)
{
    json_t *a = json_array();
    for (size_t i = 0; i < n; i++)
        json_array_append_new(a, blob(40, (double)i, 0.5 * (double)i, 1 + 0.01 * (double)i,
                                      0.05 + 0.01 * (double)(i % 5)));
    return a;
}

/* spec refused with code, pointer and a message containing needle (and starting with the
 * pointer); the reader of the effective spec is never reached. Steals spec. */
static void expect(json_t *spec, const char *code, const char *ptr, const char *needle,
                   int line)
{
    gp_spec_problem p;
    int rc = gp_spec_validate(spec, &p);
    int ok = rc != 0 && !strcmp(p.code, code) && !strcmp(p.pointer, ptr) &&
             strstr(p.message, needle) && !strncmp(p.message, ptr, strlen(ptr));
    if (!ok)
        fprintf(stderr, "line %d: rc %d code %s pointer '%s' message '%s'\n", line, rc, p.code,
                p.pointer, p.message);
    else
        printf("refused: %s\n", p.message);
    CHECK(ok);
    json_decref(spec);
}
#define BAD(spec, ptr, needle) expect(spec, "invalid_spec", ptr, needle, __LINE__)

static json_t *shape_text(const char *text) { return spec_with_shape(load(text)); }

static void test_descriptors_refused(void)
{
    BAD(shape_text("{\"descriptors\": {\"elongation\": 0.4, \"circularity\": 0.99}}"),
        "/shape/descriptors/circularity", "nearest reachable circularity 0.6");
    BAD(shape_text("{\"descriptors\": {\"circularity\": 0.99, \"elongation\": 0.4}}"),
        "/shape/descriptors/circularity", "with elongation 0.4");
    BAD(shape_text("{\"descriptors\": {\"elongation\": 0.3}}"), "/shape/descriptors/elongation",
        "nearest reachable elongation 0.");
    BAD(shape_text("{\"descriptors\": {}}"), "/shape/descriptors", "give at least one of");
    BAD(shape_text("{\"descriptors\": {\"elongation\": 1.2}}"), "/shape/descriptors/elongation",
        "expected a number in (0, 1], got 1.2");
    BAD(shape_text("{\"descriptors\": {\"regularity\": 0}}"), "/shape/descriptors/regularity",
        "expected a number in (0, 5]");
    BAD(shape_text("{\"descriptors\": {\"roughness\": 0.2}}"), "/shape/descriptors/roughness",
        "unknown field \"roughness\"; allowed here: elongation, roundness, circularity");
    BAD(shape_text("{\"descriptors\": [0.8]}"), "/shape/descriptors", "expected an object");
}

static void test_outlines_refused(void)
{
    BAD(spec_with_shape(json_pack("{s:o}", "outlines", outlines(9))), "/shape/outlines",
        "expected an array of at least 10 items, got 9");
    json_t *o = outlines(12);
    json_array_set_new(o, 3, u_shape());
    BAD(spec_with_shape(json_pack("{s:o}", "outlines", o)), "/shape/outlines/3",
        "not star-shaped: no interior point sees all of it");
    o = outlines(12);
    json_array_set_new(o, 3, u_shape());
    json_array_set_new(o, 7, load("[[0,0],[1,1],[1,0],[0,1]]")); /* a bow tie */
    BAD(spec_with_shape(json_pack("{s:o}", "outlines", o)), "/shape/outlines/3",
        "1 more outline refused: 7");
    o = outlines(12);
    json_array_set_new(o, 5, load("[[0,0],[1,1],[2,2],[0,0]]")); /* no area */
    BAD(spec_with_shape(json_pack("{s:o}", "outlines", o)), "/shape/outlines/5", "no area");
    o = outlines(12);
    json_array_set_new(o, 0, load("[[0,0],[1,1]]"));
    BAD(spec_with_shape(json_pack("{s:o}", "outlines", o)), "/shape/outlines/0",
        "expected an array of at least 3 items, got 2");
    o = outlines(12);
    json_array_set_new(o, 2, load("[[0,0],[1,0,2],[1,1]]"));
    BAD(spec_with_shape(json_pack("{s:o}", "outlines", o)), "/shape/outlines/2/1",
        "expected an array of exactly 2 items");
    o = outlines(12);
    json_array_set_new(o, 2, load("[[0,0],[1,0],[1,\"a\"]]"));
    BAD(spec_with_shape(json_pack("{s:o}", "outlines", o)), "/shape/outlines/2/2/1",
        "expected a number");
    BAD(shape_text("{\"outlines\": 3}"), "/shape/outlines", "expected an array");
}

static void test_spread_and_forms_refused(void)
{
    BAD(shape_text("{\"spread\": -0.1}"), "/shape/spread", "expected a number in [0, 1], got -0.1");
    BAD(shape_text("{\"spread\": 1.5}"), "/shape/spread", "got 1.5");
    BAD(shape_text("{\"spectrum\": [1, 0, 0.1], \"spread\": \"x\"}"), "/shape/spread",
        "got \"x\"");
    BAD(shape_text("{\"descriptors\": {\"elongation\": 0.8}, \"spread\": 2}"), "/shape/spread",
        "[0, 1]");
    BAD(shape_text("{\"D2\": 0.2, \"descriptors\": {\"elongation\": 0.8}}"),
        "/shape/descriptors", "cannot be combined with \"D2\": give the shape one way");
    BAD(shape_text("{\"spread\": 0.1, \"spectrum\": [1, 0, 0.1], \"alpha\": -2}"),
        "/shape/alpha", "cannot be combined with \"spectrum\"");
    BAD(spec_with_shape(json_pack("{s:{s:f}, s:o}", "descriptors", "elongation", 0.8,
                                  "outlines", outlines(10))),
        "/shape/outlines", "cannot be combined with \"descriptors\"");
    /* one form with a bad field is that form's problem, not a mix */
    BAD(shape_text("{\"spectrum\": [1, 0, -0.1]}"), "/shape/spectrum/2", "got -0.1");
}

/* 201 outlines of 10,000 points: 2,010,000 vertices, over the limit */
static void test_too_many_vertices(void)
{
    json_t *o = json_array();
    for (size_t i = 0; i < 201; i++)
        json_array_append_new(o, blob(10000, 0, 0, 1, 0.1));
    expect(spec_with_shape(json_pack("{s:o}", "outlines", o)), "too_large", "/shape/outlines",
           "2010000 vertices in all, over the limit of 2000000", __LINE__);
}

/* the effective spec and what the reader makes of it; steals spec */
static json_t *accept(json_t *spec, gp_spec2d *s)
{
    gp_spec_problem p;
    json_t *full = gp_spec_with_defaults(spec, &p);
    if (!full) fprintf(stderr, "unexpected: %s\n", p.message);
    CHECK(full != NULL);
    memset(s, 0, sizeof *s);
    CHECK(full && gp_spec2d_read(full, s, &p) == 0);
    json_decref(spec);
    return full;
}

static void test_accepted(void)
{
    gp_spec2d s;
    json_t *full = accept(shape_text("{\"descriptors\": {\"elongation\": 0.8, \"regularity\": "
                                     "1.5}, \"spread\": 0.2}"), &s);
    CHECK(s.shape_form == GP_SHAPE_FORM_DESCRIPTORS && !s.has_spectrum);
    CHECK(s.desc_given == 0x9 && s.desc_target[0] == 0.8 && s.desc_target[3] == 1.5);
    CHECK(s.spread == 0.2 && s.spread_given == 1);
    /* no D2 .. beta are filled in beside the descriptors */
    CHECK(json_object_size(json_object_get(full, "shape")) == 2);
    gp_spec2d_free(&s);
    json_decref(full);

    json_t *o = outlines(12);
    json_array_set_new(o, 1, load("[[0,0],[2,0],[2,1],[0,1],[0,0]]")); /* closed: dropped */
    full = accept(spec_with_shape(json_pack("{s:o}", "outlines", o)), &s);
    CHECK(s.shape_form == GP_SHAPE_FORM_OUTLINES && s.noutlines == 12 && !s.spread_given);
    CHECK(s.outlines && s.outlines[0].n == 40 && s.outlines[1].n == 5);
    CHECK(s.outlines && s.outlines[1].pts[2].x == 2 && s.outlines[1].pts[2].y == 1);
    gp_spec2d_free(&s);
    json_decref(full);

    /* spread with the paper's forms; spread alone keeps the default spectrum */
    full = accept(shape_text("{\"spread\": 0.3}"), &s);
    CHECK(s.shape_form == GP_SHAPE_FORM_D && s.D2 == 0.1 && s.spread == 0.3);
    gp_spec2d_free(&s);
    json_decref(full);
    full = accept(shape_text("{\"spectrum\": [1, 0, 0.2, 0.05], \"spread\": 0}"), &s);
    CHECK(s.has_spectrum && s.shape_form == GP_SHAPE_FORM_SPECTRUM && s.spread_given &&
          s.spread == 0);
    gp_spec2d_free(&s);
    json_decref(full);

    /* a spec without spread: its effective spec has none (the stored spec is unchanged) */
    full = accept(load("{\"kind\": \"fourier-voronoi-2d\"}"), &s);
    CHECK(!json_object_get(json_object_get(full, "shape"), "spread"));
    CHECK(s.shape_form == GP_SHAPE_FORM_D && s.spread == 0 && !s.spread_given);
    gp_spec2d_free(&s);
    json_decref(full);
}

/* the shape's work enters the bound: descriptors (fit and calibration), outlines */
static void test_bounds(void)
{
    gp_spec2d s;
    gp_spec_bounds_t b0, b1, b2;
    json_t *plain = accept(shape_text("{}"), &s);
    gp_spec2d_free(&s);
    json_t *desc = accept(shape_text("{\"descriptors\": {\"circularity\": 0.9}}"), &s);
    gp_spec2d_free(&s);
    json_t *outl = accept(spec_with_shape(json_pack("{s:o}", "outlines", outlines(100))), &s);
    gp_spec2d_free(&s);
    CHECK(gp_spec_bounds(plain, &b0, NULL) == 0 && gp_spec_bounds(desc, &b1, NULL) == 0 &&
          gp_spec_bounds(outl, &b2, NULL) == 0);
    printf("work: paper %.3g s, descriptors %.3g s, 100 outlines %.3g s\n", b0.work_s, b1.work_s,
           b2.work_s);
    CHECK(b1.work_s > b0.work_s + 0.5 && b2.work_s > b0.work_s);
    json_decref(plain);
    json_decref(desc);
    json_decref(outl);
}

/* GET /v1/schema: the combined document has the new forms */
static void test_document(void)
{
    json_t *doc = load(gp_schema_document());
    CHECK(doc != NULL);
    const json_t *shape = json_object_get(
        json_object_get(json_object_get(json_object_get(doc, "$defs"), "fourier-voronoi-2d"),
                        "properties"),
        "shape");
    const json_t *one = json_object_get(shape, "oneOf");
    CHECK(json_array_size(one) == 4);
    CHECK(json_object_get(json_object_get(json_array_get(one, 2), "properties"), "descriptors"));
    CHECK(json_object_get(json_object_get(json_array_get(one, 3), "properties"), "outlines"));
    for (size_t i = 0; i < 4; i++)
        CHECK(json_object_get(json_object_get(json_array_get(one, i), "properties"), "spread"));
    json_decref(doc);
}

int main(void)
{
    test_descriptors_refused();
    test_outlines_refused();
    test_spread_and_forms_refused();
    test_too_many_vertices();
    test_accepted();
    test_bounds();
    test_document();
    return gp_test_summary();
}
