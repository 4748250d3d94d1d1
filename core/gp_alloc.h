/* gp_alloc.h -- a set of arrays of one length, allocated together and checked once.
 *
 * For the parallel arrays a module keeps (a PSD's columns, per-element scratch):
 *     double **const cols[] = {&a, &b, &c};
 *     if (gp_alloc_doubles(n, cols, 3, err)) goto fail;
 * Every array is attempted, in order, whatever happened to the ones before: after a failure
 * the arrays that were allocated are set and the others are NULL, so the caller's usual
 * free-everything cleanup applies (free(NULL) does nothing). n = 0 may fail (malloc(0) may
 * return NULL): callers have n >= 1.
 *
 * Ownership: the arrays are the caller's (malloc'ed; free() each). No state; thread-safe.
 * Header-only (static inline), so that any core module may use it without a link dependency.
 */
#ifndef GP_ALLOC_H
#define GP_ALLOC_H

#include <stddef.h>
#include <stdlib.h>

#include "gp_error.h"

/* *arrays[k] = malloc(n doubles) for k < count. GP_OK, or GP_ERR_NOMEM ("out of memory")
 * when any of them failed (err may be NULL). */
static inline gp_status gp_alloc_doubles(size_t n, double **const arrays[], size_t count,
                                         gp_error *err)
{
    int ok = 1;
    for (size_t k = 0; k < count; k++) {
        *arrays[k] = malloc(n * sizeof(double));
        ok &= *arrays[k] != NULL;
    }
    return ok ? GP_OK : gp_error_set(err, GP_ERR_NOMEM, "out of memory");
}

#endif /* GP_ALLOC_H */
