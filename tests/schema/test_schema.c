/* test_schema.c -- the spec validator: pointers and messages of bad specs (most of them in the
 * tables k_refused and k_accepted), api.md's examples, defaults, semantic checks, the combined
 * schema document, the work and result bounds; the parsers, which read effective specs without
 * validating them again; the rings check of the core (gp_rings) that the 2D checks call. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_imc.h"
#include "gp_rings.h"
#include "gp_spec.h"
#include "gp_test.h"

static const char EX2D[] =
    "{\"kind\": \"fourier-voronoi-2d\", \"seed\": 42,"
    " \"container\": {\"polygon\": [[0,0],[1,0],[1,1],[0,1]], \"holes\": []},"
    " \"particles\": 500, \"size\": {\"cov\": 0.8},"
    " \"orientation\": {\"mean_deg\": 0, \"anisotropy\": 1.0},"
    " \"shape\": {\"D2\": 0.1, \"D3\": 0.05, \"D8\": 0.02, \"alpha\": -2, \"beta\": -2},"
    " \"solid_fraction\": 0.65,"
    " \"imc\": {\"error\": \"E3\", \"threshold\": 0.002, \"max_steps\": 1000000, \"init\": \"halton\"},"
    " \"contour_points\": 128,"
    " \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}";

static const char MIN2D[] = "{\"kind\": \"fourier-voronoi-2d\"}";

static const char EX3D[] =
    "{\"kind\": \"spheres-3d\", \"seed\": 7, \"box\": [0.5, 0.5, 0.5],"
    " \"sieve\": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], \"sieve_units\": \"mm\","
    " \"porosity\": 0.38,"
    " \"material\": {\"density\": 2600, \"young\": 15e6, \"poisson\": 0.5, \"friction_deg\": 18, \"damping\": 0.2},"
    " \"tiling\": [4, 4, 4], \"outputs\": [\"spheres\", \"contacts\", \"fabric\", \"stress\"]}";

/* a sieve-law spec: 10-40 mm grains in the unit square (about two thousand grains) */
static const char SV2D[] =
    "{\"kind\": \"fourier-voronoi-2d\", \"seed\": 3,"
    " \"size\": {\"law\": \"sieve\", \"sieve\": [[10, 0], [20, 50], [40, 100]]},"
    " \"contour_points\": 32}";

static const char MIN3D[] = "{\"kind\": \"spheres-3d\"}";

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

/* "line N" of the call, for diagnostics */
#define STR_(x) #x
#define STR(x) STR_(x)
#define HERE "line " STR(__LINE__)

/* The way of a posted spec to the worker: gp_spec_with_defaults (which validates it), then the
 * kind's parser on the effective spec (which does not). 0, or -1 with *p; free *s either way. */
static json_t *effective_or_zero(const json_t *spec, void *out, size_t size, gp_spec_problem *p)
{
    json_t *full = gp_spec_with_defaults(spec, p);
    if (!full) memset(out, 0, size);
    return full;
}

static int read_2d(const json_t *spec, gp_spec2d *s, gp_spec_problem *p)
{
    json_t *full = effective_or_zero(spec, s, sizeof *s, p);
    int rc = full ? gp_spec2d_read(full, s, p) : -1;
    json_decref(full);
    return rc;
}

static int read_3d(const json_t *spec, gp_spec3d *s, gp_spec_problem *p)
{
    json_t *full = effective_or_zero(spec, s, sizeof *s, p);
    int rc = full ? gp_spec3d_read(full, s, p) : -1;
    json_decref(full);
    return rc;
}

/* the same from a spec's text */
static int read_2d_text(const char *text, gp_spec2d *s, gp_spec_problem *p)
{
    json_t *j = load(text);
    int rc = read_2d(j, s, p);
    json_decref(j);
    return rc;
}

static int read_3d_text(const char *text, gp_spec3d *s, gp_spec_problem *p)
{
    json_t *j = load(text);
    int rc = read_3d(j, s, p);
    json_decref(j);
    return rc;
}

/* the shape and solid fraction of the defaults (and of EX2D): the paper's */
static void check_paper_shape(const gp_spec2d *s)
{
    CHECK_NEAR(s->D2, 0.1, 0);
    CHECK_NEAR(s->D3, 0.05, 0);
    CHECK_NEAR(s->D8, 0.02, 0);
    CHECK_NEAR(s->alpha, -2, 0);
    CHECK_NEAR(s->beta, -2, 0);
    CHECK_NEAR(s->solid_fraction, 0.65, 0);
}

/* expects the spec to fail with this pointer, code, and message containing needle */
static void expect_bad_code(const char *base, const char *ptr, const char *value,
                            const char *want_ptr, const char *want_code, const char *needle,
                            const char *where)
{
    json_t *doc = patched(base, ptr, value);
    gp_spec_problem p;
    int rc = gp_spec_validate(doc, &p);
    int ok = rc != 0 && !strcmp(p.pointer, want_ptr) && !strcmp(p.code, want_code) &&
             (!needle || strstr(p.message, needle));
    if (!ok || g_verbose)
        fprintf(stderr, "%s: set %s = %s -> rc %d code %s pointer '%s' message '%s'\n",
                where, ptr, value ? value : "(deleted)", rc, p.code, p.pointer, p.message);
    CHECK(ok);
    /* the message starts with the pointer */
    if (rc) CHECK(strncmp(p.message, want_ptr[0] ? want_ptr : "spec", strlen(want_ptr[0] ? want_ptr : "spec")) == 0);
    /* the way to the worker reports the same problem for 2D specs */
    if (strstr(base, "fourier")) {
        gp_spec2d s;
        gp_spec_problem q;
        CHECK(read_2d(doc, &s, &q) != 0);
        CHECK(!strcmp(q.pointer, p.pointer));
        gp_spec2d_free(&s);
    }
    json_decref(doc);
}

static void expect_bad(const char *base, const char *ptr, const char *value,
                       const char *want_ptr, const char *needle, const char *where)
{
    expect_bad_code(base, ptr, value, want_ptr, "invalid_spec", needle, where);
}
#define BAD2(ptr, val, wptr, needle) expect_bad(EX2D, ptr, val, wptr, needle, HERE)
#define BAD3(ptr, val, wptr, needle) expect_bad(EX3D, ptr, val, wptr, needle, HERE)

static void expect_good(const char *base, const char *ptr, const char *value, const char *where)
{
    json_t *doc = patched(base, ptr, value);
    gp_spec_problem p;
    int rc = gp_spec_validate(doc, &p);
    if (rc)
        fprintf(stderr, "%s: set %s = %s -> unexpected: %s\n", where, ptr,
                value ? value : "(deleted)", p.message);
    CHECK(rc == 0);
    json_decref(doc);
}

/* Cases: the base spec with the value at ptr set to value (JSON text; NULL: the field
 * deleted) is refused at want_ptr (code invalid_spec) with a message that contains needle ("":
 * any message), or accepted. */
typedef struct bad_case {
    const char *base, *ptr, *value, *want_ptr, *needle;
} bad_case;

typedef struct good_case {
    const char *base, *ptr, *value;
} good_case;

/* ---- tables of cases, each an edit of one of the specs above ---- */

static const bad_case k_refused[] = {
    /* 2D: the schema, field by field */
    {EX2D, "/kind", "\"voronoi\"", "/kind", "unknown kind \"voronoi\"; expected one of \"fourier-voronoi-2d\", \"fourier-voronoi-3d\", \"geostatic-3d\", \"spheres-3d\", \"triaxial-3d\""},
    {EX2D, "/kind", "3", "/kind", "unknown kind 3"},
    {EX2D, "/colour", "1", "/colour", "unknown field \"colour\""},
    {EX2D, "/seed", "-1", "/seed", "expected an integer in [0, 9007199254740991], got -1"},
    {EX2D, "/seed", "1.5", "/seed", "got 1.5"},
    {EX2D, "/seed", "\"7\"", "/seed", "got \"7\""},
    {EX2D, "/particles", "0", "/particles", "expected an integer in [1, 1000000], got 0"},
    {EX2D, "/particles", "1000001", "/particles", "got 1000001"},
    {EX2D, "/particles", "true", "/particles", "got true"},
    {EX2D, "/particles", "null", "/particles", "got null"},
    {EX2D, "/size/cov", "\"abc\"", "/size/cov", "/size/cov: expected a number in [0, 3], got \"abc\""},
    {EX2D, "/size/cov", "-0.1", "/size/cov", "got -0.1"},
    {EX2D, "/size/cov", "3.5", "/size/cov", ""},
    {EX2D, "/size/mean", "1", "/size/mean", "unknown field \"mean\"; allowed here: law, cov, sieve, sieve_units, of"},
    {EX2D, "/size", "0.8", "/size", "expected an object, got 0.8"},
    {EX2D, "/orientation/mean_deg", "91", "/orientation/mean_deg", "[-90, 90]"},
    {EX2D, "/orientation/anisotropy", "0", "/orientation/anisotropy", "expected a number in (0, 1], got 0"},
    {EX2D, "/orientation/anisotropy", "1.01", "/orientation/anisotropy", ""},
    {EX2D, "/shape/D2", "1", "/shape/D2", "expected a number in [0, 1), got 1"},
    {EX2D, "/shape/D3", "-0.01", "/shape/D3", ""},
    {EX2D, "/shape/D8", "\"x\"", "/shape/D8", ""},
    {EX2D, "/shape/alpha", "[]", "/shape/alpha", "got an array of 0 items"},
    {EX2D, "/shape/spectrum", "[1, 0.1, 0.2]", "/shape/spectrum", "cannot be combined with \"D2\""},
    {EX2D, "/solid_fraction", "0", "/solid_fraction", "expected a number in (0, 1], got 0"},
    {EX2D, "/solid_fraction", "1.2", "/solid_fraction", ""},
    {EX2D, "/imc/error", "\"E4\"", "/imc/error", "expected one of \"AD\", \"E1\", \"E2\", \"E3\", got \"E4\""},
    {EX2D, "/imc/threshold", "0", "/imc/threshold", "expected a number > 0, got 0"},
    {EX2D, "/imc/max_steps", "-5", "/imc/max_steps", ""},
    {EX2D, "/imc/max_steps", "10.5", "/imc/max_steps", ""},
    {EX2D, "/imc/init", "\"random\"", "/imc/init", "\"uniform\", \"halton\""},
    {EX2D, "/imc/classes", "3", "/imc/classes", "[4, 200]"},
    {EX2D, "/imc/classes", "201", "/imc/classes", ""},
    {EX2D, "/imc/steps", "5", "/imc/steps", "unknown field"},
    {EX2D, "/contour_points", "15", "/contour_points", "[16, 4096]"},
    {EX2D, "/contour_points", "4097", "/contour_points", ""},
    {EX2D, "/outputs", "[]", "/outputs", "at least 1 item,"},
    {EX2D, "/outputs", "[\"grains\", \"voxels\"]", "/outputs/1", "\"grains\", \"odec\", \"descriptors\", \"cells\""},
    {EX2D, "/outputs", "[\"grains\", \"cells\", \"grains\"]", "/outputs/2", "duplicate"},
    {EX2D, "/outputs", "\"grains\"", "/outputs", "expected an array"},
    /* container */
    {EX2D, "/container/polygon", "[[0,0],[1,0]]", "/container/polygon", "at least 3 items, got 2"},
    {EX2D, "/container/polygon/1", "[1]", "/container/polygon/1", "exactly 2 items"},
    {EX2D, "/container/polygon/1", "[1, \"a\"]", "/container/polygon/1/1", "expected a number in [-1000000000, 1000000000], got \"a\""},
    {EX2D, "/container/polygon/1", "[1, 0, 0]", "/container/polygon/1", ""},
    {EX2D, "/container/polygon", "[[0,0],[1,1],[1,0],[0,1]]", "/container/polygon", "not simple"},
    {EX2D, "/container/polygon", "[[0,0],[1,1],[2,2]]", "/container/polygon", "no area"},
    {EX2D, "/container/polygon", "[[0,0],[2,0],[1,0],[1,1]]", "/container/polygon", "not simple"},
    {EX2D, "/container/holes", "[[[2,2],[3,2],[3,3]]]", "/container/holes/0", "not inside"},
    {EX2D, "/container/holes", "[[[0.5,0.5],[1.5,0.5],[0.5,0.6]]]", "/container/holes/0", "crosses"},
    {EX2D, "/container/holes", "[[[0.1,0.1],[0.9,0.1],[0.9,0.9],[0.1,0.9]], [[0.2,0.2],[0.3,0.2],[0.3,0.3]]]", "/container/holes/1", "inside hole 0"},
    {EX2D, "/container/holes", "[[[0.1,0.1],[0.2,0.1]]]", "/container/holes/0", "at least 3"},
    {EX2D, "/container/holes", "{}", "/container/holes", "expected an array"},
    {EX2D, "/container/circle", "{\"center\": [0, 0], \"radius\": 1}", "/container", "expected a polygon container"},
    {EX2D, "/container", "{\"circle\": {\"center\": [0, 0], \"radius\": 0}}", "/container/circle/radius", "expected a number in (0, 1000000000], got 0"},
    {EX2D, "/container", "{\"circle\": {\"center\": [0, 0]}}", "/container/circle/radius", "required field is missing"},
    {EX2D, "/container", "{\"circle\": {\"center\": [0], \"radius\": 1}}", "/container/circle/center", "exactly 2 items"},
    {EX2D, "/container", "{\"circle\": {\"center\": [0, 0], \"radius\": 1, \"r\": 1}}", "/container/circle/r", "unknown field"},
    {EX2D, "/container", "{}", "/container", "expected a polygon container"},
    {EX2D, "/container", "[]", "/container", "or a circle container"},
    {EX2D, "/container", "{\"holes\": []}", "/container/polygon", "required field is missing"},
    /* spectrum shape */
    {EX2D, "/shape", "{\"spectrum\": [1, 0.1]}", "/shape/spectrum", "at least 3 items"},
    {EX2D, "/shape", "{\"spectrum\": [0, 0.1, 0.2]}", "/shape/spectrum/0", "> 0"},
    {EX2D, "/shape", "{\"spectrum\": [1, 0.1, -0.2]}", "/shape/spectrum/2", "≥ 0"},
    /* 2D size laws; cov: at least GP_LAW_COV_MIN for every law, each law's own maximum */
    {EX2D, "/size/cov", "0", "/size/cov", "/size/cov: expected at least 0.01, got 0: equal sizes cannot be tessellated exactly; use 0.01"},
    {EX2D, "/size/cov", "0.009", "/size/cov", "equal sizes"},
    {EX2D, "/size", "{\"law\": \"normal\", \"cov\": 0.005}", "/size/cov", "at least 0.01"},
    {EX2D, "/size", "{\"law\": \"uniform\", \"cov\": 0}", "/size/cov", "at least 0.01"},
    {EX2D, "/size", "{\"law\": \"normal\", \"cov\": 0.61}", "/size/cov", "at most 0.6 for law \"normal\""},
    {EX2D, "/size", "{\"law\": \"uniform\", \"cov\": 0.578}", "/size/cov", "at most 0.5773 (1/√3) for law \"uniform\""},
    {EX2D, "/size", "{\"law\": \"uniform\", \"cov\": 0.8}", "/size/cov", ""},
    {EX2D, "/size/cov", "3.01", "/size/cov", "[0, 3]"},
    {EX2D, "/size/law", "\"gamma\"", "/size/law", "\"lognormal\", \"normal\", \"uniform\", \"sieve\""},
    {EX2D, "/size/of", "\"pores\"", "/size/of", "\"cells\", \"grains\""},
    /* sieve fields without law "sieve" */
    {EX2D, "/size/sieve", "[[1, 0], [2, 100]]", "/size/sieve", "/size/sieve: only allowed with law \"sieve\" (the law here is \"lognormal\")"},
    {EX2D, "/size/sieve_units", "\"m\"", "/size/sieve_units", "only allowed with law \"sieve\""},
    {EX2D, "/size", "{\"law\": \"normal\", \"cov\": 0.2, \"sieve\": [[1, 0], [2, 100]]}", "/size/sieve", "the law here is \"normal\""},
    /* 2D sieve law: fields that it excludes or needs (particles is checked as posted) */
    {SV2D, "/particles", "100", "/particles", "/particles: leave particles out with size.law \"sieve\": the number of grains follows from the container area and solid_fraction"},
    {SV2D, "/particles", "1", "/particles", ""},
    {SV2D, "/size/cov", "0.5", "/size/cov", "not allowed with law \"sieve\""},
    {SV2D, "/size/sieve", NULL, "/size/sieve", "required with law \"sieve\""},
    {SV2D, "/size/of", "\"cells\"", "/size/of", "a sieve curve is a law of the grains"},
    /* the rows: as spheres-3d's sieve */
    {SV2D, "/size/sieve", "[[10, 0]]", "/size/sieve", "at least 2"},
    {SV2D, "/size/sieve/1", "[20]", "/size/sieve/1", "exactly 2"},
    {SV2D, "/size/sieve/1/1", "101", "/size/sieve/1/1", "[0, 100]"},
    {SV2D, "/size/sieve/1/0", "0", "/size/sieve/1/0", "> 0"},
    {SV2D, "/size/sieve/1/0", "10", "/size/sieve/1/0", "/size/sieve/1/0: sieve diameters must increase strictly"},
    {SV2D, "/size/sieve/2/1", "40", "/size/sieve/2/1", "must not decrease"},
    {SV2D, "/size/sieve/2/1", "99", "/size/sieve/2/1", "the last sieve row must pass 100 %"},
    {SV2D, "/size/sieve/0/1", "5", "/size/sieve/0/1", "must pass 0 %"},
    {SV2D, "/size/sieve_units", "\"cm\"", "/size/sieve_units", "\"mm\", \"m\""},
    /* a grain larger than the container: the units are likely wrong */
    {SV2D, "/size/sieve_units", "\"m\"", "/size/sieve/2/0", "check sieve_units"},
    /* 3D: the schema, field by field */
    {EX3D, "/kind", "\"spheres\"", "/kind", "unknown kind"},
    {EX3D, "/box", "[0.5, 0.5]", "/box", "exactly 3 items, got 2"},
    {EX3D, "/box/2", "0", "/box/2", "> 0"},
    {EX3D, "/box/1", "\"1\"", "/box/1", ""},
    {EX3D, "/sieve", "[[10, 0]]", "/sieve", "at least 2"},
    {EX3D, "/sieve/1", "[20]", "/sieve/1", "exactly 2"},
    {EX3D, "/sieve/1/1", "101", "/sieve/1/1", "[0, 100]"},
    {EX3D, "/sieve/1/0", "-20", "/sieve/1/0", "> 0"},
    {EX3D, "/sieve/2/0", "20", "/sieve/2/0", "increase strictly"},
    {EX3D, "/sieve/2/1", "1", "/sieve/2/1", "must not decrease"},
    {EX3D, "/sieve/4/1", "99", "/sieve/4/1", "100"},
    {EX3D, "/sieve/0/1", "1", "/sieve/0/1", "0 %"},
    {EX3D, "/sieve_units", "\"cm\"", "/sieve_units", "\"mm\", \"m\""},
    {EX3D, "/sieve_units", "\"m\"", "/sieve/4/0", "does not fit"},
    {EX3D, "/porosity", "1", "/porosity", "(0, 1)"},
    {EX3D, "/porosity", "0", "/porosity", ""},
    {EX3D, "/material/density", "0", "/material/density", "[100, 30000]"},
    {EX3D, "/material/young", "-1", "/material/young", ""},
    {EX3D, "/material/poisson", "0.6", "/material/poisson", "[0, 0.5]"},
    {EX3D, "/material/friction_deg", "90", "/material/friction_deg", ""},
    {EX3D, "/material/damping", "1.5", "/material/damping", ""},
    {EX3D, "/material/colour", "1", "/material/colour", "unknown field"},
    {EX3D, "/tiling", "[4, 4]", "/tiling", ""},
    {EX3D, "/tiling/0", "0", "/tiling/0", "[1, 16]"},
    {EX3D, "/tiling/0", "1.5", "/tiling/0", ""},
    {EX3D, "/outputs", "[\"spheres\", \"grains\"]", "/outputs/1", "\"spheres\", \"contacts\", \"fabric\", \"stress\""},
    {EX3D, "/outputs", "[\"stress\", \"stress\"]", "/outputs/1", "duplicate"},
    {EX3D, "/holes", "[]", "/holes", "unknown field"},
    /* 2D polygons: touching is crossing, decided exactly */
    /* a vertex on an edge */
    {EX2D, "/container/polygon", "[[0,0],[4,0],[4,4],[2,0],[0,4]]", "/container/polygon", "crosses or touches"},
    /* a figure 8: one point twice */
    {EX2D, "/container/polygon", "[[0,0],[2,0],[1,1],[2,2],[0,2],[1,1]]", "/container/polygon", "crosses or touches"},
    /* edges 2 and 3 run back over each other */
    {EX2D, "/container/polygon", "[[0,0],[2,0],[2,1],[3,1],[1,1],[0,1]]", "/container/polygon", "not simple"},
    /* edges 0 and 1 */
    {EX2D, "/container/polygon", "[[0,0],[2,0],[1,0],[1,1]]", "/container/polygon", "not simple"},
    /* holes: touching the outer ring, each other, nested, outside */
    /* a vertex on the outer ring */
    {EX2D, "/container/holes", "[[[0,0.5],[0.5,0.4],[0.5,0.6]]]", "/container/holes/0", "of /container/polygon"},
    /* a shared vertex */
    {EX2D, "/container/holes", "[[[0.1,0.1],[0.4,0.1],[0.4,0.4]], [[0.4,0.4],[0.8,0.4],[0.8,0.8]]]", "/container/holes/1", "of /container/holes/0"},
    /* the first one inside the second */
    {EX2D, "/container/holes", "[[[0.2,0.2],[0.3,0.2],[0.3,0.3]], [[0.1,0.1],[0.9,0.1],[0.9,0.9],[0.1,0.9]]]", "/container/holes/0", "inside hole 1"},
    /* nested three deep */
    {EX2D, "/container/holes", "[[[0.1,0.1],[0.9,0.1],[0.9,0.9],[0.1,0.9]], [[0.2,0.2],[0.8,0.2],[0.8,0.8],[0.2,0.8]], [[0.4,0.4],[0.6,0.4],[0.5,0.6]]]", "/container/holes/1", "inside hole 0"},
    /* a hole around the container */
    {EX2D, "/container/holes", "[[[0.1,0.1],[0.2,0.1],[0.2,0.2]], [[-1,-1],[3,-1],[3,3],[-1,3]]]", "/container/holes/0", "inside hole 1"},
    {EX2D, "/container/holes", "[[[-1,-1],[3,-1],[3,3],[-1,3]]]", "/container/holes/0", "not inside"},
    /* coordinates stay where the exact predicates are exact */
    {EX2D, "/container/polygon", "[[0,0],[1e10,0],[0,1]]", "/container/polygon/1/0", "[-1000000000, 1000000000]"},
    /* 3D physical ranges */
    {EX3D, "/material/young", "500", "/material/young", ""},
    {EX3D, "/material/young", "1e300", "/material/young", ""},
    {EX3D, "/material/density", "50", "/material/density", ""},
    {EX3D, "/material/density", "1e300", "/material/density", ""},
    {EX3D, "/material/friction_deg", "89.5", "/material/friction_deg", "[0, 89]"},
    {EX3D, "/material/damping", "1", "/material/damping", "[0, 1)"},
};

static const good_case k_accepted[] = {
    /* 2D variants */
    {EX2D, "/container", "{\"circle\": {\"center\": [0.5, -1e3], \"radius\": 2.5}}"},
    /* clockwise */
    {EX2D, "/container/polygon", "[[0,0],[0,1],[1,1],[1,0]]"},
    /* non-convex */
    {EX2D, "/container/polygon", "[[0,0],[2,0],[2,2],[1,1],[0,2]]"},
    {EX2D, "/particles", "500.0"},
    {EX2D, "/imc/classes", "25"},
    {EX2D, "/outputs", "[\"cells\"]"},
    {EX2D, "/orientation/mean_deg", "-90"},
    {EX2D, "/size/cov", "0.01"},
    {EX2D, "/imc/max_steps", "0"},
    /* 2D size laws */
    /* the default cov 0.5 is within normal's 0.6 */
    {EX2D, "/size", "{\"law\": \"normal\"}"},
    {EX2D, "/size", "{\"law\": \"normal\", \"cov\": 0.6}"},
    {EX2D, "/size", "{\"law\": \"uniform\", \"cov\": 0.5773}"},
    {EX2D, "/size", "{\"law\": \"lognormal\", \"cov\": 3}"},
    {EX2D, "/size", "{\"law\": \"normal\", \"cov\": 0.01, \"of\": \"grains\"}"},
    /* 2D sieve law */
    {SV2D, "/size/of", "\"grains\""},
    {SV2D, "/size/sieve_units", "\"mm\""},
    {SV2D, "/container", "{\"circle\": {\"center\": [0, 0], \"radius\": 0.5}}"},
    /* 3D variants */
    {EX3D, "/sieve_units", "\"mm\""},
    /* ~40,000 spheres, 64 tiles */
    {EX3D, "/sieve", "[[10, 0], [20, 100]]"},
    {EX3D, "/tiling", NULL},
    /* 2D polygons */
    /* collinear, same way */
    {EX2D, "/container/polygon", "[[0,0],[1,0],[2,0],[2,1],[0,1]]"},
    /* just above */
    {EX2D, "/container/polygon", "[[0,0],[4,0],[4,4],[2,1e-300],[0,4]]"},
    {EX2D, "/container/polygon", "[[0,0],[1e-9,0],[1e-9,1e-9],[0,1e-9]]"},
    {EX2D, "/container/holes", "[[[0.1,0.1],[0.2,0.1],[0.2,0.2]], [[0.8,0.8],[0.9,0.8],[0.9,0.9],[0.8,0.9]], [[0.5,0.1],[0.6,0.1],[0.55,0.5]]]"},
    /* 3D materials within the budget and the physical ranges */
    /* diamond: ~1.6 M steps, still within the budget */
    {EX3D, "/material/young", "1e12"},
    {EX3D, "/material/density", "100"},
    {EX3D, "/material/friction_deg", "89"},
    {EX3D, "/material/damping", "0.99"},
};

static void test_tables(void)
{
    char where[64];
    for (size_t i = 0; i < sizeof k_refused / sizeof *k_refused; i++) {
        const bad_case *c = &k_refused[i];
        snprintf(where, sizeof where, "k_refused[%zu]", i);
        expect_bad(c->base, c->ptr, c->value, c->want_ptr, c->needle, where);
    }
    for (size_t i = 0; i < sizeof k_accepted / sizeof *k_accepted; i++) {
        const good_case *c = &k_accepted[i];
        snprintf(where, sizeof where, "k_accepted[%zu]", i);
        expect_good(c->base, c->ptr, c->value, where);
    }
}

static void test_examples(void)
{
    json_t *j = load(EX2D);
    gp_spec_problem p;
    CHECK(gp_spec_validate(j, &p) == 0);
    gp_spec2d s;
    CHECK(read_2d(j, &s, &p) == 0);
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
    check_paper_shape(&s);
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
    CHECK(read_3d(j, &t, &p) == 0);
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
    CHECK(read_3d_text("{\"kind\": \"spheres-3d\", \"sieve\": [[0.01, 0], [0.02, 100]], \"sieve_units\": \"m\"}", &t, &p) == 0);
    CHECK_NEAR(t.sieve[1].diameter, 0.02, 0);
    CHECK(t.tiling[0] == 1 && t.tiling[1] == 1 && t.tiling[2] == 1);
    CHECK(t.outputs == GP_OUT3_SPHERES);
    CHECK_NEAR(t.box[1], 0.5, 0);
    gp_spec3d_free(&t);
    /* a 2D spec is not a 3D one */
    CHECK(read_3d_text(EX2D, &t, &p) != 0 && !strcmp(p.pointer, "/kind"));
    gp_spec3d_free(&t);
    CHECK(read_3d_text("{\"kind\": \"spheres-3d\", \"porosity\": 2}", &t, &p) != 0 && !strcmp(p.pointer, "/porosity"));
    gp_spec3d_free(&t);
}

static void test_defaults(void)
{
    gp_spec_problem p;
    gp_spec2d s;
    CHECK(read_2d_text(MIN2D, &s, &p) == 0);
    CHECK(s.seed == 0);
    CHECK(s.container == GP_CONTAINER_POLYGON && s.outer.n == 4 && s.nholes == 0);
    CHECK(s.particles == 100);
    CHECK_NEAR(s.cov, 0.5, 0);
    CHECK_NEAR(s.mean_deg, 0, 0);
    CHECK_NEAR(s.anisotropy, 1, 0);
    check_paper_shape(&s);
    CHECK(s.size_law == GP_LAW_LOGNORMAL && s.size_of_grains == 0 && s.nsieve == 0);
    CHECK(s.imc_error == GP_IMC_AD);
    CHECK_NEAR(s.imc_threshold, gp_imc_default_threshold(GP_IMC_ERROR_AD), 0);
    CHECK(s.imc_max_steps == 1000000);
    CHECK(s.imc_init == GP_INIT_UNIFORM);
    CHECK(s.contour_points == 128);
    CHECK(s.outputs == GP_OUT2_GRAINS);
    CHECK(s.threads == 0);
    gp_spec2d_free(&s);

    json_t *j = load(MIN2D);
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
    CHECK(read_2d_text("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 120, \"imc\": {\"error\": \"E1\", \"classes\": 12},"
                       " \"shape\": {\"D2\": 0.3}, \"container\": {\"circle\": {\"center\": [1, 2], \"radius\": 3}},"
                       " \"seed\": 5.0}", &s, &p) == 0);
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

    /* spectrum */
    CHECK(read_2d_text("{\"kind\": \"fourier-voronoi-2d\", \"shape\": {\"spectrum\": [1, 0, 0.2, 0.05, 0.01]}}", &s, &p) == 0);
    CHECK(s.has_spectrum && s.nspectrum == 5);
    CHECK_NEAR(s.spectrum[2], 0.2, 0);
    gp_spec2d_free(&s);

    /* a hole, a closing point that repeats the first */
    CHECK(read_2d_text("{\"kind\": \"fourier-voronoi-2d\", \"container\": {\"polygon\": [[0,0],[4,0],[4,4],[0,4],[0,0]],"
                       " \"holes\": [[[1,1],[1,2],[2,2],[2,1]], [[3,3],[3.5,3],[3.5,3.5]]]}}", &s, &p) == 0);
    CHECK(s.outer.n == 4 && s.nholes == 2 && s.holes[0].n == 4 && s.holes[1].n == 3);
    gp_spec2d_free(&s);

    j = load(MIN3D);
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
        CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "") && !strcmp(p.code, "invalid_spec"));
        json_decref(j);
        j = load("{\"seed\": 1}");
        CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/kind"));
        CHECK(strstr(p.message, "fourier-voronoi-2d") && strstr(p.message, "spheres-3d"));
        json_decref(j);
    }
    json_t *j = patched(EX2D, "/shape", "{\"spectrum\": [1, 0.1, 0.2, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]}");
    gp_spec_problem p;
    CHECK(gp_spec_validate(j, &p) == 0);
    json_object_set_new(j, "contour_points", json_integer(16));
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.pointer, "/shape/spectrum") && !strcmp(p.code, "invalid_spec"));
    CHECK(strstr(p.message, "too many") != NULL);
    json_decref(j);
    /* the cases of the tables (test_tables); any count with the default error AD (E3's 0.002 is below the floor of a few cells) */
    expect_good(MIN2D, "/particles", "1", HERE);
    expect_good(MIN2D, "/particles", "7.0", HERE);
}

static void test_size_laws(void)
{
    /* the laws' fields and ranges: in the tables (test_tables); what the parser fills */
    json_t *j = patched(EX2D, "/size", "{\"law\": \"uniform\", \"cov\": 0.3, \"of\": \"grains\"}");
    gp_spec2d s;
    gp_spec_problem p;
    CHECK(read_2d(j, &s, &p) == 0);
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
    CHECK(read_2d(j, &s, &p) == 0);
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
    CHECK(read_2d(j, &s, &p) == 0);
    CHECK_NEAR(s.sieve_d[1], 0.02, 0);
    gp_spec2d_free(&s);
    json_decref(j);

    /* fields that a sieve law excludes or needs, and its rows: in the tables (test_tables) */
    /* a derived count beyond particles' maximum: too_large */
    expect_bad_code(SV2D, "/size/sieve", "[[0.01, 0], [0.02, 100]]", "/size/sieve",
                    "too_large", "over the limit of 1000000", HERE);
    /* a count too large even to compute (fine grains below coarse ones) */
    expect_bad_code(SV2D, "/size/sieve", "[[1e-9, 0], [10, 100]]", "/size/sieve",
                    "too_large", "over the limit of 1000000", HERE);
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
    CHECK(!strcmp(p.code, "invalid_spec"));
    CHECK(!strcmp(p.pointer, "/imc/threshold"));
    CHECK(strncmp(p.message, "/imc/threshold: 0.002 is below the least error ", 47) == 0);
    CHECK(strstr(p.message, "20 cells") && strstr(p.message, "the default error AD"));
    CHECK(read_2d(j, &s, &p) != 0 && !strcmp(p.pointer, "/imc/threshold"));
    gp_spec2d_free(&s);
    if (g_verbose) fprintf(stderr, "%s\n", p.message);
    /* the floor itself, as the core computes it */
    gp_imc_params q;
    gp_imc_params_defaults(&q);
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
    CHECK(read_2d(j, &s, &p) == 0);
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
        CHECK(read_2d(j, &s, &p) == 0 && (int)s.imc_error == (k < 3 ? k + 1 : GP_IMC_AD));
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
    BAD2("/imc", "{\"error\": \"E1\", \"classes\": 12, \"threshold\": 0.002}", "/imc/threshold",
         "500 cells can reach with E1 and 12 size x 12 orientation classes");
    /* a sieve law: the floor of the derived count (7 classes: a count that 7 does not divide
     * has a floor > 0) */
    j = load(SV2D);
    CHECK(read_2d(j, &s, &p) == 0);
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
    gp_spec2d s;
    gp_spec_problem p;
    CHECK(read_2d_text("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"contour_points\": 1.28e2}", &s, &p) == 0);
    CHECK(s.particles == 1000000);
    CHECK(s.contour_points == 128);
    gp_spec2d_free(&s);
    BAD2("/particles", "1.0000001e6", "/particles", "[1, 1000000]");
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
    /* the schema's fields, the sieve rows, the box: in the tables (test_tables) */
    /* 1-2 um grains would fill the 0.5 m box with ~4e16 spheres: refused at submit (the DEM
     * sample takes 400,000 at most), not failed on a worker */
    expect_bad_code(EX3D, "/sieve", "[[0.001, 0], [0.002, 100]]", "/box", "too_large",
                    "over the limit of 400000 spheres", HERE);

    /* a 3D spec is not a 2D spec */
    gp_spec2d s;
    gp_spec_problem p;
    CHECK(read_2d_text(EX3D, &s, &p) != 0 && !strcmp(p.pointer, "/kind"));
    gp_spec2d_free(&s);
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
    CHECK(json_array_size(json_object_get(j, "oneOf")) == 5);
    json_t *defs = json_object_get(j, "$defs");
    CHECK(json_is_object(json_object_get(defs, "fourier-voronoi-2d")));
    CHECK(json_is_object(json_object_get(defs, "spheres-3d")));
    CHECK(json_is_object(json_object_get(defs, "triaxial-3d")));
    CHECK(json_is_object(json_object_get(defs, "geostatic-3d")));
    CHECK(json_is_object(json_object_get(defs, "fourier-voronoi-3d")));
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
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.code, "invalid_spec"));
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
    /* touching is crossing, decided exactly; holes: in the tables (test_tables) */
}

/* ---- issue #14: work and result bounds, whatever the spelling of the numbers ---- */

static void expect_too_large(const char *base, const char *ptr, const char *value,
                             const char *want_ptr, const char *needle, const char *where)
{
    expect_bad_code(base, ptr, value, want_ptr, "too_large", needle, where);
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
    expect_good(MIN2D, "/particles", "10000", HERE);
    expect_good(MIN2D, "/particles", "1e6", HERE); /* the schema's most, at the defaults */
    expect_good(MIN2D, "/imc/max_steps", "1e9", HERE); /* with 100 cells */

    /* every 2D maximum at once (~3 days) is over the budget, spelled either way */
    const char *most[] = {
        "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"imc\": {\"max_steps\": 1e9},"
        " \"contour_points\": 4.096e3, \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}",
        "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1000000, \"imc\": {\"max_steps\": 1000000000},"
        " \"contour_points\": 4096, \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}"};
    json_t *k;
    for (int i = 0; i < 2; i++) {
        k = load(most[i]);
        CHECK(gp_spec_validate(k, &p) != 0 && !strcmp(p.code, "too_large"));
        CHECK(!strcmp(p.pointer, "/imc/max_steps") && strstr(p.message, "over the budget of 172800 s"));
        json_decref(k);
    }
    /* each of them alone passes; so does the test suite's long job */
    expect_good(MIN2D, "/imc/max_steps", "1e9", HERE);
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
    CHECK(gp_spec_validate(k, &p) != 0 && !strcmp(p.code, "too_large"));
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
    CHECK(read_2d(k, &s2, &q) != 0 && !strcmp(q.pointer, "/container")); /* the way to the worker too */
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
        CHECK(eff && gp_spec_check_result(eff, 1024e6, &p) != 0 && !strcmp(p.code, "too_large"));
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
    /* diamond (young 1e12: ~1.6 M steps) and density 100 are still within the budget: in the
     * tables (test_tables) */

    /* young 1e25 made dt ~1e-14 s and the job ~50 days: out of the schema's range now, and
     * far over the work budget even without it */
    BAD3("/material/young", "1e25", "/material/young", "[1000, 1000000000000]");
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
    expect_good(MIN3D, "/material", "{\"young\": 1e11}", HERE); /* the paper's sieve: fine */
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[5, 0], [10, 100]], \"material\": {\"young\": 1e11}}");
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.code, "too_large"));
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
    expect_too_large(MIN3D, "/box", "[100, 100, 100]", "/box", "spheres in the DEM sample", HERE);
    expect_too_large(MIN3D, "/box", "[1e2, 1e2, 1e2]", "/box", NULL, HERE);
    expect_bad_code(MIN3D, "/sieve_units", "\"m\"", "/sieve/4/0", "invalid_spec", "does not fit",
                    HERE);
    j = load("{\"kind\": \"spheres-3d\", \"sieve\": [[5, 0], [10, 100]], \"tiling\": [16, 16, 16]}");
    CHECK(gp_spec_validate(j, &p) != 0 && !strcmp(p.code, "too_large") && !strcmp(p.pointer, "/tiling"));
    json_decref(j);
    /* physical ranges: in the tables (test_tables) */

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
                    "/container/polygon", "invalid_spec", "fills 1e-08 of its bounding box",
                    HERE);
    json_t *doc = patched(B, "/container", "{\"polygon\": [[0,0],[1,1],[1,1.000002]]}");
    gp_spec_problem p;
    CHECK(gp_spec_validate(doc, &p) == 0);
    json_decref(doc);
    const char *B200 = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 200}";
    expect_bad_code(B200, "/container", "{\"polygon\": [[0,0],[1,1],[1,1.000002]]}",
                    "/container/polygon", "invalid_spec", "about 2e+08 draws", HERE);
    /* a hole that leaves a thin frame: the fill counts the holes out */
    expect_bad_code(B, "/container",
                    "{\"polygon\": [[0,0],[1,0],[1,1],[0,1]], \"holes\": "
                    "[[[1e-9,1e-9],[1e-9,0.999999999],[0.999999999,0.999999999],"
                    "[0.999999999,1e-9]]]}",
                    "/container/polygon", "invalid_spec", "bounding box", HERE);
}

/* ---- the parsers read effective specs, without validating them again ---- */

static void test_parsers_read_effective_specs(void)
{
    gp_spec_problem p;
    gp_spec2d s;
    gp_spec3d t;
    /* an effective spec, and its text as the daemon stores it, read as they are */
    json_t *j = load(SV2D);
    json_t *full = gp_spec_with_defaults(j, &p);
    CHECK(full != NULL);
    CHECK(gp_spec2d_read(full, &s, &p) == 0 && s.size_law == GP_LAW_SIEVE && s.nsieve == 3);
    CHECK(p.code[0] == 0);
    gp_spec2d_free(&s);
    char *text = json_dumps(full, JSON_COMPACT);
    CHECK(read_2d_text(text, &s, &p) == 0 && s.nsieve == 3);
    gp_spec2d_free(&s);
    free(text);
    /* not validated again: a semantic problem put into an effective spec goes through */
    json_object_set_new(json_object_get(full, "size"), "sieve", load("[[20, 0], [10, 100]]"));
    CHECK(gp_spec_validate(full, &p) != 0 && !strcmp(p.pointer, "/size/sieve/1/0"));
    CHECK(gp_spec2d_read(full, &s, &p) == 0 && s.nsieve == 2 && s.sieve_d[1] < s.sieve_d[0]);
    gp_spec2d_free(&s);
    /* the cheap guard: the kind; a field missing or malformed is "internal" at that field */
    CHECK(gp_spec3d_read(full, &t, &p) != 0 && !strcmp(p.code, "invalid_spec"));
    CHECK(!strcmp(p.pointer, "/kind") && strstr(p.message, "expected \"spheres-3d\" here"));
    gp_spec3d_free(&t);
    json_object_del(full, "contour_points");
    CHECK(gp_spec2d_read(full, &s, &p) != 0 && !strcmp(p.code, "internal"));
    CHECK(!strcmp(p.pointer, "/contour_points") && s.sieve_d == NULL);
    gp_spec2d_free(&s);
    json_decref(full);
    json_decref(j);
    /* a spec as posted is no effective spec */
    j = load(MIN3D);
    CHECK(gp_spec3d_read(j, &t, &p) != 0 && !strcmp(p.code, "internal") && p.pointer[0] == '/');
    gp_spec3d_free(&t);
    json_decref(j);
    j = load(EX2D);
    json_object_set_new(json_object_get(j, "container"), "polygon", json_pack("[[i, i], [i, i]]", 0, 0, 1, 1));
    CHECK(gp_spec2d_read(j, &s, &p) != 0 && !strcmp(p.code, "internal"));
    gp_spec2d_free(&s);
    json_decref(j);
    CHECK(gp_spec2d_read(NULL, &s, NULL) != 0);
    gp_spec2d_free(&s);
}

/* ---- core/2d/gp_rings: the fault and where it is ---- */

static gp_rings_fault rings_fault(const gp_vec2 *outer, size_t n, const gp_vec2 *hole, size_t nh)
{
    gp_ring_ref r[2] = {{outer, n}, {hole, nh}};
    gp_rings_fault f;
    gp_error err;
    gp_status st = gp_rings_check(r, hole ? 2 : 1, &f, &err);
    CHECK((st == GP_OK) == (f.kind == GP_RINGS_OK));
    CHECK(st == GP_OK || (st == GP_ERR_INVALID && err.message[0]));
    return f;
}

static void test_rings(void)
{
    const gp_vec2 square[] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
    const gp_vec2 bowtie[] = {{0, 0}, {4, 4}, {4, 0}, {0, 4}};
    const gp_vec2 fold[] = {{0, 0}, {2, 0}, {1, 0}, {1, 1}};
    const gp_vec2 line[] = {{0, 0}, {1, 1}, {2, 2}};
    const gp_vec2 inner[] = {{1, 1}, {2, 1}, {2, 2}};
    const gp_vec2 outside[] = {{5, 5}, {6, 5}, {6, 6}};
    /* a vertex on edge 3 of the square: the lower ring is named first, then the hole's edge that
     * the sweep meets (2, from (1, 3) back to that vertex) */
    const gp_vec2 touching[] = {{0, 2}, {1, 1}, {1, 3}};
    CHECK(rings_fault(square, 4, NULL, 0).kind == GP_RINGS_OK);
    CHECK(rings_fault(square, 4, inner, 3).kind == GP_RINGS_OK);
    gp_rings_fault f = rings_fault(bowtie, 4, NULL, 0);
    CHECK(f.kind == GP_RINGS_CROSS && f.ring == 0 && f.ring2 == 0 && f.edge == 0 && f.edge2 == 2);
    f = rings_fault(fold, 4, NULL, 0);
    CHECK(f.kind == GP_RINGS_FOLD && f.ring == 0 && f.edge == 0 && f.edge2 == 1);
    CHECK(rings_fault(line, 3, NULL, 0).kind == GP_RINGS_DEGENERATE);
    CHECK(rings_fault(square, 2, NULL, 0).kind == GP_RINGS_DEGENERATE);
    f = rings_fault(square, 4, outside, 3);
    CHECK(f.kind == GP_RINGS_HOLE_OUTSIDE && f.ring == 1);
    f = rings_fault(square, 4, touching, 3);
    CHECK(f.kind == GP_RINGS_CROSS && f.ring == 0 && f.edge == 3 && f.ring2 == 1 && f.edge2 == 2);
    /* a hole in a hole, and the outer ring inside a hole */
    gp_ring_ref r[3] = {{square, 4}, {inner, 3}, {inner, 3}};
    const gp_vec2 big[] = {{0.5, 0.5}, {3, 0.5}, {3, 3}, {0.5, 3}};
    r[1] = (gp_ring_ref){big, 4};
    CHECK(gp_rings_check(r, 3, &f, NULL) == GP_ERR_INVALID);
    CHECK(f.kind == GP_RINGS_HOLE_IN_HOLE && f.ring == 2 && f.ring2 == 1);
    f = rings_fault(inner, 3, square, 4);
    CHECK(f.kind == GP_RINGS_HOLE_OUTSIDE && f.ring == 1);
    CHECK(gp_rings_check(NULL, 0, NULL, NULL) == GP_ERR_INVALID);
}

int main(int argc, char **argv)
{
    g_verbose = argc > 1;
    test_examples();
    test_defaults();
    test_tables();
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
    test_parsers_read_effective_specs();
    test_rings();
    return gp_test_summary();
}
