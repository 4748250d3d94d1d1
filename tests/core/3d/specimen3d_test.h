/* specimen3d_test.h -- what the tests of the 3D pipeline (test_specimen3d.c,
 * test_specimen3d_wide.c) share: the specs they start from, and the check that every sphere
 * stays in its box. Static, header-only: each test program includes it once. */
#ifndef SPECIMEN3D_TEST_H
#define SPECIMEN3D_TEST_H

#include "gp_specimen3d.h"

/* one-size 8 mm spheres (a 1e-6 wide bin) */
static const gp_sieve_row ONE_SIZE_8MM[2] = {{0.008 - 1e-6, 0}, {0.008, 100}};

/* the API defaults in a cube of the given side, with this sieve and target porosity */
static inline void spec_in_cube(gp_spec3d *s, double side, const gp_sieve_row *sieve,
                                size_t nsieve, double porosity)
{
    gp_spec3d_defaults(s);
    s->box[0] = s->box[1] = s->box[2] = side;
    s->sieve = sieve;
    s->nsieve = nsieve;
    s->porosity = porosity;
}

/* sphere faces beyond the box [0, r->box] by more than 5 % of their radius (the wall
 * overlaps: E = 15 MPa gives ~0.2 % of R at 16 kPa for a large grain, more for a small one
 * wedged by large ones; 5 % bounds them all), counted per axis; 0 without spheres */
static inline size_t spheres_outside(const gp_specimen3d *r)
{
    size_t out = 0;
    for (size_t i = 0; r->spheres && i < r->count; i++)
        for (int a = 0; a < 3; a++) {
            const double *s = r->spheres + 4 * i;
            if (s[a] - s[3] < -5e-2 * s[3] || s[a] + s[3] > r->box[a] + 5e-2 * s[3])
                out++;
        }
    return out;
}

#endif /* SPECIMEN3D_TEST_H */
