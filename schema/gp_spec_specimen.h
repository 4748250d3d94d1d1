/* gp_spec_specimen.h -- the sphere specimen a kind's spec is made on ("specimen" of the kinds
 * that test or load a packing: triaxial-3d, geostatic-3d), shared by their spec files.
 *
 * As posted, "specimen" is {"job": id} (a succeeded sphere-packing job) or {"spec": {...}} (a
 * sphere-packing spec, its kind and seed optional). The daemon's submit path resolves a job
 * into that job's stored effective spec, put at "spec" beside the id (server/kinds/kind.h,
 * gpd_resolve_job), so an effective spec always carries its specimen inline: the worker
 * rebuilds it (the same spec and seed give the same spheres bit for bit) and never reads the
 * other job. The inline spec is validated as a sphere-packing spec on its own, its problems
 * pointed at /specimen/spec/...; without a seed it takes the enclosing spec's.
 *
 * Ownership: the json_t results are new references; nothing is kept. Thread safety: none
 * needed (no state). */
#ifndef GP_SPEC_SPECIMEN_H
#define GP_SPEC_SPECIMEN_H

#include <stddef.h>

#include <jansson.h>

#include "gp_problem.h"
#include "gp_spec.h"
#include "gp_specimen3d.h"

/* The kind a specimen job must be of (the sphere packing's). */
const char *gp_spec_specimen_kind(void);

/* The specimen spec's problem q as the enclosing spec's, at /specimen/spec<its pointer>; -1. */
int gp_spec_specimen_problem(const gp_spec_problem *q, gp_spec_problem *p);

/* The effective spec (gp_spec_with_defaults) of the specimen spec in spec ("/specimen/spec"),
 * its kind and seed filled in; NULL with *p (at /specimen/spec/...). */
json_t *gp_spec_specimen_effective(const json_t *spec, gp_spec_problem *p);

/* The rules on a posted spec's specimen: a job or a spec (invalid_spec at /specimen), a job
 * resolved (at /specimen/job: only the daemon resolves one), the spec valid. 0 or -1 with *p. */
int gp_spec_specimen_check_posted(const json_t *spec, gp_spec_problem *p);

/* Replaces full's specimen spec by its effective spec; 0, or -1 (out of memory). */
int gp_spec_specimen_settle(json_t *full);

/* The bounds of the specimen spec of an effective spec (gp_spec_bounds); 0 or -1 with *p. */
int gp_spec_specimen_bounds(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p);

/* Reads an effective spec's specimen into *out (gp_spec3d_read: free it with gp_spec3d_free,
 * also after a failure) and the job id it came from into job ("" inline). 0 or -1 with *p. */
int gp_spec_specimen_read(const json_t *full, gp_spec3d *out, char job[33], gp_spec_problem *p);

/* The diameter at which the sieve rows' percent passing crosses q (linear between rows). */
double gp_spec_sieve_quantile(const gp_sieve_row *rows, size_t n, double q);

#endif /* GP_SPEC_SPECIMEN_H */
