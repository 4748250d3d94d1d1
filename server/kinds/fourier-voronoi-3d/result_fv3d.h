/* result_fv3d.h -- the result of a 3D Fourier-Voronoi specimen (core/3d/gp_fv3d.h) as JSON: its
 * format is at the top of result_fv3d.c. kind_fv3d.c writes it for a job; the tests read it
 * back through result_fv3d_tree. */
#ifndef GPD_RESULT_FV3D_H
#define GPD_RESULT_FV3D_H

#include <jansson.h>

#include "gp_fv3d.h"
#include "jobs/result_json.h"
#include "kinds/fourier-voronoi-3d/gp_spec_fv3d.h"

/* Writes the result of s into w (result_json.h: it stops by itself at w's cancel flag) and
 * returns its head: the result without "icosphere" and its per-item arrays (a new object;
 * NULL on out of memory, nothing written). spec_json is the effective spec (the echoed
 * container and outputs). */
json_t *result_fv3d_write(const gp_fv3d *s, const gp_spec_fv3d *spec, const json_t *spec_json,
                          gpd_jw *w);

/* The result of s as a tree (a new reference): the text result_fv3d_write writes, parsed
 * back; NULL on out of memory. */
json_t *result_fv3d_tree(const gp_fv3d *s, const gp_spec_fv3d *spec, const json_t *spec_json);

/* stats.fit of a specimen (a new object); without with_curves the "cdf" arrays are left out
 * (the summary of a finished job's progress detail). */
json_t *result_fv3d_fit(const gp_fv3d *s, const gp_spec_fv3d *spec, int with_curves);

/* The specimen's warnings (a new array; [] when every target was met). */
json_t *result_fv3d_warnings(const gp_fv3d *s, const gp_spec_fv3d *spec);

/* The bytes of the result's text with these outputs (GP_OUT3_*), about (the progress plan's
 * "result" phase). */
double result_fv3d_bytes(const gp_fv3d *s, unsigned outputs);

#endif /* GPD_RESULT_FV3D_H */
