/* gp_error.c -- see gp_error.h. */
#include "gp_error.h"

#include <stdarg.h>
#include <stdio.h>

gp_status gp_error_set(gp_error *err, gp_status code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

void gp_error_clear(gp_error *err)
{
    if (err) {
        err->code = GP_OK;
        err->message[0] = '\0';
    }
}

const char *gp_status_name(gp_status code)
{
    switch (code) {
    case GP_OK: return "ok";
    case GP_ERR_INVALID: return "invalid";
    case GP_ERR_NOMEM: return "nomem";
    case GP_ERR_NOT_STAR: return "not_star";
    case GP_ERR_DEGENERATE: return "degenerate";
    case GP_ERR_INFEASIBLE: return "infeasible";
    case GP_ERR_NOT_CONVERGED: return "not_converged";
    case GP_ERR_CANCELLED: return "cancelled";
    case GP_ERR_INTERNAL: return "internal";
    }
    return "unknown";
}
