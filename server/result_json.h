/* result_json.h -- a finished specimen as the JSON of GET /v1/jobs/{id}/result (api.md "Result").
 *
 * 2D ("fourier-voronoi-2d"):
 * {"kind": "fourier-voronoi-2d", "seed": 42, "outputs": [...],
 *  "container": <the spec's container, echoed>,
 *  "stats": {
 *    "particles":       {"target": N, "achieved": number of grains},
 *    "imc_error":       {"target": threshold, "achieved": e, "measure": "E3",
 *                        "floor": f, "stop_reason": "threshold|max_steps|floor|..."},
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
 *  },
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

/* A double as JSON: a real, or null when not finite. */
json_t *gpd_jreal(double x);

#endif /* GPD_RESULT_JSON_H */
