/* maint.h -- the maintenance thread of grainpackd: the retention sweep, freeing purged jobs
 * and giving their space back to the file system.
 *
 * Retention (--retain-days N, N > 0): finished jobs (succeeded, failed, cancelled) whose
 * finished_at is more than N days old are purged (store_purge: out of view at once, the row,
 * the result, the export pack and the summary freed below). A pass runs at start-up and then every minute; it purges at most
 * MAINT_SWEEP_MAX jobs, each in its own short transaction, so that it never holds the store
 * long; a pass that found that many runs again a second later, until the backlog is gone.
 * Queued and running jobs are never candidates.
 *
 * Freeing and reclaim: a purge (DELETE ?purge=1, maint_kick, or a sweep) only takes the job
 * out of view (store_purge); this thread then frees what it left, a piece a write transaction
 * (store_free_purged: one part of a result or pack, at most 256 MiB), and gives the free space
 * back to the file system in steps of a few MB (store_vacuum_step), pacing both: after a step
 * that took t it waits 10 ms + 4t, so that it holds the write lock a fifth of the time at most
 * and every other writer (a submit, a worker's progress or result) gets it within
 * milliseconds, and it checkpoints every few steps so that the WAL stays small. Then a
 * TRUNCATE checkpoint that never waits for readers; one blocked by a download in progress is
 * tried again after 1, 2, 4 ... 30 s, until it passes. A step that finds the database busy (a
 * worker storing a large result) is tried again after 0.5, 1, 2 ... 30 s. At start-up it frees
 * what a purge before a stop left.
 *
 * Checkpoints (store.h, "Checkpoints"): no connection of the store checkpoints by itself; a
 * commit that leaves the WAL large (a result of hundreds of MB) calls maint_wal_grown through
 * store_on_wal_grown, and this thread checkpoints (store_checkpoint) -- so the copy of the
 * WAL into the database runs here, never on a worker or an HTTP thread. It
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
/* A job was purged: free its values and give their space back, starting at once. */
void maint_kick(void);
/* A commit left the WAL large: checkpoint soon (the store's hook; any thread, never waits). */
void maint_wal_grown(void);
/* Stops and joins the thread (a step in progress finishes; what is left to free is freed at
 * the next start). */
void maint_stop(void);

#endif /* GPD_MAINT_H */
