/* store_pg.c -- the PostgreSQL back end of the job store (store.h, "PostgreSQL"; the type
 * object in store_impl.h): many daemons, on any hosts, share one queue.
 *
 * Tables: those of SQLite with the same columns and meaning, plus jobs.owner (the daemon that
 * runs or ran the job), jobs.lease_until (server time; NULL unless running) and
 * jobs.results_written (how many times a result was stored: 1 for every succeeded job, the
 * check of "written exactly once"). Large values (jobs.result, exports.pack and the parts of
 * larger ones, value_parts.data: store.h "Values in parts") are bytea with
 * STORAGE EXTERNAL (out of line, uncompressed), so that substring(v from off for n) reads only
 * the TOAST chunks of the range: that is how a download streams a result or pack.
 *
 * Ownership: every write that ends or updates a running job is conditioned on
 * status='running' AND owner=<this daemon>; the claim is the only way to become the owner.
 * The store thread (one per daemon, its own connection) renews lease_until of this daemon's
 * running jobs every lease/3 s, LISTENs on gp_cancel for cancels made by other daemons, and
 * watches the server (below).
 *
 * Purge: a purged job's row stays, status 'purged', out of every read, until the maintenance
 * thread deletes its rows one at a time (store_free_purged); its seq waits in purged.
 *
 * Threads: one connection per thread (a pthread key, opened lazily; statements prepared once
 * per connection, by the address of their SQL literal, as store_sqlite.c caches them); a
 * download has a private connection holding a REPEATABLE READ transaction (its snapshot: a
 * purge meanwhile does not change what it reads), made only while the daemon holds fewer than
 * store_max_connections. A connection that breaks is dropped and the next call opens a new one.
 * No user data is ever formatted into SQL.
 *
 * Calls never block on the server: connections are made with PQconnectStartParams and run in
 * non-blocking mode, and every call waits in poll() with a bound (PG_WAIT_S without a word from
 * the server, past the server's own statement_timeout; a liveness probe's own, shorter one).
 * Silence is not proof of a stalled server (a statement may wait for a row lock that another
 * transaction holds for long): a call silent for PG_SUSPECT_S asks the store thread to probe,
 * and only that probe, a statement that never waits for a lock, marks the server unreachable
 * when it gets no answer in PG_PROBE_WAIT_S. Every call then ends (its connection dropped) and
 * calls fail at once until the store thread finds the server answering again. A stopped
 * server (SIGSTOP, a lost network) thus costs a request a few seconds at most, and /v1/health
 * half a second.
 */
#include "store/store_impl.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#include <libpq-fe.h>

/* ------------------------------------------------------------------ state */

static char *conninfo = NULL;    /* the URL; set by pg_open, freed by pg_close */
static char owner[160];          /* this daemon's id: host/boot/pid/random */
static size_t owner_host_len;    /* the length of its "host/boot/" prefix */
static long long max_value = 0;  /* the largest value stored (PostgreSQL: 1 GB a field) */

#define PG_STMT_CACHE 48
#define PG_MAX_VALUE 1000000000LL /* under PostgreSQL's 1 GB limit of one field */

/* How long a call waits without a word from the server before it gives up: past the server's
 * statement_timeout (60 s), so that a statement that runs long ends with the server's own
 * error; a stalled server ends every call sooner, through the probe (PG_SUSPECT_S). */
#define PG_WAIT_S 65.0
#define PG_CONNECT_WAIT_S 5.0
#define PG_SUSPECT_S 1.0     /* a call silent this long asks the store thread to probe */
#define PG_PROBE_WAIT_S 3.0  /* the probe's bound: no answer marks the server unreachable */
#define PG_PROBE_EVERY_S 0.5 /* the probes while the server does not answer */
/* libpq's and the server's own bounds, set on every connection (before the URL's, which may
 * change them): keepalives find a server gone from the network in about 25 s, the TCP user
 * timeout a send that is never acknowledged; statement_timeout ends a runaway statement;
 * idle_in_transaction_session_timeout ends the transaction (and the snapshot) of a download
 * whose reader stopped reading (STORE_STREAM_IDLE_S) */
#define PG_STATEMENT_TIMEOUT_MS 60000
static const char *const CONN_KEYS[] = {
    "connect_timeout", "keepalives", "keepalives_idle", "keepalives_interval",
    "keepalives_count", "tcp_user_timeout", "client_encoding", "application_name", "options",
    "dbname", NULL};
static char conn_options[160]; /* the server's settings (set by pg_open) */
static const char *conn_vals[] = {
    "5", "1", "10", "5", "3", "20000", "UTF8", "grainpackd", conn_options,
    NULL /* the URL, expanded: set by pg_open */, NULL};
#define CONN_URL_SLOT (sizeof CONN_KEYS / sizeof *CONN_KEYS - 2)

/* The server's settings of every connection. A testing hook (environment, never needed in
 * production) shortens the idle transaction's bound: GRAINPACK_TEST_PG_IDLE_S, seconds. */
static void conn_options_init(void)
{
    const char *t = getenv("GRAINPACK_TEST_PG_IDLE_S");
    long idle = t && atol(t) > 0 ? atol(t) : STORE_STREAM_IDLE_S;
    snprintf(conn_options, sizeof conn_options,
             "-c statement_timeout=%d -c idle_in_transaction_session_timeout=%ld",
             PG_STATEMENT_TIMEOUT_MS, idle * 1000);
}

/* The server's state as this daemon sees it: 0 while it does not answer (a call waited past
 * its bound, or the store thread's probe did); calls then fail at once with nothing sent, and
 * the store thread probes it every PG_PROBE_EVERY_S until it answers. Atomic. */
static int reachable = 1;
static double down_since = 0; /* monotonic; written by whoever marks the server down */
/* the connections this daemon holds (threads' and downloads'): atomic */
static int open_conns = 0;

/* Per thread: the bound of this thread's calls (0: PG_WAIT_S); stalled: the last call got no
 * answer, or found the server marked unreachable; probing: the store thread's own calls,
 * which are made whatever the server's state, and whose silence marks it unreachable. */
static __thread double tl_wait_s = 0;
static __thread int tl_stalled = 0, tl_probing = 0;
/* Per thread: when set (monotonic), no wait goes past it: a liveness probe's whole budget,
 * connecting and asking together. */
static __thread double tl_until = 0;

static int lease_pipe[2] = {-1, -1}; /* to the store thread: 'x' stop, 'p' probe now */

static double call_wait(void) { return tl_wait_s > 0 ? tl_wait_s : PG_WAIT_S; }

/* 1 when calls must fail at once: the server is marked unreachable (the probe excepted) */
static int db_closed(void)
{
    return !tl_probing && !__atomic_load_n(&reachable, __ATOMIC_ACQUIRE);
}

static void wake_store_thread(char what)
{
    if (lease_pipe[1] < 0) return;
    ssize_t w = write(lease_pipe[1], &what, 1); /* non-blocking: a full pipe has one already */
    (void)w;
}

static void mark_down(const char *why)
{
    if (__atomic_exchange_n(&reachable, 0, __ATOMIC_ACQ_REL)) {
        double now = gpd_monotonic_s();
        __atomic_store(&down_since, &now, __ATOMIC_RELEASE);
        gpd_log(GPD_LOG_WARN, "postgresql: the server does not answer (%s); database calls fail "
                              "at once until it does (probed every %.1f s)",
                why, PG_PROBE_EVERY_S);
    }
    wake_store_thread('p');
}

static void mark_up(void)
{
    double since;
    __atomic_load(&down_since, &since, __ATOMIC_ACQUIRE);
    if (!__atomic_exchange_n(&reachable, 1, __ATOMIC_ACQ_REL))
        gpd_log(GPD_LOG_WARN, "postgresql: the server answers again, after %.1f s",
                gpd_monotonic_s() - since);
}

/* A call got no answer: past its bound (wait, seconds), or the server was marked unreachable
 * meanwhile. The store thread's own silence marks the server unreachable; another thread's
 * only asks it for a probe. */
static void stalled(const char *what, double wait)
{
    tl_stalled = 1;
    if (db_closed()) return;
    char why[160];
    snprintf(why, sizeof why, "%.40s: no answer within %.1f s", what, wait);
    if (tl_probing) {
        mark_down(why);
        return;
    }
    gpd_log(GPD_LOG_DEBUG, "postgresql %s", why);
    wake_store_thread('p');
}

/* Waits until pg's socket is ready for events (POLLIN, POLLOUT) or the deadline (and the
 * thread's tl_until); asks for a probe after PG_SUSPECT_S of it, and gives up early when the
 * server is marked unreachable meanwhile. The events seen, or -1. */
static int wait_socket(PGconn *pg, short events, double deadline)
{
    if (tl_until > 0 && tl_until < deadline) deadline = tl_until;
    double suspect = gpd_monotonic_s() + PG_SUSPECT_S;
    for (;;) {
        int fd = PQsocket(pg);
        double now = gpd_monotonic_s(), left = deadline - now;
        if (fd < 0 || left <= 0 || db_closed()) return -1;
        if (!tl_probing && suspect > 0 && now >= suspect) {
            wake_store_thread('p');
            suspect = 0;
        }
        struct pollfd p = {fd, events, 0};
        int n = poll(&p, 1, left > 0.1 ? 100 : (int)(left * 1000) + 1);
        if (n > 0) return p.revents;
        if (n < 0 && errno != EINTR) return -1;
    }
}

/* Takes a connection slot: a download's only while fewer than store_max_connections are
 * held. 0, or -1. */
static int take_slot(int download)
{
    int n = __atomic_add_fetch(&open_conns, 1, __ATOMIC_ACQ_REL);
    if (!download || n <= store_max_connections()) return 0;
    __atomic_sub_fetch(&open_conns, 1, __ATOMIC_ACQ_REL);
    return -1;
}

static void disconnect(PGconn *pg)
{
    if (!pg) return;
    PQfinish(pg);
    __atomic_sub_fetch(&open_conns, 1, __ATOMIC_ACQ_REL);
}

/* libpq's notices (a server's goodbye among them) go to the log, not to stderr */
static void notice_to_log(void *arg, const char *msg)
{
    (void)arg;
    size_t n = strlen(msg);
    while (n && msg[n - 1] == '\n') n--;
    gpd_log(GPD_LOG_DEBUG, "postgresql notice: %.*s", (int)n, msg);
}

/* A new connection to the server, made without blocking past the call's bound (NULL, logged,
 * when it fails; at once while the server is marked unreachable). Its slot is taken by the
 * caller (take_slot) and given back by disconnect. */
static PGconn *connect_raw(void)
{
    if (!conninfo || db_closed()) {
        tl_stalled = 1;
        return NULL;
    }
    PGconn *pg = PQconnectStartParams(CONN_KEYS, conn_vals, 1);
    double wait = tl_wait_s > 0 && tl_wait_s < PG_CONNECT_WAIT_S ? tl_wait_s : PG_CONNECT_WAIT_S;
    double deadline = gpd_monotonic_s() + wait;
    PostgresPollingStatusType st = pg && PQstatus(pg) != CONNECTION_BAD ? PGRES_POLLING_WRITING
                                                                         : PGRES_POLLING_FAILED;
    while (st == PGRES_POLLING_READING || st == PGRES_POLLING_WRITING) {
        if (wait_socket(pg, st == PGRES_POLLING_READING ? POLLIN : POLLOUT, deadline) < 0) {
            stalled("connect", wait);
            PQfinish(pg);
            return NULL;
        }
        st = PQconnectPoll(pg);
    }
    if (st != PGRES_POLLING_OK || PQsetnonblocking(pg, 1)) {
        /* while the server is marked down its probe fails every PG_PROBE_EVERY_S: mark_down
         * said it once */
        int quiet = tl_until > 0 || !__atomic_load_n(&reachable, __ATOMIC_ACQUIRE);
        gpd_log(quiet ? GPD_LOG_DEBUG : GPD_LOG_ERROR, "postgresql connect: %s",
                pg ? PQerrorMessage(pg) : "out of memory");
        if (!tl_probing) wake_store_thread('p'); /* refused: is the server gone? */
        tl_stalled = 1; /* no server to talk to: unreachable for /v1/health */
        PQfinish(pg);
        return NULL;
    }
    PQsetNoticeProcessor(pg, notice_to_log, NULL);
    return pg;
}

/* connect_raw within a slot: a thread's (always) or a download's (within the limit). */
static PGconn *connect_new(int download)
{
    if (take_slot(download)) return NULL;
    PGconn *pg = connect_raw();
    if (!pg) __atomic_sub_fetch(&open_conns, 1, __ATOMIC_ACQ_REL);
    return pg;
}

static int ok_result(const PGresult *r)
{
    ExecStatusType s = PQresultStatus(r);
    return s == PGRES_COMMAND_OK || s == PGRES_TUPLES_OK;
}

/* Waits for the result of what a PQsend* call (sent: its return) put on pg: sends what libpq
 * holds, then reads until the result is whole, each wait bounded (call_wait(): the bound is
 * renewed whenever the server is heard). The result (of several statements: the first
 * failed one, else the last), or NULL: nothing sent, or no answer (stalled()); the connection
 * is then unusable (a command is still in progress on it). */
static PGresult *await_answer(PGconn *pg, int sent, const char *what)
{
    if (!sent) return NULL;
    double wait = call_wait(), deadline = gpd_monotonic_s() + wait;
    int f;
    while ((f = PQflush(pg)) == 1) {
        int ev = wait_socket(pg, POLLOUT | POLLIN, deadline);
        if (ev < 0) {
            stalled(what, wait);
            return NULL;
        }
        if ((ev & POLLIN) && !PQconsumeInput(pg)) return NULL;
        deadline = gpd_monotonic_s() + wait;
    }
    if (f < 0) return NULL;
    PGresult *res = NULL;
    for (;;) {
        while (PQisBusy(pg)) {
            if (wait_socket(pg, POLLIN, deadline) < 0) {
                stalled(what, wait);
                PQclear(res);
                return NULL;
            }
            if (!PQconsumeInput(pg)) {
                PQclear(res);
                return NULL;
            }
            deadline = gpd_monotonic_s() + wait;
        }
        PGresult *r = PQgetResult(pg);
        if (!r) break;
        if (res && !ok_result(res)) { /* the first failure stays */
            PQclear(r);
            continue;
        }
        PQclear(res);
        res = r;
    }
    return res;
}

/* await_answer, and a connection the server closed under the call (a restart, a crash)
 * counts as a server that did not answer: the caller's thread says unreachable (503 and
 * Retry-After, not 500) and the store thread probes the server. */
static PGresult *await_result(PGconn *pg, int sent, const char *what)
{
    PGresult *r = await_answer(pg, sent, what);
    if ((!r || !ok_result(r)) && PQstatus(pg) == CONNECTION_BAD) {
        tl_stalled = 1;
        if (!tl_probing) wake_store_thread('p');
    }
    return r;
}

/* The text of one statement with parameters on pg (not prepared: the store thread's and
 * downloads' own connections), as await_result. */
static PGresult *exec_params(PGconn *pg, const char *sql, int n, const char *const *vals,
                             int binary)
{
    if (db_closed()) {
        tl_stalled = 1;
        return NULL;
    }
    return await_result(pg, PQsendQueryParams(pg, sql, n, NULL, vals, NULL, NULL, binary), sql);
}

typedef struct pg_conn {
    PGconn *pg;
    int n;
    const char *sql[PG_STMT_CACHE];
} pg_conn;

static void conn_destroy(void *p)
{
    pg_conn *c = p;
    if (!c) return;
    disconnect(c->pg);
    free(c);
}

static void close_handle(void *pg) { disconnect(pg); }
static void *open_handle(void) { return connect_new(0); }
static store_tls tls = {open_handle, close_handle, sizeof(pg_conn), conn_destroy, 0, 0};

/* An idle connection with something to read: nothing was asked on it, so it is the server's
 * goodbye (a restart, pg_terminate_backend) or the end of the stream; the thread's
 * connections do not LISTEN, so no notification comes this way. */
static int closed_by_server(PGconn *pg)
{
    if (PQstatus(pg) != CONNECTION_OK) return 1;
    if (PQtransactionStatus(pg) != PQTRANS_IDLE) return 0; /* mid-transaction: never replaced */
    struct pollfd p = {PQsocket(pg), POLLIN, 0};
    return p.fd < 0 || poll(&p, 1, 0) != 0;
}

/* This thread's connection; NULL (at once) while the server is marked unreachable. One the
 * server has closed while it was idle is replaced before anything is sent on it, so that a
 * server restarted between two calls costs a new connection, not a failed call. */
static pg_conn *conn(void)
{
    if (db_closed()) {
        tl_stalled = 1;
        return NULL;
    }
    pg_conn *c = store_tls_get(&tls);
    if (c && closed_by_server(c->pg)) {
        gpd_log(GPD_LOG_DEBUG, "postgresql: an idle connection was closed by the server; a new "
                               "one");
        store_tls_drop(&tls);
        c = store_tls_get(&tls);
    }
    return c;
}

/* After a failure: a connection that broke, or that still has a command in progress (a call
 * that got no answer), is dropped (the next call makes a new one). */
static void check_broken(pg_conn *c)
{
    PGTransactionStatusType t = PQtransactionStatus(c->pg);
    if (PQstatus(c->pg) == CONNECTION_OK && t != PQTRANS_ACTIVE && t != PQTRANS_UNKNOWN) return;
    store_tls_drop(&tls);
}

/* The name of sql's prepared statement on c ("s<i>"), preparing it the first time; NULL when
 * it cannot be (logged). */
static int prepared(pg_conn *c, const char *sql, char name[16])
{
    for (int i = 0; i < c->n; i++)
        if (c->sql[i] == sql) {
            snprintf(name, 16, "s%d", i);
            return 0;
        }
    if (c->n == PG_STMT_CACHE) return -1; /* never: the SQL literals here are fewer */
    snprintf(name, 16, "s%d", c->n);
    PGresult *r = await_result(c->pg, PQsendPrepare(c->pg, name, sql, 0, NULL), "prepare");
    int ok = r && ok_result(r);
    if (!ok && !tl_stalled)
        gpd_log(GPD_LOG_ERROR, "postgresql prepare: %s(%s)", PQerrorMessage(c->pg), sql);
    PQclear(r);
    if (!ok) return -1;
    c->sql[c->n++] = sql;
    return 0;
}

/* A failed call on c: logged and, for a write the server refused, noted for /v1/health (not
 * when the server did not answer: /v1/health says unreachable while it does not). */
static void call_failed(pg_conn *c, PGresult *r, const char *sql, const char *what)
{
    const char *em = r ? PQresultErrorMessage(r) : NULL;
    if (!em || !*em) em = PQerrorMessage(c->pg);
    if (tl_stalled) {
        gpd_log(GPD_LOG_DEBUG, "postgresql: no answer (%.60s...)", sql);
    } else {
        gpd_log(GPD_LOG_ERROR, "postgresql: %s(%.60s...)", em, sql);
        if (what) store_note_write_error(what, em);
    }
    check_broken(c);
}

/* Runs sql (a literal) with n parameters (vals; lens and fmts NULL = all text) on this
 * thread's connection; binary: results in binary (for bytea). The result, or NULL on a failure
 * (logged; a write's failure noted for /v1/health). */
static PGresult *run(const char *sql, int n, const char *const *vals, const int *lens,
                     const int *fmts, int binary)
{
    tl_stalled = 0;
    pg_conn *c = conn();
    if (!c) return NULL;
    char name[16];
    if (prepared(c, sql, name)) {
        check_broken(c);
        return NULL;
    }
    PGresult *r = await_result(
        c->pg, PQsendQueryPrepared(c->pg, name, n, vals, lens, fmts, binary), "a statement");
    if (r && ok_result(r)) return r;
    call_failed(c, r, sql, strncmp(sql, "SELECT", 6) ? "a job update" : NULL);
    PQclear(r);
    return NULL;
}

/* A statement without parameters or result (BEGIN, COMMIT, ROLLBACK); 0, or -1. */
static int simple(const char *sql)
{
    tl_stalled = 0;
    pg_conn *c = conn();
    if (!c) return -1;
    PGresult *r = await_result(c->pg, PQsendQuery(c->pg, sql), sql);
    int ok = r && ok_result(r);
    if (!ok) call_failed(c, r, sql, strcmp(sql, "ROLLBACK") ? sql : NULL);
    PQclear(r);
    return ok ? 0 : -1;
}

/* Ends a transaction: COMMIT when rc is STORE_OK (a failed commit makes it STORE_ERROR), else
 * ROLLBACK; returns the outcome. */
static store_rc end_tx(store_rc rc)
{
    if (rc == STORE_OK) return simple("COMMIT") ? STORE_ERROR : STORE_OK;
    int stall = tl_stalled;
    pg_conn *c = store_tls_peek(&tls);
    if (c && PQtransactionStatus(c->pg) != PQTRANS_IDLE) simple("ROLLBACK");
    tl_stalled |= stall;
    return rc;
}

/* The rows a write changed (PQcmdTuples), or -1. */
static long changed(PGresult *r)
{
    return r ? strtol(PQcmdTuples(r), NULL, 10) : -1;
}

/* ------------------------------------------------------------------ schema, owner */

/* Two daemons starting at once must not both create the tables: the DDL runs under an
 * advisory lock (one multi-statement query is one transaction). */
static const char *SCHEMA_SQL =
    "SELECT pg_advisory_xact_lock(7401861);"
    "CREATE TABLE IF NOT EXISTS jobs("
    " seq BIGSERIAL PRIMARY KEY,"
    STORE_JOBS_COMMON_COLUMNS
    " result BYTEA,"
    " attempts INTEGER NOT NULL DEFAULT 0,"
    " brief TEXT,"
    " owner TEXT,"
    " lease_until TIMESTAMPTZ,"
    " results_written INTEGER NOT NULL DEFAULT 0);"
    "ALTER TABLE jobs ALTER COLUMN result SET STORAGE EXTERNAL;"
    "CREATE INDEX IF NOT EXISTS jobs_status_seq ON jobs(status, seq);"
    "CREATE INDEX IF NOT EXISTS jobs_kind_status ON jobs(kind, status);"
    "CREATE INDEX IF NOT EXISTS jobs_finished_at ON jobs(finished_at)"
    " WHERE finished_at IS NOT NULL;"
    "CREATE INDEX IF NOT EXISTS jobs_owner ON jobs(owner) WHERE status = 'running';"
    "CREATE TABLE IF NOT EXISTS exports(seq BIGINT PRIMARY KEY, pack BYTEA NOT NULL);"
    "ALTER TABLE exports ALTER COLUMN pack SET STORAGE EXTERNAL;"
    "CREATE TABLE IF NOT EXISTS value_parts(seq BIGINT NOT NULL, what SMALLINT NOT NULL,"
    " part INTEGER NOT NULL, data BYTEA NOT NULL, PRIMARY KEY(seq, what, part));"
    "ALTER TABLE value_parts ALTER COLUMN data SET STORAGE EXTERNAL;"
    "CREATE TABLE IF NOT EXISTS summaries(seq BIGINT PRIMARY KEY, summary TEXT NOT NULL,"
    " arrays TEXT);"
    /* jobs purged (status 'purged') whose rows are still to be deleted (store_free_purged) */
    "CREATE TABLE IF NOT EXISTS purged(seq BIGINT PRIMARY KEY);";

/* host/boot/pid/random: the host and its boot tell whether a dead pid names a dead daemon
 * (store_recover); the random part keeps ids apart across pid reuse. */
static int make_owner(void)
{
    char host[64] = "host", boot[9] = "noboot", rnd[33];
    gethostname(host, sizeof host - 1);
    host[sizeof host - 1] = 0;
    for (char *p = host; *p; p++)
        if (*p == '/') *p = '_';
    FILE *f = fopen("/proc/sys/kernel/random/boot_id", "r");
    if (f) {
        if (fscanf(f, "%8s", boot) != 1) snprintf(boot, sizeof boot, "noboot");
        fclose(f);
    }
    if (gpd_new_id(rnd)) return -1;
    rnd[12] = 0;
    snprintf(owner, sizeof owner, "%s/%s/", host, boot);
    owner_host_len = strlen(owner);
    snprintf(owner + owner_host_len, sizeof owner - owner_host_len, "%ld/%s", (long)getpid(), rnd);
    return 0;
}

/* ------------------------------------------------------------------ the store thread */

static pthread_t lease_thread;
static int lease_running = 0;
static int lease_quit = 0; /* atomic: the thread stops (with a byte on the pipe to wake it) */

/* Renews this daemon's leases on pg (the store thread's connection); 0, or -1. */
static int renew(PGconn *pg)
{
    char secs[32];
    snprintf(secs, sizeof secs, "%.3f", store_lease());
    const char *v[2] = {owner, secs};
    /* SKIP LOCKED: the renewal is also the probe of the server, and must never wait for a
     * lock (a worker storing a large result holds its job's row for seconds; that job's lease
     * is renewed at the next turn, or ended by its success) */
    PGresult *r = exec_params(pg, "UPDATE jobs SET lease_until = now() + $2::float8 * "
                                  "interval '1 second' WHERE seq IN (SELECT seq FROM jobs "
                                  "WHERE status='running' AND owner=$1 FOR UPDATE SKIP LOCKED)",
                              2, v, 0);
    int ok = r && ok_result(r);
    if (!ok && !tl_stalled)
        gpd_log(GPD_LOG_WARN, "postgresql lease renewal: %s", PQerrorMessage(pg));
    PQclear(r);
    return ok ? 0 : -1;
}

/* Hands every notification on pg (a cancelled job's id) to the cancel hook. */
static void drain_notifies(PGconn *pg)
{
    PGnotify *n;
    PQconsumeInput(pg);
    while ((n = PQnotifies(pg))) {
        gpd_log(GPD_LOG_DEBUG, "cancel of job %s seen", n->extra);
        store_cancel_seen(n->extra);
        PQfreemem(n);
    }
}

static PGconn *listener_open(void)
{
    PGconn *pg = connect_new(0);
    if (!pg) return NULL;
    PGresult *r = exec_params(pg, "LISTEN gp_cancel", 0, NULL, 0);
    int ok = r && ok_result(r);
    PQclear(r);
    if (!ok) {
        if (!tl_stalled) gpd_log(GPD_LOG_WARN, "postgresql LISTEN: %s", PQerrorMessage(pg));
        disconnect(pg);
        return NULL;
    }
    return pg;
}

/* Reads what callers wrote on the pipe: 1 when a probe was asked for. */
static int read_pipe(void)
{
    char buf[64];
    int asked = 0;
    ssize_t n;
    while ((n = read(lease_pipe[0], buf, sizeof buf)) > 0)
        asked |= memchr(buf, 'p', (size_t)n) != NULL;
    return asked;
}

/* One turn's database work on *pg: renew when due or asked (a probe), a new connection first
 * when there is none (while the server is marked unreachable, at most every
 * PG_PROBE_EVERY_S). Updates the times of the next renewal and probe. */
static void lease_turn(PGconn **pg, int asked, double *next_renew, double *next_probe)
{
    double now = gpd_monotonic_s();
    int up = __atomic_load_n(&reachable, __ATOMIC_ACQUIRE);
    if (!up && now < *next_probe) return;
    if (!up) *next_probe = now + PG_PROBE_EVERY_S;
    if (!*pg && !(*pg = listener_open())) {
        if (up) mark_down("no connection can be made");
        return;
    }
    if (up && !asked && now < *next_renew) return;
    if (renew(*pg) == 0) {
        mark_up();
        *next_renew = now + store_lease() / 3.0;
        drain_notifies(*pg);
        return;
    }
    disconnect(*pg); /* made again at the next turn */
    *pg = NULL;
}

/* The store thread: every lease/3 s it renews this daemon's leases, and between it waits for
 * notifications (LISTEN gp_cancel), a request to probe the server or the stop. It is the
 * server's watchman too: its renewal, and a probe a caller asks for (a /v1/health that got no
 * answer in time), wait at most PG_PROBE_WAIT_S, and no answer marks the server unreachable;
 * while it is, the thread tries a new connection every PG_PROBE_EVERY_S, and the first that
 * answers marks it reachable again. A lost connection is made again at the next turn (jobs
 * keep running; their leases may lapse meanwhile, in which case another daemon takes them
 * over and their writes here are refused). */
static void *lease_main(void *arg)
{
    (void)arg;
    tl_probing = 1;
    tl_wait_s = PG_PROBE_WAIT_S;
    PGconn *pg = NULL;
    double next_renew = 0, next_probe = 0;
    int asked = 0;
    while (!__atomic_load_n(&lease_quit, __ATOMIC_ACQUIRE)) {
        lease_turn(&pg, asked, &next_renew, &next_probe);
        asked = 0;
        double now = gpd_monotonic_s();
        double until = !pg ? now + 1.0 : next_renew;
        if (!__atomic_load_n(&reachable, __ATOMIC_ACQUIRE)) until = next_probe;
        struct pollfd p[2] = {{lease_pipe[0], POLLIN, 0}, {pg ? PQsocket(pg) : -1, POLLIN, 0}};
        int ms = until > now ? (int)((until - now) * 1000) + 1 : 0;
        if (poll(p, 2, ms) < 0 && errno != EINTR) break;
        if (p[0].revents) asked = read_pipe();
        if (pg && p[1].revents) drain_notifies(pg);
    }
    disconnect(pg);
    return NULL;
}

static int lease_start(void)
{
    if (pipe(lease_pipe)) return -1;
    /* callers never wait on it (a full pipe already holds a probe request) */
    fcntl(lease_pipe[0], F_SETFL, O_NONBLOCK);
    fcntl(lease_pipe[1], F_SETFL, O_NONBLOCK);
    __atomic_store_n(&lease_quit, 0, __ATOMIC_RELEASE);
    if (pthread_create(&lease_thread, NULL, lease_main, NULL)) {
        close(lease_pipe[0]);
        close(lease_pipe[1]);
        lease_pipe[0] = lease_pipe[1] = -1;
        return -1;
    }
    lease_running = 1;
    return 0;
}

static void lease_stop(void)
{
    if (!lease_running) return;
    __atomic_store_n(&lease_quit, 1, __ATOMIC_RELEASE);
    wake_store_thread('x');
    pthread_join(lease_thread, NULL);
    int r = lease_pipe[0], w = lease_pipe[1];
    lease_pipe[0] = lease_pipe[1] = -1;
    close(r);
    close(w);
    lease_running = 0;
}

/* ------------------------------------------------------------------ open, close */

static void pg_thread_done(void)
{
    store_tls_drop(&tls);
}

static int pg_open(const char *url)
{
    if (store_tls_init(&tls)) return -1;
    const char *lim = getenv("GRAINPACK_TEST_SQLITE_MAX_LENGTH"); /* the same testing hook */
    max_value = lim && atoll(lim) > 0 ? atoll(lim) : PG_MAX_VALUE;
    free(conninfo);
    conninfo = strdup(url);
    conn_vals[CONN_URL_SLOT] = conninfo;
    conn_options_init();
    __atomic_store_n(&reachable, 1, __ATOMIC_RELEASE);
    if (!conninfo || make_owner()) return -1;
    pg_conn *c = conn();
    if (!c) return -1;
    PGresult *r = await_result(c->pg, PQsendQuery(c->pg, SCHEMA_SQL), "the job tables");
    int ok = r && ok_result(r);
    if (!ok) gpd_log(GPD_LOG_ERROR, "cannot initialise the job tables: %s", PQerrorMessage(c->pg));
    PQclear(r);
    if (!ok || lease_start()) return -1;
    gpd_log(GPD_LOG_INFO, "job store on PostgreSQL, daemon id %s, lease %.1f s, at most %d "
            "connections", owner, store_lease(), store_max_connections());
    return 0;
}

static void pg_close(void)
{
    lease_stop();
    pg_thread_done();
    conn_vals[CONN_URL_SLOT] = NULL;
    free(conninfo);
    conninfo = NULL;
}

/* ------------------------------------------------------------------ rows */

static json_t *text_val(const PGresult *r, int row, int col)
{
    return PQgetisnull(r, row, col) ? json_null() : json_string(PQgetvalue(r, row, col));
}

static json_t *json_val(const PGresult *r, int row, int col)
{
    if (PQgetisnull(r, row, col)) return json_null();
    json_t *j = json_loads(PQgetvalue(r, row, col), JSON_DECODE_ANY, NULL);
    return j ? j : json_null();
}

#define JOB_COLS "id, kind, status, created_at, started_at, finished_at, progress, error, brief"
/* a purged job's row stays, status 'purged', until store_free_purged deletes it: no read sees
 * it (store.h, store_purge) */
#define VISIBLE "status <> 'purged'"

static json_t *job_from_row(const PGresult *r, int row)
{
    json_t *j = json_object();
    static const char *const names[] = {"id", "kind", "status", "created_at", "started_at",
                                        "finished_at"};
    for (int i = 0; i < 6; i++) json_object_set_new(j, names[i], text_val(r, row, i));
    json_object_set_new(j, "progress", store_progress_or_queued(json_val(r, row, 6)));
    json_object_set_new(j, "error", json_val(r, row, 7));
    json_object_set_new(j, "brief", json_val(r, row, 8));
    return j;
}

/* The progress of a job that ended without success: its last phase and fraction, eta_s null */
#define PROGRESS_ENDED                                                                         \
    "progress = CASE WHEN progress IS NULL THEN NULL "                                         \
    "ELSE jsonb_set(progress::jsonb, '{eta_s}', 'null'::jsonb)::text END"

/* a text copy of a column (binary or text format: text columns are their bytes either way) */
static char *dup_val(const PGresult *r, int row, int col)
{
    if (PQgetisnull(r, row, col)) return NULL;
    int n = PQgetlength(r, row, col);
    char *t = malloc((size_t)n + 1);
    if (!t) return NULL;
    memcpy(t, PQgetvalue(r, row, col), (size_t)n);
    t[n] = 0;
    return t;
}

/* ------------------------------------------------------------------ recovery */

/* 1 when the daemon whose owner id is o (of this host and boot) is alive */
static int owner_alive(const char *o)
{
    long pid = strtol(o + owner_host_len, NULL, 10);
    if (pid <= 0) return 1; /* not ours to judge */
    return kill((pid_t)pid, 0) == 0 || errno == EPERM;
}

/* The restart rule for one interrupted job of a dead daemon of this host: failed when it was
 * claimed STORE_MAX_ATTEMPTS times, else queued again. Conditioned on its owner, so that a
 * job another daemon took over meanwhile is left alone. 1 failed, 0 requeued, -1 neither. */
static int recover_one(const char *id, const char *o, int attempts, const char *now)
{
    const char *v[4] = {id, o, now, store_interrupted_error()};
    PGresult *r;
    if (attempts >= STORE_MAX_ATTEMPTS)
        r = run("UPDATE jobs SET status='failed', finished_at=$3, error=$4, lease_until=NULL, "
                PROGRESS_ENDED " WHERE id=$1 AND status='running' AND owner=$2",
                4, v, NULL, NULL, 0);
    else
        r = run("UPDATE jobs SET status='queued', started_at=NULL, progress=NULL, owner=NULL, "
                "lease_until=NULL WHERE id=$1 AND status='running' AND owner=$2",
                2, v, NULL, NULL, 0);
    long n = changed(r);
    PQclear(r);
    return n == 1 ? attempts >= STORE_MAX_ATTEMPTS : -1;
}

static int pg_recover(int *requeued, int *failed)
{
    if (requeued) *requeued = 0;
    if (failed) *failed = 0;
    char prefix[160], plen[16], now[40];
    snprintf(prefix, sizeof prefix, "%.*s", (int)owner_host_len, owner);
    snprintf(plen, sizeof plen, "%zu", owner_host_len);
    gpd_now_rfc3339(now, sizeof now);
    const char *v[2] = {prefix, plen};
    PGresult *r = run("SELECT id, owner, attempts FROM jobs WHERE status='running' "
                      "AND left(owner, $2::int) = $1",
                      2, v, NULL, NULL, 0);
    if (!r) return -1;
    for (int i = 0; i < PQntuples(r); i++) {
        const char *o = PQgetvalue(r, i, 1);
        if (owner_alive(o)) continue; /* another daemon of this host, alive: its lease rules */
        int k = recover_one(PQgetvalue(r, i, 0), o, atoi(PQgetvalue(r, i, 2)), now);
        if (k == 1 && failed) (*failed)++;
        if (k == 0 && requeued) (*requeued)++;
    }
    PQclear(r);
    return 0;
}

/* ------------------------------------------------------------------ submit, read */

static store_rc pg_insert(const char *kind, const char *spec_json, const char *brief_json,
                          long max_queued, char id_out[33])
{
    if (gpd_new_id(id_out) != 0) return STORE_ERROR;
    char now[40], cap[24];
    gpd_now_rfc3339(now, sizeof now);
    snprintf(cap, sizeof cap, "%ld", max_queued);
    /* the cap: the count and the insert under one advisory lock, so that two submits (on any
     * daemons) cannot both take the last place; READ COMMITTED gives the INSERT a snapshot
     * taken after the lock */
    int capped = max_queued > 0;
    if (capped && simple("BEGIN")) return STORE_ERROR;
    PGresult *l = capped ? run("SELECT pg_advisory_xact_lock(7401862)", 0, NULL, NULL, NULL, 0)
                         : NULL;
    store_rc rc = STORE_ERROR;
    if (!capped || l) {
        const char *v[6] = {id_out, kind, spec_json, now, cap, brief_json};
        PGresult *r = run("INSERT INTO jobs(id, kind, spec, status, created_at, brief) "
                          "SELECT $1, $2, $3, 'queued', $4, $6 WHERE $5::bigint <= 0 OR "
                          "(SELECT count(*) FROM jobs WHERE status='queued') < $5::bigint",
                          6, v, NULL, NULL, 0);
        long n = changed(r);
        rc = n < 0 ? STORE_ERROR : n > 0 ? STORE_OK : STORE_FULL;
        PQclear(r);
    }
    PQclear(l);
    if (capped) rc = end_tx(rc == STORE_FULL ? STORE_OK : rc) == STORE_OK ? rc : STORE_ERROR;
    return rc;
}

/* every PostgreSQL database was made with briefs: every job has one from its submit */
static int pg_fill_briefs(store_brief_fn make)
{
    (void)make;
    return 0;
}

static json_t *pg_get_job(const char *id, store_rc *rc)
{
    const char *v[1] = {id};
    PGresult *r = run("SELECT " JOB_COLS " FROM jobs WHERE id=$1 AND " VISIBLE, 1, v, NULL,
                      NULL, 0);
    *rc = !r ? STORE_ERROR : PQntuples(r) ? STORE_OK : STORE_NOT_FOUND;
    json_t *j = *rc == STORE_OK ? job_from_row(r, 0) : NULL;
    PQclear(r);
    return j;
}

static store_rc pg_get_text(const char *id, const char *column, char **text, char status[16])
{
    *text = NULL;
    const char *sql;
    if (!strcmp(column, "spec"))
        sql = "SELECT status, spec FROM jobs WHERE id=$1 AND " VISIBLE;
    else if (!strcmp(column, "kind"))
        sql = "SELECT status, kind FROM jobs WHERE id=$1 AND " VISIBLE;
    else
        return STORE_ERROR;
    const char *v[1] = {id};
    PGresult *r = run(sql, 1, v, NULL, NULL, 1);
    if (!r) return STORE_ERROR;
    store_rc rc = PQntuples(r) ? STORE_OK : STORE_NOT_FOUND;
    if (rc == STORE_OK) {
        snprintf(status, 16, "%.*s", PQgetlength(r, 0, 0), PQgetvalue(r, 0, 0));
        if (!PQgetisnull(r, 0, 1) && !(*text = dup_val(r, 0, 1))) rc = STORE_ERROR;
    }
    PQclear(r);
    return rc;
}

static json_t *pg_list(const char *status, int limit, const char *after, store_rc *rc)
{
    *rc = STORE_ERROR;
    char after_seq[24] = "-1", lim[16];
    if (after) {
        const char *v[1] = {after};
        PGresult *q = run("SELECT seq FROM jobs WHERE id=$1 AND " VISIBLE, 1, v, NULL, NULL, 0);
        if (!q) return NULL;
        int found = PQntuples(q) > 0;
        if (found) snprintf(after_seq, sizeof after_seq, "%s", PQgetvalue(q, 0, 0));
        PQclear(q);
        if (!found) {
            *rc = STORE_NOT_FOUND;
            return NULL;
        }
    }
    snprintf(lim, sizeof lim, "%d", limit + 1);
    const char *v[3] = {status, after_seq, lim};
    PGresult *r = run("SELECT " JOB_COLS " FROM jobs WHERE ($1::text IS NULL OR status=$1) "
                      "AND " VISIBLE " AND ($2::bigint < 0 OR seq < $2::bigint) "
                      "ORDER BY seq DESC LIMIT $3::int",
                      3, v, NULL, NULL, 0);
    if (!r) return NULL;
    json_t *jobs = json_array(), *next = json_null();
    int n = PQntuples(r);
    for (int i = 0; i < n && i < limit; i++) json_array_append_new(jobs, job_from_row(r, i));
    if (n > limit && limit > 0) { /* there is more: the cursor is the last job returned */
        json_decref(next);
        next = json_incref(json_object_get(json_array_get(jobs, (size_t)limit - 1), "id"));
    }
    PQclear(r);
    *rc = STORE_OK;
    return json_pack("{s:o, s:o}", "jobs", jobs, "next", next);
}

static store_rc pg_counts(long n[STORE_NSTATUS])
{
    PGresult *r = run("SELECT status, count(*) FROM jobs GROUP BY status", 0, NULL, NULL, NULL, 0);
    if (!r) return STORE_ERROR;
    for (int i = 0; i < PQntuples(r); i++) {
        int k = store_status_slot(PQgetvalue(r, i, 0));
        if (k >= 0) n[k] = atol(PQgetvalue(r, i, 1));
    }
    PQclear(r);
    return STORE_OK;
}

/* A liveness probe's counts: a short bound, and a stall that only asks the store thread to
 * probe (a server slow for a moment is not taken for gone on one probe's word) */
/* store_reachable: the server not marked unreachable, and this thread's last call answered */
static int pg_reachable(void)
{
    return __atomic_load_n(&reachable, __ATOMIC_ACQUIRE) && !tl_stalled;
}

static store_rc pg_counts_within(long n[STORE_NSTATUS], double wait_s)
{
    if (db_closed()) return STORE_UNREACHABLE;
    tl_until = gpd_monotonic_s() + wait_s;
    store_rc rc = pg_counts(n);
    tl_until = 0;
    return rc != STORE_OK && tl_stalled ? STORE_UNREACHABLE : rc;
}

/* ------------------------------------------------------------------ claim */

/* One pass of the claim's transaction over the row it locked (seq; status; attempts): a
 * lapsed job at its last attempt fails (1: look again), any other becomes ours (0, with
 * id/kind/spec); -1 on a failure. */
static int claim_row(const char *seq, int lapsed, int attempts, char id[33], char **kind,
                     char **spec, int *att)
{
    char now[40], secs[32];
    gpd_now_rfc3339(now, sizeof now);
    if (lapsed && attempts >= STORE_MAX_ATTEMPTS) {
        const char *v[3] = {seq, now, store_interrupted_error()};
        PGresult *r = run("UPDATE jobs SET status='failed', finished_at=$2, error=$3, "
                          "lease_until=NULL, " PROGRESS_ENDED " WHERE seq=$1::bigint",
                          3, v, NULL, NULL, 0);
        long n = changed(r);
        PQclear(r);
        if (n == 1) gpd_log(GPD_LOG_WARN, "a job whose daemon stopped %d times failed "
                                          "(interrupted)", STORE_MAX_ATTEMPTS);
        return n == 1 ? 1 : -1;
    }
    snprintf(secs, sizeof secs, "%.3f", store_lease());
    const char *v[4] = {seq, now, owner, secs};
    PGresult *r = run(
        "UPDATE jobs SET status='running', started_at=$2, finished_at=NULL, "
        "attempts=attempts+1, owner=$3, lease_until=now() + $4::float8 * interval '1 second', "
        "progress='{\"phase\":\"starting\",\"fraction\":0,\"eta_s\":null,\"detail\":{}}' "
        "WHERE seq=$1::bigint RETURNING id, kind, spec, attempts",
        4, v, NULL, NULL, 0);
    int ok = r && PQntuples(r) == 1;
    if (ok) {
        snprintf(id, 33, "%s", PQgetvalue(r, 0, 0));
        *kind = strdup(PQgetvalue(r, 0, 1));
        *spec = strdup(PQgetvalue(r, 0, 2));
        *att = atoi(PQgetvalue(r, 0, 3));
        ok = *kind && *spec;
    }
    PQclear(r);
    return ok ? 0 : -1;
}

static store_rc pg_claim(char id[33], char **kind, char **spec_json, int *attempts)
{
    *kind = *spec_json = NULL;
    /* a few lapsed jobs at their last attempt may be failed on the way to a claimable one */
    for (int pass = 0; pass < 16; pass++) {
        if (simple("BEGIN")) return STORE_ERROR;
        PGresult *r = run("SELECT seq, status = 'running', attempts FROM jobs "
                          "WHERE status='queued' OR (status='running' AND lease_until < now()) "
                          "ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED",
                          0, NULL, NULL, NULL, 0);
        if (!r || PQntuples(r) == 0) {
            store_rc rc = r ? STORE_NOT_FOUND : STORE_ERROR;
            PQclear(r);
            end_tx(STORE_ERROR);
            return rc;
        }
        int k = claim_row(PQgetvalue(r, 0, 0), PQgetvalue(r, 0, 1)[0] == 't',
                          atoi(PQgetvalue(r, 0, 2)), id, kind, spec_json, attempts);
        PQclear(r);
        store_rc rc = end_tx(k >= 0 ? STORE_OK : STORE_ERROR);
        if (rc == STORE_OK && k == 0) return STORE_OK;
        free(*kind);
        free(*spec_json);
        *kind = *spec_json = NULL;
        if (rc != STORE_OK) return STORE_ERROR;
    }
    return STORE_NOT_FOUND;
}

/* ------------------------------------------------------------------ transitions */

/* A write of one of this daemon's running jobs: sql with $1 = id, $2 = owner, then the texts
 * a, b; STORE_OK, STORE_CONFLICT (no longer ours or no longer running), STORE_ERROR. */
static store_rc update_mine(const char *sql, const char *id, int n, const char *a,
                            const char *b)
{
    const char *v[4] = {id, owner, a, b};
    PGresult *r = run(sql, n, v, NULL, NULL, 0);
    long c = changed(r);
    PQclear(r);
    return c < 0 ? STORE_ERROR : c > 0 ? STORE_OK : STORE_CONFLICT;
}

static store_rc pg_progress(const char *id, const char *progress_json)
{
    return update_mine("UPDATE jobs SET progress=$3 WHERE id=$1 AND status='running' "
                       "AND owner=$2",
                       id, 3, progress_json, NULL);
}

static store_rc pg_fail(const char *id, const char *code, const char *message)
{
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    json_t *e = json_pack("{s:s, s:s}", "code", code, "message", message ? message : "");
    if (!e) e = json_pack("{s:s, s:s}", "code", code, "message", "(message not representable)");
    char *et = e ? json_dumps(e, JSON_COMPACT) : NULL;
    json_decref(e);
    if (!et) return STORE_ERROR;
    store_rc rc = update_mine("UPDATE jobs SET status='failed', error=$3, finished_at=$4, "
                              "lease_until=NULL, " PROGRESS_ENDED
                              " WHERE id=$1 AND status='running' AND owner=$2",
                              id, 4, et, now);
    free(et);
    return rc;
}

static store_rc pg_requeue(const char *id)
{
    return update_mine("UPDATE jobs SET status='queued', started_at=NULL, progress=NULL, "
                       "attempts=greatest(attempts-1, 0), owner=NULL, lease_until=NULL "
                       "WHERE id=$1 AND status='running' AND owner=$2",
                       id, 2, NULL, NULL);
}

/* Runs a write that must change exactly one row (the parameters as run's); STORE_OK, or
 * STORE_ERROR (logged by run). */
static store_rc write_row(const char *sql, int n, const char *const *vals, const int *lens,
                          const int *fmts)
{
    PGresult *r = run(sql, n, vals, lens, fmts, 0);
    long changes = changed(r);
    PQclear(r);
    return changes == 1 ? STORE_OK : STORE_ERROR;
}

/* A value to write in parts (store.h "Values in parts"): its source, the part size, and a
 * buffer of one part where the source is a file (libpq binds a parameter from memory). */
typedef struct pg_value {
    const store_text *v;
    uint64_t part;
    char *buf;
} pg_value;

/* Part k of pv as a parameter: *p and *len; 0, or -1 when the file cannot be read. */
static int part_bytes(pg_value *pv, uint64_t k, const char **p, int *len)
{
    uint64_t base = k * pv->part, n = pv->v->len - base < pv->part ? pv->v->len - base : pv->part;
    *len = (int)n; /* a part < 1 GB */
    if (pv->v->mem) {
        *p = pv->v->mem + base;
        return 0;
    }
    js_source src = store_text_source(pv->v);
    *p = pv->buf;
    return n ? src.read(src.user, base, pv->buf, (size_t)n) : 0;
}

/* The parts after part 0 of value `what` of job seq: the old ones removed, pv's written. */
static store_rc write_parts(const char *seq, int what, pg_value *pv)
{
    char w[8], k[24];
    snprintf(w, sizeof w, "%d", what);
    const char *dv[2] = {seq, w};
    PGresult *r = run("DELETE FROM value_parts WHERE seq=$1::bigint AND what=$2::smallint", 2, dv,
                      NULL, NULL, 0);
    if (!r) return STORE_ERROR;
    PQclear(r);
    for (uint64_t part = 1; part * pv->part < pv->v->len; part++) {
        const char *bytes;
        int blen;
        if (part_bytes(pv, part, &bytes, &blen)) return STORE_ERROR;
        snprintf(k, sizeof k, "%llu", (unsigned long long)part);
        const char *v[4] = {seq, w, k, bytes};
        int lens[4] = {0, 0, 0, blen}, fmts[4] = {0, 0, 0, 1};
        if (write_row("INSERT INTO value_parts(seq, what, part, data) "
                      "VALUES ($1::bigint, $2::smallint, $3::int, $4::bytea)",
                      4, v, lens, fmts))
            return STORE_ERROR;
    }
    return STORE_OK;
}

/* The rows of store_succeed's transaction after the job's own: the result's other parts, the
 * pack and the summary. */
static store_rc succeed_extras(const char *seq, pg_value *result, pg_value *pack,
                               const char *summary, size_t slen, const char *arrays)
{
    store_rc rc = write_parts(seq, STORE_VALUE_RESULT, result);
    if (rc == STORE_OK && pack->v) {
        const char *bytes;
        int blen;
        if (part_bytes(pack, 0, &bytes, &blen)) return STORE_ERROR;
        const char *v[2] = {seq, bytes};
        int lens[2] = {0, blen}, fmts[2] = {0, 1};
        rc = write_row("INSERT INTO exports(seq, pack) VALUES ($1::bigint, $2::bytea) "
                       "ON CONFLICT (seq) DO UPDATE SET pack = EXCLUDED.pack",
                       2, v, lens, fmts);
        if (rc == STORE_OK) rc = write_parts(seq, STORE_VALUE_PACK, pack);
    }
    if (rc == STORE_OK && summary) {
        const char *v[3] = {seq, summary, arrays};
        int lens[3] = {0, (int)slen, 0}, fmts[3] = {0, 0, 0};
        rc = write_row("INSERT INTO summaries(seq, summary, arrays) VALUES ($1::bigint, $2, $3) "
                       "ON CONFLICT (seq) DO UPDATE SET summary = EXCLUDED.summary, "
                       "arrays = EXCLUDED.arrays",
                       3, v, lens, fmts);
    }
    return rc;
}

/* The job's row: succeeded with part 0 of the result, only while it is still ours (a daemon
 * that lost it writes nothing: exactly one result). STORE_OK with its seq, STORE_CONFLICT. */
static store_rc mark_succeeded(const char *id, pg_value *result, const char *progress_json,
                               const char *brief_json, char seq[24])
{
    const char *bytes;
    int blen;
    if (part_bytes(result, 0, &bytes, &blen)) return STORE_ERROR;
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    const char *v[6] = {id, bytes, progress_json, now, brief_json, owner};
    int lens[6] = {0, blen, 0, 0, 0, 0}, fmts[6] = {0, 1, 0, 0, 0, 0};
    PGresult *r = run("UPDATE jobs SET status='succeeded', result=$2::bytea, progress=$3, "
                      "finished_at=$4, error=NULL, brief=coalesce($5, brief), lease_until=NULL, "
                      "results_written = results_written + 1 "
                      "WHERE id=$1 AND status='running' AND owner=$6 RETURNING seq",
                      6, v, lens, fmts, 0);
    store_rc rc = !r ? STORE_ERROR : PQntuples(r) == 1 ? STORE_OK : STORE_CONFLICT;
    if (rc == STORE_OK) snprintf(seq, 24, "%s", PQgetvalue(r, 0, 0));
    PQclear(r);
    return rc;
}

/* store_succeed: the result (from memory or its worker's file) and the pack in parts of at
 * most the largest value (store.h "Values in parts"), bound one part at a time, so that
 * neither PostgreSQL's 1 GB a field nor this daemon's memory bounds a result. */
static store_rc pg_succeed(const char *id, const store_text *result, const char *progress_json,
                           const char *brief_json, const void *pack, size_t pack_len,
                           const char *summary, size_t slen, const char *arrays, gpd_err *why)
{
    uint64_t part = store_part_size(max_value);
    store_text pt = {pack, -1, pack_len};
    pg_value rv = {result, part, NULL}, pv = {pack ? &pt : NULL, part, NULL};
    if (!result->mem && !(rv.buf = malloc(result->len < part ? result->len + 1 : part))) {
        gpd_err_set(why, 500, "out of memory for a part of the result");
        return STORE_ERROR;
    }
    if (simple("BEGIN")) {
        free(rv.buf);
        gpd_err_set(why, 500, "cannot begin a transaction on the job database");
        return STORE_ERROR;
    }
    /* the result, the pack, the summary and the status commit together */
    char seq[24] = "";
    store_rc rc = mark_succeeded(id, &rv, progress_json, brief_json, seq);
    if (rc == STORE_OK) rc = succeed_extras(seq, &rv, &pv, summary, slen, arrays);
    free(rv.buf);
    pg_conn *c = store_tls_peek(&tls);
    char em[300];
    snprintf(em, sizeof em, "%s", c ? PQerrorMessage(c->pg) : "no connection");
    rc = end_tx(rc);
    if (rc == STORE_ERROR) {
        if (tl_stalled) snprintf(em, sizeof em, "the database server does not answer");
        gpd_err_set(why, 500, "%s", em[0] ? em : "the database refused the result");
        gpd_log(GPD_LOG_ERROR, "job %s: cannot store the result: %s", id, why->msg);
        if (!tl_stalled) store_note_write_error("storing a result", why->msg);
    }
    return rc;
}

/* no WAL of ours to checkpoint (the server runs its own) */
static int pg_checkpoint(int may_yield)
{
    (void)may_yield;
    return 0;
}

static void pg_checkpoint_yield(void) {}

/* a worker's large result goes to a file on disk (the daemon may have no directory of its
 * own with PostgreSQL): TMPDIR, else /var/tmp -- not /tmp, which may be RAM */
static char *pg_spill_dir(void)
{
    const char *t = getenv("TMPDIR");
    return strdup(t && *t ? t : "/var/tmp");
}

static store_rc pg_cancel(const char *id, int *was_running, char status_out[16], char kind_out[64])
{
    *was_running = 0;
    status_out[0] = '\0';
    if (kind_out) kind_out[0] = '\0';
    char now[40];
    gpd_now_rfc3339(now, sizeof now);
    if (simple("BEGIN")) return STORE_ERROR;
    const char *v[2] = {id, now};
    PGresult *q = run("SELECT status, kind FROM jobs WHERE id=$1 AND " VISIBLE " FOR UPDATE",
                      1, v, NULL, NULL, 0);
    store_rc rc = !q ? STORE_ERROR : PQntuples(q) ? STORE_OK : STORE_NOT_FOUND;
    if (rc == STORE_OK) {
        snprintf(status_out, 16, "%s", PQgetvalue(q, 0, 0));
        if (kind_out) snprintf(kind_out, 64, "%s", PQgetvalue(q, 0, 1));
        if (strcmp(status_out, "queued") && strcmp(status_out, "running")) rc = STORE_CONFLICT;
    }
    PQclear(q);
    if (rc == STORE_OK) {
        *was_running = !strcmp(status_out, "running");
        PGresult *u = run("UPDATE jobs SET status='cancelled', finished_at=$2, lease_until=NULL, "
                          "error='{\"code\":\"cancelled\",\"message\":\"cancelled by a DELETE "
                          "request\"}', " PROGRESS_ENDED " WHERE id=$1",
                          2, v, NULL, NULL, 0);
        if (changed(u) != 1) rc = STORE_ERROR;
        PQclear(u);
    }
    if (rc == STORE_OK && *was_running) { /* delivered at the commit, to every daemon */
        PGresult *n = run("SELECT pg_notify('gp_cancel', $1)", 1, v, NULL, NULL, 0);
        if (!n) rc = STORE_ERROR;
        PQclear(n);
    }
    rc = end_tx(rc);
    if (rc == STORE_OK) snprintf(status_out, 16, "cancelled");
    return rc;
}

/* ------------------------------------------------------------------ operations */

static store_rc pg_purge(const char *id, char status_out[16])
{
    status_out[0] = '\0';
    if (simple("BEGIN")) return STORE_ERROR;
    const char *v[1] = {id};
    PGresult *q = run("SELECT status, seq FROM jobs WHERE id=$1 AND " VISIBLE " FOR UPDATE", 1,
                      v, NULL, NULL, 0);
    store_rc rc = !q ? STORE_ERROR : PQntuples(q) ? STORE_OK : STORE_NOT_FOUND;
    char seq[24] = "";
    if (rc == STORE_OK) {
        snprintf(status_out, 16, "%s", PQgetvalue(q, 0, 0));
        snprintf(seq, sizeof seq, "%s", PQgetvalue(q, 0, 1));
        if (!store_is_finished(status_out)) rc = STORE_CONFLICT;
    }
    PQclear(q);
    /* out of view, its values queued for store_free_purged: a few small rows (the row itself
     * keeps the result's first part until then: updating other columns leaves it in place) */
    static const char *const mark[] = {
        "INSERT INTO purged(seq) VALUES ($1::bigint) ON CONFLICT DO NOTHING",
        "UPDATE jobs SET status='purged', lease_until=NULL WHERE seq=$1::bigint",
        "DELETE FROM summaries WHERE seq=$1::bigint"};
    const char *sv[1] = {seq};
    for (size_t i = 0; rc == STORE_OK && i < sizeof mark / sizeof *mark; i++) {
        PGresult *d = run(mark[i], 1, sv, NULL, NULL, 0);
        if (!d) rc = STORE_ERROR;
        PQclear(d);
    }
    return end_tx(rc);
}

/* The rows of a purged job, deleted one at a time (each its own transaction: a part of a value
 * is at most STORE_PART bytes, about 0.25 s of TOAST rows a 256 MiB part), the last part
 * first; the job's row (with its result's first part) last, then it leaves purged. */
static const char *const FREE_SQL[] = {
    "DELETE FROM value_parts WHERE (seq, what, part) IN (SELECT seq, what, part FROM "
    "value_parts WHERE seq=$1::bigint ORDER BY what DESC, part DESC LIMIT 1)",
    "DELETE FROM exports WHERE seq=$1::bigint",
    "DELETE FROM jobs WHERE seq=$1::bigint AND status='purged'",
    "DELETE FROM purged WHERE seq=$1::bigint",
};

static int pg_free_purged(void)
{
    if (simple("BEGIN")) return -1;
    /* SKIP LOCKED: the daemons' maintenance threads free different jobs */
    PGresult *q = run("SELECT seq FROM purged ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED", 0,
                      NULL, NULL, NULL, 0);
    int failed = !q, found = q && PQntuples(q) == 1;
    char seq[24] = "";
    if (found) snprintf(seq, sizeof seq, "%s", PQgetvalue(q, 0, 0));
    PQclear(q);
    if (!found) {
        end_tx(STORE_ERROR); /* nothing written: a rollback */
        return failed ? -1 : 0;
    }
    const char *v[1] = {seq};
    long n = 0;
    for (size_t i = 0; n == 0 && i < sizeof FREE_SQL / sizeof *FREE_SQL; i++) {
        PGresult *d = run(FREE_SQL[i], 1, v, NULL, NULL, 0);
        n = changed(d);
        PQclear(d);
    }
    return end_tx(n < 0 ? STORE_ERROR : STORE_OK) == STORE_OK ? 1 : -1;
}

static int pg_purge_finished_before(const char *before, int max)
{
    if (max <= 0) return 0;
    char m[16];
    snprintf(m, sizeof m, "%d", max);
    const char *v[2] = {before, m};
    PGresult *r = run("SELECT id FROM jobs WHERE finished_at < $1 AND status IN "
                      "('succeeded', 'failed', 'cancelled') ORDER BY finished_at LIMIT $2::int",
                      2, v, NULL, NULL, 0);
    if (!r) return -1;
    int purged = 0;
    for (int i = 0; i < PQntuples(r); i++) {
        char status[16];
        /* a job may have gone meanwhile (a purge on any daemon): not an error */
        if (pg_purge(PQgetvalue(r, i, 0), status) == STORE_OK) purged++;
    }
    PQclear(r);
    return purged;
}

/* PostgreSQL's autovacuum makes the space of purged rows reusable; giving it back to the file
 * system (VACUUM FULL) takes an exclusive lock and is the operator's call */
static int pg_vacuum_step(void)
{
    return 0;
}

static int pg_count_by_kind(void (*fn)(void *user, const char *kind, const char *status, long n),
                            void *user)
{
    PGresult *r = run("SELECT kind, status, count(*) FROM jobs WHERE " VISIBLE
                      " GROUP BY kind, status", 0, NULL, NULL, NULL, 0);
    if (!r) return -1;
    for (int i = 0; i < PQntuples(r); i++)
        fn(user, PQgetvalue(r, i, 0), PQgetvalue(r, i, 1), atol(PQgetvalue(r, i, 2)));
    PQclear(r);
    return 0;
}

static int pg_size(long long *bytes)
{
    *bytes = 0;
    PGresult *r = run("SELECT pg_database_size(current_database())", 0, NULL, NULL, NULL, 0);
    if (!r || PQntuples(r) != 1) {
        PQclear(r);
        return -1;
    }
    *bytes = atoll(PQgetvalue(r, 0, 0));
    PQclear(r);
    return 0;
}

/* ------------------------------------------------------------------ streams */

#define PG_READ_AHEAD (256u * 1024u) /* bytes fetched per round trip */

/* A value read across its parts (store.h "Values in parts") in one snapshot. */
typedef struct pg_stream {
    PGconn *pg;        /* private: its REPEATABLE READ transaction is the snapshot */
    const char *sql;   /* the slice query of part 0's table */
    char seq[24], what[8];
    store_parts parts;
    unsigned char *buf; /* the last slice fetched: [buf_off, buf_off + buf_len) */
    uint64_t buf_off;
    size_t buf_len;
} pg_stream;

static const char *SLICE_RESULT =
    "SELECT substring(result from $2::int for $3::int) FROM jobs WHERE seq=$1::bigint";
static const char *SLICE_PACK =
    "SELECT substring(pack from $2::int for $3::int) FROM exports WHERE seq=$1::bigint";
static const char *SLICE_PART =
    "SELECT substring(data from $2::int for $3::int) FROM value_parts "
    "WHERE seq=$1::bigint AND what=$4::smallint AND part=$5::int";

static void pg_stream_close(store_stream *s)
{
    pg_stream *ps = (pg_stream *)s;
    if (!ps) return;
    disconnect(ps->pg);
    store_parts_free(&ps->parts);
    free(ps->buf);
    free(ps);
}

/* Fetches n bytes at off of part k (within it) into dst on ps's connection; 0, or -1. */
static int slice(pg_stream *ps, size_t k, uint64_t off, size_t n, unsigned char *dst)
{
    char o[24], l[24], p[24];
    snprintf(o, sizeof o, "%llu", (unsigned long long)off + 1); /* 1-based in SQL */
    snprintf(l, sizeof l, "%zu", n);
    snprintf(p, sizeof p, "%zu", k);
    const char *v[5] = {ps->seq, o, l, ps->what, p};
    if (!ps->pg) return -1;
    tl_stalled = 0;
    PGresult *r = exec_params(ps->pg, k ? SLICE_PART : ps->sql, k ? 5 : 3, v, 1);
    int ok = r && ok_result(r) && PQntuples(r) == 1 && (size_t)PQgetlength(r, 0, 0) == n;
    if (ok) memcpy(dst, PQgetvalue(r, 0, 0), n);
    else if (!tl_stalled)
        gpd_log(GPD_LOG_ERROR, "postgresql stream read: %s", PQerrorMessage(ps->pg));
    PQclear(r);
    if (!ok) { /* the download ends: its connection (and its slot) goes at once */
        disconnect(ps->pg);
        ps->pg = NULL;
    }
    return ok ? 0 : -1;
}

/* The sizes of the value's parts, in ps's snapshot: part 0 by size_sql, the others from
 * value_parts. 0, or -1. */
static int read_parts(pg_stream *ps, const char *size_sql)
{
    const char *v[2] = {ps->seq, ps->what};
    PGresult *r = exec_params(ps->pg, size_sql, 1, v, 0);
    int ok = r && ok_result(r) && PQntuples(r) == 1 && !PQgetisnull(r, 0, 0) &&
             !store_parts_add(&ps->parts, strtoull(PQgetvalue(r, 0, 0), NULL, 10));
    PQclear(r);
    r = ok ? exec_params(ps->pg, "SELECT octet_length(data) FROM value_parts "
                                 "WHERE seq=$1::bigint AND what=$2::smallint ORDER BY part",
                         2, v, 0)
           : NULL;
    ok = r && ok_result(r);
    for (int i = 0; ok && i < PQntuples(r); i++)
        ok = !store_parts_add(&ps->parts, strtoull(PQgetvalue(r, i, 0), NULL, 10));
    PQclear(r);
    return ok ? 0 : -1;
}

/* A stream of a large value: its own connection and snapshot, the parts' sizes read in it. */
static store_rc open_private(const char *sql, const char *size_sql, const char *seq, int what,
                             store_stream **out)
{
    if (take_slot(1)) {
        gpd_log(GPD_LOG_DEBUG, "postgresql: a download refused, %d connections held",
                __atomic_load_n(&open_conns, __ATOMIC_RELAXED));
        return STORE_BUSY;
    }
    pg_stream *ps = calloc(1, sizeof *ps);
    PGconn *pg = ps ? connect_raw() : NULL;
    if (!pg) { /* the slot goes back (disconnect gives it back once connected) */
        __atomic_sub_fetch(&open_conns, 1, __ATOMIC_ACQ_REL);
        free(ps);
        return STORE_ERROR;
    }
    ps->pg = pg;
    ps->sql = sql;
    snprintf(ps->seq, sizeof ps->seq, "%s", seq);
    snprintf(ps->what, sizeof ps->what, "%d", what);
    ps->buf = malloc(PG_READ_AHEAD);
    PGresult *b = ps->buf ? exec_params(ps->pg, "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY",
                                        0, NULL, 0)
                          : NULL;
    int ok = b && ok_result(b);
    PQclear(b);
    if (!ok || read_parts(ps, size_sql)) {
        pg_stream_close((store_stream *)ps);
        return STORE_ERROR;
    }
    *out = (store_stream *)ps;
    return STORE_OK;
}

static uint64_t pg_stream_size(const store_stream *s)
{
    const pg_stream *ps = (const pg_stream *)s;
    return ps->parts.end[ps->parts.n - 1];
}


/* A value of one part of at most small bytes, read whole on this thread's connection. */
static store_rc read_small(int is_pack, const char *seq, char **text, size_t *text_len)
{
    const char *w[1] = {seq};
    PGresult *r = run(is_pack ? "SELECT pack FROM exports WHERE seq=$1::bigint"
                              : "SELECT result FROM jobs WHERE seq=$1::bigint",
                      1, w, NULL, NULL, 1);
    store_rc rc = r && PQntuples(r) == 1 && !PQgetisnull(r, 0, 0) ? STORE_OK : STORE_ERROR;
    if (rc == STORE_OK) {
        *text_len = (size_t)PQgetlength(r, 0, 0);
        if (!(*text = dup_val(r, 0, 0))) rc = STORE_ERROR;
    }
    PQclear(r);
    return rc;
}

static store_rc pg_stream_open(const char *id, int is_pack, size_t small, store_stream **out,
                               char **text, size_t *text_len, char status[16])
{
    const char *v[1] = {id};
    /* octet_length of a TOASTed bytea reads its header, not the value */
    PGresult *r = run(is_pack ? "SELECT j.status, j.seq, octet_length(e.pack), EXISTS (SELECT 1 "
                                "FROM value_parts p WHERE p.seq = j.seq AND p.what = 1) "
                                "FROM jobs j LEFT JOIN exports e ON e.seq = j.seq "
                                "WHERE j.id=$1 AND j.status <> 'purged'"
                              : "SELECT status, seq, octet_length(result), EXISTS (SELECT 1 "
                                "FROM value_parts p WHERE p.seq = jobs.seq AND p.what = 0) "
                                "FROM jobs WHERE id=$1 AND " VISIBLE,
                      1, v, NULL, NULL, 0);
    if (!r) return STORE_ERROR;
    if (!PQntuples(r)) {
        PQclear(r);
        return STORE_NOT_FOUND;
    }
    snprintf(status, 16, "%s", PQgetvalue(r, 0, 0));
    char seq[24];
    snprintf(seq, sizeof seq, "%s", PQgetvalue(r, 0, 1));
    int none = PQgetisnull(r, 0, 2), parts = !strcmp(PQgetvalue(r, 0, 3), "t");
    uint64_t size = none ? 0 : strtoull(PQgetvalue(r, 0, 2), NULL, 10);
    PQclear(r);
    if (none) return STORE_OK; /* not finished, or no pack */
    if (size <= small && !parts) return read_small(is_pack, seq, text, text_len);
    store_rc rc = open_private(
        is_pack ? SLICE_PACK : SLICE_RESULT,
        is_pack ? "SELECT octet_length(pack) FROM exports WHERE seq=$1::bigint"
                : "SELECT octet_length(result) FROM jobs WHERE seq=$1::bigint",
        seq, is_pack ? STORE_VALUE_PACK : STORE_VALUE_RESULT, out);
    return store_stream_settle(rc, out, small, text, text_len);
}

static int pg_stream_read(store_stream *s, uint64_t off, void *dst, size_t n)
{
    pg_stream *ps = (pg_stream *)s;
    if (off > pg_stream_size(s) || n > pg_stream_size(s) - off) return -1;
    unsigned char *d = dst;
    while (n > 0) {
        if (off < ps->buf_off || off >= ps->buf_off + ps->buf_len) { /* the next slice */
            uint64_t start;
            size_t k = store_parts_find(&ps->parts, off, &start);
            uint64_t left = ps->parts.end[k] - off; /* a slice stays within its part */
            size_t len = left < PG_READ_AHEAD ? (size_t)left : PG_READ_AHEAD;
            if (slice(ps, k, off - start, len, ps->buf)) return -1;
            ps->buf_off = off;
            ps->buf_len = len;
        }
        size_t at = (size_t)(off - ps->buf_off), k = ps->buf_len - at;
        if (k > n) k = n;
        memcpy(d, ps->buf + at, k);
        d += k;
        off += k;
        n -= k;
    }
    return 0;
}

static store_rc pg_stored_summary(const char *id, char **text, size_t *len,
                                  uint64_t spans[STORE_SUMMARY_NSKIP][2], char status[16])
{
    const char *v[1] = {id};
    PGresult *r = run("SELECT j.status, s.summary, s.arrays FROM jobs j "
                      "LEFT JOIN summaries s ON s.seq = j.seq "
                      "WHERE j.id=$1 AND j.status <> 'purged'",
                      1, v, NULL, NULL, 0);
    if (!r) return STORE_ERROR;
    store_rc rc = PQntuples(r) ? STORE_OK : STORE_NOT_FOUND;
    uint64_t sp[STORE_SUMMARY_NSKIP][2];
    if (rc == STORE_OK) {
        snprintf(status, 16, "%s", PQgetvalue(r, 0, 0));
        if (!PQgetisnull(r, 0, 1) && !PQgetisnull(r, 0, 2) &&
            store_spans_parse(PQgetvalue(r, 0, 2), sp) == 0) {
            *text = dup_val(r, 0, 1);
            if (!*text) rc = STORE_ERROR;
            else {
                if (len) *len = (size_t)PQgetlength(r, 0, 1);
                if (spans) memcpy(spans, sp, sizeof sp);
            }
        }
    }
    PQclear(r);
    return rc;
}

const store_backend store_pg = {
    .name = "postgresql",
    .open = pg_open,
    .close = pg_close,
    .thread_done = pg_thread_done,
    .recover = pg_recover,
    .insert = pg_insert,
    .fill_briefs = pg_fill_briefs,
    .get_job = pg_get_job,
    .get_text = pg_get_text,
    .list = pg_list,
    .counts = pg_counts,
    .counts_within = pg_counts_within,
    .reachable = pg_reachable,
    .claim = pg_claim,
    .progress = pg_progress,
    .succeed = pg_succeed,
    .spill_dir = pg_spill_dir,
    .checkpoint = pg_checkpoint,
    .checkpoint_yield = pg_checkpoint_yield,
    .fail = pg_fail,
    .requeue = pg_requeue,
    .cancel = pg_cancel,
    .purge = pg_purge,
    .purge_finished_before = pg_purge_finished_before,
    .free_purged = pg_free_purged,
    .vacuum_step = pg_vacuum_step,
    .count_by_kind = pg_count_by_kind,
    .size = pg_size,
    .stream_open = pg_stream_open,
    .stream_size = pg_stream_size,
    .stream_read = pg_stream_read,
    .stream_close = pg_stream_close,
    .stored_summary = pg_stored_summary,
};
