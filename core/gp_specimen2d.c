/* gp_specimen2d.c -- the 2D pipeline: container -> IMC tessellation -> filling -> ODEC ->
 * descriptors -> statistics. See gp_specimen2d.h.
 *
 * Determinism: every random draw is tied to what it is for, not to the order of work. The
 * IMC uses stream 0 of the spec's seed; cell i draws its grain's random phases from stream
 * 1 + i. Cells are filled by a pool of threads that take cells from a shared counter and
 * write results by cell index, so the specimen is the same bits whatever the thread count.
 */
#include "gp_specimen2d.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gp_fill.h"
#include "gp_fourier.h"
#include "gp_imc.h"
#include "gp_odec.h"
#include "gp_rng.h"
#include "gp_shape.h"
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
    s->cov = 0.5;
    s->mean_deg = 0.0;
    s->anisotropy = 1.0;
    s->D2 = 0.1;
    s->D3 = 0.05;
    s->D8 = 0.02;
    s->alpha = -2.0;
    s->beta = -2.0;
    s->solid_fraction = 0.65;
    s->imc_error = GP_IMC_E3;
    s->imc_threshold = 0.002;
    s->imc_max_steps = 1000000;
    s->imc_init = GP_INIT_UNIFORM;
    s->imc_classes = 0;
    s->contour_points = 128;
    s->outputs = GP_OUT_GRAINS;
    s->threads = 1;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
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

typedef struct fill_job {
    const gp_spec2d *spec;
    const gp_voronoi *vor;
    const double *D;
    size_t nmodes, np;
    unsigned outputs;
    gp_specimen2d *out;
    gp_vec2 **cell_poly;       /* per cell: the seed's part (owned here) */
    size_t *cell_n;
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

static void fill_one(fill_job *j, gp_fill_workspace *ws, double *phases, size_t i,
                     double *tf, double *to, double *td)
{
    gp_error e;
    gp_error_clear(&e);
    gp_grain2d *g = &j->out->grains[i];
    g->cell = i;
    g->ncontour = j->np;
    g->contour = malloc(j->np * sizeof *g->contour);
    if (!g->contour) {
        gp_error_set(&e, GP_ERR_NOMEM, "out of memory");
        job_fail(j, i, &e);
        return;
    }
    double t0 = now_s();
    gp_rng *rng = gp_rng_create(j->spec->seed, 1 + (uint64_t)i, &e);
    if (!rng) {
        job_fail(j, i, &e);
        return;
    }
    gp_status st = gp_fourier_random_phases(j->nmodes, rng_u01, rng, phases, &e);
    gp_rng_destroy(rng);
    gp_fill_result fr;
    if (st == GP_OK)
        st = gp_fill_cell(ws, j->cell_poly[i], j->cell_n[i], phases, g->contour, &fr, &e);
    if (st != GP_OK) {
        gp_error tmp = e;
        gp_error_set(&e, st, "cell %zu: %s", i, tmp.message);
        job_fail(j, i, &e);
        return;
    }
    g->area = fr.area;
    g->cell_fraction = gp_voronoi_cell_area(j->vor, i) > 0.0
                           ? fr.area / gp_voronoi_cell_area(j->vor, i) : 0.0;
    g->target_met = fr.target_met;
    double w, ang, len;
    g->orientation_deg = gp_min_caliper(g->contour, g->ncontour, &w, &ang, &len, NULL) == GP_OK
                             ? ang * DEG : 0.0;
    double t1 = now_s();
    *tf += t1 - t0;

    /* the optimised phases replace the random ones for modes 2..7 */
    for (size_t k = 2; k < 8 && k < j->nmodes; k++)
        phases[k] = fr.phases[k];

    gp_odec_result od;
    memset(&od, 0, sizeof od);
    if (j->outputs & GP_OUT_ODEC) {
        st = gp_odec_build(g->contour, g->ncontour, NULL, &od, &e);
        if (st != GP_OK) {
            job_fail(j, i, &e);
            return;
        }
        g->ndiscs = od.ndiscs;
        g->discs = malloc((od.ndiscs ? od.ndiscs : 1) * 3 * sizeof(double));
        if (!g->discs) {
            gp_odec_result_free(&od);
            gp_error_set(&e, GP_ERR_NOMEM, "out of memory");
            job_fail(j, i, &e);
            return;
        }
        for (size_t k = 0; k < od.ndiscs; k++) {
            g->discs[3 * k] = od.discs[k].x;
            g->discs[3 * k + 1] = od.discs[k].y;
            g->discs[3 * k + 2] = od.discs[k].r;
        }
    }
    double t2 = now_s();
    *to += t2 - t1;

    if (j->outputs & GP_OUT_DESCRIPTORS) {
        /* Descriptors of the grain as it goes into the DEM code: its contour and ODEC, with
         * the perimeters from the analytic curve at >= 512 points (the paper's 500-point
         * note; gp_shape.h) so that regularity does not depend on contour_points. */
        gp_shape_curve curve = {fr.centre, fr.r0, j->D, phases, j->nmodes};
        gp_shape_result sr;
        st = gp_shape_describe_ex(g->contour, g->ncontour, NULL, od.ndiscs ? od.discs : NULL,
                                  od.ndiscs, &curve, &sr, &e);
        if (st != GP_OK) {
            gp_odec_result_free(&od);
            job_fail(j, i, &e);
            return;
        }
        g->descriptors.elongation = sr.elongation;
        g->descriptors.roundness = sr.roundness;
        g->descriptors.circularity = sr.circularity;
        g->descriptors.regularity = sr.regularity;
    }
    gp_odec_result_free(&od);
    *td += now_s() - t2;
}

typedef struct worker_arg {
    fill_job *job;
    gp_error err;
    double tf, to, td;
} worker_arg;

static void *fill_worker(void *p)
{
    worker_arg *a = p;
    fill_job *j = a->job;
    gp_fill_params fp;
    gp_fill_params_defaults(&fp);
    fp.solid_fraction = j->spec->solid_fraction;
    fp.D = j->D;
    fp.nmodes = j->nmodes;
    fp.contour_points = j->np;
    gp_fill_workspace *ws = gp_fill_workspace_create(&fp, &a->err);
    double *phases = malloc(j->nmodes * sizeof(double));
    if (!ws || !phases) {
        if (ws)
            gp_error_set(&a->err, GP_ERR_NOMEM, "out of memory");
        job_fail(j, 0, &a->err);
        gp_fill_workspace_destroy(ws);
        free(phases);
        return NULL;
    }
    size_t n = j->out->ngrains;
    for (;;) {
        if (atomic_load(&j->stop))
            break;
        size_t i = atomic_fetch_add(&j->next, 1);
        if (i >= n)
            break;
        fill_one(j, ws, phases, i, &a->tf, &a->to, &a->td);
        atomic_fetch_add(&j->done, 1);
    }
    gp_fill_workspace_destroy(ws);
    free(phases);
    return NULL;
}

/* ---------------------------------------------------------------- build */

typedef struct imc_relay {
    gp_progress_fn fn;
    void *user;
    const volatile int *cancel;
    double threshold;
    double error0; /* first error seen, < 0 before */
} imc_relay;

/* IMC progress -> job progress: the fraction is how far log(error) has come from the start
 * towards log(threshold), mapped to [0.05, 0.65] of the job. */
static int imc_progress(void *user, long steps, double error)
{
    imc_relay *r = user;
    double threshold = r->threshold;
    if (r->error0 < 0.0)
        r->error0 = error;
    if (cancelled(r->cancel))
        return 1;
    if (!r->fn)
        return 0;
    double frac = 0.0;
    if (error <= threshold)
        frac = 1.0;
    else if (r->error0 > threshold && error > 0.0)
        frac = fmin(1.0, fmax(0.0, log(r->error0 / error) / log(r->error0 / threshold)));
    gp_progress p = {"imc", 0.05 + 0.6 * frac, steps, error};
    return r->fn(r->user, &p);
}

static gp_status spectrum_make(const gp_spec2d *s, size_t nmodes, double *D, gp_error *err)
{
    if (!s->has_spectrum)
        return gp_fourier_spectrum(s->D2, s->D3, s->D8, s->alpha, s->beta, nmodes, D, err);
    if (!s->spectrum || s->nspectrum < 1)
        return gp_error_set(err, GP_ERR_INVALID, "shape.spectrum is empty");
    for (size_t n = 0; n < nmodes; n++)
        D[n] = n < s->nspectrum ? s->spectrum[n] : 0.0;
    D[0] = 1.0;
    return gp_fourier_spectrum_check(D, nmodes, err);
}

static gp_status check_spec(const gp_spec2d *s, gp_error *err)
{
    if (s->particles < 1)
        return gp_error_set(err, GP_ERR_INVALID, "particles must be >= 1");
    if (!(s->cov >= 0.0) || !isfinite(s->cov))
        return gp_error_set(err, GP_ERR_INVALID, "size.cov must be >= 0");
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

gp_status gp_specimen2d_build(const gp_spec2d *spec, gp_progress_fn progress, void *user,
                              const volatile int *cancel, gp_specimen2d **outp, gp_error *err)
{
    if (!spec || !outp)
        return gp_error_set(err, GP_ERR_INVALID, "specimen2d: NULL argument");
    *outp = NULL;
    gp_status st = check_spec(spec, err);
    if (st != GP_OK)
        return st;
    double t_start = now_s();

    gp_specimen2d *out = calloc(1, sizeof *out);
    if (!out)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    container cont;
    gp_voronoi *vor = NULL;
    fill_job job;
    memset(&job, 0, sizeof job);
    double *D = NULL;

    st = container_make(spec, &cont, err);
    if (st != GP_OK)
        goto fail;

    /* ---- tessellation + IMC */
    if (progress) {
        gp_progress p = {"tessellation", 0.0, 0, 0.0};
        if (progress(user, &p) || cancelled(cancel)) {
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
            goto fail;
        }
    }
    gp_imc_params ip;
    gp_imc_params_default(&ip);
    ip.seed = spec->seed;
    ip.cov = spec->cov;
    ip.mean_deg = spec->mean_deg;
    ip.anisotropy = spec->anisotropy;
    ip.error_kind = (int)spec->imc_error;
    ip.threshold = spec->imc_threshold;
    ip.max_steps = spec->imc_max_steps;
    ip.init = spec->imc_init == GP_INIT_HALTON ? 1 : 0;
    ip.classes_size = spec->imc_classes;
    ip.classes_orient = spec->imc_classes;
    imc_relay relay = {progress, user, cancel, spec->imc_threshold, -1.0};
    gp_imc_report rep;
    memset(&rep, 0, sizeof rep);
    double t_imc0 = now_s();
    st = gp_imc_run(cont.outer, cont.nouter, cont.holes, cont.nhole, cont.nholes,
                    spec->particles, &ip, imc_progress, &relay, cancel, &vor, &rep, err);
    /* timings: the initial tessellation, then the IMC steps */
    out->t_tessellation = rep.t_init;
    out->t_imc = now_s() - t_imc0 - rep.t_init;
    /* Reaching max_steps is not a failure: the specimen is built and the stats say how far
     * the IMC got ("max_steps"). A threshold below the integer-count floor, a cancel or bad
     * input end the job with the IMC's message. */
    if (st == GP_ERR_NOT_CONVERGED) {
        st = GP_OK;
        gp_error_clear(err);
    }
    if (st != GP_OK) {
        gp_imc_report_free(&rep);
        goto fail;
    }
    out->container_area = gp_voronoi_container_area(vor);
    out->imc_error = rep.error;
    out->imc_steps = rep.steps;
    out->imc_stop_reason = gp_imc_stop_name(rep.stop_reason);
    out->imc_error_floor = rep.floor;
    if (report_hist(&out->size_hist, rep.nsize, rep.size_edges, rep.size_target,
                    rep.size_achieved, vor) != 0 ||
        report_hist(&out->orientation_hist, rep.norient, rep.orient_edges, rep.orient_target,
                    rep.orient_achieved, NULL) != 0) {
        gp_imc_report_free(&rep);
        st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        goto fail;
    }
    gp_imc_report_free(&rep);

    size_t n = gp_voronoi_count(vor);

    /* ---- cells output */
    if (spec->outputs & GP_OUT_CELLS) {
        out->cells = calloc(n, sizeof *out->cells);
        if (!out->cells) {
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        out->ncells = n;
        for (size_t i = 0; i < n; i++) {
            gp_cell2d *c = &out->cells[i];
            c->seed = gp_voronoi_seed(vor, i);
            c->area = gp_voronoi_cell_area(vor, i);
            c->orientation_deg = gp_voronoi_cell_orientation(vor, i) * DEG;
            c->npolygons = gp_voronoi_cell_parts(vor, i);
            c->polygons = calloc(c->npolygons, sizeof *c->polygons);
            if (!c->polygons) {
                st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
                goto fail;
            }
            for (size_t k = 0; k < c->npolygons; k++) {
                size_t m = gp_voronoi_cell_polygon(vor, i, k, NULL, 0);
                c->polygons[k].pts = malloc((m ? m : 1) * sizeof(gp_vec2));
                if (!c->polygons[k].pts) {
                    st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
                    goto fail;
                }
                c->polygons[k].n = gp_voronoi_cell_polygon(vor, i, k, c->polygons[k].pts, m);
            }
        }
    }

    /* ---- grains: filling (+ ODEC, descriptors) on a pool of threads */
    unsigned need_grains = spec->outputs & (GP_OUT_GRAINS | GP_OUT_ODEC | GP_OUT_DESCRIPTORS);
    if (need_grains) {
        size_t np = spec->contour_points;
        size_t nmodes = np / 2;
        D = malloc(nmodes * sizeof *D);
        out->grains = calloc(n, sizeof *out->grains);
        job.cell_poly = calloc(n, sizeof *job.cell_poly);
        job.cell_n = calloc(n, sizeof *job.cell_n);
        if (!D || !out->grains || !job.cell_poly || !job.cell_n) {
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        out->ngrains = n;
        st = spectrum_make(spec, nmodes, D, err);
        if (st != GP_OK)
            goto fail;
        for (size_t i = 0; i < n; i++) {
            size_t part = gp_voronoi_cell_seed_part(vor, i);
            size_t m = gp_voronoi_cell_polygon(vor, i, part, NULL, 0);
            job.cell_poly[i] = malloc((m ? m : 1) * sizeof(gp_vec2));
            if (!job.cell_poly[i]) {
                st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
                goto fail;
            }
            job.cell_n[i] = gp_voronoi_cell_polygon(vor, i, part, job.cell_poly[i], m);
        }
        job.spec = spec;
        job.vor = vor;
        job.D = D;
        job.nmodes = nmodes;
        job.np = np;
        job.outputs = spec->outputs;
        job.out = out;
        atomic_init(&job.next, 0);
        atomic_init(&job.done, 0);
        atomic_init(&job.stop, 0);
        pthread_mutex_init(&job.lock, NULL);

        int nthreads = spec->threads > 0 ? spec->threads : 1;
        if ((size_t)nthreads > n)
            nthreads = (int)n;
        worker_arg *args = calloc((size_t)nthreads, sizeof *args);
        pthread_t *tids = calloc((size_t)nthreads, sizeof *tids);
        int started = 0;
        if (!args || !tids) {
            free(args);
            free(tids);
            pthread_mutex_destroy(&job.lock);
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        for (int t = 0; t < nthreads; t++) {
            args[t].job = &job;
            if (pthread_create(&tids[t], NULL, fill_worker, &args[t]) == 0)
                started++;
            else
                break;
        }
        if (started == 0)
            fill_worker(&args[0]); /* no thread could start: do the work here */
        /* This thread reports progress and relays cancellation while the pool works. */
        while (started > 0 && atomic_load(&job.done) < n && !atomic_load(&job.stop)) {
            struct timespec ts = {0, 50 * 1000 * 1000};
            nanosleep(&ts, NULL);
            int stop = cancelled(cancel);
            if (!stop && progress) {
                gp_progress p = {"fill", 0.65 + 0.35 * (double)atomic_load(&job.done) / (double)n,
                                 out->imc_steps, out->imc_error};
                stop = progress(user, &p);
            }
            if (stop) {
                gp_error e;
                gp_error_set(&e, GP_ERR_CANCELLED, "cancelled");
                job_fail(&job, 0, &e);
            }
        }
        for (int t = 0; t < started; t++)
            pthread_join(tids[t], NULL);
        for (int t = 0; t < nthreads; t++) {
            job.t_fill += args[t].tf;
            job.t_odec += args[t].to;
            job.t_desc += args[t].td;
        }
        free(args);
        free(tids);
        pthread_mutex_destroy(&job.lock);
        if (job.err.code != GP_OK) {
            st = job.err.code;
            if (err)
                *err = job.err;
            goto fail;
        }
        /* CPU seconds summed over threads, scaled to wall time by the thread count */
        out->t_fill = job.t_fill / nthreads;
        out->t_odec = job.t_odec / nthreads;
        out->t_descriptors = job.t_desc / nthreads;

        /* ---- statistics of the grains */
        double solid = 0.0, gap = 0.0;
        size_t met = 0;
        for (size_t i = 0; i < n; i++) {
            const gp_grain2d *g = &out->grains[i];
            solid += g->area;
            met += g->target_met != 0;
            double d = fmod(fabs(g->orientation_deg - gp_voronoi_cell_orientation(vor, i) * DEG),
                            180.0);
            gap += d > 90.0 ? 180.0 - d : d;
        }
        out->solid_fraction = solid / out->container_area;
        out->cells_target_met = met;
        out->mean_orientation_gap_deg = n ? gap / (double)n : 0.0;
        /* grain sizes on the cell classes scaled by the target fraction */
        if (hist_copy(&out->grain_size_hist, &out->size_hist, spec->solid_fraction) != 0) {
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        double *v = malloc(n * sizeof *v);
        if (!v) {
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        for (size_t i = 0; i < n; i++)
            v[i] = out->grains[i].area;
        hist_fill(&out->grain_size_hist, v, n);
        /* the grains' orientations on the IMC's classes, against the same cosine law */
        if (hist_copy(&out->grain_orientation_hist, &out->orientation_hist, 1.0) != 0) {
            free(v);
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        for (size_t i = 0; i < n; i++)
            v[i] = out->grains[i].orientation_deg >= 90.0 ? out->grains[i].orientation_deg - 180.0
                                                          : out->grains[i].orientation_deg;
        hist_fill(&out->grain_orientation_hist, v, n);
        free(v);
        if (spec->outputs & GP_OUT_DESCRIPTORS) {
            st = descriptor_stats(out, err);
            if (st != GP_OK)
                goto fail;
        }
    }

    for (size_t i = 0; job.cell_poly && i < n; i++)
        free(job.cell_poly[i]);
    free(job.cell_poly);
    free(job.cell_n);
    free(D);
    gp_voronoi_destroy(vor);
    container_free(&cont);
    out->t_total = now_s() - t_start;
    if (progress) {
        gp_progress p = {"done", 1.0, out->imc_steps, out->imc_error};
        progress(user, &p);
    }
    *outp = out;
    return GP_OK;

fail:
    if (job.cell_poly) {
        for (size_t i = 0; i < out->ngrains; i++)
            free(job.cell_poly[i]);
    }
    free(job.cell_poly);
    free(job.cell_n);
    free(D);
    gp_voronoi_destroy(vor);
    container_free(&cont);
    gp_specimen2d_destroy(out);
    return st;
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
    hist_free(&s->size_hist);
    hist_free(&s->grain_size_hist);
    hist_free(&s->orientation_hist);
    hist_free(&s->grain_orientation_hist);
    for (int d = 0; d < 4; d++)
        hist_free(&s->descriptor_hist[d]);
    free(s);
}
