/* gp_spec.c -- a JSON Schema interpreter for the spec schemas, defaults, semantic checks and
 * the parsers from JSON to the core's spec structs. See gp_spec.h. */
#include "gp_spec.h"

#include "gp_imc.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const unsigned char gp_schema_text_fourier_voronoi_2d[];
extern const unsigned char gp_schema_text_spheres_3d[];
extern const unsigned char gp_schema_text_combined[];

#define NKINDS 2
static const char *const g_kinds[NKINDS + 1] = {"fourier-voronoi-2d", "spheres-3d", NULL};
static json_t *g_schema[NKINDS];
static int g_schema_ok = 0;
static pthread_once_t g_once = PTHREAD_ONCE_INIT;

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
    char t[32];
    snprintf(t, sizeof t, "%zu", i);
    return ptr_push(b, t);
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

static int type_matches(const char *type, const json_t *v)
{
    if (!strcmp(type, "object")) return json_is_object(v);
    if (!strcmp(type, "array")) return json_is_array(v);
    if (!strcmp(type, "string")) return json_is_string(v);
    if (!strcmp(type, "number")) return json_is_number(v) && isfinite(json_number_value(v));
    if (!strcmp(type, "integer")) return is_integral(v);
    if (!strcmp(type, "boolean")) return json_is_boolean(v);
    if (!strcmp(type, "null")) return json_is_null(v);
    return 0;
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

static int validate_object(vctx *c, const json_t *schema, const json_t *v)
{
    const json_t *props = json_object_get(schema, "properties");
    const json_t *addl = json_object_get(schema, "additionalProperties");
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
    const json_t *req = json_object_get(schema, "required");
    size_t i;
    const json_t *r;
    json_array_foreach(req, i, r) {
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

static int validate_array(vctx *c, const json_t *schema, const json_t *v)
{
    size_t n = json_array_size(v);
    double lo = -1, hi = -1;
    get_num(schema, "minItems", &lo);
    get_num(schema, "maxItems", &hi);
    if ((lo >= 0 && (double)n < lo) || (hi >= 0 && (double)n > hi)) {
        const char *how = lo == hi ? "exactly" : (double)n < lo ? "at least" : "at most";
        double want = (double)n < lo ? lo : hi;
        set_problem(c->p, 400, c->ptr.s, "expected an array of %s %.0f item%s, got %zu", how,
                    want, want == 1 ? "" : "s", n);
        return -1;
    }
    const json_t *prefix = json_object_get(schema, "prefixItems");
    const json_t *items = json_object_get(schema, "items");
    size_t np = json_array_size(prefix);
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
    if (json_is_true(json_object_get(schema, "uniqueItems"))) {
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
    schema = resolve_ref(c->root, schema);
    if (!schema) {
        set_problem(c->p, 500, c->ptr.s, "broken schema reference");
        return -1;
    }
    if (json_is_true(schema)) return 0;
    if (json_is_false(schema)) {
        set_problem(c->p, 400, c->ptr.s, "no value is allowed here");
        return -1;
    }
    const json_t *k;
    if ((k = json_object_get(schema, "const")) && !json_equal(k, (json_t *)v))
        return fail_expected(c, schema, v);
    if ((k = json_object_get(schema, "enum"))) {
        int found = 0;
        size_t i;
        const json_t *e;
        json_array_foreach(k, i, e) {
            if (json_equal(e, (json_t *)v)) found = 1;
        }
        if (!found) return fail_expected(c, schema, v);
    }
    const json_t *type = json_object_get(schema, "type");
    if (type) {
        int ok = 0;
        if (json_is_string(type)) ok = type_matches(json_string_value(type), v);
        else {
            size_t i;
            const json_t *t;
            json_array_foreach(type, i, t) {
                if (json_is_string(t) && type_matches(json_string_value(t), v)) ok = 1;
            }
        }
        if (!ok) return fail_expected(c, schema, v);
    }
    if (json_is_number(v)) {
        double x = json_number_value(v), b;
        if (!isfinite(x)) return fail_expected(c, schema, v);
        if ((get_num(schema, "minimum", &b) && !(x >= b)) ||
            (get_num(schema, "maximum", &b) && !(x <= b)) ||
            (get_num(schema, "exclusiveMinimum", &b) && !(x > b)) ||
            (get_num(schema, "exclusiveMaximum", &b) && !(x < b)))
            return fail_expected(c, schema, v);
    }
    if (json_is_string(v)) {
        double b;
        size_t len = json_string_length(v);
        if ((get_num(schema, "minLength", &b) && (double)len < b) ||
            (get_num(schema, "maxLength", &b) && (double)len > b))
            return fail_expected(c, schema, v);
    }
    if (json_is_array(v) && validate_array(c, schema, v)) return -1;
    if (json_is_object(v) && (json_object_get(schema, "properties") ||
                              json_object_get(schema, "required") ||
                              json_object_get(schema, "additionalProperties")) &&
        validate_object(c, schema, v))
        return -1;
    if ((k = json_object_get(schema, "oneOf")) && validate_oneof(c, schema, k, v)) return -1;
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* defaults */

static void apply_defaults(const json_t *root, const json_t *schema, json_t *v)
{
    schema = resolve_ref(root, schema);
    if (!schema || !json_is_object(schema)) return;
    const json_t *one = json_object_get(schema, "oneOf");
    if (one) {
        size_t i;
        const json_t *b;
        json_array_foreach(one, i, b) {
            gp_spec_problem tmp;
            vctx sub = {.root = root, .p = &tmp};
            if (validate(&sub, b, v) == 0) {
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

static json_t *with_defaults_k(const json_t *spec, int k)
{
    json_t *copy = json_deep_copy(spec);
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
/* polygon checks */

typedef struct pt {
    double x, y;
} pt;

static double orient(pt a, pt b, pt c)
{
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

static int sgn(double v) { return (v > 0) - (v < 0); }

static int on_segment(pt a, pt b, pt q)
{
    return fmin(a.x, b.x) <= q.x && q.x <= fmax(a.x, b.x) && fmin(a.y, b.y) <= q.y &&
           q.y <= fmax(a.y, b.y);
}

/* closed segments [a,b] and [c,d] share a point */
static int seg_intersect(pt a, pt b, pt c, pt d)
{
    int o1 = sgn(orient(a, b, c)), o2 = sgn(orient(a, b, d));
    int o3 = sgn(orient(c, d, a)), o4 = sgn(orient(c, d, b));
    if (o1 != o2 && o3 != o4) return 1;
    if (o1 == 0 && on_segment(a, b, c)) return 1;
    if (o2 == 0 && on_segment(a, b, d)) return 1;
    if (o3 == 0 && on_segment(c, d, a)) return 1;
    if (o4 == 0 && on_segment(c, d, b)) return 1;
    return 0;
}

static double ring_area(const gp_vec2 *p, size_t n)
{
    double s = 0;
    for (size_t i = 1; i + 1 < n; i++)
        s += (p[i].x - p[0].x) * (p[i + 1].y - p[0].y) - (p[i + 1].x - p[0].x) * (p[i].y - p[0].y);
    return 0.5 * s;
}

static int point_in_ring(const gp_vec2 *p, size_t n, gp_vec2 q)
{
    int in = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++) {
        if ((p[i].y > q.y) != (p[j].y > q.y)) {
            double x = p[j].x + (q.y - p[j].y) * (p[i].x - p[j].x) / (p[i].y - p[j].y);
            if (q.x < x) in = !in;
        }
    }
    return in;
}

typedef struct edge {
    size_t ring, i;  /* ring index (0 = outer, 1.. = holes), edge from vertex i to i+1 */
    double xmin, xmax;
} edge;

static int edge_cmp(const void *a, const void *b)
{
    double x = ((const edge *)a)->xmin, y = ((const edge *)b)->xmin;
    return (x > y) - (x < y);
}

static void ring_pointer(char *buf, size_t n, size_t ring)
{
    if (ring == 0) snprintf(buf, n, "/container/polygon");
    else snprintf(buf, n, "/container/holes/%zu", ring - 1);
}

/* rings[0] is the outer ring; checks area, simplicity, and that holes lie inside the outer ring
 * and outside one another. Returns 0 or -1 with *p filled (422), or -2 for out of memory. */
static int check_rings(const gp_ring *rings, size_t nr, gp_spec_problem *p)
{
    char ptr[64];
    size_t ne = 0;
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
        ne += g->n;
    }
    edge *e = malloc(ne * sizeof *e);
    if (!e) return -2;
    size_t k = 0;
    for (size_t r = 0; r < nr; r++)
        for (size_t i = 0; i < rings[r].n; i++) {
            gp_vec2 a = rings[r].pts[i], b = rings[r].pts[(i + 1) % rings[r].n];
            e[k].ring = r;
            e[k].i = i;
            e[k].xmin = fmin(a.x, b.x);
            e[k].xmax = fmax(a.x, b.x);
            k++;
        }
    qsort(e, ne, sizeof *e, edge_cmp);
    int rc = 0;
    for (size_t u = 0; u < ne && !rc; u++) {
        const gp_ring *ru = &rings[e[u].ring];
        pt a = {ru->pts[e[u].i].x, ru->pts[e[u].i].y};
        pt b = {ru->pts[(e[u].i + 1) % ru->n].x, ru->pts[(e[u].i + 1) % ru->n].y};
        for (size_t w = u + 1; w < ne && e[w].xmin <= e[u].xmax; w++) {
            const gp_ring *rw = &rings[e[w].ring];
            pt c = {rw->pts[e[w].i].x, rw->pts[e[w].i].y};
            pt d = {rw->pts[(e[w].i + 1) % rw->n].x, rw->pts[(e[w].i + 1) % rw->n].y};
            size_t i = e[u].i, j = e[w].i, n = ru->n;
            if (e[u].ring == e[w].ring) {
                /* adjacent edges share a vertex: only a fold back (collinear overlap) is bad */
                int next = (i + 1) % n == j, prev = (j + 1) % n == i;
                if (next || prev) {
                    pt p0 = next ? a : c, p1 = next ? b : d, p2 = next ? d : b;
                    if (orient(p0, p1, p2) == 0 &&
                        (p1.x - p0.x) * (p2.x - p1.x) + (p1.y - p0.y) * (p2.y - p1.y) < 0) {
                        ring_pointer(ptr, sizeof ptr, e[u].ring);
                        set_problem(p, 422, ptr,
                                    "the polygon is not simple: edges %zu and %zu fold back onto "
                                    "each other", next ? i : j, next ? j : i);
                        rc = -1;
                        break;
                    }
                    continue;
                }
            }
            if (seg_intersect(a, b, c, d)) {
                size_t r1 = e[u].ring < e[w].ring ? e[u].ring : e[w].ring;
                size_t r2 = e[u].ring < e[w].ring ? e[w].ring : e[u].ring;
                /* (r1, e1) is the edge of the lower ring (or the lower edge of one ring) */
                int swap = e[u].ring > e[w].ring || (e[u].ring == e[w].ring && i > j);
                size_t e1 = swap ? j : i, e2 = swap ? i : j;
                if (r1 == r2) {
                    ring_pointer(ptr, sizeof ptr, r1);
                    set_problem(p, 422, ptr,
                                "the polygon is not simple: edge %zu (from point %zu) crosses or "
                                "touches edge %zu (from point %zu)", e1, e1, e2, e2);
                } else {
                    char other[64];
                    ring_pointer(ptr, sizeof ptr, r2);
                    ring_pointer(other, sizeof other, r1);
                    set_problem(p, 422, ptr,
                                "edge %zu of this hole crosses or touches edge %zu of %s", e2, e1,
                                other);
                }
                rc = -1;
                break;
            }
        }
    }
    free(e);
    if (rc) return rc;
    for (size_t r = 0; r < nr; r++) {
        double scale = 0;
        for (size_t i = 1; i < rings[r].n; i++)
            scale = fmax(scale, fmax(fabs(rings[r].pts[i].x - rings[r].pts[0].x),
                                     fabs(rings[r].pts[i].y - rings[r].pts[0].y)));
        if (!(fabs(ring_area(rings[r].pts, rings[r].n)) > 1e-12 * scale * scale)) {
            ring_pointer(ptr, sizeof ptr, r);
            set_problem(p, 422, ptr, "the polygon has no area");
            return -1;
        }
    }
    /* no crossings: a hole is inside the outer ring iff one of its vertices is */
    for (size_t r = 1; r < nr; r++) {
        ring_pointer(ptr, sizeof ptr, r);
        if (!point_in_ring(rings[0].pts, rings[0].n, rings[r].pts[0])) {
            set_problem(p, 422, ptr, "the hole is not inside the container polygon");
            return -1;
        }
        for (size_t s = 1; s < nr; s++)
            if (s != r && point_in_ring(rings[s].pts, rings[s].n, rings[r].pts[0])) {
                set_problem(p, 422, ptr, "the hole lies inside hole %zu", s - 1);
                return -1;
            }
    }
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

void gp_spec_2d_free(gp_spec2d *s)
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

/* container: a circle, or a polygon with its holes (simple, holes inside and apart) */
static int parse_container_2d(const json_t *cont, gp_spec2d *out, gp_spec_problem *p)
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
        int rc = check_rings(rings, nh + 1, p);
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
        if (!strcmp(s, "grains")) bits |= GP_OUT_GRAINS;
        else if (!strcmp(s, "odec")) bits |= GP_OUT_ODEC;
        else if (!strcmp(s, "descriptors")) bits |= GP_OUT_DESCRIPTORS;
        else if (!strcmp(s, "cells")) bits |= GP_OUT_CELLS;
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

/* fills out from a valid spec with defaults applied (settle_defaults_2d); semantic checks;
 * 0 / -1 */
static int parse_2d_full(const json_t *full, gp_spec2d *out, gp_spec_problem *p)
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
    if (parse_container_2d(json_object_get(full, "container"), out, p) ||
        parse_size_2d(json_object_get(full, "size"), out, p) ||
        parse_shape_2d(json_object_get(full, "shape"), out, p))
        return -1;
    size_t n = 0;
    if (cell_count_2d(out, &n, p)) return -1;
    return check_threshold_2d(out, n, p);
}

static int semantic_2d(const json_t *full, gp_spec_problem *p)
{
    gp_spec2d tmp;
    int rc = parse_2d_full(full, &tmp, p);
    gp_spec_2d_free(&tmp);
    return rc;
}

int gp_spec_parse_2d(const json_t *spec, gp_spec2d *out, gp_spec_problem *p)
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
        rc = parse_2d_full(full, out, p);
    json_decref(full);
    if (rc) gp_spec_2d_free(out);
    return rc;
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
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* 3D parser */

void gp_spec_3d_free(gp_spec3d *s)
{
    if (!s) return;
    free((gp_sieve_row *)s->sieve);
    memset(s, 0, sizeof *s);
}

int gp_spec_parse_3d(const json_t *spec, gp_spec3d *out, gp_spec_problem *p)
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
