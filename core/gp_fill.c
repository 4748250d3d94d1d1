/* gp_fill.c -- optimised filling of one cell with a Fourier grain. See gp_fill.h for the
 * method; this file keeps the hot objective cheap: the shape factor rho_i is a fixed part
 * (modes outside 2..7, computed once per cell) plus six modes evaluated from precomputed
 * cos(n theta_i), sin(n theta_i) tables, so one evaluation is ~12 multiply-adds per ray and
 * needs no trigonometric call beyond the twelve cos/sin of the phases. */
#include "gp_fill.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_multimin.h>
#include <gsl/gsl_vector.h>

#define FIRST_OPT 2 /* first optimised mode */
#define LAST_OPT 7  /* last optimised mode */
#define NOPT (LAST_OPT - FIRST_OPT + 1)
/* Restarts of the phases+centre simplex. Measured on the paper's Example 1 (500 cells,
 * F_S 0.65): 0 restarts 0.613, 2 restarts 0.617 global solid fraction, 5 restarts 0.614
 * (noise) at twice the time; 2 is where the gain stops paying. */
#define FILL_RESTARTS 2

struct gp_fill_workspace {
    gp_fill_params p;
    size_t np, nm, ntab;  /* rays, modes used, modes tabulated (>= 8) */
    double *cosn, *sinn;  /* ntab * np: cos(n theta_i), sin(n theta_i) */
    double *base;         /* np: 1 + fixed modes */
    double *rmax;         /* np: ray length to the cell boundary from the current centre */
    double *rho;          /* np */
    /* the cell being filled, in local coordinates: origin at the starting centre, scaled to
     * unit area, so the search sees the same numbers for a cell at 1e-6 or offset by 1e6 */
    gp_vec2 *cell;
    size_t ncell, cell_cap;
    int convex;           /* the local cell is convex (and counter-clockwise) */
    double cell_area;     /* in local coordinates (1 up to rounding) */
    int evals;
    gsl_multimin_fminimizer *nm6, *nm8;
    gsl_vector *x6, *x8, *step6, *step8;
};

void gp_fill_params_defaults(gp_fill_params *p)
{
    memset(p, 0, sizeof *p);
    p->solid_fraction = 0.65;
    p->contour_points = 128;
    p->margin = 1e-9;
    p->optimise_centre = 1;
    p->max_evals = 400;
}

void gp_fill_workspace_destroy(gp_fill_workspace *ws)
{
    if (!ws)
        return;
    free(ws->cosn);
    free(ws->sinn);
    free(ws->base);
    free(ws->rmax);
    free(ws->rho);
    free(ws->cell);
    if (ws->nm6) gsl_multimin_fminimizer_free(ws->nm6);
    if (ws->nm8) gsl_multimin_fminimizer_free(ws->nm8);
    gsl_vector_free(ws->x6);
    gsl_vector_free(ws->x8);
    gsl_vector_free(ws->step6);
    gsl_vector_free(ws->step8);
    free(ws);
}

gp_fill_workspace *gp_fill_workspace_create(const gp_fill_params *p, gp_error *err)
{
    if (!p || !p->D) {
        gp_error_set(err, GP_ERR_INVALID, "fill: parameters and spectrum are required");
        return NULL;
    }
    if (!(p->solid_fraction > 0.0 && p->solid_fraction <= 1.0)) {
        gp_error_set(err, GP_ERR_INVALID, "fill: solid_fraction must be in (0, 1], got %g",
                     p->solid_fraction);
        return NULL;
    }
    if (p->contour_points < 16) {
        gp_error_set(err, GP_ERR_INVALID, "fill: contour_points must be >= 16, got %zu",
                     p->contour_points);
        return NULL;
    }
    if (p->nmodes < 1 || p->nmodes > p->contour_points / 2) {
        gp_error_set(err, GP_ERR_INVALID, "fill: nmodes must be in [1, %zu], got %zu",
                     p->contour_points / 2, p->nmodes);
        return NULL;
    }
    for (size_t n = 0; n < p->nmodes; n++) {
        if (!(p->D[n] >= 0.0) || !isfinite(p->D[n])) {
            gp_error_set(err, GP_ERR_INVALID, "fill: spectrum D_%zu = %g must be finite and >= 0",
                         n, p->D[n]);
            return NULL;
        }
    }
    if (!(p->margin >= 0.0 && p->margin < 0.5)) {
        gp_error_set(err, GP_ERR_INVALID, "fill: margin must be in [0, 0.5), got %g", p->margin);
        return NULL;
    }

    gp_fill_workspace *ws = calloc(1, sizeof *ws);
    if (!ws) {
        gp_error_set(err, GP_ERR_NOMEM, "fill: out of memory");
        return NULL;
    }
    ws->p = *p;
    if (ws->p.max_evals <= 0)
        ws->p.max_evals = 400;
    ws->np = p->contour_points;
    ws->nm = p->nmodes;
    ws->ntab = ws->nm > LAST_OPT + 1 ? ws->nm : LAST_OPT + 1;
    ws->cosn = malloc(ws->ntab * ws->np * sizeof(double));
    ws->sinn = malloc(ws->ntab * ws->np * sizeof(double));
    ws->base = malloc(ws->np * sizeof(double));
    ws->rmax = malloc(ws->np * sizeof(double));
    ws->rho = malloc(ws->np * sizeof(double));
    ws->nm6 = gsl_multimin_fminimizer_alloc(gsl_multimin_fminimizer_nmsimplex2, NOPT);
    ws->nm8 = gsl_multimin_fminimizer_alloc(gsl_multimin_fminimizer_nmsimplex2, NOPT + 2);
    ws->x6 = gsl_vector_alloc(NOPT);
    ws->x8 = gsl_vector_alloc(NOPT + 2);
    ws->step6 = gsl_vector_alloc(NOPT);
    ws->step8 = gsl_vector_alloc(NOPT + 2);
    if (!ws->cosn || !ws->sinn || !ws->base || !ws->rmax || !ws->rho || !ws->nm6 || !ws->nm8 ||
        !ws->x6 || !ws->x8 || !ws->step6 || !ws->step8) {
        gp_fill_workspace_destroy(ws);
        gp_error_set(err, GP_ERR_NOMEM, "fill: out of memory");
        return NULL;
    }
    /* Reduce n*i modulo Np before scaling so every table entry is exact to the last bit
     * whatever n is (cos(2 pi k / Np) for an integer k < Np). */
    for (size_t n = 0; n < ws->ntab; n++) {
        for (size_t i = 0; i < ws->np; i++) {
            size_t k = (n * i) % ws->np;
            double a = 2.0 * M_PI * (double)k / (double)ws->np;
            ws->cosn[n * ws->np + i] = cos(a);
            ws->sinn[n * ws->np + i] = sin(a);
        }
    }
    return ws;
}

/* The exit of ray (ux, uy) from c through edge k of p, or -1 when the ray misses it. */
static inline double edge_exit(const gp_vec2 *p, size_t n, size_t k, gp_vec2 c, double ux,
                               double uy)
{
    gp_vec2 a = p[k], b = p[k + 1 == n ? 0 : k + 1];
    double ax = a.x - c.x, ay = a.y - c.y;
    double ex = b.x - a.x, ey = b.y - a.y;
    double den = ux * ey - uy * ex;
    if (den == 0.0) return -1.0;
    double t = (ax * ey - ay * ex) / den;
    double s = (ax * uy - ay * ux) / den;
    return (t > 0.0 && s >= 0.0 && s <= 1.0) ? t : -1.0;
}

/* Distance from c along (ux, uy) to the first crossing of the polygon boundary, or -1 if the
 * ray meets no edge (c outside or on a degenerate polygon). Parallel edges are met at their
 * ends instead. */
static double ray_exit(const gp_vec2 *p, size_t n, gp_vec2 c, double ux, double uy)
{
    double best = DBL_MAX;
    for (size_t k = 0; k < n; k++) {
        double t = edge_exit(p, n, k, c, ux, uy);
        if (t > 0.0 && t < best)
            best = t;
    }
    return best == DBL_MAX ? -1.0 : best;
}

/* rmax_i for a convex counter-clockwise cell and c inside it: a ray from an interior point
 * leaves a convex polygon through exactly one edge, and as the ray turns counter-clockwise so
 * does that edge, so one walk round the polygon serves all the rays -- O(np + ncell) instead
 * of O(np * ncell), which made this the filling's hot spot (40 % of a 2D job). Returns -1
 * when the walk finds no edge (c on or outside the boundary). */
static int cast_rays_convex(gp_fill_workspace *ws, gp_vec2 c)
{
    const double *cs = ws->cosn + ws->np, *sn = ws->sinn + ws->np; /* n = 1 */
    const gp_vec2 *p = ws->cell;
    size_t n = ws->ncell, k = 0;
    double keep = 1.0 - ws->p.margin;
    for (size_t i = 0; i < ws->np; i++) {
        double t = -1.0;
        for (size_t tries = 0; tries < n; tries++) {
            t = edge_exit(p, n, k, c, cs[i], sn[i]);
            if (t > 0.0) break;
            k = k + 1 == n ? 0 : k + 1;
        }
        if (!(t > 0.0)) return -1;
        ws->rmax[i] = t * keep;
    }
    return 0;
}

/* rmax_i from centre c; 0 on success, -1 if some ray finds no boundary (c outside). */
static int cast_rays(gp_fill_workspace *ws, gp_vec2 c)
{
    if (ws->convex) return cast_rays_convex(ws, c);
    const double *cs = ws->cosn + ws->np, *sn = ws->sinn + ws->np; /* n = 1 */
    double keep = 1.0 - ws->p.margin;
    for (size_t i = 0; i < ws->np; i++) {
        double t = ray_exit(ws->cell, ws->ncell, c, cs[i], sn[i]);
        if (!(t > 0.0))
            return -1;
        ws->rmax[i] = t * keep;
    }
    return 0;
}

/* rho_i for the given optimised phases (ph[0..5] = delta_2..delta_7); returns min rho. */
static double shape_factor(gp_fill_workspace *ws, const double *ph)
{
    size_t np = ws->np;
    double ca[NOPT], sa[NOPT];
    for (int j = 0; j < NOPT; j++) {
        size_t n = FIRST_OPT + (size_t)j;
        double d = n < ws->nm ? ws->p.D[n] : 0.0;
        ca[j] = d * cos(ph[j]);
        sa[j] = d * sin(ph[j]);
    }
    double mn = DBL_MAX;
    for (size_t i = 0; i < np; i++) {
        double r = ws->base[i];
        for (int j = 0; j < NOPT; j++) {
            size_t off = (FIRST_OPT + (size_t)j) * np + i;
            r += ca[j] * ws->cosn[off] + sa[j] * ws->sinn[off];
        }
        ws->rho[i] = r;
        if (r < mn)
            mn = r;
    }
    return mn;
}

/* Area of the polygon with radii rho_i (unit r0). */
static double unit_area(const gp_fill_workspace *ws)
{
    double s = 0.0;
    for (size_t i = 0; i < ws->np; i++)
        s += ws->rho[i] * ws->rho[(i + 1) % ws->np];
    return 0.5 * sin(2.0 * M_PI / (double)ws->np) * s;
}

/* Largest r0 allowed by the rays for the current rho. */
static double r0_limit(const gp_fill_workspace *ws)
{
    double r0 = DBL_MAX;
    for (size_t i = 0; i < ws->np; i++) {
        double q = ws->rmax[i] / ws->rho[i];
        if (q < r0)
            r0 = q;
    }
    return r0;
}

/* The achievable fraction for phases ph (and the current rmax). */
static double achievable(gp_fill_workspace *ws, const double *ph)
{
    ws->evals++;
    if (!(shape_factor(ws, ph) > 0.0))
        return 0.0; /* not star-shaped for these phases */
    double r0 = r0_limit(ws);
    return r0 * r0 * unit_area(ws) / ws->cell_area;
}

static double objective6(const gsl_vector *x, void *user)
{
    gp_fill_workspace *ws = user;
    double ph[NOPT];
    for (int j = 0; j < NOPT; j++)
        ph[j] = gsl_vector_get(x, (size_t)j);
    return -achievable(ws, ph);
}

static double objective8(const gsl_vector *x, void *user)
{
    gp_fill_workspace *ws = user;
    double ph[NOPT];
    for (int j = 0; j < NOPT; j++)
        ph[j] = gsl_vector_get(x, (size_t)j);
    gp_vec2 c = {gsl_vector_get(x, NOPT), gsl_vector_get(x, NOPT + 1)};
    if (!gp_poly_contains(ws->cell, ws->ncell, c) || cast_rays(ws, c) != 0) {
        ws->evals++;
        return 0.0;
    }
    return -achievable(ws, ph);
}

/* Runs Nelder-Mead from x until the fraction reaches target, the simplex collapses or the
 * budget is spent; leaves the best point in x and returns its fraction. */
static double maximise(gp_fill_workspace *ws, gsl_multimin_fminimizer *m, gsl_multimin_function *f,
                       gsl_vector *x, const gsl_vector *step, double target)
{
    double f0 = -f->f(x, f->params);
    if (f0 >= target)
        return f0;
    gsl_multimin_fminimizer_set(m, f, x, step);
    int budget = ws->evals + ws->p.max_evals;
    while (ws->evals < budget) {
        if (gsl_multimin_fminimizer_iterate(m) != GSL_SUCCESS)
            break;
        if (-m->fval >= target)
            break;
        if (gsl_multimin_test_size(gsl_multimin_fminimizer_size(m), 1e-4) == GSL_SUCCESS)
            break;
    }
    double best = -m->fval;
    if (best > f0) {
        gsl_vector_memcpy(x, m->x);
        return best;
    }
    return f0;
}

static int is_convex(const gp_vec2 *p, size_t n)
{
    int sign = 0;
    for (size_t k = 0; k < n; k++) {
        gp_vec2 a = p[k], b = p[(k + 1) % n], c = p[(k + 2) % n];
        double cr = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
        if (cr > 0.0) {
            if (sign < 0) return 0;
            sign = 1;
        } else if (cr < 0.0) {
            if (sign > 0) return 0;
            sign = -1;
        }
    }
    return 1;
}

gp_status gp_fill_cell(gp_fill_workspace *ws, const gp_vec2 *cell, size_t ncell,
                       const double *phases, gp_vec2 *contour, gp_fill_result *res,
                       gp_error *err)
{
    if (!ws || !cell || !phases || !contour || !res)
        return gp_error_set(err, GP_ERR_INVALID, "fill: NULL argument");
    if (ncell < 3)
        return gp_error_set(err, GP_ERR_INVALID, "fill: a cell needs >= 3 vertices, got %zu", ncell);
    memset(res, 0, sizeof *res);
    double area = gp_poly_area(cell, ncell);
    if (!(area > 0.0) || !isfinite(area))
        return gp_error_set(err, GP_ERR_DEGENERATE, "fill: cell has no area");
    res->cell_area = area;

    /* Centre: the centroid of a convex cell (it balances the cell's DFT); the pole of
     * inaccessibility otherwise, which is inside and as far from the boundary as possible,
     * so that every ray sees a long stretch of the cell. */
    gp_vec2 origin;
    if (!(is_convex(cell, ncell) && gp_poly_centroid(cell, ncell, &origin, NULL) == GP_OK &&
          gp_poly_contains(cell, ncell, origin))) {
        double rin;
        gp_status st = gp_max_inscribed_circle(cell, ncell, 0.0, &origin, &rin, err);
        if (st != GP_OK)
            return st;
    }

    /* Local coordinates: x' = (x - origin) / L with L = sqrt(area), rounded to a 2^-40 grid.
     * The rounding (1e-12 of the cell size) makes the same cell seen at another scale or
     * offset give the same bits here, hence the same simplex path and the same grain; the
     * final containment check is made against the true cell, so it costs no safety. */
    if (ncell > ws->cell_cap) {
        gp_vec2 *grown = realloc(ws->cell, ncell * sizeof *grown);
        if (!grown)
            return gp_error_set(err, GP_ERR_NOMEM, "fill: out of memory");
        ws->cell = grown;
        ws->cell_cap = ncell;
    }
    double L = sqrt(area);
    for (size_t k = 0; k < ncell; k++) {
        ws->cell[k].x = ldexp(nearbyint(ldexp((cell[k].x - origin.x) / L, 40)), -40);
        ws->cell[k].y = ldexp(nearbyint(ldexp((cell[k].y - origin.y) / L, 40)), -40);
    }
    ws->ncell = ncell;
    ws->cell_area = gp_poly_area(ws->cell, ncell);
    /* checked on the rounded cell, the one the rays are cast in; its positive area (the
     * cell's, checked above) makes it counter-clockwise */
    ws->convex = is_convex(ws->cell, ncell);
    ws->evals = 0;
    gp_vec2 c = {0.0, 0.0};
    if (cast_rays(ws, c) != 0)
        return gp_error_set(err, GP_ERR_DEGENERATE, "fill: no interior centre found for the cell");

    /* Fixed part of the shape factor: the modes that are not optimised. */
    size_t np = ws->np;
    for (size_t i = 0; i < np; i++)
        ws->base[i] = 1.0;
    for (size_t n = 1; n < ws->nm; n++) {
        if ((n >= FIRST_OPT && n <= LAST_OPT) || ws->p.D[n] == 0.0)
            continue;
        double ca = ws->p.D[n] * cos(phases[n]), sa = ws->p.D[n] * sin(phases[n]);
        for (size_t i = 0; i < np; i++)
            ws->base[i] += ca * ws->cosn[n * np + i] + sa * ws->sinn[n * np + i];
    }

    /* Start from the phases of the DFT of the cell contour seen from c (Sect. 4.1):
     * r(theta) ~ sum A_n cos(n theta) + B_n sin(n theta) = |.| cos(n theta - atan2(B, A)). */
    double ph[NOPT];
    for (int j = 0; j < NOPT; j++) {
        size_t n = FIRST_OPT + (size_t)j;
        double a = 0.0, b = 0.0;
        for (size_t i = 0; i < np; i++) {
            a += ws->rmax[i] * ws->cosn[n * np + i];
            b += ws->rmax[i] * ws->sinn[n * np + i];
        }
        ph[j] = (a == 0.0 && b == 0.0) ? phases[n] : atan2(b, a);
    }

    double target = ws->p.solid_fraction;
    gsl_multimin_function f6 = {objective6, NOPT, ws};
    for (int j = 0; j < NOPT; j++) {
        gsl_vector_set(ws->x6, (size_t)j, ph[j]);
        gsl_vector_set(ws->step6, (size_t)j, 0.6);
    }
    double best = maximise(ws, ws->nm6, &f6, ws->x6, ws->step6, target);
    for (int j = 0; j < NOPT; j++)
        ph[j] = gsl_vector_get(ws->x6, (size_t)j);

    /* Stage 2: phases and centre together, restarted from the best point while it still
     * improves (a fresh simplex escapes the collapse Nelder-Mead suffers in narrow valleys). */
    for (int round = 0; round <= FILL_RESTARTS && best < target && ws->p.optimise_centre; round++) {
        gsl_multimin_function f8 = {objective8, NOPT + 2, ws};
        for (int j = 0; j < NOPT; j++) {
            gsl_vector_set(ws->x8, (size_t)j, ph[j]);
            gsl_vector_set(ws->step8, (size_t)j, 0.3);
        }
        gsl_vector_set(ws->x8, NOPT, c.x);
        gsl_vector_set(ws->x8, NOPT + 1, c.y);
        gsl_vector_set(ws->step8, NOPT, 0.05);
        gsl_vector_set(ws->step8, NOPT + 1, 0.05);
        double b8 = maximise(ws, ws->nm8, &f8, ws->x8, ws->step8, target);
        if (!(b8 > best * (1.0 + 1e-4)))
            break;
        best = b8;
        for (int j = 0; j < NOPT; j++)
            ph[j] = gsl_vector_get(ws->x8, (size_t)j);
        c.x = gsl_vector_get(ws->x8, NOPT);
        c.y = gsl_vector_get(ws->x8, NOPT + 1);
    }

    /* Rebuild the state of the chosen point (the simplex may have evaluated others last). */
    if (cast_rays(ws, c) != 0)
        return gp_error_set(err, GP_ERR_INTERNAL, "fill: chosen centre left the cell");
    if (!(shape_factor(ws, ph) > 0.0))
        return gp_error_set(err, GP_ERR_NOT_STAR,
                            "fill: the spectrum gives r <= 0 (not star-shaped) for every phase tried");
    double a1 = unit_area(ws);
    double r0 = r0_limit(ws);
    double r0_target = sqrt(target * ws->cell_area / a1);
    if (r0_target < r0)
        r0 = r0_target;

    /* Back to world coordinates; check exact containment there, shrinking if needed. */
    gp_vec2 cw = {origin.x + L * c.x, origin.y + L * c.y};
    const double *cs = ws->cosn + np, *sn = ws->sinn + np;
    for (int shrink = 0;; shrink++) {
        double rw = L * r0;
        for (size_t i = 0; i < np; i++) {
            double r = rw * ws->rho[i];
            contour[i].x = cw.x + r * cs[i];
            contour[i].y = cw.y + r * sn[i];
        }
        if (gp_poly_inside_poly(contour, np, cell, ncell))
            break;
        if (shrink == 400)
            return gp_error_set(err, GP_ERR_INTERNAL,
                                "fill: grain does not fit its cell even after shrinking");
        r0 *= 0.99;
        res->shrinks = shrink + 1;
    }

    res->centre = cw;
    res->r0 = L * r0;
    for (size_t n = 0; n < 8; n++)
        res->phases[n] = n < ws->nm ? phases[n] : 0.0;
    for (int j = 0; j < NOPT; j++)
        res->phases[FIRST_OPT + j] = ph[j];
    res->area = gp_poly_area(contour, np);
    res->fraction = res->area / area;
    res->max_fraction = best;
    res->target_met = res->fraction >= target * (1.0 - 1e-9);
    res->evals = ws->evals;
    return GP_OK;
}
