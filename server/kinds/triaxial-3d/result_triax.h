/* result_triax.h -- what a triaxial-3d job (kind_triax.c) leaves: its run (the specimen and
 * one test per confining stress), the result JSON written from it, and the csv export of the
 * result's curves.
 *
 * The result (result_json.h for the conventions; stresses in kPa, moduli in MPa, angles in
 * degrees, strains as fractions, compression positive):
 * {"kind", "seed", "outputs",
 *  "specimen": {"job": id or null, "part": "sample|tiled", "particles": N (spheres tested),
 *               "box": [3] (m, the box of the part tested), "porosity" (that part's, before
 *               the test),
 *               "d50" (m, of its sieve by weight: the inertial number's)},
 *  "material": {"density", "young", "poisson", "friction_deg", "damping"} (the test's),
 *  "drainage", "axial_strain", "strain_rate",
 *  "box": [3] (m, the walls of the last test at its end; the spheres are given in [0, box]),
 *  "stats": {
 *    "particles": N,
 *    "tests": [{"confining_kpa",
 *               "peak": {"stress_ratio", "axial_strain", "phi_deg", "sigma1_kpa", "sigma3_kpa",
 *                        "q_kpa", "p_kpa"},
 *               "end": {"stress_ratio", "phi_deg", "axial_strain", "volumetric_strain",
 *                       "porosity"},
 *               "dilatancy_deg", "e50_mpa", "inertial_number_max", "servo_error_max",
 *               "stability" (the largest S_c over the loading), "still_rising",
 *               "consolidation": {"steps", "porosity", "stability", "wall_kpa": [x, y, z],
 *                                 "height", "volume"},
 *               "steps", "dt", "walls": {"lo": [3], "hi": [3]} (m, at the end)}, ...],
 *    "mohr_coulomb": {"phi_deg", "cohesion_kpa", "residual" (kPa: the RMS distance of the peak
 *                     states' t = (sigma1 - sigma3) / 2 from the envelope)}},
 *  "warnings": ["...", ...],
 *  "timings": {"specimen", "consolidation", "loading", "total"} (seconds),
 *  "curves": [{"confining_kpa", and arrays of the samples: "axial_strain",
 *              "volumetric_strain", "sigma1_kpa", "sigma3_kpa", "q_kpa", "p_kpa",
 *              "stress_ratio", "coordination", "coordination_mechanical", "porosity",
 *              "stability", "inertial_number", "sigma1_lw_kpa", "sigma3_lw_kpa",
 *              "servo_error"}, ...] (output curves; one per confinement, in the spec's order),
 *  "spheres": [[x, y, z, r], ...] (output spheres: the specimen at the end of the last test)}
 */
#ifndef GPD_RESULT_TRIAX_H
#define GPD_RESULT_TRIAX_H

#include <stddef.h>

#include <jansson.h>

#include "gp_specimen3d.h"
#include "gp_triax.h"
#include "jobs/result_json.h"
#include "kinds/triaxial-3d/gp_spec_triax.h"
#include "util/util.h"

/* warnings' thresholds */
#define RESULT_TRIAX_INERTIAL_MAX 1e-3 /* quasi-static below */
#define RESULT_TRIAX_SERVO_MAX 0.02    /* the lateral stress within 2 % of sigma3 */

/* a run: the specimen as built (the tested spheres) and its tests, the envelope */
typedef struct gpd_triax_run {
    gp_specimen3d *specimen;
    int specimen_ok;             /* its build succeeded */
    size_t ntests;               /* tests run (all of them once the run succeeded) */
    gp_triax_result *test[GP_SPEC_TRIAX_MAX_TESTS];
    double mc_phi_deg, mc_cohesion, mc_residual; /* Pa for the last two; NaN: none */
    char mc_error[GP_ERROR_MESSAGE_MAX];         /* why there is none ("" when there is) */
    unsigned outputs;            /* GP_OUT_TRIAX_* */
} gpd_triax_run;

/* The Mohr-Coulomb envelope (gp_triax_mohr_coulomb) of the tests' peak states (sigma3 and
 * sigma1 of each curve's sample of the largest ratio) into run; when there is none, NaNs and
 * why in run->mc_error (the result warns: a job does not fail for it). */
void result_triax_envelope(gpd_triax_run *run);

/* Writes the result of a finished run into w and returns its head (without curves and
 * spheres), a new object; NULL out of memory. */
json_t *result_triax_write(const gpd_triax_run *run, const gp_spec_triax *spec,
                           const json_t *spec_json, gpd_jw *w);

/* The expected seconds of writing the result of a run (its spheres and curves). */
double result_triax_cost(const gpd_triax_run *run);

/* The csv export of a result's summary: a header line, then one line per sample of each
 * curve: confining_kpa and the curves' arrays, in the order above. NULL with err: 409 when the
 * result has no curves, 500 out of memory. */
char *result_triax_csv(const json_t *summary, size_t *len, gpd_err *err);

#endif /* GPD_RESULT_TRIAX_H */
