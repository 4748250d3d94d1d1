/* gp_specimen2d.h -- one call from a validated 2D spec to a complete Fourier-Voronoi specimen.
 *
 * This is the integration point of the 2D pipeline (Mollon & Zhao 2012): container ->
 * tessellation -> IMC -> filling -> ODEC -> descriptors. It computes only the outputs the spec
 * lists (model only what a scene needs). The schema/ parser fills gp_spec2d from JSON; the
 * service calls gp_specimen2d_build() on a worker thread and serialises the result.
 *
 * Size laws (api.md "2D size laws", gp_law.h). With size.of = "cells" (the paper) the IMC
 * shapes the cells to the law and every grain is filled to solid_fraction of its cell, so the
 * grains follow the law scaled by solid_fraction where the fill reaches it (the paper's §5
 * warns that grains that cannot be filled shift the grain sizes left; the fit report shows by
 * how much). With size.of = "grains", and always for a sieve curve (which is a law of grains),
 * the grains themselves follow the law:
 *   1. the cells follow the grain law scaled to the cells' mean (container area / N), so that
 *      a cell filled to solid_fraction holds a grain of about the right size;
 *   2. pass A fills every cell up to solid_fraction x 1.2 (GRAIN_LAW_HEADROOM), giving each
 *      cell the largest grain it can hold up to that;
 *   3. cells sized for their grains: small cells hold less of themselves than large ones
 *      (fewer sides), so with step 1's cells the smallest grains fall short, by a KS distance
 *      that does not shrink with N while its critical value does (docs/design/specimen2d.md).
 *      When the grains step 4 would make from pass A miss the law by more than half the
 *      critical value (by number, or by mass), the cell law is drawn together
 *      (gp_law_powered: lam A^kappa, the same mean) by the kappa that pass A's own cells
 *      predict best (each keeps its rank and the fraction of itself it held), the IMC runs
 *      again from the seeds it ended on (both runs within max_steps), and pass A fills the
 *      new cells (cell_law_power; once);
 *   4. rank matching: the k-th smallest of those grains is given the k-th smallest of the
 *      grain law's N quantiles at (2k - 1) / 2N, and shrunk about its centre to that area
 *      (every contour point moves along its own ray, so it stays in its cell, and shape and
 *      orientation are kept). Sorted matching is the assignment that asks least of every
 *      cell; a grain that cannot reach its quantile keeps its largest size;
 *   5. pass B builds ODEC and descriptors on the final grains.
 * The number of grains of a sieve law follows from the container: N = round(solid_fraction x
 * area / mean grain area of the law) (gp_spec2d_cell_count).
 *
 * Shape (api.md "2D shape"). The grains' mean spectrum comes from the spec's shape
 * form: D2/D3/D8 with alpha, beta (Eqs. 10-12), a spectrum as given, target mean descriptors
 * (gp_shapemap_fit, then calibrated on the specimen's own filled grains: gp_specimen2d.c,
 * "descriptors calibration"), or outlines (gp_outline_set_analyze: their mean spectrum at
 * contour_points rays and contour_points / 2 modes, D_1 kept). With a spread, or with outlines
 * whose own per-mode cov is the default spread, every grain draws its own amplitudes around the
 * mean (gp_grainshape.h: lognormal per mode, stream 2^62 + i, redrawn while not star-shaped)
 * and is filled and described with them. No spread (or 0) is the paper's setting: every grain
 * has the mean spectrum, and nothing is drawn for it. The result's stats.shape is out->shape
 * (gp_shape_used).
 *
 * Fit and warnings. Every result carries stats.fit (gp_fit.h), measured on the cells and
 * grains themselves, and a list of warnings: each target not reached (IMC threshold, a KS
 * distance above its 5 % critical value, a sieve missed by more than 3 points, a solid
 * fraction more than 2 % short), with how close it came. A run that stops short is a valid
 * specimen that says so, never a failed job.
 */
#ifndef GP_SPECIMEN2D_H
#define GP_SPECIMEN2D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_geom.h"
#include "gp_fit.h"
#include "gp_law.h"
#include "gp_progress.h"

/* outputs (bit flags) */
enum {
    GP_OUT2_GRAINS = 1u << 0,
    GP_OUT2_ODEC = 1u << 1,
    GP_OUT2_DESCRIPTORS = 1u << 2,
    GP_OUT2_CELLS = 1u << 3
};

typedef enum { GP_CONTAINER_POLYGON = 0, GP_CONTAINER_CIRCLE = 1 } gp_container_kind;
/* GP_IMC_AD: the Anderson-Darling objective on the whole laws (the default, gp_imc.h); E1-E3:
 * the paper's histogram errors (Eqs. 16-18), kept to reproduce it. */
typedef enum { GP_IMC_E1 = 1, GP_IMC_E2 = 2, GP_IMC_E3 = 3, GP_IMC_AD = 4 } gp_imc_error_kind;
typedef enum { GP_INIT_UNIFORM = 0, GP_INIT_HALTON = 1 } gp_init_kind;

typedef struct gp_ring {
    gp_vec2 *pts;
    size_t n;
} gp_ring;

/* The form of shape (api.md "2D shape"): D2/D3/D8 with alpha, beta (Eqs. 10-12); a full
 * spectrum; target mean descriptors (gp_shapemap.h); or real grain outlines (gp_outline.h). */
typedef enum {
    GP_SHAPE_FORM_D = 0,
    GP_SHAPE_FORM_SPECTRUM = 1,
    GP_SHAPE_FORM_DESCRIPTORS = 2,
    GP_SHAPE_FORM_OUTLINES = 3
} gp_shape_form;

/* shape.spread is a coefficient of variation of each D_n from grain to grain, at most this:
 * beyond 1 a lognormal law's typical grain (its median, mean / sqrt(1 + cov^2)) drifts far
 * below the mean and its heavy tail makes grains that are not star-shaped common, so the
 * redraws (gp_grainshape.h) would cut the asked spread down instead of giving it. */
#define GP_SHAPE_SPREAD_MAX 1.0
/* shape.outlines: at least 10 outlines (api.md; the schema also bounds them at 10,000) */
#define GP_SHAPE_OUTLINES_MIN 10

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
    size_t particles;           /* 0 with a sieve law: derived (gp_spec2d_cell_count) */
    gp_law_kind size_law;       /* size.law */
    double cov;                 /* size.cov (parametric laws) */
    const double *sieve_d;      /* size.sieve diameters, in container length units (the parser
                                 * converts from size.sieve_units) */
    const double *sieve_pass;   /* size.sieve percent passing by mass */
    size_t nsieve;
    int size_of_grains;         /* size.of: 0 "cells" (the paper), 1 "grains" */
    double mean_deg;            /* orientation.mean_deg */
    double anisotropy;          /* orientation.anisotropy (min/max ratio, in (0, 1]) */
    int has_spectrum;           /* shape.spectrum given in full (it wins over shape_form) */
    double D2, D3, D8, alpha, beta;
    const double *spectrum;     /* D0, D1, D2, ... when has_spectrum */
    size_t nspectrum;
    gp_shape_form shape_form;   /* GP_SHAPE_FORM_D (0, the default) unless given otherwise */
    unsigned desc_given;        /* descriptors: bit k (GP_SHAPEMAP_BIT) for each asked one */
    double desc_target[4];      /* the asked means: elongation, roundness, circularity,
                                 * regularity (the order of gp_descriptors) */
    const gp_ring *outlines;    /* outlines: noutlines outlines, vertices in order */
    size_t noutlines;
    double spread;              /* shape.spread in [0, GP_SHAPE_SPREAD_MAX]; 0 = the paper */
    int spread_given;           /* shape.spread was given: with outlines it replaces the set's
                                 * own per-mode spread (0 then means every grain the mean);
                                 * a spread > 0 counts as given */
    double solid_fraction;
    gp_imc_error_kind imc_error;
    double imc_threshold;
    long imc_max_steps;         /* the budget of both IMC runs of a grain law together */
    int imc_max_steps_default;  /* imc_max_steps is the API's default for the cell count (the
                                 * spec left it out; set by the service's parser, which
                                 * resolves it), not the user's: the warnings say so */
    gp_init_kind imc_init;
    int imc_classes;            /* histogram classes; 0 = automatic (see gp_imc.h) */
    size_t contour_points;
    unsigned outputs;           /* GP_OUT2_* */
    int threads;                /* threads for the IMC steps and the filling; 0 = 1 */
} gp_spec2d;

/* Fills a spec with the API defaults (unit square, 100 particles, lognormal cov 0.5 on cells,
 * isotropic, D2 0.1, D3 0.05, D8 0.02, alpha = beta = -2, F_S 0.65, AD with its default
 * threshold (gp_imc_default_threshold), 1e6 steps (the default for its 100 cells), uniform,
 * 128 points, outputs grains). */
void gp_spec2d_defaults(gp_spec2d *spec);

/* The default imc.max_steps for N cells: max(GP_IMC_DEFAULT_STEPS_MIN,
 * GP_IMC_DEFAULT_STEPS_PER_CELL x N), so that both IMC runs of a grain law (the cells' law,
 * then the cells resized for their grains) reach their threshold before it at any N up to
 * 10^6 (docs/method-2d.md, "Stopping"). A function of N alone: the same spec gives the same
 * budget on any machine and thread count. The service clips it to its work budget
 * (schema/kinds/fourier-voronoi-2d/gp_spec2d.c), never below the minimum. */
#define GP_IMC_DEFAULT_STEPS_MIN 1000000L
#define GP_IMC_DEFAULT_STEPS_PER_CELL 12
long gp_spec2d_default_max_steps(size_t cells);

/* The container's area (polygon minus holes, or the circle's polygon as the tessellation uses
 * it) and the number of cells the spec asks for: `particles`, or for a sieve law
 * round(solid_fraction * area / mean grain area), at least 1. Fails (GP_ERR_INVALID with a
 * message) on a bad container or law. Cheap: the service calls it at submit. */
gp_status gp_spec2d_cell_count(const gp_spec2d *spec, double *area, size_t *count,
                               gp_error *err);

/* The laws a spec asks for, both by number of grains/cells: `cells` is the law of the cell
 * areas the IMC aims at, `grains` the law of the grain areas (the cell law scaled by
 * solid_fraction, or the law as given with size.of = "grains" or a sieve). Caller destroys
 * both. */
gp_status gp_spec2d_laws(const gp_spec2d *spec, gp_law **cells, gp_law **grains,
                         gp_error *err);

/* A histogram: nclasses classes [edges[k], edges[k+1]), target and achieved normalised by the
 * number of items (so each sums to ~1). */
typedef struct gp_hist {
    size_t nclasses;
    double *edges;              /* nclasses + 1 */
    double *target;             /* nclasses, NULL where there is no target */
    double *achieved;           /* nclasses */
} gp_hist;

/* the parts (gp_fit_area, gp_fit_orient, gp_fit_passing) are declared in gp_fit.h */
typedef struct gp_fit2d {
    gp_fit_area cell_area, grain_area;
    gp_fit_orient cell_orientation, grain_orientation;
    gp_fit_passing passing;
} gp_fit2d;

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
    gp_descriptors descriptors; /* valid with GP_OUT2_DESCRIPTORS */
    double *discs;              /* ndiscs * 3: x, y, r (with GP_OUT2_ODEC) */
    size_t ndiscs;
} gp_grain2d;

typedef struct gp_cell2d {
    gp_vec2 seed;
    gp_ring *polygons;          /* the parts of the cell (more than one only in non-convex containers) */
    size_t npolygons;
    double area;
    double orientation_deg;
} gp_cell2d;

/* The shape the grains were given, for the result: stats.shape and
 * stats.descriptors.<name>.target. Grain g's own amplitudes are drawn around `spectrum` with
 * the per-mode coefficients of variation `cov` (gp_grainshape.h). */
typedef struct gp_shape_used {
    gp_shape_form form;
    size_t nmodes;              /* length of spectrum and cov (contour_points / 2) */
    double *spectrum;           /* the mean spectrum used: D_0 = 1, D_1, ... */
    double *cov;                /* per-mode spread used; NULL when every grain has the mean */
    double spread;              /* shape.spread as used (0 when none); with outlines and no
                                 * spread given, cov[] is the set's own and this is its
                                 * summary: sum_{n>=2} D_n cov_n / sum_{n>=2} D_n */
    int spread_from_outlines;   /* cov[] is the outlines' measured cov (capped at 1) */
    double D2, D3, D8, alpha, beta; /* forms D and descriptors (fitted); spectrum and outlines:
                                 * D2, D3, D8 read off the mean spectrum, alpha = beta = NaN */
    unsigned targets;           /* bits of target[] that are set: descriptors, the asked ones;
                                 * outlines, all four (the outlines' own means) */
    double target[4];           /* descriptors: asked means; outlines: the outlines' means */
    double target_sd[4];        /* outlines: the outlines' sds (0 otherwise) */
    double predicted[4];        /* descriptors: the means gp_shapemap_fit's sampled grains had
                                 * at its spectrum (before the calibration below) */
    double calibrated[4];       /* descriptors: the means measured on the filled calibration
                                 * grains at the spectrum used (0 without calibration) */
    size_t calibration_grains;  /* grains behind calibrated[] (0: not calibrated) */
    int calibration_rounds;     /* filled-and-measured rounds spent (0, 1 or 2) */
    int fit_evaluations;        /* descriptors: gp_shapemap_fit's sampled evaluations */
    unsigned missed;            /* descriptors: bits of targets the calibration (or the fit,
                                 * without one) left outside their tolerance */
    size_t noutlines;           /* outlines given, and those analysed (all, or the run fails) */
    size_t noutlines_analysed;
    size_t grains_redrawn;      /* spread: grains whose first draw was not star-shaped */
    size_t grains_clipped;      /* ... those still not after GP_GRAINSHAPE_TRIES draws (pulled
                                 * toward the mean), or whose own spectrum the fill found no
                                 * star-shaped phases for (given the mean); warned */
} gp_shape_used;

typedef struct gp_specimen2d {
    gp_grain2d *grains;
    size_t ngrains;
    gp_cell2d *cells;           /* with GP_OUT2_CELLS */
    size_t ncells;
    /* stats */
    double container_area;
    double imc_error;
    long imc_steps;
    const char *imc_stop_reason;/* static string: "threshold", "max_steps", "floor", ... */
    double imc_error_floor;     /* E1-E3: the integer-count floor of the chosen classes (NOTES.md);
                                 * AD: 0 (the error is the excess over N's least A^2) */
    double imc_threshold;       /* the threshold used */
    double cell_law_power;      /* a grain law: the power kappa the cell law was drawn together
                                 * by before the IMC ran again (1: it was not; resize_cells in
                                 * gp_specimen2d.c); imc_steps and the IMC's times then count
                                 * both runs */
    int cells_resize_blocked;   /* a grain law would have resized its cells, but the first IMC
                                 * run used all of imc_max_steps (warned) */
    int imc_runs;               /* IMC runs made: 1, or 2 when the cells of a grain law were
                                 * resized for their grains */
    long imc_steps_resize;      /* of imc_steps, those of the second run (0 without one) */
    double grain_law_miss;      /* a grain law: how far pass A's grains, matched to the law's
                                 * quantiles, missed it (the KS distance by number or by mass,
                                 * the larger), which decided the resize; 0 otherwise */
    const char *imc_error_kind; /* "AD", "E1", "E2", "E3" */
    size_t imc_wall_ties;       /* AD: cells whose orientation is a container edge's direction,
                                 * shared with another (gp_imc_report.wall_ties) */
    double imc_error_ties;      /* AD: their share of the error (half their term: the
                                 * orientations count half) */
    int imc_at_goals;           /* AD: stalled with the cells within the KS goals the default
                                 * threshold stands for (gp_imc_report.at_goals) */
    gp_fit2d fit;               /* measured on the cells and grains themselves */
    char **warnings;            /* nwarnings one-line messages: a target not reached, and how
                                 * close it came (IMC threshold, fit beyond its KS critical
                                 * value, cells short of solid_fraction) */
    size_t nwarnings;
    double solid_fraction;      /* total grain area / container area */
    size_t cells_target_met;
    double mean_orientation_gap_deg; /* mean |theta_grain - theta_cell| (pi-periodic) */
    gp_hist size_hist;          /* cell areas: target lognormal vs achieved (cells) */
    gp_hist grain_size_hist;    /* grain areas, same classes scaled by solid_fraction */
    gp_hist orientation_hist;   /* cells: degrees in [-90, 90), target cosine law vs achieved */
    gp_hist grain_orientation_hist; /* grains, same classes and target */
    gp_descriptors descriptor_mean; /* with GP_OUT2_DESCRIPTORS */
    gp_descriptors descriptor_sd;   /* their standard deviations (n - 1) over the grains */
    gp_shape_used shape;        /* the spectrum and spread used, the targets (always set) */
    gp_hist descriptor_hist[4]; /* elongation, roundness, circularity, regularity */
    /* timings, seconds; t_shape: the shape's setup (descriptor fit or outlines' analysis)
     * and the descriptors' calibration, which the others then leave out */
    double t_tessellation, t_imc, t_fill, t_odec, t_descriptors, t_shape, t_total;
} gp_specimen2d;

/* The descriptors' calibration fills and describes at most this many of the cells, once or
 * twice (a caller's cost estimate needs it). */
#define GP_SPECIMEN2D_CALIBRATION_CELLS 500

/* Builds the specimen. Returns GP_OK, or an error with a message (GP_ERR_CANCELLED when the
 * progress callback or *cancel asked to stop). On success *out owns everything and is freed
 * with gp_specimen2d_destroy(). cancel may be NULL. The same spec and seed give the same
 * specimen bit for bit whatever spec->threads is. */
gp_status gp_specimen2d_build(const gp_spec2d *spec, gp_progress_fn progress, void *user,
                              const volatile int *cancel, gp_specimen2d **out, gp_error *err);

void gp_specimen2d_destroy(gp_specimen2d *s);

#endif /* GP_SPECIMEN2D_H */
