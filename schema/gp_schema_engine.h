/* gp_schema_engine.h -- internal to schema/: a JSON Schema (2020-12) interpreter for the
 * embedded spec schemas, knowing nothing of the kinds; it reports through gp_problem.h.
 *
 * Keywords: type, properties, required, additionalProperties, minimum / maximum /
 * exclusiveMinimum / exclusiveMaximum, minItems / maxItems, items, prefixItems, enum, const,
 * oneOf, uniqueItems, minLength / maxLength and local $ref ("#/..."); "default" for
 * gp_schema_apply_defaults; anything else is an annotation. "number" is a finite number and
 * "integer" a number without fraction (1e6 is the integer 1000000).
 *
 * Compiling: gp_schema_load() reads the keywords of every object of a document once into a
 * table found by the object's address, so that validating a value looks nothing up by name (a
 * 1 MB body is ~100,000 polygon points). The table is global: load every document before the
 * first validation, under the caller's pthread_once; afterwards everything here only reads it
 * and is thread-safe. A schema object not in the table (none of the loaded documents) is
 * compiled on the stack for each use.
 *
 * Problems: the first one found is reported (instance keys in document order, then missing
 * required fields), code "invalid_spec" with the RFC 6901 pointer of the bad value (of the
 * missing field itself) and a message "<pointer>: expected ..., got ..."; code "internal" for a
 * broken reference in the schema.
 */
#ifndef GP_SCHEMA_ENGINE_H
#define GP_SCHEMA_ENGINE_H

#include <stdarg.h>
#include <stddef.h>

#include <jansson.h>

#include "gp_problem.h"

/* Parses schema text and compiles every object of it; a new reference, or NULL (with a line on
 * stderr naming `name`) when the text is not JSON. Not thread-safe: see above. */
json_t *gp_schema_load(const char *text, const char *name);

/* Validates v against the document root (loaded). 0, or -1 with *p (never NULL) filled. */
int gp_schema_validate(const json_t *root, const json_t *v, gp_spec_problem *p);

/* Adds the "default" of every absent property of root to the objects of v (valid against
 * root), recursively; in a oneOf, the defaults of the branch that v matches. */
void gp_schema_apply_defaults(const json_t *root, json_t *v);

/* A new reference to a copy of v's objects, its arrays and scalars shared (defaults only ever
 * add fields to objects, and copying 100,000 points cost as much as validating them). NULL
 * out of memory. */
json_t *gp_schema_copy_objects(const json_t *v);

/* A short description of a value for messages: "abc" (quoted, truncated at 40 characters),
 * 1.5, true, an object, an array of 3 items, nothing (NULL). */
void gp_schema_describe_value(const json_t *v, char *buf, size_t n);

/* The number at key of a schema object: 1 with *out, or 0 (absent or not a number). */
int gp_schema_number(const json_t *schema, const char *key, double *out);

#endif /* GP_SCHEMA_ENGINE_H */
