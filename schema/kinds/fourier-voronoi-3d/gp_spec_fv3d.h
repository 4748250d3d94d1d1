/* gp_spec_fv3d.h -- the spec of kind "fourier-voronoi-3d" (shared/spec/api.md): a 3D
 * Fourier-Voronoi specimen (core/3d/gp_fv3d.h), parsed from an effective spec for the worker.
 *
 * What the reader makes of the spec's fields:
 *  - container: {"box": [lx, ly, lz]} is [0, lx] x [0, ly] x [0, lz]; {"cylinder": {"radius",
 *    "height"}} has its axis along z through x = y = 0, from z = 0 to the height, as the prism
 *    of 64 side facets inscribed in it (gp_voronoi3d.h); {"polyhedron": {"halfspaces"}} the
 *    rows n . x <= d. Its volume: the box's and the prism's by their formulas, a polyhedron's
 *    measured (gp_voronoi3d_container_measure).
 *  - size: a parametric law is made with mean 1 (the core reads its shape only: the cells'
 *    mean is the container's volume / N); a sieve is gp_law_create_sieve3d of the rows in
 *    metres, a law of grains, and N = round(solid_fraction x container volume / its mean
 *    volume) (gp_spec_fv3d_count).
 *  - shape: the D form is gp_fourier_spectrum's 31 amplitudes (degrees 0 to 30, the most a
 *    grain has: GP_GRAIN3D_DEGREE_MAX); a spectrum is divided by its D0; elongation, flatness
 *    and spread as given.
 *
 * Checks at validation (gp_spec_validate, gp_spec_with_defaults) beyond the schema's, all
 * invalid_spec unless said: particles, size.cov and size.of "cells" are refused with a sieve,
 * and sieve and sieve_units without one (at the field); two shape forms or two containers
 * mixed (at the field that starts the second); a polyhedron with a zero normal (at its row),
 * empty, without volume or unbounded, or filling less than 5 % of its bounding box (at
 * /container/polyhedron/halfspaces); size.cov within its law's range; the sieve rows (at the
 * row's cell), the largest sieve grain's cell within the container, and at least one grain
 * (at /size/sieve); the orientation axis not zero; a spectrum of at most 31 amplitudes; a
 * shape whose draws are too seldom star-shaped (gp_spec_fv3d_star: fewer than
 * GP_SPEC_FV3D_STAR_MIN of GP_SPEC_FV3D_STAR_DRAWS draws, at the field that weighs most in the
 * bound); too_large: a sieve's count over particles' maximum (at /size/sieve), the memory of
 * the build over GP_SPEC_FV3D_MEMORY_MAX, the work over the budget (at the field that drives
 * it), the result over the server's bound.
 *
 * Ownership and thread safety as gp_spec.h. */
#ifndef GP_SPEC_FV3D_H
#define GP_SPEC_FV3D_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "gp_fv3d.h"
#include "gp_problem.h"

#define GP_SPEC_FV3D_MODES 31            /* the D form's amplitudes: degrees 0 .. 30 */
#define GP_SPEC_FV3D_STAR_DRAWS 32       /* grains drawn at submit when not every one is star */
#define GP_SPEC_FV3D_STAR_MIN 8          /* ... of which at least this many must be */
#define GP_SPEC_FV3D_MEMORY_MAX 16e9     /* bytes a build may hold at its peak */
#define GP_SPEC_FV3D_FILL_MIN 0.05       /* a polyhedron's volume over its bounding box's */
#define GP_SPEC_FV3D_CYLINDER_FACETS 64

typedef enum gp_spec_fv3d_container {
    GP_SPEC_FV3D_BOX = 0,
    GP_SPEC_FV3D_CYLINDER,
    GP_SPEC_FV3D_POLYHEDRON
} gp_spec_fv3d_container;

typedef struct gp_spec_fv3d {
    /* the core's spec: its container, law and spectrum point into the members below; its
     * threads is set by the caller (threads, below) */
    gp_fv3d_spec core;
    int threads;
    /* the container as given, and its volume (m^3) and bounding box */
    gp_spec_fv3d_container container;
    double box[3];
    double radius, height;
    double *planes; /* nplanes rows (nx, ny, nz, d) */
    size_t nplanes;
    double volume, lo[3], hi[3];
    /* the size law as given: its kind (gp_law_kind), cov, of grains; a sieve's rows (metres,
     * percent) */
    int law_kind;
    double cov;
    int of_grains;
    double *sieve_d, *sieve_pass;
    size_t nsieve;
    int particles_derived; /* 1: a sieve's count (gp_spec_fv3d_count) */
    gp_law *law;           /* the core's law (owned) */
    /* the shape: form 0 D (D2 .. beta), 1 spectrum; the amplitudes, D[0] = 1 */
    int shape_form;
    double D2, D3, D8, alpha, beta;
    double *spectrum;
    size_t nspectrum;
    double star_bound; /* sum over n >= 1 of D_n sqrt((2 n + 1) / 2): < 1, every draw is star */
} gp_spec_fv3d;

/* Parses an effective spec of the kind into *out without validating it again (the law made,
 * the container's volume measured, a sieve's count derived); threads 1. 0, or -1 with *p
 * (invalid_spec at /kind for another kind, "internal" at a field missing or malformed or a
 * container or law the core cannot make). Release with gp_spec_fv3d_free (also after a
 * failure). */
int gp_spec_fv3d_read(const json_t *effective_spec, gp_spec_fv3d *out, gp_spec_problem *p);
void gp_spec_fv3d_free(gp_spec_fv3d *s);

/* The names of the outputs at the index of their bit (GP_OUT3_*). */
extern const char *const gp_spec_fv3d_outputs[4];

#endif /* GP_SPEC_FV3D_H */
