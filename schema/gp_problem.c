/* gp_problem.c -- filling a spec's first problem (gp_problem.h). */
#include "gp_problem.h"

#include <stdio.h>

int gp_problemv(gp_spec_problem *p, const char *code, const char *pointer, const char *fmt,
                va_list ap)
{
    if (!p) return -1;
    snprintf(p->code, sizeof p->code, "%s", code);
    snprintf(p->pointer, sizeof p->pointer, "%s", pointer);
    char body[480];
    vsnprintf(body, sizeof body, fmt, ap);
    snprintf(p->message, sizeof p->message, "%s: %s", pointer[0] ? pointer : "spec", body);
    return -1;
}

int gp_problem(gp_spec_problem *p, const char *code, const char *pointer, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    gp_problemv(p, code, pointer, fmt, ap);
    va_end(ap);
    return -1;
}
