/* result_json.h -- what the kinds' result writers share: a finished specimen becomes the JSON of
 * GET /v1/jobs/{id}/result (api.md "Result"), written by its kind (kind.h: gpd_kind.result;
 * each kind file documents its own format), with these pieces and in these conventions:
 *   - every result begins with {"kind", "seed", "outputs" (the spec's, echoed)};
 *   - non-finite numbers are written as null; reals are printed with 17 significant digits
 *     (they read back bit for bit, as in the exports);
 *   - the per-item arrays of a large specimen take seconds to build and to write: both stop
 *     early when the worker's cancel flag comes up.
 * The field names follow server/svg.h. */
#ifndef GPD_RESULT_JSON_H
#define GPD_RESULT_JSON_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

/* A double as JSON: a real, or null when not finite. */
json_t *gpd_jreal(double x);
/* n doubles as an array of gpd_jreal, or null when v is NULL. */
json_t *gpd_jreals(const double *v, size_t n);

/* A new result: {"kind": kind, "seed": seed, "outputs": the spec's outputs (when it has them)};
 * NULL on out of memory. */
json_t *gpd_result_new(const char *kind, uint64_t seed, const json_t *spec_json);

/* 1 when the worker's cancel flag (raised by another thread with an atomic store; may be
 * NULL) is up: the writers look at it every few thousand numbers. A tree whose building was
 * cancelled is returned as it stands (freeing it can take a second, which the caller hands to
 * another thread); the caller sees the flag. */
int gpd_cancel_raised(const volatile int *cancel);

/* json_dumps(r, flags), the same text, NULL when *cancel (read every few thousand pieces of
 * output; may be NULL) came up or memory ran out: writing a 133 MB result takes ~5 s. */
char *gpd_dumps_c(const json_t *r, size_t flags, const volatile int *cancel);

#endif /* GPD_RESULT_JSON_H */
