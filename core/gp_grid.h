/* gp_grid.h -- the uniform cell grid (cell list) of a neighbour search: how many cells along
 * each axis, and which cell a coordinate falls in.
 *
 * A search for the pairs of spheres closer than some distance bins the centres into a uniform
 * grid over their box and compares a sphere only with those of the 3 x 3 x 3 cells around its
 * own. That is exact when no cell is narrower than the largest centre distance of a pair, and
 * fast when the grid has about as many cells as spheres: many more cells only cost memory and
 * the time to clear and sum them on every build.
 *
 * gp_grid_size: along axis a, floor((hi[a] - lo[a]) / cell) cells, at least 1 and at most cap
 * (cell <= 0: 1), so every cell is at least `cell` wide; then, while the grid has more than
 * budget cells, the axis with the most cells (the first of equals) is halved, rounding up
 * (wider cells keep the search exact). inv[a] = n[a] / (hi[a] - lo[a]) scales a coordinate
 * to cell units (0 on a flat axis). Returns n[0] n[1] n[2].
 * gp_grid_cell: the cell of a coordinate in cell units f = (x - lo) inv, clamped to
 * [0, n - 1], so that a point on or beyond the box's far side (or rounded below its near
 * side) lands in the last (first) cell.
 *
 * Users: gp_dem3d.c (the DEM's per-size-level grids: cap 2048), gp_dem3d_measure.c
 * (find_pairs on a static packing: cap 4096), both with a budget of 2N + 64 cells; and
 * gp_voronoi.c's bins, gp_grid_cell only (the bins are sized by seeds per bin, not by a
 * reach: gp_voronoi.c build_grid).
 *
 * Header-only (static inline), so that any core module may use it without a link dependency.
 * No state; thread-safe.
 */
#ifndef GP_GRID_H
#define GP_GRID_H

#include <math.h>
#include <stddef.h>

static inline size_t gp_grid_size(const double lo[3], const double hi[3], double cell, size_t cap,
                                  size_t budget, size_t n[3], double inv[3])
{
    for (int a = 0; a < 3; a++) {
        double k = cell > 0 ? floor((hi[a] - lo[a]) / cell) : 1;
        if (k < 1) k = 1;
        if (k > (double)cap) k = (double)cap;
        n[a] = (size_t)k;
    }
    while (n[0] * n[1] * n[2] > budget) {
        int a = n[0] >= n[1] && n[0] >= n[2] ? 0 : (n[1] >= n[2] ? 1 : 2);
        n[a] = (n[a] + 1) / 2;
    }
    for (int a = 0; a < 3; a++) {
        double e = hi[a] - lo[a];
        inv[a] = e > 0 ? (double)n[a] / e : 0;
    }
    return n[0] * n[1] * n[2];
}

static inline size_t gp_grid_cell(double f, size_t n)
{
    return f < 0 ? 0 : (f >= (double)n ? n - 1 : (size_t)f);
}

#endif /* GP_GRID_H */
