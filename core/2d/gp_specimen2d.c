/* gp_specimen2d.c -- the 2D pipeline: container -> IMC tessellation -> filling -> ODEC ->
 * descriptors -> statistics. See gp_specimen2d.h.
 *
 * Determinism: every random draw is tied to what it is for, not to the order of work. The
 * IMC uses stream 0 of the spec's seed; cell i draws its grain's random phases from stream
 * 1 + i and, with a shape spread, its amplitudes from stream 2^62 + i (gp_grainshape.h).
 * Cells are filled by a pool of threads that take cells from a shared counter and write
 * results by cell index, so the specimen is the same bits whatever the thread count.
 *
 * Shape (gp_specimen2d_shape.c): the mean spectrum and the per-mode spread are
 * settled first (phase "shape": the descriptor fit or the outlines' analysis); with target
 * descriptors the spectrum is then calibrated on filled grains (phase "calibration", below
 * build_grains) before the fill proper.
 */
#define _GNU_SOURCE /* qsort_r */
#include "gp_specimen2d.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_clock.h"
#include "gp_fill.h"
#include "gp_fit.h"
#include "gp_fourier.h"
#include "gp_grainshape.h"
#include "gp_imc.h"
#include "gp_odec.h"
#include "gp_rng.h"
#include "gp_shape.h"
#include "gp_shapemap.h"
#include "gp_specimen2d_internal.h"
#include "gp_voronoi.h"

#define DEG (180.0 / M_PI)
#define DESCRIPTOR_CLASSES 20
/* Circle containers are polygonised with this largest distance to the circle, relative to
 * the radius (about 220 vertices; area short by ~1.3e-4 relative). */
#define CIRCLE_TOL 1e-4

void gp_spec2d_defaults(gp_spec2d *s)
{
    static gp_vec2 unit_square[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    memset(s, 0, sizeof *s);
    s->seed = 0;
    s->container = GP_CONTAINER_POLYGON;
    s->outer.pts = unit_square;
    s->outer.n = 4;
    s->particles = 100;
    s->size_law = GP_LAW_LOGNORMAL;
    s->cov = 0.5;
    s->mean_deg = 0.0;
    s->anisotropy = 1.0;
    s->D2 = 0.1;
    s->D3 = 0.05;
    s->D8 = 0.02;
    s->alpha = -2.0;
    s->beta = -2.0;
    s->solid_fraction = 0.65;
    s->imc_error = GP_IMC_AD;
    s->imc_threshold = gp_imc_default_threshold(GP_IMC_ERROR_AD);
    s->imc_max_steps = gp_spec2d_default_max_steps(s->particles);
    s->imc_init = GP_INIT_UNIFORM;
    s->imc_classes = 0;
    s->contour_points = 128;
    s->outputs = GP_OUT2_GRAINS;
    s->threads = 1;
}

long gp_spec2d_default_max_steps(size_t cells)
{
    double k = (double)GP_IMC_DEFAULT_STEPS_PER_CELL * (double)cells;
    return k > (double)GP_IMC_DEFAULT_STEPS_MIN ? (long)k : GP_IMC_DEFAULT_STEPS_MIN;
}

static double rng_u01(void *state) { return gp_rng_uniform((gp_rng *)state); }

/* The service raises the cancel flag from another thread with an atomic store; read it
 * atomically too (a plain volatile read is a data race in C11 terms). */
static int cancelled(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

/* ---------------------------------------------------------------- histograms */

static void hist_free(gp_hist *h)
{
    free(h->edges);
    free(h->target);
    free(h->achieved);
    memset(h, 0, sizeof *h);
}

static int hist_alloc(gp_hist *h, size_t k, int with_target)
{
    h->nclasses = k;
    h->edges = calloc(k + 1, sizeof(double));
    h->achieved = calloc(k, sizeof(double));
    h->target = with_target ? calloc(k, sizeof(double)) : NULL;
    return h->edges && h->achieved && (!with_target || h->target) ? 0 : -1;
}

/* Sets h->achieved to the normalised counts of values[0..n); values outside the edges go
 * to the first or last class, as the IMC counts them. */
static void hist_fill(gp_hist *h, const double *values, size_t n)
{
    for (size_t k = 0; k < h->nclasses; k++)
        h->achieved[k] = 0.0;
    if (n == 0)
        return;
    for (size_t i = 0; i < n; i++) {
        double v = values[i];
        size_t lo = 0, hi = h->nclasses; /* find k with edges[k] <= v < edges[k+1] */
        if (v < h->edges[0]) {
            hi = 1;
        } else if (v >= h->edges[h->nclasses]) {
            lo = h->nclasses - 1;
        } else {
            while (hi - lo > 1) {
                size_t mid = (lo + hi) / 2;
                if (h->edges[mid] <= v) lo = mid; else hi = mid;
            }
        }
        h->achieved[lo] += 1.0;
    }
    for (size_t k = 0; k < h->nclasses; k++)
        h->achieved[k] /= (double)n;
}

static int hist_copy(gp_hist *dst, const gp_hist *src, double scale_edges)
{
    if (hist_alloc(dst, src->nclasses, src->target != NULL) != 0)
        return -1;
    for (size_t k = 0; k <= src->nclasses; k++)
        dst->edges[k] = src->edges[k] * scale_edges;
    for (size_t k = 0; k < src->nclasses; k++) {
        dst->achieved[k] = src->achieved[k];
        if (src->target)
            dst->target[k] = src->target[k];
    }
    return 0;
}

/* A histogram from the IMC report. The last area class is open (its upper edge is +inf,
 * which JSON cannot carry): its edge is shown at the largest cell area, or one class width
 * past the previous edge if that is larger. */
static int report_hist(gp_hist *h, size_t k, const double *edges, const double *target,
                       const double *achieved, const gp_voronoi *vor)
{
    if (hist_alloc(h, k, 1) != 0)
        return -1;
    for (size_t c = 0; c <= k; c++)
        h->edges[c] = edges[c];
    for (size_t c = 0; c < k; c++) {
        h->target[c] = target[c];
        h->achieved[c] = achieved[c];
    }
    if (!isfinite(h->edges[k])) {
        double hi = k >= 2 ? 2.0 * h->edges[k - 1] - h->edges[k - 2] : 2.0 * h->edges[k - 1];
        for (size_t i = 0; vor && i < gp_voronoi_count(vor); i++)
            hi = fmax(hi, gp_voronoi_cell_area(vor, i));
        h->edges[k] = hi;
    }
    return 0;
}

/* ---------------------------------------------------------------- container */

typedef struct container {
    gp_vec2 *outer;      /* points to the spec's ring or to `owned` */
    size_t nouter;
    const gp_vec2 **holes;
    size_t *nhole;
    size_t nholes;
    gp_vec2 *owned;      /* polygonised circle */
} container;

static void container_free(container *c)
{
    free(c->owned);
    free(c->holes);
    free(c->nhole);
}

static gp_status container_make(const gp_spec2d *s, container *c, gp_error *err)
{
    memset(c, 0, sizeof *c);
    if (s->container == GP_CONTAINER_CIRCLE) {
        if (!(s->circle_radius > 0.0) || !isfinite(s->circle_radius))
            return gp_error_set(err, GP_ERR_INVALID, "container.circle.radius must be > 0");
        gp_status st = gp_voronoi_circle_polygon(s->circle_center, s->circle_radius,
                                                 CIRCLE_TOL * s->circle_radius, &c->owned,
                                                 &c->nouter, err);
        if (st != GP_OK)
            return st;
        c->outer = c->owned;
    } else {
        if (!s->outer.pts || s->outer.n < 3)
            return gp_error_set(err, GP_ERR_INVALID, "container.polygon needs >= 3 points");
        c->outer = s->outer.pts;
        c->nouter = s->outer.n;
    }
    if (s->nholes) {
        c->holes = calloc(s->nholes, sizeof *c->holes);
        c->nhole = calloc(s->nholes, sizeof *c->nhole);
        if (!c->holes || !c->nhole)
            return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        for (size_t h = 0; h < s->nholes; h++) {
            c->holes[h] = s->holes[h].pts;
            c->nhole[h] = s->holes[h].n;
        }
        c->nholes = s->nholes;
    }
    return GP_OK;
}

/* ---------------------------------------------------------------- filling pool */

/* What pass A leaves for pass B about one grain: the curve it was cut from. The random phases
 * are not kept (nmodes doubles a cell): pass B draws them again from the cell's stream. */
typedef struct grain_curve {
    gp_vec2 centre;
    double r0;
    double phases27[6];        /* the optimised phases of modes 2..7 */
    double rotation;           /* and the fill's rotation (gp_fill_result): a refill's start */
    unsigned char mean_only;   /* spread: its own spectrum could not be filled (not star-shaped
                                * for any phase the fill tried); it has the mean spectrum */
    unsigned char outcome;     /* spread: gp_grainshape_outcome of its draw */
} grain_curve;

/* PASS_CALIBRATE describes the grains of a calibration subset (descriptors form) */
enum { PASS_FILL = 0, PASS_FINISH = 1, PASS_CALIBRATE = 2 };

typedef struct fill_job {
    const gp_spec2d *spec;
    const gp_voronoi *vor;
    const double *D;           /* the mean spectrum (the specimen's shape.spectrum) */
    const gp_grainshape *gs;   /* each grain's own spectrum around it; NULL: every grain D */
    int calibrating;           /* progress reports say "calibration" */
    size_t nmodes, np;
    unsigned outputs;
    double fill_fraction;      /* what pass A fills each cell to */
    const size_t *subset;      /* pass A on these cells only (a refill), or NULL: all */
    size_t nsubset;
    gp_specimen2d *out;
    gp_vec2 **cell_poly;       /* per cell: the seed's part (owned here) */
    size_t *cell_n;
    grain_curve *curve;        /* per cell, from pass A */
    const double *area_scale;  /* per cell area factor for pass B (NULL: 1) */
    int pass;
    atomic_size_t next;
    atomic_size_t done;
    atomic_int stop;
    /* first error wins (by lowest cell index, for determinism of the message) */
    pthread_mutex_t lock;
    size_t err_cell;
    gp_error err;
    /* per-phase CPU time summed over threads, for the timings */
    double t_fill, t_odec, t_desc;
} fill_job;

static void job_fail(fill_job *j, size_t cell, const gp_error *e)
{
    pthread_mutex_lock(&j->lock);
    if (j->err.code == GP_OK || cell < j->err_cell) {
        j->err = *e;
        j->err_cell = cell;
    }
    pthread_mutex_unlock(&j->lock);
    atomic_store(&j->stop, 1);
}

/* What a worker thread owns: the fill workspace (fill passes), the phases and contour
 * scratch, and with a spread the tools of gp_grainshape_draw and the grain's spectrum. */
typedef struct worker_ctx {
    gp_fill_workspace *ws;
    double *phases;            /* nmodes */
    gp_vec2 *scratch;          /* np */
    gp_fourier *f;             /* spread only: the star test's plan */
    double *rz;                /* spread only: np + nmodes scratch of the draw */
    double *D;                 /* spread only: the grain's spectrum (nmodes) */
} worker_ctx;

/* the cell's own random phases (stream 1 + i), the same in both passes */
static gp_status cell_phases(const fill_job *j, size_t i, double *phases, gp_error *e)
{
    gp_rng *rng = gp_rng_create(j->spec->seed, 1 + (uint64_t)i, e);
    if (!rng)
        return e->code;
    gp_status st = gp_fourier_random_phases(j->nmodes, rng_u01, rng, phases, e);
    gp_rng_destroy(rng);
    return st;
}

/* The spectrum grain i is made with: the mean, or (spread) its own draw from the cell's
 * raw phases -- the mean again when mean_only (its own could not be filled). *outcome the
 * draw's. The same bits in every pass. */
static gp_status grain_spectrum(const fill_job *j, worker_ctx *w, size_t i, int mean_only,
                                const double **D, unsigned char *outcome, gp_error *e)
{
    *D = j->D;
    *outcome = GP_GRAINSHAPE_DRAWN;
    if (!j->gs || mean_only)
        return GP_OK;
    gp_grainshape_outcome oc;
    gp_status st = gp_grainshape_draw(j->gs, i, w->phases, w->f, w->rz, w->D, &oc, e);
    *D = w->D;
    *outcome = (unsigned char)oc;
    return st;
}

/* gp_fill_cell of cell i with the grain's spectrum; with a spread, a spectrum the fill finds
 * no star-shaped phases for falls back to the mean (*mean_only set). A refill (prev: the
 * cell's grain so far, found with its own spectrum) goes on from that grain. */
static gp_status fill_grain(fill_job *j, worker_ctx *w, size_t i, const grain_curve *prev,
                            gp_fill_result *fr, int *mean_only, unsigned char *outcome,
                            gp_error *e)
{
    const double *D = j->D;
    gp_status st = cell_phases(j, i, w->phases, e);
    *mean_only = 0;
    *outcome = GP_GRAINSHAPE_DRAWN;
    gp_fill_result start;
    if (prev && !prev->mean_only) {
        memset(&start, 0, sizeof start);
        memcpy(start.phases + 2, prev->phases27, sizeof prev->phases27);
        start.rotation = prev->rotation;
    }
    if (st == GP_OK)
        st = grain_spectrum(j, w, i, 0, &D, outcome, e);
    if (st == GP_OK && j->gs)
        st = gp_fill_workspace_set_spectrum(w->ws, D, e);
    if (st == GP_OK)
        st = gp_fill_cell_from(w->ws, j->cell_poly[i], j->cell_n[i], w->phases,
                               prev && !prev->mean_only ? &start : NULL, w->scratch, fr, e);
    if (st == GP_ERR_NOT_STAR && j->gs && D != j->D) {
        *mean_only = 1;
        st = gp_fill_workspace_set_spectrum(w->ws, j->D, e);
        if (st == GP_OK)
            st = gp_fill_cell(w->ws, j->cell_poly[i], j->cell_n[i], w->phases, w->scratch, fr,
                              e);
    }
    return st;
}

/* pass A: the grain of cell i, filled to j->fill_fraction into scratch; kept when it is the
 * first grain of the cell or larger than the one it has (a refill aims higher, and where it
 * cannot get there its search may end below the grain already found) */
static void fill_one(fill_job *j, worker_ctx *w, size_t i, double *tf)
{
    gp_error e;
    gp_error_clear(&e);
    gp_grain2d *g = &j->out->grains[i];
    if (!g->contour) {
        g->cell = i;
        g->ncontour = j->np;
        g->contour = malloc(j->np * sizeof *g->contour);
        if (!g->contour) {
            gp_error_set(&e, GP_ERR_NOMEM, "out of memory");
            job_fail(j, i, &e);
            return;
        }
        g->area = -1.0;
    }
    double t0 = gp_clock_seconds();
    gp_fill_result fr;
    int mean_only;
    unsigned char outcome;
    /* a refill (a subset) starts from the cell's grain */
    const grain_curve *prev = j->subset && g->area > 0.0 ? &j->curve[i] : NULL;
    gp_status st = fill_grain(j, w, i, prev, &fr, &mean_only, &outcome, &e);
    if (st != GP_OK) {
        gp_error tmp = e;
        gp_error_set(&e, st, "cell %zu: %s", i, tmp.message);
        job_fail(j, i, &e);
        return;
    }
    if (fr.area > g->area) {
        memcpy(g->contour, w->scratch, j->np * sizeof *w->scratch);
        double cell_area = gp_voronoi_cell_area(j->vor, i);
        g->area = fr.area;
        g->cell_fraction = cell_area > 0.0 ? fr.area / cell_area : 0.0;
        g->target_met = g->cell_fraction >= j->spec->solid_fraction * (1.0 - 1e-9);
        double w, ang, len;
        g->orientation_deg = gp_min_caliper_star(g->contour, g->ncontour, &w, &ang, &len,
                                                 NULL) == GP_OK
                                 ? ang * DEG : 0.0;
        grain_curve *c = &j->curve[i];
        c->centre = fr.centre;
        c->r0 = fr.r0;
        for (size_t k = 2; k < 8; k++)
            c->phases27[k - 2] = fr.phases[k];
        c->rotation = fr.rotation;
        c->mean_only = (unsigned char)mean_only;
        c->outcome = outcome;
    }
    *tf += gp_clock_seconds() - t0;
}

/* scales grain i about its centre so that its area is multiplied by f (<= 1: it stays in
 * its cell, every contour point moving along its own ray towards the centre) */
static void grain_scale(gp_grain2d *g, grain_curve *c, double f)
{
    double k = sqrt(f);
    for (size_t p = 0; p < g->ncontour; p++) {
        g->contour[p].x = c->centre.x + k * (g->contour[p].x - c->centre.x);
        g->contour[p].y = c->centre.y + k * (g->contour[p].y - c->centre.y);
    }
    g->area *= f;
    g->cell_fraction *= f;
    c->r0 *= k;
}

static gp_status odec_one(gp_grain2d *g, gp_odec_result *od, gp_error *e)
{
    gp_status st = gp_odec_build(g->contour, g->ncontour, NULL, od, e);
    if (st != GP_OK)
        return st;
    g->ndiscs = od->ndiscs;
    g->discs = malloc((od->ndiscs ? od->ndiscs : 1) * 3 * sizeof(double));
    if (!g->discs)
        return gp_error_set(e, GP_ERR_NOMEM, "out of memory");
    for (size_t k = 0; k < od->ndiscs; k++) {
        g->discs[3 * k] = od->discs[k].x;
        g->discs[3 * k + 1] = od->discs[k].y;
        g->discs[3 * k + 2] = od->discs[k].r;
    }
    return GP_OK;
}

/* Descriptors of the grain as it goes into the DEM code: its contour and ODEC, with the
 * perimeters from the analytic curve at >= 512 points (the paper's 500-point note; gp_shape.h)
 * so that regularity does not depend on contour_points. */
static gp_status describe_one(const fill_job *j, worker_ctx *w, size_t i,
                              const gp_odec_result *od, gp_error *e)
{
    gp_grain2d *g = &j->out->grains[i];
    const grain_curve *c = &j->curve[i];
    double *phases = w->phases;
    const double *D;
    unsigned char outcome;
    gp_status st = cell_phases(j, i, phases, e);
    if (st == GP_OK) /* drawn from the raw phases, as pass A did */
        st = grain_spectrum(j, w, i, c->mean_only, &D, &outcome, e);
    if (st != GP_OK)
        return st;
    for (size_t k = 2; k < 8 && k < j->nmodes; k++)
        phases[k] = c->phases27[k - 2];
    gp_shape_curve curve = {c->centre, c->r0, D, phases, j->nmodes};
    gp_shape_result sr;
    st = gp_shape_describe_ex(g->contour, g->ncontour, NULL, od->ndiscs ? od->discs : NULL,
                              od->ndiscs, &curve, &sr, e);
    /* The fill checks r > 0 on the contour's rays only; a very elongated grain (D2 near 0.8,
     * more often with a spread) can dip below 0 between them, where the perimeters' 512
     * angles look. Its contour is still a simple polygon: take the perimeters from it. */
    if (st == GP_ERR_NOT_STAR)
        st = gp_shape_describe_ex(g->contour, g->ncontour, NULL, od->ndiscs ? od->discs : NULL,
                                  od->ndiscs, NULL, &sr, e);
    if (st != GP_OK)
        return st;
    g->descriptors.elongation = sr.elongation;
    g->descriptors.roundness = sr.roundness;
    g->descriptors.circularity = sr.circularity;
    g->descriptors.regularity = sr.regularity;
    return GP_OK;
}

/* pass B: the grain's final size, then its ODEC and descriptors */
static void finish_one(fill_job *j, worker_ctx *w, size_t i, double *to, double *td)
{
    gp_error e;
    gp_error_clear(&e);
    gp_grain2d *g = &j->out->grains[i];
    if (j->area_scale && j->area_scale[i] != 1.0)
        grain_scale(g, &j->curve[i], j->area_scale[i]);
    double t1 = gp_clock_seconds();
    gp_odec_result od;
    memset(&od, 0, sizeof od);
    gp_status st = GP_OK;
    if (j->outputs & GP_OUT2_ODEC)
        st = odec_one(g, &od, &e);
    double t2 = gp_clock_seconds();
    *to += t2 - t1;
    if (st == GP_OK && (j->outputs & GP_OUT2_DESCRIPTORS))
        st = describe_one(j, w, i, &od, &e);
    gp_odec_result_free(&od);
    *td += gp_clock_seconds() - t2;
    if (st != GP_OK)
        job_fail(j, i, &e);
}

typedef struct worker_arg {
    fill_job *job;
    gp_error err;
    double tf, to, td;
} worker_arg;

/* pass "calibrate": the descriptors of a calibration grain (ODEC built for it alone) */
static void calibrate_one(fill_job *j, worker_ctx *w, size_t i, double *td)
{
    gp_error e;
    gp_error_clear(&e);
    double t0 = gp_clock_seconds();
    gp_odec_result od;
    memset(&od, 0, sizeof od);
    gp_status st = describe_one(j, w, i, &od, &e);
    *td += gp_clock_seconds() - t0;
    if (st != GP_OK)
        job_fail(j, i, &e);
}

static void worker_free(worker_ctx *w)
{
    gp_fill_workspace_destroy(w->ws);
    gp_fourier_destroy(w->f);
    free(w->phases);
    free(w->scratch);
    free(w->rz);
    free(w->D);
}

/* the thread's tools for the job's pass; GP_ERR_NOMEM (or the fill's error) in err */
static gp_status worker_init(const fill_job *j, worker_ctx *w, gp_error *err)
{
    memset(w, 0, sizeof *w);
    if (j->pass == PASS_FILL) {
        gp_fill_params fp;
        gp_fill_params_defaults(&fp);
        fp.solid_fraction = j->fill_fraction;
        fp.D = j->D;
        fp.nmodes = j->nmodes;
        fp.contour_points = j->np;
        if (!(w->ws = gp_fill_workspace_create(&fp, err)))
            return err->code;
    }
    w->phases = malloc(j->nmodes * sizeof(double));
    w->scratch = malloc(j->np * sizeof *w->scratch);
    if (j->gs) {
        w->f = gp_fourier_create(j->np, err);
        w->rz = malloc((j->np + j->nmodes) * sizeof(double));
        w->D = malloc(j->nmodes * sizeof(double));
        if (!w->f)
            return err->code;
    }
    if (!w->phases || !w->scratch || (j->gs && (!w->rz || !w->D)))
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    return GP_OK;
}

static void *fill_worker(void *p)
{
    worker_arg *a = p;
    fill_job *j = a->job;
    worker_ctx w;
    if (worker_init(j, &w, &a->err) != GP_OK) {
        job_fail(j, 0, &a->err);
        worker_free(&w);
        return NULL;
    }
    size_t n = j->subset ? j->nsubset : j->out->ngrains;
    for (;;) {
        if (atomic_load(&j->stop))
            break;
        size_t k = atomic_fetch_add(&j->next, 1);
        if (k >= n)
            break;
        size_t i = j->subset ? j->subset[k] : k;
        if (j->pass == PASS_FILL)
            fill_one(j, &w, i, &a->tf);
        else if (j->pass == PASS_CALIBRATE)
            calibrate_one(j, &w, i, &a->td);
        else
            finish_one(j, &w, i, &a->to, &a->td);
        atomic_fetch_add(&j->done, 1);
    }
    worker_free(&w);
    return NULL;
}

/* Runs one pass over every cell on spec->threads threads; this thread relays progress (from
 * f0 to f1 of the job) and cancellation. */
static gp_status run_pass(fill_job *job, int pass, double f0, double f1, gp_progress_fn progress,
                          void *user, const volatile int *cancel, gp_error *err)
{
    size_t n = pass != PASS_FINISH && job->subset ? job->nsubset : job->out->ngrains;
    job->pass = pass;
    atomic_store(&job->next, 0);
    atomic_store(&job->done, 0);
    int nthreads = job->spec->threads > 0 ? job->spec->threads : 1;
    if ((size_t)nthreads > n)
        nthreads = (int)n;
    worker_arg *args = calloc((size_t)nthreads, sizeof *args);
    pthread_t *tids = calloc((size_t)nthreads, sizeof *tids);
    if (!args || !tids) {
        free(args);
        free(tids);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    int started = 0;
    for (int t = 0; t < nthreads; t++) {
        args[t].job = job;
        if (pthread_create(&tids[t], NULL, fill_worker, &args[t]) != 0)
            break;
        started++;
    }
    if (started == 0)
        fill_worker(&args[0]); /* no thread could start: do the work here */
    while (started > 0 && atomic_load(&job->done) < n && !atomic_load(&job->stop)) {
        struct timespec ts = {0, 50 * 1000 * 1000};
        nanosleep(&ts, NULL);
        int stop = cancelled(cancel);
        if (!stop && progress) {
            gp_progress p = {
                .phase = job->calibrating ? "calibration" : pass == PASS_FILL ? "fill" : "odec",
                .fraction = f0 + (f1 - f0) * (double)atomic_load(&job->done) / (double)n,
                .phase_fraction = (double)atomic_load(&job->done) / (double)n,
                .steps = job->out->imc_steps,
                .error = job->out->imc_error};
            stop = progress(user, &p);
        }
        if (stop) {
            gp_error e;
            gp_error_set(&e, GP_ERR_CANCELLED, "cancelled");
            job_fail(job, 0, &e);
        }
    }
    for (int t = 0; t < started; t++)
        pthread_join(tids[t], NULL);
    for (int t = 0; t < nthreads; t++) {
        /* CPU seconds summed over threads, scaled to wall time by the thread count */
        job->t_fill += args[t].tf / nthreads;
        job->t_odec += args[t].to / nthreads;
        job->t_desc += args[t].td / nthreads;
    }
    free(args);
    free(tids);
    if (job->err.code != GP_OK) {
        if (err)
            *err = job->err;
        return job->err.code;
    }
    return GP_OK;
}

/* ---------------------------------------------------------------- build */

typedef struct imc_relay {
    gp_progress_fn fn;
    void *user;
    const volatile int *cancel;
    double f0, f1;             /* the job's fraction at the IMC's start and end */
} imc_relay;

/* IMC progress -> job progress: the IMC's own fraction (log(error) from its start towards
 * log(threshold)) mapped to [f0, f1] of the job: [0.05, 0.65] for the first run, the fill's
 * 0.8 for a run that resizes the cells (grain laws, resize_cells). */
static int imc_progress(void *user, const gp_progress *p)
{
    imc_relay *r = user;
    if (cancelled(r->cancel))
        return 1;
    if (!r->fn)
        return 0;
    gp_progress q = *p;
    q.fraction = r->f0 + (r->f1 - r->f0) * p->fraction;
    q.phase_fraction = p->fraction; /* the IMC's own: log(error) towards log(threshold) */
    return r->fn(r->user, &q);
}

static gp_status check_spec(const gp_spec2d *s, gp_error *err)
{
    if (s->particles < 1 && s->size_law != GP_LAW_SIEVE)
        return gp_error_set(err, GP_ERR_INVALID, "particles must be >= 1");
    if (s->size_law == GP_LAW_SIEVE && (!s->sieve_d || !s->sieve_pass || s->nsieve < 2))
        return gp_error_set(err, GP_ERR_INVALID, "size.sieve needs at least 2 rows");
    if (!(s->anisotropy > 0.0 && s->anisotropy <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "orientation.anisotropy must be in (0, 1]");
    if (!isfinite(s->mean_deg))
        return gp_error_set(err, GP_ERR_INVALID, "orientation.mean_deg must be finite");
    if (!(s->solid_fraction > 0.0 && s->solid_fraction <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "solid_fraction must be in (0, 1]");
    if (s->contour_points < GP_FOURIER_NP_MIN)
        return gp_error_set(err, GP_ERR_INVALID, "contour_points must be >= %d",
                            GP_FOURIER_NP_MIN);
    if (!(s->imc_threshold > 0.0))
        return gp_error_set(err, GP_ERR_INVALID, "imc.threshold must be > 0");
    if (s->imc_max_steps < 0)
        return gp_error_set(err, GP_ERR_INVALID, "imc.max_steps must be >= 0");
    return GP_OK;
}

/* ---------------------------------------------------------------- laws and cell count */

static double container_area(const container *c)
{
    double a = fabs(gp_poly_area(c->outer, c->nouter));
    for (size_t h = 0; h < c->nholes; h++)
        a -= fabs(gp_poly_area(c->holes[h], c->nhole[h]));
    return a;
}

/* The law the grains are asked to follow, before any scaling: the sieve, or the parametric
 * law with mean container area / N (cells) or solid_fraction times that (grains). */
static gp_law *given_law(const gp_spec2d *s, double area, size_t n, gp_error *err)
{
    if (s->size_law == GP_LAW_SIEVE)
        return gp_law_create_sieve(s->sieve_d, s->sieve_pass, s->nsieve, err);
    double mean = area / (double)n * (s->size_of_grains ? s->solid_fraction : 1.0);
    return gp_law_create(s->size_law, mean, s->cov, err);
}

static gp_status cell_count(const gp_spec2d *s, double area, size_t *count, gp_error *err)
{
    if (!(area > 0.0) || !isfinite(area))
        return gp_error_set(err, GP_ERR_INVALID, "container has no area");
    if (s->size_law != GP_LAW_SIEVE) {
        *count = s->particles;
        return GP_OK;
    }
    gp_law *g = gp_law_create_sieve(s->sieve_d, s->sieve_pass, s->nsieve, err);
    if (!g)
        return err ? err->code : GP_ERR_INVALID;
    double nf = s->solid_fraction * area / gp_law_mean(g);
    gp_law_destroy(g);
    if (!(nf < 1e12))
        return gp_error_set(err, GP_ERR_INVALID, "the sieve needs %.3g grains", nf);
    *count = nf < 1.5 ? 1 : (size_t)llround(nf);
    return GP_OK;
}

gp_status gp_spec2d_cell_count(const gp_spec2d *spec, double *area, size_t *count, gp_error *err)
{
    container c;
    gp_status st = container_make(spec, &c, err);
    double a = st == GP_OK ? container_area(&c) : 0.0;
    container_free(&c);
    if (area)
        *area = a;
    size_t n = 0;
    if (st == GP_OK)
        st = cell_count(spec, a, &n, err);
    if (count)
        *count = n;
    return st;
}

/* Cells: the grain law scaled so that its mean is exactly the container area / N (the cells
 * tile the container); grains: the law as given, or the cell law scaled by solid_fraction. */
static gp_status make_laws(const gp_spec2d *s, double area, size_t n, gp_law **cells,
                           gp_law **grains, gp_error *err)
{
    *cells = *grains = NULL;
    gp_law *given = given_law(s, area, n, err);
    if (!given)
        return err ? err->code : GP_ERR_INVALID;
    int on_grains = s->size_of_grains || s->size_law == GP_LAW_SIEVE;
    *cells = gp_law_scaled(given, area / (double)n / gp_law_mean(given), err);
    *grains = on_grains ? given : gp_law_scaled(given, s->solid_fraction, err);
    if (!on_grains)
        gp_law_destroy(given);
    if (!*cells || !*grains) {
        gp_law_destroy(*cells);
        gp_law_destroy(*grains);
        *cells = *grains = NULL;
        return err ? err->code : GP_ERR_NOMEM;
    }
    return GP_OK;
}

gp_status gp_spec2d_laws(const gp_spec2d *spec, gp_law **cells, gp_law **grains, gp_error *err)
{
    double area;
    size_t n;
    gp_status st = gp_spec2d_cell_count(spec, &area, &n, err);
    if (st != GP_OK)
        return st;
    return make_laws(spec, area, n, cells, grains, err);
}

/* the standard deviations (n - 1) of the grains' descriptors about their means */
static void descriptor_sd(gp_specimen2d *out)
{
    size_t n = out->ngrains;
    const gp_descriptors *m = &out->descriptor_mean;
    double ss[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        const gp_descriptors *d = &out->grains[i].descriptors;
        double e[4] = {d->elongation - m->elongation, d->roundness - m->roundness,
                       d->circularity - m->circularity, d->regularity - m->regularity};
        for (int k = 0; k < 4; k++)
            ss[k] += e[k] * e[k];
    }
    double q = n > 1 ? 1.0 / (double)(n - 1) : 0.0;
    out->descriptor_sd.elongation = sqrt(ss[0] * q);
    out->descriptor_sd.roundness = sqrt(ss[1] * q);
    out->descriptor_sd.circularity = sqrt(ss[2] * q);
    out->descriptor_sd.regularity = sqrt(ss[3] * q);
}

static gp_status descriptor_stats(gp_specimen2d *out, gp_error *err)
{
    /* Classes: elongation, roundness and circularity live in [0, 1]; regularity in
     * [0, cap] with the cap of gp_shape.h for convex grains. */
    double hi[4] = {1.0, 1.0, 1.0, GP_SHAPE_REGULARITY_CAP};
    size_t n = out->ngrains;
    double sum[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        const gp_descriptors *d = &out->grains[i].descriptors;
        sum[0] += d->elongation;
        sum[1] += d->roundness;
        sum[2] += d->circularity;
        sum[3] += d->regularity;
    }
    out->descriptor_mean.elongation = n ? sum[0] / n : 0.0;
    out->descriptor_mean.roundness = n ? sum[1] / n : 0.0;
    out->descriptor_mean.circularity = n ? sum[2] / n : 0.0;
    out->descriptor_mean.regularity = n ? sum[3] / n : 0.0;
    descriptor_sd(out);
    double *v = malloc((n ? n : 1) * sizeof *v);
    if (!v)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    for (int d = 0; d < 4; d++) {
        gp_hist *h = &out->descriptor_hist[d];
        if (hist_alloc(h, DESCRIPTOR_CLASSES, 0) != 0) {
            free(v);
            return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        }
        for (size_t k = 0; k <= DESCRIPTOR_CLASSES; k++)
            h->edges[k] = hi[d] * (double)k / DESCRIPTOR_CLASSES;
        for (size_t i = 0; i < n; i++) {
            const gp_descriptors *g = &out->grains[i].descriptors;
            v[i] = d == 0 ? g->elongation : d == 1 ? g->roundness
                 : d == 2 ? g->circularity : g->regularity;
        }
        hist_fill(h, v, n);
    }
    free(v);
    return GP_OK;
}

/* ---------------------------------------------------------------- phases of the build */

typedef struct build_ctx {
    const gp_spec2d *spec;
    gp_progress_fn progress;
    void *user;
    const volatile int *cancel;
    container cont;
    size_t n;
    gp_law *cell_law, *grain_law;
    gp_voronoi *vor;
    gp_specimen2d *out;
    gp_grainshape gs;          /* the grains' spectra: out->shape's mean and cov */
} build_ctx;

static const char *error_kind_name(gp_imc_error_kind k)
{
    static const char *names[] = {"E1", "E2", "E3", "AD"};
    return k >= GP_IMC_E1 && k <= GP_IMC_AD ? names[k - 1] : "?";
}

/* The IMC on b->cell_law into b->vor: from the spec's start, or (seeds) again from the seeds of
 * an earlier run, whose steps and times it adds to. */
static gp_status run_imc(build_ctx *b, const gp_vec2 *seeds, gp_error *err)
{
    const gp_spec2d *spec = b->spec;
    gp_specimen2d *out = b->out;
    gp_imc_params ip;
    gp_imc_params_defaults(&ip);
    ip.seed = spec->seed;
    ip.law = b->cell_law;
    ip.mean_deg = spec->mean_deg;
    ip.anisotropy = spec->anisotropy;
    ip.error_kind = (int)spec->imc_error;
    ip.threshold = spec->imc_threshold;
    ip.ks_goals = spec->imc_threshold == gp_imc_default_threshold(GP_IMC_ERROR_AD); /* the default's goals only */
    ip.max_steps = spec->imc_max_steps - out->imc_steps; /* one budget for both runs */
    ip.init = spec->imc_init == GP_INIT_HALTON ? 1 : 0;
    ip.classes_size = spec->imc_classes;
    ip.classes_orient = spec->imc_classes;
    ip.threads = spec->threads;
    ip.seeds = seeds;
    imc_relay relay = {b->progress, b->user, b->cancel, seeds ? 0.8 : 0.05, seeds ? 0.8 : 0.65};
    gp_imc_report rep;
    memset(&rep, 0, sizeof rep);
    double t0 = gp_clock_seconds();
    gp_status st = gp_imc_run(b->cont.outer, b->cont.nouter, b->cont.holes, b->cont.nhole,
                              b->cont.nholes, b->n, &ip, imc_progress, &relay, b->cancel, &b->vor,
                              &rep, err);
    out->t_tessellation += rep.t_init; /* out starts zeroed: a second run adds to the first */
    out->t_imc += gp_clock_seconds() - t0 - rep.t_init;
    /* Reaching max_steps is not a failure: the specimen is built and its warnings say how far
     * the IMC got. A threshold below the integer-count floor (refused at submit by the
     * service), a cancel or bad input end the job with the IMC's message. */
    if (st == GP_ERR_NOT_CONVERGED) {
        st = GP_OK;
        gp_error_clear(err);
    }
    if (st == GP_OK) {
        out->container_area = gp_voronoi_container_area(b->vor);
        out->imc_error = rep.error;
        out->imc_steps += rep.steps;
        out->imc_runs++;
        out->imc_stop_reason = gp_imc_stop_name(rep.stop_reason);
        out->imc_error_floor = rep.floor;
        out->imc_wall_ties = rep.wall_ties;
        out->imc_error_ties = 0.5 * rep.error_orient_ties;
        out->imc_at_goals = rep.at_goals;
        out->imc_threshold = spec->imc_threshold;
        out->imc_error_kind = error_kind_name(spec->imc_error);
        hist_free(&out->size_hist);
        hist_free(&out->orientation_hist);
        if (report_hist(&out->size_hist, rep.nsize, rep.size_edges, rep.size_target,
                        rep.size_achieved, b->vor) != 0 ||
            report_hist(&out->orientation_hist, rep.norient, rep.orient_edges, rep.orient_target,
                        rep.orient_achieved, NULL) != 0)
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    gp_imc_report_free(&rep);
    return st;
}

static gp_status output_cells(build_ctx *b, gp_error *err)
{
    size_t n = b->n;
    gp_specimen2d *out = b->out;
    out->cells = calloc(n, sizeof *out->cells);
    if (!out->cells)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    out->ncells = n;
    for (size_t i = 0; i < n; i++) {
        gp_cell2d *c = &out->cells[i];
        c->seed = gp_voronoi_seed(b->vor, i);
        c->area = gp_voronoi_cell_area(b->vor, i);
        c->orientation_deg = gp_voronoi_cell_orientation(b->vor, i) * DEG;
        c->npolygons = gp_voronoi_cell_parts(b->vor, i);
        c->polygons = calloc(c->npolygons, sizeof *c->polygons);
        if (!c->polygons)
            return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        for (size_t k = 0; k < c->npolygons; k++) {
            size_t m = gp_voronoi_cell_polygon(b->vor, i, k, NULL, 0);
            c->polygons[k].pts = malloc((m ? m : 1) * sizeof(gp_vec2));
            if (!c->polygons[k].pts)
                return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            c->polygons[k].n = gp_voronoi_cell_polygon(b->vor, i, k, c->polygons[k].pts, m);
        }
    }
    return GP_OK;
}

/* Headroom of the fill when the grains themselves must follow the law: each cell is filled
 * up to solid_fraction * this (stopping there), and the rank matching below then shrinks every
 * grain to its exact share. 1.2 lets a cell a fifth above its rank's target still supply it;
 * more only costs optimiser time in cells that cannot reach it anyway. */
#define GRAIN_LAW_HEADROOM 1.2

static int cmp_index_by_value(const void *a, const void *b, void *v)
{
    const double *x = v;
    double p = x[*(const size_t *)a], q = x[*(const size_t *)b];
    if (p != q)
        return p < q ? -1 : 1;
    return *(const size_t *)a < *(const size_t *)b ? -1 : *(const size_t *)a > *(const size_t *)b;
}

/* "of": "grains": the k-th smallest reachable grain gets the k-th smallest of the law's N
 * quantiles at (2k - 1) / 2N -- the closest sample of N to the law, and the assignment that
 * asks least of every cell (any other order asks a smaller grain to give more). A grain that
 * cannot reach its quantile keeps its largest size (target_met 0; the fit report shows it).
 * Writes the area factor of each grain into scale[]. */
static gp_status rank_match(build_ctx *b, double *scale, gp_error *err)
{
    size_t n = b->n;
    gp_specimen2d *out = b->out;
    size_t *idx = malloc(n * sizeof *idx);
    double *reach = malloc(n * sizeof *reach);
    if (!idx || !reach) {
        free(idx);
        free(reach);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    for (size_t i = 0; i < n; i++) {
        idx[i] = i;
        reach[i] = out->grains[i].area;
    }
    qsort_r(idx, n, sizeof *idx, cmp_index_by_value, reach);
    for (size_t k = 0; k < n; k++) {
        size_t i = idx[k];
        double q = gp_law_quantile(b->grain_law, (2.0 * (double)k + 1.0) / (2.0 * (double)n));
        scale[i] = reach[i] > 0.0 && q < reach[i] ? q / reach[i] : 1.0;
        out->grains[i].target_met = q <= reach[i];
    }
    free(idx);
    free(reach);
    return GP_OK;
}

static gp_status grain_stats(build_ctx *b, gp_error *err)
{
    gp_specimen2d *out = b->out;
    size_t n = b->n;
    double solid = 0.0, gap = 0.0;
    size_t met = 0;
    for (size_t i = 0; i < n; i++) {
        const gp_grain2d *g = &out->grains[i];
        solid += g->area;
        met += g->target_met != 0;
        double d = fmod(fabs(g->orientation_deg - gp_voronoi_cell_orientation(b->vor, i) * DEG),
                        180.0);
        gap += d > 90.0 ? 180.0 - d : d;
    }
    out->solid_fraction = solid / out->container_area;
    out->cells_target_met = met;
    out->mean_orientation_gap_deg = n ? gap / (double)n : 0.0;
    /* grain sizes on the cell classes scaled by the target fraction */
    if (hist_copy(&out->grain_size_hist, &out->size_hist, b->spec->solid_fraction) != 0)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    double *v = malloc((n ? n : 1) * sizeof *v);
    if (!v)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n; i++)
        v[i] = out->grains[i].area;
    hist_fill(&out->grain_size_hist, v, n);
    /* the grains' orientations on the IMC's classes, against the same cosine law */
    if (hist_copy(&out->grain_orientation_hist, &out->orientation_hist, 1.0) != 0) {
        free(v);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    for (size_t i = 0; i < n; i++)
        v[i] = out->grains[i].orientation_deg >= 90.0 ? out->grains[i].orientation_deg - 180.0
                                                      : out->grains[i].orientation_deg;
    hist_fill(&out->grain_orientation_hist, v, n);
    free(v);
    if (b->spec->outputs & GP_OUT2_DESCRIPTORS)
        return descriptor_stats(out, err);
    return GP_OK;
}

static gp_status job_setup(build_ctx *b, fill_job *job, gp_error *err)
{
    const gp_spec2d *spec = b->spec;
    size_t n = b->n, np = spec->contour_points, nmodes = np / 2;
    gp_specimen2d *out = b->out;
    job->D = out->shape.spectrum; /* the mean spectrum: gp_specimen2d_shape_setup's */
    job->gs = gp_grainshape_varies(&b->gs) ? &b->gs : NULL;
    out->grains = calloc(n, sizeof *out->grains);
    job->cell_poly = calloc(n, sizeof *job->cell_poly);
    job->cell_n = calloc(n, sizeof *job->cell_n);
    job->curve = calloc(n, sizeof *job->curve);
    if (!out->grains || !job->cell_poly || !job->cell_n || !job->curve)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    out->ngrains = n;
    for (size_t i = 0; i < n; i++) {
        size_t part = gp_voronoi_cell_seed_part(b->vor, i);
        size_t m = gp_voronoi_cell_polygon(b->vor, i, part, NULL, 0);
        job->cell_poly[i] = malloc((m ? m : 1) * sizeof(gp_vec2));
        if (!job->cell_poly[i])
            return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        job->cell_n[i] = gp_voronoi_cell_polygon(b->vor, i, part, job->cell_poly[i], m);
    }
    job->spec = spec;
    job->vor = b->vor;
    job->nmodes = nmodes;
    job->np = np;
    job->outputs = spec->outputs;
    job->out = out;
    int on_grains = spec->size_of_grains || spec->size_law == GP_LAW_SIEVE;
    job->fill_fraction = on_grains ? fmin(1.0, spec->solid_fraction * GRAIN_LAW_HEADROOM)
                                   : spec->solid_fraction;
    return GP_OK;
}

static void job_free(fill_job *job, size_t n)
{
    for (size_t i = 0; job->cell_poly && i < n; i++)
        free(job->cell_poly[i]);
    free(job->cell_poly);
    free(job->cell_n);
    free(job->curve);
    job->cell_poly = NULL; /* set up again by job_setup (resize_cells) */
    job->cell_n = NULL;
    job->curve = NULL;
}

/* solid_fraction is the specimen's (api.md: stats.solid_fraction is the whole container's),
 * and some cells -- mostly slivers -- cannot hold a grain of that fraction (the paper's §5:
 * Example 1 comes out at 0.635 for 0.65, and it advises asking for a little more). So the
 * shortfall is handed to the cells that did reach their target: they are refilled, all to one
 * higher fraction chosen so that the total makes up the difference, at most REFILL_PASSES
 * times. A refill goes on from the cell's grain (gp_fill_cell_from), a small fraction of the
 * evaluations of a fresh search; a cell that cannot reach the fraction so leaves its share to
 * the next pass, whose fraction is higher. The refills reach the goal (1e-6 below the asked
 * fraction) in a few passes for about half the first fill's time again
 * (docs/design/specimen2d.md). Cells keep the larger of their grains, so a refill never loses
 * area. */
#define REFILL_PASSES 4

static gp_status refill(build_ctx *b, fill_job *job, gp_error *err)
{
    const gp_spec2d *spec = b->spec;
    size_t n = b->n, *met = malloc(n * sizeof *met);
    if (!met)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    double goal = spec->solid_fraction * b->out->container_area * (1.0 - 1e-6);
    double target = spec->solid_fraction;
    gp_status st = GP_OK;
    for (int pass = 0; pass < REFILL_PASSES && st == GP_OK; pass++) {
        double total = 0.0, met_cells = 0.0, met_grains = 0.0;
        size_t nmet = 0;
        for (size_t i = 0; i < n; i++) {
            const gp_grain2d *g = &b->out->grains[i];
            double c = gp_voronoi_cell_area(b->vor, i);
            total += g->area;
            if (g->area >= target * c * (1.0 - 1e-9)) {
                met[nmet++] = i;
                met_cells += c;
                met_grains += g->area;
            }
        }
        if (total >= goal || nmet == 0)
            break;
        target = fmin(1.0, (met_grains + goal - total) / met_cells);
        job->fill_fraction = target;
        job->subset = met;
        job->nsubset = nmet;
        st = run_pass(job, PASS_FILL, 0.8, 0.9, b->progress, b->user, b->cancel, err);
    }
    job->subset = NULL;
    free(met);
    return st;
}

/* ---------------------------------------------------------------- descriptors calibration */

/* Target descriptors: gp_shapemap_fit finds a spectrum whose random-phase grains have the
 * asked means, but the specimen's grains have their phases 2..7 chosen by the cell filling
 * and, with a spread, amplitudes that vary -- neither of which the fit models, and either of
 * which moves the means by about a tolerance (docs/design/specimen2d.md). So the spectrum is
 * calibrated on the specimen's own cells: a
 * subset of them (every cell up to CAL_MAX_CELLS, else that many spread over the indices) is
 * filled and described with the current spectrum; while a given mean is further than
 * CAL_DONE of its tolerance from its target, one defect-correction step of the table
 * (gp_specimen2d_shape_correct) moves the spectrum and the subset is measured again, at most
 * CAL_ROUNDS times; the spectrum of the best measured round is used. The cells keep their
 * phases and amplitude streams from round to round (common random numbers), so the measured
 * means move smoothly with the spectrum. Cost: one or two fills and descriptions of the
 * subset. */
#define CAL_MAX_CELLS GP_SPECIMEN2D_CALIBRATION_CELLS
#define CAL_ROUNDS 2
#define CAL_DONE 0.25

/* the calibration cells: all of them, or CAL_MAX_CELLS at indices k n / CAL_MAX_CELLS (the
 * IMC numbers its seeds in random order, so these are spread over the container) */
static size_t *cal_cells(size_t n, size_t *m)
{
    *m = n < CAL_MAX_CELLS ? n : CAL_MAX_CELLS;
    size_t *c = malloc((*m ? *m : 1) * sizeof *c);
    for (size_t k = 0; c && k < *m; k++)
        c[k] = (size_t)((double)k * (double)n / (double)*m);
    return c;
}

/* forgets the grains of cells[0 .. m) so that the next fill keeps its own */
static void cal_forget(gp_specimen2d *out, const size_t *cells, size_t m)
{
    for (size_t k = 0; k < m; k++) {
        out->grains[cells[k]].area = -1.0;
        memset(&out->grains[cells[k]].descriptors, 0, sizeof(gp_descriptors));
    }
}

/* fills and describes the subset with the current spectrum; their mean descriptors in mean */
static gp_status cal_measure(build_ctx *b, fill_job *job, const size_t *cells, size_t m,
                             double *mean, gp_error *err)
{
    cal_forget(b->out, cells, m);
    job->subset = cells;
    job->nsubset = m;
    gp_status st = run_pass(job, PASS_FILL, 0.65, 0.65, b->progress, b->user, b->cancel, err);
    if (st == GP_OK)
        st = run_pass(job, PASS_CALIBRATE, 0.65, 0.65, b->progress, b->user, b->cancel, err);
    double sum[4] = {0, 0, 0, 0};
    for (size_t k = 0; st == GP_OK && k < m; k++) {
        const gp_descriptors *d = &b->out->grains[cells[k]].descriptors;
        sum[0] += d->elongation;
        sum[1] += d->roundness;
        sum[2] += d->circularity;
        sum[3] += d->regularity;
    }
    for (int k = 0; k < 4; k++)
        mean[k] = sum[k] / (double)(m ? m : 1);
    return st;
}

/* every given mean within CAL_DONE of its tolerance */
static int cal_done(const gp_shape_used *u, const double *m)
{
    for (int k = 0; k < GP_SHAPEMAP_NDESC; k++)
        if ((u->targets & GP_SHAPEMAP_BIT(k)) &&
            fabs(m[k] - u->target[k]) > CAL_DONE * gp_shapemap_tolerance(k))
            return 0;
    return 1;
}

/* the rounds: measure, keep the best, correct; leaves the best spectrum in b->out->shape */
static gp_status cal_rounds(build_ctx *b, fill_job *job, const size_t *cells, size_t m,
                            gp_error *err)
{
    gp_shape_used *u = &b->out->shape;
    double best_p[3] = {u->D2, u->D3, u->D8}, best_f = HUGE_VAL, mean[4];
    gp_status st = GP_OK;
    for (int round = 0; round < CAL_ROUNDS && st == GP_OK; round++) {
        st = cal_measure(b, job, cells, m, mean, err);
        if (st != GP_OK)
            break;
        u->calibration_rounds++;
        double f = gp_specimen2d_shape_misfit(u, mean, NULL);
        if (f < best_f) {
            best_f = f;
            best_p[0] = u->D2, best_p[1] = u->D3, best_p[2] = u->D8;
            memcpy(u->calibrated, mean, sizeof u->calibrated);
        }
        if (cal_done(u, mean) || round + 1 == CAL_ROUNDS)
            break;
        double next[3];
        if (gp_specimen2d_shape_correct(u, mean, next, err) != GP_OK) {
            gp_error_clear(err); /* the table cannot say where to go: keep what was measured */
            break;
        }
        st = gp_specimen2d_shape_set_d(u, next, err);
    }
    if (st == GP_OK)
        st = gp_specimen2d_shape_set_d(u, best_p, err);
    gp_specimen2d_shape_misfit(u, u->calibrated, &u->missed);
    u->calibration_grains = m;
    return st;
}

/* the calibration of the descriptors form (above), in the fill job before its first pass;
 * its time is the shape's, not the fill's */
static gp_status calibrate(build_ctx *b, fill_job *job, gp_error *err)
{
    if (b->out->shape.form != GP_SHAPE_FORM_DESCRIPTORS)
        return GP_OK;
    size_t m;
    size_t *cells = cal_cells(b->n, &m);
    if (!cells)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    double t0 = gp_clock_seconds(), tf = job->t_fill, td = job->t_desc;
    job->calibrating = 1;
    gp_status st = cal_rounds(b, job, cells, m, err);
    job->calibrating = 0;
    cal_forget(b->out, cells, m);
    job->subset = NULL;
    job->nsubset = 0;
    free(cells);
    job->t_fill = tf;
    job->t_desc = td;
    b->out->t_shape += gp_clock_seconds() - t0;
    return st;
}

/* the grains' spectrum draws: how many were redrawn or clipped (gp_grainshape.h) */
static void count_draws(build_ctx *b, const fill_job *job)
{
    for (size_t i = 0; job->gs && i < b->n; i++) {
        b->out->shape.grains_redrawn += job->curve[i].outcome != GP_GRAINSHAPE_DRAWN;
        b->out->shape.grains_clipped += job->curve[i].outcome == GP_GRAINSHAPE_CLIPPED ||
                                        job->curve[i].mean_only;
    }
}

/* ---------------------------------------------------------------- cells sized for their grains */

/* Below this fraction of its KS critical value the grain law is met well enough after pass A
 * that the cells are not sized again. */
#define GRAIN_LAW_KS_GOAL 0.5
/* a second IMC only when the prediction gains at least this factor */
#define RESIZE_GAIN 0.8

static int cmp_double_asc(const void *a, const void *b)
{
    double p = *(const double *)a, q = *(const double *)b;
    return p < q ? -1 : p > q;
}

/* How far from the law the grains rank matching makes from the capacities cap[] would be
 * (cap sorted here, then overwritten with the matched areas: the k-th smallest is
 * min(cap_(k), q[k])): the larger of the KS distance to the law by number and the KS distance
 * by mass (area-weighted) to the ideal sample q. By number alone a few largest grains left
 * short cost a few N-ths; by mass they are the sieve's passing at its top, which cells chosen
 * by number only miss by points (docs/design/specimen2d.md). */
static double matched_miss(double *cap, const double *q, size_t n, const gp_law *law)
{
    qsort(cap, n, sizeof *cap, cmp_double_asc);
    double sa = 0.0, sq = 0.0;
    for (size_t k = 0; k < n; k++) {
        cap[k] = fmin(cap[k], q[k]);
        sa += cap[k];
        sq += q[k];
    }
    double d = gp_fit_ks_sorted(cap, n, law);
    if (!(sa > 0.0))
        return 1.0; /* no grain at all: as far as can be */
    double ca = 0.0, cq = 0.0;
    for (size_t i = 0, j = 0; i < n || j < n;) {
        double t = j >= n || (i < n && cap[i] < q[j]) ? cap[i] : q[j];
        while (i < n && cap[i] <= t)
            ca += cap[i++];
        while (j < n && q[j] <= t)
            cq += q[j++];
        d = fmax(d, fabs(ca / sa - cq / sq));
    }
    return d;
}

/* What pass A taught about the cells: each one's rank by area (as a probability) and the
 * fraction of its area its largest grain (up to the headroom) covers. */
typedef struct sizing {
    size_t n;
    double *q;                 /* the grain law's quantiles at (2k + 1) / 2n */
    double *rank;
    double *hold;
    double *work;
} sizing;

static void sizing_free(sizing *z)
{
    free(z->q);
    free(z->rank);
    free(z->hold);
    free(z->work);
}

static gp_status sizing_measure(build_ctx *b, sizing *z, gp_error *err)
{
    size_t n = b->n;
    z->n = n;
    z->q = malloc(n * sizeof *z->q);
    z->rank = malloc(n * sizeof *z->rank);
    z->hold = malloc(n * sizeof *z->hold);
    z->work = malloc(n * sizeof *z->work);
    size_t *idx = malloc(n * sizeof *idx);
    if (!z->q || !z->rank || !z->hold || !z->work || !idx) {
        free(idx);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    for (size_t i = 0; i < n; i++) {
        idx[i] = i;
        z->work[i] = gp_voronoi_cell_area(b->vor, i);
        z->hold[i] = z->work[i] > 0 ? b->out->grains[i].area / z->work[i] : 0.0;
        z->q[i] = gp_law_quantile(b->grain_law, (2.0 * (double)i + 1.0) / (2.0 * (double)n));
    }
    qsort_r(idx, n, sizeof *idx, cmp_index_by_value, z->work);
    for (size_t r = 0; r < n; r++)
        z->rank[idx[r]] = ((double)r + 0.5) / (double)n;
    free(idx);
    return GP_OK;
}

/* The miss (matched_miss) predicted if the cells followed `cells` instead: cell i keeps its
 * rank and the fraction it held, so its capacity becomes cells' quantile at its rank times
 * that. */
static double predicted_miss(sizing *z, const gp_law *cells, const gp_law *grains)
{
    for (size_t i = 0; i < z->n; i++)
        z->work[i] = gp_law_quantile(cells, z->rank[i]) * z->hold[i];
    return matched_miss(z->work, z->q, z->n, grains);
}

/* The power kappa of the cell law (gp_law_powered, the same mean) with the least predicted
 * miss: a grid of 0.05 over [0.5, 1], then steps of 0.025 and 0.0125 around the best.
 * *miss: that prediction; *kappa 1 when nothing beats the law as it is. */
static gp_status best_power(build_ctx *b, sizing *z, double *kappa, double *miss,
                            gp_error *err)
{
    double mean = gp_law_mean(b->cell_law), best = 1.0;
    *miss = predicted_miss(z, b->cell_law, b->grain_law);
    double step = 0.05;
    for (int level = 0; level < 3; level++, step /= 2) {
        double centre = best;
        for (int j = level ? -1 : 1; j <= (level ? 1 : 10); j += level ? 2 : 1) {
            double k = level ? centre + j * step : 1.0 - j * step;
            gp_law *l = gp_law_powered(b->cell_law, k, mean, err);
            if (!l)
                return err ? err->code : GP_ERR_NOMEM;
            double d = predicted_miss(z, l, b->grain_law);
            gp_law_destroy(l);
            if (d < *miss) {
                *miss = d;
                best = k;
            }
        }
    }
    *kappa = best;
    return GP_OK;
}

/* The grains pass A made, dropped before the cells are made again */
static void grains_reset(gp_specimen2d *out)
{
    for (size_t i = 0; i < out->ngrains; i++) {
        free(out->grains[i].contour);
        free(out->grains[i].discs);
    }
    free(out->grains);
    out->grains = NULL;
    out->ngrains = 0;
}

/* A law of grains asks each cell for a grain of its rank's size, but small cells hold less of
 * their area than large ones (fewer sides: 4.9 on average in the smallest tenth at N = 10,000,
 * against 7.4 in the largest; a triangle holds at most 0.60 of itself as a disc): cells drawn
 * to the grain law scaled by 1 / F_S leave the smallest grains short, a KS distance of ~0.02
 * whatever N (10,000 and 100,000 grains, COV 0.5: 1.5 and 4.3 times the critical value).
 * So after pass A, when the matched grains miss GRAIN_LAW_KS_GOAL of the critical value, the
 * cell law is drawn together (gp_law_powered: kappa < 1 keeps the mean and narrows the
 * spread, giving the small cells room) by the kappa that pass A's own cells predict best,
 * the IMC runs again from the seeds it ended on (with what is left of the spec's max_steps),
 * and pass A fills the new cells. The new cells are the specimen whatever they give (the fit
 * report measures it); no third round. */
static gp_status resize_cells(build_ctx *b, fill_job *job, gp_error *err)
{
    if (b->n < 2)
        return GP_OK;
    sizing z;
    memset(&z, 0, sizeof z);
    gp_status st = sizing_measure(b, &z, err);
    double now = 0.0, kappa = 1.0, pred = 0.0;
    if (st == GP_OK) {
        for (size_t i = 0; i < b->n; i++)
            z.work[i] = b->out->grains[i].area;
        now = matched_miss(z.work, z.q, b->n, b->grain_law);
        b->out->grain_law_miss = now;
        if (now > GRAIN_LAW_KS_GOAL * gp_fit_ks_critical(b->n))
            st = best_power(b, &z, &kappa, &pred, err);
    }
    sizing_free(&z);
    if (st != GP_OK || kappa == 1.0 || !(pred < RESIZE_GAIN * now))
        return st;
    /* the spec's max_steps bounds both IMC runs together: none left, nothing to gain */
    if (b->out->imc_steps >= b->spec->imc_max_steps) {
        b->out->cells_resize_blocked = 1;
        return GP_OK;
    }
    gp_law *cells = gp_law_powered(b->cell_law, kappa, gp_law_mean(b->cell_law), err);
    size_t n = b->n;
    gp_vec2 *seeds = cells ? malloc(n * sizeof *seeds) : NULL;
    if (!seeds) {
        gp_law_destroy(cells);
        return cells || !err ? gp_error_set(err, GP_ERR_NOMEM, "out of memory") : err->code;
    }
    for (size_t i = 0; i < n; i++)
        seeds[i] = gp_voronoi_seed(b->vor, i);
    gp_law_destroy(b->cell_law);
    b->cell_law = cells;
    b->out->cell_law_power = kappa;
    job_free(job, n);
    grains_reset(b->out);
    gp_voronoi_destroy(b->vor);
    b->vor = NULL;
    long first = b->out->imc_steps;
    st = run_imc(b, seeds, err);
    b->out->imc_steps_resize = b->out->imc_steps - first;
    free(seeds);
    if (st == GP_OK)
        st = job_setup(b, job, err);
    if (st == GP_OK)
        st = run_pass(job, PASS_FILL, 0.8, 0.8, b->progress, b->user, b->cancel, err);
    return st;
}

/* Filling (pass A), the grain law's rank matching, then ODEC and descriptors (pass B). */
static gp_status build_grains(build_ctx *b, gp_error *err)
{
    fill_job job;
    memset(&job, 0, sizeof job);
    pthread_mutex_init(&job.lock, NULL);
    double *scale = NULL;
    gp_status st = job_setup(b, &job, err);
    if (st == GP_OK)
        st = calibrate(b, &job, err);
    if (st == GP_OK)
        st = run_pass(&job, PASS_FILL, 0.65, 0.8, b->progress, b->user, b->cancel, err);
    int on_grains = b->spec->size_of_grains || b->spec->size_law == GP_LAW_SIEVE;
    if (st == GP_OK && !on_grains)
        st = refill(b, &job, err);
    if (st == GP_OK && on_grains)
        st = resize_cells(b, &job, err);
    if (st == GP_OK && on_grains) {
        scale = malloc(b->n * sizeof *scale);
        st = scale ? rank_match(b, scale, err) : gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        job.area_scale = scale;
    }
    if (st == GP_OK && (scale || (b->spec->outputs & (GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS))))
        st = run_pass(&job, PASS_FINISH, 0.9, 1.0, b->progress, b->user, b->cancel, err);
    b->out->t_fill = job.t_fill;
    b->out->t_odec = job.t_odec;
    b->out->t_descriptors = job.t_desc;
    count_draws(b, &job);
    free(scale);
    job_free(&job, b->n);
    pthread_mutex_destroy(&job.lock);
    if (st == GP_OK)
        st = grain_stats(b, err);
    return st;
}

/* ---------------------------------------------------------------- fit report and warnings */

#define FIT_CURVE_POINTS 64

/* GP_ERR_CANCELLED once the caller's flag is up: between the steps that take up to a second at
 * 10^6 cells and do not poll it themselves */
static gp_status check_cancel(const build_ctx *b, gp_error *err)
{
    return cancelled(b->cancel) ? gp_error_set(err, GP_ERR_CANCELLED, "cancelled") : GP_OK;
}

static gp_status fit_report(build_ctx *b, gp_error *err)
{
    gp_specimen2d *out = b->out;
    size_t n = b->n, ng = out->ngrains;
    double *v = malloc(n * sizeof *v);
    if (!v)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    gp_fit2d *f = &out->fit;
    for (size_t i = 0; i < n; i++)
        v[i] = gp_voronoi_cell_area(b->vor, i);
    /* each measure takes up to ~0.7 s at 10^6 cells: the cancel flag is looked at between them */
    gp_status st = gp_fit_area_measure(v, n, b->cell_law, FIT_CURVE_POINTS, &f->cell_area, err);
    if (st == GP_OK)
        st = check_cancel(b, err);
    for (size_t i = 0; i < n && st == GP_OK; i++)
        v[i] = gp_voronoi_cell_orientation(b->vor, i) * DEG;
    if (st == GP_OK)
        st = gp_fit_orient_measure(v, n, b->spec->mean_deg, b->spec->anisotropy,
                                   &f->cell_orientation, err);
    if (st == GP_OK && ng > 0) {
        for (size_t i = 0; i < ng; i++)
            v[i] = out->grains[i].area;
        st = check_cancel(b, err);
        if (st == GP_OK)
            st = gp_fit_area_measure(v, ng, b->grain_law, FIT_CURVE_POINTS, &f->grain_area, err);
        if (st == GP_OK && b->spec->size_law == GP_LAW_SIEVE)
            st = gp_fit_passing_measure(v, ng, b->grain_law, &f->passing, err);
        for (size_t i = 0; i < ng && st == GP_OK; i++)
            v[i] = out->grains[i].orientation_deg;
        if (st == GP_OK)
            st = check_cancel(b, err);
        if (st == GP_OK)
            st = gp_fit_orient_measure(v, ng, b->spec->mean_deg, b->spec->anisotropy,
                                       &f->grain_orientation, err);
    }
    free(v);
    return st;
}

static void warn(gp_specimen2d *out, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void warn(gp_specimen2d *out, const char *fmt, ...)
{
    char buf[2 * GP_ERROR_MESSAGE_MAX]; /* the IMC's can name the run, the goals and the walls */
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    char **w = realloc(out->warnings, (out->nwarnings + 1) * sizeof *w);
    if (!w)
        return; /* a warning lost to memory exhaustion; the numbers are still in the stats */
    out->warnings = w;
    if ((w[out->nwarnings] = strdup(buf)))
        out->nwarnings++;
}

static void warn_fit_area(gp_specimen2d *out, const char *what, const gp_fit_area *f)
{
    if (f->present && f->ks > f->ks_critical)
        warn(out, "%s areas: KS distance %.4f to the %s law is above its 5 %% critical value "
                  "%.4f (mean %.4g for %.4g, COV %.3f for %.3f)", what, f->ks, gp_law_name(f->law),
             f->ks_critical, f->mean, f->target_mean, f->cov, f->target_cov);
}

/* The IMC stopped above its threshold. Near-regular cells (COV 0.1 and less) against a long
 * straight wall have their thinnest side across it and share its direction, a tie that no move
 * undoes without spoiling the areas (a 256-gon reaches the threshold where the square stalls:
 * docs/design/imc.md); when the ties carry a quarter of the error or more the warning says so.
 * A default run that stalled with its cells within the KS goals (gp_imc.h "Stopping") says so,
 * with their KS distances as measured on the cells. */
static void warn_imc(gp_specimen2d *out)
{
    char goals[200] = "";
    const gp_fit_area *a = &out->fit.cell_area;
    const gp_fit_orient *o = &out->fit.cell_orientation;
    if (out->imc_at_goals && a->present && o->present && a->ks_critical > 0)
        snprintf(goals, sizeof goals, ", falling slowly with the cells within its KS goals "
                 "(areas %.3f, orientations %.3f of critical)",
                 a->ks / a->ks_critical, o->ks / o->ks_critical);
    if (out->imc_error_ties >= 0.25 * out->imc_error)
        warn(out, "imc: the error %.4g (%s) is above the threshold %.4g: the run stopped (%s) "
                  "after %ld steps%s; %zu cells have their thinnest side along a straight wall and "
                  "share its direction (%.4g of the error): near-regular cells against long "
                  "straight walls do",
             out->imc_error, out->imc_error_kind, out->imc_threshold, out->imc_stop_reason,
             out->imc_steps, goals, out->imc_wall_ties, out->imc_error_ties);
    else
        warn(out, "imc: the error %.4g (%s) is above the threshold %.4g: the run stopped (%s) "
                  "after %ld steps%s", out->imc_error, out->imc_error_kind, out->imc_threshold,
             out->imc_stop_reason, out->imc_steps, goals);
}

static void warn_fit_orient(gp_specimen2d *out, const char *what, const gp_fit_orient *f)
{
    if (f->present && f->ks > f->ks_critical)
        warn(out, "%s orientations: KS distance %.4f to the cosine law is above its 5 %% "
                  "critical value %.4f", what, f->ks, f->ks_critical);
}

/* Grains whose cells follow the orientation law but who do not: a grain's orientation is its
 * own shape's thinnest direction, which the fill turns towards its cell's but need not reach
 * (a rounded grain's is ill-defined); the mean gap says by how much they differ. */
static void warn_grain_orient(gp_specimen2d *out)
{
    const gp_fit_orient *g = &out->fit.grain_orientation, *c = &out->fit.cell_orientation;
    if (!g->present || g->ks <= g->ks_critical) return;
    if (c->present && c->ks <= c->ks_critical)
        warn(out, "grain orientations: KS distance %.4f to the cosine law is above its 5 %% "
                  "critical value %.4f while the cells' is %.4f: a grain's own thinnest direction "
                  "differs from its cell's by %.1f deg on average",
             g->ks, g->ks_critical, c->ks, out->mean_orientation_gap_deg);
    else
        warn_fit_orient(out, "grain", g);
}

/* The target descriptors missed by more than their tolerance: by the specimen's grains when
 * they were described, else by the calibration grains (or the fit's sample); and the grains
 * whose drawn spectrum had to be clipped. */
static void warn_shape(build_ctx *b)
{
    gp_specimen2d *out = b->out;
    const gp_shape_used *u = &out->shape;
    if (u->form == GP_SHAPE_FORM_DESCRIPTORS) {
        const gp_descriptors *a = &out->descriptor_mean;
        int grains = (b->spec->outputs & GP_OUT2_DESCRIPTORS) && out->ngrains > 0;
        double all[4] = {a->elongation, a->roundness, a->circularity, a->regularity};
        const double *m = grains ? all : u->calibration_grains ? u->calibrated : u->predicted;
        for (int k = 0; k < GP_SHAPEMAP_NDESC; k++)
            if ((u->targets & GP_SHAPEMAP_BIT(k)) &&
                fabs(m[k] - u->target[k]) > gp_shapemap_tolerance(k))
                warn(out, "shape: mean %s %.4f (%s) for a target of %.4g (tolerance %g)",
                     gp_shapemap_name(k), m[k], grains ? "the grains" : u->calibration_grains
                     ? "the calibration grains" : "the fit's sample", u->target[k],
                     gp_shapemap_tolerance(k));
    }
    if (u->grains_clipped > 0)
        warn(out, "shape: %zu of %zu grains drew no star-shaped spectrum in %d tries and were "
                  "pulled toward the mean spectrum (spread)", u->grains_clipped, out->ngrains,
             GP_GRAINSHAPE_TRIES);
}

/* Every target not reached, with how close it came: a run that stops short is a valid
 * specimen that says so. */
static void collect_warnings(build_ctx *b)
{
    gp_specimen2d *out = b->out;
    const gp_spec2d *spec = b->spec;
    if (b->n == 1)
        warn(out, "1 cell: the tessellation is the container itself; its area and orientation "
                  "cannot be shaped");
    else if (out->imc_error > out->imc_threshold)
        warn_imc(out);
    warn_fit_area(out, "cell", &out->fit.cell_area);
    warn_fit_area(out, "grain", &out->fit.grain_area);
    if (out->cells_resize_blocked)
        warn(out, "grain areas: the cells were not resized for their grains: the first IMC run "
                  "used all of imc.max_steps (%ld%s); a larger max_steps lets them be",
             spec->imc_max_steps, spec->imc_max_steps_default ? ", the default" : "");
    warn_fit_orient(out, "cell", &out->fit.cell_orientation);
    warn_grain_orient(out);
    if (out->fit.passing.n > 0 && out->fit.passing.max_error_pp > 3.0)
        warn(out, "sieve: passing by mass off by up to %.1f percentage points",
             out->fit.passing.max_error_pp);
    if (out->ngrains > 0 && out->solid_fraction < 0.98 * spec->solid_fraction)
        warn(out, "fill: solid fraction %.4f for a target of %.4f (%zu of %zu grains reached "
                  "their size)", out->solid_fraction, spec->solid_fraction, out->cells_target_met,
             out->ngrains);
    warn_shape(b);
}

/* ---------------------------------------------------------------- build */

/* The grains' mean spectrum and spread (gp_specimen2d_shape.c), before the tessellation so that
 * a shape that cannot be made fails at once. Only the forms that compute something (descriptors,
 * outlines) report the phase "shape". */
static gp_status shape_step(build_ctx *b, gp_error *err)
{
    const gp_spec2d *spec = b->spec;
    gp_specimen2d *out = b->out;
    int work = !spec->has_spectrum && (spec->shape_form == GP_SHAPE_FORM_DESCRIPTORS ||
                                       spec->shape_form == GP_SHAPE_FORM_OUTLINES);
    if (work && b->progress) {
        gp_progress p = {.phase = "shape"};
        if (b->progress(b->user, &p))
            return gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
    }
    double t0 = gp_clock_seconds();
    gp_status st = gp_specimen2d_shape_setup(spec, spec->contour_points / 2, b->cancel,
                                             work ? b->progress : NULL, b->user, &out->shape,
                                             err);
    out->t_shape = gp_clock_seconds() - t0;
    b->gs = (gp_grainshape){out->shape.nmodes, out->shape.spectrum, out->shape.cov, spec->seed};
    if (st == GP_OK && work && b->progress) {
        gp_progress p = {.phase = "shape", .fraction = 0.0, .phase_fraction = 1.0};
        if (b->progress(b->user, &p))
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
    }
    return st;
}

static gp_status build_steps(build_ctx *b, gp_error *err)
{
    const gp_spec2d *spec = b->spec;
    gp_status st = container_make(spec, &b->cont, err);
    double area = st == GP_OK ? container_area(&b->cont) : 0.0;
    if (st == GP_OK)
        st = cell_count(spec, area, &b->n, err);
    if (st == GP_OK)
        st = make_laws(spec, area, b->n, &b->cell_law, &b->grain_law, err);
    if (st == GP_OK)
        st = shape_step(b, err);
    if (st == GP_OK && b->progress) {
        gp_progress p = {.phase = "tessellation"};
        if (b->progress(b->user, &p) || cancelled(b->cancel))
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
    }
    if (st == GP_OK)
        st = run_imc(b, NULL, err);
    if (st == GP_OK)
        st = check_cancel(b, err);
    if (st == GP_OK && (spec->outputs & (GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS)))
        st = build_grains(b, err); /* a grain law may run the IMC again (resize_cells) */
    if (st == GP_OK)
        st = check_cancel(b, err);
    if (st == GP_OK && (spec->outputs & GP_OUT2_CELLS))
        st = output_cells(b, err);
    if (st == GP_OK)
        st = check_cancel(b, err);
    if (st == GP_OK)
        st = fit_report(b, err);
    if (st == GP_OK)
        collect_warnings(b);
    return st;
}

gp_status gp_specimen2d_build(const gp_spec2d *spec, gp_progress_fn progress, void *user,
                              const volatile int *cancel, gp_specimen2d **outp, gp_error *err)
{
    if (!spec || !outp)
        return gp_error_set(err, GP_ERR_INVALID, "specimen2d: NULL argument");
    *outp = NULL;
    gp_status st = check_spec(spec, err);
    if (st != GP_OK)
        return st;
    double t_start = gp_clock_seconds();
    build_ctx b;
    memset(&b, 0, sizeof b);
    b.spec = spec;
    b.progress = progress;
    b.user = user;
    b.cancel = cancel;
    b.out = calloc(1, sizeof *b.out);
    if (!b.out)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    b.out->cell_law_power = 1.0;
    st = build_steps(&b, err);
    gp_voronoi_destroy(b.vor);
    container_free(&b.cont);
    gp_law_destroy(b.cell_law);
    gp_law_destroy(b.grain_law);
    if (st != GP_OK) {
        gp_specimen2d_destroy(b.out);
        return st;
    }
    b.out->t_total = gp_clock_seconds() - t_start;
    if (progress) {
        gp_progress p = {.phase = "done", .fraction = 1.0, .phase_fraction = 1.0,
                         .steps = b.out->imc_steps,
                         .error = b.out->imc_error};
        progress(user, &p);
    }
    *outp = b.out;
    return GP_OK;
}

void gp_specimen2d_destroy(gp_specimen2d *s)
{
    if (!s)
        return;
    for (size_t i = 0; i < s->ngrains; i++) {
        free(s->grains[i].contour);
        free(s->grains[i].discs);
    }
    free(s->grains);
    for (size_t i = 0; i < s->ncells; i++) {
        for (size_t k = 0; s->cells[i].polygons && k < s->cells[i].npolygons; k++)
            free(s->cells[i].polygons[k].pts);
        free(s->cells[i].polygons);
    }
    free(s->cells);
    gp_specimen2d_shape_free(&s->shape);
    hist_free(&s->size_hist);
    hist_free(&s->grain_size_hist);
    hist_free(&s->orientation_hist);
    hist_free(&s->grain_orientation_hist);
    for (int d = 0; d < 4; d++)
        hist_free(&s->descriptor_hist[d]);
    gp_fit_area_free(&s->fit.cell_area);
    gp_fit_area_free(&s->fit.grain_area);
    gp_fit_passing_free(&s->fit.passing);
    for (size_t i = 0; i < s->nwarnings; i++)
        free(s->warnings[i]);
    free(s->warnings);
    free(s);
}
