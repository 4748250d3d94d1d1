/* svg.h -- SVG pictures of a finished job's result (GET /v1/jobs/{id}/svg?view=V).
 *
 * Views: each kind lists its own (kind.h: gpd_kind.views): the 2D kind packing, cells, size,
 * orientation, descriptors (svg_views2d.c); the 3D kind section, psd (svg_views3d.c). The plot
 * kit they draw with is svg_plot.h.
 * The renderer reads the result JSON exactly as served by GET /v1/jobs/{id}/result. The fields
 * it reads (as the kinds write them: kind_fv2d.c, kind_spheres3d.c; everything optional unless
 * the view needs it):
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
 *             "grain_area": the same (optional)}   (kind_fv2d.c)
 *   }
 *   "warnings": ["one line", ...]    (optional; drawn under the size view)
 *   (The histograms mirror gp_hist in core/2d/gp_specimen2d.h: "target" may be absent or null
 *   where there is no target; "counts" is accepted in place of "achieved".)
 *   Missing (absent or null) stats histograms are recomputed from grains[] / cells[] where
 *   possible (descriptors from grains[].descriptors).
 *   What each view draws (svg_stats2d.c, svg_views2d.c):
 *   - size: the CDFs of stats.fit (target law dashed, achieved solid, cells and grains) on a
 *     log-area axis in a unit whose labels read as whole numbers (mm² for most packings), KS
 *     and its 5 % critical value in the legend, N, W1 and COV in a line under it, then the
 *     warnings; for a sieve law also the grains' percent passing by mass (stats.fit.passing).
 *     A result without stats.fit (stored before it) gets the histograms.
 *   - orientation: a rose of the grains' directions (else the cells'), read from the items: as
 *     many classes as N supports (36 of 5 degrees from N = 900, 18 of 10 from 450, ... 6 of
 *     30: 25 directions a class), the target cosine law of stats.fit.<grain|cell>_orientation
 *     and the achieved both as closed step outlines, in % per degree on labelled rings, KS in
 *     the legend; without items, stats.orientation_histogram.
 *   - descriptors: one histogram per descriptor from the grains, zoomed to the data, round
 *     Freedman-Diaconis bins (8 to 40), the mean (dashed) and stats.descriptors.<name>.target
 *     (red, when a number) marked, mean and sd in the panel's title.
 *   - packing, cells: maps coloured by area (or orientation); more than 2,000 items add a
 *     detail inset (default width then 1200 px): a square window of about 150 items where the
 *     packing is full, drawn enlarged beside the map, its frame on the map.
 *   Colour bars and axes have round ticks (1-2-5 x 10^k steps; 1, 2, 3, 5 x 10^k on a log
 *   axis) whose labels keep apart; no two texts of a picture overlap.
 *
 * 3D result
 *   "spheres": [[x,y,z,r],...] (m)                                        (api.md)
 *   "box": [bx,by,bz] (m, the box of the (tiled) packing; optional: else the spheres' bounds)
 *   "tiling": [nx,ny,nz] (optional; the mirror planes of the flip are every bz / nz)
 *   The section cuts at ?z= (a 400 naming the valid range when outside the packing), by
 *   default at mid-height of the middle base cell, the farthest a cut can be from the mirror
 *   planes (svg_views3d.c: default_z); its title has z and the spheres cut, a subtitle the
 *   porosity (stats and of the cut itself), D50, Cu and the PSD's largest error.
 *   "stats": {"porosity", "coordination_number", "fabric", "particles",   (api.md)
 *     "psd": {"diameters": [n] (m, the sieve diameters),
 *             "target_weight": [n], "achieved_weight": [n],
 *             "target_number": [n], "achieved_number": [n]}  (percent passing, 0..100)}
 *
 * Output: a standalone SVG 1.1 document with width, height and viewBox; coordinates printed
 * with at most 6 significant digits.
 *
 * Compact reading (what grainpackd does): a view reads the result's small members -- the
 * "summary": stats, warnings, container, box, kind (the result without grains, cells, spheres
 * and contacts, see store_get_summary) -- and its geometry one item at a time from an item
 * source: the export pack (gp_svg_items_pack: 2D grains, 3D spheres, fv3d grains), or an
 * array of the result text walked element by element (gp_svg_items_scan,
 * server/util/json_scan.h), or an array in memory (gp_svg_items_json). The size and psd views need only the summary; orientation and
 * descriptors read the grains' numbers in one and three light passes (no contours: O(1)
 * memory); the geometry views (packing, cells, section) read their items in two to four
 * passes (bounds and colour range, then drawing, the cells' seeds, the inset). The SVG is handed out as a pull stream (gp_svg_open /
 * gp_svg_read), one item at a time, so memory is O(1) in the number of items: the summary, one
 * item, the sources' caches and a staging buffer of about 16 KiB.
 */
#ifndef GP_SVG_H
#define GP_SVG_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "gp_export.h"
#include "svg/svg_view.h"
#include "util/json_scan.h"
#include "util/util.h"

/* Renders view of a result of the given kind (a name of kind.h's table; NULL or "" = the
 * result's "kind", else guessed from its members: gpd_kind_guess). opt may be NULL (defaults).
 * Returns a malloc'ed NUL-terminated SVG document (length in *len when len is not NULL), or
 * NULL with err (may be NULL):
 *   400 -- unknown kind, unknown view (the message lists the valid views of the kind) or a
 *          bad option;
 *   409 -- the view needs a part of the result that was not asked for (e.g. "cells" without
 *          output "cells", "packing" without "grains");
 *   500 -- out of memory or a result that is not an object.
 * The caller free()s the returned string. Thread-safe (no global state).
 * (gp_svg_open over the result in memory, read to the end.) */
char *gp_svg_render(const json_t *result, const char *kind, const char *view,
                    const gp_svg_options *opt, size_t *len, gpd_err *err);

/* ---- item sources: a result's geometry, one item at a time ---- */

/* The elements of array (a result's "grains", "cells" or "spheres"), which must outlive the
 * source; NULL when array is not an array. */
gp_svg_items *gp_svg_items_json(const json_t *array, gp_svg_part part);

/* The elements of the JSON array whose text starts at offset off of text (e.g. the stored
 * result, read as an SQLite blob), each parsed on its own when it is read; text's reader must
 * stay valid until the source is closed. NULL on out of memory. */
gp_svg_items *gp_svg_items_scan(const js_source *text, uint64_t off, gp_svg_part part);

/* The grains (2D, fv3d) or spheres (3D) of an export pack (core/export/gp_export.h), which must
 * stay readable until the source is closed. NULL when pack is not a pack, or not of that part
 * (cells are not in packs). A fv3d pack's grains come with their 2D numbers NaN: their views
 * read the records (pose, volume, radii) through the source's reader. */
gp_svg_items *gp_svg_items_pack(const gp_export_source *pack, gp_svg_part part);

void gp_svg_items_close(gp_svg_items *it);

/* ---- rendering as a pull stream ---- */

/* Prepares view and returns a stream of the SVG document; NULL with err as gp_svg_render. */
gp_svg *gp_svg_open(const gp_svg_input *in, const char *view, const gp_svg_options *opt,
                    gpd_err *err);

/* Copies up to cap (> 0) bytes of the document into buf; *n = 0 at the end. -1 when an item
 * source failed mid-way or memory ran out (the document is then incomplete: drop it; the
 * reason is gp_svg_error()). */
int gp_svg_read(gp_svg *g, char *buf, size_t cap, size_t *n);
const char *gp_svg_error(const gp_svg *g);

/* Closes the stream and the item sources it opened. */
void gp_svg_close(gp_svg *g);

#endif /* GP_SVG_H */
