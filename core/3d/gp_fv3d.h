/* gp_fv3d.h -- one call from a validated spec to a 3D Fourier-Voronoi specimen (api.md, kind
 * fourier-voronoi-3d; Mollon & Zhao 2012 §7, the 3D generalisation they announce).
 *
 * Pipeline: container -> 3D IMC (gp_imc3d.h: cells whose volumes follow the cell law and whose
 * long axes follow the orientation law) -> one star-shaped Fourier grain per cell (gp_grain3d.h:
 * a spherical-harmonic radius field on the shared icosphere, the 2D spectrum per degree, optional
 * elongation and flatness) -> each grain placed in its cell (gp_fill3d.h: long axis on the
 * cell's long axis, the largest scale by an exact LP, volume solid_fraction x the cell's where
 * reachable) -> what the outputs ask for: descriptors (3D and of three projections), clumps of
 * spheres for DEM codes (gp_clump3d.h) -> the fit of every law, measured on the specimen.
 *
 * Size laws (gp_law.h, on volumes; a sieve by mass with d = (6 V / pi)^(1/3),
 * gp_law_create_sieve3d). With of = cells the IMC fits the cells to the law and each grain is
 * filled to solid_fraction of its cell: the grains follow the law scaled by solid_fraction
 * where the fill reaches it. With of = grains (always for a sieve): the cells follow the grain
 * law scaled to the cells' mean (container volume / N); every cell is filled to the largest
 * grain it holds up to solid_fraction x GP_FV3D_HEADROOM of itself; then rank matching: the
 * k-th smallest of those grains is given the k-th of the grain law's N quantiles at
 * (2k - 1) / 2N and shrunk about its centre to that volume (a homothety about a point of the
 * grain inside the cell keeps it inside, and keeps its shape and orientation), or keeps its
 * largest volume when it cannot reach it. Sorted matching asks least of every cell.
 *
 * Randomness and determinism: the IMC draws from streams 0 and 1 of the seed (gp_imc3d.h); grain
 * i (the grain of cell i) draws its amplitudes, then its rotation search, from stream 2 + i. The
 * per-grain work runs on spec->threads threads, each grain from its own stream into its own
 * slot, so the specimen is the same bit for bit whatever the thread count.
 *
 * Bounds: the work is the IMC's (bounded by imc_max_steps) plus O(N (V F + V log V + c)) for the
 * grains (V mesh vertices, F cell faces, c the clump's); memory O(N V) for the radii (float
 * would halve it; double keeps the exported meshes exact). gp_fv3d_estimate_bytes says it
 * before a run.
 *
 * Ownership: the spec and everything it points to are the caller's, read only during the
 * build. The specimen owns its tessellation, grains and clumps (gp_fv3d_destroy).
 * Thread safety: one build per call; no global state.
 */
#ifndef GP_FV3D_H
#define GP_FV3D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_fit.h"
#include "gp_law.h"
#include "gp_progress.h"
#include "gp_voronoi3d.h"

#define GP_FV3D_HEADROOM 1.2

/* outputs (bit flags) */
enum {
    GP_OUT3_GRAINS = 1u << 0,
    GP_OUT3_CLUMPS = 1u << 1,
    GP_OUT3_DESCRIPTORS = 1u << 2,
    GP_OUT3_CELLS = 1u << 3
};

typedef struct gp_fv3d_spec {
    gp_voronoi3d_container container; /* its planes (convex) are the caller's */
    size_t particles;                 /* N >= 1 */
    const gp_law *law;                /* volumes: a parametric law gives its shape (its mean is
                                       * taken as container / N for cells, solid_fraction x that
                                       * for grains); a sieve (gp_law_create_sieve3d) is
                                       * absolute, a law of grains */
    int law_of_grains;                /* 1: the grains follow the law (always for a sieve) */
    double axis[3];                   /* orientation law: axis (any length > 0) */
    double anisotropy;                /* (0, 1], 1 isotropic */
    /* shape: the mean spectrum D[0 .. nmodes-1] (D[0] = 1), per-grain spread (COV, 0 none),
     * elongation I/L and flatness S/I in (0, 1] (1: none) */
    const double *D;
    size_t nmodes;
    double spread;
    double elongation, flatness;
    unsigned mesh_level;              /* icosphere level of every grain (default 4) */
    double solid_fraction;            /* (0, 1) */
    int spheres_max;                  /* clump: 1 .. 1000 */
    double min_radius_ratio;          /* clump: (0, 1] */
    double imc_threshold;             /* > 0 */
    long imc_max_steps;               /* >= 0 */
    unsigned outputs;                 /* GP_OUT3_* */
    uint64_t seed;
    int threads;                      /* >= 1; the result does not depend on it */
} gp_fv3d_spec;

/* Fills the defaults of api.md's example (box 1 m, 1,000 particles, lognormal COV 0.5 of cells
 * -- law NULL means that: the caller may leave it NULL -- isotropic about z, D2 0.1, D3 0.05,
 * D8 0.02, alpha = beta = -2 as a spectrum the caller supplies, solid fraction 0.55, 30 spheres,
 * min_radius_ratio 0.1, the IMC's default threshold and 10^6 steps, mesh level 4, seed 0, one
 * thread, outputs grains). */
void gp_fv3d_spec_defaults(gp_fv3d_spec *s);

/* 3D descriptors of a grain (gp_grain3d.h) and MZ12's four 2D ones of its projections along
 * its three principal axes (long, intermediate, short) */
typedef struct gp_fv3d_descriptors {
    double elongation, flatness, sphericity, convexity;
    double proj[3][4]; /* per projection: elongation, roundness, circularity, regularity */
} gp_fv3d_descriptors;

typedef struct gp_fv3d_grain {
    size_t cell;
    double centre[3];       /* the radius field's origin, placed */
    double rotation[4];     /* unit quaternion w, x, y, z */
    double scale;
    double volume;
    double centroid[3];
    double inertia[9];      /* about the centroid, unit density */
    double orientation_cos; /* |cos| of the long axis against the law's axis */
    int target_met;         /* reached its target volume */
    double *radii;          /* one a shared direction, before rotation and scale */
    gp_fv3d_descriptors desc; /* with GP_OUT3_DESCRIPTORS */
    size_t nspheres;        /* with GP_OUT3_CLUMPS: spheres[4 k ..] = x, y, z, r */
    double *spheres;
    double clump_volume_error, clump_inertia_error;
} gp_fv3d_grain;

/* The grains' descriptors in summary (with GP_OUT3_DESCRIPTORS): the 3D ones' mean and
 * standard deviation, the projections' 2D ones (elongation, roundness, circularity,
 * regularity) averaged per axis, and the same four averaged over 2D Fourier grains of the
 * spec's spectrum (GP_FV3D_REFERENCE_GRAINS contours of 128 points, random phases): what a 2D
 * specimen of that spectrum would show, for a user who compares with 2D images. A degree-n field
 * seen on a plane spreads its power to lower 2D modes (gp_grain3d.h), so the projections need
 * not match the reference; the elongation and flatness asked are beside the 3D means. */
#define GP_FV3D_REFERENCE_GRAINS 200
typedef struct gp_fv3d_descriptor_stats {
    int present;
    double mean[4], sd[4];     /* elongation, flatness, sphericity, convexity */
    double target_elongation, target_flatness;
    double projection[3][4];   /* along the long, intermediate, short axis */
    double reference2d[4];
} gp_fv3d_descriptor_stats;

typedef struct gp_fv3d_stats {
    gp_fit_area cell_volume, grain_volume;
    gp_fit_orient cell_orientation, grain_orientation; /* target_mean_deg unused (0) */
    gp_fit_passing passing;          /* a sieve law: by mass of the grains */
    double solid_fraction;           /* sum of grain volumes / container volume */
    size_t grains_short;             /* grains below their target volume */
    double imc_error, imc_error_initial;
    long imc_steps;
    int imc_stop;                    /* gp_imc_stop */
    double clump_volume_error_mean, clump_volume_error_max;
    double clump_inertia_error_mean, clump_inertia_error_max;
    double lost_volume;              /* the cylinder's facets against the true cylinder */
    gp_fv3d_descriptor_stats descriptors;
} gp_fv3d_stats;

typedef struct gp_fv3d_timings {
    double imc, grains, fill, descriptors, clumps, stats, total;
} gp_fv3d_timings;

typedef struct gp_fv3d gp_fv3d;

/* Builds the specimen. GP_OK, or GP_ERR_INVALID (a spec field, named), GP_ERR_NOMEM,
 * GP_ERR_CANCELLED (*cancel raised or progress returned non-zero), GP_ERR_NOT_STAR (a spectrum
 * no grain can follow). An IMC that stops short of its threshold still gives a specimen (its
 * stats say so). */
gp_status gp_fv3d_build(const gp_fv3d_spec *spec, gp_progress_fn progress, void *user,
                        const volatile int *cancel, gp_fv3d **out, gp_error *err);
void gp_fv3d_destroy(gp_fv3d *s);

/* Bytes a build of this spec holds at its peak (its radii, clumps and tessellation), before
 * it runs. */
double gp_fv3d_estimate_bytes(const gp_fv3d_spec *spec);

size_t gp_fv3d_count(const gp_fv3d *s);
const gp_voronoi3d *gp_fv3d_cells(const gp_fv3d *s);
const gp_fv3d_grain *gp_fv3d_grain_at(const gp_fv3d *s, size_t i);
/* the shared icosphere: directions (3 a vertex) and triangles (3 a triangle) */
size_t gp_fv3d_directions(const gp_fv3d *s, const double **xyz);
size_t gp_fv3d_triangles(const gp_fv3d *s, const uint32_t **tri);
const gp_fv3d_stats *gp_fv3d_stats_of(const gp_fv3d *s);
const gp_fv3d_timings *gp_fv3d_timings_of(const gp_fv3d *s);

/* The vertices of grain i as placed: xyz[3 k ..] = centre + scale R (radii[k] direction[k]);
 * xyz holds 3 x the direction count. */
void gp_fv3d_grain_vertices(const gp_fv3d *s, size_t i, double *xyz);

#endif /* GP_FV3D_H */
