/* gp_spec_specimen.c -- the sphere specimen of a kind's spec (see gp_spec_specimen.h). */
#include "gp_spec_internal.h"

#include "gp_spec_specimen.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

extern const gp_spec_kind gp_spec_kind_spheres_3d;

const char *gp_spec_specimen_kind(void) { return gp_spec_kind_spheres_3d.name; }

int gp_spec_specimen_problem(const gp_spec_problem *q, gp_spec_problem *p)
{
    char ptr[sizeof p->pointer];
    snprintf(ptr, sizeof ptr, "/specimen/spec%.240s", q->pointer);
    const char *head = q->pointer[0] ? q->pointer : "spec", *m = q->message;
    size_t n = strlen(head);
    if (!strncmp(m, head, n) && m[n] == ':') m += n + 1 + (m[n + 1] == ' ');
    return gp_problem(p, q->code, ptr, "%s", m);
}

/* the specimen's spec as posted in spec, made a sphere-packing spec: its kind (which may be
 * left out) and, when it has none, the enclosing spec's seed; a new object, or NULL with *p */
static json_t *posted(const json_t *spec, gp_spec_problem *p)
{
    json_t *in = json_object_get(json_object_get(spec, "specimen"), "spec");
    const json_t *kind = json_object_get(in, "kind"), *seed = json_object_get(spec, "seed");
    const char *want = gp_spec_specimen_kind();
    if (kind && !(json_is_string(kind) && !strcmp(json_string_value(kind), want))) {
        char g[80];
        gp_schema_describe_value(kind, g, sizeof g);
        gp_problem(p, "invalid_spec", "/specimen/spec/kind",
                   "expected \"%s\" (a specimen is a sphere packing), got %s", want, g);
        return NULL;
    }
    json_t *c = json_copy(in);
    if (!c || (!kind && json_object_set_new(c, "kind", json_string(want))) ||
        (seed && !json_object_get(c, "seed") && json_object_set(c, "seed", (json_t *)seed))) {
        json_decref(c);
        gp_spec_no_memory(p);
        return NULL;
    }
    return c;
}

json_t *gp_spec_specimen_effective(const json_t *spec, gp_spec_problem *p)
{
    json_t *in = posted(spec, p);
    if (!in) return NULL;
    gp_spec_problem q;
    json_t *eff = gp_spec_with_defaults(in, &q);
    json_decref(in);
    if (!eff) gp_spec_specimen_problem(&q, p);
    return eff;
}

int gp_spec_specimen_check_posted(const json_t *spec, gp_spec_problem *p)
{
    const json_t *sp = json_object_get(spec, "specimen");
    const json_t *job = json_object_get(sp, "job"), *in = json_object_get(sp, "spec");
    if (!job && !in)
        return gp_problem(p, "invalid_spec", "/specimen", "expected {\"job\": \"<id of a "
                          "succeeded %s job>\"} or {\"spec\": {...}}, got neither",
                          gp_spec_specimen_kind());
    if (!in)
        return gp_problem(p, "invalid_spec", "/specimen/job", "job %s is not resolved: only "
                          "the daemon looks a specimen job up, at submit (give the specimen "
                          "as {\"spec\": {...}} to validate it alone)", json_string_value(job));
    json_t *eff = gp_spec_specimen_effective(spec, p);
    json_decref(eff);
    return eff ? 0 : -1;
}

int gp_spec_specimen_settle(json_t *full)
{
    gp_spec_problem q;
    json_t *eff = gp_spec_specimen_effective(full, &q);
    return eff && !json_object_set_new(json_object_get(full, "specimen"), "spec", eff) ? 0 : -1;
}

int gp_spec_specimen_bounds(const json_t *full, gp_spec_bounds_t *b, gp_spec_problem *p)
{
    gp_spec_problem q;
    const json_t *inner = json_object_get(json_object_get(full, "specimen"), "spec");
    return gp_spec_bounds(inner, b, &q) ? gp_spec_specimen_problem(&q, p) : 0;
}

int gp_spec_specimen_read(const json_t *full, gp_spec3d *out, char job[33], gp_spec_problem *p)
{
    gp_spec_reader r = {0};
    const json_t *sp = gp_rd_member(&r, full, "/specimen", JSON_OBJECT, 0);
    const json_t *id = gp_rd_member(&r, sp, "/specimen/job", JSON_STRING, 1);
    snprintf(job, 33, "%s", id ? json_string_value(id) : "");
    const json_t *inner = gp_rd_member(&r, sp, "/specimen/spec", JSON_OBJECT, 0);
    if (r.bad) return gp_rd_finish(&r, p);
    gp_spec_problem q;
    return gp_spec3d_read(inner, out, &q) ? gp_spec_specimen_problem(&q, p) : 0;
}

double gp_spec_sieve_quantile(const gp_sieve_row *rows, size_t n, double q)
{
    for (size_t k = 1; k < n; k++)
        if (rows[k].passing >= q && rows[k].passing > rows[k - 1].passing)
            return rows[k - 1].diameter + (rows[k].diameter - rows[k - 1].diameter) *
                                              fmax(0, q - rows[k - 1].passing) /
                                              (rows[k].passing - rows[k - 1].passing);
    return n ? rows[n - 1].diameter : 0;
}
