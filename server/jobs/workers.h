/* workers.h -- the pool of worker threads that run queued jobs.
 *
 * Each worker claims the oldest queued job atomically (store_claim), parses its stored spec,
 * runs the core pipeline on its own thread (spec threads = 1: the pool is the parallelism)
 * and commits the result together with status 'succeeded' (store_succeed) before anyone can
 * see the job as finished. Progress is written at most every 0.25 s per job with an ETA
 * extrapolated from the elapsed time and the reported fraction. Cancel: a DELETE marks the
 * job cancelled in the store and raises the cancel flag the core polls, so a running job stops
 * within its next poll (well under a second). Shutdown raises every flag and puts the running
 * jobs back in the queue (store_requeue), so they resume on the next start.
 *
 * Time limit (--job-timeout): a watchdog thread raises the cancel flag of a job whose run has
 * lasted longer than the limit; the job then fails with error code "timeout" and a message
 * naming the limit and the phase it was stopped in. The limit applies to each run attempt:
 * a job requeued by a restart gets the whole limit again. A DELETE wins over a timeout that
 * comes after it (the job stays cancelled), a timeout over a shutdown that comes after it
 * (the job fails instead of being requeued).
 * Final writes: a result or a failure the database refuses is retried once; a result that can
 * never be stored (too big) fails the job with code "too_large", one that still cannot be
 * stored with code "store_error"; a failure that cannot be written is kept and written later,
 * and logged at level error, so that no job stays running silently.
 */
#ifndef GPD_WORKERS_H
#define GPD_WORKERS_H

#include "store/store.h"

/* The per-run time limit in seconds (0 = none; default 3600); call before workers_start. */
void workers_set_job_timeout(long seconds);
/* The threads each job's core build runs on (>= 1; default 1), set before workers_start. */
void workers_set_job_threads(int threads);
int workers_start(int n);
/* A job was queued: wake an idle worker. */
void workers_notify(void);
/* DELETE /v1/jobs/{id}: store_cancel + raise the flag of the worker running it, atomically
 * with respect to claims (no job can slip between). Same return values as store_cancel. */
store_rc workers_cancel(const char *id, char status_out[16]);
/* Graceful stop: raise every cancel flag, requeue running jobs, join the threads. */
void workers_stop(void);
int workers_total(void);
int workers_busy(void);

#endif /* GPD_WORKERS_H */
