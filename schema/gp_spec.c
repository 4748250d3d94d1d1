/* gp_spec.c -- what the kinds share: the table of kinds and the dispatch on it, the schemas
 * (loaded once), the effective spec (schema, defaults, semantic checks), the bounds entry
 * points, and the helpers of the kind files (problems, sieve rows, the work budget, the
 * reader of effective specs). See gp_spec.h and gp_spec_internal.h. */
#include "gp_spec_internal.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const unsigned char gp_schema_text_combined[];

/* the kinds, in the order of gp_spec_kinds() and of the combined document */
#define g_kinds gp_spec_kind_table
#define NKINDS GP_SPEC_NKINDS

static const char *g_names[NKINDS + 1];
static json_t *g_schema[NKINDS];
static int g_schema_ok = 0;
static pthread_once_t g_once = PTHREAD_ONCE_INIT;

static void load_schemas(void)
{
    g_schema_ok = 1;
    for (size_t k = 0; k < NKINDS; k++) {
        g_names[k] = g_kinds[k]->name;
        g_schema[k] = gp_schema_load((const char *)g_kinds[k]->schema_text, g_kinds[k]->name);
        if (!g_schema[k]) g_schema_ok = 0;
    }
    g_names[NKINDS] = NULL;
}

const char *const *gp_spec_kinds(void)
{
    pthread_once(&g_once, load_schemas);
    return g_names;
}

const char *gp_schema_document(void) { return (const char *)gp_schema_text_combined; }

static const gp_spec_kind *kind_named(const char *name)
{
    for (size_t k = 0; name && k < NKINDS; k++)
        if (!strcmp(name, g_kinds[k]->name)) return g_kinds[k];
    return NULL;
}

const char *gp_schema_text(const char *kind)
{
    const gp_spec_kind *k = kind_named(kind);
    return k ? (const char *)k->schema_text : NULL;
}

const json_t *gp_spec_schema(const gp_spec_kind *k)
{
    pthread_once(&g_once, load_schemas);
    for (size_t i = 0; i < NKINDS; i++)
        if (g_kinds[i] == k) return g_schema_ok ? g_schema[i] : NULL;
    return NULL;
}

/* the kinds for messages: "a", "b" */
static void kind_list(char *buf, size_t n)
{
    size_t len = 0;
    buf[0] = 0;
    for (size_t k = 0; k < NKINDS && len < n; k++)
        len += (size_t)snprintf(buf + len, n - len, "%s\"%s\"", k ? ", " : "", g_kinds[k]->name);
}

/* ------------------------------------------------------------------------------------------ */
/* problems */

gp_spec_problem *gp_spec_begin(gp_spec_problem *p, gp_spec_problem *local)
{
    if (!p) p = local;
    memset(p, 0, sizeof *p);
    return p;
}

int gp_spec_no_memory(gp_spec_problem *p) { return gp_problem(p, "internal", "", "out of memory"); }

int gp_spec_too_large(gp_spec_problem *p, const char *pointer, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    gp_problemv(p, "too_large", pointer, fmt, ap);
    va_end(ap);
    return -1;
}

const char *gp_spec_advice_for(const gp_spec_advice *rows, const char *pointer)
{
    for (; rows->pointer; rows++)
        if (!strcmp(rows->pointer, pointer)) break;
    return rows->text;
}

int gp_spec_over_budget(const gp_spec_bounds_t *b, const char *what,
                        const gp_spec_advice *advice, gp_spec_problem *p)
{
    if (b->work_s <= GP_SPEC_WORK_BUDGET_S) return 0;
    return gp_spec_too_large(p, b->work_pointer,
                             "the job would take about %.2g s of one core (%s), over the budget "
                             "of %.0f s; %s", b->work_s, what, GP_SPEC_WORK_BUDGET_S,
                             gp_spec_advice_for(advice, b->work_pointer));
}

/* ------------------------------------------------------------------------------------------ */
/* sieve curves (3D sieve, 2D size.sieve) */

int gp_spec_check_sieve_rows(const json_t *sieve, const char *base, gp_spec_problem *p)
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
            return gp_problem(p, "invalid_spec", ptr,
                              "sieve diameters must increase strictly: %.15g follows %.15g", d,
                              prev_d);
        }
        if (i > 0 && q < prev_q) {
            snprintf(ptr, sizeof ptr, "%s/%zu/1", base, i);
            return gp_problem(p, "invalid_spec", ptr,
                              "percent passing must not decrease: %.15g follows %.15g", q, prev_q);
        }
        if (i == 0 && q != 0) {
            snprintf(ptr, sizeof ptr, "%s/0/1", base);
            return gp_problem(p, "invalid_spec", ptr, "the first sieve row must pass 0 %% (the "
                              "smallest grain), got %.15g", q);
        }
        prev_d = d;
        prev_q = q;
    }
    if (n && prev_q != 100) {
        snprintf(ptr, sizeof ptr, "%s/%zu/1", base, n - 1);
        return gp_problem(p, "invalid_spec", ptr, "the last sieve row must pass 100 %%, got %.15g",
                          prev_q);
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* the effective spec */

/* schema validation only: the spec's kind, or NULL with *p */
static const gp_spec_kind *schema_validate(const json_t *spec, gp_spec_problem *p)
{
    char g[80], list[256];
    if (!json_is_object(spec)) {
        gp_schema_describe_value(spec, g, sizeof g);
        gp_problem(p, "invalid_spec", "", "expected a JSON object with a \"kind\" field, got %s",
                   g);
        return NULL;
    }
    const json_t *kind = json_object_get(spec, "kind");
    const gp_spec_kind *k = kind_named(json_string_value(kind));
    if (!k) {
        if (!kind) snprintf(g, sizeof g, "nothing (the field is missing)");
        else gp_schema_describe_value(kind, g, sizeof g);
        kind_list(list, sizeof list);
        gp_problem(p, "invalid_spec", "/kind", "unknown kind %s; expected one of %s", g, list);
        return NULL;
    }
    const json_t *schema = gp_spec_schema(k);
    if (!schema) {
        gp_problem(p, "internal", "", "the embedded schema of kind %s is broken", k->name);
        return NULL;
    }
    if (gp_schema_validate(schema, spec, p) == 0) return k;
    if (k->explain) k->explain(spec, p);
    return NULL;
}

/* the schema, the kind's rules on the posted spec, then every default; *k the kind. NULL with
 * *p filled */
static json_t *effective(const json_t *spec, const gp_spec_kind **k, gp_spec_problem *p)
{
    *k = schema_validate(spec, p);
    if (!*k || ((*k)->check_posted && (*k)->check_posted(spec, p))) return NULL;
    json_t *full = gp_schema_copy_objects(spec);
    if (full) gp_schema_apply_defaults(gp_spec_schema(*k), full);
    if (!full || ((*k)->settle_defaults && (*k)->settle_defaults(full))) {
        json_decref(full);
        gp_spec_no_memory(p);
        return NULL;
    }
    return full;
}

json_t *gp_spec_with_defaults(const json_t *spec, gp_spec_problem *p)
{
    gp_spec_problem local;
    p = gp_spec_begin(p, &local);
    const gp_spec_kind *k;
    json_t *full = effective(spec, &k, p);
    if (full && k->check(full, p)) {
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
/* work and result bounds */

int gp_spec_bounds(const json_t *effective_spec, gp_spec_bounds_t *out, gp_spec_problem *p)
{
    gp_spec_problem local;
    p = gp_spec_begin(p, &local);
    memset(out, 0, sizeof *out);
    const gp_spec_kind *k = kind_named(json_string_value(json_object_get(effective_spec, "kind")));
    if (!k) {
        char list[256];
        kind_list(list, sizeof list);
        return gp_problem(p, "invalid_spec", "/kind", "unknown kind; expected one of %s", list);
    }
    return k->bounds(effective_spec, out, p);
}

int gp_spec_check_result(const json_t *effective_spec, double max_bytes, gp_spec_problem *p)
{
    gp_spec_problem local;
    if (!p) p = &local;
    gp_spec_bounds_t b;
    if (gp_spec_bounds(effective_spec, &b, p)) return -1;
    if (b.result_bytes <= max_bytes) return 0;
    const gp_spec_kind *k = kind_named(json_string_value(json_object_get(effective_spec, "kind")));
    return gp_spec_too_large(p, b.result_pointer,
                             "the result would be about %.0f MB (%.0f %s), over this server's "
                             "limit of %.0f MB (--max-result-mb); ask for fewer %s",
                             b.result_bytes / 1e6, b.items, k->items, max_bytes / 1e6,
                             gp_spec_advice_for(k->result_advice, b.result_pointer));
}

/* ------------------------------------------------------------------------------------------ */
/* reading an effective spec */

int gp_spec_read_begin(const gp_spec_kind *k, const json_t *spec, void *out, size_t size,
                       gp_spec_problem *p)
{
    memset(out, 0, size);
    const json_t *kind = json_object_get(spec, "kind");
    if (json_is_string(kind) && !strcmp(json_string_value(kind), k->name)) return 0;
    char g[80];
    gp_schema_describe_value(kind, g, sizeof g);
    return gp_problem(p, "invalid_spec", "/kind", "expected \"%s\" here, got %s", k->name, g);
}

void gp_rd_bad(gp_spec_reader *r, const char *ptr)
{
    if (!r->bad) r->bad = ptr;
}

const json_t *gp_rd_member(gp_spec_reader *r, const json_t *o, const char *ptr, json_type type,
                           int optional)
{
    const char *slash = strrchr(ptr, '/');
    const json_t *v = json_object_get(o, slash ? slash + 1 : ptr);
    if (!v && optional) return NULL;
    if (!v || (type == JSON_REAL ? !json_is_number(v) : json_typeof(v) != type)) {
        gp_rd_bad(r, ptr);
        return NULL;
    }
    return v;
}

double gp_rd_value(gp_spec_reader *r, const json_t *v, const char *ptr, double lo, double hi)
{
    double x = json_number_value(v);
    if (json_is_number(v) && x >= lo && x <= hi) return x;
    gp_rd_bad(r, ptr);
    return 0;
}

const json_t *gp_rd_array(gp_spec_reader *r, const json_t *o, const char *ptr, size_t min,
                          size_t max, int optional)
{
    const json_t *a = gp_rd_member(r, o, ptr, JSON_ARRAY, optional);
    size_t n = json_array_size(a);
    if (!a || (n >= min && n <= max)) return a;
    gp_rd_bad(r, ptr);
    return NULL;
}

double gp_rd_num(gp_spec_reader *r, const json_t *o, const char *ptr, double lo, double hi)
{
    return gp_rd_value(r, gp_rd_member(r, o, ptr, JSON_REAL, 0), ptr, lo, hi);
}

/* the index of string v among names, or -1 */
static int name_index(const json_t *v, const char *const *names, int n)
{
    const char *s = json_string_value(v);
    for (int i = 0; s && i < n; i++)
        if (!strcmp(s, names[i])) return i;
    return -1;
}

int gp_rd_enum(gp_spec_reader *r, const json_t *o, const char *ptr, const char *const *names,
               int n)
{
    int i = name_index(gp_rd_member(r, o, ptr, JSON_STRING, 0), names, n);
    if (i >= 0) return i;
    gp_rd_bad(r, ptr);
    return 0;
}

unsigned gp_rd_flags(gp_spec_reader *r, const json_t *o, const char *ptr,
                     const char *const *names, int n)
{
    unsigned bits = 0;
    size_t i;
    const json_t *v;
    json_array_foreach(gp_rd_member(r, o, ptr, JSON_ARRAY, 0), i, v) {
        int k = name_index(v, names, n);
        if (k < 0) gp_rd_bad(r, ptr);
        else bits |= 1u << k;
    }
    return bits;
}

void gp_rd_pair(gp_spec_reader *r, const json_t *v, const char *ptr, double out[2])
{
    if (json_array_size(v) != 2) gp_rd_bad(r, ptr);
    for (size_t i = 0; i < 2; i++)
        out[i] = gp_rd_value(r, json_array_get(v, i), ptr, -GP_RD_ANY, GP_RD_ANY);
}

double gp_rd_sieve_scale(gp_spec_reader *r, const json_t *o, const char *ptr)
{
    static const char *const units[] = {"mm", "m"};
    return gp_rd_enum(r, o, ptr, units, 2) == 1 ? 1.0 : 1e-3;
}

void gp_rd_row(gp_spec_reader *r, const json_t *sieve, size_t i, const char *ptr, double scale,
               double *d, double *q)
{
    double row[2];
    gp_rd_pair(r, json_array_get(sieve, i), ptr, row);
    *d = row[0] * scale;
    *q = row[1];
}

int gp_rd_finish(const gp_spec_reader *r, gp_spec_problem *p)
{
    if (!r->bad) return 0;
    return gp_problem(p, "internal", r->bad, "not an effective spec: missing or malformed here "
                      "(the parsers read only what gp_spec_with_defaults returns)");
}
