/* kind.h -- the job kinds of grainpackd: one type object per kind, and their table.
 *
 * A kind is everything the daemon knows of one pipeline: its name (the spec's "kind"), how its
 * spec is bounded and parsed for the core (schema/gp_spec.h), how a job of it is built,
 * reported, written (the result JSON, result_json.h) and packed for export (core/export), the
 * SVG views of its result, its export formats and the example spec the dashboard offers. The
 * HTTP front, the workers, the SVG renderer and the dashboard look a kind up once, by name
 * (gpd_kind_find), and go through its struct: no other file names a kind. A new kind is one
 * folder, kinds/<kind>/ (its gpd_kind, views and pictures; its spec in schema/kinds/<kind>/),
 * and one line of the table in kinds.c.
 *
 * The pointers a kind hands around for its spec and its specimen (void *) are its own core
 * structs (gp_spec2d / gp_specimen2d, ...); only its own functions look inside. */
#ifndef GPD_KIND_H
#define GPD_KIND_H

#include <stddef.h>

#include <jansson.h>

#include "gp_error.h"
#include "gp_progress.h"
#include "gp_spec.h"
#include "jobs/progress.h"
#include "jobs/result_json.h"
#include "svg/svg_view.h"
#include "util/util.h"

/* A view of the SVG renderer: ?view=name draws it. */
typedef struct gpd_view {
    const char *name;
    const char *options; /* the query options it reads besides width, comma-separated ("" none) */
    gp_svg_view_fn open;
    /* the member of the result's summary the view draws from, as a dotted path
     * ("stats.transfer"), when only some results have it (NULL: every result): the dashboard
     * offers the view only where it is */
    const char *needs;
} gpd_view;

/* What the submit path lets a kind read of another job (gpd_kind.resolve): 0 with the job's
 * kind and status, (*spec, a new reference) its effective spec and, when summary is not NULL
 * and the job has succeeded, (*summary, a new reference) its result's summary
 * (store_get_summary; else NULL); 1 when there is no job of that id; -1 when the store
 * failed. */
typedef int (*gpd_job_lookup)(const char *id, char kind[64], char status[16], json_t **spec,
                              json_t **summary);

/* An export a kind writes itself, from its stored result's summary (store_get_summary), rather
 * than from an export pack (core/export): what does not fit a pack, such as curves. */
typedef struct gpd_kind_export {
    const char *format;    /* ?format= */
    const char *extension; /* of the file name, without the dot */
    const char *mime;
    /* the file (malloc'ed, *len bytes) of a succeeded job's summary; NULL with err (409 when
     * the result lacks what it needs, naming the output to ask for; 500) */
    char *(*write)(const json_t *summary, size_t *len, gpd_err *err);
} gpd_kind_export;

typedef struct gpd_kind {
    const char *name;
    /* a spec of this kind (JSON): the dashboard's example */
    const char *example;

    /* ---- POST /v1/jobs: the body as posted, before it is validated (NULL: nothing) ---- */
    /* Replaces, in place, what spec refers to in another job by what the worker needs of it,
     * read now (lookup) so that a bad reference is refused at submit and the job never reads
     * the other one (which may be purged meanwhile): 0, or -1 with *p (invalid_spec at the
     * reference; "internal" when the store failed). The spec is not validated yet: the hook
     * leaves what it does not understand to the schema. */
    int (*resolve)(json_t *spec, gpd_job_lookup lookup, gp_spec_problem *p);

    /* ---- POST /v1/jobs: a valid effective spec (gp_spec_with_defaults) ---- */
    /* Its estimated result against max_bytes: 0, or -1 with *p (422 too_large, or from the
     * estimate itself); both kinds use schema's gp_spec_check_result */
    int (*bounds)(const json_t *spec, double max_bytes, gp_spec_problem *p);
    /* The job object's "brief" (README, "Extensions to api.md"): a new object
     *   {"particles": N or null, "seed": S,
     *    "headline": {"name": "<the spec's headline target>", "target": x, "achieved": y|null}}
     * of a valid effective spec; stats is the result's "stats" once the job has succeeded, NULL
     * before (achieved null, and particles null where only the run tells it). NULL on out of
     * memory. A few dozen bytes: every row of GET /v1/jobs carries it. */
    json_t *(*brief)(const json_t *spec, const json_t *stats);

    /* ---- running a job (workers.c), in this order ---- */
    /* GPD_KIND_CORE_OPS: the glue to the kind's core pipeline (GPD_KIND_CORE below) */
    size_t spec_size; /* the core's spec struct */
    /* Parses the stored spec into *spec (spec_size zeroed bytes) for the core, to run on
     * `threads` threads (the daemon's --job-threads; the core's result does not depend on it):
     * 0, or -1 with *p; free_spec releases what it holds either way */
    int (*read_spec)(const json_t *json, void *spec, int threads, gp_spec_problem *p);
    void (*free_spec)(void *spec);
    /* Builds the specimen (the core's build): *st GP_OK, or a failure with err; the specimen may
     * come back with a failure too (freed with destroy) */
    void *(*build)(const void *spec, gp_progress_fn progress, void *user,
                   const volatile int *cancel, gp_status *st, gp_error *err);
    void (*destroy)(void *specimen);
    /* The "detail" of a progress report (a new object) */
    json_t *(*progress_detail)(const gp_progress *p);
    /* The phases a job of this spec goes through, in order, each with its expected seconds on
     * one core (progress.h: the daemon's fraction and ETA weigh the phases by them), the last
     * "result" (building, packing and storing the result): how many, at most max. spec is the
     * core's parsed spec, spec_json the effective spec. */
    int (*plan)(const void *spec, const json_t *spec_json, gpd_phase *out, int max);
    /* The expected seconds of the "result" phase for this specimen (its size now known) */
    double (*result_cost)(const void *specimen);
    /* Writes the result JSON into w as it reads the specimen (result_json.h; the writer stops
     * by itself when its cancel flag comes up, and says so), and returns its head: the result
     * without its per-item arrays (kind, seed, stats, timings, ...: what the brief and the
     * metrics read), a new object; NULL on out of memory */
    json_t *(*result)(const void *specimen, const void *spec, const json_t *spec_json,
                      gpd_jw *w);
    /* The export pack (core/export): 0 with a malloc'ed *pack, 1 when the spec asked for no
     * output a pack is made of (*pack left NULL), -1 with err. A pack flagged
     * GP_EXPORT_VIEW_ONLY is drawn by the SVG views and answered 409 by the exports, as no
     * pack is (pack_what, pack_output) */
    int (*pack)(const void *specimen, const void *spec, void **pack, size_t *len,
                gp_error *err);
    /* The "detail" of the final "done" progress (a new object; NULL: none, {}) */
    json_t *(*done_detail)(const char *id, const void *specimen);
    /* A note appended to the message of a failed build (may be NULL) */
    void (*failure_note)(const void *specimen, char *buf, size_t n);

    /* ---- a finished job ---- */
    /* its SVG views, ending with a NULL name; the first is the dashboard's default */
    const gpd_view *views;
    /* 1 when a result without a "kind" member is of this kind (NULL: never) */
    int (*owns_result)(const json_t *result);
    /* the dimension of its packs: its export formats (gp_export_format_supports); 0: no packs,
     * no formats of core/export */
    int export_dim;
    /* the exports it writes itself (ending with a NULL format; NULL: none), listed before and
     * served instead of core/export's formats of the same name */
    const gpd_kind_export *exports;
    /* a job without a pack: "job ... has no <pack_what> to export ... with <pack_output> in
     * outputs" */
    const char *pack_what, *pack_output;
    /* the phases of its result's "timings" (seconds), "total" among them, ending with NULL: the
     * job duration histograms of GET /metrics (metrics.h), observed once a job succeeds */
    const char *const *phases;
} gpd_kind;

/* The glue between a kind and its core pipeline, the same for every kind but for the names: a
 * kind file says GPD_KIND_CORE(its spec type, reader, freer, specimen type, builder,
 * destroyer) to define its read_spec, free_spec, build and destroy, and puts
 * GPD_KIND_CORE_OPS(its spec type) in its gpd_kind. */
#define GPD_KIND_CORE(SPEC, READ, FREE, SPECIMEN, BUILD, DESTROY)                              \
    static int read_spec(const json_t *json, void *spec, int threads, gp_spec_problem *p)     \
    {                                                                                          \
        int rc = READ(json, spec, p);                                                          \
        ((SPEC *)spec)->threads = threads;                                                     \
        return rc;                                                                             \
    }                                                                                          \
    static void free_spec(void *spec) { FREE(spec); }                                          \
    static void *build(const void *spec, gp_progress_fn progress, void *user,                  \
                       const volatile int *cancel, gp_status *st, gp_error *err)               \
    {                                                                                          \
        SPECIMEN *out = NULL;                                                                  \
        *st = BUILD(spec, progress, user, cancel, &out, err);                                  \
        return out;                                                                            \
    }                                                                                          \
    static void destroy(void *specimen) { DESTROY(specimen); }

#define GPD_KIND_CORE_OPS(SPEC)                                                                \
    .spec_size = sizeof(SPEC), .read_spec = read_spec, .free_spec = free_spec, .build = build,  \
    .destroy = destroy

/* The kind of that name, or NULL. */
const gpd_kind *gpd_kind_find(const char *name);
/* The kind of a result without a "kind" member: the first that owns it, else the first of the
 * table. */
const gpd_kind *gpd_kind_guess(const json_t *result);
/* The reference ref = {"job": id, ...} (at pointer ptr of the spec) to a succeeded job of kind
 * want, for a resolve hook: 0 with *spec (the job's effective spec) and, when summary is not
 * NULL, *summary (its result's summary), new references; 1 when there is nothing to resolve
 * (ref has no "job" string; or the job is gone and ref already holds member kept, its copy
 * made when it was resolved); -1 with *p: invalid_spec at ptr/job (no such job, another kind,
 * not succeeded) or internal (the store failed). */
int gpd_resolve_job(const json_t *ref, const char *ptr, const char *want, const char *kept,
                    gpd_job_lookup lookup, json_t **spec, json_t **summary, gp_spec_problem *p);

/* A resolve hook for a spec whose "specimen" may be {"job": id} of a succeeded sphere
 * packing (schema/gp_spec_specimen.h): the job's effective spec put at "spec" beside the id. */
int gpd_resolve_specimen(json_t *spec, gpd_job_lookup lookup, gp_spec_problem *p);

/* The i-th kind of the table (0-based), NULL past its end. */
const gpd_kind *gpd_kind_at(size_t i);
/* Its index in the table, -1 when it is not there. */
int gpd_kind_index(const gpd_kind *k);
/* k's view of that name, or NULL. */
const gpd_view *gpd_kind_view(const gpd_kind *k, const char *name);

/* k's own export of that format (gpd_kind.exports), or NULL. */
const gpd_kind_export *gpd_kind_export_find(const gpd_kind *k, const char *format);
/* The names of k's export formats, its own then core/export's, ", "-separated, into buf. */
void gpd_kind_export_list(const gpd_kind *k, char *buf, size_t n);

/* The names of k's views, ", "-separated ("packing, cells, ..."), into buf. */
void gpd_kind_view_list(const gpd_kind *k, char *buf, size_t n);
/* The names of the kinds, each between quote and quote, sep between two, into buf (e.g. quote
 * "\"", sep ", ": "\"a\", \"b\""). */
void gpd_kind_names(char *buf, size_t n, const char *quote, const char *sep);

/* A brief (see gpd_kind.brief) with the seed and the headline's target read from spec: its
 * member `headline` (a number); particles and achieved are taken (NULL: null). */
json_t *gpd_brief_new(const json_t *spec, const char *headline, json_t *particles,
                      json_t *achieved);
/* The brief of a kind of one grain a cell (the Fourier-Voronoi kinds): the grains (the spec's
 * count, or the one its sieve law derives, as the run will; once succeeded those the run made)
 * and the solid fraction. */
json_t *gpd_brief_cells(const json_t *spec, const json_t *stats);
/* The brief of a stored job as text (malloc'ed; NULL when its kind is unknown here or its texts
 * do not parse): kind, its effective spec and, once it has succeeded, its result summary
 * (store_get_summary; NULL before). The store fills in the briefs of jobs stored by an older
 * daemon with it (store_fill_briefs). */
char *gpd_brief_text(const char *kind, const char *spec, const char *summary);

/* What the dashboard knows of the kinds (a new object, NULL on out of memory):
 * {"<name>": {"example": <spec>, "views": [{"name", "options": [...]}, ...],
 *             "exports": ["lammps", ...]}, ...} in table order. */
json_t *gpd_kinds_json(void);

#endif /* GPD_KIND_H */
