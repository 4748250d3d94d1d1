/* gp_fill3d.c -- one grain in one convex cell: the scale LP, the aligned rotation and its
 * hill climb, the centred placement (gp_fill3d.h). */
#include "gp_fill3d.h"

#include <float.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LP_EPS 1e-12     /* pivot and reduced-cost tolerance on O(1) numbers */
#define CLIMB_PATIENCE 6 /* failed tries before the turn is halved */
#define SCALE_SAFETY (1.0 - 1e-9)

void gp_fill3d_params_defaults(gp_fill3d_params *p)
{
    p->solid_fraction = 0.55;
    p->rotations = 24;
    p->turn = 0.35;
    p->margin = 1e-9;
    p->rotation = NULL;
}

/* ------------------------------------------------------------------------------ the LP */

typedef struct tableau {
    size_t m, w;    /* rows, columns (4 free variables, then m slacks) */
    double *t;      /* m x w */
    double *rhs;    /* m */
    double *obj;    /* w: reduced costs of "z - x3 = 0"; a column improves when < 0 */
    size_t *basis;  /* m: the basic variable of each row */
    int sign[4];    /* a free variable's column negated (it is decreased) */
} tableau;

static void pivot(tableau *T, size_t r, size_t j)
{
    double *row = T->t + r * T->w, p = row[j];
    for (size_t c = 0; c < T->w; c++) row[c] /= p;
    T->rhs[r] /= p;
    for (size_t k = 0; k < T->m; k++) {
        double f = T->t[k * T->w + j];
        if (k == r || f == 0.0) continue;
        double *o = T->t + k * T->w;
        for (size_t c = 0; c < T->w; c++) o[c] -= f * row[c];
        T->rhs[k] -= f * T->rhs[r];
        if (T->rhs[k] < 0.0 && T->rhs[k] > -LP_EPS) T->rhs[k] = 0.0;
    }
    double f = T->obj[j];
    for (size_t c = 0; c < T->w; c++) T->obj[c] -= f * row[c];
    T->basis[r] = j;
}

static void negate_column(tableau *T, size_t j)
{
    for (size_t k = 0; k < T->m; k++) T->t[k * T->w + j] = -T->t[k * T->w + j];
    T->obj[j] = -T->obj[j];
    T->sign[j] = -T->sign[j];
}

/* Bland's entering column: the lowest-numbered nonbasic variable that improves (a free one
 * improving when decreased is negated first); w when optimal */
static size_t entering(tableau *T, const char *is_basic)
{
    for (size_t j = 0; j < T->w; j++) {
        if (is_basic[j]) continue;
        if (j < 4 && T->obj[j] > LP_EPS) negate_column(T, j);
        if (T->obj[j] < -LP_EPS) return j;
    }
    return T->w;
}

/* the leaving row: least ratio over rows whose basic variable is a slack (free variables are
 * unbounded and never leave), ties to the lowest basic variable; m when unbounded */
static size_t leaving(const tableau *T, size_t j)
{
    size_t r = T->m;
    double best = INFINITY;
    for (size_t k = 0; k < T->m; k++) {
        double a = T->t[k * T->w + j];
        if (T->basis[k] < 4 || a <= LP_EPS) continue;
        double q = T->rhs[k] / a;
        if (q < best || (q == best && r < T->m && T->basis[k] < T->basis[r])) {
            best = q;
            r = k;
        }
    }
    return r;
}

static int solve(tableau *T, char *is_basic)
{
    size_t budget = 50 * (T->m + 4);
    for (size_t it = 0; it < budget; it++) {
        size_t j = entering(T, is_basic);
        if (j == T->w) return 0;
        size_t r = leaving(T, j);
        if (r == T->m) return 1;
        is_basic[T->basis[r]] = 0;
        is_basic[j] = 1;
        pivot(T, r, j);
    }
    return -1;
}

int gp_fill3d_lp(const double *a, const double *b, size_t m, double x[4])
{
    tableau T = {m, 4 + m, NULL, NULL, NULL, NULL, {1, 1, 1, 1}};
    T.t = calloc(m * T.w, sizeof *T.t);
    T.rhs = malloc(m * sizeof *T.rhs);
    T.obj = calloc(T.w, sizeof *T.obj);
    T.basis = malloc(m * sizeof *T.basis);
    char *is_basic = calloc(T.w, 1);
    int rc = -1;
    if (m == 0 || !T.t || !T.rhs || !T.obj || !T.basis || !is_basic) goto out;
    for (size_t k = 0; k < m; k++) {
        memcpy(T.t + k * T.w, a + 4 * k, 4 * sizeof(double));
        T.t[k * T.w + 4 + k] = 1.0;
        T.rhs[k] = b[k] > 0.0 ? b[k] : 0.0;
        T.basis[k] = 4 + k;
        is_basic[4 + k] = 1;
    }
    T.obj[3] = -1.0;
    rc = solve(&T, is_basic);
    if (rc == 0) {
        memset(x, 0, 4 * sizeof(double));
        for (size_t k = 0; k < m; k++)
            if (T.basis[k] < 4) x[T.basis[k]] = T.sign[T.basis[k]] * T.rhs[k];
    }
out:
    free(T.t);
    free(T.rhs);
    free(T.obj);
    free(T.basis);
    free(is_basic);
    return rc;
}

/* ----------------------------------------------------------------------- the geometry */

/* the cell in local units: unit normals, offsets from the interior point over the size L */
typedef struct local_cell {
    size_t nf;
    double *n;    /* 3 nf */
    double *d;    /* nf, > 0 */
    double L;
    double q[3];
    double slack; /* the clearance kept: the caller's margin plus the rounding of absolute
                   * coordinates of size |q| against the cell's size */
} local_cell;

/* the eigenvectors of a symmetric tensor as the columns of E, least eigenvalue first */
static int axes_of(const double I[9], double E[9])
{
    double a[9];
    memcpy(a, I, sizeof a);
    gsl_matrix_view A = gsl_matrix_view_array(a, 3, 3);
    gsl_vector *ev = gsl_vector_alloc(3);
    gsl_matrix *V = gsl_matrix_alloc(3, 3);
    gsl_eigen_symmv_workspace *w = gsl_eigen_symmv_alloc(3);
    int ok = ev && V && w;
    if (ok) {
        gsl_error_handler_t *old = gsl_set_error_handler_off();
        ok = gsl_eigen_symmv(&A.matrix, ev, V, w) == GSL_SUCCESS;
        gsl_set_error_handler(old);
    }
    if (ok) {
        gsl_eigen_symmv_sort(ev, V, GSL_EIGEN_SORT_VAL_ASC);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) E[3 * r + c] = gsl_matrix_get(V, r, c);
    }
    gsl_eigen_symmv_free(w);
    gsl_matrix_free(V);
    gsl_vector_free(ev);
    return ok;
}

static double det3(const double M[9])
{
    return M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
           M[2] * (M[3] * M[7] - M[4] * M[6]);
}

int gp_fill3d_frame(const double I[9], double E[9])
{
    if (!axes_of(I, E)) return 0;
    if (det3(E) < 0)
        for (int r = 0; r < 3; r++) E[3 * r + 2] = -E[3 * r + 2];
    return 1;
}

/* R = E G^T: the grain's axis k onto the cell's axis k, a proper rotation */
static int aligned_rotation(const double Ic[9], const double Ig[9], double R[9])
{
    double E[9], G[9];
    if (!gp_fill3d_frame(Ic, E) || !gp_fill3d_frame(Ig, G)) return 0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            R[3 * r + c] = E[3 * r] * G[3 * c] + E[3 * r + 1] * G[3 * c + 1] + E[3 * r + 2] * G[3 * c + 2];
    return 1;
}

/* h[f] = max_i (R^T n_f) . p_i / G, the grain's support along each face normal */
static void supports(const local_cell *lc, const gp_fill3d_grain *g, double G, const double R[9], double *h)
{
    for (size_t f = 0; f < lc->nf; f++) {
        const double *n = lc->n + 3 * f;
        double m[3];
        for (int c = 0; c < 3; c++) m[c] = R[c] * n[0] + R[3 + c] * n[1] + R[6 + c] * n[2];
        double best = -INFINITY;
        for (size_t i = 0; i < g->n; i++) {
            const double *p = g->points + 3 * i;
            double v = m[0] * p[0] + m[1] * p[1] + m[2] * p[2];
            if (v > best) best = v;
        }
        h[f] = best / G;
    }
}

typedef struct work {
    double *a, *b, *h;
} work;

/* the largest u (scale in units of L / G) and its centre for the supports h; -1 when the LP
 * fails */
static int largest(const local_cell *lc, const double *h, work *w, double c[3], double *u)
{
    for (size_t f = 0; f < lc->nf; f++) {
        memcpy(w->a + 4 * f, lc->n + 3 * f, 3 * sizeof(double));
        w->a[4 * f + 3] = h[f];
        w->b[f] = lc->d[f];
    }
    double x[4];
    if (gp_fill3d_lp(w->a, w->b, lc->nf, x) != 0) return -1;
    memcpy(c, x, 3 * sizeof(double));
    *u = x[3];
    return 0;
}

/* the centre of most clearance for the scale u, from c0 where u fits */
static int centred(const local_cell *lc, const double *h, double u, work *w, double c[3])
{
    double c0[3] = {c[0], c[1], c[2]};
    for (size_t f = 0; f < lc->nf; f++) {
        const double *n = lc->n + 3 * f;
        memcpy(w->a + 4 * f, n, 3 * sizeof(double));
        w->a[4 * f + 3] = 1.0;
        w->b[f] = lc->d[f] - h[f] * u - (n[0] * c0[0] + n[1] * c0[1] + n[2] * c0[2]);
    }
    double x[4];
    if (gp_fill3d_lp(w->a, w->b, lc->nf, x) != 0) return -1;
    for (int k = 0; k < 3; k++) c[k] = c0[k] + x[k];
    return 0;
}

/* the largest u with every face's clearance at least margin at centre c */
static double shrink_to_fit(const local_cell *lc, const double *h, const double c[3], double u, double margin)
{
    for (size_t f = 0; f < lc->nf; f++) {
        const double *n = lc->n + 3 * f;
        double room = lc->d[f] - margin - (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]);
        if (u * h[f] > room) u = room / h[f];
    }
    return u;
}

/* ------------------------------------------------------------------------- the search */

static void rotation_about(const double ax[3], double ang, double Q[9])
{
    double c = cos(ang), s = sin(ang), t = 1.0 - c, x = ax[0], y = ax[1], z = ax[2];
    double M[9] = {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,
                   t * x * y + s * z, t * y * y + c,     t * y * z - s * x,
                   t * x * z - s * y, t * y * z + s * x, t * z * z + c};
    memcpy(Q, M, sizeof M);
}

static void matmul3(const double A[9], const double B[9], double C[9])
{
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            C[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
}

typedef struct search {
    const local_cell *lc;
    const gp_fill3d_grain *g;
    double G;
    work *w;
    double R[9], c[3], u; /* the best so far */
    int tries;
} search;

static int evaluate(search *S, const double R[9], double c[3], double *u)
{
    S->tries++;
    supports(S->lc, S->g, S->G, R, S->w->h);
    return largest(S->lc, S->w->h, S->w, c, u);
}

/* random turns of the best rotation, kept when they raise the largest scale */
static int climb(search *S, const gp_fill3d_params *p, gp_fill3d_u01_fn u01, void *state, double u_target)
{
    double turn = p->turn;
    int fails = 0;
    for (int t = 0; t < p->rotations && S->u < u_target; t++) {
        double z = 2.0 * u01(state) - 1.0, phi = 2.0 * M_PI * u01(state), ang = turn * u01(state);
        double rxy = sqrt(fmax(0.0, 1.0 - z * z)), ax[3] = {rxy * cos(phi), rxy * sin(phi), z}, Q[9], R[9], c[3], u;
        rotation_about(ax, ang, Q);
        matmul3(Q, S->R, R);
        if (evaluate(S, R, c, &u) != 0) return -1;
        if (u > S->u) {
            memcpy(S->R, R, sizeof R);
            memcpy(S->c, c, sizeof c);
            S->u = u;
            fails = 0;
        } else if (++fails >= CLIMB_PATIENCE) {
            turn *= 0.5;
            fails = 0;
        }
    }
    return 0;
}

/* ------------------------------------------------------------------------- the placement */

static gp_status check_input(const gp_fill3d_cell *cell, const gp_fill3d_grain *g, const gp_fill3d_params *p,
                             gp_fill3d_u01_fn u01, gp_error *err)
{
    if (!cell || !g || !p) return gp_error_set(err, GP_ERR_INVALID, "fill3d: cell, grain and params are required");
    if (!(p->solid_fraction > 0.0 && p->solid_fraction <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "fill3d: solid_fraction must be in (0, 1], got %g", p->solid_fraction);
    if (p->rotations < 0 || (p->rotations > 0 && !u01))
        return gp_error_set(err, GP_ERR_INVALID, "fill3d: rotations must be >= 0 (and need a u01 source)");
    if (!(p->turn >= 0.0 && p->turn <= M_PI) || !(p->margin >= 0.0 && p->margin < 0.01))
        return gp_error_set(err, GP_ERR_INVALID, "fill3d: turn must be in [0, pi] and margin in [0, 0.01)");
    if (!cell->planes || cell->nplanes < 4 || !(cell->volume > 0.0) || !isfinite(cell->volume))
        return gp_error_set(err, GP_ERR_INVALID, "fill3d: the cell needs at least 4 faces and a volume > 0");
    if (!g->points || g->n < 4 || !(g->volume > 0.0) || !isfinite(g->volume))
        return gp_error_set(err, GP_ERR_INVALID, "fill3d: the grain needs at least 4 points and a volume > 0");
    return GP_OK;
}

static gp_status local_of(const gp_fill3d_cell *cell, double margin, local_cell *lc, gp_error *err)
{
    lc->nf = cell->nplanes;
    lc->L = cbrt(cell->volume);
    memcpy(lc->q, cell->interior, sizeof lc->q);
    double far = fmax(fabs(lc->q[0]), fmax(fabs(lc->q[1]), fabs(lc->q[2])));
    lc->slack = margin + 16.0 * DBL_EPSILON * (1.0 + far / lc->L);
    for (size_t f = 0; f < lc->nf; f++) {
        const double *P = cell->planes + 4 * f;
        double len = sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2]);
        if (!(len > 0.0) || !isfinite(len) || !isfinite(P[3]))
            return gp_error_set(err, GP_ERR_INVALID, "fill3d: face %zu has no normal", f);
        for (int k = 0; k < 3; k++) lc->n[3 * f + k] = P[k] / len;
        double qn = lc->n[3 * f] * lc->q[0] + lc->n[3 * f + 1] * lc->q[1] + lc->n[3 * f + 2] * lc->q[2];
        lc->d[f] = (P[3] / len - qn) / lc->L;
        if (!(lc->d[f] > 0.0))
            return gp_error_set(err, GP_ERR_DEGENERATE, "fill3d: the interior point is not strictly inside face %zu", f);
    }
    return GP_OK;
}

static gp_status place(search *S, const gp_fill3d_cell *cell, const gp_fill3d_params *p, gp_fill3d_u01_fn u01,
                       void *state, gp_fill3d_result *out, gp_error *err)
{
    const local_cell *lc = S->lc;
    if (p->rotation)
        memcpy(S->R, p->rotation, sizeof S->R);
    else if (!aligned_rotation(cell->inertia, S->g->inertia, S->R))
        return gp_error_set(err, GP_ERR_INVALID, "fill3d: the cell's or the grain's inertia is not finite");
    if (evaluate(S, S->R, S->c, &S->u) != 0) return gp_error_set(err, GP_ERR_INTERNAL, "fill3d: the scale LP failed");
    for (size_t f = 0; f < lc->nf; f++)
        if (!(S->w->h[f] > 0.0))
            return gp_error_set(err, GP_ERR_DEGENERATE, "fill3d: the grain's origin is not inside its hull");
    double u_target = cbrt(p->solid_fraction * cell->volume / S->g->volume) * S->G / lc->L;
    if (S->u < u_target && p->rotations > 0 && climb(S, p, u01, state, u_target) != 0)
        return gp_error_set(err, GP_ERR_INTERNAL, "fill3d: the scale LP failed");
    supports(lc, S->g, S->G, S->R, S->w->h);
    double u_max = S->u, u = fmin(u_target, u_max * SCALE_SAFETY);
    if (centred(lc, S->w->h, u, S->w, S->c) != 0) return gp_error_set(err, GP_ERR_INTERNAL, "fill3d: the centre LP failed");
    u = shrink_to_fit(lc, S->w->h, S->c, u, lc->slack);
    if (!(u > 0.0)) return gp_error_set(err, GP_ERR_INTERNAL, "fill3d: no room left for the grain");
    memcpy(out->R, S->R, sizeof out->R);
    for (int k = 0; k < 3; k++) out->centre[k] = lc->q[k] + lc->L * S->c[k];
    out->scale = u * lc->L / S->G;
    out->scale_max = u_max * lc->L / S->G;
    out->fraction = out->scale * out->scale * out->scale * S->g->volume / cell->volume;
    out->target_met = u >= u_target * (1.0 - 1e-12);
    out->tries = S->tries;
    return GP_OK;
}

gp_status gp_fill3d_place(const gp_fill3d_cell *cell, const gp_fill3d_grain *grain,
                          const gp_fill3d_params *params, gp_fill3d_u01_fn u01, void *state,
                          gp_fill3d_result *out, gp_error *err)
{
    gp_status st = check_input(cell, grain, params, u01, err);
    if (st != GP_OK) return st;
    size_t nf = cell->nplanes;
    local_cell lc = {nf, malloc(3 * nf * sizeof(double)), malloc(nf * sizeof(double)), 0, {0, 0, 0}, 0};
    work w = {malloc(4 * nf * sizeof(double)), malloc(nf * sizeof(double)), malloc(nf * sizeof(double))};
    if (!lc.n || !lc.d || !w.a || !w.b || !w.h) {
        st = gp_error_set(err, GP_ERR_NOMEM, "fill3d: out of memory");
    } else if ((st = local_of(cell, params->margin, &lc, err)) == GP_OK) {
        search S = {&lc, grain, cbrt(grain->volume), &w, {0}, {0}, 0.0, 0};
        st = place(&S, cell, params, u01, state, out, err);
    }
    free(lc.n);
    free(lc.d);
    free(w.a);
    free(w.b);
    free(w.h);
    return st;
}
