/* gp_flip.h -- the flip technique (Dang & Meguid 2010, Phase 2, Figs 2-4, Eqs 11-13).
 *
 * A sample in the box [0, b] is copied to tile (kx, ky, kz) of an nx x ny x nz grid, mirrored
 * across every axis whose tile index is odd: x' = kx bx + (kx odd ? bx - x : x), likewise y, z.
 * Neighbouring tiles are thus mirror images across their common face, and a sphere that touched
 * a wall at distance d < R now touches its own image at distance 2 d: with Eq. 11's half
 * overlap the penetration is R - d, the wall penetration of Eq. 12 (Eq. 13), so the force is
 * kept (with gp_dem3d's mirror wall law it is the same force to the last bit of arithmetic).
 *
 * Sphere index in the tiled packing: t * n + i, t = (kz * ny + ky) * nx + kx.
 */
#ifndef GP_FLIP_H
#define GP_FLIP_H

#include <stddef.h>

#include "gp_dem3d.h"
#include "gp_error.h"

/* Tiles xyzr[4n] (box [0, box]) into *out (4 * n * nx * ny * nz, malloc'ed). max_spheres caps
 * the result (GP_ERR_INVALID beyond it). */
gp_status gp_flip_tile(const double *xyzr, size_t n, const double box[3], const int tiles[3],
                       size_t max_spheres, double **out, size_t *nout, gp_error *err);

/* Maps the sample's contacts to the tiled packing: every sphere contact to each tile (normal
 * and force mirrored), every wall contact to a contact with the sphere's image across an inner
 * face (full overlap 2 delta, the same normal force, Eq. 13) or to the tiled box's wall on the
 * outer faces. Sphere pairs first (i < j, sorted), then wall contacts (by sphere). xyzr: the
 * sample's spheres (n of them). */
gp_status gp_flip_contacts(const gp_dem3d_contact *c, size_t nc, const double *xyzr, size_t n,
                           const int tiles[3], gp_dem3d_contact **out, size_t *nout,
                           gp_error *err);

/* The same two, stopping with GP_ERR_CANCELLED (nothing allocated is left) when *cancel (read
 * atomically between tiles; may be NULL) becomes non-zero: a tiling of 20 million spheres
 * takes seconds. The results do not depend on cancel. */
gp_status gp_flip_tile_ex(const double *xyzr, size_t n, const double box[3], const int tiles[3],
                          size_t max_spheres, const volatile int *cancel, double **out,
                          size_t *nout, gp_error *err);
gp_status gp_flip_contacts_ex(const gp_dem3d_contact *c, size_t nc, const double *xyzr, size_t n,
                              const int tiles[3], const volatile int *cancel,
                              gp_dem3d_contact **out, size_t *nout, gp_error *err);

#endif /* GP_FLIP_H */
