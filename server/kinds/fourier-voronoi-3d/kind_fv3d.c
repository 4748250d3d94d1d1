/* kind_fv3d.c -- the kind "fourier-voronoi-3d": 3D Fourier-Voronoi specimens (core/3d/gp_fv3d.h)
 * with their result (result_fv3d.c), progress, SVG views (svg_fv3d.c) and export pack
 * (core/export: lammps, liggghts and yade of the clumps, vtk and stl of the grain surfaces).
 *
 * Progress: the core reports "imc" (detail {"steps", "error"}) and "grains" (detail
 * {"grains": done}); the plan adds "result". The brief's headline is the solid fraction. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_export.h"
#include "gp_fv3d.h"
#include "gp_grain3d.h"
#include "gp_imc.h"
#include "gp_spec.h"
#include "jobs/result_json.h"
#include "kinds/fourier-voronoi-3d/gp_spec_fv3d.h"
#include "kinds/fourier-voronoi-3d/result_fv3d.h"
#include "kinds/fourier-voronoi-3d/svg_fv3d.h"
#include "kinds/kind.h"
#include "util/util.h"

#define KIND_NAME "fourier-voronoi-3d"

/* the specimen the worker holds: the core's, the outputs its result's size depends on, and the
 * spec it was built of (the worker frees the spec after the specimen: workers.c run_kind) */
typedef struct fv3d_job {
    gp_fv3d *s;
    unsigned outputs;
    const gp_spec_fv3d *spec;
} fv3d_job;

/* the core's build on the job's threads */
static gp_status build_fv3d(const gp_spec_fv3d *spec, gp_progress_fn progress, void *user,
                            const volatile int *cancel, fv3d_job **out, gp_error *err)
{
    gp_fv3d_spec c = spec->core;
    c.threads = spec->threads > 0 ? spec->threads : 1;
    *out = calloc(1, sizeof **out);
    if (!*out) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    (*out)->outputs = c.outputs;
    (*out)->spec = spec;
    gp_status st = gp_fv3d_build(&c, progress, user, cancel, &(*out)->s, err);
    if (st != GP_OK) {
        free(*out);
        *out = NULL;
    }
    return st;
}

static void destroy_fv3d(fv3d_job *j)
{
    if (!j) return;
    gp_fv3d_destroy(j->s);
    free(j);
}

GPD_KIND_CORE(gp_spec_fv3d, gp_spec_fv3d_read, gp_spec_fv3d_free, fv3d_job, build_fv3d,
              destroy_fv3d)

/* imc: {steps, error}; grains: {grains} (done) */
static json_t *progress_detail(const gp_progress *p)
{
    if (p->phase && !strcmp(p->phase, "grains"))
        return json_pack("{s:I}", "grains", (json_int_t)p->steps);
    return json_pack("{s:I, s:o}", "steps", (json_int_t)p->steps, "error", gpd_jreal(p->error));
}

/* ---- the progress plan (progress.h): seconds on one core, measured on the development VM
 * (bench_imc3d's step rate; a 60- and a 1,000-grain job of the contract's example) ---- */
#define COST_CELL_S 15e-6     /* a Voronoi cell ... */
#define CELLS_A_MOVE 20.0     /* ... an IMC move recomputes this many ... */
#define COST_IMC_DECADE 0.2   /* ... 20 % more a tenfold more cells */
#define IMC_MOVES_GUESS 4.0   /* moves a cell to the threshold (a guess: the IMC runs until it */
#define IMC_MOVES_MIN 5000.0  /* converges or stalls; few cells need many moves a cell) */
#define COST_GRAIN_S 3.2e-3   /* a grain at level 4: radii, placement, mass ... */
#define COST_DESC_S 4.2e-3    /* ... its descriptors ... */
#define COST_CLUMP_S 7.5e-3   /* ... its clump of 30 spheres */

static double directions(unsigned level)
{
    return 10.0 * pow(4.0, level) + 2.0;
}

/* the phases: imc (the first tessellation, then the moves), grains, result */
static int plan(const void *spec_, const json_t *spec_json, gpd_phase *out, int max)
{
    const gp_spec_fv3d *spec = spec_;
    const gp_fv3d_spec *c = &spec->core;
    gp_spec_bounds_t b;
    gp_spec_problem p;
    if (max < 3 || gp_spec_bounds(spec_json, &b, &p)) return 0;
    double n = b.cells;
    double cell = COST_CELL_S * (1 + COST_IMC_DECADE * log10(fmax(n, 1000) / 1000));
    double moves = fmin((double)c->imc_max_steps, IMC_MOVES_GUESS * n + IMC_MOVES_MIN);
    double scale = directions(c->mesh_level) / directions(GP_GRAIN3D_LEVEL_DEFAULT);
    double grain = COST_GRAIN_S * scale;
    if (c->outputs & GP_OUT3_DESCRIPTORS) grain += COST_DESC_S * scale;
    if (c->outputs & GP_OUT3_CLUMPS) grain += COST_CLUMP_S * fmax(1, c->spheres_max / 30.0);
    out[0] = (gpd_phase){"imc", n * cell + moves * CELLS_A_MOVE * cell, 0};
    out[1] = (gpd_phase){"grains", n * grain, 1};
    out[2] = (gpd_phase){"result", GPD_RESULT_S_PER_BYTE * b.result_bytes, 1};
    return 3;
}

static double result_cost(const void *specimen)
{
    const fv3d_job *j = specimen;
    return GPD_RESULT_S_PER_BYTE * result_fv3d_bytes(j->s, j->outputs);
}

static json_t *result(const void *specimen, const void *spec, const json_t *spec_json,
                      gpd_jw *w)
{
    return result_fv3d_write(((const fv3d_job *)specimen)->s, spec, spec_json, w);
}

/* The export pack (core/export, GP_EXPORT_FV3D): the grains' poses, exact masses and
 * inertia, radii and clumps, made when the spec asked for the grains (1: no pack otherwise) */
static int pack(const void *specimen, const void *spec, void **pack, size_t *len,
                gp_error *err)
{
    (void)spec;
    const fv3d_job *j = specimen;
    *pack = NULL;
    *len = 0;
    if (!(j->outputs & GP_OUT3_GRAINS)) return 1;
    return gp_export_pack_fv3d(j->s, GP_EXPORT_DEFAULT_DENSITY, pack, len, err) ? -1 : 0;
}

/* How the IMC ended, the warnings and the fit summary (stats.fit without its CDF curves), so
 * that a poller of GET /v1/jobs/{id} sees them without the result. */
static json_t *done_detail(const char *id, const void *specimen)
{
    const fv3d_job *j = specimen;
    const gp_fv3d_stats *t = gp_fv3d_stats_of(j->s);
    json_t *w = result_fv3d_warnings(j->s, j->spec);
    for (size_t i = 0; i < json_array_size(w); i++)
        gpd_log(GPD_LOG_WARN, "job %s: %s", id, json_string_value(json_array_get(w, i)));
    return json_pack("{s:I, s:o, s:s, s:o, s:o}", "steps", (json_int_t)t->imc_steps, "error",
                     gpd_jreal(t->imc_error), "stop_reason",
                     gp_imc_stop_name((gp_imc_stop)t->imc_stop), "warnings",
                     w ? w : json_array(), "fit", result_fv3d_fit(j->s, j->spec, 0));
}

static const gpd_view views[] = {
    {"section", "z", svg_fv3d_section, NULL},
    {"projection", "", svg_fv3d_projection, NULL},
    {"size", "", svg_fv3d_size, NULL},
    {"descriptors", "", svg_fv3d_descriptors, "stats.descriptors"},
    {NULL, NULL, NULL, NULL},
};

/* the api.md example */
static const char example[] =
    "{\"kind\": \"" KIND_NAME "\", \"seed\": 42,"
    " \"container\": {\"box\": [1, 1, 1]},"
    " \"particles\": 1000,"
    " \"size\": {\"law\": \"lognormal\", \"cov\": 0.5, \"of\": \"cells\"},"
    " \"orientation\": {\"axis\": [0, 0, 1], \"anisotropy\": 1.0},"
    " \"shape\": {\"D2\": 0.1, \"D3\": 0.05, \"D8\": 0.02, \"alpha\": -2, \"beta\": -2,"
    " \"elongation\": 0.8, \"flatness\": 0.8},"
    " \"solid_fraction\": 0.55,"
    " \"clump\": {\"spheres_max\": 30, \"min_radius_ratio\": 0.1},"
    " \"outputs\": [\"grains\", \"clumps\", \"descriptors\", \"cells\"]}";

/* the phases of its "timings" */
static const char *const phases[] = {"imc", "grains", "stats", "total", NULL};

const gpd_kind gpd_kind_fv3d = {
    .name = KIND_NAME, .example = example, .bounds = gp_spec_check_result, .brief = gpd_brief_cells,
    GPD_KIND_CORE_OPS(gp_spec_fv3d), .progress_detail = progress_detail, .plan = plan,
    .result_cost = result_cost, .result = result, .pack = pack, .done_detail = done_detail,
    .views = views, .export_dim = GP_EXPORT_FV3D, .pack_what = "grains", .pack_output = "grains",
    .phases = phases};
