/* gp_clump3d.h -- a clump: overlapping spheres inside one 3D grain, for the DEM codes that model
 * a grain as a rigid body of spheres (LAMMPS rigid bodies, LIGGGHTS multisphere, YADE clumps).
 *
 * Input: a closed triangle mesh (vertices as x y z doubles, triangles as three uint32 vertex
 * indices, counter-clockwise seen from outside), e.g. a radius field r(u) on an icosphere of
 * 2,562 vertices / 5,120 triangles, possibly stretched by an affine map, possibly non-convex.
 * Star-shape is not needed: any closed, consistently oriented, edge-manifold mesh will do (every
 * directed edge once, its reverse once; checked).
 * Output: spheres (x, y, z, r) that lie inside the mesh, the first of them the largest, and the
 * measures of their union against the grain's own volume, centroid and inertia.
 *
 * Method: greedy inscribed spheres for the uncovered volume, on voxels (deterministic).
 *  0. Frame. The work is done in the mesh's principal frame: origin at its centroid, axes its
 *     principal axes of inertia, the longest first, each turned so that the vertices' third
 *     moment along it is >= 0, the third their cross product. A needle along a diagonal gets
 *     as many voxels as one along x, and a grain turned and moved gets its clump turned and
 *     moved (to 1e-9 of its size in the test), unless its principal axes are degenerate.
 *  1. Voxels. Cubic voxels of side h = (V / voxels)^(1/3) (V the mesh's volume, `voxels` a
 *     parameter, default 8,192: about that many voxel centres fall inside the grain, whatever
 *     its size) over the mesh's bounding box plus one voxel each side; h grows so that the grid
 *     never holds more than 16 `voxels` voxels (a grain that fills little of its box). Lengths
 *     are relative: scaling the mesh scales the clump.
 *  2. Inside. Lines of voxel centres along x cross the mesh where the triangles' (y, z)
 *     projections cover them; each crossing adds -1 (the triangle faces +x: the line leaves)
 *     or +1 to a winding number, and a centre is inside where it is > 0. A line through an
 *     edge or a vertex of the projection counts as if moved by an infinitesimal step in a fixed
 *     direction (simulation of simplicity, the "top-left" rule), each edge's sign computed once
 *     from its lower-indexed vertex, so a closed mesh counts every crossing exactly once.
 *  3. Distances d~ at inside centres, to the nearest mesh vertex: seeded at the eight centres
 *     around each vertex and beside each crossing, carried by two raster sweeps over the 26
 *     neighbours (a nearest-point transform). d~ >= d, the distance to the surface (vertices
 *     lie on it); on the test grains d~ - d is 0.07 h on average, at most about h. d~ only
 *     ranks: radii come from exact distances (5., 6.).
 *  4. Candidates: centres of maximal balls, the discrete medial surface: an inside centre p is
 *     dropped when a neighbour q has d~(q) - d~(p) >= 0.8 |q - p| (the ball of q holds the
 *     ball of p but for a sliver; off the medial surface d rises at slope >= 0.9 towards one
 *     of the 26 neighbours). For coverage nothing is lost: any inscribed ball lies in a
 *     maximal one. A candidate's radius r_p is its exact distance to the triangles around its
 *     nearest vertex (>= d(p)).
 *  5. Greedy. The gain of a candidate is the number of still uncovered inside centres in its
 *     ball B(p, r_p), counted on rows of bits (a popcount a row, row widths from a table of
 *     integer square roots). The candidate of the largest gain wins (ties: the lower voxel
 *     index). Gains only fall as coverage grows, so they are kept in a heap of upper bounds
 *     (at first the lattice points of the ball) and recounted only when one reaches the top
 *     stale, a count staying exact while the candidate's ball misses the spheres added since
 *     (lazy greedy: the choice of recounting all of them). Each winner becomes a sphere (6.),
 *     the centres inside the sphere are marked covered, and the search goes on until
 *     spheres_max spheres, or no candidate covers anything.
 *  6. The sphere of a winning candidate p: q is p's nearest surface point (exact: a tree of
 *     triangle boxes), n the unit vector from q to p; the sphere is the largest ball tangent at
 *     q with its centre on the ray q + R n, R <= |p - q| + h (shrinking ball: a tangent ball is
 *     shrunk to pass through the nearest surface point to its centre, until none is nearer;
 *     the balls are nested, so one range query lists the triangles that can enter any of
 *     them, and each step keeps those entering its ball). It holds B(p, |p - q|) and is
 *     centred off the grid, so a ridge between voxel centres costs no radius. Radius: the
 *     distance from its centre to the nearest listed triangle, at most R, times (1 - 1e-12).
 *     The first sphere then moves up the distance to the surface to a local maximum (steps
 *     along the mean unit vector from its near surface points, kept while the exact distance
 *     grows, halved down to 1e-9 r): nothing is covered yet, so it should be the largest ball
 *     there is, not the largest holding a voxel centre's ball (a sphere mesh: its inscribed
 *     sphere, to 1e-9).
 *     Radii: the first sphere (the largest ball: nothing is covered yet) sets r_1; a later
 *     sphere larger than r_1 is shrunk to r_1 about its centre, and one smaller than
 *     min_radius_ratio r_1 is refused (the candidate is dropped, the search goes on), as is a
 *     candidate with r_p < min_radius_ratio r_1. So r_1 is the largest radius and every radius
 *     is >= min_radius_ratio r_1.
 *  Prefix property: no decision depends on spheres_max, so for the same voxels the clump of
 *  spheres_max = k is the first k spheres of any larger cap's, and the union's volume grows
 *  with spheres_max. (Many spheres want more voxels: with 100 spheres, 16,384 voxels take a
 *  quarter off the volume error of 4,096; docs/design/clump3d.md.)
 *
 * Why not Ferellec-McDowell (tangent spheres at surface points, as core/2d/gp_odec.h): it
 * follows the surface, which is what contacts see, but it chooses spheres by the surface they
 * cover, not the volume, so volume and inertia converge slowly with the sphere count, and a
 * tangent sphere at a vertex still pokes out between vertices. The volume greedy puts the
 * first spheres where the mass is, and containment is exact (a radius is a distance).
 *
 * Containment (the tolerance): every sphere has r <= (1 - 1e-12) dist(c, mesh), dist the exact
 * Euclidean distance to the triangles (up to rounding, ~1e-16 of the grain's size), and its
 * centre inside: its ball, free of the surface, holds the inside centre p it grew from (the
 * first sphere's moves each stay within the ball before them).
 *
 * Union measures (gp_clump3d_union, independent of the choice; gp_clump3d_build measures in the
 * principal frame and turns the result back): a ball that overlaps no other is exact; the
 * others are integrated on lines along x through the centres of a square grid of 128 cells
 * across the larger side of their box in (y, z), each line's chords merged and integrated
 * exactly in x (powers of x), the midpoint rule across lines. Accuracy: 7e-5 rms, 2e-4 at worst
 * on the volume of 48 clumps of 5 to 300 spheres against 3,000^2 lines; 6e-5 on volume and
 * inertia of two overlapping balls against exact values (tests/core/3d).
 *
 * Figures of merit (relative to the grain given; unit density for both bodies):
 *  volume_error        (V_union - V_grain) / V_grain (<= 0 up to the quadrature: the union
 *                      lies inside);
 *  inertia_error       |lambda_union - lambda_grain| / |lambda_grain|: the principal moments
 *                      (eigenvalues of each body's inertia tensor about its own centroid,
 *                      ascending) as 3-vectors, Euclidean norms; what a DEM code gets when it
 *                      integrates the spheres at the grain's density;
 *  inertia_shape_error the same with lambda_union scaled by V_grain / V_union (the union given
 *                      the grain's mass): the error in the distribution of the mass alone;
 *  centroid_offset     |c_union - c_grain| / R_eq, R_eq = (3 V_grain / (4 pi))^(1/3).
 * (LAMMPS, LIGGGHTS and YADE can be given the grain's own mass, centre and inertia for a
 * clump; these numbers say what is lost when they are not.)
 *
 * Work and memory bounds. With N = voxels (<= 2^18), M <= 16 N voxels in the grid, T
 * triangles, k = spheres_max (<= 1000), C <= N candidates: memory about 22 M + 300 T bytes
 * (at most 95 MB + 300 T; about 0.4 MB + 300 T with the defaults);
 * time O(T log T) for the checks and the tree, O(M + T) for inside and distances, O(C) heap
 * entries, at most (k + 1) C gain counts of at most pi (r_1 / h)^2 + 1 rows each (measured:
 * about 50 counts a sphere), k + C sphere fits of one nearest and one range query and at most
 * 32 list scans (O(T) each at worst), the first sphere's ascent at most 96 tries of O(T), and
 * the union O(k^2 + 128^2 m) for m balls a line.
 * Measured (docs/design/clump3d.md): a grain of 5,120 triangles, 30 spheres, default voxels:
 * 8 ms on one core of the development VM (about a third of a desktop core's speed; 10 spheres
 * 5 ms, 100 spheres 26 ms), volume error -5 % and inertia error 8 % on random rough grains.
 *
 * Determinism: single-threaded, no state: the same input gives the same bytes (on one build).
 * Ownership: the input arrays are only read; the result owns its spheres (malloc'ed; free them
 * with gp_clump3d_result_free). Thread safety: no state besides the arguments; concurrent
 * calls on different results are safe (the mesh may be shared).
 */
#ifndef GP_CLUMP3D_H
#define GP_CLUMP3D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"

typedef struct gp_clump3d_params {
    size_t spheres_max;      /* the most spheres, 1 .. 1000 (default 30) */
    double min_radius_ratio; /* smallest radius / largest, in (0, 1] (default 0.1) */
    size_t voxels;           /* voxel centres inside the grain, about: 0 for the default
                              * 8,192, else 1,000 .. 262,144 */
} gp_clump3d_params;

/* The defaults above. */
void gp_clump3d_params_defaults(gp_clump3d_params *p);

typedef struct gp_clump3d_sphere {
    double x, y, z, r;
} gp_clump3d_sphere;

/* A rigid body of unit density: volume, centroid, and inertia tensor about the centroid
 * (I = integral of (|s|^2 Id - s s^T) dV, s from the centroid; row-major 3 x 3, symmetric). */
typedef struct gp_clump3d_body {
    double volume;
    double centroid[3];
    double inertia[9];
} gp_clump3d_body;

typedef struct gp_clump3d_result {
    gp_clump3d_sphere *spheres; /* nspheres (>= 1), the first the largest; malloc'ed */
    size_t nspheres;
    gp_clump3d_body grain;      /* the reference: the caller's, or the mesh's when none given */
    gp_clump3d_body clump;      /* the union of the spheres (gp_clump3d_union, in the grain's
                                 * principal frame, turned back) */
    double volume_error;        /* see "Figures of merit" */
    double inertia_error;
    double inertia_shape_error;
    double centroid_offset;
    double r_max, r_min;        /* the largest and smallest radius */
    double voxel;               /* h */
    size_t voxels_inside;       /* inside voxel centres */
    size_t candidates;          /* medial centres the greedy chose from */
    double covered;             /* fraction of the inside centres in some sphere */
    int capped;                 /* 1 when spheres_max stopped the search with gain left */
} gp_clump3d_result;

/* The clump of the mesh xyz (nv >= 4 vertices, 3 doubles each), tri (nt >= 4 triangles, 3
 * indices each). grain: the grain's volume, centroid and inertia for the figures of merit
 * (its volume must match the mesh's within 1e-6); NULL to take them from the mesh
 * (gp_clump3d_mesh_body). params may be NULL (defaults).
 * GP_ERR_INVALID: bad arguments, the message naming the argument (a NULL array, too few
 * vertices or triangles, an index out of range, a triangle with a repeated vertex, a vertex
 * not finite, a mesh not closed or not consistently oriented, clockwise triangles (negative
 * volume), spheres_max, min_radius_ratio or voxels out of range, a grain not finite or not
 * matching the mesh); GP_ERR_DEGENERATE: a mesh without volume (flat; |V| <= 1e-12 of its
 * box's diagonal cubed) or too thin for one voxel centre inside; GP_ERR_NOMEM. On error *out is
 * zeroed. */
gp_status gp_clump3d_build(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                           const gp_clump3d_body *grain, const gp_clump3d_params *params,
                           gp_clump3d_result *out, gp_error *err);

void gp_clump3d_result_free(gp_clump3d_result *r);

/* Volume, centroid and inertia of the solid a closed mesh bounds (divergence theorem, exact up
 * to rounding; counter-clockwise triangles give a positive volume, clockwise a negative one and
 * negated moments). Checks only the arrays and indices (GP_ERR_INVALID). */
gp_status gp_clump3d_mesh_body(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                               gp_clump3d_body *body, gp_error *err);

/* Volume, centroid and inertia (about its centroid) of the union of n balls (n >= 0; r >= 0,
 * all finite), by the power-cell quadrature above; n = 0 or all radii 0 give zeros.
 * GP_ERR_INVALID: s NULL with n > 0, a value not finite, a negative radius; GP_ERR_NOMEM. */
gp_status gp_clump3d_union(const gp_clump3d_sphere *s, size_t n, gp_clump3d_body *body,
                           gp_error *err);

/* The figures of merit of a body against a reference (see above): any pointer may be NULL.
 * The principal moments come from gp_mesh3d_eigen_sym3. */
void gp_clump3d_compare(const gp_clump3d_body *body, const gp_clump3d_body *ref,
                        double *volume_error, double *inertia_error,
                        double *inertia_shape_error, double *centroid_offset);

#endif /* GP_CLUMP3D_H */
