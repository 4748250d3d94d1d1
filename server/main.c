/* main.c -- grainpackd: options, start-up, signals, graceful shutdown.
 *
 *   grainpackd [--listen HOST:PORT] [--db PATH] [--workers N] [--log-level L] ...
 * Settings come from the command line, else the environment (GRAINPACK_*), else the defaults.
 * With port 0 the kernel picks a free port; the first line on stdout is always
 *   listening on http://HOST:PORT
 * Logs go to stderr. SIGTERM/SIGINT: stop accepting, requeue running jobs, close the database.
 */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "http/http.h"
#include "kinds/kind.h"
#include "jobs/maint.h"
#include "store/store.h"
#include "util/util.h"
#include "jobs/workers.h"

/* GPD_VERSION: the project's version, defined by server/CMakeLists.txt */

static void usage(FILE *f)
{
    fprintf(f,
            "usage: grainpackd [options]\n"
            "\n"
            "The grainpack job service: accepts packing specs over HTTP (see /v1/schema),\n"
            "queues them in SQLite, runs them on worker threads, serves results and SVG.\n"
            "\n"
            "options (environment variable in brackets; the command line wins):\n"
            "  --listen HOST:PORT     address to listen on [GRAINPACK_LISTEN]\n"
            "                         (default 127.0.0.1:8080; port 0 = pick a free port;\n"
            "                         the first stdout line is 'listening on http://HOST:PORT')\n"
            "  --db PATH|URL          the job database [GRAINPACK_DB]: a file path is SQLite\n"
            "                         (default ./grainpack.db, one daemon per file); a URL\n"
            "                         postgresql://user@host:port/dbname is PostgreSQL, where\n"
            "                         many daemons (on any hosts) share one queue\n"
            "  --lease S              PostgreSQL: seconds a running job stays claimed without\n"
            "                         its daemon renewing it (every S/3 s); a job whose lease\n"
            "                         lapsed is taken over by another daemon [GRAINPACK_LEASE]\n"
            "                         (default 30)\n"
            "  --workers N            worker threads running jobs [GRAINPACK_WORKERS]\n"
            "                         (default: the number of CPU cores)\n"
            "  --job-threads N        threads each job runs on (the IMC, filling, ODEC and\n"
            "                         descriptors of a 2D job, the DEM of a 3D one; results\n"
            "                         are the same whatever N) [GRAINPACK_JOB_THREADS]\n"
            "                         (default 0: the CPU cores over the workers, at least 1)\n"
            "  --log-level LEVEL      error|warn|info|debug [GRAINPACK_LOG_LEVEL] (default info;\n"
            "                         debug logs every request)\n"
            "  --http-threads N       HTTP thread pool size [GRAINPACK_HTTP_THREADS] (default 4)\n"
            "  --max-connections N    concurrent connection limit [GRAINPACK_MAX_CONNECTIONS]\n"
            "                         (default 1024)\n"
            "  --timeout S            idle timeout per connection, seconds [GRAINPACK_TIMEOUT]\n"
            "                         (default 30)\n"
            "  --max-body BYTES       request body limit, 413 above [GRAINPACK_MAX_BODY]\n"
            "                         (default 1048576)\n"
            "  --max-result-mb MB     refuse (422 too_large) a spec whose result would be\n"
            "                         larger, which bounds the disk one job takes\n"
            "                         [GRAINPACK_MAX_RESULT_MB] (default 8192)\n"
            "  --job-timeout S        a job whose run lasts longer fails with error code\n"
            "                         'timeout' (per run attempt; 0 = no limit)\n"
            "                         [GRAINPACK_JOB_TIMEOUT] (default 3600)\n"
            "  --retain-days N        purge finished jobs (their results and exports) N days\n"
            "                         after they finished; a real number (0.5 = 12 hours);\n"
            "                         checked at start-up and every minute\n"
            "                         [GRAINPACK_RETAIN_DAYS] (default 0 = keep every job)\n"
            "  --max-queued N         a submit while N jobs are queued gets 503 queue_full\n"
            "                         with Retry-After [GRAINPACK_MAX_QUEUED] (default 10000)\n"
            "  --allow-origin ORIGIN  also serve pages at ORIGIN (scheme://host[:port], e.g. a\n"
            "                         lab dashboard served elsewhere); repeatable or comma-\n"
            "                         separated [GRAINPACK_ALLOW_ORIGIN]. Any other Origin, and\n"
            "                         a Host naming another server, get 403 (see README)\n"
            "  --version              print the version and exit\n"
            "  --help                 this text\n"
            "\n"
            "Restart rule: jobs found 'running' at start-up (the daemon crashed) are queued again,\n"
            "up to %d attempts; a job interrupted %d times fails with error code 'interrupted'.\n"
            "On PostgreSQL a job whose daemon died is taken over once its lease lapses, and the\n"
            "same rule counts its attempts across daemons.\n"
            "SIGTERM/SIGINT requeue running jobs without counting an attempt.\n"
            "DELETE /v1/jobs/ID?purge=1 removes a finished job; GET /metrics is for Prometheus.\n",
            STORE_MAX_ATTEMPTS, STORE_MAX_ATTEMPTS);
}

static int parse_long(const char *name, const char *s, long lo, long hi, long *out)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || !end || *end || end == s || v < lo || v > hi) {
        fprintf(stderr, "grainpackd: %s expects an integer in [%ld, %ld], got \"%s\"\n", name,
                lo, hi, s);
        return -1;
    }
    *out = v;
    return 0;
}

static int parse_days(const char *name, const char *s, double *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || !end || *end || end == s || !isfinite(v) || v < 0 || v > 36500) {
        fprintf(stderr, "grainpackd: %s expects a number of days in [0, 36500] (0 = keep "
                        "forever; 0.5 = 12 hours), got \"%s\"\n",
                name, s);
        return -1;
    }
    *out = v;
    return 0;
}

static const char *env_or(const char *name, const char *dflt)
{
    const char *v = getenv(name);
    return (v && *v) ? v : dflt;
}

/* the settings as given: the command line, else the environment, else the defaults */
typedef struct settings {
    const char *listen, *db, *workers, *level, *threads, *maxconn, *timeout, *maxbody, *maxres,
        *jobto, *retain, *maxq, *lease, *jthreads;
} settings;

/* Reads the command line over st (the environment's values); -1 to go on, else the exit
 * status (--help, --version, a bad option or origin). */
static int read_args(int argc, char **argv, settings *st)
{
    const char *origins_env = env_or("GRAINPACK_ALLOW_ORIGIN", NULL);
    int origins_flag = 0; /* any --allow-origin replaces GRAINPACK_ALLOW_ORIGIN */
    static const struct option opts[] = {
        {"listen", required_argument, 0, 'l'},       {"db", required_argument, 0, 'd'},
        {"workers", required_argument, 0, 'w'},      {"log-level", required_argument, 0, 'L'},
        {"http-threads", required_argument, 0, 't'}, {"max-connections", required_argument, 0, 'c'},
        {"timeout", required_argument, 0, 'T'},      {"max-body", required_argument, 0, 'b'},
        {"max-result-mb", required_argument, 0, 'R'},
        {"job-timeout", required_argument, 0, 'J'},
        {"retain-days", required_argument, 0, 1002},
        {"max-queued", required_argument, 0, 1003},
        {"lease", required_argument, 0, 1004},
        {"job-threads", required_argument, 0, 1005},
        {"allow-origin", required_argument, 0, 1001},
        {"help", no_argument, 0, 'h'},               {"version", no_argument, 0, 'V'},
        {0, 0, 0, 0}};
    int ch;
    while ((ch = getopt_long(argc, argv, "l:d:w:L:t:c:T:b:R:J:hV", opts, NULL)) != -1) {
        switch (ch) {
        case 'l': st->listen = optarg; break;
        case 'd': st->db = optarg; break;
        case 'w': st->workers = optarg; break;
        case 'L': st->level = optarg; break;
        case 't': st->threads = optarg; break;
        case 'c': st->maxconn = optarg; break;
        case 'T': st->timeout = optarg; break;
        case 'b': st->maxbody = optarg; break;
        case 'R': st->maxres = optarg; break;
        case 'J': st->jobto = optarg; break;
        case 1002: st->retain = optarg; break;
        case 1003: st->maxq = optarg; break;
        case 1004: st->lease = optarg; break;
        case 1005: st->jthreads = optarg; break;
        case 1001:
            if (gpd_allow_origins(optarg)) return 2;
            origins_flag = 1;
            break;
        case 'h': usage(stdout); return 0;
        case 'V': printf("grainpackd %s\n", GPD_VERSION); return 0;
        default: usage(stderr); return 2;
        }
    }
    if (!origins_flag && origins_env && gpd_allow_origins(origins_env)) return 2;
    if (optind < argc) {
        fprintf(stderr, "grainpackd: unexpected argument \"%s\"\n", argv[optind]);
        usage(stderr);
        return 2;
    }
    return -1;
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
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    if (ncpu < 1) ncpu = 1;
    char ncpu_s[24];
    snprintf(ncpu_s, sizeof ncpu_s, "%ld", ncpu);
    settings st = {env_or("GRAINPACK_LISTEN", "127.0.0.1:8080"),
                   env_or("GRAINPACK_DB", "./grainpack.db"),
                   env_or("GRAINPACK_WORKERS", ncpu_s),
                   env_or("GRAINPACK_LOG_LEVEL", "info"),
                   env_or("GRAINPACK_HTTP_THREADS", "4"),
                   env_or("GRAINPACK_MAX_CONNECTIONS", "1024"),
                   env_or("GRAINPACK_TIMEOUT", "30"),
                   env_or("GRAINPACK_MAX_BODY", "1048576"),
                   env_or("GRAINPACK_MAX_RESULT_MB", "8192"),
                   env_or("GRAINPACK_JOB_TIMEOUT", "3600"),
                   env_or("GRAINPACK_RETAIN_DAYS", "0"),
                   env_or("GRAINPACK_MAX_QUEUED", "10000"),
                   env_or("GRAINPACK_LEASE", "30"),
                   env_or("GRAINPACK_JOB_THREADS", "0")};
    int rc = read_args(argc, argv, &st);
    if (rc >= 0) return rc;
    long nworkers, nthreads, maxconn, timeout, maxbody, maxres, jobto, maxq, lease, jthreads;
    double retain_days;
    if (parse_long("--workers", st.workers, 1, 1024, &nworkers) ||
        parse_long("--http-threads", st.threads, 1, 256, &nthreads) ||
        parse_long("--max-connections", st.maxconn, 1, 1000000, &maxconn) ||
        parse_long("--timeout", st.timeout, 1, 86400, &timeout) ||
        parse_long("--max-body", st.maxbody, 1024, 1L << 30, &maxbody) ||
        parse_long("--max-result-mb", st.maxres, 1, 1L << 20, &maxres) ||
        parse_long("--job-timeout", st.jobto, 0, 31622400, &jobto) ||
        parse_long("--max-queued", st.maxq, 1, 1000000000, &maxq) ||
        parse_long("--lease", st.lease, 1, 86400, &lease) ||
        parse_long("--job-threads", st.jthreads, 0, 1024, &jthreads) ||
        parse_days("--retain-days", st.retain, &retain_days))
        return 2;
    int level = gpd_log_parse_level(st.level);
    if (level < 0) {
        fprintf(stderr, "grainpackd: --log-level expects error|warn|info|debug, got \"%s\"\n",
                st.level);
        return 2;
    }
    gpd_log_set_level((gpd_log_level)level);

    /* Signals are handled by sigwait() in this thread only: block them before any thread. */
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);

    /* the cores the workers leave idle go to each job's threads (filling, ODEC, descriptors and
     * the DEM run in parallel inside a job; the result is the same whatever their number) */
    if (jthreads == 0) jthreads = ncpu / nworkers > 1 ? ncpu / nworkers : 1;
    workers_set_job_threads((int)jthreads);
    store_set_lease((double)lease);
    if (open_store(st.db)) return 1;
    gpd_http_config cfg = {.threads = (unsigned)nthreads,
                           .max_connections = (unsigned)maxconn,
                           .timeout_s = (unsigned)timeout,
                           .max_body = (size_t)maxbody,
                           .max_result_mb = (double)maxres,
                           .max_queued = maxq,
                           .listen = st.listen};
    if (start(&cfg, nworkers, jobto, retain_days)) return 1;
    printf("listening on http://%s:%d\n", cfg.host, cfg.port);
    fflush(stdout);
    char shown[512];
    db_for_log(st.db, shown, sizeof shown);
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
