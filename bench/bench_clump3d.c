/* bench_clump3d.c -- clumps of overlapping spheres in 3D grains (gp_clump3d): time per grain and
 * the figures of merit against spheres_max, for an ellipsoid (1, 0.6, 0.4) and rough grains
 * (on the icosphere of 2,562 vertices / 5,120 triangles: r = 1 + 24 random terms
 * a (u . d)^p, p = 2 .. 8, then stretched by (1, e, e f), e, f in [0.6, 1], and turned).
 *
 * Usage: bench_clump3d [grains]   (default 200 rough grains for the time per grain)
 * Prints the errors against spheres_max per grain kind, the mean volume error against voxels
 * and spheres_max, and the time per grain (mean, median and 90th percentile of the wall
 * clock, and the mean CPU time of the thread, one thread) at the defaults and a few others. */
#include "gp_clock.h"
#include "gp_clump3d.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;

/* the CPU time of this thread (the machine may be shared) */
static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double u01(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct mesh {
    double *v, *u; /* vertices; the unit directions */
    uint32_t *t;
    size_t nv, nt;
} mesh;

static uint32_t midpoint(uint64_t *key, uint32_t *val, size_t cap, mesh *m, uint32_t a, uint32_t b)
{
    uint64_t k = a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a);
    size_t h = (size_t)((k * 0x9E3779B97F4A7C15ull) >> 20) % cap;
    while (key[h] != UINT64_MAX) {
        if (key[h] == k) return val[h];
        h = (h + 1) % cap;
    }
    double *p = m->u + 3 * m->nv, *pa = m->u + 3 * a, *pb = m->u + 3 * b;
    double x = pa[0] + pb[0], y = pa[1] + pb[1], z = pa[2] + pb[2], n = sqrt(x * x + y * y + z * z);
    p[0] = x / n, p[1] = y / n, p[2] = z / n;
    key[h] = k;
    val[h] = (uint32_t)m->nv;
    return (uint32_t)m->nv++;
}

static mesh icosphere(int level)
{
    mesh m = {0};
    size_t nt = 20, nv = 12;
    for (int l = 0; l < level; l++) nv += 3 * nt / 2, nt *= 4;
    m.u = malloc(3 * nv * sizeof(double));
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
        for (int k = 0; k < 3; k++) m.u[3 * i + k] = iv[i][k] / n;
    }
    memcpy(m.t, it, sizeof it);
    m.nv = 12;
    m.nt = 20;
    uint32_t *t2 = malloc(3 * nt * sizeof(uint32_t));
    for (int l = 0; l < level; l++) {
        size_t cap = 6 * m.nt + 1;
        uint64_t *key = malloc(cap * sizeof *key);
        uint32_t *val = malloc(cap * sizeof *val);
        for (size_t i = 0; i < cap; i++) key[i] = UINT64_MAX;
        size_t n2 = 0;
        for (size_t f = 0; f < m.nt; f++) {
            uint32_t a = m.t[3 * f], b = m.t[3 * f + 1], c = m.t[3 * f + 2];
            uint32_t ab = midpoint(key, val, cap, &m, a, b), bc = midpoint(key, val, cap, &m, b, c),
                     ca = midpoint(key, val, cap, &m, c, a);
            uint32_t q[4][3] = {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}};
            memcpy(t2 + 3 * n2, q, sizeof q);
            n2 += 4;
        }
        memcpy(m.t, t2, 3 * n2 * sizeof(uint32_t));
        m.nt = n2;
        free(key);
        free(val);
    }
    free(t2);
    return m;
}

/* A rough grain on m's directions: r(u) = 1 + sum over 24 random plane waves-like terms
 * a_k (u . d_k)^p_k (odd and even powers up to 8, amplitudes decaying with the power), kept
 * positive, then stretched by diag(1, e, e f) with e, f in [0.6, 1] and turned. */
static void rough_grain(mesh *m, double rough)
{
    double d[24][3], a[24];
    int pw[24];
    for (int k = 0; k < 24; k++) {
        double z = 2 * u01() - 1, ph = 2 * 3.141592653589793 * u01(), s = sqrt(1 - z * z);
        d[k][0] = s * cos(ph), d[k][1] = s * sin(ph), d[k][2] = z;
        pw[k] = 2 + (int)(7 * u01());
        a[k] = rough * (2 * u01() - 1) / (0.5 * pw[k]);
    }
    double e = 0.6 + 0.4 * u01(), f = 0.6 + 0.4 * u01();
    double th = 3.141592653589793 * u01(), c = cos(th), sn = sin(th);
    for (size_t i = 0; i < m->nv; i++) {
        const double *u = m->u + 3 * i;
        double r = 1;
        for (int k = 0; k < 24; k++) r += a[k] * pow(u[0] * d[k][0] + u[1] * d[k][1] + u[2] * d[k][2], pw[k]);
        if (r < 0.3) r = 0.3;
        double x = r * u[0], y = r * u[1] * e, z = r * u[2] * e * f;
        m->v[3 * i] = c * x - sn * y;
        m->v[3 * i + 1] = sn * x + c * y;
        m->v[3 * i + 2] = z;
    }
}

static void ellipsoid(mesh *m)
{
    for (size_t i = 0; i < m->nv; i++) {
        m->v[3 * i] = m->u[3 * i];
        m->v[3 * i + 1] = 0.6 * m->u[3 * i + 1];
        m->v[3 * i + 2] = 0.4 * m->u[3 * i + 2];
    }
}

static int cmpd(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void error_table(const char *name, mesh *m, int grains, int rough)
{
    size_t caps[7] = {1, 5, 10, 20, 30, 50, 100};
    printf("\n%s: mean over %d grain(s) (min_radius_ratio 0.1, default voxels)\n", name, grains);
    printf("| spheres_max | spheres | volume_error | inertia_error | shape_error | centroid_off | ms/grain |\n");
    printf("|---|---|---|---|---|---|---|\n");
    for (int q = 0; q < 7; q++) {
        double ve = 0, ie = 0, se = 0, co = 0, ns = 0, t = 0;
        uint64_t keep = rng_state;
        for (int g = 0; g < grains; g++) {
            if (rough) rough_grain(m, 0.25);
            gp_clump3d_params p;
            gp_clump3d_params_defaults(&p);
            p.spheres_max = caps[q];
            gp_clump3d_result r;
            gp_error err;
            double t0 = gp_clock_seconds();
            if (gp_clump3d_build(m->v, m->nv, m->t, m->nt, NULL, &p, &r, &err)) {
                printf("error: %s\n", err.message);
                return;
            }
            t += gp_clock_seconds() - t0;
            ve += r.volume_error, ie += r.inertia_error, se += r.inertia_shape_error;
            co += r.centroid_offset, ns += (double)r.nspheres;
            gp_clump3d_result_free(&r);
        }
        rng_state = keep; /* the same grains for every row */
        printf("| %zu | %.1f | %.4f | %.4f | %.4f | %.4f | %.2f |\n", caps[q], ns / grains,
               ve / grains, ie / grains, se / grains, co / grains, 1e3 * t / grains);
    }
}

static void time_row(mesh *m, int grains, size_t cap, double ratio, size_t voxels)
{
    double *t = malloc(grains * sizeof *t), ve = 0, cpu = 0;
    uint64_t keep = rng_state;
    for (int g = 0; g < grains; g++) {
        rough_grain(m, 0.25);
        gp_clump3d_params p = {cap, ratio, voxels};
        gp_clump3d_result r;
        gp_error err;
        double t0 = gp_clock_seconds(), c0 = cpu_seconds();
        gp_status st = gp_clump3d_build(m->v, m->nv, m->t, m->nt, NULL, &p, &r, &err);
        cpu += cpu_seconds() - c0;
        t[g] = gp_clock_seconds() - t0;
        if (st) {
            printf("error: %s\n", err.message);
            free(t);
            return;
        }
        ve += r.volume_error;
        gp_clump3d_result_free(&r);
    }
    rng_state = keep;
    qsort(t, grains, sizeof *t, cmpd);
    double sum = 0;
    for (int g = 0; g < grains; g++) sum += t[g];
    char vx[32] = "default (8192)";
    if (voxels) snprintf(vx, sizeof vx, "%zu", voxels);
    printf("| %zu | %.2f | %s | %.2f | %.2f | %.2f | %.2f | %.4f |\n", cap, ratio, vx,
           1e3 * sum / grains, 1e3 * t[grains / 2], 1e3 * t[(int)(0.9 * grains)],
           1e3 * cpu / grains, ve / grains);
    free(t);
}

/* mean volume_error of 20 rough grains for voxels x spheres_max */
static void voxel_table(mesh *m)
{
    size_t vox[4] = {4096, 8192, 16384, 32768}, caps[4] = {10, 30, 100, 300};
    printf("\nmean volume_error of 20 rough grains (min_radius_ratio 0.1)\n");
    printf("| voxels | k = 10 | k = 30 | k = 100 | k = 300 |\n|---|---|---|---|---|\n");
    for (int v = 0; v < 4; v++) {
        double ve[4] = {0, 0, 0, 0};
        uint64_t keep = rng_state;
        for (int g = 0; g < 20; g++) {
            rough_grain(m, 0.25);
            for (int c = 0; c < 4; c++) {
                gp_clump3d_params p = {caps[c], 0.1, vox[v]};
                gp_clump3d_result r;
                if (gp_clump3d_build(m->v, m->nv, m->t, m->nt, NULL, &p, &r, NULL)) return;
                ve[c] += r.volume_error / 20;
                gp_clump3d_result_free(&r);
            }
        }
        rng_state = keep;
        printf("| %zu | %.4f | %.4f | %.4f | %.4f |\n", vox[v], ve[0], ve[1], ve[2], ve[3]);
    }
}

int main(int argc, char **argv)
{
    int grains = argc > 1 ? atoi(argv[1]) : 200;
    if (grains < 1) grains = 1;
    mesh m = icosphere(4);
    printf("icosphere: %zu vertices, %zu triangles\n", m.nv, m.nt);
    ellipsoid(&m);
    error_table("ellipsoid (1, 0.6, 0.4)", &m, 1, 0);
    error_table("rough grains (random degree <= 8 fields, amplitude 0.25, stretched)", &m, 20, 1);
    printf("\ntime per rough grain, one thread, %d grains\n", grains);
    printf("| spheres_max | min_radius_ratio | voxels | mean ms | median ms | p90 ms | CPU ms | mean volume_error |\n");
    printf("|---|---|---|---|---|---|---|---|\n");
    time_row(&m, grains, 30, 0.1, 0);
    time_row(&m, grains, 10, 0.1, 0);
    time_row(&m, grains, 100, 0.1, 0);
    time_row(&m, grains, 30, 0.1, 4096);
    time_row(&m, grains, 30, 0.1, 32768);
    time_row(&m, grains, 300, 0.05, 32768);
    voxel_table(&m);
    free(m.u);
    free(m.v);
    free(m.t);
    return 0;
}
