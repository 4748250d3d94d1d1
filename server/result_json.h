/* result_json.h -- a finished specimen as the JSON of GET /v1/jobs/{id}/result (api.md "Result").
 *
 * 2D ("fourier-voronoi-2d"):
 * {"kind": "fourier-voronoi-2d", "seed": 42, "outputs": [...],
 *  "container": <the spec's container, echoed>,
 *  "stats": {
 *    "particles":       {"target": N (`particles`, or the cell count a sieve law gives),
 *                        "achieved": number of grains},
 *    "imc_error":       {"target": the threshold used, "achieved": e,
 *                        "measure": "AD|E1|E2|E3", "floor": f,
 *                        "stop_reason": "threshold|max_steps|floor|..."},
 *    "imc_steps":       {"max": max_steps, "achieved": steps},
 *    "solid_fraction":  {"target": F_S, "achieved": grain area / container area},
 *    "container_area":  A,
 *    "cells_target_met": k,            cells whose grain reached F_S
 *    "mean_orientation_gap_deg": g,
 *    "size_histogram":        {"edges": [k+1], "target": [k], "achieved": [k]}  (cell areas)
 *    "grain_size_histogram":  {"edges", "target", "achieved"}                   (grain areas)
 *    "orientation_histogram": {"edges" (deg), "target", "achieved"}
 *    "descriptors": {"elongation": {"mean", "edges", "target", "achieved"}, "roundness": ...,
 *                    "circularity": ..., "regularity": ...}       (with output "descriptors")
 *    "fit": {                                           (api.md; a block only when measured)
 *      "cell_area": {"law": "lognormal|normal|uniform|sieve",
 *                    "target": {"mean", "cov"}, "achieved": {"mean", "cov"},
 *                    "ks", "ks_critical" (1.36 / sqrt(n)), "w1" (/ target mean), "n",
 *                    "range": {"achieved": [min, max], "target_p001_p999": [q001, q999]},
 *                    "cdf": {"x": [k] (area, increasing), "target": [k] F(x),
 *                            "achieved": [k] empirical CDF at x}},
 *      "grain_area": the same, against the grains' law (absent when no grains were built),
 *      "cell_orientation":  {"target": {"mean_deg", "anisotropy"}, "ks", "ks_critical", "n"},
 *      "grain_orientation": the same,
 *      "passing": {"diameters": [m], "target": [m] %, "achieved": [m] %, "max_error_pp"}
 *                 (grains by mass; sieve law only)}
 *  },
 *  "warnings": ["one line each: a target not reached and how close it came", ...]
 *              (always there; [] when every target was met),
 *  "timings": {"tessellation", "imc", "fill", "odec", "descriptors", "total"}  (seconds),
 *  "grains": [{"id", "cell", "contour": [[x,y],...], "area", "orientation_deg",
 *              "cell_fraction", "descriptors": {...} (output descriptors),
 *              "discs": [[x,y,r],...] (output odec)}]   (with any of grains/odec/descriptors),
 *  "cells": [{"id", "seed": [x,y], "polygons": [[[x,y],...],...], "area",
 *             "orientation_deg"}]                      (with output "cells")}
 *
 * 3D ("spheres-3d"):
 * {"kind": "spheres-3d", "seed": 7, "outputs": [...],
 *  "box": [bx, by, bz] (m, the final (tiled) box), "sample_box": [bx, by, bz], "tiling": [nx,ny,nz],
 *  "stats": {
 *    "porosity": {"target", "achieved" (final packing), "sample", "deposition"},
 *    "coordination_number": z (wall contacts counted), "coordination_spheres": z,
 *    "fabric": [[3x3]] (output fabric), "stress": [[3x3]] Pa (output stress),
 *    "psd": {"diameters": [n] (m), "target_weight", "achieved_weight", "target_number",
 *            "target_number_midbin", "achieved_number"}  (percent passing),
 *    "particles": n (final packing), "sample_particles", "contacts", "wall_contacts",
 *    "stop_reason", "stability", "tiled_stability", "compaction_friction_deg", "steps", "dt"},
 *  "timings": {"deposition", "compaction", "relaxation", "tiling", "total"} (seconds),
 *  "spheres": [[x, y, z, r], ...] (output spheres),
 *  "contacts": [{"i", "j", "normal": [3], "overlap", "force": [3]}] (output contacts; j < 0 is
 *              wall -1-j, walls 0..5 = x-, x+, y-, y+, z-, z+)}
 * Histogram "target" is null where there is no target. Non-finite numbers are written as null;
 * reals are printed with 17 significant digits (they read back bit for bit, as in the exports).
 * The field names follow server/svg.h.
 */
#ifndef GPD_RESULT_JSON_H
#define GPD_RESULT_JSON_H

#include <jansson.h>

#include "gp_specimen2d.h"
#include "gp_specimen3d.h"

/* A new reference (NULL on out of memory). spec_json is the effective spec (for the echoed
 * container, seed and outputs). */
json_t *gpd_result_2d(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json);

json_t *gpd_result_3d(const gp_specimen3d *s, const gp_spec3d *spec, const json_t *spec_json);

/* The same, returning early as soon as *cancel (read atomically every few thousand numbers;
 * may be NULL) is non-zero: the arrays of a large specimen take seconds to build. The caller
 * must then look at the flag: the tree returned is partial (free it: json_decref). A complete
 * tree does not depend on cancel. */
json_t *gpd_result_2d_c(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json,
                        const volatile int *cancel);
json_t *gpd_result_3d_c(const gp_specimen3d *s, const gp_spec3d *spec, const json_t *spec_json,
                        const volatile int *cancel);

/* json_dumps(r, flags), the same text, NULL when *cancel (read every few thousand pieces of
 * output; may be NULL) came up or memory ran out: writing a 133 MB result takes ~5 s. */
char *gpd_dumps_c(const json_t *r, size_t flags, const volatile int *cancel);

/* stats.fit of a specimen (a new object; blocks whose `present` is 0 are left out). Without
 * with_curves the "cdf" arrays are left out: the compact summary of a job's progress detail. */
json_t *gpd_fit_2d(const gp_fit2d *f, int with_curves);

/* The specimen's warnings as a JSON array of strings (a new reference; [] when none). */
json_t *gpd_warnings_2d(const gp_specimen2d *s);

/* A double as JSON: a real, or null when not finite. */
json_t *gpd_jreal(double x);

#endif /* GPD_RESULT_JSON_H */
