/* spec_patch.h -- the spec tests' tools (header only: each test is one program): a spec from
 * text, a copy of it with one field set or deleted, and the checks that such a spec is refused
 * at a pointer with a code, or accepted. */
#ifndef GP_TEST_SPEC_PATCH_H
#define GP_TEST_SPEC_PATCH_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "gp_spec.h"
#include "gp_test.h"

static inline json_t *load(const char *text)
{
    json_error_t e;
    json_t *j = json_loads(text, JSON_DECODE_ANY, &e);
    if (!j) fprintf(stderr, "bad test JSON: %s: %s\n", e.text, text);
    return j;
}

/* a copy of base with the value at pointer (objects made on the way; NULL value: deleted) */
static inline json_t *patched(const char *base, const char *pointer, const char *value)
{
    json_t *doc = load(base), *cur = doc;
    char path[256], *save = NULL;
    snprintf(path, sizeof path, "%s", pointer);
    for (char *tok = strtok_r(path + 1, "/", &save); tok;) {
        char *next = strtok_r(NULL, "/", &save);
        if (!next) {
            json_t *v = value ? load(value) : NULL;
            if (json_is_array(cur) && v) json_array_set_new(cur, (size_t)atoi(tok), v);
            else if (json_is_array(cur)) json_array_remove(cur, (size_t)atoi(tok));
            else if (v) json_object_set_new(cur, tok, v);
            else json_object_del(cur, tok);
        } else {
            json_t *child = json_is_array(cur) ? json_array_get(cur, (size_t)atoi(tok))
                                               : json_object_get(cur, tok);
            if (!child) json_object_set_new(cur, tok, child = json_object());
            cur = child;
        }
        tok = next;
    }
    return doc;
}

#define STR_(x) #x
#define STR(x) STR_(x)
#define HERE "line " STR(__LINE__)

/* base with ptr set to value is refused at want_ptr with code, the message starting with the
 * pointer and containing needle (NULL: any) */
static inline void bad(const char *base, const char *ptr, const char *value, const char *want_ptr,
                const char *code, const char *needle, const char *where)
{
    json_t *doc = patched(base, ptr, value);
    gp_spec_problem p;
    int rc = gp_spec_validate(doc, &p);
    int ok = rc != 0 && !strcmp(p.pointer, want_ptr) && !strcmp(p.code, code) &&
             (!needle || strstr(p.message, needle)) &&
             !strncmp(p.message, want_ptr, strlen(want_ptr));
    if (!ok)
        fprintf(stderr, "%s: set %s = %s -> rc %d code %s pointer '%s' message '%s'\n", where,
                ptr, value ? value : "(deleted)", rc, p.code, p.pointer, p.message);
    CHECK(ok);
    json_decref(doc);
}

static inline json_t *effective(const char *base, const char *ptr, const char *value)
{
    json_t *doc = patched(base, ptr, value);
    gp_spec_problem p;
    json_t *full = gp_spec_with_defaults(doc, &p);
    if (!full) fprintf(stderr, "unexpectedly refused: %s\n", p.message);
    json_decref(doc);
    return full;
}

static inline void good(const char *base, const char *ptr, const char *value, const char *where)
{
    json_t *full = effective(base, ptr, value);
    if (!full) fprintf(stderr, "%s: set %s = %s refused\n", where, ptr, value ? value : "-");
    CHECK(full != NULL);
    json_decref(full);
}

#endif /* GP_TEST_SPEC_PATCH_H */
