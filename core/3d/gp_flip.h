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
 *
 * Cancel: each function reads the caller's flag *cancel (may be NULL) atomically between
 * tiles and stops with GP_ERR_CANCELLED when it is up, leaving nothing allocated (a tiling of
 * 20 million spheres takes seconds); results do not depend on it. Ownership: inputs are only
 * read; arrays handed out are malloc'ed and the caller's to free. Thread safety: no state;
 * concurrent calls are safe.
 */
#ifndef GP_FLIP_H
#define GP_FLIP_H

#include <stddef.h>

#include "gp_dem3d.h"
#include "gp_error.h"

/* Tiles xyzr[4n] (box [0, box]) into *out (4 * n * nx * ny * nz, malloc'ed). max_spheres caps
 * the result (GP_ERR_INVALID beyond it). */
gp_status gp_flip_tile(const double *xyzr, size_t n, const double box[3], const int tiles[3],
                       size_t max_spheres, const volatile int *cancel, double **out,
                       size_t *nout, gp_error *err);

/* Maps the sample's contacts (n spheres) to the tiled packing: every sphere contact to each
 * tile (normal and force mirrored), every wall contact to a contact with the sphere's image
 * across an inner face (full overlap 2 delta, the same normal force, Eq. 13) or to the tiled
 * box's wall on the outer faces. Sphere pairs first (i < j, sorted), then wall contacts (by
 * sphere), in *out (malloc'ed). The array holds up to tiles x nc contacts (72 bytes each; ~2 GB
 * for 7.5 million spheres), so a caller that only needs measures over the contacts should
 * stream them instead (gp_flip_contacts_each). */
gp_status gp_flip_contacts(const gp_contact3d *c, size_t nc, size_t n, const int tiles[3],
                           const volatile int *cancel, gp_contact3d **out, size_t *nout,
                           gp_error *err);

/* Receives the next k (1 <= k <= cap) contacts of the tiled packing in chunk, which is the
 * caller's buffer and is overwritten after the call returns. Returns GP_OK to go on; any other
 * status stops the walk and is returned by gp_flip_contacts_each as it is (the visitor sets
 * err itself). */
typedef gp_status (*gp_flip_visit_fn)(void *user, const gp_contact3d *chunk, size_t k,
                                      gp_error *err);

/* The streaming form of gp_flip_contacts: the same contacts in the same order (so the
 * same multiset, and sums over them in the same order give the same bits), handed to visit
 * in chunks of at most cap through the caller's buffer buf[cap] (cap >= 1), with no
 * allocation that grows with the tiling: memory O(nc) for the sample's contacts sorted once,
 * instead of O(tiles x nc).
 * How: within a tile, every contact made there has i = t n + i_sample, and j = t n + j_sample
 * (a sphere pair) or t' n + i_sample with t' = t + stride along the axis (an image pair):
 * their (i, j) order is the order of the key (i_sample, j_sample or stride n + i_sample),
 * which does not depend on t. Sorting the sample's contacts by that key once therefore gives
 * every tile's sorted run by a filtered walk. Pass 1 walks the tiles for the sphere and
 * image pairs, pass 2 walks them again for the contacts with the outer walls (by tile, then
 * in the sample's order), as gp_flip_contacts lists them.
 * *cancel (may be NULL) is read atomically between tiles: GP_ERR_CANCELLED, nothing left
 * allocated (what was already visited stays visited). Errors: GP_ERR_INVALID (tiles, cap,
 * buf), GP_ERR_NOMEM, or the visitor's status. Thread safety: reads c only; concurrent calls
 * with different buffers are safe. */
gp_status gp_flip_contacts_each(const gp_contact3d *c, size_t nc, size_t n, const int tiles[3],
                                const volatile int *cancel, gp_contact3d *buf, size_t cap,
                                gp_flip_visit_fn visit, void *user, gp_error *err);

#endif /* GP_FLIP_H */
