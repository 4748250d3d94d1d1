/* gp_voronoi.h -- bounded Voronoi tessellation of a polygonal container, with local updates.
 *
 * Mollon & Zhao 2012 §3.2: N seeds inside a container D; cell i is the set of points of D closer
 * to seed i than to any other seed. The union of the cells is D, cells do not overlap.
 *
 * Container. A simple outer ring (any orientation, convex or not) with optional simple holes
 * (disjoint, inside the outer ring). A circle is polygonised by the caller with
 * gp_voronoi_circle_polygon(). Rings are not checked for simplicity beyond cheap tests (too few
 * points, zero area, a hole vertex outside the outer ring): the caller guarantees it.
 *
 * Seeds. Every seed must lie in the closed container (a seed on the boundary is allowed, within
 * 1e-12 of the container's bounding-box size). Two seeds closer than 1e-12 of that size are
 * "duplicates": gp_voronoi_create() and the moves refuse them with GP_ERR_INVALID naming both
 * indices (no jitter: the caller decides).
 *
 * Cells in non-convex containers. A Voronoi region can be split by the container (an L-shape's
 * notch, a hole): the cell then has several parts, all of them belonging to the cell (its area is
 * the sum). gp_voronoi_cell_seed_part() names the part that holds the seed (for a seed on a
 * part boundary, the part nearest to it); filling uses that part. A hole lying entirely inside a
 * cell is joined to the part around it by a zero-width "keyhole" bridge (two opposite edges), so
 * every part is one closed ring whose shoelace area is its true area.
 *
 * Orientation. Cell orientation is the grain orientation of Fig. 1a, gp_min_caliper()'s
 * angle_rad in (-pi/2, pi/2]: the direction of the side of the convex hull across which the
 * caliper width is smallest (gp_min_caliper_edge on squared widths). A multi-part cell's
 * orientation is that of the seed's part; parts and holes are located with gp_poly_contains.
 *
 * Neighbours. j is a neighbour of i when cells i and j share a boundary segment inside the
 * container (of length above ~1e-13 of the container size).
 *
 * Local updates. Moving one seed recomputes only the cells it can affect (its neighbours before
 * and after the move, about 9), in a time independent of N: each from candidates taken from the
 * neighbour lists -- a best-first search of the neighbour graph for the moved seed, the
 * neighbours of the cell and of the moved seed for the others (gp_voronoi.c, "Moves", says why
 * these sets hold every new neighbour). A full build finds candidates in a uniform grid of
 * seeds instead. Either way a cell's vertices are recomputed from the lines that bound it
 * (canonical), so a cell recomputed after moves is bit-for-bit the cell a fresh
 * gp_voronoi_create() of the same seeds gives, and a rolled-back move restores everything bit
 * for bit.
 *
 * Memory. Each cell's data (polygon, tags, neighbour lists) keeps its place for the life of the
 * object (a committed move copies the new cells back): cells numbered so that neighbours have
 * nearby indices (gp_imc.h numbers its seeds along a Hilbert curve) stay close in memory.
 *
 * Coordinates. Internally everything is relative to the container's bounding box (origin at its
 * lower-left corner, tolerances relative to its size), so the unit square scaled by 1e-6 or 1e6
 * behaves identically. Output coordinates are the caller's.
 *
 * Not thread-safe per object (queries may run concurrently with each other, not with moves).
 */
#ifndef GP_VORONOI_H
#define GP_VORONOI_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_geom.h"

typedef struct gp_voronoi gp_voronoi;

/* Builds the tessellation. outer: nouter >= 3 points. holes: nholes rings, hole h has nhole[h]
 * points (holes and nhole may be NULL when nholes == 0). seeds: n >= 1 points. Nothing is kept
 * of the caller's arrays. Returns NULL on error (GP_ERR_INVALID for bad input or duplicates,
 * GP_ERR_NOMEM, GP_ERR_INTERNAL if a cell could not be built). */
gp_voronoi *gp_voronoi_create(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                              const size_t *nhole, size_t nholes, const gp_vec2 *seeds, size_t n,
                              gp_error *err);
/* The same, stopping early when *cancel (read atomically every few thousand cells; may be NULL)
 * becomes non-zero: then NULL with GP_ERR_CANCELLED. A tessellation of 10^6 seeds takes
 * seconds; the job service passes its cancel flag here. The result does not depend on cancel. */
gp_voronoi *gp_voronoi_create_ex(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                                 const size_t *nhole, size_t nholes, const gp_vec2 *seeds,
                                 size_t n, const volatile int *cancel, gp_error *err);
void gp_voronoi_destroy(gp_voronoi *v);

/* A regular polygon inscribed in the circle (centre c, radius r), counter-clockwise, whose largest
 * distance to the circle (the sagitta r (1 - cos(pi/n))) is <= tol; at least 8 vertices, at most
 * 2^20. Its area is below the disc's by about (2/3) tol * perimeter. *out is malloc'ed: free()
 * it. tol <= 0 or r <= 0 gives GP_ERR_INVALID. */
gp_status gp_voronoi_circle_polygon(gp_vec2 c, double r, double tol, gp_vec2 **out, size_t *n,
                                    gp_error *err);

size_t gp_voronoi_count(const gp_voronoi *v);
double gp_voronoi_container_area(const gp_voronoi *v);
gp_vec2 gp_voronoi_seed(const gp_voronoi *v, size_t i);

/* Total area of cell i (all parts). */
double gp_voronoi_cell_area(const gp_voronoi *v, size_t i);
/* Orientation of cell i (of its seed's part), radians in (-pi/2, pi/2]. */
double gp_voronoi_cell_orientation(const gp_voronoi *v, size_t i);
/* Number of parts (1 except where a non-convex container splits the cell) and the seed's part. */
size_t gp_voronoi_cell_parts(const gp_voronoi *v, size_t i);
size_t gp_voronoi_cell_seed_part(const gp_voronoi *v, size_t i);
/* Writes part `part` of cell i counter-clockwise into out (at most cap points; out may be NULL
 * with cap 0) and returns its vertex count (0 for a bad index). */
size_t gp_voronoi_cell_polygon(const gp_voronoi *v, size_t i, size_t part, gp_vec2 *out,
                               size_t cap);
/* Writes the neighbours of cell i (ascending, no repeats) into out (at most cap) and returns
 * their count. */
size_t gp_voronoi_neighbours(const gp_voronoi *v, size_t i, size_t *out, size_t cap);

/* Moves seed i to p and updates the cells it affects. On error nothing has changed
 * (GP_ERR_INVALID: p outside the container, a duplicate, a bad index, or a move pending). */
gp_status gp_voronoi_move(gp_voronoi *v, size_t i, gp_vec2 p, gp_error *err);

/* The same move as a transaction: after GP_OK the new cells are visible, and the caller must
 * end it with gp_voronoi_commit() or gp_voronoi_rollback() (which restores seed and cells bit
 * for bit) before any other move. gp_voronoi_changed() lists the cells the pending move
 * recomputed (the moved seed first); the pointer is valid until the transaction ends. */
gp_status gp_voronoi_try_move(gp_voronoi *v, size_t i, gp_vec2 p, gp_error *err);
void gp_voronoi_commit(gp_voronoi *v);
void gp_voronoi_rollback(gp_voronoi *v);
size_t gp_voronoi_changed(const gp_voronoi *v, const uint32_t **cells);

/* Replicas (gp_imc.c evaluates moves in parallel, one replica per thread). dst must hold the
 * tessellation src held before its pending move (built from the same container and seeds, and
 * given the same moves since); dst then takes src's pending move as it stands -- the moved
 * seed and a copy of every changed cell, bit for bit, without recomputing anything -- and src
 * may then commit. dst may hold a pending move of its own that changes none of src's changed
 * cells: src's move then goes in underneath it, and dst's commit or rollback still works.
 * GP_ERR_INVALID without a pending move in src, or with a pending move in dst that changes one
 * of the same cells; GP_ERR_NOMEM leaves dst unusable (destroy it). dst and src are both
 * touched (src only read): neither may be used by another thread meanwhile. */
gp_status gp_voronoi_apply(gp_voronoi *dst, const gp_voronoi *src, gp_error *err);

/* The footprint of the pending move: its changed cells and their neighbours before and after
 * it, written into out (at most cap; repeats possible); returns the count (0 with no move
 * pending). A move B evaluated beside a move A on the same tessellation is the move B would
 * be after A (the same changed cells, bit for bit) when A's changed cells are outside B's
 * footprint: every cell B recomputes is bounded by seeds of its footprint both before and
 * after B, and the region B takes or frees goes to its neighbours' cells, none of which A
 * touched; the seed A moves is a changed cell of A, so it is neither a neighbour of B's cells
 * at its old place nor at its new one. (Disjoint changed cells alone may well be enough --
 * test_voronoi's side-by-side moves pass with that too -- but that is not argued here.) */
size_t gp_voronoi_footprint(const gp_voronoi *v, uint32_t *out, size_t cap);

/* Asks the memory for what moves of seeds to the k points q[] (container coordinates; k <=
 * GP_VORONOI_WARM_MAX) would read there: the cell of a seed near each point and its
 * neighbours (their records, vertices, neighbour lists, seeds). Reads only, and only what a
 * prefetch needs: nothing changes, so a caller that knows where its next moves go can ask
 * ahead and find those cells in the caches when it moves (a move far away in a large
 * tessellation otherwise waits on the memory for every cell it touches). Writes the cells
 * warmed into ids (at most cap) for the caller's own per-cell data and returns their count.
 * Not during a pending move's commit or rollback by another thread. */
#define GP_VORONOI_WARM_MAX 16
size_t gp_voronoi_warm(const gp_voronoi *v, const gp_vec2 *q, size_t k, uint32_t *ids, size_t cap);

/* A point uniformly distributed in cell i (all parts), drawn with u01() (uniform in [0, 1),
 * called a variable number of times). Returns 0 and the point in *p, or -1 if 1000 rejection
 * attempts in a very thin part all failed (then *p is the seed). */
int gp_voronoi_sample_cell(const gp_voronoi *v, size_t i, double (*u01)(void *), void *state,
                           gp_vec2 *p);

/* 1 if p lies in the closed container (boundary within 1e-12 of its size counts as inside). */
int gp_voronoi_contains(const gp_voronoi *v, gp_vec2 p);

#endif /* GP_VORONOI_H */
