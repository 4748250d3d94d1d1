/* test_odec.c -- gp_odec: circle, ellipse, square, a non-convex polygon, determinism, bad
 * input; containment, coverage and the quality measures checked by brute force. */
#include "gp_odec.h"
#include "gp_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

static void ellipse(gp_vec2 *p, size_t n, double a, double b, double phi, gp_vec2 c)
{
    for (size_t i = 0; i < n; i++) {
        double t = 2 * PI * (double)i / (double)n;
        double x = a * cos(t), y = b * sin(t);
        p[i].x = c.x + x * cos(phi) - y * sin(phi);
        p[i].y = c.y + x * sin(phi) + y * cos(phi);
    }
}

/* independent helpers */
static double seg_dist(double px, double py, gp_vec2 a, gp_vec2 b)
{
    double ex = b.x - a.x, ey = b.y - a.y, wx = px - a.x, wy = py - a.y;
    double t = (wx * ex + wy * ey) / (ex * ex + ey * ey);
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    return hypot(wx - t * ex, wy - t * ey);
}

static double bdist(const gp_vec2 *p, size_t n, double x, double y)
{
    double d = INFINITY;
    for (size_t i = 0; i < n; i++)
        d = fmin(d, seg_dist(x, y, p[i], p[(i + 1) % n]));
    return d;
}

static int inside(const gp_vec2 *p, size_t n, double x, double y)
{
    int c = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++) {
        if ((p[i].y > y) != (p[j].y > y) &&
            x < (p[j].x - p[i].x) * (y - p[i].y) / (p[j].y - p[i].y) + p[i].x)
            c = !c;
    }
    return c;
}

static double shoelace(const gp_vec2 *p, size_t n)
{
    double a = 0;
    for (size_t i = 0; i < n; i++)
        a += p[i].x * p[(i + 1) % n].y - p[(i + 1) % n].x * p[i].y;
    return 0.5 * fabs(a);
}

static double dist_to_union(const gp_odec_result *r, double x, double y)
{
    double d = INFINITY;
    for (size_t k = 0; k < r->ndiscs; k++)
        d = fmin(d, hypot(x - r->discs[k].x, y - r->discs[k].y) - r->discs[k].r);
    return d;
}

/* every disc: centre inside, clearance >= r - tol */
static double worst_protrusion(const gp_vec2 *p, size_t n, const gp_odec_result *r, int *centres_in)
{
    double w = -INFINITY;
    *centres_in = 1;
    for (size_t k = 0; k < r->ndiscs; k++) {
        *centres_in &= inside(p, n, r->discs[k].x, r->discs[k].y);
        w = fmax(w, r->discs[k].r - bdist(p, n, r->discs[k].x, r->discs[k].y));
    }
    return w;
}

/* raster estimate of |U n P| / |P| on a g x g grid of cell centres */
static double raster_ratio(const gp_vec2 *p, size_t n, const gp_odec_result *r, int g)
{
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        x0 = fmin(x0, p[i].x);
        x1 = fmax(x1, p[i].x);
        y0 = fmin(y0, p[i].y);
        y1 = fmax(y1, p[i].y);
    }
    long in_p = 0, in_both = 0;
    for (int a = 0; a < g; a++) {
        for (int b = 0; b < g; b++) {
            double x = x0 + (a + 0.5) * (x1 - x0) / g, y = y0 + (b + 0.5) * (y1 - y0) / g;
            if (!inside(p, n, x, y))
                continue;
            in_p++;
            in_both += dist_to_union(r, x, y) < 0;
        }
    }
    (void)in_p;
    return (double)in_both * (x1 - x0) * (y1 - y0) / ((double)g * g) / shoelace(p, n);
}

/* brute-force Hausdorff distance between the contour and the boundary of the union */
static double brute_hausdorff(const gp_vec2 *p, size_t n, const gp_odec_result *r)
{
    double h = 0;
    for (size_t i = 0; i < n; i++) {
        for (int t = 0; t < 50; t++) {
            double f = t / 50.0;
            gp_vec2 a = p[i], b = p[(i + 1) % n];
            h = fmax(h, dist_to_union(r, a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)));
        }
    }
    for (size_t k = 0; k < r->ndiscs; k++) {
        for (int t = 0; t < 4000; t++) {
            double th = 2 * PI * t / 4000;
            double x = r->discs[k].x + r->discs[k].r * cos(th);
            double y = r->discs[k].y + r->discs[k].r * sin(th);
            if (dist_to_union(r, x, y) < -1e-12)
                continue;
            h = fmax(h, bdist(p, n, x, y));
        }
    }
    return h;
}

static void test_circle(void)
{
    gp_vec2 p[128];
    gp_vec2 c = {1.5, -2.0};
    ellipse(p, 128, 2.0, 2.0, 0, c);
    gp_odec_result r;
    gp_error e;
    CHECK(gp_odec_build(p, 128, NULL, &r, &e) == GP_OK);
    CHECK(r.ndiscs == 1);
    CHECK(r.uncovered == 0 && r.capped == 0);
    CHECK(r.nnodes == 128);
    if (r.ndiscs >= 1) {
        CHECK_NEAR(r.discs[0].r, 2.0, 1e-12);
        CHECK_NEAR(r.discs[0].x, 1.5, 1e-12);
        CHECK_NEAR(r.discs[0].y, -2.0, 1e-12);
    }
    CHECK_NEAR(r.r_eq, sqrt(shoelace(p, 128) / PI), 1e-12);
    gp_odec_quality q;
    CHECK(gp_odec_measure(p, 128, r.discs, r.ndiscs, &q, &e) == GP_OK);
    /* the disc covers the 128-gon: ratio 1, excess = circle / polygon - 1 */
    double poly_area = 0.5 * 128 * 4.0 * sin(2 * PI / 128);
    CHECK_NEAR(q.area_ratio, 1.0, 2e-4);
    CHECK_NEAR(q.area_excess, PI * 4.0 / poly_area - 1.0, 2e-4);
    /* sagitta of a 128-gon of radius 2, over R_eq */
    double sag = 2.0 * (1 - cos(PI / 128));
    CHECK_NEAR(q.hausdorff, sag / r.r_eq, 0.01); /* the documented sampling resolution */
    CHECK_NEAR(q.max_protrusion, sag / r.r_eq, 1e-9);
    gp_odec_result_free(&r);
    CHECK(r.discs == NULL && r.ndiscs == 0);

    /* a coarse 40-gon: edges longer than the node gap get inserted nodes; still one disc */
    gp_vec2 p40[40];
    ellipse(p40, 40, 1.0, 1.0, 0.3, (gp_vec2){0, 0});
    CHECK(gp_odec_build(p40, 40, NULL, &r, &e) == GP_OK);
    CHECK(r.nnodes > 40);
    CHECK(r.uncovered == 0);
    CHECK(r.ndiscs >= 1 && r.ndiscs <= 3);
    if (r.ndiscs >= 1)
        CHECK_REL(r.discs[0].r, 1.0, 0.01);
    gp_odec_result_free(&r);
}

static void check_cluster(const char *name, const gp_vec2 *p, size_t n, const gp_odec_params *pr,
                          double min_ratio)
{
    gp_odec_params d;
    gp_odec_params_defaults(&d);
    if (!pr)
        pr = &d;
    gp_odec_result r;
    gp_error e;
    CHECK(gp_odec_build(p, n, pr, &r, &e) == GP_OK);
    CHECK(r.ndiscs >= 2);
    double req = r.r_eq;
    /* containment: centres inside; clearance tolerance from the header */
    double delta = pr->r_min - sqrt(pr->r_min * pr->r_min - pr->spacing * pr->r_min / 2);
    int cin;
    double prot = worst_protrusion(p, n, &r, &cin);
    CHECK(cin);
    CHECK(prot <= delta * req + 1e-12);
    /* every disc at least r_min */
    double rmin = INFINITY;
    for (size_t k = 0; k < r.ndiscs; k++)
        rmin = fmin(rmin, r.discs[k].r);
    CHECK(rmin >= pr->r_min * req * (1 - 1e-12));
    /* coverage: every vertex within spacing of the union */
    double worst = 0;
    for (size_t i = 0; i < n; i++)
        worst = fmax(worst, dist_to_union(&r, p[i].x, p[i].y));
    CHECK(r.uncovered == 0);
    CHECK(worst <= pr->spacing * req * (1 + 1e-9));
    /* quality against brute force */
    gp_odec_quality q;
    CHECK(gp_odec_measure(p, n, r.discs, r.ndiscs, &q, &e) == GP_OK);
    double rr = raster_ratio(p, n, &r, 700);
    CHECK(q.area_ratio > min_ratio);
    CHECK_NEAR(q.area_ratio, rr, 3e-3);
    CHECK(q.area_excess >= 0 && q.area_excess < 0.01);
    double bh = brute_hausdorff(p, n, &r) / req;
    CHECK_NEAR(q.hausdorff, bh, 0.01);
    CHECK_NEAR(q.max_protrusion, fmax(0, prot / req), 1e-9);
    printf("%-10s discs %3zu nodes %4zu ratio %.4f (raster %.4f) excess %.2e hausdorff %.4f "
           "(brute %.4f) protrusion %.2e\n", name, r.ndiscs, r.nnodes, q.area_ratio, rr,
           q.area_excess, q.hausdorff, bh, q.max_protrusion);
    gp_odec_result_free(&r);
}

static void test_shapes(void)
{
    gp_vec2 p[256];
    ellipse(p, 128, 2.0, 1.0, 0.5, (gp_vec2){0.3, 0.2});
    check_cluster("ellipse", p, 128, NULL, 0.9);
    ellipse(p, 256, 3.0, 1.0, -1.0, (gp_vec2){10, 20});
    check_cluster("ellipse3", p, 256, NULL, 0.9);

    /* square of side 2: corners covered to within spacing (checked in check_cluster) */
    gp_vec2 sq[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    check_cluster("square", sq, 4, NULL, 0.9);
    /* clockwise square gives the same discs (orientation handled) */
    gp_vec2 sqcw[4] = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
    check_cluster("square-cw", sqcw, 4, NULL, 0.9);
    gp_odec_result a;
    CHECK(gp_odec_build(sq, 4, NULL, &a, NULL) == GP_OK);
    /* the first disc is the inscribed circle */
    if (a.ndiscs)
        CHECK_NEAR(a.discs[0].r, 1.0, 1e-12);
    gp_odec_result_free(&a);

    /* an L shape (non-convex) */
    gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    check_cluster("L", L, 6, NULL, 0.9);
    /* smaller r_min / spacing: more discs, tighter fill */
    gp_odec_params fine = {0.02, 0.01, 0};
    check_cluster("L-fine", L, 6, &fine, 0.95);
}

static void test_determinism_and_cap(void)
{
    gp_vec2 p[128];
    ellipse(p, 128, 2.0, 1.0, 0.5, (gp_vec2){0.3, 0.2});
    gp_odec_result a, b;
    CHECK(gp_odec_build(p, 128, NULL, &a, NULL) == GP_OK);
    CHECK(gp_odec_build(p, 128, NULL, &b, NULL) == GP_OK);
    CHECK(a.ndiscs == b.ndiscs && a.ndiscs > 0 &&
          memcmp(a.discs, b.discs, a.ndiscs * sizeof *a.discs) == 0);
    /* discs come largest first in the main pass: the first is the largest */
    double rmax = 0;
    for (size_t k = 0; k < a.ndiscs; k++)
        rmax = fmax(rmax, a.discs[k].r);
    CHECK(a.ndiscs > 0 && a.discs[0].r == rmax);
    gp_odec_params cap = {0.05, 0.025, 2};
    gp_odec_result c;
    CHECK(gp_odec_build(p, 128, &cap, &c, NULL) == GP_OK);
    CHECK(c.ndiscs == 2 && c.capped == 1 && c.uncovered > 0);
    CHECK(c.ndiscs == 2 && memcmp(c.discs, a.discs, 2 * sizeof *a.discs) == 0);
    gp_odec_result_free(&a);
    gp_odec_result_free(&b);
    gp_odec_result_free(&c);
}

static void test_errors(void)
{
    gp_odec_result r;
    gp_error e;
    gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    CHECK(gp_odec_build(NULL, 4, NULL, &r, &e) == GP_ERR_INVALID);
    CHECK(gp_odec_build(sq, 2, NULL, &r, &e) == GP_ERR_INVALID && r.discs == NULL);
    CHECK(gp_odec_build(sq, 4, NULL, NULL, &e) == GP_ERR_INVALID);
    gp_vec2 bad[4] = {{0, 0}, {1, 0}, {NAN, 1}, {0, 1}};
    CHECK(gp_odec_build(bad, 4, NULL, &r, &e) == GP_ERR_INVALID);
    gp_odec_params p = {0, 0.025, 10};
    CHECK(gp_odec_build(sq, 4, &p, &r, &e) == GP_ERR_INVALID);
    p = (gp_odec_params){0.05, NAN, 10};
    CHECK(gp_odec_build(sq, 4, &p, &r, &e) == GP_ERR_INVALID);
    gp_vec2 line[4] = {{0, 0}, {1, 0}, {2, 0}, {1, 0}};
    CHECK(gp_odec_build(line, 4, NULL, &r, &e) == GP_ERR_DEGENERATE);
    gp_vec2 dup[4] = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};
    CHECK(gp_odec_build(dup, 4, NULL, &r, &e) == GP_ERR_DEGENERATE);
    gp_odec_quality q;
    CHECK(gp_odec_measure(sq, 4, NULL, 1, &q, &e) == GP_ERR_INVALID);
    gp_odec_disc d = {0.5, 0.5, -1};
    CHECK(gp_odec_measure(sq, 4, &d, 1, &q, &e) == GP_ERR_INVALID);
    /* duplicated vertices are tolerated */
    gp_vec2 sqd[6] = {{0, 0}, {1, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
    CHECK(gp_odec_build(sqd, 6, NULL, &r, &e) == GP_OK && r.ndiscs > 0);
    if (r.ndiscs)
        CHECK_NEAR(r.discs[0].r, 0.5, 1e-12);
    gp_odec_result_free(&r);
}

int main(void)
{
    test_circle();
    test_shapes();
    test_determinism_and_cap();
    test_errors();
    return gp_test_summary();
}
