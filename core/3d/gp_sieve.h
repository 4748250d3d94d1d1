/* gp_sieve.h -- sieve curves (percent passing by weight) -> sphere diameters.
 *
 * Dang & Meguid (2010) Eq. 9 converts the sieve analysis to percent passing by number and draws
 * diameters uniformly inside a bin. NOTES.md: the paper's printed number column uses the cube of
 * the mid-bin diameter, while uniform draws have a larger mean cube, so the drawn curve misses
 * the weight target. Here:
 *   - gp_sieve_weight_to_number() gives both conversions (GP_SIEVE_MIDBIN reproduces Table 2,
 *     GP_SIEVE_UNIFORM is the exact one for uniform-in-bin draws);
 *   - gp_sieve_draw() fills a solid volume by quota: the number of grains per bin follows from
 *     the bin's weight share of the volume (largest-remainder rounding), the diameters are
 *     stratified inside the bin, and a monotone in-bin warp makes each bin's volume equal to its
 *     share, so the curve by weight is met at every sieve and the few largest grains are not
 *     left to chance.
 * Diameters and volumes in any consistent unit; percentages in [0, 100].
 * Ownership and thread safety: inputs are only read, outputs are the caller's; no state, so
 * concurrent calls are safe given one gp_rng per thread.
 */
#ifndef GP_SIEVE_H
#define GP_SIEVE_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_rng.h"

typedef enum { GP_SIEVE_MIDBIN = 0, GP_SIEVE_UNIFORM = 1 } gp_sieve_rule;

/* A curve is n >= 2 rows (d[k], pw[k]): d strictly increasing and > 0, pw non-decreasing in
 * [0, 100], pw[0] == 0 and pw[n-1] == 100 (within 1e-9). */
gp_status gp_sieve_validate(const double *d, const double *pw, size_t n, gp_error *err);

/* Percent passing by number at each sieve (pn[n]), for diameters that are the bin's mid
 * diameter (MIDBIN) or uniform in the bin (UNIFORM). */
gp_status gp_sieve_weight_to_number(const double *d, const double *pw, size_t n,
                                    gp_sieve_rule rule, double *pn, gp_error *err);

/* Expected number of grains that fill solid_volume (sphere volumes) with uniform-in-bin draws. */
double gp_sieve_expected_count(const double *d, const double *pw, size_t n, double solid_volume);

/* Draws diameters whose total sphere volume is solid_volume and whose curve by weight matches
 * pw (see above). *diam (malloc'ed, sorted by bin from the finest, caller frees) holds *count
 * diameters. Fails with GP_ERR_INVALID when more than max_count grains would be needed. */
gp_status gp_sieve_draw(const double *d, const double *pw, size_t n, double solid_volume,
                        size_t max_count, gp_rng *rng, double **diam, size_t *count,
                        gp_error *err);

/* Measured percent passing (grains with diameter < d[k]) by weight (pw_out) and by number
 * (pn_out) at each sieve; either output may be NULL. */
void gp_sieve_passing(const double *diam, size_t count, const double *d, size_t n,
                      double *pw_out, double *pn_out);

#endif /* GP_SIEVE_H */
