/* kind_specimen.h -- what the kinds made on a sphere specimen share (triaxial-3d, geostatic-3d):
 * building the specimen their spec carries (schema/gp_spec_specimen.h), its phases in a plan,
 * failure messages that say which step failed, and the material and warnings of a result.
 *
 * Thread safety: none needed (no state); the build runs on the caller's thread with the
 * specimen's own DEM threads. */
#ifndef GPD_KIND_SPECIMEN_H
#define GPD_KIND_SPECIMEN_H

#include <jansson.h>

#include "gp_error.h"
#include "gp_progress.h"
#include "gp_specimen3d.h"
#include "jobs/progress.h"

/* st with err's message prefixed by what failed ("the specimen: ..."); GP_OK and
 * GP_ERR_CANCELLED as they are. */
gp_status gpd_specimen_failed_in(gp_status st, gp_error *err, const char *what);

/* Builds the specimen of spec (its sieve read only) on `threads` DEM threads into *out (the
 * caller destroys it, also after a failure); *ok 1 when the build succeeded with spheres. The
 * status of the build, its message prefixed "the specimen: ". */
gp_status gpd_specimen_build(const gp_spec3d *spec, int threads, gp_progress_fn fn, void *user,
                             const volatile int *cancel, gp_specimen3d **out, int *ok,
                             gp_error *err);

/* The specimen's phases in a plan (the sphere kind's plan of the specimen's effective spec
 * `inner`, without its "result"): how many, into out (GPD_PLAN_MAX at most). */
int gpd_specimen_phases(const gp_spec3d *spec, const json_t *inner, gpd_phase *out);

/* Appends a line (printf) to a result's array of warnings (nothing out of memory). */
void gpd_warnf(json_t *warnings, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* {"density", "young", "poisson", "friction_deg", "damping"} (a new object). */
json_t *gpd_specimen_material_json(const gp_material3d *m);

#endif /* GPD_KIND_SPECIMEN_H */
