/* gp_dem3d_measure.c -- contact search and measures on a static packing (see gp_dem3d.h). */
#include "gp_dem3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_grid.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static int cmp_pair(const void *a, const void *b)
{
    const size_t *x = a, *y = b;
    if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
    return x[1] < y[1] ? -1 : x[1] > y[1];
}

gp_status gp_dem3d_find_pairs(const double *xyzr, size_t n, double gap, size_t **pairs,
                              size_t *npairs, gp_error *err)
{
    *pairs = NULL;
    *npairs = 0;
    if (n == 0)
        return GP_OK;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double rmax = 0;
    for (size_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            double c = xyzr[4 * i + a];
            if (!isfinite(c))
                return gp_error_set(err, GP_ERR_INVALID, "find_pairs: sphere %zu not finite", i);
            if (c < lo[a]) lo[a] = c;
            if (c > hi[a]) hi[a] = c;
        }
        if (xyzr[4 * i + 3] > rmax) rmax = xyzr[4 * i + 3];
    }
    size_t g[3];
    double inv[3];
    size_t nc = gp_grid_size(lo, hi, 2 * rmax + (gap > 0 ? gap : 0), 4096, 2 * n + 64, g, inv);
    size_t *start = calloc(nc + 1, sizeof *start), *cell = malloc(n * sizeof *cell),
           *list = malloc(n * sizeof *list), *fill = malloc(nc * sizeof *fill);
    size_t cap = 8 * n + 64, np = 0;
    size_t *pr = malloc(2 * cap * sizeof *pr);
    if (!start || !cell || !list || !fill || !pr) {
        free(start); free(cell); free(list); free(fill); free(pr);
        return gp_error_set(err, GP_ERR_NOMEM, "find_pairs: out of memory");
    }
    for (size_t i = 0; i < n; i++) {
        size_t c[3];
        for (int a = 0; a < 3; a++)
            c[a] = gp_grid_cell((xyzr[4 * i + a] - lo[a]) * inv[a], g[a]);
        cell[i] = (c[2] * g[1] + c[1]) * g[0] + c[0];
        start[cell[i] + 1]++;
    }
    for (size_t c = 0; c < nc; c++)
        start[c + 1] += start[c];
    memcpy(fill, start, nc * sizeof *fill);
    for (size_t i = 0; i < n; i++)
        list[fill[cell[i]]++] = i;
    for (size_t i = 0; i < n; i++) {
        size_t ci = cell[i];
        long cx = (long)(ci % g[0]), cy = (long)((ci / g[0]) % g[1]), cz = (long)(ci / (g[0] * g[1]));
        const double *p = xyzr + 4 * i;
        for (long z = cz - 1; z <= cz + 1; z++) {
            if (z < 0 || z >= (long)g[2]) continue;
            for (long y = cy - 1; y <= cy + 1; y++) {
                if (y < 0 || y >= (long)g[1]) continue;
                for (long x = cx - 1; x <= cx + 1; x++) {
                    if (x < 0 || x >= (long)g[0]) continue;
                    size_t c = ((size_t)z * g[1] + (size_t)y) * g[0] + (size_t)x;
                    for (size_t k = start[c]; k < start[c + 1]; k++) {
                        size_t j = list[k];
                        if (j <= i) continue;
                        const double *q = xyzr + 4 * j;
                        double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
                        double rr = p[3] + q[3] + gap;
                        if (dx * dx + dy * dy + dz * dz < rr * rr) {
                            if (np == cap) {
                                cap *= 2;
                                size_t *p2 = realloc(pr, 2 * cap * sizeof *p2);
                                if (!p2) {
                                    free(start); free(cell); free(list); free(fill); free(pr);
                                    return gp_error_set(err, GP_ERR_NOMEM, "find_pairs: out of memory");
                                }
                                pr = p2;
                            }
                            pr[2 * np] = i;
                            pr[2 * np + 1] = j;
                            np++;
                        }
                    }
                }
            }
        }
    }
    free(start); free(cell); free(list); free(fill);
    qsort(pr, np, 2 * sizeof *pr, cmp_pair);
    *pairs = pr;
    *npairs = np;
    return GP_OK;
}

void gp_dem3d_fabric_acc_init(gp_dem3d_fabric_acc *a)
{
    memset(a, 0, sizeof *a);
}

void gp_dem3d_fabric_acc_add(gp_dem3d_fabric_acc *acc, const gp_contact3d *c, size_t nc)
{
    for (size_t k = 0; k < nc; k++) {
        double w = c[k].j >= 0 ? 2 : 1; /* seen by both spheres, or by one (a wall) */
        acc->wsum += w;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                acc->sum[a][b] += w * c[k].normal[a] * c[k].normal[b];
    }
}

void gp_dem3d_fabric_acc_finish(const gp_dem3d_fabric_acc *acc, double F[3][3])
{
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            F[a][b] = acc->wsum > 0 ? acc->sum[a][b] / acc->wsum : 0;
}

void gp_dem3d_stress_acc_init(gp_dem3d_stress_acc *a, const double *xyzr)
{
    memset(a, 0, sizeof *a);
    a->xyzr = xyzr;
}

void gp_dem3d_stress_acc_add(gp_dem3d_stress_acc *acc, const gp_contact3d *c, size_t nc)
{
    const double *xyzr = acc->xyzr;
    for (size_t k = 0; k < nc; k++) {
        const double *pi = xyzr + 4 * c[k].i;
        double l[3];
        if (c[k].j >= 0) {
            const double *pj = xyzr + 4 * c[k].j;
            for (int a = 0; a < 3; a++)
                l[a] = pj[a] - pi[a];
        } else {
            double dist = pi[3] - c[k].overlap;
            for (int a = 0; a < 3; a++)
                l[a] = dist * c[k].normal[a];
        }
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                acc->sum[a][b] -= l[a] * c[k].force[b];
    }
}

void gp_dem3d_stress_acc_finish(const gp_dem3d_stress_acc *acc, double volume, double S[3][3])
{
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            S[a][b] = volume > 0 ? acc->sum[a][b] / volume : acc->sum[a][b];
}

/* the array functions: the accumulators over the whole array */
void gp_dem3d_fabric(const gp_contact3d *c, size_t nc, double F[3][3])
{
    gp_dem3d_fabric_acc acc;
    gp_dem3d_fabric_acc_init(&acc);
    gp_dem3d_fabric_acc_add(&acc, c, nc);
    gp_dem3d_fabric_acc_finish(&acc, F);
}

void gp_dem3d_stress(const gp_contact3d *c, size_t nc, const double *xyzr, double volume,
                     double S[3][3])
{
    gp_dem3d_stress_acc acc;
    gp_dem3d_stress_acc_init(&acc, xyzr);
    gp_dem3d_stress_acc_add(&acc, c, nc);
    gp_dem3d_stress_acc_finish(&acc, volume, S);
}

static double cap_volume(double r, double dist)
{
    /* part of a sphere beyond a plane at distance dist from the centre (dist may be < 0) */
    if (dist >= r) return 0;
    if (dist <= -r) return 4.0 / 3.0 * M_PI * r * r * r;
    double h = r - dist;
    return M_PI * h * h * (3 * r - h) / 3.0;
}

double gp_dem3d_solid_volume(const double *xyzr, size_t n, const double lo[3], const double hi[3])
{
    double v = 0;
    for (size_t i = 0; i < n; i++) {
        const double *p = xyzr + 4 * i;
        double r = p[3], vi = 4.0 / 3.0 * M_PI * r * r * r;
        for (int a = 0; a < 3; a++) {
            vi -= cap_volume(r, p[a] - lo[a]);
            vi -= cap_volume(r, hi[a] - p[a]);
        }
        v += vi > 0 ? vi : 0;
    }
    return v;
}
