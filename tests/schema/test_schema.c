/* test_schema.c -- the spec validator: pointers and messages of bad specs, api.md's examples,
 * defaults, semantic checks, the combined schema document. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_imc.h"
#include "gp_spec.h"
#include "gp_test.h"

static const char *EX2D =
    "{\"kind\": \"fourier-voronoi-2d\", \"seed\": 42,"
    " \"container\": {\"polygon\": [[0,0],[1,0],[1,1],[0,1]], \"holes\": []},"
    " \"particles\": 500, \"size\": {\"cov\": 0.8},"
    " \"orientation\": {\"mean_deg\": 0, \"anisotropy\": 1.0},"
    " \"shape\": {\"D2\": 0.1, \"D3\": 0.05, \"D8\": 0.02, \"alpha\": -2, \"beta\": -2},"
    " \"solid_fraction\": 0.65,"
    " \"imc\": {\"error\": \"E3\", \"threshold\": 0.002, \"max_steps\": 1000000, \"init\": \"halton\"},"
    " \"contour_points\": 128,"
    " \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}";

static const char *MIN2D = "{\"kind\": \"fourier-voronoi-2d\"}";

static const char *EX3D =
    "{\"kind\": \"spheres-3d\", \"seed\": 7, \"box\": [0.5, 0.5, 0.5],"
    " \"sieve\": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], \"sieve_units\": \"mm\","
    " \"porosity\": 0.38,"
    " \"material\": {\"density\": 2600, \"young\": 15e6, \"poisson\": 0.5, \"friction_deg\": 18, \"damping\": 0.2},"
    " \"tiling\": [4, 4, 4], \"outputs\": [\"spheres\", \"contacts\", \"fabric\", \"stress\"]}";

static json_t *load(const char *text)
{
    json_error_t e;
    json_t *j = json_loads(text, JSON_DECODE_ANY, &e);
    if (!j) fprintf(stderr, "bad test JSON: %s: %s\n", e.text, text);
    return j;
}

/* Sets the value at a simple pointer ("/a/b", array indices allowed) in a copy of base, or
 * deletes it when value is NULL; returns the copy. */
static json_t *patched(const char *base, const char *pointer, const char *value)
{
    json_t *doc = load(base);
    char path[256];
    snprintf(path, sizeof path, "%s", pointer);
    json_t *cur = doc;
    char *save = NULL;
    char *tok = strtok_r(path + 1, "/", &save);
    while (tok) {
        char *next = strtok_r(NULL, "/", &save);
        if (!next) {
            json_t *v = value ? load(value) : NULL;
            if (json_is_array(cur)) {
                size_t i = (size_t)atoi(tok);
                if (v) json_array_set_new(cur, i, v);
                else json_array_remove(cur, i);
            } else {
                if (v) json_object_set_new(cur, tok, v);
                else json_object_del(cur, tok);
            }
        } else {
            json_t *child = json_is_array(cur) ? json_array_get(cur, (size_t)atoi(tok))
                                               : json_object_get(cur, tok);
            if (!child) {
                child = json_object();
                json_object_set_new(cur, tok, child);
            }
            cur = child;
        }
        tok = next;
    }
    return doc;
}

static int g_verbose = 0;

/* expects the spec to fail with this pointer, status, and message containing needle */
static void expect_bad_code(const char *base, const char *ptr, const char *value,
                            const char *want_ptr, int want_status, const char *want_code,
                            const char *needle, int line)
{
    json_t *doc = patched(base, ptr, value);
    gp_spec_problem p;
    int rc = gp_spec_validate(doc, &p);
    int ok = rc != 0 && !strcmp(p.pointer, want_ptr) && p.http_status == want_status &&
             !strcmp(p.code, want_code) && (!needle || strstr(p.message, needle));
    if (!ok || g_verbose)
        fprintf(stderr, "line %d: set %s = %s -> rc %d status %d pointer '%s' message '%s'\n",
                line, ptr, value ? value : "(deleted)", rc, p.http_status, p.pointer, p.message);
    CHECK(ok);
    /* the message starts with the pointer */
    if (rc) CHECK(strncmp(p.message, want_ptr[0] ? want_ptr : "spec", strlen(want_ptr[0] ? want_ptr : "spec")) == 0);
    /* the parser reports the same problem for 2D specs */
    if (strstr(base, "fourier")) {
        gp_spec2d s;
        gp_spec_problem q;
        CHECK(gp_spec2d_read(doc, &s, &q) != 0);
        CHECK(!strcmp(q.pointer, p.pointer));
        gp_spec2d_free(&s);
    }
    json_decref(doc);
}

static void expect_bad(const char *base, const char *ptr, const char *value,
                       const char *want_ptr, int want_status, const char *needle, int line)
{
    expect_bad_code(base, ptr, value, want_ptr, want_status, "invalid_spec", needle, line);
}
#define BAD2(ptr, val, wptr, st, needle) expect_bad(EX2D, ptr, val, wptr, st, needle, __LINE__)
#define BAD3(ptr, val, wptr, st, needle) expect_bad(EX3D, ptr, val, wptr, st, needle, __LINE__)

static void expect_good(const char *base, const char *ptr, const char *value, int line)
{
    json_t *doc = patched(base, ptr, value);
    gp_spec_problem p;
    int rc = gp_spec_validate(doc, &p);
    if (rc) fprintf(stderr, "line %d: set %s = %s -> unexpected: %s\n", line, ptr, value, p.message);
    CHECK(rc == 0);
    json_decref(doc);
}
#define GOOD2(ptr, val) expect_good(EX2D, ptr, val, __LINE__)
#define GOOD3(ptr, val) expect_good(EX3D, ptr, val, __LINE__)

static void test_examples(void)
{
    json_t *j = load(EX2D);
    gp_spec_problem p;
    CHECK(gp_spec_validate(j, &p) == 0);
    gp_spec2d s;
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.seed == 42);
    CHECK(s.container == GP_CONTAINER_POLYGON);
    CHECK(s.outer.n == 4);
    CHECK_NEAR(s.outer.pts[2].x, 1, 0);
    CHECK_NEAR(s.outer.pts[2].y, 1, 0);
    CHECK(s.nholes == 0);
    CHECK(s.particles == 500);
    CHECK(s.size_law == GP_LAW_LOGNORMAL);
    CHECK_NEAR(s.cov, 0.8, 0);
    CHECK(s.size_of_grains == 0);
    CHECK(s.nsieve == 0 && s.sieve_d == NULL && s.sieve_pass == NULL);
    CHECK_NEAR(s.mean_deg, 0, 0);
    CHECK_NEAR(s.anisotropy, 1, 0);
    CHECK(!s.has_spectrum);
    CHECK_NEAR(s.D2, 0.1, 0);
    CHECK_NEAR(s.D3, 0.05, 0);
    CHECK_NEAR(s.D8, 0.02, 0);
    CHECK_NEAR(s.alpha, -2, 0);
    CHECK_NEAR(s.beta, -2, 0);
    CHECK_NEAR(s.solid_fraction, 0.65, 0);
    CHECK(s.imc_error == GP_IMC_E3);
    CHECK_NEAR(s.imc_threshold, 0.002, 0);
    CHECK(s.imc_max_steps == 1000000);
    CHECK(s.imc_init == GP_INIT_HALTON);
    CHECK(s.imc_classes == 0);
    CHECK(s.contour_points == 128);
    CHECK(s.outputs == (GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS | GP_OUT2_CELLS));
    gp_spec2d_free(&s);
    CHECK(s.outer.pts == NULL);
    json_decref(j);

    j = load(EX3D);
    CHECK(gp_spec_validate(j, &p) == 0);
    json_t *full = gp_spec_with_defaults(j, &p);
    CHECK(full != NULL);
    CHECK(json_equal(full, j)); /* every field was given */
    json_decref(full);
    gp_spec3d t;
    CHECK(gp_spec3d_read(j, &t, &p) == 0);
    CHECK(t.seed == 7);
    CHECK_NEAR(t.box[0], 0.5, 0);
    CHECK_NEAR(t.box[2], 0.5, 0);
    CHECK(t.nsieve == 5);
    CHECK_NEAR(t.sieve[0].diameter, 0.010, 1e-15);
    CHECK_NEAR(t.sieve[2].diameter, 0.050, 1e-15);
    CHECK_NEAR(t.sieve[2].passing, 50, 0);
    CHECK_NEAR(t.sieve[4].passing, 100, 0);
    CHECK_NEAR(t.porosity, 0.38, 0);
    CHECK_NEAR(t.material.density, 2600, 0);
    CHECK_NEAR(t.material.young, 15e6, 0);
    CHECK_NEAR(t.material.poisson, 0.5, 0);
    CHECK_NEAR(t.material.friction_deg, 18, 0);
    CHECK_NEAR(t.material.damping, 0.2, 0);
    CHECK(t.tiling[0] == 4 && t.tiling[1] == 4 && t.tiling[2] == 4);
    CHECK(t.outputs == (GP_OUT3_SPHERES | GP_OUT3_CONTACTS | GP_OUT3_FABRIC | GP_OUT3_STRESS));
    gp_spec3d_free(&t);
    CHECK(t.sieve == NULL);
    json_decref(j);

    /* defaults and metres */
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[0.01, 0], [0.02, 100]], \"sieve_units\": \"m\"}");
    CHECK(gp_spec3d_read(j, &t, &p) == 0);
    CHECK_NEAR(t.sieve[1].diameter, 0.02, 0);
    CHECK(t.tiling[0] == 1 && t.tiling[1] == 1 && t.tiling[2] == 1);
    CHECK(t.outputs == GP_OUT3_SPHERES);
    CHECK_NEAR(t.box[1], 0.5, 0);
    gp_spec3d_free(&t);
    json_decref(j);
    /* a 2D spec is not a 3D one */
    j = load(EX2D);
    CHECK(gp_spec3d_read(j, &t, &p) != 0 && !strcmp(p.pointer, "/kind"));
    gp_spec3d_free(&t);
    json_decref(j);
    j = load("{\"kind\": \"spheres-3d\", \"porosity\": 2}");
    CHECK(gp_spec3d_read(j, &t, &p) != 0 && !strcmp(p.pointer, "/porosity"));
    gp_spec3d_free(&t);
    json_decref(j);
}

static void test_defaults(void)
{
    json_t *j = load("{\"kind\": \"fourier-voronoi-2d\"}");
    gp_spec_problem p;
    gp_spec2d s;
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.seed == 0);
    CHECK(s.container == GP_CONTAINER_POLYGON && s.outer.n == 4 && s.nholes == 0);
    CHECK(s.particles == 100);
    CHECK_NEAR(s.cov, 0.5, 0);
    CHECK_NEAR(s.mean_deg, 0, 0);
    CHECK_NEAR(s.anisotropy, 1, 0);
    CHECK_NEAR(s.D2, 0.1, 0);
    CHECK_NEAR(s.D3, 0.05, 0);
    CHECK_NEAR(s.D8, 0.02, 0);
    CHECK_NEAR(s.alpha, -2, 0);
    CHECK_NEAR(s.beta, -2, 0);
    CHECK_NEAR(s.solid_fraction, 0.65, 0);
    CHECK(s.size_law == GP_LAW_LOGNORMAL && s.size_of_grains == 0 && s.nsieve == 0);
    CHECK(s.imc_error == GP_IMC_AD);
    CHECK_NEAR(s.imc_threshold, gp_imc_default_threshold(GP_IMC_ERROR_AD), 0);
    CHECK(s.imc_max_steps == 1000000);
    CHECK(s.imc_init == GP_INIT_UNIFORM);
    CHECK(s.contour_points == 128);
    CHECK(s.outputs == GP_OUT2_GRAINS);
    CHECK(s.threads == 0);
    gp_spec2d_free(&s);

    json_t *full = gp_spec_with_defaults(j, &p);
    CHECK(full && json_is_object(json_object_get(full, "imc")));
    CHECK(!strcmp(json_string_value(json_object_get(json_object_get(full, "imc"), "error")), "AD"));
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(full, "imc"), "threshold")),
               gp_imc_default_threshold(GP_IMC_ERROR_AD), 0);
    json_t *size = json_object_get(full, "size");
    CHECK(!strcmp(json_string_value(json_object_get(size, "law")), "lognormal"));
    CHECK(!strcmp(json_string_value(json_object_get(size, "of")), "cells"));
    CHECK_NEAR(json_number_value(json_object_get(size, "cov")), 0.5, 0);
    CHECK(json_object_get(size, "sieve") == NULL && json_object_get(size, "sieve_units") == NULL);
    CHECK(json_integer_value(json_object_get(full, "particles")) == 100);
    CHECK(json_object_get(json_object_get(full, "imc"), "classes") == NULL);
    CHECK(json_array_size(json_object_get(json_object_get(full, "container"), "polygon")) == 4);
    json_decref(full);
    json_decref(j);

    /* partial objects get their missing members */
    j = load("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 120, \"imc\": {\"error\": \"E1\", \"classes\": 12},"
             " \"shape\": {\"D2\": 0.3}, \"container\": {\"circle\": {\"center\": [1, 2], \"radius\": 3}},"
             " \"seed\": 5.0}");
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.imc_error == GP_IMC_E1 && s.imc_classes == 12);
    CHECK_NEAR(s.imc_threshold, 0.002, 0);
    CHECK_NEAR(s.D2, 0.3, 0);
    CHECK_NEAR(s.D3, 0.05, 0);
    CHECK(s.container == GP_CONTAINER_CIRCLE);
    CHECK_NEAR(s.circle_center.x, 1, 0);
    CHECK_NEAR(s.circle_center.y, 2, 0);
    CHECK_NEAR(s.circle_radius, 3, 0);
    CHECK(s.outer.pts == NULL);
    CHECK(s.seed == 5);
    gp_spec2d_free(&s);
    json_decref(j);

    /* spectrum */
    j = load("{\"kind\": \"fourier-voronoi-2d\", \"shape\": {\"spectrum\": [1, 0, 0.2, 0.05, 0.01]}}");
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.has_spectrum && s.nspectrum == 5);
    CHECK_NEAR(s.spectrum[2], 0.2, 0);
    gp_spec2d_free(&s);
    json_decref(j);

    /* a hole, a closing point that repeats the first */
    j = load("{\"kind\": \"fourier-voronoi-2d\", \"container\": {\"polygon\": [[0,0],[4,0],[4,4],[0,4],[0,0]],"
             " \"holes\": [[[1,1],[1,2],[2,2],[2,1]], [[3,3],[3.5,3],[3.5,3.5]]]}}");
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.outer.n == 4 && s.nholes == 2 && s.holes[0].n == 4 && s.holes[1].n == 3);
    gp_spec2d_free(&s);
    json_decref(j);

    j = load("{\"kind\": \"spheres-3d\"}");
    full = gp_spec_with_defaults(j, &p);
    CHECK(full != NULL);
    CHECK(json_array_size(json_object_get(full, "sieve")) == 5);
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(full, "material"), "density")), 2600, 0);
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(full, "material"), "young")), 15e6, 0);
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(full, "material"), "poisson")), 0.5, 0);
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(full, "material"), "friction_deg")), 18, 0);
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(full, "material"), "damping")), 0.2, 0);
    CHECK_NEAR(json_number_value(json_object_get(full, "porosity")), 0.38, 0);
    CHECK(!strcmp(json_string_value(json_object_get(full, "sieve_units")), "mm"));
    CHECK(json_object_get(full, "tiling") == NULL);
    json_decref(full);
    json_decref(j);
}

static void test_bad_2d(void)
{
    /* document level */
    {
        json_t *j = load("[1, 2]");
        gp_spec_problem p;
        CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "") && p.http_status == 400);
        json_decref(j);
        j = load("{\"seed\": 1}");
        CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/kind"));
        CHECK(strstr(p.message, "fourier-voronoi-2d") && strstr(p.message, "spheres-3d"));
        json_decref(j);
    }
    BAD2("/kind", "\"voronoi\"", "/kind", 400, "unknown kind \"voronoi\"; expected one of \"fourier-voronoi-2d\", \"spheres-3d\"");
    BAD2("/kind", "3", "/kind", 400, "unknown kind 3");
    BAD2("/colour", "1", "/colour", 400, "unknown field \"colour\"");
    BAD2("/seed", "-1", "/seed", 400, "expected an integer in [0, 9007199254740991], got -1");
    BAD2("/seed", "1.5", "/seed", 400, "got 1.5");
    BAD2("/seed", "\"7\"", "/seed", 400, "got \"7\"");
    BAD2("/particles", "0", "/particles", 400, "expected an integer in [1, 1000000], got 0");
    BAD2("/particles", "1000001", "/particles", 400, "got 1000001");
    BAD2("/particles", "true", "/particles", 400, "got true");
    BAD2("/particles", "null", "/particles", 400, "got null");
    BAD2("/size/cov", "\"abc\"", "/size/cov", 400, "/size/cov: expected a number in [0, 3], got \"abc\"");
    BAD2("/size/cov", "-0.1", "/size/cov", 400, "got -0.1");
    BAD2("/size/cov", "3.5", "/size/cov", 400, NULL);
    BAD2("/size/mean", "1", "/size/mean", 400, "unknown field \"mean\"; allowed here: law, cov, sieve, sieve_units, of");
    BAD2("/size", "0.8", "/size", 400, "expected an object, got 0.8");
    BAD2("/orientation/mean_deg", "91", "/orientation/mean_deg", 400, "[-90, 90]");
    BAD2("/orientation/anisotropy", "0", "/orientation/anisotropy", 400, "expected a number in (0, 1], got 0");
    BAD2("/orientation/anisotropy", "1.01", "/orientation/anisotropy", 400, NULL);
    BAD2("/shape/D2", "1", "/shape/D2", 400, "expected a number in [0, 1), got 1");
    BAD2("/shape/D3", "-0.01", "/shape/D3", 400, NULL);
    BAD2("/shape/D8", "\"x\"", "/shape/D8", 400, NULL);
    BAD2("/shape/alpha", "[]", "/shape/alpha", 400, "got an array of 0 items");
    BAD2("/shape/spectrum", "[1, 0.1, 0.2]", "/shape", 400, "expected a shape by descriptors");
    BAD2("/solid_fraction", "0", "/solid_fraction", 400, "expected a number in (0, 1], got 0");
    BAD2("/solid_fraction", "1.2", "/solid_fraction", 400, NULL);
    BAD2("/imc/error", "\"E4\"", "/imc/error", 400, "expected one of \"AD\", \"E1\", \"E2\", \"E3\", got \"E4\"");
    BAD2("/imc/threshold", "0", "/imc/threshold", 400, "expected a number > 0, got 0");
    BAD2("/imc/max_steps", "-5", "/imc/max_steps", 400, NULL);
    BAD2("/imc/max_steps", "10.5", "/imc/max_steps", 400, NULL);
    BAD2("/imc/init", "\"random\"", "/imc/init", 400, "\"uniform\", \"halton\"");
    BAD2("/imc/classes", "3", "/imc/classes", 400, "[4, 200]");
    BAD2("/imc/classes", "201", "/imc/classes", 400, NULL);
    BAD2("/imc/steps", "5", "/imc/steps", 400, "unknown field");
    BAD2("/contour_points", "15", "/contour_points", 400, "[16, 4096]");
    BAD2("/contour_points", "4097", "/contour_points", 400, NULL);
    BAD2("/outputs", "[]", "/outputs", 400, "at least 1 item,");
    BAD2("/outputs", "[\"grains\", \"voxels\"]", "/outputs/1", 400, "\"grains\", \"odec\", \"descriptors\", \"cells\"");
    BAD2("/outputs", "[\"grains\", \"cells\", \"grains\"]", "/outputs/2", 400, "duplicate");
    BAD2("/outputs", "\"grains\"", "/outputs", 400, "expected an array");
    /* container */
    BAD2("/container/polygon", "[[0,0],[1,0]]", "/container/polygon", 400, "at least 3 items, got 2");
    BAD2("/container/polygon/1", "[1]", "/container/polygon/1", 400, "exactly 2 items");
    BAD2("/container/polygon/1", "[1, \"a\"]", "/container/polygon/1/1", 400, "expected a number in [-1000000000, 1000000000], got \"a\"");
    BAD2("/container/polygon/1", "[1, 0, 0]", "/container/polygon/1", 400, NULL);
    BAD2("/container/polygon", "[[0,0],[1,1],[1,0],[0,1]]", "/container/polygon", 422, "not simple");
    BAD2("/container/polygon", "[[0,0],[1,1],[2,2]]", "/container/polygon", 422, "no area");
    BAD2("/container/polygon", "[[0,0],[2,0],[1,0],[1,1]]", "/container/polygon", 422, "not simple");
    BAD2("/container/holes", "[[[2,2],[3,2],[3,3]]]", "/container/holes/0", 422, "not inside");
    BAD2("/container/holes", "[[[0.5,0.5],[1.5,0.5],[0.5,0.6]]]", "/container/holes/0", 422, "crosses");
    BAD2("/container/holes", "[[[0.1,0.1],[0.9,0.1],[0.9,0.9],[0.1,0.9]], [[0.2,0.2],[0.3,0.2],[0.3,0.3]]]",
         "/container/holes/1", 422, "inside hole 0");
    BAD2("/container/holes", "[[[0.1,0.1],[0.2,0.1]]]", "/container/holes/0", 400, "at least 3");
    BAD2("/container/holes", "{}", "/container/holes", 400, "expected an array");
    BAD2("/container/circle", "{\"center\": [0, 0], \"radius\": 1}", "/container", 400,
         "expected a polygon container");
    BAD2("/container", "{\"circle\": {\"center\": [0, 0], \"radius\": 0}}", "/container/circle/radius",
         400, "expected a number in (0, 1000000000], got 0");
    BAD2("/container", "{\"circle\": {\"center\": [0, 0]}}", "/container/circle/radius", 400,
         "required field is missing");
    BAD2("/container", "{\"circle\": {\"center\": [0], \"radius\": 1}}", "/container/circle/center",
         400, "exactly 2 items");
    BAD2("/container", "{\"circle\": {\"center\": [0, 0], \"radius\": 1, \"r\": 1}}",
         "/container/circle/r", 400, "unknown field");
    BAD2("/container", "{}", "/container", 400, "expected a polygon container");
    BAD2("/container", "[]", "/container", 400, "or a circle container");
    BAD2("/container", "{\"holes\": []}", "/container/polygon", 400, "required field is missing");
    /* spectrum shape */
    BAD2("/shape", "{\"spectrum\": [1, 0.1]}", "/shape/spectrum", 400, "at least 3 items");
    BAD2("/shape", "{\"spectrum\": [0, 0.1, 0.2]}", "/shape/spectrum/0", 400, "> 0");
    BAD2("/shape", "{\"spectrum\": [1, 0.1, -0.2]}", "/shape/spectrum/2", 400, "≥ 0");
    json_t *j = patched(EX2D, "/shape", "{\"spectrum\": [1, 0.1, 0.2, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]}");
    gp_spec_problem p;
    CHECK(gp_spec_validate(j, &p) == 0);
    json_object_set_new(j, "contour_points", json_integer(16));
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/shape/spectrum") && p.http_status == 422);
    CHECK(strstr(p.message, "too many") != NULL);
    json_decref(j);
    /* good variants */
    GOOD2("/container", "{\"circle\": {\"center\": [0.5, -1e3], \"radius\": 2.5}}");
    GOOD2("/container/polygon", "[[0,0],[0,1],[1,1],[1,0]]"); /* clockwise */
    GOOD2("/container/polygon", "[[0,0],[2,0],[2,2],[1,1],[0,2]]"); /* non-convex */
    GOOD2("/particles", "500.0");
    /* any count with the default error AD (E3's 0.002 is below the floor of a few cells) */
    expect_good(MIN2D, "/particles", "1", __LINE__);
    expect_good(MIN2D, "/particles", "7.0", __LINE__);
    GOOD2("/imc/classes", "25");
    GOOD2("/outputs", "[\"cells\"]");
    GOOD2("/orientation/mean_deg", "-90");
    GOOD2("/size/cov", "0.01");
    GOOD2("/imc/max_steps", "0");
}

/* a sieve-law spec: 10-40 mm grains in the unit square (about two thousand grains) */
static const char *SV2D =
    "{\"kind\": \"fourier-voronoi-2d\", \"seed\": 3,"
    " \"size\": {\"law\": \"sieve\", \"sieve\": [[10, 0], [20, 50], [40, 100]]},"
    " \"contour_points\": 32}";
#define BADS(ptr, val, wptr, st, needle) expect_bad(SV2D, ptr, val, wptr, st, needle, __LINE__)
#define GOODS(ptr, val) expect_good(SV2D, ptr, val, __LINE__)

static void test_size_laws(void)
{
    /* cov: at least GP_LAW_COV_MIN for every law, each law's own maximum */
    BAD2("/size/cov", "0", "/size/cov", 422, "/size/cov: expected at least 0.01, got 0: equal sizes cannot be tessellated exactly; use 0.01");
    BAD2("/size/cov", "0.009", "/size/cov", 422, "equal sizes");
    BAD2("/size", "{\"law\": \"normal\", \"cov\": 0.005}", "/size/cov", 422, "at least 0.01");
    BAD2("/size", "{\"law\": \"uniform\", \"cov\": 0}", "/size/cov", 422, "at least 0.01");
    BAD2("/size", "{\"law\": \"normal\", \"cov\": 0.61}", "/size/cov", 422, "at most 0.6 for law \"normal\"");
    GOOD2("/size", "{\"law\": \"normal\"}"); /* the default cov 0.5 is within normal's 0.6 */
    BAD2("/size", "{\"law\": \"uniform\", \"cov\": 0.578}", "/size/cov", 422, "at most 0.5773 (1/√3) for law \"uniform\"");
    BAD2("/size", "{\"law\": \"uniform\", \"cov\": 0.8}", "/size/cov", 422, NULL);
    BAD2("/size/cov", "3.01", "/size/cov", 400, "[0, 3]");
    BAD2("/size/law", "\"gamma\"", "/size/law", 400, "\"lognormal\", \"normal\", \"uniform\", \"sieve\"");
    BAD2("/size/of", "\"pores\"", "/size/of", 400, "\"cells\", \"grains\"");
    GOOD2("/size", "{\"law\": \"normal\", \"cov\": 0.6}");
    GOOD2("/size", "{\"law\": \"uniform\", \"cov\": 0.5773}");
    GOOD2("/size", "{\"law\": \"lognormal\", \"cov\": 3}");
    GOOD2("/size", "{\"law\": \"normal\", \"cov\": 0.01, \"of\": \"grains\"}");
    /* sieve fields without law "sieve" */
    BAD2("/size/sieve", "[[1, 0], [2, 100]]", "/size/sieve", 422, "/size/sieve: only allowed with law \"sieve\" (the law here is \"lognormal\")");
    BAD2("/size/sieve_units", "\"m\"", "/size/sieve_units", 422, "only allowed with law \"sieve\"");
    BAD2("/size", "{\"law\": \"normal\", \"cov\": 0.2, \"sieve\": [[1, 0], [2, 100]]}", "/size/sieve", 422, "the law here is \"normal\"");

    /* what the parser fills */
    json_t *j = patched(EX2D, "/size", "{\"law\": \"uniform\", \"cov\": 0.3, \"of\": \"grains\"}");
    gp_spec2d s;
    gp_spec_problem p;
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.size_law == GP_LAW_UNIFORM && s.size_of_grains == 1 && s.particles == 500);
    CHECK_NEAR(s.cov, 0.3, 0);
    CHECK(s.nsieve == 0 && s.sieve_d == NULL);
    gp_spec2d_free(&s);
    json_t *full = gp_spec_with_defaults(j, &p);
    CHECK(full && json_object_get(json_object_get(full, "size"), "sieve_units") == NULL);
    json_decref(full);
    json_decref(j);
}

static void test_sieve_2d(void)
{
    json_t *j = load(SV2D);
    gp_spec_problem p;
    gp_spec2d s;
    CHECK(gp_spec_validate(j, &p) == 0);
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.size_law == GP_LAW_SIEVE);
    CHECK(s.particles == 0);          /* derived */
    CHECK(s.size_of_grains == 1);
    CHECK(s.nsieve == 3);
    CHECK_NEAR(s.sieve_d[0], 0.010, 1e-15); /* mm -> m */
    CHECK_NEAR(s.sieve_d[2], 0.040, 1e-15);
    CHECK_NEAR(s.sieve_pass[1], 50, 0);
    CHECK_NEAR(s.sieve_pass[2], 100, 0);
    double area = 0;
    size_t n = 0;
    CHECK(gp_spec2d_cell_count(&s, &area, &n, NULL) == GP_OK);
    CHECK_NEAR(area, 1, 1e-12);
    CHECK(n > 500 && n < 5000);
    gp_spec2d_free(&s);
    CHECK(s.sieve_d == NULL && s.sieve_pass == NULL);

    /* the effective spec invents neither particles nor cov; the sieve is a law of the grains */
    json_t *full = gp_spec_with_defaults(j, &p);
    CHECK(full != NULL);
    json_t *size = json_object_get(full, "size");
    CHECK(json_object_get(full, "particles") == NULL);
    CHECK(json_object_get(size, "cov") == NULL);
    CHECK(!strcmp(json_string_value(json_object_get(size, "of")), "grains"));
    CHECK(!strcmp(json_string_value(json_object_get(size, "sieve_units")), "mm"));
    CHECK(!strcmp(json_string_value(json_object_get(size, "law")), "sieve"));
    json_decref(full);
    json_decref(j);

    /* metres */
    j = patched(SV2D, "/size/sieve_units", "\"m\"");
    json_object_set_new(json_object_get(j, "size"), "sieve", load("[[0.01, 0], [0.02, 50], [0.04, 100]]"));
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK_NEAR(s.sieve_d[1], 0.02, 0);
    gp_spec2d_free(&s);
    json_decref(j);

    /* fields that a sieve law excludes or needs; particles is checked as posted */
    BADS("/particles", "100", "/particles", 422, "/particles: leave particles out with size.law \"sieve\": the number of grains follows from the container area and solid_fraction");
    BADS("/particles", "1", "/particles", 422, NULL);
    BADS("/size/cov", "0.5", "/size/cov", 422, "not allowed with law \"sieve\"");
    BADS("/size/sieve", NULL, "/size/sieve", 422, "required with law \"sieve\"");
    BADS("/size/of", "\"cells\"", "/size/of", 422, "a sieve curve is a law of the grains");
    GOODS("/size/of", "\"grains\"");
    GOODS("/size/sieve_units", "\"mm\"");
    GOODS("/container", "{\"circle\": {\"center\": [0, 0], \"radius\": 0.5}}");
    /* the rows: as spheres-3d's sieve */
    BADS("/size/sieve", "[[10, 0]]", "/size/sieve", 400, "at least 2");
    BADS("/size/sieve/1", "[20]", "/size/sieve/1", 400, "exactly 2");
    BADS("/size/sieve/1/1", "101", "/size/sieve/1/1", 400, "[0, 100]");
    BADS("/size/sieve/1/0", "0", "/size/sieve/1/0", 400, "> 0");
    BADS("/size/sieve/1/0", "10", "/size/sieve/1/0", 422, "/size/sieve/1/0: sieve diameters must increase strictly");
    BADS("/size/sieve/2/1", "40", "/size/sieve/2/1", 422, "must not decrease");
    BADS("/size/sieve/2/1", "99", "/size/sieve/2/1", 422, "the last sieve row must pass 100 %");
    BADS("/size/sieve/0/1", "5", "/size/sieve/0/1", 422, "must pass 0 %");
    BADS("/size/sieve_units", "\"cm\"", "/size/sieve_units", 400, "\"mm\", \"m\"");
    /* a grain larger than the container: the units are likely wrong */
    BADS("/size/sieve_units", "\"m\"", "/size/sieve/2/0", 422, "check sieve_units");
    /* a derived count beyond particles' maximum: 422 too_large */
    expect_bad_code(SV2D, "/size/sieve", "[[0.01, 0], [0.02, 100]]", "/size/sieve", 422,
                    "too_large", "over the limit of 1000000", __LINE__);
    /* a count too large even to compute (fine grains below coarse ones) */
    expect_bad_code(SV2D, "/size/sieve", "[[1e-9, 0], [10, 100]]", "/size/sieve", 422,
                    "too_large", "over the limit of 1000000", __LINE__);
}

/* the number in "use >= X" of a refusal */
static double suggested(const char *message)
{
    const char *u = strstr(message, "use >= ");
    return u ? strtod(u + 7, NULL) : -1;
}

static void test_imc_threshold(void)
{
    const char *e3 = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 20, \"imc\": {\"error\": \"E3\"}}";
    json_t *j = load(e3);
    gp_spec_problem p;
    gp_spec2d s;
    /* E3's default 0.002 is below the integer-count floor of 20 cells */
    CHECK(gp_spec_validate(j, &p) != 0);
    CHECK(p.http_status == 422 && !strcmp(p.code, "invalid_spec"));
    CHECK(!strcmp(p.pointer, "/imc/threshold"));
    CHECK(strncmp(p.message, "/imc/threshold: 0.002 is below the least error ", 47) == 0);
    CHECK(strstr(p.message, "20 cells") && strstr(p.message, "the default error AD"));
    CHECK(gp_spec2d_read(j, &s, &p) != 0 && !strcmp(p.pointer, "/imc/threshold"));
    gp_spec2d_free(&s);
    if (g_verbose) fprintf(stderr, "%s\n", p.message);
    /* the floor itself, as the core computes it */
    gp_imc_params q;
    gp_imc_params_default(&q);
    q.error_kind = 3;
    q.threshold = 0.002;
    double floor20 = gp_imc_reachable_threshold(&q, 20);
    CHECK(floor20 > 0.002);
    /* the suggested value is accepted, and so is the floor */
    double use = suggested(p.message);
    CHECK(use >= floor20 && use < floor20 * 1.01);
    json_object_set_new(json_object_get(j, "imc"), "threshold", json_real(use));
    CHECK(gp_spec_validate(j, &p) == 0);
    json_object_set_new(json_object_get(j, "imc"), "threshold", json_real(floor20));
    CHECK(gp_spec_validate(j, &p) == 0);
    json_object_set_new(json_object_get(j, "imc"), "threshold", json_real(floor20 * 0.99));
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/imc/threshold"));
    /* AD has no floor: any threshold > 0, and its default */
    json_object_set_new(json_object_get(j, "imc"), "error", json_string("AD"));
    json_object_set_new(json_object_get(j, "imc"), "threshold", json_real(1e-6));
    CHECK(gp_spec_validate(j, &p) == 0);
    json_object_del(json_object_get(j, "imc"), "threshold");
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.imc_error == GP_IMC_AD);
    CHECK_NEAR(s.imc_threshold, gp_imc_default_threshold(GP_IMC_ERROR_AD), 0);
    gp_spec2d_free(&s);
    json_decref(j);

    /* the threshold default follows the kind, and the effective spec shows it */
    const char *kinds[] = {"E1", "E2", "E3", "AD"};
    for (int k = 0; k < 4; k++) {
        j = load("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 500}");
        json_object_set_new(j, "imc", json_pack("{s:s}", "error", kinds[k]));
        json_t *full = gp_spec_with_defaults(j, &p);
        CHECK(full != NULL);
        double want = gp_imc_default_threshold(k < 3 ? k + 1 : GP_IMC_ERROR_AD);
        CHECK_NEAR(json_number_value(json_object_get(json_object_get(full, "imc"), "threshold")), want, 0);
        CHECK_NEAR(want, k < 3 ? 0.002 : gp_imc_default_threshold(GP_IMC_ERROR_AD), 0);
        CHECK(gp_spec2d_read(j, &s, &p) == 0 && (int)s.imc_error == (k < 3 ? k + 1 : GP_IMC_AD));
        gp_spec2d_free(&s);
        json_decref(full);
        json_decref(j);
    }
    /* the schema's description names the AD default */
    j = load(gp_schema_text("fourier-voronoi-2d"));
    const char *d = json_string_value(json_object_get(json_object_get(json_object_get(json_object_get(
        json_object_get(j, "properties"), "imc"), "properties"), "threshold"), "description"));
    char want[64];
    snprintf(want, sizeof want, "%g for AD", gp_imc_default_threshold(GP_IMC_ERROR_AD));
    CHECK(d && strstr(d, want) && strstr(d, "0.002 for E1-E3"));
    CHECK(json_object_get(json_object_get(json_object_get(json_object_get(
        json_object_get(j, "properties"), "imc"), "properties"), "threshold"), "default") == NULL);
    json_decref(j);

    /* with imc.classes the message names them */
    BAD2("/imc", "{\"error\": \"E1\", \"classes\": 12, \"threshold\": 0.002}", "/imc/threshold", 422,
         "500 cells can reach with E1 and 12 size x 12 orientation classes");
    /* a sieve law: the floor of the derived count (7 classes: a count that 7 does not divide
     * has a floor > 0) */
    j = load(SV2D);
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    double area;
    size_t n = 0;
    CHECK(gp_spec2d_cell_count(&s, &area, &n, NULL) == GP_OK);
    gp_spec2d_free(&s);
    q.error_kind = 2;
    q.threshold = 1e-9;
    q.classes_size = q.classes_orient = 7;
    CHECK(n % 7 != 0 && gp_imc_reachable_threshold(&q, n) > 1e-9);
    json_object_set_new(j, "imc", load("{\"error\": \"E2\", \"threshold\": 1e-9, \"classes\": 7}"));
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/imc/threshold"));
    char cells[64];
    snprintf(cells, sizeof cells, "%zu cells can reach with E2 and 7 size x 7", n);
    CHECK(strstr(p.message, cells) != NULL);
    json_decref(j);
}

/* numbers spelled as reals are the integers they denote */
static void test_real_spelling(void)
{
    json_t *j = load("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"contour_points\": 1.28e2}");
    gp_spec2d s;
    gp_spec_problem p;
    CHECK(gp_spec2d_read(j, &s, &p) == 0);
    CHECK(s.particles == 1000000);
    CHECK(s.contour_points == 128);
    gp_spec2d_free(&s);
    json_decref(j);
    BAD2("/particles", "1.0000001e6", "/particles", 400, "[1, 1000000]");
}

/* the effective spec is itself a valid spec with the same effective spec (the daemon stores
 * it and the worker parses it again) */
static void test_effective_idempotent(void)
{
    const char *specs[] = {EX2D, SV2D, "{\"kind\": \"fourier-voronoi-2d\"}",
                           "{\"kind\": \"fourier-voronoi-2d\", \"size\": {\"law\": \"normal\", \"cov\": 0.2}}",
                           "{\"kind\": \"fourier-voronoi-2d\", \"imc\": {\"error\": \"E2\"}, \"particles\": 400}"};
    for (size_t i = 0; i < sizeof specs / sizeof *specs; i++) {
        json_t *j = load(specs[i]);
        gp_spec_problem p;
        json_t *a = gp_spec_with_defaults(j, &p);
        CHECK(a != NULL);
        json_t *b = a ? gp_spec_with_defaults(a, &p) : NULL;
        if (a && !b) fprintf(stderr, "spec %zu: effective spec refused: %s\n", i, p.message);
        CHECK(b != NULL && json_equal(a, b));
        json_decref(a);
        json_decref(b);
        json_decref(j);
    }
}

static void test_bad_3d(void)
{
    BAD3("/kind", "\"spheres\"", "/kind", 400, "unknown kind");
    BAD3("/box", "[0.5, 0.5]", "/box", 400, "exactly 3 items, got 2");
    BAD3("/box/2", "0", "/box/2", 400, "> 0");
    BAD3("/box/1", "\"1\"", "/box/1", 400, NULL);
    BAD3("/sieve", "[[10, 0]]", "/sieve", 400, "at least 2");
    BAD3("/sieve/1", "[20]", "/sieve/1", 400, "exactly 2");
    BAD3("/sieve/1/1", "101", "/sieve/1/1", 400, "[0, 100]");
    BAD3("/sieve/1/0", "-20", "/sieve/1/0", 400, "> 0");
    BAD3("/sieve/2/0", "20", "/sieve/2/0", 422, "increase strictly");
    BAD3("/sieve/2/1", "1", "/sieve/2/1", 422, "must not decrease");
    BAD3("/sieve/4/1", "99", "/sieve/4/1", 422, "100");
    BAD3("/sieve/0/1", "1", "/sieve/0/1", 422, "0 %");
    BAD3("/sieve_units", "\"cm\"", "/sieve_units", 400, "\"mm\", \"m\"");
    BAD3("/sieve_units", "\"m\"", "/sieve/4/0", 422, "does not fit");
    BAD3("/porosity", "1", "/porosity", 400, "(0, 1)");
    BAD3("/porosity", "0", "/porosity", 400, NULL);
    BAD3("/material/density", "0", "/material/density", 400, "[100, 30000]");
    BAD3("/material/young", "-1", "/material/young", 400, NULL);
    BAD3("/material/poisson", "0.6", "/material/poisson", 400, "[0, 0.5]");
    BAD3("/material/friction_deg", "90", "/material/friction_deg", 400, NULL);
    BAD3("/material/damping", "1.5", "/material/damping", 400, NULL);
    BAD3("/material/colour", "1", "/material/colour", 400, "unknown field");
    BAD3("/tiling", "[4, 4]", "/tiling", 400, NULL);
    BAD3("/tiling/0", "0", "/tiling/0", 400, "[1, 16]");
    BAD3("/tiling/0", "1.5", "/tiling/0", 400, NULL);
    BAD3("/outputs", "[\"spheres\", \"grains\"]", "/outputs/1", 400, "\"spheres\", \"contacts\", \"fabric\", \"stress\"");
    BAD3("/outputs", "[\"stress\", \"stress\"]", "/outputs/1", 400, "duplicate");
    BAD3("/holes", "[]", "/holes", 400, "unknown field");
    GOOD3("/sieve_units", "\"mm\"");
    /* 1-2 um grains would fill the 0.5 m box with ~4e16 spheres: refused at submit (the DEM
     * sample takes 400,000 at most), not failed on a worker */
    expect_bad_code(EX3D, "/sieve", "[[0.001, 0], [0.002, 100]]", "/box", 422, "too_large",
                    "over the limit of 400000 spheres", __LINE__);
    GOOD3("/sieve", "[[10, 0], [20, 100]]"); /* ~40,000 spheres, 64 tiles */
    GOOD3("/tiling", NULL);

    /* a 3D spec is not a 2D spec */
    json_t *j = load(EX3D);
    gp_spec2d s;
    gp_spec_problem p;
    CHECK(gp_spec2d_read(j, &s, &p) != 0 && !strcmp(p.pointer, "/kind"));
    gp_spec2d_free(&s);
    json_decref(j);
}

static void test_pointer_escaping(void)
{
    json_t *j = load(EX2D);
    json_object_set_new(j, "a/b~c", json_integer(1));
    gp_spec_problem p;
    CHECK(gp_spec_validate(j, &p) != 0);
    CHECK(!strcmp(p.pointer, "/a~1b~0c"));
    json_decref(j);
}

static void test_documents(void)
{
    const char *doc = gp_schema_document();
    json_error_t e;
    json_t *j = json_loads(doc, 0, &e);
    CHECK(j != NULL);
    CHECK(json_array_size(json_object_get(j, "oneOf")) == 2);
    json_t *defs = json_object_get(j, "$defs");
    CHECK(json_is_object(json_object_get(defs, "fourier-voronoi-2d")));
    CHECK(json_is_object(json_object_get(defs, "spheres-3d")));
    CHECK(!strcmp(json_string_value(json_object_get(j, "$schema")),
                  "https://json-schema.org/draft/2020-12/schema"));
    json_decref(j);
    for (const char *const *k = gp_spec_kinds(); *k; k++) {
        const char *t = gp_schema_text(*k);
        CHECK(t != NULL);
        j = json_loads(t, 0, &e);
        CHECK(j != NULL);
        CHECK(!strcmp(json_string_value(json_object_get(json_object_get(json_object_get(j, "properties"), "kind"), "const")), *k));
        json_decref(j);
    }
    CHECK(gp_schema_text("nope") == NULL);
    CHECK(gp_spec_validate(NULL, NULL) != 0);
}

/* ---- issue #14: polygons checked in near-linear time, exactly ---- */

/* points (x, y) appended to a JSON array */
static void add_pt(json_t *a, double x, double y)
{
    json_array_append_new(a, json_pack("[f, f]", x, y));
}

/* A container of stacked zigzag rings that share their x range (the layout that made the
 * former pairwise check quadratic): the outer ring's left side a zigzag x = -10 + i % 2,
 * y = 10 i, i < 9998, right side at x = 11; nholes holes x = i % 2, y = y0 + i, i < 9995,
 * closed through (-5, y0 + 4997). cross: the last ring gets a spike through its own closing
 * edge. About 10,000 edges a ring. */
static json_t *stacked_spec(int nholes, int cross, size_t *edges)
{
    const int P = 10000;
    json_t *outer = json_array(), *holes = json_array();
    for (int i = 0; i <= P - 3; i++)
        add_pt(outer, (cross && nholes == 0 && i == P / 2 + 1) ? 16 : -10 + i % 2, 10.0 * i);
    add_pt(outer, 11, 10.0 * (P - 3));
    add_pt(outer, 11, 0);
    *edges = (size_t)P;
    for (int k = 0; k < nholes; k++) {
        json_t *h = json_array();
        double y0 = 100 + k * (P + 100.0);
        for (int i = 0; i <= P - 6; i++)
            add_pt(h, (cross && k == nholes - 1 && i == 4999) ? -6 : i % 2, y0 + i);
        add_pt(h, -5, y0 + 4997);
        *edges += json_array_size(h);
        json_array_append_new(holes, h);
    }
    return json_pack("{s:s, s:i, s:{s:o, s:o}}", "kind", "fourier-voronoi-2d", "particles", 100,
                     "container", "polygon", outer, "holes", holes);
}

static void test_polygon_sweep(void)
{
    /* 100,000 edges (a 1 MB body): accepted; the same with one crossing: refused at that ring
     * (bench/bench_validate times these) */
    size_t ne;
    json_t *j = stacked_spec(9, 0, &ne);
    gp_spec_problem p;
    CHECK(ne > 99900);
    int rc = gp_spec_validate(j, &p);
    if (rc) fprintf(stderr, "stacked zigzags refused: %s\n", p.message);
    CHECK(rc == 0);
    json_decref(j);
    j = stacked_spec(9, 1, &ne);
    CHECK(gp_spec_validate(j, &p) != 0 && p.http_status == 422 && !strcmp(p.code, "invalid_spec"));
    CHECK(!strcmp(p.pointer, "/container/holes/8") && strstr(p.message, "not simple"));
    json_decref(j);
    j = stacked_spec(0, 1, &ne);
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/container/polygon"));
    CHECK(strstr(p.message, "not simple: edge") != NULL);
    json_decref(j);
    /* the brief's zigzag: (i, i % 2), closed through a far point */
    json_t *z = json_array();
    for (int i = 0; i < 9999; i++) add_pt(z, i, i % 2);
    add_pt(z, 5000, -1e6);
    j = json_pack("{s:s, s:{s:o}}", "kind", "fourier-voronoi-2d", "container", "polygon", z);
    CHECK(gp_spec_validate(j, &p) == 0);
    /* a vertex pushed through the far point's edge */
    json_array_set_new(z, 4001, json_pack("[f, f]", 4001.0, -2e6));
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/container/polygon"));
    json_decref(j);

    /* touching is crossing, decided exactly */
    BAD2("/container/polygon", "[[0,0],[4,0],[4,4],[2,0],[0,4]]", "/container/polygon", 422,
         "crosses or touches"); /* a vertex on an edge */
    BAD2("/container/polygon", "[[0,0],[2,0],[1,1],[2,2],[0,2],[1,1]]", "/container/polygon", 422,
         "crosses or touches"); /* a figure 8: one point twice */
    BAD2("/container/polygon", "[[0,0],[2,0],[2,1],[3,1],[1,1],[0,1]]", "/container/polygon", 422,
         "not simple"); /* edges 2 and 3 run back over each other */
    BAD2("/container/polygon", "[[0,0],[2,0],[1,0],[1,1]]", "/container/polygon", 422,
         "not simple"); /* edges 0 and 1 */
    GOOD2("/container/polygon", "[[0,0],[1,0],[2,0],[2,1],[0,1]]"); /* collinear, same way */
    GOOD2("/container/polygon", "[[0,0],[4,0],[4,4],[2,1e-300],[0,4]]"); /* just above */
    GOOD2("/container/polygon", "[[0,0],[1e-9,0],[1e-9,1e-9],[0,1e-9]]");
    /* holes: touching the outer ring, each other, nested, outside */
    BAD2("/container/holes", "[[[0,0.5],[0.5,0.4],[0.5,0.6]]]", "/container/holes/0", 422,
         "of /container/polygon"); /* a vertex on the outer ring */
    BAD2("/container/holes", "[[[0.1,0.1],[0.4,0.1],[0.4,0.4]], [[0.4,0.4],[0.8,0.4],[0.8,0.8]]]",
         "/container/holes/1", 422, "of /container/holes/0"); /* a shared vertex */
    BAD2("/container/holes", "[[[0.2,0.2],[0.3,0.2],[0.3,0.3]], [[0.1,0.1],[0.9,0.1],[0.9,0.9],[0.1,0.9]]]",
         "/container/holes/0", 422, "inside hole 1"); /* the first one inside the second */
    BAD2("/container/holes",
         "[[[0.1,0.1],[0.9,0.1],[0.9,0.9],[0.1,0.9]], [[0.2,0.2],[0.8,0.2],[0.8,0.8],[0.2,0.8]], [[0.4,0.4],[0.6,0.4],[0.5,0.6]]]",
         "/container/holes/1", 422, "inside hole 0"); /* nested three deep */
    BAD2("/container/holes", "[[[0.1,0.1],[0.2,0.1],[0.2,0.2]], [[-1,-1],[3,-1],[3,3],[-1,3]]]",
         "/container/holes/0", 422, "inside hole 1"); /* a hole around the container */
    BAD2("/container/holes", "[[[-1,-1],[3,-1],[3,3],[-1,3]]]", "/container/holes/0", 422,
         "not inside");
    GOOD2("/container/holes", "[[[0.1,0.1],[0.2,0.1],[0.2,0.2]], [[0.8,0.8],[0.9,0.8],[0.9,0.9],[0.8,0.9]], [[0.5,0.1],[0.6,0.1],[0.55,0.5]]]");
    /* coordinates stay where the exact predicates are exact */
    BAD2("/container/polygon", "[[0,0],[1e10,0],[0,1]]", "/container/polygon/1/0", 400,
         "[-1000000000, 1000000000]");
}

/* ---- issue #14: work and result bounds, whatever the spelling of the numbers ---- */

static void expect_too_large(const char *base, const char *ptr, const char *value,
                             const char *want_ptr, const char *needle, int line)
{
    expect_bad_code(base, ptr, value, want_ptr, 422, "too_large", needle, line);
}

/* the bounds of a spec's effective spec */
static int bounds_of(const char *text, gp_spec_bounds_t *b)
{
    json_t *j = load(text);
    gp_spec_problem p;
    json_t *eff = gp_spec_with_defaults(j, &p);
    if (!eff) fprintf(stderr, "bounds_of: refused: %s\n", p.message);
    int rc = eff ? gp_spec_bounds(eff, b, &p) : -1;
    json_decref(eff);
    json_decref(j);
    return rc;
}

static void test_work_bounds_2d(void)
{
    gp_spec_bounds_t b;
    /* the defaults, the paper's example and a 10,000-grain specimen with every output: far
     * below the budget */
    CHECK(bounds_of(MIN2D, &b) == 0);
    CHECK(b.cells == 100 && b.items == 100 && b.steps == 1e6 && b.dt == 0);
    CHECK_NEAR(b.result_bytes, 100 * (400 + 40 * 128), 0);
    CHECK(!strcmp(b.result_pointer, "/particles"));
    CHECK(b.work_s < GP_SPEC_WORK_BUDGET_S / 100);
    CHECK(bounds_of(EX2D, &b) == 0 && b.cells == 500 && b.work_s < GP_SPEC_WORK_BUDGET_S / 100);
    json_t *j = patched(EX2D, "/particles", "10000");
    json_object_set_new(json_object_get(j, "imc"), "error", json_string("AD"));
    json_object_del(json_object_get(j, "imc"), "threshold");
    gp_spec_problem p;
    json_t *eff = gp_spec_with_defaults(j, &p);
    CHECK(eff != NULL);
    CHECK(eff && gp_spec_bounds(eff, &b, &p) == 0 && b.cells == 10000);
    CHECK(b.work_s < GP_SPEC_WORK_BUDGET_S / 100);
    if (g_verbose) fprintf(stderr, "10,000 grains: %.0f s, %.0f MB\n", b.work_s, b.result_bytes / 1e6);
    json_decref(eff);
    json_decref(j);
    expect_good(MIN2D, "/particles", "10000", __LINE__);
    expect_good(MIN2D, "/particles", "1e6", __LINE__); /* the schema's most, at the defaults */
    expect_good(MIN2D, "/imc/max_steps", "1e9", __LINE__); /* with 100 cells */

    /* every 2D maximum at once (~3 days) is over the budget, spelled either way */
    const char *most[] = {
        "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"imc\": {\"max_steps\": 1e9},"
        " \"contour_points\": 4.096e3, \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}",
        "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1000000, \"imc\": {\"max_steps\": 1000000000},"
        " \"contour_points\": 4096, \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}"};
    json_t *k;
    for (int i = 0; i < 2; i++) {
        k = load(most[i]);
        CHECK(gp_spec_validate(k, &p) != 0 && p.http_status == 422 && !strcmp(p.code, "too_large"));
        CHECK(!strcmp(p.pointer, "/imc/max_steps") && strstr(p.message, "over the budget of 172800 s"));
        json_decref(k);
    }
    /* each of them alone passes; so does the test suite's long job */
    expect_good(MIN2D, "/imc/max_steps", "1e9", __LINE__);
    k = load("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"contour_points\": 4.096e3,"
             " \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}");
    CHECK(gp_spec_validate(k, &p) == 0); /* the server's result bound refuses it (below) */
    json_decref(k);
    k = load("{\"kind\": \"fourier-voronoi-2d\", \"seed\": 7, \"particles\": 40000,"
             " \"imc\": {\"error\": \"E3\", \"threshold\": 1e-9, \"max_steps\": 1000000000},"
             " \"contour_points\": 64, \"outputs\": [\"grains\", \"odec\", \"descriptors\"]}");
    CHECK(gp_spec_validate(k, &p) == 0); /* tests/integration/gpd.py LONG_2D */
    json_decref(k);
    /* a 1 MB container makes each IMC move dear: its edges count, near each cell */
    size_t ne;
    k = stacked_spec(9, 0, &ne); /* 100 cells: accepted (above) */
    json_object_set_new(k, "particles", json_real(1e1)); /* 10 cells, 10,000 edges each */
    CHECK(gp_spec_validate(k, &p) != 0 && p.http_status == 422 && !strcmp(p.code, "too_large"));
    CHECK(!strcmp(p.pointer, "/container") && strstr(p.message, "99964 edges") &&
          strstr(p.message, "over the budget of 172800 s"));
    json_object_set_new(k, "imc", json_pack("{s:i}", "max_steps", 1000));
    CHECK(gp_spec_validate(k, &p) == 0); /* fewer moves: fine */
    json_decref(k);
    k = load("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 100, \"imc\": {\"max_steps\": 1e9}}");
    json_t *ring = json_array();
    for (int i = 0; i < 9998; i++) add_pt(ring, i, i % 2);
    add_pt(ring, 5000, -1e4);
    json_object_set_new(k, "container", json_pack("{s:o}", "polygon", ring));
    CHECK(gp_spec_validate(k, &p) != 0 && !strcmp(p.code, "too_large") && !strcmp(p.pointer, "/container"));
    gp_spec2d s2;
    gp_spec_problem q;
    CHECK(gp_spec2d_read(k, &s2, &q) != 0 && !strcmp(q.pointer, "/container")); /* the worker too */
    gp_spec2d_free(&s2);
    json_decref(k);

    /* the server's result bound (gp_spec_check_result, --max-result-mb 1024): the same
     * figure for 1e6 and 1000000 */
    const char *big[] = {"{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"contour_points\": 512}",
                         "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1000000, \"contour_points\": 512}"};
    for (int i = 0; i < 2; i++) {
        k = load(big[i]);
        eff = gp_spec_with_defaults(k, &p);
        CHECK(eff != NULL);
        CHECK(eff && gp_spec_check_result(eff, 1024e6, &p) != 0 && p.http_status == 422);
        CHECK(!strcmp(p.code, "too_large") && !strcmp(p.pointer, "/particles"));
        CHECK(strstr(p.message, "/particles: the result would be about 20880 MB (1000000 grains)") != NULL);
        CHECK(strstr(p.message, "--max-result-mb") != NULL);
        json_decref(eff);
        json_decref(k);
    }
    k = load(SV2D);
    eff = gp_spec_with_defaults(k, &p);
    CHECK(eff && gp_spec_check_result(eff, 1024e6, &p) == 0);
    CHECK(eff && gp_spec_check_result(eff, 1e3, &p) != 0 && !strcmp(p.pointer, "/size/sieve"));
    json_decref(eff);
    json_decref(k);
}

static void test_work_bounds_3d(void)
{
    const char *MIN3D = "{\"kind\": \"spheres-3d\"}";
    gp_spec_bounds_t b;
    /* the paper's example: 2,430 spheres, dt 8.32e-5 s (bench_spheres3d), far below budget */
    CHECK(bounds_of(MIN3D, &b) == 0);
    CHECK_REL(b.cells, 2430, 0.02);
    CHECK_REL(b.dt, 8.32e-5, 0.01);
    CHECK(b.items == b.cells);
    CHECK(b.work_s < GP_SPEC_WORK_BUDGET_S / 100);
    CHECK(!strcmp(b.result_pointer, "/box"));
    CHECK(bounds_of(EX3D, &b) == 0);
    CHECK_REL(b.items, 64 * 2430, 0.02);
    CHECK(!strcmp(b.result_pointer, "/tiling") && b.work_s < GP_SPEC_WORK_BUDGET_S / 100);
    if (g_verbose) fprintf(stderr, "paper 3D: %.0f spheres, %.3g steps, %.0f s\n", b.cells, b.steps, b.work_s);
    GOOD3("/material/young", "1e12"); /* diamond: ~1.6 M steps, still within the budget */
    GOOD3("/material/density", "100");

    /* young 1e25 made dt ~1e-14 s and the job ~50 days: out of the schema's range now, and
     * far over the work budget even without it */
    BAD3("/material/young", "1e25", "/material/young", 400, "[1000, 1000000000000]");
    json_t *j = load(MIN3D);
    gp_spec_problem p;
    json_t *eff = gp_spec_with_defaults(j, &p);
    CHECK(eff != NULL);
    json_object_set_new(json_object_get(eff, "material"), "young", json_real(1e25));
    CHECK(eff && gp_spec_bounds(eff, &b, &p) == 0);
    CHECK(b.work_s > 1e4 * GP_SPEC_WORK_BUDGET_S && b.dt < 1e-12);
    CHECK(!strcmp(b.work_pointer, "/material/young"));
    json_decref(eff);
    json_decref(j);
    /* in range, but a stiff material on many spheres: refused at the field that drives it */
    expect_good(MIN3D, "/material", "{\"young\": 1e11}", __LINE__); /* the paper's sieve: fine */
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[5, 0], [10, 100]], \"material\": {\"young\": 1e11}}");
    CHECK(gp_spec_validate(j, &p) != 0 && p.http_status == 422 && !strcmp(p.code, "too_large"));
    CHECK(!strcmp(p.pointer, "/material/young") && strstr(p.message, "over the budget of 172800 s"));
    json_decref(j);
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[5, 0], [10, 100]], \"material\": {\"young\": 1e10}}");
    CHECK(gp_spec_validate(j, &p) == 0); /* ~1.5 days */
    json_decref(j);
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[5, 0], [10, 100]], \"material\": {\"young\": 1.5e7, \"density\": 1e2}}");
    CHECK(gp_spec_validate(j, &p) == 0); /* the same sieve with a soft material */
    json_decref(j);
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[5, 0], [10, 100]], \"material\": {\"young\": 1e12, \"density\": 100}}");
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.code, "too_large"));
    CHECK(!strcmp(p.pointer, "/material/density") || !strcmp(p.pointer, "/material/young"));
    json_decref(j);

    /* counts: a 100 m box; a tiling past 20 million spheres */
    expect_too_large(MIN3D, "/box", "[100, 100, 100]", "/box", "spheres in the DEM sample", __LINE__);
    expect_too_large(MIN3D, "/box", "[1e2, 1e2, 1e2]", "/box", NULL, __LINE__);
    expect_bad_code(MIN3D, "/sieve_units", "\"m\"", "/sieve/4/0", 422, "invalid_spec", "does not fit",
                    __LINE__);
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[5, 0], [10, 100]], \"tiling\": [16, 16, 16]}");
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.code, "too_large") && !strcmp(p.pointer, "/tiling"));
    json_decref(j);

    /* physical ranges */
    BAD3("/material/young", "500", "/material/young", 400, NULL);
    BAD3("/material/young", "1e300", "/material/young", 400, NULL);
    BAD3("/material/density", "50", "/material/density", 400, NULL);
    BAD3("/material/density", "1e300", "/material/density", 400, NULL);
    BAD3("/material/friction_deg", "89.5", "/material/friction_deg", 400, "[0, 89]");
    BAD3("/material/damping", "1", "/material/damping", 400, "[0, 1)");
    GOOD3("/material/friction_deg", "89");
    GOOD3("/material/damping", "0.99");

    /* the result bound: the 4 x 4 x 4 example fits 1024 MB; 16 x 16 x 16 tiles of it (10
     * million spheres, within the tiling limit) with contacts do not */
    j = load(EX3D);
    eff = gp_spec_with_defaults(j, &p);
    CHECK(eff && gp_spec_check_result(eff, 1024e6, &p) == 0);
    json_decref(eff);
    json_object_set_new(j, "tiling", json_pack("[i, i, i]", 16, 16, 16));
    eff = gp_spec_with_defaults(j, &p);
    CHECK(eff != NULL);
    CHECK(eff && gp_spec_check_result(eff, 1024e6, &p) != 0 && !strcmp(p.code, "too_large"));
    CHECK(!strcmp(p.pointer, "/tiling") && strstr(p.message, "spheres") != NULL);
    json_decref(eff);
    json_decref(j);
}

/* seeds are placed by rejection in the container's bounding box: n / fill draws. The issue's
 * sliver fills 1e-8 of its box (area 1e-8 over a unit box): 10 seeds, 1e9 draws, refused; a
 * sliver of fill 1e-6 holds 10 seeds (1e7 draws) but not 200 (2e8) */
static void test_seed_draws(void)
{
    const char *B = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 10}";
    expect_bad_code(B, "/container", "{\"polygon\": [[0,0],[1,1],[1,1.00000002]]}",
                    "/container/polygon", 422, "invalid_spec", "fills 1e-08 of its bounding box",
                    __LINE__);
    json_t *doc = patched(B, "/container", "{\"polygon\": [[0,0],[1,1],[1,1.000002]]}");
    gp_spec_problem p;
    CHECK(gp_spec_validate(doc, &p) == 0);
    json_decref(doc);
    const char *B200 = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 200}";
    expect_bad_code(B200, "/container", "{\"polygon\": [[0,0],[1,1],[1,1.000002]]}",
                    "/container/polygon", 422, "invalid_spec", "about 2e+08 draws", __LINE__);
    /* a hole that leaves a thin frame: the fill counts the holes out */
    expect_bad_code(B, "/container",
                    "{\"polygon\": [[0,0],[1,0],[1,1],[0,1]], \"holes\": "
                    "[[[1e-9,1e-9],[1e-9,0.999999999],[0.999999999,0.999999999],"
                    "[0.999999999,1e-9]]]}",
                    "/container/polygon", 422, "invalid_spec", "bounding box", __LINE__);
}

int main(int argc, char **argv)
{
    g_verbose = argc > 1;
    test_examples();
    test_defaults();
    test_bad_2d();
    test_size_laws();
    test_sieve_2d();
    test_imc_threshold();
    test_real_spelling();
    test_effective_idempotent();
    test_bad_3d();
    test_pointer_escaping();
    test_documents();
    test_polygon_sweep();
    test_work_bounds_2d();
    test_work_bounds_3d();
    test_seed_draws();
    return gp_test_summary();
}
