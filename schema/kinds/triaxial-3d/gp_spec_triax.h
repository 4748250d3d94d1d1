/* gp_spec_triax.h -- the spec of kind "triaxial-3d" (shared/spec/api.md): a triaxial test of a
 * sphere specimen (core/3d/gp_triax.h), parsed from an effective spec for the worker.
 *
 * The specimen of an effective spec is always inline: {"spec": {an effective spheres-3d spec},
 * "part": "sample|tiled"}, with "job": id kept for provenance when it came from a job (the
 * daemon's submit path resolves {"job": id} into that job's stored effective spec before the
 * spec is validated: server/kinds/triaxial-3d/kind_triax.c). The worker rebuilds the specimen
 * from it (the same spec and seed give the same spheres bit for bit) and runs one test per
 * confining stress.
 *
 * Checks at validation (gp_spec_validate, gp_spec_with_defaults), beyond the schema's: a
 * specimen with neither job nor spec (invalid_spec at /specimen), a job not resolved (at
 * /specimen/job: only the daemon resolves it), the inline spec as a spheres-3d spec (its
 * problems at /specimen/spec/...; its kind may be left out, and it takes the test's seed when it
 * has none), part "tiled" of an untiled specimen (at /specimen/part), and the work of the
 * specimen and of every test against GP_SPEC_WORK_BUDGET_S (too_large at the field that drives
 * it: /specimen/part, /material/young, /material/density, /strain_rate, /confining_kpa, or the
 * specimen's size, /specimen/spec/box or /specimen/job).
 *
 * Ownership and thread safety as gp_spec.h. */
#ifndef GP_SPEC_TRIAX_H
#define GP_SPEC_TRIAX_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "gp_problem.h"
#include "gp_specimen3d.h"
#include "gp_triax.h"

#define GP_SPEC_TRIAX_MAX_TESTS 5 /* confining stresses at most */
#define GP_SPEC_TRIAX_SAMPLES 250 /* points of each curve (gp_triax_params.samples) */

/* outputs (bit flags) */
enum {
    GP_OUT_TRIAX_CURVES = 1u << 0, /* the curves, one per confinement */
    GP_OUT_TRIAX_SPHERES = 1u << 1 /* the spheres at the end of the last test */
};

typedef struct gp_spec_triax {
    uint64_t seed;
    /* the specimen's spec as the core builds it: its own material and seed, outputs spheres
     * only, tiling {1, 1, 1} for part "sample" (the sample is the same bit for bit: the tiling
     * comes after it); it owns its sieve */
    gp_spec3d specimen;
    int tiled;                   /* part "tiled" */
    char job[33];                /* the specimen's job, "" for an inline spec */
    gp_material3d material;      /* the test's: the specimen's with the spec's overrides */
    size_t ntests;
    double confining[GP_SPEC_TRIAX_MAX_TESTS]; /* sigma3 of each test, Pa, as given */
    double axial_strain;         /* logarithmic, in (0, 0.5] */
    double strain_rate;          /* 1/s */
    gp_triax_drainage drainage;
    double d50;                  /* m: the median diameter by weight of the specimen's sieve */
    double r_min;                /* m: its smallest radius (the first sieve row) */
    unsigned outputs;            /* GP_OUT_TRIAX_* */
    int threads;                 /* DEM threads of the specimen and the tests (the caller's) */
} gp_spec_triax;

/* Parses an effective spec of the kind (from gp_spec_with_defaults) into *out without
 * validating it again; threads 0. 0, or -1 with *p (invalid_spec at /kind for another kind,
 * "internal" at a field missing or malformed). *out owns the specimen's sieve: release it with
 * gp_spec_triax_free (also after a failure). */
int gp_spec_triax_read(const json_t *effective_spec, gp_spec_triax *out, gp_spec_problem *p);
void gp_spec_triax_free(gp_spec_triax *s);

/* The parameters of test i (< s->ntests): gp_triax_params_defaults with the spec's confining
 * stress, strain, rate, drainage, d50, threads, GP_SPEC_TRIAX_SAMPLES samples and max_steps =
 * gp_triax_estimate_steps (the work bound counts those steps). */
void gp_spec_triax_params(const gp_spec_triax *s, size_t i, gp_triax_params *out);

#endif /* GP_SPEC_TRIAX_H */
