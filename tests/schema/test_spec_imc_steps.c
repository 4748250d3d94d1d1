/* test_spec_imc_steps.c -- imc.max_steps of kind fourier-voronoi-2d when the spec leaves it
 * out: the effective spec keeps it absent, the parser resolves it from the cell count (10^6
 * up to 83,333 cells, 12 moves a cell beyond; a sieve's derived count too), the work bound
 * counts what the parser resolved, the default is clipped to the work budget but never below
 * 10^6, and a given max_steps is kept exactly. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_spec.h"
#include "gp_test.h"
#include "schema/spec_patch.h"

static const char BASE[] = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 500}";

/* the effective spec of BASE with ptr set to value, parsed: its max_steps, default flag and
 * the bounds' moves and cells; -1 when refused */
static long steps_of(const char *base, const char *ptr, const char *value, int *dflt,
                     gp_spec_bounds_t *b)
{
    json_t *full = effective(base, ptr, value);
    if (!full) return -1;
    gp_spec2d s;
    gp_spec_problem p;
    long steps = -1;
    if (gp_spec2d_read(full, &s, &p) == 0 && gp_spec_bounds(full, b, &p) == 0) {
        steps = s.imc_max_steps;
        *dflt = s.imc_max_steps_default;
    }
    gp_spec2d_free(&s);
    json_decref(full);
    return steps;
}

/* the default grows with N from 83,334 cells on; below, 10^6 as before */
static void default_by_count(void)
{
    const char *counts[] = {"1", "500", "83333", "100000", "1e6"};
    const long want[] = {1000000, 1000000, 1000000, 1200000, 12000000};
    for (int i = 0; i < 5; i++) {
        int dflt = 0;
        gp_spec_bounds_t b;
        long steps = steps_of(BASE, "/particles", counts[i], &dflt, &b);
        if (steps != want[i]) fprintf(stderr, "particles %s: max_steps %ld\n", counts[i], steps);
        CHECK(steps == want[i] && dflt == 1);
        CHECK(b.steps == (double)want[i]); /* the work bound counts the default */
    }
    /* the effective spec leaves it out (like imc.classes): the parser picks it */
    json_t *full = effective(BASE, "/particles", "1e6");
    CHECK(full && json_object_get(json_object_get(full, "imc"), "threshold") != NULL);
    CHECK(full && json_object_get(json_object_get(full, "imc"), "max_steps") == NULL);
    json_decref(full);
}

/* a given max_steps is the user's, whatever N: kept, 0 included, never raised */
static void given_is_kept(void)
{
    const char *spec = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6}";
    const char *given[] = {"0", "5000", "1000000", "1e9"};
    const long want[] = {0, 5000, 1000000, 1000000000};
    for (int i = 0; i < 4; i++) {
        int dflt = 1;
        gp_spec_bounds_t b;
        long steps = steps_of(spec, "/imc/max_steps", given[i], &dflt, &b);
        CHECK(steps == want[i] && dflt == 0 && b.steps == (double)want[i]);
    }
}

/* a sieve law: the default follows the count the sieve derives (0.5-1 mm in a 0.3 m square,
 * F_S 0.65: ~150,000 grains) */
static void sieve_count(void)
{
    const char *sieve = "{\"kind\": \"fourier-voronoi-2d\", \"size\": {\"law\": \"sieve\","
                        " \"sieve\": [[0.5, 0], [1, 100]]}, \"container\": {\"polygon\":"
                        " [[0, 0], [0.3, 0], [0.3, 0.3], [0, 0.3]]}}";
    int dflt = 0;
    gp_spec_bounds_t b;
    long steps = steps_of(sieve, "/seed", "1", &dflt, &b);
    printf("sieve: %.0f cells, max_steps %ld\n", b.cells, steps);
    CHECK(b.cells > 100000 && b.cells < 300000);
    CHECK(dflt == 1 && steps == 12 * (long)b.cells && b.steps == (double)steps);
}

/* The largest specs the limits accept keep being accepted with their default: 10^6 cells of
 * 4,096 points with every output (the grains ~1.1e5 s of the 1.7e5 s budget, the default
 * 1.2e7 moves ~2,000 s more); and one the budget refuses at 10^6 moves is refused as before. */
static void budget_accepts(void)
{
    const char *most = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"contour_points\":"
                       " 4096, \"outputs\": [\"grains\", \"odec\", \"descriptors\", \"cells\"]}";
    int dflt = 0;
    gp_spec_bounds_t b;
    long steps = steps_of(most, "/seed", "1", &dflt, &b);
    printf("10^6 cells, 4,096 points, every output: max_steps %ld, %.0f s of work\n", steps,
           b.work_s);
    CHECK(steps == 12000000 && dflt == 1);
    CHECK(b.work_s > 1e5 && b.work_s < GP_SPEC_WORK_BUDGET_S);
    /* 2 cells in a container of 10^4 edges: each move clips against thousands of them; 10^6
     * moves (the floor) are over the budget, as they were */
    json_t *ring = json_array();
    for (int i = 0; i < 9999; i++)
        json_array_append_new(ring, json_pack("[i, i]", i, i % 2));
    json_array_append_new(ring, json_pack("[i, i]", 5000, -10000));
    json_t *k = load("{\"kind\": \"fourier-voronoi-2d\", \"particles\": 2}");
    json_object_set_new(k, "container", json_pack("{s:o}", "polygon", ring));
    gp_spec_problem p;
    int rc = gp_spec_validate(k, &p);
    if (rc != 0) printf("%s\n", p.message);
    CHECK(rc != 0 && !strcmp(p.code, "too_large") &&
          !strcmp(p.pointer, "/container") && strstr(p.message, "1e+06 IMC moves at most "
                                                     "(imc.max_steps, the default)"));
    json_decref(k);
}

/* The clip, on effective specs the API's limits cannot make (the parser reads any effective
 * spec without validating it): grains of 6,250 points leave ~1,900 s of the budget, room for
 * ~1.1e7 moves on 10^6 cells, under the 1.2e7 of the rule, and the bound then sits just under
 * the budget; grains of 6,400 points are over it alone, and the default is its floor. */
static void clipped_to_budget(void)
{
    const char *base = "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 1e6, \"outputs\":"
                       " [\"grains\", \"odec\", \"descriptors\"]}";
    json_t *full = effective(base, "/seed", "1");
    CHECK(full != NULL);
    if (!full) return;
    const long np[2] = {6250, 6400};
    for (int i = 0; i < 2; i++) {
        json_object_set_new(full, "contour_points", json_integer(np[i]));
        gp_spec2d s;
        gp_spec_problem p;
        gp_spec_bounds_t b;
        CHECK(gp_spec2d_read(full, &s, &p) == 0 && gp_spec_bounds(full, &b, &p) == 0);
        printf("%ld points: max_steps %ld, %.0f s of work\n", np[i], s.imc_max_steps, b.work_s);
        CHECK(s.imc_max_steps_default == 1);
        if (i == 0) {
            CHECK(s.imc_max_steps > 10000000 && s.imc_max_steps < 12000000);
            CHECK(b.work_s < GP_SPEC_WORK_BUDGET_S && b.work_s > 0.99 * GP_SPEC_WORK_BUDGET_S);
        } else {
            CHECK(s.imc_max_steps == 1000000);
        }
        gp_spec2d_free(&s);
    }
    json_decref(full);
}

int main(void)
{
    default_by_count();
    given_is_kept();
    sieve_count();
    budget_accepts();
    clipped_to_budget();
    return gp_test_summary();
}
