/* gp_specimen2d_internal.h -- internal to the gp_specimen2d library: the shape of the grains
 * (gp_specimen2d_shape.c) as the pipeline (gp_specimen2d.c) uses it. */
#ifndef GP_SPECIMEN2D_INTERNAL_H
#define GP_SPECIMEN2D_INTERNAL_H

#include "gp_specimen2d.h"

/* Sets *used (zeroed first; its arrays are then owned by it) from the spec's shape form: the
 * mean spectrum of nmodes modes (D2/D3/D8; a given spectrum; gp_shapemap_fit of the target
 * descriptors; gp_outline_set_analyze of the outlines) and the per-mode spread (shape.spread
 * for every mode, or the outlines' own cov, capped at GP_SHAPE_SPREAD_MAX; none: cov NULL).
 * Deterministic from the spec (the descriptor fit samples its grains from a seed derived from
 * spec->seed). cancel is polled by the outlines' analysis. Errors: GP_ERR_INVALID /
 * GP_ERR_INFEASIBLE (unreachable descriptors, too few analysable outlines) with a message,
 * GP_ERR_NOMEM, GP_ERR_CANCELLED. progress (may be NULL) hears the outlines' analysis
 * (phase "shape", gp_outline_params). */
gp_status gp_specimen2d_shape_setup(const gp_spec2d *spec, size_t nmodes,
                                    const volatile int *cancel, gp_progress_fn progress,
                                    void *user, gp_shape_used *used, gp_error *err);

/* Frees the arrays of *used and zeroes it. */
void gp_specimen2d_shape_free(gp_shape_used *used);

/* Descriptors form, one defect-correction step on filled grains (the calibration of
 * gp_specimen2d.c): the grains made with the current spectrum have the means measured[4]; the
 * table fit of the targets shifted by (measured - table prediction at the current spectrum)
 * gives the next (D2, D3, D8), written to *next (3 values). GP_ERR_INFEASIBLE when the table
 * cannot predict at the current spectrum (then nothing is to be corrected). */
gp_status gp_specimen2d_shape_correct(const gp_shape_used *used, const double *measured,
                                      double *next, gp_error *err);

/* Sets used->D2, D3, D8 and its mean spectrum to the three-parameter spectrum p[3]. */
gp_status gp_specimen2d_shape_set_d(gp_shape_used *used, const double *p, gp_error *err);

/* The misfit of means m against the targets: sum over the given descriptors of
 * ((m_k - t_k) / tol_k)^2; *missed (may be NULL) gets the bits of those beyond tol_k. */
double gp_specimen2d_shape_misfit(const gp_shape_used *used, const double *m, unsigned *missed);

#endif /* GP_SPECIMEN2D_INTERNAL_H */
