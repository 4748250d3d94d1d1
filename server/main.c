/* main.c -- grainpackd: options, start-up, signals, graceful shutdown.
 *
 *   grainpackd [--listen HOST:PORT] [--db PATH] [--workers N] [--log-level L] ...
 * Settings come from the command line, else the environment (GRAINPACK_*), else the defaults:
 * the options are one table, util/options.c, which --help and --help-markdown print.
 * With port 0 the kernel picks a free port; the first line on stdout is always
 *   listening on http://HOST:PORT
 * Logs go to stderr. SIGTERM/SIGINT: stop accepting, requeue running jobs, close the database.
 */
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "http/http.h"
#include "kinds/kind.h"
#include "jobs/maint.h"
#include "store/store.h"
#include "util/options.h"
#include "util/util.h"
#include "jobs/workers.h"

/* GPD_VERSION: the project's version, defined by server/CMakeLists.txt */

static void usage(FILE *f)
{
    fputs("usage: grainpackd [options]\n"
          "\n"
          "The grainpack job service: accepts packing specs over HTTP (see /v1/schema),\n"
          "queues them in SQLite, runs them on worker threads, serves results and SVG.\n"
          "\n"
          "options (environment variable in brackets; the command line wins):\n",
          f);
    gpd_options_help(f);
    fprintf(f,
            "\n"
            "Restart rule: jobs found 'running' at start-up (the daemon crashed) are queued again,\n"
            "up to %d attempts; a job interrupted %d times fails with error code 'interrupted'.\n"
            "On PostgreSQL a job whose daemon died is taken over once its lease lapses, and the\n"
            "same rule counts its attempts across daemons.\n"
            "SIGTERM/SIGINT requeue running jobs without counting an attempt.\n"
            "DELETE /v1/jobs/ID?purge=1 removes a finished job; GET /metrics is for Prometheus.\n",
            STORE_MAX_ATTEMPTS, STORE_MAX_ATTEMPTS);
}

/* Reads the options (util/options.h; --allow-origin's go to the HTTP server's list) into *o;
 * -1 to go on, else the exit status (--help, --version, --help-markdown, a bad option). */
static int read_options(int argc, char **argv, gpd_options *o)
{
    switch (gpd_options_parse(argc, argv, o, gpd_allow_origins)) {
    case GPD_OPTS_RUN: return -1;
    case GPD_OPTS_HELP: usage(stdout); return 0;
    case GPD_OPTS_VERSION: printf("grainpackd %s\n", GPD_VERSION); return 0;
    case GPD_OPTS_HELP_MARKDOWN: gpd_options_markdown(stdout); return 0;
    case GPD_OPTS_USAGE: usage(stderr); return 2;
    case GPD_OPTS_BAD: break;
    }
    return 2;
}

/* The --db value as it may be logged: a URL's password (user:PASSWORD@host) as "***". */
static void db_for_log(const char *db, char *out, size_t len)
{
    const char *scheme = strstr(db, "://"), *at = scheme ? strchr(scheme + 3, '@') : NULL;
    const char *colon = at ? memchr(scheme + 3, ':', (size_t)(at - scheme - 3)) : NULL;
    if (!store_is_url(db) || !colon)
        snprintf(out, len, "%s", db);
    else
        snprintf(out, len, "%.*s:***%s", (int)(colon - db), db, at);
}

/* Descriptors kept for the daemon's own use, out of the connections' reach: the database's
 * (SQLite: a file, its WAL and its shared memory per connection; PostgreSQL: a socket), the
 * workers' (their connections and the temporary files of results), the log, the listening
 * socket and the threads' wake-ups. */
#define FD_RESERVE 64
#define FD_RESERVE_PER_WORKER 8
/* the descriptors one HTTP connection may take: its socket and, while it downloads, a private
 * database connection (SQLite: three files) */
#define FD_PER_CONNECTION 4

/* The soft limit of open files raised to the hard one: the common default of 1,024 is spent by
 * a thousand idle clients, and the daemon then cannot open its database. The limit in force. */
static long raise_open_files(void)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) != 0) return 1024;
    rlim_t was = rl.rlim_cur, want = rl.rlim_max == RLIM_INFINITY ? (rlim_t)1 << 20 : rl.rlim_max;
    if (was < want) {
        rl.rlim_cur = want;
        if (setrlimit(RLIMIT_NOFILE, &rl) == 0) {
            gpd_log(GPD_LOG_INFO, "open files: soft limit raised from %llu to %llu",
                    (unsigned long long)was, (unsigned long long)want);
            return (long)want;
        }
    }
    return was == RLIM_INFINITY ? 1L << 20 : (long)was;
}

/* --max-connections within the open files, less the daemon's reserve (said when it is
 * lowered). */
static unsigned connection_limit(long wanted, long nworkers)
{
    long files = raise_open_files();
    long fit = (files - FD_RESERVE - FD_RESERVE_PER_WORKER * nworkers) / FD_PER_CONNECTION;
    if (fit < 1) fit = 1;
    if (fit >= wanted) return (unsigned)wanted;
    gpd_log(GPD_LOG_WARN,
            "--max-connections %ld lowered to %ld: the process may open %ld files, and each "
            "connection may take %d after the daemon's own (raise the hard limit: LimitNOFILE= "
            "under systemd, ulimit -Hn)",
            wanted, fit, files, FD_PER_CONNECTION);
    return (unsigned)fit;
}

/* Opens the job store (its lock first, before recovery touches any job) and applies the
 * restart rule; 0, or -1 (said on stderr). */
static int open_store(const char *db)
{
    int open_rc = store_open(db);
    if (open_rc == STORE_OPEN_LOCKED) {
        fprintf(stderr,
                "grainpackd: the job database %s is in use by another grainpackd process (it "
                "holds the database lock); refusing to start\n",
                db);
        return -1;
    }
    if (open_rc != 0) {
        char shown[512];
        db_for_log(db, shown, sizeof shown);
        fprintf(stderr, "grainpackd: cannot open the job database %s\n", shown);
        return -1;
    }
    int requeued = 0, failed = 0;
    if (store_recover(&requeued, &failed) != 0) {
        fprintf(stderr, "grainpackd: cannot recover interrupted jobs in %s\n", db);
        store_close();
        return -1;
    }
    if (requeued || failed)
        gpd_log(GPD_LOG_WARN,
                "recovered after an unclean stop: %d running job(s) requeued, %d failed after %d "
                "attempts",
                requeued, failed, STORE_MAX_ATTEMPTS);
    /* jobs stored by a daemon from before briefs get theirs once (not fatal: they show null) */
    int briefs = store_fill_briefs(gpd_brief_text);
    if (briefs > 0) gpd_log(GPD_LOG_INFO, "filled in the brief of %d older job(s)", briefs);
    return 0;
}

/* Starts the workers, the maintenance thread (maint.h) and the HTTP server on the open store;
 * 0, or -1 with everything that was started stopped and the store closed. */
static int start(gpd_http_config *cfg, long nworkers, long jobto, double retain_days)
{
    static char host[300];
    int port = 0;
    int fd = gpd_listen_socket(cfg->listen, host, sizeof host, &port);
    if (fd < 0) {
        store_close();
        return -1;
    }
    workers_set_job_timeout(jobto);
    if (workers_start((int)nworkers) != 0) {
        workers_stop();
        store_close();
        return -1;
    }
    if (maint_start(retain_days) != 0) {
        close(fd);
        workers_stop();
        store_close();
        return -1;
    }
    cfg->listen_fd = fd;
    cfg->host = host;
    cfg->port = port;
    if (gpd_http_start(cfg) != 0) {
        close(fd);
        maint_stop();
        workers_stop();
        store_close();
        return -1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    gpd_options o;
    int rc = read_options(argc, argv, &o);
    if (rc >= 0) return rc;
    const char *listen = o.v[GPD_OPT_LISTEN].text, *db = o.v[GPD_OPT_DB].text;
    long nworkers = o.v[GPD_OPT_WORKERS].n, nthreads = o.v[GPD_OPT_HTTP_THREADS].n;
    long jthreads = o.v[GPD_OPT_JOB_THREADS].n, jobto = o.v[GPD_OPT_JOB_TIMEOUT].n;
    double retain_days = o.v[GPD_OPT_RETAIN_DAYS].x;
    gpd_log_set_level((gpd_log_level)o.v[GPD_OPT_LOG_LEVEL].n);

    /* Signals are handled by sigwait() in this thread only: block them before any thread. */
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);
    /* a file-size limit fails the write (EFBIG: the job fails with a reason) rather than
     * killing the daemon */
    signal(SIGXFSZ, SIG_IGN);

    /* the cores the workers leave idle go to each job's threads (filling, ODEC, descriptors and
     * the DEM run in parallel inside a job; the result is the same whatever their number) */
    long ncpu = gpd_options_cpus();
    if (jthreads == 0) jthreads = ncpu / nworkers > 1 ? ncpu / nworkers : 1;
    workers_set_job_threads((int)jthreads);
    store_set_lease((double)o.v[GPD_OPT_LEASE].n);
    store_set_max_connections((int)o.v[GPD_OPT_DB_CONNECTIONS].n);
    if (open_store(db)) return 1;
    gpd_http_config cfg = {.threads = (unsigned)nthreads,
                           .max_connections =
                               connection_limit(o.v[GPD_OPT_MAX_CONNECTIONS].n, nworkers),
                           .per_ip = (unsigned)o.v[GPD_OPT_MAX_CONNECTIONS_PER_IP].n,
                           .timeout_s = (unsigned)o.v[GPD_OPT_TIMEOUT].n,
                           .header_timeout_s = (unsigned)o.v[GPD_OPT_HEADER_TIMEOUT].n,
                           .max_pending = (unsigned)o.v[GPD_OPT_MAX_PENDING].n,
                           .max_body = (size_t)o.v[GPD_OPT_MAX_BODY].n,
                           .max_result_mb = (double)o.v[GPD_OPT_MAX_RESULT_MB].n,
                           .max_queued = o.v[GPD_OPT_MAX_QUEUED].n,
                           .listen = listen};
    if (start(&cfg, nworkers, jobto, retain_days)) return 1;
    printf("listening on http://%s:%d\n", cfg.host, cfg.port);
    fflush(stdout);
    char shown[512];
    db_for_log(db, shown, sizeof shown);
    gpd_log(GPD_LOG_INFO, "grainpackd %s: http://%s:%d, db %s (%s), %ld workers of %ld thread(s), "
            "%ld http threads",
            GPD_VERSION, cfg.host, cfg.port, shown, store_backend_name(), nworkers, jthreads,
            nthreads);
    if (retain_days > 0)
        gpd_log(GPD_LOG_INFO, "retention: finished jobs are purged %g days after they finished",
                retain_days);

    int sig = 0;
    while (sigwait(&set, &sig) != 0) {
    }
    gpd_log(GPD_LOG_INFO, "signal %d: shutting down (running jobs are requeued)", sig);
    gpd_http_stop();
    maint_stop();
    workers_stop();
    store_close();
    gpd_log(GPD_LOG_INFO, "stopped cleanly");
    return 0;
}
