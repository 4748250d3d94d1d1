/* http.c -- libmicrohttpd front: routing, request bodies, JSON errors (see http.h). */
#include "http/http.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>
#include <microhttpd.h>

#include "gp_export.h"
#include "gp_spec.h"
#include "kinds/kind.h"
#include "jobs/file_errors.h"
#include "jobs/maint.h"
#include "jobs/metrics.h"
#include "http/conns.h"
#include "http/offload.h"
#include "http/page.h"
#include "http/routes.h"
#include "kinds/fourier-voronoi-2d/shapes.h"
#include "store/store.h"
#include "svg/svg_job.h"
#include "jobs/workers.h"

#define LIST_DEFAULT_LIMIT 50
#define HEALTH_WRITE_WINDOW_S 300.0
#define LIST_MAX_LIMIT 500

static struct MHD_Daemon *daemon_ = NULL;
static size_t max_body = 1 << 20;
/* The request bodies held at once, all connections together, are bounded by this many of the
 * largest (max_body): beyond it a body is dropped and answered 503 busy, whatever the
 * connection limits (a body is parsed off the HTTP threads into a few times its size) */
#define BODIES_HELD_MAX 4
#define BODY_BUSY_RETRY_S 5
static atomic_size_t bodies_held; /* bytes of r->cap over every request */
static unsigned max_pending = 16;
static double max_result_mb = 8192;
static long max_queued = 10000;
static double started_at = 0;

/* ------------------------------------------------------------------ per-request state */

typedef struct req {
    char *body;
    size_t len, cap;
    size_t limit;      /* the body this method of this route may carry (routes.h) */
    size_t dropped;    /* body bytes read and dropped (over the limit, or refused) */
    int too_big;
    int busy;        /* its body would take the bodies held over their bound: 503 */
    int refused;     /* answered before routing (414, 403): its body is discarded */
    int status;      /* the status sent, for the access log */
    size_t url_len;  /* the request target as sent (path and query), in bytes */
    char method[12];
    char url[128];
    char acao[256];  /* an accepted Origin, echoed in Access-Control-Allow-Origin */
    double t0;
    /* offloaded requests (offload.h): the connection is suspended while a pool thread runs
     * the handler; its response is kept here until the connection is resumed */
    int offloaded;
    struct MHD_Connection *conn;
    enum MHD_Result (*handler)(struct MHD_Connection *, struct req *, const char *);
    struct MHD_Response *resp;
    /* the route of the path (routes.h; NULL: none) and its {id}, matched when the request
     * arrives: the router answers by it, the metrics count by it */
    const gpd_route *route;
    char id[GPD_ROUTE_PARAM_MAX];
} req;

/* a handler of the route table (routes.h: gpd_handler): id is the route's {id}, "" for a route
 * without one */
typedef enum MHD_Result (*handler_fn)(struct MHD_Connection *c, req *r, const char *id);

/* *con_cls before the access handler has run: the length of the request target (on_uri) */
#define URI_LEN_TAGGED(p) (((uintptr_t)(p)) & 1u)

/* Content-Security-Policy of everything but GET / (JSON, SVG, exports: nothing runs, nothing
 * frames them); the page has its own (page.h) */
#define CSP_OTHER "default-src 'none'; frame-ancestors 'none'"

/* the headers every response carries */
static void std_headers(struct MHD_Response *resp, const req *r, const char *ctype)
{
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    MHD_add_response_header(resp, "X-Frame-Options", "DENY");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    const char *page_csp = !strncmp(ctype, "text/html", 9) ? gpd_page_csp() : NULL;
    int html = page_csp != NULL;
    MHD_add_response_header(resp, "Content-Security-Policy", html ? page_csp : CSP_OTHER);
    if (html) MHD_add_response_header(resp, "Referrer-Policy", "no-referrer");
    if (r && r->acao[0]) {
        MHD_add_response_header(resp, "Access-Control-Allow-Origin", r->acao);
        MHD_add_response_header(resp, "Access-Control-Expose-Headers",
                                "Location, Content-Disposition");
    }
    MHD_add_response_header(resp, "Vary", "Origin");
}

/* ------------------------------------------------------------------ responses */

/* Queues resp on c, or keeps it in r while r runs on a pool thread (libmicrohttpd takes a
 * response only from within its access handler: on_request queues it once resumed) */
static enum MHD_Result queue_response(struct MHD_Connection *c, req *r, unsigned status,
                                      struct MHD_Response *resp)
{
    if (r) r->status = (int)status;
    if (r && r->offloaded) {
        r->resp = resp;
        return MHD_YES;
    }
    enum MHD_Result ret = MHD_queue_response(c, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

static enum MHD_Result send_buf(struct MHD_Connection *c, req *r, unsigned status,
                                const char *ctype, char *buf, size_t len,
                                enum MHD_ResponseMemoryMode mode, const char *allow)
{
    struct MHD_Response *resp = MHD_create_response_from_buffer(len, buf, mode);
    if (!resp) {
        if (mode == MHD_RESPMEM_MUST_FREE) free(buf);
        return MHD_NO;
    }
    std_headers(resp, r, ctype);
    if (allow) MHD_add_response_header(resp, MHD_HTTP_HEADER_ALLOW, allow);
    return queue_response(c, r, status, resp);
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
    std_headers(resp, r, "application/json");
    if (hname) MHD_add_response_header(resp, hname, hval);
    return queue_response(c, r, status, resp);
}

static enum MHD_Result send_json(struct MHD_Connection *c, req *r, unsigned status, json_t *j)
{
    return send_json_hdr(c, r, status, j, NULL, NULL);
}

/* The error object with one extra header (hname NULL: none). */
static enum MHD_Result send_error_hdr(struct MHD_Connection *c, req *r, unsigned status,
                                      const char *code, const char *pointer, const char *hname,
                                      const char *hval, const char *fmt, ...)
    __attribute__((format(printf, 8, 9)));

static enum MHD_Result send_error_hdr(struct MHD_Connection *c, req *r, unsigned status,
                                      const char *code, const char *pointer, const char *hname,
                                      const char *hval, const char *fmt, ...)
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
    return send_json_hdr(c, r, status, json_pack("{s:o}", "error", e), hname, hval);
}

#define send_error(c, r, status, code, pointer, ...) \
    send_error_hdr(c, r, status, code, pointer, NULL, NULL, __VA_ARGS__)
#define send_error_allow(c, r, status, code, pointer, allow, ...) \
    send_error_hdr(c, r, status, code, pointer, MHD_HTTP_HEADER_ALLOW, allow, __VA_ARGS__)

/* A store failure: 503 while the database does not answer (it recovers by itself), else 500 */
static enum MHD_Result send_store_error(struct MHD_Connection *c, req *r)
{
    if (!store_reachable()) {
        char retry[16];
        snprintf(retry, sizeof retry, "%d", STORE_BUSY_RETRY_S);
        return send_error_hdr(c, r, 503, "unavailable", NULL, "Retry-After", retry,
                              "the job database does not answer (GET /v1/health says "
                              "\"unreachable\"); try again in %d s", STORE_BUSY_RETRY_S);
    }
    return send_error(c, r, 500, "internal", NULL, "job store error (see the daemon log)");
}

/* ------------------------------------------------------------------ helpers */

static const char *qarg(struct MHD_Connection *c, const char *name)
{
    return MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, name);
}

static int valid_status(const char *s)
{
    static const char *all[] = {"queued", "running", "succeeded", "failed", "cancelled"};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++)
        if (!strcmp(s, all[i])) return 1;
    return 0;
}

/* ------------------------------------------------------------------ handlers */

/* A download refused for want of a database connection (STORE_BUSY: --db-connections are
 * held by downloads in progress): 503 busy, and when to try again. */
static enum MHD_Result send_busy(struct MHD_Connection *c, req *r)
{
    char retry[16];
    snprintf(retry, sizeof retry, "%d", STORE_BUSY_RETRY_S);
    return send_error_hdr(c, r, 503, "busy", NULL, "Retry-After", retry,
                          "this daemon holds all the database connections it may "
                          "(--db-connections) for downloads in progress; try again in %d s",
                          STORE_BUSY_RETRY_S);
}

/* GET /v1/health answers within a second whatever the database does: its counts wait this
 * long at most (a stalled server answers 503 "unreachable") */
#define HEALTH_DB_WAIT_S 0.5

static enum MHD_Result h_health(struct MHD_Connection *c, req *r, const char *id)
{
    (void)id;
    long n[5] = {0};
    store_rc rc = store_counts_within(HEALTH_DB_WAIT_S, n);
    long q = n[0], run = n[1], su = n[2], f = n[3], ca = n[4];
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
    /* reads pass while writes may fail (a full disk): a failed write in the last 5 minutes
     * makes the daemon "degraded" (still 200: it serves what it has; 503 when reads fail) */
    char wmsg[256], wat[40];
    long wcount = 0;
    int werr = store_last_write_error(HEALTH_WRITE_WINDOW_S, wmsg, sizeof wmsg, wat, &wcount);
    /* a result's temporary file that could not be written (a full disk) is a write failure */
    if (!werr) werr = gpd_file_error_last(HEALTH_WRITE_WINDOW_S, wmsg, sizeof wmsg, wat, &wcount);
    const char *db = rc == STORE_UNREACHABLE ? "unreachable"
                     : rc != STORE_OK        ? "error"
                     : werr                  ? "write_failed"
                                             : "ok";
    json_object_set_new(j, "database", json_string(db));
    if (werr)
        json_object_set_new(j, "database_error",
                            json_pack("{s:s, s:s, s:I}", "message", wmsg, "at", wat, "count",
                                      (json_int_t)wcount));
    if (rc == STORE_OK && werr) json_object_set_new(j, "status", json_string("degraded"));
    return send_json(c, r, rc == STORE_OK ? 200 : 503, j);
}

static enum MHD_Result h_schema(struct MHD_Connection *c, req *r, const char *id)
{
    (void)id;
    const char *kind = qarg(c, "kind");
    const char *doc = kind ? gp_schema_text(kind) : gp_schema_document();
    if (!doc) {
        char kinds[256];
        gpd_kind_names(kinds, sizeof kinds, "", " or ");
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "unknown kind \"%s\"; expected %s", kind, kinds);
    }
    return send_buf(c, r, 200, "application/schema+json", (char *)doc, strlen(doc),
                    MHD_RESPMEM_PERSISTENT, NULL);
}

/* GET /metrics: the Prometheus text exposition (metrics.h) */
static enum MHD_Result h_metrics(struct MHD_Connection *c, req *r, const char *id)
{
    (void)id;
    size_t len = 0;
    char *text = metrics_render(workers_total(), workers_busy(), &len);
    if (!text) return send_error(c, r, 500, "internal", NULL, "out of memory");
    return send_buf(c, r, 200, "text/plain; version=0.0.4; charset=utf-8", text, len,
                    MHD_RESPMEM_MUST_FREE, NULL);
}

static enum MHD_Result h_dashboard(struct MHD_Connection *c, req *r, const char *id)
{
    (void)id;
    const char *html = gpd_page_html();
    if (!html) return send_error(c, r, 500, "internal", NULL, "out of memory");
    return send_buf(c, r, 200, "text/html; charset=utf-8", (char *)html, strlen(html),
                    MHD_RESPMEM_PERSISTENT, NULL);
}

/* A spec problem (schema/gp_spec.h) as the client sees it: code "internal" is a 500, any other
 * (invalid_spec, too_large) a 422 at its pointer; 400 is kept for unreadable bodies. dflt_code
 * and dflt_msg stand in for an empty code or message. */
static enum MHD_Result send_problem(struct MHD_Connection *c, req *r, const gp_spec_problem *p,
                                    const char *dflt_code, const char *dflt_msg)
{
    if (!strcmp(p->code, "internal"))
        return send_error(c, r, 500, "internal", NULL, "%s", p->message);
    return send_error(c, r, 422, p->code[0] ? p->code : dflt_code, p->pointer, "%s",
                      p->message[0] ? p->message : dflt_msg);
}

/* gpd_job_lookup (kind.h) on the store: another job's kind, status, effective spec and, once
 * it has succeeded, its result's summary */
static int lookup_job(const char *id, char kind[64], char status[16], json_t **spec,
                      json_t **summary)
{
    char *k = NULL, *text = NULL, *sum = NULL;
    *spec = NULL;
    if (summary) *summary = NULL;
    if (!gpd_id_is_plausible(id)) return 1;
    store_rc rc = store_get_text(id, "kind", &k, status);
    if (rc == STORE_OK) rc = store_get_text(id, "spec", &text, status);
    if (rc == STORE_OK && summary && !strcmp(status, "succeeded"))
        rc = store_get_summary(id, &sum, NULL, NULL, status);
    snprintf(kind, 64, "%s", k ? k : "");
    *spec = text ? json_loads(text, 0, NULL) : NULL;
    if (summary && sum) *summary = json_loads(sum, 0, NULL);
    int ok = *spec && (!sum || *summary);
    free(k);
    free(text);
    free(sum);
    if (rc == STORE_NOT_FOUND) return 1;
    if (rc == STORE_OK && ok) return 0;
    json_decref(*spec);
    *spec = NULL;
    if (summary) json_decref(*summary), *summary = NULL;
    return -1;
}

/* The body as a spec with its defaults filled in, of a kind this daemon runs, within the
 * result bound; NULL when it has been answered (400, 422, 500). A reference of the spec to
 * another job is resolved first, by the kind (gpd_kind.resolve). */
static json_t *effective_spec(struct MHD_Connection *c, req *r, const gpd_kind **kind,
                              enum MHD_Result *ret)
{
    json_error_t je;
    json_t *spec = json_loadb(r->body, r->len, JSON_REJECT_DUPLICATES, &je);
    if (!spec) {
        *ret = send_error(c, r, 400, "invalid_json", NULL,
                          "malformed JSON at line %d, column %d: %s", je.line, je.column,
                          je.text);
        return NULL;
    }
    if (!json_is_object(spec)) {
        json_decref(spec);
        *ret = send_error(c, r, 422, "invalid_spec", "",
                          ": expected a JSON object with a \"kind\"");
        return NULL;
    }
    gp_spec_problem prob;
    memset(&prob, 0, sizeof prob);
    const gpd_kind *posted = gpd_kind_find(json_string_value(json_object_get(spec, "kind")));
    if (posted && posted->resolve && posted->resolve(spec, lookup_job, &prob)) {
        json_decref(spec);
        *ret = send_problem(c, r, &prob, "invalid_spec", "invalid spec");
        return NULL;
    }
    json_t *eff = gp_spec_with_defaults(spec, &prob);
    json_decref(spec);
    if (!eff) {
        *ret = send_problem(c, r, &prob, "invalid_spec", "invalid spec");
        return NULL;
    }
    *kind = gpd_kind_find(json_string_value(json_object_get(eff, "kind")));
    if (!*kind) {
        json_decref(eff);
        char kinds[256];
        gpd_kind_names(kinds, sizeof kinds, "\"", ", ");
        *ret = send_error(c, r, 422, "invalid_spec", "/kind", "/kind: expected one of %s", kinds);
        return NULL;
    }
    /* the kind's result bound, from the spec's numbers whatever their spelling */
    if ((*kind)->bounds(eff, max_result_mb * 1e6, &prob)) {
        json_decref(eff);
        *ret = send_problem(c, r, &prob, "too_large", "");
        return NULL;
    }
    return eff;
}

static enum MHD_Result h_submit(struct MHD_Connection *c, req *r, const char *no_id)
{
    (void)no_id; /* the route has none: id is the new job's */
    if (r->len == 0)
        return send_error(c, r, 400, "invalid_json", NULL,
                          "the request body is empty; expected a JSON spec object");
    const gpd_kind *k = NULL;
    enum MHD_Result ret = MHD_NO;
    json_t *eff = effective_spec(c, r, &k, &ret);
    if (!eff) return ret;
    char *text = json_dumps(eff, JSON_COMPACT);
    /* the brief from the spec, through the kind (kind.h): a few dozen bytes in the row */
    json_t *brief = k->brief(eff, NULL);
    char *btext = brief ? json_dumps(brief, JSON_COMPACT) : NULL;
    json_decref(brief);
    char id[33];
    store_rc rc = text && btext ? store_insert(k->name, text, btext, max_queued, id) : STORE_ERROR;
    free(text);
    free(btext);
    json_decref(eff);
    if (rc == STORE_FULL) {
        char retry[16];
        snprintf(retry, sizeof retry, "%d", metrics_retry_after(workers_total()));
        return send_error_hdr(c, r, 503, "queue_full", NULL, "Retry-After", retry,
                              "the queue is full: %ld jobs are waiting, the most this daemon "
                              "queues (--max-queued %ld); submit again after Retry-After "
                              "seconds",
                              max_queued, max_queued);
    }
    if (rc != STORE_OK) return send_store_error(c, r);
    /* read back before the workers hear of it: the answer shows the job as submitted (queued),
     * not as a worker may already have claimed it a millisecond later */
    json_t *job = store_get_job(id, &rc);
    workers_notify();
    gpd_log(GPD_LOG_INFO, "job %s queued", id);
    if (!job) return send_store_error(c, r);
    char loc[64];
    snprintf(loc, sizeof loc, "/v1/jobs/%s", id);
    return send_json_hdr(c, r, 201, job, MHD_HTTP_HEADER_LOCATION, loc);
}

static int client_gone(void *arg);

/* POST /v1/shapes/analyze: outlines or an image -> their spectrum, at once (shapes.h); an
 * analysis whose client leaves stops there (its connection is then closed unanswered) */
static enum MHD_Result h_shapes(struct MHD_Connection *c, req *r, const char *id)
{
    (void)id;
    int status = 500;
    gpd_shapes_client who = {r->offloaded ? client_gone : NULL, r};
    json_t *j = gpd_shapes_analyze(r->body, r->len, &who, &status);
    if (status == SHAPES_CLIENT_GONE) {
        gpd_log(GPD_LOG_DEBUG, "http %s %s: stopped, its client has gone", r->method, r->url);
        return MHD_NO;
    }
    return send_json(c, r, (unsigned)status, j);
}

static enum MHD_Result h_list(struct MHD_Connection *c, req *r, const char *id)
{
    (void)id;
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

/* DELETE /v1/jobs/{id}?purge=1: a finished job removed (204): out of view at once, in a short
 * transaction of a few small rows whatever the job's size; its result and pack are freed, and
 * their space given back, by the maintenance thread in paced steps (maint.h), never here */
static enum MHD_Result h_purge(struct MHD_Connection *c, req *r, const char *id)
{
    char st[16];
    store_rc rc = store_purge(id, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc == STORE_CONFLICT)
        return send_error(c, r, 409, "not_finished", NULL,
                          "job %s is %s; only a finished job can be purged: cancel it first "
                          "with DELETE /v1/jobs/%s, then purge it",
                          id, st, id);
    if (rc != STORE_OK) return send_store_error(c, r);
    gpd_log(GPD_LOG_INFO, "job %s purged (was %s)", id, st);
    maint_kick();
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(0, (void *)"", MHD_RESPMEM_PERSISTENT);
    if (!resp) return MHD_NO;
    std_headers(resp, r, "application/json");
    return queue_response(c, r, 204, resp);
}

static enum MHD_Result h_cancel(struct MHD_Connection *c, req *r, const char *id)
{
    const char *purge = qarg(c, "purge");
    if (purge && (!strcmp(purge, "1") || !strcmp(purge, "true"))) return h_purge(c, r, id);
    if (purge && *purge && strcmp(purge, "0") && strcmp(purge, "false"))
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "purge: expected 1 or 0 (true or false); got \"%.32s\"", purge);
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
    std_headers(resp, r, ctype);
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
    if (rc == STORE_BUSY) return send_busy(c, r);
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

/* GET /v1/jobs/{id}/summary: the result without its per-item arrays (store_get_summary: the
 * few KB stored with the result, whatever the result's size), for pictures and result panels */
static enum MHD_Result h_summary(struct MHD_Connection *c, req *r, const char *id)
{
    char *text = NULL, st[16];
    size_t len = 0;
    store_rc rc = store_get_summary(id, &text, &len, NULL, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc != STORE_OK) return send_store_error(c, r);
    if (strcmp(st, "succeeded") || !text) {
        free(text);
        return not_ready(c, r, id, st);
    }
    return send_buf(c, r, 200, "application/json", text, len, MHD_RESPMEM_MUST_FREE, NULL);
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

static ssize_t read_svg(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos; /* read in order, once */
    size_t n = 0;
    if (svg_job_read(cls, buf, max, &n)) return MHD_CONTENT_READER_END_WITH_ERROR;
    return n ? (ssize_t)n : MHD_CONTENT_READER_END_OF_STREAM;
}

static void free_svg(void *cls)
{
    svg_job_close(cls);
}

/* a handler of a job's resource that depends on its kind (svg, export): st is its status */
typedef enum MHD_Result (*kind_handler)(struct MHD_Connection *c, req *r, const char *id,
                                        const gpd_kind *k, const char *st);

/* Looks up the kind of job id once and answers by h: 404 for an unknown job, 500 when the store
 * fails or the job is of a kind this daemon does not run. */
static enum MHD_Result with_kind(struct MHD_Connection *c, req *r, const char *id,
                                 kind_handler h)
{
    char *name = NULL, st[16];
    store_rc rc = store_get_text(id, "kind", &name, st);
    const gpd_kind *k = rc == STORE_OK ? gpd_kind_find(name) : NULL;
    enum MHD_Result ret;
    if (rc == STORE_NOT_FOUND) ret = not_found(c, r, id);
    else if (rc != STORE_OK || !name) ret = send_store_error(c, r);
    else if (!k)
        ret = send_error(c, r, 500, "internal", NULL, "job %s is of kind \"%.64s\", which "
                         "this daemon does not run", id, name);
    else ret = h(c, r, id, k, st);
    free(name);
    return ret;
}

/* The options of ?view= (color, width, z); -1 when a bad one has been answered (400). */
static int svg_options(struct MHD_Connection *c, req *r, gp_svg_options *opt,
                       enum MHD_Result *ret)
{
    memset(opt, 0, sizeof *opt);
    opt->color = qarg(c, "color");
    const char *w = qarg(c, "width"), *z = qarg(c, "z");
    if (w) {
        char *end;
        long v = strtol(w, &end, 10);
        if (*end || v < 16 || v > 16384) {
            *ret = send_error(c, r, 400, "invalid_parameter", NULL,
                              "width: expected an integer in [16, 16384]");
            return -1;
        }
        opt->width = (int)v;
    }
    if (z) {
        char *end;
        double v = strtod(z, &end);
        if (*end || end == z) {
            *ret = send_error(c, r, 400, "invalid_parameter", NULL,
                              "z: expected a number (metres)");
            return -1;
        }
        opt->has_z = 1;
        opt->z = v;
    }
    return 0;
}

static enum MHD_Result h_svg(struct MHD_Connection *c, req *r, const char *id,
                            const gpd_kind *k, const char *st)
{
    enum MHD_Result ret = MHD_NO;
    const char *view = qarg(c, "view");
    if (!view || !*view || !gpd_kind_view(k, view)) {
        char views[256];
        gpd_kind_view_list(k, views, sizeof views);
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "view: expected one of %s for kind %s%s%.64s%s", views, k->name,
                          view ? "; got \"" : "", view ? view : "", view ? "\"" : "");
    }
    gp_svg_options opt;
    if (svg_options(c, r, &opt, &ret)) return ret;
    /* drawn from the job's summary and its items read one at a time (the export pack or the
     * stored result walked element by element), streamed: bounded memory (svg_job.h) */
    svg_job *sj = NULL;
    gpd_err err;
    char now[16]; /* the status as the picture finds it */
    svg_job_rc jr = svg_job_open(id, k->name, view, &opt, &sj, now, &err);
    if (jr == SVG_JOB_NOT_FOUND) return not_found(c, r, id);
    if (jr == SVG_JOB_NOT_READY) return not_ready(c, r, id, now);
    if (jr == SVG_JOB_STORE_ERROR) return send_store_error(c, r);
    if (jr == SVG_JOB_BUSY) return send_busy(c, r);
    if (jr != SVG_JOB_OK) {
        int status = err.status < 400 || err.status > 599 ? 500 : err.status;
        return send_error(c, r, (unsigned)status,
                          status == 400 ? "invalid_parameter"
                          : status == 409 ? "not_available"
                                          : "internal",
                          NULL, "%s", err.msg[0] ? err.msg : "cannot render this view");
    }
    return send_stream(c, r, "image/svg+xml", MHD_SIZE_UNKNOWN, read_svg, sj, free_svg, NULL);
}

/* An export being downloaded: the pack (in memory when small, else an SQLite stream) and the
 * format's pull stream over it. */
typedef struct export_dl {
    store_stream *stream;
    char *pack;
    gp_export *e;
} export_dl;

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

/* 1 when the pack behind src is a view pack (gp_export.h: drawn, never exported); a pack
 * that cannot be read is left to gp_export_open to report */
static int view_pack(const gp_export_source *src)
{
    gp_export_info info;
    return gp_export_pack_info(src, &info, NULL) == GP_OK && (info.flags & GP_EXPORT_VIEW_ONLY);
}

/* The pack of job id opened into d (export_dl: in memory or streamed) and the export of it in
 * format f; -1 when it has been answered (404, 409 without a pack or with a view pack only,
 * 500). */
static int export_open(struct MHD_Connection *c, req *r, const char *id, const gpd_kind *k,
                       int f, export_dl *d, enum MHD_Result *ret)
{
    char st[16];
    size_t len = 0;
    store_rc rc = store_stream_open(id, "pack", STREAM_SMALL, &d->stream, &d->pack, &len, st);
    gp_export_source src = {0};
    if (rc == STORE_OK && (d->pack || d->stream)) {
        js_source v = store_value_source(d->pack, len, d->stream);
        src = (gp_export_source){v.read, v.user, v.size};
    }
    int none = rc == STORE_OK && (!src.read || view_pack(&src));
    if (rc == STORE_NOT_FOUND) *ret = not_found(c, r, id);
    else if (rc == STORE_BUSY) *ret = send_busy(c, r);
    else if (rc != STORE_OK) *ret = send_store_error(c, r);
    else if (none)
        *ret = send_error(c, r, 409, "missing_output", "/outputs",
                          "job %s has no %s to export (its spec did not ask for it): submit "
                          "the spec again with \"%s\" in outputs",
                          id, k->pack_what, k->pack_output);
    if (rc != STORE_OK || none) return -1;
    gp_export_info info;
    if (gp_export_format_needs_clumps(f, k->export_dim) && gp_export_pack_info(&src, &info, NULL) == GP_OK &&
        !(info.flags & GP_EXPORT_HAS_CLUMPS)) {
        *ret = send_error(c, r, 409, "missing_output", "/outputs",
                          "job %s has no clumps to export to %s (its spec did not ask for them): "
                          "submit the spec again with \"clumps\" in outputs",
                          id, gp_export_format_name(f));
        return -1;
    }
    gp_error err;
    if (gp_export_open(f, &src, &d->e, &err) == GP_OK) return 0;
    if (!store_reachable()) /* the pack's stream broke with the server */
        *ret = send_store_error(c, r);
    else
        *ret = send_error(c, r, 500, "internal", NULL, "cannot export: %s", err.message);
    return -1;
}

/* An export the kind writes itself (kind.h: gpd_kind_export), from the job's summary */
static enum MHD_Result kind_export(struct MHD_Connection *c, req *r, const char *id,
                                   const gpd_kind_export *e)
{
    char *text = NULL, st[16];
    size_t len = 0;
    store_rc rc = store_get_summary(id, &text, &len, NULL, st);
    if (rc == STORE_NOT_FOUND) return not_found(c, r, id);
    if (rc != STORE_OK) return send_store_error(c, r);
    json_t *sum = text ? json_loadb(text, len, 0, NULL) : NULL;
    free(text);
    if (!sum) return send_error(c, r, 500, "internal", NULL, "the stored summary is not JSON");
    gpd_err err = {0, ""};
    char *file = e->write(sum, &len, &err);
    json_decref(sum);
    if (!file)
        return send_error(c, r, err.status == 409 ? 409 : 500,
                          err.status == 409 ? "missing_output" : "internal",
                          err.status == 409 ? "/outputs" : NULL, "%s", err.msg);
    struct MHD_Response *resp = MHD_create_response_from_buffer(len, file, MHD_RESPMEM_MUST_FREE);
    if (!resp) {
        free(file);
        return MHD_NO;
    }
    char disp[160];
    snprintf(disp, sizeof disp, "attachment; filename=\"%s-%s.%s\"", id, e->format,
             e->extension);
    std_headers(resp, r, e->mime);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_DISPOSITION, disp);
    return queue_response(c, r, 200, resp);
}

static enum MHD_Result h_export(struct MHD_Connection *c, req *r, const char *id,
                               const gpd_kind *k, const char *st)
{
    enum MHD_Result ret = MHD_NO;
    const char *format = qarg(c, "format");
    const gpd_kind_export *own = gpd_kind_export_find(k, format);
    int f = own ? -1 : gp_export_format_parse(format);
    if (!own && (f < 0 || !gp_export_format_supports(f, k->export_dim))) {
        char formats[256];
        gpd_kind_export_list(k, formats, sizeof formats);
        if (!formats[0]) /* a kind without export formats (kind.h: no exports, export_dim 0) */
            return send_error(c, r, 400, "invalid_parameter", NULL,
                              "format: a job of kind %s has no export formats in this version%s"
                              "%.64s%s", k->name, format ? "; got \"" : "", format ? format : "",
                              format ? "\"" : "");
        return send_error(c, r, 400, "invalid_parameter", NULL,
                          "format: expected one of %s%s%.64s%s", formats,
                          format ? "; got \"" : "", format ? format : "", format ? "\"" : "");
    }
    if (strcmp(st, "succeeded")) return not_ready(c, r, id, st);
    if (own) return kind_export(c, r, id, own);
    export_dl *d = calloc(1, sizeof *d);
    if (!d) return send_error(c, r, 500, "internal", NULL, "out of memory");
    if (export_open(c, r, id, k, f, d, &ret)) {
        free_export(d);
        return ret;
    }
    char disp[160];
    snprintf(disp, sizeof disp, "attachment; filename=\"%s-%s.%s\"", id,
             gp_export_format_name(f), gp_export_format_extension_in(f, k->export_dim));
    return send_stream(c, r, gp_export_format_mime_in(f, k->export_dim), MHD_SIZE_UNKNOWN,
                       read_export, d, free_export, disp);
}

/* GET /v1/jobs/{id}/svg and /export: by the job's kind */
static enum MHD_Result h_job_svg(struct MHD_Connection *c, req *r, const char *id)
{
    return with_kind(c, r, id, h_svg);
}

static enum MHD_Result h_job_export(struct MHD_Connection *c, req *r, const char *id)
{
    return with_kind(c, r, id, h_export);
}

/* the functions of the route table's handlers (routes.h); gpd_http_start checks that every
 * handler the table names has one */
static const handler_fn handlers[GPD_H_COUNT] = {
    [GPD_H_DASHBOARD] = h_dashboard, [GPD_H_METRICS] = h_metrics,
    [GPD_H_HEALTH] = h_health,       [GPD_H_SCHEMA] = h_schema,
    [GPD_H_SHAPES] = h_shapes,       [GPD_H_LIST] = h_list,
    [GPD_H_SUBMIT] = h_submit,       [GPD_H_JOB] = h_job,
    [GPD_H_CANCEL] = h_cancel,       [GPD_H_RESULT] = h_result,
    [GPD_H_SVG] = h_job_svg,         [GPD_H_EXPORT] = h_job_export,
    [GPD_H_SPEC] = h_spec,           [GPD_H_SUMMARY] = h_summary,
};

/* a CORS preflight of an accepted origin: 204 with what it may send */
static enum MHD_Result preflight(struct MHD_Connection *c, req *r)
{
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(0, (void *)"", MHD_RESPMEM_PERSISTENT);
    if (!resp) return MHD_NO;
    std_headers(resp, r, "text/plain");
    MHD_add_response_header(resp, "Access-Control-Allow-Methods", "GET, HEAD, POST, DELETE");
    MHD_add_response_header(resp, "Access-Control-Allow-Headers", "Content-Type");
    MHD_add_response_header(resp, "Access-Control-Max-Age", "600");
    return queue_response(c, r, 204, resp);
}

/* Checks made before routing: the length of the request target, Host and Origin (origin.h).
 * Returns 1 when a response has been queued (in *ret), 0 to go on. */
static int gate(struct MHD_Connection *c, req *r, const char *method, enum MHD_Result *ret)
{
    const char *host = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    const char *origin = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Origin");
    char hname[264];
    int hport = -1;
    int have_host = host && *host && origin_host_ok(host, hname, sizeof hname, &hport);
    if (r->url_len > GPD_MAX_URL)
        *ret = send_error(c, r, 414, "uri_too_long", NULL,
                          "the request target (path and query) is %zu bytes, over the limit of "
                          "%d bytes",
                          r->url_len, GPD_MAX_URL);
    else if (host && *host && !have_host)
        *ret = send_error(c, r, 403, "forbidden_host", NULL,
                          "Host \"%.100s\" is not a name of this server (%s); use "
                          "localhost, 127.0.0.1 or the address it listens on",
                          host, origin_own_url());
    else if (origin && *origin && !origin_ok(origin, have_host ? hname : NULL, hport))
        *ret = send_error(c, r, 403, "forbidden_origin", NULL,
                          "Origin \"%.100s\" may not call this server: only pages it "
                          "serves itself (%s) and origins given with --allow-origin may",
                          origin, origin_own_url());
    else if (!origin || !*origin)
        return 0;
    else {
        if (strlen(origin) < sizeof r->acao) snprintf(r->acao, sizeof r->acao, "%s", origin);
        if (strcmp(method, "OPTIONS") ||
            !MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Access-Control-Request-Method"))
            return 0;
        *ret = preflight(c, r);
    }
    return 1;
}

/* ------------------------------------------------------------------ routing */

static enum MHD_Result method_not_allowed(struct MHD_Connection *c, req *r, const char *method,
                                          const char *url, const char *allow)
{
    return send_error_allow(c, r, 405, "method_not_allowed", NULL, allow,
                            "%s is not allowed on %s; allowed: %s", method, url, allow);
}

/* Whether the client of suspended request r has closed its connection (libmicrohttpd does not
 * look at a suspended connection): the end of the stream, or an error, at the socket. A
 * pipelined request waiting there is a client still present. */
static int client_gone(void *arg)
{
    req *r = arg;
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(r->conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (!ci) return 0;
    char b;
    ssize_t n = recv(ci->connect_fd, &b, 1, MSG_PEEK | MSG_DONTWAIT);
    return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
}

/* runs r's handler on a pool thread, then wakes its connection; the work of a client that has
 * gone meanwhile (an analysis given up after a second) is dropped unanswered */
static void run_offloaded(void *arg)
{
    req *r = arg;
    if (client_gone(r)) {
        gpd_log(GPD_LOG_DEBUG, "http %s %s: dropped, its client has gone", r->method, r->url);
        r->status = -1; /* close it */
    } else if (r->handler(r->conn, r, r->id) != MHD_YES && !r->resp) {
        r->status = -1;
    }
    MHD_resume_connection(r->conn);
}

/* Answers r by h off the HTTP threads, on the pool's lane (offload.h): the connection is
 * suspended until the response is ready, and on_request queues it. A full lane is a 503 busy
 * with Retry-After; where the pool does not take it (shutting down), h runs here. */
static enum MHD_Result offload(struct MHD_Connection *c, req *r, handler_fn h, int lane)
{
    r->conn = c;
    r->handler = h;
    r->offloaded = 1;
    MHD_suspend_connection(c);
    int retry_s = 1;
    int rc = gpd_offload_submit((gpd_lane)lane, run_offloaded, client_gone, r, &retry_s);
    if (rc == 0) return MHD_YES;
    MHD_resume_connection(c);
    r->offloaded = 0;
    if (rc < 0) return h(c, r, r->id);
    char retry[16];
    snprintf(retry, sizeof retry, "%d", retry_s);
    return send_error_hdr(c, r, 503, "busy", NULL, "Retry-After", retry,
                          "the daemon is busy: %u %s are waiting, the most it queues "
                          "(--max-pending %u); send again after Retry-After seconds",
                          max_pending, lane == GPD_LANE_ANALYSIS ? "shape analyses" : "submits",
                          max_pending);
}

/* Answers r by the route table (routes.h): 404 for a path no route matches, 405 with the
 * route's Allow for a method it does not answer, 404 for an {id} that cannot be a job id, else
 * the method's handler, offloaded or here. */
static enum MHD_Result route(struct MHD_Connection *c, req *r, const char *url,
                             const char *method)
{
    /* canonical path, for the messages: drop one trailing slash (but keep "/"), as the
     * matcher does */
    char path[512];
    size_t ul = strlen(url);
    if (ul >= sizeof path)
        return send_error(c, r, 404, "not_found", NULL, "no such resource");
    memcpy(path, url, ul + 1);
    if (ul > 1 && path[ul - 1] == '/') path[--ul] = '\0';

    const gpd_route *rt = r->route;
    if (!rt) return send_error(c, r, 404, "not_found", NULL, "no such resource: %.128s", path);
    int m = gpd_route_method_of(method);
    if (!gpd_route_answers(rt, m))
        return method_not_allowed(c, r, method, path, gpd_route_allow(rt));
    const gpd_route_op *op = &rt->op[m];
    handler_fn h = handlers[op->handler];
    if (!h) return send_error(c, r, 500, "internal", NULL, "no handler for %s %s", method, path);
    if (r->id[0] && !gpd_id_is_plausible(r->id)) return not_found(c, r, r->id);
    return op->offload ? offload(c, r, h, op->lane) : h(c, r, r->id);
}

/* What the headers say of the request's framing and size (scan_header). */
typedef struct head_scan {
    unsigned n_length, n_encoding; /* Content-Length and Transfer-Encoding headers */
    const char *encoding;          /* the last Transfer-Encoding */
    size_t bytes;                  /* the header lines as sent, about */
} head_scan;

static enum MHD_Result scan_header(void *cls, enum MHD_ValueKind kind, const char *key,
                                   const char *value)
{
    (void)kind;
    head_scan *h = cls;
    h->bytes += strlen(key) + (value ? strlen(value) : 0) + 4; /* ": " and CRLF */
    if (!strcasecmp(key, MHD_HTTP_HEADER_CONTENT_LENGTH)) h->n_length++;
    if (!strcasecmp(key, MHD_HTTP_HEADER_TRANSFER_ENCODING)) {
        h->n_encoding++;
        h->encoding = value;
    }
    return MHD_YES;
}

/* value is exactly the token tok, but for spaces around it and case */
static int is_token(const char *value, const char *tok)
{
    if (!value) return 0;
    value += strspn(value, " \t");
    size_t n = strlen(tok), rest;
    if (strncasecmp(value, tok, n)) return 0;
    rest = strspn(value + n, " \t");
    return value[n + rest] == '\0';
}

/* A refusal of the request as framed, answered at once and with the connection closed: what
 * follows on it cannot be told apart from this request's body. */
#define send_error_close(c, r, status, code, ...) \
    send_error_hdr(c, r, status, code, NULL, MHD_HTTP_HEADER_CONNECTION, "close", __VA_ARGS__)

/* The headers' size and the body's framing: 431 for headers over GPD_MAX_HEADERS, 400 for a
 * body announced both by Content-Length and Transfer-Encoding (libmicrohttpd reads such a body
 * as chunked, a proxy in front may read it by its length: the bytes one takes for the next
 * request are the other's body, a smuggled request), for more than one of either header, and
 * for a transfer coding other than chunked. Returns 1 when a response has been queued (in
 * *ret), 0 to go on. */
static int framing(struct MHD_Connection *c, req *r, enum MHD_Result *ret)
{
    head_scan h = {0, 0, NULL, 0};
    MHD_get_connection_values(c, MHD_HEADER_KIND, scan_header, &h);
    if (h.bytes + r->url_len > GPD_MAX_HEADERS)
        *ret = send_error_close(c, r, 431, "headers_too_large",
                                "the request line and headers are %zu bytes, over the limit of "
                                "%u bytes", h.bytes + r->url_len, GPD_MAX_HEADERS);
    else if (h.n_length && h.n_encoding)
        *ret = send_error_close(c, r, 400, "invalid_request",
                                "the request has both Content-Length and Transfer-Encoding; "
                                "send one of them");
    else if (h.n_length > 1 || h.n_encoding > 1)
        *ret = send_error_close(c, r, 400, "invalid_request",
                                "the request has more than one %s header",
                                h.n_length > 1 ? "Content-Length" : "Transfer-Encoding");
    else if (h.n_encoding && !is_token(h.encoding, "chunked"))
        *ret = send_error_close(c, r, 400, "invalid_request",
                                "Transfer-Encoding \"%.64s\" is not taken; send the body with "
                                "Content-Length or Transfer-Encoding: chunked",
                                h.encoding ? h.encoding : "");
    else
        return 0;
    return 1;
}

static enum MHD_Result send_too_large(struct MHD_Connection *c, req *r, const char *method,
                                      int now)
{
    const char *pattern = r->route ? r->route->pattern : r->url;
    if (now) /* before reading it: the connection goes with the unread body */
        return send_error_close(c, r, 413, "payload_too_large",
                                "the request body is over the limit of %zu bytes for %s %s",
                                r->limit, method, pattern);
    return send_error(c, r, 413, "payload_too_large", NULL,
                      "the request body is over the limit of %zu bytes for %s %s", r->limit,
                      method, pattern);
}

/* The body limit of r's route and method (routes.h), and a body announced over it: answered
 * 413 at once when the client waits for 100 Continue (it sends nothing), or when it is more
 * than GPD_DRAIN_MAX over (reading it would cost more than the answer is worth); else it is
 * read, dropped, and answered 413 once read, so that a client that sends without waiting (as
 * Python's urllib does) reads the answer instead of a reset. */
static enum MHD_Result announced_body(struct MHD_Connection *c, req *r, const char *method)
{
    int m = gpd_route_method_of(method);
    r->limit = r->route && m >= 0 && r->route->op[m].offload ? max_body : GPD_ROUTE_NO_BODY_MAX;
    const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
                                                 MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (!cl) return MHD_YES;
    char *end = NULL;
    unsigned long long n = strtoull(cl, &end, 10);
    if (!end || *end != '\0' || n <= r->limit) return MHD_YES;
    r->too_big = 1;
    const char *expect = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_EXPECT);
    if (!is_token(expect, "100-continue") && n - r->limit <= GPD_DRAIN_MAX) return MHD_YES;
    r->refused = 1;
    return send_too_large(c, r, method, 1);
}

/* The first call of a request: its headers are in. */
static enum MHD_Result request_start(struct MHD_Connection *c, req *r, const char *method)
{
    gpd_conns_headers_done(c);
    /* 414, 403 forbidden_host / forbidden_origin, CORS preflight, 431 and the framing's 400:
     * before anything else, so that a refused request creates or reads nothing */
    enum MHD_Result ret;
    if (gate(c, r, method, &ret) || framing(c, r, &ret)) {
        r->refused = 1;
        return ret;
    }
    return announced_body(c, r, method);
}

/* Body bytes not kept (over the limit, a refused request's): read up to GPD_DRAIN_MAX over the
 * limit, then the connection is closed (the answer could no longer be queued). */
static enum MHD_Result drop_body(req *r, size_t n)
{
    r->dropped += n;
    return r->dropped > r->limit + GPD_DRAIN_MAX ? MHD_NO : MHD_YES;
}

/* Frees r's body (its bytes leave the bodies held); returns the bytes it had read. */
static size_t release_body(req *r)
{
    atomic_fetch_sub(&bodies_held, r->cap);
    free(r->body);
    r->body = NULL;
    size_t had = r->len;
    r->len = r->cap = 0;
    return had;
}

/* 503 busy: the bodies held by every connection are at their bound */
static enum MHD_Result send_bodies_busy(struct MHD_Connection *c, req *r)
{
    char retry[16];
    snprintf(retry, sizeof retry, "%d", BODY_BUSY_RETRY_S);
    return send_error_hdr(c, r, 503, "busy", NULL, "Retry-After", retry,
                          "the request bodies this daemon holds are at their bound (%d times "
                          "--max-body); try again in %d s", BODIES_HELD_MAX, BODY_BUSY_RETRY_S);
}

/* A piece of the body: kept for POST, counted for the others (their bodies are ignored). */
static enum MHD_Result body_piece(req *r, const char *method, const char *data, size_t n)
{
    if (r->too_big || r->busy || r->refused) return drop_body(r, n);
    if (r->len + n > r->limit) {
        r->too_big = 1;
        return drop_body(r, release_body(r) + n);
    }
    if (strcmp(method, "POST")) {
        r->len += n; /* counted against the limit, not kept */
        return MHD_YES;
    }
    if (r->len + n + 1 > r->cap) {
        size_t cap = r->cap ? r->cap : 4096;
        while (cap < r->len + n + 1) cap *= 2;
        if (cap > r->limit + 1) cap = r->limit + 1;
        size_t grow = cap - r->cap, bound = BODIES_HELD_MAX * max_body;
        if (atomic_fetch_add(&bodies_held, grow) + grow > bound) {
            atomic_fetch_sub(&bodies_held, grow);
            r->busy = 1;
            return drop_body(r, release_body(r) + n);
        }
        char *b = realloc(r->body, cap);
        if (!b) {
            atomic_fetch_sub(&bodies_held, grow);
            return MHD_NO;
        }
        r->body = b;
        r->cap = cap;
    }
    memcpy(r->body + r->len, data, n);
    r->len += n;
    return MHD_YES;
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    req *r = *con_cls;
    if (!r || URI_LEN_TAGGED(r)) {
        /* the length of the request target as sent, from on_uri (the path alone without it) */
        size_t url_len = r ? (size_t)((uintptr_t)r >> 1) : strlen(url);
        r = calloc(1, sizeof *r);
        if (!r) return MHD_NO;
        r->t0 = gpd_monotonic_s();
        r->url_len = url_len;
        snprintf(r->method, sizeof r->method, "%s", method);
        snprintf(r->url, sizeof r->url, "%s", url);
        r->route = gpd_route_match(url, r->id, sizeof r->id);
        *con_cls = r;
        return request_start(c, r, method);
    }
    if (*upload_data_size) {
        size_t n = *upload_data_size;
        *upload_data_size = 0;
        return body_piece(r, method, upload_data, n);
    }
    if (r->offloaded) {
        /* resumed: the pool thread's response, or none (out of memory, client gone): close */
        struct MHD_Response *resp = r->resp;
        r->resp = NULL;
        r->offloaded = 0;
        if (!resp) return MHD_NO;
        enum MHD_Result ret = MHD_queue_response(c, (unsigned)r->status, resp);
        MHD_destroy_response(resp);
        return ret;
    }
    if (r->refused) return MHD_YES; /* answered at the first call */
    if (r->too_big) return send_too_large(c, r, method, 0);
    if (r->busy) return send_bodies_busy(c, r);
    return route(c, r, url, method);
}

/* Called by libmicrohttpd as soon as the request line is read, with the request target as
 * sent (path and query, still escaped): its length decides 414 before anything else. It
 * reaches on_request through *con_cls as an odd integer (a req pointer is even), so that
 * nothing is allocated before the access handler runs: libmicrohttpd drops some requests it
 * cannot parse without calling on_completed. */
static void *on_uri(void *cls, const char *uri, struct MHD_Connection *c)
{
    (void)cls;
    (void)c;
    size_t n = strlen(uri);
    if (n > SIZE_MAX / 4) n = SIZE_MAX / 4;
    return (void *)(((uintptr_t)n << 1) | 1u);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    req *r = *con_cls;
    if (!r || URI_LEN_TAGGED(r)) {
        *con_cls = NULL;
        return;
    }
    if (gpd_log_enabled(GPD_LOG_DEBUG)) {
        gpd_log(GPD_LOG_DEBUG, "http %s %s %d %.3f ms%s", r->method, r->url, r->status,
                1e3 * (gpd_monotonic_s() - r->t0),
                toe == MHD_REQUEST_TERMINATED_COMPLETED_OK ? "" : " (aborted)");
    }
    /* by the route matched when the request arrived (refused ones too) */
    metrics_http_request(r->route, r->status);
    gpd_conns_request_done(c);
    if (r->resp) MHD_destroy_response(r->resp);
    release_body(r);
    free(r);
    *con_cls = NULL;
}

static void mhd_log(void *cls, const char *fmt, va_list ap)
{
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, ap);
    size_t n = strlen(msg);
    while (n && (msg[n - 1] == '\n' || msg[n - 1] == '\r')) msg[--n] = '\0';
    /* a client that hung up or timed out is routine (a slow client closed at
     * --header-timeout, a poller gone): one line each at warn would fill the log */
    int routine = strstr(msg, "closed") || strstr(msg, "disconnected") || strstr(msg, "timed out") ||
                  strstr(msg, "timeout");
    gpd_log(routine ? GPD_LOG_DEBUG : GPD_LOG_WARN, "mhd: %s", msg);
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

/* Whether every handler the route table names has its function here (a route added to the
 * table without one would answer 500). */
static int handlers_complete(void)
{
    size_t n = 0;
    const gpd_route *rt = gpd_routes(&n);
    int ok = 1;
    for (size_t i = 0; i < n; i++)
        for (int m = 0; m < GPD_ROUTE_NMETHODS; m++) {
            gpd_handler h = rt[i].op[m].handler;
            if (h == GPD_H_NONE || (h > GPD_H_NONE && h < GPD_H_COUNT && handlers[h])) continue;
            gpd_log(GPD_LOG_ERROR, "route %s %s has no handler in http.c",
                    gpd_route_method_name(m), rt[i].pattern);
            ok = 0;
        }
    return ok;
}

int gpd_http_start(const gpd_http_config *cfg)
{
    if (!handlers_complete()) return -1;
    max_body = cfg->max_body;
    max_pending = cfg->max_pending;
    if (cfg->max_result_mb > 0) max_result_mb = cfg->max_result_mb;
    max_queued = cfg->max_queued;
    started_at = gpd_monotonic_s();
    origin_setup(cfg->listen, cfg->host, cfg->port);
    if (gpd_page_init() != 0) {
        gpd_log(GPD_LOG_ERROR, "cannot build the dashboard page (out of memory)");
        return -1;
    }
    if (gpd_offload_start(cfg->threads, cfg->max_pending) != 0) {
        gpd_log(GPD_LOG_ERROR, "cannot start the request pool");
        return -1;
    }
    if (gpd_conns_start(cfg->header_timeout_s, cfg->timeout_s) != 0) {
        gpd_log(GPD_LOG_ERROR, "cannot start the connection watch");
        gpd_offload_stop();
        return -1;
    }
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_ERROR_LOG | MHD_USE_AUTO |
                     MHD_USE_ITC | MHD_ALLOW_SUSPEND_RESUME;
    daemon_ = MHD_start_daemon(
        flags, 0, NULL, NULL, &on_request, NULL, MHD_OPTION_EXTERNAL_LOGGER, &mhd_log, NULL,
        MHD_OPTION_LISTEN_SOCKET, cfg->listen_fd,
        MHD_OPTION_THREAD_POOL_SIZE, cfg->threads, MHD_OPTION_CONNECTION_LIMIT,
        cfg->max_connections, MHD_OPTION_PER_IP_CONNECTION_LIMIT, cfg->per_ip,
        MHD_OPTION_CONNECTION_TIMEOUT, cfg->timeout_s,
        MHD_OPTION_NOTIFY_CONNECTION, &gpd_conns_notify, NULL,
        /* a request line and headers up to this size reach on_uri and on_request, which
         * answer a JSON 414 above GPD_MAX_URL and 431 above GPD_MAX_HEADERS; past it
         * libmicrohttpd answers 414 or 431 itself. The pool is mmap'ed: pages are used only
         * as far as a client fills them. */
        MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)GPD_CONN_MEMORY,
        MHD_OPTION_URI_LOG_CALLBACK, &on_uri, NULL, MHD_OPTION_NOTIFY_COMPLETED,
        &on_completed, NULL, MHD_OPTION_END);
    if (!daemon_) {
        gpd_log(GPD_LOG_ERROR, "cannot start the HTTP server");
        gpd_conns_stop();
        gpd_offload_stop();
        return -1;
    }
    return 0;
}

void gpd_http_stop(void)
{
    if (!daemon_) return;
    /* every suspended connection is resumed (its task run) before the daemon stops; not
     * MHD_quiesce_daemon: in libmicrohttpd 0.9.75 it races with a pool thread that removes
     * the listening socket from its epoll set on its own, and aborts the process ("Failed to
     * remove listen FD from epoll set", seen in it_test_bad_inputs under ASan).
     * MHD_stop_daemon closes the listening socket. */
    gpd_offload_stop();
    MHD_stop_daemon(daemon_);
    daemon_ = NULL;
    gpd_conns_stop();
}
