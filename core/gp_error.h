/* gp_error.h -- status codes and error messages shared by every core module.
 *
 * Every core function that can fail returns a gp_status (GP_OK == 0) and, when the caller
 * passes a non-NULL gp_error, fills it with the same code and a one-line human message that
 * names the offending argument. Passing NULL is always allowed.
 *
 * Ownership and thread safety: a gp_error is a plain struct the caller owns (usually on its
 * stack); nothing here allocates or has global state, so threads with their own gp_error
 * never interfere.
 */
#ifndef GP_ERROR_H
#define GP_ERROR_H

typedef enum gp_status {
    GP_OK = 0,
    GP_ERR_INVALID,       /* bad argument: NaN, out of range, too few points, ... */
    GP_ERR_NOMEM,         /* allocation failed */
    GP_ERR_NOT_STAR,      /* a Fourier spectrum whose contour has r <= 0 somewhere */
    GP_ERR_DEGENERATE,    /* geometry without area / direction where one is needed */
    GP_ERR_INFEASIBLE,    /* the target cannot be reached (a partial result may exist) */
    GP_ERR_NOT_CONVERGED, /* an iteration hit its limit before its threshold */
    GP_ERR_CANCELLED,     /* the caller's cancel flag was raised */
    GP_ERR_INTERNAL       /* a broken invariant: a bug, reported rather than crashed on */
} gp_status;

#define GP_ERROR_MESSAGE_MAX 256

typedef struct gp_error {
    gp_status code;
    char message[GP_ERROR_MESSAGE_MAX];
} gp_error;

/* Records code and a printf-style message in err (if err is not NULL); returns code so that
 * callers can write `return gp_error_set(err, GP_ERR_INVALID, "n must be >= 3");`. */
gp_status gp_error_set(gp_error *err, gp_status code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Resets err to GP_OK with an empty message (no-op on NULL). */
void gp_error_clear(gp_error *err);

/* Stable lower-case name of a status, e.g. "invalid", "not_star". */
const char *gp_status_name(gp_status code);

#endif /* GP_ERROR_H */
