/* svg_job.c -- one SVG view of a stored job as a stream (see svg_job.h). */
#include "svg_job.h"

#include <stdlib.h>
#include <string.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "json_scan.h"
#include "store.h"

/* values up to this size are read whole, larger ones through a blob stream (as http.c) */
#define SVG_JOB_SMALL (256u * 1024u)

struct svg_job {
    char id[65];
    json_t *summary;
    gp_svg *svg;
    /* the export pack */
    int pack_tried;
    store_stream *pack_stream;
    char *pack_mem;
    size_t pack_len;
    /* the result text and where its arrays start */
    int result_tried, result_failed;
    store_stream *result_stream;
    char *result_mem;
    size_t result_len;
    js_source rsrc;
    uint64_t spans[STORE_SUMMARY_NSKIP][2]; /* where the result's arrays are (store.h) */
};

static int stream_read(void *user, uint64_t off, void *dst, size_t n)
{
    return store_stream_read(user, off, dst, n);
}

static const char *const PART[3] = {"grains", "cells", "spheres"};

/* the index in STORE_SUMMARY_SKIP of a part's array */
static int skip_index(gp_svg_part part)
{
    static const char *const skip[] = STORE_SUMMARY_SKIP;
    for (int k = 0; k < STORE_SUMMARY_NSKIP; k++)
        if (!strcmp(skip[k], PART[part])) return k;
    return -1;
}

/* opens the result text once; 0 on success */
static int open_result(svg_job *j)
{
    if (j->result_tried) return j->result_failed ? -1 : 0;
    j->result_tried = 1;
    char st[16];
    store_rc rc = store_stream_open(j->id, "result", SVG_JOB_SMALL, &j->result_stream,
                                    &j->result_mem, &j->result_len, st);
    if (rc != STORE_OK || (!j->result_stream && !j->result_mem)) {
        j->result_failed = 1;
        return -1;
    }
    j->rsrc = j->result_mem ? js_memory_source(j->result_mem, j->result_len)
                            : (js_source){stream_read, j->result_stream,
                                          store_stream_size(j->result_stream)};
    return 0;
}

/* gp_svg_input.open: grains and spheres from the pack when there is one, else (and cells
 * always) from the result text */
static gp_svg_items *job_items(void *user, gp_svg_part part, int *failed)
{
    svg_job *j = user;
    *failed = 0;
    if (part != GP_SVG_CELLS) {
        if (!j->pack_tried) {
            j->pack_tried = 1;
            char st[16];
            if (store_stream_open(j->id, "pack", SVG_JOB_SMALL, &j->pack_stream, &j->pack_mem,
                                  &j->pack_len, st) != STORE_OK) {
                *failed = 1;
                return NULL;
            }
        }
        if (j->pack_stream || j->pack_mem) {
            gp_export_source src =
                j->pack_mem ? gp_export_memory_source(j->pack_mem, j->pack_len)
                            : (gp_export_source){stream_read, j->pack_stream,
                                                 store_stream_size(j->pack_stream)};
            gp_svg_items *it = gp_svg_items_pack(&src, part);
            if (it) return it;
            gpd_log(GPD_LOG_WARN, "job %s: its export pack has no %s; reading the result", j->id,
                    PART[part]);
        }
    }
    int k = skip_index(part);
    if (k < 0 || j->spans[k][1] <= j->spans[k][0]) return NULL; /* the result has none */
    if (open_result(j)) {
        *failed = 1;
        return NULL;
    }
    if (j->spans[k][1] > j->rsrc.size) {
        gpd_log(GPD_LOG_ERROR, "job %s: the %s are not where the summary says", j->id, PART[part]);
        *failed = 1;
        return NULL;
    }
    gp_svg_items *it = gp_svg_items_scan(&j->rsrc, j->spans[k][0], part);
    if (!it) *failed = 1;
    return it;
}

svg_job_rc svg_job_open(const char *id, const char *kind, const char *view,
                        const gp_svg_options *opt, svg_job **out, char status[16], int *http,
                        char *err, size_t errlen)
{
    *out = NULL;
    *http = 500;
    if (errlen) err[0] = 0;
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
        snprintf(err, errlen, "out of memory");
        return SVG_JOB_VIEW_ERROR;
    }
    snprintf(j->id, sizeof j->id, "%s", id);
    memcpy(j->spans, spans, sizeof spans);
    json_error_t je;
    j->summary = json_loadb(text, len, 0, &je);
    free(text);
    if (!j->summary) {
        svg_job_close(j);
        snprintf(err, errlen, "the stored result summary is not valid JSON");
        return SVG_JOB_VIEW_ERROR;
    }
    gp_svg_input in = {kind, j->summary, job_items, j};
    j->svg = gp_svg_open(&in, view, opt, http, err, errlen);
    if (!j->svg) {
        svg_job_close(j);
        return SVG_JOB_VIEW_ERROR;
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

void svg_job_close(svg_job *j)
{
    if (!j) return;
    gp_svg_close(j->svg);
    json_decref(j->summary);
    store_stream_close(j->pack_stream);
    free(j->pack_mem);
    store_stream_close(j->result_stream);
    free(j->result_mem);
    free(j);
#ifdef __GLIBC__
    /* what this picture freed (the summary's tree, the items, the private connections' page
     * caches) goes back to the system, as a worker's heap does after a job */
    malloc_trim(0);
#endif
}
