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
 */
#ifndef GPD_WORKERS_H
#define GPD_WORKERS_H

#include "store.h"

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
