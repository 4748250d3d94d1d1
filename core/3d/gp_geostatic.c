/* gp_geostatic.c -- see gp_geostatic.h.
 *
 * Code: gp_geostatic_run() validates, settles the spheres on one DEM (settle: chunks of CHUNK
 * steps until S_c <= tol or max_steps) and hands the DEM's final spheres, contacts and wall
 * forces to measure(), which gp_geostatic_measure() calls directly. measure() works in the
 * frame (h1, h2, v) of gravity (frame_of): every sphere, branch and force is mapped there
 * once, so that the slabs, the core and the map are boxes of one kind, and its passes are
 * serial, in the order of the spheres and of the contacts (the same bits for any thread
 * count of the DEM before it):
 *   1. per sphere: frame coordinates, d50 and d_max, the weight above each slab's mid-plane
 *      (cap volumes), the porosity of each core slab (volume clipped to the slab's box),
 *      the whole packing's clipped volume, the centroid of the weight;
 *   2. per contact: the branch segment split among the slabs (full and core) and the map's
 *      cells it crosses (clip: the fraction of the segment inside a box, the planes of
 *      neighbouring boxes shared bit for bit so that the fractions add up to the whole),
 *      the whole Love-Weber tensor (gp_dem3d_stress_acc, box axes), contact counts, and the
 *      unbalanced force of every sphere for the list's S_c;
 *   3. the profile, K0, the equilibrium, the whole packing against its walls.
 */
#include "gp_geostatic.h"

#include "gp_clock.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define CHUNK 100                /* DEM steps between looks at S_c (as the specimen's relaxation) */
#define DEFAULT_MAX_STEPS 2000000
#define LIFT_DMAX 2.0            /* the top wall is lifted this many d_max above the box */
#define DEFAULT_SLAB_D50 5.0
#define DEFAULT_MARGIN_DMAX 1.5
#define MAX_SLABS 100000
#define MAX_MAP_CELLS 4000000
#define SETTLE_WEIGHT 0.95       /* progress: the settling's share of the fraction */
#define CANCEL_EVERY 65536       /* contacts or spheres between looks at the cancel flag */
#define SLIDING 0.99             /* a pair at this fraction of tan(phi) f_n is sliding */

void gp_geostatic_params_defaults(gp_geostatic_params *p)
{
    memset(p, 0, sizeof *p);
    gp_spec3d s;
    gp_spec3d_defaults(&s);
    p->material = s.material;
    p->gravity[2] = -GP_SPEC3D_GRAVITY;
    p->wall_friction_deg = 0;
    p->phi_deg = 23.7;
    p->slab = 0;
    p->wall_margin_dmax = DEFAULT_MARGIN_DMAX;
    p->map_cell = 0;
    p->map_slice = 0;
    p->stability_tol = GP_SPEC3D_STABILITY;
    p->scaled_radius = 0;
    p->max_steps = 0;
    p->threads = 1;
    p->keep_contacts = 0;
}

void gp_geostatic_result_destroy(gp_geostatic_result *r)
{
    if (!r)
        return;
    gp_geostatic_profile *q = &r->profile;
    free(q->depth);
    free(q->sigma_xx); free(q->sigma_yy); free(q->sigma_zz);
    free(q->sigma_xx_full); free(q->sigma_yy_full); free(q->sigma_zz_full);
    free(q->weight); free(q->k0); free(q->k0_full); free(q->porosity); free(q->coordination);
    free(q->k0_counted); free(q->equilibrium_counted);
    free(r->map.sigma_v); free(r->map.sigma_h);
    free(r->spheres);
    free(r->contacts);
    free(r);
}


/* ---- the frame of gravity ---- */

/* frame axis k is box axis ax[k]: the two horizontal axes in their order, then the vertical;
 * the frame's vertical coordinate is sg times the box's (up is +v in the frame) */
typedef struct frame {
    int ax[3];
    double sg;
    double lo[3], hi[3]; /* the box in frame coordinates */
} frame;

static void frame_vec(const frame *F, const double *p, double *q)
{
    q[0] = p[F->ax[0]];
    q[1] = p[F->ax[1]];
    q[2] = F->sg * p[F->ax[2]];
}

/* the frame of a gravity along one axis; -1 when it is not */
static int frame_of(const double g[3], const double lo[3], const double hi[3], frame *F)
{
    int v = -1, nz = 0;
    for (int a = 0; a < 3; a++)
        if (g[a] != 0) {
            v = a;
            nz++;
        }
    if (nz != 1 || !isfinite(g[v]))
        return -1;
    int k = 0;
    for (int a = 0; a < 3; a++)
        if (a != v)
            F->ax[k++] = a;
    F->ax[2] = v;
    F->sg = g[v] < 0 ? 1.0 : -1.0;
    for (int k2 = 0; k2 < 2; k2++) {
        F->lo[k2] = lo[F->ax[k2]];
        F->hi[k2] = hi[F->ax[k2]];
    }
    F->lo[2] = F->sg > 0 ? lo[v] : -hi[v];
    F->hi[2] = F->sg > 0 ? hi[v] : -lo[v];
    return 0;
}

/* ---- geometry: segments and spheres clipped to boxes ---- */

/* The fraction of the segment p + t l, t in [0, 1], inside the box [lo, hi) (bounds may be
 * infinite). A segment in a plane of the box's faces (l[a] == 0) counts for the box whose
 * interval is [lo, hi) on that axis, so that neighbouring boxes share it once. */
static double clip(const double p[3], const double l[3], const double lo[3], const double hi[3])
{
    double t0 = 0, t1 = 1;
    for (int a = 0; a < 3; a++) {
        if (l[a] == 0) {
            if (!(p[a] >= lo[a] && p[a] < hi[a]))
                return 0;
            continue;
        }
        double ta = (lo[a] - p[a]) / l[a], tb = (hi[a] - p[a]) / l[a];
        if (ta > tb) {
            double t = ta;
            ta = tb;
            tb = t;
        }
        if (ta > t0) t0 = ta;
        if (tb < t1) t1 = tb;
        if (!(t1 > t0))
            return 0;
    }
    return t1 - t0;
}

/* the volume of a sphere of radius r above the plane at height d over its centre */
static double cap_above(double r, double d)
{
    if (d >= r) return 0;
    if (d <= -r) return 4.0 / 3.0 * M_PI * r * r * r;
    double h = r - d;
    return M_PI * h * h * (3 * r - h) / 3.0;
}

/* the volume of a sphere of radius r between the planes at a < b over its centre (in [-r, r]) */
static double zslice_volume(double r, double a, double b)
{
    return M_PI * (r * r * (b - a) - (b * b * b - a * a * a) / 3.0);
}

/* the integral of sqrt(rho^2 - s^2) from 0 to u, |u| <= rho */
static double half_chord_integral(double u, double rho)
{
    double h = sqrt(fmax(0, rho * rho - u * u));
    double s = u / rho;
    s = s < -1 ? -1 : (s > 1 ? 1 : s);
    return 0.5 * (u * h + rho * rho * asin(s));
}

/* the integral over [lo, min(hi, a)] of 2 h(u) (twice) or of b + h(u), h = sqrt(rho^2 - u^2) */
static double chord_piece(double lo, double hi, double a, double rho, double b, int twice)
{
    if (hi > a) hi = a;
    if (!(hi > lo))
        return 0;
    double dh = half_chord_integral(hi, rho) - half_chord_integral(lo, rho);
    return twice ? 2 * dh : b * (hi - lo) + dh;
}

/* The area of the disc of radius rho centred at 0 with u <= a and v <= b (a, b may be
 * infinite): the integral over u <= a of the chord's part below b, cut where the chord's
 * half-length equals |b| (u = +-w). */
static double quadrant_area(double a, double b, double rho)
{
    if (!(rho > 0) || a <= -rho || b <= -rho)
        return 0;
    if (a > rho) a = rho;
    if (b >= rho)
        return chord_piece(-rho, rho, a, rho, 0, 1);
    double w = sqrt(rho * rho - b * b);
    if (b >= 0)
        return chord_piece(-rho, -w, a, rho, 0, 1) + chord_piece(-w, w, a, rho, b, 0)
               + chord_piece(w, rho, a, rho, 0, 1);
    return chord_piece(-w, w, a, rho, b, 0);
}

/* the area of the disc of radius rho centred at 0 inside [x1, x2] x [y1, y2] */
static double disc_rect_area(double rho, double x1, double x2, double y1, double y2)
{
    return quadrant_area(x2, y2, rho) - quadrant_area(x1, y2, rho) - quadrant_area(x2, y1, rho)
           + quadrant_area(x1, y1, rho);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* 8-point Gauss-Legendre on [-1, 1] */
static const double GL_X[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                               -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                               0.7966664774136267,  0.9602898564975363};
static const double GL_W[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                               0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                               0.2223810344533745, 0.1012285362903763};

/* The volume of the sphere s (frame coordinates) inside the box [lo, hi] (lateral bounds may be
 * infinite). Exact when the sphere's horizontal disc is all inside or all outside the box's
 * plan; else the area of the disc clipped to the plan (exact) integrated over the height by
 * Gauss-Legendre, in pieces cut where the disc starts to cross a side or a corner (the area is
 * smooth between). */
static double sphere_box_volume(const double *s, const double lo[3], const double hi[3])
{
    double r = s[3];
    double z1 = fmax(lo[2], s[2] - r), z2 = fmin(hi[2], s[2] + r);
    if (!(z2 > z1))
        return 0;
    if (s[0] - r >= lo[0] && s[0] + r <= hi[0] && s[1] - r >= lo[1] && s[1] + r <= hi[1])
        return zslice_volume(r, z1 - s[2], z2 - s[2]);
    double ex = fmax(0, fmax(lo[0] - s[0], s[0] - hi[0]));
    double ey = fmax(0, fmax(lo[1] - s[1], s[1] - hi[1]));
    if (ex * ex + ey * ey >= r * r)
        return 0;
    double d[2][2] = {{lo[0] - s[0], hi[0] - s[0]}, {lo[1] - s[1], hi[1] - s[1]}};
    double bp[2 + 8 + 8];
    int nb = 0;
    bp[nb++] = z1;
    bp[nb++] = z2;
    double q2[8];
    int nq = 0;
    for (int a = 0; a < 2; a++)
        for (int e = 0; e < 2; e++)
            if (isfinite(d[a][e]) && fabs(d[a][e]) < r)
                q2[nq++] = r * r - d[a][e] * d[a][e];
    for (int e0 = 0; e0 < 2; e0++)
        for (int e1 = 0; e1 < 2; e1++)
            if (isfinite(d[0][e0]) && isfinite(d[1][e1])) {
                double c2 = d[0][e0] * d[0][e0] + d[1][e1] * d[1][e1];
                if (c2 < r * r)
                    q2[nq++] = r * r - c2;
            }
    for (int k = 0; k < nq; k++) {
        double q = sqrt(q2[k]);
        double zs[2] = {s[2] - q, s[2] + q};
        for (int e = 0; e < 2; e++)
            if (zs[e] > z1 && zs[e] < z2)
                bp[nb++] = zs[e];
    }
    qsort(bp, (size_t)nb, sizeof *bp, cmp_double);
    double v = 0;
    for (int k = 0; k + 1 < nb; k++) {
        double a = bp[k], b = bp[k + 1];
        if (!(b > a))
            continue;
        double mid = 0.5 * (a + b), half = 0.5 * (b - a), sum = 0;
        for (int g = 0; g < 8; g++) {
            double z = mid + half * GL_X[g] - s[2];
            double rho = sqrt(fmax(0, r * r - z * z));
            sum += GL_W[g] * disc_rect_area(rho, d[0][0], d[0][1], d[1][0], d[1][1]);
        }
        v += half * sum;
    }
    return v;
}

/* ---- validation ---- */

static gp_status validate_params(const gp_geostatic_params *p, gp_error *err)
{
    const gp_material3d *m = &p->material;
    if (!(m->density > 0) || !isfinite(m->density))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: material.density must be > 0");
    if (!(m->young > 0) || !isfinite(m->young))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: material.young must be > 0");
    if (!(m->poisson >= 0) || !(m->poisson <= 10))
        return gp_error_set(err, GP_ERR_INVALID,
                            "geostatic: material.poisson (k_s/k_n) must be in [0, 10]");
    if (!(m->friction_deg >= 0) || !(m->friction_deg < 90))
        return gp_error_set(err, GP_ERR_INVALID,
                            "geostatic: material.friction_deg must be in [0, 90)");
    if (!(m->damping >= 0) || !(m->damping < 1))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: material.damping must be in [0, 1)");
    if (p->wall_friction_deg != 0)
        return gp_error_set(err, GP_ERR_INVALID,
                            "geostatic: wall_friction_deg must be 0 (the DEM's walls are "
                            "frictionless)");
    if (!(p->phi_deg > 0) || !(p->phi_deg < 90))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: phi_deg must be in (0, 90)");
    if (!(p->slab >= 0) || !isfinite(p->slab))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: slab must be >= 0 (0: 5 d50)");
    if (!(p->wall_margin_dmax >= 0) || !isfinite(p->wall_margin_dmax))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: wall_margin_dmax must be >= 0");
    if (!(p->map_cell >= 0) || !isfinite(p->map_cell))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: map_cell must be >= 0");
    if (!(p->map_slice >= 0) || !isfinite(p->map_slice))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: map_slice must be >= 0");
    if (!(p->stability_tol > 0) || !(p->stability_tol < 1))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: stability_tol must be in (0, 1)");
    if (!isfinite(p->scaled_radius))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: scaled_radius must be finite");
    if (p->max_steps < 0)
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: max_steps must be >= 0");
    if (p->threads < 0 || p->threads > 256)
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: threads must be in [0, 256]");
    return GP_OK;
}

static gp_status validate_input(const gp_geostatic_params *p, const double *xyzr, size_t n,
                                const double lo[3], const double hi[3], frame *F, gp_error *err)
{
    if (!p || !xyzr || !lo || !hi)
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: NULL argument");
    gp_status st = validate_params(p, err);
    if (st)
        return st;
    if (n == 0 || n > UINT32_MAX / 2)
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: sphere count %zu out of range", n);
    for (int a = 0; a < 3; a++)
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || !(hi[a] > lo[a]))
            return gp_error_set(err, GP_ERR_INVALID, "geostatic: box axis %d is empty", a);
    for (size_t i = 0; i < n; i++) {
        const double *s = xyzr + 4 * i;
        if (!isfinite(s[0]) || !isfinite(s[1]) || !isfinite(s[2]) || !isfinite(s[3]) || !(s[3] > 0))
            return gp_error_set(err, GP_ERR_INVALID, "geostatic: sphere %zu is not finite or has "
                                "r <= 0", i);
        for (int a = 0; a < 3; a++)
            if (!(s[a] > lo[a] - s[3]) || !(s[a] < hi[a] + s[3]))
                return gp_error_set(err, GP_ERR_INVALID, "geostatic: sphere %zu is outside the box "
                                    "(axis %d)", i, a);
    }
    if (frame_of(p->gravity, lo, hi, F))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: gravity must be finite and along one "
                            "axis of the box (the slabs are normal to it)");
    return GP_OK;
}

/* ---- progress ---- */

typedef gp_progress_pacer progress_ctx;

/* the callback, paced (gp_progress_pace); non-zero: stop */
static int report(progress_ctx *c, const char *phase, double fraction, double pf, long steps,
                  double sc, int force)
{
    gp_progress p = {.phase = phase, .fraction = fraction, .phase_fraction = pf, .steps = steps,
                     .stability = sc};
    return gp_progress_pace(c, p, force);
}

/* ---- the measures ---- */

/* the slab (or row) index of height z among n of thickness h below top, clamped */
static size_t row_of(double top, double h, size_t n, double z)
{
    double k = floor((top - z) / h);
    if (!(k > 0)) return 0;
    if (k >= (double)n) return n - 1;
    return (size_t)k;
}

static size_t col_of(double lo, double h, size_t n, double x)
{
    double k = floor((x - lo) / h);
    if (!(k > 0)) return 0;
    if (k >= (double)n) return n - 1;
    return (size_t)k;
}

/* the state measure() works on */
typedef struct meas {
    const gp_geostatic_params *P;
    frame F;
    size_t n;
    const double *xyzr;      /* box coordinates */
    double *fx;              /* frame coordinates, 4n */
    double top, bottom, H, area;
    size_t ns;               /* slabs */
    double h;                /* their thickness */
    double *zpl;             /* ns + 1 planes, zpl[0] = top, zpl[ns] = bottom */
    double margin;
    double core_lo[3], core_hi[3]; /* the core's plan (the z bounds set per slab) */
    /* the map */
    size_t mx, mz;
    double mdx, mdz, slo, shi; /* the slice: [slo, shi) along h2 (infinite: all) */
    double *xpl, *mzpl;      /* mx + 1 columns' planes, mz + 1 rows' planes */
    /* sums: per slab (frame diagonal), full and core; per map cell (v, h1) */
    double (*sfull)[3], (*score)[3];
    double *mv, *mh;
    double *cap;             /* per slab: the caps its mid-plane cuts off (above it) */
    double *full;            /* per slab: spheres wholly above its mid-plane, differences */
    double *solid;           /* per slab: solid volume in the core slab */
    double *ncount, *ccount; /* per slab: spheres with the centre in the core slab, and their
                                contacts */
    uint32_t *contacts;      /* per sphere: its contacts */
    double *res;             /* per sphere: unbalanced force (3), box axes */
    double *sfn;             /* per sphere: sum of |f_n| */
    double tanphi;           /* the spheres' friction */
    double mobilised, sliding; /* over the sphere pairs: sum of |f_t| / (tan phi |f_n|), and
                                  how many are at the limit */
} meas;

static void meas_free(meas *M)
{
    free(M->fx); free(M->zpl); free(M->xpl); free(M->mzpl);
    free(M->sfull); free(M->score); free(M->mv); free(M->mh);
    free(M->cap); free(M->full); free(M->solid); free(M->ncount); free(M->ccount);
    free(M->contacts); free(M->res); free(M->sfn);
}

/* d50 by volume and d_max of the spheres */
static gp_status sizes(const double *xyzr, size_t n, double *d50, double *dmax, gp_error *err)
{
    double *r = malloc(n * sizeof *r);
    if (!r)
        return gp_error_set(err, GP_ERR_NOMEM, "geostatic: out of memory");
    double tot = 0;
    for (size_t i = 0; i < n; i++) {
        r[i] = xyzr[4 * i + 3];
        tot += r[i] * r[i] * r[i];
    }
    qsort(r, n, sizeof *r, cmp_double);
    double acc = 0;
    *d50 = 2 * r[n - 1];
    for (size_t i = 0; i < n; i++) {
        acc += r[i] * r[i] * r[i];
        if (acc >= 0.5 * tot) {
            *d50 = 2 * r[i];
            break;
        }
    }
    *dmax = 2 * r[n - 1];
    free(r);
    return GP_OK;
}

/* the slabs, the core and the map's cells, and every array of M */
static gp_status meas_plan(meas *M, gp_geostatic_result *R, gp_error *err)
{
    const gp_geostatic_params *P = M->P;
    const frame *F = &M->F;
    M->top = F->hi[2];
    M->bottom = F->lo[2];
    M->H = M->top - M->bottom;
    M->area = (F->hi[0] - F->lo[0]) * (F->hi[1] - F->lo[1]);
    double slab = P->slab > 0 ? P->slab : DEFAULT_SLAB_D50 * R->d50;
    double ns = floor(M->H / slab + 0.5);
    if (ns > MAX_SLABS)
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: slab %g m cuts the height %g m into "
                            "more than %d slabs", slab, M->H, MAX_SLABS);
    M->ns = ns < 1 ? 1 : (size_t)ns;
    M->h = M->H / (double)M->ns;
    M->margin = P->wall_margin_dmax * R->dmax;
    for (int k = 0; k < 2; k++) {
        M->core_lo[k] = F->lo[k] + M->margin;
        M->core_hi[k] = F->hi[k] - M->margin;
        if (!(M->core_hi[k] > M->core_lo[k]))
            return gp_error_set(err, GP_ERR_INVALID, "geostatic: the wall margin (%g m) leaves no "
                                "core in a box %g m wide", M->margin, F->hi[k] - F->lo[k]);
    }
    double cell = P->map_cell > 0 ? P->map_cell : M->h;
    double Lx = F->hi[0] - F->lo[0];
    double mx = fmax(1, floor(Lx / cell + 0.5)), mz = fmax(1, floor(M->H / cell + 0.5));
    if (mx * mz > MAX_MAP_CELLS)
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: map_cell %g m makes more than %d "
                            "cells", cell, MAX_MAP_CELLS);
    M->mx = (size_t)mx;
    M->mz = (size_t)mz;
    M->mdx = Lx / mx;
    M->mdz = M->H / mz;
    double Ly = F->hi[1] - F->lo[1];
    if (P->map_slice > 0 && P->map_slice < Ly) {
        double c = 0.5 * (F->lo[1] + F->hi[1]);
        M->slo = c - 0.5 * P->map_slice;
        M->shi = c + 0.5 * P->map_slice;
    } else {
        M->slo = -INFINITY;
        M->shi = INFINITY;
    }
    size_t ns_ = M->ns, nc = M->mx * M->mz, n = M->n;
    M->fx = malloc(4 * n * sizeof *M->fx);
    M->zpl = malloc((ns_ + 1) * sizeof *M->zpl);
    M->xpl = malloc((M->mx + 1) * sizeof *M->xpl);
    M->mzpl = malloc((M->mz + 1) * sizeof *M->mzpl);
    M->sfull = calloc(ns_, sizeof *M->sfull);
    M->score = calloc(ns_, sizeof *M->score);
    M->mv = calloc(nc, sizeof *M->mv);
    M->mh = calloc(nc, sizeof *M->mh);
    M->cap = calloc(ns_, sizeof *M->cap);
    M->full = calloc(ns_, sizeof *M->full);
    M->solid = calloc(ns_, sizeof *M->solid);
    M->ncount = calloc(ns_, sizeof *M->ncount);
    M->ccount = calloc(ns_, sizeof *M->ccount);
    M->contacts = calloc(n, sizeof *M->contacts);
    M->res = calloc(3 * n, sizeof *M->res);
    M->sfn = calloc(n, sizeof *M->sfn);
    if (!M->fx || !M->zpl || !M->xpl || !M->mzpl || !M->sfull || !M->score || !M->mv || !M->mh
        || !M->cap || !M->full || !M->solid || !M->ncount || !M->ccount || !M->contacts
        || !M->res || !M->sfn)
        return gp_error_set(err, GP_ERR_NOMEM, "geostatic: out of memory");
    /* planes: the first and last are the box's own, bit for bit */
    for (size_t k = 0; k < ns_; k++)
        M->zpl[k] = M->top - (double)k * M->h;
    M->zpl[ns_] = M->bottom;
    for (size_t k = 0; k < M->mx; k++)
        M->xpl[k] = F->lo[0] + (double)k * M->mdx;
    M->xpl[M->mx] = F->hi[0];
    for (size_t k = 0; k < M->mz; k++)
        M->mzpl[k] = M->top - (double)k * M->mdz;
    M->mzpl[M->mz] = M->bottom;
    return GP_OK;
}

/* pass 1: per sphere (frame coordinates, weight above the mid-planes, core porosity, the whole
 * packing's solid and the weight's centroid) */
static gp_status pass_spheres(meas *M, gp_geostatic_result *R, const volatile int *cancel,
                              gp_error *err)
{
    const frame *F = &M->F;
    size_t ns = M->ns;
    double solid_box = 0, vol = 0, mom = 0, surface = -INFINITY;
    for (size_t i = 0; i < M->n; i++) {
        if (i % CANCEL_EVERY == 0 && gp_progress_cancelled(cancel))
            return gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        const double *p = M->xyzr + 4 * i;
        double *s = M->fx + 4 * i;
        frame_vec(F, p, s);
        double r = s[3] = p[3];
        double v = 4.0 / 3.0 * M_PI * r * r * r;
        vol += v;
        mom += v * (s[2] - M->bottom);
        if (s[2] + r > surface)
            surface = s[2] + r;
        solid_box += sphere_box_volume(s, F->lo, F->hi);
        /* the weight above each mid-plane: a cap where the mid-plane cuts the sphere, the
         * whole sphere for every mid-plane below it (full[] is a difference array) */
        size_t k = row_of(M->top, M->h, ns, s[2] + r);
        for (k = k > 0 ? k - 1 : 0; k < ns; k++) {
            double mid = 0.5 * (M->zpl[k] + M->zpl[k + 1]);
            if (mid >= s[2] + r)
                continue;
            if (mid <= s[2] - r) {
                M->full[k] += v;
                break;
            }
            M->cap[k] += cap_above(r, mid - s[2]);
        }
        /* the core slabs the sphere reaches (one more each side: the planes decide) */
        size_t k0 = row_of(M->top, M->h, ns, s[2] + r), k1 = row_of(M->top, M->h, ns, s[2] - r);
        k0 = k0 > 0 ? k0 - 1 : 0;
        k1 = k1 + 1 < ns ? k1 + 1 : ns - 1;
        for (size_t q = k0; q <= k1; q++) {
            double lo[3] = {M->core_lo[0], M->core_lo[1], M->zpl[q + 1]};
            double hi[3] = {M->core_hi[0], M->core_hi[1], M->zpl[q]};
            M->solid[q] += sphere_box_volume(s, lo, hi);
        }
    }
    R->whole.porosity = 1 - solid_box / (M->area * M->H);
    R->whole.centroid_height = vol > 0 ? mom / vol : 0;
    R->whole.surface = surface - M->bottom;
    double g = fabs(M->P->gravity[F->ax[2]]);
    R->whole.weight = g * M->P->material.density * vol;
    return GP_OK;
}

/* the contact's branch l and force f in the frame, and its start (sphere i's centre) */
static void contact_frame(const meas *M, const gp_contact3d *c, double l[3], double f[3])
{
    const double *pi = M->fx + 4 * c->i;
    frame_vec(&M->F, c->force, f);
    if (c->j >= 0) {
        const double *pj = M->fx + 4 * (size_t)c->j;
        for (int a = 0; a < 3; a++)
            l[a] = pj[a] - pi[a];
    } else {
        double nrm[3];
        frame_vec(&M->F, c->normal, nrm);
        double dist = pi[3] - c->overlap;
        for (int a = 0; a < 3; a++)
            l[a] = dist * nrm[a];
    }
}

/* pass 2: per contact (the split Love-Weber sums of the slabs and the map, the whole
 * tensor, contact counts, the spheres' unbalanced forces and |f_n|) */
static gp_status pass_contacts(meas *M, const gp_contact3d *c, size_t nc,
                               gp_dem3d_stress_acc *whole, size_t *pairs, size_t *walls,
                               double wall_sum[6], const volatile int *cancel, gp_error *err)
{
    size_t ns = M->ns;
    for (size_t q = 0; q < nc; q++) {
        if (q % CANCEL_EVERY == 0 && gp_progress_cancelled(cancel))
            return gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        const gp_contact3d *k = c + q;
        if (k->i >= M->n || (k->j >= 0 && ((size_t)k->j >= M->n || (size_t)k->j == k->i))
            || k->j < -6)
            return gp_error_set(err, GP_ERR_INVALID, "geostatic: contact %zu refers to no sphere "
                                "or wall", q);
        gp_dem3d_stress_acc_add(whole, k, 1);
        double l[3], f[3];
        contact_frame(M, k, l, f);
        const double *p = M->fx + 4 * k->i;
        double lf[3] = {-l[0] * f[0], -l[1] * f[1], -l[2] * f[2]};
        double fn = fabs(k->force[0] * k->normal[0] + k->force[1] * k->normal[1]
                         + k->force[2] * k->normal[2]);
        M->contacts[k->i]++;
        M->sfn[k->i] += fn;
        for (int a = 0; a < 3; a++)
            M->res[3 * k->i + a] += k->force[a];
        if (k->j >= 0) {
            /* the friction the pair mobilises: |f_t| / (tan(phi_mu) |f_n|) */
            double fs2 = 0, fdn = k->force[0] * k->normal[0] + k->force[1] * k->normal[1]
                                  + k->force[2] * k->normal[2];
            for (int a = 0; a < 3; a++) {
                double t = k->force[a] - fdn * k->normal[a];
                fs2 += t * t;
            }
            double mob = fn > 0 && M->tanphi > 0 ? sqrt(fs2) / (M->tanphi * fn) : 0;
            M->mobilised += mob;
            M->sliding += mob >= SLIDING;
            (*pairs)++;
            M->contacts[k->j]++;
            M->sfn[k->j] += fn;
            for (int a = 0; a < 3; a++)
                M->res[3 * (size_t)k->j + a] -= k->force[a];
        } else {
            (*walls)++;
            int w = (int)(-1 - k->j);
            wall_sum[w] += fabs(k->force[w / 2]);
        }
        double zlo = fmin(p[2], p[2] + l[2]), zhi = fmax(p[2], p[2] + l[2]);
        /* slabs: full cross-section and core */
        size_t s0 = row_of(M->top, M->h, ns, zhi), s1 = row_of(M->top, M->h, ns, zlo);
        s0 = s0 > 0 ? s0 - 1 : 0;
        s1 = s1 + 1 < ns ? s1 + 1 : ns - 1;
        for (size_t s = s0; s <= s1; s++) {
            double lo[3] = {-INFINITY, -INFINITY, M->zpl[s + 1]};
            double hi[3] = {INFINITY, INFINITY, M->zpl[s]};
            double w = clip(p, l, lo, hi);
            if (!(w > 0))
                continue;
            for (int a = 0; a < 3; a++)
                M->sfull[s][a] += w * lf[a];
            lo[0] = M->core_lo[0];
            lo[1] = M->core_lo[1];
            hi[0] = M->core_hi[0];
            hi[1] = M->core_hi[1];
            w = clip(p, l, lo, hi);
            if (w > 0)
                for (int a = 0; a < 3; a++)
                    M->score[s][a] += w * lf[a];
        }
        /* the map's cells */
        size_t r0 = row_of(M->top, M->mdz, M->mz, zhi), r1 = row_of(M->top, M->mdz, M->mz, zlo);
        r0 = r0 > 0 ? r0 - 1 : 0;
        r1 = r1 + 1 < M->mz ? r1 + 1 : M->mz - 1;
        double xlo = fmin(p[0], p[0] + l[0]), xhi = fmax(p[0], p[0] + l[0]);
        size_t c0 = col_of(M->F.lo[0], M->mdx, M->mx, xlo);
        size_t c1 = col_of(M->F.lo[0], M->mdx, M->mx, xhi);
        c0 = c0 > 0 ? c0 - 1 : 0;
        c1 = c1 + 1 < M->mx ? c1 + 1 : M->mx - 1;
        for (size_t r = r0; r <= r1; r++)
            for (size_t cc = c0; cc <= c1; cc++) {
                double lo[3] = {M->xpl[cc], M->slo, M->mzpl[r + 1]};
                double hi[3] = {M->xpl[cc + 1], M->shi, M->mzpl[r]};
                double w = clip(p, l, lo, hi);
                if (w > 0) {
                    M->mv[r * M->mx + cc] += w * lf[2];
                    M->mh[r * M->mx + cc] += w * lf[0];
                }
            }
    }
    return GP_OK;
}

/* the profile's arrays */
static gp_status alloc_profile(gp_geostatic_profile *q, size_t ns, gp_error *err)
{
    double **const cols[] = {&q->depth,         &q->sigma_xx,      &q->sigma_yy,
                             &q->sigma_zz,      &q->sigma_xx_full, &q->sigma_yy_full,
                             &q->sigma_zz_full, &q->weight,        &q->k0,
                             &q->k0_full,       &q->porosity,      &q->coordination};
    int ok = 1;
    for (size_t k = 0; k < sizeof cols / sizeof *cols; k++)
        ok &= (*cols[k] = calloc(ns, sizeof(double))) != NULL;
    q->k0_counted = calloc(ns, 1);
    q->equilibrium_counted = calloc(ns, 1);
    if (!ok || !q->k0_counted || !q->equilibrium_counted)
        return gp_error_set(err, GP_ERR_NOMEM, "geostatic: out of memory");
    q->n = ns;
    return GP_OK;
}

/* pass 3: the profile, K0, the equilibrium, the map and the whole packing into R */
static gp_status finish(meas *M, gp_geostatic_result *R, const gp_dem3d_stress_acc *whole,
                        size_t pairs, size_t walls, const double wall_force[6], gp_error *err)
{
    const frame *F = &M->F;
    const gp_geostatic_params *P = M->P;
    size_t ns = M->ns;
    gp_geostatic_profile *q = &R->profile;
    gp_status st = alloc_profile(q, ns, err);
    if (st)
        return st;
    q->thickness = M->h;
    q->margin = M->margin;
    double g = fabs(P->gravity[F->ax[2]]), rho = P->material.density;
    double core_area = (M->core_hi[0] - M->core_lo[0]) * (M->core_hi[1] - M->core_lo[1]);
    double Vfull = M->area * M->h, Vcore = core_area * M->h;
    /* the frame's diagonal in box axes: box axis F->ax[k] is frame axis k */
    double *sc[3], *sf[3];
    double *box_core[3] = {q->sigma_xx, q->sigma_yy, q->sigma_zz};
    double *box_full[3] = {q->sigma_xx_full, q->sigma_yy_full, q->sigma_zz_full};
    for (int k = 0; k < 3; k++) {
        sc[k] = box_core[F->ax[k]];
        sf[k] = box_full[F->ax[k]];
    }
    /* spheres' centres per core slab and their contacts */
    for (size_t i = 0; i < M->n; i++) {
        const double *s = M->fx + 4 * i;
        if (!(s[0] >= M->core_lo[0] && s[0] < M->core_hi[0] && s[1] >= M->core_lo[1]
              && s[1] < M->core_hi[1] && s[2] >= M->bottom && s[2] < M->top))
            continue;
        size_t k = row_of(M->top, M->h, ns, s[2]);
        /* the planes decide (row_of may be one off at a plane) */
        while (k > 0 && s[2] >= M->zpl[k]) k--;
        while (k + 1 < ns && s[2] < M->zpl[k + 1]) k++;
        M->ncount[k] += 1;
        M->ccount[k] += M->contacts[i];
    }
    /* rows left out: the top (max(one slab, the margin)), and for K0 the bottom (the margin) */
    double skip = fmax(M->h, M->margin);
    double cum = 0;
    double ksum = 0, ksum2 = 0, hsum = 0, vsum = 0;
    size_t kn = 0, en = 0;
    double emax = 0, ecore = 0;
    for (size_t k = 0; k < ns; k++) {
        cum += M->full[k];
        q->depth[k] = M->top - 0.5 * (M->zpl[k] + M->zpl[k + 1]);
        q->weight[k] = g * rho * (cum + M->cap[k]) / M->area;
        for (int a = 0; a < 3; a++) {
            sc[a][k] = M->score[k][a] / Vcore;
            sf[a][k] = M->sfull[k][a] / Vfull;
        }
        double hv = M->score[k][2] / Vcore, hh = 0.5 * (M->score[k][0] + M->score[k][1]) / Vcore;
        double fv = M->sfull[k][2] / Vfull, fh = 0.5 * (M->sfull[k][0] + M->sfull[k][1]) / Vfull;
        q->k0[k] = hv > 0 ? hh / hv : NAN;
        q->k0_full[k] = fv > 0 ? fh / fv : NAN;
        q->porosity[k] = 1 - M->solid[k] / Vcore;
        q->coordination[k] = M->ncount[k] > 0 ? M->ccount[k] / M->ncount[k] : 0;
        double upper = M->top - M->zpl[k], lower = M->zpl[k + 1] - M->bottom;
        int away_top = upper >= skip * (1 - 1e-9);
        q->equilibrium_counted[k] = (unsigned char)away_top;
        q->k0_counted[k] = (unsigned char)(away_top && lower >= M->margin * (1 - 1e-9)
                                           && isfinite(q->k0[k]));
        if (away_top) {
            double w = q->weight[k];
            double e = w > 0 ? fabs(fv - w) / w : INFINITY;
            double ec = w > 0 ? fabs(hv - w) / w : INFINITY;
            emax = fmax(emax, e);
            ecore = fmax(ecore, ec);
            en++;
        }
        if (q->k0_counted[k]) {
            ksum += q->k0[k];
            ksum2 += q->k0[k] * q->k0[k];
            hsum += hh;
            vsum += hv;
            kn++;
        }
    }
    R->equilibrium.max_error = en ? emax : NAN;
    R->equilibrium.core_max_error = en ? ecore : NAN;
    R->equilibrium.slabs = en;
    R->k0.theory = 1 - sin(P->phi_deg * M_PI / 180);
    R->k0.slabs = kn;
    R->k0.mean = kn ? ksum / (double)kn : NAN;
    R->k0.sd = kn > 1 ? sqrt(fmax(0, (ksum2 - ksum * ksum / (double)kn) / (double)(kn - 1))) : 0;
    R->k0.bulk = vsum > 0 ? hsum / vsum : NAN;
    /* the map */
    gp_geostatic_map *mp = &R->map;
    size_t nc = M->mx * M->mz;
    mp->nx = M->mx;
    mp->nz = M->mz;
    mp->axis_h = F->ax[0];
    mp->axis_v = F->ax[2];
    mp->dx = M->mdx;
    mp->dz = M->mdz;
    mp->sigma_v = malloc(nc * sizeof *mp->sigma_v);
    mp->sigma_h = malloc(nc * sizeof *mp->sigma_h);
    if (!mp->sigma_v || !mp->sigma_h)
        return gp_error_set(err, GP_ERR_NOMEM, "geostatic: out of memory");
    double slo = isfinite(M->slo) ? M->slo : F->lo[1], shi = isfinite(M->shi) ? M->shi : F->hi[1];
    mp->slice_lo = slo;
    mp->slice_hi = shi;
    double Vcell = M->mdx * (shi - slo) * M->mdz;
    for (size_t k = 0; k < nc; k++) {
        mp->sigma_v[k] = M->mv[k] / Vcell;
        mp->sigma_h[k] = M->mh[k] / Vcell;
    }
    /* the whole packing against its walls */
    gp_geostatic_whole *wh = &R->whole;
    double V = M->area * M->H;
    gp_dem3d_stress_acc_finish(whole, V, wh->love_weber);
    double L[3]; /* box spans along the box axes */
    for (int k = 0; k < 3; k++)
        L[F->ax[k]] = F->hi[k] - F->lo[k];
    for (int w = 0; w < 6; w++) {
        int a = w / 2;
        wh->wall_stress[w] = wall_force[w] / (L[(a + 1) % 3] * L[(a + 2) % 3]);
    }
    int v = F->ax[2];
    int bottom_wall = 2 * v + (F->sg > 0 ? 0 : 1);
    wh->max_error = 0;
    for (int a = 0; a < 3; a++) {
        if (a == v)
            wh->walls[a] = wall_force[bottom_wall] * wh->centroid_height / V;
        else
            wh->walls[a] = 0.5 * (wh->wall_stress[2 * a] + wh->wall_stress[2 * a + 1]);
        double e = fabs(wh->love_weber[a][a] - wh->walls[a]);
        e = wh->walls[a] != 0 ? e / fabs(wh->walls[a]) : (e > 0 ? INFINITY : 0);
        wh->max_error = fmax(wh->max_error, e);
    }
    wh->contacts = pairs;
    wh->wall_contacts = walls;
    wh->friction_mobilised = pairs ? M->mobilised / (double)pairs : 0;
    wh->sliding = pairs ? M->sliding / (double)pairs : 0;
    wh->coordination = (2.0 * (double)pairs + (double)walls) / (double)M->n;
    /* the list's S_c: the spheres' unbalanced forces, gravity on the true mass */
    double sum_f = 0, sum_fn = 0;
    for (size_t i = 0; i < M->n; i++) {
        double r = M->xyzr[4 * i + 3];
        double m = 4.0 / 3.0 * M_PI * r * r * r * rho, e2 = 0;
        for (int a = 0; a < 3; a++) {
            double e = M->res[3 * i + a] + m * P->gravity[a];
            e2 += e * e;
        }
        sum_f += sqrt(e2);
        sum_fn += M->sfn[i];
    }
    R->stability_list = sum_fn > 0 ? sum_f / sum_fn : INFINITY;
    return GP_OK;
}

/* Everything measured on the spheres xyzr (box coordinates: R->spheres) and their contacts
 * into R (R's d50 and dmax are set here). */
static gp_status measure(const gp_geostatic_params *P, const frame *F, const double *xyzr,
                         size_t n, const gp_contact3d *c, size_t nc, const double wall_force[6],
                         const volatile int *cancel, gp_geostatic_result *R, gp_error *err)
{
    meas M;
    memset(&M, 0, sizeof M);
    M.P = P;
    M.F = *F;
    M.n = n;
    M.xyzr = xyzr;
    M.tanphi = tan(P->material.friction_deg * M_PI / 180);
    R->axis_v = F->ax[2];
    R->up_sign = F->sg > 0 ? 1 : -1;
    gp_status st = sizes(xyzr, n, &R->d50, &R->dmax, err);
    if (!st) st = meas_plan(&M, R, err);
    if (!st) st = pass_spheres(&M, R, cancel, err);
    gp_dem3d_stress_acc whole;
    gp_dem3d_stress_acc_init(&whole, xyzr);
    size_t pairs = 0, walls = 0;
    double wall_sum[6] = {0};
    if (!st) st = pass_contacts(&M, c, nc, &whole, &pairs, &walls, wall_sum, cancel, err);
    if (!st) st = finish(&M, R, &whole, pairs, walls, wall_force ? wall_force : wall_sum, err);
    meas_free(&M);
    return st;
}

/* ---- the settling ---- */

/* how far a gap closing towards end has come from g0, on a log scale */
static double gap_progress(double g0, double g, double end)
{
    if (!(g0 > end) || !(g > end)) return 1;
    return fmax(0, log(g0 / g) / log(g0 / end));
}

/* The DEM over the spheres x (replaced by the final state), gravity on, the top wall lifted;
 * its contacts (*c, malloc'ed) and wall forces at the end. */
static gp_status settle(const gp_geostatic_params *P, const frame *F, double *x, size_t n,
                        const double lo[3], const double hi[3], double dmax, progress_ctx *pc,
                        gp_geostatic_result *R, gp_contact3d **c, size_t *nc,
                        double wall_force[6], gp_error *err)
{
    double rmin = INFINITY, rmax = 0;
    for (size_t i = 0; i < n; i++) {
        rmin = fmin(rmin, x[4 * i + 3]);
        rmax = fmax(rmax, x[4 * i + 3]);
    }
    gp_dem3d_params dp;
    gp_dem3d_params_defaults(&dp);
    dp.density = P->material.density;
    dp.young = P->material.young;
    dp.ks_kn = P->material.poisson;
    dp.friction_deg = P->material.friction_deg;
    dp.damping = fmax(P->material.damping, GP_SPEC3D_RELAX_DAMPING);
    memcpy(dp.gravity, P->gravity, sizeof dp.gravity);
    /* the specimen's rule: DT_SAFETY sqrt(m / 2 E R) at the relaxation's damping */
    dp.dt_safety = GP_SPEC3D_DT_SAFETY * pow(1 + GP_SPEC3D_RELAX_DAMPING, GP_SPEC3D_DT_DAMPING_EXP);
    dp.dt_damping_exp = GP_SPEC3D_DT_DAMPING_EXP;
    dp.scaled_radius = P->scaled_radius == 0 ? rmax : (P->scaled_radius > 0 ? P->scaled_radius : 0);
    dp.skin = rmin;
    dp.threads = P->threads > 0 ? P->threads : 1;
    R->scaled_radius = dp.scaled_radius;
    double dlo[3], dhi[3];
    memcpy(dlo, lo, sizeof dlo);
    memcpy(dhi, hi, sizeof dhi);
    int v = F->ax[2];
    if (F->sg > 0)
        dhi[v] += LIFT_DMAX * dmax;
    else
        dlo[v] -= LIFT_DMAX * dmax;
    gp_dem3d *dem = NULL;
    gp_status st = gp_dem3d_create(&dp, x, n, dlo, dhi, &dem, err);
    if (st)
        return st;
    gp_dem3d_set_cancel(dem, pc->cancel);
    R->dt = gp_dem3d_dt(dem);
    long max_steps = P->max_steps > 0 ? P->max_steps : DEFAULT_MAX_STEPS;
    gp_dem3d_state ds;
    memset(&ds, 0, sizeof ds);
    double tol = P->stability_tol, sc0 = -1, pf = 0;
    while (ds.steps < max_steps) {
        long k = max_steps - ds.steps < CHUNK ? max_steps - ds.steps : CHUNK;
        if ((st = gp_dem3d_run(dem, k, err)))
            break;
        gp_dem3d_get_state(dem, &ds);
        if (sc0 < 0)
            sc0 = fmax(ds.stability, 2 * tol);
        pf = fmax(pf, gap_progress(sc0, ds.stability, tol));
        if (report(pc, "settling", SETTLE_WEIGHT * pf, pf, ds.steps, ds.stability, 0)) {
            st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
            break;
        }
        if (ds.stability <= tol) {
            R->converged = 1;
            break;
        }
    }
    if (!st) {
        R->steps = ds.steps;
        R->stability = ds.stability;
        R->dt = gp_dem3d_dt(dem);
        R->dt_cuts = ds.dt_cuts;
        memcpy(wall_force, ds.wall_force, 6 * sizeof *wall_force);
        gp_dem3d_spheres(dem, x);
        st = gp_dem3d_contacts(dem, c, nc, err);
    }
    gp_dem3d_destroy(dem);
    return st;
}

/* the result with a copy of the spheres */
static gp_status new_result(const double *xyzr, size_t n, gp_geostatic_result **out, gp_error *err)
{
    gp_geostatic_result *R = calloc(1, sizeof *R);
    if (R)
        R->spheres = malloc(4 * n * sizeof *R->spheres);
    if (!R || !R->spheres) {
        gp_geostatic_result_destroy(R);
        return gp_error_set(err, GP_ERR_NOMEM, "geostatic: out of memory");
    }
    memcpy(R->spheres, xyzr, 4 * n * sizeof *xyzr);
    R->n = n;
    *out = R;
    return GP_OK;
}

/* the final contacts to the result (keep_contacts) or freed */
static void hand_contacts(const gp_geostatic_params *P, gp_geostatic_result *R, gp_contact3d *c,
                          size_t nc)
{
    if (P->keep_contacts) {
        R->contacts = c;
        R->ncontacts = nc;
    } else {
        free(c);
    }
}

gp_status gp_geostatic_run(const gp_geostatic_params *params, const double *xyzr, size_t n,
                           const double lo[3], const double hi[3], gp_progress_fn progress,
                           void *user, const volatile int *cancel, gp_geostatic_result **out,
                           gp_error *err)
{
    if (out)
        *out = NULL;
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: NULL argument");
    frame F;
    gp_status st = validate_input(params, xyzr, n, lo, hi, &F, err);
    if (st)
        return st;
    gp_geostatic_result *R = NULL;
    if ((st = new_result(xyzr, n, &R, err)))
        return st;
    progress_ctx pc = {progress, user, cancel, 0};
    double t0 = gp_clock_seconds();
    double d50, dmax;
    gp_contact3d *c = NULL;
    size_t nc = 0;
    double wall_force[6] = {0};
    st = sizes(xyzr, n, &d50, &dmax, err);
    if (!st)
        st = settle(params, &F, R->spheres, n, lo, hi, dmax, &pc, R, &c, &nc, wall_force, err);
    double t1 = gp_clock_seconds();
    R->seconds_settling = t1 - t0;
    if (!st && report(&pc, "measuring", SETTLE_WEIGHT, 0, R->steps, R->stability, 1))
        st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
    if (!st)
        st = measure(params, &F, R->spheres, n, c, nc, wall_force, cancel, R, err);
    if (st) {
        free(c);
        gp_geostatic_result_destroy(R);
        return st;
    }
    hand_contacts(params, R, c, nc);
    R->seconds_measure = gp_clock_seconds() - t1;
    report(&pc, "measuring", 1.0, 1.0, R->steps, R->stability, 1);
    *out = R;
    if (!R->converged)
        return gp_error_set(err, GP_ERR_NOT_CONVERGED, "geostatic: S_c = %.3g after %ld steps "
                            "(> %g)", R->stability, R->steps, params->stability_tol);
    return GP_OK;
}

gp_status gp_geostatic_measure(const gp_geostatic_params *params, const double *xyzr, size_t n,
                               const double lo[3], const double hi[3], const gp_contact3d *c,
                               size_t nc, const double wall_force[6], const volatile int *cancel,
                               gp_geostatic_result **out, gp_error *err)
{
    if (out)
        *out = NULL;
    if (!out || (nc > 0 && !c))
        return gp_error_set(err, GP_ERR_INVALID, "geostatic: NULL argument");
    frame F;
    gp_status st = validate_input(params, xyzr, n, lo, hi, &F, err);
    if (st)
        return st;
    gp_geostatic_result *R = NULL;
    if ((st = new_result(xyzr, n, &R, err)))
        return st;
    double t0 = gp_clock_seconds();
    R->converged = 1;
    st = measure(params, &F, R->spheres, n, c, nc, wall_force, cancel, R, err);
    if (!st && params->keep_contacts && nc > 0) {
        if (!(R->contacts = malloc(nc * sizeof *R->contacts)))
            st = gp_error_set(err, GP_ERR_NOMEM, "geostatic: out of memory");
        else {
            memcpy(R->contacts, c, nc * sizeof *c);
            R->ncontacts = nc;
        }
    }
    if (st) {
        gp_geostatic_result_destroy(R);
        return st;
    }
    R->stability = R->stability_list;
    R->seconds_measure = gp_clock_seconds() - t0;
    *out = R;
    return GP_OK;
}
