/* gp_odec.c -- see gp_odec.h. */
#include "gp_odec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GP_PI 3.14159265358979323846

void gp_odec_params_default(gp_odec_params *p)
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

typedef struct cand {
    double r;
    size_t i;
} cand;

static int cand_cmp(const void *a, const void *b)
{
    const cand *p = a, *q = b;
    if (p->r > q->r)
        return -1;
    if (p->r < q->r)
        return 1;
    return p->i < q->i ? -1 : p->i > q->i;
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

gp_status gp_odec_build(const gp_vec2 *poly, size_t n, const gp_odec_params *params,
                        gp_odec_result *out, gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "odec: out is NULL");
    memset(out, 0, sizeof *out);
    gp_status st = check_poly(poly, n, "odec", err);
    if (st != GP_OK)
        return st;
    gp_odec_params P;
    if (params)
        P = *params;
    else
        gp_odec_params_default(&P);
    if (!(P.r_min > 0 && P.r_min < 10) || !(P.spacing > 0 && P.spacing < 10))
        return gp_error_set(err, GP_ERR_INVALID,
                            "odec: r_min = %g and spacing = %g must be in (0, 10) (relative to "
                            "the equivalent radius)", P.r_min, P.spacing);

    /* scale and duplicate tolerance */
    double xmin = poly[0].x, xmax = xmin, ymin = poly[0].y, ymax = ymin;
    for (size_t i = 1; i < n; i++) {
        xmin = fmin(xmin, poly[i].x);
        xmax = fmax(xmax, poly[i].x);
        ymin = fmin(ymin, poly[i].y);
        ymax = fmax(ymax, poly[i].y);
    }
    double size = fmax(xmax - xmin, ymax - ymin);
    double tol = 1e-12 * size;
    gp_vec2 *q = malloc(n * sizeof *q);
    if (!q)
        return gp_error_set(err, GP_ERR_NOMEM, "odec: out of memory");
    size_t nv = dedupe(poly, n, q, tol * tol);
    double A = nv >= 3 ? gp_poly_signed_area(q, nv) : 0.0;
    if (!(fabs(A) > 1e-12 * size * size)) {
        free(q);
        return gp_error_set(err, GP_ERR_DEGENERATE, "odec: the polygon has no area");
    }
    double orient = A > 0 ? 1.0 : -1.0; /* inward normal = orient * left normal of the edge */
    double req = sqrt(fabs(A) / GP_PI);
    double rmin = P.r_min * req, s = P.spacing * req;
    double gap = sqrt(2.0 * P.spacing * P.r_min) * req;

    /* 1. nodes */
    size_t m = 0;
    for (size_t i = 0; i < nv; i++) {
        gp_vec2 a = q[i], b = q[(i + 1) % nv];
        double len = hypot(b.x - a.x, b.y - a.y);
        m += 1 + (len > gap ? (size_t)ceil(len / gap) - 1 : 0);
    }
    node *nd = malloc(m * sizeof *nd);
    double *rt = malloc(m * sizeof *rt);
    cand *cd = malloc(m * sizeof *cd);
    unsigned char *covered = calloc(m, 1);
    double *forb = malloc(2 * m * sizeof *forb);
    double *X = malloc(m * sizeof *X), *Y = malloc(m * sizeof *Y);
    if (!nd || !rt || !cd || !covered || !forb || !X || !Y) {
        free(X);
        free(Y);
        free(forb);
        free(q);
        free(nd);
        free(rt);
        free(cd);
        free(covered);
        return gp_error_set(err, GP_ERR_NOMEM, "odec: out of memory for %zu nodes", m);
    }
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
    out->nnodes = m;
    out->r_eq = req;
    for (size_t i = 0; i < m; i++) {
        X[i] = nd[i].x;
        Y[i] = nd[i].y;
    }

    /* 2. tangent radii. A vertex is a sample of the grain's (smooth) curve, so its disc is
     * first computed without the nodes inserted on its two own edges (which would shrink it to
     * nothing at any convex vertex); that larger disc is kept if it cuts into those two edges
     * by no more than the tolerance between nodes, delta = r_min - sqrt(r_min^2 - g^2/4),
     * which is what it would do with no inserted nodes; otherwise (a real corner) the disc
     * respects every node. */
    double rcap = 2.0 * hypot(xmax - xmin, ymax - ymin);
    double dup2 = tol * tol;
    double delta = rmin - sqrt(fmax(0.0, rmin * rmin - 0.25 * gap * gap));
    for (size_t i = 0; i < m; i++) {
        double px = nd[i].x, py = nd[i].y, nx = nd[i].nx, ny = nd[i].ny;
        double best = rcap, bex = rcap;
        size_t kn = 0, kp = 0; /* inserted nodes right after / before vertex i */
        if (nd[i].vtx) {
            while (kn + 1 < m && !nd[(i + kn + 1) % m].vtx)
                kn++;
            while (kp + 1 < m && !nd[(i + m - kp - 1) % m].vtx)
                kp++;
        }
        if (nx == 0 && ny == 0) {
            best = bex = 0;
        } else if (kn + kp == 0) {
            for (size_t j = 0; j < m; j++) {
                double ux = X[j] - px, uy = Y[j] - py;
                double un = ux * nx + uy * ny;
                if (un <= 0)
                    continue;
                double u2 = ux * ux + uy * uy;
                if (u2 <= dup2)
                    continue;
                /* r(Q) = |u|^2 / (2 u.n) < best  <=>  u2 < 2 best un */
                if (u2 < 2.0 * best * un)
                    best = u2 / (2.0 * un);
            }
            bex = best;
        } else {
            for (size_t j = 0; j < m; j++) {
                double ux = nd[j].x - px, uy = nd[j].y - py;
                double un = ux * nx + uy * ny;
                if (un <= 0)
                    continue;
                double u2 = ux * ux + uy * uy;
                if (u2 <= dup2)
                    continue;
                if (u2 < 2.0 * best * un) {
                    double rq = u2 / (2.0 * un);
                    best = rq;
                    size_t off = j >= i ? j - i : j + m - i;
                    if ((off > kn && off < m - kp) && rq < bex)
                        bex = rq;
                } else if (u2 < 2.0 * bex * un) {
                    size_t off = j >= i ? j - i : j + m - i;
                    if (off > kn && off < m - kp)
                        bex = u2 / (2.0 * un);
                }
            }
            if (bex > best) {
                /* how far the disc of radius bex cuts into the vertex's own two edges */
                size_t in = (i + kn + 1) % m, ip = (i + m - kp - 1) % m;
                double cx = px + bex * nx, cy = py + bex * ny;
                double d1 = sqrt(seg_dist2(cx, cy, px, py, nd[in].x, nd[in].y));
                double d0 = sqrt(seg_dist2(cx, cy, nd[ip].x, nd[ip].y, px, py));
                if (bex - fmin(d0, d1) <= delta)
                    best = bex;
            }
        }
        rt[i] = best;
        cd[i] = (cand){best, i};
    }
    qsort(cd, m, sizeof *cd, cand_cmp);

    /* 3. discs, largest tangent radius first */
    size_t cap = 0;
    int nomem = 0;
    for (size_t c = 0; c < m && !nomem; c++) {
        size_t i = cd[c].i;
        double r = cd[c].r;
        if (r < rmin)
            break;
        if (covered[i])
            continue;
        if (P.max_discs && out->ndiscs >= P.max_discs) {
            out->capped = 1;
            break;
        }
        double cx = nd[i].x + r * nd[i].nx, cy = nd[i].y + r * nd[i].ny;
        if (!gp_poly_contains(q, nv, (gp_vec2){cx, cy}))
            continue; /* cannot happen for a simple polygon sampled densely enough */
        if (!add_disc(out, &cap, cx, cy, r, nd, m, covered, s))
            nomem = 1;
    }

    /* 4. uncovered nodes: the nearest admissible disc of radius r_min among the discs tangent
     * to the node segments within an arc length 2 (r_min + spacing) + gap on either side. On a
     * segment A -> B (inward unit normal nn) the tangent disc's centre is c(t) = A + r_min nn +
     * t (B - A); it is admissible where no node is closer than r_min to c(t), i.e. outside
     * one interval of t per node; |node - c(t)| is convex in t, so the best admissible t is the
     * unconstrained optimum or an end of a forbidden interval or of the segment. */
    for (size_t i = 0; i < m && !nomem && !out->capped; i++) {
        if (covered[i])
            continue;
        double bestd = INFINITY, bx = 0, by = 0;
        double reach = 2.0 * (rmin + s) + gap;
        for (int dir = -1; dir <= 1; dir += 2) {
            double arc = 0;
            size_t j = i;
            for (size_t steps = 0; steps < m && arc <= reach; steps++) {
                size_t jn = dir > 0 ? (j + 1) % m : (j + m - 1) % m;
                size_t a = dir > 0 ? j : jn, b = dir > 0 ? jn : j; /* contour order a -> b */
                double ex = nd[b].x - nd[a].x, ey = nd[b].y - nd[a].y;
                double ee = ex * ex + ey * ey, el = sqrt(ee);
                arc += el;
                j = jn;
                if (!(el > 0))
                    continue;
                double nnx = -orient * ey / el, nny = orient * ex / el;
                double ox = nd[a].x + rmin * nnx, oy = nd[a].y + rmin * nny;
                size_t nf = 0;
                double eps2 = 1e-18 * rmin * rmin * ee;
                for (size_t o = 0; o < m; o++) {
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
                    if (d < bestd) {
                        bestd = d;
                        bx = cx;
                        by = cy;
                    }
                }
            }
        }
        if (bestd <= s) {
            if (P.max_discs && out->ndiscs >= P.max_discs) {
                out->capped = 1;
                break;
            }
            if (!gp_poly_contains(q, nv, (gp_vec2){bx, by}))
                continue;
            if (!add_disc(out, &cap, bx, by, rmin, nd, m, covered, s))
                nomem = 1;
        }
    }
    size_t unc = 0;
    for (size_t i = 0; i < m; i++)
        unc += !covered[i];
    out->uncovered = unc;

    free(q);
    free(nd);
    free(rt);
    free(cd);
    free(covered);
    free(forb);
    free(X);
    free(Y);
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

    double ymin = poly[0].y, ymax = ymin;
    for (size_t i = 1; i < n; i++) {
        ymin = fmin(ymin, poly[i].y);
        ymax = fmax(ymax, poly[i].y);
    }
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

    /* areas by scanlines */
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

    /* protrusion */
    double prot = 0;
    for (size_t k = 0; k < ndiscs; k++) {
        double d = contour_dist(poly, n, discs[k].x, discs[k].y);
        int inside = gp_poly_contains(poly, n, (gp_vec2){discs[k].x, discs[k].y});
        double p = inside ? discs[k].r - d : discs[k].r + d;
        if (p > prot)
            prot = p;
    }
    q->max_protrusion = prot / req;

    /* h1: contour points (vertices, and every <= 0.01 R_eq along edges) to the union */
    double h1 = 0;
    double step = 0.01 * req;
    if (ndiscs == 0) {
        h1 = INFINITY;
    } else {
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
    }

    /* h2: boundary of the union to the contour */
    double h2 = 0;
    size_t hint = 0;
    for (size_t k = 0; k < ndiscs; k++) {
        double cx = discs[k].x, cy = discs[k].y, r = discs[k].r;
        /* samples at most 0.02 R_eq apart along the circle (at least 16) */
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
    q->hausdorff = fmax(h1, h2) / req;
    free(du);
    free(pu);
    free(xs);
    return GP_OK;
}
