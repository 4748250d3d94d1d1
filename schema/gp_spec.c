/* gp_spec.c -- a JSON Schema interpreter for the spec schemas, defaults, semantic checks and
 * the parsers from JSON to the core's spec structs. See gp_spec.h. */
#include "gp_spec.h"

#include "gp_geom.h"
#include "gp_imc.h"
#include "gp_sieve.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

extern const unsigned char gp_schema_text_fourier_voronoi_2d[];
extern const unsigned char gp_schema_text_spheres_3d[];
extern const unsigned char gp_schema_text_combined[];

#define NKINDS 2
static const char *const g_kinds[NKINDS + 1] = {"fourier-voronoi-2d", "spheres-3d", NULL};
static json_t *g_schema[NKINDS];
static int g_schema_ok = 0;
static pthread_once_t g_once = PTHREAD_ONCE_INIT;

static void compile_all(const json_t *root, const json_t *v);

static void load_schemas(void)
{
    const unsigned char *texts[NKINDS] = {gp_schema_text_fourier_voronoi_2d,
                                          gp_schema_text_spheres_3d};
    g_schema_ok = 1;
    for (int k = 0; k < NKINDS; k++) {
        json_error_t e;
        g_schema[k] = json_loads((const char *)texts[k], 0, &e);
        if (!g_schema[k]) {
            fprintf(stderr, "gp_spec: embedded schema %s is broken: %s (line %d)\n", g_kinds[k],
                    e.text, e.line);
            g_schema_ok = 0;
        }
    }
    for (int k = 0; k < NKINDS && g_schema_ok; k++) compile_all(g_schema[k], g_schema[k]);
}

const char *const *gp_spec_kinds(void) { return g_kinds; }
const char *gp_schema_document(void) { return (const char *)gp_schema_text_combined; }

static int kind_index(const char *kind)
{
    for (int k = 0; kind && k < NKINDS; k++)
        if (strcmp(kind, g_kinds[k]) == 0) return k;
    return -1;
}

const char *gp_schema_text(const char *kind)
{
    switch (kind_index(kind)) {
    case 0: return (const char *)gp_schema_text_fourier_voronoi_2d;
    case 1: return (const char *)gp_schema_text_spheres_3d;
    default: return NULL;
    }
}

static const json_t *schema_of(int k)
{
    pthread_once(&g_once, load_schemas);
    return (k >= 0 && k < NKINDS && g_schema_ok) ? g_schema[k] : NULL;
}

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

static void set_problem(gp_spec_problem *p, int status, const char *pointer, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static void set_problem(gp_spec_problem *p, int status, const char *pointer, const char *fmt, ...)
{
    if (!p) return;
    p->http_status = status;
    snprintf(p->code, sizeof p->code, "%s", status >= 500 ? "internal" : "invalid_spec");
    snprintf(p->pointer, sizeof p->pointer, "%s", pointer);
    char body[480];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(body, sizeof body, fmt, ap);
    va_end(ap);
    snprintf(p->message, sizeof p->message, "%s: %s", pointer[0] ? pointer : "spec", body);
}

static void clear_problem(gp_spec_problem *p)
{
    if (p) memset(p, 0, sizeof *p);
}

/* ------------------------------------------------------------------------------------------ */
/* describing schemas and values for messages */

static void fmt_num(char *buf, size_t n, double v)
{
    if (v == floor(v) && fabs(v) < 1e17) snprintf(buf, n, "%.0f", v);
    else snprintf(buf, n, "%.15g", v);
}

/* A short description of an instance: "abc" (quoted, truncated), 1.5, true, an object, ... */
static void describe_value(const json_t *v, char *buf, size_t n)
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

static int get_num(const json_t *schema, const char *key, double *out)
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
        describe_value(c, buf, n);
        return;
    }
    const json_t *e = json_object_get(schema, "enum");
    if (e && json_is_array(e)) {
        size_t len = (size_t)snprintf(buf, n, "one of ");
        size_t i;
        const json_t *v;
        json_array_foreach(e, i, v) {
            char t[64];
            describe_value(v, t, sizeof t);
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
        if (get_num(schema, "minimum", &lo)) has_lo = 1;
        if (get_num(schema, "exclusiveMinimum", &lo)) has_lo = lo_ex = 1;
        if (get_num(schema, "maximum", &hi)) has_hi = 1;
        if (get_num(schema, "exclusiveMaximum", &hi)) has_hi = hi_ex = 1;
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
        get_num(schema, "minItems", &lo);
        get_num(schema, "maxItems", &hi);
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
    for (int l = 0; l < L_COUNT; l++) n->has[l] = (unsigned char)get_num(s, g_limit_names[l], &n->lim[l]);
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
    describe_value(v, g, sizeof g);
    set_problem(c->p, 400, c->ptr.s, "expected %s, got %s", d, g);
    return -1;
}

static int validate(vctx *c, const json_t *schema, const json_t *v);

static int validate_oneof(vctx *c, const json_t *schema, const json_t *branches, const json_t *v)
{
    size_t nb = json_array_size(branches);
    size_t passing = 0;
    gp_spec_problem best;
    int best_level = 0, best_depth = -1, nbest = 0;
    for (size_t i = 0; i < nb; i++) {
        const json_t *b = resolve_ref(c->root, json_array_get(branches, i));
        gp_spec_problem tmp;
        clear_problem(&tmp);
        vctx sub = *c;
        sub.p = &tmp;
        if (validate(&sub, b, v) == 0) {
            passing++;
            continue;
        }
        /* how well the branch fits the instance's fields: 2 = knows every field and has all it
         * requires, 1 = knows every field; the error of the best fitting branch is the useful
         * one */
        if (!json_is_object(v) || !json_is_object(b)) continue;
        const json_t *req = json_object_get(b, "required");
        const json_t *props = json_object_get(b, "properties");
        const json_t *addl = json_object_get(b, "additionalProperties");
        int level = 2;
        size_t k;
        const json_t *r;
        json_array_foreach(req, k, r) {
            if (!json_object_get(v, json_string_value(r))) level = 1;
        }
        const char *key;
        const json_t *val;
        if (json_is_false(addl)) {
            json_object_foreach((json_t *)v, key, val) {
                if (!json_object_get(props, key)) level = 0;
            }
        }
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
        set_problem(c->p, 400, c->ptr.s, "ambiguous: matches more than one of: %s", d);
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
            set_problem(c->p, 400, c->ptr.s, "unknown field \"%s\"; allowed here: %s", key,
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
            set_problem(c->p, 400, c->ptr.s, "required field is missing; expected %s", d);
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
        set_problem(c->p, 400, c->ptr.s, "expected an array of %s %.0f item%s, got %zu", how,
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
            set_problem(c->p, 400, c->ptr.s, "unexpected item: at most %zu items allowed", np);
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
                    describe_value(json_array_get(v, i), g, sizeof g);
                    set_problem(c->p, 400, c->ptr.s,
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
        set_problem(c->p, 500, c->ptr.s, "broken schema reference");
        return -1;
    }
    if (json_is_true(schema)) return 0;
    if (json_is_false(schema)) {
        set_problem(c->p, 400, c->ptr.s, "no value is allowed here");
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
    size_t i;
    const json_t *r;
    json_array_foreach(json_object_get(b, "required"), i, r) {
        if (!json_object_get(v, json_string_value(r))) return 0;
    }
    if (json_is_false(json_object_get(b, "additionalProperties"))) {
        const json_t *props = json_object_get(b, "properties");
        const char *key;
        const json_t *val;
        json_object_foreach((json_t *)v, key, val) {
            if (!json_object_get(props, key)) return 0;
        }
    }
    return 1;
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

/* schema validation only; returns the kind index or -1 */
static int schema_validate(const json_t *spec, gp_spec_problem *p)
{
    if (!json_is_object(spec)) {
        char g[80];
        describe_value(spec, g, sizeof g);
        set_problem(p, 400, "", "expected a JSON object with a \"kind\" field, got %s", g);
        return -1;
    }
    const json_t *kind = json_object_get(spec, "kind");
    int k = json_is_string(kind) ? kind_index(json_string_value(kind)) : -1;
    if (k < 0) {
        char g[80];
        if (!kind) snprintf(g, sizeof g, "nothing (the field is missing)");
        else describe_value(kind, g, sizeof g);
        set_problem(p, 400, "/kind", "unknown kind %s; expected one of \"%s\", \"%s\"", g,
                    g_kinds[0], g_kinds[1]);
        return -1;
    }
    const json_t *schema = schema_of(k);
    if (!schema) {
        set_problem(p, 500, "", "the embedded schema of kind %s is broken", g_kinds[k]);
        return -1;
    }
    vctx c;
    memset(&c, 0, sizeof c);
    c.root = schema;
    c.p = p;
    if (validate(&c, schema, spec)) return -1;
    return k;
}

/* A copy of the objects of v; arrays and scalars are shared (new references), since defaults
 * only ever add fields to objects: copying the 100,000 points of a large polygon cost as much
 * as validating them. NULL out of memory. */
static json_t *copy_objects(const json_t *v)
{
    if (!json_is_object(v)) return json_incref((json_t *)v);
    json_t *o = json_object();
    if (!o) return NULL;
    const char *key;
    const json_t *val;
    json_object_foreach((json_t *)v, key, val) {
        json_t *c = copy_objects(val);
        if (!c || json_object_set_new(o, key, c)) {
            json_decref(o);
            return NULL;
        }
    }
    return o;
}

static json_t *with_defaults_k(const json_t *spec, int k)
{
    json_t *copy = copy_objects(spec);
    if (copy) apply_defaults(schema_of(k), schema_of(k), copy);
    return copy;
}

static int semantic_2d(const json_t *full, gp_spec_problem *p);
static int semantic_3d(const json_t *full, gp_spec_problem *p);
static int no_memory(gp_spec_problem *p);
static int str_is(const json_t *o, const char *key, const char *value);
static gp_imc_error_kind error_kind_of(const json_t *imc);

/* 2D: size.law decides which size fields belong; checked on the spec as posted, since
 * particles and size.cov have schema defaults. 0 or -1 with *p (422) */
static int check_size_fields_2d(const json_t *spec, gp_spec_problem *p)
{
    const json_t *size = json_object_get(spec, "size");
    const char *law = json_string_value(json_object_get(size, "law"));
    if (!law || strcmp(law, "sieve") != 0) {
        const char *f = json_object_get(size, "sieve")         ? "sieve"
                        : json_object_get(size, "sieve_units") ? "sieve_units" : NULL;
        if (!f) return 0;
        char ptr[32];
        snprintf(ptr, sizeof ptr, "/size/%s", f);
        set_problem(p, 422, ptr, "only allowed with law \"sieve\" (the law here is \"%s\"); "
                    "add \"law\": \"sieve\" or leave %s out", law ? law : "lognormal", f);
        return -1;
    }
    if (json_object_get(spec, "particles"))
        set_problem(p, 422, "/particles", "leave particles out with size.law \"sieve\": the "
                    "number of grains follows from the container area and solid_fraction");
    else if (json_object_get(size, "cov"))
        set_problem(p, 422, "/size/cov", "not allowed with law \"sieve\": the sieve curve sets "
                    "the spread of sizes; leave cov out");
    else if (!json_object_get(size, "sieve"))
        set_problem(p, 422, "/size/sieve", "required with law \"sieve\": expected rows "
                    "[diameter, percent passing by mass]");
    else if (str_is(size, "of", "cells"))
        set_problem(p, 422, "/size/of", "expected \"grains\" (or nothing) with law \"sieve\", "
                    "got \"cells\": a sieve curve is a law of the grains");
    else
        return 0;
    return -1;
}

/* 2D defaults that depend on other fields: a sieve law has no particles (derived) and no cov,
 * and is a law of the grains; sieve_units belongs to a sieve; the threshold follows
 * imc.error. 0, or -1 out of memory */
static int settle_defaults_2d(json_t *full)
{
    json_t *size = json_object_get(full, "size");
    int rc = 0;
    if (str_is(size, "law", "sieve")) {
        json_object_del(full, "particles");
        json_object_del(size, "cov");
        rc |= json_object_set_new(size, "of", json_string("grains"));
    } else {
        json_object_del(size, "sieve_units");
    }
    json_t *imc = json_object_get(full, "imc");
    if (!json_object_get(imc, "threshold"))
        rc |= json_object_set_new(imc, "threshold",
                                  json_real(gp_imc_default_threshold((int)error_kind_of(imc))));
    return rc ? -1 : 0;
}

/* the schema, the 2D field rules, then every default; *k the kind. NULL with *p filled */
static json_t *effective(const json_t *spec, int *k, gp_spec_problem *p)
{
    *k = schema_validate(spec, p);
    if (*k < 0 || (*k == 0 && check_size_fields_2d(spec, p))) return NULL;
    json_t *full = with_defaults_k(spec, *k);
    if (!full || (*k == 0 && settle_defaults_2d(full))) {
        json_decref(full);
        no_memory(p);
        return NULL;
    }
    return full;
}

json_t *gp_spec_with_defaults(const json_t *spec, gp_spec_problem *p)
{
    gp_spec_problem local;
    if (!p) p = &local;
    clear_problem(p);
    int k;
    json_t *full = effective(spec, &k, p);
    if (!full) return NULL;
    int rc = k == 0 ? semantic_2d(full, p) : semantic_3d(full, p);
    if (rc) {
        json_decref(full);
        return NULL;
    }
    return full;
}

int gp_spec_validate(const json_t *spec, gp_spec_problem *p)
{
    json_t *full = gp_spec_with_defaults(spec, p);
    if (!full) return -1;
    json_decref(full);
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* polygon checks
 *
 * The rings of a container (the outer ring and its holes) must be simple, apart from one
 * another, and every hole must lie in the outer ring and in no other hole. A request body of
 * 1 MB holds about 100,000 vertices, so the test is a plane sweep (Shamos & Hoey 1976) in
 * O(E log E) for E edges whatever the layout -- no pair of edges is tested unless the two are
 * neighbours on the sweep line -- and every decision is exact (gp_orient2d), so that touching
 * counts as crossing and nothing else does. The same sweep finds, at the leftmost vertex of each
 * ring, the edge right below it, which tells which ring (if any) contains that ring. */

typedef struct pt {
    double x, y;
} pt;

static double orient(pt a, pt b, pt c)
{
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

static double ring_area(const gp_vec2 *p, size_t n)
{
    double s = 0;
    for (size_t i = 1; i + 1 < n; i++)
        s += (p[i].x - p[0].x) * (p[i + 1].y - p[0].y) - (p[i + 1].x - p[0].x) * (p[i].y - p[0].y);
    return 0.5 * s;
}

static void ring_pointer(char *buf, size_t n, size_t ring)
{
    if (ring == 0) snprintf(buf, n, "/container/polygon");
    else snprintf(buf, n, "/container/holes/%zu", ring - 1);
}

#define SW_NIL UINT32_MAX

/* a < b in the sweep order: by x, then by y */
static int lex_less(gp_vec2 a, gp_vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }
static int same_point(gp_vec2 a, gp_vec2 b) { return a.x == b.x && a.y == b.y; }

typedef struct sw_edge {
    gp_vec2 l, r;               /* endpoints, l before r in the sweep order */
    uint32_t ring, i;           /* ring index, edge from vertex i to vertex i + 1 of that ring */
    uint32_t lc, rc, up, prio;  /* the sweep line's status: a treap ordered bottom to top */
} sw_edge;

typedef struct sw_vertex {
    double x, y;
    uint32_t edge;              /* the edge that starts at this vertex (global index) */
} sw_vertex;

typedef struct sweep {
    const gp_ring *rings;
    const size_t *first;        /* global index of each ring's edge 0 */
    sw_edge *e;
    uint32_t root;
    uint32_t bad_a, bad_b;      /* the first pair that shares a point it must not */
} sweep;

static int vertex_before(const sw_vertex *u, const sw_vertex *v)
{
    return u->x < v->x || (u->x == v->x && u->y < v->y);
}

/* sorts v[0..n) into the sweep order (a bottom-up merge sort, tmp of n items: qsort's calls
 * through a pointer were a fifth of the whole validation) */
static void sort_vertices(sw_vertex *v, sw_vertex *tmp, size_t n)
{
    sw_vertex *a = v, *b = tmp;
    for (size_t w = 1; w < n; w *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * w) {
            size_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi) b[k++] = vertex_before(&a[j], &a[i]) ? a[j++] : a[i++];
            while (i < mid) b[k++] = a[i++];
            while (j < hi) b[k++] = a[j++];
        }
        sw_vertex *t = a;
        a = b;
        b = t;
    }
    if (a != v) memcpy(v, a, n * sizeof *v);
}

/* the vertices of a ring edge: from a to b */
static gp_vec2 edge_from(const sweep *s, uint32_t g)
{
    return s->rings[s->e[g].ring].pts[s->e[g].i];
}

static gp_vec2 edge_to(const sweep *s, uint32_t g)
{
    const gp_ring *r = &s->rings[s->e[g].ring];
    return r->pts[(s->e[g].i + 1) % r->n];
}

/* g then h are consecutive edges of one ring (h starts where g ends) */
static int follows(const sweep *s, uint32_t g, uint32_t h)
{
    const sw_edge *a = &s->e[g], *b = &s->e[h];
    return a->ring == b->ring && (a->i + 1) % s->rings[a->ring].n == b->i;
}

/* sign of each coordinate of q - v: exact, since a difference of doubles rounds to zero only
 * when it is zero */
static int same_direction(gp_vec2 v, gp_vec2 a, gp_vec2 b)
{
    double ax = a.x - v.x, ay = a.y - v.y, bx = b.x - v.x, by = b.y - v.y;
    if (ax != 0) return (ax > 0) == (bx > 0) && bx != 0;
    return (ay > 0) == (by > 0) && by != 0;
}

/* edges g and h share a point they must not: consecutive edges (which share their common
 * vertex) only when they fold back onto each other (collinear and overlapping); any other two
 * when the closed segments meet */
static int pair_bad(const sweep *s, uint32_t g, uint32_t h)
{
    if (follows(s, h, g)) {
        uint32_t t = g;
        g = h;
        h = t;
    }
    if (follows(s, g, h)) {
        gp_vec2 v = edge_to(s, g), a = edge_from(s, g), b = edge_to(s, h);
        return gp_orient2d(v, a, b) == 0 && same_direction(v, a, b);
    }
    return gp_segments_intersect(s->e[g].l, s->e[g].r, s->e[h].l, s->e[h].r);
}

static int sw_check(sweep *s, uint32_t g, uint32_t h)
{
    if (g == SW_NIL || h == SW_NIL || !pair_bad(s, g, h)) return 0;
    s->bad_a = g;
    s->bad_b = h;
    return 1;
}

/* b, being inserted at its left end, lies above t (in the tree) on the sweep line. When b starts
 * on t (the common vertex of consecutive edges, or a touch that the neighbour test reports), b
 * goes by its direction. */
static int sw_above(const sweep *s, uint32_t b, uint32_t t)
{
    const sw_edge *B = &s->e[b], *T = &s->e[t];
    int o = gp_orient2d(T->l, T->r, B->l);
    if (o == 0) o = gp_orient2d(T->l, T->r, B->r);
    return o >= 0;
}

static void sw_set_child(sweep *s, uint32_t parent, uint32_t old, uint32_t child)
{
    if (parent == SW_NIL) s->root = child;
    else if (s->e[parent].lc == old) s->e[parent].lc = child;
    else s->e[parent].rc = child;
    if (child != SW_NIL) s->e[child].up = parent;
}

/* rotates x above its parent */
static void sw_rotate_up(sweep *s, uint32_t x)
{
    sw_edge *e = s->e;
    uint32_t p = e[x].up, g = e[p].up;
    if (e[p].lc == x) {
        e[p].lc = e[x].rc;
        if (e[x].rc != SW_NIL) e[e[x].rc].up = p;
        e[x].rc = p;
    } else {
        e[p].rc = e[x].lc;
        if (e[x].lc != SW_NIL) e[e[x].lc].up = p;
        e[x].lc = p;
    }
    e[p].up = x;
    sw_set_child(s, g, p, x);
}

static void sw_insert(sweep *s, uint32_t b)
{
    sw_edge *e = s->e;
    e[b].lc = e[b].rc = SW_NIL;
    uint32_t cur = s->root, parent = SW_NIL;
    int right = 0;
    while (cur != SW_NIL) {
        parent = cur;
        right = sw_above(s, b, cur);
        cur = right ? e[cur].rc : e[cur].lc;
    }
    e[b].up = parent;
    if (parent == SW_NIL) s->root = b;
    else if (right) e[parent].rc = b;
    else e[parent].lc = b;
    while (e[b].up != SW_NIL && e[e[b].up].prio < e[b].prio) sw_rotate_up(s, b);
}

static void sw_remove(sweep *s, uint32_t b)
{
    sw_edge *e = s->e;
    while (e[b].lc != SW_NIL && e[b].rc != SW_NIL) {
        uint32_t c = e[e[b].lc].prio > e[e[b].rc].prio ? e[b].lc : e[b].rc;
        sw_rotate_up(s, c);
    }
    sw_set_child(s, e[b].up, b, e[b].lc != SW_NIL ? e[b].lc : e[b].rc);
}

/* the next edge below (dir 0) or above (dir 1) b on the sweep line, or SW_NIL */
static uint32_t sw_next(const sweep *s, uint32_t b, int dir)
{
    const sw_edge *e = s->e;
    uint32_t c = dir ? e[b].rc : e[b].lc;
    if (c != SW_NIL) {
        while ((dir ? e[c].lc : e[c].rc) != SW_NIL) c = dir ? e[c].lc : e[c].rc;
        return c;
    }
    while (e[b].up != SW_NIL && (dir ? e[e[b].up].rc : e[e[b].up].lc) == b) b = e[b].up;
    return e[b].up;
}

/* the ring whose interior is right above edge g (its own ring, or that ring's parent) */
static long ring_above(const sweep *s, uint32_t g, const signed char *ccw, const long *parent)
{
    uint32_t r = s->e[g].ring;
    int rightward = lex_less(edge_from(s, g), edge_to(s, g));
    /* a counter-clockwise ring has its interior left of each edge: above a rightward one */
    return (ccw[r] > 0) == rightward ? (long)r : parent[r];
}

/* the first pair of edges found meeting where they must not: (ring, edge) of each, the lower
 * ring (or the lower edge of one ring) first; fold: 1 when edge i1 is followed by edge i2 and
 * they fold back onto each other, 2 the other way round, 0 when they cross or touch */
typedef struct sw_bad {
    size_t r1, i1, r2, i2;
    int fold;
} sw_bad;

/* The sweep over all edges of the rings: 1 with *bad at the first pair of edges that meet where
 * they must not, else 0 with parent[r] = the innermost ring containing ring r (-1: none).
 * -1 out of memory. */
static int sweep_rings(const gp_ring *rings, size_t nr, long *parent, sw_bad *bad_pair)
{
    size_t ne = 0;
    for (size_t r = 0; r < nr; r++) ne += rings[r].n;
    if (ne >= SW_NIL) return -1;
    size_t *first = malloc(nr * sizeof *first);
    size_t *minv = malloc(nr * sizeof *minv);
    signed char *ccw = malloc(nr);
    sw_edge *e = malloc(ne * sizeof *e);
    sw_vertex *v = malloc(2 * ne * sizeof *v);
    if (!first || !minv || !ccw || !e || !v) {
        free(first); free(minv); free(ccw); free(e); free(v);
        return -1;
    }
    /* treap priorities from a generator seeded per call, so that no input can steer the tree's
     * shape (its depth); the verdict and the pair reported depend only on the order of the
     * edges on the sweep line, not on the shape */
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    uint64_t rng = ((uint64_t)ts.tv_nsec * 0x9E3779B97F4A7C15ull) ^ (uint64_t)(uintptr_t)e;
    rng |= 1;
    size_t k = 0;
    for (size_t r = 0; r < nr; r++) {
        const gp_ring *g = &rings[r];
        first[r] = k;
        minv[r] = 0;
        for (size_t i = 0; i < g->n; i++, k++) {
            gp_vec2 a = g->pts[i], b = g->pts[(i + 1) % g->n];
            int fwd = lex_less(a, b);
            e[k].l = fwd ? a : b;
            e[k].r = fwd ? b : a;
            e[k].ring = (uint32_t)r;
            e[k].i = (uint32_t)i;
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            e[k].prio = (uint32_t)(rng >> 32);
            v[k].x = a.x;
            v[k].y = a.y;
            v[k].edge = (uint32_t)k;
            if (lex_less(a, g->pts[minv[r]])) minv[r] = i;
        }
        /* the orientation at the leftmost vertex (collinear with both neighbours only when the
         * edges there fold back, which the sweep reports) */
        size_t m = minv[r];
        ccw[r] = (signed char)gp_orient2d(g->pts[(m + g->n - 1) % g->n], g->pts[m],
                                          g->pts[(m + 1) % g->n]);
        parent[r] = -1;
    }
    sort_vertices(v, v + ne, ne);
    sweep s = {rings, first, e, SW_NIL, SW_NIL, SW_NIL};
    int bad = 0;
    for (size_t q = 0; q < ne && !bad; q++) {
        gp_vec2 at = {v[q].x, v[q].y};
        uint32_t out = v[q].edge;
        const gp_ring *g = &rings[e[out].ring];
        uint32_t in = (uint32_t)(first[e[out].ring] + (e[out].i + g->n - 1) % g->n);
        if (q + 1 < ne && v[q + 1].x == at.x && v[q + 1].y == at.y) {
            /* two vertices at one point: the edges that start there touch */
            s.bad_a = out;
            s.bad_b = v[q + 1].edge;
            bad = 1;
            break;
        }
        /* the edges that start here go in (against the edges that end here, still in), then
         * the edges that end here go out */
        int leftmost = e[out].i == minv[e[out].ring];
        uint32_t both[2] = {in, out};
        for (int t = 0; t < 2 && !bad; t++) {
            uint32_t b = both[t];
            if (!same_point(e[b].l, at)) continue;
            sw_insert(&s, b);
            uint32_t below = sw_next(&s, b, 0);
            if (leftmost && t == 0) /* a ring's first edge: what lies right below the ring */
                parent[e[b].ring] = below == SW_NIL ? -1 : ring_above(&s, below, ccw, parent);
            bad = sw_check(&s, b, below) || sw_check(&s, b, sw_next(&s, b, 1));
        }
        for (int t = 0; t < 2 && !bad; t++) {
            uint32_t b = both[t];
            if (!same_point(e[b].r, at)) continue;
            uint32_t below = sw_next(&s, b, 0), above = sw_next(&s, b, 1);
            sw_remove(&s, b);
            bad = sw_check(&s, below, above);
        }
    }
    if (bad) {
        uint32_t a = s.bad_a, b = s.bad_b;
        if (e[a].ring > e[b].ring || (e[a].ring == e[b].ring && e[a].i > e[b].i)) {
            uint32_t t = a;
            a = b;
            b = t;
        }
        bad_pair->r1 = e[a].ring;
        bad_pair->i1 = e[a].i;
        bad_pair->r2 = e[b].ring;
        bad_pair->i2 = e[b].i;
        bad_pair->fold = follows(&s, a, b) ? 1 : follows(&s, b, a) ? 2 : 0;
    }
    free(first); free(minv); free(ccw); free(e); free(v);
    return bad;
}

/* rings[0] is the outer ring; checks area, simplicity, and that holes lie inside the outer ring
 * and outside one another. Returns 0 or -1 with *p filled (422), or -2 for out of memory. */
static int check_rings(const gp_ring *rings, size_t nr, gp_spec_problem *p)
{
    char ptr[64];
    for (size_t r = 0; r < nr; r++) {
        const gp_ring *g = &rings[r];
        double minx = INFINITY, maxx = -INFINITY, miny = INFINITY, maxy = -INFINITY;
        for (size_t i = 0; i < g->n; i++) {
            minx = fmin(minx, g->pts[i].x); maxx = fmax(maxx, g->pts[i].x);
            miny = fmin(miny, g->pts[i].y); maxy = fmax(maxy, g->pts[i].y);
        }
        double scale = fmax(maxx - minx, maxy - miny);
        ring_pointer(ptr, sizeof ptr, r);
        /* all points on one line? (the farthest point from the first one defines the line) */
        size_t far = 0;
        double dfar = 0;
        for (size_t i = 1; i < g->n; i++) {
            double dx = g->pts[i].x - g->pts[0].x, dy = g->pts[i].y - g->pts[0].y;
            if (dx * dx + dy * dy > dfar) { dfar = dx * dx + dy * dy; far = i; }
        }
        int collinear = 1;
        for (size_t i = 1; i < g->n && far; i++) {
            pt a = {g->pts[0].x, g->pts[0].y}, b = {g->pts[far].x, g->pts[far].y};
            pt q = {g->pts[i].x, g->pts[i].y};
            if (fabs(orient(a, b, q)) > 1e-12 * dfar) collinear = 0;
        }
        if (g->n < 3 || !(scale > 0) || collinear) {
            set_problem(p, 422, ptr, "the polygon has no area (its points are collinear or repeated)");
            return -1;
        }
    }
    long *parent = malloc(nr * sizeof *parent);
    if (!parent) return -2;
    sw_bad b;
    int rc = sweep_rings(rings, nr, parent, &b);
    if (rc < 0) {
        free(parent);
        return -2;
    }
    if (rc > 0) {
        free(parent);
        if (b.fold) {
            ring_pointer(ptr, sizeof ptr, b.r1);
            set_problem(p, 422, ptr,
                        "the polygon is not simple: edges %zu and %zu fold back onto each other",
                        b.fold == 1 ? b.i1 : b.i2, b.fold == 1 ? b.i2 : b.i1);
        } else if (b.r1 == b.r2) {
            ring_pointer(ptr, sizeof ptr, b.r1);
            set_problem(p, 422, ptr,
                        "the polygon is not simple: edge %zu (from point %zu) crosses or touches "
                        "edge %zu (from point %zu)", b.i1, b.i1, b.i2, b.i2);
        } else {
            char other[64];
            ring_pointer(ptr, sizeof ptr, b.r2);
            ring_pointer(other, sizeof other, b.r1);
            set_problem(p, 422, ptr, "edge %zu of this hole crosses or touches edge %zu of %s",
                        b.i2, b.i1, other);
        }
        return -1;
    }
    for (size_t r = 0; r < nr; r++) {
        double scale = 0;
        for (size_t i = 1; i < rings[r].n; i++)
            scale = fmax(scale, fmax(fabs(rings[r].pts[i].x - rings[r].pts[0].x),
                                     fabs(rings[r].pts[i].y - rings[r].pts[0].y)));
        if (!(fabs(ring_area(rings[r].pts, rings[r].n)) > 1e-12 * scale * scale)) {
            ring_pointer(ptr, sizeof ptr, r);
            set_problem(p, 422, ptr, "the polygon has no area");
            free(parent);
            return -1;
        }
    }
    /* no two rings meet: a hole lies in the rings of its chain of parents, and must lie in the
     * outer ring and in no other hole (at most 1000 holes: the chains are short work) */
    for (size_t r = 1; r < nr; r++) {
        int in_outer = 0;
        long in_hole = -1;
        size_t guard = 0;
        for (long c = parent[r]; c >= 0 && guard <= nr; c = parent[c], guard++) {
            if (c == 0) in_outer = 1;
            else if (in_hole < 0 || c < in_hole) in_hole = c;
        }
        if (in_outer && in_hole < 0) continue;
        ring_pointer(ptr, sizeof ptr, r);
        if (!in_outer) set_problem(p, 422, ptr, "the hole is not inside the container polygon");
        else set_problem(p, 422, ptr, "the hole lies inside hole %ld", in_hole - 1);
        free(parent);
        return -1;
    }
    free(parent);
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* sieve curves (3D sieve, 2D size.sieve) */

/* rows [d, percent passing] of a schema-valid sieve at pointer base: d strictly increasing,
 * passing non-decreasing from 0 (first row) to 100 (last row); 0 or -1 with *p (422) */
static int check_sieve_rows(const json_t *sieve, const char *base, gp_spec_problem *p)
{
    size_t n = json_array_size(sieve);
    char ptr[96];
    double prev_d = 0, prev_q = 0;
    for (size_t i = 0; i < n; i++) {
        const json_t *row = json_array_get(sieve, i);
        double d = json_number_value(json_array_get(row, 0));
        double q = json_number_value(json_array_get(row, 1));
        if (i > 0 && !(d > prev_d)) {
            snprintf(ptr, sizeof ptr, "%s/%zu/0", base, i);
            set_problem(p, 422, ptr,
                        "sieve diameters must increase strictly: %.15g follows %.15g", d, prev_d);
            return -1;
        }
        if (i > 0 && q < prev_q) {
            snprintf(ptr, sizeof ptr, "%s/%zu/1", base, i);
            set_problem(p, 422, ptr,
                        "percent passing must not decrease: %.15g follows %.15g", q, prev_q);
            return -1;
        }
        if (i == 0 && q != 0) {
            snprintf(ptr, sizeof ptr, "%s/0/1", base);
            set_problem(p, 422, ptr,
                        "the first sieve row must pass 0 %% (the smallest grain), got %.15g", q);
            return -1;
        }
        prev_d = d;
        prev_q = q;
    }
    if (n && prev_q != 100) {
        snprintf(ptr, sizeof ptr, "%s/%zu/1", base, n - 1);
        set_problem(p, 422, ptr, "the last sieve row must pass 100 %%, got %.15g", prev_q);
        return -1;
    }
    return 0;
}

/* metres per sieve unit ("mm" or "m") */
static double sieve_scale(const char *units)
{
    return units && !strcmp(units, "m") ? 1.0 : 1e-3;
}

/* ------------------------------------------------------------------------------------------ */
/* 2D parser */

static double num(const json_t *o, const char *key)
{
    return json_number_value(json_object_get(o, key));
}

/* reads a ring, dropping repeated consecutive points and a closing point equal to the first */
static int read_ring(const json_t *arr, gp_ring *r)
{
    size_t n = json_array_size(arr);
    r->pts = malloc((n ? n : 1) * sizeof *r->pts);
    r->n = 0;
    if (!r->pts) return -1;
    for (size_t i = 0; i < n; i++) {
        const json_t *q = json_array_get(arr, i);
        gp_vec2 v = {json_number_value(json_array_get(q, 0)), json_number_value(json_array_get(q, 1))};
        if (r->n && r->pts[r->n - 1].x == v.x && r->pts[r->n - 1].y == v.y) continue;
        r->pts[r->n++] = v;
    }
    while (r->n > 1 && r->pts[r->n - 1].x == r->pts[0].x && r->pts[r->n - 1].y == r->pts[0].y)
        r->n--;
    return 0;
}

void gp_spec2d_free(gp_spec2d *s)
{
    if (!s) return;
    free(s->outer.pts);
    for (size_t i = 0; i < s->nholes; i++) free(s->holes[i].pts);
    free(s->holes);
    free((double *)s->spectrum);
    free((double *)s->sieve_d);
    free((double *)s->sieve_pass);
    memset(s, 0, sizeof *s);
}

static int no_memory(gp_spec_problem *p)
{
    set_problem(p, 500, "", "out of memory");
    return -1;
}

/* o[key] is the string value */
static int str_is(const json_t *o, const char *key, const char *value)
{
    const char *s = json_string_value(json_object_get(o, key));
    return s && !strcmp(s, value);
}

static int parse_circle_2d(const json_t *circle, gp_spec2d *out, gp_spec_problem *p)
{
    out->container = GP_CONTAINER_CIRCLE;
    const json_t *c = json_object_get(circle, "center");
    out->circle_center.x = json_number_value(json_array_get(c, 0));
    out->circle_center.y = json_number_value(json_array_get(c, 1));
    out->circle_radius = num(circle, "radius");
    double s = fmax(fabs(out->circle_center.x), fabs(out->circle_center.y));
    if (!(out->circle_radius > 1e-12 * s)) {
        set_problem(p, 422, "/container/circle/radius",
                    "the radius is too small next to the centre's coordinates");
        return -1;
    }
    return 0;
}

/* container: a circle, or a polygon with its holes (simple, holes inside and apart: checked
 * when check is set) */
static int parse_container_2d(const json_t *cont, gp_spec2d *out, gp_spec_problem *p, int check)
{
    const json_t *circle = json_object_get(cont, "circle");
    if (circle) return parse_circle_2d(circle, out, p);
    out->container = GP_CONTAINER_POLYGON;
    const json_t *holes = json_object_get(cont, "holes");
    size_t nh = json_array_size(holes);
    gp_ring *rings = calloc(nh + 1, sizeof *rings);
    if (!rings) return no_memory(p);
    int bad = read_ring(json_object_get(cont, "polygon"), &rings[0]);
    for (size_t i = 0; i < nh && !bad; i++) bad = read_ring(json_array_get(holes, i), &rings[i + 1]);
    out->outer = rings[0];
    if (nh) {
        out->holes = malloc(nh * sizeof *out->holes);
        if (out->holes) {
            memcpy(out->holes, rings + 1, nh * sizeof *rings);
            out->nholes = nh;
        } else {
            for (size_t i = 1; i <= nh; i++) free(rings[i].pts);
            bad = 1;
        }
    }
    if (!bad) {
        /* check_rings wants one array: outer then holes, as rings is */
        int rc = check ? check_rings(rings, nh + 1, p) : 0;
        free(rings);
        return rc == -2 ? no_memory(p) : rc;
    }
    free(rings);
    return no_memory(p);
}

/* index = gp_law_kind */
static const char *const g_laws[] = {"lognormal", "normal", "uniform", "sieve"};

static gp_law_kind law_of(const json_t *size)
{
    for (int k = 0; k < 4; k++)
        if (str_is(size, "law", g_laws[k])) return (gp_law_kind)k;
    return GP_LAW_LOGNORMAL;
}

/* size.cov of a parametric law: GP_LAW_COV_MIN and each law's own maximum (gp_law.h) */
static int check_cov(gp_law_kind law, double cov, gp_spec_problem *p)
{
    if (cov < GP_LAW_COV_MIN) {
        set_problem(p, 422, "/size/cov",
                    "expected at least %g, got %.15g: equal sizes cannot be tessellated exactly; "
                    "use %g for nearly equal sizes", GP_LAW_COV_MIN, cov, GP_LAW_COV_MIN);
        return -1;
    }
    if (law == GP_LAW_NORMAL && cov > GP_LAW_NORMAL_COV_MAX) {
        set_problem(p, 422, "/size/cov",
                    "expected at most %g for law \"normal\", got %.15g (a wider normal law is "
                    "mostly cut off at area 0); use law \"lognormal\" for a wider spread",
                    GP_LAW_NORMAL_COV_MAX, cov);
        return -1;
    }
    if (law == GP_LAW_UNIFORM && cov > GP_LAW_UNIFORM_COV_MAX) {
        set_problem(p, 422, "/size/cov",
                    "expected at most 0.5773 (1/√3) for law \"uniform\", got %.15g (its least "
                    "area, mean (1 - √3 cov), would be negative)", cov);
        return -1;
    }
    return 0;
}

/* size.sieve as two arrays owned by out, diameters converted to metres */
static int parse_sieve_2d(const json_t *size, gp_spec2d *out, gp_spec_problem *p)
{
    const json_t *sieve = json_object_get(size, "sieve");
    if (check_sieve_rows(sieve, "/size/sieve", p)) return -1;
    size_t n = json_array_size(sieve);
    double scale = sieve_scale(json_string_value(json_object_get(size, "sieve_units")));
    double *d = malloc(n * sizeof *d), *pw = malloc(n * sizeof *pw);
    out->sieve_d = d;
    out->sieve_pass = pw;
    if (!d || !pw) return no_memory(p);
    for (size_t i = 0; i < n; i++) {
        const json_t *row = json_array_get(sieve, i);
        d[i] = json_number_value(json_array_get(row, 0)) * scale;
        pw[i] = json_number_value(json_array_get(row, 1));
    }
    out->nsieve = n;
    return 0;
}

static int parse_size_2d(const json_t *size, gp_spec2d *out, gp_spec_problem *p)
{
    out->size_law = law_of(size);
    out->size_of_grains = str_is(size, "of", "grains");
    if (out->size_law == GP_LAW_SIEVE) return parse_sieve_2d(size, out, p);
    out->cov = num(size, "cov");
    return check_cov(out->size_law, out->cov, p);
}

static int parse_shape_2d(const json_t *shape, gp_spec2d *out, gp_spec_problem *p)
{
    const json_t *spec = json_object_get(shape, "spectrum");
    if (!spec) {
        out->D2 = num(shape, "D2");
        out->D3 = num(shape, "D3");
        out->D8 = num(shape, "D8");
        out->alpha = num(shape, "alpha");
        out->beta = num(shape, "beta");
        return 0;
    }
    size_t n = json_array_size(spec);
    if (n > out->contour_points / 2) {
        set_problem(p, 422, "/shape/spectrum",
                    "%zu amplitudes are too many for contour_points = %zu (at most %zu)", n,
                    out->contour_points, out->contour_points / 2);
        return -1;
    }
    double *d = malloc(n * sizeof *d);
    if (!d) return no_memory(p);
    for (size_t i = 0; i < n; i++) d[i] = json_number_value(json_array_get(spec, i));
    out->has_spectrum = 1;
    out->spectrum = d;
    out->nspectrum = n;
    /* D2, D3, D8 are still meaningful for reporting: take them from the spectrum */
    out->D2 = n > 2 ? d[2] / d[0] : 0;
    out->D3 = n > 3 ? d[3] / d[0] : 0;
    out->D8 = n > 8 ? d[8] / d[0] : 0;
    out->alpha = out->beta = -2;
    return 0;
}

static gp_imc_error_kind error_kind_of(const json_t *imc)
{
    if (str_is(imc, "error", "E1")) return GP_IMC_E1;
    if (str_is(imc, "error", "E2")) return GP_IMC_E2;
    if (str_is(imc, "error", "E3")) return GP_IMC_E3;
    return GP_IMC_AD;
}

static void parse_imc_2d(const json_t *imc, gp_spec2d *out)
{
    out->imc_error = error_kind_of(imc);
    const json_t *t = json_object_get(imc, "threshold");
    out->imc_threshold = t ? json_number_value(t) : gp_imc_default_threshold((int)out->imc_error);
    out->imc_max_steps = (long)num(imc, "max_steps");
    out->imc_init = str_is(imc, "init", "halton") ? GP_INIT_HALTON : GP_INIT_UNIFORM;
    const json_t *cl = json_object_get(imc, "classes");
    out->imc_classes = cl ? (int)json_number_value(cl) : 0;
}

static unsigned parse_outputs_2d(const json_t *outputs)
{
    unsigned bits = 0;
    size_t i;
    const json_t *o;
    json_array_foreach(outputs, i, o) {
        const char *s = json_string_value(o);
        if (!strcmp(s, "grains")) bits |= GP_OUT2_GRAINS;
        else if (!strcmp(s, "odec")) bits |= GP_OUT2_ODEC;
        else if (!strcmp(s, "descriptors")) bits |= GP_OUT2_DESCRIPTORS;
        else if (!strcmp(s, "cells")) bits |= GP_OUT2_CELLS;
    }
    return bits;
}

/* the schema's particles maximum: the bound of a derived cell count too */
static double max_particles(void)
{
    const json_t *props = json_object_get(schema_of(0), "properties");
    double m = 1e6;
    get_num(json_object_get(props, "particles"), "maximum", &m);
    return m;
}

/* 422 too_large at /size/sieve: the count ("what") beyond the bound of particles; -1 */
static int too_many(const gp_spec2d *s, double area, gp_spec_problem *p, const char *what)
{
    set_problem(p, 422, "/size/sieve",
                "%s in the container (area %.6g m², solid_fraction %g), over the limit of %.0f "
                "(the most particles allows); check sieve_units or use a smaller container",
                what, area, s->solid_fraction, max_particles());
    snprintf(p->code, sizeof p->code, "too_large");
    return -1;
}

/* a sieve law: its largest grain's cell fits in the container, and the derived count is
 * within particles' bound (422 too_large) */
static int check_sieve_count(const gp_spec2d *s, double area, size_t n, gp_spec_problem *p)
{
    double dmax = s->sieve_d[s->nsieve - 1];
    double cell = M_PI / 4 * dmax * dmax / s->solid_fraction;
    if (cell > area) {
        char ptr[64];
        snprintf(ptr, sizeof ptr, "/size/sieve/%zu/0", s->nsieve - 1);
        set_problem(p, 422, ptr,
                    "a grain of the largest sieve diameter (%.6g m) needs a cell of %.6g m² at "
                    "solid_fraction %g, more than the container's area %.6g m²; check "
                    "sieve_units", dmax, cell, s->solid_fraction, area);
        return -1;
    }
    if ((double)n <= max_particles()) return 0;
    char count[64];
    snprintf(count, sizeof count, "this sieve curve makes about %zu grains", n);
    return too_many(s, area, p, count);
}

/* the number of cells: particles, or derived from the container and a sieve law */
static int cell_count_2d(const gp_spec2d *s, size_t *n, gp_spec_problem *p)
{
    double area = 0;
    gp_error err;
    memset(&err, 0, sizeof err);
    if (gp_spec2d_cell_count(s, &area, n, &err) != GP_OK) {
        if (err.code == GP_ERR_NOMEM) return no_memory(p);
        int sieve = s->size_law == GP_LAW_SIEVE;
        set_problem(p, 422, sieve ? "/size/sieve" : "/container", "%s", err.message);
        /* the rows are checked and the container has an area: the count is out of reach */
        if (sieve && area > 0) too_many(s, area, p, err.message);
        return -1;
    }
    return s->size_law == GP_LAW_SIEVE ? check_sieve_count(s, area, *n, p) : 0;
}

/* Seeds are placed uniformly in the container by rejection in its bounding box (gp_imc): n /
 * fill draws on average, fill = the container's area over its box's. A sliver such as
 * [[0,0],[1,1],[1,1.00000002]] fills 1e-8 of its box, and 10 seeds would take 1e9 draws
 * (a minute); refused at submit rather than failed or timed out in the queue. */
#define MAX_SEED_DRAWS 1e8

static int check_seed_draws_2d(const gp_spec2d *s, size_t n, gp_spec_problem *p)
{
    if (s->container != GP_CONTAINER_POLYGON) return 0;
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (size_t k = 0; k < s->outer.n; k++) {
        x0 = fmin(x0, s->outer.pts[k].x);
        x1 = fmax(x1, s->outer.pts[k].x);
        y0 = fmin(y0, s->outer.pts[k].y);
        y1 = fmax(y1, s->outer.pts[k].y);
    }
    double area = fabs(ring_area(s->outer.pts, s->outer.n));
    for (size_t h = 0; h < s->nholes; h++) area -= fabs(ring_area(s->holes[h].pts, s->holes[h].n));
    double fill = area / ((x1 - x0) * (y1 - y0));
    double draws = (double)n / fill;
    if (draws <= MAX_SEED_DRAWS) return 0;
    set_problem(p, 422, "/container/polygon",
                "the container fills %.3g of its bounding box: placing %zu seeds uniformly in it "
                "(by rejection in that box) would take about %.3g draws, over the limit of %.0e; "
                "a sliver this thin cannot hold a specimen (fill at least %.3g for %zu cells)",
                fill, n, draws, MAX_SEED_DRAWS, (double)n / MAX_SEED_DRAWS, n);
    return -1;
}

/* v rounded up, as short text that reads back >= v (v > 0) */
static void fmt_up(char *buf, size_t n, double v)
{
    for (int digits = 3; digits <= 17; digits++) {
        double e = pow(10, floor(log10(v)) - (digits - 1));
        snprintf(buf, n, "%.*g", digits, ceil(v / e) * e);
        if (strtod(buf, NULL) >= v) return;
    }
}

/* a short threshold >= least that clears the floor of the classes it picks itself (automatic
 * classes follow the threshold) */
static void suggest_threshold(gp_imc_params *q, size_t n, double least, char *use, size_t len)
{
    double v = least;
    for (int i = 0; i < 8; i++) {
        fmt_up(use, len, v);
        q->threshold = strtod(use, NULL);
        double r = gp_imc_reachable_threshold(q, n);
        if (r <= q->threshold) return;
        v = r;
    }
}

/* E1-E3: the threshold must clear the integer-count floor of n cells (gp_imc.h) */
static int check_threshold_2d(const gp_spec2d *s, size_t n, gp_spec_problem *p)
{
    if (s->imc_error == GP_IMC_AD) return 0;
    gp_imc_params q;
    gp_imc_params_default(&q);
    q.error_kind = (int)s->imc_error;
    q.threshold = s->imc_threshold;
    q.classes_size = q.classes_orient = s->imc_classes;
    if (s->size_law != GP_LAW_SIEVE) q.cov = s->cov;
    q.mean_deg = s->mean_deg;
    q.anisotropy = s->anisotropy;
    double least = gp_imc_reachable_threshold(&q, n);
    if (!(s->imc_threshold < least)) return 0;
    char use[40], classes[80];
    suggest_threshold(&q, n, least, use, sizeof use);
    if (s->imc_classes)
        snprintf(classes, sizeof classes, "%d size x %d orientation classes", s->imc_classes,
                 s->imc_classes);
    else snprintf(classes, sizeof classes, "its automatic histogram classes");
    set_problem(p, 422, "/imc/threshold",
                "%.6g is below the least error %.4g that %zu cells can reach with E%d and %s "
                "(integer counts); use >= %s%s or the default error AD", s->imc_threshold, least,
                n, (int)s->imc_error, classes, use, s->imc_classes ? ", fewer imc.classes" : "");
    return -1;
}

static void bounds_2d(const gp_spec2d *s, size_t n, gp_spec_bounds_t *b);
static int over_budget(const gp_spec_bounds_t *b, const char *what, gp_spec_problem *p);

/* fills out from a valid spec with defaults applied (settle_defaults_2d); *n the cell count.
 * checks: the semantic checks (container geometry, the threshold's floor, the work budget);
 * without them only what parsing and the cell count need. 0 / -1 */
static int parse_2d_full(const json_t *full, gp_spec2d *out, gp_spec_problem *p, int checks,
                         size_t *ncells)
{
    memset(out, 0, sizeof *out);
    out->seed = (uint64_t)json_number_value(json_object_get(full, "seed"));
    out->particles = (size_t)json_number_value(json_object_get(full, "particles"));
    const json_t *ori = json_object_get(full, "orientation");
    out->mean_deg = num(ori, "mean_deg");
    out->anisotropy = num(ori, "anisotropy");
    out->contour_points = (size_t)json_number_value(json_object_get(full, "contour_points"));
    out->solid_fraction = num(full, "solid_fraction");
    parse_imc_2d(json_object_get(full, "imc"), out);
    out->outputs = parse_outputs_2d(json_object_get(full, "outputs"));
    out->threads = 0;
    if (parse_container_2d(json_object_get(full, "container"), out, p, checks) ||
        parse_size_2d(json_object_get(full, "size"), out, p) ||
        parse_shape_2d(json_object_get(full, "shape"), out, p))
        return -1;
    size_t n = 0;
    if (cell_count_2d(out, &n, p)) return -1;
    if (ncells) *ncells = n;
    if (!checks) return 0;
    if (check_seed_draws_2d(out, n, p) || check_threshold_2d(out, n, p)) return -1;
    gp_spec_bounds_t b;
    bounds_2d(out, n, &b);
    char what[200];
    size_t edges = out->outer.n;
    for (size_t h = 0; h < out->nholes; h++) edges += out->holes[h].n;
    char where[64] = "a circle";
    if (edges) snprintf(where, sizeof where, "a container of %zu edges", edges);
    snprintf(what, sizeof what, "%.3g IMC moves at most (imc.max_steps) on %zu cells in %s, then "
             "%zu grains of %zu contour points", b.steps, n, where, n, out->contour_points);
    return over_budget(&b, what, p);
}

static int semantic_2d(const json_t *full, gp_spec_problem *p)
{
    gp_spec2d tmp;
    int rc = parse_2d_full(full, &tmp, p, 1, NULL);
    gp_spec2d_free(&tmp);
    return rc;
}

int gp_spec2d_read(const json_t *spec, gp_spec2d *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    if (!p) p = &local;
    clear_problem(p);
    memset(out, 0, sizeof *out);
    int k;
    json_t *full = effective(spec, &k, p);
    if (!full) return -1;
    int rc = -1;
    if (k != 0)
        set_problem(p, 400, "/kind", "expected \"%s\" here, got \"%s\"", g_kinds[0], g_kinds[k]);
    else
        rc = parse_2d_full(full, out, p, 1, NULL);
    json_decref(full);
    if (rc) gp_spec2d_free(out);
    return rc;
}

/* ------------------------------------------------------------------------------------------ */
/* work and result bounds (gp_spec.h) */

/* Costs per unit, from the benchmarks on one core (bench/bench_imc, bench_specimen2d,
 * bench_spheres3d); estimates within a factor of a few, which is all a budget needs. */
#define COST_IMC_MOVE_S 6e-5      /* one IMC move at 1,000 cells (~17,000 moves/s) ... */
#define COST_IMC_PER_DECADE 0.6   /* ... and 60 % more per tenfold more cells (6,400/s at 1e5) */
/* ... plus the container's edges that the recomputed cells meet: the tessellation bins them
 * with about 2 seeds a bin, and a move clips a dozen cells against the edges of their bins, at
 * about 0.5 us x (edges per bin)^1.5 (measured: a 10,000-edge zigzag with 100 cells, 200 edges
 * a bin, 480 moves/s; with 10 cells, 2,000 a bin, 39 moves/s) */
#define COST_IMC_EDGE_S 0.5e-6
#define COST_FILL_S 2.5e-3        /* filling one grain of 128 contour points (~400-600 grains/s) */
#define COST_ODEC_S 0.5e-3        /* its ODEC discs, at 128 points */
#define COST_DESC_S 0.5e-3        /* its descriptors, at 128 points */
#define DEM_SPHERE_STEPS_PER_S 4e6 /* the 3D DEM, sphere-steps per second (3.9e6 measured) */
/* The 3D protocol (core/3d/gp_specimen3d.c): its constants, which its header does not export */
#define DEM_MAX_SAMPLE 400000.0   /* MAX_SAMPLE_SPHERES: spheres of the sample at most */
#define DEM_MAX_TILED 20000000.0  /* MAX_TILED_SPHERES: spheres after the tiling at most */
#define DEM_DT_SAFETY 0.3         /* DT_SAFETY, of sqrt(m / 2 E R) */
#define DEM_SCALED_RATIO 3.5      /* MAX_SCALED_RATIO: density-scaling radius >= rmax / this */
#define DEM_GRAVITY 9.81
/* The protocol's durations are multiples of T = sqrt(d50 / g): growth 1.75 T, settling 1.2 T,
 * compaction windows of 0.35-3.5 T, relaxation; the paper's example takes 16 T (13,610 steps
 * at 860 steps per T) and a 1-20 mm sieve 14-22 T. 50 T is the estimate, with room for a slow
 * compaction; the protocol's own cap (500 T) bounds a run that does not converge. */
#define DEM_PROTOCOL_T 50.0

/* result bytes of one 2D grain, by outputs (as server/http.c has estimated them) */
static double bytes_per_grain(unsigned outputs, double np)
{
    double per = 400; /* stats, ids, areas, descriptors */
    if (outputs & GP_OUT2_GRAINS) per += 40 * np;
    if (outputs & GP_OUT2_ODEC) per += 40 * np + 60 * 16;
    if (outputs & GP_OUT2_DESCRIPTORS) per += 40 * np + 120;
    if (outputs & GP_OUT2_CELLS) per += 40 * 12 + 100;
    return per;
}

static void bounds_2d(const gp_spec2d *s, size_t n, gp_spec_bounds_t *b)
{
    memset(b, 0, sizeof *b);
    double cells = (double)n, np = (double)s->contour_points;
    int sieve = s->size_law == GP_LAW_SIEVE;
    b->cells = b->items = cells;
    b->steps = (double)s->imc_max_steps;
    double edges = 0;
    if (s->container == GP_CONTAINER_POLYGON) {
        edges = (double)s->outer.n;
        for (size_t h = 0; h < s->nholes; h++) edges += (double)s->holes[h].n;
    }
    double per_bin = edges / fmax(1, cells / 2);
    double imc = b->steps * COST_IMC_MOVE_S *
                 (1 + COST_IMC_PER_DECADE * log10(fmax(cells, 1000) / 1000));
    double imc_edges = b->steps * COST_IMC_EDGE_S * per_bin * sqrt(per_bin);
    double per = COST_FILL_S;
    if (s->outputs & GP_OUT2_ODEC) per += COST_ODEC_S;
    if (s->outputs & GP_OUT2_DESCRIPTORS) per += COST_DESC_S;
    double grains = cells * per * np / 128;
    b->work_s = imc + imc_edges + grains;
    b->work_pointer = imc_edges > imc && imc_edges > grains ? "/container"
                      : imc > grains                       ? "/imc/max_steps"
                      : sieve                              ? "/size/sieve"
                                                           : "/particles";
    b->result_bytes = cells * bytes_per_grain(s->outputs, np);
    b->result_pointer = sieve ? "/size/sieve" : "/particles";
}

/* where the percent curve pc (by weight or by number) of rows d crosses q, linearly */
static double sieve_quantile(const double *d, const double *pc, size_t n, double q)
{
    for (size_t k = 1; k < n; k++)
        if (pc[k] >= q && pc[k] > pc[k - 1])
            return d[k - 1] + (d[k] - d[k - 1]) * fmax(0, q - pc[k - 1]) / (pc[k] - pc[k - 1]);
    return n ? d[n - 1] : 0;
}

/* 3D bounds of a schema-valid spec with defaults whose sieve rows are checked (sieve_rows);
 * 0, or -1 out of memory */
static int bounds_3d(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    memset(b, 0, sizeof *b);
    const json_t *sieve = json_object_get(full, "sieve");
    size_t ns = json_array_size(sieve);
    double scale = sieve_scale(json_string_value(json_object_get(full, "sieve_units")));
    double *d = malloc((ns ? ns : 1) * 3 * sizeof *d);
    if (!d) return no_memory(p);
    double *pw = d + ns, *pn = d + 2 * ns;
    for (size_t k = 0; k < ns; k++) {
        const json_t *row = json_array_get(sieve, k);
        d[k] = json_number_value(json_array_get(row, 0)) * scale;
        pw[k] = json_number_value(json_array_get(row, 1));
    }
    const json_t *box = json_object_get(full, "box");
    double V = 1;
    for (size_t i = 0; i < 3; i++) V *= json_number_value(json_array_get(box, i));
    double porosity = num(full, "porosity");
    const json_t *m = json_object_get(full, "material");
    double young = num(m, "young"), density = num(m, "density");
    double n = ns >= 2 ? gp_sieve_expected_count(d, pw, ns, (1 - porosity) * V) : 0;
    /* the time step: the density-scaling radius is the median radius by number, at least
     * rmax / 3.5 (rmax: where the curve reaches 100 %) */
    double dmax = sieve_quantile(d, pw, ns, 100);
    double dmed = dmax;
    if (ns >= 2 && gp_sieve_weight_to_number(d, pw, ns, GP_SIEVE_UNIFORM, pn, NULL) == GP_OK)
        dmed = sieve_quantile(d, pn, ns, 50);
    double rs = fmax(0.5 * dmed, 0.5 * dmax / DEM_SCALED_RATIO);
    double d50 = sieve_quantile(d, pw, ns, 50);
    free(d);
    b->dt = DEM_DT_SAFETY * rs * sqrt(2 * M_PI * density / (3 * young));
    double per_t = sqrt(d50 / DEM_GRAVITY) / b->dt; /* steps per time unit */
    b->steps = DEM_PROTOCOL_T * per_t;
    b->cells = n;
    double tiles = 1;
    const json_t *tiling = json_object_get(full, "tiling");
    for (size_t i = 0; tiling && i < 3; i++) tiles *= json_number_value(json_array_get(tiling, i));
    b->items = n * tiles;
    b->work_s = n * b->steps / DEM_SPHERE_STEPS_PER_S;
    /* what drives the work: the material when the paper's material would be within budget */
    double ref = b->work_s / sqrt((young / density) / (15e6 / 2600));
    if (b->work_s > GP_SPEC_WORK_BUDGET_S && ref <= GP_SPEC_WORK_BUDGET_S)
        b->work_pointer = young / 15e6 >= 2600 / density ? "/material/young" : "/material/density";
    else
        b->work_pointer = "/box";
    double per = 0;
    size_t i;
    const json_t *o;
    json_array_foreach(json_object_get(full, "outputs"), i, o) {
        const char *w = json_string_value(o);
        if (!strcmp(w, "spheres")) per += 90;           /* [x, y, z, r] at 17 digits */
        else if (!strcmp(w, "contacts")) per += 2.6 * 210; /* 2.6 contacts per sphere */
    }
    b->result_bytes = 20000 + b->items * per;
    b->result_pointer = tiles > 1 ? "/tiling" : "/box";
    return 0;
}

static int too_large(gp_spec_problem *p, const char *pointer, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int too_large(gp_spec_problem *p, const char *pointer, const char *fmt, ...)
{
    char body[480];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(body, sizeof body, fmt, ap);
    va_end(ap);
    set_problem(p, 422, pointer, "%s", body);
    snprintf(p->code, sizeof p->code, "too_large");
    return -1;
}

/* 422 too_large when the work is over the budget; what: the work in words */
static int over_budget(const gp_spec_bounds_t *b, const char *what, gp_spec_problem *p)
{
    if (b->work_s <= GP_SPEC_WORK_BUDGET_S) return 0;
    const char *advice =
        !strcmp(b->work_pointer, "/imc/max_steps")
            ? "ask for fewer imc.max_steps (the IMC stops at its threshold long before)"
        : !strcmp(b->work_pointer, "/container")
            ? "use a container of fewer edges, more particles or fewer imc.max_steps (each IMC "
              "move clips its cells against the container's edges near them)"
        : !strcmp(b->work_pointer, "/material/young")
            ? "use a softer young (the paper's 1.5e7 Pa: the packing barely depends on it)"
        : !strcmp(b->work_pointer, "/material/density")
            ? "use a higher density (the packing barely depends on it)"
        : !strcmp(b->work_pointer, "/box")
            ? "use a smaller box or a coarser sieve (check sieve_units)"
            : "ask for fewer grains, contour_points or outputs";
    return too_large(p, b->work_pointer,
                     "the job would take about %.2g s of one core (%s), over the budget of %.0f "
                     "s; %s", b->work_s, what, GP_SPEC_WORK_BUDGET_S, advice);
}

int gp_spec_bounds(const json_t *effective_spec, gp_spec_bounds_t *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    if (!p) p = &local;
    clear_problem(p);
    memset(out, 0, sizeof *out);
    const char *kind = json_string_value(json_object_get(effective_spec, "kind"));
    switch (kind_index(kind)) {
    case 0: {
        gp_spec2d s;
        size_t n = 0;
        int rc = parse_2d_full(effective_spec, &s, p, 0, &n);
        if (rc == 0) bounds_2d(&s, n, out);
        gp_spec2d_free(&s);
        return rc;
    }
    case 1:
        if (check_sieve_rows(json_object_get(effective_spec, "sieve"), "/sieve", p)) return -1;
        return bounds_3d(effective_spec, out, p);
    default:
        set_problem(p, 400, "/kind", "unknown kind; expected one of \"%s\", \"%s\"", g_kinds[0],
                    g_kinds[1]);
        return -1;
    }
}

int gp_spec_check_result(const json_t *effective_spec, double max_bytes, gp_spec_problem *p)
{
    gp_spec_problem local;
    if (!p) p = &local;
    gp_spec_bounds_t b;
    if (gp_spec_bounds(effective_spec, &b, p)) return -1;
    if (b.result_bytes <= max_bytes) return 0;
    int d2 = !strcmp(b.result_pointer, "/particles") || !strcmp(b.result_pointer, "/size/sieve");
    const char *fewer = !strcmp(b.result_pointer, "/particles")
                            ? "particles, contour_points or outputs"
                        : d2 ? "grains (a smaller container or coarser sieve), contour_points or "
                               "outputs"
                             : "spheres (a smaller tiling or box, a coarser sieve) or outputs "
                               "(contacts are most of it)";
    return too_large(p, b.result_pointer,
                     "the result would be about %.0f MB (%.0f %s), over this server's limit of "
                     "%.0f MB (--max-result-mb); ask for fewer %s", b.result_bytes / 1e6,
                     b.items, d2 ? "grains" : "spheres", max_bytes / 1e6, fewer);
}

/* ------------------------------------------------------------------------------------------ */
/* 3D semantic checks */

static int semantic_3d(const json_t *full, gp_spec_problem *p)
{
    const json_t *sieve = json_object_get(full, "sieve");
    size_t n = json_array_size(sieve);
    char ptr[64];
    if (check_sieve_rows(sieve, "/sieve", p)) return -1;
    double dmax = json_number_value(json_array_get(json_array_get(sieve, n - 1), 0));
    double scale = sieve_scale(json_string_value(json_object_get(full, "sieve_units")));
    const json_t *box = json_object_get(full, "box");
    double bmin = INFINITY;
    for (size_t i = 0; i < 3; i++) bmin = fmin(bmin, json_number_value(json_array_get(box, i)));
    if (dmax * scale > bmin) {
        snprintf(ptr, sizeof ptr, "/sieve/%zu/0", n - 1);
        set_problem(p, 422, ptr,
                    "the largest sieve diameter (%.6g m) does not fit in the box (smallest side "
                    "%.6g m); check sieve_units", dmax * scale, bmin);
        return -1;
    }
    gp_spec_bounds_t b;
    if (bounds_3d(full, &b, p)) return -1;
    if (b.cells > DEM_MAX_SAMPLE)
        return too_large(p, "/box",
                         "about %.3g spheres fill %g %% of the box with this sieve curve, over "
                         "the limit of %.0f spheres in the DEM sample; use a smaller box or a "
                         "coarser sieve (check sieve_units)", b.cells,
                         100 * (1 - num(full, "porosity")), DEM_MAX_SAMPLE);
    if (b.items > DEM_MAX_TILED)
        return too_large(p, "/tiling",
                         "%.0f tiles of about %.0f spheres make about %.3g spheres, over the "
                         "limit of %.0f; ask for fewer tiles or a smaller box", b.items / b.cells,
                         b.cells, b.items, DEM_MAX_TILED);
    char what[200];
    snprintf(what, sizeof what, "about %.2g DEM steps of %.0f spheres at a time step of %.2g s",
             b.steps, b.cells, b.dt);
    return over_budget(&b, what, p);
}

/* ------------------------------------------------------------------------------------------ */
/* 3D parser */

void gp_spec3d_free(gp_spec3d *s)
{
    if (!s) return;
    free((gp_sieve_row *)s->sieve);
    memset(s, 0, sizeof *s);
}

int gp_spec3d_read(const json_t *spec, gp_spec3d *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    if (!p) p = &local;
    clear_problem(p);
    memset(out, 0, sizeof *out);
    json_t *full = gp_spec_with_defaults(spec, p);
    if (!full) return -1;
    if (strcmp(json_string_value(json_object_get(full, "kind")), g_kinds[1]) != 0) {
        set_problem(p, 400, "/kind", "expected \"%s\" here, got \"%s\"", g_kinds[1],
                    json_string_value(json_object_get(full, "kind")));
        json_decref(full);
        return -1;
    }
    out->seed = (uint64_t)json_number_value(json_object_get(full, "seed"));
    const json_t *box = json_object_get(full, "box");
    for (size_t i = 0; i < 3; i++) out->box[i] = json_number_value(json_array_get(box, i));
    double scale = sieve_scale(json_string_value(json_object_get(full, "sieve_units")));
    const json_t *sieve = json_object_get(full, "sieve");
    size_t n = json_array_size(sieve);
    gp_sieve_row *rows = malloc(n * sizeof *rows);
    if (!rows) {
        set_problem(p, 500, "", "out of memory");
        json_decref(full);
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        const json_t *row = json_array_get(sieve, i);
        rows[i].diameter = json_number_value(json_array_get(row, 0)) * scale;
        rows[i].passing = json_number_value(json_array_get(row, 1));
    }
    out->sieve = rows;
    out->nsieve = n;
    out->porosity = num(full, "porosity");
    const json_t *m = json_object_get(full, "material");
    out->material.density = num(m, "density");
    out->material.young = num(m, "young");
    out->material.poisson = num(m, "poisson");
    out->material.friction_deg = num(m, "friction_deg");
    out->material.damping = num(m, "damping");
    const json_t *tiling = json_object_get(full, "tiling");
    for (size_t i = 0; i < 3; i++)
        out->tiling[i] = tiling ? (int)json_number_value(json_array_get(tiling, i)) : 1;
    size_t i;
    const json_t *o;
    json_array_foreach(json_object_get(full, "outputs"), i, o) {
        const char *str = json_string_value(o);
        if (!strcmp(str, "spheres")) out->outputs |= GP_OUT3_SPHERES;
        else if (!strcmp(str, "contacts")) out->outputs |= GP_OUT3_CONTACTS;
        else if (!strcmp(str, "fabric")) out->outputs |= GP_OUT3_FABRIC;
        else if (!strcmp(str, "stress")) out->outputs |= GP_OUT3_STRESS;
    }
    out->threads = 0;
    out->max_steps = 0;
    out->tile_relax_steps = 0;
    json_decref(full);
    return 0;
}
