/* result_geostatic.h -- what a geostatic-3d job (kind_geostatic.c) leaves: its run (the
 * specimen and the settled state), the result JSON written from it, and the csv export of the
 * result's profile.
 *
 * The result (result_json.h for the conventions; stresses in kPa, lengths in m, compression
 * positive, axes of the box: "sigma_zz" is the vertical for the default gravity):
 * {"kind", "seed", "outputs",
 *  "specimen": {"job": id or null, "part": "tiled|sample", "particles", "box": [3] (the packing
 *               settled), "sample_box": [3], "tiling": [3], "porosity" (as built)},
 *  "material": {"density", "young", "poisson", "friction_deg", "damping"},
 *  "gravity": [3], "vertical": "x|y|z", "wall_friction_deg",
 *  "phi_deg", "phi_from": {"job": id} or null,
 *  "box": [3] (m; the spheres are given in [0, box]),
 *  "stats": {
 *    "particles",
 *    "k0": {"theory" (1 - sin phi'), "mean", "sd", "bulk", "slabs" (counted)},
 *    "equilibrium": {"max_error" (full cross-section sigma_v against the weight above, the slabs
 *                    away from the top), "core_max_error", "slabs"},
 *    "stability" (the DEM's S_c at the end), "stability_contacts" (Eq. 7 recomputed from the
 *    final contacts), "converged", "steps", "dt", "dt_cuts", "scaled_radius",
 *    "d50", "dmax", "slab" (thickness used), "margin" (m, left out next to the walls),
 *    "whole": {"love_weber_kpa": [3][3], "walls_kpa": [3] (the same diagonal from the wall
 *              forces), "wall_stress_kpa": [6] (walls x-, x+, y-, y+, z-, z+), "max_error",
 *              "weight_n", "centroid_height", "porosity", "coordination", "contacts",
 *              "wall_contacts", "friction_mobilised", "sliding", "surface"}},
 *  "profile": {"depth", "sigma_xx_kpa", "sigma_yy_kpa", "sigma_zz_kpa", "weight_kpa", "k0",
 *              "porosity", "coordination" (the core of each slab), "sigma_xx_full_kpa",
 *              "sigma_yy_full_kpa", "sigma_zz_full_kpa", "k0_full" (the full cross-section),
 *              "k0_counted", "equilibrium_counted" (booleans)} (output profile; slab 0 at the
 *              top),
 *  "map": {"horizontal": "x|y", "vertical": "x|y|z", "nx", "nz", "dx", "dz",
 *          "slice": [lo, hi] (m, along the other horizontal axis), "tile": [h, v] (m, the
 *          sample's size along the map's axes: the tile seams), "sigma_v_kpa": [[nx] x nz],
 *          "sigma_h_kpa": [[nx] x nz] (row 0 at the top)},
 *  "warnings": [...],
 *  "timings": {"specimen", "settling", "measure", "total"} (seconds),
 *  "spheres": [[x, y, z, r], ...] (output spheres: the settled packing)}
 */
#ifndef GPD_RESULT_GEOSTATIC_H
#define GPD_RESULT_GEOSTATIC_H

#include <stddef.h>

#include <jansson.h>

#include "gp_geostatic.h"
#include "gp_specimen3d.h"
#include "jobs/result_json.h"
#include "kinds/geostatic-3d/gp_spec_geostatic.h"
#include "util/util.h"

#define RESULT_GEOSTATIC_EQUILIBRIUM_MAX 0.02 /* sigma_v within 2 % of the weight above */

/* a run: the specimen as built and its settled state */
typedef struct gpd_geostatic_run {
    gp_specimen3d *specimen;
    int specimen_ok;             /* its build succeeded */
    gp_geostatic_result *state;  /* NULL until settled */
    unsigned outputs;            /* GP_OUT_GEO_* */
} gpd_geostatic_run;

/* Writes the result of a finished run into w and returns its head (without spheres), a new
 * object; NULL out of memory. */
json_t *result_geostatic_write(const gpd_geostatic_run *run, const gp_spec_geostatic *spec,
                               const json_t *spec_json, gpd_jw *w);

/* The expected seconds of writing the result of a run. */
double result_geostatic_cost(const gpd_geostatic_run *run);

/* The csv export of a result's summary: a header line, then one line per slab with the
 * profile's arrays in the order above (booleans as 1 / 0). NULL with err: 409 when the result
 * has no profile, 500 out of memory. */
char *result_geostatic_csv(const json_t *summary, size_t *len, gpd_err *err);

#endif /* GPD_RESULT_GEOSTATIC_H */
