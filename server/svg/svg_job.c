/* svg_job.c -- one SVG view of a stored job as a stream (see svg_job.h). */
#include "svg/svg_job.h"

#include <stdlib.h>
#include <string.h>

#include "util/json_scan.h"
#include "store/store.h"
#include "svg/svg_internal.h"
#include "util/util.h"

/* values up to this size are read whole, larger ones through a blob stream (as http.c) */
#define SVG_JOB_SMALL (256u * 1024u)

/* A value of the job (its export pack, its result text) as the store hands it out: in memory
 * when small, else a blob stream; opened once, when first needed. */
typedef struct job_value {
    int tried, failed;
    store_rc rc; /* the store's answer to the opening */
    store_stream *stream;
    char *mem;
    size_t len;
} job_value;

struct svg_job {
    char id[65];
    json_t *summary;
    gp_svg *svg;
    job_value pack, result;
    uint64_t spans[STORE_SUMMARY_NSKIP][2]; /* where the result's arrays are (store.h) */
};

/* opens what ("pack" or "result") of the job, the first time; v->failed when the store failed,
 * or (need) when there is no such value */
static void value_open(svg_job *j, const char *what, int need, job_value *v)
{
    if (v->tried) return;
    v->tried = 1;
    char st[16];
    v->rc = store_stream_open(j->id, what, SVG_JOB_SMALL, &v->stream, &v->mem, &v->len, st);
    v->failed = v->rc != STORE_OK || (need && !v->stream && !v->mem);
}

/* A view that could not open: for want of a database connection (busy) or of the database
 * (store error) when opening one of the job's values is why, else the view's own error */
static svg_job_rc view_failed(const svg_job *j)
{
    const job_value *v[2] = {&j->pack, &j->result};
    for (int i = 0; i < 2; i++)
        if (v[i]->rc == STORE_BUSY) return SVG_JOB_BUSY;
    for (int i = 0; i < 2; i++)
        if (v[i]->tried && v[i]->rc != STORE_OK && v[i]->rc != STORE_NOT_FOUND)
            return SVG_JOB_STORE_ERROR;
    return SVG_JOB_VIEW_ERROR;
}

/* the value's bytes, for either reader (json_scan.h, gp_export.h) */
static js_source value_source(const job_value *v)
{
    return store_value_source(v->mem, v->len, v->stream);
}

/* the index in STORE_SUMMARY_SKIP of a part's array */
static int skip_index(gp_svg_part part)
{
    static const char *const skip[] = STORE_SUMMARY_SKIP;
    for (int k = 0; k < STORE_SUMMARY_NSKIP; k++)
        if (!strcmp(skip[k], svg_items_part_name[part])) return k;
    return -1;
}

/* the items of part from the export pack, when the job has one; NULL else, or with *failed */
static gp_svg_items *pack_items(svg_job *j, gp_svg_part part, int *failed)
{
    int first = !j->pack.tried;
    value_open(j, "pack", 0, &j->pack);
    if (j->pack.failed) {
        *failed = first; /* once: later views read the result instead */
        return NULL;
    }
    if (!j->pack.stream && !j->pack.mem) return NULL;
    js_source s = value_source(&j->pack);
    gp_export_source src = {s.read, s.user, s.size};
    gp_svg_items *it = gp_svg_items_pack(&src, part);
    if (!it)
        gpd_log(GPD_LOG_WARN, "job %s: its export pack has no %s; reading the result", j->id,
                svg_items_part_name[part]);
    return it;
}

/* gp_svg_input.open: grains and spheres from the pack when there is one, else (and cells
 * always) from the result text */
static gp_svg_items *job_items(void *user, gp_svg_part part, int *failed)
{
    svg_job *j = user;
    *failed = 0;
    if (part != GP_SVG_CELLS) {
        gp_svg_items *it = pack_items(j, part, failed);
        if (it || *failed) return it;
    }
    int k = skip_index(part);
    if (k < 0 || j->spans[k][1] <= j->spans[k][0]) return NULL; /* the result has none */
    value_open(j, "result", 1, &j->result);
    if (j->result.failed) {
        *failed = 1;
        return NULL;
    }
    js_source src = value_source(&j->result);
    if (j->spans[k][1] > src.size) {
        gpd_log(GPD_LOG_ERROR, "job %s: the %s are not where the summary says", j->id,
                svg_items_part_name[part]);
        *failed = 1;
        return NULL;
    }
    gp_svg_items *it = gp_svg_items_scan(&src, j->spans[k][0], part);
    if (!it) *failed = 1;
    return it;
}

svg_job_rc svg_job_open(const char *id, const char *kind, const char *view,
                        const gp_svg_options *opt, svg_job **out, char status[16], gpd_err *err)
{
    *out = NULL;
    gpd_err_set(err, 500, "%s", "");
    char *text = NULL;
    size_t len = 0;
    uint64_t spans[STORE_SUMMARY_NSKIP][2];
    store_rc rc = store_get_summary(id, &text, &len, spans, status);
    if (rc == STORE_NOT_FOUND) return SVG_JOB_NOT_FOUND;
    if (rc != STORE_OK) return SVG_JOB_STORE_ERROR;
    if (strcmp(status, "succeeded") || !text) {
        free(text);
        return SVG_JOB_NOT_READY;
    }
    svg_job *j = calloc(1, sizeof *j);
    if (!j) {
        free(text);
        gpd_err_set(err, 500, "out of memory");
        return SVG_JOB_VIEW_ERROR;
    }
    snprintf(j->id, sizeof j->id, "%s", id);
    memcpy(j->spans, spans, sizeof spans);
    json_error_t je;
    j->summary = json_loadb(text, len, 0, &je);
    free(text);
    if (!j->summary) {
        svg_job_close(j);
        gpd_err_set(err, 500, "the stored result summary is not valid JSON");
        return SVG_JOB_VIEW_ERROR;
    }
    gp_svg_input in = {kind, j->summary, job_items, j};
    j->svg = gp_svg_open(&in, view, opt, err);
    if (!j->svg) {
        svg_job_rc rc = view_failed(j);
        svg_job_close(j);
        return rc;
    }
    *out = j;
    return SVG_JOB_OK;
}

int svg_job_read(svg_job *j, char *buf, size_t cap, size_t *n)
{
    if (gp_svg_read(j->svg, buf, cap, n) == 0) return 0;
    gpd_log(GPD_LOG_ERROR, "job %s: SVG failed mid-stream: %s", j->id, gp_svg_error(j->svg));
    return -1;
}

static void value_close(job_value *v)
{
    store_stream_close(v->stream);
    free(v->mem);
}

void svg_job_close(svg_job *j)
{
    if (!j) return;
    gp_svg_close(j->svg);
    json_decref(j->summary);
    value_close(&j->pack);
    value_close(&j->result);
    free(j);
    /* what this picture freed (the summary's tree, the items, the private connections' page
     * caches) goes back to the system, as a worker's heap does after a job */
    gpd_heap_trim();
}
