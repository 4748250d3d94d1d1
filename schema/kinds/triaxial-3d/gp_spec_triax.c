/* gp_spec_triax.c -- the kind "triaxial-3d": its specimen (a spheres-3d spec, inline once the
 * daemon has resolved a specimen job), the reader of an effective spec into gp_spec_triax, its
 * semantic checks (the specimen, the part, the work of the tests) and its work and result
 * bounds. See gp_spec_triax.h. */
#include "gp_spec_internal.h"

#include "gp_spec_specimen.h"
#include "gp_spec_triax.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gp_spec_kind gp_spec_kind_triaxial_3d; /* this kind, defined at the end */

extern const unsigned char gp_schema_text_triaxial_3d[];

#define TRIAX_SPHERE_STEPS_PER_S 4e6 /* the 3D DEM, sphere-steps a second (as gp_spec3d.c) */
#define TRIAX_MAX_SPHERES 400000.0   /* spheres a test runs on at most (the DEM sample's limit) */
#define TRIAX_DEFAULT_RATE 0.01      /* the schema's default strain rate (the paper's) */
/* the result's text: a sphere [x, y, z, r] at 17 digits; a point of a curve (15 numbers); a
 * test's stats; the rest */
#define TRIAX_BYTES_SPHERE 90.0
#define TRIAX_BYTES_POINT (15 * 24.0)
#define TRIAX_BYTES_TEST 2000.0
#define TRIAX_BYTES_FIXED 20000.0

/* the names of the outputs, at the index of their bit (GP_OUT_TRIAX_*) */
static const char *const g_outputs[] = {"curves", "spheres"};

/* ------------------------------------------------------------------------------------------ */
/* the reader (an effective spec: nothing is checked but its form) */

void gp_spec_triax_free(gp_spec_triax *s)
{
    if (!s) return;
    gp_spec3d_free(&s->specimen);
    memset(s, 0, sizeof *s);
}

/* the material's overrides of the specimen's */
static void read_material(gp_spec_reader *r, const json_t *full, gp_material3d *m)
{
    static const char *const ptr[] = {"/material/density", "/material/young", "/material/poisson",
                                      "/material/friction_deg", "/material/damping"};
    double *field[] = {&m->density, &m->young, &m->poisson, &m->friction_deg, &m->damping};
    const json_t *o = gp_rd_member(r, full, "/material", JSON_OBJECT, 1);
    for (size_t i = 0; o && i < sizeof ptr / sizeof *ptr; i++) {
        const json_t *v = gp_rd_member(r, o, ptr[i], JSON_REAL, 1);
        if (v) *field[i] = gp_rd_value(r, v, ptr[i], -GP_RD_ANY, GP_RD_ANY);
    }
}

/* the test's fields: material, confining stresses, strain, rate, drainage, outputs */
static void read_test(gp_spec_reader *r, const json_t *full, gp_spec_triax *out)
{
    static const char *const drainage[] = {"drained", "constant_volume"};
    out->material = out->specimen.material;
    read_material(r, full, &out->material);
    const json_t *conf = gp_rd_array(r, full, "/confining_kpa", 1, GP_SPEC_TRIAX_MAX_TESTS, 0);
    out->ntests = json_array_size(conf);
    for (size_t i = 0; i < out->ntests; i++)
        out->confining[i] = 1e3 * gp_rd_value(r, json_array_get(conf, i), "/confining_kpa",
                                              -GP_RD_ANY, GP_RD_ANY);
    out->axial_strain = gp_rd_num(r, full, "/axial_strain", -GP_RD_ANY, GP_RD_ANY);
    out->strain_rate = gp_rd_num(r, full, "/strain_rate", -GP_RD_ANY, GP_RD_ANY);
    out->drainage = gp_rd_enum(r, full, "/drainage", drainage, 2) ? GP_TRIAX_CONSTANT_VOLUME
                                                                  : GP_TRIAX_DRAINED;
    out->outputs = gp_rd_flags(r, full, "/outputs", g_outputs, 2);
}

/* the specimen as the core builds it for the test, and its sieve's d50 and smallest radius */
static void settle_specimen(gp_spec_triax *s)
{
    gp_spec3d *sp = &s->specimen;
    sp->outputs = GP_OUT3_SPHERES;
    if (!s->tiled) sp->tiling[0] = sp->tiling[1] = sp->tiling[2] = 1;
    s->d50 = gp_spec_sieve_quantile(sp->sieve, sp->nsieve, 50);
    s->r_min = sp->nsieve ? 0.5 * sp->sieve[0].diameter : 0;
}

int gp_spec_triax_read(const json_t *full, gp_spec_triax *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    p = gp_spec_begin(p, &local);
    if (gp_spec_read_begin(&gp_spec_kind_triaxial_3d, full, out, sizeof *out, p)) return -1;
    static const char *const parts[] = {"sample", "tiled"};
    gp_spec_reader r = {0};
    out->seed = (uint64_t)gp_rd_num(&r, full, "/seed", 0, GP_RD_COUNT);
    out->tiled = gp_rd_enum(&r, json_object_get(full, "specimen"), "/specimen/part", parts, 2);
    if (r.bad) return gp_rd_finish(&r, p);
    if (gp_spec_specimen_read(full, &out->specimen, out->job, p)) return -1;
    read_test(&r, full, out);
    settle_specimen(out);
    int rc = gp_rd_finish(&r, p);
    if (rc) gp_spec_triax_free(out);
    return rc;
}

void gp_spec_triax_params(const gp_spec_triax *s, size_t i, gp_triax_params *out)
{
    gp_triax_params_defaults(out);
    out->confining = s->confining[i];
    out->axial_strain = s->axial_strain;
    out->strain_rate = s->strain_rate;
    out->drainage = s->drainage;
    out->d50 = s->d50;
    out->samples = GP_SPEC_TRIAX_SAMPLES;
    out->threads = s->threads;
    out->max_steps = gp_triax_estimate_steps(&s->material, s->r_min, out);
}

/* ------------------------------------------------------------------------------------------ */
/* work and result bounds */

/* what the tests cost */
typedef struct triax_work {
    gp_spec_bounds_t specimen; /* the specimen's bounds (its own spec's) */
    double spheres;            /* spheres of the part the tests run on */
    double steps;              /* DEM steps of all the tests at most (their max_steps) */
    double test_s;             /* the tests' seconds of one core */
} triax_work;

static int work_of(const json_t *full, const gp_spec_triax *s, triax_work *w,
                   gp_spec_problem *p)
{
    if (gp_spec_specimen_bounds(full, &w->specimen, p)) return -1;
    w->spheres = s->tiled ? w->specimen.items : w->specimen.cells;
    w->steps = 0;
    for (size_t i = 0; i < s->ntests; i++) {
        gp_triax_params tp;
        gp_spec_triax_params(s, i, &tp);
        w->steps += (double)tp.max_steps;
    }
    w->test_s = w->spheres * w->steps / TRIAX_SPHERE_STEPS_PER_S;
    return 0;
}

/* the field that drives the work: the first whose usual value would bring it within budget
 * (the sample instead of the tiling, the specimen's material, the paper's rate, one test), else
 * the specimen's size */
static const char *work_driver(const json_t *full, const gp_spec_triax *s, const triax_work *w)
{
    double room = GP_SPEC_WORK_BUDGET_S - w->specimen.work_s;
    if (s->tiled && w->specimen.items > w->specimen.cells &&
        w->test_s * w->specimen.cells / w->specimen.items <= room)
        return "/specimen/part";
    const gp_material3d *m = &s->material, *m0 = &s->specimen.material;
    double ky = m->young / m0->young, kd = m0->density / m->density; /* steps ~ sqrt(E / rho) */
    const json_t *mo = json_object_get(full, "material");
    if ((json_object_get(mo, "young") || json_object_get(mo, "density")) && ky * kd > 1 &&
        w->test_s / sqrt(ky * kd) <= room)
        return ky >= kd ? "/material/young" : "/material/density";
    if (s->strain_rate < TRIAX_DEFAULT_RATE &&
        w->test_s * s->strain_rate / TRIAX_DEFAULT_RATE <= room)
        return "/strain_rate";
    if (s->ntests > 1 && w->test_s / (double)s->ntests <= room) return "/confining_kpa";
    return s->job[0] ? "/specimen/job" : "/specimen/spec/box";
}

static const gp_spec_advice g_work_advice[] = {
    {"/specimen/part", "test the sample (part \"sample\"): the tiled packing has as many times "
                       "more spheres as it has tiles"},
    {"/material/young", "use a softer young (the specimen's): the time step scales as "
                        "1/sqrt(young)"},
    {"/material/density", "use a higher density (the specimen's)"},
    {"/strain_rate", "use a faster strain_rate (the paper's 0.01 /s)"},
    {"/confining_kpa", "test fewer confining stresses in one job"},
    {NULL, "test a smaller specimen (fewer spheres) or at a faster strain_rate"}};

static const gp_spec_advice g_result_advice[] = {
    {NULL, "spheres (leave \"spheres\" out of outputs, or test the sample)"}};

static void fill_bounds(const gp_spec_triax *s, const triax_work *w, const json_t *full,
                        gp_spec_bounds_t *b)
{
    memset(b, 0, sizeof *b);
    b->cells = w->specimen.cells;
    b->items = w->spheres;
    b->steps = w->steps;
    b->dt = w->specimen.dt;
    b->work_s = w->specimen.work_s + w->test_s;
    b->work_pointer = work_driver(full, s, w);
    int curves = (s->outputs & GP_OUT_TRIAX_CURVES) != 0;
    int spheres = (s->outputs & GP_OUT_TRIAX_SPHERES) != 0;
    b->result_bytes = TRIAX_BYTES_FIXED +
                      (double)s->ntests * (TRIAX_BYTES_TEST +
                                           curves * GP_SPEC_TRIAX_SAMPLES * TRIAX_BYTES_POINT) +
                      spheres * w->spheres * TRIAX_BYTES_SPHERE;
    b->result_pointer = !spheres ? "/confining_kpa" : s->tiled ? "/specimen/part" : "/outputs";
}

static int bounds_triax(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    gp_spec_triax s;
    triax_work w;
    int rc = gp_spec_triax_read(full, &s, p) || work_of(full, &s, &w, p);
    if (!rc) fill_bounds(&s, &w, full, b);
    gp_spec_triax_free(&s);
    return rc ? -1 : 0;
}

/* ------------------------------------------------------------------------------------------ */
/* the semantic checks */

/* part "tiled" needs a tiling */
static int check_part(const gp_spec_triax *s, gp_spec_problem *p)
{
    const int *t = s->specimen.tiling;
    if (!s->tiled || t[0] * t[1] * t[2] > 1) return 0;
    return gp_problem(p, "invalid_spec", "/specimen/part", "the specimen%s%s is not tiled (its "
                      "spec has no tiling): test part \"sample\", or a specimen with a tiling",
                      s->job[0] ? " of job " : "", s->job);
}

/* the spheres a test can run on, and the work budget */
static int check_work(const json_t *full, const gp_spec_triax *s, const triax_work *w,
                      gp_spec_problem *p)
{
    if (w->spheres > TRIAX_MAX_SPHERES) /* (a sample has at most as many: only a tiling) */
        return gp_spec_too_large(p, "/specimen/part", "the tiled packing has about %.3g "
                                 "spheres, over the limit of %.0f spheres a test runs on; test "
                                 "the sample (part \"sample\")", w->spheres, TRIAX_MAX_SPHERES);
    gp_spec_bounds_t b;
    fill_bounds(s, w, full, &b);
    char what[200];
    snprintf(what, sizeof what, "about %.2g DEM steps of %.0f spheres in %zu tests, and the "
             "specimen", w->steps, w->spheres, s->ntests);
    return gp_spec_over_budget(&b, what, g_work_advice, p);
}

static int check_triax(const json_t *full, gp_spec_problem *p)
{
    gp_spec_triax s;
    triax_work w;
    int rc = gp_spec_triax_read(full, &s, p) || check_part(&s, p) || work_of(full, &s, &w, p) ||
             check_work(full, &s, &w, p);
    gp_spec_triax_free(&s);
    return rc ? -1 : 0;
}

const gp_spec_kind gp_spec_kind_triaxial_3d = {
    .name = "triaxial-3d",
    .schema_text = gp_schema_text_triaxial_3d,
    .check_posted = gp_spec_specimen_check_posted,
    .settle_defaults = gp_spec_specimen_settle,
    .check = check_triax,
    .bounds = bounds_triax,
    .items = "spheres",
    .result_advice = g_result_advice,
};
