/* test_spec_geostatic.c -- the spec of kind geostatic-3d (schema/kinds/geostatic-3d/): every
 * refusal with its pointer and code (the schema's ranges, phi' given twice or unresolved,
 * gravity along no axis, wall friction, slabs and map cells against the packing's height, the
 * spheres and the work budget), the defaults, and the reader of an effective spec into the
 * core's parameters. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_spec.h"
#include "gp_spec_specimen.h"
#include "gp_test.h"
#include "kinds/geostatic-3d/gp_spec_geostatic.h"
#include "schema/spec_patch.h"

/* the contract's example with the paper's sample inline, tiled 2 x 2 x 2 (a 1 m cube) */
static const char EX[] =
    "{\"kind\": \"geostatic-3d\", \"seed\": 7,"
    " \"specimen\": {\"spec\": {\"box\": [0.5, 0.5, 0.5],"
    " \"sieve\": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], \"sieve_units\": \"mm\","
    " \"porosity\": 0.38, \"tiling\": [2, 2, 2]}},"
    " \"gravity\": [0, 0, -9.81], \"wall_friction_deg\": 0, \"phi_deg\": 23.7, \"slab\": 0.25,"
    " \"outputs\": [\"profile\", \"spheres\"]}";

static const char JOB[] = "0123456789abcdef0123456789abcdef";

#define BAD(ptr, val, wptr, needle) bad(EX, ptr, val, wptr, "invalid_spec", needle, HERE)
#define TOO_LARGE(ptr, val, wptr) bad(EX, ptr, val, wptr, "too_large", NULL, HERE)
#define GOOD(ptr, val) good(EX, ptr, val, HERE)

static void test_ranges(void)
{
    BAD("/gravity", "[0, -9.81]", "/gravity", NULL);
    BAD("/gravity", "[0, 0, -1001]", "/gravity/2", NULL);
    BAD("/wall_friction_deg", "-1", "/wall_friction_deg", NULL);
    BAD("/phi_deg", "0", "/phi_deg", NULL);
    BAD("/phi_deg", "90", "/phi_deg", NULL);
    BAD("/slab", "0", "/slab", NULL);
    BAD("/wall_margin_dmax", "21", "/wall_margin_dmax", NULL);
    BAD("/map_cell", "-1", "/map_cell", NULL);
    BAD("/stability", "0.02", "/stability", NULL);
    BAD("/stability", "1e-7", "/stability", NULL);
    BAD("/max_steps", "999", "/max_steps", NULL);
    BAD("/max_steps", "1000.5", "/max_steps", NULL);
    BAD("/outputs", "[\"curves\"]", "/outputs/0", NULL);
    BAD("/specimen/part", "\"all\"", "/specimen/part", NULL);
    BAD("/phi_from", "{\"job\": \"abc\"}", "/phi_from/job", NULL);
    BAD("/phi_from", "{}", "/phi_from/job", NULL);
    GOOD("/gravity", "[0, 9.81, 0]");
    GOOD("/gravity", "[-3.7, 0, 0]");
    GOOD("/outputs", "[\"spheres\"]");
    GOOD("/slab", NULL);
}

/* phi' once and resolved; gravity along an axis; the walls frictionless; slabs and cells */
static void test_checks(void)
{
    BAD("/phi_from", "{\"job\": \"0123456789abcdef0123456789abcdef\", \"phi_deg\": 30}",
        "/phi_from", "not both");
    char from[120];
    snprintf(from, sizeof from, "{\"job\": \"%s\"}", JOB);
    json_t *doc = patched(EX, "/phi_from", from);
    json_object_del(doc, "phi_deg");
    gp_spec_problem p;
    CHECK(gp_spec_validate(doc, &p) != 0 && !strcmp(p.pointer, "/phi_from/job") &&
          strstr(p.message, "not resolved"));
    /* resolved as the daemon does: accepted, and read back */
    json_object_set_new(json_object_get(doc, "phi_from"), "phi_deg", json_real(31.5));
    json_t *full = gp_spec_with_defaults(doc, &p);
    CHECK(full != NULL);
    gp_spec_geostatic s;
    CHECK(full && gp_spec_geostatic_read(full, &s, &p) == 0);
    if (full) {
        CHECK(s.params.phi_deg == 31.5 && !strcmp(s.phi_job, JOB));
        gp_spec_geostatic_free(&s);
    }
    json_decref(full);
    json_decref(doc);
    BAD("/gravity", "[1, 0, -9.81]", "/gravity", "along one axis");
    BAD("/gravity", "[0, 0, 0]", "/gravity", "along one axis");
    BAD("/wall_friction_deg", "10", "/wall_friction_deg", "frictionless");
    BAD("/slab", "1.5", "/slab", "thicker than the packing");
    TOO_LARGE("/slab", "1e-4", "/slab");
    BAD("/map_cell", "2", "/map_cell", "larger than the section");
    TOO_LARGE("/map_cell", "1e-3", "/map_cell");
    GOOD("/map_cell", "0.005");
    /* the packing's spheres and the work */
    bad(EX, "/specimen/spec/tiling", "[8, 8, 8]", "/specimen/part", "too_large", NULL, HERE);
    json_t *big = patched(EX, "/specimen/spec/tiling", "[4, 4, 4]");
    char *text = json_dumps(big, 0);
    GOOD("/max_steps", "10000000"); /* 19,440 spheres: within two days of one core */
    bad(text, "/max_steps", "10000000", "/max_steps", "too_large", NULL, HERE); /* 155,520 */
    free(text);
    json_decref(big);
}

/* the defaults and the reader into the core's parameters */
static void test_reader(void)
{
    json_t *full = effective(EX, "/slab", NULL);
    gp_spec_problem p;
    gp_spec_geostatic s;
    CHECK(full && gp_spec_geostatic_read(full, &s, &p) == 0);
    if (!full) return;
    const gp_geostatic_params *g = &s.params;
    CHECK(s.seed == 7 && s.tiled && s.job[0] == '\0' && s.phi_job[0] == '\0');
    CHECK(g->gravity[0] == 0 && g->gravity[1] == 0 && g->gravity[2] == -9.81);
    CHECK(g->phi_deg == 23.7 && g->wall_friction_deg == 0 && g->wall_margin_dmax == 1.5);
    CHECK(g->slab == 0 && g->map_cell == 0); /* the core's defaults: 5 d50, the slab */
    CHECK(g->stability_tol == 1e-4 && g->max_steps == 500000);
    CHECK(g->material.density == 2600 && g->material.friction_deg == 18);
    CHECK(s.outputs == (GP_OUT_GEO_PROFILE | GP_OUT_GEO_SPHERES));
    CHECK(s.specimen.tiling[0] == 2 && s.specimen.outputs == GP_OUT3_SPHERES);
    CHECK(s.specimen.seed == 7); /* the inline spec takes the enclosing seed */
    gp_spec_geostatic_free(&s);
    json_decref(full);
    /* without phi': 23.7; part sample: the tiling dropped */
    full = effective(EX, "/phi_deg", NULL);
    json_object_set_new(json_object_get(full, "specimen"), "part", json_string("sample"));
    CHECK(full && gp_spec_geostatic_read(full, &s, &p) == 0);
    if (full) {
        CHECK(s.params.phi_deg == GP_SPEC_GEOSTATIC_PHI_DEG && !s.tiled);
        CHECK(s.specimen.tiling[0] == 1 && s.specimen.tiling[2] == 1);
        gp_spec_geostatic_free(&s);
    }
    json_decref(full);
    /* a spec as posted is not an effective spec: "internal" at the field */
    full = load(EX);
    CHECK(gp_spec_geostatic_read(full, &s, &p) != 0 && !strcmp(p.code, "internal"));
    gp_spec_geostatic_free(&s);
    json_decref(full);
    CHECK(!strcmp(gp_spec_geostatic_phi_kind(), "triaxial-3d"));
}

/* the result bound grows with the spheres asked for */
static void test_bounds(void)
{
    json_t *a = effective(EX, "/outputs", "[\"profile\"]");
    json_t *b = effective(EX, "/outputs", "[\"profile\", \"spheres\"]");
    gp_spec_bounds_t ba, bb;
    gp_spec_problem p;
    CHECK(a && b && !gp_spec_bounds(a, &ba, &p) && !gp_spec_bounds(b, &bb, &p));
    if (a && b) {
        CHECK(ba.items == bb.items && ba.items > 15000 && ba.items < 25000);
        CHECK(bb.result_bytes > ba.result_bytes + 50 * bb.items);
        CHECK(ba.work_s > 0 && fabs(ba.work_s - bb.work_s) < 1e-9);
    }
    json_decref(a);
    json_decref(b);
}

int main(void)
{
    test_ranges();
    test_checks();
    test_reader();
    test_bounds();
    return gp_test_summary();
}
