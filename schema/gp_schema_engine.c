/* gp_schema_engine.c -- the JSON Schema interpreter of schema/. See gp_schema_engine.h. */
#include "gp_schema_engine.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* problems and pointers */

typedef struct ptrbuf {
    char s[256];
    size_t len;
    int overflow;
} ptrbuf;

/* Appends "/token" (escaped); returns the previous length to restore with ptr_pop(). */
static size_t ptr_push(ptrbuf *b, const char *tok)
{
    size_t old = b->len;
    char tmp[256];
    size_t n = 0;
    tmp[n++] = '/';
    for (const char *c = tok; *c && n + 2 < sizeof tmp; c++) {
        if (*c == '~') { tmp[n++] = '~'; tmp[n++] = '0'; }
        else if (*c == '/') { tmp[n++] = '~'; tmp[n++] = '1'; }
        else tmp[n++] = *c;
    }
    if (b->len + n + 1 > sizeof b->s) {
        b->overflow = 1;
        return old;
    }
    memcpy(b->s + b->len, tmp, n);
    b->len += n;
    b->s[b->len] = 0;
    return old;
}

static size_t ptr_push_index(ptrbuf *b, size_t i)
{
    /* every item of every array comes here: digits without printf */
    char t[32], *q = t + sizeof t - 1;
    *q = 0;
    do {
        *--q = (char)('0' + i % 10);
        i /= 10;
    } while (i);
    return ptr_push(b, q);
}

static void ptr_pop(ptrbuf *b, size_t old)
{
    b->len = old;
    b->s[old] = 0;
}

static int ptr_depth(const char *p)
{
    int d = 0;
    for (; *p; p++) d += *p == '/';
    return d;
}

/* ------------------------------------------------------------------------------------------ */
/* describing schemas and values for messages */

static void fmt_num(char *buf, size_t n, double v)
{
    if (v == floor(v) && fabs(v) < 1e17) snprintf(buf, n, "%.0f", v);
    else snprintf(buf, n, "%.15g", v);
}

/* A short description of an instance: "abc" (quoted, truncated), 1.5, true, an object, ... */
void gp_schema_describe_value(const json_t *v, char *buf, size_t n)
{
    if (!v) {
        snprintf(buf, n, "nothing");
        return;
    }
    switch (json_typeof(v)) {
    case JSON_STRING: {
        const char *s = json_string_value(v);
        size_t len = strlen(s);
        if (len > 40) snprintf(buf, n, "\"%.40s...\"", s);
        else snprintf(buf, n, "\"%s\"", s);
        break;
    }
    case JSON_INTEGER: snprintf(buf, n, "%" JSON_INTEGER_FORMAT, json_integer_value(v)); break;
    case JSON_REAL: fmt_num(buf, n, json_real_value(v)); break;
    case JSON_TRUE: snprintf(buf, n, "true"); break;
    case JSON_FALSE: snprintf(buf, n, "false"); break;
    case JSON_NULL: snprintf(buf, n, "null"); break;
    case JSON_OBJECT: snprintf(buf, n, "an object"); break;
    case JSON_ARRAY: snprintf(buf, n, "an array of %zu items", json_array_size(v)); break;
    default: snprintf(buf, n, "?"); break;
    }
}

static const json_t *resolve_ref(const json_t *root, const json_t *schema);

int gp_schema_number(const json_t *schema, const char *key, double *out)
{
    const json_t *v = json_object_get(schema, key);
    if (!v || !json_is_number(v)) return 0;
    *out = json_number_value(v);
    return 1;
}

/* "a number ≥ 0", "an integer in [1, 1000000]", "one of \"E1\", \"E2\"", ... */
static void describe_schema(const json_t *root, const json_t *schema, char *buf, size_t n)
{
    schema = resolve_ref(root, schema);
    buf[0] = 0;
    if (!schema) return;
    const json_t *c = json_object_get(schema, "const");
    if (c) {
        gp_schema_describe_value(c, buf, n);
        return;
    }
    const json_t *e = json_object_get(schema, "enum");
    if (e && json_is_array(e)) {
        size_t len = (size_t)snprintf(buf, n, "one of ");
        size_t i;
        const json_t *v;
        json_array_foreach(e, i, v) {
            char t[64];
            gp_schema_describe_value(v, t, sizeof t);
            if (len < n) len += (size_t)snprintf(buf + len, n - len, "%s%s", i ? ", " : "", t);
        }
        return;
    }
    const json_t *one = json_object_get(schema, "oneOf");
    if (one && json_is_array(one)) {
        size_t len = 0;
        size_t i;
        const json_t *b;
        json_array_foreach(one, i, b) {
            const json_t *t = json_object_get(resolve_ref(root, b), "title");
            char d[200];
            if (t && json_is_string(t)) snprintf(d, sizeof d, "%s", json_string_value(t));
            else describe_schema(root, b, d, sizeof d);
            if (len < n) len += (size_t)snprintf(buf + len, n - len, "%s%s", i ? " or " : "", d);
        }
        return;
    }
    const char *type = json_string_value(json_object_get(schema, "type"));
    if (!type) {
        snprintf(buf, n, "a valid value");
        return;
    }
    if (!strcmp(type, "number") || !strcmp(type, "integer")) {
        const char *what = type[0] == 'n' ? "a number" : "an integer";
        double lo = 0, hi = 0;
        int has_lo = 0, has_hi = 0, lo_ex = 0, hi_ex = 0;
        if (gp_schema_number(schema, "minimum", &lo)) has_lo = 1;
        if (gp_schema_number(schema, "exclusiveMinimum", &lo)) has_lo = lo_ex = 1;
        if (gp_schema_number(schema, "maximum", &hi)) has_hi = 1;
        if (gp_schema_number(schema, "exclusiveMaximum", &hi)) has_hi = hi_ex = 1;
        char a[40], b[40];
        fmt_num(a, sizeof a, lo);
        fmt_num(b, sizeof b, hi);
        if (has_lo && has_hi)
            snprintf(buf, n, "%s in %c%s, %s%c", what, lo_ex ? '(' : '[', a, b, hi_ex ? ')' : ']');
        else if (has_lo) snprintf(buf, n, "%s %s %s", what, lo_ex ? ">" : "≥", a);
        else if (has_hi) snprintf(buf, n, "%s %s %s", what, hi_ex ? "<" : "≤", b);
        else snprintf(buf, n, "%s", what);
    } else if (!strcmp(type, "array")) {
        double lo = -1, hi = -1;
        gp_schema_number(schema, "minItems", &lo);
        gp_schema_number(schema, "maxItems", &hi);
        if (lo >= 0 && lo == hi) snprintf(buf, n, "an array of exactly %.0f item%s", lo, lo == 1 ? "" : "s");
        else if (lo > 0) snprintf(buf, n, "an array of at least %.0f item%s", lo, lo == 1 ? "" : "s");
        else snprintf(buf, n, "an array");
    } else if (!strcmp(type, "object")) {
        snprintf(buf, n, "an object");
    } else if (!strcmp(type, "string")) {
        snprintf(buf, n, "a string");
    } else if (!strcmp(type, "boolean")) {
        snprintf(buf, n, "true or false");
    } else {
        snprintf(buf, n, "%s", type);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* the validator */

typedef struct vctx {
    const json_t *root;   /* the kind's schema, for local $ref */
    ptrbuf ptr;
    gp_spec_problem *p;   /* where the first problem goes (never NULL inside) */
} vctx;

static const json_t *resolve_ref(const json_t *root, const json_t *schema)
{
    for (int guard = 0; guard < 16 && schema; guard++) {
        const char *ref = json_string_value(json_object_get(schema, "$ref"));
        if (!ref) return schema;
        if (strncmp(ref, "#/", 2) != 0) return NULL;
        /* walk the pointer in root */
        const json_t *cur = root;
        const char *s = ref + 2;
        while (cur && *s) {
            char tok[128];
            size_t n = 0;
            while (*s && *s != '/' && n + 1 < sizeof tok) {
                if (s[0] == '~' && s[1] == '0') { tok[n++] = '~'; s += 2; }
                else if (s[0] == '~' && s[1] == '1') { tok[n++] = '/'; s += 2; }
                else tok[n++] = *s++;
            }
            tok[n] = 0;
            if (*s == '/') s++;
            cur = json_object_get(cur, tok);
        }
        /* keywords beside $ref (description, default) are annotations in our schemas */
        schema = cur;
    }
    return schema;
}

static int is_integral(const json_t *v)
{
    if (json_is_integer(v)) return 1;
    if (!json_is_real(v)) return 0;
    double d = json_real_value(v);
    return isfinite(d) && d == floor(d) && fabs(d) < 9.2e18;
}

/* Compiled schema nodes: the keywords of each schema object of the embedded documents, read
 * once (with the schemas, under pthread_once) and found by the object's address, so that
 * validate() looks nothing up by name for each instance value -- a 1 MB body is ~100,000
 * polygon points, each an array of two numbers. */
enum {
    T_OBJECT = 1, T_ARRAY = 2, T_STRING = 4, T_NUMBER = 8, T_INTEGER = 16, T_BOOLEAN = 32,
    T_NULL = 64, T_UNKNOWN = 128
};
enum { L_MIN, L_MAX, L_XMIN, L_XMAX, L_MINLEN, L_MAXLEN, L_MINITEMS, L_MAXITEMS, L_COUNT };
static const char *const g_limit_names[L_COUNT] = {
    "minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum",
    "minLength", "maxLength", "minItems", "maxItems"};

typedef struct cnode {
    const json_t *key;          /* the schema as written (with its $ref); NULL: a free slot */
    const json_t *s;            /* the schema it resolves to; NULL: a broken reference */
    const json_t *konst, *enm, *prefix, *items, *props, *required, *addl, *oneof;
    unsigned types;             /* T_* of the type keyword; 0 when there is none */
    unsigned char has[L_COUNT];
    double lim[L_COUNT];
    size_t nprefix;
    int unique, objkw;
} cnode;

#define CNODE_CAP 4096 /* power of two; the two schemas have a few hundred objects */
static cnode g_cnodes[CNODE_CAP];
static size_t g_ncnodes;

static unsigned type_bit(const char *t)
{
    if (!strcmp(t, "object")) return T_OBJECT;
    if (!strcmp(t, "array")) return T_ARRAY;
    if (!strcmp(t, "string")) return T_STRING;
    if (!strcmp(t, "number")) return T_NUMBER;
    if (!strcmp(t, "integer")) return T_INTEGER;
    if (!strcmp(t, "boolean")) return T_BOOLEAN;
    if (!strcmp(t, "null")) return T_NULL;
    return T_UNKNOWN;
}

/* the T_* an instance satisfies ("number": finite; "integer": a number with no fraction) */
static unsigned types_of(const json_t *v)
{
    switch (json_typeof(v)) {
    case JSON_OBJECT: return T_OBJECT;
    case JSON_ARRAY: return T_ARRAY;
    case JSON_STRING: return T_STRING;
    case JSON_INTEGER: return T_NUMBER | T_INTEGER;
    case JSON_REAL:
        if (!isfinite(json_real_value(v))) return 0;
        return T_NUMBER | (is_integral(v) ? T_INTEGER : 0);
    case JSON_TRUE:
    case JSON_FALSE: return T_BOOLEAN;
    case JSON_NULL: return T_NULL;
    default: return 0;
    }
}

static void compile_node(const json_t *root, const json_t *schema, cnode *n)
{
    memset(n, 0, sizeof *n);
    n->key = schema;
    const json_t *s = resolve_ref(root, schema);
    n->s = s;
    if (!s || !json_is_object(s)) return;
    n->konst = json_object_get(s, "const");
    n->enm = json_object_get(s, "enum");
    const json_t *type = json_object_get(s, "type");
    if (json_is_string(type)) {
        n->types = type_bit(json_string_value(type));
    } else if (type) {
        n->types = T_UNKNOWN; /* a type keyword that lists nothing known matches nothing */
        size_t i;
        const json_t *t;
        json_array_foreach(type, i, t) {
            if (json_is_string(t)) n->types |= type_bit(json_string_value(t));
        }
    }
    for (int l = 0; l < L_COUNT; l++) n->has[l] = (unsigned char)gp_schema_number(s, g_limit_names[l], &n->lim[l]);
    n->prefix = json_object_get(s, "prefixItems");
    n->nprefix = json_array_size(n->prefix);
    n->items = json_object_get(s, "items");
    n->unique = json_is_true(json_object_get(s, "uniqueItems"));
    n->props = json_object_get(s, "properties");
    n->required = json_object_get(s, "required");
    n->addl = json_object_get(s, "additionalProperties");
    n->objkw = n->props || n->required || n->addl;
    n->oneof = json_object_get(s, "oneOf");
}

static size_t cnode_slot(const json_t *key)
{
    uintptr_t h = (uintptr_t)key;
    h ^= h >> 17;
    h *= (uintptr_t)0x9E3779B97F4A7C15ull;
    return (size_t)(h >> 7) & (CNODE_CAP - 1);
}

/* compiles every object of a schema document (at load time) */
static void compile_all(const json_t *root, const json_t *v)
{
    if (json_is_object(v)) {
        size_t i = cnode_slot(v);
        while (g_cnodes[i].key && g_cnodes[i].key != v) i = (i + 1) & (CNODE_CAP - 1);
        if (!g_cnodes[i].key && g_ncnodes < CNODE_CAP / 2) {
            compile_node(root, v, &g_cnodes[i]);
            g_ncnodes++;
        }
        const char *k;
        json_t *x;
        json_object_foreach((json_t *)v, k, x) compile_all(root, x);
    } else if (json_is_array(v)) {
        size_t i;
        json_t *x;
        json_array_foreach(v, i, x) compile_all(root, x);
    }
}

/* the compiled node of schema: from the table, or compiled into *local */
static const cnode *node_of(const json_t *root, const json_t *schema, cnode *local)
{
    if (schema) {
        for (size_t i = cnode_slot(schema); g_cnodes[i].key; i = (i + 1) & (CNODE_CAP - 1))
            if (g_cnodes[i].key == schema) return &g_cnodes[i];
    }
    compile_node(root, schema, local);
    return local;
}

static int fail_expected(vctx *c, const json_t *schema, const json_t *v)
{
    char d[300], g[80];
    describe_schema(c->root, schema, d, sizeof d);
    gp_schema_describe_value(v, g, sizeof g);
    gp_problem(c->p, "invalid_spec", c->ptr.s, "expected %s, got %s", d, g);
    return -1;
}

static int validate(vctx *c, const json_t *schema, const json_t *v);

/* how well an object schema b fits the fields of an object v: 2 = it knows every field of v
 * (or allows any) and v has every field it requires, 1 = it knows every field, 0 = not even */
static int fit_level(const json_t *b, const json_t *v)
{
    int level = 2;
    size_t k;
    const json_t *r;
    json_array_foreach(json_object_get(b, "required"), k, r) {
        if (!json_object_get(v, json_string_value(r))) level = 1;
    }
    if (json_is_false(json_object_get(b, "additionalProperties"))) {
        const json_t *props = json_object_get(b, "properties");
        const char *key;
        const json_t *val;
        json_object_foreach((json_t *)v, key, val) {
            if (!json_object_get(props, key)) return 0;
        }
    }
    return level;
}

static int validate_oneof(vctx *c, const json_t *schema, const json_t *branches, const json_t *v)
{
    size_t nb = json_array_size(branches);
    size_t passing = 0;
    gp_spec_problem best;
    int best_level = 0, best_depth = -1, nbest = 0;
    for (size_t i = 0; i < nb; i++) {
        const json_t *b = resolve_ref(c->root, json_array_get(branches, i));
        gp_spec_problem tmp;
        memset(&tmp, 0, sizeof tmp);
        vctx sub = *c;
        sub.p = &tmp;
        if (validate(&sub, b, v) == 0) {
            passing++;
            continue;
        }
        /* the error of the best fitting branch is the useful one */
        if (!json_is_object(v) || !json_is_object(b)) continue;
        int level = fit_level(b, v);
        int depth = ptr_depth(tmp.pointer);
        if (level > best_level) {
            best = tmp;
            best_level = level;
            best_depth = depth;
            nbest = 1;
        } else if (level == best_level && level > 0) {
            nbest++;
            if (depth > best_depth) {
                best = tmp;
                best_depth = depth;
            }
        }
    }
    if (passing == 1) return 0;
    if (passing > 1) {
        char d[300];
        describe_schema(c->root, schema, d, sizeof d);
        gp_problem(c->p, "invalid_spec", c->ptr.s, "ambiguous: matches more than one of: %s", d);
        return -1;
    }
    if (best_level == 2 || (best_level == 1 && nbest == 1)) {
        *c->p = best;
        return -1;
    }
    return fail_expected(c, schema, v);
}

static int validate_object(vctx *c, const cnode *n, const json_t *v)
{
    const json_t *props = n->props;
    const json_t *addl = n->addl;
    const char *key;
    const json_t *val;
    json_object_foreach((json_t *)v, key, val) {
        const json_t *ps = json_object_get(props, key);
        size_t old = ptr_push(&c->ptr, key);
        int rc = 0;
        if (ps) {
            rc = validate(c, ps, val);
        } else if (json_is_false(addl)) {
            char allowed[300];
            size_t len = 0;
            const char *k2;
            const json_t *v2;
            allowed[0] = 0;
            json_object_foreach((json_t *)props, k2, v2) {
                if (len < sizeof allowed)
                    len += (size_t)snprintf(allowed + len, sizeof allowed - len, "%s%s",
                                            len ? ", " : "", k2);
            }
            gp_problem(c->p, "invalid_spec", c->ptr.s, "unknown field \"%s\"; allowed here: %s", key,
                        allowed);
            rc = -1;
        } else if (json_is_object(addl)) {
            rc = validate(c, addl, val);
        }
        ptr_pop(&c->ptr, old);
        if (rc) return rc;
    }
    size_t i;
    const json_t *r;
    json_array_foreach(n->required, i, r) {
        const char *name = json_string_value(r);
        if (name && !json_object_get(v, name)) {
            size_t old = ptr_push(&c->ptr, name);
            char d[300];
            describe_schema(c->root, json_object_get(props, name), d, sizeof d);
            gp_problem(c->p, "invalid_spec", c->ptr.s, "required field is missing; expected %s", d);
            ptr_pop(&c->ptr, old);
            return -1;
        }
    }
    return 0;
}

static int validate_array(vctx *c, const cnode *nd, const json_t *v)
{
    size_t n = json_array_size(v);
    double lo = nd->has[L_MINITEMS] ? nd->lim[L_MINITEMS] : -1;
    double hi = nd->has[L_MAXITEMS] ? nd->lim[L_MAXITEMS] : -1;
    if ((lo >= 0 && (double)n < lo) || (hi >= 0 && (double)n > hi)) {
        const char *how = lo == hi ? "exactly" : (double)n < lo ? "at least" : "at most";
        double want = (double)n < lo ? lo : hi;
        gp_problem(c->p, "invalid_spec", c->ptr.s, "expected an array of %s %.0f item%s, got %zu", how,
                    want, want == 1 ? "" : "s", n);
        return -1;
    }
    const json_t *prefix = nd->prefix;
    const json_t *items = nd->items;
    size_t np = nd->nprefix;
    for (size_t i = 0; i < n; i++) {
        const json_t *is = i < np ? json_array_get(prefix, i) : items;
        if (!is || json_is_true(is)) continue;
        size_t old = ptr_push_index(&c->ptr, i);
        int rc;
        if (json_is_false(is)) {
            gp_problem(c->p, "invalid_spec", c->ptr.s, "unexpected item: at most %zu items allowed", np);
            rc = -1;
        } else {
            rc = validate(c, is, json_array_get(v, i));
        }
        ptr_pop(&c->ptr, old);
        if (rc) return rc;
    }
    if (nd->unique) {
        for (size_t i = 1; i < n; i++)
            for (size_t j = 0; j < i; j++)
                if (json_equal(json_array_get(v, i), json_array_get(v, j))) {
                    size_t old = ptr_push_index(&c->ptr, i);
                    char g[80];
                    gp_schema_describe_value(json_array_get(v, i), g, sizeof g);
                    gp_problem(c->p, "invalid_spec", c->ptr.s,
                                "duplicate item %s (the same as item %zu); items must be unique", g,
                                j);
                    ptr_pop(&c->ptr, old);
                    return -1;
                }
    }
    return 0;
}

static int validate(vctx *c, const json_t *schema, const json_t *v)
{
    cnode local;
    const cnode *n = node_of(c->root, schema, &local);
    schema = n->s;
    if (!schema) {
        gp_problem(c->p, "internal", c->ptr.s, "broken schema reference");
        return -1;
    }
    if (json_is_true(schema)) return 0;
    if (json_is_false(schema)) {
        gp_problem(c->p, "invalid_spec", c->ptr.s, "no value is allowed here");
        return -1;
    }
    if (n->konst && !json_equal(n->konst, (json_t *)v)) return fail_expected(c, schema, v);
    if (n->enm) {
        int found = 0;
        size_t i;
        const json_t *e;
        json_array_foreach(n->enm, i, e) {
            if (json_equal(e, (json_t *)v)) found = 1;
        }
        if (!found) return fail_expected(c, schema, v);
    }
    if (n->types && !(n->types & types_of(v))) return fail_expected(c, schema, v);
    if (json_is_number(v)) {
        double x = json_number_value(v);
        if (!isfinite(x)) return fail_expected(c, schema, v);
        if ((n->has[L_MIN] && !(x >= n->lim[L_MIN])) || (n->has[L_MAX] && !(x <= n->lim[L_MAX])) ||
            (n->has[L_XMIN] && !(x > n->lim[L_XMIN])) ||
            (n->has[L_XMAX] && !(x < n->lim[L_XMAX])))
            return fail_expected(c, schema, v);
    }
    if (json_is_string(v)) {
        size_t len = json_string_length(v);
        if ((n->has[L_MINLEN] && (double)len < n->lim[L_MINLEN]) ||
            (n->has[L_MAXLEN] && (double)len > n->lim[L_MAXLEN]))
            return fail_expected(c, schema, v);
    }
    if (json_is_array(v) && validate_array(c, n, v)) return -1;
    if (json_is_object(v) && n->objkw && validate_object(c, n, v)) return -1;
    if (n->oneof && validate_oneof(c, schema, n->oneof, v)) return -1;
    return 0;
}

int gp_schema_validate(const json_t *root, const json_t *v, gp_spec_problem *p)
{
    vctx c;
    memset(&c, 0, sizeof c);
    c.root = root;
    c.p = p;
    return validate(&c, root, v);
}

/* ------------------------------------------------------------------------------------------ */
/* defaults */

/* an object branch could validate v: v has every field the branch requires, and no field
 * it does not know when it allows no others (a non-object branch or instance: maybe) */
static int branch_fits(const json_t *root, const json_t *branch, const json_t *v)
{
    const json_t *b = resolve_ref(root, branch);
    if (!json_is_object(b) || !json_is_object(v)) return 1;
    const char *type = json_string_value(json_object_get(b, "type"));
    if (type && strcmp(type, "object") != 0) return 0;
    return fit_level(b, v) == 2;
}

static void apply_defaults(const json_t *root, const json_t *schema, json_t *v)
{
    schema = resolve_ref(root, schema);
    if (!schema || !json_is_object(schema)) return;
    const json_t *one = json_object_get(schema, "oneOf");
    if (one) {
        /* the instance is valid, so exactly one branch validates it; a branch that does has
         * every field it requires and knows every field when it allows no others: when only
         * one branch fits that way it is the one, without validating (again) a large polygon */
        size_t i, nfit = 0;
        const json_t *b, *fit = NULL;
        json_array_foreach(one, i, b) {
            if (branch_fits(root, b, v)) {
                fit = b;
                nfit++;
            }
        }
        json_array_foreach(one, i, b) {
            if (nfit == 1 && b != fit) continue;
            gp_spec_problem tmp;
            vctx sub = {.root = root, .p = &tmp};
            if (nfit == 1 || validate(&sub, b, v) == 0) {
                apply_defaults(root, b, v);
                break;
            }
        }
    }
    if (!json_is_object(v)) return;
    const json_t *props = json_object_get(schema, "properties");
    const char *key;
    json_t *ps;
    json_object_foreach((json_t *)props, key, ps) {
        json_t *cur = json_object_get(v, key);
        if (!cur) {
            const json_t *rs = resolve_ref(root, ps);
            const json_t *d = json_object_get(ps, "default");
            if (!d && rs) d = json_object_get(rs, "default");
            if (!d) continue;
            json_object_set_new(v, key, json_deep_copy(d));
            cur = json_object_get(v, key);
        }
        if (cur && json_is_object(cur)) apply_defaults(root, ps, cur);
    }
}

/* A copy of the objects of v; arrays and scalars are shared (new references), since defaults
 * only ever add fields to objects: copying the 100,000 points of a large polygon cost as much
 * as validating them. NULL out of memory. */
json_t *gp_schema_copy_objects(const json_t *v)
{
    if (!json_is_object(v)) return json_incref((json_t *)v);
    json_t *o = json_object();
    if (!o) return NULL;
    const char *key;
    const json_t *val;
    json_object_foreach((json_t *)v, key, val) {
        json_t *c = gp_schema_copy_objects(val);
        if (!c || json_object_set_new(o, key, c)) {
            json_decref(o);
            return NULL;
        }
    }
    return o;
}

void gp_schema_apply_defaults(const json_t *root, json_t *v) { apply_defaults(root, root, v); }

json_t *gp_schema_load(const char *text, const char *name)
{
    json_error_t e;
    json_t *root = json_loads(text, 0, &e);
    if (!root) {
        fprintf(stderr, "gp_spec: embedded schema %s is broken: %s (line %d)\n", name, e.text,
                e.line);
        return NULL;
    }
    compile_all(root, root);
    return root;
}
