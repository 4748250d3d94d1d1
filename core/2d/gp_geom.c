/* gp_geom.c -- see gp_geom.h.
 *
 * Precision strategy
 *  - Metric quantities (area, centroid, distances, circles, calipers) are evaluated on
 *    coordinates taken relative to a reference vertex, so that a small polygon far from the
 *    origin (x = 1e6 + small) keeps its relative precision.
 *  - Combinatorial decisions (hull turns, segment crossings, point classification used by
 *    gp_poly_is_simple / gp_poly_inside_poly / gp_poly_overlap) use an exact orientation
 *    predicate: Shewchuk's floating-point filter, and when the filter cannot decide, an exact
 *    evaluation of the 2x2 determinant as a floating-point expansion (products split exactly
 *    with fma, summed with error-free TwoSum). The sign is therefore exact for every finite
 *    input (barring overflow / underflow of the products, i.e. |coordinates| < ~1e150 and
 *    differences not below ~1e-150).
 *
 * Memory: gp_max_inscribed_circle and gp_min_caliper allocate a temporary buffer (freed before
 * they return; GP_ERR_NOMEM if that fails). Everything else works in the caller's memory.
 */
#include "gp_geom.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define GP_PI 3.14159265358979323846

/* ------------------------------------------------------------------------------------------ */
/* helpers                                                                                     */

static inline int finite2(gp_vec2 v) { return isfinite(v.x) && isfinite(v.y); }

static int all_finite(const gp_vec2 *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!finite2(p[i])) return 0;
    return 1;
}

/* inline min / max for finite values (fmin / fmax are library calls without -ffast-math) */
static inline double dmin(double a, double b) { return a < b ? a : b; }
static inline double dmax(double a, double b) { return a > b ? a : b; }

static inline int veq(gp_vec2 a, gp_vec2 b) { return a.x == b.x && a.y == b.y; }

/* lexicographic (x, then y) */
static inline int vlt(gp_vec2 a, gp_vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

static void bbox_of(const gp_vec2 *p, size_t n, double *x0, double *y0, double *x1, double *y1)
{
    double a = p[0].x, b = p[0].y, c = p[0].x, d = p[0].y;
    size_t i = 1;
#if defined(__SSE2__)
    /* (x, y) at once; minpd(v, m) is v < m ? v : m, the test below, NaN skipped alike */
    __m128d lo = _mm_loadu_pd(&p[0].x), hi = lo;
    for (; i < n; i++) {
        __m128d v = _mm_loadu_pd(&p[i].x);
        lo = _mm_min_pd(v, lo);
        hi = _mm_max_pd(v, hi);
    }
    double l[2], h[2];
    _mm_storeu_pd(l, lo);
    _mm_storeu_pd(h, hi);
    a = l[0], b = l[1], c = h[0], d = h[1];
#endif
    for (; i < n; i++) {
        if (p[i].x < a) a = p[i].x;
        if (p[i].x > c) c = p[i].x;
        if (p[i].y < b) b = p[i].y;
        if (p[i].y > d) d = p[i].y;
    }
    *x0 = a;
    *y0 = b;
    *x1 = c;
    *y1 = d;
}

gp_status gp_poly_bbox(const gp_vec2 *p, size_t n, gp_vec2 *lo, gp_vec2 *hi, gp_error *err)
{
    if (!p || n == 0) return gp_error_set(err, GP_ERR_INVALID, "bbox: need n >= 1 points");
    if (!all_finite(p, n)) return gp_error_set(err, GP_ERR_INVALID, "bbox: non-finite vertex");
    double x0, y0, x1, y1;
    bbox_of(p, n, &x0, &y0, &x1, &y1);
    if (lo) *lo = (gp_vec2){x0, y0};
    if (hi) *hi = (gp_vec2){x1, y1};
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* exact orientation                                                                           */

static inline void two_sum(double a, double b, double *s, double *e)
{
    double x = a + b;
    double bv = x - a;
    double av = x - bv;
    *e = (a - av) + (b - bv);
    *s = x;
}

/* sign of ax*by - ax*cy - ay*bx + ay*cx + bx*cy - by*cx, computed exactly */
static int orient_exact(gp_vec2 a, gp_vec2 b, gp_vec2 c)
{
    const double f[6][2] = {{a.x, b.y}, {-a.x, c.y}, {-a.y, b.x},
                            {a.y, c.x}, {b.x, c.y}, {-b.y, c.x}};
    double t[12];
    for (int i = 0; i < 6; i++) {
        double pr = f[i][0] * f[i][1];
        t[2 * i] = pr;
        t[2 * i + 1] = fma(f[i][0], f[i][1], -pr);
    }
    /* grow a non-overlapping expansion term by term (Shewchuk's Grow-Expansion with zero
     * elimination); its sign is the sign of its largest (last) component */
    double e[13];
    int m = 0;
    for (int k = 0; k < 12; k++) {
        double q = t[k];
        int len = 0;
        for (int i = 0; i < m; i++) {
            double s, h;
            two_sum(q, e[i], &s, &h);
            if (h != 0.0) e[len++] = h;
            q = s;
        }
        if (q != 0.0) e[len++] = q;
        m = len;
    }
    if (m == 0) return 0;
    return e[m - 1] > 0.0 ? 1 : -1;
}

static inline int sgn(double v) { return (v > 0.0) - (v < 0.0); }

/* +1 if a, b, c turn counter-clockwise, -1 clockwise, 0 collinear (exact). */
static inline int orient(gp_vec2 a, gp_vec2 b, gp_vec2 c)
{
    const double errA = (3.0 + 16.0 * (DBL_EPSILON / 2)) * (DBL_EPSILON / 2);
    double detl = (a.x - c.x) * (b.y - c.y);
    double detr = (a.y - c.y) * (b.x - c.x);
    double det = detl - detr, detsum;
    if (detl > 0.0) {
        if (detr <= 0.0) return sgn(det);
        detsum = detl + detr;
    } else if (detl < 0.0) {
        if (detr >= 0.0) return sgn(det);
        detsum = -detl - detr;
    } else {
        return sgn(det);
    }
    double bound = errA * detsum;
    if (det >= bound || -det >= bound) return sgn(det);
    return orient_exact(a, b, c);
}

int gp_orient2d(gp_vec2 a, gp_vec2 b, gp_vec2 c) { return orient(a, b, c); }

/* closed segments [a,b] and [c,d] share a point (exact) */
static int seg_intersect(gp_vec2 a, gp_vec2 b, gp_vec2 c, gp_vec2 d)
{
    if (dmax(a.x, b.x) < dmin(c.x, d.x) || dmax(c.x, d.x) < dmin(a.x, b.x) ||
        dmax(a.y, b.y) < dmin(c.y, d.y) || dmax(c.y, d.y) < dmin(a.y, b.y))
        return 0;
    int o1 = orient(a, b, c), o2 = orient(a, b, d);
    if (o1 * o2 > 0) return 0;
    int o3 = orient(c, d, a), o4 = orient(c, d, b);
    if (o3 * o4 > 0) return 0;
    /* all collinear: the bounding boxes overlap, hence so do the segments */
    return 1;
}

int gp_segments_intersect(gp_vec2 a, gp_vec2 b, gp_vec2 c, gp_vec2 d)
{
    if (!finite2(a) || !finite2(b) || !finite2(c) || !finite2(d)) return 0;
    return seg_intersect(a, b, c, d);
}

/* ------------------------------------------------------------------------------------------ */
/* area, perimeter, centroid                                                                   */

double gp_poly_signed_area(const gp_vec2 *p, size_t n)
{
    if (!p || n < 3) return 0.0;
    const gp_vec2 o = p[0];
    double s = 0.0;
    double px = p[1].x - o.x, py = p[1].y - o.y;
    for (size_t i = 2; i < n; i++) {
        double qx = p[i].x - o.x, qy = p[i].y - o.y;
        s += px * qy - py * qx;
        px = qx;
        py = qy;
    }
    return 0.5 * s;
}

double gp_poly_area(const gp_vec2 *p, size_t n) { return fabs(gp_poly_signed_area(p, n)); }

double gp_poly_perimeter(const gp_vec2 *p, size_t n)
{
    if (!p || n < 2) return 0.0;
    double s = 0.0;
    for (size_t i = 0, j = n - 1; i < n; j = i++) s += hypot(p[i].x - p[j].x, p[i].y - p[j].y);
    return s;
}

/* 1 if every vertex lies on one line (exact), including n < 3 and all-equal */
static int all_collinear(const gp_vec2 *p, size_t n)
{
    size_t i = 1;
    while (i < n && veq(p[i], p[0])) i++;
    if (i >= n) return 1;
    for (size_t k = i + 1; k < n; k++)
        if (orient(p[0], p[i], p[k]) != 0) return 0;
    return 1;
}

gp_status gp_poly_centroid(const gp_vec2 *p, size_t n, gp_vec2 *c, gp_error *err)
{
    if (!p || n == 0 || !c) return gp_error_set(err, GP_ERR_INVALID, "centroid: need n >= 1 points");
    if (!all_finite(p, n)) return gp_error_set(err, GP_ERR_INVALID, "centroid: non-finite vertex");
    const gp_vec2 o = p[0];
    double a2 = 0.0, aabs = 0.0, sx = 0.0, sy = 0.0, mx = 0.0, my = 0.0;
    for (size_t i = 0; i < n; i++) {
        double xi = p[i].x - o.x, yi = p[i].y - o.y;
        mx += xi;
        my += yi;
        if (i + 1 < n) {
            double xj = p[i + 1].x - o.x, yj = p[i + 1].y - o.y;
            double cr = xi * yj - xj * yi;
            a2 += cr;
            aabs += fabs(cr);
            sx += (xi + xj) * cr;
            sy += (yi + yj) * cr;
        }
    }
    if (n < 3 || a2 == 0.0 || fabs(a2) <= 1e-13 * aabs || all_collinear(p, n)) {
        c->x = o.x + mx / (double)n;
        c->y = o.y + my / (double)n;
        return gp_error_set(err, GP_ERR_DEGENERATE, "centroid: polygon has zero area");
    }
    c->x = o.x + sx / (3.0 * a2);
    c->y = o.y + sy / (3.0 * a2);
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* distances                                                                                   */

static inline double seg_dist2(double qx, double qy, double ax, double ay, double bx, double by)
{
    double dx = bx - ax, dy = by - ay, wx = qx - ax, wy = qy - ay;
    double l2 = dx * dx + dy * dy;
    double t = wx * dx + wy * dy;
    if (t <= 0.0 || l2 <= 0.0) return wx * wx + wy * wy;
    if (t >= l2) {
        double ux = qx - bx, uy = qy - by;
        return ux * ux + uy * uy;
    }
    t /= l2;
    double ex = wx - t * dx, ey = wy - t * dy;
    return ex * ex + ey * ey;
}

double gp_segment_distance(gp_vec2 q, gp_vec2 a, gp_vec2 b)
{
    return sqrt(seg_dist2(q.x, q.y, a.x, a.y, b.x, b.y));
}

double gp_poly_boundary_distance(const gp_vec2 *p, size_t n, gp_vec2 q)
{
    if (!p || n == 0) return INFINITY;
    if (n == 1) return hypot(q.x - p[0].x, q.y - p[0].y);
    double m = INFINITY;
    for (size_t i = 0, j = n - 1; i < n; j = i++) {
        double d = seg_dist2(q.x, q.y, p[j].x, p[j].y, p[i].x, p[i].y);
        if (d < m) m = d;
    }
    return sqrt(m);
}

/* ------------------------------------------------------------------------------------------ */
/* point in polygon                                                                            */

/* The one point-in-polygon test of core/2d (even-odd rule): 1 inside, 0 on the boundary, -1
 * outside. Crossings are decided by the exact orientation predicate. With tol >= 0 a point
 * within tol of an edge is on the boundary too (gp_poly_contains); with tol < 0 only a point
 * exactly on it (the exact predicates of gp_poly_inside_poly and gp_poly_overlap). */
/* point_class's test of one edge a -> b: 1 when q lies on it (within tol when tol >= 0), else
 * 0 with the crossing parity *c updated */
static inline int edge_class(gp_vec2 a, gp_vec2 b, gp_vec2 q, double tol, double tol2, int *c)
{
    if (tol >= 0.0 && q.x >= dmin(a.x, b.x) - tol && q.x <= dmax(a.x, b.x) + tol &&
        q.y >= dmin(a.y, b.y) - tol && q.y <= dmax(a.y, b.y) + tol &&
        seg_dist2(q.x, q.y, a.x, a.y, b.x, b.y) <= tol2)
        return 1;
    if ((a.y > q.y) != (b.y > q.y)) {
        int o = orient(a, b, q);
        if (o == 0) return 1;
        if ((o > 0) == (b.y > a.y)) *c ^= 1;
    } else if (a.y == q.y && b.y == q.y) {
        if ((a.x <= q.x && q.x <= b.x) || (b.x <= q.x && q.x <= a.x)) return 1;
    } else if (veq(a, q)) {
        return 1;
    }
    return 0;
}

static int point_class(const gp_vec2 *p, size_t n, gp_vec2 q, double tol)
{
    const double tol2 = tol * tol;
    int c = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++) {
        if (edge_class(p[j], p[i], q, tol, tol2, &c)) return 0;
    }
    return c ? 1 : -1;
}

/* point_class(p, n, q, tol) >= 0 for tol >= 0, n >= 2: an edge matters to it only when q lies
 * in its bounding box widened by tol or its ends straddle q's line; two edges at a time are
 * screened for that (most are neither) and only those go through point_class's own tests, in
 * the same order: ODEC checks every disc centre, so this test is hot (docs/design/geometry.md). */
static int contains_screened(const gp_vec2 *p, size_t n, gp_vec2 q, double tol)
{
#if defined(__SSE2__)
    const double tol2 = tol * tol;
    const __m128d qx = _mm_set1_pd(q.x), qy = _mm_set1_pd(q.y), vt = _mm_set1_pd(tol);
    int c = 0;
    for (size_t i = 0; i < n; i += 2) {
        /* edges j -> i and i -> i + 1 (j = i - 1 cyclic; the second absent when i + 1 == n) */
        size_t j = i ? i - 1 : n - 1, k = i + 1 < n ? i + 1 : 0;
        __m128d pa = _mm_loadu_pd(&p[j].x), pb = _mm_loadu_pd(&p[i].x);
        __m128d pc = _mm_loadu_pd(&p[k].x);
        __m128d ax = _mm_unpacklo_pd(pa, pb), ay = _mm_unpackhi_pd(pa, pb);
        __m128d bx = _mm_unpacklo_pd(pb, pc), by = _mm_unpackhi_pd(pb, pc);
        __m128d near = _mm_and_pd(
            _mm_and_pd(_mm_cmpge_pd(qx, _mm_sub_pd(_mm_min_pd(ax, bx), vt)),
                       _mm_cmple_pd(qx, _mm_add_pd(_mm_max_pd(ax, bx), vt))),
            _mm_and_pd(_mm_cmpge_pd(qy, _mm_sub_pd(_mm_min_pd(ay, by), vt)),
                       _mm_cmple_pd(qy, _mm_add_pd(_mm_max_pd(ay, by), vt))));
        __m128d strad = _mm_xor_pd(_mm_cmpgt_pd(ay, qy), _mm_cmpgt_pd(by, qy));
        int mask = _mm_movemask_pd(_mm_or_pd(near, strad)) & (i + 1 < n ? 3 : 1);
        for (int e = 0; e < 2; e++) {
            if (!(mask >> e & 1)) continue;
            if (edge_class(e ? p[i] : p[j], e ? p[k] : p[i], q, tol, tol2, &c)) return 0;
        }
    }
    return c ? 1 : -1;
#else
    return point_class(p, n, q, tol);
#endif
}

int gp_poly_contains(const gp_vec2 *p, size_t n, gp_vec2 q)
{
    if (!p || n == 0 || !finite2(q)) return 0;
    double x0, y0, x1, y1;
    bbox_of(p, n, &x0, &y0, &x1, &y1);
    double size = fmax(x1 - x0, y1 - y0);
    if (!isfinite(size)) return 0;
    double tol = 1e-12 * size;
    if (q.x < x0 - tol || q.x > x1 + tol || q.y < y0 - tol || q.y > y1 + tol) return 0;
    /* a point exactly on a horizontal edge or on a vertex is within tol of that edge, so
     * point_class's exact boundary cases add nothing here */
    return (n >= 2 ? contains_screened(p, n, q, tol) : point_class(p, n, q, tol)) >= 0;
}

/* ------------------------------------------------------------------------------------------ */
/* sorting (lexicographic), no allocation                                                      */

static inline void vswap(gp_vec2 *a, gp_vec2 *b)
{
    gp_vec2 t = *a;
    *a = *b;
    *b = t;
}

static void sift_down(gp_vec2 *v, size_t root, size_t n)
{
    for (;;) {
        size_t c = 2 * root + 1;
        if (c >= n) return;
        if (c + 1 < n && vlt(v[c], v[c + 1])) c++;
        if (!vlt(v[root], v[c])) return;
        vswap(&v[root], &v[c]);
        root = c;
    }
}

static void heap_sort(gp_vec2 *v, size_t n)
{
    if (n < 2) return;
    for (size_t i = n / 2; i-- > 0;) sift_down(v, i, n);
    for (size_t end = n - 1; end > 0; end--) {
        vswap(&v[0], &v[end]);
        sift_down(v, 0, end);
    }
}

static void insertion_sort(gp_vec2 *v, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        gp_vec2 x = v[i];
        size_t j = i;
        while (j > 0 && vlt(x, v[j - 1])) {
            v[j] = v[j - 1];
            j--;
        }
        v[j] = x;
    }
}

/* introsort: median-of-three quicksort, heap sort past a depth limit, insertion sort below 16 */
static void sort_pts_rec(gp_vec2 *v, size_t n, int depth)
{
    while (n > 16) {
        if (depth-- <= 0) {
            heap_sort(v, n);
            return;
        }
        size_t mid = n / 2;
        if (vlt(v[mid], v[0])) vswap(&v[mid], &v[0]);
        if (vlt(v[n - 1], v[0])) vswap(&v[n - 1], &v[0]);
        if (vlt(v[n - 1], v[mid])) vswap(&v[n - 1], &v[mid]);
        gp_vec2 piv = v[mid];
        size_t i = 0, j = n - 1;
        for (;;) {
            while (vlt(v[i], piv)) i++;
            while (vlt(piv, v[j])) j--;
            if (i >= j) break;
            vswap(&v[i], &v[j]);
            i++;
            j--;
        }
        /* [0, j] <= piv <= [j + 1, n) with 0 <= j < n - 1 */
        size_t nl = j + 1, nr = n - nl;
        if (nl < nr) {
            sort_pts_rec(v, nl, depth);
            v += nl;
            n = nr;
        } else {
            sort_pts_rec(v + nl, nr, depth);
            n = nl;
        }
    }
    insertion_sort(v, n);
}

static void sort_pts(gp_vec2 *v, size_t n)
{
    int depth = 0;
    for (size_t m = n; m > 1; m >>= 1) depth += 2;
    sort_pts_rec(v, n, depth);
}

static void reverse_pts(gp_vec2 *v, size_t n)
{
    for (size_t i = 0, j = n; i + 1 < j; i++, j--) vswap(&v[i], &v[j - 1]);
}

/* ------------------------------------------------------------------------------------------ */
/* convex hull                                                                                 */

/* Andrew's monotone chain, done in place in h: the points are split by the line A-B (A the
 * lexicographically smallest, B the largest) into the lower set (on or below A-B, sorted
 * ascending) followed by the upper set (strictly above, sorted descending); one scan of that
 * sequence never writes past the point it reads, so h needs only n slots. Non-finite points
 * are ignored. */
size_t gp_convex_hull(const gp_vec2 *p, size_t n, gp_vec2 *h)
{
    if (!p || !h || n == 0) return 0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (finite2(p[i])) h[m++] = p[i];
    if (m == 0) return 0;
    size_t ia = 0, ib = 0;
    for (size_t i = 1; i < m; i++) {
        if (vlt(h[i], h[ia])) ia = i;
        if (vlt(h[ib], h[i])) ib = i;
    }
    const gp_vec2 A = h[ia], B = h[ib];
    if (veq(A, B)) {
        h[0] = A;
        return 1;
    }
    size_t nl = 0;
    for (size_t i = 0; i < m; i++)
        if (orient(A, B, h[i]) <= 0) vswap(&h[nl++], &h[i]);
    sort_pts(h, nl);
    sort_pts(h + nl, m - nl);
    reverse_pts(h + nl, m - nl);

    size_t k = 0;
    for (size_t i = 0; i < nl; i++) {
        gp_vec2 q = h[i];
        while (k >= 2 && orient(h[k - 2], h[k - 1], q) <= 0) k--;
        h[k++] = q;
    }
    const size_t t = k + 1;
    for (size_t i = nl; i < m; i++) {
        gp_vec2 q = h[i];
        while (k >= t && orient(h[k - 2], h[k - 1], q) <= 0) k--;
        h[k++] = q;
    }
    while (k >= t && orient(h[k - 2], h[k - 1], A) <= 0) k--;

    /* start at the lowest, then leftmost vertex */
    size_t s = 0;
    for (size_t i = 1; i < k; i++)
        if (h[i].y < h[s].y || (h[i].y == h[s].y && h[i].x < h[s].x)) s = i;
    if (s) {
        reverse_pts(h, s);
        reverse_pts(h + s, k - s);
        reverse_pts(h, k);
    }
    return k;
}

/* Graham's scan needs no sort here: a polygon star-shaped about an interior point lists its
 * vertices by angle about that point already, and one stack pass from a strict hull vertex
 * (the lowest-then-leftmost) in counter-clockwise order keeps exactly the strict left turns
 * (Graham 1972; the "three coins" pass). */
size_t gp_convex_hull_star(const gp_vec2 *p, size_t n, gp_vec2 *h)
{
    if (!p || !h || n == 0) return 0;
    if (n < 3 || !all_finite(p, n)) return gp_convex_hull(p, n, h);
    size_t s = 0;
    for (size_t i = 1; i < n; i++)
        if (p[i].y < p[s].y || (p[i].y == p[s].y && p[i].x < p[s].x)) s = i;
    int ccw = gp_poly_signed_area(p, n) > 0.0;
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        gp_vec2 q = p[ccw ? (s + k) % n : (s + n - k) % n];
        while (m >= 2 && orient(h[m - 2], h[m - 1], q) <= 0) m--;
        h[m++] = q;
    }
    while (m >= 3 && orient(h[m - 2], h[m - 1], h[0]) <= 0) m--;
    return m;
}

/* ------------------------------------------------------------------------------------------ */
/* minimum enclosing circle                                                                    */

typedef struct {
    double x, y, r2;
} circ;

static inline int circ_outside(const circ *c, double x, double y)
{
    double dx = x - c->x, dy = y - c->y;
    return dx * dx + dy * dy > c->r2 * (1.0 + 1e-12);
}

static circ circ2(double ax, double ay, double bx, double by)
{
    circ c;
    c.x = 0.5 * (ax + bx);
    c.y = 0.5 * (ay + by);
    double dx = bx - ax, dy = by - ay;
    c.r2 = 0.25 * (dx * dx + dy * dy);
    return c;
}

static circ circ3(double ax, double ay, double bx, double by, double cx, double cy)
{
    double ux = bx - ax, uy = by - ay, vx = cx - ax, vy = cy - ay;
    double d = 2.0 * (ux * vy - uy * vx);
    double U = ux * ux + uy * uy, V = vx * vx + vy * vy;
    if (fabs(d) <= 1e-14 * 2.0 * sqrt(U * V)) {
        /* (numerically) collinear: the diametral circle of the farthest pair */
        double wx = cx - bx, wy = cy - by, W = wx * wx + wy * wy;
        if (U >= V && U >= W) return circ2(ax, ay, bx, by);
        if (V >= W) return circ2(ax, ay, cx, cy);
        return circ2(bx, by, cx, cy);
    }
    double ox = (vy * U - uy * V) / d, oy = (ux * V - vx * U) / d;
    circ c = {ax + ox, ay + oy, ox * ox + oy * oy};
    return c;
}

static size_t gcd_sz(size_t a, size_t b)
{
    while (b) {
        size_t t = a % b;
        a = b;
        b = t;
    }
    return a;
}

/* Welzl's incremental algorithm (three nested loops). The points are visited in a fixed
 * pseudo-random order -- index k -> (k * s) mod n with s ~ n / golden ratio and gcd(s, n) = 1 --
 * which spreads contour points like a shuffle without RNG, state or memory; expected O(n). */
gp_status gp_min_enclosing_circle(const gp_vec2 *p, size_t n, gp_vec2 *center, double *radius,
                                  gp_error *err)
{
    if (!p || n == 0 || !center || !radius)
        return gp_error_set(err, GP_ERR_INVALID, "min_enclosing_circle: need n >= 1 points");
    if (!all_finite(p, n))
        return gp_error_set(err, GP_ERR_INVALID, "min_enclosing_circle: non-finite point");
    const gp_vec2 o = p[0];
    size_t s = 1;
    if (n > 2) {
        s = (size_t)((double)n * 0.6180339887498949);
        if (s < 1) s = 1;
        while (gcd_sz(s, n) != 1) s++;
    }
#define PX(idx) (p[idx].x - o.x)
#define PY(idx) (p[idx].y - o.y)
    circ c = {0.0, 0.0, 0.0};
    size_t pi = 0;
    for (size_t i = 1; i < n; i++) {
        pi += s;
        if (pi >= n) pi -= n;
        if (!circ_outside(&c, PX(pi), PY(pi))) continue;
        c.x = PX(pi);
        c.y = PY(pi);
        c.r2 = 0.0;
        size_t pj = 0;
        for (size_t j = 0; j < i; j++, pj = (pj + s >= n ? pj + s - n : pj + s)) {
            if (!circ_outside(&c, PX(pj), PY(pj))) continue;
            c = circ2(PX(pi), PY(pi), PX(pj), PY(pj));
            size_t pk = 0;
            for (size_t k = 0; k < j; k++, pk = (pk + s >= n ? pk + s - n : pk + s)) {
                if (!circ_outside(&c, PX(pk), PY(pk))) continue;
                c = circ3(PX(pi), PY(pi), PX(pj), PY(pj), PX(pk), PY(pk));
            }
        }
    }
#undef PX
#undef PY
    center->x = o.x + c.x;
    center->y = o.y + c.y;
    *radius = sqrt(c.r2);
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* maximum inscribed circle (pole of inaccessibility)                                          */

/* clamp to [0, 1] without a branch (the hot loop below would mispredict one) */
static inline double clamp01(double t)
{
#if defined(__SSE2__)
    return _mm_cvtsd_f64(_mm_min_sd(_mm_max_sd(_mm_set_sd(t), _mm_setzero_pd()), _mm_set_sd(1.0)));
#else
    return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
#endif
}

typedef struct {
    double x, y, h, d, max;
    size_t e1; /* nearest edge of the centre: where the children start their scan */
    size_t coff, clen; /* the edges that can be nearest in the cell (mic_src); clen 0: all */
} mic_cell;

/* The polygon relative to the reference vertex, stored twice over (2n edges) so that a scan of
 * all n edges can start anywhere without wrapping. */
typedef struct {
    size_t n;
    const double *x, *y;        /* 2n + 1 */
    const double *dx, *dy, *il; /* 2n */
} mic_poly;

enum { MIC_BLOCK = 16, MIC_K = 6 };

/* d2 (of edge i) into the sorted list mk/ik of the MIC_K nearest so far, if it belongs there */
static inline void nearest_k_add(double mk[MIC_K], size_t ik[MIC_K], double d2, size_t i)
{
    if (!(d2 < mk[MIC_K - 1])) return;
    int j = MIC_K - 1;
    for (; j > 0 && d2 < mk[j - 1]; j--) {
        mk[j] = mk[j - 1];
        ik[j] = ik[j - 1];
    }
    mk[j] = d2;
    ik[j] = i;
}

#define MIC_SQRT2 1.4142135623730951

/* Signed distance from (px, py) to the boundary (> 0 inside), scanning the edges from s;
 * near[0..MIC_K-1]: the nearest edges, nearest first. Gives up early, returning -INFINITY, as
 * soon as some edge is within sqrt(thr2) (thr2 < 0: never). */
static double mic_sdist(const mic_poly *P, double px, double py, size_t s, double thr2,
                        size_t near[MIC_K])
{
    const size_t n = P->n;
    const double *X = P->x + s, *Y = P->y + s, *DX = P->dx + s, *DY = P->dy + s, *IL = P->il + s;
    int inside = 0;
    double mk[MIC_K];
    size_t ik[MIC_K];
    for (int k = 0; k < MIC_K; k++) {
        mk[k] = INFINITY;
        ik[k] = 0;
    }
    double blk[MIC_BLOCK];
#if defined(__SSE2__)
    const __m128d vpx = _mm_set1_pd(px), vpy = _mm_set1_pd(py), zero = _mm_setzero_pd();
    const __m128d one = _mm_set1_pd(1.0);
#endif
    for (size_t b = 0; b < n; b += MIC_BLOCK) {
        size_t cnt = n - b < MIC_BLOCK ? n - b : MIC_BLOCK;
        size_t k = 0;
#if defined(__SSE2__)
        /* two edges at a time: squared distances into blk, ray crossings counted */
        for (; k + 2 <= cnt; k += 2) {
            size_t i = b + k;
            __m128d ay = _mm_loadu_pd(Y + i), by = _mm_loadu_pd(Y + i + 1);
            __m128d ddx = _mm_loadu_pd(DX + i), ddy = _mm_loadu_pd(DY + i);
            __m128d wx = _mm_sub_pd(vpx, _mm_loadu_pd(X + i)), wy = _mm_sub_pd(vpy, ay);
            __m128d t = _mm_mul_pd(_mm_add_pd(_mm_mul_pd(wx, ddx), _mm_mul_pd(wy, ddy)),
                                   _mm_loadu_pd(IL + i));
            t = _mm_min_pd(_mm_max_pd(t, zero), one);
            __m128d ex = _mm_sub_pd(wx, _mm_mul_pd(t, ddx)), ey = _mm_sub_pd(wy, _mm_mul_pd(t, ddy));
            _mm_storeu_pd(blk + k, _mm_add_pd(_mm_mul_pd(ex, ex), _mm_mul_pd(ey, ey)));
            /* crossing: straddles py (half-open) and q is left of the edge seen upward */
            __m128d s1 = _mm_cmpgt_pd(ay, vpy), s2 = _mm_cmpgt_pd(by, vpy);
            __m128d c = _mm_sub_pd(_mm_mul_pd(wx, ddy), _mm_mul_pd(ddx, wy));
            __m128d cr = _mm_or_pd(_mm_and_pd(s2, _mm_cmplt_pd(c, zero)),
                                   _mm_and_pd(s1, _mm_cmpgt_pd(c, zero)));
            cr = _mm_and_pd(cr, _mm_xor_pd(s1, s2));
            int mm = _mm_movemask_pd(cr);
            inside ^= (mm & 1) ^ (mm >> 1);
        }
#endif
        for (; k < cnt; k++) {
            size_t i = b + k;
            double ax = X[i], ay = Y[i], by = Y[i + 1], ddx = DX[i], ddy = DY[i];
            double wx = px - ax, wy = py - ay;
            double c = wx * ddy - ddx * wy;
            if ((ay > py) != (by > py) && (by > py ? c < 0.0 : c > 0.0)) inside ^= 1;
            double t = clamp01((wx * ddx + wy * ddy) * IL[i]);
            double ex = wx - t * ddx, ey = wy - t * ddy;
            blk[k] = ex * ex + ey * ey;
        }
        for (k = 0; k < cnt; k++)
            nearest_k_add(mk, ik, blk[k], b + k);
        if (mk[0] <= thr2) return -INFINITY;
    }
    for (int k = 0; k < MIC_K; k++) near[k] = mk[k] < INFINITY ? (ik[k] + s) % n : (size_t)-1;
    double d = sqrt(mk[0]);
    return inside ? d : -d;
}

/* mic_sdist over the edges of list L only, the sign given (it is known from the parent cell):
 * the same distance formula, the same nearest-K list and early exit. */
static double mic_sdist_list(const mic_poly *P, const size_t *L, size_t m, double px, double py,
                             double sign, double thr2, size_t near[MIC_K])
{
    double mk[MIC_K];
    size_t ik[MIC_K];
    for (int k = 0; k < MIC_K; k++) {
        mk[k] = INFINITY;
        ik[k] = (size_t)-1;
    }
    for (size_t q = 0; q < m; q++) {
        size_t i = L[q];
        double wx = px - P->x[i], wy = py - P->y[i], ddx = P->dx[i], ddy = P->dy[i];
        double t = clamp01((wx * ddx + wy * ddy) * P->il[i]);
        double ex = wx - t * ddx, ey = wy - t * ddy;
        nearest_k_add(mk, ik, ex * ex + ey * ey, i);
        if (mk[0] <= thr2) return -INFINITY;
    }
    for (int k = 0; k < MIC_K; k++) near[k] = ik[k];
    return sign * sqrt(mk[0]);
}

/* Where a cell's children are evaluated from: the popped parent's centre (cx, cy), signed
 * distance cd and the list L (len) of the edges that can be nearest anywhere in it. */
typedef struct {
    const size_t *L;
    size_t len;
    double cx, cy, cd;
} mic_src;

/* The signed distance at (x, y) inside src's cell (src NULL: a full scan from edge `start`).
 * A point closer to the parent's centre than |cd| is on the same side of the boundary, so
 * only the listed edges need a look; otherwise the full scan counts crossings. */
static double mic_eval(const mic_poly *P, const mic_src *src, double x, double y, size_t start,
                       double thr2, size_t near[MIC_K])
{
    if (src && fabs(src->cd) > hypot(x - src->cx, y - src->cy))
        return mic_sdist_list(P, src->L, src->len, x, y, src->cd > 0.0 ? 1.0 : -1.0, thr2, near);
    return mic_sdist(P, x, y, start, thr2, near);
}

/* distance from (px, py) to edge e (relative coordinates) */
static inline double mic_edist(const mic_poly *P, size_t e, double px, double py)
{
    double dx = P->dx[e], dy = P->dy[e], wx = px - P->x[e], wy = py - P->y[e];
    double t = clamp01((wx * dx + wy * dy) * P->il[e]);
    double ex = wx - t * dx, ey = wy - t * dy;
    return sqrt(ex * ex + ey * ey);
}

/* max over a triangle (barycentric over vertex values V[f][0..2] of k affine functions) of
 * their minimum; the point is returned as barycentric weights of vertices 1 and 2 */
static double mic_tri_lp(int k, const double V[][3], double *wb, double *wc)
{
    double best = -INFINITY, bb = 0.0, bc = 0.0;
#define MIC_TRY(lb, lc)                                                                       \
    do {                                                                                      \
        double la_ = 1.0 - (lb) - (lc), m_ = INFINITY;                                        \
        for (int f_ = 0; f_ < k; f_++) {                                                      \
            double v_ = la_ * V[f_][0] + (lb) * V[f_][1] + (lc) * V[f_][2];                  \
            m_ = v_ < m_ ? v_ : m_;                                                           \
        }                                                                                     \
        if (m_ > best) {                                                                      \
            best = m_;                                                                        \
            bb = (lb);                                                                        \
            bc = (lc);                                                                        \
        }                                                                                     \
    } while (0)
    static const double vb[3] = {0, 1, 0}, vc[3] = {0, 0, 1};
    for (int v = 0; v < 3; v++) MIC_TRY(vb[v], vc[v]);
    for (int i = 0; i < k; i++)
        for (int j = i + 1; j < k; j++) {
            double g[3];
            for (int v = 0; v < 3; v++) g[v] = V[i][v] - V[j][v];
            /* the crease g = 0 across each side of the triangle */
            for (int v = 0; v < 3; v++) {
                int w = v == 2 ? 0 : v + 1;
                if ((g[v] < 0.0 && g[w] > 0.0) || (g[v] > 0.0 && g[w] < 0.0)) {
                    double s = g[v] / (g[v] - g[w]);
                    MIC_TRY(vb[v] + s * (vb[w] - vb[v]), vc[v] + s * (vc[w] - vc[v]));
                }
            }
            /* where three functions are equal */
            for (int l = j + 1; l < k; l++) {
                double q[3];
                for (int v = 0; v < 3; v++) q[v] = V[i][v] - V[l][v];
                /* g0 + lb (g1 - g0) + lc (g2 - g0) = 0, same for q */
                double a11 = g[1] - g[0], a12 = g[2] - g[0], a21 = q[1] - q[0], a22 = q[2] - q[0];
                double det = a11 * a22 - a12 * a21;
                if (det == 0.0) continue;
                double lb = (-g[0] * a22 + q[0] * a12) / det, lc = (-q[0] * a11 + g[0] * a21) / det;
                if (lb >= 0.0 && lc >= 0.0 && lb + lc <= 1.0) MIC_TRY(lb, lc);
            }
        }
#undef MIC_TRY
    *wb = bb;
    *wc = bc;
    return best;
}

/* A tighter bound than d + h sqrt 2, and a probe point. For every edge e, d(q) <= dist(q, e),
 * and dist(., e) is convex, so on each half of the cell (split along a diagonal) it is below
 * the plane through its values at the three corners. Hence over the cell d <= the max, over
 * the two triangles, of the minimum of those planes for the nearest edges (dominated ones
 * dropped): a tiny LP, solved by enumerating triangle corners, creases meeting sides, and
 * triple points. Exact when the nearest features are edges seen from inside (so a ridge
 * between parallel edges, e.g. the axis of a rectangle, is discarded at once), within
 * ~h^2 / r near a vertex. Returns the bound and its argmax (*px, *py), where d is worth a probe:
 * in a cell that holds the pole it lands next to it. */
static double mic_lp_bound(const mic_poly *P, double x, double y, double h,
                           const size_t near[MIC_K], double *px, double *py)
{
    /* corners: 0 (-h,-h), 1 (h,-h), 2 (h,h), 3 (-h,h) */
    static const double cu[4] = {-1, 1, 1, -1}, cv[4] = {-1, -1, 1, 1};
    double F[MIC_K][4];
    int k = 0;
    for (int i = 0; i < MIC_K; i++) {
        if (near[i] == (size_t)-1) break;
        for (int c = 0; c < 4; c++) F[k][c] = mic_edist(P, near[i], x + cu[c] * h, y + cv[c] * h);
        /* drop it if an earlier (nearer) one is nowhere larger, or replace dominated ones */
        int dominated = 0;
        for (int j = 0; j < k && !dominated; j++)
            dominated = F[j][0] <= F[k][0] && F[j][1] <= F[k][1] && F[j][2] <= F[k][2] &&
                        F[j][3] <= F[k][3];
        if (!dominated) k++;
        if (k == 4) break;
    }
    if (k == 0) return INFINITY;
    double V[4][3], wb, wc, best = -INFINITY;
    /* triangle (0, 1, 2) and triangle (0, 2, 3) */
    static const int tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (int t = 0; t < 2; t++) {
        for (int f = 0; f < k; f++)
            for (int v = 0; v < 3; v++) V[f][v] = F[f][tri[t][v]];
        double m = mic_tri_lp(k, (const double(*)[3])V, &wb, &wc);
        if (m > best) {
            best = m;
            int A = tri[t][0], B = tri[t][1], C = tri[t][2];
            double wa = 1.0 - wb - wc;
            *px = x + h * (wa * cu[A] + wb * cu[B] + wc * cu[C]);
            *py = y + h * (wa * cv[A] + wb * cv[B] + wc * cv[C]);
        }
    }
    return best;
}

typedef struct {
    mic_cell *a;
    size_t n, cap;
} mic_heap;

static int heap_push(mic_heap *H, mic_cell c)
{
    if (H->n == H->cap) {
        size_t nc = H->cap ? 2 * H->cap : 256;
        mic_cell *na = realloc(H->a, nc * sizeof *na);
        if (!na) return -1;
        H->a = na;
        H->cap = nc;
    }
    size_t i = H->n++;
    while (i > 0) {
        size_t par = (i - 1) / 2;
        if (H->a[par].max >= c.max) break;
        H->a[i] = H->a[par];
        i = par;
    }
    H->a[i] = c;
    return 0;
}

/* the candidate edge lists of the popped cells, appended (offsets stay valid as it grows) */
typedef struct {
    size_t *a;
    size_t n, cap;
} mic_arena;

static int mic_arena_grow(mic_arena *A, size_t more)
{
    if (A->n + more <= A->cap) return 0;
    size_t nc = A->cap ? 2 * A->cap : 1024;
    while (nc < A->n + more) nc *= 2;
    size_t *na = realloc(A->a, nc * sizeof *na);
    if (!na) return -1;
    A->a = na;
    A->cap = nc;
    return 0;
}

static mic_cell heap_pop(mic_heap *H)
{
    mic_cell top = H->a[0], last = H->a[--H->n];
    size_t i = 0, n = H->n;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= n) break;
        if (c + 1 < n && H->a[c + 1].max > H->a[c].max) c++;
        if (H->a[c].max <= last.max) break;
        H->a[i] = H->a[c];
        i = c;
    }
    if (n) H->a[i] = last;
    return top;
}

static size_t mic_start(const mic_poly *P, size_t e)
{
    if (P->n <= MIC_BLOCK) return 0;
    return (e + P->n - MIC_BLOCK / 2) % P->n;
}

/* Evaluates the cell centred at (x, y) with half-side h, updating *best with its centre and
 * with its LP probe point. Returns 1 when the cell must be kept (its bound exceeds best + tol);
 * 0 when it provably cannot hold a point better than best + tol. */
static int mic_make(const mic_poly *P, const mic_src *src, double x, double y, double h,
                    size_t start, double tol, mic_cell *best, mic_cell *c)
{
    c->x = x;
    c->y = y;
    c->h = h;
    double thr = dmin(best->d, best->d + tol - h * MIC_SQRT2);
    size_t near[MIC_K];
    c->coff = c->clen = 0;
    c->d = mic_eval(P, src, x, y, mic_start(P, start), thr > 0.0 ? thr * thr : -1.0, near);
    if (c->d == -INFINITY) return 0;
    c->e1 = near[0];
    c->max = c->d + h * MIC_SQRT2;
    if (c->d > best->d) *best = *c;
    if (h <= 0.0 || c->max - best->d <= tol) return c->max - best->d > tol;
    double qx = x, qy = y;
    double u = mic_lp_bound(P, x, y, h, near, &qx, &qy);
    if (u < c->max) c->max = u;
    if (u < INFINITY && c->max - best->d > tol) {
        /* probe the LP's argmax: when the model is right this is the pole of the cell */
        mic_cell q;
        size_t nq[MIC_K];
        double thq = best->d;
        q.x = qx;
        q.y = qy;
        q.h = 0.0;
        q.coff = q.clen = 0;
        q.d = mic_eval(P, src, qx, qy, mic_start(P, near[0]), thq > 0.0 ? thq * thq : -1.0, nq);
        if (q.d > best->d) {
            q.e1 = nq[0];
            q.max = q.d;
            *best = q;
        }
    }
    return c->max - best->d > tol;
}

/* Branch and bound over square cells (polylabel, Agafonkin 2016, with tighter bounds).
 * Guarantee: with exact distances the returned radius r satisfies r <= r_true <= r + tol.
 * The signed distance to the boundary is 1-Lipschitz, so a square cell of half-side h centred
 * at c holds no point farther than d(c) + h sqrt 2 from the boundary (nor farther than the LP
 * bound of mic_lp_bound); the grid over the bounding box is refined, best bound first, until no
 * cell's bound exceeds the best distance found by more than tol. Rounding adds about 1e-15 of
 * the polygon's size. The centre returned is strictly inside (its distance is r > 0).
 * Cost: little more at tol = 1e-6 than at 1e-4 of the size (docs/design/geometry.md). */
gp_status gp_max_inscribed_circle(const gp_vec2 *p, size_t n, double tol, gp_vec2 *center,
                                  double *radius, gp_error *err)
{
    return gp_max_inscribed_circle_from(p, n, tol, NULL, center, radius, err);
}

gp_status gp_max_inscribed_circle_from(const gp_vec2 *p, size_t n, double tol,
                                       const gp_vec2 *guess, gp_vec2 *center, double *radius,
                                       gp_error *err)
{
    if (!p || n < 3 || !center || !radius)
        return gp_error_set(err, GP_ERR_INVALID, "max_inscribed_circle: need n >= 3 vertices");
    if (!all_finite(p, n) || isnan(tol))
        return gp_error_set(err, GP_ERR_INVALID, "max_inscribed_circle: non-finite input");
    if (all_collinear(p, n))
        return gp_error_set(err, GP_ERR_DEGENERATE, "max_inscribed_circle: polygon has no area");

    const gp_vec2 o = p[0];
    const size_t n2 = 2 * n;
    double *buf = malloc((5 * n2 + 2) * sizeof *buf);
    if (!buf) return gp_error_set(err, GP_ERR_NOMEM, "max_inscribed_circle: out of memory");
    double *X = buf, *Y = X + n2 + 1, *DX = Y + n2 + 1, *DY = DX + n2, *IL = DY + n2;
    for (size_t i = 0; i < n; i++) {
        X[i] = X[i + n] = p[i].x - o.x;
        Y[i] = Y[i + n] = p[i].y - o.y;
    }
    X[n2] = Y[n2] = 0.0; /* vertex 0 is the origin: X[0] = Y[0] = 0 exactly */
    double x0 = 0.0, x1 = 0.0, y0 = 0.0, y1 = 0.0;
    for (size_t i = 0; i < n; i++) {
        DX[i] = DX[i + n] = X[i + 1] - X[i];
        DY[i] = DY[i + n] = Y[i + 1] - Y[i];
        double l2 = DX[i] * DX[i] + DY[i] * DY[i];
        IL[i] = IL[i + n] = l2 > 0.0 ? 1.0 / l2 : 0.0;
        x0 = dmin(x0, X[i]);
        x1 = dmax(x1, X[i]);
        y0 = dmin(y0, Y[i]);
        y1 = dmax(y1, Y[i]);
    }
    mic_poly P = {n, X, Y, DX, DY, IL};
    double w = x1 - x0, hgt = y1 - y0, size = fmax(w, hgt);
    if (tol <= 0.0) tol = 1e-6 * size;
    if (tol < 1e-13 * size) tol = 1e-13 * size;

    /* initial grid: square cells of side min(w, h), but at most ~64 along the long side */
    double cell = fmax(fmin(w, hgt), size / 64.0);
    size_t nx = (size_t)ceil(w / cell), ny = (size_t)ceil(hgt / cell);
    if (nx < 1) nx = 1;
    if (ny < 1) ny = 1;
    double hh = 0.5 * cell;

    /* first guesses: the bounding-box centre and the area centroid */
    mic_cell best, c;
    best.d = -INFINITY;
    best.x = best.y = 0.0;
    best.e1 = 0;
    mic_make(&P, NULL, 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.0, 0, tol, &best, &c);
    gp_vec2 cen;
    if (gp_poly_centroid(p, n, &cen, NULL) == GP_OK)
        mic_make(&P, NULL, cen.x - o.x, cen.y - o.y, 0.0, best.e1, tol, &best, &c);
    if (guess && finite2(*guess)) /* a good one prunes most of the grid below at once */
        mic_make(&P, NULL, guess->x - o.x, guess->y - o.y, 0.0, best.e1, tol, &best, &c);

    gp_status st = GP_OK;
    mic_heap H = {NULL, 0, 0};
    mic_arena A = {NULL, 0, 0};
    for (size_t ix = 0; ix < nx && st == GP_OK; ix++)
        for (size_t iy = 0; iy < ny && st == GP_OK; iy++)
            if (mic_make(&P, NULL, x0 + ((double)ix + 0.5) * cell,
                         y0 + ((double)iy + 0.5) * cell, hh, best.e1, tol, &best, &c) &&
                heap_push(&H, c))
                st = GP_ERR_NOMEM;
    size_t evals = 0;
    const size_t max_evals = 4000000;
    while (st == GP_OK && H.n > 0) {
        mic_cell pc = heap_pop(&H);
        if (pc.max - best.d <= tol) break; /* max-heap: no remaining cell can do better */
        /* the edges that can be nearest to a point of the cell: within |d| + 2 h sqrt 2 of
         * its centre (a point x of it has d(x) <= |d| + h sqrt 2, and an edge farther than
         * that from the centre is farther than d(x) from x); the children look at only those */
        size_t have = pc.clen ? pc.clen : n, off = A.n;
        if (mic_arena_grow(&A, have) != 0) {
            st = GP_ERR_NOMEM;
            break;
        }
        double lim = fabs(pc.d) + 2.0 * pc.h * MIC_SQRT2;
        for (size_t q = 0; q < have; q++) {
            size_t e = pc.clen ? A.a[pc.coff + q] : q;
            if (mic_edist(&P, e, pc.x, pc.y) <= lim) A.a[A.n++] = e;
        }
        mic_src src = {A.a + off, A.n - off, pc.x, pc.y, pc.d};
        double h2 = 0.5 * pc.h;
        for (int k = 0; k < 4 && st == GP_OK; k++) {
            if (!mic_make(&P, &src, pc.x + ((k & 1) ? h2 : -h2), pc.y + ((k & 2) ? h2 : -h2), h2,
                          pc.e1, tol, &best, &c))
                continue;
            c.coff = off;
            c.clen = A.n - off; /* >= 1: the nearest edge, at |d| <= lim, is listed */
            if (heap_push(&H, c)) st = GP_ERR_NOMEM;
        }
        if ((evals += 4) > max_evals) st = GP_ERR_NOT_CONVERGED;
    }
    free(H.a);
    free(A.a);
    free(buf);
    center->x = o.x + best.x;
    center->y = o.y + best.y;
    *radius = best.d;
    if (st == GP_ERR_NOMEM) return gp_error_set(err, st, "max_inscribed_circle: out of memory");
    if (st == GP_ERR_NOT_CONVERGED)
        return gp_error_set(err, st, "max_inscribed_circle: cell budget exhausted before tol %g", tol);
    if (!(best.d > 0.0))
        return gp_error_set(err, GP_ERR_DEGENERATE, "max_inscribed_circle: no interior point found");
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* minimum caliper width                                                                       */

double gp_axis_angle(double ex, double ey)
{
    double ang = atan2(ey, ex);
    if (ang <= -GP_PI / 2) ang += GP_PI;
    else if (ang > GP_PI / 2) ang -= GP_PI;
    if (ang <= -GP_PI / 2) ang = GP_PI / 2; /* guard rounding at the boundary */
    return ang;
}

/* Rotating calipers: for edge k, the antipodal vertex j maximises h = cross(e_k, h[j] - h[k]);
 * as k turns counter-clockwise so does j, so one walk serves every edge (O(m)). */
/* The lowest (then leftmost) vertex of h: where gp_min_caliper_edge starts, which fixes which
 * of two equally thin edges wins. */
static size_t caliper_start(const gp_vec2 *h, size_t m)
{
    size_t s = 0;
    double sy = h[0].y, sx = h[0].x;
    for (size_t k = 1; k < m; k++)
        if (h[k].y < sy || (h[k].y == sy && h[k].x < sx)) {
            s = k;
            sy = h[k].y;
            sx = h[k].x;
        }
    return s;
}

size_t gp_min_caliper_edge(const gp_vec2 *h, size_t m, double eps2, int squared)
{
    if (!h || m < 2) return m;
    size_t best_k = m, j = m; /* j == m: not placed yet (the first edge kept places it) */
    double best = INFINITY;
    size_t k = caliper_start(h, m);
    /* the arithmetic of each width is fixed (the results are pinned to it): only the
     * bookkeeping around it is lean -- the edge's start held in registers, indices stepped */
    for (size_t c = 0; c < m; c++) {
        size_t k1 = k + 1 == m ? 0 : k + 1;
        const double kx = h[k].x, ky = h[k].y;
        double ex = h[k1].x - kx, ey = h[k1].y - ky;
        double l2 = ex * ex + ey * ey;
        if (l2 > eps2) {
            if (j == m) j = k1;
            double cur = ex * (h[j].y - ky) - ey * (h[j].x - kx);
            for (size_t step = 0; step < m; step++) {
                size_t j1 = j + 1 == m ? 0 : j + 1;
                double nxt = ex * (h[j1].y - ky) - ey * (h[j1].x - kx);
                if (nxt < cur) break;
                cur = nxt;
                j = j1;
            }
            double w = squared ? cur * cur / l2 : cur / hypot(ex, ey);
            if (w < best) {
                best = w;
                best_k = k;
            }
        }
        k = k1;
    }
    return best_k;
}

/* The minimum caliper of a convex hull h[0 .. m - 1] (m >= 3; shifted in place to h[0]) */
static void caliper_of_hull(gp_vec2 *h, size_t m, double *width, double *angle_rad,
                            double *length)
{
    const gp_vec2 o = h[0];
    for (size_t i = 0; i < m; i++) {
        h[i].x -= o.x;
        h[i].y -= o.y;
    }
    size_t best_i = gp_min_caliper_edge(h, m, -1.0, 0);
    if (best_i == m) best_i = 0; /* only for NaN widths: keep the first edge */
    /* re-measure the chosen edge in full, independently of the caliper bookkeeping */
    size_t i1 = best_i + 1 == m ? 0 : best_i + 1;
    double ex = h[i1].x - h[best_i].x, ey = h[i1].y - h[best_i].y;
    double len = hypot(ex, ey), ux = ex / len, uy = ey / len;
    double wmax = 0.0, lmin = INFINITY, lmax = -INFINITY;
    for (size_t k = 0; k < m; k++) {
        double rx = h[k].x - h[best_i].x, ry = h[k].y - h[best_i].y;
        double cr = ux * ry - uy * rx, dt = ux * rx + uy * ry;
        if (cr > wmax) wmax = cr;
        if (dt < lmin) lmin = dt;
        if (dt > lmax) lmax = dt;
    }
    double ang = gp_axis_angle(ex, ey);
    if (width) *width = wmax;
    if (angle_rad) *angle_rad = ang;
    if (length) *length = lmax - lmin;
}

static gp_status min_caliper(const gp_vec2 *p, size_t n, int star, double *width,
                             double *angle_rad, double *length, gp_error *err)
{
    if (!p || n == 0) return gp_error_set(err, GP_ERR_INVALID, "min_caliper: need n >= 1 points");
    if (!all_finite(p, n)) return gp_error_set(err, GP_ERR_INVALID, "min_caliper: non-finite vertex");
    gp_vec2 *h = malloc(n * sizeof *h);
    if (!h) return gp_error_set(err, GP_ERR_NOMEM, "min_caliper: out of memory");
    size_t m = star ? gp_convex_hull_star(p, n, h) : gp_convex_hull(p, n, h);
    if (m < 3) {
        free(h);
        return gp_error_set(err, GP_ERR_DEGENERATE, "min_caliper: points are collinear");
    }
    caliper_of_hull(h, m, width, angle_rad, length);
    free(h);
    return GP_OK;
}

gp_status gp_min_caliper(const gp_vec2 *p, size_t n, double *width, double *angle_rad,
                         double *length, gp_error *err)
{
    return min_caliper(p, n, 0, width, angle_rad, length, err);
}

gp_status gp_min_caliper_star(const gp_vec2 *p, size_t n, double *width, double *angle_rad,
                              double *length, gp_error *err)
{
    return min_caliper(p, n, 1, width, angle_rad, length, err);
}

/* ------------------------------------------------------------------------------------------ */
/* simplicity, containment, overlap (exact predicates)                                        */

/* index of the next edge after i (cyclically) that has non-zero length */
static size_t next_edge(const gp_vec2 *p, size_t n, size_t i)
{
    for (size_t k = 1; k <= n; k++) {
        size_t e = (i + k) % n;
        if (!veq(p[e], p[(e + 1) % n])) return e;
    }
    return i;
}

static size_t prev_edge(const gp_vec2 *p, size_t n, size_t i)
{
    for (size_t k = 1; k <= n; k++) {
        size_t e = (i + n - k) % n;
        if (!veq(p[e], p[(e + 1) % n])) return e;
    }
    return i;
}

int gp_poly_is_simple(const gp_vec2 *p, size_t n)
{
    if (!p || n < 3 || !all_finite(p, n)) return 0;
    size_t ne = 0;
    for (size_t i = 0; i < n; i++)
        if (!veq(p[i], p[(i + 1) % n])) ne++;
    if (ne < 3) return 0;
    for (size_t i = 0; i < n; i++) {
        gp_vec2 a = p[i], b = p[(i + 1) % n];
        if (veq(a, b)) continue;
        size_t ni = next_edge(p, n, i), pi = prev_edge(p, n, i);
        gp_vec2 c = p[(ni + 1) % n];
        /* the next edge folds back onto this one */
        if (orient(a, b, c) == 0 && (b.x - a.x) * (c.x - b.x) + (b.y - a.y) * (c.y - b.y) < 0.0)
            return 0;
        for (size_t j = i + 1; j < n; j++) {
            gp_vec2 d0 = p[j], d1 = p[j + 1 == n ? 0 : j + 1];
            if (veq(d0, d1) || j == ni || j == pi) continue;
            if (seg_intersect(a, b, d0, d1)) return 0;
        }
    }
    return 1;
}

enum { BF_CROSS = 1, BF_IN = 2, BF_OUT = 4 };

static inline double seg_param(gp_vec2 u, gp_vec2 v, gp_vec2 q)
{
    double dx = v.x - u.x, dy = v.y - u.y;
    double t = ((q.x - u.x) * dx + (q.y - u.y) * dy) / (dx * dx + dy * dy);
    return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
}

/* Segment u->v (non-degenerate) against the boundary of b. Returns 1 on a proper crossing.
 * Otherwise sets *touch if the boundary meets the closed segment anywhere, and *tnext to the
 * smallest contact parameter (in (t0, 1)) of a contact point or of an end of a collinear
 * overlap, or 1 if none. If covered is non-NULL, sets it when a collinear edge of b covers the
 * parameter tm. */
static int seg_events(gp_vec2 u, gp_vec2 v, const gp_vec2 *b, size_t nb, double t0, double tm,
                      int *touch, double *tnext, int *covered)
{
    double xlo = dmin(u.x, v.x), xhi = dmax(u.x, v.x), ylo = dmin(u.y, v.y), yhi = dmax(u.y, v.y);
    double tn = 1.0;
    for (size_t i = 0, j = nb - 1; i < nb; j = i++) {
        gp_vec2 c = b[j], d = b[i];
        if (veq(c, d)) continue;
        if (dmax(c.x, d.x) < xlo || dmin(c.x, d.x) > xhi || dmax(c.y, d.y) < ylo ||
            dmin(c.y, d.y) > yhi)
            continue;
        int o1 = orient(u, v, c), o2 = orient(u, v, d);
        if (o1 * o2 > 0) continue;
        int o3 = orient(c, d, u), o4 = orient(c, d, v);
        if (o3 * o4 > 0) continue;
        if (o1 && o2 && o3 && o4) return 1;
        *touch = 1;
        double ev[4];
        int ne = 0;
        if (o1 == 0 && o2 == 0) {
            double tc = seg_param(u, v, c), td = seg_param(u, v, d);
            double lo = dmin(tc, td), hi = dmax(tc, td);
            ev[ne++] = lo;
            ev[ne++] = hi;
            if (covered && lo <= tm && tm <= hi && lo < hi) *covered = 1;
        } else {
            if (o1 == 0) ev[ne++] = seg_param(u, v, c);
            if (o2 == 0) ev[ne++] = seg_param(u, v, d);
        }
        for (int k = 0; k < ne; k++)
            if (ev[k] > t0 && ev[k] < tn) tn = ev[k];
    }
    *tnext = tn;
    return 0;
}

/* Where the boundary of a lies relative to b: BF_CROSS (proper crossing), BF_IN (some point of
 * it strictly inside b), BF_OUT (some point strictly outside b). Stops as soon as a flag in
 * stop is set. */
static int boundary_flags(const gp_vec2 *a, size_t na, const gp_vec2 *b, size_t nb, int stop)
{
    int f = 0;
    for (size_t i = 0; i < na; i++) {
        int c = point_class(b, nb, a[i], -1.0);
        f |= c > 0 ? BF_IN : (c < 0 ? BF_OUT : 0);
        if (f & stop) return f;
    }
    for (size_t i = 0; i < na; i++) {
        gp_vec2 u = a[i], v = a[(i + 1) % na];
        if (veq(u, v)) continue;
        int touch = 0, cov = 0;
        double tn;
        if (seg_events(u, v, b, nb, 0.0, -1.0, &touch, &tn, NULL)) return f | BF_CROSS;
        if (!touch) continue; /* no contact: the edge is on the side of its end points */
        double t0 = 0.0;
        for (;;) {
            double tm = 0.5 * (t0 + tn);
            cov = 0;
            double dummy;
            int tch = 0;
            seg_events(u, v, b, nb, t0, tm, &tch, &dummy, &cov);
            if (!cov) {
                gp_vec2 q = {u.x + tm * (v.x - u.x), u.y + tm * (v.y - u.y)};
                int c = point_class(b, nb, q, -1.0);
                f |= c > 0 ? BF_IN : (c < 0 ? BF_OUT : 0);
                if (f & stop) return f;
            }
            if (tn >= 1.0) break;
            t0 = tn;
            seg_events(u, v, b, nb, t0, -1.0, &tch, &tn, NULL);
        }
    }
    return f;
}

int gp_poly_inside_poly(const gp_vec2 *a, size_t na, const gp_vec2 *b, size_t nb)
{
    if (!a || !b || na == 0 || nb < 3 || !all_finite(a, na) || !all_finite(b, nb)) return 0;
    double ax0, ay0, ax1, ay1, bx0, by0, bx1, by1;
    bbox_of(a, na, &ax0, &ay0, &ax1, &ay1);
    bbox_of(b, nb, &bx0, &by0, &bx1, &by1);
    if (ax0 < bx0 || ay0 < by0 || ax1 > bx1 || ay1 > by1) return 0;
    int f = boundary_flags(a, na, b, nb, BF_CROSS | BF_OUT);
    return (f & (BF_CROSS | BF_OUT)) ? 0 : 1;
}

int gp_poly_overlap(const gp_vec2 *a, size_t na, const gp_vec2 *b, size_t nb)
{
    if (!a || !b || na < 3 || nb < 3 || !all_finite(a, na) || !all_finite(b, nb)) return 0;
    double ax0, ay0, ax1, ay1, bx0, by0, bx1, by1;
    bbox_of(a, na, &ax0, &ay0, &ax1, &ay1);
    bbox_of(b, nb, &bx0, &by0, &bx1, &by1);
    if (ax1 <= bx0 || bx1 <= ax0 || ay1 <= by0 || by1 <= ay0) return 0;
    if (all_collinear(a, na) || all_collinear(b, nb)) return 0; /* no interior */
    int fa = boundary_flags(a, na, b, nb, BF_CROSS | BF_IN);
    if (fa & (BF_CROSS | BF_IN)) return 1;
    int fb = boundary_flags(b, nb, a, na, BF_IN);
    if (fb & BF_IN) return 1;
    /* the boundary of a lies on the boundary of b: the same region */
    return (fa & BF_OUT) ? 0 : 1;
}
