/* test_voronoi.c -- bounded Voronoi tessellation against independent truth:
 * - convex containers: every cell against a brute-force O(N^2) half-plane intersection;
 * - any container: sample points, their nearest seed (brute force) must be the one cell whose
 *   parts hold them; areas against a point count;
 * - sums of areas, seeds in their cells, neighbour symmetry, orientation against gp_min_caliper;
 * - robustness: duplicates, collinear seeds, seeds on the boundary, scales 1e-6 / 1e6, a 1000:1
 *   strip, an L-shape, an annulus, a U-shape that splits cells;
 * - moves (committed and rolled back; near edges, inside cells, anywhere) against a full rebuild
 *   of the same seeds, bit for bit: 10,000 each on a square, an L-shape, an annulus, and a square
 *   of 3,000 cells (moves recompute cells from the neighbour lists, a build from the grid). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_geom.h"
#include "gp_test.h"
#include "gp_voronoi.h"

static uint64_t rs = 88172645463325252ull;
static double urand(void)
{
    rs ^= rs << 13;
    rs ^= rs >> 7;
    rs ^= rs << 17;
    return (double)(rs >> 11) * (1.0 / 9007199254740992.0);
}

/* ---- brute-force cell of seed i in a convex CCW container: Sutherland-Hodgman ---- */
static int bf_clip(gp_vec2 *p, int n, gp_vec2 o, gp_vec2 nrm, gp_vec2 *out)
{
    int w = 0;
    for (int k = 0; k < n; k++) {
        gp_vec2 a = p[k], b = p[(k + 1) % n];
        double da = (a.x - o.x) * nrm.x + (a.y - o.y) * nrm.y;
        double db = (b.x - o.x) * nrm.x + (b.y - o.y) * nrm.y;
        if (da <= 0) out[w++] = a;
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
            double t = da / (da - db);
            out[w++] = (gp_vec2){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
        }
    }
    return w;
}

static double bf_cell_area(const gp_vec2 *box, int nbox, const gp_vec2 *s, int n, int i)
{
    gp_vec2 *a = malloc(sizeof(gp_vec2) * (size_t)(nbox + n + 8) * 2);
    gp_vec2 *b = a + nbox + n + 8;
    memcpy(a, box, sizeof(gp_vec2) * (size_t)nbox);
    int m = nbox;
    for (int j = 0; j < n && m > 0; j++) {
        if (j == i) continue;
        gp_vec2 nrm = {s[j].x - s[i].x, s[j].y - s[i].y};
        gp_vec2 mid = {0.5 * (s[i].x + s[j].x), 0.5 * (s[i].y + s[j].y)};
        m = bf_clip(a, m, mid, nrm, b);
        memcpy(a, b, sizeof(gp_vec2) * (size_t)m);
    }
    double ar = m >= 3 ? gp_poly_area(a, (size_t)m) : 0.0;
    free(a);
    return ar;
}

/* crossing-number point-in-polygon, deliberately not gp_poly_contains: the cells are checked
 * against an independent test */
static int poly_pip(const gp_vec2 *p, size_t n, gp_vec2 q)
{
    int c = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++)
        if ((p[i].y > q.y) != (p[j].y > q.y)) {
            double x = p[j].x + (q.y - p[j].y) * (p[i].x - p[j].x) / (p[i].y - p[j].y);
            if (q.x < x) c ^= 1;
        }
    return c;
}

/* which cells hold q (count), and one of them */
static int cells_holding(const gp_voronoi *v, gp_vec2 q, size_t *which)
{
    static gp_vec2 buf[4096];
    int cnt = 0;
    size_t n = gp_voronoi_count(v);
    for (size_t i = 0; i < n; i++) {
        size_t np = gp_voronoi_cell_parts(v, i);
        for (size_t p = 0; p < np; p++) {
            size_t m = gp_voronoi_cell_polygon(v, i, p, buf, 4096);
            if (m > 4096) continue;
            if (poly_pip(buf, m, q)) {
                cnt++;
                *which = i;
            }
        }
    }
    return cnt;
}

static double dist2(gp_vec2 a, gp_vec2 b) { return (a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y); }

/* Checks invariants shared by all containers. area: container area. */
static void check_invariants(const gp_voronoi *v, double area)
{
    size_t n = gp_voronoi_count(v);
    double sum = 0.0;
    static gp_vec2 buf[8192];
    static size_t nb[4096], nb2[4096];
    int seed_in = 1, nb_sym = 1, orient_ok = 1, parts_ccw = 1;
    for (size_t i = 0; i < n; i++) {
        double a = gp_voronoi_cell_area(v, i);
        sum += a;
        size_t np = gp_voronoi_cell_parts(v, i), sp = gp_voronoi_cell_seed_part(v, i);
        double psum = 0.0;
        for (size_t p = 0; p < np; p++) {
            size_t m = gp_voronoi_cell_polygon(v, i, p, buf, 8192);
            double sa = gp_poly_signed_area(buf, m);
            if (!(sa > 0)) parts_ccw = 0;
            psum += sa;
            if (p == sp) {
                gp_vec2 s = gp_voronoi_seed(v, i);
                if (!gp_poly_contains(buf, m, s) && gp_poly_boundary_distance(buf, m, s) > 1e-9 * sqrt(area))
                    seed_in = 0;
                double w, ang, len;
                if (gp_min_caliper(buf, m, &w, &ang, &len, NULL) == GP_OK) {
                    double d = fabs(ang - gp_voronoi_cell_orientation(v, i));
                    if (d > M_PI / 2) d = M_PI - d;
                    if (d > 1e-7) {
                        orient_ok = 0;
                        fprintf(stderr, "cell %zu orientation %.17g vs min_caliper %.17g\n", i,
                                gp_voronoi_cell_orientation(v, i), ang);
                    }
                }
            }
        }
        if (fabs(psum - a) > 1e-9 * a) parts_ccw = 0;
        size_t k = gp_voronoi_neighbours(v, i, nb, 4096);
        for (size_t q = 0; q < k; q++) {
            size_t k2 = gp_voronoi_neighbours(v, nb[q], nb2, 4096);
            int found = 0;
            for (size_t r = 0; r < k2; r++) found |= nb2[r] == i;
            if (!found) {
                nb_sym = 0;
                fprintf(stderr, "neighbours: %zu lists %zu but not back\n", i, nb[q]);
            }
            if (q > 0 && nb[q] <= nb[q - 1]) nb_sym = 0;
        }
    }
    CHECK_REL(sum, area, 1e-9);
    CHECK_REL(gp_voronoi_container_area(v), area, 1e-12);
    CHECK(seed_in);
    CHECK(nb_sym);
    CHECK(orient_ok);
    CHECK(parts_ccw);
}

/* sample points on a grid over [x0,x1]x[y0,y1]; inside-container points must be in exactly one
 * cell, that of their nearest seed; returns per-cell counts for an area check */
static void check_points(const gp_voronoi *v, double x0, double y0, double x1, double y1, int M,
                         double tol_area)
{
    size_t n = gp_voronoi_count(v);
    double *cnt = calloc(n, sizeof(double));
    int bad = 0, total_in = 0;
    double L = fmax(x1 - x0, y1 - y0);
    for (int a = 0; a < M; a++)
        for (int b = 0; b < M; b++) {
            gp_vec2 q = {x0 + (a + 0.5) * (x1 - x0) / M, y0 + (b + 0.5) * (y1 - y0) / M};
            if (!gp_voronoi_contains(v, q)) continue;
            total_in++;
            size_t best = 0, second = 0;
            double d1 = INFINITY, d2 = INFINITY;
            for (size_t i = 0; i < n; i++) {
                double d = dist2(q, gp_voronoi_seed(v, i));
                if (d < d1) {
                    d2 = d1;
                    second = best;
                    d1 = d;
                    best = i;
                } else if (d < d2) {
                    d2 = d;
                    second = i;
                }
            }
            (void)second;
            size_t w = n;
            int c = cells_holding(v, q, &w);
            if (sqrt(d2) - sqrt(d1) < 1e-9 * L) continue; /* on a bisector: either */
            if (c != 1 || w != best) {
                if (bad < 5)
                    fprintf(stderr, "point (%g, %g): in %d cells (%zu), nearest seed %zu\n", q.x, q.y, c,
                            w, best);
                bad++;
            }
            cnt[best] += 1.0;
        }
    CHECK(bad == 0);
    CHECK(total_in > 0);
    if (tol_area > 0) {
        double cellA = (x1 - x0) * (y1 - y0) / ((double)M * M);
        int abad = 0;
        for (size_t i = 0; i < n; i++) {
            double a = gp_voronoi_cell_area(v, i), est = cnt[i] * cellA;
            if (fabs(a - est) > tol_area) {
                if (abad < 5) fprintf(stderr, "cell %zu area %g vs count %g\n", i, a, est);
                abad++;
            }
        }
        CHECK(abad == 0);
    }
    free(cnt);
}

static void test_square_bruteforce(void)
{
    enum { N = 300 };
    gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    gp_vec2 s[N];
    for (int i = 0; i < N; i++) s[i] = (gp_vec2){urand(), urand()};
    gp_error e;
    gp_voronoi *v = gp_voronoi_create(sq, 4, NULL, NULL, 0, s, N, &e);
    CHECK(v != NULL);
    if (!v) {
        fprintf(stderr, "%s\n", e.message);
        return;
    }
    CHECK(gp_voronoi_count(v) == N);
    int bad = 0;
    for (int i = 0; i < N; i++) {
        double a = bf_cell_area(sq, 4, s, N, i);
        if (fabs(a - gp_voronoi_cell_area(v, i)) > 1e-12) bad++;
    }
    CHECK(bad == 0);
    check_invariants(v, 1.0);
    check_points(v, 0, 0, 1, 1, 120, 0.0);
    gp_voronoi_destroy(v);
}

static void test_circle_bruteforce(void)
{
    enum { N = 150 };
    gp_vec2 *c;
    size_t nc;
    CHECK(gp_voronoi_circle_polygon((gp_vec2){2, -1}, 3.0, 1e-3, &c, &nc, NULL) == GP_OK);
    /* max deviation from the circle <= tol, and not much finer than needed */
    double dev = 3.0 * (1 - cos(M_PI / nc));
    CHECK(dev <= 1e-3);
    CHECK(3.0 * (1 - cos(M_PI / (nc - 1))) > 1e-3);
    double mid = hypot(0.5 * (c[0].x + c[1].x) - 2, 0.5 * (c[0].y + c[1].y) + 1);
    CHECK(3.0 - mid <= 1e-3 + 1e-12);
    free(c);
    CHECK(gp_voronoi_circle_polygon((gp_vec2){0, 0}, 1.0, 0.0, &c, &nc, NULL) == GP_ERR_INVALID);
    CHECK(gp_voronoi_circle_polygon((gp_vec2){2, -1}, 3.0, 1e-3, &c, &nc, NULL) == GP_OK);
    gp_vec2 s[N];
    for (int i = 0; i < N;) {
        gp_vec2 p = {2 + 6 * urand() - 3, -1 + 6 * urand() - 3};
        if (gp_poly_contains(c, nc, p)) s[i++] = p;
    }
    gp_voronoi *v = gp_voronoi_create(c, nc, NULL, NULL, 0, s, N, NULL);
    CHECK(v != NULL);
    if (v) {
        int bad = 0;
        for (int i = 0; i < N; i++) {
            double a = bf_cell_area(c, (int)nc, s, N, i);
            if (fabs(a - gp_voronoi_cell_area(v, i)) > 1e-11) bad++;
        }
        CHECK(bad == 0);
        check_invariants(v, gp_poly_area(c, nc));
        gp_voronoi_destroy(v);
    }
    free(c);
}

static gp_vec2 rand_in(const gp_vec2 *outer, size_t no, const gp_vec2 *hole, size_t nh, double x0,
                       double y0, double x1, double y1)
{
    for (;;) {
        gp_vec2 p = {x0 + (x1 - x0) * urand(), y0 + (y1 - y0) * urand()};
        if (!gp_poly_contains(outer, no, p)) continue;
        if (hole && gp_poly_contains(hole, nh, p)) continue;
        return p;
    }
}

static void test_lshape(void)
{
    enum { N = 60 };
    gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    gp_vec2 s[N];
    for (int i = 0; i < N; i++) s[i] = rand_in(L, 6, NULL, 0, 0, 0, 2, 2);
    gp_error e;
    gp_voronoi *v = gp_voronoi_create(L, 6, NULL, NULL, 0, s, N, &e);
    CHECK(v != NULL);
    if (!v) {
        fprintf(stderr, "L: %s\n", e.message);
        return;
    }
    check_invariants(v, 3.0);
    check_points(v, 0, 0, 2, 2, 150, 4e-3);
    gp_voronoi_destroy(v);
}

static void test_annulus(void)
{
    enum { N = 80 };
    gp_vec2 *c, *h;
    size_t nc, nh;
    gp_voronoi_circle_polygon((gp_vec2){0, 0}, 1.0, 1e-3, &c, &nc, NULL);
    gp_voronoi_circle_polygon((gp_vec2){0.1, 0}, 0.4, 1e-3, &h, &nh, NULL);
    gp_vec2 s[N];
    for (int i = 0; i < N; i++) s[i] = rand_in(c, nc, h, nh, -1, -1, 1, 1);
    const gp_vec2 *holes[1] = {h};
    gp_error e;
    gp_voronoi *v = gp_voronoi_create(c, nc, holes, &nh, 1, s, N, &e);
    CHECK(v != NULL);
    if (v) {
        check_invariants(v, gp_poly_area(c, nc) - gp_poly_area(h, nh));
        check_points(v, -1, -1, 1, 1, 150, 4e-3);
        gp_voronoi_destroy(v);
    } else
        fprintf(stderr, "annulus: %s\n", e.message);
    /* three seeds: the hole lies wholly inside one cell (keyhole) */
    gp_vec2 s3[3] = {{-0.9, 0}, {0.95, 0.1}, {0.96, -0.1}};
    double hr = 0.05;
    gp_vec2 *h2;
    size_t nh2;
    gp_voronoi_circle_polygon((gp_vec2){-0.5, 0.0}, hr, 1e-4, &h2, &nh2, NULL);
    const gp_vec2 *holes2[1] = {h2};
    v = gp_voronoi_create(c, nc, holes2, &nh2, 1, s3, 3, &e);
    CHECK(v != NULL);
    if (v) {
        check_invariants(v, gp_poly_area(c, nc) - gp_poly_area(h2, nh2));
        check_points(v, -1, -1, 1, 1, 100, 0.0);
        gp_voronoi_destroy(v);
    } else
        fprintf(stderr, "keyhole: %s\n", e.message);
    free(h2);
    free(c);
    free(h);
}

static void test_split_cells(void)
{
    /* U-shape: the seed at the bottom-left of the gap owns a piece of the right arm too */
    gp_vec2 U[8] = {{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
    gp_vec2 s[3] = {{0.5, 2.9}, {2.5, 0.5}, {0.9, 1.2}};
    /* seed 2 near the inner corner of the left arm; seed 0 high in the left arm; seed 1 low right:
     * the top of the right arm is nearer to seed 2 or 0 than to seed 1 -> split cells */
    gp_error e;
    gp_voronoi *v = gp_voronoi_create(U, 8, NULL, NULL, 0, s, 3, &e);
    CHECK(v != NULL);
    if (!v) {
        fprintf(stderr, "U: %s\n", e.message);
        return;
    }
    size_t maxparts = 0;
    for (size_t i = 0; i < 3; i++)
        if (gp_voronoi_cell_parts(v, i) > maxparts) maxparts = gp_voronoi_cell_parts(v, i);
    CHECK(maxparts >= 2);
    check_invariants(v, 7.0);
    check_points(v, 0, 0, 3, 3, 150, 1e-2);
    gp_voronoi_destroy(v);
}

static void test_robustness(void)
{
    gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    gp_error e;
    /* duplicates: a clear error naming both */
    gp_vec2 d[3] = {{0.2, 0.2}, {0.7, 0.4}, {0.2, 0.2}};
    CHECK(gp_voronoi_create(sq, 4, NULL, NULL, 0, d, 3, &e) == NULL);
    CHECK(e.code == GP_ERR_INVALID && strstr(e.message, "duplicate") != NULL);
    /* outside */
    gp_vec2 o[2] = {{0.2, 0.2}, {1.5, 0.4}};
    CHECK(gp_voronoi_create(sq, 4, NULL, NULL, 0, o, 2, &e) == NULL && e.code == GP_ERR_INVALID);
    /* collinear seeds: vertical strips of width 0.1 */
    gp_vec2 col[10];
    for (int i = 0; i < 10; i++) col[i] = (gp_vec2){0.05 + 0.1 * i, 0.5};
    gp_voronoi *v = gp_voronoi_create(sq, 4, NULL, NULL, 0, col, 10, &e);
    CHECK(v != NULL);
    if (v) {
        for (int i = 0; i < 10; i++) CHECK_NEAR(gp_voronoi_cell_area(v, i), 0.1, 1e-14);
        /* a 0.1 x 1 strip: long axis vertical */
        CHECK_NEAR(fabs(gp_voronoi_cell_orientation(v, 3)), M_PI / 2, 1e-12);
        check_invariants(v, 1.0);
        gp_voronoi_destroy(v);
    }
    /* a lattice (exactly cocircular seeds) and seeds on the boundary / corners */
    gp_vec2 lat[25 + 6];
    for (int i = 0; i < 25; i++) lat[i] = (gp_vec2){0.1 + 0.2 * (i % 5), 0.1 + 0.2 * (i / 5)};
    for (int i = 0; i < 25; i++) {
        lat[i].x = 0.25 * (i % 5);
        lat[i].y = 0.25 * (i / 5);
    }
    v = gp_voronoi_create(sq, 4, NULL, NULL, 0, lat, 25, &e);
    CHECK(v != NULL);
    if (v) {
        CHECK_NEAR(gp_voronoi_cell_area(v, 0), 0.125 * 0.125, 1e-15);
        CHECK_NEAR(gp_voronoi_cell_area(v, 6), 0.25 * 0.25, 1e-15);
        size_t nb[16];
        CHECK(gp_voronoi_neighbours(v, 6, nb, 16) == 4);
        check_invariants(v, 1.0);
        gp_voronoi_destroy(v);
    } else
        fprintf(stderr, "lattice: %s\n", e.message);
    /* scales: the unit-square tessellation scaled by 1e-6 and 1e6 (and shifted) */
    enum { N = 100 };
    gp_vec2 s[N], ss[N], sq2[4];
    for (int i = 0; i < N; i++) s[i] = (gp_vec2){urand(), urand()};
    v = gp_voronoi_create(sq, 4, NULL, NULL, 0, s, N, NULL);
    const double scales[3] = {1e-6, 1e6, 1e6};
    const double shifts[3] = {0, 0, 3e6};
    for (int t = 0; t < 3; t++) {
        double k = scales[t];
        for (int i = 0; i < 4; i++) sq2[i] = (gp_vec2){sq[i].x * k + shifts[t], sq[i].y * k};
        for (int i = 0; i < N; i++) ss[i] = (gp_vec2){s[i].x * k + shifts[t], s[i].y * k};
        gp_voronoi *w = gp_voronoi_create(sq2, 4, NULL, NULL, 0, ss, N, &e);
        CHECK(w != NULL);
        if (!w) continue;
        int bad = 0;
        for (int i = 0; i < N; i++) {
            if (fabs(gp_voronoi_cell_area(w, i) / (k * k) - gp_voronoi_cell_area(v, i)) > 1e-9) bad++;
            double da = fabs(gp_voronoi_cell_orientation(w, i) - gp_voronoi_cell_orientation(v, i));
            if (da > 1e-6 && fabs(da - M_PI) > 1e-6) bad++;
        }
        CHECK(bad == 0);
        check_invariants(w, k * k);
        gp_voronoi_destroy(w);
    }
    gp_voronoi_destroy(v);
    /* a 1000:1 strip */
    gp_vec2 st[4] = {{0, 0}, {1000, 0}, {1000, 1}, {0, 1}};
    gp_vec2 sst[N];
    for (int i = 0; i < N; i++) sst[i] = (gp_vec2){1000 * urand(), urand()};
    sst[0] = (gp_vec2){0, 0};   /* a corner */
    sst[1] = (gp_vec2){500, 1}; /* on an edge */
    v = gp_voronoi_create(st, 4, NULL, NULL, 0, sst, N, &e);
    CHECK(v != NULL);
    if (v) {
        int bad = 0;
        for (int i = 0; i < N; i++)
            if (fabs(bf_cell_area(st, 4, sst, N, i) - gp_voronoi_cell_area(v, i)) > 1e-9) bad++;
        CHECK(bad == 0);
        check_invariants(v, 1000.0);
        gp_voronoi_destroy(v);
    }
    /* single seed: the whole container */
    gp_vec2 one = {0.3, 0.3};
    gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    v = gp_voronoi_create(L, 6, NULL, NULL, 0, &one, 1, &e);
    CHECK(v != NULL);
    if (v) {
        CHECK_REL(gp_voronoi_cell_area(v, 0), 3.0, 1e-14);
        CHECK(gp_voronoi_cell_parts(v, 0) == 1);
        gp_voronoi_destroy(v);
    }
    /* bad containers */
    gp_vec2 line[3] = {{0, 0}, {1, 1}, {2, 2}};
    CHECK(gp_voronoi_create(line, 3, NULL, NULL, 0, &one, 1, &e) == NULL && e.code == GP_ERR_INVALID);
}

/* moves against full recomputation */
static void compare_full(const gp_voronoi *v, const gp_vec2 *outer, size_t no, const gp_vec2 *const *holes,
                         const size_t *nh, size_t nholes, int *bad)
{
    size_t n = gp_voronoi_count(v);
    gp_vec2 *s = malloc(n * sizeof *s);
    for (size_t i = 0; i < n; i++) s[i] = gp_voronoi_seed(v, i);
    gp_voronoi *f = gp_voronoi_create(outer, no, holes, nh, nholes, s, n, NULL);
    if (!f) {
        (*bad)++;
        free(s);
        return;
    }
    static size_t a[1024], b[1024];
    for (size_t i = 0; i < n; i++) {
        double x = gp_voronoi_cell_area(v, i), y = gp_voronoi_cell_area(f, i);
        int b0 = *bad;
        if (fabs(x - y) > 1e-12 * y) (*bad)++;
        if (memcmp(&x, &y, sizeof x) != 0) (*bad)++; /* bit for bit, in fact */
        size_t ka = gp_voronoi_neighbours(v, i, a, 1024), kb = gp_voronoi_neighbours(f, i, b, 1024);
        if (ka != kb || memcmp(a, b, ka * sizeof(size_t)) != 0) (*bad)++;
        double oa = gp_voronoi_cell_orientation(v, i), ob = gp_voronoi_cell_orientation(f, i);
        if (memcmp(&oa, &ob, sizeof oa) != 0) (*bad)++;
        if (gp_voronoi_cell_parts(v, i) != gp_voronoi_cell_parts(f, i)) (*bad)++;
        if (*bad > b0 && *bad < 6)
            fprintf(stderr, "cell %zu: area %.17g vs %.17g, nb %zu vs %zu, orient %.17g vs %.17g\n", i, x, y,
                    ka, kb, oa, ob);
    }
    gp_voronoi_destroy(f);
    free(s);
}

/* Replica w against v: every cell's area, orientation, parts, neighbours and polygon bit for
 * bit (gp_voronoi_apply copies what v computed; w must equal it exactly). */
static void compare_replica(const gp_voronoi *v, const gp_voronoi *w, int *bad)
{
    static size_t a[1024], b[1024];
    static gp_vec2 pa[4096], pb[4096];
    for (size_t i = 0; i < gp_voronoi_count(v); i++) {
        double x = gp_voronoi_cell_area(v, i), y = gp_voronoi_cell_area(w, i);
        double oa = gp_voronoi_cell_orientation(v, i), ob = gp_voronoi_cell_orientation(w, i);
        gp_vec2 sa = gp_voronoi_seed(v, i), sb = gp_voronoi_seed(w, i);
        size_t ka = gp_voronoi_neighbours(v, i, a, 1024), kb = gp_voronoi_neighbours(w, i, b, 1024);
        size_t np = gp_voronoi_cell_parts(v, i);
        int ok = !memcmp(&x, &y, sizeof x) && !memcmp(&oa, &ob, sizeof oa) && !memcmp(&sa, &sb, sizeof sa) &&
                 ka == kb && !memcmp(a, b, ka * sizeof *a) && np == gp_voronoi_cell_parts(w, i);
        for (size_t k = 0; ok && k < np; k++) {
            size_t ma = gp_voronoi_cell_polygon(v, i, k, pa, 4096), mb = gp_voronoi_cell_polygon(w, i, k, pb, 4096);
            ok = ma == mb && ma <= 4096 && !memcmp(pa, pb, ma * sizeof *pa);
        }
        if (!ok && (*bad)++ < 3) fprintf(stderr, "replica: cell %zu differs\n", i);
    }
}

static double u01cb(void *st)
{
    (void)st;
    return urand();
}

static void property_moves(const char *name, const gp_vec2 *outer, size_t no, const gp_vec2 *const *holes,
                           const size_t *nh, size_t nholes, int N, int moves, int full_every)
{
    gp_vec2 *s = malloc((size_t)N * sizeof *s);
    gp_vec2 lo, hi;
    gp_poly_bbox(outer, no, &lo, &hi, NULL);
    double x0 = lo.x, y0 = lo.y, x1 = hi.x, y1 = hi.y;
    for (int i = 0; i < N; i++) s[i] = rand_in(outer, no, nholes ? holes[0] : NULL, nholes ? nh[0] : 0, x0, y0, x1, y1);
    gp_error e;
    gp_voronoi *v = gp_voronoi_create(outer, no, holes, nh, nholes, s, (size_t)N, &e);
    CHECK(v != NULL);
    if (!v) {
        fprintf(stderr, "%s: %s\n", name, e.message);
        free(s);
        return;
    }
    /* a replica given every kept move: by gp_voronoi_apply after try_move, or by a move of its
     * own after gp_voronoi_move */
    gp_voronoi *w = gp_voronoi_create(outer, no, holes, nh, nholes, s, (size_t)N, &e);
    CHECK(w != NULL);
    CHECK(gp_voronoi_apply(w, v, NULL) == GP_ERR_INVALID); /* nothing pending in v */
    int bad = 0, moved = 0, rolled = 0, errs = 0, applied = 0;
    double area = gp_voronoi_container_area(v);
    for (int t = 0; t < moves; t++) {
        size_t i = (size_t)(urand() * N);
        gp_vec2 p;
        double r = urand();
        if (r < 0.3) {
            /* near the boundary: a point of a random container edge, nudged */
            size_t k = (size_t)(urand() * no);
            gp_vec2 a = outer[k], b = outer[(k + 1) % no];
            double u = urand();
            p = (gp_vec2){a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)};
            if (urand() < 0.5) {
                double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1), f = 1e-3 * urand();
                p.x += f * (cx - p.x);
                p.y += f * (cy - p.y);
            }
        } else if (r < 0.6) {
            gp_voronoi_sample_cell(v, (size_t)(urand() * N), u01cb, NULL, &p);
        } else {
            p = (gp_vec2){x0 + (x1 - x0) * urand(), y0 + (y1 - y0) * urand()};
        }
        if (!gp_voronoi_contains(v, p)) continue;
        gp_status st;
        if (urand() < 0.5) {
            st = gp_voronoi_try_move(v, i, p, &e);
            if (st == GP_OK) {
                const uint32_t *ch;
                size_t nch = gp_voronoi_changed(v, &ch);
                if (nch < 1 || ch[0] != i) bad++;
                if (urand() < 0.5) {
                    gp_voronoi_rollback(v);
                    rolled++;
                } else {
                    if (gp_voronoi_apply(w, v, &e) != GP_OK) bad++;
                    applied++;
                    gp_voronoi_commit(v);
                }
            }
        } else {
            st = gp_voronoi_move(v, i, p, &e);
            if (st == GP_OK && gp_voronoi_move(w, i, p, NULL) != GP_OK) bad++;
        }
        if (st != GP_OK) {
            errs++;
            if (errs < 5) fprintf(stderr, "%s move: %s\n", name, e.message);
            continue;
        }
        moved++;
        if (full_every > 0 && (t % full_every == 0)) compare_full(v, outer, no, holes, nh, nholes, &bad);
        else {
            double sum = 0;
            for (int j = 0; j < N; j++) sum += gp_voronoi_cell_area(v, j);
            if (fabs(sum - area) > 1e-9 * area) bad++;
        }
    }
    compare_full(v, outer, no, holes, nh, nholes, &bad);
    if (w) compare_replica(v, w, &bad);
    /* a move pending in dst is refused (seed 0 moved onto its own place: a valid move) */
    gp_vec2 q0 = gp_voronoi_seed(v, 0);
    int both = w && gp_voronoi_try_move(w, 0, q0, NULL) == GP_OK;
    both = both && gp_voronoi_try_move(v, 0, q0, NULL) == GP_OK;
    CHECK(both);
    if (both) CHECK(gp_voronoi_apply(w, v, NULL) == GP_ERR_INVALID);
    gp_voronoi_rollback(v);
    gp_voronoi_rollback(w);
    printf("%s: %d moves (%d rolled back, %d applied to a replica), %d refused\n", name, moved, rolled,
           applied, errs);
    CHECK(applied > moves / 10);
    CHECK(bad == 0);
    CHECK(errs == 0);
    CHECK(moved > moves / 2);
    gp_voronoi_destroy(v);
    gp_voronoi_destroy(w);
    free(s);
}

/* Two moves evaluated side by side on two replicas (gp_imc.c's lanes): when A's changed cells
 * are outside B's footprint, B goes on top of A as it was computed -- A applied underneath B's
 * pending move, then B committed and copied back -- and the result is the tessellation a
 * fresh build of the final seeds gives, bit for bit; B rolled back instead leaves A alone. */
static void moves_side_by_side(const char *name, const gp_vec2 *outer, size_t no, const gp_vec2 *const *holes,
                               const size_t *nh, size_t nholes, int N, int trials)
{
    gp_vec2 *s = malloc((size_t)N * sizeof *s);
    gp_vec2 lo, hi;
    gp_poly_bbox(outer, no, &lo, &hi, NULL);
    for (int i = 0; i < N; i++)
        s[i] = rand_in(outer, no, nholes ? holes[0] : NULL, nholes ? nh[0] : 0, lo.x, lo.y, hi.x, hi.y);
    gp_voronoi *v = gp_voronoi_create(outer, no, holes, nh, nholes, s, (size_t)N, NULL);
    gp_voronoi *w = gp_voronoi_create(outer, no, holes, nh, nholes, s, (size_t)N, NULL);
    CHECK(v && w);
    static uint32_t fp[4096];
    int bad = 0, kept = 0, dropped = 0, clashes = 0;
    for (int t = 0; v && w && t < trials; t++) {
        size_t i = (size_t)(urand() * N), j = (size_t)(urand() * N);
        gp_vec2 p = {lo.x + (hi.x - lo.x) * urand(), lo.y + (hi.y - lo.y) * urand()};
        gp_vec2 q = {lo.x + (hi.x - lo.x) * urand(), lo.y + (hi.y - lo.y) * urand()};
        if (!gp_voronoi_contains(v, p) || !gp_voronoi_contains(v, q)) continue;
        int a = gp_voronoi_try_move(v, i, p, NULL) == GP_OK, b = a && gp_voronoi_try_move(w, j, q, NULL) == GP_OK;
        if (!b) {
            gp_voronoi_rollback(v);
            continue;
        }
        const uint32_t *ch;
        size_t nch = gp_voronoi_changed(v, &ch), nfp = gp_voronoi_footprint(w, fp, 4096);
        int clear = nfp <= 4096;
        for (size_t k = 0; clear && k < nfp; k++)
            for (size_t m = 0; clear && m < nch; m++) clear = fp[k] != ch[m];
        if (!clear) {
            clashes++;
            gp_voronoi_rollback(v);
            gp_voronoi_rollback(w);
            continue;
        }
        if (gp_voronoi_apply(w, v, NULL) != GP_OK) bad++;
        gp_voronoi_commit(v);
        if (urand() < 0.5) {
            if (gp_voronoi_apply(v, w, NULL) != GP_OK) bad++;
            gp_voronoi_commit(w);
            kept++;
        } else {
            gp_voronoi_rollback(w);
            dropped++;
        }
        if (t % 50 == 0) compare_full(v, outer, no, holes, nh, nholes, &bad);
    }
    if (v && w) {
        compare_full(v, outer, no, holes, nh, nholes, &bad);
        compare_replica(v, w, &bad);
    }
    printf("%s: %d second moves kept on top of the first, %d dropped, %d clashed\n", name, kept, dropped, clashes);
    CHECK(bad == 0);
    CHECK(kept > trials / 20 && clashes > 0);
    gp_voronoi_destroy(v);
    gp_voronoi_destroy(w);
    free(s);
}

/* gp_voronoi_create_ex: a raised cancel flag stops a large tessellation (GP_ERR_CANCELLED, NULL),
 * a lowered one changes nothing (the same cells, bit for bit, as gp_voronoi_create); a small
 * one (under the polling interval) is never cut short. */
static void test_cancel(void)
{
    gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    size_t n = 20000;
    gp_vec2 *s = malloc(n * sizeof *s);
    for (size_t i = 0; i < n; i++) s[i] = (gp_vec2){urand(), urand()};
    volatile int up = 1, down = 0;
    gp_error e;
    gp_error_clear(&e);
    gp_voronoi *v = gp_voronoi_create_ex(sq, 4, NULL, NULL, 0, s, n, &up, &e);
    CHECK(v == NULL && e.code == GP_ERR_CANCELLED);
    gp_voronoi *a = gp_voronoi_create_ex(sq, 4, NULL, NULL, 0, s, n, &down, NULL);
    gp_voronoi *b = gp_voronoi_create(sq, 4, NULL, NULL, 0, s, n, NULL);
    CHECK(a && b);
    int same = a && b;
    for (size_t i = 0; same && i < n; i++) {
        double x = gp_voronoi_cell_area(a, i), y = gp_voronoi_cell_area(b, i);
        double p = gp_voronoi_cell_orientation(a, i), q = gp_voronoi_cell_orientation(b, i);
        same = !memcmp(&x, &y, sizeof x) && !memcmp(&p, &q, sizeof p);
    }
    CHECK(same);
    gp_voronoi_destroy(a);
    gp_voronoi_destroy(b);
    v = gp_voronoi_create_ex(sq, 4, NULL, NULL, 0, s, 100, &up, NULL);
    CHECK(v != NULL);
    gp_voronoi_destroy(v);
    free(s);
}

/* A sliver (issue 14: [[0,0],[1,1],[1,1.00000002]], area 1e-8 of its bounding box): its width,
 * ~1.4e-8, is far above the tolerance (1e-12 of the box), so it tessellates like any triangle;
 * what made such a job slow was placing seeds by rejection in the bounding box (10^8 draws a
 * seed, gp_imc.c), which looks at the cancel flag. */
static void test_sliver(void)
{
    gp_vec2 t[3] = {{0, 0}, {1, 1}, {1, 1.00000002}};
    gp_vec2 s[10];
    for (int i = 0; i < 10; i++) { /* inside, along the sliver */
        double u = 0.05 + 0.09 * i, w = 0.25 + 0.05 * i;
        s[i] = (gp_vec2){u, u + w * 2e-8 * u};
    }
    gp_error e;
    gp_error_clear(&e);
    gp_voronoi *v = gp_voronoi_create(t, 3, NULL, NULL, 0, s, 10, &e);
    CHECK(v != NULL);
    if (!v) {
        fprintf(stderr, "sliver: %s\n", e.message);
        return;
    }
    double sum = 0.0;
    for (size_t i = 0; i < 10; i++) sum += gp_voronoi_cell_area(v, i);
    CHECK_REL(sum, 1e-8, 1e-6);
    CHECK_REL(gp_voronoi_container_area(v), 1e-8, 1e-6);
    gp_voronoi_destroy(v);
}

int main(void)
{
    test_square_bruteforce();
    test_circle_bruteforce();
    test_lshape();
    test_annulus();
    test_split_cells();
    test_robustness();
    gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    property_moves("square N=200", sq, 4, NULL, NULL, 0, 200, 10000, 5);
    property_moves("L-shape N=200", L, 6, NULL, NULL, 0, 200, 10000, 5);
    gp_vec2 *c, *h;
    size_t nc, nh;
    gp_voronoi_circle_polygon((gp_vec2){0, 0}, 1.0, 1e-3, &c, &nc, NULL);
    gp_voronoi_circle_polygon((gp_vec2){0, 0}, 0.35, 1e-3, &h, &nh, NULL);
    const gp_vec2 *holes[1] = {h};
    property_moves("annulus N=150", c, nc, holes, &nh, 1, 150, 10000, 25);
    /* more cells: the moved seed's search walks far on the neighbour graph (jumps anywhere) */
    property_moves("square N=3000", sq, 4, NULL, NULL, 0, 3000, 10000, 2500);
    moves_side_by_side("side by side, square N=400", sq, 4, NULL, NULL, 0, 400, 2000);
    moves_side_by_side("side by side, L-shape N=300", L, 6, NULL, NULL, 0, 300, 2000);
    moves_side_by_side("side by side, annulus N=300", c, nc, holes, &nh, 1, 300, 2000);
    free(c);
    free(h);
    test_cancel(); /* last: it draws from urand() */
    test_sliver();
    return gp_test_summary();
}
