/* gp_fill.c -- optimised filling of one cell with a Fourier grain. See gp_fill.h for the
 * method.
 *
 * The objective is evaluated thousands of times a cell, so it is kept cheap: the shape factor
 * rho_i is a fixed part (modes outside 2..7, once per cell) plus six modes summed on a quarter
 * of the rays and spread to the rest by the symmetry of the Fourier basis
 * (optimised_modes_quadrant), in SSE2, or AVX where the CPU has it (the same operations, so the
 * same bits), with rho's smallest and largest and the doubled copy lp_fit's arcs read written
 * on the way; the six phases' sin and cos inline (sincos_fast); the grain's area a constant of
 * the spectrum (spectrum_area); the grain's support along an edge taken on the arc of rays that
 * can hold it, two products at a time; the centre LP restarted from the last optimum's rows,
 * which the next evaluation mostly keeps; Nelder-Mead on plain arrays (nm_simplex); and the
 * final containment check tried first on the cell's kernel (inside_kernel). Fewer evaluations:
 * a simplex run also stops once it has gained less than STALL_REL in STALL_EVALS evaluations,
 * which is where cells that cannot reach F_S would spend most of theirs.
 * sincos_fast and libm's sincos differ in the last bits, so the searches take other (equally
 * good) paths than libm would give them. What each of these saves: docs/design/fill.md. */
#include "gp_fill.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
/* The quadrant sums also have an AVX form, picked at run time (GP_FILL_AVX): the same
 * products and sums in the same order per ray, four rays at a time, so the bits do not depend
 * on the machine. No FMA: a fused multiply-add would round differently. */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(GP_FILL_NO_AVX)
#define GP_FILL_AVX 1
#include <immintrin.h>
#endif


#define FIRST_OPT 2 /* first optimised mode */
#define LAST_OPT 7  /* last optimised mode */
#define NOPT (LAST_OPT - FIRST_OPT + 1)
/* Restarts of a simplex from its own best point while that still improves (a fresh simplex
 * escapes the collapse Nelder-Mead suffers in narrow valleys). */
#define FILL_RESTARTS 2
/* Extra random starts, spent only on cells whose best is within CLOSE of F_S: starts for every
 * cell cost far more evaluations for little more solid fraction; a third start (with the stall
 * stop below) wins back the cells the stall stop would lose (docs/design/fill.md). */
#define RANDOM_STARTS 3
#define CLOSE 0.9
/* A simplex run stops when its best has not grown by STALL_REL (relative) in STALL_EVALS
 * evaluations: run to their budget or a collapsed simplex, the cells short of F_S would take
 * most of the evaluations. Below 45 the stop trades the grains' alignment with their cells for
 * speed (docs/design/fill.md), so 45. */
#define STALL_EVALS 45
#define STALL_REL 1e-4
#define SUPPORT_ARC 16 /* rays either side of an edge's normal that support() scans at once */
#define LP_TOL 1e-12 /* feasibility slack in local (unit-area) coordinates */
#define LP_PIVOTS 64  /* dual simplex pivots before falling back to trying every vertex */

struct gp_fill_workspace {
    gp_fill_params p;
    size_t np, nm, ntab;  /* rays, modes used, modes tabulated (>= 8) */
    double *cosn, *sinn;  /* ntab * np: cos(n theta_i), sin(n theta_i) */
    double *base;         /* np: 1 + the fixed modes, in the grain's own frame */
    double *rmax;         /* np: ray length to the cell boundary from the current centre */
    double *inv_rmax;     /* np: 1 / rmax */
    double *rho;          /* np, and a copy of them after (lp_fit, for support) */
    /* np % 4 == 0: cos(n theta_i), sin(n theta_i) of modes 2..7 on the first quadrant's
     * rays i = 0 .. np/4 (stride np/4 + 1), and four sums there (optimised_modes_quadrant) */
    double *qc, *qs, *qsum;
    double rho_min, rho_max; /* of the last shape_factor */
    int avx;              /* the CPU has AVX: quadrant_avx */
    int rho_doubled;      /* the last shape_factor also wrote rho to rho[np..2np) (lp_fit) */
    double unit_area;     /* area of the grain polygon for r0 = 1 (a constant: spectrum_area) */
    /* the cell being filled, in local coordinates: origin at the starting centre, scaled to
     * unit area, so the search sees the same numbers for a cell at 1e-6 or offset by 1e6 */
    gp_vec2 *cell;
    size_t ncell, cell_cap;
    int convex;           /* the local cell is convex (and counter-clockwise) */
    double cell_area;     /* in local coordinates (1 up to rounding) */
    int use_lp;           /* objective: best centre for the shape (LP), else rays from 0 */
    /* convex cell: edge k is the half-plane nx x + ny y <= h; proj[2 k np + j] is its outward
     * normal dotted with ray j, written twice over (j and np + j) so that any arc of rays is
     * one run; arc0[k] the ray nearest that normal */
    double *nx, *ny, *h, *sup, *ones, *proj;
    size_t *arc0;
    size_t edge_cap;
    double box[4];        /* xmax, -xmin, ymax, -ymin of the local cell */
    size_t lp_basis[3];   /* the rows of the last LP optimum: where the next one starts */
    size_t rot;           /* the grain is turned by rot rays: phi = 2 pi rot / np */
    gp_vec2 lp_centre;    /* the centre found by the last lp_fit */
    int evals;
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
    free(ws->inv_rmax);
    free(ws->rho);
    free(ws->qc);
    free(ws->qs);
    free(ws->qsum);
    free(ws->cell);
    free(ws->nx);
    free(ws->ny);
    free(ws->h);
    free(ws->sup);
    free(ws->ones);
    free(ws->proj);
    free(ws->arc0);
    free(ws);
}

static gp_status check_params(const gp_fill_params *p, gp_error *err)
{
    if (!p || !p->D)
        return gp_error_set(err, GP_ERR_INVALID, "fill: parameters and spectrum are required");
    if (!(p->solid_fraction > 0.0 && p->solid_fraction <= 1.0))
        return gp_error_set(err, GP_ERR_INVALID, "fill: solid_fraction must be in (0, 1], got %g",
                            p->solid_fraction);
    if (p->contour_points < 16)
        return gp_error_set(err, GP_ERR_INVALID, "fill: contour_points must be >= 16, got %zu",
                            p->contour_points);
    if (p->nmodes < 1 || p->nmodes > p->contour_points / 2)
        return gp_error_set(err, GP_ERR_INVALID, "fill: nmodes must be in [1, %zu], got %zu",
                            p->contour_points / 2, p->nmodes);
    for (size_t n = 0; n < p->nmodes; n++)
        if (!(p->D[n] >= 0.0) || !isfinite(p->D[n]))
            return gp_error_set(err, GP_ERR_INVALID,
                                "fill: spectrum D_%zu = %g must be finite and >= 0", n, p->D[n]);
    if (!(p->margin >= 0.0 && p->margin < 0.5))
        return gp_error_set(err, GP_ERR_INVALID, "fill: margin must be in [0, 0.5), got %g",
                            p->margin);
    return GP_OK;
}

/* Area of the grain polygon for r0 = 1: (1/2) sin(2 pi / Np) sum_i rho_i rho_{i+1}, and by the
 * discrete orthogonality of the modes (all n < Np / 2) that sum is
 * Np (1 + sum_n D_n^2 cos(2 pi n / Np) / 2) whatever the phases and the rotation. So the
 * fraction is r0^2 times a constant and the search maximises r0. */
static double spectrum_area(const gp_fill_params *p)
{
    double np = (double)p->contour_points, s = 0.0;
    for (size_t n = 1; n < p->nmodes; n++)
        s += p->D[n] * p->D[n] * cos(2.0 * M_PI * (double)n / np);
    return 0.5 * sin(2.0 * M_PI / np) * np * (1.0 + 0.5 * s);
}

gp_fill_workspace *gp_fill_workspace_create(const gp_fill_params *p, gp_error *err)
{
    if (check_params(p, err) != GP_OK)
        return NULL;
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
    ws->unit_area = spectrum_area(p);
    ws->cosn = malloc(ws->ntab * ws->np * sizeof(double));
    ws->sinn = malloc(ws->ntab * ws->np * sizeof(double));
    ws->base = malloc(ws->np * sizeof(double));
    ws->rmax = malloc(ws->np * sizeof(double));
    ws->inv_rmax = malloc(ws->np * sizeof(double));
    ws->rho = malloc(2 * ws->np * sizeof(double)); /* the second half: lp_fit's copy */
    if (ws->np % 4 == 0) {
        size_t q = ws->np / 4 + 1;
#ifdef GP_FILL_AVX
        ws->avx = __builtin_cpu_supports("avx");
#endif
        ws->qc = malloc(NOPT * q * sizeof(double));
        ws->qs = malloc(NOPT * q * sizeof(double));
        ws->qsum = malloc(4 * q * sizeof(double));
        if (!ws->qc || !ws->qs || !ws->qsum) {
            gp_fill_workspace_destroy(ws);
            gp_error_set(err, GP_ERR_NOMEM, "fill: out of memory");
            return NULL;
        }
    }
    if (!ws->cosn || !ws->sinn || !ws->base || !ws->rmax || !ws->inv_rmax || !ws->rho) {
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
    for (size_t j = 0, q = ws->np / 4 + 1; ws->qc && j < NOPT; j++)
        for (size_t i = 0; i < q; i++) {
            ws->qc[j * q + i] = ws->cosn[(FIRST_OPT + j) * ws->np + i];
            ws->qs[j * q + i] = ws->sinn[(FIRST_OPT + j) * ws->np + i];
        }
    return ws;
}

gp_status gp_fill_workspace_set_spectrum(gp_fill_workspace *ws, const double *D, gp_error *err)
{
    if (!ws)
        return gp_error_set(err, GP_ERR_INVALID, "fill: NULL workspace");
    gp_fill_params p = ws->p;
    p.D = D;
    gp_status st = check_params(&p, err);
    if (st != GP_OK)
        return st;
    ws->p.D = D;
    ws->unit_area = spectrum_area(&ws->p); /* the area constant is the spectrum's */
    return GP_OK;
}

/* ------------------------------------------------------------------ rays (any cell) */

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

/* Ray length t through the edge the walk reaches for ray i of a convex counter-clockwise
 * cell: a ray from an interior point leaves it through exactly one edge, and as the ray turns
 * counter-clockwise so does that edge, so one walk round the polygon serves all the rays --
 * O(np + ncell) instead of O(np * ncell). -1 when no edge is found (c not inside). */
static double walk_exit(const gp_fill_workspace *ws, gp_vec2 c, size_t i, size_t *k)
{
    const double *cs = ws->cosn + ws->np, *sn = ws->sinn + ws->np; /* n = 1 */
    for (size_t tries = 0; tries < ws->ncell; tries++) {
        double t = edge_exit(ws->cell, ws->ncell, *k, c, cs[i], sn[i]);
        if (t > 0.0)
            return t;
        *k = *k + 1 == ws->ncell ? 0 : *k + 1;
    }
    return -1.0;
}

/* rmax_i (and 1 / rmax_i) from centre c; 0 on success, -1 if some ray finds no boundary. */
static int cast_rays(gp_fill_workspace *ws, gp_vec2 c)
{
    const double *cs = ws->cosn + ws->np, *sn = ws->sinn + ws->np; /* n = 1 */
    double keep = 1.0 - ws->p.margin;
    size_t k = 0;
    for (size_t i = 0; i < ws->np; i++) {
        double t = ws->convex ? walk_exit(ws, c, i, &k)
                              : ray_exit(ws->cell, ws->ncell, c, cs[i], sn[i]);
        if (!(t > 0.0))
            return -1;
        ws->rmax[i] = t * keep;
        ws->inv_rmax[i] = 1.0 / ws->rmax[i];
    }
    return 0;
}

/* ------------------------------------------------------------------ the grain's shape */

/* Adds mode n of amplitude d and phase delta to rho_i = r(theta_i) / r0 on the Np rays:
 * d cos(n theta_i - delta) = d cos(delta) cos(n theta_i) + d sin(delta) sin(n theta_i). This and
 * the tables it reads are the filling's own evaluation of the Fourier radius r(theta) of
 * gp_fourier.h, on purpose: the search evaluates the shape thousands of times per cell with
 * only modes 2-7 changing, so the fixed modes are summed once per cell (fixed_part, with this)
 * and each evaluation only adds the six optimised ones (shape_factor). (gp_shape_curve_points
 * evaluates the same r(theta) at any np, gp_fourier_radii by inverse FFT on a plan's samples.) */
static void add_mode(const gp_fill_workspace *ws, double *rho, size_t n, double d, double delta)
{
    size_t np = ws->np;
    double ca = d * cos(delta), sa = d * sin(delta);
    const double *cn = ws->cosn + n * np, *sn = ws->sinn + n * np;
    for (size_t i = 0; i < np; i++)
        rho[i] += ca * cn[i] + sa * sn[i];
}

/* The optimised modes on all the rays by the quadrant symmetry of the Fourier basis (np a
 * multiple of 4): on ray i of the first quadrant let Ce, Se be the even modes' (2, 4, 6) cosine
 * and sine parts and Co, So the odd modes' (3, 5, 7). At pi - theta, pi + theta and -theta the
 * parts change sign as cos(n (pi -+ t)) = (-1)^n cos(n t), sin(n (pi -+ t)) = -+(-1)^n sin(n t),
 * so the four rays i, np/2 - i, np/2 + i, np - i get (Ce + Se) + (Co + So), (Ce - Se) - (Co - So),
 * (Ce + Se) - (Co + So) and (Ce - Se) + (Co - So): a quarter of the multiplications of summing
 * every mode on every ray, which is what an evaluation mostly costs. */
/* A, B, C, E (q each, consecutive in out) = Ce + Se, Ce - Se, Co + So, Co - So of the
 * quadrant's rays from the tables c, s (mode 2 + k at [k q]); restrict lets it vectorise. */
static void quadrant_sums(size_t q, const double *restrict c, const double *restrict s,
                          const double *restrict ca, const double *restrict sa,
                          double *restrict out)
{
    double a2 = ca[0], a3 = ca[1], a4 = ca[2], a5 = ca[3], a6 = ca[4], a7 = ca[5];
    double b2 = sa[0], b3 = sa[1], b4 = sa[2], b5 = sa[3], b6 = sa[4], b7 = sa[5];
    size_t i = 0;
#if defined(__SSE2__)
    /* the same products and sums two rays at a time (the compiler left this loop scalar) */
    const __m128d A2 = _mm_set1_pd(a2), A3 = _mm_set1_pd(a3), A4 = _mm_set1_pd(a4);
    const __m128d A5 = _mm_set1_pd(a5), A6 = _mm_set1_pd(a6), A7 = _mm_set1_pd(a7);
    const __m128d B2 = _mm_set1_pd(b2), B3 = _mm_set1_pd(b3), B4 = _mm_set1_pd(b4);
    const __m128d B5 = _mm_set1_pd(b5), B6 = _mm_set1_pd(b6), B7 = _mm_set1_pd(b7);
#define LD(t, k) _mm_loadu_pd((t) + (k) * q + i)
    for (; i + 2 <= q; i += 2) {
        __m128d ce = _mm_add_pd(_mm_add_pd(_mm_mul_pd(A2, LD(c, 0)), _mm_mul_pd(A4, LD(c, 2))),
                                _mm_mul_pd(A6, LD(c, 4)));
        __m128d se = _mm_add_pd(_mm_add_pd(_mm_mul_pd(B2, LD(s, 0)), _mm_mul_pd(B4, LD(s, 2))),
                                _mm_mul_pd(B6, LD(s, 4)));
        __m128d co = _mm_add_pd(_mm_add_pd(_mm_mul_pd(A3, LD(c, 1)), _mm_mul_pd(A5, LD(c, 3))),
                                _mm_mul_pd(A7, LD(c, 5)));
        __m128d so = _mm_add_pd(_mm_add_pd(_mm_mul_pd(B3, LD(s, 1)), _mm_mul_pd(B5, LD(s, 3))),
                                _mm_mul_pd(B7, LD(s, 5)));
        _mm_storeu_pd(out + i, _mm_add_pd(ce, se));
        _mm_storeu_pd(out + q + i, _mm_sub_pd(ce, se));
        _mm_storeu_pd(out + 2 * q + i, _mm_add_pd(co, so));
        _mm_storeu_pd(out + 3 * q + i, _mm_sub_pd(co, so));
    }
#undef LD
#endif
    for (; i < q; i++) {
        double ce = a2 * c[i] + a4 * c[2 * q + i] + a6 * c[4 * q + i];
        double se = b2 * s[i] + b4 * s[2 * q + i] + b6 * s[4 * q + i];
        double co = a3 * c[q + i] + a5 * c[3 * q + i] + a7 * c[5 * q + i];
        double so = b3 * s[q + i] + b5 * s[3 * q + i] + b7 * s[5 * q + i];
        out[i] = ce + se;
        out[q + i] = ce - se;
        out[2 * q + i] = co + so;
        out[3 * q + i] = co - so;
    }
}

/* rho = base + the four rays' combinations of the quadrant sums qs (see above); the smallest
 * and largest rho_i into mm[0], mm[1] on the way (the shape factor's sign test and lp_fit's
 * support bound), instead of two more passes over rho. rho has room for 2 np: returns 1 when
 * it also wrote the copy rho[np + i] = rho[i] that lp_fit's arcs read (else lp_fit copies). */
static int quadrant_rays(size_t Q, const double *restrict qs, const double *restrict base,
                         double *restrict rho, double *mm)
{
    size_t q = Q + 1;
    const double *A = qs, *B = qs + q, *C = qs + 2 * q, *E = qs + 3 * q;
#if defined(__SSE2__)
    if (Q % 2 == 0) {
        __m128d mn = _mm_set1_pd(DBL_MAX), mx = _mm_set1_pd(-DBL_MAX);
#define PUT(k, v)                                                                             \
    do {                                                                                      \
        __m128d v_ = (v);                                                                     \
        _mm_storeu_pd(rho + (k), v_);                                                         \
        _mm_storeu_pd(rho + 4 * Q + (k), v_);                                                 \
        mn = _mm_min_pd(mn, v_);                                                              \
        mx = _mm_max_pd(mx, v_);                                                              \
    } while (0)
        for (size_t i = 0; i < Q; i += 2) {
            __m128d a = _mm_loadu_pd(A + i), c = _mm_loadu_pd(C + i);
            PUT(i, _mm_add_pd(_mm_loadu_pd(base + i), _mm_add_pd(a, c)));
            PUT(2 * Q + i, _mm_add_pd(_mm_loadu_pd(base + 2 * Q + i), _mm_sub_pd(a, c)));
        }
        /* rays 2Q - i and 4Q - i for i = j + 1, j + 2: descending, so the lanes swap */
        for (size_t j = 0; j < Q; j += 2) {
            __m128d b = _mm_loadu_pd(B + j + 1), e = _mm_loadu_pd(E + j + 1);
            __m128d be = _mm_sub_pd(b, e), bp = _mm_add_pd(b, e);
            be = _mm_shuffle_pd(be, be, 1);
            bp = _mm_shuffle_pd(bp, bp, 1);
            PUT(2 * Q - j - 2, _mm_add_pd(_mm_loadu_pd(base + 2 * Q - j - 2), be));
            PUT(4 * Q - j - 2, _mm_add_pd(_mm_loadu_pd(base + 4 * Q - j - 2), bp));
        }
#undef PUT
        double l[2], h[2];
        _mm_storeu_pd(l, mn);
        _mm_storeu_pd(h, mx);
        mm[0] = l[0] < l[1] ? l[0] : l[1];
        mm[1] = h[0] > h[1] ? h[0] : h[1];
        return 1;
    }
#endif
    double mn = DBL_MAX, mx = -DBL_MAX;
    for (size_t i = 0; i < Q; i++) {
        rho[i] = base[i] + (A[i] + C[i]);
        rho[2 * Q + i] = base[2 * Q + i] + (A[i] - C[i]);
    }
    for (size_t i = 1; i <= Q; i++) {
        rho[2 * Q - i] = base[2 * Q - i] + (B[i] - E[i]);
        rho[4 * Q - i] = base[4 * Q - i] + (B[i] + E[i]);
    }
    for (size_t i = 0; i < 4 * Q; i++) {
        mn = rho[i] < mn ? rho[i] : mn;
        mx = rho[i] > mx ? rho[i] : mx;
    }
    mm[0] = mn;
    mm[1] = mx;
    return 0;
}

#ifdef GP_FILL_AVX
/* quadrant_sums and quadrant_rays (Q % 4 == 0) four rays at a time; see them for what */
__attribute__((target("avx"))) static void quadrant_avx(size_t Q, const double *restrict c,
                                                         const double *restrict s,
                                                         const double *ca, const double *sa,
                                                         double *restrict out,
                                                         const double *restrict base,
                                                         double *restrict rho, double *mm)
{
    size_t q = Q + 1, i = 0;
    __m256d a[NOPT], b[NOPT];
    for (int j = 0; j < NOPT; j++) {
        a[j] = _mm256_set1_pd(ca[j]);
        b[j] = _mm256_set1_pd(sa[j]);
    }
#define LD(t, k) _mm256_loadu_pd((t) + (k) * q + i)
#define MUL _mm256_mul_pd
#define ADD _mm256_add_pd
#define SUB _mm256_sub_pd
    for (; i + 4 <= q; i += 4) {
        __m256d ce = ADD(ADD(MUL(a[0], LD(c, 0)), MUL(a[2], LD(c, 2))), MUL(a[4], LD(c, 4)));
        __m256d se = ADD(ADD(MUL(b[0], LD(s, 0)), MUL(b[2], LD(s, 2))), MUL(b[4], LD(s, 4)));
        __m256d co = ADD(ADD(MUL(a[1], LD(c, 1)), MUL(a[3], LD(c, 3))), MUL(a[5], LD(c, 5)));
        __m256d so = ADD(ADD(MUL(b[1], LD(s, 1)), MUL(b[3], LD(s, 3))), MUL(b[5], LD(s, 5)));
        _mm256_storeu_pd(out + i, ADD(ce, se));
        _mm256_storeu_pd(out + q + i, SUB(ce, se));
        _mm256_storeu_pd(out + 2 * q + i, ADD(co, so));
        _mm256_storeu_pd(out + 3 * q + i, SUB(co, so));
    }
#undef LD
    for (; i < q; i++) { /* scalar, as quadrant_sums */
        double ce = ca[0] * c[i] + ca[2] * c[2 * q + i] + ca[4] * c[4 * q + i];
        double se = sa[0] * s[i] + sa[2] * s[2 * q + i] + sa[4] * s[4 * q + i];
        double co = ca[1] * c[q + i] + ca[3] * c[3 * q + i] + ca[5] * c[5 * q + i];
        double so = sa[1] * s[q + i] + sa[3] * s[3 * q + i] + sa[5] * s[5 * q + i];
        out[i] = ce + se;
        out[q + i] = ce - se;
        out[2 * q + i] = co + so;
        out[3 * q + i] = co - so;
    }
    const double *A = out, *B = out + q, *C = out + 2 * q, *E = out + 3 * q;
    __m256d mn = _mm256_set1_pd(DBL_MAX), mx = _mm256_set1_pd(-DBL_MAX);
#define PUT(k, v)                                                                             \
    do {                                                                                      \
        __m256d v_ = (v);                                                                     \
        _mm256_storeu_pd(rho + (k), v_);                                                      \
        _mm256_storeu_pd(rho + 4 * Q + (k), v_);                                              \
        mn = _mm256_min_pd(mn, v_);                                                           \
        mx = _mm256_max_pd(mx, v_);                                                           \
    } while (0)
    for (size_t k = 0; k < Q; k += 4) {
        __m256d av = _mm256_loadu_pd(A + k), cv = _mm256_loadu_pd(C + k);
        PUT(k, ADD(_mm256_loadu_pd(base + k), ADD(av, cv)));
        PUT(2 * Q + k, ADD(_mm256_loadu_pd(base + 2 * Q + k), SUB(av, cv)));
    }
    for (size_t j = 0; j < Q; j += 4) { /* rays 2Q - i, 4Q - i, i = j + 1 .. j + 4: reversed */
        __m256d bv = _mm256_loadu_pd(B + j + 1), ev = _mm256_loadu_pd(E + j + 1);
        __m256d be = SUB(bv, ev), bp = ADD(bv, ev);
        be = _mm256_permute_pd(_mm256_permute2f128_pd(be, be, 1), 5);
        bp = _mm256_permute_pd(_mm256_permute2f128_pd(bp, bp, 1), 5);
        PUT(2 * Q - j - 4, ADD(_mm256_loadu_pd(base + 2 * Q - j - 4), be));
        PUT(4 * Q - j - 4, ADD(_mm256_loadu_pd(base + 4 * Q - j - 4), bp));
    }
#undef PUT
#undef MUL
#undef ADD
#undef SUB
    double l[4], h[4];
    _mm256_storeu_pd(l, mn);
    _mm256_storeu_pd(h, mx);
    double l01 = l[0] < l[1] ? l[0] : l[1], l23 = l[2] < l[3] ? l[2] : l[3];
    double h01 = h[0] > h[1] ? h[0] : h[1], h23 = h[2] > h[3] ? h[2] : h[3];
    mm[0] = l01 < l23 ? l01 : l23;
    mm[1] = h01 > h23 ? h01 : h23;
}
#endif

static void optimised_modes_quadrant(gp_fill_workspace *ws, const double *ca, const double *sa)
{
    size_t Q = ws->np / 4;
    double mm[2];
#ifdef GP_FILL_AVX
    if (ws->avx && Q % 4 == 0) {
        quadrant_avx(Q, ws->qc, ws->qs, ca, sa, ws->qsum, ws->base, ws->rho, mm);
        ws->rho_doubled = 1;
    } else
#endif
    {
        quadrant_sums(Q + 1, ws->qc, ws->qs, ca, sa, ws->qsum);
        ws->rho_doubled = quadrant_rays(Q, ws->qsum, ws->base, ws->rho, mm);
    }
    ws->rho_min = mm[0];
    ws->rho_max = mm[1];
}

/* The same for any np: mode by mode over all the rays. */
static void optimised_modes_all(gp_fill_workspace *ws, const double *ca, const double *sa)
{
    size_t np = ws->np;
    double *rho = ws->rho;
    memcpy(rho, ws->base, np * sizeof *rho);
    for (int j = 0; j < NOPT; j++) {
        const double *cn = ws->cosn + (FIRST_OPT + (size_t)j) * np;
        const double *sn = ws->sinn + (FIRST_OPT + (size_t)j) * np;
        for (size_t i = 0; i < np; i++)
            rho[i] += ca[j] * cn[i] + sa[j] * sn[i];
    }
    double mn = rho[0], mx = rho[0];
    for (size_t i = 1; i < np; i++) {
        mn = rho[i] < mn ? rho[i] : mn;
        mx = rho[i] > mx ? rho[i] : mx;
    }
    ws->rho_min = mn;
    ws->rho_max = mx;
    ws->rho_doubled = 0;
}

/* sin and cos of x to within an ulp or two (fdlibm's kernels on [-pi/4, pi/4] after a
 * two-part Cody-Waite reduction by pi/2, exact for |x| < 2^20 pi/2), inline: through libm's
 * sincos the six phases of every evaluation would be a large part of the objective
 * (docs/design/fill.md). Larger |x| (a simplex wandering far) goes to libm. */
static inline void sincos_fast(double x, double *s, double *c)
{
    if (!(fabs(x) < 1e6)) {
        *s = sin(x);
        *c = cos(x);
        return;
    }
    const double pio2_1 = 1.57079632673412561417e+00, pio2_1t = 6.07710050650619224932e-11;
    double kd = nearbyint(x * 0.63661977236758134308);
    long k = (long)kd;
    double r = (x - kd * pio2_1) - kd * pio2_1t, z = r * r;
    double sr = r + r * z * (-1.66666666666666324348e-01 +
                 z * (8.33333333332248946124e-03 + z * (-1.98412698298579493134e-04 +
                 z * (2.75573137070700676789e-06 + z * (-2.50507602534068634195e-08 +
                 z * 1.58969099521155010221e-10)))));
    double cr = 1.0 - 0.5 * z + z * z * (4.16666666666666019037e-02 +
                 z * (-1.38888888888741095749e-03 + z * (2.48015872894767294178e-05 +
                 z * (-2.75573143513906633035e-07 + z * (2.08757232129817482790e-09 +
                 z * -1.13596475577881948265e-11)))));
    double ss = (k & 1) ? cr : sr, cc = (k & 1) ? sr : cr;
    *s = (k & 2) ? -ss : ss;
    *c = ((k + 1) & 2) ? -cc : cc;
}

#if defined(__SSE2__)
/* sincos_fast of x[0] and x[1] at once, the same operations per lane (cvtpd2dq rounds to
 * nearest even as nearbyint does), so the same bits; 0 (nothing written) when either |x| is
 * too large for the reduction. */
static inline int sincos_fast2(const double *x, double *s, double *c)
{
    __m128d vx = _mm_loadu_pd(x);
    __m128d ax = _mm_andnot_pd(_mm_set1_pd(-0.0), vx);
    if (_mm_movemask_pd(_mm_cmplt_pd(ax, _mm_set1_pd(1e6))) != 3)
        return 0;
    __m128i k = _mm_cvtpd_epi32(_mm_mul_pd(vx, _mm_set1_pd(0.63661977236758134308)));
    __m128d kd = _mm_cvtepi32_pd(k);
#define P(v) _mm_set1_pd(v)
    __m128d r = _mm_sub_pd(_mm_sub_pd(vx, _mm_mul_pd(kd, P(1.57079632673412561417e+00))),
                           _mm_mul_pd(kd, P(6.07710050650619224932e-11)));
    __m128d z = _mm_mul_pd(r, r);
    __m128d ps = _mm_add_pd(P(-2.50507602534068634195e-08),
                            _mm_mul_pd(z, P(1.58969099521155010221e-10)));
    ps = _mm_add_pd(P(2.75573137070700676789e-06), _mm_mul_pd(z, ps));
    ps = _mm_add_pd(P(-1.98412698298579493134e-04), _mm_mul_pd(z, ps));
    ps = _mm_add_pd(P(8.33333333332248946124e-03), _mm_mul_pd(z, ps));
    ps = _mm_add_pd(P(-1.66666666666666324348e-01), _mm_mul_pd(z, ps));
    __m128d sr = _mm_add_pd(r, _mm_mul_pd(_mm_mul_pd(r, z), ps));
    __m128d pc = _mm_add_pd(P(2.08757232129817482790e-09),
                            _mm_mul_pd(z, P(-1.13596475577881948265e-11)));
    pc = _mm_add_pd(P(-2.75573143513906633035e-07), _mm_mul_pd(z, pc));
    pc = _mm_add_pd(P(2.48015872894767294178e-05), _mm_mul_pd(z, pc));
    pc = _mm_add_pd(P(-1.38888888888741095749e-03), _mm_mul_pd(z, pc));
    pc = _mm_add_pd(P(4.16666666666666019037e-02), _mm_mul_pd(z, pc));
    __m128d cr = _mm_add_pd(_mm_sub_pd(P(1.0), _mm_mul_pd(P(0.5), z)),
                            _mm_mul_pd(_mm_mul_pd(z, z), pc));
#undef P
    /* k of each lane in both its halves: bit 0 swaps sin and cos, bits of k and k + 1 the signs */
    __m128i kk = _mm_shuffle_epi32(k, _MM_SHUFFLE(1, 1, 0, 0));
    __m128i one = _mm_set1_epi32(1), bit1 = _mm_set_epi32(0, 2, 0, 2);
    __m128d swap = _mm_castsi128_pd(_mm_cmpeq_epi32(_mm_and_si128(kk, one), one));
    __m128d ss = _mm_or_pd(_mm_and_pd(swap, cr), _mm_andnot_pd(swap, sr));
    __m128d cc = _mm_or_pd(_mm_and_pd(swap, sr), _mm_andnot_pd(swap, cr));
    __m128i sgs = _mm_slli_epi64(_mm_and_si128(kk, bit1), 62);
    __m128i sgc = _mm_slli_epi64(_mm_and_si128(_mm_add_epi32(kk, one), bit1), 62);
    _mm_storeu_pd(s, _mm_xor_pd(ss, _mm_castsi128_pd(sgs)));
    _mm_storeu_pd(c, _mm_xor_pd(cc, _mm_castsi128_pd(sgc)));
    return 1;
}
#endif

/* rho_i for the optimised phases ph[0..5] = delta_2..delta_7 (grain frame), and their smallest
 * and largest (ws->rho_min, rho_max); returns min rho (only its sign is used). */
static double shape_factor(gp_fill_workspace *ws, const double *ph)
{
    double ca[NOPT], sa[NOPT], sn[NOPT], cs[NOPT];
    int j = 0;
#if defined(__SSE2__)
    for (; j + 2 <= NOPT && sincos_fast2(ph + j, sn + j, cs + j); j += 2)
        ;
#endif
    for (; j < NOPT; j++)
        sincos_fast(ph[j], &sn[j], &cs[j]);
    for (j = 0; j < NOPT; j++) {
        size_t n = FIRST_OPT + (size_t)j;
        double d = n < ws->nm ? ws->p.D[n] : 0.0;
        ca[j] = d * cs[j];
        sa[j] = d * sn[j];
    }
    if (ws->qc)
        optimised_modes_quadrant(ws, ca, sa);
    else
        optimised_modes_all(ws, ca, sa);
    return ws->rho_min;
}

/* Largest r0 allowed by the rays (cast in the cell's frame) for the current rho, turned by
 * rot rays: grain ray i lies along cell ray i + rot. */
/* max(q, max_i a_i b_i), two products at a time: maxpd(v, m) is v > m ? v : m, the scalar
 * test, and the maximum of the same products is the same double in any order */
static double max_products(const double *a, const double *b, size_t n, double q)
{
    size_t i = 0;
#if defined(__SSE2__)
    __m128d m = _mm_set1_pd(q);
    for (; i + 2 <= n; i += 2)
        m = _mm_max_pd(_mm_mul_pd(_mm_loadu_pd(a + i), _mm_loadu_pd(b + i)), m);
    double l[2];
    _mm_storeu_pd(l, m);
    q = l[0] > l[1] ? l[0] : l[1];
#endif
    for (; i < n; i++) {
        double v = a[i] * b[i];
        q = v > q ? v : q;
    }
    return q;
}

static double r0_rays(const gp_fill_workspace *ws)
{
    size_t np = ws->np, split = np - ws->rot; /* rays i < split meet cell ray i + rot */
    const double *rho = ws->rho, *inv = ws->inv_rmax;
    double q = max_products(rho, inv + ws->rot, split, 0.0);
    return 1.0 / max_products(rho + split, inv, np - split, q);
}

/* ------------------------------------------------------------------ the centre LP (convex) */

/* The rows of max z subject to a_k x + b_k y + w_k z <= h_k. */
typedef struct lp_rows {
    const double *a, *b, *w, *h;
    size_t n;
} lp_rows;

/* (x, y, z) satisfies every row within LP_TOL. */
static int feasible(const lp_rows *r, double x, double y, double z)
{
    for (size_t k = 0; k < r->n; k++)
        if (!(r->a[k] * x + r->b[k] * y + r->w[k] * z <= r->h[k] + LP_TOL))
            return 0;
    return 1;
}

/* M = inverse of the 3x3 matrix of rows B; -1 if it is (nearly) singular. */
static int invert3(const lp_rows *r, const size_t *B, double M[3][3])
{
    double A[3][3];
    for (int i = 0; i < 3; i++) {
        A[i][0] = r->a[B[i]];
        A[i][1] = r->b[B[i]];
        A[i][2] = r->w[B[i]];
    }
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) /* adjugate: cofactor of A[j][i] */
            M[i][j] = A[(j + 1) % 3][(i + 1) % 3] * A[(j + 2) % 3][(i + 2) % 3] -
                      A[(j + 1) % 3][(i + 2) % 3] * A[(j + 2) % 3][(i + 1) % 3];
    double det = A[0][0] * M[0][0] + A[0][1] * M[1][0] + A[0][2] * M[2][0];
    if (!(fabs(det) >= 1e-12))
        return -1;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            M[i][j] /= det;
    return 0;
}

/* Dual simplex from basis B (three rows whose dual weights, the last row of their inverse M,
 * are >= 0; have_m: M holds that inverse already): while the basis' vertex v violates a row, that row replaces the basis row the
 * ratio test picks, which keeps the weights >= 0 -- a few pivots from the last optimum.
 * 0 with the optimum in v and B; -1 if it stalls, cycles or meets a singular basis. */
static int lp_dual(const lp_rows *r, size_t *B, double *v, double M[3][3], int have_m)
{
    for (int it = 0; it < LP_PIVOTS; it++) {
        if (!(it == 0 && have_m) && invert3(r, B, M) != 0)
            return -1;
        for (int i = 0; i < 3; i++)
            v[i] = M[i][0] * r->h[B[0]] + M[i][1] * r->h[B[1]] + M[i][2] * r->h[B[2]];
        size_t q = r->n;
        double worst = LP_TOL;
        for (size_t k = 0; k < r->n; k++) {
            double e = r->a[k] * v[0] + r->b[k] * v[1] + r->w[k] * v[2] - r->h[k];
            if (e > worst)
                worst = e, q = k;
        }
        if (q == r->n)
            return M[2][0] >= -LP_TOL && M[2][1] >= -LP_TOL && M[2][2] >= -LP_TOL ? 0 : -1;
        int out = -1;
        double ratio = DBL_MAX;
        for (int i = 0; i < 3; i++) {
            double mu = M[0][i] * r->a[q] + M[1][i] * r->b[q] + M[2][i] * r->w[q];
            double wi = M[2][i] > 0.0 ? M[2][i] : 0.0; /* fmax, without the call */
            if (mu > 1e-12 && wi / mu < ratio)
                ratio = wi / mu, out = i;
        }
        if (out < 0)
            return -1; /* infeasible */
        B[out] = q;
    }
    return -1;
}

/* Fallback: every triple of rows, keeping the best feasible vertex (the optimum of a bounded
 * 3-variable LP is one). -1 if none is feasible. */
static int lp_vertices(const lp_rows *r, size_t *B, double *v)
{
    double best = -DBL_MAX, M[3][3];
    size_t T[3];
    for (T[0] = 0; T[0] + 2 < r->n; T[0]++)
        for (T[1] = T[0] + 1; T[1] + 1 < r->n; T[1]++)
            for (T[2] = T[1] + 1; T[2] < r->n; T[2]++) {
                if (invert3(r, T, M) != 0)
                    continue;
                double u[3];
                for (int i = 0; i < 3; i++)
                    u[i] = M[i][0] * r->h[T[0]] + M[i][1] * r->h[T[1]] + M[i][2] * r->h[T[2]];
                if (!(u[2] > best) || !feasible(r, u[0], u[1], u[2]))
                    continue;
                best = u[2];
                memcpy(v, u, sizeof u);
                memcpy(B, T, sizeof T);
            }
    return best == -DBL_MAX ? -1 : 0;
}

/* max z subject to nx_k x + ny_k y + w_k z <= h_k over the cell's edges, plus the bounding
 * box and z <= zmax, which the full problem implies and which make any start bounded: w and h
 * have 5 spare rows for them. Starts from the last optimum's rows when they are still dual
 * feasible (the search moves in small steps), else from the box's corner {z, x, y}. */
static int lp_solve(gp_fill_workspace *ws, double *w, double *h, double zmax, double *x,
                    double *y, double *z)
{
    size_t m = ws->ncell;
    for (size_t q = 0; q < 5; q++) {
        w[m + q] = q == 4 ? 1.0 : 0.0;
        h[m + q] = q == 4 ? zmax : ws->box[q];
    }
    lp_rows r = {ws->nx, ws->ny, w, h, m + 5};
    double M[3][3], v[3];
    size_t *B = ws->lp_basis;
    int have_m = 1; /* M is B's inverse: lp_dual's first pivot need not invert it again */
    if (invert3(&r, B, M) != 0 || M[2][0] < 0.0 || M[2][1] < 0.0 || M[2][2] < 0.0) {
        B[0] = m + 4, B[1] = m, B[2] = m + 2;
        have_m = 0;
    }
    if (lp_dual(&r, B, v, M, have_m) != 0 && lp_vertices(&r, B, v) != 0)
        return -1;
    *x = v[0], *y = v[1], *z = v[2];
    return 0;
}

/* The grain's support along edge k: max_i rho_i n_k . u(theta_i + phi), searched outwards
 * from the ray nearest the normal while rho_max times the projection (falling on each side)
 * can still beat the best so far: about a quarter of the rays instead of all. */
static double support_walk(const gp_fill_workspace *ws, size_t k)
{
    size_t np = ws->np, j0 = ws->arc0[k], i0 = (j0 + np - ws->rot) % np;
    const double *pk = ws->proj + 2 * k * np, *rho = ws->rho;
    double s = rho[i0] * pk[j0];
    for (size_t j = j0, i = i0, t = 1; t < np / 2; t++) { /* clockwise */
        j = j == 0 ? np - 1 : j - 1;
        i = i == 0 ? np - 1 : i - 1;
        if (pk[j] * ws->rho_max < s)
            break;
        s = rho[i] * pk[j] > s ? rho[i] * pk[j] : s;
    }
    for (size_t j = j0, i = i0, t = 1; t < np / 2; t++) { /* counter-clockwise */
        j = j + 1 == np ? 0 : j + 1;
        i = i + 1 == np ? 0 : i + 1;
        if (pk[j] * ws->rho_max < s)
            break;
        s = rho[i] * pk[j] > s ? rho[i] * pk[j] : s;
    }
    return s;
}

/* The same maximum taken over the fixed arc of SUPPORT_ARC rays either side of the normal, as
 * two straight runs (rho and proj are doubled) without a test per ray; it stands when the rays
 * just past the arc cannot beat it (the projection only falls further out), which is the
 * usual case, else support_walk decides. Either way the value is the maximum of the same
 * products, so the bits do not depend on which one found it. */
static double support(const gp_fill_workspace *ws, size_t k)
{
    size_t np = ws->np, w = SUPPORT_ARC;
    if (2 * w + 3 > np)
        return support_walk(ws, k);
    size_t j0 = ws->arc0[k], js = (j0 + np - w) % np, is = (js + np - ws->rot) % np;
    const double *pk = ws->proj + 2 * k * np, *a = ws->rho + is, *b = pk + js;
    size_t n = 2 * w + 1, t = 1;
    double s = a[0] * b[0];
#if defined(__SSE2__)
    /* two products at a time (maxpd; the maximum of the same products is the same double) */
    __m128d m2 = _mm_set1_pd(s);
    for (; t + 2 <= n; t += 2)
        m2 = _mm_max_pd(m2, _mm_mul_pd(_mm_loadu_pd(a + t), _mm_loadu_pd(b + t)));
    double l[2];
    _mm_storeu_pd(l, m2);
    s = l[0] > l[1] ? l[0] : l[1];
#endif
    for (; t < n; t++)
        s = a[t] * b[t] > s ? a[t] * b[t] : s;
    double e0 = pk[js + np - 1], e1 = pk[js + n]; /* the rays just outside the arc */
    double edge = e0 > e1 ? e0 : e1;
    return edge * ws->rho_max < s ? s : support_walk(ws, k);
}

/* Convex cell: the largest r0 for the current rho and rotation over every centre. A polygon
 * lies in a convex cell iff its vertices do, i.e. iff n_k . c + r0 s_k <= h_k for every edge,
 * s_k being the grain's support: linear in (c, r0), so the exact optimum is a small LP. */
static double lp_fit(gp_fill_workspace *ws)
{
    if (!ws->rho_doubled)
        memcpy(ws->rho + ws->np, ws->rho, ws->np * sizeof *ws->rho);
    for (size_t k = 0; k < ws->ncell; k++)
        ws->sup[k] = support(ws, k);
    double r0, zmax = 2.0 * sqrt(ws->cell_area / ws->unit_area);
    if (lp_solve(ws, ws->sup, ws->h, zmax, &ws->lp_centre.x, &ws->lp_centre.y, &r0) != 0 ||
        !(r0 > 0.0))
        return 0.0;
    return r0;
}

/* ------------------------------------------------------------------ objective and search */

/* The achievable fraction for phases ph at the current rotation. */
static double achievable(gp_fill_workspace *ws, const double *ph)
{
    ws->evals++;
    if (!(shape_factor(ws, ph) > 0.0))
        return 0.0; /* not star-shaped for these phases */
    double r0 = ws->use_lp ? lp_fit(ws) : r0_rays(ws);
    return r0 * r0 * ws->unit_area / ws->cell_area;
}

static double objective6(gp_fill_workspace *ws, const double *x)
{
    return -achievable(ws, x);
}

/* phases x[0..5] and centre x[6], x[7] (non-convex cells: rays from the centre) */
static double objective8(gp_fill_workspace *ws, const double *x)
{
    gp_vec2 c = {x[NOPT], x[NOPT + 1]};
    if (!gp_poly_contains(ws->cell, ws->ncell, c) || cast_rays(ws, c) != 0) {
        ws->evals++;
        return 0.0;
    }
    return -achievable(ws, x);
}

/* ------------------------------------------------------------------ Nelder-Mead */

/* GSL's nmsimplex2 (the moves, coefficients, incremental centre and size of its simplex2.c)
 * on plain arrays: through gsl_vector, gsl_matrix and CBLAS calls its bookkeeping would cost
 * more than the shape factor's sums (docs/design/fill.md). The objective is always finite here
 * (0 where the phases are not admissible), so GSL's non-finite branches are left out. */
enum { NM_MAX = NOPT + 2 };
typedef double (*nm_fn)(gp_fill_workspace *ws, const double *x);

typedef struct nm_simplex {
    size_t n;                          /* dimension; n + 1 vertices */
    double x[NM_MAX + 1][NM_MAX], y[NM_MAX + 1];
    double c[NM_MAX];                  /* centre of the n + 1 vertices */
    double S2;                         /* mean squared distance of the vertices to c */
    size_t lo;                         /* the best vertex after the last step */
} nm_simplex;

static double nm_centre_size(nm_simplex *s)
{
    size_t n = s->n, P = n + 1;
    for (size_t j = 0; j < n; j++) {
        double t = 0.0;
        for (size_t i = 0; i < P; i++)
            t += s->x[i][j];
        s->c[j] = t * (1.0 / (double)P);
    }
    double ss = 0.0;
    for (size_t i = 0; i < P; i++)
        for (size_t j = 0; j < n; j++)
            ss += (s->x[i][j] - s->c[j]) * (s->x[i][j] - s->c[j]);
    s->S2 = ss / (double)P;
    return sqrt(s->S2);
}

/* x0 (value f0, already known) and x0 + step_i e_i */
static void nm_set(nm_simplex *s, gp_fill_workspace *ws, nm_fn f, const double *x0, double f0,
                   const double *step, size_t n)
{
    s->n = n;
    memcpy(s->x[0], x0, n * sizeof *x0);
    s->y[0] = f0;
    for (size_t i = 0; i < n; i++) {
        memcpy(s->x[i + 1], x0, n * sizeof *x0);
        s->x[i + 1][i] = x0[i] + step[i];
        s->y[i + 1] = f(ws, s->x[i + 1]);
    }
    nm_centre_size(s);
    s->lo = 0;
}

/* xc = the corner `hi` moved through the centre of the others by coeff (-1 reflection, -2
 * expansion, 0.5 contraction); returns f(xc) */
static double nm_corner(const nm_simplex *s, gp_fill_workspace *ws, nm_fn f, size_t hi,
                        double coeff, double *xc)
{
    double P = (double)(s->n + 1);
    double alpha = (1.0 - coeff) * P / (P - 1.0), beta = (P * coeff - 1.0) / (P - 1.0);
    for (size_t j = 0; j < s->n; j++)
        xc[j] = alpha * s->c[j] + beta * s->x[hi][j];
    return f(ws, xc);
}

/* vertex i := x (value v), the centre and size updated as GSL does */
static void nm_update(nm_simplex *s, size_t i, const double *x, double v)
{
    size_t n = s->n;
    double P = (double)(n + 1), d2 = 0.0, xmcd = 0.0;
    for (size_t j = 0; j < n; j++) {
        double delta = x[j] - s->x[i][j];
        d2 += delta * delta;
        xmcd += (s->x[i][j] - s->c[j]) * delta;
    }
    s->S2 += (2.0 / P) * xmcd + ((P - 1.0) / P) * (d2 / P);
    for (size_t j = 0; j < n; j++) {
        s->c[j] += (x[j] - s->x[i][j]) / P;
        s->x[i][j] = x[j];
    }
    s->y[i] = v;
}

/* every vertex halfway to the best one */
static void nm_shrink(nm_simplex *s, gp_fill_workspace *ws, nm_fn f, size_t best)
{
    for (size_t i = 0; i <= s->n; i++) {
        if (i == best)
            continue;
        for (size_t j = 0; j < s->n; j++)
            s->x[i][j] = 0.5 * (s->x[i][j] + s->x[best][j]);
        s->y[i] = f(ws, s->x[i]);
    }
    nm_centre_size(s);
}

/* One step; returns the simplex size. */
static double nm_step(nm_simplex *s, gp_fill_workspace *ws, nm_fn f)
{
    size_t P = s->n + 1, hi = 0, lo = 0;
    double dhi = s->y[0], ds_hi = s->y[0], dlo = s->y[0];
    for (size_t i = 1; i < P; i++) {
        double v = s->y[i];
        if (v < dlo)
            dlo = v, lo = i;
        else if (v > dhi)
            ds_hi = dhi, dhi = v, hi = i;
        else if (v > ds_hi)
            ds_hi = v;
    }
    double xc[NM_MAX], xc2[NM_MAX];
    double v = nm_corner(s, ws, f, hi, -1.0, xc);
    if (v < s->y[lo]) {
        double v2 = nm_corner(s, ws, f, hi, -2.0, xc2);
        if (v2 < s->y[lo])
            nm_update(s, hi, xc2, v2);
        else
            nm_update(s, hi, xc, v);
    } else if (v > ds_hi) {
        if (v <= dhi)
            nm_update(s, hi, xc, v);
        double v2 = nm_corner(s, ws, f, hi, 0.5, xc2);
        if (v2 <= dhi)
            nm_update(s, hi, xc2, v2);
        else
            nm_shrink(s, ws, f, lo);
    } else {
        nm_update(s, hi, xc, v);
    }
    s->lo = 0;
    for (size_t i = 1; i < P; i++)
        if (s->y[i] < s->y[s->lo])
            s->lo = i;
    return s->S2 > 0.0 ? sqrt(s->S2) : nm_centre_size(s);
}

/* Runs Nelder-Mead from x until the fraction reaches target, the simplex collapses, the best
 * stalls (STALL_EVALS) or `budget` evaluations are spent; leaves the best point in x and
 * returns its fraction. */
static double maximise(gp_fill_workspace *ws, nm_fn f, double *x, const double *step, size_t n,
                       double target, int budget)
{
    double f0 = -f(ws, x);
    if (f0 >= target)
        return f0;
    nm_simplex s;
    nm_set(&s, ws, f, x, -f0, step, n);
    budget += ws->evals;
    double last = f0;
    int since = ws->evals;
    while (ws->evals < budget) {
        double size = nm_step(&s, ws, f);
        double fbest = -s.y[s.lo];
        if (fbest >= target || size < 1e-4)
            break;
        if (fbest > last * (1.0 + STALL_REL)) {
            last = fbest;
            since = ws->evals;
        } else if (ws->evals - since >= STALL_EVALS) {
            break;
        }
    }
    double best = -s.y[s.lo];
    if (best > f0) {
        memcpy(x, s.x[s.lo], n * sizeof *x);
        return best;
    }
    return f0;
}

/* Nelder-Mead over the phases from ph (updated to the best found), restarted from its own
 * best point up to `restarts` times while that improves. */
static double polish(gp_fill_workspace *ws, double *ph, double target, int budget, int restarts)
{
    double best = -1.0;
    for (int round = 0; round <= restarts && best < target; round++) {
        double x[NOPT], step[NOPT];
        for (int j = 0; j < NOPT; j++) {
            x[j] = ph[j];
            step[j] = round == 0 ? 0.6 : 0.3;
        }
        double f = maximise(ws, objective6, x, step, NOPT, target, budget);
        if (f > best)
            memcpy(ph, x, sizeof x);
        int improved = f > best * (1.0 + 1e-4);
        best = f > best ? f : best;
        if (!improved)
            break;
    }
    return best;
}

/* Grain-frame phases that, turned by rot rays, give the cell-frame phases cellph:
 * cos(n (theta - phi) - delta) = cos(n theta - (delta + n phi)). */
static void unturn(const gp_fill_workspace *ws, const double *cellph, size_t rot, double *ph)
{
    double phi = 2.0 * M_PI * (double)rot / (double)ws->np;
    for (int j = 0; j < NOPT; j++)
        ph[j] = remainder(cellph[j] - (double)(FIRST_OPT + j) * phi, 2.0 * M_PI);
}

/* The rotation (every other ray) where the shape fits best; leaves it in ws->rot. With dft,
 * the roughness (the fixed modes) is turned under the cell-aligned modes 2..7 of dft at each
 * rotation tried, and ph is left as that shape at the best one. */
static void best_rotation(gp_fill_workspace *ws, const double *dft, double *ph)
{
    size_t best_rot = 0;
    double best = -1.0;
    for (size_t r = 0; r < ws->np; r += 2) {
        if (dft)
            unturn(ws, dft, r, ph);
        ws->rot = r;
        double f = achievable(ws, ph);
        if (f > best) {
            best = f;
            best_rot = r;
        }
    }
    ws->rot = best_rot;
    if (dft)
        unturn(ws, dft, best_rot, ph);
}

static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

typedef struct candidate {
    double ph[NOPT];
    size_t rot;
    double f;
} candidate;

static void keep_best(candidate *best, const double *ph, size_t rot, double f)
{
    if (f > best->f) {
        memcpy(best->ph, ph, sizeof best->ph);
        best->rot = rot;
        best->f = f;
    }
}

/* Convex cell. (A) The paper's search from the cell-aligned start (start_phases), the centre
 * fixed at the centroid: most cells meet F_S here, and a grain found so follows its cell's
 * orientation best. (B) On from there with the best centre for each shape (lp_fit). (C) The
 * roughness turned under the cell-aligned start, then the same. (D) Cells within CLOSE of
 * F_S: random starts, each at its best rotation, seeded by rs. */
static double search_convex(gp_fill_workspace *ws, const double *dft, candidate *best,
                            double target, uint64_t rs)
{
    double ph[NOPT], f;
    /* Half the budget per run: with the centre exact the 6-phase simplex needs fewer steps
     * (docs/design/fill.md). */
    int budget = ws->p.max_evals / 2 > 0 ? ws->p.max_evals / 2 : 1;
    memcpy(ph, dft, sizeof ph);
    best->f = -1.0;
    ws->rot = 0;
    ws->use_lp = 0;
    f = polish(ws, ph, target, budget, 0);
    keep_best(best, ph, 0, f);
    ws->use_lp = 1;
    if (best->f < target) {
        f = polish(ws, ph, target, budget, FILL_RESTARTS);
        keep_best(best, ph, 0, f);
    }
    if (best->f < target) {
        best_rotation(ws, dft, ph);
        f = polish(ws, ph, target, budget, FILL_RESTARTS);
        keep_best(best, ph, ws->rot, f);
    }
    for (int s = 0; s < RANDOM_STARTS && best->f < target && best->f >= CLOSE * target; s++) {
        for (int j = 0; j < NOPT; j++)
            ph[j] = (double)(splitmix64(&rs) >> 11) * 0x1p-53 * 2.0 * M_PI - M_PI;
        best_rotation(ws, NULL, ph);
        f = polish(ws, ph, target, budget, FILL_RESTARTS);
        keep_best(best, ph, ws->rot, f);
    }
    return best->f;
}

/* Convex cell, from a grain this search found before for a lower fraction (a refill): on from
 * that point with the best centre for each shape, as (B), and no other start. Why not the cold
 * search where this falls short: the specimen refills every cell that met F_S to one higher
 * fraction, so a cell that cannot get there from its own grain leaves its share to the next
 * refill pass, and the cold search would cost a refill some eight times the evaluations
 * (docs/design/fill.md). */
static double search_convex_warm(gp_fill_workspace *ws, const double *start, size_t rot,
                                 candidate *best, double target)
{
    int budget = ws->p.max_evals / 2 > 0 ? ws->p.max_evals / 2 : 1;
    memcpy(best->ph, start, sizeof best->ph);
    best->rot = rot;
    ws->rot = rot;
    ws->use_lp = 1;
    best->f = polish(ws, best->ph, target, budget, FILL_RESTARTS);
    return best->f;
}

/* Non-convex cell: phases with the centre fixed, then phases and centre together with rays
 * from the centre (an LP would need convexity). Leaves the centre in *c. */
static double search_rays(gp_fill_workspace *ws, const double *dft, candidate *best, gp_vec2 *c,
                          double target)
{
    memcpy(best->ph, dft, sizeof best->ph);
    best->rot = 0;
    ws->rot = 0;
    ws->use_lp = 0;
    best->f = polish(ws, best->ph, target, ws->p.max_evals, 0);
    for (int round = 0; round <= FILL_RESTARTS && best->f < target && ws->p.optimise_centre;
         round++) {
        double x[NOPT + 2], step[NOPT + 2];
        for (int j = 0; j < NOPT; j++) {
            x[j] = best->ph[j];
            step[j] = 0.3;
        }
        x[NOPT] = c->x;
        x[NOPT + 1] = c->y;
        step[NOPT] = step[NOPT + 1] = 0.05;
        double f = maximise(ws, objective8, x, step, NOPT + 2, target, ws->p.max_evals);
        if (!(f > best->f * (1.0 + 1e-4)))
            break;
        best->f = f;
        memcpy(best->ph, x, sizeof best->ph);
        c->x = x[NOPT];
        c->y = x[NOPT + 1];
    }
    return best->f;
}

/* ------------------------------------------------------------------ per-cell set-up */

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

static int grow_edges(gp_fill_workspace *ws, size_t m)
{
    if (m <= ws->edge_cap)
        return 0;
    size_t rows = m + 5; /* + the box rows of lp_solve */
    double **arr[] = {&ws->nx, &ws->ny, &ws->h, &ws->sup, &ws->ones};
    for (size_t q = 0; q < sizeof arr / sizeof arr[0]; q++) {
        double *g = realloc(*arr[q], rows * sizeof(double));
        if (!g) return -1;
        *arr[q] = g;
    }
    double *proj = realloc(ws->proj, 2 * m * ws->np * sizeof *proj);
    if (proj) ws->proj = proj;
    size_t *arc0 = realloc(ws->arc0, m * sizeof *arc0);
    if (arc0) ws->arc0 = arc0;
    if (!proj || !arc0)
        return -1;
    ws->edge_cap = m;
    return 0;
}

/* Edges of the local convex cell as half-planes, their projections on every ray, and the
 * bounding-box rows lp_solve appends (x <= xmax, -x <= -xmin, y <= ymax, -y <= -ymin, and
 * z <= zmax). */
static int prepare_edges(gp_fill_workspace *ws)
{
    size_t m = ws->ncell, np = ws->np;
    if (grow_edges(ws, m) != 0)
        return -1;
    const double *cs = ws->cosn + np, *sn = ws->sinn + np;
    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
    for (size_t k = 0; k < m; k++) {
        gp_vec2 a = ws->cell[k], b = ws->cell[k + 1 == m ? 0 : k + 1];
        double ex = b.x - a.x, ey = b.y - a.y, len = hypot(ex, ey);
        ws->nx[k] = len > 0.0 ? ey / len : 0.0; /* outward: the cell is counter-clockwise */
        ws->ny[k] = len > 0.0 ? -ex / len : 0.0;
        ws->h[k] = ws->nx[k] * a.x + ws->ny[k] * a.y;
        ws->ones[k] = 1.0;
        ws->arc0[k] = 0;
        double *pk = ws->proj + 2 * k * np;
        for (size_t j = 0; j < np; j++) {
            pk[j] = pk[np + j] = ws->nx[k] * cs[j] + ws->ny[k] * sn[j];
            if (pk[j] > pk[ws->arc0[k]])
                ws->arc0[k] = j;
        }
        lo[0] = fmin(lo[0], a.x), hi[0] = fmax(hi[0], a.x);
        lo[1] = fmin(lo[1], a.y), hi[1] = fmax(hi[1], a.y);
    }
    double bx[5] = {1, -1, 0, 0, 0}, by[5] = {0, 0, 1, -1, 0};
    for (size_t q = 0; q < 5; q++) {
        ws->nx[m + q] = bx[q];
        ws->ny[m + q] = by[q];
    }
    ws->box[0] = hi[0], ws->box[1] = -lo[0], ws->box[2] = hi[1], ws->box[3] = -lo[1];
    ws->lp_basis[0] = m + 4, ws->lp_basis[1] = m, ws->lp_basis[2] = m + 2;
    return 0;
}

/* The cell in local coordinates: x' = (x - origin) / L with L = sqrt(area), rounded to a
 * 2^-40 grid. The rounding (1e-12 of the cell size) makes the same cell seen at another scale
 * or offset give the same bits here, hence the same search and the same grain; the final
 * containment check is made against the true cell, so it costs no safety. */
static gp_status local_cell(gp_fill_workspace *ws, const gp_vec2 *cell, size_t ncell,
                            gp_vec2 origin, double L, gp_error *err)
{
    if (ncell > ws->cell_cap) {
        gp_vec2 *grown = realloc(ws->cell, ncell * sizeof *grown);
        if (!grown)
            return gp_error_set(err, GP_ERR_NOMEM, "fill: out of memory");
        ws->cell = grown;
        ws->cell_cap = ncell;
    }
    for (size_t k = 0; k < ncell; k++) {
        ws->cell[k].x = ldexp(nearbyint(ldexp((cell[k].x - origin.x) / L, 40)), -40);
        ws->cell[k].y = ldexp(nearbyint(ldexp((cell[k].y - origin.y) / L, 40)), -40);
    }
    ws->ncell = ncell;
    ws->cell_area = gp_poly_area(ws->cell, ncell);
    /* checked on the rounded cell, the one the search sees; its positive area (the cell's,
     * checked by the caller) makes it counter-clockwise */
    ws->convex = is_convex(ws->cell, ncell);
    ws->evals = 0;
    ws->rot = 0;
    ws->use_lp = 0;
    if (cast_rays(ws, (gp_vec2){0.0, 0.0}) != 0)
        return gp_error_set(err, GP_ERR_DEGENERATE, "fill: no interior centre found for the cell");
    if (ws->convex && prepare_edges(ws) != 0)
        return gp_error_set(err, GP_ERR_NOMEM, "fill: out of memory");
    return GP_OK;
}

/* The fixed part of the shape factor (the modes that are not optimised), and a seed for the
 * random starts drawn from the caller's phases: they come from the cell's own stream, so the
 * starts are reproducible and differ from cell to cell without any state here. */
static uint64_t fixed_part(gp_fill_workspace *ws, const double *phases)
{
    size_t np = ws->np;
    uint64_t rs = 0;
    for (size_t i = 0; i < np; i++)
        ws->base[i] = 1.0;
    for (size_t n = 1; n < ws->nm; n++) {
        uint64_t u;
        memcpy(&u, &phases[n], sizeof u);
        uint64_t s = rs ^ u;
        rs = splitmix64(&s);
        if ((n >= FIRST_OPT && n <= LAST_OPT) || ws->p.D[n] == 0.0)
            continue;
        add_mode(ws, ws->base, n, ws->p.D[n], phases[n]);
    }
    return rs;
}

/* The starting phases: those of the DFT of the cell contour seen from the origin (Sect. 4.1),
 * r(theta) ~ sum A_n cos(n theta) + B_n sin(n theta) = |.| cos(n theta - atan2(B, A)), except
 * mode 2, whose axis (delta_2 / 2, the grain's long axis) is set along the cell's own
 * orientation, its minimum-caliper direction (Fig. 1a), which the specimen compares the
 * grain's with: the radius function's mode-2 axis differs from it in irregular cells. This
 * narrows the grain-cell orientation gap at the same solid fraction (docs/design/fill.md). */
static void start_phases(gp_fill_workspace *ws, const double *phases, double *dft)
{
    size_t np = ws->np;
    for (int j = 0; j < NOPT; j++) {
        size_t n = FIRST_OPT + (size_t)j;
        double a = 0.0, b = 0.0;
        for (size_t i = 0; i < np; i++) {
            a += ws->rmax[i] * ws->cosn[n * np + i];
            b += ws->rmax[i] * ws->sinn[n * np + i];
        }
        dft[j] = (a == 0.0 && b == 0.0) ? phases[n] : atan2(b, a);
    }
    double w, ang, len;
    if (gp_min_caliper(ws->cell, ws->ncell, &w, &ang, &len, NULL) == GP_OK)
        dft[0] = remainder(2.0 * ang, 2.0 * M_PI);
}

/* r0 and centre (local) of the chosen shape (rho and rot set): the largest grain, made no
 * larger than F_S. A convex cell centres a grain smaller than the largest so that its
 * clearance to the nearest edge is as large as possible (max t: n_k . c + t <= h_k - r0 s_k),
 * rather than leaving it against three edges. */
static double place(gp_fill_workspace *ws, gp_vec2 *c)
{
    double r0, r0_target = sqrt(ws->p.solid_fraction * ws->cell_area / ws->unit_area);
    if (!ws->convex) {
        if (cast_rays(ws, *c) != 0)
            return 0.0;
        r0 = r0_rays(ws);
        return r0_target < r0 ? r0_target : r0;
    }
    r0 = lp_fit(ws) * (1.0 - ws->p.margin);
    *c = ws->lp_centre;
    if (!(r0_target < r0))
        return r0;
    for (size_t k = 0; k < ws->ncell; k++)
        ws->sup[k] = ws->h[k] - r0_target * ws->sup[k];
    gp_vec2 cc;
    double t;
    if (lp_solve(ws, ws->ones, ws->sup, 1.0, &cc.x, &cc.y, &t) == 0 && t >= 0.0)
        *c = cc;
    return r0_target;
}

/* A sufficient test of gp_poly_inside_poly, an order of magnitude cheaper: every vertex of a
 * strictly on the inner side of every edge of the simple polygon b (orientation `turn`, +1
 * counter-clockwise), exactly (gp_orient2d). The inner half-planes of a simple polygon's edges
 * meet in its kernel, which lies in the polygon, and the kernel is convex, so a holds all of a.
 * When it answers 0 (a vertex on or past an edge line, as in a non-convex cell) the full test
 * decides. */
static int inside_kernel(const gp_vec2 *a, size_t na, const gp_vec2 *b, size_t nb, int turn)
{
    for (size_t k = 0; k < nb; k++) {
        gp_vec2 p = b[k], q = b[k + 1 == nb ? 0 : k + 1];
        for (size_t i = 0; i < na; i++)
            if (gp_orient2d(p, q, a[i]) != turn)
                return 0;
    }
    return 1;
}

/* The contour in world coordinates (cell ray i carries grain ray i - rot), shrunk until it
 * lies exactly inside the cell. Returns the shrink steps taken, or -1. */
static int write_contour(const gp_fill_workspace *ws, const gp_vec2 *cell, size_t ncell,
                         gp_vec2 cw, double rw, gp_vec2 *contour, double *rw_out)
{
    int turn = gp_poly_signed_area(cell, ncell) > 0.0 ? 1 : -1;
    size_t np = ws->np;
    const double *cs = ws->cosn + np, *sn = ws->sinn + np;
    for (int shrink = 0; shrink <= 400; shrink++) {
        for (size_t i = 0, j = (np - ws->rot) % np; i < np; i++, j = j + 1 == np ? 0 : j + 1) {
            double r = rw * ws->rho[j];
            contour[i].x = cw.x + r * cs[i];
            contour[i].y = cw.y + r * sn[i];
        }
        if ((ws->convex && inside_kernel(contour, np, cell, ncell, turn)) ||
            gp_poly_inside_poly(contour, np, cell, ncell)) {
            *rw_out = rw;
            return shrink;
        }
        rw *= 0.99;
    }
    return -1;
}

gp_status gp_fill_cell(gp_fill_workspace *ws, const gp_vec2 *cell, size_t ncell,
                       const double *phases, gp_vec2 *contour, gp_fill_result *res,
                       gp_error *err)
{
    return gp_fill_cell_from(ws, cell, ncell, phases, NULL, contour, res, err);
}

gp_status gp_fill_cell_from(gp_fill_workspace *ws, const gp_vec2 *cell, size_t ncell,
                            const double *phases, const gp_fill_result *start,
                            gp_vec2 *contour, gp_fill_result *res, gp_error *err)
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

    /* Origin: the centroid of a convex cell (it balances the cell's DFT); the pole of
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
    double L = sqrt(area);
    gp_status st = local_cell(ws, cell, ncell, origin, L, err);
    if (st != GP_OK)
        return st;
    uint64_t rs = fixed_part(ws, phases);
    double dft[NOPT];
    start_phases(ws, phases, dft);

    double target = ws->p.solid_fraction;
    gp_vec2 c = {0.0, 0.0};
    candidate best;
    double rots = start ? start->rotation * (double)ws->np / (2.0 * M_PI) : -1.0;
    if (ws->convex && rots >= 0.0 && rots < (double)ws->np)
        search_convex_warm(ws, start->phases + FIRST_OPT, (size_t)(rots + 0.5) % ws->np, &best,
                           target);
    else if (ws->convex)
        search_convex(ws, dft, &best, target, rs);
    else
        search_rays(ws, dft, &best, &c, target);

    /* Rebuild the state of the chosen point (the search may have evaluated others last). */
    ws->rot = best.rot;
    if (!(shape_factor(ws, best.ph) > 0.0))
        return gp_error_set(err, GP_ERR_NOT_STAR,
                            "fill: the spectrum gives r <= 0 (not star-shaped) for every phase tried");
    double r0 = place(ws, &c);
    if (!(r0 > 0.0))
        return gp_error_set(err, GP_ERR_INTERNAL, "fill: the chosen grain does not fit its cell");
    gp_vec2 cw = {origin.x + L * c.x, origin.y + L * c.y};
    double rw;
    res->shrinks = write_contour(ws, cell, ncell, cw, L * r0, contour, &rw);
    if (res->shrinks < 0)
        return gp_error_set(err, GP_ERR_INTERNAL,
                            "fill: grain does not fit its cell even after shrinking");

    res->centre = cw;
    res->r0 = rw;
    res->rotation = 2.0 * M_PI * (double)best.rot / (double)ws->np;
    for (size_t n = 0; n < 8; n++)
        res->phases[n] = n < ws->nm ? phases[n] : 0.0;
    for (int j = 0; j < NOPT; j++)
        res->phases[FIRST_OPT + j] = best.ph[j];
    res->area = gp_poly_area(contour, ws->np);
    res->fraction = res->area / area;
    res->max_fraction = best.f;
    res->target_met = res->fraction >= target * (1.0 - 1e-9);
    res->evals = ws->evals;
    return GP_OK;
}
