/* gp_adstat.h -- the Anderson-Darling statistic of a changing set of values, exactly, in
 * O(log n) per change.
 *
 * For values u_1..u_N in [0, 1] (u = F(x), F the target CDF) the statistic is
 *     A^2 = -N - (1/N) sum_i (2i - 1) [ln u_(i) + ln(1 - u_(N+1-i))]
 *         = -N - (1/N) [ 2 R - G + (2N + 1) H ],
 * with g = ln u, h = ln(1 - u), w = g - h, G = sum g, H = sum h and R = sum_i i w_(i) (i the
 * rank). Inserting w at rank r adds r w to R plus the w-sum of the elements above it (each
 * moves up one rank); removing subtracts the same. So R, G and H are running totals, and all
 * the structure has to answer is "how many elements lie below (key, id), and what is the w-sum
 * of those above": an order-statistic query.
 *
 * Exactness. g and h are taken in fixed point (integer multiples of 2^-46, ~1.4e-14, clamped
 * to [-65535, 65535], NaN to the lower end) and every sum is a 128-bit integer. Integer sums
 * do not depend on the order they were formed in: A^2, the what-if below and every internal
 * sum are functions of the set of (id, key, g, h) alone, whatever the history -- setting an
 * element back restores A^2 bit for bit (the IMC's rollback), nothing drifts however long the
 * run, and the what-if equals the A^2 after the change bit for bit. A^2 is then rounded once:
 * it is the exact statistic of the rounded logs, within N * 1.4e-14 of that of the given ones.
 * The clamp is a tail far beyond any cell that matters (ln F = -65535); such an element
 * counts as at the limit. Ties of key are broken by the element's id, which is harmless only
 * where tied keys have equal g and h.
 *
 * Structure (gp_adstat.c): the elements in (key, id) order in blocks of at most 32 (keys, ids,
 * fixed w's, and chunk prefix sums of the w's), and a directory of the blocks in two levels:
 * pages of up to 32 blocks (first keys, and the count and w-sum before each block in the
 * page) and a page table in key order (first keys) with a Fenwick tree of the pages' counts
 * and w-sums. Finding a key is a search in the page table (a few KB) and one in a page's keys;
 * a present element's block is recorded with it, and a block's page and place in the page,
 * so finding it needs no search. A query is then a search in a block, a Fenwick prefix over
 * pages and one in-page prefix -- a few cache lines, where a pointer tree walks ~log2 N nodes
 * spread over the heap -- and a change of a block's count or w-sum costs at most a page's
 * prefixes and a Fenwick update: no operation costs more than O(sqrt(N)) in the directory.
 * Blocks split when full and merge with a neighbour when the two hold <= 20, so there are at
 * most 2N / 21 + 1 of them; pages split when full and merge when two neighbours hold <= 16
 * blocks, so there are at most 2 blocks / 17 + 1 of them. The pools for both are allocated at
 * create (untouched pages of memory cost nothing) and nothing is allocated after. The sum of
 * extras is kept in a segment tree of fixed shape over ids (a function of the set as well, in
 * floating point).
 *
 * The caller passes g and h with u, computed where they are accurate (ln F and ln(1 - F) from
 * the law, gp_law_log_cdf_sf), so that values deep in a tail keep their weight.
 *
 * gp_adstat_floor(N) is the least A^2 of N values (all u_(i) = (2i - 1) / 2N, the stationary
 * point of A^2 in each u_(i)).
 *
 * Ownership: one object per statistic; not thread-safe (one writer). No global state.
 * Memory: about 90 bytes per element of capacity (per-id record 32, extras' tree 16-32, blocks
 * ~30 and their directory ~3 at their usual fill). Why blocks and not a balanced tree, and why
 * the directory has two levels: docs/design/adstat.md.
 */
#ifndef GP_ADSTAT_H
#define GP_ADSTAT_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"

typedef struct gp_adstat gp_adstat;

/* Room for elements with ids 0..capacity-1, none present; capacity <= 2^29 (GP_ERR_INVALID
 * above: the 128-bit sums are sized for it). */
gp_adstat *gp_adstat_create(size_t capacity, gp_error *err);
void gp_adstat_destroy(gp_adstat *s);

/* Puts element id (< capacity) with sort key `key` and the logs g = ln u, h = ln(1 - u) of its
 * value u = F(x) (finite), replacing the element's previous value if it had one. The key is
 * any number that orders the elements as u does (x itself, or u): ties are broken by id,
 * which is harmless only where tied keys have equal g and h. `extra` is any per-element number
 * whose sum the tree keeps as well (the IMC's squared areas, for the COV), with the same
 * guarantee: the sum is a function of the set, so it neither drifts nor depends on history. */
void gp_adstat_set(gp_adstat *s, size_t id, double key, double g, double h, double extra);

/* Removes element id if present. */
void gp_adstat_remove(gp_adstat *s, size_t id);

size_t gp_adstat_count(const gp_adstat *s);

/* A^2 of the elements present (0 when none). */
double gp_adstat_a2(const gp_adstat *s);

/* Sum of `extra` over the elements present. */
double gp_adstat_sum_extra(const gp_adstat *s);

/* What A^2 and the sum of extras would be if the k distinct present elements ids[] took the
 * keys, logs and extras given -- without changing the set. O(k log n + k^2): each element's
 * count below and w-sum above are read from the structure as it is, and the pairs among the k
 * old and the k new values are corrected directly. A^2 equals gp_adstat_a2 after the change bit
 * for bit (the same integers); the sum of extras up to rounding (another order). This is how a
 * move is judged before it is made: most moves are refused, and refusing one then costs no
 * change to the structure. k <= GP_ADSTAT_IF_MAX and every id present, else NAN. */
#define GP_ADSTAT_IF_MAX 64
double gp_adstat_a2_if(const gp_adstat *s, size_t k, const size_t *ids, const double *key,
                       const double *g, const double *h, const double *extra,
                       double *sum_extra);

/* Asks the memory for the records of the m elements ids[] (those present): for a caller that
 * knows which elements it will query or set soon. Reads only. */
void gp_adstat_warm(const gp_adstat *s, const uint32_t *ids, size_t m);

/* Recomputes every count and sum from the elements (exactly: they are integers) and checks the
 * structure's invariants (order, block sizes and balance, chunk sums, the directory: page sizes
 * and balance, page order, first keys, in-page and Fenwick prefixes, the records of where each
 * element and block is; the extras' tree). 0 when all hold, else the number of the first failed
 * check. O(n + capacity); for tests. */
int gp_adstat_check(const gp_adstat *s);

/* The least A^2 that n values can have. */
double gp_adstat_floor(size_t n);

#endif /* GP_ADSTAT_H */
