/* store_sqlite.c -- the SQLite back end of the job store (store.h: the tables and the restart
 * rule; store_impl.h: the back-end type object): the embedded default, one daemon per file. */
#define _GNU_SOURCE /* F_OFD_SETLK: the database lock (store_open) */
#include "store/store_impl.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <sqlite3.h>

#include "util/json_scan.h"

/* ------------------------------------------------------------------ connections */

static int auto_vacuum = 0; /* the database gives space back (set by store_open) */

/* The one integer a query answers (its first column of its first row); -1 when it fails. */
static long query_long(sqlite3 *db, const char *sql)
{
    sqlite3_stmt *st = NULL;
    long v = -1;
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
        v = (long)sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    return v;
}

static char *db_path = NULL;
static int closed = 0; /* guarded by path_mu */
static pthread_mutex_t path_mu = PTHREAD_MUTEX_INITIALIZER;
static int lock_fd = -1; /* holds the database lock from store_open to store_close */

/* Testing hooks (environment, read once by store_open; never needed in production): lower
 * SQLite's length limit (GRAINPACK_TEST_SQLITE_MAX_LENGTH, bytes: a result over it is
 * SQLITE_TOOBIG) or the database's page count (GRAINPACK_TEST_SQLITE_MAX_PAGES: a write past it
 * is SQLITE_FULL, as on a full disk) on every connection, so that the integration tests can
 * drive the failure paths of the store. 0 = not set. The page cap is set once the schema is
 * made (SQLite keeps it at least the file's size: a cap below the schema's pages means "no
 * page more than the schema"). */
static long test_max_length = 0, test_max_pages = 0;
static int schema_made = 0; /* atomic: store_open made the tables (the page cap applies) */

static void test_page_cap(sqlite3 *db)
{
    if (test_max_pages <= 0 || !__atomic_load_n(&schema_made, __ATOMIC_ACQUIRE)) return;
    char pragma[64];
    snprintf(pragma, sizeof pragma, "PRAGMA max_page_count=%ld", test_max_pages);
    sqlite3_exec(db, pragma, NULL, NULL, NULL);
}

/* A thread's connection and its prepared statements, cached by SQL text address (every SQL
 * string here is a literal), so that a status poll costs one sqlite3_step. */
#define STMT_CACHE 40
typedef struct conn_t {
    sqlite3 *db;
    int n;
    const char *sql[STMT_CACHE];
    sqlite3_stmt *st[STMT_CACHE];
} conn_t;

static void conn_destroy(void *p)
{
    conn_t *c = p;
    if (!c) return;
    for (int i = 0; i < c->n; i++) sqlite3_finalize(c->st[i]);
    sqlite3_close_v2(c->db);
    free(c);
}

#define STORE_JOURNAL_LIMIT "67108864" /* 64 MB */
#define STORE_PAGE_SIZE "32768"        /* of a new database (store_init) */

static const char *SCHEMA_SQL =
    "CREATE TABLE IF NOT EXISTS jobs("
    " seq INTEGER PRIMARY KEY AUTOINCREMENT,"
    STORE_JOBS_COMMON_COLUMNS
    " result TEXT,"
    " attempts INTEGER NOT NULL DEFAULT 0);"
    "CREATE INDEX IF NOT EXISTS jobs_status_seq ON jobs(status, seq);"
    /* GET /metrics counts jobs by kind and status every scrape: a covering index; the
     * retention sweep finds finished jobs by age (queued and running ones have none) */
    "CREATE INDEX IF NOT EXISTS jobs_kind_status ON jobs(kind, status);"
    "CREATE INDEX IF NOT EXISTS jobs_finished_at ON jobs(finished_at)"
    " WHERE finished_at IS NOT NULL;"
    /* the result of a succeeded job, keyed by the job's seq: the row's last column, so that it
     * is written as zeroblob(n) + incremental blob I/O without a copy in memory (store.h) */
    "CREATE TABLE IF NOT EXISTS results(seq INTEGER PRIMARY KEY, result BLOB NOT NULL);"
    /* the export pack of a succeeded job (core/export/gp_export.h), keyed by the job's seq so that
     * it can be read with incremental blob I/O */
    "CREATE TABLE IF NOT EXISTS exports(seq INTEGER PRIMARY KEY, pack BLOB NOT NULL);"
    /* the parts after the first of a value over one part (store.h "Values in parts"): a rowid
     * table, so that each part is written and read with incremental blob I/O */
    "CREATE TABLE IF NOT EXISTS value_parts(seq INTEGER NOT NULL, what INTEGER NOT NULL,"
    " part INTEGER NOT NULL, data BLOB NOT NULL, PRIMARY KEY(seq, what, part));"
    /* the summary of a succeeded job's result (store_get_summary), committed with it; a
     * table of its own so that databases written before it need no migration */
    "CREATE TABLE IF NOT EXISTS summaries(seq INTEGER PRIMARY KEY, summary TEXT NOT NULL,"
    " arrays TEXT);"
    /* jobs purged whose values are still to be freed (store.h, store_purge) */
    "CREATE TABLE IF NOT EXISTS purged(seq INTEGER PRIMARY KEY);";

/* The jobs' brief (kind.h), a column added after the table: a database made before it gets it
 * here, and its jobs their briefs from store_fill_briefs. 0, or -1 (logged). */
static int add_brief_column(sqlite3 *db)
{
    if (query_long(db, "SELECT count(*) FROM pragma_table_info('jobs') WHERE name='brief'") > 0)
        return 0;
    char *em = NULL;
    if (sqlite3_exec(db, "ALTER TABLE jobs ADD COLUMN brief TEXT", NULL, NULL, &em) == SQLITE_OK)
        return 0;
    gpd_log(GPD_LOG_ERROR, "cannot add the brief column to the jobs table: %s", em ? em : "?");
    sqlite3_free(em);
    return -1;
}

/* a copy of the database's path; NULL once the store is closed (or out of memory) */
static char *path_copy(void)
{
    pthread_mutex_lock(&path_mu);
    char *path = (closed || !db_path) ? NULL : strdup(db_path);
    pthread_mutex_unlock(&path_mu);
    return path;
}

/* Replaces SQLite's automatic checkpoint on every connection (store.h, "Checkpoints"): a
 * commit that left the WAL large only tells the maintenance thread. */
static long wal_kick_pages = STORE_WAL_KICK_BYTES / 4096; /* of the database's page size */

static int wal_grown(void *user, sqlite3 *db, const char *name, int pages)
{
    (void)user;
    (void)db;
    (void)name;
    if (pages >= __atomic_load_n(&wal_kick_pages, __ATOMIC_RELAXED)) store_wal_grown_seen();
    return SQLITE_OK;
}

static sqlite3 *conn_open(void)
{
    char *path = path_copy();
    if (!path) return NULL;
    sqlite3 *db = NULL;
    int rc = sqlite3_open_v2(path, &db,
                             SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                             NULL);
    free(path);
    if (rc != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite open: %s", db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
        sqlite3_close_v2(db);
        return NULL;
    }
    sqlite3_busy_timeout(db, 5000);
    sqlite3_wal_hook(db, wal_grown, NULL);
    char *em = NULL;
    /* journal_size_limit: a WAL that a big result grew to hundreds of MB is cut back to this
     * once a checkpoint has reset it (store_checkpoint truncates it to nothing);
     * secure_delete=FAST: freed pages are not each written again with zeros (store.h) */
    if (sqlite3_exec(db,
                     "PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON; "
                     "PRAGMA secure_delete=FAST; "
                     "PRAGMA journal_size_limit=" STORE_JOURNAL_LIMIT ";",
                     NULL, NULL, &em) != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite pragma: %s", em ? em : "?");
        sqlite3_free(em);
        sqlite3_close_v2(db);
        return NULL;
    }
    if (test_max_length > 0) sqlite3_limit(db, SQLITE_LIMIT_LENGTH, (int)test_max_length);
    test_page_cap(db);
    return db;
}

static void close_handle(void *db) { sqlite3_close_v2(db); }
static void *open_handle(void) { return conn_open(); }
static store_tls tls = {open_handle, close_handle, sizeof(conn_t), conn_destroy, 0, 0};

static conn_t *conn_t_get(void) { return store_tls_get(&tls); }

static sqlite3 *conn(void)
{
    conn_t *c = conn_t_get();
    return c ? c->db : NULL;
}

static long env_long(const char *name)
{
    const char *v = getenv(name);
    long n = v ? strtol(v, NULL, 10) : 0;
    return n > 0 ? n : 0;
}

/* The database lock: an open-file-description write lock (F_OFD_SETLK) on one byte of the
 * database file itself, far from the bytes SQLite locks (its lock page starts at 1 GiB, 512
 * bytes). Being on the file's inode it holds whatever path names the file (a symlink, a hard
 * link, "./x" and "x"); being an OFD lock it is not dropped when SQLite closes one of its own
 * descriptors of the file, as a classic POSIX lock would be; it goes when the daemon closes
 * the store or dies (kill -9 included). Where OFD locks are missing, flock() on the same file.
 * Returns 0 when taken, 1 when another process holds it, -1 on an error (logged). */
#define STORE_LOCK_OFFSET (0x40000000LL + 0x10000LL)
static int lock_take(const char *path)
{
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
        gpd_log(GPD_LOG_ERROR, "cannot open %s to lock it: %s", path, strerror(errno));
        return -1;
    }
    int r = -1, use_flock = 1;
#ifdef F_OFD_SETLK
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    fl.l_start = (off_t)STORE_LOCK_OFFSET;
    fl.l_len = 1;
    use_flock = 0;
    if (fcntl(fd, F_OFD_SETLK, &fl) == 0) {
        r = 0;
    } else if (errno == EAGAIN || errno == EACCES) {
        r = 1;
    } else if (errno == EINVAL) {
        use_flock = 1; /* a kernel without OFD locks */
    } else {
        gpd_log(GPD_LOG_ERROR, "cannot lock %s: %s", path, strerror(errno));
    }
#endif
    if (use_flock) {
        if (flock(fd, LOCK_EX | LOCK_NB) == 0)
            r = 0;
        else if (errno == EWOULDBLOCK)
            r = 1;
        else
            gpd_log(GPD_LOG_ERROR, "cannot lock %s: %s", path, strerror(errno));
    }
    if (r == 0)
        lock_fd = fd;
    else
        close(fd);
    return r;
}

static int sq_open(const char *path)
{
    if (store_tls_init(&tls)) return -1; /* store_open runs once, from main, before any thread */
    test_max_length = env_long("GRAINPACK_TEST_SQLITE_MAX_LENGTH");
    test_max_pages = env_long("GRAINPACK_TEST_SQLITE_MAX_PAGES");
    __atomic_store_n(&schema_made, 0, __ATOMIC_RELEASE);
    /* the lock first: nothing may read or change the jobs of another daemon's database */
    if (lock_fd < 0) {
        int l = lock_take(path);
        if (l) return l > 0 ? STORE_OPEN_LOCKED : -1;
    }
    pthread_mutex_lock(&path_mu);
    free(db_path);
    db_path = strdup(path);
    closed = 0;
    pthread_mutex_unlock(&path_mu);
    if (!db_path) return -1;
    sqlite3 *db = conn();
    if (!db) return -1;
    char *em = NULL;
    /* A new database gives the space of purged jobs back (store_reclaim): auto_vacuum can only
     * be chosen before the first table, and before WAL mode writes the file's first page; so
     * can the page size. 32 KB pages: a result is tens to thousands of MB, written and read
     * as a chain of pages, and SQLite's cost is per page -- a 10,000-grain result and its pack
     * (90 MB) commit in ~0.3 s instead of ~0.6 s with the default 4 KB, while a small commit
     * (a progress update) costs the same. 64 KB gains little more, and the peak memory of a
     * store grew with it (test_store_write: +22 MB against +7 MB at 32 KB and none at 16 KB,
     * for a 34 MB result). An older database keeps its pages. WAL is persistent in the file;
     * set it once here. */
    int fresh = query_long(db, "SELECT count(*) FROM sqlite_master") == 0;
    if ((fresh && sqlite3_exec(db, "PRAGMA page_size=" STORE_PAGE_SIZE "; "
                                   "PRAGMA auto_vacuum=INCREMENTAL;", NULL, NULL, &em) !=
                      SQLITE_OK) ||
        sqlite3_exec(db, "PRAGMA journal_mode=WAL;", NULL, NULL, &em) != SQLITE_OK ||
        sqlite3_exec(db, SCHEMA_SQL, NULL, NULL, &em) != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "cannot initialise database %s: %s", path, em ? em : "?");
        sqlite3_free(em);
        return -1;
    }
    if (add_brief_column(db)) return -1;
    __atomic_store_n(&schema_made, 1, __ATOMIC_RELEASE);
    test_page_cap(db);
    long psz = query_long(db, "PRAGMA page_size");
    if (psz > 0) __atomic_store_n(&wal_kick_pages, STORE_WAL_KICK_BYTES / psz, __ATOMIC_RELAXED);
    auto_vacuum = query_long(db, "PRAGMA auto_vacuum") == 2;
    if (!auto_vacuum)
        gpd_log(GPD_LOG_WARN,
                "database %s was made without auto_vacuum: the space of purged jobs is reused "
                "but not given back to the file system until it is converted once, with the "
                "daemon stopped: sqlite3 %s 'PRAGMA auto_vacuum=INCREMENTAL; VACUUM;' (see README)",
                path, path);
    return 0;
}

static void sq_thread_done(void)
{
    store_tls_drop(&tls);
}

static void sq_close(void)
{
    sq_thread_done();
    pthread_mutex_lock(&path_mu);
    closed = 1;
    free(db_path);
    db_path = NULL;
    pthread_mutex_unlock(&path_mu);
    if (lock_fd >= 0) { /* the last: the database is released once this daemon is done */
        close(lock_fd);
        lock_fd = -1;
    }
}

/* ------------------------------------------------------------------ helpers */

/* A prepared statement for sql (a string literal) on this thread's connection db; give it
 * back with done(). */
static sqlite3_stmt *prep(sqlite3 *db, const char *sql)
{
    conn_t *c = store_tls_peek(&tls);
    if (c && c->db == db)
        for (int i = 0; i < c->n; i++)
            if (c->sql[i] == sql) return c->st[i];
    sqlite3_stmt *st = NULL;
    if (sqlite3_prepare_v3(db, sql, -1, SQLITE_PREPARE_PERSISTENT, &st, NULL) != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite prepare: %s (%s)", sqlite3_errmsg(db), sql);
        return NULL;
    }
    if (c && c->db == db && c->n < STMT_CACHE) {
        c->sql[c->n] = sql;
        c->st[c->n++] = st;
    }
    return st;
}

/* Resets a statement from prep() (finalizes it when it is not cached). */
static void done(sqlite3_stmt *st)
{
    if (!st) return;
    conn_t *c = store_tls_peek(&tls);
    if (c)
        for (int i = 0; i < c->n; i++)
            if (c->st[i] == st) {
                sqlite3_reset(st);
                sqlite3_clear_bindings(st);
                return;
            }
    sqlite3_finalize(st);
}

/* Returns SQLite's code: SQLITE_OK, or e.g. SQLITE_TOOBIG (the parameter is then NULL, so a
 * write must not go on). */
static int bind_text(sqlite3_stmt *st, int i, const char *s)
{
    if (s) return sqlite3_bind_text(st, i, s, -1, SQLITE_TRANSIENT);
    return sqlite3_bind_null(st, i);
}

static int step_done(sqlite3 *db, sqlite3_stmt *st)
{
    int rc = sqlite3_step(st);
    if (rc != SQLITE_DONE && rc != SQLITE_ROW) {
        gpd_log(GPD_LOG_ERROR, "sqlite step: %s", sqlite3_errmsg(db));
        if (!sqlite3_stmt_readonly(st)) store_note_write_error("a job update", sqlite3_errmsg(db));
        return -1;
    }
    return 0;
}

static json_t *json_col(sqlite3_stmt *st, int i)
{
    const unsigned char *t = sqlite3_column_text(st, i);
    if (!t) return json_null();
    json_t *j = json_loads((const char *)t, JSON_DECODE_ANY, NULL);
    return j ? j : json_null();
}

static json_t *text_col(sqlite3_stmt *st, int i)
{
    const unsigned char *t = sqlite3_column_text(st, i);
    return t ? json_string((const char *)t) : json_null();
}

/* The progress of a job that has ended without success (failed, cancelled): its last phase
 * and fraction, eta_s null (SQL NULL becomes JSON null) -- no time is left to wait for. */
#define PROGRESS_ENDED                                                                         \
    "progress=CASE WHEN json_valid(progress) THEN json_set(progress, '$.eta_s', NULL) "          \
    "ELSE progress END"

/* job object columns */
#define JOB_COLS "id, kind, status, created_at, started_at, finished_at, progress, error, brief"

static json_t *job_from_row(sqlite3_stmt *st)
{
    json_t *j = json_object();
    json_object_set_new(j, "id", text_col(st, 0));
    json_object_set_new(j, "kind", text_col(st, 1));
    json_object_set_new(j, "status", text_col(st, 2));
    json_object_set_new(j, "created_at", text_col(st, 3));
    json_object_set_new(j, "started_at", text_col(st, 4));
    json_object_set_new(j, "finished_at", text_col(st, 5));
    json_t *p = json_col(st, 6);
    if (json_is_null(p)) {
        json_decref(p);
        p = json_pack("{s:s, s:f, s:n, s:{}}", "phase", "queued", "fraction", 0.0, "eta_s",
                      "detail");
    }
    json_object_set_new(j, "progress", p);
    json_object_set_new(j, "error", json_col(st, 7));
    json_object_set_new(j, "brief", json_col(st, 8));
    return j;
}

/* Prepares sql (a SELECT of one job: ?1 its id, column 0 its status) and steps to the job's
 * row: STORE_OK with the status copied and *stp at the row (give it back with done()),
 * STORE_NOT_FOUND, or STORE_ERROR (logged, as what) -- *stp NULL then. */
static store_rc job_row(sqlite3 *db, const char *sql, const char *id, const char *what,
                        sqlite3_stmt **stp, char status[16])
{
    *stp = NULL;
    sqlite3_stmt *st = prep(db, sql);
    if (!st) return STORE_ERROR;
    bind_text(st, 1, id);
    int s = sqlite3_step(st);
    if (s == SQLITE_ROW) {
        const unsigned char *t = sqlite3_column_text(st, 0);
        snprintf(status, 16, "%s", t ? (const char *)t : "");
        *stp = st;
        return STORE_OK;
    }
    if (s != SQLITE_DONE) gpd_log(GPD_LOG_ERROR, "sqlite %s: %s", what, sqlite3_errmsg(db));
    done(st);
    return s == SQLITE_DONE ? STORE_NOT_FOUND : STORE_ERROR;
}

/* ------------------------------------------------------------------ operations */

static int sq_recover(int *requeued, int *failed)
{
    sqlite3 *db = conn();
    if (!db) return -1;
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    int rc = -1;
    if (sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) return -1;
    sqlite3_stmt *a = prep(db, "UPDATE jobs SET status='failed', finished_at=?1, error=?2, "
                               PROGRESS_ENDED " WHERE status='running' AND attempts >= ?3");
    sqlite3_stmt *b = prep(db, "UPDATE jobs SET status='queued', started_at=NULL, progress=NULL "
                               "WHERE status='running'");
    if (a && b) {
        char err[256];
        snprintf(err, sizeof err,
                 "{\"code\":\"interrupted\",\"message\":\"interrupted %d times (the daemon "
                 "stopped while the job was running); not retried\"}",
                 STORE_MAX_ATTEMPTS);
        bind_text(a, 1, now);
        bind_text(a, 2, err);
        sqlite3_bind_int(a, 3, STORE_MAX_ATTEMPTS);
        if (step_done(db, a) == 0) {
            if (failed) *failed = sqlite3_changes(db);
            if (step_done(db, b) == 0) {
                if (requeued) *requeued = sqlite3_changes(db);
                rc = 0;
            }
        }
    }
    done(a);
    done(b);
    if (sqlite3_exec(db, rc == 0 ? "COMMIT" : "ROLLBACK", NULL, NULL, NULL) != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite recover %s: %s", rc == 0 ? "commit" : "rollback",
                sqlite3_errmsg(db));
        if (!sqlite3_get_autocommit(db)) sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
        rc = -1;
    }
    return rc;
}

static store_rc sq_insert(const char *kind, const char *spec_json, const char *brief_json,
                      long max_queued, char id_out[33])
{
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    if (gpd_new_id(id_out) != 0) return STORE_ERROR;
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    /* the queue's cap in the same statement: two submits cannot both take the last place (the
     * count walks the status index: 10,000 queued jobs cost well under a millisecond) */
    sqlite3_stmt *st = prep(db, "INSERT INTO jobs(id, kind, spec, status, created_at, brief) "
                                "SELECT ?1, ?2, ?3, 'queued', ?4, ?6 WHERE ?5 <= 0 OR "
                                "(SELECT count(*) FROM jobs WHERE status='queued') < ?5");
    if (!st) return STORE_ERROR;
    int rc = -1;
    if (bind_text(st, 1, id_out) == SQLITE_OK && bind_text(st, 2, kind) == SQLITE_OK &&
        bind_text(st, 3, spec_json) == SQLITE_OK && bind_text(st, 4, now) == SQLITE_OK &&
        sqlite3_bind_int64(st, 5, max_queued) == SQLITE_OK &&
        bind_text(st, 6, brief_json) == SQLITE_OK)
        rc = step_done(db, st);
    else
        gpd_log(GPD_LOG_ERROR, "sqlite insert: %s", sqlite3_errmsg(db));
    int inserted = rc == 0 && sqlite3_changes(db) > 0;
    done(st);
    return rc != 0 ? STORE_ERROR : inserted ? STORE_OK : STORE_FULL;
}

static json_t *sq_get_job(const char *id, store_rc *rc)
{
    sqlite3 *db = conn();
    *rc = STORE_ERROR;
    if (!db) return NULL;
    sqlite3_stmt *st = prep(db, "SELECT " JOB_COLS " FROM jobs WHERE id=?1");
    if (!st) return NULL;
    bind_text(st, 1, id);
    json_t *j = NULL;
    int s = sqlite3_step(st);
    if (s == SQLITE_ROW) {
        j = job_from_row(st);
        *rc = STORE_OK;
    } else if (s == SQLITE_DONE) {
        *rc = STORE_NOT_FOUND;
    } else {
        gpd_log(GPD_LOG_ERROR, "sqlite get: %s", sqlite3_errmsg(db));
    }
    done(st);
    return j;
}

static store_rc sq_get_text(const char *id, const char *column, char **text, char status[16])
{
    *text = NULL;
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    const char *sql;
    if (!strcmp(column, "spec"))
        sql = "SELECT status, spec FROM jobs WHERE id=?1";
    else if (!strcmp(column, "kind"))
        sql = "SELECT status, kind FROM jobs WHERE id=?1";
    else
        return STORE_ERROR;
    char what[32];
    snprintf(what, sizeof what, "get %s", column);
    sqlite3_stmt *st;
    store_rc rc = job_row(db, sql, id, what, &st, status);
    const unsigned char *t = st ? sqlite3_column_text(st, 1) : NULL;
    if (t) {
        *text = strdup((const char *)t);
        if (!*text) rc = STORE_ERROR;
    }
    done(st);
    return rc;
}

static json_t *sq_list(const char *status, int limit, const char *after, store_rc *rc)
{
    *rc = STORE_ERROR;
    sqlite3 *db = conn();
    if (!db) return NULL;
    sqlite3_int64 after_seq = -1;
    if (after) {
        sqlite3_stmt *q = prep(db, "SELECT seq FROM jobs WHERE id=?1");
        if (!q) return NULL;
        bind_text(q, 1, after);
        int s = sqlite3_step(q);
        if (s == SQLITE_ROW) after_seq = sqlite3_column_int64(q, 0);
        done(q);
        if (s == SQLITE_DONE) {
            *rc = STORE_NOT_FOUND;
            return NULL;
        }
        if (s != SQLITE_ROW) return NULL;
    }
    sqlite3_stmt *st = prep(db, "SELECT " JOB_COLS " FROM jobs "
                                "WHERE (?1 IS NULL OR status=?1) AND (?2 < 0 OR seq < ?2) "
                                "ORDER BY seq DESC LIMIT ?3");
    if (!st) return NULL;
    bind_text(st, 1, status);
    sqlite3_bind_int64(st, 2, after_seq);
    sqlite3_bind_int(st, 3, limit + 1);
    json_t *jobs = json_array();
    int n = 0, s;
    json_t *next = json_null();
    while ((s = sqlite3_step(st)) == SQLITE_ROW) {
        if (n == limit) {
            /* there is more: the cursor is the last job returned */
            json_t *last = json_array_get(jobs, (size_t)n - 1);
            json_decref(next);
            next = json_incref(json_object_get(last, "id"));
            break;
        }
        json_array_append_new(jobs, job_from_row(st));
        n++;
    }
    done(st);
    if (s != SQLITE_ROW && s != SQLITE_DONE) {
        gpd_log(GPD_LOG_ERROR, "sqlite list: %s", sqlite3_errmsg(db));
        json_decref(jobs);
        json_decref(next);
        return NULL;
    }
    *rc = STORE_OK;
    return json_pack("{s:o, s:o}", "jobs", jobs, "next", next);
}

static store_rc sq_counts(long n[STORE_NSTATUS])
{
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    sqlite3_stmt *st = prep(db, "SELECT status, count(*) FROM jobs GROUP BY status");
    if (!st) return STORE_ERROR;
    int s;
    while ((s = sqlite3_step(st)) == SQLITE_ROW) {
        int k = store_status_slot((const char *)sqlite3_column_text(st, 0));
        if (k >= 0) n[k] = (long)sqlite3_column_int64(st, 1);
    }
    done(st);
    return s == SQLITE_DONE ? STORE_OK : STORE_ERROR;
}

/* reads do not wait for writers in WAL mode: nothing to bound */
static store_rc sq_counts_within(long n[STORE_NSTATUS], double wait_s)
{
    (void)wait_s;
    return sq_counts(n);
}

static store_rc sq_claim(char id[33], char **kind, char **spec_json, int *attempts)
{
    *kind = NULL;
    *spec_json = NULL;
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    /* One statement: atomic with respect to every other connection. */
    sqlite3_stmt *st = prep(
        db, "UPDATE jobs SET status='running', started_at=?1, finished_at=NULL, "
            "attempts=attempts+1, "
            "progress='{\"phase\":\"starting\",\"fraction\":0,\"eta_s\":null,\"detail\":{}}' "
            "WHERE seq=(SELECT seq FROM jobs WHERE status='queued' ORDER BY seq LIMIT 1) "
            "AND status='queued' RETURNING id, kind, spec, attempts");
    if (!st) return STORE_ERROR;
    bind_text(st, 1, now);
    store_rc rc = STORE_ERROR;
    int s = sqlite3_step(st);
    if (s == SQLITE_ROW) {
        snprintf(id, 33, "%s", (const char *)sqlite3_column_text(st, 0));
        *kind = strdup((const char *)sqlite3_column_text(st, 1));
        *spec_json = strdup((const char *)sqlite3_column_text(st, 2));
        *attempts = sqlite3_column_int(st, 3);
        s = sqlite3_step(st); /* finish the statement so that the change commits */
        rc = (s == SQLITE_DONE && *kind && *spec_json) ? STORE_OK : STORE_ERROR;
        /* a job runs now: a checkpoint that waited for idle workers gives way to it */
        if (rc == STORE_OK) store_checkpoint_yield();
        if (rc != STORE_OK) {
            free(*kind);
            free(*spec_json);
            *kind = *spec_json = NULL;
        }
    } else if (s == SQLITE_DONE) {
        rc = STORE_NOT_FOUND;
    }
    if (rc == STORE_ERROR) {
        gpd_log(GPD_LOG_ERROR, "sqlite claim: %s", sqlite3_errmsg(db));
        store_note_write_error("claiming a job", sqlite3_errmsg(db));
    }
    done(st);
    return rc;
}

static store_rc update_running(const char *sql, const char *id, const char *a, const char *b,
                               const char *c)
{
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    sqlite3_stmt *st = prep(db, sql);
    if (!st) return STORE_ERROR;
    int np = sqlite3_bind_parameter_count(st);
    int b_rc = bind_text(st, 1, id);
    if (b_rc == SQLITE_OK && np >= 2) b_rc = bind_text(st, 2, a);
    if (b_rc == SQLITE_OK && np >= 3) b_rc = bind_text(st, 3, b);
    if (b_rc == SQLITE_OK && np >= 4) b_rc = bind_text(st, 4, c);
    int rc = -1;
    if (b_rc == SQLITE_OK)
        rc = step_done(db, st);
    else
        gpd_log(GPD_LOG_ERROR, "sqlite bind: %s", sqlite3_errstr(b_rc));
    done(st);
    if (rc) return STORE_ERROR;
    return sqlite3_changes(db) > 0 ? STORE_OK : STORE_CONFLICT;
}

static store_rc sq_progress(const char *id, const char *progress_json)
{
    return update_running("UPDATE jobs SET progress=?2 WHERE id=?1 AND status='running'", id,
                          progress_json, NULL, NULL);
}

/* Runs sql, a write of one row, with ?1 = id, ?2 = the text v and ?3 = the text a where the
 * statement has it (small values: the summary, the brief). Returns SQLite's code (SQLITE_OK
 * once done) and the rows changed in *changes. */
static int write_small(sqlite3 *db, const char *sql, const char *id, const char *v,
                       const char *a, int *changes)
{
    *changes = 0;
    sqlite3_stmt *st = prep(db, sql);
    if (!st) return sqlite3_errcode(db);
    int rc = bind_text(st, 1, id);
    if (rc == SQLITE_OK) rc = bind_text(st, 2, v);
    if (rc == SQLITE_OK && sqlite3_bind_parameter_count(st) >= 3) rc = bind_text(st, 3, a);
    if (rc == SQLITE_OK) {
        rc = sqlite3_step(st);
        if (rc == SQLITE_DONE) {
            rc = SQLITE_OK;
            *changes = sqlite3_changes(db);
        }
    }
    done(st);
    return rc;
}

/* Status 'succeeded' with the "done" progress, only while the job is running: SQLite's code,
 * and the job's seq (0 when it was not running: cancelled meanwhile). */
static int mark_succeeded(sqlite3 *db, const char *id, const char *progress_json,
                          const char *now, sqlite3_int64 *seq)
{
    *seq = 0;
    sqlite3_stmt *st = prep(db, "UPDATE jobs SET status='succeeded', progress=?2, "
                                "finished_at=?3, error=NULL WHERE id=?1 AND status='running' "
                                "RETURNING seq");
    if (!st) return sqlite3_errcode(db);
    int rc = bind_text(st, 1, id);
    if (rc == SQLITE_OK) rc = bind_text(st, 2, progress_json);
    if (rc == SQLITE_OK) rc = bind_text(st, 3, now);
    if (rc == SQLITE_OK) {
        rc = sqlite3_step(st);
        if (rc == SQLITE_ROW) {
            *seq = sqlite3_column_int64(st, 0);
            rc = sqlite3_step(st); /* to the end: the update is done */
        }
        if (rc == SQLITE_DONE) rc = SQLITE_OK;
    }
    done(st);
    return rc;
}

/* Fills the blob table.column of row rowid (made as zeroblob(n)) with bytes [base, base + n)
 * of v, STORE_PIECE at a time, straight from memory or read from the file into buf. SQLite's
 * code; a failed read of the file is SQLITE_IOERR with *read_errno set. */
static int fill_blob(sqlite3 *db, const char *table, const char *column, sqlite3_int64 rowid,
                     const store_text *v, uint64_t base, uint64_t n, char *buf, int *read_errno)
{
    sqlite3_blob *b = NULL;
    int rc = sqlite3_blob_open(db, "main", table, column, rowid, 1, &b);
    js_source src = store_text_source(v);
    for (uint64_t off = 0; rc == SQLITE_OK && off < n; off += STORE_PIECE) {
        size_t k = n - off < STORE_PIECE ? (size_t)(n - off) : STORE_PIECE;
        const char *piece = v->mem ? v->mem + base + off : buf;
        if (!v->mem && src.read(src.user, base + off, buf, k)) {
            *read_errno = errno ? errno : EIO;
            rc = SQLITE_IOERR;
            break;
        }
        rc = sqlite3_blob_write(b, piece, (int)k, (int)off); /* a part < the length limit */
    }
    int crc = sqlite3_blob_close(b);
    return rc == SQLITE_OK ? crc : rc;
}

/* Inserts one part as zeroblob(n) -- the row's last column, so SQLite keeps the zeros implicit
 * and builds no record of n bytes: sql binds ?1 seq, ?2 the zeroblob and, for value_parts,
 * ?3 what and ?4 part. SQLite's code, and the row's rowid. */
static int insert_zeroblob(sqlite3 *db, const char *sql, sqlite3_int64 seq, int what, int part,
                           uint64_t n, sqlite3_int64 *rowid)
{
    sqlite3_stmt *st = prep(db, sql);
    if (!st) return sqlite3_errcode(db);
    sqlite3_bind_int64(st, 1, seq);
    int rc = sqlite3_bind_zeroblob64(st, 2, n);
    if (rc == SQLITE_OK && sqlite3_bind_parameter_count(st) >= 4) {
        sqlite3_bind_int(st, 3, what);
        sqlite3_bind_int(st, 4, part);
    }
    if (rc == SQLITE_OK) {
        rc = sqlite3_step(st);
        if (rc == SQLITE_DONE) rc = SQLITE_OK;
    }
    *rowid = sqlite3_last_insert_rowid(db);
    done(st);
    return rc;
}

/* Writes value v (what: STORE_VALUE_*) of job seq: part 0 by home_sql into table.column (row
 * seq), the others into value_parts (store.h "Values in parts"), each filled in place. Inside
 * the caller's transaction. SQLite's code (SQLITE_OK when done). */
static int write_value(sqlite3 *db, const char *home_sql, const char *table, const char *column,
                       sqlite3_int64 seq, int what, const store_text *v, char *buf,
                       int *read_errno)
{
    sqlite3_stmt *st = prep(db, "DELETE FROM value_parts WHERE seq=?1 AND what=?2");
    if (!st) return sqlite3_errcode(db);
    sqlite3_bind_int64(st, 1, seq);
    sqlite3_bind_int(st, 2, what);
    int rc = step_done(db, st) ? sqlite3_errcode(db) : SQLITE_OK;
    done(st);
    uint64_t part = store_part_size(sqlite3_limit(db, SQLITE_LIMIT_LENGTH, -1));
    for (uint64_t base = 0, k = 0; rc == SQLITE_OK && (k == 0 || base < v->len);
         base += part, k++) {
        uint64_t n = v->len - base < part ? v->len - base : part;
        sqlite3_int64 rowid = 0;
        rc = insert_zeroblob(db,
                             k ? "INSERT INTO value_parts(seq, what, part, data) "
                                 "VALUES (?1, ?3, ?4, ?2)"
                               : home_sql,
                             seq, what, (int)k, n, &rowid);
        if (rc == SQLITE_OK)
            rc = fill_blob(db, k ? "value_parts" : table, k ? "data" : column, rowid, v, base, n,
                           buf, read_errno);
    }
    return rc;
}

/* The end of store_succeed's transaction: COMMIT when every write passed, else the reason
 * (before ROLLBACK replaces SQLite's message) in why and the log. src: the last SQLite code;
 * read_errno: a failed read of the result's file (0: none). */
static store_rc succeed_end(sqlite3 *db, const char *id, store_rc rc, int src, int read_errno,
                            gpd_err *why)
{
    if (rc == STORE_OK) {
        src = sqlite3_exec(db, "COMMIT", NULL, NULL, NULL);
        if (src != SQLITE_OK) rc = STORE_ERROR;
    }
    if (rc == STORE_ERROR) {
        if (src == SQLITE_OK) src = sqlite3_errcode(db);
        const char *em = sqlite3_errmsg(db);
        int more = em && strcmp(em, sqlite3_errstr(src));
        if ((src & 0xff) == SQLITE_TOOBIG) rc = STORE_TOOBIG;
        if (read_errno)
            gpd_err_set(why, 500, "reading the result's temporary file: %s",
                        strerror(read_errno));
        else
            gpd_err_set(why, 500, "%s%s%s", sqlite3_errstr(src), more ? ": " : "",
                        more ? em : "");
        gpd_log(GPD_LOG_ERROR, "job %s: cannot store the result: %s", id, why->msg);
        if (rc != STORE_TOOBIG) store_note_write_error("storing a result", why->msg);
    }
    if (!sqlite3_get_autocommit(db) && sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL) != SQLITE_OK)
        gpd_log(GPD_LOG_ERROR, "sqlite rollback: %s", sqlite3_errmsg(db));
    return rc;
}

/* The writes of store_succeed's transaction after the status: brief, result, pack, summary. */
static store_rc succeed_rows(sqlite3 *db, const char *id, sqlite3_int64 seq,
                             const store_text *result, const char *brief_json,
                             const void *pack, size_t pack_len, const char *summary,
                             const char *arrays, int *src, int *read_errno)
{
    int changes = 0;
    if (brief_json) {
        *src = write_small(db, "UPDATE jobs SET brief=?2 WHERE id=?1", id, brief_json, NULL,
                           &changes);
        if (*src != SQLITE_OK || changes != 1) return STORE_ERROR;
    }
    char *buf = result->mem ? NULL : malloc(STORE_PIECE);
    if (!result->mem && !buf) {
        *src = SQLITE_NOMEM;
        return STORE_ERROR;
    }
    *src = write_value(db, "INSERT OR REPLACE INTO results(seq, result) VALUES (?1, ?2)",
                       "results", "result", seq, STORE_VALUE_RESULT, result, buf, read_errno);
    free(buf);
    if (*src != SQLITE_OK) return STORE_ERROR;
    if (pack) {
        store_text p = {pack, -1, pack_len};
        *src = write_value(db, "INSERT OR REPLACE INTO exports(seq, pack) VALUES (?1, ?2)",
                           "exports", "pack", seq, STORE_VALUE_PACK, &p, NULL, read_errno);
        if (*src != SQLITE_OK) return STORE_ERROR;
    }
    if (summary) {
        *src = write_small(db, "INSERT OR REPLACE INTO summaries(seq, summary, arrays) "
                               "SELECT seq, ?2, ?3 FROM jobs WHERE id=?1",
                           id, summary, arrays, &changes);
        if (*src != SQLITE_OK || changes != 1) return STORE_ERROR;
    }
    return STORE_OK;
}

/* store_succeed's transaction (store.c made the summary and checked the arguments) */
static store_rc sq_succeed(const char *id, const store_text *result, const char *progress_json,
                           const char *brief_json, const void *pack, size_t pack_len,
                           const char *summary, size_t slen, const char *arrays, gpd_err *why)
{
    (void)slen;
    sqlite3 *db = conn();
    if (!db) {
        gpd_err_set(why, 500, "no connection to the database");
        return STORE_ERROR;
    }
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    /* The result, the pack and the status change commit together: a job never shows
     * succeeded without its files. Every SQLite code is checked: a failure anywhere rolls the
     * whole transaction back, so the job stays running for the caller to retry or fail. */
    int read_errno = 0, src = sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL);
    store_rc rc = STORE_ERROR;
    sqlite3_int64 seq = 0;
    if (src == SQLITE_OK) {
        src = mark_succeeded(db, id, progress_json, now, &seq);
        if (src == SQLITE_OK) rc = seq > 0 ? STORE_OK : STORE_CONFLICT;
    }
    if (rc == STORE_OK)
        rc = succeed_rows(db, id, seq, result, brief_json, pack, pack_len, summary, arrays,
                          &src, &read_errno);
    return succeed_end(db, id, rc, src, read_errno, why);
}

/* ------------------------------------------------------------------ streams */

/* A value read across its parts (store.h "Values in parts") in one snapshot: the private
 * connection's read transaction, begun before part 0 is opened. */
struct store_stream {
    sqlite3 *db;
    sqlite3_blob *blob;  /* the part being read (cur) */
    size_t cur;
    const char *table, *column; /* part 0's row: seq of table.column */
    sqlite3_int64 seq;
    sqlite3_int64 *rowid; /* of the other parts in value_parts (rowid[0] unused) */
    store_parts parts;
};

/* Opens table.column of row seq on db; 0 on success, 1 when there is no such value. */
static int blob_open(sqlite3 *db, const char *table, const char *column, sqlite3_int64 seq,
                     sqlite3_blob **out)
{
    *out = NULL;
    int rc = sqlite3_blob_open(db, "main", table, column, seq, 0, out);
    if (rc == SQLITE_OK) return 0;
    /* a NULL result or a job without a pack: "cannot open value of type null" / "no such
     * rowid" */
    sqlite3_blob_close(*out);
    *out = NULL;
    return 1;
}

/* The parts after part 0 of value `what` of job seq, on db (in its transaction): their rowids
 * and sizes appended to ss. 0, or -1. */
static int list_parts(sqlite3 *db, sqlite3_int64 seq, int what, store_stream *ss)
{
    sqlite3_stmt *st = NULL;
    /* length() of a blob reads its record header, not its pages */
    if (sqlite3_prepare_v2(db, "SELECT rowid, length(data) FROM value_parts "
                               "WHERE seq=?1 AND what=?2 ORDER BY part",
                           -1, &st, NULL) != SQLITE_OK)
        return -1;
    sqlite3_bind_int64(st, 1, seq);
    sqlite3_bind_int(st, 2, what);
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        sqlite3_int64 *r = realloc(ss->rowid, (ss->parts.n + 1) * sizeof *r);
        if (!r) break;
        ss->rowid = r;
        r[ss->parts.n] = sqlite3_column_int64(st, 0);
        if (store_parts_add(&ss->parts, (uint64_t)sqlite3_column_int64(st, 1))) break;
    }
    sqlite3_finalize(st);
    return rc == SQLITE_DONE ? 0 : -1;
}

/* Makes part k the open blob of ss; 0, or -1. */
static int part_open(store_stream *ss, size_t k)
{
    if (ss->blob && ss->cur == k) return 0;
    int rc;
    if (ss->blob && k > 0 && ss->cur > 0)
        rc = sqlite3_blob_reopen(ss->blob, ss->rowid[k]);
    else {
        sqlite3_blob_close(ss->blob);
        ss->blob = NULL;
        rc = sqlite3_blob_open(ss->db, "main", k ? "value_parts" : ss->table,
                               k ? "data" : ss->column, k ? ss->rowid[k] : ss->seq, 0,
                               &ss->blob);
    }
    if (rc != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite stream part %zu: %s", k, sqlite3_errmsg(ss->db));
        sqlite3_blob_close(ss->blob);
        ss->blob = NULL;
        return -1;
    }
    ss->cur = k;
    return 0;
}

static void sq_stream_close(store_stream *s);
static uint64_t sq_stream_size(const store_stream *s);

/* The stream of table.column of row seq (part 0) and its other parts, on a private connection
 * that lives as long as the stream, in one read transaction. */
static store_rc open_private(const char *table, const char *column, sqlite3_int64 seq, int what,
                             store_stream **out)
{
    char *path = path_copy();
    store_stream *ss = path ? calloc(1, sizeof *ss) : NULL;
    int rc = ss ? sqlite3_open_v2(path, &ss->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX,
                                  NULL)
                : SQLITE_NOMEM;
    free(path);
    if (!ss) return STORE_ERROR;
    ss->table = table;
    ss->column = column;
    ss->seq = seq;
    if (rc == SQLITE_OK) {
        sqlite3_busy_timeout(ss->db, 5000);
        /* the blob is read front to back once: a small page cache is enough */
        rc = sqlite3_exec(ss->db, "PRAGMA cache_size=-256; BEGIN", NULL, NULL, NULL);
    }
    if (rc != SQLITE_OK || part_open(ss, 0) ||
        store_parts_add(&ss->parts, (uint64_t)sqlite3_blob_bytes(ss->blob)) ||
        !(ss->rowid = calloc(1, sizeof *ss->rowid)) || list_parts(ss->db, seq, what, ss)) {
        gpd_log(GPD_LOG_ERROR, "sqlite stream open: %s", ss->db ? sqlite3_errmsg(ss->db) : "?");
        sq_stream_close(ss);
        return STORE_ERROR;
    }
    *out = ss;
    return STORE_OK;
}

/* 1 when value `what` of job seq has parts after part 0 (on db, this thread's). */
static int has_parts(sqlite3 *db, sqlite3_int64 seq, int what)
{
    sqlite3_stmt *st = prep(db, "SELECT 1 FROM value_parts WHERE seq=?1 AND what=?2 LIMIT 1");
    if (!st) return 1; /* the stream finds out */
    sqlite3_bind_int64(st, 1, seq);
    sqlite3_bind_int(st, 2, what);
    int rc = sqlite3_step(st);
    done(st);
    return rc != SQLITE_DONE;
}

/* A value of at most small bytes read whole (on this thread's connection; the blob closed at
 * once): 0 with *text; -1 on a failed read or out of memory. */
static int read_small(sqlite3_blob *b, uint64_t size, char **text, size_t *text_len)
{
    char *buf = malloc(size + 1);
    if (!buf || sqlite3_blob_read(b, buf, (int)size, 0) != SQLITE_OK) {
        free(buf);
        return -1;
    }
    buf[size] = 0;
    *text = buf;
    *text_len = size;
    return 0;
}

static store_rc sq_stream_open(const char *id, int is_pack, size_t small, store_stream **out,
                               char **text, size_t *text_len, char status[16])
{
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    sqlite3_stmt *st;
    store_rc rc = job_row(db, "SELECT status, seq FROM jobs WHERE id=?1", id, "stream", &st,
                          status);
    sqlite3_int64 seq = st ? sqlite3_column_int64(st, 1) : 0;
    done(st);
    if (rc != STORE_OK) return rc;
    /* a result is in results, or in jobs.result when it was stored before that table */
    const char *table = is_pack ? "exports" : "results", *column = is_pack ? "pack" : "result";
    sqlite3_blob *b;
    if (blob_open(db, table, column, seq, &b)) {
        if (is_pack || blob_open(db, "jobs", "result", seq, &b)) return STORE_OK; /* none */
        table = "jobs";
    }
    int kind = is_pack ? STORE_VALUE_PACK : STORE_VALUE_RESULT;
    uint64_t size = (uint64_t)sqlite3_blob_bytes(b);
    if (size <= small && !has_parts(db, seq, kind)) { /* the common case: on this connection */
        rc = read_small(b, size, text, text_len) ? STORE_ERROR : STORE_OK;
        sqlite3_blob_close(b);
        return rc;
    }
    sqlite3_blob_close(b);
    rc = open_private(table, column, seq, kind, out);
    return store_stream_settle(rc, out, small, text, text_len);
}

static uint64_t sq_stream_size(const store_stream *s)
{
    return s->parts.end[s->parts.n - 1];
}

static int sq_stream_read(store_stream *s, uint64_t off, void *dst, size_t n)
{
    if (off > sq_stream_size(s) || n > sq_stream_size(s) - off) return -1;
    char *d = dst;
    while (n > 0) {
        uint64_t start;
        size_t k = store_parts_find(&s->parts, off, &start);
        size_t m = s->parts.end[k] - off < n ? (size_t)(s->parts.end[k] - off) : n;
        if (part_open(s, k) || m > INT_MAX ||
            sqlite3_blob_read(s->blob, d, (int)m, (int)(off - start)) != SQLITE_OK)
            return -1;
        d += m;
        off += m;
        n -= m;
    }
    return 0;
}

static void sq_stream_close(store_stream *s)
{
    if (!s) return;
    sqlite3_blob_close(s->blob);
    sqlite3_close_v2(s->db);
    store_parts_free(&s->parts);
    free(s->rowid);
    free(s);
}

/* ------------------------------------------------------------------ summaries */

static store_rc sq_stored_summary(const char *id, char **text, size_t *len,
                           uint64_t spans[STORE_SUMMARY_NSKIP][2], char status[16])
{
    *text = NULL;
    if (len) *len = 0;
    status[0] = 0;
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    sqlite3_stmt *st;
    store_rc rc = job_row(db, "SELECT j.status, s.summary, s.arrays FROM jobs j "
                              "LEFT JOIN summaries s ON s.seq = j.seq WHERE j.id=?1",
                          id, "get summary", &st, status);
    const unsigned char *t = st ? sqlite3_column_text(st, 1) : NULL;
    uint64_t sp[STORE_SUMMARY_NSKIP][2];
    if (t && store_spans_parse((const char *)sqlite3_column_text(st, 2), sp) == 0) {
        size_t n = (size_t)sqlite3_column_bytes(st, 1);
        *text = malloc(n + 1);
        if (*text) {
            memcpy(*text, t, n + 1);
            if (len) *len = n;
            if (spans) memcpy(spans, sp, sizeof sp);
        } else {
            rc = STORE_ERROR;
        }
    }
    done(st);
    return rc;
}

/* ---- briefs of jobs stored before briefs ---- */

#define BRIEF_BATCH 64 /* jobs a pass of store_fill_briefs reads, then writes in one transaction
                        * (the LIMIT below) */

typedef struct brief_row {
    char id[33];
    char *kind, *spec, *brief;
    int succeeded;
} brief_row;

/* Up to BRIEF_BATCH jobs without a brief (their id, kind, spec and whether they succeeded):
 * how many, or -1. */
static int brief_rows(sqlite3 *db, brief_row *rows)
{
    sqlite3_stmt *st = prep(db, "SELECT id, kind, spec, status FROM jobs WHERE brief IS NULL "
                                "ORDER BY seq LIMIT 64");
    if (!st) return -1;
    int n = 0, s = SQLITE_DONE;
    while (n < BRIEF_BATCH && (s = sqlite3_step(st)) == SQLITE_ROW) {
        brief_row *r = &rows[n++];
        snprintf(r->id, sizeof r->id, "%s", (const char *)sqlite3_column_text(st, 0));
        r->kind = strdup((const char *)sqlite3_column_text(st, 1));
        r->spec = strdup((const char *)sqlite3_column_text(st, 2));
        r->succeeded = !strcmp((const char *)sqlite3_column_text(st, 3), "succeeded");
    }
    done(st);
    if (n == BRIEF_BATCH || s == SQLITE_DONE) return n;
    for (int i = 0; i < n; i++) { /* a failed read: nothing is kept */
        free(rows[i].kind);
        free(rows[i].spec);
    }
    return -1;
}

/* Writes the briefs of rows (JSON null where none could be made) in one transaction; 0, or -1. */
static int brief_write(sqlite3 *db, brief_row *rows, int n)
{
    if (sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) return -1;
    int rc = 0;
    for (int i = 0; i < n && rc == 0; i++) {
        sqlite3_stmt *u = prep(db, "UPDATE jobs SET brief=?2 WHERE id=?1");
        if (!u || bind_text(u, 1, rows[i].id) != SQLITE_OK ||
            bind_text(u, 2, rows[i].brief ? rows[i].brief : "null") != SQLITE_OK ||
            step_done(db, u))
            rc = -1;
        done(u);
    }
    if (rc == 0 && sqlite3_exec(db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) rc = -1;
    if (!sqlite3_get_autocommit(db)) sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
    return rc;
}

static int sq_fill_briefs(store_brief_fn make)
{
    sqlite3 *db = conn();
    if (!db) return -1;
    brief_row rows[BRIEF_BATCH];
    int filled = 0, n;
    while ((n = brief_rows(db, memset(rows, 0, sizeof rows))) > 0) {
        for (int i = 0; i < n; i++) {
            char *summary = NULL, st[16];
            if (rows[i].succeeded) store_get_summary(rows[i].id, &summary, NULL, NULL, st);
            if (rows[i].kind && rows[i].spec)
                rows[i].brief = make(rows[i].kind, rows[i].spec, summary);
            free(summary);
        }
        int rc = brief_write(db, rows, n);
        for (int i = 0; i < n; i++) {
            free(rows[i].kind);
            free(rows[i].spec);
            free(rows[i].brief);
        }
        if (rc) break;
        filled += n;
    }
    /* n > 0: a batch could not be written; n < 0: not read */
    if (n != 0)
        gpd_log(GPD_LOG_ERROR, "filling in the briefs of older jobs: %s", sqlite3_errmsg(db));
    return n == 0 ? filled : -1;
}

static store_rc sq_fail(const char *id, const char *code, const char *message)
{
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    json_t *e = json_pack("{s:s, s:s}", "code", code, "message", message ? message : "");
    if (!e) /* a message that is not UTF-8: keep the code at least */
        e = json_pack("{s:s, s:s}", "code", code, "message", "(message not representable)");
    char *et = e ? json_dumps(e, JSON_COMPACT) : NULL;
    json_decref(e);
    if (!et) return STORE_ERROR;
    store_rc rc = update_running("UPDATE jobs SET status='failed', error=?2, finished_at=?3, "
                                 PROGRESS_ENDED " WHERE id=?1 AND status='running'",
                                 id, et, now, NULL);
    free(et);
    return rc;
}

static store_rc sq_requeue(const char *id)
{
    return update_running("UPDATE jobs SET status='queued', started_at=NULL, progress=NULL, "
                          "attempts=max(attempts-1, 0) WHERE id=?1 AND status='running'",
                          id, NULL, NULL, NULL);
}

static store_rc sq_cancel(const char *id, int *was_running, char status_out[16], char kind_out[64])
{
    *was_running = 0;
    status_out[0] = '\0';
    if (kind_out) kind_out[0] = '\0';
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    if (sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite cancel begin: %s", sqlite3_errmsg(db));
        return STORE_ERROR;
    }
    store_rc rc = STORE_ERROR;
    sqlite3_stmt *q = prep(db, "SELECT status, kind FROM jobs WHERE id=?1");
    sqlite3_stmt *u = prep(db, "UPDATE jobs SET status='cancelled', finished_at=?2, "
                               "error='{\"code\":\"cancelled\",\"message\":\"cancelled by a "
                               "DELETE request\"}', " PROGRESS_ENDED " WHERE id=?1");
    if (q && u) {
        bind_text(q, 1, id);
        int s = sqlite3_step(q);
        if (s == SQLITE_DONE) {
            rc = STORE_NOT_FOUND;
        } else if (s == SQLITE_ROW) {
            snprintf(status_out, 16, "%s", (const char *)sqlite3_column_text(q, 0));
            const unsigned char *k = sqlite3_column_text(q, 1);
            if (kind_out) snprintf(kind_out, 64, "%s", k ? (const char *)k : "");
            if (!strcmp(status_out, "queued") || !strcmp(status_out, "running")) {
                *was_running = !strcmp(status_out, "running");
                bind_text(u, 1, id);
                bind_text(u, 2, now);
                if (step_done(db, u) == 0) {
                    rc = STORE_OK;
                    snprintf(status_out, 16, "cancelled");
                }
            } else {
                rc = STORE_CONFLICT;
            }
        }
    }
    done(q);
    done(u);
    if (sqlite3_exec(db, rc == STORE_OK ? "COMMIT" : "ROLLBACK", NULL, NULL, NULL) != SQLITE_OK &&
        rc == STORE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite cancel commit: %s", sqlite3_errmsg(db));
        rc = STORE_ERROR;
    }
    return rc;
}

/* ------------------------------------------------------------------ operations */

static store_rc sq_purge(const char *id, char status_out[16])
{
    status_out[0] = '\0';
    sqlite3 *db = conn();
    if (!db) return STORE_ERROR;
    if (sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite purge begin: %s", sqlite3_errmsg(db));
        return STORE_ERROR;
    }
    sqlite3_stmt *st;
    store_rc rc = job_row(db, "SELECT status, seq FROM jobs WHERE id=?1", id, "purge", &st,
                          status_out);
    sqlite3_int64 seq = st ? sqlite3_column_int64(st, 1) : 0;
    done(st);
    if (rc == STORE_OK && !store_is_finished(status_out)) rc = STORE_CONFLICT;
    /* the job out of view and its values queued for store_free_purged: small rows only (the
     * row of a job stored before the results table holds its result: freed here, which
     * secure_delete=FAST keeps to the freelist's pages) */
    static const char *const del[] = {"INSERT OR IGNORE INTO purged(seq) VALUES (?1)",
                                      "DELETE FROM summaries WHERE seq=?1",
                                      "DELETE FROM jobs WHERE seq=?1"};
    for (size_t i = 0; rc == STORE_OK && i < sizeof del / sizeof *del; i++) {
        sqlite3_stmt *d = prep(db, del[i]);
        if (!d) {
            rc = STORE_ERROR;
            break;
        }
        sqlite3_bind_int64(d, 1, seq);
        if (step_done(db, d)) rc = STORE_ERROR;
        done(d);
    }
    if (rc == STORE_OK && sqlite3_exec(db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
        gpd_log(GPD_LOG_ERROR, "sqlite purge commit: %s", sqlite3_errmsg(db));
        store_note_write_error("purging a job", sqlite3_errmsg(db));
        rc = STORE_ERROR;
    }
    if (!sqlite3_get_autocommit(db) && sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL) != SQLITE_OK)
        gpd_log(GPD_LOG_ERROR, "sqlite purge rollback: %s", sqlite3_errmsg(db));
    return rc;
}

static int sq_purge_finished_before(const char *before, int max)
{
    sqlite3 *db = conn();
    if (!db || max <= 0) return db ? 0 : -1;
    /* the candidates first (the index on finished_at: queued and running jobs are not in it),
     * then each purged in its own transaction, so that the sweep never holds the store long */
    sqlite3_stmt *st = prep(db, "SELECT id FROM jobs WHERE finished_at < ?1 AND status IN "
                                "('succeeded', 'failed', 'cancelled') "
                                "ORDER BY finished_at LIMIT ?2");
    if (!st) return -1;
    char(*ids)[33] = calloc((size_t)max, sizeof *ids);
    if (!ids) {
        done(st);
        return -1;
    }
    bind_text(st, 1, before);
    sqlite3_bind_int(st, 2, max);
    int n = 0, s = SQLITE_DONE;
    while (n < max && (s = sqlite3_step(st)) == SQLITE_ROW) {
        const unsigned char *t = sqlite3_column_text(st, 0);
        if (t) snprintf(ids[n++], 33, "%s", (const char *)t);
    }
    if (n < max && s != SQLITE_DONE) {
        gpd_log(GPD_LOG_ERROR, "sqlite retention: %s", sqlite3_errmsg(db));
        done(st);
        free(ids);
        return -1;
    }
    done(st);
    int purged = 0;
    for (int i = 0; i < n; i++) {
        char status[16];
        /* a job may have gone meanwhile (a DELETE ?purge=1): not an error */
        if (sq_purge(ids[i], status) == STORE_OK) purged++;
    }
    free(ids);
    return purged;
}

/* The background work (store_free_purged, store_vacuum_step) waits this long for the write
 * lock: a writer holding it (a worker storing a result) goes first, and the caller tries again
 * later, instead of queueing behind it for the 5 s of every other write. */
#define BACKGROUND_BUSY_MS 200

/* Runs sql (a write of its own, ?1 = seq when it has one) on db with the short busy timeout:
 * the rows it changed, or -1 (logged at debug: a busy database is expected; not a failed
 * write for /v1/health, the work is tried again). */
static int background_write(sqlite3 *db, const char *sql, sqlite3_int64 seq)
{
    sqlite3_stmt *st = prep(db, sql);
    if (!st) return -1;
    if (sqlite3_bind_parameter_count(st) >= 1) sqlite3_bind_int64(st, 1, seq);
    sqlite3_busy_timeout(db, BACKGROUND_BUSY_MS);
    int s = sqlite3_step(st);
    while (s == SQLITE_ROW) s = sqlite3_step(st);
    sqlite3_busy_timeout(db, 5000);
    int n = s == SQLITE_DONE ? sqlite3_changes(db) : -1;
    if (n < 0) gpd_log(GPD_LOG_DEBUG, "sqlite background write: %s", sqlite3_errmsg(db));
    done(st);
    return n;
}

/* The rows of a purged job, freed one at a time (each its own transaction: a part of a value
 * is at most STORE_PART bytes, freed in milliseconds with secure_delete=FAST), the last part
 * first; then the job leaves purged. */
static const char *const FREE_SQL[] = {
    "DELETE FROM value_parts WHERE rowid = (SELECT rowid FROM value_parts WHERE seq=?1 "
    "ORDER BY what DESC, part DESC LIMIT 1)",
    "DELETE FROM exports WHERE seq=?1",
    "DELETE FROM results WHERE seq=?1",
    "DELETE FROM purged WHERE seq=?1",
};

static int sq_free_purged(void)
{
    sqlite3 *db = conn();
    if (!db) return -1;
    sqlite3_stmt *st = prep(db, "SELECT seq FROM purged ORDER BY seq LIMIT 1");
    if (!st) return -1;
    int s = sqlite3_step(st);
    sqlite3_int64 seq = s == SQLITE_ROW ? sqlite3_column_int64(st, 0) : 0;
    done(st);
    if (s == SQLITE_DONE) return 0;
    if (s != SQLITE_ROW) return -1;
    for (size_t i = 0; i < sizeof FREE_SQL / sizeof *FREE_SQL; i++) {
        int n = background_write(db, FREE_SQL[i], seq);
        if (n != 0) return n < 0 ? -1 : 1;
    }
    return 1; /* the last statement found no row: another connection removed it */
}

static int sq_vacuum_step(void)
{
    sqlite3 *db = conn();
    if (!db) return -1;
    if (!auto_vacuum || query_long(db, "PRAGMA freelist_count") <= 0) return 0;
    /* one step of STORE_VACUUM_STEP bytes of pages (2 MB: a few ms of the write lock, a
     * page moved from the end of the file written once to the WAL) */
    long page = query_long(db, "PRAGMA page_size");
    long pages = page > 0 && STORE_VACUUM_STEP / page > 0 ? STORE_VACUUM_STEP / page : 1;
    char sql[64];
    snprintf(sql, sizeof sql, "PRAGMA incremental_vacuum(%ld)", pages);
    sqlite3_busy_timeout(db, BACKGROUND_BUSY_MS);
    char *em = NULL;
    int rc = sqlite3_exec(db, sql, NULL, NULL, &em);
    sqlite3_busy_timeout(db, 5000);
    if (rc != SQLITE_OK) {
        gpd_log(GPD_LOG_DEBUG, "sqlite incremental vacuum: %s (tried again later)",
                em ? em : "?");
        sqlite3_free(em);
        return -1;
    }
    return query_long(db, "PRAGMA freelist_count") > 0;
}

/* The connection of a checkpoint that yields to jobs (store_checkpoint(1)), for
 * store_checkpoint_yield; guarded by ckpt_mu, so that it is never interrupted once done. */
static pthread_mutex_t ckpt_mu = PTHREAD_MUTEX_INITIALIZER;
static sqlite3 *ckpt_db = NULL;

static void sq_checkpoint_yield(void)
{
    pthread_mutex_lock(&ckpt_mu);
    if (ckpt_db) sqlite3_interrupt(ckpt_db);
    pthread_mutex_unlock(&ckpt_mu);
}

/* PASSIVE first: it copies the WAL into the database (after a large result: hundreds of MB,
 * seconds) taking no lock that a writer or a reader waits for; with may_yield a claim
 * interrupts it (SQLite checks the interrupt in its copy loop; what was copied is copied
 * again next time). Then TRUNCATE: the WAL goes back to nothing and the file to its pages in
 * use; it needs the write lock and every reader on the newest snapshot, so with no busy
 * handler a writer at that moment or a download in progress makes it answer SQLITE_BUSY at
 * once instead of waiting; what it still copies is only what was committed since the PASSIVE
 * pass. */
static int checkpoint_on(sqlite3 *db, int may_yield)
{
    if (may_yield) {
        pthread_mutex_lock(&ckpt_mu);
        ckpt_db = db;
        pthread_mutex_unlock(&ckpt_mu);
    }
    int rc = sqlite3_wal_checkpoint_v2(db, "main", SQLITE_CHECKPOINT_PASSIVE, NULL, NULL);
    if (may_yield) {
        pthread_mutex_lock(&ckpt_mu);
        ckpt_db = NULL;
        pthread_mutex_unlock(&ckpt_mu);
        /* an interrupt that came after the copy would stop this connection's next statement:
         * a statement started with none active clears it */
        sqlite3_exec(db, "SELECT 1", NULL, NULL, NULL);
    }
    if (rc == SQLITE_INTERRUPT) return 2;
    if (rc != SQLITE_OK && rc != SQLITE_BUSY && rc != SQLITE_LOCKED)
        gpd_log(GPD_LOG_WARN, "sqlite passive checkpoint: %s", sqlite3_errmsg(db));
    sqlite3_busy_timeout(db, 0);
    rc = sqlite3_wal_checkpoint_v2(db, "main", SQLITE_CHECKPOINT_TRUNCATE, NULL, NULL);
    sqlite3_busy_timeout(db, 5000);
    if (rc == SQLITE_OK) return 0;
    if (rc == SQLITE_BUSY || rc == SQLITE_LOCKED) return 1;
    gpd_log(GPD_LOG_WARN, "sqlite checkpoint: %s", sqlite3_errmsg(db));
    return -1;
}

static int sq_checkpoint(int may_yield)
{
    sqlite3 *db = conn();
    return db ? checkpoint_on(db, may_yield) : -1;
}

static int sq_count_by_kind(void (*fn)(void *user, const char *kind, const char *status, long n),
                        void *user)
{
    sqlite3 *db = conn();
    if (!db) return -1;
    sqlite3_stmt *st = prep(db, "SELECT kind, status, count(*) FROM jobs GROUP BY kind, status");
    if (!st) return -1;
    int s;
    while ((s = sqlite3_step(st)) == SQLITE_ROW) {
        const unsigned char *k = sqlite3_column_text(st, 0), *t = sqlite3_column_text(st, 1);
        if (k && t) fn(user, (const char *)k, (const char *)t, (long)sqlite3_column_int64(st, 2));
    }
    if (s != SQLITE_DONE) gpd_log(GPD_LOG_ERROR, "sqlite count by kind: %s", sqlite3_errmsg(db));
    done(st);
    return s == SQLITE_DONE ? 0 : -1;
}

static int sq_size(long long *bytes)
{
    *bytes = 0;
    sqlite3 *db = conn();
    if (!db) return -1;
    sqlite3_stmt *pc = prep(db, "PRAGMA page_count"), *ps = prep(db, "PRAGMA page_size");
    long long pages = -1, size = -1;
    if (pc && sqlite3_step(pc) == SQLITE_ROW) pages = sqlite3_column_int64(pc, 0);
    if (ps && sqlite3_step(ps) == SQLITE_ROW) size = sqlite3_column_int64(ps, 0);
    done(pc);
    done(ps);
    if (pages < 0 || size < 0) return -1;
    *bytes = pages * size;
    const char *file = sqlite3_db_filename(db, "main");
    char wal[PATH_MAX + 8];
    struct stat sb;
    if (file && snprintf(wal, sizeof wal, "%s-wal", file) < (int)sizeof wal &&
        stat(wal, &sb) == 0)
        *bytes += (long long)sb.st_size;
    return 0;
}

/* the database's directory: a worker's temporary result file goes on the same disk */
static char *sq_spill_dir(void)
{
    char *dir = path_copy();
    char *slash = dir ? strrchr(dir, '/') : NULL;
    if (slash == dir && dir) /* "/x.db" */
        dir[1] = 0;
    else if (slash)
        *slash = 0;
    else if (dir) {
        free(dir);
        dir = strdup(".");
    }
    return dir;
}

const store_backend store_sqlite = {
    .name = "sqlite",
    .open = sq_open,
    .close = sq_close,
    .thread_done = sq_thread_done,
    .recover = sq_recover,
    .insert = sq_insert,
    .fill_briefs = sq_fill_briefs,
    .get_job = sq_get_job,
    .get_text = sq_get_text,
    .list = sq_list,
    .counts = sq_counts,
    .counts_within = sq_counts_within,
    .claim = sq_claim,
    .progress = sq_progress,
    .succeed = sq_succeed,
    .spill_dir = sq_spill_dir,
    .fail = sq_fail,
    .requeue = sq_requeue,
    .cancel = sq_cancel,
    .purge = sq_purge,
    .purge_finished_before = sq_purge_finished_before,
    .free_purged = sq_free_purged,
    .vacuum_step = sq_vacuum_step,
    .checkpoint = sq_checkpoint,
    .checkpoint_yield = sq_checkpoint_yield,
    .count_by_kind = sq_count_by_kind,
    .size = sq_size,
    .stream_open = sq_stream_open,
    .stream_size = sq_stream_size,
    .stream_read = sq_stream_read,
    .stream_close = sq_stream_close,
    .stored_summary = sq_stored_summary,
};
