/* kind_fv2d.h -- the result writer of the 2D kind (Fourier-Voronoi specimens of core/2d; its
 * format is at the top of kind_fv2d.c), for the tests. The kind itself, gpd_kind_fv2d (kind.h),
 * is in the table of kinds.c; its views are in svg_views2d.c.
 */
#ifndef GPD_KIND_FV2D_H
#define GPD_KIND_FV2D_H

#include <jansson.h>

#include "gp_specimen2d.h"

/* The result of s (a new reference; NULL on out of memory), returning early as soon as *cancel
 * (may be NULL) comes up: the tree is then partial (the caller sees the flag). spec_json is the
 * effective spec (the echoed container and outputs). */
json_t *gpd_result_2d(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json,
                      const volatile int *cancel);

/* stats.fit of a specimen (a new object; blocks whose `present` is 0 are left out). Without
 * with_curves the "cdf" arrays are left out: the compact summary of a job's progress detail. */
json_t *gpd_fit_2d(const gp_fit2d *f, int with_curves);

/* The specimen's warnings as a JSON array of strings (a new reference; [] when none). */
json_t *gpd_warnings_2d(const gp_specimen2d *s);

#endif /* GPD_KIND_FV2D_H */
