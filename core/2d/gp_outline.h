/* gp_outline.h -- the Fourier spectrum of real grain outlines (api.md "2D shape"): Mollon &
 * Zhao 2012, Sec. 2.2 (Eqs. 5-9) run in the analysis direction, on outlines measured on real
 * grains (traced images, digitised contours), one outline or a set of them.
 *
 * Algorithm, for one outline (a closed polygon, vertices in order, implicitly closed):
 *  1. Clean: non-finite vertices are refused; consecutive repeated points and the closing
 *     duplicate (last == first) are dropped (GP_OUTLINE_DEDUPED); fewer than 3 distinct points
 *     is refused (GP_ERR_INVALID), a polygon without area too (GP_ERR_DEGENERATE, the test of
 *     gp_poly_centroid); a clockwise outline (negative signed area) is reversed
 *     (GP_OUTLINE_REVERSED). All later steps work in coordinates relative to the bounding-box
 *     centre, so an outline far from the origin keeps its precision.
 *  2. Pole (the paper's centre O: "all the half-lines arising from O cross the particle contour
 *     exactly one time"). The polygon is star-shaped from a point p iff p lies in its kernel,
 *     the intersection of the inner half-planes of its edges. We need p strictly inside every
 *     one (then r(theta) is continuous and > 0), decided exactly with gp_orient2d:
 *      - the area centroid, if it passes (the paper's choice; then D_1 = O(D^2), ~0);
 *      - else the centroid of the kernel, computed by half-plane intersection (sorted by edge
 *        direction, a deque; O(V log V)) and verified with the same exact test; flagged
 *        GP_OUTLINE_POLE_MOVED. Why the kernel's centroid and not its Chebyshev centre (largest
 *        inscribed circle): it is unique and moves continuously with the outline (the Chebyshev
 *        centre of a rectangular kernel is any point of a segment, and jumps between
 *        candidates), it is strictly interior for any kernel with area, and it needs no
 *        iteration or tolerance;
 *      - an empty kernel (or one without area, or too thin for its centroid to pass the exact
 *        test) means no interior point sees the whole outline: refused, GP_ERR_NOT_STAR.
 *     A pole that sees every edge from its inner side still sees a self-intersecting outline
 *     that winds k > 1 times round it (a pentagram): the winding is checked and such an
 *     outline refused (GP_ERR_INVALID). Passing both tests means the polygon is simple and
 *     star-shaped from the pole.
 *     What D_1 means: moving the centre by e changes r by e cos(theta - phi) to first order, so
 *     D_1 ~ |e| / r0 measures how far the pole is from the point that makes D_1 vanish (close
 *     to the centroid). About the centroid D_1 is second order in the D_n (mean 0.005 for
 *     grains of D2 = 0.1, D3 = 0.05, D8 = 0.02); about a moved pole it grows with the
 *     pole-to-centroid distance over r0 (reported as pole_offset; equal to first order; the
 *     thin L of the tests has D_1 = 0.71 at an offset of 1.05 r0). D_1 is kept in the
 *     spectrum (the API's [D0, D1, ...]) but is not a shape descriptor: fed back to the
 *     generator it only shifts a grain about its centre (gp_fourier_spectrum sets D_1 = 0).
 *  3. Radii r_i = r(theta_i), theta_i = 2 pi i / np, exactly (up to rounding) on the polygon:
 *     the vertices' polar angles about the pole increase monotonically (step 2), so one merge
 *     walk over vertices and rays finds each ray's edge: O(V + np)
 *     (gp_outline_star_radii). gp_fourier_polygon_radii gives the same numbers (it is exact
 *     per ray, but O(np V) and it checks star-shape only along the sampled rays); the tests
 *     compare the two.
 *  4. Spectrum: gp_fourier_analyse (FFTW) on the np radii: r0, D_0 = 1, D_1 .. D_{nmodes-1},
 *     phases; the convention of gp_fourier.h, so that analysing a generated grain returns its
 *     own spectrum. Modes kept: nmodes <= gp_fourier_max_modes(np) (64 at the paper's
 *     np = 128). r(theta) of a real outline has content above np/2 (corners, pixel steps) that
 *     aliases into the top modes; np > 2 nmodes (e.g. np = 512, nmodes = 64) reduces that,
 *     D_n being normalised independently of np.
 *  5. Descriptors (optional): the four descriptors of gp_shape.h measured as the specimen
 *     measures its grains: gp_shape_describe_fourier on the outline's Fourier grain (the curve
 *     r(theta) = r0 (1 + sum D_n cos(n theta - delta_n)) about the pole, nmodes modes, an
 *     np-point contour, default ODEC parameters, perimeters at >= 512 points). So a specimen
 *     made from the measured spectrum is compared like with like, pixel staircases above the
 *     kept modes do not enter the regularity, and the work per outline does not grow with its
 *     vertex count. If the truncated curve is not star-shaped (r <= 0 at some angle: possible
 *     only for a pole very near the outline), the outline keeps its spectrum and is flagged
 *     GP_OUTLINE_NO_DESCRIPTORS.
 *
 * A set (gp_outline_set_analyze): every outline as above; the mean spectrum, the sample
 * standard deviation and the coefficient of variation (sd / mean) of each D_n across the
 * analysed outlines, the descriptors' means and sds, and per outline its flags. Refused
 * outlines: the set is analysed without them and they are reported by index (ascending) with
 * their reason, so a few bad outlines among hundreds cost the user nothing but are never
 * silently distorted; the call fails (GP_ERR_INFEASIBLE) only if fewer than min_outlines
 * (default 10, the API's minimum) remain, and then still returns the per-outline report.
 *
 * Invariants of a result: for analysed outlines D_0 = 1, D_n >= 0, r0 > 0, the pole strictly
 * inside the kernel; info.flags & GP_OUTLINE_REFUSED <=> info.error.code is the refusal.
 * Work: O(V + np log np) per outline (+ O(V log V) when the kernel is needed, + O(np^2) for
 * the descriptors' ODEC), so O(n np log np + total vertices) for a set; the descriptors cost
 * what the specimen's own grains cost (gp_shape_describe_fourier) and dominate
 * (docs/design/shape.md).
 * Ownership: a gp_outline (workspace: an FFTW plan for np and scratch growing with the largest
 * outline seen) is the caller's, freed with gp_outline_destroy; a set result owns its arrays,
 * freed with gp_outline_set_result_free. Threads: a gp_outline is used by one thread at a time
 * (one per thread); the set call makes its own, so concurrent set calls are safe. The pure
 * functions (clean, kernel, star_radii) keep no state.
 */
#ifndef GP_OUTLINE_H
#define GP_OUTLINE_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_progress.h"
#include "gp_geom.h"

/* info.flags */
#define GP_OUTLINE_REVERSED 1u        /* given clockwise; analysed reversed */
#define GP_OUTLINE_DEDUPED 2u         /* repeated points or the closing duplicate dropped */
#define GP_OUTLINE_POLE_MOVED 4u      /* not star-shaped from its centroid: kernel centroid */
#define GP_OUTLINE_REFUSED 8u         /* not analysed; info.error says why */
#define GP_OUTLINE_NO_DESCRIPTORS 16u /* analysed, but its Fourier grain could not be described */

typedef struct gp_outline_params {
    size_t np;           /* rays, >= GP_FOURIER_NP_MIN (default 128, the paper's) */
    size_t nmodes;       /* D_0 .. D_{nmodes-1}, 2 <= nmodes <= gp_fourier_max_modes(np)
                          * (default 64) */
    int descriptors;     /* 1 (default): describe each outline (step 5); 0: skip */
    size_t min_outlines; /* a set needs this many analysed outlines (default 10), >= 1 */
    /* gp_outline_set_analyze reports phase "shape" every GP_OUTLINE_REPORT_EVERY outlines
     * (phase_fraction = outlines done / n) when progress is not NULL: 10,000 outlines take
     * seconds, and a job's progress would stand still meanwhile. A non-zero return cancels. */
    gp_progress_fn progress;
    void *progress_user;
} gp_outline_params;

#define GP_OUTLINE_REPORT_EVERY 64

void gp_outline_params_defaults(gp_outline_params *p);

/* What happened to one outline. Coordinates are the input's. */
typedef struct gp_outline_info {
    unsigned flags;
    gp_error error;         /* the refusal (REFUSED), or why no descriptors (NO_DESCRIPTORS);
                             * GP_OK otherwise */
    size_t nvertices;       /* after cleaning */
    size_t ndropped;        /* points dropped by cleaning */
    double area;            /* > 0 */
    gp_vec2 centroid;       /* area centroid */
    gp_vec2 pole;           /* the rays' centre: centroid, or the kernel's centroid */
    double pole_offset;     /* |pole - centroid| / r0 */
    double kernel_fraction; /* kernel area / area when the kernel was computed, else 0 */
    double r0;              /* mean radius about the pole */
    /* descriptors of the outline's Fourier grain (0 without them) */
    double elongation, orientation_deg, roundness, circularity, regularity;
} gp_outline_info;

/* One outline of a set: n points (not owned). */
typedef struct gp_outline_points {
    const gp_vec2 *pts;
    size_t n;
} gp_outline_points;

typedef struct gp_outline_stat {
    double mean, sd; /* sd: sample standard deviation (n - 1); 0 for fewer than 2 values */
} gp_outline_stat;

typedef struct gp_outline_set_result {
    size_t n;          /* outlines given */
    size_t nanalysed;  /* outlines in the spectrum statistics */
    size_t ndescribed; /* outlines in the descriptor statistics */
    size_t nmodes;
    double *mean;      /* nmodes: mean D_n (mean[0] = 1) */
    double *sd;        /* nmodes: sample sd of D_n */
    double *cov;       /* nmodes: sd / mean (0 where the mean is 0) */
    double *spectra;   /* n * nmodes: row i = D of outline i (zeros if refused) */
    gp_outline_stat elongation, roundness, circularity, regularity;
    gp_outline_info *info; /* n */
    size_t *refused;       /* nrefused indices into the input, ascending */
    size_t nrefused;
    size_t nreversed, npole_moved, ndeduped;
} gp_outline_set_result;

typedef struct gp_outline gp_outline;

/* Workspace for p (NULL = defaults); NULL on failure (err says why). */
gp_outline *gp_outline_create(const gp_outline_params *p, gp_error *err);
void gp_outline_destroy(gp_outline *o); /* NULL is fine */

/* Analyses one outline (steps 1-5): D (nmodes) and delta (nmodes, may be NULL) receive the
 * spectrum and phases, info (required) what happened. An outline that cannot be analysed
 * returns its refusal code (GP_ERR_INVALID, GP_ERR_DEGENERATE, GP_ERR_NOT_STAR) with
 * GP_OUTLINE_REFUSED in info->flags and D zeroed; GP_ERR_NOMEM is not a refusal. */
gp_status gp_outline_analyze(gp_outline *o, const gp_vec2 *pts, size_t n, double *D,
                             double *delta, gp_outline_info *info, gp_error *err);

/* The set analysis described above. p may be NULL (defaults); cancel (may be NULL) is polled
 * once per outline (GP_ERR_CANCELLED). GP_ERR_INVALID for bad arguments (n == 0, NULL
 * outlines); GP_ERR_INFEASIBLE when fewer than p->min_outlines outlines were analysed: then
 * res holds info, refused and the counts (statistics zero) -- free it either way. On other
 * errors res is zeroed. */
gp_status gp_outline_set_analyze(const gp_outline_points *outlines, size_t n,
                                 const gp_outline_params *p, const volatile int *cancel,
                                 gp_outline_set_result *res, gp_error *err);

void gp_outline_set_result_free(gp_outline_set_result *res); /* zeroes it; NULL is fine */

/* Step 1 on its own: writes the cleaned outline, counter-clockwise, to out (capacity n; may be
 * pts itself) and its length to *nout; *flags (may be NULL) gets GP_OUTLINE_REVERSED /
 * GP_OUTLINE_DEDUPED. GP_ERR_INVALID / GP_ERR_DEGENERATE as above. */
gp_status gp_outline_clean(const gp_vec2 *pts, size_t n, gp_vec2 *out, size_t *nout,
                           unsigned *flags, gp_error *err);

/* The kernel of a counter-clockwise polygon (n >= 3, no repeated consecutive points): the
 * convex polygon, counter-clockwise, written to kernel (capacity n + 4), *nk vertices (0 when
 * it is empty or has no area, up to about 1e-12 of the polygon's size). Allocates scratch
 * (freed before returning); GP_ERR_NOMEM, GP_ERR_INVALID. O(n log n). */
gp_status gp_outline_kernel(const gp_vec2 *poly, size_t n, gp_vec2 *kernel, size_t *nk,
                            gp_error *err);

/* r[i] = distance from pole to the boundary along theta_i = 2 pi i / np, for a
 * counter-clockwise polygon strictly star-shaped from pole (each edge strictly left of it,
 * winding once). GP_ERR_NOT_STAR if an edge does not pass that exact test, GP_ERR_INVALID if
 * the polygon winds more than once or for bad arguments. O(n + np), no allocation. */
gp_status gp_outline_star_radii(const gp_vec2 *poly, size_t n, gp_vec2 pole, size_t np,
                                double *r, gp_error *err);

#endif /* GP_OUTLINE_H */
