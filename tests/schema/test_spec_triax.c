/* test_spec_triax.c -- the spec of kind triaxial-3d (schema/kinds/triaxial-3d/): every refusal
 * with its pointer and code (the schema's ranges, the specimen as a spheres-3d spec at
 * /specimen/spec/..., part "tiled" of an untiled specimen, an unresolved job, the work budget at
 * the field that drives it, the result bound), the defaults, the reader of an effective spec and
 * the parameters of a test. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_spec.h"
#include "gp_test.h"
#include "gp_spec_specimen.h"
#include "schema/spec_patch.h"
#include "kinds/triaxial-3d/gp_spec_triax.h"

/* the contract's example with the paper's sample inline */
static const char EX[] =
    "{\"kind\": \"triaxial-3d\", \"seed\": 7,"
    " \"specimen\": {\"spec\": {\"kind\": \"spheres-3d\", \"seed\": 7, \"box\": [0.5, 0.5, 0.5],"
    " \"sieve\": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], \"sieve_units\": \"mm\","
    " \"porosity\": 0.38, \"tiling\": [2, 2, 2]}, \"part\": \"sample\"},"
    " \"confining_kpa\": [50, 100], \"axial_strain\": 0.2, \"strain_rate\": 0.01,"
    " \"drainage\": \"drained\", \"outputs\": [\"curves\", \"spheres\"]}";

/* the least spec: a small specimen inline, everything else by default */
static const char MIN[] =
    "{\"kind\": \"triaxial-3d\", \"specimen\": {\"spec\": {\"box\": [0.006, 0.006, 0.006],"
    " \"sieve\": [[1, 0], [2, 100]], \"porosity\": 0.5}}}";

static const char JOB[] = "0123456789abcdef0123456789abcdef";

#define BAD(ptr, val, wptr, needle) bad(EX, ptr, val, wptr, "invalid_spec", needle, HERE)
#define TOO_LARGE(base, ptr, val, wptr) bad(base, ptr, val, wptr, "too_large", NULL, HERE)
#define GOOD(ptr, val) good(EX, ptr, val, HERE)

/* the schema's ranges, field by field */
static void test_ranges(void)
{
    BAD("/confining_kpa", "[]", "/confining_kpa", "at least 1");
    BAD("/confining_kpa", "[50, 100, 150, 200, 250, 300]", "/confining_kpa", NULL);
    BAD("/confining_kpa", "[0]", "/confining_kpa/0", NULL);
    BAD("/confining_kpa", "[50, -5]", "/confining_kpa/1", NULL);
    BAD("/confining_kpa", "[10000.5]", "/confining_kpa/0", NULL);
    BAD("/confining_kpa", "[\"50\"]", "/confining_kpa/0", NULL);
    BAD("/confining_kpa", "[50, 50]", "/confining_kpa/1", "duplicate");
    BAD("/confining_kpa", "50", "/confining_kpa", NULL);
    GOOD("/confining_kpa", "[10000]");
    GOOD("/confining_kpa", "[1e-3, 1, 10, 100, 1e4]");
    BAD("/axial_strain", "0", "/axial_strain", NULL);
    BAD("/axial_strain", "-0.1", "/axial_strain", NULL);
    BAD("/axial_strain", "0.5000001", "/axial_strain", NULL);
    GOOD("/axial_strain", "0.5");
    BAD("/strain_rate", "0", "/strain_rate", NULL);
    BAD("/strain_rate", "-1", "/strain_rate", NULL);
    BAD("/strain_rate", "10.5", "/strain_rate", NULL);
    BAD("/strain_rate", "null", "/strain_rate", NULL);
    GOOD("/strain_rate", "10");
    BAD("/drainage", "\"undrained\"", "/drainage", NULL);
    GOOD("/drainage", "\"constant_volume\"");
    BAD("/outputs", "[]", "/outputs", NULL);
    BAD("/outputs", "[\"contacts\"]", "/outputs/0", NULL);
    BAD("/outputs", "[\"curves\", \"curves\"]", "/outputs/1", "duplicate");
    BAD("/material/young", "10", "/material/young", NULL);
    BAD("/material/friction_deg", "90", "/material/friction_deg", NULL);
    BAD("/material/damping", "1", "/material/damping", NULL);
    BAD("/material/colour", "1", "/material/colour", NULL);
    GOOD("/material/friction_deg", "30");
    BAD("/seed", "-1", "/seed", NULL);
    BAD("/extra", "1", "/extra", NULL);
    BAD("/specimen", NULL, "/specimen", NULL);
    BAD("/kind", "\"triaxial\"", "/kind", "unknown kind");
}

/* the specimen: a job or a spheres-3d spec, its part */
static void test_specimen(void)
{
    BAD("/specimen", "{}", "/specimen", "\"job\"");
    BAD("/specimen", "{\"part\": \"sample\"}", "/specimen", NULL);
    BAD("/specimen", "[]", "/specimen", NULL);
    BAD("/specimen/job", "\"abc\"", "/specimen/job", NULL);
    BAD("/specimen/job", "7", "/specimen/job", NULL);
    /* a job alone: only the daemon resolves it */
    char sp[128];
    snprintf(sp, sizeof sp, "{\"job\": \"%s\"}", JOB);
    BAD("/specimen", sp, "/specimen/job", "not resolved");
    BAD("/specimen/part", "\"all\"", "/specimen/part", NULL);
    BAD("/specimen/other", "1", "/specimen/other", NULL);
    BAD("/specimen/spec", "[]", "/specimen/spec", NULL);
    /* the inline spec is a spheres-3d spec: its problems at /specimen/spec/... */
    BAD("/specimen/spec/box/0", "0", "/specimen/spec/box/0", NULL);
    BAD("/specimen/spec/porosity", "2", "/specimen/spec/porosity", NULL);
    BAD("/specimen/spec/sieve/1/0", "5", "/specimen/spec/sieve/1/0", "increase strictly");
    BAD("/specimen/spec/sieve_units", "\"m\"", "/specimen/spec/sieve/4/0", "does not fit");
    BAD("/specimen/spec/material/young", "1", "/specimen/spec/material/young", NULL);
    BAD("/specimen/spec/colour", "1", "/specimen/spec/colour", "unknown field");
    BAD("/specimen/spec/kind", "\"fourier-voronoi-2d\"", "/specimen/spec/kind", "spheres-3d");
    BAD("/specimen/spec/kind", "3", "/specimen/spec/kind", NULL);
    /* the message names the whole pointer once */
    json_t *doc = patched(EX, "/specimen/spec/porosity", "2");
    gp_spec_problem p;
    CHECK(gp_spec_validate(doc, &p) != 0);
    CHECK(!strncmp(p.message, "/specimen/spec/porosity: expected", 33));
    CHECK(strstr(p.message + 1, "/specimen/spec/porosity") == NULL);
    json_decref(doc);
    /* its own limits, as its own */
    TOO_LARGE(EX, "/specimen/spec/box", "[5, 5, 5]", "/specimen/spec/box");
    /* part tiled needs a tiling */
    doc = patched(EX, "/specimen/spec/tiling", NULL);
    json_object_set_new(json_object_get(doc, "specimen"), "part", json_string("tiled"));
    CHECK(gp_spec_validate(doc, &p) != 0 && !strcmp(p.pointer, "/specimen/part") &&
          !strcmp(p.code, "invalid_spec") && strstr(p.message, "not tiled"));
    json_decref(doc);
    good(EX, "/specimen/spec/tiling", "[1, 1, 1]", HERE);
    good(EX, "/specimen/part", "\"tiled\"", HERE); /* 8 tiles of ~3,600 spheres */
    /* 4,096 tiles: within the tiling's limit, over the spheres a test runs on */
    doc = patched(EX, "/specimen/spec/tiling", "[16, 16, 16]");
    json_object_set_new(json_object_get(doc, "specimen"), "part", json_string("tiled"));
    CHECK(gp_spec_validate(doc, &p) != 0 && !strcmp(p.pointer, "/specimen/part") &&
          !strcmp(p.code, "too_large") && strstr(p.message, "test the sample"));
    json_decref(doc);
    good(MIN, "/specimen/spec/tiling", "[2, 2, 1]", HERE);
    json_t *full = effective(MIN, "/specimen/spec/tiling", "[2, 2, 1]");
    json_object_set_new(json_object_get(full, "specimen"), "part", json_string("tiled"));
    CHECK(gp_spec_validate(full, &p) == 0);
    json_decref(full);
    /* the resolved form: the job beside its spec, kept */
    doc = patched(EX, "/specimen/job", "\"0123456789abcdef0123456789abcdef\"");
    full = gp_spec_with_defaults(doc, &p);
    CHECK(full && !strcmp(json_string_value(json_object_get(json_object_get(full, "specimen"),
                                                            "job")), JOB));
    json_decref(full);
    json_decref(doc);
}

/* the work budget at the field that drives it, and the result bound */
static void test_bounds(void)
{
    /* a slow rate */
    TOO_LARGE(EX, "/strain_rate", "1e-6", "/strain_rate");
    /* a stiff material's time step */
    TOO_LARGE(EX, "/material/young", "1e12", "/material/young");
    /* 1-2 mm spheres (a short time step) in a 5 cm box (~40,000 spheres): each test is
     * within the budget alone, five are not */
    char big[400];
    snprintf(big, sizeof big, "{\"kind\": \"triaxial-3d\", \"specimen\": {\"spec\": {\"box\": "
             "[0.05, 0.05, 0.05], \"sieve\": [[1, 0], [2, 100]], \"porosity\": 0.4}}, "
             "\"confining_kpa\": [50]}");
    gp_spec_problem p;
    gp_spec_bounds_t b;
    json_t *full = effective(big, "/seed", "1");
    CHECK(full && gp_spec_bounds(full, &b, &p) == 0);
    if (full) fprintf(stderr, "one test of %.0f spheres: %.3g s (%.3g steps)\n", b.items,
                      b.work_s, b.steps);
    CHECK(full && b.work_s > GP_SPEC_WORK_BUDGET_S / 5 && b.work_s < GP_SPEC_WORK_BUDGET_S);
    json_decref(full);
    TOO_LARGE(big, "/confining_kpa", "[25, 50, 100, 200, 400]", "/confining_kpa");
    /* larger, one test is over: the specimen drives it (its spec, or its job once resolved) */
    TOO_LARGE(big, "/specimen/spec/box", "[0.1, 0.1, 0.1]", "/specimen/spec/box");
    json_t *doc = patched(big, "/specimen/spec/box", "[0.1, 0.1, 0.1]");
    json_object_set_new(json_object_get(doc, "specimen"), "job", json_string(JOB));
    CHECK(gp_spec_validate(doc, &p) != 0 && !strcmp(p.pointer, "/specimen/job") &&
          !strcmp(p.code, "too_large") && strstr(p.message, "smaller specimen"));
    json_decref(doc);
    /* the result bound: the spheres' output */
    full = effective(EX, "/confining_kpa", "[50]");
    CHECK(full && gp_spec_check_result(full, 1e9, &p) == 0);
    CHECK(full && gp_spec_check_result(full, 1e5, &p) != 0 && !strcmp(p.code, "too_large") &&
          !strcmp(p.pointer, "/outputs") && strstr(p.message, "--max-result-mb"));
    json_decref(full);
    full = effective(EX, "/outputs", "[\"curves\"]");
    CHECK(full && gp_spec_check_result(full, 1e6, &p) == 0);
    json_decref(full);
    /* the bounds: the sample's spheres, or the tiling's */
    full = effective(EX, "/specimen/part", "\"sample\"");
    CHECK(full && gp_spec_bounds(full, &b, &p) == 0);
    fprintf(stderr, "the paper's tests: %.0f spheres, %.3g steps, %.3g s\n", b.cells, b.steps,
            b.work_s);
    CHECK(b.items == b.cells && b.cells > 2000 &&
          b.cells < 5000 && b.steps > 0 && b.work_s > 0 && b.work_s < GP_SPEC_WORK_BUDGET_S);
    json_decref(full);
}

/* the defaults, and the effective spec is its own */
static void test_defaults(void)
{
    json_t *full = effective(MIN, "/seed", "5");
    CHECK(full != NULL);
    if (!full) return;
    const json_t *sp = json_object_get(full, "specimen");
    const json_t *in = json_object_get(sp, "spec");
    CHECK(!strcmp(json_string_value(json_object_get(sp, "part")), "sample"));
    CHECK(json_object_get(sp, "job") == NULL);
    CHECK(!strcmp(json_string_value(json_object_get(in, "kind")), "spheres-3d"));
    CHECK(json_integer_value(json_object_get(in, "seed")) == 5); /* the test's seed */
    CHECK(json_number_value(json_object_get(in, "porosity")) == 0.5);
    CHECK(json_object_get(in, "material") != NULL); /* its own defaults */
    json_t *conf = json_object_get(full, "confining_kpa");
    CHECK(json_array_size(conf) == 2 && json_number_value(json_array_get(conf, 0)) == 50 &&
          json_number_value(json_array_get(conf, 1)) == 100);
    CHECK(json_number_value(json_object_get(full, "axial_strain")) == 0.2);
    CHECK(json_number_value(json_object_get(full, "strain_rate")) == 0.01);
    CHECK(!strcmp(json_string_value(json_object_get(full, "drainage")), "drained"));
    json_t *out = json_object_get(full, "outputs");
    CHECK(json_array_size(out) == 2 &&
          !strcmp(json_string_value(json_array_get(out, 0)), "curves") &&
          !strcmp(json_string_value(json_array_get(out, 1)), "spheres"));
    CHECK(json_object_get(full, "material") == NULL); /* no overrides */
    gp_spec_problem p;
    json_t *again = gp_spec_with_defaults(full, &p);
    CHECK(again && json_equal(again, full));
    json_decref(again);
    json_decref(full);
    /* an inline spec's own seed stays */
    full = effective(MIN, "/specimen/spec/seed", "9");
    CHECK(full && json_integer_value(json_object_get(
                      json_object_get(json_object_get(full, "specimen"), "spec"), "seed")) == 9);
    json_decref(full);
}

/* the reader of an effective spec, and a test's parameters */
static void test_reader(void)
{
    json_t *full = effective(EX, "/material/friction_deg", "30");
    gp_spec_triax s;
    gp_spec_problem p;
    CHECK(full && gp_spec_triax_read(full, &s, &p) == 0);
    if (!full) return;
    CHECK(s.seed == 7 && s.ntests == 2 && s.confining[0] == 50e3 && s.confining[1] == 100e3);
    CHECK(s.axial_strain == 0.2 && s.strain_rate == 0.01 && s.drainage == GP_TRIAX_DRAINED);
    CHECK(s.outputs == (GP_OUT_TRIAX_CURVES | GP_OUT_TRIAX_SPHERES));
    CHECK(!s.tiled && s.job[0] == '\0');
    /* the sample: built without its tiling, spheres only */
    CHECK(s.specimen.tiling[0] == 1 && s.specimen.tiling[1] == 1 && s.specimen.tiling[2] == 1);
    CHECK(s.specimen.outputs == GP_OUT3_SPHERES && s.specimen.seed == 7);
    CHECK_NEAR(s.specimen.sieve[0].diameter, 0.01, 1e-15);
    /* the override is the test's, the specimen keeps its own material */
    CHECK(s.material.friction_deg == 30 && s.specimen.material.friction_deg == 18);
    CHECK(s.material.young == 15e6 && s.material.damping == 0.2);
    CHECK_NEAR(s.d50, 0.05, 1e-12);
    CHECK_NEAR(s.r_min, 0.005, 1e-15);
    gp_triax_params tp;
    s.threads = 3;
    gp_spec_triax_params(&s, 1, &tp);
    CHECK(tp.confining == 100e3 && tp.axial_strain == 0.2 && tp.strain_rate == 0.01);
    CHECK(tp.samples == GP_SPEC_TRIAX_SAMPLES && tp.threads == 3 && tp.d50 == s.d50);
    CHECK(tp.max_steps > 0 && tp.max_steps == gp_triax_estimate_steps(&s.material, s.r_min, &tp));
    gp_spec_triax_free(&s);
    json_decref(full);
    /* the tiled part keeps the tiling; constant volume; another kind is refused at /kind */
    full = effective(MIN, "/specimen/spec/tiling", "[2, 1, 1]");
    json_object_set_new(json_object_get(full, "specimen"), "part", json_string("tiled"));
    json_object_set_new(full, "drainage", json_string("constant_volume"));
    CHECK(gp_spec_triax_read(full, &s, &p) == 0 && s.tiled && s.specimen.tiling[0] == 2 &&
          s.drainage == GP_TRIAX_CONSTANT_VOLUME);
    gp_spec_triax_free(&s);
    json_object_set_new(full, "kind", json_string("spheres-3d"));
    CHECK(gp_spec_triax_read(full, &s, &p) != 0 && !strcmp(p.pointer, "/kind"));
    gp_spec_triax_free(&s);
    json_decref(full);
    /* not an effective spec: "internal" at the field */
    full = load(EX);
    CHECK(gp_spec_triax_read(full, &s, &p) != 0 && !strcmp(p.code, "internal"));
    gp_spec_triax_free(&s);
    json_decref(full);
    CHECK(!strcmp(gp_spec_specimen_kind(), "spheres-3d"));
}

/* the kind is in the served document */
static void test_document(void)
{
    json_t *j = load(gp_schema_document());
    CHECK(json_is_object(json_object_get(json_object_get(j, "$defs"), "triaxial-3d")));
    json_decref(j);
    CHECK(gp_schema_text("triaxial-3d") != NULL);
}

int main(void)
{
    test_ranges();
    test_specimen();
    test_bounds();
    test_defaults();
    test_reader();
    test_document();
    return gp_test_summary();
}
