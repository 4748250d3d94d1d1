/* test_voronoi3d.c -- the bounded 3D Voronoi tessellation: exact cells on a lattice, volumes
 * that sum to the container (box, convex polyhedra, cylinder prism), the container queries
 * (bounds, inside) against the tessellation's own test, scale invariance, bad inputs, and
 * local moves against full rebuilds: on random seeds (box, cylinder) every cell
 * bit for bit after every move (memcmp of vertices, loops, neighbour ids, volume, centroid
 * and inertia); on a lattice kept degenerate, to 1e-12 (gp_voronoi3d.h, "Local updates"). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_test.h"
#include "gp_voronoi3d.h"

static uint64_t rng_state = 88172645463325252ull;

static double u01(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static double volume_sum(const gp_voronoi3d *v)
{
    double s = 0;
    for (size_t i = 0; i < gp_voronoi3d_count(v); i++) s += gp_voronoi3d_cell_volume(v, i);
    return s;
}

/* Area of face f of cell i. */
static double face_area(const gp_voronoi3d *v, size_t i, size_t f)
{
    size_t nv = gp_voronoi3d_cell_vertices(v, i, NULL, 0);
    double *x = malloc(3 * nv * sizeof(double)), s[3] = {0, 0, 0};
    uint32_t loop[256];
    gp_voronoi3d_cell_vertices(v, i, x, nv);
    size_t m = gp_voronoi3d_cell_face(v, i, f, loop, 256, NULL);
    const double *p0 = x + 3 * loop[0];
    for (size_t k = 1; k + 1 < m && m <= 256; k++) {
        const double *p = x + 3 * loop[k], *q = x + 3 * loop[k + 1];
        double u[3] = {p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]};
        double w[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
        s[0] += u[1] * w[2] - u[2] * w[1];
        s[1] += u[2] * w[0] - u[0] * w[2];
        s[2] += u[0] * w[1] - u[1] * w[0];
    }
    free(x);
    return 0.5 * sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
}

/* 1 when cell j has a face on seed i */
static int has_neighbour(const gp_voronoi3d *v, size_t j, size_t i)
{
    size_t nb[512], c = gp_voronoi3d_neighbours(v, j, nb, 512);
    for (size_t q = 0; q < c; q++)
        if (nb[q] == i) return 1;
    return 0;
}

/* Every face has >= 3 vertices, the faces come in increasing neighbour id (one per plane),
 * every edge of a cell is used once in each direction (a closed, consistently oriented
 * surface), and every neighbour relation is mutual -- except
 * that a face of area below sliver times the cell's volume^(2/3) may be one-sided: with many
 * planes through one point (co-spherical seeds), rounding leaves slivers of ~1e-20 that
 * only one of the two cells resolves. */
static int cells_consistent(const gp_voronoi3d *v, double sliver)
{
    size_t n = gp_voronoi3d_count(v), slivers = 0;
    uint32_t loop[256];
    for (size_t i = 0; i < n; i++) {
        size_t nf = gp_voronoi3d_cell_face_count(v, i), nv = gp_voronoi3d_cell_vertices(v, i, NULL, 0);
        unsigned char *use = calloc(nv * nv, 1);
        int ok = 1;
        int32_t prev = INT32_MIN;
        for (size_t f = 0; f < nf && ok; f++) {
            int32_t id;
            size_t m = gp_voronoi3d_cell_face(v, i, f, loop, 256, &id);
            ok &= m >= 3 && m <= 256 && (f == 0 || id > prev);
            prev = id;
            for (size_t k = 0; k < m && ok; k++) {
                uint32_t a = loop[k], b = loop[(k + 1) % m];
                ok &= a < nv && b < nv && !use[a * nv + b];
                if (ok) use[a * nv + b] = 1;
            }
        }
        for (size_t a = 0; a < nv && ok; a++)
            for (size_t b = 0; b < nv; b++) ok &= !use[a * nv + b] || use[b * nv + a];
        free(use);
        if (!ok) return 0;
        double scale = pow(gp_voronoi3d_cell_volume(v, i), 2.0 / 3.0);
        for (size_t f = 0; f < nf; f++) {
            int32_t j;
            gp_voronoi3d_cell_face(v, i, f, NULL, 0, &j);
            if (j < 0 || has_neighbour(v, (size_t)j, i)) continue;
            if (face_area(v, i, f) >= sliver * scale) return 0;
            slivers++;
        }
    }
    if (slivers) printf("%zu one-sided sliver faces (area < %g of the cell)\n", slivers, sliver);
    return 1;
}

static double *random_seeds(size_t n, const double lo[3], const double hi[3])
{
    double *s = malloc(3 * n * sizeof(double));
    for (size_t i = 0; i < 3 * n; i++) s[i] = lo[i % 3] + (hi[i % 3] - lo[i % 3]) * u01();
    return s;
}

/* k^3 seeds at the centres of the cells of a k x k x k lattice over [0, a]^3: every cell is a
 * cube of side a / k (6 faces, 8 vertices), with the diagonal neighbours' planes through its
 * edges and corners (degenerate on purpose). */
static void test_lattice(size_t k, double a, double off)
{
    size_t n = k * k * k;
    double *s = malloc(3 * n * sizeof(double)), h = a / (double)k;
    for (size_t i = 0; i < n; i++) {
        s[3 * i] = off + h * ((double)(i % k) + 0.5);
        s[3 * i + 1] = off + h * ((double)(i / k % k) + 0.5);
        s[3 * i + 2] = off + h * ((double)(i / k / k) + 0.5);
    }
    double lo[3] = {off, off, off}, hi[3] = {off + a, off + a, off + a};
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    gp_error err;
    gp_voronoi3d *v = gp_voronoi3d_create(&c, s, n, &err);
    CHECK(v != NULL);
    if (!v) {
        fprintf(stderr, "%s\n", err.message);
        free(s);
        return;
    }
    int faces_ok = 1, verts_ok = 1, vol_ok = 1, in_ok = 1;
    double cube = h * h * h;
    for (size_t i = 0; i < n; i++) {
        faces_ok &= gp_voronoi3d_cell_face_count(v, i) == 6;
        verts_ok &= gp_voronoi3d_cell_vertices(v, i, NULL, 0) == 8;
        vol_ok &= fabs(gp_voronoi3d_cell_volume(v, i) - cube) <= 1e-12 * cube;
        double I[9], g[3];
        gp_voronoi3d_cell_inertia(v, i, I);
        gp_voronoi3d_cell_centroid(v, i, g);
        double want = cube * h * h / 6;
        in_ok &= fabs(I[0] - want) <= 1e-9 * want && fabs(I[4] - want) <= 1e-9 * want &&
                 fabs(I[8] - want) <= 1e-9 * want && fabs(I[1]) <= 1e-9 * want;
        for (int q = 0; q < 3; q++) in_ok &= fabs(g[q] - s[3 * i + q]) <= 1e-9 * (fabs(off) + a);
    }
    CHECK(faces_ok);
    CHECK(verts_ok);
    CHECK(vol_ok);
    CHECK(in_ok);
    CHECK_REL(volume_sum(v), a * a * a, 1e-12);
    CHECK(cells_consistent(v, 0));
    gp_voronoi3d_destroy(v);
    free(s);
}

/* 1 when cell i touches a wall */
static int on_wall(const gp_voronoi3d *v, size_t i)
{
    for (size_t f = 0; f < gp_voronoi3d_cell_face_count(v, i); f++) {
        int32_t nb;
        gp_voronoi3d_cell_face(v, i, f, NULL, 0, &nb);
        if (nb < 0) return 1;
    }
    return 0;
}

/* Degenerate inputs: an FCC lattice (rhombic dodecahedra, 6 cells at some vertices) and seeds
 * all on one sphere (every cell reaches the centre: one vertex shared by all), with and
 * without a seed at the centre. */
static void test_degenerate(void)
{
    size_t k = 4, n = 4 * k * k * k, m = 0;
    double *s = malloc(3 * n * sizeof(double));
    static const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
    for (size_t c = 0; c < k * k * k; c++)
        for (int b = 0; b < 4; b++, m++) {
            s[3 * m] = (double)(c % k) + 0.25 + basis[b][0];
            s[3 * m + 1] = (double)(c / k % k) + 0.25 + basis[b][1];
            s[3 * m + 2] = (double)(c / k / k) + 0.25 + basis[b][2];
        }
    double lo[3] = {0, 0, 0}, hi[3] = {4, 4, 4};
    gp_voronoi3d_container box = gp_voronoi3d_box(lo, hi);
    gp_voronoi3d *v = gp_voronoi3d_create(&box, s, n, NULL);
    CHECK(v != NULL);
    size_t inner = 0;
    int ok = 1;
    for (size_t i = 0; v && i < n; i++) {
        if (on_wall(v, i)) continue;
        inner++;
        ok &= fabs(gp_voronoi3d_cell_volume(v, i) - 0.25) <= 1e-12 * 0.25;
        ok &= gp_voronoi3d_cell_face_count(v, i) == 12;
    }
    CHECK(ok);
    CHECK(inner > 50);
    CHECK(v && cells_consistent(v, 0));
    CHECK_REL(volume_sum(v), 64, 1e-12);
    gp_voronoi3d_destroy(v);
    free(s);

    n = 301;
    s = malloc(3 * n * sizeof(double));
    for (size_t i = 0; i < n - 1; i++) {
        double z = 2 * u01() - 1, t = 2 * M_PI * u01(), r = sqrt(1 - z * z);
        s[3 * i] = 0.5 + 0.4 * r * cos(t);
        s[3 * i + 1] = 0.5 + 0.4 * r * sin(t);
        s[3 * i + 2] = 0.5 + 0.4 * z;
    }
    s[3 * (n - 1)] = s[3 * (n - 1) + 1] = s[3 * (n - 1) + 2] = 0.5;
    double ul[3] = {0, 0, 0}, uh[3] = {1, 1, 1};
    gp_voronoi3d_container unit = gp_voronoi3d_box(ul, uh);
    for (size_t cnt = n - 1; cnt <= n; cnt++) {
        v = gp_voronoi3d_create(&unit, s, cnt, NULL);
        CHECK(v != NULL);
        CHECK(v && cells_consistent(v, 1e-12));
        CHECK_REL(volume_sum(v), 1, 1e-12);
        gp_voronoi3d_destroy(v);
    }
    free(s);
}

/* n random seeds in container c (drawn in its bounding box [lo, hi], kept when inside). */
static gp_voronoi3d *random_in(const gp_voronoi3d_container *c, size_t n, const double lo[3],
                               const double hi[3], double **seeds)
{
    /* a tessellation of one seed to ask gp_voronoi3d_contains() */
    gp_voronoi3d *probe = NULL;
    for (int t = 0; t < 1000 && !probe; t++) {
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = lo[a] + (hi[a] - lo[a]) * u01();
        probe = gp_voronoi3d_create(c, p, 1, NULL);
    }
    double *s = malloc(3 * n * sizeof(double));
    size_t m = 0;
    while (probe && m < n) {
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = lo[a] + (hi[a] - lo[a]) * u01();
        if (gp_voronoi3d_contains(probe, p)) memcpy(s + 3 * m++, p, sizeof p);
    }
    gp_voronoi3d_destroy(probe);
    gp_error err;
    gp_voronoi3d *v = gp_voronoi3d_create(c, s, n, &err);
    if (!v) fprintf(stderr, "create: %s\n", err.message);
    *seeds = s;
    return v;
}

static void test_containers(void)
{
    double lo[3] = {-1, 0, 2}, hi[3] = {2, 1, 4}, *s;
    gp_voronoi3d_container box = gp_voronoi3d_box(lo, hi);
    gp_voronoi3d *v = random_in(&box, 2000, lo, hi, &s);
    CHECK(v != NULL);
    CHECK_REL(gp_voronoi3d_container_volume(v), 6.0, 1e-15);
    CHECK_REL(volume_sum(v), 6.0, 1e-12);
    CHECK(cells_consistent(v, 0));
    gp_voronoi3d_destroy(v);
    free(s);

    /* tetrahedron x, y, z >= 0, x + y + z <= 1, given scaled and with a redundant plane */
    const double tet[5 * 4] = {-2, 0, 0, 0, 0, -1, 0, 0, 0, 0, -3, 0, 1, 1, 1, 1, 1, 1, 1, 5};
    gp_voronoi3d_container ct = gp_voronoi3d_convex(tet, 5);
    double tlo[3] = {0, 0, 0}, thi[3] = {1, 1, 1};
    v = random_in(&ct, 500, tlo, thi, &s);
    CHECK(v != NULL);
    CHECK_REL(gp_voronoi3d_container_volume(v), 1.0 / 6, 1e-14);
    CHECK_REL(volume_sum(v), 1.0 / 6, 1e-12);
    CHECK(cells_consistent(v, 0));
    gp_voronoi3d_destroy(v);
    free(s);

    /* octahedron |x| + |y| + |z| <= 2 around (10, -5, 3): volume 4 r^3 / 3 = 32 / 3 */
    double oct[8 * 4];
    for (int k = 0; k < 8; k++) {
        double n[3] = {k & 1 ? -1 : 1, k & 2 ? -1 : 1, k & 4 ? -1 : 1};
        memcpy(oct + 4 * k, n, sizeof n);
        oct[4 * k + 3] = 2 + n[0] * 10 + n[1] * -5 + n[2] * 3;
    }
    gp_voronoi3d_container co = gp_voronoi3d_convex(oct, 8);
    double olo[3] = {8, -7, 1}, ohi[3] = {12, -3, 5};
    v = random_in(&co, 800, olo, ohi, &s);
    CHECK(v != NULL);
    CHECK_REL(gp_voronoi3d_container_volume(v), 32.0 / 3, 1e-14);
    CHECK_REL(volume_sum(v), 32.0 / 3, 1e-12);
    CHECK(cells_consistent(v, 0));
    gp_voronoi3d_destroy(v);
    free(s);

    /* cylinder r = 0.5, h = 2, 64 facets: the prism loses pi r^2 h - 32 r^2 sin(pi / 32) h */
    for (size_t facets = 0; facets <= 12; facets += 12) {
        double r = 0.5, h = 2, m = facets ? 12 : 64;
        gp_voronoi3d_container cc = gp_voronoi3d_cylinder(1, 2, r, -1, 1, facets);
        double clo[3] = {0.5, 1.5, -1}, chi[3] = {1.5, 2.5, 1};
        v = random_in(&cc, 1000, clo, chi, &s);
        CHECK(v != NULL);
        double prism = 0.5 * m * r * r * sin(2 * M_PI / m) * h;
        CHECK_REL(gp_voronoi3d_container_volume(v), prism, 1e-13);
        CHECK_REL(gp_voronoi3d_lost_volume(v), M_PI * r * r * h - prism, 1e-10);
        CHECK_REL(gp_voronoi3d_cylinder_lost_volume(r, h, facets), M_PI * r * r * h - prism, 1e-12);
        CHECK_REL(volume_sum(v), prism, 1e-12);
        CHECK(cells_consistent(v, 0));
        gp_voronoi3d_destroy(v);
        free(s);
    }
    /* 64 facets lose about (2 pi^3 / 3) / 64^2 of the cylinder */
    double lost = gp_voronoi3d_cylinder_lost_volume(1, 1, 64) / M_PI;
    CHECK(lost > 0.0015 && lost < 0.0017);
}

/* test_container_queries()' own random numbers (the other tests' stay as they were) */
static uint64_t rngq_state = 0x9E3779B97F4A7C15ull;

static double u01q(void)
{
    rngq_state ^= rngq_state << 13;
    rngq_state ^= rngq_state >> 7;
    rngq_state ^= rngq_state << 17;
    return (double)(rngq_state >> 11) * (1.0 / 9007199254740992.0);
}

/* One container for test_container_queries(): its bounds are checked against want_lo and
 * want_hi (to rel of its size; skipped when want_lo is NULL), then gp_voronoi3d_container_inside()
 * against gp_voronoi3d_contains() of a tessellation of the container (the test create applies)
 * on points spread over the bounds and on points within a few tolerances of its faces. */
static void container_query(const char *name, const gp_voronoi3d_container *c, const double *want_lo,
                            const double *want_hi, double rel)
{
    double lo[3], hi[3];
    gp_error err;
    CHECK(gp_voronoi3d_container_bounds(c, lo, hi, &err) == GP_OK);
    double L[3], size = 0;
    for (int a = 0; a < 3; a++) {
        L[a] = hi[a] - lo[a];
        size += L[a] * L[a];
    }
    size = sqrt(size);
    for (int a = 0; a < 3 && want_lo; a++) {
        CHECK_NEAR(lo[a], want_lo[a], rel * size);
        CHECK_NEAR(hi[a], want_hi[a], rel * size);
    }
    /* a tessellation of one seed found by the query, to ask gp_voronoi3d_contains() */
    gp_voronoi3d *probe = NULL;
    for (int t = 0; t < 1000 && !probe; t++) {
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = lo[a] + L[a] * u01q();
        if (gp_voronoi3d_container_inside(c, lo, hi, p)) probe = gp_voronoi3d_create(c, p, 1, NULL);
    }
    CHECK(probe != NULL);
    if (!probe) return;
    /* the faces' planes (unit normals), to put points near them */
    size_t m = c->kind == GP_VORONOI3D_BOX ? 6
               : c->kind == GP_VORONOI3D_CONVEX ? c->nplanes
                                                : (c->facets ? c->facets : 64) + 2;
    double *pl = malloc(4 * m * sizeof(double));
    for (size_t k = 0; k < m; k++) {
        double *q = pl + 4 * k;
        if (c->kind == GP_VORONOI3D_BOX) {
            q[0] = q[1] = q[2] = 0;
            q[k / 2] = k & 1 ? 1 : -1;
            q[3] = k & 1 ? c->hi[k / 2] : -c->lo[k / 2];
        } else if (c->kind == GP_VORONOI3D_CONVEX) {
            double nn = sqrt(c->planes[4 * k] * c->planes[4 * k] + c->planes[4 * k + 1] * c->planes[4 * k + 1] +
                             c->planes[4 * k + 2] * c->planes[4 * k + 2]);
            for (int a = 0; a < 4; a++) q[a] = c->planes[4 * k + a] / nn;
        } else if (k + 2 < m) {
            double t = 2 * M_PI * ((double)k + 0.5) / (double)(m - 2);
            q[0] = cos(t), q[1] = sin(t), q[2] = 0;
            q[3] = q[0] * c->axis[0] + q[1] * c->axis[1] + c->radius * cos(M_PI / (double)(m - 2));
        } else {
            q[0] = q[1] = 0, q[2] = k + 1 == m ? 1 : -1;
            q[3] = k + 1 == m ? c->z1 : -c->z0;
        }
    }
    const double off[7] = {-3, -1.5, -0.5, 0, 0.5, 1.5, 3}; /* in tolerances (1e-12 size) */
    size_t n = 20000, same = 0, in = 0, near = 0;
    for (size_t t = 0; t < n; t++) {
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = lo[a] + L[a] * (1.02 * u01q() - 0.01);
        if (t & 1) { /* onto a face's plane, then off it by a few tolerances */
            const double *q = pl + 4 * (size_t)(u01q() * (double)m);
            double h = q[0] * p[0] + q[1] * p[1] + q[2] * p[2] - q[3] - off[t / 2 % 7] * 1e-12 * size;
            for (int a = 0; a < 3; a++) p[a] -= h * q[a];
            near++;
        }
        int a = gp_voronoi3d_container_inside(c, lo, hi, p), b = gp_voronoi3d_contains(probe, p);
        same += a == b;
        in += a;
    }
    printf("container queries (%s): %zu of %zu points (%zu within 3e-12 of a face's plane) agree "
           "with gp_voronoi3d_contains, %zu inside\n", name, same, n, near, in);
    CHECK(same == n);
    CHECK(in > n / 20 && in < n - n / 100);
    double nan[3] = {NAN, 0, 0}, inf[3] = {INFINITY, lo[1], lo[2]};
    CHECK(!gp_voronoi3d_container_inside(c, lo, hi, nan));
    CHECK(!gp_voronoi3d_container_inside(c, lo, hi, inf));
    free(pl);
    gp_voronoi3d_destroy(probe);
}

/* gp_voronoi3d_container_bounds() and gp_voronoi3d_container_inside(), which need no
 * tessellation: the bounds of every kind of container, near the origin and far from it, and
 * the inside test equal to the one create applies; bad containers refused. */
static void test_container_queries(void)
{
    double blo[3] = {-1, 0, 2}, bhi[3] = {2, 1, 4};
    gp_voronoi3d_container box = gp_voronoi3d_box(blo, bhi);
    container_query("box", &box, blo, bhi, 0);
    double flo[3] = {1e6, -2e6, 3e6}, fhi[3] = {1e6 + 1, -2e6 + 0.5, 3e6 + 2};
    gp_voronoi3d_container far = gp_voronoi3d_box(flo, fhi);
    container_query("box at 1e6", &far, flo, fhi, 0);
    /* tetrahedron x, y, z >= 0, x + y + z <= 1, scaled planes and a redundant one */
    const double tet[5 * 4] = {-2, 0, 0, 0, 0, -1, 0, 0, 0, 0, -3, 0, 1, 1, 1, 1, 1, 1, 1, 5};
    gp_voronoi3d_container ct = gp_voronoi3d_convex(tet, 5);
    double tlo[3] = {0, 0, 0}, thi[3] = {1, 1, 1};
    container_query("tetrahedron", &ct, tlo, thi, 1e-14);
    /* octahedron |x| + |y| + |z| <= 2 around (10, -5, 3), and around (1e6, -1e6, 1e6) */
    for (int shift = 0; shift < 2; shift++) {
        double ctr[3] = {10, -5, 3}, oct[8 * 4], olo[3], ohi[3];
        for (int a = 0; a < 3 && shift; a++) ctr[a] = a == 1 ? -1e6 : 1e6;
        for (int k = 0; k < 8; k++) {
            double nrm[3] = {k & 1 ? -1 : 1, k & 2 ? -1 : 1, k & 4 ? -1 : 1};
            memcpy(oct + 4 * k, nrm, sizeof nrm);
            oct[4 * k + 3] = 2 + nrm[0] * ctr[0] + nrm[1] * ctr[1] + nrm[2] * ctr[2];
        }
        for (int a = 0; a < 3; a++) olo[a] = ctr[a] - 2, ohi[a] = ctr[a] + 2;
        gp_voronoi3d_container co = gp_voronoi3d_convex(oct, 8);
        container_query(shift ? "octahedron at 1e6" : "octahedron", &co, olo, ohi, shift ? 1e-9 : 1e-14);
    }
    /* cylinders: 64 facets (a vertex at every quarter turn: the circle's bounds), 5 facets
     * (the bounds of the pentagon's vertices at 2 pi k / 5), one far from the origin */
    gp_voronoi3d_container cy = gp_voronoi3d_cylinder(1, 2, 0.5, -1, 1, 0);
    double ylo[3] = {0.5, 1.5, -1}, yhi[3] = {1.5, 2.5, 1};
    container_query("cylinder", &cy, ylo, yhi, 1e-14);
    gp_voronoi3d_container c5 = gp_voronoi3d_cylinder(1, 2, 0.5, -1, 1, 5);
    double plo[3] = {1 + 0.5 * cos(4 * M_PI / 5), 2 + 0.5 * sin(8 * M_PI / 5), -1};
    double phi[3] = {1.5, 2 + 0.5 * sin(2 * M_PI / 5), 1};
    container_query("pentagonal prism", &c5, plo, phi, 1e-14);
    gp_voronoi3d_container cf = gp_voronoi3d_cylinder(1e6, -1e6, 2, 0, 3, 7);
    container_query("cylinder at 1e6", &cf, NULL, NULL, 0);

    /* bad containers: refused, the bounds left alone; nothing inside one with a bad parameter */
    const double wedge[4 * 4] = {-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 1, 1, 0, 1};
    const double empty[4 * 4] = {-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 1, 1, 1, -1};
    gp_voronoi3d_container bad[5] = {gp_voronoi3d_convex(wedge, 4), gp_voronoi3d_convex(empty, 4),
                                     gp_voronoi3d_convex(tet, 3), gp_voronoi3d_cylinder(0, 0, 0, 0, 1, 0),
                                     gp_voronoi3d_box(bhi, blo)};
    for (int k = 0; k < 5; k++) {
        double lo[3] = {7, 7, 7}, hi[3] = {8, 8, 8}, p[3] = {0.1, 0.1, 0.1}, q[3] = {7.5, 7.5, 7.5};
        gp_error err;
        CHECK(gp_voronoi3d_container_bounds(&bad[k], lo, hi, &err) == GP_ERR_INVALID);
        CHECK(lo[0] == 7 && lo[2] == 7 && hi[1] == 8);
        if (k == 2 || k == 3) CHECK(!gp_voronoi3d_container_inside(&bad[k], lo, hi, k < 3 ? p : q));
    }
    double lo[3], hi[3];
    CHECK(gp_voronoi3d_container_bounds(NULL, lo, hi, NULL) == GP_ERR_INVALID);
    CHECK(!gp_voronoi3d_container_inside(NULL, blo, bhi, blo));
}

/* The same seeds scaled by 1e-6 and 1e6, and moved to 1e6: the same cells, scaled. */
static void test_scales(void)
{
    size_t n = 500;
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    double *s = random_seeds(n, lo, hi), *t = malloc(3 * n * sizeof(double));
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    gp_voronoi3d *ref = gp_voronoi3d_create(&c, s, n, NULL);
    CHECK(ref != NULL);
    const double scale[3] = {1e-6, 1e6, 1}, shift[3] = {0, 0, 1e6};
    for (int k = 0; k < 3 && ref; k++) {
        double l2[3], h2[3];
        for (int a = 0; a < 3; a++) l2[a] = shift[k], h2[a] = shift[k] + scale[k];
        for (size_t i = 0; i < 3 * n; i++) t[i] = shift[k] + scale[k] * s[i];
        gp_voronoi3d_container c2 = gp_voronoi3d_box(l2, h2);
        gp_voronoi3d *v = gp_voronoi3d_create(&c2, t, n, NULL);
        CHECK(v != NULL);
        if (!v) continue;
        double V = scale[k] * scale[k] * scale[k], worst = 0;
        int faces = 1;
        for (size_t i = 0; i < n; i++) {
            double a = gp_voronoi3d_cell_volume(v, i) / V, b = gp_voronoi3d_cell_volume(ref, i);
            worst = fmax(worst, fabs(a - b) / b);
            faces &= gp_voronoi3d_cell_face_count(v, i) == gp_voronoi3d_cell_face_count(ref, i);
        }
        /* moved to 1e6, the seeds themselves are rounded at 1e-10 */
        CHECK(worst <= (k == 2 ? 1e-7 : 1e-12));
        CHECK(faces || k == 2);
        CHECK_REL(volume_sum(v), V, 1e-12);
        gp_voronoi3d_destroy(v);
    }
    gp_voronoi3d_destroy(ref);
    free(s);
    free(t);
}

static void test_one_seed(void)
{
    double lo[3] = {0, 0, 0}, hi[3] = {2, 3, 4}, p[3] = {0.5, 0.5, 0.5};
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    gp_voronoi3d *v = gp_voronoi3d_create(&c, p, 1, NULL);
    CHECK(v != NULL);
    CHECK_REL(gp_voronoi3d_cell_volume(v, 0), 24, 1e-15);
    CHECK(gp_voronoi3d_cell_face_count(v, 0) == 6);
    CHECK(gp_voronoi3d_neighbours(v, 0, NULL, 0) == 0);
    int walls = 0;
    for (size_t f = 0; f < 6; f++) {
        int32_t nb = 0;
        gp_voronoi3d_cell_face(v, 0, f, NULL, 0, &nb);
        walls |= nb < 0 && nb >= -6 ? 1 << (-1 - nb) : 0;
    }
    CHECK(walls == 63);
    double g[3];
    gp_voronoi3d_cell_centroid(v, 0, g);
    CHECK_NEAR(g[0], 1, 1e-14);
    CHECK_NEAR(g[2], 2, 1e-14);
    /* a seed on the boundary and a move to a corner */
    double q[3] = {2, 3, 4};
    CHECK(gp_voronoi3d_move(v, 0, q, NULL) == GP_OK);
    CHECK_REL(gp_voronoi3d_cell_volume(v, 0), 24, 1e-15);
    gp_voronoi3d_destroy(v);
    const double tet[4 * 4] = {-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 1, 1, 1, 1};
    gp_voronoi3d_container ct = gp_voronoi3d_convex(tet, 4);
    double in[3] = {0.1, 0.2, 0.3};
    v = gp_voronoi3d_create(&ct, in, 1, NULL);
    CHECK(v != NULL);
    CHECK_REL(gp_voronoi3d_cell_volume(v, 0), 1.0 / 6, 1e-14);
    CHECK(gp_voronoi3d_cell_face_count(v, 0) == 4);
    CHECK(gp_voronoi3d_cell_vertices(v, 0, NULL, 0) == 4);
    gp_voronoi3d_destroy(v);
}

static void test_bad_inputs(void)
{
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    double s[9] = {0.1, 0.2, 0.3, 0.5, 0.5, 0.5, 0.1, 0.2, 0.3};
    gp_error err;
    CHECK(gp_voronoi3d_create(&c, s, 3, &err) == NULL);
    CHECK(err.code == GP_ERR_INVALID && strstr(err.message, "0 and 2"));
    s[8] = 0.3 + 1e-11; /* within 1e-10 of the size */
    CHECK(gp_voronoi3d_create(&c, s, 3, &err) == NULL && err.code == GP_ERR_INVALID);
    s[8] = 1.5;
    CHECK(gp_voronoi3d_create(&c, s, 3, &err) == NULL);
    CHECK(err.code == GP_ERR_INVALID && strstr(err.message, "outside"));
    s[8] = NAN;
    CHECK(gp_voronoi3d_create(&c, s, 3, &err) == NULL && err.code == GP_ERR_INVALID);
    s[8] = 0.9;
    CHECK(gp_voronoi3d_create(&c, s, 0, &err) == NULL && err.code == GP_ERR_INVALID);
    gp_voronoi3d_container bad = gp_voronoi3d_box(hi, lo);
    CHECK(gp_voronoi3d_create(&bad, s, 3, &err) == NULL && err.code == GP_ERR_INVALID);
    /* half-spaces that bound nothing (an open wedge) or an empty set */
    const double wedge[4 * 4] = {-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 1, 1, 0, 1};
    gp_voronoi3d_container cw = gp_voronoi3d_convex(wedge, 4);
    CHECK(gp_voronoi3d_create(&cw, s, 1, &err) == NULL && err.code == GP_ERR_INVALID);
    const double empty[4 * 4] = {-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 1, 1, 1, -1};
    gp_voronoi3d_container ce = gp_voronoi3d_convex(empty, 4);
    CHECK(gp_voronoi3d_create(&ce, s, 1, &err) == NULL && err.code == GP_ERR_INVALID);
    gp_voronoi3d_container cz = gp_voronoi3d_cylinder(0, 0, 0, 0, 1, 0);
    CHECK(gp_voronoi3d_create(&cz, s, 1, &err) == NULL && err.code == GP_ERR_INVALID);
    /* inside the cylinder, outside its prism: refused */
    gp_voronoi3d_container cy = gp_voronoi3d_cylinder(0, 0, 1, 0, 1, 8);
    double rim[3] = {cos(M_PI / 8) * 0.999, sin(M_PI / 8) * 0.999, 0.5};
    CHECK(gp_voronoi3d_create(&cy, rim, 1, &err) == NULL && err.code == GP_ERR_INVALID);
    /* bad moves leave everything as it was */
    gp_voronoi3d *v = gp_voronoi3d_create(&c, s, 3, &err);
    CHECK(v != NULL);
    double vol = gp_voronoi3d_cell_volume(v, 1);
    CHECK(gp_voronoi3d_move(v, 1, (const double[3]){0.1, 0.2, 0.3}, &err) == GP_ERR_INVALID);
    CHECK(gp_voronoi3d_move(v, 1, (const double[3]){0.1, 2, 0.3}, &err) == GP_ERR_INVALID);
    CHECK(gp_voronoi3d_move(v, 7, (const double[3]){0.1, 0.5, 0.3}, &err) == GP_ERR_INVALID);
    CHECK(gp_voronoi3d_try_move(v, 1, (const double[3]){0.6, 0.5, 0.3}, &err) == GP_OK);
    CHECK(gp_voronoi3d_try_move(v, 0, (const double[3]){0.6, 0.6, 0.3}, &err) == GP_ERR_INVALID);
    gp_voronoi3d_rollback(v);
    CHECK(gp_voronoi3d_cell_volume(v, 1) == vol);
    gp_voronoi3d_destroy(v);
}

/* 1 when cell i of a and of b are the same bits: volume, centroid, inertia, the vertices as
 * ordered, every face's loop and neighbour id, the neighbour list. */
static int cell_bits_equal(const gp_voronoi3d *a, const gp_voronoi3d *b, size_t i)
{
    double xa[3 * 512], xb[3 * 512], va = gp_voronoi3d_cell_volume(a, i),
                                      vb = gp_voronoi3d_cell_volume(b, i);
    double ga[3], gb[3], Ia[9], Ib[9];
    gp_voronoi3d_cell_centroid(a, i, ga);
    gp_voronoi3d_cell_centroid(b, i, gb);
    gp_voronoi3d_cell_inertia(a, i, Ia);
    gp_voronoi3d_cell_inertia(b, i, Ib);
    if (memcmp(&va, &vb, sizeof va) || memcmp(ga, gb, sizeof ga) || memcmp(Ia, Ib, sizeof Ia))
        return 0;
    size_t nva = gp_voronoi3d_cell_vertices(a, i, xa, 512), nvb = gp_voronoi3d_cell_vertices(b, i, xb, 512);
    if (nva != nvb || nva > 512 || memcmp(xa, xb, 3 * nva * sizeof(double))) return 0;
    size_t nf = gp_voronoi3d_cell_face_count(a, i);
    if (nf != gp_voronoi3d_cell_face_count(b, i)) return 0;
    for (size_t f = 0; f < nf; f++) {
        uint32_t la[256], lb[256];
        int32_t ja, jb;
        size_t ma = gp_voronoi3d_cell_face(a, i, f, la, 256, &ja);
        size_t mb = gp_voronoi3d_cell_face(b, i, f, lb, 256, &jb);
        if (ma != mb || ma > 256 || ja != jb || memcmp(la, lb, ma * sizeof(uint32_t))) return 0;
    }
    size_t na[512], nb[512];
    size_t ca = gp_voronoi3d_neighbours(a, i, na, 512), cb = gp_voronoi3d_neighbours(b, i, nb, 512);
    return ca == cb && ca <= 512 && !memcmp(na, nb, ca * sizeof(size_t));
}

/* Cell-by-cell comparison: bit-equal cells counted into *same; each cell's volume, centroid
 * and inertia within rel and its neighbours the same (0 demands every cell bit-equal). */
static int same_as(const gp_voronoi3d *a, const gp_voronoi3d *b, double rel, size_t *same)
{
    size_t n = gp_voronoi3d_count(a), na[512], nb[512];
    for (size_t i = 0; i < n; i++) {
        int bits = cell_bits_equal(a, b, i);
        *same += (size_t)bits;
        if (bits) continue;
        if (rel == 0) {
            fprintf(stderr, "cell %zu: not bit-equal to the rebuild's\n", i);
            return 0;
        }
        double x = gp_voronoi3d_cell_volume(a, i), y = gp_voronoi3d_cell_volume(b, i);
        if (!(fabs(x - y) <= rel * fmax(x, y))) {
            fprintf(stderr, "cell %zu: volume %.17g against %.17g\n", i, x, y);
            return 0;
        }
        double ga[3], gb[3], Ia[9], Ib[9], h = cbrt(x);
        gp_voronoi3d_cell_centroid(a, i, ga);
        gp_voronoi3d_cell_centroid(b, i, gb);
        gp_voronoi3d_cell_inertia(a, i, Ia);
        gp_voronoi3d_cell_inertia(b, i, Ib);
        int close = 1;
        for (int q = 0; q < 3; q++) close &= fabs(ga[q] - gb[q]) <= rel * h;
        for (int q = 0; q < 9; q++) close &= fabs(Ia[q] - Ib[q]) <= rel * (Ib[0] + Ib[4] + Ib[8]);
        if (!close) {
            fprintf(stderr, "cell %zu: centroid or inertia differ\n", i);
            return 0;
        }
        size_t ca = gp_voronoi3d_neighbours(a, i, na, 512), cb = gp_voronoi3d_neighbours(b, i, nb, 512);
        if (ca != cb || memcmp(na, nb, ca * sizeof(size_t))) {
            fprintf(stderr, "cell %zu: neighbours differ (%zu against %zu)\n", i, ca, cb);
            return 0;
        }
    }
    return 1;
}

/* Random moves (small steps and jumps; to multiples of snap when snap > 0), committed or
 * rolled back at random; after every `every`-th, the tessellation against a fresh build of the
 * same seeds: every cell bit-equal (rel 0), or within rel (see same_as). s holds the n seeds
 * (updated as moves commit). */
static void moves_against_rebuilds(const gp_voronoi3d_container *c, gp_voronoi3d *v, double *s,
                                   const double lo[3], const double hi[3], int moves, int every,
                                   double snap, double rel, const char *what)
{
    size_t n = gp_voronoi3d_count(v);
    int ok = 1, restored = 1, rejected = 0, committed = 0;
    size_t same = 0, compared = 0, changed = 0;
    for (int m = 0; m < moves && ok; m++) {
        size_t i = (size_t)(u01() * (double)n);
        double p[3], before = gp_voronoi3d_cell_volume(v, i);
        double step = u01() < 0.2 ? 1.0 : 0.05;
        for (int a = 0; a < 3; a++) {
            p[a] = s[3 * i + a] + step * (hi[a] - lo[a]) * (2 * u01() - 1);
            if (snap > 0) p[a] = snap * round(p[a] / snap);
        }
        if (gp_voronoi3d_try_move(v, i, p, NULL) != GP_OK) {
            rejected++; /* outside the container, or onto another seed */
            continue;
        }
        const uint32_t *cells;
        changed += gp_voronoi3d_changed(v, &cells);
        ok &= cells[0] == i;
        if (u01() < 0.5) {
            gp_voronoi3d_commit(v);
            memcpy(s + 3 * i, p, sizeof p);
            committed++;
        } else {
            gp_voronoi3d_rollback(v);
            restored &= gp_voronoi3d_cell_volume(v, i) == before;
        }
        if (m % every == 0 || m == moves - 1) {
            gp_voronoi3d *w = gp_voronoi3d_create(c, s, n, NULL);
            ok &= w && same_as(v, w, rel, &same);
            compared += n;
            gp_voronoi3d_destroy(w);
        }
    }
    CHECK(ok);
    CHECK(restored);
    CHECK(committed > moves / 4);
    CHECK(rel > 0 || same == compared);
    printf("moves (%s): n %zu, %d moves (%d outside, %d committed), %.1f cells changed per move, "
           "%zu of %zu compared cells bit-equal to a rebuild\n",
           what, n, moves, rejected, committed, (double)changed / (moves - rejected), same, compared);
}

/* Random seeds in c: every cell bit-equal to a rebuild's after every checked move. */
static void test_moves(const gp_voronoi3d_container *c, const double lo[3], const double hi[3],
                       size_t n, int moves, int every, const char *what)
{
    double *s;
    gp_voronoi3d *v = random_in(c, n, lo, hi, &s);
    CHECK(v != NULL);
    if (v) moves_against_rebuilds(c, v, s, lo, hi, moves, every, 0, 0, what);
    gp_voronoi3d_destroy(v);
    free(s);
}

/* Moves on a cubic lattice: the seeds start at the centres of 4^3 cubes and move to multiples
 * of a quarter of the cube (centres, faces, edges and corners of the cubes, the walls), so
 * that four planes or more keep meeting at vertices, with a co-spherical tie to every cut.
 * There the cut order can decide which of the coincident planes keeps a face (or a sliver of
 * ~1e-20), and a cell that is not recomputed keeps the choice of its last computation: the
 * canonical vertices do not cover that. So volumes, centroids and inertia within 1e-12 and
 * the neighbours the same, the bit-equal cells counted. */
static void test_lattice_moves(void)
{
    size_t k = 4, n = k * k * k;
    double *s = malloc(3 * n * sizeof(double)), lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    for (size_t i = 0; i < n; i++) {
        s[3 * i] = ((double)(i % k) + 0.5) / (double)k;
        s[3 * i + 1] = ((double)(i / k % k) + 0.5) / (double)k;
        s[3 * i + 2] = ((double)(i / k / k) + 0.5) / (double)k;
    }
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    gp_voronoi3d *v = gp_voronoi3d_create(&c, s, n, NULL);
    CHECK(v != NULL);
    if (v) moves_against_rebuilds(&c, v, s, lo, hi, 2000, 1, 0.25 / (double)k, 1e-12, "cubic lattice");
    gp_voronoi3d_destroy(v);
    free(s);
}

/* gp_voronoi3d_container_measure against the formulas (a box, a 64-facet prism, a tetrahedron
 * of volume 1/6 far from the origin) and gp_voronoi3d_cell_planes against the cells' own
 * vertices: unit normals, every vertex inside every plane, each face's vertices on its plane */
static void test_measure_and_planes(void)
{
    double lo[3] = {1, 2, 3}, hi[3] = {2, 4, 3.5}, vol, blo[3], bhi[3];
    gp_voronoi3d_container box = gp_voronoi3d_box(lo, hi);
    CHECK(gp_voronoi3d_container_measure(&box, &vol, blo, bhi, NULL) == GP_OK);
    CHECK(vol == 1.0 && blo[1] == 2 && bhi[2] == 3.5);
    gp_voronoi3d_container cyl = gp_voronoi3d_cylinder(5, -1, 0.5, 0, 2, 0);
    CHECK(gp_voronoi3d_container_measure(&cyl, &vol, NULL, NULL, NULL) == GP_OK);
    CHECK_NEAR(vol / (32 * 0.25 * sin(2 * M_PI / 64) * 2), 1.0, 1e-14);
    double o = 1e4, tet[16] = {-1, 0, 0, -o, 0, -1, 0, -o, 0, 0, -1, -o, 1, 1, 1, 3 * o + 1};
    gp_voronoi3d_container t = gp_voronoi3d_convex(tet, 4);
    CHECK(gp_voronoi3d_container_measure(&t, &vol, blo, bhi, NULL) == GP_OK);
    CHECK_NEAR(vol * 6, 1.0, 1e-9);
    double bad[16] = {1, 0, 0, 0, -1, 0, 0, -1, 0, 1, 0, 0, 0, -1, 0, 0};
    gp_voronoi3d_container unb = gp_voronoi3d_convex(bad, 4);
    CHECK(gp_voronoi3d_container_measure(&unb, &vol, NULL, NULL, NULL) == GP_ERR_INVALID);

    double seeds[3 * 300], worst_in = -INFINITY, worst_on = 0, worst_n = 0, pl[4 * 128], xyz[3 * 512];
    uint32_t loop[128];
    for (int k = 0; k < 900; k++) seeds[k] = (k % 3 == 0 ? 5 : k % 3 == 1 ? -1 : 1) + 0.6 * (rand() / (double)RAND_MAX - 0.5);
    gp_voronoi3d *v = gp_voronoi3d_create(&cyl, seeds, 300, NULL);
    CHECK(v != NULL);
    for (size_t i = 0; v && i < 300; i++) {
        size_t nf = gp_voronoi3d_cell_planes(v, i, pl, 128), nv = gp_voronoi3d_cell_vertices(v, i, xyz, 512);
        CHECK(nf == gp_voronoi3d_cell_face_count(v, i) && nv <= 512);
        for (size_t f = 0; f < nf; f++) {
            const double *q = pl + 4 * f;
            worst_n = fmax(worst_n, fabs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] - 1));
            for (size_t k = 0; k < nv; k++)
                worst_in = fmax(worst_in, q[0] * xyz[3 * k] + q[1] * xyz[3 * k + 1] + q[2] * xyz[3 * k + 2] - q[3]);
            size_t m = gp_voronoi3d_cell_face(v, i, f, loop, 128, NULL);
            for (size_t k = 0; k < m; k++) {
                const double *x = xyz + 3 * loop[k];
                worst_on = fmax(worst_on, fabs(q[0] * x[0] + q[1] * x[1] + q[2] * x[2] - q[3]));
            }
        }
    }
    printf("container volumes exact; cell planes: |n| - 1 within %.1e, vertices inside within %.1e, "
           "on their faces within %.1e\n", worst_n, worst_in, worst_on);
    CHECK(worst_n < 1e-14 && worst_in < 1e-12 && worst_on < 1e-12);
    gp_voronoi3d_destroy(v);
}

int main(void)
{
    test_measure_and_planes();
    test_lattice(6, 1, 0);
    test_lattice(10, 1e-6, 0);
    test_lattice(7, 1e6, -3e6);
    test_degenerate();
    test_containers();
    test_container_queries();
    test_scales();
    test_one_seed();
    test_bad_inputs();
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    gp_voronoi3d_container box = gp_voronoi3d_box(lo, hi);
    test_moves(&box, lo, hi, 60, 10000, 1, "box");
    test_moves(&box, lo, hi, 2000, 400, 100, "box");
    gp_voronoi3d_container cyl = gp_voronoi3d_cylinder(0, 0, 1, 0, 1, 16);
    double clo[3] = {-1, -1, 0}, chi[3] = {1, 1, 1};
    test_moves(&cyl, clo, chi, 60, 10000, 1, "cylinder");
    test_lattice_moves();
    return gp_test_summary();
}
