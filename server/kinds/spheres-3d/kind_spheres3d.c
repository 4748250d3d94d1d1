/* kind_spheres3d.c -- the 3D kind, "spheres-3d": sphere packings by DEM deposition, compaction
 * and flip tiling (core/3d), with their result, export pack, progress and SVG views
 * (svg_views3d.c).
 *
 * The result (result_json.h for the conventions):
 * {"kind": "spheres-3d", "seed": 7, "outputs": [...],
 *  "box": [bx, by, bz] (m, the final (tiled) box), "sample_box": [bx, by, bz],
 *  "tiling": [nx, ny, nz],
 *  "stats": {
 *    "porosity": {"target", "achieved" (final packing), "sample", "deposition"},
 *    "coordination_number": z (wall contacts counted), "coordination_spheres": z,
 *    "fabric": [[3x3]] (output fabric), "stress": [[3x3]] Pa (output stress),
 *    "psd": {"diameters": [n] (m), "target_weight", "achieved_weight", "target_number",
 *            "target_number_midbin", "achieved_number"}  (percent passing),
 *    "particles": n (final packing), "sample_particles", "contacts", "wall_contacts",
 *    "stop_reason", "stability", "tiled_stability", "compaction_friction_deg", "steps", "dt",
 *    "transfer" (a tiled result only: transfer_json below)},
 *  "timings": {"deposition", "compaction", "relaxation", "tiling", "transfer" (tiled only),
 *              "total"} (seconds),
 *  "spheres": [[x, y, z, r], ...] (output spheres),
 *  "contacts": [{"i", "j", "normal": [3], "overlap", "force": [3]}] (output contacts; j < 0 is
 *              wall -1-j, walls 0..5 = x-, x+, y-, y+, z-, z+)}
 */
#include <stdio.h>
#include <stdlib.h>

#include "gp_export.h"
#include "gp_spec.h"
#include "gp_specimen3d.h"
#include "kinds/kind.h"
#include "jobs/result_json.h"
#include "svg/svg_views.h"
#include "kinds/spheres-3d/svg_transfer3d.h"

#define KIND_NAME "spheres-3d"

/* ------------------------------------------------------------------ the result */

static json_t *vec3(const double *v)
{
    return json_pack("[o, o, o]", gpd_jreal(v[0]), gpd_jreal(v[1]), gpd_jreal(v[2]));
}

static json_t *mat3(const double m[3][3])
{
    return json_pack("[o, o, o]", vec3(m[0]), vec3(m[1]), vec3(m[2]));
}

static json_t *psd_json(const gp_psd3d *p)
{
    return json_pack("{s:o, s:o, s:o, s:o, s:o, s:o}", "diameters", gpd_jreals(p->diameter, p->n),
                     "target_weight", gpd_jreals(p->target_weight, p->n), "achieved_weight",
                     gpd_jreals(p->achieved_weight, p->n), "target_number",
                     gpd_jreals(p->target_number, p->n), "target_number_midbin",
                     gpd_jreals(p->target_number_midbin, p->n), "achieved_number",
                     gpd_jreals(p->achieved_number, p->n));
}

static json_t *stats_3d(const gp_stats3d *t, unsigned out)
{
    json_t *st = json_object();
    json_object_set_new(st, "porosity",
                        json_pack("{s:o, s:o, s:o, s:o}", "target", gpd_jreal(t->porosity_target),
                                  "achieved", gpd_jreal(t->porosity), "sample",
                                  gpd_jreal(t->sample_porosity), "deposition",
                                  gpd_jreal(t->deposition_porosity)));
    json_object_set_new(st, "coordination_number", gpd_jreal(t->coordination_number));
    json_object_set_new(st, "coordination_spheres", gpd_jreal(t->coordination_spheres));
    if (out & GP_OUT3_FABRIC) json_object_set_new(st, "fabric", mat3(t->fabric));
    if (out & GP_OUT3_STRESS) json_object_set_new(st, "stress", mat3(t->stress));
    json_object_set_new(st, "psd", psd_json(&t->psd));
    json_object_set_new(st, "particles", json_integer((json_int_t)t->particles));
    json_object_set_new(st, "sample_particles", json_integer((json_int_t)t->sample_particles));
    json_object_set_new(st, "contacts", json_integer((json_int_t)t->contacts));
    json_object_set_new(st, "wall_contacts", json_integer((json_int_t)t->wall_contacts));
    json_object_set_new(st, "stop_reason", json_string(t->stop_reason ? t->stop_reason : ""));
    json_object_set_new(st, "stability", gpd_jreal(t->stability));
    json_object_set_new(st, "tiled_stability", gpd_jreal(t->tiled_stability));
    json_object_set_new(st, "compaction_friction_deg", gpd_jreal(t->compaction_friction_deg));
    json_object_set_new(st, "steps", json_integer((json_int_t)t->steps));
    json_object_set_new(st, "dt", gpd_jreal(t->dt));
    return st;
}

/* ---- stats.transfer: the sample and the final packing side by side (gp_transfer.h) ----
 * {"porosity": {"sample", "final"}, "coordination_number": {..} (walls counted),
 *  "coordination_spheres": {..}, "fabric": {"sample": 3x3, "final": 3x3},
 *  "psd": {"diameters": [m], "number": {"sample": [%], "final": [%]}, "weight": {..},
 *          "d50": {"sample", "final"} (m, by weight)},
 *  "rdf": {"r": [m] (bin middles), "r_d50": [r / d50], "d50": m (the sample's: the unit of
 *          both), "sample": [g], "final": [g], "max_difference", "at_r" (m), "at_r_d50", "rms",
 *          "measured_on": "..." (the final packing's part whose g(r) this is),
 *          "block": {"tiles": [3], "origin": [3] (first tile), "box": [3] m, "spheres"}},
 *  "max_difference": {"porosity", "coordination_number", "coordination_spheres", "fabric",
 *                     "fabric_diagonal", "psd_number", "psd_weight", "d50", "rdf"}} */

static json_t *side_pair(double a, double b)
{
    return json_pack("{s:o, s:o}", "sample", gpd_jreal(a), "final", gpd_jreal(b));
}

static json_t *side_arrays(const double *a, const double *b, size_t n)
{
    return json_pack("{s:o, s:o}", "sample", gpd_jreals(a, n), "final", gpd_jreals(b, n));
}

/* "tiles 1-2 of 4 along x, ..." or "the whole tiling" (buf of n bytes) */
static void measured_on(const gp_specimen3d *s, const int tiling[3], char *buf, size_t n)
{
    const char *axis = "xyz";
    int whole = 1, k = 0;
    for (int a = 0; a < 3; a++) whole &= s->transfer_block[a] == tiling[a];
    if (whole) {
        snprintf(buf, n, "the whole tiling: %d x %d x %d tiles, %zu spheres", tiling[0],
                 tiling[1], tiling[2], s->count);
        return;
    }
    k = snprintf(buf, n, "a block of %d x %d x %d tiles near the centre:", s->transfer_block[0],
                 s->transfer_block[1], s->transfer_block[2]);
    for (int a = 0; a < 3 && k > 0 && (size_t)k < n; a++) {
        int o = s->transfer_block_origin[a], b = s->transfer_block[a];
        if (b > 1)
            k += snprintf(buf + k, n - (size_t)k, " tiles %d-%d of %d along %c,", o + 1, o + b,
                          tiling[a], axis[a]);
        else
            k += snprintf(buf + k, n - (size_t)k, " tile %d of %d along %c,", o + 1, tiling[a],
                          axis[a]);
    }
    if (k > 0 && (size_t)k < n)
        snprintf(buf + k - 1, n - (size_t)k + 1, "; %zu of the %zu spheres (centres in the "
                 "block), in the block's box", s->transfer_block_spheres, s->count);
}

static json_t *transfer_json(const gp_specimen3d *s, const gp_spec3d *spec)
{
    const gp_transfer_side *a = s->transfer_sample, *b = s->transfer_final;
    const gp_transfer_diff *d = &s->transfer_diff;
    size_t nb = a->nbins < b->nbins ? a->nbins : b->nbins;
    double *r = malloc((nb ? nb : 1) * sizeof *r), *rd = malloc((nb ? nb : 1) * sizeof *rd);
    if (!r || !rd) {
        free(r);
        free(rd);
        return NULL;
    }
    for (size_t k = 0; k < nb; k++) {
        rd[k] = ((double)k + 0.5) * a->dr;
        r[k] = rd[k] * a->unit;
    }
    char on[400];
    measured_on(s, spec->tiling, on, sizeof on);
    double bbox[3];
    for (int k = 0; k < 3; k++) bbox[k] = s->transfer_block[k] * s->sample_box[k];
    json_t *rdf = json_pack(
        "{s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:s, s:{s:[i, i, i], s:[i, i, i], s:o, s:I}}",
        "r", gpd_jreals(r, nb), "r_d50", gpd_jreals(rd, nb), "d50", gpd_jreal(a->unit), "sample",
        gpd_jreals(a->g, nb), "final", gpd_jreals(b->g, nb), "max_difference", gpd_jreal(d->rdf),
        "at_r", gpd_jreal(d->rdf_r * a->unit), "at_r_d50", gpd_jreal(d->rdf_r), "rms",
        gpd_jreal(d->rdf_rms), "measured_on", on, "block", "tiles", s->transfer_block[0],
        s->transfer_block[1], s->transfer_block[2], "origin", s->transfer_block_origin[0],
        s->transfer_block_origin[1], s->transfer_block_origin[2], "box", vec3(bbox), "spheres",
        (json_int_t)s->transfer_block_spheres);
    free(r);
    free(rd);
    json_t *psd = json_pack("{s:o, s:o, s:o, s:o}", "diameters", gpd_jreals(a->sieve, a->nsieve),
                            "number", side_arrays(a->psd_number, b->psd_number, a->nsieve),
                            "weight", side_arrays(a->psd_weight, b->psd_weight, a->nsieve),
                            "d50", side_pair(a->d50, b->d50));
    json_t *md = json_pack("{s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o}", "porosity",
                           gpd_jreal(d->porosity), "coordination_number",
                           gpd_jreal(d->coordination), "coordination_spheres",
                           gpd_jreal(d->coordination_spheres), "fabric", gpd_jreal(d->fabric),
                           "fabric_diagonal", gpd_jreal(d->fabric_diagonal), "psd_number",
                           gpd_jreal(d->psd_number), "psd_weight", gpd_jreal(d->psd_weight),
                           "d50", gpd_jreal(d->d50), "rdf", gpd_jreal(d->rdf));
    return json_pack("{s:o, s:o, s:o, s:{s:o, s:o}, s:o, s:o, s:o}", "porosity",
                     side_pair(a->porosity, b->porosity), "coordination_number",
                     side_pair(a->coordination, b->coordination), "coordination_spheres",
                     side_pair(a->coordination_spheres, b->coordination_spheres), "fabric",
                     "sample", mat3(a->fabric), "final", mat3(b->fabric), "psd", psd, "rdf", rdf,
                     "max_difference", md);
}

static void vec3_w(gpd_jw *w, const double *v)
{
    gpd_jw_begin_array(w);
    for (int k = 0; k < 3; k++) gpd_jw_real(w, v[k]);
    gpd_jw_end_array(w);
}

/* a contact: {"i", "j", "normal", "overlap", "force"} */
static void contact_w(gpd_jw *w, const gp_contact3d *c)
{
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "i");
    gpd_jw_integer(w, (long long)c->i);
    gpd_jw_key(w, "j");
    gpd_jw_integer(w, (long long)c->j);
    gpd_jw_key(w, "normal");
    vec3_w(w, c->normal);
    gpd_jw_key(w, "overlap");
    gpd_jw_real(w, c->overlap);
    gpd_jw_key(w, "force");
    vec3_w(w, c->force);
    gpd_jw_end_object(w);
}

/* the arrays' items for gpd_jw_items, in blocks of ~400 KB of text (a sphere is ~100 B, a
 * contact ~200 B) */
#define ITEMS_BLOCK 4096

static void sphere_item(gpd_jw *w, size_t i, const void *user)
{
    const gp_specimen3d *s = user;
    gpd_jw_begin_array(w);
    for (int k = 0; k < 4; k++) gpd_jw_real(w, s->spheres[4 * i + k]);
    gpd_jw_end_array(w);
}

static void contact_item(gpd_jw *w, size_t i, const void *user)
{
    const gp_specimen3d *s = user;
    contact_w(w, &s->contacts[i]);
}

/* the result without its arrays: kind, seed, outputs, box, sample_box, tiling, stats, timings */
static json_t *head_3d(const gp_specimen3d *s, const gp_spec3d *spec, const json_t *spec_json)
{
    json_t *r = gpd_result_new(KIND_NAME, spec->seed, spec_json);
    if (!r) return NULL;
    json_object_set_new(r, "box", vec3(s->box));
    json_object_set_new(r, "sample_box", vec3(s->sample_box));
    json_object_set_new(r, "tiling", json_pack("[i, i, i]", spec->tiling[0], spec->tiling[1],
                                               spec->tiling[2]));
    json_t *st = stats_3d(&s->stats, spec->outputs);
    json_t *tm = json_pack("{s:o, s:o, s:o, s:o}", "deposition", gpd_jreal(s->t_deposition),
                           "compaction", gpd_jreal(s->t_compaction), "relaxation",
                           gpd_jreal(s->t_relaxation), "tiling", gpd_jreal(s->t_tiling));
    if (s->transfer_sample && s->transfer_final) {
        json_t *tr = transfer_json(s, spec);
        if (!tr || !st || json_object_set_new(st, "transfer", tr)) {
            if (!st) json_decref(tr); /* (set_new has taken it otherwise) */
            json_decref(st);
            json_decref(tm);
            json_decref(r);
            return NULL;
        }
        json_object_set_new(tm, "transfer", gpd_jreal(s->t_transfer));
    }
    json_object_set_new(tm, "total", gpd_jreal(s->t_total));
    json_object_set_new(r, "stats", st);
    json_object_set_new(r, "timings", tm);
    return r;
}

static json_t *result(const void *specimen, const void *spec_, const json_t *spec_json,
                      gpd_jw *w)
{
    const gp_specimen3d *s = specimen;
    const gp_spec3d *spec = spec_;
    json_t *head = head_3d(s, spec, spec_json);
    if (!head) return NULL;
    unsigned out = spec->outputs;
    gpd_jw_begin_object(w);
    gpd_jw_members(w, head);
    /* the arrays, written as they are read; the writer stops by itself at the cancel flag */
    int nt = spec->threads > 0 ? spec->threads : 1; /* the job's: the same bytes whatever */
    if ((out & GP_OUT3_SPHERES) && s->spheres) {
        gpd_jw_key(w, "spheres");
        gpd_jw_begin_array(w);
        gpd_jw_items(w, s->count, sphere_item, s, nt, ITEMS_BLOCK);
        gpd_jw_end_array(w);
    }
    if ((out & GP_OUT3_CONTACTS) && s->contacts) {
        gpd_jw_key(w, "contacts");
        gpd_jw_begin_array(w);
        gpd_jw_items(w, s->ncontacts, contact_item, s, nt, ITEMS_BLOCK / 2);
        gpd_jw_end_array(w);
    }
    gpd_jw_end_object(w);
    return head;
}

/* ------------------------------------------------------------------ the kind */

GPD_KIND_CORE(gp_spec3d, gp_spec3d_read, gp_spec3d_free, gp_specimen3d, gp_specimen3d_build,
              gp_specimen3d_destroy)

/* {steps, porosity, stability} */
static json_t *progress_detail(const gp_progress *p)
{
    return json_pack("{s:I, s:o, s:o}", "steps", (json_int_t)p->steps, "porosity",
                     gpd_jreal(p->porosity), "stability", gpd_jreal(p->stability));
}

/* The brief: the spheres of the final (tiled) packing, known once it has succeeded (the
 * sieve's count is only drawn by the run), and the porosity. */
static json_t *brief(const json_t *spec, const json_t *stats)
{
    json_t *particles = NULL, *achieved = NULL;
    if (stats) {
        particles = json_deep_copy(json_object_get(stats, "particles"));
        achieved = json_deep_copy(json_object_get(json_object_get(stats, "porosity"), "achieved"));
    }
    return gpd_brief_new(spec, "porosity", particles, achieved);
}

/* ---- the progress plan (progress.h): seconds on one core, measured with
 * bench/bench_progress.py (the paper's example, in the run that measured the 2D kind's) ---- */
#define SPHERE_STEPS_S 3.5e6 /* DEM sphere-steps a second */
/* the phases' seconds, as shares of the protocol's DEM that gp_spec_bounds counts (50 time
 * units of sqrt(d50 / g)): deposition is GROW_T + SETTLE_T = 2.95 of them at most (core/3d);
 * compaction and relaxation run until they converge (the paper's example, seven runs: 2.7 to
 * 6 and 0.9 to 2 times the deposition's seconds; their steps cost more, with more contacts) */
#define DEPOSITION_SHARE 0.059
#define COMPACTION_SHARE 0.32
#define RELAXATION_SHARE 0.11
#define COST_TILE_S 0.4e-6    /* the flip and the measures, a sphere of the tiled packing */
#define BYTES_SPHERE 90       /* the result's text: a sphere [x, y, z, r] at 17 digits */
#define COST_CONTACT_S 23e-6  /* a contact of the result: an object of 210 bytes, 0.11 us each */
#define CONTACTS_GUESS 2.3    /* contacts a sphere of the tiled packing, for the plan */
/* stats.transfer of a tiling (gp_specimen3d.h), reported as "tiling": g(r) to 5 d50 costs
 * ~25 us a sphere of the sample (its ~500 pairs in reach, and the images of most spheres
 * across the near walls) and ~10 us a sphere of the block of at most 2 x 2 x 2 tiles where
 * the final packing's is measured (S0 of the paper: 0.06 s, and 0.18 s for 19,440 spheres);
 * the whole tiling's porosity, contacts, fabric and PSD ~0.25 us a sphere (0.036 s for the
 * 155,520 of 4 x 4 x 4) */
#define COST_RDF_SAMPLE_S 25e-6
#define COST_RDF_BLOCK_S 10e-6
#define COST_TRANSFER_S 0.25e-6

static int plan(const void *spec_, const json_t *spec_json, gpd_phase *out, int max)
{
    gp_spec_bounds_t b;
    gp_spec_problem p;
    if (gp_spec_bounds(spec_json, &b, &p) || max < 5) return 0;
    double dem = b.cells * b.steps / SPHERE_STEPS_S; /* the whole protocol's */
    out[0] = (gpd_phase){"deposition", DEPOSITION_SHARE * dem, 1};
    out[1] = (gpd_phase){"compaction", COMPACTION_SHARE * dem, 0};
    out[2] = (gpd_phase){"relaxation", RELAXATION_SHARE * dem, 0};
    /* (the measures report as "tiling" without a tiling too) */
    out[3] = (gpd_phase){"tiling", COST_TILE_S * b.items, 1};
    const int *tl = ((const gp_spec3d *)spec_)->tiling;
    if (tl[0] * (double)tl[1] * tl[2] > 1) {
        double block = 1;
        for (int a = 0; a < 3; a++) block *= tl[a] < 2 ? tl[a] : 2;
        out[3].cost_s += COST_RDF_SAMPLE_S * b.cells + COST_RDF_BLOCK_S * block * b.cells +
                         COST_TRANSFER_S * b.items;
    }
    unsigned o = ((const gp_spec3d *)spec_)->outputs;
    double per = ((o & GP_OUT3_SPHERES) ? GPD_RESULT_S_PER_BYTE * BYTES_SPHERE : 0) +
                 ((o & GP_OUT3_CONTACTS) ? CONTACTS_GUESS * COST_CONTACT_S : 0);
    out[4] = (gpd_phase){"result", per * b.items, 1};
    return 5;
}

/* the result's spheres and contacts */
static double result_cost(const void *specimen)
{
    const gp_specimen3d *s = specimen;
    return (s->spheres ? GPD_RESULT_S_PER_BYTE * BYTES_SPHERE * (double)s->count : 0) +
           (s->contacts ? COST_CONTACT_S * (double)s->ncontacts : 0);
}

/* the sphere list, when the spec asked for it, with the material and DEM settings that the
 * lammps-relax export writes into its LAMMPS script */
static int pack(const void *specimen, const void *spec, void **pack, size_t *len, gp_error *err)
{
    const gp_specimen3d *s = specimen;
    if (!s->spheres) return 1;
    return gp_export_pack_3d_dem(s, spec, pack, len, err) ? -1 : 0;
}

/* an infeasible or unconverged packing says why it stopped */
static void failure_note(const void *specimen, char *buf, size_t n)
{
    const gp_specimen3d *s = specimen;
    if (s->stats.stop_reason) snprintf(buf, n, " (stop reason: %s)", s->stats.stop_reason);
}

/* a result without "kind": its spheres, its box or its sieve curves */
static int owns_result(const json_t *r)
{
    return json_object_get(r, "spheres") || json_object_get(r, "box") ||
           json_object_get(json_object_get(r, "stats"), "psd");
}

/* the api.md example */
static const char example[] =
    "{\"kind\": \"" KIND_NAME "\", \"seed\": 7, \"box\": [0.5, 0.5, 0.5],"
    " \"sieve\": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], \"sieve_units\": \"mm\","
    " \"porosity\": 0.38,"
    " \"material\": {\"density\": 2600, \"young\": 15e6, \"poisson\": 0.5, \"friction_deg\": 18,"
    " \"damping\": 0.2},"
    " \"tiling\": [4, 4, 4], \"outputs\": [\"spheres\", \"contacts\", \"fabric\", \"stress\"]}";

static const gpd_view views[] = {
    {"section", "z", svg_views3d_section, NULL},
    {"psd", "", svg_views3d_psd, NULL},
    {"transfer", "", svg_transfer3d_rdf, "stats.transfer"},
    {NULL, NULL, NULL, NULL},
};

/* the phases of its "timings" (result) */
static const char *const phases[] = {"deposition", "compaction", "relaxation", "tiling", "total",
                                     NULL};

const gpd_kind gpd_kind_spheres3d = {
    .name = KIND_NAME, .example = example, .views = views, .owns_result = owns_result,
    .bounds = gp_spec_check_result, .brief = brief, GPD_KIND_CORE_OPS(gp_spec3d),
    .progress_detail = progress_detail, .plan = plan, .result_cost = result_cost,
    .result = result, .pack = pack, .failure_note = failure_note, .export_dim = 3, .pack_what = "sphere list",
    .pack_output = "spheres", .phases = phases};
