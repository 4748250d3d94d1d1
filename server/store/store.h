/* store.h -- the job store of grainpackd: one interface, two back ends (store_impl.h), chosen
 * by store_open from the --db value: a file path is SQLite (the embedded default, one daemon
 * per file), a postgresql:// or postgres:// URL is PostgreSQL (many daemons, on any hosts,
 * share one queue; store_pg.c). The jobs, their statuses and the rules below are the same on
 * both; where PostgreSQL differs it is said under "PostgreSQL" at the end of this comment.
 *
 * SQLite: one table, jobs (WAL journal, busy_timeout 5 s, synchronous=FULL; a new database is
 * made with auto_vacuum=INCREMENTAL so that purged jobs give their space back
 * (store_vacuum_step), and every connection sets journal_size_limit=64 MB so that the WAL
 * shrinks after a checkpoint, and secure_delete=FAST: SQLite as Debian builds it overwrites
 * every freed page with zeros, which makes freeing a result of hundreds of MB write as much
 * again to the WAL while holding the write lock; FAST still clears deleted cells in the pages
 * a change writes anyway. No connection checkpoints by itself -- see "Checkpoints" below):
 *   seq         INTEGER PRIMARY KEY AUTOINCREMENT  submission order (newest = largest)
 *   id          TEXT NOT NULL UNIQUE               32 hex digits, 128 random bits (/dev/urandom)
 *   kind        TEXT NOT NULL
 *   spec        TEXT NOT NULL                      the effective spec (defaults filled), JSON
 *   status      TEXT NOT NULL                      queued|running|succeeded|failed|cancelled
 *   progress    TEXT                               JSON {phase, fraction, eta_s, detail}
 *   created_at, started_at, finished_at TEXT       RFC 3339 UTC with milliseconds
 *   error       TEXT                               JSON {code, message} or NULL
 *   result      TEXT                               the result of a job that succeeded before
 *                                                  the results table (NULL for newer jobs)
 *   attempts    INTEGER NOT NULL DEFAULT 0         times a worker claimed the job
 *   brief       TEXT                               JSON, the job object's "brief" (kind.h):
 *                                                  written at submit, replaced at success;
 *                                                  added by store_open to a database made
 *                                                  before it, filled by store_fill_briefs
 * and results(seq INTEGER PRIMARY KEY = jobs.seq, result BLOB NOT NULL): the result's JSON
 * text (a BLOB: it is written in pieces, below), committed in the same transaction as
 * status='succeeded' (durable before it shows); readers take results.result, else the older
 * jobs.result;
 * and exports(seq INTEGER PRIMARY KEY = jobs.seq, pack BLOB NOT NULL): the export pack of a
 * succeeded job (core/export/gp_export.h), committed with the result;
 * and summaries(seq INTEGER PRIMARY KEY = jobs.seq, summary TEXT NOT NULL, arrays TEXT): the
 * result's summary and where its arrays are in its text (store_get_summary), committed with
 * the result;
 * and purged(seq INTEGER PRIMARY KEY): jobs purged whose values (results, exports,
 * value_parts rows) are still to be freed (store_purge, store_free_purged).
 *
 * Connections: one per thread (opened lazily, closed when the thread exits or on
 * store_close()); every write is a single statement or an IMMEDIATE transaction, so claims and
 * cancels are atomic across threads and processes.
 *
 * Writing a large value without a second copy (SQLite): the result and the pack are inserted as
 * zeroblob(n) -- the last column of their row, so that SQLite keeps the zeros implicit and
 * never builds the record in memory -- and then written with sqlite3_blob_write in
 * STORE_PIECE pieces read from their source (memory, or a worker's temporary file:
 * store_text), inside the one transaction of store_succeed; the pager spills the dirty pages to
 * the WAL as the cache fills, so the store's memory is a piece plus SQLite's page cache.
 *
 * Values in parts (both): a result or a pack larger than one part (256 MiB, STORE_PART; less
 * under a lower limit on one value) is stored as parts of that size, the last shorter: part 0
 * where a value of one part is (results.result or exports.pack; on PostgreSQL jobs.result or
 * exports.pack), the others in value_parts(seq, what, part, data) -- what 0 for the result, 1
 * for the pack -- written in the same transaction. So neither database's limit on one value
 * (SQLite 1e9 bytes, PostgreSQL 1 GB) bounds a result: a 10^6-grain specimen's ~7 GB result is
 * 27 parts. A stream reads the parts as one value, in one snapshot; a purge removes them.
 *
 * Checkpoints (SQLite): a commit of a large result leaves hundreds of MB in the WAL; SQLite's
 * automatic checkpoint would copy them into the database on the connection that commits next
 * (a worker, or an HTTP thread), holding it for seconds. So no connection checkpoints by
 * itself (wal_autocheckpoint off); a commit that leaves the WAL over STORE_WAL_KICK_BYTES
 * calls the store_on_wal_grown hook instead, and the maintenance thread (maint.h) checkpoints:
 * a PASSIVE pass that copies the frames without blocking writers or readers, then a TRUNCATE
 * that does not wait (store_checkpoint); it waits for idle workers and gives way to a claim.
 *
 * Restart rule (store_recover): a job found 'running' when the daemon starts was interrupted
 * by a crash. It is put back in the queue unless it has already been claimed
 * STORE_MAX_ATTEMPTS (3) times, in which case it fails with error
 * {"code": "interrupted", "message": "interrupted 3 times ..."}. A graceful shutdown
 * (SIGTERM/SIGINT) requeues running jobs without counting the attempt.
 *
 * PostgreSQL (store_pg.c): the same tables (result and pack as bytea stored uncompressed, so a
 * range is read without reading the value whole), plus jobs.owner (the daemon running the job:
 * host/boot id/pid/random) and jobs.lease_until. A claim is one short transaction, SELECT ...
 * FOR UPDATE SKIP LOCKED over queued jobs and running jobs whose lease lapsed (their daemon
 * died or lost the server), oldest first; it counts an attempt, and a lapsed job already
 * claimed STORE_MAX_ATTEMPTS times fails with "interrupted" instead -- the restart rule across
 * hosts. A thread of the store renews this daemon's leases every lease/3 s and LISTENs on
 * channel gp_cancel: a DELETE on any daemon NOTIFYs the job's id, and the daemon running it
 * raises its cancel flag (store_on_cancel). Progress, success and failure are written only
 * while the job is running under this daemon's owner id: a daemon that lost the job (taken
 * over, cancelled) gets STORE_CONFLICT and writes nothing, so a result is written once.
 * store_recover applies the restart rule only to jobs of this host's daemons that are dead
 * (same host and boot, pid gone); other daemons' jobs are left to their leases. A graceful
 * shutdown requeues only this daemon's jobs. No file lock: many daemons is the point.
 * Connections: one per thread, like SQLite's, every statement prepared and parameterised;
 * plus one per download in progress (its snapshot), within store_set_max_connections: a
 * PostgreSQL server serves a fixed number of clients for every daemon on it, and slow
 * downloads on one daemon must not take them all (STORE_BUSY beyond it).
 * A server that stops answering (stalled, a lost network) must not stall the daemon: every
 * call waits for the server at most a bounded time without hearing from it, and while the
 * server is known not to answer calls fail at once with nothing sent (STORE_UNREACHABLE for
 * store_counts_within); a thread of the store probes it and everything works again, with new
 * connections where the old ones broke, once it answers. Server side, every connection sets
 * statement_timeout and idle_in_transaction_session_timeout, so that neither a runaway
 * statement nor a stalled client holds rows or a snapshot for long; TCP keepalives find a
 * server gone from the network.
 * On PostgreSQL store_vacuum_step and store_checkpoint do nothing (autovacuum makes purged
 * space reusable) and store_size is pg_database_size; store_fill_briefs has nothing to fill
 * (every job of a PostgreSQL store had its brief at submit).
 *
 * Thread safety (both): every function may be called from any thread, each using its own
 * connection; store_open, store_set_lease and store_close from the main thread only, before
 * and after the others.
 */
#ifndef GPD_STORE_H
#define GPD_STORE_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "util/json_scan.h"
#include "util/util.h"

/* ---- the store ---- */
#define STORE_MAX_ATTEMPTS 3

/* STORE_TOOBIG: a row larger than the database can hold (SQLITE_TOOBIG); retrying is futile.
 * STORE_FULL: the queue already holds the most jobs it may (store_insert's max_queued).
 * STORE_BUSY: a download would take a database connection over store_set_max_connections
 * (store_stream_open; try again later).
 * STORE_UNREACHABLE: the database server does not answer (store_counts_within). */
typedef enum {
    STORE_OK = 0,
    STORE_NOT_FOUND = 1,
    STORE_CONFLICT = 2,
    STORE_TOOBIG = 3,
    STORE_FULL = 4,
    STORE_BUSY = 5,
    STORE_UNREACHABLE = 6,
    STORE_ERROR = -1
} store_rc;

/* Opens (creates) the database at path, sets WAL and creates the table. 0 on success,
 * STORE_OPEN_LOCKED when another process (another grainpackd) holds the database, -1 on any
 * other error (logged).
 * First of all it takes an exclusive advisory lock on the database file, held until
 * store_close() or the end of the process (a kill -9 releases it too): an open-file-description
 * fcntl lock on one byte past SQLite's own lock bytes, so it follows the file whatever path
 * names it and leaves SQLite's locking alone. So two daemons never share one file. */
#define STORE_OPEN_LOCKED 1
int store_open(const char *path);
/* 1 when target is a PostgreSQL URL (postgresql:// or postgres://), 0 for a file path. */
int store_is_url(const char *target);
/* "sqlite" or "postgresql": the back end store_open chose. */
const char *store_backend_name(void);

/* The lease of a running job on PostgreSQL (--lease, seconds; default 30): set before
 * store_open. A job whose daemon has not renewed it for this long is taken over by another. */
#define STORE_LEASE_DEFAULT_S 30.0
void store_set_lease(double seconds);
double store_lease(void);
/* PostgreSQL: the most connections this daemon holds at once (--db-connections; default
 * STORE_MAX_CONNECTIONS_DEFAULT), set before store_open. The threads' own connections (one
 * per thread that uses the store) are always made; a download (store_stream_open of a large
 * value) gets one only while fewer are open, else STORE_BUSY. SQLite: no limit. */
#define STORE_MAX_CONNECTIONS_DEFAULT 32
void store_set_max_connections(int n);
/* 0 when the database is known not to answer (PostgreSQL stalled or gone: store_rc's
 * failures then mean "try again later", not a fault), or this thread's last call got no
 * answer; 1 otherwise (SQLite: always). */
int store_reachable(void);

/* The seconds a client should wait before trying a download again after STORE_BUSY. */
#define STORE_BUSY_RETRY_S 5
/* fn(id) is called (from the store's own thread) when another daemon cancelled job id, which
 * may be running here (PostgreSQL; never with SQLite, where every cancel is local). */
void store_on_cancel(void (*fn)(const char *id));
/* Closes the calling thread's connection, forbids new ones and releases the database lock. */
void store_close(void);
/* Closes the calling thread's connection (the next call opens a new one). */
void store_thread_done(void);

/* Crash recovery at startup (rule above). Returns the number of jobs requeued and failed. */
int store_recover(int *requeued, int *failed);

/* Inserts a queued job (brief_json: its brief, may be NULL); fills id. With max_queued > 0 the
 * job is inserted only while fewer than max_queued jobs are queued, checked in the same
 * statement (atomic with respect to every other writer): STORE_FULL when the queue is full. */
store_rc store_insert(const char *kind, const char *spec_json, const char *brief_json,
                      long max_queued, char id_out[33]);

/* Makes the brief of a job as text (malloc'ed; NULL when it cannot) from its kind, its effective
 * spec and, when it has succeeded, its result summary (NULL otherwise): gpd_brief_text. */
typedef char *(*store_brief_fn)(const char *kind, const char *spec, const char *summary);
/* Fills in the brief of every job that has none (stored by a daemon from before briefs): from
 * its spec, and its summary once succeeded (store_get_summary: a scan of the result where the
 * summary was not stored either). A job whose brief cannot be made gets JSON null, so that it is
 * not tried again. Run once at start-up, before the workers. Returns how many were filled, -1
 * on an error (logged). */
int store_fill_briefs(store_brief_fn make);

/* The job object of api.md (a new reference), or NULL with *rc set. */
json_t *store_get_job(const char *id, store_rc *rc);

/* The raw text of one column ("spec" or "kind") and the job's status; *text is malloc'ed
 * (NULL when the column is NULL). STORE_NOT_FOUND for an unknown id. (A result is read with
 * store_stream_open: it may be in parts.) */
store_rc store_get_text(const char *id, const char *column, char **text, char status[16]);

/* Lists jobs newest first: status may be NULL (all), after is a job id (exclusive cursor) or
 * NULL. Returns {"jobs": [...], "next": id|null}; *rc = STORE_NOT_FOUND when after is unknown. */
json_t *store_list(const char *status, int limit, const char *after, store_rc *rc);

/* Counts per status (any pointer may be NULL). */
store_rc store_counts(long *queued, long *running, long *succeeded, long *failed,
                      long *cancelled);

/* store_counts for a liveness probe (/v1/health): waits for the database at most wait_s
 * seconds, and answers STORE_UNREACHABLE then, or at once while the server is known not to
 * answer (PostgreSQL); SQLite: store_counts. n in store_counts' order (queued, running,
 * succeeded, failed, cancelled). */
store_rc store_counts_within(double wait_s, long n[5]);

/* The last failed write (any SQLite error on a statement that writes, a failed commit of a
 * result): 1 and its message, time (RFC 3339) and how many writes have failed since the start,
 * or 0 when none has failed within the last window_s seconds. A write that succeeds does not
 * clear it: on a nearly full disk small updates pass while results fail. */
int store_last_write_error(double window_s, char *msg, size_t msg_len, char at[40],
                           long *count);

/* Atomically claims the oldest queued job: status running, started_at now, attempts+1.
 * Returns STORE_OK and malloc'ed id/kind/spec, STORE_NOT_FOUND when the queue is empty. */
store_rc store_claim(char id[33], char **kind, char **spec_json, int *attempts);

/* Progress of a running job (JSON text). STORE_CONFLICT when the job is no longer running
 * (cancelled meanwhile). */
store_rc store_progress(const char *id, const char *progress_json);

/* A value to store, where its writer left it: len bytes in memory at mem, or (mem NULL) in
 * the file fd from offset 0, read with pread (a worker's temporary file, result_json.h). The
 * store reads it, never changes or closes it. */
#define STORE_PIECE ((size_t)1 << 20) /* bytes read and written at a time */
typedef struct store_text {
    const char *mem;
    int fd;
    uint64_t len;
} store_text;
/* The value as a byte source (json_scan.h). */
js_source store_text_source(const store_text *t);

/* Where a worker may put the temporary file of a large result (malloc'ed): the database's
 * directory (SQLite; its disk, not a RAM /tmp), TMPDIR or else /var/tmp (PostgreSQL); NULL
 * when the store is closed. */
char *store_spill_dir(void);

/* Final transitions of a running job (no-ops returning STORE_CONFLICT when it is no longer
 * running, e.g. cancelled by DELETE).
 * store_succeed commits the result (non-NULL; its JSON text), the pack (may be NULL), the
 * result's summary (store_get_summary; made here from the result, read through its source,
 * left out when it cannot be made) and status 'succeeded' in one transaction, or nothing: every
 * SQLite code is checked and a failure rolls it all back, leaving the job running. Both write
 * the result and the pack in parts (above); SQLite fills each in pieces, PostgreSQL binds each
 * from memory or reads it from the file into a buffer of one part. STORE_TOOBIG: a row the
 * database cannot store whatever the retries (SQLITE_TOOBIG: a summary over a lowered limit);
 * STORE_ERROR: anything else (disk full, I/O error, a failed commit...), which may pass on a
 * retry. On both, why (may be NULL) gets a sentence saying what went wrong (status 500). */
store_rc store_succeed(const char *id, const store_text *result, const char *progress_json,
                       const char *brief_json, const void *pack, size_t pack_len, gpd_err *why);
/* brief_json: the brief with what the run achieved (NULL: the one of the submit is kept).
 * store_fail, store_cancel and the restart rule's failures keep the last progress's phase and
 * fraction and set its eta_s to null: a job that has ended says no time is left to wait. */
store_rc store_fail(const char *id, const char *code, const char *message);
/* Back to queued (graceful shutdown): the attempt is not counted. */
store_rc store_requeue(const char *id);

/* DELETE: a queued or running job becomes cancelled (finished_at now). STORE_CONFLICT (with
 * its status in status_out) when it has already finished, STORE_NOT_FOUND when unknown.
 * was_running tells whether a worker must be told; kind_out (may be NULL) gets the job's kind. */
store_rc store_cancel(const char *id, int *was_running, char status_out[16], char kind_out[64]);

/* ---- operations: purging finished jobs, giving the space back, sizes ---- */

/* DELETE ?purge=1: removes a finished job (succeeded, failed or cancelled) from view -- it is
 * unknown to every call at once -- in one short transaction that writes a few rows whatever
 * the job's size: the job's seq goes into the table purged(seq), and its result, export pack
 * and their parts stay where they are until store_free_purged frees them, a bounded piece per
 * write transaction (on the maintenance thread, maint.h). Freeing a value of hundreds of MB in
 * the request's transaction would hold SQLite's write lock for seconds (every freed page
 * written again), so that other writers time out. STORE_CONFLICT (with the status in
 * status_out) when the job is queued or running, STORE_NOT_FOUND when unknown (or purged).
 * A download of its result or pack in progress keeps reading the value as it was: a stream
 * (store_stream_open) holds a read transaction, whose snapshot a later write never changes.
 * SQLite: the job's row and summary are deleted; PostgreSQL: its row is marked
 * status='purged' (deleting it would delete its result's first part with it, up to 256 MiB of
 * TOAST rows) and every read leaves such rows out. */
store_rc store_purge(const char *id, char status_out[16]);

/* The retention sweep: purges (store_purge, each job its own short transaction) at most max
 * finished jobs whose finished_at is before `before` (RFC 3339, as the store writes it),
 * oldest first. Returns how many were purged, -1 when the candidates could not be read. */
int store_purge_finished_before(const char *before, int max);

/* Frees one piece of what purged jobs left (a part of a result or pack: at most STORE_PART
 * bytes; then the job's last rows), in its own short write transaction that waits for the
 * write lock only briefly (a writer that holds it wins: the caller tries again later). 1 when
 * more is left, 0 when nothing is, -1 on an error or a busy database (logged at debug). The
 * caller paces the calls (maint.h), so that other writers get the lock between them. Any
 * daemon may free any purged job (PostgreSQL: rows of purged are claimed with SKIP LOCKED). */
int store_free_purged(void);

/* One step of giving free space back to the file system (SQLite: an incremental vacuum of
 * STORE_VACUUM_STEP bytes of free pages, its own short write transaction; every page it moves
 * is written to the WAL). 1 when free pages are left, 0 when none (or the database was made
 * without auto_vacuum; PostgreSQL: always, its autovacuum makes the space reusable), -1 on an
 * error or a busy database. Paced by the caller as store_free_purged. */
#define STORE_VACUUM_STEP (2 << 20)
int store_vacuum_step(void);

/* Everything at once, for a caller that may hold the store (tests, tools): store_free_purged
 * and store_vacuum_step until nothing is left, then a checkpoint in TRUNCATE mode (as
 * store_checkpoint(0)). 0 when done, 1 when the checkpoint was blocked, -1 on an error. A
 * database made without auto_vacuum (before it was set at creation) only checkpoints: its file
 * keeps its size, its free pages are reused. */
int store_reclaim(void);

/* Empties the WAL: a PASSIVE checkpoint (copies the WAL into the database without blocking
 * anyone: the long part after a large result) and a checkpoint in TRUNCATE mode that does not
 * wait: a writer at that moment or a reader of an older snapshot (a download in progress)
 * blocks it, and the caller tries again later. 0 done, 1 blocked (try again later),
 * 2 given way to a job (may_yield: a claim on any thread interrupted it, store_checkpoint_yield;
 * its copying starts over next time), -1 an error (logged). PostgreSQL: 0. */
int store_checkpoint(int may_yield);
/* Interrupts a checkpoint running with may_yield, if any (any thread; store_claim calls it). */
void store_checkpoint_yield(void);

/* fn() is called (on the committing thread, which must not wait for it) after a commit that
 * left the WAL over STORE_WAL_KICK_BYTES (SQLite; never on PostgreSQL): a checkpoint is due
 * (store_checkpoint). NULL: none. */
#define STORE_WAL_KICK_BYTES (4 << 20) /* SQLite's own autocheckpoint threshold, 1000 pages of
                                          its default 4 KB */
void store_on_wal_grown(void (*fn)(void));

/* The jobs in the store by kind and status (one GROUP BY over an index): fn is called once
 * per pair present. 0, or -1. */
int store_count_by_kind(void (*fn)(void *user, const char *kind, const char *status, long n),
                        void *user);

/* The database's size on disk: page_count * page_size plus the WAL file. 0, or -1. */
int store_size(long long *bytes);

/* ---- reading large values (results, export packs) without holding them in memory ---- */
typedef struct store_stream store_stream;

/* Opens what ("result" or "pack") of job id. STORE_NOT_FOUND for an unknown job; otherwise
 * STORE_OK with the job's status and one of: *text (malloc'ed, NUL-terminated, *text_len
 * bytes) when the value has at most `small` bytes; *out, a stream on a private connection, when
 * it is larger; neither when the job has no such value (not finished, or no pack). The stream
 * may be read from any one thread at a time and must be closed. STORE_BUSY when a stream
 * would take a connection over store_set_max_connections (PostgreSQL). A PostgreSQL stream's
 * transaction ends, and its next read fails, when it stays idle for STORE_STREAM_IDLE_S (a
 * reader that stopped reading must not hold a snapshot, which keeps vacuum from every row
 * deleted since, for long). */
#define STORE_STREAM_IDLE_S 60
store_rc store_stream_open(const char *id, const char *what, size_t small, store_stream **out,
                           char **text, size_t *text_len, char status[16]);
uint64_t store_stream_size(const store_stream *s);
/* What store_stream_open gave (text of len bytes in memory, else the stream s) as a byte source
 * for the readers of json_scan.h and core/export/gp_export.h (both take this shape). */
js_source store_value_source(const char *text, size_t len, store_stream *s);
/* Reads n bytes at off; 0 on success. */
int store_stream_read(store_stream *s, uint64_t off, void *dst, size_t n);
void store_stream_close(store_stream *s);

/* ---- the summary of a result: what pictures and a result panel read ---- */

/* The members a summary leaves out: a result's per-item arrays, its bulk (and a 3D
 * Fourier-Voronoi result's shared icosphere, a few hundred KB its views make again). */
#define STORE_SUMMARY_SKIP {"grains", "cells", "spheres", "contacts", "clumps", "icosphere", NULL}
#define STORE_SUMMARY_NSKIP 6

/* The summary of job id's result: the result object without STORE_SUMMARY_SKIP's members --
 * kind, seed, outputs, container or box, stats, warnings, timings..., a few KB -- as JSON text
 * (*text malloc'ed, *len bytes; len may be NULL), with the job's status; and, when spans is
 * not NULL, where the left-out arrays are in the stored result text: spans[k] = [off, end) of
 * the value of STORE_SUMMARY_SKIP[k] ({0, 0} when the result has none), for reading one of
 * them element by element (store_stream_open(id, "result", ...)) without a scan.
 * store_succeed stores both with the result (table summaries: summary, arrays); for a result
 * stored before summaries existed they are made by scanning the stored result (streamed: time
 * in the result's size, memory in the summary's). *text NULL when the job has no result (not
 * succeeded). STORE_NOT_FOUND for an unknown id. */
store_rc store_get_summary(const char *id, char **text, size_t *len,
                           uint64_t spans[STORE_SUMMARY_NSKIP][2], char status[16]);

#endif /* GPD_STORE_H */
