/* gp_specimen3d.c -- see gp_specimen3d.h.
 *
 * Protocol (what the paper does, and where this differs; see also gp_dem3d.h):
 *  phase 0, deposition: the sieve is drawn by quota for V_s = (1 - p) b_x b_y b_z (NOTES.md,
 *    Eq. 8), the spheres are placed at random without overlap (largest first) at a reduced
 *    radius in a box of the sample's plan and a taller height, then grown to full size while they
 *    settle under gravity (the "grow radii" variant of pouring: the same loose, gravity-made
 *    structure without minutes of free fall), and left to settle.
 *  phase 1, compaction: the top wall becomes a servo wall (Eq. 10) pressing with
 *    COMPACTION_STRESS and descends onto the deposit at full friction (phase 0's porosity is
 *    read where it comes to rest on it); then, instead of shaking the walls, the friction is
 *    lowered step by step while the wall stops making progress (a friction ladder, as YADE's
 *    compaction scripts reach a porosity); the wall never goes below the target height b_z.
 *  relaxation: when the wall reaches b_z the friction is restored and the wall stays a servo
 *    wall pressing with the same stress (never below b_z), until S_c <= 1e-4 (Eq. 7,
 *    NOTES.md), with local damping raised to RELAX_DAMPING. Should the packing still settle
 *    away from the wall, the wall follows it down by at most POROSITY_SLACK. The sample box is
 *    where the wall ends, so the porosity reported is the one of the spheres in that box.
 *  If the approach without friction stalls above b_z (less than STALL_FRACTION of the
 *  remaining porosity gained in STALL_T), the target is denser than this sieve packs in this
 *  box ("target_too_dense"), unless it stalled within POROSITY_SLACK of it; if after relaxation the top wall carries no force, the deposit
 *  itself is denser than the target ("target_too_loose").
 *  Durations are in units of sqrt(d50 / g), not in steps, so that a wide sieve (whose time
 *  step follows its small grains) gets the same physical time as the paper's.
 *  phase 2, tiling: gp_flip.
 */
#include "gp_specimen3d.h"

#include "gp_dem3d.h"
#include "gp_flip.h"
#include "gp_rng.h"
#include "gp_sieve.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MAX_SAMPLE_SPHERES 400000
#define MAX_TILED_SPHERES 20000000
#define GRAVITY 9.81
#define STABILITY 1e-4           /* Eq. 7: 0.01 % */
#define GROW_FROM 0.6            /* initial radius scale of the placement */
/* durations, in units of sqrt(d50 / g) (see where tu is computed; the paper's sieve has ~860
 * steps per unit, and these are its former step counts) */
#define GROW_T 1.75              /* growth of the radii */
#define SETTLE_T 1.2             /* deposition ends after this ... */
#define SETTLE_SC 5e-2           /* ... or when S_c is below this */
#define LADDER_T 0.35            /* progress window of the friction ladder */
#define STALL_T 3.5              /* progress window without friction */
#define MAX_T 500                /* default cap on the DEM steps (at least 400,000) */
#define LID_SPEED 1.4            /* top-wall speed limit, times sqrt(g d50) (1 m/s in the paper) */
#define APPROACH_T 1.0           /* the wall closes the gap to b_z in no less than this */
#define CHUNK 100
#define STALL_FRACTION 0.1
#define LADDER_FRACTION 0.2      /* least progress per window, of the height still to go */
#define LADDER_MIN_LEFT 0.002    /* ... counted as at least this fraction of b_z */
#define LADDER_FACTOR 0.5        /* friction step of the ladder */
#define LADDER_MIN_DEG 0.5       /* below this the ladder goes to zero friction */
#define MAX_SCALED_RATIO 3.5     /* density scaling radius >= rmax / this */
#define POROSITY_SLACK 0.003     /* the wall may end this far from the target porosity (the
                                    tolerance is 0.005): above, where the packing jams without
                                    friction; below, following a packing that settles away */
#define DT_SAFETY 0.3            /* of sqrt(m / 2 E R): omega dt <= 0.3 sqrt(12) ~ 1 < 2 even
                                    with 12 contacts as stiff as a wall */
#define COMPACTION_STRESS 1.0    /* top-wall stress, times the geostatic stress at the bottom */
#define RELAX_DAMPING 0.7        /* local damping during relaxation (the static state does not
                                    depend on it; Sc <= 1e-4 comes ~2x sooner than at 0.2) */

static const gp_sieve_row TABLE2[5] = {
    {0.010, 0}, {0.020, 2}, {0.050, 50}, {0.080, 95}, {0.100, 100}};

void gp_spec3d_defaults(gp_spec3d *s)
{
    memset(s, 0, sizeof *s);
    s->seed = 0;
    s->box[0] = s->box[1] = s->box[2] = 0.5;
    s->sieve = TABLE2;
    s->nsieve = 5;
    s->porosity = 0.38;
    s->material.density = 2600;
    s->material.young = 15e6;
    s->material.poisson = 0.5;
    s->material.friction_deg = 18;
    s->material.damping = 0.2;
    s->tiling[0] = s->tiling[1] = s->tiling[2] = 1;
    s->outputs = GP_OUT3_SPHERES;
    s->threads = 1;
    s->max_steps = 0;
    s->tile_relax_steps = 0;
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct run_ctx {
    gp_progress_fn fn;
    void *user;
    const volatile int *cancel;
    double last;
} run_ctx;

/* the caller's cancel flag, raised by another thread with an atomic store */
static int cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

static int report(run_ctx *c, const char *phase, double fraction, long steps, double porosity,
                  double sc, int force)
{
    if (cancel_raised(c->cancel))
        return 1;
    if (!c->fn)
        return 0;
    double t = now();
    if (!force && t - c->last < 0.05)
        return 0;
    c->last = t;
    gp_progress p = {.phase = phase,
                     .fraction = fraction < 0 ? 0 : (fraction > 1 ? 1 : fraction),
                     .steps = steps,
                     .porosity = porosity,
                     .stability = isfinite(sc) ? sc : 0};
    return c->fn(c->user, &p) != 0;
}

void gp_specimen3d_destroy(gp_specimen3d *s)
{
    if (!s)
        return;
    free(s->spheres);
    free(s->contacts);
    free(s->stats.psd.diameter);
    free(s->stats.psd.target_weight);
    free(s->stats.psd.target_number);
    free(s->stats.psd.target_number_midbin);
    free(s->stats.psd.achieved_weight);
    free(s->stats.psd.achieved_number);
    free(s);
}

static int cmp_desc(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x > y ? -1 : x < y;
}

/* Random sequential placement of spheres (radii lam * d / 2, largest first) without overlap in
 * [0, L]. Returns 0 on success, 1 when a sphere found no place, 2 when *cancel came up (looked
 * at every 256 spheres: up to 4000 tries each), -1 out of memory. */
static int place(const double *diam, size_t n, double lam, const double L[3], gp_rng *rng,
                 const volatile int *cancel, double *xyzr)
{
    double rmax = 0.5 * lam * diam[0];
    double cs = 2 * rmax;
    size_t g[3];
    for (int a = 0; a < 3; a++) {
        double ga = floor(L[a] / cs);
        g[a] = ga < 1 ? 1 : (ga > 512 ? 512 : (size_t)ga);
    }
    while (g[0] * g[1] * g[2] > 4 * n + 64) {
        int a = g[0] >= g[1] && g[0] >= g[2] ? 0 : (g[1] >= g[2] ? 1 : 2);
        g[a] = (g[a] + 1) / 2;
    }
    size_t nc = g[0] * g[1] * g[2];
    long *head = malloc(nc * sizeof *head), *next = malloc(n * sizeof *next);
    if (!head || !next) {
        free(head); free(next);
        return -1;
    }
    for (size_t c = 0; c < nc; c++)
        head[c] = -1;
    int ok = 1;
    for (size_t i = 0; i < n && ok; i++) {
        if (i % 256 == 0 && cancel_raised(cancel)) {
            ok = -1;
            break;
        }
        double r = 0.5 * lam * diam[i];
        int placed = 0;
        for (int t = 0; t < 4000 && !placed; t++) {
            double p[3];
            size_t c[3];
            for (int a = 0; a < 3; a++) {
                p[a] = r + gp_rng_uniform(rng) * (L[a] - 2 * r);
                long k = (long)(p[a] / L[a] * (double)g[a]);
                c[a] = k < 0 ? 0 : (k >= (long)g[a] ? g[a] - 1 : (size_t)k);
            }
            int clash = 0;
            for (long z = (long)c[2] - 1; z <= (long)c[2] + 1 && !clash; z++) {
                if (z < 0 || z >= (long)g[2]) continue;
                for (long y = (long)c[1] - 1; y <= (long)c[1] + 1 && !clash; y++) {
                    if (y < 0 || y >= (long)g[1]) continue;
                    for (long x = (long)c[0] - 1; x <= (long)c[0] + 1 && !clash; x++) {
                        if (x < 0 || x >= (long)g[0]) continue;
                        for (long j = head[((size_t)z * g[1] + (size_t)y) * g[0] + (size_t)x]; j >= 0; j = next[j]) {
                            const double *q = xyzr + 4 * j;
                            double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2], rr = q[3] + r;
                            if (dx * dx + dy * dy + dz * dz < rr * rr) {
                                clash = 1;
                                break;
                            }
                        }
                    }
                }
            }
            if (!clash) {
                for (int a = 0; a < 3; a++)
                    xyzr[4 * i + a] = p[a];
                xyzr[4 * i + 3] = r;
                size_t cell = (c[2] * g[1] + c[1]) * g[0] + c[0];
                next[i] = head[cell];
                head[cell] = (long)i;
                placed = 1;
            }
        }
        ok = placed;
    }
    free(head);
    free(next);
    return ok < 0 ? 2 : (ok ? 0 : 1);
}

/* ---- measures over the final packing's contacts ----
 * One pass feeds every measure: contact counts (always reported), fabric and stress (when
 * asked), and the contact list (only with GP_OUT3_CONTACTS). A tiled packing's contacts come
 * in chunks from gp_flip_contacts_each and are never all held at once unless the list is
 * asked for (it was ~2 GB for 7.5 million spheres); an untiled or relaxed packing's array goes
 * through the same code. The sums run in the contacts' order whatever the chunks, so the
 * numbers do not depend on how the contacts arrive, nor on GP_OUT3_CONTACTS. */
#define MEASURE_CHUNK 4096 /* contacts per chunk (288 KB); the cancel flag is read per chunk */

typedef struct measure_acc {
    unsigned outputs;
    size_t pairs, walls;
    gp_dem3d_fabric_acc fabric;
    gp_dem3d_stress_acc stress;
    gp_contact3d *out; /* GP_OUT3_CONTACTS: room for cap contacts, nout of them filled */
    size_t nout, cap;
    const volatile int *cancel;
} measure_acc;

/* cap: an upper bound on the number of contacts (the list is allocated once, then shrunk) */
static gp_status measure_init(measure_acc *m, unsigned outputs, const double *xyzr, size_t cap,
                              const volatile int *cancel, gp_error *err)
{
    memset(m, 0, sizeof *m);
    m->outputs = outputs;
    m->cancel = cancel;
    gp_dem3d_fabric_acc_init(&m->fabric);
    gp_dem3d_stress_acc_init(&m->stress, xyzr);
    if (outputs & GP_OUT3_CONTACTS) {
        m->out = malloc((cap ? cap : 1) * sizeof *m->out);
        if (!m->out)
            return gp_error_set(err, GP_ERR_NOMEM, "out of memory (%zu contacts)", cap);
        m->cap = cap;
    }
    return GP_OK;
}

/* gp_flip_visit_fn: one chunk into every measure */
static gp_status measure_add(void *user, const gp_dem3d_contact *c, size_t k, gp_error *err)
{
    measure_acc *m = user;
    if (cancel_raised(m->cancel))
        return gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
    for (size_t q = 0; q < k; q++) {
        if (c[q].j >= 0) m->pairs++;
        else m->walls++;
    }
    if (m->outputs & GP_OUT3_FABRIC)
        gp_dem3d_fabric_acc_add(&m->fabric, c, k);
    if (m->outputs & GP_OUT3_STRESS)
        gp_dem3d_stress_acc_add(&m->stress, c, k);
    if (m->out) {
        if (k > m->cap - m->nout) /* cannot happen: cap bounds the count */
            return gp_error_set(err, GP_ERR_INTERNAL, "contacts: more than %zu", m->cap);
        for (size_t q = 0; q < k; q++) {
            gp_contact3d *o = m->out + m->nout++;
            o->i = c[q].i;
            o->j = c[q].j;
            memcpy(o->normal, c[q].normal, sizeof o->normal);
            o->overlap = c[q].overlap;
            memcpy(o->force, c[q].force, sizeof o->force);
        }
    }
    return GP_OK;
}

/* the same, over an array, chunk by chunk (the cancel flag is looked at between them) */
static gp_status measure_array(measure_acc *m, const gp_dem3d_contact *c, size_t nc,
                               gp_error *err)
{
    gp_status st = GP_OK;
    for (size_t k = 0; k < nc && !st; k += MEASURE_CHUNK)
        st = measure_add(m, c + k, nc - k < MEASURE_CHUNK ? nc - k : MEASURE_CHUNK, err);
    return st;
}

/* statistics over n spheres and a box of the given volume into res; the list (if any) moves
 * to res */
static void measure_finish(measure_acc *m, size_t n, double volume, gp_specimen3d *res)
{
    gp_stats3d *S = &res->stats;
    S->contacts = m->pairs;
    S->wall_contacts = m->walls;
    S->coordination_number = n ? (2.0 * (double)m->pairs + (double)m->walls) / (double)n : 0;
    S->coordination_spheres = n ? 2.0 * (double)m->pairs / (double)n : 0;
    if (m->outputs & GP_OUT3_FABRIC)
        gp_dem3d_fabric_acc_finish(&m->fabric, S->fabric);
    if (m->outputs & GP_OUT3_STRESS)
        gp_dem3d_stress_acc_finish(&m->stress, volume, S->stress);
    if (m->out) {
        gp_contact3d *fit = realloc(m->out, (m->nout ? m->nout : 1) * sizeof *fit);
        res->contacts = fit ? fit : m->out;
        res->ncontacts = m->nout;
        m->out = NULL;
    }
}

/* The measures of the final packing (nf spheres fx). stream: the contacts are the sample's
 * (c, nc; n spheres xyzr), mapped to the tiling on the fly; else c is the final list. */
static gp_status measure(const gp_spec3d *spec, int stream, const gp_dem3d_contact *c,
                         size_t nc, const double *xyzr, size_t n, const double *fx, size_t nf,
                         const volatile int *cancel, gp_specimen3d *res, gp_error *err)
{
    size_t ntile = (size_t)spec->tiling[0] * (size_t)spec->tiling[1] * (size_t)spec->tiling[2];
    measure_acc m;
    gp_status st = measure_init(&m, spec->outputs, fx, stream ? ntile * nc : nc, cancel, err);
    if (!st && stream) {
        gp_dem3d_contact *buf = malloc(MEASURE_CHUNK * sizeof *buf);
        st = buf ? gp_flip_contacts_each(c, nc, xyzr, n, spec->tiling, cancel, buf,
                                         MEASURE_CHUNK, measure_add, &m, err)
                 : gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        free(buf);
    } else if (!st) {
        st = measure_array(&m, c, nc, err);
    }
    if (!st)
        measure_finish(&m, nf, res->box[0] * res->box[1] * res->box[2], res);
    free(m.out);
    return st;
}

/* the optional DEM relaxation of the tiled packing (tile_relax_steps): moves the spheres of
 * tiled in the box [0, hi], and gives the DEM's own contacts (*tcon, malloc'ed), which the
 * measures then use */
static gp_status relax_tiled(const gp_spec3d *spec, const gp_dem3d_params *dp, run_ctx *rc,
                             gp_stats3d *S, double *tiled, size_t ntiled, const double hi[3],
                             gp_dem3d_contact **tcon, size_t *ntcon, gp_error *err)
{
    const double lo[3] = {0, 0, 0};
    gp_dem3d *dem = NULL;
    gp_dem3d_state ds;
    memset(&ds, 0, sizeof ds);
    gp_status st = gp_dem3d_create(dp, tiled, ntiled, lo, hi, &dem, err);
    if (!st)
        gp_dem3d_set_cancel(dem, rc->cancel);
    for (long s = 0; !st && s < spec->tile_relax_steps; s += CHUNK) {
        st = gp_dem3d_run(dem, CHUNK, err);
        gp_dem3d_get_state(dem, &ds);
        if (!st && report(rc, "tiling", 0.9 + 0.1 * s / spec->tile_relax_steps,
                          S->steps + ds.steps, spec->porosity, ds.stability, 0))
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        if (ds.stability <= STABILITY)
            break;
    }
    if (!st) {
        S->tiled_stability = ds.stability;
        gp_dem3d_spheres(dem, tiled);
        st = gp_dem3d_contacts(dem, tcon, ntcon, err);
    }
    gp_dem3d_destroy(dem);
    return st;
}

/* porosity of the tiled packing (box: the tiled box, sb: the sample's) from its true solid
 * volume: each copy clipped to its own tile (inner faces are not walls) */
static gp_status tiled_porosity(const int tiling[3], const double sb[3], const double box[3],
                                const double *tiled, size_t n, const volatile int *cancel,
                                double *porosity, gp_error *err)
{
    size_t nx = (size_t)tiling[0], ny = (size_t)tiling[1], ntile = nx * ny * (size_t)tiling[2];
    double solid = 0;
    for (size_t t = 0; t < ntile; t++) {
        if (cancel_raised(cancel))
            return gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        size_t kx = t % nx, ky = (t / nx) % ny, kz = t / (nx * ny);
        double tlo[3] = {kx * sb[0], ky * sb[1], kz * sb[2]};
        double thi[3] = {tlo[0] + sb[0], tlo[1] + sb[1], tlo[2] + sb[2]};
        solid += gp_dem3d_solid_volume(tiled + 4 * t * n, n, tlo, thi);
    }
    *porosity = 1 - solid / (box[0] * box[1] * box[2]);
    return GP_OK;
}

static gp_status validate(const gp_spec3d *s, gp_error *err)
{
    for (int a = 0; a < 3; a++)
        if (!isfinite(s->box[a]) || !(s->box[a] > 0))
            return gp_error_set(err, GP_ERR_INVALID, "box[%d] must be > 0", a);
    if (!(s->porosity > 0) || !(s->porosity < 1))
        return gp_error_set(err, GP_ERR_INVALID, "porosity must be in (0, 1)");
    const gp_material3d *m = &s->material;
    if (!(m->density > 0) || !isfinite(m->density))
        return gp_error_set(err, GP_ERR_INVALID, "material.density must be > 0");
    if (!(m->young > 0) || !isfinite(m->young))
        return gp_error_set(err, GP_ERR_INVALID, "material.young must be > 0");
    if (!(m->poisson >= 0) || !(m->poisson <= 10))
        return gp_error_set(err, GP_ERR_INVALID, "material.poisson (k_s/k_n) must be in [0, 10]");
    if (!(m->friction_deg >= 0) || !(m->friction_deg < 90))
        return gp_error_set(err, GP_ERR_INVALID, "material.friction_deg must be in [0, 90)");
    if (!(m->damping >= 0) || !(m->damping < 1))
        return gp_error_set(err, GP_ERR_INVALID, "material.damping must be in [0, 1)");
    for (int a = 0; a < 3; a++)
        if (s->tiling[a] < 1 || s->tiling[a] > 4096)
            return gp_error_set(err, GP_ERR_INVALID, "tiling[%d] must be in [1, 4096]", a);
    if (s->threads < 0 || s->threads > 256)
        return gp_error_set(err, GP_ERR_INVALID, "threads must be in [0, 256]");
    if (s->max_steps < 0 || s->tile_relax_steps < 0)
        return gp_error_set(err, GP_ERR_INVALID, "max_steps and tile_relax_steps must be >= 0");
    if (!s->sieve || s->nsieve < 2)
        return gp_error_set(err, GP_ERR_INVALID, "sieve: need at least 2 rows");
    return GP_OK;
}

gp_status gp_specimen3d_build(const gp_spec3d *spec, gp_progress_fn progress, void *user,
                              const volatile int *cancel, gp_specimen3d **out, gp_error *err)
{
    double t0 = now();
    *out = NULL;
    if (!spec)
        return gp_error_set(err, GP_ERR_INVALID, "spec is NULL");
    gp_status st = validate(spec, err);
    if (st)
        return st;
    size_t ns = spec->nsieve;
    double *sd = malloc(ns * sizeof *sd), *sw = malloc(ns * sizeof *sw);
    if (!sd || !sw) {
        free(sd); free(sw);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    for (size_t k = 0; k < ns; k++) {
        sd[k] = spec->sieve[k].diameter;
        sw[k] = spec->sieve[k].passing;
    }
    st = gp_sieve_validate(sd, sw, ns, err);
    if (st) {
        free(sd); free(sw);
        return st;
    }
    const double *B = spec->box;
    double bmin = fmin(B[0], fmin(B[1], B[2]));
    double dmax = sd[ns - 1];
    if (dmax > bmin) {
        free(sd); free(sw);
        return gp_error_set(err, GP_ERR_INVALID,
                            "box: its smallest side (%g m) is smaller than the largest grain "
                            "(%g m, the last sieve)", bmin, dmax);
    }
    size_t ntile = (size_t)spec->tiling[0] * (size_t)spec->tiling[1] * (size_t)spec->tiling[2];
    double p = spec->porosity;
    double V = B[0] * B[1] * B[2];
    double vs = (1 - p) * V; /* Eq. 8 corrected (NOTES.md) */

    gp_specimen3d *res = calloc(1, sizeof *res);
    gp_rng *rng = gp_rng_create(spec->seed, 0, err);
    double *diam = NULL, *xyzr = NULL;
    gp_dem3d *dem = NULL;
    gp_dem3d_contact *con = NULL, *tcon = NULL;
    double *tiled = NULL;
    size_t n = 0, ncon = 0, ntcon = 0, ntiled = 0;
    gp_status ret = GP_OK;
    if (!res || !rng) {
        ret = res ? (err ? err->code : GP_ERR_NOMEM) : gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        if (ret == GP_OK) ret = GP_ERR_NOMEM;
        goto fail;
    }
    st = gp_sieve_draw(sd, sw, ns, vs, MAX_SAMPLE_SPHERES, rng, &diam, &n, err);
    if (st) {
        ret = st;
        goto fail;
    }
    if (n * ntile > MAX_TILED_SPHERES) {
        ret = gp_error_set(err, GP_ERR_INVALID, "tiling: %zu tiles of %zu spheres exceed the limit "
                           "of %d spheres", ntile, n, MAX_TILED_SPHERES);
        goto fail;
    }
    /* PSD: targets and achieved (by the drawn sample) */
    gp_psd3d *psd = &res->stats.psd;
    psd->n = ns;
    psd->diameter = malloc(ns * sizeof(double));
    psd->target_weight = malloc(ns * sizeof(double));
    psd->target_number = malloc(ns * sizeof(double));
    psd->target_number_midbin = malloc(ns * sizeof(double));
    psd->achieved_weight = malloc(ns * sizeof(double));
    psd->achieved_number = malloc(ns * sizeof(double));
    xyzr = malloc(4 * n * sizeof *xyzr);
    if (!psd->diameter || !psd->target_weight || !psd->target_number || !psd->target_number_midbin
        || !psd->achieved_weight || !psd->achieved_number || !xyzr) {
        ret = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        goto fail;
    }
    memcpy(psd->diameter, sd, ns * sizeof *sd);
    memcpy(psd->target_weight, sw, ns * sizeof *sw);
    gp_sieve_weight_to_number(sd, sw, ns, GP_SIEVE_UNIFORM, psd->target_number, NULL);
    gp_sieve_weight_to_number(sd, sw, ns, GP_SIEVE_MIDBIN, psd->target_number_midbin, NULL);
    gp_sieve_passing(diam, n, sd, ns, psd->achieved_weight, psd->achieved_number);
    qsort(diam, n, sizeof *diam, cmp_desc);

    gp_stats3d *S = &res->stats;
    S->porosity_target = p;
    S->sample_particles = n;
    res->sample_box[0] = B[0];
    res->sample_box[1] = B[1];
    res->sample_box[2] = B[2];
    run_ctx rc = {progress, user, cancel, 0};
    const char *reason = "stable";

    /* ---- phase 0: placement and deposition ---- */
    double H0 = fmax(1.15 * B[2], B[2] * (1 - p) / 0.5);
    double L[3] = {B[0], B[1], H0};
    double lam = GROW_FROM;
    int tries = 0;
    int pl;
    while ((pl = place(diam, n, lam, L, rng, cancel, xyzr)) != 0) {
        if (pl < 0) {
            ret = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        if (pl == 2) {
            ret = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
            goto fail;
        }
        if (++tries > 12) {
            ret = gp_error_set(err, GP_ERR_INTERNAL, "deposition: cannot place the spheres");
            goto fail;
        }
        lam *= 0.85;
    }
    /* density scaling radius (see gp_dem3d.h): the median radius by number, but no less than
     * rmax / MAX_SCALED_RATIO. With the paper's sieve the median is rmax / 3.4; with a size
     * ratio of 20 it can be rmax / 12, and then dt (set by the scaled radius) is so small next
     * to the time the large grains need to move that the protocol costs 3-4 times more steps
     * than the sieve's range requires. Raising the small grains' inertia does not change the
     * static state (gravity acts on the true mass). */
    gp_dem3d_params dp;
    gp_dem3d_params_defaults(&dp);
    dp.density = spec->material.density;
    dp.young = spec->material.young;
    dp.ks_kn = spec->material.poisson;
    dp.friction_deg = spec->material.friction_deg;
    dp.damping = spec->material.damping;
    dp.gravity[2] = -GRAVITY;
    dp.scaled_radius = fmax(0.5 * diam[n / 2], 0.5 * diam[0] / MAX_SCALED_RATIO);
    dp.skin = 0.5 * diam[n - 1]; /* the smallest radius (rebuilds against candidates; results
                                    do not depend on it) */
    dp.dt_safety = DT_SAFETY;
    dp.threads = spec->threads > 0 ? spec->threads : 1;
    for (size_t i = 0; i < n; i++)
        xyzr[4 * i + 3] = 0.5 * diam[i]; /* full radii; the DEM scales them */
    double lo[3] = {0, 0, 0};
    st = gp_dem3d_create(&dp, xyzr, n, lo, L, &dem, err);
    if (st) {
        ret = st;
        goto fail;
    }
    gp_dem3d_set_cancel(dem, cancel); /* a chunk of 100 steps of a large sample takes seconds */
    /* Every duration of the protocol is a multiple of the skeleton's time sqrt(d50 / g) (d50 the
     * median diameter by weight: the grains that carry the load), the time a grain takes to
     * fall its own size. In steps this unit is ~860 for the paper's sieve and ~2300 for a size
     * ratio of 20, where dt follows the small grains: counted in steps, the windows that judge
     * progress were too short there, and the deposit never had the time to settle. */
    double d50 = diam[n - 1];
    {
        double tot = 0, acc = 0;
        for (size_t i = 0; i < n; i++)
            tot += diam[i] * diam[i] * diam[i];
        for (size_t i = 0; i < n; i++) { /* diam is sorted from the largest */
            acc += diam[i] * diam[i] * diam[i];
            if (acc >= 0.5 * tot) {
                d50 = diam[i];
                break;
            }
        }
    }
    double tu = sqrt(d50 / GRAVITY) / gp_dem3d_dt(dem); /* steps per time unit */
    long grow_steps = 10 * (long)ceil(GROW_T * tu / 10);
    long settle_steps = CHUNK * (long)ceil(SETTLE_T * tu / CHUNK);
    long ladder_steps = CHUNK * (long)ceil(LADDER_T * tu / CHUNK);
    long stall_steps = CHUNK * (long)ceil(STALL_T * tu / CHUNK);
    double lid_speed = LID_SPEED * sqrt(GRAVITY * d50);
    long max_steps = spec->max_steps > 0 ? spec->max_steps
                                         : (long)fmax(400000, MAX_T * tu);
    gp_dem3d_state ds;
    double t_phase = now();
    for (long s = 0; s < grow_steps; s += 10) {
        gp_dem3d_set_radius_scale(dem, lam + (1 - lam) * (double)(s + 10) / grow_steps);
        if ((st = gp_dem3d_run(dem, 10, err))) {
            ret = st;
            goto fail;
        }
        if (report(&rc, "deposition", 0.1 * s / grow_steps, s, 0, 0, 0)) {
            ret = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
            goto fail;
        }
    }
    gp_dem3d_set_radius_scale(dem, 1.0);
    for (long s = 0; s < settle_steps; s += CHUNK) {
        if ((st = gp_dem3d_run(dem, CHUNK, err))) {
            ret = st;
            goto fail;
        }
        gp_dem3d_get_state(dem, &ds);
        if (report(&rc, "deposition", 0.1 + 0.1 * s / settle_steps, ds.steps, 0, ds.stability, 0)) {
            ret = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
            goto fail;
        }
        if (ds.stability < SETTLE_SC)
            break;
    }
    res->t_deposition = now() - t_phase;

    /* ---- phase 1: compaction with the servo top wall (Eq. 10) and a friction ladder ---- */
    t_phase = now();
    double area = B[0] * B[1];
    double sigma0 = COMPACTION_STRESS * (1 - p) * spec->material.density * GRAVITY * B[2];
    gp_dem3d_set_servo(dem, 5, sigma0 * area, lid_speed);
    gp_dem3d_set_servo_limit(dem, 5, B[2]);
    double phi = spec->material.friction_deg;
    double h_touch = NAN, h_prev = H0, h_win = H0;
    int pushed = 0; /* the wall has pressed on grains */
    int reached = 0;
    long win_steps = 0, stall_steps_done = 0;
    double por_cp = 1;
    while (!reached) {
        if ((st = gp_dem3d_run(dem, CHUNK, err))) {
            ret = st;
            goto fail;
        }
        gp_dem3d_get_state(dem, &ds);
        double h = gp_dem3d_wall(dem, 5);
        double por = 1 - vs / (area * h);
        if (report(&rc, "compaction", 0.2 + 0.4 * fmin(1, (H0 - h) / (H0 - B[2])), ds.steps, por,
                   ds.stability, 0)) {
            ret = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
            goto fail;
        }
        pushed |= ds.wall_force[5] > 0;
        if (h <= B[2]) {
            reached = 1;
            break;
        }
        /* The wall slows down as it nears b_z (it may not close the remaining gap faster than
         * in APPROACH_T): the packing arrives at the target height nearly at rest, instead of
         * being driven there and settling on below the wall once it stops. */
        gp_dem3d_set_servo(dem, 5, sigma0 * area,
                           fmin(lid_speed, fmax(h - B[2], LADDER_MIN_LEFT * B[2])
                                               / (APPROACH_T * sqrt(d50 / GRAVITY))));
        /* The wall rests on the deposit when it carries half its force and has slowed to less
         * than half its free speed (a grain still bouncing can push it, but not stop it):
         * phase 0's porosity, and the start of the ladder. */
        if (isnan(h_touch) && ds.wall_force[5] >= 0.5 * sigma0 * area
            && h_prev - h < 0.5 * lid_speed * gp_dem3d_dt(dem) * CHUNK) {
            h_touch = h;
            h_win = h;
            win_steps = 0;
        }
        h_prev = h;
        /* Friction ladder (YADE's way of reaching a porosity, Chareyre's triaxial scripts):
         * while the wall, pressing with sigma0, gains less than LADDER_FRACTION of the height
         * still to go in LADDER_T, the packing is (nearly) jammed at this friction: lower it
         * by LADDER_FACTOR. The target height is then reached by a packing in equilibrium
         * at friction phi_c <= phi, which restoring phi can only stiffen: it does not settle
         * away from the wall during relaxation, as a loose heap pushed there without friction
         * can (it is not jammed at the target height, and keeps compacting under gravity:
         * with a size ratio of 20 the wall then lost every contact at once). */
        if (!isnan(h_touch) && phi > 0 && (win_steps += CHUNK) >= ladder_steps) {
            double left = fmax(h - B[2], LADDER_MIN_LEFT * B[2]);
            if (h_win - h < LADDER_FRACTION * left) {
                phi = phi * LADDER_FACTOR < LADDER_MIN_DEG ? 0 : phi * LADDER_FACTOR;
                gp_dem3d_set_friction(dem, phi);
                por_cp = por;
                stall_steps_done = 0;
            }
            h_win = h;
            win_steps = 0;
        }
        /* without friction, the approach has stalled: over the last STALL_T the porosity fell
         * by less than STALL_FRACTION of what remains to the target: the target is denser
         * than this sieve packs here (unless it is within POROSITY_SLACK: then this is the
         * sample's height) */
        if (phi == 0 && (stall_steps_done += CHUNK) >= stall_steps) {
            if (por_cp - por < STALL_FRACTION * (por - p) && por - p <= POROSITY_SLACK) {
                reached = 1;
                break;
            }
            if (por_cp - por < STALL_FRACTION * (por - p)) {
                reason = "target_too_dense";
                ret = gp_error_set(err, GP_ERR_INFEASIBLE,
                                   "porosity %g is denser than this sieve packs in this box "
                                   "without friction (stalled at %.4f)", p, por);
                break;
            }
            por_cp = por;
            stall_steps_done = 0;
        }
        if (ds.steps > max_steps) {
            reason = "max_steps";
            ret = gp_error_set(err, GP_ERR_NOT_CONVERGED, "compaction: %ld steps without reaching "
                               "porosity %g (at %.4f)", ds.steps, p, por);
            break;
        }
    }
    S->deposition_porosity = 1 - vs / (area * (isnan(h_touch) ? gp_dem3d_wall(dem, 5) : h_touch));
    S->compaction_friction_deg = phi;
    res->t_compaction = now() - t_phase;

    /* ---- relaxation at the target height, friction restored ---- */
    t_phase = now();
    if (reached) {
        /* The top wall stays a servo wall pressing with sigma0 (never below b_z): it keeps
         * the packing confined as it was compacted, and if the packing pushes harder it rises,
         * so the box it reports is the one the spheres fill. */
        gp_dem3d_set_friction(dem, spec->material.friction_deg);
        gp_dem3d_set_damping(dem, fmax(spec->material.damping, RELAX_DAMPING));
        /* pass 0: the wall never below b_z. Pass 1, only if the packing settled away from the
         * wall although the wall had pressed on it: the wall follows it down,
         * at most to the height of porosity p - POROSITY_SLACK, and relaxation goes on; the
         * porosity is then that of the lower box, still within the tolerance of the target. */
        double h_sink = vs / (area * (1 - (p - POROSITY_SLACK)));
        for (int pass = 0; pass < 2 && ret == GP_OK; pass++) {
            if (pass == 1) {
                if (ds.wall_force[5] > 0 || !pushed)
                    break;
                gp_dem3d_set_servo_limit(dem, 5, h_sink);
            }
            for (;;) {
                if ((st = gp_dem3d_run(dem, CHUNK, err))) {
                    ret = st;
                    goto fail;
                }
                gp_dem3d_get_state(dem, &ds);
                double sc = ds.stability;
                double fr = log(fmax(sc, STABILITY) / 1.0) / log(STABILITY);
                if (report(&rc, "relaxation", 0.6 + 0.3 * fmin(1, fmax(0, fr)), ds.steps,
                           1 - vs / (area * gp_dem3d_wall(dem, 5)), sc, 0)) {
                    ret = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
                    goto fail;
                }
                /* (pass 1: and the wall is back on the packing, or as low as it may go) */
                if (sc <= STABILITY
                    && (pass == 0 || ds.wall_force[5] > 0 || gp_dem3d_wall(dem, 5) <= h_sink))
                    break;
                if (ds.steps > max_steps) {
                    reason = "max_steps";
                    ret = gp_error_set(err, GP_ERR_NOT_CONVERGED,
                                       "relaxation: S_c = %.3g after %ld steps (> 1e-4)", sc,
                                       ds.steps);
                    break;
                }
            }
        }
        if (ret == GP_OK && !(ds.wall_force[5] > 0)) {
            /* the wall never touched a grain above b_z: the deposit is denser than the target;
             * or (pass 1) the packing settled further than POROSITY_SLACK */
            reason = "target_too_loose";
            ret = gp_error_set(err, GP_ERR_INFEASIBLE,
                               "porosity %g is looser than this sieve holds at friction %g deg: "
                               "the packing settles below the top wall (%s)", p,
                               spec->material.friction_deg,
                               !pushed ? "the deposit is denser"
                                       : "after compaction to the target height");
        }
    }
    res->t_relaxation = now() - t_phase;
    gp_dem3d_get_state(dem, &ds);
    S->stability = ds.stability;
    S->steps = ds.steps;
    S->dt = gp_dem3d_dt(dem);
    S->stop_reason = reason;
    gp_dem3d_spheres(dem, xyzr);
    res->sample_box[2] = gp_dem3d_wall(dem, 5);
    st = gp_dem3d_contacts(dem, &con, &ncon, err);
    if (st) {
        ret = st;
        goto fail;
    }
    gp_dem3d_destroy(dem);
    dem = NULL;
    {
        double hi[3] = {res->sample_box[0], res->sample_box[1], res->sample_box[2]};
        double Vb = hi[0] * hi[1] * hi[2];
        S->sample_porosity = 1 - gp_dem3d_solid_volume(xyzr, n, lo, hi) / Vb;
    }

    /* ---- phase 2: flip tiling ---- */
    t_phase = now();
    for (int a = 0; a < 3; a++)
        res->box[a] = res->sample_box[a];
    int tile = ntile > 1 && (ret == GP_OK || ret == GP_ERR_NOT_CONVERGED);
    int relaxed = tile && spec->tile_relax_steps > 0; /* measured on the DEM's contacts */
    if (tile) {
        report(&rc, "tiling", 0.9, S->steps, p, S->stability, 1);
        st = gp_flip_tile_ex(xyzr, n, res->sample_box, spec->tiling, MAX_TILED_SPHERES, cancel,
                             &tiled, &ntiled, err);
        /* (the reports between the steps show the phase: a tiling of 10^7 spheres takes
         * seconds, and the first report may have come too soon after the last to be shown) */
        if (!st && report(&rc, "tiling", 0.93, S->steps, p, S->stability, 0))
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        for (int a = 0; a < 3; a++)
            res->box[a] = res->sample_box[a] * spec->tiling[a];
        if (!st && relaxed)
            st = relax_tiled(spec, &dp, &rc, S, tiled, ntiled, res->box, &tcon, &ntcon, err);
        if (!st)
            st = tiled_porosity(spec->tiling, res->sample_box, res->box, tiled, n, cancel,
                                &S->porosity, err);
        if (st) {
            ret = st;
            goto fail;
        }
    } else {
        S->porosity = S->sample_porosity;
    }

    /* ---- measures on the final packing ---- */
    /* Without a tiled relaxation the tiled contacts are the sample's, mapped by the flip as
     * they are measured (never all held unless the list is an output); t_tiling counts that
     * pass too. */
    if (report(&rc, "tiling", 0.96, S->steps, p, S->stability, 0)) {
        ret = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        goto fail;
    }
    S->particles = tile ? ntiled : n;
    res->count = S->particles;
    st = measure(spec, tile && !relaxed, relaxed ? tcon : con, relaxed ? ntcon : ncon, xyzr, n,
                 tile ? tiled : xyzr, S->particles, cancel, res, err);
    if (st) {
        ret = st;
        goto fail;
    }
    res->t_tiling = now() - t_phase;
    if (spec->outputs & GP_OUT3_SPHERES) {
        if (tile) {
            res->spheres = tiled;
            tiled = NULL;
        } else {
            res->spheres = xyzr;
            xyzr = NULL;
        }
    }
    report(&rc, "tiling", 1.0, S->steps, S->porosity, S->stability, 1);
    free(con); free(tcon); free(tiled); free(xyzr); free(diam); free(sd); free(sw);
    gp_rng_destroy(rng);
    res->t_total = now() - t0;
    *out = res;
    return ret;

fail:
    gp_dem3d_destroy(dem);
    free(con); free(tcon); free(tiled); free(xyzr); free(diam); free(sd); free(sw);
    if (rng) gp_rng_destroy(rng);
    gp_specimen3d_destroy(res);
    return ret;
}
