/* test_fv3d.c -- the 3D Fourier-Voronoi specimen (gp_fv3d.h), checked from its own geometry by
 * the test: every vertex of every grain inside its cell (planes from the cell's faces), grain
 * volumes and inertia from the placed meshes, the solid fraction on a voxel grid (point in grain
 * by ray casting, no mesh integral), the laws' KS from those volumes and long axes, a sieve's
 * passing by mass, the same bytes on 1 and 2 threads, and the errors. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_fv3d.h"
#include "gp_fourier.h"
#include "gp_imc3d.h"
#include "gp_test.h"

/* ------------------------------------------------------------------ the test's own geometry */

static void rot_of(const double q[4], double R[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    R[0] = w * w + x * x - y * y - z * z;
    R[1] = 2 * (x * y - w * z);
    R[2] = 2 * (x * z + w * y);
    R[3] = 2 * (x * y + w * z);
    R[4] = w * w - x * x + y * y - z * z;
    R[5] = 2 * (y * z - w * x);
    R[6] = 2 * (x * z - w * y);
    R[7] = 2 * (y * z + w * x);
    R[8] = w * w - x * x - y * y + z * z;
}

/* the placed vertices of grain i from the result's representation alone */
static double *placed(const gp_fv3d *s, size_t i, size_t *nv)
{
    const double *dirs;
    *nv = gp_fv3d_directions(s, &dirs);
    const gp_fv3d_grain *g = gp_fv3d_grain_at(s, i);
    double R[9], *x = malloc(3 * *nv * sizeof *x);
    rot_of(g->rotation, R);
    for (size_t k = 0; k < *nv; k++) {
        double p[3] = {g->radii[k] * dirs[3 * k], g->radii[k] * dirs[3 * k + 1], g->radii[k] * dirs[3 * k + 2]};
        for (int r = 0; r < 3; r++)
            x[3 * k + r] = g->centre[r] + g->scale * (R[3 * r] * p[0] + R[3 * r + 1] * p[1] + R[3 * r + 2] * p[2]);
    }
    return x;
}

/* volume and inertia (about the centroid) of a closed mesh, tetrahedra from its first vertex */
static void mesh_integrals(const double *x, const uint32_t *t, size_t nt, double *V, double I[9])
{
    const double *o = x;
    double v = 0, m1[3] = {0, 0, 0}, M[9] = {0};
    for (size_t f = 0; f < nt; f++) {
        double a[3], b[3], c[3];
        for (int k = 0; k < 3; k++) {
            a[k] = x[3 * t[3 * f] + k] - o[k];
            b[k] = x[3 * t[3 * f + 1] + k] - o[k];
            c[k] = x[3 * t[3 * f + 2] + k] - o[k];
        }
        double d = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
        v += d / 6;
        for (int k = 0; k < 3; k++) m1[k] += d / 24 * (a[k] + b[k] + c[k]);
        for (int r = 0; r < 3; r++)
            for (int q = 0; q < 3; q++)
                M[3 * r + q] += d / 120 * (a[r] * a[q] + b[r] * b[q] + c[r] * c[q] +
                                           (a[r] + b[r] + c[r]) * (a[q] + b[q] + c[q]));
    }
    double g[3] = {m1[0] / v, m1[1] / v, m1[2] / v};
    for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) M[3 * r + q] -= v * g[r] * g[q];
    double tr = M[0] + M[4] + M[8];
    for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) I[3 * r + q] = (r == q ? tr : 0.0) - M[3 * r + q];
    *V = v;
}

/* the outward planes of cell i from its face loops (Newell), normalised */
static size_t cell_planes(const gp_voronoi3d *v, size_t i, double *pl, size_t cap)
{
    size_t nv = gp_voronoi3d_cell_vertices(v, i, NULL, 0), nf = gp_voronoi3d_cell_face_count(v, i);
    if (nf > cap) return 0;
    double *xyz = malloc(3 * nv * sizeof *xyz);
    uint32_t loop[256];
    gp_voronoi3d_cell_vertices(v, i, xyz, nv);
    for (size_t f = 0; f < nf; f++) {
        size_t m = gp_voronoi3d_cell_face(v, i, f, loop, 256, NULL);
        double n[3] = {0, 0, 0}, c[3] = {0, 0, 0};
        for (size_t e = 0; e < m; e++) {
            const double *P = xyz + 3 * loop[e], *Q = xyz + 3 * loop[(e + 1) % m];
            n[0] += (P[1] - Q[1]) * (P[2] + Q[2]);
            n[1] += (P[2] - Q[2]) * (P[0] + Q[0]);
            n[2] += (P[0] - Q[0]) * (P[1] + Q[1]);
            for (int k = 0; k < 3; k++) c[k] += P[k] / m;
        }
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++) pl[4 * f + k] = n[k] / len;
        pl[4 * f + 3] = (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]) / len;
    }
    free(xyz);
    return nf;
}

/* the least-moment axis of I against e: |cos| (power iteration on tr I - I, whose largest
 * eigenvalue is I's least) */
static double long_axis_cos(const double I[9], const double e[3])
{
    double tr = I[0] + I[4] + I[8], A[9], u[3] = {0.577, 0.577, 0.578};
    for (int k = 0; k < 9; k++) A[k] = (k % 4 == 0 ? tr : 0.0) - I[k];
    for (int it = 0; it < 2000; it++) {
        double w[3];
        for (int r = 0; r < 3; r++) w[r] = A[3 * r] * u[0] + A[3 * r + 1] * u[1] + A[3 * r + 2] * u[2];
        double n = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        for (int r = 0; r < 3; r++) u[r] = w[r] / n;
    }
    double n = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    return fabs(u[0] * e[0] + u[1] * e[1] + u[2] * e[2]) / n;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double ks_uniform(double *u, size_t n)
{
    qsort(u, n, sizeof *u, cmp_double);
    double d = 0;
    for (size_t i = 0; i < n; i++) d = fmax(d, fmax((i + 1.0) / n - u[i], u[i] - (double)i / n));
    return d;
}

/* ray from the grain's centre through x: 1 when x is inside the placed mesh (Moller-Trumbore
 * against every triangle: the farthest crossing along the ray is the surface, star shape) */
static int inside_grain(const double *vx, const uint32_t *t, size_t nt, const double c[3], const double x[3])
{
    double d[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]}, far = -1;
    for (size_t f = 0; f < nt; f++) {
        const double *A = vx + 3 * t[3 * f], *B = vx + 3 * t[3 * f + 1], *C = vx + 3 * t[3 * f + 2];
        double e1[3], e2[3], s[3], p[3], q[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = B[k] - A[k];
            e2[k] = C[k] - A[k];
            s[k] = c[k] - A[k];
        }
        p[0] = d[1] * e2[2] - d[2] * e2[1];
        p[1] = d[2] * e2[0] - d[0] * e2[2];
        p[2] = d[0] * e2[1] - d[1] * e2[0];
        double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
        if (fabs(det) < 1e-300) continue;
        double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
        if (u < -1e-12 || u > 1 + 1e-12) continue;
        q[0] = s[1] * e1[2] - s[2] * e1[1];
        q[1] = s[2] * e1[0] - s[0] * e1[2];
        q[2] = s[0] * e1[1] - s[1] * e1[0];
        double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
        if (v < -1e-12 || u + v > 1 + 1e-12) continue;
        double tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
        if (tt > far) far = tt;
    }
    return far >= 1.0;
}

/* ---------------------------------------------------------------------------- the checks */

typedef struct measured {
    double worst_out;      /* largest n.x - d of any vertex over its cell's size */
    double vol_gap, inertia_gap;
    double sum_grains, sum_cells;
    double ks_grain, ks_grain_orient, ks_cell;
    double clump_out;      /* largest sphere reach past its cell's faces, over the cell's size */
    size_t spheres_over;   /* clumps with more spheres than asked */
    size_t short_count;    /* grains under solid_fraction of their cell (law of cells) */
} measured;

static measured measure(const gp_fv3d *s, const gp_fv3d_spec *spec, const gp_law *grain_law, const gp_law *cell_law)
{
    measured m = {-INFINITY, 0, 0, 0, 0, 0, 0, 0, -INFINITY, 0, 0};
    size_t n = gp_fv3d_count(s), nv;
    const uint32_t *tri;
    size_t nt = gp_fv3d_triangles(s, &tri);
    const gp_voronoi3d *v = gp_fv3d_cells(s);
    double *gu = malloc(n * sizeof *gu), *go = malloc(n * sizeof *go), *cu = malloc(n * sizeof *cu), pl[4 * 200];
    double kk = gp_orient3d_k(spec->anisotropy);
    for (size_t i = 0; i < n; i++) {
        const gp_fv3d_grain *g = gp_fv3d_grain_at(s, i);
        double *x = placed(s, i, &nv), V, I[9];
        size_t nf = cell_planes(v, g->cell, pl, 200);
        double L = cbrt(gp_voronoi3d_cell_volume(v, g->cell));
        for (size_t k = 0; k < nv; k++)
            for (size_t f = 0; f < nf; f++) {
                const double *P = pl + 4 * f;
                m.worst_out = fmax(m.worst_out, (P[0] * x[3 * k] + P[1] * x[3 * k + 1] + P[2] * x[3 * k + 2] - P[3]) / L);
            }
        for (size_t k = 0; k < g->nspheres; k++)
            for (size_t f = 0; f < nf; f++) {
                const double *P = pl + 4 * f, *b = g->spheres + 4 * k;
                m.clump_out = fmax(m.clump_out, (P[0] * b[0] + P[1] * b[1] + P[2] * b[2] + b[3] - P[3]) / L);
            }
        m.spheres_over += g->nspheres > (size_t)spec->spheres_max;
        mesh_integrals(x, tri, nt, &V, I);
        m.vol_gap = fmax(m.vol_gap, fabs(V - g->volume) / V);
        for (int k = 0; k < 9; k++) m.inertia_gap = fmax(m.inertia_gap, fabs(I[k] - g->inertia[k]) / (I[0] + I[4] + I[8]));
        m.sum_grains += V;
        m.short_count += V < spec->solid_fraction * gp_voronoi3d_cell_volume(v, g->cell) * (1 - 1e-6);
        m.sum_cells += gp_voronoi3d_cell_volume(v, g->cell);
        gu[i] = gp_law_cdf(grain_law, V);
        cu[i] = gp_law_cdf(cell_law, gp_voronoi3d_cell_volume(v, i));
        double c = long_axis_cos(I, spec->axis);
        go[i] = c + 0.5 * kk * (c * c * c - c);
        free(x);
    }
    m.ks_grain = ks_uniform(gu, n);
    m.ks_grain_orient = ks_uniform(go, n);
    m.ks_cell = ks_uniform(cu, n);
    free(gu);
    free(go);
    free(cu);
    return m;
}

/* the solid fraction on a g^3 grid of voxel centres: each centre's cell by the nearest seed,
 * then inside its grain or not */
static double voxel_fraction(const gp_fv3d *s, int g)
{
    size_t n = gp_fv3d_count(s), nv, inside = 0;
    const uint32_t *tri;
    size_t nt = gp_fv3d_triangles(s, &tri);
    const gp_voronoi3d *v = gp_fv3d_cells(s);
    double **vx = malloc(n * sizeof *vx), *seeds = malloc(3 * n * sizeof *seeds);
    for (size_t i = 0; i < n; i++) {
        vx[i] = placed(s, i, &nv);
        gp_voronoi3d_seed(v, i, seeds + 3 * i);
    }
    for (int a = 0; a < g; a++)
        for (int b = 0; b < g; b++)
            for (int c = 0; c < g; c++) {
                double x[3] = {(a + 0.5) / g, (b + 0.5) / g, (c + 0.5) / g}, best = INFINITY;
                size_t cell = 0;
                for (size_t i = 0; i < n; i++) {
                    double d = 0;
                    for (int k = 0; k < 3; k++) d += (x[k] - seeds[3 * i + k]) * (x[k] - seeds[3 * i + k]);
                    if (d < best) {
                        best = d;
                        cell = i;
                    }
                }
                inside += inside_grain(vx[cell], tri, nt, gp_fv3d_grain_at(s, cell)->centre, x);
            }
    for (size_t i = 0; i < n; i++) free(vx[i]);
    free(vx);
    free(seeds);
    return (double)inside / ((double)g * g * g);
}

static double D[16];

static void spec_for(gp_fv3d_spec *sp, size_t n, const gp_law *law, unsigned level)
{
    gp_fv3d_spec_defaults(sp);
    sp->particles = n;
    sp->law = law;
    sp->D = D;
    sp->nmodes = 16;
    sp->mesh_level = level;
    sp->seed = 7;
}

/* N = 150 in a unit box, lognormal COV 0.5 of cells, a = 0.5 about z, every output */
static void box_specimen(void)
{
    size_t n = 150;
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.0 / n, 0.5, NULL);
    gp_fv3d_spec sp;
    spec_for(&sp, n, law, 2);
    sp.anisotropy = 0.5;
    sp.solid_fraction = 0.3;
    sp.outputs = GP_OUT3_GRAINS | GP_OUT3_CLUMPS | GP_OUT3_DESCRIPTORS;
    sp.spheres_max = 12;
    gp_fv3d *s = NULL;
    gp_error e;
    gp_status st = gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e);
    CHECK(st == GP_OK);
    if (st != GP_OK) {
        fprintf(stderr, "%s\n", e.message);
        gp_law_destroy(law);
        return;
    }
    gp_law *gl = gp_law_scaled(law, sp.solid_fraction, NULL);
    measured m = measure(s, &sp, gl, law);
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    double crit = 1.36 / sqrt((double)n), vox = voxel_fraction(s, 72);
    printf("box N %zu: vertices out by %.2e of a cell at most; volumes %.1e, inertia %.1e from the meshes; "
           "solid fraction %.4f (meshes) %.4f (voxels 72^3) %.4f (reported), %zu short; grain KS %.3f (%.3f), "
           "cell KS %.3f (%.3f), grain orientation KS %.3f (%.3f), crit %.3f; clumps past their cell %.1e, "
           "volume error mean %.3f max %.3f\n",
           n, m.worst_out, m.vol_gap, m.inertia_gap, m.sum_grains / m.sum_cells, vox, t->solid_fraction,
           t->grains_short, m.ks_grain, t->grain_volume.ks, m.ks_cell, t->cell_volume.ks, m.ks_grain_orient,
           t->grain_orientation.ks, crit, m.clump_out, t->clump_volume_error_mean, t->clump_volume_error_max);
    CHECK(m.worst_out <= 0.0);
    CHECK(m.vol_gap < 1e-9 && m.inertia_gap < 1e-9);
    CHECK(fabs(m.sum_grains / m.sum_cells - t->solid_fraction) < 1e-12);
    CHECK(fabs(vox / t->solid_fraction - 1) < 0.005);
    CHECK(m.short_count == t->grains_short && t->grains_short < n / 4);
    CHECK(t->solid_fraction <= sp.solid_fraction * (1 + 1e-12) && t->solid_fraction > 0.9 * sp.solid_fraction);
    CHECK(fabs(m.ks_grain - t->grain_volume.ks) < 1e-9 && fabs(m.ks_cell - t->cell_volume.ks) < 1e-9);
    CHECK(t->cell_volume.ks <= 0.3 * crit);
    CHECK(fabs(m.ks_grain_orient - t->grain_orientation.ks) < 1e-6);
    CHECK(t->grain_orientation.ks <= crit && t->cell_orientation.ks <= crit);
    CHECK(m.clump_out <= 1e-9 && m.spheres_over == 0);
    CHECK(t->clump_volume_error_max < 0.5);
    /* the summary against the grains' own values; the 2D reference's elongation against a
     * grain of mode 2 alone, (1 - D2) / (1 + D2) (modes 3 and 8 move it by a few percent) */
    const gp_fv3d_descriptor_stats *ds = &t->descriptors;
    double me = 0;
    for (size_t i = 0; i < n; i++) me += gp_fv3d_grain_at(s, i)->desc.elongation / n;
    printf("descriptors: 3D elongation %.3f (sd %.3f), flatness %.3f, sphericity %.3f, convexity %.3f; "
           "projection along the short axis: 2D elongation %.3f roundness %.3f; 2D reference %.3f %.3f %.3f %.3f\n",
           ds->mean[0], ds->sd[0], ds->mean[1], ds->mean[2], ds->mean[3], ds->projection[2][0], ds->projection[2][1],
           ds->reference2d[0], ds->reference2d[1], ds->reference2d[2], ds->reference2d[3]);
    CHECK(ds->present && fabs(ds->mean[0] - me) < 1e-12);
    CHECK(fabs(ds->reference2d[0] - (1 - D[2]) / (1 + D[2])) < 0.05);
    const gp_fv3d_grain *g0 = gp_fv3d_grain_at(s, 0);
    CHECK(g0->desc.sphericity > 0.5 && g0->desc.sphericity <= 1.0 && g0->desc.convexity > 0.5 &&
          g0->desc.convexity <= 1.0 + 1e-12);
    gp_fv3d_destroy(s);
    gp_law_destroy(gl);
    gp_law_destroy(law);
}

/* the same spec on 1 and 2 threads: the same bytes */
static void threads_same(void)
{
    size_t n = 60;
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.0 / n, 0.8, NULL);
    gp_fv3d_spec sp;
    spec_for(&sp, n, law, 2);
    sp.outputs = GP_OUT3_GRAINS | GP_OUT3_CLUMPS;
    sp.spread = 0.3;
    gp_fv3d *a = NULL, *b = NULL;
    CHECK(gp_fv3d_build(&sp, NULL, NULL, NULL, &a, NULL) == GP_OK);
    sp.threads = 2;
    CHECK(gp_fv3d_build(&sp, NULL, NULL, NULL, &b, NULL) == GP_OK);
    int same = a && b;
    size_t nv = a ? gp_fv3d_directions(a, NULL) : 0;
    for (size_t i = 0; same && i < n; i++) {
        const gp_fv3d_grain *x = gp_fv3d_grain_at(a, i), *y = gp_fv3d_grain_at(b, i);
        same = !memcmp(x->centre, y->centre, sizeof x->centre) && !memcmp(x->rotation, y->rotation, sizeof x->rotation) &&
               x->scale == y->scale && !memcmp(x->radii, y->radii, nv * sizeof(double)) && x->nspheres == y->nspheres &&
               !memcmp(x->spheres, y->spheres, 4 * x->nspheres * sizeof(double));
    }
    CHECK(same);
    gp_fv3d_destroy(a);
    gp_fv3d_destroy(b);
    gp_law_destroy(law);
}

/* a sieve of grains by mass: the grains' passing, recomputed from their meshes' volumes */
static void sieve_of_grains(void)
{
    const double d[4] = {0.09, 0.135, 0.18, 0.24}, pw[4] = {0, 30, 80, 100};
    gp_law *law = gp_law_create_sieve3d(d, pw, 4, NULL);
    size_t n = (size_t)lround(0.3 / gp_law_mean(law));
    gp_fv3d_spec sp;
    spec_for(&sp, n, law, 2);
    sp.law_of_grains = 1;
    sp.solid_fraction = 0.3;
    gp_fv3d *s = NULL;
    gp_error e;
    CHECK(gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e) == GP_OK);
    if (!s) {
        gp_law_destroy(law);
        return;
    }
    measured m = measure(s, &sp, law, law);
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    /* passing by mass at each sieve from the meshes' volumes */
    size_t nv;
    double tot = 0, pass[4] = {0}, worst = 0;
    const uint32_t *tri;
    size_t nt = gp_fv3d_triangles(s, &tri);
    for (size_t i = 0; i < n; i++) {
        double *x = placed(s, i, &nv), V, I[9];
        mesh_integrals(x, tri, nt, &V, I);
        double dia = cbrt(6 * V / M_PI);
        tot += V;
        for (int k = 0; k < 4; k++)
            if (dia < d[k]) pass[k] += V;
        free(x);
    }
    for (int k = 0; k < 4; k++) worst = fmax(worst, fabs(100 * pass[k] / tot - pw[k]));
    printf("sieve IMC: %ld steps, error %.4f, stop %d, %.1f s; grains %.1f s\n", t->imc_steps, t->imc_error, t->imc_stop, gp_fv3d_timings_of(s)->imc, gp_fv3d_timings_of(s)->grains);
    printf("sieve of grains, N %zu: passing within %.2f pp (reported %.2f), grain KS %.3f (crit %.3f), %zu short, "
           "solid fraction %.4f\n", n, worst, t->passing.max_error_pp, m.ks_grain, 1.36 / sqrt((double)n),
           t->grains_short, t->solid_fraction);
    CHECK(t->passing.n == 4 && fabs(worst - t->passing.max_error_pp) < 1e-6);
    CHECK(worst < 3.0);
    /* the grains that cannot reach their quantile (7 % here) keep their largest size */
    CHECK(fabs(m.ks_grain - t->grain_volume.ks) < 1e-9 && m.ks_grain <= 1.36 / sqrt((double)n));
    CHECK(m.worst_out <= 0.0);
    gp_fv3d_destroy(s);
    gp_law_destroy(law);
}

/* a cylinder, elongated and flat grains: inside their cells, the 3D elongation and flatness
 * near what was asked */
static void cylinder_elongated(void)
{
    size_t n = 80;
    gp_fv3d_spec sp;
    gp_law *law = NULL;
    spec_for(&sp, n, NULL, 3);
    sp.container = gp_voronoi3d_cylinder(0, 0, 0.5, 0, 1.0, 0);
    double vol = 64 * 0.5 * 0.25 * sin(2 * M_PI / 64) * 1.0;
    law = gp_law_create(GP_LAW_LOGNORMAL, vol / n, 0.3, NULL);
    sp.law = law;
    sp.elongation = 0.5;
    sp.flatness = 0.7;
    sp.outputs = GP_OUT3_GRAINS | GP_OUT3_DESCRIPTORS;
    gp_fv3d *s = NULL;
    gp_error e;
    gp_status st = gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e);
    CHECK(st == GP_OK);
    if (!s) {
        fprintf(stderr, "%s\n", e.message);
        gp_law_destroy(law);
        return;
    }
    gp_law *gl = gp_law_scaled(law, sp.solid_fraction, NULL);
    measured m = measure(s, &sp, gl, law);
    double el = 0, fl = 0;
    for (size_t i = 0; i < n; i++) {
        el += gp_fv3d_grain_at(s, i)->desc.elongation / n;
        fl += gp_fv3d_grain_at(s, i)->desc.flatness / n;
    }
    const gp_fv3d_stats *t = gp_fv3d_stats_of(s);
    printf("cylinder N %zu, elongation 0.5 flatness 0.7: mean 3D elongation %.3f, flatness %.3f; vertices out by %.1e; "
           "solid fraction %.4f, %zu short\n", n, el, fl, m.worst_out, t->solid_fraction, t->grains_short);
    CHECK(m.worst_out <= 0.0);
    CHECK(fabs(el - 0.5) < 0.1 && fabs(fl - 0.7) < 0.1);
    gp_fv3d_destroy(s);
    gp_law_destroy(gl);
    gp_law_destroy(law);
}

static int stop_now(void *user, const gp_progress *p)
{
    (void)p;
    return ++*(int *)user >= 2;
}

static void errors_and_cancel(void)
{
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.0 / 40, 0.5, NULL);
    gp_fv3d_spec sp;
    spec_for(&sp, 40, law, 2);
    gp_fv3d *s = NULL;
    gp_error e;
    double big[4] = {1, 0, 1.5, 0.5};
    sp.D = big;
    sp.nmodes = 4;
    CHECK(gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e) == GP_ERR_NOT_STAR && s == NULL && strstr(e.message, "r <= 0"));
    spec_for(&sp, 40, law, 2);
    sp.solid_fraction = 1.0;
    CHECK(gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e) == GP_ERR_INVALID && strstr(e.message, "solid_fraction"));
    spec_for(&sp, 40, law, 2);
    sp.imc_threshold = 1e-9;
    sp.imc_max_steps = 100000;
    int calls = 0;
    CHECK(gp_fv3d_build(&sp, stop_now, &calls, NULL, &s, &e) == GP_ERR_CANCELLED && s == NULL);
    /* one grain: the container is its cell */
    gp_law *one = gp_law_create(GP_LAW_LOGNORMAL, 1.0, 0.5, NULL);
    spec_for(&sp, 1, one, 2);
    sp.solid_fraction = 0.4;
    CHECK(gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e) == GP_OK && s && gp_fv3d_count(s) == 1);
    if (s) CHECK(fabs(gp_fv3d_stats_of(s)->solid_fraction - 0.4) < 1e-9);
    gp_fv3d_destroy(s);
    gp_law_destroy(one);
    gp_law_destroy(law);
}

int main(void)
{
    CHECK(gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 16, D, NULL) == GP_OK);
    box_specimen();
    threads_same();
    sieve_of_grains();
    cylinder_elongated();
    errors_and_cancel();
    return gp_test_summary();
}
