/* result_triax.c -- the result JSON of a triaxial-3d run and the csv of its curves (see
 * result_triax.h). */
#include "kinds/triaxial-3d/result_triax.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "jobs/progress.h"
#include "kinds/kind_specimen.h"

/* the arrays of a curve: name, member of gp_triax_point, factor to the unit of the name */
typedef struct curve_col {
    const char *name;
    size_t off;
    double scale;
} curve_col;

#define COL(name, member, scale) {name, offsetof(gp_triax_point, member), scale}
static const curve_col g_cols[] = {
    COL("axial_strain", axial_strain, 1),
    COL("volumetric_strain", volumetric_strain, 1),
    COL("sigma1_kpa", sigma1, 1e-3),
    COL("sigma3_kpa", sigma3, 1e-3),
    COL("q_kpa", q, 1e-3),
    COL("p_kpa", p, 1e-3),
    COL("stress_ratio", ratio, 1),
    COL("coordination", coordination, 1),
    COL("coordination_mechanical", coordination_mechanical, 1),
    COL("porosity", porosity, 1),
    COL("stability", stability, 1),
    COL("inertial_number", inertial_number, 1),
    COL("sigma1_lw_kpa", sigma1_lw, 1e-3),
    COL("sigma3_lw_kpa", sigma3_lw, 1e-3),
    COL("servo_error", servo_error, 1),
};
#undef COL
#define NCOLS (sizeof g_cols / sizeof *g_cols)

#define BYTES_SPHERE 90 /* a sphere [x, y, z, r] at 17 digits */
#define BYTES_VALUE 24  /* a number of a curve */
#define ITEMS_BLOCK 4096

static double col_of(const gp_triax_point *pt, const curve_col *c)
{
    return *(const double *)((const char *)pt + c->off) * c->scale;
}

/* ------------------------------------------------------------------ the stats */

static json_t *vec3(const double *v)
{
    return json_pack("[o, o, o]", gpd_jreal(v[0]), gpd_jreal(v[1]), gpd_jreal(v[2]));
}

/* the sample of the peak: the first of the largest ratio (as the core finds it) */
static size_t peak_index(const gp_triax_result *t)
{
    size_t kp = 0;
    for (size_t k = 1; k < t->ncurve; k++)
        if (t->curve[k].ratio > t->curve[kp].ratio) kp = k;
    return kp;
}

static json_t *peak_json(const gp_triax_result *t)
{
    const gp_triax_point *pk = &t->curve[peak_index(t)];
    return json_pack("{s:o, s:o, s:o, s:o, s:o, s:o, s:o}", "stress_ratio",
                     gpd_jreal(t->peak_ratio), "axial_strain", gpd_jreal(t->peak_axial_strain),
                     "phi_deg", gpd_jreal(t->peak_phi_deg), "sigma1_kpa",
                     gpd_jreal(pk->sigma1 * 1e-3), "sigma3_kpa", gpd_jreal(pk->sigma3 * 1e-3),
                     "q_kpa", gpd_jreal(pk->q * 1e-3), "p_kpa", gpd_jreal(pk->p * 1e-3));
}

static json_t *end_json(const gp_triax_result *t)
{
    const gp_triax_point *e = &t->curve[t->ncurve - 1];
    return json_pack("{s:o, s:o, s:o, s:o, s:o}", "stress_ratio", gpd_jreal(t->end_ratio),
                     "phi_deg", gpd_jreal(t->end_phi_deg), "axial_strain",
                     gpd_jreal(e->axial_strain), "volumetric_strain",
                     gpd_jreal(e->volumetric_strain), "porosity", gpd_jreal(e->porosity));
}

static json_t *consolidation_json(const gp_triax_result *t)
{
    double kpa[3] = {t->consolidation_wall[0] * 1e-3, t->consolidation_wall[1] * 1e-3,
                     t->consolidation_wall[2] * 1e-3};
    return json_pack("{s:I, s:o, s:o, s:o, s:o, s:o}", "steps",
                     (json_int_t)t->consolidation_steps, "porosity",
                     gpd_jreal(t->consolidation_porosity), "stability",
                     gpd_jreal(t->consolidation_stability), "wall_kpa", vec3(kpa), "height",
                     gpd_jreal(t->height0), "volume", gpd_jreal(t->volume0));
}

/* the largest S_c over the loading (the samples after the origin) */
static double loading_stability(const gp_triax_result *t)
{
    double s = 0;
    for (size_t k = 1; k < t->ncurve; k++) s = fmax(s, t->curve[k].stability);
    return s;
}

static json_t *test_json(const gp_triax_result *t)
{
    json_t *o = json_object();
    json_object_set_new(o, "confining_kpa", gpd_jreal(t->confining * 1e-3));
    json_object_set_new(o, "peak", peak_json(t));
    json_object_set_new(o, "end", end_json(t));
    json_object_set_new(o, "dilatancy_deg", gpd_jreal(t->dilatancy_deg));
    json_object_set_new(o, "e50_mpa", gpd_jreal(t->e50 * 1e-6));
    json_object_set_new(o, "inertial_number_max", gpd_jreal(t->inertial_number_max));
    json_object_set_new(o, "servo_error_max", gpd_jreal(t->servo_error_max));
    json_object_set_new(o, "stability", gpd_jreal(loading_stability(t)));
    json_object_set_new(o, "still_rising", json_boolean(t->still_rising));
    json_object_set_new(o, "consolidation", consolidation_json(t));
    json_object_set_new(o, "steps", json_integer((json_int_t)t->steps));
    json_object_set_new(o, "dt", gpd_jreal(t->dt));
    json_object_set_new(o, "walls", json_pack("{s:o, s:o}", "lo", vec3(t->box_lo), "hi",
                                              vec3(t->box_hi)));
    return o;
}

void result_triax_envelope(gpd_triax_run *run)
{
    double s3[GP_SPEC_TRIAX_MAX_TESTS], s1[GP_SPEC_TRIAX_MAX_TESTS];
    for (size_t i = 0; i < run->ntests; i++) {
        const gp_triax_point *pk = &run->test[i]->curve[peak_index(run->test[i])];
        s3[i] = pk->sigma3;
        s1[i] = pk->sigma1;
    }
    gp_error err;
    gp_error_clear(&err);
    run->mc_error[0] = '\0';
    if (gp_triax_mohr_coulomb(s3, s1, run->ntests, &run->mc_phi_deg, &run->mc_cohesion,
                              &run->mc_residual, &err) == GP_OK)
        return;
    run->mc_phi_deg = run->mc_cohesion = run->mc_residual = NAN;
    snprintf(run->mc_error, sizeof run->mc_error, "%s", err.message);
}

static json_t *stats_json(const gpd_triax_run *run)
{
    json_t *tests = json_array();
    for (size_t i = 0; tests && i < run->ntests; i++)
        json_array_append_new(tests, test_json(run->test[i]));
    return json_pack("{s:I, s:o, s:{s:o, s:o, s:o}}", "particles",
                     (json_int_t)run->specimen->count, "tests", tests ? tests : json_null(),
                     "mohr_coulomb", "phi_deg", gpd_jreal(run->mc_phi_deg), "cohesion_kpa",
                     gpd_jreal(run->mc_cohesion * 1e-3), "residual",
                     gpd_jreal(run->mc_residual * 1e-3));
}

/* ------------------------------------------------------------------ the warnings */

/* a test not quasi-static, its lateral stress off sigma3, its ratio still rising at the end */
static void test_warnings(json_t *a, const gp_triax_result *t, const gp_spec_triax *s)
{
    double kpa = t->confining * 1e-3;
    if (t->inertial_number_max > RESULT_TRIAX_INERTIAL_MAX)
        gpd_warnf(a,
                  "test at %g kPa: the inertial number reached %.3g, above %g: the loading is not "
                  "quasi-static; use a slower strain_rate (%g /s now)",
                  kpa, t->inertial_number_max, RESULT_TRIAX_INERTIAL_MAX, s->strain_rate);
    if (t->servo_error_max > RESULT_TRIAX_SERVO_MAX)
        gpd_warnf(a,
                  "test at %g kPa: the lateral walls' stress was up to %.3g %% off sigma3 (more "
                  "than %g %%); use a slower strain_rate",
                  kpa, 100 * t->servo_error_max, 100 * RESULT_TRIAX_SERVO_MAX);
    if (t->still_rising)
        gpd_warnf(a,
                  "test at %g kPa: the stress ratio was still rising at the end (axial strain "
                  "%g): the peak may lie beyond it; use a larger axial_strain",
                  kpa, s->axial_strain);
}

static json_t *warnings_json(const gpd_triax_run *run, const gp_spec_triax *s)
{
    json_t *a = json_array();
    for (size_t i = 0; a && i < run->ntests; i++) test_warnings(a, run->test[i], s);
    if (a && run->mc_error[0])
        gpd_warnf(a, "no Mohr-Coulomb envelope through the peaks: %s", run->mc_error);
    return a ? a : json_null();
}

/* ------------------------------------------------------------------ the head */

static json_t *specimen_json(const gpd_triax_run *run, const gp_spec_triax *s)
{
    const gp_specimen3d *sp = run->specimen;
    return json_pack("{s:o, s:s, s:I, s:o, s:o, s:o}", "job",
                     s->job[0] ? json_string(s->job) : json_null(), "part",
                     s->tiled ? "tiled" : "sample", "particles", (json_int_t)sp->count, "box",
                     vec3(sp->box), "porosity", gpd_jreal(sp->stats.porosity), "d50",
                     gpd_jreal(s->d50));
}

static json_t *timings_json(const gpd_triax_run *run)
{
    double cons = 0, load = 0;
    for (size_t i = 0; i < run->ntests; i++) {
        cons += run->test[i]->seconds_consolidation;
        load += run->test[i]->seconds_loading;
    }
    double spec = run->specimen->t_total;
    return json_pack("{s:o, s:o, s:o, s:o}", "specimen", gpd_jreal(spec), "consolidation",
                     gpd_jreal(cons), "loading", gpd_jreal(load), "total",
                     gpd_jreal(spec + cons + load));
}

/* the walls of the last test at its end, [0, size] */
static const gp_triax_result *last_test(const gpd_triax_run *run)
{
    return run->test[run->ntests - 1];
}

static json_t *head_triax(const gpd_triax_run *run, const gp_spec_triax *s,
                          const json_t *spec_json)
{
    json_t *r = gpd_result_new(json_string_value(json_object_get(spec_json, "kind")), s->seed,
                               spec_json);
    if (!r) return NULL;
    const gp_triax_result *t = last_test(run);
    double size[3] = {t->box_hi[0] - t->box_lo[0], t->box_hi[1] - t->box_lo[1],
                      t->box_hi[2] - t->box_lo[2]};
    json_object_set_new(r, "specimen", specimen_json(run, s));
    json_object_set_new(r, "material", gpd_specimen_material_json(&s->material));
    json_object_set(r, "drainage", json_object_get(spec_json, "drainage"));
    json_object_set_new(r, "axial_strain", gpd_jreal(s->axial_strain));
    json_object_set_new(r, "strain_rate", gpd_jreal(s->strain_rate));
    json_object_set_new(r, "box", vec3(size));
    json_object_set_new(r, "stats", stats_json(run));
    json_object_set_new(r, "warnings", warnings_json(run, s));
    json_object_set_new(r, "timings", timings_json(run));
    return r;
}

/* ------------------------------------------------------------------ the arrays */

static void curve_w(gpd_jw *w, const gp_triax_result *t)
{
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "confining_kpa");
    gpd_jw_real(w, t->confining * 1e-3);
    for (size_t c = 0; c < NCOLS; c++) {
        gpd_jw_key(w, g_cols[c].name);
        gpd_jw_begin_array(w);
        for (size_t k = 0; k < t->ncurve; k++) gpd_jw_real(w, col_of(&t->curve[k], &g_cols[c]));
        gpd_jw_end_array(w);
    }
    gpd_jw_end_object(w);
}

/* a sphere of the last test, in the frame of its walls: [0, box] */
static void sphere_item(gpd_jw *w, size_t i, const void *user)
{
    const gp_triax_result *t = user;
    gpd_jw_begin_array(w);
    for (int k = 0; k < 3; k++) gpd_jw_real(w, t->spheres[4 * i + k] - t->box_lo[k]);
    gpd_jw_real(w, t->spheres[4 * i + 3]);
    gpd_jw_end_array(w);
}

json_t *result_triax_write(const gpd_triax_run *run, const gp_spec_triax *s,
                           const json_t *spec_json, gpd_jw *w)
{
    json_t *head = head_triax(run, s, spec_json);
    if (!head) return NULL;
    gpd_jw_begin_object(w);
    gpd_jw_members(w, head);
    if (run->outputs & GP_OUT_TRIAX_CURVES) {
        gpd_jw_key(w, "curves");
        gpd_jw_begin_array(w);
        for (size_t i = 0; i < run->ntests; i++) curve_w(w, run->test[i]);
        gpd_jw_end_array(w);
    }
    const gp_triax_result *t = last_test(run);
    if ((run->outputs & GP_OUT_TRIAX_SPHERES) && t->spheres) {
        gpd_jw_key(w, "spheres");
        gpd_jw_begin_array(w);
        int nt = s->threads > 0 ? s->threads : 1; /* the job's: the same bytes whatever */
        gpd_jw_items(w, t->n, sphere_item, t, nt, ITEMS_BLOCK);
        gpd_jw_end_array(w);
    }
    gpd_jw_end_object(w);
    return head;
}

double result_triax_cost(const gpd_triax_run *run)
{
    double values = 0;
    for (size_t i = 0; i < run->ntests; i++) values += (double)(run->test[i]->ncurve * NCOLS);
    double spheres = (run->outputs & GP_OUT_TRIAX_SPHERES) ? (double)run->specimen->count : 0;
    double curves = (run->outputs & GP_OUT_TRIAX_CURVES) ? values : 0;
    return GPD_RESULT_S_PER_BYTE * (BYTES_SPHERE * spheres + BYTES_VALUE * curves);
}

/* ------------------------------------------------------------------ the csv */

/* one number of a csv line: 17 digits, empty when not a number */
static void csv_value(gpd_buf *b, const json_t *v, int first)
{
    if (!first) gpd_buf_add(b, ",", 1);
    if (json_is_number(v) && isfinite(json_number_value(v)))
        gpd_buf_printf(b, "%.17g", json_number_value(v));
}

/* the lines of one curve */
static void csv_curve(gpd_buf *b, const json_t *curve)
{
    const json_t *cols[NCOLS];
    for (size_t c = 0; c < NCOLS; c++) cols[c] = json_object_get(curve, g_cols[c].name);
    size_t n = json_array_size(cols[0]);
    for (size_t k = 0; k < n; k++) {
        csv_value(b, json_object_get(curve, "confining_kpa"), 1);
        for (size_t c = 0; c < NCOLS; c++) csv_value(b, json_array_get(cols[c], k), 0);
        gpd_buf_add(b, "\n", 1);
    }
}

char *result_triax_csv(const json_t *summary, size_t *len, gpd_err *err)
{
    const json_t *curves = json_object_get(summary, "curves");
    if (!json_is_array(curves)) {
        gpd_err_set(err, 409, "this job has no curves to export (its spec did not ask for "
                              "them): submit the spec again with \"curves\" in outputs");
        return NULL;
    }
    gpd_buf b = {NULL, 0, 0, 0};
    gpd_buf_printf(&b, "confining_kpa");
    for (size_t c = 0; c < NCOLS; c++) gpd_buf_printf(&b, ",%s", g_cols[c].name);
    gpd_buf_add(&b, "\n", 1);
    size_t i;
    const json_t *curve;
    json_array_foreach(curves, i, curve) csv_curve(&b, curve);
    if (b.oom || !b.buf) {
        free(b.buf);
        gpd_err_set(err, 500, "out of memory");
        return NULL;
    }
    *len = b.len;
    return b.buf;
}
