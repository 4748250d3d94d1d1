/* kind_triax.c -- the kind "triaxial-3d": a triaxial test of a sphere specimen (core/3d/gp_triax.h;
 * Dang & Meguid 2010, "Triaxial Tests", Fig. 7). Its spec is schema/kinds/triaxial-3d/, its
 * result result_triax.c (the format is there), its views svg_triax.c.
 *
 * Submit: a specimen given as {"job": id} is resolved at once (resolve: the job must exist, be
 * of the spheres' kind and have succeeded) into that job's stored effective spec, the id kept:
 * the worker rebuilds the specimen from it -- the same spec and seed give the same spheres bit
 * for bit -- and never reads the other job, which may be purged meanwhile. A specimen spec
 * given inline is built the same way.
 *
 * Run: the specimen (gp_specimen3d_build; part "sample" is built without its tiling: the
 * sample is the same, the tiling comes after it), then one test per confining stress on its
 * spheres in its box (gp_triax_run), then the Mohr-Coulomb envelope of the peaks. Progress:
 * the specimen's phases (deposition, compaction, relaxation, tiling; one phase "specimen" when
 * there are more than DETAILED_MAX_TESTS tests, so that the plan fits GPD_PLAN_MAX), then
 * "consolidation" and "loading" for each confinement, the loading's fraction by axial strain;
 * the detail says which test and, while loading, the axial strain reached. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_spec.h"
#include "gp_spec_specimen.h"
#include "gp_specimen3d.h"
#include "gp_triax.h"
#include "kinds/kind.h"
#include "kinds/kind_specimen.h"
#include "kinds/triaxial-3d/gp_spec_triax.h"
#include "kinds/triaxial-3d/result_triax.h"
#include "kinds/triaxial-3d/svg_triax.h"

#define KIND_NAME "triaxial-3d"

#define DETAILED_MAX_TESTS 3 /* 4 phases of the specimen + 2 a test + the result <= GPD_PLAN_MAX */

/* ------------------------------------------------------------------ progress */

/* What the workers get as a report (and hand back to progress_detail): the core's, renamed
 * where the plan has other names, and what the detail says besides. */
typedef struct triax_progress {
    gp_progress p;              /* first: the workers see this */
    const char *specimen_phase; /* the core's phase when the specimen shows as one phase */
    int test, ntests;           /* the test (index in confining_kpa), -1 for the specimen */
    double confining_kpa;
    double axial_strain;        /* while loading, else NaN */
} triax_progress;

typedef struct relay {
    gp_progress_fn fn;
    void *user;
    const gp_spec_triax *s;
    int test;
} relay;

static int merged(const gp_spec_triax *s) { return s->ntests > DETAILED_MAX_TESTS; }

static int relay_progress(void *user, const gp_progress *p)
{
    relay *rl = user;
    triax_progress tp = {*p, NULL, rl->test, (int)rl->s->ntests, NAN, NAN};
    if (rl->test < 0 && merged(rl->s)) {
        tp.specimen_phase = p->phase;
        tp.p.phase = "specimen";
        tp.p.phase_fraction = p->fraction;
    } else if (rl->test >= 0) {
        tp.confining_kpa = rl->s->confining[rl->test] * 1e-3;
        if (p->phase && !strcmp(p->phase, "loading"))
            tp.axial_strain = p->phase_fraction * rl->s->axial_strain;
    }
    return rl->fn ? rl->fn(rl->user, &tp.p) : 0;
}

/* {steps, porosity, stability}, and {test, tests, confining_kpa, axial_strain} in a test */
static json_t *progress_detail(const gp_progress *p)
{
    const triax_progress *t = (const triax_progress *)p; /* relay_progress's */
    /* (the core measures no porosity while it consolidates: 0 there, shown as null) */
    json_t *d = json_pack("{s:I, s:o, s:o}", "steps", (json_int_t)p->steps, "porosity",
                          gpd_jreal(p->porosity > 0 ? p->porosity : NAN), "stability",
                          gpd_jreal(p->stability));
    if (d && t->specimen_phase)
        json_object_set_new(d, "specimen_phase", json_string(t->specimen_phase));
    if (d && t->test >= 0) {
        json_object_set_new(d, "test", json_integer(t->test));
        json_object_set_new(d, "tests", json_integer(t->ntests));
        json_object_set_new(d, "confining_kpa", gpd_jreal(t->confining_kpa));
        if (isfinite(t->axial_strain))
            json_object_set_new(d, "axial_strain", gpd_jreal(t->axial_strain));
    }
    return d;
}

/* ------------------------------------------------------------------ the run */

static void triax_destroy(gpd_triax_run *run)
{
    if (!run) return;
    gp_specimen3d_destroy(run->specimen);
    for (size_t i = 0; i < GP_SPEC_TRIAX_MAX_TESTS; i++) gp_triax_result_destroy(run->test[i]);
    free(run);
}

static gp_status build_specimen(gpd_triax_run *run, const gp_spec_triax *s, relay *rl,
                                const volatile int *cancel, gp_error *err)
{
    rl->test = -1;
    return gpd_specimen_build(&s->specimen, s->threads, relay_progress, rl, cancel,
                              &run->specimen, &run->specimen_ok, err);
}

static gp_status run_test(gpd_triax_run *run, const gp_spec_triax *s, size_t i, relay *rl,
                          const volatile int *cancel, gp_error *err)
{
    gp_triax_params tp;
    gp_spec_triax_params(s, i, &tp);
    rl->test = (int)i;
    const gp_specimen3d *sp = run->specimen;
    const double lo[3] = {0, 0, 0};
    gp_status st = gp_triax_run(&s->material, sp->spheres, sp->count, lo, sp->box, &tp,
                                relay_progress, rl, cancel, &run->test[i], err);
    if (!st) run->ntests = i + 1;
    char what[64];
    snprintf(what, sizeof what, "the test at %g kPa", s->confining[i] * 1e-3);
    return gpd_specimen_failed_in(st, err, what);
}

static gp_status triax_build(const gp_spec_triax *s, gp_progress_fn fn, void *user,
                             const volatile int *cancel, gpd_triax_run **out, gp_error *err)
{
    gpd_triax_run *run = calloc(1, sizeof *run);
    *out = run;
    if (!run) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    run->outputs = s->outputs;
    relay rl = {fn, user, s, -1};
    gp_status st = build_specimen(run, s, &rl, cancel, err);
    for (size_t i = 0; !st && i < s->ntests; i++) st = run_test(run, s, i, &rl, cancel, err);
    if (!st) result_triax_envelope(run);
    return st;
}

GPD_KIND_CORE(gp_spec_triax, gp_spec_triax_read, gp_spec_triax_free, gpd_triax_run, triax_build,
              triax_destroy)

/* the specimen's stop reason, when its build failed */
static void failure_note(const void *specimen, char *buf, size_t n)
{
    const gpd_triax_run *run = specimen;
    if (run->specimen && !run->specimen_ok && run->specimen->stats.stop_reason)
        snprintf(buf, n, " (stop reason: %s)", run->specimen->stats.stop_reason);
}

/* ------------------------------------------------------------------ submit */

/* the spheres tested once it has succeeded, and the Mohr-Coulomb friction angle */
static json_t *brief(const json_t *spec, const json_t *stats)
{
    json_t *particles = NULL, *achieved = NULL;
    if (stats) {
        particles = json_deep_copy(json_object_get(stats, "particles"));
        achieved = json_deep_copy(
            json_object_get(json_object_get(stats, "mohr_coulomb"), "phi_deg"));
    }
    return gpd_brief_new(spec, "phi_deg", particles, achieved);
}

/* ------------------------------------------------------------------ the plan */

#define SPHERE_STEPS_S 4.4e6 /* the test's DEM, sphere-steps a second on one core (measured: three
                               * tests of 275 spheres, consolidation and loading alike) */
#define CONS_GUESS 0.25      /* the consolidation's steps, a share of what it may take */
#define BYTES_SPHERE 90.0    /* the result's text: a sphere [x, y, z, r] at 17 digits */
#define BYTES_CURVES 360.0   /* a sample of a curve: 15 numbers */

/* the loading's time step: the specimen's rule (gp_specimen3d.h) at the smallest radius and
 * the test's damping, true masses (gp_triax.c) */
static double load_dt(const gp_spec_triax *s)
{
    const gp_material3d *m = &s->material;
    double r = s->r_min, mass = 4.0 / 3.0 * M_PI * r * r * r * m->density;
    return GP_SPEC3D_DT_SAFETY *
           pow((1 + GP_SPEC3D_RELAX_DAMPING) / (1 + m->damping), GP_SPEC3D_DT_DAMPING_EXP) *
           sqrt(mass / (2 * m->young * r));
}

/* the phases of test i on n spheres: its consolidation (until it converges) and its loading */
static void test_phases(const gp_spec_triax *s, size_t i, double n, gpd_phase *out)
{
    gp_triax_params tp;
    gp_spec_triax_params(s, i, &tp);
    double dt = load_dt(s);
    double load = dt > 0 ? s->axial_strain / s->strain_rate / dt : 0;
    double cons = CONS_GUESS * fmax(0, (double)tp.max_steps - load);
    out[0] = (gpd_phase){"consolidation", n * cons / SPHERE_STEPS_S, 0};
    out[1] = (gpd_phase){"loading", n * load / SPHERE_STEPS_S, 1};
}

/* the specimen's phases (its kind's plan, without its result), or one phase "specimen" */
static int specimen_phases(const gp_spec_triax *s, const json_t *inner, gpd_phase *out)
{
    gpd_phase sp[GPD_PLAN_MAX];
    int n = gpd_specimen_phases(&s->specimen, inner, sp);
    if (!merged(s)) {
        memcpy(out, sp, (size_t)n * sizeof *sp);
        return n;
    }
    double cost = 0;
    for (int k = 0; k < n; k++) cost += sp[k].cost_s;
    out[0] = (gpd_phase){"specimen", cost, 1};
    return 1;
}

static int plan(const void *spec_, const json_t *spec_json, gpd_phase *out, int max)
{
    const gp_spec_triax *s = spec_;
    const json_t *inner = json_object_get(json_object_get(spec_json, "specimen"), "spec");
    gpd_phase ph[2 * GPD_PLAN_MAX];
    int k = specimen_phases(s, inner, ph);
    gp_spec_bounds_t b;
    gp_spec_problem prob;
    double n = gp_spec_bounds(inner, &b, &prob) ? 0 : s->tiled ? b.items : b.cells;
    for (size_t i = 0; i < s->ntests; i++, k += 2) test_phases(s, i, n, ph + k);
    if (k + 1 > max) return 0;
    memcpy(out, ph, (size_t)k * sizeof *ph);
    double bytes = ((s->outputs & GP_OUT_TRIAX_SPHERES) ? BYTES_SPHERE * n : 0) +
                   ((s->outputs & GP_OUT_TRIAX_CURVES)
                        ? BYTES_CURVES * (double)(s->ntests * GP_SPEC_TRIAX_SAMPLES) : 0);
    out[k++] = (gpd_phase){"result", GPD_RESULT_S_PER_BYTE * bytes, 1};
    return k;
}

static double result_cost(const void *specimen) { return result_triax_cost(specimen); }

static json_t *result(const void *specimen, const void *spec, const json_t *spec_json, gpd_jw *w)
{
    return result_triax_write(specimen, spec, spec_json, w);
}

/* no export pack: its export is the curves' csv, written from the result */
static int pack(const void *specimen, const void *spec, void **pack, size_t *len, gp_error *err)
{
    return 1;
}

/* a result without "kind": its curves or its envelope */
static int owns_result(const json_t *r)
{
    return json_object_get(r, "curves") ||
           json_object_get(json_object_get(r, "stats"), "mohr_coulomb");
}

/* the api.md example, with the paper's sample given inline */
static const char example[] =
    "{\"kind\": \"" KIND_NAME "\", \"seed\": 7,"
    " \"specimen\": {\"spec\": {\"box\": [0.5, 0.5, 0.5],"
    " \"sieve\": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], \"sieve_units\": \"mm\","
    " \"porosity\": 0.38}, \"part\": \"sample\"},"
    " \"confining_kpa\": [50, 100], \"axial_strain\": 0.2, \"strain_rate\": 0.01,"
    " \"drainage\": \"drained\", \"outputs\": [\"curves\", \"spheres\"]}";

static const gpd_view views[] = {
    {"stress-strain", "", svg_triax_stress_strain, NULL},
    {"mohr", "", svg_triax_mohr, NULL},
    {"section", "z", svg_triax_section, NULL},
    {NULL, NULL, NULL, NULL},
};

static const gpd_kind_export exports[] = {
    {"csv", "csv", "text/csv; charset=utf-8", result_triax_csv},
    {NULL, NULL, NULL, NULL},
};

/* the phases of its "timings" (result) */
static const char *const phases[] = {"specimen", "consolidation", "loading", "total", NULL};

const gpd_kind gpd_kind_triax = {
    .name = KIND_NAME, .example = example, .views = views, .owns_result = owns_result,
    .resolve = gpd_resolve_specimen, .bounds = gp_spec_check_result, .brief = brief,
    GPD_KIND_CORE_OPS(gp_spec_triax), .progress_detail = progress_detail, .plan = plan,
    .result_cost = result_cost, .result = result, .pack = pack, .failure_note = failure_note,
    .export_dim = 0, .exports = exports, .pack_what = "curves", .pack_output = "curves",
    .phases = phases};
