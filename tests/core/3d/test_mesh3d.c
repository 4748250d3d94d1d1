/* test_mesh3d.c -- closed triangle meshes: the icosphere's counts and nesting; mass properties
 * of a sphere and an ellipsoid meshed on icospheres of levels 1-5 against the formulas
 * (second-order convergence, and Richardson's extrapolation of levels 4 and 5), of a cube and a
 * rotated, translated box exactly; principal axes and extents; far from the origin; the convex
 * hull (a cube's corners with interior and face points, a sphere's vertices, a non-convex star,
 * random points, degenerate sets); bad meshes refused. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gp_mesh3d.h"
#include "gp_test.h"

#define PI 3.14159265358979323846

static uint64_t rng_state = 88172645463325252ull;

static double u01(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double max_abs9(const double *a)
{
    double m = 0;
    for (int i = 0; i < 9; i++) m = fabs(a[i]) > m ? fabs(a[i]) : m;
    return m;
}

/* largest |a - b| over a 3 x 3 matrix, relative to b's largest entry */
static double rel9(const double *a, const double *b)
{
    double d = 0;
    for (int i = 0; i < 9; i++) d = fabs(a[i] - b[i]) > d ? fabs(a[i] - b[i]) : d;
    return d / max_abs9(b);
}

/* icosphere vertices scaled to (a x, b y, c z) and moved by off */
static double *scaled(const gp_mesh3d *m, double a, double b, double c, const double off[3])
{
    size_t nv = gp_mesh3d_vertex_count(m);
    const double *v = gp_mesh3d_vertices(m);
    double *x = malloc(3 * nv * sizeof(double));
    for (size_t i = 0; i < nv; i++) {
        x[3 * i] = a * v[3 * i] + off[0];
        x[3 * i + 1] = b * v[3 * i + 1] + off[1];
        x[3 * i + 2] = c * v[3 * i + 2] + off[2];
    }
    return x;
}

/* The ellipsoid's area by quadrature in t = cos(theta) (midpoint, 20,000 steps: error ~1e-9)
 * and phi (midpoint, 256 steps: spectrally accurate for the periodic integrand). */
static double ellipsoid_area(double a, double b, double c)
{
    int nt = 20000, np = 256;
    double s = 0;
    for (int i = 0; i < nt; i++) {
        double t = -1 + (i + 0.5) * 2.0 / nt, st2 = 1 - t * t;
        for (int j = 0; j < np; j++) {
            double p = (j + 0.5) * 2 * PI / np, cp = cos(p), sp = sin(p);
            s += sqrt(b * b * c * c * st2 * cp * cp + a * a * c * c * st2 * sp * sp + a * a * b * b * t * t);
        }
    }
    return s * (2.0 / nt) * (2 * PI / np);
}

static void test_icosphere(void)
{
    gp_mesh3d *prev = NULL;
    for (unsigned l = 0; l <= 5; l++) {
        gp_error err;
        gp_mesh3d *m = gp_mesh3d_icosphere(l, &err);
        CHECK(m != NULL);
        if (!m) return;
        size_t nv = gp_mesh3d_vertex_count(m), nt = gp_mesh3d_triangle_count(m);
        CHECK(nv == 10 * ((size_t)1 << (2 * l)) + 2);
        CHECK(nt == 20 * ((size_t)1 << (2 * l)));
        CHECK(gp_mesh3d_check(nv, gp_mesh3d_triangles(m), nt, &err) == GP_OK);
        const double *v = gp_mesh3d_vertices(m);
        double worst = 0;
        for (size_t i = 0; i < nv; i++)
            worst = fmax(worst, fabs(sqrt(v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]) - 1));
        CHECK(worst < 1e-15);
        if (prev) /* nested: the previous level's vertices come first, bit for bit */
            CHECK(memcmp(v, gp_mesh3d_vertices(prev), 3 * gp_mesh3d_vertex_count(prev) * sizeof(double)) == 0);
        int axes = 0; /* +-x, +-y, +-z are vertices from level 1 on */
        for (size_t i = 0; i < nv; i++)
            for (int k = 0; k < 3; k++)
                axes += fabs(fabs(v[3 * i + k]) - 1) < 1e-15;
        CHECK(l == 0 ? axes == 0 : axes == 6);
        gp_mesh3d_mass ms;
        CHECK(gp_mesh3d_mass_properties(v, nv, gp_mesh3d_triangles(m), nt, &ms, NULL) == GP_OK);
        CHECK(ms.volume > 0); /* counter-clockwise seen from outside */
        gp_mesh3d_destroy(prev);
        prev = m;
    }
    gp_mesh3d_destroy(prev);
    gp_error err;
    CHECK(gp_mesh3d_icosphere(GP_MESH3D_ICOSPHERE_LEVEL_MAX + 1, &err) == NULL && err.code == GP_ERR_INVALID);
    /* deterministic: the same level twice gives the same bytes */
    gp_mesh3d *a = gp_mesh3d_icosphere(3, NULL), *b = gp_mesh3d_icosphere(3, NULL);
    CHECK(memcmp(gp_mesh3d_vertices(a), gp_mesh3d_vertices(b), 642 * 3 * sizeof(double)) == 0);
    CHECK(memcmp(gp_mesh3d_triangles(a), gp_mesh3d_triangles(b), 1280 * 3 * sizeof(uint32_t)) == 0);
    gp_mesh3d_destroy(a);
    gp_mesh3d_destroy(b);
}

typedef struct errs {
    double vol, cen, inr, area;
    gp_mesh3d_mass m;
} errs;

/* The ellipsoid (a, b, c) on the icosphere of level l against the formulas. */
static errs ellipsoid_errors(unsigned l, double a, double b, double c, double A_true)
{
    errs e;
    gp_mesh3d *m = gp_mesh3d_icosphere(l, NULL);
    double off[3] = {0, 0, 0}, *x = scaled(m, a, b, c, off);
    gp_status st = gp_mesh3d_mass_properties(x, gp_mesh3d_vertex_count(m), gp_mesh3d_triangles(m),
                                             gp_mesh3d_triangle_count(m), &e.m, NULL);
    CHECK(st == GP_OK);
    double V = 4.0 / 3.0 * PI * a * b * c;
    double I[9] = {V * (b * b + c * c) / 5, 0, 0, 0, V * (a * a + c * c) / 5, 0, 0, 0, V * (a * a + b * b) / 5};
    e.vol = fabs(e.m.volume - V) / V;
    e.cen = fmax(fabs(e.m.centroid[0]), fmax(fabs(e.m.centroid[1]), fabs(e.m.centroid[2])));
    e.inr = rel9(e.m.inertia, I);
    e.area = fabs(e.m.area - A_true) / A_true;
    free(x);
    gp_mesh3d_destroy(m);
    return e;
}

static void test_convergence(const char *name, double a, double b, double c)
{
    double A = ellipsoid_area(a, b, c);
    if (a == b && b == c) CHECK_REL(A, 4 * PI * a * a, 1e-9); /* the quadrature itself */
    errs e[6];
    printf("%s (%g, %g, %g): relative errors of the icosphere mesh against the formulas\n", name, a, b, c);
    printf("  level  volume     centroid   inertia    area\n");
    for (unsigned l = 1; l <= 5; l++) {
        e[l] = ellipsoid_errors(l, a, b, c, A);
        printf("  %u      %.3e  %.1e    %.3e  %.3e\n", l, e[l].vol, e[l].cen, e[l].inr, e[l].area);
        CHECK(e[l].cen < 1e-14); /* symmetric meshes */
    }
    for (unsigned l = 1; l < 5; l++) { /* second order: each level divides the error by ~4 */
        CHECK(e[l + 1].vol < e[l].vol / 3.5 && e[l + 1].vol > e[l].vol / 4.5);
        CHECK(e[l + 1].inr < e[l].inr / 3.5 && e[l + 1].inr > e[l].inr / 4.5);
        CHECK(e[l + 1].area < e[l].area / 3.5 && e[l + 1].area > e[l].area / 4.5);
    }
    /* the mesh is inscribed: its own discretisation error (not the integration's) is 2.2e-3
     * of the volume at level 4 and 5.4e-4 at level 5 (a flat triangle lies inside the sphere);
     * the extrapolation of levels 4 and 5 is within 1e-5 */
    CHECK(e[4].vol < 2.5e-3 && e[4].inr < 4e-3 && e[4].area < 1.3e-3);
    CHECK(e[5].vol < 6e-4 && e[5].inr < 1e-3 && e[5].area < 3.5e-4);
    double V = 4.0 / 3.0 * PI * a * b * c;
    double Vr = (4 * e[5].m.volume - e[4].m.volume) / 3, Ar = (4 * e[5].m.area - e[4].m.area) / 3;
    double Ixx = (4 * e[5].m.inertia[0] - e[4].m.inertia[0]) / 3;
    printf("  Richardson (4, 5): volume %.1e, Ixx %.1e, area %.1e\n", fabs(Vr - V) / V,
           fabs(Ixx - V * (b * b + c * c) / 5) / (V * (b * b + c * c) / 5), fabs(Ar - A) / A);
    CHECK_REL(Vr, V, 1e-5);
    CHECK_REL(Ar, A, 1e-5);
    CHECK_REL(Ixx, V * (b * b + c * c) / 5, 1e-5);
    /* principal axes of the ellipsoid: x, y, z with extents 2a, 2b, 2c (axes are vertices) */
    gp_mesh3d *m = gp_mesh3d_icosphere(4, NULL);
    double off[3] = {0, 0, 0}, *x = scaled(m, a, b, c, off);
    gp_mesh3d_axes ax;
    CHECK(gp_mesh3d_principal_axes(x, gp_mesh3d_vertex_count(m), &e[4].m, &ax, NULL) == GP_OK);
    if (a == b) { /* a sphere: any axes, extents within the mesh's 2e-3 of the diameter */
        for (int k = 0; k < 3; k++) CHECK(ax.extent[k] <= 2 * a && ax.extent[k] > 2 * a * (1 - 2e-3));
    } else {
        CHECK_NEAR(ax.extent[0], 2 * a, 1e-12);
        CHECK_NEAR(ax.extent[1], 2 * b, 1e-12);
        CHECK_NEAR(ax.extent[2], 2 * c, 1e-12);
    }
    if (a > b && b > c) {
        CHECK_NEAR(ax.axis[0][0], 1, 1e-12);
        CHECK_NEAR(ax.axis[1][1], 1, 1e-12);
        CHECK_NEAR(ax.axis[2][2], 1, 1e-12);
        CHECK(ax.moment[0] < ax.moment[1] && ax.moment[1] < ax.moment[2]);
    }
    free(x);
    gp_mesh3d_destroy(m);
}

/* a unit cube [0,1]^3 or a box: 8 corners (bit k of i: coordinate k high), 12 triangles */
static const uint32_t cube_tri[36] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                      2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};

static void rotation(double ax, double ay, double az, double ang, double R[9])
{
    double n = sqrt(ax * ax + ay * ay + az * az), x = ax / n, y = ay / n, z = az / n;
    double c = cos(ang), s = sin(ang), t = 1 - c;
    double r[9] = {t * x * x + c, t * x * y - s * z, t * x * z + s * y, t * x * y + s * z, t * y * y + c,
                   t * y * z - s * x, t * x * z - s * y, t * y * z + s * x, t * z * z + c};
    memcpy(R, r, sizeof r);
}

static void test_boxes(void)
{
    double x[24];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) x[3 * i + k] = (i >> k) & 1;
    gp_error err;
    CHECK(gp_mesh3d_check(8, cube_tri, 12, &err) == GP_OK);
    gp_mesh3d_mass m;
    CHECK(gp_mesh3d_mass_properties(x, 8, cube_tri, 12, &m, &err) == GP_OK);
    CHECK_NEAR(m.volume, 1, 1e-15);
    CHECK_NEAR(m.area, 6, 1e-14);
    for (int k = 0; k < 3; k++) CHECK_NEAR(m.centroid[k], 0.5, 1e-15);
    for (int i = 0; i < 9; i++) CHECK_NEAR(m.inertia[i], i % 4 == 0 ? 1.0 / 6 : 0, 1e-15);
    /* a 2 x 3 x 0.5 box, rotated and translated */
    double L[3] = {2, 3, 0.5}, R[9], t[3] = {10, -5, 3}, y[24];
    rotation(1, 2, 3, 0.7, R);
    for (int i = 0; i < 8; i++) {
        double p[3] = {L[0] * x[3 * i], L[1] * x[3 * i + 1], L[2] * x[3 * i + 2]};
        for (int r = 0; r < 3; r++) y[3 * i + r] = t[r] + R[3 * r] * p[0] + R[3 * r + 1] * p[1] + R[3 * r + 2] * p[2];
    }
    CHECK(gp_mesh3d_mass_properties(y, 8, cube_tri, 12, &m, &err) == GP_OK);
    double V = L[0] * L[1] * L[2], d[3] = {V * (L[1] * L[1] + L[2] * L[2]) / 12, V * (L[0] * L[0] + L[2] * L[2]) / 12,
                                          V * (L[0] * L[0] + L[1] * L[1]) / 12};
    CHECK_NEAR(m.volume, V, 1e-12);
    CHECK_NEAR(m.area, 2 * (L[0] * L[1] + L[1] * L[2] + L[2] * L[0]), 1e-12);
    for (int r = 0; r < 3; r++) {
        double c = t[r] + (R[3 * r] * L[0] + R[3 * r + 1] * L[1] + R[3 * r + 2] * L[2]) / 2;
        CHECK_NEAR(m.centroid[r], c, 1e-12);
        for (int s = 0; s < 3; s++) { /* I = R diag(d) R^T */
            double v = 0;
            for (int k = 0; k < 3; k++) v += R[3 * r + k] * d[k] * R[3 * s + k];
            CHECK_NEAR(m.inertia[3 * r + s], v, 1e-12);
        }
    }
    gp_mesh3d_axes ax;
    CHECK(gp_mesh3d_principal_axes(y, 8, &m, &ax, &err) == GP_OK);
    CHECK_NEAR(ax.extent[0], 3, 1e-12); /* along R e_y */
    CHECK_NEAR(ax.extent[1], 2, 1e-12);
    CHECK_NEAR(ax.extent[2], 0.5, 1e-12);
    CHECK_NEAR(fabs(ax.axis[0][0] * R[1] + ax.axis[0][1] * R[4] + ax.axis[0][2] * R[7]), 1, 1e-12);
    CHECK_NEAR(fabs(ax.axis[1][0] * R[0] + ax.axis[1][1] * R[3] + ax.axis[1][2] * R[6]), 1, 1e-12);
    double *a0 = ax.axis[0], *a1 = ax.axis[1], *a2 = ax.axis[2]; /* right-handed */
    CHECK_NEAR(a2[0], a0[1] * a1[2] - a0[2] * a1[1], 1e-15);
    CHECK_NEAR(a0[0] * a1[0] + a0[1] * a1[1] + a0[2] * a1[2], 0, 1e-14);
    /* the hull of the box's corners is the box */
    double hv;
    CHECK(gp_mesh3d_hull_volume(y, 8, &hv, &err) == GP_OK);
    CHECK_NEAR(hv, V, 1e-12);
}

static void test_eigen(void)
{
    for (int trial = 0; trial < 100; trial++) {
        double a[9], val[3], vec[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = i; j < 3; j++) a[3 * i + j] = a[3 * j + i] = 2 * u01() - 1;
        if (trial == 0) memset(a, 0, sizeof a);
        if (trial == 1) a[1] = a[3] = a[2] = a[6] = a[5] = a[7] = 0; /* diagonal */
        gp_mesh3d_eigen_sym3(a, val, vec);
        double worst = 0;
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++) {
                double av = a[3 * i] * vec[k][0] + a[3 * i + 1] * vec[k][1] + a[3 * i + 2] * vec[k][2];
                worst = fmax(worst, fabs(av - val[k] * vec[k][i]));
            }
        CHECK(worst < 1e-14);
        CHECK(val[0] <= val[1] && val[1] <= val[2]);
        CHECK_NEAR(vec[0][0] * vec[1][0] + vec[0][1] * vec[1][1] + vec[0][2] * vec[1][2], 0, 1e-14);
    }
}

/* Every point is inside (or within tol of) every hull triangle's plane; the hull is closed. */
static int hull_contains(const gp_mesh3d *h, const double *p, size_t n, double tol)
{
    const double *v = gp_mesh3d_vertices(h);
    const uint32_t *t = gp_mesh3d_triangles(h);
    if (gp_mesh3d_check(gp_mesh3d_vertex_count(h), t, gp_mesh3d_triangle_count(h), NULL)) return 0;
    for (size_t f = 0; f < gp_mesh3d_triangle_count(h); f++) {
        const double *a = v + 3 * t[3 * f], *b = v + 3 * t[3 * f + 1], *c = v + 3 * t[3 * f + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double nn[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double len = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
        if (!(len > 0)) return 0; /* no sliver: the points here are on the snapping grid */
        for (size_t i = 0; i < n; i++) {
            const double *q = p + 3 * i;
            if ((nn[0] * (q[0] - a[0]) + nn[1] * (q[1] - a[1]) + nn[2] * (q[2] - a[2])) / len > tol) return 0;
        }
    }
    return 1;
}

static void test_hull_cube(void)
{
    size_t n = 8 + 1000 + 600 + 8;
    double *p = malloc(3 * n * sizeof(double));
    size_t k = 0;
    for (int i = 0; i < 8; i++, k++)
        for (int j = 0; j < 3; j++) p[3 * k + j] = (i >> j) & 1;
    for (int i = 0; i < 1000; i++, k++) /* interior */
        for (int j = 0; j < 3; j++) p[3 * k + j] = u01();
    for (int i = 0; i < 600; i++, k++) { /* on the faces: coplanar with the hull's triangles */
        int ax = i % 3, hi = (i / 3) % 2;
        for (int j = 0; j < 3; j++) p[3 * k + j] = j == ax ? hi : u01();
    }
    for (int i = 0; i < 8; i++, k++) /* duplicates of the corners */
        for (int j = 0; j < 3; j++) p[3 * k + j] = (i >> j) & 1;
    /* shuffle so that the corners come anywhere */
    for (size_t i = n - 1; i > 0; i--) {
        size_t j = (size_t)(u01() * (i + 1));
        for (int c = 0; c < 3; c++) {
            double t = p[3 * i + c];
            p[3 * i + c] = p[3 * j + c];
            p[3 * j + c] = t;
        }
    }
    double v;
    gp_error err;
    CHECK(gp_mesh3d_hull_volume(p, n, &v, &err) == GP_OK);
    CHECK_NEAR(v, 1, 1e-12);
    gp_mesh3d *h = gp_mesh3d_hull(p, n, &err);
    CHECK(h != NULL);
    if (h) {
        /* its vertices are the corners and face points (the faces are triangulated through
         * face points that were hull vertices before the corners came), none inside */
        const double *hv = gp_mesh3d_vertices(h);
        int corners = 0, inside = 0;
        for (size_t i = 0; i < gp_mesh3d_vertex_count(h); i++) {
            int on = 0;
            for (int j = 0; j < 3; j++) on += hv[3 * i + j] == 0 || hv[3 * i + j] == 1;
            corners += on == 3;
            inside += on == 0;
        }
        printf("hull of a cube's corners, 1,000 interior and 600 face points: %zu vertices, %zu triangles\n",
               gp_mesh3d_vertex_count(h), gp_mesh3d_triangle_count(h));
        CHECK(corners == 8 && inside == 0);
        CHECK(hull_contains(h, p, n, 1e-15));
        gp_mesh3d_destroy(h);
    }
    free(p);
}

static void test_hull_sphere_and_star(void)
{
    gp_mesh3d *m = gp_mesh3d_icosphere(4, NULL);
    size_t nv = gp_mesh3d_vertex_count(m), nt = gp_mesh3d_triangle_count(m);
    const double *x = gp_mesh3d_vertices(m);
    gp_mesh3d_mass ms;
    gp_mesh3d_mass_properties(x, nv, gp_mesh3d_triangles(m), nt, &ms, NULL);
    double v = 0, t0 = now();
    int reps = 200;
    for (int r = 0; r < reps; r++) CHECK(gp_mesh3d_hull_volume(x, nv, &v, NULL) == GP_OK);
    double dt = (now() - t0) / reps;
    printf("hull of the 2,562 vertices of the level-4 icosphere: %.3f ms\n", 1e3 * dt);
    CHECK_REL(v, ms.volume, 1e-13); /* the icosphere polyhedron is convex */
    gp_mesh3d *h = gp_mesh3d_hull(x, nv, NULL);
    CHECK(h && gp_mesh3d_vertex_count(h) == nv && gp_mesh3d_triangle_count(h) == nt);
    CHECK(h && hull_contains(h, x, nv, 1e-14));
    gp_mesh3d_destroy(h);
    /* a star: the 12 icosahedron vertices pushed out to radius 2, the others at 1 (level 3) */
    gp_mesh3d *s3 = gp_mesh3d_icosphere(3, NULL);
    size_t n3 = gp_mesh3d_vertex_count(s3);
    double *y = malloc(3 * n3 * sizeof(double));
    memcpy(y, gp_mesh3d_vertices(s3), 3 * n3 * sizeof(double));
    for (size_t i = 0; i < 12; i++)
        for (int k = 0; k < 3; k++) y[3 * i + k] *= 2;
    gp_mesh3d_mass sm;
    CHECK(gp_mesh3d_mass_properties(y, n3, gp_mesh3d_triangles(s3), gp_mesh3d_triangle_count(s3), &sm, NULL) == GP_OK);
    double hv;
    CHECK(gp_mesh3d_hull_volume(y, n3, &hv, NULL) == GP_OK);
    printf("star: volume %.4f, hull %.4f, convexity %.3f\n", sm.volume, hv, sm.volume / hv);
    CHECK(hv > 1.3 * sm.volume);
    h = gp_mesh3d_hull(y, n3, NULL);
    CHECK(h && hull_contains(h, y, n3, 1e-14));
    if (h) { /* the hull of the hull's vertices is the same */
        double hv2;
        gp_mesh3d_hull_volume(gp_mesh3d_vertices(h), gp_mesh3d_vertex_count(h), &hv2, NULL);
        CHECK_REL(hv2, hv, 1e-14);
        gp_mesh3d_mass hm;
        CHECK(gp_mesh3d_mass_properties(gp_mesh3d_vertices(h), gp_mesh3d_vertex_count(h), gp_mesh3d_triangles(h),
                                        gp_mesh3d_triangle_count(h), &hm, NULL) == GP_OK);
        CHECK_REL(hm.volume, hv, 1e-13);
    }
    gp_mesh3d_destroy(h);
    free(y);
    gp_mesh3d_destroy(s3);
    gp_mesh3d_destroy(m);
}

static void test_hull_random(void)
{
    size_t n = 10000;
    double *p = malloc(3 * n * sizeof(double));
    for (size_t i = 0; i < n; i++) { /* in a ball, a tenth of them on its sphere */
        double q[3], r2;
        do {
            for (int k = 0; k < 3; k++) q[k] = 2 * u01() - 1;
            r2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
        } while (r2 > 1 || r2 < 1e-6);
        double s = i % 10 == 0 ? 1 / sqrt(r2) : 1;
        for (int k = 0; k < 3; k++) p[3 * i + k] = q[k] * s;
    }
    double t0 = now(), v;
    CHECK(gp_mesh3d_hull_volume(p, n, &v, NULL) == GP_OK);
    printf("hull of 10,000 random points (1,000 on the sphere): %.2f ms, volume %.4f\n", 1e3 * (now() - t0), v);
    gp_mesh3d *h = gp_mesh3d_hull(p, n, NULL);
    CHECK(h && hull_contains(h, p, n, 1e-14));
    if (h) {
        size_t V = gp_mesh3d_vertex_count(h), F = gp_mesh3d_triangle_count(h);
        CHECK(V - 3 * F / 2 + F == 2); /* Euler */
        CHECK(V >= 1000);
    }
    gp_mesh3d_destroy(h);
    CHECK(v < 4.0 / 3.0 * PI && v > 0.97 * 4.0 / 3.0 * PI);
    /* a lattice: many coplanar and collinear points */
    size_t k = 0;
    for (int i = 0; i < 10; i++)
        for (int j = 0; j < 10; j++)
            for (int l = 0; l < 10; l++, k++) {
                p[3 * k] = i;
                p[3 * k + 1] = j;
                p[3 * k + 2] = l;
            }
    CHECK(gp_mesh3d_hull_volume(p, 1000, &v, NULL) == GP_OK);
    CHECK_NEAR(v, 729, 1e-9);
    /* 300 random subsets of a small lattice (duplicates, coplanar and collinear points
     * everywhere), some scaled by 2^-23 or moved by 1e6: the hull is closed, made of the points,
     * and holds them all (so it is their convex hull), its volume its mesh's */
    int good = 1, flat = 0;
    for (int trial = 0; trial < 300; trial++) {
        size_t m = 4 + (size_t)(u01() * 120);
        double sc = trial % 3 == 0 ? ldexp(1, -23) : 1, off = trial % 3 && trial % 5 == 0 ? 1e6 : 0;
        for (size_t i = 0; i < 3 * m; i++) p[i] = off + sc * (double)(int)(u01() * 4);
        gp_error err;
        gp_mesh3d *h = gp_mesh3d_hull(p, m, &err);
        if (!h) {
            flat++;
            good &= err.code == GP_ERR_DEGENERATE;
            continue;
        }
        double hv;
        gp_mesh3d_mass hm;
        int g1 = hull_contains(h, p, m, 1e-12 * sc);
        int g2 = gp_mesh3d_hull_volume(p, m, &hv, NULL) == GP_OK;
        int g3 = gp_mesh3d_mass_properties(gp_mesh3d_vertices(h), gp_mesh3d_vertex_count(h), gp_mesh3d_triangles(h),
                                           gp_mesh3d_triangle_count(h), &hm, NULL) == GP_OK;
        int g4 = fabs(hm.volume - hv) <= 1e-9 * hv;
        /* a lattice polytope's volume is a multiple of 1/6 */
        double k = hv / (sc * sc * sc) * 6;
        int g5 = fabs(k - round(k)) < 1e-6;
        if (!(g1 && g2 && g3 && g4 && g5))
            printf("lattice trial %d (%zu points, scale %g, offset %g): %d %d %d %d %d, volume %.17g\n", trial, m, sc, off,
                   g1, g2, g3, g4, g5, hv);
        good &= g1 && g2 && g3 && g4 && g5;
        gp_mesh3d_destroy(h);
    }
    printf("300 lattice subsets: %d flat, the others' hulls checked\n", flat);
    CHECK(good);
    free(p);
}

static void test_hull_degenerate(void)
{
    double p[3 * 50] = {0};
    gp_error err;
    double v = -1;
    CHECK(gp_mesh3d_hull_volume(p, 0, &v, &err) == GP_OK && v == 0);
    for (int i = 0; i < 50; i++) { /* coplanar: z = x + y */
        p[3 * i] = u01();
        p[3 * i + 1] = u01();
        p[3 * i + 2] = p[3 * i] + p[3 * i + 1];
    }
    v = -1;
    CHECK(gp_mesh3d_hull_volume(p, 50, &v, &err) == GP_OK && fabs(v) < 1e-12);
    for (int i = 0; i < 50; i++) { /* z = 0 exactly */
        p[3 * i + 2] = 0;
    }
    CHECK(gp_mesh3d_hull_volume(p, 50, &v, &err) == GP_OK && v == 0);
    CHECK(gp_mesh3d_hull(p, 50, &err) == NULL && err.code == GP_ERR_DEGENERATE);
    for (int i = 0; i < 50; i++) /* collinear */
        p[3 * i] = p[3 * i + 1] = p[3 * i + 2] = i;
    CHECK(gp_mesh3d_hull_volume(p, 50, &v, &err) == GP_OK && v == 0);
    for (int i = 0; i < 150; i++) p[i] = 7; /* one point */
    CHECK(gp_mesh3d_hull_volume(p, 50, &v, &err) == GP_OK && v == 0);
    p[7] = NAN;
    CHECK(gp_mesh3d_hull_volume(p, 50, &v, &err) == GP_ERR_INVALID);
}

static void test_far(void)
{
    gp_mesh3d *m = gp_mesh3d_icosphere(4, NULL);
    size_t nv = gp_mesh3d_vertex_count(m), nt = gp_mesh3d_triangle_count(m);
    double o0[3] = {0, 0, 0}, o1[3] = {1e6, -2e6, 3e6};
    double *x = scaled(m, 1, 0.7, 0.4, o0), *y = scaled(m, 1, 0.7, 0.4, o1);
    gp_mesh3d_mass a, b;
    CHECK(gp_mesh3d_mass_properties(x, nv, gp_mesh3d_triangles(m), nt, &a, NULL) == GP_OK);
    CHECK(gp_mesh3d_mass_properties(y, nv, gp_mesh3d_triangles(m), nt, &b, NULL) == GP_OK);
    double dI = rel9(b.inertia, a.inertia);
    printf("moved by 1e6: volume %.1e, inertia %.1e, area %.1e, centroid %.1e (relative)\n",
           fabs(b.volume - a.volume) / a.volume, dI, fabs(b.area - a.area) / a.area,
           fmax(fabs(b.centroid[0] - o1[0] - a.centroid[0]), fabs(b.centroid[2] - o1[2] - a.centroid[2])));
    CHECK_REL(b.volume, a.volume, 1e-9);
    CHECK_REL(b.area, a.area, 1e-9);
    CHECK(dI < 1e-9);
    for (int k = 0; k < 3; k++) CHECK_NEAR(b.centroid[k] - o1[k], a.centroid[k], 1e-9);
    double ha, hb;
    CHECK(gp_mesh3d_hull_volume(x, nv, &ha, NULL) == GP_OK);
    CHECK(gp_mesh3d_hull_volume(y, nv, &hb, NULL) == GP_OK);
    CHECK_REL(hb, ha, 1e-9);
    CHECK_REL(ha, a.volume, 1e-12);
    free(x);
    free(y);
    gp_mesh3d_destroy(m);
}

static void test_bad_meshes(void)
{
    double x[24];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) x[3 * i + k] = (i >> k) & 1;
    uint32_t t[36];
    gp_error err;
    gp_mesh3d_mass m;
    memcpy(t, cube_tri, sizeof t);
    CHECK(gp_mesh3d_check(8, t, 11, &err) == GP_ERR_INVALID); /* open */
    gp_mesh3d *c = gp_mesh3d_create(x, 8, t, 12, &err);
    CHECK(c != NULL && gp_mesh3d_vertex_count(c) == 8 && gp_mesh3d_triangle_count(c) == 12);
    gp_mesh3d_destroy(c);
    CHECK(gp_mesh3d_create(x, 8, t, 11, &err) == NULL && err.code == GP_ERR_INVALID);
    t[5] = t[4]; /* a repeated vertex */
    CHECK(gp_mesh3d_check(8, t, 12, &err) == GP_ERR_INVALID);
    memcpy(t, cube_tri, sizeof t);
    uint32_t s = t[1]; /* one triangle flipped: inconsistent orientation */
    t[1] = t[2];
    t[2] = s;
    CHECK(gp_mesh3d_check(8, t, 12, &err) == GP_ERR_INVALID);
    memcpy(t, cube_tri, sizeof t);
    t[3] = 8;
    CHECK(gp_mesh3d_check(8, t, 12, &err) == GP_ERR_INVALID);
    CHECK(gp_mesh3d_mass_properties(x, 8, t, 12, &m, &err) == GP_ERR_INVALID);
    for (int i = 0; i < 12; i++) { /* inside out */
        t[3 * i] = cube_tri[3 * i];
        t[3 * i + 1] = cube_tri[3 * i + 2];
        t[3 * i + 2] = cube_tri[3 * i + 1];
    }
    CHECK(gp_mesh3d_check(8, t, 12, &err) == GP_OK);
    CHECK(gp_mesh3d_mass_properties(x, 8, t, 12, &m, &err) == GP_ERR_DEGENERATE);
    x[4] = NAN;
    CHECK(gp_mesh3d_mass_properties(x, 8, cube_tri, 12, &m, &err) == GP_ERR_INVALID);
    CHECK(gp_mesh3d_create(x, 8, cube_tri, 12, &err) == NULL && err.code == GP_ERR_INVALID);
}

int main(void)
{
    test_icosphere();
    test_convergence("sphere", 1, 1, 1);
    test_convergence("ellipsoid", 1, 0.7, 0.4);
    test_boxes();
    test_eigen();
    test_hull_cube();
    test_hull_sphere_and_star();
    test_hull_random();
    test_hull_degenerate();
    test_far();
    test_bad_meshes();
    return gp_test_summary();
}
