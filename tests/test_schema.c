/* test_schema.c -- the spec validator: pointers and messages of bad specs, api.md's examples,
 * defaults, semantic checks, the combined schema document. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

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
static void expect_bad(const char *base, const char *ptr, const char *value,
                       const char *want_ptr, int want_status, const char *needle, int line)
{
    json_t *doc = patched(base, ptr, value);
    gp_spec_problem p;
    int rc = gp_spec_validate(doc, &p);
    int ok = rc != 0 && !strcmp(p.pointer, want_ptr) && p.http_status == want_status &&
             !strcmp(p.code, "invalid_spec") && (!needle || strstr(p.message, needle));
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
        CHECK(gp_spec_parse_2d(doc, &s, &q) != 0);
        CHECK(!strcmp(q.pointer, p.pointer));
        gp_spec_2d_free(&s);
    }
    json_decref(doc);
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
    CHECK(gp_spec_parse_2d(j, &s, &p) == 0);
    CHECK(s.seed == 42);
    CHECK(s.container == GP_CONTAINER_POLYGON);
    CHECK(s.outer.n == 4);
    CHECK_NEAR(s.outer.pts[2].x, 1, 0);
    CHECK_NEAR(s.outer.pts[2].y, 1, 0);
    CHECK(s.nholes == 0);
    CHECK(s.particles == 500);
    CHECK_NEAR(s.cov, 0.8, 0);
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
    CHECK(s.outputs == (GP_OUT_GRAINS | GP_OUT_ODEC | GP_OUT_DESCRIPTORS | GP_OUT_CELLS));
    gp_spec_2d_free(&s);
    CHECK(s.outer.pts == NULL);
    json_decref(j);

    j = load(EX3D);
    CHECK(gp_spec_validate(j, &p) == 0);
    json_t *full = gp_spec_with_defaults(j, &p);
    CHECK(full != NULL);
    CHECK(json_equal(full, j)); /* every field was given */
    json_decref(full);
    gp_spec3d t;
    CHECK(gp_spec_parse_3d(j, &t, &p) == 0);
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
    gp_spec_3d_free(&t);
    CHECK(t.sieve == NULL);
    json_decref(j);

    /* defaults and metres */
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[0.001, 0], [0.002, 100]], \"sieve_units\": \"m\"}");
    CHECK(gp_spec_parse_3d(j, &t, &p) == 0);
    CHECK_NEAR(t.sieve[1].diameter, 0.002, 0);
    CHECK(t.tiling[0] == 1 && t.tiling[1] == 1 && t.tiling[2] == 1);
    CHECK(t.outputs == GP_OUT3_SPHERES);
    CHECK_NEAR(t.box[1], 0.5, 0);
    gp_spec_3d_free(&t);
    json_decref(j);
    /* a 2D spec is not a 3D one */
    j = load(EX2D);
    CHECK(gp_spec_parse_3d(j, &t, &p) != 0 && !strcmp(p.pointer, "/kind"));
    gp_spec_3d_free(&t);
    json_decref(j);
    j = load("{\"kind\": \"spheres-3d\", \"porosity\": 2}");
    CHECK(gp_spec_parse_3d(j, &t, &p) != 0 && !strcmp(p.pointer, "/porosity"));
    gp_spec_3d_free(&t);
    json_decref(j);
}

static void test_defaults(void)
{
    json_t *j = load("{\"kind\": \"fourier-voronoi-2d\"}");
    gp_spec_problem p;
    gp_spec2d s;
    CHECK(gp_spec_parse_2d(j, &s, &p) == 0);
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
    CHECK(s.imc_error == GP_IMC_E3);
    CHECK_NEAR(s.imc_threshold, 0.002, 0);
    CHECK(s.imc_max_steps == 1000000);
    CHECK(s.imc_init == GP_INIT_UNIFORM);
    CHECK(s.contour_points == 128);
    CHECK(s.outputs == GP_OUT_GRAINS);
    CHECK(s.threads == 0);
    gp_spec_2d_free(&s);

    json_t *full = gp_spec_with_defaults(j, &p);
    CHECK(full && json_is_object(json_object_get(full, "imc")));
    CHECK(!strcmp(json_string_value(json_object_get(json_object_get(full, "imc"), "error")), "E3"));
    CHECK(json_object_get(json_object_get(full, "imc"), "classes") == NULL);
    CHECK(json_array_size(json_object_get(json_object_get(full, "container"), "polygon")) == 4);
    json_decref(full);
    json_decref(j);

    /* partial objects get their missing members */
    j = load("{\"kind\": \"fourier-voronoi-2d\", \"imc\": {\"error\": \"E1\", \"classes\": 12},"
             " \"shape\": {\"D2\": 0.3}, \"container\": {\"circle\": {\"center\": [1, 2], \"radius\": 3}},"
             " \"seed\": 5.0}");
    CHECK(gp_spec_parse_2d(j, &s, &p) == 0);
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
    gp_spec_2d_free(&s);
    json_decref(j);

    /* spectrum */
    j = load("{\"kind\": \"fourier-voronoi-2d\", \"shape\": {\"spectrum\": [1, 0, 0.2, 0.05, 0.01]}}");
    CHECK(gp_spec_parse_2d(j, &s, &p) == 0);
    CHECK(s.has_spectrum && s.nspectrum == 5);
    CHECK_NEAR(s.spectrum[2], 0.2, 0);
    gp_spec_2d_free(&s);
    json_decref(j);

    /* a hole, a closing point that repeats the first */
    j = load("{\"kind\": \"fourier-voronoi-2d\", \"container\": {\"polygon\": [[0,0],[4,0],[4,4],[0,4],[0,0]],"
             " \"holes\": [[[1,1],[1,2],[2,2],[2,1]], [[3,3],[3.5,3],[3.5,3.5]]]}}");
    CHECK(gp_spec_parse_2d(j, &s, &p) == 0);
    CHECK(s.outer.n == 4 && s.nholes == 2 && s.holes[0].n == 4 && s.holes[1].n == 3);
    gp_spec_2d_free(&s);
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
    BAD2("/size/mean", "1", "/size/mean", 400, "unknown field \"mean\"; allowed here: cov");
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
    BAD2("/imc/error", "\"E4\"", "/imc/error", 400, "expected one of \"E1\", \"E2\", \"E3\", got \"E4\"");
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
    BAD2("/container/polygon/1", "[1, \"a\"]", "/container/polygon/1/1", 400, "expected a number, got \"a\"");
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
         400, "expected a number > 0, got 0");
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
    GOOD2("/particles", "1");
    GOOD2("/particles", "7.0");
    GOOD2("/imc/classes", "25");
    GOOD2("/outputs", "[\"cells\"]");
    GOOD2("/orientation/mean_deg", "-90");
    GOOD2("/size/cov", "0");
    GOOD2("/imc/max_steps", "0");
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
    BAD3("/material/density", "0", "/material/density", 400, "> 0");
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
    GOOD3("/sieve", "[[0.001, 0], [0.002, 100]]");
    GOOD3("/tiling", NULL);

    /* a 3D spec is not a 2D spec */
    json_t *j = load(EX3D);
    gp_spec2d s;
    gp_spec_problem p;
    CHECK(gp_spec_parse_2d(j, &s, &p) != 0 && !strcmp(p.pointer, "/kind"));
    gp_spec_2d_free(&s);
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

int main(int argc, char **argv)
{
    g_verbose = argc > 1;
    test_examples();
    test_defaults();
    test_bad_2d();
    test_bad_3d();
    test_pointer_escaping();
    test_documents();
    return gp_test_summary();
}
