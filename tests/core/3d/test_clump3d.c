/* test_clump3d.c -- clumps of overlapping spheres inside 3D grains (gp_clump3d), each against a
 * truth of the test's own:
 *  - the union quadrature against exact values: one ball, two overlapping balls (the lens
 *    formula), a repeated ball and a ball inside another (counted once), three balls against
 *    Monte-Carlo;
 *  - a sphere mesh (an icosphere the test builds) gives one sphere of its radius within the
 *    mesh's chordal error, and volume_error of the size of the mesh's own deficit;
 *  - an ellipsoid (1, 0.6, 0.4): every sphere inside (the test's own point-triangle distances,
 *    brute force, and its own ray test for the centre), volume_error rising towards 0 for
 *    spheres_max = 1, 5, 20, 50 (and inertia_error falling), the clumps prefixes of each other,
 *    the radius ratio kept, the union volume, centroid and inertia against Monte-Carlo (3 sigma);
 *  - a non-convex star grain r = 1 + 0.3 P3(cos theta) + 0.2 sin^3(theta) cos(3 phi), the same,
 *    and the same grain sheared;
 *  - a torus (not star-shaped): every sphere inside (a parity ray test), none across the hole;
 *  - a grain turned, moved far from the origin and scaled: the same clump, turned, moved and
 *    scaled; a needle along a diagonal keeps its resolution (the grid lies in its own frame);
 *  - bad parameters and meshes refused (GP_ERR_INVALID naming the argument), flat meshes
 *    refused (GP_ERR_DEGENERATE), the result zeroed on error;
 *  - determinism: the same input twice gives the same bytes.
 * The grain's volume, centroid and inertia come from the test's own divergence-theorem integral
 * (checked against the analytic ellipsoid, within the mesh's discretisation). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_clump3d.h"
#include "gp_test.h"

#define PI 3.14159265358979323846

/* ------------------------------------------------------------------------------------------ */
/* meshes                                                                                      */

typedef struct mesh {
    double *v;
    uint32_t *t;
    size_t nv, nt;
} mesh;

static void mesh_free(mesh *m)
{
    free(m->v);
    free(m->t);
    memset(m, 0, sizeof *m);
}

typedef struct emap {
    uint64_t *key;
    uint32_t *val;
    size_t cap;
} emap;

static uint32_t midpoint(emap *e, mesh *m, uint32_t a, uint32_t b)
{
    uint64_t k = a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a);
    size_t h = (size_t)((k * 0x9E3779B97F4A7C15ull) >> 20) % e->cap;
    while (e->key[h] != UINT64_MAX) {
        if (e->key[h] == k) return e->val[h];
        h = (h + 1) % e->cap;
    }
    double *p = m->v + 3 * m->nv, *pa = m->v + 3 * a, *pb = m->v + 3 * b;
    double x = pa[0] + pb[0], y = pa[1] + pb[1], z = pa[2] + pb[2], n = sqrt(x * x + y * y + z * z);
    p[0] = x / n, p[1] = y / n, p[2] = z / n;
    e->key[h] = k;
    e->val[h] = (uint32_t)m->nv;
    return (uint32_t)m->nv++;
}

/* The unit icosphere: the icosahedron subdivided `level` times (level 4: 2,562 vertices,
 * 5,120 triangles), counter-clockwise seen from outside. */
static mesh icosphere(int level)
{
    mesh m = {0};
    size_t nt = 20, nv = 12;
    for (int l = 0; l < level; l++) nv += 3 * nt / 2, nt *= 4;
    m.v = malloc(3 * nv * sizeof(double));
    m.t = malloc(3 * nt * sizeof(uint32_t));
    double g = (1 + sqrt(5.0)) / 2;
    double iv[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                        {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    uint32_t it[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                          {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                          {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                          {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (int i = 0; i < 12; i++) {
        double n = sqrt(iv[i][0] * iv[i][0] + iv[i][1] * iv[i][1] + iv[i][2] * iv[i][2]);
        for (int k = 0; k < 3; k++) m.v[3 * i + k] = iv[i][k] / n;
    }
    memcpy(m.t, it, sizeof it);
    m.nv = 12;
    m.nt = 20;
    uint32_t *t2 = malloc(3 * nt * sizeof(uint32_t));
    for (int l = 0; l < level; l++) {
        emap e;
        e.cap = 6 * m.nt + 1;
        e.key = malloc(e.cap * sizeof *e.key);
        e.val = malloc(e.cap * sizeof *e.val);
        for (size_t i = 0; i < e.cap; i++) e.key[i] = UINT64_MAX;
        size_t n2 = 0;
        for (size_t f = 0; f < m.nt; f++) {
            uint32_t a = m.t[3 * f], b = m.t[3 * f + 1], c = m.t[3 * f + 2];
            uint32_t ab = midpoint(&e, &m, a, b), bc = midpoint(&e, &m, b, c),
                     ca = midpoint(&e, &m, c, a);
            uint32_t q[4][3] = {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}};
            memcpy(t2 + 3 * n2, q, sizeof q);
            n2 += 4;
        }
        memcpy(m.t, t2, 3 * n2 * sizeof(uint32_t));
        m.nt = n2;
        free(e.key);
        free(e.val);
    }
    free(t2);
    return m;
}

/* A star grain: vertex i moved to centre + A (radius(u_i) u_i) for the unit icosphere's u_i. */
static mesh star_grain(int level, double (*radius)(const double u[3]), const double A[9],
                       const double centre[3])
{
    mesh m = icosphere(level);
    for (size_t i = 0; i < m.nv; i++) {
        double *p = m.v + 3 * i, r = radius ? radius(p) : 1, q[3];
        for (int k = 0; k < 3; k++)
            q[k] = A[3 * k] * p[0] * r + A[3 * k + 1] * p[1] * r + A[3 * k + 2] * p[2] * r;
        for (int k = 0; k < 3; k++) p[k] = centre[k] + q[k];
    }
    return m;
}

/* r = 1 + 0.3 P3(cos theta) + 0.2 sin^3(theta) cos(3 phi): non-convex, r >= 0.7 */
static double bumpy(const double u[3])
{
    double c = u[2], p3 = 0.5 * (5 * c * c * c - 3 * c);
    /* sin^3(theta) cos(3 phi) = x^3 - 3 x y^2 on the unit sphere */
    double c3 = u[0] * u[0] * u[0] - 3 * u[0] * u[1] * u[1];
    return 1 + 0.3 * p3 + 0.2 * c3;
}

/* ------------------------------------------------------------------------------------------ */
/* the test's own geometry                                                                     */

static void sub3(const double *a, const double *b, double *o)
{
    o[0] = a[0] - b[0], o[1] = a[1] - b[1], o[2] = a[2] - b[2];
}
static double dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void cross(const double *a, const double *b, double *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static double seg_dist(const double *p, const double *a, const double *b)
{
    double d[3], ap[3];
    sub3(b, a, d);
    sub3(p, a, ap);
    double s = dot(ap, d) / dot(d, d);
    if (s < 0) s = 0;
    if (s > 1) s = 1;
    double e[3] = {ap[0] - s * d[0], ap[1] - s * d[1], ap[2] - s * d[2]};
    return sqrt(dot(e, e));
}

/* distance from p to triangle abc: the plane when p projects inside, else the nearest edge */
static double tri_dist(const double *p, const double *a, const double *b, const double *c)
{
    double ab[3], ac[3], n[3], ap[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    cross(ab, ac, n);
    double nn = sqrt(dot(n, n));
    sub3(p, a, ap);
    double h = dot(ap, n) / nn;
    double x[3] = {p[0] - h * n[0] / nn, p[1] - h * n[1] / nn, p[2] - h * n[2] / nn};
    const double *V[3] = {a, b, c};
    int in = 1;
    for (int e = 0; e < 3; e++) {
        double u[3], w[3], cr[3];
        sub3(V[(e + 1) % 3], V[e], u);
        sub3(x, V[e], w);
        cross(u, w, cr);
        if (dot(cr, n) < 0) in = 0;
    }
    if (in) return fabs(h);
    return fmin(seg_dist(p, a, b), fmin(seg_dist(p, b, c), seg_dist(p, c, a)));
}

static double mesh_dist(const mesh *m, const double *p)
{
    double best = INFINITY;
    for (size_t f = 0; f < m->nt; f++) {
        const uint32_t *t = m->t + 3 * f;
        double d = tri_dist(p, m->v + 3 * t[0], m->v + 3 * t[1], m->v + 3 * t[2]);
        if (d < best) best = d;
    }
    return best;
}

/* 1 if p is inside a mesh star-shaped about o: nearer to o than the surface along the ray
 * (Moller-Trumbore against every triangle; the farthest hit). */
static int star_inside(const mesh *m, const double *o, const double *p)
{
    double d[3];
    sub3(p, o, d);
    double L = sqrt(dot(d, d)), far = -1;
    if (L == 0) return 1;
    for (int k = 0; k < 3; k++) d[k] /= L;
    for (size_t f = 0; f < m->nt; f++) {
        const double *a = m->v + 3 * m->t[3 * f], *b = m->v + 3 * m->t[3 * f + 1],
                     *c = m->v + 3 * m->t[3 * f + 2];
        double e1[3], e2[3], pv[3], tv[3], qv[3];
        sub3(b, a, e1);
        sub3(c, a, e2);
        cross(d, e2, pv);
        double det = dot(e1, pv);
        if (fabs(det) < 1e-300) continue;
        sub3(o, a, tv);
        double u = dot(tv, pv) / det;
        if (u < -1e-12 || u > 1 + 1e-12) continue;
        cross(tv, e1, qv);
        double v = dot(d, qv) / det;
        if (v < -1e-12 || u + v > 1 + 1e-12) continue;
        double t = dot(e2, qv) / det;
        if (t > far) far = t;
    }
    return far > 0 && L < far;
}

/* The test's own mass properties: signed tetrahedra from the origin; the inertia tensor from
 * the covariance of each tetrahedron (Tonon 2004). */
static gp_clump3d_body own_body(const mesh *m)
{
    double V = 0, s[3] = {0, 0, 0}, C[3][3] = {{0}};
    for (size_t f = 0; f < m->nt; f++) {
        const double *a = m->v + 3 * m->t[3 * f], *b = m->v + 3 * m->t[3 * f + 1],
                     *c = m->v + 3 * m->t[3 * f + 2];
        double bc[3];
        cross(b, c, bc);
        double v = dot(a, bc) / 6;
        V += v;
        for (int k = 0; k < 3; k++) s[k] += v * (a[k] + b[k] + c[k]) / 4;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                C[i][j] += v / 20 *
                           (2 * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j]) + a[i] * b[j] +
                            a[j] * b[i] + a[i] * c[j] + a[j] * c[i] + b[i] * c[j] + b[j] * c[i]);
    }
    gp_clump3d_body g;
    memset(&g, 0, sizeof g);
    g.volume = V;
    for (int k = 0; k < 3; k++) g.centroid[k] = s[k] / V;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) C[i][j] -= V * g.centroid[i] * g.centroid[j];
    double tr = C[0][0] + C[1][1] + C[2][2];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) g.inertia[3 * i + j] = (i == j ? tr : 0) - C[i][j];
    return g;
}

/* ------------------------------------------------------------------------------------------ */
/* Monte-Carlo of a union of balls                                                             */

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double u01(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct mc {
    double V, sV;         /* volume and its standard error */
    double c[3], sc[3];   /* centroid and standard errors */
    double I[9], sI[9];   /* inertia about the reported centroid (given), standard errors */
} mc;

/* n samples in the union's box; inertia about `about` */
static mc monte_carlo(const gp_clump3d_sphere *s, size_t ns, size_t n, const double about[3])
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < ns; i++) {
        double c[3] = {s[i].x, s[i].y, s[i].z};
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], c[k] - s[i].r);
            hi[k] = fmax(hi[k], c[k] + s[i].r);
        }
    }
    double box = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    double m1[3] = {0}, m1sq[3] = {0}, f[9] = {0}, fsq[9] = {0};
    size_t hit = 0;
    for (size_t q = 0; q < n; q++) {
        double p[3];
        for (int k = 0; k < 3; k++) p[k] = lo[k] + (hi[k] - lo[k]) * u01();
        int in = 0;
        for (size_t i = 0; i < ns && !in; i++) {
            double dx = p[0] - s[i].x, dy = p[1] - s[i].y, dz = p[2] - s[i].z;
            in = dx * dx + dy * dy + dz * dz <= s[i].r * s[i].r;
        }
        if (!in) continue;
        hit++;
        double r[3] = {p[0] - about[0], p[1] - about[1], p[2] - about[2]}, r2 = dot(r, r);
        for (int k = 0; k < 3; k++) m1[k] += p[k], m1sq[k] += p[k] * p[k];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double v = (i == j ? r2 : 0) - r[i] * r[j];
                f[3 * i + j] += v;
                fsq[3 * i + j] += v * v;
            }
    }
    mc out;
    double p = (double)hit / (double)n;
    out.V = box * p;
    out.sV = box * sqrt(p * (1 - p) / (double)n);
    for (int k = 0; k < 3; k++) {
        double mean = m1[k] / (double)hit, var = m1sq[k] / (double)hit - mean * mean;
        out.c[k] = mean;
        out.sc[k] = sqrt(fmax(var, 0) / (double)hit);
    }
    /* I_ij = box E[1_in v_ij]: per-sample values box 1_in v */
    for (int q = 0; q < 9; q++) {
        double mean = f[q] / (double)n, m2 = fsq[q] / (double)n;
        out.I[q] = box * mean;
        out.sI[q] = box * sqrt(fmax(m2 - mean * mean, 0) / (double)n);
    }
    return out;
}

/* ------------------------------------------------------------------------------------------ */
/* checks shared by the grains                                                                 */

/* Every sphere inside (the test's own distances and ray test), radii as promised. Returns
 * the largest (r - distance) / r (<= 0 when inside). */
static double check_inside(const mesh *m, const double *o, const gp_clump3d_result *r,
                           double ratio)
{
    double worst = -INFINITY;
    int all_in = 1;
    for (size_t i = 0; i < r->nspheres; i++) {
        const gp_clump3d_sphere *s = &r->spheres[i];
        double c[3] = {s->x, s->y, s->z};
        double d = mesh_dist(m, c);
        worst = fmax(worst, (s->r - d) / s->r);
        all_in &= star_inside(m, o, c);
        CHECK(s->r <= r->spheres[0].r);
        CHECK(s->r >= ratio * r->spheres[0].r);
        CHECK(s->r > 0);
    }
    CHECK(all_in);
    CHECK(worst <= 1e-13);
    CHECK(r->r_max == r->spheres[0].r);
    return worst;
}

static void check_mc(const gp_clump3d_result *r, size_t n, const char *what)
{
    mc e = monte_carlo(r->spheres, r->nspheres, n, r->clump.centroid);
    double zv = (r->clump.volume - e.V) / e.sV;
    printf("  %s: union volume %.6f, Monte-Carlo %.6f +- %.6f (%.2f sigma)\n", what,
           r->clump.volume, e.V, e.sV, zv);
    CHECK(fabs(zv) <= 3);
    for (int k = 0; k < 3; k++) CHECK(fabs(r->clump.centroid[k] - e.c[k]) <= 3 * e.sc[k] + 1e-12);
    double zmax = 0;
    for (int q = 0; q < 9; q++) {
        double z = fabs(r->clump.inertia[q] - e.I[q]) / (e.sI[q] + 1e-15);
        if (q == 0 || q == 4 || q == 8 || fabs(e.I[q]) > 5 * e.sI[q]) zmax = fmax(zmax, z);
        CHECK(fabs(r->clump.inertia[q] - e.I[q]) <= 3.5 * e.sI[q] + 1e-12);
    }
    printf("  %s: inertia against Monte-Carlo, worst %.2f sigma\n", what, zmax);
}

/* ------------------------------------------------------------------------------------------ */
/* the tests                                                                                   */

/* Two balls on the axis ax (unit) from c1, radii r1, r2, centres d apart: the union's section
 * across the axis at s is the larger of two centred discs, R^2(s) = max of two quadratics, so
 * volume and moments are integrals of piecewise polynomials (degree <= 4), exact with 5-point
 * Gauss-Legendre between the breakpoints. */
static gp_clump3d_body two_balls(const double c1[3], const double ax[3], double r1, double r2,
                                 double d)
{
    double bp[5] = {-r1, r1, d - r2, d + r2, (d * d + r1 * r1 - r2 * r2) / (2 * d)};
    for (int i = 1; i < 5; i++)
        for (int j = i; j > 0 && bp[j - 1] > bp[j]; j--) {
            double x = bp[j];
            bp[j] = bp[j - 1];
            bp[j - 1] = x;
        }
    static const double gx[5] = {-0.9061798459386640, -0.5384693101056831, 0,
                                 0.5384693101056831, 0.9061798459386640};
    static const double gw[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                                 0.4786286704993665, 0.2369268850561891};
    double V = 0, M1 = 0, A = 0, P = 0;
    for (int i = 0; i + 1 < 5; i++) {
        double a = bp[i], c = bp[i + 1];
        if (!(c > a)) continue;
        double mid = 0.5 * (a + c);
        double q1 = r1 * r1 - mid * mid, q2 = r2 * r2 - (mid - d) * (mid - d);
        int which = q1 >= q2 ? 1 : 2;
        if ((which == 1 ? q1 : q2) <= 0) continue;
        for (int g = 0; g < 5; g++) {
            double x = mid + 0.5 * (c - a) * gx[g], w = 0.5 * (c - a) * gw[g];
            double R2 = which == 1 ? r1 * r1 - x * x : r2 * r2 - (x - d) * (x - d);
            V += w * PI * R2;
            M1 += w * PI * R2 * x;
            A += w * PI * R2 * x * x;
            P += w * PI * R2 * R2 / 4;
        }
    }
    gp_clump3d_body b;
    memset(&b, 0, sizeof b);
    double g = M1 / V, Aa = A - V * g * g; /* axial second moment about the centroid */
    b.volume = V;
    for (int k = 0; k < 3; k++) b.centroid[k] = c1[k] + g * ax[k];
    /* covariance C = Aa e e^T + P (Id - e e^T); inertia = tr(C) Id - C */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double C = Aa * ax[i] * ax[j] + P * ((i == j) - ax[i] * ax[j]);
            b.inertia[3 * i + j] = (i == j ? Aa + 2 * P : 0) - C;
        }
    return b;
}

static void test_union(void)
{
    gp_clump3d_body b;
    gp_error err;
    /* one ball */
    gp_clump3d_sphere one = {0.3, -0.2, 5, 0.7};
    CHECK(gp_clump3d_union(&one, 1, &b, &err) == GP_OK);
    double V1 = 4.0 / 3.0 * PI * 0.343;
    CHECK_REL(b.volume, V1, 1e-14);
    CHECK_REL(b.inertia[0], 0.4 * V1 * 0.49, 1e-14);
    CHECK_NEAR(b.inertia[1], 0, 1e-15);
    CHECK_NEAR(b.centroid[2], 5, 1e-14);
    /* two balls: the lens formula for the volume, and the test's own exact integral along
     * the axis for volume, centroid and inertia */
    double worst = 0, worst_i = 0;
    double cases[6][3] = {{1, 1, 1}, {1, 0.6, 1.2}, {0.8, 0.5, 0.45}, {1, 1, 0.05},
                          {1, 0.3, 1.25}, {0.7, 0.65, 1.0}};
    double ax[3] = {0.6, 0.8, 0}, c1[3] = {0.1, 0.2, 0.3};
    for (int q = 0; q < 6; q++) {
        double r1 = cases[q][0], r2 = cases[q][1], d = cases[q][2];
        gp_clump3d_sphere s[2] = {{c1[0], c1[1], c1[2], r1},
                                  {c1[0] + d * ax[0], c1[1] + d * ax[1], c1[2] + d * ax[2], r2}};
        CHECK(gp_clump3d_union(s, 2, &b, &err) == GP_OK);
        double lens = PI * (r1 + r2 - d) * (r1 + r2 - d) *
                      (d * d + 2 * d * r2 - 3 * r2 * r2 + 2 * d * r1 + 6 * r1 * r2 - 3 * r1 * r1) /
                      (12 * d);
        double exact = 4.0 / 3.0 * PI * (r1 * r1 * r1 + r2 * r2 * r2) - lens;
        gp_clump3d_body t = two_balls(c1, ax, r1, r2, d);
        CHECK_REL(t.volume, exact, 1e-13);
        worst = fmax(worst, fabs(b.volume - exact) / exact);
        CHECK_REL(b.volume, exact, 2e-4);
        double scale = t.inertia[0] + t.inertia[4] + t.inertia[8];
        for (int k = 0; k < 9; k++) {
            worst_i = fmax(worst_i, fabs(b.inertia[k] - t.inertia[k]) / scale);
            CHECK_NEAR(b.inertia[k], t.inertia[k], 3e-4 * scale);
        }
        for (int k = 0; k < 3; k++) CHECK_NEAR(b.centroid[k], t.centroid[k], 1e-4 * (r1 + r2));
    }
    printf("union of two balls against exact values: worst relative error %.2e (volume), "
           "%.2e (inertia / its trace)\n", worst, worst_i);
    /* the same ball twice counts once; a ball inside another adds nothing */
    gp_clump3d_sphere dup[3] = {{1, 2, 3, 0.5}, {1, 2, 3, 0.5}, {1.1, 2, 3, 0.2}};
    CHECK(gp_clump3d_union(dup, 3, &b, &err) == GP_OK);
    CHECK_REL(b.volume, 4.0 / 3.0 * PI * 0.125, 1e-14);
    /* three balls against Monte-Carlo (the result's own check) */
    gp_clump3d_result r;
    memset(&r, 0, sizeof r);
    gp_clump3d_sphere three[3] = {{0, 0, 0, 1}, {0.9, 0.3, 0, 0.7}, {0.4, -0.2, 0.6, 0.6}};
    r.spheres = three;
    r.nspheres = 3;
    CHECK(gp_clump3d_union(three, 3, &r.clump, &err) == GP_OK);
    check_mc(&r, 2000000, "three balls");
    /* bad input */
    gp_clump3d_sphere bad = {0, 0, 0, -1};
    CHECK(gp_clump3d_union(&bad, 1, &b, &err) == GP_ERR_INVALID);
    CHECK(strstr(err.message, "r < 0") != NULL);
    CHECK(gp_clump3d_union(NULL, 2, &b, &err) == GP_ERR_INVALID);
    CHECK(gp_clump3d_union(NULL, 0, &b, &err) == GP_OK && b.volume == 0);
}

static void test_mesh_body(void)
{
    double A[9] = {1, 0, 0, 0, 0.6, 0, 0, 0, 0.4}, o[3] = {0.5, -1, 2};
    mesh m = star_grain(4, NULL, A, o);
    gp_clump3d_body own = own_body(&m), mod;
    gp_error err;
    CHECK(gp_clump3d_mesh_body(m.v, m.nv, m.t, m.nt, &mod, &err) == GP_OK);
    CHECK_REL(mod.volume, own.volume, 1e-12);
    for (int k = 0; k < 3; k++) CHECK_NEAR(mod.centroid[k], own.centroid[k], 1e-12);
    for (int k = 0; k < 9; k++) CHECK_NEAR(mod.inertia[k], own.inertia[k], 1e-12);
    /* against the analytic ellipsoid, within the discretisation (the mesh is inscribed) */
    double V = 4.0 / 3.0 * PI * 0.24;
    CHECK(own.volume < V && own.volume > V * 0.995);
    CHECK_REL(own.inertia[0], V / 5 * (0.36 + 0.16), 0.01);
    CHECK_REL(own.inertia[4], V / 5 * (1 + 0.16), 0.01);
    CHECK_REL(own.inertia[8], V / 5 * (1 + 0.36), 0.01);
    for (int k = 0; k < 3; k++) CHECK_NEAR(own.centroid[k], o[k], 1e-12);
    mesh_free(&m);
}

static void test_sphere_mesh(void)
{
    double A[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, o[3] = {0, 0, 0};
    mesh m = star_grain(4, NULL, A, o);
    gp_clump3d_body g = own_body(&m);
    /* the inscribed radius of the mesh: its nearest face plane; the chordal error 1 - that */
    double rin = mesh_dist(&m, o);
    double chord = 1 - rin;
    gp_clump3d_params p;
    gp_clump3d_params_defaults(&p);
    gp_clump3d_result r;
    gp_error err;
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, &g, &p, &r, &err) == GP_OK);
    CHECK(r.nspheres == 1);
    if (r.nspheres >= 1) {
        printf("sphere mesh: 1 sphere r = %.6f (inscribed %.6f, chordal error %.2e), centre "
               "(%.1e %.1e %.1e), volume_error %.3e (mesh deficit %.3e)\n",
               r.spheres[0].r, rin, chord, r.spheres[0].x, r.spheres[0].y, r.spheres[0].z,
               r.volume_error, g.volume / (4.0 / 3.0 * PI) - 1);
        CHECK(r.spheres[0].r >= rin - 1e-3 * chord);
        CHECK(r.spheres[0].r <= 1);
        double cn = sqrt(r.spheres[0].x * r.spheres[0].x + r.spheres[0].y * r.spheres[0].y +
                         r.spheres[0].z * r.spheres[0].z);
        CHECK(cn <= chord);
        /* the deficit of a ball of the inscribed radius against the mesh: about 3 chord */
        double vin = 4.0 / 3.0 * PI * rin * rin * rin;
        CHECK(r.volume_error <= 0);
        CHECK(r.volume_error >= (vin - g.volume) / g.volume - 1e-6);
        CHECK(fabs(r.volume_error) <= 4 * chord);
        CHECK(r.inertia_error <= 6 * chord);
        CHECK(r.centroid_offset <= chord);
        check_inside(&m, o, &r, p.min_radius_ratio);
    }
    gp_clump3d_result_free(&r);
    mesh_free(&m);
}

/* Clumps of a grain for spheres_max = 1, 5, 20, 50: inside, prefixes, volume error rising to 0,
 * the 50-sphere union against Monte-Carlo with nmc samples. */
static void grain_series(const char *name, const mesh *m, const double *o, double ratio,
                         size_t nmc)
{
    gp_clump3d_body g = own_body(m);
    size_t caps[4] = {1, 5, 20, 50};
    gp_clump3d_result r[4];
    gp_error err;
    printf("%s (V = %.5f):\n", name, g.volume);
    printf("  spheres_max | spheres | volume_error | inertia_error | shape_error | centroid_off "
           "| r_min/r_max | covered\n");
    for (int q = 0; q < 4; q++) {
        gp_clump3d_params p;
        gp_clump3d_params_defaults(&p);
        p.spheres_max = caps[q];
        p.min_radius_ratio = ratio;
        CHECK(gp_clump3d_build(m->v, m->nv, m->t, m->nt, &g, &p, &r[q], &err) == GP_OK);
        printf("  %11zu | %7zu | %12.4f | %13.4f | %11.4f | %12.4f | %11.3f | %.4f\n", caps[q],
               r[q].nspheres, r[q].volume_error, r[q].inertia_error, r[q].inertia_shape_error,
               r[q].centroid_offset, r[q].r_min / r[q].r_max, r[q].covered);
        CHECK(r[q].nspheres >= 1 && r[q].nspheres <= caps[q]);
        double worst = check_inside(m, o, &r[q], ratio);
        if (q == 3) printf("  worst (r - distance) / r over the spheres: %.2e\n", worst);
        CHECK(r[q].volume_error < 0);
        CHECK(r[q].volume_error > -1);
    }
    for (int q = 1; q < 4; q++) {
        /* the prefix property: the smaller cap's clump begins the larger's */
        CHECK(r[q].nspheres >= r[q - 1].nspheres);
        CHECK(memcmp(r[q].spheres, r[q - 1].spheres,
                     r[q - 1].nspheres * sizeof(gp_clump3d_sphere)) == 0);
        /* volume_error rises towards 0 (more spheres, a larger union) */
        if (r[q].nspheres > r[q - 1].nspheres) CHECK(r[q].volume_error > r[q - 1].volume_error);
        else CHECK(r[q].volume_error == r[q - 1].volume_error);
    }
    CHECK(r[3].inertia_error < r[0].inertia_error);
    CHECK(r[3].inertia_error < r[1].inertia_error);
    check_mc(&r[3], nmc, name);
    for (int q = 0; q < 4; q++) gp_clump3d_result_free(&r[q]);
}

static void test_ellipsoid(void)
{
    double A[9] = {1, 0, 0, 0, 0.6, 0, 0, 0, 0.4}, o[3] = {0, 0, 0};
    mesh m = star_grain(4, NULL, A, o);
    grain_series("ellipsoid (1, 0.6, 0.4)", &m, o, 0.1, 2000000);
    /* the 50-sphere clump: within 15 % of the volume */
    gp_clump3d_params p;
    gp_clump3d_params_defaults(&p);
    p.spheres_max = 50;
    gp_clump3d_result r;
    gp_error err;
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, NULL, &p, &r, &err) == GP_OK);
    CHECK(r.volume_error > -0.15);
    CHECK(r.capped == 1);
    gp_clump3d_result_free(&r);
    mesh_free(&m);
}

static void test_rough(void)
{
    double A[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, o[3] = {0, 0, 0};
    mesh m = star_grain(4, bumpy, A, o);
    grain_series("star grain 1 + 0.3 P3 + 0.2 sin^3 cos 3phi", &m, o, 0.1, 2000000);
    /* and stretched by an affine map (a shear), with a small radius ratio */
    double B[9] = {1.2, 0.3, 0, 0, 0.7, 0.1, 0.05, 0, 0.5};
    mesh s = star_grain(4, bumpy, B, o);
    grain_series("the star grain sheared", &s, o, 0.05, 1000000);
    mesh_free(&s);
    mesh_free(&m);
}

/* A torus (R = 1, r = 0.35; 96 x 32 quads, two triangles each): not star-shaped, genus 1. */
static mesh torus(size_t nu, size_t nw, double R, double r)
{
    mesh m = {malloc(3 * nu * nw * sizeof(double)), malloc(6 * nu * nw * sizeof(uint32_t)),
              nu * nw, 2 * nu * nw};
    for (size_t i = 0; i < nu; i++)
        for (size_t j = 0; j < nw; j++) {
            double u = 2 * PI * (double)i / (double)nu, w = 2 * PI * (double)j / (double)nw;
            double *p = m.v + 3 * (i * nw + j);
            p[0] = (R + r * cos(w)) * cos(u);
            p[1] = (R + r * cos(w)) * sin(u);
            p[2] = r * sin(w);
        }
    for (size_t i = 0; i < nu; i++)
        for (size_t j = 0; j < nw; j++) {
            uint32_t a = (uint32_t)(i * nw + j), b = (uint32_t)(((i + 1) % nu) * nw + j);
            uint32_t c = (uint32_t)(((i + 1) % nu) * nw + (j + 1) % nw);
            uint32_t d = (uint32_t)(i * nw + (j + 1) % nw);
            uint32_t *t = m.t + 6 * (i * nw + j);
            t[0] = a, t[1] = b, t[2] = c, t[3] = a, t[4] = c, t[5] = d;
        }
    return m;
}

/* 1 if p is inside the closed mesh: crossings of a ray in a fixed generic direction, odd. */
static int parity_inside(const mesh *m, const double *p)
{
    double d[3] = {0.5773502691896258, 0.5163977794943222, 0.6324555320336759};
    int odd = 0;
    for (size_t f = 0; f < m->nt; f++) {
        const double *a = m->v + 3 * m->t[3 * f], *b = m->v + 3 * m->t[3 * f + 1],
                     *c = m->v + 3 * m->t[3 * f + 2];
        double e1[3], e2[3], pv[3], tv[3], qv[3];
        sub3(b, a, e1);
        sub3(c, a, e2);
        cross(d, e2, pv);
        double det = dot(e1, pv);
        if (fabs(det) < 1e-300) continue;
        sub3(p, a, tv);
        double u = dot(tv, pv) / det;
        if (u < 0 || u > 1) continue;
        cross(tv, e1, qv);
        double v = dot(d, qv) / det;
        if (v < 0 || u + v > 1) continue;
        if (dot(e2, qv) / det > 0) odd ^= 1;
    }
    return odd;
}

static void test_torus(void)
{
    mesh m = torus(96, 32, 1, 0.35);
    gp_clump3d_body g = own_body(&m);
    gp_clump3d_params p;
    gp_clump3d_params_defaults(&p);
    p.spheres_max = 40;
    gp_clump3d_result r;
    gp_error err;
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, &g, &p, &r, &err) == GP_OK);
    int in = 1;
    double worst = -INFINITY;
    for (size_t i = 0; i < r.nspheres; i++) {
        double c[3] = {r.spheres[i].x, r.spheres[i].y, r.spheres[i].z};
        in &= parity_inside(&m, c);
        worst = fmax(worst, (r.spheres[i].r - mesh_dist(&m, c)) / r.spheres[i].r);
        /* the ring: every centre near the core circle, no sphere through the hole */
        double rho = sqrt(c[0] * c[0] + c[1] * c[1]);
        CHECK(fabs(rho - 1) + r.spheres[i].r <= 0.35 + 1e-9);
    }
    CHECK(in);
    CHECK(worst <= 1e-13);
    printf("torus (not star-shaped): %zu spheres, volume_error %.4f, inertia_error %.4f, worst "
           "(r - distance) / r %.1e\n",
           r.nspheres, r.volume_error, r.inertia_error, worst);
    CHECK(r.volume_error < 0 && r.volume_error > -0.2);
    gp_clump3d_result_free(&r);
    mesh_free(&m);
}

/* The same grain turned, moved far away and scaled: the same clump, turned, moved and scaled
 * (the grid is laid in the grain's principal frame). */
static void test_frames(void)
{
    double A[9] = {0.9, 0.2, 0, -0.1, 0.6, 0.05, 0, 0.1, 0.45}, o[3] = {0, 0, 0};
    double far[3] = {1000.25, -500.5, 20.125}, S = 1e-3;
    /* a rotation: 0.7 rad about the unit axis (1, 2, 2) / 3 */
    double ax[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, th = 0.7, c = cos(th), sn = sin(th), Q[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double cr = 0;
            if (i != j) {
                int k = 3 - i - j;
                double sg = ((j - i + 3) % 3 == 1) ? -1 : 1;
                cr = sg * ax[k];
            }
            Q[3 * i + j] = c * (i == j) + (1 - c) * ax[i] * ax[j] + sn * cr;
        }
    double B[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double x = 0;
            for (int k = 0; k < 3; k++) x += Q[3 * i + k] * A[3 * k + j];
            B[3 * i + j] = S * x;
        }
    mesh m = star_grain(4, bumpy, A, o), n = star_grain(4, bumpy, B, far);
    gp_clump3d_result r, t;
    gp_error err;
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, NULL, NULL, &r, &err) == GP_OK);
    CHECK(gp_clump3d_build(n.v, n.nv, n.t, n.nt, NULL, NULL, &t, &err) == GP_OK);
    CHECK(r.nspheres == t.nspheres);
    double worst = 0;
    for (size_t i = 0; i < r.nspheres && i < t.nspheres; i++) {
        double x[3] = {r.spheres[i].x, r.spheres[i].y, r.spheres[i].z};
        double y[3] = {t.spheres[i].x, t.spheres[i].y, t.spheres[i].z};
        for (int k = 0; k < 3; k++) {
            double want = far[k] + S * (Q[3 * k] * x[0] + Q[3 * k + 1] * x[1] + Q[3 * k + 2] * x[2]);
            worst = fmax(worst, fabs(y[k] - want) / S);
        }
        worst = fmax(worst, fabs(t.spheres[i].r - S * r.spheres[i].r) / S);
    }
    printf("turned by 0.7 rad, moved by 1e3 and scaled by 1e-3: the same %zu spheres within "
           "%.1e of the size\n", r.nspheres, worst);
    CHECK(worst < 1e-6);
    CHECK_NEAR(r.volume_error, t.volume_error, 1e-6);
    CHECK_NEAR(r.inertia_error, t.inertia_error, 1e-6);
    gp_clump3d_result_free(&r);
    gp_clump3d_result_free(&t);
    mesh_free(&m);
    mesh_free(&n);
}

/* A needle (1, 0.05, 0.05) along a diagonal: voxels in its own frame, not the box's. */
static void test_needle(void)
{
    double c = cos(0.7), sn = sin(0.7), o[3] = {0.3, -0.2, 0.1};
    double A[9] = {c * 0.577, -sn * 0.05, 0, sn * 0.577, c * 0.05, 0, 0.577, 0, 0.05};
    mesh m = star_grain(4, NULL, A, o);
    gp_clump3d_result r;
    gp_error err;
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, NULL, NULL, &r, &err) == GP_OK);
    printf("needle 20:1 along a diagonal: %zu voxel centres inside, %zu spheres, volume_error "
           "%.3f\n", r.voxels_inside, r.nspheres, r.volume_error);
    CHECK(r.voxels_inside > 6000);
    check_inside(&m, o, &r, 0.1);
    gp_clump3d_result_free(&r);
    mesh_free(&m);
}

static void test_determinism(void)
{
    double A[9] = {1, 0.2, 0, 0, 0.7, 0, 0.1, 0, 0.5}, o[3] = {0.1, 0.2, 0.3};
    mesh m = star_grain(4, bumpy, A, o);
    gp_clump3d_params p;
    gp_clump3d_params_defaults(&p);
    p.spheres_max = 40;
    gp_clump3d_result a, b;
    gp_error err;
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, NULL, &p, &a, &err) == GP_OK);
    /* a copy of the input, and a heap disturbed in between */
    mesh c = {malloc(3 * m.nv * sizeof(double)), malloc(3 * m.nt * sizeof(uint32_t)), m.nv, m.nt};
    memcpy(c.v, m.v, 3 * m.nv * sizeof(double));
    memcpy(c.t, m.t, 3 * m.nt * sizeof(uint32_t));
    void *noise = malloc(12345);
    memset(noise, 0xab, 12345);
    CHECK(gp_clump3d_build(c.v, c.nv, c.t, c.nt, NULL, &p, &b, &err) == GP_OK);
    free(noise);
    CHECK(a.nspheres == b.nspheres);
    CHECK(a.nspheres > 0 &&
          memcmp(a.spheres, b.spheres, a.nspheres * sizeof(gp_clump3d_sphere)) == 0);
    gp_clump3d_sphere *sa = a.spheres, *sb = b.spheres;
    a.spheres = b.spheres = NULL;
    CHECK(memcmp(&a, &b, sizeof a) == 0);
    a.spheres = sa, b.spheres = sb;
    gp_clump3d_result_free(&a);
    gp_clump3d_result_free(&b);
    mesh_free(&c);
    mesh_free(&m);
}

static int zeroed(const gp_clump3d_result *r)
{
    gp_clump3d_result z;
    memset(&z, 0, sizeof z);
    return memcmp(r, &z, sizeof z) == 0;
}

static void expect(gp_status got, gp_status want, const gp_error *err, const char *word,
                   const gp_clump3d_result *r, int line)
{
    int ok = got == want && strstr(err->message, word) != NULL && zeroed(r);
    if (!ok)
        fprintf(stderr, "line %d: status %d (want %d), message \"%s\" (want \"%s\")\n", line,
                (int)got, (int)want, err->message, word);
    CHECK(ok);
}

static void test_bad_input(void)
{
    double A[9] = {1, 0, 0, 0, 0.6, 0, 0, 0, 0.4}, o[3] = {0, 0, 0};
    mesh m = star_grain(3, NULL, A, o);
    gp_clump3d_params p;
    gp_clump3d_result r;
    gp_error err;
#define BUILD(xyz, nv, t, nt, g, pp) gp_clump3d_build(xyz, nv, t, nt, g, pp, &r, &err)
    gp_clump3d_params_defaults(&p);
    CHECK(p.spheres_max == 30 && p.min_radius_ratio == 0.1 && p.voxels == 0);
    size_t bad_caps[2] = {0, 1001};
    for (int q = 0; q < 2; q++) {
        gp_clump3d_params_defaults(&p);
        p.spheres_max = bad_caps[q];
        expect(BUILD(m.v, m.nv, m.t, m.nt, NULL, &p), GP_ERR_INVALID, &err, "spheres_max", &r,
               __LINE__);
    }
    double bad_ratio[4] = {0, -0.5, 1.5, NAN};
    for (int q = 0; q < 4; q++) {
        gp_clump3d_params_defaults(&p);
        p.min_radius_ratio = bad_ratio[q];
        expect(BUILD(m.v, m.nv, m.t, m.nt, NULL, &p), GP_ERR_INVALID, &err, "min_radius_ratio",
               &r, __LINE__);
    }
    size_t bad_voxels[2] = {10, 300000};
    for (int q = 0; q < 2; q++) {
        gp_clump3d_params_defaults(&p);
        p.voxels = bad_voxels[q];
        expect(BUILD(m.v, m.nv, m.t, m.nt, NULL, &p), GP_ERR_INVALID, &err, "voxels", &r,
               __LINE__);
    }
    gp_clump3d_params_defaults(&p);
    p.min_radius_ratio = 1; /* allowed: every sphere as large as the first */
    CHECK(BUILD(m.v, m.nv, m.t, m.nt, NULL, &p) == GP_OK);
    CHECK(r.nspheres >= 1 && r.r_min == r.r_max);
    gp_clump3d_result_free(&r);
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, NULL, NULL, NULL, &err) == GP_ERR_INVALID);

    expect(BUILD(NULL, m.nv, m.t, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "xyz", &r, __LINE__);
    expect(BUILD(m.v, m.nv, NULL, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "tri", &r, __LINE__);
    expect(BUILD(m.v, 3, m.t, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "nv", &r, __LINE__);
    expect(BUILD(m.v, m.nv, m.t, 3, NULL, NULL), GP_ERR_INVALID, &err, "nt", &r, __LINE__);
    /* an index out of range, a repeated vertex, a vertex not finite */
    uint32_t keep = m.t[7];
    m.t[7] = (uint32_t)m.nv;
    expect(BUILD(m.v, m.nv, m.t, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "index", &r, __LINE__);
    m.t[7] = m.t[6];
    expect(BUILD(m.v, m.nv, m.t, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "repeats", &r, __LINE__);
    m.t[7] = keep;
    double kv = m.v[4];
    m.v[4] = NAN;
    expect(BUILD(m.v, m.nv, m.t, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "finite", &r, __LINE__);
    m.v[4] = kv;
    /* an open mesh (one triangle missing), a flipped triangle, every triangle flipped */
    expect(BUILD(m.v, m.nv, m.t, m.nt - 1, NULL, NULL), GP_ERR_INVALID, &err, "not closed", &r,
           __LINE__);
    uint32_t *flip = malloc(3 * m.nt * sizeof(uint32_t));
    memcpy(flip, m.t, 3 * m.nt * sizeof(uint32_t));
    flip[0] = m.t[1], flip[1] = m.t[0];
    expect(BUILD(m.v, m.nv, flip, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "oriented", &r,
           __LINE__);
    for (size_t f = 0; f < m.nt; f++) flip[3 * f] = m.t[3 * f + 1], flip[3 * f + 1] = m.t[3 * f];
    expect(BUILD(m.v, m.nv, flip, m.nt, NULL, NULL), GP_ERR_INVALID, &err, "clockwise", &r,
           __LINE__);
    free(flip);
    /* a grain that is not this mesh's, or not finite */
    gp_clump3d_body g = own_body(&m);
    g.volume *= 1.01;
    expect(BUILD(m.v, m.nv, m.t, m.nt, &g, NULL), GP_ERR_INVALID, &err, "grain", &r, __LINE__);
    g = own_body(&m);
    g.inertia[4] = INFINITY;
    expect(BUILD(m.v, m.nv, m.t, m.nt, &g, NULL), GP_ERR_INVALID, &err, "grain", &r, __LINE__);
    g = own_body(&m);
    CHECK(BUILD(m.v, m.nv, m.t, m.nt, &g, NULL) == GP_OK);
    gp_clump3d_result_free(&r);

    /* flat meshes: the ellipsoid squashed to z = 0, and to 1e-14 of its size */
    double F[9] = {1, 0, 0, 0, 0.6, 0, 0, 0, 0};
    mesh f = star_grain(3, NULL, F, o);
    expect(BUILD(f.v, f.nv, f.t, f.nt, NULL, NULL), GP_ERR_DEGENERATE, &err, "no volume", &r,
           __LINE__);
    mesh_free(&f);
    F[8] = 1e-14;
    f = star_grain(3, NULL, F, o);
    expect(BUILD(f.v, f.nv, f.t, f.nt, NULL, NULL), GP_ERR_DEGENERATE, &err, "volume", &r,
           __LINE__);
    mesh_free(&f);
    /* a thin plate with volume: one voxel thick at most, refused or a clump inside */
    F[8] = 2e-3;
    f = star_grain(3, NULL, F, o);
    gp_status st = BUILD(f.v, f.nv, f.t, f.nt, NULL, NULL);
    CHECK(st == GP_OK || st == GP_ERR_DEGENERATE);
    if (st == GP_OK) check_inside(&f, o, &r, 0.1);
    gp_clump3d_result_free(&r);
    mesh_free(&f);
    mesh_free(&m);
#undef BUILD
}

/* Many small spheres: spheres_max 1000 with a small radius ratio and a finer grid. */
static void test_many(void)
{
    double A[9] = {1, 0, 0, 0, 0.6, 0, 0, 0, 0.4}, o[3] = {0, 0, 0};
    mesh m = star_grain(4, bumpy, A, o);
    gp_clump3d_params p = {1000, 0.02, 100000};
    gp_clump3d_result r;
    gp_error err;
    CHECK(gp_clump3d_build(m.v, m.nv, m.t, m.nt, NULL, &p, &r, &err) == GP_OK);
    printf("spheres_max 1000, ratio 0.02, 1e5 voxels: %zu spheres, volume_error %.4f, "
           "inertia_error %.4f, covered %.4f\n",
           r.nspheres, r.volume_error, r.inertia_error, r.covered);
    CHECK(r.nspheres > 50 && r.nspheres <= 1000);
    CHECK(r.volume_error < 0 && r.volume_error > -0.1);
    size_t step = r.nspheres / 60 + 1;
    gp_clump3d_result sub = r;
    gp_clump3d_sphere *pick = malloc(r.nspheres * sizeof *pick);
    size_t k = 0;
    for (size_t i = 0; i < r.nspheres; i += step) pick[k++] = r.spheres[i];
    sub.spheres = pick;
    sub.nspheres = k;
    check_inside(&m, o, &sub, 0.02);
    free(pick);
    gp_clump3d_result_free(&r);
    mesh_free(&m);
}

int main(void)
{
    test_union();
    test_mesh_body();
    test_sphere_mesh();
    test_ellipsoid();
    test_rough();
    test_torus();
    test_frames();
    test_needle();
    test_determinism();
    test_bad_input();
    test_many();
    return gp_test_summary();
}
