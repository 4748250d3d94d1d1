/* gp_transfer.c -- see gp_transfer.h. */
#include "gp_transfer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_flip.h"
#include "gp_grid.h"
#include "gp_team.h"
#include "gp_progress.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

__extension__ typedef unsigned __int128 u128;

#define PAIR_SCALE 0x1p56   /* a pair weight V / gamma <= 64 as a multiple of 2^-56 (< 2^62) */
#define VOLUME_SCALE 0x1p62 /* a grain's d^3 / d_max^3 <= 1 as a multiple of 2^-62 */
#define R_MAX_BOX 0.75      /* r_max <= this x the box's shortest side: V / gamma <= 64 */
#define STENCIL 3           /* g(r) cells at least r_max / STENCIL wide */
#define D50_BINS 4096       /* bins of one pass of the d50 search */
#define CHUNK 4096          /* contacts per chunk */

void gp_transfer_params_defaults(gp_transfer_params *p)
{
    memset(p, 0, sizeof *p);
    p->r_max = 5;
    p->dr = 0.05;
    p->threads = 1;
}

/* ---- validation ---- */

static gp_status validate(const gp_transfer_packing *P, const gp_transfer_params *par,
                          size_t *ntile, gp_error *err)
{
    if (!P || !par)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: packing and params are required");
    if (P->n < 2 || !P->xyzr)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: n must be >= 2 (got %zu)", P->n);
    for (int a = 0; a < 3; a++)
        if (!(P->box[a] > 0) || !isfinite(P->box[a]))
            return gp_error_set(err, GP_ERR_INVALID, "transfer: box[%d] must be > 0", a);
    for (size_t i = 0; i < P->n; i++) {
        const double *s = P->xyzr + 4 * i;
        if (!isfinite(s[0]) || !isfinite(s[1]) || !isfinite(s[2]) || !isfinite(s[3]) || s[3] < 0)
            return gp_error_set(err, GP_ERR_INVALID,
                                "transfer: sphere %zu must be finite with r >= 0", i);
    }
    size_t t = 1;
    int untiled = P->tiles[0] == 0 && P->tiles[1] == 0 && P->tiles[2] == 0;
    for (int a = 0; a < 3 && !untiled; a++) {
        if (P->tiles[a] < 1 || P->tiles[a] > 4096)
            return gp_error_set(err, GP_ERR_INVALID,
                                "transfer: tiles[%d] = %d must be in [1, 4096]", a, P->tiles[a]);
        t *= (size_t)P->tiles[a];
    }
    if (P->n % t)
        return gp_error_set(err, GP_ERR_INVALID,
                            "transfer: n = %zu is not a multiple of the %zu tiles", P->n, t);
    *ntile = t;
    size_t n0 = P->n / t, nc = P->ncontacts;
    switch (P->contact_kind) {
    case GP_TRANSFER_CONTACTS_FLIPPED:
        if (t == 1 && untiled)
            return gp_error_set(err, GP_ERR_INVALID, "transfer: flipped contacts need tiles");
        /* fall through */
    case GP_TRANSFER_CONTACTS_GIVEN: {
        size_t m = P->contact_kind == GP_TRANSFER_CONTACTS_FLIPPED ? n0 : P->n;
        if (nc && !P->contacts)
            return gp_error_set(err, GP_ERR_INVALID, "transfer: %zu contacts but no array", nc);
        for (size_t k = 0; k < nc; k++) {
            const gp_contact3d *c = P->contacts + k;
            if (c->i >= m || c->j < -6 || (c->j >= 0 && (size_t)c->j >= m))
                return gp_error_set(err, GP_ERR_INVALID,
                                    "transfer: contact %zu (%zu, %ld) out of the %zu spheres", k,
                                    c->i, c->j, m);
        }
        break;
    }
    case GP_TRANSFER_CONTACTS_GEOMETRIC:
        break;
    default:
        return gp_error_set(err, GP_ERR_INVALID, "transfer: unknown contact_kind %d",
                            (int)P->contact_kind);
    }
    if (par->nsieve > GP_TRANSFER_MAX_SIEVES)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: at most %d sieves (got %zu)",
                            GP_TRANSFER_MAX_SIEVES, par->nsieve);
    if (par->nsieve && !par->sieve)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: %zu sieves but no array", par->nsieve);
    for (size_t k = 0; k < par->nsieve; k++)
        if (!(par->sieve[k] > 0) || !isfinite(par->sieve[k]) ||
            (k > 0 && !(par->sieve[k] > par->sieve[k - 1])))
            return gp_error_set(err, GP_ERR_INVALID,
                                "transfer: sieve[%zu] must be > 0 and above the one before", k);
    if (!(par->unit >= 0) || !isfinite(par->unit))
        return gp_error_set(err, GP_ERR_INVALID, "transfer: unit must be >= 0 (0: d50)");
    if (!(par->r_max > 0) || !isfinite(par->r_max) || !(par->dr > 0) || !isfinite(par->dr))
        return gp_error_set(err, GP_ERR_INVALID, "transfer: r_max and dr must be > 0");
    double nb = ceil(par->r_max / par->dr - 1e-9);
    if (nb > GP_TRANSFER_MAX_BINS)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: r_max / dr = %.0f bins (at most %d)",
                            nb, GP_TRANSFER_MAX_BINS);
    if (par->threads < 0 || par->threads > 256)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: threads must be in [0, 256]");
    return GP_OK;
}

/* ---- porosity ---- */

static double porosity(const gp_transfer_packing *P, size_t ntile)
{
    const double *b = P->box;
    if (ntile == 1) {
        const double lo[3] = {0, 0, 0};
        return 1 - gp_dem3d_solid_volume(P->xyzr, P->n, lo, b) / (b[0] * b[1] * b[2]);
    }
    /* each copy clipped to its own tile, summed tile by tile (as gp_specimen3d does) */
    size_t nx = (size_t)P->tiles[0], ny = (size_t)P->tiles[1], n0 = P->n / ntile;
    double sb[3] = {b[0] / P->tiles[0], b[1] / P->tiles[1], b[2] / P->tiles[2]};
    double solid = 0;
    for (size_t t = 0; t < ntile; t++) {
        size_t kx = t % nx, ky = (t / nx) % ny, kz = t / (nx * ny);
        double tlo[3] = {kx * sb[0], ky * sb[1], kz * sb[2]};
        double thi[3] = {tlo[0] + sb[0], tlo[1] + sb[1], tlo[2] + sb[2]};
        solid += gp_dem3d_solid_volume(P->xyzr + 4 * t * n0, n0, tlo, thi);
    }
    return 1 - solid / (b[0] * b[1] * b[2]);
}

/* ---- PSD and d50 ---- */

/* a grain's weight d^3 / d_max^3 as an integer multiple of 2^-62 */
static uint64_t grain_weight(double d, double dmax)
{
    if (!(dmax > 0))
        return 0;
    double f = d / dmax;
    return (uint64_t)(f * f * f * VOLUME_SCALE + 0.5);
}

/* the smallest diameter D with 2 weight(d <= D) >= total: passes of D50_BINS bins over
 * [lo, hi], each keeping the bin where the cumulative weight reaches half, until the bin
 * holds one value */
static gp_status d50_by_weight(const double *xyzr, size_t n, double dmin, double dmax,
                               u128 total, double *d50, gp_error *err)
{
    if (total == 0) {
        *d50 = dmax;
        return GP_OK;
    }
    u128 *w = malloc(D50_BINS * sizeof *w);
    double *bmin = malloc(D50_BINS * sizeof *bmin), *bmax = malloc(D50_BINS * sizeof *bmax);
    if (!w || !bmin || !bmax) {
        free(w); free(bmin); free(bmax);
        return gp_error_set(err, GP_ERR_NOMEM, "transfer: out of memory");
    }
    double lo = dmin, hi = dmax;
    u128 below = 0; /* weight of the grains below lo */
    while (lo < hi) {
        memset(w, 0, D50_BINS * sizeof *w);
        for (size_t b = 0; b < D50_BINS; b++) {
            bmin[b] = INFINITY;
            bmax[b] = -INFINITY;
        }
        double span = hi - lo;
        for (size_t i = 0; i < n; i++) {
            double d = 2 * xyzr[4 * i + 3];
            if (d < lo || d > hi)
                continue;
            size_t b = gp_grid_cell((d - lo) / span * D50_BINS, D50_BINS);
            w[b] += grain_weight(d, dmax);
            if (d < bmin[b]) bmin[b] = d;
            if (d > bmax[b]) bmax[b] = d;
        }
        u128 cum = below;
        size_t b = 0;
        while (b < D50_BINS - 1 && 2 * (cum + w[b]) < total)
            cum += w[b++];
        /* the first bin that reaches half holds weight, so values; its range is narrower than
         * [lo, hi] (lo and hi fall in bins 0 and D50_BINS - 1) */
        below = cum;
        lo = bmin[b];
        hi = bmax[b];
    }
    free(w); free(bmin); free(bmax);
    *d50 = lo;
    return GP_OK;
}

static gp_status psd(const gp_transfer_packing *P, const gp_transfer_params *par,
                     gp_transfer_side *S, gp_error *err)
{
    size_t n = P->n, ns = par->nsieve;
    double dmin = INFINITY, dmax = 0;
    for (size_t i = 0; i < n; i++) {
        double d = 2 * P->xyzr[4 * i + 3];
        if (d < dmin) dmin = d;
        if (d > dmax) dmax = d;
    }
    /* per sieve bin b (the grains that pass sieves b .. ns - 1): count and weight */
    size_t cnt[GP_TRANSFER_MAX_SIEVES + 1] = {0};
    u128 wt[GP_TRANSFER_MAX_SIEVES + 1];
    memset(wt, 0, sizeof wt);
    u128 total = 0;
    for (size_t i = 0; i < n; i++) {
        double d = 2 * P->xyzr[4 * i + 3];
        size_t lo = 0, hi = ns; /* the first sieve with d < sieve */
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (d < par->sieve[mid]) hi = mid;
            else lo = mid + 1;
        }
        uint64_t q = grain_weight(d, dmax);
        cnt[lo]++;
        wt[lo] += q;
        total += q;
    }
    S->nsieve = ns;
    size_t c = 0;
    u128 v = 0;
    for (size_t k = 0; k < ns; k++) {
        c += cnt[k];
        v += wt[k];
        S->sieve[k] = par->sieve[k];
        S->psd_number[k] = 100.0 * (double)c / (double)n;
        S->psd_weight[k] = total ? 100.0 * (double)v / (double)total : 0;
    }
    S->d_min = dmin;
    S->d_max = dmax;
    return d50_by_weight(P->xyzr, n, dmin, dmax, total, &S->d50, err);
}

/* ---- contacts: counts and fabric, over chunks in order ---- */

typedef struct contact_acc {
    size_t pairs, walls;
    gp_dem3d_fabric_acc fabric;
    const volatile int *cancel;
} contact_acc;

static gp_status contact_visit(void *user, const gp_contact3d *c, size_t k, gp_error *err)
{
    contact_acc *m = user;
    if (gp_progress_cancelled(m->cancel))
        return gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
    for (size_t q = 0; q < k; q++) {
        if (c[q].j >= 0) m->pairs++;
        else m->walls++;
    }
    gp_dem3d_fabric_acc_add(&m->fabric, c, k);
    return GP_OK;
}

/* the overlapping pairs in (i, j) order, then each sphere's wall crossings (walls 0..5 =
 * x-, x+, y-, y+, z-, z+; the normal points to the wall), as gp_dem3d_contacts lists them */
static gp_status geometric_contacts(const gp_transfer_packing *P, contact_acc *m,
                                    gp_contact3d *buf, gp_error *err)
{
    size_t *pr = NULL, np = 0, k = 0;
    const double *s = P->xyzr;
    gp_status st = gp_dem3d_find_pairs(s, P->n, 0, &pr, &np, err);
    for (size_t q = 0; !st && q < np; q++) {
        size_t i = pr[2 * q], j = pr[2 * q + 1];
        const double *a = s + 4 * i, *b = s + 4 * j;
        double h[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double d = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        gp_contact3d *c = buf + k++;
        memset(c, 0, sizeof *c);
        c->i = i;
        c->j = (long)j;
        for (int e = 0; e < 3; e++)
            c->normal[e] = d > 0 ? h[e] / d : 0;
        c->overlap = a[3] + b[3] - d;
        if (k == CHUNK) {
            st = contact_visit(m, buf, k, err);
            k = 0;
        }
    }
    free(pr);
    for (size_t i = 0; !st && i < P->n; i++) {
        const double *a = s + 4 * i;
        for (int w = 0; w < 6 && !st; w++) {
            int ax = w / 2;
            double dist = w % 2 ? P->box[ax] - a[ax] : a[ax];
            if (!(dist < a[3]))
                continue;
            gp_contact3d *c = buf + k++;
            memset(c, 0, sizeof *c);
            c->i = i;
            c->j = -1 - w;
            c->normal[ax] = w % 2 ? 1 : -1;
            c->overlap = a[3] - dist;
            if (k == CHUNK) {
                st = contact_visit(m, buf, k, err);
                k = 0;
            }
        }
    }
    if (!st && k)
        st = contact_visit(m, buf, k, err);
    return st;
}

static gp_status contacts(const gp_transfer_packing *P, const gp_transfer_params *par,
                          size_t ntile, gp_transfer_side *S, gp_error *err)
{
    contact_acc m;
    memset(&m, 0, sizeof m);
    gp_dem3d_fabric_acc_init(&m.fabric);
    m.cancel = par->cancel;
    gp_status st = GP_OK;
    if (P->contact_kind == GP_TRANSFER_CONTACTS_GIVEN) {
        for (size_t k = 0; k < P->ncontacts && !st; k += CHUNK)
            st = contact_visit(&m, P->contacts + k,
                               P->ncontacts - k < CHUNK ? P->ncontacts - k : CHUNK, err);
    } else {
        gp_contact3d *buf = malloc(CHUNK * sizeof *buf);
        if (!buf)
            return gp_error_set(err, GP_ERR_NOMEM, "transfer: out of memory");
        if (P->contact_kind == GP_TRANSFER_CONTACTS_FLIPPED)
            st = gp_flip_contacts_each(P->contacts, P->ncontacts, P->n / ntile, P->tiles,
                                       par->cancel, buf, CHUNK, contact_visit, &m, err);
        else
            st = geometric_contacts(P, &m, buf, err);
        free(buf);
    }
    if (st)
        return st;
    double n = (double)P->n;
    S->contacts = m.pairs;
    S->wall_contacts = m.walls;
    S->coordination = (2.0 * (double)m.pairs + (double)m.walls) / n;
    S->coordination_spheres = 2.0 * (double)m.pairs / n;
    gp_dem3d_fabric_acc_finish(&m.fabric, S->fabric);
    return GP_OK;
}

/* ---- g(r) ----
 * One grid over the box grown by r_max on every side holds the spheres (real) and, apart,
 * their mirror images across the walls within r_max (ghosts: per axis x, and -x or 2 L - x
 * when that wall is nearer than r_max; every combination but x, y, z itself). Real pairs are
 * met once each through a forward half-stencil and feed both g (translation weight) and
 * g_mirror (2: either sphere is a reference); a real sphere meets the ghosts through the full
 * stencil, for g_mirror only (1: the real one is the reference). */

typedef struct rdf_run {
    const double *pos;    /* real centres sorted by cell, x y z */
    const size_t *start;  /* cell c holds pos[3 start[c] .. 3 start[c + 1]) */
    const double *gpos;   /* ghosts, likewise */
    const size_t *gstart;
    size_t g[3];
    double lo[3], w[3];   /* the grid's origin and cell widths */
    int (*stencil)[3];    /* the full stencil: offsets whose cells come closer than reach; the
                             first nhalf of them are the forward half (the own cell apart) */
    size_t nst, nhalf;
    double L[3], V, reach, reach2, inv_dr;
    size_t nbins;
    size_t nrows;         /* rows of cells along x: g[1] g[2] */
    size_t next;          /* atomic: the next row to take */
    int stop;             /* atomic: cancelled */
    const volatile int *cancel;
    u128 *wsum;           /* per thread, nbins each */
    uint64_t *cnt, *mcnt;
} rdf_run;

/* bin of a separation (nbins: none) */
static inline size_t rdf_bin(const rdf_run *R, double dx, double dy, double dz)
{
    double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 >= R->reach2)
        return R->nbins;
    size_t k = (size_t)(sqrt(d2) * R->inv_dr);
    return k < R->nbins ? k : R->nbins;
}

static inline void rdf_pair(const rdf_run *R, const double *a, const double *b, u128 *ws,
                            uint64_t *cnt, uint64_t *mcnt)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
    size_t k = rdf_bin(R, dx, dy, dz);
    if (k == R->nbins)
        return;
    /* the translation weight V / gamma(h): symmetric in a and b, so the sums do not depend on
     * which of the two is the reference */
    double gam = (R->L[0] - fabs(dx)) * (R->L[1] - fabs(dy)) * (R->L[2] - fabs(dz));
    ws[k] += (uint64_t)(R->V / gam * PAIR_SCALE + 0.5);
    cnt[k]++;
    mcnt[k] += 2;
}

static void rdf_row(const rdf_run *R, size_t row, u128 *ws, uint64_t *cnt, uint64_t *mcnt)
{
    const size_t *g = R->g;
    size_t y = row % g[1], z = row / g[1];
    for (size_t x = 0; x < g[0]; x++) {
        size_t c = (z * g[1] + y) * g[0] + x;
        const double *A = R->pos + 3 * R->start[c];
        size_t na = R->start[c + 1] - R->start[c];
        if (!na)
            continue;
        for (size_t i = 0; i < na; i++)
            for (size_t j = i + 1; j < na; j++)
                rdf_pair(R, A + 3 * i, A + 3 * j, ws, cnt, mcnt);
        /* does the cell come within reach of a wall (so of a ghost)? */
        size_t cc[3] = {x, y, z};
        int near = 0;
        for (int a = 0; a < 3; a++) {
            double clo = R->lo[a] + (double)cc[a] * R->w[a], chi = clo + R->w[a];
            near |= clo < R->reach || chi > R->L[a] - R->reach;
        }
        for (size_t s = 0; s < (near ? R->nst : R->nhalf); s++) {
            long nx = (long)x + R->stencil[s][0], ny = (long)y + R->stencil[s][1],
                 nz = (long)z + R->stencil[s][2];
            if (nx < 0 || ny < 0 || nz < 0 || nx >= (long)g[0] || ny >= (long)g[1] ||
                nz >= (long)g[2])
                continue;
            size_t cb = ((size_t)nz * g[1] + (size_t)ny) * g[0] + (size_t)nx;
            if (s < R->nhalf) {
                const double *B = R->pos + 3 * R->start[cb];
                size_t nb = R->start[cb + 1] - R->start[cb];
                for (size_t i = 0; i < na; i++)
                    for (size_t j = 0; j < nb; j++)
                        rdf_pair(R, A + 3 * i, B + 3 * j, ws, cnt, mcnt);
            }
            const double *G = R->gpos + 3 * R->gstart[cb];
            size_t ng = R->gstart[cb + 1] - R->gstart[cb];
            for (size_t i = 0; i < na; i++)
                for (size_t j = 0; j < ng; j++) {
                    const double *a = A + 3 * i, *b = G + 3 * j;
                    size_t k = rdf_bin(R, b[0] - a[0], b[1] - a[1], b[2] - a[2]);
                    if (k < R->nbins)
                        mcnt[k]++;
                }
        }
    }
}

/* gp_team_fn: rows taken one at a time; the sums are integers, so which thread takes which
 * row changes nothing */
static void rdf_work(void *ctx, int tid)
{
    rdf_run *R = ctx;
    u128 *ws = R->wsum + (size_t)tid * R->nbins;
    uint64_t *cnt = R->cnt + (size_t)tid * R->nbins, *mcnt = R->mcnt + (size_t)tid * R->nbins;
    for (;;) {
        if (gp_progress_cancelled(R->cancel)) {
            __atomic_store_n(&R->stop, 1, __ATOMIC_RELAXED);
            return;
        }
        size_t row = __atomic_fetch_add(&R->next, 1, __ATOMIC_RELAXED);
        if (row >= R->nrows)
            return;
        rdf_row(R, row, ws, cnt, mcnt);
    }
}

/* the images of sphere p across the walls within reach (up to 26: a sphere may be within
 * reach of both walls of an axis; the sphere itself not) */
static size_t ghosts_of(const double *p, const double L[3], double reach, double (*out)[3])
{
    double im[3][3];
    size_t ni[3];
    for (int a = 0; a < 3; a++) {
        ni[a] = 0;
        im[a][ni[a]++] = p[a];
        if (p[a] < reach) im[a][ni[a]++] = -p[a];
        if (L[a] - p[a] < reach) im[a][ni[a]++] = 2 * L[a] - p[a];
    }
    size_t m = 0;
    for (size_t k = 0; k < ni[2]; k++)
        for (size_t j = 0; j < ni[1]; j++)
            for (size_t i = 0; i < ni[0]; i++) {
                if (i == 0 && j == 0 && k == 0)
                    continue;
                out[m][0] = im[0][i];
                out[m][1] = im[1][j];
                out[m][2] = im[2][k];
                m++;
            }
    return m;
}

/* counting sort of m points (from pts, stride 4 or 3) into the grid: start[nc + 1], pos[3 m] */
static void sort_into_cells(const rdf_run *R, const double *inv, size_t nc, size_t *start,
                            size_t *cell, const double *pts, size_t stride, size_t m, double *pos)
{
    for (size_t i = 0; i < m; i++) {
        size_t c[3];
        for (int a = 0; a < 3; a++)
            c[a] = gp_grid_cell((pts[stride * i + a] - R->lo[a]) * inv[a], R->g[a]);
        cell[i] = (c[2] * R->g[1] + c[1]) * R->g[0] + c[0];
        start[cell[i] + 1]++;
    }
    for (size_t c = 0; c < nc; c++)
        start[c + 1] += start[c];
    for (size_t i = 0; i < m; i++) {
        size_t k = start[cell[i]]++;
        memcpy(pos + 3 * k, pts + stride * i, 3 * sizeof *pos);
    }
    for (size_t c = nc; c > 0; c--) /* back to the first index of each cell */
        start[c] = start[c - 1];
    start[0] = 0;
}

static gp_status rdf(const gp_transfer_packing *P, const gp_transfer_params *par,
                     gp_transfer_side *S, gp_error *err)
{
    size_t n = P->n;
    double unit = par->unit > 0 ? par->unit : S->d50;
    if (!(unit > 0))
        return gp_error_set(err, GP_ERR_INVALID,
                            "transfer: unit is 0 and the spheres have no size: give params.unit");
    size_t nbins = (size_t)ceil(par->r_max / par->dr - 1e-9);
    if (nbins < 1) nbins = 1;
    double dra = par->dr * unit, reach = (double)nbins * dra;
    double Lmin = fmin(P->box[0], fmin(P->box[1], P->box[2]));
    if (!(reach <= R_MAX_BOX * Lmin))
        return gp_error_set(err, GP_ERR_INVALID,
                            "transfer: r_max = %g m is more than 3/4 of the box's shortest side "
                            "(%g m)", reach, Lmin);
    S->unit = unit;
    S->dr = par->dr;
    S->nbins = nbins;
    S->r_max = (double)nbins * par->dr;

    rdf_run R;
    memset(&R, 0, sizeof R);
    R.nbins = nbins;
    R.inv_dr = 1.0 / dra;
    R.reach = reach * (1 + 1e-12);
    R.reach2 = R.reach * R.reach;
    for (int a = 0; a < 3; a++)
        R.L[a] = P->box[a];
    R.V = P->box[0] * P->box[1] * P->box[2];
    R.cancel = par->cancel;

    size_t ng = 0;
    double gh[26][3];
    for (size_t i = 0; i < n; i++)
        ng += ghosts_of(P->xyzr + 4 * i, R.L, R.reach, gh);
    /* cells at least reach / STENCIL wide over the box grown by reach */
    double lo[3], hi[3], inv[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = R.lo[a] = -R.reach;
        hi[a] = R.L[a] + R.reach;
    }
    size_t nc = gp_grid_size(lo, hi, R.reach * (1 + 1e-9) / STENCIL, 1024, 2 * (n + ng) + 64,
                             R.g, inv);
    for (int a = 0; a < 3; a++)
        R.w[a] = (hi[a] - lo[a]) / (double)R.g[a];
    size_t *start = calloc(nc + 1, sizeof *start), *gstart = calloc(nc + 1, sizeof *gstart);
    size_t *cell = malloc((n > ng ? n : ng) * sizeof *cell + 1);
    double *pos = malloc(3 * n * sizeof *pos), *gpos = malloc(3 * ng * sizeof *gpos + 1);
    double *graw = malloc(3 * ng * sizeof *graw + 1);
    int (*stencil)[3] = malloc((2 * STENCIL + 1) * (2 * STENCIL + 1) * (2 * STENCIL + 1) *
                               sizeof *stencil);
    gp_team *team = NULL;
    gp_status st = GP_OK;
    if (!start || !gstart || !cell || !pos || !gpos || !graw || !stencil) {
        st = gp_error_set(err, GP_ERR_NOMEM, "transfer: out of memory");
        goto done;
    }
    sort_into_cells(&R, inv, nc, start, cell, P->xyzr, 4, n, pos);
    for (size_t i = 0, m = 0; i < n; i++) {
        size_t k = ghosts_of(P->xyzr + 4 * i, R.L, R.reach, gh);
        memcpy(graw + 3 * m, gh, 3 * k * sizeof *graw);
        m += k;
    }
    sort_into_cells(&R, inv, nc, gstart, cell, graw, 3, ng, gpos);
    free(graw);
    graw = NULL;
    free(cell);
    cell = NULL;
    /* the stencil: forward half first, then the own cell and the backward half; offsets whose
     * cells come no closer than reach are left out */
    for (int half = 1; half >= 0; half--)
        for (int oz = -STENCIL; oz <= STENCIL; oz++)
            for (int oy = -STENCIL; oy <= STENCIL; oy++)
                for (int ox = -STENCIL; ox <= STENCIL; ox++) {
                    int fwd = oz > 0 || (oz == 0 && (oy > 0 || (oy == 0 && ox > 0)));
                    if (fwd != half)
                        continue;
                    int o[3] = {ox, oy, oz};
                    double gap2 = 0;
                    for (int a = 0; a < 3; a++) {
                        double gap = (abs(o[a]) > 1 ? abs(o[a]) - 1 : 0) * R.w[a];
                        gap2 += gap * gap;
                    }
                    if (gap2 >= R.reach2)
                        continue;
                    memcpy(stencil[R.nst++], o, sizeof o);
                    if (half)
                        R.nhalf = R.nst;
                }
    R.pos = pos;
    R.start = start;
    R.gpos = gpos;
    R.gstart = gstart;
    R.stencil = stencil;
    R.nrows = R.g[1] * R.g[2];

    int nt = par->threads > 1 ? par->threads : 1;
    if (nt > 1) {
        team = gp_team_create(nt, err);
        if (!team) {
            st = err ? err->code : GP_ERR_NOMEM;
            goto done;
        }
        nt = gp_team_size(team);
    }
    R.wsum = calloc((size_t)nt * nbins, sizeof *R.wsum);
    R.cnt = calloc((size_t)nt * nbins, sizeof *R.cnt);
    R.mcnt = calloc((size_t)nt * nbins, sizeof *R.mcnt);
    if (!R.wsum || !R.cnt || !R.mcnt) {
        st = gp_error_set(err, GP_ERR_NOMEM, "transfer: out of memory");
        goto done;
    }
    if (team)
        gp_team_run(team, rdf_work, &R);
    else
        rdf_work(&R, 0);
    if (R.stop) {
        st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        goto done;
    }
    /* integer sums: any order gives the same totals */
    for (int t = 1; t < nt; t++)
        for (size_t k = 0; k < nbins; k++) {
            R.wsum[k] += R.wsum[(size_t)t * nbins + k];
            R.cnt[k] += R.cnt[(size_t)t * nbins + k];
            R.mcnt[k] += R.mcnt[(size_t)t * nbins + k];
        }
    double rho = (double)(n - 1) / R.V, rho_m = (double)n / R.V, dr3 = dra * dra * dra;
    for (size_t k = 0; k < nbins; k++) {
        double kk = (double)k;
        double shell = 4.0 / 3.0 * M_PI * dr3 * (3 * kk * kk + 3 * kk + 1);
        double N = 2.0 * ((double)R.wsum[k] / PAIR_SCALE) / (double)n;
        S->neighbours[k] = N;
        S->pairs[k] = R.cnt[k];
        S->g[k] = N / (rho * shell);
        S->g_err[k] = R.cnt[k] ? S->g[k] / sqrt((double)R.cnt[k]) : 0;
        S->g_mirror[k] = (double)R.mcnt[k] / (double)n / (rho_m * shell);
    }
done:
    gp_team_destroy(team);
    free(R.wsum);
    free(R.cnt);
    free(R.mcnt);
    free(start);
    free(gstart);
    free(cell);
    free(pos);
    free(gpos);
    free(graw);
    free(stencil);
    return st;
}

/* ---- the two calls ---- */

gp_status gp_transfer_measure(const gp_transfer_packing *P, const gp_transfer_params *par,
                              gp_transfer_side *out, gp_error *err)
{
    size_t ntile = 1;
    gp_status st = validate(P, par, &ntile, err);
    if (st)
        return st;
    gp_transfer_side *S = malloc(sizeof *S);
    if (!S)
        return gp_error_set(err, GP_ERR_NOMEM, "transfer: out of memory");
    memset(S, 0, sizeof *S);
    S->n = P->n;
    memcpy(S->box, P->box, sizeof S->box);
    S->porosity = porosity(P, ntile);
    st = psd(P, par, S, err);
    if (!st && gp_progress_cancelled(par->cancel))
        st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
    if (!st)
        st = contacts(P, par, ntile, S, err);
    if (!st)
        st = rdf(P, par, S, err);
    if (!st)
        *out = *S;
    free(S);
    return st;
}

gp_status gp_transfer_compare(const gp_transfer_side *a, const gp_transfer_side *b,
                              gp_transfer_diff *d, gp_error *err)
{
    if (!a || !b || !d)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: compare needs two sides and a diff");
    if (a->nsieve != b->nsieve)
        return gp_error_set(err, GP_ERR_INVALID, "transfer: %zu sieves against %zu", a->nsieve,
                            b->nsieve);
    for (size_t k = 0; k < a->nsieve; k++)
        if (a->sieve[k] != b->sieve[k])
            return gp_error_set(err, GP_ERR_INVALID, "transfer: sieve[%zu] differs", k);
    if (a->nbins != b->nbins || a->dr != b->dr)
        return gp_error_set(err, GP_ERR_INVALID,
                            "transfer: bins differ (%zu of %g against %zu of %g)", a->nbins,
                            a->dr, b->nbins, b->dr);
    memset(d, 0, sizeof *d);
    d->porosity = fabs(b->porosity - a->porosity);
    d->coordination = fabs(b->coordination - a->coordination);
    d->coordination_spheres = fabs(b->coordination_spheres - a->coordination_spheres);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double e = fabs(b->fabric[i][j] - a->fabric[i][j]);
            d->fabric = fmax(d->fabric, e);
            if (i == j)
                d->fabric_diagonal = fmax(d->fabric_diagonal, e);
        }
    d->d50 = fabs(b->d50 - a->d50);
    for (size_t k = 0; k < a->nsieve; k++) {
        d->psd_number = fmax(d->psd_number, fabs(b->psd_number[k] - a->psd_number[k]));
        d->psd_weight = fmax(d->psd_weight, fabs(b->psd_weight[k] - a->psd_weight[k]));
    }
    double ss = 0;
    for (size_t k = 0; k < a->nbins; k++) {
        double e = b->g[k] - a->g[k];
        ss += e * e;
        if (fabs(e) > d->rdf) {
            d->rdf = fabs(e);
            d->rdf_r = ((double)k + 0.5) * a->dr;
        }
        double s2 = a->g_err[k] * a->g_err[k] + b->g_err[k] * b->g_err[k];
        if (s2 > 0)
            d->rdf_z = fmax(d->rdf_z, fabs(e) / sqrt(s2));
    }
    d->rdf_rms = a->nbins ? sqrt(ss / (double)a->nbins) : 0;
    for (size_t k = 0; k < a->nbins; k++)
        d->rdf_mirror = fmax(d->rdf_mirror, fabs(b->g_mirror[k] - a->g_mirror[k]));
    return GP_OK;
}
