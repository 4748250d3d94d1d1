/* gp_odec.h -- Overlapping Discrete Element Cluster: a grain contour filled with overlapping
 * discs (Ferellec & McDowell 2008; Mollon & Zhao 2012 Sec. 4.2).
 *
 * Algorithm (deterministic). Lengths are relative to the polygon's equivalent radius
 * R_eq = sqrt(area / pi).
 *  1. Nodes: the polygon's vertices (consecutive duplicates dropped) plus points inserted on
 *     every edge longer than the node gap g = sqrt(2 spacing r_min) R_eq, evenly. The inward
 *     normal of a node is the edge normal, or at a vertex the bisector of its two edges' normals.
 *  2. Tangent disc of a node P with inward normal n: the largest disc tangent to the contour at P,
 *     i.e. centre P + r n with r = min over the other nodes Q with (Q - P).n > 0 of
 *     |Q - P|^2 / (2 (Q - P).n), so that no node lies inside it (the contour is treated as the
 *     smooth curve its nodes sample: a disc tangent at a vertex of a 128-gon inscribed in a
 *     circle is that circle).
 *  3. Nodes are visited by decreasing tangent radius (ties: lower node index first). A node not
 *     yet covered whose tangent radius is >= r_min R_eq gets its disc; then every node within
 *     spacing R_eq of the new disc (|Q - c| <= r + spacing R_eq) is marked covered.
 *  4. Nodes still uncovered (sharp corners, where no disc of radius r_min is tangent), by index:
 *     among the discs of radius exactly r_min R_eq tangent to the contour at points near the
 *     node (nodes and 7 points per node segment, within an arc length 2 (r_min + spacing) + g on
 *     either side) whose tangent radius is >= r_min R_eq, the one nearest to the node is added
 *     if it comes within spacing R_eq of it; otherwise the node stays uncovered (counted). At a
 *     90-degree corner this disc is ~0.414 r_min away, so the defaults cover square corners.
 *  Stops early, with capped = 1, after max_discs discs.
 *
 * Containment: no node lies strictly inside a disc; the contour between two nodes (at most g
 * apart) can cut into a disc of radius r >= r_min R_eq by at most r - sqrt(r^2 - g^2/4)
 * <= (r_min - sqrt(r_min^2 - spacing r_min / 2)) R_eq (0.0067 R_eq with the defaults).
 * gp_odec_measure() measures what is achieved.
 *
 * Cost: O(m^2) for m nodes (m ~ 1.1-2 n for a 128-point Fourier contour with default
 * parameters), but lazily: step 3 takes the nodes from a queue of cheap upper bounds of their
 * tangent radii (a subset of the nodes), and a node gets its exact radius only when it comes
 * first uncovered, which few do (docs/design/geometry.md); the discs are those of sorting
 * every exact radius.
 * Thread safe: no state besides the arguments.
 */
#ifndef GP_ODEC_H
#define GP_ODEC_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_geom.h"

typedef struct gp_odec_params {
    double r_min;     /* smallest disc radius / R_eq (default 0.05); > 0 */
    double spacing;   /* coverage distance tolerance / R_eq (default 0.025); > 0 */
    size_t max_discs; /* cap on the number of discs (default 1000); 0 = no cap */
} gp_odec_params;

/* The defaults above. */
void gp_odec_params_defaults(gp_odec_params *p);

typedef struct gp_odec_disc {
    double x, y, r;
} gp_odec_disc;

typedef struct gp_odec_result {
    gp_odec_disc *discs; /* ndiscs, malloc'ed; free with gp_odec_result_free() */
    size_t ndiscs;
    double r_eq;         /* sqrt(polygon area / pi) */
    size_t nnodes;       /* boundary nodes used (vertices + inserted) */
    size_t uncovered;    /* nodes left farther than spacing from every disc */
    int capped;          /* 1 if max_discs stopped the filling */
} gp_odec_result;

/* Fills a simple polygon (n >= 3 finite vertices, either orientation) with discs as above.
 * params may be NULL (defaults). On success *out owns the discs (ndiscs >= 1 unless the polygon
 * is too thin for one disc of radius r_min, then 0 discs and every node uncovered).
 * GP_ERR_INVALID: bad arguments; GP_ERR_DEGENERATE: zero area (after dropping duplicate
 * vertices); GP_ERR_NOMEM. On error *out is zeroed. */
gp_status gp_odec_build(const gp_vec2 *poly, size_t n, const gp_odec_params *params,
                        gp_odec_result *out, gp_error *err);

void gp_odec_result_free(gp_odec_result *r);

/* Quality of a disc cluster against its polygon, all relative to the polygon:
 *  area_ratio  |U intersect P| / |P|, U the union of the discs;
 *  area_excess |U \ P| / |P|;
 *  Both by scanlines: nlines = 512 horizontal lines through the bounding box at cell centres,
 *  on each the exact lengths of the union of disc chords and of the polygon's inside intervals
 *  (midpoint rule in y, exact in x): absolute error about 1e-4 for smooth grains (O(h^1.5) at
 *  the top and bottom of each disc, h = height / 512).
 *  hausdorff   max(h1, h2) / R_eq with h1 = max over contour points (the vertices and points
 *  at most 0.01 R_eq apart along the edges: sampling error <= 0.005) of the distance to U, and
 *  h2 = max over points of the boundary of U of the distance to the contour; the boundary of U
 *  is sampled at every pairwise circle intersection on it (the cusps, where its maxima
 *  usually are) and at most 0.02 R_eq apart on each circle: h1 and h2 are within 0.01 of the
 *  exact values (distances are 1-Lipschitz along the curves).
 *  max_protrusion  max over discs of (r - distance from centre to the contour) / R_eq, 0 if
 *  every disc lies inside (negative values clamp to 0); a disc whose centre is outside counts
 *  r + distance. */
typedef struct gp_odec_quality {
    double area_ratio;
    double area_excess;
    double hausdorff;
    double max_protrusion;
} gp_odec_quality;

gp_status gp_odec_measure(const gp_vec2 *poly, size_t n, const gp_odec_disc *discs,
                          size_t ndiscs, gp_odec_quality *q, gp_error *err);

#endif /* GP_ODEC_H */
