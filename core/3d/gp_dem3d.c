/* gp_dem3d.c -- see gp_dem3d.h.
 *
 * Details the header does not spell out:
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
 *    differs), and so is everything near contact; the fines of a wide sieve come to rest much
 *    sooner (docs/design/dem3d.md).
 *  - the candidate list holds the pairs with a gap below skin + free_gap, so a sphere sees
 *    every surface within free_gap until the two spheres that moved (or grew) most have
 *    together moved the skin: one fine falling through the pores at ~1 m/s may go nearly the
 *    whole skin alone. The skin only trades rebuilds against candidates: results do not
 *    depend on it (test_dem3d runs a skin 40 times smaller and compares the bits).
 *  - S_c, the kinetic energy and vmax are read only after a run, so only a run's last step
 *    sums them (a square root per sphere saved on every other step); the walls' forces and
 *    stiffnesses, which the servo needs, are summed on every step.
 *  - vectors: the pair kernel and the sphere step run on vectors of four doubles (GCC's
 *    generic vectors; an AVX2 clone picked at load time on x86-64, two SSE2 halves
 *    elsewhere), branch-free where a branch would be a coin toss; every lane does the IEEE
 *    operations of the scalar form in its order, so the bits are those of one sphere or pair
 *    at a time, and the same on any machine (-ffp-contract=off: no FMA).
 */
#include "gp_dem3d.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gp_grid.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define BLK 64          /* spheres per reduction block (fixed: results do not depend on threads) */
#define SERVO_GAIN 0.25 /* fraction of Eq. 10's displacement applied per step (of servo_dt) */
#define NLEVEL 8        /* size levels of the cell grids (see rebuild) */
#define FREE_GAP 0.05   /* free flight beyond this gap, times the smallest radius (see job_spheres) */
#define DT_CUT 0.9      /* a cut time step: this fraction of the proven limit (see check_dt) */

typedef struct blk_acc {
    double sum_f, sum_fn, ke, vmax2;
    double lam;      /* the largest per-sphere bound on omega^2 (see stiffness_weights) */
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

/* The arrays of one pair list (capacity cap pairs). The per-pair reals are component planes
 * (one array per component, all in one block) so that the pair kernel reads and writes them
 * with unit stride and the compiler vectorises it. The contents are never kept across a
 * reserve: a rebuild reserves the spare list, then fills all of it. */
enum { PS_FS = 0, PS_F = 3, PS_C = 6, PS_FN = 9, PS_WI = 10, PS_WJ = 11, PS_PLANES = 12 };

typedef struct pair_set {
    size_t cap;
    uint32_t *pi, *pj;
    double *buf;                   /* PS_PLANES planes of cap reals */
    double *fs[3], *F[3], *c[3];   /* shear spring, force on i, n x fs: planes of buf */
    double *fn;                    /* f_n (> 0 touching, -1 within free_gap, 0 beyond) */
    double *wi, *wj;               /* the pair's share of omega^2's bound on i and on j */
    uint32_t *idx;                 /* the touching pairs of a step (pair_kernel) */
    size_t *adj;
} pair_set;

static void pair_set_free(pair_set *p)
{
    free(p->pi); free(p->pj); free(p->buf); free(p->idx); free(p->adj);
    memset(p, 0, sizeof *p);
}

static int pair_set_reserve(pair_set *p, size_t cap)
{
    if (cap <= p->cap)
        return 0;
    cap += cap / 4 + 64;
    pair_set_free(p);
    p->pi = malloc(cap * sizeof *p->pi);
    p->pj = malloc(cap * sizeof *p->pj);
    p->buf = malloc(PS_PLANES * cap * sizeof *p->buf);
    p->idx = malloc(cap * sizeof *p->idx);
    p->adj = malloc(2 * cap * sizeof *p->adj);
    if (!p->pi || !p->pj || !p->buf || !p->idx || !p->adj) {
        pair_set_free(p);
        return -1;
    }
    for (int a = 0; a < 3; a++) {
        p->fs[a] = p->buf + (PS_FS + a) * cap;
        p->F[a] = p->buf + (PS_F + a) * cap;
        p->c[a] = p->buf + (PS_C + a) * cap;
    }
    p->fn = p->buf + PS_FN * cap;
    p->wi = p->buf + PS_WI * cap;
    p->wj = p->buf + PS_WJ * cap;
    p->cap = cap;
    return 0;
}

struct gp_dem3d {
    size_t n;
    double *x, *v, *w;         /* 3n (+ 1 double of padding: see gather3) */
    double *r0, *r;            /* full and current radii */
    double *m, *minv, *iinv;   /* true mass; inverse inertial mass and moment */
    double *xref;              /* positions at the last rebuild */
    double *mtinv;             /* 1 / true mass (free flight) */
    /* one thread's sums per sphere while a step runs, in pair order (see step_serial): force
     * (3n, starting from gravity), moment (3n), sum of f_n (n), the shares of the bound on
     * omega^2 (n), a surface within free_gap (n) */
    double *af, *at, *afn, *alam;
    unsigned char *anear;
    double rscale, rscale_ref, r0max, r0min;
    double E, ks_kn, tanphi, damping, g[3], dt, skin, free_gap;
    double *sminv;             /* sqrt(minv) (the bound's off-diagonal share) */
    double beta;               /* a contact's largest eigenvalue, times m_i / k_n (see header) */
    int dt_guard;              /* cut dt when the bound fails (not params.dt_unguarded) */
    double dt_exp;             /* params.dt_damping_exp: dt (1 + c)^dt_exp = dt_und */
    double dt_und;             /* dt (1 + c)^dt_exp, c the damping in force */
    double lam_max;            /* the bound on omega_max^2 at the last step */
    double dt_ratio;           /* the largest fraction of the proven limit a step has used */
    long dt_cuts;
    double wall[6];            /* positions: lo x, hi x, lo y, hi y, lo z, hi z */
    double servo_f[6], servo_v[6], servo_lim[6];
    double servo_s[6];         /* > 0: a stress servo (its force: this times the face area) */
    int servo_stress;          /* some wall has servo_s > 0 */
    double wall_v[6];          /* a prescribed wall velocity (m/s, along +axis) ... */
    int wall_vmode[6];         /* ... when this is set */
    double servo_dt;           /* SERVO_GAIN per step of this dt (0: per step, whatever dt) */
    double wall_f[6], wall_k[6];
    size_t wall_n;
    /* candidate pairs (i < j), sorted */
    size_t np;
    pair_set cur, spare;       /* the list in use, and the buffers the next rebuild fills */
    uint32_t *pi, *pj;         /* = cur.pi, cur.pj, cur.fn (short names) */
    double *pfn;
    size_t *ioff;              /* pairs of sphere i as the first: ioff[i] .. ioff[i + 1] - 1 */
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

/* more than one thread: forces per pair, then gathered per sphere (see step) */
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
    free(d->af); free(d->at); free(d->afn); free(d->alam); free(d->anear); free(d->sminv);
    free(d->raw); free(d->tnc);
    pair_set_free(&d->cur);
    pair_set_free(&d->spare);
    for (int L = 0; L < NLEVEL; L++) {
        free(d->lv_start[L]);
        free(d->lv_list[L]);
    }
    free(d->off); free(d->ioff); free(d->fill);
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
    /* one double past the last sphere: the kernel reads each sphere's x, y, z as four */
    d->x = calloc(3 * n + 1, sizeof *d->x);
    d->v = calloc(3 * n + 1, sizeof *d->v);
    d->w = calloc(3 * n + 1, sizeof *d->w);
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
    d->alam = malloc(n * sizeof *d->alam);
    d->sminv = malloc(n * sizeof *d->sminv);
    d->anear = malloc(n);
    d->off = calloc(n + 1, sizeof *d->off);
    d->ioff = calloc(n + 1, sizeof *d->ioff);
    d->fill = malloc(n * sizeof *d->fill);
    d->cell_of = malloc(n * sizeof *d->cell_of);
    d->level = malloc(n * sizeof *d->level);
    d->nblk = (n + BLK - 1) / BLK;
    d->blk = calloc(d->nblk, sizeof *d->blk);
    if (!d->x || !d->v || !d->w || !d->xref || !d->r0 || !d->r || !d->m || !d->minv || !d->iinv
        || !d->mtinv || !d->af || !d->at || !d->afn || !d->alam || !d->sminv || !d->anear
        || !d->off || !d->ioff || !d->fill || !d->cell_of || !d->level || !d->blk) {
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
        d->sminv[i] = sqrt(d->minv[i]);
        double t = sqrt(mi / (2 * d->E * r));
        if (t < tmin) tmin = t;
    }
    /* dt_damping_exp e: the step at damping c is dt_und / (1 + c)^e (e = 0.5: the same
     * fraction of the damped limit omega dt sqrt(1 + c) < 2 for any c; see the header) */
    d->dt_exp = p->dt_damping_exp > 0 ? p->dt_damping_exp : 0;
    d->dt_und = safety * tmin;
    d->dt = d->dt_exp > 0 ? d->dt_und / pow(1 + d->damping, d->dt_exp) : d->dt_und;
    /* a contact's largest eigenvalue times m_i / k_n: the normal mode (1), or the shear spring
     * at the contact point, which moves by u + r theta: k_s (1/m + r^2/I) = k_s (1 + 2.5) / m */
    d->beta = fmax(1.0, 3.5 * d->ks_kn);
    d->dt_guard = !p->dt_unguarded;
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
/* with dt_damping_exp the step follows c: dt_und (the last cut's included) / (1 + c)^e */
void gp_dem3d_set_damping(gp_dem3d *d, double c)
{
    d->damping = c;
    if (d->dt_exp > 0)
        d->dt = d->dt_und / pow(1 + c, d->dt_exp);
}

void gp_dem3d_reset_dt_ratio(gp_dem3d *d) { d->dt_ratio = 0; }
double gp_dem3d_wall(const gp_dem3d *d, int w) { return d->wall[w]; }

void gp_dem3d_set_radius_scale(gp_dem3d *d, double s)
{
    d->rscale = s;
    for (size_t i = 0; i < d->n; i++)
        d->r[i] = d->r0[i] * s;
    if (s < d->rscale_ref) /* shrinking never misses a contact, but keep the reference honest */
        d->rscale_ref = s;
}

/* whether some wall is a stress servo (the step then computes the faces' areas) */
static void servo_modes(gp_dem3d *d)
{
    d->servo_stress = 0;
    for (int w = 0; w < 6; w++)
        d->servo_stress |= d->servo_s[w] > 0;
}

void gp_dem3d_set_servo(gp_dem3d *d, int w, double force, double vmax)
{
    d->servo_f[w] = force > 0 ? force : 0;
    d->servo_v[w] = vmax;
    d->servo_s[w] = 0;
    d->wall_vmode[w] = 0;
    d->wall_v[w] = 0;
    servo_modes(d);
}

void gp_dem3d_set_servo_stress(gp_dem3d *d, int w, double stress, double vmax)
{
    d->servo_s[w] = stress > 0 ? stress : 0;
    d->servo_f[w] = 0;
    d->servo_v[w] = vmax;
    d->wall_vmode[w] = 0;
    d->wall_v[w] = 0;
    servo_modes(d);
}

void gp_dem3d_set_wall_velocity(gp_dem3d *d, int w, double v)
{
    d->servo_f[w] = 0;
    d->servo_s[w] = 0;
    d->wall_vmode[w] = 1;
    d->wall_v[w] = v;
    servo_modes(d);
}

/* the area of wall w's face: the spans of the other two axes */
static double face_area(const double *W, int w)
{
    int a = w / 2, b = (a + 1) % 3, c = (a + 2) % 3;
    return (W[2 * b + 1] - W[2 * b]) * (W[2 * c + 1] - W[2 * c]);
}

double gp_dem3d_face_area(const gp_dem3d *d, int w) { return face_area(d->wall, w); }

void gp_dem3d_set_servo_dt(gp_dem3d *d, double dt_ref) { d->servo_dt = dt_ref > 0 ? dt_ref : 0; }

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
        memcpy(G->lo, ext_lo, sizeof G->lo);
        size_t nc = gp_grid_size(ext_lo, ext_hi, G->cs, 2048, 2 * G->n + 64, G->g, G->inv);
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
        for (int a = 0; a < 3; a++)
            c[a] = gp_grid_cell((d->x[3 * i + a] - G->lo[a]) * G->inv[a], G->g[a]);
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

/* Room in d->raw for one more pair (-1: out of memory). */
static int raw_grow(gp_dem3d *d)
{
    size_t c = d->raw_cap + d->raw_cap / 2 + 1024;
    uint32_t *b2 = realloc(d->raw, 2 * c * sizeof *b2);
    if (!b2)
        return -1;
    d->raw = b2;
    d->raw_cap = c;
    return 0;
}

/* Appends the pair (a, b) to d->raw when its gap is below reach. The test is written on
 * (min, max) so that it gives the same bits whichever sphere found the pair. Inlined into
 * the cell loops, and branch-free: the pair is always written and counted only when it
 * passes (one test in ten or so does, at random). */
static inline __attribute__((always_inline)) int try_pair(gp_dem3d *d, size_t a, size_t b,
                                                          double reach, size_t *m)
{
    size_t i = a < b ? a : b, j = a < b ? b : a;
    const double *x = d->x;
    double ex = x[3 * j] - x[3 * i], ey = x[3 * j + 1] - x[3 * i + 1];
    double ez = x[3 * j + 2] - x[3 * i + 2];
    double rr = d->r[i] + reach + d->r[j];
    if (*m == d->raw_cap && raw_grow(d))
        return -1;
    d->raw[2 * *m] = (uint32_t)i;
    d->raw[2 * *m + 1] = (uint32_t)j;
    *m += (size_t)(ex * ex + ey * ey + ez * ez < rr * rr);
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

/* The m pairs of d->raw into P sorted by (i, j): counted by i (d->ioff, which the serial
 * force loop keeps), then each sphere's handful of partners by insertion. */
static void sort_pairs(gp_dem3d *d, pair_set *P, size_t m)
{
    size_t n = d->n;
    memset(d->ioff, 0, (n + 1) * sizeof *d->ioff);
    for (size_t k = 0; k < m; k++)
        d->ioff[d->raw[2 * k] + 1]++;
    for (size_t i = 0; i < n; i++)
        d->ioff[i + 1] += d->ioff[i];
    memcpy(d->fill, d->ioff, n * sizeof *d->fill);
    for (size_t k = 0; k < m; k++) {
        size_t e = d->fill[d->raw[2 * k]]++;
        P->pi[e] = d->raw[2 * k];
        P->pj[e] = d->raw[2 * k + 1];
    }
    for (size_t i = 0; i < n; i++)
        for (size_t k = d->ioff[i] + 1; k < d->ioff[i + 1]; k++) {
            uint32_t v = P->pj[k];
            size_t q = k;
            while (q > d->ioff[i] && P->pj[q - 1] > v) {
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
    const pair_set *C = &d->cur;
    for (int a = 0; a < 3; a++)
        memset(P->fs[a], 0, np * sizeof *P->fs[a]);
    memset(P->fn, 0, np * sizeof *P->fn);
    size_t o = 0;
    for (size_t k = 0; k < np && o < d->np; k++) {
        while (o < d->np && (C->pi[o] < P->pi[k] || (C->pi[o] == P->pi[k] && C->pj[o] < P->pj[k])))
            o++;
        if (o < d->np && C->pi[o] == P->pi[k] && C->pj[o] == P->pj[k]) {
            for (int a = 0; a < 3; a++)
                P->fs[a][k] = C->fs[a][o];
            P->fn[k] = C->fn[o]; /* the pair kernel clears the spring of a contact that opens */
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

/* Each candidate's share of the bound on omega_max^2 (see the header): on sphere i,
 * beta k_n (1/m_i + 1/sqrt(m_i m_j)), the contact's diagonal block and its off-diagonal block
 * (block Gershgorin; the inertial, density-scaled masses), and the same on j. k_n from the
 * full radii: the current ones are never larger (set_radius_scale), nor is the lever arm of
 * the shear spring. Computed once per rebuild; a step adds the shares of the pairs that touch. */
static void stiffness_weights(const gp_dem3d *d, pair_set *P, size_t np)
{
    for (size_t k = 0; k < np; k++) {
        size_t i = P->pi[k], j = P->pj[k];
        double ri = d->r0[i], rj = d->r0[j];
        double kb = d->beta * (2 * d->E * ri * rj / (ri + rj)), off = d->sminv[i] * d->sminv[j];
        P->wi[k] = kb * (d->minv[i] + off);
        P->wj[k] = kb * (d->minv[j] + off);
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
    stiffness_weights(d, P, np);
    if (threaded(d)) /* one thread sums the forces in pair order (step_serial) */
        pair_adjacency(d, P, np);
    pair_set t = d->cur;
    d->cur = *P;
    *P = t;
    d->np = np;
    d->pi = d->cur.pi; d->pj = d->cur.pj; d->pfn = d->cur.fn; d->adj = d->cur.adj;
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

/* ---- the pair kernel (Eqs. 1-3), four pairs at a time ----
 * Two passes: sift_pairs finds which candidates touch (a third of them do not, most of them
 * early in a run) and settles those that do not; touch_pairs computes the contacts. Both
 * are written on GCC's generic vectors of four doubles: every branch is a select (bitwise,
 * on the comparison masks), every square root and quotient is taken in all lanes and only
 * its result selected. A lane computes exactly what the scalar expressions do (IEEE sqrt
 * and division are correctly rounded in any width, and -ffp-contract=off forbids FMA), so
 * the bits depend neither on the width the machine runs (the AVX2 clone or two SSE2
 * halves) nor on where a thread's range of pairs starts. */
typedef double v4d __attribute__((vector_size(32)));
typedef long long v4l __attribute__((vector_size(32)));
#define VL 4

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) \
    && !defined(GP_DEM3D_NO_CLONES) /* (-D to build the default alone: compare the bits) */
#define KERNEL_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define KERNEL_CLONES
#endif
/* Every function that takes or returns a vector is inlined into its caller: called across
 * targets (a clone and the default), a vector would pass by two conventions (-Wpsabi). */
#define VINLINE static inline __attribute__((always_inline))

VINLINE v4d vsel(v4l m, v4d a, v4d b) { return (v4d)((m & (v4l)a) | (~m & (v4l)b)); }
VINLINE v4d vsqrt(v4d a)
{
    v4d r;
    for (int l = 0; l < VL; l++)
        r[l] = sqrt(a[l]);
    return r;
}
VINLINE v4d vsplat(double a) { return (v4d){a, a, a, a}; }
/* p[s * k[l] + o] in lane l: built in registers (stored lane by lane and read back whole,
 * it would stall on store forwarding) */
VINLINE v4d gather(const double *p, size_t s, const size_t k[VL], size_t o)
{
    return (v4d){p[s * k[0] + o], p[s * k[1] + o], p[s * k[2] + o], p[s * k[3] + o]};
}

#if defined(__clang__)
#define SHUF(a, b, p, q, r, s) __builtin_shufflevector(a, b, p, q, r, s)
#else
#define SHUF(a, b, p, q, r, s) __builtin_shuffle(a, b, (v4l){p, q, r, s})
#endif

/* The 3-vectors p[3 k[l] .. 3 k[l] + 2] into x, y, z by lane: each read as four doubles
 * (the arrays end with one double of padding), then transposed in registers (four loads
 * and six shuffles instead of twelve loads and inserts). */
VINLINE void gather3(const double *p, const size_t k[VL], v4d *x, v4d *y, v4d *z)
{
    v4d a0, a1, a2, a3;
    memcpy(&a0, p + 3 * k[0], sizeof a0);
    memcpy(&a1, p + 3 * k[1], sizeof a1);
    memcpy(&a2, p + 3 * k[2], sizeof a2);
    memcpy(&a3, p + 3 * k[3], sizeof a3);
    v4d t0 = SHUF(a0, a1, 0, 4, 2, 6), t1 = SHUF(a0, a1, 1, 5, 3, 7);
    v4d t2 = SHUF(a2, a3, 0, 4, 2, 6), t3 = SHUF(a2, a3, 1, 5, 3, 7);
    *x = SHUF(t0, t2, 0, 1, 4, 5);
    *y = SHUF(t1, t3, 0, 1, 4, 5);
    *z = SHUF(t0, t2, 2, 3, 6, 7);
}

/* Pass 1 over the candidates k0 .. k1 - 1, VL at a time (a block's lanes from k1 on repeat
 * pair k1 - 1 and are dropped): which touch (a pair at the same centre does not: no normal;
 * NaN does, to be caught as a sphere that is not finite), into idx in pair order (returns
 * how many); each other one gets f_n = -1 (within free_gap: the sphere step reads it as
 * "not in free flight") or 0, and its spring goes if it was touching. mark: also set both
 * spheres' d->anear (one thread only: two ranges may share a sphere). Branch-free but for
 * an opening contact: whether a pair touches is a coin toss. */
KERNEL_CLONES
static size_t sift_pairs(gp_dem3d *d, size_t k0, size_t k1, uint32_t *idx, int mark)
{
    pair_set *P = &d->cur;
    const double *x = d->x, *r = d->r;
    unsigned char *anear = d->anear;
    size_t m = 0;
    for (size_t k = k0; k < k1; k += VL) {
        size_t kk[VL], ii[VL], jj[VL];
        for (int l = 0; l < VL; l++) {
            kk[l] = k + (size_t)l < k1 ? k + (size_t)l : k1 - 1;
            ii[l] = P->pi[kk[l]];
            jj[l] = P->pj[kk[l]];
        }
        v4d xi, yi, zi, xj, yj, zj;
        gather3(x, ii, &xi, &yi, &zi);
        gather3(x, jj, &xj, &yj, &zj);
        v4d dx = xj - xi, dy = yj - yi, dz = zj - zi;
        v4d R = gather(r, 1, ii, 0) + gather(r, 1, jj, 0);
        v4d d2 = dx * dx + dy * dy + dz * dz, rg = R + d->free_gap;
        v4l touch = ~((d2 >= R * R) | (d2 == 0)), near = ~touch & (d2 < rg * rg);
        v4d fn0 = gather(P->fn, 1, kk, 0);
        v4d fn = vsel(touch, fn0, vsel(near, vsplat(-1), vsplat(0)));
        v4l opened = ~touch & (fn0 > 0);
        size_t lanes = k1 - k < VL ? k1 - k : VL;
        for (size_t l = 0; l < lanes; l++) {
            P->fn[k + l] = fn[l];
            idx[m] = (uint32_t)(k + l);
            m += (size_t)(touch[l] & 1);
            if (mark) {
                anear[ii[l]] |= (unsigned char)(near[l] & 1);
                anear[jj[l]] |= (unsigned char)(near[l] & 1);
            }
        }
        if (opened[0] | opened[1] | opened[2] | opened[3]) /* the spring goes */
            for (size_t l = 0; l < lanes; l++)
                if (opened[l])
                    P->fs[0][k + l] = P->fs[1][k + l] = P->fs[2][k + l] = 0;
    }
    return m;
}

/* The touching pairs kk[0 .. VL - 1] (Eqs. 1-3): each one's shear spring, f_n (> 0), force
 * on i (F) and n x f_s (c: the moment of the pair on either sphere is that sphere's radius
 * times c). A pair may repeat (a block's tail): it is computed twice from the same values. */
VINLINE void touch_block(gp_dem3d *d, const pair_consts *q, const size_t kk[VL])
{
    pair_set *P = &d->cur;
    size_t ii[VL], jj[VL];
    for (int l = 0; l < VL; l++) {
        ii[l] = P->pi[kk[l]];
        jj[l] = P->pj[kk[l]];
    }
    v4d xi, yi, zi, xj, yj, zj;
    gather3(d->x, ii, &xi, &yi, &zi);
    gather3(d->x, jj, &xj, &yj, &zj);
    v4d dx = xj - xi, dy = yj - yi, dz = zj - zi;
    v4d ri = gather(d->r, 1, ii, 0), rj = gather(d->r, 1, jj, 0), R = ri + rj;
    v4d d2 = dx * dx + dy * dy + dz * dz;
    v4d dist = vsqrt(d2), id = 1.0 / dist;
    v4d nx = dx * id, ny = dy * id, nz = dz * id;
    v4d kn = q->E2 * ri * rj / R;
    v4d fn = kn * (R - dist);
    /* contact-point velocities: i at +ri n, j at -rj n */
    v4d wi0, wi1, wi2, wj0, wj1, wj2, vi0, vi1, vi2, vj0, vj1, vj2;
    gather3(d->w, ii, &wi0, &wi1, &wi2);
    gather3(d->w, jj, &wj0, &wj1, &wj2);
    gather3(d->v, ii, &vi0, &vi1, &vi2);
    gather3(d->v, jj, &vj0, &vj1, &vj2);
    v4d vrx = vi0 - vj0 + ri * (wi1 * nz - wi2 * ny) + rj * (wj1 * nz - wj2 * ny);
    v4d vry = vi1 - vj1 + ri * (wi2 * nx - wi0 * nz) + rj * (wj2 * nx - wj0 * nz);
    v4d vrz = vi2 - vj2 + ri * (wi0 * ny - wi1 * nx) + rj * (wj0 * ny - wj1 * nx);
    v4d vn = vrx * nx + vry * ny + vrz * nz;
    v4d vtx = vrx - vn * nx, vty = vry - vn * ny, vtz = vrz - vn * nz;
    /* keep the spring tangent (rotate with the contact, same magnitude) */
    v4d ox = gather(P->fs[0], 1, kk, 0), oy = gather(P->fs[1], 1, kk, 0);
    v4d oz = gather(P->fs[2], 1, kk, 0);
    v4d s2 = ox * ox + oy * oy + oz * oz;
    v4d sn = ox * nx + oy * ny + oz * nz;
    v4d tx = ox - sn * nx, ty = oy - sn * ny, tz = oz - sn * nz;
    v4d t2 = tx * tx + ty * ty + tz * tz;
    v4d rot = vsqrt(s2 / t2);
    v4l spring = s2 > 0, turn = spring & (t2 > 0);
    v4d sx = vsel(spring, vsel(turn, tx * rot, tx), ox);
    v4d sy = vsel(spring, vsel(turn, ty * rot, ty), oy);
    v4d sz = vsel(spring, vsel(turn, tz * rot, tz), oz);
    v4d ks = q->ksr * kn;
    sx -= ks * vtx * q->dt; sy -= ks * vty * q->dt; sz -= ks * vtz * q->dt;
    /* Coulomb: the spring truncated at tan(phi) f_n */
    v4d smax = q->mu * fn;
    v4d ss = sx * sx + sy * sy + sz * sz;
    v4d cut = vsel(ss > 0, smax / vsqrt(ss), vsplat(0));
    v4l slip = ss > smax * smax;
    sx = vsel(slip, sx * cut, sx); sy = vsel(slip, sy * cut, sy); sz = vsel(slip, sz * cut, sz);
    v4d Fx = -fn * nx + sx, Fy = -fn * ny + sy, Fz = -fn * nz + sz;
    v4d cx = ny * sz - nz * sy, cy = nz * sx - nx * sz, cz = nx * sy - ny * sx;
    for (int l = 0; l < VL; l++) {
        size_t k = kk[l];
        P->fs[0][k] = sx[l]; P->fs[1][k] = sy[l]; P->fs[2][k] = sz[l];
        P->fn[k] = fn[l];
        P->F[0][k] = Fx[l]; P->F[1][k] = Fy[l]; P->F[2][k] = Fz[l];
        P->c[0][k] = cx[l]; P->c[1][k] = cy[l]; P->c[2][k] = cz[l];
    }
}

/* Pass 2: the m touching pairs idx[0 .. m - 1] */
KERNEL_CLONES
static void touch_pairs(gp_dem3d *d, const uint32_t *idx, size_t m)
{
    const pair_consts q = consts_of(d);
    for (size_t c = 0; c < m; c += VL) {
        size_t kk[VL];
        for (size_t l = 0; l < VL; l++)
            kk[l] = idx[c + l < m ? c + l : m - 1];
        touch_block(d, &q, kk);
    }
}

/* Both passes over the candidates k0 .. k1 - 1 (idx: room for k1 - k0 indices); returns
 * the contacts. */
static size_t pair_kernel(gp_dem3d *d, size_t k0, size_t k1, uint32_t *idx, int mark)
{
    size_t m = sift_pairs(d, k0, k1, idx, mark);
    touch_pairs(d, idx, m);
    return m;
}

/* Each sphere's x, y, z in the first three lanes of a vector (the fourth is idle), so that
 * one vector operation does what the scalar code did per component, with the same bits. */
VINLINE v4d vload3(const double *p) { return (v4d){p[0], p[1], p[2], 0}; }
VINLINE void vstore3(double *p, v4d a)
{
    p[0] = a[0];
    p[1] = a[1];
    p[2] = a[2];
}
/* any of the first three lanes */
VINLINE int vany3(v4l m) { return (m[0] | m[1] | m[2]) != 0; }

/* Local damping: the force times dm = 1 - c where it does work (f v > 0), times dp = 1 + c
 * where it brakes, unchanged where f v = 0 (selects: the sign of f v is a coin toss). */
VINLINE v4d damp(v4d f, v4d v, double dm, double dp)
{
    v4d p = f * v;
    return f * vsel(p > 0, vsplat(dm), vsel(p < 0, vsplat(dp), vsplat(1)));
}

/* what every sphere of a step shares (copied: the compiler then knows that the spheres'
 * arrays, which a step writes, do not hold them) */
typedef struct sphere_consts {
    v4d lo, hi; /* the walls: x-, y-, z-, -inf and x+, y+, z+, +inf (the idle lane never
                   touches a wall, nor leaves the box) */
    double dt, dm, dp, dscale, E2, gap, g[3];
    double E2w;  /* 2 E times the most walls one sphere can touch on an axis (the bound) */
    int measure;
} sphere_consts;

static sphere_consts sphere_consts_of(const gp_dem3d *d)
{
    const double *W = d->wall;
    sphere_consts k = {{W[0], W[2], W[4], -INFINITY}, {W[1], W[3], W[5], INFINITY}, d->dt,
                       1 - d->damping, 1 + d->damping,
                       d->rscale > d->rscale_ref ? d->rscale - d->rscale_ref : 0, 2 * d->E,
                       d->free_gap, {d->g[0], d->g[1], d->g[2]}, 2 * d->E, d->measure};
    for (int a = 0; a < 3; a++) /* both walls of an axis on one sphere: a box below 2 r */
        if (W[2 * a + 1] - W[2 * a] < 2 * d->r0max * d->rscale)
            k.E2w = 4 * d->E;
    return k;
}

/* a block's sums while it runs: the scalar ones, the walls' by axis in lanes, and masks
 * (-1 per lane) counted or or-ed only at the end */
typedef struct blk_run {
    blk_acc s;
    v4d wf_lo, wf_hi, wk_lo, wk_hi;
    v4l wn;  /* minus the wall contacts, by axis */
    v4l bad; /* a sphere outside the box, or not finite, by axis */
} blk_run;

static void blk_begin(blk_run *a) { memset(a, 0, sizeof *a); }

static void blk_end(const blk_run *a, blk_acc *out)
{
    *out = a->s;
    out->wn = (size_t)-(a->wn[0] + a->wn[1] + a->wn[2] + a->wn[3]);
    out->bad = (a->bad[0] | a->bad[1] | a->bad[2] | a->bad[3]) != 0;
    for (int x = 0; x < 3; x++) {
        out->wf[2 * x] = a->wf_lo[x];
        out->wf[2 * x + 1] = a->wf_hi[x];
        out->wk[2 * x] = a->wk_lo[x];
        out->wk[2 * x + 1] = a->wk_hi[x];
    }
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

/* The walls' forces on a sphere (centre x, radius ri) added to F and to the block's wall
 * sums (a wall acts as the mirror image: 2 E ri (ri - d)); returns the sum of their normal
 * forces, in the order x-, x+, y-, y+, z-, z+, and sets *near when a wall is within
 * free_gap. A wall not touched adds zeros, which change no sum. */
VINLINE double wall_forces(const sphere_consts *k, v4d x, double ri, v4d *F, blk_run *acc,
                           int *near)
{
    const v4d rv = vsplat(ri), zero = vsplat(0), kw = vsplat(k->E2 * ri);
    v4d dl = x - k->lo, dh = k->hi - x;
    v4l ml = dl < rv, mh = dh < rv;
    v4d fl = vsel(ml, k->E2 * ri * (rv - dl), zero), fh = vsel(mh, k->E2 * ri * (rv - dh), zero);
    *F = *F + fl - fh;
    acc->wf_lo += fl;
    acc->wf_hi += fh;
    acc->wk_lo += vsel(ml, kw, zero);
    acc->wk_hi += vsel(mh, kw, zero);
    acc->wn += ml + mh; /* true is -1 (the idle lane never is) */
    const v4d rg = vsplat(ri + k->gap);
    *near |= vany3((dl < rg) | (dh < rg));
    double sfn = 0;
    for (int a = 0; a < 3; a++) {
        sfn += fl[a];
        sfn += fh[a];
    }
    return sfn;
}

/* Sphere i once its pair sums are complete (F: gravity and the pairs' forces, T: their
 * moments, sfn: their sum of f_n, lam: their shares of the bound on omega^2, near: a sphere
 * within free_gap): the walls, S_c's sums, local damping and the leapfrog step; the block's
 * sums (acc), its largest bound and two largest moves. */
VINLINE void move_sphere(gp_dem3d *d, const sphere_consts *k, size_t i, v4d F, v4d T,
                         double sfn, double lam, int near, blk_run *acc)
{
    double *restrict xp = d->x + 3 * i, *restrict vp = d->v + 3 * i, *restrict wp = d->w + 3 * i;
    const double dt = k->dt, ri = d->r[i];
    v4d x = vload3(xp), v = vload3(vp), w = vload3(wp);
    double sw = wall_forces(k, x, ri, &F, acc, &near);
    sfn += sw;
    /* the walls' block is diagonal: 2 E ri times the walls it touches on one axis, at most
     * one unless the box is narrower than a sphere (k->E2w) */
    lam += sw > 0 ? k->E2w * ri * d->minv[i] : 0;
    acc->s.lam = lam > acc->s.lam ? lam : acc->s.lam;
    if (k->measure) /* read only after a run: summed on its last step */
        acc->s.sum_f += sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]);
    if (k->measure)
        acc->s.sum_fn += sfn;
    /* free flight: nothing within free_gap, so no contact stiffness for density scaling to
     * serve and no oscillation for local damping to take out; the sphere falls with its true
     * mass, undamped (see the top of this file) */
    int fly = !(near || sfn > 0);
    double mi = (fly ? d->mtinv[i] : d->minv[i]) * dt, ii = d->iinv[i] * dt;
    v = v + damp(F, v, fly ? 1.0 : k->dm, fly ? 1.0 : k->dp) * mi;
    w = w + damp(T, w, k->dm, k->dp) * ii;
    x = x + v * dt;
    v4d e = x - vload3(d->xref + 3 * i);
    e = e * e;
    double d2 = e[0] + e[1] + e[2];
    if (k->measure) {
        double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        acc->s.ke += 0.5 * d->m[i] * v2;
        if (v2 > acc->s.vmax2) acc->s.vmax2 = v2;
    }
    double mv = d2; /* the distance a gap may have closed by this sphere, squared */
    if (k->dscale > 0) {
        double g = sqrt(d2) + k->dscale * d->r0[i];
        mv = g * g;
    }
    top2(acc->s.move, mv);
    /* outside, or not a number (a velocity that is not finite makes x so at once) */
    const v4d rv = vsplat(ri);
    acc->bad |= ~((x > k->lo - rv) & (x < k->hi + rv));
    vstore3(xp, x);
    vstore3(vp, v);
    vstore3(wp, w);
}

/* ---- a step: the pair kernel, then each sphere's sums and its move ---- */

/* One thread: the kernel over every pair, then the spheres in order, block by block. Each
 * contact's force is added to both spheres' sums in pair order: sphere i's contacts as the
 * second sphere (i' < i) all come before its own (i, j), so when its turn comes its sums
 * are taken into registers, run over its own contacts (its partners j get their share
 * added in place), and are then complete: the sphere moves at once (no later pair reads
 * it, and the kernel has already read every position). A sphere's sums thus run over its
 * contacts in pair order, as the threaded gather does: the same bits. Returns the
 * contacts. */
KERNEL_CLONES
static size_t step_serial(gp_dem3d *d)
{
    const sphere_consts sk = sphere_consts_of(d);
    const pair_set *P = &d->cur;
    const uint32_t *restrict pj = P->pj, *restrict idx = P->idx;
    const size_t *restrict ioff = d->ioff; /* i's pairs: ioff[i] .. ioff[i + 1] - 1 */
    const double *restrict r = d->r, *restrict pfn = P->fn;
    const double *restrict Fx = P->F[0], *restrict Fy = P->F[1], *restrict Fz = P->F[2];
    const double *restrict cx = P->c[0], *restrict cy = P->c[1], *restrict cz = P->c[2];
    const double *restrict wi = P->wi, *restrict wj = P->wj;
    double *restrict af = d->af, *restrict at = d->at, *restrict afn = d->afn;
    double *restrict alam = d->alam;
    for (size_t i = 0; i < d->n; i++) { /* gravity on the true mass */
        for (int a = 0; a < 3; a++) {
            af[3 * i + a] = d->m[i] * sk.g[a];
            at[3 * i + a] = 0;
        }
        afn[i] = 0;
        alam[i] = 0;
        d->anear[i] = 0;
    }
    size_t nc = pair_kernel(d, 0, d->np, P->idx, 1), c = 0;
    for (size_t b = 0; b < d->nblk; b++) {
        blk_run acc;
        blk_begin(&acc);
        size_t i0 = b * BLK, i1 = i0 + BLK < d->n ? i0 + BLK : d->n;
        for (size_t i = i0; i < i1; i++) {
            double f0 = af[3 * i], f1 = af[3 * i + 1], f2 = af[3 * i + 2];
            double t0 = at[3 * i], t1 = at[3 * i + 1], t2 = at[3 * i + 2];
            double sfn = afn[i], ri = r[i], lam = alam[i];
            for (size_t end = ioff[i + 1]; c < nc && idx[c] < end; c++) { /* i's own */
                size_t k = idx[c], j = pj[k];
                double rj = r[j];
                f0 += Fx[k]; f1 += Fy[k]; f2 += Fz[k];
                af[3 * j] -= Fx[k]; af[3 * j + 1] -= Fy[k]; af[3 * j + 2] -= Fz[k];
                t0 += ri * cx[k]; t1 += ri * cy[k]; t2 += ri * cz[k];
                at[3 * j] += rj * cx[k]; at[3 * j + 1] += rj * cy[k]; at[3 * j + 2] += rj * cz[k];
                sfn += pfn[k];
                afn[j] += pfn[k];
                lam += wi[k];
                alam[j] += wj[k];
            }
            move_sphere(d, &sk, i, (v4d){f0, f1, f2, 0}, (v4d){t0, t1, t2, 0}, sfn, lam,
                        d->anear[i], &acc);
        }
        blk_end(&acc, d->blk + b);
    }
    return nc;
}

/* threads, first half: each thread the kernel over a range of pairs */
static void job_pairs(gp_dem3d *d, int tid, int nt)
{
    size_t np = d->np;
    size_t k0 = np * (size_t)tid / (size_t)nt, k1 = np * (size_t)(tid + 1) / (size_t)nt;
    d->tnc[tid] = pair_kernel(d, k0, k1, d->cur.idx + k0, 0);
}

/* threads, second half: blocks of spheres, each sphere's sums gathered from its contacts
 * in pair order (d->adj), the same additions in the same order as step_serial, and the
 * sphere moved (no thread reads another sphere's position any more in this step) */
KERNEL_CLONES
static void job_spheres(gp_dem3d *d, int tid, int nt)
{
    const sphere_consts sk = sphere_consts_of(d);
    const pair_set *P = &d->cur;
    const double *restrict pfn = P->fn, *restrict wi = P->wi, *restrict wj = P->wj;
    const double *restrict Fx = P->F[0], *restrict Fy = P->F[1], *restrict Fz = P->F[2];
    const double *restrict cx = P->c[0], *restrict cy = P->c[1], *restrict cz = P->c[2];
    const size_t *restrict adj = d->adj, *restrict off = d->off;
    for (size_t b = (size_t)tid; b < d->nblk; b += (size_t)nt) {
        blk_run acc;
        blk_begin(&acc);
        size_t i0 = b * BLK, i1 = i0 + BLK < d->n ? i0 + BLK : d->n;
        for (size_t i = i0; i < i1; i++) {
            double ri = d->r[i], m = d->m[i];
            double f0 = m * sk.g[0], f1 = m * sk.g[1], f2 = m * sk.g[2];
            double t0 = 0, t1 = 0, t2 = 0, sfn = 0, lam = 0;
            int near = 0;
            for (size_t e = off[i]; e < off[i + 1]; e++) {
                size_t k = adj[e] >> 1;
                double fn = pfn[k];
                if (fn == 0 || fn == -1) { /* not touching (the kernel's own marks) */
                    near |= fn < 0;
                    continue;
                }
                if (adj[e] & 1) { /* i is the pair's j: the force on it is -F */
                    f0 -= Fx[k]; f1 -= Fy[k]; f2 -= Fz[k];
                    lam += wj[k];
                } else {
                    f0 += Fx[k]; f1 += Fy[k]; f2 += Fz[k];
                    lam += wi[k];
                }
                t0 += ri * cx[k]; t1 += ri * cy[k]; t2 += ri * cz[k];
                sfn += fn;
            }
            move_sphere(d, &sk, i, (v4d){f0, f1, f2, 0}, (v4d){t0, t1, t2, 0}, sfn, lam, near,
                        &acc);
        }
        blk_end(&acc, d->blk + b);
    }
}

/* One step of every sphere (d->blk holds the blocks' sums); returns the sphere-sphere
 * contacts. */
static size_t step(gp_dem3d *d)
{
    if (!threaded(d))
        return step_serial(d);
    run_job(d, job_pairs);
    run_job(d, job_spheres);
    size_t nc = 0;
    for (int t = 0; t < d->pool.nt; t++)
        nc += d->tnc[t];
    return nc;
}

void gp_dem3d_set_cancel(gp_dem3d *d, const volatile int *cancel) { d->cancel = cancel; }

/* The stability check after a step (see the header): lam bounds omega_max^2 over the
 * contacts of the step; leapfrog with local damping c is stable while omega dt sqrt(1 + c)
 * < 2. Above, the guard cuts dt to DT_CUT of the limit for the steps that follow (a single
 * step beyond it cannot blow up: instability needs the growth of many). lam is a maximum
 * over spheres, the same bits for any thread count, so is the cut. */
static void check_dt(gp_dem3d *d, double lam)
{
    d->lam_max = lam;
    double wc = sqrt(lam * (1 + d->damping)); /* omega sqrt(1 + c) */
    double ratio = 0.5 * wc * d->dt;
    if (ratio > d->dt_ratio)
        d->dt_ratio = ratio;
    if (d->dt_guard && ratio >= 1) {
        d->dt = DT_CUT * 2 / wc;
        /* a later damping keeps the cut's share */
        d->dt_und = d->dt_exp > 0 ? d->dt * pow(1 + d->damping, d->dt_exp) : d->dt;
        d->dt_cuts++;
    }
}

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
        size_t nc = step(d), wn = 0;
        double sf = 0, sfn = 0, ke = 0, vm = 0, lam = 0;
        double wf[6] = {0}, wk[6] = {0};
        double move[2] = {0, 0};
        int bad = 0;
        for (size_t b = 0; b < d->nblk; b++) {
            const blk_acc *a = d->blk + b;
            sf += a->sum_f; sfn += a->sum_fn; ke += a->ke;
            if (a->vmax2 > vm) vm = a->vmax2;
            if (a->lam > lam) lam = a->lam;
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
        /* servo walls (Eq. 10); a stress servo's force from the faces as the step found
         * them (before any wall moves); walls with a prescribed velocity */
        double area[6] = {0};
        if (d->servo_stress)
            for (int w = 0; w < 6; w++)
                area[w] = face_area(d->wall, w);
        for (int w = 0; w < 6; w++) {
            if (d->wall_vmode[w]) {
                d->wall[w] += d->wall_v[w] * d->dt;
                continue;
            }
            double target = d->servo_s[w] > 0 ? d->servo_s[w] * area[w] : d->servo_f[w];
            if (target <= 0)
                continue;
            double lim = d->servo_v[w] * d->dt;
            /* a rate in time (servo_dt): a longer step moves the wall further, so that the
             * protocol's windows, which are in time, see the same wall whatever dt */
            double gain = d->servo_dt > 0 ? SERVO_GAIN * d->dt / d->servo_dt : SERVO_GAIN;
            double mv = wk[w] > 0 ? gain * (target - wf[w]) / wk[w] : lim;
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
        check_dt(d, lam);
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
    s->omega_bound = sqrt(d->lam_max);
    s->dt_ratio = d->dt_ratio;
    s->dt_cuts = d->dt_cuts;
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
            c[m].force[a] = d->cur.F[a][k];
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
