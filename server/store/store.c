/* store.c -- the job store's dispatch to its back end (store_impl.h) and what the back ends
 * share: the last failed write, result summaries, values as byte sources. */
#define _GNU_SOURCE /* pread */
#include "store/store_impl.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util/json_scan.h"

/* chosen by store_open (before any thread) and kept to the end: reads need no lock */
static const store_backend *be = &store_sqlite;
static double lease_s = STORE_LEASE_DEFAULT_S;
static int max_connections = STORE_MAX_CONNECTIONS_DEFAULT;
static void (*cancel_hook)(const char *id) = NULL;
static void (*wal_hook)(void) = NULL;

int store_is_url(const char *target)
{
    return !strncmp(target, "postgresql://", 13) || !strncmp(target, "postgres://", 11);
}

void store_set_lease(double seconds)
{
    lease_s = seconds > 0 ? seconds : STORE_LEASE_DEFAULT_S;
}

double store_lease(void)
{
    return lease_s;
}

void store_set_max_connections(int n)
{
    max_connections = n > 0 ? n : STORE_MAX_CONNECTIONS_DEFAULT;
}

int store_max_connections(void)
{
    return max_connections;
}

void store_on_cancel(void (*fn)(const char *id))
{
    __atomic_store_n(&cancel_hook, fn, __ATOMIC_RELEASE);
}

void store_cancel_seen(const char *id)
{
    void (*fn)(const char *) = __atomic_load_n(&cancel_hook, __ATOMIC_ACQUIRE);
    if (fn) fn(id);
}

void store_on_wal_grown(void (*fn)(void))
{
    __atomic_store_n(&wal_hook, fn, __ATOMIC_RELEASE);
}

void store_wal_grown_seen(void)
{
    void (*fn)(void) = __atomic_load_n(&wal_hook, __ATOMIC_ACQUIRE);
    if (fn) fn();
}

char *store_spill_dir(void)
{
    return be->spill_dir();
}

const char *store_backend_name(void)
{
    return be->name;
}

int store_open(const char *target)
{
    be = store_is_url(target) ? &store_pg : &store_sqlite;
    return be->open(target);
}

void store_close(void) { be->close(); }
void store_thread_done(void) { be->thread_done(); }
int store_recover(int *requeued, int *failed) { return be->recover(requeued, failed); }

store_rc store_insert(const char *kind, const char *spec_json, const char *brief_json,
                      long max_queued, char id_out[33])
{
    return be->insert(kind, spec_json, brief_json, max_queued, id_out);
}

int store_fill_briefs(store_brief_fn make) { return be->fill_briefs(make); }
json_t *store_get_job(const char *id, store_rc *rc) { return be->get_job(id, rc); }

store_rc store_get_text(const char *id, const char *column, char **text, char status[16])
{
    return be->get_text(id, column, text, status);
}

json_t *store_list(const char *status, int limit, const char *after, store_rc *rc)
{
    return be->list(status, limit, after, rc);
}

static const char *const status_names[STORE_NSTATUS] = {"queued", "running", "succeeded",
                                                        "failed", "cancelled"};

int store_status_slot(const char *status)
{
    for (int i = 0; status && i < STORE_NSTATUS; i++)
        if (!strcmp(status, status_names[i])) return i;
    return -1;
}

store_rc store_counts(long *queued, long *running, long *succeeded, long *failed,
                      long *cancelled)
{
    long n[STORE_NSTATUS] = {0};
    store_rc rc = be->counts(n);
    if (rc != STORE_OK) return rc;
    long *out[STORE_NSTATUS] = {queued, running, succeeded, failed, cancelled};
    for (int i = 0; i < STORE_NSTATUS; i++)
        if (out[i]) *out[i] = n[i];
    return STORE_OK;
}

store_rc store_counts_within(double wait_s, long n[STORE_NSTATUS])
{
    memset(n, 0, STORE_NSTATUS * sizeof *n);
    return be->counts_within(n, wait_s);
}

int store_reachable(void) { return !be || !be->reachable || be->reachable(); }

store_rc store_claim(char id[33], char **kind, char **spec_json, int *attempts)
{
    return be->claim(id, kind, spec_json, attempts);
}

store_rc store_progress(const char *id, const char *progress_json)
{
    return be->progress(id, progress_json);
}

store_rc store_fail(const char *id, const char *code, const char *message)
{
    return be->fail(id, code, message);
}

store_rc store_requeue(const char *id) { return be->requeue(id); }

store_rc store_cancel(const char *id, int *was_running, char status_out[16], char kind_out[64])
{
    return be->cancel(id, was_running, status_out, kind_out);
}

store_rc store_purge(const char *id, char status_out[16]) { return be->purge(id, status_out); }

int store_purge_finished_before(const char *before, int max)
{
    return be->purge_finished_before(before, max);
}

int store_free_purged(void) { return be->free_purged(); }
int store_vacuum_step(void) { return be->vacuum_step(); }

int store_reclaim(void)
{
    int rc;
    while ((rc = be->free_purged()) > 0) {
    }
    while (rc == 0 && (rc = be->vacuum_step()) > 0) {
    }
    return rc < 0 ? -1 : be->checkpoint(0);
}
int store_checkpoint(int may_yield) { return be->checkpoint(may_yield); }
void store_checkpoint_yield(void) { be->checkpoint_yield(); }

int store_count_by_kind(void (*fn)(void *user, const char *kind, const char *status, long n),
                        void *user)
{
    return be->count_by_kind(fn, user);
}

int store_size(long long *bytes) { return be->size(bytes); }

store_rc store_stream_open(const char *id, const char *what, size_t small, store_stream **out,
                           char **text, size_t *text_len, char status[16])
{
    *out = NULL;
    *text = NULL;
    *text_len = 0;
    status[0] = 0;
    int is_pack = !strcmp(what, "pack");
    if (!is_pack && strcmp(what, "result")) return STORE_ERROR;
    return be->stream_open(id, is_pack, small, out, text, text_len, status);
}

store_rc store_stream_settle(store_rc rc, store_stream **out, size_t small, char **text,
                             size_t *text_len)
{
    if (rc != STORE_OK || be->stream_size(*out) > small) return rc;
    rc = store_stream_read_whole(*out, text, text_len);
    *out = NULL;
    return rc;
}

/* ------------------------------------------------------------------ a connection a thread */

int store_tls_init(store_tls *t)
{
    if (t->made) return 0;
    if (pthread_key_create(&t->key, t->destroy)) return -1;
    t->made = 1;
    return 0;
}

void *store_tls_peek(const store_tls *t) { return t->made ? pthread_getspecific(t->key) : NULL; }

void *store_tls_get(store_tls *t)
{
    void *rec = store_tls_peek(t);
    if (rec || !t->made) return rec;
    void *h = t->open();
    if (!h) return NULL;
    rec = calloc(1, t->size);
    if (!rec) {
        t->close(h);
        return NULL;
    }
    memcpy(rec, &h, sizeof h); /* the record's first member, the handle */
    pthread_setspecific(t->key, rec);
    return rec;
}

void store_tls_drop(store_tls *t)
{
    void *rec = store_tls_peek(t);
    if (!rec) return;
    t->destroy(rec);
    pthread_setspecific(t->key, NULL);
}

uint64_t store_stream_size(const store_stream *s) { return be->stream_size(s); }

int store_stream_read(store_stream *s, uint64_t off, void *dst, size_t n)
{
    return be->stream_read(s, off, dst, n);
}

void store_stream_close(store_stream *s)
{
    if (s) be->stream_close(s);
}

/* ------------------------------------------------------------------ shared */

/* ---- values in parts ---- */

uint64_t store_part_size(long long limit)
{
    return limit > 2048 && (uint64_t)limit - 1024 < STORE_PART ? (uint64_t)limit - 1024
                                                                : STORE_PART;
}

int store_parts_add(store_parts *p, uint64_t len)
{
    uint64_t *e = realloc(p->end, (p->n + 1) * sizeof *e);
    if (!e) return -1;
    e[p->n] = (p->n ? e[p->n - 1] : 0) + len;
    p->end = e;
    p->n++;
    return 0;
}

size_t store_parts_find(const store_parts *p, uint64_t off, uint64_t *start)
{
    size_t lo = 0, hi = p->n - 1; /* the first part whose end is past off */
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (p->end[mid] > off) hi = mid;
        else lo = mid + 1;
    }
    *start = lo ? p->end[lo - 1] : 0;
    return lo;
}

void store_parts_free(store_parts *p)
{
    free(p->end);
    p->end = NULL;
    p->n = 0;
}

store_rc store_stream_read_whole(store_stream *s, char **text, size_t *text_len)
{
    size_t size = (size_t)store_stream_size(s);
    char *buf = malloc(size + 1);
    store_rc rc = buf && !store_stream_read(s, 0, buf, size) ? STORE_OK : STORE_ERROR;
    store_stream_close(s);
    if (rc != STORE_OK) {
        free(buf);
        return rc;
    }
    buf[size] = 0;
    *text = buf;
    *text_len = size;
    return STORE_OK;
}

/* ---- the last failed write, for /v1/health ---- */
static pthread_mutex_t werr_mu = PTHREAD_MUTEX_INITIALIZER;
static struct {
    long count;
    double when; /* gpd_monotonic_s */
    char at[40];
    char msg[256];
} werr;

void store_note_write_error(const char *what, const char *msg)
{
    pthread_mutex_lock(&werr_mu);
    werr.count++;
    werr.when = gpd_monotonic_s();
    gpd_now_rfc3339(werr.at, sizeof werr.at);
    /* "what: msg", cut to the buffer as snprintf would (msg may be a long gpd_err message) */
    snprintf(werr.msg, sizeof werr.msg, "%s: ", what);
    size_t n = strlen(werr.msg), m = strlen(msg);
    if (m > sizeof werr.msg - 1 - n) m = sizeof werr.msg - 1 - n;
    memcpy(werr.msg + n, msg, m);
    werr.msg[n + m] = '\0';
    pthread_mutex_unlock(&werr_mu);
}

int store_last_write_error(double window_s, char *msg, size_t msg_len, char at[40],
                           long *count)
{
    pthread_mutex_lock(&werr_mu);
    int recent = werr.count > 0 && gpd_monotonic_s() - werr.when <= window_s;
    if (recent) {
        snprintf(msg, msg_len, "%s", werr.msg);
        snprintf(at, 40, "%s", werr.at);
        *count = werr.count;
    }
    pthread_mutex_unlock(&werr_mu);
    return recent;
}

int store_is_finished(const char *status)
{
    return !strcmp(status, "succeeded") || !strcmp(status, "failed") ||
           !strcmp(status, "cancelled");
}

const char *store_interrupted_error(void)
{
    /* STORE_MAX_ATTEMPTS spelled out: the message is part of the API (README) */
    return "{\"code\":\"interrupted\",\"message\":\"interrupted 3 times (the daemon stopped "
           "while the job was running); not retried\"}";
}

json_t *store_progress_or_queued(json_t *p)
{
    if (!json_is_null(p)) return p;
    json_decref(p);
    return json_pack("{s:s, s:f, s:n, s:{}}", "phase", "queued", "fraction", 0.0, "eta_s",
                     "detail");
}

char *store_spans_text(uint64_t spans[STORE_SUMMARY_NSKIP][2])
{
    static const char *const skip[] = STORE_SUMMARY_SKIP;
    char *t = malloc(64 + STORE_SUMMARY_NSKIP * 64);
    if (!t) return NULL;
    size_t n = 0;
    t[n++] = '{';
    for (int k = 0; k < STORE_SUMMARY_NSKIP; k++)
        if (spans[k][1] > spans[k][0])
            n += (size_t)sprintf(t + n, "%s\"%s\":[%llu,%llu]", n > 1 ? "," : "", skip[k],
                                 (unsigned long long)spans[k][0], (unsigned long long)spans[k][1]);
    t[n++] = '}';
    t[n] = 0;
    return t;
}

int store_spans_parse(const char *text, uint64_t spans[STORE_SUMMARY_NSKIP][2])
{
    static const char *const skip[] = STORE_SUMMARY_SKIP;
    json_t *j = text ? json_loads(text, 0, NULL) : NULL;
    if (!json_is_object(j)) {
        json_decref(j);
        return -1;
    }
    for (int k = 0; k < STORE_SUMMARY_NSKIP; k++) {
        const json_t *a = json_object_get(j, skip[k]);
        json_int_t o = json_integer_value(json_array_get(a, 0)),
                   e = json_integer_value(json_array_get(a, 1));
        spans[k][0] = o >= 0 && e > o ? (uint64_t)o : 0;
        spans[k][1] = o >= 0 && e > o ? (uint64_t)e : 0;
    }
    json_decref(j);
    return 0;
}

/* store_text_source's reader: a file, from offset 0 */
static int file_read(void *user, uint64_t off, void *dst, size_t n)
{
    const store_text *t = user;
    char *p = dst;
    while (n > 0) {
        ssize_t k = pread(t->fd, p, n, (off_t)off);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return -1;
        p += k;
        off += (uint64_t)k;
        n -= (size_t)k;
    }
    return 0;
}

js_source store_text_source(const store_text *t)
{
    if (t->mem) return json_scan_memory_source(t->mem, (size_t)t->len);
    return (js_source){file_read, (void *)t, t->len};
}

store_rc store_succeed(const char *id, const store_text *result, const char *progress_json,
                       const char *brief_json, const void *pack, size_t pack_len, gpd_err *why)
{
    gpd_err dummy;
    if (!why) why = &dummy;
    gpd_err_set(why, 0, "%s", "");
    if (!result || (!result->mem && result->fd < 0)) {
        gpd_err_set(why, 500, "there is no result to store");
        return STORE_ERROR;
    }
    /* the summary (the result without its per-item arrays), made before the write lock is
     * taken, from the same source the store then copies; a result it cannot be made of (not an
     * object, out of memory, a failed read) is stored without one, and its readers fall back
     * to scanning the result */
    static const char *const skip[] = STORE_SUMMARY_SKIP;
    js_source rsrc = store_text_source(result);
    size_t slen = 0;
    uint64_t spans[STORE_SUMMARY_NSKIP][2];
    char *summary = json_scan_object_without(&rsrc, skip, &slen, spans);
    char *arrays = summary ? store_spans_text(spans) : NULL;
    if (!summary || !arrays) {
        gpd_log(GPD_LOG_WARN, "job %s: no result summary (the views will scan the result)", id);
        free(summary);
        summary = NULL;
    }
    store_rc rc = be->succeed(id, result, progress_json, brief_json, pack, pack_len, summary,
                              slen, arrays, why);
    free(summary);
    free(arrays);
    return rc;
}

/* ---- values as byte sources, summaries ---- */

static int stream_read(void *user, uint64_t off, void *dst, size_t n)
{
    return store_stream_read(user, off, dst, n);
}

js_source store_value_source(const char *text, size_t len, store_stream *s)
{
    if (text) return json_scan_memory_source(text, len);
    return (js_source){stream_read, s, store_stream_size(s)};
}

/* The summary of a job stored before summaries: made by scanning its result (streamed when
 * large). */
static store_rc summary_by_scan(const char *id, char **text, size_t *len,
                                uint64_t spans[STORE_SUMMARY_NSKIP][2])
{
    store_stream *ss = NULL;
    char *small = NULL;
    size_t small_len = 0;
    char st[16];
    store_rc rc = store_stream_open(id, "result", 256u * 1024u, &ss, &small, &small_len, st);
    if (rc != STORE_OK) return rc;
    if (!ss && !small) return STORE_OK; /* no result */
    js_source src = store_value_source(small, small_len, ss);
    static const char *const skip[] = STORE_SUMMARY_SKIP;
    uint64_t sp[STORE_SUMMARY_NSKIP][2];
    *text = json_scan_object_without(&src, skip, len, sp);
    if (*text && spans) memcpy(spans, sp, sizeof sp);
    free(small);
    store_stream_close(ss);
    if (*text) return STORE_OK;
    gpd_log(GPD_LOG_ERROR, "job %s: cannot make the summary of its stored result", id);
    return STORE_ERROR;
}

store_rc store_get_summary(const char *id, char **text, size_t *len,
                           uint64_t spans[STORE_SUMMARY_NSKIP][2], char status[16])
{
    *text = NULL;
    if (len) *len = 0;
    status[0] = 0;
    store_rc rc = be->stored_summary(id, text, len, spans, status);
    if (rc != STORE_OK || *text || strcmp(status, "succeeded")) return rc;
    return summary_by_scan(id, text, len, spans);
}
