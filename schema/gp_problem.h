/* gp_problem.h -- a spec's first problem: its error code, the RFC 6901 pointer of the bad field
 * and a message naming both. The JSON-Schema engine (gp_schema_engine.h) and the spec layer
 * (gp_spec.h) report through it; the daemon turns it into its 4xx JSON body.
 *
 * Pure functions of their arguments, thread-safe. */
#ifndef GP_PROBLEM_H
#define GP_PROBLEM_H

#include <stdarg.h>

typedef struct gp_spec_problem {
    char code[32];              /* "invalid_spec", "too_large" or "internal" ("" when none) */
    char pointer[256];          /* RFC 6901 pointer of the first bad field */
    char message[512];          /* "<pointer>: expected ..., got ..." */
} gp_spec_problem;

/* Fills *p (when p is not NULL): code, pointer, and the message "<pointer>: <printf text>"
 * ("spec: ..." for the empty pointer). Returns -1, for `return gp_problem(...)`. */
int gp_problem(gp_spec_problem *p, const char *code, const char *pointer, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
int gp_problemv(gp_spec_problem *p, const char *code, const char *pointer, const char *fmt,
                va_list ap) __attribute__((format(printf, 4, 0)));

#endif /* GP_PROBLEM_H */
