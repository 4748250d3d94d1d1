/* http.c -- libmicrohttpd front: routing, request bodies, JSON errors (see http.h). */
#include "http.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>
#include <microhttpd.h>

#include "gp_export.h"
#include "store.h"
#include "workers.h"
#ifdef GPD_HAVE_SCHEMA
#include "gp_spec.h"
#endif
#ifdef GPD_HAVE_SVG
#include "svg.h"
#endif
#ifdef GPD_HAVE_DASHBOARD
#include "dashboard.h"
#endif

#ifndef GPD_VERSION
#define GPD_VERSION "0.1.0"
#endif

#define LIST_DEFAULT_LIMIT 50
#define LIST_MAX_LIMIT 500

static struct MHD_Daemon *daemon_ = NULL;
static size_t max_body = 1 << 20;
static double max_result_mb = 1024;
static double started_at = 0;

/* ------------------------------------------------------------------ per-request state */

typedef struct req {
    char *body;
    size_t len, cap;
    int too_big;
    int status;      /* the status sent, for the access log */
    char method[12];
    char url[128];
    double t0;
} req;

/* ------------------------------------------------------------------ responses */

static enum MHD_Result send_buf(struct MHD_Connection *c, req *r, unsigned status,
                                const char *ctype, char *buf, size_t len,
                                enum MHD_ResponseMemoryMode mode, const char *allow)
{
    struct MHD_Response *resp = MHD_create_response_from_buffer(len, buf, mode);
    if (!resp) {
        if (mode == MHD_RESPMEM_MUST_FREE) free(buf);
        return MHD_NO;
    }
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    if (allow) MHD_add_response_header(resp, MHD_HTTP_HEADER_ALLOW, allow);
    if (r) r->status = (int)status;
    enum MHD_Result ret = MHD_queue_response(c, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

static enum MHD_Result send_json_hdr(struct MHD_Connection *c, req *r, unsigned status,
                                     json_t *j, const char *hname, const char *hval)
{
    char *text = j ? json_dumps(j, JSON_COMPACT) : NULL;
    json_decref(j);
    if (!text) {
        static const char oom[] =
            "{\"error\":{\"code\":\"internal\",\"message\":\"out of memory\"}}";
        return send_buf(c, r, 500, "application/json", (char *)oom, sizeof oom - 1,
                        MHD_RESPMEM_PERSISTENT, NULL);
    }
    size_t n = strlen(text);
    /* a trailing newline makes curl sessions readable */
    char *t2 = realloc(text, n + 2);
    if (t2) {
        text = t2;
        text[n++] = '\n';
        text[n] = '\0';
    }
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(n, text, MHD_RESPMEM_MUST_FREE);
    if (!resp) {
        free(text);
        return MHD_NO;
    }
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "application/json");
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    if (hname) MHD_add_response_header(resp, hname, hval);
    if (r) r->status = (int)status;
    enum MHD_Result ret = MHD_queue_response(c, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

static enum MHD_Result send_json(struct MHD_Connection *c, req *r, unsigned status, json_t *j)
{
    return send_json_hdr(c, r, status, j, NULL, NULL);
}

static enum MHD_Result send_error_allow(struct MHD_Connection *c, req *r, unsigned status,
                                        const char *code, const char *pointer,
                                        const char *allow, const char *fmt, ...)
    __attribute__((format(printf, 7, 8)));

static enum MHD_Result send_error_allow(struct MHD_Connection *c, req *r, unsigned status,
                                        const char *code, const char *pointer,
                                        const char *allow, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    json_t *e = json_object();
    json_object_set_new(e, "code", json_string(code));
    /* json_string needs valid UTF-8: fall back to a byte-safe copy */
    json_t *m = json_string(msg);
    if (!m) {
        for (char *p = msg; *p; p++)
            if ((unsigned char)*p >= 0x80) *p = '?';
        m = json_string(msg);
    }
    json_object_set_new(e, "message", m ? m : json_string(""));
    if (pointer) {
        json_t *pj = json_string(pointer);
        json_object_set_new(e, "pointer", pj ? pj : json_string(""));
    }
    return send_json_hdr(c, r, status, json_pack("{s:o}", "error", e),
                         allow ? MHD_HTTP_HEADER_ALLOW : NULL, allow);
}

#define send_error(c, r, status, code, pointer, ...) \
    send_error_allow(c, r, status, code, pointer, NULL, __VA_ARGS__)

static enum MHD_Result send_store_error(struct MHD_Connection *c, req *r)
{
    return send_error(c, r, 500, "internal", NULL, "job store error (see the daemon log)");
}

/* ------------------------------------------------------------------ helpers */

static const char *qarg(struct MHD_Connection *c, const char *name)
{
    return MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, name);
}

static int is_get(const char *m) { return !strcmp(m, "GET") || !strcmp(m, "HEAD"); }

static int valid_status(const char *s)
{
    static const char *all[] = {"queued", "running", "succeeded", "failed", "cancelled"};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++)
        if (!strcmp(s, all[i])) return 1;
    return 0;
}

/* 1 when word is one of the comma-separated items of list */
static int in_list(const char *list, const char *word)
{
    size_t wl = strlen(word);
    const char *p = list;
    while (p && *p) {
        while (*p == ' ' || *p == ',') p++;
        const char *e = p;
        while (*e && *e != ',') e++;
        const char *t = e;
        while (t > p && t[-1] == ' ') t--;
        if ((size_t)(t - p) == wl && !strncmp(p, word, wl)) return 1;
        p = e;
    }
    return 0;
}

/* ------------------------------------------------------------------ handlers */

static enum MHD_Result h_health(struct MHD_Connection *c, req *r)
{
    long q = 0, run = 0, su = 0, f = 0, ca = 0;
    store_rc rc = store_counts(&q, &run, &su, &f, &ca);
    json_t *j = json_object();
    json_object_set_new(j, "status", json_string(rc == STORE_OK ? "ok" : "degraded"));
    json_object_set_new(j, "version", json_string(GPD_VERSION));
    json_object_set_new(j, "uptime_s", json_real(gpd_monotonic_s() - started_at));
    json_object_set_new(j, "queue_depth", json_integer(q));
    json_object_set_new(j, "running", json_integer(run));
    json_object_set_new(j, "workers", json_integer(workers_total()));
    json_object_set_new(j, "workers_busy", json_integer(workers_busy()));
    json_object_set_new(j, "jobs",
                        json_pack("{s:I, s:I, s:I, s:I, s:I}", "queued", (json_int_t)q,
                                  "running", (json_int_t)run, "succeeded", (json_int_t)su,
                                  "failed", (json_int_t)f, "cancelled", (json_int_t)ca));
    json_object_set_new(j, "database", json_string(rc == STORE_OK ? "ok" : "error"));
    return send_json(c, r, rc == STORE_OK ? 200 : 503, j);
}

static enum MHD_Result h_schema(struct MHD_Connection *c, req *r)
{
#ifdef GPD_HAVE_SCHEMA
    const char *kind = qarg(c, "kind");
    const char *doc = kind ? gp_schema_text(kind) : gp_schema_document();
    if (!doc)
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "unknown kind \"%s\"; expected fourier-voronoi-2d or spheres-3d", kind);
    return send_buf(c, r, 200, "application/schema+json", (char *)doc, strlen(doc),
                    MHD_RESPMEM_PERSISTENT, NULL);
#else
    return send_error(c, r, 501, "not_implemented", NULL,
                      "the schema module is not part of this build yet");
#endif
}

static enum MHD_Result h_dashboard(struct MHD_Connection *c, req *r)
{
#ifdef GPD_HAVE_DASHBOARD
    const char *html = gp_dashboard_html();
    return send_buf(c, r, 200, "text/html; charset=utf-8", (char *)html, strlen(html),
                    MHD_RESPMEM_PERSISTENT, NULL);
#else
    return send_error(c, r, 501, "not_implemented", NULL,
                      "the dashboard is not part of this build yet; see /v1/jobs");
#endif
}

/* ------------------------------------------------------------------ result-size bound */

/* bytes of one grain in a 2D result with np contour points and these outputs */
static double bytes_per_grain(const json_t *outputs, double np)
{
    double per = 400; /* stats, ids, areas, descriptors */
    size_t k;
    json_t *o;
    json_array_foreach(outputs, k, o)
    {
        const char *w = json_string_value(o);
        if (!w) continue;
        if (!strcmp(w, "grains")) per += 40 * np;
        else if (!strcmp(w, "odec")) per += 40 * np + 60 * 16;
        else if (!strcmp(w, "descriptors")) per += 40 * np + 120;
        else if (!strcmp(w, "cells")) per += 40 * 12 + 100;
    }
    return per;
}

/* the grains and contour points of a valid effective 2D spec, whatever the spelling of its
 * numbers (1e6 is 1000000); *pointer: the field that sets the count. 0, or -1 with msg */
static int grains_2d(const json_t *eff, double *n, double *np, const char **pointer, char *msg,
                     size_t msglen)
{
#ifdef GPD_HAVE_SCHEMA
    gp_spec2d s;
    gp_spec_problem prob;
    if (gp_spec_parse_2d(eff, &s, &prob) != 0) {
        snprintf(msg, msglen, "the effective spec does not parse: %.400s", prob.message);
        return -1;
    }
    size_t cells = s.particles;
    double area = 0;
    gp_error err;
    memset(&err, 0, sizeof err);
    int rc = 0;
    if (s.size_law == GP_LAW_SIEVE) {
        *pointer = "/size/sieve";
        if (gp_spec2d_cell_count(&s, &area, &cells, &err) != GP_OK) {
            snprintf(msg, msglen, "the cell count of a valid spec failed: %s", err.message);
            rc = -1;
        }
    }
    *n = (double)cells;
    *np = (double)s.contour_points;
    gp_spec_2d_free(&s);
    return rc;
#else
    *n = json_number_value(json_object_get(eff, "particles"));
    *np = json_number_value(json_object_get(eff, "contour_points"));
    if (*np <= 0) *np = 128;
    return 0;
#endif
}

/* bounds the memory of one job by an estimate of its result's size: 0 within the limit, 1 over
 * it (msg and *pointer say why), -1 internal error (msg) */
static int result_too_large_2d(const json_t *eff, char *msg, size_t msglen, const char **pointer)
{
    double n = 0, np = 0;
    if (grains_2d(eff, &n, &np, pointer, msg, msglen)) return -1;
    double mb = n * bytes_per_grain(json_object_get(eff, "outputs"), np) / 1e6;
    if (mb <= max_result_mb) return 0;
    snprintf(msg, msglen,
             "%s: the result would be about %.0f MB (%.0f grains), over this server's limit of "
             "%.0f MB (--max-result-mb); ask for fewer %s, contour_points or outputs",
             *pointer, mb, n, max_result_mb,
             strcmp(*pointer, "/particles") ? "grains (a smaller container or coarser sieve)"
                                            : "particles");
    return 1;
}

static enum MHD_Result h_submit(struct MHD_Connection *c, req *r)
{
    if (r->len == 0)
        return send_error(c, r, 400, "invalid_json", NULL,
                          "the request body is empty; expected a JSON spec object");
    json_error_t je;
    json_t *spec = json_loadb(r->body, r->len, JSON_REJECT_DUPLICATES, &je);
    if (!spec)
        return send_error(c, r, 400, "invalid_json", NULL,
                          "malformed JSON at line %d, column %d: %s", je.line, je.column,
                          je.text);
    if (!json_is_object(spec)) {
        json_decref(spec);
        return send_error(c, r, 422, "invalid_spec", "",
                          ": expected a JSON object with a \"kind\"");
    }
    json_t *eff = NULL;
#ifdef GPD_HAVE_SCHEMA
    gp_spec_problem prob;
    memset(&prob, 0, sizeof prob);
    eff = gp_spec_with_defaults(spec, &prob);
    json_decref(spec);
    if (!eff) {
        if (prob.http_status >= 500)
            return send_error(c, r, 500, prob.code[0] ? prob.code : "internal", NULL, "%s",
                              prob.message);
        /* every spec problem is a 422, invalid_spec (or too_large: a sieve law that derives
         * more grains than particles allows); 400 is kept for unreadable bodies */
        return send_error(c, r, 422, prob.code[0] ? prob.code : "invalid_spec", prob.pointer,
                          "%s", prob.message[0] ? prob.message : "invalid spec");
    }
#else
    eff = spec;
#endif
    const char *kind = json_string_value(json_object_get(eff, "kind"));
    if (!kind || (strcmp(kind, "fourier-voronoi-2d") && strcmp(kind, "spheres-3d"))) {
        json_decref(eff);
        return send_error(c, r, 422, "invalid_spec", "/kind",
                          "/kind: expected one of \"fourier-voronoi-2d\", \"spheres-3d\"");
    }
#ifndef GPD_HAVE_SPECIMEN3D
    if (!strcmp(kind, "spheres-3d")) {
        json_decref(eff);
        return send_error(c, r, 501, "not_implemented", "/kind",
                          "/kind: \"spheres-3d\" is not available in this build yet");
    }
#endif
    if (!strcmp(kind, "fourier-voronoi-2d")) {
        char msg[512];
        const char *pointer = "/particles";
        int big = result_too_large_2d(eff, msg, sizeof msg, &pointer);
        if (big) {
            json_decref(eff);
            if (big < 0) return send_error(c, r, 500, "internal", NULL, "%s", msg);
            return send_error(c, r, 422, "too_large", pointer, "%s", msg);
        }
    }
    char *text = json_dumps(eff, JSON_COMPACT);
    char id[33];
    store_rc rc = text ? store_insert(kind, text, id) : STORE_ERROR;
    free(text);
    json_decref(eff);
    if (rc != STORE_OK) return send_store_error(c, r);
    workers_notify();
    gpd_log(GPD_LOG_INFO, "job %s queued", id);
    json_t *job = store_get_job(id, &rc);
    if (!job) return send_store_error(c, r);
    char loc[64];
    snprintf(loc, sizeof loc, "/v1/jobs/%s", id);
    return send_json_hdr(c, r, 201, job, MHD_HTTP_HEADER_LOCATION, loc);
}

static enum MHD_Result h_list(struct MHD_Connection *c, req *r)
{
    const char *status = qarg(c, "status");
    const char *lim = qarg(c, "limit");
    const char *after = qarg(c, "after");
    if (status && !*status) status = NULL;
    if (after && !*after) after = NULL;
    if (status && !valid_status(status))
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "status: expected one of queued, running, succeeded, failed, "
                          "cancelled; got \"%.64s\"",
                          status);
    int limit = LIST_DEFAULT_LIMIT;
    if (lim && *lim) {
        char *end = NULL;
        errno = 0;
        long v = strtol(lim, &end, 10);
        if (errno || *end || v < 1 || v > LIST_MAX_LIMIT)
            return send_error(c, r, 400, "invalid_parameter", NULL,
                              "limit: expected an integer in [1, %d]; got \"%.32s\"",
                              LIST_MAX_LIMIT, lim);
        limit = (int)v;
    }
    if (after && !gpd_id_is_plausible(after))
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "after: expected a job id (the \"next\" of the previous page)");
    store_rc rc;
    json_t *j = store_list(status, limit, after, &rc);
    if (rc == STORE_NOT_FOUND)
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "after: no job with id \"%s\"", after);
    if (!j) return send_store_error(c, r);
    return send_json(c, r, 200, j);
}

static enum MHD_Result not_found(struct MHD_Connection *c, req *r, const char *id)
{
    return send_error(c, r, 404, "not_found", NULL, "no job with id \"%.64s\"", id);
}

static enum MHD_Result h_job(struct MHD_Connection *c, req *r, const char *id)
{
    store_rc rc;
    json_t *j = store_get_job(id, &rc);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (!j) return send_store_error(c, r);
    return send_json(c, r, 200, j);
}

static enum MHD_Result h_cancel(struct MHD_Connection *c, req *r, const char *id)
{
    char st[16];
    store_rc rc = workers_cancel(id, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc == STORE_CONFLICT)
        return send_error(c, r, 409, "already_finished", NULL,
                          "job %s has already finished (status %s); nothing to cancel", id, st);
    if (rc != STORE_OK) return send_store_error(c, r);
    return h_job(c, r, id);
}

static enum MHD_Result not_ready(struct MHD_Connection *c, req *r, const char *id,
                                 const char *status)
{
    return send_error(c, r, 409, "not_ready", NULL,
                      "job %s is %s; the result exists only once it has succeeded", id, status);
}

/* Results and packs up to this size are read whole; larger ones are streamed from SQLite
 * (incremental blob I/O on a private connection), so that serving a 230,000-sphere result
 * costs the daemon a few hundred KB, not the result's size. */
#define STREAM_SMALL (256u * 1024u)
#define STREAM_BLOCK (32u * 1024u)

static ssize_t read_result_stream(void *cls, uint64_t pos, char *buf, size_t max)
{
    store_stream *s = cls;
    uint64_t size = store_stream_size(s);
    if (pos >= size) return MHD_CONTENT_READER_END_OF_STREAM;
    size_t n = size - pos < max ? (size_t)(size - pos) : max;
    if (store_stream_read(s, pos, buf, n)) return MHD_CONTENT_READER_END_WITH_ERROR;
    return (ssize_t)n;
}

static void free_result_stream(void *cls)
{
    store_stream_close(cls);
}

/* Queues a streamed response (takes ownership of cls, freed by fr even on failure). */
static enum MHD_Result send_stream(struct MHD_Connection *c, req *r, const char *ctype,
                                   uint64_t size, MHD_ContentReaderCallback rd, void *cls,
                                   MHD_ContentReaderFreeCallback fr, const char *disposition)
{
    struct MHD_Response *resp = MHD_create_response_from_callback(size, STREAM_BLOCK, rd, cls, fr);
    if (!resp) {
        fr(cls);
        return MHD_NO;
    }
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    if (disposition) MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_DISPOSITION, disposition);
    r->status = 200;
    enum MHD_Result ret = MHD_queue_response(c, 200, resp);
    MHD_destroy_response(resp);
    return ret;
}

static enum MHD_Result h_result(struct MHD_Connection *c, req *r, const char *id)
{
    char *text = NULL;
    size_t len = 0;
    char st[16];
    store_stream *s = NULL;
    store_rc rc = store_stream_open(id, "result", STREAM_SMALL, &s, &text, &len, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc != STORE_OK) return send_store_error(c, r);
    if (strcmp(st, "succeeded") || (!text && !s)) {
        free(text);
        store_stream_close(s);
        return not_ready(c, r, id, st);
    }
    if (text)
        return send_buf(c, r, 200, "application/json", text, len, MHD_RESPMEM_MUST_FREE, NULL);
    return send_stream(c, r, "application/json", store_stream_size(s), read_result_stream, s,
                       free_result_stream, NULL);
}

static enum MHD_Result h_spec(struct MHD_Connection *c, req *r, const char *id)
{
    char *text = NULL;
    char st[16];
    store_rc rc = store_get_text(id, "spec", &text, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc != STORE_OK || !text) {
        free(text);
        return send_store_error(c, r);
    }
    return send_buf(c, r, 200, "application/json", text, strlen(text), MHD_RESPMEM_MUST_FREE,
                    NULL);
}

static enum MHD_Result h_svg(struct MHD_Connection *c, req *r, const char *id)
{
    char *kind = NULL;
    char st[16];
    store_rc rc = store_get_text(id, "kind", &kind, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc != STORE_OK || !kind) {
        free(kind);
        return send_store_error(c, r);
    }
#ifdef GPD_HAVE_SVG
    const char *view = qarg(c, "view");
    const char *views = gp_svg_views(kind);
    if (!view || !*view || (views && !in_list(views, view))) {
        enum MHD_Result ret =
            send_error(c, r, 400, "invalid_parameter", NULL,
                       "view: expected one of %s for kind %s%s%.64s%s", views ? views : "?",
                       kind, view ? "; got \"" : "", view ? view : "", view ? "\"" : "");
        free(kind);
        return ret;
    }
    gp_svg_options opt;
    memset(&opt, 0, sizeof opt);
    opt.color = qarg(c, "color");
    const char *w = qarg(c, "width"), *z = qarg(c, "z");
    if (w) {
        char *end;
        long v = strtol(w, &end, 10);
        if (*end || v < 16 || v > 16384) {
            free(kind);
            return send_error(c, r, 400, "invalid_parameter", NULL,
                              "width: expected an integer in [16, 16384]");
        }
        opt.width = (int)v;
    }
    if (z) {
        char *end;
        double v = strtod(z, &end);
        if (*end || end == z) {
            free(kind);
            return send_error(c, r, 400, "invalid_parameter", NULL,
                              "z: expected a number (metres)");
        }
        opt.has_z = 1;
        opt.z = v;
    }
    char *text = NULL;
    rc = store_get_text(id, "result", &text, st);
    if (rc == STORE_NOT_FOUND) {
        free(kind);
        return not_found(c, r, id);
    }
    if (rc != STORE_OK || strcmp(st, "succeeded") || !text) {
        free(text);
        free(kind);
        return rc != STORE_OK ? send_store_error(c, r) : not_ready(c, r, id, st);
    }
    json_error_t je;
    json_t *res = json_loads(text, 0, &je);
    free(text);
    if (!res) {
        free(kind);
        return send_error(c, r, 500, "internal", NULL, "stored result is not valid JSON");
    }
    size_t len = 0;
    int status = 500;
    char err[512] = "";
    char *svg = gp_svg_render(res, kind, view, &opt, &len, &status, err, sizeof err);
    json_decref(res);
    free(kind);
    if (!svg) {
        if (status < 400 || status > 599) status = 500;
        return send_error(c, r, (unsigned)status,
                          status == 400 ? "invalid_parameter"
                          : status == 409 ? "not_available"
                                          : "internal",
                          NULL, "%s", err[0] ? err : "cannot render this view");
    }
    return send_buf(c, r, 200, "image/svg+xml", svg, len ? len : strlen(svg),
                    MHD_RESPMEM_MUST_FREE, NULL);
#else
    (void)in_list;
    free(kind);
    if (strcmp(st, "succeeded")) return not_ready(c, r, id, st);
    return send_error(c, r, 501, "not_implemented", NULL,
                      "the SVG renderer is not part of this build yet");
#endif
}

/* An export being downloaded: the pack (in memory when small, else an SQLite stream) and the
 * format's pull stream over it. */
typedef struct export_dl {
    store_stream *stream;
    char *pack;
    gp_export *e;
} export_dl;

static int export_src_read(void *user, uint64_t off, void *dst, size_t n)
{
    return store_stream_read(user, off, dst, n);
}

static ssize_t read_export(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos; /* the stream is read in order, once */
    export_dl *d = cls;
    size_t n = 0;
    gp_error err;
    if (gp_export_read(d->e, buf, max, &n, &err)) {
        gpd_log(GPD_LOG_ERROR, "export failed mid-stream: %s", err.message);
        return MHD_CONTENT_READER_END_WITH_ERROR;
    }
    return n ? (ssize_t)n : MHD_CONTENT_READER_END_OF_STREAM;
}

static void free_export(void *cls)
{
    export_dl *d = cls;
    if (!d) return;
    gp_export_destroy(d->e);
    store_stream_close(d->stream);
    free(d->pack);
    free(d);
}

static enum MHD_Result h_export(struct MHD_Connection *c, req *r, const char *id)
{
    char *kind = NULL;
    char st[16];
    store_rc rc = store_get_text(id, "kind", &kind, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc != STORE_OK || !kind) {
        free(kind);
        return send_store_error(c, r);
    }
    int dim = !strcmp(kind, "spheres-3d") ? 3 : 2;
    free(kind);
    const char *format = qarg(c, "format");
    int f = gp_export_format_parse(format);
    if (f < 0 || !gp_export_format_supports(f, dim))
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "format: expected one of %s%s%.64s%s", gp_export_format_list(dim),
                          format ? "; got \"" : "", format ? format : "", format ? "\"" : "");
    if (strcmp(st, "succeeded")) return not_ready(c, r, id, st);

    export_dl *d = calloc(1, sizeof *d);
    if (!d) return send_error(c, r, 500, "internal", NULL, "out of memory");
    size_t len = 0;
    rc = store_stream_open(id, "pack", STREAM_SMALL, &d->stream, &d->pack, &len, st);
    if (rc == STORE_NOT_FOUND) {
        free_export(d);
        return not_found(c, r, id);
    }
    if (rc != STORE_OK) {
        free_export(d);
        return send_store_error(c, r);
    }
    if (!d->pack && !d->stream) {
        free_export(d);
        return send_error(c, r, 409, "missing_output", "/outputs",
                          "job %s has no %s to export (its spec did not ask for it): submit "
                          "the spec again with \"%s\" in outputs",
                          id, dim == 3 ? "sphere list" : "ODEC discs", dim == 3 ? "spheres" : "odec");
    }
    gp_export_source src = d->pack ? gp_export_memory_source(d->pack, len)
                                   : (gp_export_source){export_src_read, d->stream,
                                                        store_stream_size(d->stream)};
    gp_error err;
    if (gp_export_open(f, &src, &d->e, &err)) {
        free_export(d);
        return send_error(c, r, 500, "internal", NULL, "cannot export: %s", err.message);
    }
    char disp[160];
    snprintf(disp, sizeof disp, "attachment; filename=\"%s-%s.%s\"", id,
             gp_export_format_name(f), gp_export_format_extension(f));
    return send_stream(c, r, gp_export_format_mime(f), MHD_SIZE_UNKNOWN, read_export, d,
                       free_export, disp);
}

/* ------------------------------------------------------------------ routing */

static enum MHD_Result method_not_allowed(struct MHD_Connection *c, req *r, const char *method,
                                          const char *url, const char *allow)
{
    return send_error_allow(c, r, 405, "method_not_allowed", NULL, allow,
                            "%s is not allowed on %s; allowed: %s", method, url, allow);
}

static enum MHD_Result route(struct MHD_Connection *c, req *r, const char *url,
                             const char *method)
{
    /* canonical path: drop one trailing slash (but keep "/") */
    char path[512];
    size_t ul = strlen(url);
    if (ul >= sizeof path)
        return send_error(c, r, 404, "not_found", NULL, "no such resource");
    memcpy(path, url, ul + 1);
    if (ul > 1 && path[ul - 1] == '/') path[--ul] = '\0';

    if (!strcmp(path, "/")) {
        if (!is_get(method)) return method_not_allowed(c, r, method, path, "GET, HEAD");
        return h_dashboard(c, r);
    }
    if (!strcmp(path, "/v1/health")) {
        if (!is_get(method)) return method_not_allowed(c, r, method, path, "GET, HEAD");
        return h_health(c, r);
    }
    if (!strcmp(path, "/v1/schema")) {
        if (!is_get(method)) return method_not_allowed(c, r, method, path, "GET, HEAD");
        return h_schema(c, r);
    }
    if (!strcmp(path, "/v1/jobs")) {
        if (!strcmp(method, "POST")) return h_submit(c, r);
        if (is_get(method)) return h_list(c, r);
        return method_not_allowed(c, r, method, path, "GET, HEAD, POST");
    }
    if (!strncmp(path, "/v1/jobs/", 9)) {
        char id[80];
        const char *p = path + 9;
        const char *slash = strchr(p, '/');
        size_t il = slash ? (size_t)(slash - p) : strlen(p);
        if (il == 0 || il >= sizeof id)
            return send_error(c, r, 404, "not_found", NULL, "no such resource: %.128s", path);
        memcpy(id, p, il);
        id[il] = '\0';
        const char *sub = slash ? slash + 1 : NULL;
        if (!sub) {
            if (!strcmp(method, "DELETE")) {
                if (!gpd_id_is_plausible(id)) return not_found(c, r, id);
                return h_cancel(c, r, id);
            }
            if (!is_get(method))
                return method_not_allowed(c, r, method, path, "GET, HEAD, DELETE");
            if (!gpd_id_is_plausible(id)) return not_found(c, r, id);
            return h_job(c, r, id);
        }
        enum MHD_Result (*h)(struct MHD_Connection *, req *, const char *) = NULL;
        if (!strcmp(sub, "result")) h = h_result;
        else if (!strcmp(sub, "svg")) h = h_svg;
        else if (!strcmp(sub, "export")) h = h_export;
        else if (!strcmp(sub, "spec")) h = h_spec;
        if (!h) return send_error(c, r, 404, "not_found", NULL, "no such resource: %.128s", path);
        if (!is_get(method)) return method_not_allowed(c, r, method, path, "GET, HEAD");
        if (!gpd_id_is_plausible(id)) return not_found(c, r, id);
        return h(c, r, id);
    }
    return send_error(c, r, 404, "not_found", NULL, "no such resource: %.128s", path);
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    req *r = *con_cls;
    if (!r) {
        r = calloc(1, sizeof *r);
        if (!r) return MHD_NO;
        r->t0 = gpd_monotonic_s();
        snprintf(r->method, sizeof r->method, "%s", method);
        snprintf(r->url, sizeof r->url, "%s", url);
        *con_cls = r;
        /* refuse an announced oversized body before reading any of it */
        const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
                                                     MHD_HTTP_HEADER_CONTENT_LENGTH);
        if (cl) {
            char *end = NULL;
            unsigned long long n = strtoull(cl, &end, 10);
            if (end && *end == '\0' && n > max_body) {
                r->too_big = 1;
                return send_error(c, r, 413, "payload_too_large", NULL,
                                  "request body of %llu bytes is over the limit of %zu bytes", n,
                                  max_body);
            }
        }
        return MHD_YES;
    }
    if (*upload_data_size) {
        size_t n = *upload_data_size;
        *upload_data_size = 0;
        if (r->too_big) return MHD_YES; /* discard */
        if (strcmp(method, "POST")) return MHD_YES; /* bodies of other methods are ignored */
        if (r->len + n > max_body) {
            r->too_big = 1;
            free(r->body);
            r->body = NULL;
            r->len = r->cap = 0;
            return MHD_YES;
        }
        if (r->len + n + 1 > r->cap) {
            size_t cap = r->cap ? r->cap : 4096;
            while (cap < r->len + n + 1) cap *= 2;
            if (cap > max_body + 1) cap = max_body + 1;
            char *b = realloc(r->body, cap);
            if (!b) return MHD_NO;
            r->body = b;
            r->cap = cap;
        }
        memcpy(r->body + r->len, upload_data, n);
        r->len += n;
        return MHD_YES;
    }
    if (r->too_big)
        return send_error(c, r, 413, "payload_too_large", NULL,
                          "request body over the limit of %zu bytes", max_body);
    return route(c, r, url, method);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    req *r = *con_cls;
    if (!r) return;
    if (gpd_log_threshold >= GPD_LOG_DEBUG) {
        gpd_log(GPD_LOG_DEBUG, "http %s %s %d %.3f ms%s", r->method, r->url, r->status,
                1e3 * (gpd_monotonic_s() - r->t0),
                toe == MHD_REQUEST_TERMINATED_COMPLETED_OK ? "" : " (aborted)");
    }
    free(r->body);
    free(r);
    *con_cls = NULL;
}

static void mhd_log(void *cls, const char *fmt, va_list ap)
{
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, ap);
    size_t n = strlen(msg);
    while (n && (msg[n - 1] == '\n' || msg[n - 1] == '\r')) msg[--n] = '\0';
    gpd_log(GPD_LOG_WARN, "mhd: %s", msg);
}

/* ------------------------------------------------------------------ lifecycle */

int gpd_listen_socket(const char *listen_spec, char *host_out, size_t host_len, int *port)
{
    char host[256], portbuf[16];
    const char *colon;
    if (listen_spec[0] == '[') {
        const char *rb = strchr(listen_spec, ']');
        if (!rb || rb[1] != ':') goto bad;
        size_t hl = (size_t)(rb - listen_spec - 1);
        if (hl >= sizeof host) goto bad;
        memcpy(host, listen_spec + 1, hl);
        host[hl] = '\0';
        colon = rb + 1;
    } else {
        colon = strrchr(listen_spec, ':');
        if (!colon) goto bad;
        size_t hl = (size_t)(colon - listen_spec);
        if (hl >= sizeof host) goto bad;
        memcpy(host, listen_spec, hl);
        host[hl] = '\0';
        if (!host[0]) snprintf(host, sizeof host, "127.0.0.1");
    }
    {
        char *end;
        long pv = strtol(colon + 1, &end, 10);
        if (!colon[1] || *end || pv < 0 || pv > 65535) goto bad;
        snprintf(portbuf, sizeof portbuf, "%ld", pv);
    }
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
    int gai = getaddrinfo(host, portbuf, &hints, &res);
    if (gai != 0) {
        fprintf(stderr, "grainpackd: cannot resolve %s: %s\n", host, gai_strerror(gai));
        return -1;
    }
    int fd = -1;
    for (struct addrinfo *ai = res; ai; ai = ai->ai_next) {
        fd = socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
        if (fd < 0) continue;
        int one = 1;
        setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        if (bind(fd, ai->ai_addr, ai->ai_addrlen) == 0 && listen(fd, 1024) == 0) break;
        close(fd);
        fd = -1;
    }
    int saved = errno;
    freeaddrinfo(res);
    if (fd < 0) {
        fprintf(stderr, "grainpackd: cannot listen on %s: %s\n", listen_spec, strerror(saved));
        return -1;
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl >= 0) fcntl(fd, F_SETFL, fl | O_NONBLOCK);
    struct sockaddr_storage ss;
    socklen_t sl = sizeof ss;
    if (getsockname(fd, (struct sockaddr *)&ss, &sl) != 0) {
        close(fd);
        return -1;
    }
    char hbuf[1025], sbuf[32];
    if (getnameinfo((struct sockaddr *)&ss, sl, hbuf, sizeof hbuf, sbuf, sizeof sbuf,
                    NI_NUMERICHOST | NI_NUMERICSERV) != 0) {
        close(fd);
        return -1;
    }
    *port = atoi(sbuf);
    if (ss.ss_family == AF_INET6)
        snprintf(host_out, host_len, "[%s]", hbuf);
    else
        snprintf(host_out, host_len, "%s", hbuf);
    return fd;
bad:
    fprintf(stderr, "grainpackd: --listen expects HOST:PORT (e.g. 127.0.0.1:8080), got \"%s\"\n",
            listen_spec);
    return -1;
}

int gpd_http_start(const gpd_http_config *cfg)
{
    max_body = cfg->max_body;
    if (cfg->max_result_mb > 0) max_result_mb = cfg->max_result_mb;
    started_at = gpd_monotonic_s();
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_ERROR_LOG | MHD_USE_AUTO | MHD_USE_ITC;
    daemon_ = MHD_start_daemon(
        flags, 0, NULL, NULL, &on_request, NULL, MHD_OPTION_EXTERNAL_LOGGER, &mhd_log, NULL,
        MHD_OPTION_LISTEN_SOCKET, cfg->listen_fd,
        MHD_OPTION_THREAD_POOL_SIZE, cfg->threads, MHD_OPTION_CONNECTION_LIMIT,
        cfg->max_connections, MHD_OPTION_CONNECTION_TIMEOUT, cfg->timeout_s,
        MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)64 * 1024, MHD_OPTION_NOTIFY_COMPLETED,
        &on_completed, NULL, MHD_OPTION_END);
    if (!daemon_) {
        gpd_log(GPD_LOG_ERROR, "cannot start the HTTP server");
        return -1;
    }
    return 0;
}

void gpd_http_stop(void)
{
    if (!daemon_) return;
    MHD_socket fd = MHD_quiesce_daemon(daemon_);
    MHD_stop_daemon(daemon_);
    daemon_ = NULL;
    if (fd != MHD_INVALID_SOCKET) close(fd);
}
