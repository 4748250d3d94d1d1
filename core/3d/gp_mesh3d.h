/* gp_mesh3d.h -- closed triangle meshes: the geodesic icosphere, exact mass properties, the
 * convex hull, principal axes and extents.
 *
 * Meshes. A mesh is nv vertices (3 doubles each, x y z) and nt triangles (3 uint32 vertex
 * indices each), counter-clockwise seen from outside, i.e. (b - a) x (c - a) points out. A
 * closed mesh uses every directed edge (i, j) once and its reverse (j, i) once: that is what
 * gp_mesh3d_check() and gp_mesh3d_create() verify (a closed, consistently oriented 2-manifold
 * surface). The functions that take raw arrays (mass properties, principal axes) trust the
 * caller on that; on an open or inconsistently oriented mesh their numbers mean nothing.
 *
 * Icosphere. gp_mesh3d_icosphere(level) is the regular icosahedron (12 vertices
 * (0, +-1, +-phi) and their cyclic permutations, normalised; 20 triangles) subdivided level
 * times: each triangle (a, b, c) becomes (a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca),
 * the edge midpoints normalised to the unit sphere. Vertices keep their numbers from one level
 * to the next (level l's vertices are the first 10 4^l + 2 of level l + 1's), the new ones
 * numbered in order of first appearance over the triangles; so the order is fixed:
 * 10 4^l + 2 vertices, 20 4^l triangles (level 4: 2,562 and 5,120). The coordinate axes are
 * among the vertices from level 1 on (the icosahedron's 2-fold axes are x, y, z). Levels
 * 0 .. GP_MESH3D_ICOSPHERE_LEVEL_MAX.
 *
 * Mass properties (unit density), by the divergence theorem: the polyhedron is the signed sum
 * of the tetrahedra (ref, a, b, c) over its triangles, ref the mean of its vertices (a point
 * near the mesh, so that a mesh far from the origin loses nothing to cancellation: moved by
 * 1e6 its volume and inertia change by ~1e-10 relative). Per tetrahedron with edges
 * a, b, c from ref and d = a . (b x c): volume d / 6, first moment (d / 24)(a + b + c), second
 * moment (d / 120)(a a^T + b b^T + c c^T + s s^T), s = a + b + c. The inertia tensor about the
 * centroid g is I = tr(M) Id - M with M = M_ref - V (g - ref)(g - ref)^T: exact for the
 * polyhedron (rounding aside; a cube's is right to 1e-15). Surface area: sum of the
 * triangles' areas. A mesh whose volume is not positive (inside out, flat) is refused
 * (GP_ERR_DEGENERATE).
 *
 * Convex hull (gp_mesh3d_hull, gp_mesh3d_hull_volume): incremental (Quickhull's order: each
 * face keeps the points above it, the farthest one is added next; the faces it sees go, a
 * fan from it to their horizon comes in, their points go to the new faces or are dropped as
 * inside). Robustness comes from exact predicates rather than tolerances: the points are
 * snapped to an integer grid, (x - lo) 2^k rounded with 2^k the largest power of two that
 * keeps the bounding box's largest side below 2^40 steps (moving a point by at most 2^-40 of
 * that side, ~1e-12; coordinates on a binary grid, such as small integers or a cube's, are not
 * moved at all), and every orientation test is exact: a floating-point value when its error
 * bound proves the sign (nearly always), else 128-bit integers. So coplanar, collinear and
 * duplicate points (a cube's face points, lattices) cannot make the hull inconsistent: a
 * point exactly on a face is inside. The hull's triangles (the grid's topology) are measured
 * with the original coordinates, so a cube's corners give its volume to rounding. Points
 * whose hull is flat or empty (fewer than four points not coplanar on the grid) have hull
 * volume 0; gp_mesh3d_hull() then fails with GP_ERR_DEGENERATE. Coplanar hull triangles are
 * not merged: a face of the hull may be triangulated through points on it that were hull
 * vertices before the points that enclose them came (a cube's corners, face and interior
 * points: 18 vertices, 32 triangles); points that snapping moved off a common plane or line
 * may leave slivers of nearly zero area. Cost on one core: 2,562 points on a sphere in about
 * 1.2 ms, the 2,562 vertices of a rough grain in about 0.85 ms (docs/design/grain3d.md).
 *
 * Principal axes (gp_mesh3d_principal_axes): the eigenvectors of the inertia tensor about the
 * centroid (cyclic Jacobi rotations on the 3 x 3 matrix, converged to rounding). The extents
 * are the lengths of the vertices' projections on each axis (max - min), and the three axes
 * are ordered by extent, longest first: L >= I >= S (the long axis is the one the body is
 * longest along, which for an ellipsoid is its axis of least inertia; ordering by extent
 * rather than by moment guarantees L >= I >= S whatever the shape). Axes are unit vectors,
 * the first two with their largest component positive, the third their cross product (a
 * right-handed frame). Where two moments are equal (a sphere, a body of revolution) the axes
 * in that plane are any orthonormal pair.
 *
 * Ownership: gp_mesh3d_create() copies its arrays; a gp_mesh3d owns its arrays, freed by
 * gp_mesh3d_destroy(); the getters return pointers into it, valid while it lives. Thread
 * safety: no global state; a mesh is immutable after creation, so any number of threads may
 * read one; the raw-array functions are pure (they allocate their own scratch).
 */
#ifndef GP_MESH3D_H
#define GP_MESH3D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"

#define GP_MESH3D_ICOSPHERE_LEVEL_MAX 8

typedef struct gp_mesh3d gp_mesh3d;

/* Mass properties for unit density. */
typedef struct gp_mesh3d_mass {
    double volume;
    double centroid[3];
    double inertia[9]; /* about the centroid, row-major, symmetric: integral (|r|^2 Id - r r^T) dV */
    double area;
} gp_mesh3d_mass;

/* Principal axes and extents. */
typedef struct gp_mesh3d_axes {
    double axis[3][3];  /* axis[0] long, axis[1] intermediate, axis[2] short: unit, right-handed */
    double moment[3];   /* the principal moments of inertia about those axes */
    double extent[3];   /* L, I, S: max - min of the vertices' projections on each axis */
} gp_mesh3d_axes;

/* The icosphere of the given level (<= GP_MESH3D_ICOSPHERE_LEVEL_MAX): unit directions and
 * triangles, as above. NULL on error (GP_ERR_INVALID, GP_ERR_NOMEM). */
gp_mesh3d *gp_mesh3d_icosphere(unsigned level, gp_error *err);

/* A copy of the caller's mesh, checked: coordinates finite, indices < nv, no triangle with a
 * repeated index, closed and consistently oriented (gp_mesh3d_check). NULL on error. */
gp_mesh3d *gp_mesh3d_create(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                            gp_error *err);
void gp_mesh3d_destroy(gp_mesh3d *m); /* NULL is fine */

size_t gp_mesh3d_vertex_count(const gp_mesh3d *m);
size_t gp_mesh3d_triangle_count(const gp_mesh3d *m);
const double *gp_mesh3d_vertices(const gp_mesh3d *m);    /* 3 per vertex */
const uint32_t *gp_mesh3d_triangles(const gp_mesh3d *m); /* 3 per triangle */

/* GP_OK if every index is < nv, no triangle repeats an index, and every directed edge appears
 * exactly once with its reverse exactly once (closed, consistently oriented); else
 * GP_ERR_INVALID naming the first offending triangle or edge. nt >= 4. O(nt log nt). */
gp_status gp_mesh3d_check(size_t nv, const uint32_t *tri, size_t nt, gp_error *err);

/* Volume, centroid, inertia about the centroid and area of the closed mesh (see above).
 * GP_ERR_INVALID for nv < 4, nt < 4, an index >= nv or a non-finite coordinate;
 * GP_ERR_DEGENERATE if the volume is not positive. */
gp_status gp_mesh3d_mass_properties(const double *xyz, size_t nv, const uint32_t *tri,
                                    size_t nt, gp_mesh3d_mass *out, gp_error *err);

/* Principal axes of mass->inertia and the extents of the nv points xyz (relative to
 * mass->centroid) along them, ordered L >= I >= S (see above). GP_ERR_INVALID for nv == 0 or
 * non-finite input. */
gp_status gp_mesh3d_principal_axes(const double *xyz, size_t nv, const gp_mesh3d_mass *mass,
                                   gp_mesh3d_axes *out, gp_error *err);

/* Eigen-decomposition of a symmetric 3 x 3 matrix a (row-major; only its upper triangle is
 * read): values[k] with unit vectors[k] (a vectors[k] = values[k] vectors[k]), values in
 * increasing order. Cyclic Jacobi; pure. */
void gp_mesh3d_eigen_sym3(const double a[9], double values[3], double vectors[3][3]);

/* Volume of the convex hull of n points (3 doubles each): 0 when their hull is flat or empty
 * (n < 4 included). GP_ERR_INVALID for a non-finite coordinate; GP_ERR_NOMEM. */
gp_status gp_mesh3d_hull_volume(const double *pts, size_t n, double *volume, gp_error *err);

/* The convex hull as a mesh: its vertices (a subset of the points, numbered in order of first
 * appearance over its triangles) and triangles, counter-clockwise seen from outside. NULL on
 * error: GP_ERR_DEGENERATE for a flat or empty hull, GP_ERR_INVALID, GP_ERR_NOMEM,
 * GP_ERR_INTERNAL (a broken invariant; not met in the tests). */
gp_mesh3d *gp_mesh3d_hull(const double *pts, size_t n, gp_error *err);

#endif /* GP_MESH3D_H */
