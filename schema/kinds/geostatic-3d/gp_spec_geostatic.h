/* gp_spec_geostatic.h -- the spec of kind "geostatic-3d" (shared/spec/api.md): a sphere
 * packing settled at rest under gravity and measured in slabs (core/3d/gp_geostatic.h), parsed
 * from an effective spec for the worker.
 *
 * The specimen is always inline in an effective spec (gp_spec_specimen.h: the daemon resolves
 * {"job": id}); the worker rebuilds it, its part "tiled" (the final packing; an untiled
 * specimen is its one tile) or "sample". phi' is "phi_deg", or "phi_from": {"job": id} of a
 * triaxial test, which the daemon resolves at submit into {"job": id, "phi_deg": its
 * Mohr-Coulomb phi'} (server/kinds/geostatic-3d/kind_geostatic.c); without either, 23.7.
 *
 * Checks at validation (gp_spec_validate, gp_spec_with_defaults), beyond the schema's: the
 * specimen as gp_spec_specimen.h says; phi_deg and phi_from not both (invalid_spec at
 * /phi_from), phi_from resolved (at /phi_from/job); gravity along one axis of the box, not
 * zero (at /gravity); wall friction 0 (at /wall_friction_deg: the DEM's walls are
 * frictionless); the slab and the map's cells within the packing's height and at most
 * GP_SPEC_GEOSTATIC_MAX_SLABS slabs and GP_SPEC_GEOSTATIC_MAX_MAP cells along an axis (at
 * /slab, /map_cell); at most GP_SPEC_GEOSTATIC_MAX_SPHERES spheres (at /specimen/part, or the
 * specimen's spec); the work of the specimen and of max_steps DEM steps against
 * GP_SPEC_WORK_BUDGET_S (too_large at /max_steps, or the specimen's size).
 *
 * Ownership and thread safety as gp_spec.h. */
#ifndef GP_SPEC_GEOSTATIC_H
#define GP_SPEC_GEOSTATIC_H

#include <stdint.h>

#include <jansson.h>

#include "gp_geostatic.h"
#include "gp_problem.h"
#include "gp_specimen3d.h"

#define GP_SPEC_GEOSTATIC_MAX_SPHERES 400000.0 /* spheres settled at most (the DEM's limit) */
#define GP_SPEC_GEOSTATIC_MAX_SLABS 2000       /* slabs over the height at most */
#define GP_SPEC_GEOSTATIC_MAX_MAP 200          /* map cells along an axis at most */
#define GP_SPEC_GEOSTATIC_PHI_DEG 23.7         /* phi' when the spec gives none */

/* outputs (bit flags) */
enum {
    GP_OUT_GEO_PROFILE = 1u << 0, /* the slab profiles */
    GP_OUT_GEO_SPHERES = 1u << 1  /* the settled spheres */
};

typedef struct gp_spec_geostatic {
    uint64_t seed;
    /* the specimen's spec as the core builds it: outputs spheres only, tiling {1, 1, 1} for
     * part "sample"; it owns its sieve */
    gp_spec3d specimen;
    int tiled;                   /* part "tiled" */
    char job[33];                /* the specimen's job, "" inline */
    char phi_job[33];            /* the triaxial job phi' came from, "" when given */
    /* the core's parameters: the specimen's material, gravity, wall friction, phi', slab (0:
     * 5 d50), margin, map cell (0: the slab), stability, max_steps; threads set by the run */
    gp_geostatic_params params;
    unsigned outputs;            /* GP_OUT_GEO_* */
    int threads;                 /* DEM threads (the caller's) */
} gp_spec_geostatic;

/* Parses an effective spec of the kind into *out without validating it again; threads 0. 0,
 * or -1 with *p (invalid_spec at /kind for another kind, "internal" at a field missing or
 * malformed). *out owns the specimen's sieve: release it with gp_spec_geostatic_free (also
 * after a failure). */
int gp_spec_geostatic_read(const json_t *effective_spec, gp_spec_geostatic *out,
                           gp_spec_problem *p);
void gp_spec_geostatic_free(gp_spec_geostatic *s);

/* The kind phi_from's job must be of (the triaxial test's). */
const char *gp_spec_geostatic_phi_kind(void);

#endif /* GP_SPEC_GEOSTATIC_H */
