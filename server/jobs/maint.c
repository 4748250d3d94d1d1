/* maint.c -- the retention sweep and the reclaim of purged space (see maint.h). */
#include "jobs/maint.h"

#include <pthread.h>
#include <time.h>

#include "store/store.h"
#include "util/util.h"
#include "jobs/workers.h"

#define RECLAIM_RETRY_MIN_S 1.0
#define RECLAIM_RETRY_MAX_S 30.0
#define SWEEP_AGAIN_S 1.0 /* a full pass: the next one soon */
/* a checkpoint a large commit asked for waits until the workers have been idle this long (the
 * copy of hundreds of MB would slow the next job: its fsyncs queue behind the copy's), looking
 * every CKPT_POLL_S, and gives way to a claim; after CKPT_DEFER_MAX_S it runs regardless */
#define CKPT_IDLE_S 1.0
#define CKPT_POLL_S 0.25
#define CKPT_DEFER_MAX_S 60.0

static pthread_t thread;
static int running = 0;
static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t cv;
static int quit = 0;   /* guarded by mu */
static int kicked = 0; /* guarded by mu: 1 a purge (at once), 2 a grown WAL (keeps back-off) */
static double retain_s = 0;

/* One pass of the sweep: purges up to MAINT_SWEEP_MAX jobs past the limit; their number. */
static int sweep(void)
{
    char before[40];
    gpd_past_rfc3339(retain_s, before, sizeof before);
    int n = store_purge_finished_before(before, MAINT_SWEEP_MAX);
    if (n > 0)
        gpd_log(GPD_LOG_INFO, "retention: purged %d finished job(s) that finished before %s", n,
                before);
    return n;
}

/* waits until the monotonic time `until` (0 = no limit), a kick or the stop; 1 when stopping */
static int wait_until(double until)
{
    pthread_mutex_lock(&mu);
    while (!quit && !kicked) {
        if (until <= 0) {
            pthread_cond_wait(&cv, &mu);
            continue;
        }
        double left = until - gpd_monotonic_s();
        if (left <= 0) break;
        struct timespec dl;
        clock_gettime(CLOCK_MONOTONIC, &dl);
        double t = (double)dl.tv_sec + 1e-9 * (double)dl.tv_nsec + left;
        dl.tv_sec = (time_t)t;
        dl.tv_nsec = (long)((t - (double)dl.tv_sec) * 1e9);
        if (dl.tv_nsec >= 1000000000L) dl.tv_nsec = 999999999L;
        pthread_cond_timedwait(&cv, &mu, &dl);
    }
    int q = quit;
    pthread_mutex_unlock(&mu);
    return q;
}

/* One try at what is due: after a purge (ckpt_asked 0) store_reclaim at once; for a grown WAL
 * (asked at ckpt_asked) a checkpoint once no worker has been busy for CKPT_IDLE_S, giving way
 * to a claim, until CKPT_DEFER_MAX_S have passed (then it runs whatever runs). 0 done, 1
 * blocked (back off), 2 deferred or given way (look again in CKPT_POLL_S), -1 an error.
 * *last_busy: when a worker was last seen busy. */
static int reclaim_step(double now, double *ckpt_asked, double *last_busy)
{
    if (*ckpt_asked <= 0) return store_reclaim();
    if (workers_busy() > 0) *last_busy = now;
    int overdue = now - *ckpt_asked >= CKPT_DEFER_MAX_S;
    if (!overdue && now - *last_busy < CKPT_IDLE_S) return 2;
    int rc = store_checkpoint(!overdue);
    if (rc == 2) *last_busy = gpd_monotonic_s();
    if (rc == 0) *ckpt_asked = 0;
    return rc;
}

static void *maint_main(void *arg)
{
    (void)arg;
    double next_sweep = retain_s > 0 ? gpd_monotonic_s() : 0; /* at start-up first */
    int dirty = 0;              /* space to give back, or a checkpoint due */
    double retry = 0, retry_at = 0;
    double ckpt_asked = 0, last_busy = 0; /* a checkpoint a grown WAL asked for (0: none) */
    for (;;) {
        double until = next_sweep;
        if (dirty && retry_at > 0 && (until <= 0 || retry_at < until)) until = retry_at;
        if (wait_until(dirty && retry_at <= 0 ? gpd_monotonic_s() : until)) break;
        double now = gpd_monotonic_s();
        pthread_mutex_lock(&mu);
        if (kicked == 1 || (kicked && !dirty)) {
            dirty = 1;
            retry_at = 0;
            ckpt_asked = kicked == 2 ? now : 0;
            last_busy = now; /* the commit came from a job: idle is to be seen first */
        }
        kicked = 0;
        pthread_mutex_unlock(&mu);
        if (next_sweep > 0 && now >= next_sweep) {
            int n = sweep();
            if (n > 0) {
                dirty = 1;
                retry_at = 0;
                ckpt_asked = 0;
            }
            next_sweep = now + (n >= MAINT_SWEEP_MAX ? SWEEP_AGAIN_S : MAINT_SWEEP_INTERVAL_S);
        }
        if (!dirty || (retry_at > 0 && now < retry_at)) continue;
        int rc = reclaim_step(now, &ckpt_asked, &last_busy);
        if (rc == 0) {
            dirty = 0;
            retry = 0;
            retry_at = 0;
        } else if (rc == 2) {
            retry_at = gpd_monotonic_s() + CKPT_POLL_S;
        } else { /* blocked by a reader (or an error): later, backing off */
            retry = retry <= 0 ? RECLAIM_RETRY_MIN_S
                               : (retry * 2 > RECLAIM_RETRY_MAX_S ? RECLAIM_RETRY_MAX_S
                                                                   : retry * 2);
            retry_at = gpd_monotonic_s() + retry;
            gpd_log(GPD_LOG_DEBUG, "reclaim: the checkpoint is blocked; again in %.0f s", retry);
        }
    }
    store_thread_done();
    return NULL;
}

int maint_start(double retain_days)
{
    retain_s = retain_days > 0 ? retain_days * 86400.0 : 0;
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&cv, &ca);
    pthread_condattr_destroy(&ca);
    quit = 0;
    kicked = 0;
    if (pthread_create(&thread, NULL, maint_main, NULL) != 0) {
        gpd_log(GPD_LOG_ERROR, "cannot start the maintenance thread");
        pthread_cond_destroy(&cv);
        return -1;
    }
    pthread_mutex_lock(&mu);
    running = 1;
    pthread_mutex_unlock(&mu);
    store_on_wal_grown(maint_wal_grown);
    return 0;
}

/* running is read under mu: a worker's commit may call this while maint_stop destroys cv */
static void kick(int why)
{
    pthread_mutex_lock(&mu);
    if (running) {
        if (kicked != 1) kicked = why; /* a purge's "at once" wins */
        pthread_cond_signal(&cv);
    }
    pthread_mutex_unlock(&mu);
}

void maint_kick(void) { kick(1); }
void maint_wal_grown(void) { kick(2); }

void maint_stop(void)
{
    if (!running) return;
    store_on_wal_grown(NULL);
    pthread_mutex_lock(&mu);
    quit = 1;
    pthread_cond_signal(&cv);
    pthread_mutex_unlock(&mu);
    pthread_join(thread, NULL);
    pthread_mutex_lock(&mu);
    running = 0;
    pthread_mutex_unlock(&mu);
    pthread_cond_destroy(&cv);
}
