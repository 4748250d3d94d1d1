/* gp_fv3d.c -- the 3D Fourier-Voronoi pipeline: IMC, grains, placement, rank matching, clumps,
 * fit (gp_fv3d.h). */
#include "gp_fv3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_clock.h"
#include "gp_clump3d.h"
#include "gp_fill3d.h"
#include "gp_fourier.h"
#include "gp_shape.h"
#include "gp_grain3d.h"
#include "gp_imc3d.h"
#include "gp_rng.h"
#include "gp_team.h"

#define FV3D_STAR_DRAWS 100      /* draws of a grain's amplitudes before its spectrum is refused */
#define FV3D_STREAM_GRAINS 2     /* grain i draws from stream 2 + i */
#define FV3D_STREAM_REFERENCE (1ULL << 62) /* the 2D reference grains */
#define FV3D_PROGRESS_EVERY 64   /* grains between two progress reports */
#define FV3D_CURVE_POINTS 64
#define FV3D_PROBE_LEVEL 3       /* 162 directions: degrees <= FV3D_MATCH_DEGREE resolved */
#define FV3D_MATCH_DEGREE 7      /* degrees 2 .. this take their cell's shape */

/* the directions and harmonics on which a cell's shape is projected (match_low_modes) */
typedef struct probe {
    gp_mesh3d *sphere;  /* icosphere of FV3D_PROBE_LEVEL */
    size_t n;
    unsigned degree;
    double *Y;          /* n x (degree + 1)^2 */
} probe;

struct gp_fv3d {
    size_t n;
    probe probe;
    gp_voronoi3d *cells;
    gp_grain3d_basis *basis;
    gp_fv3d_grain *grains;
    const double *dirs;
    const uint32_t *tris;
    size_t ndirs, ntris;
    gp_fv3d_stats stats;
    gp_fv3d_timings timings;
};

void gp_fv3d_spec_defaults(gp_fv3d_spec *s)
{
    static const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    memset(s, 0, sizeof *s);
    s->container = gp_voronoi3d_box(lo, hi);
    s->particles = 1000;
    s->axis[2] = 1.0;
    s->anisotropy = 1.0;
    s->elongation = s->flatness = 1.0;
    s->mesh_level = GP_GRAIN3D_LEVEL_DEFAULT;
    s->solid_fraction = 0.55;
    s->spheres_max = 30;
    s->min_radius_ratio = 0.1;
    s->imc_threshold = gp_imc_default_threshold(GP_IMC_ERROR_AD);
    s->imc_max_steps = 1000000;
    s->outputs = GP_OUT3_GRAINS;
    s->threads = 1;
}

/* ------------------------------------------------------------------------------ the spec */

static gp_status check_spec(const gp_fv3d_spec *s, gp_error *err)
{
    if (!s) return gp_error_set(err, GP_ERR_INVALID, "fv3d: no spec");
    if (s->particles < 1) return gp_error_set(err, GP_ERR_INVALID, "fv3d: particles must be >= 1");
    if (!s->law) return gp_error_set(err, GP_ERR_INVALID, "fv3d: size: no law");
    if (!(s->anisotropy > 0.0 && s->anisotropy <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "fv3d: orientation.anisotropy must be in (0, 1]");
    if (!s->D || s->nmodes < 1) return gp_error_set(err, GP_ERR_INVALID, "fv3d: shape: no spectrum");
    if (!(s->spread >= 0.0 && s->spread <= 2.0))
        return gp_error_set(err, GP_ERR_INVALID, "fv3d: shape.spread must be in [0, 2]");
    if (!(s->elongation > 0.0 && s->elongation <= 1.0) || !(s->flatness > 0.0 && s->flatness <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "fv3d: shape.elongation and shape.flatness must be in (0, 1]");
    if (s->mesh_level > GP_MESH3D_ICOSPHERE_LEVEL_MAX)
        return gp_error_set(err, GP_ERR_INVALID, "fv3d: mesh level must be <= %d", GP_MESH3D_ICOSPHERE_LEVEL_MAX);
    if (!(s->solid_fraction > 0.0 && s->solid_fraction < 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "fv3d: solid_fraction must be in (0, 1)");
    if (s->spheres_max < 1 || s->spheres_max > 1000 || !(s->min_radius_ratio > 0.0 && s->min_radius_ratio <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "fv3d: clump.spheres_max must be in 1..1000 and "
                                                 "clump.min_radius_ratio in (0, 1]");
    if (s->threads < 1) return gp_error_set(err, GP_ERR_INVALID, "fv3d: threads must be >= 1");
    return GP_OK;
}

static unsigned degree_of(const gp_fv3d_spec *s)
{
    size_t n = s->nmodes - 1;
    return n > GP_GRAIN3D_DEGREE_MAX ? GP_GRAIN3D_DEGREE_MAX : (unsigned)n;
}

/* ------------------------------------------------------------------------------ the cells */

typedef struct cellbuf {
    double *planes;
    size_t cap;
} cellbuf;

/* the outward planes of cell i (gp_voronoi3d_cell_planes); 0 when out of memory */
static size_t cell_planes(const gp_voronoi3d *v, size_t i, cellbuf *b)
{
    size_t nf = gp_voronoi3d_cell_face_count(v, i);
    if (nf > b->cap) {
        double *q = realloc(b->planes, 4 * 2 * nf * sizeof *q);
        if (!q) return 0;
        b->planes = q;
        b->cap = 2 * nf;
    }
    return gp_voronoi3d_cell_planes(v, i, b->planes, nf);
}

/* ----------------------------------------------------------------------------- one grain */

typedef struct job {
    const gp_fv3d_spec *spec;
    gp_fv3d *out;
    gp_grain3d_law law;
    double *cov;              /* per mode: the spread */
    double fill_fraction;     /* F_S, or F_S x headroom for a law of grains */
    int next;                 /* the next grain to take (atomic) */
    int done;                 /* grains finished (atomic) */
    gp_status *status;        /* per grain */
    gp_error *errors;         /* per grain */
    const volatile int *cancel;
    int cancelled;            /* atomic */
    gp_progress_fn progress;  /* called from the caller's thread only */
    void *user;
} job;

typedef struct worker {
    cellbuf cb;
    double *xyz;   /* the grain's vertices at scale 1 */
    gp_rng *rng;
} worker;

static double u01(void *r) { return gp_rng_uniform(r); }

static void quat_of(const double R[9], double q[4])
{
    double t = R[0] + R[4] + R[8];
    if (t > 0) {
        double s = 2.0 * sqrt(1.0 + t);
        q[0] = 0.25 * s;
        q[1] = (R[7] - R[5]) / s;
        q[2] = (R[2] - R[6]) / s;
        q[3] = (R[3] - R[1]) / s;
    } else if (R[0] > R[4] && R[0] > R[8]) {
        double s = 2.0 * sqrt(1.0 + R[0] - R[4] - R[8]);
        q[0] = (R[7] - R[5]) / s;
        q[1] = 0.25 * s;
        q[2] = (R[1] + R[3]) / s;
        q[3] = (R[2] + R[6]) / s;
    } else if (R[4] > R[8]) {
        double s = 2.0 * sqrt(1.0 + R[4] - R[0] - R[8]);
        q[0] = (R[2] - R[6]) / s;
        q[1] = (R[1] + R[3]) / s;
        q[2] = 0.25 * s;
        q[3] = (R[5] + R[7]) / s;
    } else {
        double s = 2.0 * sqrt(1.0 + R[8] - R[0] - R[4]);
        q[0] = (R[3] - R[1]) / s;
        q[1] = (R[2] + R[6]) / s;
        q[2] = (R[5] + R[7]) / s;
        q[3] = 0.25 * s;
    }
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int k = 0; k < 4; k++) q[k] /= n;
    if (q[0] < 0)
        for (int k = 0; k < 4; k++) q[k] = -q[k];
}

static void rot_of(const double q[4], double R[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                   2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                   2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    memcpy(R, M, sizeof M);
}

/* the grain's world pose and integrals from its unit-scale mass properties and the fill */
static void pose(gp_fv3d_grain *g, const gp_mesh3d_mass *m, const gp_fill3d_result *f, const double axis[3])
{
    double R[9], s = f->scale, RI[9];
    memcpy(R, f->R, sizeof R);
    memcpy(g->centre, f->centre, sizeof g->centre);
    quat_of(R, g->rotation);
    g->scale = s;
    g->volume = s * s * s * m->volume;
    for (int r = 0; r < 3; r++)
        g->centroid[r] = g->centre[r] + s * (R[3 * r] * m->centroid[0] + R[3 * r + 1] * m->centroid[1] +
                                             R[3 * r + 2] * m->centroid[2]);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            RI[3 * r + c] = R[3 * r] * m->inertia[c] + R[3 * r + 1] * m->inertia[3 + c] + R[3 * r + 2] * m->inertia[6 + c];
    double s5 = s * s * s * s * s;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            g->inertia[3 * r + c] = s5 * (RI[3 * r] * R[3 * c] + RI[3 * r + 1] * R[3 * c + 1] + RI[3 * r + 2] * R[3 * c + 2]);
    g->orientation_cos = gp_orient3d_cos(g->inertia, axis);
    g->target_met = f->target_met;
}

static void describe(gp_fv3d_grain *g, const gp_grain3d_basis *b, const gp_grain3d_descriptors *d, gp_error *err)
{
    g->desc.elongation = d->elongation;
    g->desc.flatness = d->flatness;
    g->desc.sphericity = d->sphericity;
    g->desc.convexity = d->convexity;
    gp_shape_result pr[3];
    if (gp_grain3d_describe_projections(b, g->radii, &d->axes, NULL, pr, err) != GP_OK) {
        for (int k = 0; k < 3; k++)
            for (int q = 0; q < 4; q++) g->desc.proj[k][q] = NAN;
        return;
    }
    for (int k = 0; k < 3; k++) {
        g->desc.proj[k][0] = pr[k].elongation;
        g->desc.proj[k][1] = pr[k].roundness;
        g->desc.proj[k][2] = pr[k].circularity;
        g->desc.proj[k][3] = pr[k].regularity;
    }
}

/* the clump of the unit-scale grain, in its own frame (placed once the scale is final) */
static gp_status clump(job *J, worker *W, gp_fv3d_grain *g, const gp_mesh3d_mass *m, gp_error *err)
{
    gp_clump3d_params cp;
    gp_clump3d_params_defaults(&cp);
    cp.spheres_max = (size_t)J->spec->spheres_max;
    cp.min_radius_ratio = J->spec->min_radius_ratio;
    gp_clump3d_body body = {m->volume, {m->centroid[0], m->centroid[1], m->centroid[2]}, {0}};
    memcpy(body.inertia, m->inertia, sizeof body.inertia);
    gp_clump3d_result r;
    gp_status st = gp_clump3d_build(W->xyz, J->out->ndirs, J->out->tris, J->out->ntris, &body, &cp, &r, err);
    if (st != GP_OK) return st;
    g->spheres = malloc(4 * r.nspheres * sizeof(double));
    if (!g->spheres) {
        gp_clump3d_result_free(&r);
        return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory for a clump");
    }
    for (size_t k = 0; k < r.nspheres; k++) {
        g->spheres[4 * k] = r.spheres[k].x;
        g->spheres[4 * k + 1] = r.spheres[k].y;
        g->spheres[4 * k + 2] = r.spheres[k].z;
        g->spheres[4 * k + 3] = r.spheres[k].r;
    }
    g->nspheres = r.nspheres;
    g->clump_volume_error = r.volume_error;
    g->clump_inertia_error = r.inertia_error;
    gp_clump3d_result_free(&r);
    return GP_OK;
}

/* ------------------------------------------------------------- the grain takes its cell's shape */

static gp_status probe_init(probe *P, unsigned degree, gp_error *err)
{
    P->degree = degree < FV3D_MATCH_DEGREE ? degree : FV3D_MATCH_DEGREE;
    if (!(P->sphere = gp_mesh3d_icosphere(FV3D_PROBE_LEVEL, err))) return err ? err->code : GP_ERR_NOMEM;
    P->n = gp_mesh3d_vertex_count(P->sphere);
    size_t m = GP_GRAIN3D_NCOEF(P->degree);
    if (!(P->Y = malloc(P->n * m * sizeof *P->Y))) return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    const double *u = gp_mesh3d_vertices(P->sphere);
    for (size_t i = 0; i < P->n; i++) gp_grain3d_harmonics(P->degree, u + 3 * i, P->Y + i * m);
    return GP_OK;
}

static void probe_free(probe *P)
{
    gp_mesh3d_destroy(P->sphere);
    free(P->Y);
}

/* The cell seen from c in the grain's frame before its stretch: a grain point y is at
 * x = c + s E S y, so the face n . x <= d reads (S E^T n) . y <= (d - n . c) / s; along u its
 * distance is the least (d - n . c) / ((S E^T n) . u) over the faces in front (s dropped: only
 * the shape counts). Its harmonics of degrees 2 .. P->degree by the probe's quadrature (equal
 * weights), and each degree of the grain turned to them with its own norm kept: the spectrum
 * stays exact, the grain's low modes follow its cell as the 2D grain's phases follow its
 * cell's contour (Mollon & Zhao, Sect. 4.1). */
static void match_low_modes(const probe *P, const double *planes, size_t nf, const double c[3], const double E[9],
                            double elong, double flat, gp_grain3d_shape *shape)
{
    double S[3] = {1.0, elong, elong * flat}, cell[GP_GRAIN3D_NCOEF(FV3D_MATCH_DEGREE)] = {0};
    size_t m = GP_GRAIN3D_NCOEF(P->degree);
    const double *u = gp_mesh3d_vertices(P->sphere);
    for (size_t i = 0; i < P->n; i++) {
        double r = INFINITY;
        for (size_t f = 0; f < nf; f++) {
            const double *n = planes + 4 * f;
            double h = n[3] - (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]), mu = 0.0;
            for (int k = 0; k < 3; k++) mu += S[k] * (E[k] * n[0] + E[3 + k] * n[1] + E[6 + k] * n[2]) * u[3 * i + k];
            if (mu > 0.0 && h / mu < r) r = h / mu;
        }
        for (size_t k = 0; k < m; k++) cell[k] += r * P->Y[i * m + k];
    }
    /* a grain given an elongation or flatness keeps its degree 2 as drawn: turned to its cell,
     * that degree would take up the cell's own aspect in place of the one asked for */
    unsigned first = elong < 1.0 || flat < 1.0 ? 3 : 2;
    for (unsigned n = first; n <= P->degree && n <= shape->degree; n++) {
        double a = 0.0, b = 0.0;
        for (int q = -(int)n; q <= (int)n; q++) {
            a += cell[GP_GRAIN3D_INDEX(n, q)] * cell[GP_GRAIN3D_INDEX(n, q)];
            b += shape->c[GP_GRAIN3D_INDEX(n, q)] * shape->c[GP_GRAIN3D_INDEX(n, q)];
        }
        if (!(a > 0.0)) continue;
        double f = sqrt(b / a);
        for (int q = -(int)n; q <= (int)n; q++) shape->c[GP_GRAIN3D_INDEX(n, q)] = f * cell[GP_GRAIN3D_INDEX(n, q)];
    }
}

/* the cell as gp_fill3d takes it, its principal frame, and the grain's scale-1 integrals */
static gp_status cell_of(job *J, worker *W, size_t i, gp_fill3d_cell *cell, double E[9], gp_error *err)
{
    const gp_voronoi3d *v = J->out->cells;
    size_t nf = cell_planes(v, i, &W->cb);
    if (nf == 0) return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory for cell %zu", i);
    *cell = (gp_fill3d_cell){W->cb.planes, nf, {0, 0, 0}, gp_voronoi3d_cell_volume(v, i), {0}};
    gp_voronoi3d_cell_centroid(v, i, cell->interior);
    gp_voronoi3d_cell_inertia(v, i, cell->inertia);
    if (!gp_fill3d_frame(cell->inertia, E)) return gp_error_set(err, GP_ERR_INTERNAL, "fv3d: cell %zu has no axes", i);
    return GP_OK;
}

/* the grain's radii: its amplitudes drawn from its stream and its low modes turned to its
 * cell's; when that is not star-shaped, the amplitudes as drawn; when neither is, drawn again */
static gp_status shape_grain(job *J, worker *W, const gp_fill3d_cell *cell, const double E[9], double *radii,
                             gp_error *err)
{
    gp_grain3d_shape shape;
    gp_status st = GP_ERR_NOT_STAR;
    for (int t = 0; t < FV3D_STAR_DRAWS && st == GP_ERR_NOT_STAR; t++) {
        if ((st = gp_grain3d_draw(&J->law, u01, W->rng, &shape, err)) != GP_OK) return st;
        gp_grain3d_shape matched = shape;
        match_low_modes(&J->out->probe, cell->planes, cell->nplanes, cell->interior, E, J->spec->elongation,
                        J->spec->flatness, &matched);
        st = gp_grain3d_radii(J->out->basis, &matched, radii, err);
        if (st == GP_ERR_NOT_STAR) st = gp_grain3d_radii(J->out->basis, &shape, radii, err);
    }
    if (st == GP_ERR_NOT_STAR)
        return gp_error_set(err, GP_ERR_NOT_STAR, "fv3d: shape: %d draws of the spectrum all have r <= 0 somewhere "
                                                  "(amplitudes too large for a star-shaped grain)", FV3D_STAR_DRAWS);
    return st;
}

static gp_status one_grain(job *J, worker *W, size_t i, gp_error *err)
{
    gp_fv3d *S = J->out;
    gp_fv3d_grain *g = &S->grains[i];
    g->cell = i;
    gp_rng_destroy(W->rng);
    if (!(W->rng = gp_rng_create(J->spec->seed, FV3D_STREAM_GRAINS + (uint64_t)i, err))) return err ? err->code : GP_ERR_NOMEM;
    if (!(g->radii = malloc(S->ndirs * sizeof(double)))) return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    gp_fill3d_cell cell;
    double E[9];
    gp_status st = cell_of(J, W, i, &cell, E, err);
    if (st == GP_OK) st = shape_grain(J, W, &cell, E, g->radii, err);
    if (st != GP_OK) return st;
    gp_grain3d_vertices(S->basis, g->radii, W->xyz);
    gp_grain3d_descriptors d;
    if (J->spec->outputs & GP_OUT3_DESCRIPTORS)
        st = gp_grain3d_describe(S->basis, g->radii, &d, err);
    else
        st = gp_mesh3d_mass_properties(W->xyz, S->ndirs, S->tris, S->ntris, &d.mass, err);
    if (st != GP_OK) return st;
    gp_fill3d_grain grain = {W->xyz, S->ndirs, d.mass.volume, {0}};
    memcpy(grain.inertia, d.mass.inertia, sizeof grain.inertia);
    gp_fill3d_params fp;
    gp_fill3d_params_defaults(&fp);
    fp.solid_fraction = J->fill_fraction;
    fp.rotation = E;
    gp_fill3d_result f;
    if ((st = gp_fill3d_place(&cell, &grain, &fp, u01, W->rng, &f, err)) != GP_OK) return st;
    pose(g, &d.mass, &f, J->spec->axis);
    if (J->spec->outputs & GP_OUT3_DESCRIPTORS) describe(g, S->basis, &d, err);
    if (J->spec->outputs & GP_OUT3_CLUMPS) st = clump(J, W, g, &d.mass, err);
    return st;
}

/* the caller's thread (tid 0) reports progress between its grains */
static int report_grains(job *J, int *last)
{
    int done = __atomic_load_n(&J->done, __ATOMIC_RELAXED);
    if (!J->progress || done - *last < FV3D_PROGRESS_EVERY) return 0;
    *last = done;
    double f = (double)done / (double)J->out->n;
    gp_progress pr = {"grains", f, f, done, 0.0, 0.0, 0.0};
    return J->progress(J->user, &pr);
}

static void grains_worker(void *ctx, int tid)
{
    job *J = ctx;
    worker W = {{NULL, 0}, malloc(3 * J->out->ndirs * sizeof(double)), NULL};
    int last = 0;
    for (;;) {
        if (__atomic_load_n(&J->cancelled, __ATOMIC_RELAXED) || gp_progress_cancelled(J->cancel) ||
            (tid == 0 && report_grains(J, &last))) {
            __atomic_store_n(&J->cancelled, 1, __ATOMIC_RELAXED);
            break;
        }
        int i = __atomic_fetch_add(&J->next, 1, __ATOMIC_RELAXED);
        if (i >= (int)J->out->n) break;
        J->status[i] = W.xyz ? one_grain(J, &W, (size_t)i, &J->errors[i])
                             : gp_error_set(&J->errors[i], GP_ERR_NOMEM, "fv3d: out of memory");
        __atomic_fetch_add(&J->done, 1, __ATOMIC_RELAXED);
    }
    gp_rng_destroy(W.rng);
    free(W.xyz);
    free(W.cb.planes);
}

/* ------------------------------------------------------------------------- rank matching */

typedef struct ranked {
    double v;
    size_t i;
} ranked;

static int cmp_ranked(const void *a, const void *b)
{
    const ranked *x = a, *y = b;
    if (x->v != y->v) return x->v < y->v ? -1 : 1;
    return (x->i > y->i) - (x->i < y->i);
}

/* shrinks grain g about its centre by lam (volume by lam^3): it stays in its convex cell,
 * since the centre and every vertex are in it */
static void shrink(gp_fv3d_grain *g, double lam)
{
    g->scale *= lam;
    g->volume *= lam * lam * lam;
    for (int k = 0; k < 3; k++) g->centroid[k] = g->centre[k] + lam * (g->centroid[k] - g->centre[k]);
    double l5 = lam * lam * lam * lam * lam;
    for (int k = 0; k < 9; k++) g->inertia[k] *= l5;
}

/* the k-th smallest grain gets the grain law's quantile (2k + 1) / 2N, when it is that large */
static gp_status rank_match(gp_fv3d *S, const gp_law *grain_law, gp_error *err)
{
    ranked *r = malloc(S->n * sizeof *r);
    if (!r) return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    for (size_t i = 0; i < S->n; i++) r[i] = (ranked){S->grains[i].volume, i};
    qsort(r, S->n, sizeof *r, cmp_ranked);
    for (size_t k = 0; k < S->n; k++) {
        gp_fv3d_grain *g = &S->grains[r[k].i];
        double q = gp_law_quantile(grain_law, (2.0 * k + 1.0) / (2.0 * S->n));
        g->target_met = g->volume >= q * (1.0 - 1e-12);
        if (q < g->volume) shrink(g, cbrt(q / g->volume));
    }
    free(r);
    return GP_OK;
}

/* the clumps, made at scale 1 in each grain's frame, placed with its final pose */
static void place_clumps(gp_fv3d *S)
{
    for (size_t i = 0; i < S->n; i++) {
        gp_fv3d_grain *g = &S->grains[i];
        double R[9];
        rot_of(g->rotation, R);
        for (size_t k = 0; k < g->nspheres; k++) {
            double *p = g->spheres + 4 * k, x[3] = {p[0], p[1], p[2]};
            for (int r = 0; r < 3; r++) p[r] = g->centre[r] + g->scale * (R[3 * r] * x[0] + R[3 * r + 1] * x[1] + R[3 * r + 2] * x[2]);
            p[3] *= g->scale;
        }
    }
}

/* --------------------------------------------------------------------------------- stats */

static gp_status fit_orient(const double *c, size_t n, double a, gp_fit_orient *out, gp_error *err)
{
    double *w = malloc((n ? n : 1) * sizeof *w);
    if (!w) return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    memcpy(w, c, n * sizeof *w);
    *out = (gp_fit_orient){n > 0, 0.0, a, n ? gp_orient3d_ks(w, n, a) : 0.0, gp_fit_ks_critical(n), n};
    free(w);
    return GP_OK;
}

static gp_status fit_all(gp_fv3d *S, const gp_fv3d_spec *spec, const gp_law *cell_law, const gp_law *grain_law,
                         gp_error *err)
{
    size_t n = S->n;
    gp_fv3d_stats *t = &S->stats;
    double *cv = malloc(n * sizeof *cv), *gv = malloc(n * sizeof *gv), *cc = malloc(n * sizeof *cc),
           *gc = malloc(n * sizeof *gc), sum = 0.0, total = 0.0;
    gp_status st = cv && gv && cc && gc ? GP_OK : gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    for (size_t i = 0; st == GP_OK && i < n; i++) {
        double I[9];
        cv[i] = gp_voronoi3d_cell_volume(S->cells, i);
        gp_voronoi3d_cell_inertia(S->cells, i, I);
        cc[i] = gp_orient3d_cos(I, spec->axis);
        gv[i] = S->grains[i].volume;
        gc[i] = S->grains[i].orientation_cos;
        sum += gv[i];
        total += cv[i];
        t->grains_short += !S->grains[i].target_met;
    }
    if (st == GP_OK) st = gp_fit_area_measure(cv, n, cell_law, FV3D_CURVE_POINTS, &t->cell_volume, err);
    if (st == GP_OK) st = gp_fit_area_measure(gv, n, grain_law, FV3D_CURVE_POINTS, &t->grain_volume, err);
    if (st == GP_OK) st = fit_orient(cc, n, spec->anisotropy, &t->cell_orientation, err);
    if (st == GP_OK) st = fit_orient(gc, n, spec->anisotropy, &t->grain_orientation, err);
    if (st == GP_OK && spec->law_of_grains) st = gp_fit_passing_measure(gv, n, spec->law, &t->passing, err);
    t->solid_fraction = sum / total;
    free(cv);
    free(gv);
    free(cc);
    free(gc);
    return st;
}

static void clump_stats(gp_fv3d *S)
{
    gp_fv3d_stats *t = &S->stats;
    size_t m = 0;
    for (size_t i = 0; i < S->n; i++) {
        const gp_fv3d_grain *g = &S->grains[i];
        if (!g->nspheres) continue;
        m++;
        t->clump_volume_error_mean += fabs(g->clump_volume_error);
        t->clump_inertia_error_mean += g->clump_inertia_error;
        t->clump_volume_error_max = fmax(t->clump_volume_error_max, fabs(g->clump_volume_error));
        t->clump_inertia_error_max = fmax(t->clump_inertia_error_max, g->clump_inertia_error);
    }
    if (m) {
        t->clump_volume_error_mean /= m;
        t->clump_inertia_error_mean /= m;
    }
}

/* the four 2D descriptors averaged over 2D Fourier grains of the spectrum */
static gp_status reference2d(const gp_fv3d_spec *spec, double mean[4], gp_error *err)
{
    size_t np = 128, nm = spec->nmodes < gp_fourier_max_modes(np) ? spec->nmodes : gp_fourier_max_modes(np);
    gp_rng *r = gp_rng_create(spec->seed, FV3D_STREAM_REFERENCE, err);
    double *delta = malloc(nm * sizeof *delta);
    gp_status st = r && delta ? GP_OK : gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    size_t got = 0;
    memset(mean, 0, 4 * sizeof *mean);
    for (int t = 0; st == GP_OK && got < GP_FV3D_REFERENCE_GRAINS && t < 4 * GP_FV3D_REFERENCE_GRAINS; t++) {
        if ((st = gp_fourier_random_phases(nm, u01, r, delta, err)) != GP_OK) break;
        gp_shape_curve curve = {{0.0, 0.0}, 1.0, spec->D, delta, nm};
        gp_shape_result res;
        if (gp_shape_describe_fourier(NULL, np, &curve, NULL, &res, NULL) != GP_OK) continue;
        double d[4] = {res.elongation, res.roundness, res.circularity, res.regularity};
        for (int k = 0; k < 4; k++) mean[k] += d[k];
        got++;
    }
    for (int k = 0; k < 4; k++) mean[k] = got ? mean[k] / (double)got : NAN;
    gp_rng_destroy(r);
    free(delta);
    return st;
}

static gp_status descriptor_stats(gp_fv3d *S, const gp_fv3d_spec *spec, gp_error *err)
{
    gp_fv3d_descriptor_stats *d = &S->stats.descriptors;
    memset(d, 0, sizeof *d);
    if (!(spec->outputs & GP_OUT3_DESCRIPTORS) || S->n == 0) return GP_OK;
    d->present = 1;
    d->target_elongation = spec->elongation;
    d->target_flatness = spec->flatness;
    double s2[4] = {0, 0, 0, 0}, n = (double)S->n;
    for (size_t i = 0; i < S->n; i++) {
        const gp_fv3d_descriptors *g = &S->grains[i].desc;
        double v[4] = {g->elongation, g->flatness, g->sphericity, g->convexity};
        for (int k = 0; k < 4; k++) {
            d->mean[k] += v[k] / n;
            s2[k] += v[k] * v[k] / n;
        }
        for (int a = 0; a < 3; a++)
            for (int k = 0; k < 4; k++) d->projection[a][k] += g->proj[a][k] / n;
    }
    for (int k = 0; k < 4; k++) d->sd[k] = sqrt(fmax(0.0, s2[k] - d->mean[k] * d->mean[k]));
    return reference2d(spec, d->reference2d, err);
}

/* --------------------------------------------------------------------------------- build */

static gp_status run_imc(gp_fv3d *S, const gp_fv3d_spec *spec, gp_progress_fn progress, void *user,
                         const volatile int *cancel, gp_error *err)
{
    gp_imc3d_params p;
    gp_imc3d_params_defaults(&p);
    p.law = spec->law;
    p.scale_law = 1;
    memcpy(p.axis, spec->axis, sizeof p.axis);
    p.anisotropy = spec->anisotropy;
    p.threshold = spec->imc_threshold;
    p.max_steps = spec->imc_max_steps;
    p.seed = spec->seed;
    p.threads = spec->threads;
    gp_imc3d_report r;
    memset(&r, 0, sizeof r);
    gp_status st = gp_imc3d_run(&spec->container, S->n, &p, progress, user, cancel, &S->cells, &r, err);
    S->stats.imc_error = r.error;
    S->stats.imc_error_initial = r.error_initial;
    S->stats.imc_steps = r.steps;
    S->stats.imc_stop = (int)r.stop_reason;
    if (st == GP_ERR_NOT_CONVERGED && S->cells) return GP_OK; /* a specimen that says so */
    return st;
}

static gp_status run_grains(gp_fv3d *S, const gp_fv3d_spec *spec, gp_progress_fn progress, void *user,
                            const volatile int *cancel, gp_error *err)
{
    job J;
    memset(&J, 0, sizeof J);
    J.spec = spec;
    J.out = S;
    J.fill_fraction = spec->law_of_grains ? fmin(1.0, spec->solid_fraction * GP_FV3D_HEADROOM) : spec->solid_fraction;
    J.cancel = cancel;
    J.progress = progress;
    J.user = user;
    J.cov = malloc(spec->nmodes * sizeof *J.cov);
    J.status = calloc(S->n, sizeof *J.status);
    J.errors = calloc(S->n, sizeof *J.errors);
    gp_team *team = NULL;
    gp_status st = J.cov && J.status && J.errors ? GP_OK : gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    if (st == GP_OK && !(team = gp_team_create(spec->threads, err))) st = GP_ERR_NOMEM;
    if (st == GP_OK) {
        for (size_t k = 0; k < spec->nmodes; k++) J.cov[k] = spec->spread;
        J.law = (gp_grain3d_law){spec->D, spec->spread > 0 ? J.cov : NULL, spec->nmodes, degree_of(spec),
                                 spec->elongation, spec->flatness};
        gp_team_run(team, grains_worker, &J);
        if (J.cancelled) st = gp_error_set(err, GP_ERR_CANCELLED, "fv3d: cancelled while building grains");
        for (size_t i = 0; st == GP_OK && i < S->n; i++)
            if (J.status[i] != GP_OK) {
                st = J.status[i];
                if (err) *err = J.errors[i];
            }
    }
    gp_team_destroy(team);
    free(J.cov);
    free(J.status);
    free(J.errors);
    return st;
}

/* the laws of the cells and of the grains, as the tessellation's volume makes them: a
 * parametric law gives its shape (the cells' mean is container / N, the grains' solid_fraction
 * of it); a sieve of grains is absolute */
static gp_status laws_of(const gp_fv3d *S, const gp_fv3d_spec *spec, gp_law **cell_law, gp_law **grain_law,
                         gp_error *err)
{
    double mean = gp_voronoi3d_container_volume(S->cells) / (double)S->n, m = gp_law_mean(spec->law);
    int sieve = gp_law_kind_of(spec->law) == GP_LAW_SIEVE;
    *cell_law = gp_law_scaled(spec->law, mean / m, err);
    *grain_law = gp_law_scaled(spec->law, sieve ? 1.0 : spec->solid_fraction * mean / m, err);
    return *cell_law && *grain_law ? GP_OK : (err ? err->code : GP_ERR_NOMEM);
}

static gp_status build(gp_fv3d *S, const gp_fv3d_spec *spec, gp_progress_fn progress, void *user,
                       const volatile int *cancel, gp_error *err)
{
    double t0 = gp_clock_seconds(), t;
    gp_status st = run_imc(S, spec, progress, user, cancel, err);
    S->timings.imc = (t = gp_clock_seconds()) - t0;
    if (st != GP_OK) return st;
    S->basis = gp_grain3d_basis_create_ex(spec->mesh_level, degree_of(spec), spec->elongation, spec->flatness, err);
    if (!S->basis) return err ? err->code : GP_ERR_NOMEM;
    const gp_mesh3d *m = gp_grain3d_basis_mesh(S->basis);
    S->ndirs = gp_mesh3d_vertex_count(m);
    S->ntris = gp_mesh3d_triangle_count(m);
    S->dirs = gp_mesh3d_vertices(m);
    S->tris = gp_mesh3d_triangles(m);
    if (!(S->grains = calloc(S->n, sizeof *S->grains))) return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    if ((st = probe_init(&S->probe, degree_of(spec), err)) != GP_OK) return st;
    st = run_grains(S, spec, progress, user, cancel, err);
    S->timings.grains = gp_clock_seconds() - t;
    if (st != GP_OK) return st;
    t = gp_clock_seconds();
    gp_law *cell_law = NULL, *grain_law = NULL;
    st = laws_of(S, spec, &cell_law, &grain_law, err);
    if (st == GP_OK && spec->law_of_grains) st = rank_match(S, grain_law, err);
    if (st == GP_OK) {
        place_clumps(S);
        st = fit_all(S, spec, cell_law, grain_law, err);
        clump_stats(S);
        if (st == GP_OK) st = descriptor_stats(S, spec, err);
    }
    S->stats.lost_volume = gp_voronoi3d_lost_volume(S->cells);
    gp_law_destroy(cell_law);
    gp_law_destroy(grain_law);
    S->timings.stats = gp_clock_seconds() - t;
    S->timings.total = gp_clock_seconds() - t0;
    return st;
}

gp_status gp_fv3d_build(const gp_fv3d_spec *spec, gp_progress_fn progress, void *user,
                        const volatile int *cancel, gp_fv3d **out, gp_error *err)
{
    if (!out) return gp_error_set(err, GP_ERR_INVALID, "fv3d: no output");
    *out = NULL;
    gp_status st = check_spec(spec, err);
    if (st != GP_OK) return st;
    gp_fv3d *S = calloc(1, sizeof *S);
    if (!S) return gp_error_set(err, GP_ERR_NOMEM, "fv3d: out of memory");
    S->n = spec->particles;
    st = build(S, spec, progress, user, cancel, err);
    if (st != GP_OK) {
        gp_fv3d_destroy(S);
        return st;
    }
    *out = S;
    return GP_OK;
}

void gp_fv3d_destroy(gp_fv3d *S)
{
    if (!S) return;
    for (size_t i = 0; S->grains && i < S->n; i++) {
        free(S->grains[i].radii);
        free(S->grains[i].spheres);
    }
    free(S->grains);
    gp_fit_area_free(&S->stats.cell_volume);
    gp_fit_area_free(&S->stats.grain_volume);
    gp_fit_passing_free(&S->stats.passing);
    gp_grain3d_basis_destroy(S->basis);
    probe_free(&S->probe);
    gp_voronoi3d_destroy(S->cells);
    free(S);
}

double gp_fv3d_estimate_bytes(const gp_fv3d_spec *spec)
{
    double nv = 10.0 * pow(4.0, spec->mesh_level) + 2.0, n = (double)spec->particles;
    double per = nv * sizeof(double) + sizeof(gp_fv3d_grain) + 600.0 /* a cell */;
    if (spec->outputs & GP_OUT3_CLUMPS) per += 4.0 * sizeof(double) * spec->spheres_max;
    double basis = nv * (double)GP_GRAIN3D_NCOEF(spec->nmodes > 1 ? degree_of(spec) : 0) * sizeof(double);
    return n * per + basis + (double)spec->threads * 4.0 * nv * sizeof(double);
}

size_t gp_fv3d_count(const gp_fv3d *s) { return s->n; }
const gp_voronoi3d *gp_fv3d_cells(const gp_fv3d *s) { return s->cells; }
const gp_fv3d_grain *gp_fv3d_grain_at(const gp_fv3d *s, size_t i) { return &s->grains[i]; }
const gp_fv3d_stats *gp_fv3d_stats_of(const gp_fv3d *s) { return &s->stats; }
const gp_fv3d_timings *gp_fv3d_timings_of(const gp_fv3d *s) { return &s->timings; }

size_t gp_fv3d_directions(const gp_fv3d *s, const double **xyz)
{
    if (xyz) *xyz = s->dirs;
    return s->ndirs;
}

size_t gp_fv3d_triangles(const gp_fv3d *s, const uint32_t **tri)
{
    if (tri) *tri = s->tris;
    return s->ntris;
}

void gp_fv3d_grain_vertices(const gp_fv3d *s, size_t i, double *xyz)
{
    const gp_fv3d_grain *g = &s->grains[i];
    double R[9];
    rot_of(g->rotation, R);
    for (size_t k = 0; k < s->ndirs; k++) {
        const double *d = s->dirs + 3 * k;
        double p[3] = {g->radii[k] * d[0], g->radii[k] * d[1], g->radii[k] * d[2]};
        for (int r = 0; r < 3; r++)
            xyz[3 * k + r] = g->centre[r] + g->scale * (R[3 * r] * p[0] + R[3 * r + 1] * p[1] + R[3 * r + 2] * p[2]);
    }
}
