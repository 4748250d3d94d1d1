/* gp_shapemap.c -- target descriptors -> (D2, D3, D8): the table map, its fit, the nearest
 * reachable target and the sampled refinement (gp_shapemap.h says why each step is so). */
#include "gp_shapemap.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_multimin.h>

#include "gp_shapemap_table.h"

#define N2 GP_SHAPEMAP_TABLE_N2
#define N3 GP_SHAPEMAP_TABLE_N3
#define N8 GP_SHAPEMAP_TABLE_N8
#define ND GP_SHAPEMAP_NDESC

/* Outside the box: the objective at the nearest box point plus this times the squared
 * (scaled) distance, so that Nelder-Mead is pulled back continuously. */
#define BOX_PENALTY 1e4
/* In a cell with an unusable (not star-shaped) node: a plateau Nelder-Mead contracts away
 * from (its simplex starts in usable cells and only accepts improvements). */
#define UNUSABLE 1e9
/* Weight on descriptors held at their goals while the nearest value of another is sought. */
#define HOLD 1e4
#define NM_MAX_ITER 600
#define NM_SIZE_TOL 1e-7
#define NSTART 3

static const double *const AXES[3] = {gp_shapemap_table_d2, gp_shapemap_table_d3,
                                      gp_shapemap_table_d8};
static const size_t NAX[3] = {N2, N3, N8};
/* the paper's / the API's typical spectrum (gp_spec2d_defaults): where free parameters go */
static const double TYPICAL[3] = {0.1, 0.05, 0.02};
/* relative pull toward TYPICAL per axis: weak on D2, so that when elongation is asked D2 takes
 * it and D3, D8 stay at their typical values rather than sharing the elongation with D2 */
static const double PULL[3] = {0.01, 1.0, 1.0};
/* the paper's order of scales: elongation (D2), circularity (D3), roundness, regularity (D8) */
static const int PRIORITY[ND] = {GP_SHAPEMAP_ELONGATION, GP_SHAPEMAP_CIRCULARITY,
                                 GP_SHAPEMAP_ROUNDNESS, GP_SHAPEMAP_REGULARITY};
static const double TOL[ND] = {GP_SHAPEMAP_TOL_ELONGATION, GP_SHAPEMAP_TOL_ROUNDNESS,
                               GP_SHAPEMAP_TOL_CIRCULARITY, GP_SHAPEMAP_TOL_REGULARITY};
static const char *const NAMES[ND] = {"elongation", "roundness", "circularity", "regularity"};
static const double VMAX[ND] = {1.0, 1.0, 1.0, 5.0}; /* GP_SHAPE_REGULARITY_CAP */

const char *gp_shapemap_name(int k)
{
    return k >= 0 && k < ND ? NAMES[k] : NULL;
}

double gp_shapemap_tolerance(int k)
{
    return k >= 0 && k < ND ? TOL[k] : NAN;
}

/* ------------------------------------------------------------------ the table map */

static const float *row(size_t i, size_t j, size_t k)
{
    return gp_shapemap_table_rows[(i * N3 + j) * N8 + k];
}

static int usable(size_t i, size_t j, size_t k)
{
    /* the table prints the fraction to 4 decimals: compare with that slack */
    return row(i, j, k)[8] >= GP_SHAPEMAP_STAR_MIN - 1e-6;
}

static double range(int a)
{
    return AXES[a][NAX[a] - 1];
}

/* Cell index c (0 .. n-2) with ax[c] <= x <= ax[c+1] and the fraction of x in it; x is
 * inside [ax[0], ax[n-1]]. */
static size_t locate(const double *ax, size_t n, double x, double *frac)
{
    size_t lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (ax[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    *frac = (x - ax[lo]) / (ax[lo + 1] - ax[lo]);
    return lo;
}

/* Trilinear means and sds at p (inside the box); 0 if a node of the cell is unusable. */
static int interp(const double p[3], double *mean, double *sd)
{
    size_t c[3];
    double f[3];
    for (int a = 0; a < 3; a++)
        c[a] = locate(AXES[a], NAX[a], p[a], &f[a]);
    double acc[2 * ND] = {0};
    for (int corner = 0; corner < 8; corner++) {
        size_t i = c[0] + (corner & 1), j = c[1] + ((corner >> 1) & 1), k = c[2] + (corner >> 2);
        double w = ((corner & 1) ? f[0] : 1 - f[0]) * (((corner >> 1) & 1) ? f[1] : 1 - f[1]) *
                   ((corner >> 2) ? f[2] : 1 - f[2]);
        if (w == 0.0)
            continue; /* on a face of the cell: its far nodes do not matter */
        if (!usable(i, j, k))
            return 0;
        const float *r = row(i, j, k);
        for (int d = 0; d < 2 * ND; d++)
            acc[d] += w * (double)r[d];
    }
    for (int d = 0; d < ND; d++) {
        if (mean)
            mean[d] = acc[d];
        if (sd)
            sd[d] = acc[ND + d];
    }
    return 1;
}

void gp_shapemap_table(gp_shapemap_table_info *info)
{
    info->n2 = N2;
    info->n3 = N3;
    info->n8 = N8;
    info->d2 = gp_shapemap_table_d2;
    info->d3 = gp_shapemap_table_d3;
    info->d8 = gp_shapemap_table_d8;
    info->contour_points = GP_SHAPEMAP_TABLE_NP;
    info->ngrains = GP_SHAPEMAP_TABLE_NGRAINS;
    info->seed = GP_SHAPEMAP_TABLE_SEED;
    info->alpha = GP_SHAPEMAP_ALPHA;
    info->beta = GP_SHAPEMAP_BETA;
}

gp_status gp_shapemap_table_node(size_t i, size_t j, size_t k, gp_shapemap_node *out,
                                 gp_error *err)
{
    if (i >= N2 || j >= N3 || k >= N8 || !out)
        return gp_error_set(err, GP_ERR_INVALID, "table node (%zu, %zu, %zu) out of range", i, j,
                            k);
    const float *r = row(i, j, k);
    out->D2 = gp_shapemap_table_d2[i];
    out->D3 = gp_shapemap_table_d3[j];
    out->D8 = gp_shapemap_table_d8[k];
    for (int d = 0; d < ND; d++) {
        out->mean[d] = r[d];
        out->sd[d] = r[ND + d];
    }
    out->star_fraction = r[8];
    return GP_OK;
}

gp_status gp_shapemap_predict(double D2, double D3, double D8, double *mean, double *sd,
                              gp_error *err)
{
    double p[3] = {D2, D3, D8};
    for (int a = 0; a < 3; a++)
        if (!(p[a] >= 0.0 && p[a] <= range(a)))
            return gp_error_set(err, GP_ERR_INFEASIBLE,
                                "D%d = %g is outside the table's [0, %g]", a == 0 ? 2 : a == 1 ? 3 : 8,
                                p[a], range(a));
    if (!interp(p, mean, sd))
        return gp_error_set(err, GP_ERR_INFEASIBLE,
                            "D2 %g, D3 %g, D8 %g: too few star-shaped grains in the table", D2,
                            D3, D8);
    return GP_OK;
}

/* ------------------------------------------------------------------ the table fit */

/* Weighted goals: w[k] = 0 for descriptors not used. */
typedef struct problem {
    double goal[ND], w[ND];
} problem;

/* The scaled error e = (m - goal) / tol enters as e^2 + e^8: least squares inside the
 * tolerance, and beyond it a steep wall, so that with four goals and three parameters the
 * fit spreads the misses (near minimax) rather than leaving one just outside. */
static double misfit(const problem *pr, const double *m)
{
    double s = 0.0;
    for (int k = 0; k < ND; k++) {
        if (pr->w[k] == 0.0)
            continue;
        double e = (m[k] - pr->goal[k]) / TOL[k], e2 = e * e, e4 = e2 * e2;
        s += pr->w[k] * (e2 + e4 * e4);
    }
    return s;
}

/* Objective of the scaled point x (x_a = D_a / range_a); see gp_shapemap.h. */
static double objective(const gsl_vector *x, void *params)
{
    const problem *pr = params;
    double p[3], out = 0.0, m[ND];
    for (int a = 0; a < 3; a++) {
        double xa = gsl_vector_get(x, (size_t)a), c = xa < 0.0 ? 0.0 : xa > 1.0 ? 1.0 : xa;
        out += BOX_PENALTY * (xa - c) * (xa - c);
        p[a] = c * range(a);
        double r = (p[a] - TYPICAL[a]) / range(a);
        out += GP_SHAPEMAP_LAMBDA * PULL[a] * r * r;
    }
    if (!interp(p, m, NULL))
        return out + UNUSABLE;
    return out + misfit(pr, m);
}

typedef struct nm_work {
    gsl_multimin_fminimizer *m;
    gsl_vector *x, *step;
} nm_work;

static void nm_free(nm_work *w)
{
    if (w->m)
        gsl_multimin_fminimizer_free(w->m);
    gsl_vector_free(w->x);
    gsl_vector_free(w->step);
}

static gp_status nm_alloc(nm_work *w, gp_error *err)
{
    w->m = gsl_multimin_fminimizer_alloc(gsl_multimin_fminimizer_nmsimplex2, 3);
    w->x = gsl_vector_alloc(3);
    w->step = gsl_vector_alloc(3);
    if (!w->m || !w->x || !w->step) {
        nm_free(w);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    return GP_OK;
}

/* Initial simplex step along each axis: half the grid cell around p (the grid is finer where
 * the map is steeper, so this is the scale the map changes on). */
static void local_step(const double *p, double *step)
{
    for (int a = 0; a < 3; a++) {
        double f;
        size_t c = locate(AXES[a], NAX[a], p[a], &f);
        step[a] = 0.5 * (AXES[a][c + 1] - AXES[a][c]) / range(a);
    }
}

/* Nelder-Mead from p (in the box) to *p; returns the objective there. Restarted once from its
 * own result, because a collapsed simplex can stop short on the map's cell edges. */
static double nm_run(nm_work *w, gsl_multimin_function *fn, double *p)
{
    double fbest = HUGE_VAL;
    for (int round = 0; round < 2; round++) {
        double step[3];
        local_step(p, step);
        for (int a = 0; a < 3; a++) {
            gsl_vector_set(w->x, (size_t)a, p[a] / range(a));
            gsl_vector_set(w->step, (size_t)a, step[a]);
        }
        gsl_multimin_fminimizer_set(w->m, fn, w->x, w->step);
        for (int it = 0; it < NM_MAX_ITER; it++) {
            if (gsl_multimin_fminimizer_iterate(w->m) != GSL_SUCCESS)
                break;
            if (gsl_multimin_test_size(gsl_multimin_fminimizer_size(w->m), NM_SIZE_TOL) ==
                GSL_SUCCESS)
                break;
        }
        if (!(w->m->fval < fbest))
            break;
        fbest = w->m->fval;
        for (int a = 0; a < 3; a++) {
            double xa = gsl_vector_get(w->m->x, (size_t)a);
            p[a] = (xa < 0.0 ? 0.0 : xa > 1.0 ? 1.0 : xa) * range(a);
        }
    }
    return fbest;
}

/* The NSTART usable nodes of lowest objective, best first, into starts[][3]; returns how many. */
static int scan_nodes(gsl_multimin_function *fn, double starts[NSTART][3])
{
    double fs[NSTART];
    int n = 0;
    gsl_vector_view xv;
    double x[3];
    xv = gsl_vector_view_array(x, 3);
    for (size_t i = 0; i < N2; i++)
        for (size_t j = 0; j < N3; j++)
            for (size_t k = 0; k < N8; k++) {
                double p[3] = {AXES[0][i], AXES[1][j], AXES[2][k]};
                for (int a = 0; a < 3; a++)
                    x[a] = p[a] / range(a);
                double f = fn->f(&xv.vector, fn->params);
                if (f >= UNUSABLE)
                    continue;
                int at = n < NSTART ? n : NSTART; /* insertion into the sorted best list */
                while (at > 0 && fs[at - 1] > f) {
                    if (at < NSTART) {
                        fs[at] = fs[at - 1];
                        memcpy(starts[at], starts[at - 1], sizeof starts[0]);
                    }
                    at--;
                }
                if (at < NSTART) {
                    fs[at] = f;
                    memcpy(starts[at], p, sizeof p);
                    n += n < NSTART;
                }
            }
    return n;
}

/* Global table fit: the best nodes, and `also` if not NULL, each polished by Nelder-Mead; the
 * best result in p. */
static double table_fit(nm_work *w, gsl_multimin_function *fn, const double *also, double *p)
{
    double starts[NSTART + 1][3], fbest = HUGE_VAL;
    int n = scan_nodes(fn, starts);
    memcpy(p, TYPICAL, sizeof TYPICAL); /* defined even if nothing is usable (never so) */
    if (also)
        memcpy(starts[n++], also, sizeof starts[0]);
    for (int s = 0; s < n; s++) {
        double q[3] = {starts[s][0], starts[s][1], starts[s][2]};
        double f = nm_run(w, fn, q);
        if (f < fbest) {
            fbest = f;
            memcpy(p, q, sizeof q);
        }
    }
    return fbest;
}

/* ------------------------------------------------------------------ check and nearest */

static gp_status validate(const gp_shapemap_target *t, gp_error *err)
{
    if (!t || t->given == 0 || (t->given & ~GP_SHAPEMAP_ALL))
        return gp_error_set(err, GP_ERR_INVALID,
                            "descriptors: give at least one of elongation, roundness, "
                            "circularity, regularity");
    for (int k = 0; k < ND; k++) {
        double v = t->value[k];
        if ((t->given & GP_SHAPEMAP_BIT(k)) && !(v > 0.0 && v <= VMAX[k]))
            return gp_error_set(err, GP_ERR_INVALID, "%s must be in (0, %g]", NAMES[k], VMAX[k]);
    }
    return GP_OK;
}

static void problem_of(const gp_shapemap_target *t, problem *pr)
{
    memset(pr, 0, sizeof *pr);
    for (int k = 0; k < ND; k++)
        if (t->given & GP_SHAPEMAP_BIT(k)) {
            pr->goal[k] = t->value[k];
            pr->w[k] = 1.0;
        }
}

/* Goals of pr (w > 0) that m misses by more than the tolerance. */
static unsigned missed_of(const problem *pr, const double *m)
{
    unsigned missed = 0;
    for (int k = 0; k < ND; k++)
        if (pr->w[k] > 0.0 && fabs(m[k] - pr->goal[k]) > TOL[k])
            missed |= GP_SHAPEMAP_BIT(k);
    return missed;
}

typedef struct hold_problem {
    problem base;
    unsigned held;
} hold_problem;

/* Pure least squares on the goals, those in `held` weighted HOLD: the closest the map gets to
 * the others while keeping those (no e^8 wall here: a far goal's wall would push the held
 * ones out of their tolerance). */
static double hold_objective(const gsl_vector *x, void *params)
{
    const hold_problem *h = params;
    problem none;
    memset(&none, 0, sizeof none);
    double f = objective(x, &none), m[ND], p[3];
    if (f >= UNUSABLE)
        return f;
    for (int a = 0; a < 3; a++) {
        double xa = gsl_vector_get(x, (size_t)a);
        p[a] = (xa < 0.0 ? 0.0 : xa > 1.0 ? 1.0 : xa) * range(a);
    }
    interp(p, m, NULL);
    for (int k = 0; k < ND; k++) {
        double e = (m[k] - h->base.goal[k]) / TOL[k];
        f += h->base.w[k] * ((h->held & GP_SHAPEMAP_BIT(k)) ? HOLD : 1.0) * e * e;
    }
    return f;
}

/* Table fit of pr into p (also: an extra start, may be NULL); the map's means there in m. */
static void fit_goals(nm_work *w, const problem *pr, const double *also, double *p, double *m)
{
    gsl_multimin_function fn = {objective, 3, (void *)pr};
    table_fit(w, &fn, also, p);
    interp(p, m, NULL);
}

/* The nearest reachable target, in the paper's order of scales (gp_shapemap.h): goal[] holds
 * the target on entry and the nearest reachable values on return; p the spectrum of those.
 * Returns the descriptors whose value had to change. */
static unsigned nearest(nm_work *w, unsigned given, double *goal, double *p)
{
    problem pr;
    memset(&pr, 0, sizeof pr);
    unsigned missed = 0, kept = 0;
    double m[ND];
    for (int q = 0; q < ND; q++) {
        int k = PRIORITY[q];
        if (!(given & GP_SHAPEMAP_BIT(k)))
            continue;
        pr.goal[k] = goal[k];
        pr.w[k] = 1.0;
        fit_goals(w, &pr, NULL, p, m);
        if (missed_of(&pr, m)) {
            hold_problem h = {pr, kept};
            gsl_multimin_function fn = {hold_objective, 3, &h};
            table_fit(w, &fn, p, p);
            interp(p, m, NULL);
            goal[k] = pr.goal[k] = m[k];
            missed |= GP_SHAPEMAP_BIT(k);
        }
        kept |= GP_SHAPEMAP_BIT(k);
    }
    double held[3] = {p[0], p[1], p[2]};
    fit_goals(w, &pr, held, p, m); /* the spectrum of the nearest target, all goals at once */
    return missed;
}

/* appends printf-style text to buf (size n), truncating */
static void append(char *buf, size_t n, const char *fmt, const char *name, double v)
{
    size_t len = strlen(buf);
    if (len + 1 < n)
        snprintf(buf + len, n - len, fmt, len ? ", " : "", name, v);
}

/* "circularity 0.99 is not reachable by star-shaped Fourier grains with elongation 0.4:
 * nearest reachable circularity 0.634" */
static gp_status refuse(const gp_shapemap_result *r, gp_error *err)
{
    char what[80] = "", with[80] = "", near[80] = "";
    int nmiss = 0;
    for (int q = 0; q < ND; q++) {
        int k = PRIORITY[q];
        if (!(r->given & GP_SHAPEMAP_BIT(k)))
            continue;
        if (r->missed & GP_SHAPEMAP_BIT(k)) {
            append(what, sizeof what, "%s%s %g", NAMES[k], r->target[k]);
            append(near, sizeof near, "%s%s %.3f", NAMES[k], r->nearest[k]);
            nmiss++;
        } else {
            append(with, sizeof with, "%s%s %g", NAMES[k], r->target[k]);
        }
    }
    return gp_error_set(err, GP_ERR_INFEASIBLE,
                        "%s %s not reachable by star-shaped Fourier grains%s%s: nearest "
                        "reachable %s",
                        what, nmiss > 1 ? "are" : "is", with[0] ? " with " : "", with, near);
}

static void result_init(gp_shapemap_result *r, const gp_shapemap_target *t)
{
    memset(r, 0, sizeof *r);
    r->alpha = GP_SHAPEMAP_ALPHA;
    r->beta = GP_SHAPEMAP_BETA;
    r->given = t->given;
    for (int k = 0; k < ND; k++)
        r->target[k] = r->nearest[k] = (t->given & GP_SHAPEMAP_BIT(k)) ? t->value[k] : 0.0;
}

static void result_spectrum(gp_shapemap_result *r, const double *p)
{
    r->D2 = p[0];
    r->D3 = p[1];
    r->D8 = p[2];
}

/* The table part of check: fit, and when it misses, the nearest reachable target. */
static void check_table(nm_work *w, const gp_shapemap_target *t, gp_shapemap_result *r)
{
    problem pr;
    problem_of(t, &pr);
    double p[3], m[ND];
    fit_goals(w, &pr, NULL, p, m);
    r->missed = missed_of(&pr, m);
    if (r->missed) {
        double goal[ND];
        memcpy(goal, pr.goal, sizeof goal);
        r->missed = nearest(w, t->given, goal, p);
        for (int k = 0; k < ND; k++)
            if (r->missed & GP_SHAPEMAP_BIT(k))
                r->nearest[k] = goal[k];
    }
    result_spectrum(r, p);
    interp(p, r->mean, r->sd);
    r->ngrains = GP_SHAPEMAP_TABLE_NGRAINS;
}

gp_status gp_shapemap_check(const gp_shapemap_target *t, gp_shapemap_result *out,
                            gp_error *err)
{
    gp_status st = validate(t, err);
    if (st != GP_OK)
        return st;
    nm_work w = {0};
    if ((st = nm_alloc(&w, err)) != GP_OK)
        return st;
    gp_shapemap_result r;
    result_init(&r, t);
    check_table(&w, t, &r);
    nm_free(&w);
    if (out)
        *out = r;
    if (r.missed)
        return refuse(&r, err);
    gp_error_clear(err);
    return GP_OK;
}

/* ------------------------------------------------------------------ sampled refinement */

void gp_shapemap_params_defaults(gp_shapemap_params *p)
{
    p->contour_points = 128;
    p->ngrains = 256;
    p->seed = 1;
    p->max_evals = 6;
}

/* Whether the sample's means are good enough to stop: each goal within
 * GP_SHAPEMAP_REFINE_FRACTION of its tolerance, or, where the table fit itself misses it by
 * allowed[k] tolerances (four goals, three parameters), within allowed[k] + that fraction and
 * still inside REFINE_CAP of the tolerance. */
#define REFINE_CAP 0.8
static int refine_done(const problem *pr, const double *mean, const double *allowed)
{
    for (int k = 0; k < ND; k++) {
        if (pr->w[k] == 0.0)
            continue;
        double e = fabs(mean[k] - pr->goal[k]) / TOL[k];
        if (e > GP_SHAPEMAP_REFINE_FRACTION &&
            (e > allowed[k] + GP_SHAPEMAP_REFINE_FRACTION || e > REFINE_CAP))
            return 0;
    }
    return 1;
}

typedef struct refine_state {
    double p[3], best_p[3], best_misfit;
    double allowed[ND];
    gp_shapemap_stats best;
    int have;
} refine_state;

/* One sampled evaluation at rs->p; then the next p: defect correction from an improvement, or
 * halfway back to the best after a step that made things worse. Returns 1 to go on. */
static int refine_step(nm_work *w, gp_shapemap_sampler *s, const problem *pr, refine_state *rs,
                       gp_status *st, gp_error *err)
{
    gp_shapemap_stats now;
    *st = gp_shapemap_sampler_measure(s, rs->p[0], rs->p[1], rs->p[2], GP_SHAPEMAP_ALPHA,
                                      GP_SHAPEMAP_BETA, &now, err);
    if (*st != GP_OK)
        return 0;
    double f = misfit(pr, now.mean);
    if (rs->have && !(f < rs->best_misfit)) {
        for (int a = 0; a < 3; a++)
            rs->p[a] = 0.5 * (rs->p[a] + rs->best_p[a]);
        return 1;
    }
    rs->have = 1;
    rs->best_misfit = f;
    rs->best = now;
    memcpy(rs->best_p, rs->p, sizeof rs->p);
    if (refine_done(pr, now.mean, rs->allowed))
        return 0;
    double m[ND];
    interp(rs->p, m, NULL);
    problem shifted = *pr; /* the table plus the sample's offset at p, fitted from p */
    for (int k = 0; k < ND; k++)
        shifted.goal[k] -= now.mean[k] - m[k];
    gsl_multimin_function fn = {objective, 3, &shifted};
    nm_run(w, &fn, rs->p);
    return 1;
}

static gp_status refine(nm_work *w, gp_shapemap_sampler *s, const gp_shapemap_target *t,
                        int max_evals, gp_shapemap_result *r, gp_error *err)
{
    problem pr;
    problem_of(t, &pr);
    refine_state rs = {.p = {r->D2, r->D3, r->D8}, .best_misfit = HUGE_VAL};
    for (int k = 0; k < ND; k++) /* r->mean: the table's prediction at the table fit */
        rs.allowed[k] = pr.w[k] > 0.0 ? fabs(r->mean[k] - pr.goal[k]) / TOL[k] : 0.0;
    gp_status st = GP_OK;
    for (int e = 0; e < max_evals; e++) {
        r->evaluations++;
        if (!refine_step(w, s, &pr, &rs, &st, err))
            break;
    }
    if (!rs.have)
        return st != GP_OK ? st : gp_error_set(err, GP_ERR_INTERNAL, "refinement: no evaluation");
    result_spectrum(r, rs.best_p);
    memcpy(r->mean, rs.best.mean, sizeof r->mean);
    memcpy(r->sd, rs.best.sd, sizeof r->sd);
    r->ngrains = rs.best.ngrains;
    r->missed = missed_of(&pr, r->mean);
    gp_error_clear(err);
    return GP_OK;
}

gp_status gp_shapemap_fit(const gp_shapemap_target *t, const gp_shapemap_params *params,
                          gp_shapemap_result *out, gp_error *err)
{
    gp_shapemap_params p;
    if (params)
        p = *params;
    else
        gp_shapemap_params_defaults(&p);
    if (p.max_evals < 1)
        return gp_error_set(err, GP_ERR_INVALID, "max_evals must be >= 1");
    gp_shapemap_result r;
    gp_status st = gp_shapemap_check(t, &r, err);
    if (st != GP_OK) {
        if (out && st == GP_ERR_INFEASIBLE)
            *out = r;
        return st;
    }
    gp_error e;
    gp_shapemap_sampler *s = gp_shapemap_sampler_create(p.contour_points, p.ngrains, p.seed, &e);
    if (!s)
        return gp_error_set(err, e.code, "%s", e.message);
    nm_work w = {0};
    st = nm_alloc(&w, err);
    if (st == GP_OK)
        st = refine(&w, s, t, p.max_evals, &r, err);
    nm_free(&w);
    gp_shapemap_sampler_destroy(s);
    if (st == GP_OK && out)
        *out = r;
    return st;
}
