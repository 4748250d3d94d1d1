/* gp_geom.h -- planar polygon geometry on double coordinates: the one point-in-polygon test,
 * bounding box and minimum caliper (Mollon & Zhao 2012 Fig. 1a) that the rest of core/2d uses.
 *
 * Polygons are arrays of vertices, implicitly closed (the last vertex joins the first), in
 * either orientation unless a function says otherwise. Functions tolerate duplicate
 * consecutive vertices and collinear runs. Nothing here allocates except where stated, and
 * nothing keeps state: every function is safe to call from several threads.
 */
#ifndef GP_GEOM_H
#define GP_GEOM_H

#include <stddef.h>

#include "gp_error.h"

typedef struct gp_vec2 {
    double x, y;
} gp_vec2;

/* Signed area (positive for counter-clockwise), by the shoelace formula evaluated about the
 * first vertex so that huge coordinates with a small polygon keep their precision. */
double gp_poly_signed_area(const gp_vec2 *p, size_t n);
double gp_poly_area(const gp_vec2 *p, size_t n);
double gp_poly_perimeter(const gp_vec2 *p, size_t n);

/* Area centroid. GP_ERR_DEGENERATE when the area is zero (then *c is the vertex mean). */
gp_status gp_poly_centroid(const gp_vec2 *p, size_t n, gp_vec2 *c, gp_error *err);

/* Point in polygon (even-odd rule): 1 strictly inside, 0 outside; a point on an edge (within
 * a relative tolerance of ~1e-12 of the polygon's size) counts as inside (returns 1). The one
 * point-in-polygon test of core/2d (gp_voronoi's cell parts and holes use it too). */
int gp_poly_contains(const gp_vec2 *p, size_t n, gp_vec2 q);

/* Convex hull by Andrew's monotone chain: writes h (capacity >= n) counter-clockwise, starting
 * from the lowest-then-leftmost point, without collinear or duplicate points; returns its vertex
 * count (0 for n == 0, 1 or 2 for degenerate input). */
size_t gp_convex_hull(const gp_vec2 *p, size_t n, gp_vec2 *h);

/* Smallest circle enclosing all points (Welzl, deterministic move-to-front, expected O(n)). */
gp_status gp_min_enclosing_circle(const gp_vec2 *p, size_t n, gp_vec2 *center, double *radius,
                                  gp_error *err);

/* Largest circle inside a simple polygon: centre and radius with |r - r_true| <= tol
 * (grid refinement with a distance bound, "pole of inaccessibility"). tol <= 0 picks
 * 1e-6 of the polygon's bounding-box size. */
gp_status gp_max_inscribed_circle(const gp_vec2 *p, size_t n, double tol, gp_vec2 *center,
                                  double *radius, gp_error *err);

/* Minimum caliper (Feret) width by rotating calipers on the hull. The minimum width S is
 * measured across direction angle_rad + pi/2; angle_rad (in (-pi/2, pi/2]) is the direction of
 * the grain's long axis (Mollon & Zhao Fig. 1a: theta), and length is the extent L of the
 * polygon along that direction. So elongation = width / length. */
gp_status gp_min_caliper(const gp_vec2 *p, size_t n, double *width, double *angle_rad,
                         double *length, gp_error *err);

/* Distance from q to the segment [a, b]. */
double gp_segment_distance(gp_vec2 q, gp_vec2 a, gp_vec2 b);

/* Distance from q to the polygon boundary (unsigned). */
double gp_poly_boundary_distance(const gp_vec2 *p, size_t n, gp_vec2 q);

/* 1 if the polygon is simple (no two non-adjacent edges intersect), else 0. O(n^2): meant for
 * checks and tests, not hot loops. */
int gp_poly_is_simple(const gp_vec2 *p, size_t n);

/* 1 if polygon a lies inside polygon b (every vertex of a inside b and no edges crossing). */
int gp_poly_inside_poly(const gp_vec2 *a, size_t na, const gp_vec2 *b, size_t nb);

/* 1 if the interiors of two simple polygons overlap (edge crossing or one inside the other). */
int gp_poly_overlap(const gp_vec2 *a, size_t na, const gp_vec2 *b, size_t nb);

/* --- additions (appended; the declarations above are pinned) --- */

/* Notes on the functions above, as implemented:
 * - gp_max_inscribed_circle and gp_min_caliper allocate a temporary buffer, freed before they
 *   return (GP_ERR_NOMEM if unavailable); nothing else allocates.
 * - gp_convex_hull skips non-finite points. The fallible functions return GP_ERR_INVALID on
 *   non-finite input; gp_poly_is_simple / _inside_poly / _overlap return 0 for it.
 * - gp_poly_is_simple, gp_poly_inside_poly, gp_poly_overlap and gp_convex_hull decide with an
 *   exact orientation predicate (gp_orient2d), so touching and crossing are told apart exactly
 *   on the given doubles. gp_poly_contains adds a boundary tolerance of 1e-12 of the size.
 * - gp_max_inscribed_circle: r <= r_true <= r + tol (up to ~1e-15 of the size in rounding);
 *   the centre is strictly inside. */

/* gp_max_inscribed_circle with one more first guess of the centre (NULL: none), such as the
 * centre of a disc known to be inside: the same guarantee whatever the guess (it is only
 * evaluated), but a guess near the pole lets the search discard most cells at once. */
gp_status gp_max_inscribed_circle_from(const gp_vec2 *p, size_t n, double tol,
                                       const gp_vec2 *guess, gp_vec2 *center, double *radius,
                                       gp_error *err);

/* Axis-aligned bounding box of n >= 1 points. GP_ERR_INVALID for n == 0 or non-finite input. */
gp_status gp_poly_bbox(const gp_vec2 *p, size_t n, gp_vec2 *lo, gp_vec2 *hi, gp_error *err);

/* Exact orientation of (a, b, c): +1 counter-clockwise (c left of a->b), -1 clockwise, 0
 * collinear. Adaptive: a floating-point filter, then exact expansion arithmetic, so the sign is
 * exact for all finite input (|coordinates| below ~1e150). */
int gp_orient2d(gp_vec2 a, gp_vec2 b, gp_vec2 c);

/* 1 if the closed segments [a, b] and [c, d] share at least one point (exact); 0 otherwise or
 * for non-finite input. */
int gp_segments_intersect(gp_vec2 a, gp_vec2 b, gp_vec2 c, gp_vec2 d);

/* The rotating-calipers pass of gp_min_caliper, for a polygon that is already convex and
 * counter-clockwise (a hull; the convex Voronoi cells): the index k of the edge h[k] -> h[k+1]
 * across which the polygon is thinnest, the edges visited from the lowest-then-leftmost vertex
 * on, the first thinnest winning; edges with squared length <= eps2 are skipped (the collinear
 * runs of a polygon clipped in floating point; eps2 < 0 skips none). m when every edge was
 * skipped (or m < 2). The width across edge k is h_k / |e_k| (squared = 0, gp_min_caliper) or
 * compared as h_k^2 / |e_k|^2 (squared = 1, gp_voronoi's cell orientation): the two rank edges
 * alike up to rounding, and each caller's results are pinned to its own. O(m), no allocation. */
size_t gp_min_caliper_edge(const gp_vec2 *h, size_t m, double eps2, int squared);

/* The axis angle of the direction (ex, ey): atan2 folded into (-pi/2, pi/2] (Fig. 1a's theta;
 * the angle_rad of gp_min_caliper). */
double gp_axis_angle(double ex, double ey);

/* gp_convex_hull's hull (the same vertices, order and start) of a polygon star-shaped about an
 * interior point (every ray from it meets the
 * boundary once: a Fourier grain's points about its centre), either orientation, in O(n)
 * with one stack pass and no sort; h needs capacity n. For other polygons the result is
 * undefined (a polygon, but maybe not the hull); non-finite input falls back to
 * gp_convex_hull. */
size_t gp_convex_hull_star(const gp_vec2 *p, size_t n, gp_vec2 *h);

/* gp_min_caliper of a polygon star-shaped about an interior point (gp_convex_hull_star's
 * condition: a Fourier grain's contour): the same result from the O(n) hull, several times
 * cheaper than the sorting hull (docs/design/geometry.md). Undefined for other polygons. */
gp_status gp_min_caliper_star(const gp_vec2 *p, size_t n, double *width, double *angle_rad,
                              double *length, gp_error *err);

#endif /* GP_GEOM_H */
