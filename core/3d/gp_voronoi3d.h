/* gp_voronoi3d.h -- bounded 3D Voronoi tessellation of a convex container, with local updates.
 *
 * N seeds inside a convex container D; cell i is the set of points of D closer to seed i than
 * to any other seed: D cut by the bisector half-spaces H_ij = {x : |x - s_i| <= |x - s_j|}.
 * The cells are convex polyhedra that tile D.
 *
 * Container (gp_voronoi3d_container; the helpers below fill one):
 *  - an axis-aligned box [lo, hi];
 *  - a bounded convex polyhedron given by m >= 4 half-spaces n_k . x <= d_k (n_k need not be
 *    unit vectors; redundant half-spaces are allowed; an unbounded or empty set is refused);
 *  - a cylinder with its axis parallel to z: a prism of `facets` side facets (64 when 0, at
 *    least 3) inscribed in the circle of radius r, its vertices at angles 2 pi k / facets. The
 *    prism is the container: gp_voronoi3d_lost_volume() is pi r^2 h minus its volume
 *    (about (2 pi^3 / 3) r^2 h / facets^2, 0.16 % at 64 facets).
 * Wall ids: a face on the container's boundary has the negative neighbour id -1 - k, k the
 * container's half-space: for a box 0..5 = x-, x+, y-, y+, z-, z+; for a polyhedron the
 * caller's order; for a cylinder the side facets 0 .. facets-1 (facet k faces the angle
 * 2 pi (k + 1/2) / facets), then the bottom (z0) and the top (z1).
 *
 * Seeds. Every seed must lie in the closed container (within 1e-12 of the container's size,
 * the diagonal of its bounding box). Two seeds closer than 1e-10 of that size are duplicates:
 * gp_voronoi3d_create() and the moves refuse them with GP_ERR_INVALID naming both indices.
 *
 * Algorithm. Seeds are binned in a uniform grid over the container's bounding box (about 3 per
 * bin). Cell i starts as a box (the container itself, or its bounding box enlarged by 10 %)
 * and is cut by the bisector planes of the seeds of the bins around seed i, nearest bins
 * first: the bins within Chebyshev distance 3 of seed i's bin in increasing order of the least
 * distance a point of that bin can have to them (the 27 around it first), in batches of equal
 * bound, the seeds of a batch in increasing distance (ties by index); then, for a cell that
 * reaches farther (a sparse corner), whole shells of bins. After the first batch the
 * container's half-spaces cut it too. Security radius: with R the largest distance from seed
 * i to a vertex of the current polyhedron, a seed farther than 2 R cannot cut (its bisector
 * lies beyond every vertex), so a bin or a batch that far is skipped and the search stops.
 * With seeds spread through the container a cell costs O(1), the build O(N). The nearest seed
 * of the first batch also tells a duplicate.
 *
 * Plane cutting. The polyhedron is kept as its vertex graph (voro++'s representation: each
 * vertex with its edges in order around it, each edge with the face on its left), in
 * coordinates relative to its seed, and cut in place. A plane is first tested against every
 * vertex (most planes tested cut nothing); a plane that cuts classifies every vertex once by
 * its signed distance: outside (> tol), inside (< -tol) or on; tol = 1e-12 R (relative to the
 * cell's size, so scaling all coordinates changes nothing). An edge from inside to outside
 * gets one new vertex; the new face (the cap) is found by walking, from each new vertex, its
 * face through the outside vertices to the next crossing; only the outside vertices and their
 * edges are visited, and the new vertices take the outside ones' places. With on vertices
 * (degenerate input) the same rules of the one classification decide everything: a face with
 * an outside vertex and no inside one goes, one with both is clipped (each run of outside
 * vertices replaced by its ends, a new vertex or an on vertex), the cap is the loop of those
 * ends and of the edges between on vertices with a face that goes on one side only, and the
 * on vertices' edges are rebuilt around the faces that stay. So the result is a closed
 * polyhedron whatever the degeneracy: a plane through vertices or along edges (lattices,
 * co-spherical seeds) cuts nothing it should not, and the volumes stay exact. A cell whose
 * cutting goes wrong anyway (a cap that is not one loop) is reported (GP_ERR_INTERNAL), never
 * guessed.
 *
 * Faces and neighbours. A face is kept only with a vertex strictly inside the cutting plane,
 * so it has positive area; j is a neighbour of i when cell i has a face on the bisector of i
 * and j. Faces are not merged: one face per bounding plane. voro++ does not merge either: on
 * 1,000 and 10,000 random seeds it gives the same face count for every cell
 * (tests/core/3d/test_voronoi3d_voro.c). Where many bisectors pass through one point
 * (co-spherical seeds: all of them through the sphere's centre) rounding can leave a sliver
 * face of area ~1e-20 of the cell's surface on one cell and not on its neighbour; the
 * volumes are unaffected, and the neighbour relation is mutual for every face above that.
 *
 * Canonical cells: the same planes give the same bits. The cutting leaves each vertex where its
 * history put it (an edge's crossing with a plane, interpolated on an intermediate polyhedron
 * that other cut orders never build), so the finished polyhedron is rewritten from its planes
 * alone. A face's plane is the one it was cut with, a function of its tag and the seeds only:
 * for seed j, n = s_j - s_i and c = |n|^2 / 2 (coordinates relative to the container's
 * bounding box's lower corner, n . x <= c in cell i's seed frame); for a wall, the container's
 * half-space moved to that frame. Each vertex is recomputed from the planes of the faces
 * that meet at it, sorted by tag: from three (the generic case) their point by Cramer's rule
 * in that order; from four or more (degenerate input), the first triple in lexicographic order
 * of tags whose conditioning |det| / (|n_a| |n_b| |n_c|) reaches 1e-3, else the
 * best-conditioned (of the lowest 16 planes), so a near-singular triple is not used where a
 * sound one exists. The faces are written in increasing tag (the walls, -1 - k, first), each
 * loop from its vertex of lowest key (the sorted list of its faces' tags, lexicographic), the
 * vertices numbered in order of first appearance along the loops so written; volume, centroid
 * and inertia are integrated from those vertices in that order. So every reported number of a
 * cell (vertices and their order, loops, neighbour ids, volume, centroid, inertia) is a
 * function of its seed and its final planes, not of the order or the history of its cuts. A
 * recomputed vertex lies within about 1e-16 R / conditioning of the cut's (7e-13 R at most
 * on random seeds, 2.4e-10 R with lattices, co-spherical seeds and scaled containers); one
 * farther than 1e-6 R, or not finite, would keep the cut's position (a guard, never met in
 * the tests). Cost: about a third of a cell's time (docs/design/voronoi3d.md has the
 * times).
 *
 * Local updates. Lemma: cell j (j != i) changes when seed i moves from a to b only if i is a
 * neighbour of j before or after the move. Proof: V_j = W_j intersected with H_ji, with
 * W_j = D intersected with H_jk over k != i, j, which the move does not change. If i is not a
 * neighbour of j with i at a, H_ji(a) is redundant (a half-space that cut W_j would cut off a
 * part of positive volume and leave a face of positive area), so V_j = W_j; likewise with i at
 * b; so V_j is W_j before and after. Neighbours are mutual (a shared face), so the cells to
 * recompute are i, its neighbours before the move (kept with cell i) and its neighbours after
 * it (read from the new cell i, computed first). gp_voronoi3d_try_move() recomputes those --
 * taken from the seeds whose planes cut cell i while it was being built, a superset of its
 * neighbours, so that a face at the tolerance's edge is still covered -- with the same
 * function as the full build (the grid search). A cell that is not recomputed keeps its final
 * planes, and its bits are a function of them (canonical cells, above), even where the moved
 * seed cut one of its intermediate polyhedra. So after any sequence of moves, committed or
 * rolled back, every cell is bit for bit the one a full rebuild of the same seeds gives:
 * vertices, loops, neighbours, volume, centroid and inertia (test_voronoi3d compares every
 * cell after each of 10,000 moves on random seeds in a box and in a cylinder, with memcmp).
 * The one exception is degenerate input, where four or more planes meet within the cutting
 * tolerance: there the cut order can decide which of the coincident planes keeps a face (or a
 * one-sided sliver, above), and a cell not recomputed keeps the choice of its last
 * computation; the volumes still agree to 1e-12 (on a cubic lattice with moves to its quarter
 * points every cell was bit-equal all the same).
 *
 * Memory. One block per cell (vertices, loops, face tags, neighbours, cutters), replaced when
 * the cell is recomputed: about 1.4 KB a cell in all (150 MB for 10^5 random seeds).
 *
 * Coordinates. Internally everything is relative to the container's bounding box's lower
 * corner and each cell to its seed; tolerances are relative (1e-12 of the cell for cuts, of
 * the container for the inside test), so a container scaled by 1e-6 or 1e6 or moved far from
 * the origin behaves the same. Output coordinates are the caller's.
 *
 * Determinism: single-threaded; the tessellation is a pure function of the container and the
 * seeds (bit for bit on one build of the code), and after any sequence of moves bit for bit
 * the tessellation of the current seeds (barring degenerate input, above).
 *
 * Ownership: gp_voronoi3d_create() copies the caller's arrays; the object owns everything and
 * gp_voronoi3d_destroy() frees it. Thread safety: one object per thread for moves; queries
 * (the const functions) may run concurrently with each other, not with a move or a build.
 */
#ifndef GP_VORONOI3D_H
#define GP_VORONOI3D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"

typedef struct gp_voronoi3d gp_voronoi3d;

typedef enum gp_voronoi3d_kind {
    GP_VORONOI3D_BOX,
    GP_VORONOI3D_CONVEX,
    GP_VORONOI3D_CYLINDER
} gp_voronoi3d_kind;

typedef struct gp_voronoi3d_container {
    gp_voronoi3d_kind kind;
    double lo[3], hi[3];  /* BOX */
    const double *planes; /* CONVEX: nplanes rows (nx, ny, nz, d) meaning n . x <= d */
    size_t nplanes;
    double axis[2];       /* CYLINDER: the axis (parallel to z) passes through (x, y) = axis */
    double radius, z0, z1;
    size_t facets;        /* CYLINDER: side facets of the prism, 0 for 64 */
} gp_voronoi3d_container;

gp_voronoi3d_container gp_voronoi3d_box(const double lo[3], const double hi[3]);
/* planes is not copied here (create copies it). */
gp_voronoi3d_container gp_voronoi3d_convex(const double *planes, size_t nplanes);
gp_voronoi3d_container gp_voronoi3d_cylinder(double x, double y, double radius, double z0,
                                             double z1, size_t facets);

/* Builds the tessellation of seeds (n >= 1 points, 3 doubles each, x y z) in container c.
 * Returns NULL on error: GP_ERR_INVALID (bad container, a seed outside or not finite,
 * duplicates, n > 2^31 - 1), GP_ERR_NOMEM, GP_ERR_INTERNAL (a cell could not be built). */
gp_voronoi3d *gp_voronoi3d_create(const gp_voronoi3d_container *c, const double *seeds, size_t n,
                                  gp_error *err);
/* The same, stopping early with GP_ERR_CANCELLED when *cancel (read atomically every 1024
 * cells; may be NULL) becomes non-zero. The result does not depend on cancel. */
gp_voronoi3d *gp_voronoi3d_create_ex(const gp_voronoi3d_container *c, const double *seeds,
                                     size_t n, const volatile int *cancel, gp_error *err);
void gp_voronoi3d_destroy(gp_voronoi3d *v);

size_t gp_voronoi3d_count(const gp_voronoi3d *v);
/* The container's volume (for a cylinder, the prism's) and, for a cylinder, pi r^2 h minus
 * it (0 for the other containers). */
double gp_voronoi3d_container_volume(const gp_voronoi3d *v);
double gp_voronoi3d_lost_volume(const gp_voronoi3d *v);
/* The volume a prism of `facets` side facets inscribed in a cylinder of radius r and height
 * h loses against it: pi r^2 h - (facets / 2) r^2 sin(2 pi / facets) h. */
double gp_voronoi3d_cylinder_lost_volume(double r, double h, size_t facets);
void gp_voronoi3d_seed(const gp_voronoi3d *v, size_t i, double p[3]);

/* Cell i's volume, centroid and inertia tensor about its centroid for unit density
 * (I = integral of (|r|^2 Id - r r^T) dV, r from the centroid; row-major 3 x 3, symmetric).
 * A bad index gives 0 / zeros. */
double gp_voronoi3d_cell_volume(const gp_voronoi3d *v, size_t i);
void gp_voronoi3d_cell_centroid(const gp_voronoi3d *v, size_t i, double c[3]);
void gp_voronoi3d_cell_inertia(const gp_voronoi3d *v, size_t i, double I[9]);

/* Cell i's vertices (3 doubles each) written into xyz (at most cap vertices; xyz may be NULL
 * with cap 0); returns their count (0 for a bad index). */
size_t gp_voronoi3d_cell_vertices(const gp_voronoi3d *v, size_t i, double *xyz, size_t cap);
size_t gp_voronoi3d_cell_face_count(const gp_voronoi3d *v, size_t i);
/* Face f of cell i: its vertex loop (indices into the cell's vertices, counter-clockwise seen
 * from outside the cell) written into loop (at most cap), and in *neighbour (may be NULL) the
 * seed across it or a negative wall id (-1 - k). The faces come in increasing neighbour id
 * (walls first), each loop from its canonical first vertex (see "Canonical cells"). Returns
 * the loop's length (0 for a bad index). */
size_t gp_voronoi3d_cell_face(const gp_voronoi3d *v, size_t i, size_t f, uint32_t *loop,
                              size_t cap, int32_t *neighbour);
/* The outward plane of each face of cell i: planes[4 f ..] = (nx, ny, nz, d), n a unit normal
 * (Newell's, of the face's loop) and n . x <= d inside, in the order of the faces; at most cap
 * faces written, the count returned. */
size_t gp_voronoi3d_cell_planes(const gp_voronoi3d *v, size_t i, double *planes, size_t cap);
/* The neighbour seeds of cell i (ascending, no repeats) into out (at most cap); returns their
 * count. */
size_t gp_voronoi3d_neighbours(const gp_voronoi3d *v, size_t i, size_t *out, size_t cap);

/* Moves seed i to p (caller's coordinates) and updates the cells it affects. On error nothing
 * has changed (GP_ERR_INVALID: p outside the container or not finite, a duplicate, a bad
 * index, or a move pending; GP_ERR_NOMEM; GP_ERR_INTERNAL). */
gp_status gp_voronoi3d_move(gp_voronoi3d *v, size_t i, const double p[3], gp_error *err);

/* The same move as a transaction: after GP_OK the new cells are visible, and the caller must
 * end it with gp_voronoi3d_commit() or gp_voronoi3d_rollback() (which restores the seed and
 * the cells bit for bit) before any other move. gp_voronoi3d_changed() lists the cells the
 * pending move recomputed (the moved seed first); the pointer is valid until the transaction
 * ends. */
gp_status gp_voronoi3d_try_move(gp_voronoi3d *v, size_t i, const double p[3], gp_error *err);
void gp_voronoi3d_commit(gp_voronoi3d *v);
void gp_voronoi3d_rollback(gp_voronoi3d *v);
size_t gp_voronoi3d_changed(const gp_voronoi3d *v, const uint32_t **cells);

/* 1 if p lies in the closed container (within 1e-12 of its size). */
int gp_voronoi3d_contains(const gp_voronoi3d *v, const double p[3]);

/* Container-only queries (no tessellation needed), for placing seeds before a build.
 *
 * gp_voronoi3d_container_bounds(): the container's bounding box as gp_voronoi3d_create() sets
 * it up: a box's lo and hi; a cylinder's prism or a convex polyhedron's vertices' extent
 * (computed by cutting, within rounding of the exact one). Fails as create would for the
 * container (GP_ERR_INVALID: a bad box or cylinder, fewer than 4 planes, an empty or
 * unbounded polyhedron; GP_ERR_NOMEM); then lo and hi are left alone.
 *
 * gp_voronoi3d_container_inside(): 1 if p lies in the closed container within 1e-12 of its
 * size, else 0 (also for p not finite, and for a cylinder or a polyhedron with a bad
 * parameter; half-spaces that bound nothing only gp_voronoi3d_container_bounds() tells),
 * given lo and hi from gp_voronoi3d_container_bounds() (for a box, the test uses them, not
 * c->lo and c->hi): the very test gp_voronoi3d_create() and the moves apply to a seed (the
 * same frame and arithmetic, the same answer), so a point it accepts is never refused as
 * outside. Cost: O(1) for a box and for a cylinder's point not near the facets (decided by
 * the inscribed and circumscribed circles, with margins far above the facet tests'
 * rounding); O(planes) for a polyhedron and near a cylinder's rim (its facet planes computed
 * each call, a cos and a sin each). */
gp_status gp_voronoi3d_container_bounds(const gp_voronoi3d_container *c, double lo[3], double hi[3],
                                        gp_error *err);
/* The container's volume as gp_voronoi3d_container_volume() gives it after a build (a
 * cylinder: its prism's) and its bounds (lo, hi may be NULL); fails as
 * gp_voronoi3d_container_bounds() does. */
gp_status gp_voronoi3d_container_measure(const gp_voronoi3d_container *c, double *volume, double lo[3],
                                         double hi[3], gp_error *err);
int gp_voronoi3d_container_inside(const gp_voronoi3d_container *c, const double lo[3],
                                  const double hi[3], const double p[3]);

#endif /* GP_VORONOI3D_H */
