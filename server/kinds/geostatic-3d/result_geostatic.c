/* result_geostatic.c -- the result JSON of a geostatic-3d run and the csv of its profile (see
 * result_geostatic.h). */
#include "kinds/geostatic-3d/result_geostatic.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "jobs/progress.h"
#include "kinds/kind_specimen.h"

#define BYTES_SPHERE 90 /* a sphere [x, y, z, r] at 17 digits */
#define BYTES_VALUE 24  /* a number of the profile or the map */
#define ITEMS_BLOCK 4096

static const char *const g_axis[3] = {"x", "y", "z"};

/* the profile's columns: name, its array in gp_geostatic_profile (double or, with flag, a
 * boolean array), factor to the unit of the name */
typedef struct profile_col {
    const char *name;
    size_t off;
    double scale;
    int flag;
} profile_col;

#define COL(name, member, scale) {name, offsetof(gp_geostatic_profile, member), scale, 0}
#define FLAG(name, member) {name, offsetof(gp_geostatic_profile, member), 1, 1}
static const profile_col g_cols[] = {
    COL("depth", depth, 1),
    COL("sigma_xx_kpa", sigma_xx, 1e-3),
    COL("sigma_yy_kpa", sigma_yy, 1e-3),
    COL("sigma_zz_kpa", sigma_zz, 1e-3),
    COL("weight_kpa", weight, 1e-3),
    COL("k0", k0, 1),
    COL("porosity", porosity, 1),
    COL("coordination", coordination, 1),
    COL("sigma_xx_full_kpa", sigma_xx_full, 1e-3),
    COL("sigma_yy_full_kpa", sigma_yy_full, 1e-3),
    COL("sigma_zz_full_kpa", sigma_zz_full, 1e-3),
    COL("k0_full", k0_full, 1),
    FLAG("k0_counted", k0_counted),
    FLAG("equilibrium_counted", equilibrium_counted),
};
#undef COL
#undef FLAG
#define NCOLS (sizeof g_cols / sizeof *g_cols)

/* ------------------------------------------------------------------ pieces */

static json_t *vec(const double *v, size_t n, double scale)
{
    json_t *a = json_array();
    for (size_t k = 0; a && k < n; k++) json_array_append_new(a, gpd_jreal(v[k] * scale));
    return a;
}

static json_t *profile_column(const gp_geostatic_profile *pr, const profile_col *c)
{
    json_t *a = json_array();
    const char *base = (const char *)pr + c->off;
    for (size_t k = 0; a && k < pr->n; k++) {
        if (c->flag)
            json_array_append_new(a, json_boolean((*(unsigned char *const *)base)[k]));
        else
            json_array_append_new(a, gpd_jreal((*(double *const *)base)[k] * c->scale));
    }
    return a;
}

static json_t *profile_json(const gp_geostatic_profile *pr)
{
    json_t *o = json_object();
    for (size_t c = 0; o && c < NCOLS; c++)
        json_object_set_new(o, g_cols[c].name, profile_column(pr, &g_cols[c]));
    return o;
}

/* rows of a map's field (nz x nx, row-major), kPa */
static json_t *map_rows(const double *f, size_t nx, size_t nz)
{
    json_t *rows = json_array();
    for (size_t i = 0; rows && i < nz; i++) json_array_append_new(rows, vec(f + i * nx, nx, 1e-3));
    return rows;
}

static json_t *map_json(const gp_geostatic_map *m, const gp_specimen3d *sp)
{
    double tile[2] = {sp->sample_box[m->axis_h], sp->sample_box[m->axis_v]};
    double slice[2] = {m->slice_lo, m->slice_hi};
    return json_pack("{s:s, s:s, s:I, s:I, s:o, s:o, s:o, s:o, s:o, s:o}", "horizontal",
                     g_axis[m->axis_h], "vertical", g_axis[m->axis_v], "nx", (json_int_t)m->nx,
                     "nz", (json_int_t)m->nz, "dx", gpd_jreal(m->dx), "dz", gpd_jreal(m->dz),
                     "slice", vec(slice, 2, 1), "tile", vec(tile, 2, 1), "sigma_v_kpa",
                     map_rows(m->sigma_v, m->nx, m->nz), "sigma_h_kpa",
                     map_rows(m->sigma_h, m->nx, m->nz));
}

/* ------------------------------------------------------------------ the stats */

static json_t *whole_json(const gp_geostatic_whole *w)
{
    json_t *lw = json_array();
    for (int i = 0; lw && i < 3; i++) json_array_append_new(lw, vec(w->love_weber[i], 3, 1e-3));
    json_t *o = json_pack("{s:o, s:o, s:o, s:o}", "love_weber_kpa", lw, "walls_kpa",
                          vec(w->walls, 3, 1e-3), "wall_stress_kpa",
                          vec(w->wall_stress, 6, 1e-3), "max_error", gpd_jreal(w->max_error));
    json_object_set_new(o, "weight_n", gpd_jreal(w->weight));
    json_object_set_new(o, "centroid_height", gpd_jreal(w->centroid_height));
    json_object_set_new(o, "porosity", gpd_jreal(w->porosity));
    json_object_set_new(o, "coordination", gpd_jreal(w->coordination));
    json_object_set_new(o, "contacts", json_integer((json_int_t)w->contacts));
    json_object_set_new(o, "wall_contacts", json_integer((json_int_t)w->wall_contacts));
    json_object_set_new(o, "friction_mobilised", gpd_jreal(w->friction_mobilised));
    json_object_set_new(o, "sliding", gpd_jreal(w->sliding));
    json_object_set_new(o, "surface", gpd_jreal(w->surface));
    return o;
}

static json_t *stats_json(const gp_geostatic_result *g)
{
    json_t *o = json_object();
    json_object_set_new(o, "particles", json_integer((json_int_t)g->n));
    json_object_set_new(o, "k0", json_pack("{s:o, s:o, s:o, s:o, s:I}", "theory",
                                           gpd_jreal(g->k0.theory), "mean", gpd_jreal(g->k0.mean),
                                           "sd", gpd_jreal(g->k0.sd), "bulk",
                                           gpd_jreal(g->k0.bulk), "slabs",
                                           (json_int_t)g->k0.slabs));
    json_object_set_new(o, "equilibrium",
                        json_pack("{s:o, s:o, s:I}", "max_error",
                                  gpd_jreal(g->equilibrium.max_error), "core_max_error",
                                  gpd_jreal(g->equilibrium.core_max_error), "slabs",
                                  (json_int_t)g->equilibrium.slabs));
    json_object_set_new(o, "stability", gpd_jreal(g->stability));
    json_object_set_new(o, "stability_contacts", gpd_jreal(g->stability_list));
    json_object_set_new(o, "converged", json_boolean(g->converged));
    json_object_set_new(o, "steps", json_integer((json_int_t)g->steps));
    json_object_set_new(o, "dt", gpd_jreal(g->dt));
    json_object_set_new(o, "dt_cuts", json_integer((json_int_t)g->dt_cuts));
    json_object_set_new(o, "scaled_radius", gpd_jreal(g->scaled_radius));
    json_object_set_new(o, "d50", gpd_jreal(g->d50));
    json_object_set_new(o, "dmax", gpd_jreal(g->dmax));
    json_object_set_new(o, "slab", gpd_jreal(g->profile.thickness));
    json_object_set_new(o, "margin", gpd_jreal(g->profile.margin));
    json_object_set_new(o, "whole", whole_json(&g->whole));
    return o;
}

/* ------------------------------------------------------------------ the warnings */

static json_t *warnings_json(const gp_geostatic_result *g, const gp_spec_geostatic *s)
{
    json_t *a = json_array();
    if (!a) return json_null();
    if (!g->converged)
        gpd_warnf(a, "the packing was not at rest after %ld DEM steps (S_c %.3g, above %g): the "
                  "stresses are those of the state reached; raise max_steps",
                  g->steps, g->stability, s->params.stability_tol);
    if (g->equilibrium.slabs && g->equilibrium.max_error > RESULT_GEOSTATIC_EQUILIBRIUM_MAX)
        gpd_warnf(a, "sigma_v differs from the weight above by up to %.3g %% (more than %g %%): "
                  "the packing is not in equilibrium", 100 * g->equilibrium.max_error,
                  100 * RESULT_GEOSTATIC_EQUILIBRIUM_MAX);
    if (!g->k0.slabs)
        gpd_warnf(a, "no slab is far enough from the top and the bottom for K0 (margin %g m, slab "
                  "%g m): use thinner slabs or a smaller wall_margin_dmax", g->profile.margin,
                  g->profile.thickness);
    return a;
}

/* ------------------------------------------------------------------ the head */

static json_t *specimen_json(const gpd_geostatic_run *run, const gp_spec_geostatic *s)
{
    const gp_specimen3d *sp = run->specimen;
    double tiling[3] = {s->specimen.tiling[0], s->specimen.tiling[1], s->specimen.tiling[2]};
    return json_pack("{s:o, s:s, s:I, s:o, s:o, s:o, s:o}", "job",
                     s->job[0] ? json_string(s->job) : json_null(), "part",
                     s->tiled ? "tiled" : "sample", "particles", (json_int_t)sp->count, "box",
                     vec(sp->box, 3, 1), "sample_box", vec(sp->sample_box, 3, 1), "tiling",
                     vec(tiling, 3, 1), "porosity", gpd_jreal(sp->stats.porosity));
}

static json_t *timings_json(const gpd_geostatic_run *run)
{
    const gp_geostatic_result *g = run->state;
    double spec = run->specimen->t_total;
    return json_pack("{s:o, s:o, s:o, s:o}", "specimen", gpd_jreal(spec), "settling",
                     gpd_jreal(g->seconds_settling), "measure", gpd_jreal(g->seconds_measure),
                     "total", gpd_jreal(spec + g->seconds_settling + g->seconds_measure));
}

static void set_physics(json_t *r, const gp_spec_geostatic *s, const gp_geostatic_result *g)
{
    const gp_geostatic_params *p = &s->params;
    json_object_set_new(r, "material", gpd_specimen_material_json(&p->material));
    json_object_set_new(r, "gravity", vec(p->gravity, 3, 1));
    json_object_set_new(r, "vertical", json_string(g_axis[g->axis_v]));
    json_object_set_new(r, "wall_friction_deg", gpd_jreal(p->wall_friction_deg));
    json_object_set_new(r, "phi_deg", gpd_jreal(p->phi_deg));
    json_object_set_new(r, "phi_from", s->phi_job[0] ? json_pack("{s:s}", "job", s->phi_job)
                                                     : json_null());
}

static json_t *head_geostatic(const gpd_geostatic_run *run, const gp_spec_geostatic *s,
                              const json_t *spec_json)
{
    json_t *r = gpd_result_new(json_string_value(json_object_get(spec_json, "kind")), s->seed,
                               spec_json);
    if (!r) return NULL;
    const gp_geostatic_result *g = run->state;
    json_object_set_new(r, "specimen", specimen_json(run, s));
    set_physics(r, s, g);
    json_object_set_new(r, "box", vec(run->specimen->box, 3, 1));
    json_object_set_new(r, "stats", stats_json(g));
    if (run->outputs & GP_OUT_GEO_PROFILE)
        json_object_set_new(r, "profile", profile_json(&g->profile));
    json_object_set_new(r, "map", map_json(&g->map, run->specimen));
    json_object_set_new(r, "warnings", warnings_json(g, s));
    json_object_set_new(r, "timings", timings_json(run));
    return r;
}

/* ------------------------------------------------------------------ the spheres */

static void sphere_item(gpd_jw *w, size_t i, const void *user)
{
    const gp_geostatic_result *g = user;
    gpd_jw_begin_array(w);
    for (int k = 0; k < 4; k++) gpd_jw_real(w, g->spheres[4 * i + k]);
    gpd_jw_end_array(w);
}

json_t *result_geostatic_write(const gpd_geostatic_run *run, const gp_spec_geostatic *s,
                               const json_t *spec_json, gpd_jw *w)
{
    json_t *head = head_geostatic(run, s, spec_json);
    if (!head) return NULL;
    gpd_jw_begin_object(w);
    gpd_jw_members(w, head);
    const gp_geostatic_result *g = run->state;
    if ((run->outputs & GP_OUT_GEO_SPHERES) && g->spheres) {
        gpd_jw_key(w, "spheres");
        gpd_jw_begin_array(w);
        int nt = s->threads > 0 ? s->threads : 1; /* the job's: the same bytes whatever */
        gpd_jw_items(w, g->n, sphere_item, g, nt, ITEMS_BLOCK);
        gpd_jw_end_array(w);
    }
    gpd_jw_end_object(w);
    return head;
}

double result_geostatic_cost(const gpd_geostatic_run *run)
{
    const gp_geostatic_result *g = run->state;
    double spheres = (run->outputs & GP_OUT_GEO_SPHERES) && g ? (double)g->n : 0;
    double values = g ? (double)(g->profile.n * NCOLS + 2 * g->map.nx * g->map.nz) : 0;
    return GPD_RESULT_S_PER_BYTE * (BYTES_SPHERE * spheres + BYTES_VALUE * values);
}

/* ------------------------------------------------------------------ the csv */

/* one value of a csv line: a number at 17 digits, a boolean as 1 / 0, empty otherwise */
static void csv_value(gpd_buf *b, const json_t *v, int first)
{
    if (!first) gpd_buf_add(b, ",", 1);
    if (json_is_boolean(v)) gpd_buf_add(b, json_is_true(v) ? "1" : "0", 1);
    else if (json_is_number(v) && isfinite(json_number_value(v)))
        gpd_buf_printf(b, "%.17g", json_number_value(v));
}

char *result_geostatic_csv(const json_t *summary, size_t *len, gpd_err *err)
{
    const json_t *profile = json_object_get(summary, "profile");
    if (!json_is_object(profile)) {
        gpd_err_set(err, 409, "this job has no profile to export (its spec did not ask for "
                              "it): submit the spec again with \"profile\" in outputs");
        return NULL;
    }
    const json_t *cols[NCOLS];
    gpd_buf b = {NULL, 0, 0, 0};
    for (size_t c = 0; c < NCOLS; c++) {
        cols[c] = json_object_get(profile, g_cols[c].name);
        gpd_buf_printf(&b, "%s%s", c ? "," : "", g_cols[c].name);
    }
    gpd_buf_add(&b, "\n", 1);
    for (size_t k = 0; k < json_array_size(cols[0]); k++) {
        for (size_t c = 0; c < NCOLS; c++) csv_value(&b, json_array_get(cols[c], k), c == 0);
        gpd_buf_add(&b, "\n", 1);
    }
    if (b.oom || !b.buf) {
        free(b.buf);
        gpd_err_set(err, 500, "out of memory");
        return NULL;
    }
    *len = b.len;
    return b.buf;
}
