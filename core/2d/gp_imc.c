/* gp_imc.c -- inverse Monte-Carlo on a locally updated Voronoi tessellation. See gp_imc.h.
 *
 * Hot path per step: one gp_voronoi_try_move (about 9 cells recomputed from the neighbour
 * lists), then for each changed cell: its histogram classes (O(log k) + O(1), integer counts,
 * kept for every kind because the report shows them), and for AD its two order statistics
 * (O(log N) each, gp_adstat.h, exact integer sums). Both are exact functions of the cells, so
 * a rollback restores the error bit for bit and nothing drifts. No allocation per step.
 *
 * Where a step's time goes: recomputing its ~9 cells (each of which really changes), the
 * what-if of the two AD statistics, and for an accepted step their commits. What grows with N
 * is the commits (with the acceptance rate) and the cache misses, hence the memory order:
 * seeds numbered along a Hilbert curve and swept in that order (hilbert_sort, sweep_seed),
 * each cell's data kept in place across moves (gp_voronoi.h "Memory"), the AD statistics in
 * contiguous sorted blocks (gp_adstat.c). A step much cheaper than this would take another
 * kind of update (a Delaunay structure kept by edge flips instead of re-clipping the cells).
 *
 * Threads (gp_imc.h "Threads"): lanes evaluate the next steps at once on replicas of the
 * tessellation. A round lasts as long as its slowest lane (a jump recomputes ~18 cells, a
 * short move ~9), and its settling (rollbacks, the accepted move's statistics and its copies
 * into the replicas) is serial: two threads gain while few steps are accepted, little while
 * many are. Left to gain: splitting the settling between the threads (the two statistics are
 * independent, and each replica could take its copy on its own thread).
 *
 * The profiles, speeds and cache measurements behind these choices: docs/design/imc.md.
 */
#include "gp_imc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_adstat.h"
#include "gp_clock.h"
#include "gp_fit.h"
#include "gp_rng.h"
#include "gp_team.h"

#include <gsl/gsl_rng.h>

#define GP_IMC_PI 3.14159265358979323846
#define GP_IMC_KMAX 20
#define GP_IMC_KMIN 3
#define GP_IMC_PROGRESS_EVERY 4096
/* The cancel flag is read before every step: a step can take tens of milliseconds (a container
 * of 10^4 edges with few cells clips every cell against thousands of edges), so that polling
 * every few hundred steps would answer a cancel seconds late; one relaxed load a step costs
 * nothing next to a step. */
#define GP_IMC_CANCEL_EVERY 1
/* Default AD threshold: the excess A^2 over N's floor at which to stop. A^2 grows like N D^2
 * for a KS distance D, so a fixed threshold keeps D / (1.36 / sqrt(N)) fixed at every N: at
 * 0.05 the cell-area KS is at most 0.2 of its 5 % critical value, as tight as Neper's fitted
 * tessellations at N = 500 and 2,000, and the orientation KS about 0.2 (bench_fit2d; the
 * figures in docs/design/imc.md). */
#define GP_IMC_AD_THRESHOLD 0.05
/* the KS goals a run at the default threshold stops on (gp_imc.h "Stopping"): fractions of the
 * 5 % critical value 1.36 / sqrt(N) (gp_fit_ks_critical); the threshold tightened by 0.7 while
 * they are missed, down to 0.25 of the params' (at 0.05: 0.035, 0.0245, 0.01715), within twice
 * the steps the params' took (ks_budget_spent) */
#define GP_IMC_KS_GOAL_SIZE 0.15
#define GP_IMC_KS_GOAL_ORIENT 0.3
#define GP_IMC_KS_TIGHTEN 0.7
#define GP_IMC_KS_TIGHTEST 0.25
#define GP_IMC_KS_EXTRA 2
/* a default run that falls slowly towards its threshold while its cells already meet the KS
 * goals (the orientations' with a margin) and the COV within GP_IMC_COV_GOAL stops as stalled
 * (slow_at_goals): the rate is taken over at least max(GP_IMC_SLOW_LAG, N) steps */
#define GP_IMC_COV_GOAL 0.01
#define GP_IMC_SLOW_GOAL_ORIENT 0.25 /* the orientations' goal with the areas' margin (0.15 for 0.2) */
#define GP_IMC_SLOW_LAG 8192
/* the orientations' excess counts half in the error and the descent (gp_imc.h "Objective") */
#define GP_IMC_ORIENT_WEIGHT 0.5

void gp_imc_params_defaults(gp_imc_params *p)
{
    if (!p) return;
    memset(p, 0, sizeof *p);
    p->cov = 0.5;
    p->mean_deg = 0.0;
    p->anisotropy = 1.0;
    p->error_kind = GP_IMC_ERROR_AD;
    p->threshold = GP_IMC_AD_THRESHOLD;
    p->ks_goals = 1;
    p->max_steps = 1000000;
    p->init = 0;
    p->seed = 1;
}

double gp_imc_default_threshold(int error_kind)
{
    return error_kind == GP_IMC_ERROR_AD ? GP_IMC_AD_THRESHOLD : 0.002;
}

const char *gp_imc_stop_name(gp_imc_stop s)
{
    switch (s) {
    case GP_IMC_STOP_THRESHOLD: return "threshold";
    case GP_IMC_STOP_MAX_STEPS: return "max_steps";
    case GP_IMC_STOP_FLOOR: return "floor";
    case GP_IMC_STOP_CANCELLED: return "cancelled";
    case GP_IMC_STOP_STALLED: return "stalled";
    case GP_IMC_STOP_SINGLE_CELL: return "single_cell";
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
/* classes, targets and floors                                                                 */

/* area classes of equal probability 1/k (law quantiles); law NULL: edges unset (floors only) */
static void size_classes(const gp_law *law, int k, double *edges, double *target)
{
    for (int j = 0; j <= k && law; j++)
        edges[j] = j == 0 ? 0.0 : j == k ? INFINITY : gp_law_quantile(law, (double)j / k);
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

/* floor of k classes of one histogram */
static double class_floor(const gp_imc_params *p, int is_size, int k, size_t n)
{
    double e[251], t[250]; /* classes are at most 250 (check_params) */
    if (is_size) size_classes(NULL, k, e, t);
    else orient_classes(p->mean_deg, p->anisotropy, k, e, t);
    return gp_imc_floor(t, (size_t)k, n, p->error_kind);
}

/* The class count: the user's, or for E1-E3 the largest whose floor leaves room to converge:
 * the slack N * threshold (in counts) decides how many classes can be matched in practice (at
 * N = 500, E3 = 0.002 allows one count of squared deviation: 5 classes converge in a few
 * thousand steps where 10 stall). For AD the classes only serve the report: N / 25 in 3..20. */
static int pick_classes(const gp_imc_params *p, int is_size, size_t n)
{
    int user = is_size ? p->classes_size : p->classes_orient;
    if (user > 0) return user;
    int kcap = (int)(n / 25 > GP_IMC_KMAX ? GP_IMC_KMAX : n / 25);
    if (p->error_kind == GP_IMC_ERROR_AD) return kcap < GP_IMC_KMIN ? GP_IMC_KMIN : kcap;
    double slack = (double)n * p->threshold;
    double kf = floor(4.5 + 0.5 * slack * slack);
    int kmax = kf > GP_IMC_KMAX ? GP_IMC_KMAX : (int)kf;
    if (kmax > kcap) kmax = kcap;
    if (kmax < GP_IMC_KMIN) kmax = GP_IMC_KMIN;
    for (int k = kmax; k > GP_IMC_KMIN; k--)
        if (class_floor(p, is_size, k, n) <= 0.5 * p->threshold) return k;
    return GP_IMC_KMIN;
}

double gp_imc_reachable_threshold(const gp_imc_params *p, size_t n)
{
    if (!p || n == 0 || p->error_kind == GP_IMC_ERROR_AD) return 0.0;
    int ks = pick_classes(p, 1, n), kt = pick_classes(p, 0, n);
    return combine(p->error_kind, class_floor(p, 1, ks, n), class_floor(p, 0, kt, n));
}

/* ------------------------------------------------------------------------------------------ */
/* the state of a run: classes (all kinds) and the AD statistics                              */

typedef struct imc_state {
    int kind;
    size_t n;
    const gp_law *law;
    double mean_deg, aniso;
    double ulo;                /* orientation u clamp: [ulo, 1 - ulo] */
    double ad_floor;
    double mu, cov_t;          /* mean cell area; the population COV the cells aim at */
    double box[4];             /* container bounding box x0, y0, x1, y1 */
    /* histograms: edges, targets as expected counts N * H, counts, class of each cell */
    int ks, kt;
    double *se, *st, *te, *tt;
    int *cs, *ct;
    unsigned char *clss, *clst;
    double tscale;             /* classes per radian */
    /* AD: one statistic per law, and per cell its current keys and logs (together: a cell's
     * are one cache line, not six) */
    gp_adstat *ads, *adt;
    struct ad_val {
        double sk, sg, sh, tk, tg, th, ang;
    } *adv;
    /* AD: cells whose orientation is a wall's direction (wall_tie_of) */
    double *wall_dir;          /* the container's edge directions, radians, sorted, distinct */
    int nwall;
    long *tie_count;           /* per direction, the cells on it */
    int *tie_of;               /* per cell, its direction's index or -1 */
    long tie_pairs;            /* sum over directions of k (k - 1) */
} imc_state;

static void state_free(imc_state *S)
{
    free(S->se);
    free(S->st);
    free(S->te);
    free(S->tt);
    free(S->cs);
    free(S->ct);
    free(S->clss);
    free(S->clst);
    gp_adstat_destroy(S->ads);
    gp_adstat_destroy(S->adt);
    free(S->adv);
    free(S->wall_dir);
    free(S->tie_count);
    free(S->tie_of);
}

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

/* A cell's contribution to both objectives, computed from its area and orientation. */
typedef struct cell_val {
    unsigned char cs, ct;      /* classes */
    double sk, sg, sh;         /* area: key, ln F, ln(1 - F) */
    double tk, tg, th;         /* orientation: key, ln u, ln(1 - u) */
    double ang;                /* the orientation they come from, radians */
    int tie;                   /* the wall direction it lies on, or -1 */
} cell_val;

/* Walls tie orientations. A cell against a straight wall often has its thinnest side across
 * the wall, and then its orientation is the wall's direction exactly: on a square of N = 500,
 * 15-30 cells at exactly 0 deg. A^2 barely sees such a tie (the values next to it can make up
 * the step within a rank or two: a cost of order k^3 / N^2), but the KS distance, and the eye
 * on a rose diagram, see a step of k / N. So the orientation excess carries
 * sum_d k_d (k_d - 1) / N over the wall directions d with k_d cells on them: N D^2 for the step
 * D ~ k / N, the scale of A^2, and 0 for a lone cell on a direction. Integer counts: exact,
 * and the same whatever the order of the moves. */
#define GP_IMC_TIE_EPS 1e-9

static int wall_tie_of(const imc_state *S, double th)
{
    int lo = 0, hi = S->nwall; /* first direction >= th */
    while (lo < hi) {
        int mid = (lo + hi) >> 1;
        if (S->wall_dir[mid] < th) lo = mid + 1;
        else hi = mid;
    }
    /* the nearest directions, and across the cut of (-pi/2, pi/2] the ends */
    int cand[4] = {lo, lo - 1, 0, S->nwall - 1};
    for (int k = 0; k < 4; k++) {
        if (cand[k] < 0 || cand[k] >= S->nwall) continue;
        double d = fabs(S->wall_dir[cand[k]] - th);
        if (d < GP_IMC_TIE_EPS || GP_IMC_PI - d < GP_IMC_TIE_EPS) return cand[k];
    }
    return -1;
}

static double tie_term(const imc_state *S, long pairs) { return (double)pairs / (double)S->n; }

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static size_t ring_dirs(const gp_vec2 *r, size_t m, double *out)
{
    size_t k = 0;
    for (size_t i = 0; i < m; i++) {
        double dx = r[(i + 1) % m].x - r[i].x, dy = r[(i + 1) % m].y - r[i].y;
        if (dx == 0.0 && dy == 0.0) continue;
        double a = atan2(dy, dx);
        a = a <= -GP_IMC_PI / 2 ? a + GP_IMC_PI : a > GP_IMC_PI / 2 ? a - GP_IMC_PI : a;
        out[k++] = a;
    }
    return k;
}

/* The container's edge directions (sorted, one of each within GP_IMC_TIE_EPS) and the tie
 * counts, every cell on none; for the AD objective only. */
static gp_status walls_init(imc_state *S, const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                            const size_t *nhole, size_t nholes, size_t n, gp_error *err)
{
    size_t m = nouter;
    for (size_t h = 0; h < nholes; h++) m += nhole[h];
    S->wall_dir = malloc((m ? m : 1) * sizeof *S->wall_dir);
    S->tie_of = malloc(n * sizeof *S->tie_of);
    if (!S->wall_dir || !S->tie_of) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
    size_t k = ring_dirs(outer, nouter, S->wall_dir);
    for (size_t h = 0; h < nholes; h++) k += ring_dirs(holes[h], nhole[h], S->wall_dir + k);
    qsort(S->wall_dir, k, sizeof *S->wall_dir, cmp_double);
    size_t d = 0;
    for (size_t i = 0; i < k; i++)
        if (d == 0 || S->wall_dir[i] - S->wall_dir[d - 1] >= GP_IMC_TIE_EPS) S->wall_dir[d++] = S->wall_dir[i];
    if (d > 1 && S->wall_dir[0] + GP_IMC_PI - S->wall_dir[d - 1] < GP_IMC_TIE_EPS) d--; /* -pi/2 is pi/2 */
    S->nwall = (int)d;
    S->tie_count = calloc(d ? d : 1, sizeof *S->tie_count);
    if (!S->tie_count) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
    for (size_t i = 0; i < n; i++) S->tie_of[i] = -1;
    return GP_OK;
}

/* The change of sum_d k_d (k_d - 1) if the nch cells ch[] took the directions nv[].tie
 * (quadratic in nch, a dozen cells a step: no buffer) */
static long dir_change(const imc_state *S, const uint32_t *ch, size_t nch, const cell_val *nv, int d)
{
    long dk = 0;
    for (size_t k = 0; k < nch; k++) dk += (nv[k].tie == d) - (S->tie_of[ch[k]] == d);
    return dk;
}

static int dir_seen(const imc_state *S, const uint32_t *ch, size_t upto, const cell_val *nv, int d)
{
    for (size_t k = 0; k < upto; k++)
        if (nv[k].tie != S->tie_of[ch[k]] && (nv[k].tie == d || S->tie_of[ch[k]] == d)) return 1;
    return 0;
}

static long tie_pairs_if(const imc_state *S, const uint32_t *ch, size_t nch, const cell_val *nv)
{
    long delta = 0;
    for (size_t k = 0; k < nch; k++) {
        int from = S->tie_of[ch[k]], to = nv[k].tie;
        if (from == to) continue;
        for (int side = 0; side < 2; side++) {
            int d = side ? to : from;
            if (d < 0 || dir_seen(S, ch, k, nv, d)) continue;
            long c = S->tie_count[d], c2 = c + dir_change(S, ch, nch, nv, d);
            delta += c2 * (c2 - 1) - c * (c - 1);
        }
    }
    return delta;
}

/* Cell i's contribution; with recorded (its values as S holds them), an orientation equal to
 * the recorded one bit for bit keeps the recorded u and logs: a neighbour of a moved seed keeps
 * its orientation whenever its thinnest side does not touch the edge that changed (canonical
 * vertices: the same lines give the same bits), about half of them. */
static void cell_eval(const imc_state *S, const gp_voronoi *v, size_t i, cell_val *c, int recorded)
{
    double a = gp_voronoi_cell_area(v, i), th = gp_voronoi_cell_orientation(v, i);
    c->cs = (unsigned char)size_class(S, a);
    c->ct = (unsigned char)orient_class(S, th);
    if (S->kind != GP_IMC_ERROR_AD) return;
    c->sk = a;
    gp_law_log_cdf_sf(S->law, a, &c->sg, &c->sh);
    c->ang = th;
    c->tie = wall_tie_of(S, th);
    const struct ad_val *o = &S->adv[i];
    if (recorded && memcmp(&o->ang, &th, sizeof th) == 0) {
        c->tk = o->tk;
        c->tg = o->tg;
        c->th = o->th;
        return;
    }
    /* the orientation window is circular: its cut is not a tail, so u is kept a quarter of a
     * rank step away from 0 and 1 (a cell exactly at the cut would otherwise cost ln 0) */
    double u = gp_orient_cdf(S->mean_deg, S->aniso, th * 180.0 / GP_IMC_PI);
    u = u < S->ulo ? S->ulo : u > 1.0 - S->ulo ? 1.0 - S->ulo : u;
    c->tk = u;
    c->tg = log(u);
    c->th = log1p(-u);
}

/* Makes cell i's recorded contribution c (histogram counts, AD statistics, per-cell arrays). */
static void cell_put(imc_state *S, size_t i, const cell_val *c)
{
    S->cs[S->clss[i]]--;
    S->cs[c->cs]++;
    S->ct[S->clst[i]]--;
    S->ct[c->ct]++;
    S->clss[i] = c->cs;
    S->clst[i] = c->ct;
    if (S->kind != GP_IMC_ERROR_AD) return;
    gp_adstat_set(S->ads, i, c->sk, c->sg, c->sh, c->sk * c->sk);
    gp_adstat_set(S->adt, i, c->tk, c->tg, c->th, 0.0);
    S->adv[i] = (struct ad_val){c->sk, c->sg, c->sh, c->tk, c->tg, c->th, c->ang};
    if (S->tie_of[i] >= 0) S->tie_pairs -= 2 * --S->tie_count[S->tie_of[i]];
    if (c->tie >= 0) S->tie_pairs += 2 * S->tie_count[c->tie]++;
    S->tie_of[i] = c->tie;
}

/* cell i's recorded contribution */
static void cell_get(const imc_state *S, size_t i, cell_val *c)
{
    c->cs = S->clss[i];
    c->ct = S->clst[i];
    if (S->kind != GP_IMC_ERROR_AD) return;
    const struct ad_val *a = &S->adv[i];
    c->sk = a->sk;
    c->sg = a->sg;
    c->sh = a->sh;
    c->tk = a->tk;
    c->tg = a->tg;
    c->th = a->th;
    c->ang = a->ang;
    c->tie = S->tie_of[i];
}

static void hist_errors(const imc_state *s, int kind, double *es, double *et)
{
    double a = 0.0, b = 0.0, n = (double)s->n;
    for (int j = 0; j < s->ks; j++) {
        double d = s->cs[j] - s->st[j];
        a = kind == 2 ? fmax(a, fabs(d)) : a + d * d;
    }
    for (int j = 0; j < s->kt; j++) {
        double d = s->ct[j] - s->tt[j];
        b = kind == 2 ? fmax(b, fabs(d)) : b + d * d;
    }
    *es = (kind == 2 ? a : sqrt(a)) / n;
    *et = (kind == 2 ? b : sqrt(b)) / n;
}

/* N (COV / COV_t - 1)^2: the second moment, which the tails carry. A^2 alone leaves the
 * largest cells of a wide law short (COV 1.2 at N = 500: 6-11 % low). COV_t is the law's COV,
 * as the sample COV (n - 1) the user measures: not that of the law's N quantiles, which is
 * below it at small N (-3.5 % at N = 500, COV 1.2: the largest quantile is the 1 - 1/2N one);
 * the largest cells take up the difference at little cost in A^2 (docs/design/imc.md). */
double gp_imc_cov_term(size_t n, double mu, double cov_t, double sum_sq)
{
    double nn = (double)n, var = sum_sq / nn - mu * mu;
    double c = sqrt(var > 0 ? var : 0) / mu, r = c / cov_t - 1.0;
    return nn * r * r;
}

static double cov_term_of(const imc_state *s, double sum_sq)
{
    return gp_imc_cov_term(s->n, s->mu, s->cov_t, sum_sq);
}

static void ad_errors(const imc_state *s, double *es, double *et)
{
    *es = gp_adstat_a2(s->ads) - s->ad_floor + cov_term_of(s, gp_adstat_sum_extra(s->ads));
    *et = gp_adstat_a2(s->adt) - s->ad_floor + tie_term(s, s->tie_pairs);
}

/* The error of the run's kind (reported, compared with the threshold) and the value a move
 * must not increase: for AD the sum of both excesses; for E1-E3 the error itself, with the
 * sum of squared count deviations as a tie-breaker (plateaus of the integer histograms). */
typedef struct objective {
    double error, descent, tie;
} objective;

static objective evaluate(const imc_state *s)
{
    objective o;
    double a, b;
    if (s->kind == GP_IMC_ERROR_AD) {
        ad_errors(s, &a, &b);
        b *= GP_IMC_ORIENT_WEIGHT;
        o.error = a > b ? a : b;
        o.descent = a + b;
        o.tie = 0.0;
        return o;
    }
    hist_errors(s, s->kind, &a, &b);
    o.error = combine(s->kind, a, b);
    o.descent = o.error;
    double t = 0.0;
    for (int j = 0; j < s->ks; j++) t += (s->cs[j] - s->st[j]) * (s->cs[j] - s->st[j]);
    for (int j = 0; j < s->kt; j++) t += (s->ct[j] - s->tt[j]) * (s->ct[j] - s->tt[j]);
    o.tie = t;
    return o;
}

static int not_worse(const objective *n, const objective *o)
{
    return n->descent < o->descent || (n->descent == o->descent && n->tie <= o->tie);
}

/* Classes, targets and the AD statistics for the tessellation v; returns the E1-E3 floor. */
static int cancel_raised(const volatile int *cancel);

static gp_status state_init(imc_state *S, const gp_imc_params *p, const gp_law *law,
                            const gp_voronoi *v, size_t n, const volatile int *cancel,
                            double *floor_e, gp_error *err)
{
    S->kind = p->error_kind;
    S->n = n;
    S->law = law;
    S->mean_deg = p->mean_deg;
    S->aniso = p->anisotropy;
    S->ulo = 0.25 / (double)n;
    S->ks = pick_classes(p, 1, n);
    S->kt = pick_classes(p, 0, n);
    S->se = malloc((size_t)(S->ks + 1) * sizeof(double));
    S->st = malloc((size_t)S->ks * sizeof(double));
    S->te = malloc((size_t)(S->kt + 1) * sizeof(double));
    S->tt = malloc((size_t)S->kt * sizeof(double));
    S->cs = calloc((size_t)S->ks, sizeof(int));
    S->ct = calloc((size_t)S->kt, sizeof(int));
    S->clss = calloc(n, 1);
    S->clst = calloc(n, 1);
    int ok = S->se && S->st && S->te && S->tt && S->cs && S->ct && S->clss && S->clst;
    if (ok && S->kind == GP_IMC_ERROR_AD) {
        S->ads = gp_adstat_create(n, err);
        S->adt = gp_adstat_create(n, err);
        S->adv = malloc(n * sizeof *S->adv);
        ok = S->ads && S->adt && S->adv;
        S->ad_floor = gp_adstat_floor(n);
        S->mu = gp_law_mean(law);
        S->cov_t = gp_law_cov(law) * (n > 1 ? sqrt((double)(n - 1) / (double)n) : 1.0);
    }
    if (!ok) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
    size_classes(law, S->ks, S->se, S->st);
    orient_classes(p->mean_deg, p->anisotropy, S->kt, S->te, S->tt);
    double fs = gp_imc_floor(S->st, (size_t)S->ks, n, S->kind);
    double ft = gp_imc_floor(S->tt, (size_t)S->kt, n, S->kind);
    *floor_e = S->kind == GP_IMC_ERROR_AD ? 0.0 : combine(S->kind, fs, ft);
    for (int j = 0; j < S->ks; j++) S->st[j] *= (double)n;
    for (int j = 0; j < S->kt; j++) S->tt[j] *= (double)n;
    S->tscale = S->kt / GP_IMC_PI;
    S->cs[0] = S->ct[0] = (int)n; /* every cell starts in class 0; cell_put moves it */
    for (size_t i = 0; i < n; i++) {
        /* seconds in all at 10^6 cells (the AD statistics), so poll the flag */
        if ((i + 1) % 4096 == 0 && cancel_raised(cancel))
            return gp_error_set(err, GP_ERR_CANCELLED, "imc: cancelled while evaluating the cells");
        cell_val c;
        cell_eval(S, v, i, &c, 0);
        cell_put(S, i, &c);
    }
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* seeds                                                                                       */

/* The outer ring's bounding box {x0, y0, x1, y1}, passing over NaN coordinates (fmin / fmax:
 * place_seeds' area checks then refuse such a container; gp_poly_bbox would stop at them). */
static void outer_box(const gp_vec2 *outer, size_t nouter, double box[4])
{
    box[0] = box[1] = INFINITY;
    box[2] = box[3] = -INFINITY;
    for (size_t k = 0; k < nouter; k++) {
        box[0] = fmin(box[0], outer[k].x);
        box[1] = fmin(box[1], outer[k].y);
        box[2] = fmax(box[2], outer[k].x);
        box[3] = fmax(box[3], outer[k].y);
    }
}

/* The position of grid cell (x, y) along a Hilbert curve of order 16 (a 65536 x 65536 grid;
 * the classic xy2d, starting at (0, 0) and ending at (65535, 0)): at each level, the
 * quadrant's rank on the curve, then the rotation that brings the quadrant's sub-curve back to
 * the base orientation (flip when in the lower-right quadrant, transpose when in a lower one).
 * test_imc checks it against Warren's state-table form. */
static uint64_t hilbert_d(uint32_t x, uint32_t y)
{
    const uint32_t side = 1u << 16;
    uint64_t d = 0;
    for (uint32_t s = side / 2; s > 0; s /= 2) {
        uint32_t rx = (x & s) != 0, ry = (y & s) != 0;
        d += (uint64_t)s * s * ((3 * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = side - 1 - x;
                y = side - 1 - y;
            }
            uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return d;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Renumbers the seeds along a Hilbert curve over the box (one scale for both axes, so that the
 * curve's cells are square). Why: an IMC step recomputes a random cell and its ~9 neighbours;
 * with the seeds in draw order these are scattered over every per-cell array (cells, neighbour
 * lists, bins, AD values), and at 10^5-10^6 cells each step would miss cache many times
 * (docs/design/imc.md). Along the curve, neighbours have nearby indices, and their data,
 * allocated in index order, lies together.
 * The key is (curve index << 32 | draw index): all keys differ, so the order is unique and
 * the same on every machine (the draw index breaks ties between seeds in one curve cell).
 * Returns -1 when out of memory. */
static int hilbert_sort(gp_vec2 *seeds, size_t n, const double *box)
{
    uint64_t *key = malloc(n * sizeof *key);
    gp_vec2 *tmp = malloc(n * sizeof *tmp);
    if (!key || !tmp) {
        free(key);
        free(tmp);
        return -1;
    }
    double side = fmax(box[2] - box[0], box[3] - box[1]), scale = 65536.0 / side;
    for (size_t i = 0; i < n; i++) {
        double fx = (seeds[i].x - box[0]) * scale, fy = (seeds[i].y - box[1]) * scale;
        uint32_t x = fx >= 65535.0 ? 65535u : fx > 0.0 ? (uint32_t)fx : 0u;
        uint32_t y = fy >= 65535.0 ? 65535u : fy > 0.0 ? (uint32_t)fy : 0u;
        key[i] = hilbert_d(x, y) << 32 | (uint64_t)i;
    }
    qsort(key, n, sizeof *key, cmp_u64);
    memcpy(tmp, seeds, n * sizeof *tmp);
    for (size_t k = 0; k < n; k++) seeds[k] = tmp[key[k] & 0xffffffffu];
    free(key);
    free(tmp);
    return 0;
}

static gp_status place_seeds(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                             const size_t *nhole, size_t nholes, size_t n, const gp_imc_params *p,
                             const double *box, gp_rng *rng, const volatile int *cancel,
                             gp_vec2 *seeds, gp_error *err)
{
    if (p->seeds) {
        memcpy(seeds, p->seeds, n * sizeof *seeds);
        return GP_OK;
    }
    const double x0 = box[0], y0 = box[1], x1 = box[2], y1 = box[3];
    if (!(x1 > x0 && y1 > y0) || !isfinite(x1 - x0) || !isfinite(y1 - y0))
        return gp_error_set(err, GP_ERR_INVALID, "imc: container has no area");
    double aout = gp_poly_area(outer, nouter), ahole = 0.0;
    for (size_t h = 0; h < nholes; h++) ahole += gp_poly_area(holes[h], nhole[h]);
    double frac = (aout - ahole) / ((x1 - x0) * (y1 - y0));
    if (!(frac > 1e-9)) return gp_error_set(err, GP_ERR_INVALID, "imc: container area is not positive");
    /* rejection: expected n / frac draws; give up far beyond that (self-intersecting input) */
    uint64_t tries = 0, limit = (uint64_t)(100.0 * (double)n / frac) + 100000;
    for (size_t i = 0; i < n;) {
        if (++tries > limit) return gp_error_set(err, GP_ERR_INVALID, "imc: could not place seeds in the container");
        if ((tries % 4096) == 0 && cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED))
            return gp_error_set(err, GP_ERR_CANCELLED, "imc: cancelled while placing seeds");
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
        if (!inhole) seeds[i++] = q;
    }
    if (hilbert_sort(seeds, n, box) != 0) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
    return GP_OK;
}

static gp_status check_params(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                              const size_t *nhole, size_t nholes, size_t n, const gp_imc_params *p,
                              gp_error *err)
{
    if (!outer || nouter < 3) return gp_error_set(err, GP_ERR_INVALID, "imc: outer ring needs >= 3 points");
    if (n < 1 || n > (size_t)INT32_MAX / 4) return gp_error_set(err, GP_ERR_INVALID, "imc: bad cell count %zu", n);
    if (!p->law && (!(p->cov >= GP_LAW_COV_MIN) || !isfinite(p->cov)))
        return gp_error_set(err, GP_ERR_INVALID, "imc: cov must be >= %g (got %g)", GP_LAW_COV_MIN, p->cov);
    if (!(p->anisotropy > 0 && p->anisotropy <= 1))
        return gp_error_set(err, GP_ERR_INVALID, "imc: anisotropy must be in (0, 1] (got %g)", p->anisotropy);
    if (!isfinite(p->mean_deg)) return gp_error_set(err, GP_ERR_INVALID, "imc: mean_deg is not finite");
    if (p->error_kind < 1 || p->error_kind > GP_IMC_ERROR_AD)
        return gp_error_set(err, GP_ERR_INVALID, "imc: error_kind must be 1..4 (got %d)", p->error_kind);
    if (!(p->threshold > 0) || !isfinite(p->threshold))
        return gp_error_set(err, GP_ERR_INVALID, "imc: threshold must be > 0 (got %g)", p->threshold);
    if (p->max_steps < 0) return gp_error_set(err, GP_ERR_INVALID, "imc: max_steps must be >= 0");
    if (p->init != 0 && p->init != 1) return gp_error_set(err, GP_ERR_INVALID, "imc: init must be 0 or 1");
    if (p->classes_size < 0 || p->classes_size > 250 || p->classes_orient < 0 || p->classes_orient > 250)
        return gp_error_set(err, GP_ERR_INVALID, "imc: classes must be in 0..250 (0 = automatic)");
    for (size_t h = 0; h < nholes; h++)
        if (!holes || !nhole || !holes[h] || nhole[h] < 3)
            return gp_error_set(err, GP_ERR_INVALID, "imc: hole %zu needs >= 3 points", h);
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* the loop                                                                                    */

typedef struct step_buf {
    size_t *nb;
    size_t nbcap;
    size_t cap;                /* room of the arrays below, in changed cells */
    cell_val *undo;            /* the changed cells' contributions before the move */
    cell_val *nv;              /* ... and after it */
    size_t *ids, *tids;        /* gp_adstat_a2_if arguments (areas, orientations) */
    double *sk, *sg, *sh, *sx, *tk, *tg, *th, *tx;
} step_buf;

static void step_buf_free(step_buf *b)
{
    free(b->nb);
    free(b->undo);
    free(b->nv);
    free(b->ids);
    free(b->tids);
    double **d[8] = {&b->sk, &b->sg, &b->sh, &b->sx, &b->tk, &b->tg, &b->th, &b->tx};
    for (int k = 0; k < 8; k++) free(*d[k]);
}

static int step_buf_grow(step_buf *b, size_t need)
{
    size_t c = need * 2;
    cell_val *u = realloc(b->undo, c * sizeof *u);
    if (u) b->undo = u;
    cell_val *w = realloc(b->nv, c * sizeof *w);
    if (w) b->nv = w;
    size_t *id = realloc(b->ids, c * sizeof *id);
    if (id) b->ids = id;
    size_t *tid = realloc(b->tids, c * sizeof *tid);
    if (tid) b->tids = tid;
    int ok = u && w && id && tid;
    double **d[8] = {&b->sk, &b->sg, &b->sh, &b->sx, &b->tk, &b->tg, &b->th, &b->tx};
    for (int k = 0; k < 8; k++) {
        double *x = realloc(*d[k], c * sizeof *x);
        if (x) *d[k] = x;
        ok = ok && x;
    }
    if (ok) b->cap = c;
    return ok ? 0 : -1;
}

static double u01(void *r) { return gsl_rng_uniform((gsl_rng *)r); }

/* d1: the seed step `step` moves. The paper picks one at random; here SWEEP_HEADS heads run
 * along the seeds' order, evenly spaced, and step s takes head s mod SWEEP_HEADS, which then
 * moves on by one seed: every seed in turn, once a pass of n steps (exactly when
 * SWEEP_HEADS divides n, else each seed SWEEP_HEADS times in SWEEP_HEADS passes). Why: with the
 * seeds along a Hilbert curve (hilbert_sort), a head's consecutive steps touch neighbouring
 * cells, so the cells a step reads are in the nearest caches from the steps just before,
 * where a random pick at large N finds them in none; and a sweep leaves no seed untried for a
 * pass, where random picks leave e^-1 of them. Several heads, not one: the steps of one round
 * of lanes (gp_imc.h "Threads") are consecutive, and on one head their cells would be
 * neighbours, their footprints clashing (8 heads: the lanes of up to 4 threads on distinct
 * heads). The sweep reaches the thresholds as random picks do, in fewer steps
 * (docs/design/imc.md), and leaves no trace in space (test_imc "even in space"). */
#define SWEEP_HEADS 8

static size_t sweep_seed(long step, size_t n)
{
    uint64_t s = (uint64_t)step, h = s % SWEEP_HEADS, p = s / SWEEP_HEADS;
    return (size_t)((h * (uint64_t)n / SWEEP_HEADS + p) % n);
}

/* d4: a point q uniform in the union of seed i's cell and its neighbours' (a cell chosen by
 * area). Returns 0 on success, 1 to skip this step, -1 out of memory. */
static int propose(const gp_voronoi *v, gsl_rng *rng, size_t i, step_buf *b, gp_vec2 *q)
{
    size_t nn = gp_voronoi_neighbours(v, i, b->nb, b->nbcap);
    if (nn > b->nbcap) {
        size_t *t = realloc(b->nb, nn * 2 * sizeof *t);
        if (!t) return -1;
        b->nb = t;
        b->nbcap = nn * 2;
        nn = gp_voronoi_neighbours(v, i, b->nb, b->nbcap);
    }
    double tot = gp_voronoi_cell_area(v, i);
    for (size_t k = 0; k < nn; k++) tot += gp_voronoi_cell_area(v, b->nb[k]);
    double u = gsl_rng_uniform(rng) * tot, acc = gp_voronoi_cell_area(v, i);
    size_t j = i;
    for (size_t k = 0; k < nn && u >= acc; k++) {
        j = b->nb[k];
        acc += gp_voronoi_cell_area(v, b->nb[k]);
    }
    return gp_voronoi_sample_cell(v, j, u01, rng, q) != 0 ? 1 : 0;
}

/* A point uniform in the bounding box x0, y0, x1, y1: two draws (warm_ahead draws them again) */
static gp_vec2 box_point(gsl_rng *rng, const double *box)
{
    gp_vec2 q;
    q.x = box[0] + (box[2] - box[0]) * gsl_rng_uniform(rng);
    q.y = box[1] + (box[3] - box[1]) * gsl_rng_uniform(rng);
    return q;
}

/* A point uniform in the container (rejection in its bounding box; 1 when 64 draws missed). */
static int propose_anywhere(const gp_voronoi *v, gsl_rng *rng, const double *box, gp_vec2 *q)
{
    for (int t = 0; t < 64; t++) {
        *q = box_point(rng, box);
        if (gp_voronoi_contains(v, *q)) return 0;
    }
    return 1;
}

/* The AD moves: the paper's (40 %), a short move towards a point of the seed's own cell
 * (40 %), or a jump anywhere in the container (20 %). The paper's move alone jumps too far to
 * be accepted near convergence, short moves fine-tune, and jumps take a seed out of a crowd to
 * another region: without them the few largest cells of a wide law are never formed
 * (docs/design/imc.md). */
#define GP_IMC_JUMP_FROM 0.8 /* a step whose first draw is at least this jumps */

static int propose_ad(const gp_voronoi *v, gsl_rng *rng, size_t i, step_buf *b, const double *box,
                      gp_vec2 *q)
{
    double r = gsl_rng_uniform(rng);
    if (r < 0.4) return propose(v, rng, i, b, q);
    if (r >= GP_IMC_JUMP_FROM) return propose_anywhere(v, rng, box, q);
    if (gp_voronoi_sample_cell(v, i, u01, rng, q) != 0) return 1;
    gp_vec2 s = gp_voronoi_seed(v, i);
    double lam = gsl_rng_uniform(rng);
    q->x = s.x + lam * (q->x - s.x);
    q->y = s.y + lam * (q->y - s.y);
    return 0;
}

/* The objective the run would have with the changed cells' new contributions nv[], judged
 * without changing the AD statistics (gp_adstat_a2_if). Cells whose orientation values did
 * not change are left out of the orientations' what-if: its sums are exact integers, so an
 * element set to its own value changes nothing, bit for bit, and costs two rank queries. */
static objective evaluate_ad_if(const imc_state *S, const uint32_t *ch, size_t nch, const cell_val *nv,
                                step_buf *b)
{
    size_t nt = 0;
    for (size_t k = 0; k < nch; k++) {
        b->ids[k] = ch[k];
        b->sk[k] = nv[k].sk;
        b->sg[k] = nv[k].sg;
        b->sh[k] = nv[k].sh;
        b->sx[k] = nv[k].sk * nv[k].sk;
        const struct ad_val *o = &S->adv[ch[k]];
        if (nv[k].tk == o->tk && nv[k].tg == o->tg && nv[k].th == o->th) continue;
        b->tids[nt] = ch[k];
        b->tk[nt] = nv[k].tk;
        b->tg[nt] = nv[k].tg;
        b->th[nt] = nv[k].th;
        b->tx[nt++] = 0.0;
    }
    double sx;
    double as = gp_adstat_a2_if(S->ads, nch, b->ids, b->sk, b->sg, b->sh, b->sx, &sx);
    double at = gp_adstat_a2_if(S->adt, nt, b->tids, b->tk, b->tg, b->th, b->tx, NULL);
    double es = as - S->ad_floor + cov_term_of(S, sx);
    double et = at - S->ad_floor + tie_term(S, S->tie_pairs + tie_pairs_if(S, ch, nch, nv));
    et *= GP_IMC_ORIENT_WEIGHT;
    objective o = {es > et ? es : et, es + et, 0.0};
    return o;
}

/* ------------------------------------------------------------------------------------------ */
/* lanes: steps evaluated in parallel                                                          */

/* Each step draws from a stream of its own: GSL's taus2, seeded from (seed, step) -- so that
 * what a step proposes depends on the tessellation and its number only, not on how many
 * numbers the steps before it drew (a proposal's rejection sampling draws a variable count).
 * That is what lets a lane evaluate step s + 1 before step s is decided: when s is refused
 * (most steps near the end), s + 1 was evaluated on the right
 * tessellation and stands. Stream 0 of the run's seed places the seeds (MT19937); step s uses
 * (seed, s) through gp_rng_derive_key, of which taus2 keeps 32 bits. */
static void step_rng_set(gsl_rng *r, uint64_t seed, long step)
{
    uint32_t key[4];
    gp_rng_derive_key(seed, (uint64_t)step, key);
    gsl_rng_set(r, key[0] ^ key[2]);
}

enum { LANE_SKIP, LANE_REJECT, LANE_ACCEPT, LANE_SERIAL, LANE_NOMEM };

/* One lane: a replica of the tessellation (lane 0's is the run's own), its buffers, and what
 * it made of its step: an outcome, and with a pending move the changed cells' new values. */
typedef struct lane {
    gp_voronoi *v;
    gsl_rng *rng;
    step_buf b;
    long step;
    int out, pending;
    int redo;                  /* settle_round: evaluated on a tessellation that has changed */
    objective nw;
    uint32_t *fp;              /* the pending move's footprint (gp_voronoi_footprint) */
    size_t nfp, fpcap;
} lane;

/* d1-d5 for lane L's step, judged against cur without changing anything shared (S and the AD
 * statistics are only read): the move stays pending in L's replica. A step that cannot be
 * judged so (E1-E3 change their counts; more changed cells than a what-if takes) is left
 * pending as LANE_SERIAL for judge_serial. Thread-safe against other lanes. */
static void lane_eval(lane *L, const imc_state *S, uint64_t seed, const objective *cur)
{
    step_rng_set(L->rng, seed, L->step);
    size_t i = sweep_seed(L->step, S->n);
    gp_vec2 q;
    int r = S->kind == GP_IMC_ERROR_AD ? propose_ad(L->v, L->rng, i, &L->b, S->box, &q)
                                       : propose(L->v, L->rng, i, &L->b, &q);
    L->pending = 0;
    L->out = r < 0 ? LANE_NOMEM : LANE_SKIP;
    if (r != 0) return;
    if (gp_voronoi_try_move(L->v, i, q, NULL) != GP_OK) return; /* duplicate / degenerate */
    L->pending = 1;
    const uint32_t *ch;
    size_t nch = gp_voronoi_changed(L->v, &ch);
    if (nch > L->b.cap && step_buf_grow(&L->b, nch) != 0) {
        L->out = LANE_NOMEM;
        return;
    }
    if (S->kind != GP_IMC_ERROR_AD || nch > GP_ADSTAT_IF_MAX) {
        L->out = LANE_SERIAL;
        return;
    }
    for (size_t k = 0; k < nch; k++) cell_eval(S, L->v, ch[k], &L->b.nv[k], 1);
    L->nw = evaluate_ad_if(S, ch, nch, L->b.nv, &L->b);
    L->out = not_worse(&L->nw, cur) ? LANE_ACCEPT : LANE_REJECT;
}

/* A LANE_SERIAL step judged by changing the statistics (kept when accepted, put back when
 * not); only while no lane runs. */
static int judge_serial(imc_state *S, lane *L, const objective *cur, double cap)
{
    const uint32_t *ch;
    size_t nch = gp_voronoi_changed(L->v, &ch);
    for (size_t k = 0; k < nch; k++) {
        cell_get(S, ch[k], &L->b.undo[k]);
        cell_eval(S, L->v, ch[k], &L->b.nv[k], 1);
    }
    for (size_t k = 0; k < nch; k++) cell_put(S, ch[k], &L->b.nv[k]);
    L->nw = evaluate(S);
    if (not_worse(&L->nw, cur) && L->nw.error <= cap) return LANE_ACCEPT;
    for (size_t k = nch; k-- > 0;) cell_put(S, ch[k], &L->b.undo[k]);
    return LANE_REJECT;
}

static int cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED);
}

typedef struct run_out {
    long steps, accepted;
    gp_imc_stop why;
    int at_goals;              /* stalled by slow_at_goals */
    double error0;             /* the error at the first progress report; < 0 before */
} run_out;

/* One progress report (gp_progress.h): phase "imc", the steps and error, and as the fraction
 * how far log(error) has come from its value at the first report towards log(threshold). */
static int report(gp_progress_fn progress, void *user, const gp_imc_params *p, run_out *ro,
                  double error)
{
    if (ro->error0 < 0.0) ro->error0 = error;
    double frac = 0.0;
    if (error <= p->threshold)
        frac = 1.0;
    else if (ro->error0 > p->threshold && error > 0.0)
        frac = fmin(1.0, fmax(0.0, log(ro->error0 / error) / log(ro->error0 / p->threshold)));
    gp_progress r = {.phase = "imc", .fraction = frac, .phase_fraction = frac, .steps = ro->steps,
                     .error = error};
    return progress(user, &r);
}

long gp_imc_stall_window(size_t n) { return 20000 + 50 * (long)(n < 100000000 ? n : 100000000); }

/* stop reasons checked before each step; GP_IMC_STOP_THRESHOLD means "go on" here */
static gp_imc_stop stop_check(const imc_state *S, const gp_imc_params *p, const objective *cur,
                              const run_out *ro, double *best, long *best_step)
{
    if (S->n == 1) return GP_IMC_STOP_SINGLE_CELL;
    if (ro->steps >= p->max_steps) return GP_IMC_STOP_MAX_STEPS;
    if (S->kind == GP_IMC_ERROR_AD) {
        if (cur->descent < *best * (1.0 - 1e-2)) {
            *best = cur->descent;
            *best_step = ro->steps;
        } else if (ro->steps - *best_step > gp_imc_stall_window(S->n)) {
            return GP_IMC_STOP_STALLED;
        }
    }
    return GP_IMC_STOP_THRESHOLD;
}

/* The run as the lanes see it: lane t of a round evaluates step steps + 1 + t. */
typedef struct run_ctx {
    imc_state *S;
    const gp_imc_params *p;
    gp_progress_fn progress;
    void *user;
    const volatile int *cancel;
    gp_team *team;
    lane *lanes;
    int nl, nt, nr;            /* lanes, threads, lanes this round (thread t evaluates lanes t,
                                * t + nt, ... < nr) */
    double acc_rate;           /* recent fraction of steps accepted (a moving average) */
    uint32_t *wmark, mark;     /* per cell: the mark of the last accepted move that changed it */
    int alone;                 /* run_round: this stretch runs on the caller alone */
    int stretch;               /* 0 probe alone, 1 probe the team, 2 the faster of the two */
    long stretch_end;          /* the step the stretch ends at */
    long stretch_s0;           /* its first step and start time */
    double stretch_t0, rate[2];/* steps/s measured alone and on the team */
    objective cur;
    run_out ro;
    double best;
    long best_step;
    double thr;                /* the threshold in force: p->threshold, tightened by ks_short */
    long first_at;             /* the step the params' threshold was first reached at (or -1) */
    double cap;                /* from first_at on, p->threshold: no accepted move takes the
                                * error back above it (the moves are judged on the descent,
                                * which can fall while the error, a max, rises) */
    long slow_at;              /* slow_at_goals: the step of the error the rate is taken from */
    double slow_error;         /* (or -1: none yet) and that error */
    gsl_rng *warm_rng;         /* warm_ahead (NULL: not at this N) */
    long warm_next;            /* the first step whose jump it has not warmed */
} run_ctx;

static void round_fn(void *ctx, int tid)
{
    run_ctx *C = ctx;
    for (int t = tid; t < C->nr; t += C->nt) lane_eval(&C->lanes[t], C->S, C->p->seed, &C->cur);
}

/* Alone or on the team: other work on the machine can keep the helpers from their CPUs, and a
 * round then waits for them, so that two threads can run slower than one. So the run measures
 * both: 2,048 steps alone, 2,048 on the team, then 65,536 steps on the faster, and again; on
 * an idle machine the probes cost little (docs/design/imc.md). Nothing but the speed depends
 * on this. */
#define GP_IMC_PROBE_STEPS 2048
#define GP_IMC_STRETCH_STEPS 65536

static void next_stretch(run_ctx *C)
{
    double now = gp_clock_seconds();
    if (C->stretch < 2) {
        double dt = now - C->stretch_t0;
        C->rate[C->stretch] = dt > 0 ? (double)(C->ro.steps - C->stretch_s0) / dt : 0.0;
    }
    C->stretch = (C->stretch + 1) % 3;
    C->alone = C->stretch == 0 || (C->stretch == 2 && C->rate[0] > C->rate[1]);
    C->stretch_end = C->ro.steps + (C->stretch < 2 ? GP_IMC_PROBE_STEPS : GP_IMC_STRETCH_STEPS);
    C->stretch_s0 = C->ro.steps;
    C->stretch_t0 = now;
}

static void run_round(run_ctx *C)
{
    if (C->alone)
        lane_eval(&C->lanes[0], C->S, C->p->seed, &C->cur);
    else
        gp_team_run(C->team, round_fn, C);
}

/* The KS distance of the n values u (sorted here) to the uniform law. */
static double ks_uniform(double *u, size_t n)
{
    qsort(u, n, sizeof *u, cmp_double);
    return gp_fit_ks_uniform(u, n);
}

/* 1 when the cells' KS distances, from the values the AD statistics hold, meet the goals the
 * default threshold stands for (gp_imc.h "Stopping"), the orientations' as given; 0 when either
 * misses; -1 when the check cannot be made (out of memory). AD runs of n >= 2 only. */
static int ks_goals_met(const imc_state *S, double goal_orient)
{
    double *u = malloc(S->n * sizeof *u), crit = gp_fit_ks_critical(S->n);
    if (!u) return -1;
    for (size_t i = 0; i < S->n; i++) u[i] = exp(S->adv[i].sg);
    int met = ks_uniform(u, S->n) <= GP_IMC_KS_GOAL_SIZE * crit;
    for (size_t i = 0; met && i < S->n; i++) u[i] = S->adv[i].tk;
    met = met && ks_uniform(u, S->n) <= goal_orient * crit;
    free(u);
    return met;
}

/* 1 when the run is at its threshold but the cells' KS distances miss the goals that threshold
 * stands for; 0 when they meet them, when the params ask for no check, or when it cannot be
 * made (out of memory: the run stops as it would without it). */
static int ks_short(const imc_state *S, const gp_imc_params *p)
{
    if (!p->ks_goals || S->kind != GP_IMC_ERROR_AD || S->n < 2) return 0;
    return ks_goals_met(S, GP_IMC_KS_GOAL_ORIENT) == 0;
}

/* The cell areas' population COV within GP_IMC_COV_GOAL of the one aimed at: the COV term of
 * the area excess, n (COV / cov_t - 1)^2, from the sum of squared areas the statistic keeps. */
static int cov_goal_met(const imc_state *S)
{
    double n = (double)S->n;
    return cov_term_of(S, gp_adstat_sum_extra(S->ads)) <= n * GP_IMC_COV_GOAL * GP_IMC_COV_GOAL;
}

/* At the threshold in force: 1 to stop; 0 to go on to a tighter one, while the KS goals are
 * missed and the threshold has room (down to GP_IMC_KS_TIGHTEST of the params'). */
static int at_threshold(run_ctx *C)
{
    if (C->first_at < 0) {
        C->first_at = C->ro.steps;
        C->cap = C->p->threshold;
    }
    if (C->thr * GP_IMC_KS_TIGHTEN < C->p->threshold * GP_IMC_KS_TIGHTEST || !ks_short(C->S, C->p)) return 1;
    C->thr *= GP_IMC_KS_TIGHTEN;
    return 0;
}

/* Past the params' threshold the KS goals get GP_IMC_KS_EXTRA times the steps it took to get
 * there, at least one sweep: a tightened threshold can be out of reach, and the stall window
 * alone would let such a run go on for long. */
static int ks_budget_spent(const run_ctx *C)
{
    if (C->first_at < 0) return 0;
    long extra = GP_IMC_KS_EXTRA * C->first_at, sweep = (long)C->S->n;
    return C->ro.steps - C->first_at > (extra > sweep ? extra : sweep);
}

/* A default run before its threshold, at a progress report: 1 when the error, falling at its
 * rate since the last look (at least max(GP_IMC_SLOW_LAG, N) steps back), would take more steps
 * than the run has made to reach the threshold, while the cells already meet the goals the
 * default threshold stands for (the KS goals, and the COV: ks_goals_met, cov_goal_met). Near-
 * regular cells (COV 0.1) meet them in a fifth of the steps the threshold takes, then creep
 * towards it (docs/design/imc.md). Reads the run at a step boundary only: the same on any
 * thread count. */
static int slow_at_goals(run_ctx *C)
{
    const imc_state *S = C->S;
    long s = C->ro.steps, lag = (long)S->n > GP_IMC_SLOW_LAG ? (long)S->n : GP_IMC_SLOW_LAG;
    if (!C->p->ks_goals || S->kind != GP_IMC_ERROR_AD || S->n < 2 || C->first_at >= 0 ||
        s == 0 || s % GP_IMC_PROGRESS_EVERY != 0)
        return 0;
    if (C->slow_at >= 0 && s - C->slow_at < lag) return 0;
    double e = C->cur.error, done = C->slow_at >= 0 ? log(C->slow_error / e) : 0.0;
    int slow = C->slow_at >= 0 && !(done * (double)s > log(e / C->p->threshold) * (double)(s - C->slow_at));
    C->slow_at = s;
    C->slow_error = e;
    return slow && ks_goals_met(S, GP_IMC_SLOW_GOAL_ORIENT) == 1 && cov_goal_met(S);
}

/* The checks each step starts with, in step order; 1 when the run stops here (ro.why). Past
 * the params' threshold (a tightened one in force) the run stops for "threshold" whatever
 * ends it. */
static int stop_before_step(run_ctx *C)
{
    run_out *ro = &C->ro;
    ro->why = GP_IMC_STOP_THRESHOLD;
    if (C->cur.error <= C->thr && at_threshold(C)) return 1;
    if (ks_budget_spent(C) && C->cur.error <= C->p->threshold) return 1;
    ro->why = stop_check(C->S, C->p, &C->cur, ro, &C->best, &C->best_step);
    if (ro->why != GP_IMC_STOP_THRESHOLD) {
        if (C->cur.error <= C->p->threshold && ro->why != GP_IMC_STOP_SINGLE_CELL) ro->why = GP_IMC_STOP_THRESHOLD;
        return 1;
    }
    if (slow_at_goals(C)) {
        ro->why = GP_IMC_STOP_STALLED;
        ro->at_goals = 1;
        return 1;
    }
    if ((ro->steps % GP_IMC_CANCEL_EVERY) == 0 && cancel_raised(C->cancel)) {
        ro->why = GP_IMC_STOP_CANCELLED;
        return 1;
    }
    if (ro->steps > 0 && (ro->steps % GP_IMC_PROGRESS_EVERY) == 0 && C->progress &&
        report(C->progress, C->user, C->p, ro, C->cur.error)) {
        ro->why = GP_IMC_STOP_CANCELLED;
        return 1;
    }
    return 0;
}

/* Lane u's footprint into u->fp; -1 out of memory. */
static int lane_footprint(lane *u)
{
    size_t need = gp_voronoi_footprint(u->v, u->fp, u->fpcap);
    if (need > u->fpcap) {
        uint32_t *f = realloc(u->fp, 2 * need * sizeof *f);
        if (!f) return -1;
        u->fp = f;
        u->fpcap = 2 * need;
        need = gp_voronoi_footprint(u->v, u->fp, u->fpcap);
    }
    u->nfp = need;
    return 0;
}

/* Lane w's move becomes the run's: recorded in the statistics (unless judge_serial did), given
 * to every other replica, committed. A later lane of the round whose pending move is clear of
 * w's changed cells (gp_voronoi_footprint) keeps it and takes w's move underneath; one that is
 * not is rolled back and marked redo, and so is a later lane without a pending move (its
 * proposal may have read w's cells). */
static gp_status lane_commit(run_ctx *C, int w, int put, gp_error *err)
{
    lane *L = &C->lanes[w];
    const uint32_t *ch;
    size_t nch = gp_voronoi_changed(L->v, &ch);
    for (size_t k = 0; put && k < nch; k++) cell_put(C->S, ch[k], &L->b.nv[k]);
    if (++C->mark == 0 && C->wmark) { /* wrapped (2^32 accepted moves): start the marks again */
        memset(C->wmark, 0, C->S->n * sizeof *C->wmark);
        C->mark = 1;
    }
    uint32_t mark = C->mark;
    for (size_t k = 0; C->wmark && k < nch; k++) C->wmark[ch[k]] = mark; /* NULL: one lane */
    for (int u = 0; u < C->nl; u++) {
        lane *U = &C->lanes[u];
        if (u == w) continue;
        if (u > w && u < C->nr && !U->redo) {
            int clear = U->pending;
            if (clear && lane_footprint(U) != 0) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
            for (size_t k = 0; clear && k < U->nfp; k++) clear = C->wmark[U->fp[k]] != mark;
            if (!clear) {
                U->redo = 1;
                if (U->pending) gp_voronoi_rollback(U->v);
                U->pending = 0;
            }
        }
        if (gp_voronoi_apply(U->v, L->v, err) != GP_OK) return GP_ERR_NOMEM;
    }
    gp_voronoi_commit(L->v);
    L->pending = 0;
    C->cur = put ? evaluate(C->S) : L->nw; /* the what-if rounds the extras sum */
    return GP_OK;
}

/* The outcome of lane L's step taken now: as evaluated while no step of the round was accepted
 * before it, else judged again against the statistics as they are (its cells are those it
 * would have computed, lane_commit saw to that). */
static int lane_outcome(run_ctx *C, lane *L, int after_win)
{
    if (L->out == LANE_SERIAL) return judge_serial(C->S, L, &C->cur, C->cap);
    int out = L->out;
    if (after_win && (out == LANE_ACCEPT || out == LANE_REJECT)) {
        const uint32_t *ch;
        size_t nch = gp_voronoi_changed(L->v, &ch);
        L->nw = evaluate_ad_if(C->S, ch, nch, L->b.nv, &L->b);
        out = not_worse(&L->nw, &C->cur) ? LANE_ACCEPT : LANE_REJECT;
    }
    /* the lane was judged before the cap it is settled under (at_threshold) */
    return out == LANE_ACCEPT && L->nw.error > C->cap ? LANE_REJECT : out;
}

/* A round's steps in order, as one thread would take them: each accepted step is committed
 * (lane_commit), and the round goes on with the next lane unless that lane must be redone;
 * the lanes from there on are taken again next round, with the same streams. Every pending
 * move left is rolled back. Returns 1 when the run stops. */
static int settle_round(run_ctx *C, gp_status *st, gp_error *err)
{
    int stop = 0, wins = 0;
    for (int t = 0; t < C->nr && !stop; t++) {
        lane *L = &C->lanes[t];
        if (L->redo || stop_before_step(C)) {
            stop = !L->redo;
            break;
        }
        C->ro.steps++;
        if (L->out == LANE_NOMEM) {
            *st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
            stop = 1;
            break;
        }
        int out = lane_outcome(C, L, wins > 0);
        C->acc_rate = 0.99 * C->acc_rate + (out == LANE_ACCEPT ? 0.01 : 0.0);
        if (out != LANE_ACCEPT) {
            if (L->pending) gp_voronoi_rollback(L->v); /* before a later win copies into it */
            L->pending = 0;
            continue;
        }
        C->ro.accepted++;
        wins++;
        if (lane_commit(C, t, L->out != LANE_SERIAL, err) != GP_OK) {
            *st = GP_ERR_NOMEM;
            stop = 1;
        }
    }
    for (int t = 0; t < C->nl; t++) {
        lane *L = &C->lanes[t];
        if (L->pending) gp_voronoi_rollback(L->v);
        L->pending = 0;
        L->redo = 0;
    }
    return stop;
}

/* The next round: how many lanes, and their step numbers. Lanes after an accepted step are
 * wasted, so while many steps are accepted a round has one lane per thread; when few are
 * (below 5 %), GP_IMC_LANES_PER_THREAD per thread, which evens out the threads' loads (a
 * round lasts as long as its slowest thread; docs/design/imc.md has the speeds). Which lanes
 * run changes nothing but the speed. */
static void number_lanes(run_ctx *C)
{
    if (C->nt > 1 && C->ro.steps >= C->stretch_end) next_stretch(C);
    C->nr = C->alone ? 1 : C->acc_rate < 0.05 ? C->nl : C->nt;
    for (int t = 0; t < C->nr; t++) C->lanes[t].step = C->ro.steps + 1 + t;
}

/* A jump (propose_ad) lands anywhere in the container: at large N in cells that no recent step
 * touched, whose records, vertices and neighbour lists, and the run's values of them, are far
 * from every cache; a jump then costs about 16 us more than a move among neighbours at
 * N = 100,000 (bench_imc). Where each step's jump lands is known ahead -- its stream is named
 * by its number (step_rng_set) and the point is its first draws after the one that chose the
 * jump, whatever the tessellation -- so the run asks the memory for those cells
 * GP_IMC_WARM_AHEAD steps before, GP_IMC_WARM_BATCH steps at once (gp_voronoi_warm). Only
 * the speed depends on it: it reads, and only the run's own replica (lane 0). */
#define GP_IMC_WARM_CELLS 20000 /* from this N on: below it the cells stay in the caches */
#define GP_IMC_WARM_AHEAD 32
#define GP_IMC_WARM_BATCH 16

static void warm_ahead(run_ctx *C)
{
    if (!C->warm_rng) return;
    const imc_state *S = C->S;
    while (C->warm_next <= C->ro.steps + 1 + GP_IMC_WARM_AHEAD) {
        gp_vec2 q[GP_IMC_WARM_BATCH];
        size_t k = 0;
        for (long t = C->warm_next; t < C->warm_next + GP_IMC_WARM_BATCH; t++) {
            step_rng_set(C->warm_rng, C->p->seed, t);
            if (gsl_rng_uniform(C->warm_rng) >= GP_IMC_JUMP_FROM) q[k++] = box_point(C->warm_rng, S->box);
        }
        C->warm_next += GP_IMC_WARM_BATCH;
        uint32_t ids[GP_IMC_WARM_BATCH * 16];
        size_t m = gp_voronoi_warm(C->lanes[0].v, q, k, ids, sizeof ids / sizeof ids[0]);
        for (size_t j = 0; j < m; j++) __builtin_prefetch(&S->adv[ids[j]]);
        gp_adstat_warm(S->ads, ids, m);
        gp_adstat_warm(S->adt, ids, m);
    }
}

static gp_status run_loop(run_ctx *C, gp_error *err)
{
    gp_status st = GP_OK;
    C->best = C->cur.descent;
    C->best_step = 0;
    C->acc_rate = 1.0;
    C->stretch = 2; /* the first stretch (probe alone) starts at step 0 */
    C->stretch_end = 0;
    do {
        warm_ahead(C);
        number_lanes(C);
        run_round(C);
    } while (!settle_round(C, &st, err));
    return st;
}

/* Lanes and threads for a run: up to GP_IMC_LANES_PER_THREAD lanes per thread of
 * params.threads (at most GP_IMC_LANES_MAX), for AD with N > 1; E1-E3 judge every step
 * serially, lanes would not help. Each lane beyond the first holds a whole tessellation (~660
 * bytes a cell), so the replicas hold at most
 * GP_IMC_REPLICA_CELLS cells together: 3 replicas at N = 100,000... 250,000 (2 threads),
 * none at 10^6 (there the steps are a small part of the job). No more threads than lanes. */
#define GP_IMC_LANES_MAX 16
#define GP_IMC_LANES_PER_THREAD 2
#define GP_IMC_REPLICA_CELLS 500000

static void lane_count(const gp_imc_params *p, int threads, size_t n, int *nl, int *nt)
{
    int t = threads < 1 ? 1 : threads > GP_IMC_LANES_MAX ? GP_IMC_LANES_MAX : threads;
    size_t cap = n > 1 ? 1 + GP_IMC_REPLICA_CELLS / n : 1, l = (size_t)(GP_IMC_LANES_PER_THREAD * t);
    if (t == 1 || p->error_kind != GP_IMC_ERROR_AD) l = 1;
    *nl = (int)(l < cap ? l : cap);
    *nt = t < *nl ? t : *nl;
}

/* the replicas of lanes 1.. are built from the run's seeds, each on its own thread: the same
 * seeds give the same tessellation bit for bit */
typedef struct replica_job {
    lane *lanes;
    const gp_vec2 *outer;
    size_t nouter;
    const gp_vec2 *const *holes;
    const size_t *nhole;
    size_t nholes;
    const gp_vec2 *seeds;
    size_t n;
    const volatile int *cancel;
    int nl, nt;
    gp_error errs[GP_IMC_LANES_PER_THREAD * GP_IMC_LANES_MAX];
} replica_job;

static void replica_fn(void *ctx, int tid)
{
    replica_job *J = ctx;
    for (int t = tid; t < J->nl; t += J->nt)
        if (t > 0) /* lane 0 is the run's own tessellation */
            J->lanes[t].v = gp_voronoi_create_ex(J->outer, J->nouter, J->holes, J->nhole, J->nholes,
                                                 J->seeds, J->n, J->cancel, &J->errs[t]);
}

static void lanes_free(run_ctx *C)
{
    for (int t = 0; C->lanes && t < C->nl; t++) {
        if (t > 0) gp_voronoi_destroy(C->lanes[t].v);
        if (C->lanes[t].rng) gsl_rng_free(C->lanes[t].rng);
        step_buf_free(&C->lanes[t].b);
        free(C->lanes[t].fp);
    }
    free(C->lanes);
    free(C->wmark);
    C->wmark = NULL;
    gp_team_destroy(C->team);
    C->lanes = NULL;
    C->team = NULL;
}

/* The team and its lanes, lane 0 on v (the run's tessellation, not owned). */
static gp_status lanes_init(run_ctx *C, gp_voronoi *v, replica_job *J, gp_error *err)
{
    int nl, nt;
    lane_count(C->p, C->p->threads, C->S->n, &nl, &nt);
    C->team = gp_team_create(nt, err);
    if (!C->team) return GP_ERR_NOMEM;
    /* the team may have fewer threads (the CPUs online, or refused): lanes for what it has */
    lane_count(C->p, gp_team_size(C->team), C->S->n, &nl, &nt);
    C->nt = gp_team_size(C->team);
    C->nl = nl;
    C->lanes = calloc((size_t)C->nl, sizeof *C->lanes);
    if (!C->lanes) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
    for (int t = 0; t < C->nl; t++) {
        lane *L = &C->lanes[t];
        L->rng = gsl_rng_alloc(gsl_rng_taus2);
        L->b.nb = malloc(64 * sizeof(size_t));
        L->b.nbcap = 64;
        if (!L->rng || !L->b.nb) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
    }
    C->lanes[0].v = v;
    if (C->nl == 1) return GP_OK;
    C->wmark = calloc(C->S->n, sizeof *C->wmark);
    if (!C->wmark) return gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
    J->lanes = C->lanes;
    J->nl = C->nl;
    J->nt = C->nt;
    gp_team_run(C->team, replica_fn, J);
    for (int t = 1; t < C->nl; t++)
        if (!C->lanes[t].v) {
            if (err) *err = J->errs[t];
            return J->errs[t].code;
        }
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* report and run                                                                              */

static gp_status fill_report(gp_imc_report *rep, const imc_state *S, const gp_imc_params *p)
{
    rep->nsize = (size_t)S->ks;
    rep->norient = (size_t)S->kt;
    rep->size_edges = malloc((size_t)(S->ks + 1) * sizeof(double));
    rep->size_target = malloc((size_t)S->ks * sizeof(double));
    rep->size_achieved = malloc((size_t)S->ks * sizeof(double));
    rep->orient_edges = malloc((size_t)(S->kt + 1) * sizeof(double));
    rep->orient_target = malloc((size_t)S->kt * sizeof(double));
    rep->orient_achieved = malloc((size_t)S->kt * sizeof(double));
    if (!rep->size_edges || !rep->size_target || !rep->size_achieved || !rep->orient_edges ||
        !rep->orient_target || !rep->orient_achieved)
        return GP_ERR_NOMEM;
    size_classes(S->law, S->ks, rep->size_edges, rep->size_target);
    orient_classes(p->mean_deg, p->anisotropy, S->kt, rep->orient_edges, rep->orient_target);
    for (int j = 0; j < S->ks; j++) rep->size_achieved[j] = S->cs[j] / (double)S->n;
    for (int j = 0; j < S->kt; j++) rep->orient_achieved[j] = S->ct[j] / (double)S->n;
    hist_errors(S, S->kind == 2 ? 2 : 3, &rep->error_size, &rep->error_orient);
    if (S->kind == GP_IMC_ERROR_AD) {
        ad_errors(S, &rep->error_size_ad, &rep->error_orient_ad);
        for (int d = 0; d < S->nwall; d++) rep->wall_ties += S->tie_count[d] > 1 ? (size_t)S->tie_count[d] : 0;
        rep->error_orient_ties = tie_term(S, S->tie_pairs);
    }
    return GP_OK;
}

/* The steps, on as many lanes as the params allow (a cancel while their replicas are built
 * counts as a cancel before the first step). */
static gp_status run_steps(imc_state *S, const gp_imc_params *p, gp_voronoi *v, replica_job *J,
                           gp_progress_fn progress, void *user, const volatile int *cancel,
                           objective *cur, run_out *ro, gp_error *err)
{
    run_ctx C = {.S = S, .p = p, .progress = progress, .user = user, .cancel = cancel, .cur = *cur,
                 .ro = *ro, .thr = p->threshold, .first_at = -1, .slow_at = -1,
                 .cap = INFINITY, .warm_next = 1};
    if (S->kind == GP_IMC_ERROR_AD && S->n >= GP_IMC_WARM_CELLS) C.warm_rng = gsl_rng_alloc(gsl_rng_taus2);
    gp_status st = lanes_init(&C, v, J, err);
    if (st == GP_ERR_CANCELLED) {
        C.ro.why = GP_IMC_STOP_CANCELLED;
        st = GP_OK;
    } else if (st == GP_OK) {
        st = run_loop(&C, err);
    }
    lanes_free(&C);
    if (C.warm_rng) gsl_rng_free(C.warm_rng);
    *cur = C.cur;
    *ro = C.ro;
    return st;
}

static void end_message(gp_status *st, const run_out *ro, const gp_imc_params *p, double e, gp_error *err)
{
    if (*st != GP_OK) return;
    if (ro->at_goals)
        *st = gp_error_set(err, GP_ERR_NOT_CONVERGED, "imc: stalled after %ld steps without reaching %g "
                           "(error %g), falling slowly with the cells within the KS goals it stands for",
                           ro->steps, p->threshold, e);
    else if (ro->why == GP_IMC_STOP_MAX_STEPS || ro->why == GP_IMC_STOP_STALLED ||
             ro->why == GP_IMC_STOP_SINGLE_CELL)
        *st = gp_error_set(err, GP_ERR_NOT_CONVERGED, "imc: %s after %ld steps without reaching %g (error %g)",
                           gp_imc_stop_name(ro->why), ro->steps, p->threshold, e);
    else if (ro->why == GP_IMC_STOP_CANCELLED)
        *st = gp_error_set(err, GP_ERR_CANCELLED, "imc: cancelled after %ld steps (error %g)", ro->steps, e);
    else
        gp_error_clear(err);
}

gp_status gp_imc_run(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                     const size_t *nhole, size_t nholes, size_t n, const gp_imc_params *p,
                     gp_progress_fn progress, void *user, const volatile int *cancel,
                     gp_voronoi **out, gp_imc_report *rep, gp_error *err)
{
    if (out) *out = NULL;
    if (rep) memset(rep, 0, sizeof *rep);
    if (!out || !p) return gp_error_set(err, GP_ERR_INVALID, "imc: out and params are required");
    gp_status st = check_params(outer, nouter, holes, nhole, nholes, n, p, err);
    if (st != GP_OK) return st;

    gp_rng *rng = gp_rng_create(p->seed, 0, err);
    if (!rng) return err ? err->code : GP_ERR_NOMEM;
    gp_vec2 *seeds = malloc(n * sizeof *seeds);
    imc_state S;
    memset(&S, 0, sizeof S);
    gp_voronoi *v = NULL;
    gp_law *own_law = NULL;
    run_out ro = {0, 0, GP_IMC_STOP_MAX_STEPS, 0, -1.0};
    if (!seeds) {
        st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
        goto done;
    }
    outer_box(outer, nouter, S.box);
    st = place_seeds(outer, nouter, holes, nhole, nholes, n, p, S.box, rng, cancel, seeds, err);
    gp_rng_destroy(rng);
    rng = NULL;
    if (st != GP_OK) goto done;
    double t0 = gp_clock_seconds();
    v = gp_voronoi_create_ex(outer, nouter, holes, nhole, nholes, seeds, n, cancel, err);
    if (rep) rep->t_init = gp_clock_seconds() - t0;
    if (!v) {
        st = err ? err->code : GP_ERR_INVALID;
        goto done;
    }
    const gp_law *law = p->law;
    if (!law) {
        law = own_law = gp_law_create(GP_LAW_LOGNORMAL, gp_voronoi_container_area(v) / (double)n, p->cov, err);
        if (!law) {
            st = err ? err->code : GP_ERR_INVALID;
            goto done;
        }
    }
    double floor_e = 0.0;
    if (p->error_kind == GP_IMC_ERROR_AD) st = walls_init(&S, outer, nouter, holes, nhole, nholes, n, err);
    if (st != GP_OK) goto done;
    st = state_init(&S, p, law, v, n, cancel, &floor_e, err);
    if (st != GP_OK) goto done;
    objective cur = evaluate(&S);
    if (rep) {
        rep->error_initial = cur.error;
        rep->floor = floor_e;
    }
    if (p->threshold < floor_e) {
        ro.why = GP_IMC_STOP_FLOOR;
        st = gp_error_set(err, GP_ERR_INFEASIBLE,
                          "imc: threshold %g is below the error floor %g of %d size x %d orientation "
                          "classes at N = %zu (integer counts); raise it or use the AD error",
                          p->threshold, floor_e, S.ks, S.kt, n);
    } else {
        replica_job J = {.outer = outer, .nouter = nouter, .holes = holes, .nhole = nhole,
                         .nholes = nholes, .seeds = seeds, .n = n, .cancel = cancel};
        st = run_steps(&S, p, v, &J, progress, user, cancel, &cur, &ro, err);
        if (progress && st == GP_OK) report(progress, user, p, &ro, cur.error);
        end_message(&st, &ro, p, cur.error, err);
    }
    if (st == GP_ERR_NOMEM) goto done;
    if (rep) {
        rep->steps = ro.steps;
        rep->accepted = ro.accepted;
        rep->error = cur.error;
        rep->stop_reason = ro.why;
        rep->at_goals = ro.at_goals;
        if (fill_report(rep, &S, p) != GP_OK) {
            gp_imc_report_free(rep);
            st = gp_error_set(err, GP_ERR_NOMEM, "imc: out of memory");
            goto done;
        }
    }
    *out = v;
    v = NULL;
done:
    gp_voronoi_destroy(v);
    gp_law_destroy(own_law);
    gp_rng_destroy(rng);
    free(seeds);
    state_free(&S);
    return st;
}
