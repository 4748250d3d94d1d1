/* bench_grain3d.c -- the cost of one 3D Fourier grain (gp_grain3d) on one thread, phase by
 * phase: the draw, the radii (table product, star-shape check, stretched resampling), the mass
 * properties, the principal axes, the convex hull, and the three projections' 2D
 * descriptors; with the spectrum of the API's example (D2 = 0.1, D3 = 0.05, D8 = 0.02,
 * alpha = beta = -2) at degrees 15 and 30, without and with the aspect ratios 0.8 / 0.8, on the
 * level-4 icosphere (2,562 directions): the stretch on a basis made for it, and (a tenth of
 * the grains) on the plain basis, summed direction by direction. Also: the basis' build, the
 * grains refused as not star-shaped, and the descriptors' means.
 *
 * Usage: bench_grain3d [grains] (default 1000). */
#include "gp_clock.h"
#include "gp_grain3d.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double u01(void *p)
{
    uint64_t *s = p;
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct phases {
    double draw, radii, mass, axes, hull, proj;
    int made, refused;
    double elong, flat, sph, conv, p_elong, p_circ, p_round;
} phases;

static void run(const gp_grain3d_basis *b, unsigned degree, double e, double f, int ngrains, phases *ph)
{
    size_t nv = gp_grain3d_basis_count(b);
    const gp_mesh3d *m = gp_grain3d_basis_mesh(b);
    double D[GP_GRAIN3D_DEGREE_MAX + 1], *r = malloc(nv * sizeof *r), *xyz = malloc(3 * nv * sizeof *xyz);
    gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, degree + 1, D, NULL);
    gp_grain3d_law law = {D, NULL, degree + 1, degree, e, f};
    memset(ph, 0, sizeof *ph);
    for (int g = 0; ph->made < ngrains; g++) {
        uint64_t st = 0x9E3779B97F4A7C15ull * (uint64_t)(g + 1);
        gp_grain3d_shape s;
        double t0 = gp_clock_seconds();
        gp_grain3d_draw(&law, u01, &st, &s, NULL);
        double t1 = gp_clock_seconds();
        gp_status ok = gp_grain3d_radii(b, &s, r, NULL);
        double t2 = gp_clock_seconds();
        ph->draw += t1 - t0;
        ph->radii += t2 - t1;
        if (ok != GP_OK) {
            ph->refused++;
            continue;
        }
        gp_grain3d_vertices(b, r, xyz);
        gp_mesh3d_mass ms;
        gp_mesh3d_axes ax;
        double hv;
        gp_shape_result pr[3];
        t0 = gp_clock_seconds();
        gp_mesh3d_mass_properties(xyz, nv, gp_mesh3d_triangles(m), gp_mesh3d_triangle_count(m), &ms, NULL);
        t1 = gp_clock_seconds();
        gp_mesh3d_principal_axes(xyz, nv, &ms, &ax, NULL);
        t2 = gp_clock_seconds();
        gp_mesh3d_hull_volume(xyz, nv, &hv, NULL);
        double t3 = gp_clock_seconds();
        gp_grain3d_describe_projections(b, r, &ax, NULL, pr, NULL);
        double t4 = gp_clock_seconds();
        ph->mass += t1 - t0;
        ph->axes += t2 - t1;
        ph->hull += t3 - t2;
        ph->proj += t4 - t3;
        ph->elong += ax.extent[1] / ax.extent[0];
        ph->flat += ax.extent[2] / ax.extent[1];
        ph->sph += cbrt(M_PI) * pow(6 * ms.volume, 2.0 / 3.0) / ms.area;
        ph->conv += ms.volume / hv;
        for (int k = 0; k < 3; k++) {
            ph->p_elong += pr[k].elongation / 3;
            ph->p_circ += pr[k].circularity / 3;
            ph->p_round += pr[k].roundness / 3;
        }
        ph->made++;
    }
    free(r);
    free(xyz);
}

int main(int argc, char **argv)
{
    int ng = argc > 1 ? atoi(argv[1]) : 1000;
    if (ng < 1) ng = 1000;
    printf("bench_grain3d: %d grains a row, level-4 icosphere (2,562 directions, 5,120 triangles), one thread\n", ng);
    printf("spectrum D2=0.1 D3=0.05 D8=0.02 alpha=beta=-2; times in ms per grain\n\n");
    printf("%6s %9s | %6s %6s %6s %6s %6s %6s | %6s | %7s | %5s %5s %5s %5s | %5s %5s %5s\n", "degree", "e / f",
           "draw", "radii", "mass", "axes", "hull", "proj", "total", "refused", "I/L", "S/I", "sph", "conv",
           "p-el", "p-cir", "p-rnd");
    unsigned degs[2] = {15, 30};
    for (int d = 0; d < 2; d++) {
        double t0 = gp_clock_seconds();
        gp_grain3d_basis *plain = gp_grain3d_basis_create(4, degs[d], NULL);
        printf("(basis of degree %u: %.1f ms, %.1f MB)\n", degs[d], 1e3 * (gp_clock_seconds() - t0),
               2562.0 * (degs[d] + 1) * (degs[d] + 1) * 8 / 1e6);
        gp_grain3d_basis *stretched = gp_grain3d_basis_create_ex(4, degs[d], 0.8, 0.8, NULL);
        /* no stretch; the stretch of the basis; a stretch summed directly (another basis') */
        const gp_grain3d_basis *bs[3] = {plain, stretched, plain};
        const char *how[3] = {"", "", " direct"};
        for (int s = 0; s < 3; s++) {
            phases p;
            double e = s ? 0.8 : 1, f = s ? 0.8 : 1;
            int n = s == 2 ? (ng + 9) / 10 : ng;
            run(bs[s], degs[d], e, f, n, &p);
            double k = 1e3 / n, tot = p.draw + p.radii + p.mass + p.axes + p.hull + p.proj;
            printf("%6u %4.1f/%-4.1f | %6.3f %6.3f %6.3f %6.3f %6.3f %6.3f | %6.3f | %7d | %5.3f %5.3f %5.3f %5.3f | %5.3f %5.3f %5.3f%s\n",
                   degs[d], e, f, p.draw * k, p.radii * k, p.mass * k, p.axes * k, p.hull * k, p.proj * k, tot * k,
                   p.refused, p.elong / n, p.flat / n, p.sph / n, p.conv / n, p.p_elong / n, p.p_circ / n,
                   p.p_round / n, how[s]);
        }
        gp_grain3d_basis_destroy(plain);
        gp_grain3d_basis_destroy(stretched);
    }
    return 0;
}
