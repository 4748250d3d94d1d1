/* gp_spec3d.c -- the kind "spheres-3d": the reader of an effective spec into gp_spec3d, its
 * semantic checks (the sieve rows, the largest grain against the box, the DEM's sphere limits,
 * the work budget) and its work and result bounds. See gp_spec.h. */
#include "gp_spec_internal.h"

#include "gp_sieve.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gp_spec_kind gp_spec_kind_spheres_3d; /* this kind, defined at the end */

extern const unsigned char gp_schema_text_spheres_3d[];

/* the names of the outputs, at the index of their bit (GP_OUT3_*) */
static const char *const g_outputs[] = {"spheres", "contacts", "fabric", "stress"};

/* ------------------------------------------------------------------------------------------ */
/* the reader (an effective spec: nothing is checked but its form) */

void gp_spec3d_free(gp_spec3d *s)
{
    if (!s) return;
    free((gp_sieve_row *)s->sieve);
    memset(s, 0, sizeof *s);
}

/* gp_spec.h. Also the first step of the checks and the bounds. */
int gp_spec3d_read(const json_t *full, gp_spec3d *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    p = gp_spec_begin(p, &local);
    if (gp_spec_read_begin(&gp_spec_kind_spheres_3d, full, out, sizeof *out, p)) return -1;
    gp_spec_reader r = {0};
    out->seed = (uint64_t)gp_rd_num(&r, full, "/seed", 0, GP_RD_COUNT);
    const json_t *box = gp_rd_array(&r, full, "/box", 3, 3, 0);
    for (size_t i = 0; i < 3; i++)
        out->box[i] = gp_rd_value(&r, json_array_get(box, i), "/box", -GP_RD_ANY, GP_RD_ANY);
    double scale = gp_rd_sieve_scale(&r, full, "/sieve_units");
    const json_t *sieve = gp_rd_array(&r, full, "/sieve", 2, SIZE_MAX, 0);
    size_t n = json_array_size(sieve);
    gp_sieve_row *rows = malloc((n ? n : 1) * sizeof *rows);
    if (!rows) return gp_spec_no_memory(p); /* *out owns nothing yet */
    for (size_t i = 0; i < n; i++)
        gp_rd_row(&r, sieve, i, "/sieve", scale, &rows[i].diameter, &rows[i].passing);
    out->sieve = rows;
    out->nsieve = n;
    out->porosity = gp_rd_num(&r, full, "/porosity", -GP_RD_ANY, GP_RD_ANY);
    const json_t *m = gp_rd_member(&r, full, "/material", JSON_OBJECT, 0);
    out->material.density = gp_rd_num(&r, m, "/material/density", -GP_RD_ANY, GP_RD_ANY);
    out->material.young = gp_rd_num(&r, m, "/material/young", -GP_RD_ANY, GP_RD_ANY);
    out->material.poisson = gp_rd_num(&r, m, "/material/poisson", -GP_RD_ANY, GP_RD_ANY);
    out->material.friction_deg = gp_rd_num(&r, m, "/material/friction_deg", -GP_RD_ANY, GP_RD_ANY);
    out->material.damping = gp_rd_num(&r, m, "/material/damping", -GP_RD_ANY, GP_RD_ANY);
    const json_t *tiling = gp_rd_array(&r, full, "/tiling", 3, 3, 1);
    for (size_t i = 0; i < 3; i++)
        out->tiling[i] = tiling ? (int)gp_rd_value(&r, json_array_get(tiling, i), "/tiling", 0,
                                                   GP_RD_INT)
                                : 1;
    out->outputs = gp_rd_flags(&r, full, "/outputs", g_outputs, 4);
    out->threads = 0;
    out->max_steps = 0;
    out->tile_relax_steps = 0;
    int rc = gp_rd_finish(&r, p);
    if (rc) gp_spec3d_free(out);
    return rc;
}

/* ------------------------------------------------------------------------------------------ */
/* work and result bounds (gp_spec.h) */

#define DEM_SPHERE_STEPS_PER_S 4e6 /* the 3D DEM, sphere-steps per second (3.9e6 measured) */
/* The 3D protocol (core/3d/gp_specimen3d.c): its constants, which its header does not export */
#define DEM_MAX_SAMPLE 400000.0   /* MAX_SAMPLE_SPHERES: spheres of the sample at most */
#define DEM_MAX_TILED 20000000.0  /* MAX_TILED_SPHERES: spheres after the tiling at most */
#define DEM_DT_SAFETY 0.3         /* DT_SAFETY, of sqrt(m / 2 E R) */
#define DEM_SCALED_RATIO 3.5      /* MAX_SCALED_RATIO: density-scaling radius >= rmax / this */
#define DEM_GRAVITY 9.81
/* The protocol's durations are multiples of T = sqrt(d50 / g): growth 1.75 T, settling 1.2 T,
 * compaction windows of 0.35-3.5 T, relaxation; the paper's example takes 16 T (13,610 steps
 * at 860 steps per T) and a 1-20 mm sieve 14-22 T. 50 T is the estimate, with room for a slow
 * compaction; the protocol's own cap (500 T) bounds a run that does not converge. */
#define DEM_PROTOCOL_T 50.0

/* where the percent curve pc (by weight or by number) of rows d crosses q, linearly */
static double sieve_quantile(const double *d, const double *pc, size_t n, double q)
{
    for (size_t k = 1; k < n; k++)
        if (pc[k] >= q && pc[k] > pc[k - 1])
            return d[k - 1] + (d[k] - d[k - 1]) * fmax(0, q - pc[k - 1]) / (pc[k] - pc[k - 1]);
    return n ? d[n - 1] : 0;
}

/* the sample's spheres (the count the DEM draws) and the DEM time step */
static int spheres_3d(const gp_spec3d *s, gp_spec_bounds_t *b, double *d50, gp_spec_problem *p)
{
    size_t ns = s->nsieve;
    double *d = malloc((ns ? ns : 1) * 3 * sizeof *d);
    if (!d) return gp_spec_no_memory(p);
    double *pw = d + ns, *pn = d + 2 * ns;
    for (size_t k = 0; k < ns; k++) {
        d[k] = s->sieve[k].diameter;
        pw[k] = s->sieve[k].passing;
    }
    double V = 1;
    for (size_t i = 0; i < 3; i++) V *= s->box[i];
    b->cells = ns >= 2 ? gp_sieve_expected_count(d, pw, ns, (1 - s->porosity) * V) : 0;
    /* the time step: the density-scaling radius is the median radius by number, at least
     * rmax / 3.5 (rmax: where the curve reaches 100 %) */
    double dmax = sieve_quantile(d, pw, ns, 100);
    double dmed = dmax;
    if (ns >= 2 && gp_sieve_weight_to_number(d, pw, ns, GP_SIEVE_UNIFORM, pn, NULL) == GP_OK)
        dmed = sieve_quantile(d, pn, ns, 50);
    double rs = fmax(0.5 * dmed, 0.5 * dmax / DEM_SCALED_RATIO);
    *d50 = sieve_quantile(d, pw, ns, 50);
    free(d);
    b->dt = DEM_DT_SAFETY * rs * sqrt(2 * M_PI * s->material.density / (3 * s->material.young));
    return 0;
}

/* the bounds of a read spec whose sieve rows are checked; 0, or -1 out of memory */
static int bounds_3d(const gp_spec3d *s, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    memset(b, 0, sizeof *b);
    double d50 = 0;
    if (spheres_3d(s, b, &d50, p)) return -1;
    double young = s->material.young, density = s->material.density;
    double per_t = sqrt(d50 / DEM_GRAVITY) / b->dt; /* steps per time unit */
    b->steps = DEM_PROTOCOL_T * per_t;
    double tiles = 1;
    for (size_t i = 0; i < 3; i++) tiles *= s->tiling[i];
    b->items = b->cells * tiles;
    b->work_s = b->cells * b->steps / DEM_SPHERE_STEPS_PER_S;
    /* what drives the work: the material when the paper's material would be within budget */
    double ref = b->work_s / sqrt((young / density) / (15e6 / 2600));
    if (b->work_s > GP_SPEC_WORK_BUDGET_S && ref <= GP_SPEC_WORK_BUDGET_S)
        b->work_pointer = young / 15e6 >= 2600 / density ? "/material/young" : "/material/density";
    else
        b->work_pointer = "/box";
    double per = 0;
    if (s->outputs & GP_OUT3_SPHERES) per += 90;          /* [x, y, z, r] at 17 digits */
    if (s->outputs & GP_OUT3_CONTACTS) per += 2.6 * 210;  /* 2.6 contacts per sphere */
    b->result_bytes = 20000 + b->items * per;
    b->result_pointer = tiles > 1 ? "/tiling" : "/box";
    return 0;
}

static const gp_spec_advice g_work_advice[] = {
    {"/material/young", "use a softer young (the paper's 1.5e7 Pa: the packing barely depends on "
                        "it)"},
    {"/material/density", "use a higher density (the packing barely depends on it)"},
    {"/box", "use a smaller box or a coarser sieve (check sieve_units)"},
    {NULL, "ask for fewer grains, contour_points or outputs"}};

static const gp_spec_advice g_result_advice[] = {
    {NULL, "spheres (a smaller tiling or box, a coarser sieve) or outputs (contacts are most of "
           "it)"}};

/* ------------------------------------------------------------------------------------------ */
/* the semantic checks */

/* the largest grain fits in the box */
static int check_fit_3d(const gp_spec3d *s, gp_spec_problem *p)
{
    double dmax = s->sieve[s->nsieve - 1].diameter;
    double bmin = INFINITY;
    for (size_t i = 0; i < 3; i++) bmin = fmin(bmin, s->box[i]);
    if (!(dmax > bmin)) return 0;
    char ptr[64];
    snprintf(ptr, sizeof ptr, "/sieve/%zu/0", s->nsieve - 1);
    return gp_problem(p, "invalid_spec", ptr, "the largest sieve diameter (%.6g m) does not fit "
                      "in the box (smallest side %.6g m); check sieve_units", dmax, bmin);
}

/* the DEM's sphere limits and the work budget */
static int check_limits_3d(const gp_spec3d *s, gp_spec_problem *p)
{
    gp_spec_bounds_t b;
    if (bounds_3d(s, &b, p)) return -1;
    if (b.cells > DEM_MAX_SAMPLE)
        return gp_spec_too_large(p, "/box", "about %.3g spheres fill %g %% of the box with this "
                                 "sieve curve, over the limit of %.0f spheres in the DEM sample; "
                                 "use a smaller box or a coarser sieve (check sieve_units)",
                                 b.cells, 100 * (1 - s->porosity), DEM_MAX_SAMPLE);
    if (b.items > DEM_MAX_TILED)
        return gp_spec_too_large(p, "/tiling", "%.0f tiles of about %.0f spheres make about %.3g "
                                 "spheres, over the limit of %.0f; ask for fewer tiles or a "
                                 "smaller box", b.items / b.cells, b.cells, b.items,
                                 DEM_MAX_TILED);
    char what[200];
    snprintf(what, sizeof what, "about %.2g DEM steps of %.0f spheres at a time step of %.2g s",
             b.steps, b.cells, b.dt);
    return gp_spec_over_budget(&b, what, g_work_advice, p);
}

/* ------------------------------------------------------------------------------------------ */
/* the kind */

/* reads an effective spec into *s (free it with gp_spec3d_free, also on failure) and checks its
 * sieve rows */
static int read_rows_3d(const json_t *full, gp_spec3d *s, gp_spec_problem *p)
{
    if (gp_spec3d_read(full, s, p)) return -1;
    return gp_spec_check_sieve_rows(json_object_get(full, "sieve"), "/sieve", p);
}

static int check_3d(const json_t *full, gp_spec_problem *p)
{
    gp_spec3d s;
    int rc = read_rows_3d(full, &s, p) || check_fit_3d(&s, p) || check_limits_3d(&s, p);
    gp_spec3d_free(&s);
    return rc ? -1 : 0;
}

static int spec_bounds_3d(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    gp_spec3d s;
    int rc = read_rows_3d(full, &s, p) || bounds_3d(&s, b, p);
    gp_spec3d_free(&s);
    return rc ? -1 : 0;
}

/* no rules on the spec as posted, no defaults that depend on other fields */
const gp_spec_kind gp_spec_kind_spheres_3d = {
    .name = "spheres-3d",
    .schema_text = gp_schema_text_spheres_3d,
    .check = check_3d,
    .bounds = spec_bounds_3d,
    .items = "spheres",
    .result_advice = g_result_advice,
};
