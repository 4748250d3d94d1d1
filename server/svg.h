/* svg.h -- SVG pictures of a finished job's result (GET /v1/jobs/{id}/svg?view=V).
 *
 * Views: for "fourier-voronoi-2d": packing, cells, size, orientation, descriptors;
 *        for "spheres-3d": section, psd.
 * The renderer reads the result JSON exactly as served by GET /v1/jobs/{id}/result. The fields
 * it reads (proposal for server/result_json.c; everything optional unless the view needs it):
 *
 * 2D result
 *   "grains": [{"id", "cell", "contour": [[x,y],...], "area", "orientation_deg",
 *               "descriptors": {...}, "discs": [[x,y,r],...]}]          (api.md)
 *   "cells":  [{"id", "seed": [x,y], "polygons": [[[x,y],...],...], "area",
 *               "orientation_deg"}]                                       (api.md)
 *   "container": {"polygon": [[x,y],...], "holes": [...]} | {"circle": {"center", "radius"}}
 *               (optional echo of the spec's container; drawn as the outline when present)
 *   "stats": {
 *     "imc_error", "imc_steps", "solid_fraction" (a number or {"target", "achieved"}),
 *     "size_histogram":        {"edges": [k+1], "target": [k], "achieved": [k]},
 *                              cell areas (m^2), fractions of the number of cells (sum ~1)
 *     "grain_size_histogram":  same shape, grain areas (optional; drawn as a 2nd series)
 *     "orientation_histogram": {"edges": [k+1] degrees in [-90, 90], "target": [k],
 *                               "achieved": [k]}
 *     "descriptors": {"elongation":  {"mean": m, "edges": [k+1], "achieved": [k]},
 *                     "roundness":   {...}, "circularity": {...}, "regularity": {...}}
 *     "fit": {"cell_area":  {"law", "ks", "ks_critical", "w1", "target": {"cov"},
 *                            "achieved": {"cov"}, "cdf": {"x": [k], "target": [k],
 *                            "achieved": [k]}},
 *             "grain_area": the same (optional)}   (server/result_json.h)
 *   }
 *   "warnings": ["one line", ...]    (optional; drawn under the size view)
 *   (The histograms mirror gp_hist in core/gp_specimen2d.h: "target" may be absent or null
 *   where there is no target; "counts" is accepted in place of "achieved".)
 *   Missing (absent or null) stats histograms are recomputed from grains[] / cells[] where
 *   possible (descriptors from grains[].descriptors).
 *   The size view draws the CDFs of stats.fit (target law dashed, achieved solid, x in log
 *   scale when it spans more than a decade, one KS line per series, then the warnings); a
 *   result without them (stored before stats.fit) gets the histograms.
 *
 * 3D result
 *   "spheres": [[x,y,z,r],...] (m)                                        (api.md)
 *   "box": [bx,by,bz] (m, the box of the (tiled) packing; optional: else the spheres' bounds)
 *   "stats": {"porosity", "coordination_number", "fabric", "particles",   (api.md)
 *     "psd": {"diameters": [n] (m, the sieve diameters),
 *             "target_weight": [n], "achieved_weight": [n],
 *             "target_number": [n], "achieved_number": [n]}  (percent passing, 0..100)}
 *
 * Output: a standalone SVG 1.1 document with width, height and viewBox; coordinates printed
 * with at most 6 significant digits. Rendering is O(size of the result).
 */
#ifndef GP_SVG_H
#define GP_SVG_H

#include <stddef.h>

#include <jansson.h>

typedef struct gp_svg_options {
    const char *color;  /* packing: "size" (default) or "orientation"; NULL = default */
    int has_z;          /* section: cut at z (m) instead of the middle of the box */
    double z;
    int width;          /* picture width in px; 0 = default (800) */
} gp_svg_options;

/* Renders view of a result of the given kind ("fourier-voronoi-2d" or "spheres-3d"; NULL or
 * "" = guess from the result). opt may be NULL (defaults).
 * Returns a malloc'ed NUL-terminated SVG document (length in *len when len is not NULL), or
 * NULL with a one-line message in errbuf and an HTTP status in *status (status may be NULL):
 *   400 -- unknown view (the message lists the valid views of the kind) or a bad option;
 *   409 -- the view needs a part of the result that was not asked for (e.g. "cells" without
 *          output "cells", "packing" without "grains");
 *   500 -- out of memory or a result that is not an object.
 * The caller free()s the returned string. Thread-safe (no global state). */
char *gp_svg_render(const json_t *result, const char *kind, const char *view,
                    const gp_svg_options *opt, size_t *len, int *status, char *errbuf,
                    size_t errlen);

/* The views of a kind as a comma-separated list ("packing, cells, size, orientation,
 * descriptors"), or NULL for an unknown kind. */
const char *gp_svg_views(const char *kind);

#endif /* GP_SVG_H */
