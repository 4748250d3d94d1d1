/* gp_adstat.h -- the Anderson-Darling statistic of a changing set of values, exactly, in
 * O(log n) per change.
 *
 * For values u_1..u_N in [0, 1] (u = F(x), F the target CDF) the statistic is
 *     A^2 = -N - (1/N) sum_i (2i - 1) [ln u_(i) + ln(1 - u_(N+1-i))]
 *         = -N - (1/N) [ 2 R - G + (2N + 1) H ],
 * with g = ln u, h = ln(1 - u), w = g - h, G = sum g, H = sum h and R = sum_i i w_(i) (i the
 * rank). R is linear in the ranks, so it composes over a binary search tree: a subtree with
 * count c, sum of w  W and rank-weighted sum R (ranks local to the subtree) joins its left
 * part L, its root x and its right part Q as
 *     R = R_L + (c_L + 1) w_x + R_Q + (c_L + 1) W_Q.
 * The tree is a treap keyed by (u, id) -- ties broken by the element's id -- whose priorities
 * are a fixed hash of the id, so its shape, and hence every floating-point sum in it, is a
 * function of the set of (id, key, g, h) alone: setting an element back to an earlier value restores
 * A^2 bit for bit (the IMC's rollback), and no sum drifts however long the run.
 *
 * The caller passes g and h with u, computed where they are accurate (ln F and ln(1 - F) from
 * the law, gp_law_log_cdf_sf), so that values deep in a tail keep their weight.
 *
 * gp_adstat_floor(N) is the least A^2 of N values (all u_(i) = (2i - 1) / 2N, the stationary
 * point of A^2 in each u_(i)).
 *
 * Ownership: one object per statistic; not thread-safe (one writer). No global state.
 */
#ifndef GP_ADSTAT_H
#define GP_ADSTAT_H

#include <stddef.h>

#include "gp_error.h"

typedef struct gp_adstat gp_adstat;

/* Room for elements with ids 0..capacity-1, none present. */
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
 * count below and w-sum above are read from the tree as it is, and the pairs among the k old
 * and the k new values are corrected directly. Equals gp_adstat_a2 after the change up to
 * rounding (the sums are formed in another order). This is how a move is judged before it is
 * made: most moves are refused, and refusing one then costs no change to the tree.
 * k <= GP_ADSTAT_IF_MAX, else NAN. */
#define GP_ADSTAT_IF_MAX 64
double gp_adstat_a2_if(const gp_adstat *s, size_t k, const size_t *ids, const double *key,
                       const double *g, const double *h, const double *extra,
                       double *sum_extra);

/* The least A^2 that n values can have. */
double gp_adstat_floor(size_t n);

#endif /* GP_ADSTAT_H */
