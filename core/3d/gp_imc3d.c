/* gp_imc3d.c -- IMC of a bounded 3D Voronoi tessellation (gp_imc3d.h). */
#include "gp_imc3d.h"

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_adstat.h"
#include "gp_clock.h"
#include "gp_rng.h"

#define IMC3D_PROGRESS_EVERY 4096
#define IMC3D_TRIES 1000 /* rejection draws for a point in a cell or the container */

void gp_imc3d_params_defaults(gp_imc3d_params *p)
{
    if (!p) return;
    memset(p, 0, sizeof *p);
    p->cov = 0.5;
    p->axis[2] = 1.0;
    p->anisotropy = 1.0;
    p->threshold = gp_imc_default_threshold(GP_IMC_ERROR_AD);
    p->max_steps = 1000000;
    p->seed = 1;
}

/* ------------------------------------------------------------------------------------------ */
/* the orientation law                                                                         */

double gp_orient3d_k(double a) { return 2.0 * (1.0 - a) / (1.0 + 2.0 * a); }

double gp_orient3d_cdf(double a, double c)
{
    c = c < 0.0 ? 0.0 : c > 1.0 ? 1.0 : c;
    return c + 0.5 * gp_orient3d_k(a) * (c * c * c - c);
}

static double axis_cos_ws(gsl_eigen_symmv_workspace *ws, const double I[9], const double axis[3])
{
    for (int k = 0; k < 9; k++)
        if (!isfinite(I[k])) return NAN;
    double m[9], ev[3], vec[9];
    memcpy(m, I, sizeof m);
    gsl_matrix_view A = gsl_matrix_view_array(m, 3, 3), V = gsl_matrix_view_array(vec, 3, 3);
    gsl_vector_view E = gsl_vector_view_array(ev, 3);
    if (gsl_eigen_symmv(&A.matrix, &E.vector, &V.matrix, ws) != 0) return NAN;
    int j = 0; /* the least moment: the longest axis */
    for (int k = 1; k < 3; k++)
        if (ev[k] < ev[j]) j = k;
    double d = vec[0 * 3 + j] * axis[0] + vec[1 * 3 + j] * axis[1] + vec[2 * 3 + j] * axis[2];
    return fmin(fabs(d), 1.0);
}

double gp_orient3d_cos(const double I[9], const double axis[3])
{
    gsl_eigen_symmv_workspace *ws = gsl_eigen_symmv_alloc(3);
    if (!ws) return NAN;
    double c = axis_cos_ws(ws, I, axis);
    gsl_eigen_symmv_free(ws);
    return c;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double gp_orient3d_ks(double *c, size_t n, double a)
{
    qsort(c, n, sizeof *c, cmp_double);
    double d = 0.0;
    for (size_t i = 0; i < n; i++) {
        double u = gp_orient3d_cdf(a, c[i]);
        d = fmax(d, fmax((i + 1.0) / (double)n - u, u - (double)i / (double)n));
    }
    return d;
}

/* ------------------------------------------------------------------------------------------ */
/* the container: bounding box and inside test, before any tessellation exists                 */

typedef struct shape {
    const gp_voronoi3d_container *c;
    double lo[3], hi[3];
} shape;

/* the test gp_voronoi3d_create applies to a seed: a point it accepts is never refused */
static int inside(const shape *s, const double p[3])
{
    return gp_voronoi3d_container_inside(s->c, s->lo, s->hi, p);
}

static gp_status shape_init(shape *s, const gp_voronoi3d_container *c, gp_error *err)
{
    s->c = c;
    return gp_voronoi3d_container_bounds(c, s->lo, s->hi, err);
}

static int point_in_box(const shape *s, gp_rng *r, double p[3])
{
    for (int t = 0; t < IMC3D_TRIES; t++) {
        for (int k = 0; k < 3; k++) p[k] = gp_rng_range(r, s->lo[k], s->hi[k]);
        if (inside(s, p)) return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* seeds: uniform in the container, numbered along a Morton curve                              */

typedef struct keyed {
    uint64_t key;
    size_t i;
} keyed;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key ? 1 : (x->i > y->i) - (x->i < y->i);
}

static uint64_t spread3(uint64_t v) /* 21 bits -> every third bit */
{
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

static gp_status place_seeds(const shape *s, size_t n, uint64_t seed, double *xyz, gp_error *err)
{
    gp_rng *r = gp_rng_create(seed, 0, err);
    keyed *ord = malloc(n * sizeof *ord);
    double *tmp = malloc(3 * n * sizeof *tmp);
    gp_status st = r && ord && tmp ? GP_OK : gp_error_set(err, GP_ERR_NOMEM, "imc3d: out of memory");
    for (size_t i = 0; st == GP_OK && i < n; i++) {
        if (!point_in_box(s, r, tmp + 3 * i))
            st = gp_error_set(err, GP_ERR_INVALID, "imc3d: the container fills too little of its box");
        uint64_t key = 0;
        for (int k = 0; k < 3; k++) {
            double f = (tmp[3 * i + k] - s->lo[k]) / (s->hi[k] - s->lo[k]);
            key |= spread3((uint64_t)(fmin(fmax(f, 0.0), 1.0) * 2097151.0)) << k;
        }
        ord[i] = (keyed){key, i};
    }
    if (st == GP_OK) {
        qsort(ord, n, sizeof *ord, cmp_keyed);
        for (size_t i = 0; i < n; i++) memcpy(xyz + 3 * i, tmp + 3 * ord[i].i, 3 * sizeof *xyz);
    }
    gp_rng_destroy(r);
    free(ord);
    free(tmp);
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* the objective                                                                               */

typedef struct cell_val {
    double vk, vg, vh; /* volume: key, ln F, ln (1 - F) */
    double ok, og, oh; /* orientation c: key, ln F, ln (1 - F) */
} cell_val;

typedef struct objective {
    double error, descent, ev, eo;
} objective;

typedef struct state {
    size_t n;
    const gp_law *law;
    double a, axis[3], mu, cov_t, ulo, floor;
    gp_adstat *vs, *os;
    cell_val *val;
    gsl_eigen_symmv_workspace *ws;
    /* a step's changed cells: ids, new values, old values */
    size_t cap;
    size_t *ids;
    cell_val *nv, *ov;
    double *key, *g, *h, *x;
} state;

static void state_free(state *S)
{
    gp_adstat_destroy(S->vs);
    gp_adstat_destroy(S->os);
    free(S->val);
    if (S->ws) gsl_eigen_symmv_free(S->ws);
    free(S->ids);
    free(S->nv);
    free(S->ov);
    free(S->key);
    free(S->g);
    free(S->h);
    free(S->x);
}

static void cell_eval(state *S, const gp_voronoi3d *v, size_t i, cell_val *c)
{
    double vol = gp_voronoi3d_cell_volume(v, i), I[9];
    c->vk = vol;
    gp_law_log_cdf_sf(S->law, vol, &c->vg, &c->vh);
    gp_voronoi3d_cell_inertia(v, i, I);
    double cs = axis_cos_ws(S->ws, I, S->axis);
    double u = gp_orient3d_cdf(S->a, isfinite(cs) ? cs : 0.5);
    u = u < S->ulo ? S->ulo : u > 1.0 - S->ulo ? 1.0 - S->ulo : u;
    c->ok = u;
    c->og = log(u);
    c->oh = log1p(-u);
}

static void cell_put(state *S, size_t i, const cell_val *c)
{
    gp_adstat_set(S->vs, i, c->vk, c->vg, c->vh, c->vk * c->vk);
    gp_adstat_set(S->os, i, c->ok, c->og, c->oh, 0.0);
    S->val[i] = *c;
}

static double cov_term(const state *S, double sum_sq)
{
    return gp_imc_cov_term(S->n, S->mu, S->cov_t, sum_sq);
}

static objective objective_of(double ev, double eo)
{
    objective o = {fmax(ev, 0.5 * eo), ev + 0.5 * eo, ev, eo};
    return o;
}

static objective evaluate(const state *S)
{
    double ev = gp_adstat_a2(S->vs) - S->floor + cov_term(S, gp_adstat_sum_extra(S->vs));
    return objective_of(ev, gp_adstat_a2(S->os) - S->floor);
}

/* what the objective would be with the k changed cells at S->nv, without changing the sets
 * (gp_adstat_a2_if) or, beyond its batch limit, by setting them (the caller sets them back) */
static objective evaluate_if(state *S, size_t k)
{
    if (k > GP_ADSTAT_IF_MAX) {
        for (size_t j = 0; j < k; j++) {
            S->ov[j] = S->val[S->ids[j]];
            cell_put(S, S->ids[j], &S->nv[j]);
        }
        return evaluate(S);
    }
    double sx;
    for (size_t j = 0; j < k; j++) {
        S->key[j] = S->nv[j].vk;
        S->g[j] = S->nv[j].vg;
        S->h[j] = S->nv[j].vh;
        S->x[j] = S->nv[j].vk * S->nv[j].vk;
    }
    double av = gp_adstat_a2_if(S->vs, k, S->ids, S->key, S->g, S->h, S->x, &sx);
    for (size_t j = 0; j < k; j++) {
        S->key[j] = S->nv[j].ok;
        S->g[j] = S->nv[j].og;
        S->h[j] = S->nv[j].oh;
        S->x[j] = 0.0;
    }
    double ao = gp_adstat_a2_if(S->os, k, S->ids, S->key, S->g, S->h, S->x, NULL);
    return objective_of(av - S->floor + cov_term(S, sx), ao - S->floor);
}

static gp_status state_init(state *S, const gp_imc3d_params *p, const gp_law *law,
                            const gp_voronoi3d *v, size_t n, gp_error *err)
{
    memset(S, 0, sizeof *S);
    S->n = n;
    S->law = law;
    S->a = p->anisotropy;
    double len = sqrt(p->axis[0] * p->axis[0] + p->axis[1] * p->axis[1] + p->axis[2] * p->axis[2]);
    for (int k = 0; k < 3; k++) S->axis[k] = p->axis[k] / len;
    S->mu = gp_law_mean(law);
    S->cov_t = gp_law_cov(law) * (n > 1 ? sqrt((double)(n - 1) / (double)n) : 1.0);
    S->ulo = 0.25 / (double)n;
    S->floor = gp_adstat_floor(n);
    S->vs = gp_adstat_create(n, err);
    S->os = gp_adstat_create(n, err);
    S->val = malloc(n * sizeof *S->val);
    S->ws = gsl_eigen_symmv_alloc(3);
    if (!S->vs || !S->os || !S->val || !S->ws) return gp_error_set(err, GP_ERR_NOMEM, "imc3d: out of memory");
    for (size_t i = 0; i < n; i++) {
        cell_val c;
        cell_eval(S, v, i, &c);
        cell_put(S, i, &c);
    }
    return GP_OK;
}

static int state_room(state *S, size_t k)
{
    if (k <= S->cap) return 1;
    size_t cap = k < 64 ? 64 : 2 * k;
    size_t *ids = realloc(S->ids, cap * sizeof *ids);
    if (ids) S->ids = ids;
    cell_val *nv = realloc(S->nv, cap * sizeof *nv);
    if (nv) S->nv = nv;
    cell_val *ov = realloc(S->ov, cap * sizeof *ov);
    if (ov) S->ov = ov;
    double *arr[4] = {S->key, S->g, S->h, S->x};
    for (int j = 0; j < 4; j++) {
        double *t = realloc(arr[j], cap * sizeof(double));
        if (t) arr[j] = t;
    }
    S->key = arr[0];
    S->g = arr[1];
    S->h = arr[2];
    S->x = arr[3];
    if (!ids || !nv || !ov || arr[0] == NULL || arr[1] == NULL || arr[2] == NULL || arr[3] == NULL) return 0;
    S->cap = cap;
    return 1;
}

/* ------------------------------------------------------------------------------------------ */
/* moves                                                                                       */

/* a cell's faces as planes, for points uniform in it */
typedef struct cellbuf {
    size_t cap_v, cap_p;
    double *xyz, *planes;
    size_t nb_cap;
    size_t *nb;
} cellbuf;

static void cellbuf_free(cellbuf *b)
{
    free(b->xyz);
    free(b->planes);
    free(b->nb);
}

static int grow(void **p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return 1;
    size_t c = need < 64 ? 64 : 2 * need;
    void *q = realloc(*p, c * size);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

/* the outward planes of cell i (gp_voronoi3d_cell_planes) and the cell's box; returns the face
 * count, 0 when out of memory */
static size_t cell_planes(const gp_voronoi3d *v, size_t i, cellbuf *b, double lo[3], double hi[3])
{
    size_t nv = gp_voronoi3d_cell_vertices(v, i, NULL, 0), nf = gp_voronoi3d_cell_face_count(v, i);
    if (!grow((void **)&b->xyz, &b->cap_v, 3 * nv, sizeof(double)) ||
        !grow((void **)&b->planes, &b->cap_p, 4 * nf, sizeof(double)))
        return 0;
    gp_voronoi3d_cell_vertices(v, i, b->xyz, nv);
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (size_t j = 0; j < nv; j++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], b->xyz[3 * j + k]);
            hi[k] = fmax(hi[k], b->xyz[3 * j + k]);
        }
    return gp_voronoi3d_cell_planes(v, i, b->planes, nf);
}

static int point_in_cell(const gp_voronoi3d *v, size_t i, cellbuf *b, gp_rng *r, double p[3])
{
    double lo[3], hi[3];
    size_t nf = cell_planes(v, i, b, lo, hi);
    for (int t = 0; nf > 0 && t < IMC3D_TRIES; t++) {
        for (int k = 0; k < 3; k++) p[k] = gp_rng_range(r, lo[k], hi[k]);
        size_t f = 0;
        while (f < nf && b->planes[4 * f] * p[0] + b->planes[4 * f + 1] * p[1] + b->planes[4 * f + 2] * p[2] <=
                             b->planes[4 * f + 3])
            f++;
        if (f == nf) return 1;
    }
    return 0;
}

/* the paper's move: a cell of {i} and its neighbours, chosen by volume (vol: every cell's
 * current volume, the run's recorded values) */
static size_t cell_by_volume(const gp_voronoi3d *v, const cell_val *vol, size_t i, cellbuf *b, gp_rng *r)
{
    size_t k = gp_voronoi3d_neighbours(v, i, NULL, 0);
    if (!grow((void **)&b->nb, &b->nb_cap, k, sizeof(size_t))) return i;
    gp_voronoi3d_neighbours(v, i, b->nb, k);
    double total = vol[i].vk;
    for (size_t j = 0; j < k; j++) total += vol[b->nb[j]].vk;
    double t = gp_rng_uniform(r) * total - vol[i].vk;
    for (size_t j = 0; j < k && t >= 0.0; j++) {
        t -= vol[b->nb[j]].vk;
        if (t < 0.0) return b->nb[j];
    }
    return i;
}

static int propose(const gp_voronoi3d *v, const cell_val *vol, const shape *s, size_t i, cellbuf *b, gp_rng *r,
                   double q[3])
{
    double u = gp_rng_uniform(r);
    if (u < 0.4) return point_in_cell(v, cell_by_volume(v, vol, i, b, r), b, r, q);
    if (u < 0.8) return point_in_cell(v, i, b, r, q);
    return point_in_box(s, r, q);
}

/* ------------------------------------------------------------------------------------------ */
/* the run                                                                                     */

typedef struct run {
    state S;
    shape sh;
    cellbuf b;
    gp_rng *r;
    objective cur;
    long steps, accepted, best_step;
    double best, e0;
} run;

/* One step on seed i: 1 kept, 0 refused, -1 on an error (err set). */
static int step(run *R, gp_voronoi3d *v, size_t i, gp_error *err)
{
    double q[3];
    if (!propose(v, R->S.val, &R->sh, i, &R->b, R->r, q)) return 0;
    gp_error e;
    gp_status st = gp_voronoi3d_try_move(v, i, q, &e);
    if (st == GP_ERR_INVALID) return 0; /* a duplicate of another seed, or outside */
    if (st != GP_OK) {
        if (err) *err = e;
        return -1;
    }
    const uint32_t *cells;
    size_t k = gp_voronoi3d_changed(v, &cells);
    state *S = &R->S;
    if (!state_room(S, k)) {
        gp_voronoi3d_rollback(v);
        gp_error_set(err, GP_ERR_NOMEM, "imc3d: out of memory");
        return -1;
    }
    for (size_t j = 0; j < k; j++) {
        S->ids[j] = cells[j];
        cell_eval(S, v, cells[j], &S->nv[j]);
    }
    objective o = evaluate_if(S, k);
    if (o.descent <= R->cur.descent) {
        gp_voronoi3d_commit(v);
        for (size_t j = 0; j < k; j++) cell_put(S, S->ids[j], &S->nv[j]);
        R->cur = evaluate(S);
        return 1;
    }
    if (k > GP_ADSTAT_IF_MAX)
        for (size_t j = 0; j < k; j++) cell_put(S, S->ids[j], &S->ov[j]);
    gp_voronoi3d_rollback(v);
    return 0;
}

static int report(run *R, const gp_imc3d_params *p, gp_progress_fn progress, void *user)
{
    if (!progress) return 0;
    double f = 0.0;
    if (R->e0 > p->threshold && R->cur.error > 0)
        f = (log(R->e0) - log(R->cur.error)) / (log(R->e0) - log(p->threshold));
    gp_progress pr = {"imc", 0.0, fmin(fmax(f, 0.0), 1.0), R->steps, R->cur.error, 0.0, 0.0};
    return progress(user, &pr);
}

static gp_imc_stop run_steps(run *R, gp_voronoi3d *v, const gp_imc3d_params *p, gp_progress_fn progress,
                             void *user, const volatile int *cancel, gp_error *err, int *failed)
{
    size_t n = R->S.n;
    if (n == 1) return GP_IMC_STOP_SINGLE_CELL;
    R->best = R->cur.error;
    for (;;) {
        if (R->cur.error <= p->threshold) return GP_IMC_STOP_THRESHOLD;
        if (R->steps >= p->max_steps) return GP_IMC_STOP_MAX_STEPS;
        if (R->steps - R->best_step > gp_imc_stall_window(n)) return GP_IMC_STOP_STALLED;
        if ((cancel && __atomic_load_n(cancel, __ATOMIC_RELAXED)) ||
            (R->steps % IMC3D_PROGRESS_EVERY == 0 && R->steps > 0 && report(R, p, progress, user)))
            return GP_IMC_STOP_CANCELLED;
        int kept = step(R, v, (size_t)(R->steps % (long)n), err);
        if (kept < 0) {
            *failed = 1;
            return GP_IMC_STOP_CANCELLED;
        }
        R->steps++;
        R->accepted += kept;
        if (R->cur.error < 0.99 * R->best) {
            R->best = R->cur.error;
            R->best_step = R->steps;
        }
    }
}

static gp_status check(const gp_voronoi3d_container *c, size_t n, const gp_imc3d_params *p, gp_voronoi3d **out,
                       gp_error *err)
{
    if (!c || !p || !out) return gp_error_set(err, GP_ERR_INVALID, "imc3d: container, params and out are required");
    if (n < 1 || n > (size_t)1 << 29) return gp_error_set(err, GP_ERR_INVALID, "imc3d: n must be in [1, 2^29]");
    double len = sqrt(p->axis[0] * p->axis[0] + p->axis[1] * p->axis[1] + p->axis[2] * p->axis[2]);
    if (!(len > 0) || !isfinite(len)) return gp_error_set(err, GP_ERR_INVALID, "imc3d: the axis must be a non-zero vector");
    if (!(p->anisotropy > 0.0 && p->anisotropy <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "imc3d: anisotropy must be in (0, 1]");
    if (!(p->threshold > 0.0)) return gp_error_set(err, GP_ERR_INVALID, "imc3d: threshold must be > 0");
    if (p->max_steps < 0) return gp_error_set(err, GP_ERR_INVALID, "imc3d: max_steps must be >= 0");
    if (!p->law && !(p->cov > 0.0 && isfinite(p->cov))) return gp_error_set(err, GP_ERR_INVALID, "imc3d: cov must be > 0");
    return GP_OK;
}

static gp_status end_status(gp_imc_stop why, int failed, const run *R, const gp_imc3d_params *p, gp_error *err)
{
    if (failed) return err ? err->code : GP_ERR_INTERNAL;
    if (why == GP_IMC_STOP_THRESHOLD) return GP_OK;
    if (why == GP_IMC_STOP_CANCELLED) return gp_error_set(err, GP_ERR_CANCELLED, "imc3d: cancelled after %ld steps", R->steps);
    return gp_error_set(err, GP_ERR_NOT_CONVERGED, "imc3d: %s after %ld steps without reaching %g (error %g)",
                        gp_imc_stop_name(why), R->steps, p->threshold, R->cur.error);
}

gp_status gp_imc3d_run(const gp_voronoi3d_container *c, size_t n, const gp_imc3d_params *p,
                       gp_progress_fn progress, void *user, const volatile int *cancel,
                       gp_voronoi3d **out, gp_imc3d_report *rep, gp_error *err)
{
    if (rep) memset(rep, 0, sizeof *rep);
    gp_status st = check(c, n, p, out, err);
    if (st != GP_OK) return st;
    *out = NULL;
    run R;
    memset(&R, 0, sizeof R);
    gp_voronoi3d *v = NULL;
    gp_law *own = NULL;
    double *xyz = malloc(3 * n * sizeof *xyz), t0 = gp_clock_seconds();
    st = xyz ? shape_init(&R.sh, c, err) : gp_error_set(err, GP_ERR_NOMEM, "imc3d: out of memory");
    if (st == GP_OK) st = place_seeds(&R.sh, n, p->seed, xyz, err);
    if (st == GP_OK && !(v = gp_voronoi3d_create_ex(c, xyz, n, cancel, err))) st = err ? err->code : GP_ERR_INVALID;
    const gp_law *law = p->law;
    if (st == GP_OK && !law) {
        law = own = gp_law_create(GP_LAW_LOGNORMAL, gp_voronoi3d_container_volume(v) / (double)n, p->cov, err);
        if (!law) st = err ? err->code : GP_ERR_INVALID;
    }
    if (st == GP_OK && p->law && p->scale_law) {
        double want = gp_voronoi3d_container_volume(v) / (double)n;
        law = own = gp_law_scaled(p->law, want / gp_law_mean(p->law), err);
        if (!law) st = err ? err->code : GP_ERR_INVALID;
    } else if (st == GP_OK && p->law) {
        double want = gp_voronoi3d_container_volume(v) / (double)n, mean = gp_law_mean(p->law);
        if (!(fabs(mean - want) <= 1e-9 * want))
            st = gp_error_set(err, GP_ERR_INVALID, "imc3d: the law's mean volume %g is not the container's "
                              "volume / n = %g", mean, want);
    }
    if (st == GP_OK) st = state_init(&R.S, p, law, v, n, err);
    if (st == GP_OK && !(R.r = gp_rng_create(p->seed, 1, err))) st = GP_ERR_NOMEM;
    if (rep) rep->t_init = gp_clock_seconds() - t0;
    if (st == GP_OK) {
        R.cur = evaluate(&R.S);
        R.e0 = R.cur.error;
        int failed = 0;
        gp_imc_stop why = run_steps(&R, v, p, progress, user, cancel, err, &failed);
        st = end_status(why, failed, &R, p, err);
        if (rep) {
            *rep = (gp_imc3d_report){R.steps, R.accepted, R.cur.error, R.e0, R.cur.ev, R.cur.eo, why, rep->t_init};
        }
        if (!failed) {
            *out = v;
            v = NULL;
        }
    }
    gp_voronoi3d_destroy(v);
    gp_law_destroy(own);
    gp_rng_destroy(R.r);
    state_free(&R.S);
    cellbuf_free(&R.b);
    free(xyz);
    return st;
}
