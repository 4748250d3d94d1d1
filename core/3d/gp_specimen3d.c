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
 *  step follows its small grains) gets the same physical time as the paper's. For the same
 *  reason the servo is a rate in time (gp_dem3d_set_servo_dt): deposition and compaction, at
 *  the material's damping, step longer than relaxation (DT_DAMPING_EXP), and the wall moves
 *  as it would at relaxation's step.
 *  phase 2, tiling: gp_flip.
 * Code: gp_specimen3d_build() runs one function per phase over one build_run (read_spec,
 * draw_sample, place_sample, start_dem, deposit, compact, relax, collect_sample, tile_sample,
 * measure_final, measure_transfer); the measures of the final packing are one pass over its
 * contacts (measure); a tiled specimen's sample and final packing are then measured side by
 * side by gp_transfer (measure_transfer), which reads the spheres and contacts and changes
 * nothing else.
 */
#include "gp_specimen3d.h"

#include "gp_alloc.h"
#include "gp_clock.h"
#include "gp_dem3d.h"
#include "gp_flip.h"
#include "gp_rng.h"
#include "gp_sieve.h"
#include "gp_transfer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MAX_SAMPLE_SPHERES 400000
#define MAX_TILED_SPHERES 20000000
#define GRAVITY GP_SPEC3D_GRAVITY
#define STABILITY GP_SPEC3D_STABILITY /* Eq. 7: 0.01 % */
#define GROW_FROM 0.6            /* initial radius scale of the placement */
/* durations, in units of sqrt(d50 / g) (see where tu is computed; the paper's sieve has ~860
 * steps per unit at the relaxation's dt, ~735 at the deposition's and compaction's) */
#define GROW_T 1.75              /* growth of the radii */
#define SETTLE_T 1.2             /* deposition ends after this ... */
#define SETTLE_SC 5e-2           /* ... or when S_c is below this */
#define LADDER_T 0.35            /* progress window of the friction ladder */
#define STALL_T 3.5              /* progress window without friction */
#define MAX_T 500                /* default cap on the DEM steps (at least 400,000) */
#define LID_SPEED 1.4            /* top-wall speed limit, times sqrt(g d50) (1 m/s in the paper) */
#define APPROACH_T 1.0           /* the wall closes the gap to b_z in no less than this */
#define CHUNK 100
/* Relaxation looks at S_c (Eq. 7, measured on a run's last step) every CHUNK steps and stops
 * at the first look <= 1e-4: the paper's condition, checked once (as YADE's scripts check
 * it). S_c is noisy there (rattlers settling): after that stop it is back above 1e-4 at most
 * later looks, and holding it for 100 steps would cost hundreds to thousands of steps more. A
 * finer look stops earlier, on a dip of that noise, and leaves the packing no more stable, so
 * the look stays at CHUNK (docs/design/specimen3d.md). */
#define STALL_FRACTION 0.1
#define LADDER_FRACTION 0.2      /* least progress per window, of the height still to go */
#define LADDER_MIN_LEFT 0.004    /* ... counted as at least this fraction of b_z; also the
                                    least gap of the approach's speed limit (APPROACH_T). The
                                    last stretch of compaction creeps at this floor: lower, it
                                    creeps longer; higher, relaxation takes longer than
                                    compaction saves (the packing arrives faster than it
                                    settles; docs/design/specimen3d.md) */
#define LADDER_FACTOR 0.5        /* friction step of the ladder */
#define LADDER_MIN_DEG 0.5       /* below this the ladder goes to zero friction */
#define MAX_SCALED_RATIO 3.5     /* density scaling radius >= rmax / this */
#define POROSITY_SLACK 0.003     /* the wall may end this far from the target porosity (the
                                    tolerance is 0.005): above, where the packing jams without
                                    friction; below, following a packing that settles away */
/* DT_SAFETY (0.4): of sqrt(m / 2 E R), m density-scaled, at the relaxation's damping c = 0.7.
 * The DEM checks every step against a proven bound on omega_max (shear and rotation included)
 * and the limit omega dt < 2 / sqrt(1 + c) of leapfrog with local damping c (gp_dem3d.h); a
 * little higher, relaxation needs cuts on some seeds (docs/design/specimen3d.md).
 * DT_DAMPING_EXP (0.45): the other phases (c = the material's 0.2) step
 * ((1 + 0.7) / (1 + c))^0.45 = 1.17 x longer (params.dt_damping_exp): for the same contacts
 * they use (1.2 / 1.7)^0.05 = 0.98 of the relaxation's fraction of its own limit, so that no
 * phase needs a cut. 0.5 (the same fraction, 1.19 x) saves as many steps, but a small loose
 * spec of the integration tests then jams short of its porosity (docs/design/specimen3d.md).
 * Both are public (gp_specimen3d.h): a triaxial test of the specimen steps by the same rule. */
#define DT_SAFETY GP_SPEC3D_DT_SAFETY
#define DT_DAMPING_EXP GP_SPEC3D_DT_DAMPING_EXP
#define COMPACTION_STRESS 1.0    /* top-wall stress, times the geostatic stress at the bottom */
/* local damping during relaxation (the static state does not depend on it; S_c <= 1e-4 comes
 * far sooner than at the material's 0.2: docs/design/specimen3d.md) */
#define RELAX_DAMPING GP_SPEC3D_RELAX_DAMPING

/* the phase fractions of the progress reports (gp_progress.h) */
#define COMPACT_GAP_END 3e-4     /* compaction: the log of the wall's gap to b_z, from its start
                                    to this fraction of b_z (nearly the end: the last stretch,
                                    at a constant speed, is quicker on this scale) */
#define TILE_FLIP_PF 0.4         /* tiling: the flip done ... */
#define TILE_MEASURE_PF 0.6      /* ... and the tiled relaxation, before the measures */
#define TILE_TRANSFER_PF 0.7     /* ... and the measures, before gp_transfer's (a tiling) */

/* gp_transfer's g(r) (measure_transfer): bins of TRANSFER_DR up to TRANSFER_R_MAX, in units of
 * the sample's d50, the final packing's on a block of at most TRANSFER_BLOCK tiles a side */
#define TRANSFER_DR 0.05
#define TRANSFER_R_MAX 5.0
#define TRANSFER_R_MAX_BOX 0.75  /* r_max <= this x the box's shortest side (gp_transfer.h) */
#define TRANSFER_BLOCK 2

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

/* the caller's progress callback and cancel flag, paced (gp_progress_pace) */
typedef gp_progress_pacer progress_ctx;

/* the caller's cancel flag, raised by another thread with an atomic store */

static int report(progress_ctx *c, const char *phase, double fraction, double pf, long steps,
                  double porosity, double sc, int force)
{
    gp_progress p = {.phase = phase, .fraction = fraction, .phase_fraction = pf, .steps = steps,
                     .porosity = porosity, .stability = sc};
    return gp_progress_pace(c, p, force);
}

/* How far a gap closing towards end has come from g0, on a log scale: 0 at g0, 1 at end or
 * below (a servo's gap and S_c both close about exponentially: this grows with the time). */
static double gap_progress(double g0, double g, double end)
{
    if (!(g0 > end) || !(g > end)) return 1;
    return fmax(0, log(g0 / g) / log(g0 / end));
}

void gp_specimen3d_destroy(gp_specimen3d *s)
{
    if (!s)
        return;
    free(s->spheres);
    free(s->sample_spheres);
    free(s->contacts);
    free(s->stats.psd.diameter);
    free(s->stats.psd.target_weight);
    free(s->stats.psd.target_number);
    free(s->stats.psd.target_number_midbin);
    free(s->stats.psd.achieved_weight);
    free(s->stats.psd.achieved_number);
    free(s->transfer_sample);
    free(s->transfer_final);
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
        if (i % 256 == 0 && gp_progress_cancelled(cancel)) {
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
 * asked for (~2 GB for 7.5 million spheres); an untiled or relaxed packing's array goes
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
static gp_status measure_add(void *user, const gp_contact3d *c, size_t k, gp_error *err)
{
    measure_acc *m = user;
    if (gp_progress_cancelled(m->cancel))
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
        memcpy(m->out + m->nout, c, k * sizeof *c);
        m->nout += k;
    }
    return GP_OK;
}

/* the same, over an array, chunk by chunk (the cancel flag is looked at between them) */
static gp_status measure_array(measure_acc *m, const gp_contact3d *c, size_t nc,
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
 * (c, nc; n spheres), mapped to the tiling on the fly; else c is the final list. */
static gp_status measure(const gp_spec3d *spec, int stream, const gp_contact3d *c, size_t nc,
                         size_t n, const double *fx, size_t nf, const volatile int *cancel,
                         gp_specimen3d *res, gp_error *err)
{
    size_t ntile = (size_t)spec->tiling[0] * (size_t)spec->tiling[1] * (size_t)spec->tiling[2];
    measure_acc m;
    gp_status st = measure_init(&m, spec->outputs, fx, stream ? ntile * nc : nc, cancel, err);
    if (!st && stream) {
        gp_contact3d *buf = malloc(MEASURE_CHUNK * sizeof *buf);
        st = buf ? gp_flip_contacts_each(c, nc, n, spec->tiling, cancel, buf, MEASURE_CHUNK,
                                         measure_add, &m, err)
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
static gp_status relax_tiled(const gp_spec3d *spec, const gp_dem3d_params *dp, progress_ctx *rc,
                             gp_stats3d *S, double *tiled, size_t ntiled, const double hi[3],
                             gp_contact3d **tcon, size_t *ntcon, gp_error *err)
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
        double f = (double)s / spec->tile_relax_steps;
        if (!st && report(rc, "tiling", 0.9 + 0.1 * f,
                          TILE_FLIP_PF + (TILE_MEASURE_PF - TILE_FLIP_PF) * f,
                          S->steps + ds.steps, spec->porosity, ds.stability, 0))
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        if (ds.stability <= STABILITY)
            break;
    }
    if (!st) {
        S->dt_cuts += ds.dt_cuts; /* (flipped walls are image spheres: stiffer than walls) */
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
        if (gp_progress_cancelled(cancel))
            return gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        size_t kx = t % nx, ky = (t / nx) % ny, kz = t / (nx * ny);
        double tlo[3] = {kx * sb[0], ky * sb[1], kz * sb[2]};
        double thi[3] = {tlo[0] + sb[0], tlo[1] + sb[1], tlo[2] + sb[2]};
        solid += gp_dem3d_solid_volume(tiled + 4 * t * n, n, tlo, thi);
    }
    *porosity = 1 - solid / (box[0] * box[1] * box[2]);
    return GP_OK;
}

gp_status gp_material3d_check(const gp_material3d *m, gp_error *err)
{
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
    gp_status mst = gp_material3d_check(m, err);
    if (mst)
        return mst;
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
/* ---- the build: one run struct, a function per phase ----
 * gp_specimen3d_build() runs the phases below in order over one build_run. A phase returns
 * GP_OK to go on, or the status of a failure that leaves no specimen (bad spec, out of
 * memory, cancelled, a DEM error). An end that still gives a specimen (target_too_dense,
 * max_steps, target_too_loose) is kept in R->outcome and R->reason, and the later phases go
 * on as the protocol says. Everything a phase allocates is the run's until
 * build_run_release(); the result (R->res) moves to *out on success. */
typedef struct build_run {
    const gp_spec3d *spec;
    const volatile int *cancel;
    progress_ctx rc;
    gp_error *err;
    double *sd, *sw;         /* the sieve: diameters, percent passing (spec->nsieve rows) */
    size_t ntile;            /* tiles of the flip */
    double p, vs;            /* target porosity; solid volume (1 - p) V (Eq. 8 corrected, NOTES.md) */
    gp_specimen3d *res;      /* the result being filled */
    gp_rng *rng;
    double *diam;            /* the n drawn diameters, sorted from the largest */
    size_t n;
    double *xyzr;            /* the sample's spheres, 4n */
    /* phases 0-1 and relaxation */
    gp_dem3d_params dp;
    gp_dem3d *dem;
    gp_dem3d_state ds;       /* the DEM's state after its last chunk */
    double lam;              /* radius scale of the placement */
    double H0;               /* height of the deposition box */
    double d50;              /* median diameter by weight; the time unit is sqrt(d50 / g) */
    long grow_steps, settle_steps, ladder_steps, stall_steps, max_steps;
    double lid_speed;        /* the top wall's speed limit */
    double area, sigma0;     /* the top wall's area and servo stress (phase 1 on) */
    int pushed;              /* the top wall has pressed on grains */
    int reached;             /* the top wall reached b_z (or stalled within POROSITY_SLACK) */
    long phase_start;        /* the DEM's steps when the current phase began */
    gp_status outcome;       /* GP_OK, GP_ERR_INFEASIBLE or GP_ERR_NOT_CONVERGED */
    const char *reason;      /* stats.stop_reason */
    /* phase 2 */
    gp_contact3d *con, *tcon; /* the sample's contacts; the relaxed tiling's */
    size_t ncon, ntcon;
    double *tiled;           /* the tiled spheres, 4 ntiled */
    size_t ntiled;
    int tile, relaxed;       /* the sample is tiled; the tiling is relaxed by the DEM */
} build_run;

static void build_run_release(build_run *R)
{
    gp_dem3d_destroy(R->dem);
    free(R->con); free(R->tcon); free(R->tiled); free(R->xyzr); free(R->diam);
    free(R->sd); free(R->sw);
    gp_rng_destroy(R->rng);
}

/* the spec's checks, and its sieve as two arrays (R->sd, R->sw) */
static gp_status read_spec(build_run *R)
{
    const gp_spec3d *spec = R->spec;
    gp_status st = validate(spec, R->err);
    if (st)
        return st;
    size_t ns = spec->nsieve;
    double **const sieve[] = {&R->sd, &R->sw};
    if ((st = gp_alloc_doubles(ns, sieve, 2, R->err)))
        return st;
    for (size_t k = 0; k < ns; k++) {
        R->sd[k] = spec->sieve[k].diameter;
        R->sw[k] = spec->sieve[k].passing;
    }
    st = gp_sieve_validate(R->sd, R->sw, ns, R->err);
    if (st)
        return st;
    const double *B = spec->box;
    double bmin = fmin(B[0], fmin(B[1], B[2]));
    double dmax = R->sd[ns - 1];
    if (dmax > bmin)
        return gp_error_set(R->err, GP_ERR_INVALID,
                            "box: its smallest side (%g m) is smaller than the largest grain "
                            "(%g m, the last sieve)", bmin, dmax);
    R->ntile = (size_t)spec->tiling[0] * (size_t)spec->tiling[1] * (size_t)spec->tiling[2];
    R->p = spec->porosity;
    double V = B[0] * B[1] * B[2];
    R->vs = (1 - R->p) * V; /* Eq. 8 corrected (NOTES.md) */
    return GP_OK;
}

/* the result, the random stream, the sieve drawn for V_s (sorted from the largest), and the
 * PSD: targets and achieved (by the drawn sample) */
static gp_status draw_sample(build_run *R)
{
    gp_error *err = R->err;
    const double *B = R->spec->box;
    R->res = calloc(1, sizeof *R->res);
    R->rng = gp_rng_create(R->spec->seed, 0, err);
    if (!R->res)
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    if (!R->rng)
        return GP_ERR_NOMEM; /* err set by gp_rng_create */
    size_t ns = R->spec->nsieve;
    gp_status st = gp_sieve_draw(R->sd, R->sw, ns, R->vs, MAX_SAMPLE_SPHERES, R->rng, &R->diam,
                                 &R->n, err);
    if (st)
        return st;
    if (R->n * R->ntile > MAX_TILED_SPHERES)
        return gp_error_set(err, GP_ERR_INVALID, "tiling: %zu tiles of %zu spheres exceed the limit "
                            "of %d spheres", R->ntile, R->n, MAX_TILED_SPHERES);
    gp_psd3d *psd = &R->res->stats.psd;
    psd->n = ns;
    double **const cols[] = {&psd->diameter,        &psd->target_weight,   &psd->target_number,
                             &psd->target_number_midbin, &psd->achieved_weight,
                             &psd->achieved_number};
    if (gp_alloc_doubles(ns, cols, 6, err) || !(R->xyzr = malloc(4 * R->n * sizeof *R->xyzr)))
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    memcpy(psd->diameter, R->sd, ns * sizeof *R->sd);
    memcpy(psd->target_weight, R->sw, ns * sizeof *R->sw);
    gp_sieve_weight_to_number(R->sd, R->sw, ns, GP_SIEVE_UNIFORM, psd->target_number, NULL);
    gp_sieve_weight_to_number(R->sd, R->sw, ns, GP_SIEVE_MIDBIN, psd->target_number_midbin, NULL);
    gp_sieve_passing(R->diam, R->n, R->sd, ns, psd->achieved_weight, psd->achieved_number);
    qsort(R->diam, R->n, sizeof *R->diam, cmp_desc);

    gp_stats3d *S = &R->res->stats;
    S->porosity_target = R->p;
    S->sample_particles = R->n;
    for (int a = 0; a < 3; a++)
        R->res->sample_box[a] = B[a];
    return GP_OK;
}

/* ---- phase 0: placement and deposition ---- */

/* the spheres placed at random without overlap at radius scale R->lam (GROW_FROM, times 0.85
 * for each failed try, at most 12) in the deposition box: the sample's plan, height R->H0 */
static gp_status place_sample(build_run *R)
{
    const double *B = R->spec->box;
    R->H0 = fmax(1.15 * B[2], B[2] * (1 - R->p) / 0.5);
    double L[3] = {B[0], B[1], R->H0};
    double lam = GROW_FROM;
    int tries = 0;
    int pl;
    while ((pl = place(R->diam, R->n, lam, L, R->rng, R->cancel, R->xyzr)) != 0) {
        if (pl < 0)
            return gp_error_set(R->err, GP_ERR_NOMEM, "out of memory");
        if (pl == 2)
            return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
        if (++tries > 12)
            return gp_error_set(R->err, GP_ERR_INTERNAL, "deposition: cannot place the spheres");
        lam *= 0.85;
    }
    R->lam = lam;
    return GP_OK;
}

/* the DEM over the placed spheres at full radii (it scales them), and the protocol's durations
 * in its steps */
static gp_status start_dem(build_run *R)
{
    const gp_spec3d *spec = R->spec;
    const double *diam = R->diam;
    size_t n = R->n;
    /* density scaling radius (see gp_dem3d.h): the median radius by number, but no less than
     * rmax / MAX_SCALED_RATIO. With the paper's sieve the median is rmax / 3.4; with a size
     * ratio of 20 it can be rmax / 12, and then dt (set by the scaled radius) is so small next
     * to the time the large grains need to move that the protocol costs 3-4 times more steps
     * than the sieve's range requires. Raising the small grains' inertia does not change the
     * static state (gravity acts on the true mass). */
    gp_dem3d_params *dp = &R->dp;
    gp_dem3d_params_defaults(dp);
    dp->density = spec->material.density;
    dp->young = spec->material.young;
    dp->ks_kn = spec->material.poisson;
    dp->friction_deg = spec->material.friction_deg;
    dp->damping = spec->material.damping;
    dp->gravity[2] = -GRAVITY;
    dp->scaled_radius = fmax(0.5 * diam[n / 2], 0.5 * diam[0] / MAX_SCALED_RATIO);
    dp->skin = 0.5 * diam[n - 1]; /* the smallest radius (rebuilds against candidates; results
                                     do not depend on it) */
    /* the step of damping c is DT_SAFETY ((1 + RELAX_DAMPING) / (1 + c))^DT_DAMPING_EXP of
     * sqrt(m / 2 E R): the relaxation's is DT_SAFETY's */
    dp->dt_safety = DT_SAFETY * pow(1 + RELAX_DAMPING, DT_DAMPING_EXP);
    dp->dt_damping_exp = DT_DAMPING_EXP;
    R->res->stats.scaled_radius = dp->scaled_radius;
    dp->threads = spec->threads > 0 ? spec->threads : 1;
    for (size_t i = 0; i < n; i++)
        R->xyzr[4 * i + 3] = 0.5 * diam[i]; /* full radii; the DEM scales them */
    double lo[3] = {0, 0, 0};
    double L[3] = {spec->box[0], spec->box[1], R->H0};
    gp_status st = gp_dem3d_create(dp, R->xyzr, n, lo, L, &R->dem, R->err);
    if (st)
        return st;
    /* The servo is a rate in time, SERVO_GAIN per step of the relaxation's dt: the windows
     * that judge the wall's progress are in time, and at a longer step a servo moving a
     * fixed fraction per step would press faster, and the protocol would change with dt.
     * (Setting the damping back gives the first step bit for bit: dt_und is unchanged.) */
    double c_relax = fmax(spec->material.damping, RELAX_DAMPING);
    gp_dem3d_set_damping(R->dem, c_relax);
    double dt_relax = gp_dem3d_dt(R->dem);
    gp_dem3d_set_servo_dt(R->dem, dt_relax);
    gp_dem3d_set_damping(R->dem, spec->material.damping);
    gp_dem3d_set_cancel(R->dem, R->cancel); /* a chunk of 100 steps of a large sample takes seconds */
    /* Every duration of the protocol is a multiple of the skeleton's time sqrt(d50 / g) (d50 the
     * median diameter by weight: the grains that carry the load), the time a grain takes to
     * fall its own size. In steps this unit is ~860 for the paper's sieve and ~2300 for a size
     * ratio of 20 (at the relaxation's dt; 1.17 x fewer at the deposition's, tu), where dt
     * follows the small grains: counted in steps, the windows that judge progress would be too
     * short there, and the deposit would never have the time to settle. */
    double d50 = diam[n - 1];
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
    R->d50 = d50;
    double tu = sqrt(d50 / GRAVITY) / gp_dem3d_dt(R->dem); /* steps per time unit */
    R->grow_steps = 10 * (long)ceil(GROW_T * tu / 10);
    R->settle_steps = CHUNK * (long)ceil(SETTLE_T * tu / CHUNK);
    R->ladder_steps = CHUNK * (long)ceil(LADDER_T * tu / CHUNK);
    R->stall_steps = CHUNK * (long)ceil(STALL_T * tu / CHUNK);
    R->lid_speed = LID_SPEED * sqrt(GRAVITY * d50);
    /* the cap counts steps of the relaxation's (shortest) dt, as when every phase had it */
    double tu_relax = sqrt(d50 / GRAVITY) / dt_relax;
    R->max_steps = spec->max_steps > 0 ? spec->max_steps : (long)fmax(400000, MAX_T * tu_relax);
    return GP_OK;
}

/* the end of DEM phase k (0 deposition, 1 compaction, 2 relaxation): its time step, steps and
 * largest fraction of the stability limit into the stats; the next phase's fraction starts
 * afresh */
static void end_phase(build_run *R, int k)
{
    gp_stats3d *S = &R->res->stats;
    gp_dem3d_get_state(R->dem, &R->ds);
    S->phase_dt[k] = gp_dem3d_dt(R->dem);
    S->phase_steps[k] = R->ds.steps - R->phase_start;
    S->phase_dt_ratio[k] = R->ds.dt_ratio;
    S->dt_cuts = R->ds.dt_cuts;
    R->phase_start = R->ds.steps;
    gp_dem3d_reset_dt_ratio(R->dem);
}

/* the radii grow to full size under gravity (GROW_T), then the deposit settles (SETTLE_T, or
 * until S_c < SETTLE_SC) */
static gp_status deposit(build_run *R)
{
    gp_dem3d *dem = R->dem;
    gp_dem3d_state *ds = &R->ds;
    double lam = R->lam;
    long grow_steps = R->grow_steps, settle_steps = R->settle_steps;
    gp_status st;
    double t_phase = gp_clock_seconds();
    for (long s = 0; s < grow_steps; s += 10) {
        gp_dem3d_set_radius_scale(dem, lam + (1 - lam) * (double)(s + 10) / grow_steps);
        if ((st = gp_dem3d_run(dem, 10, R->err)))
            return st;
        if (report(&R->rc, "deposition", 0.1 * s / grow_steps,
                   (double)s / (grow_steps + settle_steps), s, 0, 0, 0))
            return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
    }
    gp_dem3d_set_radius_scale(dem, 1.0);
    for (long s = 0; s < settle_steps; s += CHUNK) {
        if ((st = gp_dem3d_run(dem, CHUNK, R->err)))
            return st;
        gp_dem3d_get_state(dem, ds);
        if (report(&R->rc, "deposition", 0.1 + 0.1 * s / settle_steps,
                   (double)(grow_steps + s) / (grow_steps + settle_steps), ds->steps, 0,
                   ds->stability, 0))
            return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
        if (ds->stability < SETTLE_SC)
            break;
    }
    end_phase(R, 0);
    R->res->t_deposition = gp_clock_seconds() - t_phase;
    return GP_OK;
}

/* ---- phase 1: compaction with the servo top wall (Eq. 10) and a friction ladder ----
 * Sets R->reached, or R->outcome and R->reason (target_too_dense, max_steps); phase 0's
 * porosity is read where the wall comes to rest on the deposit. */
static gp_status compact(build_run *R)
{
    const gp_spec3d *spec = R->spec;
    const double *B = spec->box;
    gp_dem3d *dem = R->dem;
    gp_dem3d_state *ds = &R->ds;
    gp_stats3d *S = &R->res->stats;
    double p = R->p, vs = R->vs, H0 = R->H0, d50 = R->d50, lid_speed = R->lid_speed;
    gp_status st;
    double t_phase = gp_clock_seconds();
    double area = B[0] * B[1];
    double sigma0 = COMPACTION_STRESS * (1 - p) * spec->material.density * GRAVITY * B[2];
    R->area = area;
    R->sigma0 = sigma0;
    gp_dem3d_set_servo(dem, 5, sigma0 * area, lid_speed);
    gp_dem3d_set_servo_limit(dem, 5, B[2]);
    double phi = spec->material.friction_deg;
    double h_touch = NAN, h_prev = H0, h_win = H0;
    long win_steps = 0, stall_steps_done = 0;
    double por_cp = 1;
    while (!R->reached) {
        if ((st = gp_dem3d_run(dem, CHUNK, R->err)))
            return st;
        gp_dem3d_get_state(dem, ds);
        double h = gp_dem3d_wall(dem, 5);
        double por = 1 - vs / (area * h);
        if (report(&R->rc, "compaction", 0.2 + 0.4 * fmin(1, (H0 - h) / (H0 - B[2])),
                   gap_progress(H0 - B[2], h - B[2], COMPACT_GAP_END * B[2]), ds->steps, por,
                   ds->stability, 0))
            return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
        R->pushed |= ds->wall_force[5] > 0;
        if (h <= B[2]) {
            R->reached = 1;
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
        if (isnan(h_touch) && ds->wall_force[5] >= 0.5 * sigma0 * area
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
        if (!isnan(h_touch) && phi > 0 && (win_steps += CHUNK) >= R->ladder_steps) {
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
        if (phi == 0 && (stall_steps_done += CHUNK) >= R->stall_steps) {
            if (por_cp - por < STALL_FRACTION * (por - p) && por - p <= POROSITY_SLACK) {
                R->reached = 1;
                break;
            }
            if (por_cp - por < STALL_FRACTION * (por - p)) {
                R->reason = "target_too_dense";
                R->outcome = gp_error_set(R->err, GP_ERR_INFEASIBLE,
                                          "porosity %g is denser than this sieve packs in this box "
                                          "without friction (stalled at %.4f)", p, por);
                break;
            }
            por_cp = por;
            stall_steps_done = 0;
        }
        if (ds->steps > R->max_steps) {
            R->reason = "max_steps";
            R->outcome = gp_error_set(R->err, GP_ERR_NOT_CONVERGED, "compaction: %ld steps without "
                                      "reaching porosity %g (at %.4f)", ds->steps, p, por);
            break;
        }
    }
    S->deposition_porosity = 1 - vs / (area * (isnan(h_touch) ? gp_dem3d_wall(dem, 5) : h_touch));
    S->compaction_friction_deg = phi;
    end_phase(R, 1);
    R->res->t_compaction = gp_clock_seconds() - t_phase;
    return GP_OK;
}

/* ---- relaxation at the target height, friction restored ----
 * Only when the wall reached b_z. The top wall stays a servo wall pressing with sigma0 (never
 * below b_z): it keeps the packing confined as it was compacted, and if the packing pushes
 * harder it rises, so the box it reports is the one the spheres fill. Pass 0: the wall never
 * below b_z. Pass 1, only if the packing settled away from the wall although the wall had
 * pressed on it: the wall follows it down, at most to the height of porosity
 * p - POROSITY_SLACK, and relaxation goes on; the porosity is then that of the lower box,
 * still within the tolerance of the target. Sets R->outcome and R->reason on max_steps or
 * target_too_loose. */
static gp_status relax(build_run *R)
{
    const gp_spec3d *spec = R->spec;
    gp_dem3d *dem = R->dem;
    gp_dem3d_state *ds = &R->ds;
    double p = R->p, vs = R->vs, area = R->area;
    double t_phase = gp_clock_seconds();
    if (R->reached) {
        gp_dem3d_set_friction(dem, spec->material.friction_deg);
        gp_dem3d_set_damping(dem, fmax(spec->material.damping, RELAX_DAMPING));
        double h_sink = vs / (area * (1 - (p - POROSITY_SLACK)));
        double sc0 = -1, pf = 0; /* progress: log(S_c) from its first value towards STABILITY */
        for (int pass = 0; pass < 2 && R->outcome == GP_OK; pass++) {
            if (pass == 1) {
                if (ds->wall_force[5] > 0 || !R->pushed)
                    break;
                gp_dem3d_set_servo_limit(dem, 5, h_sink);
            }
            for (;;) {
                gp_status st = gp_dem3d_run(dem, CHUNK, R->err);
                if (st)
                    return st;
                gp_dem3d_get_state(dem, ds);
                double sc = ds->stability;
                double fr = log(fmax(sc, STABILITY) / 1.0) / log(STABILITY);
                if (sc0 < 0) sc0 = fmax(sc, 2 * STABILITY);
                pf = fmax(pf, gap_progress(sc0, sc, STABILITY));
                if (report(&R->rc, "relaxation", 0.6 + 0.3 * fmin(1, fmax(0, fr)), pf, ds->steps,
                           1 - vs / (area * gp_dem3d_wall(dem, 5)), sc, 0))
                    return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
                /* (pass 1: and the wall is back on the packing, or as low as it may go) */
                if (sc <= STABILITY
                    && (pass == 0 || ds->wall_force[5] > 0 || gp_dem3d_wall(dem, 5) <= h_sink))
                    break;
                if (ds->steps > R->max_steps) {
                    R->reason = "max_steps";
                    R->outcome = gp_error_set(R->err, GP_ERR_NOT_CONVERGED,
                                              "relaxation: S_c = %.3g after %ld steps (> 1e-4)",
                                              sc, ds->steps);
                    break;
                }
            }
        }
        end_phase(R, 2);
        if (R->outcome == GP_OK && !(ds->wall_force[5] > 0)) {
            /* the wall never touched a grain above b_z: the deposit is denser than the target;
             * or (pass 1) the packing settled further than POROSITY_SLACK */
            R->reason = "target_too_loose";
            R->outcome = gp_error_set(R->err, GP_ERR_INFEASIBLE,
                                      "porosity %g is looser than this sieve holds at friction "
                                      "%g deg: the packing settles below the top wall (%s)", p,
                                      spec->material.friction_deg,
                                      !R->pushed ? "the deposit is denser"
                                                 : "after compaction to the target height");
        }
    }
    R->res->t_relaxation = gp_clock_seconds() - t_phase;
    return GP_OK;
}

/* the sample as the DEM leaves it: its statistics, spheres, box (up to where the wall ended),
 * contacts and porosity; the DEM is released */
static gp_status collect_sample(build_run *R)
{
    gp_specimen3d *res = R->res;
    gp_stats3d *S = &res->stats;
    gp_dem3d *dem = R->dem;
    gp_dem3d_get_state(dem, &R->ds);
    S->stability = R->ds.stability;
    S->steps = R->ds.steps;
    /* stats.dt is the relaxation's step (an export's relaxation runs at it), also where the
     * protocol ended before relaxing */
    if (!R->reached)
        gp_dem3d_set_damping(dem, fmax(R->spec->material.damping, RELAX_DAMPING));
    S->dt = gp_dem3d_dt(dem);
    S->stop_reason = R->reason;
    gp_dem3d_spheres(dem, R->xyzr);
    res->sample_box[2] = gp_dem3d_wall(dem, 5);
    if (!(res->sample_spheres = malloc(4 * R->n * sizeof *res->sample_spheres)))
        return gp_error_set(R->err, GP_ERR_NOMEM, "out of memory");
    memcpy(res->sample_spheres, R->xyzr, 4 * R->n * sizeof *R->xyzr);
    gp_status st = gp_dem3d_contacts(dem, &R->con, &R->ncon, R->err);
    if (st)
        return st;
    gp_dem3d_destroy(dem);
    R->dem = NULL;
    double lo[3] = {0, 0, 0};
    double hi[3] = {res->sample_box[0], res->sample_box[1], res->sample_box[2]};
    double Vb = hi[0] * hi[1] * hi[2];
    S->sample_porosity = 1 - gp_dem3d_solid_volume(R->xyzr, R->n, lo, hi) / Vb;
    return GP_OK;
}

/* ---- phase 2: flip tiling ----
 * When tiled (and the sample is not infeasible): the tiled spheres, the tiled box, the
 * optional DEM relaxation of the tiling, and its porosity; else the sample's porosity. */
static gp_status tile_sample(build_run *R)
{
    const gp_spec3d *spec = R->spec;
    gp_specimen3d *res = R->res;
    gp_stats3d *S = &res->stats;
    for (int a = 0; a < 3; a++)
        res->box[a] = res->sample_box[a];
    R->tile = R->ntile > 1 && (R->outcome == GP_OK || R->outcome == GP_ERR_NOT_CONVERGED);
    R->relaxed = R->tile && spec->tile_relax_steps > 0; /* measured on the DEM's contacts */
    if (!R->tile) {
        S->porosity = S->sample_porosity;
        return GP_OK;
    }
    report(&R->rc, "tiling", 0.9, 0, S->steps, R->p, S->stability, 1);
    gp_status st = gp_flip_tile(R->xyzr, R->n, res->sample_box, spec->tiling,
                                MAX_TILED_SPHERES, R->cancel, &R->tiled, &R->ntiled, R->err);
    /* (the reports between the steps show the phase: a tiling of 10^7 spheres takes
     * seconds, and the first report may have come too soon after the last to be shown) */
    if (!st && report(&R->rc, "tiling", 0.93, TILE_FLIP_PF, S->steps, R->p, S->stability, 0))
        st = gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
    for (int a = 0; a < 3; a++)
        res->box[a] = res->sample_box[a] * spec->tiling[a];
    if (!st && R->relaxed)
        st = relax_tiled(spec, &R->dp, &R->rc, S, R->tiled, R->ntiled, res->box, &R->tcon,
                         &R->ntcon, R->err);
    if (!st)
        st = tiled_porosity(spec->tiling, res->sample_box, res->box, R->tiled, R->n, R->cancel,
                            &S->porosity, R->err);
    return st;
}

/* ---- measures on the final packing ----
 * Without a tiled relaxation the tiled contacts are the sample's, mapped by the flip as they
 * are measured (never all held unless the list is an output). */
static gp_status measure_final(build_run *R)
{
    gp_stats3d *S = &R->res->stats;
    if (report(&R->rc, "tiling", 0.96, R->tile ? TILE_MEASURE_PF : 0, S->steps, R->p,
               S->stability, 0))
        return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
    S->particles = R->tile ? R->ntiled : R->n;
    R->res->count = S->particles;
    return measure(R->spec, R->tile && !R->relaxed, R->relaxed ? R->tcon : R->con,
                   R->relaxed ? R->ntcon : R->ncon, R->n, R->tile ? R->tiled : R->xyzr,
                   S->particles, R->cancel, R->res, R->err);
}

/* ---- the sample and the final packing side by side (gp_transfer.h) ----
 * Only a tiled specimen. The sample: its spheres, box and own contacts. The final packing:
 * its porosity, contacts, fabric and PSD on the whole tiling (the sample's contacts flipped
 * as they are read, or the relaxed tiling's), and its g(r) on a block of at most
 * TRANSFER_BLOCK tiles a side: the g(r) of a tiling costs O(spheres), ~0.5 us a pair (500 or
 * so pairs a sphere within 5 d50), and a tiling may hold millions of spheres; the block's is
 * at most TRANSFER_BLOCK^3 times the sample's, its box at least the sample's, so the same
 * r_max fits in it. The whole tiling's own pass then runs with g(r) to one bin (r_max = dr:
 * a pass over the spheres' neighbour cells, no pair in reach but the overlapping ones), and
 * the block's g(r) takes its place. Every figure is a sum of integers or a pass in the
 * spheres' order: the same bits for any thread count. */

/* the spec's sieve diameters for gp_transfer: all of them, or GP_TRANSFER_MAX_SIEVES evenly
 * chosen rows (the first and last among them) when it has more */
static size_t transfer_sieves(const build_run *R, double *out)
{
    size_t ns = R->spec->nsieve;
    if (ns <= GP_TRANSFER_MAX_SIEVES) {
        memcpy(out, R->sd, ns * sizeof *out);
        return ns;
    }
    for (size_t k = 0; k < GP_TRANSFER_MAX_SIEVES; k++)
        out[k] = R->sd[k * (ns - 1) / (GP_TRANSFER_MAX_SIEVES - 1)];
    return GP_TRANSFER_MAX_SIEVES;
}

/* the bins of g(r) in units of d50: min(TRANSFER_R_MAX, what TRANSFER_R_MAX_BOX of the sample
 * box's shortest side allows) / TRANSFER_DR, as gp_transfer computes its reach */
static double transfer_r_max(const double sb[3], double d50)
{
    double lmin = fmin(sb[0], fmin(sb[1], sb[2]));
    double nb = floor(TRANSFER_R_MAX / TRANSFER_DR + 0.5);
    double fit = floor(TRANSFER_R_MAX_BOX * lmin / (TRANSFER_DR * d50));
    if (fit < nb) nb = fit;
    while (nb > 1 && !(nb * (TRANSFER_DR * d50) <= TRANSFER_R_MAX_BOX * lmin))
        nb--;
    return (nb < 1 ? 1 : nb) * TRANSFER_DR;
}

/* the spheres of tiled (nt) whose centres lie in the block of tiles [o, o + b) of the sample
 * box sb, moved by -o sb (into the block's box); *out malloc'ed, *m of them */
static gp_status transfer_block_spheres(const double *tiled, size_t nt, const double sb[3],
                                        const int o[3], const int b[3], double **out, size_t *m,
                                        gp_error *err)
{
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = o[a] * sb[a];
        hi[a] = (o[a] + b[a]) * sb[a];
    }
    size_t k = 0;
    for (int pass = 0; pass < 2; pass++) {
        k = 0;
        for (size_t i = 0; i < nt; i++) {
            const double *q = tiled + 4 * i;
            if (!(q[0] >= lo[0] && q[0] < hi[0] && q[1] >= lo[1] && q[1] < hi[1] &&
                  q[2] >= lo[2] && q[2] < hi[2]))
                continue;
            if (pass) {
                for (int a = 0; a < 3; a++)
                    (*out)[4 * k + a] = q[a] - lo[a];
                (*out)[4 * k + 3] = q[3];
            }
            k++;
        }
        if (!pass && !(*out = malloc((k ? k : 1) * 4 * sizeof **out)))
            return gp_error_set(err, GP_ERR_NOMEM, "out of memory (%zu spheres)", k);
    }
    *m = k;
    return GP_OK;
}

static gp_status measure_transfer(build_run *R)
{
    gp_specimen3d *res = R->res;
    gp_stats3d *S = &res->stats;
    const gp_spec3d *spec = R->spec;
    if (!R->tile || R->n < 2)
        return GP_OK;
    double t0 = gp_clock_seconds();
    gp_error *err = R->err;
    double sieve[GP_TRANSFER_MAX_SIEVES];
    gp_transfer_params par;
    gp_transfer_params_defaults(&par);
    par.nsieve = transfer_sieves(R, sieve);
    par.sieve = sieve;
    par.dr = TRANSFER_DR;
    par.r_max = TRANSFER_DR;
    par.threads = spec->threads > 0 ? spec->threads : 1;
    par.cancel = R->cancel;
    gp_transfer_side *side = NULL, *blk = NULL;
    double *bx = NULL;
    gp_status st = GP_OK;
    if (!(res->transfer_sample = malloc(sizeof *res->transfer_sample)) ||
        !(res->transfer_final = malloc(sizeof *res->transfer_final)) ||
        !(side = malloc(sizeof *side)) || !(blk = malloc(sizeof *blk))) {
        st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (report(&R->rc, "tiling", 0.97, TILE_TRANSFER_PF, S->steps, R->p, S->stability, 0)) {
        st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        goto done;
    }
    /* the sample: its d50 (a pass with g(r) to one bin), then every figure in units of it */
    gp_transfer_packing ps = {.xyzr = R->xyzr, .n = R->n, .contact_kind = GP_TRANSFER_CONTACTS_GIVEN,
                              .contacts = R->con, .ncontacts = R->ncon};
    memcpy(ps.box, res->sample_box, sizeof ps.box);
    if ((st = gp_transfer_measure(&ps, &par, side, err)))
        goto done;
    par.unit = side->d50;
    par.r_max = transfer_r_max(res->sample_box, side->d50);
    if ((st = gp_transfer_measure(&ps, &par, res->transfer_sample, err)))
        goto done;
    if (report(&R->rc, "tiling", 0.98, TILE_TRANSFER_PF + 0.1, S->steps, R->p, S->stability, 0)) {
        st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        goto done;
    }
    /* the final packing, whole */
    gp_transfer_packing pf = {.xyzr = R->tiled, .n = R->ntiled,
                              .contact_kind = R->relaxed ? GP_TRANSFER_CONTACTS_GIVEN
                                                         : GP_TRANSFER_CONTACTS_FLIPPED,
                              .contacts = R->relaxed ? R->tcon : R->con,
                              .ncontacts = R->relaxed ? R->ntcon : R->ncon};
    memcpy(pf.box, res->box, sizeof pf.box);
    memcpy(pf.tiles, spec->tiling, sizeof pf.tiles);
    int whole = 1;
    for (int a = 0; a < 3; a++) {
        int b = spec->tiling[a] < TRANSFER_BLOCK ? spec->tiling[a] : TRANSFER_BLOCK;
        res->transfer_block[a] = b;
        res->transfer_block_origin[a] = (spec->tiling[a] - b) / 2;
        whole &= b == spec->tiling[a];
    }
    double r_max = par.r_max;
    if (!whole)
        par.r_max = TRANSFER_DR;
    if ((st = gp_transfer_measure(&pf, &par, res->transfer_final, err)))
        goto done;
    res->transfer_block_spheres = R->ntiled;
    if (!whole) {
        /* g(r) of the block: its spheres, no contacts, no sieve (only its g(r) is kept) */
        if (report(&R->rc, "tiling", 0.99, TILE_TRANSFER_PF + 0.15, S->steps, R->p,
                   S->stability, 0)) {
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
            goto done;
        }
        size_t m = 0;
        if ((st = transfer_block_spheres(R->tiled, R->ntiled, res->sample_box,
                                         res->transfer_block_origin, res->transfer_block, &bx,
                                         &m, err)))
            goto done;
        gp_transfer_packing pb = {.xyzr = bx, .n = m, .contact_kind = GP_TRANSFER_CONTACTS_GIVEN};
        for (int a = 0; a < 3; a++)
            pb.box[a] = res->transfer_block[a] * res->sample_box[a];
        par.r_max = r_max;
        par.sieve = NULL;
        par.nsieve = 0;
        if ((st = gp_transfer_measure(&pb, &par, blk, err)))
            goto done;
        gp_transfer_side *f = res->transfer_final;
        f->unit = blk->unit;
        f->dr = blk->dr;
        f->r_max = blk->r_max;
        f->nbins = blk->nbins;
        memcpy(f->g, blk->g, sizeof f->g);
        memcpy(f->g_err, blk->g_err, sizeof f->g_err);
        memcpy(f->neighbours, blk->neighbours, sizeof f->neighbours);
        memcpy(f->pairs, blk->pairs, sizeof f->pairs);
        memcpy(f->g_mirror, blk->g_mirror, sizeof f->g_mirror);
        res->transfer_block_spheres = m;
    }
    st = gp_transfer_compare(res->transfer_sample, res->transfer_final, &res->transfer_diff, err);
done:
    free(side);
    free(blk);
    free(bx);
    if (st) {
        free(res->transfer_sample);
        free(res->transfer_final);
        res->transfer_sample = res->transfer_final = NULL;
    }
    res->t_transfer = gp_clock_seconds() - t0;
    return st;
}

/* the final spheres move to the result (GP_OUT3_SPHERES) */
static void hand_out_spheres(build_run *R)
{
    if (!(R->spec->outputs & GP_OUT3_SPHERES))
        return;
    if (R->tile) {
        R->res->spheres = R->tiled;
        R->tiled = NULL;
    } else {
        R->res->spheres = R->xyzr;
        R->xyzr = NULL;
    }
}

gp_status gp_specimen3d_build(const gp_spec3d *spec, gp_progress_fn progress, void *user,
                              const volatile int *cancel, gp_specimen3d **out, gp_error *err)
{
    double t0 = gp_clock_seconds();
    *out = NULL;
    if (!spec)
        return gp_error_set(err, GP_ERR_INVALID, "spec is NULL");
    build_run R;
    memset(&R, 0, sizeof R);
    R.spec = spec;
    R.cancel = cancel;
    R.rc = (progress_ctx){progress, user, cancel, 0};
    R.err = err;
    R.outcome = GP_OK;
    R.reason = "stable";
    gp_status st = read_spec(&R);
    if (!st) st = draw_sample(&R);
    if (!st) st = place_sample(&R);
    if (!st) st = start_dem(&R);
    if (!st) st = deposit(&R);
    if (!st) st = compact(&R);
    if (!st) st = relax(&R);
    if (!st) st = collect_sample(&R);
    double t_phase = gp_clock_seconds(); /* t_tiling: the tiling and the measures */
    if (!st) st = tile_sample(&R);
    if (!st) st = measure_final(&R);
    double t_measured = gp_clock_seconds();
    if (!st) st = measure_transfer(&R);
    gp_specimen3d *res = R.res;
    if (st) {
        gp_specimen3d_destroy(res);
        build_run_release(&R);
        return st;
    }
    res->t_tiling = t_measured - t_phase;
    hand_out_spheres(&R);
    report(&R.rc, "tiling", 1.0, 1.0, res->stats.steps, res->stats.porosity, res->stats.stability,
           1);
    build_run_release(&R);
    res->t_total = gp_clock_seconds() - t0;
    *out = res;
    return R.outcome;
}
