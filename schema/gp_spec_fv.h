/* gp_spec_fv.h -- internal to schema/: what the two Fourier-Voronoi kinds' spec files
 * (kinds/fourier-voronoi-2d/gp_spec2d.c, kinds/fourier-voronoi-3d/gp_spec_fv3d.c) share: the
 * size law (its rules on the spec as posted, its defaults, its reader, its checks), the IMC
 * threshold's default and the reader of a shape's D form or spectrum. Their specs give these
 * fields alike; what differs is the measure a law is of (an area or a volume), a word of the
 * messages here, and the structs the readers fill (the kinds copy from the ones below).
 *
 * The problems are the kinds' own: the same pointers and messages whichever kind calls. */
#ifndef GP_SPEC_FV_H
#define GP_SPEC_FV_H

#include <stddef.h>

#include <jansson.h>

#include "gp_spec_internal.h"

/* size.law decides which size fields belong: sieve and sieve_units only with a sieve; with
 * one no particles, no cov, no size.of "cells". On the spec as posted, since particles and
 * size.cov have schema defaults. room: what a sieve's count follows from, in the words of the
 * /particles problem ("the container area"). 0 or -1 with *p. */
int gp_spec_fv_check_size_posted(const json_t *spec, const char *room, gp_spec_problem *p);

/* The defaults that depend on other fields: a sieve law has no particles (derived) and no
 * cov, and is a law of the grains; sieve_units belongs to a sieve; imc.threshold, when not
 * given, is the default of imc_error (a gp_imc_error_kind: the kind's objective). 0, or -1 out
 * of memory. */
int gp_spec_fv_settle(json_t *full, int imc_error);

/* a size law as read */
typedef struct gp_spec_fv_size {
    int law;                    /* gp_law_kind */
    int of_grains;              /* size.of: 0 "cells", 1 "grains" */
    double cov;                 /* a parametric law's (0 with a sieve) */
    double *sieve_d, *sieve_pass; /* a sieve's rows: diameters in metres, percent passing */
    size_t nsieve;
} gp_spec_fv_size;

/* The size object (at /size) of an effective spec into *z (zeroed first). -1 out of memory,
 * the rows z holds still to free. */
int gp_spec_fv_read_size(gp_spec_reader *r, const json_t *size, gp_spec_fv_size *z);

/* The shape's D form, its five numbers into *num[0..4] (D2, D3, D8, alpha, beta), or its
 * spectrum as given (D0 first: a malloc'ed array of *n amplitudes into *spectrum). 0 the D
 * form, 1 a spectrum, -1 out of memory. */
int gp_spec_fv_read_shape(gp_spec_reader *r, const json_t *shape, double *const num[5],
                          double **spectrum, size_t *n);

/* A sieve's rows (at /size/sieve), or a parametric law's size.cov: its least value and each
 * law's own maximum (gp_law.h); measure: what the law is of, "area" or "volume". 0 or -1 with
 * *p. */
int gp_spec_fv_check_size(const json_t *full, int law, double cov, const char *measure,
                          gp_spec_problem *p);

#endif /* GP_SPEC_FV_H */
