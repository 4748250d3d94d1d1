/* test_geom.c -- gp_geom against independent truth: closed forms, hand computations and brute
 * force (all-pairs/triples enclosing circles, dense grid searches, angle sweeps). */
#include "gp_geom.h"
#include "gp_test.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PI 3.14159265358979323846

/* deterministic test-local generator (xorshift64*) */
static uint64_t rs = 0x9E3779B97F4A7C15ull;
static double urand(void)
{
    rs ^= rs >> 12;
    rs ^= rs << 25;
    rs ^= rs >> 27;
    return (double)((rs * 0x2545F4914F6CDD1Dull) >> 11) * 0x1.0p-53;
}

static void regular_ngon(gp_vec2 *p, size_t n, double cx, double cy, double R, double phase)
{
    for (size_t i = 0; i < n; i++) {
        double t = phase + 2.0 * PI * (double)i / (double)n;
        p[i] = (gp_vec2){cx + R * cos(t), cy + R * sin(t)};
    }
}

static void transform(const gp_vec2 *in, gp_vec2 *out, size_t n, double s, double ox, double oy)
{
    for (size_t i = 0; i < n; i++) out[i] = (gp_vec2){ox + s * in[i].x, oy + s * in[i].y};
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* one unit in the last place of |x| */
static double ulp(double x) { return nextafter(fabs(x), INFINITY) - fabs(x); }

static int naive_contains(const gp_vec2 *p, size_t n, gp_vec2 q);

static const gp_vec2 SQ[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
/* L-shape: [0,2]x[0,1] u [0,1]x[1,2]; area 3, centroid (5/6, 5/6) */
static const gp_vec2 LSH[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};

static void test_area_perimeter_centroid(void)
{
    gp_vec2 c;
    CHECK_NEAR(gp_poly_signed_area(SQ, 4), 1.0, 1e-15);
    CHECK_NEAR(gp_poly_perimeter(SQ, 4), 4.0, 1e-15);
    CHECK(gp_poly_centroid(SQ, 4, &c, NULL) == GP_OK);
    CHECK_NEAR(c.x, 0.5, 1e-15);
    CHECK_NEAR(c.y, 0.5, 1e-15);

    /* scaled and offset copies: relative accuracy 1e-12 */
    const double scales[] = {1e-6, 1.0, 1e6, 1e-3, 1.0};
    const double offs[] = {0.0, 1e6, 0.0, 1e6, -3e7};
    for (int k = 0; k < 5; k++) {
        gp_vec2 q[4];
        transform(SQ, q, 4, scales[k], offs[k], -offs[k]);
        /* exact side lengths of the stored doubles (Sterbenz: the differences are exact) */
        double sx = q[1].x - q[0].x, sy = q[2].y - q[1].y;
        CHECK_REL(gp_poly_signed_area(q, 4), sx * sy, 1e-12);
        CHECK_REL(gp_poly_perimeter(q, 4), 2.0 * (sx + sy), 1e-12);
        CHECK(gp_poly_centroid(q, 4, &c, NULL) == GP_OK);
        /* the centroid itself is a rounded coordinate: allow one ulp of it */
        CHECK_NEAR(c.x, q[0].x + 0.5 * sx, 1e-12 * sx + ulp(c.x));
        CHECK_NEAR(c.y, q[0].y + 0.5 * sy, 1e-12 * sy + ulp(c.y));
    }

    /* orientation: clockwise gives a negative signed area, same centroid */
    gp_vec2 cw[4] = {SQ[0], SQ[3], SQ[2], SQ[1]};
    CHECK_NEAR(gp_poly_signed_area(cw, 4), -1.0, 1e-15);
    CHECK_NEAR(gp_poly_area(cw, 4), 1.0, 1e-15);
    CHECK(gp_poly_centroid(cw, 4, &c, NULL) == GP_OK);
    CHECK_NEAR(c.x, 0.5, 1e-15);
    CHECK_NEAR(c.y, 0.5, 1e-15);

    /* duplicate and collinear vertices change nothing */
    gp_vec2 dup[9] = {{0, 0}, {0, 0}, {0.5, 0}, {1, 0}, {1, 0.25}, {1, 1}, {1, 1}, {0, 1}, {0, 0}};
    CHECK_NEAR(gp_poly_area(dup, 9), 1.0, 1e-15);
    CHECK_NEAR(gp_poly_perimeter(dup, 9), 4.0, 1e-15);
    CHECK(gp_poly_centroid(dup, 9, &c, NULL) == GP_OK);
    CHECK_NEAR(c.x, 0.5, 1e-15);
    CHECK_NEAR(c.y, 0.5, 1e-15);

    /* L-shape, by hand: (2*(1,0.5) + 1*(0.5,1.5)) / 3 */
    CHECK_NEAR(gp_poly_area(LSH, 6), 3.0, 1e-15);
    CHECK_NEAR(gp_poly_perimeter(LSH, 6), 8.0, 1e-15);
    CHECK(gp_poly_centroid(LSH, 6, &c, NULL) == GP_OK);
    CHECK_NEAR(c.x, 5.0 / 6.0, 1e-15);
    CHECK_NEAR(c.y, 5.0 / 6.0, 1e-15);
    gp_vec2 lbig[6];
    transform(LSH, lbig, 6, 0x1p-20, 1e6, 1e6); /* exactly representable */
    CHECK(gp_poly_centroid(lbig, 6, &c, NULL) == GP_OK);
    CHECK_NEAR(c.x, 1e6 + (5.0 / 6.0) * 0x1p-20, 1e-12 * 0x1p-20 + ulp(1e6));
    CHECK_REL(gp_poly_area(lbig, 6), 3.0 * 0x1p-40, 1e-12);

    /* degenerate: zero area -> vertex mean */
    gp_vec2 line[3] = {{0, 0}, {1, 1}, {2, 2}};
    gp_error e;
    CHECK(gp_poly_centroid(line, 3, &c, &e) == GP_ERR_DEGENERATE && e.code == GP_ERR_DEGENERATE);
    CHECK_NEAR(c.x, 1.0, 1e-15);
    CHECK_NEAR(c.y, 1.0, 1e-15);
    CHECK(gp_poly_area(line, 2) == 0.0);
}

static void test_orient(void)
{
    /* points (x, x) lie exactly on y = x, however inexact a naive determinant would be */
    int wrong = 0;
    for (int k = 0; k < 2000; k++) {
        double x1 = urand() * 100, x2 = urand() * 100 + 200, x3 = 0.1 + urand();
        gp_vec2 a = {x1, x1}, b = {x2, x2}, c = {x3, x3};
        if (gp_orient2d(a, b, c) != 0) wrong++;
        gp_vec2 up = {x3, nextafter(x3, INFINITY)}, dn = {x3, nextafter(x3, -INFINITY)};
        if (gp_orient2d(a, b, up) != 1 || gp_orient2d(a, b, dn) != -1) wrong++;
        if (gp_orient2d(b, a, up) != -1) wrong++;
    }
    CHECK(wrong == 0);
    /* Shewchuk's classic near-degenerate grid around (0.5, 0.5) against long double-free truth:
     * c = (0.5 + i*ulp, 0.5 + j*ulp), a = (12, 12), b = (24, 24): sign is sign(j - i) */
    double u = 0x1p-53;
    wrong = 0;
    for (int i = 0; i < 32; i++)
        for (int j = 0; j < 32; j++) {
            gp_vec2 cc = {0.5 + i * u, 0.5 + j * u};
            int want = (j > i) - (j < i);
            if (gp_orient2d((gp_vec2){12, 12}, (gp_vec2){24, 24}, cc) != want) wrong++;
        }
    CHECK(wrong == 0);
    CHECK(gp_segments_intersect((gp_vec2){0, 0}, (gp_vec2){2, 2}, (gp_vec2){0, 2}, (gp_vec2){2, 0}));
    CHECK(gp_segments_intersect((gp_vec2){0, 0}, (gp_vec2){1, 1}, (gp_vec2){1, 1}, (gp_vec2){2, 0}));
    CHECK(!gp_segments_intersect((gp_vec2){0, 0}, (gp_vec2){1, 0}, (gp_vec2){2, 0}, (gp_vec2){3, 0}));
    CHECK(gp_segments_intersect((gp_vec2){0, 0}, (gp_vec2){2, 0}, (gp_vec2){1, 0}, (gp_vec2){3, 0}));
}

static int is_input_point(const gp_vec2 *p, size_t n, gp_vec2 q)
{
    for (size_t i = 0; i < n; i++)
        if (p[i].x == q.x && p[i].y == q.y) return 1;
    return 0;
}

static void test_hull(void)
{
    gp_vec2 h[64];
    CHECK(gp_convex_hull(SQ, 0, h) == 0);
    CHECK(gp_convex_hull(SQ, 1, h) == 1);
    gp_vec2 two[3] = {{1, 1}, {1, 1}, {1, 1}};
    CHECK(gp_convex_hull(two, 3, h) == 1);
    gp_vec2 col[5] = {{0, 3}, {1, 2}, {2, 1}, {3, 0}, {1.5, 1.5}};
    size_t m = gp_convex_hull(col, 5, h);
    CHECK(m == 2);
    CHECK(h[0].x == 3 && h[0].y == 0 && h[1].x == 0 && h[1].y == 3);

    /* square with collinear, duplicate and interior points, clockwise */
    gp_vec2 sq[10] = {{0, 1}, {1, 1}, {1, 1}, {1, 0.5}, {1, 0}, {0.5, 0}, {0, 0},
                      {0.5, 0.5}, {0, 0.5}, {0, 1}};
    m = gp_convex_hull(sq, 10, h);
    CHECK(m == 4);
    CHECK(h[0].x == 0 && h[0].y == 0);
    CHECK(h[1].x == 1 && h[1].y == 0);
    CHECK(h[2].x == 1 && h[2].y == 1);
    CHECK(h[3].x == 0 && h[3].y == 1);

    /* lowest-then-leftmost start when two points share the lowest y */
    gp_vec2 tri[3] = {{2, 0}, {1, 1}, {-1, 0}};
    m = gp_convex_hull(tri, 3, h);
    CHECK(m == 3 && h[0].x == -1 && h[0].y == 0 && h[1].x == 2);

    /* random clouds (some at huge offset): contains all, strictly convex, CCW, from input */
    int bad = 0;
    for (int trial = 0; trial < 200; trial++) {
        gp_vec2 p[64];
        size_t n = 3 + (size_t)(urand() * 61);
        double off = (trial % 3 == 0) ? 1e6 : 0.0, sc = (trial % 4 == 0) ? 1e-6 : 1.0;
        for (size_t i = 0; i < n; i++) {
            p[i] = (gp_vec2){off + sc * urand(), off + sc * urand()};
            if (trial % 5 == 0) p[i].x = off + sc * floor(urand() * 4); /* many collinear */
        }
        m = gp_convex_hull(p, n, h);
        if (m < 3 || m > n) {
            bad++;
            continue;
        }
        for (size_t i = 0; i < m; i++) {
            gp_vec2 a = h[i], b = h[(i + 1) % m], c = h[(i + 2) % m];
            if (gp_orient2d(a, b, c) <= 0) bad++;
            if (!is_input_point(p, n, a)) bad++;
            if (h[i].y < h[0].y || (h[i].y == h[0].y && h[i].x < h[0].x)) bad++;
            for (size_t k = 0; k < n; k++)
                if (gp_orient2d(a, b, p[k]) < 0) bad++;
        }
    }
    CHECK(bad == 0);
    /* NaN points are ignored */
    gp_vec2 withnan[5] = {{0, 0}, {NAN, 1}, {1, 0}, {0, 1}, {1, INFINITY}};
    CHECK(gp_convex_hull(withnan, 5, h) == 3);
}

/* gp_convex_hull_star against gp_convex_hull (the monotone chain with a sort, an independent
 * algorithm), and gp_min_caliper_star against gp_min_caliper: the same vertices in the same order on random star-shaped polygons (sorted
 * angles, random radii; some with radii on a coarse grid or points on the edges of a square,
 * so collinear runs occur; both orientations; some far from the origin), and the fallback. */
static int hull_star_same(const gp_vec2 *p, size_t n, int reverse)
{
    gp_vec2 q[200], h1[200], h2[200];
    for (size_t i = 0; i < n; i++) q[i] = reverse ? p[n - 1 - i] : p[i];
    size_t m1 = gp_convex_hull(q, n, h1), m2 = gp_convex_hull_star(q, n, h2);
    /* and gp_min_caliper_star, on that hull, the bits of gp_min_caliper (checked below against
     * an angle sweep) */
    double c1[3], c2[3];
    int cal = gp_min_caliper(q, n, c1, c1 + 1, c1 + 2, NULL) == GP_OK &&
              gp_min_caliper_star(q, n, c2, c2 + 1, c2 + 2, NULL) == GP_OK &&
              memcmp(c1, c2, sizeof c1) == 0;
    return m1 >= 3 && m1 == m2 && memcmp(h1, h2, m1 * sizeof *h1) == 0 && cal;
}

static void test_hull_star(void)
{
    uint64_t keep = rs; /* its own draws: the later tests see the stream they always saw */
    int bad = 0, trials = 0;
    gp_vec2 p[200];
    for (int trial = 0; trial < 600; trial++) {
        size_t n = 3 + (size_t)(urand() * 190);
        double off = trial % 3 == 0 ? 1e6 : 0.0, th[200];
        for (size_t i = 0; i < n; i++) th[i] = 2.0 * PI * ((double)i + 0.9 * urand()) / (double)n;
        for (size_t i = 0; i < n; i++) {
            double r = trial % 4 == 1 ? 1.0 + floor(urand() * 3) : 0.2 + urand();
            if (trial % 4 == 2) { /* on the square's edges: many collinear */
                double c = cos(th[i]), sn = sin(th[i]), k = fmax(fabs(c), fabs(sn));
                r = 1.0 / k;
            }
            p[i] = (gp_vec2){off + r * cos(th[i]), off + r * sin(th[i])};
        }
        bad += !hull_star_same(p, n, trial & 1);
        trials++;
    }
    CHECK(trials == 600 && bad == 0);
    gp_vec2 nan[5] = {{0, 0}, {2, 0}, {NAN, 1}, {2, 2}, {0, 2}}, h[5];
    CHECK(gp_convex_hull_star(nan, 5, h) == 4 && h[0].x == 0 && h[0].y == 0 && h[2].x == 2);
    rs = keep;
}

/* brute-force smallest enclosing circle: the smallest among all pair/triple circles that
 * contain every point */
static double brute_mec(const gp_vec2 *p, size_t n)
{
    double best = INFINITY;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            for (size_t k = j; k < n; k++) {
                double cx, cy, r;
                if (k == j) {
                    cx = 0.5 * (p[i].x + p[j].x);
                    cy = 0.5 * (p[i].y + p[j].y);
                    r = 0.5 * hypot(p[i].x - p[j].x, p[i].y - p[j].y);
                } else {
                    double ax = p[i].x, ay = p[i].y;
                    double bx = p[j].x - ax, by = p[j].y - ay, qx = p[k].x - ax, qy = p[k].y - ay;
                    double d = 2 * (bx * qy - by * qx);
                    if (fabs(d) < 1e-12) continue;
                    double B = bx * bx + by * by, C = qx * qx + qy * qy;
                    double ux = (qy * B - by * C) / d, uy = (bx * C - qx * B) / d;
                    cx = ax + ux;
                    cy = ay + uy;
                    r = hypot(ux, uy);
                }
                if (r >= best) continue;
                int ok = 1;
                for (size_t m = 0; m < n && ok; m++)
                    if (hypot(p[m].x - cx, p[m].y - cy) > r * (1 + 1e-9)) ok = 0;
                if (ok) best = r;
            }
        }
    return best;
}

static void test_mec(void)
{
    gp_vec2 c;
    double r;
    gp_vec2 one = {3, 4};
    CHECK(gp_min_enclosing_circle(&one, 1, &c, &r, NULL) == GP_OK);
    CHECK(c.x == 3 && c.y == 4 && r == 0);
    gp_vec2 two[2] = {{0, 0}, {2, 0}};
    CHECK(gp_min_enclosing_circle(two, 2, &c, &r, NULL) == GP_OK);
    CHECK_NEAR(r, 1.0, 1e-15);
    CHECK_NEAR(c.x, 1.0, 1e-15);
    /* right triangle: half the hypotenuse, centred on it */
    gp_vec2 rt[3] = {{0, 0}, {3, 0}, {0, 4}};
    CHECK(gp_min_enclosing_circle(rt, 3, &c, &r, NULL) == GP_OK);
    CHECK_NEAR(r, 2.5, 1e-14);
    CHECK_NEAR(c.x, 1.5, 1e-14);
    CHECK_NEAR(c.y, 2.0, 1e-14);
    /* equilateral: circumradius a / sqrt(3); obtuse: half the longest side */
    gp_vec2 eq[3] = {{0, 0}, {1, 0}, {0.5, sqrt(3.0) / 2}};
    CHECK(gp_min_enclosing_circle(eq, 3, &c, &r, NULL) == GP_OK);
    CHECK_REL(r, 1.0 / sqrt(3.0), 1e-14);
    gp_vec2 obt[3] = {{0, 0}, {4, 0}, {1, 0.5}};
    CHECK(gp_min_enclosing_circle(obt, 3, &c, &r, NULL) == GP_OK);
    CHECK_REL(r, 2.0, 1e-14);
    /* collinear set: the extreme pair */
    gp_vec2 col[6] = {{1, 1}, {4, 5}, {2.5, 3}, {-2, -3}, {0, -1 / 3.0}, {1, 1}};
    CHECK(gp_min_enclosing_circle(col, 6, &c, &r, NULL) == GP_OK);
    CHECK_REL(r, 0.5 * hypot(6.0, 8.0), 1e-14);
    CHECK_NEAR(c.x, 1.0, 1e-14);
    CHECK_NEAR(c.y, 1.0, 1e-14);

    /* regular n-gons, also tiny / huge / offset */
    for (size_t n = 3; n <= 1024; n = n * 2 + 1) {
        gp_vec2 *p = malloc(n * sizeof *p);
        regular_ngon(p, n, 1e6, -1e6, 0.01, 0.3);
        CHECK(gp_min_enclosing_circle(p, n, &c, &r, NULL) == GP_OK);
        CHECK_REL(r, 0.01, 4 * ulp(1e6) / 0.01); /* the vertices are rounded at 1e6 */
        CHECK_NEAR(c.x, 1e6, 4 * ulp(1e6));
        regular_ngon(p, n, 0, 0, 1e-6, 0.1);
        CHECK(gp_min_enclosing_circle(p, n, &c, &r, NULL) == GP_OK);
        CHECK_REL(r, 1e-6, 1e-12);
        free(p);
    }

    /* random clouds against brute force; contains all and touches >= 2 points */
    int bad = 0;
    for (int trial = 0; trial < 60; trial++) {
        gp_vec2 p[25];
        size_t n = 2 + (size_t)(urand() * 23);
        for (size_t i = 0; i < n; i++) p[i] = (gp_vec2){urand() * 3, urand()};
        CHECK(gp_min_enclosing_circle(p, n, &c, &r, NULL) == GP_OK);
        double rb = brute_mec(p, n);
        if (fabs(r - rb) > 1e-9 * rb) bad++;
        int touching = 0;
        for (size_t i = 0; i < n; i++) {
            double d = hypot(p[i].x - c.x, p[i].y - c.y);
            if (d > r * (1 + 1e-11)) bad++;
            if (d >= r * (1 - 1e-11)) touching++;
        }
        if (touching < 2) bad++;
    }
    CHECK(bad == 0);
    /* a large cloud: contains all, tight */
    size_t n = 5000;
    gp_vec2 *p = malloc(n * sizeof *p);
    for (size_t i = 0; i < n; i++) {
        double t = urand() * 2 * PI, s = sqrt(urand());
        p[i] = (gp_vec2){1e6 + 2 * s * cos(t), 1e6 + s * sin(t)};
    }
    CHECK(gp_min_enclosing_circle(p, n, &c, &r, NULL) == GP_OK);
    int outside = 0, touching = 0;
    for (size_t i = 0; i < n; i++) {
        double d = hypot(p[i].x - c.x, p[i].y - c.y);
        if (d > r * (1 + 1e-11)) outside++;
        if (d >= r * (1 - 1e-11)) touching++;
    }
    CHECK(outside == 0 && touching >= 2);
    free(p);

    gp_error e;
    CHECK(gp_min_enclosing_circle(NULL, 0, &c, &r, &e) == GP_ERR_INVALID);
}

/* reference pole of inaccessibility: textbook polylabel with the d + h sqrt 2 bound. An
 * independent check of gp_max_inscribed_circle on purpose: its own bounding box, cells and
 * point-in-polygon test (naive_contains), nothing shared with the library's. */
static double ref_sdist(const gp_vec2 *p, size_t n, double x, double y)
{
    gp_vec2 q = {x, y};
    double d = gp_poly_boundary_distance(p, n, q);
    return naive_contains(p, n, q) ? d : -d;
}

static double ref_polylabel(const gp_vec2 *p, size_t n, double tol)
{
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        x0 = fmin(x0, p[i].x);
        x1 = fmax(x1, p[i].x);
        y0 = fmin(y0, p[i].y);
        y1 = fmax(y1, p[i].y);
    }
    size_t cap = 1 << 16, cnt = 0;
    double(*cell)[4] = malloc(cap * sizeof *cell); /* x, y, h, d */
    double h = 0.5 * fmax(x1 - x0, y1 - y0), best = -INFINITY;
    cell[cnt][0] = 0.5 * (x0 + x1);
    cell[cnt][1] = 0.5 * (y0 + y1);
    cell[cnt][2] = h;
    cell[cnt][3] = ref_sdist(p, n, cell[cnt][0], cell[cnt][1]);
    cnt++;
    while (cnt > 0) {
        /* pop the cell with the largest bound (linear scan: simple and obviously right) */
        size_t bi = 0;
        for (size_t i = 1; i < cnt; i++)
            if (cell[i][3] + cell[i][2] * sqrt(2.0) > cell[bi][3] + cell[bi][2] * sqrt(2.0)) bi = i;
        double cx = cell[bi][0], cy = cell[bi][1], ch = cell[bi][2], cd = cell[bi][3];
        cell[bi][0] = cell[cnt - 1][0];
        cell[bi][1] = cell[cnt - 1][1];
        cell[bi][2] = cell[cnt - 1][2];
        cell[bi][3] = cell[cnt - 1][3];
        cnt--;
        if (cd > best) best = cd;
        if (cd + ch * sqrt(2.0) - best <= tol) break;
        for (int k = 0; k < 4 && cnt < cap; k++) {
            double nx = cx + ((k & 1) ? 0.5 : -0.5) * ch, ny = cy + ((k & 2) ? 0.5 : -0.5) * ch;
            double nd = ref_sdist(p, n, nx, ny);
            if (nd > best) best = nd;
            if (nd + 0.5 * ch * sqrt(2.0) - best > tol) {
                cell[cnt][0] = nx;
                cell[cnt][1] = ny;
                cell[cnt][2] = 0.5 * ch;
                cell[cnt][3] = nd;
                cnt++;
            }
        }
    }
    free(cell);
    return best;
}

/* checks a max inscribed circle against the truth r_true with the documented guarantee */
static void check_mic(const gp_vec2 *p, size_t n, double tol, double r_true, double cx, double cy,
                      int check_center)
{
    gp_vec2 c;
    double r;
    gp_error e;
    CHECK(gp_max_inscribed_circle(p, n, tol, &c, &r, &e) == GP_OK);
    if (tol <= 0) tol = 1e-6 * r_true * 2; /* the default: 1e-6 of the size (here 2 r) */
    CHECK(r <= r_true * (1 + 1e-12) && r_true - r <= tol);
    CHECK(gp_poly_contains(p, n, c));
    /* the returned centre is rounded to its coordinates' ulp */
    double slack = 4 * ulp(fabs(c.x) + fabs(c.y));
    CHECK_NEAR(gp_poly_boundary_distance(p, n, c), r, 1e-12 * r_true + slack);
    if (check_center) {
        /* the optimum is unique and the distance falls off at least linearly here */
        CHECK(hypot(c.x - cx, c.y - cy) <= 4 * tol + 1e-6 * r_true + slack);
    }
}

static void test_mic(void)
{
    gp_vec2 q[4];
    /* square side a: a/2 at the centre */
    check_mic(SQ, 4, 1e-6, 0.5, 0.5, 0.5, 1);
    transform(SQ, q, 4, 0x1p-20, 1e6, 1e6);
    check_mic(q, 4, 1e-12, 0x1p-21, 1e6 + 0x1p-21, 1e6 + 0x1p-21, 1);
    transform(SQ, q, 4, 1e6, 0, 0);
    check_mic(q, 4, 0.0, 0.5e6, 0.5e6, 0.5e6, 1); /* default tol: 1e-6 of the size */
    /* equilateral triangle side a: a / (2 sqrt 3) at the centroid */
    gp_vec2 eq[3] = {{0, 0}, {2, 0}, {1, sqrt(3.0)}};
    check_mic(eq, 3, 1e-7, 1.0 / sqrt(3.0), 1.0, 1.0 / sqrt(3.0), 1);
    /* regular polygons: the apothem */
    for (size_t n = 5; n <= 1024; n *= 2) {
        gp_vec2 *p = malloc(n * sizeof *p);
        regular_ngon(p, n, 3, -2, 2.0, 0.2);
        check_mic(p, n, 1e-5, 2.0 * cos(PI / (double)n), 3, -2, 1);
        free(p);
    }
    /* L-shape: tangent to x = 0 and y = 0 and through the reflex corner (1,1): r = 2 - sqrt 2 */
    double rl = 2.0 - sqrt(2.0);
    check_mic(LSH, 6, 1e-6, rl, rl, rl, 1);
    gp_vec2 lcw[6];
    for (int i = 0; i < 6; i++) lcw[i] = LSH[5 - i];
    check_mic(lcw, 6, 1e-6, rl, rl, rl, 1);
    /* a thin rectangle 100 x 1 (many initial cells): 0.5 */
    gp_vec2 thin[4] = {{0, 0}, {100, 0}, {100, 1}, {0, 1}};
    check_mic(thin, 4, 1e-6, 0.5, 0, 0, 0);

    /* a non-convex star against a brute-force grid search of the distance */
    size_t n = 128;
    gp_vec2 st[128];
    for (size_t i = 0; i < n; i++) {
        double t = 2 * PI * (double)i / (double)n;
        double rr = 1.0 + 0.3 * cos(3 * t) + 0.1 * sin(7 * t);
        st[i] = (gp_vec2){rr * cos(t), rr * sin(t)};
    }
    gp_vec2 c;
    double r;
    CHECK(gp_max_inscribed_circle(st, n, 1e-6, &c, &r, NULL) == GP_OK);
    double rg = 0;
    for (int i = 0; i <= 400; i++)
        for (int j = 0; j <= 400; j++) {
            gp_vec2 g = {-1.5 + 3.0 * i / 400, -1.5 + 3.0 * j / 400};
            if (!gp_poly_contains(st, n, g)) continue;
            double d = gp_poly_boundary_distance(st, n, g);
            if (d > rg) rg = d;
        }
    CHECK(r + 1e-6 >= rg);                   /* nothing on the grid beats it */
    CHECK(r <= rg + 3.0 / 400 * sqrt(0.5)); /* and the grid comes close to it */

    /* random non-convex polygons (noisy stars, some very jagged) against a plain reference
     * polylabel (Lipschitz bound only, best-first, no pruning tricks) at a tight tolerance */
    int bad = 0;
    for (int trial = 0; trial < 40; trial++) {
        size_t m = 8 + (size_t)(urand() * 250);
        gp_vec2 *poly = malloc(m * sizeof *poly);
        double amp = trial % 4 == 0 ? 0.5 : 0.15, ph = urand() * 6;
        for (size_t i = 0; i < m; i++) {
            double t = 2 * PI * (double)i / (double)m;
            double rr = 1.0 + 0.25 * cos(2 * t + ph) + 0.1 * cos(3 * t + 2 * ph) + amp * (urand() - 0.5) * 0.3;
            poly[i] = (gp_vec2){5 + rr * cos(t), -2 + rr * sin(t)};
        }
        double rref = ref_polylabel(poly, m, 1e-7);
        const double tols[3] = {1e-2, 1e-4, 1e-6};
        for (int k = 0; k < 3; k++) {
            if (gp_max_inscribed_circle(poly, m, tols[k], &c, &r, NULL) != GP_OK) {
                bad++;
                continue;
            }
            if (r > rref + 1e-7 + 1e-12 || rref - r > tols[k] + 1e-12) bad++;
            if (fabs(gp_poly_boundary_distance(poly, m, c) - r) > 1e-12 || !gp_poly_contains(poly, m, c))
                bad++;
        }
        free(poly);
    }
    CHECK(bad == 0);

    gp_error e;
    gp_vec2 line[3] = {{0, 0}, {1, 1}, {2, 2}};
    CHECK(gp_max_inscribed_circle(line, 3, 0, &c, &r, &e) == GP_ERR_DEGENERATE);
    CHECK(gp_max_inscribed_circle(SQ, 2, 0, &c, &r, &e) == GP_ERR_INVALID);

    /* speed: 128-gons at tol = 1e-4 of the size */
    gp_vec2 circ[128];
    regular_ngon(circ, 128, 0, 0, 1.0, 0.0);
    const int reps = 2000;
    double sink = 0, t0 = now_s();
    for (int k = 0; k < reps; k++) {
        gp_max_inscribed_circle(circ, 128, 2e-4, &c, &r, NULL);
        sink += r;
    }
    double t1 = now_s();
    for (int k = 0; k < reps; k++) {
        gp_max_inscribed_circle(st, 128, 1e-4 * 2.6, &c, &r, NULL);
        sink += r;
    }
    double t2 = now_s();
    gp_vec2 big[1024];
    for (size_t i = 0; i < 1024; i++) {
        double t = 2 * PI * (double)i / 1024.0;
        double rr = 1.0 + 0.3 * cos(3 * t) + 0.1 * sin(7 * t) + 0.02 * cos(40 * t);
        big[i] = (gp_vec2){rr * cos(t), rr * sin(t)};
    }
    for (int k = 0; k < reps / 10; k++) {
        gp_max_inscribed_circle(big, 1024, 1e-4 * 2.6, &c, &r, NULL);
        sink += r;
    }
    double t3 = now_s();
    printf("max_inscribed_circle: regular 128-gon %.1f us, star 128-gon %.1f us, star 1024-gon %.1f us"
           " (tol 1e-4 size; sink %g)\n",
           1e6 * (t1 - t0) / reps, 1e6 * (t2 - t1) / reps, 1e6 * (t3 - t2) / (reps / 10), sink);
    CHECK((t2 - t0) / (2 * reps) < 5e-3); /* generous: sanitizer builds, loaded machines */
}

static void rect(gp_vec2 *p, double w, double h, double phi, double cx, double cy)
{
    double c = cos(phi), s = sin(phi);
    const double u[4][2] = {{-w / 2, -h / 2}, {w / 2, -h / 2}, {w / 2, h / 2}, {-w / 2, h / 2}};
    for (int i = 0; i < 4; i++)
        p[i] = (gp_vec2){cx + c * u[i][0] - s * u[i][1], cy + s * u[i][0] + c * u[i][1]};
}

/* width of a point set across direction theta (i.e. extent along the normal) */
static double extent(const gp_vec2 *p, size_t n, double theta)
{
    double nx = -sin(theta), ny = cos(theta), lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        double d = nx * p[i].x + ny * p[i].y;
        lo = fmin(lo, d);
        hi = fmax(hi, d);
    }
    return hi - lo;
}

static double angle_diff(double a, double b)
{
    double d = fmod(a - b, PI);
    if (d > PI / 2) d -= PI;
    if (d < -PI / 2) d += PI;
    return fabs(d);
}

/* gp_min_caliper_edge, the pass gp_voronoi's cell orientations use, against brute force: the
 * width across every edge from all its vertices, on random convex polygons with short
 * (collinear) edges slipped in; the tie rule (first thinnest from the lowest-leftmost vertex)
 * on squares given from every starting vertex; and its edge cases. */
static double edge_width(const gp_vec2 *h, size_t m, size_t k)
{
    size_t k1 = (k + 1) % m;
    double ex = h[k1].x - h[k].x, ey = h[k1].y - h[k].y, wmax = 0.0;
    for (size_t j = 0; j < m; j++) wmax = fmax(wmax, ex * (h[j].y - h[k].y) - ey * (h[j].x - h[k].x));
    return wmax / hypot(ex, ey);
}

static void test_caliper_edge(void)
{
    int bad = 0, trials = 0;
    for (int trial = 0; trial < 400; trial++) {
        gp_vec2 pts[24], h[48], g[96];
        size_t n = 3 + (size_t)(urand() * 21);
        for (size_t i = 0; i < n; i++) pts[i] = (gp_vec2){urand() * 3 - 1, urand() * 0.7 + 2};
        size_t m = gp_convex_hull(pts, n, h);
        if (m < 3) continue;
        /* a short collinear edge after some vertices: 1e-13 of the size, below eps2's 1e-12 */
        size_t mg = 0;
        for (size_t k = 0; k < m; k++) {
            g[mg++] = h[k];
            if (urand() < 0.3) {
                gp_vec2 a = h[k], b = h[(k + 1) % m];
                g[mg++] = (gp_vec2){a.x + 1e-13 * (b.x - a.x), a.y + 1e-13 * (b.y - a.y)};
            }
        }
        double wmin = INFINITY;
        for (size_t k = 0; k < m; k++) wmin = fmin(wmin, edge_width(h, m, k));
        for (int sq = 0; sq < 2; sq++) {
            size_t k = gp_min_caliper_edge(g, mg, 1e-24, sq);
            trials++;
            if (k >= mg) { bad++; continue; }
            gp_vec2 a = g[k], b = g[(k + 1) % mg];
            if (hypot(b.x - a.x, b.y - a.y) <= 1e-12) bad++; /* a short edge was not skipped */
            if (fabs(edge_width(g, mg, k) - wmin) > 1e-12 * wmin) bad++;
        }
    }
    CHECK(trials > 700 && bad == 0);
    /* a square from every start: the first edge from (0, 0) wins the four-way tie */
    for (size_t r = 0; r < 4; r++) {
        gp_vec2 q[4];
        for (size_t k = 0; k < 4; k++) q[k] = SQ[(k + r) % 4];
        size_t want = (4 - r) % 4; /* where (0, 0) now is */
        CHECK(gp_min_caliper_edge(q, 4, -1.0, 0) == want);
        CHECK(gp_min_caliper_edge(q, 4, -1.0, 1) == want);
    }
    /* a 3 x 1 rectangle: one of the two long sides, the first from the lowest vertex */
    gp_vec2 rc[4] = {{3, 1}, {0, 1}, {0, 0}, {3, 0}};
    CHECK(gp_min_caliper_edge(rc, 4, -1.0, 1) == 2);
    CHECK(gp_min_caliper_edge(rc, 1, -1.0, 1) == 1);
    CHECK(gp_min_caliper_edge(NULL, 4, -1.0, 1) == 4);
    CHECK(gp_min_caliper_edge(rc, 4, 100.0, 1) == 4); /* every edge skipped */
}

static void test_caliper(void)
{
    double w, ang, len;
    gp_vec2 p[4];
    const double phis[] = {0.0, 0.3, -0.7, 1.2, PI / 2 - 1e-3, -PI / 2 + 1e-3, 2.5, -3.0, PI / 2};
    for (int k = 0; k < 9; k++) {
        rect(p, 3.0, 1.0, phis[k], 1e6, -5.0);
        CHECK(gp_min_caliper(p, 4, &w, &ang, &len, NULL) == GP_OK);
        CHECK_REL(w, 1.0, 1e-9);
        CHECK_REL(len, 3.0, 1e-9);
        CHECK(angle_diff(ang, phis[k]) < 1e-9);
        CHECK(ang > -PI / 2 && ang <= PI / 2);
    }
    /* square: width = side; a vertical long axis reports +pi/2 */
    CHECK(gp_min_caliper(SQ, 4, &w, &ang, &len, NULL) == GP_OK);
    CHECK_NEAR(w, 1.0, 1e-15);
    CHECK_NEAR(len, 1.0, 1e-15);
    gp_vec2 tall[4];
    rect(tall, 1.0, 4.0, 0.0, 0, 0);
    CHECK(gp_min_caliper(tall, 4, &w, &ang, &len, NULL) == GP_OK);
    CHECK_NEAR(ang, PI / 2, 1e-15);
    CHECK_NEAR(w, 1.0, 1e-15);
    CHECK_NEAR(len, 4.0, 1e-15);

    /* ellipse a:b = 2:1 at 30 degrees, 1024 points */
    const size_t n = 1024;
    gp_vec2 *el = malloc(n * sizeof *el);
    double a = 2.0, b = 1.0, phi = PI / 6;
    for (int variant = 0; variant < 2; variant++) {
        for (size_t i = 0; i < n; i++) {
            double t = 2 * PI * ((double)i + 0.5 * variant) / (double)n;
            double x = a * cos(t), y = b * sin(t);
            el[i] = (gp_vec2){7 + cos(phi) * x - sin(phi) * y, -3 + sin(phi) * x + cos(phi) * y};
        }
        CHECK(gp_min_caliper(el, n, &w, &ang, &len, NULL) == GP_OK);
        CHECK_REL(w, 2 * b, 1e-5);
        CHECK_REL(len, 2 * a, 1e-5);
        /* with a vertex at the minor apex the best edge is tilted by about pi/n * b/a */
        CHECK(angle_diff(ang, phi) < (variant ? 1e-9 : 0.01 * PI / 180 + 2 * PI / n));
        /* brute force: no direction gives a smaller extent */
        double wmin = INFINITY;
        for (int s = 0; s < 20000; s++) wmin = fmin(wmin, extent(el, n, PI * s / 20000.0));
        CHECK(w <= wmin * (1 + 1e-12));
        CHECK_REL(extent(el, n, ang), w, 1e-12);
    }
    free(el);

    /* random polygons: matches a fine angle sweep */
    int bad = 0;
    for (int trial = 0; trial < 30; trial++) {
        gp_vec2 q[40];
        size_t m = 3 + (size_t)(urand() * 37);
        for (size_t i = 0; i < m; i++) q[i] = (gp_vec2){urand() * 2, urand()};
        if (gp_min_caliper(q, m, &w, &ang, &len, NULL) != GP_OK) {
            bad++;
            continue;
        }
        /* the minimum width is attained across the direction of some pair of points */
        double wmin = INFINITY;
        for (size_t i = 0; i < m; i++)
            for (size_t j = i + 1; j < m; j++)
                wmin = fmin(wmin, extent(q, m, atan2(q[j].y - q[i].y, q[j].x - q[i].x)));
        if (fabs(w - wmin) > 1e-12 * wmin) bad++;
        if (fabs(extent(q, m, ang) - w) > 1e-12) bad++;
    }
    CHECK(bad == 0);

    gp_error e;
    gp_vec2 col[4] = {{0, 0}, {1, 1}, {2, 2}, {1, 1}};
    CHECK(gp_min_caliper(col, 4, &w, &ang, &len, &e) == GP_ERR_DEGENERATE);
    CHECK(gp_min_caliper(col, 1, &w, &ang, &len, &e) == GP_ERR_DEGENERATE);
    CHECK(gp_min_caliper(col, 0, &w, &ang, &len, &e) == GP_ERR_INVALID);
}

/* independent even-odd count with the textbook formula (fine away from edges) */
static int naive_contains(const gp_vec2 *p, size_t n, gp_vec2 q)
{
    int c = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++)
        if ((p[i].y > q.y) != (p[j].y > q.y) &&
            q.x < (p[j].x - p[i].x) * (q.y - p[i].y) / (p[j].y - p[i].y) + p[i].x)
            c = !c;
    return c;
}

static void test_contains(void)
{
    /* L-shape: interior, the notch, edges, vertices, the reflex corner */
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){0.5, 0.5}));
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){1.5, 0.5}));
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){0.5, 1.5}));
    CHECK(!gp_poly_contains(LSH, 6, (gp_vec2){1.5, 1.5}));
    CHECK(!gp_poly_contains(LSH, 6, (gp_vec2){-0.1, 0.5}));
    CHECK(!gp_poly_contains(LSH, 6, (gp_vec2){2.5, 1.0}));
    CHECK(!gp_poly_contains(LSH, 6, (gp_vec2){0.5, 2.0 + 1e-9}));
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){1.0, 1.0}));  /* reflex vertex */
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){1.5, 1.0}));  /* edge */
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){1.0, 1.5}));  /* edge */
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){2.0, 0.0}));  /* vertex */
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){0.0, 0.7}));  /* edge */
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){2.0, 0.5}));  /* edge */
    CHECK(gp_poly_contains(LSH, 6, (gp_vec2){1.5, 1.0 + 1e-13})); /* within the tolerance */
    CHECK(!gp_poly_contains(LSH, 6, (gp_vec2){1.5, 1.0 + 1e-9}));
    /* the same at a huge offset, tiny scale */
    gp_vec2 L[6];
    transform(LSH, L, 6, 1e-3, 1e6, 1e6);
    CHECK(gp_poly_contains(L, 6, (gp_vec2){1e6 + 0.5e-3, 1e6 + 0.5e-3}));
    CHECK(!gp_poly_contains(L, 6, (gp_vec2){1e6 + 1.5e-3, 1e6 + 1.5e-3}));
    CHECK(gp_poly_contains(L, 6, L[3]));
    CHECK(gp_poly_contains(L, 6, (gp_vec2){L[1].x, 0.5 * (L[1].y + L[2].y)}));
    /* random points away from the boundary agree with the textbook test, both orientations */
    gp_vec2 st[100], rv[100];
    for (size_t i = 0; i < 100; i++) {
        double t = 2 * PI * (double)i / 100.0, rr = 1.0 + 0.5 * cos(5 * t);
        st[i] = (gp_vec2){rr * cos(t), rr * sin(t)};
    }
    for (size_t i = 0; i < 100; i++) rv[i] = st[99 - i];
    int bad = 0;
    for (int k = 0; k < 20000; k++) {
        gp_vec2 q = {urand() * 3.2 - 1.6, urand() * 3.2 - 1.6};
        if (gp_poly_boundary_distance(st, 100, q) < 1e-9) continue;
        int want = naive_contains(st, 100, q);
        if (gp_poly_contains(st, 100, q) != want || gp_poly_contains(rv, 100, q) != want) bad++;
    }
    CHECK(bad == 0);
    /* every vertex and every edge midpoint counts as inside */
    for (size_t i = 0; i < 100; i++) {
        gp_vec2 m = {0.5 * (st[i].x + st[(i + 1) % 100].x), 0.5 * (st[i].y + st[(i + 1) % 100].y)};
        if (!gp_poly_contains(st, 100, st[i]) || !gp_poly_contains(st, 100, m)) bad++;
    }
    CHECK(bad == 0);
    /* an odd vertex count (the screen takes edges two at a time), a triangle, a notch at the
     * last edge: random points, vertices and midpoints */
    gp_vec2 odd[99], tri[3] = {{0, 0}, {1, 0}, {0.3, 0.8}};
    for (size_t i = 0; i < 99; i++) {
        double t = 2 * PI * (double)i / 99.0, rr = i == 98 ? 0.3 : 1.0 + 0.4 * sin(7 * t);
        odd[i] = (gp_vec2){rr * cos(t), rr * sin(t)};
    }
    int checked = 0;
    uint64_t keep = rs; /* its own draws (as test_hull_star) */
    for (int k = 0; k < 20000; k++) {
        gp_vec2 q = {urand() * 3.2 - 1.6, urand() * 3.2 - 1.6}, r = {urand(), urand()};
        if (gp_poly_boundary_distance(odd, 99, q) >= 1e-9) {
            bad += gp_poly_contains(odd, 99, q) != naive_contains(odd, 99, q);
            checked++;
        }
        if (gp_poly_boundary_distance(tri, 3, r) >= 1e-9)
            bad += gp_poly_contains(tri, 3, r) != naive_contains(tri, 3, r);
    }
    for (size_t i = 0; i < 99; i++) {
        gp_vec2 m = {0.5 * (odd[i].x + odd[(i + 1) % 99].x), 0.5 * (odd[i].y + odd[(i + 1) % 99].y)};
        bad += !gp_poly_contains(odd, 99, odd[i]) + !gp_poly_contains(odd, 99, m);
    }
    CHECK(bad == 0 && checked > 15000);
    rs = keep;
    CHECK_NEAR(gp_segment_distance((gp_vec2){0, 1}, (gp_vec2){-1, 0}, (gp_vec2){1, 0}), 1.0, 0);
    CHECK_NEAR(gp_segment_distance((gp_vec2){3, 4}, (gp_vec2){-1, 0}, (gp_vec2){0, 0}), 5.0, 1e-15);
    CHECK_NEAR(gp_segment_distance((gp_vec2){3, 4}, (gp_vec2){0, 0}, (gp_vec2){0, 0}), 5.0, 1e-15);
    CHECK_NEAR(gp_poly_boundary_distance(LSH, 6, (gp_vec2){1.5, 1.5}), 0.5, 1e-15);
    CHECK_NEAR(gp_poly_boundary_distance(LSH, 6, (gp_vec2){0.25, 0.5}), 0.25, 1e-15);
}

static void test_simple_inside_overlap(void)
{
    /* simplicity */
    CHECK(gp_poly_is_simple(SQ, 4));
    CHECK(gp_poly_is_simple(LSH, 6));
    gp_vec2 bow[4] = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
    CHECK(!gp_poly_is_simple(bow, 4));
    gp_vec2 dup[7] = {{0, 0}, {0, 0}, {0.5, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
    CHECK(gp_poly_is_simple(dup, 7));
    gp_vec2 spike[5] = {{0, 0}, {1, 0}, {2, 0}, {1, 0}, {0, 1}}; /* folds back along y = 0 */
    CHECK(!gp_poly_is_simple(spike, 5));
    gp_vec2 flat[3] = {{0, 0}, {1, 0}, {2, 0}};
    CHECK(!gp_poly_is_simple(flat, 3));
    gp_vec2 pinch[6] = {{0, 0}, {1, 1}, {2, 0}, {2, 2}, {1, 1}, {0, 2}}; /* touches itself */
    CHECK(!gp_poly_is_simple(pinch, 6));
    gp_vec2 vtouch[5] = {{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}}; /* vertex on an edge */
    CHECK(!gp_poly_is_simple(vtouch, 5));
    gp_vec2 star[128];
    for (size_t i = 0; i < 128; i++) {
        double t = 2 * PI * (double)i / 128.0, rr = 1.0 + 0.3 * cos(3 * t);
        star[i] = (gp_vec2){1e6 + rr * cos(t), rr * sin(t)};
    }
    CHECK(gp_poly_is_simple(star, 128));

    /* overlap */
    gp_vec2 a[4], b[4];
    transform(SQ, a, 4, 1, 0, 0);
    transform(SQ, b, 4, 1, 1, 0); /* shares the edge x = 1 */
    CHECK(!gp_poly_overlap(a, 4, b, 4));
    transform(SQ, b, 4, 1, 1, 1); /* touches at one vertex */
    CHECK(!gp_poly_overlap(a, 4, b, 4));
    transform(SQ, b, 4, 1, 0.5, 0.5); /* crossing */
    CHECK(gp_poly_overlap(a, 4, b, 4));
    transform(SQ, b, 4, 1, 2, 0); /* apart */
    CHECK(!gp_poly_overlap(a, 4, b, 4));
    transform(SQ, b, 4, 0.5, 0.25, 0.25); /* nested strictly */
    CHECK(gp_poly_overlap(a, 4, b, 4) && gp_poly_overlap(b, 4, a, 4));
    transform(SQ, b, 4, 0.5, 0.0, 0.0); /* nested, sharing two edges */
    CHECK(gp_poly_overlap(a, 4, b, 4) && gp_poly_overlap(b, 4, a, 4));
    CHECK(gp_poly_overlap(a, 4, a, 4)); /* identical */
    gp_vec2 arev[4] = {a[3], a[2], a[1], a[0]};
    CHECK(gp_poly_overlap(a, 4, arev, 4));
    transform(SQ, b, 4, 1, 0.5, 1); /* shares half an edge */
    CHECK(!gp_poly_overlap(a, 4, b, 4));
    transform(SQ, b, 4, 1, 0.5, 1 - 1e-15); /* overlaps by a hair */
    CHECK(gp_poly_overlap(a, 4, b, 4));
    transform(SQ, b, 4, 1, 1 + 1e-15, 0.5); /* apart by a hair */
    CHECK(!gp_poly_overlap(a, 4, b, 4));
    /* a triangle poking a vertex onto an edge from outside, and through it */
    gp_vec2 t1[3] = {{0.5, 1}, {1, 2}, {0, 2}};
    CHECK(!gp_poly_overlap(a, 4, t1, 3));
    gp_vec2 t2[3] = {{0.5, 0.999}, {1, 2}, {0, 2}};
    CHECK(gp_poly_overlap(a, 4, t2, 3));
    /* the L-shape and a square in its notch, touching along two edges */
    transform(SQ, b, 4, 1, 1, 1);
    CHECK(!gp_poly_overlap(LSH, 6, b, 4));
    transform(SQ, b, 4, 1, 0.9, 0.9);
    CHECK(gp_poly_overlap(LSH, 6, b, 4));
    /* a bar across the notch whose vertices all lie on the L's boundary or outside */
    gp_vec2 bar[4] = {{1, 1}, {2, 1}, {2, 1.2}, {1, 1.2}};
    CHECK(!gp_poly_overlap(LSH, 6, bar, 4));

    /* inside */
    transform(SQ, b, 4, 0.5, 0.25, 0.25);
    CHECK(gp_poly_inside_poly(b, 4, a, 4));
    CHECK(!gp_poly_inside_poly(a, 4, b, 4));
    transform(SQ, b, 4, 0.5, 0.0, 0.0); /* touching the boundary counts as inside */
    CHECK(gp_poly_inside_poly(b, 4, a, 4));
    CHECK(gp_poly_inside_poly(a, 4, a, 4));
    transform(SQ, b, 4, 0.5, 0.6, 0.25); /* sticks out */
    CHECK(!gp_poly_inside_poly(b, 4, a, 4));
    transform(SQ, b, 4, 0.5, 0.5 + 1e-15, 0.25); /* sticks out by a hair */
    CHECK(!gp_poly_inside_poly(b, 4, a, 4));
    /* a U container with a triangle bridging the gap: every vertex inside, no proper crossing,
     * but an edge runs through the notch */
    gp_vec2 U[8] = {{0, 0}, {3, 0}, {3, 2}, {2, 2}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    gp_vec2 br[3] = {{0.5, 1.5}, {2.5, 1.5}, {1.5, 0.5}};
    CHECK(!gp_poly_inside_poly(br, 3, U, 8));
    /* all vertices on U's boundary, no proper crossing, yet outside: the notch itself, and a
     * triangle from the mouth corners to the notch bottom */
    gp_vec2 notch[4] = {{1, 2}, {2, 2}, {2, 1}, {1, 1}};
    CHECK(!gp_poly_inside_poly(notch, 4, U, 8));
    CHECK(!gp_poly_overlap(notch, 4, U, 8));
    gp_vec2 br2[3] = {{1, 2}, {2, 2}, {1.5, 1}};
    CHECK(!gp_poly_inside_poly(br2, 3, U, 8));
    CHECK(!gp_poly_overlap(br2, 3, U, 8));
    gp_vec2 ok3[3] = {{0.5, 0.5}, {2.5, 0.5}, {1.5, 1}}; /* touches the notch bottom */
    CHECK(gp_poly_inside_poly(ok3, 3, U, 8));
    gp_vec2 ok4[4] = {{0, 0}, {3, 0}, {2, 1}, {1, 1}}; /* shares the bottom edge and a corner */
    CHECK(gp_poly_inside_poly(ok4, 4, U, 8));
    /* a grain in a cell at huge offset */
    gp_vec2 cell[5] = {{1e6, 1e6}, {1e6 + 1e-3, 1e6}, {1e6 + 1.2e-3, 1e6 + 1e-3},
                       {1e6 + 0.5e-3, 1e6 + 1.5e-3}, {1e6 - 0.2e-3, 1e6 + 0.8e-3}};
    gp_vec2 grain[64];
    regular_ngon(grain, 64, 1e6 + 0.5e-3, 1e6 + 0.6e-3, 0.4e-3, 0.0);
    CHECK(gp_poly_inside_poly(grain, 64, cell, 5));
    CHECK(gp_poly_overlap(grain, 64, cell, 5));
    regular_ngon(grain, 64, 1e6 + 0.5e-3, 1e6 + 0.3e-3, 0.4e-3, 0.0);
    CHECK(!gp_poly_inside_poly(grain, 64, cell, 5));
}

static void test_nan(void)
{
    gp_vec2 p[4] = {{0, 0}, {1, 0}, {NAN, 1}, {0, 1}};
    gp_vec2 c, h[4];
    double r, w, ang, len;
    gp_error e;
    (void)gp_poly_signed_area(p, 4);
    (void)gp_poly_perimeter(p, 4);
    CHECK(gp_poly_centroid(p, 4, &c, &e) == GP_ERR_INVALID);
    CHECK(gp_min_enclosing_circle(p, 4, &c, &r, &e) == GP_ERR_INVALID);
    CHECK(gp_max_inscribed_circle(p, 4, 0, &c, &r, &e) == GP_ERR_INVALID);
    CHECK(gp_max_inscribed_circle(SQ, 4, NAN, &c, &r, &e) == GP_ERR_INVALID);
    CHECK(gp_min_caliper(p, 4, &w, &ang, &len, &e) == GP_ERR_INVALID);
    CHECK(gp_convex_hull(p, 4, h) == 3);
    (void)gp_poly_contains(p, 4, (gp_vec2){0.5, 0.5});
    CHECK(!gp_poly_contains(SQ, 4, (gp_vec2){NAN, 0.5}));
    CHECK(!gp_poly_is_simple(p, 4));
    CHECK(!gp_poly_inside_poly(p, 4, SQ, 4));
    CHECK(!gp_poly_overlap(p, 4, SQ, 4));
    CHECK(gp_poly_bbox(p, 4, &c, &c, &e) == GP_ERR_INVALID);
    (void)gp_poly_boundary_distance(p, 4, (gp_vec2){0.5, 0.5});
    CHECK(gp_poly_area(NULL, 0) == 0.0);
    gp_vec2 lo, hi;
    CHECK(gp_poly_bbox(LSH, 6, &lo, &hi, NULL) == GP_OK && lo.x == 0 && hi.x == 2 && hi.y == 2);
}

int main(void)
{
    test_area_perimeter_centroid();
    test_orient();
    test_hull();
    test_hull_star();
    test_mec();
    test_mic();
    test_caliper();
    test_caliper_edge();
    test_contains();
    test_simple_inside_overlap();
    test_nan();
    return gp_test_summary();
}
