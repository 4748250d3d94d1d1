/* kind_geostatic.c -- the kind "geostatic-3d": a sphere packing settled at rest under gravity
 * and measured in slabs (core/3d/gp_geostatic.h; Dang & Meguid 2010, "Stress Distribution",
 * Fig. 8). Its spec is schema/kinds/geostatic-3d/, its result result_geostatic.c (the format
 * is there), its views svg_geostatic.c.
 *
 * Submit: a specimen given as {"job": id} is resolved at once into that job's stored
 * effective spec, the id kept (as the triaxial test's: gpd_resolve_job), and phi_from's
 * {"job": id} into that triaxial job's Mohr-Coulomb phi', written beside the id: the worker
 * reads neither job, either of which may be purged meanwhile. A triaxial job without an
 * envelope (one confinement, or a failed fit) is refused there, at /phi_from/job.
 *
 * Run: the specimen (gp_specimen3d_build, part "sample" without its tiling), then
 * gp_geostatic_run on its spheres in its box. A packing not at rest within max_steps is
 * measured as it is: the job succeeds with converged false and a warning (the state is
 * what a user would inspect to choose a larger bound). Progress: the specimen's phases, then
 * "settling" (its fraction by the log of S_c, with steps and S_c) and "measuring". */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_geostatic.h"
#include "gp_spec.h"
#include "gp_spec_specimen.h"
#include "gp_specimen3d.h"
#include "kinds/geostatic-3d/gp_spec_geostatic.h"
#include "kinds/geostatic-3d/result_geostatic.h"
#include "kinds/geostatic-3d/svg_geostatic.h"
#include "kinds/kind.h"
#include "kinds/kind_specimen.h"

#define KIND_NAME "geostatic-3d"

/* ------------------------------------------------------------------ progress */

/* {steps, porosity, stability} */
static json_t *progress_detail(const gp_progress *p)
{
    return json_pack("{s:I, s:o, s:o}", "steps", (json_int_t)p->steps, "porosity",
                     gpd_jreal(p->porosity > 0 ? p->porosity : NAN), "stability",
                     gpd_jreal(p->stability));
}

/* ------------------------------------------------------------------ the run */

static void geo_destroy(gpd_geostatic_run *run)
{
    if (!run) return;
    gp_specimen3d_destroy(run->specimen);
    gp_geostatic_result_destroy(run->state);
    free(run);
}

static gp_status build_specimen(gpd_geostatic_run *run, const gp_spec_geostatic *s,
                                gp_progress_fn fn, void *user, const volatile int *cancel,
                                gp_error *err)
{
    return gpd_specimen_build(&s->specimen, s->threads, fn, user, cancel, &run->specimen,
                              &run->specimen_ok, err);
}

static gp_status settle(gpd_geostatic_run *run, const gp_spec_geostatic *s, gp_progress_fn fn,
                        void *user, const volatile int *cancel, gp_error *err)
{
    gp_geostatic_params gp = s->params;
    gp.threads = s->threads;
    const gp_specimen3d *sp = run->specimen;
    const double lo[3] = {0, 0, 0};
    gp_status st = gp_geostatic_run(&gp, sp->spheres, sp->count, lo, sp->box, fn, user, cancel,
                                    &run->state, err);
    if (st == GP_ERR_NOT_CONVERGED && run->state) return GP_OK; /* measured, with a warning */
    return gpd_specimen_failed_in(st, err, "the settling");
}

static gp_status geo_build(const gp_spec_geostatic *s, gp_progress_fn fn, void *user,
                           const volatile int *cancel, gpd_geostatic_run **out, gp_error *err)
{
    gpd_geostatic_run *run = calloc(1, sizeof *run);
    *out = run;
    if (!run) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    run->outputs = s->outputs;
    gp_status st = build_specimen(run, s, fn, user, cancel, err);
    if (!st) st = settle(run, s, fn, user, cancel, err);
    return st;
}

GPD_KIND_CORE(gp_spec_geostatic, gp_spec_geostatic_read, gp_spec_geostatic_free,
              gpd_geostatic_run, geo_build, geo_destroy)

/* the specimen's stop reason, when its build failed */
static void failure_note(const void *specimen, char *buf, size_t n)
{
    const gpd_geostatic_run *run = specimen;
    if (run->specimen && !run->specimen_ok && run->specimen->stats.stop_reason)
        snprintf(buf, n, " (stop reason: %s)", run->specimen->stats.stop_reason);
}

/* ------------------------------------------------------------------ submit */

/* phi_from's triaxial job: its Mohr-Coulomb phi' beside the id */
static int resolve_phi(json_t *spec, gpd_job_lookup lookup, gp_spec_problem *p)
{
    json_t *from = json_object_get(spec, "phi_from"), *js, *sum;
    /* (not an object, or phi_deg beside it: the spec's checks refuse it) */
    if (!json_is_object(from) || json_object_get(spec, "phi_deg")) return 0;
    int rc = gpd_resolve_job(from, "/phi_from", gp_spec_geostatic_phi_kind(), "phi_deg", lookup,
                             &js, &sum, p);
    if (rc) return rc > 0 ? 0 : -1;
    const json_t *mc = json_object_get(json_object_get(sum, "stats"), "mohr_coulomb");
    const json_t *phi = json_object_get(mc, "phi_deg");
    double v = json_is_number(phi) ? json_number_value(phi) : NAN;
    const char *id = json_string_value(json_object_get(from, "job"));
    json_decref(js);
    json_decref(sum);
    if (!(v > 0 && v < 90))
        return gp_problem(p, "invalid_spec", "/phi_from/job", "job %s has no Mohr-Coulomb "
                          "friction angle (its tests gave no envelope: it takes two confining "
                          "stresses or more): give phi_deg instead", id);
    return json_object_set_new(from, "phi_deg", json_real(v))
               ? gp_problem(p, "internal", "", "out of memory") : 0;
}

static int resolve(json_t *spec, gpd_job_lookup lookup, gp_spec_problem *p)
{
    return gpd_resolve_specimen(spec, lookup, p) || resolve_phi(spec, lookup, p) ? -1 : 0;
}

/* the spheres settled once it has succeeded, and the mean K0 */
static json_t *brief(const json_t *spec, const json_t *stats)
{
    json_t *particles = NULL, *achieved = NULL;
    if (stats) {
        particles = json_deep_copy(json_object_get(stats, "particles"));
        achieved = json_deep_copy(json_object_get(json_object_get(stats, "k0"), "mean"));
    }
    json_t *b = gpd_brief_new(spec, "k0", particles, achieved);
    /* K0's target is its theory, 1 - sin phi' */
    const json_t *from = json_object_get(spec, "phi_from");
    const json_t *phi = json_object_get(from ? from : spec, "phi_deg");
    double deg = phi ? json_number_value(phi) : GP_SPEC_GEOSTATIC_PHI_DEG;
    json_object_set_new(json_object_get(b, "headline"), "target",
                        gpd_jreal(1 - sin(deg * M_PI / 180)));
    return b;
}

/* ------------------------------------------------------------------ the plan */

#define SPHERE_STEPS_S 4e6   /* the settling's DEM, sphere-steps a second on one core */
#define MEASURE_S 2e-6       /* the measures, seconds a sphere */
#define BYTES_SPHERE 90.0    /* the result's text: a sphere [x, y, z, r] at 17 digits */
/* the settling's time, s of the DEM's clock, at a height of 1 m, and how it grows with the
 * height (S0 tiled 2 x 2 x 2 and 4 x 4 x 4: ~5 s and ~7.3 s) */
#define SETTLE_T_1M 5.0
#define SETTLE_T_EXP 0.57
#define SETTLE_DT_RATIO 2.0  /* the settling's step over the specimen's (density scaling) */

static int plan(const void *spec_, const json_t *spec_json, gpd_phase *out, int max)
{
    const gp_spec_geostatic *s = spec_;
    const json_t *inner = json_object_get(json_object_get(spec_json, "specimen"), "spec");
    gpd_phase ph[GPD_PLAN_MAX];
    int k = gpd_specimen_phases(&s->specimen, inner, ph);
    gp_spec_bounds_t b;
    gp_spec_problem prob;
    double n = gp_spec_bounds(inner, &b, &prob) ? 0 : s->tiled ? b.items : b.cells;
    const int *t = s->specimen.tiling;
    double height = s->specimen.box[2] * (s->tiled ? t[2] : 1);
    double dt = SETTLE_DT_RATIO * b.dt;
    double steps = dt > 0 ? SETTLE_T_1M * pow(height, SETTLE_T_EXP) / dt : 0;
    steps = fmin(steps, (double)s->params.max_steps);
    if (k + 3 > max) return 0;
    memcpy(out, ph, (size_t)k * sizeof *ph);
    out[k++] = (gpd_phase){"settling", n * steps / SPHERE_STEPS_S, 1};
    out[k++] = (gpd_phase){"measuring", n * MEASURE_S, 1};
    double bytes = (s->outputs & GP_OUT_GEO_SPHERES) ? BYTES_SPHERE * n : 0;
    out[k++] = (gpd_phase){"result", GPD_RESULT_S_PER_BYTE * bytes, 1};
    return k;
}

static double result_cost(const void *specimen) { return result_geostatic_cost(specimen); }

static json_t *result(const void *specimen, const void *spec, const json_t *spec_json, gpd_jw *w)
{
    return result_geostatic_write(specimen, spec, spec_json, w);
}

/* no export pack: its export is the profile's csv, written from the result */
static int pack(const void *specimen, const void *spec, void **pack, size_t *len, gp_error *err)
{
    return 1;
}

/* a result without "kind": its profile or its K0 */
static int owns_result(const json_t *r)
{
    return json_object_get(r, "profile") || json_object_get(json_object_get(r, "stats"), "k0");
}

/* the api.md example, with the paper's sample given inline and tiled 2 x 2 x 2 */
static const char example[] =
    "{\"kind\": \"" KIND_NAME "\", \"seed\": 7,"
    " \"specimen\": {\"spec\": {\"box\": [0.5, 0.5, 0.5],"
    " \"sieve\": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], \"sieve_units\": \"mm\","
    " \"porosity\": 0.38, \"tiling\": [2, 2, 2]}},"
    " \"gravity\": [0, 0, -9.81], \"wall_friction_deg\": 0, \"phi_deg\": 23.7, \"slab\": 0.25,"
    " \"outputs\": [\"profile\", \"spheres\"]}";

static const gpd_view views[] = {
    {"profile", "", svg_geostatic_profile, "profile"},
    {"k0", "", svg_geostatic_k0, "profile"},
    {"stress-map", "", svg_geostatic_stress_map, NULL},
    {NULL, NULL, NULL, NULL},
};

static const gpd_kind_export exports[] = {
    {"csv", "csv", "text/csv; charset=utf-8", result_geostatic_csv},
    {NULL, NULL, NULL, NULL},
};

/* the phases of its "timings" (result) */
static const char *const phases[] = {"specimen", "settling", "measure", "total", NULL};

const gpd_kind gpd_kind_geostatic = {
    .name = KIND_NAME, .example = example, .views = views, .owns_result = owns_result,
    .resolve = resolve, .bounds = gp_spec_check_result, .brief = brief,
    GPD_KIND_CORE_OPS(gp_spec_geostatic), .progress_detail = progress_detail, .plan = plan,
    .result_cost = result_cost, .result = result, .pack = pack, .failure_note = failure_note,
    .export_dim = 0, .exports = exports, .pack_what = "profile", .pack_output = "profile",
    .phases = phases};
