/* kinds.c -- the table of job kinds and the look-ups over it (see kind.h). */
#include "kinds/kind.h"

#include <stdio.h>
#include <string.h>

#include "gp_export.h"
#include "gp_spec_specimen.h"

/* The table: one line a kind, in the order the dashboard and the messages list them; the first
 * is the kind a result without "kind" falls back to. */
#define GPD_KINDS(X)          \
    X(gpd_kind_fv2d)          \
    X(gpd_kind_spheres3d)     \
    X(gpd_kind_triax)         \
    X(gpd_kind_geostatic)     \
    X(gpd_kind_fv3d)

#define DECLARE(k) extern const gpd_kind k;
GPD_KINDS(DECLARE)
#define ENTRY(k) &k,
static const gpd_kind *const table[] = {GPD_KINDS(ENTRY) NULL};

const gpd_kind *gpd_kind_find(const char *name)
{
    for (size_t i = 0; name && table[i]; i++)
        if (!strcmp(table[i]->name, name)) return table[i];
    return NULL;
}

const gpd_kind *gpd_kind_at(size_t i)
{
    for (size_t j = 0; table[j]; j++)
        if (j == i) return table[j];
    return NULL;
}

int gpd_kind_index(const gpd_kind *k)
{
    for (size_t i = 0; k && table[i]; i++)
        if (table[i] == k) return (int)i;
    return -1;
}

const gpd_kind *gpd_kind_guess(const json_t *result)
{
    for (size_t i = 0; table[i]; i++)
        if (table[i]->owns_result && table[i]->owns_result(result)) return table[i];
    return table[0];
}

const gpd_view *gpd_kind_view(const gpd_kind *k, const char *name)
{
    for (const gpd_view *v = k->views; name && v->name; v++)
        if (!strcmp(v->name, name)) return v;
    return NULL;
}

/* appends "<quote>word<quote>" to buf, after sep unless it is the first */
static void join(char *buf, size_t n, int first, const char *sep, const char *quote,
                 const char *word)
{
    size_t at = strlen(buf);
    if (at < n) snprintf(buf + at, n - at, "%s%s%s%s", first ? "" : sep, quote, word, quote);
}

const gpd_kind_export *gpd_kind_export_find(const gpd_kind *k, const char *format)
{
    for (const gpd_kind_export *e = k->exports; format && e && e->format; e++)
        if (!strcmp(e->format, format)) return e;
    return NULL;
}

void gpd_kind_export_list(const gpd_kind *k, char *buf, size_t n)
{
    if (n) buf[0] = '\0';
    int first = 1;
    for (const gpd_kind_export *e = k->exports; e && e->format; e++, first = 0)
        join(buf, n, first, ", ", "", e->format);
    if (k->export_dim <= 0) return;
    /* core/export's formats, but those the kind writes itself */
    const char *p = gp_export_format_list(k->export_dim);
    while (*p) {
        size_t w = strcspn(p, ", ");
        char f[32];
        snprintf(f, sizeof f, "%.*s", (int)w, p);
        if (w && !gpd_kind_export_find(k, f)) join(buf, n, first, ", ", "", f), first = 0;
        p += w;
        p += strspn(p, ", ");
    }
}

void gpd_kind_view_list(const gpd_kind *k, char *buf, size_t n)
{
    if (n) buf[0] = '\0';
    for (const gpd_view *v = k->views; v->name; v++) join(buf, n, v == k->views, ", ", "", v->name);
}

void gpd_kind_names(char *buf, size_t n, const char *quote, const char *sep)
{
    if (n) buf[0] = '\0';
    for (size_t i = 0; table[i]; i++) join(buf, n, i == 0, sep, quote, table[i]->name);
}

json_t *gpd_brief_new(const json_t *spec, const char *headline, json_t *particles,
                      json_t *achieved)
{
    json_t *target = json_object_get(spec, headline);
    return json_pack("{s:o, s:O, s:{s:s, s:O, s:o}}", "particles",
                     particles ? particles : json_null(), "seed",
                     json_object_get(spec, "seed") ? json_object_get(spec, "seed") : json_null(),
                     "headline", "name", headline, "target", target ? target : json_null(),
                     "achieved", achieved ? achieved : json_null());
}

json_t *gpd_brief_cells(const json_t *spec, const json_t *stats)
{
    json_t *particles = NULL, *achieved = NULL;
    if (stats) {
        particles =
            json_deep_copy(json_object_get(json_object_get(stats, "particles"), "achieved"));
        achieved =
            json_deep_copy(json_object_get(json_object_get(stats, "solid_fraction"), "achieved"));
    } else {
        gp_spec_bounds_t b;
        gp_spec_problem p;
        if (gp_spec_bounds(spec, &b, &p) == 0 && b.cells >= 1)
            particles = json_integer((json_int_t)b.cells);
    }
    return gpd_brief_new(spec, "solid_fraction", particles, achieved);
}

char *gpd_brief_text(const char *kind, const char *spec, const char *summary)
{
    const gpd_kind *k = gpd_kind_find(kind);
    json_t *sj = k && spec ? json_loads(spec, 0, NULL) : NULL;
    json_t *rj = sj && summary ? json_loads(summary, 0, NULL) : NULL;
    json_t *b = sj ? k->brief(sj, rj ? json_object_get(rj, "stats") : NULL) : NULL;
    char *text = b ? json_dumps(b, JSON_COMPACT) : NULL;
    json_decref(b);
    json_decref(rj);
    json_decref(sj);
    return text;
}

/* "a, b, c" as ["a", "b", "c"] */
static json_t *words(const char *list)
{
    json_t *a = json_array();
    for (const char *p = list; a && p && *p;) {
        size_t w = strcspn(p, ", ");
        if (w) json_array_append_new(a, json_stringn(p, w));
        p += w;
        p += strspn(p, ", ");
    }
    return a;
}

static json_t *kind_json(const gpd_kind *k)
{
    json_t *views = json_array();
    for (const gpd_view *v = k->views; views && v->name; v++)
        json_array_append_new(views, json_pack("{s:s, s:o, s:o}", "name", v->name, "options",
                                               words(v->options), "needs",
                                               v->needs ? json_string(v->needs) : json_null()));
    char exports[256];
    gpd_kind_export_list(k, exports, sizeof exports);
    return json_pack("{s:o, s:o, s:o}", "example", json_loads(k->example, 0, NULL), "views",
                     views, "exports", words(exports));
}

json_t *gpd_kinds_json(void)
{
    json_t *all = json_object();
    for (size_t i = 0; all && table[i]; i++) {
        json_t *one = kind_json(table[i]);
        if (!one || json_object_set_new(all, table[i]->name, one)) {
            json_decref(all);
            return NULL;
        }
    }
    return all;
}

int gpd_resolve_job(const json_t *ref, const char *ptr, const char *want, const char *kept,
                    gpd_job_lookup lookup, json_t **spec, json_t **summary, gp_spec_problem *p)
{
    *spec = NULL;
    if (summary) *summary = NULL;
    const char *id = json_string_value(json_object_get(ref, "job"));
    if (!id) return 1; /* nothing to resolve (or the schema's to refuse) */
    char kind[64], status[16], at[160];
    snprintf(at, sizeof at, "%s/job", ptr);
    int rc = lookup(id, kind, status, spec, summary);
    if (rc < 0)
        return gp_problem(p, "internal", at, "the job store failed while reading job %s (see "
                          "the daemon log)", id);
    if (rc > 0 && json_object_get(ref, kept)) return 1;
    if (rc > 0)
        return gp_problem(p, "invalid_spec", at, "no job %.64s: expected a succeeded %s job",
                          id, want);
    if (!strcmp(kind, want) && !strcmp(status, "succeeded")) return 0;
    json_decref(*spec);
    *spec = NULL;
    if (summary) json_decref(*summary), *summary = NULL;
    if (strcmp(kind, want))
        return gp_problem(p, "invalid_spec", at, "job %s is of kind \"%s\": expected a "
                          "succeeded %s job", id, kind, want);
    return gp_problem(p, "invalid_spec", at, "job %s is %s, not succeeded: %s", id, status,
                      strcmp(status, "queued") && strcmp(status, "running")
                          ? "only a succeeded job can be used"
                          : "submit this spec once it has succeeded");
}

int gpd_resolve_specimen(json_t *spec, gpd_job_lookup lookup, gp_spec_problem *p)
{
    json_t *sp = json_object_get(spec, "specimen"), *js;
    int rc = gpd_resolve_job(sp, "/specimen", gp_spec_specimen_kind(), "spec", lookup, &js,
                             NULL, p);
    if (rc) return rc > 0 ? 0 : -1;
    return json_object_set_new(sp, "spec", js) ? gp_problem(p, "internal", "", "out of memory")
                                                : 0;
}
