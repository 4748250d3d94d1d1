/* gp_dem3d.c -- see gp_dem3d.h.
 *
 * Two details the header does not spell out:
 *  - free flight: density scaling raises a small sphere's inertia so that its contacts keep
 *    the time step; gravity acting on the true mass then accelerates it by only g (m / m_i),
 *    down to g / 100 for a grain a tenth of the scaling radius, and the fines of a wide sieve
 *    take tens of thousands of steps to fall into the pores of the skeleton. A sphere with
 *    no surface (sphere or wall) within free_gap has no contact stiffness to protect, so it
 *    moves with its true mass and without local damping (which is there to take the energy
 *    out of contact oscillations, and would make it fall at (1 - c) g): it falls at g, as it
 *    would. The switch happens at a gap, not at contact, because one free step under g moves
 *    a small sphere about as far as its static overlap (g dt^2 ~ m g / k): switching at
 *    contact makes a resting sphere bounce for ever. Static states are unchanged (no force
 *    differs), and so is everything near contact. With the relaxation's damping of 0.7, the
 *    fines of a size ratio of 20 come to rest in about half the steps.
 *  - the candidate list holds the pairs with a gap below skin + free_gap, so a sphere sees
 *    every surface within free_gap until the two spheres that moved (or grew) most have
 *    together moved the skin: one fine falling through the pores at ~1 m/s may go nearly the
 *    whole skin alone. The skin only trades rebuilds against candidates: results do not
 *    depend on it (test_dem3d runs a skin 40 times smaller and compares the bits).
 *  - S_c, the kinetic energy and vmax are read only after a run, so only a run's last step
 *    sums them (a square root per sphere saved on every other step); the walls' forces and
 *    stiffnesses, which the servo needs, are summed on every step.
 */
#include "gp_dem3d.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define BLK 64          /* spheres per reduction block (fixed: results do not depend on threads) */
#define SERVO_GAIN 0.25 /* fraction of Eq. 10's displacement applied per step */
#define NLEVEL 8        /* size levels of the cell grids (see rebuild) */
#define FREE_GAP 0.05   /* free flight beyond this gap, times the smallest radius (see job_spheres) */

typedef struct blk_acc {
    double sum_f, sum_fn, ke, vmax2;
    double move[2];  /* the two largest (|x - xref| + growth of the radius)^2 of the block */
    double wf[6], wk[6];
    size_t wn;
    int bad;
} blk_acc;

struct gp_dem3d;
typedef void (*job_fn)(struct gp_dem3d *d, int tid, int nt);

typedef struct pool {
    int nt;
    pthread_t *th;
    pthread_mutex_t mu;
    pthread_cond_t cv_start, cv_done;
    unsigned gen;
    int pending, quit, started;
    job_fn fn;
    struct gp_dem3d *d;
} pool;

typedef struct worker_arg {
    pool *p;
    int tid;
} worker_arg;

/* the arrays of one pair list (capacity cap pairs) */
typedef struct pair_set {
    size_t cap;
    uint32_t *pi, *pj;
    double *fs, *F, *c, *fn;
    size_t *adj;
} pair_set;

static void pair_set_free(pair_set *p)
{
    free(p->pi); free(p->pj); free(p->fs); free(p->F); free(p->c); free(p->fn); free(p->adj);
    memset(p, 0, sizeof *p);
}

static int pair_set_reserve(pair_set *p, size_t cap)
{
    if (cap <= p->cap)
        return 0;
    cap += cap / 4 + 64;
    uint32_t *a = realloc(p->pi, cap * sizeof *a);
    if (a) p->pi = a;
    uint32_t *b = realloc(p->pj, cap * sizeof *b);
    if (b) p->pj = b;
    double *fs = realloc(p->fs, 3 * cap * sizeof *fs);
    if (fs) p->fs = fs;
    double *F = realloc(p->F, 3 * cap * sizeof *F);
    if (F) p->F = F;
    double *c = realloc(p->c, 3 * cap * sizeof *c);
    if (c) p->c = c;
    double *fn = realloc(p->fn, cap * sizeof *fn);
    if (fn) p->fn = fn;
    size_t *adj = realloc(p->adj, 2 * cap * sizeof *adj);
    if (adj) p->adj = adj;
    if (!a || !b || !fs || !F || !c || !fn || !adj)
        return -1;
    p->cap = cap;
    return 0;
}

struct gp_dem3d {
    size_t n;
    double *x, *v, *w;         /* 3n */
    double *r0, *r;            /* full and current radii */
    double *m, *minv, *iinv;   /* true mass; inverse inertial mass and moment */
    double *xref;              /* positions at the last rebuild */
    double *mtinv;             /* 1 / true mass (free flight) */
    /* the step's sums per sphere, in pair order (see step_forces): force (3n, starting from
     * gravity), moment (3n), sum of f_n (n), a surface within free_gap (n) */
    double *af, *at, *afn;
    unsigned char *anear;
    double rscale, rscale_ref, r0max, r0min;
    double E, ks_kn, tanphi, damping, g[3], dt, skin, free_gap;
    double wall[6];            /* positions: lo x, hi x, lo y, hi y, lo z, hi z */
    double servo_f[6], servo_v[6], servo_lim[6];
    double wall_f[6], wall_k[6];
    size_t wall_n;
    /* candidate pairs (i < j), sorted */
    size_t np;
    pair_set cur, spare;       /* the list in use, and the buffers the next rebuild fills */
    uint32_t *pi, *pj;         /* = cur.pi, cur.pj, ... (short names for the hot loops) */
    double *pfs, *pF, *pc, *pfn; /* shear spring (3), force on i (3), n x fs (3), f_n */
    /* per-sphere pair lists: entries (pair << 1) | (sphere is j) */
    size_t *off, *fill;
    size_t *adj;
    /* the pairs a rebuild finds, unsorted (2 each), and the threads' contact counts */
    uint32_t *raw;
    size_t raw_cap;
    size_t *tnc;
    /* cell grids of the rebuild, kept between rebuilds */
    size_t *lv_start[NLEVEL], *lv_list[NLEVEL], lv_start_cap[NLEVEL], lv_list_cap[NLEVEL];
    /* cells */
    size_t *cell_of;
    unsigned char *level;
    /* blocks */
    size_t nblk;
    blk_acc *blk;
    /* status */
    long steps, rebuilds;
    double time, stability, kinetic, vmax;
    size_t ncontacts;
    int need_rebuild;
    int measure;               /* this step sums S_c, kinetic energy, vmax (a run's last step) */
    const volatile int *cancel; /* gp_dem3d_set_cancel; read atomically once a step */
    pool pool;
    worker_arg *wargs;
};

/* ------------------------------------------------------------------ thread pool */

static void *worker_main(void *arg)
{
    worker_arg *wa = arg;
    pool *p = wa->p;
    unsigned seen = 0;
    for (;;) {
        pthread_mutex_lock(&p->mu);
        while (p->gen == seen && !p->quit)
            pthread_cond_wait(&p->cv_start, &p->mu);
        if (p->quit) {
            pthread_mutex_unlock(&p->mu);
            return NULL;
        }
        seen = p->gen;
        job_fn fn = p->fn;
        struct gp_dem3d *d = p->d;
        pthread_mutex_unlock(&p->mu);
        fn(d, wa->tid, p->nt);
        pthread_mutex_lock(&p->mu);
        if (--p->pending == 0)
            pthread_cond_signal(&p->cv_done);
        pthread_mutex_unlock(&p->mu);
    }
}

static void run_job(gp_dem3d *d, job_fn fn)
{
    pool *p = &d->pool;
    if (p->nt <= 1 || !p->started) {
        fn(d, 0, 1);
        return;
    }
    pthread_mutex_lock(&p->mu);
    p->fn = fn;
    p->d = d;
    p->pending = p->nt - 1;
    p->gen++;
    pthread_cond_broadcast(&p->cv_start);
    pthread_mutex_unlock(&p->mu);
    fn(d, 0, p->nt);
    pthread_mutex_lock(&p->mu);
    while (p->pending > 0)
        pthread_cond_wait(&p->cv_done, &p->mu);
    pthread_mutex_unlock(&p->mu);
}

static int pool_start(gp_dem3d *d, int nt)
{
    pool *p = &d->pool;
    p->nt = nt < 1 ? 1 : nt;
    if (p->nt == 1)
        return 0;
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->cv_start, NULL);
    pthread_cond_init(&p->cv_done, NULL);
    p->th = calloc((size_t)p->nt, sizeof *p->th);
    d->wargs = calloc((size_t)p->nt, sizeof *d->wargs);
    if (!p->th || !d->wargs)
        return -1;
    p->started = 1;
    for (int t = 1; t < p->nt; t++) {
        d->wargs[t].p = p;
        d->wargs[t].tid = t;
        if (pthread_create(&p->th[t], NULL, worker_main, &d->wargs[t]) != 0) {
            p->nt = t; /* run with the threads we have */
            break;
        }
    }
    return 0;
}

static void pool_stop(gp_dem3d *d)
{
    pool *p = &d->pool;
    if (!p->started)
        return;
    pthread_mutex_lock(&p->mu);
    p->quit = 1;
    pthread_cond_broadcast(&p->cv_start);
    pthread_mutex_unlock(&p->mu);
    for (int t = 1; t < p->nt; t++)
        pthread_join(p->th[t], NULL);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->cv_start);
    pthread_cond_destroy(&p->cv_done);
    free(p->th);
    free(d->wargs);
    p->started = 0;
}

/* more than one thread: forces per pair, then gathered per sphere (see step_forces) */
static int threaded(const gp_dem3d *d) { return d->pool.started && d->pool.nt > 1; }

/* ------------------------------------------------------------------ create / destroy */

void gp_dem3d_params_defaults(gp_dem3d_params *p)
{
    memset(p, 0, sizeof *p);
    p->density = 2600;
    p->young = 15e6;
    p->ks_kn = 0.5;
    p->friction_deg = 18;
    p->damping = 0.2;
    p->gravity[2] = -9.81;
    p->dt_safety = 0.2;
    p->threads = 1;
}

void gp_dem3d_destroy(gp_dem3d *d)
{
    if (!d)
        return;
    pool_stop(d);
    free(d->x); free(d->v); free(d->w); free(d->r0); free(d->r);
    free(d->m); free(d->minv); free(d->iinv); free(d->xref); free(d->mtinv);
    free(d->af); free(d->at); free(d->afn); free(d->anear);
    free(d->raw); free(d->tnc);
    pair_set_free(&d->cur);
    pair_set_free(&d->spare);
    for (int L = 0; L < NLEVEL; L++) {
        free(d->lv_start[L]);
        free(d->lv_list[L]);
    }
    free(d->off); free(d->fill);
    free(d->cell_of); free(d->level);
    free(d->blk);
    free(d);
}

gp_status gp_dem3d_create(const gp_dem3d_params *p, const double *xyzr, size_t n,
                          const double lo[3], const double hi[3], gp_dem3d **out, gp_error *err)
{
    *out = NULL;
    if (!p || !xyzr || !lo || !hi)
        return gp_error_set(err, GP_ERR_INVALID, "dem3d: NULL argument");
    if (n == 0 || n > UINT32_MAX / 2)
        return gp_error_set(err, GP_ERR_INVALID, "dem3d: sphere count %zu out of range", n);
    if (!(p->density > 0) || !(p->young > 0) || !(p->ks_kn >= 0) || !(p->friction_deg >= 0)
        || !(p->friction_deg < 90) || !(p->damping >= 0) || !(p->damping < 1))
        return gp_error_set(err, GP_ERR_INVALID, "dem3d: material out of range");
    for (int a = 0; a < 3; a++)
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || !(hi[a] > lo[a]) || !isfinite(p->gravity[a]))
            return gp_error_set(err, GP_ERR_INVALID, "dem3d: box axis %d is empty", a);
    gp_dem3d *d = calloc(1, sizeof *d);
    if (!d)
        return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory");
    d->n = n;
    d->x = malloc(3 * n * sizeof *d->x);
    d->v = calloc(3 * n, sizeof *d->v);
    d->w = calloc(3 * n, sizeof *d->w);
    d->xref = malloc(3 * n * sizeof *d->xref);
    d->r0 = malloc(n * sizeof *d->r0);
    d->r = malloc(n * sizeof *d->r);
    d->m = malloc(n * sizeof *d->m);
    d->minv = malloc(n * sizeof *d->minv);
    d->iinv = malloc(n * sizeof *d->iinv);
    d->mtinv = malloc(n * sizeof *d->mtinv);
    d->af = malloc(3 * n * sizeof *d->af);
    d->at = malloc(3 * n * sizeof *d->at);
    d->afn = malloc(n * sizeof *d->afn);
    d->anear = malloc(n);
    d->off = calloc(n + 1, sizeof *d->off);
    d->fill = malloc(n * sizeof *d->fill);
    d->cell_of = malloc(n * sizeof *d->cell_of);
    d->level = malloc(n * sizeof *d->level);
    d->nblk = (n + BLK - 1) / BLK;
    d->blk = calloc(d->nblk, sizeof *d->blk);
    if (!d->x || !d->v || !d->w || !d->xref || !d->r0 || !d->r || !d->m || !d->minv || !d->iinv
        || !d->mtinv || !d->af || !d->at || !d->afn || !d->anear || !d->off || !d->fill
        || !d->cell_of || !d->level || !d->blk) {
        gp_dem3d_destroy(d);
        return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory (%zu spheres)", n);
    }
    d->r0min = INFINITY;
    for (size_t i = 0; i < n; i++) {
        const double *s = xyzr + 4 * i;
        if (!isfinite(s[0]) || !isfinite(s[1]) || !isfinite(s[2]) || !(s[3] > 0) || !isfinite(s[3])) {
            gp_dem3d_destroy(d);
            return gp_error_set(err, GP_ERR_INVALID, "dem3d: sphere %zu is not finite or has r <= 0", i);
        }
        for (int a = 0; a < 3; a++)
            d->x[3 * i + a] = s[a];
        d->r0[i] = d->r[i] = s[3];
        if (s[3] > d->r0max) d->r0max = s[3];
        if (s[3] < d->r0min) d->r0min = s[3];
    }
    d->E = p->young;
    d->ks_kn = p->ks_kn;
    d->tanphi = tan(p->friction_deg * M_PI / 180);
    d->damping = p->damping;
    memcpy(d->g, p->gravity, sizeof d->g);
    d->rscale = d->rscale_ref = 1;
    d->skin = p->skin > 0 ? p->skin : 0.2 * d->r0min;
    d->free_gap = FREE_GAP * d->r0min;
    for (int a = 0; a < 3; a++) {
        d->wall[2 * a] = lo[a];
        d->wall[2 * a + 1] = hi[a];
    }
    /* masses and the time step (density scaling, see the header) */
    double safety = p->dt_safety > 0 ? p->dt_safety : 0.2;
    double rs = p->scaled_radius > 0 ? p->scaled_radius : 0;
    double tmin = INFINITY;
    for (size_t i = 0; i < n; i++) {
        double r = d->r0[i];
        double m = 4.0 / 3.0 * M_PI * r * r * r * p->density;
        double mi = m;
        if (rs > r) {
            double ms = 4.0 / 3.0 * M_PI * rs * rs * rs * p->density;
            mi = ms * r / rs; /* sqrt(mi / (2 E r)) = sqrt(ms / (2 E rs)) */
        }
        d->m[i] = m;
        d->mtinv[i] = 1.0 / m;
        d->minv[i] = 1.0 / mi;
        d->iinv[i] = 1.0 / (0.4 * mi * r * r);
        double t = sqrt(mi / (2 * d->E * r));
        if (t < tmin) tmin = t;
    }
    d->dt = safety * tmin;
    for (int w = 0; w < 6; w++)
        d->servo_lim[w] = NAN;
    d->need_rebuild = 1;
    d->stability = HUGE_VAL;
    if (pool_start(d, p->threads) != 0
        || !(d->tnc = calloc((size_t)(p->threads > 1 ? p->threads : 1), sizeof *d->tnc))) {
        gp_dem3d_destroy(d);
        return gp_error_set(err, GP_ERR_NOMEM, "dem3d: cannot start threads");
    }
    *out = d;
    return GP_OK;
}

double gp_dem3d_dt(const gp_dem3d *d) { return d->dt; }
void gp_dem3d_set_friction(gp_dem3d *d, double deg) { d->tanphi = tan(deg * M_PI / 180); }
void gp_dem3d_set_damping(gp_dem3d *d, double c) { d->damping = c; }
double gp_dem3d_wall(const gp_dem3d *d, int w) { return d->wall[w]; }

void gp_dem3d_set_radius_scale(gp_dem3d *d, double s)
{
    d->rscale = s;
    for (size_t i = 0; i < d->n; i++)
        d->r[i] = d->r0[i] * s;
    if (s < d->rscale_ref) /* shrinking never misses a contact, but keep the reference honest */
        d->rscale_ref = s;
}

void gp_dem3d_set_servo(gp_dem3d *d, int w, double force, double vmax)
{
    d->servo_f[w] = force > 0 ? force : 0;
    d->servo_v[w] = vmax;
}

void gp_dem3d_set_servo_limit(gp_dem3d *d, int w, double pos)
{
    d->servo_lim[w] = pos;
}

/* ------------------------------------------------------------------ neighbour list */


/* One grid per size level (level L holds radii in (rmax / 2^(L+1), rmax / 2^L], NLEVEL
 * levels); cells of level L are as wide as the largest pair reach of the level, so a wide size
 * range does not make the small spheres scan cells sized for the largest ones. */
typedef struct level_grid {
    size_t g[3], n;
    double lo[3], inv[3], cs, rmax;
    size_t *start, *list;
} level_grid;

static int grow_size_t(size_t **buf, size_t *cap, size_t need)
{
    if (need <= *cap)
        return 0;
    size_t c = need + need / 4 + 64;
    size_t *b = realloc(*buf, c * sizeof *b);
    if (!b)
        return -1;
    *buf = b;
    *cap = c;
    return 0;
}

/* The cell grids of the rebuild, one per size level, over the spheres' extent: each sphere's
 * level (d->level) and cell (d->cell_of), and each grid's spheres by cell (start / list, in
 * the buffers d keeps between rebuilds). reach: the gap below which a pair is listed. */
static gp_status level_grids(gp_dem3d *d, level_grid lv[NLEVEL], double reach, gp_error *err)
{
    size_t n = d->n;
    double rmax = d->r0max * d->rscale;
    double ext_lo[3], ext_hi[3];
    for (int a = 0; a < 3; a++) {
        /* spheres may sit slightly outside a wall: the grid covers the spheres' extent */
        double mn = d->wall[2 * a], mx = d->wall[2 * a + 1];
        for (size_t i = 0; i < n; i++) {
            double c = d->x[3 * i + a];
            if (c < mn) mn = c;
            if (c > mx) mx = c;
        }
        ext_lo[a] = mn;
        ext_hi[a] = mx;
    }
    memset(lv, 0, NLEVEL * sizeof *lv);
    unsigned char *lev = d->level;
    for (size_t i = 0; i < n; i++) {
        int L = 0;
        double r = d->r[i];
        while (L < NLEVEL - 1 && r <= 0.5 * rmax / (double)(1u << L))
            L++;
        lev[i] = (unsigned char)L;
        lv[L].n++;
        if (r > lv[L].rmax) lv[L].rmax = r;
    }
    size_t *cellbuf = d->cell_of; /* cell index of each sphere in its level */
    for (int L = 0; L < NLEVEL; L++) {
        level_grid *G = lv + L;
        if (!G->n)
            continue;
        G->cs = 2 * G->rmax + reach;
        for (int a = 0; a < 3; a++) {
            double e = ext_hi[a] - ext_lo[a];
            double ga = floor(e / G->cs);
            if (ga < 1) ga = 1;
            if (ga > 2048) ga = 2048;
            G->g[a] = (size_t)ga;
        }
        while (G->g[0] * G->g[1] * G->g[2] > 2 * G->n + 64) {
            int a = G->g[0] >= G->g[1] && G->g[0] >= G->g[2] ? 0 : (G->g[1] >= G->g[2] ? 1 : 2);
            G->g[a] = (G->g[a] + 1) / 2;
        }
        for (int a = 0; a < 3; a++) {
            double e = ext_hi[a] - ext_lo[a];
            G->lo[a] = ext_lo[a];
            G->inv[a] = e > 0 ? (double)G->g[a] / e : 0;
        }
        size_t nc = G->g[0] * G->g[1] * G->g[2];
        if (grow_size_t(&d->lv_start[L], &d->lv_start_cap[L], nc + 1)
            || grow_size_t(&d->lv_list[L], &d->lv_list_cap[L], G->n))
            return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory (cells)");
        G->start = d->lv_start[L];
        G->list = d->lv_list[L];
        memset(G->start, 0, (nc + 1) * sizeof *G->start);
    }
    for (size_t i = 0; i < n; i++) {
        level_grid *G = lv + lev[i];
        size_t c[3];
        for (int a = 0; a < 3; a++) {
            long k = (long)((d->x[3 * i + a] - G->lo[a]) * G->inv[a]);
            if (k < 0) k = 0;
            if (k >= (long)G->g[a]) k = (long)G->g[a] - 1;
            c[a] = (size_t)k;
        }
        cellbuf[i] = (c[2] * G->g[1] + c[1]) * G->g[0] + c[0];
        G->start[cellbuf[i] + 1]++;
    }
    for (int L = 0; L < NLEVEL; L++) {
        level_grid *G = lv + L;
        if (!G->n)
            continue;
        size_t nc = G->g[0] * G->g[1] * G->g[2];
        for (size_t c = 0; c < nc; c++)
            G->start[c + 1] += G->start[c];
    }
    for (size_t i = 0; i < n; i++) { /* fill (start is used as the cursor, then shifted back) */
        level_grid *G = lv + lev[i];
        G->list[G->start[cellbuf[i]]++] = i;
    }
    for (int L = 0; L < NLEVEL; L++) {
        level_grid *G = lv + L;
        if (!G->n)
            continue;
        size_t nc = G->g[0] * G->g[1] * G->g[2];
        for (size_t c = nc; c > 0; c--)
            G->start[c] = G->start[c - 1];
        G->start[0] = 0;
    }
    return GP_OK;
}

/* Appends the pair (a, b) to d->raw when its gap is below reach. The test is written on
 * (min, max) so that it gives the same bits whichever sphere found the pair. */
static int try_pair(gp_dem3d *d, size_t a, size_t b, double reach, size_t *m)
{
    size_t i = a < b ? a : b, j = a < b ? b : a;
    const double *x = d->x;
    double ex = x[3 * j] - x[3 * i], ey = x[3 * j + 1] - x[3 * i + 1];
    double ez = x[3 * j + 2] - x[3 * i + 2];
    double rr = d->r[i] + reach + d->r[j];
    if (!(ex * ex + ey * ey + ez * ez < rr * rr))
        return 0;
    if (*m == d->raw_cap) {
        size_t c = d->raw_cap + d->raw_cap / 2 + 1024;
        uint32_t *b2 = realloc(d->raw, 2 * c * sizeof *b2);
        if (!b2)
            return -1;
        d->raw = b2;
        d->raw_cap = c;
    }
    d->raw[2 * *m] = (uint32_t)i;
    d->raw[2 * *m + 1] = (uint32_t)j;
    (*m)++;
    return 0;
}

/* Pairs within one level: a cell is at least as wide as the level's largest pair reach, so
 * each pair lies in one cell or two adjacent ones; each is seen once, from its own cell or
 * from the first of the two in the order of the 13 forward neighbours. */
static int level_pairs(gp_dem3d *d, const level_grid *G, double reach, size_t *m)
{
    static const int fwd[13][3] = {{1, 0, 0},  {-1, 1, 0}, {0, 1, 0},  {1, 1, 0},  {-1, -1, 1},
                                   {0, -1, 1}, {1, -1, 1}, {-1, 0, 1}, {0, 0, 1},  {1, 0, 1},
                                   {-1, 1, 1}, {0, 1, 1},  {1, 1, 1}};
    for (size_t z = 0; z < G->g[2]; z++)
        for (size_t y = 0; y < G->g[1]; y++)
            for (size_t xx = 0; xx < G->g[0]; xx++) {
                size_t c = (z * G->g[1] + y) * G->g[0] + xx;
                for (size_t p = G->start[c]; p < G->start[c + 1]; p++) {
                    size_t a = G->list[p];
                    for (size_t q = p + 1; q < G->start[c + 1]; q++)
                        if (try_pair(d, a, G->list[q], reach, m))
                            return -1;
                    for (int o = 0; o < 13; o++) {
                        long cx = (long)xx + fwd[o][0], cy = (long)y + fwd[o][1];
                        long cz = (long)z + fwd[o][2];
                        if (cx < 0 || cy < 0 || cx >= (long)G->g[0] || cy >= (long)G->g[1]
                            || cz >= (long)G->g[2])
                            continue;
                        size_t c2 = ((size_t)cz * G->g[1] + (size_t)cy) * G->g[0] + (size_t)cx;
                        for (size_t q = G->start[c2]; q < G->start[c2 + 1]; q++)
                            if (try_pair(d, a, G->list[q], reach, m))
                                return -1;
                    }
                }
            }
    return 0;
}

/* Pairs of a sphere i with the spheres of a coarser level G (seen from the smaller sphere
 * only, so once): the cells within its reach plus G's largest radius. */
static int cross_pairs(gp_dem3d *d, size_t i, const level_grid *G, double reach, size_t *m)
{
    const double *xi = d->x + 3 * i;
    double R = d->r[i] + reach + G->rmax;
    long c0[3], c1[3];
    for (int a = 0; a < 3; a++) {
        c0[a] = (long)floor((xi[a] - R - G->lo[a]) * G->inv[a]);
        c1[a] = (long)floor((xi[a] + R - G->lo[a]) * G->inv[a]);
        if (c0[a] < 0) c0[a] = 0;
        if (c1[a] >= (long)G->g[a]) c1[a] = (long)G->g[a] - 1;
    }
    for (long z = c0[2]; z <= c1[2]; z++)
        for (long y = c0[1]; y <= c1[1]; y++)
            for (long xx = c0[0]; xx <= c1[0]; xx++) {
                size_t c = ((size_t)z * G->g[1] + (size_t)y) * G->g[0] + (size_t)xx;
                for (size_t k = G->start[c]; k < G->start[c + 1]; k++)
                    if (try_pair(d, i, G->list[k], reach, m))
                        return -1;
            }
    return 0;
}

/* The m pairs of d->raw into P sorted by (i, j): counted by i (d->off), then each sphere's
 * handful of partners by insertion. */
static void sort_pairs(gp_dem3d *d, pair_set *P, size_t m)
{
    size_t n = d->n;
    memset(d->off, 0, (n + 1) * sizeof *d->off);
    for (size_t k = 0; k < m; k++)
        d->off[d->raw[2 * k] + 1]++;
    for (size_t i = 0; i < n; i++)
        d->off[i + 1] += d->off[i];
    memcpy(d->fill, d->off, n * sizeof *d->fill);
    for (size_t k = 0; k < m; k++) {
        size_t e = d->fill[d->raw[2 * k]]++;
        P->pi[e] = d->raw[2 * k];
        P->pj[e] = d->raw[2 * k + 1];
    }
    for (size_t i = 0; i < n; i++)
        for (size_t k = d->off[i] + 1; k < d->off[i + 1]; k++) {
            uint32_t v = P->pj[k];
            size_t q = k;
            while (q > d->off[i] && P->pj[q - 1] > v) {
                P->pj[q] = P->pj[q - 1];
                q--;
            }
            P->pj[q] = v;
        }
}

/* The candidate pairs (i < j, gap below reach) into P (grown as needed), sorted by (i, j);
 * *np of them. Each pair is looked at once: within a level by forward cells, across levels
 * from the smaller sphere. */
static gp_status find_candidates(gp_dem3d *d, const level_grid lv[NLEVEL], double reach,
                                 pair_set *P, size_t *np_out, gp_error *err)
{
    size_t m = 0;
    for (int L = 0; L < NLEVEL; L++) {
        const level_grid *G = lv + L;
        if (!G->n)
            continue;
        if (level_pairs(d, G, reach, &m))
            return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory (pairs)");
        size_t ncell = G->g[0] * G->g[1] * G->g[2];
        for (size_t p = 0; p < G->start[ncell]; p++)
            for (int L2 = 0; L2 < L; L2++)
                if (lv[L2].n && cross_pairs(d, G->list[p], lv + L2, reach, &m))
                    return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory (pairs)");
    }
    if (pair_set_reserve(P, m))
        return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory (pairs)");
    sort_pairs(d, P, m);
    *np_out = m;
    return GP_OK;
}

/* The shear springs (and the contact state) of the list in use carried over to the np pairs
 * of P by (i, j): both lists are sorted by (i, j). */
static void carry_springs(const gp_dem3d *d, pair_set *P, size_t np)
{
    memset(P->fs, 0, 3 * np * sizeof *P->fs);
    memset(P->fn, 0, np * sizeof *P->fn);
    size_t o = 0;
    for (size_t k = 0; k < np && o < d->np; k++) {
        while (o < d->np && (d->pi[o] < P->pi[k] || (d->pi[o] == P->pi[k] && d->pj[o] < P->pj[k])))
            o++;
        if (o < d->np && d->pi[o] == P->pi[k] && d->pj[o] == P->pj[k]) {
            memcpy(P->fs + 3 * k, d->pfs + 3 * o, 3 * sizeof *P->fs);
            P->fn[k] = d->pfn[o]; /* job_pairs clears the spring of a contact that opens */
        }
    }
}

/* Each sphere's list of the np pairs of P, in pair order: d->off (offsets), P->adj. */
static void pair_adjacency(gp_dem3d *d, pair_set *P, size_t np)
{
    size_t n = d->n;
    memset(d->off, 0, (n + 1) * sizeof *d->off);
    for (size_t k = 0; k < np; k++) {
        d->off[P->pi[k] + 1]++;
        d->off[P->pj[k] + 1]++;
    }
    for (size_t i = 0; i < n; i++)
        d->off[i + 1] += d->off[i];
    memcpy(d->fill, d->off, n * sizeof *d->fill);
    for (size_t k = 0; k < np; k++) {
        P->adj[d->fill[P->pi[k]]++] = k << 1;
        P->adj[d->fill[P->pj[k]]++] = (k << 1) | 1;
    }
}

/* Rebuilds the candidate pair list, sorted by (i, j); shear springs are carried over by
 * (i, j). Buffers are kept from one rebuild to the next (no allocation in the steady state):
 * the new list is built in the spare buffers, which then become the list in use. */
static gp_status rebuild(gp_dem3d *d, gp_error *err)
{
    size_t n = d->n;
    /* a pair is listed when its gap is below the skin plus free_gap: job_spheres then sees
     * every surface within free_gap until a sphere has moved half the skin */
    const double reach = d->skin + d->free_gap;
    level_grid lv[NLEVEL];
    gp_status st = level_grids(d, lv, reach, err);
    if (st)
        return st;
    pair_set *P = &d->spare;
    if (pair_set_reserve(P, d->np > 0 ? d->np + d->np / 4 + 64 : 8 * n + 64))
        return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory (pairs)");
    size_t np = 0;
    if ((st = find_candidates(d, lv, reach, P, &np, err)))
        return st;
    carry_springs(d, P, np);
    if (threaded(d)) /* one thread sums the forces in the pair loop (step_forces) */
        pair_adjacency(d, P, np);
    pair_set t = d->cur;
    d->cur = *P;
    *P = t;
    d->np = np;
    d->pi = d->cur.pi; d->pj = d->cur.pj; d->pfs = d->cur.fs; d->pF = d->cur.F;
    d->pc = d->cur.c; d->pfn = d->cur.fn; d->adj = d->cur.adj;
    memcpy(d->xref, d->x, 3 * n * sizeof *d->x);
    d->rscale_ref = d->rscale;
    d->need_rebuild = 0;
    d->rebuilds++;
    return GP_OK;
}

/* ------------------------------------------------------------------ one step */

/* what every pair of a step shares */
typedef struct pair_consts {
    double E2, ksr, mu, dt, gap;
} pair_consts;

static pair_consts consts_of(const gp_dem3d *d)
{
    pair_consts q = {2 * d->E, d->ks_kn, d->tanphi, d->dt, d->free_gap};
    return q;
}

/* Candidate pair k = (i, j) (Eqs. 1-3): updates its shear spring and its f_n (d->pfn: > 0
 * touching, -1 within free_gap, 0 beyond; job_spheres reads -1 as "not in free flight") and,
 * when the spheres touch, returns 1 with the force on i in F and n x f_s in c (the moment of
 * the pair on either sphere is that sphere's radius times c). */
static inline int pair_force(gp_dem3d *d, const pair_consts *q, size_t k, size_t i, size_t j,
                             double F[3], double c[3])
{
    const double *x = d->x, *v = d->v, *w = d->w, *r = d->r;
    double dx = x[3 * j] - x[3 * i], dy = x[3 * j + 1] - x[3 * i + 1];
    double dz = x[3 * j + 2] - x[3 * i + 2];
    double ri = r[i], rj = r[j], R = ri + rj;
    double d2 = dx * dx + dy * dy + dz * dz;
    double *fs = d->pfs + 3 * k;
    if (d2 >= R * R || d2 == 0) {
        /* the spring goes when the contact opens */
        if (d->pfn[k] > 0)
            fs[0] = fs[1] = fs[2] = 0;
        double rg = R + q->gap;
        d->pfn[k] = d2 < rg * rg ? -1 : 0;
        return 0;
    }
    double dist = sqrt(d2), id = 1.0 / dist;
    double nx = dx * id, ny = dy * id, nz = dz * id;
    double ov = R - dist;
    double kn = q->E2 * ri * rj / R;
    double fn = kn * ov;
    /* contact-point velocities: i at +ri n, j at -rj n */
    const double *vi = v + 3 * i, *vj = v + 3 * j, *wi = w + 3 * i, *wj = w + 3 * j;
    double vrx = vi[0] - vj[0] + ri * (wi[1] * nz - wi[2] * ny) + rj * (wj[1] * nz - wj[2] * ny);
    double vry = vi[1] - vj[1] + ri * (wi[2] * nx - wi[0] * nz) + rj * (wj[2] * nx - wj[0] * nz);
    double vrz = vi[2] - vj[2] + ri * (wi[0] * ny - wi[1] * nx) + rj * (wj[0] * ny - wj[1] * nx);
    double vn = vrx * nx + vry * ny + vrz * nz;
    double vtx = vrx - vn * nx, vty = vry - vn * ny, vtz = vrz - vn * nz;
    /* keep the spring tangent (rotate with the contact, same magnitude) */
    double sx = fs[0], sy = fs[1], sz = fs[2];
    double s2 = sx * sx + sy * sy + sz * sz;
    if (s2 > 0) {
        double sn = sx * nx + sy * ny + sz * nz;
        sx -= sn * nx; sy -= sn * ny; sz -= sn * nz;
        double t2 = sx * sx + sy * sy + sz * sz;
        if (t2 > 0) {
            double f = sqrt(s2 / t2);
            sx *= f; sy *= f; sz *= f;
        }
    }
    double ks = q->ksr * kn;
    sx -= ks * vtx * q->dt; sy -= ks * vty * q->dt; sz -= ks * vtz * q->dt;
    double smax = q->mu * fn;
    double ss = sx * sx + sy * sy + sz * sz;
    if (ss > smax * smax) {
        double f = ss > 0 ? smax / sqrt(ss) : 0;
        sx *= f; sy *= f; sz *= f;
    }
    fs[0] = sx; fs[1] = sy; fs[2] = sz;
    F[0] = -fn * nx + sx;
    F[1] = -fn * ny + sy;
    F[2] = -fn * nz + sz;
    c[0] = ny * sz - nz * sy;
    c[1] = nz * sx - nx * sz;
    c[2] = nx * sy - ny * sx;
    d->pfn[k] = fn;
    return 1;
}

/* sums of sphere i before its pairs: gravity on the true mass, nothing else */
static void sums_start(gp_dem3d *d, size_t i)
{
    double m = d->m[i];
    for (int a = 0; a < 3; a++) {
        d->af[3 * i + a] = m * d->g[a];
        d->at[3 * i + a] = 0;
    }
    d->afn[i] = 0;
    d->anear[i] = 0;
}

/* One thread: every pair once, in pair order, its force added to both spheres' sums at once
 * (a sphere's sums thus run over its pairs in pair order, as the threaded gather does: the
 * same bits). The forces on i stay in d->pF for gp_dem3d_contacts. Returns the contacts. */
static size_t forces_serial(gp_dem3d *d)
{
    const pair_consts q = consts_of(d);
    double *restrict af = d->af, *restrict at = d->at, *restrict afn = d->afn;
    const uint32_t *pi = d->pi, *pj = d->pj;
    const double *r = d->r;
    size_t nc = 0;
    for (size_t i = 0; i < d->n; i++)
        sums_start(d, i);
    for (size_t k = 0; k < d->np; k++) {
        size_t i = pi[k], j = pj[k];
        double F[3], c[3];
        if (!pair_force(d, &q, k, i, j, F, c)) {
            if (d->pfn[k] < 0)
                d->anear[i] = d->anear[j] = 1;
            continue;
        }
        double fn = d->pfn[k], ri = r[i], rj = r[j];
        for (int a = 0; a < 3; a++) {
            d->pF[3 * k + a] = F[a];
            af[3 * i + a] += F[a];
            af[3 * j + a] -= F[a];
            at[3 * i + a] += ri * c[a];
            at[3 * j + a] += rj * c[a];
        }
        afn[i] += fn;
        afn[j] += fn;
        nc++;
    }
    return nc;
}

/* threads, first half: each thread a range of pairs; force and n x f_s kept per pair */
static void job_pairs(gp_dem3d *d, int tid, int nt)
{
    const pair_consts q = consts_of(d);
    size_t np = d->np, nc = 0;
    size_t k0 = np * (size_t)tid / (size_t)nt, k1 = np * (size_t)(tid + 1) / (size_t)nt;
    for (size_t k = k0; k < k1; k++)
        nc += (size_t)pair_force(d, &q, k, d->pi[k], d->pj[k], d->pF + 3 * k, d->pc + 3 * k);
    d->tnc[tid] = nc;
}

/* threads, second half: each sphere's sums gathered from its pairs in pair order (d->adj) */
static void job_gather(gp_dem3d *d, int tid, int nt)
{
    const double *restrict pfn = d->pfn, *restrict pF = d->pF, *restrict pc = d->pc;
    const size_t *restrict adj = d->adj, *restrict off = d->off;
    for (size_t b = (size_t)tid; b < d->nblk; b += (size_t)nt) {
        size_t i0 = b * BLK, i1 = i0 + BLK < d->n ? i0 + BLK : d->n;
        for (size_t i = i0; i < i1; i++) {
            double ri = d->r[i];
            double *F = d->af + 3 * i, *T = d->at + 3 * i;
            sums_start(d, i);
            for (size_t e = off[i]; e < off[i + 1]; e++) {
                size_t k = adj[e] >> 1;
                double fn = pfn[k];
                if (fn <= 0) { /* not touching (an overlap always has f_n > 0); -1: near */
                    d->anear[i] |= fn < 0;
                    continue;
                }
                const double *Fk = pF + 3 * k, *ck = pc + 3 * k;
                double sg = (adj[e] & 1) ? -1 : 1;
                for (int a = 0; a < 3; a++) {
                    F[a] += sg * Fk[a];
                    T[a] += ri * ck[a];
                }
                d->afn[i] += fn;
            }
        }
    }
}

/* The step's force and moment sums of every sphere (d->af, d->at, d->afn, d->anear); returns
 * the sphere-sphere contacts. */
static size_t step_forces(gp_dem3d *d)
{
    if (!threaded(d))
        return forces_serial(d);
    run_job(d, job_pairs);
    run_job(d, job_gather);
    size_t nc = 0;
    for (int t = 0; t < d->pool.nt; t++)
        nc += d->tnc[t];
    return nc;
}

/* Local damping: the force times dm = 1 - c where it does work (f v > 0), times dp = 1 + c
 * where it brakes, unchanged where f v = 0. Written as selects, which the compiler makes
 * branch-free: the sign of f v is a coin toss. */
static inline double sgn_damp(double f, double v, double dm, double dp)
{
    double p = f * v;
    double k = p > 0 ? dm : 1.0;
    k = p < 0 ? dp : k;
    return f * k;
}

/* The walls' forces on sphere i added to F and to the block's wall sums; returns the sum of
 * their normal forces and sets *near when a wall is within free_gap. */
static double wall_forces(const gp_dem3d *d, size_t i, double F[3], blk_acc *acc, int *near)
{
    const double E2 = 2 * d->E, gap = d->free_gap, *x = d->x + 3 * i, *wall = d->wall;
    double ri = d->r[i], sfn = 0;
    for (int a = 0; a < 3; a++) {
        double dl = x[a] - wall[2 * a];
        if (dl < ri) {
            double f = E2 * ri * (ri - dl);
            F[a] += f;
            acc->wf[2 * a] += f;
            acc->wk[2 * a] += E2 * ri;
            acc->wn++;
            sfn += f;
        }
        double dh = wall[2 * a + 1] - x[a];
        if (dh < ri) {
            double f = E2 * ri * (ri - dh);
            F[a] -= f;
            acc->wf[2 * a + 1] += f;
            acc->wk[2 * a + 1] += E2 * ri;
            acc->wn++;
            sfn += f;
        }
        *near |= (dl < ri + gap) | (dh < ri + gap);
    }
    return sfn;
}

/* t[0] >= t[1]: the two largest values seen */
static inline void top2(double t[2], double v)
{
    if (v > t[1]) {
        if (v > t[0]) {
            t[1] = t[0];
            t[0] = v;
        } else {
            t[1] = v;
        }
    }
}

/* Per sphere: the walls, S_c's sums, local damping and the leapfrog step; the block's sums
 * (fixed blocks of BLK spheres, whatever the thread count) and its two largest moves. */
static void job_spheres(gp_dem3d *d, int tid, int nt)
{
    const double dt = d->dt, dm = 1 - d->damping, dp = 1 + d->damping;
    const double dscale = d->rscale > d->rscale_ref ? d->rscale - d->rscale_ref : 0;
    const double *wall = d->wall;
    for (size_t b = (size_t)tid; b < d->nblk; b += (size_t)nt) {
        blk_acc *acc = d->blk + b;
        memset(acc, 0, sizeof *acc);
        size_t i0 = b * BLK, i1 = i0 + BLK < d->n ? i0 + BLK : d->n;
        for (size_t i = i0; i < i1; i++) {
            double *x = d->x + 3 * i, *v = d->v + 3 * i, *w = d->w + 3 * i;
            const double *T = d->at + 3 * i;
            double ri = d->r[i], m = d->m[i];
            double F[3] = {d->af[3 * i], d->af[3 * i + 1], d->af[3 * i + 2]};
            int near = d->anear[i];
            double sfn = d->afn[i];
            sfn += wall_forces(d, i, F, acc, &near);
            if (d->measure) { /* read only after a run: summed on its last step */
                acc->sum_f += sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]);
                acc->sum_fn += sfn;
            }
            /* free flight: nothing within free_gap, so no contact stiffness for density scaling
             * to serve and no oscillation for local damping to take out; the sphere falls with
             * its true mass, undamped (see the top of this file) */
            int fly = !(near || sfn > 0);
            double mi = (fly ? d->mtinv[i] : d->minv[i]) * dt, ii = d->iinv[i] * dt;
            double fm = fly ? 1.0 : dm, fp = fly ? 1.0 : dp; /* free flight: no damping */
            double d2 = 0;
            for (int a = 0; a < 3; a++) {
                v[a] += sgn_damp(F[a], v[a], fm, fp) * mi;
                w[a] += sgn_damp(T[a], w[a], dm, dp) * ii;
                x[a] += v[a] * dt;
                double e = x[a] - d->xref[3 * i + a];
                d2 += e * e;
            }
            if (d->measure) {
                double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                acc->ke += 0.5 * m * v2;
                if (v2 > acc->vmax2) acc->vmax2 = v2;
            }
            double mv = d2; /* the distance a gap may have closed by this sphere, squared */
            if (dscale > 0) {
                double e = sqrt(d2) + dscale * d->r0[i];
                mv = e * e;
            }
            top2(acc->move, mv);
            /* a velocity that is not finite makes x so (or far outside the box) at once */
            for (int a = 0; a < 3; a++) /* outside, or not a number */
                acc->bad |= !(x[a] > wall[2 * a] - ri) | !(x[a] < wall[2 * a + 1] + ri);
        }
    }
}

void gp_dem3d_set_cancel(gp_dem3d *d, const volatile int *cancel) { d->cancel = cancel; }

gp_status gp_dem3d_run(gp_dem3d *d, long nsteps, gp_error *err)
{
    for (long s = 0; s < nsteps; s++) {
        d->measure = s + 1 == nsteps;
        /* once a step: a step over N spheres costs ~N / 4e6 s, so a chunk of 100 steps of a
         * 400,000-sphere sample would otherwise run 10 s past a cancel; one relaxed load a
         * step costs nothing next to it, and the state stays that of the steps completed */
        if (d->cancel && __atomic_load_n((const int *)d->cancel, __ATOMIC_RELAXED))
            return gp_error_set(err, GP_ERR_CANCELLED, "dem3d: cancelled after %ld steps",
                                d->steps);
        if (d->need_rebuild) {
            gp_status st = rebuild(d, err);
            if (st)
                return st;
        }
        size_t nc = step_forces(d), wn = 0;
        run_job(d, job_spheres);
        double sf = 0, sfn = 0, ke = 0, vm = 0;
        double wf[6] = {0}, wk[6] = {0};
        double move[2] = {0, 0};
        int bad = 0;
        for (size_t b = 0; b < d->nblk; b++) {
            const blk_acc *a = d->blk + b;
            sf += a->sum_f; sfn += a->sum_fn; ke += a->ke;
            if (a->vmax2 > vm) vm = a->vmax2;
            top2(move, a->move[0]);
            top2(move, a->move[1]);
            wn += a->wn; bad |= a->bad;
            for (int w = 0; w < 6; w++) {
                wf[w] += a->wf[w];
                wk[w] += a->wk[w];
            }
        }
        if (d->measure) {
            d->stability = sfn > 0 ? sf / sfn : HUGE_VAL;
            d->kinetic = ke;
            d->vmax = sqrt(vm);
        }
        d->ncontacts = nc;
        d->wall_n = wn;
        memcpy(d->wall_f, wf, sizeof wf);
        memcpy(d->wall_k, wk, sizeof wk);
        d->steps++;
        d->time += d->dt;
        if (bad)
            return gp_error_set(err, GP_ERR_DEGENERATE,
                                "dem3d: a sphere left the box or diverged at step %ld (time step too "
                                "large for the loading?)", d->steps);
        /* servo walls (Eq. 10) */
        for (int w = 0; w < 6; w++) {
            if (d->servo_f[w] <= 0)
                continue;
            double lim = d->servo_v[w] * d->dt;
            double mv = wk[w] > 0 ? SERVO_GAIN * (d->servo_f[w] - wf[w]) / wk[w] : lim;
            if (mv > lim) mv = lim;
            if (mv < -lim) mv = -lim;
            d->wall[w] += (w & 1) ? -mv : mv;
            if (!isnan(d->servo_lim[w])) {
                if ((w & 1) && d->wall[w] < d->servo_lim[w])
                    d->wall[w] = d->servo_lim[w];
                if (!(w & 1) && d->wall[w] > d->servo_lim[w])
                    d->wall[w] = d->servo_lim[w];
            }
        }
        /* a pair not listed had a gap of at least skin + free_gap: it cannot come within
         * free_gap before the two spheres that moved (and grew) most have together moved the
         * skin (a lone fast sphere, a fine falling through the pores, may go nearly the whole
         * skin) */
        if (sqrt(move[0]) + sqrt(move[1]) >= d->skin)
            d->need_rebuild = 1;
    }
    return GP_OK;
}

void gp_dem3d_get_state(const gp_dem3d *d, gp_dem3d_state *s)
{
    memset(s, 0, sizeof *s);
    s->steps = d->steps;
    s->time = d->time;
    s->stability = d->stability;
    s->kinetic = d->kinetic;
    s->vmax = d->vmax;
    memcpy(s->wall_force, d->wall_f, sizeof s->wall_force);
    s->contacts = d->ncontacts;
    s->wall_contacts = d->wall_n;
    s->rebuilds = d->rebuilds;
}

void gp_dem3d_spheres(const gp_dem3d *d, double *xyzr)
{
    for (size_t i = 0; i < d->n; i++) {
        xyzr[4 * i] = d->x[3 * i];
        xyzr[4 * i + 1] = d->x[3 * i + 1];
        xyzr[4 * i + 2] = d->x[3 * i + 2];
        xyzr[4 * i + 3] = d->r[i];
    }
}

gp_status gp_dem3d_contacts(const gp_dem3d *d, gp_contact3d **out, size_t *nout, gp_error *err)
{
    *out = NULL;
    *nout = 0;
    size_t cnt = 0;
    for (size_t k = 0; k < d->np; k++)
        cnt += d->pfn[k] > 0;
    for (size_t i = 0; i < d->n; i++)
        for (int a = 0; a < 3; a++) {
            cnt += d->x[3 * i + a] - d->wall[2 * a] < d->r[i];
            cnt += d->wall[2 * a + 1] - d->x[3 * i + a] < d->r[i];
        }
    gp_contact3d *c = malloc((cnt ? cnt : 1) * sizeof *c);
    if (!c)
        return gp_error_set(err, GP_ERR_NOMEM, "dem3d: out of memory (contacts)");
    size_t m = 0;
    for (size_t k = 0; k < d->np; k++) {
        if (!(d->pfn[k] > 0))
            continue;
        size_t i = d->pi[k], j = d->pj[k];
        double e[3], l2 = 0;
        for (int a = 0; a < 3; a++) {
            e[a] = d->x[3 * j + a] - d->x[3 * i + a];
            l2 += e[a] * e[a];
        }
        double l = sqrt(l2);
        c[m].i = i;
        c[m].j = (long)j;
        for (int a = 0; a < 3; a++) {
            c[m].normal[a] = e[a] / l;
            c[m].force[a] = d->pF[3 * k + a];
        }
        c[m].overlap = d->r[i] + d->r[j] - l;
        m++;
    }
    for (size_t i = 0; i < d->n; i++)
        for (int w = 0; w < 6; w++) {
            int a = w / 2;
            double dist = (w & 1) ? d->wall[w] - d->x[3 * i + a] : d->x[3 * i + a] - d->wall[w];
            double ri = d->r[i];
            if (!(dist < ri))
                continue;
            double f = 2 * d->E * ri * (ri - dist);
            c[m].i = i;
            c[m].j = -1 - w;
            memset(c[m].normal, 0, sizeof c[m].normal);
            memset(c[m].force, 0, sizeof c[m].force);
            c[m].normal[a] = (w & 1) ? 1 : -1;
            c[m].force[a] = (w & 1) ? -f : f;
            c[m].overlap = ri - dist;
            m++;
        }
    *out = c;
    *nout = m;
    return GP_OK;
}
