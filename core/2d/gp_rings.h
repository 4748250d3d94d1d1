/* gp_rings.h -- the checks that make a polygon with holes a valid container: every ring has
 * an area, every ring is simple, no two rings meet, and every hole lies inside the outer ring
 * and outside every other hole.
 *
 * Algorithm. One plane sweep over the edges of all the rings together (Shamos & Hoey 1976):
 * the vertices in (x, y) order, the edges that cross the sweep line kept bottom to top in a
 * treap, and only neighbours on the sweep line tested for contact. O(E log E) for E edges
 * whatever the layout (a 1 MB request body holds about 100,000), O(E) memory. Every
 * combinatorial decision is exact (gp_orient2d, gp_segments_intersect of gp_geom.h), so
 * touching counts as crossing and nothing else does. The same sweep finds, at the leftmost
 * vertex of each ring, the edge right below it, which tells which ring (if any) contains that
 * ring; containment of a hole is then read off its chain of enclosing rings.
 *
 * Invariants checked, in this order (the first one broken is reported):
 *   1. each ring has at least 3 points, a non-zero extent, and its points do not all lie on
 *      one line (within 1e-12 of the squared distance to the point farthest from the first:
 *      GP_RINGS_DEGENERATE);
 *   2. no two edges share a point, except consecutive edges of one ring at their common
 *      vertex, and those do not fold back onto each other (GP_RINGS_FOLD, GP_RINGS_CROSS);
 *   3. each ring's |area| exceeds 1e-12 of the square of its extent about its first point
 *      (GP_RINGS_NO_AREA);
 *   4. each hole (rings 1 ..) lies inside ring 0 (GP_RINGS_HOLE_OUTSIDE) and inside no other
 *      hole (GP_RINGS_HOLE_IN_HOLE).
 * A ring is implicitly closed; the caller drops repeated consecutive points and a closing
 * point equal to the first one (a repeated point is a touch: GP_RINGS_CROSS). Either
 * orientation. Coordinates finite and below ~1e150 in magnitude (gp_orient2d's range).
 *
 * Ownership: the rings are the caller's and only read. Memory: O(E), allocated and freed within
 * the call (GP_ERR_NOMEM when it fails). Thread safety: no state; safe to call from several
 * threads at once (the treap's priorities come from a generator seeded per call, so that no
 * input can steer the tree's depth; the verdict and the fault reported do not depend on it).
 */
#ifndef GP_RINGS_H
#define GP_RINGS_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_geom.h"

/* A ring: n points, read only. */
typedef struct gp_ring_ref {
    const gp_vec2 *pts;
    size_t n;
} gp_ring_ref;

typedef enum gp_rings_fault_kind {
    GP_RINGS_OK = 0,
    GP_RINGS_DEGENERATE,        /* ring: < 3 points, no extent, or all points on one line */
    GP_RINGS_FOLD,              /* ring's edge and edge2 (which follows it) fold back onto each
                                 * other: collinear and overlapping */
    GP_RINGS_CROSS,             /* edge of ring crosses or touches edge2 of ring2; ring <= ring2,
                                 * and edge < edge2 when they are the same ring */
    GP_RINGS_NO_AREA,           /* ring: simple, but of no area next to its extent */
    GP_RINGS_HOLE_OUTSIDE,      /* hole ring is not inside ring 0 */
    GP_RINGS_HOLE_IN_HOLE       /* hole ring lies inside hole ring2 (the lowest-numbered hole
                                 * around it) */
} gp_rings_fault_kind;

/* What is at fault: the kind, and the rings and edges it names (edge i runs from point i to
 * point i + 1 of its ring; unused fields are 0). */
typedef struct gp_rings_fault {
    gp_rings_fault_kind kind;
    size_t ring, edge;
    size_t ring2, edge2;
} gp_rings_fault;

/* Checks rings[0] (the outer ring) and rings[1 .. nrings) (its holes) against the invariants
 * above. GP_OK with fault->kind GP_RINGS_OK; GP_ERR_INVALID with *fault set (and err's message
 * naming the rings and edges); GP_ERR_NOMEM. fault may be NULL. */
gp_status gp_rings_check(const gp_ring_ref *rings, size_t nrings, gp_rings_fault *fault,
                         gp_error *err);

#endif /* GP_RINGS_H */
