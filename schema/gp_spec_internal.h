/* gp_spec_internal.h -- internal to schema/: the table of kinds that gp_spec.c dispatches on,
 * and what the kind files (gp_spec2d.c, gp_spec3d.c) share.
 *
 * A kind is one gp_spec_kind, defined in its own file with everything that knows its fields:
 * the rules on the spec as posted, the defaults that depend on other fields, the semantic
 * checks, the work and result bounds, the parser. gp_spec.c knows the kinds only through the
 * table (gp_spec.c: g_kinds). Thread safety and ownership as in gp_spec.h.
 */
#ifndef GP_SPEC_INTERNAL_H
#define GP_SPEC_INTERNAL_H

#include <float.h>

#include "gp_schema_engine.h"
#include "gp_spec.h"

/* Advice by the field that drives a bound: rows {pointer, text}, the last one {NULL, the
 * text for any other field}. */
typedef struct gp_spec_advice {
    const char *pointer;
    const char *text;
} gp_spec_advice;

typedef struct gp_spec_kind {
    const char *name;                   /* the value of "kind" */
    const unsigned char *schema_text;   /* its embedded schema (NUL-terminated JSON) */
    /* once the schema refused spec with *p: a clearer problem where the schema can only say
     * something vague (NULL: none), e.g. two forms of a oneOf mixed in one object, which no
     * branch knows ("/shape: expected ... or ..."); replaces *p (returns 1) or leaves it (0) */
    int (*explain)(const json_t *spec, gp_spec_problem *p);
    /* rules on the spec as posted, once it fits the schema and before the defaults fill it
     * (NULL: none); 0 or -1 with *p */
    int (*check_posted)(const json_t *spec, gp_spec_problem *p);
    /* the defaults that depend on other fields, after the schema's (NULL: none); 0, or -1 out
     * of memory */
    int (*settle_defaults)(json_t *full);
    /* the semantic checks of an effective spec, the work budget included; 0 or -1 with *p */
    int (*check)(const json_t *full, gp_spec_problem *p);
    /* gp_spec_bounds of an effective spec of this kind; 0 or -1 with *p */
    int (*bounds)(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p);
    const char *items;                  /* what the result holds: "grains", "spheres" */
    /* what to ask fewer of when the result is over the server's bound, by result_pointer */
    const gp_spec_advice *result_advice;
} gp_spec_kind;

extern const gp_spec_kind gp_spec_kind_2d;  /* gp_spec2d.c */
extern const gp_spec_kind gp_spec_kind_3d;  /* gp_spec3d.c */

/* The loaded schema of a kind (the schemas are loaded once, on first use); NULL when the
 * embedded schemas are broken. */
const json_t *gp_spec_schema(const gp_spec_kind *k);

/* p, or local when p is NULL, cleared: the first line of the public entry points */
gp_spec_problem *gp_spec_begin(gp_spec_problem *p, gp_spec_problem *local);

/* internal "out of memory" at the document; -1 */
int gp_spec_no_memory(gp_spec_problem *p);

/* too_large at pointer (a printf message); -1 */
int gp_spec_too_large(gp_spec_problem *p, const char *pointer, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* the text of the row of pointer, or of the last row */
const char *gp_spec_advice_for(const gp_spec_advice *rows, const char *pointer);

/* 0 when b->work_s is within GP_SPEC_WORK_BUDGET_S, else too_large at b->work_pointer: the
 * work ("what": in words) against the budget, and the advice for that field; -1 */
int gp_spec_over_budget(const gp_spec_bounds_t *b, const char *what,
                        const gp_spec_advice *advice, gp_spec_problem *p);

/* Rows [d, percent passing] of a schema-valid sieve at pointer base (3D "/sieve", 2D
 * "/size/sieve"): d strictly increasing, passing non-decreasing from 0 (first row) to 100
 * (last row); 0 or -1 with *p (invalid_spec at the row's cell). */
int gp_spec_check_sieve_rows(const json_t *sieve, const char *base, gp_spec_problem *p);

/* ---- reading an effective spec without validating it (gp_spec2d_read, gp_spec3d_read) ----
 *
 * The accessors take the pointer of the field (its last token is the member's name) and, when
 * the field is missing or of another type, remember that pointer (the first one) and return a
 * neutral value (0, NULL, the first name), so that the parser can read on; gp_rd_finish then
 * turns it into an "internal" problem. Numbers must be finite, and within a range where a cast
 * needs one; nothing else is checked (the semantic checks are the kind's check function). */
typedef struct gp_spec_reader {
    const char *bad;                    /* the first malformed field; NULL while none */
} gp_spec_reader;

#define GP_RD_ANY DBL_MAX               /* any finite number: [-GP_RD_ANY, GP_RD_ANY] */
#define GP_RD_COUNT 9007199254740992.0  /* 2^53: counts and seeds, in [0, GP_RD_COUNT] */
#define GP_RD_INT 2147483647.0          /* an int, in [0, GP_RD_INT] */

/* notes ptr as malformed (unless a field was already) */
void gp_rd_bad(gp_spec_reader *r, const char *ptr);
/* The member of o named by ptr when it has that JSON type (JSON_OBJECT, JSON_ARRAY, JSON_STRING,
 * JSON_REAL for any number), else NULL (malformed unless optional and absent). */
const json_t *gp_rd_member(gp_spec_reader *r, const json_t *o, const char *ptr, json_type type,
                           int optional);
/* v (at ptr) as a number in [lo, hi]; 0 when it is not one */
double gp_rd_value(gp_spec_reader *r, const json_t *v, const char *ptr, double lo, double hi);
/* the member of o named by ptr, an array of min to max items (absent: NULL; malformed unless
 * optional) */
const json_t *gp_rd_array(gp_spec_reader *r, const json_t *o, const char *ptr, size_t min,
                          size_t max, int optional);
/* the member of o named by ptr as a number in [lo, hi] */
double gp_rd_num(gp_spec_reader *r, const json_t *o, const char *ptr, double lo, double hi);
/* the index of the member's string among names[0 .. n) */
int gp_rd_enum(gp_spec_reader *r, const json_t *o, const char *ptr, const char *const *names,
               int n);
/* the member, an array of strings among names[0 .. n), as the bits 1 << index */
unsigned gp_rd_flags(gp_spec_reader *r, const json_t *o, const char *ptr,
                     const char *const *names, int n);
/* v (at ptr), an array of two numbers, into out[0], out[1] */
void gp_rd_pair(gp_spec_reader *r, const json_t *v, const char *ptr, double out[2]);
/* metres per unit of the member of o named by ptr ("mm" or "m") */
double gp_rd_sieve_scale(gp_spec_reader *r, const json_t *o, const char *ptr);
/* row i of the sieve array at ptr: *d = its diameter times scale, *q its percent passing */
void gp_rd_row(gp_spec_reader *r, const json_t *sieve, size_t i, const char *ptr, double scale,
               double *d, double *q);
/* 0 when everything read was well formed, else -1 with *p "internal" at the first bad field */
int gp_rd_finish(const gp_spec_reader *r, gp_spec_problem *p);

/* The first step of a reader: zeroes *out (size bytes), then the guard: spec is an object of
 * kind k. 0, or -1 with *p (invalid_spec at /kind). */
int gp_spec_read_begin(const gp_spec_kind *k, const json_t *spec, void *out, size_t size,
                       gp_spec_problem *p);

#endif /* GP_SPEC_INTERNAL_H */
