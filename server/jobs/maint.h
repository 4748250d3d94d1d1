/* maint.h -- the maintenance thread of grainpackd: the retention sweep and giving the space of
 * purged jobs back to the file system.
 *
 * Retention (--retain-days N, N > 0): finished jobs (succeeded, failed, cancelled) whose
 * finished_at is more than N days old are purged (store_purge: the row, the result, the export
 * pack and the summary). A pass runs at start-up and then every minute; it purges at most
 * MAINT_SWEEP_MAX jobs, each in its own short transaction, so that it never holds the store
 * long; a pass that found that many runs again a second later, until the backlog is gone.
 * Queued and running jobs are never candidates.
 *
 * Reclaim: after a pass that purged anything, or a DELETE ?purge=1 (maint_kick), the thread
 * runs store_reclaim: an incremental vacuum in short steps, a PASSIVE checkpoint and a TRUNCATE
 * checkpoint that never waits for readers; a checkpoint blocked by a download in progress is
 * tried again after 1, 2, 4 ... 30 s, until it passes.
 *
 * Checkpoints (store.h, "Checkpoints"): no connection of the store checkpoints by itself; a
 * commit that leaves the WAL large (a result of hundreds of MB) calls maint_wal_grown through
 * store_on_wal_grown, and this thread runs store_reclaim as after a purge -- so the copy of the
 * WAL into the database runs here, never on a worker or an HTTP thread (store_checkpoint). It
 * waits until no worker has been busy for a second, and a claim interrupts it (it starts over
 * once the workers are idle again), so that the copy of hundreds of MB does not slow the jobs
 * that follow (their commits would wait for their fsyncs behind it); after a minute it runs
 * whatever runs, so that a daemon that is never idle still checkpoints. A commit while a
 * blocked checkpoint waits for its retry keeps the back-off (it does not retry at once). */
#ifndef GPD_MAINT_H
#define GPD_MAINT_H

#define MAINT_SWEEP_MAX 100         /* jobs purged in one pass at most */
#define MAINT_SWEEP_INTERVAL_S 60.0 /* between two passes */

/* Starts the thread on the open store; retain_days 0 = keep every job (the thread then only
 * reclaims after purges). 0, or -1. */
int maint_start(double retain_days);
/* A job was purged: give its space back soon. */
void maint_kick(void);
/* A commit left the WAL large: checkpoint soon (the store's hook; any thread, never waits). */
void maint_wal_grown(void);
/* Stops and joins the thread (a pass in progress finishes its current job). */
void maint_stop(void);

#endif /* GPD_MAINT_H */
