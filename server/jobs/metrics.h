/* metrics.h -- GET /metrics: the daemon's figures in the Prometheus text exposition format
 * 0.0.4 (Content-Type "text/plain; version=0.0.4; charset=utf-8").
 *
 * The names are part of the contract (api.md "Operations"; docs/api.md "GET /metrics";
 * tests/integration/test_operations.py reads them):
 *   grainpack_jobs{kind,status}                     gauge: jobs in the store (one GROUP BY over
 *                                                   an index, at each scrape); every kind of the
 *                                                   table and every status, 0 included
 *   grainpack_jobs_finished_total{kind,status}      counter: jobs that finished in this process
 *                                                   (succeeded, failed, cancelled)
 *   grainpack_queue_depth                           gauge: queued jobs
 *   grainpack_workers, grainpack_workers_busy       gauges
 *   grainpack_job_duration_seconds{kind,phase}      histogram (_bucket{le}, _sum, _count) of the
 *                                                   "timings" of each succeeded job's result, one
 *                                                   series a phase of its kind (kind.h: phases)
 *   grainpack_http_requests_total{route,status}     counter: responses by route and HTTP
 *                                                   status, counted when the request completes.
 *                                                   route is the label of the route table's row
 *                                                   (http/routes.h; "/", "/v1/jobs/:id/result",
 *                                                   ...) or "other". The job id is ":id", not
 *                                                   "{id}": a "}" inside a label value is valid
 *                                                   Prometheus text but trips simple line parsers
 *                                                   (the integration test's among them)
 *   grainpack_database_bytes                        gauge: page_count * page_size + the WAL file
 *
 * Locking: the counters are integers in static tables, updated with relaxed atomics (each is
 * read on its own; a scrape may see one request counted and the next not yet). The histograms,
 * whose buckets, sum and count must agree, and the mean run time behind Retry-After, are under
 * one mutex, held for an observation (once a job) or a copy (once a scrape). A scrape costs one
 * SQL query, one PRAGMA pair and a stat(): cheap enough every second under load.
 *
 * Dependencies: the workers report finished jobs here (metrics_job_*); the metrics read
 * nothing of the workers (their figures are passed to metrics_render by the caller, http.c),
 * so that jobs/workers -> jobs/metrics is one way.
 */
#ifndef GPD_METRICS_H
#define GPD_METRICS_H

#include <stddef.h>

#include <jansson.h>

#include "http/routes.h"
#include "kinds/kind.h"

/* A response of status to a request whose path matched route (gpd_route_match; NULL: none,
 * counted as "other"). */
void metrics_http_request(const gpd_route *route, int status);

/* A job of kind (its name) finished with status "succeeded", "failed" or "cancelled" after
 * running run_s seconds (< 0: it never ran, e.g. cancelled while queued). */
void metrics_job_finished(const char *kind, const char *status, double run_s);

/* The "timings" object of a succeeded job's result, observed into k's phase histograms (phases
 * it does not have are left out). */
void metrics_job_timings(const gpd_kind *k, const json_t *timings);

/* A Retry-After for a refused submit (queue full), in whole seconds >= 1: the time one of
 * `workers` busy workers takes to free a place, from the mean of recent run times (5 before
 * any job has finished). */
int metrics_retry_after(int workers);

/* The exposition text (malloc'ed, *len bytes), or NULL on out of memory; workers and busy
 * are the pool's figures (workers_total(), workers_busy() of jobs/workers.h). */
char *metrics_render(int workers, int busy, size_t *len);

#endif /* GPD_METRICS_H */
