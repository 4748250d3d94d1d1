/* gp_spec.h -- the spec layer of the service: the JSON Schemas of a job spec, a validator
 * that interprets them, the semantic checks the schemas cannot express, the defaults, the
 * parsers from an effective spec to the core's spec structs, and the work and result bounds.
 *
 * Single source of truth: schema/<kind>.schema.json (JSON Schema 2020-12, one per kind: the
 * 2D Fourier-Voronoi specimen and the 3D sphere packing), embedded into the library at build
 * time. The validator interprets those documents (type, properties, required,
 * additionalProperties, minimum/maximum/exclusiveMinimum/exclusiveMaximum, minItems/maxItems,
 * items, prefixItems, enum, const, oneOf, uniqueItems, minLength/maxLength, local $ref) and the
 * defaults are read from their "default" keywords. Other keywords are annotations to the
 * engine: the one the schemas use, minProperties (shape.descriptors), is checked by the kind's
 * C code with its own message.
 *
 * Layout (schema/): gp_schema_engine.c, the generic JSON Schema interpreter; gp_spec.c, the
 * table of kinds and what they share (dispatch, defaults, problems, bounds entry points);
 * gp_spec2d.c and gp_spec3d.c, each kind's parser, semantic checks and bounds. The polygon
 * rings of a 2D container are checked by the core (core/2d/gp_rings.h: exact plane sweep).
 *
 * The life of a spec: POST /v1/jobs calls gp_spec_with_defaults() once (schema, semantic
 * checks, work budget; the result is the effective spec the daemon stores), then
 * gp_spec_check_result(); the worker reads the stored effective spec with gp_spec2d_read() /
 * gp_spec3d_read(), which do NOT validate again.
 *
 * GET /v1/schema serves gp_schema_document(): one document
 *   {"$schema": ".../2020-12/schema", "$id": "...", "title": ..., "description": ...,
 *    "oneOf": [{"$ref": "#/$defs/<2D kind>"}, {"$ref": "#/$defs/<3D kind>"}],
 *    "$defs": {"<2D kind>": <2D schema>, "<3D kind>": <3D schema>}}
 * (each kind's schema is a complete embedded schema resource with its own $id).
 *
 * Problems. The FIRST problem found (instance keys in document order, then missing required
 * fields) is reported, with a code; the HTTP layer chooses the status (server/http/http.c: 500 for
 * "internal", 422 for the others):
 *   "invalid_spec" -- the spec breaks its schema (wrong type, range, unknown field, missing
 *                     field, bad enum, unknown kind, ...), or fits it but is not meaningful
 *                     (self-intersecting polygon, hole outside the container, sieve rows not
 *                     increasing, largest sieve diameter larger than the box, a size.cov out of
 *                     its law's range, a field that size.law excludes or needs, an E1-E3
 *                     imc.threshold below the integer-count floor of the cell count, two shape
 *                     forms mixed (at the field that starts the second: "/shape/descriptors:
 *                     cannot be combined with "D2" ..."), empty shape.descriptors, target
 *                     descriptors that no star-shaped Fourier grain reaches (at
 *                     /shape/descriptors/<name>, the first in the order elongation,
 *                     circularity, roundness, regularity, with the nearest reachable value:
 *                     gp_shapemap_check), an outline that is not star-shaped from any interior
 *                     point, crosses itself or has no area (at /shape/outlines/<i>, the first,
 *                     naming the others), ...);
 *   "too_large"    -- a 2D sieve law whose derived cell count exceeds the schema's particles
 *                     maximum (/size/sieve); 2D shape.outlines of more than 2,000,000 vertices
 *                     in all (/shape/outlines); a 3D sample of more spheres than the DEM takes
 *                     (/box) or a tiling beyond its sphere limit (/tiling); a spec whose
 *                     estimated work is over GP_SPEC_WORK_BUDGET_S (see gp_spec_bounds), at the
 *                     field that drives it; a result over the server's bound;
 *   "internal"     -- out of memory, a broken embedded schema, or a parser given what is not
 *                     an effective spec (a field missing or malformed).
 * pointer is an RFC 6901 JSON pointer into the spec ("" is the whole document, keys escaped
 * with ~0/~1). For a missing required field the pointer names the missing field itself
 * (e.g. "/imc/error"). message is one human line that starts with the pointer, e.g.
 *   /size/cov: expected a number >= 0, got "abc"
 *   /kind: unknown kind "x"; expected one of <the kinds, quoted>
 *   /container/polygon: expected at least 3 items, got 2
 *   /particles: unknown field (allowed here: ...)
 *
 * Ownership: the functions only read the specs they are given; what they return is the
 * caller's (a new JSON reference, or arrays in a struct to free with its _free function).
 * Thread safety: every function may be called from several threads at once; the embedded
 * schemas are parsed once (pthread_once) and only read afterwards.
 */
#ifndef GP_SPEC_H
#define GP_SPEC_H

#include <jansson.h>

#include "gp_problem.h"
#include "gp_specimen2d.h"
#include "gp_specimen3d.h"

/* The kinds' names, NULL-terminated: {<2D kind>, <3D kind>, NULL} (the "kind" of a spec;
 * schema/<kind>.schema.json). */
const char *const *gp_spec_kinds(void);

/* The combined schema document served at GET /v1/schema (static, NUL-terminated JSON). */
const char *gp_schema_document(void);

/* The schema text of one kind, or NULL for an unknown kind. */
const char *gp_schema_text(const char *kind);

/* Validates a spec against the schema of its "kind" AND runs the semantic checks that the
 * schema cannot express. Returns 0 when valid, else -1 and fills *p (p may be NULL). */
int gp_spec_validate(const json_t *spec, gp_spec_problem *p);

/* A new reference to a copy of a valid spec with every default filled in (for storing the
 * effective spec and echoing it back). NULL (and *p filled) when the spec is invalid.
 * 2D defaults that depend on other fields: with size.law "sieve" the copy has no particles
 * (the count is derived: gp_spec2d_cell_count) and no size.cov, and size.of is "grains";
 * without it there is no size.sieve_units; imc.threshold, when absent, is
 * gp_imc_default_threshold() of imc.error; imc.max_steps, when absent, stays absent (its
 * default depends on the cell count: gp_spec2d_read resolves it). The copy is itself a valid
 * spec whose effective spec is the same copy. Its objects are new; its arrays (and scalars)
 * are shared with spec, read-only: change neither in place while the other is in use. */
json_t *gp_spec_with_defaults(const json_t *spec, gp_spec_problem *p);

/* Parses an effective spec of the 2D kind -- one that gp_spec_with_defaults() returned (or
 * its JSON text read back) -- into *out, WITHOUT validating it again: the input must come from
 * gp_spec_with_defaults. out->threads is 0 (the caller picks); out->particles
 * is 0 with a sieve law, whose sieve_d are in metres, converted from size.sieve_units.
 * imc.max_steps absent: out->imc_max_steps_default is 1 and out->imc_max_steps the default
 * for the cell count (gp_spec2d_default_max_steps, clipped to what the work budget leaves
 * after the grains, never below GP_IMC_DEFAULT_STEPS_MIN); the work bounds count it. The
 * shape: shape_form and its fields (D2 .. beta; spectrum; desc_given and desc_target; outlines
 * as given, vertices in their order), spread and spread_given (absent: 0 and 0). A cheap
 * guard only: another kind is refused with invalid_spec at /kind, a field missing or of the
 * wrong form with "internal" at that field. Returns 0 on success; *out then owns its arrays
 * (outer.pts, holes[*].pts, holes, spectrum, sieve_d, sieve_pass, outlines[*].pts, outlines)
 * and must be released with
 * gp_spec2d_free(). On failure returns -1, fills *p, and *out owns nothing (freeing it is still
 * allowed). */
int gp_spec2d_read(const json_t *effective_spec, gp_spec2d *out, gp_spec_problem *p);
void gp_spec2d_free(gp_spec2d *s);

/* The same for the 3D kind (from gp_spec_with_defaults, not validated again): sieve
 * diameters converted to metres (sieve_units), tiling {1, 1, 1} when absent; threads,
 * max_steps and tile_relax_steps are set to 0 (the caller picks). *out owns its sieve array;
 * release with gp_spec3d_free(). */
int gp_spec3d_read(const json_t *effective_spec, gp_spec3d *out, gp_spec_problem *p);
void gp_spec3d_free(gp_spec3d *s);

/* ---- work and result bounds (api.md "Limits and origin") ---- */

/* What a job of a valid effective spec will cost, estimated from its numbers whatever their
 * spelling (1e6 is the integer 1000000), in one place per kind:
 *   2D: cells = particles, or the count a sieve law derives; the IMC at its cap
 *     (imc.max_steps moves or their default, each costing a little more on more cells), the
 *     filling, ODEC and descriptors per grain in proportion to contour_points, the shape's own
 *     work (target descriptors: the fit and the calibration's fills; outlines: one description
 *     each); the result as server/http/http.c has always estimated it (bytes per grain by
 *     outputs and contour_points);
 *   3D: the sample's spheres (gp_sieve_expected_count, the count the DEM draws), its
 *     time step (gp_dem3d.h: 0.3 sqrt(m / 2 E R) at the density-scaling radius of
 *     gp_specimen3d.c) and the steps its protocol needs (durations are multiples of
 *     sqrt(d50 / g)); the result by spheres and contacts of the tiled packing.
 * The figures are estimates (within a factor of a few of what the benchmarks measure), meant
 * for bounds, not for progress. */
typedef struct gp_spec_bounds {
    double cells;               /* 2D: Voronoi cells (= grains); 3D: spheres of the sample */
    double items;               /* grains (2D) or spheres of the final, tiled packing (3D) */
    double steps;               /* 2D: IMC moves at most; 3D: DEM steps the protocol needs */
    double dt;                  /* 3D: the DEM time step, s (0 in 2D) */
    double work_s;              /* estimated seconds of one core for the whole job */
    double result_bytes;        /* estimated size of the result JSON */
    const char *work_pointer;   /* the field that drives the work (static string) */
    const char *result_pointer; /* the field that drives the result size (static string) */
} gp_spec_bounds_t;

/* The fixed work budget: a spec whose work_s is over it is refused at validation (too_large at
 * work_pointer), by gp_spec_validate and gp_spec_with_defaults.
 * Two days of one core. The paper's 3D example is estimated at ~30 s and a 10,000-grain 2D
 * specimen with every output at ~2 min, three orders of magnitude below; the test suite's long
 * job (40,000 cells, E3 at 1e-9, imc.max_steps 1e9: ~1.4 days at its cap) passes. Refused:
 * every 2D maximum at once (a million grains of 4,096 points, 1e9 IMC moves: ~3 days), a DEM
 * time step collapsed by a huge young on many spheres, a 1 MB container whose edges make each
 * IMC move cost a second. The server's --job-timeout bounds what runs (1 h by default); this
 * bounds what is accepted, whatever that setting. */
#define GP_SPEC_WORK_BUDGET_S 172800.0

/* Fills *out for a valid effective spec (from gp_spec_with_defaults; the container geometry
 * is not checked again). Returns 0, or -1 with *p (e.g. a sieve count out of reach). */
int gp_spec_bounds(const json_t *effective_spec, gp_spec_bounds_t *out, gp_spec_problem *p);

/* The server's result bound: 0 when the estimated result of a valid effective spec is at most
 * max_bytes, else -1 with *p = too_large at result_pointer ("/particles", "/size/sieve",
 * "/box" or "/tiling") and a message that gives both sizes in MB and names
 * --max-result-mb; -1 with *p from gp_spec_bounds when it fails. */
int gp_spec_check_result(const json_t *effective_spec, double max_bytes, gp_spec_problem *p);

#endif /* GP_SPEC_H */
