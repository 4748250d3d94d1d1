/* metrics.c -- the counters and histograms of GET /metrics and their exposition (metrics.h). */
#include "jobs/metrics.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "http/routes.h"
#include "store/store.h"
#include "util/util.h"

/* the kinds and phases the static tables have room for (a kind past them is not counted) */
#define MAX_KINDS 8
#define MAX_PHASES 8

/* ------------------------------------------------------------------ HTTP requests */

/* by route of the table (routes.h), the last row for requests no route matched ("other") */
#define ROUTE_OTHER GPD_ROUTES_MAX
#define STATUS_LO 100 /* statuses 100..599 are counted */
#define NSTATUS 500

static uint64_t http_count[GPD_ROUTES_MAX + 1][NSTATUS]; /* atomic */

void metrics_http_request(const gpd_route *route, int status)
{
    if (status < STATUS_LO || status >= STATUS_LO + NSTATUS) return;
    size_t n = 0;
    const gpd_route *table = gpd_routes(&n);
    size_t i = route && route >= table && route < table + n ? (size_t)(route - table) : ROUTE_OTHER;
    __atomic_add_fetch(&http_count[i][status - STATUS_LO], 1, __ATOMIC_RELAXED);
}

/* ------------------------------------------------------------------ jobs */

static const char *const statuses[] = {"queued", "running", "succeeded", "failed", "cancelled"};
#define NSTATUSES 5
#define FIRST_FINAL 2 /* statuses[2..4] are the final ones */

static uint64_t finished[MAX_KINDS][NSTATUSES]; /* atomic; only the final statuses move */

static int status_index(const char *s)
{
    for (int i = 0; i < NSTATUSES; i++)
        if (!strcmp(statuses[i], s)) return i;
    return -1;
}

/* the duration histograms: upper bounds in seconds, +Inf implied */
static const double bounds[] = {0.01, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 120, 300, 600,
                                1800, 3600};
#define NBOUNDS (sizeof bounds / sizeof *bounds)

typedef struct hist {
    uint64_t bucket[NBOUNDS]; /* observations <= bounds[i], not cumulative */
    uint64_t count;
    double sum;
} hist;

static pthread_mutex_t hist_mu = PTHREAD_MUTEX_INITIALIZER;
static hist hists[MAX_KINDS][MAX_PHASES]; /* guarded by hist_mu */
static double run_mean = -1;              /* moving mean of run times, s; guarded by hist_mu */

void metrics_job_finished(const char *kind, const char *status, double run_s)
{
    int k = gpd_kind_index(gpd_kind_find(kind)), s = status ? status_index(status) : -1;
    if (k >= 0 && k < MAX_KINDS && s >= FIRST_FINAL)
        __atomic_add_fetch(&finished[k][s], 1, __ATOMIC_RELAXED);
    if (run_s >= 0 && isfinite(run_s)) {
        /* a mean over the last twenty jobs or so */
        pthread_mutex_lock(&hist_mu);
        run_mean = run_mean < 0 ? run_s : 0.95 * run_mean + 0.05 * run_s;
        pthread_mutex_unlock(&hist_mu);
    }
}

void metrics_job_timings(const gpd_kind *k, const json_t *timings)
{
    int ki = gpd_kind_index(k);
    if (ki < 0 || ki >= MAX_KINDS || !k->phases || !json_is_object(timings)) return;
    pthread_mutex_lock(&hist_mu);
    for (int p = 0; p < MAX_PHASES && k->phases[p]; p++) {
        const json_t *v = json_object_get(timings, k->phases[p]);
        double x = json_number_value(v);
        if (!json_is_number(v) || !isfinite(x)) continue;
        hist *h = &hists[ki][p];
        size_t b = 0;
        while (b < NBOUNDS && x > bounds[b]) b++;
        if (b < NBOUNDS) h->bucket[b]++;
        h->count++;
        h->sum += x;
    }
    pthread_mutex_unlock(&hist_mu);
}

int metrics_retry_after(int workers)
{
    pthread_mutex_lock(&hist_mu);
    double mean = run_mean;
    pthread_mutex_unlock(&hist_mu);
    if (mean < 0) return 5;
    double s = ceil(mean / (workers > 0 ? workers : 1));
    return s < 1 ? 1 : s > 600 ? 600 : (int)s;
}

/* ------------------------------------------------------------------ the exposition */

/* a label value as the text format wants it: backslash, quote and newline escaped */
static void label(gpd_buf *b, const char *v)
{
    for (const char *p = v; *p; p++) {
        if (*p == '\\' || *p == '"') gpd_buf_add(b, "\\", 1);
        if (*p == '\n')
            gpd_buf_add(b, "\\n", 2);
        else
            gpd_buf_add(b, p, 1);
    }
}

static void head(gpd_buf *b, const char *name, const char *type, const char *help)
{
    gpd_buf_printf(b, "# HELP %s %s\n# TYPE %s %s\n", name, help, name, type);
}

/* what the GROUP BY gives, for the kinds of the table; other kinds' lines are written at once */
typedef struct job_counts {
    long n[MAX_KINDS][NSTATUSES];
    long queued;
    gpd_buf *out; /* the lines of kinds or statuses this daemon does not know */
} job_counts;

static void on_count(void *user, const char *kind, const char *status, long n)
{
    job_counts *c = user;
    int k = gpd_kind_index(gpd_kind_find(kind)), s = status_index(status);
    if (s == 0) c->queued += n;
    if (k >= 0 && k < MAX_KINDS && s >= 0) {
        c->n[k][s] += n;
        return;
    }
    gpd_buf_add(c->out, "grainpack_jobs{kind=\"", 21);
    label(c->out, kind);
    gpd_buf_add(c->out, "\",status=\"", 10);
    label(c->out, status);
    gpd_buf_printf(c->out, "\"} %ld\n", n);
}

static void render_jobs(gpd_buf *b)
{
    gpd_buf other = {0};
    job_counts c;
    memset(&c, 0, sizeof c);
    c.out = &other;
    int ok = store_count_by_kind(on_count, &c) == 0;
    head(b, "grainpack_jobs", "gauge", "Jobs in the job store by kind and status.");
    for (int k = 0; ok && k < MAX_KINDS && gpd_kind_at((size_t)k); k++)
        for (int s = 0; s < NSTATUSES; s++)
            gpd_buf_printf(b, "grainpack_jobs{kind=\"%s\",status=\"%s\"} %ld\n",
                           gpd_kind_at((size_t)k)->name, statuses[s], c.n[k][s]);
    if (ok && other.len) gpd_buf_add(b, other.buf, other.len);
    free(other.buf);
    head(b, "grainpack_queue_depth", "gauge", "Jobs waiting in the queue.");
    if (ok) gpd_buf_printf(b, "grainpack_queue_depth %ld\n", c.queued);
}

static void render_finished(gpd_buf *b)
{
    head(b, "grainpack_jobs_finished_total", "counter",
         "Jobs that finished in this process, by kind and final status.");
    for (int k = 0; k < MAX_KINDS && gpd_kind_at((size_t)k); k++)
        for (int s = FIRST_FINAL; s < NSTATUSES; s++)
            gpd_buf_printf(b, "grainpack_jobs_finished_total{kind=\"%s\",status=\"%s\"} %llu\n",
                           gpd_kind_at((size_t)k)->name, statuses[s],
                           (unsigned long long)__atomic_load_n(&finished[k][s],
                                                               __ATOMIC_RELAXED));
}

static void render_histograms(gpd_buf *b)
{
    static hist copy[MAX_KINDS][MAX_PHASES]; /* guarded by render_mu: off the stack */
    static pthread_mutex_t render_mu = PTHREAD_MUTEX_INITIALIZER;
    pthread_mutex_lock(&render_mu);
    pthread_mutex_lock(&hist_mu);
    memcpy(copy, hists, sizeof copy);
    pthread_mutex_unlock(&hist_mu);
    head(b, "grainpack_job_duration_seconds", "histogram",
         "Run time of each phase of succeeded jobs (the timings of their results), by kind and "
         "phase.");
    for (int k = 0; k < MAX_KINDS && gpd_kind_at((size_t)k); k++) {
        const gpd_kind *kd = gpd_kind_at((size_t)k);
        for (int p = 0; kd->phases && p < MAX_PHASES && kd->phases[p]; p++) {
            const hist *h = &copy[k][p];
            uint64_t cum = 0;
            for (size_t i = 0; i < NBOUNDS; i++) {
                cum += h->bucket[i];
                gpd_buf_printf(b,
                               "grainpack_job_duration_seconds_bucket{kind=\"%s\",phase=\"%s\","
                               "le=\"%g\"} %llu\n",
                               kd->name, kd->phases[p], bounds[i], (unsigned long long)cum);
            }
            gpd_buf_printf(b,
                           "grainpack_job_duration_seconds_bucket{kind=\"%s\",phase=\"%s\","
                           "le=\"+Inf\"} %llu\n",
                           kd->name, kd->phases[p], (unsigned long long)h->count);
            gpd_buf_printf(b, "grainpack_job_duration_seconds_sum{kind=\"%s\",phase=\"%s\"} %.9g\n",
                           kd->name, kd->phases[p], h->sum);
            gpd_buf_printf(b,
                           "grainpack_job_duration_seconds_count{kind=\"%s\",phase=\"%s\"} %llu\n",
                           kd->name, kd->phases[p], (unsigned long long)h->count);
        }
    }
    pthread_mutex_unlock(&render_mu);
}

static void render_http(gpd_buf *b)
{
    head(b, "grainpack_http_requests_total", "counter",
         "HTTP responses by route pattern and status code.");
    size_t nroutes = 0;
    const gpd_route *table = gpd_routes(&nroutes);
    for (size_t r = 0; r <= nroutes; r++) {
        size_t row = r < nroutes ? r : ROUTE_OTHER;
        const char *label = r < nroutes ? table[r].label : GPD_ROUTE_OTHER_LABEL;
        for (int s = 0; s < NSTATUS; s++) {
            uint64_t n = __atomic_load_n(&http_count[row][s], __ATOMIC_RELAXED);
            if (n)
                gpd_buf_printf(b,
                               "grainpack_http_requests_total{route=\"%s\",status=\"%d\"} %llu\n",
                               label, s + STATUS_LO, (unsigned long long)n);
        }
    }
}

char *metrics_render(int workers, int busy, size_t *len)
{
    gpd_buf b = {0};
    gpd_buf_reserve(&b, 16384);
    render_jobs(&b);
    render_finished(&b);
    head(&b, "grainpack_workers", "gauge", "Worker threads that run jobs.");
    gpd_buf_printf(&b, "grainpack_workers %d\n", workers);
    head(&b, "grainpack_workers_busy", "gauge", "Worker threads running a job now.");
    gpd_buf_printf(&b, "grainpack_workers_busy %d\n", busy);
    render_histograms(&b);
    render_http(&b);
    long long bytes = 0;
    head(&b, "grainpack_database_bytes", "gauge",
         "Size of the job database on disk: SQLite's pages and write-ahead log, or "
         "PostgreSQL's pg_database_size.");
    if (store_size(&bytes) == 0) gpd_buf_printf(&b, "grainpack_database_bytes %lld\n", bytes);
    if (b.oom) {
        free(b.buf);
        return NULL;
    }
    *len = b.len;
    return b.buf;
}
