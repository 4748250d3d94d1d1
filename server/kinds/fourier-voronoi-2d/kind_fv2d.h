/* kind_fv2d.h -- the result writer of the 2D kind (Fourier-Voronoi specimens of core/2d; its
 * format is at the top of kind_fv2d.c), for the tests. The kind itself, gpd_kind_fv2d (kind.h),
 * is in the table of kinds.c; its views are in svg_views2d.c.
 */
#ifndef GPD_KIND_FV2D_H
#define GPD_KIND_FV2D_H

#include <jansson.h>

#include "gp_specimen2d.h"
#include "jobs/result_json.h"

/* Writes the result of s into w (result_json.h: it stops by itself at w's cancel flag) and
 * returns its head: the result without its arrays "grains" and "cells" (a new object; NULL on
 * out of memory, nothing written). spec_json is the effective spec (the echoed container and
 * outputs). */
json_t *gpd_result_2d_write(const gp_specimen2d *s, const gp_spec2d *spec,
                            const json_t *spec_json, gpd_jw *w);

/* The result of s as a tree (a new reference), for the tests: the text gpd_result_2d_write
 * writes, parsed back; NULL on out of memory or when *cancel (may be NULL) came up. */
json_t *gpd_result_2d(const gp_specimen2d *s, const gp_spec2d *spec, const json_t *spec_json,
                      const volatile int *cancel);

/* stats.fit of a specimen (a new object; blocks whose `present` is 0 are left out). Without
 * with_curves the "cdf" arrays are left out: the compact summary of a job's progress detail. */
json_t *gpd_fit_2d(const gp_fit2d *f, int with_curves);

/* The specimen's warnings as a JSON array of strings (a new reference; [] when none). */
json_t *gpd_warnings_2d(const gp_specimen2d *s);

#endif /* GPD_KIND_FV2D_H */
