/* gp_imc.c -- inverse Monte-Carlo on a locally updated Voronoi tessellation. See gp_imc.h.
 *
 * Hot path per step: one gp_voronoi_try_move (about a dozen cells re-clipped), then for each
 * changed cell an O(log k) area-class lookup and an O(1) orientation class, integer count
 * updates, and an O(k) error evaluation from the counts (exact, so no drift and no
 * order-dependence). No allocation per step.
 */
#include "gp_imc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gp_rng.h"

#define GP_IMC_PI 3.14159265358979323846
#define GP_IMC_KMAX 20
#define GP_IMC_KMIN 3
#define GP_IMC_PROGRESS_EVERY 4096
#define GP_IMC_CANCEL_EVERY 256

void gp_imc_params_default(gp_imc_params *p)
{
    if (!p) return;
    memset(p, 0, sizeof *p);
    p->cov = 0.5;
    p->mean_deg = 0.0;
    p->anisotropy = 1.0;
    p->error_kind = 3;
    p->threshold = 0.002;
    p->max_steps = 1000000;
    p->init = 0;
    p->seed = 1;
}

const char *gp_imc_stop_name(gp_imc_stop s)
{
    switch (s) {
    case GP_IMC_STOP_THRESHOLD: return "threshold";
    case GP_IMC_STOP_MAX_STEPS: return "max_steps";
    case GP_IMC_STOP_FLOOR: return "floor";
    case GP_IMC_STOP_CANCELLED: return "cancelled";
    }
    return "unknown";
}

void gp_imc_report_free(gp_imc_report *r)
{
    if (!r) return;
    free(r->size_edges);
    free(r->size_target);
    free(r->size_achieved);
    free(r->orient_edges);
    free(r->orient_target);
    free(r->orient_achieved);
    memset(r, 0, sizeof *r);
}

/* ------------------------------------------------------------------------------------------ */
/* targets and floors                                                                          */

/* standard normal quantile: Acklam's rational approximation + one Halley step on erfc */
static double norm_quantile(double p)
{
    if (p <= 0) return -INFINITY;
    if (p >= 1) return INFINITY;
    static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                               1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
    static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                               6.680131188771972e+01, -1.328068155288572e+01};
    static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                               -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
    static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                               3.754408661907416e+00};
    double x;
    if (p < 0.02425) {
        double q = sqrt(-2 * log(p));
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
    } else if (p <= 1 - 0.02425) {
        double q = p - 0.5, r = q * q;
        x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
    } else {
        double q = sqrt(-2 * log(1 - p));
        x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
    }
    double e = 0.5 * erfc(-x / sqrt(2.0)) - p;
    double u = e * sqrt(2 * GP_IMC_PI) * exp(x * x / 2);
    return x - u / (1 + x * u / 2);
}

/* area class edges (nk + 1) for lognormal(mean mu, cov) at equal probabilities */
static void size_classes(double mu, double cov, int k, double *edges, double *target)
{
    double s2 = log(1.0 + cov * cov), s = sqrt(s2), m = log(mu) - 0.5 * s2;
    edges[0] = 0.0;
    for (int j = 1; j < k; j++) edges[j] = exp(m + s * norm_quantile((double)j / k));
    edges[k] = INFINITY;
    for (int j = 0; j < k; j++) target[j] = 1.0 / k;
}

/* orientation classes over [-90, 90) degrees */
static void orient_classes(double mean_deg, double a, int k, double *edges, double *target)
{
    double tb = mean_deg * GP_IMC_PI / 180.0, norm = (1.0 + a) * GP_IMC_PI / 2.0;
    for (int j = 0; j <= k; j++) edges[j] = -90.0 + 180.0 * j / k;
    double sum = 0.0;
    for (int j = 0; j < k; j++) {
        double lo = edges[j] * GP_IMC_PI / 180.0, hi = edges[j + 1] * GP_IMC_PI / 180.0;
        target[j] = ((1.0 + a) / 2.0 * (hi - lo) +
                     (1.0 - a) / 4.0 * (sin(2.0 * (hi - tb)) - sin(2.0 * (lo - tb)))) /
                    norm;
        sum += target[j];
    }
    for (int j = 0; j < k; j++) target[j] /= sum; /* exact 1 against rounding */
}

double gp_imc_floor(const double *target, size_t k, size_t n, int kind)
{
    if (!target || k == 0 || n == 0) return 0.0;
    /* largest remainders: floor everything, hand the rest to the largest fractional parts */
    double *fr = malloc(k * sizeof *fr);
    long *c = malloc(k * sizeof *c);
    if (!fr || !c) {
        free(fr);
        free(c);
        return NAN;
    }
    long given = 0;
    for (size_t j = 0; j < k; j++) {
        double t = target[j] * (double)n;
        c[j] = (long)floor(t);
        fr[j] = t - floor(t);
        given += c[j];
    }
    long rest = (long)n - given;
    while (rest > 0) {
        size_t best = 0;
        for (size_t j = 1; j < k; j++)
            if (fr[j] > fr[best]) best = j;
        c[best]++;
        fr[best] = -1.0;
        rest--;
    }
    double s2 = 0.0, mx = 0.0;
    for (size_t j = 0; j < k; j++) {
        double d = (double)c[j] - target[j] * (double)n;
        s2 += d * d;
        if (fabs(d) > mx) mx = fabs(d);
    }
    free(fr);
    free(c);
    return kind == 2 ? mx / (double)n : sqrt(s2) / (double)n;
}

static double combine(int kind, double a, double b)
{
    return kind == 1 ? 0.5 * (a + b) : (a > b ? a : b);
}

/* ------------------------------------------------------------------------------------------ */
/* run                                                                                         */

typedef struct imc_state {
    int kind;
    int ks, kt;
    double *se, *st, *te, *tt; /* edges and targets (targets as expected counts N * H) */
    int *cs, *ct;              /* counts */
    unsigned char *clss, *clst;/* class of each cell */
    double tscale;             /* classes per radian */
    double n;
} imc_state;

static inline int size_class(const imc_state *s, double a)
{
    int lo = 0, hi = s->ks - 1; /* first class whose upper edge is > a */
    while (lo < hi) {
        int mid = (lo + hi) >> 1;
        if (a < s->se[mid + 1]) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

static inline int orient_class(const imc_state *s, double th)
{
    int c = (int)floor((th + GP_IMC_PI / 2) * s->tscale);
    if (c >= s->kt) c -= s->kt; /* +90 deg is -90 deg */
    if (c < 0) c = 0;
    return c;
}

/* sum of squared count deviations of both histograms: the tie-breaker */
static double sec_error(const imc_state *s)
{
    double a = 0.0;
    for (int j = 0; j < s->ks; j++) a += (s->cs[j] - s->st[j]) * (s->cs[j] - s->st[j]);
    for (int j = 0; j < s->kt; j++) a += (s->ct[j] - s->tt[j]) * (s->ct[j] - s->tt[j]);
    return a;
}

static void hist_errors(const imc_state *s, double *es, double *et)
{
    double a = 0.0, b = 0.0;
    if (s->kind == 2) {
        for (int j = 0; j < s->ks; j++) a = fmax(a, fabs(s->cs[j] - s->st[j]));
        for (int j = 0; j < s->kt; j++) b = fmax(b, fabs(s->ct[j] - s->tt[j]));
        *es = a / s->n;
        *et = b / s->n;
        return;
    }
    for (int j = 0; j < s->ks; j++) {
        double d = s->cs[j] - s->st[j];
        a += d * d;
    }
    for (int j = 0; j < s->kt; j++) {
        double d = s->ct[j] - s->tt[j];
        b += d * d;
    }
    *es = sqrt(a) / s->n;
    *et = sqrt(b) / s->n;
}

static double current_error(const imc_state *s)
{
    double a, b;
    hist_errors(s, &a, &b);
    return combine(s->kind, a, b);
}

static double u01(void *r) { return gp_rng_uniform((gp_rng *)r); }

static int pick_classes(int user, int n, double thr, int kind, int is_size, const gp_imc_params *p,
                        double mu)
{
    if (user > 0) return user;
    /* the slack N * threshold (in counts) decides how many classes can be matched in practice:
     * at N = 500, E3 = 0.002 allows one count of squared deviation, and 5 classes converge in a
     * few thousand steps where 10 stall (measured on the unit square) */
    double slack = (double)n * thr;
    double kf = floor(4.5 + 0.5 * slack * slack);
    int kmax = kf > GP_IMC_KMAX ? GP_IMC_KMAX : (int)kf;
    if (kmax > n / 25) kmax = n / 25;
    if (kmax < GP_IMC_KMIN) kmax = GP_IMC_KMIN;
    double e[GP_IMC_KMAX + 1], t[GP_IMC_KMAX];
    for (int k = kmax; k > GP_IMC_KMIN; k--) {
        if (is_size) size_classes(mu, p->cov, k, e, t);
        else orient_classes(p->mean_deg, p->anisotropy, k, e, t);
        double f = gp_imc_floor(t, (size_t)k, (size_t)n, kind);
        if (f <= 0.5 * thr) return k;
    }
    return GP_IMC_KMIN;
}

static gp_status fill_report(gp_imc_report *rep, const imc_state *s, const gp_voronoi *v,
                             double mu, const gp_imc_params *p)
{
    if (!rep) return GP_OK;
    rep->nsize = (size_t)s->ks;
    rep->norient = (size_t)s->kt;
    rep->size_edges = malloc((size_t)(s->ks + 1) * sizeof(double));
    rep->size_target = malloc((size_t)s->ks * sizeof(double));
    rep->size_achieved = malloc((size_t)s->ks * sizeof(double));
    rep->orient_edges = malloc((size_t)(s->kt + 1) * sizeof(double));
    rep->orient_target = malloc((size_t)s->kt * sizeof(double));
    rep->orient_achieved = malloc((size_t)s->kt * sizeof(double));
    if (!rep->size_edges || !rep->size_target || !rep->size_achieved || !rep->orient_edges ||
        !rep->orient_target || !rep->orient_achieved)
        return GP_ERR_NOMEM;
    size_classes(mu, p->cov, s->ks, rep->size_edges, rep->size_target);
    orient_classes(p->mean_deg, p->anisotropy, s->kt, rep->orient_edges, rep->orient_target);
    for (int j = 0; j < s->ks; j++) rep->size_achieved[j] = s->cs[j] / s->n;
    for (int j = 0; j < s->kt; j++) rep->orient_achieved[j] = s->ct[j] / s->n;
    hist_errors(s, &rep->error_size, &rep->error_orient);
    (void)v;
    return GP_OK;
}

gp_status gp_imc_run(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                     const size_t *nhole, size_t nholes, size_t n, const gp_imc_params *p,
                     gp_imc_progress_fn progress, void *user, const volatile int *cancel,
                     gp_voronoi **out, gp_imc_report *rep, gp_error *err)
{
    if (out) *out = NULL;
    if (rep) memset(rep, 0, sizeof *rep);
    if (!out || !p) return gp_error_set(err, GP_ERR_INVALID, "imc: out and params are required");
    if (!outer || nouter < 3) return gp_error_set(err, GP_ERR_INVALID, "imc: outer ring needs >= 3 points");
    if (n < 1 || n > (size_t)INT32_MAX / 4) return gp_error_set(err, GP_ERR_INVALID, "imc: bad cell count %zu", n);
    if (!(p->cov > 0) || !isfinite(p->cov))
        return gp_error_set(err, GP_ERR_INVALID, "imc: cov must be > 0 (got %g)", p->cov);
    if (!(p->anisotropy > 0 && p->anisotropy <= 1))
        return gp_error_set(err, GP_ERR_INVALID, "imc: anisotropy must be in (0, 1] (got %g)", p->anisotropy);
    if (!isfinite(p->mean_deg)) return gp_error_set(err, GP_ERR_INVALID, "imc: mean_deg is not finite");
    if (p->error_kind < 1 || p->error_kind > 3)
        return gp_error_set(err, GP_ERR_INVALID, "imc: error_kind must be 1, 2 or 3 (got %d)", p->error_kind);
    if (!(p->threshold > 0) || !isfinite(p->threshold))
        return gp_error_set(err, GP_ERR_INVALID, "imc: threshold must be > 0 (got %g)", p->threshold);
    if (p->max_steps < 0) return gp_error_set(err, GP_ERR_INVALID, "imc: max_steps must be >= 0");
    if (p->init != 0 && p->init != 1) return gp_error_set(err, GP_ERR_INVALID, "imc: init must be 0 or 1");
    if (p->classes_size < 0 || p->classes_size > 250 || p->classes_orient < 0 || p->classes_orient > 250)
        return gp_error_set(err, GP_ERR_INVALID, "imc: classes must be in 0..250 (0 = automatic)");
    for (size_t h = 0; h < nholes; h++)
        if (!holes || !nhole || !holes[h] || nhole[h] < 3)
            return gp_error_set(err, GP_ERR_INVALID, "imc: hole %zu needs >= 3 points", h);

    gp_status st = GP_OK;
    gp_rng *rng = gp_rng_create(p->seed, 0, err);
    if (!rng) return err ? err->code : GP_ERR_NOMEM;
    gp_vec2 *seeds = malloc(n * sizeof *seeds);
    imc_state S;
    memset(&S, 0, sizeof S);
    gp_voronoi *v = NULL;
    size_t *nbuf = NULL;
    size_t nbcap = 64;
    unsigned char *undo_s = NULL, *undo_t = NULL;
    size_t undocap = 0;
    if (!seeds) {
        st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
        goto done;
    }
    /* --- initial seeds --- */
    if (p->seeds) {
        memcpy(seeds, p->seeds, n * sizeof *seeds);
    } else {
        double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
        for (size_t k = 0; k < nouter; k++) {
            x0 = fmin(x0, outer[k].x);
            x1 = fmax(x1, outer[k].x);
            y0 = fmin(y0, outer[k].y);
            y1 = fmax(y1, outer[k].y);
        }
        if (!(x1 > x0 && y1 > y0) || !isfinite(x1 - x0) || !isfinite(y1 - y0)) {
            st = gp_error_set(err, GP_ERR_INVALID, "imc: container has no area");
            goto done;
        }
        double aout = gp_poly_area(outer, nouter), ahole = 0.0;
        for (size_t h = 0; h < nholes; h++) ahole += gp_poly_area(holes[h], nhole[h]);
        double frac = (aout - ahole) / ((x1 - x0) * (y1 - y0));
        if (!(frac > 1e-9)) {
            st = gp_error_set(err, GP_ERR_INVALID, "imc: container area is not positive");
            goto done;
        }
        /* rejection: expected n / frac draws; give up far beyond that (self-intersecting input) */
        uint64_t tries = 0, limit = (uint64_t)(100.0 * (double)n / frac) + 100000;
        for (size_t i = 0; i < n;) {
            if (++tries > limit) {
                st = gp_error_set(err, GP_ERR_INVALID, "imc: could not place seeds in the container");
                goto done;
            }
            gp_vec2 q;
            if (p->init == 1) {
                q.x = x0 + (x1 - x0) * gp_halton(tries, 2);
                q.y = y0 + (y1 - y0) * gp_halton(tries, 3);
            } else {
                q.x = x0 + (x1 - x0) * gp_rng_uniform(rng);
                q.y = y0 + (y1 - y0) * gp_rng_uniform(rng);
            }
            if (!gp_poly_contains(outer, nouter, q)) continue;
            int inhole = 0;
            for (size_t h = 0; h < nholes && !inhole; h++) inhole = gp_poly_contains(holes[h], nhole[h], q);
            if (inhole) continue;
            seeds[i++] = q;
        }
    }
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    v = gp_voronoi_create(outer, nouter, holes, nhole, nholes, seeds, n, err);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (rep)
        rep->t_init = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    if (!v) {
        st = err ? err->code : GP_ERR_INVALID;
        goto done;
    }
    /* --- classes and targets --- */
    const double SD = gp_voronoi_container_area(v), mu = SD / (double)n;
    S.kind = p->error_kind;
    S.n = (double)n;
    S.ks = pick_classes(p->classes_size, (int)n, p->threshold, p->error_kind, 1, p, mu);
    S.kt = pick_classes(p->classes_orient, (int)n, p->threshold, p->error_kind, 0, p, mu);
    S.se = malloc((size_t)(S.ks + 1) * sizeof(double));
    S.st = malloc((size_t)S.ks * sizeof(double));
    S.te = malloc((size_t)(S.kt + 1) * sizeof(double));
    S.tt = malloc((size_t)S.kt * sizeof(double));
    S.cs = calloc((size_t)S.ks, sizeof(int));
    S.ct = calloc((size_t)S.kt, sizeof(int));
    S.clss = malloc(n);
    S.clst = malloc(n);
    nbuf = malloc(nbcap * sizeof *nbuf);
    if (!S.se || !S.st || !S.te || !S.tt || !S.cs || !S.ct || !S.clss || !S.clst || !nbuf) {
        st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
        goto done;
    }
    size_classes(mu, p->cov, S.ks, S.se, S.st);
    orient_classes(p->mean_deg, p->anisotropy, S.kt, S.te, S.tt);
    double fs = gp_imc_floor(S.st, (size_t)S.ks, n, S.kind), ft = gp_imc_floor(S.tt, (size_t)S.kt, n, S.kind);
    double floor_e = combine(S.kind, fs, ft);
    for (int j = 0; j < S.ks; j++) S.st[j] *= (double)n;
    for (int j = 0; j < S.kt; j++) S.tt[j] *= (double)n;
    S.tscale = S.kt / GP_IMC_PI;
    for (size_t i = 0; i < n; i++) {
        int a = size_class(&S, gp_voronoi_cell_area(v, i)), b = orient_class(&S, gp_voronoi_cell_orientation(v, i));
        S.clss[i] = (unsigned char)a;
        S.clst[i] = (unsigned char)b;
        S.cs[a]++;
        S.ct[b]++;
    }
    double E = current_error(&S), E2nd = sec_error(&S);
    long steps = 0, accepted = 0;
    gp_imc_stop why;
    if (rep) {
        rep->error_initial = E;
        rep->floor = floor_e;
    }
    if (p->threshold < floor_e) {
        why = GP_IMC_STOP_FLOOR;
        st = gp_error_set(err, GP_ERR_INFEASIBLE,
                          "imc: threshold %g is below the error floor %g of %d size x %d orientation "
                          "classes at N = %zu (integer counts); raise it or use fewer classes",
                          p->threshold, floor_e, S.ks, S.kt, n);
        goto report;
    }
    /* --- the loop --- */
    why = GP_IMC_STOP_MAX_STEPS;
    for (;;) {
        if (E <= p->threshold) {
            why = GP_IMC_STOP_THRESHOLD;
            break;
        }
        if (steps >= p->max_steps) break;
        if ((steps % GP_IMC_CANCEL_EVERY) == 0 && cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED)) {
            why = GP_IMC_STOP_CANCELLED;
            break;
        }
        if (steps > 0 && (steps % GP_IMC_PROGRESS_EVERY) == 0 && progress && progress(user, steps, E)) {
            why = GP_IMC_STOP_CANCELLED;
            break;
        }
        steps++;
        /* d1: a seed; d4: a point uniform in its cell and the adjacent cells */
        size_t i = (size_t)gp_rng_uint(rng, n);
        size_t nn = gp_voronoi_neighbours(v, i, nbuf, nbcap);
        if (nn > nbcap) {
            size_t *q = realloc(nbuf, nn * 2 * sizeof *q);
            if (!q) {
                st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
                goto done;
            }
            nbuf = q;
            nbcap = nn * 2;
            nn = gp_voronoi_neighbours(v, i, nbuf, nbcap);
        }
        double tot = gp_voronoi_cell_area(v, i);
        for (size_t k = 0; k < nn; k++) tot += gp_voronoi_cell_area(v, nbuf[k]);
        double u = gp_rng_uniform(rng) * tot, acc = gp_voronoi_cell_area(v, i);
        size_t j = i;
        for (size_t k = 0; k < nn && u >= acc; k++) {
            j = nbuf[k];
            acc += gp_voronoi_cell_area(v, nbuf[k]);
        }
        gp_vec2 q;
        if (gp_voronoi_sample_cell(v, j, u01, rng, &q) != 0) continue;
        /* d5: local update */
        if (gp_voronoi_try_move(v, i, q, NULL) != GP_OK) continue; /* duplicate / degenerate: skip */
        const uint32_t *ch;
        size_t nch = gp_voronoi_changed(v, &ch);
        if (nch > undocap) {
            size_t c = nch * 2;
            unsigned char *a = realloc(undo_s, c), *b = realloc(undo_t, c);
            if (a) undo_s = a;
            if (b) undo_t = b;
            if (!a || !b) {
                gp_voronoi_rollback(v);
                st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
                goto done;
            }
            undocap = c;
        }
        for (size_t k = 0; k < nch; k++) {
            uint32_t c = ch[k];
            int a = size_class(&S, gp_voronoi_cell_area(v, c));
            int b = orient_class(&S, gp_voronoi_cell_orientation(v, c));
            undo_s[k] = (unsigned char)a;
            undo_t[k] = (unsigned char)b;
            S.cs[S.clss[c]]--;
            S.cs[a]++;
            S.ct[S.clst[c]]--;
            S.ct[b]++;
        }
        double En = current_error(&S), En2 = En <= E ? sec_error(&S) : 0.0;
        if (En < E || (En == E && En2 <= E2nd)) {
            for (size_t k = 0; k < nch; k++) {
                S.clss[ch[k]] = undo_s[k];
                S.clst[ch[k]] = undo_t[k];
            }
            gp_voronoi_commit(v);
            E = En;
            E2nd = En2;
            accepted++;
        } else {
            for (size_t k = 0; k < nch; k++) {
                uint32_t c = ch[k];
                S.cs[undo_s[k]]--;
                S.cs[S.clss[c]]++;
                S.ct[undo_t[k]]--;
                S.ct[S.clst[c]]++;
            }
            gp_voronoi_rollback(v);
        }
    }
    if (progress) progress(user, steps, E);
    if (why == GP_IMC_STOP_MAX_STEPS)
        st = gp_error_set(err, GP_ERR_NOT_CONVERGED, "imc: %ld steps without reaching %g (error %g)", steps,
                          p->threshold, E);
    else if (why == GP_IMC_STOP_CANCELLED)
        st = gp_error_set(err, GP_ERR_CANCELLED, "imc: cancelled after %ld steps (error %g)", steps, E);
    else
        gp_error_clear(err);
report:
    if (rep) {
        rep->steps = steps;
        rep->accepted = accepted;
        rep->error = E;
        rep->stop_reason = why;
        if (fill_report(rep, &S, v, mu, p) != GP_OK) {
            gp_imc_report_free(rep);
            st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
            gp_voronoi_destroy(v);
            v = NULL;
            goto done;
        }
    }
    *out = v;
    v = NULL;
done:
    gp_voronoi_destroy(v);
    gp_rng_destroy(rng);
    free(seeds);
    free(S.se);
    free(S.st);
    free(S.te);
    free(S.tt);
    free(S.cs);
    free(S.ct);
    free(S.clss);
    free(S.clst);
    free(nbuf);
    free(undo_s);
    free(undo_t);
    return st;
}
