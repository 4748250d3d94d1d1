/* gp_specimen2d.h -- one call from a validated 2D spec to a complete Fourier-Voronoi specimen.
 *
 * This is the integration point of the 2D pipeline (Mollon & Zhao 2012): container ->
 * tessellation -> IMC -> filling -> ODEC -> descriptors. It computes only the outputs the spec
 * lists (model only what a scene needs). The schema/ parser fills gp_spec2d from JSON; the
 * service calls gp_specimen2d_build() on a worker thread and serialises the result.
 */
#ifndef GP_SPECIMEN2D_H
#define GP_SPECIMEN2D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_geom.h"

/* outputs (bit flags) */
enum {
    GP_OUT_GRAINS = 1u << 0,
    GP_OUT_ODEC = 1u << 1,
    GP_OUT_DESCRIPTORS = 1u << 2,
    GP_OUT_CELLS = 1u << 3
};

typedef enum { GP_CONTAINER_POLYGON = 0, GP_CONTAINER_CIRCLE = 1 } gp_container_kind;
typedef enum { GP_IMC_E1 = 1, GP_IMC_E2 = 2, GP_IMC_E3 = 3 } gp_imc_error_kind;
typedef enum { GP_INIT_UNIFORM = 0, GP_INIT_HALTON = 1 } gp_init_kind;

typedef struct gp_ring {
    gp_vec2 *pts;
    size_t n;
} gp_ring;

/* The spec of kind "fourier-voronoi-2d" (names as in shared/spec/api.md). The caller owns all
 * arrays; gp_specimen2d_build() only reads them. */
typedef struct gp_spec2d {
    uint64_t seed;
    gp_container_kind container;
    gp_ring outer;              /* container.polygon */
    gp_ring *holes;             /* container.holes */
    size_t nholes;
    gp_vec2 circle_center;      /* container.circle */
    double circle_radius;
    size_t particles;
    double cov;                 /* size.cov */
    double mean_deg;            /* orientation.mean_deg */
    double anisotropy;          /* orientation.anisotropy (min/max ratio, in (0, 1]) */
    int has_spectrum;           /* shape.spectrum given in full */
    double D2, D3, D8, alpha, beta;
    const double *spectrum;     /* D0, D1, D2, ... when has_spectrum */
    size_t nspectrum;
    double solid_fraction;
    gp_imc_error_kind imc_error;
    double imc_threshold;
    long imc_max_steps;
    gp_init_kind imc_init;
    int imc_classes;            /* histogram classes; 0 = automatic (see gp_imc.h) */
    size_t contour_points;
    unsigned outputs;           /* GP_OUT_* */
    int threads;                /* worker threads for filling; 0 = 1 */
} gp_spec2d;

/* Fills a spec with the API defaults (unit square, 100 particles, cov 0.5, isotropic, D2 0.1,
 * D3 0.05, D8 0.02, alpha = beta = -2, F_S 0.65, E3 0.002, 1e6 steps, uniform, 128 points,
 * outputs grains). */
void gp_spec2d_defaults(gp_spec2d *spec);

/* A histogram: nclasses classes [edges[k], edges[k+1]), target and achieved normalised by the
 * number of items (so each sums to ~1). */
typedef struct gp_hist {
    size_t nclasses;
    double *edges;              /* nclasses + 1 */
    double *target;             /* nclasses, NULL where there is no target */
    double *achieved;           /* nclasses */
} gp_hist;

typedef struct gp_descriptors {
    double elongation, roundness, circularity, regularity;
} gp_descriptors;

typedef struct gp_grain2d {
    size_t cell;                /* index of the cell it fills */
    gp_vec2 *contour;           /* ncontour points, counter-clockwise */
    size_t ncontour;
    double area;
    double orientation_deg;
    double cell_fraction;       /* grain area / cell area */
    int target_met;             /* cell_fraction reached solid_fraction (within 1e-3) */
    gp_descriptors descriptors; /* valid with GP_OUT_DESCRIPTORS */
    double *discs;              /* ndiscs * 3: x, y, r (with GP_OUT_ODEC) */
    size_t ndiscs;
} gp_grain2d;

typedef struct gp_cell2d {
    gp_vec2 seed;
    gp_ring *polygons;          /* the parts of the cell (more than one only in non-convex containers) */
    size_t npolygons;
    double area;
    double orientation_deg;
} gp_cell2d;

typedef struct gp_specimen2d {
    gp_grain2d *grains;
    size_t ngrains;
    gp_cell2d *cells;           /* with GP_OUT_CELLS */
    size_t ncells;
    /* stats */
    double container_area;
    double imc_error;
    long imc_steps;
    const char *imc_stop_reason;/* static string: "threshold", "max_steps", "floor", ... */
    double imc_error_floor;     /* the integer-count floor of the chosen classes (NOTES.md) */
    double solid_fraction;      /* total grain area / container area */
    size_t cells_target_met;
    double mean_orientation_gap_deg; /* mean |theta_grain - theta_cell| (pi-periodic) */
    gp_hist size_hist;          /* cell areas: target lognormal vs achieved (cells) */
    gp_hist grain_size_hist;    /* grain areas, same classes scaled by solid_fraction */
    gp_hist orientation_hist;   /* cells: degrees in [-90, 90), target cosine law vs achieved */
    gp_hist grain_orientation_hist; /* grains, same classes and target */
    gp_descriptors descriptor_mean; /* with GP_OUT_DESCRIPTORS */
    gp_hist descriptor_hist[4]; /* elongation, roundness, circularity, regularity */
    /* timings, seconds */
    double t_tessellation, t_imc, t_fill, t_odec, t_descriptors, t_total;
} gp_specimen2d;

/* Progress report: phase ("tessellation", "imc", "fill", "odec", "descriptors"), fraction of
 * the whole job done in [0, 1], and the IMC step count and error where meaningful. */
typedef struct gp_progress {
    const char *phase;
    double fraction;
    long steps;
    double error;
} gp_progress;

/* Called at a bounded rate from the building thread; return non-zero to cancel. */
typedef int (*gp_progress_fn)(void *user, const gp_progress *p);

/* Builds the specimen. Returns GP_OK, or an error with a message (GP_ERR_CANCELLED when the
 * progress callback or *cancel asked to stop). On success *out owns everything and is freed
 * with gp_specimen2d_destroy(). cancel may be NULL. The same spec and seed give the same
 * specimen bit for bit whatever spec->threads is. */
gp_status gp_specimen2d_build(const gp_spec2d *spec, gp_progress_fn progress, void *user,
                              const volatile int *cancel, gp_specimen2d **out, gp_error *err);

void gp_specimen2d_destroy(gp_specimen2d *s);

#endif /* GP_SPECIMEN2D_H */
