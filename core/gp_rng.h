/* gp_rng.h -- reproducible, independent random streams, and Halton sequences.
 *
 * A stream is named by (seed, stream): the user's seed and an index the caller picks from the
 * work item (grain number, cell number, trial number...), never from a thread id or from the
 * order in which streams are created. The same (seed, stream) always gives the same sequence,
 * on every platform and whatever the thread count.
 *
 * Generator: MT19937 (Matsumoto & Nishimura 1998, the reference generator, identical to GSL's
 * gsl_rng_mt19937), seeded with the reference init_by_array() from a 128-bit key derived from
 * (seed, stream) by splitmix64:
 *     a = splitmix64(splitmix64(seed)),  b = splitmix64(splitmix64(a ^ splitmix64(stream)))
 *     key = { lo32(a), hi32(a), lo32(b), hi32(b) }
 * (splitmix64 = the finaliser of Steele, Lea & Flood 2014). The map (seed, stream) -> (a, b)
 * is a bijection, so distinct streams get distinct keys; neighbouring indices get unrelated
 * keys. (GSL's own gsl_rng_set() keeps only 32 bits of a seed, which is why the state is
 * seeded here rather than through it.) Each gp_rng exposes a gsl_rng view, so any gsl_ran_*
 * distribution can draw from the same stream.
 *
 * Ownership: gp_rng_create*() return a stream the caller frees with gp_rng_destroy(); its
 * gsl_rng view (gp_rng_gsl) lives inside it. A gp_rng is not thread-safe; use one per
 * thread / work item. Nothing here has global state.
 */
#ifndef GP_RNG_H
#define GP_RNG_H

#include <stddef.h>
#include <stdint.h>

#include <gsl/gsl_rng.h>

#include "gp_error.h"

typedef struct gp_rng gp_rng;

/* A new stream; NULL (and err set to GP_ERR_NOMEM) if allocation fails. */
gp_rng *gp_rng_create(uint64_t seed, uint64_t stream, gp_error *err);
void gp_rng_destroy(gp_rng *r); /* NULL is fine */

/* A stream seeded by the reference init_by_array(key, len) (len >= 1), to reproduce another
 * MT19937 program; NULL with GP_ERR_INVALID / GP_ERR_NOMEM on bad input / no memory. */
gp_rng *gp_rng_create_from_key(const uint32_t *key, size_t len, gp_error *err);

/* The 128-bit init_by_array key of (seed, stream), as described above (exposed for tests and
 * for documentation of results). */
void gp_rng_derive_key(uint64_t seed, uint64_t stream, uint32_t key[4]);

/* The GSL view of the stream, for gsl_ran_* (valid as long as r). Its gsl_rng_uniform()
 * draws 53-bit doubles (two 32-bit words), its gsl_rng_get() 32-bit words. */
gsl_rng *gp_rng_gsl(gp_rng *r);

double gp_rng_uniform(gp_rng *r);             /* [0, 1), 53-bit resolution */
double gp_rng_uniform_pos(gp_rng *r);         /* (0, 1) */
double gp_rng_range(gp_rng *r, double a, double b); /* [a, b) for a < b; a if a >= b */
unsigned long gp_rng_uint(gp_rng *r, unsigned long n); /* [0, n), unbiased; 0 if n == 0 */
double gp_rng_gaussian(gp_rng *r, double sigma); /* N(0, sigma^2) (GSL ziggurat) */
uint32_t gp_rng_u32(gp_rng *r);               /* one raw 32-bit word */

/* Halton sequences: the radical inverse of index in base (>= 2), i.e. the digits of index
 * mirrored about the radix point. Index 0 gives 0; the usual sequence starts at index 1:
 * base 2: 1/2, 1/4, 3/4, 1/8, 5/8, ...; base 3: 1/3, 2/3, 1/9, 4/9, 7/9, ... Returns NaN for
 * base < 2. Accurate to about one ulp for every 64-bit index (the digits are mirrored into
 * an integer and divided once). */
double gp_halton(uint64_t index, unsigned base);

/* The 2D Halton point of index (bases 2 and 3), in [0, 1)^2; index from 1 as above. */
void gp_halton2(uint64_t index, double *x, double *y);

#endif /* GP_RNG_H */
