/* gp_spec_geostatic.c -- the kind "geostatic-3d": the reader of an effective spec into
 * gp_spec_geostatic, its semantic checks (the specimen, phi', gravity, wall friction, slabs,
 * the map) and its work and result bounds. See gp_spec_geostatic.h. */
#include "gp_spec_internal.h"

#include "gp_spec_geostatic.h"
#include "gp_spec_specimen.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

extern const gp_spec_kind gp_spec_kind_geostatic_3d; /* this kind, defined at the end */
extern const gp_spec_kind gp_spec_kind_triaxial_3d;  /* phi_from's */

extern const unsigned char gp_schema_text_geostatic_3d[];

#define GEO_SPHERE_STEPS_PER_S 4e6 /* the 3D DEM, sphere-steps a second (as gp_spec3d.c) */
/* the result's text: a sphere [x, y, z, r] at 17 digits; a slab of the profile (16 numbers);
 * a map cell (2 numbers); the rest */
#define GEO_BYTES_SPHERE 90.0
#define GEO_BYTES_SLAB (16 * 24.0)
#define GEO_BYTES_CELL (2 * 24.0)
#define GEO_BYTES_FIXED 20000.0

static const char *const g_outputs[] = {"profile", "spheres"};

const char *gp_spec_geostatic_phi_kind(void) { return gp_spec_kind_triaxial_3d.name; }

/* ------------------------------------------------------------------------------------------ */
/* the reader (an effective spec: nothing is checked but its form) */

void gp_spec_geostatic_free(gp_spec_geostatic *s)
{
    if (!s) return;
    gp_spec3d_free(&s->specimen);
    memset(s, 0, sizeof *s);
}

/* phi': phi_from's (resolved), phi_deg, or the default */
static double read_phi(gp_spec_reader *r, const json_t *full, char job[33])
{
    const json_t *from = gp_rd_member(r, full, "/phi_from", JSON_OBJECT, 1);
    if (from) {
        const json_t *id = gp_rd_member(r, from, "/phi_from/job", JSON_STRING, 0);
        snprintf(job, 33, "%s", id ? json_string_value(id) : "");
        return gp_rd_num(r, from, "/phi_from/phi_deg", -GP_RD_ANY, GP_RD_ANY);
    }
    if (json_object_get(full, "phi_deg"))
        return gp_rd_num(r, full, "/phi_deg", -GP_RD_ANY, GP_RD_ANY);
    return GP_SPEC_GEOSTATIC_PHI_DEG;
}

/* an optional length (0 when absent: the core's default) */
static double read_optional(gp_spec_reader *r, const json_t *full, const char *ptr)
{
    return json_object_get(full, ptr + 1) ? gp_rd_num(r, full, ptr, -GP_RD_ANY, GP_RD_ANY) : 0;
}

static void read_params(gp_spec_reader *r, const json_t *full, gp_spec_geostatic *out)
{
    gp_geostatic_params *g = &out->params;
    gp_geostatic_params_defaults(g);
    g->material = out->specimen.material;
    const json_t *grav = gp_rd_array(r, full, "/gravity", 3, 3, 0);
    for (size_t k = 0; k < 3; k++)
        g->gravity[k] = gp_rd_value(r, json_array_get(grav, k), "/gravity", -GP_RD_ANY,
                                    GP_RD_ANY);
    g->wall_friction_deg = gp_rd_num(r, full, "/wall_friction_deg", -GP_RD_ANY, GP_RD_ANY);
    g->phi_deg = read_phi(r, full, out->phi_job);
    g->slab = read_optional(r, full, "/slab");
    g->wall_margin_dmax = gp_rd_num(r, full, "/wall_margin_dmax", -GP_RD_ANY, GP_RD_ANY);
    g->map_cell = read_optional(r, full, "/map_cell");
    g->stability_tol = gp_rd_num(r, full, "/stability", -GP_RD_ANY, GP_RD_ANY);
    g->max_steps = (long)gp_rd_num(r, full, "/max_steps", 0, GP_RD_INT);
    out->outputs = gp_rd_flags(r, full, "/outputs", g_outputs, 2);
}

int gp_spec_geostatic_read(const json_t *full, gp_spec_geostatic *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    p = gp_spec_begin(p, &local);
    if (gp_spec_read_begin(&gp_spec_kind_geostatic_3d, full, out, sizeof *out, p)) return -1;
    static const char *const parts[] = {"tiled", "sample"};
    gp_spec_reader r = {0};
    out->seed = (uint64_t)gp_rd_num(&r, full, "/seed", 0, GP_RD_COUNT);
    out->tiled = !gp_rd_enum(&r, json_object_get(full, "specimen"), "/specimen/part", parts, 2);
    if (r.bad) return gp_rd_finish(&r, p);
    if (gp_spec_specimen_read(full, &out->specimen, out->job, p)) return -1;
    gp_spec3d *sp = &out->specimen;
    sp->outputs = GP_OUT3_SPHERES;
    if (!out->tiled) sp->tiling[0] = sp->tiling[1] = sp->tiling[2] = 1;
    read_params(&r, full, out);
    int rc = gp_rd_finish(&r, p);
    if (rc) gp_spec_geostatic_free(out);
    return rc;
}

/* ------------------------------------------------------------------------------------------ */
/* the packing's size, work and result bounds */

/* the packing settled: its box (m), its spheres, the specimen's bounds */
typedef struct geo_work {
    gp_spec_bounds_t specimen;
    double box[3];
    double spheres;
    double d50;                 /* m, of the sieve by weight */
    double settle_s;            /* the settling's seconds of one core at max_steps */
} geo_work;

static int work_of(const json_t *full, const gp_spec_geostatic *s, geo_work *w,
                   gp_spec_problem *p)
{
    if (gp_spec_specimen_bounds(full, &w->specimen, p)) return -1;
    const gp_spec3d *sp = &s->specimen;
    for (int k = 0; k < 3; k++) w->box[k] = sp->box[k] * sp->tiling[k];
    w->spheres = s->tiled ? w->specimen.items : w->specimen.cells;
    w->d50 = gp_spec_sieve_quantile(sp->sieve, sp->nsieve, 50);
    w->settle_s = w->spheres * (double)s->params.max_steps / GEO_SPHERE_STEPS_PER_S;
    return 0;
}

/* the vertical axis of a gravity vector along one axis, -1 when it is not */
static int vertical_axis(const double g[3])
{
    int axis = -1, nonzero = 0;
    for (int k = 0; k < 3; k++)
        if (g[k] != 0) axis = k, nonzero++;
    return nonzero == 1 ? axis : -1;
}

/* slabs and map cells over the packing (the core's defaults: 5 d50, the slab) */
static double slab_of(const gp_spec_geostatic *s, const geo_work *w)
{
    return s->params.slab > 0 ? s->params.slab : 5 * w->d50;
}

static void fill_bounds(const gp_spec_geostatic *s, const geo_work *w, gp_spec_bounds_t *b)
{
    memset(b, 0, sizeof *b);
    int v = vertical_axis(s->params.gravity);
    double height = w->box[v < 0 ? 2 : v], slab = slab_of(s, w);
    double cell = s->params.map_cell > 0 ? s->params.map_cell : slab;
    double slabs = fmax(1, round(height / slab));
    double cells = fmax(1, round(w->box[v == 0 ? 1 : 0] / cell)) * fmax(1, round(height / cell));
    b->cells = w->specimen.cells;
    b->items = w->spheres;
    b->steps = (double)s->params.max_steps;
    b->dt = w->specimen.dt;
    b->work_s = w->specimen.work_s + w->settle_s;
    b->work_pointer = "/max_steps";
    int spheres = (s->outputs & GP_OUT_GEO_SPHERES) != 0;
    int profile = (s->outputs & GP_OUT_GEO_PROFILE) != 0;
    b->result_bytes = GEO_BYTES_FIXED + profile * slabs * GEO_BYTES_SLAB +
                      cells * GEO_BYTES_CELL + spheres * w->spheres * GEO_BYTES_SPHERE;
    b->result_pointer = spheres ? (s->tiled ? "/specimen/part" : "/outputs") : "/map_cell";
}

static int bounds_geostatic(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    gp_spec_geostatic s;
    geo_work w;
    int rc = gp_spec_geostatic_read(full, &s, p) || work_of(full, &s, &w, p);
    if (!rc) fill_bounds(&s, &w, b);
    gp_spec_geostatic_free(&s);
    return rc ? -1 : 0;
}

static const gp_spec_advice g_work_advice[] = {
    {"/max_steps", "lower max_steps, or settle a smaller packing (fewer tiles, or part "
                   "\"sample\")"},
    {NULL, "settle a smaller packing"}};

static const gp_spec_advice g_result_advice[] = {
    {"/map_cell", "a larger map_cell (fewer cells in the stress map)"},
    {NULL, "spheres (leave \"spheres\" out of outputs, or settle the sample)"}};

/* ------------------------------------------------------------------------------------------ */
/* the semantic checks */

/* the specimen (gp_spec_specimen.h), and phi' given once and resolved */
static int check_posted_geostatic(const json_t *spec, gp_spec_problem *p)
{
    if (gp_spec_specimen_check_posted(spec, p)) return -1;
    const json_t *from = json_object_get(spec, "phi_from");
    if (from && json_object_get(spec, "phi_deg"))
        return gp_problem(p, "invalid_spec", "/phi_from", "give phi_deg or phi_from, not "
                          "both");
    if (from && !json_object_get(from, "phi_deg"))
        return gp_problem(p, "invalid_spec", "/phi_from/job", "job %s is not resolved: only "
                          "the daemon reads a %s job's phi', at submit (give phi_deg to "
                          "validate the spec alone)", json_string_value(json_object_get(from,
                          "job")), gp_spec_geostatic_phi_kind());
    return 0;
}

static int check_gravity(const gp_spec_geostatic *s, gp_spec_problem *p)
{
    const double *g = s->params.gravity;
    if (vertical_axis(g) < 0)
        return gp_problem(p, "invalid_spec", "/gravity", "expected a vector along one axis of "
                          "the box (two components 0, the third not), got [%g, %g, %g]",
                          g[0], g[1], g[2]);
    if (s->params.wall_friction_deg != 0)
        return gp_problem(p, "invalid_spec", "/wall_friction_deg", "expected 0: the walls are "
                          "frictionless in this version (the DEM has no sphere-wall shear "
                          "spring), got %g", s->params.wall_friction_deg);
    return 0;
}

/* slabs and map cells: within the height, not too many */
static int check_cuts(const gp_spec_geostatic *s, const geo_work *w, gp_spec_problem *p)
{
    int v = vertical_axis(s->params.gravity);
    double height = w->box[v], slab = slab_of(s, w), across = w->box[v == 0 ? 1 : 0];
    double cell = s->params.map_cell > 0 ? s->params.map_cell : slab;
    const char *sp = s->params.slab > 0 ? "/slab" : "/specimen";
    if (slab > height)
        return gp_problem(p, "invalid_spec", sp, "the slab (%g m) is thicker than the packing "
                          "is high (%g m)", slab, height);
    if (height / slab > GP_SPEC_GEOSTATIC_MAX_SLABS + 0.5)
        return gp_spec_too_large(p, sp, "%.0f slabs of %g m over the packing's height of %g m, "
                                 "over the limit of %d: use a thicker slab", height / slab,
                                 slab, height, GP_SPEC_GEOSTATIC_MAX_SLABS);
    const char *cp = s->params.map_cell > 0 ? "/map_cell" : sp;
    if (cell > fmax(height, across))
        return gp_problem(p, "invalid_spec", cp, "the map's cell (%g m) is larger than the "
                          "section (%g x %g m)", cell, across, height);
    if (fmax(height, across) / cell > GP_SPEC_GEOSTATIC_MAX_MAP + 0.5)
        return gp_spec_too_large(p, cp, "%.0f map cells of %g m along the section (%g x %g m), "
                                 "over the limit of %d: use a larger map_cell",
                                 fmax(height, across) / cell, cell, across, height,
                                 GP_SPEC_GEOSTATIC_MAX_MAP);
    return 0;
}

static int check_work(const gp_spec_geostatic *s, const geo_work *w, gp_spec_problem *p)
{
    if (w->spheres > GP_SPEC_GEOSTATIC_MAX_SPHERES)
        return gp_spec_too_large(p, s->tiled ? "/specimen/part" : "/specimen", "the packing "
                                 "has about %.3g spheres, over the limit of %.0f spheres the "
                                 "settling runs on; settle fewer tiles (or the sample)",
                                 w->spheres, GP_SPEC_GEOSTATIC_MAX_SPHERES);
    gp_spec_bounds_t b;
    fill_bounds(s, w, &b);
    char what[200];
    snprintf(what, sizeof what, "up to %ld DEM steps of %.0f spheres, and the specimen",
             s->params.max_steps, w->spheres);
    return gp_spec_over_budget(&b, what, g_work_advice, p);
}

static int check_geostatic(const json_t *full, gp_spec_problem *p)
{
    gp_spec_geostatic s;
    geo_work w;
    int rc = gp_spec_geostatic_read(full, &s, p) || check_gravity(&s, p) ||
             work_of(full, &s, &w, p) || check_cuts(&s, &w, p) || check_work(&s, &w, p);
    gp_spec_geostatic_free(&s);
    return rc ? -1 : 0;
}

const gp_spec_kind gp_spec_kind_geostatic_3d = {
    .name = "geostatic-3d",
    .schema_text = gp_schema_text_geostatic_3d,
    .check_posted = check_posted_geostatic,
    .settle_defaults = gp_spec_specimen_settle,
    .check = check_geostatic,
    .bounds = bounds_geostatic,
    .items = "spheres",
    .result_advice = g_result_advice,
};
