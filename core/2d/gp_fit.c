/* gp_fit.c -- see gp_fit.h. */
#include "gp_fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- shared helpers ---- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* First non-finite value, named by its index (what: "area", "theta_deg", ...). */
static gp_status check_finite(const double *v, size_t n, const char *what, gp_error *err)
{
    if (n > 0 && !v)
        return gp_error_set(err, GP_ERR_INVALID, "fit: %s values missing (n = %zu)", what, n);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return gp_error_set(err, GP_ERR_INVALID, "fit: %s[%zu] is not a finite number", what, i);
    return GP_OK;
}

static double *sorted_copy(const double *v, size_t n)
{
    double *s = malloc(n * sizeof *s);
    if (!s)
        return NULL;
    memcpy(s, v, n * sizeof *s);
    qsort(s, n, sizeof *s, cmp_double);
    return s;
}

double gp_fit_ks_critical(size_t n)
{
    return n ? 1.36 / sqrt((double)n) : 0.0;
}

/* Two-sided KS distance of u_i = F(x_(i)) given in the order of the sorted x: the empirical CDF
 * jumps from (i-1)/n to i/n at x_(i), so the sup of |F_n - F| is reached at one of those ends
 * (with ties, the extreme ends of a run are among them). */
static double ks_at(double d, double u, size_t i, size_t n)
{
    double above = (double)(i + 1) / (double)n - u;
    double below = u - (double)i / (double)n;
    if (above > d) d = above;
    if (below > d) d = below;
    return d;
}

double gp_fit_ks_uniform(const double *u, size_t n)
{
    double d = 0;
    for (size_t i = 0; i < n; i++)
        d = ks_at(d, u[i], i, n);
    return d;
}

double gp_fit_ks_sorted(const double *x, size_t n, const gp_law *law)
{
    double d = 0;
    for (size_t i = 0; i < n; i++)
        d = ks_at(d, gp_law_cdf(law, x[i]), i, n);
    return d;
}

/* ---- adaptive Gauss-Kronrod 7/15 (QUADPACK qk15 nodes and weights) ----
 * Own rule rather than gsl_integration_*: GSL reports a failure through its process-wide error
 * handler (abort by default), which a library without global state cannot switch off. */

typedef double (*fit_fn)(double x, const void *ctx);

static const double XGK[8] = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.000000000000000000000000000000000};
static const double WGK[8] = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
/* Gauss 7-point weights of the nodes XGK[1], XGK[3], XGK[5], XGK[7] */
static const double WG[4] = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

static double gk15(fit_fn f, const void *ctx, double a, double b, double *errest)
{
    double c = 0.5 * (a + b), h = 0.5 * (b - a);
    double fc = f(c, ctx);
    double k = WGK[7] * fc, g = WG[3] * fc;
    for (int j = 0; j < 7; j++) {
        double s = f(c - h * XGK[j], ctx) + f(c + h * XGK[j], ctx);
        k += WGK[j] * s;
        if (j % 2 == 1)
            g += WG[j / 2] * s;
    }
    *errest = fabs((k - g) * h);
    return k * h;
}

/* Bisects until the Kronrod-Gauss difference is under tol (halved with each split). *budget
 * counts the rules left to this integral: noise in f (rounding) can keep the estimate above a
 * tight tol on every piece, and a full bisection tree would then be exponential in the depth;
 * once spent, pieces take their last rule, already far finer than needed. */
static double adapt_rec(fit_fn f, const void *ctx, double a, double b, double tol, int depth,
                        long *budget)
{
    double e, v = gk15(f, ctx, a, b, &e);
    if (e <= tol || depth <= 0 || --*budget <= 0)
        return v;
    double m = 0.5 * (a + b);
    return adapt_rec(f, ctx, a, m, 0.5 * tol, depth - 1, budget)
           + adapt_rec(f, ctx, m, b, 0.5 * tol, depth - 1, budget);
}

#define FIT_DEPTH 48
#define FIT_BUDGET 2000
#define FIT_RTOL 1e-13

static double adapt(fit_fn f, const void *ctx, double a, double b, double tol)
{
    long budget = FIT_BUDGET;
    return adapt_rec(f, ctx, a, b, tol, FIT_DEPTH, &budget);
}

/* ---- W1 ---- */

typedef struct {
    const gp_law *law;
    double c;        /* F_n on the piece */
    double x0, s;    /* tail: x = x0 + s t / (1 - t) */
} w1_ctx;

static double gap_fn(double x, const void *vctx)
{
    const w1_ctx *q = vctx;
    return fabs(q->c - gp_law_cdf(q->law, x));
}

/* 1 - F on the unbounded tail, from ln(1 - F): 1 - gp_law_cdf() would carry an absolute
 * rounding of ~1e-16 that the factor s / (1 - t)^2 blows up near t = 1. The log survival is of
 * the working law F_w, which is F itself for the unbounded (lognormal, normal) laws, the only
 * ones with a tail. */
static double tail_fn(double t, const void *vctx)
{
    const w1_ctx *q = vctx;
    double u = 1.0 - t, x = q->x0 + q->s * t / u;
    if (!isfinite(x))
        return 0.0;
    double lf, ls;
    gp_law_log_cdf_sf(q->law, x, &lf, &ls);
    return exp(ls) * q->s / (u * u);
}

/* integral of |c - F| over [a, b], a piece where F is smooth: split where F crosses c, so that
 * each half is smooth too (|.| has a kink there). */
static double smooth_piece(w1_ctx *q, double a, double b)
{
    if (!(b > a))
        return 0;
    double fa = gp_law_cdf(q->law, a) - q->c, fb = gp_law_cdf(q->law, b) - q->c;
    double tol = FIT_RTOL * (b - a);
    if (fa < 0 && fb > 0) {
        double xs = gp_law_quantile(q->law, q->c);
        if (xs > a && xs < b)
            return adapt(gap_fn, q, a, xs, 0.5 * tol)
                   + adapt(gap_fn, q, xs, b, 0.5 * tol);
    }
    return adapt(gap_fn, q, a, b, tol);
}

/* integral of |c - F| over [a, b], split first at the law's kinks inside it. *k walks the
 * sorted kinks along with the increasing pieces. */
static double gap_piece(w1_ctx *q, double a, double b, const double *kinks, size_t nk, size_t *k)
{
    double sum = 0, lo = a;
    while (*k < nk && kinks[*k] <= a)
        (*k)++;
    for (size_t j = *k; j < nk && kinks[j] < b; j++) {
        sum += smooth_piece(q, lo, kinks[j]);
        lo = kinks[j];
    }
    return sum + smooth_piece(q, lo, b);
}

/* Area factor of a sieve law over its rows: gp_law_sieve_rows gives the rows "as given", also
 * for a gp_law_scaled law, and gp_law.h has no scale getter; the largest row's disc is the
 * support's upper end on the law's own scale. Exactly 1 for an unscaled law. */
static double sieve_scale(const gp_law *law, const double *d, size_t nrows)
{
    double lo, hi;
    gp_law_support(law, &lo, &hi);
    return hi / gp_law_sieve_size(law, d[nrows - 1]);
}

/* Where F may have a kink: the support's finite ends and, for a sieve law, the rows' areas. */
static double *law_kinks(const gp_law *law, size_t *nk)
{
    const double *d, *pw;
    size_t nrows = gp_law_sieve_rows(law, &d, &pw);
    double lo, hi;
    gp_law_support(law, &lo, &hi);
    double *k = malloc((nrows + 2) * sizeof *k);
    if (!k)
        return NULL;
    size_t m = 0;
    if (isfinite(lo)) k[m++] = lo;
    if (isfinite(hi)) k[m++] = hi;
    if (nrows > 0 && isfinite(hi)) {
        double scale = sieve_scale(law, d, nrows);
        for (size_t r = 0; r < nrows; r++)
            k[m++] = gp_law_dim(law) == 2 ? scale * M_PI / 4 * d[r] * d[r] : scale * gp_law_sieve_size(law, d[r]);
    }
    qsort(k, m, sizeof *k, cmp_double);
    *nk = m;
    return k;
}

/* W1 = integral of |F_n - F| dx over the sorted sample x[0..n-1]. */
static gp_status wasserstein1(const double *x, size_t n, const gp_law *law, double *w1)
{
    size_t nk = 0, k = 0;
    double *kinks = law_kinks(law, &nk);
    if (!kinks)
        return GP_ERR_NOMEM;
    double lo, hi;
    gp_law_support(law, &lo, &hi);
    w1_ctx q = {law, 0.0, 0.0, 0.0};
    double sum = 0;
    if (x[0] > lo)              /* below the sample F_n = 0; below the support F = 0 too */
        sum += gap_piece(&q, lo, x[0], kinks, nk, &k);
    for (size_t i = 0; i + 1 < n; i++) {
        q.c = (double)(i + 1) / (double)n;
        sum += gap_piece(&q, x[i], x[i + 1], kinks, nk, &k);
    }
    q.c = 1.0;
    if (isfinite(hi)) {
        if (x[n - 1] < hi)
            sum += gap_piece(&q, x[n - 1], hi, kinks, nk, &k);
    } else {
        /* the unbounded tail, on t in [0, 1); the scale s puts the bulk of 1 - F mid-range */
        q.x0 = x[n - 1];
        q.s = gp_law_mean(law) * (1.0 + gp_law_cov(law));
        sum += adapt(tail_fn, &q, 0.0, 1.0, FIT_RTOL * q.s);
    }
    free(kinks);
    *w1 = sum;
    return GP_OK;
}

/* ---- area fit ---- */

/* mean and COV (sample standard deviation, n - 1; 0 for n = 1), two passes for accuracy */
static void moments(const double *x, size_t n, double *mean, double *cov)
{
    double s = 0;
    for (size_t i = 0; i < n; i++)
        s += x[i];
    double m = s / (double)n, ss = 0;
    for (size_t i = 0; i < n; i++)
        ss += (x[i] - m) * (x[i] - m);
    *mean = m;
    *cov = (n > 1 && m != 0) ? sqrt(ss / (double)(n - 1)) / fabs(m) : 0.0;
}

/* number of sorted values <= v (the empirical CDF times n, right-continuous) */
static size_t count_le(const double *x, size_t n, double v)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (x[mid] <= v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The two CDFs on ncurve points over [min(q001, min), max(q999, max)]. */
static gp_status fill_curve(const double *x, size_t n, const gp_law *law, size_t ncurve,
                            gp_fit_area *out)
{
    if (ncurve == 0)
        return GP_OK;
    out->curve_x = malloc(ncurve * sizeof(double));
    out->curve_target = malloc(ncurve * sizeof(double));
    out->curve_achieved = malloc(ncurve * sizeof(double));
    if (!out->curve_x || !out->curve_target || !out->curve_achieved)
        return GP_ERR_NOMEM;
    out->ncurve = ncurve;
    double a = fmin(out->q001, out->min), b = fmax(out->q999, out->max);
    int logs = a > 0 && b > 10 * a;     /* more than a decade: log spacing */
    double den = ncurve > 1 ? (double)(ncurve - 1) : 1.0;
    for (size_t j = 0; j < ncurve; j++) {
        double t = (double)j / den;
        double v = logs ? a * pow(b / a, t) : a + t * (b - a);
        if (j + 1 == ncurve && ncurve > 1)
            v = b;                      /* the end exactly, whatever pow's rounding */
        out->curve_x[j] = v;
        out->curve_target[j] = gp_law_cdf(law, v);
        out->curve_achieved[j] = (double)count_le(x, n, v) / (double)n;
    }
    return GP_OK;
}

static void area_targets(const gp_law *law, size_t n, gp_fit_area *out)
{
    out->law = gp_law_kind_of(law);
    out->target_mean = gp_law_mean(law);
    out->target_cov = gp_law_cov(law);
    out->q001 = gp_law_quantile(law, 0.001);
    out->q999 = gp_law_quantile(law, 0.999);
    out->n = n;
    out->ks_critical = gp_fit_ks_critical(n);
}

/* everything measured on the sorted sample x */
static gp_status area_measures(const double *x, size_t n, const gp_law *law, size_t ncurve,
                               gp_fit_area *out)
{
    double *u = malloc(n * sizeof *u);
    if (!u)
        return GP_ERR_NOMEM;
    for (size_t i = 0; i < n; i++)
        u[i] = gp_law_cdf(law, x[i]);
    out->ks = gp_fit_ks_uniform(u, n);
    free(u);
    moments(x, n, &out->mean, &out->cov);
    out->min = x[0];
    out->max = x[n - 1];
    double w1;
    gp_status st = wasserstein1(x, n, law, &w1);
    if (st)
        return st;
    out->w1 = w1 / out->target_mean;
    return fill_curve(x, n, law, ncurve, out);
}

gp_status gp_fit_area_measure(const double *values, size_t n, const gp_law *law, size_t ncurve,
                              gp_fit_area *out, gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "fit: no output");
    memset(out, 0, sizeof *out);
    if (!law)
        return gp_error_set(err, GP_ERR_INVALID, "fit: no target law");
    gp_status st = check_finite(values, n, "area", err);
    if (st)
        return st;
    area_targets(law, n, out);
    if (n == 0)
        return GP_OK;
    double *x = sorted_copy(values, n);
    st = x ? area_measures(x, n, law, ncurve, out) : GP_ERR_NOMEM;
    free(x);
    if (st) {
        gp_fit_area_free(out);
        return gp_error_set(err, st, "fit: out of memory measuring %zu areas", n);
    }
    out->present = 1;
    return GP_OK;
}

void gp_fit_area_free(gp_fit_area *f)
{
    if (!f)
        return;
    free(f->curve_x);
    free(f->curve_target);
    free(f->curve_achieved);
    memset(f, 0, sizeof *f);
}

/* ---- orientation fit ---- */

gp_status gp_fit_orient_measure(const double *theta_deg, size_t n, double mean_deg,
                                double anisotropy, gp_fit_orient *out, gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "fit: no output");
    memset(out, 0, sizeof *out);
    if (!isfinite(mean_deg))
        return gp_error_set(err, GP_ERR_INVALID, "fit: orientation mean_deg must be finite");
    if (!(anisotropy > 0 && anisotropy <= 1))
        return gp_error_set(err, GP_ERR_INVALID, "fit: anisotropy must be in (0, 1], got %g",
                            anisotropy);
    gp_status st = check_finite(theta_deg, n, "theta_deg", err);
    if (st)
        return st;
    out->target_mean_deg = mean_deg;
    out->target_anisotropy = anisotropy;
    out->n = n;
    out->ks_critical = gp_fit_ks_critical(n);
    if (n == 0)
        return GP_OK;
    /* the law's CDF u of each direction (on its window) is uniform under the law: D of the
     * sorted u against the uniform is D of the directions against the law */
    double *u = malloc(n * sizeof *u);
    if (!u)
        return gp_error_set(err, GP_ERR_NOMEM, "fit: out of memory measuring %zu directions", n);
    for (size_t i = 0; i < n; i++)
        u[i] = gp_orient_cdf(mean_deg, anisotropy, theta_deg[i]);
    qsort(u, n, sizeof *u, cmp_double);
    out->ks = gp_fit_ks_uniform(u, n);
    free(u);
    out->present = 1;
    return GP_OK;
}

/* ---- passing by mass (sieve laws) ---- */

static gp_status check_areas(const double *a, size_t n, gp_error *err)
{
    gp_status st = check_finite(a, n, "area", err);
    if (st)
        return st;
    for (size_t i = 0; i < n; i++)
        if (a[i] < 0)
            return gp_error_set(err, GP_ERR_INVALID, "fit: area[%zu] = %g is negative", i, a[i]);
    return GP_OK;
}

static gp_status passing_alloc(gp_fit_passing *out, size_t nrows)
{
    out->diameters = malloc(nrows * sizeof(double));
    out->target = malloc(nrows * sizeof(double));
    out->achieved = malloc(nrows * sizeof(double));
    if (!out->diameters || !out->target || !out->achieved)
        return GP_ERR_NOMEM;
    out->n = nrows;
    return GP_OK;
}

/* Percent of the total area in grains of diameter < d[k]: sorted diameters, one sweep. */
static void passing_sweep(const double *dg, const double *ag, size_t n, gp_fit_passing *out)
{
    double total = 0;
    for (size_t i = 0; i < n; i++)
        total += ag[i];
    double acc = 0;
    size_t i = 0;
    out->max_error_pp = 0;
    for (size_t k = 0; k < out->n; k++) {
        while (i < n && dg[i] < out->diameters[k])
            acc += ag[i++];
        out->achieved[k] = total > 0 ? 100.0 * acc / total : 0.0;
        double e = fabs(out->achieved[k] - out->target[k]);
        if (e > out->max_error_pp)
            out->max_error_pp = e;
    }
}

/* grains by increasing diameter: the pairs (d, A) sorted by d (an area sorts as its d) */
static gp_status passing_grains(const double *areas, size_t n, const gp_law *law, double **dg, double **ag)
{
    *ag = sorted_copy(areas, n);
    *dg = malloc(n * sizeof **dg);
    if (!*ag || !*dg)
        return GP_ERR_NOMEM;
    for (size_t i = 0; i < n; i++)
        (*dg)[i] = gp_law_sieve_diameter(law, (*ag)[i]);
    return GP_OK;
}

gp_status gp_fit_passing_measure(const double *areas, size_t n, const gp_law *sieve_law,
                                 gp_fit_passing *out, gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "fit: no output");
    memset(out, 0, sizeof *out);
    gp_status st = check_areas(areas, n, err);
    if (st)
        return st;
    const double *d = NULL, *pw = NULL;
    size_t nrows = sieve_law ? gp_law_sieve_rows(sieve_law, &d, &pw) : 0;
    if (nrows == 0 || n == 0)
        return GP_OK;
    double *dg = NULL, *ag = NULL;
    st = passing_alloc(out, nrows);
    if (!st)
        st = passing_grains(areas, n, sieve_law, &dg, &ag);
    if (!st) {
        /* the law's own diameters */
        double sc = sieve_scale(sieve_law, d, nrows), f = gp_law_dim(sieve_law) == 2 ? sqrt(sc) : cbrt(sc);
        for (size_t k = 0; k < nrows; k++)
            out->diameters[k] = f * d[k];
        memcpy(out->target, pw, nrows * sizeof *pw);
        passing_sweep(dg, ag, n, out);
    }
    free(dg);
    free(ag);
    if (st) {
        gp_fit_passing_free(out);
        return gp_error_set(err, st, "fit: out of memory measuring passing of %zu grains", n);
    }
    return GP_OK;
}

void gp_fit_passing_free(gp_fit_passing *p)
{
    if (!p)
        return;
    free(p->diameters);
    free(p->target);
    free(p->achieved);
    memset(p, 0, sizeof *p);
}
