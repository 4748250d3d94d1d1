/* store_impl.h -- what the job store's back ends share (private to store*.c).
 *
 * store.c is the dispatch: every function of store.h calls the one back end chosen by
 * store_open from the --db value -- a type object (a struct of function pointers, as GSL's
 * algorithm types): store_sqlite (store_sqlite.c, a file path: the embedded default) or
 * store_pg (store_pg.c, a postgresql:// or postgres:// URL: many daemons on one queue). The
 * back end is chosen once, before any thread, and never changes, so the dispatch needs no lock.
 * What does not depend on the database -- the record of the last failed write, the summary of
 * a result and where its arrays are, reading a stored value as a byte source -- lives in
 * store.c, once.
 *
 * A back end keeps the semantics of store.h: the same statuses and transitions, the same
 * restart rule (attempts counted per claim, STORE_MAX_ATTEMPTS), results and packs committed
 * with status 'succeeded' in one transaction, streams that read a snapshot.
 */
#ifndef GPD_STORE_IMPL_H
#define GPD_STORE_IMPL_H

#include <pthread.h>

#include "store/store.h"

/* store_set_max_connections' value (PostgreSQL). */
int store_max_connections(void);

/* The statuses in the order of store_counts' arguments. */
enum { STORE_NSTATUS = 5 };

typedef struct store_backend {
    const char *name; /* "sqlite", "postgresql" */
    int (*open)(const char *target);
    void (*close)(void);
    void (*thread_done)(void);
    int (*recover)(int *requeued, int *failed);
    store_rc (*insert)(const char *kind, const char *spec_json, const char *brief_json,
                       long max_queued, char id_out[33]);
    int (*fill_briefs)(store_brief_fn make);
    json_t *(*get_job)(const char *id, store_rc *rc);
    store_rc (*get_text)(const char *id, const char *column, char **text, char status[16]);
    json_t *(*list)(const char *status, int limit, const char *after, store_rc *rc);
    /* adds each status's count at n[store_status_slot(status)] (n zeroed by store.c) */
    store_rc (*counts)(long n[STORE_NSTATUS]);
    /* store_counts_within: the same, waiting at most wait_s for the database */
    store_rc (*counts_within)(long n[STORE_NSTATUS], double wait_s);
    /* store_reachable: 0 when the database is known not to answer, or this thread's last
     * call got no answer (NULL: always reachable) */
    int (*reachable)(void);
    store_rc (*claim)(char id[33], char **kind, char **spec_json, int *attempts);
    store_rc (*progress)(const char *id, const char *progress_json);
    /* store_succeed after the shared part: summary (may be NULL) of slen bytes and its arrays'
     * spans as text (store_spans_text) were made by store.c from the result */
    store_rc (*succeed)(const char *id, const store_text *result, const char *progress_json,
                        const char *brief_json, const void *pack, size_t pack_len,
                        const char *summary, size_t slen, const char *arrays, gpd_err *why);
    /* store_spill_dir (NULL: values are bound whole) */
    char *(*spill_dir)(void);
    store_rc (*fail)(const char *id, const char *code, const char *message);
    store_rc (*requeue)(const char *id);
    store_rc (*cancel)(const char *id, int *was_running, char status_out[16], char kind_out[64]);
    store_rc (*purge)(const char *id, char status_out[16]);
    int (*purge_finished_before)(const char *before, int max);
    int (*free_purged)(void);
    int (*vacuum_step)(void);
    int (*checkpoint)(int may_yield);
    void (*checkpoint_yield)(void);
    int (*count_by_kind)(void (*fn)(void *user, const char *kind, const char *status, long n),
                         void *user);
    int (*size)(long long *bytes);
    /* store_stream_open after store.c checked `what` and cleared the outputs; a value in parts
     * within small bytes is left to store_stream_settle */
    store_rc (*stream_open)(const char *id, int is_pack, size_t small, store_stream **out,
                            char **text, size_t *text_len, char status[16]);
    uint64_t (*stream_size)(const store_stream *s);
    int (*stream_read)(store_stream *s, uint64_t off, void *dst, size_t n);
    void (*stream_close)(store_stream *s);
    /* the summary as stored with the result (*text NULL when none was: store.c then scans the
     * result), with the job's status */
    store_rc (*stored_summary)(const char *id, char **text, size_t *len,
                               uint64_t spans[STORE_SUMMARY_NSKIP][2], char status[16]);
} store_backend;

extern const store_backend store_sqlite;
extern const store_backend store_pg;

/* ---- values in parts (store.h "Values in parts") ---- */
#define STORE_PART ((uint64_t)256 << 20) /* bytes of a part, under both databases' 1 GB */
enum { STORE_VALUE_RESULT = 0, STORE_VALUE_PACK = 1 }; /* value_parts.what */
/* The part size a writer uses under its database's limit on one value (bytes; <= 0: none):
 * STORE_PART, or 1 kB less than the limit where that is lower (SQLite's limit bounds a row's
 * record, keys and header included; a testing hook lowers it to a few kB). */
uint64_t store_part_size(long long limit);
/* Where a stream's parts are: end[k] is the value's offset just past part k (n parts, end[n-1]
 * the value's size); made by a back end's stream when it opens, in its snapshot. */
typedef struct store_parts {
    size_t n;
    uint64_t *end;
} store_parts;
/* Appends a part of len bytes; 0, or -1 (out of memory). */
int store_parts_add(store_parts *p, uint64_t len);
/* The part holding byte off (< the value's size), and its first byte in *start. */
size_t store_parts_find(const store_parts *p, uint64_t off, uint64_t *start);
void store_parts_free(store_parts *p);
/* Reads stream s (of at most a few hundred KB: a value in parts that store_stream_open was
 * asked to return whole) into *text (malloc'ed, NUL-terminated), and closes it. */
store_rc store_stream_read_whole(store_stream *s, char **text, size_t *text_len);

/* A stream a back end just opened (rc): when rc is STORE_OK and the value is within small
 * bytes, it is read whole into *text and closed (*out NULL). Returns the outcome. */
store_rc store_stream_settle(store_rc rc, store_stream **out, size_t small, char **text,
                             size_t *text_len);

/* The index of a status name in store_counts' order, or -1. */
int store_status_slot(const char *status);

/* The jobs table's columns that both databases declare alike (between the key and the result). */
#define STORE_JOBS_COMMON_COLUMNS                                                              \
    " id TEXT NOT NULL UNIQUE, kind TEXT NOT NULL, spec TEXT NOT NULL, status TEXT NOT NULL,"  \
    " progress TEXT, created_at TEXT NOT NULL, started_at TEXT, finished_at TEXT, error TEXT,"

/* ---- one database connection a thread ---- */
/* A back end's connection record begins with its database handle (a pointer: PGconn *,
 * sqlite3 *); each thread opens its own on first use and closes it when it ends
 * (thread_done) or its thread exits. */
typedef struct store_tls {
    void *(*open)(void);        /* a new handle, or NULL (logged) */
    void (*close)(void *handle);
    size_t size;                /* of the record, handle first, the rest zeroed */
    void (*destroy)(void *rec); /* closes the handle and frees the record (and what it holds) */
    pthread_key_t key;
    int made;
} store_tls;
/* Once, from the back end's open, before any thread: 0, or -1. */
int store_tls_init(store_tls *t);
/* This thread's record, or NULL when it has none. */
void *store_tls_peek(const store_tls *t);
/* This thread's record, opened when it has none; NULL when the database cannot be reached. */
void *store_tls_get(store_tls *t);
/* Closes this thread's record, if any (the next store_tls_get opens a new one). */
void store_tls_drop(store_tls *t);

/* Calls the hook of store_on_cancel, if any (store_pg's listener). */
void store_cancel_seen(const char *id);
/* Calls the hook of store_on_wal_grown, if any (store_sqlite's WAL hook). */
void store_wal_grown_seen(void);
/* Records a failed write for store_last_write_error (/v1/health): what was being written and
 * the database's message. Thread-safe. */
void store_note_write_error(const char *what, const char *msg);
/* The arrays' spans as stored: {"grains":[off,end],...} for the members present (malloc'ed). */
char *store_spans_text(uint64_t spans[STORE_SUMMARY_NSKIP][2]);
/* Reads store_spans_text(); 0 on success. */
int store_spans_parse(const char *text, uint64_t spans[STORE_SUMMARY_NSKIP][2]);
/* 1 for the statuses of a job that has ended (a purge may remove it). */
int store_is_finished(const char *status);
/* The error of a job failed by the restart rule (JSON text, static). */
const char *store_interrupted_error(void);
/* The progress a job object shows before any was written (a new reference). */
json_t *store_progress_or_queued(json_t *p);

#endif /* GPD_STORE_IMPL_H */
