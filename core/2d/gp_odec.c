/* gp_odec.c -- see gp_odec.h. */
#include "gp_odec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define GP_PI 3.14159265358979323846
/* radius_bound's subset: every ODEC_STRIDE-th node and ODEC_NEAR either side of the window */
#define ODEC_STRIDE 8
#define ODEC_NEAR 4

void gp_odec_params_defaults(gp_odec_params *p)
{
    if (!p)
        return;
    p->r_min = 0.05;
    p->spacing = 0.025;
    p->max_discs = 1000;
}

void gp_odec_result_free(gp_odec_result *r)
{
    if (!r)
        return;
    free(r->discs);
    memset(r, 0, sizeof *r);
}

static gp_status check_poly(const gp_vec2 *poly, size_t n, const char *who, gp_error *err)
{
    if (!poly)
        return gp_error_set(err, GP_ERR_INVALID, "%s: polygon is NULL", who);
    if (n < 3)
        return gp_error_set(err, GP_ERR_INVALID, "%s: n = %zu vertices, need >= 3", who, n);
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(poly[i].x) || !isfinite(poly[i].y))
            return gp_error_set(err, GP_ERR_INVALID, "%s: vertex %zu is not finite", who, i);
    }
    return GP_OK;
}

/* Copies poly without consecutive (cyclic) duplicates into q; returns the count. */
static size_t dedupe(const gp_vec2 *poly, size_t n, gp_vec2 *q, double tol2)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (m > 0) {
            double dx = poly[i].x - q[m - 1].x, dy = poly[i].y - q[m - 1].y;
            if (dx * dx + dy * dy <= tol2)
                continue;
        }
        q[m++] = poly[i];
    }
    while (m > 1) {
        double dx = q[m - 1].x - q[0].x, dy = q[m - 1].y - q[0].y;
        if (dx * dx + dy * dy > tol2)
            break;
        m--;
    }
    return m;
}

static double seg_dist2(double px, double py, double ax, double ay, double bx, double by)
{
    double ex = bx - ax, ey = by - ay, wx = px - ax, wy = py - ay;
    double ee = ex * ex + ey * ey;
    double t = ee > 0 ? (wx * ex + wy * ey) / ee : 0.0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    double dx = wx - t * ex, dy = wy - t * ey;
    return dx * dx + dy * dy;
}

typedef struct node {
    double x, y, nx, ny; /* position, unit inward normal (0, 0 if undefined) */
    int vtx;             /* 1 for a polygon vertex, 0 for a node inserted on an edge */
} node;

/* A node in the queue of step 3: its tangent radius (exact) or an upper bound of it. */
typedef struct cand {
    double r;
    size_t i;
    int exact;
} cand;

/* p goes before q: larger r; at equal r a bound before an exact radius (the bound's node may
 * have that radius too and a lower index); then the lower index (gp_odec.h, step 3) */
static int cand_before(const cand *p, const cand *q)
{
    if (p->r != q->r)
        return p->r > q->r;
    if (p->exact != q->exact)
        return !p->exact;
    return p->i < q->i;
}

static void cand_push(cand *h, size_t *n, cand c)
{
    size_t k = (*n)++;
    while (k > 0 && cand_before(&c, &h[(k - 1) / 2])) {
        h[k] = h[(k - 1) / 2];
        k = (k - 1) / 2;
    }
    h[k] = c;
}

static cand cand_pop(cand *h, size_t *n)
{
    cand top = h[0], last = h[--*n];
    size_t k = 0;
    for (;;) {
        size_t c = 2 * k + 1;
        if (c >= *n)
            break;
        if (c + 1 < *n && cand_before(&h[c + 1], &h[c]))
            c++;
        if (!cand_before(&h[c], &last))
            break;
        h[k] = h[c];
        k = c;
    }
    if (*n)
        h[k] = last;
    return top;
}

/* Appends a disc, marking covered nodes; returns 0 on allocation failure. */
static int add_disc(gp_odec_result *out, size_t *cap, double cx, double cy, double r,
                    const node *nd, size_t m, unsigned char *covered, double s)
{
    if (out->ndiscs == *cap) {
        size_t nc = *cap ? 2 * *cap : 16;
        gp_odec_disc *d = realloc(out->discs, nc * sizeof *d);
        if (!d)
            return 0;
        out->discs = d;
        *cap = nc;
    }
    out->discs[out->ndiscs++] = (gp_odec_disc){cx, cy, r};
    double lim = r + s, lim2 = lim * lim;
    for (size_t j = 0; j < m; j++) {
        if (covered[j])
            continue;
        double dx = nd[j].x - cx, dy = nd[j].y - cy;
        if (dx * dx + dy * dy <= lim2)
            covered[j] = 1;
    }
    return 1;
}

/* One ODEC build: the polygon without duplicate vertices, the scales of the algorithm, and the
 * nodes with their tangent radii. The steps of gp_odec.h run in order over this state. */
typedef struct odec_run {
    gp_odec_params P;
    gp_vec2 *q;            /* the polygon, consecutive duplicates dropped: nv vertices */
    size_t nv;
    double orient;         /* inward normal = orient * left normal of an edge */
    double req, rmin, s, gap;
    double tol;            /* duplicate tolerance, 1e-12 of the polygon's size */
    double rcap;           /* no tangent radius exceeds this */
    size_t m;              /* nodes */
    node *nd;
    double *forb, *X, *Y;  /* X, Y: the nodes' coordinates */
    double *XS, *YS;       /* every ODEC_STRIDE-th node's (radius_bound): ms */
    size_t ms;
    double delta;          /* step 2's tolerance for a vertex's own edges */
    cand *cd;              /* step 3's queue */
    unsigned char *covered;
    size_t cap;            /* discs allocated in out */
    gp_odec_result *out;
} odec_run;

static void odec_free(odec_run *R)
{
    free(R->q);
    free(R->nd);
    free(R->XS);
    free(R->cd);
    free(R->covered);
    free(R->forb);
    free(R->X);
    free(R->Y);
}

/* Arguments, parameters, and the polygon's scales: size, duplicates, area, R_eq. */
static gp_status odec_setup(odec_run *R, const gp_vec2 *poly, size_t n, const gp_odec_params *params,
                            gp_error *err)
{
    gp_status st = check_poly(poly, n, "odec", err);
    if (st != GP_OK)
        return st;
    if (params)
        R->P = *params;
    else
        gp_odec_params_defaults(&R->P);
    if (!(R->P.r_min > 0 && R->P.r_min < 10) || !(R->P.spacing > 0 && R->P.spacing < 10))
        return gp_error_set(err, GP_ERR_INVALID,
                            "odec: r_min = %g and spacing = %g must be in (0, 10) (relative to "
                            "the equivalent radius)", R->P.r_min, R->P.spacing);
    gp_vec2 lo, hi;
    gp_poly_bbox(poly, n, &lo, &hi, NULL);
    double size = fmax(hi.x - lo.x, hi.y - lo.y);
    R->tol = 1e-12 * size;
    R->rcap = 2.0 * hypot(hi.x - lo.x, hi.y - lo.y);
    R->q = malloc(n * sizeof *R->q);
    if (!R->q)
        return gp_error_set(err, GP_ERR_NOMEM, "odec: out of memory");
    R->nv = dedupe(poly, n, R->q, R->tol * R->tol);
    double A = R->nv >= 3 ? gp_poly_signed_area(R->q, R->nv) : 0.0;
    if (!(fabs(A) > 1e-12 * size * size))
        return gp_error_set(err, GP_ERR_DEGENERATE, "odec: the polygon has no area");
    R->orient = A > 0 ? 1.0 : -1.0;
    R->req = sqrt(fabs(A) / GP_PI);
    R->rmin = R->P.r_min * R->req;
    R->s = R->P.spacing * R->req;
    R->gap = sqrt(2.0 * R->P.spacing * R->P.r_min) * R->req;
    return GP_OK;
}

/* Step 1: the vertices plus nodes inserted evenly on every edge longer than the gap; a
 * vertex's normal bisects its two edges' inward normals. */
static gp_status odec_nodes(odec_run *R, gp_error *err)
{
    const gp_vec2 *q = R->q;
    const size_t nv = R->nv;
    const double gap = R->gap, orient = R->orient;
    size_t m = 0;
    for (size_t i = 0; i < nv; i++) {
        gp_vec2 a = q[i], b = q[(i + 1) % nv];
        double len = hypot(b.x - a.x, b.y - a.y);
        m += 1 + (len > gap ? (size_t)ceil(len / gap) - 1 : 0);
    }
    R->m = m;
    R->nd = malloc(m * sizeof *R->nd);
    R->ms = (m + ODEC_STRIDE - 1) / ODEC_STRIDE;
    R->XS = malloc(2 * R->ms * sizeof *R->XS);
    R->YS = R->XS ? R->XS + R->ms : NULL;
    R->cd = malloc(m * sizeof *R->cd);
    R->covered = calloc(m, 1);
    R->forb = malloc(2 * m * sizeof *R->forb);
    R->X = malloc(m * sizeof *R->X);
    R->Y = malloc(m * sizeof *R->Y);
    if (!R->nd || !R->XS || !R->cd || !R->covered || !R->forb || !R->X || !R->Y)
        return gp_error_set(err, GP_ERR_NOMEM, "odec: out of memory for %zu nodes", m);
    node *nd = R->nd;
    size_t k = 0;
    for (size_t i = 0; i < nv; i++) {
        gp_vec2 p = q[(i + nv - 1) % nv], a = q[i], b = q[(i + 1) % nv];
        double l0 = hypot(a.x - p.x, a.y - p.y), l1 = hypot(b.x - a.x, b.y - a.y);
        /* inward unit normals of edges p->a and a->b */
        double n0x = -orient * (a.y - p.y) / l0, n0y = orient * (a.x - p.x) / l0;
        double n1x = -orient * (b.y - a.y) / l1, n1y = orient * (b.x - a.x) / l1;
        double sx = n0x + n1x, sy = n0y + n1y, sl = hypot(sx, sy);
        node v = {a.x, a.y, 0, 0, 1};
        if (sl > 1e-9) {
            v.nx = sx / sl;
            v.ny = sy / sl;
        }
        nd[k++] = v;
        if (l1 > gap) {
            size_t extra = (size_t)ceil(l1 / gap) - 1;
            for (size_t e = 1; e <= extra; e++) {
                double t = (double)e / (double)(extra + 1);
                nd[k++] = (node){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), n1x, n1y, 0};
            }
        }
    }
    for (size_t i = 0; i < m; i++) {
        R->X[i] = nd[i].x;
        R->Y[i] = nd[i].y;
    }
    for (size_t p = 0; p < R->ms; p++) {
        R->XS[p] = R->X[p * ODEC_STRIDE];
        R->YS[p] = R->Y[p * ODEC_STRIDE];
    }
    return GP_OK;
}

/* min over nodes j in [j0, j1) of |u|^2 / (2 u.n), u = Q_j - P, taken over the nodes ahead of
 * the tangent at P (u.n > 0) that are not P itself (|u|^2 > dup2): the radius of the disc
 * tangent at P through Q_j; cap when there is none. This is where ODEC spends its time (m^2
 * pairs), so it runs without a branch, two nodes at a time: the quotient is taken for every
 * node and the ones behind the tangent masked to cap. The minimum of the same quotients in any
 * order is the same double, so the result does not depend on the split. */
static double min_radius(const double *restrict X, const double *restrict Y, size_t j0,
                         size_t j1, double px, double py, double nx, double ny, double dup2,
                         double cap)
{
    double best = cap;
    size_t j = j0;
#if defined(__SSE2__)
    const __m128d vpx = _mm_set1_pd(px), vpy = _mm_set1_pd(py), vnx = _mm_set1_pd(nx);
    const __m128d vny = _mm_set1_pd(ny), vd2 = _mm_set1_pd(dup2), vcap = _mm_set1_pd(cap);
    const __m128d zero = _mm_setzero_pd(), two = _mm_set1_pd(2.0);
    __m128d b = vcap;
    for (; j + 2 <= j1; j += 2) {
        __m128d ux = _mm_sub_pd(_mm_loadu_pd(X + j), vpx);
        __m128d uy = _mm_sub_pd(_mm_loadu_pd(Y + j), vpy);
        __m128d un = _mm_add_pd(_mm_mul_pd(ux, vnx), _mm_mul_pd(uy, vny));
        __m128d u2 = _mm_add_pd(_mm_mul_pd(ux, ux), _mm_mul_pd(uy, uy));
        __m128d ok = _mm_and_pd(_mm_cmpgt_pd(un, zero), _mm_cmpgt_pd(u2, vd2));
        /* where !ok the quotient may be inf or NaN: masked before the min */
        __m128d q = _mm_div_pd(u2, _mm_mul_pd(two, un));
        q = _mm_or_pd(_mm_and_pd(ok, q), _mm_andnot_pd(ok, vcap));
        b = _mm_min_pd(b, q);
    }
    double lanes[2];
    _mm_storeu_pd(lanes, b);
    best = lanes[0] < lanes[1] ? lanes[0] : lanes[1];
#endif
    for (; j < j1; j++) {
        double ux = X[j] - px, uy = Y[j] - py;
        double un = ux * nx + uy * ny, u2 = ux * ux + uy * uy;
        if (un > 0 && u2 > dup2) {
            double q = u2 / (2.0 * un);
            best = q < best ? q : best;
        }
    }
    return best;
}

/* The same over the cyclic index range of `count` points from j (j < m) of X, Y (m each). */
static double min_radius_ring(const double *X, const double *Y, size_t m, size_t j, size_t count,
                              double px, double py, double nx, double ny, double dup2, double cap)
{
    size_t first = count < m - j ? count : m - j;
    double b = min_radius(X, Y, j, j + first, px, py, nx, ny, dup2, cap);
    if (count > first)
        b = min_radius(X, Y, 0, count - first, px, py, nx, ny, dup2, b);
    return b;
}

static double min_radius_cyclic(const odec_run *R, size_t j, size_t count, double px, double py,
                                double nx, double ny, double cap)
{
    return min_radius_ring(R->X, R->Y, R->m, j, count, px, py, nx, ny, R->tol * R->tol, cap);
}

/* The window of node i: the first index w0 and count wn of the vertex i with the nodes inserted
 * on its two edges (wn = 1, w0 = i for an inserted node or a vertex without them). */
static void node_window(const odec_run *R, size_t i, size_t *w0, size_t *wn)
{
    const node *nd = R->nd;
    const size_t m = R->m;
    size_t kn = 0, kp = 0;
    if (nd[i].vtx) {
        while (kn + 1 < m && !nd[(i + kn + 1) % m].vtx)
            kn++;
        while (kp + 1 < m && !nd[(i + m - kp - 1) % m].vtx)
            kp++;
    }
    *w0 = (i + m - kp) % m;
    *wn = kp + kn + 1;
}

/* Step 2 for node i: the largest disc tangent at it that holds no node. A vertex is a sample of
 * the grain's (smooth) curve, so its disc is first computed without the nodes inserted on its
 * two own edges (which would shrink it to nothing at any convex vertex); that larger disc is
 * kept if it cuts into those two edges by no more than the tolerance between nodes,
 * delta = r_min - sqrt(r_min^2 - g^2/4), which is what it would do with no inserted nodes;
 * otherwise (a real corner) the disc respects every node. The two discs are the minimum over
 * the nodes off those edges (bex) and that and the edges' own nodes (best). */
static double tangent_radius(const odec_run *R, size_t i, double delta)
{
    const node *nd = R->nd;
    const size_t m = R->m;
    double px = nd[i].x, py = nd[i].y, nx = nd[i].nx, ny = nd[i].ny;
    size_t w0, wn; /* the vertex and the nodes inserted on its edges, i - kp .. i + kn */
    node_window(R, i, &w0, &wn);
    size_t kp = (i + m - w0) % m, kn = wn - 1 - kp;
    if (nx == 0 && ny == 0)
        return 0;
    if (wn == 1) /* the common case: every node */
        return min_radius_cyclic(R, 0, m, px, py, nx, ny, R->rcap);
    double bex = wn < m ? min_radius_cyclic(R, (w0 + wn) % m, m - wn, px, py, nx, ny, R->rcap)
                        : R->rcap;
    double best = min_radius_cyclic(R, w0, wn < m ? wn : m, px, py, nx, ny, bex);
    if (bex > best) {
        /* how far the disc of radius bex cuts into the vertex's own two edges */
        size_t in = (i + kn + 1) % m, ip = (i + m - kp - 1) % m;
        double cx = px + bex * nx, cy = py + bex * ny;
        double d1 = sqrt(seg_dist2(cx, cy, px, py, nd[in].x, nd[in].y));
        double d0 = sqrt(seg_dist2(cx, cy, nd[ip].x, nd[ip].y, px, py));
        if (bex - fmin(d0, d1) <= delta)
            best = bex;
    }
    return best;
}

/* An upper bound of node i's tangent radius: the minimum of step 2 over a subset of the nodes
 * off its window -- the ODEC_NEAR either side of it and every ODEC_STRIDE-th -- which is >= the
 * minimum over all of them (bex), which is >= the radius (best or bex). About a sixth of the
 * pairs of the exact radius. */
static double radius_bound(const odec_run *R, size_t i)
{
    const node *n = &R->nd[i];
    const size_t m = R->m, K = ODEC_STRIDE, ms = R->ms;
    if (n->nx == 0 && n->ny == 0)
        return 0;
    size_t w0, wn;
    node_window(R, i, &w0, &wn);
    if (wn + 2 * ODEC_NEAR + K >= m)
        return tangent_radius(R, i, R->delta);
    double b = min_radius_cyclic(R, (w0 + wn) % m, ODEC_NEAR, n->x, n->y, n->nx, n->ny, R->rcap);
    b = min_radius_cyclic(R, (w0 + m - ODEC_NEAR) % m, ODEC_NEAR, n->x, n->y, n->nx, n->ny, b);
    /* subset positions p (node p K) off the window [w0, w0 + wn), cyclic */
    size_t e = w0 + wn, in, start;
    if (e <= m) {
        start = (e + K - 1) / K;
        in = start - (w0 + K - 1) / K;
    } else {
        start = (e - m + K - 1) / K;
        in = ms - (w0 + K - 1) / K + start;
    }
    if (in < ms)
        b = min_radius_ring(R->XS, R->YS, ms, start % ms, ms - in, n->x, n->y, n->nx, n->ny,
                            R->tol * R->tol, b);
    return b;
}

/* Steps 2 and 3 together, lazily: the queue starts with every node's upper bound; a node that
 * comes first by its bound gets its exact radius and goes back in; one that comes first by its
 * exact radius is the node step 3 takes next (every node still queued has a radius no larger,
 * and ties go by index as there). A node found covered leaves the queue without its exact
 * radius, which is most of them: the exact radii (O(m) each) are taken for a small fraction of
 * the nodes (docs/design/geometry.md). The discs and their order are those of computing every
 * radius and sorting.
 * 0, or -1 when out of memory. */
static int odec_discs(odec_run *R)
{
    R->delta = R->rmin - sqrt(fmax(0.0, R->rmin * R->rmin - 0.25 * R->gap * R->gap));
    size_t nq = 0;
    for (size_t i = 0; i < R->m; i++)
        cand_push(R->cd, &nq, (cand){radius_bound(R, i), i, 0});
    while (nq > 0) {
        cand c = cand_pop(R->cd, &nq);
        size_t i = c.i;
        double r = c.r;
        if (r < R->rmin)
            break; /* the radii still queued are all below r_min */
        if (R->covered[i])
            continue;
        if (!c.exact) {
            cand_push(R->cd, &nq, (cand){tangent_radius(R, i, R->delta), i, 1});
            continue;
        }
        if (R->P.max_discs && R->out->ndiscs >= R->P.max_discs) {
            R->out->capped = 1;
            break;
        }
        const node *n = &R->nd[i];
        double cx = n->x + r * n->nx, cy = n->y + r * n->ny;
        if (!gp_poly_contains(R->q, R->nv, (gp_vec2){cx, cy}))
            continue; /* cannot happen for a simple polygon sampled densely enough */
        if (!add_disc(R->out, &R->cap, cx, cy, r, R->nd, R->m, R->covered, R->s))
            return -1;
    }
    return 0;
}

/* The admissible disc of radius r_min tangent to segment a -> b nearest to node i: on the
 * segment (inward unit normal nn) the centre is c(t) = a + r_min nn + t (b - a); it is
 * admissible where no node is closer than r_min to c(t), i.e. outside one interval of t per
 * node; |node - c(t)| is convex in t, so the best admissible t is the unconstrained optimum or
 * an end of a forbidden interval or of the segment. Updates *bestd and (*bx, *by). */
static void segment_disc(odec_run *R, size_t i, size_t a, size_t b, double *bestd, double *bx,
                         double *by)
{
    const node *nd = R->nd;
    const double rmin = R->rmin;
    double *forb = R->forb;
    double ex = nd[b].x - nd[a].x, ey = nd[b].y - nd[a].y;
    double ee = ex * ex + ey * ey, el = sqrt(ee);
    double nnx = -R->orient * ey / el, nny = R->orient * ex / el;
    double ox = nd[a].x + rmin * nnx, oy = nd[a].y + rmin * nny;
    size_t nf = 0;
    double eps2 = 1e-18 * rmin * rmin * ee;
    for (size_t o = 0; o < R->m; o++) {
        double wx = nd[o].x - ox, wy = nd[o].y - oy;
        double we = wx * ex + wy * ey;
        double D = we * we - ee * (wx * wx + wy * wy - rmin * rmin);
        if (D <= eps2)
            continue;
        double sq = sqrt(D);
        double t1 = (we - sq) / ee, t2 = (we + sq) / ee;
        if (t2 <= 0 || t1 >= 1)
            continue;
        forb[2 * nf] = t1;
        forb[2 * nf + 1] = t2;
        nf++;
    }
    double tc[3];
    double tstar = ((nd[i].x - ox) * ex + (nd[i].y - oy) * ey) / ee;
    tc[0] = tstar < 0 ? 0 : (tstar > 1 ? 1 : tstar);
    tc[1] = 0;
    tc[2] = 1;
    for (size_t c = 0; c < 3 + 2 * nf; c++) {
        double t = c < 3 ? tc[c] : forb[c - 3];
        if (t < 0 || t > 1)
            continue;
        int ok = 1;
        for (size_t f = 0; f < nf && ok; f++)
            ok = !(t > forb[2 * f] + 1e-12 && t < forb[2 * f + 1] - 1e-12);
        if (!ok)
            continue;
        double cx = ox + t * ex, cy = oy + t * ey;
        double d = hypot(nd[i].x - cx, nd[i].y - cy) - rmin;
        if (d < *bestd) {
            *bestd = d;
            *bx = cx;
            *by = cy;
        }
    }
}

/* Step 4: each node still uncovered, by index, gets the nearest admissible disc of radius
 * r_min among those tangent to the node segments within an arc length 2 (r_min + spacing) +
 * gap on either side, if it comes within spacing of the node. 0, or -1 when out of memory. */
static int odec_corners(odec_run *R)
{
    const size_t m = R->m;
    const double reach = 2.0 * (R->rmin + R->s) + R->gap;
    for (size_t i = 0; i < m && !R->out->capped; i++) {
        if (R->covered[i])
            continue;
        double bestd = INFINITY, bx = 0, by = 0;
        for (int dir = -1; dir <= 1; dir += 2) {
            double arc = 0;
            size_t j = i;
            for (size_t steps = 0; steps < m && arc <= reach; steps++) {
                size_t jn = dir > 0 ? (j + 1) % m : (j + m - 1) % m;
                size_t a = dir > 0 ? j : jn, b = dir > 0 ? jn : j; /* contour order a -> b */
                double ex = R->nd[b].x - R->nd[a].x, ey = R->nd[b].y - R->nd[a].y;
                double el = sqrt(ex * ex + ey * ey);
                arc += el;
                j = jn;
                if (el > 0)
                    segment_disc(R, i, a, b, &bestd, &bx, &by);
            }
        }
        if (bestd <= R->s) {
            if (R->P.max_discs && R->out->ndiscs >= R->P.max_discs) {
                R->out->capped = 1;
                break;
            }
            if (!gp_poly_contains(R->q, R->nv, (gp_vec2){bx, by}))
                continue;
            if (!add_disc(R->out, &R->cap, bx, by, R->rmin, R->nd, m, R->covered, R->s))
                return -1;
        }
    }
    return 0;
}

gp_status gp_odec_build(const gp_vec2 *poly, size_t n, const gp_odec_params *params,
                        gp_odec_result *out, gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "odec: out is NULL");
    memset(out, 0, sizeof *out);
    odec_run R;
    memset(&R, 0, sizeof R);
    R.out = out;
    gp_status st = odec_setup(&R, poly, n, params, err);
    if (st == GP_OK)
        st = odec_nodes(&R, err);
    if (st != GP_OK) {
        odec_free(&R);
        return st;
    }
    out->nnodes = R.m;
    out->r_eq = R.req;
    int nomem = odec_discs(&R) != 0 || odec_corners(&R) != 0;
    size_t unc = 0;
    for (size_t i = 0; i < R.m; i++)
        unc += !R.covered[i];
    out->uncovered = unc;
    odec_free(&R);
    if (nomem) {
        gp_odec_result_free(out);
        return gp_error_set(err, GP_ERR_NOMEM, "odec: out of memory for discs");
    }
    return GP_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* quality measures */

static double contour_dist(const gp_vec2 *p, size_t n, double x, double y)
{
    double best = INFINITY;
    gp_vec2 a = p[n - 1];
    for (size_t i = 0; i < n; i++) {
        double d = seg_dist2(x, y, a.x, a.y, p[i].x, p[i].y);
        if (d < best)
            best = d;
        a = p[i];
    }
    return sqrt(best);
}

/* Distance from (x, y) to the contour if it exceeds thresh, else some value <= thresh (early
 * exit: for a running maximum only larger distances matter). Segments are visited outwards
 * from *hint (the nearest segment of the previous query), which is updated. */
static double contour_dist_above(const gp_vec2 *p, size_t n, double x, double y, double thresh,
                                 size_t *hint)
{
    double best = INFINITY, t2 = thresh * thresh;
    size_t h = *hint < n ? *hint : 0, bi = h;
    for (size_t k = 0; k < n; k++) {
        size_t off = (k + 1) / 2;
        size_t i = (k & 1) ? (h + off) % n : (h + n - off % n) % n;
        size_t i0 = (i + n - 1) % n;
        double d = seg_dist2(x, y, p[i0].x, p[i0].y, p[i].x, p[i].y);
        if (d < best) {
            best = d;
            bi = i;
            if (best <= t2)
                break;
        }
    }
    *hint = bi;
    return sqrt(best);
}

typedef struct ival {
    double a, b;
} ival;

static int ival_cmp(const void *x, const void *y)
{
    const ival *p = x, *q = y;
    return (p->a > q->a) - (p->a < q->a);
}

static int dbl_cmp(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* merges sorted intervals in place; returns the new count */
static size_t merge_ivals(ival *v, size_t k)
{
    if (k == 0)
        return 0;
    size_t w = 0;
    for (size_t i = 1; i < k; i++) {
        if (v[i].a <= v[w].b) {
            if (v[i].b > v[w].b)
                v[w].b = v[i].b;
        } else {
            v[++w] = v[i];
        }
    }
    return w + 1;
}

/* total length of the intersection of two sorted disjoint interval lists */
static double inter_len(const ival *u, size_t nu, const ival *v, size_t nv)
{
    double L = 0;
    size_t i = 0, j = 0;
    while (i < nu && j < nv) {
        double lo = fmax(u[i].a, v[j].a), hi = fmin(u[i].b, v[j].b);
        if (hi > lo)
            L += hi - lo;
        if (u[i].b < v[j].b)
            i++;
        else
            j++;
    }
    return L;
}

/* area_ratio and area_excess by 512 scanlines: on each, the union of the disc chords and the
 * polygon's inside intervals, exactly in x. */
static gp_status scan_areas(const gp_vec2 *poly, size_t n, const gp_odec_disc *discs,
                            size_t ndiscs, double area, gp_odec_quality *q, gp_error *err)
{
    gp_vec2 lo, hi;
    gp_poly_bbox(poly, n, &lo, &hi, NULL);
    double ymin = lo.y, ymax = hi.y;
    for (size_t k = 0; k < ndiscs; k++) {
        ymin = fmin(ymin, discs[k].y - discs[k].r);
        ymax = fmax(ymax, discs[k].y + discs[k].r);
    }
    ival *du = malloc((ndiscs + 1) * sizeof *du);
    ival *pu = malloc((n / 2 + 2) * sizeof *pu);
    double *xs = malloc((n + 2) * sizeof *xs);
    if (!du || !pu || !xs) {
        free(du);
        free(pu);
        free(xs);
        return gp_error_set(err, GP_ERR_NOMEM, "odec quality: out of memory");
    }
    const size_t nlines = 512;
    double h = (ymax - ymin) / (double)nlines;
    double a_union = 0, a_inter = 0;
    for (size_t l = 0; l < nlines; l++) {
        double y = ymin + ((double)l + 0.5) * h;
        size_t nd = 0;
        for (size_t k = 0; k < ndiscs; k++) {
            double dy = y - discs[k].y, w2 = discs[k].r * discs[k].r - dy * dy;
            if (w2 > 0) {
                double w = sqrt(w2);
                du[nd++] = (ival){discs[k].x - w, discs[k].x + w};
            }
        }
        if (nd == 0)
            continue;
        qsort(du, nd, sizeof *du, ival_cmp);
        nd = merge_ivals(du, nd);
        for (size_t k = 0; k < nd; k++)
            a_union += (du[k].b - du[k].a) * h;
        size_t nx = 0;
        gp_vec2 a = poly[n - 1];
        for (size_t i = 0; i < n; i++) {
            gp_vec2 b = poly[i];
            if ((a.y > y) != (b.y > y))
                xs[nx++] = a.x + (y - a.y) / (b.y - a.y) * (b.x - a.x);
            a = b;
        }
        qsort(xs, nx, sizeof *xs, dbl_cmp);
        size_t np = 0;
        for (size_t i = 0; i + 1 < nx; i += 2)
            pu[np++] = (ival){xs[i], xs[i + 1]};
        a_inter += inter_len(du, nd, pu, np) * h;
    }
    q->area_ratio = a_inter / area;
    q->area_excess = fmax(0.0, (a_union - a_inter) / area);
    free(du);
    free(pu);
    free(xs);
    return GP_OK;
}

/* max over discs of how far each reaches beyond the contour (r - distance, or r + distance for
 * a centre outside), 0 if none does */
static double max_protrusion(const gp_vec2 *poly, size_t n, const gp_odec_disc *discs,
                             size_t ndiscs)
{
    double prot = 0;
    for (size_t k = 0; k < ndiscs; k++) {
        double d = contour_dist(poly, n, discs[k].x, discs[k].y);
        int inside = gp_poly_contains(poly, n, (gp_vec2){discs[k].x, discs[k].y});
        double p = inside ? discs[k].r - d : discs[k].r + d;
        if (p > prot)
            prot = p;
    }
    return prot;
}

/* h1: contour points (vertices, and every <= step along edges) to the union */
static double contour_to_union(const gp_vec2 *poly, size_t n, const gp_odec_disc *discs,
                               size_t ndiscs, double step)
{
    if (ndiscs == 0)
        return INFINITY;
    double h1 = 0;
    gp_vec2 a = poly[n - 1];
    for (size_t i = 0; i < n; i++) {
        gp_vec2 b = poly[i];
        double len = hypot(b.x - a.x, b.y - a.y);
        size_t ns = (size_t)ceil(len / step);
        if (ns < 1)
            ns = 1;
        for (size_t t = 0; t < ns; t++) {
            double f = (double)t / (double)ns;
            double x = a.x + f * (b.x - a.x), y = a.y + f * (b.y - a.y);
            double best = INFINITY;
            for (size_t k = 0; k < ndiscs; k++) {
                double d = hypot(x - discs[k].x, y - discs[k].y) - discs[k].r;
                if (d < best)
                    best = d;
            }
            if (best > h1)
                h1 = best;
        }
        a = b;
    }
    return h1;
}

/* h2: the boundary of the union to the contour, sampled at the pairwise circle intersections
 * on it (the cusps) and at most 0.02 R_eq apart along each circle (at least 16 points) */
static double union_to_contour(const gp_vec2 *poly, size_t n, const gp_odec_disc *discs,
                               size_t ndiscs, double req)
{
    double h2 = 0;
    size_t hint = 0;
    for (size_t k = 0; k < ndiscs; k++) {
        double cx = discs[k].x, cy = discs[k].y, r = discs[k].r;
        int nsamp = (int)ceil(2.0 * GP_PI * r / (0.02 * req));
        nsamp = nsamp < 16 ? 16 : (nsamp > 4096 ? 4096 : nsamp);
        for (size_t j = 0; j <= ndiscs; j++) {
            /* j < ndiscs: the two intersection points with circle j; j == ndiscs: samples */
            int cnt;
            double px[2], py[2];
            if (j == ndiscs) {
                cnt = nsamp;
            } else {
                if (j == k)
                    continue;
                double dx = discs[j].x - cx, dy = discs[j].y - cy, d = hypot(dx, dy);
                double rj = discs[j].r;
                if (d >= r + rj || d <= fabs(r - rj) || d == 0)
                    continue;
                double a = (r * r - rj * rj + d * d) / (2 * d);
                double hh = sqrt(fmax(0.0, r * r - a * a));
                double mx = cx + a * dx / d, my = cy + a * dy / d;
                px[0] = mx - hh * dy / d;
                py[0] = my + hh * dx / d;
                px[1] = mx + hh * dy / d;
                py[1] = my - hh * dx / d;
                cnt = 2;
            }
            for (int t = 0; t < cnt; t++) {
                if (j == ndiscs) {
                    double th = 2.0 * GP_PI * t / nsamp;
                    px[0] = cx + r * cos(th);
                    py[0] = cy + r * sin(th);
                }
                int ti = j == ndiscs ? 0 : t;
                int inside = 0;
                for (size_t o = 0; o < ndiscs && !inside; o++) {
                    if (o == k || o == j)
                        continue;
                    double ex = px[ti] - discs[o].x, ey = py[ti] - discs[o].y;
                    double ro = discs[o].r * (1 - 1e-12);
                    inside = ex * ex + ey * ey < ro * ro;
                }
                if (inside)
                    continue;
                double d = contour_dist_above(poly, n, px[ti], py[ti], h2, &hint);
                if (d > h2)
                    h2 = d;
            }
        }
    }
    return h2;
}

gp_status gp_odec_measure(const gp_vec2 *poly, size_t n, const gp_odec_disc *discs,
                          size_t ndiscs, gp_odec_quality *q, gp_error *err)
{
    if (!q)
        return gp_error_set(err, GP_ERR_INVALID, "odec quality: q is NULL");
    memset(q, 0, sizeof *q);
    gp_status st = check_poly(poly, n, "odec quality", err);
    if (st != GP_OK)
        return st;
    if (ndiscs > 0 && !discs)
        return gp_error_set(err, GP_ERR_INVALID, "odec quality: discs is NULL");
    for (size_t k = 0; k < ndiscs; k++) {
        if (!isfinite(discs[k].x) || !isfinite(discs[k].y) || !(discs[k].r > 0) ||
            !isfinite(discs[k].r))
            return gp_error_set(err, GP_ERR_INVALID, "odec quality: disc %zu is invalid", k);
    }
    double area = gp_poly_area(poly, n);
    if (!(area > 0))
        return gp_error_set(err, GP_ERR_DEGENERATE, "odec quality: the polygon has no area");
    double req = sqrt(area / GP_PI);
    st = scan_areas(poly, n, discs, ndiscs, area, q, err);
    if (st != GP_OK)
        return st;
    q->max_protrusion = max_protrusion(poly, n, discs, ndiscs) / req;
    double h1 = contour_to_union(poly, n, discs, ndiscs, 0.01 * req);
    double h2 = union_to_contour(poly, n, discs, ndiscs, req);
    q->hausdorff = fmax(h1, h2) / req;
    return GP_OK;
}
